/*
 * collision_topology.h - the surface behind a collision mesh's separate parts (internal to
 * src/contact/).
 *
 * A NURBS model is tessellated part by part, so its collision mesh is many open meshes whose
 * boundaries meet at the parts' seams. The sign of a distance (inside or outside the other
 * object) is read from a pseudonormal (Baerentzen and Aanaes 2005), which is right only on a
 * closed surface: at an open boundary a point outside is called inside, at a depth of up to
 * the search radius, and its contact energy jumps when it comes into range (the paper's
 * astronauts failed so). Welding the points that coincide (within a tolerance: CAD models
 * have small gaps) and finding the triangles on either side of each edge makes the seams
 * closed again for the normals, while each point keeps its own part's row of J.
 */
#ifndef SEM_CONTACT_COLLISION_TOPOLOGY_H
#define SEM_CONTACT_COLLISION_TOPOLOGY_H

#include "sem/status.h"

/* A triangle edge by its ends (a < b) and its slot 3 t + e; sorted by sem_compare_edge_slot
 * (a, then b, then slot), the triangles on one edge come together. */
typedef struct sem_edge_slot {
    int a, b, slot;
} sem_edge_slot;
int sem_compare_edge_slot(const void *x, const void *y);

/* edge_other[3 t + e] = the triangle across edge e (from vertex e to vertex e + 1 mod 3) of
 * triangle t, by welded ends; -1 on a boundary or where more than two triangles meet. */
sem_status sem_collision_edge_neighbours(const int *triangles, int n_triangles, const int *weld, int *edge_other,
                                         sem_error *err);

/* The mesh's edges, once each (by their two point indices), as BVH triangles (a, b, b):
 * 3 ints per edge in *out (malloc'd), *n_edges of them; edges whose ends are one welded
 * point (weld may be NULL) are left out. */
sem_status sem_collision_edges(const int *triangles, int n_triangles, const int *weld, int **out, int *n_edges,
                               sem_error *err);

#endif
