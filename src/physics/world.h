/*
 * world.h - the world: its settings, objects, clock and counters (internal to src/physics/).
 */
#ifndef SEM_PHYSICS_WORLD_H
#define SEM_PHYSICS_WORLD_H

#include "object.h"
#include "system.h"
#include "sem/simulation.h"

struct sem_world {
    sem_world_def def;
    int n_objects, cap;
    sem_object **objects;
    sem_system **systems;      /* per object: the system it is solved in (owned) */
    double time;
    int step_index;
    double last_step_s, last_factor_s;
    int last_iterations;
    sem_world_counters counters;
};

#endif
