/*
 * linear_solver.h - symmetric positive definite solves for the time steppers.
 *
 * The matrix pattern (upper triangle, CSC) is fixed for a simulation, so the symbolic
 * analysis is done once (cholmod_analyze) and only the numeric factorization is repeated
 * every step, as CHOLMOD intends. Small SEM systems are nearly dense; with SEM_SOLVER_AUTO
 * a fixed rule by size picks dense LAPACK for the smallest and CHOLMOD for the rest (see
 * SEM_DENSE_MAX_DOFS), so that the same scene gives the same bits on every run.
 */
#ifndef SEM_LINEAR_SOLVER_H
#define SEM_LINEAR_SOLVER_H

#include "sem/simulation.h"

typedef struct sem_linear_solver sem_linear_solver;

/* n x n, upper triangle in CSC (col_start n+1, row sorted within each column, row <= col).
 * The arrays are copied. */
sem_status sem_linear_solver_create(int n, const int *col_start, const int *row,
                                    sem_solver_choice choice, sem_linear_solver **out,
                                    sem_error *err);
/* A second solver of the same pattern and order (its own values and factor): positions
 * remapped for s are valid for it. */
sem_status sem_linear_solver_clone_pattern(const sem_linear_solver *s, sem_linear_solver **out,
                                           sem_error *err);
void sem_linear_solver_destroy(sem_linear_solver *s);
/* The solver stores the matrix in its own (fill-reducing) order: translates positions in
 * the pattern given to create (-1 stays -1) into positions of sem_linear_solver_values. */
void sem_linear_solver_remap(const sem_linear_solver *s, int *positions, size_t count);
/* The values, at the remapped positions, to fill before each factorization. */
double *sem_linear_solver_values(sem_linear_solver *s);
sem_status sem_linear_solver_factorize(sem_linear_solver *s, sem_error *err);
/* x = A^-1 b (x may alias b). */
sem_status sem_linear_solver_solve(sem_linear_solver *s, const double *b, double *x,
                                   sem_error *err);
/* x = A^-1 b with the factor alone, without the step of iterative refinement (for callers
 * that iterate themselves). */
sem_status sem_linear_solver_solve_plain(sem_linear_solver *s, const double *b, double *x,
                                         sem_error *err);
/* r = b - A x with the values of the last factorization (same bits on any thread count). */
/* With scale, also |A| |x| (for a componentwise backward error). */
void sem_linear_solver_residual(sem_linear_solver *s, const double *b, const double *x, double *r,
                                double *scale);
const char *sem_linear_solver_name(const sem_linear_solver *s);
double sem_linear_solver_last_factor_seconds(const sem_linear_solver *s);
/* Non-zeros of the full symmetric matrix as a percentage of n^2. */
double sem_linear_solver_nnz_percent(const sem_linear_solver *s);

#endif
