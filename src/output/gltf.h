/*
 * gltf.h - an animated glTF 2.0 binary (.glb) of tessellated frames (internal; written by
 * sem_animation_finish, see sem/animation.h).
 */
#ifndef SEM_OUTPUT_GLTF_H
#define SEM_OUTPUT_GLTF_H

#include "sem/tessellate.h"

typedef struct gltf_object {
    const sem_mesh *mesh;          /* topology: triangles and part ranges (positions unused) */
    const char *const *part_names; /* mesh->n_parts names ("" for none) */
    int first_part;                /* number of its first part over all objects (its colour) */
} gltf_object;

typedef struct gltf_animation {
    int n_objects;
    const gltf_object *objects;
    int n_frames;
    const double *times;           /* seconds, increasing */
    const float *const *positions; /* per frame: every object's vertices in turn, 3 each */
    const float *const *normals;   /* the same for unit normals */
    double meters_per_unit;        /* model units (glTF is in metres) */
    const char *generator;
} gltf_animation;

/* Writes path atomically. */
sem_status gltf_write(const char *path, const gltf_animation *a, sem_error *err);

#endif
