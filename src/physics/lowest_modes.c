/*
 * lowest_modes.c - the lowest vibration modes K x = lambda M x of a free object, for counting
 * its zero-energy (spurious) modes (issue 11; see modes.c for what is counted).
 *
 * Block shift-invert subspace iteration with Rayleigh-Ritz (Bathe's subspace iteration):
 *   Y = (K + sigma M)^-1 M X,  Y M-orthonormalised (Cholesky QR, twice),
 *   Ritz pairs of Y^T K Y (LAPACK dsyev),  X = Y V.
 * The 6 rigid motions, which K annihilates exactly (the error energy vanishes for every affine
 * motion and the rest stiffness for infinitesimal rotations), are projected out of every
 * iterate (M-orthogonal complement), so every eigenvalue found near 0 is a spurious mode,
 * with multiplicity up to the block size. Convergence of mode i goes like
 * ((lambda_i + sigma) / (lambda_{b+1} + sigma))^iterations: near-zero modes converge in a few
 * iterations when sigma is small against the first true elastic mode.
 * The start block is deterministic (a fixed linear congruential sequence), so the result is
 * the same on every run.
 */
#include "lowest_modes.h"
#include "util/free_all.h"

#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dot(size_t n, const double *a, const double *b)
{
    double s = 0;
    for (size_t i = 0; i < n; ++i) s += a[i] * b[i];
    return s;
}

/* M-orthonormalises the b columns of Y (column-major n x b) against the columns of R
 * (r of them, M-orthonormal, with MR = M R given) and among themselves. MY receives M Y.
 * Returns the number of columns kept (dependent ones are dropped), -1 on failure. */
static int m_orthonormalize(const sem_mode_operator *op, size_t n, int b, double *Y, double *MY,
                            const double *R, const double *MR, int r)
{
    for (int pass = 0; pass < 2; ++pass) {
        for (int j = 0; j < b; ++j) {
            double *y = Y + (size_t)j * n;
            for (int k = 0; k < r; ++k) {
                double c = dot(n, MR + (size_t)k * n, y);
                const double *rk = R + (size_t)k * n;
                for (size_t i = 0; i < n; ++i) y[i] -= c * rk[i];
            }
        }
    }
    int kept = 0;
    for (int pass = 0; pass < 2; ++pass) {
        kept = 0;
        for (int j = 0; j < b; ++j) {
            double *y = Y + (size_t)j * n, *my = MY + (size_t)j * n;
            /* Gram-Schmidt against the kept columns (modified, in the M inner product) */
            if (op->mult_M(op->user, y, my) != 0) return -1;
            for (int k = 0; k < kept; ++k) {
                const double *yk = Y + (size_t)k * n, *myk = MY + (size_t)k * n;
                double c = dot(n, myk, y);
                for (size_t i = 0; i < n; ++i) {
                    y[i] -= c * yk[i];
                    my[i] -= c * myk[i];
                }
            }
            double nn = dot(n, y, my);
            if (!(nn > 1e-28) || !isfinite(nn)) continue; /* dependent: drop */
            double s = 1.0 / sqrt(nn);
            double *dst = Y + (size_t)kept * n, *mdst = MY + (size_t)kept * n;
            for (size_t i = 0; i < n; ++i) {
                dst[i] = y[i] * s;
                mdst[i] = my[i] * s;
            }
            kept++;
        }
        b = kept;
    }
    return kept;
}

int sem_lowest_modes(const sem_mode_operator *op, size_t n, int block, int want, int max_iter, double coarse_above,
                     const double *rigid, int n_rigid, double *values, double *vectors)
{
    if (!op || n == 0 || block < 1 || want < 1 || want > block) return -1;
    if ((size_t)block > n) block = (int)n;
    if (want > block) want = block;
    double *X = malloc((size_t)block * n * sizeof *X);
    double *MX = malloc((size_t)block * n * sizeof *MX);
    double *R = n_rigid > 0 ? malloc((size_t)n_rigid * n * sizeof *R) : NULL;
    double *MR = n_rigid > 0 ? malloc((size_t)n_rigid * n * sizeof *MR) : NULL;
    double *KY = malloc((size_t)block * n * sizeof *KY);
    double *H = malloc((size_t)block * block * sizeof *H);
    double *w = malloc((size_t)block * sizeof *w);
    double *prev = malloc((size_t)block * sizeof *prev);
    int rc = -1;
    if (!X || !MX || !KY || !H || !w || !prev || (n_rigid > 0 && (!R || !MR))) goto done;

    /* the rigid motions, M-orthonormalised */
    int r = 0;
    if (n_rigid > 0) {
        memcpy(R, rigid, (size_t)n_rigid * n * sizeof *R);
        r = m_orthonormalize(op, n, n_rigid, R, MR, NULL, NULL, 0);
        if (r < 0) goto done;
    }
    /* deterministic start block */
    unsigned long long seed = 88172645463325252ull;
    for (size_t i = 0; i < (size_t)block * n; ++i) {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        X[i] = (double)(seed >> 11) / 9007199254740992.0 - 0.5;
    }
    int b = m_orthonormalize(op, n, block, X, MX, R, MR, r);
    if (b < want) goto done;
    for (int k = 0; k < block; ++k) prev[k] = INFINITY;
    int converged = 0;
    for (int it = 0; it < max_iter && !converged; ++it) {
        /* Y = (K + sigma M)^-1 M X (MX holds M X) */
        for (int j = 0; j < b; ++j)
            if (op->solve_shifted(op->user, MX + (size_t)j * n, X + (size_t)j * n) != 0) goto done;
        b = m_orthonormalize(op, n, b, X, MX, R, MR, r);
        if (b < want) goto done;
        /* Rayleigh-Ritz: H = Y^T K Y */
        for (int j = 0; j < b; ++j)
            if (op->mult_K(op->user, X + (size_t)j * n, KY + (size_t)j * n) != 0) goto done;
        for (int i = 0; i < b; ++i)
            for (int j = i; j < b; ++j)
                H[(size_t)i * b + j] = H[(size_t)j * b + i] =
                    0.5 * (dot(n, X + (size_t)i * n, KY + (size_t)j * n) +
                           dot(n, X + (size_t)j * n, KY + (size_t)i * n));
        if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', b, H, b, w) != 0) goto done;
        /* X = Y V (columns of H, row-major: H[i * b + k] is V_ik), in KY as scratch */
        for (int k = 0; k < b; ++k) {
            double *dst = KY + (size_t)k * n;
            memset(dst, 0, n * sizeof *dst);
            for (int i = 0; i < b; ++i) {
                double c = H[(size_t)i * b + k];
                const double *y = X + (size_t)i * n;
                for (size_t q = 0; q < n; ++q) dst[q] += c * y[q];
            }
        }
        memcpy(X, KY, (size_t)b * n * sizeof *X);
        for (int j = 0; j < b; ++j)
            if (op->mult_M(op->user, X + (size_t)j * n, MX + (size_t)j * n) != 0) goto done;
        converged = 1;
        double scale = fabs(w[b - 1]) > 0 ? fabs(w[b - 1]) : 1.0;
        for (int k = 0; k < want; ++k) {
            double change = fabs(w[k] - prev[k]);
            int coarse = coarse_above > 0 && w[k] > coarse_above && change <= SEM_MODES_COARSE * w[k];
            if (!(change <= 1e-10 * scale + 1e-8 * fabs(w[k])) && !coarse) converged = 0;
        }
        for (int k = 0; k < b; ++k) prev[k] = w[k];
    }
    for (int k = 0; k < want; ++k) values[k] = w[k];
    if (vectors) memcpy(vectors, X, (size_t)want * n * sizeof *vectors);
    rc = converged ? 0 : 1;
done:
    SEM_FREE_ALL(X, MX, R, MR, KY, H, w, prev);
    return rc;
}
