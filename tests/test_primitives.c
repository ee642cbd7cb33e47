/* test_primitives.c - the built-in solids are exact, closed forms hold, normals point out. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/measure.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "test_util.h"

static double model_area(const sem_model *m)
{
    sem_part_measure_result total;
    sem_error err;
    sem_status st = sem_model_measure(m, NULL, &total, &err);
    CHECK(st == SEM_OK, "measure failed: %s", err.message);
    return total.area;
}

/* The normal at the centre of every part's domain points away from `inside` (the
 * solid's centroid). */
static void check_outward(const sem_model *m, const double inside[3], const char *what)
{
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        double u = 0.5 * (s->u0 + s->u1), v = 0.5 * (s->v0 + s->v1), x[3], n[3];
        sem_surface_eval(s, u, v, x, NULL, NULL, NULL);
        sem_surface_normal(s, u, v, n);
        double d[3] = {x[0] - inside[0], x[1] - inside[1], x[2] - inside[2]};
        double dot = d[0] * n[0] + d[1] * n[1] + d[2] * n[2];
        CHECK(dot > 0, "%s part %d (%s): normal (%g %g %g) at (%g %g %g) points inward", what, i,
              m->parts[i].name, n[0], n[1], n[2], x[0], x[1], x[2]);
    }
}

static void test_box(void)
{
    sem_model *m = sem_model_create();
    sem_box_def def = sem_default_box_def();
    def.size[0] = 2.0;
    def.size[1] = 0.5;
    def.size[2] = 3.0;
    def.center[0] = 1.0;
    def.center[2] = -4.0;
    sem_error err;
    CHECK(sem_primitive_box(m, &def, &err) == SEM_OK, "box: %s", err.message);
    CHECK(m->n_parts == 6, "box has %d parts", m->n_parts);
    CHECK(sem_model_control_points(m) == 96, "box control points %zu", sem_model_control_points(m));
    for (int i = 0; i < m->n_parts; ++i)
        CHECK(m->parts[i].surface.degree_u == 3 && m->parts[i].surface.degree_v == 3 &&
                  m->parts[i].surface.n_u == 4 && m->parts[i].surface.n_v == 4,
              "box part %d is not bicubic 4x4", i);
    double X = 2.0, Y = 0.5, Z = 3.0;
    CHECK_REL(model_area(m), 2.0 * (X * Y + Y * Z + X * Z), 1e-9);
    double inside[3] = {1.0, 0.0, -4.0};
    check_outward(m, inside, "box");
    sem_part_measure_result total;
    sem_model_measure(m, NULL, &total, &err);
    CHECK_NEAR(total.bbox_min[0], 0.0, 1e-12);
    CHECK_NEAR(total.bbox_max[0], 2.0, 1e-12);
    CHECK_NEAR(total.bbox_min[1], -0.25, 1e-12);
    CHECK_NEAR(total.bbox_max[2], -2.5, 1e-12);
    /* invalid sizes are rejected with a message */
    def.size[1] = -1.0;
    CHECK(sem_primitive_box(m, &def, &err) == SEM_ERR_INVALID && strstr(err.message, "box"),
          "negative size accepted (%s)", err.message);
    sem_model_destroy(m);
}

static void test_sphere(void)
{
    const double r = 1.7, c[3] = {0.3, -2.0, 5.0};
    sem_model *m = sem_model_create();
    sem_sphere_def def = sem_default_sphere_def();
    def.radius = r;
    memcpy(def.center, c, sizeof c);
    sem_error err;
    CHECK(sem_primitive_sphere(m, &def, &err) == SEM_OK, "sphere: %s", err.message);
    CHECK(m->n_parts == 1 && m->parts[0].surface.n_u == 9 && m->parts[0].surface.n_v == 5,
          "sphere net");
    CHECK(sem_surface_validate(&m->parts[0].surface, &err) == SEM_OK, "sphere: %s", err.message);
    /* every point on the sphere to 1e-12, poles and seams included */
    double worst = 0.0;
    for (int j = 0; j <= 40; ++j) {
        for (int i = 0; i <= 40; ++i) {
            double x[3];
            sem_surface_eval(&m->parts[0].surface, i / 40.0, j / 40.0, x, NULL, NULL, NULL);
            double d = sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                            (x[2] - c[2]) * (x[2] - c[2]));
            if (fabs(d - r) > worst) worst = fabs(d - r);
        }
    }
    for (int k = 0; k < 1000; ++k) { /* irrational-ish parameters */
        double u = fmod(k * 0.6180339887498949, 1.0), v = fmod(k * 0.4142135623730951, 1.0);
        double x[3];
        sem_surface_eval(&m->parts[0].surface, u, v, x, NULL, NULL, NULL);
        double d = sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                        (x[2] - c[2]) * (x[2] - c[2]));
        if (fabs(d - r) > worst) worst = fabs(d - r);
    }
    CHECK(worst <= 1e-12 * r, "sphere point off by %g", worst);
    /* the poles are the parameter ends in v */
    double pole[3];
    sem_surface_eval(&m->parts[0].surface, 0.3, 1.0, pole, NULL, NULL, NULL);
    CHECK_NEAR(pole[2], c[2] + r, 1e-12);
    sem_surface_eval(&m->parts[0].surface, 0.7, 0.0, pole, NULL, NULL, NULL);
    CHECK_NEAR(pole[2], c[2] - r, 1e-12);
    CHECK_REL(model_area(m), 4.0 * M_PI * r * r, 1e-9);
    check_outward(m, c, "sphere");
    sem_part_measure_result total;
    sem_model_measure(m, NULL, &total, &err);
    for (int d = 0; d < 3; ++d) {
        CHECK_NEAR(total.bbox_min[d], c[d] - r, 1e-9);
        CHECK_NEAR(total.bbox_max[d], c[d] + r, 1e-9);
    }
    sem_model_destroy(m);
}

static void test_torus(void)
{
    const double R = 2.0, r = 0.5;
    sem_model *m = sem_model_create();
    sem_torus_def def = sem_default_torus_def();
    def.major = R;
    def.minor = r;
    sem_error err;
    CHECK(sem_primitive_torus(m, &def, &err) == SEM_OK, "torus: %s", err.message);
    CHECK(sem_model_control_points(m) == 81, "torus net %zu", sem_model_control_points(m));
    double worst = 0.0;
    for (int k = 0; k < 2000; ++k) {
        double u = fmod(k * 0.6180339887498949, 1.0), v = fmod(k * 0.7320508075688772, 1.0);
        double x[3];
        sem_surface_eval(&m->parts[0].surface, u, v, x, NULL, NULL, NULL);
        double rho = sqrt(x[0] * x[0] + x[1] * x[1]);
        double d = sqrt((rho - R) * (rho - R) + x[2] * x[2]);
        if (fabs(d - r) > worst) worst = fabs(d - r);
    }
    CHECK(worst <= 1e-12, "torus point off the tube by %g", worst);
    CHECK_REL(model_area(m), 4.0 * M_PI * M_PI * R * r, 1e-9);
    /* outward: away from the tube's centre circle */
    const sem_surface *s = &m->parts[0].surface;
    for (int k = 0; k < 16; ++k) {
        double u = (k + 0.5) / 16.0, v = fmod(k * 0.37, 1.0), x[3], n[3];
        sem_surface_eval(s, u, v, x, NULL, NULL, NULL);
        sem_surface_normal(s, u, v, n);
        double rho = sqrt(x[0] * x[0] + x[1] * x[1]);
        double t[3] = {x[0] - R * x[0] / rho, x[1] - R * x[1] / rho, x[2]};
        CHECK(t[0] * n[0] + t[1] * n[1] + t[2] * n[2] > 0, "torus normal inward at u %g v %g", u,
              v);
    }
    def.minor = 3.0;
    CHECK(sem_primitive_torus(m, &def, &err) == SEM_ERR_INVALID, "minor > major accepted");
    sem_model_destroy(m);
}

static void test_cylinder(void)
{
    const double r = 0.75, h = 3.0, c[3] = {1.0, 2.0, 3.0};
    sem_model *m = sem_model_create();
    sem_cylinder_def def = sem_default_cylinder_def();
    def.radius = r;
    def.height = h;
    memcpy(def.center, c, sizeof c);
    sem_error err;
    CHECK(sem_primitive_cylinder(m, &def, &err) == SEM_OK, "cylinder: %s", err.message);
    CHECK(m->n_parts == 3, "cylinder parts %d", m->n_parts);
    CHECK_REL(model_area(m), 2.0 * M_PI * r * h + 2.0 * M_PI * r * r, 1e-9);
    /* side points at distance r from the axis, caps in their planes within r */
    double worst = 0.0;
    for (int k = 0; k < 500; ++k) {
        double u = fmod(k * 0.6180339887498949, 1.0), v = fmod(k * 0.4142135623730951, 1.0);
        double x[3];
        sem_surface_eval(&m->parts[0].surface, u, v, x, NULL, NULL, NULL);
        double rho = hypot(x[0] - c[0], x[1] - c[1]);
        if (fabs(rho - r) > worst) worst = fabs(rho - r);
        sem_surface_eval(&m->parts[2].surface, u, v, x, NULL, NULL, NULL);
        if (fabs(x[2] - (c[2] + 0.5 * h)) > worst) worst = fabs(x[2] - (c[2] + 0.5 * h));
    }
    CHECK(worst <= 1e-12, "cylinder points off by %g", worst);
    check_outward(m, c, "cylinder");
    sem_part_measure_result total;
    sem_model_measure(m, NULL, &total, &err);
    CHECK_NEAR(total.bbox_min[0], c[0] - r, 1e-9);
    CHECK_NEAR(total.bbox_max[1], c[1] + r, 1e-9);
    CHECK_NEAR(total.bbox_max[2], c[2] + 0.5 * h, 1e-12);
    sem_model_destroy(m);
}

static void test_beam(void)
{
    for (int sections = 1; sections <= 10; sections += 3) {
        sem_model *m = sem_model_create();
        sem_beam_def def = sem_default_beam_def();
        def.sections = sections;
        sem_error err;
        CHECK(sem_primitive_beam(m, &def, &err) == SEM_OK, "beam: %s", err.message);
        int parts = 6 + 4 * (sections - 1);
        CHECK(m->n_parts == parts, "beam %d sections has %d parts, want %d", sections,
              m->n_parts, parts);
        /* the paper's files: biquadratic 3 x 3 patches, so q = 3 * 9 * parts (b1: 162) */
        CHECK(sem_model_control_points(m) * 3 == (size_t)(27 * parts), "beam dofs %zu",
              3 * sem_model_control_points(m));
        /* default 5 x 1 x 1: area 2 * (5 + 5 + 1) = 22 */
        CHECK_REL(model_area(m), 22.0, 1e-9);
        double inside[3] = {2.5, 0.5, 0.5};
        check_outward(m, inside, "beam");
        /* the clamped end x = 0 is the first part */
        double x[3];
        sem_surface_eval(&m->parts[0].surface, 0.3, 0.6, x, NULL, NULL, NULL);
        CHECK_NEAR(x[0], 0.0, 0.0);
        sem_model_destroy(m);
    }
}

int main(void)
{
    test_box();
    test_sphere();
    test_torus();
    test_cylinder();
    test_beam();
    return test_finish("test_primitives");
}
