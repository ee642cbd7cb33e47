/*
 * loads.h - what acts on an object from outside: gravity, region and point loads, and the
 * prescribed motion of its pinned control points (internal to src/physics/).
 *
 * Every load is a force on the quadrature points, taken to the control points through
 * Gamma^T (x = Gamma q at the quadrature points, Eq. 12):
 *   gravity       f_g = sum_p rho_p vol_p Gamma_p^T g, computed once; its potential -f_g . q
 *                 is exact because x is linear in q;
 *   region loads  a force density on the quadrature points inside a box, constant or
 *                 scaled by (1 + sin(2 pi f t + phase)) / 2;
 *   point loads   a force at the quadrature point nearest its rest position.
 * Pinned control points are not solved for (see system.h). Each follows its prescription
 * (an affine map of its rest position, or a rotation about an axis at a rate) or stays
 * where it is; the integrators move them to sem_prescribed_position at the end of a step.
 */
#ifndef SEM_PHYSICS_LOADS_H
#define SEM_PHYSICS_LOADS_H

#include "object.h"

/* Copies the definition's point and region loads into the object and sets its pinned
 * flags and prescriptions (a prescribe group pins its points). */
sem_status sem_loads_init(sem_object *o, const sem_object_def *def, sem_error *err);
/* f_gravity for gravity g (needs the object's point_rho_vol). */
sem_status sem_loads_gravity(sem_object *o, const double g[3], sem_error *err);
/* A prescription applied to a rest position x0 at time t (out unchanged for
 * SEM_PRESCRIBE_NONE): the pinned control points' motion, and the material pins' (pins.h). */
void sem_prescription_apply(const sem_prescribe *pr, double t, const double x0[3], double out[3]);
/* Where pinned control point c is at time t: its prescription applied to its rest position,
 * or (no prescription) where it is now. */
void sem_prescribed_position(const sem_object *o, double t, int c, double out[3]);
/* The external forces at time t on the control points (3 n_ctrl): gravity, region loads,
 * point loads. */
void sem_external_force(const sem_object *o, double t, double *f);

#endif
