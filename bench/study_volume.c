/*
 * study_volume.c - volume convergence of the ray-cast quadrature (paper Sec. 6.3, Fig. 7):
 * relative error of the quadrature volume versus the ray grid n x n on
 *   - a sphere of radius 1 (sem_primitive_sphere, exact rational NURBS; exact 4/3 pi), and
 *   - the shared rounded_cube.iges against its divergence-theorem volume
 *     V = 1/3 sum_i sign_i * integral x . (x_u x x_v) du dv (Gauss-Legendre per knot span,
 *     part signs from the ray-cast orientation fix), as in tests/test_quadrature.c.
 *
 * usage: study_volume [--models DIR] [--rays LIST]   (default 2,3,4,6,8,12,16,24,32,48,64,96)
 * Output (stdout, whitespace separated, '#' comments, for gnuplot):
 *   shape rays quad_points volume reference relative_error
 * The quadrature uses 2 points per interval (the volume of a midpoint rule along the ray
 * does not depend on it: each interval is integrated exactly in its length).
 *
 * study_volume --defaults [--models DIR] [--repeat N] [--reference-rays N] [--only TEXT]
 * [--all-references] (models whose name contains TEXT; fine-grid references for the other
 * Table 1 models too, slow): the default
 * quadrature (cells of the object's frame, quadrature_subrays.c) on primitives and shared
 * models, for each ray setting: depth 0 without correction (the midpoint rule of 4 x 4 rays
 * per finest cell, the quadrature before issue 27), then depths 0-3 with the curvature
 * correction (sem_preprocess uses sem_subray_default_settings()). Output:
 *   model depth correct points rays volume reference relative_error quad_s
 * quad_s is the quadrature step's fastest of --repeat runs (default 3; wall time, on the
 * threads OMP_NUM_THREADS allows). References: exact for the primitives and the box beams
 * (5 x 1 x 1), the divergence theorem for rounded_cube.iges, and for the trimmed or open
 * castle and mug the mean over the three axes of the explicit midpoint grid of
 * --reference-rays^2 rays (default 400; tessellation 32), whose spread is printed as a
 * comment.
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "bench/validation.h"
#include "preprocess/raycast.h"
#include "preprocess/steps.h"
#include "sem/nurbs.h"
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

static double divergence_volume(const sem_model *m, const sem_raycast_scene *scene)
{
    double gx[12], gw[12], bu[512], bv[512];
    sem_gauss_legendre(12, gx, gw);
    double total = 0;
    for (int p = 0; p < m->n_parts; p++) {
        const sem_surface *s = &m->parts[p].surface;
        int nu = sem_knot_breaks(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, bu, 512);
        int nv = sem_knot_breaks(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, bv, 512);
        double sum = 0;
        for (int a = 0; a + 1 < nu; a++)
            for (int b = 0; b + 1 < nv; b++) {
                double hu = 0.5 * (bu[a + 1] - bu[a]), hv = 0.5 * (bv[b + 1] - bv[b]);
                for (int i = 0; i < 12; i++)
                    for (int j = 0; j < 12; j++) {
                        double X[3], Su[3], Sv[3];
                        sem_surface_eval(s, bu[a] + hu * (gx[i] + 1), bv[b] + hv * (gx[j] + 1), X, Su, Sv, NULL);
                        double n[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                                       Su[0] * Sv[1] - Su[1] * Sv[0]};
                        sum += gw[i] * gw[j] * hu * hv * (X[0] * n[0] + X[1] * n[1] + X[2] * n[2]);
                    }
            }
        total += sem_raycast_part_sign(scene, p) * sum;
    }
    return total / 3.0;
}

/* Quadrature volume on an n x n grid (the quadrature step alone, as sem_preprocess runs it). */
static int quad_volume(const sem_model *m, const sem_raycast_scene *scene, int n, double *vol, int *npts)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    o.rays[0] = o.rays[1] = n;
    o.points_per_interval = 2;
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_error err;
    if (sem_step_quadrature(m, scene, &o, &d, &err) != SEM_OK) {
        fprintf(stderr, "quadrature %dx%d: %s\n", n, n, err.message);
        return 0;
    }
    *vol = d.volume;
    *npts = d.n_quad;
    free(d.quad_X);
    free(d.quad_volume);
    free(d.quad_part);
    return 1;
}

static void study(const char *shape, const sem_model *m, double reference, const sem_raycast_scene *scene,
                  const int *rays, int n_rays)
{
    for (int k = 0; k < n_rays; ++k) {
        double v;
        int np;
        if (!quad_volume(m, scene, rays[k], &v, &np)) continue;
        printf("%-13s %4d %7d %.10f %.10f %.4e\n", shape, rays[k], np, v, reference,
               fabs(v / reference - 1));
        fflush(stdout);
    }
}

/* ---- the default quadrature ---- */

/* The default quadrature of m with the given ray settings, as sem_preprocess runs it (boundary
 * samples, scene at the default tessellation, object frame, quadrature step). */
static int default_quadrature(const sem_model *m, const sem_subray_settings *st, int repeat,
                              double *volume, int *points, long long *rays, double *seconds)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    sem_error err;
    sem_discretization *d = calloc(1, sizeof *d);
    sem_raycast_scene *scene = NULL;
    int ok = d && sem_step_sample(m, 0, d, &err) == SEM_OK &&
             sem_raycast_scene_build(m, o.tessellation, &scene, &err) == SEM_OK &&
             sem_step_frame(scene, d, &err) == SEM_OK;
    *seconds = INFINITY;
    for (int r = 0; ok && r < repeat; ++r) {
        double t0 = omp_get_wtime();
        ok = sem_step_quadrature_with(m, scene, &o, st, d, rays, &err) == SEM_OK;
        double t = omp_get_wtime() - t0;
        if (t < *seconds) *seconds = t;
    }
    if (!ok) fprintf(stderr, "default quadrature: %s\n", err.message);
    if (ok) {
        *volume = d->volume;
        *points = d->n_quad;
    }
    sem_raycast_scene_destroy(scene);
    sem_discretization_destroy(d);
    return ok;
}

/* The mean over the three axes of the explicit n x n midpoint grid (tessellation 32), and the
 * largest difference between axes. */
static int grid_reference(const sem_model *m, int n, double *mean, double *spread)
{
    sem_raycast_scene *scene = NULL;
    sem_error err;
    if (sem_raycast_scene_build(m, 32, &scene, &err) != SEM_OK) {
        fprintf(stderr, "reference: %s\n", err.message);
        return 0;
    }
    double v[3];
    int ok = 1;
    for (int a = 0; a < 3 && ok; ++a) {
        sem_preprocess_options o = sem_default_preprocess_options();
        o.rays[0] = o.rays[1] = n;
        o.ray_axis = a;
        o.points_per_interval = 1;
        sem_discretization d;
        memset(&d, 0, sizeof d);
        ok = sem_step_quadrature(m, scene, &o, &d, &err) == SEM_OK;
        if (!ok) fprintf(stderr, "reference: %s\n", err.message);
        v[a] = d.volume;
        free(d.quad_X);
        free(d.quad_volume);
        free(d.quad_part);
    }
    sem_raycast_scene_destroy(scene);
    *mean = (v[0] + v[1] + v[2]) / 3.0;
    *spread = fmax(fabs(v[0] - v[1]), fmax(fabs(v[1] - v[2]), fabs(v[0] - v[2])));
    return ok;
}

static int study_defaults(const char *dir, int repeat, int reference_rays, const char *only,
                          int all_references)
{
    printf("# model depth correct points rays volume reference relative_error quad_s\n");
    /* the first 12 have references (exact, divergence theorem, fine grids); the rest are the
     * other Table 1 models, for points, rays and time (nan: no reference, unless
     * --all-references asks for their fine grids too) */
    const char *names[] = {"sphere", "torus", "cylinder", "box", "rounded_cube.iges",
                           "beams/perf/b1.igs", "beams/perf/b4.igs", "beams/perf/b10.igs",
                           "beams/beam_cmp3_b.iges", "mugs/mug_trimmed_complex.iges",
                           "castle/castle.iges", "castle/castle_super_simple.iges",
                           "rocket/rocket.iges", "starship/starship_fall_simpler.igs",
                           "lamppost.iges", "tire.iges", "chicken/chicken_simple_closed.iges",
                           "grumpy.iges", "puft/puft_full_simpler.iges"};
    int failures = 0;
    for (size_t k = 0; k < sizeof names / sizeof *names; ++k) {
        if (only && !strstr(names[k], only)) continue;
        sem_error err;
        sem_model *m = NULL;
        double reference = 0;
        int built = 0;
        if (k < 4) {
            m = sem_model_create();
            if (k == 0) {
                sem_sphere_def def = sem_default_sphere_def();
                built = sem_primitive_sphere(m, &def, &err) == SEM_OK;
                reference = 4.0 / 3.0 * M_PI * def.radius * def.radius * def.radius;
            } else if (k == 1) {
                sem_torus_def def = sem_default_torus_def();
                built = sem_primitive_torus(m, &def, &err) == SEM_OK;
                reference = 2.0 * M_PI * M_PI * def.major * def.minor * def.minor;
            } else if (k == 2) {
                sem_cylinder_def def = sem_default_cylinder_def();
                built = sem_primitive_cylinder(m, &def, &err) == SEM_OK;
                reference = M_PI * def.radius * def.radius * def.height;
            } else {
                sem_box_def def = sem_default_box_def();
                built = sem_primitive_box(m, &def, &err) == SEM_OK;
                reference = def.size[0] * def.size[1] * def.size[2];
            }
        } else {
            char path[4096];
            snprintf(path, sizeof path, "%s/%s", dir, names[k]);
            if (!exists(path)) {
                fprintf(stderr, "study_volume: %s absent, skipped\n", path);
                continue;
            }
            built = sem_model_load(path, &m, &err) == SEM_OK;
            if (built && k == 4) {
                sem_raycast_scene *scene = NULL;
                built = sem_raycast_scene_build(m, 16, &scene, &err) == SEM_OK;
                if (built) reference = divergence_volume(m, scene);
                sem_raycast_scene_destroy(scene);
            } else if (built && k < 9) {
                reference = 5.0; /* the box beams: 5 x 1 x 1 */
            } else if (built && k >= 12 && !all_references) {
                reference = NAN;
            } else if (built) {
                double spread = 0;
                built = grid_reference(m, reference_rays, &reference, &spread);
                if (built)
                    printf("# %s: reference %.10g from %d^2 rays along x, y, z (largest difference "
                       "between axes %.2e relative)\n",
                       names[k], reference, reference_rays, spread / reference);
            }
        }
        if (!built) {
            fprintf(stderr, "study_volume: %s: %s\n", names[k], err.message);
            failures++;
            sem_model_destroy(m);
            continue;
        }
        for (int setting = -1; setting <= 3; ++setting) {
            sem_subray_settings st = sem_subray_default_settings();
            st.max_depth = setting < 0 ? 0 : setting;
            st.correct = setting >= 0;
            double volume, seconds;
            int points;
            long long rays;
            if (!default_quadrature(m, &st, repeat, &volume, &points, &rays, &seconds)) {
                failures++;
                continue;
            }
            printf("%-32s %d %d %7d %8lld %.10g %.10g %+.3e %.4f\n", names[k], st.max_depth,
                   st.correct, points, rays, volume, reference, volume / reference - 1, seconds);
            fflush(stdout);
        }
        sem_model_destroy(m);
    }
    return failures ? 1 : 0;
}

int main(int argc, char **argv)
{
    const char *dir_arg = NULL, *list = "2,3,4,6,8,12,16,24,32,48,64,96";
    int defaults = 0, repeat = 3, reference_rays = 400;
    const char *only = NULL;
    int all_references = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--models") && i + 1 < argc) dir_arg = argv[++i];
        else if (!strcmp(argv[i], "--rays") && i + 1 < argc) list = argv[++i];
        else if (!strcmp(argv[i], "--defaults")) defaults = 1;
        else if (!strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
        else if (!strcmp(argv[i], "--all-references")) all_references = 1;
        else if (!strcmp(argv[i], "--repeat") && i + 1 < argc) repeat = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--reference-rays") && i + 1 < argc) reference_rays = atoi(argv[++i]);
        else {
            fprintf(stderr,
                    "usage: %s [--models DIR] [--rays LIST] | --defaults [--models DIR] "
                    "[--repeat N] [--reference-rays N] [--only TEXT] [--all-references]\n",
                    argv[0]);
            return 2;
        }
    }
    if (defaults) {
        if (repeat < 1 || reference_rays < 1 || reference_rays > 4096) {
            fprintf(stderr, "study_volume: --repeat and --reference-rays must be in range\n");
            return 2;
        }
        return study_defaults(models_dir(dir_arg), repeat, reference_rays, only, all_references);
    }
    int rays[64], n_rays = 0;
    for (const char *p = list; *p && n_rays < 64;) {
        char *end;
        long v = strtol(p, &end, 10);
        if (end == p || v < 1 || v > 4096) {
            fprintf(stderr, "study_volume: bad --rays list %s\n", list);
            return 2;
        }
        rays[n_rays++] = (int)v;
        p = *end == ',' ? end + 1 : end;
    }
    printf("# shape rays quad_points volume reference relative_error\n");
    sem_error err;
    int failures = 0;
    /* sphere, exact volume */
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sem_raycast_scene *scene = NULL;
    if (sem_primitive_sphere(m, &sd, &err) != SEM_OK || sem_raycast_scene_build(m, 16, &scene, &err) != SEM_OK) {
        fprintf(stderr, "sphere: %s\n", err.message);
        failures++;
    } else
        study("sphere", m, 4.0 / 3.0 * M_PI, scene, rays, n_rays);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
    /* rounded cube, divergence theorem */
    char path[4096];
    snprintf(path, sizeof path, "%s/rounded_cube.iges", models_dir(dir_arg));
    m = NULL;
    scene = NULL;
    if (!exists(path)) fprintf(stderr, "study_volume: %s absent, skipped\n", path);
    else if (sem_model_load(path, &m, &err) != SEM_OK || sem_raycast_scene_build(m, 16, &scene, &err) != SEM_OK) {
        fprintf(stderr, "rounded_cube: %s\n", err.message);
        failures++;
    } else
        study("rounded_cube", m, divergence_volume(m, scene), scene, rays, n_rays);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
    return failures ? 1 : 0;
}
