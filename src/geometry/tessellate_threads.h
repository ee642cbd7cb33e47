/*
 * tessellate_threads.h - sem_mesh_from_model with the caller's thread count (internal; the
 * preprocessing honours its `threads` option without changing OpenMP's process-wide setting).
 */
#ifndef SEM_GEOMETRY_TESSELLATE_THREADS_H
#define SEM_GEOMETRY_TESSELLATE_THREADS_H

#include "sem/tessellate.h"

/* sem_mesh_from_model on `threads` threads (0: OpenMP's default); the same mesh on any count. */
sem_status sem_mesh_from_model_threads(const sem_model *model, int resolution, int threads,
                                       sem_mesh *out, sem_error *err);

#endif
