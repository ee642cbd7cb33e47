/*
 * quadrature_subrays.c - the rays of the default quadrature: a grid of parallel rays across
 * every column of cells, refined where the inside length is not smooth (paper Sec. 6.3,
 * Eq. 11; issue 27).
 *
 * The volume of a column is the integral over its cross-section of the inside length L(y, z)
 * of the ray through (y, z). quadrature_cells.c used the midpoint rule over base x base
 * squares per column (4 per finest cell and direction). On the default grids (a sphere gets 4
 * cells per diameter) that was 0.8 % off on a sphere, 0.7 % on a torus: L is smooth where the
 * rays cross the surface at an angle, but it falls like a square root at a silhouette
 * (L ~ sqrt(distance)) and jumps at a wall along the rays, and there the midpoint rule is only
 * of order s^1.5 or s. And even where L is smooth, squares of an eighth of a radius leave
 * ~1e-3 (the rule's s^2 / 24 curvature term). The number of rays sets only the preprocessing
 * time; the points, one per cell (the cost of every time step), do not change. So:
 *
 * 1. Corrected midpoint rule. Each crossing of the surface that bounds an inside interval is
 *    a point of a height field t = g(y, z) (hit_curvature.c); the midpoint rule over a square
 *    of sides sy x sz misses (sy^2 g_yy + sz^2 g_zz) sy sz / 24 of it (+ at an exit, - at an
 *    entry), which is added as a correction volume at that end (dv0, dv1; quadrature_cells.c
 *    puts it in the cell of the crossing). The rule is then fourth order where the surface is
 *    smooth: exact Hessians from the NURBS, no neighbouring rays needed.
 * 2. Refinement, level by level up to MAX_DEPTH, of the squares where the rule cannot be
 *    trusted, into quarters with a ray each:
 *    - rough: a crossing whose surface bends too much across the square: r = s |Hess g|
 *      |n . d| > ROUGH (s |Hess g| |n . d| ~ s / distance to the silhouette, i.e. where the
 *      Taylor expansion behind 1. fails), or whose derivatives are unknown (Newton did not
 *      converge onto the NURBS, a seam where parts meet, a ray in the tangent plane);
 *    - a neighbour (8 around, the same size, looked up across columns) with another number
 *      of inside intervals (of the union: crossings of overlapping solids inside it change
 *      nothing). A silhouette, a wall along the rays, a hole or a trim edge lies between
 *      them. At the base level every such square is split once; below it only next to a
 *      rough crossing, i.e. the miss side of a silhouette, which only this finds. A wall's
 *      squares are only counted in or out, so halving them again gains little (the cylinder
 *      along its axis stays 0.59 % off; splitting its wall squares to the last level too gave
 *      0.27 % for 2 x the rays) while complex models have many (the astronaut: 5.6 x the rays
 *      and 9 x the time, since its refined rays cross the surface closely, where the winding
 *      numbers of quadrature.c's vetoes are expensive).
 *    A rough crossing gets no correction (plain midpoint rule) even at the last level. Squares
 *    end at SUBRAYS << MAX_DEPTH per base cell: columns refined for a small part have that
 *    many from the start.
 * Levels are global: every column's squares of one level are judged (reading the
 * neighbouring columns' squares of that level and coarser ones) before any is split, so the
 * result does not depend on the order or the threads that do it. A box whose faces lie on the
 * grid's bounds has straight walls at the grid's edges and flat faces across the rays: no
 * square is refined and its volume stays exact.
 *
 * Measured at the default grids (docs/validation.md section 4; bench/study_volume --defaults):
 * sphere 0.79 % -> 0.061 %, torus 0.71 % -> 0.043 %, rounded_cube.iges 0.56 % -> 0.056 %,
 * mug_trimmed_complex.iges 0.67 % -> 0.005 % (against fine grids along x, y, z, which differ by
 * 0.13 %), with 5.1, 4.5, 4.3 and 1.9 times the rays and the same points (the rounded cube 198
 * for 194). The correction alone (MAX_DEPTH 0) gives 0.34 %, 0.49 %, 0.50 %; a third level
 * 0.017 %, 0.006 %, 0.056 % for twice the rays again. What is left: kinks of the inside length
 * where parts meet at an angle (rounded_cube.iges), and walls along the rays; and the
 * tessellation, whose polygon the rays must hit before they reach the exact surface (-0.16 %
 * on the cylinder's caps).
 */
#include "quadrature_subrays.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "util/grow.h"
#include "util/threads.h"

/* Levels of quarters below the base squares. */
#define MAX_DEPTH 2
/* A crossing is rough when s |Hess g| |n . d| exceeds this (s the square's larger side). */
#define ROUGH 1.0

sem_subray_settings sem_subray_default_settings(void)
{
    sem_subray_settings st = {MAX_DEPTH, ROUGH, 1};
    return st;
}

static int grow(void **p, int *cap, int need, size_t elem)
{
    return sem_grow(p, cap, need, elem, 64, INT_MAX);
}

/* Column ci + n[1] cj. */
static int column_index(const sem_subray_grid *g, int ci, int cj) { return ci + g->n[1] * cj; }

/* The sizes of a square of `level` in column col. */
static void square_size(const sem_subray_grid *g, const sem_subray_column *col, int level,
                        double *sy, double *sz)
{
    const int R = col->base << level;
    *sy = g->h[1] / R;
    *sz = g->h[2] / R;
}

/* The correction of the midpoint rule at one end of an inside segment (sign +1 at an exit,
 * -1 at an entry), or 0 and *rough set. */
static double end_correction(const sem_raycast_scene *scene, const sem_subray_grid *g,
                             const sem_subray_settings *st, const sem_ray_hit *hit, double sy,
                             double sz, double sign, int *rough)
{
    double H[3], facing;
    if (!hit->smooth ||
        !sem_hit_height_hessian(sem_raycast_part_surface(scene, hit->part), hit->u, hit->v,
                                g->axis[0], g->axis[1], g->axis[2], H, &facing)) {
        *rough = 1;
        return 0.0;
    }
    const double s = sy > sz ? sy : sz;
    const double norm = sqrt(H[0] * H[0] + H[1] * H[1] + 2.0 * H[2] * H[2]);
    if (s * norm * facing > st->rough) {
        *rough = 1;
        return 0.0;
    }
    if (!st->correct) return 0.0;
    return sign * sy * sz * (sy * sy * H[0] + sz * sz * H[1]) / 24.0;
}

/* Casts the ray of node k of column (ci, cj) and stores its inside segments. Returns 0 when
 * out of memory. */
static int cast(const sem_raycast_scene *scene, const sem_subray_grid *g,
                const sem_subray_settings *st, int ci, int cj, sem_subray_column *col, int k)
{
    sem_subray_node *node = &col->nodes[k];
    double sy, sz;
    square_size(g, col, node->level, &sy, &sz);
    const double s0 = g->lo[0] - g->pad;
    const double s1 = g->lo[1] + ci * g->h[1] + (node->i + 0.5) * sy;
    const double s2 = g->lo[2] + cj * g->h[2] + (node->j + 0.5) * sz;
    double origin[3];
    for (int e = 0; e < 3; ++e)
        origin[e] = g->origin[e] + s0 * g->axis[0][e] + s1 * g->axis[1][e] + s2 * g->axis[2][e];
    sem_ray_segment *seg = NULL;
    sem_ray_hit *hits = NULL;
    int n_seg = 0, n_hits = 0;
    col->rays++;
    if (!sem_ray_inside_segments(scene, origin, g->axis[0], g->pad, g->length - g->pad,
                                 g->length, &seg, &n_seg, &hits, &n_hits))
        return 0;
    node->seg_begin = col->n_seg;
    node->n_seg = 0;
    node->rough = 0;
    unsigned intervals = 0;
    int ok = 1;
    for (int q = 0; q < n_seg; ++q) {
        if (!seg[q].inside || !(seg[q].t1 > seg[q].t0)) continue;
        /* segment q runs from hit q - 1 to hit q; an end shared with another inside segment
         * is no boundary of the union */
        int entry = q >= 1 && !(seg[q - 1].inside && seg[q - 1].t1 > seg[q - 1].t0);
        intervals += !(q >= 1 && seg[q - 1].inside && seg[q - 1].t1 > seg[q - 1].t0);
        int exit = q < n_hits && !(q + 1 < n_seg && seg[q + 1].inside && seg[q + 1].t1 > seg[q + 1].t0);
        double dv0 = 0, dv1 = 0;
        if (entry) dv0 = end_correction(scene, g, st, &hits[q - 1], sy, sz, -1.0, &node->rough);
        if (exit) dv1 = end_correction(scene, g, st, &hits[q], sy, sz, 1.0, &node->rough);
        if (!grow((void **)&col->seg, &col->cap_seg, col->n_seg + 1, sizeof *col->seg)) {
            ok = 0;
            break;
        }
        col->seg[col->n_seg++] = (sem_subray_segment){seg[q].t0, seg[q].t1, seg[q].part, dv0, dv1};
        node->n_seg++;
    }
    node->signature = intervals;
    free(seg);
    free(hits);
    return ok;
}

/* The leaf of the grid at (b, c) (frame coordinates relative to lo), or NULL outside it. */
static const sem_subray_node *leaf_at(const sem_subray_grid *g, const sem_subray_column *cols,
                                      double b, double c)
{
    if (!(b >= 0) || !(c >= 0)) return NULL;
    const double fb = b / g->h[1], fc = c / g->h[2];
    if (!(fb < g->n[1]) || !(fc < g->n[2])) return NULL;
    const int ci = (int)fb, cj = (int)fc;
    const sem_subray_column *col = &cols[column_index(g, ci, cj)];
    if (col->n_nodes == 0) return NULL;
    const double u = fb - ci, v = fc - cj; /* in [0, 1) across the column */
    int R = col->base;
    int i = (int)(u * R), j = (int)(v * R);
    i = i < 0 ? 0 : (i >= R ? R - 1 : i);
    j = j < 0 ? 0 : (j >= R ? R - 1 : j);
    const sem_subray_node *node = &col->nodes[i + col->base * j];
    while (node->child >= 0) {
        R *= 2;
        int a = (int)(u * R) - 2 * node->i, e = (int)(v * R) - 2 * node->j;
        a = a < 0 ? 0 : (a > 1 ? 1 : a);
        e = e < 0 ? 0 : (e > 1 ? 1 : e);
        node = &col->nodes[node->child + a + 2 * e];
    }
    return node;
}

/* Should node k of column (ci, cj) be split? */
static int wants_split(const sem_subray_grid *g, const sem_subray_column *cols, int ci, int cj,
                       int k)
{
    const sem_subray_column *col = &cols[column_index(g, ci, cj)];
    const sem_subray_node *node = &col->nodes[k];
    if (node->rough) return 1;
    const double R = (double)(col->base << node->level);
    const double b = (ci + (node->i + 0.5) / R) * g->h[1], c = (cj + (node->j + 0.5) / R) * g->h[2];
    const double db = g->h[1] / R, dc = g->h[2] / R;
    for (int y = -1; y <= 1; ++y)
        for (int z = -1; z <= 1; ++z) {
            if (!y && !z) continue;
            const sem_subray_node *other = leaf_at(g, cols, b + y * db, c + z * dc);
            if (other && other->signature != node->signature && (node->level == 0 || other->rough))
                return 1;
        }
    return 0;
}

void sem_subrays_free(sem_subray_column *columns, int n_columns)
{
    if (!columns) return;
    for (int c = 0; c < n_columns; ++c) {
        free(columns[c].nodes);
        free(columns[c].seg);
    }
    free(columns);
}

sem_status sem_subrays_cast(const sem_raycast_scene *scene, const sem_subray_grid *g,
                            const int *base, const sem_subray_settings *st, int threads,
                            sem_subray_column **columns_out, sem_error *err)
{
    const int n_threads = sem_threads(threads);
    *columns_out = NULL;
    const int n_columns = g->n[1] * g->n[2];
    sem_subray_column *cols = calloc((size_t)(n_columns > 0 ? n_columns : 1), sizeof *cols);
    if (!cols) return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    int failed = 0;
    /* level 0: the base squares */
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed) num_threads(n_threads)
    for (int c = 0; c < n_columns; ++c) {
        sem_subray_column *col = &cols[c];
        const int S = base[c];
        col->base = S;
        if (!grow((void **)&col->nodes, &col->cap_nodes, S * S, sizeof *col->nodes)) {
            failed |= 1;
            continue;
        }
        col->n_nodes = S * S;
        for (int j = 0; j < S; ++j)
            for (int i = 0; i < S; ++i)
                col->nodes[i + S * j] = (sem_subray_node){0, i, j, -1, 0, 0, 0u, 0};
        for (int k = 0; k < S * S && !failed; ++k)
            if (!cast(scene, g, st, c % g->n[1], c / g->n[1], col, k)) failed |= 1;
        col->level_begin = 0;
        col->level_end = S * S;
    }
    const int depth = st->max_depth;
    unsigned char **split = calloc((size_t)(n_columns > 0 ? n_columns : 1), sizeof *split);
    if (!split) failed = 1;
    for (int level = 0; level < depth && !failed; ++level) {
        /* judge every square of this level, then split: the judgement reads neighbours only */
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed) num_threads(n_threads)
        for (int c = 0; c < n_columns; ++c) {
            const sem_subray_column *col = &cols[c];
            const int m = col->level_end - col->level_begin;
            free(split[c]);
            split[c] = m > 0 ? malloc((size_t)m) : NULL;
            if (m > 0 && !split[c]) {
                failed |= 1;
                continue;
            }
            /* squares no finer than subrays << depth per base cell: a column refined for a
             * small part (base subrays << L) has that many already when L = depth */
            const int may_split = (col->base << (level + 1)) <= (g->subrays << depth);
            for (int k = 0; k < m; ++k)
                split[c][k] = may_split && wants_split(g, cols, c % g->n[1], c / g->n[1],
                                                       col->level_begin + k);
        }
        if (failed) break;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed) num_threads(n_threads)
        for (int c = 0; c < n_columns; ++c) {
            sem_subray_column *col = &cols[c];
            const int begin = col->level_begin, end = col->level_end;
            const int first_new = col->n_nodes;
            for (int k = begin; k < end && !failed; ++k) {
                if (!split[c][k - begin]) continue;
                if (!grow((void **)&col->nodes, &col->cap_nodes, col->n_nodes + 4, sizeof *col->nodes)) {
                    failed |= 1;
                    break;
                }
                const int child = col->n_nodes, lv = col->nodes[k].level + 1;
                const int i = col->nodes[k].i, j = col->nodes[k].j;
                col->nodes[k].child = child;
                for (int q = 0; q < 4; ++q) {
                    col->nodes[child + q] =
                        (sem_subray_node){lv, 2 * i + (q & 1), 2 * j + (q >> 1), -1, 0, 0, 0u, 0};
                    col->n_nodes++;
                    if (!cast(scene, g, st, c % g->n[1], c / g->n[1], col, child + q)) {
                        failed |= 1;
                        break;
                    }
                }
            }
            col->level_begin = first_new;
            col->level_end = col->n_nodes;
        }
    }
    if (split)
        for (int c = 0; c < n_columns; ++c) free(split[c]);
    free(split);
    if (failed) {
        sem_subrays_free(cols, n_columns);
        return sem_error_set(err, SEM_ERR_NOMEM, "quadrature: out of memory");
    }
    *columns_out = cols;
    return SEM_OK;
}
