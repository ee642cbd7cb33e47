/*
 * origins_cluster.c - deformation origins by coupling (the default rule; paper Sec. 6.2).
 *
 * What an origin does: the parts that share origin j share its translation t_j (Eq. 7), so
 * their polynomials agree on it, and each part's linear fit about Xbar_j is determined only in
 * the directions its group's boundary samples span. So a group must (a) span 3D, or its fit is
 * singular (a lone box face, see origins_merge.c), and (b) be made of parts that are blended
 * together, so that the polynomials mixed at a quadrature point are consistent.
 *
 * Why not the paper's rule by default: its min-cost flow (Eq. 10, origins.c) gives each part
 * the candidate group where the part's weight sum is *smallest*, i.e. a group of a few points
 * at the fringe of alpha. Which fringe groups exist depends on the exact quadrature and the
 * weight threshold, and a symmetric model has mirror-image groups of equal cost that the
 * solver separates by round-off. Measured on the 10-section cantilever (beams/perf/b10.igs,
 * static, gravity along -z), over grids of 0.1-0.25 m: the tip moved between 3.69 and 4.45 m
 * and sideways by up to 10 % of its deflection (the load is symmetric, so it should not move
 * sideways at all). Taking the largest weight sum instead makes every part pick its own
 * group, so nothing is shared and the flat-origin merge decides everything.
 *
 * The rule here (agglomerative, deterministic, symmetric):
 *   coupling   c_ab = sum_p vol_p w_a(X_p) w_b(X_p)   (how much parts a and b are blended;
 *              c_aa is a part's own blended mass)
 *   groups     start as single parts. A group is *settled* when its boundary samples span 3D:
 *              the smallest eigenvalue of their second moment is at least FLAT_RATIO times
 *              the largest (thickness >= ~10 % of the size). Each round, every unsettled
 *              group joins the neighbour group(s) it is most similar to,
 *              S(C, D) = c(C, D) / sqrt(c(C, C) c(D, D)) (normalised, so big groups do not
 *              attract everything), all groups of the round at once and every neighbour
 *              within TIE of the best (mirror images join together). Rounds repeat until
 *              every group is settled. A group coupled to nothing joins the nearest group.
 *   origins    the groups, numbered by their smallest part; each at the area-weighted
 *              centroid of its parts' samples (as t_j in Eq. 7).
 * On the cantilever this gives one origin per section (its four faces; the end caps with
 * their section), the same for every grid, turned with the model and mirror-symmetric.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/flatness.h"
#include "steps.h"
#include "util/free_all.h"
#include "util/union_find.h"

/* A group whose samples' second-moment eigenvalues have a smaller/larger ratio than this is
 * flat (its thinnest extent is under ~10 % of its largest). */
#define FLAT_RATIO 1e-2
/* Similarities within this relative distance of the best are ties. */
#define TIE 1e-6

typedef struct pair_coupling {
    int a, b;   /* parts, a < b */
    double c;   /* sum vol w_a w_b */
} pair_coupling;

static int pair_cmp(const void *x, const void *y)
{
    const pair_coupling *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    return (p->b > q->b) - (p->b < q->b);
}

/* Per group root: area, first and second moments of its samples (10 numbers). */
static void group_moments(const sem_discretization *d, int *parent, double *mom)
{
    memset(mom, 0, 10 * (size_t)d->n_parts * sizeof *mom);
    for (int k = 0; k < d->n_samples; ++k) {
        double *m = mom + 10 * (size_t)sem_uf_find(parent, d->sample_part[k]);
        double a = d->sample_area[k] > 0 ? d->sample_area[k] : 0.0;
        const double *X = d->sample_X + 3 * (size_t)k;
        m[0] += a;
        for (int e = 0; e < 3; ++e) m[1 + e] += a * X[e];
        m[4] += a * X[0] * X[0];
        m[5] += a * X[1] * X[1];
        m[6] += a * X[2] * X[2];
        m[7] += a * X[0] * X[1];
        m[8] += a * X[0] * X[2];
        m[9] += a * X[1] * X[2];
    }
}

/* The flatness ratio of a group's samples (0 for no samples). */
static double group_ratio(const double *m)
{
    if (!(m[0] > 0)) return 0.0;
    double c[3] = {m[1] / m[0], m[2] / m[0], m[3] / m[0]};
    double C[6] = {m[4] / m[0] - c[0] * c[0], m[5] / m[0] - c[1] * c[1],
                   m[6] / m[0] - c[2] * c[2], m[7] / m[0] - c[0] * c[1],
                   m[8] / m[0] - c[0] * c[2], m[9] / m[0] - c[1] * c[2]};
    return sem_eigenvalue_ratio(C);
}

/* The ratio of the union of two groups (moments add). */
static double union_ratio(const double *a, const double *b)
{
    double m[10];
    for (int k = 0; k < 10; ++k) m[k] = a[k] + b[k];
    return group_ratio(m);
}

/* Does joining b make group a less flat? (Joining a coplanar neighbour does not.) */
static int improves(const double *a, const double *b)
{
    double r = group_ratio(a);
    return union_ratio(a, b) >= fmax(1.5 * r, 1e-6);
}

/* The part couplings c_ab (a < b) summed over the quadrature, sorted and merged, and the self
 * couplings c_aa. Returns the pair count, -1 when out of memory. */
static long long part_couplings(const sem_discretization *d, pair_coupling **out, double *self)
{
    const sem_csr *W = &d->W;
    size_t n = 0;
    for (int p = 0; p < W->n_rows; ++p) {
        size_t len = (size_t)(W->row_start[p + 1] - W->row_start[p]);
        n += len * (len - 1) / 2;
    }
    pair_coupling *pc = malloc((n > 0 ? n : 1) * sizeof *pc);
    if (!pc) return -1;
    memset(self, 0, (size_t)d->n_parts * sizeof *self);
    size_t k = 0;
    for (int p = 0; p < W->n_rows; ++p) {
        const double v = d->quad_volume ? d->quad_volume[p] : 1.0;
        for (int i = W->row_start[p]; i < W->row_start[p + 1]; ++i) {
            self[W->col[i]] += v * W->val[i] * W->val[i];
            for (int j = i + 1; j < W->row_start[p + 1]; ++j)
                pc[k++] = (pair_coupling){W->col[i], W->col[j], v * W->val[i] * W->val[j]};
        }
    }
    if (k > 0) qsort(pc, k, sizeof *pc, pair_cmp);
    size_t m = 0;
    for (size_t i = 0; i < k; ++i) {
        if (m > 0 && pc[m - 1].a == pc[i].a && pc[m - 1].b == pc[i].b)
            pc[m - 1].c += pc[i].c;
        else
            pc[m++] = pc[i];
    }
    *out = pc;
    return (long long)m;
}

sem_status sem_step_origins_coupled(sem_discretization *d, sem_error *err)
{
    const int np = d->n_parts;
    if (np <= 0) return sem_error_set(err, SEM_ERR_INVALID, "origins: no parts");
    if (d->W.n_rows != d->n_quad || (d->n_quad > 0 && d->W.n_cols != np) ||
        (d->n_samples > 0 && (!d->sample_X || !d->sample_part || !d->sample_area)))
        return sem_error_set(err, SEM_ERR_INVALID, "origins: weights or samples missing");
    int *parent = malloc((size_t)np * sizeof *parent);
    int *join = malloc((size_t)np * sizeof *join);
    double *self = malloc((size_t)np * sizeof *self);
    double *gself = malloc((size_t)np * sizeof *gself);
    double *best = malloc((size_t)np * sizeof *best);
    double *mom = malloc(10 * (size_t)np * sizeof *mom);
    int *settled = malloc((size_t)np * sizeof *settled);
    int *any_improving = malloc((size_t)np * sizeof *any_improving);
    pair_coupling *pc = NULL, *gpc = NULL;
    sem_status st = SEM_OK;
    if (!parent || !join || !self || !gself || !best || !mom || !settled || !any_improving) goto nomem;
    long long n_pairs = part_couplings(d, &pc, self);
    if (n_pairs < 0) goto nomem;
    gpc = malloc((size_t)(n_pairs > 0 ? n_pairs : 1) * sizeof *gpc);
    if (!gpc) goto nomem;
    for (int i = 0; i < np; ++i) parent[i] = i;

    for (int round = 0; round < np; ++round) {
        group_moments(d, parent, mom);
        int n_groups = 0, n_unsettled = 0;
        for (int i = 0; i < np; ++i) {
            settled[i] = 1;
            if (sem_uf_find(parent, i) != i) continue;
            n_groups++;
            settled[i] = group_ratio(mom + 10 * (size_t)i) >= FLAT_RATIO;
            n_unsettled += !settled[i];
        }
        if (n_unsettled == 0 || n_groups <= 1) break;
        /* group couplings: self (c(C, C)) and between groups (pairs merged again) */
        memset(gself, 0, (size_t)np * sizeof *gself);
        for (int i = 0; i < np; ++i) gself[sem_uf_find(parent, i)] += self[i];
        long long ng = 0;
        for (long long k = 0; k < n_pairs; ++k) {
            int a = sem_uf_find(parent, pc[k].a), b = sem_uf_find(parent, pc[k].b);
            if (a == b) {
                gself[a] += 2 * pc[k].c;
            } else {
                gpc[ng++] = (pair_coupling){a < b ? a : b, a < b ? b : a, pc[k].c};
            }
        }
        if (ng > 0) qsort(gpc, (size_t)ng, sizeof *gpc, pair_cmp);
        for (int i = 0; i < np; ++i) join[i] = i;
        int merged = 0;
        long long m = 0;
        for (long long k = 0; k < ng; ++k) {
            if (m > 0 && gpc[m - 1].a == gpc[k].a && gpc[m - 1].b == gpc[k].b)
                gpc[m - 1].c += gpc[k].c;
            else
                gpc[m++] = gpc[k];
        }
        /* each unsettled group's best similarity among the neighbours that make it less flat
         * (among all when none does), then its joins (ties included); decided from the state
         * at the start of the round, so the order does not matter */
        for (int i = 0; i < np; ++i) {
            best[i] = 0.0;
            any_improving[i] = 0;
        }
        for (long long k = 0; k < m; ++k) {
            int a = gpc[k].a, b = gpc[k].b;
            const double *ma = mom + 10 * (size_t)a, *mb = mom + 10 * (size_t)b;
            if (!settled[a]) any_improving[a] |= improves(ma, mb);
            if (!settled[b]) any_improving[b] |= improves(mb, ma);
        }
        for (int pass = 0; pass < 2; ++pass)
            for (long long k = 0; k < m; ++k) {
                double s = gpc[k].c / sqrt(gself[gpc[k].a] * gself[gpc[k].b]);
                for (int side = 0; side < 2; ++side) {
                    int a = side ? gpc[k].b : gpc[k].a, b = side ? gpc[k].a : gpc[k].b;
                    if (settled[a]) continue;
                    if (any_improving[a] && !improves(mom + 10 * (size_t)a, mom + 10 * (size_t)b))
                        continue;
                    if (pass == 0) {
                        best[a] = fmax(best[a], s);
                    } else if (best[a] > 0 && s >= best[a] * (1 - TIE)) {
                        sem_uf_unite(join, a, b);
                        merged = 1;
                    }
                }
            }
        /* an unsettled group coupled to nothing joins the nearest group (centroids) */
        for (int i = 0; i < np; ++i) {
            if (settled[i] || best[i] > 0 || sem_uf_find(parent, i) != i) continue;
            const double *mi = mom + 10 * (size_t)i;
            double bd = INFINITY;
            int bj = -1;
            for (int j = 0; j < np; ++j) {
                if (j == i || sem_uf_find(parent, j) != j) continue;
                const double *mj = mom + 10 * (size_t)j;
                if (!(mi[0] > 0) || !(mj[0] > 0)) continue;
                double dd = 0;
                for (int e = 1; e < 4; ++e) {
                    double x = mi[e] / mi[0] - mj[e] / mj[0];
                    dd += x * x;
                }
                if (dd < bd) {
                    bd = dd;
                    bj = j;
                }
            }
            if (bj >= 0) {
                sem_uf_unite(join, i, bj);
                merged = 1;
            }
        }
        if (!merged) break;
        for (int i = 0; i < np; ++i) sem_uf_unite(parent, i, sem_uf_find(join, sem_uf_find(parent, i)));
    }

    /* origins: groups numbered by their smallest part, at their samples' centroid */
    {
        int n_origins = 0;
        int *part_origin = malloc((size_t)np * sizeof *part_origin);
        int *root_origin = malloc((size_t)np * sizeof *root_origin);
        if (!part_origin || !root_origin) {
            free(part_origin);
            free(root_origin);
            goto nomem;
        }
        for (int i = 0; i < np; ++i) root_origin[i] = -1;
        for (int i = 0; i < np; ++i) {
            int r = sem_uf_find(parent, i);
            if (root_origin[r] < 0) root_origin[r] = n_origins++;
            part_origin[i] = root_origin[r];
        }
        group_moments(d, parent, mom);
        double *X = calloc(3 * (size_t)n_origins, sizeof *X);
        if (!X) {
            free(part_origin);
            free(root_origin);
            goto nomem;
        }
        for (int i = 0; i < np; ++i) {
            if (sem_uf_find(parent, i) != i) continue;
            const double *mi = mom + 10 * (size_t)i;
            double *x = X + 3 * (size_t)root_origin[i];
            if (mi[0] > 0)
                for (int e = 0; e < 3; ++e) x[e] = mi[1 + e] / mi[0];
        }
        free(root_origin);
        sem_set_origins(d, X, part_origin, n_origins);
    }
    goto done;
nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
done:
    SEM_FREE_ALL(parent, join, self, gself, best, mom, settled, any_improving, pc, gpc);
    return st;
}
