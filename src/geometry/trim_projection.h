/*
 * geometry/trim_projection.h - trim loops given in model space, brought into a surface's
 * parameter domain (internal; used by the IGES reader for faces whose boundaries carry no
 * parameter-space curves, IGES 141 type 0 and 508 edges without them).
 */
#ifndef SEM_GEOMETRY_TRIM_PROJECTION_H
#define SEM_GEOMETRY_TRIM_PROJECTION_H

#include "geometry/closest_point.h"
#include "sem/model.h"

typedef struct sem_trim_projection_settings {
    double tolerance;    /* the (u,v) polygon's image may depart from the projected curve by
                            this much (model units); default 2e-5 x surface size */
    double max_distance; /* a curve point farther than this from the surface fails the loop;
                            default 1e-2 x surface size */
    double max_gap;      /* a gap up to this between consecutive curves (model units) is
                            bridged by a straight (u,v) connector; default 1e-4 x surface size */
} sem_trim_projection_settings;

/* Defaults for a surface: relative to the diagonal of its control points' bounding box. */
sem_trim_projection_settings sem_default_trim_projection_settings(const sem_surface *s);

/* Projects a closed chain of model-space curves onto sampler->surface by closest-point
 * inversion along each curve, and returns the loop in (u,v): one degree-1 curve per input
 * curve (the projected points, refined until the polygon's image follows the projected
 * curve within settings->tolerance), plus straight connectors across collapsed edges
 * (poles). Curves are taken in chain order, each run whichever way continues the chain.
 * On a surface closed in u or v, points on the seam take the side of their neighbours, so
 * seam edges come out on the right side.
 * *border is set to 1 (and out left empty) when the loop runs along the border of the
 * domain only and encloses all of it, or wraps around a closed surface on its border (a
 * periodic surface's natural boundary given without its seam): a trim that trims nothing.
 * A gap between consecutive curves of at most settings->max_gap is bridged by a connector;
 * *gap receives the widest bridged (0: none), for the caller's warning. On a closed surface
 * a loop that crosses the seam is projected again with its (u,v) unwrapped across the seam
 * (it then leaves the domain by up to a period; geometry/seam.h moves the seam to fit).
 * Fails (SEM_ERR_INVALID, message says why) when a curve is off the surface or the loop
 * does not close in (u,v). */
sem_status sem_trim_project_loop(const sem_surface_sampler *sampler, const sem_curve *curves,
                                 int n_curves, const sem_trim_projection_settings *settings,
                                 sem_trim_loop *out, int *border, double *gap, sem_error *err);

#endif
