/*
 * trim.c - inside/outside queries on trimmed parameter domains.
 *
 * Why polygons and even-odd: CAD exporters orient trim loops inconsistently (Rhino writes
 * holes clockwise, others do not care), and loops arrive as chains of curves whose
 * directions are not always head-to-tail. Counting crossings over every loop together
 * gives "inside the outer loop and outside every hole" without needing orientation.
 * Each curve is flattened per non-empty knot span finely enough (32 + 8 * degree points)
 * that the polygon departs from the curve by far less than any sampling spacing we use.
 * Queries are bucketed by v so that one query only visits the edges of its row.
 *
 * Bounds. A part's loops may hold at most SEM_MAX_TRIM_CURVES curves and
 * SEM_MAX_TRIM_SEGMENTS knot spans in all (sem/limits.h), which bounds the polygons. An
 * edge is stored once in every bucket its v range overlaps, so a loop of long zig-zag
 * edges would fill every bucket: the bucket count is halved until the stored entries are
 * at most a small multiple of the edges. Bucket indices are computed in floating point
 * and clamped before the conversion to int (coordinates like 1e308 give inf and NaN).
 */
#include "sem/trim.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/limits.h"
#include "sem/nurbs.h"

typedef struct polygon {
    int n;        /* vertices */
    double *uv;   /* 2n */
} polygon;

struct sem_trim_region {
    double u0, u1, v0, v1;
    int n_loops;
    polygon *loops;
    int trimmed;
    /* v-buckets of edges: edges of all loops, bucket b holds edges overlapping its v band */
    int n_buckets;
    int *bucket_start; /* n_buckets + 1 */
    double *edges;     /* 4 doubles per bucketed edge entry: u_a, v_a, u_b, v_b */
    double bv0, bv1;
};

static int push_point(polygon *p, int *cap, double u, double v)
{
    if (p->n == *cap) {
        int nc = *cap ? 2 * *cap : 64;
        double *x = realloc(p->uv, (size_t)nc * 2 * sizeof *x);
        if (!x) return 0;
        p->uv = x;
        *cap = nc;
    }
    p->uv[2 * p->n] = u;
    p->uv[2 * p->n + 1] = v;
    p->n++;
    return 1;
}

static double dist2d(const double *a, const double *b)
{
    return hypot(a[0] - b[0], a[1] - b[1]);
}

/* floor(f) clamped to [0, n - 1]; NaN gives 0 (no undefined float-to-int conversion) */
static int clamp_index(double f, int n)
{
    if (!(f > 0)) return 0;
    if (f >= n - 1) return n - 1;
    return (int)f;
}

/* Checks a part's trim loops against the curve and knot-span limits. */
static sem_status check_trim_size(const sem_part *part, sem_error *err)
{
    long long curves = 0, spans = 0;
    int n_loops = (part->has_outer ? 1 : 0) + part->n_holes;
    for (int l = 0; l < n_loops; ++l) {
        const sem_trim_loop *loop = part->has_outer && l == 0 ? &part->outer
                                                              : &part->holes[l - part->has_outer];
        curves += loop->n_curves;
        for (int c = 0; c < loop->n_curves; ++c) {
            const sem_curve *cv = &loop->curves[c];
            /* distinct knots in range bound the spans */
            long long n = 1;
            for (int i = cv->degree + 1; i < cv->n_ctrl; ++i)
                n += cv->knots[i] > cv->knots[i - 1] && cv->knots[i] > cv->t0 && cv->knots[i] < cv->t1;
            spans += n;
        }
    }
    if (curves > SEM_MAX_TRIM_CURVES)
        return sem_error_set(err, SEM_ERR_INVALID, "trim loops have %lld curves; at most %d per "
                                                   "part (limit SEM_MAX_TRIM_CURVES)",
                             curves, SEM_MAX_TRIM_CURVES);
    if (spans > SEM_MAX_TRIM_SEGMENTS)
        return sem_error_set(err, SEM_ERR_INVALID, "trim curves have %lld knot spans; at most %d "
                                                   "per part (limit SEM_MAX_TRIM_SEGMENTS)",
                             spans, SEM_MAX_TRIM_SEGMENTS);
    return SEM_OK;
}

/* Flattens one loop. Curves may run either way; each is appended in the direction that
 * continues the chain. Returns SEM_OK or an error naming the gap. */
static sem_status flatten_loop(const sem_trim_loop *loop, double tol, polygon *out,
                               const char *what, sem_error *err)
{
    int cap = 0;
    memset(out, 0, sizeof *out);
    double first[2] = {0, 0}, last[2] = {0, 0};
    for (int c = 0; c < loop->n_curves; ++c) {
        const sem_curve *cv = &loop->curves[c];
        /* at most n_ctrl - degree + 1 breaks (distinct knots in range plus the ends) */
        int max_breaks = cv->n_ctrl - cv->degree + 2;
        double *breaks = malloc((size_t)max_breaks * sizeof *breaks);
        if (!breaks) {
            free(out->uv);
            out->uv = NULL;
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory flattening a trim loop");
        }
        int nb = sem_knot_breaks(cv->degree, cv->n_ctrl, cv->knots, cv->t0, cv->t1, breaks,
                                 max_breaks);
        int per = 32 + 8 * cv->degree;
        double a[3], b[3];
        sem_curve_eval(cv, cv->t0, a, NULL);
        sem_curve_eval(cv, cv->t1, b, NULL);
        int reverse = 0;
        if (c == 0) {
            /* orient the first curve towards the second when there is one */
            if (loop->n_curves > 1) {
                const sem_curve *nx = &loop->curves[1];
                double c0[3], c1[3];
                sem_curve_eval(nx, nx->t0, c0, NULL);
                sem_curve_eval(nx, nx->t1, c1, NULL);
                double db = fmin(dist2d(b, c0), dist2d(b, c1));
                double da = fmin(dist2d(a, c0), dist2d(a, c1));
                reverse = da < db;
            }
        } else {
            double ds = dist2d(last, a), de = dist2d(last, b);
            reverse = de < ds;
            double gap = fmin(ds, de);
            if (gap > tol) {
                free(breaks);
                free(out->uv);
                out->uv = NULL;
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "%s does not close: gap %.3g between curve %d and curve %d "
                                     "(tolerance %.3g)",
                                     what, gap, c, c + 1, tol);
            }
        }
        int total = (nb - 1) * per;
        for (int k = 0; k <= total; ++k) {
            int kk = reverse ? total - k : k;
            int span = kk / per, r = kk % per;
            double t = span >= nb - 1 ? breaks[nb - 1]
                                      : breaks[span] + (breaks[span + 1] - breaks[span]) * r / per;
            double x[3];
            sem_curve_eval(cv, t, x, NULL);
            if (c > 0 && k == 0) continue; /* shared with the previous curve's end */
            if (!push_point(out, &cap, x[0], x[1])) {
                free(breaks);
                free(out->uv);
                out->uv = NULL;
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory flattening a trim loop");
            }
        }
        free(breaks);
        if (c == 0) {
            first[0] = out->uv[0];
            first[1] = out->uv[1];
        }
        last[0] = out->uv[2 * (out->n - 1)];
        last[1] = out->uv[2 * (out->n - 1) + 1];
    }
    if (out->n < 3) {
        free(out->uv);
        out->uv = NULL;
        return sem_error_set(err, SEM_ERR_INVALID, "%s has fewer than 3 points", what);
    }
    double gap = dist2d(first, last);
    if (gap > tol) {
        free(out->uv);
        out->uv = NULL;
        return sem_error_set(err, SEM_ERR_INVALID,
                             "%s does not close: gap %.3g between its end and its start "
                             "(tolerance %.3g)",
                             what, gap, tol);
    }
    return SEM_OK;
}

static double closure_tolerance(const sem_part *part)
{
    const sem_surface *s = &part->surface;
    return 1e-3 * hypot(s->u1 - s->u0, s->v1 - s->v0);
}

static sem_status build_buckets(sem_trim_region *r)
{
    double v0 = INFINITY, v1 = -INFINITY;
    size_t n_edges = 0;
    for (int l = 0; l < r->n_loops; ++l) {
        n_edges += (size_t)r->loops[l].n;
        for (int i = 0; i < r->loops[l].n; ++i) {
            double v = r->loops[l].uv[2 * i + 1];
            v0 = fmin(v0, v);
            v1 = fmax(v1, v);
        }
    }
    int nb = (int)fmin(1024.0, fmax(1.0, sqrt((double)n_edges) * 2));
    if (!(v1 > v0)) v1 = v0 + 1.0;
    if (!isfinite(v1 - v0)) nb = 1; /* coordinates near the double range: one bucket */
    /* fewer buckets until the entries stay within 4 per edge (plus a few) */
    for (;;) {
        size_t entries = 0;
        for (int l = 0; l < r->n_loops; ++l) {
            const polygon *p = &r->loops[l];
            for (int i = 0; i < p->n; ++i) {
                const double *a = p->uv + 2 * i, *b = p->uv + 2 * ((i + 1) % p->n);
                double lo = fmin(a[1], b[1]), hi = fmax(a[1], b[1]);
                entries += (size_t)(clamp_index((hi - v0) / (v1 - v0) * nb, nb) -
                                    clamp_index((lo - v0) / (v1 - v0) * nb, nb) + 1);
            }
        }
        if (nb == 1 || entries <= 4 * n_edges + 4096) break;
        nb /= 2;
    }
    r->n_buckets = nb;
    r->bv0 = v0;
    r->bv1 = v1;
    r->bucket_start = calloc((size_t)nb + 1, sizeof(int));
    if (!r->bucket_start) return SEM_ERR_NOMEM;
    /* two passes: count, then fill */
    for (int pass = 0; pass < 2; ++pass) {
        int *fill = NULL;
        if (pass == 1) {
            for (int b = 0; b < nb; ++b) r->bucket_start[b + 1] += r->bucket_start[b];
            r->edges = malloc((size_t)(r->bucket_start[nb] ? r->bucket_start[nb] : 1) * 4 *
                              sizeof(double));
            fill = malloc((size_t)nb * sizeof(int));
            if (!r->edges || !fill) {
                free(fill);
                return SEM_ERR_NOMEM;
            }
            memcpy(fill, r->bucket_start, (size_t)nb * sizeof(int));
        }
        for (int l = 0; l < r->n_loops; ++l) {
            const polygon *p = &r->loops[l];
            for (int i = 0; i < p->n; ++i) {
                const double *a = p->uv + 2 * i, *b = p->uv + 2 * ((i + 1) % p->n);
                double lo = fmin(a[1], b[1]), hi = fmax(a[1], b[1]);
                int b0 = clamp_index((lo - v0) / (v1 - v0) * nb, nb);
                int b1 = clamp_index((hi - v0) / (v1 - v0) * nb, nb);
                for (int bk = b0; bk <= b1; ++bk) {
                    if (pass == 0) {
                        r->bucket_start[bk + 1]++;
                    } else {
                        double *e = r->edges + 4 * (size_t)fill[bk]++;
                        e[0] = a[0];
                        e[1] = a[1];
                        e[2] = b[0];
                        e[3] = b[1];
                    }
                }
            }
        }
        free(fill);
    }
    return SEM_OK;
}

sem_status sem_trim_region_build(const sem_part *part, sem_trim_region **out, sem_error *err)
{
    *out = NULL;
    sem_trim_region *r = calloc(1, sizeof *r);
    if (!r) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    const sem_surface *s = &part->surface;
    r->u0 = s->u0;
    r->u1 = s->u1;
    r->v0 = s->v0;
    r->v1 = s->v1;
    int n_loops = (part->has_outer ? 1 : 0) + part->n_holes;
    r->trimmed = n_loops > 0;
    if (!r->trimmed) {
        *out = r;
        return SEM_OK;
    }
    /* without an outer trim loop the domain rectangle is the outer loop */
    int with_rect = part->has_outer ? 0 : 1;
    r->loops = calloc((size_t)(n_loops + with_rect), sizeof *r->loops);
    if (!r->loops) {
        free(r);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    double tol = closure_tolerance(part);
    sem_status st = check_trim_size(part, err);
    if (with_rect) {
        polygon *p = &r->loops[r->n_loops++];
        p->n = 4;
        p->uv = malloc(8 * sizeof(double));
        if (!p->uv) st = SEM_ERR_NOMEM;
        else {
            double q[8] = {s->u0, s->v0, s->u1, s->v0, s->u1, s->v1, s->u0, s->v1};
            memcpy(p->uv, q, sizeof q);
        }
    }
    if (st == SEM_OK && part->has_outer) {
        st = flatten_loop(&part->outer, tol, &r->loops[r->n_loops], "outer trim loop", err);
        if (st == SEM_OK) r->n_loops++;
    }
    for (int h = 0; st == SEM_OK && h < part->n_holes; ++h) {
        char what[64];
        snprintf(what, sizeof what, "hole %d trim loop", h + 1);
        st = flatten_loop(&part->holes[h], tol, &r->loops[r->n_loops], what, err);
        if (st == SEM_OK) r->n_loops++;
    }
    if (st == SEM_OK && build_buckets(r) != SEM_OK)
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    if (st != SEM_OK) {
        if (st == SEM_ERR_NOMEM && err && err->status != SEM_ERR_NOMEM)
            sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        sem_trim_region_destroy(r);
        return st;
    }
    *out = r;
    return SEM_OK;
}

void sem_trim_region_destroy(sem_trim_region *r)
{
    if (!r) return;
    for (int l = 0; l < r->n_loops; ++l) free(r->loops[l].uv);
    free(r->loops);
    free(r->bucket_start);
    free(r->edges);
    free(r);
}

int sem_trim_region_inside(const sem_trim_region *r, double u, double v)
{
    if (!r->trimmed) return u >= r->u0 && u <= r->u1 && v >= r->v0 && v <= r->v1;
    if (v < r->bv0 || v > r->bv1) return 0;
    int b = clamp_index((v - r->bv0) / (r->bv1 - r->bv0) * r->n_buckets, r->n_buckets);
    int crossings = 0;
    for (int k = r->bucket_start[b]; k < r->bucket_start[b + 1]; ++k) {
        const double *e = r->edges + 4 * (size_t)k;
        /* half-open rule: an edge counts when v is in [min, max) */
        if ((e[1] > v) != (e[3] > v)) {
            double x = e[0] + (v - e[1]) * (e[2] - e[0]) / (e[3] - e[1]);
            if (x > u) crossings++;
        }
    }
    return crossings & 1;
}

int sem_trim_region_loop_count(const sem_trim_region *r)
{
    return r->n_loops;
}

const double *sem_trim_region_loop(const sem_trim_region *r, int loop, int *n_vertices)
{
    if (loop < 0 || loop >= r->n_loops) {
        *n_vertices = 0;
        return NULL;
    }
    *n_vertices = r->loops[loop].n;
    return r->loops[loop].uv;
}

sem_status sem_part_validate_trims(const sem_part *part, sem_error *err)
{
    sem_trim_region *r;
    sem_status st = sem_trim_region_build(part, &r, err);
    sem_trim_region_destroy(r);
    return st;
}
