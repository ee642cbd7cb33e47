/*
 * narrow_phase.h - distances between the primitives of surfaces: a point and a triangle
 * (closest point, its barycentric coordinates and the feature it lies on: geometry's
 * sem_point_triangle_closest, geometry/point_triangle.h), the signed distance the contact
 * springs act on, and two segments (the barrier's edge-edge pairs) (internal to
 * src/contact/).
 */
#ifndef SEM_CONTACT_NARROW_PHASE_H
#define SEM_CONTACT_NARROW_PHASE_H

#include "geometry/point_triangle.h"

/* Signed distance of p to a surface whose closest point is c, with an outward direction
 * `outward` at c (a face normal, or a pseudonormal at an edge or vertex): |p - c| with the
 * sign of (p - c) . outward; *normal receives the distance's gradient in p (unit). */
double sem_signed_distance(const double p[3], const double c[3], const double outward[3],
                           double normal[3]);

/* Closest points of segments a0-a1 and b0-b1 (Ericson, Real-Time Collision Detection,
 * 5.1.9): a0 + s (a1 - a0) and b0 + t (b1 - b0), s, t in [0, 1]; returns their squared
 * distance. Parallel segments give one of their closest pairs; a segment of zero length
 * its first end. */
double sem_segment_closest(const double a0[3], const double a1[3], const double b0[3], const double b1[3],
                           double *s, double *t);

#endif
