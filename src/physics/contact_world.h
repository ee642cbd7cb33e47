/*
 * contact_world.h - a world's contact: its colliders, every object's collision mesh, the
 * friction lagged at the start of a step, and the contact potential the integrators add
 * (internal; the world owns one, see src/physics/world.h).
 *
 * How a step uses it (docs/simulation.md, "Contact"):
 *   sem_contact_begin_step    at q_n: finds the active contacts and fixes friction's normal
 *                             forces, tangent planes and reference points (IPC's lagging);
 *                             objects near each other get their coupling blocks in the
 *                             system's pattern (a new system when blocks are missing)
 *   sem_contact_potential     Newton (implicit Euler, statics): the energy of the springs
 *                             and of friction at any q of the system, its gradient, and its
 *                             Hessian as point terms (src/physics/point_terms.h) that Newton
 *                             adds to the matrix after sem_system_fill
 *   sem_contact_linearized    the linearly implicit step: springs at q_n, friction at
 *                             q_n + h v_n, into its matrix and right-hand side
 *   sem_contact_end_step      counts the contacts and the smallest gap at q_{n+1}
 *   sem_contact_max_step      the barrier model: how much of a Newton step keeps every
 *                             surface apart (continuous collision check)
 *
 * Detection. Every collision point (collision_mesh.h) is tested against every collider
 * (planes: the signed distance; triangle meshes: the nearest triangle within a search
 * radius through the mesh's tree, signed by its pseudonormals) and against the other
 * objects' triangle meshes (refitted trees), within the radius thickness + L / 20 (L the
 * point's object's size): a point that went deeper than L / 20 into a mesh in one step is
 * lost (tunnels). Planes are half-spaces and have no such limit.
 *
 * Contact between objects needs both in one linear system: while it is on (two objects or
 * more, contact not disabled) the world solves all its objects in one system.
 * Results do not depend on the thread count: points are visited in order.
 */
#ifndef SEM_CONTACT_WORLD_H
#define SEM_CONTACT_WORLD_H

#include "object.h"
#include "point_terms.h"
#include "system.h"
#include "sem/contact.h"

typedef struct sem_contact sem_contact;

sem_status sem_contact_create(const sem_contact_def *def, sem_contact **out, sem_error *err);
void sem_contact_destroy(sem_contact *c);
sem_status sem_contact_add_collider(sem_contact *c, const sem_collider_def *def, sem_error *err);
/* The object's collision mesh, from its model (the next object of the world). */
sem_status sem_contact_add_object(sem_contact *c, const sem_object *o, sem_error *err);
/* Undoes the last sem_contact_add_object (the world could not add that object). */
void sem_contact_remove_last_object(sem_contact *c);
/* 1 when objects push each other (at least two objects, contact not disabled). */
int sem_contact_between_objects(const sem_contact *c);
/* 1 when anything can touch (colliders, or contact between objects). */
int sem_contact_active(const sem_contact *c);

/* Islands: island[i] = the lowest index of the objects (objects[0..n), each in the world)
 * that object i may touch within a step of h, transitively: their control points' boxes
 * (which hold their surfaces), widened by three search radii and by h times their fastest
 * control point's speed, overlap. Objects of different islands are solved apart. */
sem_status sem_contact_islands(sem_contact *c, sem_object *const *objects, int n, double h, int *island,
                               sem_error *err);
/* The barrier model, after a step solved in several systems: an error if objects of
 * different systems ended within reach of each other (their crossing would have gone
 * unchecked; the islands are grown by twice the predicted move so that it does not happen). */
sem_status sem_contact_check_islands(sem_contact *c, sem_object *const *objects, int n, sem_error *err);
/* Starts a world step: the statistics (contacts, min_gap, seconds) sum over its systems. */
void sem_contact_begin_world_step(sem_contact *c);
/* Also makes the system again (solver: its choice) when objects came near each other and
 * its pattern lacks the coupling blocks their contact needs: *s may change. */
sem_status sem_contact_begin_step(sem_contact *c, sem_system **s, double h, sem_solver_choice solver,
                                  sem_error *err);
/* The contact energy at the system's vector q (springs; friction when h > 0); its gradient
 * is added to grad (n_dofs, may be NULL) and, with grad, its Hessian becomes the terms
 * sem_contact_terms returns. */
double sem_contact_potential(sem_contact *c, const sem_system *s, const double *q, double h, double *grad,
                             sem_error *err);
const sem_point_terms *sem_contact_terms(const sem_contact *c);
/* The linearly implicit step: the system's values (already filled) get h^2 (springs +
 * friction) and rhs (full vectors) -h grad + h^2 A_friction v_n. */
sem_status sem_contact_linearized(sem_contact *c, sem_system *s, double h, double *rhs, sem_error *err);
/* Counts the contacts and the smallest gap at the step's end; the barrier model fails
 * there if two surfaces touch (which its collision check rules out). */
sem_status sem_contact_end_step(sem_contact *c, const sem_system *s, sem_error *err);

/* The barrier model (contact.model "barrier", contact_barrier.c): 1 when it is on and
 * anything can touch. */
int sem_contact_barrier(const sem_contact *c);
/* The largest t in [0, 1] such that the system's surfaces, moved linearly from q to
 * q + t scale dq, touch nowhere on the way (1 without the barrier model). */
sem_status sem_contact_max_step(sem_contact *c, const sem_system *s, const double *q, const double *dq, double scale,
                                double *t, sem_error *err);
void sem_contact_get_stats(const sem_contact *c, sem_contact_stats *out);

#endif
