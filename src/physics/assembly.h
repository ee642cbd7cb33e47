/*
 * assembly.h - an object's energies, forces and matrices (internal to src/physics/):
 * the elastic terms (assembly.c) and the constant mass and error matrices (mass_error.c).
 *
 * Design. The elastic Hessian of SEM is K = sum_p vol_p B_p^T (d2psi/dF2) B_p with
 * B_p = sum_i w_pi (grad b_i)^T Pi_i (Eq. 15). Forming B_p over control points is wasteful:
 * a quadrature point sees only the few parts with non-zero weight there, but through Pi
 * each part couples every control point of the parts sharing its origin. So the work is
 * split the way the maths factors:
 *
 *   1. z-space (polynomial coefficients, m per part per coordinate, written in one basis
 *      b(X - ref) shared by all parts; see setup_stiffness in assembly.c): per point, the 3x3
 *      deformation gradient, psi, P, d2psi/dF2 and its pull-back N_p to the shared basis;
 *      then per *part pair* the 3m x 3m block sum_p w_a w_b N_p.
 *   2. q-space: K_q = Pi^T K_z Pi. Pi_i's columns are exactly the control points of part
 *      i's group (object.h), so K_q is made of dense blocks per *group pair*; each
 *      part-pair block adds Pi_i^T K_z Pi_i' into one group-pair block with dgemm.
 *   3. Optionally, as each group-pair block is formed (while it is in cache), its entries
 *      are written through the system's map into the solver's values (system.h).
 *
 * The mass matrix M (with per-point density, Eq. 14) and the error matrix M_eps (Eq. 16)
 * are constant and kept as scalar group-pair blocks. Error energy: gamma * sum_s a_s
 * |Gamma_s q - J_s q|^2 = gamma q^T M_eps q, so its Hessian is 2 gamma M_eps.
 *
 * Every per-point Hessian is projected to positive semi-definite unless the object's
 * exact_hessian is set (Newton near a minimum; see integrators.h).
 *
 * Determinism: the same bits on any thread count. The per-point sums (gradient, energy) go
 * to GRADIENT_SHARES fixed accumulators added in order (below); per-pair sums are in point
 * order by one thread each.
 */
#ifndef SEM_PHYSICS_ASSEMBLY_H
#define SEM_PHYSICS_ASSEMBLY_H

#include "object.h"
#include "shared_kernels.h"
#include "system.h"

/* The per-point loop of the elastic assembly sums into this many gradient and energy
 * accumulators (o->grad_z_share), each over fixed blocks of points, added in order
 * afterwards: the result is the same bits on any thread count (a per-thread accumulator
 * would depend on it). Blocks are n_quad / (4 x GRADIENT_SHARES) points (rounded up), so
 * every share gets 4 blocks (+-1) and the shares, spread statically over the threads, have
 * equal work. It caps that loop's parallelism at 16 threads. */
#define GRADIENT_SHARES 16

/* assembly.c: the shared basis, the point lists of the part pairs and the work space of
 * the elastic terms; assembly_chunk points are summed at a time (<= 0: 8192). */
sem_status sem_assembly_init(sem_object *o, int assembly_chunk, sem_error *err);
/* Elastic energy (into o->elastic_energy), its gradient in q (into grad_q, if not NULL)
 * and, if want_hessian, K_blocks; with fill, the system's values of the object's group
 * pairs too (see sem_system_fill_gpair). Fails (SEM_ERR_NUMERIC) when the energy is
 * undefined (an inverted element, a non-finite state). */
sem_status sem_assemble_elastic(sem_object *o, const double *q, int want_hessian, double *grad_q,
                                const sem_fill_target *fill, sem_error *err);
/* want_hessian: none, the coefficient-space blocks Kz only, or Kz and the q-space K_blocks
 * (with the fill). */
enum { SEM_HESSIAN_NONE = 0, SEM_HESSIAN_FULL = 1, SEM_HESSIAN_Z = 2, SEM_HESSIAN_POINTS = 3 };
/* (SEM_HESSIAN_POINTS keeps each point's (projected) d2psi/dF2 in o->point_H instead, for
 * the products below; q-space objects only.) Kz from the kept point Hessians. */
void sem_assemble_kz_from_points(sem_object *o);
/* |H - H0| / |H0| over the points (volume-weighted Frobenius norms), H0 the rest Hessians. */
double sem_point_hessian_change(const sem_object *o);
/* y += c K x from the kept point Hessians (minus_rest: c (K - K0) x) without forming K.
 * work: (1 + GRADIENT_SHARES) n_parts 3 ma doubles. */
void sem_point_hessian_multiply(const sem_object *o, double c, int minus_rest, const double *x, double *y,
                                double *work);
/* The q-space stage alone, from the current Kz: K_blocks (and the fill), or, for a
 * structured object, the fill's coefficients. */
sem_status sem_assemble_stiffness_blocks(sem_object *o, const sem_fill_target *fill, sem_error *err);
/* sum_p vol_p det F_p: the volume of the deformed body by the quadrature (Eq. 15's F);
 * *min_det (may be NULL) receives the smallest det F_p. Uses o->z as work. */
double sem_deformed_volume(sem_object *o, const double *q, double *min_det);

/* mass_error.c: M_blocks, E_blocks (with the orphan control points' ties), A_blocks (the
 * material pins, pins.h), and the CSR copy of M and E_blocks. */
sem_status sem_mass_error_init(sem_object *o, sem_error *err);
/* Error energy gamma q^T M_eps q (Eq. 16) and its gradient 2 gamma M_eps q (into grad). */
double sem_error_energy(sem_object *o, const double *q, double *grad);
/* y = (cM M + cE 2 M_eps) x + cK K x + cD K0 x + cA A x over all the object's dofs (A: the
 * material pins' anchor, pins.h). */
void sem_blocks_multiply(const sem_object *o, double cM, double cE, double cK, double cD, double cA,
                         const double *x, double *y);

#endif
