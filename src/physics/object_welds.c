/*
 * object_welds.c - control points that are one point (sem_object_def.weld).
 *
 * Why: a B-rep's faces share their edges, and where two faces' parametrizations agree along
 * an edge their boundary rows of control points coincide; a collapsed edge (a sphere's pole)
 * is a row of coincident control points; a closed surface's first and last rows coincide on
 * its seam. SEM moves each part's control points with its own polynomial (Eq. 7) and ties
 * parts only softly through the error energy (Eq. 16), so under load such seams open and
 * poles split, although the model says they are one point. Welding them restores what the
 * model says: each pair becomes a tie row e_a - e_b of the error matrix (mass_error.c, and
 * the structured solver's sample rows), SEM_WELD_STIFFNESS times a control point's typical
 * error weight, which holds them together to about 1e-6 of the model's size. It vanishes for
 * every motion of the body as a whole (rigid, affine), so the patch test and momentum stay.
 *
 * Which points: within SEM_WELD_TOLERANCE of the control net's size of each other,
 * transitively (geometry/weld_points.c): CAD files write the coincident points with the same
 * digits, and a looser tolerance would join a fine net's neighbouring points.
 *
 * A weld across two deformation origins' groups couples them in the structured solver's
 * sample matrix S0, which structured_solver.c allows for by decomposing such groups together
 * (blocks_of).
 */
#include <math.h>
#include <stdlib.h>

#include "geometry/weld_points.h"
#include "object.h"

/* A control point with the keys that order it: its cluster of coincident points and its
 * index. */
typedef struct weld_key {
    int cluster, ctrl;
} weld_key;

static int by_cluster(const void *x, const void *y)
{
    const weld_key *a = x, *b = y;
    if (a->cluster != b->cluster) return (a->cluster > b->cluster) - (a->cluster < b->cluster);
    return (a->ctrl > b->ctrl) - (a->ctrl < b->ctrl);
}

sem_status sem_object_find_welds(sem_object *o, sem_error *err)
{
    o->n_welds = 0;
    o->weld_ctrl = NULL;
    int n = o->n_ctrl;
    if (n < 2) return SEM_OK;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < n; ++c)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], o->q0[3 * (size_t)c + k]);
            hi[k] = fmax(hi[k], o->q0[3 * (size_t)c + k]);
        }
    double size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    int *rep = malloc((size_t)n * sizeof *rep);
    weld_key *keys = malloc((size_t)n * sizeof *keys);
    if (!rep || !keys) {
        free(rep);
        free(keys);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_status st = sem_weld_points(o->q0, n, SEM_WELD_TOLERANCE * size, rep, err);
    /* each point is tied to the lowest point of its cluster (the sort keeps every cluster
     * together, in index order) */
    for (int c = 0; st == SEM_OK && c < n; ++c) keys[c] = (weld_key){rep[c], c};
    int count = 0;
    if (st == SEM_OK) {
        qsort(keys, (size_t)n, sizeof *keys, by_cluster);
        for (int k = 1; k < n; ++k)
            count += keys[k].cluster == keys[k - 1].cluster;
    }
    if (st == SEM_OK && count > 0) {
        o->weld_ctrl = malloc(2 * (size_t)count * sizeof *o->weld_ctrl);
        if (!o->weld_ctrl) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int k = 1, first = 0; st == SEM_OK && k < n; ++k) {
            if (keys[k].cluster != keys[k - 1].cluster) {
                first = k;
                continue;
            }
            o->weld_ctrl[2 * o->n_welds] = keys[first].ctrl;
            o->weld_ctrl[2 * o->n_welds + 1] = keys[k].ctrl;
            o->n_welds++;
        }
    }
    free(rep);
    free(keys);
    return st;
}
