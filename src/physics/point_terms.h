/*
 * point_terms.h - the one entry point through which terms acting on surface points reach a
 * system's linear system (internal to src/physics/; contact's Hessian uses it).
 *
 * A *point term* is a point x = sum_j w_j q_j of one or two objects' control points (a
 * collision mesh vertex x = J q, or the difference x_A - x_B of points of two objects, whose
 * weights for B are negative) and a symmetric positive semi-definite 3 x 3 matrix H in the
 * world frame. Its meaning is the Hessian contribution J^T H J over the system's dofs.
 * Callers compute their own energies and gradients (J^T g); what they hand to the solver is
 * only this list. The list is rebuilt whenever the terms change (every Newton iteration).
 *
 *   sem_system_fill(s, ...);                       the objects' own matrices
 *   sem_system_set_point_terms(s, lists, c, n);    + sum_l c_l sum_(t in list l) J^T H J
 *   sem_system_factorize(s, err);
 *
 * sem_point_terms_multiply is the matching product y += c A_t x with the matrix A_t that
 * sem_system_set_point_terms adds (what a linearization's right-hand side needs).
 *
 * The implementation (point_terms.c) is tied to the solver behind system.h and is the one
 * file to change with it. Today's solver: the entries of one object's group (a point's
 * weights are the control points of one part, so of one group) are in the system's
 * pattern; entries between two objects are there when the system was created with their
 * groups' coupling block (sem_system_create_coupled; contact asks for the blocks of the
 * parts near each other, contact_world.c). A term whose cross blocks are missing adds
 * m J_i^T H J_i for each of its m (object, group) sets i instead: the matrix
 * (sum_i J_i x)^T H (sum_i J_i x) <= m sum_i (J_i x)^T H (J_i x) is bounded from above, so
 * the system stays positive definite and Newton's steps stay descent directions (it
 * converges, more slowly); the forces, computed by the caller from the energy's gradient,
 * stay equal and opposite.
 */
#ifndef SEM_PHYSICS_POINT_TERMS_H
#define SEM_PHYSICS_POINT_TERMS_H

#include "system.h"

typedef struct sem_point_weight {
    int object;   /* index into the system's objects */
    int ctrl;     /* control point of that object */
    double w;     /* weight (negative for the far side of a relative point) */
} sem_point_weight;

typedef struct sem_point_term {
    int first, count; /* its weights in sem_point_terms.weights */
    double H[9];      /* symmetric PSD, row-major */
} sem_point_term;

typedef struct sem_point_terms {
    int n, cap;
    sem_point_term *terms;
    int n_weights, cap_weights;
    sem_point_weight *weights;
} sem_point_terms;

void sem_point_terms_init(sem_point_terms *t);
void sem_point_terms_free(sem_point_terms *t);
void sem_point_terms_clear(sem_point_terms *t);
/* Appends a term (weights and H copied). */
sem_status sem_point_terms_push(sem_point_terms *t, const sem_point_weight *weights, int count,
                                const double H[9], sem_error *err);
/* Adds scale[l] x the Hessian of lists[l] to the system's values, l < n_lists, after the
 * coupling blocks (which only point terms write) are zeroed: after sem_system_fill (or the
 * assembly that fills the objects' blocks), before sem_system_factorize; with n_lists 0 it
 * only zeroes. Pinned control points drop out. */
void sem_system_set_point_terms(sem_system *s, const sem_point_terms *const *lists, const double *scale,
                                int n_lists);
/* y += scale A_t x over the system's full vectors (n_dofs; pinned points included), A_t the
 * matrix sem_system_add_point_terms adds. */
void sem_point_terms_multiply(const sem_system *s, const sem_point_terms *t, double scale,
                              const double *x, double *y);

#endif
