/* test_barrier.c - the pieces of the barrier contact model (issue 31, item 2;
 * src/contact/barrier.h, ccd.h, narrow_phase.h):
 *   - IPC's barrier against its closed form, C2 at dhat (value, slope, curvature 0), its
 *     derivatives against central differences, infinite at contact;
 *   - the edge-edge mollifier: 1 for crossing edges, 0 for parallel ones, its gradient
 *     against central differences;
 *   - the closest points of two segments against a fine grid of both parameters;
 *   - additive CCD on random linear motions built to collide at a known time t*: the
 *     returned time is never later than t*, the pair stays apart at 2,000 times over the
 *     returned interval (the guarantee), and it is not absurdly early (>= 1e-3 t*); motions
 *     that separate return the whole step; point-plane exactly.
 */
#include <math.h>
#include <string.h>

#include "contact/barrier.h"
#include "contact/ccd.h"
#include "contact/narrow_phase.h"
#include "geometry/point_triangle.h"
#include "test_util.h"

static void test_barrier_function(void)
{
    double dhat = 0.01, db, d2b;
    /* closed form at dhat / 2: -(dhat/2)^2 ln(1/2) */
    CHECK_REL(sem_barrier(0.005, dhat, NULL, NULL), 0.25e-4 * log(2.0), 1e-14);
    /* C2 at dhat, zero beyond */
    CHECK(sem_barrier(dhat, dhat, &db, &d2b) == 0 && db == 0 && d2b == 0, "active at dhat");
    CHECK(sem_barrier(2 * dhat, dhat, &db, &d2b) == 0 && db == 0 && d2b == 0, "active beyond dhat");
    double near = 0.999999 * dhat;
    sem_barrier(near, dhat, &db, &d2b);
    CHECK(fabs(db) < 1e-10 && fabs(d2b) < 1e-3, "slope %g, curvature %g just below dhat", db, d2b);
    /* infinite at contact, decreasing and convex inside */
    CHECK(isinf(sem_barrier(0, dhat, NULL, NULL)), "b(0) is finite");
    CHECK(isinf(sem_barrier(-1e-3, dhat, NULL, NULL)), "b(d < 0) is finite");
    for (double d = 1e-6; d < dhat; d *= 1.7) {
        double h = 1e-6 * d, bp, bm, dbp, dbm;
        sem_barrier(d, dhat, &db, &d2b);
        bp = sem_barrier(d + h, dhat, &dbp, NULL);
        bm = sem_barrier(d - h, dhat, &dbm, NULL);
        CHECK(db < 0 && d2b > 0, "d = %g: slope %g, curvature %g", d, db, d2b);
        CHECK_REL(db, (bp - bm) / (2 * h), 1e-6);
        CHECK_REL(d2b, (dbp - dbm) / (2 * h), 1e-6);
    }
}

static void edge_positions(const double *v, double x[4][3])
{
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) x[i][k] = v[3 * i + k];
}

static void test_mollifier(void)
{
    double a0[3] = {0, 0, 0}, a1[3] = {1, 0, 0}, b0[3] = {0, -0.5, 0.1}, b1[3] = {0, 0.5, 0.1};
    double g[4][3];
    CHECK(sem_edge_mollifier(a0, a1, b0, b1, 1e-3, g) == 1, "crossing edges are mollified");
    double c0[3] = {0, 0, 0.1}, c1[3] = {1, 0, 0.1};
    CHECK(sem_edge_mollifier(a0, a1, c0, c1, 1e-3, g) == 0, "parallel edges keep their barrier");
    /* the gradient of nearly parallel edges against central differences */
    unsigned long long seed = 12345;
    int checked = 0;
    for (int trial = 0; trial < 200; ++trial) {
        double v[12];
        for (int i = 0; i < 12; ++i) v[i] = test_uniform(&seed) - 0.5;
        /* edge b nearly parallel to edge a */
        for (int k = 0; k < 3; ++k) v[9 + k] = v[6 + k] + (v[3 + k] - v[k]) + 0.02 * (test_uniform(&seed) - 0.5);
        double x[4][3];
        edge_positions(v, x);
        double eps = 1e-3;
        double m = sem_edge_mollifier(x[0], x[1], x[2], x[3], eps, g);
        if (!(m > 0 && m < 1)) continue;
        ++checked;
        for (int i = 0; i < 12; ++i) {
            double h = 1e-7, vp[12], vm[12], xp[4][3], xm[4][3];
            memcpy(vp, v, sizeof v);
            memcpy(vm, v, sizeof v);
            vp[i] += h;
            vm[i] -= h;
            edge_positions(vp, xp);
            edge_positions(vm, xm);
            double fd = (sem_edge_mollifier(xp[0], xp[1], xp[2], xp[3], eps, NULL) -
                         sem_edge_mollifier(xm[0], xm[1], xm[2], xm[3], eps, NULL)) /
                        (2 * h);
            CHECK(fabs(fd - g[i / 3][i % 3]) <= 1e-5 * (1 + fabs(fd)), "trial %d, coordinate %d: %g vs %g", trial, i,
                  g[i / 3][i % 3], fd);
        }
    }
    CHECK(checked >= 20, "only %d mollified pairs", checked);
}

static void test_segments(void)
{
    unsigned long long seed = 777;
    for (int trial = 0; trial < 300; ++trial) {
        double v[12];
        for (int i = 0; i < 12; ++i) v[i] = test_uniform(&seed) - 0.5;
        if (trial % 3 == 1) /* parallel */
            for (int k = 0; k < 3; ++k) v[9 + k] = v[6 + k] + 0.7 * (v[3 + k] - v[k]);
        if (trial % 3 == 2) /* a point-like segment */
            for (int k = 0; k < 3; ++k) v[3 + k] = v[k];
        double s, t, d2 = sem_segment_closest(v, v + 3, v + 6, v + 9, &s, &t);
        CHECK(s >= 0 && s <= 1 && t >= 0 && t <= 1, "parameters %g %g", s, t);
        double diff2 = 0;
        for (int k = 0; k < 3; ++k) {
            double d = v[k] + s * (v[3 + k] - v[k]) - v[6 + k] - t * (v[9 + k] - v[6 + k]);
            diff2 += d * d;
        }
        CHECK_NEAR(diff2, d2, 1e-14);
        double best = INFINITY;
        int n = 200;
        for (int i = 0; i <= n; ++i)
            for (int j = 0; j <= n; ++j) {
                double u = (double)i / n, w = (double)j / n, e2 = 0;
                for (int k = 0; k < 3; ++k) {
                    double d = v[k] + u * (v[3 + k] - v[k]) - v[6 + k] - w * (v[9 + k] - v[6 + k]);
                    e2 += d * d;
                }
                if (e2 < best) best = e2;
            }
        CHECK(d2 <= best + 1e-14, "trial %d: %g above the grid's %g", trial, d2, best);
        CHECK(sqrt(best) - sqrt(d2) <= 0.02, "trial %d: %g far below the grid's %g", trial, d2, best);
    }
}

/* distance of the pair at time t: point-triangle (edges 0) or edge-edge */
static double pair_distance(int edges, const double x0[4][3], const double p[4][3], double t)
{
    double y[4][3];
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) y[i][k] = x0[i][k] + t * p[i][k];
    if (edges) {
        double s, u;
        return sqrt(sem_segment_closest(y[0], y[1], y[2], y[3], &s, &u));
    }
    sem_tri_closest c;
    sem_point_triangle_closest(y[0], y[1], y[2], y[3], &c);
    return sqrt(c.dist2);
}

/* Random pairs that meet at t*: the point reaches a point inside the triangle (or the
 * edges cross) at t*, every vertex moving linearly from a random start. */
static void test_ccd(int edges)
{
    unsigned long long seed = edges ? 4242 : 2424;
    int early = 0, trials = 400;
    for (int trial = 0; trial < trials; ++trial) {
        double tstar = 0.05 + 0.9 * test_uniform(&seed);
        double at[4][3], x0[4][3], p[4][3];
        double X[3];
        for (int k = 0; k < 3; ++k) X[k] = test_uniform(&seed) - 0.5;
        if (edges) {
            double u[3], w[3];
            for (int k = 0; k < 3; ++k) {
                u[k] = test_uniform(&seed) - 0.5;
                w[k] = test_uniform(&seed) - 0.5;
            }
            double sa = 0.1 + 0.8 * test_uniform(&seed), sb = 0.1 + 0.8 * test_uniform(&seed);
            for (int k = 0; k < 3; ++k) {
                at[0][k] = X[k] - sa * u[k];
                at[1][k] = X[k] + (1 - sa) * u[k];
                at[2][k] = X[k] - sb * w[k];
                at[3][k] = X[k] + (1 - sb) * w[k];
            }
        } else {
            /* a triangle around X, the point at X */
            double b1 = 0.1 + 0.3 * test_uniform(&seed), b2 = 0.1 + 0.3 * test_uniform(&seed), b0 = 1 - b1 - b2;
            double e1[3], e2[3];
            for (int k = 0; k < 3; ++k) {
                e1[k] = test_uniform(&seed) - 0.5;
                e2[k] = test_uniform(&seed) - 0.5;
            }
            for (int k = 0; k < 3; ++k) {
                /* X = b0 A + b1 B + b2 C with B = A + e1, C = A + e2 */
                at[1][k] = X[k] - b1 * e1[k] - b2 * e2[k];
                at[2][k] = at[1][k] + e1[k];
                at[3][k] = at[1][k] + e2[k];
                at[0][k] = X[k];
            }
            (void)b0;
        }
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 3; ++k) {
                x0[i][k] = at[i][k] + (test_uniform(&seed) - 0.5);
                p[i][k] = (at[i][k] - x0[i][k]) / tstar;
            }
        const double *xs[4] = {x0[0], x0[1], x0[2], x0[3]}, *ps[4] = {p[0], p[1], p[2], p[3]};
        double t = edges ? sem_ccd_edge_edge(xs, ps, 1.0) : sem_ccd_point_triangle(xs, ps, 1.0);
        CHECK(t <= tstar, "trial %d: CCD %g after the contact at %g", trial, t, tstar);
        double least = INFINITY;
        for (int i = 0; i <= 2000; ++i) least = fmin(least, pair_distance(edges, x0, p, t * i / 2000.0));
        CHECK(least > 0, "trial %d: the pair touches before the CCD's %g (distance %g)", trial, t, least);
        early += t < 1e-3 * tstar;
        /* reversed, the same pair separates: nothing stops it before the end */
        double q[4][3];
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 3; ++k) q[i][k] = -p[i][k];
        const double *qs[4] = {q[0], q[1], q[2], q[3]};
        double d0 = pair_distance(edges, x0, q, 0), least_back = INFINITY;
        for (int i = 0; i <= 200; ++i) least_back = fmin(least_back, pair_distance(edges, x0, q, i / 200.0));
        if (least_back >= 0.5 * d0) { /* (it truly moves apart) */
            double back = edges ? sem_ccd_edge_edge(xs, qs, 1.0) : sem_ccd_point_triangle(xs, qs, 1.0);
            CHECK(back > 0.05, "trial %d: a separating motion stopped at %g", trial, back);
        }
    }
    CHECK(early <= trials / 100, "%d of %d CCD times below 1e-3 t*", early, trials);
    /* a rigid translation of both keeps the distance: the whole step */
    double x0[4][3] = {{0, 0, 1}, {0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, p[4][3];
    for (int i = 0; i < 4; ++i) {
        p[i][0] = 5;
        p[i][1] = -3;
        p[i][2] = 2;
    }
    const double *xs[4] = {x0[0], x0[1], x0[2], x0[3]}, *ps[4] = {p[0], p[1], p[2], p[3]};
    CHECK(sem_ccd_point_triangle(xs, ps, 1.0) == 1.0, "a translation is stopped");
}

static void test_plane(void)
{
    /* at 1 m, approaching at 4 m/s: stops at (1 - s) / 4 */
    CHECK_REL(sem_ccd_point_plane(1.0, -4.0, 1.0), (1 - SEM_CCD_SEPARATION) / 4.0, 1e-15);
    CHECK(sem_ccd_point_plane(1.0, 4.0, 1.0) == 1.0, "moving away is stopped");
    CHECK(sem_ccd_point_plane(1.0, -0.5, 1.0) == 1.0, "a point that does not reach the plane is stopped");
    CHECK(sem_ccd_point_plane(0.0, -1.0, 1.0) == 0.0, "a point on the plane may move into it");
}

int main(void)
{
    test_barrier_function();
    test_mollifier();
    test_segments();
    test_ccd(0);
    test_ccd(1);
    test_plane();
    return test_finish("barrier");
}
