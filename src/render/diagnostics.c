/*
 * diagnostics.c - what the diagnostic colourings show: blending weights near the surface,
 * and quadrature points and deformation origins carried by the SEM map.
 *
 * Weights (paper Fig. 5). Eq. 8 makes the weights a Kronecker delta on the surface itself
 * (a surface point lies on its own part, so every other part's secondary ray stops there),
 * so colouring the surface by w_i(X) would only show part i. What the simulation blends is
 * the field inside, at the quadrature points; each surface point gets the inverse squared
 * distance average of the weights at its 8 nearest quadrature points. The nearest points
 * are found in a uniform grid (about 2 points per cell), searched in growing shells of
 * cells until no unvisited cell can be closer than the 8th point found.
 *
 * Motion (Eq. 6-7). A quadrature point X_p moves to x_p = sum_i w_pi b(X_p - Xbar_i)^T C_i
 * with C_i = Pi_i Q the coefficients of part i's fitted polynomial (Gamma_p q, Eq. 12,
 * without forming Gamma); an origin Xbar_j moves with the constant term of the parts
 * fitted about it, t_j (the first row of C_i, equal for all of them).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/render.h"

#define NEAREST 8

typedef struct point_grid {
    double lo[3], cell;
    int dims[3];
    int *start; /* cells + 1 */
    int *index; /* points sorted by cell */
} point_grid;

static int cell_of(const point_grid *g, const double X[3], int c[3])
{
    for (int k = 0; k < 3; ++k) {
        int i = (int)floor((X[k] - g->lo[k]) / g->cell);
        c[k] = i < 0 ? 0 : i >= g->dims[k] ? g->dims[k] - 1 : i;
    }
    return c[0] + g->dims[0] * (c[1] + g->dims[1] * c[2]);
}

static sem_status grid_build(point_grid *g, int n, const double *X, sem_error *err)
{
    double hi[3];
    for (int k = 0; k < 3; ++k) g->lo[k] = hi[k] = X[k];
    for (int p = 1; p < n; ++p)
        for (int k = 0; k < 3; ++k) {
            if (X[3 * p + k] < g->lo[k]) g->lo[k] = X[3 * p + k];
            if (X[3 * p + k] > hi[k]) hi[k] = X[3 * p + k];
        }
    double ext[3], volume = 1, diagonal = 0;
    for (int k = 0; k < 3; ++k) {
        ext[k] = hi[k] - g->lo[k];
        diagonal += ext[k] * ext[k];
    }
    diagonal = sqrt(diagonal);
    if (!(diagonal > 0)) diagonal = 1;
    for (int k = 0; k < 3; ++k) volume *= fmax(ext[k], 1e-3 * diagonal);
    g->cell = cbrt(2.0 * volume / n);
    long cells = 1;
    for (int k = 0; k < 3; ++k) {
        double d = ceil(fmax(ext[k], 1e-3 * diagonal) / g->cell);
        g->dims[k] = d < 1 ? 1 : d > 1024 ? 1024 : (int)d;
        cells *= g->dims[k];
    }
    g->start = calloc((size_t)cells + 1, sizeof *g->start);
    g->index = malloc((size_t)n * sizeof *g->index);
    int *cell = malloc((size_t)n * sizeof *cell);
    if (!g->start || !g->index || !cell) {
        free(cell);
        return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    }
    int c[3];
    for (int p = 0; p < n; ++p) {
        cell[p] = cell_of(g, &X[3 * p], c);
        g->start[cell[p] + 1]++;
    }
    for (long k = 0; k < cells; ++k) g->start[k + 1] += g->start[k];
    int *fill = malloc((size_t)cells * sizeof *fill);
    if (!fill) {
        free(cell);
        return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    }
    memcpy(fill, g->start, (size_t)cells * sizeof *fill);
    for (int p = 0; p < n; ++p) g->index[fill[cell[p]]++] = p; /* point order within a cell */
    free(fill);
    free(cell);
    return SEM_OK;
}

static void grid_free(point_grid *g)
{
    free(g->start);
    free(g->index);
}

/* The NEAREST (or fewer) closest points to Y: indices and squared distances, closest
 * first (ties: lower index first). Returns how many. */
static int nearest(const point_grid *g, const double *X, const double Y[3], int *best, double *best_d2)
{
    int found = 0, c[3];
    cell_of(g, Y, c);
    const int max_shell = g->dims[0] + g->dims[1] + g->dims[2];
    for (int r = 0; r <= max_shell; ++r) {
        double bound = (r - 1) * g->cell;
        if (found == NEAREST && bound > 0 && bound * bound > best_d2[found - 1]) break;
        for (int k = c[2] - r; k <= c[2] + r; ++k) {
            if (k < 0 || k >= g->dims[2]) continue;
            for (int j = c[1] - r; j <= c[1] + r; ++j) {
                if (j < 0 || j >= g->dims[1]) continue;
                for (int i = c[0] - r; i <= c[0] + r; ++i) {
                    if (i < 0 || i >= g->dims[0]) continue;
                    /* only the shell's surface */
                    if (abs(i - c[0]) != r && abs(j - c[1]) != r && abs(k - c[2]) != r) continue;
                    int cell = i + g->dims[0] * (j + g->dims[1] * k);
                    for (int s = g->start[cell]; s < g->start[cell + 1]; ++s) {
                        int p = g->index[s];
                        double d2 = 0;
                        for (int e = 0; e < 3; ++e) d2 += (X[3 * p + e] - Y[e]) * (X[3 * p + e] - Y[e]);
                        if (found == NEAREST && !(d2 < best_d2[found - 1] ||
                                                  (d2 == best_d2[found - 1] && p < best[found - 1])))
                            continue;
                        int at = found < NEAREST ? found++ : NEAREST - 1;
                        while (at > 0 && (best_d2[at - 1] > d2 || (best_d2[at - 1] == d2 && best[at - 1] > p))) {
                            best[at] = best[at - 1];
                            best_d2[at] = best_d2[at - 1];
                            at--;
                        }
                        best[at] = p;
                        best_d2[at] = d2;
                    }
                }
            }
        }
    }
    return found;
}

/* W[p, part], 0 when not stored. */
static double weight_of(const sem_csr *W, int p, int part)
{
    int lo = W->row_start[p], hi = W->row_start[p + 1] - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2;
        if (W->col[mid] == part) return W->val[mid];
        if (W->col[mid] < part)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return 0.0;
}

static sem_status check_weights(const sem_discretization *d, sem_error *err)
{
    if (!d || d->n_quad < 1 || !d->quad_X || !d->W.row_start || d->W.n_rows != d->n_quad ||
        d->W.n_cols != d->n_parts)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "render: the preprocessed data has no quadrature points with weights");
    return SEM_OK;
}

sem_status sem_render_part_weights(const sem_discretization *d, int part, int n, const double *X,
                                   float *weights, sem_error *err)
{
    sem_status st = check_weights(d, err);
    if (st != SEM_OK) return st;
    if (part < 0 || part >= d->n_parts)
        return sem_error_set(err, SEM_ERR_INVALID, "render: part %d does not exist (the model has parts 0..%d)",
                             part, d->n_parts - 1);
    point_grid g;
    memset(&g, 0, sizeof g);
    if ((st = grid_build(&g, d->n_quad, d->quad_X, err)) != SEM_OK) {
        grid_free(&g);
        return st;
    }
    /* a floor on the squared distance, so a point on a quadrature point is not infinite */
    const double floor2 = 1e-12 * g.cell * g.cell;
#pragma omp parallel for schedule(static)
    for (int v = 0; v < n; ++v) {
        int best[NEAREST];
        double best_d2[NEAREST];
        int found = nearest(&g, d->quad_X, &X[3 * (size_t)v], best, best_d2);
        double sum = 0, total = 0;
        for (int k = 0; k < found; ++k) {
            double w = 1.0 / (best_d2[k] + floor2);
            sum += w * weight_of(&d->W, best[k], part);
            total += w;
        }
        weights[v] = total > 0 ? (float)(sum / total) : 0.0f;
    }
    grid_free(&g);
    return SEM_OK;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y ? 1 : 0;
}

double sem_render_point_spacing(int n, const double *X)
{
    if (n < 2 || !X) return 0.0;
    point_grid g;
    memset(&g, 0, sizeof g);
    double *d = malloc((size_t)n * sizeof *d);
    if (!d || grid_build(&g, n, X, NULL) != SEM_OK) {
        free(d);
        grid_free(&g);
        return 0.0;
    }
#pragma omp parallel for schedule(static)
    for (int p = 0; p < n; ++p) {
        int best[NEAREST];
        double best_d2[NEAREST];
        int found = nearest(&g, X, &X[3 * (size_t)p], best, best_d2);
        d[p] = 0.0;
        for (int k = 0; k < found; ++k)
            if (best[k] != p) { /* the first other point (a duplicate counts, at 0) */
                d[p] = sqrt(best_d2[k]);
                break;
            }
    }
    qsort(d, (size_t)n, sizeof *d, compare_doubles);
    double median = d[n / 2];
    free(d);
    grid_free(&g);
    return median;
}

static sem_status check_map(const sem_discretization *d, sem_error *err)
{
    if (!d->Pi.row_start || d->Pi.n_rows != d->n_parts * d->n_basis || d->Pi.n_cols != d->n_ctrl ||
        !d->part_origin || (d->n_origins > 0 && !d->origin_X))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "render: the preprocessed data has no projection Pi or origins");
    return SEM_OK;
}

/* C_i = Pi_i Q for every part: n_parts x n_basis x 3. */
static double *coefficients(const sem_discretization *d, const double *q)
{
    double *C = malloc((size_t)d->n_parts * (size_t)d->n_basis * 3 * sizeof *C + 1);
    if (!C) return NULL;
    for (int i = 0; i < d->n_parts; ++i)
        sem_projection_coefficients(d, i, q, 3, &C[(size_t)i * d->n_basis * 3]);
    return C;
}

sem_status sem_render_map_quadrature(const sem_discretization *d, const double *q, double *x_out,
                                     sem_error *err)
{
    sem_status st = check_weights(d, err);
    if (st == SEM_OK) st = check_map(d, err);
    if (st != SEM_OK) return st;
    double *C = coefficients(d, q);
    if (!C) return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    const int m = d->n_basis;
#pragma omp parallel for schedule(static)
    for (int p = 0; p < d->n_quad; ++p) {
        double x[3] = {0, 0, 0};
        for (int s = d->W.row_start[p]; s < d->W.row_start[p + 1]; ++s) {
            const int i = d->W.col[s];
            const double *origin = &d->origin_X[3 * (size_t)d->part_origin[i]];
            double dX[3], b[10];
            for (int e = 0; e < 3; ++e) dX[e] = d->quad_X[3 * (size_t)p + e] - origin[e];
            sem_polynomial_basis(d->order, dX, b, NULL);
            const double *Ci = &C[(size_t)i * m * 3];
            for (int k = 0; k < m; ++k)
                for (int e = 0; e < 3; ++e) x[e] += d->W.val[s] * b[k] * Ci[3 * k + e];
        }
        for (int e = 0; e < 3; ++e) x_out[3 * (size_t)p + e] = x[e];
    }
    free(C);
    return SEM_OK;
}

sem_status sem_render_map_origins(const sem_discretization *d, const double *q, double *x_out,
                                  sem_error *err)
{
    sem_status st = check_map(d, err);
    if (st != SEM_OK) return st;
    double *C = coefficients(d, q);
    if (!C) return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    /* the origin's rest position when no part is fitted about it */
    memcpy(x_out, d->origin_X, 3 * (size_t)d->n_origins * sizeof *x_out);
    for (int i = d->n_parts - 1; i >= 0; --i) { /* the lowest part wins (all agree) */
        const int j = d->part_origin[i];
        for (int e = 0; e < 3; ++e) x_out[3 * (size_t)j + e] = C[(size_t)i * d->n_basis * 3 + e];
    }
    free(C);
    return SEM_OK;
}
