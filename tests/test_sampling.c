/* test_sampling.c - boundary samples (paper Sec. 5): areas, counts, J-hat, trims. */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "preprocess/steps.h"
#include "test_util.h"

/* A planar rectangle o + s e1 + t e2, s,t in [0,1], as a clamped uniform B-spline of the
 * given degree with `spans` knot spans per direction. Control points at the Greville
 * abscissae reproduce the linear map exactly. */
static void planar_part(sem_part *part, const double o[3], const double e1[3],
                        const double e2[3], int degree, int spans_u, int spans_v)
{
    memset(part, 0, sizeof *part);
    int n_u = degree + spans_u, n_v = degree + spans_v;
    sem_surface *s = &part->surface;
    sem_surface_alloc(s, degree, degree, n_u, n_v);
    for (int pass = 0; pass < 2; ++pass) {
        int n = pass ? n_v : n_u, spans = pass ? spans_v : spans_u;
        double *k = pass ? s->knots_v : s->knots_u;
        for (int i = 0; i < n + degree + 1; ++i) {
            int j = i - degree;
            k[i] = j < 0 ? 0.0 : (j > spans ? 1.0 : (double)j / spans);
        }
    }
    for (int j = 0; j < n_v; ++j)
        for (int i = 0; i < n_u; ++i) {
            double gu = 0, gv = 0;
            for (int r = 1; r <= degree; ++r) {
                gu += s->knots_u[i + r];
                gv += s->knots_v[j + r];
            }
            gu /= degree;
            gv /= degree;
            for (int d = 0; d < 3; ++d) s->ctrl[3 * (i + n_u * j) + d] = o[d] + gu * e1[d] + gv * e2[d];
        }
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
}

/* Box [0,a] x [0,b] x [0,c] as 6 planar patches. */
static sem_model *box_model(const double size[3], int degree, int spans)
{
    sem_model *m = sem_model_create();
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            double o[3] = {0, 0, 0}, e1[3] = {0, 0, 0}, e2[3] = {0, 0, 0};
            o[axis] = side * size[axis];
            e1[a1] = size[a1];
            e2[a2] = size[a2];
            sem_part part;
            planar_part(&part, o, e1, e2, degree, spans, spans + 1);
            sem_model_take_part(m, &part, NULL);
        }
    return m;
}

static void discretization_free(sem_discretization *d)
{
    free(d->part_ctrl_offset);
    free(d->sample_part);
    free(d->sample_uv);
    free(d->sample_X);
    free(d->sample_area);
    free(d->sample_seam);
    sem_csr_free(&d->J_hat);
    memset(d, 0, sizeof *d);
}

static double total_area(const sem_discretization *d)
{
    double a = 0;
    for (int s = 0; s < d->n_samples; ++s) a += d->sample_area[s];
    return a;
}

/* J-hat q0 reproduces the stored sample positions. */
static double j_hat_error(const sem_model *m, const sem_discretization *d)
{
    double *q = malloc(3 * sem_model_control_points(m) * sizeof *q);
    double *x = malloc(3 * (size_t)d->n_samples * sizeof *x);
    sem_model_get_q(m, q);
    sem_csr_multiply(&d->J_hat, q, 3, x);
    double e = 0;
    for (int k = 0; k < 3 * d->n_samples; ++k) e = fmax(e, fabs(x[k] - d->sample_X[k]));
    free(q);
    free(x);
    return e;
}

static void test_box_area_and_counts(void)
{
    const double size[3] = {1.5, 2.0, 0.7};
    sem_model *m = box_model(size, 3, 2);
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_error err;
    sem_status st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st != SEM_OK) return;
    double exact = 2 * (size[0] * size[1] + size[1] * size[2] + size[2] * size[0]);
    CHECK_NEAR(total_area(&d), exact, 1e-12);
    /* parts x spans x (p+1)^2: 6 x (2 x 3) x 16 */
    CHECK(d.n_samples == 6 * 6 * 16, "n_samples %d", d.n_samples);
    CHECK(d.n_parts == 6, "n_parts %d", d.n_parts);
    CHECK(d.n_ctrl == 6 * 5 * 6, "n_ctrl %d", d.n_ctrl);
    CHECK(d.part_ctrl_offset[3] == 3 * 30, "offset %d", d.part_ctrl_offset[3]);
    CHECK(d.J_hat.n_rows == d.n_samples && d.J_hat.n_cols == d.n_ctrl, "J-hat shape");
    CHECK_NEAR(j_hat_error(m, &d), 0.0, 1e-14);
    /* every face's own area; samples in part order; each J row sums to 1 (partition of unity)
     * and references only its part's control points */
    double face[6] = {0};
    int ordered = 1, own_columns = 1;
    double row_sum_err = 0;
    for (int s = 0; s < d.n_samples; ++s) {
        int p = d.sample_part[s];
        face[p] += d.sample_area[s];
        if (s > 0 && p < d.sample_part[s - 1]) ordered = 0;
        double sum = 0;
        for (int k = d.J_hat.row_start[s]; k < d.J_hat.row_start[s + 1]; ++k) {
            sum += d.J_hat.val[k];
            if (d.J_hat.col[k] < d.part_ctrl_offset[p] || d.J_hat.col[k] >= d.part_ctrl_offset[p + 1])
                own_columns = 0;
        }
        row_sum_err = fmax(row_sum_err, fabs(sum - 1.0));
    }
    CHECK(ordered, "samples are grouped in part order");
    CHECK(own_columns, "J-hat rows reference their own part only");
    CHECK_NEAR(row_sum_err, 0.0, 1e-14);
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side)
            CHECK_NEAR(face[2 * axis + side], size[(axis + 1) % 3] * size[(axis + 2) % 3], 1e-13);
    /* the (u,v) lie in the domain and X is the surface point there */
    double eval_err = 0;
    for (int s = 0; s < d.n_samples; s += 7) {
        double x[3];
        sem_surface_eval(&m->parts[d.sample_part[s]].surface, d.sample_uv[2 * s],
                         d.sample_uv[2 * s + 1], x, NULL, NULL, NULL);
        for (int k = 0; k < 3; ++k) eval_err = fmax(eval_err, fabs(x[k] - d.sample_X[3 * s + k]));
    }
    CHECK_NEAR(eval_err, 0.0, 1e-14);

    /* deterministic whatever the thread count */
    sem_discretization d1;
    memset(&d1, 0, sizeof d1);
    omp_set_num_threads(1);
    st = sem_step_sample(m, 0, &d1, &err);
    omp_set_num_threads(2);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st == SEM_OK) {
        CHECK(d1.n_samples == d.n_samples, "same count");
        CHECK(memcmp(d1.sample_X, d.sample_X, 3 * (size_t)d.n_samples * sizeof(double)) == 0,
              "bitwise identical samples with 1 and 2 threads");
        CHECK(memcmp(d1.J_hat.val, d.J_hat.val, sem_csr_nnz(&d.J_hat) * sizeof(double)) == 0,
              "bitwise identical J-hat");
    }
    discretization_free(&d1);
    discretization_free(&d);
    sem_model_destroy(m);
}

/* Degree 1 parts still get 2 x 2 points per span; mixed degrees (p_u+1)(p_v+1). */
static void test_low_degree_counts(void)
{
    sem_model *m = sem_model_create();
    double o[3] = {0, 0, 0}, e1[3] = {3, 0, 0}, e2[3] = {0, 2, 0};
    sem_part part;
    planar_part(&part, o, e1, e2, 1, 3, 4);
    sem_model_take_part(m, &part, NULL);
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_error err;
    sem_status st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st == SEM_OK) {
        CHECK(d.n_samples == 3 * 4 * 4, "n_samples %d", d.n_samples);
        CHECK_NEAR(total_area(&d), 6.0, 1e-13);
    }
    discretization_free(&d);
    sem_model_destroy(m);
}

/* n-arc rational quadratic arc from angle a0 to a1: 2n+1 points (cos, sin), weights, knots */
static void arc(int n, double a0, double a1, double *cs, double *w, double *knots)
{
    double h = 0.5 * (a1 - a0) / n;
    for (int k = 0; k <= 2 * n; ++k) {
        double a = a0 + h * k;
        double f = (k % 2) ? 1.0 / cos(h) : 1.0;
        cs[2 * k] = f * cos(a);
        cs[2 * k + 1] = f * sin(a);
        w[k] = (k % 2) ? cos(h) : 1.0;
    }
    knots[0] = knots[1] = knots[2] = 0.0;
    for (int k = 1; k < n; ++k) knots[1 + 2 * k] = knots[2 + 2 * k] = (double)k / n;
    knots[2 * n + 1] = knots[2 * n + 2] = knots[2 * n + 3] = 1.0;
}

/* Sphere as one rational biquadratic patch with n_u arcs of longitude and n_v of latitude
 * (the primitives' sphere is n_u = 4, n_v = 2); the poles are collapsed edges. */
static sem_model *sphere_model(double radius, int n_u, int n_v)
{
    sem_model *m = sem_model_create();
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface *s = &part.surface;
    sem_surface_alloc(s, 2, 2, 2 * n_u + 1, 2 * n_v + 1);
    double *cu = malloc((size_t)(2 * s->n_u) * sizeof *cu), *wu = malloc((size_t)s->n_u * sizeof *wu);
    double *cv = malloc((size_t)(2 * s->n_v) * sizeof *cv), *wv = malloc((size_t)s->n_v * sizeof *wv);
    arc(n_u, 0.0, 2 * M_PI, cu, wu, s->knots_u);
    arc(n_v, -0.5 * M_PI, 0.5 * M_PI, cv, wv, s->knots_v);
    for (int j = 0; j < s->n_v; ++j)
        for (int i = 0; i < s->n_u; ++i) {
            double *P = s->ctrl + 3 * (i + s->n_u * j);
            P[0] = radius * cv[2 * j] * cu[2 * i];
            P[1] = radius * cv[2 * j] * cu[2 * i + 1];
            P[2] = radius * cv[2 * j + 1];
            s->weights[i + s->n_u * j] = wu[i] * wv[j];
        }
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
    free(cu);
    free(wu);
    free(cv);
    free(wv);
    sem_model_take_part(m, &part, NULL);
    return m;
}

static void test_sphere_and_cylinder_area(void)
{
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.radius = 1.7;
    sd.center[0] = 0.3;
    sem_error err;
    CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "%s", err.message);
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_status st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    double exact = 4 * M_PI * sd.radius * sd.radius;
    if (st == SEM_OK) {
        double got = total_area(&d);
        printf("sphere 4 x 2 arcs: %d samples, area %.15g, exact %.15g, rel err %.3g\n",
               d.n_samples, got, exact, fabs(got - exact) / exact);
        /* (p+1) Lobatto points per span are not exact for rational patches: on the coarse
         * 4 x 2 span sphere the area is 2.01% too large (observed), allowed 2.5% */
        CHECK_REL(got, exact, 0.025);
        /* 4 x 2 spans, 3 x 3 points */
        CHECK(d.n_samples == 8 * 9, "n_samples %d", d.n_samples);
        CHECK_NEAR(j_hat_error(m, &d), 0.0, 1e-14);
        /* every sample lies on the sphere */
        double r_err = 0;
        for (int s = 0; s < d.n_samples; ++s) {
            double dx = d.sample_X[3 * s] - 0.3, dy = d.sample_X[3 * s + 1],
                   dz = d.sample_X[3 * s + 2];
            r_err = fmax(r_err, fabs(sqrt(dx * dx + dy * dy + dz * dz) - sd.radius));
        }
        CHECK_NEAR(r_err, 0.0, 1e-14);
    }
    discretization_free(&d);
    sem_model_destroy(m);

    /* Finer arcs: the rule converges at O(h^4) (3-point Lobatto), to 1e-6 with 64 x 32 arcs. */
    double previous = 0.0;
    for (int level = 0; level < 4; ++level) {
        int n_u = 4 << (level * 1), n_v = 2 << (level * 1);
        if (level == 3) {
            n_u = 64;
            n_v = 32;
        }
        m = sphere_model(sd.radius, n_u, n_v);
        memset(&d, 0, sizeof d);
        st = sem_step_sample(m, 0, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            double rel = fabs(total_area(&d) - exact) / exact;
            printf("sphere %d x %d arcs: %d samples, rel area err %.3g\n", n_u, n_v, d.n_samples,
                   rel);
            CHECK(d.n_samples == n_u * n_v * 9, "count %d", d.n_samples);
            if (level == 0) CHECK_NEAR(rel, 0.0201, 5e-4);
            if (level > 0 && level < 3) CHECK(rel < previous / 10, "converges: %g then %g", previous, rel);
            if (level == 3) CHECK(rel < 1e-6, "64 x 32 arcs: rel err %g", rel);
            previous = rel;
        }
        discretization_free(&d);
        sem_model_destroy(m);
    }

    /* The closed cylinder: side 2 pi r h, discs pi r^2 each (collapsed edges at the centres). */
    m = sem_model_create();
    sem_cylinder_def cd = sem_default_cylinder_def();
    CHECK(sem_primitive_cylinder(m, &cd, &err) == SEM_OK, "%s", err.message);
    memset(&d, 0, sizeof d);
    st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st == SEM_OK) {
        exact = 2 * M_PI * cd.radius * cd.height + 2 * M_PI * cd.radius * cd.radius;
        double got = total_area(&d);
        printf("cylinder: %d samples, area %.15g, exact %.15g, rel err %.3g\n", d.n_samples, got,
               exact, fabs(got - exact) / exact);
        CHECK_REL(got, exact, 5e-3);
    }
    discretization_free(&d);
    sem_model_destroy(m);
}

/* a full circle as 4 rational quadratic arcs (9 control points) */
static void circle_curve(sem_curve *c, double cu, double cv, double r)
{
    sem_curve_alloc(c, 2, 9);
    double k[12] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
    memcpy(c->knots, k, sizeof k);
    double p[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = cu + r * p[i][0];
        c->ctrl[3 * i + 1] = cv + r * p[i][1];
        c->weights[i] = (i % 2) ? sqrt(0.5) : 1.0;
    }
    c->t0 = 0;
    c->t1 = 4;
}

static void add_hole(sem_part *part, double cu, double cv, double r)
{
    part->n_holes = 1;
    part->holes = calloc(1, sizeof *part->holes);
    part->holes[0].n_curves = 1;
    part->holes[0].curves = calloc(1, sizeof(sem_curve));
    circle_curve(&part->holes[0].curves[0], cu, cv, r);
}

/* A 2 x 2 square with a hole of radius 0.5 (domain [0,1]^2 maps to the square, so the hole
 * has radius 0.25 in (u,v)). */
static void test_trimmed_square(void)
{
    const int spans = 16;
    double o[3] = {0, 0, 0}, e1[3] = {2, 0, 0}, e2[3] = {0, 2, 0};
    sem_model *m = sem_model_create();
    sem_part part;
    planar_part(&part, o, e1, e2, 3, spans, spans);
    add_hole(&part, 0.5, 0.5, 0.25);
    sem_error err;
    CHECK(sem_model_take_part(m, &part, &err) == SEM_OK, "%s", err.message);
    /* the same square untrimmed, for the counts */
    sem_model *full = sem_model_create();
    planar_part(&part, o, e1, e2, 3, spans, spans);
    sem_model_take_part(full, &part, NULL);

    sem_discretization d, df;
    memset(&d, 0, sizeof d);
    memset(&df, 0, sizeof df);
    sem_status st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    CHECK(sem_step_sample(full, 0, &df, &err) == SEM_OK, "%s", err.message);
    if (st == SEM_OK) {
        double exact = 4.0 - M_PI * 0.25;
        double got = total_area(&d);
        printf("trimmed square: %d of %d samples kept, area %.10g, exact %.10g, rel err %.3g\n",
               d.n_samples, df.n_samples, got, exact, fabs(got - exact) / exact);
        CHECK_REL(got, exact, 0.02);
        int inside_hole = 0;
        for (int s = 0; s < d.n_samples; ++s) {
            double du = d.sample_uv[2 * s] - 0.5, dv = d.sample_uv[2 * s + 1] - 0.5;
            if (sqrt(du * du + dv * dv) < 0.25 * (1 - 1e-3)) inside_hole++;
        }
        CHECK(inside_hole == 0, "%d samples inside the hole", inside_hole);
        /* every sample of the full square clearly outside the hole is kept */
        int expected = 0;
        for (int s = 0; s < df.n_samples; ++s) {
            double du = df.sample_uv[2 * s] - 0.5, dv = df.sample_uv[2 * s + 1] - 0.5;
            if (sqrt(du * du + dv * dv) > 0.25 * (1 + 1e-3)) expected++;
        }
        int kept_outside = 0;
        for (int s = 0; s < d.n_samples; ++s) {
            double du = d.sample_uv[2 * s] - 0.5, dv = d.sample_uv[2 * s + 1] - 0.5;
            if (sqrt(du * du + dv * dv) > 0.25 * (1 + 1e-3)) kept_outside++;
        }
        CHECK(kept_outside == expected, "kept %d of %d samples outside the hole", kept_outside,
              expected);
        /* the domain's edges (u = 1, v = 1 on the trim rectangle) are kept too */
        CHECK(d.n_samples > df.n_samples * 0.7, "kept %d", d.n_samples);
        CHECK_NEAR(j_hat_error(m, &d), 0.0, 1e-14);
    }
    discretization_free(&d);
    discretization_free(&df);
    sem_model_destroy(m);
    sem_model_destroy(full);
}

/* Errors: no parts; every sample trimmed away ("empty model"); invalid surface. */
static void test_errors(void)
{
    sem_model *m = sem_model_create();
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_error err;
    CHECK(sem_step_sample(m, 0, &d, &err) == SEM_ERR_INVALID, "no parts");
    CHECK(strstr(err.message, "empty model") != NULL, "message: %s", err.message);

    /* a hole bigger than the domain removes every sample */
    double o[3] = {0, 0, 0}, e1[3] = {1, 0, 0}, e2[3] = {0, 1, 0};
    sem_part part;
    planar_part(&part, o, e1, e2, 2, 2, 2);
    add_hole(&part, 0.5, 0.5, 5.0);
    sem_model_take_part(m, &part, NULL);
    sem_status st = sem_step_sample(m, 0, &d, &err);
    CHECK(st != SEM_OK, "everything trimmed away must fail");
    if (st == SEM_OK) discretization_free(&d);
    else CHECK(strstr(err.message, "empty model") != NULL || strstr(err.message, "part 0") != NULL,
               "message: %s", err.message);
    sem_model_destroy(m);

    /* a NaN control point is reported with the part index, not sampled */
    m = sem_model_create();
    planar_part(&part, o, e1, e2, 2, 2, 2);
    sem_model_take_part(m, &part, NULL);
    planar_part(&part, o, e1, e2, 2, 2, 2);
    part.surface.ctrl[4] = NAN;
    sem_model_take_part(m, &part, NULL);
    memset(&d, 0, sizeof d);
    st = sem_step_sample(m, 0, &d, &err);
    CHECK(st == SEM_ERR_INVALID, "NaN control point: status %d", (int)st);
    CHECK(strstr(err.message, "part 1") != NULL, "message: %s", err.message);
    CHECK(d.sample_X == NULL && d.J_hat.row_start == NULL, "nothing filled on failure");
    sem_model_destroy(m);
}

/* The seam weight (sample_seam): a sample on a side of its part's parameter range weighs as
 * if the part were one knot span across that side, so it does not change when the part is
 * refined; elsewhere it is the sample's area. A unit box of biquadratic faces (one span) has
 * seam == area everywhere; refined by 3, a sample on one side has 3 x its area, on a corner
 * 9 x, inside 1 x. */
static void test_seam_weights(void)
{
    sem_error err;
    sem_model *box = sem_model_create(), *fine = NULL;
    sem_box_def bd = sem_default_box_def();
    bd.degree = 2;
    CHECK(sem_primitive_box(box, &bd, &err) == SEM_OK, "box: %s", err.message);
    CHECK(sem_model_refine(box, 3, &fine, &err) == SEM_OK, "refine: %s", err.message);
    for (int r = 0; r < 2 && fine; ++r) {
        const sem_model *m = r ? fine : box;
        sem_discretization d;
        memset(&d, 0, sizeof d);
        CHECK(sem_step_sample(m, 0, &d, &err) == SEM_OK, "%s", err.message);
        int bad = 0, sides[3] = {0, 0, 0};
        double seam_side = 0, area_side = 0;
        for (int k = 0; k < d.n_samples; ++k) {
            const sem_surface *sf = &m->parts[d.sample_part[k]].surface;
            double u = d.sample_uv[2 * k], v = d.sample_uv[2 * k + 1];
            int n = (u == sf->u0 || u == sf->u1) + (v == sf->v0 || v == sf->v1);
            double want = r ? pow(3.0, n) : 1.0;
            bad += fabs(d.sample_seam[k] - want * d.sample_area[k]) > 1e-12 * want * d.sample_area[k];
            sides[n]++;
            if (n == 1) {
                seam_side += d.sample_seam[k];
                area_side += d.sample_area[k];
            }
        }
        printf("seam weights, box refined by %d: %d samples (%d inside, %d on a side, %d on a corner), "
               "side samples weigh %.4g as seams, %.4g as areas\n", r ? 3 : 1, d.n_samples, sides[0], sides[1],
               sides[2], seam_side, area_side);
        CHECK(bad == 0, "refined by %d: %d samples with the wrong seam weight", r ? 3 : 1, bad);
        CHECK(sides[1] > 0 && sides[2] > 0, "samples on sides and corners");
        discretization_free(&d);
    }
    sem_model_destroy(box);
    sem_model_destroy(fine);
}

int main(void)
{
    test_seam_weights();
    test_box_area_and_counts();
    test_low_degree_counts();
    test_sphere_and_cylinder_area();
    test_trimmed_square();
    test_errors();
    return test_finish("test_sampling");
}
