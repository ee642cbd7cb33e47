/*
 * io/mesh_obj_read.h - plain triangle meshes from Wavefront OBJ polygon files (a terrain, an
 * obstacle), for contact's static colliders.
 */
#ifndef SEM_IO_MESH_OBJ_READ_H
#define SEM_IO_MESH_OBJ_READ_H

#include "sem/status.h"

typedef struct sem_triangle_soup {
    int n_vertices, n_triangles;
    double *vertices;  /* 3 per vertex */
    int *triangles;    /* 3 vertex indices (from 0) per triangle */
} sem_triangle_soup;

/* Reads the 'v' and 'f' statements of an OBJ file (regular files up to
 * SEM_MAX_MODEL_FILE_BYTES; 'v/vt/vn' references and negative indices allowed; other
 * statements skipped). Quads become two triangles (split along the shorter diagonal); a
 * face with fewer than 3 or more than 4 vertices, an index out of range or a file with no
 * face is an error "FILE:LINE: ...". *freeform (may be NULL) is set to 1 instead,
 * with nothing read, when the file holds free-form surfaces ("surf"): read it as a model. */
sem_status sem_obj_triangles_read(const char *path, sem_triangle_soup *out, int *freeform, sem_error *err);
void sem_triangle_soup_free(sem_triangle_soup *s);

#endif
