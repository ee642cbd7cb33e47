/*
 * quadrature_subrays.h - the rays of the default quadrature (internal; quadrature_subrays.c
 * casts them, quadrature_cells.c turns them into points).
 */
#ifndef SEM_QUADRATURE_SUBRAYS_H
#define SEM_QUADRATURE_SUBRAYS_H

#include "steps.h"

/* The grid of columns, in the object's frame: rays along axis[0] start at lo[0] - pad and run
 * `length`; column (ci, cj) covers [lo[1] + ci h[1], + h[1]] x [lo[2] + cj h[2], + h[2]]
 * across them; n[1] x n[2] columns, each of n[0] cells of h[0] along the rays. */
typedef struct sem_subray_grid {
    double origin[3], axis[3][3];
    double lo[3], h[3];
    int n[3];
    double pad, length;
    int subrays; /* squares per direction of a base cell at level 0 without small parts */
} sem_subray_grid;

/* An inside piece of one ray: [t0, t1] along it, the part whose material it takes, and the
 * corrections of the midpoint rule at its ends (volumes; 0 where an end is not a crossing of
 * the surface or the surface cannot be trusted to be smooth there). */
typedef struct sem_subray_segment {
    double t0, t1;
    int part;
    double dv0, dv1;
} sem_subray_segment;

/* One square of a column's cross-section with the ray through its centre: at `level`, the
 * column has (base << level) squares per direction and this is square (i, j). A leaf when
 * child < 0; else children child .. child + 3 are its quarters ((0,0), (1,0), (0,1), (1,1)). */
typedef struct sem_subray_node {
    int level, i, j;
    int child;
    int seg_begin, n_seg;  /* its inside segments in the column's pool */
    unsigned signature;    /* crossings and the inside pattern; see quadrature_subrays.c */
    int rough;             /* a crossing where the midpoint rule cannot be trusted */
} sem_subray_node;

typedef struct sem_subray_column {
    int base;              /* squares per direction at level 0 */
    int n_nodes, cap_nodes;
    sem_subray_node *nodes; /* the base squares first, (i, j) at i + base j */
    int n_seg, cap_seg;
    sem_subray_segment *seg;
    int level_begin, level_end; /* nodes of the level being refined */
    int rays;              /* rays cast */
} sem_subray_column;

/* Casts the rays of every column: base[c] squares per direction in column c (c = ci + n[1] cj),
 * refined where the inside length is not smooth (see quadrature_subrays.c). *columns gets
 * n[1] n[2] columns (free with sem_subrays_free). */
sem_status sem_subrays_cast(const sem_raycast_scene *scene, const sem_subray_grid *grid,
                            const int *base, const sem_subray_settings *settings, int threads,
                            sem_subray_column **columns, sem_error *err);
void sem_subrays_free(sem_subray_column *columns, int n_columns);

#endif
