/*
 * object.h - one SEM object of a world: its state, the block structure of its matrices
 * and the data the physics files share (internal to src/physics/).
 *
 * Block structure. Pi_i (Eq. 7) maps the control points of the parts that share part i's
 * deformation origin - its *group* - to part i's polynomial coefficients. A quadrature
 * point or boundary sample couples the parts with weight there, so every matrix over
 * control points (mass M, error matrix M_eps, stiffness K) is made of dense blocks, one
 * per *group pair* (ga, gb) of two coupled parts' groups. The blocks of an object are stored
 * one after the other: group pair g's block is |Ga| x |Gb| scalars at gpair_offset[g] (M,
 * M_eps: the same for each coordinate) or 9 sub-blocks (d, d'), one per coordinate pair, at
 * 9 gpair_offset[g] (K). The layout is fixed when the object is added
 * (object_layout.c) and every other file works through it.
 *
 * Who fills what (the others only read it):
 *   world.c          def, d, sizes, q, v, q0, materials, point_rho_vol, volume, mass,
 *                    gamma, nthreads, the initial velocity, K0_blocks (K at rest)
 *   loads.c          the definition's loads, pinned, prescriptions, f_gravity
 *   object_layout.c  groups, part pairs, group pairs, block offsets, pi_dense
 *   assembly.c       the shared basis, point lists, z-space work, K_blocks,
 *                    elastic_energy, qc
 *   object_welds.c   n_welds, weld_ctrl
 *   object_seam_ties.c n_seam_ties, seam_tie_pair, seam_tie_weight (and seams, built early)
 *   pins.c           pins (material pins: the anchored points)
 *   mass_error.c     entry_basis, point_pairs, M_blocks, E_blocks and their CSR copy,
 *                    A_blocks (the pins' anchor), n_orphans, part_tied
 *   system_layout.c  free_index, n_free, system
 *   newton.c         exact_hessian (during a solve)
 */
#ifndef SEM_PHYSICS_OBJECT_H
#define SEM_PHYSICS_OBJECT_H

#include <stddef.h>

#include "sem/measure.h"
#include "sem/simulation.h"

struct sem_system;
struct sem_pins;

typedef struct sem_object {
    sem_object_def def;
    const sem_discretization *d;
    int n_ctrl, n_parts, m, n_quad;
    double *q, *v, *q0;        /* 3 n_ctrl */
    /* per quadrature point */
    const sem_material **point_material; /* into material / part_mats of this object */
    sem_material *part_mats;   /* initialized copies of def->part_materials */
    double *point_rho_vol;
    double *entry_basis;       /* per W entry: m, w * b_k */
    int *entry_pair_offset;    /* per point: start into point_pairs (k*k pairs) */
    int *point_pairs;
    /* part pairs (z-space blocks) */
    int n_pairs;
    int *pair_a, *pair_b;
    int *pair_lookup;          /* n_parts^2 -> pair or -1 */
    /* groups (one per origin) */
    int n_groups;
    int *group_start, *group_ctrl; /* CSR: control points of each group */
    int *ctrl_group, *ctrl_local;
    double **pi_dense;         /* per part: m x |group| row-major */
    /* stiffness in one shared basis (see assembly.h) */
    int ma;                    /* basis functions with a gradient: m - 1 */
    double ref_X[3];           /* the shared basis is b(X - ref_X) */
    double **pi_shared;        /* per part: ma x |group|, rows 1..m-1 of T_i^T Pi_i */
    double *point_D;           /* per point: ma x 3, d b_k(X_p - ref_X) / dX_e, k = 1..m-1 */
    int *plist_start;          /* per part pair: its points, in order; only pairs a <= b that
                                * share a quadrature point have any (see pair_has_points) */
    int *plist_point;
    double *plist_w;           /* w_a w_b at that point */
    int *plist_cursor;         /* per pair: first entry not yet summed (chunked assembly) */
    int n_packed;              /* 3ma (3ma + 1) / 2 */
    int chunk;                 /* points per assembly chunk */
    double *N_chunk;           /* chunk x n_packed: vol B^T H B per point, packed upper */
    double *Kz_packed;         /* per pair: running sum over earlier chunks */
    /* group-pair blocks */
    int n_gpairs;
    int *gpair_a, *gpair_b;
    int *gpair_lookup;         /* n_groups^2 -> gpair or -1 */
    size_t *gpair_offset;      /* scalar block offsets (size |Ga||Gb|), n_gpairs + 1 */
    int *part_pair_gpair;      /* per part pair */
    int *gpair_pairs_start, *gpair_pairs; /* part pairs per group pair */
    double *K_blocks;          /* 9 * gpair_offset[n]: entry (la, lb) of sub-block (d,d') at
                                * 9*off + (9 la + 3d + d') |Gb| + lb; formed for group
                                * pairs ga <= gb only (symmetry) */
    double *M_blocks;          /* gpair_offset[n] */
    double *E_blocks;          /* error matrix, gpair_offset[n] */
    int *me_start, *me_col;    /* M and E_blocks as one CSR pattern over control points */
    double *me_M, *me_E;
    double *K0_blocks;         /* rest stiffness, for Rayleigh damping */
    double *A_blocks;          /* the material pins' anchor (pins.h), gpair_offset[n]; NULL
                                * without pins */
    int n_orphans;             /* control points tied to their part's polynomial (no samples) */
    int n_welds;               /* welded pairs (object_welds.c): weld_ctrl[2k], [2k + 1] */
    int *weld_ctrl;
    int n_seam_ties;           /* seam pairs tied (object_seam_ties.c): indices into seams */
    int *seam_tie_pair;
    double *seam_tie_weight;   /* per tie: its row's weight in the error matrix */
    int *part_tied;            /* per part: how many of its control points are tied */
    /* forces */
    double *f_gravity;         /* 3 n_ctrl */
    double gamma;
    struct sem_pins *pins;     /* material pins (pins.h), NULL when none */
    /* free dofs */
    unsigned char *pinned;
    int *presc_index;          /* per ctrl: prescription followed, or -1 (stays put) */
    sem_prescribe *presc;
    int n_presc;
    int *free_index;           /* per ctrl: free index or -1 */
    int n_free;
    struct sem_system *system; /* the system it is solved in (system.h); not owned */
    /* z-space work */
    double *z;                 /* n_parts*ma x 3: shared-basis coefficients */
    double *grad_z;            /* n_parts*ma x 3 */
    double *Kz;                /* n_pairs x (3ma)^2, for pairs with points (Kz_ba = Kz_ab) */
    int nthreads;
    int exact_hessian;         /* 1: skip the PSD projection (Newton near a minimum) */
    double *grad_z_share;      /* GRADIENT_SHARES x n_parts*ma x 3 (see assembly.h) */
    double *qc;                /* q (or q - q0) minus its mean, 3 n_ctrl (see sem_centered) */
    double elastic_energy;
    double volume, mass;
    double runaway_budget;     /* runaway.c: energy the inputs can supply */
    /* structured matrices (structured.h): set when the world's solver is structured; then
     * no q-space block (K_blocks, M_blocks, E_blocks, K0_blocks) and no group pair exists */
    int structured;
    struct sem_structured_ops *ops;
    double *K0z;               /* Kz at rest (Rayleigh damping; the rest factor) */
    double *point_H, *point_H0; /* q-space: per point 9 x 9 d2psi/dF2 now and at rest */
    /* the seam monitor (sem/measure.h): built on the first sem_world_object_checks */
    int seams_built;
    sem_seams seams;
} sem_object;

/* Control points in group g. */
static inline size_t sem_group_size(const sem_object *o, int g)
{
    return (size_t)(o->group_start[g + 1] - o->group_start[g]);
}

/* object_layout.c: groups, part pairs (from the weights at quadrature points and boundary
 * samples), group pairs (from part pairs and the patterns of M and M_eps), block offsets,
 * and zeroed K, K0, M and M_eps blocks. */
sem_status sem_object_layout_init(sem_object *o, sem_error *err);
/* object_welds.c: the pairs of control points that coincide at rest (sem_object_def.weld),
 * each point of a cluster paired with the cluster's lowest index. */
sem_status sem_object_find_welds(sem_object *o, sem_error *err);
/* object_checks.c: o->seams (the seam monitor's pairs), built on the first call. */
sem_status sem_object_seams(sem_object *o, sem_error *err);
/* Seam ties (object_seam_ties.c) of stiffness k (<= 0: none); needs o->gamma. */
sem_status sem_object_find_seam_ties(sem_object *o, double stiffness, sem_error *err);
/* Seam tie t's row J_a - J_b: its entries are seams.row_ctrl[e] for e in [*e0, *e1); entry
 * e's value is seam_tie_value(o, t, e). */
static inline void seam_tie_row(const sem_object *o, int t, int *e0, int *e1)
{
    int k = o->seam_tie_pair[t];
    *e0 = o->seams.row_start[2 * k];
    *e1 = o->seams.row_start[2 * k + 2];
}
static inline double seam_tie_value(const sem_object *o, int t, int e)
{
    int k = o->seam_tie_pair[t];
    return e < o->seams.row_start[2 * k + 1] ? o->seams.row_w[e] : -o->seams.row_w[e];
}

/* The largest group (at least 1). */
size_t sem_max_group_size(const sem_object *o);

#endif
