/*
 * analytic_surfaces.c - planes, cylinders, cones, spheres and tori as exact rational
 * B-splines (see geometry/analytic_surfaces.h).
 */
#include "geometry/analytic_surfaces.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* the 9-point rational quadratic unit circle: points (cx, cy), weights, knots */
static const double CX[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1};
static const double CY[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
static const double CK[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
#define W2 0.70710678118654752440

static double cw(int i) { return i % 2 ? W2 : 1.0; }

static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

sem_status sem_frame_make(const double origin[3], const double axis[3], const double *ref,
                          sem_frame *out, sem_error *err)
{
    double len = sqrt(dot(axis, axis));
    if (!(len > 0) || !isfinite(len)) return sem_error_set(err, SEM_ERR_INVALID, "zero axis");
    for (int d = 0; d < 3; ++d) {
        out->o[d] = origin[d];
        out->z[d] = axis[d] / len;
    }
    double x[3] = {0, 0, 0};
    if (ref) {
        double p = dot(ref, out->z);
        for (int d = 0; d < 3; ++d) x[d] = ref[d] - p * out->z[d];
    }
    double lx = sqrt(dot(x, x));
    if (!(lx > 1e-12 * (ref ? sqrt(dot(ref, ref)) : 1.0))) {
        /* any perpendicular: cross z with the axis it is least aligned with */
        int a = fabs(out->z[0]) <= fabs(out->z[1]) && fabs(out->z[0]) <= fabs(out->z[2]) ? 0
                : fabs(out->z[1]) <= fabs(out->z[2])                                     ? 1
                                                                                         : 2;
        double e[3] = {0, 0, 0};
        e[a] = 1;
        x[0] = e[1] * out->z[2] - e[2] * out->z[1];
        x[1] = e[2] * out->z[0] - e[0] * out->z[2];
        x[2] = e[0] * out->z[1] - e[1] * out->z[0];
        lx = sqrt(dot(x, x));
    }
    for (int d = 0; d < 3; ++d) out->x[d] = x[d] / lx;
    out->y[0] = out->z[1] * out->x[2] - out->z[2] * out->x[1];
    out->y[1] = out->z[2] * out->x[0] - out->z[0] * out->x[2];
    out->y[2] = out->z[0] * out->x[1] - out->z[1] * out->x[0];
    return SEM_OK;
}

/* frame point o + a x + b y + c z */
static void at(const sem_frame *f, double a, double b, double c, double *p)
{
    for (int d = 0; d < 3; ++d) p[d] = f->o[d] + a * f->x[d] + b * f->y[d] + c * f->z[d];
}

sem_status sem_analytic_plane(sem_surface *s, const sem_frame *f, double half, sem_error *err)
{
    if (sem_surface_alloc(s, 1, 1, 2, 2) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    at(f, -half, -half, 0, s->ctrl);
    at(f, half, -half, 0, s->ctrl + 3);
    at(f, -half, half, 0, s->ctrl + 6);
    at(f, half, half, 0, s->ctrl + 9);
    s->knots_u[0] = s->knots_u[1] = s->knots_v[0] = s->knots_v[1] = s->u0 = s->v0 = 0;
    s->knots_u[2] = s->knots_u[3] = s->knots_v[2] = s->knots_v[3] = s->u1 = s->v1 = 1;
    return SEM_OK;
}

sem_status sem_analytic_cone(sem_surface *s, const sem_frame *f, double radius,
                             double tan_angle, double h0, double h1, sem_error *err)
{
    if (sem_surface_alloc(s, 2, 1, 9, 2) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(s->knots_u, CK, sizeof CK);
    s->knots_v[0] = s->knots_v[1] = s->u0 = s->v0 = 0;
    s->knots_v[2] = s->knots_v[3] = s->u1 = s->v1 = 1;
    for (int j = 0; j < 2; ++j) {
        double h = j ? h1 : h0, r = radius + h * tan_angle;
        for (int i = 0; i < 9; ++i) {
            at(f, r * CX[i], r * CY[i], h, s->ctrl + 3 * (i + 9 * j));
            s->weights[i + 9 * j] = cw(i);
        }
    }
    s->closed_u = 1;
    return SEM_OK;
}

sem_status sem_analytic_sphere(sem_surface *s, const sem_frame *f, double radius, sem_error *err)
{
    /* the semicircle from the south pole to the north pole in the (rho, z) half plane */
    static const double rho[5] = {0, 1, 1, 1, 0}, zz[5] = {-1, -1, 0, 1, 1};
    static const double vk[8] = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    if (sem_surface_alloc(s, 2, 2, 9, 5) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(s->knots_u, CK, sizeof CK);
    memcpy(s->knots_v, vk, sizeof vk);
    s->u0 = s->v0 = 0;
    s->u1 = s->v1 = 1;
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 9; ++i) {
            at(f, radius * rho[j] * CX[i], radius * rho[j] * CY[i], radius * zz[j],
               s->ctrl + 3 * (i + 9 * j));
            s->weights[i + 9 * j] = cw(i) * cw(j);
        }
    s->closed_u = 1;
    return SEM_OK;
}

sem_status sem_analytic_torus(sem_surface *s, const sem_frame *f, double major, double minor,
                              sem_error *err)
{
    if (sem_surface_alloc(s, 2, 2, 9, 9) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(s->knots_u, CK, sizeof CK);
    memcpy(s->knots_v, CK, sizeof CK);
    s->u0 = s->v0 = 0;
    s->u1 = s->v1 = 1;
    for (int j = 0; j < 9; ++j) {
        double rho = major + minor * CX[j], z = minor * CY[j];
        for (int i = 0; i < 9; ++i) {
            at(f, rho * CX[i], rho * CY[i], z, s->ctrl + 3 * (i + 9 * j));
            s->weights[i + 9 * j] = cw(i) * cw(j);
        }
    }
    s->closed_u = s->closed_v = 1;
    return SEM_OK;
}

/* centroid of the 8 distinct control points of row j (the 9-point circle repeats its first) */
static void row_centre(const sem_surface *s, int j, double c[3])
{
    c[0] = c[1] = c[2] = 0;
    int n = s->n_u > 1 ? s->n_u - 1 : 1;
    for (int i = 0; i < n; ++i)
        for (int d = 0; d < 3; ++d) c[d] += s->ctrl[3 * (i + s->n_u * j) + d] / n;
}

void sem_surface_fit_axial_range(sem_surface *s, const double *points, size_t n)
{
    if (s->n_v != 2 || n == 0) return;
    double c0[3], c1[3], a[3];
    row_centre(s, 0, c0);
    row_centre(s, 1, c1);
    for (int d = 0; d < 3; ++d) a[d] = c1[d] - c0[d];
    double aa = dot(a, a);
    if (!(aa > 0)) return;
    double lo = INFINITY, hi = -INFINITY;
    for (size_t k = 0; k < n; ++k) {
        const double *p = points + 3 * k;
        double q[3] = {p[0] - c0[0], p[1] - c0[1], p[2] - c0[2]};
        double t = dot(q, a) / aa;
        lo = fmin(lo, t);
        hi = fmax(hi, t);
    }
    if (!(hi > lo)) return;
    /* rows at t = lo and t = hi along the generators (exact: the surface is linear in t) */
    for (int i = 0; i < s->n_u; ++i) {
        double *p0 = s->ctrl + 3 * i, *p1 = s->ctrl + 3 * (i + s->n_u);
        for (int d = 0; d < 3; ++d) {
            double a0 = p0[d], a1 = p1[d];
            p0[d] = a0 + lo * (a1 - a0);
            p1[d] = a0 + hi * (a1 - a0);
        }
    }
}

void sem_surface_fit_plane_rectangle(sem_surface *s, const double *points, size_t n)
{
    if (s->n_u != 2 || s->n_v != 2 || n == 0) return;
    const double *p00 = s->ctrl, *p10 = s->ctrl + 3, *p01 = s->ctrl + 6;
    double o[3], a[3], b[3];
    for (int d = 0; d < 3; ++d) {
        o[d] = p00[d];
        a[d] = p10[d] - p00[d];
        b[d] = p01[d] - p00[d];
    }
    double aa = dot(a, a), bb = dot(b, b), ab = dot(a, b), det = aa * bb - ab * ab;
    if (!(det > 0)) return;
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t k = 0; k < n; ++k) {
        const double *p = points + 3 * k;
        double q[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
        double qa = dot(q, a), qb = dot(q, b);
        double u = (bb * qa - ab * qb) / det, v = (aa * qb - ab * qa) / det;
        lo[0] = fmin(lo[0], u), hi[0] = fmax(hi[0], u);
        lo[1] = fmin(lo[1], v), hi[1] = fmax(hi[1], v);
    }
    if (!(hi[0] > lo[0]) || !(hi[1] > lo[1])) return;
    double uv[4][2] = {{lo[0], lo[1]}, {hi[0], lo[1]}, {lo[0], hi[1]}, {hi[0], hi[1]}};
    for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) s->ctrl[3 * k + d] = o[d] + uv[k][0] * a[d] + uv[k][1] * b[d];
    /* the parameters keep their scale: u in [u0 + lo0 (u1 - u0), ...] */
    double du = s->u1 - s->u0, dv = s->v1 - s->v0, u0 = s->u0, v0 = s->v0;
    s->knots_u[0] = s->knots_u[1] = s->u0 = u0 + lo[0] * du;
    s->knots_u[2] = s->knots_u[3] = s->u1 = u0 + hi[0] * du;
    s->knots_v[0] = s->knots_v[1] = s->v0 = v0 + lo[1] * dv;
    s->knots_v[2] = s->knots_v[3] = s->v1 = v0 + hi[1] * dv;
}

static int compare_doubles(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

void sem_surface_place_seam(sem_surface *s, const double *points, const size_t *offsets,
                            int n_curves)
{
    size_t n = n_curves > 0 ? offsets[n_curves] : 0;
    if (s->n_u != 9 || n == 0) return;
    /* the axis and a point on it from a row of the circle that is not a pole */
    int j = s->n_v / 2;
    double c[3];
    row_centre(s, j, c);
    const double *p0 = s->ctrl + 3 * (size_t)(s->n_u * j), *p2 = s->ctrl + 3 * (size_t)(2 + s->n_u * j);
    double x[3] = {p0[0] - c[0], p0[1] - c[1], p0[2] - c[2]};
    double y0[3] = {p2[0] - c[0], p2[1] - c[1], p2[2] - c[2]};
    double z[3] = {x[1] * y0[2] - x[2] * y0[1], x[2] * y0[0] - x[0] * y0[2], x[0] * y0[1] - x[1] * y0[0]};
    double lx = sqrt(dot(x, x)), lz = sqrt(dot(z, z));
    if (!(lx > 0) || !(lz > 0)) return;
    for (int d = 0; d < 3; ++d) x[d] /= lx, z[d] /= lz;
    double y[3] = {z[1] * x[2] - z[2] * x[1], z[2] * x[0] - z[0] * x[2], z[0] * x[1] - z[1] * x[0]};
    /* every point's angle about the axis from the current seam; NAN on the axis */
    double *angle = malloc(2 * n * sizeof *angle), *sorted = angle + n;
    if (!angle) return;
    size_t m = 0;
    for (size_t k = 0; k < n; ++k) {
        const double *p = points + 3 * k;
        double q[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        double a = dot(q, x), b = dot(q, y);
        double t = atan2(b, a);
        angle[k] = hypot(a, b) <= 1e-9 * lx ? NAN : t < 0 ? t + 2 * M_PI : t;
        if (!isnan(angle[k])) sorted[m++] = angle[k];
    }
    if (m == 0) {
        free(angle);
        return;
    }
    /* curves at one angle each (generators, meridians); two at the same angle: a seam edge */
    double seam = NAN, eps = 1e-7;
    for (int a = 0; a < n_curves && isnan(seam); ++a) {
        double ta = NAN;
        int one = 1;
        for (size_t k = offsets[a]; k < offsets[a + 1] && one; ++k) {
            if (isnan(angle[k])) continue;
            if (isnan(ta)) ta = angle[k];
            else one = fabs(remainder(angle[k] - ta, 2 * M_PI)) <= eps;
        }
        if (!one || isnan(ta)) continue;
        for (int b = a + 1; b < n_curves && isnan(seam); ++b) {
            int same = 1, any = 0;
            for (size_t k = offsets[b]; k < offsets[b + 1] && same; ++k) {
                if (isnan(angle[k])) continue;
                any = 1;
                same = fabs(remainder(angle[k] - ta, 2 * M_PI)) <= eps;
            }
            if (same && any) seam = ta;
        }
    }
    if (isnan(seam)) {
        /* the middle of the widest gap */
        qsort(sorted, m, sizeof *sorted, compare_doubles);
        double gap = sorted[0] + 2 * M_PI - sorted[m - 1];
        seam = sorted[m - 1] + 0.5 * gap;
        for (size_t k = 1; k < m; ++k)
            if (sorted[k] - sorted[k - 1] > gap) {
                gap = sorted[k] - sorted[k - 1];
                seam = sorted[k - 1] + 0.5 * gap;
            }
    }
    free(angle);
    /* rotate every control point by `seam` about the axis (Rodrigues; z . (p - c) stays) */
    double cs = cos(seam), sn = sin(seam);
    size_t count = (size_t)s->n_u * (size_t)s->n_v;
    for (size_t k = 0; k < count; ++k) {
        double *p = s->ctrl + 3 * k;
        double q[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
        double qz = dot(q, z), zq[3] = {z[1] * q[2] - z[2] * q[1], z[2] * q[0] - z[0] * q[2], z[0] * q[1] - z[1] * q[0]};
        for (int d = 0; d < 3; ++d)
            p[d] = c[d] + q[d] * cs + zq[d] * sn + z[d] * qz * (1 - cs);
    }
}
