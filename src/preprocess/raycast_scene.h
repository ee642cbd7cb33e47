/*
 * raycast_scene.h - the Embree scene that the ray casting files share (internal to
 * src/preprocess/; the interface is raycast.h). raycast_build.c builds and frees it;
 * raycast_hits.c casts rays against it (first hit, all hits); raycast_closest.c finds the
 * closest point of each part; winding_number.c sums the generalized winding number;
 * part_orientation.c decides each part's orientation while the scene is built.
 */
#ifndef SEM_RAYCAST_SCENE_H
#define SEM_RAYCAST_SCENE_H

#include "raycast.h"

#include <embree3/rtcore.h>

#include "geometry/vector3.h"

/* The tessellation as the scene build uses it: vertices (3 doubles each) and triangles (3
 * vertex indices each) with the part of each triangle. */
typedef struct raw_mesh {
    int n_vertices;
    double *vertices;
    double *uv; /* 2 per vertex: the part's (u,v) */
    int n_triangles;
    int *triangles;
    int *triangle_part;
} raw_mesh;

struct sem_raycast_scene {
    RTCDevice device;
    RTCScene scene;
    int n_parts;
    int *part_sign;       /* n_parts, +1/-1 */
    int *part_component;  /* n_parts: smallest part index of the touching parts' component */
    int *part_tri_offset; /* n_parts + 1: part i owns triangles [off[i], off[i+1]) */
    int n_triangles;
    double *tri;          /* 9 per triangle: v0, v1, v2 */
    double *tri_normal;   /* 3 per triangle: unit (v1-v0)x(v2-v0), before the fix */
    double *tri_area;     /* per triangle */
    double *tri_uv;       /* 6 per triangle: (u,v) of v0, v1, v2 */
    /* fast winding number tree (see sem_raycast_winding_number) */
    struct winding_node *winding_nodes;
    int n_winding_nodes;
    int *winding_order;       /* build scratch: triangle indices in tree order */
    signed char *winding_sign; /* build scratch: part_sign of each triangle */
    struct winding_tri *winding_tris; /* the triangles in tree order, orientation-corrected */
    int winding_failed;       /* out of memory while building it: exact sums instead */
    /* per-part bounding-volume trees for closest-point queries (built on first use) */
    struct part_node *part_nodes;
    int *part_root;           /* n_parts: root node of each part, -1 when empty */
    int *part_tri_order;      /* triangles in tree order (global indices) */
    struct part_node *top_nodes; /* a tree over the parts' root boxes (leaves: top_order) */
    int *top_order;           /* part indices in that tree's order */
    int top_root;             /* -1 when no part has triangles */
    int parts_built, parts_failed;
    sem_surface *surfaces; /* copies of the parts' surfaces, for exact hit refinement */
    double lo[3], hi[3];
    double scale;         /* bounding-box diagonal (> 0) */
    double merge_eps;     /* hits of one part closer than this are one crossing */
};

/* Boundary samples per part for the component search (part_orientation.c). */
#define COMPONENT_SAMPLES 48

/* raycast_hits.c: all hits in (t_near, t_far), merged and sorted. Returns the count (writes
 * at most max_hits), or -1 when out of memory. use_sign 0: normals before the orientation
 * fix. */
int sem_raycast_all_hits(const sem_raycast_scene *s, const double *origin, const double *dir,
                         double t_near, double t_far, sem_ray_hit *out, int max_hits, int use_sign);

/* raycast_closest.c: closest parts by one Embree point query over the whole scene (for the
 * small radii of the component search); the median split of the box trees (also the winding
 * tree's); freeing the per-part trees. */
int sem_raycast_closest_parts_embree(const sem_raycast_scene *scene, const double X[3],
                                     double radius, int *out_parts, double *out_dist,
                                     double *out_points);
void sem_raycast_select_median(int *o, int count, const double *centroid, int axis);
void sem_raycast_free_part_trees(sem_raycast_scene *s);

/* winding_number.c: builds the winding-number tree once part_sign is known. Returns 0 when
 * out of memory. */
int sem_raycast_build_winding_tree(sem_raycast_scene *s);

/* part_orientation.c: the boundary samples of each part (COMPONENT_SAMPLES at most, 3
 * doubles each), the components of touching parts, and a part's sign by ray parity votes.
 * The first two return 0 when out of memory. */
int sem_raycast_boundary_samples(const raw_mesh *mesh, int n_parts, double *samples,
                                 int *n_samples);
int sem_raycast_part_components(const sem_raycast_scene *s, const double *samples,
                                const int *n_samples, int *component);
int sem_raycast_estimate_part_sign(const sem_raycast_scene *s, const int *component, int part);

#endif
