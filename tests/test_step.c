/* test_step.c - STEP files (through Open CASCADE, src/io/step_occt.cpp): a model written as
 * STEP and read back is the same model (parts, control points to 1e-12, trims, areas, unit);
 * `sem convert` and `sem inspect` take .step/.stp; bad files give one clear error and leave
 * nothing behind. Without Open CASCADE (SEM_WITH_OCCT=OFF) the same calls must say that STEP
 * is not compiled in. (Open CASCADE's own view of these files: tests/occt_check.cpp.) */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sem/sem.h"
#include "test_util.h"

static char out[1 << 16], err[1 << 16];

static double area_of(const sem_model *m, double *per_part)
{
    sem_part_measure_result total;
    sem_part_measure_result *per = calloc((size_t)m->n_parts, sizeof *per);
    sem_error e;
    if (!per || sem_model_measure(m, per, &total, &e) != SEM_OK) {
        free(per);
        return NAN;
    }
    for (int i = 0; per_part && i < m->n_parts; ++i) per_part[i] = per[i].area;
    free(per);
    return total.area;
}

static int trimmed_parts(const sem_model *m)
{
    int n = 0;
    for (int i = 0; i < m->n_parts; ++i) n += m->parts[i].has_outer || m->parts[i].n_holes > 0;
    return n;
}

/* write m as STEP, read it back, compare */
static void roundtrip(const char *what, const sem_model *m, double trimmed_tol)
{
    char path[512];
    snprintf(path, sizeof path, "%s/%s.step", test_tmpdir(), what);
    sem_error e;
    sem_status st = sem_step_write(m, path, &e);
    CHECK(st == SEM_OK, "%s: write: %s", what, st == SEM_OK ? "" : e.message);
    if (st != SEM_OK) return;
    sem_model *b = NULL;
    st = sem_model_load(path, &b, &e);
    CHECK(st == SEM_OK, "%s: read: %s", what, st == SEM_OK ? "" : e.message);
    if (st != SEM_OK) return;
    CHECK(b->n_parts == m->n_parts, "%s: %d parts read, %d written", what, b->n_parts, m->n_parts);
    CHECK(strcmp(b->units, m->units) == 0 && b->unit_to_meter == m->unit_to_meter,
          "%s: unit %s (%g m) read, %s (%g m) written", what, b->units, b->unit_to_meter, m->units,
          m->unit_to_meter);
    CHECK(b->n_warnings == 0, "%s: warnings: %s", what, b->n_warnings ? b->warnings[0] : "");
    CHECK(trimmed_parts(b) == trimmed_parts(m), "%s: %d trimmed parts read, %d written", what,
          trimmed_parts(b), trimmed_parts(m));
    if (b->n_parts == m->n_parts) {
        double *pa = calloc((size_t)m->n_parts, sizeof *pa), *pb = calloc((size_t)m->n_parts, sizeof *pb);
        area_of(m, pa);
        area_of(b, pb);
        for (int i = 0; i < m->n_parts; ++i) {
            const sem_surface *s = &m->parts[i].surface, *t = &b->parts[i].surface;
            int trimmed = m->parts[i].has_outer || m->parts[i].n_holes > 0;
            /* untrimmed: the same surface, measured to 1e-12 each time */
            CHECK_REL(pb[i], pa[i], trimmed ? trimmed_tol : 1e-10);
            CHECK(t->degree_u == s->degree_u && t->degree_v == s->degree_v && t->n_u == s->n_u &&
                      t->n_v == s->n_v,
                  "%s: part %d: %dx%d degree %dx%d read, %dx%d degree %dx%d written", what, i,
                  t->n_u, t->n_v, t->degree_u, t->degree_v, s->n_u, s->n_v, s->degree_u,
                  s->degree_v);
            if (t->n_u != s->n_u || t->n_v != s->n_v) continue;
            /* the same control points, in the same order, unless the face came back
             * reversed in u (then mirrored) */
            double worst = 0, worst_mirror = 0;
            for (int j = 0; j < s->n_v; ++j)
                for (int k = 0; k < s->n_u; ++k) {
                    const double *p = s->ctrl + 3 * (k + s->n_u * j);
                    const double *q = t->ctrl + 3 * (k + s->n_u * j);
                    const double *r = t->ctrl + 3 * (s->n_u - 1 - k + s->n_u * j);
                    for (int d = 0; d < 3; ++d) {
                        worst = fmax(worst, fabs(p[d] - q[d]));
                        worst_mirror = fmax(worst_mirror, fabs(p[d] - r[d]));
                    }
                }
            CHECK(worst < 1e-12, "%s: part %d: control points differ by %g", what, i, worst);
        }
        free(pa);
        free(pb);
    }
    sem_model_destroy(b);
}

static void test_roundtrips(void)
{
    sem_model *m = sem_model_create();
    sem_box_def box = sem_default_box_def();
    box.size[0] = 1, box.size[1] = 2, box.size[2] = 3;
    sem_sphere_def sphere = sem_default_sphere_def();
    sphere.center[0] = 5;
    sem_primitive_box(m, &box, NULL);
    sem_primitive_sphere(m, &sphere, NULL);
    /* the unit travels: metres in, metres out */
    snprintf(m->units, sizeof m->units, "M");
    m->unit_to_meter = 1.0;
    CHECK_REL(area_of(m, NULL), 22.0 + 4 * M_PI, 1e-10);
    roundtrip("primitives", m, 0);
    sem_model_destroy(m);

    /* trimmed parts: a composite outer loop, a circular hole, a triangle (tests/data) */
    sem_model *t = NULL;
    sem_error e;
    if (sem_model_load(SEM_TEST_DATA "/iges_cad_trimmed.igs", &t, &e) == SEM_OK) {
        snprintf(t->units, sizeof t->units, "MM");
        t->unit_to_meter = 0.001;
        roundtrip("trimmed", t, 1e-3);
        sem_model_destroy(t);
    } else {
        CHECK(0, "iges_cad_trimmed.igs: %s", e.message);
    }
    /* trims from model-space boundaries (a plate with a hole, a cylinder across its seam, a
     * sphere cap through its pole) */
    if (sem_model_load(SEM_TEST_DATA "/iges_model_space.igs", &t, &e) == SEM_OK) {
        roundtrip("model_space", t, 1e-3);
        sem_model_destroy(t);
    }
    /* a shared model with many trimmed parts */
    const char *mug = test_shared_model("mugs/mug_trimmed_complex.iges");
    if (mug && sem_model_load(mug, &t, &e) == SEM_OK) {
        roundtrip("mug", t, 1e-3);
        sem_model_destroy(t);
    }
}

static void test_cli(void)
{
    char igs[512], step[512], stp[512];
    snprintf(igs, sizeof igs, "%s/beam.igs", test_tmpdir());
    snprintf(step, sizeof step, "%s/beam.step", test_tmpdir());
    snprintf(stp, sizeof stp, "%s/BEAM.STP", test_tmpdir());
    char args[2048];
    snprintf(args, sizeof args, "primitive beam --sections 3 -o %s", igs);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "primitive: %s", err);
    snprintf(args, sizeof args, "convert %s %s", igs, step);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "convert to STEP: %s", err);
    snprintf(args, sizeof args, "convert %s %s", step, stp);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "convert STEP to STP: %s", err);
    snprintf(args, sizeof args, "inspect %s", stp);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "inspect .STP: %s", err);
    /* 5 x 1 x 1 beam: 6 + 4 * 2 parts, area 22 */
    CHECK(strstr(out, "parts           14 (0 trimmed") != NULL, "inspect: %s", out);
    CHECK(strstr(out, "area            22\n") != NULL, "inspect: %s", out);
    CHECK(strlen(err) == 0, "inspect printed on stderr: %s", err);
    /* preprocess and run take STEP models like any other */
    snprintf(args, sizeof args, "preprocess %s --order 1 --rays 3 3 --json", stp);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "preprocess .STP: %s", err);
    CHECK(strstr(out, "\"volume\"") != NULL, "preprocess --json: %.300s", out);
    char scene[512], dir[512];
    snprintf(scene, sizeof scene, "%s/scene.json", test_tmpdir());
    snprintf(dir, sizeof dir, "%s/run", test_tmpdir());
    FILE *f = fopen(scene, "w");
    if (f) {
        fprintf(f, "{\"objects\": [{\"model\": \"BEAM.STP\", \"sem\": {\"order\": 1, "
                   "\"rays\": [3, 3]}, \"pin\": {\"box\": [[-0.01, -1, -1], [0.01, 2, 2]]}}], "
                   "\"integrator\": {\"type\": \"linearly_implicit_euler\", \"dt\": 0.01}}\n");
        fclose(f);
    }
    snprintf(args, sizeof args, "run %s --frames 1 --out %s --quiet --no-cache", scene, dir);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 0, "run with a STEP model: %s", err);
    snprintf(args, sizeof args, "%s/frame_0001.igs", dir);
    CHECK(access(args, F_OK) == 0, "run wrote no frame_0001.igs");
}

static void test_errors(void)
{
    char path[512], bad[512];
    sem_model *m = NULL;
    sem_error e;
    snprintf(path, sizeof path, "%s/missing.step", test_tmpdir());
    CHECK(sem_model_load(path, &m, &e) == SEM_ERR_IO && m == NULL, "missing file: %s", e.message);
    CHECK(strstr(e.message, "missing.step") && strstr(e.message, "cannot open"), "message: %s",
          e.message);
    snprintf(bad, sizeof bad, "%s/garbage.stp", test_tmpdir());
    FILE *f = fopen(bad, "w");
    if (f) {
        fputs("ISO-10303-21;\nHEADER;\nthis is not STEP\n", f);
        fclose(f);
    }
    CHECK(sem_model_load(bad, &m, &e) == SEM_ERR_PARSE && m == NULL, "garbage: %s", e.message);
    CHECK(strstr(e.message, "garbage.stp") != NULL, "message: %s", e.message);
    /* only regular files go to Open CASCADE (a FIFO would block it; docs/reliability.md) */
    snprintf(path, sizeof path, "%s/fifo.step", test_tmpdir());
    CHECK(mkfifo(path, 0600) == 0, "mkfifo %s", path);
    CHECK(sem_model_load(path, &m, &e) == SEM_ERR_IO && m == NULL &&
              strstr(e.message, "not a regular file (a FIFO)"),
          "FIFO: %s", e.message);
    snprintf(path, sizeof path, "%s/folder.stp", test_tmpdir());
    CHECK(mkdir(path, 0700) == 0, "mkdir %s", path);
    CHECK(sem_model_load(path, &m, &e) == SEM_ERR_IO && m == NULL &&
              strstr(e.message, "not a regular file (a folder)"),
          "folder: %s", e.message);
    /* a failed write leaves nothing: into a folder that does not exist */
    sem_model *box = sem_model_create();
    sem_box_def def = sem_default_box_def();
    sem_primitive_box(box, &def, NULL);
    snprintf(path, sizeof path, "%s/no/such/folder/x.step", test_tmpdir());
    CHECK(sem_model_save(box, path, &e) == SEM_ERR_IO, "write into a missing folder: %s", e.message);
    CHECK(access(path, F_OK) != 0, "a file was left behind");
    /* the CLI: one line, exit 1 */
    char args[1024];
    snprintf(args, sizeof args, "inspect %s", bad);
    CHECK(test_run_cli(args, out, sizeof out, err, sizeof err) == 1, "inspect garbage");
    CHECK(strncmp(err, "sem: ", 5) == 0 && strchr(err, '\n') == err + strlen(err) - 1,
          "one error line: %s", err);
    sem_model_destroy(box);
}

/* built without Open CASCADE: every STEP call says so */
static void test_not_compiled_in(void)
{
    sem_model *m = NULL, *box = sem_model_create();
    sem_error e;
    CHECK(sem_model_load(SEM_TEST_DATA "/x.step", &m, &e) == SEM_ERR_UNSUPPORTED, "load");
    CHECK(strstr(e.message, "not supported by this build") != NULL, "message: %s", e.message);
    char path[512];
    snprintf(path, sizeof path, "%s/x.stp", test_tmpdir());
    CHECK(sem_model_save(box, path, &e) == SEM_ERR_UNSUPPORTED, "save");
    CHECK(access(path, F_OK) != 0, "a file was written");
    CHECK(test_run_cli("--version", out, sizeof out, err, sizeof err) == 0 &&
              strstr(out, "without STEP") != NULL,
          "--version: %s", out);
    sem_model_destroy(box);
}

int main(void)
{
    if (sem_has_step()) {
        test_roundtrips();
        test_cli();
        test_errors();
    } else {
        test_not_compiled_in();
    }
    return test_finish("test_step");
}
