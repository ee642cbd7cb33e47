/*
 * study_deflection.c - the deflection study of the paper's Fig. 10: static tip deflection of
 * the 5 x 1 x 1 m cantilever (clamped at x = 0, gravity 10 m/s^2 along -z, rho 1000,
 * E 1e6, nu 0.45, quadratic SEM with the authors' alpha 0.501, rays 3 x 3, 100 points per
 * interval) as a percentage of the converged FEM figure, versus parts and degrees of freedom.
 *
 * usage: study_deflection [--models DIR] [--fem FILE] [--sections LIST] [--gamma G]
 *                         [--alpha A] [--material NAME] [--rays N1 N2]
 *                         [--points-per-interval N] [--no-files] [--no-generated]
 *   --models DIR    folder of the shared models (beams/perf/b1..b10.igs); default
 *                   $SEM_SHARED_MODELS, ../shared/models or ../../shared/models
 *   --fem FILE      FEM reference (default validation/fem_cantilever.json, also tried
 *                   relative to ..)
 *   --sections LIST comma-separated section counts of generated beams (sem_primitive_beam),
 *                   default 1,2,3,4,5,6,8,10,12,15,20,25,30
 *   --gamma G       error stiffness (default: the preprocessing default, kappa E / L)
 *   --alpha A       weight cut-off distance in metres (default the authors' 0.501)
 *   --material NAME neohookean (default) or any name sem_material_parse_type accepts
 *   --rays N1 N2    ray grid across x (default the authors' 3 x 3)
 *   --points-per-interval N (default 100)
 *
 * Output (stdout, whitespace separated, '#' comments, for gnuplot):
 *   source sections parts dofs tip_m percent_of_fem newton preprocess_s solve_s
 * Progress on stderr.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench/validation.h"
#include "sem/primitives.h"

static int exists(const char *p)
{
    struct stat st;
    return stat(p, &st) == 0;
}

static const char *models_dir(const char *arg)
{
    if (arg) return arg;
    const char *dir = sem_bench_models_dir();
    return dir ? dir : "../shared/models";
}

static void report(const char *source, int sections, const sem_cantilever_result *r, double fem)
{
    printf("%-10s %3d %4d %6d %10.6f %8.3f %3d %8.3f %8.3f\n", source, sections, r->parts, r->dofs,
           r->tip_deflection, fem > 0 ? 100.0 * r->tip_deflection / fem : NAN, r->newton_iterations,
           r->preprocess_s, r->solve_s);
    fflush(stdout);
}

int main(int argc, char **argv)
{
    const char *dir_arg = NULL, *fem_path = NULL, *sections_arg = "1,2,3,4,5,6,8,10,12,15,20,25,30";
    int files = 1, generated = 1;
    sem_cantilever_settings s = sem_default_cantilever_settings();
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--models") && i + 1 < argc) dir_arg = argv[++i];
        else if (!strcmp(argv[i], "--fem") && i + 1 < argc) fem_path = argv[++i];
        else if (!strcmp(argv[i], "--sections") && i + 1 < argc) sections_arg = argv[++i];
        else if (!strcmp(argv[i], "--gamma") && i + 1 < argc) s.gamma = atof(argv[++i]);
        else if (!strcmp(argv[i], "--alpha") && i + 1 < argc) s.alpha = atof(argv[++i]);
        else if (!strcmp(argv[i], "--rays") && i + 2 < argc) {
            s.rays[0] = atoi(argv[++i]);
            s.rays[1] = atoi(argv[++i]);
        } else if (!strcmp(argv[i], "--points-per-interval") && i + 1 < argc)
            s.points_per_interval = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--material") && i + 1 < argc) {
            if (sem_material_parse_type(argv[++i], &s.material) != SEM_OK) {
                fprintf(stderr, "study_deflection: unknown material %s\n", argv[i]);
                return 2;
            }
        } else if (!strcmp(argv[i], "--no-files")) files = 0;
        else if (!strcmp(argv[i], "--no-generated")) generated = 0;
        else {
            fprintf(stderr, "usage: %s [--models DIR] [--fem FILE] [--sections LIST] [--gamma G] [--alpha A] "
                            "[--material NAME] [--rays N1 N2] [--points-per-interval N] [--no-files] "
                            "[--no-generated]\n", argv[0]);
            return 2;
        }
    }
    int counts[64];
    int n_counts = sem_parse_count_list(sections_arg, 1000, counts, 64);
    if (n_counts < 0) {
        fprintf(stderr, "study_deflection: bad --sections list %s (up to 64 counts, 1..1000)\n",
                sections_arg);
        return 2;
    }
    sem_error err;
    double fem = sem_fem_reference_find(fem_path, "study_deflection");
    if (fem <= 0) fprintf(stderr, "study_deflection: no FEM reference; percent column is nan\n");

    printf("# SEM static cantilever vs FEM (tip deflection %.6f m)\n", fem);
    printf("# material %s, gamma %s%g, order %d, rays %dx%d, %d per interval, alpha %g\n",
           sem_material_type_name(s.material), s.gamma > 0 ? "" : "default ", s.gamma, s.order,
           s.rays[0], s.rays[1], s.points_per_interval, s.alpha);
    printf("# source sections parts dofs tip_m percent_of_fem newton preprocess_s solve_s\n");
    int failures = 0;
    if (files) {
        const char *dir = models_dir(dir_arg);
        for (int k = 1; k <= 10; ++k) {
            char path[4096];
            snprintf(path, sizeof path, "%s/beams/perf/b%d.igs", dir, k);
            if (!exists(path)) continue;
            sem_model *m = NULL;
            if (sem_model_load(path, &m, &err) != SEM_OK) {
                fprintf(stderr, "%s\n", err.message);
                failures++;
                continue;
            }
            fprintf(stderr, "b%d (%d parts)...\n", k, m->n_parts);
            sem_cantilever_result r;
            char name[16];
            snprintf(name, sizeof name, "b%d", k);
            if (sem_cantilever_solve(m, &s, &r, &err) == SEM_OK) report(name, k, &r, fem);
            else {
                fprintf(stderr, "b%d: %s\n", k, err.message);
                failures++;
            }
            sem_model_destroy(m);
        }
    }
    if (generated) {
        for (int j = 0; j < n_counts; ++j) {
            long n = counts[j];
            sem_model *m = sem_model_create();
            sem_beam_def bd = sem_default_beam_def();
            bd.sections = (int)n;
            if (!m || sem_primitive_beam(m, &bd, &err) != SEM_OK) {
                fprintf(stderr, "beam %ld: %s\n", n, m ? err.message : "out of memory");
                sem_model_destroy(m);
                failures++;
                continue;
            }
            fprintf(stderr, "generated beam, %ld sections (%d parts)...\n", n, m->n_parts);
            sem_cantilever_result r;
            if (sem_cantilever_solve(m, &s, &r, &err) == SEM_OK) report("generated", (int)n, &r, fem);
            else {
                fprintf(stderr, "generated %ld: %s\n", n, err.message);
                failures++;
            }
            sem_model_destroy(m);
        }
    }
    return failures ? 1 : 0;
}
