/*
 * geometry/weld_points.h - which points of a set are one point: those within a tolerance of
 * each other, transitively (internal: contact's collision meshes, whose parts meet at seams,
 * and the physics' welded control points, which coincide where a B-rep's faces share an edge).
 */
#ifndef SEM_GEOMETRY_WELD_POINTS_H
#define SEM_GEOMETRY_WELD_POINTS_H

#include "sem/status.h"

/* weld[i] = the lowest index of the points within tol of point i, transitively (x: 3 n).
 * O(n log n) for any shape. tol <= 0: every point is its own. */
sem_status sem_weld_points(const double *x, int n, double tol, int *weld, sem_error *err);

#endif
