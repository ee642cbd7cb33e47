/*
 * polynomial_basis.c - the polynomial basis b(X - Xbar) of every part's deformation
 * (Eq. 3): 1, x, y, z for order 1, plus xy, xz, yz, x^2, y^2, z^2 for order 2, and its
 * gradient. Shared by the preprocessing (operators) and the simulator, below both, so
 * that neither pulls in the other.
 */
#include "sem/polynomial.h"

#include <string.h>

void sem_polynomial_basis(int order, const double dX[3], double *b, double *db)
{
    const double x = dX[0], y = dX[1], z = dX[2];
    const int m = order >= 2 ? 10 : 4;
    if (b) {
        b[0] = 1.0;
        b[1] = x;
        b[2] = y;
        b[3] = z;
        if (m == 10) {
            b[4] = x * y;
            b[5] = x * z;
            b[6] = y * z;
            b[7] = x * x;
            b[8] = y * y;
            b[9] = z * z;
        }
    }
    if (db) {
        memset(db, 0, (size_t)(3 * m) * sizeof *db);
        for (int e = 0; e < 3; ++e) db[e * m + 1 + e] = 1.0;
        if (m == 10) {
            /* d/dX */
            db[0 * m + 4] = y;
            db[0 * m + 5] = z;
            db[0 * m + 7] = 2 * x;
            /* d/dY */
            db[1 * m + 4] = x;
            db[1 * m + 6] = z;
            db[1 * m + 8] = 2 * y;
            /* d/dZ */
            db[2 * m + 5] = x;
            db[2 * m + 6] = y;
            db[2 * m + 9] = 2 * z;
        }
    }
}
