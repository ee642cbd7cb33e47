/*
 * sem/trim.h - trimmed-surface domains: is (u,v) inside the trimmed part?
 *
 * The loops are flattened once into polygons in (u,v) (each curve sampled finely per
 * knot span, so the polygon follows the curve to well below sampling resolution), then
 * queried with an even-odd crossing test over all loops (outer and holes together), which
 * does not care about loop orientation - CAD files mix clockwise and counter-clockwise
 * loops freely. A loop that does not close (gap above tolerance) is rejected when built.
 */
#ifndef SEM_TRIM_H
#define SEM_TRIM_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_trim_region sem_trim_region;

/* Builds the query structure of a part; for an untrimmed part the region is its domain
 * rectangle. Fails when a loop does not close (gap > tolerance relative to the domain). */
sem_status sem_trim_region_build(const sem_part *part, sem_trim_region **out, sem_error *err);
void sem_trim_region_destroy(sem_trim_region *region);
/* 1 when (u,v) is inside the trimmed domain, else 0. */
int sem_trim_region_inside(const sem_trim_region *region, double u, double v);
/* Number of polygons (loops) and access to their vertices (u,v pairs), for tessellation. */
int sem_trim_region_loop_count(const sem_trim_region *region);
const double *sem_trim_region_loop(const sem_trim_region *region, int loop, int *n_vertices);

/* Checks that every loop of the part is closed; message names the part and the gap. */
sem_status sem_part_validate_trims(const sem_part *part, sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
