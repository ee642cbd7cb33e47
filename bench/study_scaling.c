/*
 * study_scaling.c - the scalability study of the paper's Fig. 13: beams of unit cubes
 * (beams/cubes/cube1..cube100, 6 + 4(N-1) parts) preprocessed with a fixed weight cut-off,
 * then a few linearly implicit Euler steps (gravity 10 m/s^2 along -z, clamped at x = 0,
 * rho 1000, E 1e6, nu 0.45, dt 0.01). Reports the non-zero percentage of the q-space
 * system matrix and the mean step time versus degrees of freedom, and the growth exponent p
 * of step time ~ dofs^p from a least-squares fit on log-log axes.
 *
 * usage: study_scaling [--models DIR] [--steps N] [--alpha A] [--order 1|2] [--max N]
 *   --steps N  timed steps per model after one warm-up step (default 5)
 *   --alpha A  weight cut-off in model units (default 0.501, as in the deflection study)
 *   --max N    skip cubeN files with N above this
 * Settings: rays 3 x 3 along x, 20 volume points per metre of ray (at least 20).
 *
 * Output (stdout, whitespace separated, '#' comments, for gnuplot):
 *   file cubes parts dofs quad nnz_percent step_s factor_s preprocess_s solver
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench/validation.h"
#include "sem/simulation.h"

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

int main(int argc, char **argv)
{
    const char *dir_arg = NULL;
    int steps = 5, order = 2, max_n = 1000;
    double alpha = 0.501;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--models") && i + 1 < argc) dir_arg = argv[++i];
        else if (!strcmp(argv[i], "--steps") && i + 1 < argc) steps = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--alpha") && i + 1 < argc) alpha = atof(argv[++i]);
        else if (!strcmp(argv[i], "--order") && i + 1 < argc) order = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--max") && i + 1 < argc) max_n = atoi(argv[++i]);
        else {
            fprintf(stderr, "usage: %s [--models DIR] [--steps N] [--alpha A] [--order 1|2] [--max N]\n",
                    argv[0]);
            return 2;
        }
    }
    if (steps < 1) steps = 1;
    const char *dir = models_dir(dir_arg);
    static const int sizes[] = {1, 2, 3, 4, 5, 10, 15, 20, 25, 30, 40, 50, 75, 100};
    const int n_sizes = (int)(sizeof sizes / sizeof sizes[0]);
    double dofs[32], step_t[32], factor_t[32];
    int n = 0, failures = 0;
    printf("# scalability: cubes, order %d, alpha %g, rays 3x3, %d timed linearly implicit Euler steps, "
           "%d threads\n", order, alpha, steps, omp_get_max_threads());
    printf("# file cubes parts dofs quad nnz_percent step_s factor_s preprocess_s solver\n");
    for (int k = 0; k < n_sizes; ++k) {
        if (sizes[k] > max_n) continue;
        char path[4096], name[32];
        snprintf(name, sizeof name, sizes[k] == 1 ? "cube%d.igs" : "cube%d.iges", sizes[k]);
        snprintf(path, sizeof path, "%s/beams/cubes/%s", dir, name);
        if (!exists(path)) continue;
        sem_error err;
        sem_model *m = NULL;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            fprintf(stderr, "%s\n", err.message);
            failures++;
            continue;
        }
        size_t nc = sem_model_control_points(m);
        double *q0 = malloc(3 * nc * sizeof *q0);
        unsigned char *pin = calloc(nc, 1);
        sem_model_get_q(m, q0);
        double xmin = INFINITY, xmax = -INFINITY;
        for (size_t c = 0; c < nc; ++c) {
            xmin = fmin(xmin, q0[3 * c]);
            xmax = fmax(xmax, q0[3 * c]);
        }
        for (size_t c = 0; c < nc; ++c) pin[c] = q0[3 * c] < xmin + 1e-9;
        sem_preprocess_options po = sem_default_preprocess_options();
        po.order = order;
        po.alpha = alpha;
        po.rays[0] = po.rays[1] = 3;
        po.points_per_interval = (int)fmax(20.0, ceil(20.0 * (xmax - xmin)));
        fprintf(stderr, "%s (%d parts)...\n", name, m->n_parts);
        double t0 = omp_get_wtime();
        sem_discretization *d = NULL;
        sem_world *w = NULL;
        if (sem_preprocess(m, &po, &d, &err) != SEM_OK) goto fail;
        double t_pre = omp_get_wtime() - t0;
        sem_world_def wd = sem_default_world_def();
        wd.gravity[2] = -10.0;
        wd.dt = 0.01;
        wd.integrator = SEM_LINEARLY_IMPLICIT_EULER;
        w = sem_world_create(&wd, &err);
        if (!w) goto fail;
        sem_object_def od = sem_default_object_def();
        od.model = m;
        od.disc = d;
        od.material = sem_default_material();
        od.pinned = pin;
        if (sem_world_add_object(w, &od, &err) < 0) goto fail;
        if (sem_world_step(w, &err) != SEM_OK) goto fail; /* warm-up (symbolic analysis) */
        double ts = 0, tf = 0;
        for (int s = 0; s < steps; ++s) {
            if (sem_world_step(w, &err) != SEM_OK) goto fail;
            ts += sem_world_last_step_seconds(w);
            tf += sem_world_last_factor_seconds(w);
        }
        dofs[n] = sem_world_object_dofs(w, 0);
        step_t[n] = ts / steps;
        factor_t[n] = tf / steps;
        printf("%-12s %3d %4d %6d %7d %8.3f %10.4e %10.4e %8.3f %s\n", name, sizes[k], m->n_parts,
               (int)dofs[n], d->n_quad, sem_world_object_nnz_percent(w, 0), step_t[n], factor_t[n], t_pre,
               sem_world_solver_name(w, 0));
        fflush(stdout);
        n++;
        goto next;
    fail:
        fprintf(stderr, "%s: %s\n", name, err.message);
        failures++;
    next:
        sem_world_destroy(w);
        sem_discretization_destroy(d);
        free(pin);
        free(q0);
        sem_model_destroy(m);
    }
    /* fit on the larger half (small models are dominated by fixed costs) and on all */
    double c_all, c_big, cf;
    double p_all = sem_loglog_fit(dofs, step_t, n, &c_all);
    int h = n / 2;
    double p_big = sem_loglog_fit(dofs + h, step_t + h, n - h, &c_big);
    double p_fac = sem_loglog_fit(dofs + h, factor_t + h, n - h, &cf);
    printf("# fit step_s = c dofs^p: all models p = %.3f (c = %.3e); largest %d models p = %.3f (c = %.3e)\n",
           p_all, c_all, n - h, p_big, c_big);
    printf("# fit factor_s = c dofs^p: largest %d models p = %.3f (c = %.3e)\n", n - h, p_fac, cf);
    fprintf(stderr, "step time exponent %.3f (all), %.3f (largest %d)\n", p_all, p_big, n - h);
    return failures ? 1 : 0;
}
