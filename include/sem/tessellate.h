/*
 * sem/tessellate.h - triangle meshes of NURBS parts, for rendering, render-mesh output and
 * ray casting (the render map x = J_render q of the paper's Sec. 7-8).
 *
 * Each part's domain [u0,u1] x [v0,v1] is cut at its knots and every non-empty knot span
 * is split into resolution x resolution cells, two triangles per cell. In a trimmed part a
 * triangle is kept when its (u,v) centroid is inside the trim region (sem/trim.h): the
 * boundary is followed to within one cell, which is what rendering and ray casting need.
 *
 * Two phases, as CHOLMOD's analyse/factorise: the (u,v) samples, the kept triangles and the
 * rational basis functions at every sample depend only on knots, weights and trims, so
 * they are computed once in a sem_mesh_template; sem_mesh_update then only forms
 * x = sum phi_k P_k (and the normal from the derivative rows) for new control points P,
 * which is what an animation needs every frame.
 */
#ifndef SEM_TESSELLATE_H
#define SEM_TESSELLATE_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_mesh {
    int n_vertices, n_triangles;
    double *positions;     /* 3 per vertex */
    double *normals;       /* 3 per vertex, unit length (x_u x x_v direction) */
    double *uv;            /* 2 per vertex: the part's (u,v) */
    int *triangles;        /* 3 vertex indices per triangle, counter-clockwise in (u,v) */
    int *triangle_part;    /* part index of each triangle */
    int n_parts;
    int *part_vertex_start;   /* n_parts + 1: vertices of part i are [start[i], start[i+1]) */
    int *part_triangle_start; /* n_parts + 1: the same for triangles */
} sem_mesh;

typedef struct sem_mesh_template sem_mesh_template;

/* Samples, kept triangles and basis rows of every part. resolution >= 1 cells per knot span
 * and direction. Fails when a trim loop does not close (message names the part). */
sem_status sem_mesh_template_build(const sem_model *model, int resolution,
                                   sem_mesh_template **out, sem_error *err);
/* The same, but a trimmed part keeps every triangle that reaches into its trimmed domain
 * (a corner, an edge midpoint or the centroid inside): the mesh covers the domain and
 * overhangs the trim curves by up to one cell, for a renderer that cuts them exactly at
 * each hit's (u,v) with sem_trim_region_inside (sem/render.h). */
sem_status sem_mesh_template_build_covering(const sem_model *model, int resolution,
                                            sem_mesh_template **out, sem_error *err);
void sem_mesh_template_destroy(sem_mesh_template *tmpl);

/* Allocates mesh arrays and fills the topology (triangles, uv, parts); positions and
 * normals are zero until sem_mesh_update. */
sem_status sem_mesh_template_mesh(const sem_mesh_template *tmpl, sem_mesh *mesh, sem_error *err);

/* Positions and normals for the model's current control points. The model must have the
 * parts, sizes, knots and weights the template was built from (only ctrl may change). */
sem_status sem_mesh_update(const sem_mesh_template *tmpl, const sem_model *model, sem_mesh *mesh,
                           sem_error *err);

/* One-shot: template, mesh, update. */
sem_status sem_mesh_from_model(const sem_model *model, int resolution, sem_mesh *out,
                               sem_error *err);
void sem_mesh_free(sem_mesh *mesh);

/* Sum of triangle areas (for tests and diagnostics). */
double sem_mesh_area(const sem_mesh *mesh);

/* Writes the mesh as OBJ (v, vn, f v//vn; one 'g' group per part, named after the model's
 * parts when model is non-NULL), atomically. */
sem_status sem_mesh_write_obj(const sem_mesh *mesh, const sem_model *model, const char *path,
                              sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
