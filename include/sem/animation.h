/*
 * sem/animation.h - animation output: per-frame NURBS (IGES, optionally OBJ free-form),
 * per-frame render meshes (OBJ), one USD (usda) file of the whole animation with
 * time-sampled points, loadable in Blender and usdview, and one animated glTF binary
 * (animation.glb: per-part materials, the motion as morph targets) for Blender, three.js
 * and other glTF viewers.
 *
 * Each frame is written atomically (temp file, then rename), so a run that stops early
 * leaves every earlier frame complete on disk. The USD and glTF files are written by
 * sem_animation_finish, which a caller also calls after a failed step.
 */
#ifndef SEM_ANIMATION_H
#define SEM_ANIMATION_H

#include "sem/model.h"
#include "sem/preprocess.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_animation_def {
    const char *dir;         /* output folder (created if missing) */
    int write_iges, write_obj, write_mesh, write_usd;
    int write_glb;           /* animation.glb */
    int mesh_resolution;     /* tessellation cells per knot span */
    double frames_per_second;
    /* The models are in metres. Frame files (NURBS and meshes) are written in frame_units
     * (an IGES unit name, e.g. "MM"; NULL or "": metres), numbers divided by
     * frame_unit_to_meter, so a CAD tool shows the model at its size in its own units. The
     * USD file is in metres (metersPerUnit 1). */
    const char *frame_units;
    double frame_unit_to_meter;
    int frame_digits;        /* width of NNNN in frame_NNNN.*; 0: 4 */
} sem_animation_def;

typedef struct sem_animation sem_animation;

/* Whether dir can take the animation, without creating anything: an existing folder this
 * process may write into, or a path whose first existing ancestor is one (sem_animation_create
 * makes the missing folders). A program calls it before the long work - `sem run` does before
 * preprocessing - so a folder it cannot write is refused at once, not after minutes.
 * SEM_ERR_IO with a message naming the folder and the reason otherwise. */
sem_status sem_animation_check_dir(const char *dir, sem_error *err);

/* One object per model; the models' topology is fixed, only control points move. */
sem_status sem_animation_create(const sem_animation_def *def, int n_objects,
                                const sem_model *const *models, sem_animation **out,
                                sem_error *err);
/* Writes frame `frame` with the objects' current control points q (3 per control point). */
sem_status sem_animation_add_frame(sem_animation *anim, int frame, const double *const *q,
                                   sem_error *err);
/* Records frame `frame` for the USD file without writing its files (they exist: a run that
 * continues after an interruption). */
sem_status sem_animation_restore_frame(sem_animation *anim, int frame, const double *const *q,
                                       sem_error *err);
/* Writes the USD file with every frame added so far. */
sem_status sem_animation_finish(sem_animation *anim, sem_error *err);
void sem_animation_destroy(sem_animation *anim);
/* Path of the USD file (valid after create). */
const char *sem_animation_usd_path(const sem_animation *anim);
/* Path of the glTF file (valid after create). */
const char *sem_animation_glb_path(const sem_animation *anim);

/* Writes DIR/preprocess_K.semdisc for object K: its discretization without the boundary
 * samples and the simulation operators (J-hat, Gamma, Grad, M, M_eps): the quadrature
 * points, blending weights, deformation origins and projection Pi that `sem render
 * --color weights:P|origins|quadrature` shows (read with sem_discretization_load). */
sem_status sem_animation_write_preprocess(const sem_animation *anim, int object,
                                          const sem_discretization *d, sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
