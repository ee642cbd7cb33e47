/*
 * sem/model.h - NURBS models: the geometry SEM animates.
 *
 * A model is a list of parts; a part is one rational B-spline surface, optionally
 * trimmed by loops of curves in its (u,v) parameter domain (an outer loop and holes).
 * Curves (trim curves in (u,v), stored as (u,v,0)) are rational B-splines too: every
 * entity the readers accept (lines, arcs, composites, analytic surfaces) is converted
 * exactly to this one representation, so writers and the SEM pipeline see one form.
 *
 * Degrees of freedom q are the stacked control points of all parts, part by part, in the
 * order (i + n_u * j) within a part (the IGES 128 order: u index fastest).
 */
#ifndef SEM_MODEL_H
#define SEM_MODEL_H

#include <stddef.h>

#include "sem/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* A rational B-spline curve. ctrl holds 3 doubles per control point. */
typedef struct sem_curve {
    int degree;
    int n_ctrl;
    double *knots;   /* n_ctrl + degree + 1 values, non-decreasing */
    double *ctrl;    /* 3 * n_ctrl */
    double *weights; /* n_ctrl, all > 0 */
    double t0, t1;   /* parameter range in use */
} sem_curve;

/* A rational B-spline surface (IGES 128). */
typedef struct sem_surface {
    int degree_u, degree_v;
    int n_u, n_v;       /* control grid */
    double *knots_u;    /* n_u + degree_u + 1 */
    double *knots_v;    /* n_v + degree_v + 1 */
    double *ctrl;       /* 3 * n_u * n_v, point (i,j) at 3*(i + n_u*j) */
    double *weights;    /* n_u * n_v, all > 0 */
    double u0, u1, v0, v1; /* parameter range in use */
    int closed_u, closed_v;     /* flags as read (informational) */
    int periodic_u, periodic_v; /* flags as read (informational) */
} sem_surface;

/* A closed loop of curves in the (u,v) domain of a surface. */
typedef struct sem_trim_loop {
    int n_curves;
    sem_curve *curves;
} sem_trim_loop;

typedef struct sem_part {
    char name[64];      /* from the file when it has one, else "" */
    sem_surface surface;
    int has_outer;      /* 0: the outer boundary is the boundary of the domain */
    sem_trim_loop outer;
    int n_holes;
    sem_trim_loop *holes;
    int source_entity;  /* IGES directory entry number of the surface, or 0 */
    int color;          /* IGES colour number (or -DE of a 314), 0 when none */
    int has_rgb;        /* 1 when the file gives the part a colour: */
    float rgb[3];       /* red, green, blue in 0..1 (IGES: the colour number's or the 314's) */
} sem_part;

typedef struct sem_model {
    int n_parts;
    int capacity;
    sem_part *parts;
    char units[16];        /* "MM", "M", "IN", ... from the IGES Global section */
    double unit_to_meter;  /* 1 unit of the model in metres */
    int n_warnings;
    char **warnings;       /* non-fatal messages from the reader */
} sem_model;

/* ---- life cycle ---- */
sem_model *sem_model_create(void);
void sem_model_destroy(sem_model *model);
/* Deep-copies part into the model (the caller keeps ownership of its own arrays). */
sem_status sem_model_add_part(sem_model *model, const sem_part *part, sem_error *err);
/* Takes ownership of the arrays inside part (part is zeroed on return). */
sem_status sem_model_take_part(sem_model *model, sem_part *part, sem_error *err);
sem_model *sem_model_clone(const sem_model *model);
/* Adds a warning (control bytes shown as '?'); after SEM_MODEL_MAX_WARNINGS one last line
 * says that the rest were dropped. */
#define SEM_MODEL_MAX_WARNINGS 1000
void sem_model_warn(sem_model *model, const char *fmt, ...);

void sem_part_free(sem_part *part);
void sem_curve_free(sem_curve *curve);
void sem_surface_free(sem_surface *surface);
sem_status sem_curve_copy(sem_curve *dst, const sem_curve *src);
sem_status sem_surface_copy(sem_surface *dst, const sem_surface *src);
sem_status sem_part_copy(sem_part *dst, const sem_part *src);

/* Allocates arrays for a surface/curve of the given size; weights set to 1. */
sem_status sem_surface_alloc(sem_surface *s, int degree_u, int degree_v, int n_u, int n_v);
sem_status sem_curve_alloc(sem_curve *c, int degree, int n_ctrl);

/* Checks knots, weights, sizes, finite numbers. Message names what is wrong. */
sem_status sem_surface_validate(const sem_surface *s, sem_error *err);
sem_status sem_curve_validate(const sem_curve *c, sem_error *err);

/* Checks what the readers check after conversion (sem/limits.h): parts, and the knot spans
 * of all surfaces weighted by their basis size, which bounds the work of every later step
 * (area, sampling, tessellation) for a model read from a small file. */
sem_status sem_model_check_limits(const sem_model *model, sem_error *err);

/* ---- sizes ---- */
size_t sem_model_control_points(const sem_model *model);
/* Offset (in control points) of each part's first control point in q; out has n_parts+1. */
void sem_model_part_offsets(const sem_model *model, size_t *out);
/* Gathers/scatters the control points of all parts into/from q (3 * control_points). */
void sem_model_get_q(const sem_model *model, double *q);
void sem_model_set_q(sem_model *model, const double *q);

/* ---- files ---- */
/* Format by extension (any case): .igs/.iges (IGES 5.3), .obj (free-form), .step/.stp
 * (ISO 10303-21 through Open CASCADE; SEM_ERR_UNSUPPORTED when libsem was built without it,
 * see sem_has_step() in sem/version.h). Only regular files are read, and the readers stop
 * at the limits of sem/limits.h with a message naming the limit. */
sem_status sem_model_load(const char *path, sem_model **out, sem_error *err);
sem_status sem_model_save(const sem_model *model, const char *path, sem_error *err);
sem_status sem_iges_read(const char *path, sem_model **out, sem_error *err);
sem_status sem_iges_read_buffer(const char *name, const char *data, size_t len, sem_model **out,
                                sem_error *err);
sem_status sem_iges_write(const sem_model *model, const char *path, sem_error *err);
sem_status sem_obj_read(const char *path, sem_model **out, sem_error *err);
sem_status sem_obj_read_buffer(const char *name, const char *data, size_t len, sem_model **out,
                               sem_error *err);
sem_status sem_obj_write(const sem_model *model, const char *path, sem_error *err);
/* STEP AP214 through Open CASCADE: every face of the file becomes one part (its surface as
 * a NURBS, its wires as parameter-space trim loops; model-space edges without a
 * parameter-space curve are projected into the face), lengths in the file's unit. Writing
 * stores each part as a trimmed B-spline face in the model's unit. */
sem_status sem_step_read(const char *path, sem_model **out, sem_error *err);
sem_status sem_step_write(const sem_model *model, const char *path, sem_error *err);
/* Tessellated triangle mesh with normals; `resolution` samples per knot span per direction. */
sem_status sem_mesh_obj_write(const sem_model *model, const char *path, int resolution,
                              sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
