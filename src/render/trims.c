/*
 * trims.c - exact trim curves in pictures (see sem/render.h).
 *
 * A tessellation keeps or drops whole triangles, so trim curves drawn from it are jagged
 * by one grid cell (the centroid rule of sem_mesh_template_build). Instead the renderer
 * draws a covering mesh (every triangle that reaches into the trimmed domain) and an
 * Embree filter drops each hit whose (u,v) lies outside the trim loops, so trim curves are
 * exact at every pixel, in the picture and in the shadows. Only triangles that cross a
 * trim curve are tested: those whose corners, edge midpoints and centroid are all inside
 * are taken as inside (a curve could only cut off a sliver between those points).
 */
#include <stdlib.h>

#include "sem/render.h"

struct sem_render_trims {
    int n_parts;
    sem_trim_region **regions;       /* per part, NULL when untrimmed */
    const sem_trim_region **table;   /* per triangle */
};

void sem_render_trims_destroy(sem_render_trims *t)
{
    if (!t) return;
    if (t->regions)
        for (int i = 0; i < t->n_parts; ++i) sem_trim_region_destroy(t->regions[i]);
    free(t->regions);
    free(t->table);
    free(t);
}

const struct sem_trim_region *const *sem_render_trims_table(const sem_render_trims *t)
{
    return t ? (const struct sem_trim_region *const *)t->table : NULL;
}

/* Are the corners, edge midpoints and centroid of triangle k all inside? */
static int inside_triangle(const sem_trim_region *r, const sem_mesh *m, int k)
{
    double u[3], v[3];
    for (int c = 0; c < 3; ++c) {
        int vtx = m->triangles[3 * (size_t)k + c];
        u[c] = m->uv[2 * (size_t)vtx];
        v[c] = m->uv[2 * (size_t)vtx + 1];
        if (!sem_trim_region_inside(r, u[c], v[c])) return 0;
    }
    for (int c = 0; c < 3; ++c)
        if (!sem_trim_region_inside(r, 0.5 * (u[c] + u[(c + 1) % 3]), 0.5 * (v[c] + v[(c + 1) % 3]))) return 0;
    return sem_trim_region_inside(r, (u[0] + u[1] + u[2]) / 3.0, (v[0] + v[1] + v[2]) / 3.0);
}

sem_status sem_render_trims_build(const sem_model *model, const sem_mesh *mesh, sem_render_trims **out,
                                  sem_error *err)
{
    *out = NULL;
    if (!model || !mesh || mesh->n_parts != model->n_parts)
        return sem_error_set(err, SEM_ERR_INVALID, "render: the mesh is not of this model");
    sem_render_trims *t = calloc(1, sizeof *t);
    if (!t) return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    t->n_parts = model->n_parts;
    t->regions = calloc((size_t)model->n_parts + 1, sizeof *t->regions);
    t->table = calloc((size_t)mesh->n_triangles + 1, sizeof *t->table);
    if (!t->regions || !t->table) {
        sem_render_trims_destroy(t);
        return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    }
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_part *part = &model->parts[i];
        if (!part->has_outer && part->n_holes == 0) continue;
        sem_status st = sem_trim_region_build(part, &t->regions[i], err);
        if (st != SEM_OK) {
            sem_render_trims_destroy(t);
            return st;
        }
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (int k = 0; k < mesh->n_triangles; ++k) {
        const sem_trim_region *r = t->regions[mesh->triangle_part[k]];
        t->table[k] = r && !inside_triangle(r, mesh, k) ? r : NULL;
    }
    *out = t;
    return SEM_OK;
}
