/*
 * crossings.c - intersecting triangles of a deformed mesh (see crossings.h).
 */
#include "crossings.h"

#include <math.h>
#include <stdlib.h>

#include "contact/narrow_phase.h"
#include "geometry/point_triangle.h"

typedef struct box {
    double lo[3], hi[3];
    int t;
} box;

static int compare_box(const void *a, const void *b)
{
    double x = ((const box *)a)->lo[0], y = ((const box *)b)->lo[0];
    return (x > y) - (x < y);
}

static void sub(const double *a, const double *b, double *r)
{
    for (int k = 0; k < 3; ++k) r[k] = a[k] - b[k];
}

static void cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Does the open segment p q pass through the interior or boundary of triangle a b c? */
static int segment_hits(const double *p, const double *q, const double *a, const double *b, const double *c)
{
    double e1[3], e2[3], n[3], dp[3], dq[3];
    sub(b, a, e1);
    sub(c, a, e2);
    cross(e1, e2, n);
    sub(p, a, dp);
    sub(q, a, dq);
    double sp = dot(n, dp), sq = dot(n, dq);
    if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || sp == sq) return 0; /* one side, or in the plane */
    double s = sp / (sp - sq), x[3];
    for (int k = 0; k < 3; ++k) x[k] = p[k] + s * (q[k] - p[k]);
    /* x inside a b c: the three sub-triangles turn the way n does */
    const double *v[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
        double e[3], w[3], m[3];
        sub(v[(i + 1) % 3], v[i], e);
        sub(x, v[i], w);
        cross(e, w, m);
        if (dot(m, n) < 0) return 0;
    }
    return 1;
}

static int triangles_cross(const double *x, const int *s, const int *t)
{
    for (int pass = 0; pass < 2; ++pass) {
        const int *e = pass ? t : s, *f = pass ? s : t;
        for (int i = 0; i < 3; ++i)
            if (segment_hits(x + 3 * (size_t)e[i], x + 3 * (size_t)e[(i + 1) % 3], x + 3 * (size_t)f[0],
                             x + 3 * (size_t)f[1], x + 3 * (size_t)f[2]))
                return 1;
    }
    return 0;
}

static int touch_at_rest(const double *x0, const int *s, const int *t, double tol2)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d[3];
            sub(x0 + 3 * (size_t)s[i], x0 + 3 * (size_t)t[j], d);
            if (dot(d, d) <= tol2) return 1;
        }
    return 0;
}

/* The distance between triangles s and t at x (the least of their vertex-triangle and
 * edge-edge distances). */
static double triangle_distance(const double *x, const int *s, const int *t)
{
    double best = INFINITY;
    for (int side = 0; side < 2; ++side) {
        const int *a = side ? t : s, *b = side ? s : t;
        for (int i = 0; i < 3; ++i) {
            sem_tri_closest c;
            sem_point_triangle_closest(x + 3 * (size_t)a[i], x + 3 * (size_t)b[0], x + 3 * (size_t)b[1],
                                       x + 3 * (size_t)b[2], &c);
            best = fmin(best, c.dist2);
        }
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double u, v;
            best = fmin(best, sem_segment_closest(x + 3 * (size_t)s[i], x + 3 * (size_t)s[(i + 1) % 3],
                                                  x + 3 * (size_t)t[j], x + 3 * (size_t)t[(j + 1) % 3], &u, &v));
        }
    return sqrt(best);
}

long count_crossings(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles)
{
    return count_crossings_apart(x0, x, n_vertices, triangles, n_triangles, 0);
}

long count_crossings_apart(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles,
                           double apart)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int v = 0; v < n_vertices; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], x0[3 * v + k]);
            hi[k] = fmax(hi[k], x0[3 * v + k]);
        }
    double size2 = 0;
    for (int k = 0; k < 3; ++k) size2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    double tol2 = 1e-18 * size2;
    box *b = malloc(((size_t)n_triangles + 1) * sizeof *b);
    if (!b) return -1;
    for (int t = 0; t < n_triangles; ++t) {
        b[t].t = t;
        for (int k = 0; k < 3; ++k) {
            b[t].lo[k] = INFINITY;
            b[t].hi[k] = -INFINITY;
        }
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) {
                double c = x[3 * (size_t)triangles[3 * t + i] + k];
                b[t].lo[k] = fmin(b[t].lo[k], c);
                b[t].hi[k] = fmax(b[t].hi[k], c);
            }
    }
    qsort(b, (size_t)n_triangles, sizeof *b, compare_box);
    long count = 0;
    for (int i = 0; i < n_triangles; ++i)
        for (int j = i + 1; j < n_triangles && b[j].lo[0] <= b[i].hi[0]; ++j) {
            if (b[j].lo[1] > b[i].hi[1] || b[i].lo[1] > b[j].hi[1] || b[j].lo[2] > b[i].hi[2] ||
                b[i].lo[2] > b[j].hi[2])
                continue;
            const int *s = triangles + 3 * (size_t)b[i].t, *t = triangles + 3 * (size_t)b[j].t;
            if (touch_at_rest(x0, s, t, tol2)) continue;
            if (triangles_cross(x, s, t) && !triangles_cross(x0, s, t) &&
                !(apart > 0 && triangle_distance(x0, s, t) < apart))
                ++count;
        }
    free(b);
    return count;
}
