/* flatness.c - see geometry/flatness.h. */
#include "geometry/flatness.h"

#include <math.h>

double sem_eigenvalue_ratio(const double C[6])
{
    double a = C[0], b = C[1], c = C[2], d = C[3], e = C[4], f = C[5];
    double p1 = d * d + e * e + f * f, q = (a + b + c) / 3.0;
    double p2 = (a - q) * (a - q) + (b - q) * (b - q) + (c - q) * (c - q) + 2.0 * p1;
    double p = sqrt(p2 / 6.0);
    if (!(p > 0)) return q > 0 ? 1.0 : 0.0; /* three equal eigenvalues */
    double B[6] = {(a - q) / p, (b - q) / p, (c - q) / p, d / p, e / p, f / p};
    double det = B[0] * (B[1] * B[2] - B[5] * B[5]) - B[3] * (B[3] * B[2] - B[5] * B[4]) +
                 B[4] * (B[3] * B[5] - B[1] * B[4]);
    double r = det / 2.0;
    double phi = r <= -1 ? M_PI / 3.0 : r >= 1 ? 0.0 : acos(r) / 3.0;
    double l1 = q + 2.0 * p * cos(phi), l3 = q + 2.0 * p * cos(phi + 2.0 * M_PI / 3.0);
    return l1 > 0 ? fmax(l3, 0.0) / l1 : 0.0;
}
