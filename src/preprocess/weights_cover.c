/*
 * weights_cover.c - every part must carry weight at some quadrature point.
 *
 * Why: a thin part (a rocket fin hit by no ray of a coarse grid) can end with no volume
 * point where its weight is non-zero: the secondary rays of Eq. 8 from its surface
 * through nearby interior points hit the body first, so theta = 0 everywhere. Its
 * polynomial then enters neither the mass nor the stiffness, and its control points can
 * move freely at zero energy: the system matrix is singular and the part would detach
 * from the body. The paper's Eq. 8-9 leave this case open. We blend such a part into the
 * quadrature points nearest to its surface: at the K nearest points (distance measured to
 * its boundary samples) it gets weight w = 0.5 d_min / d (0.5 at the nearest point,
 * less farther away) and the point's other weights are scaled by (1 - w), so rows still
 * sum to one. The part then moves with the body around it, as a thin attached feature
 * should. This runs after the weights and before the origins (which read W).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "steps.h"
#include "util/free_all.h"

#define COVER_POINTS 8

/* A quadrature point with a lower bound of its squared distance to a part. */
typedef struct point_bound {
    double bound;
    int point;
} point_bound;

static int by_bound(const point_bound *x, const point_bound *y)
{
    if (x->bound != y->bound) return x->bound < y->bound ? -1 : 1;
    return (x->point > y->point) - (x->point < y->point);
}

/* Squared distance from quadrature point p to the nearest boundary sample of part i. */
static double part_distance2(const sem_discretization *d, const int *part_start, const int *part_samples, int i,
                             int p)
{
    double dm = INFINITY;
    const double *X = d->quad_X + 3 * (size_t)p;
    for (int k = part_start[i]; k < part_start[i + 1]; ++k) {
        const double *S = d->sample_X + 3 * (size_t)part_samples[k];
        double dd = (X[0] - S[0]) * (X[0] - S[0]) + (X[1] - S[1]) * (X[1] - S[1]) + (X[2] - S[2]) * (X[2] - S[2]);
        if (dd < dm) dm = dd;
    }
    return dm;
}

sem_status sem_cover_unweighted_parts(sem_discretization *d, int *n_covered, sem_error *err)
{
    *n_covered = 0;
    int np = d->n_parts, nq = d->n_quad;
    if (nq == 0 || np == 0) return SEM_OK;
    unsigned char *seen = calloc((size_t)np, 1);
    if (!seen) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (size_t e = 0; e < sem_csr_nnz(&d->W); ++e)
        if (d->W.val[e] > 0) seen[d->W.col[e]] = 1;
    int missing = 0;
    for (int i = 0; i < np; ++i) missing += !seen[i];
    free(d->part_covered);
    d->part_covered = calloc((size_t)np, sizeof *d->part_covered);
    if (!d->part_covered) {
        free(seen);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < np; ++i) d->part_covered[i] = !seen[i];
    if (missing == 0) {
        free(seen);
        return SEM_OK;
    }
    /* triplets of the new W */
    size_t cap = sem_csr_nnz(&d->W) + (size_t)missing * COVER_POINTS;
    int *rows = malloc((cap + 1) * sizeof(int)), *cols = malloc((cap + 1) * sizeof(int));
    double *vals = malloc((cap + 1) * sizeof(double));
    double *scale = malloc((size_t)nq * sizeof(double));
    double *dist = malloc((size_t)nq * sizeof(double));
    point_bound *near = malloc((size_t)nq * sizeof *near);
    int *best = malloc(COVER_POINTS * sizeof(int));
    /* samples grouped by part, so a missing part scans only its own */
    int *part_start = NULL, *part_samples = NULL;
    int grouped = sem_samples_by_part(d, &part_start, &part_samples);
    if (!rows || !cols || !vals || !scale || !dist || !near || !best || !grouped) {
        SEM_FREE_ALL(rows, cols, vals, scale, dist, near, best, seen, part_start, part_samples);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int p = 0; p < nq; ++p) scale[p] = 1.0;
    size_t n = 0;
    /* new entries first (their rows' other weights are scaled below) */
    for (int i = 0; i < np; ++i) {
        if (seen[i]) continue;
        /* Distances to the part's samples, exactly for every point that can be among the
         * COVER_POINTS nearest (those whose distance to the samples' bounding box, a lower
         * bound, is within the upper bound below); the others get INFINITY, farther than any
         * chosen one, so the choice is that of the exact distances. */
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int k = part_start[i]; k < part_start[i + 1]; ++k)
            for (int e = 0; e < 3; ++e) {
                lo[e] = fmin(lo[e], d->sample_X[3 * (size_t)part_samples[k] + e]);
                hi[e] = fmax(hi[e], d->sample_X[3 * (size_t)part_samples[k] + e]);
            }
        for (int p = 0; p < nq; ++p) {
            const double *X = d->quad_X + 3 * (size_t)p;
            double b2 = 0;
            for (int e = 0; e < 3; ++e) {
                double g = X[e] < lo[e] ? lo[e] - X[e] : X[e] > hi[e] ? X[e] - hi[e] : 0;
                b2 += g * g;
            }
            near[p].bound = b2;
            near[p].point = p;
            dist[p] = INFINITY;
        }
        /* the COVER_POINTS points of smallest bound (partial selection), their exact
         * distances' largest is an upper bound U of the COVER_POINTS-th distance; then
         * every point whose bound is at most U */
        int k = nq < COVER_POINTS ? nq : COVER_POINTS;
        for (int j = 0; j < k; ++j) {
            int m = j;
            for (int p = j + 1; p < nq; ++p)
                if (by_bound(&near[p], &near[m]) < 0) m = p;
            point_bound t = near[j];
            near[j] = near[m];
            near[m] = t;
        }
        double U = 0;
        int n_eval = 0; /* the evaluated points, gathered at the front of near */
        for (int j = 0; j < k; ++j) {
            double dm = part_distance2(d, part_start, part_samples, i, near[j].point);
            dist[near[j].point] = sqrt(dm);
            U = fmax(U, dm);
            n_eval++;
        }
        for (int j = k; j < nq; ++j)
            if (near[j].bound <= U) {
                dist[near[j].point] = sqrt(part_distance2(d, part_start, part_samples, i, near[j].point));
                near[n_eval++] = near[j];
            }
        /* the k nearest: smallest distance, then lowest index */
        for (int j = 0; j < k; ++j) {
            int b = -1;
            for (int e = j; e < n_eval; ++e) {
                int p = near[e].point;
                if (b < 0 || dist[p] < dist[near[b].point] || (dist[p] == dist[near[b].point] && p < near[b].point))
                    b = e;
            }
            point_bound t = near[j];
            near[j] = near[b];
            near[b] = t;
            best[j] = near[j].point;
        }
        double dmin = dist[best[0]] > 0 ? dist[best[0]] : 1e-300;
        for (int j = 0; j < k; ++j) {
            int p = best[j];
            double w = 0.5 * (dist[p] > 0 ? dmin / dist[p] : 1.0);
            if (w > 0.5) w = 0.5;
            w *= scale[p]; /* a point covering several parts shares what is left */
            scale[p] -= w;
            rows[n] = p;
            cols[n] = i;
            vals[n++] = w;
        }
        (*n_covered)++;
    }
    for (int p = 0; p < nq; ++p)
        for (int e = d->W.row_start[p]; e < d->W.row_start[p + 1]; ++e) {
            rows[n] = p;
            cols[n] = d->W.col[e];
            vals[n++] = d->W.val[e] * scale[p];
        }
    sem_csr W;
    sem_status st = sem_csr_from_triplets(&W, nq, np, n, rows, cols, vals);
    if (st == SEM_OK) {
        sem_csr_free(&d->W);
        d->W = W;
        d->weight_nonzero_fraction = (double)sem_csr_nnz(&W) / ((double)nq * np);
    } else {
        sem_error_set(err, st, "out of memory");
    }
    SEM_FREE_ALL(rows, cols, vals, scale, dist, near, best, seen, part_start, part_samples);
    return st;
}
