/* test_structured.c - the structured solver (src/physics/structured.h, issue 12) gives the
 * states of the q-space solver (CHOLMOD on the assembled matrix) on the same discretization:
 * linearly implicit and implicit Euler steps of a pinned, refined box under gravity agree to
 * round-off and Newton's tolerance; a free body moving rigidly keeps its velocity (the patch
 * test of a rigid translation and the conservation of linear momentum); the automatic rule
 * picks it for a model with many control points per part and not for a coarse one; and the
 * preprocessing skips the q-space operators exactly when it does. With seam ties
 * (sem_object_def.seam_ties: rows across parts, and so across origin groups) the same: both
 * solvers agree and a free body keeps its rigid translation. No shared models needed. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/simulation.h"
#include "test_util.h"
#include "util/free_all.h"

/* A 1 x 0.5 x 0.5 box (bicubic faces) refined by 3: 6 parts, 216 control points. */
static sem_model *refined_box(void)
{
    sem_error err;
    sem_model *box = sem_model_create(), *fine = NULL;
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = 1;
    bd.size[1] = 0.5;
    bd.size[2] = 0.5;
    if (!box || sem_primitive_box(box, &bd, &err) != SEM_OK || sem_model_refine(box, 3, &fine, &err) != SEM_OK) {
        CHECK(0, "refined box: %s", err.message);
        sem_model_destroy(box);
        return NULL;
    }
    sem_model_destroy(box);
    return fine;
}

/* The seam ties of every object run() makes (0: none). */
static double seam_ties;

/* A world of one object (pinned at x < lo + 0.05 when pin) stepped `steps` times; returns q
 * (caller frees) and the solver's name. */
static double *run(const sem_model *m, const sem_discretization *d, sem_solver_choice solver,
                   sem_integrator integ, int steps, int pin, const double v0[3], char *name)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.solver = solver;
    wd.integrator = integ;
    wd.dt = 0.01;
    wd.threads = 2;
    if (!pin) wd.gravity[2] = 0;
    sem_world *w = sem_world_create(&wd, &err);
    size_t n = 3 * (size_t)d->n_ctrl;
    unsigned char *pinned = calloc((size_t)d->n_ctrl, 1);
    double *q0 = malloc(n * sizeof(double)), *q = NULL;
    if (!w || !pinned || !q0) {
        CHECK(0, "world: %s", w ? "out of memory" : err.message);
        goto done;
    }
    sem_model_get_q(m, q0);
    double lo = INFINITY;
    for (int c = 0; c < d->n_ctrl; ++c) lo = fmin(lo, q0[3 * c]);
    for (int c = 0; pin && c < d->n_ctrl; ++c) pinned[c] = q0[3 * c] < lo + 0.05;
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.material = sem_default_material();
    od.material.youngs_modulus = 1e5; /* soft: visible sag in a few steps */
    od.pinned = pinned; /* all zero when free */
    od.seam_ties = seam_ties;
    for (int k = 0; k < 3 && v0; ++k) od.initial_velocity[k] = v0[k];
    if (sem_world_add_object(w, &od, &err) < 0) {
        CHECK(0, "add object: %s", err.message);
        goto done;
    }
    snprintf(name, 32, "%s", sem_world_solver_name(w, 0));
    for (int s = 0; s < steps; ++s)
        if (sem_world_step(w, &err) != SEM_OK) {
            CHECK(0, "%s step %d: %s", name, s, err.message);
            goto done;
        }
    q = malloc(n * sizeof(double));
    if (q) memcpy(q, sem_world_object_q(w, 0), n * sizeof(double));
    if (q && !pin) {
        /* a rigid translation: every control point moves with v0 */
        const double *v = sem_world_object_velocity(w, 0);
        double worst = 0;
        for (size_t i = 0; i < n; ++i) worst = fmax(worst, fabs(v[i] - v0[i % 3]));
        printf("%s: free box after %d steps: velocity error %.3g m/s\n", name, steps, worst);
        CHECK(worst <= 1e-10, "%s: rigid translation lost: velocity error %.3g", name, worst);
        double moved = 0;
        for (size_t i = 0; i < n; ++i) moved = fmax(moved, fabs(q[i] - q0[i] - steps * wd.dt * v0[i % 3]));
        CHECK(moved <= 1e-10, "%s: rigid translation lost: position error %.3g", name, moved);
    }
done:
    sem_world_destroy(w);
    free(pinned);
    free(q0);
    return q;
}

static double max_diff(const double *a, const double *b, const double *ref, size_t n, double *scale)
{
    double d = 0, s = 0;
    for (size_t i = 0; i < n; ++i) {
        d = fmax(d, fabs(a[i] - b[i]));
        s = fmax(s, fabs(a[i] - ref[i]));
    }
    *scale = s;
    return d;
}

/* Pinned under gravity, linearly implicit (10 steps) and implicit Euler (4 steps): `solver`
 * (which must be the structured one) gives CHOLMOD's states on the same discretization, to
 * round-off and to Newton's tolerance relative to the displacement. */
static void compare_with_q_space(const sem_model *m, const sem_discretization *d, sem_solver_choice solver,
                                 const char *what)
{
    size_t n = 3 * (size_t)d->n_ctrl;
    double *q0 = malloc(n * sizeof(double));
    sem_model_get_q(m, q0);
    char na[32] = "", nb[32] = "";
    const sem_integrator integ[2] = {SEM_LINEARLY_IMPLICIT_EULER, SEM_IMPLICIT_EULER};
    const int steps[2] = {10, 4};
    const double tol[2] = {1e-9, 1e-6}; /* relative to the displacement: round-off; Newton's tolerance */
    for (int t = 0; t < 2; ++t) {
        double *qa = run(m, d, SEM_SOLVER_SPARSE, integ[t], steps[t], 1, NULL, na);
        double *qb = run(m, d, solver, integ[t], steps[t], 1, NULL, nb);
        if (qa && qb) {
            double scale = 0, diff = max_diff(qa, qb, q0, n, &scale);
            printf("%s: %s vs %s, %s: displacement %.4g m, states differ by %.3g m\n", what, na, nb,
                   t ? "implicit Euler" : "linearly implicit", scale, diff);
            CHECK(scale > 1e-4, "%s should sag (%.3g m)", what, scale);
            CHECK(diff <= tol[t] * scale, "%s: structured and q-space states differ by %.3g of %.3g", what,
                  diff, scale);
            CHECK(!strcmp(na, "cholmod") && !strcmp(nb, "structured"), "%s: solvers %s, %s", what, na, nb);
        }
        free(qa);
        free(qb);
    }
    free(q0);
}

/* Shared fits (sem_fit_rule): a 3-section beam (14 parts) whose origins each hold several
 * faces, one polynomial per origin. The structured solver keeps one of the equal rows of Pi
 * (origins x m coefficients) and must give the q-space solver's states; a free body keeps a
 * rigid translation; and under solver auto a shared model takes the structured solver even
 * where the per-part rule would not (9 control points per part here). */
static void test_shared_fits(void)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 3;
    bd.length = 1.5;
    bd.width = 0.5;
    bd.height = 0.5;
    if (!m || sem_primitive_beam(m, &bd, &err) != SEM_OK) {
        CHECK(0, "beam: %s", err.message);
        sem_model_destroy(m);
        return;
    }
    sem_preprocess_options po = sem_default_preprocess_options();
    po.fit_rule = SEM_FIT_ORIGINS;
    CHECK(sem_preprocess_q_space(m, &po) == 0, "shared fits: no q-space operators by default");
    po.q_space_operators = 1;
    sem_discretization *d = NULL;
    if (sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        sem_model_destroy(m);
        return;
    }
    CHECK(d->shared_fit == 1 && d->n_origins < d->n_parts, "%d origins for %d parts", d->n_origins, d->n_parts);
    compare_with_q_space(m, d, SEM_SOLVER_AUTO, "shared fits, the beam");
    char nb[32] = "";
    const sem_integrator integ[2] = {SEM_LINEARLY_IMPLICIT_EULER, SEM_IMPLICIT_EULER};
    const double v0[3] = {0.3, -0.2, 0.1};
    for (int t = 0; t < 2; ++t) free(run(m, d, SEM_SOLVER_STRUCTURED, integ[t], 5, 0, v0, nb));
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

int main(void)
{
    sem_error err;
    sem_model *m = refined_box();
    if (!m) return test_finish("test_structured");
    sem_preprocess_options po = sem_default_preprocess_options();
    CHECK(sem_preprocess_q_space(m, &po) == 0, "automatic: no q-space operators for %zu control points, %d parts",
          sem_model_control_points(m), m->n_parts);
    po.q_space_operators = 1; /* both solvers run on the same discretization */
    sem_discretization *d = NULL;
    if (sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        sem_model_destroy(m);
        return test_finish("test_structured");
    }
    compare_with_q_space(m, d, SEM_SOLVER_STRUCTURED, "the refined box");
    char na[32] = "", nb[32] = "";
    const sem_integrator integ[2] = {SEM_LINEARLY_IMPLICIT_EULER, SEM_IMPLICIT_EULER};
    /* free flight: a rigid translation stays one */
    const double v0[3] = {0.3, -0.2, 0.1};
    for (int t = 0; t < 2; ++t) free(run(m, d, SEM_SOLVER_STRUCTURED, integ[t], 5, 0, v0, nb));
    /* with seam ties: rows J_a - J_b across the faces' groups */
    {
        /* the ties change the answer (they are in the matrices), if only a little here: the
         * box's faces hardly move apart under gravity */
        double *qa = run(m, d, SEM_SOLVER_STRUCTURED, SEM_LINEARLY_IMPLICIT_EULER, 10, 1, NULL, na);
        seam_ties = 30;
        double *qb = run(m, d, SEM_SOLVER_STRUCTURED, SEM_LINEARLY_IMPLICIT_EULER, 10, 1, NULL, nb);
        double *q0 = malloc(3 * (size_t)d->n_ctrl * sizeof(double)), scale = 0;
        sem_model_get_q(m, q0);
        double diff = qa && qb ? max_diff(qa, qb, q0, 3 * (size_t)d->n_ctrl, &scale) : 0;
        printf("the refined box, structured: seam ties move the state by %.3g m of %.3g m\n", diff, scale);
        CHECK(diff > 1e-9 * scale, "seam ties changed nothing (%.3g of %.3g)", diff, scale);
        SEM_FREE_ALL(qa, qb, q0);
    }
    compare_with_q_space(m, d, SEM_SOLVER_STRUCTURED, "the refined box, seam ties");
    for (int t = 0; t < 2; ++t) free(run(m, d, SEM_SOLVER_STRUCTURED, integ[t], 5, 0, v0, nb));
    seam_ties = 0;
    /* the automatic rule */
    double *q = run(m, d, SEM_SOLVER_AUTO, SEM_LINEARLY_IMPLICIT_EULER, 1, 1, NULL, na);
    CHECK(!strcmp(na, "structured"), "auto picked %s for the refined box", na);
    free(q);
    sem_discretization_destroy(d);
    /* a coarse box (96 control points, 6 parts x 10 terms): the q-space solvers and operators */
    sem_model *coarse = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    if (coarse && sem_primitive_box(coarse, &bd, &err) == SEM_OK) {
        po = sem_default_preprocess_options();
        CHECK(sem_preprocess_q_space(coarse, &po) == 1, "automatic: q-space operators for the coarse box");
        d = NULL;
        if (sem_preprocess(coarse, &po, &d, &err) == SEM_OK) {
            CHECK(sem_csr_nnz(&d->M) > 0, "coarse box: M formed");
            q = run(coarse, d, SEM_SOLVER_AUTO, SEM_LINEARLY_IMPLICIT_EULER, 1, 1, NULL, na);
            CHECK(strcmp(na, "structured") != 0, "auto picked %s for the coarse box", na);
            free(q);
            sem_discretization_destroy(d);
        } else {
            CHECK(0, "coarse box: %s", err.message);
        }
    }
    sem_model_destroy(coarse);
    sem_model_destroy(m);
    test_shared_fits();
    return test_finish("test_structured");
}
