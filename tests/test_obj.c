/*
 * test_obj.c - OBJ free-form reading and writing: a hand-written file with Bezier and
 * B-spline patches, relative indices, continuation lines and a trimmed patch with a hole
 * reads to the surfaces it describes (checked at known points), writes back and reads
 * again bit for bit; malformed files fail with "FILE:LINE: what".
 */
#define _POSIX_C_SOURCE 200809L
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/trim.h"
#include "test_util.h"

static const char *data_file(const char *name)
{
    static char path[1024];
    snprintf(path, sizeof path, "%s/%s", SEM_TEST_DATA, name);
    return path;
}

static void eval(const sem_surface *s, double u, double v, double x[3])
{
    sem_surface_eval(s, u, v, x, NULL, NULL, NULL);
}

static void test_hand_written(void)
{
    sem_error err;
    sem_model *m = NULL;
    CHECK(sem_model_load(data_file("obj_patches.obj"), &m, &err) == SEM_OK, "%s", err.message);
    if (!m) return;
    CHECK(m->n_parts == 4, "%d parts", m->n_parts);
    if (m->n_parts != 4) {
        sem_model_destroy(m);
        return;
    }
    double x[3];
    /* 1: Bezier bump, knots 0 0 0 1 1 1, centre (1,1,1) (Bernstein weights 1/4 1/2 1/4) */
    const sem_surface *s = &m->parts[0].surface;
    CHECK(strcmp(m->parts[0].name, "bezier_bump") == 0, "name '%s'", m->parts[0].name);
    CHECK(s->degree_u == 2 && s->n_u == 3 && s->n_v == 3, "bump size");
    CHECK(s->knots_u[2] == 0 && s->knots_u[3] == 1, "bump knots");
    eval(s, 0.5, 0.5, x);
    CHECK_NEAR(x[0], 1.0, 1e-15);
    CHECK_NEAR(x[1], 1.0, 1e-15);
    CHECK_NEAR(x[2], 1.0, 1e-15);
    eval(s, 0.25, 0.5, x); /* z = 4 * (2 t (1-t)) * 1/2 at t = 1/4: 4 * 0.375 * 0.5 */
    CHECK_NEAR(x[2], 0.75, 1e-15);

    /* 2: two cubic Bezier segments over [0,1] and [1,3]: knots 0x4 1x3 3x4, 7 x 2 points */
    s = &m->parts[1].surface;
    CHECK(strcmp(m->parts[1].name, "two segment bezier") == 0, "name '%s'", m->parts[1].name);
    CHECK(s->degree_u == 3 && s->degree_v == 1 && s->n_u == 7 && s->n_v == 2, "strip size %d %d",
          s->n_u, s->n_v);
    double expect_knots[11] = {0, 0, 0, 0, 1, 1, 1, 3, 3, 3, 3};
    CHECK(memcmp(s->knots_u, expect_knots, sizeof expect_knots) == 0, "Bezier knots");
    eval(s, 2.0, 0.5, x); /* middle of the second segment: x = (3+3*4+3*5+6)/8 = 4.5 */
    CHECK_NEAR(x[0], 4.5, 1e-14);
    CHECK_NEAR(x[1], 0.5, 1e-15);
    eval(s, 1.0, 0.0, x); /* the shared end point */
    CHECK_NEAR(x[0], 3.0, 1e-15);
    CHECK(s->u0 == 0 && s->u1 == 3, "strip range");

    /* 3: non-rational B-spline: the w on the v lines is ignored */
    s = &m->parts[2].surface;
    CHECK(strcmp(m->parts[2].name, "plain bspline") == 0, "name '%s'", m->parts[2].name);
    int all_one = 1;
    for (int i = 0; i < s->n_u * s->n_v; ++i) all_one &= s->weights[i] == 1.0;
    CHECK(all_one, "non-rational weights are not 1");
    CHECK(s->n_u == 4 && s->n_v == 2 && s->ctrl[3 * 1 + 2] == 1.0, "plain ctrl");
    eval(s, 1.0, 0.0, x); /* N(1) = (0, 1/2, 1/2, 0): z = 1, x = 1.5 */
    CHECK_NEAR(x[0], 1.5, 1e-15);
    CHECK_NEAR(x[2], 1.0, 1e-15);

    /* 4: trimmed plate */
    const sem_part *p = &m->parts[3];
    CHECK(strcmp(p->name, "trimmed plate") == 0, "name '%s'", p->name);
    CHECK(p->has_outer == 1 && p->outer.n_curves == 1 && p->n_holes == 1 &&
              p->holes[0].n_curves == 1,
          "trims: outer %d (%d curves), holes %d", p->has_outer, p->outer.n_curves, p->n_holes);
    if (p->n_holes == 1 && p->has_outer) {
        const sem_curve *c = &p->holes[0].curves[0];
        CHECK(c->degree == 2 && c->n_ctrl == 9 && c->weights[1] == 0.70710678118654757,
              "hole curve");
        double y[3];
        sem_curve_eval(c, 0.125, y, NULL); /* 45 degrees on the circle */
        CHECK_NEAR(hypot(y[0] - 0.5, y[1] - 0.5), 0.25, 1e-15);
        CHECK(p->outer.curves[0].t0 == 0 && p->outer.curves[0].t1 == 4, "outer range");
        sem_trim_region *r = NULL;
        CHECK(sem_trim_region_build(p, &r, &err) == SEM_OK, "%s", err.message);
        if (r) {
            CHECK(sem_trim_region_inside(r, 0.1, 0.1) == 1, "corner inside");
            CHECK(sem_trim_region_inside(r, 0.5, 0.5) == 0, "centre is in the hole");
            CHECK(sem_trim_region_inside(r, 0.5, 0.8) == 1, "above the hole");
            sem_trim_region_destroy(r);
        }
    }
    CHECK(m->n_warnings == 0, "%d warnings", m->n_warnings);

    /* write, read back: bit for bit */
    char path[512];
    snprintf(path, sizeof path, "%s/patches_out.obj", test_tmpdir());
    CHECK(sem_obj_write(m, path, &err) == SEM_OK, "%s", err.message);
    sem_model *b = NULL;
    CHECK(sem_obj_read(path, &b, &err) == SEM_OK, "%s", err.message);
    if (b && b->n_parts == m->n_parts) {
        for (int i = 0; i < m->n_parts; ++i) {
            const sem_surface *s1 = &m->parts[i].surface, *s2 = &b->parts[i].surface;
            size_t n = (size_t)s1->n_u * (size_t)s1->n_v;
            CHECK(s1->n_u == s2->n_u && s1->n_v == s2->n_v &&
                      memcmp(s1->ctrl, s2->ctrl, 3 * n * sizeof(double)) == 0 &&
                      memcmp(s1->weights, s2->weights, n * sizeof(double)) == 0 &&
                      memcmp(s1->knots_u, s2->knots_u,
                             (size_t)(s1->n_u + s1->degree_u + 1) * sizeof(double)) == 0 &&
                      memcmp(s1->knots_v, s2->knots_v,
                             (size_t)(s1->n_v + s1->degree_v + 1) * sizeof(double)) == 0,
                  "part %d changed", i);
            CHECK(strcmp(m->parts[i].name, b->parts[i].name) == 0, "name %s", b->parts[i].name);
            CHECK(m->parts[i].n_holes == b->parts[i].n_holes &&
                      m->parts[i].has_outer == b->parts[i].has_outer,
                  "trims of part %d", i);
        }
        const sem_curve *c1 = &m->parts[3].holes[0].curves[0], *c2 = &b->parts[3].holes[0].curves[0];
        CHECK(memcmp(c1->weights, c2->weights, 9 * sizeof(double)) == 0 &&
                  memcmp(c1->ctrl, c2->ctrl, 27 * sizeof(double)) == 0,
              "hole curve changed");
    } else {
        CHECK(0, "read back %d parts", b ? b->n_parts : -1);
    }
    /* the writer chose the plainest cstype for each element */
    FILE *f = fopen(path, "r");
    char line[512];
    int n_rat = 0, n_plain = 0, n_hole = 0, n_trim = 0;
    while (f && fgets(line, sizeof line, f)) {
        n_rat += strncmp(line, "cstype rat bspline", 18) == 0;
        n_plain += strcmp(line, "cstype bspline\n") == 0;
        n_hole += strncmp(line, "hole ", 5) == 0;
        n_trim += strncmp(line, "trim ", 5) == 0;
    }
    if (f) fclose(f);
    CHECK(n_rat == 1 && n_plain == 5 && n_hole == 1 && n_trim == 1,
          "rat %d plain %d hole %d trim %d", n_rat, n_plain, n_hole, n_trim);
    sem_model_destroy(b);
    sem_model_destroy(m);
}

/* Writes text to a file and reads it; returns the status and leaves the message in err. */
static sem_status read_text(const char *name, const char *text, sem_error *err, char *path_out)
{
    snprintf(path_out, 512, "%s/%s", test_tmpdir(), name);
    FILE *f = fopen(path_out, "w");
    fputs(text, f);
    fclose(f);
    sem_model *m = NULL;
    sem_status st = sem_obj_read(path_out, &m, err);
    if (st == SEM_OK) sem_model_destroy(m);
    else CHECK(m == NULL, "model returned on error");
    return st;
}

#define SQUARE_V "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
#define SQUARE_BODY "parm u 0 0 1 1\nparm v 0 0 1 1\nend\n"

static void expect_error(const char *name, const char *text, int line, const char *what)
{
    sem_error err;
    char path[512], prefix[600];
    sem_status st = read_text(name, text, &err, path);
    CHECK(st != SEM_OK, "%s was accepted", name);
    if (st == SEM_OK) return;
    snprintf(prefix, sizeof prefix, "%s:%d: ", path, line);
    CHECK(strncmp(err.message, prefix, strlen(prefix)) == 0, "%s: message '%s' lacks '%s'", name,
          err.message, prefix);
    CHECK(strstr(err.message, what) != NULL, "%s: message '%s' lacks '%s'", name, err.message,
          what);
}

static void test_malformed(void)
{
    expect_error("bad_index.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 9\n" SQUARE_BODY, 7,
                 "out of range");
    expect_error("bad_relative.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 -1 -2 -3 -5\n" SQUARE_BODY, 7,
                 "out of range");
    expect_error("zero_index.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 0 1 2 3\n" SQUARE_BODY, 7,
                 "out of range");
    expect_error("missing_deg.obj", SQUARE_V "cstype bspline\nsurf 0 1 0 1 1 2 3 4\n" SQUARE_BODY,
                 6, "deg");
    expect_error("missing_cstype.obj", SQUARE_V "deg 1 1\nsurf 0 1 0 1 1 2 3 4\n" SQUARE_BODY, 6,
                 "cstype");
    expect_error("one_degree.obj",
                 SQUARE_V "cstype bspline\ndeg 1\nsurf 0 1 0 1 1 2 3 4\n" SQUARE_BODY, 7,
                 "two degrees");
    expect_error("count.obj", SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3\n" SQUARE_BODY,
                 7, "control vertices");
    expect_error("not_number.obj", "v 0 0 0\nv 1 abc 0\n", 2, "'abc' is not a number");
    expect_error("nan.obj", "# comment\nv 0 0 0\nv nan 0 0\n", 3, "not a finite number");
    expect_error("inf.obj", "v 0 0 inf\n", 1, "not a finite number");
    expect_error("zero_weight.obj", "v 0 0 0 1\nv 1 0 0 0\n", 2, "weight");
    expect_error("negative_vp_weight.obj", "vp 0 0 -1\n", 1, "weight");
    expect_error("knots_decrease.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nparm u 0 0 1 1\n"
                          "parm v 0 1 0 1\nend\n",
                 7, "decrease");
    expect_error("knot_count.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nparm u 0 0 1 1 1\n"
                          "parm v 0 0 1 1\nend\n",
                 7, "control vertices");
    expect_error("range.obj", SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 2 0 1 1 2 3 4\n" SQUARE_BODY,
                 7, "range");
    expect_error("no_end.obj", SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n"
                                        "parm u 0 0 1 1\nparm v 0 0 1 1\n",
                 7, "without 'end'");
    expect_error("trim_index.obj",
                 SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nparm u 0 0 1 1\n"
                          "parm v 0 0 1 1\ntrim 0 1 3\nend\n",
                 10, "curv2 index 3");
    expect_error("unknown.obj", "v 0 0 0\nfrobnicate 1 2\n", 2, "unknown statement");
    expect_error("cardinal.obj",
                 SQUARE_V "cstype cardinal\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n" SQUARE_BODY, 7,
                 "not supported");
    expect_error("degree.obj", "deg 0 1\n", 1, "out of range");
    expect_error("empty.obj", "# nothing\n", 1, "no free-form surfaces");
    /* continuation: the error is reported at the first line of the logical line */
    expect_error("continued.obj", "v 0 \\\n 0 \\\n x\n", 1, "'x' is not a number");
    expect_error("parm_outside.obj", "parm u 0 1\n", 1, "parm outside");
    expect_error("nested.obj", SQUARE_V "cstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n"
                                        "surf 0 1 0 1 1 2 3 4\n",
                 8, "before the 'end'");

    /* a missing file is an IO error naming the file */
    sem_error err;
    sem_model *m = NULL;
    CHECK(sem_obj_read("/nonexistent/x.obj", &m, &err) == SEM_ERR_IO && !m, "missing file");
    CHECK(strstr(err.message, "/nonexistent/x.obj") != NULL, "%s", err.message);

    /* polygon statements are skipped with a warning, not an error */
    char path[512];
    snprintf(path, sizeof path, "%s/mixed.obj", test_tmpdir());
    FILE *f = fopen(path, "w");
    fputs(SQUARE_V "f 1 2 3\ncstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n" SQUARE_BODY, f);
    fclose(f);
    CHECK(sem_obj_read(path, &m, &err) == SEM_OK, "%s", err.message);
    if (m) {
        CHECK(m->n_parts == 1 && m->n_warnings == 1, "%d parts %d warnings", m->n_parts,
              m->n_warnings);
        sem_model_destroy(m);
    }
}

/* Every prefix of the hand-written file, and the file with one byte changed at each
 * position, either reads or fails with a FILE:LINE message: never a crash or a hang. */
static void test_truncated_and_corrupted(void)
{
    FILE *f = fopen(data_file("obj_patches.obj"), "rb");
    static char text[65536];
    size_t len = f ? fread(text, 1, sizeof text - 1, f) : 0;
    if (f) fclose(f);
    CHECK(len > 1000, "data file has %zu bytes", len);
    char path[512];
    snprintf(path, sizeof path, "%s/mutant.obj", test_tmpdir());
    int n_ok = 0, n_err = 0, bad_messages = 0;
    for (size_t cut = 0; cut < len; cut += 7) {
        for (int mode = 0; mode < 2; ++mode) {
            FILE *o = fopen(path, "wb");
            if (mode == 0) {
                fwrite(text, 1, cut, o);
            } else {
                char saved = text[cut];
                text[cut] = "x-9\\ /.#"[cut % 8];
                fwrite(text, 1, len, o);
                text[cut] = saved;
            }
            fclose(o);
            sem_model *m = NULL;
            sem_error err;
            if (sem_obj_read(path, &m, &err) == SEM_OK) {
                n_ok++;
                sem_model_destroy(m);
            } else {
                n_err++;
                bad_messages += strncmp(err.message, path, strlen(path)) != 0;
            }
        }
    }
    printf("  mutated files: %d read, %d rejected\n", n_ok, n_err);
    CHECK(n_ok > 0 && n_err > 0, "%d read, %d rejected", n_ok, n_err);
    CHECK(bad_messages == 0, "%d messages without the file name", bad_messages);
}

int main(void)
{
    test_hand_written();
    test_malformed();
    test_truncated_and_corrupted();
    return test_finish("test_obj");
}
