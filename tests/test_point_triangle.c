/* test_point_triangle.c - the one point-triangle closest point (geometry/point_triangle.h):
 * on random triangles and points, the closest point lies in the triangle and no point of a
 * fine grid over the triangle is nearer; its barycentric coordinates give the point; the
 * region tests alone place the same point (to rounding) from a vertex along the edge
 * vectors, as the closest parts of the preprocessing do; every feature is met. */
#include <math.h>
#include <string.h>

#include "geometry/point_triangle.h"
#include "test_util.h"

static double distance2(const double *x, const double *y)
{
    double d0 = x[0] - y[0], d1 = x[1] - y[1], d2 = x[2] - y[2];
    return d0 * d0 + d1 * d1 + d2 * d2;
}

/* The smallest squared distance from p to the points of triangle abc at n x n barycentric
 * grid steps. */
static double grid_distance2(const double *p, const double *a, const double *b, const double *c, int n)
{
    double best = INFINITY;
    for (int i = 0; i <= n; i++)
        for (int j = 0; i + j <= n; j++) {
            double v = (double)i / n, w = (double)j / n, u = 1 - v - w, x[3];
            for (int k = 0; k < 3; k++) x[k] = u * a[k] + v * b[k] + w * c[k];
            double d = distance2(p, x);
            if (d < best) best = d;
        }
    return best;
}

/* The point from the region alone, from a vertex along the edge vectors. */
static void region_point(const sem_tri_region *r, const double *a, const double *b, const double *c,
                         double *q)
{
    const double *corner[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        double ab = b[k] - a[k], ac = c[k] - a[k];
        if (r->feature == SEM_TRI_VERTEX) q[k] = corner[r->index][k];
        else if (r->feature == SEM_TRI_EDGE)
            q[k] = r->index == 0 ? a[k] + r->t * ab : r->index == 2 ? a[k] + r->t * ac : b[k] + r->t * (c[k] - b[k]);
        else {
            double s = r->va + r->vb + r->vc;
            q[k] = a[k] + ab * (r->vb / s) + ac * (r->vc / s);
        }
    }
}

static void test_random_triangles(void)
{
    unsigned long long state = 0x9e3779b97f4a7c15ull;
    int seen[3] = {0, 0, 0}, bad_grid = 0, bad_inside = 0, bad_point = 0, bad_region = 0;
    for (int trial = 0; trial < 2000; trial++) {
        double a[3], b[3], c[3], p[3];
        for (int k = 0; k < 3; k++) {
            a[k] = 2 * test_uniform(&state) - 1;
            b[k] = 2 * test_uniform(&state) - 1;
            c[k] = 2 * test_uniform(&state) - 1;
            p[k] = 4 * test_uniform(&state) - 2;
        }
        sem_tri_closest cl;
        sem_point_triangle_closest(p, a, b, c, &cl);
        seen[cl.feature]++;
        /* in the triangle, and its coordinates give it */
        double sum = cl.bary[0] + cl.bary[1] + cl.bary[2], x[3];
        for (int k = 0; k < 3; k++) x[k] = cl.bary[0] * a[k] + cl.bary[1] * b[k] + cl.bary[2] * c[k];
        if (cl.bary[0] < -1e-12 || cl.bary[1] < -1e-12 || cl.bary[2] < -1e-12 || fabs(sum - 1) > 1e-12 ||
            distance2(x, cl.point) > 1e-24)
            bad_inside++;
        if (fabs(distance2(p, cl.point) - cl.dist2) > 1e-14) bad_point++;
        /* no grid point nearer */
        if (grid_distance2(p, a, b, c, 40) < cl.dist2 - 1e-12) bad_grid++;
        /* the region alone: the same feature, the same point to rounding */
        sem_tri_region r;
        sem_point_triangle_region(p, a, b, c, &r);
        double q[3];
        region_point(&r, a, b, c, q);
        if (r.feature != cl.feature || r.index != cl.index || distance2(q, cl.point) > 1e-24) bad_region++;
    }
    CHECK(bad_inside == 0, "%d closest points outside the triangle or off their coordinates", bad_inside);
    CHECK(bad_point == 0, "%d squared distances off", bad_point);
    CHECK(bad_grid == 0, "%d triangles with a grid point nearer than the closest point", bad_grid);
    CHECK(bad_region == 0, "%d region answers differ from the closest point", bad_region);
    CHECK(seen[SEM_TRI_FACE] > 0 && seen[SEM_TRI_EDGE] > 0 && seen[SEM_TRI_VERTEX] > 0,
          "every feature met: face %d, edge %d, vertex %d", seen[SEM_TRI_FACE], seen[SEM_TRI_EDGE],
          seen[SEM_TRI_VERTEX]);
}

/* A triangle with no area gives its first vertex. */
static void test_degenerate(void)
{
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, c[3] = {2, 0, 0}, p[3] = {1, 1, 0};
    sem_tri_closest cl;
    sem_point_triangle_closest(p, a, b, c, &cl);
    CHECK(cl.feature != SEM_TRI_FACE, "a triangle without area has no inside");
    CHECK(cl.dist2 <= 1 + 1e-15, "distance %g", sqrt(cl.dist2));
}

int main(void)
{
    test_random_triangles();
    test_degenerate();
    return test_finish("point_triangle");
}
