/*
 * narrow_phase.h - distances between a point and the primitives of a surface: a plane, a
 * triangle (closest point, its barycentric coordinates and the feature it lies on), and the
 * signed distance the contact springs act on (internal to src/contact/).
 */
#ifndef SEM_CONTACT_NARROW_PHASE_H
#define SEM_CONTACT_NARROW_PHASE_H

/* Closest point feature of a triangle: its inside, edge k (from vertex k to k + 1), or
 * vertex k. */
typedef enum sem_tri_feature { SEM_TRI_FACE, SEM_TRI_EDGE, SEM_TRI_VERTEX } sem_tri_feature;

typedef struct sem_tri_closest {
    double point[3];   /* closest point of the triangle */
    double bary[3];    /* its barycentric coordinates */
    double dist2;      /* squared distance */
    sem_tri_feature feature;
    int index;         /* edge or vertex index (0..2) */
} sem_tri_closest;

/* Closest point of triangle (a, b, c) to p (Ericson, Real-Time Collision Detection 5.1.5). */
void sem_point_triangle_closest(const double p[3], const double a[3], const double b[3],
                                const double c[3], sem_tri_closest *out);

/* Signed distance of p to a surface whose closest point is c, with an outward direction
 * `outward` at c (a face normal, or a pseudonormal at an edge or vertex): |p - c| with the
 * sign of (p - c) . outward; *normal receives the distance's gradient in p (unit). */
double sem_signed_distance(const double p[3], const double c[3], const double outward[3],
                           double normal[3]);

#endif
