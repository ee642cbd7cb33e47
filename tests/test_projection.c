/* test_projection.c - the hierarchical projection Pi (paper Eq. 7): the patch test (affine
 * motions are fitted exactly, c1 = A, c2 = 0, t = A Xbar + b), a direct dense least-squares
 * solve for general motions, ill-posed planar parts, and every shared model. */
#include <lapacke.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "preprocess/steps.h"
#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "test_util.h"

/* ---- helpers ---- */

static unsigned long long rng_state = 88172645463325252ULL;
static double uniform(void) /* [-1, 1] */
{
    return 2.0 * test_uniform(&rng_state) - 1.0;
}

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* A planar rectangle o + s e1 + t e2 as a clamped uniform B-spline (Greville control points). */
static void planar_part(sem_part *part, const double o[3], const double e1[3],
                        const double e2[3], int degree, int spans)
{
    memset(part, 0, sizeof *part);
    int n = degree + spans;
    sem_surface *s = &part->surface;
    sem_surface_alloc(s, degree, degree, n, n);
    for (int i = 0; i < n + degree + 1; ++i) {
        int j = i - degree;
        s->knots_u[i] = s->knots_v[i] = j < 0 ? 0.0 : (j > spans ? 1.0 : (double)j / spans);
    }
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double gu = 0, gv = 0;
            for (int r = 1; r <= degree; ++r) {
                gu += s->knots_u[i + r];
                gv += s->knots_v[j + r];
            }
            gu /= degree;
            gv /= degree;
            for (int d = 0; d < 3; ++d) s->ctrl[3 * (i + n * j) + d] = o[d] + gu * e1[d] + gv * e2[d];
        }
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
}

static void free_disc(sem_discretization *d)
{
    free(d->part_ctrl_offset);
    free(d->sample_part);
    free(d->sample_uv);
    free(d->sample_X);
    free(d->sample_area);
    free(d->sample_seam);
    sem_csr_free(&d->J_hat);
    free(d->origin_X);
    free(d->part_origin);
    sem_csr_free(&d->Pi);
    memset(d, 0, sizeof *d);
}

/* Samples the model and assigns origins by hand: part_origin given (NULL: one per part);
 * each origin at the area-weighted centroid of its parts' samples (as the origins step). */
static sem_status make_disc(const sem_model *m, const int *part_origin, int order,
                            sem_discretization *d, sem_error *err)
{
    memset(d, 0, sizeof *d);
    sem_status st = sem_step_sample(m, 0, d, err);
    if (st != SEM_OK) return st;
    d->order = order;
    d->part_origin = malloc((size_t)d->n_parts * sizeof(int));
    int n_origins = 0;
    for (int i = 0; i < d->n_parts; ++i) {
        d->part_origin[i] = part_origin ? part_origin[i] : i;
        if (d->part_origin[i] + 1 > n_origins) n_origins = d->part_origin[i] + 1;
    }
    d->n_origins = n_origins;
    d->origin_X = calloc(3 * (size_t)n_origins, sizeof(double));
    double *area = calloc((size_t)n_origins, sizeof(double));
    for (int s = 0; s < d->n_samples; ++s) {
        int j = d->part_origin[d->sample_part[s]];
        area[j] += d->sample_area[s];
        for (int e = 0; e < 3; ++e) d->origin_X[3 * j + e] += d->sample_area[s] * d->sample_X[3 * s + e];
    }
    for (int j = 0; j < n_origins; ++j)
        for (int e = 0; e < 3; ++e) d->origin_X[3 * j + e] /= area[j] > 0 ? area[j] : 1.0;
    free(area);
    return SEM_OK;
}

/* the basis order of sem/preprocess.h, written out independently */
static void basis(int order, const double p[3], double *b)
{
    b[0] = 1;
    b[1] = p[0];
    b[2] = p[1];
    b[3] = p[2];
    if (order == 2) {
        b[4] = p[0] * p[1];
        b[5] = p[0] * p[2];
        b[6] = p[1] * p[2];
        b[7] = p[0] * p[0];
        b[8] = p[1] * p[1];
        b[9] = p[2] * p[2];
    }
}

/* a random well-conditioned A (2 I + noise) and b */
static void random_affine(double A[3][3], double b[3], double scale)
{
    for (int r = 0; r < 3; ++r) {
        for (int c = 0; c < 3; ++c) A[r][c] = (r == c ? 2.0 : 0.0) + 0.8 * uniform();
        b[r] = scale * uniform();
    }
}

static double *affine_q(const sem_model *m, double A[3][3], const double b[3])
{
    size_t n = sem_model_control_points(m);
    double *q0 = malloc(3 * n * sizeof *q0), *q = malloc(3 * n * sizeof *q);
    sem_model_get_q(m, q0);
    for (size_t k = 0; k < n; ++k)
        for (int r = 0; r < 3; ++r)
            q[3 * k + r] = A[r][0] * q0[3 * k] + A[r][1] * q0[3 * k + 1] + A[r][2] * q0[3 * k + 2] + b[r];
    free(q0);
    return q;
}

/* Area-weighted covariance of part i's samples about its origin; eigen-decomposed.
 * Returns eigenvalues (ascending) relative to the largest, vectors in V columns. */
static void part_covariance(const sem_discretization *d, int i, double rel[3], double V[9])
{
    const double *Xbar = d->origin_X + 3 * d->part_origin[i];
    double M[9] = {0};
    for (int s = 0; s < d->n_samples; ++s) {
        if (d->sample_part[s] != i) continue;
        double p[3];
        for (int e = 0; e < 3; ++e) p[e] = d->sample_X[3 * s + e] - Xbar[e];
        for (int e = 0; e < 3; ++e)
            for (int f = 0; f < 3; ++f) M[3 * e + f] += d->sample_area[s] * p[e] * p[f];
    }
    double w[3];
    LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, M, 3, w);
    memcpy(V, M, sizeof M);
    for (int e = 0; e < 3; ++e) rel[e] = w[2] > 0 ? w[e] / w[2] : 0.0;
}

typedef struct patch_result {
    double c1_err, c2_err, t_err, eval_err; /* relative */
    int checked_full, checked_projected;
} patch_result;

/* The patch test on every part: C = Pi_i Q' for Q' = A Q0 + b.
 * c1 (rows 1..3, column d) = A[d][k] in the directions the part's samples span (all three
 * unless the part is planar with its origin in its plane and no help from its group:
 * expected_full[i] = 0), c2 = 0, t = A Xbar + b, and the fitted map reproduces every sample. */
static patch_result patch_test(const sem_model *m, const sem_discretization *d, const int *expected_full)
{
    patch_result r;
    memset(&r, 0, sizeof r);
    double A[3][3], b[3];
    double size = 0;
    for (int k = 0; k < 3 * d->n_samples; ++k) size = fmax(size, fabs(d->sample_X[k]));
    random_affine(A, b, size);
    double normA = 0;
    for (int p = 0; p < 3; ++p)
        for (int c = 0; c < 3; ++c) normA = fmax(normA, fabs(A[p][c]));
    double *Q = affine_q(m, A, b);
    const int mb = d->n_basis;
    double C[10 * 3];
    double *x = malloc(3 * (size_t)d->n_samples * sizeof *x);
    sem_csr_multiply(&d->J_hat, Q, 3, x);
    for (int i = 0; i < d->n_parts; ++i) {
        sem_projection_coefficients(d, i, Q, 3, C);
        const double *Xbar = d->origin_X + 3 * d->part_origin[i];
        double xscale = normA * (fabs(Xbar[0]) + fabs(Xbar[1]) + fabs(Xbar[2])) + fabs(b[0]) +
                        fabs(b[1]) + fabs(b[2]) + normA;
        for (int e = 0; e < 3; ++e) {
            double t = A[e][0] * Xbar[0] + A[e][1] * Xbar[1] + A[e][2] * Xbar[2] + b[e];
            r.t_err = fmax(r.t_err, fabs(C[0 * 3 + e] - t) / xscale);
        }
        double rel[3], V[9];
        part_covariance(d, i, rel, V);
        int full = expected_full ? expected_full[i] : rel[0] > 1e-6;
        if (full) {
            r.checked_full++;
            for (int k = 0; k < 3; ++k)
                for (int e = 0; e < 3; ++e)
                    r.c1_err = fmax(r.c1_err, fabs(C[(1 + k) * 3 + e] - A[e][k]) / normA);
        } else if (rel[0] < 1e-12) {
            /* in-plane directions (eigenvectors 1, 2) exact, the normal one dropped (0) */
            r.checked_projected++;
            for (int v = 0; v < 3; ++v)
                for (int e = 0; e < 3; ++e) {
                    double got = 0, want = 0;
                    for (int k = 0; k < 3; ++k) {
                        got += V[3 * k + v] * C[(1 + k) * 3 + e];
                        want += V[3 * k + v] * A[e][k];
                    }
                    if (v == 0) want = 0; /* pseudo-inverse: minimal norm */
                    r.c1_err = fmax(r.c1_err, fabs(got - want) / normA);
                }
        }
        for (int k = 4; k < mb; ++k)
            for (int e = 0; e < 3; ++e) r.c2_err = fmax(r.c2_err, fabs(C[k * 3 + e]) / normA);
        for (int s = 0; s < d->n_samples; ++s) {
            if (d->sample_part[s] != i) continue;
            double p[3], bb[10];
            for (int e = 0; e < 3; ++e) p[e] = d->sample_X[3 * s + e] - Xbar[e];
            basis(d->order, p, bb);
            for (int e = 0; e < 3; ++e) {
                double v = 0;
                for (int k = 0; k < mb; ++k) v += bb[k] * C[k * 3 + e];
                r.eval_err = fmax(r.eval_err, fabs(v - x[3 * s + e]) / xscale);
            }
        }
    }
    free(x);
    free(Q);
    return r;
}

/* Eq. 7 solved directly by dense least squares (LAPACK), independent of projection.c, for
 * part i at the motion Q (x: the samples' positions, J-hat Q): t over the samples of all the
 * parts of i's origin, then c1 and c2 order by order over the samples of part `fit` (per-part
 * fits), or of all the origin's parts when fit < 0 (shared fits). Returns the largest
 * difference to projection.c's coefficients of part i, relative to their largest. */
static double dense_fit_error(const sem_discretization *d, const double *Q, const double *x, int i, int fit)
{
    const int j = d->part_origin[i];
    const double *Xbar = d->origin_X + 3 * j;
    double t[3] = {0, 0, 0}, area = 0;
    int n = 0;
    for (int s = 0; s < d->n_samples; ++s) {
        if (d->part_origin[d->sample_part[s]] != j) continue;
        area += d->sample_area[s];
        for (int e = 0; e < 3; ++e) t[e] += d->sample_area[s] * x[3 * s + e];
        n += fit < 0 || d->sample_part[s] == fit;
    }
    for (int e = 0; e < 3; ++e) t[e] /= area;
    /* weighted rows sqrt(a) [P1 | P2 | residual] */
    double *P1 = malloc((size_t)n * 3 * sizeof *P1), *P2 = malloc((size_t)n * 6 * sizeof *P2);
    double *R = malloc((size_t)n * 3 * sizeof *R), *R2 = malloc((size_t)n * 3 * sizeof *R2);
    double *P1c = malloc((size_t)n * 3 * sizeof *P1c);
    int row = 0;
    for (int s = 0; s < d->n_samples; ++s) {
        if (d->part_origin[d->sample_part[s]] != j || (fit >= 0 && d->sample_part[s] != fit)) continue;
        double w = sqrt(d->sample_area[s]), p[3], bb[10];
        for (int e = 0; e < 3; ++e) p[e] = d->sample_X[3 * s + e] - Xbar[e];
        basis(2, p, bb);
        for (int k = 0; k < 3; ++k) P1[row * 3 + k] = w * bb[1 + k];
        for (int k = 0; k < 6; ++k) P2[row * 6 + k] = w * bb[4 + k];
        for (int e = 0; e < 3; ++e) R[row * 3 + e] = w * (x[3 * s + e] - t[e]);
        row++;
    }
    memcpy(P1c, P1, (size_t)n * 3 * sizeof *P1);
    memcpy(R2, R, (size_t)n * 3 * sizeof *R);
    LAPACKE_dgels(LAPACK_ROW_MAJOR, 'N', n, 3, 3, P1c, 3, R2, 3); /* c1 in R2[0..8] */
    double c1[9];
    memcpy(c1, R2, sizeof c1);
    for (int r = 0; r < n; ++r)
        for (int e = 0; e < 3; ++e)
            for (int k = 0; k < 3; ++k) R[r * 3 + e] -= P1[r * 3 + k] * c1[k * 3 + e];
    LAPACKE_dgels(LAPACK_ROW_MAJOR, 'N', n, 6, 3, P2, 6, R, 3); /* c2 in R[0..17] */
    double C[30], scale = 0, err = 0;
    sem_projection_coefficients(d, i, Q, 3, C);
    for (int k = 0; k < 30; ++k) scale = fmax(scale, fabs(C[k]));
    for (int e = 0; e < 3; ++e) {
        err = fmax(err, fabs(C[e] - t[e]) / scale);
        for (int k = 0; k < 3; ++k) err = fmax(err, fabs(C[(1 + k) * 3 + e] - c1[k * 3 + e]) / scale);
        for (int k = 0; k < 6; ++k) err = fmax(err, fabs(C[(4 + k) * 3 + e] - R[k * 3 + e]) / scale);
    }
    free(P1);
    free(P2);
    free(R);
    free(R2);
    free(P1c);
    return err;
}

static sem_model *box_model(void)
{
    sem_model *m = sem_model_create();
    const double size[3] = {1.5, 2.0, 0.7}, corner[3] = {0.3, -0.2, 1.1};
    for (int axis = 0; axis < 3; ++axis)
        for (int side = 0; side < 2; ++side) {
            int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
            double o[3], e1[3] = {0, 0, 0}, e2[3] = {0, 0, 0};
            memcpy(o, corner, sizeof o);
            o[axis] += side * size[axis];
            e1[a1] = size[a1];
            e2[a2] = size[a2];
            sem_part part;
            planar_part(&part, o, e1, e2, 3, 2);
            sem_model_take_part(m, &part, NULL);
        }
    return m;
}

/* ---- tests ---- */

/* Box of 6 planar patches, one origin per pair of opposite faces (at the box centre, off
 * each face's plane): every fit is well posed and the patch test exact. */
static void test_box_patch(void)
{
    sem_model *m = box_model();
    const int pairs[6] = {0, 0, 1, 1, 2, 2};
    for (int order = 1; order <= 2; ++order) {
        sem_discretization d;
        sem_error err;
        sem_status st = make_disc(m, pairs, order, &d, &err);
        if (st == SEM_OK) st = sem_step_projection(NULL, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            CHECK(d.n_basis == (order == 2 ? 10 : 4), "n_basis %d", d.n_basis);
            CHECK(d.Pi.n_rows == 6 * d.n_basis && d.Pi.n_cols == d.n_ctrl, "Pi shape");
            /* sparse: a part's rows reach only the two faces of its origin */
            CHECK((int)sem_csr_nnz(&d.Pi) == 6 * d.n_basis * 2 * 25, "nnz %zu", sem_csr_nnz(&d.Pi));
            int inside = 1;
            for (int i = 0; i < 6; ++i)
                for (int r = i * d.n_basis; r < (i + 1) * d.n_basis; ++r)
                    for (int k = d.Pi.row_start[r]; k < d.Pi.row_start[r + 1]; ++k)
                        if (d.Pi.col[k] / 25 / 2 != i / 2) inside = 0;
            CHECK(inside, "Pi rows reach only parts sharing the origin");
            for (int rep = 0; rep < 3; ++rep) {
                patch_result r = patch_test(m, &d, (const int[]){1, 1, 1, 1, 1, 1});
                CHECK(r.checked_full == 6, "full %d", r.checked_full);
                CHECK_NEAR(r.c1_err, 0, 1e-10);
                CHECK_NEAR(r.c2_err, 0, 1e-10);
                CHECK_NEAR(r.t_err, 0, 1e-12);
                CHECK_NEAR(r.eval_err, 0, 1e-12);
            }
        }
        free_disc(&d);
    }
    sem_model_destroy(m);
}

/* Direct dense solve of Eq. 7 for a general (random) motion, independent of projection.c:
 * t over the group, c1 on the part, c2 on the residual, via LAPACK least squares. */
static void test_matches_dense_least_squares(void)
{
    sem_model *m = box_model();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.center[0] = 4;
    sem_primitive_sphere(m, &sd, NULL);
    const int groups[7] = {0, 1, 1, 0, 2, 2, 1}; /* the sphere shares origin 1 */
    sem_discretization d;
    sem_error err;
    sem_status st = make_disc(m, groups, 2, &d, &err);
    if (st == SEM_OK) st = sem_step_projection(NULL, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st != SEM_OK) {
        sem_model_destroy(m);
        return;
    }
    double *Q = malloc(3 * (size_t)d.n_ctrl * sizeof *Q);
    sem_model_get_q(m, Q);
    for (int k = 0; k < 3 * d.n_ctrl; ++k) Q[k] += 0.3 * uniform();
    double *x = malloc(3 * (size_t)d.n_samples * sizeof *x);
    sem_csr_multiply(&d.J_hat, Q, 3, x);
    double max_err = 0;
    for (int i = 0; i < d.n_parts; ++i) max_err = fmax(max_err, dense_fit_error(&d, Q, x, i, i));
    CHECK_NEAR(max_err, 0, 1e-10);

    /* deterministic: bitwise the same Pi with 1 and 2 threads */
    sem_csr Pi2;
    sem_csr_copy(&Pi2, &d.Pi);
    omp_set_num_threads(1);
    st = sem_step_projection(NULL, &d, &err);
    omp_set_num_threads(2);
    CHECK(st == SEM_OK, "%s", err.message);
    CHECK(sem_csr_nnz(&Pi2) == sem_csr_nnz(&d.Pi) &&
              memcmp(Pi2.val, d.Pi.val, sem_csr_nnz(&Pi2) * sizeof(double)) == 0,
          "same Pi with 1 and 2 threads");
    sem_csr_free(&Pi2);
    free(Q);
    free(x);
    free_disc(&d);
    sem_model_destroy(m);
}

/* Shared fits (sem_fit_rule): every part of an origin takes the order-by-order fit over the
 * samples of all its origin's parts. Checked against a dense least-squares solve over the
 * group's samples (LAPACK), with rows equal bit for bit within an origin, and the patch test:
 * for an affine motion every part has t = A Xbar + b, c1 = A, c2 = 0, flat faces included
 * (each group here spans 3D and its quadratic fit is well posed: no quadratic vanishes on
 * three faces of a box, or on three faces and a sphere). */
static void test_shared_fits(void)
{
    sem_model *m = box_model();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.center[0] = 4;
    sem_primitive_sphere(m, &sd, NULL);
    const int groups[7] = {0, 0, 0, 1, 1, 1, 1};
    sem_discretization d;
    sem_error err;
    sem_status st = make_disc(m, groups, 2, &d, &err);
    d.shared_fit = 1;
    if (st == SEM_OK) st = sem_step_projection(NULL, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    if (st != SEM_OK) {
        free_disc(&d);
        sem_model_destroy(m);
        return;
    }
    const int mb = d.n_basis;
    /* equal rows within an origin */
    int equal = 1;
    for (int i = 1; i < d.n_parts; ++i) {
        int first = 0;
        while (d.part_origin[first] != d.part_origin[i]) ++first;
        for (int k = 0; k < mb; ++k) {
            int a = d.Pi.row_start[i * mb + k], b = d.Pi.row_start[first * mb + k];
            int len = d.Pi.row_start[i * mb + k + 1] - a;
            equal &= len == d.Pi.row_start[first * mb + k + 1] - b &&
                     memcmp(d.Pi.val + a, d.Pi.val + b, (size_t)len * sizeof(double)) == 0 &&
                     memcmp(d.Pi.col + a, d.Pi.col + b, (size_t)len * sizeof(int)) == 0;
        }
    }
    CHECK(equal, "the parts of an origin have equal rows of Pi");

    /* a general motion against the dense least squares over the group */
    double *Q = malloc(3 * (size_t)d.n_ctrl * sizeof *Q);
    sem_model_get_q(m, Q);
    for (int k = 0; k < 3 * d.n_ctrl; ++k) Q[k] += 0.3 * uniform();
    double *x = malloc(3 * (size_t)d.n_samples * sizeof *x);
    sem_csr_multiply(&d.J_hat, Q, 3, x);
    double max_err = 0;
    for (int i = 0; i < d.n_parts; ++i) max_err = fmax(max_err, dense_fit_error(&d, Q, x, i, -1));
    CHECK_NEAR(max_err, 0, 1e-10);

    /* the patch test, every part (flat ones too) */
    double A[3][3], b[3];
    random_affine(A, b, 2.0);
    double *Qa = affine_q(m, A, b);
    double patch = 0;
    for (int i = 0; i < d.n_parts; ++i) {
        const double *Xbar = d.origin_X + 3 * d.part_origin[i];
        double C[30];
        sem_projection_coefficients(&d, i, Qa, 3, C);
        for (int e = 0; e < 3; ++e) {
            double t = b[e];
            for (int k = 0; k < 3; ++k) t += A[e][k] * Xbar[k];
            patch = fmax(patch, fabs(C[e] - t) / (fabs(t) + 1));
            for (int k = 0; k < 3; ++k) patch = fmax(patch, fabs(C[(1 + k) * 3 + e] - A[e][k]));
            for (int k = 4; k < mb; ++k) patch = fmax(patch, fabs(C[k * 3 + e]));
        }
    }
    CHECK_NEAR(patch, 0, 1e-10);
    free(Qa);
    free(Q);
    free(x);
    free_disc(&d);
    sem_model_destroy(m);
}

/* A tilted planar square whose origin lies in its plane: alone in its group the normal
 * direction is undetermined (finite Pi, in-plane terms exact, normal terms 0); sharing the
 * origin with a sphere centred in the same plane, the group fixes it and the fit is exact. */
static void test_planar_square(void)
{
    /* the plane through c spanned by e1, e2 (tilted) */
    const double c[3] = {0.5, -0.3, 0.2};
    double e1[3] = {1.2, 0.3, -0.4}, e2[3] = {-0.2, 0.9, 0.5};
    double o[3];
    for (int e = 0; e < 3; ++e) o[e] = c[e] - 0.5 * (e1[e] + e2[e]);
    for (int order = 1; order <= 2; ++order) {
        sem_model *m = sem_model_create();
        sem_part part;
        planar_part(&part, o, e1, e2, 3, 2);
        sem_model_take_part(m, &part, NULL);
        sem_discretization d;
        sem_error err;
        sem_status st = make_disc(m, NULL, order, &d, &err);
        if (st == SEM_OK) st = sem_step_projection(NULL, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            int finite = 1;
            for (size_t k = 0; k < sem_csr_nnz(&d.Pi); ++k) finite &= isfinite(d.Pi.val[k]);
            CHECK(finite, "Pi finite for the ill-posed planar part");
            patch_result r = patch_test(m, &d, (const int[]){0});
            CHECK(r.checked_projected == 1, "planar part detected as planar");
            CHECK_NEAR(r.c1_err, 0, 1e-10);
            CHECK_NEAR(r.c2_err, 0, 1e-10);
            CHECK_NEAR(r.t_err, 0, 1e-12);
            CHECK_NEAR(r.eval_err, 0, 1e-12);
        }
        free_disc(&d);

        /* + a sphere centred on the square's centre: origin still in the plane */
        sem_sphere_def sd = sem_default_sphere_def();
        sd.radius = 0.4;
        memcpy(sd.center, c, sizeof sd.center);
        CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "%s", err.message);
        st = make_disc(m, (const int[]){0, 0}, order, &d, &err);
        if (st == SEM_OK) {
            /* the shared origin lies in the square's plane */
            double nrm[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                             e1[0] * e2[1] - e1[1] * e2[0]};
            double dist = 0;
            for (int e = 0; e < 3; ++e) dist += (d.origin_X[e] - c[e]) * nrm[e];
            CHECK_NEAR(dist, 0, 1e-13);
            st = sem_step_projection(NULL, &d, &err);
        }
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            for (int rep = 0; rep < 3; ++rep) {
                patch_result r = patch_test(m, &d, (const int[]){1, 1});
                CHECK_NEAR(r.c1_err, 0, 1e-10);
                CHECK_NEAR(r.c2_err, 0, 1e-10);
                CHECK_NEAR(r.t_err, 0, 1e-12);
                CHECK_NEAR(r.eval_err, 0, 1e-12);
            }
        }
        free_disc(&d);
        sem_model_destroy(m);
    }
}

/* a full circle as 4 rational quadratic arcs (9 control points), for a trim hole */
static void hole_everywhere(sem_part *part)
{
    part->n_holes = 1;
    part->holes = calloc(1, sizeof *part->holes);
    part->holes[0].n_curves = 1;
    part->holes[0].curves = calloc(1, sizeof(sem_curve));
    sem_curve *c = &part->holes[0].curves[0];
    sem_curve_alloc(c, 2, 9);
    double k[12] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
    memcpy(c->knots, k, sizeof k);
    double p[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = 0.5 + 5 * p[i][0]; /* radius 5 around the centre of [0,1]^2 */
        c->ctrl[3 * i + 1] = 0.5 + 5 * p[i][1];
        c->weights[i] = (i % 2) ? sqrt(0.5) : 1.0;
    }
    c->t0 = 0;
    c->t1 = 4;
}

/* A part trimmed away entirely has no samples: sharing an origin, its fit comes from the
 * group (exact for affine motions); alone, its Pi rows are still finite. */
static void test_part_without_samples(void)
{
    sem_model *m = box_model();
    double o[3] = {0.5, 0.2, 1.3}, e1[3] = {0.5, 0, 0}, e2[3] = {0, 0.5, 0};
    sem_part part;
    planar_part(&part, o, e1, e2, 2, 1);
    hole_everywhere(&part);
    sem_model_take_part(m, &part, NULL);
    for (int order = 1; order <= 2; ++order) {
        sem_discretization d;
        sem_error err;
        sem_status st = make_disc(m, (const int[]){0, 0, 1, 1, 2, 2, 0}, order, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st != SEM_OK) continue;
        int n6 = 0;
        for (int s = 0; s < d.n_samples; ++s) n6 += d.sample_part[s] == 6;
        CHECK(n6 == 0, "part 6 trimmed away, has %d samples", n6);
        st = sem_step_projection(NULL, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            patch_result r = patch_test(m, &d, (const int[]){1, 1, 1, 1, 1, 1, 1});
            CHECK(r.checked_full == 7, "full %d", r.checked_full);
            CHECK_NEAR(r.c1_err, 0, 1e-10);
            CHECK_NEAR(r.c2_err, 0, 1e-10);
            CHECK_NEAR(r.t_err, 0, 1e-12);
        }
        sem_csr_free(&d.Pi);
        /* alone in its own group (no area at all): finite rows */
        d.part_origin[6] = 3;
        d.n_origins = 4;
        d.origin_X = realloc(d.origin_X, 12 * sizeof(double));
        d.origin_X[9] = d.origin_X[10] = d.origin_X[11] = 0.0;
        st = sem_step_projection(NULL, &d, &err);
        CHECK(st == SEM_OK, "%s", err.message);
        if (st == SEM_OK) {
            int finite = 1;
            for (size_t k = 0; k < sem_csr_nnz(&d.Pi); ++k) finite &= isfinite(d.Pi.val[k]);
            CHECK(finite, "finite Pi for a part without samples");
        }
        free_disc(&d);
    }
    sem_model_destroy(m);
}

/* Bad inputs: an origin that is not its group's centroid, missing origins, bad order. */
static void test_errors(void)
{
    sem_model *m = box_model();
    sem_discretization d;
    sem_error err;
    sem_status st = make_disc(m, NULL, 2, &d, &err);
    CHECK(st == SEM_OK, "%s", err.message);
    d.origin_X[3 * 2 + 1] += 1e-3;
    CHECK(sem_step_projection(NULL, &d, &err) == SEM_ERR_INVALID, "origin off its centroid");
    CHECK(strstr(err.message, "origin 2") != NULL, "message: %s", err.message);
    CHECK(d.Pi.row_start == NULL, "no Pi on failure");
    d.origin_X[3 * 2 + 1] -= 1e-3;
    d.part_origin[4] = 17;
    CHECK(sem_step_projection(NULL, &d, &err) == SEM_ERR_INVALID, "origin index out of range");
    d.part_origin[4] = 4;
    d.order = 3;
    sem_preprocess_options o;
    memset(&o, 0, sizeof o);
    o.order = 5;
    CHECK(sem_step_projection(&o, &d, &err) == SEM_ERR_INVALID, "order 5");
    o.order = 1;
    CHECK(sem_step_projection(&o, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.n_basis == 4 && d.order == 1, "order from the options");
    free_disc(&d);
    sem_model_destroy(m);
}

/* Every shared model, one origin per part (at its own centroid): the patch test holds on
 * every part (planar parts: in-plane only), orders 1 and 2. Prints the sampling and Build Pi
 * times beside the paper's Table 1. */
static void test_shared_models(void)
{
    static const struct {
        const char *file;
        double paper_sample, paper_pi; /* Table 1, seconds (order 2 unless noted) */
    } models[] = {
        {"rocket/rocket.iges", 2.83e-2, 6.83e-2},
        {"starship/starship_fall_simpler.igs", 6.78e-2, 9.52e-2},
        {"beams/beam_cmp3_b.iges", 1.97e-1, 5.16e-1},
        {"lamppost.iges", 1.28e-1, 1.07},
        {"tire.iges", 1.74e-1, 6.79e-1},
        {"chicken/chicken_simple_closed.iges", 9.19e-1, 1.91},
        {"mugs/mug_trimmed_complex.iges", 4.18e-1, 2.08},
        {"castle/castle_super_simple.iges", 4.84e-1, 5.78e-1},
        {"grumpy.iges", 2.92e-1, 2.89},
        {"puft/puft_full_simpler.iges", 2.47, 10.9},
        {"beams/perf/b10.igs", 0, 0},
        {"beams/cubes/cube100.iges", 0, 0},
        {"mugs/mug_trimmed_complex_bad.iges", 0, 0},
        {"chicken/chicken.iges", 0, 0},
        {"castle/castle.iges", 0, 0},
        {"cylinder.iges", 0, 0},
        {"rounded_cube.iges", 0, 0},
        {"rocket/rocket_with_nose.iges", 0, 0},
    };
    if (!test_shared_model("README.md")) {
        printf("shared models absent: skipped\n");
        return;
    }
    printf("%-38s %6s %8s %10s %10s %10s %10s\n", "model", "parts", "samples", "sample s",
           "paper", "pi s (o2)", "paper");
    for (size_t k = 0; k < sizeof models / sizeof models[0]; ++k) {
        const char *path = test_shared_model(models[k].file);
        if (!path) continue;
        sem_model *m = NULL;
        sem_error err;
        sem_status st = sem_model_load(path, &m, &err);
        CHECK(st == SEM_OK, "%s: %s", models[k].file, err.message);
        if (st != SEM_OK) continue;
        for (int order = 2; order >= 1; --order) {
            sem_discretization d;
            st = make_disc(m, NULL, order, &d, &err);
            if (st == SEM_OK) st = sem_step_projection(NULL, &d, &err);
            CHECK(st == SEM_OK, "%s order %d: %s", models[k].file, order, err.message);
            if (st == SEM_OK) {
                patch_result r = patch_test(m, &d, NULL);
                /* c2 = 0 only to rounding x the condition of the part's quadratic fit:
                 * real parts have N2 eigenvalue ratios down to ~1e-9 (mug part 4: c2 ~ 4e-8,
                 * mug_bad 2e-7); the fitted map itself is exact at the samples */
                CHECK(r.c1_err <= 1e-9 && r.c2_err <= 1e-6 && r.t_err <= 1e-11 &&
                          r.eval_err <= 1e-10,
                      "%s order %d: c1 %.3g c2 %.3g t %.3g eval %.3g (full %d, planar %d)",
                      models[k].file, order, r.c1_err, r.c2_err, r.t_err, r.eval_err,
                      r.checked_full, r.checked_projected);
            }
            if (st == SEM_OK && order == 2) {
                /* timings: best of 5 (the machine is shared; the minimum is the cost) */
                double best_sample = 1e300, best_pi = 1e300;
                for (int rep = 0; rep < 5; ++rep) {
                    sem_discretization d2;
                    memset(&d2, 0, sizeof d2);
                    double t0 = now();
                    sem_step_sample(m, 0, &d2, &err);
                    best_sample = fmin(best_sample, now() - t0);
                    free_disc(&d2);
                    sem_csr_free(&d.Pi);
                    t0 = now();
                    sem_step_projection(NULL, &d, &err);
                    best_pi = fmin(best_pi, now() - t0);
                }
                printf("%-38s %6d %8d %10.3g %10.3g %10.3g %10.3g\n", models[k].file, d.n_parts,
                       d.n_samples, best_sample, models[k].paper_sample, best_pi,
                       models[k].paper_pi);
            }
            free_disc(&d);
        }
        sem_model_destroy(m);
    }
}

/* With the real pipeline's origins (min-cost flow, Sec. 6.2) and Pi from sem_preprocess:
 * the patch test on every part; groups share origins here, so planar parts are helped. */
static void test_pipeline_origins(void)
{
    static const char *files[] = {"rocket/rocket.iges", "beams/beam_cmp3_b.iges",
                                  "starship/starship_fall_simpler.igs"};
    for (size_t k = 0; k < sizeof files / sizeof files[0]; ++k) {
        const char *path = test_shared_model(files[k]);
        if (!path) continue;
        sem_model *m = NULL;
        sem_error err;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            CHECK(0, "%s: %s", files[k], err.message);
            continue;
        }
        for (int order = 1; order <= 2; ++order) {
            sem_preprocess_options o = sem_default_preprocess_options();
            o.order = order;
            o.rays[0] = o.rays[1] = 6;
            sem_discretization *d = NULL;
            sem_status st = sem_preprocess(m, &o, &d, &err);
            CHECK(st == SEM_OK, "%s: %s", files[k], err.message);
            if (st != SEM_OK) continue;
            patch_result r = patch_test(m, d, NULL);
            CHECK(r.c1_err <= 1e-9 && r.c2_err <= 1e-6 && r.t_err <= 1e-11 && r.eval_err <= 1e-10,
                  "%s order %d (%d origins): c1 %.3g c2 %.3g t %.3g eval %.3g (full %d, planar %d)",
                  files[k], order, d->n_origins, r.c1_err, r.c2_err, r.t_err, r.eval_err,
                  r.checked_full, r.checked_projected);
            printf("%s order %d: %d parts, %d origins, Pi nnz %zu, build Pi %.3g s\n", files[k],
                   order, d->n_parts, d->n_origins, sem_csr_nnz(&d->Pi), d->timings.build_pi_s);
            sem_discretization_destroy(d);
        }
        sem_model_destroy(m);
    }
}

int main(void)
{
    test_box_patch();
    test_matches_dense_least_squares();
    test_shared_fits();
    test_planar_square();
    test_part_without_samples();
    test_errors();
    test_shared_models();
    test_pipeline_origins();
    return test_finish("test_projection");
}
