/*
 * ccd.c - additive continuous collision detection (see ccd.h).
 */
#include "ccd.h"

#include <math.h>

#include "geometry/point_triangle.h"
#include "geometry/vector3.h"
#include "narrow_phase.h"

static double distance(int edges, const double y[4][3])
{
    if (edges) {
        double s, t;
        return sqrt(sem_segment_closest(y[0], y[1], y[2], y[3], &s, &t));
    }
    sem_tri_closest c;
    sem_point_triangle_closest(y[0], y[1], y[2], y[3], &c);
    return sqrt(c.dist2);
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
