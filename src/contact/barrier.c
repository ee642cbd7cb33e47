/*
 * barrier.c - IPC's log barrier and its edge-edge mollifier (see barrier.h).
 */
#include "barrier.h"

#include <math.h>

#include "geometry/vector3.h"

double sem_barrier(double d, double dhat, double *db, double *d2b)
{
    if (db) *db = 0;
    if (d2b) *d2b = 0;
    if (!(d < dhat)) return 0;
    if (!(d > 0)) return INFINITY;
    double e = d - dhat, l = log(d / dhat);
    if (db) *db = -2 * e * l - e * e / d;
    if (d2b) *d2b = -2 * l - 4 * e / d + e * e / (d * d);
    return -e * e * l;
}

double sem_edge_mollifier(const double a0[3], const double a1[3], const double b0[3], const double b1[3],
                          double eps_x, double grad[4][3])
{
    double e0[3] = {a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]};
    double e1[3] = {b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]};
    double c[3];
    cross3(e0, e1, c);
    double x = dot3(c, c);
    if (grad)
        for (int i = 0; i < 4; ++i) grad[i][0] = grad[i][1] = grad[i][2] = 0;
    if (!(eps_x > 0) || !(x < eps_x)) return 1;
    double r = x / eps_x;
    if (grad) {
        /* dm/dx = (2 - 2 r) / eps_x; dx/de0 = 2 e1 x c, dx/de1 = 2 c x e0 */
        double dm = (2 - 2 * r) / eps_x, g0[3], g1[3];
        cross3(e1, c, g0);
        cross3(c, e0, g1);
        for (int k = 0; k < 3; ++k) {
            grad[0][k] = -2 * dm * g0[k];
            grad[1][k] = 2 * dm * g0[k];
            grad[2][k] = -2 * dm * g1[k];
            grad[3][k] = 2 * dm * g1[k];
        }
    }
    return (2 - r) * r;
}
