/*
 * geometry/net_size.h - the size of a surface's control net (internal): the box of its control
 * points (which holds the surface, the weights being positive) and that box's diagonal, the
 * length the trim projection's and the STEP reader's tolerances scale with.
 */
#ifndef SEM_GEOMETRY_NET_SIZE_H
#define SEM_GEOMETRY_NET_SIZE_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* The bounding box of s's control points: lo[3], hi[3]. */
void sem_surface_net_box(const sem_surface *s, double lo[3], double hi[3]);

/* The diagonal of that box; 1 when it is zero or not finite (a point-like or broken net). */
double sem_surface_net_size(const sem_surface *s);

#ifdef __cplusplus
}
#endif
#endif
