/*
 * weights.c - blending weights by secondary rays (paper Sec. 6.1, Eq. 8-9).
 *
 * For a point X and a part i within the cut-off distance alpha:
 *   X*        = closest point of part i to X               (sem_raycast_closest_parts)
 *   d_primary = |X - X*|
 *   X^h       = first hit of the secondary ray from X* through X on any part
 *   d_total   = |X^h - X*|  (no hit: infinity)
 *   theta_i   = max(1 - d_primary / min(d_total, alpha), 0)                  (Eq. 8)
 * and the weights solve min w^T diag(1/theta) w s.t. sum w = 1, 0 <= w <= 1 (Eq. 9), whose
 * closed form is w_i = theta_i / sum_k theta_k. Small weights (< threshold) are dropped and
 * the rest renormalised so that W is sparse and every row still sums to one.
 *
 * Choices the paper leaves open (documented here, tested in tests/test_weights.c):
 *  - Self hit ("inside a closed part"): theta_i = 1 when the secondary ray's first hit is on
 *    part i itself *beyond X*. X* is the closest point of part i, so the open segment X* X
 *    cannot touch part i; a self hit closer than X can only be a single-precision re-hit of
 *    the triangles around X* (Embree works in float), so it is skipped and the ray is cast
 *    again from just past it. Hits whose double-precision distance is below t_near (a part
 *    through X* itself) are skipped the same way.
 *  - X on a part (d_primary <= 1e-6 x model extent): theta = 1 for every part through X
 *    (equal weights on an intersection line or a shared edge) and 0 for all others, with
 *    no secondary rays. This is Eq. 8 in exact arithmetic: the secondary ray of any other
 *    part j reaches the part X lies on at X itself, so d_total_j <= d_primary_j. Casting
 *    those rays instead would be ill-posed (a ray from a cube's edge to a point of an
 *    adjacent face grazes that face, and float decides whether it is hit). So a point on
 *    a part's surface away from other parts has weight exactly 1 there (Kronecker delta).
 *    Boundary samples know their own part and are treated as lying on it, whatever the
 *    tessellation's chord error.
 *  - Every theta zero (X farther than alpha from every part, or occluded from all of them):
 *    the nearest part gets weight 1 (ties: lowest part index). The nearest part is found
 *    with a query radius that covers the whole model. Rows never contain NaN and always
 *    sum to one.
 *  - The threshold never empties a row: the largest weight is always kept.
 *
 * alpha: explicit (> 0), or found by bisection so that nnz(W) / (n_quad n_parts) approaches
 * the target sparsity T (stop when within 1% of T, relative, or after 30 halvings; keep the
 * alpha whose fraction came closest), or half the median part size (default_alpha). A T that even
 * alpha = diagonal does not reach (occlusion zeroes many theta) gets alpha = diagonal, the
 * densest W the model allows. theta depends on alpha only through "d_primary <= alpha" and
 * min(d_total, alpha), so the expensive part (closest points and secondary rays) is
 * computed once at the largest radius of the search and every bisection step only
 * re-evaluates Eq. 8-9 on the stored distances; W is then built from the same distances.
 * The bisection's nnz is not exactly monotone in alpha (the threshold and renormalisation
 * act per row), which is harmless for a search that keeps the best alpha seen.
 *
 * Threads: OpenMP over points; each point's candidates and row depend on that point only and
 * are merged serially in point order, so W is identical for any thread count.
 */
#include "steps.h"
#include "util/free_all.h"
#include "util/grow.h"
#include "util/threads.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

/* Tolerances relative to the model's extent: Embree intersects in single precision (ray
 * origins are rounded to float), so anything finer than ~1e-7 of the model size is noise. */
#define SEM_WEIGHTS_ON_SURFACE 1e-6
#define SEM_WEIGHTS_T_NEAR 1e-6
#define SEM_WEIGHTS_MAX_RECAST 8

/* Per-point candidate parts with their alpha-independent distances. d_total < 0 marks a
 * theta forced to 1 (X on the part, own part of a sample, or self hit beyond X). */
typedef struct weight_candidates {
    int n_points;
    int *start; /* n_points + 1 */
    int *part;
    double *d_primary;
    double *d_total;
} weight_candidates;

static void candidates_free(weight_candidates *c)
{
    SEM_FREE_ALL(c->start, c->part, c->d_primary, c->d_total);
    memset(c, 0, sizeof *c);
}

/* Growable per-thread buffer of candidates. */
typedef struct candidate_buffer {
    size_t n, cap;
    int *part;
    double *d_primary, *d_total;
} candidate_buffer;

static int buffer_reserve(candidate_buffer *b, size_t extra)
{
    if (b->n + extra <= b->cap) return 1;
    size_t cap = b->cap ? b->cap : 256;
    while (cap < b->n + extra) cap *= 2;
    if (!sem_resize((void **)&b->part, cap, sizeof *b->part) ||
        !sem_resize((void **)&b->d_primary, cap, sizeof *b->d_primary) ||
        !sem_resize((void **)&b->d_total, cap, sizeof *b->d_total))
        return 0;
    b->cap = cap;
    return 1;
}

typedef struct scene_scale {
    double lo[3], hi[3];
    double diagonal;
    double on_surface; /* d_primary below this: X is on the part */
    double t_near;     /* secondary rays start this far from X* */
} scene_scale;

static scene_scale scene_scale_of(const sem_raycast_scene *scene)
{
    scene_scale s;
    sem_raycast_bounds(scene, s.lo, s.hi);
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) d2 += (s.hi[k] - s.lo[k]) * (s.hi[k] - s.lo[k]);
    s.diagonal = sqrt(d2);
    if (!(s.diagonal > 0.0) || !isfinite(s.diagonal)) s.diagonal = 1.0;
    /* ray origins are rounded to float: the tolerances grow with the coordinates too */
    double extent = s.diagonal;
    for (int k = 0; k < 3; ++k) extent = fmax(extent, fmax(fabs(s.lo[k]), fabs(s.hi[k])));
    s.on_surface = SEM_WEIGHTS_ON_SURFACE * extent;
    s.t_near = SEM_WEIGHTS_T_NEAR * extent;
    return s;
}

/* Default cut-off when neither alpha nor a sparsity is given: half the median part size
 * (the diagonal of the bounding box of each part's boundary samples, in the object's frame so
 * that it does not change when the object is turned). The paper's own
 * settings are of that order (beams: 0.51 for 1 m faces). A model-wide scale such as half
 * the bounding-box diagonal blends far-away parts into every point; measured on the default
 * scene's 2 m beam (0.5 m sections), that made the clamped beam sag to a centre of mass 8 m
 * below the clamp in statics, against 0.5-0.7 m for alpha up to 0.4. */
static double default_alpha(const sem_discretization *d, double fallback)
{
    double median = 0.0;
    if (sem_part_sizes(d, NULL, &median) != SEM_OK || !(median > 0)) return 0.5 * fallback;
    return 0.5 * median;
}

/* A radius that contains every part from X: distance to the bounding box plus its diagonal. */
static double covering_radius(const scene_scale *s, const double X[3])
{
    double d2 = 0.0;
    for (int k = 0; k < 3; ++k) {
        double e = 0.0;
        if (X[k] < s->lo[k]) e = s->lo[k] - X[k];
        if (X[k] > s->hi[k]) e = X[k] - s->hi[k];
        d2 += e * e;
    }
    return 1.01 * (sqrt(d2) + s->diagonal) + 1e-12;
}

/* d_total for part `part` seen from its closest point Xs towards X (Eq. 8), or -1 when the
 * first hit is part itself beyond X (theta forced to 1). */
static double secondary_distance(const sem_raycast_scene *scene, const scene_scale *s, int part,
                                 const double Xs[3], const double X[3], double d_primary)
{
    double dir[3];
    for (int k = 0; k < 3; ++k) dir[k] = (X[k] - Xs[k]) / d_primary;
    double t_near = s->t_near;
    for (int attempt = 0; attempt < SEM_WEIGHTS_MAX_RECAST; ++attempt) {
        sem_ray_hit hit;
        if (!sem_raycast_first(scene, Xs, dir, t_near, INFINITY, &hit)) return INFINITY;
        if (!(hit.t >= t_near)) {
            /* Embree accepted the hit in float but its double distance is below t_near
             * (a part through X* itself): like any hit closer than t_near, skip it */
            t_near = 2.0 * t_near + fabs(hit.t);
            continue;
        }
        if (hit.part != part) return hit.t;
        if (hit.t >= d_primary * (1.0 - 1e-9)) return -1.0; /* inside a closed part */
        /* float re-hit of part i near X*: skip it */
        t_near = hit.t + s->t_near;
    }
    return INFINITY;
}

/* Candidates of every point within `radius` (plus the nearest part when none is). own_part
 * (may be NULL) gives each point a part it lies on. Returns SEM_OK or SEM_ERR_NOMEM. */
static sem_status gather_candidates(const sem_raycast_scene *scene, const scene_scale *s,
                                    int n_points, const double *X, const int *own_part,
                                    double radius, int n_threads, weight_candidates *out)
{
    memset(out, 0, sizeof *out);
    const int n_parts = sem_raycast_part_count(scene);
    const int max_threads = sem_threads(n_threads);
    int *point_thread = malloc(((size_t)n_points + 1) * sizeof *point_thread);
    size_t *point_offset = malloc(((size_t)n_points + 1) * sizeof *point_offset);
    int *point_count = malloc(((size_t)n_points + 1) * sizeof *point_count);
    candidate_buffer *buffers = calloc((size_t)max_threads, sizeof *buffers);
    int failed = !point_thread || !point_offset || !point_count || !buffers;

    if (!failed) {
#pragma omp parallel num_threads(max_threads)
        {
            int tid = 0;
#ifdef _OPENMP
            tid = omp_get_thread_num();
#endif
            candidate_buffer *b = &buffers[tid];
            int *parts = malloc(((size_t)n_parts + 1) * sizeof *parts);
            double *dist = malloc(((size_t)n_parts + 1) * sizeof *dist);
            double *points = malloc(((size_t)n_parts + 1) * 3 * sizeof *points);
            int *order = malloc(((size_t)n_parts + 1) * sizeof *order);
            int local_failed = !parts || !dist || !points || !order;
            if (local_failed) {
#pragma omp atomic write
                failed = 1;
            }
#pragma omp for schedule(dynamic, 16)
            for (int p = 0; p < n_points; ++p) {
                if (local_failed) continue;
                const double *x = &X[3 * (size_t)p];
                /* a sample lies on its own part, so only parts through it matter (see
                 * the header): a tiny query radius, far cheaper than alpha */
                const int own = own_part ? own_part[p] : -1;
                const double query = own >= 0 ? s->on_surface : radius;
                /* (its own part is added below with theta 1 whatever its distance) */
                int found = sem_raycast_closest_parts_except(scene, x, query, own, parts, dist, points);
                int fallback_only = 0;
                if (found <= 0 && own < 0) {
                    /* nothing within the radius: keep only the nearest part, for the
                     * "every theta is zero" rule */
                    found = sem_raycast_closest_parts(scene, x, covering_radius(s, x), parts, dist,
                                                      points);
                    fallback_only = 1;
                }
                if (found < 0) found = 0;
                if (found > n_parts) found = n_parts;
                if (fallback_only && found > 1) {
                    int best = 0;
                    for (int k = 1; k < found; ++k)
                        if (dist[k] < dist[best] || (dist[k] == dist[best] && parts[k] < parts[best]))
                            best = k;
                    parts[0] = parts[best];
                    dist[0] = dist[best];
                    memcpy(points, &points[3 * best], 3 * sizeof *points);
                    found = 1;
                }
                /* a sample's own part is always a candidate with theta 1 */
                int have_own = 0;
                for (int k = 0; k < found; ++k) have_own |= parts[k] == own;
                int total = found + (own >= 0 && own < n_parts && !have_own);
                if (!buffer_reserve(b, (size_t)total)) {
                    local_failed = 1;
#pragma omp atomic write
                    failed = 1;
                    continue;
                }
                /* sort by part index so rows come out with sorted columns */
                for (int k = 0; k < found; ++k) order[k] = k;
                for (int a = 1; a < found; ++a) { /* insertion sort: lists are short */
                    int v = order[a], c = a - 1;
                    while (c >= 0 && parts[order[c]] > parts[v]) {
                        order[c + 1] = order[c];
                        --c;
                    }
                    order[c + 1] = v;
                }
                /* X on one or more parts (or a sample on its own part): in Eq. 8 the
                 * secondary ray of any other part j reaches the part X lies on at X itself,
                 * so d_total_j <= d_primary_j and theta_j = 0; the parts through X get
                 * theta 1. Applied directly instead of by (grazing, float) rays. */
                int on_surface = own >= 0 && own < n_parts;
                for (int k = 0; k < found; ++k) on_surface |= !(dist[k] > s->on_surface);
                size_t base = b->n;
                for (int j = 0; j < found; ++j) {
                    int k = order[j];
                    int part = parts[k];
                    double dp = dist[k], dt;
                    if (on_surface) {
                        if (part != own && dp > s->on_surface) continue;
                        dp = 0.0;
                        dt = -1.0;
                    } else {
                        dt = secondary_distance(scene, s, part, &points[3 * k], x, dp);
                    }
                    b->part[b->n] = part;
                    b->d_primary[b->n] = dp;
                    b->d_total[b->n] = dt;
                    b->n++;
                }
                if (total > found) { /* own part missed by the query: insert in order */
                    size_t at = base;
                    while (at < b->n && b->part[at] < own) ++at;
                    for (size_t m = b->n; m > at; --m) {
                        b->part[m] = b->part[m - 1];
                        b->d_primary[m] = b->d_primary[m - 1];
                        b->d_total[m] = b->d_total[m - 1];
                    }
                    b->part[at] = own;
                    b->d_primary[at] = 0.0;
                    b->d_total[at] = -1.0;
                    b->n++;
                }
                point_thread[p] = tid;
                point_offset[p] = base;
                point_count[p] = (int)(b->n - base);
            }
            SEM_FREE_ALL(parts, dist, points, order);
        }
    }

    if (!failed) {
        size_t total = 0;
        for (int t = 0; t < max_threads; ++t) total += buffers[t].n;
        out->n_points = n_points;
        out->start = malloc(((size_t)n_points + 1) * sizeof *out->start);
        out->part = malloc((total ? total : 1) * sizeof *out->part);
        out->d_primary = malloc((total ? total : 1) * sizeof *out->d_primary);
        out->d_total = malloc((total ? total : 1) * sizeof *out->d_total);
        if (!out->start || !out->part || !out->d_primary || !out->d_total || total > (size_t)INT_MAX) {
            failed = 1;
        } else {
            size_t at = 0;
            out->start[0] = 0;
            for (int p = 0; p < n_points; ++p) {
                const candidate_buffer *b = &buffers[point_thread[p]];
                size_t o = point_offset[p], n = (size_t)point_count[p];
                memcpy(&out->part[at], &b->part[o], n * sizeof *out->part);
                memcpy(&out->d_primary[at], &b->d_primary[o], n * sizeof *out->d_primary);
                memcpy(&out->d_total[at], &b->d_total[o], n * sizeof *out->d_total);
                at += n;
                out->start[p + 1] = (int)at;
            }
        }
    }
    if (buffers)
        for (int t = 0; t < max_threads; ++t) {
            free(buffers[t].part);
            free(buffers[t].d_primary);
            free(buffers[t].d_total);
        }
    SEM_FREE_ALL(buffers, point_thread, point_offset, point_count);
    if (failed) {
        candidates_free(out);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

/* Eq. 8-9 for one point at cut-off alpha: writes the row (sorted parts, weights summing to
 * one) into cols/vals (room for the point's candidate count) and returns its length (>= 1
 * when the point has any candidate). */
static int evaluate_row(const weight_candidates *c, int p, double alpha, double threshold,
                        int *cols, double *vals)
{
    const int b = c->start[p], e = c->start[p + 1];
    int n = 0;
    double sum = 0.0;
    for (int k = b; k < e; ++k) {
        double dp = c->d_primary[k], dt = c->d_total[k];
        if (!(dp <= alpha)) continue;
        double theta;
        if (dt < 0.0) {
            theta = 1.0;
        } else {
            double reach = dt < alpha ? dt : alpha;
            theta = reach > 0.0 ? 1.0 - dp / reach : 0.0;
            if (!(theta > 0.0 && theta <= 1.0)) theta = 0.0;
        }
        if (theta > 0.0) {
            cols[n] = c->part[k];
            vals[n] = theta;
            sum += theta;
            ++n;
        }
    }
    if (n == 0) {
        /* every theta is zero: the nearest part takes the point (see the header) */
        int best = -1;
        for (int k = b; k < e; ++k)
            if (best < 0 || c->d_primary[k] < c->d_primary[best]) best = k;
        if (best < 0) return 0;
        cols[0] = c->part[best];
        vals[0] = 1.0;
        return 1;
    }
    /* Eq. 9 closed form, then drop small weights and renormalise (largest always kept) */
    int largest = 0;
    for (int k = 1; k < n; ++k)
        if (vals[k] > vals[largest]) largest = k;
    int m = 0;
    double kept = 0.0;
    for (int k = 0; k < n; ++k) {
        double w = vals[k] / sum;
        if (w < threshold && k != largest) continue;
        cols[m] = cols[k];
        vals[m] = w;
        kept += w;
        ++m;
    }
    for (int k = 0; k < m; ++k) vals[k] /= kept;
    return m;
}

static int max_candidates(const weight_candidates *c)
{
    int most = 1;
    for (int p = 0; p < c->n_points; ++p)
        if (c->start[p + 1] - c->start[p] > most) most = c->start[p + 1] - c->start[p];
    return most;
}

/* evaluate_row's scratch, one per thread: room for the most candidates any point has. Both
 * NULL, and *failed set, when out of memory. */
typedef struct row_scratch {
    int *cols;
    double *vals;
} row_scratch;

static row_scratch row_scratch_alloc(int most, int *failed)
{
    row_scratch r = {malloc((size_t)most * sizeof *r.cols), malloc((size_t)most * sizeof *r.vals)};
    if (!r.cols || !r.vals) {
        free(r.cols);
        free(r.vals);
        r.cols = NULL;
        r.vals = NULL;
#pragma omp atomic write
        *failed = 1;
    }
    return r;
}

static void row_scratch_free(row_scratch *r)
{
    free(r->cols);
    free(r->vals);
}

/* Number of non-zero weights at cut-off alpha, or -1 when out of memory. */
static long long count_nonzeros(const weight_candidates *c, double alpha, double threshold,
                                int n_threads)
{
    const int most = max_candidates(c);
    long long nnz = 0;
    int failed = 0;
#pragma omp parallel num_threads(n_threads > 0 ? n_threads : 1) reduction(+ : nnz)
    {
        row_scratch r = row_scratch_alloc(most, &failed);
#pragma omp for schedule(static)
        for (int p = 0; p < c->n_points; ++p)
            if (r.cols) nnz += evaluate_row(c, p, alpha, threshold, r.cols, r.vals);
        row_scratch_free(&r);
    }
    return failed ? -1 : nnz;
}

/* W (n_points x n_parts, CSR) at cut-off alpha. */
static sem_status build_matrix(const weight_candidates *c, int n_parts, double alpha,
                               double threshold, int n_threads, sem_csr *W)
{
    memset(W, 0, sizeof *W);
    const int n = c->n_points;
    const int most = max_candidates(c);
    int *length = malloc(((size_t)n + 1) * sizeof *length);
    if (!length) return SEM_ERR_NOMEM;
    int failed = 0;
    /* Two passes over the rows with the same scratch: their lengths, then (with W sized) the
     * rows themselves. evaluate_row uses room for every candidate before dropping small
     * weights, so rows are evaluated in scratch and copied. */
#pragma omp parallel num_threads(n_threads > 0 ? n_threads : 1)
    {
        row_scratch r = row_scratch_alloc(most, &failed);
#pragma omp for schedule(static)
        for (int p = 0; p < n; ++p)
            length[p] = r.cols ? evaluate_row(c, p, alpha, threshold, r.cols, r.vals) : 0;
#pragma omp single
        {
            size_t nnz = 0;
            for (int p = 0; p < n; ++p) nnz += (size_t)length[p];
            if (failed || nnz > (size_t)INT_MAX || sem_csr_alloc(W, n, n_parts, nnz) != SEM_OK) {
                failed = 1;
            } else {
                W->row_start[0] = 0;
                for (int p = 0; p < n; ++p) W->row_start[p + 1] = W->row_start[p] + length[p];
            }
        }
#pragma omp for schedule(static)
        for (int p = 0; p < n; ++p) {
            if (failed || !r.cols) continue;
            const int at = W->row_start[p];
            const int m = evaluate_row(c, p, alpha, threshold, r.cols, r.vals);
            memcpy(&W->col[at], r.cols, (size_t)m * sizeof *r.cols);
            memcpy(&W->val[at], r.vals, (size_t)m * sizeof *r.vals);
        }
        row_scratch_free(&r);
    }
    free(length);
    if (failed) {
        sem_csr_free(W);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

static sem_status check_points(int n_points, const double *X, const char *what, sem_error *err)
{
    if (n_points < 0) return sem_error_set(err, SEM_ERR_INVALID, "weights: negative %s count", what);
    if (n_points > 0 && !X)
        return sem_error_set(err, SEM_ERR_INVALID, "weights: %s positions missing", what);
    for (size_t k = 0; k < 3 * (size_t)n_points; ++k)
        if (!isfinite(X[k]))
            return sem_error_set(err, SEM_ERR_INVALID, "weights: %s %zu has a non-finite coordinate",
                                 what, k / 3);
    return SEM_OK;
}

static sem_status check_threshold(double threshold, sem_error *err)
{
    if (!(threshold >= 0.0 && threshold < 1.0))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "weights: weight threshold %g must be in [0, 1)", threshold);
    return SEM_OK;
}

static sem_status blend_weights(const sem_raycast_scene *scene, int n_points, const double *X,
                                const int *own_part, double alpha, double threshold,
                                int n_threads, sem_csr *W, sem_error *err)
{
    scene_scale s = scene_scale_of(scene);
    weight_candidates c;
    sem_status st = gather_candidates(scene, &s, n_points, X, own_part, alpha, n_threads, &c);
    if (st != SEM_OK) return sem_error_set(err, st, "weights: out of memory");
    st = build_matrix(&c, sem_raycast_part_count(scene), alpha, threshold, n_threads, W);
    candidates_free(&c);
    if (st != SEM_OK) return sem_error_set(err, st, "weights: out of memory");
    return SEM_OK;
}

sem_status sem_blend_weights(const sem_raycast_scene *scene, int n_points, const double *X,
                             double alpha, double threshold, sem_csr *W, sem_error *err)
{
    if (W) memset(W, 0, sizeof *W);
    if (!scene || !W) return sem_error_set(err, SEM_ERR_INVALID, "weights: missing scene or output");
    if (sem_raycast_part_count(scene) <= 0)
        return sem_error_set(err, SEM_ERR_INVALID, "weights: the scene has no parts");
    if (!(alpha > 0.0) || !isfinite(alpha))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "weights: alpha (cut-off distance) must be positive and finite, got %g",
                             alpha);
    sem_status st = check_threshold(threshold, err);
    if (st == SEM_OK) st = check_points(n_points, X, "point", err);
    if (st != SEM_OK) return st;
    return blend_weights(scene, n_points, X, NULL, alpha, threshold, sem_threads(0), W, err);
}

/* Fraction of non-zero weights at cut-off alpha, or -1 when out of memory. */
static double nonzero_fraction(const weight_candidates *c, int n_parts, double alpha,
                               double threshold, int n_threads)
{
    if (c->n_points == 0) return 0.0;
    long long nnz = count_nonzeros(c, alpha, threshold, n_threads);
    return nnz < 0 ? -1.0 : (double)nnz / ((double)c->n_points * (double)n_parts);
}

/* alpha whose non-zero fraction is closest to the target T (bisection, see the header).
 * The closest-point queries dominate and grow with the radius, so the smallest radius in
 * {1/4, 1/2, 1} x diagonal that reaches T is first found on a subsample of at most 256
 * points; all points are then gathered once at that radius (doubling again if the full
 * set falls short) and the bisection only re-evaluates Eq. 8-9. The candidates are handed
 * back in *c, valid for any alpha up to the radius, so W is built without a new gather. */
static sem_status alpha_from_sparsity(const sem_raycast_scene *scene, const scene_scale *s,
                                      const sem_discretization *d, double target,
                                      double threshold, int n_threads, double *alpha_out,
                                      weight_candidates *c, sem_error *err)
{
    const int n_parts = d->n_parts;
    const double tolerance = 0.01 * target;
    double radius = 0.25 * s->diagonal, f_hi;

    const int stride = d->n_quad > 256 ? (d->n_quad + 255) / 256 : 1;
    if (stride > 1) {
        const int n_sub = (d->n_quad + stride - 1) / stride;
        double *sub = malloc(3 * (size_t)n_sub * sizeof *sub);
        if (!sub) return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
        for (int k = 0; k < n_sub; ++k)
            memcpy(&sub[3 * (size_t)k], &d->quad_X[3 * (size_t)k * stride], 3 * sizeof *sub);
        for (;;) {
            if (gather_candidates(scene, s, n_sub, sub, NULL, radius, n_threads, c) != SEM_OK) {
                free(sub);
                return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
            }
            f_hi = nonzero_fraction(c, n_parts, radius, threshold, n_threads);
            candidates_free(c);
            if (f_hi < 0.0) {
                free(sub);
                return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
            }
            if (f_hi >= target || radius >= s->diagonal) break;
            radius = fmin(2.0 * radius, s->diagonal);
        }
        free(sub);
    }
    for (;;) {
        if (gather_candidates(scene, s, d->n_quad, d->quad_X, NULL, radius, n_threads, c) != SEM_OK)
            return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
        f_hi = nonzero_fraction(c, n_parts, radius, threshold, n_threads);
        if (f_hi < 0.0) {
            candidates_free(c);
            return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
        }
        /* alpha beyond the diagonal changes nothing: every distance is shorter; a target
         * that is not reached there gets the largest fraction the model allows */
        if (f_hi >= target || radius >= s->diagonal) break;
        candidates_free(c);
        radius = fmin(2.0 * radius, s->diagonal);
    }
    double best_alpha = radius, best_gap = fabs(f_hi - target);
    double lo = 0.0, hi = radius;
    for (int it = 0; it < 30 && best_gap > tolerance && f_hi >= target; ++it) {
        const double mid = 0.5 * (lo + hi);
        const double f = nonzero_fraction(c, n_parts, mid, threshold, n_threads);
        if (f < 0.0) {
            candidates_free(c);
            return sem_error_set(err, SEM_ERR_NOMEM, "weights: out of memory");
        }
        if (fabs(f - target) < best_gap) {
            best_gap = fabs(f - target);
            best_alpha = mid;
        }
        if (f < target)
            lo = mid;
        else
            hi = mid;
    }
    *alpha_out = best_alpha;
    return SEM_OK;
}

sem_status sem_step_weights(const sem_model *model, const sem_raycast_scene *scene,
                            const sem_preprocess_options *o, sem_discretization *d,
                            sem_error *err)
{
    (void)model;
    if (!scene || !o || !d)
        return sem_error_set(err, SEM_ERR_INVALID, "weights: missing scene, options or data");
    const int n_parts = sem_raycast_part_count(scene);
    if (n_parts <= 0) return sem_error_set(err, SEM_ERR_INVALID, "weights: the scene has no parts");
    if (d->n_parts > 0 && d->n_parts != n_parts)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "weights: the discretization has %d parts but the scene %d", d->n_parts,
                             n_parts);
    if (!(o->alpha >= 0.0) || !isfinite(o->alpha))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "weights: alpha (cut-off distance) must be positive, got %g", o->alpha);
    if (o->sparsity != 0.0 && !(o->sparsity > 0.0 && o->sparsity < 1.0))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "weights: target sparsity %g must be in (0, 1)", o->sparsity);
    sem_status st = check_threshold(o->weight_threshold, err);
    if (st == SEM_OK) st = check_points(d->n_quad, d->quad_X, "quadrature point", err);
    if (st == SEM_OK) st = check_points(d->n_samples, d->sample_X, "boundary sample", err);
    if (st != SEM_OK) return st;
    if (d->n_samples > 0 && !d->sample_part)
        return sem_error_set(err, SEM_ERR_INVALID, "weights: boundary samples without parts");
    for (int k = 0; k < d->n_samples; ++k)
        if (d->sample_part[k] < 0 || d->sample_part[k] >= n_parts)
            return sem_error_set(err, SEM_ERR_INVALID, "weights: sample %d has part %d of %d", k,
                                 d->sample_part[k], n_parts);
    d->n_parts = n_parts;

    const int n_threads = sem_threads(o->threads);
    scene_scale s = scene_scale_of(scene);
    double alpha = 0.0;
    weight_candidates c;
    memset(&c, 0, sizeof c);
    if (o->alpha > 0.0) {
        alpha = o->alpha;
    } else if (o->sparsity > 0.0 && d->n_quad > 0) {
        st = alpha_from_sparsity(scene, &s, d, o->sparsity, o->weight_threshold, n_threads, &alpha,
                                 &c, err);
        if (st != SEM_OK) return st;
        if (!(alpha > 0.0)) { /* bisection collapsed on alpha -> 0 */
            candidates_free(&c);
            alpha = 0.5 * s.diagonal;
        }
    } else {
        alpha = default_alpha(d, s.diagonal);
    }

    sem_csr_free(&d->W);
    sem_csr_free(&d->W_samples);
    if (c.start) { /* candidates of the sparsity search cover alpha: no new gather */
        st = build_matrix(&c, n_parts, alpha, o->weight_threshold, n_threads, &d->W);
        candidates_free(&c);
        if (st != SEM_OK) st = sem_error_set(err, st, "weights: out of memory");
    } else {
        st = blend_weights(scene, d->n_quad, d->quad_X, NULL, alpha, o->weight_threshold,
                           n_threads, &d->W, err);
    }
    if (st == SEM_OK)
        st = blend_weights(scene, d->n_samples, d->sample_X, d->sample_part, alpha,
                           o->weight_threshold, n_threads, &d->W_samples, err);
    if (st != SEM_OK) {
        sem_csr_free(&d->W);
        sem_csr_free(&d->W_samples);
        return st;
    }
    d->alpha = alpha;
    d->weight_nonzero_fraction =
        d->n_quad > 0 ? (double)sem_csr_nnz(&d->W) / ((double)d->n_quad * (double)n_parts) : 0.0;
    return SEM_OK;
}
