/*
 * validation.c - the static cantilever of the deflection study (paper Fig. 10), the FEM
 * reference file, Table 1 settings and a log-log fit (see validation.h).
 */
#include "bench/validation.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>

#include "sem/simulation.h"

int sem_bench_is_dir(const char *path)
{
    struct stat st;
    return path && stat(path, &st) == 0 && S_ISDIR(st.st_mode);
}

const char *sem_bench_models_dir(void)
{
    const char *env = getenv("SEM_SHARED_MODELS");
    if (sem_bench_is_dir(env)) return env;
    if (sem_bench_is_dir("../shared/models")) return "../shared/models";
    if (sem_bench_is_dir("../../shared/models")) return "../../shared/models";
    return NULL;
}

sem_cantilever_settings sem_default_cantilever_settings(void)
{
    sem_cantilever_settings s;
    s.order = 2;
    s.rays[0] = s.rays[1] = 3;
    s.points_per_interval = 100;
    s.alpha = 0.501;
    s.gamma = 0.0;
    s.material = SEM_MATERIAL_NEOHOOKEAN;
    s.density = 1000.0;
    s.youngs_modulus = 1e6;
    s.poisson_ratio = 0.45;
    s.gravity = 10.0;
    s.threads = 0;
    s.projected_hessian = 0;
    s.blend = 0.0;
    s.seams = SEM_SEAMS_PAPER;
    return s;
}

sem_preprocess_options sem_cantilever_preprocess_options(const sem_cantilever_settings *s)
{
    sem_preprocess_options po = sem_default_preprocess_options();
    po.order = s->order;
    po.rays[0] = s->rays[0];
    po.rays[1] = s->rays[1];
    po.points_per_interval = s->points_per_interval;
    po.alpha = s->alpha;
    po.youngs_modulus = s->youngs_modulus;
    po.threads = s->threads;
    po.origin_rule = SEM_ORIGINS_PAPER; /* the authors' settings: the paper's origins (Eq. 10) */
    if (s->gamma > 0) po.gamma = s->gamma;
    return po;
}

sem_status sem_cantilever_material(const sem_cantilever_settings *s, sem_material *m,
                                   sem_error *err)
{
    sem_material t = sem_default_material();
    t.type = s->material;
    t.density = s->density;
    t.youngs_modulus = s->youngs_modulus;
    t.poisson_ratio = s->poisson_ratio;
    sem_status st = sem_material_init(&t, err);
    if (st == SEM_OK) *m = t;
    return st;
}

void sem_cantilever_clamp(const double *q0, size_t nc, unsigned char *pin)
{
    double xmin = INFINITY, xmax = -INFINITY;
    for (size_t c = 0; c < nc; ++c) {
        xmin = fmin(xmin, q0[3 * c]);
        xmax = fmax(xmax, q0[3 * c]);
    }
    for (size_t c = 0; c < nc; ++c) pin[c] = q0[3 * c] < xmin + 1e-9 * fmax(1.0, xmax - xmin);
}

int sem_parse_count_list(const char *text, int max, int *out, int cap)
{
    int n = 0;
    const char *p = text;
    while (*p) {
        char *end;
        long v = strtol(p, &end, 10);
        if (end == p || v < 1 || v > max || n == cap || (*end && *end != ',')) return -1;
        out[n++] = (int)v;
        p = *end ? end + 1 : end;
    }
    return n;
}

double sem_cantilever_tip(const sem_model *m, const double *q0, const double *q)
{
    size_t nc = sem_model_control_points(m);
    double xmax = -INFINITY, xmin = INFINITY;
    for (size_t c = 0; c < nc; ++c) {
        xmax = fmax(xmax, q0[3 * c]);
        xmin = fmin(xmin, q0[3 * c]);
    }
    double tol = 1e-9 * fmax(1.0, xmax - xmin);
    size_t *off = malloc((size_t)(m->n_parts + 1) * sizeof *off);
    if (!off) return NAN;
    sem_model_part_offsets(m, off);
    double s = 0;
    long n = 0;
    for (int p = 0; p < m->n_parts; ++p) {
        int cap = 1;
        for (size_t c = off[p]; c < off[p + 1] && cap; ++c) cap = q0[3 * c] > xmax - tol;
        if (!cap) continue;
        for (size_t c = off[p]; c < off[p + 1]; ++c) {
            s += q0[3 * c + 2] - q[3 * c + 2];
            n++;
        }
    }
    if (n == 0) /* no end cap: every control point at the end */
        for (size_t c = 0; c < nc; ++c)
            if (q0[3 * c] > xmax - tol) {
                s += q0[3 * c + 2] - q[3 * c + 2];
                n++;
            }
    free(off);
    return n ? s / (double)n : NAN;
}

sem_status sem_cantilever_solve(const sem_model *model, const sem_cantilever_settings *s,
                                sem_cantilever_result *out, sem_error *err)
{
    sem_preprocess_options po = sem_cantilever_preprocess_options(s);
    double t0 = omp_get_wtime();
    sem_discretization *d = NULL;
    sem_status st = sem_preprocess(model, &po, &d, err);
    if (st != SEM_OK) return st;
    double t1 = omp_get_wtime();

    size_t nc = sem_model_control_points(model);
    double *q0 = malloc(3 * nc * sizeof *q0);
    unsigned char *pin = calloc(nc ? nc : 1, 1);
    sem_world *w = NULL;
    if (!q0 || !pin) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    sem_model_get_q(model, q0);
    sem_cantilever_clamp(q0, nc, pin);

    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -s->gravity;
    wd.integrator = SEM_STATIC;
    wd.threads = s->threads;
    wd.advanced.projected_hessian = s->projected_hessian;
    w = sem_world_create(&wd, err);
    if (!w) {
        st = err ? err->status : SEM_ERR_INVALID;
        goto done;
    }
    sem_object_def od = sem_default_object_def();
    od.model = model;
    od.disc = d;
    if ((st = sem_cantilever_material(s, &od.material, err)) != SEM_OK) goto done;
    od.gamma = s->gamma;
    od.blend = s->blend;
    od.seams = s->seams;
    od.pinned = pin;
    if (sem_world_add_object(w, &od, err) < 0) {
        st = err ? err->status : SEM_ERR_INVALID;
        goto done;
    }
    st = sem_world_solve_static(w, err);
    if (st != SEM_OK) goto done;
    double t2 = omp_get_wtime();
    out->parts = model->n_parts;
    out->dofs = sem_world_object_dofs(w, 0);
    out->quad_points = d->n_quad;
    out->volume = d->volume;
    out->tip_deflection = sem_cantilever_tip(model, q0, sem_world_object_q(w, 0));
    out->newton_iterations = sem_world_last_iterations(w);
    out->exact_hessian_fallbacks = sem_world_get_counters(w).exact_hessian_fallbacks;
    out->preprocess_s = t1 - t0;
    out->solve_s = t2 - t1;
done:
    sem_world_destroy(w);
    free(pin);
    free(q0);
    sem_discretization_destroy(d);
    return st;
}

double sem_fem_reference_find(const char *path, const char *who)
{
    const char *candidates[] = {path, "validation/fem_cantilever.json",
                                "../validation/fem_cantilever.json"};
    double fem = 0;
    struct stat st;
    for (int k = 0; k < 3 && fem <= 0; ++k) {
        sem_error err;
        if (candidates[k] && stat(candidates[k], &st) == 0 &&
            sem_fem_reference_read(candidates[k], &fem, &err) != SEM_OK)
            fprintf(stderr, "%s: %s\n", who, err.message);
    }
    return fem;
}

sem_status sem_fem_reference_read(const char *path, double *tip_deflection, sem_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return sem_error_set(err, SEM_ERR_IO, "%s: cannot open", path);
    char buf[1 << 16];
    size_t n = fread(buf, 1, sizeof buf - 1, f);
    fclose(f);
    buf[n] = '\0';
    cJSON *j = cJSON_Parse(buf);
    if (!j) return sem_error_set(err, SEM_ERR_PARSE, "%s: not a JSON document", path);
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(j, "tip_deflection_m");
    sem_status st = SEM_OK;
    if (!cJSON_IsNumber(t) || !isfinite(t->valuedouble) || t->valuedouble <= 0)
        st = sem_error_set(err, SEM_ERR_PARSE, "%s: no positive tip_deflection_m", path);
    else
        *tip_deflection = t->valuedouble;
    cJSON_Delete(j);
    return st;
}

double sem_loglog_fit(const double *x, const double *y, int n, double *c)
{
    double sx = 0, sy = 0, sxx = 0, sxy = 0;
    int k = 0;
    for (int i = 0; i < n; ++i) {
        if (!(x[i] > 0) || !(y[i] > 0)) continue;
        double lx = log(x[i]), ly = log(y[i]);
        sx += lx;
        sy += ly;
        sxx += lx * lx;
        sxy += lx * ly;
        k++;
    }
    double den = k * sxx - sx * sx;
    if (k < 2 || den == 0) return NAN;
    double p = (k * sxy - sx * sy) / den;
    if (c) *c = exp((sy - p * sx) / k);
    return p;
}

/* Paper's Table 1 (models README); settings from the authors' example scripts. The tire
 * has the paper's two materials: tread rubber, and steel for its hub, parts 0-6 of
 * tire.iges (the rim and axle surfaces, all within radius 0.89 of the axis; the tread and
 * sidewall parts 7-46 reach radius 1.6). */
const sem_table1_row sem_table1[] = {
    {"Rocket (soft)", "rocket/rocket.iges", 1.27e3, 7e6, 0.40, 2, {9, 15}, 5, 10, 648,
     2.83e-2, 5.62e-3, 5.58e-1, 6.83e-2, 1.26, 100, 0, 0, 0, 0},
    {"Rocket (stiff)", "rocket/rocket.iges", 8e3, 2e11, 0.32, 1, {5, 15}, 5, 10, 648,
     2.56e-2, 5.97e-3, 4.59e-1, 3.48e-2, 9.99e-2, 100, 0, 0, 0, 0},
    {"Starship", "starship/starship_fall_simpler.igs", 8e3, 2e11, 0.32, 1, {10, 10}, 5, 0.7, 750,
     6.78e-2, 1.52e-2, 8.50e-1, 9.52e-2, 6.95e-1, 100, 0, 0, 0, 0},
    {"Beam (twist)", "beams/beam_cmp3_b.iges", 1e3, 1e6, 0.45, 2, {3, 3}, 15, 0.51, 756,
     1.97e-1, 2.25e-2, 1.35, 5.16e-1, 3.95, 46.94, 0, 0, 0, 0},
    {"Lamppost", "lamppost.iges", 3e3, 1e6, 0.40, 2, {5, 35}, 2, 0.8, 942,
     1.28e-1, 1.27e-2, 1.89, 1.07, 2.22, 56.38, 0, 0, 0, 0},
    {"Tire", "tire.iges", 2e3, 1e6, 0.47, 2, {9, 9}, 4, 1.1, 1404,
     1.74e-1, 1.32e-2, 1.82, 6.79e-1, 12.8, 92.5, 7, 3e3, 7e9, 0.35},
    {"Chicken", "chicken/chicken_simple_closed.iges", 1.27e3, 1e4, 0.47, 2, {6, 6}, 3, 0, 1773,
     9.19e-1, 2.31e-2, 3.38, 1.91, 10.8, 100, 0, 0, 0, 0},
    {"Coffee mug (soft)", "mugs/mug_trimmed_complex.iges", 1e3, 1e4, 0.47, 2, {10, 10}, 5, 0, 1800,
     4.18e-1, 2.87e-2, 3.77, 2.08, 11.9, 100, 0, 0, 0, 0},
    {"Coffee mug (stiff)", "mugs/mug_trimmed_complex.iges", 1e3, 4e7, 0.40, 2, {10, 10}, 5, 0, 1800,
     4.15e-2, 1.17e-2, 6.86e-1, 1.09e-1, 5.00e-1, 81.42, 0, 0, 0, 0},
    {"Castle", "castle/castle_super_simple.iges", 1.27e3, 2e3, 0.45, 2, {12, 15}, 12, 0, 1872,
     4.84e-1, 1.44e-2, 1.52, 5.78e-1, 8.02, 100, 0, 0, 0, 0},
    {"Grumpy", "grumpy.iges", 1e3, 1e4, 0.40, 2, {10, 10}, 5, 0, 2010,
     2.92e-1, 1.23e-2, 2.29, 2.89, 6.02, 84.15, 0, 0, 0, 0},
    {"Astronaut (soft)", "puft/puft_full_simpler.iges", 1.27e3, 1e6, 0.47, 2, {8, 15}, 3, 0, 3609,
     2.47, 6.71e-2, 11.3, 10.9, 14.1, 49.04, 0, 0, 0, 0},
};

const int sem_table1_count = (int)(sizeof sem_table1 / sizeof sem_table1[0]);

sem_preprocess_options sem_table1_options(const sem_table1_row *r)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    o.order = r->order;
    o.rays[0] = r->rays[0];
    o.rays[1] = r->rays[1];
    o.points_per_interval = r->points_per_interval;
    o.alpha = r->alpha;
    o.youngs_modulus = r->youngs_modulus;
    o.tessellation = 8;
    o.origin_rule = SEM_ORIGINS_PAPER; /* the paper's min-cost flow (Eq. 10) */
    return o;
}

void sem_timings_keep_fastest(sem_preprocess_timings *best, const sem_preprocess_timings *t)
{
    best->sample_s = fmin(best->sample_s, t->sample_s);
    best->scene_s = fmin(best->scene_s, t->scene_s);
    best->quad_s = fmin(best->quad_s, t->quad_s);
    best->weights_s = fmin(best->weights_s, t->weights_s);
    best->build_pi_s = fmin(best->build_pi_s, t->build_pi_s);
    best->operators_s = fmin(best->operators_s, t->operators_s);
}
