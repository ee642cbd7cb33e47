/*
 * world.h - the world: its settings, objects, the systems a step solves, clock and
 * counters (internal to src/physics/). Objects are numbered in the order they were added
 * (the public API's object ids).
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
    int n_systems;
    sem_system **systems;      /* what a step solves: the objects, each in one system */
    double time;
    int step_index;
    double last_step_s, last_factor_s;
    int last_iterations;
    sem_world_counters counters;
    struct sem_contact *contact; /* colliders, collision meshes, friction (contact_world.h) */
};

/* Islands (contact between objects, not solve_together): the world's systems become one per
 * group of objects that may touch within a step of h (sem_contact_islands), made again only
 * when the groups change. Objects keep their world order within a system. */
sem_status sem_world_regroup(sem_world *w, double h, sem_error *err);

#endif
