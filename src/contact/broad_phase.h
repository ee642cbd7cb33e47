/*
 * broad_phase.h - a bounding volume hierarchy over a triangle mesh, to find the triangle
 * nearest a point within a search radius in about log(n) box tests (internal to
 * src/contact/).
 *
 * The tree is built once from a mesh's positions (median splits along the longest axis of
 * the triangle centroids, 4 triangles a leaf; ties broken by triangle index, so the same
 * mesh gives the same tree) and refitted, not rebuilt, when the mesh moves (a deforming
 * object keeps its topology; its boxes only grow by rotation). Queries visit the nearer
 * child first and prune by the best distance so far; the first of equally near triangles
 * in the tree's order wins, so results do not depend on threads.
 */
#ifndef SEM_CONTACT_BROAD_PHASE_H
#define SEM_CONTACT_BROAD_PHASE_H

#include "narrow_phase.h"
#include "sem/status.h"

typedef struct sem_bvh_node {
    double lo[3], hi[3];
    int left, right;   /* children (inner node), or -1 */
    int first, count;  /* leaf: triangles order[first .. first + count) */
} sem_bvh_node;

typedef struct sem_bvh {
    int n_nodes, n_triangles;
    sem_bvh_node *nodes;   /* node 0 the root; children after their parent */
    int *order;
} sem_bvh;

sem_status sem_bvh_build(sem_bvh *bvh, const double *vertices, const int *triangles, int n_triangles,
                         sem_error *err);
/* New boxes for moved vertices (same triangles). */
void sem_bvh_refit(sem_bvh *bvh, const double *vertices, const int *triangles);
/* Boxes that hold each triangle at both vertex positions x0 and x1 (x1 NULL: x0 only) and
 * all of the straight motion between them (continuous collision detection, ccd.h). */
void sem_bvh_refit_swept(sem_bvh *bvh, const double *x0, const double *x1, const int *triangles);
/* Calls visit(triangle, context) for every triangle of a leaf whose box meets the box
 * [lo, hi], in the tree's order (the caller tests the triangle itself). */
void sem_bvh_overlap(const sem_bvh *bvh, const double lo[3], const double hi[3], void (*visit)(int triangle, void *context),
                     void *context);
void sem_bvh_free(sem_bvh *bvh);
/* The triangle nearest p with squared distance < max_dist2, or -1; *out its closest point. */
int sem_bvh_closest(const sem_bvh *bvh, const double *vertices, const int *triangles, const double p[3],
                    double max_dist2, sem_tri_closest *out);
/* The same among the triangles for which skip(triangle, context) is 0 (skip is asked only
 * of triangles nearer than the best so far; NULL: none is skipped). */
int sem_bvh_closest_except(const sem_bvh *bvh, const double *vertices, const int *triangles, const double p[3],
                           double max_dist2, int (*skip)(int triangle, void *context), void *context,
                           sem_tri_closest *out);

#endif
