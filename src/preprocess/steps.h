/*
 * steps.h - the preprocessing steps as pure functions (internal; composed by preprocess.c).
 *
 * Each step reads the model and earlier results and fills its own fields of
 * sem_discretization; nothing else is shared. Threads: OpenMP over the per-point loops,
 * with per-thread results merged in a fixed order so results are deterministic for a
 * fixed thread count.
 */
#ifndef SEM_STEPS_H
#define SEM_STEPS_H

#include "sem/preprocess.h"
#include "raycast.h"

/* sampling.c: fills n_samples, sample_part, sample_uv, sample_X, sample_area, J_hat,
 * part_ctrl_offset, n_ctrl, n_parts. Order-of-degree+1 Gauss-Lobatto points per non-empty
 * knot span in each direction; trimmed parts keep only samples inside their trims, and
 * their spans are subdivided to at least 24 points per direction so a small trimmed region
 * is never missed. */
sem_status sem_step_sample(const sem_model *model, int threads, sem_discretization *d,
                           sem_error *err);
/* The samples of each part: (*start)[i] .. (*start)[i + 1] index (*index), a stable counting
 * sort by sample_part, so each part's samples stay in sample order. Both arrays are
 * allocated here (n_parts + 1 and n_samples entries); 0 when out of memory (none left). */
int sem_samples_by_part(const sem_discretization *d, int **start, int **index);

/* object_frame.c: fills frame_axes, frame_center, frame_lo, frame_hi from the scene's
 * tessellation (principal axes of the surface, degenerate ones fixed by the normals). */
sem_status sem_step_frame(const sem_raycast_scene *scene, sem_discretization *d, sem_error *err);
/* Every part's bounding box of its boundary samples in the frame (sem_frame_coordinates):
 * 6 numbers a part, lower then upper corner (+inf then -inf for a part without samples). */
void sem_part_frame_boxes(const sem_discretization *d, double *box);
/* Size of every part (the diagonal of its boundary samples' bounding box in the frame, so it
 * does not change when the object is turned; 0 for a part without samples) into size (may be
 * NULL, n_parts entries) and the median over parts with samples into *median (may be NULL). */
sem_status sem_part_sizes(const sem_discretization *d, double *size, double *median);
/* Coordinates of X along the frame's axes, relative to its centre (world axes when the frame
 * has not been computed: a caller running the steps by hand). */
void sem_frame_coordinates(const sem_discretization *d, const double X[3], double Y[3]);

/* Points of one ray or one column of cells, before concatenation (quadrature*.c). */
typedef struct sem_ray_points {
    int n;
    double *X;      /* 3 per point */
    double *volume;
    int *part;
} sem_ray_points;

/* quadrature.c: appends one point (geometric growth; *cap is the arrays' capacity). Returns 0
 * when out of memory. */
int sem_ray_points_push(sem_ray_points *r, int *cap, const double X[3], double volume, int part);

/* A piece of a ray between two hits: inside the solid or not, and the part whose material it
 * takes (the innermost entered component's entering part). */
typedef struct sem_ray_segment {
    double t0, t1;
    int inside;
    int part;
} sem_ray_segment;

/* quadrature.c: the inside segments of one ray through the box [t_begin, t_end] (CSG union by
 * enter/leave counting, winding-number fallback and veto; see quadrature.c). *seg is
 * allocated (n_hits + 1 segments, *n_seg 0 when nothing is hit): segment i runs from hit i - 1
 * to hit i (segment 0 from t_begin, the last to t_end). When hits is not NULL, *hits gets the
 * hits (allocated, caller frees; NULL when there are none) and *n_hits their count. Returns 0
 * when out of memory. */
int sem_ray_inside_segments(const sem_raycast_scene *scene, const double origin[3],
                            const double dir[3], double t_begin, double t_end, double length,
                            sem_ray_segment **seg, int *n_seg, sem_ray_hit **hits,
                            int *n_hits);

/* hit_curvature.c: the surface near the point S(u, v) as a height field t = g(y, z) along the
 * unit direction d over the plane of the unit axes e1, e2 (d, e1, e2 orthonormal): H = {g_yy,
 * g_zz, g_yz} and *facing = |n . d|. Returns 0 where that is undefined (the direction in the
 * tangent plane, a singular parametrization). */
int sem_hit_height_hessian(const sem_surface *surface, double u, double v, const double d[3],
                           const double e1[3], const double e2[3], double H[3], double *facing);

/* How quadrature_subrays.c integrates the inside volume of the default quadrature's columns:
 * levels of refinement below 4 x 4 rays per finest cell, the roughness above which a crossing
 * is refined and not corrected, and whether the midpoint rule is corrected by the surface's
 * curvature. The defaults are what sem_preprocess uses; bench/study_volume varies them. */
typedef struct sem_subray_settings {
    int max_depth;
    double rough;
    int correct;
} sem_subray_settings;
sem_subray_settings sem_subray_default_settings(void);

/* quadrature_cells.c: the default quadrature, cells of size h in the object's frame refined near
 * small parts and thin solids (model may be NULL: no thickness), one point per cell: *columns gets one sem_ray_points per column (caller frees),
 * sets quad_spacing. */
sem_status sem_quadrature_cells(const sem_model *model, const sem_raycast_scene *scene, double h,
                                const sem_subray_settings *settings, sem_discretization *d,
                                sem_ray_points **columns, int *n_columns, long long *n_rays,
                                int threads, sem_error *err);

/* quadrature.c: fills quad_spacing, n_quad, quad_X, quad_volume, quad_part, volume (Eq. 11);
 * needs the frame. */
sem_status sem_step_quadrature(const sem_model *model, const sem_raycast_scene *scene,
                               const sem_preprocess_options *o, sem_discretization *d,
                               sem_error *err);
/* The same with the default quadrature's ray settings (NULL: the defaults); *n_rays (may be
 * NULL) gets the number of rays cast. For studies of the quadrature. */
sem_status sem_step_quadrature_with(const sem_model *model, const sem_raycast_scene *scene,
                                    const sem_preprocess_options *o,
                                    const sem_subray_settings *settings, sem_discretization *d,
                                    long long *n_rays, sem_error *err);

/* point_materials.c: rewrites quad_part, the quadrature's innermost entered part, to the
 * part of that part's component with the largest weight at the point (needs W). */
sem_status sem_step_point_materials(const sem_raycast_scene *scene, sem_discretization *d,
                                    sem_error *err);

/* weights.c: fills alpha, W, W_samples, weight_nonzero_fraction (Eq. 8-9). */
sem_status sem_step_weights(const sem_model *model, const sem_raycast_scene *scene,
                            const sem_preprocess_options *o, sem_discretization *d,
                            sem_error *err);
/* theta_i and normalised weights at arbitrary points (used for samples and queries). */
sem_status sem_blend_weights(const sem_raycast_scene *scene, int n_points, const double *X,
                             double alpha, double threshold, sem_csr *W, sem_error *err);

/* weights_cover.c: blends every part that has no weight at any quadrature point into the
 * points nearest to it (rows still sum to one); *n_covered counts such parts. */
sem_status sem_cover_unweighted_parts(sem_discretization *d, int *n_covered, sem_error *err);

/* origins.c: fills n_origins, origin_X, part_origin (Sec. 6.2, min-cost flow in GLPK). */
sem_status sem_step_origins(const sem_model *model, sem_discretization *d, sem_error *err);
/* origins.c: d's origins become these (d takes the arrays; the old ones are freed): every
 * origin rule ends here. */
void sem_set_origins(sem_discretization *d, double *origin_X, int *part_origin, int n_origins);
/* origins_cluster.c: the default rule (SEM_ORIGINS_COUPLED): fills n_origins, origin_X,
 * part_origin by merging flat groups of parts with the parts they blend with most. */
sem_status sem_step_origins_coupled(sem_discretization *d, sem_error *err);
/* origins_merge.c: merges every origin whose samples are flat (planar or collinear) into
 * its most blended neighbour, so every linear fit is determined (affine-exact). */
sem_status sem_merge_degenerate_origins(sem_discretization *d, sem_error *err);

/* origins_tie.c: merges origins so that no group of touching parts can translate against the
 * rest at no energy (Eq. 15 keeps weights constant); *n_ties counts the merges. */
sem_status sem_tie_translation_components(sem_discretization *d, int *n_ties, sem_error *err);
/* origins_tie.c: the origins joined by the union-find array merge (over origins) made one:
 * renumbered by their smallest part, each placed at its parts' area-weighted sample centroid
 * (without sample area: at one of its old positions). */
sem_status sem_merge_origins(sem_discretization *d, int *merge, sem_error *err);

/* projection.c: fills Pi (Eq. 7), hierarchical, robust to ill-conditioned fits. */
sem_status sem_step_projection(const sem_preprocess_options *o, sem_discretization *d,
                               sem_error *err);

/* operators.c: fills Gamma, Grad, Gamma_samples, M, M_eps, gamma, length_scale,
 * stiffness_nnz_percent (Eq. 12-16). */
sem_status sem_step_operators(const sem_preprocess_options *o, sem_discretization *d,
                              sem_error *err);

#endif
