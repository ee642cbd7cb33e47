/*
 * collision_mesh.h - the surface points and triangles of an object that contact sees
 * (internal to src/contact/).
 *
 * The render tessellation of the object's NURBS parts (sem/tessellate.h), with each vertex
 * kept as its row of the render map x = J q (the paper's Sec. 7-8): the rational basis
 * values phi_k(u, v) of its part's control points, evaluated once. Positions for any q are
 * then a sparse product, and a force f on a point reaches the control points as J^T f
 * (phi_k f each), as point loads do. Each point carries its share of the rest surface area
 * (a third of its triangles'), which scales its contact spring. Vertices no kept triangle
 * uses (trimmed away) are dropped.
 *
 * Normals for the sign of a distance (collision_topology.h): points that coincide at rest
 * (within 1e-4 of the object's size) are welded, the triangles across each edge found, and
 * the parts turned to one orientation across their seams, so that the face, edge and
 * angle-weighted vertex pseudonormals see one closed surface where the model is closed.
 * Welded points of one part (the corners of a collapsed edge: a sphere's pole has a vertex per
 * u) share one row, the mean of theirs, so that they stay one point as the collapsed control
 * points move apart; the triangles that keep no area there take part in no query.
 */
#ifndef SEM_CONTACT_COLLISION_MESH_H
#define SEM_CONTACT_COLLISION_MESH_H

#include "broad_phase.h"
#include "sem/model.h"

typedef struct sem_collision_mesh {
    int n_points;
    int *row_start;        /* n_points + 1: J's rows (CSR) */
    int *row_ctrl;         /* control point of the object (model order) */
    double *row_w;         /* phi */
    double *area;          /* rest area share per point */
    int n_triangles;
    int *triangles;        /* 3 point indices per triangle */
    double *x;             /* current positions (sem_collision_mesh_update) */
    double *x0;            /* rest positions (what self-contact's exclusion rule measures) */
    double *face_normal;   /* current unit triangle normals (outward) */
    double *pseudo_normal; /* current angle-weighted vertex normals over the welded point */
    int *weld;             /* the point's representative: points that coincide at rest */
    int *copy_start;       /* n_points + 1: the point's copies in copy_point (itself included): */
    int *copy_point;       /* the points of its part that coincide with it at rest (the corners
                            * of a collapsed edge: a sphere's pole has one per u) */
    int *edge_other;       /* 3 per triangle: the triangle across edge e (vertex e to e + 1), or -1 */
    double length;         /* bounding-box diagonal at rest */
    int resolution;        /* tessellation cells per knot span used */
    sem_bvh bvh;           /* over the triangles at the last update */
    int n_edges;           /* the triangles' edges once each, collapsed ones left out: */
    int *edge_tri;         /* 3 per edge, its ends a, b and b again (a triangle for edge_bvh) */
    sem_bvh edge_bvh;      /* over the edges (the barrier's edge pairs; its user refits it) */
} sem_collision_mesh;

/* The mesh of a model (rest control points q0 = the model's). resolution <= 0: the
 * automatic choice of sem_contact_def.resolution. */
sem_status sem_collision_mesh_build(const sem_model *model, int resolution, sem_collision_mesh *out,
                                    sem_error *err);
void sem_collision_mesh_free(sem_collision_mesh *m);
/* x = J q for every point; with between (contact between objects or of an object with
 * itself, or the barrier: the users of the normals and of this mesh's tree) also the face
 * and vertex normals and the triangle tree's boxes.
 * The mesh as built has normals at the rest shape. */
void sem_collision_mesh_update(sem_collision_mesh *m, const double *q, int between);
/* The box of the points at their positions x and (x1 non-NULL) at x1, widened by grow. */
void sem_collision_mesh_box(const sem_collision_mesh *m, const double *x1, double grow, double lo[3], double hi[3]);
/* out = J q (3 per point), the positions alone. */
void sem_collision_mesh_positions(const sem_collision_mesh *m, const double *q, double *out);
/* The outward direction at the closest feature of triangle t (narrow_phase.h: feature,
 * index): its normal, the sum of the normals on either side of an edge, or the vertex's
 * pseudonormal. */
void sem_collision_mesh_outward(const sem_collision_mesh *m, int t, int feature, int index, double out[3]);

#endif
