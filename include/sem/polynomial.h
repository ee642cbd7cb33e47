/*
 * sem/polynomial.h - the polynomial basis b(X - Xbar) of every part's deformation (paper
 * Eq. 3): 1, x, y, z for order 1, plus xy, xz, yz, x^2, y^2, z^2 for order 2
 * (src/geometry/polynomial_basis.c). The preprocessing (sem/preprocess.h, which includes this
 * header) and the simulator both use it; so may a caller that evaluates a part's deformation.
 */
#ifndef SEM_POLYNOMIAL_H
#define SEM_POLYNOMIAL_H

/* Polynomial basis and its gradient at dX (Eq. 3): b has n_basis entries (4 for order 1, 10
 * for order 2), db 3 x n_basis (db[e * n_basis + k] = d b_k / d X_e; may be NULL). */
void sem_polynomial_basis(int order, const double dX[3], double *b, double *db);

#endif
