/*
 * nurbs.c - B-spline basis functions and rational surface/curve evaluation (paper Eq. 1-2).
 *
 * Algorithms A2.1 (span) and A2.3 (basis derivatives) of Piegl & Tiller, The NURBS Book.
 * They need nothing of the knot vector but non-decreasing values, so clamped, unclamped
 * (periodic-style, as Rhino writes closed surfaces), repeated interior knots and ranges
 * that do not start at 0 are all the same case. Rational derivatives use the quotient
 * rule on the homogeneous coordinates (A4.4 for surfaces, restricted to order 2).
 */
#include "sem/nurbs.h"

#include <math.h>
#include <string.h>

int sem_bspline_span(int degree, int n_ctrl, const double *knots, double t)
{
    int lo = degree, hi = n_ctrl; /* valid spans: degree .. n_ctrl-1 */
    if (t >= knots[n_ctrl]) {
        /* end of the range: the last non-empty span */
        int s = n_ctrl - 1;
        while (s > degree && !(knots[s] < knots[s + 1])) --s;
        return s;
    }
    if (t <= knots[degree]) {
        int s = degree;
        while (s < n_ctrl - 1 && !(knots[s] < knots[s + 1])) ++s;
        return s;
    }
    /* binary search for knots[lo] <= t < knots[hi] */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (t < knots[mid])
            hi = mid;
        else
            lo = mid;
    }
    return lo;
}

void sem_bspline_basis(int degree, const double *knots, int span, double t, int n_derivs,
                       double *ders)
{
    const int p = degree;
    double ndu[SEM_MAX_DEGREE + 1][SEM_MAX_DEGREE + 1];
    double left[SEM_MAX_DEGREE + 2], right[SEM_MAX_DEGREE + 2];
    double a[2][SEM_MAX_DEGREE + 1];

    ndu[0][0] = 1.0;
    for (int j = 1; j <= p; ++j) {
        left[j] = t - knots[span + 1 - j];
        right[j] = knots[span + j] - t;
        double saved = 0.0;
        for (int r = 0; r < j; ++r) {
            ndu[j][r] = right[r + 1] + left[j - r]; /* lower triangle: knot differences */
            double temp = ndu[j][r] != 0.0 ? ndu[r][j - 1] / ndu[j][r] : 0.0;
            ndu[r][j] = saved + right[r + 1] * temp;
            saved = left[j - r] * temp;
        }
        ndu[j][j] = saved;
    }
    for (int j = 0; j <= p; ++j) ders[j] = ndu[j][p];
    int nd = n_derivs < p ? n_derivs : p;
    for (int k = p + 1; k <= n_derivs; ++k)
        for (int j = 0; j <= p; ++j) ders[k * (p + 1) + j] = 0.0;
    if (nd == 0) return;

    for (int r = 0; r <= p; ++r) {
        int s1 = 0, s2 = 1;
        a[0][0] = 1.0;
        for (int k = 1; k <= nd; ++k) {
            double d = 0.0;
            int rk = r - k, pk = p - k;
            if (r >= k) {
                a[s2][0] = ndu[pk + 1][rk] != 0.0 ? a[s1][0] / ndu[pk + 1][rk] : 0.0;
                d = a[s2][0] * ndu[rk][pk];
            }
            int j1 = rk >= -1 ? 1 : -rk;
            int j2 = (r - 1 <= pk) ? k - 1 : p - r;
            for (int j = j1; j <= j2; ++j) {
                double den = ndu[pk + 1][rk + j];
                a[s2][j] = den != 0.0 ? (a[s1][j] - a[s1][j - 1]) / den : 0.0;
                d += a[s2][j] * ndu[rk + j][pk];
            }
            if (r <= pk) {
                double den = ndu[pk + 1][r];
                a[s2][k] = den != 0.0 ? -a[s1][k - 1] / den : 0.0;
                d += a[s2][k] * ndu[r][pk];
            }
            ders[k * (p + 1) + r] = d;
            int tmp = s1;
            s1 = s2;
            s2 = tmp;
        }
    }
    double factor = p;
    for (int k = 1; k <= nd; ++k) {
        for (int j = 0; j <= p; ++j) ders[k * (p + 1) + j] *= factor;
        factor *= (double)(p - k);
    }
}

/* Homogeneous sums for the surface: A = sum w N_i N_j P, W = sum w N_i N_j and their
 * derivatives up to order 2, then the quotient rule. */
void sem_surface_eval(const sem_surface *s, double u, double v, double point[3], double du[3],
                      double dv[3], double d2[9])
{
    const int pu = s->degree_u, pv = s->degree_v;
    int nd = d2 ? 2 : (du || dv) ? 1 : 0;
    double Nu[3 * (SEM_MAX_DEGREE + 1)], Nv[3 * (SEM_MAX_DEGREE + 1)];
    int su = sem_bspline_span(pu, s->n_u, s->knots_u, u);
    int sv = sem_bspline_span(pv, s->n_v, s->knots_v, v);
    sem_bspline_basis(pu, s->knots_u, su, u, nd, Nu);
    sem_bspline_basis(pv, s->knots_v, sv, v, nd, Nv);

    /* H[a][b] = d^a/du^a d^b/dv^b of (wx, wy, wz, w), a + b <= 2 */
    double H[3][3][4];
    memset(H, 0, sizeof H);
    for (int l = 0; l <= pv; ++l) {
        int j = sv - pv + l;
        double tmp[3][4];
        memset(tmp, 0, sizeof tmp);
        for (int k = 0; k <= pu; ++k) {
            int i = su - pu + k;
            size_t idx = (size_t)i + (size_t)s->n_u * (size_t)j;
            double w = s->weights[idx];
            const double *P = s->ctrl + 3 * idx;
            double hw[4] = {w * P[0], w * P[1], w * P[2], w};
            for (int a = 0; a <= nd; ++a) {
                double b = Nu[a * (pu + 1) + k];
                for (int c = 0; c < 4; ++c) tmp[a][c] += b * hw[c];
            }
        }
        for (int a = 0; a <= nd; ++a)
            for (int b = 0; a + b <= nd; ++b) {
                double nv = Nv[b * (pv + 1) + l];
                for (int c = 0; c < 4; ++c) H[a][b][c] += nv * tmp[a][c];
            }
    }
    double w = H[0][0][3];
    double S[3][3][3]; /* derivatives of the rational point */
    for (int a = 0; a <= nd; ++a)
        for (int b = 0; a + b <= nd; ++b)
            for (int c = 0; c < 3; ++c) {
                double v_ = H[a][b][c];
                /* subtract binomial terms (A4.4) */
                for (int j = 1; j <= b; ++j) v_ -= (b == 2 && j == 1 ? 2.0 : 1.0) * H[0][j][3] * S[a][b - j][c];
                for (int i = 1; i <= a; ++i) {
                    double bi = (a == 2 && i == 1) ? 2.0 : 1.0;
                    v_ -= bi * H[i][0][3] * S[a - i][b][c];
                    for (int j = 1; j <= b; ++j) {
                        double bj = (b == 2 && j == 1) ? 2.0 : 1.0;
                        v_ -= bi * bj * H[i][j][3] * S[a - i][b - j][c];
                    }
                }
                S[a][b][c] = v_ / w;
            }
    if (point) memcpy(point, S[0][0], 3 * sizeof(double));
    if (du) memcpy(du, S[1][0], 3 * sizeof(double));
    if (dv) memcpy(dv, S[0][1], 3 * sizeof(double));
    if (d2) {
        memcpy(d2, S[2][0], 3 * sizeof(double));
        memcpy(d2 + 3, S[1][1], 3 * sizeof(double));
        memcpy(d2 + 6, S[0][2], 3 * sizeof(double));
    }
}

int sem_surface_basis(const sem_surface *s, double u, double v, int *index, double *phi,
                      double *phi_u, double *phi_v)
{
    const int pu = s->degree_u, pv = s->degree_v;
    int nd = (phi_u || phi_v) ? 1 : 0;
    double Nu[2 * (SEM_MAX_DEGREE + 1)], Nv[2 * (SEM_MAX_DEGREE + 1)];
    int su = sem_bspline_span(pu, s->n_u, s->knots_u, u);
    int sv = sem_bspline_span(pv, s->n_v, s->knots_v, v);
    sem_bspline_basis(pu, s->knots_u, su, u, nd, Nu);
    sem_bspline_basis(pv, s->knots_v, sv, v, nd, Nv);
    return sem_surface_basis_from_spans(s, su, Nu, sv, Nv, index, phi, phi_u, phi_v);
}

int sem_surface_basis_from_spans(const sem_surface *s, int su, const double *Nu, int sv,
                                 const double *Nv, int *index, double *phi, double *phi_u,
                                 double *phi_v)
{
    const int pu = s->degree_u, pv = s->degree_v;
    int nd = (phi_u || phi_v) ? 1 : 0;
    double W = 0, Wu = 0, Wv = 0;
    int n = 0;
    for (int l = 0; l <= pv; ++l) {
        int j = sv - pv + l;
        for (int k = 0; k <= pu; ++k) {
            int i = su - pu + k;
            int idx = i + s->n_u * j;
            double w = s->weights[idx];
            double b = w * Nu[k] * Nv[l];
            index[n] = idx;
            phi[n] = b;
            W += b;
            if (nd) {
                double bu = w * Nu[(pu + 1) + k] * Nv[l];
                double bv = w * Nu[k] * Nv[(pv + 1) + l];
                if (phi_u) phi_u[n] = bu;
                if (phi_v) phi_v[n] = bv;
                Wu += bu;
                Wv += bv;
            }
            ++n;
        }
    }
    /* phi = b / W, phi_u = (b_u W - b W_u) / W^2 */
    for (int k = 0; k < n; ++k) {
        double b = phi[k];
        phi[k] = b / W;
        if (phi_u) phi_u[k] = (phi_u[k] - phi[k] * Wu) / W;
        if (phi_v) phi_v[k] = (phi_v[k] - phi[k] * Wv) / W;
    }
    return n;
}

static double cross_norm(const double a[3], const double b[3], double n[3])
{
    n[0] = a[1] * b[2] - a[2] * b[1];
    n[1] = a[2] * b[0] - a[0] * b[2];
    n[2] = a[0] * b[1] - a[1] * b[0];
    return sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

double sem_surface_normal(const sem_surface *s, double u, double v, double normal[3])
{
    double du[3], dv[3], n[3];
    sem_surface_eval(s, u, v, NULL, du, dv, NULL);
    double len = cross_norm(du, dv, n);
    double scale = sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]) *
                   sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
    double area = len;
    if (!(len > 1e-12 * scale) || len == 0.0) {
        /* Collapsed edge (e.g. a sphere's pole): take the normal a short step inside the
         * domain, which converges to the limit normal there. */
        double hu = 1e-6 * (s->u1 - s->u0), hv = 1e-6 * (s->v1 - s->v0);
        double uu = u + (u - s->u0 < s->u1 - u ? hu : -hu);
        double vv = v + (v - s->v0 < s->v1 - v ? hv : -hv);
        sem_surface_eval(s, uu, vv, NULL, du, dv, NULL);
        len = cross_norm(du, dv, n);
    }
    if (len > 0.0) {
        normal[0] = n[0] / len;
        normal[1] = n[1] / len;
        normal[2] = n[2] / len;
    } else {
        normal[0] = normal[1] = 0.0;
        normal[2] = 1.0;
    }
    return area;
}

void sem_curve_eval(const sem_curve *c, double t, double point[3], double d1[3])
{
    const int p = c->degree;
    double N[2 * (SEM_MAX_DEGREE + 1)];
    int span = sem_bspline_span(p, c->n_ctrl, c->knots, t);
    int nd = d1 ? 1 : 0;
    sem_bspline_basis(p, c->knots, span, t, nd, N);
    double A[4] = {0, 0, 0, 0}, Ad[4] = {0, 0, 0, 0};
    for (int k = 0; k <= p; ++k) {
        int i = span - p + k;
        double w = c->weights[i];
        const double *P = c->ctrl + 3 * i;
        for (int d = 0; d < 3; ++d) A[d] += N[k] * w * P[d];
        A[3] += N[k] * w;
        if (nd) {
            for (int d = 0; d < 3; ++d) Ad[d] += N[p + 1 + k] * w * P[d];
            Ad[3] += N[p + 1 + k] * w;
        }
    }
    for (int d = 0; d < 3; ++d) {
        double x = A[d] / A[3];
        if (point) point[d] = x;
        if (d1) d1[d] = (Ad[d] - x * Ad[3]) / A[3];
    }
}

/* Legendre polynomial P_n and derivative at x by the three-term recurrence. */
static void legendre(int n, double x, double *p, double *dp)
{
    double p0 = 1.0, p1 = x;
    if (n == 0) {
        *p = 1.0;
        *dp = 0.0;
        return;
    }
    for (int k = 2; k <= n; ++k) {
        double pk = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = pk;
    }
    *p = p1;
    *dp = n * (x * p1 - p0) / (x * x - 1.0);
}

void sem_gauss_legendre(int n, double *x, double *w)
{
    for (int i = 0; i < (n + 1) / 2; ++i) {
        double z = cos(M_PI * (i + 0.75) / (n + 0.5)), p, dp;
        for (int it = 0; it < 100; ++it) {
            legendre(n, z, &p, &dp);
            double dz = p / dp;
            z -= dz;
            if (fabs(dz) < 1e-16) break;
        }
        legendre(n, z, &p, &dp);
        x[i] = -z;
        x[n - 1 - i] = z;
        w[i] = w[n - 1 - i] = 2.0 / ((1.0 - z * z) * dp * dp);
    }
}

void sem_gauss_lobatto(int n, double *x, double *w)
{
    /* end points plus the roots of P'_{n-1}; weights 2 / (n(n-1) P_{n-1}(x)^2) */
    int m = n - 1;
    x[0] = -1.0;
    x[m] = 1.0;
    w[0] = w[m] = 2.0 / (n * (n - 1.0));
    for (int i = 1; i <= (m) / 2; ++i) {
        /* initial guess: Chebyshev-Gauss-Lobatto nodes */
        double z = -cos(M_PI * i / m);
        for (int it = 0; it < 100; ++it) {
            /* Newton on (1-z^2) P'_m(z): use P_m'' from the Legendre ODE */
            double p, dp;
            legendre(m, z, &p, &dp);
            double d2p = (2.0 * z * dp - m * (m + 1.0) * p) / (1.0 - z * z);
            double dz = dp / d2p;
            z -= dz;
            if (fabs(dz) < 1e-16) break;
        }
        double p, dp;
        legendre(m, z, &p, &dp);
        x[i] = z;
        x[m - i] = -z;
        w[i] = w[m - i] = 2.0 / (n * (n - 1.0) * p * p);
    }
    if (n % 2 == 1) {
        double p, dp;
        legendre(m, 0.0, &p, &dp);
        x[m / 2] = 0.0;
        w[m / 2] = 2.0 / (n * (n - 1.0) * p * p);
    }
}

int sem_knot_breaks(int degree, int n_ctrl, const double *knots, double t0, double t1,
                    double *breaks, int max_breaks)
{
    int n = 0;
    if (max_breaks < 2) return 0;
    breaks[n++] = t0;
    for (int i = degree + 1; i < n_ctrl; ++i) {
        double k = knots[i];
        if (k > t0 && k < t1 && k > breaks[n - 1]) {
            if (n >= max_breaks - 1) break;
            breaks[n++] = k;
        }
    }
    breaks[n++] = t1;
    return n;
}
