/*
 * origins_merge.c - no deformation origin may see only a flat set of samples.
 *
 * Why: the linear fit of Eq. 7 about an origin Xbar is determined only in the directions
 * its group's boundary samples span. A group made of one planar part (a box face that the
 * min-cost flow of Sec. 6.2 left alone) has its origin in that plane, so the coefficient
 * of the normal direction is undetermined: the fit cannot reproduce an affine motion, and
 * quadrature points inside the volume near that face get a deformation gradient with a
 * zero column (det F = 0 at rest). Regularising cannot recover information the samples do
 * not hold, so the group borrows it from its neighbours: a degenerate group is merged
 * into the origin it shares the most blending weight with (the parts whose polynomials
 * are blended with its own), which keeps the groups a partition of the parts (Pi stays
 * block-sparse by origin) and makes every fit affine-exact. Merging stops when no group
 * is degenerate or one origin is left (a single flat model has no volume anyway).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/flatness.h"
#include "steps.h"
#include "util/free_all.h"

/* second moments of the samples of the parts in origin j about their centroid */
static void moments(const sem_discretization *d, const int *part_origin, int j, double centroid[3],
                    double C[6], double *area)
{
    double A = 0, s[3] = {0, 0, 0};
    for (int k = 0; k < d->n_samples; ++k) {
        if (part_origin[d->sample_part[k]] != j) continue;
        double a = d->sample_area[k];
        A += a;
        for (int e = 0; e < 3; ++e) s[e] += a * d->sample_X[3 * k + e];
    }
    for (int e = 0; e < 3; ++e) centroid[e] = A > 0 ? s[e] / A : 0.0;
    memset(C, 0, 6 * sizeof(double));
    for (int k = 0; k < d->n_samples; ++k) {
        if (part_origin[d->sample_part[k]] != j) continue;
        double a = d->sample_area[k];
        const double *X = d->sample_X + 3 * k;
        double x = X[0] - centroid[0], y = X[1] - centroid[1], z = X[2] - centroid[2];
        C[0] += a * x * x;
        C[1] += a * y * y;
        C[2] += a * z * z;
        C[3] += a * x * y;
        C[4] += a * x * z;
        C[5] += a * y * z;
    }
    *area = A;
}

sem_status sem_merge_degenerate_origins(sem_discretization *d, sem_error *err)
{
    int np = d->n_parts, no = d->n_origins;
    if (no <= 1) return SEM_OK;
    double *link = calloc((size_t)no * no, sizeof(double));
    int *alive = malloc((size_t)no * sizeof(int));
    double *cent = malloc(3 * (size_t)no * sizeof(double));
    if (!link || !alive || !cent) {
        free(link);
        free(alive);
        free(cent);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory merging origins");
    }
    /* blending links between origins: sum over points of w_a w_b for parts of each */
    for (int p = 0; p < d->W.n_rows; ++p)
        for (int a = d->W.row_start[p]; a < d->W.row_start[p + 1]; ++a)
            for (int b = d->W.row_start[p]; b < d->W.row_start[p + 1]; ++b) {
                int oa = d->part_origin[d->W.col[a]], ob = d->part_origin[d->W.col[b]];
                if (oa != ob) link[(size_t)oa * no + ob] += d->W.val[a] * d->W.val[b];
            }
    for (int j = 0; j < no; ++j) alive[j] = 1;
    int n_alive = no;
    for (int pass = 0; pass < no && n_alive > 1; ++pass) {
        int merged = 0;
        for (int j = 0; j < no && n_alive > 1; ++j) {
            if (!alive[j]) continue;
            double C[6], area;
            moments(d, d->part_origin, j, cent + 3 * j, C, &area);
            if (area > 0 && sem_eigenvalue_ratio(C) > 1e-8) continue;
            /* degenerate: the most linked live origin, else the nearest one */
            int best = -1;
            double bl = 0;
            for (int k = 0; k < no; ++k)
                if (k != j && alive[k] && link[(size_t)j * no + k] > bl) {
                    bl = link[(size_t)j * no + k];
                    best = k;
                }
            if (best < 0) {
                double bd = INFINITY;
                for (int k = 0; k < no; ++k) {
                    if (k == j || !alive[k]) continue;
                    double ck[3], Ck[6], ak;
                    moments(d, d->part_origin, k, ck, Ck, &ak);
                    double dd = hypot(hypot(ck[0] - cent[3 * j], ck[1] - cent[3 * j + 1]), ck[2] - cent[3 * j + 2]);
                    if (dd < bd) {
                        bd = dd;
                        best = k;
                    }
                }
            }
            if (best < 0) break;
            for (int i = 0; i < np; ++i)
                if (d->part_origin[i] == j) d->part_origin[i] = best;
            for (int k = 0; k < no; ++k) {
                link[(size_t)best * no + k] += link[(size_t)j * no + k];
                link[(size_t)k * no + best] += link[(size_t)k * no + j];
                link[(size_t)j * no + k] = link[(size_t)k * no + j] = 0;
            }
            link[(size_t)best * no + best] = 0;
            alive[j] = 0;
            n_alive--;
            merged = 1;
        }
        if (!merged) break;
    }
    /* renumber the live origins and recompute their positions (area-weighted centroids) */
    int *map = malloc((size_t)no * sizeof(int));
    if (!map) {
        free(link);
        free(alive);
        free(cent);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory merging origins");
    }
    int n_new = 0;
    for (int j = 0; j < no; ++j) map[j] = alive[j] ? n_new++ : -1;
    if (n_new != no) {
        double *X = malloc(3 * (size_t)n_new * sizeof(double));
        if (!X) {
            SEM_FREE_ALL(map, link, alive, cent);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory merging origins");
        }
        for (int i = 0; i < np; ++i) d->part_origin[i] = map[d->part_origin[i]];
        for (int j = 0; j < n_new; ++j) {
            double C[6], area;
            moments(d, d->part_origin, j, X + 3 * j, C, &area);
        }
        free(d->origin_X);
        d->origin_X = X;
        d->n_origins = n_new;
    }
    SEM_FREE_ALL(map, link, alive, cent);
    return SEM_OK;
}
