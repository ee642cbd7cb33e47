/* test_quadrature.c - ray-cast volume quadrature (Sec. 6.3, Eq. 11, Fig. 7).
 *
 * Boxes are exact for any ray grid (their intervals are exact and the grid spans the
 * bounding box), so they check the bookkeeping to 1e-12: CSG union of overlapping solids,
 * innermost-part materials, inward faces, the winding-number fallback. The sphere checks
 * convergence (Fig. 7). The paper's models check robustness on real CAD data. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "preprocess/steps.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "test_util.h"

static sem_preprocess_options options(int n1, int n2, int axis, int ppi, int tessellation)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    o.rays[0] = n1;
    o.rays[1] = n2;
    o.ray_axis = axis;
    o.points_per_interval = ppi;
    o.tessellation = tessellation;
    return o;
}

static void free_quad(sem_discretization *d)
{
    free(d->quad_X);
    free(d->quad_volume);
    free(d->quad_part);
    memset(d, 0, sizeof *d);
}

/* Quadrature of a model; returns the status, fills d. */
static sem_status run(const sem_model *m, const sem_preprocess_options *o, sem_discretization *d,
                      sem_raycast_scene **keep_scene)
{
    memset(d, 0, sizeof *d);
    sem_raycast_scene *scene = NULL;
    sem_error err;
    sem_status st = sem_raycast_scene_build(m, o->tessellation, &scene, &err);
    CHECK(st == SEM_OK, "scene: %s", err.message);
    if (st != SEM_OK) return st;
    st = sem_step_quadrature(m, scene, o, d, &err);
    CHECK(st == SEM_OK, "quadrature: %s", err.message);
    if (keep_scene)
        *keep_scene = scene;
    else
        sem_raycast_scene_destroy(scene);
    return st;
}

static double volume_sum(const sem_discretization *d)
{
    double v = 0;
    for (int p = 0; p < d->n_quad; p++) v += d->quad_volume[p];
    return v;
}

static void add_box(sem_model *m, double sx, double sy, double sz, double cx, double cy,
                    double cz)
{
    sem_box_def b = sem_default_box_def();
    b.size[0] = sx;
    b.size[1] = sy;
    b.size[2] = sz;
    b.center[0] = cx;
    b.center[1] = cy;
    b.center[2] = cz;
    sem_error err;
    CHECK(sem_primitive_box(m, &b, &err) == SEM_OK, "box: %s", err.message);
}

/* A box's volume is exact for every grid and axis; points lie in the box. */
static void test_box_exact(void)
{
    sem_model *m = sem_model_create();
    add_box(m, 2.0, 3.0, 0.5, 0.1, -0.2, 0.3);
    const int grids[][2] = {{1, 1}, {7, 5}, {3, 11}};
    for (int axis = 0; axis < 3; axis++)
        for (size_t g = 0; g < 3; g++) {
            sem_preprocess_options o = options(grids[g][0], grids[g][1], axis, 3, 2);
            sem_discretization d;
            if (run(m, &o, &d, NULL) != SEM_OK) continue;
            CHECK_REL(d.volume, 3.0, 1e-12);
            CHECK_REL(volume_sum(&d), d.volume, 1e-15);
            CHECK(d.n_quad == grids[g][0] * grids[g][1] * 3, "n_quad %d", d.n_quad);
            int inside = 1, parts_ok = 1;
            for (int p = 0; p < d.n_quad; p++) {
                const double *X = d.quad_X + 3 * p;
                if (fabs(X[0] - 0.1) > 1.0 || fabs(X[1] + 0.2) > 1.5 || fabs(X[2] - 0.3) > 0.25)
                    inside = 0;
                if (d.quad_part[p] < 0 || d.quad_part[p] >= 6) parts_ok = 0;
            }
            CHECK(inside, "points inside the box (axis %d)", axis);
            CHECK(parts_ok, "parts in range");
            free_quad(&d);
        }
    sem_model_destroy(m);
}

/* Reverses the u direction of a part's control net: flips its normal. */
static void flip_part(sem_part *part)
{
    sem_surface *s = &part->surface;
    for (int j = 0; j < s->n_v; j++)
        for (int i = 0; i < s->n_u / 2; i++) {
            int a = i + s->n_u * j, b = (s->n_u - 1 - i) + s->n_u * j;
            for (int d = 0; d < 3; d++) {
                double t = s->ctrl[3 * a + d];
                s->ctrl[3 * a + d] = s->ctrl[3 * b + d];
                s->ctrl[3 * b + d] = t;
            }
            double w = s->weights[a];
            s->weights[a] = s->weights[b];
            s->weights[b] = w;
        }
}

/* Overlapping boxes count once (CSG union, Fig. 17), inward faces are fixed, nested boxes
 * give the inner part's material to the inner points. */
static void test_union_and_materials(void)
{
    /* A = [0,2]^3, B = [1,3] x [0.5,2.5]^2 (B's y = 0.5 face flipped):
     * |A u B| = 8 + 8 - 1 x 1.5 x 1.5 */
    sem_model *m = sem_model_create();
    add_box(m, 2, 2, 2, 1, 1, 1);
    add_box(m, 2, 2, 2, 2, 1.5, 1.5);
    for (int p = 6; p < 12; p++) {
        double X[3];
        sem_surface_eval(&m->parts[p].surface, 0.5, 0.5, X, NULL, NULL, NULL);
        if (fabs(X[1] - 0.5) < 1e-12) flip_part(&m->parts[p]);
    }
    /* grids whose cell boundaries fall on the boxes' faces (cells of 0.5): exact */
    const int grids[3][2] = {{5, 5}, {6, 5}, {6, 5}};
    for (int axis = 0; axis < 3; axis++) {
        sem_preprocess_options o = options(grids[axis][0], grids[axis][1], axis, 4, 2);
        sem_discretization d;
        if (run(m, &o, &d, NULL) != SEM_OK) continue;
        CHECK_REL(d.volume, 13.75, 1e-12);
        free_quad(&d);
    }
    sem_model_destroy(m);

    /* nested: outer [0,4]^3 (parts 0-5), inner [1,3]^3 (parts 6-11) */
    m = sem_model_create();
    add_box(m, 4, 4, 4, 2, 2, 2);
    add_box(m, 2, 2, 2, 2, 2, 2);
    sem_preprocess_options o = options(8, 8, 0, 8, 2);
    sem_discretization d;
    if (run(m, &o, &d, NULL) == SEM_OK) {
        CHECK_REL(d.volume, 64.0, 1e-12);
        int wrong = 0;
        double inner_volume = 0;
        for (int p = 0; p < d.n_quad; p++) {
            const double *X = d.quad_X + 3 * p;
            int in_inner = X[0] > 1 && X[0] < 3 && X[1] > 1 && X[1] < 3 && X[2] > 1 && X[2] < 3;
            if (in_inner != (d.quad_part[p] >= 6)) wrong++;
            if (d.quad_part[p] >= 6) inner_volume += d.quad_volume[p];
        }
        CHECK(wrong == 0, "%d points with the wrong material", wrong);
        CHECK_REL(inner_volume, 8.0, 1e-12);
        free_quad(&d);
    }
    sem_model_destroy(m);
}

/* A unit cube with an open sheet inside (x = 0.5, [0.25,0.75]^2, like a fin): rays through
 * the sheet cannot be counted consistently and fall back to the winding number; the
 * volume stays exactly 1. */
static void test_winding_fallback(void)
{
    sem_model *m = sem_model_create();
    add_box(m, 1, 1, 1, 0.5, 0.5, 0.5);
    sem_part sheet;
    memset(&sheet, 0, sizeof sheet);
    CHECK(sem_surface_alloc(&sheet.surface, 1, 1, 2, 2) == SEM_OK, "alloc");
    sem_surface *s = &sheet.surface;
    const double knots[4] = {0, 0, 1, 1};
    memcpy(s->knots_u, knots, sizeof knots);
    memcpy(s->knots_v, knots, sizeof knots);
    s->u0 = s->v0 = 0;
    s->u1 = s->v1 = 1;
    const double corners[4][3] = {{0.5, 0.25, 0.25}, {0.5, 0.75, 0.25}, {0.5, 0.25, 0.75},
                                  {0.5, 0.75, 0.75}};
    memcpy(s->ctrl, corners, sizeof corners);
    sem_error err;
    CHECK(sem_model_take_part(m, &sheet, &err) == SEM_OK, "sheet");
    sem_preprocess_options o = options(8, 8, 0, 4, 2);
    sem_discretization d;
    if (run(m, &o, &d, NULL) == SEM_OK) {
        CHECK_REL(d.volume, 1.0, 1e-12);
        CHECK(d.n_quad == 8 * 8 * 4, "one merged interval per ray: %d points", d.n_quad);
        free_quad(&d);
    }
    sem_model_destroy(m);
}

/* Sphere: error of the midpoint rule across the grid shrinks as rays increase (Fig. 7). The
 * hits are refined on the exact NURBS, so the tessellation only matters at the silhouette. */
static void test_sphere_convergence(void)
{
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.radius = 2.0;
    sd.center[0] = 0.3;
    sem_error err;
    CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "sphere: %s", err.message);
    double exact = 4.0 / 3.0 * M_PI * 8.0;
    const int rays[] = {10, 20, 40};
    double e[3] = {1, 1, 1};
    for (int k = 0; k < 3; k++) {
        sem_preprocess_options o = options(rays[k], rays[k], 0, 5, 16);
        sem_discretization d;
        if (run(m, &o, &d, NULL) != SEM_OK) continue;
        e[k] = fabs(d.volume / exact - 1);
        printf("sphere %dx%d rays: volume %.8f, relative error %.3e\n", rays[k], rays[k],
               d.volume, e[k]);
        free_quad(&d);
    }
    CHECK(e[0] < 1e-2, "10x10: %g", e[0]);
    CHECK(e[1] < e[0], "20x20 better than 10x10");
    CHECK(e[2] < e[1], "40x40 better than 20x20");
    CHECK(e[2] < 1e-3, "40x40 within 0.1%%: %g", e[2]);
    /* default options */
    sem_preprocess_options o = sem_default_preprocess_options();
    sem_discretization d;
    if (run(m, &o, &d, NULL) == SEM_OK) {
        double ed = fabs(d.volume / exact - 1);
        printf("sphere default options (object-frame grid %g, tessellation %d): %d points, "
               "relative error %.3e\n",
               d.quad_spacing, o.tessellation, d.n_quad, ed);
        /* without boundary samples (no part sizes) the grid is thinnest extent / 3: 3 cells
         * per diameter, 4 x 4 rays per cell refined near the silhouette */
        CHECK(ed < 6e-3, "default settings: sphere volume off by %g (> 0.6%%)", ed);
        free_quad(&d);
    }
    sem_model_destroy(m);
}

/* The height field seen along a ray (hit_curvature.c) against finite differences: the point
 * of the surface over (y, z) found by Newton on (X . e1, X . e2) = (y, z), its t = X . d. */
static double height_at(const sem_surface *s, double u, double v, const double *d,
                        const double *e1, const double *e2, double y, double z)
{
    for (int it = 0; it < 50; ++it) {
        double X[3], Xu[3], Xv[3];
        sem_surface_eval(s, u, v, X, Xu, Xv, NULL);
        double fy = X[0] * e1[0] + X[1] * e1[1] + X[2] * e1[2] - y;
        double fz = X[0] * e2[0] + X[1] * e2[1] + X[2] * e2[2] - z;
        double a = Xu[0] * e1[0] + Xu[1] * e1[1] + Xu[2] * e1[2], b = Xv[0] * e1[0] + Xv[1] * e1[1] + Xv[2] * e1[2];
        double c = Xu[0] * e2[0] + Xu[1] * e2[1] + Xu[2] * e2[2], e = Xv[0] * e2[0] + Xv[1] * e2[1] + Xv[2] * e2[2];
        double det = a * e - b * c;
        u -= (e * fy - b * fz) / det;
        v -= (-c * fy + a * fz) / det;
    }
    double X[3];
    sem_surface_eval(s, u, v, X, NULL, NULL, NULL);
    return X[0] * d[0] + X[1] * d[1] + X[2] * d[2];
}

static void test_height_hessian(void)
{
    sem_model *m = sem_model_create();
    sem_torus_def td = sem_default_torus_def();
    sem_error err;
    CHECK(sem_primitive_torus(m, &td, &err) == SEM_OK, "torus: %s", err.message);
    const sem_surface *s = &m->parts[0].surface;
    unsigned seed = 12345;
    int checked = 0;
    double worst = 0;
    for (int trial = 0; trial < 200; ++trial) {
        double r[5];
        for (int k = 0; k < 5; ++k) {
            seed = seed * 1103515245u + 12345u;
            r[k] = (double)(seed >> 8) / (double)(1u << 24);
        }
        double u = s->u0 + (0.05 + 0.9 * r[0]) * (s->u1 - s->u0);
        double v = s->v0 + (0.05 + 0.9 * r[1]) * (s->v1 - s->v0);
        double th = 2 * M_PI * r[2], ph = acos(2 * r[3] - 1), ps = 2 * M_PI * r[4];
        double d[3] = {sin(ph) * cos(th), sin(ph) * sin(th), cos(ph)}, p[3], e1[3], e2[3];
        p[0] = fabs(d[0]) < 0.9 ? 1 : 0;
        p[1] = 1 - p[0];
        p[2] = 0;
        /* e1 = normalize(p - (p.d) d) turned by ps about d; e2 = d x e1 */
        double pd = p[0] * d[0] + p[1] * d[1] + p[2] * d[2], q[3], n = 0;
        for (int k = 0; k < 3; ++k) q[k] = p[k] - pd * d[k], n += q[k] * q[k];
        for (int k = 0; k < 3; ++k) q[k] /= sqrt(n);
        double w[3] = {d[1] * q[2] - d[2] * q[1], d[2] * q[0] - d[0] * q[2], d[0] * q[1] - d[1] * q[0]};
        for (int k = 0; k < 3; ++k) e1[k] = cos(ps) * q[k] + sin(ps) * w[k];
        e2[0] = d[1] * e1[2] - d[2] * e1[1];
        e2[1] = d[2] * e1[0] - d[0] * e1[2];
        e2[2] = d[0] * e1[1] - d[1] * e1[0];
        double H[3], facing;
        if (!sem_hit_height_hessian(s, u, v, d, e1, e2, H, &facing) || facing < 0.3) continue;
        double X[3];
        sem_surface_eval(s, u, v, X, NULL, NULL, NULL);
        double y = X[0] * e1[0] + X[1] * e1[1] + X[2] * e1[2], z = X[0] * e2[0] + X[1] * e2[1] + X[2] * e2[2];
        const double h = 1e-4;
        double g0 = height_at(s, u, v, d, e1, e2, y, z);
        double gyy = (height_at(s, u, v, d, e1, e2, y + h, z) - 2 * g0 + height_at(s, u, v, d, e1, e2, y - h, z)) / (h * h);
        double gzz = (height_at(s, u, v, d, e1, e2, y, z + h) - 2 * g0 + height_at(s, u, v, d, e1, e2, y, z - h)) / (h * h);
        double gyz = (height_at(s, u, v, d, e1, e2, y + h, z + h) - height_at(s, u, v, d, e1, e2, y + h, z - h) -
                      height_at(s, u, v, d, e1, e2, y - h, z + h) + height_at(s, u, v, d, e1, e2, y - h, z - h)) /
                     (4 * h * h);
        double scale = 1 + fabs(H[0]) + fabs(H[1]) + fabs(H[2]);
        double e = (fabs(gyy - H[0]) + fabs(gzz - H[1]) + fabs(gyz - H[2])) / scale;
        if (e > worst) worst = e;
        checked++;
    }
    printf("height-field Hessian: %d hits, worst relative difference to finite differences %.2e\n",
           checked, worst);
    CHECK(checked > 50, "%d hits checked", checked);
    CHECK(worst < 1e-4, "Hessian off by %g", worst);
    sem_model_destroy(m);
}

static void test_errors(void)
{
    sem_model *m = sem_model_create();
    add_box(m, 1, 1, 1, 0, 0, 0);
    sem_raycast_scene *scene = NULL;
    sem_error err;
    CHECK(sem_raycast_scene_build(m, 2, &scene, &err) == SEM_OK, "scene");
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_preprocess_options o = options(0, 4, 0, 3, 2);
    CHECK(sem_step_quadrature(m, scene, &o, &d, &err) == SEM_ERR_INVALID, "0 rays");
    o = options(4, 4, 3, 3, 2);
    CHECK(sem_step_quadrature(m, scene, &o, &d, &err) == SEM_ERR_INVALID, "axis 3");
    o = options(4, 4, 0, -1, 2);
    CHECK(sem_step_quadrature(m, scene, &o, &d, &err) == SEM_ERR_INVALID, "-1 points");
    CHECK(d.n_quad == 0 && d.quad_X == NULL, "untouched on error");
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* ---- the default quadrature (sem_preprocess's cells of the object's frame) ---- */

static sem_model *load_shared(const char *relative);

/* The default quadrature's volume (issue 27, item 5): within 0.1 % of the exact volume, with at
 * most 1.5 x the points the midpoint rule's cells gave before (136 sphere, 712 torus, 194
 * rounded cube: the points are the cost of every time step; the rays are not). The result is
 * bit-identical on 1 and 2 threads. */
static void check_default_volume(const char *name, const sem_model *m, double exact,
                                 int points_before)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    sem_discretization *d1 = NULL, *d2 = NULL;
    sem_error err;
    o.threads = 1;
    CHECK(sem_preprocess(m, &o, &d1, &err) == SEM_OK, "%s: %s", name, err.message);
    o.threads = 2;
    CHECK(sem_preprocess(m, &o, &d2, &err) == SEM_OK, "%s: %s", name, err.message);
    if (!d1 || !d2) {
        sem_discretization_destroy(d1);
        sem_discretization_destroy(d2);
        return;
    }
    double e = d1->volume / exact - 1;
    printf("%s default quadrature: %d points (%d before), volume %.8f, exact %.8f, relative "
           "error %+.2e\n",
           name, d1->n_quad, points_before, d1->volume, exact, e);
    CHECK(fabs(e) < 1e-3, "%s: default quadrature volume off by %.3g (> 0.1 %%)", name, e);
    CHECK(d1->n_quad <= 1.5 * points_before, "%s: %d points (before: %d)", name, d1->n_quad,
          points_before);
    CHECK(d1->n_quad == d2->n_quad &&
              !memcmp(d1->quad_X, d2->quad_X, 3 * (size_t)d1->n_quad * sizeof *d1->quad_X) &&
              !memcmp(d1->quad_volume, d2->quad_volume, (size_t)d1->n_quad * sizeof *d1->quad_volume) &&
              !memcmp(d1->quad_part, d2->quad_part, (size_t)d1->n_quad * sizeof *d1->quad_part),
          "%s: quadrature differs on 1 and 2 threads", name);
    sem_discretization_destroy(d1);
    sem_discretization_destroy(d2);
}

static void test_default_volume(void)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "sphere: %s", err.message);
    check_default_volume("sphere", m, 4.0 / 3.0 * M_PI * sd.radius * sd.radius * sd.radius, 136);
    sem_model_destroy(m);

    m = sem_model_create();
    sem_torus_def td = sem_default_torus_def();
    CHECK(sem_primitive_torus(m, &td, &err) == SEM_OK, "torus: %s", err.message);
    check_default_volume("torus", m, 2.0 * M_PI * M_PI * td.major * td.minor * td.minor, 712);
    sem_model_destroy(m);

    m = load_shared("rounded_cube.iges");
    if (m) {
        /* the divergence-theorem volume of test_rounded_cube */
        check_default_volume("rounded cube", m, 1.1769711, 194);
        sem_model_destroy(m);
    }
}

/* ---- the paper's models ---- */

static sem_model *load_shared(const char *relative)
{
    const char *path = test_shared_model(relative);
    if (!path) {
        printf("skip %s: shared models absent\n", relative);
        return NULL;
    }
    sem_model *m = NULL;
    sem_error err;
    if (sem_iges_read(path, &m, &err) != SEM_OK) {
        printf("skip %s: %s\n", relative, err.message);
        return NULL;
    }
    return m;
}

/* Divergence theorem, V = 1/3 sum over parts of sign_i * integral of x . (x_u x x_v) du dv,
 * Gauss-Legendre per knot span (untrimmed parts only), signs from the orientation fix. */
static double divergence_volume(const sem_model *m, const sem_raycast_scene *scene)
{
    double gx[12], gw[12], breaks_u[512], breaks_v[512];
    sem_gauss_legendre(12, gx, gw);
    double total = 0;
    for (int p = 0; p < m->n_parts; p++) {
        const sem_surface *s = &m->parts[p].surface;
        int nu = sem_knot_breaks(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, breaks_u, 512);
        int nv = sem_knot_breaks(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, breaks_v, 512);
        double sum = 0;
        for (int a = 0; a + 1 < nu; a++)
            for (int b = 0; b + 1 < nv; b++) {
                double hu = 0.5 * (breaks_u[a + 1] - breaks_u[a]);
                double hv = 0.5 * (breaks_v[b + 1] - breaks_v[b]);
                for (int i = 0; i < 12; i++)
                    for (int j = 0; j < 12; j++) {
                        double u = breaks_u[a] + hu * (gx[i] + 1), v = breaks_v[b] + hv * (gx[j] + 1);
                        double X[3], Su[3], Sv[3];
                        sem_surface_eval(s, u, v, X, Su, Sv, NULL);
                        double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                                       Su[0] * Sv[1] - Su[1] * Sv[0]};
                        sum += gw[i] * gw[j] * hu * hv * (X[0] * n[0] + X[1] * n[1] + X[2] * n[2]);
                    }
            }
        total += sem_raycast_part_sign(scene, p) * sum;
    }
    return total / 3.0;
}

/* Winding-number estimate of the volume on the same ray grid as the quadrature, sampling
 * each ray at `samples` midpoints: isolates the inside/outside classification. */
static double winding_volume(const sem_raycast_scene *scene, const sem_preprocess_options *o,
                             int samples)
{
    double lo[3], hi[3];
    sem_raycast_bounds(scene, lo, hi);
    int a = o->ray_axis, b = a == 0 ? 1 : 0, c = a == 2 ? 1 : 2;
    int n1 = o->rays[0], n2 = o->rays[1];
    double wb = (hi[b] - lo[b]) / n1, wc = (hi[c] - lo[c]) / n2, h = (hi[a] - lo[a]) / samples;
    long long inside = 0;
#pragma omp parallel for schedule(dynamic) reduction(+ : inside)
    for (int r = 0; r < n1 * n2 * samples; r++) {
        int k = r % samples, i = (r / samples) % n1, j = r / samples / n1;
        double X[3];
        X[a] = lo[a] + (k + 0.5) * h;
        X[b] = lo[b] + (i + 0.5) * wb;
        X[c] = lo[c] + (j + 0.5) * wc;
        if (sem_raycast_winding_number(scene, X) > 0.5) inside++;
    }
    return (double)inside * h * wb * wc;
}

static void test_beam(void)
{
    sem_model *m = load_shared("beams/perf/b1.igs");
    if (!m) return;
    sem_preprocess_options o = options(3, 3, 0, 100, 8); /* the deflection study's settings */
    sem_discretization d;
    if (run(m, &o, &d, NULL) == SEM_OK) {
        printf("b1: volume %.10f (5 x 1 x 1)\n", d.volume);
        CHECK_REL(d.volume, 5.0, 5e-3);
        free_quad(&d);
    }
    sem_model_destroy(m);
}

static void test_rounded_cube(void)
{
    sem_model *m = load_shared("rounded_cube.iges");
    if (!m) return;
    /* 4 bicubic blobby patches: the grid error at the silhouette is 2e-3 at 40 x 40 and
     * 4e-4 at 80 x 80 rays (it converges to the divergence-theorem volume) */
    sem_preprocess_options o = options(80, 80, 0, 2, 16);
    sem_discretization d;
    sem_raycast_scene *scene = NULL;
    if (run(m, &o, &d, &scene) == SEM_OK) {
        double v = divergence_volume(m, scene);
        printf("rounded cube: quadrature %.8g, divergence theorem %.8g\n", d.volume, v);
        CHECK_REL(d.volume, v, 1e-3);
        free_quad(&d);
    }
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* Open or overlapping models: compare with the winding-number estimate on the same rays. */
static void test_against_winding(const char *file, int n1, int n2, int tessellation,
                                 double tolerance, double *volume_out)
{
    sem_model *m = load_shared(file);
    if (!m) return;
    sem_preprocess_options o = options(n1, n2, 0, 5, tessellation);
    sem_discretization d;
    sem_raycast_scene *scene = NULL;
    if (run(m, &o, &d, &scene) == SEM_OK) {
        double w = winding_volume(scene, &o, 200);
        printf("%s: quadrature %.8g, winding number %.8g (%d points)\n", file, d.volume, w,
               d.n_quad);
        CHECK(d.volume > 0, "positive volume");
        CHECK_REL(d.volume, w, tolerance);
        if (volume_out) *volume_out = d.volume;
        free_quad(&d);
    }
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* The rocket has no bottom and its fins pierce the body. Rays across its axis (x and y)
 * see closed sections and must agree; rays along the axis (z) enter through the open end
 * and need the winding-number fallback. The winding number of an open tube is below 1/2
 * near its open end, so the winding estimate is lower than the closed-rocket volume the
 * cross rays measure: it bounds the result loosely. */
static void test_rocket(void)
{
    sem_model *m = load_shared("rocket/rocket.iges");
    if (!m) return;
    double v[3] = {0, 0, 0}, w = 0;
    for (int axis = 0; axis < 3; axis++) {
        sem_preprocess_options o = options(15, 15, axis, 5, 4);
        sem_discretization d;
        sem_raycast_scene *scene = NULL;
        if (run(m, &o, &d, &scene) != SEM_OK) continue;
        v[axis] = d.volume;
        if (axis == 0) w = winding_volume(scene, &o, 200);
        free_quad(&d);
        sem_raycast_scene_destroy(scene);
    }
    printf("rocket: quadrature along x %.8g, y %.8g, z %.8g; winding number %.8g\n", v[0], v[1],
           v[2], w);
    CHECK(v[0] > 0 && v[1] > 0 && v[2] > 0, "positive volumes");
    CHECK_REL(v[1], v[0], 0.03);
    CHECK_REL(v[2], v[0], 0.15);
    CHECK(v[0] >= w && v[0] < 1.15 * w, "winding estimate %g vs %g", w, v[0]);
    sem_model_destroy(m);
}

int main(void)
{
    test_box_exact();
    test_union_and_materials();
    test_winding_fallback();
    test_height_hessian();
    test_sphere_convergence();
    test_default_volume();
    test_errors();
    test_beam();
    test_rounded_cube();
    test_rocket();
    double v_mug = 0, v_bad = 0;
    test_against_winding("mugs/mug_trimmed_complex.iges", 15, 15, 4, 0.05, &v_mug);
    test_against_winding("mugs/mug_trimmed_complex_bad.iges", 15, 15, 4, 0.05, &v_bad);
    if (v_mug > 0 && v_bad > 0) CHECK_REL(v_bad, v_mug, 0.02);
    test_against_winding("starship/starship_fall_simpler.igs", 15, 15, 4, 0.05, NULL);
    return test_finish("quadrature");
}
