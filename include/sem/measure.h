/*
 * sem/measure.h - surface area and bounding box of parts and models.
 *
 * Area is the integral of |x_u x x_v| over the (trimmed) parameter domain. Untrimmed parts
 * use Gauss-Legendre quadrature per knot span with adaptive subdivision (1e-12 relative on
 * smooth parts); trimmed parts subdivide the cells that a trim loop crosses down to a
 * fine leaf size and test Gauss points there with sem_trim_region_inside (about 1e-4
 * relative on typical trims). The bounding box is that of evaluated surface points (not of
 * the control points, which bound the surface only loosely): a dense sample, the part's
 * boundary curves, then a local search from the best samples of each coordinate extremum.
 * Only points inside the trim count.
 */
#ifndef SEM_MEASURE_H
#define SEM_MEASURE_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_part_measure_result {
    double area;
    double bbox_min[3]; /* +inf .. -inf (empty) when nothing was measured */
    double bbox_max[3];
} sem_part_measure_result;

/* Area and bbox of one part. Fails when the part's trim loops do not close (message from
 * sem_trim_region_build) or the surface is invalid. */
sem_status sem_part_measure(const sem_part *part, sem_part_measure_result *out, sem_error *err);

/* All parts (OpenMP over parts, deterministic: per-part results, then a serial sum).
 * per_part (optional) receives n_parts results; a part that fails gets NaN area and an
 * empty bbox and is left out of total; the first failing part (by index) sets err and the
 * return status, prefixed "part I (NAME): ", but every other part is still measured. */
sem_status sem_model_measure(const sem_model *model, sem_part_measure_result *per_part,
                             sem_part_measure_result *total, sem_error *err);

/* ---- Seams (src/geometry/seams.c) ----
 * Points where two parts meet at rest: each part's boundary (trim loops, or its domain's
 * border) is walked with points about 1 % of the model size apart, and a point pairs with
 * every other part whose surface (inside its trim) comes within tolerance x the model size
 * of it. Both points of a pair are kept as rows of x = J q (the parts' rational basis at
 * their (u,v)), so a deformed state is measured without evaluating any NURBS: a pair's gap
 * is how much farther apart its two points are than at rest. In a sound deformation the
 * seams of a closed body stay shut; SEM couples parts only softly (Eq. 16), so this is what
 * shows when its faces come apart. */
typedef struct sem_seams {
    int n_pairs;
    int *part;             /* 2 per pair: the two parts */
    int *row_start;        /* 2 n_pairs + 1: point 2k (part a) and 2k + 1 (part b), CSR */
    int *row_ctrl;         /* control point index in the model's q order */
    double *row_w;         /* rational basis value */
    double *rest_distance; /* per pair, at rest */
    double *length;        /* per pair: the length of part a's boundary its point stands for
                            * (the walk's spacing there; 0 at a pole) */
    double size;           /* model size used (diagonal of the boundary's bounding box) */
    double tolerance;      /* the distance below which points paired, model units */
} sem_seams;

/* Tolerance SEM_SEAM_TOLERANCE relative to the model size suits CAD files (their gaps are
 * far below it). Rest control points are the model's. */
#define SEM_SEAM_TOLERANCE 1e-3
sem_status sem_seams_build(const sem_model *model, double tolerance, sem_seams *out, sem_error *err);
void sem_seams_free(sem_seams *seams);

typedef struct sem_seam_gap {
    double gap;      /* the largest opening, model units (0 when none opened) */
    double relative; /* gap / size */
    int pair;        /* its pair, or -1 */
    int part_a, part_b;
    double X[3];     /* where (the midpoint of its two points now) */
} sem_seam_gap;

/* The largest gap of the state q (3 per control point, the model's order). */
void sem_seams_measure(const sem_seams *seams, const double *q, sem_seam_gap *out);

#ifdef __cplusplus
}
#endif
#endif
