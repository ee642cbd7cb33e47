/*
 * point_triangle.c - the closest point of a triangle to a point (see point_triangle.h).
 */
#include "geometry/point_triangle.h"

#include <math.h>

#include "geometry/vector3.h"

static void set_region(sem_tri_region *r, sem_tri_feature feature, int index, double t)
{
    r->feature = feature;
    r->index = index;
    r->t = t;
    r->va = r->vb = r->vc = 0;
}

void sem_point_triangle_region(const double p[3], const double a[3], const double b[3],
                               const double c[3], sem_tri_region *out)
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; ++k) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
    double d1 = dot3(ab, ap), d2 = dot3(ac, ap);
    if (d1 <= 0 && d2 <= 0) return set_region(out, SEM_TRI_VERTEX, 0, 0);
    double bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    double d3 = dot3(ab, bp), d4 = dot3(ac, bp);
    if (d3 >= 0 && d4 <= d3) return set_region(out, SEM_TRI_VERTEX, 1, 0);
    double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) return set_region(out, SEM_TRI_EDGE, 0, d1 / (d1 - d3));
    double cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double d5 = dot3(ab, cp), d6 = dot3(ac, cp);
    if (d6 >= 0 && d5 <= d6) return set_region(out, SEM_TRI_VERTEX, 2, 0);
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) return set_region(out, SEM_TRI_EDGE, 2, d2 / (d2 - d6));
    double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
        return set_region(out, SEM_TRI_EDGE, 1, (d4 - d3) / ((d4 - d3) + (d5 - d6)));
    set_region(out, SEM_TRI_FACE, 0, 0);
    out->va = va;
    out->vb = vb;
    out->vc = vc;
}

static void set_result(sem_tri_closest *o, const double a[3], const double b[3],
                       const double c[3], double u, double v, double w, sem_tri_feature f,
                       int index, const double p[3])
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
    sem_tri_region r;
    sem_point_triangle_region(p, a, b, c, &r);
    if (r.feature == SEM_TRI_VERTEX)
        return set_result(out, a, b, c, r.index == 0, r.index == 1, r.index == 2, SEM_TRI_VERTEX,
                          r.index, p);
    if (r.feature == SEM_TRI_EDGE) {
        double s = 1 - r.t;
        if (r.index == 0) return set_result(out, a, b, c, s, r.t, 0, SEM_TRI_EDGE, 0, p);
        if (r.index == 1) return set_result(out, a, b, c, 0, s, r.t, SEM_TRI_EDGE, 1, p);
        return set_result(out, a, b, c, s, 0, r.t, SEM_TRI_EDGE, 2, p);
    }
    double denom = r.va + r.vb + r.vc;
    if (!(fabs(denom) > 0)) /* degenerate triangle: its first vertex */
        return set_result(out, a, b, c, 1, 0, 0, SEM_TRI_VERTEX, 0, p);
    double v = r.vb / denom, w = r.vc / denom;
    set_result(out, a, b, c, 1 - v - w, v, w, SEM_TRI_FACE, 0, p);
}
