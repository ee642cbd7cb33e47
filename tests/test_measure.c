/* test_measure.c - areas and bounding boxes of trimmed and curved parts against closed
 * forms and brute force. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/measure.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "test_util.h"

/* A circle of radius r about (cu, cv) in the parameter plane: 4 rational quadratic arcs. */
static void circle_curve(sem_curve *c, double cu, double cv, double r)
{
    static const double xy[9][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1}, {-1, 0},
                                    {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    static const double knots[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
    sem_curve_alloc(c, 2, 9);
    memcpy(c->knots, knots, sizeof knots);
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = cu + r * xy[i][0];
        c->ctrl[3 * i + 1] = cv + r * xy[i][1];
        c->weights[i] = (i % 2) ? sqrt(0.5) : 1.0;
    }
    c->t0 = 0.0;
    c->t1 = 1.0;
}

static void line_curve(sem_curve *c, double u0, double v0, double u1, double v1)
{
    sem_curve_alloc(c, 1, 2);
    c->knots[0] = c->knots[1] = 0.0;
    c->knots[2] = c->knots[3] = 1.0;
    c->ctrl[0] = u0;
    c->ctrl[1] = v0;
    c->ctrl[3] = u1;
    c->ctrl[4] = v1;
    c->t0 = 0.0;
    c->t1 = 1.0;
}

/* Outer loop: the rectangle [u0,u1] x [v0,v1] as 4 lines. */
static void rectangle_loop(sem_trim_loop *loop, double u0, double u1, double v0, double v1)
{
    loop->n_curves = 4;
    loop->curves = calloc(4, sizeof *loop->curves);
    line_curve(&loop->curves[0], u0, v0, u1, v0);
    line_curve(&loop->curves[1], u1, v0, u1, v1);
    line_curve(&loop->curves[2], u1, v1, u0, v1);
    line_curve(&loop->curves[3], u0, v1, u0, v0);
}

/* A side x side planar bilinear square with a circular hole of radius r (in space). */
static void test_square_with_hole(int with_outer)
{
    const double side = 2.0, r = 0.4;
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface *s = &part.surface;
    sem_surface_alloc(s, 1, 1, 2, 2);
    double knots[4] = {0, 0, 1, 1};
    memcpy(s->knots_u, knots, sizeof knots);
    memcpy(s->knots_v, knots, sizeof knots);
    double P[4][3] = {{0, 0, 0}, {side, 0, 0}, {0, side, 0}, {side, side, 0}};
    memcpy(s->ctrl, P, sizeof P);
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
    part.n_holes = 1;
    part.holes = calloc(1, sizeof *part.holes);
    part.holes[0].n_curves = 1;
    part.holes[0].curves = calloc(1, sizeof(sem_curve));
    /* hole centre (0.6, 0.45) in (u,v) = (1.2, 0.9) in space, radius r / side in (u,v) */
    circle_curve(&part.holes[0].curves[0], 0.6, 0.45, r / side);
    if (with_outer) {
        part.has_outer = 1;
        rectangle_loop(&part.outer, 0, 1, 0, 1);
    }
    sem_part_measure_result res;
    sem_error err;
    CHECK(sem_part_measure(&part, &res, &err) == SEM_OK, "measure: %s", err.message);
    double exact = side * side - M_PI * r * r;
    /* target 0.5%; the trim polygon (48 points per arc) is an inscribed 192-gon, whose
     * area differs from the circle's by pi r^2 (2 pi / 192)^2 / 6 = 2.6e-5 of this area,
     * and the integration over the polygon is exact, so expect that much */
    CHECK_REL(res.area, exact, 5e-3);
    CHECK_REL(res.area, exact, 4e-5);
    CHECK_NEAR(res.bbox_min[0], 0.0, 1e-12);
    CHECK_NEAR(res.bbox_max[0], side, 1e-12);
    CHECK_NEAR(res.bbox_max[1], side, 1e-12);
    CHECK_NEAR(res.bbox_max[2], 0.0, 1e-12);
    sem_part_free(&part);
}

/* A hole near the corner: only the part of the plane inside both counts, and the bbox
 * shrinks when the hole takes out a whole side. */
static void test_hole_cuts_bbox(void)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface *s = &part.surface;
    sem_surface_alloc(s, 1, 1, 2, 2);
    double knots[4] = {0, 0, 1, 1};
    memcpy(s->knots_u, knots, sizeof knots);
    memcpy(s->knots_v, knots, sizeof knots);
    double P[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    memcpy(s->ctrl, P, sizeof P);
    s->u1 = s->v1 = 1.0;
    /* outer loop: the strip [0, 0.3] x [0, 1] */
    part.has_outer = 1;
    rectangle_loop(&part.outer, 0, 0.3, 0, 1);
    sem_part_measure_result res;
    sem_error err;
    CHECK(sem_part_measure(&part, &res, &err) == SEM_OK, "measure: %s", err.message);
    CHECK_REL(res.area, 0.3, 1e-12);
    CHECK_NEAR(res.bbox_max[0], 0.3, 1e-6);
    CHECK_NEAR(res.bbox_max[1], 1.0, 1e-12);
    sem_part_free(&part);
}

/* The sphere trimmed to v >= t/2 (a zone above a latitude): Archimedes' area
 * 2 pi r (r - z) and a bbox that ends at that latitude. */
static void test_trimmed_sphere(void)
{
    const double r = 1.5, t = 0.6; /* v = 0.3 on the first (south) quarter arc */
    sem_model *m = sem_model_create();
    sem_sphere_def def = sem_default_sphere_def();
    def.radius = r;
    sem_primitive_sphere(m, &def, NULL);
    sem_part *part = &m->parts[0];
    part->has_outer = 1;
    rectangle_loop(&part->outer, 0, 1, 0.5 * t, 1);
    /* z of the rational quarter arc (0,-r), (r,-r) w = 1/sqrt2, (r,0) at parameter t */
    double h = sqrt(0.5), b0 = (1 - t) * (1 - t), b1 = 2 * t * (1 - t) * h, b2 = t * t;
    double z = (b0 * -r + b1 * -r) / (b0 + b1 + b2);
    double rho = (b1 * r + b2 * r) / (b0 + b1 + b2);
    CHECK_NEAR(rho * rho + z * z, r * r, 1e-12);
    sem_part_measure_result res;
    sem_error err;
    CHECK(sem_part_measure(part, &res, &err) == SEM_OK, "measure: %s", err.message);
    CHECK_REL(res.area, 2 * M_PI * r * (r - z), 1e-9);
    CHECK_NEAR(res.bbox_min[2], z, 1e-6);
    CHECK_NEAR(res.bbox_max[2], r, 1e-9);
    CHECK_NEAR(res.bbox_max[0], r, 1e-9);
    CHECK_NEAR(res.bbox_min[1], -r, 1e-9);
    sem_model_destroy(m);
}

/* A curved bicubic patch with two knot spans: bbox against a brute-force evaluation. */
static void test_curved_bbox(void)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface *s = &part.surface;
    sem_surface_alloc(s, 3, 2, 5, 4);
    double ku[9] = {0, 0, 0, 0, 0.4, 1, 1, 1, 1}, kv[7] = {0, 0, 0, 0.5, 1, 1, 1};
    memcpy(s->knots_u, ku, sizeof ku);
    memcpy(s->knots_v, kv, sizeof kv);
    unsigned seed = 12345u;
    for (int k = 0; k < 20; ++k) {
        int i = k % 5, j = k / 5;
        for (int d = 0; d < 3; ++d) {
            seed = seed * 1103515245u + 12345u;
            double noise = ((seed >> 8) & 0xffff) / 65535.0 - 0.5;
            double base = d == 0 ? i : (d == 1 ? j : 0.0);
            s->ctrl[3 * k + d] = base + 1.5 * noise;
        }
        seed = seed * 1103515245u + 12345u;
        s->weights[k] = 0.5 + ((seed >> 8) & 0xffff) / 65535.0;
    }
    s->u1 = s->v1 = 1.0;
    sem_part_measure_result res;
    sem_error err;
    CHECK(sem_part_measure(&part, &res, &err) == SEM_OK, "measure: %s", err.message);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    const int n = 1200;
    for (int j = 0; j <= n; ++j) {
        for (int i = 0; i <= n; ++i) {
            double x[3];
            sem_surface_eval(s, (double)i / n, (double)j / n, x, NULL, NULL, NULL);
            for (int d = 0; d < 3; ++d) {
                if (x[d] < lo[d]) lo[d] = x[d];
                if (x[d] > hi[d]) hi[d] = x[d];
            }
        }
    }
    double size = 0.0;
    for (int d = 0; d < 3; ++d) size = fmax(size, hi[d] - lo[d]);
    for (int d = 0; d < 3; ++d) {
        /* contains every brute-force point, and is no looser than the grid's error */
        CHECK(res.bbox_min[d] <= lo[d] + 1e-12 && res.bbox_max[d] >= hi[d] - 1e-12,
              "coordinate %d: bbox [%.15g, %.15g] misses brute force [%.15g, %.15g]", d,
              res.bbox_min[d], res.bbox_max[d], lo[d], hi[d]);
        CHECK_NEAR(res.bbox_min[d], lo[d], 1e-6 * size);
        CHECK_NEAR(res.bbox_max[d], hi[d], 1e-6 * size);
    }
    /* control points bound the surface but not tightly: the measure is tighter */
    double cmin = INFINITY;
    for (int k = 0; k < 20; ++k) cmin = fmin(cmin, s->ctrl[3 * k + 2]);
    CHECK(res.bbox_min[2] >= cmin - 1e-12, "bbox below the control hull");
    sem_part_free(&part);
}

/* The model total is the serial sum of the parts; a broken trim is reported with the
 * part's number and the other parts are still measured. */
static void test_model_totals_and_errors(void)
{
    sem_model *m = sem_model_create();
    sem_box_def box = sem_default_box_def();
    sem_primitive_box(m, &box, NULL);
    sem_sphere_def sph = sem_default_sphere_def();
    sph.center[0] = 5.0;
    sem_primitive_sphere(m, &sph, NULL);
    sem_part_measure_result per[7], total;
    sem_error err;
    CHECK(sem_model_measure(m, per, &total, &err) == SEM_OK, "measure: %s", err.message);
    CHECK_REL(total.area, 6.0 + 4.0 * M_PI, 1e-9);
    CHECK_NEAR(total.bbox_min[0], -0.5, 1e-12);
    CHECK_NEAR(total.bbox_max[0], 6.0, 1e-9);
    CHECK_REL(per[6].area, 4.0 * M_PI, 1e-9);
    /* a hole loop that does not close */
    sem_part *p = &m->parts[2];
    p->n_holes = 1;
    p->holes = calloc(1, sizeof *p->holes);
    p->holes[0].n_curves = 1;
    p->holes[0].curves = calloc(1, sizeof(sem_curve));
    line_curve(&p->holes[0].curves[0], 0.2, 0.2, 0.8, 0.7);
    sem_status st = sem_model_measure(m, per, &total, &err);
    CHECK(st != SEM_OK, "open hole loop accepted");
    CHECK(strstr(err.message, "part 3") != NULL, "message does not name the part: %s",
          err.message);
    CHECK(isnan(per[2].area), "failed part has area %g", per[2].area);
    CHECK_REL(total.area, 5.0 + 4.0 * M_PI, 1e-9);
    sem_model_destroy(m);
}

int main(void)
{
    test_square_with_hole(0);
    test_square_with_hole(1);
    test_hole_cuts_bbox();
    test_trimmed_sphere();
    test_curved_bbox();
    test_model_totals_and_errors();
    return test_finish("test_measure");
}
