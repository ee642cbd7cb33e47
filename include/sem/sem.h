/*
 * sem/sem.h - the whole public API of libsem in one include.
 *
 * The Shape Matching Element Method (Trusty, Chen, Levin, ACM TOG 2021): animate NURBS CAD
 * models directly. The pipeline, one header per stage:
 *
 *   status.h      one error channel: sem_status codes and a sem_error message
 *   limits.h      how much any reader reads and builds (SEM_MAX_*)
 *   version.h     SEM_VERSION_* macros, sem_version(), sem_has_step()
 *   model.h       NURBS models (parts, trims) and files (IGES, OBJ free-form, STEP)
 *   nurbs.h       B-spline / NURBS evaluation          trim.h      trimmed domains
 *   tessellate.h  triangle meshes                      measure.h   area, bounding box
 *   primitives.h  exact NURBS solids built in code    refine.h    exact knot refinement
 *   sparse.h      compressed sparse rows (the preprocessing data)
 *   polynomial.h  the polynomial basis of each part's deformation (Eq. 3)
 *   preprocess.h  model -> SEM discretization (paper Sec. 5-7, Alg. 1)
 *   cache.h       a bounded folder of discretizations keyed by model and settings
 *   material.h    hyperelastic energy densities
 *   simulation.h  worlds, objects, integrators (Sec. 7, Alg. 2)
 *   scene.h       scene files (JSON) and the world a scene describes
 *   animation.h   per-frame NURBS, meshes, USD and glTF output
 *   render.h      ray-traced pictures (PNG) and the diagnostic colourings
 *
 * Constructors. What can fail for a reason the caller should read is made by
 * `sem_status NAME_create(const DEF *def, ..., T **out, sem_error *err)` (sem_renderer_create,
 * sem_animation_create, sem_scene_world_create; sem_preprocess and the file readers have the
 * same shape): *out is set only on SEM_OK, err says why otherwise. Two constructors keep an
 * older shape, documented at each: sem_model_create() returns an empty model or NULL (out of
 * memory is its only failure), and sem_world_create(def, err) returns the world or NULL with
 * err set. Every T made is released by its T_destroy, which accepts NULL.
 *
 * Build against an installed copy with `pkg-config --cflags --libs sem` or CMake's
 * find_package(sem) and the target sem::sem (docs/library.md).
 */
#ifndef SEM_SEM_H
#define SEM_SEM_H

#include "sem/status.h"
#include "sem/limits.h"
#include "sem/version.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/trim.h"
#include "sem/tessellate.h"
#include "sem/measure.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/sparse.h"
#include "sem/polynomial.h"
#include "sem/preprocess.h"
#include "sem/cache.h"
#include "sem/material.h"
#include "sem/simulation.h"
#include "sem/scene.h"
#include "sem/animation.h"
#include "sem/render.h"

#endif
