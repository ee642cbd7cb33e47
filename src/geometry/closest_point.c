/*
 * closest_point.c - point inversion on NURBS surfaces (see geometry/closest_point.h).
 *
 * Why a sampler and several starts: Newton on the squared distance converges fast from
 * near the answer but may stop at a local minimum on a curved patch (the far side of a
 * cylinder, or a bump of f at the border of a narrow twisted strip: rocket.iges has a
 * constrained minimum 0.33 away from a point that lies on the strip's other edge), or crawl
 * along a collapsed edge (a pole, where x_u vanishes). Callers that follow a curve pass the
 * previous point's parameters as the guess, which is right almost always: a guess that ends
 * on the point (within `accept`) is taken; otherwise the nearest samples are tried too and
 * the best result wins.
 */
#include "geometry/closest_point.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/vector3.h"
#include "sem/nurbs.h"

#define NEWTON_ITERATIONS 40
#define STARTS 4 /* nearest samples tried when the guess is not good enough */

sem_status sem_surface_sampler_build(const sem_surface *s, sem_surface_sampler *out,
                                     sem_error *err)
{
    /* per span: 2 intervals (3 points); Newton from the nearest few finds the rest */
    return sem_surface_sampler_build_dense(s, 2, out, err);
}

sem_status sem_surface_sampler_build_dense(const sem_surface *s, int per_span,
                                           sem_surface_sampler *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    out->surface = s;
    double bu[512], bv[512];
    int nu = sem_knot_breaks(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, bu, 512);
    int nv = sem_knot_breaks(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, bv, 512);
    if (nu < 2 || nv < 2) {
        bu[0] = s->u0, bu[1] = s->u1, nu = 2;
        bv[0] = s->v0, bv[1] = s->v1, nv = 2;
    }
    int per_u = per_span < 1 ? 1 : per_span, per_v = per_u;
    int gu = (nu - 1) * per_u + 1, gv = (nv - 1) * per_v + 1;
    out->n = gu * gv;
    out->uv = malloc((size_t)out->n * 2 * sizeof(double));
    out->x = malloc((size_t)out->n * 3 * sizeof(double));
    if (!out->uv || !out->x) {
        sem_surface_sampler_free(out);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory sampling a surface");
    }
    for (int j = 0; j < gv; ++j) {
        int sj = j / per_v, rj = j % per_v;
        double v = sj >= nv - 1 ? bv[nv - 1] : bv[sj] + (bv[sj + 1] - bv[sj]) * rj / per_v;
        for (int i = 0; i < gu; ++i) {
            int si = i / per_u, ri = i % per_u;
            double u = si >= nu - 1 ? bu[nu - 1] : bu[si] + (bu[si + 1] - bu[si]) * ri / per_u;
            size_t k = (size_t)j * gu + i;
            out->uv[2 * k] = u;
            out->uv[2 * k + 1] = v;
            sem_surface_eval(s, u, v, out->x + 3 * k, NULL, NULL, NULL);
        }
    }
    /* closed directions: the sides meet within 1e-9 of the surface's size (an exact closed
     * NURBS meets to round-off) at the samples along them */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k < out->n; ++k)
        for (int d = 0; d < 3; ++d) {
            lo[d] = fmin(lo[d], out->x[3 * k + d]);
            hi[d] = fmax(hi[d], out->x[3 * k + d]);
        }
    double size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    for (int dir = 0; dir < 2; ++dir) {
        int n_side = dir == 0 ? gv : gu, closed = size > 0;
        for (int j = 0; j < n_side && closed; ++j) {
            const double *a = out->x + 3 * (dir == 0 ? (size_t)j * gu : (size_t)j);
            const double *b = out->x + 3 * (dir == 0 ? (size_t)j * gu + gu - 1 : (size_t)(gv - 1) * gu + j);
            double e[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
            closed = dot3(e, e) <= 1e-18 * size * size;
        }
        out->period[dir] = closed ? (dir == 0 ? s->u1 - s->u0 : s->v1 - s->v0) : 0;
    }
    return SEM_OK;
}

void sem_surface_sampler_free(sem_surface_sampler *sampler)
{
    free(sampler->uv);
    free(sampler->x);
    sampler->uv = sampler->x = NULL;
    sampler->n = 0;
}

static double clampd(double x, double lo, double hi) { return x < lo ? lo : x > hi ? hi : x; }

/* t into [lo, hi] by the period (a closed direction) or by clamping */
static double into(double t, double lo, double hi, double period)
{
    if (period > 0 && (t < lo || t > hi)) t -= period * floor((t - lo) / period);
    return clampd(t, lo, hi);
}

/* Newton from uv; a step across a seam (period > 0 in that direction) wraps around. */
static double newton(const sem_surface *s, const double period[2], const double p[3], double uv[2])
{
    double u = clampd(uv[0], s->u0, s->u1), v = clampd(uv[1], s->v0, s->v1);
    double span_u = s->u1 - s->u0, span_v = s->v1 - s->v0;
    double x[3], xu[3], xv[3], d2[9], d[3];
    sem_surface_eval(s, u, v, x, xu, xv, d2);
    for (int c = 0; c < 3; ++c) d[c] = x[c] - p[c];
    double f = dot3(d, d);
    for (int it = 0; it < NEWTON_ITERATIONS; ++it) {
        double g0 = dot3(xu, d), g1 = dot3(xv, d);
        double a = dot3(xu, xu), b = dot3(xu, xv), c = dot3(xv, xv);
        /* full Hessian of f/2 */
        double A = a + dot3(d2, d), B = b + dot3(d2 + 3, d), C = c + dot3(d2 + 6, d);
        double det = A * C - B * B;
        if (!(A > 0 && det > 1e-14 * (A * C + B * B + DBL_MIN))) {
            /* Gauss-Newton: drop the curvature terms, keep it positive definite */
            A = a * (1 + 1e-12) + DBL_MIN, B = b, C = c * (1 + 1e-12) + DBL_MIN;
            det = A * C - B * B;
            if (!(det > 0)) {
                /* a degenerate point (pole): move along the non-degenerate direction */
                A = a + 1e-30, C = c + 1e-30, B = 0, det = A * C;
            }
        }
        double du = -(C * g0 - B * g1) / det, dv = -(A * g1 - B * g0) / det;
        if (!isfinite(du) || !isfinite(dv)) break;
        /* backtracking on f so that a bad quadratic model cannot walk away */
        double step = 1.0, nu_ = u, nv_ = v, nf = f;
        double nx[3], nxu[3], nxv[3], nd2[9], ndv[3];
        int accepted = 0;
        for (int ls = 0; ls < 12; ++ls, step *= 0.5) {
            nu_ = into(u + step * du, s->u0, s->u1, period[0]);
            nv_ = into(v + step * dv, s->v0, s->v1, period[1]);
            sem_surface_eval(s, nu_, nv_, nx, nxu, nxv, nd2);
            for (int k = 0; k < 3; ++k) ndv[k] = nx[k] - p[k];
            nf = dot3(ndv, ndv);
            if (nf <= f) {
                accepted = 1;
                break;
            }
        }
        if (!accepted) break;
        double mu = fabs(nu_ - u), mv = fabs(nv_ - v);
        if (period[0] > 0) mu = fmin(mu, fabs(span_u - mu)); /* across a seam */
        if (period[1] > 0) mv = fmin(mv, fabs(span_v - mv));
        double moved = mu / span_u + mv / span_v;
        u = nu_, v = nv_, f = nf;
        memcpy(x, nx, sizeof x), memcpy(xu, nxu, sizeof xu), memcpy(xv, nxv, sizeof xv);
        memcpy(d2, nd2, sizeof d2), memcpy(d, ndv, sizeof d);
        if (moved < 1e-15) break;
    }
    uv[0] = u;
    uv[1] = v;
    return sqrt(f);
}

double sem_surface_refine_closest(const sem_surface *s, const double p[3], double uv[2])
{
    const double open[2] = {0, 0};
    return newton(s, open, p, uv);
}

double sem_surface_closest_point(const sem_surface_sampler *sampler, const double p[3],
                                 const double *guess, double accept, double uv[2])
{
    const sem_surface *s = sampler->surface;
    double best = INFINITY, best_uv[2] = {s->u0, s->v0};
    if (guess) {
        best_uv[0] = guess[0], best_uv[1] = guess[1];
        best = newton(s, sampler->period, p, best_uv);
        if (best <= accept) {
            uv[0] = best_uv[0], uv[1] = best_uv[1];
            return best;
        }
    }
    /* the STARTS nearest samples */
    int idx[STARTS];
    double dist[STARTS];
    for (int k = 0; k < STARTS; ++k) idx[k] = -1, dist[k] = INFINITY;
    for (int i = 0; i < sampler->n; ++i) {
        const double *x = sampler->x + 3 * i;
        double e[3] = {x[0] - p[0], x[1] - p[1], x[2] - p[2]};
        double d = dot3(e, e);
        if (d >= dist[STARTS - 1]) continue;
        /* one start per point: the samples of a collapsed row (a pole) are one point, and
         * starts there all stay there (x_v = 0: Newton cannot turn to the point's meridian;
         * a surface of revolution's pole took all four starts: corpus occt_solidworks_tube) */
        int same = 0;
        for (int k = 0; k < STARTS && idx[k] >= 0 && !same; ++k) {
            const double *y = sampler->x + 3 * idx[k];
            double f[3] = {x[0] - y[0], x[1] - y[1], x[2] - y[2]};
            same = dot3(f, f) <= 1e-24 * (dot3(x, x) + dot3(e, e));
        }
        if (same) continue;
        int k = STARTS - 1;
        while (k > 0 && dist[k - 1] > d) {
            dist[k] = dist[k - 1], idx[k] = idx[k - 1];
            --k;
        }
        dist[k] = d, idx[k] = i;
    }
    for (int k = 0; k < STARTS && idx[k] >= 0; ++k) {
        double t[2] = {sampler->uv[2 * idx[k]], sampler->uv[2 * idx[k] + 1]};
        double d = newton(s, sampler->period, p, t);
        /* the guess wins ties: it keeps a curve on its side of a seam or pole */
        if (d < best * (1 - 1e-9) - 1e-300) {
            best = d;
            best_uv[0] = t[0], best_uv[1] = t[1];
        }
    }
    uv[0] = best_uv[0], uv[1] = best_uv[1];
    return best;
}
