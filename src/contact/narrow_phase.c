/*
 * narrow_phase.c - point-triangle closest points and signed distances (see narrow_phase.h).
 */
#include "narrow_phase.h"

#include <math.h>

#include "geometry/vector3.h"

static void set_result(sem_tri_closest *o, const double a[3], const double b[3], const double c[3],
                       double u, double v, double w, sem_tri_feature f, int index, const double p[3])
{
    o->bary[0] = u;
    o->bary[1] = v;
    o->bary[2] = w;
    for (int k = 0; k < 3; ++k) o->point[k] = u * a[k] + v * b[k] + w * c[k];
    double d[3] = {p[0] - o->point[0], p[1] - o->point[1], p[2] - o->point[2]};
    o->dist2 = dot3(d, d);
    o->feature = f;
    o->index = index;
}

void sem_point_triangle_closest(const double p[3], const double a[3], const double b[3],
                                const double c[3], sem_tri_closest *out)
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) return set_result(out, a, b, c, 1, 0, 0, SEM_TRI_VERTEX, 0, p);
    double bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) return set_result(out, a, b, c, 0, 1, 0, SEM_TRI_VERTEX, 1, p);
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        return set_result(out, a, b, c, 1 - v, v, 0, SEM_TRI_EDGE, 0, p);
    }
    double cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) return set_result(out, a, b, c, 0, 0, 1, SEM_TRI_VERTEX, 2, p);
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        return set_result(out, a, b, c, 1 - w, 0, w, SEM_TRI_EDGE, 2, p);
    }
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return set_result(out, a, b, c, 0, 1 - w, w, SEM_TRI_EDGE, 1, p);
    }
    double denom = va + vb + vc;
    if (!(fabs(denom) > 0)) /* degenerate triangle: its first vertex */
        return set_result(out, a, b, c, 1, 0, 0, SEM_TRI_VERTEX, 0, p);
    double v = vb / denom, w = vc / denom;
    set_result(out, a, b, c, 1 - v - w, v, w, SEM_TRI_FACE, 0, p);
}

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
