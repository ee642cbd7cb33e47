/* test_run.c - `sem run` end to end with the built binary: output files, summary.json,
 * frames read back, the USD animation, the preprocessing cache, failures (a step that
 * explodes, bad scenes) and every example scene in examples/. */
#include <cjson/cJSON.h>
#include <dirent.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sem/model.h"
#include "sem/primitives.h"
#include "test_util.h"

static char g_out[65536], g_err[65536];
static int g_sanitized;

static int exists(const char *dir, const char *name)
{
    char p[1024];
    struct stat st;
    snprintf(p, sizeof p, "%s/%s", dir, name);
    return stat(p, &st) == 0 && st.st_size > 0;
}


static double num(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

static const char *str(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsString(x) ? x->valuestring : "";
}

/* Lines of s that start with "sem:" and the total number of lines. */
static int sem_lines(const char *s, int *lines)
{
    int n = 0, l = 0;
    for (const char *p = s; *p;) {
        const char *e = strchr(p, '\n');
        if (!strncmp(p, "sem:", 4)) n++;
        l++;
        if (!e) break;
        p = e + 1;
    }
    *lines = l;
    return n;
}

/* No temporary file of an atomic write is left behind. */
static int tmp_files(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d) return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        if (strstr(e->d_name, ".tmp")) n++;
    closedir(d);
    return n;
}

static double vec_n(const cJSON *o, const char *key, int k)
{
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(o, key);
    const cJSON *x = cJSON_IsArray(a) && cJSON_GetArraySize(a) == 3 ? cJSON_GetArrayItem(a, k) : NULL;
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

/* strict: every number finite. Otherwise (a failed run) an energy may be null: the elastic
 * energy of an inverted element is undefined (+inf, which JSON writes as null). */
static void check_summary_keys(const cJSON *s, int n_frames, int strict)
{
    static const char *const top[] = {"volume", "mass", "dofs", "steps", "mean_step_s", "max_step_s", NULL};
    for (int k = 0; top[k]; ++k) CHECK(isfinite(num(s, top[k])), "summary.%s missing", top[k]);
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(s, "frames");
    CHECK(cJSON_IsArray(frames) && cJSON_GetArraySize(frames) == n_frames, "summary.frames has %d entries, want %d",
          cJSON_IsArray(frames) ? cJSON_GetArraySize(frames) : -1, n_frames);
    static const char *const fk[] = {"time", "kinetic_energy", "elastic_energy", "gravity_energy", "error_energy",
                                     NULL};
    static const char *const fv[] = {"center_of_mass", "linear_momentum", "angular_momentum", NULL};
    int f = 0;
    for (const cJSON *it = frames ? frames->child : NULL; it; it = it->next, ++f) {
        for (int k = 0; fk[k]; ++k) {
            const cJSON *x = cJSON_GetObjectItemCaseSensitive(it, fk[k]);
            CHECK(isfinite(num(it, fk[k])) || (!strict && cJSON_IsNull(x)), "frames[%d].%s missing", f, fk[k]);
        }
        for (int k = 0; fv[k]; ++k)
            CHECK(isfinite(vec_n(it, fv[k], 0)) && isfinite(vec_n(it, fv[k], 2)), "frames[%d].%s missing", f, fv[k]);
    }
}

/* The default scene (embedded): files, summary values, frames read back, USD. */
static void test_default_scene(const char *tmp)
{
    char dir[512], args[1024];
    snprintf(dir, sizeof dir, "%s/default", tmp);
    snprintf(args, sizeof args, "run --frames 2 --out %s --json", dir);
    int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc == 0, "sem run (default) exit %d: %s", rc, g_err);
    CHECK(strstr(g_err, "embedded default scene") != NULL, "says the default scene is used: %s", g_err);
    /* --json prints the summary on stdout */
    cJSON *printed = cJSON_Parse(g_out);
    CHECK(printed != NULL, "stdout is JSON: %.200s", g_out);
    CHECK(printed && !strcmp(str(printed, "status"), "ok"), "printed status");
    cJSON_Delete(printed);
    static const char *const files[] = {"frame_0000.igs",      "frame_0001.igs",      "frame_0002.igs",
                                        "frame_0000_mesh.obj", "frame_0001_mesh.obj", "frame_0002_mesh.obj",
                                        "animation.usda",      "summary.json",        NULL};
    for (int k = 0; files[k]; ++k) CHECK(exists(dir, files[k]), "%s/%s missing", dir, files[k]);
    CHECK(!exists(dir, "frame_0003.igs"), "only 2 frames + the rest frame");
    CHECK(!exists(dir, "frame_0000_nurbs.obj"), "NURBS OBJ is off by default");
    CHECK(tmp_files(dir) == 0, "temporary files left in %s", dir);

    cJSON *s = test_read_summary(dir);
    CHECK(s != NULL, "summary.json parses");
    if (s) {
        check_summary_keys(s, 3, 1);
        CHECK(!strcmp(str(s, "status"), "ok"), "status %s", str(s, "status"));
        CHECK(cJSON_IsFalse(cJSON_GetObjectItemCaseSensitive(s, "preprocess_cached")), "first run preprocesses");
        /* beam 2 x 0.4 x 0.4 of density 1100; 18 biquadratic patches of 9 control points */
        /* the default cells take their lengths from Embree's single-precision ray hits */
        CHECK_REL(num(s, "volume"), 0.32, 1e-7);
        CHECK_REL(num(s, "mass"), 352.0, 1e-7);
        CHECK(num(s, "dofs") == 3 * 18 * 9, "dofs %g", num(s, "dofs"));
        CHECK(num(s, "steps") == 4, "steps %g", num(s, "steps"));
        CHECK(num(s, "max_step_s") >= num(s, "mean_step_s") && num(s, "mean_step_s") > 0, "step times");
        const cJSON *fr = cJSON_GetObjectItemCaseSensitive(s, "frames");
        for (int f = 0; f < 3 && fr; ++f) {
            const cJSON *x = cJSON_GetArrayItem(fr, f);
            CHECK_NEAR(num(x, "time"), 0.02 * f, 1e-12);
        }
        const cJSON *f0 = fr ? cJSON_GetArrayItem(fr, 0) : NULL, *f2 = fr ? cJSON_GetArrayItem(fr, 2) : NULL;
        if (f0 && f2) {
            /* at rest: no motion, no strain, centre of mass at the beam's centre, m g z */
            CHECK_NEAR(num(f0, "kinetic_energy"), 0, 0);
            CHECK_NEAR(num(f0, "elastic_energy"), 0, 1e-9);
            CHECK_NEAR(vec_n(f0, "center_of_mass", 0), 1.0, 1e-12);
            CHECK_NEAR(vec_n(f0, "center_of_mass", 1), 0.2, 1e-12);
            CHECK_NEAR(vec_n(f0, "center_of_mass", 2), 0.2, 1e-12);
            CHECK_REL(num(f0, "gravity_energy"), 352.0 * 9.81 * 0.2, 1e-7);
            /* falling under gravity: the centre of mass drops, energy turns kinetic and elastic,
             * and the total does not grow (implicit Euler dissipates) */
            CHECK(vec_n(f2, "center_of_mass", 2) < 0.2 - 1e-3, "com z %g", vec_n(f2, "center_of_mass", 2));
            CHECK(vec_n(f2, "linear_momentum", 2) < 0, "momentum z %g", vec_n(f2, "linear_momentum", 2));
            CHECK(num(f2, "kinetic_energy") > 0 && num(f2, "elastic_energy") > 0, "energies");
            double e0 = num(f0, "gravity_energy") + num(f0, "error_energy");
            double e2 = num(f2, "kinetic_energy") + num(f2, "elastic_energy") + num(f2, "gravity_energy") +
                        num(f2, "error_energy");
            CHECK(e2 <= e0 + 1e-9 * fabs(e0), "energy grew: %.10g -> %.10g", e0, e2);
        }
        cJSON_Delete(s);
    }

    /* the frames load back: same parts and control points as the generated beam; frame 0 is
     * the rest shape and the clamped end (x = 0) stays: its pin box holds the material there,
     * which the end face's control points follow through the error energy (Eq. 16): 3.3e-6 m
     * at frame 1 while the free end fell 3.0e-3 m (docs/simulation.md, "Pins") */
    sem_model *rest = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 4;
    bd.length = 2;
    bd.width = bd.height = 0.4;
    sem_error err;
    CHECK(rest && sem_primitive_beam(rest, &bd, &err) == SEM_OK, "beam");
    size_t n_rest = sem_model_control_points(rest);
    for (int f = 0; f < 3; ++f) {
        char path[1024];
        snprintf(path, sizeof path, "%s/frame_%04d.igs", dir, f);
        sem_model *m = NULL;
        CHECK(sem_iges_read(path, &m, &err) == SEM_OK, "%s: %s", path, err.message);
        if (!m) continue;
        CHECK(m->n_parts == rest->n_parts, "frame %d: %d parts", f, m->n_parts);
        CHECK(sem_model_control_points(m) == n_rest, "frame %d: %zu control points, want %zu", f,
              sem_model_control_points(m), n_rest);
        if (m->n_parts == rest->n_parts && sem_model_control_points(m) == n_rest) {
            double moved = 0, clamped = 0, max_dz = 0;
            for (int i = 0; i < m->n_parts; ++i) {
                const sem_surface *a = &m->parts[i].surface, *b = &rest->parts[i].surface;
                for (int c = 0; c < a->n_u * a->n_v; ++c)
                    for (int k = 0; k < 3; ++k) {
                        double d = fabs(a->ctrl[3 * c + k] - b->ctrl[3 * c + k]);
                        moved = fmax(moved, d);
                        if (b->ctrl[3 * c] == 0) clamped = fmax(clamped, d);
                        if (k == 2) max_dz = fmax(max_dz, b->ctrl[3 * c + 2] - a->ctrl[3 * c + 2]);
                    }
            }
            if (f == 0) CHECK(moved <= 1e-12, "frame 0 differs from the rest shape by %g", moved);
            if (f > 0) CHECK(max_dz > 1e-3, "frame %d: the free end did not fall (%g)", f, max_dz);
            CHECK(clamped <= 1e-2 * max_dz, "frame %d: the clamped end moved by %g (the free end %g)", f, clamped,
                  max_dz);
        }
        sem_model_destroy(m);
    }
    sem_model_destroy(rest);

    /* USD: header, one mesh, 3 time samples 0, 1, 2 */
    char path[1024];
    snprintf(path, sizeof path, "%s/animation.usda", dir);
    char *usd = test_slurp(path, NULL);
    CHECK(usd != NULL, "read %s", path);
    if (usd) {
        CHECK(!strncmp(usd, "#usda 1.0", 9), "USD header");
        CHECK(strstr(usd, "def Mesh \"object_0\"") != NULL, "mesh prim");
        const char *ts = strstr(usd, "points.timeSamples");
        CHECK(ts != NULL, "points.timeSamples");
        int samples = 0, in_order = 1;
        for (const char *p = ts; p && (p = strstr(p, "\n            ")); ++p) {
            int idx;
            if (sscanf(p + 13, "%d: [", &idx) == 1 && p[13] >= '0' && p[13] <= '9') {
                in_order &= idx == samples;
                samples++;
            }
        }
        CHECK(samples == 3 && in_order, "%d time samples (in order %d)", samples, in_order);
        CHECK(strstr(usd, "startTimeCode = 0") && strstr(usd, "endTimeCode = 2"), "time range");
        free(usd);
    }
}

/* The second run of the same scene loads the preprocessed data from $SEM_CACHE_DIR;
 * --no-cache preprocesses again. */
static void test_cache(const char *tmp)
{
    char args[1024];
    snprintf(args, sizeof args, "run --frames 0 --out %s/cache_run --quiet", tmp);
    int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc == 0, "cached run exit %d: %s", rc, g_err);
    char dir[512];
    snprintf(dir, sizeof dir, "%s/cache_run", tmp);
    cJSON *s = test_read_summary(dir);
    const cJSON *c = s ? cJSON_GetObjectItemCaseSensitive(s, "preprocess_cached") : NULL;
    CHECK(cJSON_IsTrue(c), "second run of the default scene reuses the cache");
    CHECK(s && num(s, "steps") == 0 && cJSON_GetArraySize(cJSON_GetObjectItemCaseSensitive(s, "frames")) == 1,
          "--frames 0 writes the rest frame only");
    cJSON_Delete(s);
    CHECK(exists(dir, "frame_0000.igs") && !exists(dir, "frame_0001.igs"), "rest frame only");
    /* the cache folder holds the discretization */
    char cache[600];
    snprintf(cache, sizeof cache, "%s/cache", tmp);
    DIR *d = opendir(cache);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)))
        if (strstr(e->d_name, ".semdisc")) n++;
    if (d) closedir(d);
    CHECK(n >= 1, "%d cache files in %s", n, cache);
    snprintf(args, sizeof args, "run --frames 0 --out %s/cache_run --quiet --no-cache --overwrite",
             tmp);
    rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc == 0, "--no-cache exit %d: %s", rc, g_err);
    s = test_read_summary(dir);
    c = s ? cJSON_GetObjectItemCaseSensitive(s, "preprocess_cached") : NULL;
    CHECK(cJSON_IsFalse(c), "--no-cache preprocesses");
    cJSON_Delete(s);
}

/* A step that fails: exit 1, one "sem:" error line, earlier frames kept, summary says failed. */
static void test_explode(const char *tmp)
{
    char dir[512], args[1024];
    snprintf(dir, sizeof dir, "%s/explode", tmp);
    snprintf(args, sizeof args, "run %s/scene_explode.json --out %s --quiet", SEM_TEST_DATA, dir);
    int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc == 1, "exploding scene exit %d", rc);
    /* one error line; before it, the trust checks of frame 1 may warn (the state is already
     * running away: seams open, elements inverted), each warning one "sem: warning:" line */
    int lines, n = sem_lines(g_err, &lines), warnings = 0;
    for (const char *p = strstr(g_err, "sem: warning:"); p; p = strstr(p + 1, "sem: warning:")) warnings++;
    CHECK(n == lines && n - warnings == 1, "one sem: error line on stderr, got %d lines, %d warnings: %s", lines,
          warnings, g_err);
    CHECK(strstr(g_err, "step 2") && strstr(g_err, dir), "message names the step and the folder: %s", g_err);
    CHECK(exists(dir, "frame_0000.igs") && exists(dir, "frame_0001.igs"), "frames before the failure kept");
    CHECK(!exists(dir, "frame_0002.igs"), "no frame after the failure");
    CHECK(exists(dir, "animation.usda"), "USD written with the frames done");
    CHECK(tmp_files(dir) == 0, "temporary files left in %s", dir);
    cJSON *s = test_read_summary(dir);
    CHECK(s != NULL, "summary.json written after the failure");
    if (s) {
        CHECK(!strcmp(str(s, "status"), "failed"), "status %s", str(s, "status"));
        CHECK(strstr(str(s, "error"), "step 2") != NULL, "error %s", str(s, "error"));
        CHECK(num(s, "steps") == 1, "steps done %g", num(s, "steps"));
        check_summary_keys(s, 2, 0);
        cJSON_Delete(s);
    }
    /* the frames on disk are whole */
    char path[1024];
    sem_model *m = NULL;
    sem_error err;
    snprintf(path, sizeof path, "%s/frame_0001.igs", dir);
    CHECK(sem_iges_read(path, &m, &err) == SEM_OK && m && m->n_parts == 10, "frame 1 loads: %s", err.message);
    sem_model_destroy(m);
}

/* Bad scenes: exit 1, exactly one line "sem: FILE: key: why", nothing written. */
static void test_bad_scenes(const char *tmp)
{
    static const struct {
        const char *file, *needle1, *needle2;
    } cases[] = {
        {"scene_bad_key.json", "objects[0].material: unknown key \"desnity\"", "allowed"},
        {"scene_bad_model.json", "objects[0].model", "scene_no_such_model.igs: cannot open"},
        {"scene_bad_pin.json", "objects[0].pin.box", "holds none of the model's material"},
        {"scene_bad_dt.json", "integrator.dt", "must be positive"},
        {"scene_bad_nu.json", "objects[0].material", "poisson_ratio"},
        {"scene_bad_json.json", "scene_bad_json.json:4:", "not valid JSON"},
        {"scene_does_not_exist.json", "scene_does_not_exist.json", "cannot open"},
    };
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        char dir[512], args[1024];
        snprintf(dir, sizeof dir, "%s/bad_%zu", tmp, k);
        snprintf(args, sizeof args, "run %s/%s --out %s --quiet", SEM_TEST_DATA, cases[k].file, dir);
        int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
        CHECK(rc == 1, "%s: exit %d", cases[k].file, rc);
        int lines, n = sem_lines(g_err, &lines);
        CHECK(n == 1 && lines == 1, "%s: want one sem: line, got: %s", cases[k].file, g_err);
        CHECK(!strncmp(g_err, "sem: ", 5) && strstr(g_err, cases[k].needle1) && strstr(g_err, cases[k].needle2),
              "%s: message \"%s\" lacks \"%s\" / \"%s\"", cases[k].file, g_err, cases[k].needle1, cases[k].needle2);
        struct stat st;
        CHECK(stat(dir, &st) != 0, "%s: nothing may be written for a bad scene", cases[k].file);
    }
    /* usage errors */
    int rc = test_run_cli("run --frames -3", g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc != 0 && rc != 1 && strstr(g_err, "--frames"), "usage error exit %d: %s", rc, g_err);
    rc = test_run_cli("run a.json b.json", g_out, sizeof g_out, g_err, sizeof g_err);
    CHECK(rc != 0 && rc != 1, "two scenes: exit %d", rc);
}

/* An output folder that cannot be written is refused before preprocessing: exit 1, one line
 * naming the folder and why, nothing preprocessed (the cache stays empty), nothing created.
 * A folder under a regular file fails for every user; a folder without write permission only
 * for one who is not root. */
static void test_unwritable_folder(const char *tmp)
{
    char file[512], cache[512], args[2048];
    snprintf(file, sizeof file, "%s/not_a_folder", tmp);
    FILE *f = fopen(file, "w");
    CHECK(f != NULL, "cannot create %s", file);
    if (f) fclose(f);
    snprintf(cache, sizeof cache, "%s/cache_unwritable", tmp);
    const char *saved = getenv("SEM_CACHE_DIR");
    char saved_cache[512];
    snprintf(saved_cache, sizeof saved_cache, "%s", saved ? saved : "");
    setenv("SEM_CACHE_DIR", cache, 1);
    char locked[512], below[600];
    snprintf(locked, sizeof locked, "%s/locked", tmp);
    mkdir(locked, 0555);
    chmod(locked, 0555);
    snprintf(below, sizeof below, "%s/out/x", locked);
    struct {
        char dir[640];
        const char *why;
        int run;
    } cases[] = {{"", "is not a folder", 1}, {"", "not_a_folder is not a folder", 1}, {"", "Permission denied", geteuid() != 0}};
    snprintf(cases[0].dir, sizeof cases[0].dir, "%s", file);
    snprintf(cases[1].dir, sizeof cases[1].dir, "%s/frames/a", file);
    snprintf(cases[2].dir, sizeof cases[2].dir, "%s", below);
    for (size_t k = 0; k < sizeof cases / sizeof cases[0]; ++k) {
        if (!cases[k].run) continue;
        snprintf(args, sizeof args, "run --frames 2 --out %s --quiet", cases[k].dir);
        int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
        int lines, n = sem_lines(g_err, &lines);
        CHECK(rc == 1 && n == 1 && lines == 1, "unwritable %s: exit %d, want one sem: line: %s", cases[k].dir,
              rc, g_err);
        CHECK(strstr(g_err, cases[k].dir) && strstr(g_err, cases[k].why), "message names %s and \"%s\": %s",
              cases[k].dir, cases[k].why, g_err);
        struct stat st;
        CHECK(stat(cache, &st) != 0, "%s: preprocessing ran (the cache %s was written) before the refusal",
              cases[k].dir, cache);
    }
    chmod(locked, 0755);
    if (saved_cache[0]) setenv("SEM_CACHE_DIR", saved_cache, 1);
}

/* The patch test example: every control point at A X + b, elastic energy of the uniform
 * stretch F = diag(1.1, 1, 1) with nu = 0: psi = mu/2 (I1 - 3) - mu ln J, mu = E/2. */
static void check_patch_test(const char *dir)
{
    sem_error err;
    sem_model *m0 = NULL, *m1 = NULL;
    char p[1024];
    snprintf(p, sizeof p, "%s/frame_0000.igs", dir);
    sem_iges_read(p, &m0, &err);
    snprintf(p, sizeof p, "%s/frame_0001.igs", dir);
    sem_iges_read(p, &m1, &err);
    CHECK(m0 && m1 && m0->n_parts == 6 && m1->n_parts == 6, "patch test frames");
    if (m0 && m1 && m0->n_parts == 6 && m1->n_parts == 6) {
        double worst = 0;
        for (int i = 0; i < 6; ++i) {
            const sem_surface *a = &m0->parts[i].surface, *b = &m1->parts[i].surface;
            for (int c = 0; c < a->n_u * a->n_v; ++c) {
                const double *X = a->ctrl + 3 * c, *x = b->ctrl + 3 * c;
                double want[3] = {1.1 * X[0] + 0.05, X[1], X[2]};
                for (int k = 0; k < 3; ++k) worst = fmax(worst, fabs(x[k] - want[k]));
            }
        }
        /* the boundary-consistency penalty leaves O(1/gamma) = 3e-5 with gamma = 1e10 */
        CHECK(worst < 1e-4, "patch test: control points miss A X + b by %g", worst);
    }
    sem_model_destroy(m0);
    sem_model_destroy(m1);
    cJSON *s = test_read_summary(dir);
    const cJSON *fr = s ? cJSON_GetObjectItemCaseSensitive(s, "frames") : NULL;
    const cJSON *last = fr ? cJSON_GetArrayItem(fr, cJSON_GetArraySize(fr) - 1) : NULL;
    double mu = 0.5e6, psi = 0.5 * mu * (1.21 - 1.0) - mu * log(1.1);
    CHECK(last != NULL, "patch test frames in summary");
    if (last) CHECK_REL(num(last, "elastic_energy"), psi * 1.0, 2e-3);
    cJSON_Delete(s);
}

/* Every example scene that needs no model file runs (2 frames) and writes a parseable
 * summary with status ok (the paper's contact scenes, which read ../shared/models, are run
 * by hand: docs/scenes.md). */
static void test_examples(const char *tmp)
{
    static const char *const examples[] = {"default_beam",  "twisting_beam", "bouncing_sphere",
                                           "patch_test",    "two_materials", "wind_castle",
                                           "box_drop",      "incline",       "spheres_collide", "torus_chain",
                                           NULL};
    for (int k = 0; examples[k]; ++k) {
        /* under sanitizers: one frame, and the slow implicit default scene only once above */
        if (g_sanitized && !strcmp(examples[k], "default_beam")) continue;
        char dir[512], args[1024];
        snprintf(dir, sizeof dir, "%s/ex_%s", tmp, examples[k]);
        snprintf(args, sizeof args, "run %s/../../examples/%s.json --frames %d --out %s --quiet", SEM_TEST_DATA,
                 examples[k], g_sanitized ? 1 : 2, dir);
        int rc = test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
        CHECK(rc == 0, "example %s: exit %d: %s", examples[k], rc, g_err);
        CHECK(g_err[0] == '\0', "example %s: --quiet run printed: %s", examples[k], g_err);
        cJSON *s = test_read_summary(dir);
        CHECK(s != NULL, "example %s: summary.json parses", examples[k]);
        if (s) {
            CHECK(!strcmp(str(s, "status"), "ok"), "example %s: status %s", examples[k], str(s, "status"));
            check_summary_keys(s, g_sanitized ? 2 : 3, 1);
            cJSON_Delete(s);
        }
        CHECK(tmp_files(dir) == 0, "example %s: temporary files left", examples[k]);
        if (!strcmp(examples[k], "patch_test")) check_patch_test(dir);
        if (!strcmp(examples[k], "bouncing_sphere")) {
            /* zero gravity, no pins: momentum is conserved (m v0 with v0 = (2, 0, 1)) */
            cJSON *j = test_read_summary(dir);
            const cJSON *fr = j ? cJSON_GetObjectItemCaseSensitive(j, "frames") : NULL;
            const cJSON *last = fr ? cJSON_GetArrayItem(fr, cJSON_GetArraySize(fr) - 1) : NULL;
            double m = j ? num(j, "mass") : NAN;
            CHECK(last != NULL, "sphere frames");
            if (last) {
                CHECK_REL(vec_n(last, "linear_momentum", 0), 2 * m, 1e-8);
                CHECK_NEAR(vec_n(last, "linear_momentum", 1), 0, 1e-8 * m);
                CHECK_REL(vec_n(last, "linear_momentum", 2), 1 * m, 1e-8);
            }
            cJSON_Delete(j);
        }
    }
}

int main(void)
{
    g_sanitized = getenv("SEM_SANITIZED") != NULL;
    const char *tmp = test_tmpdir();
    /* never touch the user's cache: every run below uses a fresh cache folder */
    char cache[512];
    snprintf(cache, sizeof cache, "%s/cache", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    test_bad_scenes(tmp);
    test_unwritable_folder(tmp);
    test_default_scene(tmp);
    test_cache(tmp);
    test_explode(tmp);
    test_examples(tmp);
    return test_finish("test_run");
}
