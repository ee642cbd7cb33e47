/*
 * model_locator.c - closest point of a model (see geometry/model_locator.h).
 *
 * Samples: a few per knot span and direction (up to 4 intervals, fewer on parts with many
 * spans so that a part holds at most about MAX_SAMPLES), because the points this serves lie
 * on the surface and Newton from the nearest sample then lands on them; the nearest four
 * samples are tried (geometry/closest_point.c), which covers the far side of a cylinder and
 * the poles of a sphere.
 */
#include "geometry/model_locator.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/closest_point.h"
#include "sem/nurbs.h"
#include "sem/trim.h"

#define MAX_SAMPLES 4096

typedef struct part_entry {
    double box_min[3], box_max[3]; /* control-point box */
    sem_surface_sampler sampler;
    sem_trim_region *trim;         /* NULL for an untrimmed part: its domain is the rectangle */
} part_entry;

struct sem_model_locator {
    const sem_model *model;
    int n;
    part_entry *parts;
};

void sem_model_locator_destroy(sem_model_locator *loc)
{
    if (!loc) return;
    for (int i = 0; i < loc->n; ++i) {
        sem_surface_sampler_free(&loc->parts[i].sampler);
        sem_trim_region_destroy(loc->parts[i].trim);
    }
    free(loc->parts);
    free(loc);
}

static int spans(int degree, int n_ctrl, const double *knots, double t0, double t1)
{
    double breaks[512];
    int n = sem_knot_breaks(degree, n_ctrl, knots, t0, t1, breaks, 512);
    return n < 2 ? 1 : n - 1;
}

sem_status sem_model_locator_build(const sem_model *model, sem_model_locator **out, sem_error *err)
{
    *out = NULL;
    sem_model_locator *loc = calloc(1, sizeof *loc);
    if (!loc) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    loc->model = model;
    loc->parts = calloc(model->n_parts > 0 ? (size_t)model->n_parts : 1, sizeof *loc->parts);
    if (!loc->parts) {
        free(loc);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_part *part = &model->parts[i];
        const sem_surface *s = &part->surface;
        part_entry *e = &loc->parts[i];
        loc->n = i + 1;
        for (int c = 0; c < 3; ++c) e->box_min[c] = INFINITY, e->box_max[c] = -INFINITY;
        for (int k = 0; k < s->n_u * s->n_v; ++k)
            for (int c = 0; c < 3; ++c) {
                double x = s->ctrl[3 * k + c];
                if (x < e->box_min[c]) e->box_min[c] = x;
                if (x > e->box_max[c]) e->box_max[c] = x;
            }
        double cells = (double)spans(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1) *
                       spans(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1);
        int per = (int)floor(sqrt(MAX_SAMPLES / cells));
        per = per < 1 ? 1 : per > 4 ? 4 : per;
        sem_status st = sem_surface_sampler_build_dense(s, per, &e->sampler, err);
        if (st == SEM_OK && (part->has_outer || part->n_holes > 0))
            st = sem_trim_region_build(part, &e->trim, err);
        if (st != SEM_OK) {
            sem_model_locator_destroy(loc);
            return st;
        }
    }
    *out = loc;
    return SEM_OK;
}

static double box_distance(const part_entry *e, const double p[3])
{
    double d2 = 0;
    for (int c = 0; c < 3; ++c) {
        double d = p[c] < e->box_min[c] ? e->box_min[c] - p[c] : p[c] > e->box_max[c] ? p[c] - e->box_max[c] : 0;
        d2 += d * d;
    }
    return sqrt(d2);
}

typedef struct candidate {
    double box_distance;
    int part;
} candidate;

static int by_box_distance(const void *a, const void *b)
{
    const candidate *x = a, *y = b;
    if (x->box_distance != y->box_distance) return x->box_distance < y->box_distance ? -1 : 1;
    return x->part - y->part;
}

void sem_model_locator_find(const sem_model_locator *loc, const double p[3], double slack,
                            sem_model_location *out)
{
    memset(out, 0, sizeof *out);
    out->part = -1;
    out->distance = INFINITY;
    if (loc->n == 0) return;
    if (!(slack >= 0)) slack = 0;
    candidate small[64], *order = loc->n <= 64 ? small : malloc((size_t)loc->n * sizeof *order);
    if (!order) return;
    for (int i = 0; i < loc->n; ++i) order[i].box_distance = box_distance(&loc->parts[i], p), order[i].part = i;
    qsort(order, (size_t)loc->n, sizeof *order, by_box_distance);
    sem_model_location any = *out, inside = *out;
    for (int k = 0; k < loc->n; ++k) {
        /* no box can hold a closer point, nor an inside point within the slack */
        double bound = fmin(inside.distance, any.distance + slack);
        if (order[k].box_distance > bound) break;
        int i = order[k].part;
        const part_entry *e = &loc->parts[i];
        double uv[2];
        /* accept: a point on the surface (round-off of the file's numbers) */
        double d = sem_surface_closest_point(&e->sampler, p, NULL, 0, uv);
        if (!isfinite(d)) continue;
        int in = e->trim ? sem_trim_region_inside(e->trim, uv[0], uv[1]) : 1;
        sem_model_location here = {i, {uv[0], uv[1]}, {0, 0, 0}, d, in};
        if (d < any.distance) any = here;
        if (in && d < inside.distance) inside = here;
    }
    if (order != small) free(order);
    *out = inside.part >= 0 && inside.distance <= any.distance + slack ? inside : any;
    if (out->part >= 0)
        sem_surface_eval(&loc->model->parts[out->part].surface, out->uv[0], out->uv[1], out->point, NULL, NULL,
                         NULL);
}
