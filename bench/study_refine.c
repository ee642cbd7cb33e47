/*
 * study_refine.c - what exact refinement (sem_model_refine, `sem refine`) costs and what it
 * does to a solution.
 *
 * 1. Time: the rocket (rocket/rocket.iges, 648 dofs) refined to about 1e4, 4e4 and 1e5 dofs
 *    (K = 12, 27, 44; 3 (12 (3 + K)^2 + (3 + K)(3 + 3K)) dofs), the fastest of --repeat runs of
 *    sem_model_refine alone (no file reading or writing).
 * 2. Solution: the cantilever of docs/validation.md (sem_primitive_beam, 10 sections, 5 x 1 x 1
 *    m, clamped at x = 0, gravity 10 m/s^2 along -z, neo-Hookean rho 1000, E 1e6, nu 0.45,
 *    static) refined by each factor of --factors and solved at sem's default settings (as
 *    tests/test_defaults.c) and with the authors' (as bench/study_deflection.c). The geometry
 *    is the same; only the control nets differ. tip = mean -u_z of the free end cap's control
 *    points (sem_cantilever_tip), centre = -u_z of the cap's surface at its parameter centre.
 *
 * usage: study_refine [--models DIR] [--factors LIST] [--repeat N] [--no-authors]
 *   --models DIR     shared models folder (default $SEM_SHARED_MODELS, ../shared/models, ...)
 *   --factors LIST   refinement factors of the beam (default 1,2,4)
 *   --repeat N       timed runs per rocket size (default 5)
 *   --no-authors     only the default settings
 *
 * Output (stdout, whitespace separated, '#' comments):
 *   rocket K dofs refine_ms
 *   beam settings K dofs tip_m centre_m percent_of_fem ratio_to_K1 preprocess_s solve_s
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/simulation.h"

static void time_rocket(const char *dir, int repeat)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/rocket/rocket.iges", dir ? dir : ".");
    sem_model *m = NULL;
    sem_error err;
    if (!dir || sem_model_load(path, &m, &err) != SEM_OK) {
        printf("# rocket: not found (%s)\n", dir ? err.message : "no models folder");
        return;
    }
    printf("# rocket K dofs refine_ms (fastest of %d)\n", repeat);
    static const int factors[] = {12, 27, 44};
    for (int k = 0; k < 3; ++k) {
        double best = INFINITY;
        size_t dofs = 0;
        for (int r = 0; r < repeat; ++r) {
            sem_model *out = NULL;
            double t0 = omp_get_wtime();
            if (sem_model_refine(m, factors[k], &out, &err) != SEM_OK) {
                fprintf(stderr, "study_refine: %s\n", err.message);
                break;
            }
            best = fmin(best, omp_get_wtime() - t0);
            dofs = 3 * sem_model_control_points(out);
            sem_model_destroy(out);
        }
        printf("rocket %2d %6zu %.3f\n", factors[k], dofs, 1e3 * best);
    }
    sem_model_destroy(m);
}

/* -u_z of the free end cap's centre: the cap is the part whose control points all lie at
 * x = 5 at rest. */
static double cap_centre_deflection(const sem_model *m, const double *q0, const double *q)
{
    size_t off = 0;
    for (int p = 0; p < m->n_parts; ++p) {
        const sem_surface *s = &m->parts[p].surface;
        size_t n = (size_t)s->n_u * s->n_v;
        int cap = 1;
        for (size_t c = 0; c < n && cap; ++c) cap = fabs(q0[3 * (off + c)] - 5.0) < 1e-12;
        if (cap) {
            sem_surface moved = *s; /* shares everything but the control points */
            moved.ctrl = (double *)(q + 3 * off);
            double u = 0.5 * (s->u0 + s->u1), v = 0.5 * (s->v0 + s->v1), x0[3], x1[3];
            sem_surface_eval(s, u, v, x0, NULL, NULL, NULL);
            sem_surface_eval(&moved, u, v, x1, NULL, NULL, NULL);
            return x0[2] - x1[2];
        }
        off += n;
    }
    return NAN;
}

/* The beam refined by `factor`, solved statically at defaults (authors = 0) or with the
 * authors' settings; 0 on failure. */
static int solve_beam(int factor, int authors, double *tip, double *centre, size_t *dofs,
                      double *pre_s, double *solve_s)
{
    sem_error err;
    sem_model *base = sem_model_create(), *m = NULL;
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 10;
    bd.length = 5;
    bd.width = 1;
    bd.height = 1;
    if (sem_primitive_beam(base, &bd, &err) != SEM_OK ||
        sem_model_refine(base, factor, &m, &err) != SEM_OK) {
        fprintf(stderr, "study_refine: %s\n", err.message);
        sem_model_destroy(base);
        return 0;
    }
    sem_model_destroy(base);
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof *q0);
    unsigned char *pin = calloc(nc, 1);
    sem_model_get_q(m, q0);
    sem_cantilever_clamp(q0, nc, pin);
    sem_cantilever_settings cs = sem_default_cantilever_settings();
    sem_preprocess_options o =
        authors ? sem_cantilever_preprocess_options(&cs) : sem_default_preprocess_options();
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    int ok = 0;
    double t0 = omp_get_wtime();
    if (sem_preprocess(m, &o, &d, &err) != SEM_OK) goto done;
    double t1 = omp_get_wtime();
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -10;
    wd.integrator = SEM_STATIC;
    if (!(w = sem_world_create(&wd, &err))) goto done;
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.pinned = pin;
    if (authors) {
        if (sem_cantilever_material(&cs, &od.material, &err) != SEM_OK) goto done;
        od.gamma = cs.gamma;
        od.blend = cs.blend;
        od.seams = cs.seams;
    } else {
        od.material = sem_default_material(); /* neo-Hookean, rho 1000, E 1e6, nu 0.45 */
    }
    if (sem_world_add_object(w, &od, &err) < 0 || sem_world_solve_static(w, &err) != SEM_OK)
        goto done;
    *solve_s = omp_get_wtime() - t1;
    *pre_s = t1 - t0;
    *tip = sem_cantilever_tip(m, q0, sem_world_object_q(w, 0));
    *centre = cap_centre_deflection(m, q0, sem_world_object_q(w, 0));
    *dofs = 3 * nc;
    ok = 1;
done:
    if (!ok) fprintf(stderr, "study_refine: beam by %d: %s\n", factor, err.message);
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    free(q0);
    free(pin);
    return ok;
}

int main(int argc, char **argv)
{
    const char *dir = NULL;
    int factors[16] = {1, 2, 4}, n_factors = 3, repeat = 5, authors = 1;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--models") == 0 && i + 1 < argc) dir = argv[++i];
        else if (strcmp(argv[i], "--factors") == 0 && i + 1 < argc) {
            n_factors = sem_parse_count_list(argv[++i], SEM_MAX_REFINE_FACTOR, factors, 16);
            if (n_factors < 1) {
                fprintf(stderr, "study_refine: --factors: a list of 1..%d\n", SEM_MAX_REFINE_FACTOR);
                return 2;
            }
        } else if (strcmp(argv[i], "--repeat") == 0 && i + 1 < argc) repeat = atoi(argv[++i]);
        else if (strcmp(argv[i], "--no-authors") == 0) authors = 0;
        else {
            fprintf(stderr, "usage: %s [--models DIR] [--factors LIST] [--repeat N] [--no-authors]\n",
                    argv[0]);
            return 2;
        }
    }
    if (repeat < 1) repeat = 1;
    if (!dir) dir = sem_bench_models_dir();
    time_rocket(dir, repeat);

    double fem = sem_fem_reference_find(NULL, "study_refine");
    printf("# beam settings K dofs tip_m centre_m percent_of_fem ratio_to_K1 preprocess_s "
           "solve_s (FEM %.4f m)\n",
           fem);
    for (int a = 0; a <= authors; ++a) {
        double tip1 = NAN;
        for (int k = 0; k < n_factors; ++k) {
            double tip = NAN, centre = NAN, pre = 0, solve = 0;
            size_t dofs = 0;
            if (!solve_beam(factors[k], a, &tip, &centre, &dofs, &pre, &solve)) continue;
            if (factors[k] == 1) tip1 = tip;
            printf("beam %-8s %2d %5zu %.6f %.6f %6.2f %.4f %.2f %.2f\n", a ? "authors" : "defaults",
                   factors[k], dofs, tip, centre, fem > 0 ? 100 * tip / fem : NAN, tip / tip1, pre,
                   solve);
            fflush(stdout);
        }
    }
    return 0;
}
