/*
 * runaway.h - a state that runs away stops the run (internal to src/physics/; see runaway.c).
 */
#ifndef SEM_PHYSICS_RUNAWAY_H
#define SEM_PHYSICS_RUNAWAY_H

#include "object.h"

/* The object's energy budget, from its state at rest (when it is added). */
sem_status sem_runaway_init(sem_object *o, const double gravity[3], sem_error *err);
/* After a step to time t: SEM_ERR_NUMERIC with a one-line message when the object's
 * mechanical energy exceeds by orders of magnitude what its inputs can supply, or its state
 * is not finite (is_static: also far below, see runaway.c). */
sem_status sem_runaway_check(sem_object *o, int is_static, double t, sem_error *err);
/* After a step to time t: SEM_ERR_NUMERIC with a one-line message when any of x[0..n-1] (the
 * system's new positions or velocities) is not finite. */
sem_status sem_runaway_check_finite(const double *x, size_t n, double t, sem_error *err);

#endif
