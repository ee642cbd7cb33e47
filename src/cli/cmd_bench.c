/*
 * cmd_bench.c - `sem bench [--json] [--models DIR] [--steps N] [--solver S] [--only TEXT]`: the paper's
 * Table 1 on the shared models, beside the paper's figures (MATLAB + C++ MEX on a 2.3 GHz
 * i5 laptop) with the speed-up paper / ours per column.
 *
 * Each row uses the paper's material and order and the authors' ray settings (models
 * README; table in src/bench/validation.c). Columns: dofs; the preprocessing phases of
 * sem_preprocess (sample, quad, weights, build Pi), each the fastest of `--repeat` runs
 * (default 5: phases of a few milliseconds vary by 2-10x on a busy 2-core machine, and the
 * fastest run is the one least disturbed), with the Embree scene build that quadrature and
 * weights share reported beside them as scene_s (the paper's table has no such column);
 * step = mean wall time of `--steps`
 * linearly implicit Euler steps (gravity 9.8 m/s^2 along -z, dt 0.01, no collision), after
 * one untimed warm-up step that does the one-off work (solver choice, symbolic analysis);
 * factor = mean time of the one factorization inside those steps
 * (sem_world_last_factor_seconds); Nnz% of the q-space system matrix; the process's peak
 * resident memory after the row (getrusage: the rows share one process, so a row's figure
 * is the largest of the rows so far).
 *
 * Rows whose file is missing are skipped (with a warning). Progress goes to stderr.
 * Exit status: 0 when every available row ran; 1 when one failed or none was found.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench/validation.h"
#include "cli.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/simulation.h"

#define CMD "bench"

typedef struct bench_result {
    int dofs;
    sem_preprocess_timings pre; /* the fastest run of each phase */
    double step_s, factor_s, nnz_percent;
    const char *solver;
} bench_result;

/* defaults: sem's default settings (object-frame quadrature, coupled origins, volume
 * consistency) instead of the authors' (the file's numbers are read as metres either way). */
static sem_status run_row(const sem_table1_row *r, const char *path, int steps, int repeat,
                          sem_solver_choice solver, int defaults,
                          bench_result *out, sem_error *err)
{
    sem_model *m = NULL;
    sem_status st = sem_model_load(path, &m, err);
    if (st != SEM_OK) return st;
    sem_preprocess_options po = sem_table1_options(r);
    if (defaults) {
        po = sem_default_preprocess_options();
        po.youngs_modulus = r->youngs_modulus;
    }
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -9.8;
    wd.dt = 0.01;
    wd.integrator = SEM_LINEARLY_IMPLICIT_EULER;
    wd.solver = solver;
    /* the q-space operators only for the solvers that use them */
    po.q_space_operators =
        !sem_world_def_structured(&wd, sem_model_control_points(m), m->n_parts, po.order == 1 ? 4 : 10,
                                  sem_preprocess_shared_fit(m, &po));
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    for (int k = 0; k < repeat; ++k) {
        sem_discretization_destroy(d);
        d = NULL;
        st = sem_preprocess(m, &po, &d, err);
        if (st != SEM_OK) goto done;
        if (k == 0) out->pre = d->timings;
        else sem_timings_keep_fastest(&out->pre, &d->timings);
    }
    out->dofs = 3 * d->n_ctrl;

    w = sem_world_create(&wd, err);
    if (!w) {
        st = err->status != SEM_OK ? err->status : SEM_ERR_INVALID;
        goto done;
    }
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.blend = defaults ? SEM_DEFAULT_BLEND : 0; /* 0: the authors' discretization */
    od.seams = defaults ? SEM_SEAMS_GEOMETRIC : SEM_SEAMS_PAPER;
    od.material.density = r->density;
    od.material.youngs_modulus = r->youngs_modulus;
    od.material.poisson_ratio = r->poisson_ratio;
    sem_material inner = od.material;
    int *part_material = NULL;
    if (r->inner_parts > 0) {
        part_material = malloc((size_t)m->n_parts * sizeof *part_material);
        if (!part_material) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto done;
        }
        for (int p = 0; p < m->n_parts; ++p) part_material[p] = p < r->inner_parts ? 0 : -1;
        inner.density = r->inner_density;
        inner.youngs_modulus = r->inner_youngs_modulus;
        inner.poisson_ratio = r->inner_poisson_ratio;
        od.part_material = part_material;
        od.part_materials = &inner;
        od.n_part_materials = 1;
    }
    int added = sem_world_add_object(w, &od, err);
    free(part_material);
    if (added < 0) {
        st = err->status != SEM_OK ? err->status : SEM_ERR_INVALID;
        goto done;
    }
    st = sem_world_step(w, err); /* warm-up */
    double ts = 0, tf = 0;
    for (int s = 0; s < steps && st == SEM_OK; ++s) {
        st = sem_world_step(w, err);
        ts += sem_world_last_step_seconds(w);
        tf += sem_world_last_factor_seconds(w);
    }
    if (st != SEM_OK) goto done;
    out->step_s = ts / steps;
    out->factor_s = tf / steps;
    out->nnz_percent = sem_world_object_nnz_percent(w, 0);
    out->solver = sem_world_solver_name(w, 0);
done:
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    return st;
}

static void print_cell(double ours, double paper)
{
    printf(" %8.2e %8.2e %6.1fx |", ours, paper, paper / ours);
}

int cmd_bench(int argc, char **argv)
{
    int json = 0, steps = 20, repeat = 5, defaults = 0;
    sem_solver_choice solver = SEM_SOLVER_AUTO;
    const char *dir = NULL, *only = NULL;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--json") == 0) json = 1;
        else if (strcmp(argv[i], "--defaults") == 0) defaults = 1;
        else if (strcmp(argv[i], "--models") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1)) return CLI_USAGE;
            dir = argv[++i];
        } else if (strcmp(argv[i], "--only") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1)) return CLI_USAGE;
            only = argv[++i];
        } else if (strcmp(argv[i], "--steps") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1)) return CLI_USAGE;
            int rc = cli_parse_int(CMD, "--steps", argv[++i], &steps);
            if (rc) return rc;
            if (steps < 1 || steps > 100000) return cli_fail("--steps must be in [1, 100000] (got %d)", steps);
        } else if (strcmp(argv[i], "--repeat") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1)) return CLI_USAGE;
            int rc = cli_parse_int(CMD, "--repeat", argv[++i], &repeat);
            if (rc) return rc;
            if (repeat < 1 || repeat > 1000) return cli_fail("--repeat must be in [1, 1000] (got %d)", repeat);
        } else if (strcmp(argv[i], "--solver") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1)) return CLI_USAGE;
            const char *v = argv[++i];
            if (strcmp(v, "auto") == 0) solver = SEM_SOLVER_AUTO;
            else if (strcmp(v, "sparse") == 0) solver = SEM_SOLVER_SPARSE;
            else if (strcmp(v, "dense") == 0) solver = SEM_SOLVER_DENSE;
            else if (strcmp(v, "structured") == 0) solver = SEM_SOLVER_STRUCTURED;
            else return cli_usage(CMD, "--solver must be auto, sparse or dense (got '%s')", v);
        } else if (argv[i][0] == '-') return cli_usage(CMD, "unknown option '%s'", argv[i]);
        else return cli_usage(CMD, "unexpected argument '%s'", argv[i]);
    }
    if (!dir) dir = sem_bench_models_dir();
    if (!dir) return cli_fail("no models folder: pass --models DIR or set SEM_SHARED_MODELS");
    if (!sem_bench_is_dir(dir)) return cli_fail("%s: not a folder", dir);

    cJSON *list = json ? cJSON_CreateArray() : NULL;
    if (json && !list) return cli_fail("out of memory");
    if (!json) {
        printf("Table 1: ours / paper (s) and speed-up paper / ours; %d threads; preprocessing phases "
               "the fastest of %d runs, step the mean of %d steps\n",
               omp_get_max_threads(), repeat, steps);
        printf("%-19s %5s %5s | %-25s | %-25s | %-25s | %-25s | %-25s | %8s | %6s %6s | %8s | %7s\n", "example",
               "dofs", "paper", "sample", "quad", "weights", "build Pi", "step", "factor", "Nnz%",
               "paper", "scene", "peak MB");
    }
    /* Warm-up: the first preprocessing of a process pays one-off costs (Embree device,
     * thread pools, page faults) that belong to no row, and the first row used to run
     * slower than its repeats later in the process; a generated box preprocessed for about
     * a tenth of a second takes them. */
    {
        sem_error werr;
        sem_model *box = sem_model_create();
        sem_box_def bd = sem_default_box_def();
        sem_preprocess_options wo = sem_default_preprocess_options();
        wo.rays[0] = wo.rays[1] = 8;
        if (box && sem_primitive_box(box, &bd, &werr) == SEM_OK) {
            double t0 = omp_get_wtime();
            for (int k = 0; k < 50 && omp_get_wtime() - t0 < 0.1; ++k) {
                sem_discretization *wd = NULL;
                if (sem_preprocess(box, &wo, &wd, &werr) != SEM_OK) break;
                sem_discretization_destroy(wd);
            }
        }
        sem_model_destroy(box);
    }
    int ran = 0, failed = 0;
    for (int k = 0; k < sem_table1_count; ++k) {
        const sem_table1_row *r = &sem_table1[k];
        if (only && !strstr(r->example, only) && !strstr(r->file, only)) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, r->file);
        struct stat st;
        if (stat(path, &st) != 0) {
            cli_warn("%s: %s not found, skipped", r->example, path);
            continue;
        }
        fprintf(stderr, "sem bench: [%d/%d] %s (%s)...\n", k + 1, sem_table1_count, r->example, r->file);
        bench_result b;
        memset(&b, 0, sizeof b);
        b.solver = "none";
        sem_error err;
        sem_error_clear(&err);
        double t0 = omp_get_wtime();
        if (run_row(r, path, steps, repeat, solver, defaults, &b, &err) != SEM_OK) {
            cli_warn("%s: %s", r->example, err.message);
            failed++;
            continue;
        }
        fprintf(stderr, "sem bench: %s done in %.1f s\n", r->example, omp_get_wtime() - t0);
        ran++;
        if (json) {
            cJSON *o = cJSON_CreateObject();
            if (!o) {
                cJSON_Delete(list);
                return cli_fail("out of memory");
            }
            cJSON_AddItemToArray(list, o);
            cJSON_AddStringToObject(o, "example", r->example);
            cJSON_AddStringToObject(o, "file", r->file);
            cJSON_AddNumberToObject(o, "order", r->order);
            cJSON_AddNumberToObject(o, "dofs", b.dofs);
            cJSON_AddNumberToObject(o, "sample_s", b.pre.sample_s);
            cJSON_AddNumberToObject(o, "scene_s", b.pre.scene_s);
            cJSON_AddNumberToObject(o, "quad_s", b.pre.quad_s);
            cJSON_AddNumberToObject(o, "weights_s", b.pre.weights_s);
            cJSON_AddNumberToObject(o, "build_pi_s", b.pre.build_pi_s);
            cJSON_AddNumberToObject(o, "step_s", b.step_s);
            cJSON_AddNumberToObject(o, "factor_s", b.factor_s);
            cJSON_AddNumberToObject(o, "nnz_percent", b.nnz_percent);
            cJSON_AddStringToObject(o, "solver", b.solver);
            /* the process's peak so far: rows run one after the other in one process, so
             * this is the largest row up to this one (docs/validation.md, section 5) */
            cJSON_AddNumberToObject(o, "peak_memory_bytes", cli_peak_memory());
            cJSON *p = cJSON_AddObjectToObject(o, "paper");
            if (p) {
                cJSON_AddNumberToObject(p, "dofs", r->paper_q);
                cJSON_AddNumberToObject(p, "sample_s", r->paper_sample);
                cJSON_AddNumberToObject(p, "quad_s", r->paper_quad);
                cJSON_AddNumberToObject(p, "weights_s", r->paper_weights);
                cJSON_AddNumberToObject(p, "build_pi_s", r->paper_build_pi);
                cJSON_AddNumberToObject(p, "step_s", r->paper_step);
                cJSON_AddNumberToObject(p, "nnz_percent", r->paper_nnz);
            }
        } else {
            printf("%-19s %5d %5d |", r->example, b.dofs, r->paper_q);
            print_cell(b.pre.sample_s, r->paper_sample);
            print_cell(b.pre.quad_s, r->paper_quad);
            print_cell(b.pre.weights_s, r->paper_weights);
            print_cell(b.pre.build_pi_s, r->paper_build_pi);
            print_cell(b.step_s, r->paper_step);
            printf(" %8.2e | %6.2f %6.2f | %8.2e | %7.0f\n", b.factor_s, b.nnz_percent, r->paper_nnz,
                   b.pre.scene_s, cli_peak_memory() / (1024.0 * 1024.0));
            fflush(stdout);
        }
    }
    if (json) {
        int rc = cli_print_json(list);
        if (rc) return rc;
    }
    if (ran == 0 && failed == 0) return cli_fail("no Table 1 model found in %s", dir);
    return failed ? CLI_FAILED : CLI_OK;
}
