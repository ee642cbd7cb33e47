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

static double clamp01(double x) { return x < 0 ? 0 : x > 1 ? 1 : x; }

double sem_segment_closest(const double a0[3], const double a1[3], const double b0[3], const double b1[3],
                           double *s, double *t)
{
    double d1[3] = {a1[0] - a0[0], a1[1] - a0[1], a1[2] - a0[2]};
    double d2[3] = {b1[0] - b0[0], b1[1] - b0[1], b1[2] - b0[2]};
    double r[3] = {a0[0] - b0[0], a0[1] - b0[1], a0[2] - b0[2]};
    double a = dot3(d1, d1), e = dot3(d2, d2), f = dot3(d2, r);
    double tiny = 1e-30 * (1 + dot3(a0, a0) + dot3(b0, b0));
    double ss = 0, tt = 0;
    if (a <= tiny && e <= tiny) {
        ss = tt = 0;
    } else if (a <= tiny) {
        tt = clamp01(f / e);
    } else {
        double c = dot3(d1, r);
        if (e <= tiny) {
            ss = clamp01(-c / a);
        } else {
            double b = dot3(d1, d2), denom = a * e - b * b;
            ss = denom > 1e-14 * a * e ? clamp01((b * f - c * e) / denom) : 0;
            tt = (b * ss + f) / e;
            if (tt < 0) {
                tt = 0;
                ss = clamp01(-c / a);
            } else if (tt > 1) {
                tt = 1;
                ss = clamp01((b - c) / a);
            }
        }
    }
    double d[3];
    for (int k = 0; k < 3; ++k) d[k] = a0[k] + ss * d1[k] - b0[k] - tt * d2[k];
    *s = ss;
    *t = tt;
    return dot3(d, d);
}
