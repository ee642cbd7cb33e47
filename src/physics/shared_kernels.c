/*
 * shared_kernels.c - the z-space and error-row kernels that the assembly, the mass and error
 * matrices and the structured solver all use (see shared_kernels.h). A leaf of src/physics/:
 * it needs only the object's layout (object.h), so the files that use it do not need each
 * other for it.
 */
#include "shared_kernels.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Part pair pr is a <= b and shares a quadrature point: its stiffness block Kz is formed
 * (W rows list parts in increasing order). */
int sem_pair_has_points(const sem_object *o, int pr)
{
    return o->plist_start[pr + 1] > o->plist_start[pr];
}

/* T with b(y + s) = T b(y) for the polynomial basis (m x m, row-major): the change from a
 * part's own basis, b(X - Xbar_i) with s = ref_X - Xbar_i, to the shared one, b(X - ref_X). */
void sem_basis_shift(int m, const double s[3], double *T)
{
    memset(T, 0, (size_t)m * m * sizeof(double));
    for (int k = 0; k < m; ++k) T[k * m + k] = 1.0;
    for (int e = 0; e < 3; ++e) T[(1 + e) * m] = s[e];
    if (m < 10) return;
    /* b4..b9 = xy, xz, yz, x^2, y^2, z^2 */
    static const int pa[6] = {0, 0, 1, 0, 1, 2}, pb[6] = {1, 2, 2, 0, 1, 2};
    for (int q = 0; q < 6; ++q) {
        double *row = T + (size_t)(4 + q) * m;
        int a = pa[q], b = pb[q];
        row[0] = s[a] * s[b];
        row[1 + a] += s[b];
        row[1 + b] += s[a];
    }
}

const double *sem_centered(sem_object *o, const double *q, const double *ref)
{
    double mean[3] = {0, 0, 0};
    for (int c = 0; c < o->n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) mean[k] += q[3 * c + k] - (ref ? ref[3 * c + k] : 0);
    for (int k = 0; k < 3; ++k) mean[k] /= o->n_ctrl > 0 ? o->n_ctrl : 1;
    for (int c = 0; c < o->n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) o->qc[3 * c + k] = q[3 * c + k] - (ref ? ref[3 * c + k] : 0) - mean[k];
    return o->qc;
}

void sem_part_rows_multiply(const sem_object *o, int i, const double *rows, int n_rows, const double *x,
                            double *zi)
{
    int g = o->d->part_origin[i];
    size_t n = sem_group_size(o, g);
    const int *ctrl = o->group_ctrl + o->group_start[g];
    for (int k = 0; k < n_rows; ++k) {
        const double *row = rows + (size_t)k * n;
        double s0 = 0, s1 = 0, s2 = 0;
        for (size_t j = 0; j < n; ++j) {
            const double *xc = x + 3 * (size_t)ctrl[j];
            s0 += row[j] * xc[0];
            s1 += row[j] * xc[1];
            s2 += row[j] * xc[2];
        }
        zi[k * 3 + 0] = s0;
        zi[k * 3 + 1] = s1;
        zi[k * 3 + 2] = s2;
    }
}

void sem_shared_coefficients(const sem_object *o, const double *x, double *z)
{
    int ma = o->ma;
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int i = 0; i < o->n_parts; ++i) sem_part_rows_multiply(o, i, o->pi_shared[i], ma, x, z + (size_t)i * ma * 3);
}

void sem_shared_add_transpose(const sem_object *o, const double *z, double *y)
{
    int ma = o->ma;
    /* groups own disjoint control points: one thread per group, its parts in order (the
     * same bits as the serial loop over parts) */
#pragma omp parallel for schedule(dynamic, 1) num_threads(o->nthreads)
    for (int g = 0; g < o->n_groups; ++g) {
        size_t n = sem_group_size(o, g);
        const int *ctrl = o->group_ctrl + o->group_start[g];
        for (int i = 0; i < o->n_parts; ++i) {
            if (o->d->part_origin[i] != g) continue;
            const double *zi = z + (size_t)i * ma * 3;
            for (int k = 0; k < ma; ++k) {
                const double *row = o->pi_shared[i] + (size_t)k * n;
                for (size_t j = 0; j < n; ++j) {
                    double *yc = y + 3 * (size_t)ctrl[j];
                    yc[0] += row[j] * zi[k * 3 + 0];
                    yc[1] += row[j] * zi[k * 3 + 1];
                    yc[2] += row[j] * zi[k * 3 + 2];
                }
            }
        }
    }
}

void sem_stiffness_z_multiply(const sem_object *o, double ca, const double *Ka, double cb, const double *Kb,
                              const double *x, double *y, double *work)
{
    int ma = o->ma, n3 = 3 * ma;
    size_t nz = (size_t)o->n_parts * n3, bs = (size_t)n3 * n3;
    double *zs = work, *out = work + nz;
    sem_shared_coefficients(o, x, zs);
    memset(out, 0, nz * sizeof(double));
    /* Kz rows (k, d) = 3k + d, columns (d', k') = d' ma + k'; z entries 3k + d. Part a's
     * output sums its pairs in pair order, as a (K_ab z_b) or as b (K_ba^T z_a'), one thread
     * per part: the same bits on any thread count. */
    int *start = calloc((size_t)o->n_parts + 1, sizeof(int));
    int *list = malloc((2 * (size_t)o->n_pairs + 1) * sizeof(int));
    if (!start || !list) {
        free(start);
        free(list);
        return; /* unreachable in practice; the product is then incomplete */
    }
    for (int pr = 0; pr < o->n_pairs; ++pr)
        if (o->pair_a[pr] <= o->pair_b[pr] && sem_pair_has_points(o, pr)) {
            start[o->pair_a[pr] + 1]++;
            if (o->pair_b[pr] != o->pair_a[pr]) start[o->pair_b[pr] + 1]++;
        }
    for (int p = 0; p < o->n_parts; ++p) start[p + 1] += start[p];
    for (int pr = 0; pr < o->n_pairs; ++pr) {
        if (o->pair_a[pr] > o->pair_b[pr] || !sem_pair_has_points(o, pr)) continue;
        list[start[o->pair_a[pr]]++] = pr;
        if (o->pair_b[pr] != o->pair_a[pr]) list[start[o->pair_b[pr]]++] = pr;
    }
    for (int p = o->n_parts; p > 0; --p) start[p] = start[p - 1];
    start[0] = 0;
#pragma omp parallel for schedule(dynamic, 4) num_threads(o->nthreads)
    for (int p = 0; p < o->n_parts; ++p) {
        double *op = out + (size_t)p * n3;
        for (int e = start[p]; e < start[p + 1]; ++e) {
            int pr = list[e], a = o->pair_a[pr], b = o->pair_b[pr];
            const double *K = Ka + (size_t)pr * bs, *K2 = Kb ? Kb + (size_t)pr * bs : NULL;
            if (a == p) {
                const double *zb = zs + (size_t)b * n3;
                for (int r = 0; r < n3; ++r)
                    for (int d2 = 0; d2 < 3; ++d2)
                        for (int k2 = 0; k2 < ma; ++k2) {
                            size_t at = (size_t)r * n3 + (size_t)(d2 * ma + k2);
                            double v = ca * K[at] + (K2 ? cb * K2[at] : 0);
                            op[r] += v * zb[3 * k2 + d2];
                        }
            }
            if (b == p && a != b) {
                const double *za = zs + (size_t)a * n3;
                for (int r = 0; r < n3; ++r)
                    for (int d2 = 0; d2 < 3; ++d2)
                        for (int k2 = 0; k2 < ma; ++k2) {
                            size_t at = (size_t)r * n3 + (size_t)(d2 * ma + k2);
                            double v = ca * K[at] + (K2 ? cb * K2[at] : 0);
                            op[3 * k2 + d2] += v * za[r];
                        }
            }
        }
    }
    free(start);
    free(list);
    sem_shared_add_transpose(o, out, y);
}

/* The error rows' floor (shared_kernels.h): 5 % of each part's mean sample area, per part. */
double *sem_error_part_floors(const sem_discretization *d, int n_parts)
{
    double *part_mean = calloc((size_t)n_parts + 1, sizeof(double));
    int *part_count = calloc((size_t)n_parts + 1, sizeof(int));
    if (!part_mean || !part_count) {
        free(part_mean);
        free(part_count);
        return NULL;
    }
    for (int r = 0; r < d->n_samples; ++r) {
        part_mean[d->sample_part[r]] += d->sample_area[r];
        part_count[d->sample_part[r]]++;
    }
    for (int i = 0; i < n_parts; ++i) part_mean[i] = part_count[i] ? 0.05 * part_mean[i] / part_count[i] : 0;
    free(part_count);
    return part_mean;
}

sem_status sem_error_rows(const sem_object *o, sem_error_row **rows, int *n_rows, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *Ws = &d->W_samples;
    const int split = o->def.seams != SEM_SEAMS_PAPER;
    *rows = NULL;
    *n_rows = 0;
    size_t n = 0;
    for (int r = 0; r < d->n_samples; ++r) {
        int k = Ws->row_start[r + 1] - Ws->row_start[r];
        n += split && k > 1 ? (size_t)k : 1;
    }
    if (n > (size_t)INT_MAX / 2) return sem_error_set(err, SEM_ERR_INVALID, "too many error rows (%zu)", n);
    double *part_floor = sem_error_part_floors(d, o->n_parts);
    sem_error_row *out = malloc((n + 1) * sizeof *out);
    if (!part_floor || !out) {
        free(part_floor);
        free(out);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    size_t at = 0;
    for (int r = 0; r < d->n_samples; ++r) {
        double fl = part_floor[d->sample_part[r]];
        int e0 = Ws->row_start[r], e1 = Ws->row_start[r + 1];
        if (!split || e1 - e0 <= 1) {
            out[at++] = (sem_error_row){r, -1, fmax(d->sample_area[r], fl)};
            continue;
        }
        double seam = fmax(d->sample_seam ? d->sample_seam[r] : d->sample_area[r], fl);
        for (int e = e0; e < e1; ++e) out[at++] = (sem_error_row){r, e, seam * Ws->val[e]};
    }
    free(part_floor);
    *rows = out;
    *n_rows = (int)n;
    return SEM_OK;
}
