/*
 * shared_kernels.h - kernels that the elastic assembly (assembly.c), the mass and error
 * matrices (mass_error.c) and the structured solver (structured_operators.c) share, in a leaf
 * file of src/physics/ (internal): products with pi_shared in z-space (the polynomial
 * coefficients in one basis shared by all parts; assembly.h, "Design"), the change of basis,
 * the centred q, and the rows of the error energy.
 */
#ifndef SEM_PHYSICS_SHARED_KERNELS_H
#define SEM_PHYSICS_SHARED_KERNELS_H

#include "object.h"

/* Part pair pr is a <= b and shares a quadrature point: its stiffness block Kz is formed
 * (W rows list parts in increasing order). */
int sem_pair_has_points(const sem_object *o, int pr);
/* zi = rows x over part i's group (n_rows rows of the group's size, row-major; zi n_rows x 3,
 * coordinates interleaved): Pi_i x with rows pi_dense[i], pi_shared x with pi_shared[i]. */
void sem_part_rows_multiply(const sem_object *o, int i, const double *rows, int n_rows, const double *x,
                            double *zi);
/* z = pi_shared x (per part ma x 3, coordinates interleaved), x over all control points. */
void sem_shared_coefficients(const sem_object *o, const double *x, double *z);
/* y += pi_shared^T z. */
void sem_shared_add_transpose(const sem_object *o, const double *z, double *y);
/* y += pi_shared^T (ca Ka + cb Kb) pi_shared x with Ka, Kb laid out as o->Kz (Kb may be
 * NULL). work: 2 n_parts 3 ma doubles. */
void sem_stiffness_z_multiply(const sem_object *o, double ca, const double *Ka, double cb, const double *Kb,
                              const double *x, double *y, double *work);
/* T (m x m, row-major) with b(y + s) = T b(y): from a part's own basis b(X - Xbar_i),
 * s = ref_X - Xbar_i, to the shared one b(X - ref_X) (see setup_stiffness in assembly.c). */
void sem_basis_shift(int m, const double s[3], double *T);
/* q - ref (ref NULL: q itself) minus its mean over the control points (per coordinate), in
 * o->qc. Elastic and error energies are translation invariant, but evaluated at q far from
 * the origin their round-off grows with |q|; a body that travels (free fall, a thrown object)
 * would then slowly lose momentum conservation. Evaluating at the centred q removes that.
 * The error energy takes ref = q0, the displacement (mass_error.c, sem_error_energy). */
const double *sem_centered(sem_object *o, const double *q, const double *ref);

/* The boundary samples' weights in the error matrix are their areas, each at least 5 % of
 * its part's mean sample area, since a collapsed edge (a sphere's pole) has a zero area
 * element and its samples would drop out, and with them the only information that fixes the
 * control points of the collapsed row (the system would be singular). */
/* The rows of the error energy (Eq. 16): per boundary sample one row, the residual of the
 * blended map (entry -1), except on a seam under SEM_SEAMS_GEOMETRIC (a sample whose W_samples
 * row has several parts): one row per part, the residual of that part's polynomial alone
 * (entry: the W_samples entry), weighted by the part's weight times the sample's seam weight
 * (sem_discretization.sample_seam, with the floor of sem_sample_weights). In sample order. */
typedef struct sem_error_row {
    int sample, entry;
    double weight;
} sem_error_row;
sem_status sem_error_rows(const sem_object *o, sem_error_row **rows, int *n_rows, sem_error *err);
/* The error rows' floor per part: 5 % of the part's mean sample area (caller frees). */
double *sem_error_part_floors(const sem_discretization *d, int n_parts);

#endif
