/*
 * sem/render.h - ray-traced pictures of tessellated NURBS frames (Embree), written as PNG.
 *
 * A renderer is made once per animation from a definition (picture size, camera, the box
 * the camera frames); every frame is then a list of triangle surfaces (a sem_mesh's
 * positions and normals with a colour per vertex and an opacity) and of point sets drawn as
 * small spheres (the quadrature points and deformation origins of the diagnostic views).
 * Frames are independent: several may be rendered at once with one renderer.
 *
 * The picture: smooth-shaded surfaces under a key light (with shadows), a sky/ground
 * ambient term, a head light and a small highlight; a ground plane under the box with the
 * object's shadow, fading into the background; edges antialiased by extra samples at
 * fixed sub-pixel positions. Every pixel depends only on the frame, never on threads or
 * timing, so the same input gives the same bytes.
 *
 * Colours are linear RGB in [0, 1] (the picture is encoded as sRGB).
 */
#ifndef SEM_RENDER_H
#define SEM_RENDER_H

#include "sem/preprocess.h"
#include "sem/status.h"
#include "sem/tessellate.h"
#include "sem/trim.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Orbit camera about the centre of the framed box (default), or a look-at camera. */
typedef struct sem_camera {
    double azimuth;   /* degrees about +z, from +x towards +y (default -60) */
    double elevation; /* degrees above the xy plane, in [-90, 90] (default 25) */
    double distance;  /* from the box centre; <= 0: the nearest at which the box fits (default) */
    int look_at;      /* 1: eye and target below instead of the orbit */
    double eye[3], target[3];
    double fov;       /* vertical field of view, degrees in (0, 170) (default 30) */
} sem_camera;

typedef struct sem_render_def {
    int width, height;   /* pixels, 1..16384 (default 1280 x 720) */
    sem_camera camera;
    double bounds[6];    /* x0 y0 z0 x1 y1 z1: what the camera frames (the whole animation),
                            the ground lies at z0; required (x1 >= x0, ...) */
    int ground;          /* 1: ground plane with shadows (default) */
    int antialias;       /* 1: extra samples at edges (default) */
} sem_render_def;

sem_render_def sem_default_render_def(void);

/* A triangle surface; positions/normals/triangles as in sem_mesh (tessellate.h). */
typedef struct sem_render_surface {
    int n_vertices, n_triangles;
    const double *positions; /* 3 per vertex */
    const double *normals;   /* 3 per vertex (unit; either orientation: surfaces are two-sided) */
    const int *triangles;    /* 3 per triangle */
    const float *colors;     /* 3 per vertex */
    float opacity;           /* (0, 1]; below 1 the surface is see-through */
    /* Exact trim curves (optional): a hit on triangle t counts only where its (u,v),
     * interpolated from uv, is inside triangle_trim[t] (no test where that is NULL). */
    const double *uv;        /* 2 per vertex, or NULL */
    const struct sem_trim_region *const *triangle_trim; /* n_triangles entries, or NULL */
} sem_render_surface;

/* Points drawn as spheres of one radius. */
typedef struct sem_render_points {
    int n;
    const double *positions; /* 3 per point */
    const float *colors;     /* 3 per point */
    double radius;
} sem_render_points;

typedef struct sem_render_frame {
    int n_surfaces;
    const sem_render_surface *surfaces;
    int n_point_sets;
    const sem_render_points *point_sets;
} sem_render_frame;

typedef struct sem_renderer sem_renderer;

/* Checks the definition and places the camera. */
sem_status sem_renderer_create(const sem_render_def *def, sem_renderer **out, sem_error *err);
void sem_renderer_destroy(sem_renderer *renderer);

/* Renders one frame into rgb (3 bytes per pixel, sRGB, rows from the top). threads: pixel
 * rows in parallel (0: OpenMP default, 1: this thread only). Thread-safe: several frames
 * may be rendered at once with one renderer. */
sem_status sem_render_image(const sem_renderer *renderer, const sem_render_frame *frame,
                            int threads, unsigned char *rgb, sem_error *err);

/* Exact trims for a mesh of sem_mesh_template_build_covering (tessellate.h): for each
 * triangle that crosses its part's trim curves, that part's trim region; NULL for the
 * triangles inside (a corner, an edge midpoint and the centroid all inside) and for
 * untrimmed parts, which need no test. model: the model the mesh was made from. */
typedef struct sem_render_trims sem_render_trims;
sem_status sem_render_trims_build(const sem_model *model, const sem_mesh *mesh,
                                  sem_render_trims **out, sem_error *err);
/* The table for sem_render_surface.triangle_trim (valid while trims lives). */
const struct sem_trim_region *const *sem_render_trims_table(const sem_render_trims *trims);
void sem_render_trims_destroy(sem_render_trims *trims);

/* Writes an 8-bit RGB PNG (libpng), atomically. */
sem_status sem_png_write(const char *path, int width, int height, const unsigned char *rgb,
                         sem_error *err);

/* ---- colours (palette.c) ---- */

/* Colour of part / origin / material number `index`: a palette of 10 distinct colours,
 * repeated. */
void sem_render_palette(int index, float rgb[3]);
/* The colour ramp of scalar fields, t in [0, 1]: dark blue, cyan, green, yellow, red. */
void sem_render_ramp(double t, float rgb[3]);
/* sRGB byte <-> linear value. */
float sem_srgb_to_linear(unsigned char value);
unsigned char sem_linear_to_srgb(float value);

/* ---- what the diagnostic colourings show (diagnostics.c) ---- */

/* Blending weight of `part` near each of n points: the discretization's weights at its
 * quadrature points (the weights the simulation uses), interpolated by inverse squared
 * distance from the 8 nearest quadrature points. On the surface itself Eq. 8 gives a
 * Kronecker delta (weight 1 on the point's own part), so this shows the field just
 * beneath the surface, which is what the simulation blends (paper Fig. 5). */
sem_status sem_render_part_weights(const sem_discretization *d, int part, int n,
                                   const double *X, float *weights, sem_error *err);

/* Median distance from each of n points to its nearest other point (0 for n < 2): the
 * size of dots that show a point cloud without merging. */
double sem_render_point_spacing(int n, const double *X);

/* The SEM map x(X) = sum_i w_i(X) P_i(X) Pi_i q (Eq. 6) at the quadrature points for
 * control points q (3 per control point, n_ctrl of them): x_out has 3 n_quad values.
 * Needs the discretization's W, origins and Pi (not its operators). */
sem_status sem_render_map_quadrature(const sem_discretization *d, const double *q,
                                     double *x_out, sem_error *err);
/* Where each deformation origin is for control points q: the translation t_j of the
 * parts fitted about it (Eq. 7). x_out has 3 n_origins values. */
sem_status sem_render_map_origins(const sem_discretization *d, const double *q,
                                  double *x_out, sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
