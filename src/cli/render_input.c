/*
 * render_input.c - the frames `sem render` draws (see render_input.h).
 *
 * Every frame of a run is the same NURBS model with moved control points, so the frames
 * are read once (in parallel: parsing IGES is a large share of the work) and kept as
 * control point arrays; the tessellation template is built once from frame 0 and each
 * frame's mesh is one sem_mesh_update. The template covers trimmed parts past their trim
 * curves, which the renderer then cuts exactly (sem_render_trims). The camera must frame the whole animation, so the
 * box of every selected frame's tessellation is known before the first picture.
 * Frame 0 is always read: it is the rest state, where the diagnostic colourings are
 * evaluated, even when --frames starts later.
 */
#include "render_input.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <omp.h>

static void bounds_add(double b[6], const sem_mesh *m)
{
    for (int v = 0; v < m->n_vertices; ++v)
        for (int k = 0; k < 3; ++k) {
            double x = m->positions[3 * (size_t)v + k];
            if (x < b[k]) b[k] = x;
            if (x > b[k + 3]) b[k + 3] = x;
        }
}

static sem_status objects_of(render_input *in, sem_error *err)
{
    const int n_obj = in->is_run ? in->run.n_objects : 1;
    in->object_first_part = calloc((size_t)n_obj + 1, sizeof *in->object_first_part);
    in->object_first_ctrl = calloc((size_t)n_obj + 1, sizeof *in->object_first_ctrl);
    if (!in->object_first_part || !in->object_first_ctrl) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    in->n_objects = n_obj;
    int known = 1, total = 0;
    for (int o = 0; o < n_obj && in->is_run; ++o) {
        if (in->run.object_parts[o] <= 0) known = 0;
        total += in->run.object_parts[o];
    }
    if (!in->is_run || !known || total != in->rest->n_parts) {
        /* one object (a model file, or a run without a usable summary.json) */
        in->n_objects = 1;
        in->object_first_part[1] = in->rest->n_parts;
    } else {
        for (int o = 0; o < n_obj; ++o)
            in->object_first_part[o + 1] = in->object_first_part[o] + in->run.object_parts[o];
    }
    size_t *offsets = malloc(((size_t)in->rest->n_parts + 1) * sizeof *offsets);
    if (!offsets) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_model_part_offsets(in->rest, offsets);
    for (int o = 0; o <= in->n_objects; ++o) in->object_first_ctrl[o] = offsets[in->object_first_part[o]];
    free(offsets);
    return SEM_OK;
}

static sem_status prepare(render_input *in, int resolution, sem_error *err)
{
    in->n_ctrl = sem_model_control_points(in->rest);
    if (in->rest->n_parts < 1 || in->n_ctrl < 1)
        return sem_error_set(err, SEM_ERR_INVALID, "%s: the model has no parts", in->path);
    sem_status st = objects_of(in, err);
    if (st == SEM_OK) st = sem_mesh_template_build_covering(in->rest, resolution, &in->tmpl, err);
    if (st != SEM_OK) return st;
    /* trims need the topology and (u,v) only, which every frame shares */
    sem_mesh mesh;
    if ((st = sem_mesh_template_mesh(in->tmpl, &mesh, err)) != SEM_OK) return st;
    st = sem_render_trims_build(in->rest, &mesh, &in->trims, err);
    sem_mesh_free(&mesh);
    return st;
}

sem_status render_input_mesh(const render_input *in, int k, sem_model *model, sem_mesh *mesh,
                             sem_error *err)
{
    sem_model_set_q(model, &in->q[3 * in->n_ctrl * (size_t)k]);
    return sem_mesh_update(in->tmpl, model, mesh, err);
}

/* Reads every frame of the run: keeps the control points of frames first.. and the box of
 * all frames' meshes, so that the camera is the same whichever frames are drawn (frame k
 * alone gives the same picture as frame k of the whole run). */
static sem_status read_frames(render_input *in, sem_error *err)
{
    const int n_all = in->is_run ? in->run.n_frames : in->count;
    in->q = malloc(3 * in->n_ctrl * (size_t)in->count * sizeof *in->q);
    if (!in->q) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory (%d frames)", in->count);
    for (int k = 0; k < 3; ++k) {
        in->bounds[k] = INFINITY;
        in->bounds[k + 3] = -INFINITY;
    }
    int failed_frame = n_all; /* the lowest failing frame reports */
    sem_error first_error;
    sem_error_clear(&first_error);
#pragma omp parallel
    {
        sem_model *scratch = sem_model_clone(in->rest);
        sem_mesh mesh;
        memset(&mesh, 0, sizeof mesh);
        double box[6] = {INFINITY, INFINITY, INFINITY, -INFINITY, -INFINITY, -INFINITY};
        double *q_other = malloc(3 * in->n_ctrl * sizeof *q_other); /* frames not drawn */
        sem_error e;
        sem_error_clear(&e);
        int ok = scratch && q_other && sem_mesh_template_mesh(in->tmpl, &mesh, &e) == SEM_OK;
        if (!scratch || !q_other) sem_error_set(&e, SEM_ERR_NOMEM, "out of memory");
#pragma omp for schedule(dynamic, 1)
        for (int frame = 0; frame < n_all; ++frame) {
            const int k = frame - in->first, drawn = k >= 0 && k < in->count;
            double *q = drawn ? &in->q[3 * in->n_ctrl * (size_t)k] : q_other;
            int bad = !ok;
            if (!bad) {
                char path[4200];
                run_folder_frame_path(&in->run, frame, path, sizeof path);
                sem_model *m = NULL;
                if (sem_model_load(path, &m, &e) != SEM_OK) {
                    bad = 1;
                } else if (!run_frame_matches(in->rest, m)) {
                    sem_error_set(&e, SEM_ERR_INVALID,
                                  "%s: not the same model as frame 0 (%d parts, frame 0 has %d, or other grids)",
                                  path, m->n_parts, in->rest->n_parts);
                    bad = 1;
                } else {
                    sem_model_get_q(m, q);
                    sem_model_set_q(scratch, q);
                    if (sem_mesh_update(in->tmpl, scratch, &mesh, &e) != SEM_OK)
                        bad = 1;
                    else
                        bounds_add(box, &mesh);
                }
                sem_model_destroy(m);
            }
            if (bad) {
#pragma omp critical(render_input_error)
                if (frame < failed_frame) {
                    failed_frame = frame;
                    first_error = e;
                }
            }
        }
#pragma omp critical(render_input_bounds)
        for (int j = 0; j < 3; ++j) {
            if (box[j] < in->bounds[j]) in->bounds[j] = box[j];
            if (box[j + 3] > in->bounds[j + 3]) in->bounds[j + 3] = box[j + 3];
        }
        sem_mesh_free(&mesh);
        sem_model_destroy(scratch);
        free(q_other);
    }
    if (failed_frame < n_all) {
        if (err) *err = first_error;
        return first_error.status != SEM_OK ? first_error.status : SEM_ERR_INVALID;
    }
    return SEM_OK;
}

sem_status render_input_open_run(const char *dir, int first, int last, int resolution,
                                 render_input *in, sem_error *err)
{
    memset(in, 0, sizeof *in);
    in->is_run = 1;
    snprintf(in->path, sizeof in->path, "%s", dir);
    sem_status st = run_folder_open(dir, &in->run, err);
    if (st != SEM_OK) return st;
    const int n = in->run.n_frames;
    if (last < 0) last = n - 1;
    if (first < 0 || first > last || last >= n) {
        st = sem_error_set(err, SEM_ERR_INVALID, "--frames %d:%d: the run has frames 0..%d", first, last, n - 1);
        render_input_free(in);
        return st;
    }
    in->first = first;
    in->count = last - first + 1;
    char path[4200];
    run_folder_frame_path(&in->run, 0, path, sizeof path);
    if ((st = sem_model_load(path, &in->rest, err)) != SEM_OK || (st = prepare(in, resolution, err)) != SEM_OK ||
        (st = read_frames(in, err)) != SEM_OK) {
        render_input_free(in);
        return st;
    }
    return SEM_OK;
}

sem_status render_input_open_model(const char *path, int resolution, render_input *in, sem_error *err)
{
    memset(in, 0, sizeof *in);
    snprintf(in->path, sizeof in->path, "%s", path);
    in->first = 0;
    in->count = 1;
    sem_status st = sem_model_load(path, &in->rest, err);
    if (st == SEM_OK) st = prepare(in, resolution, err);
    if (st == SEM_OK) {
        in->q = malloc(3 * in->n_ctrl * sizeof *in->q);
        if (!in->q) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    if (st == SEM_OK) {
        sem_model_get_q(in->rest, in->q);
        for (int k = 0; k < 3; ++k) {
            in->bounds[k] = INFINITY;
            in->bounds[k + 3] = -INFINITY;
        }
        st = sem_mesh_template_mesh(in->tmpl, &mesh, err);
        if (st == SEM_OK) st = sem_mesh_update(in->tmpl, in->rest, &mesh, err);
        if (st == SEM_OK) bounds_add(in->bounds, &mesh);
    }
    sem_mesh_free(&mesh);
    if (st != SEM_OK) render_input_free(in);
    return st;
}

void render_input_free(render_input *in)
{
    if (in->is_run) run_folder_close(&in->run);
    sem_model_destroy(in->rest);
    sem_mesh_template_destroy(in->tmpl);
    sem_render_trims_destroy(in->trims);
    free(in->q);
    free(in->object_first_part);
    free(in->object_first_ctrl);
    memset(in, 0, sizeof *in);
}
