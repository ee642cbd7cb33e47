/*
 * primitives.c - exact NURBS boxes, beams, spheres, cylinders and tori (see sem/primitives.h).
 *
 * Two constructions cover every shape:
 *  - planar Bezier patches with evenly spaced control points, so that x(u,v) = o + u a + v b
 *    exactly (box faces, beam sides);
 *  - rational surfaces of revolution (Piegl & Tiller A8.1): a profile (rho(v), z(v)) given
 *    as a rational curve, swept by the 9-point quadratic rational circle. The control point
 *    (i,j) is (rho_j cx_i, rho_j cy_i, z_j) with weight wu_i wv_j, which reproduces
 *    (rho(v) c(u), z(v)) exactly because both factors share their denominators.
 * Orientation: for a revolution x_u x x_v = rho theta' (z' e_r - rho' e_z), so a profile
 * that runs counter-clockwise in the (rho, z) half-plane gives outward normals.
 */
#include "sem/primitives.h"
#include "sem/limits.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

sem_box_def sem_default_box_def(void)
{
    sem_box_def d = {{1.0, 1.0, 1.0}, {0.0, 0.0, 0.0}, 3};
    return d;
}

sem_beam_def sem_default_beam_def(void)
{
    sem_beam_def d = {1, 5.0, 1.0, 1.0, 2};
    return d;
}

sem_sphere_def sem_default_sphere_def(void)
{
    sem_sphere_def d = {1.0, {0.0, 0.0, 0.0}};
    return d;
}

sem_cylinder_def sem_default_cylinder_def(void)
{
    sem_cylinder_def d = {1.0, 2.0, {0.0, 0.0, 0.0}};
    return d;
}

sem_torus_def sem_default_torus_def(void)
{
    sem_torus_def d = {1.0, 0.25, {0.0, 0.0, 0.0}};
    return d;
}

/* ---- checks ---- */

static int positive(double x)
{
    return isfinite(x) && x > 0.0;
}

static int finite3(const double c[3])
{
    return isfinite(c[0]) && isfinite(c[1]) && isfinite(c[2]);
}

/* ---- planar Bezier patch ---- */

static void bezier_knots(double *knots, int degree)
{
    for (int k = 0; k <= degree; ++k) {
        knots[k] = 0.0;
        knots[degree + 1 + k] = 1.0;
    }
}

/* Appends the patch x(u,v) = origin + u a + v b, (u,v) in [0,1]^2; normal a x b. */
static sem_status add_planar_patch(sem_model *model, const char *name, int color,
                                   const double origin[3], const double a[3], const double b[3],
                                   int degree, sem_error *err)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    int n = degree + 1;
    if (sem_surface_alloc(&part.surface, degree, degree, n, n) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory building a primitive");
    sem_surface *s = &part.surface;
    bezier_knots(s->knots_u, degree);
    bezier_knots(s->knots_v, degree);
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
    for (int j = 0; j < n; ++j) {
        for (int i = 0; i < n; ++i) {
            double *P = s->ctrl + 3 * (i + n * j);
            double su = (double)i / degree, sv = (double)j / degree;
            for (int d = 0; d < 3; ++d) P[d] = origin[d] + su * a[d] + sv * b[d];
        }
    }
    snprintf(part.name, sizeof part.name, "%s", name);
    part.color = color;
    sem_status st = sem_model_take_part(model, &part, err);
    if (st != SEM_OK) sem_part_free(&part);
    return st;
}

/* ---- surfaces of revolution ---- */

/* The unit circle as 9 rational quadratic control points, 4 arcs of 90 degrees. */
static const double circle_xy[9][2] = {{1, 0},  {1, 1},   {0, 1},  {-1, 1}, {-1, 0},
                                       {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
static const double circle_knots[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};

static double circle_weight(int i)
{
    return (i % 2) ? sqrt(0.5) : 1.0;
}

/* A degree-2 profile curve in the (rho, z) half-plane. */
typedef struct profile {
    int n;
    const double (*rz)[2];
    const double *weights;
    const double *knots; /* n + 3 */
} profile;

static sem_status add_revolution(sem_model *model, const char *name, const double center[3],
                                 const profile *pr, sem_error *err)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    if (sem_surface_alloc(&part.surface, 2, 2, 9, pr->n) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory building a primitive");
    sem_surface *s = &part.surface;
    memcpy(s->knots_u, circle_knots, sizeof circle_knots);
    memcpy(s->knots_v, pr->knots, (size_t)(pr->n + 3) * sizeof(double));
    s->u0 = 0.0;
    s->u1 = 1.0;
    s->v0 = pr->knots[0];
    s->v1 = pr->knots[pr->n + 2];
    s->closed_u = 1;
    for (int j = 0; j < pr->n; ++j) {
        for (int i = 0; i < 9; ++i) {
            int k = i + 9 * j;
            double *P = s->ctrl + 3 * k;
            P[0] = center[0] + pr->rz[j][0] * circle_xy[i][0];
            P[1] = center[1] + pr->rz[j][0] * circle_xy[i][1];
            P[2] = center[2] + pr->rz[j][1];
            s->weights[k] = circle_weight(i) * pr->weights[j];
        }
    }
    snprintf(part.name, sizeof part.name, "%s", name);
    sem_status st = sem_model_take_part(model, &part, err);
    if (st != SEM_OK) sem_part_free(&part);
    return st;
}

/* ---- box ---- */

sem_status sem_primitive_box(sem_model *model, const sem_box_def *def, sem_error *err)
{
    if (!positive(def->size[0]) || !positive(def->size[1]) || !positive(def->size[2]))
        return sem_error_set(err, SEM_ERR_INVALID, "box size %g x %g x %g must be positive",
                             def->size[0], def->size[1], def->size[2]);
    if (!finite3(def->center))
        return sem_error_set(err, SEM_ERR_INVALID, "box centre is not finite");
    if (def->degree < 1 || def->degree > 10)
        return sem_error_set(err, SEM_ERR_INVALID, "box degree %d out of range 1..10",
                             def->degree);
    double lo[3], hi[3];
    for (int d = 0; d < 3; ++d) {
        lo[d] = def->center[d] - 0.5 * def->size[d];
        hi[d] = def->center[d] + 0.5 * def->size[d];
    }
    double X = def->size[0], Y = def->size[1], Z = def->size[2];
    /* each face: origin, u edge, v edge with u x v along the outward normal */
    struct {
        const char *name;
        double o[3], a[3], b[3];
    } faces[6] = {
        {"box_xmin", {lo[0], lo[1], lo[2]}, {0, 0, Z}, {0, Y, 0}},
        {"box_xmax", {hi[0], lo[1], lo[2]}, {0, Y, 0}, {0, 0, Z}},
        {"box_ymin", {lo[0], lo[1], lo[2]}, {X, 0, 0}, {0, 0, Z}},
        {"box_ymax", {lo[0], hi[1], lo[2]}, {0, 0, Z}, {X, 0, 0}},
        {"box_zmin", {lo[0], lo[1], lo[2]}, {0, Y, 0}, {X, 0, 0}},
        {"box_zmax", {lo[0], lo[1], hi[2]}, {X, 0, 0}, {0, Y, 0}},
    };
    for (int f = 0; f < 6; ++f) {
        sem_status st = add_planar_patch(model, faces[f].name, 0, faces[f].o, faces[f].a,
                                         faces[f].b, def->degree, err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

/* ---- beam ---- */

sem_status sem_primitive_beam(sem_model *model, const sem_beam_def *def, sem_error *err)
{
    if (def->sections < 1 || def->sections > SEM_MAX_BEAM_SECTIONS)
        return sem_error_set(err, SEM_ERR_INVALID, "beam sections %d out of range 1..%d",
                             def->sections, SEM_MAX_BEAM_SECTIONS);
    if (!positive(def->length) || !positive(def->width) || !positive(def->height))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "beam length %g, width %g and height %g must be positive",
                             def->length, def->width, def->height);
    if (def->degree < 1 || def->degree > 10)
        return sem_error_set(err, SEM_ERR_INVALID, "beam degree %d out of range 1..10",
                             def->degree);
    const double L = def->length, W = def->width, H = def->height;
    const int p = def->degree;
    sem_status st;
    /* end caps first, as in the paper's files; x = 0 is the clamped end (IGES colour 2, red) */
    double o0[3] = {0, 0, 0}, oL[3] = {L, 0, 0};
    double ez[3] = {0, 0, H}, ey[3] = {0, W, 0};
    st = add_planar_patch(model, "beam_end_x0", 2, o0, ez, ey, p, err); /* normal -x */
    if (st != SEM_OK) return st;
    st = add_planar_patch(model, "beam_end_xL", 0, oL, ey, ez, p, err); /* normal +x */
    if (st != SEM_OK) return st;
    for (int k = 0; k < def->sections; ++k) {
        /* section end points computed from k directly (no accumulated round-off) */
        double x0 = L * k / def->sections, x1 = L * (k + 1) / def->sections;
        double dx = x1 - x0;
        double ex[3] = {dx, 0, 0};
        struct {
            const char *side;
            double o[3];
            const double *a, *b;
        } sides[4] = {
            {"bottom", {x0, 0, 0}, ey, ex}, /* y x x = -z */
            {"top", {x0, 0, H}, ex, ey},    /* x x y = +z */
            {"front", {x0, 0, 0}, ex, ez},  /* x x z = -y */
            {"back", {x0, W, 0}, ez, ex},   /* z x x = +y */
        };
        for (int f = 0; f < 4; ++f) {
            char name[64];
            snprintf(name, sizeof name, "beam_s%d_%s", k + 1, sides[f].side);
            st = add_planar_patch(model, name, 0, sides[f].o, sides[f].a, sides[f].b, p, err);
            if (st != SEM_OK) return st;
        }
    }
    return SEM_OK;
}

/* ---- sphere, cylinder, torus ---- */

sem_status sem_primitive_sphere(sem_model *model, const sem_sphere_def *def, sem_error *err)
{
    if (!positive(def->radius))
        return sem_error_set(err, SEM_ERR_INVALID, "sphere radius %g must be positive",
                             def->radius);
    if (!finite3(def->center))
        return sem_error_set(err, SEM_ERR_INVALID, "sphere centre is not finite");
    const double r = def->radius, h = sqrt(0.5);
    /* semicircle from the south pole to the north pole (counter-clockwise in (rho, z)) */
    const double rz[5][2] = {{0, -r}, {r, -r}, {r, 0}, {r, r}, {0, r}};
    const double w[5] = {1, h, 1, h, 1};
    const double knots[8] = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    profile pr = {5, rz, w, knots};
    return add_revolution(model, "sphere", def->center, &pr, err);
}

sem_status sem_primitive_cylinder(sem_model *model, const sem_cylinder_def *def, sem_error *err)
{
    if (!positive(def->radius) || !positive(def->height))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "cylinder radius %g and height %g must be positive", def->radius,
                             def->height);
    if (!finite3(def->center))
        return sem_error_set(err, SEM_ERR_INVALID, "cylinder centre is not finite");
    const double r = def->radius, zb = -0.5 * def->height, zt = 0.5 * def->height;
    const double w[3] = {1, 1, 1};
    const double knots[6] = {0, 0, 0, 1, 1, 1};
    /* side: upward line at rho = r; bottom: centre to rim; top: rim to centre. All three
     * run counter-clockwise around the solid's (rho, z) cross-section, hence outward. */
    const double side[3][2] = {{r, zb}, {r, 0.0}, {r, zt}};
    const double bottom[3][2] = {{0, zb}, {0.5 * r, zb}, {r, zb}};
    const double top[3][2] = {{r, zt}, {0.5 * r, zt}, {0, zt}};
    profile p_side = {3, side, w, knots}, p_bottom = {3, bottom, w, knots},
            p_top = {3, top, w, knots};
    sem_status st = add_revolution(model, "cylinder_side", def->center, &p_side, err);
    if (st == SEM_OK) st = add_revolution(model, "cylinder_bottom", def->center, &p_bottom, err);
    if (st == SEM_OK) st = add_revolution(model, "cylinder_top", def->center, &p_top, err);
    return st;
}

sem_status sem_primitive_torus(sem_model *model, const sem_torus_def *def, sem_error *err)
{
    if (!positive(def->major) || !positive(def->minor) || !(def->minor < def->major))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "torus radii major %g, minor %g: need 0 < minor < major",
                             def->major, def->minor);
    if (!finite3(def->center))
        return sem_error_set(err, SEM_ERR_INVALID, "torus centre is not finite");
    double rz[9][2], w[9];
    for (int j = 0; j < 9; ++j) {
        rz[j][0] = def->major + def->minor * circle_xy[j][0];
        rz[j][1] = def->minor * circle_xy[j][1];
        w[j] = circle_weight(j);
    }
    profile pr = {9, (const double(*)[2])rz, w, circle_knots};
    sem_status st = add_revolution(model, "torus", def->center, &pr, err);
    if (st == SEM_OK) model->parts[model->n_parts - 1].surface.closed_v = 1;
    return st;
}
