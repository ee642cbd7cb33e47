/*
 * curve_tools.h - exact operations on NURBS curves (internal; used by the IGES reader for
 * ruled surfaces and trim curves). Each keeps the curve's shape exactly; on out of memory the
 * curve is left as it was and SEM_ERR_NOMEM is returned.
 */
#ifndef SEM_GEOMETRY_CURVE_TOOLS_H
#define SEM_GEOMETRY_CURVE_TOOLS_H

#include "sem/nurbs.h"

/* Inserts knot t (strictly inside the knot range) `times` times, clamped so that its
 * multiplicity stays <= degree (Piegl & Tiller A5.1, in homogeneous coordinates). */
sem_status sem_curve_insert_knot(sem_curve *c, double t, int times);
/* 1 when the first and last knots have multiplicity degree + 1. */
int sem_curve_is_clamped(const sem_curve *c);
/* Raises a clamped curve to degree q exactly (nothing when q <= its degree). */
sem_status sem_curve_elevate(sem_curve *c, int q);
/* Affine change of parameter so that the knot range becomes [0, 1] (t0, t1 follow). */
void sem_curve_normalize(sem_curve *c);
/* Makes two clamped curves on [0, 1] share degree and knot vector (exactly). */
sem_status sem_curves_make_compatible(sem_curve *a, sem_curve *b);

#endif
