/* test_trim.c - inside/outside on trimmed domains: holes, reversed curves, open loops. */
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/trim.h"
#include "test_util.h"

/* a line segment as a degree-1 curve */
static void line(sem_curve *c, double u0, double v0, double u1, double v1)
{
    sem_curve_alloc(c, 1, 2);
    double k[4] = {0, 0, 1, 1};
    memcpy(c->knots, k, sizeof k);
    c->ctrl[0] = u0;
    c->ctrl[1] = v0;
    c->ctrl[3] = u1;
    c->ctrl[4] = v1;
    c->t0 = 0;
    c->t1 = 1;
}

/* a full circle as 4 rational quadratic arcs in one curve (9 control points) */
static void circle(sem_curve *c, double cu, double cv, double r)
{
    sem_curve_alloc(c, 2, 9);
    double k[12] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
    memcpy(c->knots, k, sizeof k);
    double p[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = cu + r * p[i][0];
        c->ctrl[3 * i + 1] = cv + r * p[i][1];
        c->weights[i] = (i % 2) ? sqrt(0.5) : 1.0;
    }
    c->t0 = 0;
    c->t1 = 4;
}

static void make_plane(sem_part *part)
{
    memset(part, 0, sizeof *part);
    sem_surface_alloc(&part->surface, 1, 1, 2, 2);
    double k[4] = {0, 0, 2, 2};
    memcpy(part->surface.knots_u, k, sizeof k);
    memcpy(part->surface.knots_v, k, sizeof k);
    double P[12] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 2, 2, 0};
    memcpy(part->surface.ctrl, P, sizeof P);
    part->surface.u0 = part->surface.v0 = 0;
    part->surface.u1 = part->surface.v1 = 2;
}

/* Monte-Carlo-free area: fraction of a fine grid inside = area / domain area */
static double grid_area(const sem_trim_region *r, int n)
{
    int inside = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j) inside += sem_trim_region_inside(r, 2.0 * (i + 0.5) / n, 2.0 * (j + 0.5) / n);
    return 4.0 * inside / ((double)n * n);
}

static void test_hole_without_outer(void)
{
    sem_part part;
    make_plane(&part);
    part.n_holes = 1;
    part.holes = calloc(1, sizeof *part.holes);
    part.holes[0].n_curves = 1;
    part.holes[0].curves = calloc(1, sizeof(sem_curve));
    circle(&part.holes[0].curves[0], 1.0, 1.0, 0.5);
    sem_trim_region *r;
    sem_error err;
    CHECK(sem_trim_region_build(&part, &r, &err) == SEM_OK, "%s", err.message);
    CHECK(!sem_trim_region_inside(r, 1.0, 1.0), "centre of hole is outside");
    CHECK(sem_trim_region_inside(r, 0.1, 0.1), "corner is inside");
    CHECK(!sem_trim_region_inside(r, 1.0 + 0.5 * cos(0.3) * 0.999, 1.0 + 0.5 * sin(0.3) * 0.999), "just inside hole");
    CHECK(sem_trim_region_inside(r, 1.0 + 0.5 * cos(0.3) * 1.001, 1.0 + 0.5 * sin(0.3) * 1.001), "just outside hole");
    CHECK_NEAR(grid_area(r, 800), 4.0 - M_PI * 0.25, 2e-3);
    sem_trim_region_destroy(r);
    sem_part_free(&part);
}

/* Outer loop of 4 lines given in mixed directions, one reversed. */
static void test_outer_mixed_directions(void)
{
    sem_part part;
    make_plane(&part);
    part.has_outer = 1;
    part.outer.n_curves = 4;
    part.outer.curves = calloc(4, sizeof(sem_curve));
    line(&part.outer.curves[0], 0.5, 0.5, 1.5, 0.5);
    line(&part.outer.curves[1], 1.5, 1.5, 1.5, 0.5); /* reversed */
    line(&part.outer.curves[2], 1.5, 1.5, 0.5, 1.5);
    line(&part.outer.curves[3], 0.5, 1.5, 0.5, 0.5);
    sem_trim_region *r;
    sem_error err;
    CHECK(sem_trim_region_build(&part, &r, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_trim_region_inside(r, 1.0, 1.0), "centre inside");
    CHECK(!sem_trim_region_inside(r, 0.2, 1.0), "outside left");
    CHECK(!sem_trim_region_inside(r, 1.0, 1.7), "outside top");
    CHECK_NEAR(grid_area(r, 400), 1.0, 1e-9);
    sem_trim_region_destroy(r);

    /* open the loop: move the last segment's end away */
    part.outer.curves[3].ctrl[4] = 0.8;
    CHECK(sem_trim_region_build(&part, &r, &err) == SEM_ERR_INVALID, "open loop rejected");
    CHECK(strstr(err.message, "does not close") != NULL, "%s", err.message);
    CHECK(sem_part_validate_trims(&part, &err) == SEM_ERR_INVALID, "validate rejects");
    sem_part_free(&part);
}

int main(void)
{
    test_hole_without_outer();
    test_outer_mixed_directions();
    return test_finish("test_trim");
}
