/*
 * bench_preprocess.c - SEM preprocessing times on the paper's Table 1 models, beside the
 * paper's own (MATLAB + C++ MEX, 2.3 GHz Intel i5 laptop).
 *
 * usage: bench_preprocess [MODELS_DIR] [--csv] [--repeat N] [--only NAME]
 *   MODELS_DIR defaults to $SEM_SHARED_MODELS, else ../shared/models (relative to the
 *   current directory, then to the repository root this file was built from).
 *
 * Each model runs with the authors' settings from their released example scripts (models
 * README): order, ray grid, points per interval, alpha; the defaults where a script gives
 * none. Columns: our time per phase / the paper's, and the speed-up paper / ours. Our quad
 * column is the ray-cast quadrature alone: building the Embree scene that quadrature and
 * weights share (tessellation, orientation fix, winding-number tree) is timed apart as
 * scene_s (see src/preprocess/preprocess.c and `sem bench`). The best of --repeat runs
 * (default 3) is reported.
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sem/preprocess.h"

typedef struct bench_case {
    const char *name, *file;
    int order, rays0, rays1, points;
    double alpha;
    /* paper, Table 1 (seconds) and Nnz% */
    int paper_q;
    double sample, quad, weights, build_pi, nnz;
} bench_case;

static const bench_case cases[] = {
    {"rocket-soft", "rocket/rocket.iges", 2, 9, 15, 5, 10.0, 648, 2.83e-2, 5.62e-3, 5.58e-1, 6.83e-2, 100},
    {"rocket-stiff", "rocket/rocket.iges", 1, 5, 15, 5, 10.0, 648, 2.56e-2, 5.97e-3, 4.59e-1, 3.48e-2, 100},
    {"starship", "starship/starship_fall_simpler.igs", 1, 10, 10, 5, 0.7, 750, 6.78e-2, 1.52e-2, 8.50e-1, 9.52e-2, 100},
    {"beam-twist", "beams/beam_cmp3_b.iges", 2, 3, 3, 15, 0.51, 756, 1.97e-1, 2.25e-2, 1.35, 5.16e-1, 46.94},
    {"lamppost", "lamppost.iges", 2, 5, 35, 2, 0.8, 942, 1.28e-1, 1.27e-2, 1.89, 1.07, 56.38},
    {"tire", "tire.iges", 2, 9, 9, 4, 1.1, 1404, 1.74e-1, 1.32e-2, 1.82, 6.79e-1, 92.5},
    {"chicken", "chicken/chicken_simple_closed.iges", 2, 6, 6, 3, 0.0, 1773, 9.19e-1, 2.31e-2, 3.38, 1.91, 100},
    {"mug-soft", "mugs/mug_trimmed_complex.iges", 2, 10, 10, 5, 0.0, 1800, 4.18e-1, 2.87e-2, 3.77, 2.08, 100},
    {"castle", "castle/castle_super_simple.iges", 2, 12, 15, 12, 0.0, 1872, 4.84e-1, 1.44e-2, 1.52, 5.78e-1, 100},
    {"grumpy", "grumpy.iges", 2, 10, 10, 5, 0.0, 2010, 2.92e-1, 1.23e-2, 2.29, 2.89, 84.15},
    {"astronaut", "puft/puft_full_simpler.iges", 2, 8, 15, 3, 0.0, 3609, 2.47, 6.71e-2, 11.3, 10.9, 49.04},
};

static int is_dir(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0 && S_ISDIR(st.st_mode);
}

static const char *models_dir(const char *arg)
{
    if (arg) return arg;
    const char *env = getenv("SEM_SHARED_MODELS");
    if (env && is_dir(env)) return env;
    if (is_dir("../shared/models")) return "../shared/models";
    if (is_dir("../../shared/models")) return "../../shared/models";
    return "../shared/models";
}

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
    const char *dir = models_dir(dir_arg);
    if (!is_dir(dir)) {
        fprintf(stderr, "bench_preprocess: models folder %s not found\n", dir);
        return 1;
    }

    if (csv)
        printf("model,dofs,nnz,paper_nnz,sample_s,paper_sample_s,quad_s,paper_quad_s,weights_s,"
               "paper_weights_s,build_pi_s,paper_build_pi_s,operators_s\n");
    else {
        printf("threads: %d; times in seconds, ours / paper (speed-up = paper / ours)\n",
               omp_get_max_threads());
        printf("%-12s %5s %6s %6s | %-24s | %-24s | %-24s | %-24s | %8s\n", "model", "dofs",
               "Nnz%", "paper", "sample", "quad", "weights", "build Pi", "operators");
    }
    int failures = 0;
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; ++c) {
        const bench_case *b = &cases[c];
        if (only && strcmp(only, b->name) != 0) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, b->file);
        sem_model *model = NULL;
        sem_error err;
        if (sem_model_load(path, &model, &err) != SEM_OK) {
            fprintf(stderr, "%s: %s\n", b->name, err.message);
            failures++;
            continue;
        }
        sem_preprocess_options o = sem_default_preprocess_options();
        o.order = b->order;
        o.rays[0] = b->rays0;
        o.rays[1] = b->rays1;
        o.points_per_interval = b->points;
        o.alpha = b->alpha;
        o.tessellation = 8; /* the ray casts' triangulation; the sphere-accuracy default 16 is not needed here */
        sem_preprocess_timings best = {1e30, 1e30, 1e30, 1e30, 1e30, 1e30};
        int dofs = 0;
        double nnz = 0;
        int ok = 1;
        for (int r = 0; r < repeat && ok; ++r) {
            sem_discretization *d = NULL;
            if (sem_preprocess(model, &o, &d, &err) != SEM_OK) {
                fprintf(stderr, "%s: %s\n", b->name, err.message);
                failures++;
                ok = 0;
                break;
            }
            dofs = 3 * d->n_ctrl;
            nnz = d->stiffness_nnz_percent;
#define KEEP(f) best.f = d->timings.f < best.f ? d->timings.f : best.f
            KEEP(sample_s);
            KEEP(scene_s);
            KEEP(quad_s);
            KEEP(weights_s);
            KEEP(build_pi_s);
            KEEP(operators_s);
#undef KEEP
            sem_discretization_destroy(d);
        }
        sem_model_destroy(model);
        if (!ok) continue;
        if (csv) {
            printf("%s,%d,%.2f,%.2f,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g,%.4g\n", b->name, dofs,
                   nnz, b->nnz, best.sample_s, b->sample, best.quad_s, b->quad, best.weights_s,
                   b->weights, best.build_pi_s, b->build_pi, best.operators_s);
        } else {
            printf("%-12s %5d %6.2f %6.2f | %7.2e/%7.2e %6.1fx | %7.2e/%7.2e %6.1fx | %7.2e/%7.2e "
                   "%6.1fx | %7.2e/%7.2e %6.1fx | %8.2e\n",
                   b->name, dofs, nnz, b->nnz, best.sample_s, b->sample, b->sample / best.sample_s,
                   best.quad_s, b->quad, b->quad / best.quad_s, best.weights_s, b->weights,
                   b->weights / best.weights_s, best.build_pi_s, b->build_pi,
                   b->build_pi / best.build_pi_s, best.operators_s);
        }
        fflush(stdout);
    }
    return failures ? 1 : 0;
}
