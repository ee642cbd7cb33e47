/*
 * narrow_phase.h - distances between a point and the primitives of a surface: a triangle
 * (closest point, its barycentric coordinates and the feature it lies on: geometry's
 * sem_point_triangle_closest, geometry/point_triangle.h) and the signed distance the contact
 * springs act on (internal to src/contact/).
 */
#ifndef SEM_CONTACT_NARROW_PHASE_H
#define SEM_CONTACT_NARROW_PHASE_H

#include "geometry/point_triangle.h"

/* Signed distance of p to a surface whose closest point is c, with an outward direction
 * `outward` at c (a face normal, or a pseudonormal at an edge or vertex): |p - c| with the
 * sign of (p - c) . outward; *normal receives the distance's gradient in p (unit). */
double sem_signed_distance(const double p[3], const double c[3], const double outward[3],
                           double normal[3]);

#endif
