/*
 * origins_tie.c - no group of parts may translate freely against the rest of its solid.
 *
 * Why: Eq. 15 holds the blending weights constant, F = sum_i w_i grad P_i, so translating all
 * the parts of one deformation origin by d (their NURBS, their translation t_j and with it
 * their polynomials) changes no deformation gradient: it costs no elastic energy. It costs
 * error energy (Eq. 16) only where a boundary sample blends a part of that origin with a part
 * of another one, which the weights of Eq. 8 do only between parts that continue each other
 * (a sample on a face gets weight 0 from a face meeting it at an angle: the secondary ray hits
 * the sample's own face first). So the sections of a beam hold together through their
 * coplanar faces, but a rocket's fins, which meet its body at an angle, hold it by nothing:
 * pinned by its fins under gravity, the body fell freely (and a static solve found the system
 * singular). The same happens to knobs, handles and fins of CAD models ("small parts fly
 * away").
 *
 * What: origins are grouped into translation components, joined where some boundary sample
 * carries weight (above TIE_WEIGHT) of parts of both. Two components whose parts are blended at
 * quadrature points (they touch) are tied by merging their most strongly blended pair of
 * origins (sum over points of vol w_a w_b), which then share one translation (Eq. 7).
 * Kruskal's order over the candidate pairs, strongest first (ties by index), merges each
 * component once, so the beam's sections keep their origins and the rocket's body joins one
 * fin origin per fin. Parts of solids that do not touch are left alone (separate bodies).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "steps.h"
#include "util/free_all.h"
#include "util/union_find.h"

/* A boundary sample couples two origins when both carry at least this weight there. */
#define TIE_WEIGHT 0.05

typedef struct origin_pair {
    int a, b;   /* origins, a < b */
    double c;   /* sum over quadrature points of vol w_a w_b (parts summed per origin) */
} origin_pair;

static int pair_by_index(const void *x, const void *y)
{
    const origin_pair *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    return (p->b > q->b) - (p->b < q->b);
}

static int pair_by_strength(const void *x, const void *y)
{
    const origin_pair *p = x, *q = y;
    if (p->c != q->c) return p->c < q->c ? 1 : -1;
    return pair_by_index(x, y);
}

sem_status sem_merge_origins(sem_discretization *d, int *merge, sem_error *err)
{
    const int no = d->n_origins, np = d->n_parts;
    int n_new = 0;
    int *seen = malloc(((size_t)no + 1) * sizeof *seen);
    int *part_origin = malloc(((size_t)np + 1) * sizeof *part_origin);
    if (!seen || !part_origin) {
        free(seen);
        free(part_origin);
        return sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
    }
    for (int j = 0; j < no; ++j) seen[j] = -1;
    for (int i = 0; i < np; ++i) {
        int r = sem_uf_find(merge, d->part_origin[i]);
        if (seen[r] < 0) seen[r] = n_new++;
        part_origin[i] = seen[r];
    }
    free(seen);
    if (n_new == no) {
        free(part_origin);
        return SEM_OK;
    }
    double *X = calloc(3 * (size_t)n_new, sizeof *X);
    double *A = calloc((size_t)n_new, sizeof *A);
    if (!X || !A) {
        free(X);
        free(A);
        free(part_origin);
        return sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
    }
    for (int s = 0; s < d->n_samples; ++s) {
        int o = part_origin[d->sample_part[s]];
        double a = d->sample_area[s] > 0 ? d->sample_area[s] : 0.0;
        A[o] += a;
        for (int e = 0; e < 3; ++e) X[3 * (size_t)o + e] += a * d->sample_X[3 * (size_t)s + e];
    }
    /* an origin without sample area keeps the position of one of its old origins */
    for (int i = 0; i < np; ++i) {
        int o = part_origin[i];
        if (A[o] > 0 || A[o] < 0) continue;
        memcpy(X + 3 * (size_t)o, d->origin_X + 3 * (size_t)d->part_origin[i], 3 * sizeof *X);
        A[o] = -1;
    }
    for (int o = 0; o < n_new; ++o)
        if (A[o] > 0)
            for (int e = 0; e < 3; ++e) X[3 * (size_t)o + e] /= A[o];
    free(A);
    sem_set_origins(d, X, part_origin, n_new);
    return SEM_OK;
}

sem_status sem_tie_translation_components(sem_discretization *d, int *n_ties, sem_error *err)
{
    if (n_ties) *n_ties = 0;
    const int no = d->n_origins, np = d->n_parts;
    if (no <= 1) return SEM_OK;
    int *comp = malloc((size_t)no * sizeof *comp);
    int *merge = malloc((size_t)no * sizeof *merge);
    int *seen = malloc((size_t)no * sizeof *seen);
    double *acc = calloc((size_t)no, sizeof *acc);
    origin_pair *pairs = NULL;
    size_t n_pairs = 0, cap = 0;
    sem_status st = SEM_OK;
    if (!comp || !merge || !seen || !acc) goto nomem;
    for (int j = 0; j < no; ++j) comp[j] = merge[j] = j;

    /* translation components: origins blended at a boundary sample */
    const sem_csr *Ws = &d->W_samples;
    for (int s = 0; s < Ws->n_rows; ++s) {
        int first = -1;
        for (int k = Ws->row_start[s]; k < Ws->row_start[s + 1]; ++k) {
            if (Ws->val[k] < TIE_WEIGHT) continue;
            int o = d->part_origin[Ws->col[k]];
            if (first < 0)
                first = o;
            else
                sem_uf_unite(comp, first, o);
        }
    }
    /* origin pairs blended at quadrature points, across components */
    for (int j = 0; j < no; ++j) seen[j] = -1;
    const sem_csr *W = &d->W;
    for (int p = 0; p < W->n_rows; ++p) {
        const double v = d->quad_volume ? d->quad_volume[p] : 1.0;
        int b0 = W->row_start[p], b1 = W->row_start[p + 1];
        for (int i = b0; i < b1; ++i) {
            int oi = d->part_origin[W->col[i]];
            for (int k = i + 1; k < b1; ++k) {
                int ok = d->part_origin[W->col[k]];
                if (oi == ok || sem_uf_find(comp, oi) == sem_uf_find(comp, ok)) continue;
                if (n_pairs == cap) {
                    size_t nc = cap ? 2 * cap : 256;
                    origin_pair *g = realloc(pairs, nc * sizeof *g);
                    if (!g) goto nomem;
                    pairs = g;
                    cap = nc;
                }
                pairs[n_pairs++] = (origin_pair){oi < ok ? oi : ok, oi < ok ? ok : oi,
                                                 v * W->val[i] * W->val[k]};
            }
        }
    }
    (void)np;
    if (n_pairs > 0) {
        qsort(pairs, n_pairs, sizeof *pairs, pair_by_index);
        size_t m = 0;
        for (size_t k = 0; k < n_pairs; ++k) {
            if (m > 0 && pairs[m - 1].a == pairs[k].a && pairs[m - 1].b == pairs[k].b)
                pairs[m - 1].c += pairs[k].c;
            else
                pairs[m++] = pairs[k];
        }
        qsort(pairs, m, sizeof *pairs, pair_by_strength);
        int ties = 0;
        for (size_t k = 0; k < m; ++k) {
            int ca = sem_uf_find(comp, pairs[k].a), cb = sem_uf_find(comp, pairs[k].b);
            if (ca == cb) continue;
            sem_uf_unite(comp, ca, cb);
            sem_uf_unite(merge, pairs[k].a, pairs[k].b);
            ties++;
        }
        if (n_ties) *n_ties = ties;
    }

    /* renumber the merged origins (by their smallest part) and place them */
    if (n_pairs > 0 && (st = sem_merge_origins(d, merge, err)) != SEM_OK) goto done;
    goto done;
nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
done:
    SEM_FREE_ALL(comp, merge, seen, acc, pairs);
    return st;
}
