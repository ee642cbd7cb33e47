/*
 * gltf.c - an animated glTF 2.0 binary (.glb) of tessellated frames (see gltf.h).
 *
 * Layout, chosen so that Blender, three.js and other viewers play the file as it is:
 *  - one node per object under a root node that turns sem's z-up into glTF's y-up and
 *    scales model units to metres;
 *  - one mesh per object with one primitive per part, each with its own material (the
 *    part's colour in the palette of sem/render.h, double-sided: CAD patches face either
 *    way). The primitives of an object share its vertex accessors and differ only in their
 *    indices, so every frame's data is stored once per object, not once per part;
 *  - the motion as morph targets: frame 0 is the base mesh, frame k > 0 is target k - 1
 *    (positions and normals as differences from frame 0), and one animation drives the
 *    target weights: at frame k's time, weight 1 on target k - 1 and 0 elsewhere, linear in
 *    between, so a player interpolates between consecutive frames. The weights output
 *    (frames x targets numbers, nearly all zero) is a sparse accessor with one non-zero per
 *    frame, so it grows linearly with the frame count, not quadratically;
 *  - extras.targetNames names the targets frame_0001, ... (Blender's shape key names).
 * Accessor min/max are computed on the float values as stored, which the validator checks.
 */
#include "gltf.h"

#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/atomic_file.h"
#include "sem/render.h"

enum {
    GL_FLOAT = 5126,
    GL_UNSIGNED_INT = 5125,
    GL_ARRAY_BUFFER = 34962,
    GL_ELEMENT_ARRAY_BUFFER = 34963
};

typedef struct writer {
    unsigned char *bin;
    size_t size, cap;
    int failed;
    cJSON *views, *accessors;
    int n_views, n_accessors;
} writer;

/* Appends bytes to the binary chunk at a 4-byte boundary; returns the offset. */
static size_t bin_add(writer *w, const void *data, size_t bytes)
{
    size_t offset = (w->size + 3) & ~(size_t)3;
    if (offset + bytes > w->cap) {
        size_t cap = w->cap ? w->cap : 1 << 16;
        while (cap < offset + bytes) cap *= 2;
        unsigned char *b = realloc(w->bin, cap);
        if (!b) {
            w->failed = 1;
            return 0;
        }
        w->bin = b;
        w->cap = cap;
    }
    memset(w->bin + w->size, 0, offset - w->size);
    if (bytes) memcpy(w->bin + offset, data, bytes);
    w->size = offset + bytes;
    return offset;
}

static int add_view(writer *w, const void *data, size_t bytes, int target)
{
    size_t offset = bin_add(w, data, bytes);
    cJSON *v = cJSON_CreateObject();
    cJSON_AddNumberToObject(v, "buffer", 0);
    cJSON_AddNumberToObject(v, "byteOffset", (double)offset);
    cJSON_AddNumberToObject(v, "byteLength", (double)bytes);
    if (target) cJSON_AddNumberToObject(v, "target", target);
    cJSON_AddItemToArray(w->views, v);
    return w->n_views++;
}

/* An accessor over a whole view; min/max of `components` floats per element when given. */
static int add_accessor(writer *w, int view, int component_type, size_t count, const char *type,
                        const float *values, int components)
{
    cJSON *a = cJSON_CreateObject();
    if (view >= 0) cJSON_AddNumberToObject(a, "bufferView", view);
    cJSON_AddNumberToObject(a, "componentType", component_type);
    cJSON_AddNumberToObject(a, "count", (double)count);
    cJSON_AddStringToObject(a, "type", type);
    if (values && count > 0) {
        double lo[4], hi[4];
        for (int c = 0; c < components; ++c) lo[c] = hi[c] = values[c];
        for (size_t k = 0; k < count; ++k)
            for (int c = 0; c < components; ++c) {
                double x = values[k * (size_t)components + (size_t)c];
                if (x < lo[c]) lo[c] = x;
                if (x > hi[c]) hi[c] = x;
            }
        cJSON_AddItemToObject(a, "min", cJSON_CreateDoubleArray(lo, components));
        cJSON_AddItemToObject(a, "max", cJSON_CreateDoubleArray(hi, components));
    }
    cJSON_AddItemToArray(w->accessors, a);
    return w->n_accessors++;
}

static int add_floats(writer *w, const float *values, size_t count, const char *type, int components,
                      int target, int with_bounds)
{
    int view = add_view(w, values, count * (size_t)components * sizeof(float), target);
    return add_accessor(w, view, GL_FLOAT, count, type, with_bounds ? values : NULL, components);
}

static cJSON *material(int colour_index, const char *name, int part)
{
    cJSON *m = cJSON_CreateObject();
    char fallback[32];
    snprintf(fallback, sizeof fallback, "part_%d", part);
    cJSON_AddStringToObject(m, "name", name && name[0] ? name : fallback);
    float rgb[3];
    sem_render_palette(colour_index, rgb);
    double colour[4] = {rgb[0], rgb[1], rgb[2], 1.0};
    cJSON *pbr = cJSON_AddObjectToObject(m, "pbrMetallicRoughness");
    cJSON_AddItemToObject(pbr, "baseColorFactor", cJSON_CreateDoubleArray(colour, 4));
    cJSON_AddNumberToObject(pbr, "metallicFactor", 0.0);
    cJSON_AddNumberToObject(pbr, "roughnessFactor", 0.6);
    cJSON_AddBoolToObject(m, "doubleSided", 1);
    return m;
}

/* One object's mesh: accessors for its vertices, targets and parts; returns the mesh. */
static cJSON *object_mesh(writer *w, const gltf_animation *a, int o, size_t vertex_offset, cJSON *materials)
{
    const gltf_object *obj = &a->objects[o];
    const sem_mesh *m = obj->mesh;
    const size_t nv = (size_t)m->n_vertices;
    const int n_targets = a->n_frames - 1;
    float *scratch = malloc(3 * nv * sizeof *scratch + 1);
    if (!scratch) {
        w->failed = 1;
        return NULL;
    }
    const float *p0 = a->positions[0] + 3 * vertex_offset, *n0 = a->normals[0] + 3 * vertex_offset;
    int position = add_floats(w, p0, nv, "VEC3", 3, GL_ARRAY_BUFFER, 1);
    int normal = add_floats(w, n0, nv, "VEC3", 3, GL_ARRAY_BUFFER, 0);
    int *target_position = malloc(((size_t)n_targets + 1) * sizeof *target_position);
    int *target_normal = malloc(((size_t)n_targets + 1) * sizeof *target_normal);
    if (!target_position || !target_normal) w->failed = 1;
    for (int t = 0; t < n_targets && !w->failed; ++t) {
        const float *p = a->positions[t + 1] + 3 * vertex_offset, *n = a->normals[t + 1] + 3 * vertex_offset;
        for (size_t k = 0; k < 3 * nv; ++k) scratch[k] = p[k] - p0[k];
        target_position[t] = add_floats(w, scratch, nv, "VEC3", 3, GL_ARRAY_BUFFER, 1);
        for (size_t k = 0; k < 3 * nv; ++k) scratch[k] = n[k] - n0[k];
        target_normal[t] = add_floats(w, scratch, nv, "VEC3", 3, GL_ARRAY_BUFFER, 0);
    }
    free(scratch);
    cJSON *mesh = cJSON_CreateObject();
    char name[64];
    snprintf(name, sizeof name, "object_%d", o);
    cJSON_AddStringToObject(mesh, "name", name);
    cJSON *primitives = cJSON_AddArrayToObject(mesh, "primitives");
    for (int p = 0; p < m->n_parts && !w->failed; ++p) {
        cJSON_AddItemToArray(materials, material(obj->first_part + p, obj->part_names[p], obj->first_part + p));
        const int t0 = m->part_triangle_start[p], t1 = m->part_triangle_start[p + 1];
        if (t1 == t0) continue; /* trimmed away entirely */
        const size_t count = 3 * (size_t)(t1 - t0);
        int view = add_view(w, &m->triangles[3 * (size_t)t0], count * sizeof(uint32_t), GL_ELEMENT_ARRAY_BUFFER);
        int indices = add_accessor(w, view, GL_UNSIGNED_INT, count, "SCALAR", NULL, 1);
        cJSON *prim = cJSON_CreateObject();
        cJSON *attributes = cJSON_AddObjectToObject(prim, "attributes");
        cJSON_AddNumberToObject(attributes, "POSITION", position);
        cJSON_AddNumberToObject(attributes, "NORMAL", normal);
        cJSON_AddNumberToObject(prim, "indices", indices);
        cJSON_AddNumberToObject(prim, "material", obj->first_part + p);
        cJSON_AddNumberToObject(prim, "mode", 4);
        if (n_targets > 0) {
            cJSON *targets = cJSON_AddArrayToObject(prim, "targets");
            for (int t = 0; t < n_targets; ++t) {
                cJSON *target = cJSON_CreateObject();
                cJSON_AddNumberToObject(target, "POSITION", target_position[t]);
                cJSON_AddNumberToObject(target, "NORMAL", target_normal[t]);
                cJSON_AddItemToArray(targets, target);
            }
        }
        cJSON_AddItemToArray(primitives, prim);
    }
    if (n_targets > 0) {
        cJSON *extras = cJSON_AddObjectToObject(mesh, "extras");
        cJSON *names = cJSON_AddArrayToObject(extras, "targetNames");
        for (int t = 0; t < n_targets; ++t) {
            char target_name[32];
            snprintf(target_name, sizeof target_name, "frame_%04d", t + 1);
            cJSON_AddItemToArray(names, cJSON_CreateString(target_name));
        }
    }
    free(target_position);
    free(target_normal);
    if (cJSON_GetArraySize(primitives) == 0) {
        cJSON_Delete(mesh);
        return NULL;
    }
    return mesh;
}

/* The animation: one sampler (times -> sparse one-hot weights), one channel per mesh. */
static cJSON *animation(writer *w, const gltf_animation *a, const int *mesh_node, int n_mesh_nodes)
{
    const int n = a->n_frames, n_targets = n - 1;
    float *times = malloc((size_t)n * sizeof *times);
    uint32_t *index = malloc((size_t)n_targets * sizeof *index);
    float *ones = malloc((size_t)n_targets * sizeof *ones);
    if (!times || !index || !ones) {
        free(times);
        free(index);
        free(ones);
        w->failed = 1;
        return NULL;
    }
    for (int f = 0; f < n; ++f) times[f] = (float)a->times[f];
    /* frame f's weights are entries f * n_targets .. f * n_targets + n_targets - 1 of the
     * output; its one non-zero is target f - 1 */
    for (int f = 1; f < n; ++f) {
        index[f - 1] = (uint32_t)((size_t)f * (size_t)n_targets + (size_t)(f - 1));
        ones[f - 1] = 1.0f;
    }
    int input = add_floats(w, times, (size_t)n, "SCALAR", 1, 0, 1);
    int index_view = add_view(w, index, (size_t)n_targets * sizeof *index, 0);
    int value_view = add_view(w, ones, (size_t)n_targets * sizeof *ones, 0);
    free(times);
    free(index);
    free(ones);
    int output = add_accessor(w, -1, GL_FLOAT, (size_t)n * (size_t)n_targets, "SCALAR", NULL, 1);
    cJSON *out_accessor = cJSON_GetArrayItem(w->accessors, output);
    cJSON *sparse = cJSON_AddObjectToObject(out_accessor, "sparse");
    cJSON_AddNumberToObject(sparse, "count", n_targets);
    cJSON *si = cJSON_AddObjectToObject(sparse, "indices");
    cJSON_AddNumberToObject(si, "bufferView", index_view);
    cJSON_AddNumberToObject(si, "componentType", GL_UNSIGNED_INT);
    cJSON *sv = cJSON_AddObjectToObject(sparse, "values");
    cJSON_AddNumberToObject(sv, "bufferView", value_view);

    cJSON *anim = cJSON_CreateObject();
    cJSON_AddStringToObject(anim, "name", "simulation");
    cJSON *samplers = cJSON_AddArrayToObject(anim, "samplers");
    cJSON *sampler = cJSON_CreateObject();
    cJSON_AddNumberToObject(sampler, "input", input);
    cJSON_AddNumberToObject(sampler, "output", output);
    cJSON_AddStringToObject(sampler, "interpolation", "LINEAR");
    cJSON_AddItemToArray(samplers, sampler);
    cJSON *channels = cJSON_AddArrayToObject(anim, "channels");
    for (int k = 0; k < n_mesh_nodes; ++k) {
        cJSON *channel = cJSON_CreateObject();
        cJSON_AddNumberToObject(channel, "sampler", 0);
        cJSON *target = cJSON_AddObjectToObject(channel, "target");
        cJSON_AddNumberToObject(target, "node", mesh_node[k]);
        cJSON_AddStringToObject(target, "path", "weights");
        cJSON_AddItemToArray(channels, channel);
    }
    return anim;
}

static sem_status check(const gltf_animation *a, sem_error *err)
{
    if (a->n_objects < 1 || a->n_frames < 1 || !a->objects || !a->times || !a->positions || !a->normals)
        return sem_error_set(err, SEM_ERR_INVALID, "glTF: nothing to write");
    for (int f = 1; f < a->n_frames; ++f)
        if (!(a->times[f] > a->times[f - 1]))
            return sem_error_set(err, SEM_ERR_INVALID, "glTF: frame times must increase");
    if ((double)a->n_frames * (double)a->n_frames > 4e9)
        return sem_error_set(err, SEM_ERR_INVALID, "glTF: %d frames is too many for one animation", a->n_frames);
    return SEM_OK;
}

static void put_u32(unsigned char *p, uint32_t v)
{
    for (int k = 0; k < 4; ++k) p[k] = (unsigned char)(v >> (8 * k));
}

sem_status gltf_write(const char *path, const gltf_animation *a, sem_error *err)
{
    sem_status st = check(a, err);
    if (st != SEM_OK) return st;
    writer w;
    memset(&w, 0, sizeof w);
    cJSON *root = cJSON_CreateObject();
    w.views = cJSON_CreateArray();
    w.accessors = cJSON_CreateArray();
    cJSON *nodes = cJSON_CreateArray(), *meshes = cJSON_CreateArray(), *materials = cJSON_CreateArray();
    int *mesh_node = malloc((size_t)a->n_objects * sizeof *mesh_node);
    if (!root || !w.views || !w.accessors || !nodes || !meshes || !materials || !mesh_node) w.failed = 1;

    cJSON *asset = cJSON_AddObjectToObject(root, "asset");
    cJSON_AddStringToObject(asset, "version", "2.0");
    cJSON_AddStringToObject(asset, "generator", a->generator ? a->generator : "sem");
    cJSON_AddNumberToObject(root, "scene", 0);
    cJSON *scenes = cJSON_AddArrayToObject(root, "scenes");
    cJSON *scene = cJSON_CreateObject();
    cJSON_AddItemToObject(scene, "nodes", cJSON_CreateIntArray((int[]){0}, 1));
    cJSON_AddItemToArray(scenes, scene);

    /* root: z-up to y-up (-90 degrees about x), model units to metres */
    cJSON *top = cJSON_CreateObject();
    cJSON_AddStringToObject(top, "name", "sem");
    const double half = sqrt(0.5);
    cJSON_AddItemToObject(top, "rotation", cJSON_CreateDoubleArray((double[]){-half, 0, 0, half}, 4));
    double s = a->meters_per_unit > 0 ? a->meters_per_unit : 1.0;
    if (s != 1.0) cJSON_AddItemToObject(top, "scale", cJSON_CreateDoubleArray((double[]){s, s, s}, 3));
    cJSON *children = cJSON_AddArrayToObject(top, "children");
    cJSON_AddItemToArray(nodes, top);

    int n_mesh_nodes = 0;
    size_t vertex_offset = 0;
    for (int o = 0; o < a->n_objects && !w.failed; ++o) {
        cJSON *node = cJSON_CreateObject();
        char name[64];
        snprintf(name, sizeof name, "object_%d", o);
        cJSON_AddStringToObject(node, "name", name);
        cJSON *mesh = object_mesh(&w, a, o, vertex_offset, materials);
        if (mesh) {
            cJSON_AddNumberToObject(node, "mesh", cJSON_GetArraySize(meshes));
            cJSON_AddItemToArray(meshes, mesh);
            mesh_node[n_mesh_nodes++] = o + 1;
        }
        cJSON_AddItemToArray(children, cJSON_CreateNumber(o + 1));
        cJSON_AddItemToArray(nodes, node);
        vertex_offset += (size_t)a->objects[o].mesh->n_vertices;
    }
    cJSON_AddItemToObject(root, "nodes", nodes);
    if (cJSON_GetArraySize(meshes) > 0)
        cJSON_AddItemToObject(root, "meshes", meshes);
    else
        cJSON_Delete(meshes);
    cJSON_AddItemToObject(root, "materials", materials);
    if (a->n_frames > 1 && n_mesh_nodes > 0 && !w.failed) {
        cJSON *anim = animation(&w, a, mesh_node, n_mesh_nodes);
        cJSON *animations = cJSON_AddArrayToObject(root, "animations");
        if (anim) cJSON_AddItemToArray(animations, anim);
    }
    free(mesh_node);
    cJSON_AddItemToObject(root, "accessors", w.accessors);
    cJSON_AddItemToObject(root, "bufferViews", w.views);
    cJSON *buffers = cJSON_AddArrayToObject(root, "buffers");
    cJSON *buffer = cJSON_CreateObject();
    size_t bin_size = (w.size + 3) & ~(size_t)3;
    cJSON_AddNumberToObject(buffer, "byteLength", (double)bin_size);
    cJSON_AddItemToArray(buffers, buffer);
    char *json = w.failed ? NULL : cJSON_PrintUnformatted(root);
    cJSON_Delete(root);
    if (!json || w.failed) {
        free(json);
        free(w.bin);
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    }
    size_t json_size = strlen(json), json_padded = (json_size + 3) & ~(size_t)3;
    size_t total = 12 + 8 + json_padded + 8 + bin_size;
    if (total > UINT32_MAX) {
        free(json);
        free(w.bin);
        return sem_error_set(err, SEM_ERR_INVALID, "%s: the animation is too large for one glb file (%zu bytes)",
                             path, total);
    }
    sem_atomic_file file;
    st = sem_atomic_open(&file, path, err);
    if (st == SEM_OK) {
        unsigned char header[20];
        memcpy(header, "glTF", 4);
        put_u32(header + 4, 2);
        put_u32(header + 8, (uint32_t)total);
        put_u32(header + 12, (uint32_t)json_padded);
        memcpy(header + 16, "JSON", 4);
        int ok = fwrite(header, 1, 20, file.fp) == 20 && fwrite(json, 1, json_size, file.fp) == json_size;
        for (size_t k = json_size; k < json_padded && ok; ++k) ok = fputc(' ', file.fp) != EOF;
        unsigned char bin_header[8];
        put_u32(bin_header, (uint32_t)bin_size);
        memcpy(bin_header + 4, "BIN\0", 4);
        if (ok) ok = fwrite(bin_header, 1, 8, file.fp) == 8 && (w.size == 0 || fwrite(w.bin, 1, w.size, file.fp) == w.size);
        for (size_t k = w.size; k < bin_size && ok; ++k) ok = fputc(0, file.fp) != EOF;
        if (!ok) {
            sem_atomic_abort(&file);
            st = sem_error_set(err, SEM_ERR_IO, "%s: write failed", path);
        } else {
            st = sem_atomic_commit(&file, err);
        }
    }
    free(json);
    free(w.bin);
    return st;
}
