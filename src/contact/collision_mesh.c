/*
 * collision_mesh.c - an object's contact points as rows of x = J q (see collision_mesh.h).
 */
#include "collision_mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/tessellate.h"

/* Cells per knot span so that triangle edges are at most about L / 16 (2..16). */
static int automatic_resolution(const sem_model *model, double L, sem_error *err, int *out)
{
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    sem_status st = sem_mesh_from_model(model, 1, &mesh, err);
    if (st != SEM_OK) return st;
    double longest = 0;
    for (int t = 0; t < mesh.n_triangles; ++t)
        for (int e = 0; e < 3; ++e) {
            const double *a = mesh.positions + 3 * (size_t)mesh.triangles[3 * t + e];
            const double *b = mesh.positions + 3 * (size_t)mesh.triangles[3 * t + (e + 1) % 3];
            double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                            (a[2] - b[2]) * (a[2] - b[2]));
            if (d > longest) longest = d;
        }
    sem_mesh_free(&mesh);
    int r = L > 0 ? (int)ceil(longest / (L / 16.0)) : 2;
    *out = r < 2 ? 2 : r > 16 ? 16 : r;
    return SEM_OK;
}

/* Turns every part's triangles so that they face away from the object's inside. A part's
 * (u, v) orientation is the modeller's; the contact between objects needs outward normals.
 * Heuristic: a part whose triangles enclose a negative volume seen from the surface's
 * area centroid is turned (exact for star-shaped bodies; the preprocessing's own
 * orientation fix is not part of the discretization). */
static void orient_parts(sem_collision_mesh *m, const sem_mesh *mesh)
{
    double centre[3] = {0, 0, 0}, total = 0;
    for (int t = 0; t < m->n_triangles; ++t) {
        const int *tri = m->triangles + 3 * t;
        for (int v = 0; v < 3; ++v) {
            const double *x = m->x + 3 * (size_t)tri[v];
            double a = 1.0;
            for (int k = 0; k < 3; ++k) centre[k] += a * x[k];
            total += a;
        }
    }
    if (total > 0)
        for (int k = 0; k < 3; ++k) centre[k] /= total;
    for (int p = 0; p < mesh->n_parts; ++p) {
        double volume = 0;
        int t0 = mesh->part_triangle_start[p], t1 = mesh->part_triangle_start[p + 1];
        for (int t = t0; t < t1; ++t) {
            const int *tri = m->triangles + 3 * t;
            double a[3], b[3], c[3];
            for (int k = 0; k < 3; ++k) {
                a[k] = m->x[3 * (size_t)tri[0] + k] - centre[k];
                b[k] = m->x[3 * (size_t)tri[1] + k] - centre[k];
                c[k] = m->x[3 * (size_t)tri[2] + k] - centre[k];
            }
            volume += a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) +
                      a[2] * (b[0] * c[1] - b[1] * c[0]);
        }
        if (volume < 0)
            for (int t = t0; t < t1; ++t) {
                int x = m->triangles[3 * t + 1];
                m->triangles[3 * t + 1] = m->triangles[3 * t + 2];
                m->triangles[3 * t + 2] = x;
            }
    }
}

void sem_collision_mesh_free(sem_collision_mesh *m)
{
    free(m->row_start);
    free(m->row_ctrl);
    free(m->row_w);
    free(m->area);
    free(m->triangles);
    free(m->x);
    free(m->pseudo_normal);
    sem_bvh_free(&m->bvh);
    memset(m, 0, sizeof *m);
}

sem_status sem_collision_mesh_build(const sem_model *model, int resolution, sem_collision_mesh *out,
                                    sem_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n_ctrl = sem_model_control_points(model);
    double *q = malloc(3 * n_ctrl * sizeof(double) + 1);
    size_t *part_offset = malloc(((size_t)model->n_parts + 1) * sizeof(size_t));
    if (!q || !part_offset) {
        free(q);
        free(part_offset);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_model_get_q(model, q);
    sem_model_part_offsets(model, part_offset);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t c = 0; c < n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], q[3 * c + k]);
            hi[k] = fmax(hi[k], q[3 * c + k]);
        }
    out->length = n_ctrl ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                (hi[2] - lo[2]) * (hi[2] - lo[2]))
                         : 0;
    sem_status st = SEM_OK;
    sem_mesh_template *tmpl = NULL;
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    int *index = NULL, *used = NULL;
    double *phi = NULL;
    if (resolution <= 0 && (st = automatic_resolution(model, out->length, err, &resolution)) != SEM_OK)
        goto done;
    out->resolution = resolution;
    if ((st = sem_mesh_template_build(model, resolution, &tmpl, err)) != SEM_OK) goto done;
    if ((st = sem_mesh_template_mesh(tmpl, &mesh, err)) != SEM_OK) goto done;
    int max_basis = 1;
    for (int p = 0; p < model->n_parts; ++p) {
        const sem_surface *s = &model->parts[p].surface;
        int nb = (s->degree_u + 1) * (s->degree_v + 1);
        if (nb > max_basis) max_basis = nb;
    }
    index = malloc((size_t)max_basis * sizeof(int));
    phi = malloc((size_t)max_basis * sizeof(double));
    used = malloc(((size_t)mesh.n_vertices + 1) * sizeof(int));
    if (!index || !phi || !used) goto nomem;
    /* points: the vertices some triangle uses, numbered in vertex order */
    for (int v = 0; v < mesh.n_vertices; ++v) used[v] = -1;
    for (int t = 0; t < 3 * mesh.n_triangles; ++t) used[mesh.triangles[t]] = 0;
    for (int v = 0; v < mesh.n_vertices; ++v)
        if (used[v] == 0) used[v] = out->n_points++;
    size_t np = (size_t)out->n_points + 1;
    out->row_start = malloc((np + 1) * sizeof(int));
    out->row_ctrl = malloc(np * (size_t)max_basis * sizeof(int));
    out->row_w = malloc(np * (size_t)max_basis * sizeof(double));
    out->area = calloc(np, sizeof(double));
    out->x = calloc(3 * np, sizeof(double));
    out->pseudo_normal = calloc(3 * np, sizeof(double));
    out->n_triangles = mesh.n_triangles;
    out->triangles = malloc((3 * (size_t)mesh.n_triangles + 1) * sizeof(int));
    if (!out->row_start || !out->row_ctrl || !out->row_w || !out->area || !out->x || !out->pseudo_normal ||
        !out->triangles)
        goto nomem;
    out->row_start[0] = 0;
    int part = 0;
    for (int v = 0; v < mesh.n_vertices; ++v) {
        if (used[v] < 0) continue;
        while (part + 1 < mesh.n_parts && v >= mesh.part_vertex_start[part + 1]) ++part;
        const sem_surface *s = &model->parts[part].surface;
        int n = sem_surface_basis(s, mesh.uv[2 * v], mesh.uv[2 * v + 1], index, phi, NULL, NULL);
        int r = used[v], start = out->row_start[r], kept = 0;
        for (int k = 0; k < n; ++k) {
            if (phi[k] == 0) continue;
            out->row_ctrl[start + kept] = (int)part_offset[part] + index[k];
            out->row_w[start + kept] = phi[k];
            ++kept;
        }
        out->row_start[r + 1] = start + kept;
    }
    for (int t = 0; t < 3 * mesh.n_triangles; ++t) out->triangles[t] = used[mesh.triangles[t]];
    sem_collision_mesh_update(out, q, 0);
    orient_parts(out, &mesh);
    sem_collision_mesh_update(out, q, 0); /* normals of the turned triangles */
    for (int t = 0; t < out->n_triangles; ++t) {
        const int *tri = out->triangles + 3 * t;
        const double *a = out->x + 3 * (size_t)tri[0], *b = out->x + 3 * (size_t)tri[1], *c = out->x + 3 * (size_t)tri[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double area = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; ++k) out->area[tri[k]] += area / 3;
    }
    st = sem_bvh_build(&out->bvh, out->x, out->triangles, out->n_triangles, err);
    goto done;
nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collision mesh");
done:
    if (st != SEM_OK) sem_collision_mesh_free(out);
    sem_mesh_free(&mesh);
    sem_mesh_template_destroy(tmpl);
    free(index);
    free(phi);
    free(used);
    free(q);
    free(part_offset);
    return st;
}

void sem_collision_mesh_update(sem_collision_mesh *m, const double *q, int refit_tree)
{
    for (int p = 0; p < m->n_points; ++p) {
        double x[3] = {0, 0, 0};
        for (int e = m->row_start[p]; e < m->row_start[p + 1]; ++e) {
            const double *qc = q + 3 * (size_t)m->row_ctrl[e];
            for (int k = 0; k < 3; ++k) x[k] += m->row_w[e] * qc[k];
        }
        memcpy(m->x + 3 * (size_t)p, x, sizeof x);
    }
    memset(m->pseudo_normal, 0, 3 * (size_t)m->n_points * sizeof(double));
    for (int t = 0; t < m->n_triangles; ++t) {
        const int *tri = m->triangles + 3 * t;
        const double *a = m->x + 3 * (size_t)tri[0], *b = m->x + 3 * (size_t)tri[1], *c = m->x + 3 * (size_t)tri[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k) m->pseudo_normal[3 * (size_t)tri[v] + k] += n[k];
    }
    if (refit_tree) sem_bvh_refit(&m->bvh, m->x, m->triangles);
}
