/*
 * sem/preprocess.h - from a NURBS model to the SEM discrete operators (paper Sec. 5-7, Alg. 1).
 *
 * Pipeline (each step is a pure function in src/preprocess/, composed by sem_preprocess):
 *   sampling    boundary Gauss-Lobatto samples, J-hat, area weights S        (Sec. 5)
 *   quadrature  ray-cast volume points with CSG union along each ray         (Sec. 6.3, Eq. 11)
 *   weights     blending weights by secondary rays, normalised               (Sec. 6.1, Eq. 8-9)
 *   origins     deformation origins by min-cost network flow (GLPK)          (Sec. 6.2, Eq. 10)
 *   projection  hierarchical polynomial fit Pi                               (Sec. 6, Eq. 7)
 *   operators   Gamma, gradient rows, M, M_eps, gravity                      (Sec. 7, Eq. 12-16)
 *
 * All operators are *scalar* matrices over control points (see sem/sparse.h): the same fit
 * applies to x, y and z. q-space (3 x control points) matrices are their Kronecker product
 * with I3.
 *
 * Polynomial basis b(dX) about an origin Xbar, dX = X - Xbar (order 1: 4 terms; order 2: 10):
 *   [1, dX, dY, dZ, dX dY, dX dZ, dY dZ, dX^2, dY^2, dZ^2]
 * Part i's fitted map is x_d(X) = b(X - Xbar_i)^T (Pi_i Q)[:, d] where Q is the
 * control_points x 3 matrix of q and Pi_i the rows [i*m, (i+1)*m) of Pi.
 */
#ifndef SEM_PREPROCESS_H
#define SEM_PREPROCESS_H

#include "sem/model.h"
#include "sem/polynomial.h"
#include "sem/sparse.h"

#ifdef __cplusplus
extern "C" {
#endif

/* How the parts are grouped into deformation origins (Sec. 6.2). */
typedef enum sem_origin_rule {
    SEM_ORIGINS_COUPLED = 0, /* default: parts whose samples are (nearly) flat join the parts
                                they blend with most, all at once and ties together, until every
                                origin's samples span 3D (src/preprocess/origins_cluster.c):
                                symmetric models stay symmetric */
    SEM_ORIGINS_PAPER = 1    /* the paper's min-cost flow (Eq. 10, GLPK), then flat origins
                                merged (src/preprocess/origins.c, origins_merge.c) */
} sem_origin_rule;

/* Which parts share a polynomial (Sec. 6, Eq. 7). The paper fits one polynomial per part (its
 * translation shared by the parts of an origin). A model of many small faces (a machined part
 * read from STEP: hundreds of faces of 6 to 20 control points) then has as many coefficients
 * as control points, which no solver handles at scale: neither the structured solver (its dense
 * Schur complement is as large as the coefficient space) nor the q-space solvers (the matrix
 * over control points is nearly full). Fitting one polynomial per origin (over the samples of
 * all its parts, order by order as Eq. 7) makes the coefficient space origins x m: every part
 * of an origin moves with its origin's polynomial, so the model is coarser (stiffer) than the
 * paper's; docs/preprocessing.md "Shared fits" measures by how much. */
typedef enum sem_fit_rule {
    SEM_FIT_AUTO = 0,    /* default: per part, unless neither solver takes the per-part model:
                            the structured solver needs n_ctrl >= 2 n_parts m and
                            3 n_parts m <= SEM_MAX_STRUCTURED_COEFFICIENTS, and the q-space
                            solvers are kept to 3 n_ctrl <= SEM_MAX_PER_PART_Q_SPACE_DOFS;
                            otherwise per origin (sem_preprocess_shared_fit) */
    SEM_FIT_PARTS = 1,   /* always per part (the paper) */
    SEM_FIT_ORIGINS = 2  /* always per origin */
} sem_fit_rule;

typedef struct sem_preprocess_options {
    int order;               /* 1 (linear) or 2 (quadratic, default) */
    /* Volume quadrature (Sec. 6.3). Default: a ray grid laid in the object's own frame (the
     * principal axes of its surface), cells of `spacing` across the rays and points spaced
     * alike along them, so the quadrature turns with the object. `rays` gives the paper's
     * explicit grid instead: n1 x n2 rays along the world axis `ray_axis`. */
    double spacing;          /* cell size of the object-frame grid, model units; 0 (default):
                                automatic, from the object's size and thinnest extent */
    int rays[2];             /* explicit grid (n1, n2) across ray_axis; 0 x 0 (default): none */
    int ray_axis;            /* with rays: 0 = x, 1 = y, 2 = z; -1 (default): x */
    int points_per_interval; /* points per inside interval; 0 (default): as many as the
                                interval's length holds at the grid's spacing */
    double alpha;            /* weight cut-off distance, model units; <= 0: use sparsity */
    double sparsity;         /* target non-zero fraction T in (0,1) when alpha <= 0;
                                when both are unset (alpha 0, sparsity 0): alpha = half
                                the median part size (its samples' bbox diagonal) */
    double weight_threshold; /* weights below are dropped; default 1e-4 */
    int origin_rule;         /* sem_origin_rule; default SEM_ORIGINS_COUPLED */
    int fit_rule;            /* sem_fit_rule; default SEM_FIT_AUTO */
    double gamma;            /* error-energy stiffness; <= 0: default kappa E / L */
    double youngs_modulus;   /* for the default gamma; default 1e6 */
    int tessellation;        /* triangle grid cells per knot span per direction; default 16 */
    int threads;             /* 0: OpenMP default */
    int q_space_operators;   /* 1: also form the control-point-space operators
                                Gamma_samples, M and M_eps (the q-space solvers need them; dense
                                blocks for most models); 2: and Grad (no solver reads it: for
                                inspection and the operator tests); 0: Gamma only, which is all
                                the structured solver needs; -1 (default): 1 when the default
                                world would not use the structured solver
                                (sem_world_def_structured), else 0 */
} sem_preprocess_options;

sem_preprocess_options sem_default_preprocess_options(void);

typedef struct sem_preprocess_timings {
    double sample_s;     /* boundary sampling (Table 1's Sample) */
    double scene_s;      /* tessellation + Embree build + orientation fix + object frame (not in Table 1) */
    double quad_s;       /* ray-cast volume quadrature (Table 1's Quad) */
    double weights_s;    /* blending weights + origins (Table 1's Weights) */
    double build_pi_s;   /* projection Pi (Table 1's Build Pi) */
    double operators_s;  /* Gamma, M, M_eps (not in Table 1) */
} sem_preprocess_timings;

typedef struct sem_discretization {
    int order;        /* polynomial order, 1 or 2 */
    int n_basis;      /* m = 4 or 10 */
    int n_parts;
    int n_ctrl;       /* control points; dofs = 3 n_ctrl */
    int *part_ctrl_offset; /* n_parts + 1 */

    /* boundary samples (Sec. 5) */
    int n_samples;
    int *sample_part;      /* part of each sample */
    double *sample_uv;     /* 2 per sample */
    double *sample_X;      /* rest position, 3 per sample */
    double *sample_area;   /* area weight (diagonal of S) */
    /* the weight of the sample as a seam sample: sample_area as if the part were a single
     * knot span across each side of its parameter range the sample lies on (sample_area
     * elsewhere); a property of the part, not of its knot spans (docs/refine.md) */
    double *sample_seam;
    sem_csr J_hat;         /* n_samples x n_ctrl: x(sample) = J_hat Q */

    /* the object's frame (object_frame.c): rows of frame_axes are unit axes by decreasing
     * extent, frame_lo/hi the tessellation's bounds along them relative to frame_center */
    double frame_axes[9];
    double frame_center[3];
    double frame_lo[3], frame_hi[3];

    /* volume quadrature (Sec. 6.3) */
    double quad_spacing;   /* cell size across the rays of the grid used (geometric mean) */
    int n_quad;
    double *quad_X;        /* 3 per point */
    double *quad_volume;   /* per point */
    int *quad_part;        /* part whose material the point takes (innermost), per point */
    double volume;         /* sum of quad_volume */

    /* blending weights (Sec. 6.1) */
    double alpha;
    sem_csr W;             /* n_quad x n_parts, rows sum to 1 */
    sem_csr W_samples;     /* n_samples x n_parts: weights at the boundary samples */

    /* deformation origins (Sec. 6.2) */
    int n_origins;
    double *origin_X;      /* 3 per origin (rest) */
    int *part_origin;      /* origin of each part */
    int *part_covered;     /* per part: 1 when no quadrature point lay in its solid (too small
                              or thin for the quadrature): it has no volume of its own and is
                              blended into the points nearest it (weights_cover.c) */
    int shared_fit;        /* 1: every part of an origin has its origin's polynomial (rows of
                              Pi equal within an origin; sem_fit_rule), 0: one per part */

    /* projection (Eq. 7): n_parts * n_basis rows x n_ctrl */
    sem_csr Pi;

    /* operators (Sec. 7) */
    sem_csr Gamma;         /* n_quad x n_ctrl: x(X_p) = Gamma Q (Eq. 12) */
    sem_csr Grad;          /* 3 n_quad x n_ctrl: F_p[d][e] = (Grad[3p+e] . Q[:,d]) (Eq. 15) */
    sem_csr Gamma_samples; /* n_samples x n_ctrl: SEM map at the boundary samples */
    /* Gamma_samples, M, M_eps: formed with options.q_space_operators >= 1, Grad with 2, else
     * empty (their rows, no entries) */
    sem_csr M;             /* n_ctrl x n_ctrl, unit density: sum vol Gamma^T Gamma (Eq. 14) */
    sem_csr M_eps;         /* n_ctrl x n_ctrl: sum area (Gamma_s - J_s)^T (Gamma_s - J_s) (Eq. 16),
                              without gamma */
    double gamma;          /* error stiffness to multiply M_eps with */
    double length_scale;   /* L used for the default gamma (bbox diagonal) */

    double stiffness_nnz_percent; /* non-zeros of the q-space stiffness pattern, % */
    double weight_nonzero_fraction;
    sem_preprocess_timings timings;
    unsigned long long model_hash; /* of the model's geometry and the options */
} sem_discretization;

sem_status sem_preprocess(const sem_model *model, const sem_preprocess_options *options,
                          sem_discretization **out, sem_error *err);
void sem_discretization_destroy(sem_discretization *d);

/* Versioned binary file; loading checks the version and the model/options hash. */
sem_status sem_discretization_save(const sem_discretization *d, const char *path, sem_error *err);
sem_status sem_discretization_load(const char *path, unsigned long long expected_hash,
                                   sem_discretization **out, sem_error *err);
/* The same from bytes in memory (inspection tools, fuzzing); name is used in messages. */
sem_status sem_discretization_load_buffer(const char *name, const void *data, size_t size,
                                          unsigned long long expected_hash,
                                          sem_discretization **out, sem_error *err);
/* Whether options form the q-space operators for this model (resolves -1). */
int sem_preprocess_q_space(const sem_model *model, const sem_preprocess_options *o);
/* Whether the parts of an origin share one polynomial for this model (resolves
 * SEM_FIT_AUTO; sem_fit_rule). */
int sem_preprocess_shared_fit(const sem_model *model, const sem_preprocess_options *o);
/* Hash of a model's geometry (degrees, knots, weights, control points, trims) and options. */
unsigned long long sem_preprocess_hash(const sem_model *model, const sem_preprocess_options *o);

/* Part `part`'s polynomial coefficients C = Pi_part Q (Eq. 7): Q is n_ctrl x width
 * row-major (width 3 for control points), C is n_basis x width; then part i's map is
 * x_d(X) = sum_k b_k(X - Xbar_i) C[k][d], i.e. C[k][d] = d x_d / d X_k for k = 1..3. */
void sem_projection_coefficients(const sem_discretization *d, int part, const double *Q,
                                 int width, double *C);

#ifdef __cplusplus
}
#endif
#endif
