/*
 * ccd.c - additive continuous collision detection (see ccd.h).
 */
#include "ccd.h"

#include <math.h>

#include "geometry/point_triangle.h"
#include "geometry/vector3.h"
#include "narrow_phase.h"

int sem_ccd_degenerate(const double a[3], const double b[3], const double c[3])
{
    double e[3][3], n[3], longest = 0;
    for (int k = 0; k < 3; ++k) {
        e[0][k] = b[k] - a[k];
        e[1][k] = c[k] - b[k];
        e[2][k] = a[k] - c[k];
    }
    for (int i = 0; i < 3; ++i) longest = fmax(longest, dot3(e[i], e[i]));
    n[0] = e[0][1] * e[2][2] - e[0][2] * e[2][1];
    n[1] = e[0][2] * e[2][0] - e[0][0] * e[2][2];
    n[2] = e[0][0] * e[2][1] - e[0][1] * e[2][0];
    return !(dot3(n, n) > 1e-20 * longest * longest);
}

double sem_ccd_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3])
{
    if (sem_ccd_degenerate(a, b, c)) {
        const double *v[4] = {a, b, c, a};
        double best = INFINITY, s, t;
        for (int i = 0; i < 3; ++i) best = fmin(best, sem_segment_closest(p, p, v[i], v[i + 1], &s, &t));
        return sqrt(best);
    }
    sem_tri_closest cl;
    sem_point_triangle_closest(p, a, b, c, &cl);
    return sqrt(cl.dist2);
}

static double distance(int edges, const double y[4][3])
{
    if (edges) {
        double s, t;
        return sqrt(sem_segment_closest(y[0], y[1], y[2], y[3], &s, &t));
    }
    return sem_ccd_triangle_distance(y[0], y[1], y[2], y[3]);
}

static double additive(int edges, const double *const x[4], const double *const p[4], double t_max)
{
    double q[4][3], y[4][3], mean[3] = {0, 0, 0}, len[4];
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) mean[k] += 0.25 * p[i][k];
    for (int i = 0; i < 4; ++i) {
        for (int k = 0; k < 3; ++k) q[i][k] = p[i][k] - mean[k];
        len[i] = sqrt(dot3(q[i], q[i]));
    }
    double lp = edges ? fmax(len[0], len[1]) + fmax(len[2], len[3]) : len[0] + fmax(len[1], fmax(len[2], len[3]));
    if (!(lp > 0)) return t_max; /* (a rigid translation of both keeps the distance) */
    for (int i = 0; i < 4; ++i)
        for (int k = 0; k < 3; ++k) y[i][k] = x[i][k];
    double d = distance(edges, y);
    if (!(d > 0)) return 0;
    double goal = SEM_CCD_SEPARATION * d, t = 0, advance = (1 - SEM_CCD_SEPARATION) * d / lp;
    for (int it = 0; it < SEM_CCD_MAX_ADVANCES; ++it) {
        double next = t + advance;
        if (next > t_max) return t_max;
        for (int i = 0; i < 4; ++i)
            for (int k = 0; k < 3; ++k) y[i][k] = x[i][k] + next * q[i][k];
        d = distance(edges, y);
        if (t > 0 && !(d >= goal)) return t;
        t = next;
        advance = 0.9 * d / lp;
    }
    return t;
}

double sem_ccd_point_triangle(const double *const x[4], const double *const p[4], double t_max)
{
    return additive(0, x, p, t_max);
}

double sem_ccd_edge_edge(const double *const x[4], const double *const p[4], double t_max)
{
    return additive(1, x, p, t_max);
}

double sem_ccd_point_plane(double d, double v, double t_max)
{
    if (!(d > 0)) return 0;
    if (!(v < 0)) return t_max;
    double t = (1 - SEM_CCD_SEPARATION) * d / -v;
    return t < t_max ? t : t_max;
}
