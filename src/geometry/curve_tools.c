/*
 * curve_tools.c - exact operations on NURBS curves (see curve_tools.h): knot insertion,
 * degree elevation, reparameterization to [0, 1], and making two curves share degree and knots
 * (a ruled surface's rails). Piegl & Tiller, The NURBS Book, A5.1 and section 5.5.
 */
#include "curve_tools.h"
#include "util/free_all.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Inserts knot t (strictly inside the knot range) `times` times, clamped so that its
 * multiplicity stays <= degree (Piegl & Tiller A5.1, in homogeneous coordinates). */
sem_status sem_curve_insert_knot(sem_curve *c, double t, int times)
{
    int p = c->degree, n = c->n_ctrl;
    const double *U = c->knots;
    int k = sem_bspline_span(p, n, U, t);
    while (k < n - 1 && U[k + 1] <= t) ++k;
    int s = 0;
    for (int i = 0; i < n + p + 1; ++i)
        if (U[i] == t) s++;
    if (times + s > p) times = p - s;
    if (times <= 0) return SEM_OK;
    int nq = n + times;
    double *UQ = malloc((size_t)(nq + p + 1) * sizeof *UQ);
    double *Qw = malloc((size_t)nq * 4 * sizeof *Qw);
    double *Pw = malloc((size_t)n * 4 * sizeof *Pw);
    double Rw[4 * (SEM_MAX_DEGREE + 1)];
    if (!UQ || !Qw || !Pw) {
        free(UQ);
        free(Qw);
        free(Pw);
        return SEM_ERR_NOMEM;
    }
    for (int i = 0; i < n; ++i) {
        double w = c->weights[i];
        for (int d = 0; d < 3; ++d) Pw[4 * i + d] = c->ctrl[3 * i + d] * w;
        Pw[4 * i + 3] = w;
    }
    for (int i = 0; i <= k; ++i) UQ[i] = U[i];
    for (int i = 1; i <= times; ++i) UQ[k + i] = t;
    for (int i = k + 1; i <= n + p; ++i) UQ[i + times] = U[i];
    for (int i = 0; i <= k - p; ++i) memcpy(Qw + 4 * i, Pw + 4 * i, 4 * sizeof(double));
    for (int i = k - s; i <= n - 1; ++i)
        memcpy(Qw + 4 * (i + times), Pw + 4 * i, 4 * sizeof(double));
    for (int i = 0; i <= p - s; ++i) memcpy(Rw + 4 * i, Pw + 4 * (k - p + i), 4 * sizeof(double));
    int L = 0;
    for (int j = 1; j <= times; ++j) {
        L = k - p + j;
        for (int i = 0; i <= p - j - s; ++i) {
            double alpha = (t - U[L + i]) / (U[i + k + 1] - U[L + i]);
            for (int d = 0; d < 4; ++d)
                Rw[4 * i + d] = alpha * Rw[4 * (i + 1) + d] + (1.0 - alpha) * Rw[4 * i + d];
        }
        memcpy(Qw + 4 * L, Rw, 4 * sizeof(double));
        memcpy(Qw + 4 * (k + times - j - s), Rw + 4 * (p - j - s), 4 * sizeof(double));
    }
    for (int i = L + 1; i < k - s; ++i) memcpy(Qw + 4 * i, Rw + 4 * (i - L), 4 * sizeof(double));
    double *ctrl = malloc((size_t)nq * 3 * sizeof *ctrl), *w = malloc((size_t)nq * sizeof *w);
    if (!ctrl || !w) {
        SEM_FREE_ALL(ctrl, w, UQ, Qw, Pw);
        return SEM_ERR_NOMEM;
    }
    for (int i = 0; i < nq; ++i) {
        w[i] = Qw[4 * i + 3];
        for (int d = 0; d < 3; ++d) ctrl[3 * i + d] = Qw[4 * i + d] / w[i];
    }
    SEM_FREE_ALL(c->knots, c->ctrl, c->weights, Qw, Pw);
    c->knots = UQ;
    c->ctrl = ctrl;
    c->weights = w;
    c->n_ctrl = nq;
    return SEM_OK;
}

int sem_curve_is_clamped(const sem_curve *c)
{
    int p = c->degree, m = c->n_ctrl + p + 1;
    for (int i = 1; i <= p; ++i)
        if (c->knots[i] != c->knots[0] || c->knots[m - 1 - i] != c->knots[m - 1]) return 0;
    return 1;
}

/* Raises a clamped curve to degree q exactly: split into Bezier pieces by knot insertion,
 * raise each piece (Q_i = i/(p+1) P_{i-1} + (1 - i/(p+1)) P_i in homogeneous form), and
 * join them again with interior knots of multiplicity q. */
sem_status sem_curve_elevate(sem_curve *c, int q)
{
    int p = c->degree;
    if (q <= p) return SEM_OK;
    for (int i = p + 1; i < c->n_ctrl; ++i) {
        double t = c->knots[i];
        if (t > c->knots[p] && t < c->knots[c->n_ctrl] && (i == p + 1 || t != c->knots[i - 1])) {
            sem_status st = sem_curve_insert_knot(c, t, p);
            if (st != SEM_OK) return st;
        }
    }
    int nseg = 0;
    for (int i = p + 1; i < c->n_ctrl + p + 1; ++i) nseg += c->knots[i] != c->knots[i - 1];
    if (nseg < 1 || c->n_ctrl != nseg * p + 1) return SEM_ERR_INVALID; /* a break of mult. p+1 */
    double *breaks = malloc((size_t)(nseg + 1) * sizeof *breaks);
    double *hw = malloc((size_t)(nseg * q + 1) * 4 * sizeof *hw);
    if (!breaks || !hw) {
        free(breaks);
        free(hw);
        return SEM_ERR_NOMEM;
    }
    int nb = 0;
    breaks[nb++] = c->knots[0];
    for (int i = p + 1; i < c->n_ctrl + p + 1 && nb <= nseg; ++i)
        if (c->knots[i] != breaks[nb - 1]) breaks[nb++] = c->knots[i];
    for (int sgm = 0; sgm < nseg; ++sgm) {
        double b[4 * (SEM_MAX_DEGREE + 1)], e[4 * (SEM_MAX_DEGREE + 1)];
        for (int i = 0; i <= p; ++i) {
            const double *P = c->ctrl + 3 * (sgm * p + i);
            double w = c->weights[sgm * p + i];
            b[4 * i] = P[0] * w;
            b[4 * i + 1] = P[1] * w;
            b[4 * i + 2] = P[2] * w;
            b[4 * i + 3] = w;
        }
        for (int d = p; d < q; ++d) {
            memcpy(e, b, 4 * sizeof(double));
            for (int i = 1; i <= d; ++i) {
                double a = (double)i / (d + 1);
                for (int k = 0; k < 4; ++k)
                    e[4 * i + k] = a * b[4 * (i - 1) + k] + (1 - a) * b[4 * i + k];
            }
            memcpy(e + 4 * (d + 1), b + 4 * d, 4 * sizeof(double));
            memcpy(b, e, (size_t)(d + 2) * 4 * sizeof(double));
        }
        memcpy(hw + 4 * (size_t)(sgm * q), b, (size_t)(q + 1) * 4 * sizeof(double));
    }
    sem_curve out;
    double t0 = c->t0, t1 = c->t1;
    if (sem_curve_alloc(&out, q, nseg * q + 1) != SEM_OK) {
        free(breaks);
        free(hw);
        return SEM_ERR_NOMEM;
    }
    int m = 0;
    for (int i = 0; i <= q; ++i) out.knots[m++] = breaks[0];
    for (int sgm = 1; sgm < nseg; ++sgm)
        for (int i = 0; i < q; ++i) out.knots[m++] = breaks[sgm];
    for (int i = 0; i <= q; ++i) out.knots[m++] = breaks[nb - 1];
    for (int i = 0; i < out.n_ctrl; ++i) {
        out.weights[i] = hw[4 * i + 3];
        for (int d = 0; d < 3; ++d) out.ctrl[3 * i + d] = hw[4 * i + d] / out.weights[i];
    }
    out.t0 = t0;
    out.t1 = t1;
    free(breaks);
    free(hw);
    sem_curve_free(c);
    *c = out;
    return SEM_OK;
}

/* Affine change of parameter so that the knot range becomes [0, 1]. */
void sem_curve_normalize(sem_curve *c)
{
    int m = c->n_ctrl + c->degree + 1;
    double a = c->knots[0], b = c->knots[m - 1];
    if (a == 0.0 && b == 1.0) return;
    for (int i = 0; i < m; ++i) c->knots[i] = i == m - 1 ? 1.0 : (c->knots[i] - a) / (b - a);
    c->t0 = (c->t0 - a) / (b - a);
    c->t1 = (c->t1 - a) / (b - a);
}

/* Makes two clamped curves on [0,1] share degree and knot vector (exactly). */
sem_status sem_curves_make_compatible(sem_curve *a, sem_curve *b)
{
    int q = a->degree > b->degree ? a->degree : b->degree;
    sem_status st = sem_curve_elevate(a, q);
    if (st == SEM_OK) st = sem_curve_elevate(b, q);
    if (st != SEM_OK) return st;
    for (int pass = 0; pass < 2; ++pass) {
        sem_curve *from = pass ? b : a, *to = pass ? a : b;
        int m = from->n_ctrl + q + 1;
        for (int i = q + 1; i < m - q - 1; ++i) {
            double t = from->knots[i];
            if (i > q + 1 && t == from->knots[i - 1]) continue;
            int mf = 0, mt = 0;
            for (int j = 0; j < m; ++j) mf += from->knots[j] == t;
            for (int j = 0; j < to->n_ctrl + q + 1; ++j) mt += to->knots[j] == t;
            if (mf > mt) {
                st = sem_curve_insert_knot(to, t, mf - mt);
                if (st != SEM_OK) return st;
            }
        }
    }
    return SEM_OK;
}
