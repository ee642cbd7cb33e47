/* test_validation.c - the fast subset of the validation (docs/validation.md, issue 5):
 * - the recorded FEM reference (validation/fem_cantilever.json, tools/fem/cantilever.py) is
 *   sane: converged tip deflection in [3.5, 5] m and its linear check within 10 % of
 *   Euler-Bernoulli beam theory;
 * - SEM static deflection of the paper's cantilevers b1..b4 and b10 (authors' settings:
 *   quadratic, alpha 0.501, rays 3 x 3, 100 points per interval; default error stiffness
 *   gamma = 1000 E / L) as a fraction of the FEM figure (issue 5): the error shrinks
 *   b1 -> b2 -> b3 -> b4 -> b10 (35.3, 42.8, 57.0, 68.2, 93.8 % of FEM measured), b4 is within
 *   [60 %, 76 %] and b10, the 10-section beam, within 10 % of FEM (SEM_SANITIZED: b1, b2
 *   only). Beyond 10 sections the default does not keep converging (docs/validation.md,
 *   section 2); that is documented, not asserted. b10's static Newton solve converges
 *   quadratically near the end (at most 22 iterations; 34 with the projected Hessian);
 * - volume convergence of the ray-cast quadrature (Fig. 7) on the exact NURBS sphere:
 *   relative error < 1e-2 at 12 x 12 rays, < 1e-3 at 48 x 48 and 10x smaller than at 12. */
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "preprocess/raycast.h"
#include "preprocess/steps.h"
#include "sem/primitives.h"
#include "test_util.h"

#define FEM_JSON SEM_TEST_DATA "/../../validation/fem_cantilever.json"

static double fem_tip(void)
{
    double tip = 0;
    sem_error err;
    CHECK(sem_fem_reference_read(FEM_JSON, &tip, &err) == SEM_OK, "%s", err.message);
    printf("FEM reference tip deflection %.5f m\n", tip);
    CHECK(tip > 3.5 && tip < 5.0, "FEM tip deflection %g m outside [3.5, 5]", tip);
    /* the linear check recorded beside it */
    FILE *f = fopen(FEM_JSON, "rb");
    if (f) {
        char buf[1 << 16];
        size_t n = fread(buf, 1, sizeof buf - 1, f);
        fclose(f);
        buf[n] = '\0';
        const char *k = strstr(buf, "\"fem_over_euler_bernoulli\"");
        CHECK(k != NULL, "no linear check in %s", FEM_JSON);
        if (k) {
            double r = strtod(strchr(k, ':') + 1, NULL);
            printf("FEM linear check: FEM / Euler-Bernoulli = %.4f\n", r);
            CHECK(r > 0.9 && r < 1.1, "linear FEM / beam theory %g", r);
        }
    }
    /* errors are reported above */
    return tip;
}

static void test_deflection(double fem)
{
    /* b1..b4 and b10 (the 10-section beam of issue 5); b8, b9 are not in the shared folder */
    const int beams[5] = {1, 2, 3, 4, 10};
    int n_beams = getenv("SEM_SANITIZED") ? 2 : 5;
    double pct[5] = {0};
    int newton[5] = {0};
    sem_cantilever_settings s = sem_default_cantilever_settings(); /* default gamma 1000 E / L */
    for (int j = 0; j < n_beams; ++j) {
        int k = beams[j];
        char rel[64];
        snprintf(rel, sizeof rel, "beams/perf/b%d.igs", k);
        const char *path = test_shared_model(rel);
        if (!path) {
            printf("skip: shared models absent\n");
            return;
        }
        sem_error err;
        sem_model *m = NULL;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            CHECK(0, "%s", err.message);
            return;
        }
        sem_cantilever_result r;
        if (sem_cantilever_solve(m, &s, &r, &err) != SEM_OK) {
            CHECK(0, "b%d: %s", k, err.message);
            sem_model_destroy(m);
            return;
        }
        pct[j] = 100.0 * r.tip_deflection / fem;
        newton[j] = r.newton_iterations;
        printf("b%d: %d parts, %d dofs, tip %.4f m = %.2f %% of FEM (%d Newton iterations, %.2f s)\n", k,
               r.parts, r.dofs, r.tip_deflection, pct[j], r.newton_iterations,
               r.preprocess_s + r.solve_s);
        CHECK(m->n_parts == 6 + 4 * (k - 1), "b%d has %d parts", k, m->n_parts);
        CHECK_REL(r.volume, 5.0, 5e-3);
        CHECK(pct[j] > 30 && pct[j] < 110, "b%d at %.2f %% of FEM", k, pct[j]);
        /* the error shrinks from below: each beam at least 3 points of FEM closer */
        if (j > 0) CHECK(pct[j] > pct[j - 1] + 3, "error not shrinking b%d -> b%d (%.2f -> %.2f %%)",
                         beams[j - 1], k, pct[j - 1], pct[j]);
        sem_model_destroy(m);
    }
    if (n_beams == 5) {
        CHECK(pct[3] > 60 && pct[3] < 76, "b4 at %.2f %% of FEM, expected 60..76", pct[3]);
        CHECK(pct[4] > 90 && pct[4] < 110, "b10 at %.2f %% of FEM, not within 10 %% (issue 5)", pct[4]);
        /* Newton takes the exact Hessian once its steps are full, and then converges
         * quadratically: 16 iterations; with the PSD-projected Hessian throughout it crawls
         * linearly (|g| halves per iteration) and stops on round-off after 34. */
        CHECK(newton[4] <= 22, "b10 static solve took %d Newton iterations, expected <= 22", newton[4]);
    }
}

static double sphere_error(const sem_model *m, const sem_raycast_scene *scene, int n)
{
    sem_preprocess_options o = sem_default_preprocess_options();
    o.rays[0] = o.rays[1] = n;
    o.points_per_interval = 2;
    sem_discretization d;
    memset(&d, 0, sizeof d);
    sem_error err;
    if (sem_step_quadrature(m, scene, &o, &d, &err) != SEM_OK) {
        CHECK(0, "quadrature %d: %s", n, err.message);
        return 1;
    }
    double e = fabs(d.volume / (4.0 / 3.0 * M_PI) - 1);
    printf("sphere %dx%d rays: %d points, relative volume error %.3e\n", n, n, d.n_quad, e);
    free(d.quad_X);
    free(d.quad_volume);
    free(d.quad_part);
    return e;
}

static void test_volume(void)
{
    sem_model *m = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sem_raycast_scene *scene = NULL;
    sem_error err;
    if (sem_primitive_sphere(m, &sd, &err) != SEM_OK || sem_raycast_scene_build(m, 16, &scene, &err) != SEM_OK) {
        CHECK(0, "sphere: %s", err.message);
        sem_model_destroy(m);
        return;
    }
    double e12 = sphere_error(m, scene, 12), e48 = sphere_error(m, scene, 48);
    CHECK(e12 < 1e-2, "12x12: %g", e12);
    CHECK(e48 < 1e-3, "48x48: %g", e48);
    CHECK(e48 < e12 / 10, "no convergence: %g -> %g", e12, e48);
    sem_raycast_scene_destroy(scene);
    sem_model_destroy(m);
}

static void test_fit(void)
{
    double x[4] = {10, 100, 1000, 10000}, y[4];
    for (int i = 0; i < 4; ++i) y[i] = 3e-4 * pow(x[i], 1.5);
    double c;
    double p = sem_loglog_fit(x, y, 4, &c);
    CHECK_NEAR(p, 1.5, 1e-12);
    CHECK_REL(c, 3e-4, 1e-10);
    CHECK(isnan(sem_loglog_fit(x, y, 1, NULL)), "one point cannot be fitted");
}

/* Newton with the exact Hessian (once its steps are full) reaches the same equilibrium as
 * with the PSD-projected one, in fewer iterations. On the 6-section beam under 10 m/s^2 the
 * exact system stays positive definite; under 30 m/s^2 it is not at some iterate, and
 * Newton must fall back to the projected Hessian and still converge to the same tip. */
static void test_newton_hessian(void)
{
    const double gravity[2] = {10, 30};
    for (int c = 0; c < 2; ++c) {
        sem_error err;
        sem_model *m = sem_model_create();
        sem_beam_def bd = sem_default_beam_def();
        bd.sections = 6;
        CHECK(m && sem_primitive_beam(m, &bd, &err) == SEM_OK, "beam: %s", err.message);
        sem_cantilever_settings s = sem_default_cantilever_settings();
        s.gravity = gravity[c];
        sem_cantilever_result r[2];
        long fallbacks[2];
        for (int exact = 0; exact < 2; ++exact) {
            s.projected_hessian = !exact;
            sem_status st = sem_cantilever_solve(m, &s, &r[exact], &err);
            fallbacks[exact] = r[exact].exact_hessian_fallbacks;
            CHECK(st == SEM_OK, "gravity %g, exact %d: %s", gravity[c], exact, err.message);
            if (st != SEM_OK) {
                sem_model_destroy(m);
                return;
            }
        }
        printf("6 sections, gravity %g: tip %.9f m in %d iterations projected, %.9f m in %d "
               "exact (%ld fallbacks)\n", gravity[c], r[0].tip_deflection, r[0].newton_iterations,
               r[1].tip_deflection, r[1].newton_iterations, fallbacks[1]);
        /* the projected solve stops on round-off, 4.5e-7 short at gravity 10 */
        CHECK_REL(r[1].tip_deflection, r[0].tip_deflection, 2e-6);
        CHECK(fallbacks[0] == 0, "the projected Hessian never falls back");
        if (c == 0) {
            CHECK(fallbacks[1] == 0, "gravity 10: exact Hessian fell back %ld times", fallbacks[1]);
            CHECK(r[1].newton_iterations < r[0].newton_iterations,
                  "gravity 10: exact Hessian %d iterations, projected %d", r[1].newton_iterations,
                  r[0].newton_iterations);
        } else {
            CHECK(fallbacks[1] == 1, "gravity 30: exact Hessian fell back %ld times, expected 1",
                  fallbacks[1]);
        }
        sem_model_destroy(m);
    }
}

int main(void)
{
    test_fit();
    test_newton_hessian();
    test_volume();
    double fem = fem_tip();
    if (fem > 0) test_deflection(fem);
    return test_finish("test_validation");
}
