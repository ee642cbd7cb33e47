/*
 * test_roundtrip.c - writing a model and reading it back changes nothing, bit for bit:
 * IGES -> IGES, OBJ -> OBJ and IGES -> OBJ -> IGES, for models built in code (with awkward
 * numbers: 0.1, 1/3, -0, 1e-300, 1e300, pi) and for every IGES file of the shared models.
 */
#define _POSIX_C_SOURCE 200809L
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "sem/model.h"
#include "test_util.h"

static int same_doubles(const double *a, const double *b, size_t n)
{
    return n == 0 || memcmp(a, b, n * sizeof(double)) == 0;
}

/* Prints the first difference; returns 1 when the curves are identical. */
static int same_curve(const sem_curve *a, const sem_curve *b, const char *where)
{
    if (a->degree != b->degree || a->n_ctrl != b->n_ctrl) {
        fprintf(stderr, "%s: curve degree/size %d/%d vs %d/%d\n", where, a->degree, a->n_ctrl,
                b->degree, b->n_ctrl);
        return 0;
    }
    size_t n = (size_t)a->n_ctrl;
    if (!same_doubles(a->knots, b->knots, n + (size_t)a->degree + 1) ||
        !same_doubles(a->ctrl, b->ctrl, 3 * n) || !same_doubles(a->weights, b->weights, n) ||
        memcmp(&a->t0, &b->t0, sizeof a->t0) != 0 || memcmp(&a->t1, &b->t1, sizeof a->t1) != 0) {
        fprintf(stderr, "%s: curve data differ\n", where);
        return 0;
    }
    return 1;
}

static int same_loop(const sem_trim_loop *a, const sem_trim_loop *b, const char *where)
{
    if (a->n_curves != b->n_curves) {
        fprintf(stderr, "%s: %d vs %d curves\n", where, a->n_curves, b->n_curves);
        return 0;
    }
    for (int i = 0; i < a->n_curves; ++i)
        if (!same_curve(&a->curves[i], &b->curves[i], where)) return 0;
    return 1;
}

/* check_flags: closed/periodic flags survive IGES but not OBJ (which has no such fields). */
static int same_part(const sem_part *a, const sem_part *b, int check_flags, const char *where)
{
    const sem_surface *s = &a->surface, *t = &b->surface;
    if (s->degree_u != t->degree_u || s->degree_v != t->degree_v || s->n_u != t->n_u ||
        s->n_v != t->n_v) {
        fprintf(stderr, "%s: surface sizes differ\n", where);
        return 0;
    }
    size_t n = (size_t)s->n_u * (size_t)s->n_v;
    if (!same_doubles(s->knots_u, t->knots_u, (size_t)(s->n_u + s->degree_u + 1)) ||
        !same_doubles(s->knots_v, t->knots_v, (size_t)(s->n_v + s->degree_v + 1))) {
        fprintf(stderr, "%s: knots differ\n", where);
        return 0;
    }
    if (!same_doubles(s->ctrl, t->ctrl, 3 * n) || !same_doubles(s->weights, t->weights, n)) {
        fprintf(stderr, "%s: control points or weights differ\n", where);
        return 0;
    }
    double ra[4] = {s->u0, s->u1, s->v0, s->v1}, rb[4] = {t->u0, t->u1, t->v0, t->v1};
    if (!same_doubles(ra, rb, 4)) {
        fprintf(stderr, "%s: ranges differ\n", where);
        return 0;
    }
    if (check_flags && (s->closed_u != t->closed_u || s->closed_v != t->closed_v ||
                        s->periodic_u != t->periodic_u || s->periodic_v != t->periodic_v)) {
        fprintf(stderr, "%s: closed/periodic flags differ\n", where);
        return 0;
    }
    if (a->has_outer != b->has_outer || a->n_holes != b->n_holes) {
        fprintf(stderr, "%s: trims differ (outer %d/%d, holes %d/%d)\n", where, a->has_outer,
                b->has_outer, a->n_holes, b->n_holes);
        return 0;
    }
    if (a->has_outer && !same_loop(&a->outer, &b->outer, where)) return 0;
    for (int i = 0; i < a->n_holes; ++i)
        if (!same_loop(&a->holes[i], &b->holes[i], where)) return 0;
    return 1;
}

static int same_model(const sem_model *a, const sem_model *b, int check_flags, int check_names,
                      const char *where)
{
    if (a->n_parts != b->n_parts) {
        fprintf(stderr, "%s: %d vs %d parts\n", where, a->n_parts, b->n_parts);
        return 0;
    }
    if (strcasecmp(a->units, b->units) != 0 && !(a->unit_to_meter == b->unit_to_meter)) {
        fprintf(stderr, "%s: units %s vs %s\n", where, a->units, b->units);
        return 0;
    }
    for (int i = 0; i < a->n_parts; ++i) {
        char w[512];
        snprintf(w, sizeof w, "%s part %d", where, i);
        if (!same_part(&a->parts[i], &b->parts[i], check_flags, w)) return 0;
        if (check_names && strcmp(a->parts[i].name, b->parts[i].name) != 0) {
            fprintf(stderr, "%s: name '%s' vs '%s'\n", w, a->parts[i].name, b->parts[i].name);
            return 0;
        }
    }
    return 1;
}

/* ---- models built in code ---- */

static double awkward(int k)
{
    static const double values[] = {0.1, 1.0 / 3.0, -0.0, 1e-300, 2.0 / 7.0, M_PI, -1e300,
                                    123456789.123456789, 5e-324, -2.5, 1e17, 0.7};
    return values[k % (int)(sizeof values / sizeof values[0])];
}

static void set_line(sem_curve *c, double u0, double v0, double u1, double v1)
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

/* A rational circle of 9 points (degree 2), radius r around (cu, cv), parameter [a, b]. */
static void set_circle(sem_curve *c, double cu, double cv, double r, double a, double b)
{
    sem_curve_alloc(c, 2, 9);
    double k[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1};
    double px[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1}, py[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
    for (int i = 0; i < 12; ++i) c->knots[i] = a + (b - a) * k[i];
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = cu + r * px[i];
        c->ctrl[3 * i + 1] = cv + r * py[i];
        c->weights[i] = i % 2 ? sqrt(0.5) : 1.0;
    }
    c->t0 = a;
    c->t1 = b;
}

static sem_model *build_model(void)
{
    sem_model *m = sem_model_create();
    strcpy(m->units, "MM");
    m->unit_to_meter = 0.001;

    /* 1: untrimmed bicubic x biquadratic, non-uniform knots, weights != 1, range inside */
    sem_part p;
    memset(&p, 0, sizeof p);
    strcpy(p.name, "Free patch");
    sem_surface_alloc(&p.surface, 3, 2, 6, 4);
    double ku[10] = {-1, -1, -1, -1, 0.1, 1.0 / 3.0, 2, 2, 2, 2};
    double kv[7] = {0, 0, 0, 0.7, 5, 5, 5};
    memcpy(p.surface.knots_u, ku, sizeof ku);
    memcpy(p.surface.knots_v, kv, sizeof kv);
    for (int i = 0; i < 24; ++i) {
        p.surface.ctrl[3 * i] = (i % 6) + awkward(i);
        p.surface.ctrl[3 * i + 1] = (i / 6) * 0.1 + awkward(i + 3) * 1e-3;
        p.surface.ctrl[3 * i + 2] = awkward(i + 7);
        p.surface.weights[i] = 0.5 + 0.1 * i;
    }
    p.surface.u0 = -1;
    p.surface.u1 = 2;
    p.surface.v0 = 0.1;
    p.surface.v1 = 5;
    p.surface.closed_v = 1;
    sem_model_take_part(m, &p, NULL);

    /* 2: bilinear square [0,1]^2 trimmed by a 4-line outer loop and two holes: a circle
     * (one curve) and a half-disc (arc + line, two curves) */
    memset(&p, 0, sizeof p);
    strcpy(p.name, "Plate");
    p.color = 3;
    sem_surface_alloc(&p.surface, 1, 1, 2, 2);
    double k01[4] = {0, 0, 1, 1};
    memcpy(p.surface.knots_u, k01, sizeof k01);
    memcpy(p.surface.knots_v, k01, sizeof k01);
    double sq[12] = {0, 0, 0, 10, 0, 0, 0, 10, 0, 10, 10, 0.1};
    memcpy(p.surface.ctrl, sq, sizeof sq);
    p.surface.u1 = p.surface.v1 = 1;
    p.has_outer = 1;
    p.outer.n_curves = 4;
    p.outer.curves = calloc(4, sizeof(sem_curve));
    set_line(&p.outer.curves[0], 0.05, 0.05, 0.95, 0.05);
    set_line(&p.outer.curves[1], 0.95, 0.05, 0.95, 0.95);
    set_line(&p.outer.curves[2], 0.95, 0.95, 0.05, 0.95);
    set_line(&p.outer.curves[3], 0.05, 0.95, 0.05, 0.05);
    p.n_holes = 2;
    p.holes = calloc(2, sizeof(sem_trim_loop));
    p.holes[0].n_curves = 1;
    p.holes[0].curves = calloc(1, sizeof(sem_curve));
    set_circle(&p.holes[0].curves[0], 0.3, 0.3, 0.1, 0.0, 2.0 * M_PI);
    p.holes[1].n_curves = 2;
    p.holes[1].curves = calloc(2, sizeof(sem_curve));
    /* upper half of a circle: the first 5 points of a circle, then the diameter */
    set_circle(&p.holes[1].curves[0], 0.7, 0.7, 0.1, 0.0, 1.0);
    p.holes[1].curves[0].t1 = 0.5;
    set_line(&p.holes[1].curves[1], 0.6, 0.7, 0.8, 0.7);
    sem_model_take_part(m, &p, NULL);

    /* 3: only a hole (IGES 144 with N1 = 0), unnamed */
    memset(&p, 0, sizeof p);
    sem_surface_alloc(&p.surface, 2, 1, 3, 2);
    double kq[6] = {0, 0, 0, 1, 1, 1};
    memcpy(p.surface.knots_u, kq, sizeof kq);
    memcpy(p.surface.knots_v, k01, sizeof k01);
    for (int i = 0; i < 6; ++i) {
        p.surface.ctrl[3 * i] = (i % 3) * 0.5;
        p.surface.ctrl[3 * i + 1] = i / 3;
        p.surface.ctrl[3 * i + 2] = (i % 3 == 1) ? 0.25 : 0.0;
    }
    p.surface.weights[1] = p.surface.weights[4] = 0.9;
    p.surface.u1 = p.surface.v1 = 1;
    p.n_holes = 1;
    p.holes = calloc(1, sizeof(sem_trim_loop));
    p.holes[0].n_curves = 1;
    p.holes[0].curves = calloc(1, sizeof(sem_curve));
    set_circle(&p.holes[0].curves[0], 0.5, 0.5, 0.2, -1.0, 3.0);
    sem_model_take_part(m, &p, NULL);
    return m;
}

static void roundtrip_built_model(void)
{
    sem_model *m = build_model();
    sem_error err;
    CHECK(sem_surface_validate(&m->parts[0].surface, &err) == SEM_OK, "%s", err.message);
    char igs[512], obj[512], igs2[512];
    snprintf(igs, sizeof igs, "%s/built.igs", test_tmpdir());
    snprintf(obj, sizeof obj, "%s/built.obj", test_tmpdir());
    snprintf(igs2, sizeof igs2, "%s/built_again.IGES", test_tmpdir());

    sem_model *a = NULL, *b = NULL, *c = NULL;
    CHECK(sem_model_save(m, igs, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_model_load(igs, &a, &err) == SEM_OK, "%s", err.message);
    if (a) {
        CHECK(same_model(m, a, 1, 1, "built IGES"), "IGES round trip changed the model");
        CHECK(strcmp(a->units, "MM") == 0, "units %s", a->units);
        CHECK(a->unit_to_meter == 0.001, "unit_to_meter %g", a->unit_to_meter);
        CHECK(a->n_parts == 3 && a->parts[1].color == 3, "colour of the plate lost");
    }
    CHECK(sem_model_save(m, obj, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_model_load(obj, &b, &err) == SEM_OK, "%s", err.message);
    if (b) {
        CHECK(same_model(m, b, 0, 1, "built OBJ"), "OBJ round trip changed the model");
        CHECK(strcmp(b->units, "MM") == 0 && b->unit_to_meter == 0.001, "OBJ units %s %g",
              b->units, b->unit_to_meter);
        CHECK(sem_model_save(b, igs2, &err) == SEM_OK, "%s", err.message);
        CHECK(sem_model_load(igs2, &c, &err) == SEM_OK, "%s", err.message);
        if (c) CHECK(same_model(m, c, 0, 1, "built OBJ->IGES"), "OBJ -> IGES changed the model");
    }
    sem_model_destroy(a);
    sem_model_destroy(b);
    sem_model_destroy(c);
    sem_model_destroy(m);
}

/* ---- the shared models ---- */

static int n_files, n_read, n_ok;

static void roundtrip_file(const char *path)
{
    sem_error err;
    sem_model *m = NULL;
    n_files++;
    if (sem_iges_read(path, &m, &err) != SEM_OK) {
        printf("  skip %s (the reader rejects it: %s)\n", path, err.message);
        return;
    }
    n_read++;
    char igs[512], obj[512], igs2[512];
    snprintf(igs, sizeof igs, "%s/rt.igs", test_tmpdir());
    snprintf(obj, sizeof obj, "%s/rt.obj", test_tmpdir());
    snprintf(igs2, sizeof igs2, "%s/rt2.igs", test_tmpdir());
    sem_model *a = NULL, *b = NULL, *c = NULL;
    int ok = 1;
    sem_status st = sem_iges_write(m, igs, &err);
    CHECK(st == SEM_OK, "%s: write IGES: %s", path, err.message);
    ok &= st == SEM_OK;
    if (st == SEM_OK) {
        st = sem_iges_read(igs, &a, &err);
        CHECK(st == SEM_OK, "%s: read written IGES: %s", path, err.message);
        ok &= st == SEM_OK && same_model(m, a, 1, 1, path);
    }
    st = sem_obj_write(m, obj, &err);
    CHECK(st == SEM_OK, "%s: write OBJ: %s", path, err.message);
    ok &= st == SEM_OK;
    if (st == SEM_OK) {
        st = sem_obj_read(obj, &b, &err);
        CHECK(st == SEM_OK, "%s: read written OBJ: %s", path, err.message);
        ok &= st == SEM_OK && same_model(m, b, 0, 1, path);
        if (st == SEM_OK) {
            st = sem_iges_write(b, igs2, &err);
            if (st == SEM_OK) st = sem_iges_read(igs2, &c, &err);
            CHECK(st == SEM_OK, "%s: IGES -> OBJ -> IGES: %s", path, err.message);
            ok &= st == SEM_OK && same_model(m, c, 0, 1, path);
        }
    }
    CHECK(ok, "%s: round trip changed the model", path);
    n_ok += ok;
    sem_model_destroy(a);
    sem_model_destroy(b);
    sem_model_destroy(c);
    sem_model_destroy(m);
}

static int has_iges_extension(const char *name)
{
    const char *dot = strrchr(name, '.');
    return dot && (strcasecmp(dot, ".igs") == 0 || strcasecmp(dot, ".iges") == 0);
}

static int compare_names(const void *a, const void *b)
{
    return strcmp(*(char *const *)a, *(char *const *)b);
}

static void walk(const char *dir, int depth)
{
    if (depth > 8) return;
    DIR *d = opendir(dir);
    if (!d) return;
    char **names = NULL;
    size_t n = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        if (e->d_name[0] == '.') continue;
        char **t = realloc(names, (n + 1) * sizeof *t);
        if (!t) break;
        names = t;
        names[n] = malloc(strlen(dir) + strlen(e->d_name) + 2);
        sprintf(names[n], "%s/%s", dir, e->d_name);
        n++;
    }
    closedir(d);
    qsort(names, n, sizeof *names, compare_names);
    for (size_t i = 0; i < n; ++i) {
        struct stat st;
        if (stat(names[i], &st) == 0) {
            if (S_ISDIR(st.st_mode)) walk(names[i], depth + 1);
            else if (S_ISREG(st.st_mode) && has_iges_extension(names[i])) roundtrip_file(names[i]);
        }
        free(names[i]);
    }
    free(names);
}

int main(void)
{
    roundtrip_built_model();
    const char *root = test_shared_model("");
    if (root) {
        char dir[4096];
        snprintf(dir, sizeof dir, "%s", root);
        walk(dir, 0);
        printf("shared models: %d IGES files, %d read, %d round-tripped exactly\n", n_files,
               n_read, n_ok);
        CHECK(n_files > 0, "no IGES files under %s", dir);
        CHECK(n_read > 0, "the reader read none of the shared models");
    } else {
        printf("shared models absent: skipping the file loop\n");
    }
    return test_finish("test_roundtrip");
}
