/*
 * geometry/point_triangle.h - the closest point of a triangle to a point (internal; the
 * contact's narrow phase and the preprocessing's closest parts, preprocess/raycast_closest.c).
 *
 * Ericson, Real-Time Collision Detection, 5.1.5: the Voronoi regions of the vertices a, b, c
 * and of the edges are tested in turn, from the dot products of the edge vectors ab, ac with
 * p - a, p - b and p - c; a point in none of them projects into the face. The tests are
 * written once, in sem_point_triangle_region, which says which feature is closest and gives
 * the numbers that place the point on it. sem_point_triangle_closest places it as a
 * barycentric blend of the corners (the contact springs want the coordinates); the closest
 * parts place it from a vertex along the edge vectors. The two round differently, and each
 * caller keeps its own rounding so that its results do not change.
 */
#ifndef SEM_GEOMETRY_POINT_TRIANGLE_H
#define SEM_GEOMETRY_POINT_TRIANGLE_H

/* Closest point feature of a triangle: its inside, edge k (from vertex k to k + 1), or
 * vertex k. */
typedef enum sem_tri_feature { SEM_TRI_FACE, SEM_TRI_EDGE, SEM_TRI_VERTEX } sem_tri_feature;

/* Where the closest point lies, as the region tests find it. */
typedef struct sem_tri_region {
    sem_tri_feature feature;
    int index;         /* edge or vertex index (0..2) */
    double t;          /* on an edge: the weight of b on edge 0, of c on edges 1 and 2, so
                          the point is a + t ab, b + t (c - b), a + t ac */
    double va, vb, vc; /* in the face: the barycentric coordinates of a, b, c times their
                          sum (which is 0 when the triangle is degenerate) */
} sem_tri_region;

/* The region tests alone: which feature of triangle (a, b, c) is closest to p. */
void sem_point_triangle_region(const double p[3], const double a[3], const double b[3],
                               const double c[3], sem_tri_region *out);

typedef struct sem_tri_closest {
    double point[3];   /* closest point of the triangle */
    double bary[3];    /* its barycentric coordinates */
    double dist2;      /* squared distance */
    sem_tri_feature feature;
    int index;         /* edge or vertex index (0..2) */
} sem_tri_closest;

/* Closest point of triangle (a, b, c) to p: the barycentric blend of the corners, its
 * squared distance and its feature. A degenerate triangle (the face's coordinates sum to 0)
 * gives its first vertex. */
void sem_point_triangle_closest(const double p[3], const double a[3], const double b[3],
                                const double c[3], sem_tri_closest *out);

#endif
