/*
 * mesh_obj.c - render meshes as Wavefront OBJ polygon files (v, vn, f v//vn), one 'g'
 * group per part, for viewers and DCC tools. Written atomically (io/atomic_file.h).
 *
 * Nine significant digits are enough for rendering (single precision round trips), and
 * keep per-frame files of an animation small; exact geometry goes to IGES or free-form OBJ.
 */
#include "sem/model.h"
#include "sem/tessellate.h"

#include <stdio.h>
#include <string.h>

#include "io/atomic_file.h"

static void group_name(const sem_model *model, int part, char *out, size_t size)
{
    const char *name = model && part < model->n_parts ? model->parts[part].name : "";
    if (name[0]) snprintf(out, size, "%s", name);
    else snprintf(out, size, "part_%d", part);
    /* a group name is one word */
    for (char *c = out; *c; ++c)
        if (*c == ' ' || *c == '\t' || *c == '\n' || *c == '\r' || *c == '#' || *c == '\\')
            *c = '_';
}

sem_status sem_mesh_write_obj(const sem_mesh *mesh, const sem_model *model, const char *path,
                              sem_error *err)
{
    if (!mesh || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_mesh_write_obj: NULL argument");
    sem_atomic_file file;
    sem_status st = sem_atomic_open(&file, path, err);
    if (st != SEM_OK) return st;
    FILE *f = file.fp;
    fprintf(f, "# sem render mesh: %d vertices, %d triangles, %d parts\n", mesh->n_vertices,
            mesh->n_triangles, mesh->n_parts);
    for (int p = 0; p < mesh->n_parts; ++p) {
        char name[80];
        group_name(model, p, name, sizeof name);
        fprintf(f, "g %s\n", name);
        for (int v = mesh->part_vertex_start[p]; v < mesh->part_vertex_start[p + 1]; ++v) {
            const double *x = mesh->positions + 3 * (size_t)v;
            fprintf(f, "v %.9g %.9g %.9g\n", x[0], x[1], x[2]);
        }
        for (int v = mesh->part_vertex_start[p]; v < mesh->part_vertex_start[p + 1]; ++v) {
            const double *n = mesh->normals + 3 * (size_t)v;
            fprintf(f, "vn %.9g %.9g %.9g\n", n[0], n[1], n[2]);
        }
        for (int t = mesh->part_triangle_start[p]; t < mesh->part_triangle_start[p + 1]; ++t) {
            const int *tri = mesh->triangles + 3 * (size_t)t;
            fprintf(f, "f %d//%d %d//%d %d//%d\n", tri[0] + 1, tri[0] + 1, tri[1] + 1, tri[1] + 1,
                    tri[2] + 1, tri[2] + 1);
        }
    }
    return sem_atomic_commit(&file, err);
}

sem_status sem_mesh_obj_write(const sem_model *model, const char *path, int resolution,
                              sem_error *err)
{
    if (!model || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_mesh_obj_write: NULL argument");
    sem_mesh mesh;
    sem_status st = sem_mesh_from_model(model, resolution, &mesh, err);
    if (st != SEM_OK) return st;
    st = sem_mesh_write_obj(&mesh, model, path, err);
    sem_mesh_free(&mesh);
    return st;
}
