/*
 * render.c - pictures of frames: the renderer's life cycle and the sample loop.
 *
 * Antialiasing is adaptive and deterministic. Pass 1 traces one ray through every pixel
 * centre. Pass 2 looks at each pixel's 8 neighbours: where the first thing seen changes
 * (another geometry, the ground, the background) or the colour jumps (a part boundary, a
 * shadow edge, a silhouette against the ground), the pixel gets 8 more rays at the
 * sub-pixel positions of the usual 8x multisampling pattern, averaged with its centre.
 * The choice reads pass 1's results only and is complete (a barrier) before any pixel is
 * refined, so a pixel's value depends on the frame alone and not on which thread computed
 * what: the same frame gives the same bytes on any number of threads. Typically a few percent of the pixels are refined, so a picture costs little
 * more than one ray (plus one shadow ray) per pixel.
 *
 * The key light is placed relative to the camera (35 degrees to the side of it, 55 degrees
 * up) so that every camera position gets the same kind of light and shadow.
 *
 * Threads are the caller's (OpenMP over rows here, or over frames in `sem render`). The
 * Embree device gets one thread of its own: its task scheduler's workers otherwise spin
 * beside ours, which cost a fifth of the CPU time of a run's frames on 2 cores, while a
 * frame's tree build is a few milliseconds on one thread.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#ifdef _OPENMP
#include <omp.h>
#endif

#include "render_internal.h"

struct sem_renderer {
    sem_render_def def;
    render_camera camera;
    render_lighting lighting;
    RTCDevice device;
};

sem_render_def sem_default_render_def(void)
{
    sem_render_def d;
    memset(&d, 0, sizeof d);
    d.width = 1280;
    d.height = 720;
    d.camera.azimuth = -60;
    d.camera.elevation = 25;
    d.camera.distance = 0;
    d.camera.fov = 30;
    d.ground = 1;
    d.antialias = 1;
    return d;
}

static sem_status check_def(const sem_render_def *d, sem_error *err)
{
    if (d->width < 1 || d->height < 1 || d->width > 16384 || d->height > 16384)
        return sem_error_set(err, SEM_ERR_INVALID, "render: picture size %d x %d must be 1..16384 pixels",
                             d->width, d->height);
    for (int k = 0; k < 6; ++k)
        if (!isfinite(d->bounds[k]))
            return sem_error_set(err, SEM_ERR_INVALID, "render: the box to frame is not finite");
    for (int k = 0; k < 3; ++k)
        if (d->bounds[k] > d->bounds[k + 3])
            return sem_error_set(err, SEM_ERR_INVALID, "render: the box to frame is empty");
    const sem_camera *c = &d->camera;
    if (!isfinite(c->distance) || !isfinite(c->azimuth) || !isfinite(c->elevation))
        return sem_error_set(err, SEM_ERR_INVALID, "render: camera values must be finite");
    if (c->look_at)
        for (int k = 0; k < 3; ++k)
            if (!isfinite(c->eye[k]) || !isfinite(c->target[k]))
                return sem_error_set(err, SEM_ERR_INVALID, "render: camera eye and target must be finite");
    return SEM_OK;
}

sem_status sem_renderer_create(const sem_render_def *def, sem_renderer **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!def || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_renderer_create: NULL argument");
    sem_status st = check_def(def, err);
    if (st != SEM_OK) return st;
    sem_renderer *r = calloc(1, sizeof *r);
    if (!r) return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory");
    r->def = *def;
    if ((st = render_camera_place(def, &r->camera, err)) != SEM_OK) {
        free(r);
        return st;
    }
    const double *b = def->bounds;
    double ext[3] = {b[3] - b[0], b[4] - b[1], b[5] - b[2]};
    double diagonal = sqrt(ext[0] * ext[0] + ext[1] * ext[1] + ext[2] * ext[2]);
    if (!(diagonal > 0)) diagonal = 1.0;
    render_lighting *l = &r->lighting;
    /* the light's azimuth follows the camera's (from the centre towards the eye) */
    const double *f = r->camera.forward;
    double camera_azimuth = atan2(-f[1], -f[0]);
    if (fabs(f[2]) > 0.999999) camera_azimuth = 0;
    const double az = camera_azimuth + 35.0 * M_PI / 180.0, el = 55.0 * M_PI / 180.0;
    l->light[0] = cos(el) * cos(az);
    l->light[1] = cos(el) * sin(az);
    l->light[2] = sin(el);
    l->ground = def->ground;
    l->ground_z = b[2] - 1e-3 * diagonal;
    for (int k = 0; k < 3; ++k) l->center[k] = 0.5 * (b[k] + b[k + 3]);
    l->fade_start = 0.75 * diagonal;
    l->fade_end = 2.0 * diagonal;
    l->epsilon = 1e-4 * diagonal;
    r->device = rtcNewDevice("threads=1");
    if (!r->device) {
        free(r);
        return sem_error_set(err, SEM_ERR_INVALID, "render: cannot start Embree (error %d)",
                             (int)rtcGetDeviceError(NULL));
    }
    *out = r;
    return SEM_OK;
}

void sem_renderer_destroy(sem_renderer *r)
{
    if (!r) return;
    if (r->device) rtcReleaseDevice(r->device);
    free(r);
}

/* The 8x multisampling pattern (sixteenths of a pixel about its centre). */
static const double SUBPIXEL[8][2] = {{1, -3}, {-1, 3}, {5, 1}, {-3, -5}, {-5, 5}, {-7, -1}, {3, 7}, {7, -7}};

/* What a pixel's centre ray saw first, for comparing neighbours: 0 background, 1 ground,
 * 2 + geometry index; the top bit marks a pixel chosen for more samples. */
enum { FIRST_SEEN_REFINE = 0x8000 };

static unsigned short first_seen(int id)
{
    return (unsigned short)((id + 2) & 0x7fff);
}

/* Does the pixel differ from a neighbour (what was seen, or the colour by more than 10 of
 * 255 levels in a channel)? Reads pass 1's bytes and ids only. */
static int needs_samples(const unsigned char *rgb, const unsigned short *seen, int w, int h, int x, int y)
{
    const size_t c = (size_t)y * w + x;
    for (int dy = -1; dy <= 1; ++dy)
        for (int dx = -1; dx <= 1; ++dx) {
            int nx = x + dx, ny = y + dy;
            if ((dx == 0 && dy == 0) || nx < 0 || ny < 0 || nx >= w || ny >= h) continue;
            const size_t n = (size_t)ny * w + nx;
            if ((seen[n] & 0x7fff) != (seen[c] & 0x7fff)) return 1;
            for (int k = 0; k < 3; ++k)
                if (abs((int)rgb[3 * n + k] - (int)rgb[3 * c + k]) > 10) return 1;
        }
    return 0;
}

sem_status sem_render_image(const sem_renderer *r, const sem_render_frame *frame, int threads,
                            unsigned char *rgb, sem_error *err)
{
    if (!r || !frame || !rgb) return sem_error_set(err, SEM_ERR_INVALID, "sem_render_image: NULL argument");
    render_scene scene;
    sem_status st = render_scene_build(r->device, frame, &scene, err);
    if (st != SEM_OK) return st;
    const int w = r->def.width, h = r->def.height;
    /* small on purpose: fresh pages cost more than the arithmetic on a virtual machine, so
     * pass 1 writes the caller's picture directly and keeps only 2 bytes per pixel */
    unsigned short *seen = malloc((size_t)w * (size_t)h * sizeof *seen);
    if (!seen) {
        render_scene_release(&scene);
        return sem_error_set(err, SEM_ERR_NOMEM, "render: out of memory (%d x %d picture)", w, h);
    }
    int n_threads = threads;
#ifdef _OPENMP
    if (n_threads <= 0) n_threads = omp_get_max_threads();
#endif
    if (n_threads < 1) n_threads = 1;
    const render_camera *cam = &r->camera;
    const render_lighting *light = &r->lighting;
    const int antialias = r->def.antialias;

#pragma omp parallel num_threads(n_threads) if (n_threads > 1)
    {
        /* pass 1: one ray through every pixel centre */
#pragma omp for schedule(dynamic, 4)
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                double d[3];
                render_camera_ray(cam, x + 0.5, y + 0.5, d);
                render_sample s = render_trace(&scene, light, cam->eye, d);
                const size_t p = (size_t)y * w + x;
                for (int k = 0; k < 3; ++k) rgb[3 * p + k] = sem_linear_to_srgb(s.rgb[k]);
                seen[p] = first_seen(s.id);
            }
        if (antialias) {
            /* pass 2a: choose the pixels to refine (reads pass 1 only) */
#pragma omp for schedule(dynamic, 4)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    if (needs_samples(rgb, seen, w, h, x, y)) seen[(size_t)y * w + x] |= FIRST_SEEN_REFINE;
            /* pass 2b: 9 rays for each (the centre again, to average in linear light) */
#pragma omp for schedule(dynamic, 4)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x) {
                    const size_t p = (size_t)y * w + x;
                    if (!(seen[p] & FIRST_SEEN_REFINE)) continue;
                    float sum[3] = {0, 0, 0};
                    for (int k = 0; k <= 8; ++k) {
                        double d[3];
                        double ox = k < 8 ? SUBPIXEL[k][0] / 16.0 : 0.0, oy = k < 8 ? SUBPIXEL[k][1] / 16.0 : 0.0;
                        render_camera_ray(cam, x + 0.5 + ox, y + 0.5 + oy, d);
                        render_sample s = render_trace(&scene, light, cam->eye, d);
                        for (int j = 0; j < 3; ++j) sum[j] += s.rgb[j];
                    }
                    for (int j = 0; j < 3; ++j) rgb[3 * p + j] = sem_linear_to_srgb(sum[j] / 9.0f);
                }
        }
    }
    free(seen);
    render_scene_release(&scene);
    return SEM_OK;
}
