/*
 * raycast_build.c - the Embree scene of a model's tessellation (raycast.h): triangles grouped
 * by part, one Embree geometry per part, then each part's orientation (part_orientation.c)
 * and the winding-number tree (winding_number.c); its destruction and accessors.
 *
 * Design
 * - One Embree triangle geometry per part, attached with geomID = part index, so a hit's
 *   geomID is the part directly. Parts whose tessellation is empty (fully trimmed away)
 *   simply have no geometry. The scene uses RTC_SCENE_FLAG_ROBUST (watertight traversal:
 *   a ray through a shared edge hits at least one of the two triangles) and
 *   RTC_BUILD_QUALITY_LOW (Morton build: a scene serves one preprocessing run, where the
 *   build costs more than the few rays per triangle gain from a better tree). Each scene
 *   owns its Embree device: no process-wide state. After the first device of a process
 *   (which starts Embree's thread pool once, ~1 ms) a new one costs ~0.05 ms, nothing
 *   beside building even the smallest scene. The all-hits query still removes a
 *   triangle reported twice, which higher build qualities (spatial splits) can do.
 */
#include "raycast_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/tessellate.h"
#include "geometry/tessellate_threads.h"
#include "util/threads.h"

static void raw_mesh_free(raw_mesh *m)
{
    free(m->vertices);
    free(m->uv);
    free(m->triangles);
    free(m->triangle_part);
    memset(m, 0, sizeof *m);
}

/* The shared tessellation (sem/tessellate.h): trimmed parts keep the triangles whose (u,v)
 * centroid is inside the trim. */
static sem_status tessellate(const sem_model *model, int resolution, int threads,
                             raw_mesh *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    sem_status st = sem_mesh_from_model_threads(model, resolution, threads, &mesh, err);
    if (st != SEM_OK) {
        sem_mesh_free(&mesh);
        return st;
    }
    out->n_vertices = mesh.n_vertices;
    out->vertices = mesh.positions;
    out->uv = mesh.uv;
    out->n_triangles = mesh.n_triangles;
    out->triangles = mesh.triangles;
    out->triangle_part = mesh.triangle_part;
    mesh.positions = NULL;
    mesh.uv = NULL;
    mesh.triangles = NULL;
    mesh.triangle_part = NULL;
    sem_mesh_free(&mesh);
    if (out->n_triangles > 0 && (!out->vertices || !out->uv || !out->triangles ||
                                 !out->triangle_part)) {
        raw_mesh_free(out);
        return sem_error_set(err, SEM_ERR_INVALID, "raycast: incomplete tessellation");
    }
    return SEM_OK;
}

static void embree_error(void *user, enum RTCError code, const char *str)
{
    (void)user;
    (void)code;
    (void)str; /* reported through rtcGetDeviceError where it matters */
}

sem_status sem_raycast_scene_build(const sem_model *model, int resolution,
                                   sem_raycast_scene **out, sem_error *err)
{
    return sem_raycast_scene_build_threads(model, resolution, 0, out, err);
}

sem_status sem_raycast_scene_build_threads(const sem_model *model, int resolution, int threads,
                                           sem_raycast_scene **out, sem_error *err)
{
    if (!out) return sem_error_set(err, SEM_ERR_INVALID, "raycast: NULL output");
    *out = NULL;
    if (!model || model->n_parts <= 0)
        return sem_error_set(err, SEM_ERR_INVALID, "raycast: model has no parts");
    if (resolution < 1)
        return sem_error_set(err, SEM_ERR_INVALID, "raycast: tessellation resolution %d < 1",
                             resolution);

    raw_mesh mesh_data, *mesh = &mesh_data;
    sem_status st = tessellate(model, resolution, threads, mesh, err);
    if (st != SEM_OK) return st;

    sem_raycast_scene *s = calloc(1, sizeof *s);
    if (!s) {
        raw_mesh_free(mesh);
        return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
    }
    int n_parts = model->n_parts;
    s->n_parts = n_parts;
    s->part_sign = malloc((size_t)n_parts * sizeof *s->part_sign);
    s->part_tri_offset = calloc((size_t)n_parts + 1, sizeof *s->part_tri_offset);
    size_t cap = mesh->n_triangles > 0 ? (size_t)mesh->n_triangles : 1;
    s->tri = malloc(cap * 9 * sizeof *s->tri);
    s->tri_normal = malloc(cap * 3 * sizeof *s->tri_normal);
    s->tri_area = malloc(cap * sizeof *s->tri_area);
    s->tri_uv = malloc(cap * 6 * sizeof *s->tri_uv);
    s->surfaces = calloc((size_t)n_parts, sizeof *s->surfaces);
    int *order = malloc(cap * sizeof *order);
    int copied = 1;
    if (s->surfaces)
        for (int p = 0; p < n_parts && copied; p++)
            if (sem_surface_copy(&s->surfaces[p], &model->parts[p].surface) != SEM_OK) {
                memset(&s->surfaces[p], 0, sizeof s->surfaces[p]);
                copied = 0;
            }
    if (!s->part_sign || !s->part_tri_offset || !s->tri || !s->tri_normal || !s->tri_area ||
        !s->tri_uv || !s->surfaces || !copied || !order) {
        free(order);
        raw_mesh_free(mesh);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
    }
    for (int i = 0; i < n_parts; i++) s->part_sign[i] = 1;

    /* group triangles by part (stable counting sort), drop degenerate ones */
    for (int t = 0; t < mesh->n_triangles; t++) {
        int p = mesh->triangle_part[t];
        if (p >= 0 && p < n_parts) s->part_tri_offset[p + 1]++;
    }
    for (int p = 0; p < n_parts; p++) s->part_tri_offset[p + 1] += s->part_tri_offset[p];
    {
        int *fill = calloc((size_t)n_parts, sizeof *fill);
        if (!fill) {
            free(order);
            raw_mesh_free(mesh);
            sem_raycast_scene_destroy(s);
            return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
        }
        for (int t = 0; t < mesh->n_triangles; t++) {
            int p = mesh->triangle_part[t];
            if (p >= 0 && p < n_parts) order[s->part_tri_offset[p] + fill[p]++] = t;
        }
        free(fill);
    }
    int total = s->part_tri_offset[n_parts];
    int *new_offset = calloc((size_t)n_parts + 1, sizeof *new_offset);
    if (!new_offset) {
        free(order);
        raw_mesh_free(mesh);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
    }
    int kept = 0;
    for (int i = 0; i < 3; i++) {
        s->lo[i] = INFINITY;
        s->hi[i] = -INFINITY;
    }
    for (int p = 0; p < n_parts; p++) {
        new_offset[p] = kept;
        for (int k = s->part_tri_offset[p]; k < s->part_tri_offset[p + 1]; k++) {
            int t = order[k];
            double *v = s->tri + 9 * (size_t)kept;
            int ok = 1;
            for (int c = 0; c < 3; c++) {
                int vi = mesh->triangles[3 * (size_t)t + c];
                if (vi < 0 || vi >= mesh->n_vertices) {
                    ok = 0;
                    break;
                }
                memcpy(v + 3 * c, mesh->vertices + 3 * (size_t)vi, 3 * sizeof *v);
                memcpy(s->tri_uv + 6 * (size_t)kept + 2 * c, mesh->uv + 2 * (size_t)vi,
                       2 * sizeof *v);
                for (int d = 0; d < 3; d++)
                    if (!isfinite(v[3 * c + d])) ok = 0;
            }
            if (!ok) continue;
            double e1[3], e2[3], n[3];
            sub3(v + 3, v, e1);
            sub3(v + 6, v, e2);
            cross3(e1, e2, n);
            double len = sqrt(dot3(n, n));
            if (!(len > 0)) continue;
            for (int d = 0; d < 3; d++) s->tri_normal[3 * (size_t)kept + d] = n[d] / len;
            s->tri_area[kept] = 0.5 * len;
            for (int c = 0; c < 3; c++)
                for (int d = 0; d < 3; d++) {
                    if (v[3 * c + d] < s->lo[d]) s->lo[d] = v[3 * c + d];
                    if (v[3 * c + d] > s->hi[d]) s->hi[d] = v[3 * c + d];
                }
            kept++;
        }
    }
    new_offset[n_parts] = kept;
    (void)total;
    double *bsamples = malloc((size_t)n_parts * COMPONENT_SAMPLES * 3 * sizeof *bsamples);
    int *n_bsamples = malloc((size_t)n_parts * sizeof *n_bsamples);
    if (!bsamples || !n_bsamples ||
        !sem_raycast_boundary_samples(mesh, n_parts, bsamples, n_bsamples)) {
        free(bsamples);
        free(n_bsamples);
        free(new_offset);
        free(order);
        raw_mesh_free(mesh);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
    }
    memcpy(s->part_tri_offset, new_offset, ((size_t)n_parts + 1) * sizeof *new_offset);
    free(new_offset);
    free(order);
    raw_mesh_free(mesh);
    s->n_triangles = kept;
    if (kept == 0) {
        free(bsamples);
        free(n_bsamples);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_INVALID,
                             "raycast: the tessellation of the model has no triangles");
    }
    double diag[3];
    sub3(s->hi, s->lo, diag);
    s->scale = sqrt(dot3(diag, diag));
    if (!(s->scale > 0)) s->scale = 1.0;
    s->merge_eps = 1e-7 * s->scale;

    /* Embree scene, on a device of its own */
    s->device = rtcNewDevice(NULL);
    if (!s->device) {
        free(bsamples);
        free(n_bsamples);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_UNSUPPORTED, "raycast: cannot create Embree device");
    }
    rtcSetDeviceErrorFunction(s->device, embree_error, NULL);
    s->scene = rtcNewScene(s->device);
    rtcSetSceneFlags(s->scene, RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    /* a scene lives for one preprocessing run and casts few rays per triangle: the fast
     * (Morton) build beats a better tree (spatial splits) by far in total */
    rtcSetSceneBuildQuality(s->scene, RTC_BUILD_QUALITY_LOW);
    for (int p = 0; p < n_parts; p++) {
        int t0 = s->part_tri_offset[p], nt = s->part_tri_offset[p + 1] - t0;
        if (nt == 0) continue;
        RTCGeometry g = rtcNewGeometry(s->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        rtcSetGeometryBuildQuality(g, RTC_BUILD_QUALITY_LOW);
        float *vb = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                            3 * sizeof(float), 3 * (size_t)nt);
        unsigned *ib = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                               3 * sizeof(unsigned), (size_t)nt);
        if (!vb || !ib) {
            rtcReleaseGeometry(g);
                free(bsamples);
            free(n_bsamples);
            sem_raycast_scene_destroy(s);
            return sem_error_set(err, SEM_ERR_NOMEM, "raycast: Embree buffer allocation failed");
        }
        for (int k = 0; k < 9 * nt; k++) vb[k] = (float)s->tri[9 * (size_t)t0 + k];
        for (int k = 0; k < 3 * nt; k++) ib[k] = (unsigned)k;
        rtcCommitGeometry(g);
        rtcAttachGeometryByID(s->scene, g, (unsigned)p);
        rtcReleaseGeometry(g);
    }
    rtcCommitScene(s->scene);
    enum RTCError e = rtcGetDeviceError(s->device);
    if (e != RTC_ERROR_NONE) {
        free(bsamples);
        free(n_bsamples);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_NUMERIC, "raycast: Embree scene build failed (error %d)",
                             (int)e);
    }

    /* orientation fix: votes read only the geometry, each part writes its own entry */
    int *sign = malloc((size_t)n_parts * sizeof *sign);
    int *component = malloc((size_t)n_parts * sizeof *component);
    if (!sign || !component || !sem_raycast_part_components(s, bsamples, n_bsamples, component)) {
        free(sign);
        free(component);
        free(bsamples);
        free(n_bsamples);
        sem_raycast_scene_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "raycast: out of memory");
    }
    free(bsamples);
    free(n_bsamples);
#pragma omp parallel for schedule(dynamic, 1) num_threads(sem_threads(threads))
    for (int p = 0; p < n_parts; p++) sign[p] = sem_raycast_estimate_part_sign(s, component, p);
    memcpy(s->part_sign, sign, (size_t)n_parts * sizeof *sign);
    free(sign);
    s->part_component = component;
    /* the winding-number tree depends on the corrected signs; the quadrature queries it for
     * every inside segment, so it is part of preparing the scene (out of memory: the
     * queries fall back to exact sums) */
    s->winding_failed = !sem_raycast_build_winding_tree(s);
    *out = s;
    return SEM_OK;
}

void sem_raycast_scene_destroy(sem_raycast_scene *scene)
{
    if (!scene) return;
    if (scene->scene) rtcReleaseScene(scene->scene);
    if (scene->device) rtcReleaseDevice(scene->device);
    free(scene->part_sign);
    free(scene->part_component);
    free(scene->part_tri_offset);
    free(scene->tri);
    free(scene->tri_normal);
    free(scene->tri_area);
    free(scene->tri_uv);
    free(scene->winding_nodes);
    free(scene->winding_order);
    free(scene->winding_sign);
    free(scene->winding_tris);
    sem_raycast_free_part_trees(scene);
    if (scene->surfaces)
        for (int p = 0; p < scene->n_parts; p++) sem_surface_free(&scene->surfaces[p]);
    free(scene->surfaces);
    free(scene);
}

void sem_raycast_bounds(const sem_raycast_scene *scene, double lo[3], double hi[3])
{
    for (int d = 0; d < 3; d++) {
        lo[d] = scene ? scene->lo[d] : 0.0;
        hi[d] = scene ? scene->hi[d] : 0.0;
    }
}

int sem_raycast_part_count(const sem_raycast_scene *scene) { return scene ? scene->n_parts : 0; }

int sem_raycast_part_component(const sem_raycast_scene *scene, int part)
{
    if (!scene || !scene->part_component || part < 0 || part >= scene->n_parts) return part;
    return scene->part_component[part];
}

int sem_raycast_triangles(const sem_raycast_scene *scene, const double **triangles,
                          const double **areas, const double **normals, const int **part_offset)
{
    if (triangles) *triangles = scene ? scene->tri : NULL;
    if (areas) *areas = scene ? scene->tri_area : NULL;
    if (normals) *normals = scene ? scene->tri_normal : NULL;
    if (part_offset) *part_offset = scene ? scene->part_tri_offset : NULL;
    return scene ? scene->n_triangles : 0;
}

const sem_surface *sem_raycast_part_surface(const sem_raycast_scene *scene, int part)
{
    if (!scene || !scene->surfaces || part < 0 || part >= scene->n_parts) return NULL;
    return &scene->surfaces[part];
}

int sem_raycast_part_sign(const sem_raycast_scene *scene, int part)
{
    if (!scene || part < 0 || part >= scene->n_parts) return 1;
    return scene->part_sign[part];
}
