/* test_nurbs.c - basis functions and NURBS evaluation against closed forms. */
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "test_util.h"

/* partition of unity and derivative sums for random knot vectors (repeated interior,
 * unclamped, shifted ranges), derivatives against central differences */
static void test_basis_properties(void)
{
    srand(7);
    for (int trial = 0; trial < 200; ++trial) {
        int p = 1 + rand() % 5;
        int n = p + 1 + rand() % 6;
        int m = n + p + 1;
        double knots[64];
        double x = -3.0 + (rand() % 100) / 10.0;
        int clamped = trial % 2;
        for (int i = 0; i < m; ++i) {
            if (clamped && i <= p) {
                knots[i] = x;
                continue;
            }
            if (clamped && i >= n) {
                knots[i] = knots[n];
                if (i == n) knots[i] = x + 0.5 + (rand() % 3) * 0.25;
                if (i > n) knots[i] = knots[n];
                continue;
            }
            x += (rand() % 4 == 0) ? 0.0 : 0.1 + (rand() % 10) / 10.0; /* some repeats */
            knots[i] = x;
        }
        if (clamped) for (int i = n + 1; i < m; ++i) knots[i] = knots[n];
        double a = knots[p], b = knots[n];
        if (!(b > a)) continue;
        for (int s = 0; s <= 20; ++s) {
            double t = s == 20 ? b : a + (b - a) * s / 20.0;
            int span = sem_bspline_span(p, n, knots, t);
            CHECK(span >= p && span <= n - 1, "span %d", span);
            CHECK(knots[span] <= t && (t < knots[span + 1] || (t == b && knots[span + 1] == b)),
                  "t %g not in span [%g,%g)", t, knots[span], knots[span + 1]);
            double d[3 * 32];
            sem_bspline_basis(p, knots, span, t, 2, d);
            double sum = 0, sum1 = 0, sum2 = 0;
            for (int r = 0; r <= p; ++r) {
                sum += d[r];
                sum1 += d[p + 1 + r];
                sum2 += d[2 * (p + 1) + r];
                CHECK(d[r] >= -1e-13, "basis negative %g", d[r]);
            }
            CHECK_NEAR(sum, 1.0, 1e-13);
            CHECK_NEAR(sum1, 0.0, 1e-9 * (1 + fabs(d[p + 1])));
            CHECK_NEAR(sum2, 0.0, 1e-7 * (1 + fabs(d[2 * (p + 1)])));
            /* central difference inside the span */
            double h = 1e-6 * (knots[span + 1] - knots[span]);
            if (t - h > knots[span] && t + h < knots[span + 1]) {
                double dp[3 * 32], dm[3 * 32];
                sem_bspline_basis(p, knots, span, t + h, 1, dp);
                sem_bspline_basis(p, knots, span, t - h, 1, dm);
                for (int r = 0; r <= p; ++r) {
                    double fd = (dp[r] - dm[r]) / (2 * h);
                    CHECK_NEAR(d[p + 1 + r], fd, 1e-6 * (1 + fabs(fd)));
                    double fd2 = (dp[p + 1 + r] - dm[p + 1 + r]) / (2 * h);
                    CHECK_NEAR(d[2 * (p + 1) + r], fd2, 1e-4 * (1 + fabs(fd2)));
                }
            }
        }
    }
}

/* Quarter circle as rational quadratic: every point at radius 1 (closed form). */
static void test_rational_circle(void)
{
    sem_curve c;
    CHECK(sem_curve_alloc(&c, 2, 3) == SEM_OK, "alloc");
    double k[6] = {0, 0, 0, 1, 1, 1};
    memcpy(c.knots, k, sizeof k);
    double P[9] = {1, 0, 0, 1, 1, 0, 0, 1, 0};
    memcpy(c.ctrl, P, sizeof P);
    c.weights[1] = sqrt(0.5);
    c.t0 = 0;
    c.t1 = 1;
    for (int i = 0; i <= 50; ++i) {
        double x[3], d[3];
        sem_curve_eval(&c, i / 50.0, x, d);
        CHECK_NEAR(hypot(x[0], x[1]), 1.0, 1e-14);
        CHECK_NEAR(x[0] * d[0] + x[1] * d[1], 0.0, 1e-13); /* tangent orthogonal to radius */
    }
    sem_curve_free(&c);
}

/* A rational sphere octant patch (degree 2x2); points on the sphere, derivatives by FD,
 * and the basis row reproduces the point (x = J q). */
static void test_rational_surface(void)
{
    sem_surface s;
    CHECK(sem_surface_alloc(&s, 2, 2, 3, 3) == SEM_OK, "alloc");
    double k[6] = {0, 0, 0, 1, 1, 1};
    memcpy(s.knots_u, k, sizeof k);
    memcpy(s.knots_v, k, sizeof k);
    /* surface of revolution of the quarter circle (x,z) about z, quarter turn */
    double arc[3][2] = {{1, 0}, {1, 1}, {0, 1}}; /* (r, z) */
    double aw[3] = {1, sqrt(0.5), 1};
    double rot[3][2] = {{1, 0}, {1, 1}, {0, 1}};
    double rw[3] = {1, sqrt(0.5), 1};
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 3; ++i) {
            int idx = i + 3 * j;
            s.ctrl[3 * idx] = arc[i][0] * rot[j][0];
            s.ctrl[3 * idx + 1] = arc[i][0] * rot[j][1];
            s.ctrl[3 * idx + 2] = arc[i][1];
            s.weights[idx] = aw[i] * rw[j];
        }
    s.u0 = s.v0 = 0;
    s.u1 = s.v1 = 1;
    CHECK(sem_surface_validate(&s, NULL) == SEM_OK, "valid");
    for (int a = 0; a <= 10; ++a)
        for (int b = 0; b <= 10; ++b) {
            double u = a / 10.0, v = b / 10.0, x[3], du[3], dv[3], d2[9];
            sem_surface_eval(&s, u, v, x, du, dv, d2);
            CHECK_NEAR(sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]), 1.0, 1e-14);
            int idx[9];
            double phi[9], phu[9], phv[9], y[3] = {0, 0, 0}, yu[3] = {0, 0, 0};
            int n = sem_surface_basis(&s, u, v, idx, phi, phu, phv);
            CHECK(n == 9, "n %d", n);
            for (int k2 = 0; k2 < n; ++k2)
                for (int d = 0; d < 3; ++d) {
                    y[d] += phi[k2] * s.ctrl[3 * idx[k2] + d];
                    yu[d] += phu[k2] * s.ctrl[3 * idx[k2] + d];
                }
            for (int d = 0; d < 3; ++d) {
                CHECK_NEAR(y[d], x[d], 1e-14);
                CHECK_NEAR(yu[d], du[d], 1e-12);
            }
            if (a > 0 && a < 10 && b > 0 && b < 10) {
                double h = 1e-5, xp[3], xm[3], dup[3], dum[3];
                sem_surface_eval(&s, u + h, v, xp, dup, NULL, NULL);
                sem_surface_eval(&s, u - h, v, xm, dum, NULL, NULL);
                for (int d = 0; d < 3; ++d) {
                    CHECK_NEAR(du[d], (xp[d] - xm[d]) / (2 * h), 1e-8);
                    CHECK_NEAR(d2[d], (dup[d] - dum[d]) / (2 * h), 1e-6);
                }
                double dvp[3], dvm[3];
                sem_surface_eval(&s, u, v + h, xp, NULL, dvp, NULL);
                sem_surface_eval(&s, u, v - h, xm, NULL, dvm, NULL);
                for (int d = 0; d < 3; ++d) {
                    CHECK_NEAR(dv[d], (xp[d] - xm[d]) / (2 * h), 1e-8);
                    CHECK_NEAR(d2[6 + d], (dvp[d] - dvm[d]) / (2 * h), 1e-6);
                }
                sem_surface_eval(&s, u + h, v, NULL, NULL, dvp, NULL);
                sem_surface_eval(&s, u - h, v, NULL, NULL, dvm, NULL);
                for (int d = 0; d < 3; ++d) CHECK_NEAR(d2[3 + d], (dvp[d] - dvm[d]) / (2 * h), 1e-6);
            }
        }
    /* the pole (u = 1, collapsed edge) has a finite normal pointing along +z */
    double nrm[3];
    double area = sem_surface_normal(&s, 1.0, 0.5, nrm);
    CHECK(area < 1e-12, "area element at pole %g", area);
    CHECK_NEAR(fabs(nrm[2]), 1.0, 1e-5);
    sem_surface_free(&s);
}

static void test_quadrature_rules(void)
{
    for (int n = 1; n <= 20; ++n) {
        double x[64], w[64];
        sem_gauss_legendre(n, x, w);
        /* exact for degree 2n-1 */
        for (int d = 0; d <= 2 * n - 1; ++d) {
            double s = 0;
            for (int i = 0; i < n; ++i) s += w[i] * pow(x[i], d);
            CHECK_NEAR(s, d % 2 ? 0.0 : 2.0 / (d + 1), 1e-13);
        }
        if (n >= 2) {
            sem_gauss_lobatto(n, x, w);
            CHECK(x[0] == -1.0 && x[n - 1] == 1.0, "lobatto ends");
            for (int d = 0; d <= 2 * n - 3; ++d) {
                double s = 0;
                for (int i = 0; i < n; ++i) s += w[i] * pow(x[i], d);
                CHECK_NEAR(s, d % 2 ? 0.0 : 2.0 / (d + 1), 1e-13);
            }
        }
    }
}

static void test_validate(void)
{
    sem_surface s;
    sem_surface_alloc(&s, 3, 3, 4, 4);
    double k[8] = {0, 0, 0, 0, 1, 1, 1, 1};
    memcpy(s.knots_u, k, sizeof k);
    memcpy(s.knots_v, k, sizeof k);
    s.u1 = s.v1 = 1;
    sem_error err;
    CHECK(sem_surface_validate(&s, &err) == SEM_OK, "valid");
    s.weights[5] = 0.0;
    CHECK(sem_surface_validate(&s, &err) == SEM_ERR_INVALID, "zero weight");
    CHECK(strstr(err.message, "weight") != NULL, "%s", err.message);
    s.weights[5] = 1.0;
    s.knots_u[4] = -1;
    CHECK(sem_surface_validate(&s, &err) == SEM_ERR_INVALID, "decreasing knots");
    s.knots_u[4] = 1;
    s.ctrl[4] = NAN;
    CHECK(sem_surface_validate(&s, &err) == SEM_ERR_INVALID, "nan");
    sem_surface_free(&s);
}

int main(void)
{
    test_basis_properties();
    test_rational_circle();
    test_rational_surface();
    test_quadrature_rules();
    test_validate();
    return test_finish("test_nurbs");
}
