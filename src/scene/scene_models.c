/*
 * scene_models.c - from a parsed scene to what the library takes (see sem/scene.h): each
 * object's model (file or primitive, in metres, transformed), its pins, pin regions, part
 * materials and prescribe groups, and the colliders. Parsing and checking the JSON is
 * scene.c.
 */
#include "sem/scene.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/mesh_obj_read.h"
#include "sem/tessellate.h"
#include "sem/primitives.h"

static void apply_transform(sem_model *m, const double T[12])
{
    int identity = 1;
    static const double I[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    for (int k = 0; k < 12; ++k) identity &= T[k] == I[k];
    if (identity) return;
    for (int i = 0; i < m->n_parts; ++i) {
        sem_surface *s = &m->parts[i].surface;
        for (int c = 0; c < s->n_u * s->n_v; ++c) {
            double *x = s->ctrl + 3 * c, y[3];
            for (int r = 0; r < 3; ++r) y[r] = T[4 * r] * x[0] + T[4 * r + 1] * x[1] + T[4 * r + 2] * x[2] + T[4 * r + 3];
            memcpy(x, y, sizeof y);
        }
    }
}

double sem_unit_to_meter(const char *name, char *canonical)
{
    static const struct {
        const char *name, *iges;
        double m;
    } units[] = {{"M", "M", 1.0},          {"METER", "M", 1.0},     {"METRE", "M", 1.0},
                 {"METERS", "M", 1.0},     {"METRES", "M", 1.0},    {"MM", "MM", 1e-3},
                 {"CM", "CM", 1e-2},       {"KM", "KM", 1e3},       {"UM", "UM", 1e-6},
                 {"MICRON", "UM", 1e-6},   {"IN", "IN", 0.0254},    {"INCH", "IN", 0.0254},
                 {"INCHES", "IN", 0.0254}, {"FT", "FT", 0.3048},    {"FOOT", "FT", 0.3048},
                 {"FEET", "FT", 0.3048},   {"MI", "MI", 1609.344},  {"MILE", "MI", 1609.344},
                 {"MIL", "MIL", 2.54e-5},  {"UIN", "UIN", 2.54e-8}};
    if (!name) return 0.0;
    char up[32];
    size_t n = strlen(name);
    if (n == 0 || n >= sizeof up) return 0.0;
    for (size_t k = 0; k <= n; ++k) up[k] = (char)toupper((unsigned char)name[k]);
    for (size_t i = 0; i < sizeof units / sizeof units[0]; ++i)
        if (!strcmp(up, units[i].name)) {
            if (canonical) snprintf(canonical, 16, "%s", units[i].iges);
            return units[i].m;
        }
    return 0.0;
}

static void scale_model(sem_model *m, double f)
{
    if (f == 1.0) return;
    for (int i = 0; i < m->n_parts; ++i) {
        sem_surface *s = &m->parts[i].surface;
        for (int c = 0; c < 3 * s->n_u * s->n_v; ++c) s->ctrl[c] *= f;
    }
}

sem_status sem_scene_object_model(const sem_scene *scene, int index, sem_model **out, sem_error *err)
{
    return sem_scene_object_model_units(scene, index, out, NULL, NULL, err);
}

/* Puts "name: where<key>: " before err's message (the step that failed, told where). */
static void name_where(sem_error *err, sem_status st, const char *name, const char *where, const char *key)
{
    if (!err) return;
    char msg[sizeof err->message];
    snprintf(msg, sizeof msg, "%s", err->message);
    sem_error_set(err, st, "%s: %s%s: %s", name, where, key, msg);
}

/* The model of an object's or a collider's shape (where: "objects[0]", "colliders[1]"), in
 * metres and transformed. */
static sem_status shape_model(const sem_scene *scene, const sem_scene_object *o, const char *where,
                              sem_model **out, double *file_unit_to_meter, char *file_units, sem_error *err)
{
    *out = NULL;
    sem_status st;
    sem_model *m = NULL;
    if (o->model_path[0]) {
        st = sem_model_load(o->model_path, &m, err);
        if (st != SEM_OK) {
            /* always name the key: "scene.json: objects[0].model: dir/x.igs: cannot open: ..." */
            name_where(err, st, scene->path[0] ? scene->path : "scene", where, ".model");
            return st;
        }
    } else {
        m = sem_model_create();
        if (!m) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        const char *t = o->primitive;
        if (!strcmp(t, "box")) {
            sem_box_def d = sem_default_box_def();
            for (int k = 0; k < 3; ++k)
                if (o->primitive_size[k] > 0) d.size[k] = o->primitive_size[k];
            st = sem_primitive_box(m, &d, err);
        } else if (!strcmp(t, "beam")) {
            sem_beam_def d = sem_default_beam_def();
            if (o->primitive_sections > 0) d.sections = o->primitive_sections;
            if (o->primitive_size[0] > 0) d.length = o->primitive_size[0];
            if (o->primitive_size[1] > 0) d.width = o->primitive_size[1];
            if (o->primitive_size[2] > 0) d.height = o->primitive_size[2];
            st = sem_primitive_beam(m, &d, err);
        } else if (!strcmp(t, "sphere")) {
            sem_sphere_def d = sem_default_sphere_def();
            if (o->primitive_radius > 0) d.radius = o->primitive_radius;
            st = sem_primitive_sphere(m, &d, err);
        } else if (!strcmp(t, "cylinder")) {
            sem_cylinder_def d = sem_default_cylinder_def();
            if (o->primitive_radius > 0) d.radius = o->primitive_radius;
            if (o->primitive_height > 0) d.height = o->primitive_height;
            st = sem_primitive_cylinder(m, &d, err);
        } else {
            sem_torus_def d = sem_default_torus_def();
            if (o->primitive_radius > 0) d.major = o->primitive_radius;
            if (o->primitive_radius2 > 0) d.minor = o->primitive_radius2;
            st = sem_primitive_torus(m, &d, err);
        }
        if (st != SEM_OK) {
            sem_model_destroy(m);
            return st;
        }
    }
    /* to metres (the model's own units unless the scene says otherwise), then the transform,
     * which is in metres */
    char label[16];
    snprintf(label, sizeof label, "%s", m->units[0] ? m->units : "M");
    double f = m->unit_to_meter > 0 && isfinite(m->unit_to_meter) ? m->unit_to_meter : 1.0;
    if (!strcmp(o->units, "as_metres")) {
        f = 1.0;
    } else if (o->units[0]) {
        f = sem_unit_to_meter(o->units, label);
    }
    scale_model(m, f);
    snprintf(m->units, sizeof m->units, "M");
    m->unit_to_meter = 1.0;
    if (file_unit_to_meter) *file_unit_to_meter = f;
    if (file_units) snprintf(file_units, 16, "%s", label);
    apply_transform(m, o->transform);
    *out = m;
    return SEM_OK;
}

sem_status sem_scene_object_model_units(const sem_scene *scene, int index, sem_model **out,
                                        double *file_unit_to_meter, char *file_units,
                                        sem_error *err)
{
    char where[64];
    snprintf(where, sizeof where, "objects[%d]", index);
    return shape_model(scene, &scene->objects[index], where, out, file_unit_to_meter, file_units, err);
}

/* Cells per knot span of a collider model's tessellation: flat or gently curved obstacles
 * and terrains need few. */
#define COLLIDER_RESOLUTION 8

sem_status sem_scene_collider_def(const sem_scene *scene, int index, sem_collider_def *out,
                                  double **vertices, int **triangles, sem_error *err)
{
    const sem_scene_collider *col = &scene->colliders[index];
    const char *name = scene->path[0] ? scene->path : "scene";
    *vertices = NULL;
    *triangles = NULL;
    *out = sem_default_collider_def();
    out->friction = col->friction;
    if (col->is_plane) {
        out->type = SEM_COLLIDER_PLANE;
        memcpy(out->point, col->point, sizeof out->point);
        memcpy(out->normal, col->normal, sizeof out->normal);
        return SEM_OK;
    }
    out->type = SEM_COLLIDER_MESH;
    char where[64];
    snprintf(where, sizeof where, "colliders[%d]", index);
    const sem_scene_object *o = &col->shape;
    size_t len = strlen(o->model_path);
    int freeform = 1;
    sem_triangle_soup soup;
    memset(&soup, 0, sizeof soup);
    sem_status st;
    if (len > 4 && !strcasecmp(o->model_path + len - 4, ".obj")) {
        /* a plain triangle mesh, unless the file holds free-form surfaces */
        st = sem_obj_triangles_read(o->model_path, &soup, &freeform, err);
        if (st != SEM_OK) {
            name_where(err, st, name, where, ".model");
            return st;
        }
    }
    if (!freeform) {
        double f = 1.0;
        if (o->units[0] && strcmp(o->units, "as_metres") != 0) f = sem_unit_to_meter(o->units, NULL);
        for (int v = 0; v < soup.n_vertices; ++v) {
            double *x = soup.vertices + 3 * (size_t)v, y[3];
            for (int r = 0; r < 3; ++r)
                y[r] = o->transform[4 * r] * f * x[0] + o->transform[4 * r + 1] * f * x[1] +
                       o->transform[4 * r + 2] * f * x[2] + o->transform[4 * r + 3];
            memcpy(x, y, sizeof y);
        }
    } else {
        sem_model *m = NULL;
        if ((st = shape_model(scene, o, where, &m, NULL, NULL, err)) != SEM_OK) return st;
        sem_mesh mesh;
        memset(&mesh, 0, sizeof mesh);
        st = sem_mesh_from_model(m, COLLIDER_RESOLUTION, &mesh, err);
        sem_model_destroy(m);
        if (st != SEM_OK) {
            name_where(err, st, name, where, "");
            return st;
        }
        soup.n_vertices = mesh.n_vertices;
        soup.n_triangles = mesh.n_triangles;
        soup.vertices = mesh.positions;
        soup.triangles = mesh.triangles;
        mesh.positions = NULL;
        mesh.triangles = NULL;
        sem_mesh_free(&mesh);
        if (soup.n_triangles == 0) {
            sem_triangle_soup_free(&soup);
            return sem_error_set(err, SEM_ERR_INVALID, "%s: %s: the model has no surface to collide with", name,
                                 where);
        }
    }
    out->vertices = soup.vertices;
    out->n_vertices = soup.n_vertices;
    out->triangles = soup.triangles;
    out->n_triangles = soup.n_triangles;
    *vertices = soup.vertices;
    *triangles = soup.triangles;
    return SEM_OK;
}

/* Does parts[0..n-1] (a pin's or a prescribed group's "parts") name part i? */
static int lists_part(const int *parts, int n, int i)
{
    int listed = 0;
    for (int k = 0; k < n; ++k) listed |= parts[k] == i;
    return listed;
}

/* Is x inside box b (lower corner, upper corner), its faces included? */
static int in_box(const double x[3], const double b[6])
{
    return x[0] >= b[0] && x[1] >= b[1] && x[2] >= b[2] && x[0] <= b[3] && x[1] <= b[4] && x[2] <= b[5];
}

sem_status sem_scene_object_pins(const sem_scene_object *o, const sem_model *m, unsigned char **out,
                                 sem_error *err)
{
    size_t n = sem_model_control_points(m);
    *out = NULL;
    if (!o->has_pin_control_box && o->n_pin_parts == 0 && o->n_pin_points == 0) return SEM_OK;
    unsigned char *pin = calloc(n + 1, 1);
    if (!pin) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    size_t *off = malloc(((size_t)m->n_parts + 1) * sizeof(size_t));
    if (!off) {
        free(pin);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_model_part_offsets(m, off);
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        int whole = lists_part(o->pin_parts, o->n_pin_parts, i);
        for (int c = 0; c < s->n_u * s->n_v; ++c)
            if (whole || (o->has_pin_control_box && in_box(s->ctrl + 3 * c, o->pin_control_box)))
                pin[off[i] + (size_t)c] = 1;
    }
    for (int k = 0; k < o->n_pin_parts; ++k)
        if (o->pin_parts[k] >= m->n_parts) {
            free(off);
            free(pin);
            return sem_error_set(err, SEM_ERR_INVALID, "pin.parts: part %d does not exist (model has %d parts)",
                                 o->pin_parts[k], m->n_parts);
        }
    for (int k = 0; k < o->n_pin_points; ++k) {
        if ((size_t)o->pin_points[k] >= n) {
            free(off);
            free(pin);
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "pin.points: control point %d does not exist (model has %zu)", o->pin_points[k], n);
        }
        pin[o->pin_points[k]] = 1;
    }
    free(off);
    size_t count = 0;
    for (size_t c = 0; c < n; ++c) count += pin[c];
    if (count == 0) {
        free(pin);
        if (o->has_pin_control_box)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "pin.control_box: [[%g, %g, %g], [%g, %g, %g]] contains no control point of the "
                                 "model (after its transform)",
                                 o->pin_control_box[0], o->pin_control_box[1], o->pin_control_box[2],
                                 o->pin_control_box[3], o->pin_control_box[4], o->pin_control_box[5]);
        return sem_error_set(err, SEM_ERR_INVALID, "pin: selects no control point of the model");
    }
    *out = pin;
    return SEM_OK;
}

sem_status sem_scene_object_pin_regions(const sem_scene_object *o, sem_pin_region **out, int *n, sem_error *err)
{
    *out = NULL;
    *n = 0;
    int count = o->has_pin_box;
    for (int g = 0; g < o->n_prescribe_groups; ++g) count += o->prescribe_groups[g].has_box;
    if (count == 0) return SEM_OK;
    sem_pin_region *r = calloc((size_t)count, sizeof *r);
    if (!r) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    if (o->has_pin_box) {
        memcpy(r[*n].box, o->pin_box, sizeof r[*n].box);
        /* the object's own pin follows its single "prescribe"; with prescribe groups it stays */
        r[(*n)++].prescribe = o->n_prescribe_groups == 0 && o->prescribe.type != SEM_PRESCRIBE_NONE ? 0 : -1;
    }
    for (int g = 0; g < o->n_prescribe_groups; ++g) {
        if (!o->prescribe_groups[g].has_box) continue;
        memcpy(r[*n].box, o->prescribe_groups[g].box, sizeof r[*n].box);
        r[(*n)++].prescribe = g;
    }
    *out = r;
    return SEM_OK;
}

sem_status sem_scene_object_part_materials(const sem_scene_object *o, const sem_model *m, int **out,
                                           sem_material **materials, sem_error *err)
{
    *out = NULL;
    *materials = NULL;
    if (o->n_part_materials == 0) return SEM_OK;
    int *idx = malloc(((size_t)m->n_parts + 1) * sizeof(int));
    sem_material *mats = malloc((size_t)o->n_part_materials * sizeof(sem_material));
    if (!idx || !mats) {
        free(idx);
        free(mats);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < m->n_parts; ++i) idx[i] = -1;
    for (int k = 0; k < o->n_part_materials; ++k) {
        const sem_scene_part_material *pm = &o->part_materials[k];
        mats[k] = pm->material;
        int found = 0;
        for (int i = 0; i < m->n_parts; ++i) {
            if ((pm->part >= 0 && pm->part == i) || (pm->part < 0 && !strcmp(pm->name, m->parts[i].name))) {
                idx[i] = k;
                found = 1;
            }
        }
        if (!found) {
            free(idx);
            free(mats);
            if (pm->part >= 0)
                return sem_error_set(err, SEM_ERR_INVALID, "part_materials: part %d does not exist (model has %d parts)",
                                     pm->part, m->n_parts);
            return sem_error_set(err, SEM_ERR_INVALID, "part_materials: no part is named \"%s\"", pm->name);
        }
    }
    *out = idx;
    *materials = mats;
    return SEM_OK;
}

sem_status sem_scene_object_prescribe_groups(const sem_scene_object *o, const sem_model *m, int **out,
                                             sem_error *err)
{
    *out = NULL;
    if (o->n_prescribe_groups == 0) return SEM_OK;
    size_t n = sem_model_control_points(m);
    int *group = malloc((n + 1) * sizeof(int));
    size_t *off = malloc(((size_t)m->n_parts + 1) * sizeof(size_t));
    if (!group || !off) {
        free(group);
        free(off);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (size_t c = 0; c < n; ++c) group[c] = -1;
    sem_model_part_offsets(m, off);
    for (int g = 0; g < o->n_prescribe_groups; ++g) {
        const sem_scene_prescribe_group *gr = &o->prescribe_groups[g];
        size_t count = 0;
        for (int k = 0; k < gr->n_parts; ++k)
            if (gr->parts[k] >= m->n_parts) {
                free(group);
                free(off);
                return sem_error_set(err, SEM_ERR_INVALID, "prescribe[%d].pin.parts: part %d does not exist (model has %d parts)",
                                     g, gr->parts[k], m->n_parts);
            }
        for (int k = 0; k < gr->n_points; ++k)
            if ((size_t)gr->points[k] >= n) {
                free(group);
                free(off);
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "prescribe[%d].pin.points: control point %d does not exist (model has %zu)", g,
                                     gr->points[k], n);
            }
        for (int i = 0; i < m->n_parts; ++i) {
            const sem_surface *s = &m->parts[i].surface;
            int whole = lists_part(gr->parts, gr->n_parts, i);
            for (int c = 0; c < s->n_u * s->n_v; ++c)
                if (whole || (gr->has_control_box && in_box(s->ctrl + 3 * c, gr->control_box))) {
                    group[off[i] + (size_t)c] = g;
                    count++;
                }
        }
        for (int k = 0; k < gr->n_points; ++k) {
            group[gr->points[k]] = g;
            count++;
        }
        /* (a group whose only selection is a material box moves no control point: the box's
         * material is checked against the discretization, sem_scene_object_pin_regions) */
        if (count == 0 && !gr->has_box) {
            free(group);
            free(off);
            return sem_error_set(err, SEM_ERR_INVALID, "prescribe[%d].pin: selects no control point of the model", g);
        }
    }
    free(off);
    *out = group;
    return SEM_OK;
}
