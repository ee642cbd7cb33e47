/* test_seams.c - the seam monitor and the trust checks of a state (issue 27, item 4).
 *
 * - Seams are found where faces meet: on an exact NURBS box every edge of every face pairs
 *   with its neighbour, none opens at rest, and an affine motion of the whole model (which
 *   every seam follows) opens none (below 1e-12 of the size).
 * - A face moved off its neighbours by d opens its seams by exactly d, and the two faces
 *   are named; a face slid along its own plane by d opens them by d too (the material
 *   points of the two faces no longer coincide).
 * - The checks of a world's state (sem_world_object_checks): at rest nothing is suspect;
 *   the control points scaled by s about the centre give volume_change = s^3 - 1 (an affine
 *   motion: det F = s^3 at every quadrature point), reported, not suspect; mirrored, det F = -1
 *   and the inverted flag; one face moved out by 5 % of the size gives the seam flag and an
 *   error energy that dominates (the polynomials no longer follow the surface).
 * - Welds (sem_object_def.weld): the 10-section cantilever's faces, whose edges share control
 *   points, stay together under its static load, and its deflection hardly changes (88.76 %
 *   of FEM against 89.21 %).
 * - sem run marks such a run "suspect" (a pinned face prescribed away from its neighbours,
 *   welds off), warns once naming the parts and the frame, and with --strict fails (exit 1,
 *   frames kept); with welds (sem.weld true) the same face drags its neighbours' edges along
 *   and no seam opens (0.18 % of the size against 14 % without welds).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <cjson/cJSON.h>

#include "sem/measure.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/simulation.h"
#include "test_util.h"

static sem_model *make_box(int degree)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_box_def def = sem_default_box_def();
    def.size[0] = 2;
    def.size[1] = 1;
    def.size[2] = 0.5;
    def.degree = degree;
    if (sem_primitive_box(m, &def, &err) != SEM_OK) {
        CHECK(0, "box: %s", err.message);
        sem_model_destroy(m);
        return NULL;
    }
    return m;
}

static void test_box_seams(void)
{
    sem_model *m = make_box(3);
    if (!m) return;
    sem_seams s;
    sem_error err;
    CHECK(sem_seams_build(m, SEM_SEAM_TOLERANCE, &s, &err) == SEM_OK, "%s", err.message);
    double size = sqrt(2 * 2 + 1 + 0.25);
    CHECK_REL(s.size, size, 1e-9);
    /* every face pairs with its four neighbours, none with the face opposite */
    int touch[6][6] = {{0}};
    for (int k = 0; k < s.n_pairs; ++k) touch[s.part[2 * k]][s.part[2 * k + 1]] = 1;
    for (int a = 0; a < 6; ++a)
        for (int b = 0; b < 6; ++b) {
            int opposite = a / 2 == b / 2; /* box_xmin, box_xmax, box_ymin, ... */
            CHECK(touch[a][b] == (a != b && !opposite), "faces %d and %d: paired %d", a, b, touch[a][b]);
        }
    size_t nc = sem_model_control_points(m);
    double *q = malloc(3 * nc * sizeof *q), *q0 = malloc(3 * nc * sizeof *q0);
    sem_model_get_q(m, q0);
    sem_seam_gap g;
    sem_seams_measure(&s, q0, &g);
    CHECK(g.gap < 1e-12 * size, "gap at rest %g", g.gap);
    /* rigid: a rotation about (1, 2, 3) by 0.7 rad and a shift; then the same with a stretch
     * of 1.3 along x. Pairs of points that coincide at rest stay together; pairs a CAD gap
     * (or a corner) apart at rest change their distance by at most the stretch x that gap. */
    double A[9], c = cos(0.7), sn = sin(0.7), n[3] = {1, 2, 3}, nn = sqrt(14.0), max_rest = 0;
    for (int k = 0; k < 3; ++k) n[k] /= nn;
    for (int k = 0; k < s.n_pairs; ++k)
        if (s.rest_distance[k] > max_rest) max_rest = s.rest_distance[k];
    CHECK(max_rest <= s.tolerance, "rest distance %g above the tolerance %g", max_rest, s.tolerance);
    for (int stretch = 0; stretch < 2; ++stretch) {
        for (int i = 0; i < 3; ++i)
            for (int j = 0; j < 3; ++j) {
                double e = (i == j ? c : 0) + (1 - c) * n[i] * n[j];
                if ((i + 1) % 3 == j) e -= sn * n[3 - i - j];
                if ((j + 1) % 3 == i) e += sn * n[3 - i - j];
                A[3 * i + j] = e * (stretch && j == 0 ? 1.3 : 1.0);
            }
        for (size_t p = 0; p < nc; ++p)
            for (int i = 0; i < 3; ++i)
                q[3 * p + i] = A[3 * i] * q0[3 * p] + A[3 * i + 1] * q0[3 * p + 1] + A[3 * i + 2] * q0[3 * p + 2] + 5.0 * i;
        sem_seams_measure(&s, q, &g);
        if (stretch)
            CHECK(g.gap <= 0.3 * max_rest + 1e-12 * size, "stretch opened a seam by %g (rest gaps up to %g)", g.gap, max_rest);
        else
            CHECK(g.gap < 1e-12 * size, "rigid motion opened a seam by %g", g.gap);
    }
    /* face 5 (box_zmax) moved up by d: its seams open by d */
    size_t off[7];
    sem_model_part_offsets(m, off);
    double d = 0.013;
    memcpy(q, q0, 3 * nc * sizeof *q);
    for (size_t p = off[5]; p < off[6]; ++p) q[3 * p + 2] += d;
    sem_seams_measure(&s, q, &g);
    CHECK_REL(g.gap, d, 1e-9);
    CHECK_REL(g.relative, d / size, 1e-9);
    CHECK(g.part_a == 5 || g.part_b == 5, "parts %d %d", g.part_a, g.part_b);
    CHECK(fabs(g.X[2] - (0.25 + d / 2)) < 1e-9, "where: z %g", g.X[2]);
    /* slid along its own plane by d: the same material points, d apart */
    memcpy(q, q0, 3 * nc * sizeof *q);
    for (size_t p = off[5]; p < off[6]; ++p) q[3 * p] += d;
    sem_seams_measure(&s, q, &g);
    CHECK_REL(g.gap, d, 1e-9);
    free(q);
    free(q0);
    sem_seams_free(&s);
    sem_model_destroy(m);
}

/* A world of one box (degree 2: the quadratic polynomials reproduce it), at rest, with seam
 * ties of stiffness ties (0: none) and its top face (part 5) raised by gap at rest. */
static int make_world_ties(test_setup *t, double ties, double gap)
{
    memset(t, 0, sizeof *t);
    sem_error err;
    t->model = make_box(2);
    if (!t->model) return 0;
    if (gap != 0) {
        sem_surface *top = &t->model->parts[5].surface;
        for (int c = 0; c < top->n_u * top->n_v; ++c) top->ctrl[3 * (size_t)c + 2] += gap;
    }
    sem_preprocess_options po = sem_default_preprocess_options();
    if (sem_preprocess(t->model, &po, &t->disc, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        return 0;
    }
    sem_world_def wd = sem_default_world_def();
    if (gap != 0) wd.gravity[2] = 0;
    t->world = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = t->model;
    od.disc = t->disc;
    od.seam_ties = ties;
    if (!t->world || sem_world_add_object(t->world, &od, &err) < 0) {
        CHECK(0, "world: %s", err.message);
        return 0;
    }
    return 1;
}

static int make_world(test_setup *t)
{
    return make_world_ties(t, 0, 0);
}

static void test_world_checks(void)
{
    test_setup t;
    if (!make_world(&t)) {
        test_setup_free(&t);
        return;
    }
    sem_error err;
    sem_object_checks c;
    CHECK(sem_world_object_checks(t.world, 0, &c, &err) == SEM_OK, "%s", err.message);
    CHECK(c.suspect == 0, "at rest: suspect %d", c.suspect);
    CHECK(c.seam_pairs > 100, "seam pairs %d", c.seam_pairs);
    CHECK(fabs(c.volume_change) < 1e-9, "volume change at rest %g", c.volume_change);
    CHECK(c.error_share == 0, "error share at rest %g", c.error_share);
    int n = sem_world_object_dofs(t.world, 0);
    double *q = malloc((size_t)n * sizeof *q);
    memcpy(q, sem_world_object_q(t.world, 0), (size_t)n * sizeof *q);
    /* scaled by 1.1 about the origin (the box's centre): det F = 1.331 everywhere */
    double *qs = malloc((size_t)n * sizeof *qs);
    for (int i = 0; i < n; ++i) qs[i] = 1.1 * q[i];
    sem_world_object_set_state(t.world, 0, qs, NULL);
    CHECK(sem_world_object_checks(t.world, 0, &c, &err) == SEM_OK, "%s", err.message);
    CHECK_REL(c.volume_change, 1.331 - 1, 1e-9);
    CHECK_REL(c.min_det_f, 1.331, 1e-9);
    CHECK(c.suspect == 0, "scaled: suspect %d (a volume change alone is not)", c.suspect);
    CHECK(c.seam_gap_relative <= 0.1 * SEM_SEAM_TOLERANCE, "scaled: seams %g", c.seam_gap_relative);
    CHECK(c.error_share < 1e-12, "scaled: error share %g", c.error_share);
    /* mirrored through z = 0 (x, y, -z): det F = -1 everywhere, turned inside out */
    for (int i = 0; i < n; ++i) qs[i] = i % 3 == 2 ? -q[i] : q[i];
    sem_world_object_set_state(t.world, 0, qs, NULL);
    CHECK(sem_world_object_checks(t.world, 0, &c, &err) == SEM_OK, "%s", err.message);
    CHECK_REL(c.min_det_f, -1.0, 1e-9);
    CHECK(c.suspect & SEM_SUSPECT_INVERTED, "mirrored: suspect %d", c.suspect);
    /* face 5 (box_zmax) out by 5 % of the size */
    size_t off[7];
    sem_model_part_offsets(t.model, off);
    double size = sqrt(2 * 2 + 1 + 0.25), d = 0.05 * size;
    memcpy(qs, q, (size_t)n * sizeof *qs);
    for (size_t p = off[5]; p < off[6]; ++p) qs[3 * p + 2] += d;
    sem_world_object_set_state(t.world, 0, qs, NULL);
    CHECK(sem_world_object_checks(t.world, 0, &c, &err) == SEM_OK, "%s", err.message);
    CHECK_REL(c.seam_gap_relative, 0.05, 1e-6);
    CHECK_REL(c.seam_gap, d, 1e-6);
    CHECK(c.seam_parts[0] == 5 || c.seam_parts[1] == 5, "parts %d %d", c.seam_parts[0], c.seam_parts[1]);
    CHECK(c.suspect & SEM_SUSPECT_SEAM, "face out: suspect %d", c.suspect);
    CHECK(c.error_share > SEM_ERROR_SHARE_LIMIT, "face out: error share %g", c.error_share);
    CHECK(sem_world_object_checks(t.world, 1, &c, &err) == SEM_ERR_INVALID, "object 1 of 1");
    free(q);
    free(qs);
    test_setup_free(&t);
}

static double error_energy_of(test_setup *t, const double *q)
{
    sem_world_object_set_state(t->world, 0, q, NULL);
    sem_object_stats st;
    sem_world_object_stats(t->world, 0, &st);
    return st.error_energy;
}

/* Seam ties (sem_object_def.seam_ties, k = 10) on the 2 x 1 x 0.5 box (E 1e6 by default):
 * - at rest and under an affine motion (rotation, stretch, shift) they store nothing (below
 *   1e-10 of E V x the motion's strain squared: round-off of the error matrix);
 * - the top face out by d: its four edges (length 6) open by d, seen from the face and from
 *   its neighbours, so the ties add k E (6 + 6) d^2 to the error energy (closed form; the
 *   walk's points stand for the boundary's length up to its corners, 2 %);
 * - a box whose top face stands 2e-4 of the size off its neighbours at rest (a CAD gap
 *   within the seam tolerance) keeps its gap: at rest it stores nothing and feels no force
 *   (a step without gravity leaves every control point where it was, to 1e-10 of the size). */
static void test_seam_ties(void)
{
    test_setup t0, t1;
    if (!make_world_ties(&t0, 0, 0) || !make_world_ties(&t1, 10, 0)) {
        test_setup_free(&t0);
        test_setup_free(&t1);
        return;
    }
    const double E = sem_default_material().youngs_modulus, V = 1.0, size = sqrt(2 * 2 + 1 + 0.25);
    int n = sem_world_object_dofs(t1.world, 0);
    double *q0 = malloc((size_t)n * sizeof *q0), *q = malloc((size_t)n * sizeof *q);
    memcpy(q0, sem_world_object_q(t1.world, 0), (size_t)n * sizeof *q0);
    CHECK(fabs(error_energy_of(&t1, q0)) < 1e-12 * E * V, "ties at rest: error energy %g", error_energy_of(&t1, q0));
    /* rotation about z by 0.4 rad, stretch 1.2 along x, shift (1, 2, 3): strain 0.2 */
    double c = cos(0.4), sn = sin(0.4);
    for (int p = 0; p < n / 3; ++p) {
        const double *x = q0 + 3 * p;
        q[3 * p + 0] = 1.2 * c * x[0] - sn * x[1] + 1;
        q[3 * p + 1] = 1.2 * sn * x[0] + c * x[1] + 2;
        q[3 * p + 2] = x[2] + 3;
    }
    double affine = error_energy_of(&t1, q);
    CHECK(fabs(affine) < 1e-10 * E * V * 0.04, "ties under an affine motion: error energy %g", affine);
    /* the top face out by d */
    size_t off[7];
    sem_model_part_offsets(t1.model, off);
    double d = 0.01;
    memcpy(q, q0, (size_t)n * sizeof *q);
    for (size_t p = off[5]; p < off[6]; ++p) q[3 * p + 2] += d;
    double with = error_energy_of(&t1, q), without = error_energy_of(&t0, q);
    printf("top face out by %g m: error energy %.6g J with seam ties, %.6g J without; ties' share %.6g J, "
           "closed form %.6g J\n",
           d, with, without, with - without, 10 * E * 12 * d * d);
    CHECK_REL(with - without, 10 * E * 12 * d * d, 0.02);
    free(q0);
    free(q);
    test_setup_free(&t0);
    test_setup_free(&t1);
    /* a rest gap */
    test_setup tg;
    double gap = 2e-4 * size;
    if (!make_world_ties(&tg, 10, gap)) {
        test_setup_free(&tg);
        return;
    }
    n = sem_world_object_dofs(tg.world, 0);
    q0 = malloc((size_t)n * sizeof *q0);
    memcpy(q0, sem_world_object_q(tg.world, 0), (size_t)n * sizeof *q0);
    sem_object_stats st;
    sem_world_object_stats(tg.world, 0, &st);
    CHECK(fabs(st.error_energy) < 1e-9 * 10 * E * 12 * gap * gap, "rest gap: error energy at rest %g", st.error_energy);
    sem_error err;
    double moved = 0;
    for (int k = 0; k < 3; ++k) CHECK(sem_world_step(tg.world, &err) == SEM_OK, "step: %s", err.message);
    const double *qs = sem_world_object_q(tg.world, 0);
    for (int i = 0; i < n; ++i) moved = fmax(moved, fabs(qs[i] - q0[i]));
    CHECK(moved < 1e-10 * size, "rest gap: a step moved a control point by %g", moved);
    free(q0);
    test_setup_free(&tg);
}

/* The 10-section cantilever (static, gravity, clamped at x = 0, defaults otherwise) with
 * and without welds: its sections' faces share their edges' control points, and welded they
 * stay together (measured: largest seam opening 9.7e-7 of the size, against 4.9e-4 without),
 * while the deflection hardly changes (88.76 % against 89.21 % of FEM). */
static void test_welded_beam(void)
{
    double tip[2] = {0, 0}, gap[2] = {0, 0};
    for (int weld = 0; weld < 2; ++weld) {
        sem_error err;
        test_setup t;
        memset(&t, 0, sizeof t);
        t.model = sem_model_create();
        sem_beam_def bd = sem_default_beam_def();
        bd.sections = 10;
        if (sem_primitive_beam(t.model, &bd, &err) != SEM_OK) {
            CHECK(0, "beam: %s", err.message);
            test_setup_free(&t);
            return;
        }
        size_t nc = sem_model_control_points(t.model);
        double *q0 = malloc(3 * nc * sizeof *q0);
        unsigned char *pin = calloc(nc, 1);
        sem_model_get_q(t.model, q0);
        for (size_t c = 0; c < nc; ++c) pin[c] = fabs(q0[3 * c]) < 1e-12;
        sem_preprocess_options po = sem_default_preprocess_options();
        sem_world_def wd = sem_default_world_def();
        wd.gravity[2] = -10;
        wd.integrator = SEM_STATIC;
        sem_object_def od = sem_default_object_def();
        od.pinned = pin;
        od.weld = weld;
        if (sem_preprocess(t.model, &po, &t.disc, &err) != SEM_OK || !(t.world = sem_world_create(&wd, &err))) {
            CHECK(0, "%s", err.message);
        } else {
            od.model = t.model;
            od.disc = t.disc;
            sem_object_checks c;
            if (sem_world_add_object(t.world, &od, &err) < 0 || sem_world_solve_static(t.world, &err) != SEM_OK ||
                sem_world_object_checks(t.world, 0, &c, &err) != SEM_OK) {
                CHECK(0, "welds %d: %s", weld, err.message);
            } else {
                const double *q = sem_world_object_q(t.world, 0);
                int n = 0;
                for (size_t k = 0; k < nc; ++k)
                    if (fabs(q0[3 * k] - 5) < 1e-12) tip[weld] -= q[3 * k + 2] - q0[3 * k + 2], n++;
                tip[weld] /= n;
                gap[weld] = c.seam_gap_relative;
            }
        }
        printf("b10 static, welds %s: tip %.5f m, largest seam opening %.3g of the size\n", weld ? "on " : "off", tip[weld],
               gap[weld]);
        free(q0);
        free(pin);
        test_setup_free(&t);
    }
    CHECK(gap[0] > 1e-4 && gap[1] < 1e-5, "seams: %g without welds, %g with", gap[0], gap[1]);
    CHECK(fabs(tip[1] / tip[0] - 1) < 0.01, "tip %g with welds, %g without", tip[1], tip[0]);
}

/* Writes the scene of test_run_status (welds on or off) into dir; returns its path. */
static const char *write_scene(const char *dir, const char *name, int weld, const char *out)
{
    static char scene[4096];
    snprintf(scene, sizeof scene, "%s/%s.json", dir, name);
    FILE *f = fopen(scene, "w");
    if (!f) {
        CHECK(0, "cannot write %s", scene);
        return NULL;
    }
    fprintf(f, "{\"objects\": [{\"primitive\": {\"type\": \"box\", \"size\": [2, 1, 0.5]},\n"
               "  \"material\": {\"density\": 1e6, \"youngs_modulus\": 1e3, \"poisson_ratio\": 0.45},\n"
               "  \"sem\": {\"weld\": %s},\n"
               "  \"prescribe\": [{\"pin\": {\"parts\": [5]}, \"affine\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0.2]]}]}],\n"
               " \"gravity\": [0, 0, 0], \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01},\n"
               " \"frames\": 3, \"output\": {\"dir\": \"%s\"}}\n",
            weld ? "true" : "false", out);
    fclose(f);
    return scene;
}

/* sem run of a box whose top face is pinned and prescribed 20 cm up at once, the body too
 * heavy and soft (rho 1e6, E 1e3) to follow within a few steps. Without welds the face comes
 * off: suspect, warned, and --strict fails with the frames kept. With welds (the default)
 * the face's edges hold its neighbours' edges: the seams stay shut, but the neighbours are
 * stretched far from their polynomials, which the error energy's share shows. */
static void test_run_status(void)
{
    const char *dir = test_tmpdir();
    char out[4096], args[9000], errbuf[8192], path[4200];
    snprintf(out, sizeof out, "%s/seam_out", dir);
    const char *scene = write_scene(dir, "seam_scene", 0, out);
    if (!scene) return;
    snprintf(args, sizeof args, "run %s --overwrite --quiet", scene);
    int rc = test_run_cli(args, NULL, 0, errbuf, sizeof errbuf);
    CHECK(rc == 0, "sem run: exit %d: %s", rc, errbuf);
    CHECK(strstr(errbuf, "warning: object 0, frame 1: the seam between") != NULL && strstr(errbuf, "part 5 (box_zmax)"),
          "warning: %s", errbuf);
    snprintf(path, sizeof path, "%s/summary.json", out);
    char *summary = test_slurp(path, NULL);
    CHECK(summary && strstr(summary, "\"status\":\t\"suspect\""), "summary status");
    CHECK(summary && strstr(summary, "\"seam_gap_max\""), "summary checks");
    free(summary);
    snprintf(args, sizeof args, "run %s --overwrite --quiet --strict", scene);
    rc = test_run_cli(args, NULL, 0, errbuf, sizeof errbuf);
    CHECK(rc == 1, "sem run --strict: exit %d", rc);
    CHECK(strstr(errbuf, "--strict: object 0, frame 1: the seam between") != NULL, "strict error: %s", errbuf);
    snprintf(path, sizeof path, "%s/frame_0001.igs", out);
    FILE *kept = fopen(path, "r");
    CHECK(kept != NULL, "frame 1 kept after --strict");
    if (kept) fclose(kept);
    snprintf(path, sizeof path, "%s/frame_0002.igs", out);
    kept = fopen(path, "r");
    CHECK(kept == NULL, "no frame after the suspect one under --strict");
    if (kept) fclose(kept);
    snprintf(path, sizeof path, "%s/summary.json", out);
    summary = test_slurp(path, NULL);
    CHECK(summary && strstr(summary, "\"status\":\t\"failed\""), "strict summary status");
    free(summary);
    /* welded (sem.weld true): no seam opens, the error energy's share tells */
    scene = write_scene(dir, "seam_scene_weld", 1, out);
    if (!scene) return;
    snprintf(args, sizeof args, "run %s --overwrite --quiet", scene);
    rc = test_run_cli(args, NULL, 0, errbuf, sizeof errbuf);
    CHECK(rc == 0, "sem run (welds): exit %d: %s", rc, errbuf);
    CHECK(strstr(errbuf, "the seam between") == NULL, "welds: a seam opened: %s", errbuf);
    CHECK(strstr(errbuf, "frame 1: the error energy (Eq. 16) is") != NULL, "welds: %s", errbuf);
    summary = test_slurp(path, NULL);
    cJSON *s = summary ? cJSON_Parse(summary) : NULL;
    free(summary);
    const cJSON *checks = cJSON_GetObjectItemCaseSensitive(s, "checks");
    const cJSON *gap = cJSON_GetObjectItemCaseSensitive(checks, "seam_gap_max");
    /* measured 0.18 % (14 % without welds): the ties give a little under this load */
    CHECK(cJSON_IsNumber(gap) && gap->valuedouble < 0.3 * SEM_SEAM_GAP_LIMIT, "welded seams opened by %g",
          cJSON_IsNumber(gap) ? gap->valuedouble : -1);
    cJSON_Delete(s);
}

int main(void)
{
    test_box_seams();
    test_world_checks();
    test_seam_ties();
    test_welded_beam();
    test_run_status();
    return test_finish("test_seams");
}
