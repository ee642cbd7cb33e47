/*
 * hit_curvature.c - how the surface bends where a ray crosses it, seen along the ray.
 *
 * Near a hit the surface is a height field t = g(y, z) over the plane across the ray
 * (t along the ray direction d, y and z along the two axes e1, e2 across it). The volume
 * quadrature (quadrature_subrays.c) integrates inside lengths, differences of such height
 * fields, over the squares of its ray grid; the midpoint rule over a square of sides sy, sz
 * is off by (sy^2 g_yy + sz^2 g_zz) sy sz / 24 + O(s^6), so the Hessian of g at the hit both
 * corrects that (the rule becomes fourth order where the surface is smooth) and says where
 * that expansion cannot be trusted (near a silhouette g_yy grows like 1 / (n . d)^3).
 *
 * With X(u, v) the surface and (y, z) = J (u, v) to first order, J = [X_u . e1, X_v . e1;
 * X_u . e2, X_v . e2]: grad g = (X_u . d, X_v . d) J^-1 and, differentiating
 * t(u, v) = g(y(u, v), z(u, v)) twice (the second derivatives of y and z carry the
 * gradient terms), Hess g = J^-T [X_ij . w] J^-1 with w = d - g_y e1 - g_z e2 (a normal of
 * the surface). Exact for any regular parametrization, rational or not; it fails only where
 * J is singular: the ray tangent to the surface, or a collapsed pole.
 */
#include <math.h>

#include "geometry/vector3.h"
#include "sem/nurbs.h"
#include "steps.h"

int sem_hit_height_hessian(const sem_surface *surface, double u, double v, const double d[3],
                           const double e1[3], const double e2[3], double H[3],
                           double *facing)
{
    if (!surface) return 0;
    double X[3], Xu[3], Xv[3], X2[9];
    sem_surface_eval(surface, u, v, X, Xu, Xv, X2);
    const double J00 = dot3(Xu, e1), J01 = dot3(Xv, e1), J10 = dot3(Xu, e2), J11 = dot3(Xv, e2);
    const double det = J00 * J11 - J01 * J10;
    const double scale = sqrt(dot3(Xu, Xu) * dot3(Xv, Xv));
    /* a ray within ~1e-8 rad of the tangent plane, or a degenerate parametrization */
    if (!(fabs(det) > 1e-8 * scale) || !isfinite(det)) return 0;
    /* A = J^-1 */
    const double A00 = J11 / det, A01 = -J01 / det, A10 = -J10 / det, A11 = J00 / det;
    const double tu = dot3(Xu, d), tv = dot3(Xv, d);
    const double gy = tu * A00 + tv * A10, gz = tu * A01 + tv * A11;
    double w[3];
    for (int k = 0; k < 3; ++k) w[k] = d[k] - gy * e1[k] - gz * e2[k];
    const double Muu = dot3(X2, w), Muv = dot3(X2 + 3, w), Mvv = dot3(X2 + 6, w);
    /* H = A^T M A */
    const double B00 = Muu * A00 + Muv * A10, B01 = Muu * A01 + Muv * A11; /* M A, row u */
    const double B10 = Muv * A00 + Mvv * A10, B11 = Muv * A01 + Mvv * A11; /* M A, row v */
    H[0] = A00 * B00 + A10 * B10;
    H[1] = A01 * B01 + A11 * B11;
    H[2] = A00 * B01 + A10 * B11;
    *facing = 1.0 / sqrt(1.0 + gy * gy + gz * gz);
    return isfinite(H[0]) && isfinite(H[1]) && isfinite(H[2]);
}
