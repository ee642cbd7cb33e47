/* test_material.c - hyperelastic materials: derivatives against finite differences, rest
 * state, rotation invariance, small-strain limit, closed forms, PSD projection, SVD and
 * parameter validation. */
#include <stdint.h>
#include <string.h>

#include "sem/material.h"
#include "test_util.h"

static const sem_material_type all_types[SEM_MATERIAL_TYPE_COUNT] = {
    SEM_MATERIAL_NEOHOOKEAN, SEM_MATERIAL_STABLE_NEOHOOKEAN, SEM_MATERIAL_COROTATED,
    SEM_MATERIAL_STVK, SEM_MATERIAL_LINEAR};

/* deterministic uniform numbers in [-1, 1] (xorshift64) */
static unsigned long long rng_state = 0x9E3779B97F4A7C15ull;
static double urand(void)
{
    return test_uniform(&rng_state) * 2.0 - 1.0;
}

static sem_material make_material(sem_material_type type)
{
    sem_material m = sem_default_material();
    m.type = type;
    sem_error err;
    sem_status st = sem_material_init(&m, &err);
    CHECK(st == SEM_OK, "init %s: %s", sem_material_type_name(type), err.message);
    return m;
}

static void mat3_mul(const double A[9], const double B[9], double C[9])
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            C[3 * i + j] = A[3 * i] * B[j] + A[3 * i + 1] * B[3 + j] + A[3 * i + 2] * B[6 + j];
}

static double det3(const double A[9])
{
    return A[0] * (A[4] * A[8] - A[5] * A[7]) - A[1] * (A[3] * A[8] - A[5] * A[6]) +
           A[2] * (A[3] * A[7] - A[4] * A[6]);
}

/* rotation from a random unit quaternion */
static void random_rotation(double R[9])
{
    double q[4], n = 0.0;
    do {
        n = 0.0;
        for (int i = 0; i < 4; ++i) {
            q[i] = urand();
            n += q[i] * q[i];
        }
    } while (n < 1e-2);
    n = sqrt(n);
    double w = q[0] / n, x = q[1] / n, y = q[2] / n, z = q[3] / n;
    double r[9] = {1 - 2 * (y * y + z * z), 2 * (x * y - w * z),     2 * (x * z + w * y),
                   2 * (x * y + w * z),     1 - 2 * (x * x + z * z), 2 * (y * z - w * x),
                   2 * (x * z - w * y),     2 * (y * z + w * x),     1 - 2 * (x * x + y * y)};
    memcpy(R, r, sizeof r);
}

/* F = R1 diag(s) R2 */
static void rotated_diagonal(double s0, double s1, double s2, double F[9])
{
    double R1[9], R2[9], D[9] = {s0, 0, 0, 0, s1, 0, 0, 0, s2}, T[9];
    random_rotation(R1);
    random_rotation(R2);
    mat3_mul(R1, D, T);
    mat3_mul(T, R2, F);
}

static double norm(const double *a, int n)
{
    double s = 0.0;
    for (int i = 0; i < n; ++i) s += a[i] * a[i];
    return sqrt(s);
}

/* P against central differences of psi, H against central differences of P, relative to
 * max(|P|, mu) and max(|H|, mu); H must also be exactly symmetric. */
static void check_derivatives(const sem_material *m, const double F[9], const char *what)
{
    double P[9], H[81];
    double psi = sem_material_energy(m, F, P, H);
    const char *name = sem_material_type_name(m->type);
    CHECK(isfinite(psi), "%s at %s: psi = %g", name, what, psi);
    double scale = 1.0;
    for (int a = 0; a < 9; ++a) scale = fmax(scale, fabs(F[a]));
    double h = 1e-5 * scale;
    double P_fd[9], H_fd[81];
    for (int b = 0; b < 9; ++b) {
        double Fp[9], Fm[9], Pp[9], Pm[9];
        memcpy(Fp, F, sizeof Fp);
        memcpy(Fm, F, sizeof Fm);
        Fp[b] += h;
        Fm[b] -= h;
        double psi_p = sem_material_energy(m, Fp, Pp, NULL);
        double psi_m = sem_material_energy(m, Fm, Pm, NULL);
        P_fd[b] = (psi_p - psi_m) / (2.0 * h);
        for (int a = 0; a < 9; ++a) H_fd[9 * a + b] = (Pp[a] - Pm[a]) / (2.0 * h);
    }
    double dP[9], dH[81];
    for (int a = 0; a < 9; ++a) dP[a] = P_fd[a] - P[a];
    for (int a = 0; a < 81; ++a) dH[a] = H_fd[a] - H[a];
    double p_err = norm(dP, 9) / fmax(norm(P, 9), m->mu);
    double h_err = norm(dH, 81) / fmax(norm(H, 81), m->mu);
    CHECK(p_err < 1e-6, "%s at %s: |P - P_fd| relative %.3g", name, what, p_err);
    CHECK(h_err < 1e-6, "%s at %s: |H - H_fd| relative %.3g", name, what, h_err);
    int symmetric = 1;
    for (int a = 0; a < 9; ++a)
        for (int b = 0; b < 9; ++b) symmetric &= H[9 * a + b] == H[9 * b + a];
    CHECK(symmetric, "%s at %s: H not symmetric", name, what);
    /* P and H must not depend on whether the other is requested */
    double P2[9], H2[81];
    sem_material_energy(m, F, P2, NULL);
    double psi3 = sem_material_energy(m, F, NULL, H2);
    double psi4 = sem_material_energy(m, F, NULL, NULL);
    CHECK(memcmp(P, P2, sizeof P) == 0 && memcmp(H, H2, sizeof H) == 0 && psi3 == psi &&
              psi4 == psi,
          "%s at %s: outputs depend on which are requested", name, what);
}

static void test_derivatives_against_finite_differences(void)
{
    for (int t = 0; t < SEM_MATERIAL_TYPE_COUNT; ++t) {
        sem_material m = make_material(all_types[t]);
        char what[64];
        double F[9];
        /* near identity */
        for (int trial = 0; trial < 5; ++trial) {
            for (int a = 0; a < 9; ++a) F[a] = (a % 4 == 0 ? 1.0 : 0.0) + 0.1 * urand();
            snprintf(what, sizeof what, "near identity #%d", trial);
            check_derivatives(&m, F, what);
        }
        /* large deformations */
        double stretch[9] = {2, 0, 0, 0, 1, 0, 0, 0, 1};
        check_derivatives(&m, stretch, "uniaxial stretch 2x");
        double shear[9] = {1, 1, 0, 0, 1, 0, 0, 0, 1};
        check_derivatives(&m, shear, "simple shear 1");
        rotated_diagonal(2.0, 1.0, 0.6, F);
        check_derivatives(&m, F, "rotated stretch (2, 1, 0.6)");
        rotated_diagonal(0.5, 0.45, 0.4, F);
        check_derivatives(&m, F, "rotated compression (0.5, 0.45, 0.4)");
        for (int trial = 0; trial < 5; ++trial) {
            do {
                for (int a = 0; a < 9; ++a) F[a] = (a % 4 == 0 ? 1.0 : 0.0) + 0.7 * urand();
            } while (det3(F) < 0.2);
            snprintf(what, sizeof what, "large random #%d", trial);
            check_derivatives(&m, F, what);
        }
        /* inverted: every material but neo-Hookean is defined (and smooth) there */
        if (all_types[t] != SEM_MATERIAL_NEOHOOKEAN) {
            rotated_diagonal(1.0, 0.9, -0.5, F);
            check_derivatives(&m, F, "inverted (1, 0.9, -0.5)");
            rotated_diagonal(1.5, 1.2, -0.1, F);
            check_derivatives(&m, F, "inverted (1.5, 1.2, -0.1)");
            for (int trial = 0; trial < 3; ++trial) {
                do {
                    for (int a = 0; a < 9; ++a) F[a] = (a % 4 == 0 ? 1.0 : 0.0) + urand();
                } while (det3(F) > -0.2);
                double U[9], s[3], V[9];
                sem_svd_3x3(F, U, s, V);
                if (fabs(s[1] + s[2]) < 0.05) continue; /* co-rotated kink, not smooth */
                snprintf(what, sizeof what, "inverted random #%d", trial);
                check_derivatives(&m, F, what);
            }
        }
    }
}

static void test_rest_state_and_rotations(void)
{
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    for (int t = 0; t < SEM_MATERIAL_TYPE_COUNT; ++t) {
        sem_material m = make_material(all_types[t]);
        const char *name = sem_material_type_name(m.type);
        double P[9], H[81];
        double psi = sem_material_energy(&m, I, P, H);
        CHECK(fabs(psi) <= 1e-12 * m.mu, "%s: psi(I) = %g", name, psi);
        CHECK(norm(P, 9) <= 1e-12 * m.mu, "%s: |P(I)| = %g", name, norm(P, 9));
        for (int trial = 0; trial < 5; ++trial) {
            double R[9];
            random_rotation(R);
            psi = sem_material_energy(&m, R, P, NULL);
            if (all_types[t] == SEM_MATERIAL_LINEAR) {
                /* linear elasticity is not rotation invariant: a rotation stores energy */
                CHECK(psi > 1e-3 * m.mu, "linear: psi(R) = %g should be > 0", psi);
                continue;
            }
            CHECK(fabs(psi) <= 1e-12 * m.mu, "%s: psi(R) = %g", name, psi);
            CHECK(norm(P, 9) <= 1e-10 * m.mu, "%s: |P(R)| = %g", name, norm(P, 9));
        }
    }
}

/* every material's Hessian at rest is the linear one, and psi(I + eps G) matches the linear
 * psi to O(eps): the materials share (mu, lambda) */
static void test_small_strain_limit(void)
{
    sem_material lin = make_material(SEM_MATERIAL_LINEAR);
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double H_lin[81];
    sem_material_energy(&lin, I, NULL, H_lin);
    /* closed form of the linear Hessian: mu (d_ik d_jl + d_il d_jk) + lambda d_ij d_kl */
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j)
            for (int k = 0; k < 3; ++k)
                for (int l = 0; l < 3; ++l) {
                    double h = lin.mu * ((i == k && j == l) + (i == l && j == k)) +
                               lin.lambda * (i == j && k == l);
                    CHECK_NEAR(H_lin[9 * (3 * i + j) + 3 * k + l], h, 1e-9 * lin.mu);
                }
    for (int t = 0; t < SEM_MATERIAL_TYPE_COUNT; ++t) {
        sem_material m = make_material(all_types[t]);
        const char *name = sem_material_type_name(m.type);
        double H[81], dH[81];
        sem_material_energy(&m, I, NULL, H);
        for (int a = 0; a < 81; ++a) dH[a] = H[a] - H_lin[a];
        CHECK(norm(dH, 81) <= 1e-12 * norm(H_lin, 81), "%s: H(I) differs from linear by %g",
              name, norm(dH, 81));
        for (int trial = 0; trial < 10; ++trial) {
            const double eps = 1e-6;
            double F[9];
            for (int a = 0; a < 9; ++a) F[a] = (a % 4 == 0 ? 1.0 : 0.0) + eps * urand();
            double psi = sem_material_energy(&m, F, NULL, NULL);
            double psi_lin = sem_material_energy(&lin, F, NULL, NULL);
            CHECK(psi_lin > 0.0, "linear psi %g", psi_lin);
            CHECK(fabs(psi - psi_lin) <= 1e-4 * psi_lin,
                  "%s: psi(I + 1e-6 G) = %.12g vs linear %.12g", name, psi, psi_lin);
        }
    }
}

/* F = diag(s, 1, 1): closed forms of every energy and of the neo-Hookean stress */
static void test_uniaxial_closed_forms(void)
{
    const double stretches[] = {0.3, 0.5, 0.9, 1.0 + 1e-4, 1.5, 2.0, 3.0};
    for (size_t k = 0; k < sizeof stretches / sizeof stretches[0]; ++k) {
        double s = stretches[k];
        double F[9] = {s, 0, 0, 0, 1, 0, 0, 0, 1};
        /* references in cancellation-free pieces: s^2 - 1 = (s - 1)(s + 1), ln s = log1p(s-1);
         * the tolerance is roundoff of the sum of their magnitudes */
        double sm1 = s - 1.0, s2m1 = sm1 * (s + 1.0), ls = log1p(sm1);
        for (int t = 0; t < SEM_MATERIAL_TYPE_COUNT; ++t) {
            sem_material m = make_material(all_types[t]);
            double mu = m.mu, la = m.lambda, expect = 0.0, size = 0.0;
            switch (m.type) {
            case SEM_MATERIAL_NEOHOOKEAN:
                expect = 0.5 * mu * s2m1 - mu * ls + 0.5 * la * ls * ls;
                size = fabs(0.5 * mu * s2m1) + fabs(mu * ls) + 0.5 * la * ls * ls;
                break;
            case SEM_MATERIAL_STABLE_NEOHOOKEAN: {
                /* mu'/2 (s^2 - 1) + lambda'/2 ((s - alpha)^2 - (1 - alpha)^2)
                 * - mu'/2 (ln(s^2 + 3) - ln 4) */
                double mu_s = 4.0 / 3.0 * mu, la_s = la + 5.0 / 6.0 * mu;
                double alpha = 1.0 + mu_s / la_s - mu_s / (4.0 * la_s);
                double t1 = 0.5 * mu_s * s2m1;
                double t2 = 0.5 * la_s * sm1 * (s + 1.0 - 2.0 * alpha);
                double t3 = -0.5 * mu_s * log1p(0.25 * s2m1);
                expect = t1 + t2 + t3;
                size = fabs(t1) + fabs(t2) + fabs(t3);
                break;
            }
            case SEM_MATERIAL_COROTATED: expect = (mu + 0.5 * la) * sm1 * sm1; break;
            case SEM_MATERIAL_STVK: expect = (mu + 0.5 * la) * 0.25 * s2m1 * s2m1; break;
            case SEM_MATERIAL_LINEAR: expect = (mu + 0.5 * la) * sm1 * sm1; break;
            }
            if (size == 0.0) size = fabs(expect);
            double P[9];
            double psi = sem_material_energy(&m, F, P, NULL);
            CHECK(fabs(psi - expect) <= 1e-14 * size, "%s: psi(diag(%g,1,1)) = %.17g, "
                  "closed form %.17g", sem_material_type_name(m.type), s, psi, expect);
            if (m.type == SEM_MATERIAL_NEOHOOKEAN) {
                CHECK_REL(P[0], mu * s + (la * ls - mu) / s, 1e-13);
                CHECK_NEAR(P[4], la * ls, 1e-13 * mu);
                CHECK_NEAR(P[1], 0.0, 0.0);
            }
        }
    }
    /* the neo-Hookean is undefined for inverted or collapsed elements */
    sem_material nh = make_material(SEM_MATERIAL_NEOHOOKEAN);
    double flat[9] = {0, 0, 0, 0, 1, 0, 0, 0, 1}, inverted[9] = {-1, 0, 0, 0, 1, 0, 0, 0, 1};
    double P[9], H[81];
    CHECK(sem_material_energy(&nh, flat, NULL, NULL) == INFINITY, "neohookean at J = 0");
    CHECK(sem_material_energy(&nh, inverted, P, H) == INFINITY, "neohookean at J = -1");
    CHECK(isnan(P[0]) && isnan(H[80]), "neohookean P, H at J < 0 should be NaN");
    /* the stable one stays finite and pushes the inverted element back out (dpsi/dF00 < 0
     * at F00 = -1 means increasing F00 lowers the energy) */
    sem_material snh = make_material(SEM_MATERIAL_STABLE_NEOHOOKEAN);
    double psi = sem_material_energy(&snh, inverted, P, NULL);
    CHECK(isfinite(psi) && psi > 0.0, "stable_neohookean inverted psi %g", psi);
    CHECK(P[0] < 0.0, "stable_neohookean inverted P00 %g", P[0]);
}

static void random_symmetric(double A[81])
{
    for (int i = 0; i < 9; ++i)
        for (int j = 0; j <= i; ++j) A[9 * i + j] = A[9 * j + i] = urand();
}

static double min_eigenvalue(const double H[81])
{
    double A[81], V[81], w[9];
    memcpy(A, H, sizeof A);
    sem_symmetric_eigen(9, A, V, w);
    double lo = w[0];
    for (int i = 1; i < 9; ++i) lo = fmin(lo, w[i]);
    return lo;
}

static double max_diff(const double *a, const double *b, int n)
{
    double d = 0.0;
    for (int i = 0; i < n; ++i) d = fmax(d, fabs(a[i] - b[i]));
    return d;
}

static void test_eigen_and_psd_projection(void)
{
    for (int trial = 0; trial < 20; ++trial) {
        /* eigen-decomposition reproduces the matrix with orthonormal vectors */
        double A[81], S[81], V[81], w[9];
        random_symmetric(A);
        memcpy(S, A, sizeof S);
        sem_symmetric_eigen(9, S, V, w);
        double err = 0.0, orth = 0.0;
        for (int i = 0; i < 9; ++i)
            for (int j = 0; j < 9; ++j) {
                double a = 0.0, o = 0.0;
                for (int k = 0; k < 9; ++k) {
                    a += V[9 * i + k] * w[k] * V[9 * j + k];
                    o += V[9 * k + i] * V[9 * k + j];
                }
                err = fmax(err, fabs(a - A[9 * i + j]));
                orth = fmax(orth, fabs(o - (i == j)));
            }
        CHECK(err < 1e-13 && orth < 1e-13, "eigen: reconstruction %g orthogonality %g", err,
              orth);

        /* a matrix with known eigenvalues, some negative: the projection clamps exactly them */
        double w_known[9], M[81], expect[81];
        for (int k = 0; k < 9; ++k) w_known[k] = (k % 3 == 0 ? -1.0 : 1.0) * (0.5 + k);
        if (trial % 4 == 0) w_known[4] = 0.0;
        for (int i = 0; i < 9; ++i)
            for (int j = 0; j < 9; ++j) {
                double mij = 0.0, eij = 0.0;
                for (int k = 0; k < 9; ++k) {
                    mij += V[9 * i + k] * w_known[k] * V[9 * j + k];
                    eij += V[9 * i + k] * fmax(w_known[k], 0.0) * V[9 * j + k];
                }
                M[9 * i + j] = mij;
                expect[9 * i + j] = eij;
            }
        for (int i = 0; i < 9; ++i)
            for (int j = 0; j < i; ++j) M[9 * i + j] = M[9 * j + i];
        sem_project_psd_9x9(M);
        CHECK(max_diff(M, expect, 81) < 1e-12, "projection of known spectrum off by %g",
              max_diff(M, expect, 81));
        CHECK(min_eigenvalue(M) >= -1e-12, "projected min eigenvalue %g", min_eigenvalue(M));
        double M2[81];
        memcpy(M2, M, sizeof M2);
        sem_project_psd_9x9(M2);
        CHECK(max_diff(M, M2, 81) < 1e-12, "projection not idempotent: %g", max_diff(M, M2, 81));

        /* PSD matrices are left alone: full rank (Cholesky path) and rank 5 (eigen path) */
        for (int rank = 9; rank >= 5; rank -= 4) {
            double B[81], C[81], C0[81];
            for (int a = 0; a < 81; ++a) B[a] = urand();
            for (int i = 0; i < 9; ++i)
                for (int j = 0; j < 9; ++j) {
                    double c = 0.0;
                    for (int k = 0; k < rank; ++k) c += B[9 * i + k] * B[9 * j + k];
                    C[9 * i + j] = c;
                }
            memcpy(C0, C, sizeof C0);
            sem_project_psd_9x9(C);
            CHECK(max_diff(C, C0, 81) < 1e-12, "rank %d PSD matrix changed by %g", rank,
                  max_diff(C, C0, 81));
        }
    }
    /* a compressed neo-Hookean point has an indefinite Hessian; projection fixes it */
    sem_material nh = make_material(SEM_MATERIAL_NEOHOOKEAN);
    double F[9], H[81];
    rotated_diagonal(0.3, 0.3, 3.0, F);
    sem_material_energy(&nh, F, NULL, H);
    double lo = min_eigenvalue(H);
    CHECK(lo < -1e-3 * nh.mu, "expected an indefinite neo-Hookean Hessian, min eig %g", lo);
    sem_project_psd_9x9(H);
    lo = min_eigenvalue(H);
    CHECK(lo >= -1e-12 * nh.lambda, "projected neo-Hookean Hessian min eig %g", lo);
}

static void test_svd(void)
{
    for (int trial = 0; trial < 200; ++trial) {
        double F[9];
        switch (trial % 5) {
        case 0:
            for (int a = 0; a < 9; ++a) F[a] = urand();
            break;
        case 1: rotated_diagonal(1.0, 1.0, 1.0 + 1e-9 * urand(), F); break; /* repeated */
        case 2: rotated_diagonal(2.0, 0.0, 0.0, F); break;                 /* rank 1 */
        case 3: rotated_diagonal(1.5, 0.7, -0.2, F); break;                /* inverted */
        default:
            for (int a = 0; a < 9; ++a) F[a] = (a % 4 == 0 ? 1.0 : 0.0) + 1e-7 * urand();
        }
        double U[9], s[3], V[9], US[9], R[9];
        sem_svd_3x3(F, U, s, V);
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) US[3 * i + j] = U[3 * i + j] * s[j];
        double err = 0.0, orth = 0.0;
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                double r = 0.0, ou = 0.0, ov = 0.0;
                for (int k = 0; k < 3; ++k) {
                    r += US[3 * i + k] * V[3 * j + k];
                    ou += U[3 * k + i] * U[3 * k + j];
                    ov += V[3 * k + i] * V[3 * k + j];
                }
                R[3 * i + j] = r;
                orth = fmax(orth, fmax(fabs(ou - (i == j)), fabs(ov - (i == j))));
            }
        err = max_diff(R, F, 9);
        CHECK(err < 1e-14 * 4.0, "svd #%d: |U S V^T - F| = %g", trial, err);
        CHECK(orth < 1e-14, "svd #%d: orthogonality %g", trial, orth);
        CHECK(fabs(det3(U) - 1.0) < 1e-14 && fabs(det3(V) - 1.0) < 1e-14, "svd #%d: det %g %g",
              trial, det3(U), det3(V));
        CHECK(s[0] >= 0.0 && s[1] >= 0.0 && s[0] >= s[1] - 1e-15 && s[1] >= fabs(s[2]) - 1e-15,
              "svd #%d: sigma %.17g %.17g %.17g", trial, s[0], s[1], s[2]);
        if (fabs(det3(F)) > 1e-10)
            CHECK((s[2] < 0.0) == (det3(F) < 0.0), "svd #%d: sign of sigma2 %g vs det %g", trial,
                  s[2], det3(F));
    }
}

static void test_parameters(void)
{
    sem_material m = sem_default_material();
    CHECK(m.type == SEM_MATERIAL_NEOHOOKEAN && m.density == 1000.0 && m.youngs_modulus == 1e6 &&
              m.poisson_ratio == 0.45,
          "default material");
    CHECK_REL(m.mu, 1e6 / 2.9, 1e-15);
    CHECK_REL(m.lambda, 0.45e6 / (1.45 * 0.1), 1e-14);
    m.mu = m.lambda = 0.0;
    CHECK(sem_material_init(&m, NULL) == SEM_OK, "init default");
    CHECK_REL(m.mu, 1e6 / 2.9, 1e-15);
    CHECK_REL(m.lambda, 0.45e6 / (1.45 * 0.1), 1e-14);
    m.poisson_ratio = 0.0;
    sem_material_init(&m, NULL);
    CHECK(m.lambda == 0.0 && m.mu == 5e5, "nu = 0: mu %g lambda %g", m.mu, m.lambda);

    static const struct {
        double density, e, nu;
        const char *word;
    } bad[] = {
        {0.0, 1e6, 0.3, "density"},     {-1.0, 1e6, 0.3, "density"},
        {NAN, 1e6, 0.3, "density"},     {INFINITY, 1e6, 0.3, "density"},
        {1000, 0.0, 0.3, "youngs_modulus"}, {1000, -5.0, 0.3, "youngs_modulus"},
        {1000, NAN, 0.3, "youngs_modulus"}, {1000, 1e6, 0.5, "poisson_ratio"},
        {1000, 1e6, 0.6, "poisson_ratio"}, {1000, 1e6, -1.0, "poisson_ratio"},
        {1000, 1e6, -1.5, "poisson_ratio"}, {1000, 1e6, NAN, "poisson_ratio"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        sem_material b = sem_default_material();
        b.density = bad[i].density;
        b.youngs_modulus = bad[i].e;
        b.poisson_ratio = bad[i].nu;
        sem_error err;
        sem_error_clear(&err);
        sem_status st = sem_material_init(&b, &err);
        CHECK(st == SEM_ERR_INVALID && err.status == SEM_ERR_INVALID, "bad #%zu accepted", i);
        CHECK(strstr(err.message, bad[i].word) != NULL, "bad #%zu message '%s' lacks '%s'", i,
              err.message, bad[i].word);
    }
    sem_material b = sem_default_material();
    b.type = (sem_material_type)17;
    CHECK(sem_material_init(&b, NULL) == SEM_ERR_INVALID, "unknown type accepted");
    CHECK(isnan(sem_material_energy(&b, (const double[9]){1, 0, 0, 0, 1, 0, 0, 0, 1}, NULL,
                                    NULL)),
          "unknown type energy should be NaN");

    /* names round trip, aliases, rejection */
    for (int t = 0; t < SEM_MATERIAL_TYPE_COUNT; ++t) {
        sem_material_type out = (sem_material_type)-1;
        CHECK(sem_material_parse_type(sem_material_type_name(all_types[t]), &out) == SEM_OK &&
                  out == all_types[t],
              "round trip of %s", sem_material_type_name(all_types[t]));
    }
    sem_material_type out = SEM_MATERIAL_LINEAR;
    CHECK(sem_material_parse_type("Neo-Hookean", &out) == SEM_OK &&
              out == SEM_MATERIAL_NEOHOOKEAN, "Neo-Hookean alias");
    CHECK(sem_material_parse_type("STABLE-NEOHOOKEAN", &out) == SEM_OK &&
              out == SEM_MATERIAL_STABLE_NEOHOOKEAN, "STABLE-NEOHOOKEAN alias");
    CHECK(sem_material_parse_type("st_venant_kirchhoff", &out) == SEM_OK &&
              out == SEM_MATERIAL_STVK, "stvk alias");
    out = SEM_MATERIAL_LINEAR;
    CHECK(sem_material_parse_type("rubber", &out) == SEM_ERR_INVALID &&
              out == SEM_MATERIAL_LINEAR, "unknown name accepted");
    CHECK(sem_material_parse_type("", &out) == SEM_ERR_INVALID, "empty name accepted");
    CHECK(sem_material_parse_type(NULL, &out) == SEM_ERR_INVALID, "NULL name accepted");
    CHECK(strcmp(sem_material_type_name((sem_material_type)99), "unknown") == 0, "bad name");
}

int main(void)
{
    test_derivatives_against_finite_differences();
    test_rest_state_and_rotations();
    test_small_strain_limit();
    test_uniaxial_closed_forms();
    test_eigen_and_psd_projection();
    test_svd();
    test_parameters();
    return test_finish("material");
}
