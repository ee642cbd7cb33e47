/*
 * validation.h - helpers shared by the validation studies (bench/study_*.c), `sem bench`
 * and tests/test_validation.c: the static cantilever of the deflection study (paper Fig. 10),
 * the recorded FEM reference (validation/fem_cantilever.json, tools/fem/cantilever.py),
 * the Table 1 rows with the authors' settings and a least-squares fit on log-log axes.
 *
 * Not part of the public API (src/ include path only).
 */
#ifndef SEM_BENCH_VALIDATION_H
#define SEM_BENCH_VALIDATION_H

#include "sem/material.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/status.h"

/* The deflection study's setup: 5 x 1 x 1 m beam clamped at x = 0 (control points with
 * x = 0 pinned), gravity along -z, quadratic SEM with the authors' ray settings. */
typedef struct sem_cantilever_settings {
    int order;               /* 2 */
    int rays[2];             /* 3 x 3 */
    int points_per_interval; /* 100 */
    double alpha;            /* 0.501 */
    double gamma;            /* error stiffness; <= 0: the preprocessing default (kappa E / L) */
    double blend;            /* sem_object_def.blend; 0: none, as in the paper */
    int seams;               /* sem_object_def.seams; SEM_SEAMS_PAPER, as in the paper */
    sem_material_type material; /* neo-Hookean (the paper's) */
    double density, youngs_modulus, poisson_ratio; /* 1000, 1e6, 0.45 */
    double gravity;          /* 10 m/s^2 along -z */
    int threads;             /* 0: OpenMP default */
    int projected_hessian;   /* 1: Newton without the exact-Hessian switch (sem_world_advanced) */
} sem_cantilever_settings;

sem_cantilever_settings sem_default_cantilever_settings(void);

typedef struct sem_cantilever_result {
    int parts, dofs, quad_points;
    double volume;
    double tip_deflection;   /* mean -u_z of the free end cap's control points, m */
    int newton_iterations;
    long exact_hessian_fallbacks; /* the world's counter (sem_world_get_counters) */
    double preprocess_s, solve_s;
} sem_cantilever_result;

/* The preprocessing options of the settings (order, rays, points per interval, alpha, E,
 * gamma when > 0, threads). */
sem_preprocess_options sem_cantilever_preprocess_options(const sem_cantilever_settings *s);
/* The material of the settings (type, density, E, nu; Lame parameters set). */
sem_status sem_cantilever_material(const sem_cantilever_settings *s, sem_material *m,
                                   sem_error *err);
/* The clamp: pin[c] = 1 for the control points at the smallest x of the rest positions q0
 * (3 per point, nc points), 0 for the others. */
void sem_cantilever_clamp(const double *q0, size_t nc, unsigned char *pin);
/* Tip deflection: mean -u_z over the control points of the parts lying entirely at the
 * largest x (every control point at that x when no part does); NaN if none. */
double sem_cantilever_tip(const sem_model *m, const double *q0, const double *q);

/* Positive integers separated by commas ("1,2,10"), each <= max, into out (at most cap);
 * returns how many, or -1 for a malformed or too long list. */
int sem_parse_count_list(const char *text, int max, int *out, int cap);

/* Preprocesses the model with the settings and solves statics. The free end is the part
 * whose control points all lie at the largest x (the end cap; for a uniform biquadratic
 * Bezier cap the mean of its control points is exactly its area-weighted mean, since each
 * degree-2 Bernstein polynomial integrates to 1/3). */
sem_status sem_cantilever_solve(const sem_model *model, const sem_cantilever_settings *s,
                                sem_cantilever_result *out, sem_error *err);

/* Reads "tip_deflection_m" of the FEM reference file written by tools/fem/cantilever.py. */
sem_status sem_fem_reference_read(const char *path, double *tip_deflection, sem_error *err);
/* The FEM tip deflection from the first readable of path (may be NULL),
 * validation/fem_cantilever.json and ../validation/fem_cantilever.json; files that do not
 * exist are skipped, each unreadable one is reported on stderr after `who`. 0 if none. */
double sem_fem_reference_find(const char *path, const char *who);

/* Least squares y = c x^p on log-log axes over the points with x, y > 0: returns p, sets
 * *c (may be NULL). NaN with fewer than 2 usable points. */
double sem_loglog_fit(const double *x, const double *y, int n, double *c);

/* 1 when path (may be NULL) names a folder. */
int sem_bench_is_dir(const char *path);

/* The shared models folder: $SEM_SHARED_MODELS, else ../shared/models, else
 * ../../shared/models (the first that is a folder); NULL when none is. */
const char *sem_bench_models_dir(void);

/* Table 1 of the paper with the authors' settings (models README) and the paper's figures. */
typedef struct sem_table1_row {
    const char *example, *file;
    double density, youngs_modulus, poisson_ratio;
    int order, rays[2], points_per_interval;
    double alpha;            /* 0: the default rule */
    int paper_q;
    double paper_sample, paper_quad, paper_weights, paper_build_pi, paper_step, paper_nnz;
    /* A second material for parts 0 .. inner_parts - 1 (the tire's steel hub; a quadrature
     * point takes the material of the innermost part it lies in); 0: one material. */
    int inner_parts;
    double inner_density, inner_youngs_modulus, inner_poisson_ratio;
} sem_table1_row;

extern const sem_table1_row sem_table1[];
extern const int sem_table1_count;

/* The preprocessing options of a row: its order, rays, points per interval, alpha and E (for
 * the default gamma), and tessellation 8 (the ray casts' triangulation; the sphere-accuracy
 * default 16 is not an authors' setting and not needed here). */
sem_preprocess_options sem_table1_options(const sem_table1_row *r);

/* Keeps in *best the fastest of each phase seen so far (*best starts as the first run). */
void sem_timings_keep_fastest(sem_preprocess_timings *best, const sem_preprocess_timings *t);

#endif
