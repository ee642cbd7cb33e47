/* test_raycast.c - Embree scene: orientation fix, winding number, first/all hits, closest parts.
 *
 * The model is the unit cube [0,1]^3 made of 6 bilinear patches, one of them (x = 1)
 * flipped so its x_u x x_v points into the cube, as in the paper's CAD files. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "preprocess/raycast.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "test_util.h"

/* Adds the patch x(u,v) = o + u a + v b, u,v in [0,1], of degree `degree` (evenly spaced
 * control points, so the map is exactly linear). */
static void add_patch(sem_model *m, const double o[3], const double a[3], const double b[3],
                      int degree)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    int n = degree + 1;
    CHECK(sem_surface_alloc(&part.surface, degree, degree, n, n) == SEM_OK, "alloc");
    sem_surface *s = &part.surface;
    for (int k = 0; k < 2 * n; k++) {
        s->knots_u[k] = k < n ? 0.0 : 1.0;
        s->knots_v[k] = k < n ? 0.0 : 1.0;
    }
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            for (int d = 0; d < 3; d++)
                s->ctrl[3 * (i + n * j) + d] =
                    o[d] + (double)i / degree * a[d] + (double)j / degree * b[d];
    sem_error err;
    CHECK(sem_model_take_part(m, &part, &err) == SEM_OK, "take part: %s", err.message);
}

/* Faces in order: x=0, x=1 (flipped), y=0, y=1, z=0, z=1. */
static sem_model *make_cube(int degree)
{
    sem_model *m = sem_model_create();
    const double O[3] = {0, 0, 0}, X1[3] = {1, 0, 0}, Y1[3] = {0, 1, 0}, Z1[3] = {0, 0, 1};
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    add_patch(m, O, ez, ey, degree);  /* x = 0, ez x ey = -x: outward */
    add_patch(m, X1, ez, ey, degree); /* x = 1, normal -x: INWARD (the flipped face) */
    add_patch(m, O, ex, ez, degree);  /* y = 0, ex x ez = -y: outward */
    add_patch(m, Y1, ez, ex, degree); /* y = 1, ez x ex = +y: outward */
    add_patch(m, O, ey, ex, degree);  /* z = 0, ey x ex = -z: outward */
    add_patch(m, Z1, ex, ey, degree); /* z = 1, ex x ey = +z: outward */
    return m;
}

static void test_cube(int degree, int resolution)
{
    sem_model *m = make_cube(degree);
    sem_raycast_scene *scene = NULL;
    sem_error err;
    sem_status st = sem_raycast_scene_build(m, resolution, &scene, &err);
    CHECK(st == SEM_OK, "build: %s", err.message);
    if (st != SEM_OK) {
        sem_model_destroy(m);
        return;
    }
    CHECK(sem_raycast_part_count(scene) == 6, "6 parts");

    /* orientation fix: only the x = 1 face is flipped */
    for (int p = 0; p < 6; p++)
        CHECK(sem_raycast_part_sign(scene, p) == (p == 1 ? -1 : 1), "part %d sign %d", p,
              sem_raycast_part_sign(scene, p));

    double lo[3], hi[3];
    sem_raycast_bounds(scene, lo, hi);
    for (int d = 0; d < 3; d++) {
        CHECK_NEAR(lo[d], 0.0, 1e-15);
        CHECK_NEAR(hi[d], 1.0, 1e-15);
    }

    /* winding number: 1 inside, 0 outside; the uncorrected flipped face would give 2/3 */
    const double centre[3] = {0.5, 0.5, 0.5}, inside[3] = {0.9, 0.15, 0.7};
    const double outside[3] = {2.0, 0.5, 0.5}, outside2[3] = {0.5, -0.3, 1.2};
    CHECK_NEAR(sem_raycast_winding_number_exact(scene, centre), 1.0, 1e-10);
    CHECK_NEAR(sem_raycast_winding_number_exact(scene, inside), 1.0, 1e-10);
    CHECK_NEAR(sem_raycast_winding_number_exact(scene, outside), 0.0, 1e-10);
    CHECK_NEAR(sem_raycast_winding_number_exact(scene, outside2), 0.0, 1e-10);
    /* the fast (tree) version: within its far-field error */
    CHECK_NEAR(sem_raycast_winding_number(scene, centre), 1.0, 2e-3);
    CHECK_NEAR(sem_raycast_winding_number(scene, inside), 1.0, 2e-3);
    CHECK_NEAR(sem_raycast_winding_number(scene, outside), 0.0, 2e-3);
    CHECK_NEAR(sem_raycast_winding_number(scene, outside2), 0.0, 2e-3);

    /* first hit from outside along +x: the x = 0 face at t = 1, normal -x */
    sem_ray_hit h;
    const double o1[3] = {-1.0, 0.3, 0.7}, dx[3] = {1, 0, 0};
    CHECK(sem_raycast_first(scene, o1, dx, 0.0, INFINITY, &h) == 1, "hit");
    CHECK_NEAR(h.t, 1.0, 1e-6);
    CHECK(h.part == 0, "part %d", h.part);
    CHECK_NEAR(h.normal[0], -1.0, 1e-12);
    /* from inside along an oblique direction: closest face z = 1 at t = 0.5 / dz */
    double dir[3] = {0.3, 0.4, sqrt(1 - 0.09 - 0.16)};
    CHECK(sem_raycast_first(scene, centre, dir, 0.0, INFINITY, &h) == 1, "hit");
    CHECK_NEAR(h.t, 0.5 / dir[2], 1e-6);
    CHECK(h.part == 5, "part %d", h.part);
    /* the flipped face, hit from inside along +x: corrected normal points out (+x) */
    CHECK(sem_raycast_first(scene, centre, dx, 0.0, INFINITY, &h) == 1, "hit");
    CHECK_NEAR(h.t, 0.5, 1e-6);
    CHECK(h.part == 1, "part %d", h.part);
    CHECK_NEAR(h.normal[0], 1.0, 1e-12);
    /* t_far before the surface: no hit */
    CHECK(sem_raycast_first(scene, o1, dx, 0.0, 0.99, &h) == 0, "no hit before t_far");

    /* all hits through the cube: exactly 2 (enter at 1, leave at 2), also through points
     * where the tessellation's triangles meet (grid vertices and edges of the patches) */
    const double yz[][2] = {{0.3, 0.7}, {0.5, 0.5}, {0.25, 0.25}, {0.25, 0.6}, {0.375, 0.375},
                            {0.125, 0.875}, {0.0625, 0.5}};
    for (size_t k = 0; k < sizeof yz / sizeof yz[0]; k++) {
        const double o[3] = {-1.0, yz[k][0], yz[k][1]};
        sem_ray_hit hits[8];
        int n = sem_raycast_all(scene, o, dx, 0.0, INFINITY, hits, 8);
        CHECK(n == 2, "ray (%g, %g): %d hits", yz[k][0], yz[k][1], n);
        if (n == 2) {
            CHECK_NEAR(hits[0].t, 1.0, 1e-12);
            CHECK_NEAR(hits[1].t, 2.0, 1e-12);
            CHECK(hits[0].part == 0 && hits[1].part == 1, "parts %d %d", hits[0].part,
                  hits[1].part);
            CHECK(hits[0].normal[0] < 0 && hits[1].normal[0] > 0, "enter then leave");
            /* on the exact surface, inside one part: smooth, (u,v) the point hit */
            for (int q = 0; q < 2; ++q) {
                double X[3];
                sem_surface_eval(&m->parts[hits[q].part].surface, hits[q].u, hits[q].v, X, NULL,
                                 NULL, NULL);
                CHECK(hits[q].smooth, "ray (%g, %g): hit %d not smooth", yz[k][0], yz[k][1], q);
                for (int d = 0; d < 3; ++d) CHECK_NEAR(X[d], o[d] + hits[q].t * dx[d], 1e-12);
            }
        }
    }

    /* a vertical ray: along z through y = 0.5, x = 0.5 */
    {
        const double o[3] = {0.5, 0.5, -2.0}, dz[3] = {0, 0, 1};
        sem_ray_hit hits[8];
        int n = sem_raycast_all(scene, o, dz, 0.0, INFINITY, hits, 8);
        CHECK(n == 2, "%d hits", n);
        if (n == 2) {
            CHECK_NEAR(hits[0].t, 2.0, 1e-12);
            CHECK_NEAR(hits[1].t, 3.0, 1e-12);
            CHECK(hits[0].part == 4 && hits[1].part == 5, "parts");
        }
        /* max_hits smaller than the count: total still returned */
        CHECK(sem_raycast_all(scene, o, dz, 0.0, INFINITY, hits, 1) == 2, "count");
        /* t range excludes the first hit */
        CHECK(sem_raycast_all(scene, o, dz, 2.5, INFINITY, hits, 8) == 1, "range");
    }
    /* a ray that misses */
    {
        const double o[3] = {-1.0, 1.5, 0.5};
        sem_ray_hit hits[4];
        CHECK(sem_raycast_all(scene, o, dx, 0.0, INFINITY, hits, 4) == 0, "miss");
    }

    /* closest parts within a radius */
    {
        int parts[6];
        double dist[6], pts[18];
        const double X[3] = {0.5, 0.5, 0.1};
        int n = sem_raycast_closest_parts(scene, X, 0.45, parts, dist, pts);
        CHECK(n == 1, "%d parts within 0.45", n);
        if (n >= 1) {
            CHECK(parts[0] == 4, "part %d", parts[0]);
            CHECK_NEAR(dist[0], 0.1, 1e-14);
            CHECK_NEAR(pts[2], 0.0, 1e-14);
            CHECK_NEAR(pts[0], 0.5, 1e-14);
        }
        n = sem_raycast_closest_parts(scene, X, 0.55, parts, dist, pts);
        CHECK(n == 5, "%d parts within 0.55", n);
        if (n == 5) {
            const int expect[5] = {0, 1, 2, 3, 4};
            for (int k = 0; k < 5; k++) CHECK(parts[k] == expect[k], "sorted parts");
            CHECK_NEAR(dist[0], 0.5, 1e-14);
            CHECK_NEAR(dist[4], 0.1, 1e-14);
            CHECK_NEAR(pts[3 * 1 + 0], 1.0, 1e-14); /* on x = 1 */
        }
        const double Y[3] = {1.2, 1.2, 0.5};
        n = sem_raycast_closest_parts(scene, Y, 0.3, parts, dist, pts);
        CHECK(n == 2, "%d parts near the edge", n);
        if (n == 2) {
            CHECK(parts[0] == 1 && parts[1] == 3, "parts %d %d", parts[0], parts[1]);
            CHECK_NEAR(dist[0], sqrt(0.08), 1e-14);
            CHECK_NEAR(dist[1], sqrt(0.08), 1e-14);
            CHECK_NEAR(pts[0], 1.0, 1e-14);
            CHECK_NEAR(pts[1], 1.0, 1e-14);
            CHECK_NEAR(pts[2], 0.5, 1e-14);
        }
        CHECK(sem_raycast_closest_parts(scene, Y, 0.2, parts, dist, pts) == 0, "none");
    }

    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* Two separate cubes, the second entirely flipped (all its normals inward): the fix is per
 * part and finds them all. */
/* Two unit boxes touching at x = 1: the crossing there is merged from two parts' hits (one
 * leaving, one entering), where the surface has no one tangent plane: not smooth; the outer
 * faces' hits are. */
static void test_touching_boxes(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    for (int k = 0; k < 2; ++k) {
        sem_box_def b = sem_default_box_def();
        b.center[0] = 0.5 + k;
        b.center[1] = b.center[2] = 0.5;
        CHECK(sem_primitive_box(m, &b, &err) == SEM_OK, "box: %s", err.message);
    }
    sem_raycast_scene *scene = NULL;
    if (sem_raycast_scene_build(m, 4, &scene, &err) == SEM_OK) {
        const double o[3] = {-1.0, 0.3, 0.7}, dx[3] = {1, 0, 0};
        sem_ray_hit hits[8];
        int n = sem_raycast_all(scene, o, dx, 0.0, INFINITY, hits, 8);
        CHECK(n == 4, "%d hits", n);
        for (int q = 0; q < n && q < 8; ++q) {
            int at_seam = fabs(hits[q].t - 2.0) < 1e-9;
            CHECK(hits[q].smooth == !at_seam, "hit at t = %g: smooth %d", hits[q].t, hits[q].smooth);
        }
    } else {
        CHECK(0, "scene: %s", err.message);
    }
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

static void test_inverted_solid(void)
{
    sem_model *m = sem_model_create();
    const double ex[3] = {1, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    const double O[3] = {3, 0, 0}, X1[3] = {4, 0, 0}, Y1[3] = {3, 1, 0}, Z1[3] = {3, 0, 1};
    add_patch(m, O, ey, ez, 3);  /* x = 3, ey x ez = +x: inward */
    add_patch(m, X1, ez, ey, 3); /* x = 4, -x: inward */
    add_patch(m, O, ez, ex, 3);  /* y = 0, +y: inward */
    add_patch(m, Y1, ex, ez, 3); /* y = 1, -y: inward */
    add_patch(m, O, ex, ey, 3);  /* z = 0, +z: inward */
    add_patch(m, Z1, ey, ex, 3); /* z = 1, -z: inward */
    sem_raycast_scene *scene = NULL;
    sem_error err;
    CHECK(sem_raycast_scene_build(m, 3, &scene, &err) == SEM_OK, "build: %s", err.message);
    if (scene) {
        for (int p = 0; p < 6; p++) CHECK(sem_raycast_part_sign(scene, p) == -1, "part %d", p);
        const double c[3] = {3.5, 0.5, 0.5};
        CHECK_NEAR(sem_raycast_winding_number_exact(scene, c), 1.0, 1e-10);
    }
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* Fast (tree) winding number against the exact sum on a sphere and an open hemisphere-like
 * patch, at points away from the surface. */
static void test_fast_winding(void)
{
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sem_error err;
    CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "sphere");
    /* an open sheet too (the cube's x = 0 face moved away) */
    const double o[3] = {2, -1, -1}, a[3] = {0, 0, 2}, b[3] = {0, 2, 0};
    add_patch(m, o, a, b, 3);
    sem_raycast_scene *scene = NULL;
    CHECK(sem_raycast_scene_build(m, 16, &scene, &err) == SEM_OK, "build: %s", err.message);
    if (scene) {
        double worst = 0, worst_coarse = 0;
        unsigned seed = 12345;
        for (int k = 0; k < 400; k++) {
            double X[3];
            for (int d = 0; d < 3; d++) {
                seed = seed * 1103515245u + 12345u;
                X[d] = -3.0 + 6.0 * (double)(seed >> 8) / (double)(1u << 24);
            }
            double r = sqrt(X[0] * X[0] + X[1] * X[1] + X[2] * X[2]);
            if (fabs(r - 1) < 0.05 || fabs(X[0] - 2) < 0.05) continue;
            double fast = sem_raycast_winding_number(scene, X);
            double exact = sem_raycast_winding_number_exact(scene, X);
            double coarse = sem_raycast_winding_number_coarse(scene, X);
            if (fabs(fast - exact) > worst) worst = fabs(fast - exact);
            if (fabs(coarse - exact) > worst_coarse) worst_coarse = fabs(coarse - exact);
            if (r < 0.95) CHECK(fabs(exact - 1) < 0.2 || fabs(X[0] - 2) < 1, "inside %g", exact);
        }
        printf("fast winding number: worst difference %.3g\n", worst);
        CHECK(worst < 5e-3, "fast vs exact winding number %g", worst);
        /* the coarse far field decides the quadrature's veto (threshold 1/4 between values
         * ~0 and ~1): it must stay well inside that margin */
        printf("coarse winding number: worst difference %.3g\n", worst_coarse);
        CHECK(worst_coarse < 0.1, "coarse vs exact winding number %g", worst_coarse);
        const double c[3] = {0, 0, 0};
        CHECK_NEAR(sem_raycast_winding_number_exact(scene, c) -
                       sem_raycast_winding_number(scene, c), 0.0, 5e-3);
    }
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

static void test_errors(void)
{
    sem_error err;
    sem_raycast_scene *scene = (sem_raycast_scene *)&err; /* must be reset to NULL */
    sem_model *m = sem_model_create();
    CHECK(sem_raycast_scene_build(m, 4, &scene, &err) == SEM_ERR_INVALID, "empty model");
    CHECK(scene == NULL, "out reset");
    sem_model_destroy(m);
    m = make_cube(1);
    CHECK(sem_raycast_scene_build(m, 0, &scene, &err) == SEM_ERR_INVALID, "resolution 0");
    sem_model_destroy(m);
}

int main(void)
{
    test_touching_boxes();
    test_cube(1, 4);
    test_cube(3, 5);
    test_inverted_solid();
    test_fast_winding();
    test_errors();
    return test_finish("raycast");
}
