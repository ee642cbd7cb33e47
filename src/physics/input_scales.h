/*
 * input_scales.h - is a time step of this object meaningful in double precision?
 *
 * Internal (physics). See input_scales.c for the ratios checked and why.
 */
#ifndef SEM_PHYSICS_INPUT_SCALES_H
#define SEM_PHYSICS_INPUT_SCALES_H

#include "sem/simulation.h"

/* Checks the object's materials, loads and gravity against its size (length: a model length,
 * volume > 0) and the world's time step. SEM_ERR_INVALID with a one-line message naming the
 * quantity when a step cannot be computed meaningfully. */
sem_status sem_check_input_scales(const sem_world_def *world, const sem_object_def *object,
                                  double length, double volume, sem_error *err);

#endif
