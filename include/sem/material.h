/*
 * sem/material.h - hyperelastic energy densities psi(F) and their derivatives (paper Sec. 7.1).
 *
 * The elastic energy of an object is V(q) = sum_p vol_p psi(F_p) over its volume quadrature
 * points, with F_p = B_p q linear in the control points (Eq. 15), so all that physics needs
 * from a material is psi, P = dpsi/dF and H = d2psi/dF2 at one F. These are pure functions
 * (no state, no allocation, thread safe) because they run per quadrature point per Newton
 * iteration.
 *
 * Conventions: F is 3x3 row-major, F[3*i+j] = dx_i/dX_j. P uses the same layout. H is 9x9
 * row-major over that flattening, H[9*a+b] = dP_a/dF_b with a = 3i+j, b = 3k+l; it is
 * symmetric. All materials share the Lame parameters mu, lambda of linear elasticity at rest:
 * psi(I) = 0, P(I) = 0, and d2psi/dF2(I) equals the linear material's Hessian.
 *
 * Energies are evaluated from the displacement gradient G = F - I (I1 - 3 = 2 tr G + |G|^2,
 * J - 1 from the invariants of G, log1p), so tiny strains of stiff objects keep full relative
 * precision instead of cancelling against the rest-state constants; a line search that
 * compares energies near convergence depends on that.
 */
#ifndef SEM_MATERIAL_H
#define SEM_MATERIAL_H

#include "sem/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sem_material_type {
    /* The paper's: psi = mu/2 (I1 - 3) - mu ln J + lambda/2 (ln J)^2; +INFINITY when J <= 0. */
    SEM_MATERIAL_NEOHOOKEAN = 0,
    /* Smith, de Goes, Kim 2018, Eq. 14 with the Lame re-parametrisation of their Sec. 3.4
     * (mu' = 4/3 mu, lambda' = lambda + 5/6 mu): psi = mu'/2 (I1 - 3) + lambda'/2 (J - alpha)^2
     * - mu'/2 ln(I1 + 1) - const, alpha = 1 + 3 mu' / (4 lambda'). Defined for inverted F. */
    SEM_MATERIAL_STABLE_NEOHOOKEAN,
    /* Fixed co-rotated (Stomakhin et al. 2012): psi = mu |F - R|^2 + lambda/2 (J - 1)^2 with R
     * the rotation of the rotation-variant SVD (det R = +1, the sign of an inversion goes to
     * the smallest singular value). */
    SEM_MATERIAL_COROTATED,
    /* St. Venant-Kirchhoff: E = (F^T F - I)/2, psi = mu E:E + lambda/2 (tr E)^2. */
    SEM_MATERIAL_STVK,
    /* Linear elasticity: eps = (F + F^T)/2 - I, psi = mu eps:eps + lambda/2 (tr eps)^2. */
    SEM_MATERIAL_LINEAR
} sem_material_type;

#define SEM_MATERIAL_TYPE_COUNT 5

typedef struct sem_material {
    sem_material_type type;
    double density;        /* rho, kg/m^3 */
    double youngs_modulus; /* E, Pa */
    double poisson_ratio;  /* nu, -1 < nu < 0.5 */
    double mu, lambda;     /* Lame parameters, set by sem_material_init from E and nu */
} sem_material;

/* Neo-Hookean, rho 1000, E 1e6, nu 0.45 (the paper's Fig. 12 beams), mu and lambda set. */
sem_material sem_default_material(void);

/* Validates type, density > 0, E > 0, -1 < nu < 0.5 (all finite) and sets
 * mu = E / (2 (1 + nu)), lambda = E nu / ((1 + nu) (1 - 2 nu)). SEM_ERR_INVALID with a
 * message naming the parameter otherwise (m is then left unchanged). */
sem_status sem_material_init(sem_material *m, sem_error *err);

/* "neohookean", "stable_neohookean", "corotated", "stvk", "linear" (case-insensitive; '-'
 * and '_' interchangeable; also "neo_hookean", "snh", "fixed_corotated",
 * "st_venant_kirchhoff"). SEM_ERR_INVALID for an unknown name (*out untouched). */
sem_status sem_material_parse_type(const char *name, sem_material_type *out);
/* Canonical name as accepted by sem_material_parse_type; "unknown" for a bad value. */
const char *sem_material_type_name(sem_material_type t);

/* psi(F); P = dpsi/dF and H = d2psi/dF2 when non-NULL (layout above). Neo-Hookean returns
 * +INFINITY for det F <= 0 (energy undefined, so a line search rejects the step) and then
 * fills P and H with NaN. H is the exact Hessian, possibly indefinite: project it with
 * sem_project_psd_9x9 for Newton. NaN for an unknown type. m and F must be non-NULL. Cost of
 * psi + P + H (-O2, this machine): neo-Hookean ~0.15 us, stable neo-Hookean and StVK ~0.18 us,
 * co-rotated ~0.7 us (3x3 SVD), linear ~0.04 us. */
double sem_material_energy(const sem_material *m, const double F[9], double P[9], double H[81]);

/* Projects a symmetric 9x9 matrix (only its symmetric part is used) onto the positive
 * semi-definite cone in the Frobenius norm: negative eigenvalues are clamped to 0. A
 * Cholesky factorisation first detects the common positive definite case, which is
 * returned bit-for-bit unchanged (~0.17 us); otherwise cyclic Jacobi (no LAPACK: thread safe
 * inside OpenMP loops, accurate to roundoff, ~0.7 us) computes the eigensystem. */
void sem_project_psd_9x9(double H[81]);

/* Eigen-decomposition of a symmetric n x n matrix (n <= 9) by cyclic Jacobi:
 * A = V diag(w) V^T with V row-major (eigenvectors in columns), w unsorted. A is
 * overwritten. Used by the projection above and the 3x3 SVD. */
void sem_symmetric_eigen(int n, double *A, double *V, double *w);

/* Rotation-variant SVD of a 3x3 matrix (McAdams et al. 2011: Jacobi on F^T F, then Givens
 * QR of F V): F = U diag(sigma) V^T with U, V rotations (det +1), |sigma| sorted
 * descending (to roundoff), sigma[0], sigma[1] >= 0 and sigma[2] carrying the sign of det F. */
void sem_svd_3x3(const double F[9], double U[9], double sigma[3], double V[9]);

#ifdef __cplusplus
}
#endif
#endif
