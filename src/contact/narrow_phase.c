/*
 * narrow_phase.c - signed distances (see narrow_phase.h; the point-triangle closest point is
 * geometry/point_triangle.c).
 */
#include "narrow_phase.h"

#include <math.h>

#include "geometry/vector3.h"

double sem_signed_distance(const double p[3], const double c[3], const double outward[3],
                           double normal[3])
{
    double d[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double len = sqrt(dot3(d, d));
    double side = dot3(d, outward);
    double on = sqrt(dot3(outward, outward));
    /* on the surface (or numerically so): the outward direction is the gradient */
    if (len <= 1e-12 * (1.0 + sqrt(dot3(c, c)))) {
        for (int k = 0; k < 3; ++k) normal[k] = on > 0 ? outward[k] / on : 0;
        return 0;
    }
    double s = side >= 0 ? 1.0 : -1.0;
    for (int k = 0; k < 3; ++k) normal[k] = s * d[k] / len;
    return s * len;
}
