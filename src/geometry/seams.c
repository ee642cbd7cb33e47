/*
 * seams.c - where the parts of a model meet at rest, and how far those meetings open once
 * the control points move (see sem/measure.h, "Seams").
 *
 * Why: SEM moves every part's control points through its own polynomial (Eq. 6-7) and ties
 * the parts to each other only softly, through the blending weights and the error energy
 * (Eq. 16). Nothing in the method keeps two faces that touch at rest touching: when the
 * coupling is too weak for a load (large flat faces, few control points, contact forces on
 * a face's corners) the faces come apart, and the energies alone do not show it. A seam
 * monitor measures it directly, on the NURBS the user gets back.
 *
 * Seam points. Each part's boundary is walked in 3D: its trim loops (the polygons of
 * sem_trim_region, which follow the curves closely) or, untrimmed, the border of its
 * domain, with points spaced by about SPACING x the model size (and at least a few per
 * loop). A boundary point X of part a pairs with every other part b whose surface comes
 * within the tolerance of X inside b's trim (exact point inversion on b's NURBS, then,
 * when that lands outside b's trim, the nearest point of b's own trim boundary). Such a pair
 * is the same material point of the body seen from two faces; in a sound deformation it
 * stays together.
 *
 * Both points are kept as rows of the render map x = J q (the parts' rational basis at their
 * (u,v)), so measuring a state is two short dot products per pair: no NURBS evaluation, no
 * search. A pair's gap is how much farther apart its two points are than at rest.
 *
 * Cost: one pass over the parts' boundaries with candidate parts found by boxes (OpenMP over
 * parts; each part's pairs are collected on its own and concatenated in part order, so the
 * result is the same on any thread count).
 */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/closest_point.h"
#include "sem/measure.h"
#include "sem/nurbs.h"
#include "sem/trim.h"
#include "util/free_all.h"
#include "util/grow.h"

/* Boundary points about this far apart, relative to the model size. */
#define SPACING 0.01
/* ... but at least this many on each loop, and at most this many. */
#define MIN_LOOP_POINTS 8
#define MAX_LOOP_POINTS 400

typedef struct point_list {
    int n, cap;
    double *uv; /* 2 per point */
    double *X;  /* 3 per point */
    double *ds; /* per point: the walk's spacing there (the boundary length it stands for) */
} point_list;

static int point_push(point_list *l, const double uv[2], const double X[3], double ds)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        if (!sem_resize((void **)&l->uv, (size_t)cap * 2, sizeof(double)) ||
            !sem_resize((void **)&l->X, (size_t)cap * 3, sizeof(double)) ||
            !sem_resize((void **)&l->ds, (size_t)cap, sizeof(double)))
            return -1;
        l->cap = cap;
    }
    l->ds[l->n] = ds;
    memcpy(l->uv + 2 * (size_t)l->n, uv, 2 * sizeof(double));
    memcpy(l->X + 3 * (size_t)l->n, X, 3 * sizeof(double));
    l->n++;
    return 0;
}

static void point_list_free(point_list *l)
{
    free(l->uv);
    free(l->X);
    free(l->ds);
}

static double dist3(const double *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Points along one closed polygon in (u,v), spaced by about h in 3D. */
static int walk_loop(const sem_surface *s, const double *uv, int n, double h, point_list *out)
{
    if (n < 2) return 0;
    double *X = malloc((size_t)n * 3 * sizeof(double));
    if (!X) return -1;
    double length = 0;
    for (int i = 0; i < n; ++i) sem_surface_eval(s, uv[2 * i], uv[2 * i + 1], X + 3 * i, NULL, NULL, NULL);
    for (int i = 0; i < n; ++i) length += dist3(X + 3 * i, X + 3 * ((i + 1) % n));
    int want = length > 0 ? (int)ceil(length / h) : 1;
    if (want < MIN_LOOP_POINTS) want = MIN_LOOP_POINTS;
    if (want > MAX_LOOP_POINTS) want = MAX_LOOP_POINTS;
    int rc = 0;
    if (!(length > 0)) {
        /* a loop collapsed to a point (a pole): one point */
        rc = point_push(out, uv, X, 0.0);
        free(X);
        return rc;
    }
    double step = length / want, next = 0, run = 0;
    for (int i = 0; i < n && rc == 0; ++i) {
        const double *a = X + 3 * i, *b = X + 3 * ((i + 1) % n);
        const double *ua = uv + 2 * i, *ub = uv + 2 * ((i + 1) % n);
        double seg = dist3(a, b);
        /* this segment's points, run <= next < run + seg: the polygon's vertices are on the
         * curve; between them the (u,v) is interpolated and the point evaluated */
        for (; rc == 0 && next < run + seg; next += step) {
            double t = (next - run) / seg;
            double p[2] = {ua[0] + t * (ub[0] - ua[0]), ua[1] + t * (ub[1] - ua[1])}, x[3];
            sem_surface_eval(s, p[0], p[1], x, NULL, NULL, NULL);
            rc = point_push(out, p, x, step);
        }
        run += seg;
    }
    free(X);
    return rc;
}

/* The boundary points of part p: its trim polygons, or its domain's border. */
static int boundary_points(const sem_part *part, const sem_trim_region *region, double h, point_list *out)
{
    const sem_surface *s = &part->surface;
    int loops = sem_trim_region_loop_count(region);
    if (loops == 0) {
        /* the domain rectangle, its sides cut at the knots so the polygon follows the
         * surface (the walk evaluates between the vertices anyway) */
        double bu[514], bv[514];
        int nu = sem_knot_breaks(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, bu, 512);
        int nv = sem_knot_breaks(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, bv, 512);
        if (nu < 2) bu[0] = s->u0, bu[1] = s->u1, nu = 2;
        if (nv < 2) bv[0] = s->v0, bv[1] = s->v1, nv = 2;
        /* 8 vertices per knot span and side */
        int n = 8 * (2 * (nu - 1) + 2 * (nv - 1));
        double *uv = malloc((size_t)n * 2 * sizeof(double));
        if (!uv) return -1;
        int k = 0;
        for (int i = 0; i + 1 < nu; ++i)
            for (int j = 0; j < 8; ++j) uv[2 * k] = bu[i] + (bu[i + 1] - bu[i]) * j / 8.0, uv[2 * k + 1] = s->v0, ++k;
        for (int i = 0; i + 1 < nv; ++i)
            for (int j = 0; j < 8; ++j) uv[2 * k] = s->u1, uv[2 * k + 1] = bv[i] + (bv[i + 1] - bv[i]) * j / 8.0, ++k;
        for (int i = nu - 1; i > 0; --i)
            for (int j = 0; j < 8; ++j) uv[2 * k] = bu[i] - (bu[i] - bu[i - 1]) * j / 8.0, uv[2 * k + 1] = s->v1, ++k;
        for (int i = nv - 1; i > 0; --i)
            for (int j = 0; j < 8; ++j) uv[2 * k] = s->u0, uv[2 * k + 1] = bv[i] - (bv[i] - bv[i - 1]) * j / 8.0, ++k;
        int rc = walk_loop(s, uv, k, h, out);
        free(uv);
        return rc;
    }
    for (int l = 0; l < loops; ++l) {
        int n = 0;
        const double *uv = sem_trim_region_loop(region, l, &n);
        /* the region's loops end where they start: drop the repeated vertex */
        if (n > 1 && uv[0] == uv[2 * (n - 1)] && uv[1] == uv[2 * (n - 1) + 1]) --n;
        if (walk_loop(s, uv, n, h, out) != 0) return -1;
    }
    return 0;
}

typedef struct pair_list {
    int n, cap;
    int *part;   /* 2 per pair */
    double *uv;  /* 4 per pair */
    double *rest; /* per pair */
    double *ds;   /* per pair: the boundary length its first point stands for */
} pair_list;

static int pair_push(pair_list *l, int a, const double uva[2], int b, const double uvb[2], double rest, double ds)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 64;
        if (!sem_resize((void **)&l->part, (size_t)cap * 2, sizeof(int)) ||
            !sem_resize((void **)&l->uv, (size_t)cap * 4, sizeof(double)) ||
            !sem_resize((void **)&l->rest, (size_t)cap, sizeof(double)) ||
            !sem_resize((void **)&l->ds, (size_t)cap, sizeof(double)))
            return -1;
        l->cap = cap;
    }
    l->ds[l->n] = ds;
    l->part[2 * l->n] = a;
    l->part[2 * l->n + 1] = b;
    memcpy(l->uv + 4 * (size_t)l->n, uva, 2 * sizeof(double));
    memcpy(l->uv + 4 * (size_t)l->n + 2, uvb, 2 * sizeof(double));
    l->rest[l->n] = rest;
    l->n++;
    return 0;
}

static void pair_list_free(pair_list *l)
{
    free(l->part);
    free(l->uv);
    free(l->rest);
    free(l->ds);
}

/* The point of part b nearest X that lies on b (inside its trim), if within tol:
 * 1 and uv set, else 0. */
static int partner(const sem_surface_sampler *sampler, const sem_trim_region *region, const point_list *boundary,
                   const double X[3], double tol, double uv[2], double *distance)
{
    double t[2];
    double d = sem_surface_closest_point(sampler, X, NULL, 0.0, t);
    if (d <= tol && sem_trim_region_inside(region, t[0], t[1])) {
        uv[0] = t[0], uv[1] = t[1];
        *distance = d;
        return 1;
    }
    /* on b's trim boundary: its nearest boundary point (the points are SPACING L apart, so
     * the pair is taken only when one of them is itself within tol) */
    int best = -1;
    double bd = tol;
    for (int i = 0; i < boundary->n; ++i) {
        double e = dist3(boundary->X + 3 * (size_t)i, X);
        if (e <= bd) bd = e, best = i;
    }
    if (best < 0) return 0;
    uv[0] = boundary->uv[2 * (size_t)best];
    uv[1] = boundary->uv[2 * (size_t)best + 1];
    *distance = bd;
    return 1;
}

/* A pair found d > 0 apart: the two points of the same place are usually closer. Near a
 * corner the walk's point X of part a pairs with the corner of b (which lies on a too), and
 * where two faces meet along an edge at an angle, X's nearest point of b is a little off the
 * edge. Alternating projections (a's point onto b, b's onto a) shrink the distance towards
 * the surfaces' common curve, or to a gap's true width; a point is moved only while the pair
 * gets closer and stays within tol of X. uva, uvb: in, the pair; out, the closer pair.
 * Returns its distance. */
static double closest_pair(const sem_surface_sampler *sa, const sem_surface_sampler *sb, const double X[3],
                           double tol, double uva[2], double uvb[2], double d)
{
    double xa[3], xb[3];
    memcpy(xa, X, sizeof xa);
    sem_surface_eval(sb->surface, uvb[0], uvb[1], xb, NULL, NULL, NULL);
    for (int it = 0; it < 8 && d > 1e-12 * tol; ++it) {
        double t[2] = {uva[0], uva[1]}, y[3];
        double e = sem_surface_closest_point(sa, xb, uva, 0.0, t);
        sem_surface_eval(sa->surface, t[0], t[1], y, NULL, NULL, NULL);
        if (!(e < d) || dist3(y, X) > tol) break;
        memcpy(uva, t, sizeof t);
        memcpy(xa, y, sizeof y);
        d = e;
        t[0] = uvb[0], t[1] = uvb[1];
        e = sem_surface_closest_point(sb, xa, uvb, 0.0, t);
        sem_surface_eval(sb->surface, t[0], t[1], y, NULL, NULL, NULL);
        if (!(e < d) || dist3(y, X) > tol) break;
        memcpy(uvb, t, sizeof t);
        memcpy(xb, y, sizeof y);
        d = e;
    }
    return d;
}

void sem_seams_free(sem_seams *s)
{
    if (!s) return;
    SEM_FREE_ALL(s->part, s->row_start, s->row_ctrl, s->row_w, s->rest_distance, s->length);
    memset(s, 0, sizeof *s);
}

sem_status sem_seams_build(const sem_model *model, double tolerance, sem_seams *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    int np = model->n_parts;
    if (np <= 0) return SEM_OK;
    sem_status st = SEM_OK;
    sem_trim_region **regions = calloc((size_t)np, sizeof *regions);
    sem_surface_sampler *samplers = calloc((size_t)np, sizeof *samplers);
    point_list *boundary = calloc((size_t)np, sizeof *boundary);
    pair_list *pairs = calloc((size_t)np, sizeof *pairs);
    double *box = malloc((size_t)np * 6 * sizeof(double));
    size_t *offset = malloc(((size_t)np + 1) * sizeof *offset);
    if (!regions || !samplers || !boundary || !pairs || !box || !offset) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory finding the model's seams");
        goto done;
    }
    sem_model_part_offsets(model, offset);
    /* the model's size: the box of its control points (trimmed nets overreach, so the walk
     * below measures the boundary's own box and uses that) */
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (int p = 0; p < np; ++p) {
        const sem_surface *s = &model->parts[p].surface;
        double *b = box + 6 * (size_t)p;
        for (int k = 0; k < 3; ++k) b[k] = DBL_MAX, b[3 + k] = -DBL_MAX;
        for (int c = 0; c < s->n_u * s->n_v; ++c)
            for (int k = 0; k < 3; ++k) {
                double x = s->ctrl[3 * (size_t)c + k];
                if (x < b[k]) b[k] = x;
                if (x > b[3 + k]) b[3 + k] = x;
            }
        for (int k = 0; k < 3; ++k) {
            if (b[k] < lo[k]) lo[k] = b[k];
            if (b[3 + k] > hi[k]) hi[k] = b[3 + k];
        }
    }
    double L = dist3(lo, hi);
    if (!(L > 0) || !isfinite(L)) goto done;
    int failed = 0;
#pragma omp parallel for schedule(dynamic) reduction(| : failed)
    for (int p = 0; p < np; ++p) {
        sem_error e;
        if (sem_trim_region_build(&model->parts[p], &regions[p], &e) != SEM_OK) {
            /* a part whose loops do not close is measured on its domain (as the reader
             * keeps it untrimmed) */
            regions[p] = NULL;
            sem_part untrimmed = model->parts[p];
            untrimmed.has_outer = 0;
            untrimmed.n_holes = 0;
            if (sem_trim_region_build(&untrimmed, &regions[p], &e) != SEM_OK) {
                failed = 1;
                continue;
            }
        }
        if (sem_surface_sampler_build(&model->parts[p].surface, &samplers[p], &e) != SEM_OK ||
            boundary_points(&model->parts[p], regions[p], SPACING * L, &boundary[p]) != 0)
            failed = 1;
    }
    if (failed) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory finding the model's seams");
        goto done;
    }
    /* the tolerance: relative to the boundary's own box (control nets of trimmed faces
     * reach far outside what the user sees) */
    for (int k = 0; k < 3; ++k) lo[k] = DBL_MAX, hi[k] = -DBL_MAX;
    for (int p = 0; p < np; ++p)
        for (int i = 0; i < boundary[p].n; ++i)
            for (int k = 0; k < 3; ++k) {
                double x = boundary[p].X[3 * (size_t)i + k];
                if (x < lo[k]) lo[k] = x;
                if (x > hi[k]) hi[k] = x;
            }
    double size = dist3(lo, hi);
    if (!(size > 0)) size = L;
    double tol = tolerance * size;
#pragma omp parallel for schedule(dynamic) reduction(| : failed)
    for (int a = 0; a < np; ++a) {
        for (int i = 0; i < boundary[a].n && !failed; ++i) {
            const double *X = boundary[a].X + 3 * (size_t)i;
            for (int b = 0; b < np; ++b) {
                if (b == a) continue;
                const double *bb = box + 6 * (size_t)b;
                if (X[0] < bb[0] - tol || X[1] < bb[1] - tol || X[2] < bb[2] - tol || X[0] > bb[3] + tol ||
                    X[1] > bb[4] + tol || X[2] > bb[5] + tol)
                    continue;
                double uv[2], d, uva[2] = {boundary[a].uv[2 * (size_t)i], boundary[a].uv[2 * (size_t)i + 1]};
                if (!partner(&samplers[b], regions[b], &boundary[b], X, tol, uv, &d)) continue;
                d = closest_pair(&samplers[a], &samplers[b], X, tol, uva, uv, d);
                if (pair_push(&pairs[a], a, uva, b, uv, d, boundary[a].ds[i]) != 0) {
                    failed = 1;
                    break;
                }
            }
        }
    }
    if (failed) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory finding the model's seams");
        goto done;
    }
    /* concatenate in part order; each point's row of the render map */
    int n = 0;
    for (int p = 0; p < np; ++p) n += pairs[p].n;
    out->n_pairs = n;
    out->size = size;
    out->tolerance = tol;
    if (n == 0) goto done;
    int max_row = 0;
    for (int p = 0; p < np; ++p) {
        const sem_surface *s = &model->parts[p].surface;
        int r = (s->degree_u + 1) * (s->degree_v + 1);
        if (r > max_row) max_row = r;
    }
    out->part = malloc((size_t)n * 2 * sizeof(int));
    out->rest_distance = malloc((size_t)n * sizeof(double));
    out->length = malloc((size_t)n * sizeof(double));
    out->row_start = malloc(((size_t)2 * n + 1) * sizeof(int));
    out->row_ctrl = malloc((size_t)2 * n * max_row * sizeof(int));
    out->row_w = malloc((size_t)2 * n * max_row * sizeof(double));
    int *index = malloc((size_t)max_row * sizeof(int));
    if (!out->part || !out->rest_distance || !out->length || !out->row_start || !out->row_ctrl || !out->row_w || !index) {
        free(index);
        sem_seams_free(out);
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory finding the model's seams");
        goto done;
    }
    int k = 0, e = 0;
    out->row_start[0] = 0;
    for (int p = 0; p < np; ++p)
        for (int i = 0; i < pairs[p].n; ++i, ++k) {
            out->part[2 * k] = pairs[p].part[2 * i];
            out->part[2 * k + 1] = pairs[p].part[2 * i + 1];
            out->rest_distance[k] = pairs[p].rest[i];
            out->length[k] = pairs[p].ds[i];
            for (int side = 0; side < 2; ++side) {
                int part = pairs[p].part[2 * i + side];
                const double *uv = pairs[p].uv + 4 * (size_t)i + 2 * side;
                int c = sem_surface_basis(&model->parts[part].surface, uv[0], uv[1], index, out->row_w + e, NULL, NULL);
                for (int j = 0; j < c; ++j) out->row_ctrl[e + j] = (int)offset[part] + index[j];
                e += c;
                out->row_start[2 * k + side + 1] = e;
            }
        }
    free(index);
done:
    for (int p = 0; regions && p < np; ++p) sem_trim_region_destroy(regions[p]);
    for (int p = 0; samplers && p < np; ++p) sem_surface_sampler_free(&samplers[p]);
    for (int p = 0; boundary && p < np; ++p) point_list_free(&boundary[p]);
    for (int p = 0; pairs && p < np; ++p) pair_list_free(&pairs[p]);
    SEM_FREE_ALL(regions, samplers, boundary, pairs, box, offset);
    return st;
}

static void row_point(const sem_seams *s, int row, const double *q, double x[3])
{
    x[0] = x[1] = x[2] = 0;
    for (int e = s->row_start[row]; e < s->row_start[row + 1]; ++e) {
        const double *c = q + 3 * (size_t)s->row_ctrl[e];
        double w = s->row_w[e];
        x[0] += w * c[0], x[1] += w * c[1], x[2] += w * c[2];
    }
}

void sem_seams_measure(const sem_seams *s, const double *q, sem_seam_gap *out)
{
    memset(out, 0, sizeof *out);
    out->pair = -1;
    out->part_a = out->part_b = -1;
    for (int k = 0; k < s->n_pairs; ++k) {
        double a[3], b[3];
        row_point(s, 2 * k, q, a);
        row_point(s, 2 * k + 1, q, b);
        double gap = dist3(a, b) - s->rest_distance[k];
        /* the first of equal gaps wins: the result does not depend on anything but q */
        if (gap > out->gap) {
            out->gap = gap;
            out->pair = k;
            out->part_a = s->part[2 * k];
            out->part_b = s->part[2 * k + 1];
            for (int c = 0; c < 3; ++c) out->X[c] = 0.5 * (a[c] + b[c]);
        }
    }
    out->relative = s->size > 0 ? out->gap / s->size : 0;
}
