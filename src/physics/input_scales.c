/*
 * input_scales.c - inputs whose numbers make a step meaningless are errors, not `ok`.
 *
 * A density of 1e300 or a point load of 1e200 N is a valid double, and the solver returns
 * something for it: the elastic forces vanish below the rounding of the inertia (the object
 * "freezes" or falls through itself), or the first step moves the control points by 1e190 m.
 * Nothing in the result says so. The dimensionless ratios below bound what double precision
 * (16 digits) can carry through one step of M + h^2 K (the step matrix) and q + h v:
 *
 *   stiffness / inertia   r = h^2 E / (rho L^2)        (h: dt; L: the model's length)
 *       r < 1e-13: the stiffness is below the rounding of the mass matrix: no elastic
 *       response can be computed (density far too large, or E far too small, for dt).
 *       r > 1e15: the inertia is below the rounding of the stiffness (the opposite).
 *   load / inertia         a h^2 / L with a = |g| or |F| / (rho V)  (displacement per step)
 *   load / stiffness       |g| rho L / E, |F| / (E L^2), |f| L / E  (strain of the load)
 *       either above 1e6: the load moves or strains the object by a million times its size
 *       in one step or at equilibrium; the positions lose every significant digit.
 * The static integrator has no time step: only the load/stiffness ratio applies.
 * Heterogeneous objects are checked with every material they use.
 */
#include "input_scales.h"

#include <math.h>
#include <stdio.h>

#define MIN_STIFFNESS_RATIO 1e-13
#define MAX_STIFFNESS_RATIO 1e15
#define MAX_LOAD_RATIO 1e6

/* |v| without overflow for components near the largest doubles (a 1e200 N load) */
static double norm3(const double *v)
{
    double m = fmax(fabs(v[0]), fmax(fabs(v[1]), fabs(v[2])));
    if (!(m > 0) || !isfinite(m)) return m;
    double a = v[0] / m, b = v[1] / m, c = v[2] / m;
    return m * sqrt(a * a + b * b + c * c);
}

static sem_status check_material(const sem_world_def *w, const sem_object_def *o,
                                 const sem_material *m, const char *which, double L, double V,
                                 sem_error *err)
{
    const double rho = m->density, E = m->youngs_modulus, h = w->dt;
    if (!(rho > 0) || !isfinite(rho) || !(E > 0) || !isfinite(E))
        return sem_error_set(err, SEM_ERR_INVALID, "%s: density and Young's modulus must be "
                             "positive and finite (got %g, %g)", which, rho, E);
    if (w->integrator != SEM_STATIC) {
        double r = h * h * E / (rho * L * L);
        if (!(r >= MIN_STIFFNESS_RATIO))
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s: density %g kg/m^3 is too large for Young's modulus %g Pa "
                                 "at dt %g s on a %g m object: the elastic forces are below the "
                                 "rounding of the inertia (h^2 E / (rho L^2) = %.3g < %g)",
                                 which, rho, E, h, L, r, MIN_STIFFNESS_RATIO);
        if (!(r <= MAX_STIFFNESS_RATIO))
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s: Young's modulus %g Pa is too large for density %g kg/m^3 "
                                 "at dt %g s on a %g m object: the inertia is below the rounding "
                                 "of the stiffness (h^2 E / (rho L^2) = %.3g > %g)",
                                 which, E, rho, h, L, r, MAX_STIFFNESS_RATIO);
    }
    double g = norm3(w->gravity);
    if (g > 0) {
        if (!isfinite(g)) return sem_error_set(err, SEM_ERR_INVALID, "gravity is not finite");
        if (w->integrator != SEM_STATIC && g * h * h / L > MAX_LOAD_RATIO)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "gravity %g m/s^2 moves a %g m object by %.3g times its size "
                                 "in one step of %g s",
                                 g, L, g * h * h / L, h);
        if (g * rho * L / E > MAX_LOAD_RATIO)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s: gravity %g m/s^2 strains a %g m object of density %g "
                                 "kg/m^3 and Young's modulus %g Pa by %.3g",
                                 which, g, L, rho, E, g * rho * L / E);
    }
    for (int k = 0; k < o->n_point_loads; ++k) {
        double F = norm3(o->point_loads[k].force);
        if (!isfinite(F))
            return sem_error_set(err, SEM_ERR_INVALID, "point load %d is not finite", k);
        if (F / (E * L * L) > MAX_LOAD_RATIO)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "point load %d of %g N strains a %g m object of Young's modulus "
                                 "%g Pa by %.3g",
                                 k, F, L, E, F / (E * L * L));
        if (w->integrator != SEM_STATIC && F / (rho * V) * h * h / L > MAX_LOAD_RATIO)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "point load %d of %g N moves a %g kg object by %.3g times its "
                                 "size in one step",
                                 k, F, rho * V, F / (rho * V) * h * h / L);
    }
    for (int k = 0; k < o->n_region_loads; ++k) {
        double f = norm3(o->region_loads[k].force_density);
        if (!isfinite(f))
            return sem_error_set(err, SEM_ERR_INVALID, "region load %d is not finite", k);
        if (f * L / E > MAX_LOAD_RATIO ||
            (w->integrator != SEM_STATIC && f / rho * h * h / L > MAX_LOAD_RATIO))
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "region load %d of %g N/m^3 is too large for a %g m object "
                                 "(density %g kg/m^3, Young's modulus %g Pa)",
                                 k, f, L, rho, E);
    }
    for (int e = 0; e < 3; ++e)
        if (!isfinite(o->initial_velocity[e]) || !isfinite(o->initial_angular_velocity[e]))
            return sem_error_set(err, SEM_ERR_INVALID, "initial velocity is not finite");
    if (w->integrator != SEM_STATIC &&
        (norm3(o->initial_velocity) + norm3(o->initial_angular_velocity) * L) * h / L >
            MAX_LOAD_RATIO)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "the initial velocity moves a %g m object by more than %g times its "
                             "size in one step",
                             L, MAX_LOAD_RATIO);
    return SEM_OK;
}

sem_status sem_check_input_scales(const sem_world_def *world, const sem_object_def *object,
                                  double length, double volume, sem_error *err)
{
    if (!(length > 0) || !isfinite(length) || !(volume > 0) || !isfinite(volume))
        return sem_error_set(err, SEM_ERR_INVALID, "the object has no size (length %g, volume %g)",
                             length, volume);
    if (world->integrator != SEM_STATIC && (!(world->dt > 0) || !isfinite(world->dt)))
        return sem_error_set(err, SEM_ERR_INVALID, "dt must be positive and finite (got %g)",
                             world->dt);
    sem_status st = check_material(world, object, &object->material, "material", length, volume,
                                   err);
    for (int k = 0; k < object->n_part_materials && st == SEM_OK; ++k) {
        char which[48];
        snprintf(which, sizeof which, "part material %d", k);
        st = check_material(world, object, &object->part_materials[k], which, length, volume, err);
    }
    return st;
}
