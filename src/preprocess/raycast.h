/*
 * raycast.h - Embree ray casting against a tessellation of the model's parts (internal):
 * the scene (raycast_build.c), first and all hits (raycast_hits.c), the closest parts
 * (raycast_closest.c), the generalized winding number (winding_number.c) and each part's
 * orientation (part_orientation.c).
 *
 * One Embree triangle geometry per part (geomID = part index), built from
 * sem_mesh_from_model (include/sem/tessellate.h). The paper ray casts a triangulation
 * too (Sec. 6.3); the tessellation resolution is an option.
 *
 * part_sign[i] (+1/-1) is the orientation correction of part i: multiplying the part's
 * geometric normal by it makes the normal point out of the solid. CAD files have inward
 * faces (every box-beam section has one), so this is estimated once when the scene is
 * built (see part_orientation.c for how) and used by the quadrature (enter/leave along a
 * ray) and by the winding-number inside test.
 */
#ifndef SEM_RAYCAST_H
#define SEM_RAYCAST_H

#include "sem/model.h"

typedef struct sem_raycast_scene sem_raycast_scene;

typedef struct sem_ray_hit {
    double t;         /* distance along the (unit) direction */
    int part;         /* geomID */
    int triangle;     /* primID */
    double normal[3]; /* unit geometric normal, orientation-corrected (points outward) */
    double u, v;      /* the part's parameters at the hit (sem_raycast_all: on the exact surface) */
    int smooth;       /* sem_raycast_all: 1 when the hit is on the exact surface (Newton
                         converged) and inside one part (not where two parts meet), so the
                         surface's derivatives there describe the crossing */
} sem_ray_hit;

/* Builds the scene from a tessellation with `resolution` cells per knot span. */
sem_status sem_raycast_scene_build(const sem_model *model, int resolution,
                                   sem_raycast_scene **out, sem_error *err);
/* The same on `threads` threads (0: OpenMP's default); the same scene on any count. */
sem_status sem_raycast_scene_build_threads(const sem_model *model, int resolution, int threads,
                                           sem_raycast_scene **out, sem_error *err);
void sem_raycast_scene_destroy(sem_raycast_scene *scene);

/* First hit from origin along unit direction dir for t in (t_near, t_far); returns 1 when
 * hit. t is the double-precision ray-plane distance of the hit triangle. Thread-safe. */
int sem_raycast_first(const sem_raycast_scene *scene, const double origin[3], const double dir[3],
                      double t_near, double t_far, sem_ray_hit *hit);
/* All hits along the ray in (t_near, t_far), sorted by t; writes at most max_hits, returns
 * the total count. Hits are refined onto the exact NURBS surface (Newton from the
 * triangle's (u,v)); hits of one part at (nearly) one t - shared edges and vertices of the
 * tessellation - are merged into one crossing, touching ones removed; a crossing where
 * several parts meet is not smooth. Thread-safe. */
int sem_raycast_all(const sem_raycast_scene *scene, const double origin[3], const double dir[3],
                    double t_near, double t_far, sem_ray_hit *hits, int max_hits);
/* Closest point on each part within radius of X: calls back per part with the smallest
 * distance found, the closest point and the part index. Returns number of parts found.
 * out_parts/out_dist/out_points must hold n_parts entries (points 3 each). Thread-safe. */
int sem_raycast_closest_parts(const sem_raycast_scene *scene, const double X[3], double radius,
                              int *out_parts, double *out_dist, double *out_points);
/* The same without part `exclude` (-1: none): a boundary sample needs only the other parts
 * through it, and its own part's search is the most expensive one. */
int sem_raycast_closest_parts_except(const sem_raycast_scene *scene, const double X[3], double radius,
                                     int exclude, int *out_parts, double *out_dist, double *out_points);
/* Generalized winding number (Jacobson et al. 2013) of the orientation-corrected
 * tessellation at X: ~1 inside, ~0 outside, fractional near open boundaries. */
double sem_raycast_winding_number(const sem_raycast_scene *scene, const double X[3]);
/* The same with a second-order far field from 1.5 node radii (error up to ~0.1 measured
 * on the shared models): for yes/no decisions with a margin, such as the quadrature's. */
double sem_raycast_winding_number_coarse(const sem_raycast_scene *scene, const double X[3]);
/* Is the winding number at X above threshold? Decided by the cheapest far field whose
 * error bound keeps it clear of the threshold (see winding_number.c); thread-safe. */
int sem_raycast_winding_above(const sem_raycast_scene *scene, const double X[3], double threshold);
/* The same summed exactly over every triangle (O(triangles)); the function above uses
 * Barill et al.'s (2018) tree with a second-order far field (see winding_number.c), equal
 * to this within ~5e-3 away from the surface. */
double sem_raycast_winding_number_exact(const sem_raycast_scene *scene, const double X[3]);
/* Bounding box of the tessellation: lo[3], hi[3]. */
void sem_raycast_bounds(const sem_raycast_scene *scene, double lo[3], double hi[3]);
int sem_raycast_part_count(const sem_raycast_scene *scene);
/* The component of a part: parts whose boundaries touch (within 5e-3 of the model size) form
 * one component, named by its smallest part index (a box's six faces; a nested or embedded
 * solid that does not touch the outer one is its own component). */
int sem_raycast_part_component(const sem_raycast_scene *scene, int part);
/* The tessellation's triangles, owned by the scene (read-only): 9 doubles each (v0, v1, v2),
 * their areas, their unit normals before the orientation fix (3 each), and the triangles of
 * part i are [part_offset[i], part_offset[i + 1]). Returns the triangle count. */
int sem_raycast_triangles(const sem_raycast_scene *scene, const double **triangles,
                          const double **areas, const double **normals, const int **part_offset);
/* The scene's copy of a part's surface (read-only), for derivatives at a hit's (u, v). */
const sem_surface *sem_raycast_part_surface(const sem_raycast_scene *scene, int part);
/* Orientation correction of a part, +1 or -1. */
int sem_raycast_part_sign(const sem_raycast_scene *scene, int part);

#endif
