/*
 * object_layout.c - the block structure of an object's matrices (see object.h): groups,
 * part pairs, group pairs, the storage of their blocks, and Pi per part as a dense matrix
 * over its group's control points.
 */
#include "object.h"

#include <stdlib.h>
#include <string.h>

static sem_status setup_groups(sem_object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    int ng = d->n_origins;
    o->n_groups = ng;
    o->group_start = calloc((size_t)ng + 1, sizeof(int));
    o->group_ctrl = malloc((size_t)o->n_ctrl * sizeof(int));
    o->ctrl_group = malloc((size_t)o->n_ctrl * sizeof(int));
    o->ctrl_local = malloc((size_t)o->n_ctrl * sizeof(int));
    if (!o->group_start || !o->group_ctrl || !o->ctrl_group || !o->ctrl_local)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        if (g < 0 || g >= ng)
            return sem_error_set(err, SEM_ERR_INVALID, "part %d has no valid origin", i);
        o->group_start[g + 1] += d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i];
    }
    for (int g = 0; g < ng; ++g) o->group_start[g + 1] += o->group_start[g];
    int *fill = malloc((size_t)ng * sizeof(int));
    if (!fill) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(fill, o->group_start, (size_t)ng * sizeof(int));
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        for (int c = d->part_ctrl_offset[i]; c < d->part_ctrl_offset[i + 1]; ++c) {
            o->ctrl_group[c] = g;
            o->ctrl_local[c] = fill[g] - o->group_start[g];
            o->group_ctrl[fill[g]++] = c;
        }
    }
    free(fill);
    /* dense Pi per part over its group's control points */
    o->pi_dense = calloc((size_t)(o->n_parts > 0 ? o->n_parts : 1), sizeof(double *));
    if (!o->pi_dense) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    int m = o->m;
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        size_t n = sem_group_size(o, g);
        o->pi_dense[i] = calloc((size_t)m * n, sizeof(double));
        if (!o->pi_dense[i]) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int k = 0; k < m; ++k) {
            int row = i * m + k;
            for (int e = d->Pi.row_start[row]; e < d->Pi.row_start[row + 1]; ++e) {
                int c = d->Pi.col[e];
                if (o->ctrl_group[c] != g)
                    return sem_error_set(err, SEM_ERR_INVALID,
                                         "projection of part %d reaches a control point outside "
                                         "its origin's parts",
                                         i);
                o->pi_dense[i][(size_t)k * n + (size_t)o->ctrl_local[c]] = d->Pi.val[e];
            }
        }
    }
    return SEM_OK;
}

/* Part pairs from the weights at quadrature points and boundary samples; group pairs
 * from part pairs and from the error matrix. */
static sem_status setup_pairs(sem_object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    int np = o->n_parts, ng = o->n_groups;
    o->pair_lookup = malloc((size_t)np * np * sizeof(int));
    o->gpair_lookup = malloc((size_t)ng * ng * sizeof(int));
    if (!o->pair_lookup || !o->gpair_lookup) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (size_t k = 0; k < (size_t)np * np; ++k) o->pair_lookup[k] = -1;
    for (size_t k = 0; k < (size_t)ng * ng; ++k) o->gpair_lookup[k] = -1;
    int cap = 64;
    o->pair_a = malloc((size_t)cap * sizeof(int));
    o->pair_b = malloc((size_t)cap * sizeof(int));
    if (!o->pair_a || !o->pair_b) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    const sem_csr *Ws[2] = {&d->W, &d->W_samples};
    for (int w = 0; w < 2; ++w) {
        const sem_csr *W = Ws[w];
        for (int p = 0; p < W->n_rows; ++p)
            for (int a = W->row_start[p]; a < W->row_start[p + 1]; ++a)
                for (int b = W->row_start[p]; b < W->row_start[p + 1]; ++b) {
                    int i = W->col[a], j = W->col[b];
                    if (o->pair_lookup[(size_t)i * np + j] >= 0) continue;
                    if (o->n_pairs == cap) {
                        cap *= 2;
                        int *x = realloc(o->pair_a, (size_t)cap * sizeof(int));
                        if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                        o->pair_a = x;
                        x = realloc(o->pair_b, (size_t)cap * sizeof(int));
                        if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                        o->pair_b = x;
                    }
                    o->pair_lookup[(size_t)i * np + j] = o->n_pairs;
                    o->pair_a[o->n_pairs] = i;
                    o->pair_b[o->n_pairs] = j;
                    o->n_pairs++;
                }
    }
    /* structured matrices have no group-pair blocks (structured.h) */
    if (o->structured) return SEM_OK;
    /* group pairs: from part pairs, and from the error matrix's pattern */
    o->part_pair_gpair = malloc((size_t)o->n_pairs * sizeof(int));
    int gcap = 64;
    o->gpair_a = malloc((size_t)gcap * sizeof(int));
    o->gpair_b = malloc((size_t)gcap * sizeof(int));
    if (!o->part_pair_gpair || !o->gpair_a || !o->gpair_b)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
#define ADD_GPAIR(ga, gb)                                                                   \
    do {                                                                                    \
        size_t key_ = (size_t)(ga) * ng + (size_t)(gb);                                     \
        if (o->gpair_lookup[key_] < 0) {                                                    \
            if (o->n_gpairs == gcap) {                                                      \
                gcap *= 2;                                                                  \
                int *x_ = realloc(o->gpair_a, (size_t)gcap * sizeof(int));                  \
                if (!x_) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");         \
                o->gpair_a = x_;                                                            \
                x_ = realloc(o->gpair_b, (size_t)gcap * sizeof(int));                       \
                if (!x_) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");         \
                o->gpair_b = x_;                                                            \
            }                                                                               \
            o->gpair_lookup[key_] = o->n_gpairs;                                            \
            o->gpair_a[o->n_gpairs] = (ga);                                                 \
            o->gpair_b[o->n_gpairs] = (gb);                                                 \
            o->n_gpairs++;                                                                  \
        }                                                                                   \
    } while (0)
    for (int k = 0; k < o->n_pairs; ++k) {
        int ga = d->part_origin[o->pair_a[k]], gb = d->part_origin[o->pair_b[k]];
        ADD_GPAIR(ga, gb);
        o->part_pair_gpair[k] = o->gpair_lookup[(size_t)ga * ng + gb];
    }
    for (int r = 0; r < d->M_eps.n_rows; ++r)
        for (int e = d->M_eps.row_start[r]; e < d->M_eps.row_start[r + 1]; ++e) {
            int ga = o->ctrl_group[r], gb = o->ctrl_group[d->M_eps.col[e]];
            ADD_GPAIR(ga, gb);
        }
    for (int r = 0; r < d->M.n_rows; ++r)
        for (int e = d->M.row_start[r]; e < d->M.row_start[r + 1]; ++e) {
            int ga = o->ctrl_group[r], gb = o->ctrl_group[d->M.col[e]];
            ADD_GPAIR(ga, gb);
        }
    /* welded control points (object_welds.c): their tie rows join the error matrix */
    for (int k = 0; k < o->n_welds; ++k) {
        int ga = o->ctrl_group[o->weld_ctrl[2 * k]], gb = o->ctrl_group[o->weld_ctrl[2 * k + 1]];
        ADD_GPAIR(ga, ga);
        ADD_GPAIR(gb, gb);
        ADD_GPAIR(ga, gb);
        ADD_GPAIR(gb, ga);
    }
    /* seam ties (object_seam_ties.c): rows over both points' control points */
    for (int t = 0; t < o->n_seam_ties; ++t) {
        int e0, e1;
        seam_tie_row(o, t, &e0, &e1);
        for (int x = e0; x < e1; ++x)
            for (int y = e0; y < e1; ++y)
                ADD_GPAIR(o->ctrl_group[o->seams.row_ctrl[x]], o->ctrl_group[o->seams.row_ctrl[y]]);
    }
#undef ADD_GPAIR
    o->gpair_offset = malloc(((size_t)o->n_gpairs + 1) * sizeof(size_t));
    if (!o->gpair_offset) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    o->gpair_offset[0] = 0;
    for (int k = 0; k < o->n_gpairs; ++k)
        o->gpair_offset[k + 1] = o->gpair_offset[k] + sem_group_size(o, o->gpair_a[k]) * sem_group_size(o, o->gpair_b[k]);
    /* part pairs per group pair (for a parallel, race-free Pi^T Kz Pi) */
    o->gpair_pairs_start = calloc((size_t)o->n_gpairs + 1, sizeof(int));
    o->gpair_pairs = malloc(((size_t)o->n_pairs + 1) * sizeof(int));
    if (!o->gpair_pairs_start || !o->gpair_pairs) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int k = 0; k < o->n_pairs; ++k) o->gpair_pairs_start[o->part_pair_gpair[k] + 1]++;
    for (int g = 0; g < o->n_gpairs; ++g) o->gpair_pairs_start[g + 1] += o->gpair_pairs_start[g];
    int *fill = malloc(((size_t)o->n_gpairs + 1) * sizeof(int));
    if (!fill) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(fill, o->gpair_pairs_start, (size_t)o->n_gpairs * sizeof(int));
    for (int k = 0; k < o->n_pairs; ++k) o->gpair_pairs[fill[o->part_pair_gpair[k]]++] = k;
    free(fill);
    /* within a group pair, pairs with the same first part are consecutive (see the
     * projection in assemble_elastic) */
    for (int g = 0; g < o->n_gpairs; ++g) {
        int a = o->gpair_pairs_start[g], b = o->gpair_pairs_start[g + 1];
        for (int k = a + 1; k < b; ++k) {
            int x = o->gpair_pairs[k], j = k - 1;
            while (j >= a && o->pair_a[o->gpair_pairs[j]] > o->pair_a[x]) {
                o->gpair_pairs[j + 1] = o->gpair_pairs[j];
                --j;
            }
            o->gpair_pairs[j + 1] = x;
        }
    }
    size_t total = o->gpair_offset[o->n_gpairs];
    o->K_blocks = calloc(9 * total + 1, sizeof(double));
    o->K0_blocks = calloc(9 * total + 1, sizeof(double));
    o->M_blocks = calloc(total + 1, sizeof(double));
    o->E_blocks = calloc(total + 1, sizeof(double));
    if (!o->K_blocks || !o->K0_blocks || !o->M_blocks || !o->E_blocks)
        return sem_error_set(err, SEM_ERR_NOMEM,
                             "out of memory for the system blocks (%zu entries)", 9 * total);
    return SEM_OK;
}

size_t sem_max_group_size(const sem_object *o)
{
    size_t mx = 1;
    for (int g = 0; g < o->n_groups; ++g)
        if (sem_group_size(o, g) > mx) mx = sem_group_size(o, g);
    return mx;
}

sem_status sem_object_layout_init(sem_object *o, sem_error *err)
{
    sem_status st = setup_groups(o, err);
    if (st == SEM_OK) st = setup_pairs(o, err);
    return st;
}
