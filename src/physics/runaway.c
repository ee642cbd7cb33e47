/*
 * runaway.c - a state that runs away stops the run instead of writing nonsense frames.
 *
 * An unstable step (a linearly implicit step too large for the stiffness, an element that
 * inverts and springs back) or a part nothing holds can feed energy into an object without
 * any input doing work; the state then grows by orders of magnitude within a few steps.
 * After every step the object's mechanical energy
 *
 *   E_mech = 1/2 v^T M v + elastic + error energy + E_pin(t) - f_ext(t) . (q - q0)
 *
 * (E_pin: the material pins' anchor, pins.h; the last term is the exact potential of gravity
 * and of constant loads) is compared with
 * a budget fixed at the first step: what the inputs can supply when the object moves by its
 * own size L,
 *
 *   B = E_mech(0) + m |g| L + sum |F| L + sum |f| V L + 1e-6 E V  (+ E V with prescribed
 *       motion of pinned control points or material, which can strain the body by order 1)
 *
 * (F point loads, f region force densities, V the volume, E the largest Young's modulus; the
 * last terms keep B away from zero). E_mech > RUNAWAY_FACTOR B is a runaway. A dissipative
 * integrator never gets near it: energy only comes from the inputs, and those are in B.
 * A static solution has E_mech = -(work of the loads) + stored energy, about minus half the
 * work for an elastic body; E_mech < -RUNAWAY_FACTOR B means the loads travelled orders of
 * magnitude beyond the body's size with nothing storing their work (parts not held).
 */
#include "runaway.h"

#include <math.h>
#include <stdlib.h>

#include "assembly.h"
#include "loads.h"
#include "pins.h"

#define RUNAWAY_FACTOR 1e4

static double largest_modulus(const sem_object *o)
{
    double E = o->def.material.youngs_modulus;
    for (int k = 0; k < o->def.n_part_materials && o->part_mats; ++k) E = fmax(E, o->part_mats[k].youngs_modulus);
    return E;
}

static double mechanical_energy(sem_object *o, double t, double *tmp, double *f)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    sem_blocks_multiply(o, 1.0, 0, 0, 0, 0, o->v, tmp);
    double kin = 0, pot = 0;
    for (size_t i = 0; i < n; ++i) kin += 0.5 * o->v[i] * tmp[i];
    double err_e = sem_error_energy(o, o->q, tmp);
    sem_external_force(o, t, f);
    for (size_t i = 0; i < n; ++i) pot -= f[i] * (o->q[i] - o->q0[i]);
    return kin + o->elastic_energy + err_e + sem_pins_energy(o, o->q, t, NULL) + pot;
}

sem_status sem_runaway_init(sem_object *o, const double gravity[3], sem_error *err)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    double *tmp = malloc(n * sizeof(double) + 1), *f = malloc(n * sizeof(double) + 1);
    if (!tmp || !f) {
        free(tmp);
        free(f);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    double e = mechanical_energy(o, 0.0, tmp, f);
    double L = o->d->length_scale, V = o->volume, E = largest_modulus(o);
    double g = sqrt(gravity[0] * gravity[0] + gravity[1] * gravity[1] + gravity[2] * gravity[2]);
    int moves = 0; /* prescribed motion (pins that stay put do no work) */
    for (int k = 0; k < o->n_presc; ++k) moves |= o->presc[k].type != SEM_PRESCRIBE_NONE;
    if (o->pins) moves |= o->pins->moves;
    double b = fabs(e) + o->mass * g * L + 1e-6 * E * V + (moves ? E * V : 0);
    for (int k = 0; k < o->def.n_point_loads; ++k) {
        const double *F = o->def.point_loads[k].force;
        b += sqrt(F[0] * F[0] + F[1] * F[1] + F[2] * F[2]) * L;
    }
    for (int k = 0; k < o->def.n_region_loads; ++k) {
        const double *fd = o->def.region_loads[k].force_density;
        b += sqrt(fd[0] * fd[0] + fd[1] * fd[1] + fd[2] * fd[2]) * V * L;
    }
    o->runaway_budget = b;
    free(tmp);
    free(f);
    return SEM_OK;
}

sem_status sem_runaway_check(sem_object *o, int is_static, double t, sem_error *err)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(o->q[i]) || !isfinite(o->v[i]))
            return sem_error_set(err, SEM_ERR_NUMERIC, "the state became non-finite (NaN) at t = %g", t);
    double *tmp = malloc(n * sizeof(double) + 1), *f = malloc(n * sizeof(double) + 1);
    if (!tmp || !f) {
        free(tmp);
        free(f);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    double e = mechanical_energy(o, t, tmp, f);
    sem_status st = SEM_OK;
    /* dynamics: energy above the budget; statics: also far below it (the loads moved a long
     * way with nothing storing their work: an equilibrium that does not exist) */
    if (is_static && -e > RUNAWAY_FACTOR * o->runaway_budget)
        st = sem_error_set(err, SEM_ERR_NUMERIC,
                           "the static solution at t = %g is not held: the loads moved %.0e times farther than "
                           "the object's size allows with nothing storing their work (%.3g J); parts free to "
                           "move (zero-energy modes) or missing pins",
                           t, -e / o->runaway_budget, -e);
    else if (!isfinite(e) || e > RUNAWAY_FACTOR * o->runaway_budget)
        st = sem_error_set(err, SEM_ERR_NUMERIC,
                           "the motion ran away at t = %g: the object's energy (%.3g J) is %.0e times what its "
                           "loads and initial state can supply (%.3g J); the step is unstable (try a smaller dt, "
                           "implicit_euler or damping) or parts are not held",
                           t, e, fabs(e) / o->runaway_budget, o->runaway_budget);
    free(tmp);
    free(f);
    return st;
}

sem_status sem_runaway_check_finite(const double *x, size_t n, double t, sem_error *err)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return sem_error_set(err, SEM_ERR_NUMERIC, "the state became non-finite (NaN) at t = %g", t);
    return SEM_OK;
}
