/*
 * sem/refine.h - exact refinement of NURBS models by knot insertion (more degrees of
 * freedom, the same geometry).
 *
 * Refining by a factor K splits every non-empty knot span of a surface's domain
 * [knots[degree], knots[n]] into K spans of equal parameter length, in u and in v, by
 * knot insertion in homogeneous coordinates (Boehm's algorithm, Piegl & Tiller A5.4-A5.5).
 * The surface is the same function of (u, v) up to round-off (rational surfaces included),
 * so trims, parameter ranges and everything else in the model stay as they are; only the
 * control nets and knot vectors grow. A direction with s non-empty spans and n control
 * points gets n + (K - 1) s: a part of many spans has about K^2 times its control points,
 * a single Bezier patch of degree (p, p) goes from (p + 1)^2 to (p + K)^2. (A span so short
 * that a split point would not fall strictly inside it in double precision gets fewer
 * splits; no real model has one.)
 *
 * Uses: more degrees of freedom for the same model (scaling studies, convergence in the
 * discretization of q), and `sem refine IN OUT --factor K` (docs/refine.md).
 */
#ifndef SEM_REFINE_H
#define SEM_REFINE_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Largest refinement factor accepted (a bicubic patch refined by 64 has 4489 control points). */
#define SEM_MAX_REFINE_FACTOR 64

/* out = in with every non-empty knot span split into factor_u (in u) and factor_v (in v)
 * equal parts; out must not hold arrays (it is overwritten) and gets its own. Parameter
 * range and flags are copied. factor 1 in a direction leaves it as it is. Errors:
 * SEM_ERR_INVALID for a factor outside 1..SEM_MAX_REFINE_FACTOR or an invalid surface,
 * SEM_ERR_NOMEM. */
sem_status sem_surface_refine(const sem_surface *in, int factor_u, int factor_v,
                              sem_surface *out, sem_error *err);

/* out = in with the knots Xu (ru values, ascending, repeats allowed) inserted in u and Xv in
 * v, each strictly inside the knot vector's domain [knots[degree], knots[n]]; a knot's
 * multiplicity must stay at most the degree. The same surface (Boehm, Piegl & Tiller A5.4 in
 * homogeneous coordinates); parameter range and flags copied. */
sem_status sem_surface_insert_knots(const sem_surface *in, const double *Xu, int ru, const double *Xv, int rv,
                                    sem_surface *out, sem_error *err);

/* *out = a new model: every part's surface refined by `factor` in both directions; names,
 * trims, colours, entity numbers, units, unit_to_meter and warnings copied. factor 1 gives
 * a copy. The result is refused (SEM_ERR_INVALID, one line naming the limit) before anything
 * large is allocated when it would exceed what the readers accept (sem/limits.h:
 * SEM_MAX_PART_CONTROL_POINTS, SEM_MAX_MODEL_CONTROL_POINTS counting trim curves,
 * SEM_MAX_KNOTS, SEM_MAX_MODEL_SPAN_WORK), so every refined model can be saved and read back.
 * On error *out is NULL. */
sem_status sem_model_refine(const sem_model *in, int factor, sem_model **out, sem_error *err);

/* ---- Patches (src/geometry/split.c): the accuracy setting's cut ----
 * Every part cut into patches of at most `size` (model units) along each parameter direction
 * (of its trimmed area), the same surfaces: each cut is inserted as a knot up to the degree's
 * multiplicity, and each cell between cuts becomes a clamped NURBS patch of the refined
 * control points, keeping its part's trims; cells with no trimmed area are dropped. A part
 * that cannot be cut (an unclamped knot vector at its domain's end, trims that do not close
 * within a patch's tolerance) stays whole. Neighbouring patches hold the points of their
 * common cut twice (coincident: the simulator welds them, sem_object_def.weld). */
typedef struct sem_patches {
    sem_model *model;      /* the patches */
    sem_model *refined;    /* one part per input part, knots inserted at its cuts: what the
                              patches were cut from (the frames of a run) */
    int *part_parent;      /* per patch: its input part */
    int *ctrl_refined;     /* per control point of model: the control point of refined it is */
} sem_patches;

sem_status sem_model_patches(const sem_model *in, double size, sem_patches *out, sem_error *err);
void sem_patches_free(sem_patches *split);
/* The refined model's control points (3 each) from a state of the patches' (3 per point of
 * model); refined points no patch holds (outside every trimmed area) keep their rest place. */
void sem_patches_gather(const sem_patches *split, const double *q_split, double *q_refined);

#ifdef __cplusplus
}
#endif
#endif
