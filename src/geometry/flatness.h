/*
 * geometry/flatness.h - how flat a cloud of points is: the smallest over the largest
 * eigenvalue of its second-moment matrix (internal; the origins' groups of preprocessing
 * must not be flat, preprocess/origins_cluster.c and origins_merge.c).
 */
#ifndef SEM_GEOMETRY_FLATNESS_H
#define SEM_GEOMETRY_FLATNESS_H

/* Smallest / largest eigenvalue of the symmetric 3x3 C (xx yy zz xy xz yz), in closed form
 * (Smith 1961): 0 for a flat cloud, 1 for a round one. 0 when the largest is not positive; a
 * smallest eigenvalue that rounding makes negative counts as 0. */
double sem_eigenvalue_ratio(const double C[6]);

#endif
