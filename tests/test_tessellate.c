/*
 * test_tessellate.c - render meshes of NURBS parts: a rational unit sphere tessellates to
 * vertices exactly on the sphere with outward unit normals (finite at the collapsed poles)
 * and an area converging to 4 pi at second order; a trimmed plate with a round hole has the
 * analytic area 4 - pi/4 up to the one-cell boundary error; the per-frame update agrees
 * with a fresh tessellation; the OBJ render mesh has the counts and groups it should.
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sem/model.h"
#include "sem/tessellate.h"
#include "test_util.h"

/* Unit sphere as one rational biquadratic surface of revolution: a 9-point circle in u
 * times a 5-point half circle (pole to pole) in v, weights multiplied. */
static sem_model *unit_sphere(void)
{
    sem_model *m = sem_model_create();
    sem_part p;
    memset(&p, 0, sizeof p);
    strcpy(p.name, "sphere");
    sem_surface *s = &p.surface;
    sem_surface_alloc(s, 2, 2, 9, 5);
    double ku[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
    double kv[8] = {0, 0, 0, 0.5, 0.5, 1, 1, 1};
    memcpy(s->knots_u, ku, sizeof ku);
    memcpy(s->knots_v, kv, sizeof kv);
    const double r = sqrt(0.5);
    double cx[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1}, cy[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
    double cw[9] = {1, r, 1, r, 1, r, 1, r, 1};
    double pr[5] = {0, 1, 1, 1, 0}, pz[5] = {-1, -1, 0, 1, 1}, pw[5] = {1, r, 1, r, 1};
    for (int j = 0; j < 5; ++j)
        for (int i = 0; i < 9; ++i) {
            int k = i + 9 * j;
            s->ctrl[3 * k] = pr[j] * cx[i];
            s->ctrl[3 * k + 1] = pr[j] * cy[i];
            s->ctrl[3 * k + 2] = pz[j];
            s->weights[k] = cw[i] * pw[j];
        }
    s->u1 = s->v1 = 1;
    sem_model_take_part(m, &p, NULL);
    return m;
}

static void test_sphere(void)
{
    sem_model *m = unit_sphere();
    sem_error err;
    double previous_error = 0.0, last_ratio = 0.0;
    for (int res = 2; res <= 32; res *= 2) {
        sem_mesh mesh;
        CHECK(sem_mesh_from_model(m, res, &mesh, &err) == SEM_OK, "%s", err.message);
        /* 4 x 2 spans, res x res cells each, 2 triangles per cell */
        CHECK(mesh.n_triangles == 2 * (4 * res) * (2 * res), "%d triangles at resolution %d",
              mesh.n_triangles, res);
        CHECK(mesh.n_vertices == (4 * res + 1) * (2 * res + 1), "%d vertices", mesh.n_vertices);
        double worst_radius = 0.0, worst_normal = 0.0;
        int finite = 1;
        for (int v = 0; v < mesh.n_vertices; ++v) {
            const double *x = mesh.positions + 3 * v, *n = mesh.normals + 3 * v;
            double rad = sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
            worst_radius = fmax(worst_radius, fabs(rad - 1.0));
            finite &= isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]);
            /* outward: x_u x x_v points away from the centre for this orientation */
            double dot = n[0] * x[0] + n[1] * x[1] + n[2] * x[2];
            worst_normal = fmax(worst_normal, fabs(dot - 1.0));
        }
        CHECK(worst_radius <= 1e-12, "resolution %d: vertex off the sphere by %.3g", res,
              worst_radius);
        CHECK(finite, "non-finite normal at resolution %d", res);
        CHECK(worst_normal <= 1e-5, "resolution %d: normal differs from the radius by %.3g", res,
              worst_normal);
        double area = sem_mesh_area(&mesh);
        double error = 4.0 * M_PI - area;
        CHECK(error > 0, "an inscribed mesh has less area than the sphere (%.17g)", area);
        if (previous_error > 0) last_ratio = previous_error / error;
        previous_error = error;
        printf("  sphere resolution %2d: %6d triangles, area %.12f, error %.3e\n", res,
               mesh.n_triangles, area, error);
        sem_mesh_free(&mesh);
    }
    CHECK(previous_error < 2e-3 * 4 * M_PI, "area error at resolution 32: %.3g", previous_error);
    CHECK(last_ratio > 3.5 && last_ratio < 4.5, "area converges at order %.2f, expected 2",
          log2(last_ratio));
    sem_model_destroy(m);
}

static void test_trimmed_plate(void)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/obj_patches.obj", SEM_TEST_DATA);
    sem_model *all = NULL;
    sem_error err;
    CHECK(sem_obj_read(path, &all, &err) == SEM_OK, "%s", err.message);
    if (!all) return;
    sem_model *m = sem_model_create();
    sem_model_add_part(m, &all->parts[3], NULL); /* the plate with a hole */
    sem_model_destroy(all);
    const double exact = 4.0 - M_PI / 4.0; /* 2 x 2 square minus a disc of radius 0.5 */
    double previous = 0.0;
    for (int res = 16; res <= 256; res *= 4) {
        sem_mesh mesh;
        CHECK(sem_mesh_from_model(m, res, &mesh, &err) == SEM_OK, "%s", err.message);
        double area = sem_mesh_area(&mesh);
        double error = fabs(area - exact);
        printf("  plate resolution %3d: area %.6f (exact %.6f), error %.2e\n", res, area, exact,
               error);
        /* Keeping a boundary cell's triangle by its centroid errs by at most the area of
         * the cells the circle crosses (~ 2 pi r / h cells of area h^2, r = 0.5 in 3D); in
         * practice the errors cancel and stay far below a quarter of that. */
        double h = 2.0 / res;
        CHECK(error < 0.25 * M_PI * h, "resolution %d: area %.6f vs %.6f", res, area, exact);
        previous = error;
        /* no triangle inside the hole */
        int inside_hole = 0;
        for (int t = 0; t < mesh.n_triangles; ++t) {
            double c[2] = {0, 0};
            for (int k = 0; k < 3; ++k) {
                c[0] += mesh.uv[2 * mesh.triangles[3 * t + k]] / 3;
                c[1] += mesh.uv[2 * mesh.triangles[3 * t + k] + 1] / 3;
            }
            inside_hole += hypot(c[0] - 0.5, c[1] - 0.5) < 0.25 - 1e-9;
        }
        CHECK(inside_hole == 0, "%d triangles in the hole", inside_hole);
        sem_mesh_free(&mesh);
    }
    CHECK(previous < 2e-3, "area error %.3g at resolution 256", previous);
    sem_model_destroy(m);
}

static void test_update_matches_fresh(void)
{
    sem_model *m = unit_sphere();
    sem_error err;
    sem_mesh_template *t = NULL;
    sem_mesh mesh;
    CHECK(sem_mesh_template_build(m, 6, &t, &err) == SEM_OK, "%s", err.message);
    if (!t) return;
    CHECK(sem_mesh_template_mesh(t, &mesh, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_mesh_update(t, m, &mesh, &err) == SEM_OK, "%s", err.message);
    /* move and stretch the control points: x -> (2x + 1, y - 3, z) */
    sem_surface *s = &m->parts[0].surface;
    for (int k = 0; k < s->n_u * s->n_v; ++k) {
        s->ctrl[3 * k] = 2 * s->ctrl[3 * k] + 1;
        s->ctrl[3 * k + 1] -= 3;
    }
    CHECK(sem_mesh_update(t, m, &mesh, &err) == SEM_OK, "%s", err.message);
    sem_mesh fresh;
    CHECK(sem_mesh_from_model(m, 6, &fresh, &err) == SEM_OK, "%s", err.message);
    double worst = 0.0;
    for (int i = 0; i < 3 * mesh.n_vertices; ++i) {
        worst = fmax(worst, fabs(mesh.positions[i] - fresh.positions[i]));
        worst = fmax(worst, fabs(mesh.normals[i] - fresh.normals[i]));
    }
    CHECK(mesh.n_vertices == fresh.n_vertices && worst == 0.0, "update differs by %.3g", worst);
    /* an ellipsoid with semi-axes 2, 1, 1 around (1, -3, 0) */
    double worst_surface = 0.0;
    for (int v = 0; v < mesh.n_vertices; ++v) {
        const double *x = mesh.positions + 3 * v;
        double q = pow((x[0] - 1) / 2, 2) + pow(x[1] + 3, 2) + x[2] * x[2];
        worst_surface = fmax(worst_surface, fabs(q - 1));
    }
    CHECK(worst_surface < 1e-12, "vertex off the ellipsoid by %.3g", worst_surface);

    /* a model of another size is refused */
    sem_model *other = sem_model_create();
    CHECK(sem_mesh_update(t, other, &mesh, &err) == SEM_ERR_INVALID, "size mismatch accepted");
    sem_model_destroy(other);
    sem_mesh_template *t0 = NULL;
    CHECK(sem_mesh_template_build(m, 0, &t0, &err) == SEM_ERR_INVALID && t0 == NULL,
          "resolution 0 accepted");
    sem_mesh_free(&fresh);
    sem_mesh_free(&mesh);
    sem_mesh_template_destroy(t);
    sem_model_destroy(m);
}

static void test_open_loop(void)
{
    sem_model *m = unit_sphere();
    sem_part *p = &m->parts[0];
    p->has_outer = 1;
    p->outer.n_curves = 1;
    p->outer.curves = calloc(1, sizeof(sem_curve));
    sem_curve *c = &p->outer.curves[0];
    sem_curve_alloc(c, 1, 3);
    double k[5] = {0, 0, 0.5, 1, 1}, x[9] = {0.1, 0.1, 0, 0.9, 0.1, 0, 0.9, 0.9, 0};
    memcpy(c->knots, k, sizeof k);
    memcpy(c->ctrl, x, sizeof x);
    c->t1 = 1;
    sem_error err;
    sem_mesh mesh;
    CHECK(sem_mesh_from_model(m, 4, &mesh, &err) != SEM_OK, "open loop accepted");
    CHECK(strstr(err.message, "sphere") != NULL, "message names the part: %s", err.message);
    sem_model_destroy(m);
}

static void test_mesh_obj(void)
{
    sem_model *m = unit_sphere();
    sem_model_add_part(m, &m->parts[0], NULL);
    m->parts[1].name[0] = '\0';
    for (int k = 0; k < 45; ++k) m->parts[1].surface.ctrl[3 * k] += 3.0;
    char path[512];
    snprintf(path, sizeof path, "%s/mesh.obj", test_tmpdir());
    sem_error err;
    CHECK(sem_mesh_obj_write(m, path, 3, &err) == SEM_OK, "%s", err.message);
    FILE *f = fopen(path, "r");
    int nv = 0, nn = 0, nf = 0, ng = 0, bad = 0;
    char line[256], groups[2][64] = {"", ""};
    while (f && fgets(line, sizeof line, f)) {
        if (strncmp(line, "v ", 2) == 0) nv++;
        else if (strncmp(line, "vn ", 3) == 0) nn++;
        else if (strncmp(line, "g ", 2) == 0) {
            if (ng < 2) sscanf(line + 2, "%63s", groups[ng]);
            ng++;
        } else if (strncmp(line, "f ", 2) == 0) {
            int a, a2, b, b2, c, c2;
            nf++;
            if (sscanf(line, "f %d//%d %d//%d %d//%d", &a, &a2, &b, &b2, &c, &c2) != 6 || a != a2 ||
                b != b2 || c != c2 || a < 1 || b < 1 || c < 1 || a > nv || b > nv || c > nv)
                bad++;
        }
    }
    if (f) fclose(f);
    int per_part_v = (4 * 3 + 1) * (2 * 3 + 1), per_part_f = 2 * 12 * 6;
    CHECK(nv == 2 * per_part_v && nn == nv, "%d v, %d vn", nv, nn);
    CHECK(nf == 2 * per_part_f && bad == 0, "%d faces, %d bad", nf, bad);
    CHECK(ng == 2 && strcmp(groups[0], "sphere") == 0 && strcmp(groups[1], "part_1") == 0,
          "groups %d: %s %s", ng, groups[0], groups[1]);
    sem_model_destroy(m);
}

/* The per-frame cost on a real model, for the record (asserts only sanity). */
static void test_speed(void)
{
    const char *path = test_shared_model("mugs/mug_trimmed_complex.iges");
    if (!path) {
        printf("  shared models absent: skipping the speed check\n");
        return;
    }
    sem_model *m = NULL;
    sem_error err;
    if (sem_iges_read(path, &m, &err) != SEM_OK) {
        printf("  cannot read %s: %s\n", path, err.message);
        return;
    }
    struct timespec t0, t1, t2;
    clock_gettime(CLOCK_MONOTONIC, &t0);
    sem_mesh_template *t = NULL;
    sem_mesh mesh;
    CHECK(sem_mesh_template_build(m, 8, &t, &err) == SEM_OK, "%s", err.message);
    if (t) {
        sem_mesh_template_mesh(t, &mesh, &err);
        clock_gettime(CLOCK_MONOTONIC, &t1);
        for (int frame = 0; frame < 10; ++frame) sem_mesh_update(t, m, &mesh, &err);
        clock_gettime(CLOCK_MONOTONIC, &t2);
        double build = (double)(t1.tv_sec - t0.tv_sec) + 1e-9 * (double)(t1.tv_nsec - t0.tv_nsec);
        double frame = ((double)(t2.tv_sec - t1.tv_sec) + 1e-9 * (double)(t2.tv_nsec - t1.tv_nsec)) / 10;
        printf("  mug (%d parts): %d triangles, template %.3f s, update %.4f s per frame\n",
               m->n_parts, mesh.n_triangles, build, frame);
        CHECK(mesh.n_triangles > 1000, "%d triangles", mesh.n_triangles);
        sem_mesh_free(&mesh);
        sem_mesh_template_destroy(t);
    }
    sem_model_destroy(m);
}

int main(void)
{
    test_sphere();
    test_trimmed_plate();
    test_update_matches_fresh();
    test_open_loop();
    test_mesh_obj();
    test_speed();
    return test_finish("test_tessellate");
}
