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
 */
#include <math.h>
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

int main(int argc, char **argv)
{
    const char *dir_arg = NULL, *list = "2,3,4,6,8,12,16,24,32,48,64,96";
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--models") && i + 1 < argc) dir_arg = argv[++i];
        else if (!strcmp(argv[i], "--rays") && i + 1 < argc) list = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--models DIR] [--rays LIST]\n", argv[0]);
            return 2;
        }
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
