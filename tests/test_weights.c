/* test_weights.c - blending weights (paper Sec. 6.1, Eq. 8-9): partition of unity,
 * Kronecker delta on a part's own surface, equal weights where parts cross, closed forms of
 * Eq. 8 (occlusion by another part, the "inside a closed part" self-hit rule), the far-point
 * fallback, alpha from a target sparsity, and bad input. */
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "preprocess/steps.h"
#include "test_util.h"

/* A planar bilinear patch o + u a + v b, (u,v) in [0,1]^2. */
static void add_square(sem_model *m, const double o[3], const double a[3], const double b[3])
{
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface *s = &part.surface;
    if (sem_surface_alloc(s, 1, 1, 2, 2) != SEM_OK) exit(2);
    const double knots[4] = {0, 0, 1, 1};
    memcpy(s->knots_u, knots, sizeof knots);
    memcpy(s->knots_v, knots, sizeof knots);
    s->u0 = s->v0 = 0.0;
    s->u1 = s->v1 = 1.0;
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 2; ++i)
            for (int k = 0; k < 3; ++k) s->ctrl[3 * (i + 2 * j) + k] = o[k] + i * a[k] + j * b[k];
    sem_error err;
    CHECK(sem_model_take_part(m, &part, &err) == SEM_OK, "%s", err.message);
}

static sem_raycast_scene *build_scene(const sem_model *m)
{
    sem_raycast_scene *scene = NULL;
    sem_error err;
    sem_status st = sem_raycast_scene_build(m, 8, &scene, &err);
    CHECK(st == SEM_OK, "scene: %s", err.message);
    return st == SEM_OK ? scene : NULL;
}

/* Weight of part `part` in row r (0 when absent). */
static double weight_of(const sem_csr *W, int r, int part)
{
    for (int k = W->row_start[r]; k < W->row_start[r + 1]; ++k)
        if (W->col[k] == part) return W->val[k];
    return 0.0;
}

/* Every row: finite, sorted columns, values in (0,1], sum 1 to 1e-12. Returns failures. */
static int check_partition_of_unity(const sem_csr *W, const char *what)
{
    int bad = 0;
    for (int r = 0; r < W->n_rows; ++r) {
        double sum = 0.0;
        int ok = W->row_start[r + 1] > W->row_start[r];
        for (int k = W->row_start[r]; k < W->row_start[r + 1]; ++k) {
            ok &= isfinite(W->val[k]) && W->val[k] > 0.0 && W->val[k] <= 1.0;
            ok &= W->col[k] >= 0 && W->col[k] < W->n_cols;
            if (k > W->row_start[r]) ok &= W->col[k] > W->col[k - 1];
            sum += W->val[k];
        }
        ok &= fabs(sum - 1.0) <= 1e-12;
        if (!ok) ++bad;
    }
    CHECK(bad == 0, "%s: %d of %d rows break the partition of unity", what, bad, W->n_rows);
    return bad;
}

/* Part of a box whose face centre (surface mid-domain) is closest to c. */
static int part_at(const sem_model *m, const double c[3])
{
    int best = -1;
    double best_d = INFINITY;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        double x[3];
        sem_surface_eval(s, 0.5 * (s->u0 + s->u1), 0.5 * (s->v0 + s->v1), x, NULL, NULL, NULL);
        double d = sqrt((x[0] - c[0]) * (x[0] - c[0]) + (x[1] - c[1]) * (x[1] - c[1]) +
                        (x[2] - c[2]) * (x[2] - c[2]));
        if (d < best_d) {
            best_d = d;
            best = i;
        }
    }
    return best;
}

/* Two unit squares crossing at right angles: A in z = 0, B in x = 0. */
static void test_crossing_squares(void)
{
    sem_model *m = sem_model_create();
    const double oA[3] = {-0.5, -0.5, 0}, aA[3] = {1, 0, 0}, bA[3] = {0, 1, 0};
    const double oB[3] = {0, -0.5, -0.5}, aB[3] = {0, 1, 0}, bB[3] = {0, 0, 1};
    add_square(m, oA, aA, bA);
    add_square(m, oB, aB, bB);
    sem_raycast_scene *scene = build_scene(m);
    if (!scene) {
        sem_model_destroy(m);
        return;
    }
    sem_error err;
    sem_csr W;

    /* equal weights on the intersection line (x = z = 0) */
    double line[9 * 3];
    for (int k = 0; k < 9; ++k) {
        line[3 * k] = 0.0;
        line[3 * k + 1] = -0.4 + 0.1 * k;
        line[3 * k + 2] = 0.0;
    }
    CHECK(sem_blend_weights(scene, 9, line, 0.3, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    for (int k = 0; k < 9; ++k) {
        CHECK(W.row_start[k + 1] - W.row_start[k] == 2, "line point %d has %d parts", k,
              W.row_start[k + 1] - W.row_start[k]);
        CHECK_NEAR(weight_of(&W, k, 0), 0.5, 1e-12);
        CHECK_NEAR(weight_of(&W, k, 1), 0.5, 1e-12);
    }
    sem_csr_free(&W);

    /* Eq. 8 closed form with no secondary hits: theta = 1 - d_primary / alpha */
    const double X[3] = {0.2, 0.1, 0.1};
    CHECK(sem_blend_weights(scene, 1, X, 1.0, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK_NEAR(weight_of(&W, 0, 0), 0.9 / 1.7, 1e-12);
    CHECK_NEAR(weight_of(&W, 0, 1), 0.8 / 1.7, 1e-12);
    sem_csr_free(&W);

    /* a point on A away from B (farther than alpha): weight exactly 1 */
    const double onA[3] = {0.4, -0.3, 0.0};
    CHECK(sem_blend_weights(scene, 1, onA, 0.3, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK(W.row_start[1] == 1 && W.col[0] == 0 && W.val[0] == 1.0, "on A: %d entries", W.row_start[1]);
    sem_csr_free(&W);

    /* farther than alpha from everything: the nearest part (B, 4.5 away) gets 1, no NaN */
    const double far[3] = {0.0, 0.0, 5.0};
    CHECK(sem_blend_weights(scene, 1, far, 0.3, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK(W.row_start[1] == 1 && W.col[0] == 1 && W.val[0] == 1.0, "far point: %d entries, col %d",
          W.row_start[1], W.row_start[1] > 0 ? W.col[0] : -1);
    sem_csr_free(&W);

    /* partition of unity on a grid around the squares, for several alphas */
    const int n = 11;
    double *grid = malloc(3 * (size_t)n * n * n * sizeof *grid);
    for (int i = 0, p = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k, ++p) {
                grid[3 * p] = -0.7 + 1.4 * i / (n - 1);
                grid[3 * p + 1] = -0.7 + 1.4 * j / (n - 1);
                grid[3 * p + 2] = -0.7 + 1.4 * k / (n - 1);
            }
    const double alphas[3] = {0.05, 0.3, 2.0};
    for (int a = 0; a < 3; ++a) {
        CHECK(sem_blend_weights(scene, n * n * n, grid, alphas[a], 1e-4, &W, &err) == SEM_OK, "%s",
              err.message);
        check_partition_of_unity(&W, "crossing squares grid");
        sem_csr_free(&W);
    }
    free(grid);

    /* bad input */
    CHECK(sem_blend_weights(scene, 1, X, 0.0, 1e-4, &W, &err) == SEM_ERR_INVALID, "alpha 0");
    CHECK(strstr(err.message, "alpha") != NULL, "message: %s", err.message);
    CHECK(sem_blend_weights(scene, 1, X, -1.0, 1e-4, &W, &err) == SEM_ERR_INVALID, "alpha < 0");
    CHECK(sem_blend_weights(scene, 1, X, NAN, 1e-4, &W, &err) == SEM_ERR_INVALID, "alpha NaN");
    CHECK(sem_blend_weights(scene, 1, X, 1.0, 1.5, &W, &err) == SEM_ERR_INVALID, "threshold");
    const double nan_point[3] = {0.0, NAN, 0.0};
    CHECK(sem_blend_weights(scene, 1, nan_point, 1.0, 1e-4, &W, &err) == SEM_ERR_INVALID,
          "NaN point");
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* Unit cube [-0.5,0.5]^3 of 6 patches. */
static void test_cube(void)
{
    sem_model *m = sem_model_create();
    sem_box_def def = sem_default_box_def();
    sem_error err;
    CHECK(sem_primitive_box(m, &def, &err) == SEM_OK, "%s", err.message);
    sem_raycast_scene *scene = build_scene(m);
    if (!scene) {
        sem_model_destroy(m);
        return;
    }
    const double cx0[3] = {-0.5, 0, 0}, cx1[3] = {0.5, 0, 0}, cz1[3] = {0, 0, 0.5};
    const double cy0[3] = {0, -0.5, 0}, cz0[3] = {0, 0, -0.5};
    const int x0 = part_at(m, cx0), x1 = part_at(m, cx1), z1 = part_at(m, cz1);
    const int y0 = part_at(m, cy0), z0 = part_at(m, cz0);
    sem_csr W;

    /* Eq. 8 with secondary hits on the opposite faces (d_total = 1), alpha saturated:
     * theta = 0.75 (x = -0.5), 0.25 (x = 0.5), 0.5 (4 others); sum 3 */
    const double X[3] = {-0.25, 0, 0};
    CHECK(sem_blend_weights(scene, 1, X, 2.0, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK(W.row_start[1] == 6, "interior point has %d parts", W.row_start[1]);
    for (int i = 0; i < 6; ++i) {
        double expect = i == x0 ? 0.25 : i == x1 ? 1.0 / 12.0 : 1.0 / 6.0;
        CHECK_NEAR(weight_of(&W, 0, i), expect, 1e-9);
    }
    sem_csr_free(&W);

    /* the centre: all six equal at any alpha above 0.5 */
    const double centre[3] = {0, 0, 0};
    CHECK(sem_blend_weights(scene, 1, centre, 0.6, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    for (int i = 0; i < 6; ++i) CHECK_NEAR(weight_of(&W, 0, i), 1.0 / 6.0, 1e-12);
    sem_csr_free(&W);

    /* face centres: weight exactly 1 on the own face, even with a large alpha (Kronecker
     * delta); an edge midpoint: 1/2 on each of its two faces */
    double faces[6 * 3];
    for (int i = 0; i < 6; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        sem_surface_eval(s, 0.5 * (s->u0 + s->u1), 0.5 * (s->v0 + s->v1), &faces[3 * i], NULL, NULL, NULL);
    }
    const double alphas[2] = {0.3, 2.0};
    for (int a = 0; a < 2; ++a) {
        CHECK(sem_blend_weights(scene, 6, faces, alphas[a], 1e-4, &W, &err) == SEM_OK, "%s",
              err.message);
        for (int i = 0; i < 6; ++i)
            CHECK(W.row_start[i + 1] - W.row_start[i] == 1 && W.col[W.row_start[i]] == i &&
                      W.val[W.row_start[i]] == 1.0,
                  "face %d centre, alpha %g: %d entries", i, alphas[a],
                  W.row_start[i + 1] - W.row_start[i]);
        sem_csr_free(&W);
    }
    const double edge[3] = {0, -0.5, -0.5};
    CHECK(sem_blend_weights(scene, 1, edge, 2.0, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK(W.row_start[1] == 2, "edge point has %d parts", W.row_start[1]);
    CHECK_NEAR(weight_of(&W, 0, y0), 0.5, 1e-12);
    CHECK_NEAR(weight_of(&W, 0, z0), 0.5, 1e-12);
    sem_csr_free(&W);

    /* outside, farther than alpha from every face: the nearest (top) face gets 1 */
    const double far[3] = {0.1, -0.2, 3.0};
    CHECK(sem_blend_weights(scene, 1, far, 0.5, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    CHECK(W.row_start[1] == 1 && W.col[0] == z1 && W.val[0] == 1.0, "far point");
    sem_csr_free(&W);

    /* the step: interior grid as quadrature points, face centres as samples */
    const int n = 12;
    sem_discretization d;
    memset(&d, 0, sizeof d);
    d.n_parts = 6;
    d.n_quad = n * n * n;
    d.quad_X = malloc(3 * (size_t)d.n_quad * sizeof *d.quad_X);
    for (int i = 0, p = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k, ++p) {
                d.quad_X[3 * p] = -0.5 + (i + 0.5) / n;
                d.quad_X[3 * p + 1] = -0.5 + (j + 0.5) / n;
                d.quad_X[3 * p + 2] = -0.5 + (k + 0.5) / n;
            }
    int sample_part[6] = {0, 1, 2, 3, 4, 5};
    d.n_samples = 6;
    d.sample_X = faces;
    d.sample_part = sample_part;
    sem_preprocess_options o;
    memset(&o, 0, sizeof o);
    o.weight_threshold = 1e-4;
    const double targets[3] = {0.3, 0.5, 0.8};
    for (int t = 0; t < 3; ++t) {
        o.sparsity = targets[t];
        CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
        CHECK(fabs(d.weight_nonzero_fraction - targets[t]) <= 0.03 * targets[t],
              "target %g: fraction %g (alpha %g)", targets[t], d.weight_nonzero_fraction, d.alpha);
        CHECK_NEAR(d.weight_nonzero_fraction, (double)sem_csr_nnz(&d.W) / (6.0 * d.n_quad), 1e-15);
        CHECK(d.alpha > 0.0 && d.alpha < 2.0, "alpha %g", d.alpha);
        check_partition_of_unity(&d.W, "cube step");
        check_partition_of_unity(&d.W_samples, "cube samples");
        for (int i = 0; i < 6; ++i) CHECK(weight_of(&d.W_samples, i, i) == 1.0, "sample %d", i);
    }
    /* a larger target needs a larger alpha (monotone) */
    double alpha_08 = d.alpha;
    o.sparsity = 0.5;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.alpha < alpha_08, "alpha(T=0.5) %g >= alpha(T=0.8) %g", d.alpha, alpha_08);

    /* explicit alpha and the default (0.5 x diagonal) */
    o.sparsity = 0.0;
    o.alpha = 0.35;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.alpha == 0.35, "alpha %g", d.alpha);
    o.alpha = 0.0;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
    CHECK_NEAR(d.alpha, 0.5 * sqrt(3.0), 1e-9);

    /* bad options: negative alpha, sparsity outside (0,1) */
    o.alpha = -1.0;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_ERR_INVALID, "alpha -1");
    CHECK(strstr(err.message, "alpha") != NULL, "message: %s", err.message);
    o.alpha = 0.0;
    const double bad_t[4] = {1.0, 1.5, -0.2, NAN};
    for (int t = 0; t < 4; ++t) {
        o.sparsity = bad_t[t];
        CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_ERR_INVALID, "sparsity %g", bad_t[t]);
        CHECK(strstr(err.message, "sparsity") != NULL, "message: %s", err.message);
    }

    /* deterministic for any thread count */
    o.sparsity = 0.0;
    o.alpha = 0.4;
    o.threads = 1;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
    sem_csr one;
    sem_csr_copy(&one, &d.W);
    o.threads = 2;
    CHECK(sem_step_weights(m, scene, &o, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_csr_nnz(&one) == sem_csr_nnz(&d.W) &&
              memcmp(one.col, d.W.col, sem_csr_nnz(&one) * sizeof(int)) == 0 &&
              memcmp(one.val, d.W.val, sem_csr_nnz(&one) * sizeof(double)) == 0,
          "1 and 2 threads differ");
    sem_csr_free(&one);

    sem_csr_free(&d.W);
    sem_csr_free(&d.W_samples);
    free(d.quad_X);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
    (void)x1;
}

/* A closed sphere (one part) with a small square inside it: the sphere's secondary ray hits
 * the sphere itself beyond X, so theta_sphere = 1 ("inside a closed part"). */
static void test_self_hit(void)
{
    sem_model *m = sem_model_create();
    sem_sphere_def def = sem_default_sphere_def();
    sem_error err;
    CHECK(sem_primitive_sphere(m, &def, &err) == SEM_OK, "%s", err.message);
    const double o[3] = {0.5, -0.2, -0.2}, a[3] = {0, 0.4, 0}, b[3] = {0, 0, 0.4};
    add_square(m, o, a, b);
    sem_raycast_scene *scene = build_scene(m);
    if (!scene) {
        sem_model_destroy(m);
        return;
    }
    const double X[3] = {0, -0.5, 0};
    sem_csr W;
    CHECK(sem_blend_weights(scene, 1, X, 2.0, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    /* square: X* = (0.5, -0.2, 0), the ray through X leaves the unit sphere at t = d_total */
    const double Xs[3] = {0.5, -0.2, 0};
    double u[3], dp = 0.0;
    for (int k = 0; k < 3; ++k) u[k] = X[k] - Xs[k];
    dp = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    for (int k = 0; k < 3; ++k) u[k] /= dp;
    double xu = Xs[0] * u[0] + Xs[1] * u[1] + Xs[2] * u[2];
    double xx = Xs[0] * Xs[0] + Xs[1] * Xs[1] + Xs[2] * Xs[2];
    double dt = -xu + sqrt(xu * xu - (xx - 1.0));
    double theta_square = 1.0 - dp / dt;
    /* the tessellated sphere is within ~5e-3 of the exact one */
    CHECK_NEAR(weight_of(&W, 0, 0), 1.0 / (1.0 + theta_square), 5e-3);
    CHECK_NEAR(weight_of(&W, 0, 1), theta_square / (1.0 + theta_square), 5e-3);
    /* without the rule the sphere would get theta 1 - 0.5/2 = 0.75: weight 0.588 */
    CHECK(weight_of(&W, 0, 0) > 0.63, "sphere weight %g", weight_of(&W, 0, 0));
    sem_csr_free(&W);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

/* Partition of unity on the twisting beam (a real model): interior points with a winding
 * number above 1/2, at the authors' alpha 0.51. */
static void test_shared_beam(void)
{
    const char *path = test_shared_model("beams/beam_cmp3_b.iges");
    if (!path) {
        printf("skipped: beams/beam_cmp3_b.iges not found\n");
        return;
    }
    sem_model *m = NULL;
    sem_error err;
    if (sem_iges_read(path, &m, &err) != SEM_OK) {
        CHECK(0, "read %s: %s", path, err.message);
        return;
    }
    sem_raycast_scene *scene = build_scene(m);
    if (!scene) {
        sem_model_destroy(m);
        return;
    }
    double lo[3], hi[3];
    sem_raycast_bounds(scene, lo, hi);
    const int n = 16;
    double *X = malloc(3 * (size_t)n * n * n * sizeof *X);
    int count = 0;
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < n; ++j)
            for (int k = 0; k < n; ++k) {
                double p[3] = {lo[0] + (hi[0] - lo[0]) * (i + 0.5) / n,
                               lo[1] + (hi[1] - lo[1]) * (j + 0.5) / n,
                               lo[2] + (hi[2] - lo[2]) * (k + 0.5) / n};
                if (sem_raycast_winding_number(scene, p) > 0.5) {
                    memcpy(&X[3 * count], p, sizeof p);
                    ++count;
                }
            }
    CHECK(count > n * n * n / 4, "only %d interior points", count);
    sem_csr W;
    clock_t t0 = clock();
    CHECK(sem_blend_weights(scene, count, X, 0.51, 1e-4, &W, &err) == SEM_OK, "%s", err.message);
    printf("beam_cmp3_b: %d parts, %d points, nnz %zu (%.1f%%), %.3f s cpu\n",
           sem_raycast_part_count(scene), count, sem_csr_nnz(&W),
           100.0 * sem_csr_nnz(&W) / ((double)count * sem_raycast_part_count(scene)),
           (double)(clock() - t0) / CLOCKS_PER_SEC);
    check_partition_of_unity(&W, "beam_cmp3_b");
    sem_csr_free(&W);
    free(X);

    /* the step on the real quadrature points and samples, authors' settings (models
     * README: alpha 0.51, rays 3 x 3, 15 points per interval) */
    sem_preprocess_options o = sem_default_preprocess_options();
    o.alpha = 0.51;
    o.rays[0] = o.rays[1] = 3;
    o.points_per_interval = 15;
    sem_discretization *d = calloc(1, sizeof *d);
    sem_status st = sem_step_sample(m, 0, d, &err);
    if (st == SEM_OK) st = sem_step_quadrature(m, scene, &o, d, &err);
    if (st == SEM_OK) st = sem_step_weights(m, scene, &o, d, &err);
    CHECK(st == SEM_OK, "beam steps: %s", err.message);
    if (st == SEM_OK) {
        CHECK(d->n_quad > 0 && d->W.n_rows == d->n_quad && d->W.n_cols == d->n_parts, "W shape");
        check_partition_of_unity(&d->W, "beam_cmp3_b quadrature");
        check_partition_of_unity(&d->W_samples, "beam_cmp3_b samples");
        int own_ok = 1;
        for (int k = 0; k < d->n_samples; ++k) {
            double w = weight_of(&d->W_samples, k, d->sample_part[k]);
            int len = d->W_samples.row_start[k + 1] - d->W_samples.row_start[k];
            own_ok &= len >= 1 && fabs(w - 1.0 / len) <= 1e-12;
        }
        CHECK(own_ok, "samples: own part weight is not 1 / (parts through the sample)");
        printf("beam_cmp3_b step: %d quadrature points, %d samples, nnz %.1f%%\n", d->n_quad,
               d->n_samples, 100.0 * d->weight_nonzero_fraction);
    }
    sem_discretization_destroy(d);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

int main(void)
{
    test_crossing_squares();
    test_cube();
    test_self_hit();
    test_shared_beam();
    return test_finish("test_weights");
}
