/*
 * bench_preprocess.c - SEM preprocessing times on the paper's Table 1 models, beside the
 * paper's own (MATLAB + C++ MEX, 2.3 GHz Intel i5 laptop).
 *
 * usage: bench_preprocess [MODELS_DIR] [--csv] [--repeat N] [--only TEXT]
 *   MODELS_DIR defaults to $SEM_SHARED_MODELS, else ../shared/models, else
 *   ../../shared/models; --only keeps the rows whose example or file contains TEXT.
 *
 * The rows are `sem bench`'s (sem_table1 in src/bench/validation.c): the authors' settings
 * from their released example scripts (models README), order, ray grid, points per
 * interval, alpha, the defaults where a script gives none. This program adds the
 * operators step (not a Table 1 column) and a CSV form; `sem bench` adds the step times. Columns: our time per phase / the paper's, and the speed-up paper / ours. Our quad
 * column is the ray-cast quadrature alone: building the Embree scene that quadrature and
 * weights share (tessellation, orientation fix, winding-number tree) is timed apart as
 * scene_s (see src/preprocess/preprocess.c and `sem bench`). The best of --repeat runs
 * (default 3) is reported.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "sem/preprocess.h"

int main(int argc, char **argv)
{
    const char *dir_arg = NULL, *only = NULL;
    int csv = 0, repeat = 3;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--csv") == 0) csv = 1;
        else if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) repeat = atoi(argv[++i]);
        else if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) only = argv[++i];
        else if (argv[i][0] == '-') {
            fprintf(stderr, "usage: %s [MODELS_DIR] [--csv] [--repeat N] [--only NAME]\n", argv[0]);
            return 2;
        } else dir_arg = argv[i];
    }
    if (repeat < 1) repeat = 1;
    const char *dir = dir_arg ? dir_arg : sem_bench_models_dir();
    if (!sem_bench_is_dir(dir)) {
        fprintf(stderr, "bench_preprocess: models folder %s not found\n", dir ? dir : "../shared/models");
        return 1;
    }

    if (csv)
        printf("model,dofs,nnz,paper_nnz,sample_s,paper_sample_s,scene_s,quad_s,paper_quad_s,weights_s,"
               "paper_weights_s,build_pi_s,paper_build_pi_s,operators_s\n");
    else {
        printf("threads: %d; times in seconds, ours / paper (speed-up = paper / ours)\n",
               omp_get_max_threads());
        printf("%-19s %5s %6s %6s | %-24s | %-24s | %-24s | %-24s | %8s %8s\n", "model", "dofs",
               "Nnz%", "paper", "sample", "quad", "weights", "build Pi", "scene", "operators");
    }
    int failures = 0;
    for (int c = 0; c < sem_table1_count; ++c) {
        const sem_table1_row *b = &sem_table1[c];
        if (only && !strstr(b->example, only) && !strstr(b->file, only)) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, b->file);
        sem_model *model = NULL;
        sem_error err;
        if (sem_model_load(path, &model, &err) != SEM_OK) {
            fprintf(stderr, "%s: %s\n", b->example, err.message);
            failures++;
            continue;
        }
        sem_preprocess_options o = sem_table1_options(b);
        sem_preprocess_timings best = {1e30, 1e30, 1e30, 1e30, 1e30, 1e30};
        int dofs = 0;
        double nnz = 0;
        int ok = 1;
        for (int r = 0; r < repeat && ok; ++r) {
            sem_discretization *d = NULL;
            if (sem_preprocess(model, &o, &d, &err) != SEM_OK) {
                fprintf(stderr, "%s: %s\n", b->example, err.message);
                failures++;
                ok = 0;
                break;
            }
            dofs = 3 * d->n_ctrl;
            nnz = d->stiffness_nnz_percent;
            sem_timings_keep_fastest(&best, &d->timings);
            sem_discretization_destroy(d);
        }
        sem_model_destroy(model);
        if (!ok) continue;
        if (csv) {
            printf("\"%s\",%d,%.2f,%.2f,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g\n", b->example,
                   dofs, nnz, b->paper_nnz, best.sample_s, b->paper_sample, best.scene_s, best.quad_s,
                   b->paper_quad, best.weights_s, b->paper_weights, best.build_pi_s, b->paper_build_pi,
                   best.operators_s);
        } else {
            printf("%-19s %5d %6.2f %6.2f | %7.2e/%7.2e %6.1fx | %7.2e/%7.2e %6.1fx | %7.2e/%7.2e "
                   "%6.1fx | %7.2e/%7.2e %6.1fx | %8.2e %8.2e\n",
                   b->example, dofs, nnz, b->paper_nnz, best.sample_s, b->paper_sample,
                   b->paper_sample / best.sample_s, best.quad_s, b->paper_quad,
                   b->paper_quad / best.quad_s, best.weights_s, b->paper_weights,
                   b->paper_weights / best.weights_s, best.build_pi_s, b->paper_build_pi,
                   b->paper_build_pi / best.build_pi_s, best.scene_s, best.operators_s);
        }
        fflush(stdout);
    }
    return failures ? 1 : 0;
}
