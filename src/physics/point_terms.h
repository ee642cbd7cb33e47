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
 *   sem_system_fill(s, ...);                 the objects' own matrices
 *   sem_system_add_point_terms(s, &t, c);    + c sum J^T H J
 *   sem_system_factorize(s, err);
 *
 * sem_point_terms_multiply is the matching product y += c A_t x with the matrix A_t that
 * sem_system_add_point_terms adds (what a linearization's right-hand side needs).
 *
 * The implementation (point_terms.c) is tied to the solver behind system.h and is the one
 * file to change with it. Today's solver: the entries of one object's group (a point's
 * weights are the control points of one part, so of one group) are in the system's
 * pattern; entries between two objects are not. A term spanning m > 1 (object, group) sets
 * therefore adds m J_i^T H J_i for each set i instead of the cross blocks: the matrix
 * (sum_i J_i x)^T H (sum_i J_i x) <= m sum_i (J_i x)^T H (J_i x) is bounded from above, so
 * the system stays positive definite and Newton's steps stay descent directions (with a
 * line search the solve converges to the same answer, in a few more iterations); the
 * forces, computed by the caller from the energy's gradient, stay equal and opposite. A
 * solver with a coupling term can add the cross blocks exactly here instead.
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
/* Adds scale x the terms' Hessian to the system's values: after sem_system_fill (or the
 * assembly that fills them), before sem_system_factorize. Pinned control points drop out. */
void sem_system_add_point_terms(sem_system *s, const sem_point_terms *t, double scale);
/* y += scale A_t x over the system's full vectors (n_dofs; pinned points included), A_t the
 * matrix sem_system_add_point_terms adds. */
void sem_point_terms_multiply(const sem_system *s, const sem_point_terms *t, double scale,
                              const double *x, double *y);

#endif
