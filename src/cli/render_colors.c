/*
 * render_colors.c - the colours of `sem render --color` (see render_input.h, docs/render.md).
 *
 *   part        one palette colour per part (parts numbered over all objects, as in the
 *               frame files and `sem inspect`)
 *   material    one colour per distinct material: an object's own material and each of its
 *               part_materials entries (summary.json's part_material; a model file has one)
 *   weights:P   the blending weight of part P near the surface, on a ramp from 0 (dark
 *               blue) to 1 (red) (paper Fig. 5)
 *   origins     each deformation origin's parts in one colour, see-through, with the
 *               origins as spheres (Fig. 6)
 *   quadrature  the volume quadrature points as dots inside a see-through surface (Fig. 7)
 *
 * The diagnostic views need each object's preprocessing: a run folder has it in
 * preprocess_K.semdisc (written by `sem run`); for a model file it is read from --disc or
 * computed with the default settings. Points (quadrature points, origins) follow the SEM
 * map frame by frame, as the simulation moves them.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "render_input.h"
#include "sem/render.h"
#include "util/free_all.h"

int render_colors_parse(const char *text, render_color_mode *mode, int *part)
{
    *part = -1;
    if (!strcmp(text, "part") || !strcmp(text, "parts")) {
        *mode = RENDER_COLOR_PART;
    } else if (!strcmp(text, "material") || !strcmp(text, "materials")) {
        *mode = RENDER_COLOR_MATERIAL;
    } else if (!strcmp(text, "origins")) {
        *mode = RENDER_COLOR_ORIGINS;
    } else if (!strcmp(text, "quadrature")) {
        *mode = RENDER_COLOR_QUADRATURE;
    } else if (!strncmp(text, "weights:", 8)) {
        *mode = RENDER_COLOR_WEIGHTS;
        if (cli_parse_int("render", "--color weights:PART", text + 8, part) != CLI_OK) return CLI_USAGE;
    } else {
        return cli_usage("render", "--color must be part, material, weights:PART, origins or quadrature (got '%s')",
                         text);
    }
    return CLI_OK;
}

/* Which object a global part belongs to. */
static int object_of_part(const render_input *in, int part)
{
    int o = 0;
    while (o + 1 < in->n_objects && part >= in->object_first_part[o + 1]) o++;
    return o;
}

/* The object's sub-model: a view into in->rest (no copies). */
static sem_model object_view(const render_input *in, int o)
{
    sem_model view = *in->rest;
    view.parts = in->rest->parts + in->object_first_part[o];
    view.n_parts = in->object_first_part[o + 1] - in->object_first_part[o];
    view.n_warnings = 0;
    view.warnings = NULL;
    return view;
}

static sem_status check_disc(const sem_discretization *d, const render_input *in, int o, const char *path,
                             sem_error *err)
{
    int parts = in->object_first_part[o + 1] - in->object_first_part[o];
    size_t ctrl = in->object_first_ctrl[o + 1] - in->object_first_ctrl[o];
    if (d->n_parts != parts || (size_t)d->n_ctrl != ctrl)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "%s: preprocessed data for %d parts and %d control points, but the model has %d and %zu",
                             path, d->n_parts, d->n_ctrl, parts, ctrl);
    return SEM_OK;
}

static sem_status load_discs(const render_input *in, const char *disc_path, void (*log)(const char *),
                             render_colors *c, sem_error *err)
{
    c->discs = calloc((size_t)in->n_objects, sizeof *c->discs);
    if (!c->discs) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int o = 0; o < in->n_objects; ++o) {
        char path[4300];
        sem_status st;
        if (in->is_run) {
            snprintf(path, sizeof path, "%s/preprocess_%d.semdisc", in->run.dir, o);
            st = sem_discretization_load(path, 0, &c->discs[o], err);
            if (st == SEM_ERR_IO)
                return sem_error_set(err, st,
                                     "%s: not found; the diagnostic colourings need the preprocessing sem run "
                                     "writes there (run the scene again with this version of sem)",
                                     path);
        } else if (disc_path) {
            snprintf(path, sizeof path, "%s", disc_path);
            st = sem_discretization_load(path, 0, &c->discs[o], err);
        } else {
            snprintf(path, sizeof path, "%s", in->path);
            if (log) {
                char msg[4400];
                snprintf(msg, sizeof msg, "preprocessing %s with the default settings (--disc FILE to use others)",
                         in->path);
                log(msg);
            }
            sem_model view = object_view(in, o);
            sem_preprocess_options opt = sem_default_preprocess_options();
            st = sem_preprocess(&view, &opt, &c->discs[o], err);
        }
        if (st != SEM_OK) return st;
        if ((st = check_disc(c->discs[o], in, o, path, err)) != SEM_OK) return st;
    }
    return SEM_OK;
}

/* part_material of summary.json: material number of each part over all objects. */
static sem_status material_numbers(const render_input *in, int *number, sem_error *err)
{
    const int n = in->rest->n_parts;
    for (int p = 0; p < n; ++p) number[p] = 0;
    if (!in->is_run || !in->run.summary) return SEM_OK;
    /* distinct (object, index) pairs in order of first appearance */
    int next = 0;
    for (int o = 0; o < in->n_objects; ++o) {
        const cJSON *obj = run_folder_object(&in->run, o);
        const cJSON *pm = cJSON_GetObjectItemCaseSensitive(obj, "part_material");
        const int parts = in->object_first_part[o + 1] - in->object_first_part[o];
        if (!cJSON_IsArray(pm) || cJSON_GetArraySize(pm) != parts)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s/summary.json: objects[%d].part_material is missing; --color material needs "
                                 "a run written by this version of sem",
                                 in->run.dir, o);
        int max = -1;
        for (int p = 0; p < parts; ++p) {
            const cJSON *m = cJSON_GetArrayItem(pm, p);
            if (!cJSON_IsNumber(m) || m->valuedouble < -1 || m->valuedouble > 1e6)
                return sem_error_set(err, SEM_ERR_INVALID, "%s/summary.json: objects[%d].part_material: bad entry",
                                     in->run.dir, o);
            if ((int)m->valuedouble > max) max = (int)m->valuedouble;
        }
        int *seen = malloc(((size_t)max + 2) * sizeof *seen);
        if (!seen) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int k = 0; k < max + 2; ++k) seen[k] = -1;
        for (int p = 0; p < parts; ++p) {
            int slot = (int)cJSON_GetArrayItem(pm, p)->valuedouble + 1; /* 0: the object's material */
            if (seen[slot] < 0) seen[slot] = next++;
            number[in->object_first_part[o] + p] = seen[slot];
        }
        free(seen);
    }
    return SEM_OK;
}

sem_status render_colors_build(const render_input *in, render_color_mode mode, int part, const char *disc_path,
                               void (*log)(const char *), render_colors *c, sem_error *err)
{
    memset(c, 0, sizeof *c);
    c->mode = mode;
    c->part = part;
    c->opacity = 1.0f;
    const int n_parts = in->rest->n_parts;
    if (mode == RENDER_COLOR_WEIGHTS && (part < 0 || part >= n_parts))
        return sem_error_set(err, SEM_ERR_INVALID, "--color weights:%d: %s has parts 0..%d", part, in->path,
                             n_parts - 1);
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    sem_status st = sem_mesh_template_mesh(in->tmpl, &mesh, err);
    if (st == SEM_OK) st = sem_mesh_update(in->tmpl, in->rest, &mesh, err); /* at rest */
    int *number = NULL;
    if (st == SEM_OK) {
        c->vertex_colors = malloc(3 * ((size_t)mesh.n_vertices + 1) * sizeof *c->vertex_colors);
        number = malloc(((size_t)n_parts + 1) * sizeof *number);
        if (!c->vertex_colors || !number) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    if (st == SEM_OK && mode >= RENDER_COLOR_WEIGHTS) st = load_discs(in, disc_path, log, c, err);
    if (st == SEM_OK) {
        switch (mode) {
        case RENDER_COLOR_PART:
            for (int p = 0; p < n_parts; ++p) number[p] = p;
            break;
        case RENDER_COLOR_MATERIAL:
            st = material_numbers(in, number, err);
            break;
        case RENDER_COLOR_ORIGINS: {
            int offset = 0;
            for (int o = 0; o < in->n_objects; ++o) {
                const sem_discretization *d = c->discs[o];
                for (int p = in->object_first_part[o]; p < in->object_first_part[o + 1]; ++p)
                    number[p] = offset + d->part_origin[p - in->object_first_part[o]];
                offset += d->n_origins;
            }
            c->opacity = 0.45f;
            break;
        }
        default:
            break;
        }
    }
    if (st == SEM_OK && mode == RENDER_COLOR_WEIGHTS) {
        const int o = object_of_part(in, part);
        float *w = calloc((size_t)mesh.n_vertices + 1, sizeof *w);
        if (!w) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        const int v0 = mesh.part_vertex_start[in->object_first_part[o]];
        const int v1 = mesh.part_vertex_start[in->object_first_part[o + 1]];
        if (st == SEM_OK)
            st = sem_render_part_weights(c->discs[o], part - in->object_first_part[o], v1 - v0,
                                         &mesh.positions[3 * (size_t)v0], &w[v0], err);
        for (int v = 0; v < mesh.n_vertices && st == SEM_OK; ++v) sem_render_ramp(w[v], &c->vertex_colors[3 * (size_t)v]);
        free(w);
        c->opacity = 0.55f;
    } else if (st == SEM_OK && mode == RENDER_COLOR_QUADRATURE) {
        float grey[3] = {0.62f, 0.64f, 0.68f};
        for (int v = 0; v < mesh.n_vertices; ++v) memcpy(&c->vertex_colors[3 * (size_t)v], grey, sizeof grey);
        c->opacity = 0.28f;
    } else if (st == SEM_OK) {
        for (int p = 0; p < n_parts; ++p) {
            float rgb[3];
            sem_render_palette(number[p], rgb);
            for (int v = mesh.part_vertex_start[p]; v < mesh.part_vertex_start[p + 1]; ++v)
                memcpy(&c->vertex_colors[3 * (size_t)v], rgb, sizeof rgb);
        }
    }
    /* points: quadrature points or origins */
    if (st == SEM_OK && mode != RENDER_COLOR_PART && mode != RENDER_COLOR_MATERIAL) {
        c->object_first_point = calloc((size_t)in->n_objects + 1, sizeof *c->object_first_point);
        if (!c->object_first_point) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int o = 0; o < in->n_objects && st == SEM_OK; ++o)
            c->object_first_point[o + 1] = c->object_first_point[o] +
                                           (mode == RENDER_COLOR_ORIGINS ? c->discs[o]->n_origins : c->discs[o]->n_quad);
        c->n_points = st == SEM_OK ? c->object_first_point[in->n_objects] : 0;
        c->point_colors = malloc(3 * ((size_t)c->n_points + 1) * sizeof *c->point_colors);
        if (!c->point_colors) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        double diagonal = 0;
        for (int k = 0; k < 3; ++k)
            diagonal += (in->bounds[k + 3] - in->bounds[k]) * (in->bounds[k + 3] - in->bounds[k]);
        diagonal = diagonal > 0 ? sqrt(diagonal) : 1.0;
        if (st == SEM_OK && mode != RENDER_COLOR_ORIGINS) {
            float dot[3] = {0.86f, 0.20f, 0.04f};
            for (int p = 0; p < c->n_points; ++p) memcpy(&c->point_colors[3 * (size_t)p], dot, sizeof dot);
            if (mode == RENDER_COLOR_WEIGHTS) { /* each quadrature point by its own weight */
                const int o = object_of_part(in, part), local = part - in->object_first_part[o];
                const sem_discretization *d = c->discs[o];
                for (int p = 0; p < c->n_points; ++p) sem_render_ramp(0.0, &c->point_colors[3 * (size_t)p]);
                for (int p = 0; p < d->n_quad; ++p)
                    for (int s = d->W.row_start[p]; s < d->W.row_start[p + 1]; ++s)
                        if (d->W.col[s] == local)
                            sem_render_ramp(d->W.val[s], &c->point_colors[3 * (size_t)(c->object_first_point[o] + p)]);
            }
            /* dots a third of the typical spacing across, visible at any picture size */
            double spacing = 0;
            for (int o = 0; o < in->n_objects; ++o) {
                double s = sem_render_point_spacing(c->discs[o]->n_quad, c->discs[o]->quad_X);
                if (o == 0 || s < spacing) spacing = s;
            }
            c->point_radius = 0.3 * spacing;
            if (c->point_radius > 0.02 * diagonal) c->point_radius = 0.02 * diagonal;
            if (c->point_radius < 0.002 * diagonal) c->point_radius = 0.002 * diagonal;
        } else if (st == SEM_OK) {
            int offset = 0;
            for (int o = 0; o < in->n_objects; ++o) {
                for (int j = 0; j < c->discs[o]->n_origins; ++j) {
                    float rgb[3];
                    sem_render_palette(offset + j, rgb);
                    for (int k = 0; k < 3; ++k) rgb[k] *= 0.6f; /* darker than its parts */
                    memcpy(&c->point_colors[3 * (size_t)(c->object_first_point[o] + j)], rgb, sizeof rgb);
                }
                offset += c->discs[o]->n_origins;
            }
            c->point_radius = 0.02 * diagonal;
        }
    }
    free(number);
    sem_mesh_free(&mesh);
    if (st != SEM_OK) render_colors_free(c, in->n_objects);
    return st;
}

sem_status render_colors_points(const render_colors *c, const render_input *in, int k, double *x, sem_error *err)
{
    const double *q = &in->q[3 * in->n_ctrl * (size_t)k];
    for (int o = 0; o < in->n_objects; ++o) {
        const double *qo = &q[3 * in->object_first_ctrl[o]];
        double *xo = &x[3 * (size_t)c->object_first_point[o]];
        sem_status st = c->mode == RENDER_COLOR_ORIGINS ? sem_render_map_origins(c->discs[o], qo, xo, err)
                                                        : sem_render_map_quadrature(c->discs[o], qo, xo, err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

void render_colors_free(render_colors *c, int n_objects)
{
    if (c->discs)
        for (int o = 0; o < n_objects; ++o) sem_discretization_destroy(c->discs[o]);
    SEM_FREE_ALL(c->discs, c->vertex_colors, c->point_colors, c->object_first_point);
    memset(c, 0, sizeof *c);
}
