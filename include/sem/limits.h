/*
 * sem/limits.h - how much any reader will read and build (docs/reliability.md).
 *
 * Why: a few kilobytes of IGES can describe 10^8 surfaces (subfigure instances that each
 * list the same definition many times, composite curves that repeat one member), and a
 * model path may name /dev/zero or a FIFO. Every reader checks these limits before it
 * allocates, and a file beyond one fails with one line naming the limit, e.g.
 *
 *     sem: big.igs: the model has more than 4000000 control points (limit
 *     SEM_MAX_MODEL_CONTROL_POINTS)
 *
 * The limits are far above every real model we know (the largest of the paper's models
 * has 3558 control points and 394 parts; the biggest file is 422 KB) and low enough that
 * no input of 1 MB or less makes `sem inspect` use more than 1 GB or 10 s (tests/
 * test_limits.c, docs/reliability.md).
 * Only regular files are read: devices, FIFOs and folders are refused before any read.
 */
#ifndef SEM_LIMITS_H
#define SEM_LIMITS_H

/* ---- files ---- */
#define SEM_MAX_MODEL_FILE_BYTES (64LL << 20)  /* IGES and OBJ model files: 64 MiB */
#define SEM_MAX_SCENE_FILE_BYTES (8LL << 20)   /* scene JSON files: 8 MiB */
#define SEM_MAX_CACHE_FILE_BYTES (4LL << 30)   /* one preprocessed (.semdisc) file: 4 GiB */

/* ---- models (every reader, after conversion to NURBS) ---- */
#define SEM_MAX_PARTS 5000                     /* surfaces in one model */
#define SEM_MAX_PART_CONTROL_POINTS 1000000    /* control points of one surface */
#define SEM_MAX_MODEL_CONTROL_POINTS 4000000   /* surfaces and trim curves of one model */
#define SEM_MAX_KNOTS 100000                   /* knots of one curve or one surface direction */
#define SEM_MAX_MODEL_SPAN_WORK 5e7             /* evaluation work of all surfaces: the sum
                                                  over knot spans of (degree_u + 1)
                                                  (degree_v + 1) G_u G_v, G = min(24,
                                                  max(8, degree + 6)) Gauss points; 38,000
                                                  bicubic spans, 84 of degree 31 */
#define SEM_MAX_TRIM_CURVES 100000             /* curves in one part's trim loops */
#define SEM_MAX_TRIM_SEGMENTS 8192             /* knot spans over one part's trim curves */

/* ---- preprocessing (estimated from the model and the settings before any step runs) ---- */
#define SEM_MAX_PREPROCESS_CONTROL_POINTS 20000 /* with the q-space operators (dense blocks
                                                  over control points): the cubes study's
                                                  largest has 3546 */
#define SEM_MAX_STRUCTURED_CONTROL_POINTS 200000 /* without them (the structured solver):
                                                  the rocket refined to 1e5 dofs has 33,000 */
#define SEM_MAX_STRUCTURED_COEFFICIENTS 15000  /* 3 n_parts m: the side of the structured
                                                  solver's dense matrix (1.8 GB at the limit);
                                                  above, the automatic rule keeps the q-space
                                                  solvers */
#define SEM_MAX_PER_PART_Q_SPACE_DOFS 12000     /* SEM_FIT_AUTO: a model the structured
                                                  solver cannot take per part is fitted per
                                                  origin above this many dofs (the q-space
                                                  matrix of such models is nearly full: NIST
                                                  CTC-04, 11,439 dofs, peaks at 3.5 GB) */
#define SEM_MAX_SHARED_FIT_PARTS 1500          /* parts of a model with shared fits (its
                                                  origins' coefficients, about a quarter of
                                                  the parts x 30, make the structured
                                                  solver's dense matrix; NIST CTC-02 has 637) */
#define SEM_MAX_BOUNDARY_ENTRIES 1e7           /* boundary samples x control points each
                                                  touches ((degree + 1)^2): J-hat's size */
#define SEM_MAX_TRIANGLES 4e6                  /* ray-casting tessellation */
#define SEM_MAX_QUADRATURE_POINTS 1e7          /* rays[0] x rays[1] x points_per_interval */

/* ---- settings ---- */
#define SEM_MAX_RAYS_PER_AXIS 4096             /* sem.rays, --rays */
#define SEM_MAX_POINTS_PER_INTERVAL 10000      /* sem.points_per_interval */
#define SEM_MAX_BEAM_SECTIONS 10000            /* primitive beam sections */
#define SEM_MAX_RESOLUTION 1000                /* sem.resolution: patches across the size */
#define SEM_MAX_FRAMES 100000000               /* frames of one run */

/* ---- IGES ---- */
#define SEM_MAX_IGES_ENTITIES 1000000          /* directory entries */
#define SEM_MAX_IGES_EXPANSION 1000000         /* entities converted, counting every
                                                  subfigure instance and shared member
                                                  again (the total subfigure expansion) */

#endif
