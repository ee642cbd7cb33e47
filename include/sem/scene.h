/*
 * sem/scene.h - scene files: what to simulate and how (JSON, documented in docs/scenes.md).
 *
 * A scene lists objects (a model file or a generated primitive, a transform, materials,
 * SEM settings, pins, prescribed motion, initial velocities, loads), the world (gravity,
 * integrator, time step, damping) and the output (frames, folder, formats). Parsing
 * validates every key: unknown keys and bad values are errors that name the key and why.
 */
#ifndef SEM_SCENE_H
#define SEM_SCENE_H

#include "sem/material.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/simulation.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_scene_part_material {
    int part;           /* part index, or -1 when named */
    char name[64];      /* part name when not an index */
    sem_material material;
} sem_scene_part_material;

/* One prescribed motion with its own selection ("prescribe": [...]): the material in box
 * (sem_pin_region) and the control points in control_box, of parts, and points. */
typedef struct sem_scene_prescribe_group {
    int has_box;
    double box[6];
    int has_control_box;
    double control_box[6];
    int n_parts;
    int *parts;
    int n_points;
    int *points;
    sem_prescribe prescribe;
} sem_scene_prescribe_group;

typedef struct sem_scene_object {
    char model_path[4096];   /* resolved relative to the scene file; "" for a primitive */
    char primitive[16];      /* "box", "beam", "sphere", "cylinder", "torus" or "" */
    double primitive_size[3];/* box size / beam length,width,height */
    double primitive_radius, primitive_radius2, primitive_height;
    int primitive_sections;
    double transform[12];    /* 3 x 4 row-major [A | b], applied to the model (in metres) */
    /* "units": how the model file's numbers become metres. "" (default): the file's own
     * units (IGES global section; OBJ "# sem units" comment; metres when the file says
     * nothing); "as_metres": the numbers are metres whatever the file says (the paper's
     * reading of its models); or a unit name ("mm", "cm", "m", "in", "ft", ...) that
     * overrides the file. */
    char units[16];
    sem_material material;
    int n_part_materials;
    sem_scene_part_material *part_materials;
    sem_preprocess_options sem;
    double blend;              /* sem.blend: sem_object_def.blend (default SEM_DEFAULT_BLEND) */
    int seams;                 /* sem.seams: sem_object_def.seams (default SEM_SEAMS_GEOMETRIC) */
    int weld;                  /* sem.weld: sem_object_def.weld (default -1: on with
                                  sem.resolution, else off) */
    double seam_ties;          /* sem.seam_ties: sem_object_def.seam_ties (default
                                  SEM_DEFAULT_SEAM_TIES; 0: the paper's coupling) */
    /* sem.resolution R (default 0: off): the accuracy setting. Every part is cut into patches
     * of at most L / R (L the model's bounding-box diagonal), each with its own polynomial
     * (sem_model_patches); the frames hold the file's parts, refined at the cuts. */
    double resolution;
    /* "pin": the material in pin_box is held (a material pin, sem_pin_region); the control
     * points in pin_control_box, of pin_parts and pin_points are pinned */
    int has_pin_box;
    double pin_box[6];
    int has_pin_control_box;
    double pin_control_box[6];
    int n_pin_parts;
    int *pin_parts;
    int n_pin_points;
    int *pin_points;
    sem_prescribe prescribe;          /* "prescribe": {...}: moves every pinned point */
    int n_prescribe_groups;           /* "prescribe": [{pin, affine|rotate}, ...] */
    sem_scene_prescribe_group *prescribe_groups;
    double initial_velocity[3];
    double initial_angular_velocity[3];
    int n_point_loads;
    sem_point_load *point_loads;
    int n_region_loads;
    sem_region_load *region_loads;
    double friction;         /* Coulomb coefficient of its surface (sem/contact.h) */
} sem_scene_object;

/* A static collider ("colliders": [...]): a plane, or a model file (IGES, OBJ free-form or
 * an OBJ triangle mesh) or a primitive, placed by its transform. */
typedef struct sem_scene_collider {
    int is_plane;
    double point[3], normal[3];  /* the plane */
    sem_scene_object shape;      /* otherwise: model_path or primitive, units and transform */
    double friction;
} sem_scene_collider;

typedef struct sem_scene {
    char path[4096];         /* scene file ("" for the embedded default) */
    int n_objects;
    sem_scene_object *objects;
    sem_world_def world;
    int frames;
    int steps_per_frame;
    char output_dir[4096];
    int write_iges, write_obj, write_mesh, write_usd;
    int write_glb;           /* output.glb: animation.glb */
    int mesh_resolution;
    int n_colliders;
    sem_scene_collider *colliders;
} sem_scene;

sem_status sem_scene_load(const char *path, sem_scene **out, sem_error *err);
/* name is used in messages; base_dir resolves relative model paths. */
sem_status sem_scene_parse(const char *json, const char *name, const char *base_dir,
                           sem_scene **out, sem_error *err);
void sem_scene_destroy(sem_scene *scene);
/* The embedded default scene: a rubber beam clamped at x = 0 swinging under gravity. */
const char *sem_scene_default_json(void);

/* Loads or generates the object's model, converts it to metres (see units) and applies its
 * transform: the model returned is in metres (units "M"). *file_unit_to_meter (may be NULL)
 * receives the factor used and file_units (may be NULL, 16 chars) the file's unit name, so
 * results can be written back in the file's own units (numbers / factor). */
sem_status sem_scene_object_model_units(const sem_scene *scene, int object, sem_model **out,
                                        double *file_unit_to_meter, char *file_units,
                                        sem_error *err);
/* The same without the units. */
sem_status sem_scene_object_model(const sem_scene *scene, int object, sem_model **out,
                                  sem_error *err);
/* The collider's definition for sem_world_add_collider: a plane, or the triangles of its
 * model (tessellated) or OBJ triangle mesh, in metres and transformed. *vertices and
 * *triangles (NULL for a plane) are the caller's to free. Errors name the key
 * ("scene.json: colliders[0].model: terrain.obj:12: a face with 5 vertices ..."). */
sem_status sem_scene_collider_def(const sem_scene *scene, int index, sem_collider_def *out,
                                  double **vertices, int **triangles, sem_error *err);
/* Metres per unit of a unit name ("mm", "M", "inch", ...; case-insensitive), 0 if unknown.
 * canonical (may be NULL, 16 chars) receives the IGES name ("MM", "M", "IN", ...). */
double sem_unit_to_meter(const char *name, char *canonical);
/* Per control point pin flags (1 = pinned: pin.control_box, pin.parts, pin.points) for the
 * object's model, or *out = NULL when none is; caller frees. */
sem_status sem_scene_object_pins(const sem_scene_object *obj, const sem_model *model,
                                 unsigned char **out, sem_error *err);
/* The material pins (sem_object_def.pin_regions) of pin.box and of the prescribe groups'
 * pin.box, in that order: the object's follows its single "prescribe" (or stays put), group g's
 * follows group g (prescribes[g]). *out = NULL and *n = 0 when there are none; caller frees. */
sem_status sem_scene_object_pin_regions(const sem_scene_object *obj, sem_pin_region **out, int *n,
                                        sem_error *err);
/* Per control point index into prescribe_groups (-1: none), or *out = NULL when the object
 * has no prescribe groups. A group that selects nothing (no control point, no material box)
 * is an error. */
sem_status sem_scene_object_prescribe_groups(const sem_scene_object *obj, const sem_model *model,
                                             int **out, sem_error *err);
/* Per part material index into part_materials (or -1); caller frees. */
sem_status sem_scene_object_part_materials(const sem_scene_object *obj, const sem_model *model,
                                           int **out, sem_material **materials, sem_error *err);


/* ---- a scene turned into a world (src/scene/scene_world.c) ---- */

/* Informational lines while a scene world is built ("object 0: 6 parts, 162 dofs;
 * preprocessing..."), and warnings (model reader warnings, discretization warnings): level
 * 0 info, 1 warning. */
typedef void (*sem_scene_log_fn)(void *user, int level, const char *message);

typedef struct sem_scene_world_options {
    const char *cache_dir;  /* folder of cached discretizations; NULL or "": no cache */
    int read_cache;         /* reuse a cached discretization when one matches */
    int write_cache;        /* store new discretizations in cache_dir */
    long long cache_max_bytes; /* bound of the cache folder (sem/cache.h); <= 0: none */
    sem_scene_log_fn log;   /* may be NULL */
    void *log_user;
    int skip_modes;         /* 1: do not look for zero-energy modes (sem_world_object_modes;
                               one factorization per object) */
    double memory_available; /* bytes the machine can give the run; > 0: once every object
                                is preprocessed, and before the world allocates its matrices,
                                a warning (log level 1) when the estimated peak
                                (sem_scene_world_estimated_memory) exceeds it; 0: no check */
} sem_scene_world_options;

sem_scene_world_options sem_default_scene_world_options(void);

/* The models (transformed), discretizations (preprocessed or loaded from the cache), pins,
 * materials and prescriptions of every object of a scene, and the world that steps them. */
typedef struct sem_scene_world sem_scene_world;

/* Builds everything a scene describes. Errors name the scene file and the object
 * ("scene.json: objects[1].pin.box: ..."). The scene must outlive the result. */
sem_status sem_scene_world_create(const sem_scene *scene, const sem_scene_world_options *options,
                                  sem_scene_world **out, sem_error *err);
void sem_scene_world_destroy(sem_scene_world *sw);
sem_world *sem_scene_world_world(sem_scene_world *sw);
const sem_scene *sem_scene_world_scene(const sem_scene_world *sw);
int sem_scene_world_object_count(const sem_scene_world *sw);
/* The object's model as simulated: in metres, transformed, at rest (the world holds the
 * moving control points). */
const sem_model *sem_scene_world_model(const sem_scene_world *sw, int object);
const sem_discretization *sem_scene_world_discretization(const sem_scene_world *sw, int object);
/* The units the object's model file was read in (see sem_scene_object_model_units): frames
 * are written back in them. */
const char *sem_scene_world_file_units(const sem_scene_world *sw, int object);
double sem_scene_world_file_unit_to_meter(const sem_scene_world *sw, int object);
/* The model an object's frames show, in metres, and its control points for the world's state
 * q: the simulated model itself, or with sem.resolution the file's parts refined at the
 * patches' cuts (sem_model_patches). q_out has 3 x sem_model_control_points(output model)
 * values. */
const sem_model *sem_scene_world_output_model(const sem_scene_world *sw, int object);
void sem_scene_world_output_q(const sem_scene_world *sw, int object, const double *q, double *q_out);
/* A copy of the object's model at its current control points in its file's units (numbers
 * times 1 / sem_scene_world_file_unit_to_meter, the model's units and unit_to_meter set to
 * them), exactly what `sem run` writes as a frame: a file saved from it (sem_model_save)
 * shows the model at its size in a CAD tool, as the run's frame_NNNN.igs does. The world
 * itself (sem_scene_world_model, sem_world_object_q) is in metres. The caller destroys it. */
sem_status sem_scene_world_frame_model(const sem_scene_world *sw, int object, sem_model **out,
                                       sem_error *err);
/* 1 when every object's discretization came from the cache. */
int sem_scene_world_all_cached(const sem_scene_world *sw);
/* Zero-energy modes found in an object (sem_world_object_modes), -1 when not looked for;
 * each one is also a warning in the log naming the parts that are not held. */
int sem_scene_world_spurious_modes(const sem_scene_world *sw, int object);
/* Wall time spent loading models and preprocessing (or reading the cache), seconds. */
double sem_scene_world_preprocess_seconds(const sem_scene_world *sw);
/* Estimated peak resident memory of the run, bytes: the program's base and, per object,
 * sem_world_estimate_memory without its base (objects are preprocessed one after the other,
 * so the largest preprocessing counts once). */
double sem_scene_world_estimated_memory(const sem_scene_world *sw);

#ifdef __cplusplus
}
#endif
#endif
