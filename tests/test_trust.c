/* test_trust.c - a discretization or a solve that cannot be trusted says so (issue 11).
 *
 * - Zero-energy modes are found (sem_world_object_modes): the 10-section cantilever turned
 *   90 degrees about z with the authors' settings (3 x 3 rays along x, 100 points per
 *   interval, alpha 0.501, the paper's origins, no volume consistency term) has a motion
 *   nothing resists, and the parts that move in it are named; the volume consistency term
 *   (sem_object_def.blend, default) removes it, and the default discretization has none
 *   (every Table 1 model at defaults: test_table1_modes.c).
 * - No silent garbage: the static solve of that beam under gravity does not converge and
 *   fails (it used to return ok with the centre of mass 1.67 million m below the clamp); with
 *   accept_unconverged it is kept, and then the runaway check finds the loads moved five
 *   orders of magnitude farther than the body allows. A Newton step cut at one iteration fails
 *   unless accepted (then counted).
 * - Inputs that make a step meaningless are refused when the object is added: a density of
 *   1e300, a point load of 1e200 N.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/simulation.h"
#include "bench/validation.h"
#include "test_util.h"

typedef struct beam {
    sem_model *model;
    sem_discretization *disc;
    unsigned char *pin;
} beam;

/* The 5 x 1 x 1 m cantilever of 10 sections, turned 90 degrees about z when turned, clamped
 * at its x = 0 end (turned: y = 0), preprocessed with the authors' settings or the defaults. */
static int make_beam(int turned, int authors, beam *b)
{
    memset(b, 0, sizeof *b);
    sem_error err;
    b->model = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 10;
    bd.length = 5;
    bd.width = 1;
    bd.height = 1;
    if (sem_primitive_beam(b->model, &bd, &err) != SEM_OK) {
        CHECK(0, "beam: %s", err.message);
        return 0;
    }
    size_t nc = sem_model_control_points(b->model);
    double *q = malloc(3 * nc * sizeof *q);
    b->pin = calloc(nc, 1);
    sem_model_get_q(b->model, q);
    for (size_t c = 0; c < nc; ++c) {
        b->pin[c] = fabs(q[3 * c]) < 1e-12;
        if (turned) { /* (x, y, z) -> (-y, x, z) */
            double x = q[3 * c];
            q[3 * c] = -q[3 * c + 1];
            q[3 * c + 1] = x;
        }
    }
    sem_model_set_q(b->model, q);
    free(q);
    sem_preprocess_options o = sem_default_preprocess_options();
    if (authors) {
        o.rays[0] = o.rays[1] = 3;
        o.ray_axis = 0;
        o.points_per_interval = 100;
        o.alpha = 0.501;
        o.origin_rule = SEM_ORIGINS_PAPER;
    }
    if (sem_preprocess(b->model, &o, &b->disc, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        return 0;
    }
    return 1;
}

static void free_beam(beam *b)
{
    sem_discretization_destroy(b->disc);
    sem_model_destroy(b->model);
    free(b->pin);
}

/* A world (static unless integrator given) with the beam, pinned when pinned. */
static sem_world *beam_world(const beam *b, double blend, int pinned, sem_world_def wd, sem_error *err)
{
    sem_world *w = sem_world_create(&wd, err);
    if (!w) return NULL;
    sem_object_def od = sem_default_object_def();
    od.model = b->model;
    od.disc = b->disc;
    od.blend = blend;
    od.pinned = pinned ? b->pin : NULL;
    if (sem_world_add_object(w, &od, err) < 0) {
        sem_world_destroy(w);
        return NULL;
    }
    return w;
}

static sem_world_def static_def(void)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[0] = wd.gravity[1] = 0;
    wd.gravity[2] = -10;
    wd.integrator = SEM_STATIC;
    return wd;
}

static void test_modes(int full)
{
    beam b;
    sem_error err;
    sem_world *w;
    if (!full) goto defaults;
    if (!make_beam(1, 1, &b)) {
        free_beam(&b);
        return;
    }
    /* without the consistency term: a zero-energy mode, and the parts moving in it named */
    w = beam_world(&b, 0.0, 0, static_def(), &err);
    CHECK(w != NULL, "world: %s", err.message);
    if (w) {
        sem_object_modes m;
        int flags[64] = {0};
        CHECK(b.disc->n_parts <= 64, "parts %d", b.disc->n_parts);
        CHECK(sem_world_object_modes(w, 0, &m, flags, &err) == SEM_OK, "modes: %s", err.message);
        printf("turned, authors' settings, blend 0: %d spurious modes, lowest %.3g %.3g\n", m.spurious, m.values[0],
               m.values[1]);
        CHECK(m.spurious >= 1, "a zero-energy mode is found (got %d)", m.spurious);
        CHECK(fabs(m.values[0]) < SEM_SPURIOUS_MODE_TOLERANCE, "lowest %g", m.values[0]);
        int named = 0;
        for (int i = 0; i < b.disc->n_parts; ++i) named += flags[i];
        CHECK(named >= 1 && named < b.disc->n_parts, "parts not held named: %d of %d", named, b.disc->n_parts);
        sem_world_destroy(w);
    }
    /* the default consistency term holds them */
    w = beam_world(&b, SEM_DEFAULT_BLEND, 0, static_def(), &err);
    CHECK(w != NULL, "world: %s", err.message);
    if (w) {
        sem_object_modes m;
        CHECK(sem_world_object_modes(w, 0, &m, NULL, &err) == SEM_OK, "modes: %s", err.message);
        printf("turned, authors' settings, default blend: %d spurious modes, lowest %.3g\n", m.spurious, m.values[0]);
        CHECK(m.spurious == 0, "no zero-energy mode (got %d)", m.spurious);
        CHECK(m.values[0] > 1e-4, "lowest mode %g", m.values[0]);
        sem_world_destroy(w);
    }
    free_beam(&b);
defaults:
    /* the default discretization, turned: none; its lowest mode is the free beam's first
     * bending mode (Euler-Bernoulli free-free: 22.37 EI / (rho A l^4) = 1.73 E / (rho L^2)
     * with L the bounding-box diagonal 5.196; shear and the polynomials' coarseness make the
     * 5 x 1 x 1 beam softer, about 1.1) */
    if (!make_beam(1, 0, &b)) {
        free_beam(&b);
        return;
    }
    w = beam_world(&b, SEM_DEFAULT_BLEND, 0, static_def(), &err);
    CHECK(w != NULL, "world: %s", err.message);
    if (w) {
        sem_object_modes m;
        CHECK(sem_world_object_modes(w, 0, &m, NULL, &err) == SEM_OK, "modes: %s", err.message);
        printf("turned, defaults: %d spurious modes, lowest %.4g %.4g (converged %d)\n", m.spurious, m.values[0],
               m.values[1], m.converged);
        CHECK(m.spurious == 0, "no zero-energy mode (got %d)", m.spurious);
        CHECK(m.values[0] > 0.5 && m.values[0] < 1.8, "first bending mode %g", m.values[0]);
        CHECK(fabs(m.values[0] - m.values[1]) < 0.02 * m.values[0], "square section: two equal bending modes %g %g",
              m.values[0], m.values[1]);
        sem_world_destroy(w);
    }
    free_beam(&b);
}

static void test_no_silent_garbage(int full)
{
    beam b;
    sem_error err;
    sem_world_def wd;
    if (!full) goto well_posed;
    if (!make_beam(1, 1, &b)) {
        free_beam(&b);
        return;
    }
    /* A static step as sem run takes it (50 Newton iterations). There is no equilibrium;
     * where Newton's iterates go is decided by round-off in a singular system, so it fails
     * either way: out of iterations, a matrix that is no longer positive definite, or (when
     * unconverged solves are accepted) the runaway check. */
    wd = static_def();
    for (int accept = 0; accept < 2; ++accept) {
        wd.accept_unconverged = accept;
        sem_world *w = beam_world(&b, 0.0, 1, wd, &err);
        CHECK(w != NULL, "world: %s", err.message);
        if (!w) continue;
        sem_error_clear(&err);
        sem_status st = sem_world_step(w, &err);
        printf("turned, authors' settings, static step (accept_unconverged %d): %s\n", accept, err.message);
        CHECK(st == SEM_ERR_NUMERIC &&
                  (strstr(err.message, accept ? "not held" : "did not converge") ||
                   strstr(err.message, "not positive definite")),
              "the static step fails and says why: %s", err.message);
        sem_world_destroy(w);
    }
    free_beam(&b);

well_posed:
    /* a well-posed problem with Newton cut at one iteration */
    if (!make_beam(0, 0, &b)) {
        free_beam(&b);
        return;
    }
    wd = static_def();
    wd.integrator = SEM_IMPLICIT_EULER;
    wd.dt = 0.05;
    wd.newton_max_iterations = 1;
    sem_world *w = beam_world(&b, SEM_DEFAULT_BLEND, 1, wd, &err);
    CHECK(w != NULL, "world: %s", err.message);
    if (w) {
        sem_error_clear(&err);
        CHECK(sem_world_step(w, &err) == SEM_ERR_NUMERIC && strstr(err.message, "did not converge"),
              "one Newton iteration is not enough: %s", err.message);
        sem_world_destroy(w);
    }
    wd.accept_unconverged = 1;
    w = beam_world(&b, SEM_DEFAULT_BLEND, 1, wd, &err);
    CHECK(w != NULL, "world: %s", err.message);
    if (w) {
        CHECK(sem_world_step(w, &err) == SEM_OK, "accepted: %s", err.message);
        CHECK(sem_world_get_counters(w).unconverged_solves == 1, "counted: %ld",
              sem_world_get_counters(w).unconverged_solves);
        sem_world_destroy(w);
    }
    /* converged solves count nothing */
    wd.newton_max_iterations = 50;
    w = beam_world(&b, SEM_DEFAULT_BLEND, 1, wd, &err);
    if (w) {
        for (int k = 0; k < 3; ++k) CHECK(sem_world_step(w, &err) == SEM_OK, "step: %s", err.message);
        CHECK(sem_world_get_counters(w).unconverged_solves == 0, "none unconverged");
        sem_world_destroy(w);
    }

    /* meaningless inputs are refused when the object is added */
    wd = static_def();
    wd.integrator = SEM_IMPLICIT_EULER;
    wd.dt = 0.01;
    w = sem_world_create(&wd, &err);
    if (w) {
        sem_object_def od = sem_default_object_def();
        od.model = b.model;
        od.disc = b.disc;
        od.pinned = b.pin;
        od.material.density = 1e300;
        sem_error_clear(&err);
        CHECK(sem_world_add_object(w, &od, &err) < 0 && strstr(err.message, "density"), "density 1e300: %s",
              err.message);
        od.material.density = 1000;
        sem_point_load pl = {{5, 0.5, 0.5}, {0, 0, -1e200}};
        od.point_loads = &pl;
        od.n_point_loads = 1;
        sem_error_clear(&err);
        CHECK(sem_world_add_object(w, &od, &err) < 0 && strstr(err.message, "point load"), "1e200 N: %s",
              err.message);
        pl.force[2] = -1e3; /* a sensible load is fine */
        CHECK(sem_world_add_object(w, &od, &err) == 0, "1e3 N: %s", err.message);
        sem_world_destroy(w);
    }
    free_beam(&b);
}

int main(void)
{
    /* the authors'-settings beam (300 points per cell column, Newton to its limit) takes
     * minutes under the sanitizers: there only the default-settings checks run */
    int full = getenv("SEM_SANITIZED") == NULL;
    test_modes(full);
    test_no_silent_garbage(full);
    return test_finish("test_trust");
}
