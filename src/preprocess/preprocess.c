/*
 * preprocess.c - composes the SEM preprocessing steps (paper Alg. 1) and owns the result.
 *
 * sem_preprocess runs the pure steps of steps.h in the paper's order
 *     sample -> (ray-cast scene) -> quadrature -> weights -> origins -> projection -> operators
 * and times them as the columns of Table 1:
 *     sample_s     boundary sampling (Sec. 5) only;
 *     scene_s      building the Embree scene (tessellation, BVH, orientation fix), reported
 *                  apart: it is shared by the quadrature and the weights;
 *     quad_s       the volume quadrature (Sec. 6.3), i.e. the ray casting of the paper's
 *                  "Quad" column;
 *     weights_s    blending weights (Sec. 6.1) + deformation origins (Sec. 6.2);
 *     build_pi_s   hierarchical projection Pi (Eq. 7);
 *     operators_s  Gamma, gradient rows, M, M_eps (Eq. 12-16), not a column of Table 1.
 *
 * The result is plain data (sem_discretization) that can be saved and loaded again. The file
 * is versioned and carries a hash of the model geometry and of every option that changes the
 * result, so a simulation never silently runs on operators of another model or setting.
 *
 * The file format of the result (sem_discretization_save / _load): disc_file.c.
 */
#include "sem/preprocess.h"

#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "disc_format.h"
#include "sem/limits.h"
#include "steps.h"
#include "util/fnv_hash.h"
#include "util/free_all.h"

/* ------------------------------------------------------------------------------------ */
/* options                                                                               */

sem_preprocess_options sem_default_preprocess_options(void)
{
    sem_preprocess_options o;
    memset(&o, 0, sizeof o);
    o.order = 2;
    o.spacing = 0.0;  /* automatic object-frame grid (quadrature step) */
    o.rays[0] = 0;
    o.rays[1] = 0;
    o.ray_axis = -1;
    o.points_per_interval = 0;
    o.alpha = 0.0;    /* with sparsity 0: alpha = 0.5 x bbox diagonal (weights step) */
    o.sparsity = 0.0;
    o.weight_threshold = 1e-4;
    o.origin_rule = SEM_ORIGINS_COUPLED;
    o.fit_rule = SEM_FIT_AUTO;
    o.gamma = 0.0;    /* default kappa E / L (operators step) */
    o.youngs_modulus = 1e6;
    o.tessellation = 16;
    o.threads = 0;
    o.q_space_operators = -1;
    return o;
}

/* Upper bounds that keep a typo from asking for unbounded memory or time. */
#define MAX_RAYS_PER_AXIS SEM_MAX_RAYS_PER_AXIS
#define MAX_POINTS_PER_INTERVAL SEM_MAX_POINTS_PER_INTERVAL
#define MAX_TESSELLATION 1024

static sem_status validate_options(const sem_preprocess_options *o, sem_error *err)
{
    if (o->order != 1 && o->order != 2)
        return sem_error_set(err, SEM_ERR_INVALID, "order must be 1 or 2 (got %d)", o->order);
    int explicit_grid = o->rays[0] != 0 || o->rays[1] != 0;
    if (explicit_grid)
        for (int k = 0; k < 2; ++k)
            if (o->rays[k] < 1 || o->rays[k] > MAX_RAYS_PER_AXIS)
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "rays must be between 1 and %d (got %d x %d)",
                                     MAX_RAYS_PER_AXIS, o->rays[0], o->rays[1]);
    if (o->ray_axis < -1 || o->ray_axis > 2)
        return sem_error_set(err, SEM_ERR_INVALID, "ray axis must be 0 (x), 1 (y) or 2 (z) (got %d)",
                             o->ray_axis);
    if (o->ray_axis >= 0 && !explicit_grid)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "a ray axis needs an explicit rays grid (without rays the grid is "
                             "laid in the object's own frame)");
    if (!isfinite(o->spacing) || o->spacing < 0)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "spacing must be > 0 (or 0 for the automatic one) (got %g)", o->spacing);
    if (o->spacing > 0 && explicit_grid)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "give a quadrature spacing or a rays grid, not both");
    if (o->points_per_interval < 0 || o->points_per_interval > MAX_POINTS_PER_INTERVAL)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "points per interval must be between 1 and %d, or 0 for as many as "
                             "the spacing holds (got %d)",
                             MAX_POINTS_PER_INTERVAL, o->points_per_interval);
    if (!isfinite(o->alpha) || o->alpha < 0)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "alpha must be > 0 (or 0 for the default rule) (got %g)", o->alpha);
    if (!isfinite(o->sparsity) || o->sparsity < 0 || o->sparsity >= 1)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "sparsity must be in (0,1) (or 0 for the default rule) (got %g)",
                             o->sparsity);
    if (!isfinite(o->weight_threshold) || o->weight_threshold < 0 || o->weight_threshold >= 1)
        return sem_error_set(err, SEM_ERR_INVALID, "weight threshold must be in [0,1) (got %g)",
                             o->weight_threshold);
    if (o->origin_rule != SEM_ORIGINS_COUPLED && o->origin_rule != SEM_ORIGINS_PAPER)
        return sem_error_set(err, SEM_ERR_INVALID, "origin rule must be 0 (coupled) or 1 (paper) (got %d)",
                             o->origin_rule);
    if (o->fit_rule != SEM_FIT_AUTO && o->fit_rule != SEM_FIT_PARTS && o->fit_rule != SEM_FIT_ORIGINS)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "fit rule must be 0 (auto), 1 (parts) or 2 (origins) (got %d)",
                             o->fit_rule);
    if (!isfinite(o->gamma) || o->gamma < 0)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "gamma must be > 0 (or 0 for the default E / L) (got %g)", o->gamma);
    if (!isfinite(o->youngs_modulus) || o->youngs_modulus <= 0)
        return sem_error_set(err, SEM_ERR_INVALID, "Young's modulus must be > 0 (got %g)",
                             o->youngs_modulus);
    if (o->tessellation < 1 || o->tessellation > MAX_TESSELLATION)
        return sem_error_set(err, SEM_ERR_INVALID, "tessellation must be between 1 and %d (got %d)",
                             MAX_TESSELLATION, o->tessellation);
    if (o->threads < 0)
        return sem_error_set(err, SEM_ERR_INVALID, "threads must be >= 0 (got %d)", o->threads);
    return SEM_OK;
}

/* ------------------------------------------------------------------------------------ */
/* hash (FNV-1a 64)                                                                      */

static void fnv_int(sem_fnv *f, int v)
{
    int32_t x = (int32_t)v;
    sem_fnv_bytes(f, &x, sizeof x);
}

/* -0.0 hashes as 0.0 so equal numbers give equal hashes. */
static void fnv_doubles(sem_fnv *f, const double *v, size_t n)
{
    if (!v) {
        fnv_int(f, -1);
        return;
    }
    for (size_t k = 0; k < n; ++k) {
        double x = v[k] == 0.0 ? 0.0 : v[k];
        sem_fnv_bytes(f, &x, sizeof x);
    }
}

static void hash_curve(sem_fnv *f, const sem_curve *c)
{
    fnv_int(f, c->degree);
    fnv_int(f, c->n_ctrl);
    if (c->n_ctrl <= 0 || c->degree < 0) return;
    fnv_doubles(f, c->knots, (size_t)(c->n_ctrl + c->degree + 1));
    fnv_doubles(f, c->ctrl, (size_t)c->n_ctrl * 3);
    fnv_doubles(f, c->weights, (size_t)c->n_ctrl);
    fnv_doubles(f, &c->t0, 1);
    fnv_doubles(f, &c->t1, 1);
}

static void hash_loop(sem_fnv *f, const sem_trim_loop *l)
{
    fnv_int(f, l->n_curves);
    for (int k = 0; k < l->n_curves && l->curves; ++k) hash_curve(f, &l->curves[k]);
}

/* Whether the structured solver takes the per-part model (the rule of SEM_SOLVER_AUTO,
 * sem_world_def_structured). */
static int per_part_structured(size_t n_ctrl, size_t n_parts, size_t m)
{
    return n_ctrl >= 2 * n_parts * m && 3 * n_parts * m <= SEM_MAX_STRUCTURED_COEFFICIENTS;
}

int sem_preprocess_shared_fit(const sem_model *model, const sem_preprocess_options *o)
{
    if (o->fit_rule == SEM_FIT_PARTS) return 0;
    if (o->fit_rule == SEM_FIT_ORIGINS) return 1;
    size_t n_ctrl = model ? sem_model_control_points(model) : 0;
    size_t n_parts = model ? (size_t)model->n_parts : 0, m = o->order == 1 ? 4 : 10;
    return !per_part_structured(n_ctrl, n_parts, m) && 3 * n_ctrl > SEM_MAX_PER_PART_Q_SPACE_DOFS;
}

int sem_preprocess_q_space(const sem_model *model, const sem_preprocess_options *o)
{
    if (o->q_space_operators >= 0) return o->q_space_operators > 2 ? 2 : o->q_space_operators;
    /* the rule of SEM_SOLVER_AUTO for a default world (sem_world_def_structured): shared
     * fits always take the structured solver */
    if (sem_preprocess_shared_fit(model, o)) return 0;
    size_t n_ctrl = model ? sem_model_control_points(model) : 0;
    size_t n_parts = model ? (size_t)model->n_parts : 0, m = o->order == 1 ? 4 : 10;
    return !per_part_structured(n_ctrl, n_parts, m);
}

unsigned long long sem_preprocess_hash(const sem_model *model, const sem_preprocess_options *o)
{
    sem_fnv f;
    sem_fnv_init(&f);
    sem_fnv_bytes(&f, sem_disc_magic, sizeof sem_disc_magic);
    fnv_int(&f, (int)SEM_DISC_FORMAT_VERSION);
    /* Revision of what the steps compute for the same input, for cached results that a
     * changed step would no longer give: 1 = the fits of groups whose weighted samples are
     * flat (projection.c, decide_floored; issue 29). */
    fnv_int(&f, 1);
    if (model) {
        fnv_int(&f, model->n_parts);
        for (int i = 0; i < model->n_parts; ++i) {
            const sem_part *p = &model->parts[i];
            const sem_surface *s = &p->surface;
            fnv_int(&f, s->degree_u);
            fnv_int(&f, s->degree_v);
            fnv_int(&f, s->n_u);
            fnv_int(&f, s->n_v);
            if (s->n_u > 0 && s->n_v > 0 && s->degree_u >= 0 && s->degree_v >= 0) {
                fnv_doubles(&f, s->knots_u, (size_t)(s->n_u + s->degree_u + 1));
                fnv_doubles(&f, s->knots_v, (size_t)(s->n_v + s->degree_v + 1));
                fnv_doubles(&f, s->ctrl, (size_t)s->n_u * s->n_v * 3);
                fnv_doubles(&f, s->weights, (size_t)s->n_u * s->n_v);
            }
            const double range[4] = {s->u0, s->u1, s->v0, s->v1};
            fnv_doubles(&f, range, 4);
            fnv_int(&f, p->has_outer);
            if (p->has_outer) hash_loop(&f, &p->outer);
            fnv_int(&f, p->n_holes);
            for (int h = 0; h < p->n_holes && p->holes; ++h) hash_loop(&f, &p->holes[h]);
        }
    }
    if (o) {
        /* every option that changes the result; not `threads` (results are the same up to
         * rounding order). */
        fnv_int(&f, o->order);
        fnv_int(&f, o->rays[0]);
        fnv_int(&f, o->rays[1]);
        fnv_int(&f, o->ray_axis);
        fnv_int(&f, o->points_per_interval);
        const double v[6] = {o->alpha, o->sparsity, o->weight_threshold, o->gamma,
                             o->youngs_modulus, o->spacing};
        fnv_doubles(&f, v, 6);
        fnv_int(&f, o->tessellation);
        if (o->rays[0] == 0 && o->rays[1] == 0 && o->points_per_interval == 0)
            fnv_int(&f, SEM_DEFAULT_QUADRATURE_REVISION);
        fnv_int(&f, o->origin_rule);
        fnv_int(&f, sem_preprocess_shared_fit(model, o));
        fnv_int(&f, sem_preprocess_q_space(model, o));
    }
    return (unsigned long long)f.h;
}

/* ------------------------------------------------------------------------------------ */
/* life cycle                                                                            */

void sem_discretization_destroy(sem_discretization *d)
{
    if (!d) return;
    SEM_FREE_ALL(d->part_ctrl_offset, d->sample_part, d->sample_uv, d->sample_X, d->sample_area, d->sample_seam);
    sem_csr_free(&d->J_hat);
    SEM_FREE_ALL(d->quad_X, d->quad_volume, d->quad_part, d->part_covered);
    sem_csr_free(&d->W);
    sem_csr_free(&d->W_samples);
    free(d->origin_X);
    free(d->part_origin);
    sem_csr_free(&d->Pi);
    sem_csr_free(&d->Gamma);
    sem_csr_free(&d->Grad);
    sem_csr_free(&d->Gamma_samples);
    sem_csr_free(&d->M);
    sem_csr_free(&d->M_eps);
    free(d);
}

/* All control points in one plane => every surface lies in it (convex hull property of
 * NURBS with positive weights) => the model encloses no volume. Checked up front so a single
 * planar patch gets a clear message whatever the ray caster makes of it. */
static int model_is_flat(const sem_model *model)
{
    double c[3] = {0, 0, 0}, C[9] = {0};
    size_t n = 0;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_surface *s = &model->parts[i].surface;
        for (int k = 0; k < s->n_u * s->n_v; ++k) {
            for (int e = 0; e < 3; ++e) {
                c[e] += s->ctrl[3 * k + e];
                lo[e] = fmin(lo[e], s->ctrl[3 * k + e]);
                hi[e] = fmax(hi[e], s->ctrl[3 * k + e]);
            }
            n++;
        }
    }
    if (n < 4) return 1;
    for (int e = 0; e < 3; ++e) c[e] /= (double)n;
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_surface *s = &model->parts[i].surface;
        for (int k = 0; k < s->n_u * s->n_v; ++k) {
            double d[3];
            for (int e = 0; e < 3; ++e) d[e] = s->ctrl[3 * k + e] - c[e];
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b) C[3 * a + b] += d[a] * d[b];
        }
    }
    double diag2 = 0;
    for (int e = 0; e < 3; ++e) diag2 += (hi[e] - lo[e]) * (hi[e] - lo[e]);
    if (!(diag2 > 0)) return 1;
    /* smallest eigenvalue of the scatter matrix by the closed form for symmetric 3x3
     * (Smith 1961): flat when the spread normal to the best plane is ~0. */
    double p1 = C[1] * C[1] + C[2] * C[2] + C[5] * C[5];
    double q = (C[0] + C[4] + C[8]) / 3.0;
    double p2 = (C[0] - q) * (C[0] - q) + (C[4] - q) * (C[4] - q) + (C[8] - q) * (C[8] - q) + 2 * p1;
    double lmin;
    if (p2 <= 0) {
        lmin = q;
    } else {
        double p = sqrt(p2 / 6.0), B[9];
        for (int k = 0; k < 9; ++k) B[k] = (C[k] - (k % 4 == 0 ? q : 0.0)) / p;
        double detB = B[0] * (B[4] * B[8] - B[5] * B[7]) - B[1] * (B[3] * B[8] - B[5] * B[6]) +
                      B[2] * (B[3] * B[7] - B[4] * B[6]);
        double r = fmax(-1.0, fmin(1.0, detB / 2.0));
        double phi = acos(r) / 3.0;
        lmin = q + 2 * p * cos(phi + 2.0 * M_PI / 3.0);
    }
    /* lmin / n is the mean squared distance to the best plane */
    return lmin / (double)n <= 1e-20 * diag2;
}

/* Knot spans in use along one direction. */
static double spans_in_use(int degree, int n, const double *knots, double t0, double t1)
{
    double spans = 1;
    for (int i = degree + 1; i < n; ++i)
        spans += knots[i] > knots[i - 1] && knots[i] > t0 && knots[i] < t1;
    return spans;
}

/* Triangles of the ray-casting tessellation at `tessellation` cells per knot span. */
static double tessellation_triangles(const sem_model *model, int tessellation)
{
    double triangles = 0;
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_surface *s = &model->parts[i].surface;
        double su = spans_in_use(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1);
        double sv = spans_in_use(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1);
        triangles += 2.0 * su * sv * tessellation * tessellation;
    }
    return triangles;
}

/* The tessellation is per knot span, so a model with many small spans (a refined model:
 * `sem refine`) would get a mesh far finer than its shape needs; above SEM_MAX_TRIANGLES the
 * cells per span are lowered until the mesh has about SEM_MAX_TRIANGLES / 4 triangles (at
 * least one cell per span). */
static int fitted_tessellation(const sem_model *model, int tessellation)
{
    double t = tessellation_triangles(model, tessellation);
    if (t <= SEM_MAX_TRIANGLES) return tessellation;
    int fit = (int)floor(tessellation * sqrt(0.25 * SEM_MAX_TRIANGLES / t));
    return fit < 1 ? 1 : fit;
}

/* What the settings and the model would make the steps build, estimated before any of it
 * is built (sem/limits.h): a small file can hold a surface of degree 31 whose boundary
 * samples each touch 1024 control points (3.6 GB of J-hat for a 70 KB file), and a ray grid
 * or tessellation can be set to billions of rays or triangles. The genuine size of a model
 * (many parts coupled by the weights) is not limited here. */
static sem_status check_sizes(const sem_model *model, const sem_preprocess_options *o,
                              sem_error *err)
{
    double entries = 0, triangles = 0, ctrl = 0;
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_part *part = &model->parts[i];
        const sem_surface *s = &part->surface;
        int trimmed = part->has_outer || part->n_holes > 0;
        double su = spans_in_use(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1);
        double sv = spans_in_use(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1);
        /* sampling.c: (degree + 1) Lobatto points per span, at least 24 (+ a span's worth)
         * per direction on a trimmed part; each sample holds (p + 1)(q + 1) basis values */
        double pu = s->degree_u + 1 < 2 ? 2 : s->degree_u + 1;
        double pv = s->degree_v + 1 < 2 ? 2 : s->degree_v + 1;
        double nu = su * pu, nv = sv * pv;
        if (trimmed) {
            nu = fmax(nu, 24 + 2 * pu);
            nv = fmax(nv, 24 + 2 * pv);
        }
        entries += nu * nv * (s->degree_u + 1) * (s->degree_v + 1);
        ctrl += (double)s->n_u * s->n_v;
    }
    if (sem_preprocess_q_space(model, o) && ctrl > SEM_MAX_PREPROCESS_CONTROL_POINTS)
        return sem_error_set(err, SEM_ERR_INVALID, "model has %.0f control points; preprocessing "
                                                   "with the q-space operators takes at most %d "
                                                   "(limit SEM_MAX_PREPROCESS_CONTROL_POINTS)",
                             ctrl, SEM_MAX_PREPROCESS_CONTROL_POINTS);
    if (sem_preprocess_shared_fit(model, o) && model->n_parts > SEM_MAX_SHARED_FIT_PARTS)
        return sem_error_set(err, SEM_ERR_INVALID, "model has %d parts; preprocessing with shared "
                                                   "fits takes at most %d (limit "
                                                   "SEM_MAX_SHARED_FIT_PARTS)",
                             model->n_parts, SEM_MAX_SHARED_FIT_PARTS);
    if (ctrl > SEM_MAX_STRUCTURED_CONTROL_POINTS)
        return sem_error_set(err, SEM_ERR_INVALID, "model has %.0f control points; preprocessing "
                                                   "takes at most %d (limit "
                                                   "SEM_MAX_STRUCTURED_CONTROL_POINTS)",
                             ctrl, SEM_MAX_STRUCTURED_CONTROL_POINTS);
    if (entries > SEM_MAX_BOUNDARY_ENTRIES)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "boundary sampling would store %.3g basis values (samples times "
                             "the (degree + 1)^2 control points each touches; limit "
                             "SEM_MAX_BOUNDARY_ENTRIES = %.3g): lower the surfaces' degree or "
                             "knot count",
                             entries, (double)SEM_MAX_BOUNDARY_ENTRIES);
    int tess = fitted_tessellation(model, o->tessellation);
    triangles = tessellation_triangles(model, tess);
    if (triangles > SEM_MAX_TRIANGLES)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "tessellation %d would make %.3g triangles (limit "
                             "SEM_MAX_TRIANGLES = %.3g): the model has too many knot spans",
                             tess, triangles, (double)SEM_MAX_TRIANGLES);
    double points = (double)o->rays[0] * o->rays[1] * o->points_per_interval;
    if (points > SEM_MAX_QUADRATURE_POINTS)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "rays %d x %d with %d points per interval would make at least %.3g "
                             "quadrature points (limit SEM_MAX_QUADRATURE_POINTS = %.3g)",
                             o->rays[0], o->rays[1], o->points_per_interval, points,
                             (double)SEM_MAX_QUADRATURE_POINTS);
    return SEM_OK;
}

sem_status sem_preprocess(const sem_model *model, const sem_preprocess_options *options,
                          sem_discretization **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!model || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_preprocess: NULL argument");
    sem_preprocess_options o = options ? *options : sem_default_preprocess_options();
    sem_status st = validate_options(&o, err);
    if (st != SEM_OK) return st;
    if (model->n_parts <= 0) return sem_error_set(err, SEM_ERR_INVALID, "model has no parts");
    for (int i = 0; i < model->n_parts; ++i) {
        sem_error e2;
        if (sem_surface_validate(&model->parts[i].surface, &e2) != SEM_OK)
            return sem_error_set(err, SEM_ERR_INVALID, "part %d: %s", i, e2.message);
    }
    if (model_is_flat(model))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "model encloses no volume (all its surfaces lie in one plane)");
    st = check_sizes(model, &o, err);
    if (st != SEM_OK) return st;

    sem_discretization *d = calloc(1, sizeof *d);
    sem_raycast_scene *scene = NULL;
    if (!d) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    d->order = o.order;
    d->n_basis = o.order == 1 ? 4 : 10;
    d->model_hash = sem_preprocess_hash(model, &o);
    o.tessellation = fitted_tessellation(model, o.tessellation);
    o.q_space_operators = sem_preprocess_q_space(model, &o);
    d->shared_fit = sem_preprocess_shared_fit(model, &o);

    double t0 = omp_get_wtime();
    st = sem_step_sample(model, o.threads, d, err);
    if (st != SEM_OK) goto done;
    double t1 = omp_get_wtime();
    d->timings.sample_s = t1 - t0;

    st = sem_raycast_scene_build_threads(model, o.tessellation, o.threads, &scene, err);
    if (st != SEM_OK) goto done;
    /* the object's frame (principal axes of the surface) belongs to the shared setup: the
     * quadrature cells and the default alpha and gamma lengths are measured in it */
    st = sem_step_frame(scene, d, err);
    if (st != SEM_OK) goto done;
    double t1b = omp_get_wtime();
    d->timings.scene_s = t1b - t1;
    st = sem_step_quadrature(model, scene, &o, d, err);
    if (st != SEM_OK) goto done;
    double t2 = omp_get_wtime();
    d->timings.quad_s = t2 - t1b;
    if (d->n_quad <= 0 || !(d->volume > 0)) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "model encloses no volume (no ray of the quadrature grid found an "
                           "inside)");
        goto done;
    }

    st = sem_step_weights(model, scene, &o, d, err);
    if (st != SEM_OK) goto done;
    int n_covered = 0;
    st = sem_cover_unweighted_parts(d, &n_covered, err);
    if (st == SEM_OK) st = sem_step_point_materials(scene, d, err);
    if (st != SEM_OK) goto done;
    if (o.origin_rule == SEM_ORIGINS_PAPER) {
        st = sem_step_origins(model, d, err);
        if (st == SEM_OK) st = sem_merge_degenerate_origins(d, err);
    } else {
        st = sem_step_origins_coupled(d, err);
    }
    int n_ties = 0;
    if (st == SEM_OK) st = sem_tie_translation_components(d, &n_ties, err);
    if (st != SEM_OK) goto done;
    double t3 = omp_get_wtime();
    d->timings.weights_s = t3 - t2;

    st = sem_step_projection(&o, d, err);
    if (st != SEM_OK) goto done;
    double t4 = omp_get_wtime();
    d->timings.build_pi_s = t4 - t3;

    st = sem_step_operators(&o, d, err);
    if (st != SEM_OK) goto done;
    d->timings.operators_s = omp_get_wtime() - t4;

done:
    sem_raycast_scene_destroy(scene);
    if (st != SEM_OK) {
        sem_discretization_destroy(d);
        return st;
    }
    *out = d;
    return SEM_OK;
}
