/*
 * render_internal.h - the pieces of the renderer (internal; the API is sem/render.h).
 *
 *   camera.c        where the camera is and the ray through a point of the picture
 *   render_scene.c  one frame's surfaces and point sets in an Embree scene
 *   shade.c         the colour seen along one ray (lights, shadows, ground, see-through)
 *   render.c        the picture: samples per pixel, antialiasing, threads
 *   palette.c       part colours, the scalar ramp, sRGB
 *   png_write.c     PNG files
 */
#ifndef SEM_RENDER_INTERNAL_H
#define SEM_RENDER_INTERNAL_H

#include <embree3/rtcore.h>

#include "sem/render.h"

/* ---- camera.c ---- */

typedef struct render_camera {
    double eye[3];
    double forward[3], right[3], up[3]; /* orthonormal */
    double tan_half_width, tan_half_height;
    int width, height;
} render_camera;

/* Places the camera of def (orbit about the box centre, or look-at). */
sem_status render_camera_place(const sem_render_def *def, render_camera *camera, sem_error *err);
/* Unit direction of the ray through picture point (x, y): pixel units, (0, 0) is the top
 * left corner of the picture, pixel (i, j)'s centre is (i + 0.5, j + 0.5). */
void render_camera_ray(const render_camera *camera, double x, double y, double dir[3]);

/* ---- render_scene.c ---- */

/* Ray masks: shadow rays towards the light pass through see-through surfaces when they
 * start on the object (so points inside a see-through surface are lit). */
enum { RENDER_MASK_OPAQUE = 1, RENDER_MASK_SEE_THROUGH = 2 };

typedef struct render_geometry {
    int is_points;
    const sem_render_surface *surface; /* when !is_points */
    const sem_render_points *points;   /* when is_points */
    float opacity;
} render_geometry;

typedef struct render_scene {
    RTCScene scene;
    int n_geometries;           /* geomID = index */
    render_geometry *geometries;
    int any_see_through;
} render_scene;

sem_status render_scene_build(RTCDevice device, const sem_render_frame *frame,
                              render_scene *scene, sem_error *err);
void render_scene_release(render_scene *scene);

/* ---- shade.c ---- */

typedef struct render_lighting {
    double light[3];      /* unit direction towards the key light */
    double ground_z;      /* height of the ground plane */
    int ground;           /* 0: no ground */
    double center[3];     /* centre of the framed box (the ground fades away from it) */
    double fade_start, fade_end; /* ground fade radii about the centre */
    double epsilon;       /* offset of secondary rays, model units */
} render_lighting;

/* What a primary ray saw first: for deciding where a pixel needs more samples. */
typedef struct render_sample {
    float rgb[3];  /* linear */
    int id;        /* -1 background, -2 ground, else geometry index */
} render_sample;

/* Colour seen from origin o along unit direction d. */
render_sample render_trace(const render_scene *scene, const render_lighting *lighting,
                           const double o[3], const double d[3]);

#endif
