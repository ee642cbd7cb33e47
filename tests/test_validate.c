/* test_validate.c - `sem validate` (tools/fem/validate.py through the sem binary):
 *
 *  - on the 5 x 1 x 1 m cantilever of docs/validation.md section 1 (a `sem primitive beam`,
 *    pinned at x = 0 by a scene's pin box, gravity 10, neo-Hookean E 1e6, nu 0.45), the FEM
 *    side's tip deflection (area-weighted mean of -u_z over the free end, from the nodes and
 *    faces validate writes) is within 2 % of the converged reference in
 *    validation/fem_cantilever.json, with two meshes that agree to 1 %;
 *  - the reported relative L2 error and largest-displacement ratio equal an independent
 *    computation: every surface node is placed on its flat beam face by a Newton solve of this
 *    test's own, sem's deformed frame is evaluated there with sem_surface_eval, and the
 *    surface integral of the quadratic interpolant is formed from the 6-node faces;
 *  - errors: an open model (a beam without its end cap) is one line saying gmsh could not make
 *    a solid, a missing file and a bad scene are one line with exit 1, a bad option exit 2.
 *
 * gmsh and CalculiX come from Debian; validate installs them when it may. When they are
 * missing and cannot be installed (exit status 3) the test is skipped. */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "test_util.h"

static char out[1 << 20], err[1 << 16];

static int run(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static int run(const char *fmt, ...)
{
    char args[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    return test_run_cli(args, out, sizeof out, err, sizeof err);
}

static int count_lines(const char *s)
{
    int n = 0;
    for (; *s; ++s) n += *s == '\n';
    return n;
}

/* Errors are exactly one line "sem: ..." on stderr. */
static void check_one_error_line(const char *what)
{
    CHECK(strncmp(err, "sem: ", 5) == 0, "%s: stderr does not start with 'sem: ': %s", what, err);
    CHECK(count_lines(err) == 1, "%s: stderr has %d lines: %s", what, count_lines(err), err);
}

static double json_number(const cJSON *o, const char *path)
{
    /* "a.b.c" */
    char key[128];
    const char *p = path;
    const cJSON *x = o;
    while (x && *p) {
        size_t n = strcspn(p, ".");
        snprintf(key, sizeof key, "%.*s", (int)n, p);
        x = cJSON_GetObjectItemCaseSensitive(x, key);
        p += n + (p[n] == '.');
    }
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

static int write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    fputs(text, f);
    return fclose(f) == 0;
}

/* ---- what validate writes: surface_nodes.csv and surface_faces.csv ---- */

typedef struct surface_node {
    int id, part, used;
    double X[3], u_fem[3], u_sem[3];
} surface_node;

typedef struct surface {
    int n_nodes, n_faces;
    surface_node *nodes;
    int *faces; /* 6 node ids per face */
    int max_id;
    int *index; /* node id -> row, -1 */
} surface;

static void surface_free(surface *s)
{
    free(s->nodes);
    free(s->faces);
    free(s->index);
    memset(s, 0, sizeof *s);
}

static int read_surface(const char *dir, surface *s)
{
    memset(s, 0, sizeof *s);
    char path[1024];
    snprintf(path, sizeof path, "%s/surface_nodes.csv", dir);
    FILE *f = fopen(path, "r");
    if (!f) return 0;
    char line[2048];
    int cap = 0;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    while (fgets(line, sizeof line, f)) {
        if (s->n_nodes == cap) {
            cap = cap ? 2 * cap : 1024;
            s->nodes = realloc(s->nodes, (size_t)cap * sizeof *s->nodes);
        }
        surface_node *n = &s->nodes[s->n_nodes];
        double dist;
        int inside;
        if (sscanf(line, "%d,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%lf,%d,%d,%d", &n->id, &n->X[0], &n->X[1], &n->X[2],
                   &n->u_fem[0], &n->u_fem[1], &n->u_fem[2], &n->u_sem[0], &n->u_sem[1], &n->u_sem[2], &dist,
                   &n->part, &inside, &n->used) != 14)
            break;
        if (n->id > s->max_id) s->max_id = n->id;
        s->n_nodes++;
    }
    fclose(f);
    snprintf(path, sizeof path, "%s/surface_faces.csv", dir);
    f = fopen(path, "r");
    if (!f) return 0;
    cap = 0;
    if (!fgets(line, sizeof line, f)) {
        fclose(f);
        return 0;
    }
    while (fgets(line, sizeof line, f)) {
        if (s->n_faces == cap) {
            cap = cap ? 2 * cap : 1024;
            s->faces = realloc(s->faces, (size_t)cap * 6 * sizeof *s->faces);
        }
        int *t = s->faces + 6 * s->n_faces;
        if (sscanf(line, "%d,%d,%d,%d,%d,%d", &t[0], &t[1], &t[2], &t[3], &t[4], &t[5]) != 6) break;
        s->n_faces++;
    }
    fclose(f);
    s->index = malloc((size_t)(s->max_id + 1) * sizeof *s->index);
    for (int i = 0; i <= s->max_id; ++i) s->index[i] = -1;
    for (int i = 0; i < s->n_nodes; ++i) s->index[s->nodes[i].id] = i;
    for (int k = 0; k < 6 * s->n_faces; ++k)
        if (s->faces[k] < 0 || s->faces[k] > s->max_id || s->index[s->faces[k]] < 0) return 0;
    return s->n_nodes > 0 && s->n_faces > 0;
}

static double tri_area(const double *a, const double *b, const double *c)
{
    double e[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, g[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {e[1] * g[2] - e[2] * g[1], e[2] * g[0] - e[0] * g[2], e[0] * g[1] - e[1] * g[0]};
    return 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
}

/* The integral of |v|^2 over the faces for the quadratic interpolant of nodal values v
 * (3 per row of s->nodes): the 6-node triangle's consistent mass matrix, A/180 times
 * corners 6 (diagonal), -1 (corner-corner), -4 (corner-opposite mid), 0 (corner-adjacent mid),
 * mids 32 (diagonal), 16 (mid-mid). */
static double surface_integral(const surface *s, const double *v)
{
    static const double M[6][6] = {{6, -1, -1, 0, -4, 0},  {-1, 6, -1, 0, 0, -4},  {-1, -1, 6, -4, 0, 0},
                                    {0, 0, -4, 32, 16, 16}, {-4, 0, 0, 16, 32, 16}, {0, -4, 0, 16, 16, 32}};
    double total = 0;
    for (int f = 0; f < s->n_faces; ++f) {
        const int *t = s->faces + 6 * f;
        int r[6];
        for (int k = 0; k < 6; ++k) r[k] = s->index[t[k]];
        double A = tri_area(s->nodes[r[0]].X, s->nodes[r[1]].X, s->nodes[r[2]].X);
        for (int i = 0; i < 6; ++i)
            for (int j = 0; j < 6; ++j)
                total += A / 180 * M[i][j] *
                         (v[3 * r[i]] * v[3 * r[j]] + v[3 * r[i] + 1] * v[3 * r[j] + 1] + v[3 * r[i] + 2] * v[3 * r[j] + 2]);
    }
    return total;
}

/* The tip deflection as tools/fem/cantilever.py measures it: the area-weighted mean of -u_z
 * over the end face x = L (6-node triangles weigh corners 0, mid-edge nodes A/3). */
static double tip_deflection(const surface *s, double L)
{
    double w = 0, wu = 0;
    for (int f = 0; f < s->n_faces; ++f) {
        const int *t = s->faces + 6 * f;
        const surface_node *c[6];
        for (int k = 0; k < 6; ++k) c[k] = &s->nodes[s->index[t[k]]];
        if (fabs(c[0]->X[0] - L) > 1e-9 || fabs(c[1]->X[0] - L) > 1e-9 || fabs(c[2]->X[0] - L) > 1e-9) continue;
        double A = tri_area(c[0]->X, c[1]->X, c[2]->X);
        for (int k = 3; k < 6; ++k) {
            w += A / 3;
            wu += A / 3 * -c[k]->u_fem[2];
        }
    }
    return w > 0 ? wu / w : NAN;
}

/* (u,v) of a point X on a flat part of rest: Newton on S(u,v) = X in the least-squares
 * sense (exact for the beam's faces, whose surfaces are affine in (u,v)); the residual
 * distance is returned. */
static double invert_flat(const sem_surface *s, const double X[3], double uv[2])
{
    uv[0] = 0.5 * (s->u0 + s->u1), uv[1] = 0.5 * (s->v0 + s->v1);
    double x[3], xu[3], xv[3];
    for (int it = 0; it < 30; ++it) {
        sem_surface_eval(s, uv[0], uv[1], x, xu, xv, NULL);
        double r[3] = {X[0] - x[0], X[1] - x[1], X[2] - x[2]};
        double a = xu[0] * xu[0] + xu[1] * xu[1] + xu[2] * xu[2], b = xu[0] * xv[0] + xu[1] * xv[1] + xu[2] * xv[2];
        double c = xv[0] * xv[0] + xv[1] * xv[1] + xv[2] * xv[2];
        double g0 = xu[0] * r[0] + xu[1] * r[1] + xu[2] * r[2], g1 = xv[0] * r[0] + xv[1] * r[1] + xv[2] * r[2];
        double det = a * c - b * b;
        uv[0] += (c * g0 - b * g1) / det;
        uv[1] += (a * g1 - b * g0) / det;
    }
    sem_surface_eval(s, uv[0], uv[1], x, NULL, NULL, NULL);
    return sqrt((X[0] - x[0]) * (X[0] - x[0]) + (X[1] - x[1]) * (X[1] - x[1]) + (X[2] - x[2]) * (X[2] - x[2]));
}

static void test_cantilever(const char *dir, int *skipped)
{
    char beam[1024], scene[1024], work[1024], path[1200];
    snprintf(beam, sizeof beam, "%s/beam.igs", dir);
    snprintf(scene, sizeof scene, "%s/cantilever.json", dir);
    snprintf(work, sizeof work, "%s/work", dir);
    int rc = run("primitive beam -o %s", beam);
    CHECK(rc == 0, "primitive beam: exit %d: %s", rc, err);
    /* pinned at x = 0 (the box ends at the end face: the mesh needs no cut) */
    CHECK(write_text(scene, "{\"objects\": [{\"model\": \"beam.igs\",\n"
                            "  \"material\": {\"type\": \"neohookean\", \"density\": 1000, \"youngs_modulus\": 1e6,"
                            " \"poisson_ratio\": 0.45},\n"
                            "  \"pin\": {\"box\": [[-1, -1, -1], [0, 2, 2]]}}],\n"
                            " \"gravity\": [0, 0, -10]}\n"),
          "cannot write %s", scene);
    /* two meshes (h 0.5, 0.35 m; 1,800 nodes at most): the FEM tip moves by about 0.4 % */
    rc = run("validate %s %s --json --quiet --workdir %s --h0 0.5 --max-levels 2 --tolerance 0.01", beam, scene, work);
    if (rc == 3) {
        printf("skip: %s", err);
        *skipped = 1;
        return;
    }
    CHECK(rc == 0, "validate: exit %d: %s", rc, err);
    if (rc != 0) return;
    cJSON *j = cJSON_Parse(out);
    CHECK(j != NULL, "validate --json: not JSON: %.300s", out);
    if (!j) return;
    const cJSON *fem = cJSON_GetObjectItemCaseSensitive(j, "fem");
    CHECK(cJSON_IsTrue(cJSON_GetObjectItemCaseSensitive(fem, "converged")), "FEM not converged: %.2000s", out);
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(fem, "levels")) == 2, "levels: %.2000s", out);
    CHECK(json_number(j, "problem.material.youngs_modulus") == 1e6, "E");
    CHECK(json_number(j, "sem.dofs") == 162, "sem dofs %g", json_number(j, "sem.dofs"));
    CHECK(json_number(j, "comparison.nodes_off_surface") == 0, "nodes off surface %g",
          json_number(j, "comparison.nodes_off_surface"));

    /* the FEM tip against the recorded reference (tools/fem/cantilever.py) */
    surface s;
    CHECK(read_surface(work, &s), "cannot read %s/surface_*.csv", work);
    snprintf(path, sizeof path, "%s/../../validation/fem_cantilever.json", SEM_TEST_DATA);
    char *ref_text = test_slurp(path, NULL);
    cJSON *ref = ref_text ? cJSON_Parse(ref_text) : NULL;
    free(ref_text);
    double reference = json_number(ref, "tip_deflection_m");
    CHECK(reference > 4.2 && reference < 4.3, "reference tip %g from %s", reference, path);
    double tip = tip_deflection(&s, 5.0);
    CHECK_REL(tip, reference, 0.02);
    printf("FEM tip deflection %.5f m, reference %.5f m (%+.2f %%)\n", tip, reference, 100 * (tip / reference - 1));
    cJSON_Delete(ref);

    /* sem's displacement at the nodes, independently: the part validate chose must contain
     * the node; (u,v) by this test's own inversion; the frame evaluated there */
    sem_model *rest = NULL, *frame = NULL;
    sem_error e;
    snprintf(path, sizeof path, "%s/sem/frame_0000.igs", work);
    CHECK(sem_model_load(path, &rest, &e) == SEM_OK, "%s: %s", path, e.message);
    snprintf(path, sizeof path, "%s/sem/frame_0001.igs", work);
    CHECK(sem_model_load(path, &frame, &e) == SEM_OK, "%s: %s", path, e.message);
    if (rest && frame && s.n_nodes > 0) {
        double *u_fem = malloc((size_t)s.n_nodes * 3 * sizeof(double));
        double *u_sem = malloc((size_t)s.n_nodes * 3 * sizeof(double));
        double *diff = malloc((size_t)s.n_nodes * 3 * sizeof(double));
        double worst_residual = 0, worst_mismatch = 0, max_fem = 0, max_sem = 0;
        int bad_part = 0;
        for (int i = 0; i < s.n_nodes; ++i) {
            const surface_node *n = &s.nodes[i];
            if (n->part < 0 || n->part >= rest->n_parts) {
                bad_part++;
                continue;
            }
            double uv[2], x[3];
            double r = invert_flat(&rest->parts[n->part].surface, n->X, uv);
            if (r > worst_residual) worst_residual = r;
            sem_surface_eval(&frame->parts[n->part].surface, uv[0], uv[1], x, NULL, NULL, NULL);
            double a = 0, b = 0;
            for (int c = 0; c < 3; ++c) {
                u_fem[3 * i + c] = n->u_fem[c];
                u_sem[3 * i + c] = x[c] - n->X[c];
                diff[3 * i + c] = u_sem[3 * i + c] - u_fem[3 * i + c];
                if (fabs(u_sem[3 * i + c] - n->u_sem[c]) > worst_mismatch) worst_mismatch = fabs(u_sem[3 * i + c] - n->u_sem[c]);
                a += u_fem[3 * i + c] * u_fem[3 * i + c];
                b += u_sem[3 * i + c] * u_sem[3 * i + c];
            }
            if (sqrt(a) > max_fem) max_fem = sqrt(a);
            if (sqrt(b) > max_sem) max_sem = sqrt(b);
        }
        CHECK(bad_part == 0, "%d nodes without a part", bad_part);
        CHECK(worst_residual < 1e-9, "a node lies %g m off the part validate chose", worst_residual);
        CHECK(worst_mismatch < 1e-9, "sem's displacement in surface_nodes.csv differs by %g m", worst_mismatch);
        double l2 = sqrt(surface_integral(&s, diff) / surface_integral(&s, u_fem));
        CHECK_REL(json_number(j, "comparison.l2_error"), l2, 1e-6);
        CHECK_REL(json_number(j, "comparison.max_displacement.ratio"), max_sem / max_fem, 1e-9);
        CHECK_REL(json_number(j, "comparison.max_displacement.fem_m"), max_fem, 1e-9);
        /* the cantilever b1 of docs/validation.md section 2: sem's one-section beam bends far
         * less than FEM (35 % of the tip deflection at the default gamma) */
        CHECK(max_sem / max_fem > 0.2 && max_sem / max_fem < 0.6, "sem / FEM largest displacement %g",
              max_sem / max_fem);
        printf("relative L2 error %.4f (reported %.4f), largest displacement sem / FEM %.4f\n", l2,
               json_number(j, "comparison.l2_error"), max_sem / max_fem);
        free(u_fem);
        free(u_sem);
        free(diff);
    }
    sem_model_destroy(rest);
    sem_model_destroy(frame);
    surface_free(&s);
    cJSON_Delete(j);
}

static void test_errors(const char *dir)
{
    char beam[1024], open_model[1024], path[1200];
    snprintf(beam, sizeof beam, "%s/beam.igs", dir);
    snprintf(open_model, sizeof open_model, "%s/open_beam.igs", dir);
    /* the beam without its end cap at x = L: an open box */
    sem_model *m = NULL, *open = sem_model_create();
    sem_error e;
    CHECK(sem_model_load(beam, &m, &e) == SEM_OK, "%s: %s", beam, e.message);
    if (m && open) {
        for (int i = 0; i < m->n_parts; ++i)
            if (i != 1) CHECK(sem_model_add_part(open, &m->parts[i], &e) == SEM_OK, "add part: %s", e.message);
        snprintf(open->units, sizeof open->units, "%s", m->units);
        open->unit_to_meter = m->unit_to_meter;
        CHECK(sem_model_save(open, open_model, &e) == SEM_OK, "%s: %s", open_model, e.message);
    }
    sem_model_destroy(m);
    sem_model_destroy(open);
    int rc = run("validate %s --quiet", open_model);
    CHECK(rc == 1, "open model: exit %d: %s", rc, err);
    check_one_error_line("open model");
    CHECK(strstr(err, "open_beam.igs") && strstr(err, "gmsh") && strstr(err, "solid") &&
              strstr(err, "open surfaces or gaps"),
          "open model: %s", err);

    rc = run("validate %s/missing.igs --quiet", dir);
    CHECK(rc == 1, "missing file: exit %d", rc);
    check_one_error_line("missing file");
    CHECK(strstr(err, "missing.igs: cannot open") != NULL, "missing file: %s", err);

    rc = run("validate %s --bogus", beam);
    CHECK(rc == 2, "bad option: exit %d", rc);
    CHECK(strncmp(err, "sem: ", 5) == 0 && strstr(err, "--bogus") && strstr(err, "usage: sem validate"),
          "bad option: %s", err);
    rc = run("validate %s --tolerance 0", beam);
    CHECK(rc == 2 && strstr(err, "--tolerance"), "--tolerance 0: exit %d: %s", rc, err);
    rc = run("validate");
    CHECK(rc == 2, "no model: exit %d", rc);

    /* scenes validate cannot map to the FEM side */
    snprintf(path, sizeof path, "%s/parts_pin.json", dir);
    write_text(path, "{\"objects\": [{\"model\": \"beam.igs\", \"pin\": {\"parts\": [0]}}]}");
    rc = run("validate %s %s --quiet", beam, path);
    CHECK(rc == 1, "pin by parts: exit %d", rc);
    check_one_error_line("pin by parts");
    CHECK(strstr(err, "objects[0].pin") != NULL, "pin by parts: %s", err);
    snprintf(path, sizeof path, "%s/two.json", dir);
    write_text(path, "{\"objects\": [{\"model\": \"beam.igs\"}, {\"model\": \"beam.igs\"}]}");
    rc = run("validate %s %s --quiet", beam, path);
    CHECK(rc == 1, "two objects: exit %d", rc);
    check_one_error_line("two objects");
    snprintf(path, sizeof path, "%s/bad.json", dir);
    write_text(path, "{\"objects\": [");
    rc = run("validate %s %s --quiet", beam, path);
    CHECK(rc == 1, "bad JSON: exit %d", rc);
    check_one_error_line("bad JSON");

    /* sem probe: the helper's own errors */
    rc = run("probe %s", beam);
    CHECK(rc == 2, "probe without points: exit %d", rc);
    snprintf(path, sizeof path, "%s/points.txt", dir);
    write_text(path, "1 2\n");
    rc = run("probe %s %s %s", beam, beam, path);
    CHECK(rc == 1 && strstr(err, "points.txt:1: expected three numbers"), "probe bad points: exit %d: %s", rc, err);
    check_one_error_line("probe bad points");
    write_text(path, "# x y z\n2.5 0.5 1\n0 0.5 0.5\n");
    rc = run("probe %s %s %s", beam, beam, path);
    CHECK(rc == 0 && count_lines(out) == 2, "probe: exit %d: %s %s", rc, out, err);
    int part;
    double u, v, d, x[3];
    int inside;
    CHECK(sscanf(out, "%d %lf %lf %lf %d %lf %lf %lf", &part, &u, &v, &d, &inside, &x[0], &x[1], &x[2]) == 8 &&
              d < 1e-12 && inside == 1 && fabs(x[0] - 2.5) < 1e-12 && fabs(x[2] - 1) < 1e-12,
          "probe on the top face: %s", out);
}

int main(void)
{
    const char *dir = test_tmpdir();
    int skipped = 0;
    test_cantilever(dir, &skipped);
    if (skipped) {
        test_finish("test_validate");
        return TEST_SKIPPED;
    }
    test_errors(dir);
    return test_finish("test_validate");
}
