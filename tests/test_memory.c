/*
 * test_memory.c - memory is reported and estimated (docs/simulation.md, "Memory").
 *
 *  - sem_world_estimate_memory: every term positive on a beam, the total their sum as
 *    documented, the blocks term exactly 216 bytes per block entry of a model whose one
 *    group couples everything (a box), refused arguments;
 *  - `sem run`: summary.json has a plausible peak_memory_bytes (1 MB .. 24 GB) and the
 *    estimate made before the world was built is within a factor 2 of it on the coffee mug
 *    (Table 1; skipped without the shared models); the final line names the peak;
 *  - the warning: with SEM_MEMORY_AVAILABLE_MB=1 the run warns "this run needs about X GB
 *    and the machine has Y GB available" (and still runs); without it, no warning;
 *  - `sem bench --json`: every row has a plausible peak_memory_bytes.
 */
#include <cjson/cJSON.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/primitives.h"
#include "sem/simulation.h"
#include "test_util.h"

#define MB (1024.0 * 1024.0)
#define GB (1024.0 * MB)

static char out_buf[1 << 16], err_buf[1 << 16];


static double num(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(x) ? x->valuedouble : NAN;
}

static sem_discretization *preprocess(sem_model *m)
{
    sem_error err;
    sem_preprocess_options o = sem_default_preprocess_options();
    sem_discretization *d = NULL;
    CHECK(sem_preprocess(m, &o, &d, &err) == SEM_OK, "%s", err.message);
    return d;
}

static void test_estimate_terms(void)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 4;
    CHECK(sem_primitive_beam(m, &bd, &err) == SEM_OK, "%s", err.message);
    sem_discretization *d = preprocess(m);
    if (d) {
        sem_memory_estimate e;
        CHECK(sem_world_estimate_memory(d, &e, &err) == SEM_OK, "%s", err.message);
        CHECK(e.base > 0 && e.discretization > 0 && e.preprocessing > 0 && e.blocks > 0 &&
                  e.assembly > 0 && e.solver > 0,
              "terms %g %g %g %g %g %g", e.base, e.discretization, e.preprocessing, e.blocks,
              e.assembly, e.solver);
        double run = e.blocks + e.assembly + e.solver;
        CHECK_REL(e.total, e.base + e.discretization + (e.preprocessing > run ? e.preprocessing : run), 1e-12);
        CHECK(e.total > 10 * MB && e.total < 1 * GB, "a 4-section beam needs %g MB", e.total / MB);
        printf("beam (4 sections, %d dofs): estimate %.1f MB (blocks %.2f, assembly %.2f, solver "
               "%.2f, discretization %.2f)\n",
               3 * d->n_ctrl, e.total / MB, e.blocks / MB, e.assembly / MB, e.solver / MB,
               e.discretization / MB);
    }
    CHECK(sem_world_estimate_memory(NULL, NULL, &err) == SEM_ERR_INVALID, "NULL accepted");
    sem_discretization_destroy(d);
    sem_model_destroy(m);

    /* a box: its 6 faces share one origin, so there is one group pair of 6 x 9 = 54
     * control points (biquadratic faces) and the blocks hold 54^2 entries of 216 bytes */
    m = sem_model_create();
    sem_box_def xd = sem_default_box_def();
    CHECK(sem_primitive_box(m, &xd, &err) == SEM_OK, "%s", err.message);
    d = preprocess(m);
    if (d) {
        sem_memory_estimate e;
        CHECK(sem_world_estimate_memory(d, &e, &err) == SEM_OK, "%s", err.message);
        double n = d->n_ctrl;
        CHECK(d->n_origins == 1, "box has %d origins", d->n_origins);
        if (d->n_origins == 1) CHECK_REL(e.blocks, 216.0 * n * n, 1e-12);
    }
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

static void write_scene(const char *path, const char *model, const char *out_dir)
{
    FILE *f = fopen(path, "w");
    if (!f) return;
    fprintf(f,
            "{\"objects\": [{%s, \"material\": {\"type\": \"neohookean\", \"density\": 1000, "
            "\"youngs_modulus\": 1e6, \"poisson_ratio\": 0.45}}],\n"
            " \"gravity\": [0, 0, -9.81], \"integrator\": {\"type\": \"linearly_implicit_euler\", "
            "\"dt\": 0.01}, \"frames\": 1, \"output\": {\"dir\": \"%s\", \"usd\": false, \"glb\": false}}\n",
            model, out_dir);
    fclose(f);
}

/* The warning with a tiny "available" memory, and none without it. */
static void test_warning(void)
{
    const char *tmp = test_tmpdir();
    char scene[1024], out[1024], args[4096];
    snprintf(scene, sizeof scene, "%s/box_scene.json", tmp);
    snprintf(out, sizeof out, "%s/box_out", tmp);
    write_scene(scene, "\"primitive\": {\"type\": \"box\"}", out);
    snprintf(args, sizeof args, "run '%s' --overwrite --no-cache", scene);

    setenv("SEM_MEMORY_AVAILABLE_MB", "1", 1);
    int rc = test_run_cli(args, out_buf, sizeof out_buf, err_buf, sizeof err_buf);
    unsetenv("SEM_MEMORY_AVAILABLE_MB");
    CHECK(rc == 0, "run with 1 MB available: exit %d: %s", rc, err_buf);
    const char *w = strstr(err_buf, "sem: warning: this run needs about ");
    CHECK(w != NULL, "no memory warning: %s", err_buf);
    if (w) {
        double need = 0, have = 0;
        CHECK(sscanf(w, "sem: warning: this run needs about %lf GB and the machine has %lf GB", &need, &have) == 2,
              "warning not parsed: %.200s", w);
        CHECK(need > 0.01 && need < 2, "needs %g GB", need);
        CHECK_REL(have, 1.0 / 1024, 0.01);
        /* said before the run started: before the simulation's progress and final line */
        const char *final = strstr(err_buf, " steps, mean ");
        CHECK(final && w < final, "the warning comes after the run: %s", err_buf);
    }
    CHECK(strstr(err_buf, "peak memory ") != NULL, "final line without the peak: %s", err_buf);

    rc = test_run_cli(args, out_buf, sizeof out_buf, err_buf, sizeof err_buf);
    CHECK(rc == 0, "run: exit %d: %s", rc, err_buf);
    CHECK(strstr(err_buf, "this run needs about") == NULL, "a box on this machine warns: %s", err_buf);
    cJSON *s = test_read_summary(out);
    CHECK(s != NULL, "no summary.json in %s", out);
    if (s) {
        double peak = num(s, "peak_memory_bytes"), est = num(s, "estimated_memory_bytes");
        CHECK(peak > 1 * MB && peak < 24 * GB, "peak_memory_bytes %g", peak);
        CHECK(est > 1 * MB && est < 24 * GB, "estimated_memory_bytes %g", est);
        cJSON_Delete(s);
    }
}

/* The estimate against the measured peak of a real run (Table 1's coffee mug, sem's
 * defaults): within a factor 2. */
static void test_estimate_vs_peak(void)
{
    const char *mug = test_shared_model("mugs/mug_trimmed_complex.iges");
    if (!mug) return;
    const char *tmp = test_tmpdir();
    char scene[1024], out[1024], model[1200], args[4096];
    snprintf(scene, sizeof scene, "%s/mug_scene.json", tmp);
    snprintf(out, sizeof out, "%s/mug_out", tmp);
    snprintf(model, sizeof model, "\"model\": \"%s\"", mug);
    write_scene(scene, model, out);
    snprintf(args, sizeof args, "run '%s' --overwrite --no-cache --quiet", scene);
    int rc = test_run_cli(args, out_buf, sizeof out_buf, err_buf, sizeof err_buf);
    CHECK(rc == 0, "mug run: exit %d: %s", rc, err_buf);
    cJSON *s = test_read_summary(out);
    CHECK(s != NULL, "no summary.json in %s", out);
    if (!s) return;
    double peak = num(s, "peak_memory_bytes"), est = num(s, "estimated_memory_bytes");
    printf("mug: peak %.1f MB, estimated %.1f MB (ratio %.2f)\n", peak / MB, est / MB, est / peak);
    CHECK(peak > 1 * MB && peak < 24 * GB, "peak_memory_bytes %g", peak);
    /* sanitizers' shadow memory and quarantine are not the program's */
    if (!getenv("SEM_SANITIZED")) CHECK(est > 0.5 * peak && est < 2 * peak, "estimate %g MB, peak %g MB", est / MB, peak / MB);
    cJSON_Delete(s);
}

/* sem bench --json: every row has a plausible peak. */
static void test_bench(void)
{
    const char *rocket = test_shared_model("rocket/rocket.iges");
    if (!rocket) return;
    char dir[1024], args[2048];
    snprintf(dir, sizeof dir, "%s", rocket);
    char *slash = strstr(dir, "/rocket/rocket.iges");
    if (slash) *slash = '\0';
    snprintf(args, sizeof args, "bench --models '%s' --only 'Rocket (stiff)' --json --steps 1 --repeat 1", dir);
    int rc = test_run_cli(args, out_buf, sizeof out_buf, err_buf, sizeof err_buf);
    CHECK(rc == 0, "bench: exit %d: %s", rc, err_buf);
    cJSON *j = cJSON_Parse(out_buf);
    CHECK(cJSON_IsArray(j) && cJSON_GetArraySize(j) == 1, "bench json: %.300s", out_buf);
    const cJSON *row;
    cJSON_ArrayForEach(row, j)
    {
        double peak = num(row, "peak_memory_bytes");
        printf("bench %s: peak %.1f MB\n", cJSON_GetObjectItem(row, "example")->valuestring, peak / MB);
        CHECK(peak > 1 * MB && peak < 24 * GB, "bench peak_memory_bytes %g", peak);
    }
    cJSON_Delete(j);
}

int main(void)
{
    test_estimate_terms();
    test_warning();
    test_estimate_vs_peak();
    test_bench();
    return test_finish("test_memory");
}
