/*
 * material.c - hyperelastic energy densities, their first and second derivatives, and the
 * positive semi-definite projection Newton needs (see sem/material.h for conventions).
 *
 * Every material is written in terms of three ingredients whose derivatives are simple:
 *   I1 = |F|^2           dI1/dF = 2F,           d2I1/dF2 = 2 Id
 *   J  = det F           dJ/dF  = g = cof F,    d2J/dF2  = HJ, HJ_{ij,kl} = e_ikm e_jln F_mn
 *   R  (polar rotation)  dR/dF  = sum over the three "twist" modes 2/(s_x+s_y) q q^T
 * (the last from Smith, de Goes, Kim 2019, "Analytic eigensystems for isotropic distortion
 * energies", Sec. 5: q = vec(U T V^T)/sqrt 2 with T the skew generators in the SVD frame).
 * Chain rule then gives P and H in closed form; every Hessian is assembled from symmetric
 * pieces, so it is exactly symmetric in floating point.
 *
 * Precision: the rest-state constants (I1 = 3, J = 1) are removed analytically by working
 * with G = F - I, so psi keeps its relative precision for strains down to 1e-8 and below.
 */
#include "sem/material.h"

#include <ctype.h>
#include <float.h>
#include <math.h>
#include <string.h>

/* ------------------------------------------------------------------------------------ */
/* Parameters                                                                            */
/* ------------------------------------------------------------------------------------ */

sem_material sem_default_material(void)
{
    sem_material m;
    m.type = SEM_MATERIAL_NEOHOOKEAN;
    m.density = 1000.0;
    m.youngs_modulus = 1e6;
    m.poisson_ratio = 0.45;
    m.mu = m.youngs_modulus / (2.0 * (1.0 + m.poisson_ratio));
    m.lambda = m.youngs_modulus * m.poisson_ratio /
               ((1.0 + m.poisson_ratio) * (1.0 - 2.0 * m.poisson_ratio));
    return m;
}

sem_status sem_material_init(sem_material *m, sem_error *err)
{
    if (!m) return sem_error_set(err, SEM_ERR_INVALID, "material: NULL pointer");
    if ((int)m->type < 0 || (int)m->type >= SEM_MATERIAL_TYPE_COUNT)
        return sem_error_set(err, SEM_ERR_INVALID, "material type %d is unknown", (int)m->type);
    /* written as !(x > 0) so that NaN is rejected too */
    if (!(m->density > 0.0) || !isfinite(m->density))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "material density must be positive and finite (got %g)", m->density);
    if (!(m->youngs_modulus > 0.0) || !isfinite(m->youngs_modulus))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "material youngs_modulus (E) must be positive and finite (got %g)",
                             m->youngs_modulus);
    if (!(m->poisson_ratio > -1.0 && m->poisson_ratio < 0.5))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "material poisson_ratio (nu) must be in (-1, 0.5) (got %g)",
                             m->poisson_ratio);
    double e = m->youngs_modulus, nu = m->poisson_ratio;
    m->mu = e / (2.0 * (1.0 + nu));
    m->lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
    return SEM_OK;
}

static const char *const type_names[SEM_MATERIAL_TYPE_COUNT] = {
    "neohookean", "stable_neohookean", "corotated", "stvk", "linear"};

const char *sem_material_type_name(sem_material_type t)
{
    if ((int)t < 0 || (int)t >= SEM_MATERIAL_TYPE_COUNT) return "unknown";
    return type_names[t];
}

sem_status sem_material_parse_type(const char *name, sem_material_type *out)
{
    static const struct {
        const char *name;
        sem_material_type type;
    } aliases[] = {
        {"neohookean", SEM_MATERIAL_NEOHOOKEAN},
        {"neo_hookean", SEM_MATERIAL_NEOHOOKEAN},
        {"stable_neohookean", SEM_MATERIAL_STABLE_NEOHOOKEAN},
        {"stable_neo_hookean", SEM_MATERIAL_STABLE_NEOHOOKEAN},
        {"snh", SEM_MATERIAL_STABLE_NEOHOOKEAN},
        {"corotated", SEM_MATERIAL_COROTATED},
        {"co_rotated", SEM_MATERIAL_COROTATED},
        {"fixed_corotated", SEM_MATERIAL_COROTATED},
        {"stvk", SEM_MATERIAL_STVK},
        {"st_venant_kirchhoff", SEM_MATERIAL_STVK},
        {"saint_venant_kirchhoff", SEM_MATERIAL_STVK},
        {"linear", SEM_MATERIAL_LINEAR},
    };
    if (!name || !out) return SEM_ERR_INVALID;
    char key[64];
    size_t n = strlen(name);
    if (n == 0 || n >= sizeof key) return SEM_ERR_INVALID;
    for (size_t i = 0; i <= n; ++i) {
        char c = (char)tolower((unsigned char)name[i]);
        key[i] = c == '-' ? '_' : c;
    }
    for (size_t i = 0; i < sizeof aliases / sizeof aliases[0]; ++i) {
        if (strcmp(key, aliases[i].name) == 0) {
            *out = aliases[i].type;
            return SEM_OK;
        }
    }
    return SEM_ERR_INVALID;
}

/* ------------------------------------------------------------------------------------ */
/* Shared invariants                                                                     */
/* ------------------------------------------------------------------------------------ */

/* g = cof F = dJ/dF (row-major, same layout as F). */
static void cofactor(const double F[9], double g[9])
{
    g[0] = F[4] * F[8] - F[5] * F[7];
    g[1] = F[5] * F[6] - F[3] * F[8];
    g[2] = F[3] * F[7] - F[4] * F[6];
    g[3] = F[2] * F[7] - F[1] * F[8];
    g[4] = F[0] * F[8] - F[2] * F[6];
    g[5] = F[1] * F[6] - F[0] * F[7];
    g[6] = F[1] * F[5] - F[2] * F[4];
    g[7] = F[2] * F[3] - F[0] * F[5];
    g[8] = F[0] * F[4] - F[1] * F[3];
}

/* Strain invariants from G = F - I without cancellation:
 * *d = I1 - 3 = 2 tr G + |G|^2 and *j1 = J - 1 = tr G + I2(G) + det G. */
static void rest_relative_invariants(const double F[9], double *d, double *j1)
{
    double G[9];
    for (int a = 0; a < 9; ++a) G[a] = F[a];
    G[0] -= 1.0;
    G[4] -= 1.0;
    G[8] -= 1.0;
    double tr = G[0] + G[4] + G[8];
    double sq = 0.0;
    for (int a = 0; a < 9; ++a) sq += G[a] * G[a];
    double i2 = (G[0] * G[4] - G[1] * G[3]) + (G[0] * G[8] - G[2] * G[6]) +
                (G[4] * G[8] - G[5] * G[7]);
    double det = G[0] * (G[4] * G[8] - G[5] * G[7]) - G[1] * (G[3] * G[8] - G[5] * G[6]) +
                 G[2] * (G[3] * G[7] - G[4] * G[6]);
    *d = 2.0 * tr + sq;
    *j1 = tr + i2 + det;
}

static void outer_add(double c, const double a[9], const double b[9], double H[81])
{
    for (int r = 0; r < 9; ++r) {
        double ca = c * a[r];
        for (int s = 0; s < 9; ++s) H[9 * r + s] += ca * b[s];
    }
}

/* H += c d2J/dF2, d2J/dF_ij dF_kl = e_ikm e_jln F_mn: non-zero only for i != k and j != l,
 * where m and n are the remaining indices; 36 entries. */
static void det_hessian_add(double c, const double F[9], double H[81])
{
    for (int i = 0; i < 3; ++i) {
        for (int k = 0; k < 3; ++k) {
            if (k == i) continue;
            int m = 3 - i - k;
            double si = (k == (i + 1) % 3) ? c : -c; /* e_ikm: +1 for cyclic (i,k,m) */
            for (int j = 0; j < 3; ++j) {
                for (int l = 0; l < 3; ++l) {
                    if (l == j) continue;
                    int n = 3 - j - l;
                    double s = (l == (j + 1) % 3) ? si : -si;
                    H[9 * (3 * i + j) + 3 * k + l] += s * F[3 * m + n];
                }
            }
        }
    }
}

/* The pieces above are symmetric in exact arithmetic but their products round differently
 * on either side of the diagonal; averaging makes H bitwise symmetric, which sparse
 * assemblers that store one triangle and the PSD projection rely on. */
static void symmetrize_81(double H[81])
{
    for (int a = 0; a < 9; ++a)
        for (int b = a + 1; b < 9; ++b)
            H[9 * a + b] = H[9 * b + a] = 0.5 * (H[9 * a + b] + H[9 * b + a]);
}

static void identity_81(double c, double H[81])
{
    memset(H, 0, 81 * sizeof(double));
    for (int a = 0; a < 9; ++a) H[10 * a] = c;
}

/* ------------------------------------------------------------------------------------ */
/* Materials                                                                             */
/* ------------------------------------------------------------------------------------ */

/* psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2 (the paper's neo-Hookean).
 * P = mu F + c g with c = (lambda ln J - mu)/J, since F^-T = g/J;
 * H = mu Id + c'(J) g g^T + c HJ, c' = (lambda (1 - ln J) + mu)/J^2. */
static double neohookean(double mu, double lambda, const double F[9], double P[9], double H[81])
{
    double d, j1;
    rest_relative_invariants(F, &d, &j1);
    if (!(j1 > -1.0)) {
        if (P)
            for (int a = 0; a < 9; ++a) P[a] = NAN;
        if (H)
            for (int a = 0; a < 81; ++a) H[a] = NAN;
        return INFINITY;
    }
    double J = 1.0 + j1;
    double lnj = log1p(j1);
    double psi = 0.5 * mu * d - mu * lnj + 0.5 * lambda * lnj * lnj;
    if (!P && !H) return psi;
    double g[9];
    cofactor(F, g);
    double c = (lambda * lnj - mu) / J;
    if (P)
        for (int a = 0; a < 9; ++a) P[a] = mu * F[a] + c * g[a];
    if (H) {
        identity_81(mu, H);
        outer_add((lambda * (1.0 - lnj) + mu) / (J * J), g, g, H);
        det_hessian_add(c, F, H);
        symmetrize_81(H);
    }
    return psi;
}

/* Smith et al. 2018 Eq. 14 with their Sec. 3.4 re-parametrisation so that the small-strain
 * limit is linear elasticity with (mu, lambda): mu' = 4/3 mu, lambda' = lambda + 5/6 mu
 * (lambda' > 0 for every valid nu since it exceeds the bulk modulus lambda + 2/3 mu), and
 * alpha = 1 + 3 mu'/(4 lambda') makes P(I) = 0. The constant lambda'/2 (1 - alpha)^2 -
 * mu'/2 ln 4 is subtracted so psi(I) = 0; with 1 - alpha = -3mu'/(4 lambda'):
 *   psi = mu'/2 d - mu'/2 log1p(d/4) + lambda'/2 j1^2 - 3/4 mu' j1   (d = I1-3, j1 = J-1)
 *   P   = mu' (1 - 1/(I1 + 1)) F + lambda' (J - alpha) g
 *   H   = mu' (1 - 1/(I1 + 1)) Id + 2 mu'/(I1 + 1)^2 F F^T + lambda' g g^T
 *         + lambda' (J - alpha) HJ.
 * I1 >= 0, so ln(I1 + 1) is defined for every F, inverted or not. */
static double stable_neohookean(double mu, double lambda, const double F[9], double P[9],
                                double H[81])
{
    double mu_s = 4.0 / 3.0 * mu;
    double lambda_s = lambda + 5.0 / 6.0 * mu;
    double one_minus_alpha = -0.75 * mu_s / lambda_s;
    double d, j1;
    rest_relative_invariants(F, &d, &j1);
    double psi = 0.5 * mu_s * (d - log1p(0.25 * d)) + 0.5 * lambda_s * j1 * j1 -
                 0.75 * mu_s * j1;
    if (!P && !H) return psi;
    double g[9];
    cofactor(F, g);
    double ic1 = d + 4.0; /* I1 + 1 */
    double cf = mu_s * (d + 3.0) / ic1;
    double cj = lambda_s * (j1 + one_minus_alpha); /* lambda' (J - alpha) */
    if (P)
        for (int a = 0; a < 9; ++a) P[a] = cf * F[a] + cj * g[a];
    if (H) {
        identity_81(cf, H);
        outer_add(2.0 * mu_s / (ic1 * ic1), F, F, H);
        outer_add(lambda_s, g, g, H);
        det_hessian_add(cj, F, H);
        symmetrize_81(H);
    }
    return psi;
}

/* psi = mu |F - R|^2 + lambda/2 (J - 1)^2, R = U V^T of the rotation-variant SVD.
 * d/dF |F - R|^2 = 2 (F - R) because R : dR = 0 (R^T dR is skew), so P = 2 mu (F - R) +
 * lambda (J - 1) g, and H = 2 mu (Id - dR/dF) + lambda g g^T + lambda (J - 1) HJ with
 * dR/dF = sum_{x<y} 2/(s_x + s_y) q q^T, q = vec(u_x v_y^T - u_y v_x^T)/sqrt 2. Because
 * only the smallest singular value may be negative, s_x + s_y >= 0; where it vanishes R is
 * not differentiable and the sum is floored at a tiny positive value (huge but finite H). */
static double corotated(double mu, double lambda, const double F[9], double P[9], double H[81])
{
    double U[9], s[3], V[9], R[9];
    sem_svd_3x3(F, U, s, V);
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            R[3 * i + j] = U[3 * i] * V[3 * j] + U[3 * i + 1] * V[3 * j + 1] +
                           U[3 * i + 2] * V[3 * j + 2];
    double d, j1;
    rest_relative_invariants(F, &d, &j1);
    double fr = 0.0;
    for (int a = 0; a < 9; ++a) fr += (F[a] - R[a]) * (F[a] - R[a]);
    double psi = mu * fr + 0.5 * lambda * j1 * j1;
    if (!P && !H) return psi;
    double g[9];
    cofactor(F, g);
    if (P)
        for (int a = 0; a < 9; ++a) P[a] = 2.0 * mu * (F[a] - R[a]) + lambda * j1 * g[a];
    if (H) {
        identity_81(2.0 * mu, H);
        outer_add(lambda, g, g, H);
        det_hessian_add(lambda * j1, F, H);
        double floor_sum = 1e-12 * (fabs(s[0]) > 1e-300 ? fabs(s[0]) : 1e-300);
        static const int pairs[3][2] = {{0, 1}, {0, 2}, {1, 2}};
        for (int t = 0; t < 3; ++t) {
            int x = pairs[t][0], y = pairs[t][1];
            double sum = s[x] + s[y];
            if (sum < floor_sum) sum = floor_sum;
            double w[9];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j)
                    w[3 * i + j] = U[3 * i + x] * V[3 * j + y] - U[3 * i + y] * V[3 * j + x];
            outer_add(-2.0 * mu / sum, w, w, H); /* -2mu * 2/sum * (w/sqrt2)(w/sqrt2)^T */
        }
        symmetrize_81(H);
    }
    return psi;
}

/* E = (G + G^T + G^T G)/2 (= (F^T F - I)/2 without cancellation), S = 2 mu E + lambda trE I,
 * P = F S, and with dE = (dF^T F + F^T dF)/2:
 * H_{ij,kl} = d_ik S_lj + mu F_il F_kj + mu (F F^T)_ik d_jl + lambda F_ij F_kl. */
static double stvk(double mu, double lambda, const double F[9], double P[9], double H[81])
{
    double G[9], E[9];
    for (int a = 0; a < 9; ++a) G[a] = F[a];
    G[0] -= 1.0;
    G[4] -= 1.0;
    G[8] -= 1.0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            E[3 * i + j] = 0.5 * (G[3 * i + j] + G[3 * j + i] +
                                  G[i] * G[j] + G[3 + i] * G[3 + j] + G[6 + i] * G[6 + j]);
    double tr = E[0] + E[4] + E[8];
    double ee = 0.0;
    for (int a = 0; a < 9; ++a) ee += E[a] * E[a];
    double psi = mu * ee + 0.5 * lambda * tr * tr;
    if (!P && !H) return psi;
    double S[9];
    for (int a = 0; a < 9; ++a) S[a] = 2.0 * mu * E[a];
    S[0] += lambda * tr;
    S[4] += lambda * tr;
    S[8] += lambda * tr;
    if (P)
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                P[3 * i + j] = F[3 * i] * S[j] + F[3 * i + 1] * S[3 + j] + F[3 * i + 2] * S[6 + j];
    if (H) {
        double FFt[9];
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k)
                FFt[3 * i + k] = F[3 * i] * F[3 * k] + F[3 * i + 1] * F[3 * k + 1] +
                                 F[3 * i + 2] * F[3 * k + 2];
        memset(H, 0, 81 * sizeof(double));
        outer_add(lambda, F, F, H);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j)
                for (int k = 0; k < 3; ++k)
                    for (int l = 0; l < 3; ++l) {
                        double h = mu * F[3 * i + l] * F[3 * k + j];
                        if (i == k) h += S[3 * l + j];
                        if (j == l) h += mu * FFt[3 * i + k];
                        H[9 * (3 * i + j) + 3 * k + l] += h;
                    }
        symmetrize_81(H);
    }
    return psi;
}

/* eps = (G + G^T)/2, P = 2 mu eps + lambda tr(eps) I,
 * H_{ij,kl} = mu (d_ik d_jl + d_il d_jk) + lambda d_ij d_kl (constant). */
static double linear(double mu, double lambda, const double F[9], double P[9], double H[81])
{
    double eps[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            eps[3 * i + j] = 0.5 * (F[3 * i + j] + F[3 * j + i]) - (i == j ? 1.0 : 0.0);
    double tr = eps[0] + eps[4] + eps[8];
    double ee = 0.0;
    for (int a = 0; a < 9; ++a) ee += eps[a] * eps[a];
    if (P) {
        for (int a = 0; a < 9; ++a) P[a] = 2.0 * mu * eps[a];
        P[0] += lambda * tr;
        P[4] += lambda * tr;
        P[8] += lambda * tr;
    }
    if (H) {
        identity_81(mu, H);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) H[9 * (3 * i + j) + 3 * j + i] += mu;
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) H[9 * (4 * i) + 4 * k] += lambda;
    }
    return mu * ee + 0.5 * lambda * tr * tr;
}

double sem_material_energy(const sem_material *m, const double F[9], double P[9], double H[81])
{
    switch (m->type) {
    case SEM_MATERIAL_NEOHOOKEAN: return neohookean(m->mu, m->lambda, F, P, H);
    case SEM_MATERIAL_STABLE_NEOHOOKEAN: return stable_neohookean(m->mu, m->lambda, F, P, H);
    case SEM_MATERIAL_COROTATED: return corotated(m->mu, m->lambda, F, P, H);
    case SEM_MATERIAL_STVK: return stvk(m->mu, m->lambda, F, P, H);
    case SEM_MATERIAL_LINEAR: return linear(m->mu, m->lambda, F, P, H);
    }
    return NAN;
}

/* ------------------------------------------------------------------------------------ */
/* Linear algebra: symmetric eigensystem, PSD projection, 3x3 SVD                        */
/* ------------------------------------------------------------------------------------ */

/* Cyclic Jacobi (Golub & Van Loan, Alg. 8.5.3). Each rotation zeroes a_pq exactly; an
 * off-diagonal entry below 1e-3 DBL_EPSILON |A|_F is dropped (a perturbation far below the
 * roundoff of any eigen-solver), and the sweeps stop when one performs no rotation.
 * Convergence is quadratic, about 6-8 sweeps for 9x9; the cap only guards NaN input. */
void sem_symmetric_eigen(int n, double *A, double *V, double *w)
{
    double norm2 = 0.0;
    for (int a = 0; a < n * n; ++a) norm2 += A[a] * A[a];
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) V[n * i + j] = i == j ? 1.0 : 0.0;
    double tol = 1e-3 * DBL_EPSILON * sqrt(norm2);
    for (int sweep = 0; sweep < 64; ++sweep) {
        int rotated = 0;
        for (int p = 0; p < n - 1; ++p) {
            for (int q = p + 1; q < n; ++q) {
                double apq = A[n * p + q];
                if (!(fabs(apq) > tol)) {
                    if (fabs(apq) <= tol) A[n * p + q] = A[n * q + p] = 0.0;
                    continue;
                }
                rotated = 1;
                double theta = (A[n * q + q] - A[n * p + p]) / (2.0 * apq);
                double t = fabs(theta) > 1e150
                               ? 0.5 / theta
                               : (theta >= 0.0 ? 1.0 : -1.0) /
                                     (fabs(theta) + sqrt(1.0 + theta * theta));
                double c = 1.0 / sqrt(1.0 + t * t), s = t * c;
                for (int k = 0; k < n; ++k) { /* A J */
                    double akp = A[n * k + p], akq = A[n * k + q];
                    A[n * k + p] = c * akp - s * akq;
                    A[n * k + q] = s * akp + c * akq;
                }
                for (int k = 0; k < n; ++k) { /* J^T (A J) */
                    double apk = A[n * p + k], aqk = A[n * q + k];
                    A[n * p + k] = c * apk - s * aqk;
                    A[n * q + k] = s * apk + c * aqk;
                }
                A[n * p + q] = A[n * q + p] = 0.0;
                for (int k = 0; k < n; ++k) { /* V J */
                    double vkp = V[n * k + p], vkq = V[n * k + q];
                    V[n * k + p] = c * vkp - s * vkq;
                    V[n * k + q] = s * vkp + c * vkq;
                }
            }
        }
        if (!rotated) break;
    }
    for (int i = 0; i < n; ++i) w[i] = A[n * i + i];
}

/* 1 when the (symmetric) matrix has a Cholesky factor with positive pivots. */
/* Is H + shift I positive definite (Cholesky succeeds)? */
static int is_positive_definite_9x9(const double H[81], double shift)
{
    double L[81];
    for (int j = 0; j < 9; ++j) {
        double diag = H[10 * j] + shift;
        for (int k = 0; k < j; ++k) diag -= L[9 * j + k] * L[9 * j + k];
        if (!(diag > 0.0) || !isfinite(diag)) return 0;
        double ljj = sqrt(diag);
        L[10 * j] = ljj;
        for (int i = j + 1; i < 9; ++i) {
            double v = H[9 * i + j];
            for (int k = 0; k < j; ++k) v -= L[9 * i + k] * L[9 * j + k];
            L[9 * i + j] = v / ljj;
        }
    }
    return 1;
}

void sem_project_psd_9x9(double H[81])
{
    for (int i = 0; i < 9; ++i)
        for (int j = i + 1; j < 9; ++j)
            H[9 * i + j] = H[9 * j + i] = 0.5 * (H[9 * i + j] + H[9 * j + i]);
    /* Fast path: no eigenvalue below -1e-10 of the largest diagonal entry. The clamp would
     * move such an eigenvalue by less than that, and many Hessians sit exactly there: at
     * rest and under rigid rotation a neo-Hookean Hessian is singular (zero modes of the
     * infinitesimal rotations), so plain Cholesky fails on round-off and half the step's
     * per-point work went to 9 x 9 eigendecompositions that changed nothing. */
    double dmax = 0.0;
    for (int i = 0; i < 9; ++i) dmax = fmax(dmax, fabs(H[10 * i]));
    if (is_positive_definite_9x9(H, 1e-10 * dmax)) return;
    double A[81], V[81], w[9];
    memcpy(A, H, sizeof A);
    sem_symmetric_eigen(9, A, V, w);
    for (int i = 0; i < 9; ++i) {
        for (int j = i; j < 9; ++j) {
            double h = 0.0;
            for (int k = 0; k < 9; ++k)
                if (w[k] > 0.0) h += w[k] * V[9 * i + k] * V[9 * j + k];
            H[9 * i + j] = H[9 * j + i] = h;
        }
    }
}

/* Givens rotation on rows r0, r1 of the 3x3 R that zeroes R[r1][col] and leaves
 * R[r0][col] = hypot >= 0; Q accumulates the transposes so that Q R stays constant. */
static void givens_zero(double R[9], double Q[9], int r0, int r1, int col)
{
    double a = R[3 * r0 + col], b = R[3 * r1 + col];
    double r = hypot(a, b);
    if (r == 0.0) return;
    double c = a / r, s = b / r;
    for (int k = 0; k < 3; ++k) {
        double x = R[3 * r0 + k], y = R[3 * r1 + k];
        R[3 * r0 + k] = c * x + s * y;
        R[3 * r1 + k] = -s * x + c * y;
        double qx = Q[3 * k + r0], qy = Q[3 * k + r1];
        Q[3 * k + r0] = c * qx + s * qy;
        Q[3 * k + r1] = -s * qx + c * qy;
    }
    R[3 * r1 + col] = 0.0;
}

/* McAdams et al. 2011: V from the eigenvectors of F^T F (sorted by decreasing eigenvalue,
 * det V = +1), then F V = Q R by Givens rotations, so U = Q is a rotation, and R is diagonal
 * up to roundoff because the columns of F V are orthogonal. The first two diagonal entries
 * come out as norms (>= 0) and the last one carries the sign of det F. */
void sem_svd_3x3(const double F[9], double U[9], double sigma[3], double V[9])
{
    double A[9], Vr[9], w[3];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            A[3 * i + j] = F[i] * F[j] + F[3 + i] * F[3 + j] + F[6 + i] * F[6 + j];
    sem_symmetric_eigen(3, A, Vr, w);
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 2; ++i)
        for (int j = i + 1; j < 3; ++j)
            if (w[order[j]] > w[order[i]]) {
                int t = order[i];
                order[i] = order[j];
                order[j] = t;
            }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) V[3 * i + j] = Vr[3 * i + order[j]];
    double detv = V[0] * (V[4] * V[8] - V[5] * V[7]) - V[1] * (V[3] * V[8] - V[5] * V[6]) +
                  V[2] * (V[3] * V[7] - V[4] * V[6]);
    if (detv < 0.0) {
        V[2] = -V[2];
        V[5] = -V[5];
        V[8] = -V[8];
    }
    double R[9];
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            R[3 * i + j] = F[3 * i] * V[j] + F[3 * i + 1] * V[3 + j] + F[3 * i + 2] * V[6 + j];
    for (int a = 0; a < 9; ++a) U[a] = (a % 4 == 0) ? 1.0 : 0.0;
    givens_zero(R, U, 0, 1, 0);
    givens_zero(R, U, 0, 2, 0);
    givens_zero(R, U, 1, 2, 1);
    sigma[0] = R[0];
    sigma[1] = R[4];
    sigma[2] = R[8];
}
