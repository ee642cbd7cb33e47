/*
 * system.h - the linear system of a set of objects solved together: which degrees of
 * freedom are free, the sparse pattern of the matrix, where each block entry of the objects
 * goes in it, and the linear solver (internal to src/physics/).
 *
 * Free and pinned. Pinned control points are eliminated: only free ones enter the solve,
 * and the prescribed motion of pinned ones enters the right-hand side through A_fp (see
 * integrators.c). An object numbers its free control points in order (free_index); a
 * system places the objects one after the other: object k's free point f is the system's
 * free point free_offset[k] + f (3 dofs each, coordinates interleaved), and object k's
 * 3 n_ctrl values sit at dof_offset[k] of the system's full vectors.
 *
 * One system, several objects. The system's matrix has each object's matrix as a
 * diagonal block. Today every object is solved in a system of its own (objects do not
 * interact); contact will put the objects that touch into one system and add the
 * coupling blocks between them to the pattern.
 *
 * Pattern and maps (system_layout.c). The matrix is symmetric and the objects' stiffness
 * blocks are formed for group pairs ga <= gb only (object.h). The pattern is the upper
 * triangle of the free dofs in CSC, built once; every entry of an object's blocks (9 per
 * scalar entry: the coordinate pairs) has its position in the solver's values computed
 * once (map): its own position or its mirror's, or -1 (a pinned row or column, a group
 * pair ga > gb, the lower triangle of a diagonal block). No two entries share a position,
 * so filling the matrix is one pass over the blocks, group pair by group pair, in parallel.
 *
 * The system is the only part of the simulator that knows the linear solver: the
 * integrators fill c_M M + c_E 2 gamma M_eps + c_K K + c_D K0 + c_A A (A: the material pins'
 * anchor, pins.h), factorize and solve through it. A solver that exploits the matrix's structure (blocks per group plus a low-rank
 * coupling through Pi) can replace CHOLMOD / LAPACK behind these calls alone.
 */
#ifndef SEM_PHYSICS_SYSTEM_H
#define SEM_PHYSICS_SYSTEM_H

#include "linear_solver.h"
#include "object.h"

/* A coupling block between two objects of a system: the control points of object a's
 * group ga against those of object b's group gb (a < b, system indices). Contact between
 * objects (point terms spanning two objects, point_terms.h) needs them in the pattern. */
typedef struct sem_system_coupling {
    int a, ga, b, gb;
} sem_system_coupling;

typedef struct sem_system {
    int n_objects;
    sem_object **objects;      /* not owned */
    int *free_offset;          /* n_objects + 1: first free control point of each object */
    size_t *dof_offset;        /* n_objects + 1: first of each object's 3 n_ctrl values */
    int n_free;                /* free control points (3 dofs each) */
    size_t n_dofs;             /* 3 x all control points */
    int **map;                 /* per object: per K block entry, position in the values or -1 */
    sem_linear_solver *solver; /* NULL when nothing is free (or structured) */
    /* the rest matrix's factor, kept for the run (integrators.c, "Reusing the rest
     * factor"): same pattern as solver, values cM M + cE 2 gamma M_eps + cD K0 + cA A */
    sem_linear_solver *rest;
    double rest_coef[4];
    int structured;            /* the objects' own structured solvers (structured.h) instead */
    struct sem_structured_solver **ssolver; /* per object, NULL when it has nothing free */
    double factor_s;           /* seconds of the last factorization (structured) */
    /* contact: coupling blocks, sorted (a, ga, b, gb); coupling_map[i] holds the position of
     * entry (la, d, d', lb) at (9 la + 3 d + d') |Gb| + lb, or -1 (a pinned point) */
    int n_couplings;
    sem_system_coupling *couplings;
    int **coupling_map;
} sem_system;

/* Where assembly writes an object's blocks while it forms them (sem_assemble_elastic). */
typedef struct sem_fill_target {
    sem_system *system;
    int object;                /* index into system->objects */
    double coef[5];            /* of M, 2 M_eps, K, K0, A (see sem_system_fill_gpair) */
} sem_fill_target;

/* Numbers the object's free control points (free_index, n_free) from its pinned flags. */
sem_status sem_object_free_dofs(sem_object *o, sem_error *err);

/* The system of the given objects (each with its free dofs numbered): its pattern, maps
 * and solver. Sets every object's system. */
sem_status sem_system_create(sem_object **objects, int n_objects, sem_solver_choice choice,
                             sem_system **out, sem_error *err);
/* The same with coupling blocks between objects (copied; any order, duplicates allowed). */
sem_status sem_system_create_coupled(sem_object **objects, int n_objects, const sem_system_coupling *couplings,
                                     int n_couplings, sem_solver_choice choice, sem_system **out, sem_error *err);
/* The coupling block (a, ga, b, gb) with a < b, or -1. */
int sem_system_find_coupling(const sem_system *s, int a, int ga, int b, int gb);
void sem_system_destroy(sem_system *s);

/* The solver's values of object k's group pair g: c[0] M + c[1] 2 M_eps + c[2] K + c[3] K0
 * + c[4] A (c[1] includes the object's gamma; A the material pins' anchor, pins.h: a constant
 * potential's Hessian, so c[4] is the coefficient a Hessian gets, h^2 in the linearly
 * implicit step, 1 in Newton). Group pairs write distinct positions. */
void sem_system_fill_gpair(sem_system *s, int k, int g, const double c[5], double *val);
/* All values: cM M + cE gamma_k 2 M_eps + cK K + cD K0 + cA A for every object k. */
void sem_system_fill(sem_system *s, double cM, double cE, double cK, double cD, double cA);
/* Structured systems: the matrix of object k is c[0] M + 2 c[1] M_eps + c[2] K + c[3] K0 +
 * c[4] A with its current K (sem_assemble_elastic records it this way when given a fill
 * target). */
void sem_system_set_object(sem_system *s, int k, const double c[5]);
/* The values to fill (NULL when nothing is free or the system is structured). */
double *sem_system_values(sem_system *s);
sem_status sem_system_factorize(sem_system *s, sem_error *err);
/* Seconds of the last factorization. */
double sem_system_factor_seconds(const sem_system *s);
/* x = A^-1 b over the free dofs (x may alias b). */
sem_status sem_system_solve(sem_system *s, const double *b, double *x, sem_error *err);

/* The factor of the rest matrix cM M + cE 2 gamma_k M_eps + cD K0 + cA A (q-space systems):
 * made the first time, and again only when the coefficients change; *factored says whether
 * this call factored. */
sem_status sem_system_factorize_rest(sem_system *s, double cM, double cE, double cD, double cA, int *factored,
                                    sem_error *err);
double sem_system_rest_factor_seconds(const sem_system *s);
/* x = R^-1 b with the rest factor alone (no refinement; the caller iterates). */
sem_status sem_system_solve_rest(sem_system *s, const double *b, double *x, sem_error *err);

/* Structured systems: x = A^-1 b by each object's conjugate gradients preconditioned with its
 * rest factor (made the first time; counted into *factorizations and *factor_s), at most
 * max_it iterations; nothing is tried when a coefficient-space factor is larger than
 * max_order (the rest factor would double its memory). *solved = 0: not converged (x
 * undefined, not an error). */
sem_status sem_system_solve_structured_rest(sem_system *s, int max_order, int max_it, const double *b, double *x,
                                           int *solved, long *factorizations, double *factor_s, sem_error *err);
/* r = b - R x over the free dofs, R the rest matrix. */
void sem_system_residual_rest(sem_system *s, const double *b, const double *x, double *r, double *scale);

/* Free dofs of a full vector (the objects' 3 n_ctrl values at dof_offset) and back. */
void sem_system_gather_free(const sem_system *s, const double *full, double *free_values);
void sem_system_scatter_free(const sem_system *s, const double *free_values, double *full);

#endif
