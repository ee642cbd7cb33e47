/*
 * sem/primitives.h - exact NURBS models of simple solids, built in code.
 *
 * Each builder appends the closed surface of one solid to a model as untrimmed parts whose
 * normals (x_u x x_v) point out of the solid, so the SEM pipeline (ray sampling of the
 * interior, paper Sec. 5.1) and the tests can use them without any file. Curved shapes are
 * exact rational surfaces of revolution (Piegl & Tiller, The NURBS Book, Sec. 8.5): a
 * profile curve in the (rho, z) half-plane swept by the 9-point rational circle.
 *
 * Use: sem_box_def def = sem_default_box_def(); def.size[0] = 2; sem_primitive_box(m, &def, &err);
 */
#ifndef SEM_PRIMITIVES_H
#define SEM_PRIMITIVES_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Axis-aligned box: 6 planar Bezier patches of degree `degree` (default 3: bicubic,
 * 4 x 4 evenly spaced control points, so x(u,v) is linear in u and v). */
typedef struct sem_box_def {
    double size[3];   /* edge lengths along x, y, z (default 1 1 1) */
    double center[3]; /* default 0 0 0 */
    int degree;       /* default 3 */
} sem_box_def;

/* Cantilever box beam as in the paper's deflection study (Fig. 10, files beams/perf/bN.igs):
 * `sections` segments along x from 0 to length, each with 4 side patches (bottom z = 0,
 * top z = height, front y = 0, back y = width), plus 2 end caps (x = 0 first: the clamped
 * end, coloured red as in the paper's files, and x = length): 6 + 4 (sections - 1) parts.
 * Patches are Bezier of degree `degree` with evenly spaced control points (default 2, the
 * 3 x 3 biquadratic patches of the paper's files). */
typedef struct sem_beam_def {
    int sections;   /* default 1 */
    double length;  /* along x, default 5 */
    double width;   /* along y, default 1 */
    double height;  /* along z, default 1 */
    int degree;     /* default 2 */
} sem_beam_def;

/* Sphere: one rational biquadratic patch, 9 x 5 control net (the semicircle from the south
 * to the north pole swept about z); u = longitude, v = latitude. */
typedef struct sem_sphere_def {
    double radius;    /* default 1 */
    double center[3]; /* default 0 0 0 */
} sem_sphere_def;

/* Closed cylinder about the z axis, from center.z - height/2 to center.z + height/2: the
 * side (9 x 3 net, a straight profile elevated to degree 2) and two discs, each a rational
 * patch whose v = 0 edge collapses to the disc centre (9 x 3 net). 3 parts. */
typedef struct sem_cylinder_def {
    double radius;    /* default 1 */
    double height;    /* default 2 */
    double center[3]; /* default 0 0 0 */
} sem_cylinder_def;

/* Torus about the z axis: the minor circle swept about z; one 9 x 9 rational patch. */
typedef struct sem_torus_def {
    double major;     /* distance of the tube centre from the axis, default 1 */
    double minor;     /* tube radius, default 0.25; must be < major */
    double center[3]; /* default 0 0 0 */
} sem_torus_def;

sem_box_def sem_default_box_def(void);
sem_beam_def sem_default_beam_def(void);
sem_sphere_def sem_default_sphere_def(void);
sem_cylinder_def sem_default_cylinder_def(void);
sem_torus_def sem_default_torus_def(void);

/* Builders: append the solid's parts to model. Invalid sizes -> SEM_ERR_INVALID. */
sem_status sem_primitive_box(sem_model *model, const sem_box_def *def, sem_error *err);
sem_status sem_primitive_beam(sem_model *model, const sem_beam_def *def, sem_error *err);
sem_status sem_primitive_sphere(sem_model *model, const sem_sphere_def *def, sem_error *err);
sem_status sem_primitive_cylinder(sem_model *model, const sem_cylinder_def *def, sem_error *err);
sem_status sem_primitive_torus(sem_model *model, const sem_torus_def *def, sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
