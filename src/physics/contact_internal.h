/*
 * contact_internal.h - the data of a world's contact, shared by its two files (internal to
 * src/physics/): contact_world.c (colliders, the penalty springs, friction, the step) and
 * contact_barrier.c (the barrier model: its pairs and the continuous collision check).
 */
#ifndef SEM_CONTACT_INTERNAL_H
#define SEM_CONTACT_INTERNAL_H

#include "contact_world.h"
#include "contact/collision_mesh.h"
#include "point_terms.h"

/* Default penalty stiffness per area: KAPPA E / L (see sem_contact_def.stiffness). */
#define KAPPA 1000.0
#define DEFAULT_THICKNESS 1e-3     /* x L */
#define SEARCH_DEPTH 0.05          /* x L: how deep a point may be and still be pushed out */
#define DEFAULT_FRICTION_VELOCITY 1e-3
#define MAX_WEIGHTS 256            /* a point's row plus a triangle's three rows; an edge pair's four */
/* Self-contact's exclusion rule: a point never collides with the part of its own object's
 * surface that lies within SELF_EXCLUSION x the search radius of it at rest (its own
 * neighbourhood, the other sheet of a thin wall, the other side of a seam). Twice the
 * search radius: at rest no point is within reach of a surface it may collide with. */
#define SELF_EXCLUSION 2.0

typedef struct collider {
    sem_collider_type type;
    double point[3], normal[3];
    double friction;
    int n_vertices, n_triangles;
    double *vertices;
    int *triangles;
    double *face_normal;   /* unit, per triangle */
    double *edge_normal;   /* per triangle edge (3 per triangle): sum of the faces' normals */
    double *vertex_normal; /* angle-weighted pseudonormal (Baerentzen and Aanaes 2005) */
    sem_bvh bvh;
    int n_edges;
    int *edge_tri;         /* 3 per edge (collision_topology.h; the barrier's edge pairs) */
    sem_bvh edge_bvh;
    int *mark;             /* n_vertices scratch of the barrier's vertex queries */
} collider;

typedef struct contact_object {
    const sem_object *object;
    int built;               /* mesh and the numbers below (mesh_for) */
    sem_collision_mesh mesh;
    double youngs, friction, length, thickness;
    int self_far;            /* at the last detection no point can reach its own surface
                              * beyond the exclusion rule (self_far_apart): no self query */
    double *x1;              /* the barrier's collision check: the points at the step's end */
    int sweep_far;           /* ... and no point can meet its own surface on the way */
} contact_object;

/* An active contact: point `point` of system object k against a collider or a triangle of
 * system object `other`. */
typedef struct contact_rec {
    int k, point, other, collider, triangle;
    double bary[3];
    double d, n[3];          /* signed distance and its gradient */
    double stiffness, thickness, mu;
} contact_rec;

/* A barrier pair (contact.model "barrier"): two primitives, by their vertices, closer
 * than the reach; the relative point r = sum coef_i x_i, its length the distance (a plane:
 * n . r, signed). */
typedef struct barrier_pair {
    int nv;                  /* vertices, 1 to 4 */
    int object[4];           /* system object of each vertex, or -1: a collider's vertex */
    int point[4];            /* the object's collision point, or the collider's vertex */
    double coef[4];
    double d, n[3];          /* distance and its gradient in r (unit) */
    double kappa, dhat, mu;  /* stiffness, the barrier's reach, friction */
    double mollifier;        /* 1; an edge pair's mollifier (barrier.h) */
    double dm[4][3];         /* its gradient per vertex */
    int collider;            /* the collider of its -1 vertices (or plane), or -1 */
    int edge;                /* an edge-edge pair */
} barrier_pair;

/* A friction contact fixed at the start of a step (friction.h). */
typedef struct friction_rec {
    int first, count;        /* weights */
    double T[6], X0[3], mu_lambda;
    double u_last[2];
    signed char slipping;    /* at the last iterate with a Hessian: 1, 0; -1: none yet */
} friction_rec;

struct sem_contact {
    sem_contact_def def;
    int n_colliders, cap_colliders;
    collider *colliders;
    int n_objects, cap_objects;
    contact_object *objects;
    /* per evaluation */
    int n_recs, cap_recs;
    contact_rec *recs;
    contact_rec *slots;      /* detection scratch: per point of an object, its contacts */
    int *slot_count;
    size_t cap_slots;
    int cap_count;
    int *sys_to_contact;     /* system object -> contact object */
    int n_sys;
    double min_gap;
    sem_point_terms terms;   /* Hessian of the last sem_contact_potential with a gradient */
    sem_point_terms friction_terms;
    /* friction of the current step */
    int n_friction, cap_friction;
    friction_rec *friction;
    int n_fweights, cap_fweights;
    sem_point_weight *fweights;
    double friction_eps;     /* eps_v h of the step; 0: no friction */
    int n_couplings, cap_couplings;
    sem_system_coupling *couplings; /* the blocks contact between objects needs */
    long rebuilds;           /* systems made again for new coupling blocks */
    sem_contact_stats stats;
    /* the barrier model (contact_barrier.c) */
    int n_pairs, cap_pairs;
    barrier_pair *pairs;     /* the pairs closer than their reach at the last detection */
    int *candidates;         /* collider vertices near an object */
    int cap_candidates;
    struct pair_list *lists; /* per thread: the pairs it found (contact_barrier.c) */
    int n_lists;
};

/* The contact stiffness per area: the setting, or KAPPA E / L (E the softer side's modulus,
 * L the point's object's size). */
double sem_contact_stiffness(const sem_contact *c, double youngs, double length);
/* The contact objects of the system's objects (c->sys_to_contact), their meshes built. */
sem_status sem_contact_map_system(sem_contact *c, const sem_system *s, sem_error *err);
/* Self-contact on (sem_contact_def.self: 0 the default, on; -1 off). */
int sem_contact_self_on(const sem_contact *c);
/* Is the mesh so near a rigid motion of its rest shape that no point can be within the
 * radius of a triangle the self-contact exclusion rule leaves it? */
int sem_contact_self_far_apart(const sem_collision_mesh *m, double radius);
/* The same at positions x (3 per point); with rotation (may be NULL) the rotation it fitted
 * (row-major), set whenever the test got that far. */
int sem_contact_self_far_apart_at(const sem_collision_mesh *m, const double *x, double radius, double rotation[9]);
/* grad += sum_i w_i f over the weights' dofs */
void sem_contact_add_gradient(const sem_system *s, const sem_point_weight *w, int n, const double f[3], double *grad);

/* The barrier model (contact_barrier.c). */
/* Every pair closer than its reach dhat + margin x the search radius (margin 0: the pairs
 * the barrier acts on) at the system's vector q into c->pairs; c->min_gap their smallest
 * distance. */
sem_status sem_barrier_detect(sem_contact *c, const sem_system *s, const double *q, double margin, sem_error *err);
/* Energy of c->pairs (they are at q); gradient into grad and Hessian into terms when grad
 * is given. */
sem_status sem_barrier_energy(sem_contact *c, const sem_system *s, double *grad, sem_point_terms *terms,
                              double *energy, sem_error *err);
/* The weights of a pair's relative point (at most MAX_WEIGHTS); returns their count. */
int sem_barrier_weights(const sem_contact *c, const barrier_pair *p, sem_point_weight *w);
/* Frees the threads' pair lists. */
void sem_barrier_free_lists(sem_contact *c);
/* The colliders' edge lists and trees (at sem_contact_add_collider). */
sem_status sem_barrier_collider_edges(collider *k, sem_error *err);

#endif
