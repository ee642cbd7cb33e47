/*
 * projection.c - the hierarchical shape-matching projection Pi (paper Sec. 6, Eq. 7, Fig. 3).
 *
 * What is computed. Part i, assigned to deformation origin j (rest position Xbar_j), gets
 * the polynomial x(X) = b(X - Xbar_j)^T C_i with b = [1, dX, dY, dZ, dXdY, dXdZ, dYdZ, dX^2,
 * dY^2, dZ^2] (sem/preprocess.h) and C_i = Pi_i Q, fitted order by order over the boundary
 * samples s (rest X_s, area a_s, current x_s = J_s Q):
 *   t_j  = sum_{s in G_j} a_s J_s Q / sum_{s in G_j} a_s     (G_j: all parts of origin j)
 *   c1_i = argmin sum_{s in i} a_s |p_s^T c - (J_s Q - t_j)|^2,            p_s = X_s - Xbar_j
 *   c2_i = argmin sum_{s in i} a_s |r_s^T c - (J_s Q - t_j - p_s^T c1_i)|^2,
 *          r_s = [dXdY, dXdZ, dYdZ, dX^2, dY^2, dZ^2](p_s)
 * Each fit is linear in Q and the same for x, y and z, so Pi is a scalar matrix with
 * n_parts * m rows; the rows of part i only reach the control points of the parts of its
 * group (t_j couples them), which makes Pi sparse (Pi = U^-1 B of the paper, block
 * triangular per group). Row i*m + 0 is t_j (repeated for every part of the group).
 *
 * Consistency of the origin. The fitted map must give x(Xbar_j) = t_j for every motion, in
 * particular at rest, so Xbar_j must be the area-weighted rest centroid of the group's
 * samples (as the origins step defines it). We check this (relative 1e-9) and refuse an
 * inconsistent origin rather than silently breaking the patch test.
 *
 * Ill-posed fits. A planar part whose origin lies in its own plane has P1^T S P1 singular
 * (no sample moves the fit along the normal); the quadratic normal matrix is singular for
 * planar parts and for parts lying on a quadric through the origin. We detect this from the
 * eigenvalues of the small (3 x 3 or 6 x 6) normal matrix N_i, computed after scaling dX by
 * the group's sample spread L_j (so N is O(1) and the threshold is scale free): directions
 * with eigenvalue <= 1e-8 x the largest are "null" directions Z of the part (1e-8: a nearly
 * flat part then amplifies round-off by at most ~1e8, so the patch test stays exact to ~1e-8).
 * In the null directions the coefficients are taken from the group's fit: with N_G and
 * rhs_G the same normal matrix and right-hand side assembled over the samples of all parts
 * of origin j (part i included, residuals taken against part i's lower-order fit),
 *   c = N_i^+ rhs_i + Z y,  y = argmin of the group objective  =>  (Z^T N_G Z) y =
 *   Z^T (rhs_G - N_G N_i^+ rhs_i),
 * and if Z^T N_G Z is still singular (the whole group is planar) the remaining directions
 * are dropped (eigen pseudo-inverse: coefficient 0 there, which is harmless, since then no
 * sample of the part can feel that coefficient). Nothing is ever divided by a tiny
 * eigenvalue.
 * Why this keeps the patch test exact: for an affine motion x = A X + b every part's data
 * are exactly polynomial, t_j = A Xbar_j + b, and the exact coefficients c* satisfy both
 * N_i c* = rhs_i and N_G c* = rhs_G. Then N_i^+ rhs_i is the component of c* in the range
 * of N_i and the group equation returns exactly its Z component, so c = c* (order 2: the
 * residual after the exact linear fit is 0, so c2 = 0). We prefer this split to adding
 * lambda N_G to N_i (Tikhonov towards the group fit, also exact for affine motions): the
 * split leaves the well-posed directions of each part untouched for general motions and
 * needs no lambda, whose choice trades bias against conditioning.
 *
 * Shared fits (d->shared_fit, sem_fit_rule). Every part of origin j takes the group's fit:
 * the same order-by-order least squares over the samples of all the group's parts,
 *   c1_G = N1_G^+ R1_G,   c2_G = N2_G^+ (B2_G - M21_G c1_G),
 * (pseudo-inverses as above: a group whose samples are flat gets 0 in its null directions).
 * Each part computes them itself from the group's sums alone, so the rows of the parts of one
 * origin are equal bit for bit (the structured solver merges equal rows: its coefficient space
 * is then origins x m). The patch test holds as for parts: affine data are fitted exactly.
 *
 * The eigenvalues come from a cyclic Jacobi sweep written here rather than LAPACK dsyev:
 * the matrices are at most 6 x 6, the sweep is accurate for small eigenvalues, and it keeps
 * OpenBLAS (pthread build) out of the OpenMP loops.
 *
 * Threads: per-part sums and per-part solves are independent (each part writes its own
 * rows of Pi, whose layout is fixed in advance); the group sums are formed serially in part
 * order, so the result does not depend on the thread count.
 */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "steps.h"
#include "util/free_all.h"
#include "util/threads.h"

/* Relative eigenvalue threshold below which a fit direction counts as undetermined. */
#define SEM_PROJECTION_NULL_TOL 1e-8
/* Relative tolerance on |Xbar_j - rest centroid of group j| (see the opening comment). */
#define SEM_PROJECTION_ORIGIN_TOL 1e-9

enum { N1 = 3, N2 = 6 };

/* ---- small symmetric eigen problems (k <= 6) ---- */

/* Cyclic Jacobi: A (k x k symmetric, row-major) -> eigenvalues w[k] and eigenvectors as the
 * columns of V (V[r*k + c] = component r of vector c). A is destroyed. */
static void jacobi_eigen(int k, double *A, double *w, double *V)
{
    for (int r = 0; r < k; ++r)
        for (int c = 0; c < k; ++c) V[r * k + c] = r == c ? 1.0 : 0.0;
    for (int sweep = 0; sweep < 100; ++sweep) {
        double off = 0.0, diag = 0.0;
        for (int r = 0; r < k; ++r) {
            diag += A[r * k + r] * A[r * k + r];
            for (int c = r + 1; c < k; ++c) off += A[r * k + c] * A[r * k + c];
        }
        if (off <= 1e-34 * diag || off == 0.0) break;
        for (int p = 0; p < k; ++p)
            for (int q = p + 1; q < k; ++q) {
                double apq = A[p * k + q];
                if (apq == 0.0) continue;
                double theta = (A[q * k + q] - A[p * k + p]) / (2.0 * apq);
                double t = (theta >= 0 ? 1.0 : -1.0) / (fabs(theta) + sqrt(theta * theta + 1.0));
                double c = 1.0 / sqrt(t * t + 1.0), s = t * c;
                for (int r = 0; r < k; ++r) { /* columns p, q */
                    double arp = A[r * k + p], arq = A[r * k + q];
                    A[r * k + p] = c * arp - s * arq;
                    A[r * k + q] = s * arp + c * arq;
                }
                for (int r = 0; r < k; ++r) { /* rows p, q */
                    double apr = A[p * k + r], aqr = A[q * k + r];
                    A[p * k + r] = c * apr - s * aqr;
                    A[q * k + r] = s * apr + c * aqr;
                }
                for (int r = 0; r < k; ++r) {
                    double vrp = V[r * k + p], vrq = V[r * k + q];
                    V[r * k + p] = c * vrp - s * vrq;
                    V[r * k + q] = s * vrp + c * vrq;
                }
            }
    }
    for (int r = 0; r < k; ++r) w[r] = A[r * k + r];
}

/* K_own, K_group (k x k) with c = K_own rhs_own + K_group rhs_group, as derived in the
 * opening comment. Returns the number of null directions of N_own that the group could not
 * determine either (0 when the fit is fully determined). */
static int robust_inverse(int k, const double *N_own, const double *N_group, double *K_own,
                          double *K_group)
{
    double A[N2 * N2], V[N2 * N2], w[N2];
    memcpy(A, N_own, (size_t)(k * k) * sizeof *A);
    jacobi_eigen(k, A, w, V);
    double wmax = 0.0;
    for (int c = 0; c < k; ++c) wmax = fmax(wmax, w[c]);
    int range[N2], null_dirs[N2], n_range = 0, n_null = 0;
    for (int c = 0; c < k; ++c) {
        if (wmax > 0.0 && w[c] > SEM_PROJECTION_NULL_TOL * wmax) range[n_range++] = c;
        else null_dirs[n_null++] = c;
    }
    /* N_own^+ */
    double Ninv[N2 * N2];
    for (int r = 0; r < k; ++r)
        for (int s = 0; s < k; ++s) {
            double sum = 0.0;
            for (int a = 0; a < n_range; ++a) {
                int c = range[a];
                sum += V[r * k + c] * V[s * k + c] / w[c];
            }
            Ninv[r * k + s] = sum;
        }
    memcpy(K_own, Ninv, (size_t)(k * k) * sizeof *K_own);
    memset(K_group, 0, (size_t)(k * k) * sizeof *K_group);
    if (n_null == 0) return 0;

    /* G = Z^T N_group Z and its pseudo-inverse, threshold relative to N_group's scale */
    double G[N2 * N2], U[N2 * N2], g[N2], scale = 0.0;
    for (int r = 0; r < k; ++r) scale = fmax(scale, N_group[r * k + r]);
    for (int a = 0; a < n_null; ++a)
        for (int b = 0; b < n_null; ++b) {
            double sum = 0.0;
            for (int r = 0; r < k; ++r)
                for (int s = 0; s < k; ++s)
                    sum += V[r * k + null_dirs[a]] * N_group[r * k + s] * V[s * k + null_dirs[b]];
            G[a * n_null + b] = sum;
        }
    jacobi_eigen(n_null, G, g, U);
    /* Ginv (n_null x n_null) */
    double Ginv[N2 * N2];
    int undetermined = 0;
    memset(Ginv, 0, sizeof Ginv);
    for (int c = 0; c < n_null; ++c) {
        if (!(scale > 0.0 && g[c] > SEM_PROJECTION_NULL_TOL * scale)) {
            ++undetermined;
            continue;
        }
        for (int a = 0; a < n_null; ++a)
            for (int b = 0; b < n_null; ++b)
                Ginv[a * n_null + b] += U[a * n_null + c] * U[b * n_null + c] / g[c];
    }
    /* K_group = Z Ginv Z^T */
    for (int r = 0; r < k; ++r)
        for (int s = 0; s < k; ++s) {
            double sum = 0.0;
            for (int a = 0; a < n_null; ++a)
                for (int b = 0; b < n_null; ++b)
                    sum += V[r * k + null_dirs[a]] * Ginv[a * n_null + b] * V[s * k + null_dirs[b]];
            K_group[r * k + s] = sum;
        }
    /* K_own = Ninv - K_group N_group Ninv */
    double T[N2 * N2];
    for (int r = 0; r < k; ++r)
        for (int s = 0; s < k; ++s) {
            double sum = 0.0;
            for (int a = 0; a < k; ++a) sum += N_group[r * k + a] * Ninv[a * k + s];
            T[r * k + s] = sum;
        }
    for (int r = 0; r < k; ++r)
        for (int s = 0; s < k; ++s) {
            double sum = 0.0;
            for (int a = 0; a < k; ++a) sum += K_group[r * k + a] * T[a * k + s];
            K_own[r * k + s] = Ninv[r * k + s] - sum;
        }
    return undetermined;
}

/* ---- per-part and per-group sums ---- */

/* Quadratic terms of a (scaled) offset p, in the basis order of sem/preprocess.h. */
static void quadratic_terms(const double p[3], double r[N2])
{
    r[0] = p[0] * p[1];
    r[1] = p[0] * p[2];
    r[2] = p[1] * p[2];
    r[3] = p[0] * p[0];
    r[4] = p[1] * p[1];
    r[5] = p[2] * p[2];
}

/* Area-weighted moments of one part's samples about its group's origin, dX scaled by 1/L.
 * Rows of J are kept compact over the part's own control points. */
typedef struct part_sums {
    double area, centroid_sum[3], spread_sum; /* rest moments (spread: sum a |X - Xbar|^2) */
    int n_samples;
    double floor;     /* 5 % of the mean sample area: the fit weights' floor (group floored) */
    double *T;  /* n_ctrl_i: sum a J */
    double *S1; /* 3 x n_ctrl_i: sum a p J */
    double *S2; /* 6 x n_ctrl_i: sum a r J (order 2) */
    double m1[N1], m2[N2];           /* sum a p, sum a r */
    double N1m[N1 * N1], N2m[N2 * N2]; /* sum a p p^T, sum a r r^T */
    double M21[N2 * N1];             /* sum a r p^T */
} part_sums;

typedef struct group {
    int n_parts;
    int *parts;       /* ascending */
    int n_cols;       /* control points of its parts */
    double L;         /* length scale of dX */
    double area;
    double *t;        /* n_cols */
    double *R1;       /* 3 x n_cols: sum over the group of a p (J - t) */
    double *B2;       /* 6 x n_cols: sum over the group of a r (J - t) */
    double N1m[N1 * N1], N2m[N2 * N2], M21[N2 * N1];
    int floored;      /* the fits weigh each sample at least its part's floor (see below) */
} group;

typedef struct context {
    const sem_discretization *d;
    int order, m;
    int shared;        /* shared fits: every part takes its group's fit */
    int *sample_start; /* n_parts + 1 */
    int *sample_index; /* samples of each part, in sample order */
    int *group_col0;   /* per part: first column of the part inside its group's columns */
    part_sums *sums;
    group *groups;
} context;

static void part_rest_moments(const context *cx, int i)
{
    const sem_discretization *d = cx->d;
    part_sums *ps = &cx->sums[i];
    const double *Xbar = d->origin_X + 3 * (size_t)d->part_origin[i];
    for (int k = cx->sample_start[i]; k < cx->sample_start[i + 1]; ++k) {
        int s = cx->sample_index[k];
        double a = d->sample_area[s];
        const double *X = d->sample_X + 3 * (size_t)s;
        ps->area += a;
        double r2 = 0.0;
        for (int e = 0; e < 3; ++e) {
            ps->centroid_sum[e] += a * X[e];
            r2 += (X[e] - Xbar[e]) * (X[e] - Xbar[e]);
        }
        ps->spread_sum += a * r2;
        ps->n_samples++;
    }
    ps->floor = ps->n_samples > 0 ? 0.05 * ps->area / ps->n_samples : 0.0;
}

/* Degenerate weights. The samples where a surface collapses (a cone's apex, a pole) have no
 * area, so a part whose other samples are flat fits as if it were flat: a cone with a straight
 * generatrix has its Lobatto points on the base circle and at the apex only (corpus
 * occt_cone_catia), its group's linear fit had no z direction, F was singular at rest and the
 * run ended "element inverted" before its first step. Such a group (its area-weighted samples
 * flat, the same samples with the error rows' 5 % floor on each weight not) weighs each
 * sample at least that floor in its fits; the centroid t_j keeps the areas, and since any
 * weights fit affine motions exactly the patch test is unchanged. Groups whose samples span
 * 3D as they are (every shared model) are untouched. */
static void decide_floored(const context *cx, int j)
{
    const sem_discretization *d = cx->d;
    group *g = &cx->groups[j];
    const double *Xbar = d->origin_X + 3 * (size_t)j;
    double raw[9] = {0}, fl[9] = {0};
    for (int a = 0; a < g->n_parts; ++a) {
        int i = g->parts[a];
        for (int k = cx->sample_start[i]; k < cx->sample_start[i + 1]; ++k) {
            int s = cx->sample_index[k];
            double w = d->sample_area[s], wf = fmax(w, cx->sums[i].floor);
            const double *X = d->sample_X + 3 * (size_t)s;
            double p[3] = {(X[0] - Xbar[0]) / g->L, (X[1] - Xbar[1]) / g->L, (X[2] - Xbar[2]) / g->L};
            for (int e = 0; e < 3; ++e)
                for (int f = 0; f < 3; ++f) {
                    raw[e * 3 + f] += w * p[e] * p[f];
                    fl[e * 3 + f] += wf * p[e] * p[f];
                }
        }
    }
    double V[9], wr[3], wf[3];
    jacobi_eigen(3, raw, wr, V);
    jacobi_eigen(3, fl, wf, V);
    double rmax = fmax(fmax(wr[0], wr[1]), wr[2]), rmin = fmin(fmin(wr[0], wr[1]), wr[2]);
    double fmax_ = fmax(fmax(wf[0], wf[1]), wf[2]), fmin_ = fmin(fmin(wf[0], wf[1]), wf[2]);
    g->floored = !(rmin > SEM_PROJECTION_NULL_TOL * rmax) && fmin_ > SEM_PROJECTION_NULL_TOL * fmax_;
}

static void part_fit_moments(const context *cx, int i)
{
    const sem_discretization *d = cx->d;
    part_sums *ps = &cx->sums[i];
    const int j = d->part_origin[i];
    const double *Xbar = d->origin_X + 3 * (size_t)j;
    const double invL = 1.0 / cx->groups[j].L;
    const int off = d->part_ctrl_offset[i];
    const int nc = d->part_ctrl_offset[i + 1] - off;
    const int floored = cx->groups[j].floored;
    for (int k = cx->sample_start[i]; k < cx->sample_start[i + 1]; ++k) {
        int s = cx->sample_index[k];
        /* t_j's sums keep the area (a0); the fits' weigh a (decide_floored) */
        double a0 = d->sample_area[s], a = floored ? fmax(a0, ps->floor) : a0;
        const double *X = d->sample_X + 3 * (size_t)s;
        double p[3] = {(X[0] - Xbar[0]) * invL, (X[1] - Xbar[1]) * invL, (X[2] - Xbar[2]) * invL};
        double r[N2];
        quadratic_terms(p, r);
        for (int e = 0; e < N1; ++e) {
            ps->m1[e] += a * p[e];
            for (int f = 0; f < N1; ++f) ps->N1m[e * N1 + f] += a * p[e] * p[f];
        }
        if (cx->order == 2)
            for (int e = 0; e < N2; ++e) {
                ps->m2[e] += a * r[e];
                for (int f = 0; f < N2; ++f) ps->N2m[e * N2 + f] += a * r[e] * r[f];
                for (int f = 0; f < N1; ++f) ps->M21[e * N1 + f] += a * r[e] * p[f];
            }
        for (int q = d->J_hat.row_start[s]; q < d->J_hat.row_start[s + 1]; ++q) {
            int c = d->J_hat.col[q] - off; /* checked to lie in [0, nc) beforehand */
            double aj = a * d->J_hat.val[q];
            ps->T[c] += a0 * d->J_hat.val[q];
            for (int e = 0; e < N1; ++e) ps->S1[(size_t)e * nc + c] += aj * p[e];
            if (cx->order == 2)
                for (int e = 0; e < N2; ++e) ps->S2[(size_t)e * nc + c] += aj * r[e];
        }
    }
}

/* Group sums (serial, in part order): t_j, and the group right-hand sides. */
static sem_status group_sums(const context *cx, int j)
{
    const sem_discretization *d = cx->d;
    group *g = &cx->groups[j];
    size_t nc = (size_t)g->n_cols;
    g->t = calloc(nc ? nc : 1, sizeof *g->t);
    g->R1 = calloc(N1 * (nc ? nc : 1), sizeof *g->R1);
    g->B2 = cx->order == 2 ? calloc(N2 * (nc ? nc : 1), sizeof *g->B2) : NULL;
    if (!g->t || !g->R1 || (cx->order == 2 && !g->B2)) return SEM_ERR_NOMEM;
    double m1[N1] = {0}, m2[N2] = {0};
    for (int a = 0; a < g->n_parts; ++a) {
        int i = g->parts[a];
        const part_sums *ps = &cx->sums[i];
        int n = d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i], c0 = cx->group_col0[i];
        for (int c = 0; c < n; ++c) {
            g->t[c0 + c] = ps->T[c];
            for (int e = 0; e < N1; ++e) g->R1[e * nc + (size_t)(c0 + c)] = ps->S1[(size_t)e * n + c];
            if (cx->order == 2)
                for (int e = 0; e < N2; ++e)
                    g->B2[e * nc + (size_t)(c0 + c)] = ps->S2[(size_t)e * n + c];
        }
        for (int e = 0; e < N1 * N1; ++e) g->N1m[e] += ps->N1m[e];
        for (int e = 0; e < N2 * N2; ++e) g->N2m[e] += ps->N2m[e];
        for (int e = 0; e < N2 * N1; ++e) g->M21[e] += ps->M21[e];
        for (int e = 0; e < N1; ++e) m1[e] += ps->m1[e];
        for (int e = 0; e < N2; ++e) m2[e] += ps->m2[e];
    }
    if (g->area > 0.0) {
        for (size_t c = 0; c < nc; ++c) g->t[c] /= g->area;
    } else {
        /* No sample area at all in this group (every part trimmed away or degenerate): the
         * mean of its control points still moves rigidly with them. */
        for (size_t c = 0; c < nc; ++c) g->t[c] = 1.0 / (double)nc;
    }
    /* R1 = S1 - m1 t, B2 = S2 - m2 t */
    for (size_t c = 0; c < nc; ++c) {
        for (int e = 0; e < N1; ++e) g->R1[e * nc + c] -= m1[e] * g->t[c];
        if (cx->order == 2)
            for (int e = 0; e < N2; ++e) g->B2[e * nc + c] -= m2[e] * g->t[c];
    }
    return SEM_OK;
}

/* out (k x nc) = K1 (k x k) X1 (k x nc) + K2 X2 */
static void apply_pair(int k, size_t nc, const double *K1, const double *X1, const double *K2,
                       const double *X2, double *out)
{
    for (int r = 0; r < k; ++r) {
        double *o = out + (size_t)r * nc;
        for (size_t c = 0; c < nc; ++c) o[c] = 0.0;
        for (int a = 0; a < k; ++a) {
            double k1 = K1[r * k + a], k2 = K2[r * k + a];
            const double *x1 = X1 + (size_t)a * nc, *x2 = X2 + (size_t)a * nc;
            if (k1 != 0.0)
                for (size_t c = 0; c < nc; ++c) o[c] += k1 * x1[c];
            if (k2 != 0.0)
                for (size_t c = 0; c < nc; ++c) o[c] += k2 * x2[c];
        }
    }
}

/* Solves part i's fits and writes its m rows of Pi (layout fixed by the caller). */
static sem_status part_solve(const context *cx, int i, sem_csr *Pi, const int *group_cols)
{
    const sem_discretization *d = cx->d;
    const part_sums *ps = &cx->sums[i];
    const group *g = &cx->groups[d->part_origin[i]];
    const size_t nc = (size_t)g->n_cols;
    const int n = d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i], c0 = cx->group_col0[i];
    const int k2 = cx->order == 2 ? N2 : 0;
    /* R_own (k x nc) and the solution C (k x nc) for k = 3 then 6 */
    double *R = malloc((size_t)(N1 + k2) * nc * sizeof *R);
    double *C1 = malloc(N1 * nc * sizeof *C1);
    double *C2 = k2 ? malloc(N2 * nc * sizeof *C2) : NULL;
    double *RG = k2 ? malloc(N2 * nc * sizeof *RG) : NULL;
    if (!R || !C1 || (k2 && (!C2 || !RG))) {
        SEM_FREE_ALL(R, C1, C2, RG);
        return SEM_ERR_NOMEM;
    }
    double K_own[N2 * N2], K_group[N2 * N2];

    /* linear terms: rhs_own = S1_i - m1_i t (shared fits: the group's R1) */
    if (cx->shared) {
        memcpy(R, g->R1, N1 * nc * sizeof *R);
    } else {
        for (int e = 0; e < N1; ++e) {
            double *r = R + (size_t)e * nc;
            for (size_t c = 0; c < nc; ++c) r[c] = -ps->m1[e] * g->t[c];
            for (int c = 0; c < n; ++c) r[c0 + c] += ps->S1[(size_t)e * n + c];
        }
    }
    /* shared fits: the group's own pseudo-inverse (a zero "group" leaves its null
     * directions at 0) */
    static const double zero[N2 * N2];
    robust_inverse(N1, cx->shared ? g->N1m : ps->N1m, cx->shared ? zero : g->N1m, K_own, K_group);
    apply_pair(N1, nc, K_own, R, K_group, g->R1, C1);

    if (k2) {
        /* quadratic terms fit the residual of the linear fit:
         * rhs_own = S2_i - m2_i t - M21_i C1, rhs_group = B2_G - M21_G C1 */
        for (int e = 0; e < N2; ++e) {
            double *r = R + (size_t)e * nc, *rg = RG + (size_t)e * nc;
            const double *bg = g->B2 + (size_t)e * nc;
            for (size_t c = 0; c < nc; ++c) {
                double own = -ps->m2[e] * g->t[c], grp = bg[c];
                for (int f = 0; f < N1; ++f) {
                    own -= ps->M21[e * N1 + f] * C1[(size_t)f * nc + c];
                    grp -= g->M21[e * N1 + f] * C1[(size_t)f * nc + c];
                }
                r[c] = cx->shared ? grp : own;
                rg[c] = grp;
            }
            if (!cx->shared)
                for (int c = 0; c < n; ++c) r[c0 + c] += ps->S2[(size_t)e * n + c];
        }
        robust_inverse(N2, cx->shared ? g->N2m : ps->N2m, cx->shared ? zero : g->N2m, K_own,
                       K_group);
        apply_pair(N2, nc, K_own, R, K_group, RG, C2);
    }

    /* rows: t, then c1 / L, then c2 / L^2 (undo the scaling of dX) */
    const double invL = 1.0 / g->L, invL2 = invL * invL;
    for (int k = 0; k < cx->m; ++k) {
        int row = i * cx->m + k;
        size_t start = (size_t)Pi->row_start[row];
        const double *src = k == 0 ? g->t : (k <= N1 ? C1 + (size_t)(k - 1) * nc
                                                     : C2 + (size_t)(k - 1 - N1) * nc);
        double scale = k == 0 ? 1.0 : (k <= N1 ? invL : invL2);
        for (size_t c = 0; c < nc; ++c) {
            Pi->col[start + c] = group_cols[c];
            Pi->val[start + c] = scale * src[c];
        }
    }
    SEM_FREE_ALL(R, C1, C2, RG);
    return SEM_OK;
}

static void context_free(context *cx, int n_parts, int n_origins)
{
    free(cx->sample_start);
    free(cx->sample_index);
    free(cx->group_col0);
    if (cx->sums)
        for (int i = 0; i < n_parts; ++i) {
            free(cx->sums[i].T);
            free(cx->sums[i].S1);
            free(cx->sums[i].S2);
        }
    free(cx->sums);
    if (cx->groups)
        for (int j = 0; j < n_origins; ++j) {
            SEM_FREE_ALL(cx->groups[j].parts, cx->groups[j].t, cx->groups[j].R1, cx->groups[j].B2);
        }
    free(cx->groups);
}

static sem_status check_inputs(const sem_discretization *d, sem_error *err)
{
    if (d->n_parts <= 0 || !d->part_ctrl_offset)
        return sem_error_set(err, SEM_ERR_INVALID, "projection: no parts (run sampling first)");
    if (d->n_samples < 0 || (d->n_samples > 0 && (!d->sample_part || !d->sample_X ||
                                                  !d->sample_area || !d->J_hat.row_start)))
        return sem_error_set(err, SEM_ERR_INVALID, "projection: missing boundary samples");
    if (d->n_origins <= 0 || !d->origin_X || !d->part_origin)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "projection: missing deformation origins (run origins first)");
    if (d->part_ctrl_offset[0] != 0 || d->part_ctrl_offset[d->n_parts] != d->n_ctrl)
        return sem_error_set(err, SEM_ERR_INVALID, "projection: inconsistent control offsets");
    for (int i = 0; i < d->n_parts; ++i) {
        if (d->part_ctrl_offset[i + 1] < d->part_ctrl_offset[i])
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "projection: inconsistent control offsets");
        if (d->part_origin[i] < 0 || d->part_origin[i] >= d->n_origins)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "projection: part %d has origin %d, not in [0, %d)", i,
                                 d->part_origin[i], d->n_origins);
    }
    for (int j = 0; j < d->n_origins; ++j)
        for (int e = 0; e < 3; ++e)
            if (!isfinite(d->origin_X[3 * j + e]))
                return sem_error_set(err, SEM_ERR_NUMERIC, "projection: origin %d is not finite",
                                     j);
    if (d->n_samples > 0 && (d->J_hat.n_rows != d->n_samples || d->J_hat.n_cols != d->n_ctrl))
        return sem_error_set(err, SEM_ERR_INVALID, "projection: J-hat is %d x %d, expected %d x %d",
                             d->J_hat.n_rows, d->J_hat.n_cols, d->n_samples, d->n_ctrl);
    for (int s = 0; s < d->n_samples; ++s) {
        int p = d->sample_part[s];
        if (p < 0 || p >= d->n_parts)
            return sem_error_set(err, SEM_ERR_INVALID, "projection: sample %d has part %d", s, p);
        double a = d->sample_area[s];
        if (!isfinite(a) || a < 0.0 || !isfinite(d->sample_X[3 * s]) ||
            !isfinite(d->sample_X[3 * s + 1]) || !isfinite(d->sample_X[3 * s + 2]))
            return sem_error_set(err, SEM_ERR_NUMERIC,
                                 "projection: sample %d has a non-finite position or bad area", s);
        for (int q = d->J_hat.row_start[s]; q < d->J_hat.row_start[s + 1]; ++q)
            if (d->J_hat.col[q] < d->part_ctrl_offset[p] ||
                d->J_hat.col[q] >= d->part_ctrl_offset[p + 1] || !isfinite(d->J_hat.val[q]))
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "projection: J-hat row %d leaves part %d's control points",
                                     s, p);
    }
    return SEM_OK;
}

sem_status sem_step_projection(const sem_preprocess_options *o, sem_discretization *d,
                               sem_error *err)
{
    if (!d) return sem_error_set(err, SEM_ERR_INVALID, "projection: null discretization");
    int order = d->order;
    if (order != 1 && order != 2) order = o ? o->order : 2;
    if (order != 1 && order != 2)
        return sem_error_set(err, SEM_ERR_INVALID, "projection: order %d is not 1 or 2", order);
    sem_status st = check_inputs(d, err);
    if (st != SEM_OK) return st;

    const int n_parts = d->n_parts, n_origins = d->n_origins, m = order == 2 ? 10 : 4;
    context cx;
    memset(&cx, 0, sizeof cx);
    cx.d = d;
    cx.order = order;
    cx.m = m;
    cx.shared = d->shared_fit != 0;
    /* samples of each part (sampling already emits them in order) */
    sem_samples_by_part(d, &cx.sample_start, &cx.sample_index);
    cx.group_col0 = malloc((size_t)n_parts * sizeof *cx.group_col0);
    cx.sums = calloc((size_t)n_parts, sizeof *cx.sums);
    cx.groups = calloc((size_t)n_origins, sizeof *cx.groups);
    int *group_cols = NULL;
    int *group_cols_start = NULL;
    sem_csr Pi;
    memset(&Pi, 0, sizeof Pi);
    if (!cx.sample_start || !cx.sample_index || !cx.group_col0 || !cx.sums || !cx.groups)
        goto nomem;

    /* groups: parts per origin (ascending) and their columns */
    for (int i = 0; i < n_parts; ++i) cx.groups[d->part_origin[i]].n_parts++;
    for (int j = 0; j < n_origins; ++j) {
        cx.groups[j].parts = malloc(((size_t)cx.groups[j].n_parts + 1) * sizeof(int));
        if (!cx.groups[j].parts) goto nomem;
        cx.groups[j].n_parts = 0;
    }
    for (int i = 0; i < n_parts; ++i) {
        group *g = &cx.groups[d->part_origin[i]];
        g->parts[g->n_parts++] = i;
        cx.group_col0[i] = g->n_cols;
        g->n_cols += d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i];
    }
    size_t nnz = 0, total_cols = 0;
    for (int i = 0; i < n_parts; ++i) nnz += (size_t)m * (size_t)cx.groups[d->part_origin[i]].n_cols;
    if (nnz > (size_t)INT_MAX) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "projection: Pi would have %zu non-zeros (too many parts per origin)",
                           nnz);
        goto fail;
    }
    group_cols_start = malloc(((size_t)n_origins + 1) * sizeof *group_cols_start);
    if (!group_cols_start) goto nomem;
    group_cols_start[0] = 0;
    for (int j = 0; j < n_origins; ++j) {
        total_cols += (size_t)cx.groups[j].n_cols;
        group_cols_start[j + 1] = (int)total_cols;
    }
    group_cols = malloc((total_cols + 1) * sizeof *group_cols);
    if (!group_cols) goto nomem;
    for (int j = 0; j < n_origins; ++j) {
        int *gc = group_cols + group_cols_start[j];
        for (int a = 0; a < cx.groups[j].n_parts; ++a) {
            int i = cx.groups[j].parts[a];
            for (int c = d->part_ctrl_offset[i]; c < d->part_ctrl_offset[i + 1]; ++c)
                gc[cx.group_col0[i] + c - d->part_ctrl_offset[i]] = c;
        }
    }

    /* Threads only pay off for large inputs: small models (most of Table 1) take well under
     * a millisecond, less than a fork/join on a busy machine. */
    const int parallel = d->n_samples > 20000 || nnz > 200000;
    const int threads = sem_threads(o ? o->threads : 0);

    /* rest moments -> length scale L_j and the origin consistency check */
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads) if (parallel)
    for (int i = 0; i < n_parts; ++i) part_rest_moments(&cx, i);
    for (int j = 0; j < n_origins; ++j) {
        group *g = &cx.groups[j];
        double centroid[3] = {0, 0, 0}, spread = 0.0;
        for (int a = 0; a < g->n_parts; ++a) {
            const part_sums *ps = &cx.sums[g->parts[a]];
            g->area += ps->area;
            spread += ps->spread_sum;
            for (int e = 0; e < 3; ++e) centroid[e] += ps->centroid_sum[e];
        }
        g->L = g->area > 0.0 ? sqrt(spread / g->area) : 0.0;
        if (!(g->L > 0.0) || !isfinite(g->L)) g->L = 1.0; /* a point-like or empty group */
        if (g->area > 0.0) {
            const double *Xbar = d->origin_X + 3 * (size_t)j;
            double dist = 0.0, size = 0.0;
            for (int e = 0; e < 3; ++e) {
                double c = centroid[e] / g->area;
                dist = fmax(dist, fabs(c - Xbar[e]));
                size = fmax(size, fabs(Xbar[e]));
            }
            if (dist > SEM_PROJECTION_ORIGIN_TOL * (g->L + size)) {
                st = sem_error_set(err, SEM_ERR_INVALID,
                                   "projection: origin %d at (%g, %g, %g) is not the area-weighted "
                                   "centroid of its parts' samples (off by %g); Eq. 7 needs "
                                   "Xbar_j = t_j(q0)",
                                   j, Xbar[0], Xbar[1], Xbar[2], dist);
                goto fail;
            }
        }
    }

    /* per-part fit moments */
    for (int i = 0; i < n_parts; ++i) {
        part_sums *ps = &cx.sums[i];
        size_t nc = (size_t)(d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i]);
        ps->T = calloc(nc ? nc : 1, sizeof *ps->T);
        ps->S1 = calloc(N1 * (nc ? nc : 1), sizeof *ps->S1);
        ps->S2 = order == 2 ? calloc(N2 * (nc ? nc : 1), sizeof *ps->S2) : NULL;
        if (!ps->T || !ps->S1 || (order == 2 && !ps->S2)) goto nomem;
    }
    for (int j = 0; j < n_origins; ++j) decide_floored(&cx, j);
#pragma omp parallel for schedule(dynamic, 4) num_threads(threads) if (parallel)
    for (int i = 0; i < n_parts; ++i) part_fit_moments(&cx, i);
    for (int j = 0; j < n_origins; ++j)
        if (group_sums(&cx, j) != SEM_OK) goto nomem;

    /* Pi layout: every row of part i spans its group's columns */
    if (sem_csr_alloc(&Pi, n_parts * m, d->n_ctrl, nnz) != SEM_OK) goto nomem;
    for (int i = 0; i < n_parts; ++i)
        for (int k = 0; k < m; ++k) {
            int row = i * m + k;
            Pi.row_start[row + 1] = Pi.row_start[row] + cx.groups[d->part_origin[i]].n_cols;
        }
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed) num_threads(threads) if (parallel)
    for (int i = 0; i < n_parts; ++i)
        if (part_solve(&cx, i, &Pi, group_cols + group_cols_start[d->part_origin[i]]) != SEM_OK)
            failed = 1;
    if (failed) goto nomem;
    for (size_t k = 0; k < nnz; ++k)
        if (!isfinite(Pi.val[k])) {
            st = sem_error_set(err, SEM_ERR_NUMERIC, "projection: non-finite entry in Pi");
            goto fail;
        }

    sem_csr_free(&d->Pi);
    d->Pi = Pi;
    d->order = order;
    d->n_basis = m;
    free(group_cols);
    free(group_cols_start);
    context_free(&cx, n_parts, n_origins);
    return SEM_OK;

nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "projection: out of memory");
fail:
    sem_csr_free(&Pi);
    free(group_cols);
    free(group_cols_start);
    context_free(&cx, n_parts, n_origins);
    return st;
}

void sem_projection_coefficients(const sem_discretization *d, int part, const double *Q,
                                 int width, double *C)
{
    /* a view of part's m rows: row_start entries are absolute offsets into col/val */
    sem_csr rows = d->Pi;
    rows.n_rows = d->n_basis;
    rows.row_start = d->Pi.row_start + (size_t)part * (size_t)d->n_basis;
    sem_csr_multiply(&rows, Q, width, C);
}
