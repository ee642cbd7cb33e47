/* test_refine_physics.c - a model refined by knot insertion (sem refine, docs/refine.md) is the
 * same shape, so it must give the same answer (issue 12, item 3). At default settings:
 * - the 10-section cantilever of docs/validation.md (5 x 1 x 1 m, E 1e6, gravity 10, static)
 *   refined by K = 2 and 4 deflects within 2 % of the unrefined beam (measured: +0.8 %,
 *   +0.6 %); with the paper's seam weighting (SEM_SEAMS_PAPER) it deflected 6.7 % and 11 % more,
 *   which this test also checks, so that it shows what the geometric seams fix;
 * - the twisting beam of examples/twisting_beam.json (6 sections, 4 x 0.4 x 0.4 m, one end
 *   turned 90 degrees, static) refined by K = 2 and 3 turns its sections at x = 2/3, 4/3 and 2
 *   (the middle) by the same angles within 1 degree (the middle turns 45 degrees by symmetry
 *   whatever the model; the others do not).
 * No shared models needed. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/simulation.h"
#include "bench/validation.h"
#include "test_util.h"

/* The beam of `sections` sections (length x width x width) refined by K, or NULL. */
static sem_model *refined_beam(int sections, double length, double width, int K)
{
    sem_error err;
    sem_model *base = sem_model_create(), *m = NULL;
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = sections;
    bd.length = length;
    bd.width = width;
    bd.height = width;
    if (!base || sem_primitive_beam(base, &bd, &err) != SEM_OK || sem_model_refine(base, K, &m, &err) != SEM_OK) {
        CHECK(0, "beam refined by %d: %s", K, err.message);
        m = NULL;
    }
    sem_model_destroy(base);
    return m;
}

/* Static cantilever at default settings (seams as given): tip deflection, or NaN. */
static double cantilever_tip(int K, int seams, int *dofs)
{
    sem_error err;
    double tip = NAN;
    sem_model *m = refined_beam(10, 5, 1, K);
    if (!m) return tip;
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof(double));
    unsigned char *pin = calloc(nc, 1);
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -10;
    wd.integrator = SEM_STATIC;
    if (!q0 || !pin || sem_preprocess(m, &po, &d, &err) != SEM_OK || !(w = sem_world_create(&wd, &err))) {
        CHECK(0, "cantilever K = %d: %s", K, err.message);
        goto done;
    }
    sem_model_get_q(m, q0);
    sem_cantilever_clamp(q0, nc, pin);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.pinned = pin;
    od.seams = seams;
    if (sem_world_add_object(w, &od, &err) < 0 || sem_world_solve_static(w, &err) != SEM_OK) {
        CHECK(0, "cantilever K = %d: %s", K, err.message);
        goto done;
    }
    tip = sem_cantilever_tip(m, q0, sem_world_object_q(w, 0));
    *dofs = 3 * (int)nc;
done:
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    free(q0);
    free(pin);
    return tip;
}

static void test_cantilever(void)
{
    const int K[3] = {1, 2, 4};
    const int n = getenv("SEM_SANITIZED") ? 2 : 3;
    double tip[2][3] = {{0}};
    for (int s = 0; s < 2; ++s)
        for (int k = 0; k < n; ++k) {
            int seams = s ? SEM_SEAMS_PAPER : SEM_SEAMS_GEOMETRIC, dofs = 0;
            tip[s][k] = cantilever_tip(K[k], seams, &dofs);
            printf("cantilever refined by %d (%d dofs), %s seams: tip %.6f m (%.4f of K = 1)\n", K[k], dofs,
                   s ? "paper's" : "geometric", tip[s][k], tip[s][k] / tip[s][0]);
        }
    for (int k = 1; k < n; ++k) {
        CHECK(fabs(tip[0][k] / tip[0][0] - 1) <= 0.02, "refined by %d: tip %.6f m, unrefined %.6f m", K[k],
              tip[0][k], tip[0][0]);
        /* what the paper's weighting gave (+6.7 % for K = 2, +11 % for K = 4) */
        CHECK(tip[1][k] / tip[1][0] - 1 >= 0.05, "paper's seams refined by %d: %.6f m vs %.6f m", K[k],
              tip[1][k], tip[1][0]);
    }
}

/* The twisting beam refined by K, one static step turning the x = 4 end by 90 degrees about
 * the beam's axis: the mean angles (degrees) by which the control points away from the axis
 * of the sections at x = 2/3, 4/3 and 2 (the middle) turned, into angle[3]. */
static void twist_sections(int K, double angle[3])
{
    sem_error err;
    for (int k = 0; k < 3; ++k) angle[k] = NAN;
    sem_model *m = refined_beam(6, 4, 0.4, K);
    if (!m) return;
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof(double));
    int *group = malloc(nc * sizeof(int));
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.integrator = SEM_STATIC;
    wd.dt = 1.0;
    if (!q0 || !group || sem_preprocess(m, &po, &d, &err) != SEM_OK || !(w = sem_world_create(&wd, &err))) {
        CHECK(0, "twist K = %d: %s", K, err.message);
        goto done;
    }
    sem_model_get_q(m, q0);
    for (size_t c = 0; c < nc; ++c) group[c] = fabs(q0[3 * c]) < 1e-9 ? 0 : fabs(q0[3 * c] - 4) < 1e-9 ? 1 : -1;
    sem_prescribe pr[2];
    memset(pr, 0, sizeof pr);
    pr[0].type = SEM_PRESCRIBE_AFFINE; /* identity: held */
    pr[0].affine[0] = pr[0].affine[5] = pr[0].affine[10] = 1.0;
    pr[1].type = SEM_PRESCRIBE_ROTATE;
    pr[1].axis_point[0] = 4;
    pr[1].axis_point[1] = pr[1].axis_point[2] = 0.2;
    pr[1].axis_direction[0] = 1;
    pr[1].rate = M_PI / 2; /* 90 degrees at t = 1 */
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.prescribe_group = group;
    od.prescribes = pr;
    od.n_prescribes = 2;
    if (sem_world_add_object(w, &od, &err) < 0 || sem_world_step(w, &err) != SEM_OK) {
        CHECK(0, "twist K = %d: %s", K, err.message);
        goto done;
    }
    const double *q = sem_world_object_q(w, 0);
    for (int k = 0; k < 3; ++k) {
        double sum = 0, xs = 2.0 * (k + 1) / 3;
        int count = 0;
        for (size_t c = 0; c < nc; ++c) {
            const double *x0 = q0 + 3 * c, *x = q + 3 * c;
            double y0 = x0[1] - 0.2, z0 = x0[2] - 0.2, y = x[1] - 0.2, z = x[2] - 0.2;
            if (fabs(x0[0] - xs) > 1e-9 || hypot(y0, z0) < 0.1) continue;
            double a = atan2(z, y) - atan2(z0, y0);
            while (a > M_PI) a -= 2 * M_PI;
            while (a < -M_PI) a += 2 * M_PI;
            sum += a;
            count++;
        }
        CHECK(count > 0, "twist K = %d: no control points at x = %g", K, xs);
        if (count) angle[k] = sum / count * 180 / M_PI;
    }
done:
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    free(q0);
    free(group);
}

static void test_twist(void)
{
    const int K[3] = {1, 2, 3};
    const int n = getenv("SEM_SANITIZED") ? 2 : 3;
    double a[3][3] = {{0}};
    for (int k = 0; k < n; ++k) {
        twist_sections(K[k], a[k]);
        printf("twisting beam refined by %d: sections at x = 2/3, 4/3, 2 turned %.3f, %.3f, %.3f degrees "
               "(90 at x = 4)\n", K[k], a[k][0], a[k][1], a[k][2]);
    }
    /* uniform torsion would give 15, 30, 45; the held and turned ends' warping changes the
     * first two */
    CHECK(a[0][2] > 35 && a[0][2] < 55, "middle section turned %.3f degrees", a[0][2]);
    for (int k = 1; k < n; ++k)
        for (int x = 0; x < 3; ++x)
            CHECK(fabs(a[k][x] - a[0][x]) <= 1.0, "refined by %d: section %d turned %.3f degrees, unrefined %.3f",
                  K[k], x, a[k][x], a[0][x]);
}

int main(void)
{
    test_cantilever();
    test_twist();
    return test_finish("test_refine_physics");
}
