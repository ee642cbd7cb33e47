/*
 * trim_projection.c - model-space trim loops into parameter space (geometry/trim_projection.h).
 *
 * Design. Each curve is sampled a few times per knot span, every sample is inverted onto the
 * surface starting from the previous sample's (u,v) (geometry/closest_point.c), and each
 * interval is halved while the surface point at the middle of the (u,v) chord departs from
 * the projected middle of the curve by more than the tolerance: the result is a polygon in
 * (u,v) whose image follows the curve, stored as a degree-1 B-spline (whose flattening in
 * trim.c is this polygon again). Polygons are what trim regions are made of anyway, so
 * nothing is lost against fitting a smooth curve, and nothing can overshoot. A curve gets at
 * most MAX_POINTS points (trim.c flattens at most 4095 spans of a curve).
 *
 * Two places where (u,v) is not a function of the model-space point need care:
 *  - seams of closed surfaces (u0 and u1 map to the same curve): a point on the seam takes
 *    the side of its nearest neighbour off the seam within its curve; a curve that lies on
 *    the seam (a B-rep's seam edge, traversed once on each side) takes the side on which it
 *    joins both neighbouring curves, so it lands once on u0 and once on u1;
 *  - collapsed edges (poles of a sphere-like patch, where x_u = 0 along v = v0): a pole
 *    point takes u from its neighbour on the same curve, and consecutive curves that meet at
 *    the pole with different u are joined by a straight connector along the collapsed edge
 *    (its image is a single point, so the connector is exact).
 */
#include "geometry/trim_projection.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/net_size.h"
#include "geometry/seam.h"
#include "sem/nurbs.h"

#define SAMPLES_PER_SPAN_MIN 4
#define MAX_DEPTH 18
#define MAX_POINTS 3000

typedef struct point {
    double t;
    double uv[2];
    double x[3]; /* S(uv) */
    double d;    /* distance of the curve point from x */
} point;

typedef struct chain {
    int n, cap;
    point *p;
} chain;

typedef struct context {
    const sem_surface_sampler *sampler;
    const sem_surface *s;
    double tol, max_distance;
    int closed[2];     /* seam: S(u0, v) == S(u1, v) (u) / the same in v */
    double eps[2];     /* "on the border" in u and v */
    double worst;      /* largest distance of a curve point from the surface */
    int unwrap;        /* the second pass: (u,v) continuous across seams (see below) */
    double max_gap;    /* gaps between curves bridged (model units) */
    double gap;        /* the largest gap bridged */
    int join_failed;   /* the loop did not close in (u,v) */
} context;

/* (u,v) in the domain: in the unwrapping pass, a coordinate of a closed direction modulo the
 * period (the loop's points leave the domain where it crosses the seam) */
static void wrap(const context *c, const double in[2], double out[2])
{
    const sem_surface *s = c->s;
    double lo[2] = {s->u0, s->v0}, hi[2] = {s->u1, s->v1};
    for (int d = 0; d < 2; ++d) {
        out[d] = in[d];
        if (!c->unwrap || !c->closed[d]) continue;
        double P = hi[d] - lo[d];
        out[d] -= P * floor((out[d] - lo[d]) / P);
        out[d] = fmin(fmax(out[d], lo[d]), hi[d]);
    }
}

/* S(u,v), wrapped */
static void surface_at(const context *c, const double uv[2], double x[3])
{
    double w[2];
    wrap(c, uv, w);
    sem_surface_eval(c->s, w[0], w[1], x, NULL, NULL, NULL);
}

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

sem_trim_projection_settings sem_default_trim_projection_settings(const sem_surface *s)
{
    double size = sem_surface_net_size(s);
    sem_trim_projection_settings o = {2e-5 * size, 1e-2 * size, 1e-4 * size};
    return o;
}

/* The line u = const (dir 0: x_u = 0 along it, a pole at this v) is collapsed when the
 * iso-curve in u through (u,v) has (near) zero length. */
static int collapsed_in(const context *c, int dir, const double uv_in[2])
{
    const sem_surface *s = c->s;
    double a[3], b[3], m[3], du[3], dv[3], w[2];
    wrap(c, uv_in, w);
    const double *uv = w;
    /* cheap test first: the iso-curve cannot be collapsed where it has a tangent */
    sem_surface_eval(s, uv[0], uv[1], m, du, dv, NULL);
    const double *t = dir == 0 ? du : dv;
    double span = dir == 0 ? s->u1 - s->u0 : s->v1 - s->v0;
    if (sqrt(t[0] * t[0] + t[1] * t[1] + t[2] * t[2]) * span > c->tol) return 0;
    if (dir == 0) {
        sem_surface_eval(s, s->u0, uv[1], a, NULL, NULL, NULL);
        sem_surface_eval(s, s->u1, uv[1], b, NULL, NULL, NULL);
        sem_surface_eval(s, 0.5 * (s->u0 + s->u1), uv[1], m, NULL, NULL, NULL);
    } else {
        sem_surface_eval(s, uv[0], s->v0, a, NULL, NULL, NULL);
        sem_surface_eval(s, uv[0], s->v1, b, NULL, NULL, NULL);
        sem_surface_eval(s, uv[0], 0.5 * (s->v0 + s->v1), m, NULL, NULL, NULL);
    }
    return dist3(a, b) < c->tol && dist3(a, m) < c->tol;
}

static int push(chain *ch, const point *p)
{
    if (ch->n == ch->cap) {
        int nc = ch->cap ? 2 * ch->cap : 64;
        point *q = realloc(ch->p, (size_t)nc * sizeof *q);
        if (!q) return 0;
        ch->p = q;
        ch->cap = nc;
    }
    ch->p[ch->n++] = *p;
    return 1;
}

/* The curve point at t onto the surface, starting from guess. A guess is taken without trying
 * the sampler's starts when it ends no farther from the surface than `near` (the distance of
 * the curve's neighbouring points; 0 for a first point) plus a tenth of the tolerance: the
 * distance varies continuously along the curve, so such a guess follows the same nearest sheet
 * (on a curve that lies on its surface, near is 0 and this is the plain test). */
static void project(context *c, const sem_curve *cv, double t, const double *guess, double near,
                    point *out)
{
    double X[3], g[2];
    sem_curve_eval(cv, t, X, NULL);
    out->t = t;
    if (guess) wrap(c, guess, g);
    double d = sem_surface_closest_point(c->sampler, X, guess ? g : NULL, near + 0.1 * c->tol, out->uv);
    out->d = d;
    if (d > c->worst) c->worst = d;
    sem_surface_eval(c->s, out->uv[0], out->uv[1], out->x, NULL, NULL, NULL);
    /* unwrapping: the point's (u,v) taken the number of periods that puts it nearest the
     * previous one, so that the loop runs on across a seam instead of jumping back */
    if (c->unwrap && guess) {
        const sem_surface *s = c->s;
        double P[2] = {s->u1 - s->u0, s->v1 - s->v0};
        for (int k = 0; k < 2; ++k)
            if (c->closed[k]) out->uv[k] += P[k] * round((guess[k] - out->uv[k]) / P[k]);
    }
}

/* Points of (a, b] between a and b, refined; appended to ch. */
static int refine(context *c, const sem_curve *cv, const point *a, const point *b, int depth,
                  chain *ch)
{
    if (depth < MAX_DEPTH && ch->n < MAX_POINTS) {
        point m;
        double mid_uv[2] = {0.5 * (a->uv[0] + b->uv[0]), 0.5 * (a->uv[1] + b->uv[1])};
        project(c, cv, 0.5 * (a->t + b->t), mid_uv, a->d > b->d ? a->d : b->d, &m);
        double chord[3];
        surface_at(c, mid_uv, chord);
        if (dist3(chord, m.x) > c->tol) {
            if (!refine(c, cv, a, &m, depth + 1, ch)) return 0;
            return refine(c, cv, &m, b, depth + 1, ch);
        }
    }
    return push(ch, b);
}

/* One curve, from t_start to t_end, starting from guess (may be NULL). */
static int project_curve(context *c, const sem_curve *cv, int reverse, const double *guess,
                         chain *ch)
{
    double breaks[1026];
    int nb = sem_knot_breaks(cv->degree, cv->n_ctrl, cv->knots, cv->t0, cv->t1, breaks, 1026);
    if (nb < 2) {
        breaks[0] = cv->t0, breaks[1] = cv->t1;
        nb = 2;
    }
    int per = cv->degree + 1 > SAMPLES_PER_SPAN_MIN ? cv->degree + 1 : SAMPLES_PER_SPAN_MIN;
    if ((nb - 1) * per > MAX_POINTS) per = MAX_POINTS / (nb - 1) > 1 ? MAX_POINTS / (nb - 1) : 1;
    int total = (nb - 1) * per;
    point prev;
    for (int k = 0; k <= total; ++k) {
        int kk = reverse ? total - k : k;
        int span = kk / per, r = kk % per;
        double t = span >= nb - 1 ? breaks[nb - 1]
                                  : breaks[span] + (breaks[span + 1] - breaks[span]) * r / per;
        point p;
        project(c, cv, t, k == 0 ? guess : prev.uv, k == 0 ? 0.0 : prev.d, &p);
        if (k == 0) {
            if (!push(ch, &p)) return 0;
        } else if (!refine(c, cv, &prev, &p, 0, ch)) {
            return 0;
        }
        prev = p;
    }
    return 1;
}

static int on_seam(const context *c, int dir, double x)
{
    if (!c->closed[dir]) return 0;
    const sem_surface *s = c->s;
    double lo = dir == 0 ? s->u0 : s->v0, hi = dir == 0 ? s->u1 : s->v1;
    return fabs(x - lo) <= c->eps[dir] || fabs(x - hi) <= c->eps[dir];
}

/* a and b can be consecutive points of a loop: equal in (u,v), or joined by a straight
 * (u,v) segment whose image is a single point (a collapsed edge) */
static int joinable(const context *c, const double a[2], const double b[2])
{
    const sem_surface *s = c->s;
    double du = (b[0] - a[0]) / (s->u1 - s->u0), dv = (b[1] - a[1]) / (s->v1 - s->v0);
    if (hypot(du, dv) < 1e-9) return 1;
    double xa[3], x[3];
    surface_at(c, a, xa);
    for (int k = 1; k <= 8; ++k) {
        double uv[2] = {a[0] + (b[0] - a[0]) * k / 8.0, a[1] + (b[1] - a[1]) * k / 8.0};
        surface_at(c, uv, x);
        if (dist3(x, xa) > c->tol) return 0;
    }
    return 1;
}

static int curve_on_seam(const context *c, int dir, const chain *ch)
{
    for (int i = 0; i < ch->n; ++i)
        if (!on_seam(c, dir, ch->p[i].uv[dir])) return 0;
    return 1;
}

/* Seam and pole fixes along the loop, curve by curve in chain order. */
static void fix_seams_and_poles(context *c, chain *chains, int n)
{
    const sem_surface *s = c->s;
    for (int dir = 0; dir < 2; ++dir) {
        double lo = dir == 0 ? s->u0 : s->v0, hi = dir == 0 ? s->u1 : s->v1;
        double mid = 0.5 * (lo + hi);
        /* poles: a collapsed iso-line of the *other* direction leaves this parameter
         * arbitrary; take the neighbour's */
        for (int k = 0; k < n; ++k) {
            chain *ch = &chains[k];
            for (int i = 0; i < ch->n; ++i) {
                if (!collapsed_in(c, dir, ch->p[i].uv)) continue;
                int j = i - 1 >= 0 && !collapsed_in(c, dir, ch->p[i - 1].uv) ? i - 1
                        : i + 1 < ch->n ? i + 1 : -1;
                if (j >= 0 && !collapsed_in(c, dir, ch->p[j].uv)) ch->p[i].uv[dir] = ch->p[j].uv[dir];
            }
        }
        if (!c->closed[dir] || c->unwrap) continue; /* unwrapped points need no side */
        /* a point on the seam in a curve that leaves it takes the side of the nearest
         * point of that curve off the seam */
        unsigned char *pure = calloc((size_t)n, 1);
        if (!pure) return;
        for (int k = 0; k < n; ++k) {
            chain *ch = &chains[k];
            pure[k] = (unsigned char)curve_on_seam(c, dir, ch);
            if (pure[k]) continue;
            for (int i = 0; i < ch->n; ++i) {
                double *x = &ch->p[i].uv[dir];
                if (!on_seam(c, dir, *x)) continue;
                double ref = NAN;
                for (int d = 1; d < ch->n && isnan(ref); ++d) {
                    if (i - d >= 0 && !on_seam(c, dir, ch->p[i - d].uv[dir]))
                        ref = ch->p[i - d].uv[dir];
                    else if (i + d < ch->n && !on_seam(c, dir, ch->p[i + d].uv[dir]))
                        ref = ch->p[i + d].uv[dir];
                }
                *x = ref < mid ? lo : hi;
            }
        }
        /* a seam edge (every point on the seam; a B-rep runs it once on each side) takes
         * the side on which it joins both of its neighbours in (u,v); the next curve counts
         * only once it is settled */
        for (int k = 0; k < n; ++k) {
            if (!pure[k]) continue;
            chain *ch = &chains[k];
            const chain *prev = &chains[(k + n - 1) % n], *next = &chains[(k + 1) % n];
            int best_score = -1;
            double best = lo;
            for (int side = 0; side < 2; ++side) {
                double value = side ? hi : lo;
                double a[2] = {ch->p[0].uv[0], ch->p[0].uv[1]};
                double b[2] = {ch->p[ch->n - 1].uv[0], ch->p[ch->n - 1].uv[1]};
                a[dir] = b[dir] = value;
                int score = 0;
                if (n > 1 && !pure[(k + n - 1) % n] && joinable(c, prev->p[prev->n - 1].uv, a))
                    score += 2;
                if (n > 1 && !pure[(k + 1) % n] && joinable(c, b, next->p[0].uv)) score += 2;
                /* ties: continue from the previous curve's side */
                if (n > 1 && fabs(prev->p[prev->n - 1].uv[dir] - value) <= c->eps[dir]) score += 1;
                if (score > best_score) best_score = score, best = value;
            }
            for (int i = 0; i < ch->n; ++i) ch->p[i].uv[dir] = best;
            pure[k] = 0; /* settled */
        }
        free(pure);
    }
}

/* The point is on the border of the domain: its image is within tol of the image of the
 * nearest border point (so a curve lying on an edge within the file's tolerance counts). */
static int on_border(const context *c, const double uv[2])
{
    const sem_surface *s = c->s;
    double du0 = uv[0] - s->u0, du1 = s->u1 - uv[0], dv0 = uv[1] - s->v0, dv1 = s->v1 - uv[1];
    double ru = fmin(du0, du1) / (s->u1 - s->u0), rv = fmin(dv0, dv1) / (s->v1 - s->v0);
    double b[2] = {uv[0], uv[1]};
    if (ru <= rv) b[0] = du0 <= du1 ? s->u0 : s->u1;
    else b[1] = dv0 <= dv1 ? s->v0 : s->v1;
    double x[3], y[3];
    sem_surface_eval(s, uv[0], uv[1], x, NULL, NULL, NULL);
    sem_surface_eval(s, b[0], b[1], y, NULL, NULL, NULL);
    return dist3(x, y) <= c->tol;
}

static int all_on_border(const context *c, const chain *chains, int n)
{
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < chains[k].n; ++i)
            if (!on_border(c, chains[k].p[i].uv)) return 0;
    return 1;
}

/* |signed area| of the loop's polygon in (u,v), over the domain's area */
static double area_fraction(const context *c, const chain *chains, int n)
{
    double area = 0.0;
    const double *first = NULL, *prev = NULL;
    for (int k = 0; k < n; ++k)
        for (int i = 0; i < chains[k].n; ++i) {
            const double *uv = chains[k].p[i].uv;
            if (!first) first = uv;
            else area += prev[0] * uv[1] - uv[0] * prev[1];
            prev = uv;
        }
    if (first) area += prev[0] * first[1] - first[0] * prev[1];
    const sem_surface *s = c->s;
    return fabs(0.5 * area) / ((s->u1 - s->u0) * (s->v1 - s->v0));
}

static sem_status make_curve(const double *uv, int n, sem_curve *out, sem_error *err)
{
    if (sem_curve_alloc(out, 1, n) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory projecting a trim curve");
    for (int i = 0; i < n; ++i) {
        out->ctrl[3 * i] = uv[2 * i];
        out->ctrl[3 * i + 1] = uv[2 * i + 1];
        out->ctrl[3 * i + 2] = 0.0;
    }
    out->knots[0] = 0.0;
    for (int i = 0; i < n; ++i) out->knots[i + 1] = (double)i;
    out->knots[n + 1] = (double)(n - 1);
    out->t0 = 0.0;
    out->t1 = (double)(n - 1);
    return SEM_OK;
}

/* Joins chain a's end to chain b's start: snap when they meet in (u,v), a connector when
 * the gap is a collapsed edge, else an error. *connector receives the two points of a
 * connector, *needs 1 then. */
static sem_status join(context *c, const point *a_end, point *b_start, int *needs,
                       double connector[4], const char *where, sem_error *err)
{
    const sem_surface *s = c->s;
    double du = (b_start->uv[0] - a_end->uv[0]) / (s->u1 - s->u0);
    double dv = (b_start->uv[1] - a_end->uv[1]) / (s->v1 - s->v0);
    *needs = 0;
    if (hypot(du, dv) < 1e-9) {
        b_start->uv[0] = a_end->uv[0], b_start->uv[1] = a_end->uv[1];
        return SEM_OK;
    }
    /* is the straight (u,v) segment between them a single point in space (a collapsed
     * edge), or, failing that, a gap between the curves' ends no wider than max_gap (the
     * file's resolution: a connector there is within what the file itself tolerates)? */
    double far = 0, gap = dist3(a_end->x, b_start->x);
    for (int k = 1; k < 8; ++k) {
        double uv[2] = {a_end->uv[0] + (b_start->uv[0] - a_end->uv[0]) * k / 8.0,
                        a_end->uv[1] + (b_start->uv[1] - a_end->uv[1]) * k / 8.0};
        double x[3];
        surface_at(c, uv, x);
        far = fmax(far, fmin(dist3(x, a_end->x), dist3(x, b_start->x)));
    }
    if (far > c->tol && !(far <= c->max_gap && gap <= c->max_gap)) {
        c->join_failed = 1;
        return sem_error_set(err, SEM_ERR_INVALID,
                             "the loop does not close in (u,v) %s: (%.6g, %.6g) to "
                             "(%.6g, %.6g)%s",
                             where, a_end->uv[0], a_end->uv[1], b_start->uv[0], b_start->uv[1],
                             !c->closed[0] && !c->closed[1] ? ""
                             : c->unwrap ? " (it winds around a closed surface)"
                                         : " (it crosses the seam of a closed surface)");
    }
    if (far > c->tol) c->gap = fmax(c->gap, gap);
    *needs = 1;
    connector[0] = a_end->uv[0], connector[1] = a_end->uv[1];
    connector[2] = b_start->uv[0], connector[3] = b_start->uv[1];
    return SEM_OK;
}

/* One pass of sem_trim_project_loop; unwrap: the second (see there). */
static sem_status project_pass(const sem_surface_sampler *sampler, const sem_curve *curves,
                               int n_curves, const sem_trim_projection_settings *settings,
                               int unwrap, sem_trim_loop *out, int *border, double *gap,
                               int *join_failed, sem_error *err)
{
    memset(out, 0, sizeof *out);
    *border = 0;
    *gap = 0;
    *join_failed = 0;
    context c;
    memset(&c, 0, sizeof c);
    c.sampler = sampler;
    c.s = sampler->surface;
    c.tol = settings->tolerance;
    c.max_distance = settings->max_distance;
    c.max_gap = settings->max_gap;
    c.unwrap = unwrap;
    c.closed[0] = sem_surface_is_closed(c.s, 0, c.tol);
    c.closed[1] = sem_surface_is_closed(c.s, 1, c.tol);
    c.eps[0] = 1e-9 * (c.s->u1 - c.s->u0);
    c.eps[1] = 1e-9 * (c.s->v1 - c.s->v0);

    /* chain order: each curve runs from the end nearer the previous curve's end */
    int *reverse = calloc((size_t)n_curves, sizeof *reverse);
    chain *chains = calloc((size_t)n_curves, sizeof *chains);
    sem_status st = SEM_OK;
    if (!reverse || !chains) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory projecting a trim loop");
        goto done;
    }
    /* The surface lies in the box of its control points (positive weights): a curve point
     * farther from that box than allowed fails the loop before any point is projected (a
     * stray curve would otherwise cost every one of its points a full inversion search) */
    double lo[3], hi[3], apart = 0;
    sem_surface_net_box(c.s, lo, hi);
    double last[3];
    for (int k = 0; k < n_curves; ++k) {
        const sem_curve *cv = &curves[k];
        double a[3], b[3];
        sem_curve_eval(cv, cv->t0, a, NULL);
        sem_curve_eval(cv, cv->t1, b, NULL);
        for (int j = 0; j <= 32; ++j) { /* 33 points along the curve, its ends included */
            double x[3], d2 = 0;
            if (j == 0 || j == 32)
                memcpy(x, j ? b : a, sizeof x);
            else
                sem_curve_eval(cv, cv->t0 + (cv->t1 - cv->t0) * j / 32.0, x, NULL);
            for (int e = 0; e < 3; ++e) {
                double g = fmax(fmax(lo[e] - x[e], x[e] - hi[e]), 0);
                d2 += g * g;
            }
            apart = fmax(apart, sqrt(d2));
        }
        if (k == 0) {
            if (n_curves > 1) {
                const sem_curve *nx = &curves[1];
                double c0[3], c1[3];
                sem_curve_eval(nx, nx->t0, c0, NULL);
                sem_curve_eval(nx, nx->t1, c1, NULL);
                reverse[0] = fmin(dist3(a, c0), dist3(a, c1)) < fmin(dist3(b, c0), dist3(b, c1));
            }
        } else {
            reverse[k] = dist3(last, b) < dist3(last, a);
        }
        const double *end = reverse[k] ? a : b;
        memcpy(last, end, sizeof last);
    }

    if (!(apart <= c.max_distance)) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "a model-space boundary curve is %.3g away from its surface "
                           "(allowed %.3g)",
                           apart, c.max_distance);
        goto done;
    }
    for (int k = 0; k < n_curves; ++k) {
        const double *guess = k > 0 && chains[k - 1].n ? chains[k - 1].p[chains[k - 1].n - 1].uv
                                                        : NULL;
        if (!project_curve(&c, &curves[k], reverse[k], guess, &chains[k])) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory projecting a trim loop");
            goto done;
        }
    }
    if (c.worst > c.max_distance) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "a model-space boundary curve is %.3g away from its surface "
                           "(allowed %.3g)",
                           c.worst, c.max_distance);
        goto done;
    }
    fix_seams_and_poles(&c, chains, n_curves);
    /* A curve that crosses the seam of a closed surface jumps by about a period inside its
     * chain (the closest points are found on both sides): the loop cannot be drawn in the
     * domain as it is; the second pass unwraps it. (A jump along a collapsed edge, over a
     * pole, is no crossing.) */
    for (int k = 0; !c.unwrap && (c.closed[0] || c.closed[1]) && k < n_curves; ++k)
        for (int i = 1; i < chains[k].n; ++i) {
            const double *a = chains[k].p[i - 1].uv, *b = chains[k].p[i].uv;
            int jump = (c.closed[0] && fabs(b[0] - a[0]) > 0.5 * (c.s->u1 - c.s->u0)) ||
                       (c.closed[1] && fabs(b[1] - a[1]) > 0.5 * (c.s->v1 - c.s->v0));
            if (jump && !joinable(&c, a, b)) {
                c.join_failed = 1;
                st = sem_error_set(err, SEM_ERR_INVALID, "the loop does not close in (u,v): curve "
                                                         "%d crosses the seam of a closed surface",
                                   k + 1);
                goto done;
            }
        }
    if (!c.unwrap && all_on_border(&c, chains, n_curves)) {
        /* the domain's own border: all of it, or around a closed surface (where the loop,
         * given without the seam, cannot close in (u,v)) */
        int wraps = c.closed[0] || c.closed[1];
        if (wraps || fabs(area_fraction(&c, chains, n_curves) - 1.0) < 1e-6) {
            *border = 1;
            goto done;
        }
    }

    /* joins, then the curves: each chain, and a connector where one is needed */
    out->curves = calloc((size_t)(2 * n_curves), sizeof *out->curves);
    if (!out->curves) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory projecting a trim loop");
        goto done;
    }
    for (int k = 0; k < n_curves && st == SEM_OK; ++k) {
        chain *ch = &chains[k];
        chain *next = &chains[(k + 1) % n_curves];
        double conn[4] = {0, 0, 0, 0};
        int needs = 0;
        char where[64];
        if (k + 1 < n_curves)
            snprintf(where, sizeof where, "between curves %d and %d", k + 1, k + 2);
        else
            snprintf(where, sizeof where, "between its end and its start");
        st = join(&c, &ch->p[ch->n - 1], &next->p[0], &needs, conn, where, err);
        if (st != SEM_OK) break;
        double *uv = malloc((size_t)ch->n * 2 * sizeof *uv);
        if (!uv) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory projecting a trim loop");
            break;
        }
        for (int i = 0; i < ch->n; ++i) uv[2 * i] = ch->p[i].uv[0], uv[2 * i + 1] = ch->p[i].uv[1];
        if (k + 1 == n_curves && !needs) {
            /* closed exactly: the first point of the loop may have been snapped above */
            uv[2 * (ch->n - 1)] = chains[0].p[0].uv[0];
            uv[2 * (ch->n - 1) + 1] = chains[0].p[0].uv[1];
        }
        st = make_curve(uv, ch->n, &out->curves[out->n_curves], err);
        free(uv);
        if (st != SEM_OK) break;
        out->n_curves++;
        if (needs) {
            st = make_curve(conn, 2, &out->curves[out->n_curves], err);
            if (st == SEM_OK) out->n_curves++;
        }
    }

done:
    *gap = c.gap;
    *join_failed = c.join_failed;
    if (st != SEM_OK && out->curves) {
        for (int k = 0; k < out->n_curves; ++k) sem_curve_free(&out->curves[k]);
        free(out->curves);
        memset(out, 0, sizeof *out);
    }
    if (chains)
        for (int k = 0; k < n_curves; ++k) free(chains[k].p);
    free(chains);
    free(reverse);
    return st;
}

sem_status sem_trim_project_loop(const sem_surface_sampler *sampler, const sem_curve *curves,
                                 int n_curves, const sem_trim_projection_settings *settings,
                                 sem_trim_loop *out, int *border, double *gap, sem_error *err)
{
    memset(out, 0, sizeof *out);
    *border = 0;
    *gap = 0;
    if (n_curves < 1) return sem_error_set(err, SEM_ERR_INVALID, "empty trim loop");
    int join_failed = 0;
    sem_status st = project_pass(sampler, curves, n_curves, settings, 0, out, border, gap,
                                 &join_failed, err);
    const sem_surface *s = sampler->surface;
    if (st == SEM_ERR_INVALID && join_failed &&
        (sem_surface_is_closed(s, 0, settings->tolerance) || sem_surface_is_closed(s, 1, settings->tolerance))) {
        /* A loop that crosses the seam of a closed surface jumps by a period where it does,
         * and cannot close in the domain: projected again, each point unwrapped to the
         * period nearest the point before it (as Open CASCADE's shape fixing unwraps its
         * pcurves), the loop runs on across the seam and closes outside the domain; the
         * reader then moves the surface's seam out of its way (geometry/seam.h). The first
         * pass stays the rule: it keeps the seam edges of B-rep faces on their sides. */
        sem_error second;
        int border2 = 0, failed2 = 0;
        double gap2 = 0;
        sem_status st2 = project_pass(sampler, curves, n_curves, settings, 1, out, &border2, &gap2,
                                      &failed2, &second);
        if (st2 == SEM_OK || st2 == SEM_ERR_NOMEM) {
            st = st2;
            *border = border2;
            *gap = gap2;
            if (st2 != SEM_OK && err) *err = second;
        }
    }
    return st;
}
