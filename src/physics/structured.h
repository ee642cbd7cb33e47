/*
 * structured.h - an object's matrices kept in the form the method gives them, and the
 * solver that exploits it (internal to src/physics/).
 *
 * Every matrix of an object is "part-sparse plus low rank through Pi". Per coordinate, with
 * P = Pi (n_parts m rows, one row per part and basis function, dense over the part's group)
 * and the boundary samples s (area a_s, J_s the sample's row of J-hat, g_s its row of the
 * SEM map in coefficient space: w_si b_k(X_s - Xbar_i) for the parts i blended there):
 *
 *   M       = P^T Mz P                                   (Eq. 14, Mz per part pair)
 *   M_eps   = sum_s a_s (g_s P - J_s)^T (g_s P - J_s) + ties + P^T Bz P   (Eq. 16, blend)
 *           = S0 - P^T G - G^T P + P^T (Bb + Bz) P
 *             with S0 = sum_s a_s J_s^T J_s (sparse, one block per part), G = sum_s a_s g_s^T J_s,
 *             Bb = sum_s a_s g_s^T g_s
 *   K, K0   = P'^T Kz P'     (Kz per part pair in the shared basis, P' = pi_shared; Eq. 15)
 *   A       = P^T Az P       (the material pins' anchor, pins.h: Mz's form with k w_a for rho vol)
 *
 * (The orphan ties of mass_error.c are samples too: J = e_c, g = b(X_c - Xbar) on the part;
 * and so are the welds of object_welds.c: J = e_a - e_b, g = 0.)
 * So the system matrix A = cM M + c M_eps + cK K + cD K0 + cA A (c = 2 cE gamma) is
 *
 *   A = c S0 + V^T Mid V,   V = [P; G],   Mid = [[Z, -c I], [-c I, 0]],
 *   Z = c (Bb + Bz) + cM Mz + cK Kz + cD K0z + cA Az   (coefficient space, 3 n_parts m square)
 *
 * and Woodbury gives A^-1 = S^-1 - S^-1 V^T Cap^-1 V S^-1 with S = c S0 and
 * Cap = Mid^-1 + V S^-1 V^T = (1/c) [[F1, F2 - I], [F2^T - I, F3 - Z/c]], F = V S0^-1 V^T.
 * S0 is factorized once (CHOLMOD, scalar, the same for x, y, z), F is computed once, F1 is
 * eliminated once, and a factorization of A is the Cholesky factorization of a dense
 * coefficient-space Schur complement (at most 3 n_parts m square; structured_solver.c):
 * nothing of size n_ctrl^2 is ever formed, and a step costs about linearly in the control
 * points (plus the cube of the coefficient count).
 * The factored form cancels large terms (S0 against P^T G), so the direct solve is used as
 * the preconditioner of conjugate gradients on the exact products (M_eps x summed sample by
 * sample as above, never in factored form): one or two iterations reach round-off.
 *
 * structured_operators.c: the object's data (sample rows, P, Mz, Bb, Bz by part-pair blocks)
 *                         and products.
 * structured_solver.c:    the solver of one object's free dofs.
 */
#ifndef SEM_PHYSICS_STRUCTURED_H
#define SEM_PHYSICS_STRUCTURED_H

#include "object.h"

typedef struct sem_structured_ops {
    int r0;              /* n_parts m: coefficients per coordinate */
    /* P = Pi over all control points, CSR, rows i m + k (columns in the part's group) */
    int *p_start, *p_col;
    double *p_val;
    /* the samples of M_eps: boundary samples, then the orphan ties */
    int n_rows;
    double *area;        /* a_s, with the 5 % floor of mass_error.c */
    int *j_start, *j_col; /* J_s over control points */
    double *j_val;
    int *g_start, *g_idx; /* g_s over coefficients (i m + k) */
    double *g_val;
    /* Mz with density, Bb, Bz (blend, over gamma), Az (the pins' anchor; NULL without pins):
     * r0 x r0, stored by part-pair blocks (m x m, row-major) for the pairs (a, b) with any
     * non-zero entry: nb_part lists the parts b of part a, ascending, from nb_start[a]; entry
     * e's blocks start at e m^2 */
    int *nb_start, *nb_part;
    double *Mz, *Bb, *Bz, *Az;
} sem_structured_ops;

/* structured_operators.c: builds o->ops from the discretization, the pair blocks Mz, Bz and
 * Az of mass_error.c (n_pairs x m x m, or NULL), the orphan ties (control point, its part,
 * weight) and the welds of o (o->weld_ctrl: rows e_a - e_b of weight weld_weight, no
 * coefficient part). */
sem_status sem_structured_init(sem_object *o, const double *Mz_pairs, const double *Bz_pairs,
                               const double *Az_pairs, int n_ties, const int *tie_ctrl, const int *tie_part,
                               double tie_weight, double weld_weight, sem_error *err);
void sem_structured_free(sem_object *o);
/* y = cM M x + 2 cE M_eps x + cK K x + cD K0 x + cA A x over all the object's dofs (x, y:
 * 3 n_ctrl). */
void sem_structured_multiply(const sem_object *o, double cM, double cE, double cK, double cD, double cA,
                             const double *x, double *y);
/* The coefficient-space stiffness of part pair (a, b) in the parts' own bases:
 * out (3m x 3m, rows 3k + d of a, columns 3l + d' of b) = R_a^T Kz_ab R_b, from a shared-basis
 * block (layout of o->Kz) or NULL for zero. */
void sem_structured_own_basis(const sem_object *o, int a, int b, const double *Kz_ab, int transpose,
                              double *out);

typedef struct sem_structured_solver sem_structured_solver;
/* The solver of o's free dofs (o->free_index). */
sem_status sem_structured_solver_create(sem_object *o, sem_structured_solver **out, sem_error *err);
void sem_structured_solver_destroy(sem_structured_solver *s);
/* The matrix c[0] M + 2 c[1] M_eps + c[2] K + c[3] K0 + c[4] A (c[1] includes gamma), with K
 * the object's current Kz; c[1] > 0. */
void sem_structured_solver_set(sem_structured_solver *s, const double c[5]);
sem_status sem_structured_solver_factorize(sem_structured_solver *s, sem_error *err);
/* x = A^-1 b over the object's free dofs (3 n_free, interleaved; x may alias b). */
sem_status sem_structured_solver_solve(sem_structured_solver *s, const double *b, double *x,
                                       sem_error *err);
double sem_structured_solver_factor_seconds(const sem_structured_solver *s);
/* The factor of the rest matrix: the current coefficients with K0 in place of K (made once,
 * again when the coefficients change; *factored says whether this call factored). The
 * current factor is kept apart from it. */
/* The order of its coefficient-space factor (3 k). */
int sem_structured_solver_coefficients(const sem_structured_solver *s);
sem_status sem_structured_solver_factorize_rest(sem_structured_solver *s, int *factored, sem_error *err);
/* x = A^-1 b for the current matrix by conjugate gradients preconditioned with the rest
 * factor, at most max_it iterations; *solved = 0 when that did not reach the solver's
 * tolerance (x is then undefined; not an error). */
sem_status sem_structured_solver_solve_rest(sem_structured_solver *s, const double *b, double *x, int max_it,
                                            int *solved, sem_error *err);

#endif
