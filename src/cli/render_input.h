/*
 * render_input.h - what `sem render` draws: the frames (render_input.c) and their colours
 * (render_colors.c).
 */
#ifndef SEM_CLI_RENDER_INPUT_H
#define SEM_CLI_RENDER_INPUT_H

#include "run_folder.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/render.h"
#include "sem/tessellate.h"

/* ---- the frames (render_input.c) ---- */

typedef struct render_input {
    int is_run;                 /* a run folder, or one model file at rest */
    run_folder run;
    char path[4096];            /* the folder or the model file */
    int first, count;           /* frames first .. first + count - 1 (a model: 0, 1) */
    sem_model *rest;            /* frame 0 (the rest state) or the model */
    size_t n_ctrl;
    double *q;                  /* count x 3 n_ctrl control point coordinates */
    int n_objects;
    int *object_first_part;     /* n_objects + 1 */
    size_t *object_first_ctrl;  /* n_objects + 1 */
    sem_mesh_template *tmpl;    /* tessellation of rest (same topology in every frame),
                                   covering trimmed parts past their trim curves */
    sem_render_trims *trims;    /* exact trim curves for the renderer */
    double bounds[6];           /* box of every frame's tessellation */
} render_input;

/* A run folder: the frames to draw are first..last (last < 0: to the end); every frame is
 * read (in parallel), checked to have frame 0's parts, and counted in the box the camera
 * frames. */
sem_status render_input_open_run(const char *dir, int first, int last, int resolution,
                                 render_input *in, sem_error *err);
/* One model at rest. */
sem_status render_input_open_model(const char *path, int resolution, render_input *in,
                                   sem_error *err);
void render_input_free(render_input *in);
/* The mesh of frame k (0-based in first..) into mesh (allocated by sem_mesh_template_mesh);
 * model is a scratch copy of in->rest. */
sem_status render_input_mesh(const render_input *in, int k, sem_model *model, sem_mesh *mesh,
                             sem_error *err);

/* ---- the colours (render_colors.c) ---- */

typedef enum render_color_mode {
    RENDER_COLOR_PART,
    RENDER_COLOR_MATERIAL,
    RENDER_COLOR_WEIGHTS,
    RENDER_COLOR_ORIGINS,
    RENDER_COLOR_QUADRATURE
} render_color_mode;

typedef struct render_colors {
    render_color_mode mode;
    int part;                 /* weights:PART */
    float *vertex_colors;     /* 3 per vertex of the tessellation */
    float opacity;
    int n_points;             /* quadrature points or origins of every object */
    int *object_first_point;  /* n_objects + 1 */
    float *point_colors;
    double point_radius;
    sem_discretization **discs; /* per object, for the diagnostic modes */
} render_colors;

/* Parses part|material|weights:PART|origins|quadrature (usage errors are 2, via cli). */
int render_colors_parse(const char *text, render_color_mode *mode, int *part);
/* Colours for mode. Diagnostics read each object's preprocess_K.semdisc (a run folder),
 * disc_path (a model with --disc), or preprocess the model with default settings. log
 * (may be NULL) gets informational lines. */
sem_status render_colors_build(const render_input *in, render_color_mode mode, int part,
                               const char *disc_path, void (*log)(const char *message),
                               render_colors *colors, sem_error *err);
/* Where the points are in frame k: 3 n_points values. */
sem_status render_colors_points(const render_colors *colors, const render_input *in, int k,
                                double *x, sem_error *err);
void render_colors_free(render_colors *colors, int n_objects);

#endif
