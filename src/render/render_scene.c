/*
 * render_scene.c - one frame's surfaces and point sets in an Embree scene.
 *
 * Every surface is one Embree triangle geometry and every point set one sphere-point
 * geometry, attached with geomID = its index in the frame's list (surfaces first, then point
 * sets; an empty one is left out). Vertex buffers are Embree's own (single precision,
 * as Embree traces); shading reads the frame's double-precision normals and colours
 * through the geometry table. Opaque geometry has ray mask RENDER_MASK_OPAQUE,
 * see-through surfaces RENDER_MASK_SEE_THROUGH. Medium build quality: a frame's rays are
 * many per triangle, so a better tree pays for its build.
 */
#include <math.h>
#include <stdlib.h>

#include "render_internal.h"

static sem_status embree_error(RTCDevice device, sem_error *err, const char *what)
{
    return sem_error_set(err, SEM_ERR_INVALID, "render: Embree could not build the %s (error %d)", what,
                         (int)rtcGetDeviceError(device));
}

/* Embree's RTCHitN accessors are C++ only; the layout (structure of arrays: Ng_x, Ng_y,
 * Ng_z, u, v, primID, ... each N wide) is part of its API. */
static float hit_u(const struct RTCHitN *hit, unsigned N, unsigned i) { return ((const float *)hit)[3 * N + i]; }
static float hit_v(const struct RTCHitN *hit, unsigned N, unsigned i) { return ((const float *)hit)[4 * N + i]; }
static unsigned hit_prim(const struct RTCHitN *hit, unsigned N, unsigned i)
{
    return ((const unsigned *)hit)[5 * N + i];
}

/* Drops hits outside the trim curves (see trims.c); for rays and shadow rays alike. */
static void trim_filter(const struct RTCFilterFunctionNArguments *args)
{
    const render_geometry *g = args->geometryUserPtr;
    const sem_render_surface *s = g->surface;
    for (unsigned i = 0; i < args->N; ++i) {
        if (args->valid[i] != -1) continue;
        const unsigned prim = hit_prim(args->hit, args->N, i);
        const sem_trim_region *region = s->triangle_trim[prim];
        if (!region) continue;
        const double u = hit_u(args->hit, args->N, i), v = hit_v(args->hit, args->N, i);
        const int *t = &s->triangles[3 * (size_t)prim];
        const double w[3] = {1.0 - u - v, u, v};
        double pu = 0, pv = 0;
        for (int c = 0; c < 3; ++c) {
            pu += w[c] * s->uv[2 * (size_t)t[c]];
            pv += w[c] * s->uv[2 * (size_t)t[c] + 1];
        }
        if (!sem_trim_region_inside(region, pu, pv)) args->valid[i] = 0;
    }
}

static sem_status add_surface(RTCDevice device, RTCScene scene, unsigned id,
                              const sem_render_surface *s, render_geometry *user, sem_error *err)
{
    if (s->n_triangles == 0) return SEM_OK; /* nothing to hit; its geomID stays unused */
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!g) return embree_error(device, err, "triangles");
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                       3 * sizeof(float), (size_t)s->n_vertices);
    unsigned *t = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                          3 * sizeof(unsigned), (size_t)s->n_triangles);
    if (!v || !t) {
        rtcReleaseGeometry(g);
        return embree_error(device, err, "triangle buffers");
    }
    for (size_t k = 0; k < 3 * (size_t)s->n_vertices; ++k) v[k] = (float)s->positions[k];
    for (size_t k = 0; k < 3 * (size_t)s->n_triangles; ++k) t[k] = (unsigned)s->triangles[k];
    rtcSetGeometryMask(g, s->opacity < 1.0f ? RENDER_MASK_SEE_THROUGH : RENDER_MASK_OPAQUE);
    if (s->triangle_trim && s->uv) {
        rtcSetGeometryUserData(g, user);
        rtcSetGeometryIntersectFilterFunction(g, trim_filter);
        rtcSetGeometryOccludedFilterFunction(g, trim_filter);
    }
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, id);
    rtcReleaseGeometry(g);
    return SEM_OK;
}

static sem_status add_points(RTCDevice device, RTCScene scene, unsigned id,
                             const sem_render_points *p, sem_error *err)
{
    if (p->n == 0) return SEM_OK;
    RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_SPHERE_POINT);
    if (!g) return embree_error(device, err, "points");
    float *v = rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4,
                                       4 * sizeof(float), (size_t)p->n);
    if (!v) {
        rtcReleaseGeometry(g);
        return embree_error(device, err, "point buffer");
    }
    for (size_t k = 0; k < (size_t)p->n; ++k) {
        for (int c = 0; c < 3; ++c) v[4 * k + c] = (float)p->positions[3 * k + c];
        v[4 * k + 3] = (float)p->radius;
    }
    rtcSetGeometryMask(g, RENDER_MASK_OPAQUE);
    rtcCommitGeometry(g);
    rtcAttachGeometryByID(scene, g, id);
    rtcReleaseGeometry(g);
    return SEM_OK;
}

static sem_status check_frame(const sem_render_frame *f, sem_error *err)
{
    for (int i = 0; i < f->n_surfaces; ++i) {
        const sem_render_surface *s = &f->surfaces[i];
        if (s->n_vertices < 0 || s->n_triangles < 0 ||
            (s->n_triangles > 0 && (!s->positions || !s->normals || !s->triangles || !s->colors)))
            return sem_error_set(err, SEM_ERR_INVALID, "render: surface %d has missing arrays", i);
        if (!(s->opacity > 0.0f && s->opacity <= 1.0f))
            return sem_error_set(err, SEM_ERR_INVALID, "render: surface %d: opacity %g must be in (0, 1]",
                                 i, (double)s->opacity);
        for (size_t k = 0; k < 3 * (size_t)s->n_triangles; ++k)
            if (s->triangles[k] < 0 || s->triangles[k] >= s->n_vertices)
                return sem_error_set(err, SEM_ERR_INVALID, "render: surface %d: vertex index out of range", i);
        for (size_t k = 0; k < 3 * (size_t)s->n_vertices; ++k)
            if (!isfinite(s->positions[k]))
                return sem_error_set(err, SEM_ERR_INVALID, "render: surface %d: non-finite position", i);
    }
    for (int i = 0; i < f->n_point_sets; ++i) {
        const sem_render_points *p = &f->point_sets[i];
        if (p->n < 0 || (p->n > 0 && (!p->positions || !p->colors)) || !(p->radius > 0))
            return sem_error_set(err, SEM_ERR_INVALID, "render: point set %d needs points, colours and a radius > 0", i);
        for (size_t k = 0; k < 3 * (size_t)p->n; ++k)
            if (!isfinite(p->positions[k]))
                return sem_error_set(err, SEM_ERR_INVALID, "render: point set %d: non-finite position", i);
    }
    return SEM_OK;
}

sem_status render_scene_build(RTCDevice device, const sem_render_frame *frame, render_scene *rs,
                              sem_error *err)
{
    rs->scene = NULL;
    rs->n_geometries = 0;
    rs->any_see_through = 0;
    rs->geometries = NULL;
    sem_status st = check_frame(frame, err);
    if (st != SEM_OK) return st;
    const int n = frame->n_surfaces + frame->n_point_sets;
    rs->geometries = calloc((size_t)(n > 0 ? n : 1), sizeof *rs->geometries);
    if (!rs->geometries) return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    rs->scene = rtcNewScene(device);
    if (!rs->scene) {
        render_scene_release(rs);
        return embree_error(device, err, "scene");
    }
    rtcSetSceneBuildQuality(rs->scene, RTC_BUILD_QUALITY_MEDIUM);
    for (int i = 0; i < frame->n_surfaces && st == SEM_OK; ++i) {
        const sem_render_surface *s = &frame->surfaces[i];
        render_geometry *g = &rs->geometries[rs->n_geometries++];
        g->surface = s;
        g->opacity = s->opacity;
        if (s->opacity < 1.0f) rs->any_see_through = 1;
        st = add_surface(device, rs->scene, (unsigned)i, s, g, err);
    }
    for (int i = 0; i < frame->n_point_sets && st == SEM_OK; ++i) {
        render_geometry *g = &rs->geometries[rs->n_geometries++];
        g->is_points = 1;
        g->points = &frame->point_sets[i];
        g->opacity = 1.0f;
        st = add_points(device, rs->scene, (unsigned)(frame->n_surfaces + i), g->points, err);
    }
    if (st == SEM_OK) {
        rtcCommitScene(rs->scene);
        if (rtcGetDeviceError(device) != RTC_ERROR_NONE) st = embree_error(device, err, "scene");
    }
    if (st != SEM_OK) render_scene_release(rs);
    return st;
}

void render_scene_release(render_scene *rs)
{
    if (rs->scene) rtcReleaseScene(rs->scene);
    rs->scene = NULL;
    free(rs->geometries);
    rs->geometries = NULL;
    rs->n_geometries = 0;
}
