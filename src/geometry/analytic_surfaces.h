/*
 * geometry/analytic_surfaces.h - exact rational B-spline forms of the analytic surfaces CAD
 * files use (planes, right circular cylinders and cones, spheres, tori: IGES 5.3 entities
 * 190-198), built in a frame (internal; used by the IGES reader).
 *
 * Every curved direction is the 9-point rational quadratic circle (The NURBS Book, Sec. 7.5),
 * so the surfaces are exact, with u running once around the axis from the frame's x axis.
 * Planes, cylinders and cones are unbounded in the files: they are built over a given range
 * (a square of half side `half`, heights h0..h1 along the axis) and can be refitted later to
 * the boundary curves that bound the face (sem_surface_fit_axial_range).
 */
#ifndef SEM_GEOMETRY_ANALYTIC_SURFACES_H
#define SEM_GEOMETRY_ANALYTIC_SURFACES_H

#include "sem/model.h"

/* A right-handed orthonormal frame: origin o, axes x, y, z (z the surface's axis/normal). */
typedef struct sem_frame {
    double o[3], x[3], y[3], z[3];
} sem_frame;

/* A frame with z along axis (normalised) and x along ref made perpendicular to it, or any
 * perpendicular when ref is NULL or parallel to axis. Fails when axis is zero. */
sem_status sem_frame_make(const double origin[3], const double axis[3], const double *ref,
                          sem_frame *out, sem_error *err);

/* The square [-half, half]^2 of the plane z = 0 (bilinear). */
sem_status sem_analytic_plane(sem_surface *s, const sem_frame *f, double half, sem_error *err);
/* Radius r(h) = radius + h tan_angle at height h along z, h in [h0, h1]; tan_angle = 0: a
 * cylinder. u: the circle, v: the height (degree 1). */
sem_status sem_analytic_cone(sem_surface *s, const sem_frame *f, double radius,
                             double tan_angle, double h0, double h1, sem_error *err);
/* The whole sphere: u longitude, v latitude from the south pole (-z) to the north pole. */
sem_status sem_analytic_sphere(sem_surface *s, const sem_frame *f, double radius, sem_error *err);
/* The whole torus about z: u the major circle, v the minor circle (starting outside). */
sem_status sem_analytic_torus(sem_surface *s, const sem_frame *f, double major, double minor,
                              sem_error *err);

/* A surface that is linear in v (a cylinder or a cone from sem_analytic_cone, in any
 * coordinates): its two rows of control points moved along the generators so that the v
 * range covers, along the surface's axis, the n points (3 doubles each) and no more. */
void sem_surface_fit_axial_range(sem_surface *s, const double *points, size_t n);

/* A bilinear plane patch (sem_analytic_plane, in any coordinates) refitted to the bounding
 * rectangle, in the patch's own axes, of the n points. */
void sem_surface_fit_plane_rectangle(sem_surface *s, const double *points, size_t n);

/* A surface of revolution built here (u the 9-point circle about the axis) turned about its
 * axis so that its seam (u = u0) lies where a face's boundary needs it, for files that do
 * not say where the seam is (IGES 19x form 0). The boundary is given as points sampled along
 * n_curves curves (curve k: points[3 offsets[k]] .. points[3 offsets[k + 1]]): when two curves
 * lie at one angle about the axis each (a seam edge, which a B-rep loop runs twice), the seam
 * goes there; otherwise in the middle of the widest angular gap between the points (a face
 * that does not wrap all the way round). */
void sem_surface_place_seam(sem_surface *s, const double *points, const size_t *offsets,
                            int n_curves);

#endif
