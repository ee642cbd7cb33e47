/*
 * quadrature.c - meshless volume quadrature by parallel rays (paper Sec. 6.3, Eq. 11, Fig. 7).
 *
 * A regular grid of o->rays[0] x o->rays[1] parallel rays along axis a = o->ray_axis goes
 * through the cell centres of the model's bounding-box cross-section; the other two axes
 * in increasing order are (b, c) (x: y,z; y: x,z; z: x,y) with rays[0] cells along b and
 * rays[1] along c. The grid spans exactly the bounding box of the tessellation (no padding
 * across the rays, so a box's volume is exact for any ray count); along the ray the
 * origin sits slightly outside the box. Each ray's inside intervals get
 * o->points_per_interval points at the midpoints of equal sub-segments, each with volume
 * (sub-segment length) x (cell area): the midpoint rule along the ray and across the grid.
 *
 * Inside intervals: ray_segments.c (CSG union by enter/leave counting, the winding-number
 * fallback and veto, the innermost part's material).
 *
 * Threads: OpenMP over rays, per-ray results concatenated in ray order (b index fastest),
 * so the output is deterministic and independent of the thread count.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "steps.h"
#include "util/threads.h"

/* Automatic spacing of the object-frame grid (see the file comment): at most the thinnest
 * extent / CELLS_THINNEST and the median part size / CELLS_PER_PART; at least what keeps the
 * grid within MAX_AUTO_POINTS points of the bounding box. */
#define CELLS_THINNEST 3
#define CELLS_PER_PART 6
#define MAX_AUTO_POINTS 60000.0
/* Points of one interval at most (a guard; a sane grid never comes near). */
#define MAX_POINTS_ALONG 100000

/* The paper's points of one ray (explicit grid): adjacent inside segments merged into
 * intervals, each split into equal sub-segments with a point at each midpoint (a fixed count
 * per interval, or as many as the interval holds at h_along). Returns 0 on out of memory. */
static int quadrature_ray(const sem_raycast_scene *scene, const double origin[3],
                          const double dir[3], double t_begin, double t_end, double length,
                          int points_per_interval, double h_along, double cell_area,
                          sem_ray_points *result)
{
    sem_ray_segment *seg;
    int n_seg;
    if (!sem_ray_inside_segments(scene, origin, dir, t_begin, t_end, length, &seg, &n_seg, NULL,
                                 NULL))
        return 0;
    int ok = 1, cap = 0, i = 0;
    while (i < n_seg && ok) {
        if (!seg[i].inside) {
            i++;
            continue;
        }
        int j = i;
        while (j + 1 < n_seg && seg[j + 1].inside) j++;
        double a = seg[i].t0, b = seg[j].t1;
        if (b > a) {
            int count = points_per_interval;
            if (count <= 0) { /* as many as the interval holds at the grid's spacing */
                double c = floor((b - a) / h_along + 0.5);
                count = c < 1 ? 1 : (c > MAX_POINTS_ALONG ? MAX_POINTS_ALONG : (int)c);
            }
            double h = (b - a) / count;
            int s = i;
            for (int k = 0; k < count; k++) {
                double t = a + (k + 0.5) * h, X[3];
                while (s < j && seg[s].t1 <= t) s++;
                for (int d = 0; d < 3; d++) X[d] = origin[d] + t * dir[d];
                if (!sem_ray_points_push(result, &cap, X, h * cell_area, seg[s].part)) {
                    ok = 0;
                    break;
                }
            }
        }
        i = j + 1;
    }
    free(seg);
    return ok;
}

/* The ray grid: rays along axis[0] from (lo[0] - pad) through the cell centres of the
 * n1 x n2 grid spanning [lo[1], hi[1]] x [lo[2], hi[2]] (coordinates along axis[k] relative to
 * origin). */
typedef struct ray_grid {
    double origin[3];
    double axis[3][3];
    double lo[3], hi[3];
    int n1, n2;
    int points_per_interval; /* > 0: fixed count per interval */
    double h_along;          /* else: point spacing along the rays */
    double cell_size;        /* > 0: the object-frame grid of cells (quadrature_cells.c) */
} ray_grid;

static int cells(double extent, double h)
{
    double n = ceil(extent / h * (1.0 - 1e-6)); /* an extent of exactly k cells (to rounding) is k */
    return n < 1 ? 1 : (n > 1e6 ? 1000000 : (int)n);
}

/* The grid of the options: the paper's explicit world-axis grid, or the object's frame. */
static sem_status make_grid(const sem_raycast_scene *scene, const sem_preprocess_options *o,
                            const sem_discretization *d, ray_grid *g, sem_error *err)
{
    memset(g, 0, sizeof *g);
    g->points_per_interval = o->points_per_interval;
    if (o->rays[0] > 0 || o->rays[1] > 0) {
        double lo[3], hi[3];
        sem_raycast_bounds(scene, lo, hi);
        int a = o->ray_axis < 0 ? 0 : o->ray_axis;
        int b = a == 0 ? 1 : 0;
        int c = a == 2 ? 1 : 2;
        int idx[3] = {a, b, c};
        for (int k = 0; k < 3; ++k) {
            g->axis[k][idx[k]] = 1.0;
            g->lo[k] = lo[idx[k]];
            g->hi[k] = hi[idx[k]];
        }
        g->n1 = o->rays[0];
        g->n2 = o->rays[1];
        g->h_along = 0.5 * ((g->hi[1] - g->lo[1]) / g->n1 + (g->hi[2] - g->lo[2]) / g->n2);
    } else {
        memcpy(g->origin, d->frame_center, sizeof g->origin);
        for (int k = 0; k < 3; ++k) {
            memcpy(g->axis[k], d->frame_axes + 3 * k, sizeof g->axis[k]);
            g->lo[k] = d->frame_lo[k];
            g->hi[k] = d->frame_hi[k];
        }
        double e0 = g->hi[0] - g->lo[0], e1 = g->hi[1] - g->lo[1], e2 = g->hi[2] - g->lo[2];
        double h = o->spacing;
        if (!(h > 0)) {
            double median = 0.0;
            if (sem_part_sizes(d, NULL, &median) != SEM_OK)
                return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
            h = e2 / CELLS_THINNEST;
            if (median > 0) h = fmin(h, median / CELLS_PER_PART);
            h = fmax(h, cbrt(e0 * e1 * e2 / MAX_AUTO_POINTS));
        }
        if (!(h > 0) || !isfinite(h))
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "quadrature: the model's extent is flat or empty "
                                 "(%g x %g x %g): no volume to sample",
                                 e0, g->hi[1] - g->lo[1], e2);
        g->n1 = cells(g->hi[1] - g->lo[1], h);
        g->n2 = cells(e2, h);
        g->h_along = e0 / cells(e0, h);
        /* with a fixed count per interval: the paper's points along the rays of this grid */
        if (o->points_per_interval == 0) g->cell_size = h;
        if ((long long)g->n1 * g->n2 > 100000000LL)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "quadrature: spacing %g gives %d x %d rays (more than 1e8)", h,
                                 g->n1, g->n2);
    }
    return SEM_OK;
}

sem_status sem_step_quadrature(const sem_model *model, const sem_raycast_scene *scene,
                               const sem_preprocess_options *o, sem_discretization *d,
                               sem_error *err)
{
    return sem_step_quadrature_with(model, scene, o, NULL, d, NULL, err);
}

sem_status sem_step_quadrature_with(const sem_model *model, const sem_raycast_scene *scene,
                                    const sem_preprocess_options *o,
                                    const sem_subray_settings *settings, sem_discretization *d,
                                    long long *n_rays_cast, sem_error *err)
{
    if (n_rays_cast) *n_rays_cast = 0;
    if (!scene || !o || !d)
        return sem_error_set(err, SEM_ERR_INVALID, "quadrature: NULL scene, options or output");
    int explicit_grid = o->rays[0] != 0 || o->rays[1] != 0;
    if ((explicit_grid && (o->rays[0] < 1 || o->rays[1] < 1)) || o->rays[0] > 100000 ||
        o->rays[1] > 100000 || (long long)o->rays[0] * o->rays[1] > 100000000LL)
        return sem_error_set(err, SEM_ERR_INVALID, "quadrature: ray grid %d x %d is invalid",
                             o->rays[0], o->rays[1]);
    if (o->ray_axis < -1 || o->ray_axis > 2)
        return sem_error_set(err, SEM_ERR_INVALID, "quadrature: ray axis %d is not 0, 1 or 2",
                             o->ray_axis);
    if (o->points_per_interval < 0 || o->points_per_interval > 100000)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "quadrature: points per interval %d is invalid",
                             o->points_per_interval);

    int have_frame = 0;
    for (int k = 0; k < 9; ++k) have_frame |= d->frame_axes[k] != 0.0;
    if (!have_frame) { /* a caller that runs the steps itself */
        sem_status fst = sem_step_frame(scene, d, err);
        if (fst != SEM_OK) return fst;
    }
    ray_grid g;
    sem_status gst = make_grid(scene, o, d, &g, err);
    if (gst != SEM_OK) return gst;
    double wb = g.hi[1] - g.lo[1], wc = g.hi[2] - g.lo[2], wa = g.hi[0] - g.lo[0];
    if (!(wb > 0) || !(wc > 0) || !(wa > 0) || !isfinite(wa + wb + wc))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "quadrature: the model's bounding box is flat or empty "
                             "(%g x %g x %g): no volume to sample",
                             wa, wb, wc);
    int n1 = g.n1, n2 = g.n2;
    int n_rays = n1 * n2;
    double cell_area = (wb / n1) * (wc / n2);
    d->quad_spacing = sqrt(cell_area);
    double diag = sqrt(wa * wa + wb * wb + wc * wc);
    double pad = 1e-3 * diag;
    double length = wa + 2 * pad;

    int failed = 0;
    int ppi = g.points_per_interval;
    double h_along = g.h_along;
    sem_ray_points *rays = NULL;
    if (g.cell_size > 0) {
        /* the object-frame grid of cells (quadrature_cells.c): points per column */
        sem_status cst = sem_quadrature_cells(model, scene, g.cell_size, settings, d, &rays,
                                              &n_rays, n_rays_cast, o->threads, err);
        if (cst != SEM_OK) {
            for (int r = 0; rays && r < n_rays; r++) {
                free(rays[r].X);
                free(rays[r].volume);
                free(rays[r].part);
            }
            free(rays);
            return cst;
        }
    } else {
        if (n_rays_cast) *n_rays_cast = n_rays;
        rays = calloc((size_t)n_rays, sizeof *rays);
        if (!rays) return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    /* a ray costs 5-20 us (exact hit refinement, winding-number vetoes), so even the
     * authors' small grids (81-180 rays) gain from a second thread: tire 1.1 -> 0.5 ms */
#pragma omp parallel for schedule(dynamic, 4) reduction(| : failed) \
    num_threads(sem_threads(o->threads)) if (n_rays >= 16)
    for (int r = 0; r < n_rays; r++) {
        int i = r % n1, j = r / n1;
        double s0 = g.lo[0] - pad, s1 = g.lo[1] + (i + 0.5) * (wb / n1),
               s2 = g.lo[2] + (j + 0.5) * (wc / n2);
        double origin[3], dir[3];
        for (int k = 0; k < 3; ++k) {
            origin[k] = g.origin[k] + s0 * g.axis[0][k] + s1 * g.axis[1][k] + s2 * g.axis[2][k];
            dir[k] = g.axis[0][k];
        }
        if (!quadrature_ray(scene, origin, dir, pad, pad + wa, length, ppi, h_along, cell_area,
                            &rays[r]))
            failed |= 1;
    }
    }

    sem_status st = SEM_OK;
    long long total = 0;
    for (int r = 0; r < n_rays; r++) total += rays[r].n;
    if (failed || total > 1000000000LL) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory (%lld points)", total);
    } else {
        free(d->quad_X);
        free(d->quad_volume);
        free(d->quad_part);
        d->quad_X = NULL;
        d->quad_volume = NULL;
        d->quad_part = NULL;
        d->n_quad = 0;
        d->volume = 0;
        size_t m = total > 0 ? (size_t)total : 1;
        d->quad_X = malloc(m * 3 * sizeof *d->quad_X);
        d->quad_volume = malloc(m * sizeof *d->quad_volume);
        d->quad_part = malloc(m * sizeof *d->quad_part);
        if (!d->quad_X || !d->quad_volume || !d->quad_part) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
        } else {
            size_t k = 0;
            double volume = 0;
            for (int r = 0; r < n_rays; r++) {
                if (rays[r].n == 0) continue;
                memcpy(d->quad_X + 3 * k, rays[r].X, (size_t)rays[r].n * 3 * sizeof(double));
                memcpy(d->quad_volume + k, rays[r].volume, (size_t)rays[r].n * sizeof(double));
                memcpy(d->quad_part + k, rays[r].part, (size_t)rays[r].n * sizeof(int));
                for (int p = 0; p < rays[r].n; p++) volume += rays[r].volume[p];
                k += (size_t)rays[r].n;
            }
            d->n_quad = (int)total;
            d->volume = volume;
            if (total == 0)
                st = sem_error_set(err, SEM_ERR_INVALID,
                                   "quadrature: no ray found an inside interval (%d x %d rays): "
                                   "the model encloses no volume",
                                   n1, n2);
        }
    }
    for (int r = 0; r < n_rays; r++) {
        free(rays[r].X);
        free(rays[r].volume);
        free(rays[r].part);
    }
    free(rays);
    return st;
}
