/*
 * geometry/seam.h - moving the seam of a closed surface (internal; used by the IGES reader
 * for trim loops that cross a closed surface's seam).
 */
#ifndef SEM_GEOMETRY_SEAM_H
#define SEM_GEOMETRY_SEAM_H

#include "sem/model.h"

/* 1 when the surface is closed in direction dir (0: u, 1: v): its two sides in that direction
 * meet within tol (model units) at 9 points along them. */
int sem_surface_is_closed(const sem_surface *s, int dir, double tol);

/* The same surface with its parameter domain in direction dir moved to [start, start + P]
 * (P = the domain's length, start within one period of the old start and not equal to it),
 * for a surface closed in that direction: a trim loop that crossed the old seam then lies
 * inside the domain. Exact: the knots at the new seam (and at the old ends, when the knot
 * vector runs past them) are inserted to multiplicity degree (homogeneous coordinates), the
 * domain is cut there and the two pieces swap places, the moved one shifted by one period.
 * The old seam becomes an interior knot of multiplicity degree + 1 (its two columns are both
 * kept). The surface is unchanged on failure (out of memory, or a knot vector whose sizes
 * would pass SEM_MAX_KNOTS). */
sem_status sem_surface_move_seam(sem_surface *s, int dir, double start, sem_error *err);

#endif
