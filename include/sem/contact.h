/*
 * sem/contact.h - contact and friction between a world's objects and with static colliders
 * (paper Sec. 7-8; design notes in docs/simulation.md, "Contact").
 *
 * Every object carries a collision mesh: its render tessellation, whose vertices are linear
 * in the control points (x = J q). Those points are kept out of the colliders (planes and
 * triangle meshes that do not move) and out of the other objects' surfaces by penalty
 * springs: energy 1/2 k (d - thickness)^2 for a point at signed distance d < thickness, with
 * k = stiffness x the point's share of the surface area. The springs are a potential: its
 * gradient and PSD Hessian enter Newton (implicit Euler, statics) and the linearly implicit
 * matrix. Friction is Coulomb's, as a lagged smoothed potential (IPC, Li et al. 2020).
 *
 * Usage: the world definition's contact settings (sem_world_def.contact) hold the defaults
 * below; sem_world_add_collider adds a static collider; contact between objects is on
 * whenever the world has two objects or more, and self-contact (sem_contact_def.self)
 * wherever contact is on.
 */
#ifndef SEM_CONTACT_H
#define SEM_CONTACT_H

#include "sem/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How surfaces are kept apart (sem_contact_def.model). */
typedef enum sem_contact_model {
    /* Penalty springs on the collision points (the default): cheap; a point may sink a
     * little into what it presses on, and a fast or thin one can pass through. */
    SEM_CONTACT_PENALTY,
    /* IPC's log barrier on the distances between the collision surfaces (points against
     * triangles, edges against edges), with a continuous collision check that bounds every
     * Newton step: surfaces never cross (Li et al. 2020; docs/simulation.md). Implicit Euler
     * and statics only. */
    SEM_CONTACT_BARRIER
} sem_contact_model;

/* Contact settings of a world (zero: the defaults). */
typedef struct sem_contact_def {
    /* Penalty stiffness per unit area (N/m^3: the contact pressure per metre of
     * penetration); <= 0: 1000 E / L with E the smaller Young's modulus of the two sides and
     * L the object's size (bounding-box diagonal): a body resting on a face sinks into it by
     * about 1e-3 of the strain its own weight causes (the springs are much stiffer than the
     * body they stop). */
    double stiffness;
    /* Distance from a surface at which the springs start (m); <= 0: 1e-3 L of each object.
     * A resting object floats about this far above what it rests on. The barrier model's
     * reach dhat (its surfaces feel each other from this distance on). */
    double thickness;
    /* Self-contact: an object's surface is kept out of itself, away from where it meets
     * itself at rest (a point never collides with its own surface within twice the search
     * radius, 2 (thickness + 0.05 L), of where it is at rest). 0: on wherever contact is on
     * (colliders, or two objects or more); 1: on, and contact is on for a lone object too
     * (a mat twisted in the air); -1: off. */
    int self;
    int disabled;          /* 1: no contact at all (objects pass through each other) */
    /* Friction's smoothing velocity (m/s; IPC's epsilon_v): below it, sticking is an
     * ultra-stiff spring; a held object creeps at about this speed. <= 0: 1e-3 m/s. */
    double friction_velocity;
    /* Collision tessellation: cells per knot span and direction; <= 0: chosen per model so
     * that the points are no farther apart than about 1/16 of its size (2..16). */
    int resolution;
    sem_contact_model model;
} sem_contact_def;

typedef enum sem_collider_type {
    SEM_COLLIDER_PLANE, /* the half-space n . (x - point) < 0 is solid */
    SEM_COLLIDER_MESH   /* a triangle mesh (terrain, obstacle); its front side (counter-
                           clockwise triangles) is free space */
} sem_collider_type;

typedef struct sem_collider_def {
    sem_collider_type type;
    double point[3], normal[3];        /* plane; normal non-zero (normalized on use) */
    const double *vertices;            /* mesh: 3 per vertex, metres (copied) */
    int n_vertices;
    const int *triangles;              /* mesh: 3 per triangle (copied) */
    int n_triangles;
    double friction;                   /* Coulomb coefficient; a pair uses sqrt(mu_a mu_b) */
} sem_collider_def;

#define SEM_DEFAULT_FRICTION 0.5

/* A plane through the origin facing +z, friction SEM_DEFAULT_FRICTION. */
sem_collider_def sem_default_collider_def(void);

/* What the last step's contact did (sem_world_contact_stats). */
typedef struct sem_contact_stats {
    int contacts;     /* contact points pushed at the end of the last step */
    int self_contacts; /* of which against their own object's surface (self-contact) */
    double min_gap;   /* smallest signed distance of a collision point to another surface
                         it is near (m; negative: penetration); +inf when none is near. The
                         barrier model: the smallest distance of its pairs (points against
                         triangles, edges against edges), never <= 0 */
    double seconds;   /* wall time of the last step spent in contact */
    int colliders;
} sem_contact_stats;

#ifdef __cplusplus
}
#endif
#endif
