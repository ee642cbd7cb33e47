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

#ifdef __cplusplus
}
#endif
#endif
