/*
 * geometry/closest_point.h - point inversion on a NURBS surface: the (u,v) whose surface
 * point is closest to a point in space (internal; used to project model-space trim curves
 * into a face's parameter domain, geometry/trim_projection.c).
 *
 * A sampler holds a grid of surface points (a few per knot span and direction) to start
 * from when there is no good guess; the minimisation of |S(u,v) - p|^2 is Newton's method
 * with the full Hessian (second derivatives of S), falling back to Gauss-Newton where the
 * Hessian is not positive definite, each step clipped to the domain (Piegl & Tiller, The
 * NURBS Book, Sec. 6.1).
 */
#ifndef SEM_GEOMETRY_CLOSEST_POINT_H
#define SEM_GEOMETRY_CLOSEST_POINT_H

#include "sem/model.h"

typedef struct sem_surface_sampler {
    const sem_surface *surface;
    int n;          /* samples */
    double *uv;     /* 2 per sample */
    double *x;      /* 3 per sample */
    double period[2]; /* u, v: the domain's length where the surface is closed (its two sides
                         meet), else 0; Newton steps across such a seam come in on the other
                         side instead of stopping at it */
} sem_surface_sampler;

sem_status sem_surface_sampler_build(const sem_surface *s, sem_surface_sampler *out,
                                     sem_error *err);
/* The same with per_span intervals per knot span and direction (>= 1; the plain build uses 2). */
sem_status sem_surface_sampler_build_dense(const sem_surface *s, int per_span,
                                           sem_surface_sampler *out, sem_error *err);
void sem_surface_sampler_free(sem_surface_sampler *sampler);

/* Newton from uv (in: the start, out: the result); returns the distance |S(uv) - p|. */
double sem_surface_refine_closest(const sem_surface *s, const double p[3], double uv[2]);

/* The closest point from the best of: the guess (when given) and the nearest samples; a
 * guess that ends within `accept` of p is taken without trying the samples. Returns the
 * distance; uv receives the parameters. */
double sem_surface_closest_point(const sem_surface_sampler *sampler, const double p[3],
                                 const double *guess, double accept, double uv[2]);

#endif
