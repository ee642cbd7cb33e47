/*
 * geometry/model_locator.h - the closest point of a whole NURBS model to a point in space:
 * which part, at which (u,v), how far, and whether (u,v) lies inside the part's trims
 * (internal; `sem probe` uses it to evaluate a deformed model at the rest parameters of
 * given points, for `sem validate`).
 *
 * Build once, query many (thread-safe queries). Each part keeps its control-point box (the
 * surface lies in the convex hull of its control points, weights being positive, so the box
 * bounds the untrimmed surface), a grid of surface samples (start points for Newton,
 * geometry/closest_point.h) and its trim region (sem/trim.h). A query visits the parts in
 * order of the distance to their boxes and stops when no box can hold a closer point.
 *
 * Trimmed parts: the closest point of the untrimmed surface may lie outside the trims (the
 * plane of a face runs through its neighbours). A point inside the trims is preferred when
 * its distance exceeds the best one by at most `slack`; otherwise the closest point of any
 * part is returned with inside_trim = 0 (a point on a trim edge, where the polygonal trim
 * test may answer either way, or a point off the model).
 */
#ifndef SEM_GEOMETRY_MODEL_LOCATOR_H
#define SEM_GEOMETRY_MODEL_LOCATOR_H

#include "sem/model.h"

typedef struct sem_model_locator sem_model_locator;

typedef struct sem_model_location {
    int part;          /* -1 when the model has no part */
    double uv[2];
    double point[3];   /* the surface point at (part, uv) */
    double distance;   /* |point - query| */
    int inside_trim;   /* 1 when uv is inside the part's trimmed domain */
} sem_model_location;

/* The model must outlive the locator (its surfaces are referenced, not copied). Fails when a
 * trim loop does not close or memory runs out (message names the part). */
sem_status sem_model_locator_build(const sem_model *model, sem_model_locator **out, sem_error *err);
void sem_model_locator_destroy(sem_model_locator *locator);

/* The closest point of the model to p (see above for trims and `slack`, >= 0). */
void sem_model_locator_find(const sem_model_locator *locator, const double p[3], double slack,
                            sem_model_location *out);

#endif
