/*
 * shade.c - the colour seen along one ray.
 *
 * Lighting (linear RGB), chosen for legible pictures of CAD parts rather than realism:
 *   ambient   a sky/ground hemisphere term by the normal's z (surfaces facing down are
 *             not black)
 *   key       one directional light with hard shadows (rtcOccluded1)
 *   head      a weak light from the camera, so faces in shadow keep their shape
 *   highlight Blinn-Phong, white, only where the key light reaches
 * Surfaces are two-sided (NURBS patches of CAD files face either way): the interpolated
 * vertex normal is turned towards the viewer, using the triangle's geometric normal to
 * decide which side is seen. The ground is the plane z = ground_z, hit analytically;
 * it takes the object's shadow and fades into the background with the distance from the
 * framed box, so the picture has no horizon line.
 *
 * See-through surfaces (the quadrature and origin views) are composited front to back:
 * each layer adds opacity x its colour and passes the rest on, until the remaining
 * weight is below 1% or 16 layers were crossed. They do not shadow the object's other
 * geometry (the points inside them stay lit) and cast a lighter shadow on the ground.
 */
#include <math.h>

#include "render_internal.h"

#define MAX_LAYERS 16

static const float SKY[3] = {0.60f, 0.66f, 0.76f};
static const float BOUNCE[3] = {0.30f, 0.29f, 0.27f};
static const float KEY[3] = {0.88f, 0.85f, 0.80f};
static const float GROUND[3] = {0.78f, 0.78f, 0.76f};
static const float HORIZON[3] = {0.87f, 0.88f, 0.90f};
static const float ZENITH[3] = {0.56f, 0.63f, 0.74f};

static double dot(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static void background(const double d[3], float rgb[3])
{
    double f = d[2] > 0 ? fmin(1.0, 1.6 * d[2]) : 0.0;
    for (int k = 0; k < 3; ++k) rgb[k] = (float)((1 - f) * HORIZON[k] + f * ZENITH[k]);
}

static int occluded(const render_scene *s, const double p[3], const double dir[3], double t_near,
                    unsigned mask)
{
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    struct RTCRay ray;
    ray.org_x = (float)p[0];
    ray.org_y = (float)p[1];
    ray.org_z = (float)p[2];
    ray.dir_x = (float)dir[0];
    ray.dir_y = (float)dir[1];
    ray.dir_z = (float)dir[2];
    ray.tnear = (float)t_near;
    ray.tfar = INFINITY;
    ray.time = 0;
    ray.mask = mask;
    ray.id = 0;
    ray.flags = 0;
    rtcOccluded1(s->scene, &context, &ray);
    return ray.tfar < 0; /* Embree sets tfar to -inf on a hit */
}

/* Shading of a surface or sphere point with unit normal n (facing the viewer). */
static void shade_point(const render_scene *s, const render_lighting *l, const double p[3],
                        const double n[3], const double d[3], const float base[3], float rgb[3])
{
    const double *L = l->light;
    double ndl = dot(n, L);
    double visible = 0;
    if (ndl > 0) {
        double o[3] = {p[0] + l->epsilon * n[0], p[1] + l->epsilon * n[1], p[2] + l->epsilon * n[2]};
        visible = occluded(s, o, L, l->epsilon, RENDER_MASK_OPAQUE) ? 0.0 : 1.0;
    } else {
        ndl = 0;
    }
    double up = 0.5 + 0.5 * n[2];
    double head = -dot(n, d);
    if (head < 0) head = 0;
    double h[3] = {L[0] - d[0], L[1] - d[1], L[2] - d[2]};
    double hn = sqrt(dot(h, h));
    double spec = 0;
    if (visible > 0 && hn > 0) {
        double c = dot(n, h) / hn;
        if (c > 0) {
            double c2 = c * c, c4 = c2 * c2, c8 = c4 * c4, c16 = c8 * c8;
            spec = 0.22 * c16 * c16 * c16; /* c^48, without pow() per pixel */
        }
    }
    for (int k = 0; k < 3; ++k) {
        double ambient = 0.50 * ((1 - up) * BOUNCE[k] + up * SKY[k]);
        double light = ambient + KEY[k] * ndl * visible + 0.22 * head;
        rgb[k] = (float)(base[k] * light + spec);
    }
}

static void shade_ground(const render_scene *s, const render_lighting *l, const double p[3],
                         const double d[3], float rgb[3])
{
    const double *L = l->light;
    double visible = 1;
    if (L[2] > 0) {
        if (occluded(s, p, L, l->epsilon, RENDER_MASK_OPAQUE))
            visible = 0;
        else if (s->any_see_through && occluded(s, p, L, l->epsilon, RENDER_MASK_SEE_THROUGH))
            visible = 0.5;
    }
    double lz = L[2] > 0 ? L[2] : 0;
    double dx = p[0] - l->center[0], dy = p[1] - l->center[1];
    double r = sqrt(dx * dx + dy * dy);
    double f = (r - l->fade_start) / (l->fade_end - l->fade_start);
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    f = f * f * (3 - 2 * f);
    float sky[3];
    background(d, sky);
    for (int k = 0; k < 3; ++k) {
        double lit = GROUND[k] * (0.50 * SKY[k] + KEY[k] * lz * visible);
        rgb[k] = (float)((1 - f) * lit + f * sky[k]);
    }
}

static void normalize(double v[3])
{
    double n = sqrt(dot(v, v));
    if (n > 0)
        for (int k = 0; k < 3; ++k) v[k] /= n;
}

/* Colour of the hit (geometry g, primitive prim, barycentric u, v, geometric normal ng). */
static void shade_hit(const render_scene *s, const render_lighting *l, const render_geometry *g,
                      unsigned prim, float u, float v, const double ng_in[3], const double p[3],
                      const double d[3], float rgb[3])
{
    double ng[3] = {ng_in[0], ng_in[1], ng_in[2]};
    normalize(ng);
    if (dot(ng, d) > 0)
        for (int k = 0; k < 3; ++k) ng[k] = -ng[k];
    if (g->is_points) {
        const float *c = &g->points->colors[3 * (size_t)prim];
        shade_point(s, l, p, ng, d, c, rgb);
        return;
    }
    const sem_render_surface *sf = g->surface;
    const int *t = &sf->triangles[3 * (size_t)prim];
    const double w[3] = {1.0 - u - v, u, v};
    double n[3] = {0, 0, 0};
    float base[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
        const double *nv = &sf->normals[3 * (size_t)t[c]];
        const float *cv = &sf->colors[3 * (size_t)t[c]];
        for (int k = 0; k < 3; ++k) {
            n[k] += w[c] * nv[k];
            base[k] += (float)w[c] * cv[k];
        }
    }
    double len = sqrt(dot(n, n));
    if (!(len > 1e-12)) {
        for (int k = 0; k < 3; ++k) n[k] = ng[k];
    } else {
        for (int k = 0; k < 3; ++k) n[k] /= len;
        if (dot(n, ng) < 0)
            for (int k = 0; k < 3; ++k) n[k] = -n[k];
    }
    shade_point(s, l, p, n, d, base, rgb);
}

render_sample render_trace(const render_scene *s, const render_lighting *l, const double o[3],
                           const double d[3])
{
    render_sample out = {{0, 0, 0}, -1};
    double t_ground = INFINITY;
    if (l->ground && d[2] < 0 && o[2] > l->ground_z) t_ground = (l->ground_z - o[2]) / d[2];
    double through = 1.0; /* weight left for what lies behind */
    double t_near = 0.0;
    struct RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int layer = 0; layer < MAX_LAYERS; ++layer) {
        struct RTCRayHit rh;
        rh.ray.org_x = (float)o[0];
        rh.ray.org_y = (float)o[1];
        rh.ray.org_z = (float)o[2];
        rh.ray.dir_x = (float)d[0];
        rh.ray.dir_y = (float)d[1];
        rh.ray.dir_z = (float)d[2];
        rh.ray.tnear = (float)t_near;
        rh.ray.tfar = INFINITY;
        rh.ray.time = 0;
        rh.ray.mask = RENDER_MASK_OPAQUE | RENDER_MASK_SEE_THROUGH;
        rh.ray.id = 0;
        rh.ray.flags = 0;
        rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
        rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
        rtcIntersect1(s->scene, &context, &rh);
        float rgb[3];
        if (rh.hit.geomID != RTC_INVALID_GEOMETRY_ID && rh.ray.tfar < t_ground) {
            const render_geometry *g = &s->geometries[rh.hit.geomID];
            const double t = rh.ray.tfar;
            const double p[3] = {o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]};
            const double ng[3] = {rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z};
            shade_hit(s, l, g, rh.hit.primID, rh.hit.u, rh.hit.v, ng, p, d, rgb);
            if (out.id == -1 && layer == 0) out.id = (int)rh.hit.geomID;
            const double a = g->opacity;
            for (int k = 0; k < 3; ++k) out.rgb[k] += (float)(through * a * rgb[k]);
            through *= 1.0 - a;
            if (through < 0.01) return out;
            t_near = t + l->epsilon;
            continue;
        }
        if (t_ground < INFINITY) {
            const double p[3] = {o[0] + t_ground * d[0], o[1] + t_ground * d[1], l->ground_z};
            shade_ground(s, l, p, d, rgb);
            if (layer == 0) out.id = -2;
        } else {
            background(d, rgb);
        }
        for (int k = 0; k < 3; ++k) out.rgb[k] += (float)(through * rgb[k]);
        return out;
    }
    float rgb[3];
    background(d, rgb);
    for (int k = 0; k < 3; ++k) out.rgb[k] += (float)(through * rgb[k]);
    return out;
}
