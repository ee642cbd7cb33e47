/*
 * measure.c - area and bounding box of NURBS parts (see sem/measure.h).
 *
 * Area. A = integral over the domain of |x_u x x_v| du dv. The integrand is smooth inside a
 * knot span, so each span gets a tensor Gauss-Legendre rule; a span whose 2 x 2 split
 * disagrees with the whole-span rule is split again (adaptive cubature), which reaches
 * 1e-12 relative on rational spheres and tori with one or two levels. Trimmed domains: a
 * cell that no trim-polygon edge crosses is entirely inside or outside (one inside test at
 * its centre decides); crossed cells are split until they reach a leaf size of 1/64 of
 * the domain and are crossed by at most LEAF_MAX_EDGES edges (a leaf with more vertices than
 * leaf_cell takes fell back to testing Gauss points, 5e-4 off on a projected circle). The error
 * is small even there: a leaf is integrated exactly for the trim polygon (bands between
 * the polygon's vertices, trapezoids inside each band, see leaf_cell), so only the
 * polygon's departure from the trim curves and the smoothness of |x_u x x_v| remain.
 *
 * Bounding box. The extreme coordinates of a surface usually lie on its boundary or at a
 * smooth interior extremum. A dense sample (denser along the domain edges and including
 * every vertex of the trim polygons) gives each of the 6 extremes approximately; a compass
 * search (pattern search with halving steps, clamped to the domain and to the trimmed
 * region) from the best few samples then converges to the local extremum to ~1e-13.
 */
#include "sem/measure.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/trim.h"
#include "util/free_all.h"

#define MAX_GAUSS 24
#define LEAF_DIVISIONS 64.0 /* trimmed leaves: this many per domain width */
#define MAX_TRIM_DEPTH 30
#define LEAF_MAX_EDGES 24   /* leaves crossed by more edges are split (leaf_cell's limits) */
#define MAX_ADAPT_DEPTH 6

/* ---------------------------------------------------------------- area ---- */

typedef struct gauss_rule {
    int n;
    double x[MAX_GAUSS], w[MAX_GAUSS];
} gauss_rule;

static void gauss_rule_init(gauss_rule *g, int n)
{
    if (n > MAX_GAUSS) n = MAX_GAUSS;
    g->n = n;
    sem_gauss_legendre(n, g->x, g->w);
}

static double area_element(const sem_surface *s, double u, double v)
{
    double du[3], dv[3];
    sem_surface_eval(s, u, v, NULL, du, dv, NULL);
    double n0 = du[1] * dv[2] - du[2] * dv[1];
    double n1 = du[2] * dv[0] - du[0] * dv[2];
    double n2 = du[0] * dv[1] - du[1] * dv[0];
    return sqrt(n0 * n0 + n1 * n1 + n2 * n2);
}

/* Tensor Gauss rule on [u0,u1] x [v0,v1]; with a region, points outside it count 0. */
static double gauss_cell(const sem_surface *s, const sem_trim_region *region,
                         const gauss_rule *g, double u0, double u1, double v0, double v1)
{
    double hu = 0.5 * (u1 - u0), hv = 0.5 * (v1 - v0);
    double cu = 0.5 * (u0 + u1), cv = 0.5 * (v0 + v1);
    double sum = 0.0;
    for (int j = 0; j < g->n; ++j) {
        double v = cv + hv * g->x[j];
        double row = 0.0;
        for (int i = 0; i < g->n; ++i) {
            double u = cu + hu * g->x[i];
            if (region && !sem_trim_region_inside(region, u, v)) continue;
            row += g->w[i] * area_element(s, u, v);
        }
        sum += g->w[j] * row;
    }
    return sum * hu * hv;
}

/* Adaptive cubature: `whole` is the rule on the cell; accept its 2 x 2 refinement when the
 * two agree to tol. *budget counts the evaluations the part may still spend on refinement:
 * a wildly oscillating surface (random control points of degree 31) never meets tol, and
 * refining it to the depth limit everywhere took minutes for a 14 KB file; out of budget,
 * the 2 x 2 value is kept (smooth CAD surfaces converge long before). */
static double adaptive_cell(const sem_surface *s, const gauss_rule *g, double u0, double u1,
                            double v0, double v1, double whole, double tol, int depth,
                            double *budget)
{
    double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
    double q[4] = {gauss_cell(s, NULL, g, u0, um, v0, vm), gauss_cell(s, NULL, g, um, u1, v0, vm),
                   gauss_cell(s, NULL, g, u0, um, vm, v1), gauss_cell(s, NULL, g, um, u1, vm, v1)};
    *budget -= 4.0 * g->n * g->n;
    double sum = q[0] + q[1] + q[2] + q[3];
    if (fabs(sum - whole) <= tol || depth >= MAX_ADAPT_DEPTH || *budget <= 0) return sum;
    return adaptive_cell(s, g, u0, um, v0, vm, q[0], 0.5 * tol, depth + 1, budget) +
           adaptive_cell(s, g, um, u1, v0, vm, q[1], 0.5 * tol, depth + 1, budget) +
           adaptive_cell(s, g, u0, um, vm, v1, q[2], 0.5 * tol, depth + 1, budget) +
           adaptive_cell(s, g, um, u1, vm, v1, q[3], 0.5 * tol, depth + 1, budget);
}

typedef struct trim_ctx {
    const sem_surface *s;
    const sem_trim_region *region;
    gauss_rule span_rule, sub_rule, leaf_rule;
    int n_seg;
    double *seg;  /* 4 doubles per trim-polygon edge */
    int *scratch; /* (MAX_TRIM_DEPTH + 1) * n_seg edge indices */
    double leaf_u, leaf_v, eps_u, eps_v;
    double tol;   /* absolute tolerance for whole inside spans */
    double budget; /* evaluations left for adaptive refinement (adaptive_cell) */
} trim_ctx;

/* Does segment a-b meet the open rectangle (shrunk by eps)? Liang-Barsky clipping. Edges
 * lying on a cell side (typical for outer loops that follow the domain boundary) do not. */
static int segment_crosses(const double *e, double u0, double u1, double v0, double v1)
{
    double dx = e[2] - e[0], dy = e[3] - e[1];
    double p[4] = {-dx, dx, -dy, dy};
    double q[4] = {e[0] - u0, u1 - e[0], e[1] - v0, v1 - e[1]};
    double t0 = 0.0, t1 = 1.0;
    for (int k = 0; k < 4; ++k) {
        if (p[k] == 0.0) {
            if (q[k] < 0.0) return 0;
        } else {
            double r = q[k] / p[k];
            if (p[k] < 0.0) {
                if (r > t1) return 0;
                if (r > t0) t0 = r;
            } else {
                if (r < t0) return 0;
                if (r < t1) t1 = r;
            }
        }
    }
    return t0 <= t1;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

/* A leaf cell crossed by trim edges, integrated exactly for the polygon: between the v
 * values of the edges' vertices every crossing u(v) is linear, so each such band is a
 * union of trapezoids. A Gauss rule in v per band and along u per inside interval (found
 * by walking the crossings of the scanline from the cell's left side, whose state one
 * inside test gives) integrates |x_u x x_v| over them. */
static double leaf_cell(trim_ctx *c, double u0, double u1, double v0, double v1,
                        const int *edges, int n_edges)
{
    enum { MAX_BREAKS = 64, MAX_CROSS = 64 };
    double vb[MAX_BREAKS + 2];
    int nb = 0;
    vb[nb++] = v0;
    for (int k = 0; k < n_edges && nb < MAX_BREAKS; ++k) {
        const double *e = c->seg + 4 * (size_t)edges[k];
        if (e[1] > v0 && e[1] < v1) vb[nb++] = e[1];
        if (e[3] > v0 && e[3] < v1 && nb < MAX_BREAKS) vb[nb++] = e[3];
    }
    if (nb >= MAX_BREAKS) /* pathological: many vertices in one leaf; test points instead */
        return gauss_cell(c->s, c->region, &c->sub_rule, u0, u1, v0, v1);
    vb[nb++] = v1;
    qsort(vb, (size_t)nb, sizeof *vb, compare_doubles);
    const gauss_rule *g = &c->leaf_rule;
    double ustart = u0 + c->eps_u, sum = 0.0;
    for (int b = 0; b + 1 < nb; ++b) {
        double va = vb[b], vbnd = vb[b + 1];
        if (!(vbnd - va > 1e-14 * (v1 - v0))) continue;
        double hv = 0.5 * (vbnd - va), cv = 0.5 * (va + vbnd);
        for (int q = 0; q < g->n; ++q) {
            double v = cv + hv * g->x[q];
            double cross[MAX_CROSS + 2];
            int nc = 0;
            for (int k = 0; k < n_edges; ++k) {
                const double *e = c->seg + 4 * (size_t)edges[k];
                if ((e[1] > v) != (e[3] > v)) {
                    double x = e[0] + (v - e[1]) * (e[2] - e[0]) / (e[3] - e[1]);
                    if (x > ustart && x < u1) {
                        if (nc == MAX_CROSS) return gauss_cell(c->s, c->region, &c->sub_rule,
                                                               u0, u1, v0, v1);
                        cross[nc++] = x;
                    }
                }
            }
            qsort(cross, (size_t)nc, sizeof *cross, compare_doubles);
            cross[nc++] = u1;
            int inside = sem_trim_region_inside(c->region, ustart, v);
            double a = u0, row = 0.0;
            for (int k = 0; k < nc; ++k) {
                if (inside && cross[k] > a) {
                    double hu = 0.5 * (cross[k] - a), cu = 0.5 * (cross[k] + a);
                    for (int p = 0; p < g->n; ++p)
                        row += g->w[p] * hu * area_element(c->s, cu + hu * g->x[p], v);
                }
                a = cross[k];
                inside = !inside;
            }
            sum += g->w[q] * hv * row;
        }
    }
    return sum;
}

static double trimmed_cell(trim_ctx *c, double u0, double u1, double v0, double v1,
                           const int *edges, int n_edges, int depth)
{
    int *mine = c->scratch + (size_t)depth * (size_t)c->n_seg;
    int m = 0;
    for (int k = 0; k < n_edges; ++k) {
        if (segment_crosses(c->seg + 4 * (size_t)edges[k], u0 + c->eps_u, u1 - c->eps_u,
                            v0 + c->eps_v, v1 - c->eps_v))
            mine[m++] = edges[k];
    }
    if (m == 0) {
        if (!sem_trim_region_inside(c->region, 0.5 * (u0 + u1), 0.5 * (v0 + v1))) return 0.0;
        if (depth == 0) {
            double whole = gauss_cell(c->s, NULL, &c->span_rule, u0, u1, v0, v1);
            return adaptive_cell(c->s, &c->span_rule, u0, u1, v0, v1, whole, c->tol, 0,
                                 &c->budget);
        }
        return gauss_cell(c->s, NULL, &c->sub_rule, u0, u1, v0, v1);
    }
    int split_u = (u1 - u0) > c->leaf_u, split_v = (v1 - v0) > c->leaf_v;
    /* a leaf crossed by more edges than leaf_cell integrates exactly (a dense polygon: a
     * model-space loop projected in fine steps) is split further */
    if (!split_u && !split_v && m > LEAF_MAX_EDGES) split_u = split_v = 1;
    if ((!split_u && !split_v) || depth >= MAX_TRIM_DEPTH)
        return leaf_cell(c, u0, u1, v0, v1, mine, m);
    double um = 0.5 * (u0 + u1), vm = 0.5 * (v0 + v1);
    double su[3] = {u0, split_u ? um : u1, u1}, sv[3] = {v0, split_v ? vm : v1, v1};
    double sum = 0.0;
    for (int j = 0; j < 1 + split_v; ++j)
        for (int i = 0; i < 1 + split_u; ++i)
            sum += trimmed_cell(c, su[i], su[i + 1], sv[j], sv[j + 1], mine, m, depth + 1);
    return sum;
}

static int span_breaks(const sem_surface *s, int dir, double **out)
{
    int n_ctrl = dir ? s->n_v : s->n_u, p = dir ? s->degree_v : s->degree_u;
    const double *knots = dir ? s->knots_v : s->knots_u;
    double t0 = dir ? s->v0 : s->u0, t1 = dir ? s->v1 : s->u1;
    int max = n_ctrl + 2;
    *out = malloc((size_t)max * sizeof(double));
    if (!*out) return 0;
    return sem_knot_breaks(p, n_ctrl, knots, t0, t1, *out, max);
}

static sem_status part_area(const sem_part *part, const sem_trim_region *region,
                            const double *bu, int nbu, const double *bv, int nbv,
                            double extra_work, double *area, sem_error *err)
{
    const sem_surface *s = &part->surface;
    int deg = s->degree_u > s->degree_v ? s->degree_u : s->degree_v;
    trim_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.region = region;
    gauss_rule_init(&c.span_rule, deg + 6 > 8 ? deg + 6 : 8);
    gauss_rule_init(&c.sub_rule, deg + 2 > 5 ? deg + 2 : 5);
    gauss_rule_init(&c.leaf_rule, 3);

    /* coarse estimate fixes the absolute tolerance of the adaptive pass */
    double estimate = 0.0;
    for (int j = 0; j + 1 < nbv; ++j)
        for (int i = 0; i + 1 < nbu; ++i)
            estimate += gauss_cell(s, NULL, &c.span_rule, bu[i], bu[i + 1], bv[j], bv[j + 1]);
    int n_cells = (nbu - 1) * (nbv - 1);
    /* |refined - whole| measures the error of `whole`; for smooth integrands the refined
     * value is better by a factor 2^(2n), so 1e-10 here leaves errors far below 1e-12,
     * while parts with collapsed edges (sqrt-like area elements) stop after a few levels */
    c.tol = 1e-10 * estimate / (n_cells > 0 ? n_cells : 1);
    /* refinement may cost 4 times the plain rule, plus extra_work basis-function
     * evaluations (2e6 for a part alone: ~400 refinements of a bicubic span, what the
     * rocket's collapsed nose needs); this bounds a model's measure by its knot spans
     * (SEM_MAX_MODEL_SPAN_WORK) and its part count, whatever its surfaces look like */
    double basis = (double)(s->degree_u + 1) * (s->degree_v + 1);
    c.budget = 4.0 * n_cells * c.span_rule.n * c.span_rule.n + extra_work / basis;

    int trimmed = part->has_outer || part->n_holes > 0;
    if (!trimmed) {
        double sum = 0.0;
        for (int j = 0; j + 1 < nbv; ++j) {
            for (int i = 0; i + 1 < nbu; ++i) {
                double whole =
                    gauss_cell(s, NULL, &c.span_rule, bu[i], bu[i + 1], bv[j], bv[j + 1]);
                sum += adaptive_cell(s, &c.span_rule, bu[i], bu[i + 1], bv[j], bv[j + 1], whole,
                                     c.tol, 0, &c.budget);
            }
        }
        *area = sum;
        return SEM_OK;
    }

    /* gather the edges of every trim polygon */
    int n_loops = sem_trim_region_loop_count(region), n_seg = 0;
    for (int l = 0; l < n_loops; ++l) {
        int nv;
        sem_trim_region_loop(region, l, &nv);
        n_seg += nv;
    }
    c.seg = malloc((size_t)(n_seg > 0 ? n_seg : 1) * 4 * sizeof(double));
    c.scratch = malloc((size_t)(MAX_TRIM_DEPTH + 2) * (size_t)(n_seg > 0 ? n_seg : 1) * sizeof(int));
    if (!c.seg || !c.scratch) {
        free(c.seg);
        free(c.scratch);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory measuring a trimmed part");
    }
    int k = 0;
    for (int l = 0; l < n_loops; ++l) {
        int nv;
        const double *uv = sem_trim_region_loop(region, l, &nv);
        for (int a = 0; a < nv; ++a) {
            int b = (a + 1) % nv;
            double *e = c.seg + 4 * (size_t)k++;
            e[0] = uv[2 * a];
            e[1] = uv[2 * a + 1];
            e[2] = uv[2 * b];
            e[3] = uv[2 * b + 1];
        }
    }
    c.n_seg = n_seg;
    int *all = c.scratch + (size_t)(MAX_TRIM_DEPTH + 1) * (size_t)(n_seg > 0 ? n_seg : 1);
    for (int e = 0; e < n_seg; ++e) all[e] = e;
    double wu = s->u1 - s->u0, wv = s->v1 - s->v0;
    c.leaf_u = wu / LEAF_DIVISIONS;
    c.leaf_v = wv / LEAF_DIVISIONS;
    c.eps_u = 1e-10 * wu;
    c.eps_v = 1e-10 * wv;
    double sum = 0.0;
    for (int j = 0; j + 1 < nbv; ++j)
        for (int i = 0; i + 1 < nbu; ++i)
            sum += trimmed_cell(&c, bu[i], bu[i + 1], bv[j], bv[j + 1], all, n_seg, 0);
    free(c.seg);
    free(c.scratch);
    *area = sum;
    return SEM_OK;
}

/* ---------------------------------------------------------------- bbox ---- */

#define N_STARTS 4

typedef struct extremum {
    double value[N_STARTS]; /* sign * coordinate, best first */
    double u[N_STARTS], v[N_STARTS];
    int n;
} extremum;

typedef struct bbox_ctx {
    const sem_surface *s;
    const sem_trim_region *region; /* NULL when untrimmed */
    double lo[3], hi[3];
    extremum ext[6];               /* 2c: min of x_c (as max of -x_c), 2c+1: max of x_c */
} bbox_ctx;

static void extremum_offer(extremum *e, double value, double u, double v)
{
    int pos = e->n;
    while (pos > 0 && value > e->value[pos - 1]) pos--;
    if (pos >= N_STARTS) return;
    int last = e->n < N_STARTS ? e->n : N_STARTS - 1;
    for (int k = last; k > pos; --k) {
        e->value[k] = e->value[k - 1];
        e->u[k] = e->u[k - 1];
        e->v[k] = e->v[k - 1];
    }
    e->value[pos] = value;
    e->u[pos] = u;
    e->v[pos] = v;
    if (e->n < N_STARTS) e->n++;
}

static void bbox_point(bbox_ctx *c, double u, double v, double x[3])
{
    sem_surface_eval(c->s, u, v, x, NULL, NULL, NULL);
    for (int d = 0; d < 3; ++d) {
        if (x[d] < c->lo[d]) c->lo[d] = x[d];
        if (x[d] > c->hi[d]) c->hi[d] = x[d];
    }
}

/* A sample: counts when inside the region (or forced: points on trim curves). */
static void bbox_sample(bbox_ctx *c, double u, double v, int forced)
{
    if (!forced && c->region && !sem_trim_region_inside(c->region, u, v)) return;
    double x[3];
    bbox_point(c, u, v, x);
    for (int d = 0; d < 3; ++d) {
        extremum_offer(&c->ext[2 * d], -x[d], u, v);
        extremum_offer(&c->ext[2 * d + 1], x[d], u, v);
    }
}

static double clamp(double t, double a, double b)
{
    return t < a ? a : (t > b ? b : t);
}

/* Compass search for the maximum of sign * x_coord from (u,v); every point it evaluates
 * is a valid surface point and enters the box. */
static void compass_search(bbox_ctx *c, int coord, double sign, double u, double v, double hu,
                           double hv)
{
    const sem_surface *s = c->s;
    double x[3];
    bbox_point(c, u, v, x);
    double f = sign * x[coord];
    double tol_u = 1e-13 * (s->u1 - s->u0), tol_v = 1e-13 * (s->v1 - s->v0);
    static const int dirs[8][2] = {{1, 0}, {-1, 0}, {0, 1}, {0, -1},
                                   {1, 1}, {-1, -1}, {1, -1}, {-1, 1}};
    for (int iter = 0; iter < 4000 && (hu > tol_u || hv > tol_v); ++iter) {
        double best = f, bu = u, bv = v;
        for (int k = 0; k < 8; ++k) {
            double nu = clamp(u + dirs[k][0] * hu, s->u0, s->u1);
            double nv = clamp(v + dirs[k][1] * hv, s->v0, s->v1);
            if (nu == u && nv == v) continue;
            if (c->region && !sem_trim_region_inside(c->region, nu, nv)) continue;
            bbox_point(c, nu, nv, x);
            if (sign * x[coord] > best) {
                best = sign * x[coord];
                bu = nu;
                bv = nv;
            }
        }
        if (best > f) {
            f = best;
            u = bu;
            v = bv;
        } else {
            hu *= 0.5;
            hv *= 0.5;
        }
    }
}

/* Sample positions along one direction: `per_span` per knot span, span ends included. */
static double *sample_line(const double *breaks, int nb, int per_span, int *count)
{
    int n = (nb - 1) * per_span + 1;
    double *t = malloc((size_t)n * sizeof *t);
    if (!t) return NULL;
    int k = 0;
    for (int i = 0; i + 1 < nb; ++i)
        for (int j = 0; j < per_span; ++j)
            t[k++] = breaks[i] + (breaks[i + 1] - breaks[i]) * j / per_span;
    t[k++] = breaks[nb - 1];
    *count = k;
    return t;
}

static int per_span_samples(int n_spans, int degree)
{
    int m = 2 * degree + 4;
    if (m < 8) m = 8;
    /* keep a part's grid near 128 samples per direction when it has many spans */
    while (m > 2 && n_spans * m > 128) m--;
    return m;
}

static sem_status part_bbox(const sem_part *part, const sem_trim_region *region,
                            const double *bu, int nbu, const double *bv, int nbv,
                            sem_part_measure_result *out, sem_error *err)
{
    const sem_surface *s = &part->surface;
    bbox_ctx c;
    memset(&c, 0, sizeof c);
    c.s = s;
    c.region = (part->has_outer || part->n_holes > 0) ? region : NULL;
    for (int d = 0; d < 3; ++d) {
        c.lo[d] = INFINITY;
        c.hi[d] = -INFINITY;
    }
    int mu = per_span_samples(nbu - 1, s->degree_u), mv = per_span_samples(nbv - 1, s->degree_v);
    int nu, nv, nu_edge, nv_edge;
    double *tu = sample_line(bu, nbu, mu, &nu), *tv = sample_line(bv, nbv, mv, &nv);
    double *tu_edge = sample_line(bu, nbu, 4 * mu, &nu_edge);
    double *tv_edge = sample_line(bv, nbv, 4 * mv, &nv_edge);
    if (!tu || !tv || !tu_edge || !tv_edge) {
        SEM_FREE_ALL(tu, tv, tu_edge, tv_edge);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory measuring a part");
    }
    for (int j = 0; j < nv; ++j)
        for (int i = 0; i < nu; ++i) bbox_sample(&c, tu[i], tv[j], 0);
    /* the domain boundary, denser (extremes of box-like parts sit on edges and corners) */
    for (int i = 0; i < nu_edge; ++i) {
        bbox_sample(&c, tu_edge[i], s->v0, 0);
        bbox_sample(&c, tu_edge[i], s->v1, 0);
    }
    for (int j = 0; j < nv_edge; ++j) {
        bbox_sample(&c, s->u0, tv_edge[j], 0);
        bbox_sample(&c, s->u1, tv_edge[j], 0);
    }
    /* the trim curves: polygon vertices and edge midpoints lie on the trimmed boundary */
    if (c.region) {
        int n_loops = sem_trim_region_loop_count(region);
        for (int l = 0; l < n_loops; ++l) {
            int n;
            const double *uv = sem_trim_region_loop(region, l, &n);
            for (int a = 0; a < n; ++a) {
                int b = (a + 1) % n;
                double ua = clamp(uv[2 * a], s->u0, s->u1), va = clamp(uv[2 * a + 1], s->v0, s->v1);
                double ub = clamp(uv[2 * b], s->u0, s->u1), vb = clamp(uv[2 * b + 1], s->v0, s->v1);
                bbox_sample(&c, ua, va, 1);
                bbox_sample(&c, 0.5 * (ua + ub), 0.5 * (va + vb), 1);
            }
        }
    }
    double hu = (s->u1 - s->u0) / (double)(nu - 1), hv = (s->v1 - s->v0) / (double)(nv - 1);
    /* convex hull property (weights > 0): no surface point goes beyond the control points'
     * box, so an extreme that a sample already reaches needs no search (box-like parts:
     * every extreme sits at a corner control point; this makes their box 6 times cheaper) */
    double hull[6];
    for (int d = 0; d < 3; ++d) {
        hull[2 * d] = hull[2 * d + 1] = -INFINITY;
        for (size_t k = 0; k < (size_t)s->n_u * (size_t)s->n_v; ++k) {
            hull[2 * d] = fmax(hull[2 * d], -s->ctrl[3 * k + d]);
            hull[2 * d + 1] = fmax(hull[2 * d + 1], s->ctrl[3 * k + d]);
        }
    }
    for (int e = 0; e < 6; ++e) {
        const extremum *x = &c.ext[e];
        if (x->n > 0 && x->value[0] >= hull[e]) continue;
        for (int k = 0; k < x->n; ++k)
            compass_search(&c, e / 2, (e % 2) ? 1.0 : -1.0, x->u[k], x->v[k], hu, hv);
    }
    SEM_FREE_ALL(tu, tv, tu_edge, tv_edge);
    for (int d = 0; d < 3; ++d) {
        out->bbox_min[d] = c.lo[d];
        out->bbox_max[d] = c.hi[d];
    }
    return SEM_OK;
}

/* ---------------------------------------------------------------- API ---- */

static void result_empty(sem_part_measure_result *r, double area)
{
    r->area = area;
    for (int d = 0; d < 3; ++d) {
        r->bbox_min[d] = INFINITY;
        r->bbox_max[d] = -INFINITY;
    }
}

/* Refinement work a part may spend beyond 4 times its plain rule: 2e6 basis-function
 * evaluations, shared out when a model has more than 1000 parts (a model then costs at most
 * 2e9 of them beyond its spans, e.g. 10,000 instances of one wildly oscillating patch). */
#define PART_EXTRA_WORK 2e6
#define MODEL_EXTRA_WORK 2e9

static sem_status part_measure(const sem_part *part, double extra_work,
                               sem_part_measure_result *out, sem_error *err)
{
    result_empty(out, NAN);
    sem_status st = sem_surface_validate(&part->surface, err);
    if (st != SEM_OK) return st;
    sem_trim_region *region = NULL;
    st = sem_trim_region_build(part, &region, err);
    if (st != SEM_OK) return st;
    double *bu = NULL, *bv = NULL;
    int nbu = span_breaks(&part->surface, 0, &bu), nbv = span_breaks(&part->surface, 1, &bv);
    if (nbu < 2 || nbv < 2) {
        st = (bu && bv) ? sem_error_set(err, SEM_ERR_INVALID, "surface has no knot span in use")
                        : sem_error_set(err, SEM_ERR_NOMEM, "out of memory measuring a part");
    }
    double area = 0.0;
    if (st == SEM_OK) st = part_area(part, region, bu, nbu, bv, nbv, extra_work, &area, err);
    if (st == SEM_OK) st = part_bbox(part, region, bu, nbu, bv, nbv, out, err);
    if (st == SEM_OK) out->area = area;
    free(bu);
    free(bv);
    sem_trim_region_destroy(region);
    return st;
}

sem_status sem_part_measure(const sem_part *part, sem_part_measure_result *out, sem_error *err)
{
    return part_measure(part, PART_EXTRA_WORK, out, err);
}

sem_status sem_model_measure(const sem_model *model, sem_part_measure_result *per_part,
                             sem_part_measure_result *total, sem_error *err)
{
    int n = model->n_parts;
    result_empty(total, 0.0);
    if (n == 0) return SEM_OK;
    sem_part_measure_result *res = per_part ? per_part : malloc((size_t)n * sizeof *res);
    sem_error *errors = malloc((size_t)n * sizeof *errors);
    if (!res || !errors) {
        if (!per_part) free(res);
        free(errors);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory measuring a model");
    }
    double extra = MODEL_EXTRA_WORK / n < PART_EXTRA_WORK ? MODEL_EXTRA_WORK / n : PART_EXTRA_WORK;
#pragma omp parallel for schedule(dynamic, 1)
    for (int i = 0; i < n; ++i) {
        sem_error_clear(&errors[i]);
        part_measure(&model->parts[i], extra, &res[i], &errors[i]);
    }
    sem_status st = SEM_OK;
    for (int i = 0; i < n; ++i) {
        if (errors[i].status != SEM_OK) {
            if (st == SEM_OK) {
                const char *name = model->parts[i].name;
                st = sem_error_set(err, errors[i].status, "part %d%s%s%s: %s", i + 1,
                                   name[0] ? " (" : "", name, name[0] ? ")" : "",
                                   errors[i].message);
            }
            continue;
        }
        total->area += res[i].area;
        for (int d = 0; d < 3; ++d) {
            if (res[i].bbox_min[d] < total->bbox_min[d]) total->bbox_min[d] = res[i].bbox_min[d];
            if (res[i].bbox_max[d] > total->bbox_max[d]) total->bbox_max[d] = res[i].bbox_max[d];
        }
    }
    if (!per_part) free(res);
    free(errors);
    return st;
}
