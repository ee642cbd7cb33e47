/*
 * quadrature_cells.c - the default volume quadrature: cells of a grid laid in the object's own
 * frame, refined near small parts (paper Sec. 6.3, Eq. 11; issue 11).
 *
 * The paper shoots a world-aligned grid of rays and places points along them (quadrature.c
 * keeps that for explicit `rays`). That quadrature depends on how the object lies in its file,
 * and a coarse grid misses small parts or gives them a point or two, so their polynomials get
 * almost no mass or stiffness (and fly away). Here instead:
 *
 * - The grid: base cells of size h in the object's frame (object_frame.c: principal axes of
 *   the surface), rays along the frame's longest axis. h is the option `spacing`, or
 *   automatically min(thinnest extent / 3, median part size / 6), at least what keeps the
 *   bounding box within MAX_AUTO_POINTS cells (see quadrature.c's constants).
 * - Refinement: a part of size s (its samples' bounding-box diagonal in the frame) asks for
 *   cells of at most s / SMALL_PART_CELLS in its bounding box grown by that much. A base cell
 *   there is split into 2^l x 2^l x 2^l sub-cells (l <= MAX_LEVEL), so a knob, fin or handle
 *   gets points in proportion to the solid it bounds and not to the grid's luck.
 * - One point per (sub-)cell with inside volume, at the centroid of that volume, weighted by
 *   it. The inside volume is integrated by the rays of quadrature_subrays.c: SUBRAYS x SUBRAYS
 *   per finest cell of the column (the inside intervals of quadrature.c's
 *   sem_ray_inside_segments, CSG union and winding-number fallback included), refined where
 *   the surface makes the midpoint rule unreliable, with the midpoint rule corrected by the
 *   surface's curvature at each crossing (a volume put in the cell of the crossing). So the
 *   volume is that of a much finer grid while the number of points (the cost of every time
 *   step) stays that of the cells. A box is exact; the default sphere, torus and
 *   rounded_cube.iges are within 0.07 % (they were 0.8 %, 0.7 %, 0.6 % with the plain
 *   midpoint rule of 4 x 4 rays; docs/validation.md section 4).
 * - Material: each cell takes the part whose material the longest inside length in it has
 *   (point_materials.c then picks by weight inside that part's solid).
 * Threads: columns in parallel, each column's points in a fixed order (cells along the axis,
 * sub-cells in index order; its rays' contributions in the order of their tree), concatenated
 * in column order: the result does not depend on the thread count. Nothing depends on the
 * world axes, so the quadrature turns with the object.
 */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <lapacke.h>

#include "quadrature_subrays.h"
#include "util/free_all.h"
#include "util/grow.h"
#include "util/threads.h"

#define SUBRAYS 4            /* rays per finest cell per direction */
#define SMALL_PART_CELLS 3.0 /* a part asks for cells of at most its size / this */
#define THIN_STD 0.2         /* a cell's inside volume thinner than this x the cell (standard
                                deviation along a principal direction) gets two points across */
#define MAX_LEVEL 3          /* sub-cells per base cell per direction: at most 2^3 */
#define MIN_CELL_FRACTION 1e-9
#define MAX_POINTS 2000000.0 /* refinement is coarsened until the cells fit */
#define CORRECTION_LIMIT 0.5 /* a cell keeps the midpoint rule where the correction is larger
                                than this fraction of its volume */

typedef struct cell_entry {
    int cell, part;
    double len;
} cell_entry;

static int entry_cmp(const void *a, const void *b)
{
    const cell_entry *x = a, *y = b;
    if (x->cell != y->cell) return (x->cell > y->cell) - (x->cell < y->cell);
    return (x->part > y->part) - (x->part < y->part);
}

/* One thread's buffers for a column. */
typedef struct column_buffers {
    int cap_cells;
    double *volume, *moment; /* cap_cells, 3 cap_cells: the midpoint rule's */
    double *second;          /* 6 cap_cells: xx yy zz xy xz yz, about the column origin */
    double *dvolume, *dmoment; /* cap_cells, 3 cap_cells: its corrections (quadrature_subrays.c) */
    double *base_volume;     /* cap_cells: the volume the base rays alone find */
    int *part;               /* cap_cells: material, -1 for none */
    unsigned char *keep;     /* cap_cells: gets a point */
    int *offset;             /* cells along + 1 */
    int n_entries, cap_entries;
    cell_entry *entries;
} column_buffers;

typedef struct cell_grid {
    double origin[3], axis[3][3], lo[3];
    int n[3];     /* base cells along axis 0 (the rays), 1, 2 */
    double h[3];  /* base cell sizes */
    unsigned char *level; /* per base cell, index k + n0 (i + n1 j) */
    double pad, length;
} cell_grid;

static int grow(void **p, int *cap, int need, size_t elem)
{
    return sem_grow(p, cap, need, elem, 64, INT_MAX);
}

static int push_entry(column_buffers *b, int cell, int part, double len)
{
    if (b->n_entries > 0) { /* the same sub-ray usually stays in one part */
        cell_entry *e = &b->entries[b->n_entries - 1];
        if (e->cell == cell && e->part == part) {
            e->len += len;
            return 1;
        }
    }
    if (!grow((void **)&b->entries, &b->cap_entries, b->n_entries + 1, sizeof *b->entries)) return 0;
    b->entries[b->n_entries++] = (cell_entry){cell, part, len};
    return 1;
}

/* The point(s) of one cell of volume V and centroid c (relative to col_origin): one at c, or,
 * where the inside volume is thin along principal directions (a wall, a fin, a rod narrower
 * than ~0.7 cells: standard deviation below THIN_STD of the cell size h), two points across
 * each thin direction at c +- one standard deviation with the volume shared equally: the
 * two-point Gauss rule along that direction, which matches the volume's first and second
 * moments. One point at the middle of a wall would see no bending strain (it sits on the
 * neutral surface), so walls thinner than a cell would have zero-energy bending modes. The
 * principal directions come from the midpoint rule's moments (b's, uncorrected: the
 * corrections of quadrature_subrays.c are volumes at the surface, with no spread of their
 * own). Returns 0 on out of memory. */
static int emit_cell(const column_buffers *b, int cell, const double col_origin[3], double h,
                     double V, const double c[3], int part, sem_ray_points *result, int *cap)
{
    const double V0 = b->volume[cell];
    double c0[3], C[9];
    for (int e = 0; e < 3; ++e) c0[e] = b->moment[3 * (size_t)cell + e] / V0;
    const double *s2 = b->second + 6 * (size_t)cell;
    C[0] = s2[0] / V0 - c0[0] * c0[0];
    C[4] = s2[1] / V0 - c0[1] * c0[1];
    C[8] = s2[2] / V0 - c0[2] * c0[2];
    C[1] = C[3] = s2[3] / V0 - c0[0] * c0[1];
    C[2] = C[6] = s2[4] / V0 - c0[0] * c0[2];
    C[5] = C[7] = s2[5] / V0 - c0[1] * c0[2];
    double w[3];
    int thin[3] = {0, 0, 0}, n_thin = 0;
    if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, C, 3, w) == 0)
        for (int a = 0; a < 3; ++a) {
            thin[a] = w[a] < (THIN_STD * h) * (THIN_STD * h);
            n_thin += thin[a];
        }
    if (n_thin == 3) n_thin = 0; /* a speck: one point */
    const int n_points = 1 << n_thin;
    for (int k = 0; k < n_points; ++k) {
        double X[3] = {c[0], c[1], c[2]};
        int bit = 0;
        for (int a = 0; a < 3 && n_thin > 0; ++a) {
            if (!thin[a]) continue;
            double sgn = (k >> bit++) & 1 ? 1.0 : -1.0, sd = sqrt(fmax(w[a], 0.0));
            for (int e = 0; e < 3; ++e) X[e] += sgn * sd * C[3 * e + a]; /* column a: eigenvector */
        }
        for (int e = 0; e < 3; ++e) X[e] += col_origin[e];
        if (!sem_ray_points_push(result, cap, X, V / n_points, part)) return 0;
    }
    return 1;
}

/* Adds volume dv at t along the column's ray through `origin` to the cell that holds it. */
static void add_correction(column_buffers *b, const cell_grid *g, const unsigned char *lev,
                           const double origin[3], const double col_origin[3], int bi_num,
                           int ci_num, int R, double t, double dv)
{
    const int n0 = g->n[0];
    const double h0 = g->h[0];
    int k = (int)floor((t - g->pad) / h0);
    k = k < 0 ? 0 : (k >= n0 ? n0 - 1 : k);
    const int ns = 1 << lev[k];
    const double hs = h0 / ns;
    int a = (int)floor((t - g->pad - k * h0) / hs);
    a = a < 0 ? 0 : (a >= ns ? ns - 1 : a);
    const int bi = bi_num * ns / R, ci = ci_num * ns / R;
    const int cell = b->offset[k] + (a * ns + bi) * ns + ci;
    b->dvolume[cell] += dv;
    for (int e = 0; e < 3; ++e)
        b->dmoment[3 * (size_t)cell + e] += dv * (origin[e] + t * g->axis[0][e] - col_origin[e]);
}

/* The points of column (i, j) from its rays (quadrature_subrays.c). Returns 0 on out of
 * memory. */
static int column(const cell_grid *g, const sem_subray_column *rays, int i, int j,
                  column_buffers *b, sem_ray_points *result)
{
    const int n0 = g->n[0];
    const unsigned char *lev = g->level + (size_t)n0 * ((size_t)i + (size_t)g->n[1] * j);
    b->offset[0] = 0;
    for (int k = 0; k < n0; ++k) b->offset[k + 1] = b->offset[k] + (1 << (3 * lev[k]));
    const int n_cells = b->offset[n0];
    if (!grow((void **)&b->volume, &b->cap_cells, n_cells, sizeof *b->volume)) return 0;
    const size_t cap = (size_t)b->cap_cells;
    if (!sem_resize((void **)&b->moment, 3 * cap, sizeof *b->moment) ||
        !sem_resize((void **)&b->second, 6 * cap, sizeof *b->second) ||
        !sem_resize((void **)&b->dvolume, cap, sizeof *b->dvolume) ||
        !sem_resize((void **)&b->dmoment, 3 * cap, sizeof *b->dmoment) ||
        !sem_resize((void **)&b->base_volume, cap, sizeof *b->base_volume) ||
        !sem_resize((void **)&b->part, cap, sizeof *b->part) || !sem_resize((void **)&b->keep, cap, 1))
        return 0;
    memset(b->volume, 0, (size_t)n_cells * sizeof *b->volume);
    memset(b->moment, 0, 3 * (size_t)n_cells * sizeof *b->moment);
    memset(b->second, 0, 6 * (size_t)n_cells * sizeof *b->second);
    memset(b->dvolume, 0, (size_t)n_cells * sizeof *b->dvolume);
    memset(b->dmoment, 0, 3 * (size_t)n_cells * sizeof *b->dmoment);
    memset(b->base_volume, 0, (size_t)n_cells * sizeof *b->base_volume);
    b->n_entries = 0;

    const double h0 = g->h[0];
    const double *dir = g->axis[0];
    const double s0 = g->lo[0] - g->pad, s1 = g->lo[1] + i * g->h[1], s2 = g->lo[2] + j * g->h[2];
    double col_origin[3]; /* moments about the column's corner: small numbers, no cancellation */
    for (int e = 0; e < 3; ++e)
        col_origin[e] = g->origin[e] + g->lo[0] * g->axis[0][e] + s1 * g->axis[1][e] + s2 * g->axis[2][e];
    /* the leaves in node order: a fixed order, so fixed sums; the base rays (level 0, split
     * or not) also say which cells get a point */
    for (int nd = 0; nd < rays->n_nodes; ++nd) {
        const sem_subray_node *node = &rays->nodes[nd];
        const int leaf = node->child < 0, base = node->level == 0;
        if (!leaf && !base) continue;
        const int R = rays->base << node->level;
        const double sy = g->h[1] / R, sz = g->h[2] / R, area = sy * sz;
        const double cb = s1 + (node->i + 0.5) * sy, cc = s2 + (node->j + 0.5) * sz;
        double origin[3];
        for (int e = 0; e < 3; ++e)
            origin[e] = g->origin[e] + s0 * g->axis[0][e] + cb * g->axis[1][e] + cc * g->axis[2][e];
        for (int q = 0; q < node->n_seg; ++q) {
            const sem_subray_segment *seg = &rays->seg[node->seg_begin + q];
            double a0 = (seg->t0 - g->pad) / h0, a1 = (seg->t1 - g->pad) / h0;
            int k0 = (int)floor(fmax(a0, 0.0)), k1 = (int)floor(fmin(a1, (double)n0 - 1e-12));
            for (int k = k0; k <= k1 && k < n0; ++k) {
                const int l = lev[k], ns = 1 << l;
                const double hs = h0 / ns;
                /* R is a multiple of ns (base = SUBRAYS << the column's finest level) */
                const int bi = node->i * ns / R, ci = node->j * ns / R;
                for (int a = 0; a < ns; ++a) {
                    double c0 = g->pad + k * h0 + a * hs;
                    double t0 = fmax(seg->t0, c0), t1 = fmin(seg->t1, c0 + hs);
                    if (!(t1 > t0)) continue;
                    int cell = b->offset[k] + (a * ns + bi) * ns + ci;
                    double vol = (t1 - t0) * area, tm = 0.5 * (t0 + t1);
                    if (base) b->base_volume[cell] += vol;
                    if (!leaf) continue;
                    b->volume[cell] += vol;
                    double x[3];
                    for (int e = 0; e < 3; ++e) {
                        x[e] = origin[e] + tm * dir[e] - col_origin[e];
                        b->moment[3 * (size_t)cell + e] += vol * x[e];
                    }
                    /* int (x x^T) over the segment: length (m m^T + L^2/12 d d^T) */
                    double L12 = (t1 - t0) * (t1 - t0) / 12.0, *s2c = b->second + 6 * (size_t)cell;
                    s2c[0] += vol * (x[0] * x[0] + L12 * dir[0] * dir[0]);
                    s2c[1] += vol * (x[1] * x[1] + L12 * dir[1] * dir[1]);
                    s2c[2] += vol * (x[2] * x[2] + L12 * dir[2] * dir[2]);
                    s2c[3] += vol * (x[0] * x[1] + L12 * dir[0] * dir[1]);
                    s2c[4] += vol * (x[0] * x[2] + L12 * dir[0] * dir[2]);
                    s2c[5] += vol * (x[1] * x[2] + L12 * dir[1] * dir[2]);
                    if (!push_entry(b, cell, seg->part, t1 - t0)) return 0;
                }
            }
            if (!leaf) continue;
            if (seg->dv0 != 0.0)
                add_correction(b, g, lev, origin, col_origin, node->i, node->j, R, seg->t0, seg->dv0);
            if (seg->dv1 != 0.0)
                add_correction(b, g, lev, origin, col_origin, node->i, node->j, R, seg->t1, seg->dv1);
        }
    }
    /* each cell's material: the part with the longest inside length (entries summed) */
    if (b->n_entries > 0) qsort(b->entries, (size_t)b->n_entries, sizeof *b->entries, entry_cmp);
    int e = 0;
    for (int cell = 0; cell < n_cells; ++cell) {
        int part = -1;
        double best = -1;
        while (e < b->n_entries && b->entries[e].cell < cell) ++e;
        while (e < b->n_entries && b->entries[e].cell == cell) {
            int p = b->entries[e].part;
            double len = 0;
            while (e < b->n_entries && b->entries[e].cell == cell && b->entries[e].part == p)
                len += b->entries[e++].len;
            if (len > best) {
                best = len;
                part = p;
            }
        }
        b->part[cell] = part;
    }
    /* The points are the cells the base rays find inside, as the midpoint rule of those rays
     * alone had them: the finer rays sharpen volumes and centroids but add no point. Volume
     * they find in a cell the base rays missed (a sliver at a silhouette, a corner of a small
     * part) joins the kept cell of the column whose centroid is nearest, so the volume and
     * its first moment stay whole; a sliver point of its own would carry almost no volume
     * and could leave a small part owning one or two such points, too few to hold its
     * polynomial (mugs/mug.iges, part 0), where before it was blended into its neighbours.
     * Only a column without any kept cell keeps its slivers as points. */
    int n_keep = 0;
    for (int k = 0; k < n0; ++k) {
        const double cell_volume = h0 * g->h[1] * g->h[2] / (double)(1 << (3 * lev[k]));
        for (int cell = b->offset[k]; cell < b->offset[k + 1]; ++cell) {
            b->keep[cell] = b->base_volume[cell] > MIN_CELL_FRACTION * cell_volume &&
                            b->volume[cell] > 0 && b->part[cell] >= 0;
            n_keep += b->keep[cell];
        }
    }
    for (int k = 0; k < n0 && n_keep > 0; ++k) {
        const double cell_volume = h0 * g->h[1] * g->h[2] / (double)(1 << (3 * lev[k]));
        for (int cell = b->offset[k]; cell < b->offset[k + 1]; ++cell) {
            if (b->keep[cell] || !(b->volume[cell] > MIN_CELL_FRACTION * cell_volume)) continue;
            const double *m = b->moment + 3 * (size_t)cell;
            const double V = b->volume[cell];
            int target = -1;
            double best = INFINITY;
            for (int other = 0; other < n_cells; ++other) {
                if (!b->keep[other]) continue;
                const double *mo = b->moment + 3 * (size_t)other, Vo = b->volume[other];
                double d2 = 0;
                for (int d = 0; d < 3; ++d) d2 += (mo[d] / Vo - m[d] / V) * (mo[d] / Vo - m[d] / V);
                if (d2 < best) {
                    best = d2;
                    target = other;
                }
            }
            b->volume[target] += b->volume[cell];
            b->dvolume[target] += b->dvolume[cell];
            for (int d = 0; d < 3; ++d) {
                b->moment[3 * (size_t)target + d] += b->moment[3 * (size_t)cell + d];
                b->dmoment[3 * (size_t)target + d] += b->dmoment[3 * (size_t)cell + d];
            }
            for (int d = 0; d < 6; ++d) b->second[6 * (size_t)target + d] += b->second[6 * (size_t)cell + d];
            b->volume[cell] = 0;
        }
    }
    int cap_points = 0;
    for (int k = 0; k < n0; ++k) {
        const double cell_volume = h0 * g->h[1] * g->h[2] / (double)(1 << (3 * lev[k]));
        for (int cell = b->offset[k]; cell < b->offset[k + 1]; ++cell) {
            const double V0 = b->volume[cell], dV = b->dvolume[cell];
            if (!(n_keep > 0 ? b->keep[cell] : V0 > MIN_CELL_FRACTION * cell_volume) ||
                b->part[cell] < 0)
                continue;
            /* the correction of a sliver can exceed the sliver (it is a term of an expansion
             * over the whole square): there keep the midpoint rule */
            const int corrected = fabs(dV) <= CORRECTION_LIMIT * V0;
            const double V = corrected ? V0 + dV : V0;
            double c[3];
            for (int d = 0; d < 3; ++d)
                c[d] = (b->moment[3 * (size_t)cell + d] + (corrected ? b->dmoment[3 * (size_t)cell + d] : 0.0)) / V;
            if (!emit_cell(b, cell, col_origin, cbrt(cell_volume), V, c, b->part[cell], result,
                           &cap_points))
                return 0;
        }
    }
    return 1;
}

static int clamp_index(double x, int n)
{
    if (!(x > 0)) return 0;
    if (x >= n) return n - 1;
    return (int)x;
}

/* Marks the base cells near every part smaller than the cells; returns the number of cells
 * the refined grid would have at most (upper bound), or -1 when out of memory. */
static double refine(const sem_discretization *d, cell_grid *g, int max_level)
{
    const int np = d->n_parts;
    const size_t n_base = (size_t)g->n[0] * g->n[1] * g->n[2];
    memset(g->level, 0, n_base);
    double *size = malloc((size_t)(np > 0 ? np : 1) * sizeof *size);
    double *box = malloc(6 * (size_t)(np > 0 ? np : 1) * sizeof *box);
    if (!size || !box) {
        free(size);
        free(box);
        return -1;
    }
    if (sem_part_sizes(d, size, NULL) != SEM_OK) {
        free(size);
        free(box);
        return -1;
    }
    sem_part_frame_boxes(d, box);
    const double h = fmin(g->h[0], fmin(g->h[1], g->h[2]));
    for (int p = 0; p < np; ++p) {
        double want = size[p] / SMALL_PART_CELLS;
        if (!(size[p] > 0) || !(want < h)) continue;
        int l = (int)ceil(log2(h / want) - 1e-9);
        if (l > max_level) l = max_level;
        if (l < 1) continue;
        const double *bx = box + 6 * (size_t)p;
        int lo[3], hi[3];
        for (int e = 0; e < 3; ++e) {
            lo[e] = clamp_index((bx[e] - want - g->lo[e]) / g->h[e], g->n[e]);
            hi[e] = clamp_index((bx[3 + e] + want - g->lo[e]) / g->h[e], g->n[e]);
        }
        for (int j = lo[2]; j <= hi[2]; ++j)
            for (int i = lo[1]; i <= hi[1]; ++i)
                for (int k = lo[0]; k <= hi[0]; ++k) {
                    unsigned char *c = &g->level[k + (size_t)g->n[0] * (i + (size_t)g->n[1] * j)];
                    if (*c < l) *c = (unsigned char)l;
                }
    }
    double total = 0;
    for (size_t c = 0; c < n_base; ++c) total += (double)(1 << (3 * g->level[c]));
    free(size);
    free(box);
    return total;
}

sem_status sem_quadrature_cells(const sem_model *model, const sem_raycast_scene *scene, double h,
                                const sem_subray_settings *settings, sem_discretization *d,
                                sem_ray_points **columns_out, int *n_columns_out,
                                long long *n_rays, int threads, sem_error *err)
{
    if (n_rays) *n_rays = 0;
    *columns_out = NULL;
    *n_columns_out = 0;
    cell_grid g;
    memset(&g, 0, sizeof g);
    memcpy(g.origin, d->frame_center, sizeof g.origin);
    double extent[3];
    for (int e = 0; e < 3; ++e) {
        memcpy(g.axis[e], d->frame_axes + 3 * e, sizeof g.axis[e]);
        g.lo[e] = d->frame_lo[e];
        extent[e] = d->frame_hi[e] - d->frame_lo[e];
        double n = ceil(extent[e] / h * (1.0 - 1e-6)); /* an extent of k cells (to rounding) is k */
        g.n[e] = n < 1 ? 1 : (int)fmin(n, 1e6);
        g.h[e] = extent[e] / g.n[e];
    }
    double diag = sqrt(extent[0] * extent[0] + extent[1] * extent[1] + extent[2] * extent[2]);
    g.pad = 1e-3 * diag;
    g.length = extent[0] + 2 * g.pad;
    size_t n_base = (size_t)g.n[0] * g.n[1] * g.n[2];
    if ((double)g.n[0] * g.n[1] * g.n[2] > MAX_POINTS)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "quadrature: spacing %g gives %d x %d x %d cells (more than %g)", h,
                             g.n[0], g.n[1], g.n[2], MAX_POINTS);
    (void)model;
    g.level = calloc(n_base, 1);
    if (!g.level) return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    for (int max_level = MAX_LEVEL; max_level >= 0; --max_level) {
        double cells = refine(d, &g, max_level);
        if (cells < 0) {
            free(g.level);
            return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
        }
        if (cells <= MAX_POINTS) break;
    }
    const int n_columns = g.n[1] * g.n[2];
    /* the rays: SUBRAYS per finest cell of each column and direction, refined where needed */
    sem_subray_grid rg;
    memcpy(rg.origin, g.origin, sizeof rg.origin);
    memcpy(rg.axis, g.axis, sizeof rg.axis);
    memcpy(rg.lo, g.lo, sizeof rg.lo);
    memcpy(rg.h, g.h, sizeof rg.h);
    memcpy(rg.n, g.n, sizeof rg.n);
    rg.pad = g.pad;
    rg.length = g.length;
    rg.subrays = SUBRAYS;
    int *base = malloc((size_t)n_columns * sizeof *base);
    sem_ray_points *cols = calloc((size_t)n_columns, sizeof *cols);
    if (!cols || !base) {
        free(base);
        free(cols);
        free(g.level);
        return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    }
    for (int c = 0; c < n_columns; ++c) {
        const unsigned char *lev = g.level + (size_t)g.n[0] * (size_t)c;
        int L = 0;
        for (int k = 0; k < g.n[0]; ++k)
            if (lev[k] > L) L = lev[k];
        base[c] = SUBRAYS << L;
    }
    sem_subray_column *rays = NULL;
    sem_subray_settings defaults = sem_subray_default_settings();
    sem_status rst = sem_subrays_cast(scene, &rg, base, settings ? settings : &defaults, threads,
                                      &rays, err);
    free(base);
    if (rst != SEM_OK) {
        free(cols);
        free(g.level);
        return rst;
    }
    int failed = 0;
#pragma omp parallel num_threads(sem_threads(threads)) reduction(| : failed)
    {
        column_buffers b;
        memset(&b, 0, sizeof b);
        b.offset = malloc(((size_t)g.n[0] + 1) * sizeof *b.offset);
        if (!b.offset) failed |= 1;
#pragma omp for schedule(dynamic, 1)
        for (int c = 0; c < n_columns; ++c) {
            if (!b.offset) continue;
            if (!column(&g, &rays[c], c % g.n[1], c / g.n[1], &b, &cols[c])) failed |= 1;
        }
        SEM_FREE_ALL(b.offset, b.volume, b.moment, b.second, b.dvolume, b.dmoment, b.base_volume, b.part, b.keep,
                     b.entries);
    }
    if (n_rays)
        for (int c = 0; c < n_columns; ++c) *n_rays += rays[c].rays;
    sem_subrays_free(rays, n_columns);
    free(g.level);
    d->quad_spacing = h;
    *columns_out = cols;
    *n_columns_out = n_columns;
    if (failed) return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    return SEM_OK;
}
