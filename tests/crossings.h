/*
 * crossings.h - do a deformed triangle mesh's surfaces pass through each other? (tests)
 *
 * The check of the self-contact scenes (issue 31): every pair of triangles of a frame's
 * render mesh that intersect, except pairs that touch at rest (they share a corner position
 * within 1e-9 of the mesh's size at rest: neighbours, and neighbours across the seams of
 * parts, whose vertices the mesh repeats). Two triangles intersect when an edge of one
 * passes through the other (a proper crossing of non-coplanar triangles always has one;
 * coplanar touching is not counted). Sweep and prune along x over the triangles' boxes, so a
 * frame of a few thousand triangles takes milliseconds. Also the same over a run's frames
 * (the barrier's scenes, tests/test_barrier_scenes.c).
 */
#ifndef SEM_TESTS_CROSSINGS_H
#define SEM_TESTS_CROSSINGS_H

/* Counts the intersecting pairs of the mesh at positions x (3 per vertex) that do not touch
 * or cross at rest positions x0; triangles: 3 vertex indices each. -1: out of memory. */
long count_crossings(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles);
/* The same among pairs at least `apart` from each other at rest (self-contact's exclusion
 * rule: parts of one object near each other at rest, such as a limb overlapping a body, are
 * not kept apart). */
long count_crossings_apart(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles,
                           double apart);

/* The crossing pairs over frames 0..frames of a `sem run` folder (its n_objects objects'
 * frame meshes as one mesh; pairs touching or crossing in frame 0, or nearer than apart
 * there, left out); the frame with the most in *worst; -1 when a frame is missing. The
 * surfaces checked are the collision meshes when the run's output.mesh_resolution is its
 * contact.resolution: the frames' render meshes with the copies of a point on one part (a
 * sphere's pole: a vertex per u, one point at rest) at their mean, as the collision mesh
 * keeps them (src/contact/collision_mesh.h; the NURBS itself may open up there as its
 * collapsed control points part). */
long run_crossings(const char *dir, int frames, int n_objects, double apart, int *worst);

#endif
