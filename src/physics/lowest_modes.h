/*
 * lowest_modes.h - the lowest eigenpairs of K x = lambda M x by shift-invert subspace
 * iteration (internal to src/physics/; see lowest_modes.c).
 */
#ifndef SEM_PHYSICS_LOWEST_MODES_H
#define SEM_PHYSICS_LOWEST_MODES_H

#include <stddef.h>

/* The operators of the problem on vectors of length n; each returns 0 on success. */
typedef struct sem_mode_operator {
    void *user;
    int (*mult_M)(void *user, const double *x, double *y);        /* y = M x */
    int (*mult_K)(void *user, const double *x, double *y);        /* y = K x */
    int (*solve_shifted)(void *user, const double *b, double *x); /* x = (K + sigma M)^-1 b */
} sem_mode_operator;

/* The `want` smallest eigenvalues (ascending, into values) of K x = lambda M x in the
 * M-orthogonal complement of the n_rigid columns of `rigid` (n x n_rigid, column-major; may be
 * NULL), with a block of `block` >= want vectors and at most max_iter iterations; vectors (may
 * be NULL) receives the M-orthonormal eigenvectors (n x want, column-major). A value is
 * converged when its Ritz value changes by at most 1e-10 of the largest plus 1e-8 of itself
 * in an iteration, or, above `coarse_above` (a level the caller only needs to know a value is
 * above; 0: none), by at most SEM_MODES_COARSE of itself. Returns 0 when converged, 1 when
 * max_iter was reached (values are the last Ritz values), -1 on failure. */
#define SEM_MODES_COARSE 1e-4
int sem_lowest_modes(const sem_mode_operator *op, size_t n, int block, int want, int max_iter, double coarse_above,
                     const double *rigid, int n_rigid, double *values, double *vectors);

#endif
