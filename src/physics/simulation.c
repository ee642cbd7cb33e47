/*
 * simulation.c - SEM elastodynamics (paper Sec. 7, Alg. 2).
 *
 * Design. The elastic Hessian of SEM is K = sum_p vol_p B_p^T (d2psi/dF2) B_p with
 * B_p = sum_i w_pi (grad b_i)^T Pi_i (Eq. 15). Forming B_p over control points is wasteful:
 * a quadrature point sees only the few parts with non-zero weight there, but through Pi
 * each part couples every control point of the parts sharing its origin. So the work is
 * split the way the maths factors:
 *
 *   1. z-space (polynomial coefficients, m per part per coordinate, written in one basis
 *      b(X - ref) shared by all parts; see setup_stiffness): per point, the local 3x3
 *      deformation gradient, psi, P, d2psi/dF2 and its pull-back N_p to the shared basis;
 *      then per *part pair* the 3m x 3m block sum_p w_a w_b N_p.
 *   2. q-space: K_q = Pi^T K_z Pi. Pi_i's columns are exactly the control points of the
 *      parts sharing part i's origin (its "group"), so K_q is made of dense blocks per
 *      *group pair*; each part-pair block adds Pi_i^T K_z Pi_i' into one group-pair block
 *      with dgemm (per coordinate pair).
 *   3. The group-pair blocks are scattered, through a map computed once, into the fixed
 *      CSC pattern of the free degrees of freedom for CHOLMOD (or a dense matrix).
 *
 * The mass matrix M (with per-point density) and the error matrix M_eps (Eq. 16) are
 * constant and kept as scalar group-pair blocks. Error energy: gamma * sum_s a_s
 * |Gamma_s q - J_s q|^2 = gamma q^T M_eps q, so its Hessian is 2 gamma M_eps.
 *
 * Pinned control points are eliminated: only free dofs enter the solve; prescribed
 * motion of pinned points enters the right-hand side through A_fp.
 *
 * Every per-point Hessian is projected to positive semi-definite before assembly, for the
 * linearly implicit step too: the paper's neo-Hookean Hessian becomes indefinite under
 * compression, and then M + h^2 K can lose definiteness and Cholesky fails. Newton (statics
 * and implicit Euler) switches to the exact Hessian once its steps are full: the clamped
 * eigenvalues are the compressed fibres' geometric stiffness, and without them Newton only
 * converges linearly (by about half per iteration on the bent cantilever). If the exact
 * system is not positive definite, Newton falls back to the projected one for the rest of
 * that solve.
 *
 * Determinism: per-thread accumulators reduced in thread order; the thread count is fixed
 * by the world definition (or OMP_NUM_THREADS).
 */
#include "sem/simulation.h"

#include <cblas.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <stdio.h>
#include <string.h>

#include "linear_solver.h"
#include "simulation_internal.h"

typedef struct object {
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
    /* stiffness in one shared basis (see assemble_elastic) */
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
    int n_orphans;             /* control points tied to their part's polynomial (no samples) */
    /* forces */
    double *f_gravity;         /* 3 n_ctrl */
    double gamma;
    /* free dofs */
    unsigned char *pinned;
    int *presc_index;          /* per ctrl: prescription followed, or -1 (stays put) */
    sem_prescribe *presc;
    int n_presc;
    int *free_index;           /* per ctrl: free index or -1 */
    int n_free;
    int *map;                  /* per block entry (9 per scalar entry): CSC position or -1 */
    sem_linear_solver *solver;
    /* z-space work */
    double *z;                 /* n_parts*ma x 3: shared-basis coefficients */
    double *grad_z;            /* n_parts*ma x 3 */
    double *Kz;                /* n_pairs x (3ma)^2, for pairs with points (Kz_ba = Kz_ab) */
    int nthreads;
    int exact_hessian;         /* 1: skip the PSD projection (Newton near a minimum) */
    double *grad_z_share;      /* GRADIENT_SHARES x n_parts*ma x 3 (see assemble_elastic) */
    double *qc;                /* q minus its mean, 3 n_ctrl (see centered) */
    double elastic_energy;
    double volume, mass;
} object;

struct sem_world {
    sem_world_def def;
    int n_objects, cap;
    object **objects;
    double time;
    int step_index;
    double last_step_s, last_factor_s;
    int last_iterations;
};

sem_world_def sem_default_world_def(void)
{
    sem_world_def d;
    memset(&d, 0, sizeof d);
    d.gravity[2] = -9.81;
    d.integrator = SEM_LINEARLY_IMPLICIT_EULER;
    d.dt = 0.01;
    d.newton_tolerance = 1e-8;
    d.newton_max_iterations = 50;
    d.solver = SEM_SOLVER_AUTO;
    return d;
}

sem_object_def sem_default_object_def(void)
{
    sem_object_def d;
    memset(&d, 0, sizeof d);
    d.material = sem_default_material();
    return d;
}

sem_world *sem_world_create(const sem_world_def *def, sem_error *err)
{
    if (!(def->dt > 0) || !isfinite(def->dt)) {
        sem_error_set(err, SEM_ERR_INVALID, "time step dt must be positive (got %g)", def->dt);
        return NULL;
    }
    for (int k = 0; k < 3; ++k)
        if (!isfinite(def->gravity[k])) {
            sem_error_set(err, SEM_ERR_INVALID, "gravity must be finite");
            return NULL;
        }
    if (def->rayleigh_mass < 0 || def->rayleigh_stiffness < 0) {
        sem_error_set(err, SEM_ERR_INVALID, "Rayleigh damping coefficients must be >= 0");
        return NULL;
    }
    sem_world *w = calloc(1, sizeof *w);
    if (!w) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        return NULL;
    }
    w->def = *def;
    if (w->def.newton_tolerance <= 0) w->def.newton_tolerance = 1e-8;
    if (w->def.newton_max_iterations <= 0) w->def.newton_max_iterations = 50;
    return w;
}

static void object_destroy(object *o)
{
    if (!o) return;
    free(o->q);
    free(o->v);
    free(o->q0);
    free(o->point_material);
    free(o->point_rho_vol);
    free(o->entry_basis);
    free(o->entry_pair_offset);
    free(o->part_mats);
    free(o->point_pairs);
    free(o->pair_a);
    free(o->pair_b);
    free(o->pair_lookup);
    free(o->group_start);
    free(o->group_ctrl);
    free(o->ctrl_group);
    free(o->ctrl_local);
    if (o->pi_dense)
        for (int i = 0; i < o->n_parts; ++i) free(o->pi_dense[i]);
    free(o->pi_dense);
    if (o->pi_shared)
        for (int i = 0; i < o->n_parts; ++i) free(o->pi_shared[i]);
    free(o->pi_shared);
    free(o->point_D);
    free(o->plist_start);
    free(o->plist_point);
    free(o->plist_w);
    free(o->plist_cursor);
    free(o->N_chunk);
    free(o->Kz_packed);
    free(o->gpair_a);
    free(o->gpair_b);
    free(o->gpair_lookup);
    free(o->gpair_offset);
    free(o->part_pair_gpair);
    free(o->gpair_pairs_start);
    free(o->gpair_pairs);
    free(o->K_blocks);
    free(o->M_blocks);
    free(o->E_blocks);
    free(o->me_start);
    free(o->me_col);
    free(o->me_M);
    free(o->me_E);
    free(o->K0_blocks);
    free(o->f_gravity);
    free(o->pinned);
    free(o->presc_index);
    free(o->presc);
    free(o->free_index);
    free(o->map);
    sem_linear_solver_destroy(o->solver);
    free(o->z);
    free(o->grad_z);
    free(o->Kz);
    free(o->qc);
    free(o->grad_z_share);
    free((void *)o->def.point_loads);
    free((void *)o->def.region_loads);
    free(o);
}

void sem_world_destroy(sem_world *w)
{
    if (!w) return;
    for (int i = 0; i < w->n_objects; ++i) object_destroy(w->objects[i]);
    free(w->objects);
    free(w);
}

/* ---------------------------------------------------------------------------------- */
/* setup                                                                               */

static size_t gsize(const object *o, int g)
{
    return (size_t)(o->group_start[g + 1] - o->group_start[g]);
}

static sem_status setup_groups(object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    int ng = d->n_origins;
    o->n_groups = ng;
    o->group_start = calloc((size_t)ng + 1, sizeof(int));
    o->group_ctrl = malloc((size_t)o->n_ctrl * sizeof(int));
    o->ctrl_group = malloc((size_t)o->n_ctrl * sizeof(int));
    o->ctrl_local = malloc((size_t)o->n_ctrl * sizeof(int));
    if (!o->group_start || !o->group_ctrl || !o->ctrl_group || !o->ctrl_local)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        if (g < 0 || g >= ng)
            return sem_error_set(err, SEM_ERR_INVALID, "part %d has no valid origin", i);
        o->group_start[g + 1] += d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i];
    }
    for (int g = 0; g < ng; ++g) o->group_start[g + 1] += o->group_start[g];
    int *fill = malloc((size_t)ng * sizeof(int));
    if (!fill) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(fill, o->group_start, (size_t)ng * sizeof(int));
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        for (int c = d->part_ctrl_offset[i]; c < d->part_ctrl_offset[i + 1]; ++c) {
            o->ctrl_group[c] = g;
            o->ctrl_local[c] = fill[g] - o->group_start[g];
            o->group_ctrl[fill[g]++] = c;
        }
    }
    free(fill);
    /* dense Pi per part over its group's control points */
    o->pi_dense = calloc((size_t)(o->n_parts > 0 ? o->n_parts : 1), sizeof(double *));
    if (!o->pi_dense) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    int m = o->m;
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        size_t n = gsize(o, g);
        o->pi_dense[i] = calloc((size_t)m * n, sizeof(double));
        if (!o->pi_dense[i]) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int k = 0; k < m; ++k) {
            int row = i * m + k;
            for (int e = d->Pi.row_start[row]; e < d->Pi.row_start[row + 1]; ++e) {
                int c = d->Pi.col[e];
                if (o->ctrl_group[c] != g)
                    return sem_error_set(err, SEM_ERR_INVALID,
                                         "projection of part %d reaches a control point outside "
                                         "its origin's parts",
                                         i);
                o->pi_dense[i][(size_t)k * n + (size_t)o->ctrl_local[c]] = d->Pi.val[e];
            }
        }
    }
    return SEM_OK;
}

/* Part pairs from the weights at quadrature points and boundary samples; group pairs
 * from part pairs and from the error matrix. */
static sem_status setup_pairs(object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    int np = o->n_parts, ng = o->n_groups;
    o->pair_lookup = malloc((size_t)np * np * sizeof(int));
    o->gpair_lookup = malloc((size_t)ng * ng * sizeof(int));
    if (!o->pair_lookup || !o->gpair_lookup) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (size_t k = 0; k < (size_t)np * np; ++k) o->pair_lookup[k] = -1;
    for (size_t k = 0; k < (size_t)ng * ng; ++k) o->gpair_lookup[k] = -1;
    int cap = 64;
    o->pair_a = malloc((size_t)cap * sizeof(int));
    o->pair_b = malloc((size_t)cap * sizeof(int));
    if (!o->pair_a || !o->pair_b) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    const sem_csr *Ws[2] = {&d->W, &d->W_samples};
    for (int w = 0; w < 2; ++w) {
        const sem_csr *W = Ws[w];
        for (int p = 0; p < W->n_rows; ++p)
            for (int a = W->row_start[p]; a < W->row_start[p + 1]; ++a)
                for (int b = W->row_start[p]; b < W->row_start[p + 1]; ++b) {
                    int i = W->col[a], j = W->col[b];
                    if (o->pair_lookup[(size_t)i * np + j] >= 0) continue;
                    if (o->n_pairs == cap) {
                        cap *= 2;
                        int *x = realloc(o->pair_a, (size_t)cap * sizeof(int));
                        if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                        o->pair_a = x;
                        x = realloc(o->pair_b, (size_t)cap * sizeof(int));
                        if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                        o->pair_b = x;
                    }
                    o->pair_lookup[(size_t)i * np + j] = o->n_pairs;
                    o->pair_a[o->n_pairs] = i;
                    o->pair_b[o->n_pairs] = j;
                    o->n_pairs++;
                }
    }
    /* group pairs: from part pairs, and from the error matrix's pattern */
    o->part_pair_gpair = malloc((size_t)o->n_pairs * sizeof(int));
    int gcap = 64;
    o->gpair_a = malloc((size_t)gcap * sizeof(int));
    o->gpair_b = malloc((size_t)gcap * sizeof(int));
    if (!o->part_pair_gpair || !o->gpair_a || !o->gpair_b)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
#define ADD_GPAIR(ga, gb)                                                                   \
    do {                                                                                    \
        size_t key_ = (size_t)(ga) * ng + (size_t)(gb);                                     \
        if (o->gpair_lookup[key_] < 0) {                                                    \
            if (o->n_gpairs == gcap) {                                                      \
                gcap *= 2;                                                                  \
                int *x_ = realloc(o->gpair_a, (size_t)gcap * sizeof(int));                  \
                if (!x_) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");         \
                o->gpair_a = x_;                                                            \
                x_ = realloc(o->gpair_b, (size_t)gcap * sizeof(int));                       \
                if (!x_) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");         \
                o->gpair_b = x_;                                                            \
            }                                                                               \
            o->gpair_lookup[key_] = o->n_gpairs;                                            \
            o->gpair_a[o->n_gpairs] = (ga);                                                 \
            o->gpair_b[o->n_gpairs] = (gb);                                                 \
            o->n_gpairs++;                                                                  \
        }                                                                                   \
    } while (0)
    for (int k = 0; k < o->n_pairs; ++k) {
        int ga = d->part_origin[o->pair_a[k]], gb = d->part_origin[o->pair_b[k]];
        ADD_GPAIR(ga, gb);
        o->part_pair_gpair[k] = o->gpair_lookup[(size_t)ga * ng + gb];
    }
    for (int r = 0; r < d->M_eps.n_rows; ++r)
        for (int e = d->M_eps.row_start[r]; e < d->M_eps.row_start[r + 1]; ++e) {
            int ga = o->ctrl_group[r], gb = o->ctrl_group[d->M_eps.col[e]];
            ADD_GPAIR(ga, gb);
        }
    for (int r = 0; r < d->M.n_rows; ++r)
        for (int e = d->M.row_start[r]; e < d->M.row_start[r + 1]; ++e) {
            int ga = o->ctrl_group[r], gb = o->ctrl_group[d->M.col[e]];
            ADD_GPAIR(ga, gb);
        }
#undef ADD_GPAIR
    o->gpair_offset = malloc(((size_t)o->n_gpairs + 1) * sizeof(size_t));
    if (!o->gpair_offset) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    o->gpair_offset[0] = 0;
    for (int k = 0; k < o->n_gpairs; ++k)
        o->gpair_offset[k + 1] = o->gpair_offset[k] + gsize(o, o->gpair_a[k]) * gsize(o, o->gpair_b[k]);
    /* part pairs per group pair (for a parallel, race-free Pi^T Kz Pi) */
    o->gpair_pairs_start = calloc((size_t)o->n_gpairs + 1, sizeof(int));
    o->gpair_pairs = malloc(((size_t)o->n_pairs + 1) * sizeof(int));
    if (!o->gpair_pairs_start || !o->gpair_pairs) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int k = 0; k < o->n_pairs; ++k) o->gpair_pairs_start[o->part_pair_gpair[k] + 1]++;
    for (int g = 0; g < o->n_gpairs; ++g) o->gpair_pairs_start[g + 1] += o->gpair_pairs_start[g];
    int *fill = malloc(((size_t)o->n_gpairs + 1) * sizeof(int));
    if (!fill) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(fill, o->gpair_pairs_start, (size_t)o->n_gpairs * sizeof(int));
    for (int k = 0; k < o->n_pairs; ++k) o->gpair_pairs[fill[o->part_pair_gpair[k]]++] = k;
    free(fill);
    /* within a group pair, pairs with the same first part are consecutive (see the
     * projection in assemble_elastic) */
    for (int g = 0; g < o->n_gpairs; ++g) {
        int a = o->gpair_pairs_start[g], b = o->gpair_pairs_start[g + 1];
        for (int k = a + 1; k < b; ++k) {
            int x = o->gpair_pairs[k], j = k - 1;
            while (j >= a && o->pair_a[o->gpair_pairs[j]] > o->pair_a[x]) {
                o->gpair_pairs[j + 1] = o->gpair_pairs[j];
                --j;
            }
            o->gpair_pairs[j + 1] = x;
        }
    }
    size_t total = o->gpair_offset[o->n_gpairs];
    o->K_blocks = calloc(9 * total + 1, sizeof(double));
    o->K0_blocks = calloc(9 * total + 1, sizeof(double));
    o->M_blocks = calloc(total + 1, sizeof(double));
    o->E_blocks = calloc(total + 1, sizeof(double));
    if (!o->K_blocks || !o->K0_blocks || !o->M_blocks || !o->E_blocks)
        return sem_error_set(err, SEM_ERR_NOMEM,
                             "out of memory for the system blocks (%zu entries)", 9 * total);
    return SEM_OK;
}

/* Per-point data in z-space: w * b at X_p - Xbar_i for each weight entry (mass), and the
 * point's part pairs. */
static sem_status setup_points(object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    size_t n_entries = sem_csr_nnz(W);
    int m = o->m;
    o->entry_basis = malloc((n_entries * (size_t)m + 1) * sizeof(double));
    o->entry_pair_offset = malloc(((size_t)o->n_quad + 1) * sizeof(int));
    if (!o->entry_basis || !o->entry_pair_offset)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    size_t n_pp = 0;
    o->entry_pair_offset[0] = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        size_t k = (size_t)(W->row_start[p + 1] - W->row_start[p]);
        n_pp += k * k;
        o->entry_pair_offset[p + 1] = (int)n_pp;
    }
    o->point_pairs = malloc((n_pp + 1) * sizeof(int));
    if (!o->point_pairs) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
#pragma omp parallel for schedule(static)
    for (int p = 0; p < o->n_quad; ++p) {
        const double *X = d->quad_X + 3 * (size_t)p;
        int r0 = W->row_start[p], r1 = W->row_start[p + 1];
        int pp = o->entry_pair_offset[p];
        for (int r = r0; r < r1; ++r) {
            int i = W->col[r];
            const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
            double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]};
            double b[10];
            sem_polynomial_basis(o->d->order, dX, b, NULL);
            double w = W->val[r];
            for (int k = 0; k < m; ++k) o->entry_basis[(size_t)r * m + k] = w * b[k];
            for (int r2 = r0; r2 < r1; ++r2)
                o->point_pairs[pp++] = o->pair_lookup[(size_t)i * o->n_parts + W->col[r2]];
        }
    }
    return SEM_OK;
}

#define DEFAULT_ASSEMBLY_CHUNK 8192
static int assembly_chunk = DEFAULT_ASSEMBLY_CHUNK;

static int exact_hessian_policy = 1;
static long exact_hessian_fallbacks;

int sem_simulation_set_exact_hessian(int on)
{
    int old = exact_hessian_policy;
    exact_hessian_policy = on != 0;
    return old;
}

long sem_simulation_exact_hessian_fallbacks(void)
{
    return exact_hessian_fallbacks;
}

void sem_simulation_set_assembly_chunk(int points)
{
    assembly_chunk = points > 0 ? points : DEFAULT_ASSEMBLY_CHUNK;
}

/* Part pair pr is a <= b and shares a quadrature point: its stiffness block Kz is formed
 * (W rows list parts in increasing order). */
static int pair_has_points(const object *o, int pr)
{
    return o->plist_start[pr + 1] > o->plist_start[pr];
}

/* T with b(y + s) = T b(y) for the polynomial basis (m x m, row-major): the change from a
 * part's own basis, b(X - Xbar_i) with s = ref_X - Xbar_i, to the shared one, b(X - ref_X). */
static void basis_shift(int m, const double s[3], double *T)
{
    memset(T, 0, (size_t)m * m * sizeof(double));
    for (int k = 0; k < m; ++k) T[k * m + k] = 1.0;
    for (int e = 0; e < 3; ++e) T[(1 + e) * m] = s[e];
    if (m < 10) return;
    /* b4..b9 = xy, xz, yz, x^2, y^2, z^2 */
    static const int pa[6] = {0, 0, 1, 0, 1, 2}, pb[6] = {1, 2, 2, 0, 1, 2};
    for (int q = 0; q < 6; ++q) {
        double *row = T + (size_t)(4 + q) * m;
        int a = pa[q], b = pb[q];
        row[0] = s[a] * s[b];
        row[1 + a] += s[b];
        row[1 + b] += s[a];
    }
}

/* The stiffness in one shared basis. With Eq. 15, a part's contribution to F at point p
 * is w_i (grad b(X_p - Xbar_i))^T z_i = w_i (grad b(X_p - ref))^T (T_i^T z_i): every part
 * at p shares the point's D_p = grad b(X_p - ref), so a part pair's block is
 *   Kz_ab = sum_p w_a w_b N_p,   N_p = vol_p D_p^T (d2psi/dF2) D_p (per coordinate pair),
 * N_p is computed once per point (not once per part pair), and Kz_ab = Kz_ba is symmetric.
 * The change of basis goes into Pi: pi_shared_i = T_i^T Pi_i. The constant basis function
 * has no gradient, so only rows 1..m-1 take part. */
static sem_status setup_stiffness(object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    int m = o->m, ma = m - 1;
    o->ma = ma;
    /* the shared origin: the volume centroid (keeps the monomials small) */
    double vsum = 0;
    for (int k = 0; k < 3; ++k) o->ref_X[k] = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        double v = d->quad_volume[p];
        vsum += v;
        for (int k = 0; k < 3; ++k) o->ref_X[k] += v * d->quad_X[3 * (size_t)p + k];
    }
    for (int k = 0; k < 3; ++k) o->ref_X[k] = vsum > 0 ? o->ref_X[k] / vsum : 0;
    o->pi_shared = calloc((size_t)(o->n_parts > 0 ? o->n_parts : 1), sizeof(double *));
    if (!o->pi_shared) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < o->n_parts; ++i) {
        const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
        double sh[3] = {o->ref_X[0] - Xb[0], o->ref_X[1] - Xb[1], o->ref_X[2] - Xb[2]}, T[100];
        basis_shift(m, sh, T);
        size_t n = gsize(o, d->part_origin[i]);
        double *ps = o->pi_shared[i] = calloc((size_t)ma * n + 1, sizeof(double));
        if (!ps) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int l = 1; l < m; ++l)
            for (int k = 0; k < m; ++k) {
                double t = T[k * m + l];
                if (t == 0) continue;
                const double *src = o->pi_dense[i] + (size_t)k * n;
                double *dst = ps + (size_t)(l - 1) * n;
                for (size_t j = 0; j < n; ++j) dst[j] += t * src[j];
            }
    }
    o->point_D = malloc(((size_t)o->n_quad * ma * 3 + 1) * sizeof(double));
    if (!o->point_D) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int p = 0; p < o->n_quad; ++p) {
        const double *X = d->quad_X + 3 * (size_t)p;
        double y[3] = {X[0] - o->ref_X[0], X[1] - o->ref_X[1], X[2] - o->ref_X[2]}, db[30];
        sem_polynomial_basis(o->d->order, y, NULL, db);
        double *D = o->point_D + (size_t)p * ma * 3;
        for (int k = 1; k < m; ++k)
            for (int e = 0; e < 3; ++e) D[(k - 1) * 3 + e] = db[e * m + k];
    }
    /* the points of each upper part pair, in point order, with w_a w_b */
    o->plist_start = calloc((size_t)o->n_pairs + 1, sizeof(int));
    o->plist_cursor = malloc(((size_t)o->n_pairs + 1) * sizeof(int));
    if (!o->plist_start || !o->plist_cursor) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int p = 0; p < o->n_quad; ++p)
        for (int r = W->row_start[p]; r < W->row_start[p + 1]; ++r)
            for (int r2 = r; r2 < W->row_start[p + 1]; ++r2)
                o->plist_start[o->pair_lookup[(size_t)W->col[r] * o->n_parts + W->col[r2]] + 1]++;
    for (int k = 0; k < o->n_pairs; ++k) o->plist_start[k + 1] += o->plist_start[k];
    size_t nl = (size_t)o->plist_start[o->n_pairs];
    o->plist_point = malloc((nl + 1) * sizeof(int));
    o->plist_w = malloc((nl + 1) * sizeof(double));
    if (!o->plist_point || !o->plist_w) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(o->plist_cursor, o->plist_start, (size_t)o->n_pairs * sizeof(int));
    for (int p = 0; p < o->n_quad; ++p)
        for (int r = W->row_start[p]; r < W->row_start[p + 1]; ++r)
            for (int r2 = r; r2 < W->row_start[p + 1]; ++r2) {
                int pr = o->pair_lookup[(size_t)W->col[r] * o->n_parts + W->col[r2]];
                o->plist_point[o->plist_cursor[pr]] = p;
                o->plist_w[o->plist_cursor[pr]++] = W->val[r] * W->val[r2];
            }
    int n3 = 3 * ma;
    o->n_packed = n3 * (n3 + 1) / 2;
    /* points are assembled in chunks so that N stays small (25 MB at most) */
    o->chunk = o->n_quad < assembly_chunk ? (o->n_quad > 0 ? o->n_quad : 1) : assembly_chunk;
    o->N_chunk = malloc(((size_t)o->chunk * o->n_packed + 1) * sizeof(double));
    o->Kz = malloc(((size_t)o->n_pairs * n3 * n3 + 1) * sizeof(double));
    o->Kz_packed = o->chunk < o->n_quad
                       ? malloc(((size_t)o->n_pairs * o->n_packed + 1) * sizeof(double))
                       : calloc(1, sizeof(double));
    if (!o->N_chunk || !o->Kz || !o->Kz_packed)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the stiffness blocks");
    return SEM_OK;
}

/* Adds Pi_a^T X Pi_b for a part pair into its group-pair block. X is m x m with leading
 * dimension ldx; block is |Ga| x |Gb| row-major; tmp has room for m x |Gb|. */
static void add_projected(const object *o, int pa, int pb, const double *X, int ldx, double *block,
                          double *tmp)
{
    int m = o->m;
    int na = (int)gsize(o, o->d->part_origin[pa]), nb = (int)gsize(o, o->d->part_origin[pb]);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, m, nb, m, 1.0, X, ldx, o->pi_dense[pb],
                nb, 0.0, tmp, nb);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, na, nb, m, 1.0, o->pi_dense[pa], na, tmp,
                nb, 1.0, block, nb);
}

static size_t max_group(const object *o)
{
    size_t mx = 1;
    for (int g = 0; g < o->n_groups; ++g)
        if (gsize(o, g) > mx) mx = gsize(o, g);
    return mx;
}

/* Constant blocks: mass with per-point density, and the error matrix. */
static sem_status setup_constant_blocks(object *o, sem_error *err)
{
    int m = o->m, np = o->n_pairs;
    double *Mz = calloc((size_t)np * m * m + 1, sizeof(double));
    if (!Mz) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    const sem_csr *W = &o->d->W;
    for (int p = 0; p < o->n_quad; ++p) {
        double rv = o->point_rho_vol[p];
        int r0 = W->row_start[p], r1 = W->row_start[p + 1];
        int pp = o->entry_pair_offset[p];
        for (int a = r0; a < r1; ++a)
            for (int b = r0; b < r1; ++b) {
                double *blk = Mz + (size_t)o->point_pairs[pp++] * m * m;
                const double *ba = o->entry_basis + (size_t)a * m, *bb = o->entry_basis + (size_t)b * m;
                for (int k = 0; k < m; ++k)
                    for (int l = 0; l < m; ++l) blk[k * m + l] += rv * ba[k] * bb[l];
            }
    }
    size_t mg = max_group(o);
    double *tmp = malloc((size_t)m * mg * sizeof(double));
    if (!tmp) {
        free(Mz);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < np; ++k) {
        int g = o->part_pair_gpair[k];
        add_projected(o, o->pair_a[k], o->pair_b[k], Mz + (size_t)k * m * m, m,
                      o->M_blocks + o->gpair_offset[g], tmp);
    }
    free(tmp);
    free(Mz);
    /* Control points that no boundary sample sees (their basis functions are supported
     * only where a trim removed the surface) appear in no term of the discretization, so
     * the system would be singular. Each such point is tied to its own part's polynomial
     * at its rest position: residual q_c - b(X_c - Xbar)^T Pi_i Q, weighted like a typical
     * control point's error term. It vanishes for every affine motion (the control points
     * of an affinely mapped NURBS are affinely mapped), so the patch test is unaffected. */
    {
        const sem_csr *J = &o->d->J_hat;
        double *colw = calloc((size_t)o->n_ctrl + 1, sizeof(double));
        if (!colw) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int r = 0; r < J->n_rows; ++r)
            for (int e = J->row_start[r]; e < J->row_start[r + 1]; ++e)
                colw[J->col[e]] += o->d->sample_area[r] * J->val[e] * J->val[e];
        double mean = 0;
        for (int c = 0; c < o->n_ctrl; ++c) mean += colw[c];
        mean /= o->n_ctrl > 0 ? o->n_ctrl : 1;
        double *row = malloc(mg * sizeof(double) + 1);
        if (!row) {
            free(colw);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        o->n_orphans = 0;
        for (int i = 0; i < o->n_parts; ++i) {
            int g = o->d->part_origin[i];
            size_t n = gsize(o, g);
            int gp = o->gpair_lookup[(size_t)g * o->n_groups + g];
            if (gp < 0) continue;
            for (int c = o->d->part_ctrl_offset[i]; c < o->d->part_ctrl_offset[i + 1]; ++c) {
                if (colw[c] > 1e-10 * mean) continue;
                const double *X = o->q0 + 3 * (size_t)c, *Xb = o->d->origin_X + 3 * (size_t)g;
                double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, b[10];
                sem_polynomial_basis(o->d->order, dX, b, NULL);
                for (size_t l = 0; l < n; ++l) {
                    double v = 0;
                    for (int k = 0; k < m; ++k) v += b[k] * o->pi_dense[i][(size_t)k * n + l];
                    row[l] = -v;
                }
                row[o->ctrl_local[c]] += 1.0;
                double *blk = o->E_blocks + o->gpair_offset[gp];
                for (size_t a = 0; a < n; ++a)
                    if (row[a] != 0)
                        for (size_t bb = 0; bb < n; ++bb) blk[a * n + bb] += mean * row[a] * row[bb];
                o->n_orphans++;
            }
        }
        free(row);
        free(colw);
    }
    /* Error matrix (Eq. 16) as a sum of outer products of r_s = Gamma_s - J_s, so it is
     * positive semi-definite by construction. The factored form Pi^T(...)Pi - ... + J^T A J
     * cancels large terms, and its round-off can leave small negative eigenvalues exactly in
     * the directions the mass matrix does not see (M has rank at most the number of
     * quadrature points per coordinate), which makes M + h^2 (K + 2 gamma M_eps) indefinite. */
    {
        const sem_csr *G = &o->d->Gamma_samples, *J = &o->d->J_hat;
        int *rc = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
        double *rv = malloc(((size_t)o->n_ctrl + 1) * sizeof(double));
        if (!rc || !rv) {
            free(rc);
            free(rv);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        /* A collapsed edge (a sphere's pole) has a zero area element, so its samples would
         * drop out, and with them the only information that fixes the control points of the
         * collapsed row: the system becomes singular. Every sample keeps at least 5% of its
         * part's mean sample weight. */
        double *part_mean = calloc((size_t)o->n_parts + 1, sizeof(double));
        int *part_count = calloc((size_t)o->n_parts + 1, sizeof(int));
        if (!part_mean || !part_count) {
            free(part_mean);
            free(part_count);
            free(rc);
            free(rv);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        for (int r = 0; r < o->d->n_samples; ++r) {
            part_mean[o->d->sample_part[r]] += o->d->sample_area[r];
            part_count[o->d->sample_part[r]]++;
        }
        for (int i = 0; i < o->n_parts; ++i)
            if (part_count[i]) part_mean[i] /= part_count[i];
        for (int r = 0; r < G->n_rows; ++r) {
            /* merge the sorted rows of Gamma_s and J_s */
            int a = G->row_start[r], ae = G->row_start[r + 1], b = J->row_start[r], be = J->row_start[r + 1];
            int n = 0;
            while (a < ae || b < be) {
                if (b >= be || (a < ae && G->col[a] < J->col[b])) {
                    rc[n] = G->col[a];
                    rv[n++] = G->val[a++];
                } else if (a >= ae || J->col[b] < G->col[a]) {
                    rc[n] = J->col[b];
                    rv[n++] = -J->val[b++];
                } else {
                    rc[n] = G->col[a];
                    rv[n++] = G->val[a++] - J->val[b++];
                }
            }
            double area = fmax(o->d->sample_area[r], 0.05 * part_mean[o->d->sample_part[r]]);
            for (int x = 0; x < n; ++x) {
                int gx = o->ctrl_group[rc[x]];
                double ax = area * rv[x];
                if (ax == 0) continue;
                for (int y = 0; y < n; ++y) {
                    int gy = o->ctrl_group[rc[y]];
                    int gp = o->gpair_lookup[(size_t)gx * o->n_groups + gy];
                    if (gp < 0) {
                        free(part_mean);
                        free(part_count);
                        free(rc);
                        free(rv);
                        return sem_error_set(err, SEM_ERR_INVALID, "error matrix pattern outside the system pattern");
                    }
                    size_t nb = gsize(o, gy);
                    o->E_blocks[o->gpair_offset[gp] + (size_t)o->ctrl_local[rc[x]] * nb + (size_t)o->ctrl_local[rc[y]]] +=
                        ax * rv[y];
                }
            }
        }
        free(part_mean);
        free(part_count);
        free(rc);
        free(rv);
    }
    return SEM_OK;
}

/* M and E_blocks as CSR rows over control points, for products with them alone (the
 * right-hand side and the error force of every step) run in parallel by rows. */
static sem_status setup_constant_csr(object *o, sem_error *err)
{
    int nc = o->n_ctrl;
    o->me_start = calloc((size_t)nc + 1, sizeof(int));
    if (!o->me_start) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], nb = (int)gsize(o, o->gpair_b[g]);
        for (int x = o->group_start[ga]; x < o->group_start[ga + 1]; ++x) o->me_start[o->group_ctrl[x] + 1] += nb;
    }
    for (int c = 0; c < nc; ++c) o->me_start[c + 1] += o->me_start[c];
    size_t nnz = (size_t)o->me_start[nc];
    o->me_col = malloc((nnz + 1) * sizeof(int));
    o->me_M = malloc((nnz + 1) * sizeof(double));
    o->me_E = malloc((nnz + 1) * sizeof(double));
    int *fill = malloc(((size_t)nc + 1) * sizeof(int));
    if (!o->me_col || !o->me_M || !o->me_E || !fill) {
        free(fill);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    memcpy(fill, o->me_start, (size_t)nc * sizeof(int));
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], gb = o->gpair_b[g];
        size_t na = gsize(o, ga), nb = gsize(o, gb), off = o->gpair_offset[g];
        const int *ca = o->group_ctrl + o->group_start[ga], *cb = o->group_ctrl + o->group_start[gb];
        for (size_t la = 0; la < na; ++la)
            for (size_t lb = 0; lb < nb; ++lb) {
                int k = fill[ca[la]]++;
                o->me_col[k] = cb[lb];
                o->me_M[k] = o->M_blocks[off + la * nb + lb];
                o->me_E[k] = o->E_blocks[off + la * nb + lb];
            }
    }
    free(fill);
    return SEM_OK;
}

/* CSC pattern of the free system (upper triangle) and the map from block entries. The
 * system is symmetric and its blocks are formed for group pairs ga <= gb only: an entry of
 * such a block maps to its own position or to its mirror's; blocks ga > gb map nowhere. */
static sem_status setup_system(object *o, const sem_world_def *wd, sem_error *err)
{
    int nf = 3 * o->n_free;
    size_t total = o->gpair_offset[o->n_gpairs];
    o->map = malloc((9 * total + 1) * sizeof(int));
    int *count = calloc((size_t)nf + 1, sizeof(int));
    if (!o->map || !count) {
        free(count);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
    }
    /* pass 1: count entries per column (row <= col) */
    for (int pass = 0; pass < 2; ++pass) {
        int *rows = NULL;
        int *fill = NULL;
        if (pass == 1) {
            for (int c = 0; c < nf; ++c) count[c + 1] += count[c];
            rows = malloc(((size_t)count[nf] + 1) * sizeof(int));
            fill = malloc(((size_t)nf + 1) * sizeof(int));
            if (!rows || !fill) {
                free(rows);
                free(fill);
                free(count);
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
            }
            memcpy(fill, count, (size_t)nf * sizeof(int));
        }
        for (int g = 0; g < o->n_gpairs; ++g) {
            int ga = o->gpair_a[g], gb = o->gpair_b[g];
            size_t na = gsize(o, ga), nb = gsize(o, gb);
            for (size_t la = 0; la < na; ++la) {
                int fa = o->free_index[o->group_ctrl[o->group_start[ga] + la]];
                for (size_t lb = 0; lb < nb; ++lb) {
                    int fb = o->free_index[o->group_ctrl[o->group_start[gb] + lb]];
                    for (int dd = 0; dd < 9; ++dd) {
                        int d1 = dd / 3, d2 = dd % 3;
                        size_t idx = 9 * o->gpair_offset[g] + (la * 9 + (size_t)dd) * nb + lb;
                        if (fa < 0 || fb < 0) {
                            if (pass == 1) o->map[idx] = -1;
                            continue;
                        }
                        int r = 3 * fa + d1, c = 3 * fb + d2;
                        if (ga > gb || (ga == gb && r > c)) {
                            if (pass == 1) o->map[idx] = -1;
                            continue;
                        }
                        if (r > c) {
                            int x = r;
                            r = c;
                            c = x;
                        }
                        if (pass == 0)
                            count[c + 1]++;
                        else {
                            rows[fill[c]] = r;
                            o->map[idx] = fill[c]++;
                        }
                    }
                }
            }
        }
        if (pass == 1) {
            /* Each (r,c) occurs once: group pairs are distinct and a control point is in one
             * group. Sort rows within columns and remap positions. */
            int *perm = malloc(((size_t)count[nf] + 1) * sizeof(int));
            int *inv = malloc(((size_t)count[nf] + 1) * sizeof(int));
            if (!perm || !inv) {
                free(perm);
                free(inv);
                free(rows);
                free(fill);
                free(count);
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            }
            for (int c = 0; c < nf; ++c) {
                int a = count[c], b = count[c + 1];
                /* insertion sort is fine for short columns; use counting by row otherwise */
                for (int k = a; k < b; ++k) perm[k] = k;
                for (int k = a + 1; k < b; ++k) {
                    int x = perm[k], j = k - 1;
                    while (j >= a && rows[perm[j]] > rows[x]) {
                        perm[j + 1] = perm[j];
                        --j;
                    }
                    perm[j + 1] = x;
                }
                for (int k = a; k < b; ++k) inv[perm[k]] = k;
            }
            int *sorted = malloc(((size_t)count[nf] + 1) * sizeof(int));
            if (!sorted) {
                free(perm);
                free(inv);
                free(rows);
                free(fill);
                free(count);
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            }
            for (int k = 0; k < count[nf]; ++k) sorted[inv[k]] = rows[k];
            for (size_t k = 0; k < 9 * total; ++k)
                if (o->map[k] >= 0) o->map[k] = inv[o->map[k]];
            sem_status st = sem_linear_solver_create(nf, count, sorted, wd->solver, &o->solver, err);
            if (st == SEM_OK) sem_linear_solver_remap(o->solver, o->map, 9 * total);
            free(sorted);
            free(perm);
            free(inv);
            free(rows);
            free(fill);
            free(count);
            return st;
        }
    }
    free(count);
    return SEM_OK;
}

static const sem_material *material_of_part(const object *o, const sem_object_def *def, int part)
{
    if (def->part_material && o->part_mats) {
        int k = def->part_material[part];
        if (k >= 0 && k < def->n_part_materials) return &o->part_mats[k];
    }
    return &o->def.material;
}

static void compute_gravity(object *o, const double g[3])
{
    const sem_csr *G = &o->d->Gamma;
    double *fp = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    if (!fp) return;
    for (int p = 0; p < o->n_quad; ++p)
        for (int k = 0; k < 3; ++k) fp[3 * p + k] = o->point_rho_vol[p] * g[k];
    sem_csr_multiply_transpose(G, fp, 3, o->f_gravity);
    free(fp);
}

/* The per-point loop of the elastic assembly sums into this many gradient and energy
 * accumulators, each over fixed blocks of points, added in order afterwards: the result is
 * the same bits on any thread count (a per-thread accumulator would depend on it). Blocks
 * are n_quad / (4 x GRADIENT_SHARES) points (rounded up), so every share gets 4 blocks (+-1)
 * and the shares, spread statically over the threads, have equal work. It caps that loop's
 * parallelism at 16 threads. */
#define GRADIENT_SHARES 16

static sem_status assemble_elastic(object *o, const double *q, int want_hessian, double *grad_q,
                                   const double *system, sem_error *err);

int sem_world_add_object(sem_world *w, const sem_object_def *def, sem_error *err)
{
    if (!def->model || !def->disc) {
        sem_error_set(err, SEM_ERR_INVALID, "object needs a model and its discretization");
        return -1;
    }
    const sem_discretization *d = def->disc;
    if ((size_t)d->n_ctrl != sem_model_control_points(def->model) || d->n_parts != def->model->n_parts) {
        sem_error_set(err, SEM_ERR_INVALID, "discretization does not match the model");
        return -1;
    }
    object *o = calloc(1, sizeof *o);
    if (!o) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        return -1;
    }
    o->def = *def;
    /* the caller's arrays are copied where needed; keep no pointer to them */
    o->def.pinned = NULL;
    o->def.prescribe_group = NULL;
    o->def.prescribes = NULL;
    o->def.point_loads = NULL;
    o->def.region_loads = NULL;
    o->def.n_point_loads = 0;
    o->def.n_region_loads = 0;
    if (def->n_point_loads > 0) {
        sem_point_load *pl = malloc((size_t)def->n_point_loads * sizeof *pl);
        if (pl) {
            memcpy(pl, def->point_loads, (size_t)def->n_point_loads * sizeof *pl);
            o->def.point_loads = pl;
            o->def.n_point_loads = def->n_point_loads;
        }
    }
    if (def->n_region_loads > 0) {
        sem_region_load *rl = malloc((size_t)def->n_region_loads * sizeof *rl);
        if (rl) {
            memcpy(rl, def->region_loads, (size_t)def->n_region_loads * sizeof *rl);
            o->def.region_loads = rl;
            o->def.n_region_loads = def->n_region_loads;
        }
    }
    o->d = d;
    o->n_ctrl = d->n_ctrl;
    o->n_parts = d->n_parts;
    o->m = d->n_basis;
    o->n_quad = d->n_quad;
    size_t nq = 3 * (size_t)o->n_ctrl;
    sem_status st = SEM_OK;
    o->q = malloc(nq * sizeof(double));
    o->v = calloc(nq, sizeof(double));
    o->q0 = malloc(nq * sizeof(double));
    o->f_gravity = calloc(nq, sizeof(double));
    o->point_material = malloc(((size_t)o->n_quad + 1) * sizeof(*o->point_material));
    o->point_rho_vol = malloc(((size_t)o->n_quad + 1) * sizeof(double));
    o->pinned = calloc((size_t)o->n_ctrl, 1);
    o->free_index = malloc((size_t)o->n_ctrl * sizeof(int));
    o->z = calloc((size_t)o->n_parts * o->m * 3, sizeof(double));
    o->grad_z = calloc((size_t)o->n_parts * o->m * 3, sizeof(double)); /* room for ma rows */
    if (!o->q || !o->v || !o->q0 || !o->f_gravity || !o->point_material || !o->point_rho_vol ||
        !o->pinned || !o->free_index || !o->z || !o->grad_z) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    /* materials */
    {
        sem_material mat = def->material;
        if ((st = sem_material_init(&mat, err)) != SEM_OK) goto fail;
        o->def.material = mat;
        /* the object keeps initialized copies: the caller's array need not outlive this
         * call, and its Lame parameters need not be set */
        if (def->part_materials && def->n_part_materials > 0) {
            o->part_mats = malloc((size_t)def->n_part_materials * sizeof *o->part_mats);
            if (!o->part_mats) {
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                goto fail;
            }
            for (int k = 0; k < def->n_part_materials; ++k) {
                o->part_mats[k] = def->part_materials[k];
                if ((st = sem_material_init(&o->part_mats[k], err)) != SEM_OK) goto fail;
            }
        }
    }
    sem_model_get_q(def->model, o->q0);
    memcpy(o->q, o->q0, nq * sizeof(double));
    o->volume = 0;
    o->mass = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        int part = d->quad_part ? d->quad_part[p] : 0;
        if (part < 0 || part >= o->n_parts) part = 0;
        const sem_material *mt = material_of_part(o, def, part);
        o->point_material[p] = mt;
        o->point_rho_vol[p] = mt->density * d->quad_volume[p];
        o->volume += d->quad_volume[p];
        o->mass += o->point_rho_vol[p];
    }
    o->def.part_material = NULL; /* the caller's arrays: read above, not kept */
    o->def.part_materials = NULL;
    if (def->pinned) memcpy(o->pinned, def->pinned, (size_t)o->n_ctrl);
    o->presc_index = malloc((size_t)o->n_ctrl * sizeof(int));
    o->n_presc = def->prescribe_group ? def->n_prescribes : 1;
    o->presc = calloc((size_t)(o->n_presc > 0 ? o->n_presc : 1), sizeof(sem_prescribe));
    if (!o->presc_index || !o->presc) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    if (def->prescribe_group) {
        if (def->n_prescribes > 0) memcpy(o->presc, def->prescribes, (size_t)def->n_prescribes * sizeof(sem_prescribe));
        for (int c = 0; c < o->n_ctrl; ++c) {
            int g = def->prescribe_group[c];
            if (g >= def->n_prescribes) {
                sem_error_set(err, SEM_ERR_INVALID, "control point %d: prescribed group %d does not exist", c, g);
                goto fail;
            }
            o->presc_index[c] = g >= 0 ? g : -1;
            if (g >= 0) o->pinned[c] = 1;
        }
    } else {
        o->presc[0] = def->prescribe;
        if (def->prescribe.type != SEM_PRESCRIBE_NONE && !def->pinned)
            memset(o->pinned, 1, (size_t)o->n_ctrl); /* prescribe all control points */
        for (int c = 0; c < o->n_ctrl; ++c)
            o->presc_index[c] = def->prescribe.type != SEM_PRESCRIBE_NONE && o->pinned[c] ? 0 : -1;
    }
    o->n_free = 0;
    for (int c = 0; c < o->n_ctrl; ++c) o->free_index[c] = o->pinned[c] ? -1 : o->n_free++;
    /* error stiffness: the discretization's default is for its E; rescale to ours */
    o->gamma = def->gamma > 0 ? def->gamma : d->gamma;
    if ((st = setup_groups(o, err)) != SEM_OK) goto fail;
    if ((st = setup_pairs(o, err)) != SEM_OK) goto fail;
    if ((st = setup_points(o, err)) != SEM_OK) goto fail;
    if ((st = setup_stiffness(o, err)) != SEM_OK) goto fail;
    if ((st = setup_constant_blocks(o, err)) != SEM_OK) goto fail;
    if ((st = setup_constant_csr(o, err)) != SEM_OK) goto fail;
    o->nthreads = w->def.threads > 0 ? w->def.threads : omp_get_max_threads();
    o->grad_z_share =
        malloc(((size_t)GRADIENT_SHARES * o->n_parts * o->ma * 3 + 1) * sizeof(double));
    o->qc = malloc(3 * (size_t)o->n_ctrl * sizeof(double) + 1);
    if (!o->qc || !o->grad_z_share) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    compute_gravity(o, w->def.gravity);
    if (o->n_free > 0 && (st = setup_system(o, &w->def, err)) != SEM_OK) goto fail;
    /* rest stiffness for Rayleigh damping */
    if ((st = assemble_elastic(o, o->q0, 1, NULL, NULL, err)) != SEM_OK) goto fail;
    memcpy(o->K0_blocks, o->K_blocks, 9 * o->gpair_offset[o->n_gpairs] * sizeof(double));
    /* initial velocity: v = v0 + omega x (x - com) is affine, so exact on control points */
    {
        sem_object_stats s;
        double com[3] = {0, 0, 0};
        if (o->mass > 0) {
            double *xp = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
            if (!xp) {
                sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                goto fail;
            }
            sem_csr_multiply(&d->Gamma, o->q, 3, xp);
            for (int p = 0; p < o->n_quad; ++p)
                for (int k = 0; k < 3; ++k) com[k] += o->point_rho_vol[p] * xp[3 * p + k];
            for (int k = 0; k < 3; ++k) com[k] /= o->mass;
            free(xp);
        }
        (void)s;
        const double *v0 = def->initial_velocity, *om = def->initial_angular_velocity;
        for (int c = 0; c < o->n_ctrl; ++c) {
            if (o->pinned[c]) continue;
            const double *x = o->q + 3 * c;
            double r[3] = {x[0] - com[0], x[1] - com[1], x[2] - com[2]};
            o->v[3 * c + 0] = v0[0] + om[1] * r[2] - om[2] * r[1];
            o->v[3 * c + 1] = v0[1] + om[2] * r[0] - om[0] * r[2];
            o->v[3 * c + 2] = v0[2] + om[0] * r[1] - om[1] * r[0];
        }
    }
    if (w->n_objects == w->cap) {
        int nc = w->cap ? 2 * w->cap : 4;
        object **x = realloc(w->objects, (size_t)nc * sizeof *x);
        if (!x) {
            sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto fail;
        }
        w->objects = x;
        w->cap = nc;
    }
    w->objects[w->n_objects] = o;
    return w->n_objects++;
fail:
    object_destroy(o);
    return -1;
}

/* ---------------------------------------------------------------------------------- */
/* assembly                                                                            */

/* q minus the mean of its control points (per coordinate), in o->qc. Elastic and error
 * energies are translation invariant, but evaluated at q far from the origin their
 * round-off grows with |q|; a body that travels (free fall, a thrown object) would then
 * slowly lose momentum conservation. Evaluating at the centred q removes that. */
static const double *centered(object *o, const double *q)
{
    double mean[3] = {0, 0, 0};
    for (int c = 0; c < o->n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) mean[k] += q[3 * c + k];
    for (int k = 0; k < 3; ++k) mean[k] /= o->n_ctrl > 0 ? o->n_ctrl : 1;
    for (int c = 0; c < o->n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) o->qc[3 * c + k] = q[3 * c + k] - mean[k];
    return o->qc;
}

static void blocks_multiply(const object *o, double cM, double cE, double cK, double cD,
                            const double *x, double *y);

/* Error energy gamma q^T M_eps q (Eq. 16) and its gradient 2 gamma M_eps q (in grad). */
static double error_term(object *o, const double *q, double *grad)
{
    const double *qc = centered(o, q);
    blocks_multiply(o, 0, o->gamma, 0, 0, qc, grad);
    double e = 0;
    for (size_t i = 0; i < 3 * (size_t)o->n_ctrl; ++i) e += 0.5 * qc[i] * grad[i];
    return e;
}

/* Elastic energy, gradient in q (if grad_q) and, if want_hessian, K_blocks. */
/* The kernels below are element-wise (no reordered sums, and ISO C mode keeps the compiler
 * from contracting to FMA), so every clone gives the same bits. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(SEM_NO_CLONES)
#define SEM_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define SEM_VECTOR_CLONES
#endif

/* One point's N = vol D^T (d2psi/dF2) D, rows and columns (d, k) (coordinate d, basis
 * function k = 1..ma), as the packed upper triangle (row by row) of the 3ma x 3ma matrix:
 * N[(d,k),(d',k')] = vol sum_{e,e'} D[k][e] H[(d,e),(d',e')] D[k'][e']. */
SEM_VECTOR_CLONES
static void point_stiffness(int ma, double vol, const double *H, const double *D, double *N)
{
    int n3 = 3 * ma;
    double HD[9 * 27]; /* HD[(d,e)][(d',k')] = sum_e' H[(d,e),(d',e')] D[k'][e'] */
    for (int de = 0; de < 9; ++de)
        for (int d2 = 0; d2 < 3; ++d2) {
            const double *h = H + de * 9 + d2 * 3;
            for (int k2 = 0; k2 < ma; ++k2)
                HD[de * n3 + d2 * ma + k2] = h[0] * D[k2 * 3 + 0] + h[1] * D[k2 * 3 + 1] + h[2] * D[k2 * 3 + 2];
        }
    int idx = 0;
    for (int d1 = 0; d1 < 3; ++d1)
        for (int k1 = 0; k1 < ma; ++k1) {
            double a0 = vol * D[k1 * 3 + 0], a1 = vol * D[k1 * 3 + 1], a2 = vol * D[k1 * 3 + 2];
            const double *h0 = HD + (d1 * 3 + 0) * n3, *h1 = HD + (d1 * 3 + 1) * n3, *h2 = HD + (d1 * 3 + 2) * n3;
            for (int j = d1 * ma + k1; j < n3; ++j) N[idx++] = a0 * h0[j] + a1 * h1[j] + a2 * h2[j];
        }
}

/* acc += sum over the pair's entries [e0, e1) of w_e N_{point e} (points from c0 on). */
SEM_VECTOR_CLONES
static void pair_sum(int np, const int *point, const double *w, int e0, int e1, int c0,
                     const double *N, double *acc)
{
    for (int e = e0; e < e1; ++e) {
        const double *n = N + (size_t)(point[e] - c0) * np;
        double we = w[e];
        for (int x = 0; x < np; ++x) acc[x] += we * n[x];
    }
}

static void fill_gpair(object *o, int g, const double c[4], double *val);

/* system: NULL, or the coefficients (cM, cE, cK, cD) of fill_system, whose work is then
 * done group pair by group pair as each K block is formed (while it is in cache). */
static sem_status assemble_elastic(object *o, const double *q, int want_hessian, double *grad_q,
                                   const double *system, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    int ma = o->ma, n3 = 3 * ma, np = o->n_packed;
    size_t nz = (size_t)o->n_parts * ma * 3;
    size_t bs = (size_t)n3 * n3;
    /* z_i = pi_shared_i Q (shared-basis coefficients), with Q centred (translation
     * invariance; see centered) */
    const double *qc = centered(o, q);
    for (int i = 0; i < o->n_parts; ++i) {
        int g = d->part_origin[i];
        size_t n = gsize(o, g);
        const int *ctrl = o->group_ctrl + o->group_start[g];
        double *zi = o->z + (size_t)i * ma * 3;
        for (int k = 0; k < ma; ++k) {
            const double *row = o->pi_shared[i] + (size_t)k * n;
            double s0 = 0, s1 = 0, s2 = 0;
            for (size_t j = 0; j < n; ++j) {
                const double *x = qc + 3 * (size_t)ctrl[j];
                s0 += row[j] * x[0];
                s1 += row[j] * x[1];
                s2 += row[j] * x[2];
            }
            zi[k * 3 + 0] = s0;
            zi[k * 3 + 1] = s1;
            zi[k * 3 + 2] = s2;
        }
    }
    int nth = o->nthreads;
    double energy_total = 0, share_energy[GRADIENT_SHARES] = {0};
    int bad = 0;
    const int block = (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES) > 0
                          ? (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES)
                          : 1;
    memset(o->grad_z_share, 0, (size_t)GRADIENT_SHARES * nz * sizeof(double));
#pragma omp parallel num_threads(nth) reduction(| : bad)
    {
        for (int c0 = 0; c0 < o->n_quad; c0 += o->chunk) {
            int c1 = o->n_quad - c0 > o->chunk ? c0 + o->chunk : o->n_quad;
            /* per point: F, psi, P, and N_p. Blocks of `block` points go to the
             * GRADIENT_SHARES accumulators in turn (block b to share b mod S), whatever the
             * thread count and the chunk size; each share sums its points in point order
             * (continued from chunk to chunk), and the shares are added in order below, so
             * the sums are the same bits on any number of threads. */
#pragma omp for schedule(static)
            for (int sh = 0; sh < GRADIENT_SHARES; ++sh) {
                double *gz = o->grad_z_share + (size_t)sh * nz;
                double energy = share_energy[sh];
                for (int p = c0; p < c1; ++p) {
                    if ((p / block) % GRADIENT_SHARES != sh) {
                        /* skip to the next block */
                        p += block - 1 - p % block;
                        continue;
                    }
                    int r0 = W->row_start[p], r1 = W->row_start[p + 1];
                    const double *D = o->point_D + (size_t)p * ma * 3;
                    double zb[27] = {0}; /* sum_i w_i z_i */
                    for (int r = r0; r < r1; ++r) {
                        const double *zi = o->z + (size_t)W->col[r] * ma * 3;
                        double w = W->val[r];
                        for (int x = 0; x < n3; ++x) zb[x] += w * zi[x];
                    }
                    double F[9];
                    for (int dd = 0; dd < 3; ++dd)
                        for (int e = 0; e < 3; ++e) {
                            double f = 0;
                            for (int k = 0; k < ma; ++k) f += zb[k * 3 + dd] * D[k * 3 + e];
                            F[dd * 3 + e] = f;
                        }
                    double P[9], H[81];
                    double vol = d->quad_volume[p];
                    double psi = sem_material_energy(o->point_material[p], F, P, want_hessian ? H : NULL);
                    if (!isfinite(psi)) {
                        bad = 1;
                        if (want_hessian) memset(o->N_chunk + (size_t)(p - c0) * np, 0, (size_t)np * sizeof(double));
                        continue;
                    }
                    energy += vol * psi;
                    /* d psi / d z_i[k][d] = vol w_i sum_e P[d][e] D[k][e] */
                    double v[27];
                    for (int k = 0; k < ma; ++k)
                        for (int dd = 0; dd < 3; ++dd)
                            v[k * 3 + dd] = vol * (P[dd * 3 + 0] * D[k * 3 + 0] + P[dd * 3 + 1] * D[k * 3 + 1] +
                                                   P[dd * 3 + 2] * D[k * 3 + 2]);
                    for (int r = r0; r < r1; ++r) {
                        double *gzi = gz + (size_t)W->col[r] * ma * 3;
                        double w = W->val[r];
                        for (int x = 0; x < n3; ++x) gzi[x] += w * v[x];
                    }
                    if (!want_hessian) continue;
                    if (!o->exact_hessian) sem_project_psd_9x9(H);
                    point_stiffness(ma, vol, H, D, o->N_chunk + (size_t)(p - c0) * np);
                }
                share_energy[sh] = energy;
            }
            if (!want_hessian) continue;
            /* per upper part pair: Kz_ab += sum_p w_a w_b N_p over the chunk's points, each
             * pair summed by one thread in point order (deterministic for any thread count) */
            int first = c0 == 0, last = c1 == o->n_quad;
#pragma omp for schedule(dynamic, 8)
            for (int pr = 0; pr < o->n_pairs; ++pr) {
                if (!pair_has_points(o, pr)) continue;
                double acc[378];
                if (first) {
                    memset(acc, 0, (size_t)np * sizeof(double));
                    o->plist_cursor[pr] = o->plist_start[pr];
                } else {
                    memcpy(acc, o->Kz_packed + (size_t)pr * np, (size_t)np * sizeof(double));
                }
                int e0 = o->plist_cursor[pr], e1 = e0, end = o->plist_start[pr + 1];
                while (e1 < end && o->plist_point[e1] < c1) e1++;
                pair_sum(np, o->plist_point, o->plist_w, e0, e1, c0, o->N_chunk, acc);
                o->plist_cursor[pr] = e1;
                if (!last) {
                    memcpy(o->Kz_packed + (size_t)pr * np, acc, (size_t)np * sizeof(double));
                    continue;
                }
                /* full matrix, rows (k, d), columns (d', k') (see the projection below) */
                double *K = o->Kz + (size_t)pr * bs;
                int idx = 0;
                for (int i = 0; i < n3; ++i) {
                    int ri = (i % ma) * 3 + i / ma;
                    for (int j = i; j < n3; ++j) {
                        int rj = (j % ma) * 3 + j / ma;
                        K[ri * n3 + j] = K[rj * n3 + i] = acc[idx++];
                    }
                }
            }
        }
    }
    for (int sh = 0; sh < GRADIENT_SHARES; ++sh) energy_total += share_energy[sh];
    if (bad)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "an element inverted or the state became non-finite (elastic energy "
                             "undefined)");
    o->elastic_energy = energy_total;
    /* reduce in share order */
    memcpy(o->grad_z, o->grad_z_share, nz * sizeof(double));
    for (int sh = 1; sh < GRADIENT_SHARES; ++sh)
        for (size_t k = 0; k < nz; ++k) o->grad_z[k] += o->grad_z_share[(size_t)sh * nz + k];
    if (grad_q) {
        memset(grad_q, 0, 3 * (size_t)o->n_ctrl * sizeof(double));
        for (int i = 0; i < o->n_parts; ++i) {
            int g = d->part_origin[i];
            size_t n = gsize(o, g);
            const int *ctrl = o->group_ctrl + o->group_start[g];
            const double *gzi = o->grad_z + (size_t)i * ma * 3;
            for (int k = 0; k < ma; ++k) {
                const double *row = o->pi_shared[i] + (size_t)k * n;
                for (size_t j = 0; j < n; ++j) {
                    double *y = grad_q + 3 * (size_t)ctrl[j];
                    y[0] += row[j] * gzi[k * 3 + 0];
                    y[1] += row[j] * gzi[k * 3 + 1];
                    y[2] += row[j] * gzi[k * 3 + 2];
                }
            }
        }
    }
    if (!want_hessian) return SEM_OK;
    /* K_q blocks = sum over part pairs Pi_a^T Kz Pi_b per coordinate pair. The small dgemm
     * calls run inside our OpenMP threads: OpenBLAS's own threads would only oversubscribe
     * the cores (measured: the rocket's step went from 18 ms to 11 ms), so BLAS is single
     * threaded here and gets its threads back for the factorization. */
    size_t mg = max_group(o);
    int fail = 0;
    int blas_threads = openblas_get_num_threads();
    double *val = system ? sem_linear_solver_values(o->solver) : NULL;
    openblas_set_num_threads(1);
#pragma omp parallel num_threads(nth) reduction(| : fail)
    {
        /* Block(ga,gb) = sum_a Pi_a^T (sum_b Kz_ab Pi_b) with the shared-basis Pi: the inner
         * sum first, so the expensive product with Pi_a^T is done once per part a, not per
         * pair. Kz_ab (rows (k, d), columns (d', k')) is read as a (3ma x 3) x ma matrix,
         * rows (k, d, d'), so the inner product is one call:
         * U[(k,d,d')][j] = sum_k' Kz[(k,d),(d',k')] Pi_b[k'][j]; U is then an ma x 9|Gb|
         * matrix, and Pi_a^T U is one call whose rows (la) hold the 9 sub-block rows side by
         * side, the layout of K_blocks.
         * Kz_ba = Kz_ab (symmetric) is stored once, under the pair a <= b. Pairs without a
         * shared quadrature point (only in the error matrix's pattern) have no stiffness.
         * K is symmetric, so only group pairs ga <= gb are formed (see setup_system). */
        double *U = malloc(9 * (size_t)ma * mg * sizeof(double));
        if (!U) fail = 1;
#pragma omp for schedule(dynamic, 4)
        for (int g = 0; g < o->n_gpairs; ++g) {
            if (!U || o->gpair_a[g] > o->gpair_b[g]) continue;
            int na = (int)gsize(o, o->gpair_a[g]), nb = (int)gsize(o, o->gpair_b[g]);
            double *blk = o->K_blocks + 9 * o->gpair_offset[g];
            int written = 0; /* the first product overwrites the block (no clearing pass) */
            int k = o->gpair_pairs_start[g], end = o->gpair_pairs_start[g + 1];
            while (k < end) {
                int a = o->pair_a[o->gpair_pairs[k]];
                int any = 0;
                for (; k < end && o->pair_a[o->gpair_pairs[k]] == a; ++k) {
                    int pr = o->gpair_pairs[k], b = o->pair_b[pr];
                    int up = a <= b ? pr : o->pair_lookup[(size_t)b * o->n_parts + a];
                    if (!pair_has_points(o, up)) continue;
                    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, 3 * n3, nb, ma, 1.0,
                                o->Kz + (size_t)up * bs, ma, o->pi_shared[b], nb, any ? 1.0 : 0.0, U, nb);
                    any = 1;
                }
                if (!any) continue;
                cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, na, 9 * nb, ma, 1.0, o->pi_shared[a], na,
                            U, 9 * nb, written ? 1.0 : 0.0, blk, 9 * nb);
                written = 1;
            }
            if (!written) memset(blk, 0, 9 * (size_t)na * nb * sizeof(double));
            if (system) fill_gpair(o, g, system, val);
        }
        free(U);
    }
    openblas_set_num_threads(blas_threads);
    if (fail) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    return SEM_OK;
}

/* y = (cM M + cE 2 M_eps) x + cK K x + cD K0 x over all dofs (block form). */
static void blocks_multiply(const object *o, double cM, double cE, double cK, double cD,
                            const double *x, double *y)
{
    if (cK == 0 && cD == 0) {
        /* mass and error matrix only: by rows in parallel */
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
        for (int c = 0; c < o->n_ctrl; ++c) {
            double y0 = 0, y1 = 0, y2 = 0;
            for (int k = o->me_start[c]; k < o->me_start[c + 1]; ++k) {
                double v = cM * o->me_M[k] + 2.0 * cE * o->me_E[k];
                const double *xb = x + 3 * (size_t)o->me_col[k];
                y0 += v * xb[0];
                y1 += v * xb[1];
                y2 += v * xb[2];
            }
            y[3 * (size_t)c + 0] = y0;
            y[3 * (size_t)c + 1] = y1;
            y[3 * (size_t)c + 2] = y2;
        }
        return;
    }
    memset(y, 0, 3 * (size_t)o->n_ctrl * sizeof(double));
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], gb = o->gpair_b[g];
        size_t na = gsize(o, ga), nb = gsize(o, gb);
        size_t off = o->gpair_offset[g];
        const int *ca = o->group_ctrl + o->group_start[ga], *cb = o->group_ctrl + o->group_start[gb];
        for (size_t la = 0; la < na; ++la) {
            double *ya = y + 3 * (size_t)ca[la];
            for (size_t lb = 0; lb < nb; ++lb) {
                const double *xb = x + 3 * (size_t)cb[lb];
                size_t e = la * nb + lb;
                double s = cM * o->M_blocks[off + e] + 2.0 * cE * o->E_blocks[off + e];
                for (int d = 0; d < 3; ++d) ya[d] += s * xb[d];
                if ((cK != 0 || cD != 0) && ga <= gb) {
                    /* K is kept for ga <= gb; block (gb, ga) is its transpose */
                    const double *xa = x + 3 * (size_t)ca[la];
                    double *yb = y + 3 * (size_t)cb[lb];
                    for (int d1 = 0; d1 < 3; ++d1)
                        for (int d2 = 0; d2 < 3; ++d2) {
                            size_t idx = 9 * off + (la * 9 + (size_t)(d1 * 3 + d2)) * nb + lb;
                            double k = cK * o->K_blocks[idx] + cD * o->K0_blocks[idx];
                            ya[d1] += k * xb[d2];
                            if (ga < gb) yb[d2] += k * xa[d1];
                        }
                }
            }
        }
    }
}

/* The solver's values of group pair g (ga <= gb): c[0] M + c[1] 2 M_eps + c[2] K + c[3] K0.
 * Every block entry has its own position (or none), so group pairs are independent. */
static void fill_gpair(object *o, int g, const double c[4], double *val)
{
    if (o->gpair_a[g] > o->gpair_b[g]) return; /* mapped nowhere (see setup_system) */
    size_t na = gsize(o, o->gpair_a[g]), nb = gsize(o, o->gpair_b[g]);
    size_t off = o->gpair_offset[g];
    for (size_t la = 0; la < na; ++la) {
        const double *Ms = o->M_blocks + off + la * nb, *Es = o->E_blocks + off + la * nb;
        for (int dd = 0; dd < 9; ++dd) {
            int diag = dd / 3 == dd % 3;
            size_t row = 9 * off + (la * 9 + (size_t)dd) * nb;
            const int *map = o->map + row;
            const double *K = o->K_blocks + row, *K0 = o->K0_blocks + row;
            for (size_t lb = 0; lb < nb; ++lb) {
                int pos = map[lb];
                if (pos < 0) continue;
                double v = c[2] * K[lb] + c[3] * K0[lb];
                if (diag) v += c[0] * Ms[lb] + 2.0 * c[1] * Es[lb];
                val[pos] = v;
            }
        }
    }
}

/* Fills the solver's values with cM M + cE 2 M_eps + cK K + cD K0 on free dofs. */
static void fill_system(object *o, double cM, double cE, double cK, double cD)
{
    double *val = sem_linear_solver_values(o->solver);
    const double c[4] = {cM, cE, cK, cD};
#pragma omp parallel for schedule(dynamic, 8) num_threads(o->nthreads)
    for (int g = 0; g < o->n_gpairs; ++g) fill_gpair(o, g, c, val);
}

/* ---------------------------------------------------------------------------------- */
/* loads and prescribed motion                                                         */

static void prescribed_position(const object *o, double t, int c, double out[3])
{
    const double *x0 = o->q0 + 3 * c;
    if (o->presc_index[c] < 0) {
        memcpy(out, o->q + 3 * c, 3 * sizeof(double));
        return;
    }
    const sem_prescribe *pr = &o->presc[o->presc_index[c]];
    if (pr->type == SEM_PRESCRIBE_AFFINE) {
        const double *A = pr->affine;
        for (int r = 0; r < 3; ++r) out[r] = A[4 * r] * x0[0] + A[4 * r + 1] * x0[1] + A[4 * r + 2] * x0[2] + A[4 * r + 3];
        return;
    }
    if (pr->type == SEM_PRESCRIBE_ROTATE) {
        double tt = pr->duration > 0 && t > pr->duration ? pr->duration : t;
        double ang = pr->rate * tt;
        double k[3] = {pr->axis_direction[0], pr->axis_direction[1], pr->axis_direction[2]};
        double kn = sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
        if (kn > 0)
            for (int i = 0; i < 3; ++i) k[i] /= kn;
        double r[3] = {x0[0] - pr->axis_point[0], x0[1] - pr->axis_point[1], x0[2] - pr->axis_point[2]};
        double cs = cos(ang), sn = sin(ang);
        double kxr[3] = {k[1] * r[2] - k[2] * r[1], k[2] * r[0] - k[0] * r[2], k[0] * r[1] - k[1] * r[0]};
        double kdr = k[0] * r[0] + k[1] * r[1] + k[2] * r[2];
        for (int i = 0; i < 3; ++i)
            out[i] = pr->axis_point[i] + r[i] * cs + kxr[i] * sn + k[i] * kdr * (1 - cs);
        return;
    }
    memcpy(out, o->q + 3 * c, 3 * sizeof(double));
}

/* External forces at time t: gravity, region loads, point loads (through Gamma^T). */
static void external_force(const object *o, double t, double *f)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    memcpy(f, o->f_gravity, n * sizeof(double));
    const sem_discretization *d = o->d;
    for (int l = 0; l < o->def.n_region_loads; ++l) {
        const sem_region_load *rl = &o->def.region_loads[l];
        double s = rl->frequency > 0 ? 0.5 * (1 + sin(2 * M_PI * rl->frequency * t + rl->phase)) : 1.0;
        for (int p = 0; p < o->n_quad; ++p) {
            const double *X = d->quad_X + 3 * p;
            if (X[0] < rl->box[0] || X[1] < rl->box[1] || X[2] < rl->box[2] || X[0] > rl->box[3] ||
                X[1] > rl->box[4] || X[2] > rl->box[5])
                continue;
            double vol = d->quad_volume[p];
            for (int e = d->Gamma.row_start[p]; e < d->Gamma.row_start[p + 1]; ++e)
                for (int k = 0; k < 3; ++k)
                    f[3 * (size_t)d->Gamma.col[e] + k] += d->Gamma.val[e] * vol * s * rl->force_density[k];
        }
    }
    for (int l = 0; l < o->def.n_point_loads; ++l) {
        /* the force acts at the quadrature point nearest its rest position */
        const sem_point_load *pl = &o->def.point_loads[l];
        int best = -1;
        double bd = INFINITY;
        for (int p = 0; p < o->n_quad; ++p) {
            const double *X = d->quad_X + 3 * p;
            double dd = (X[0] - pl->X[0]) * (X[0] - pl->X[0]) + (X[1] - pl->X[1]) * (X[1] - pl->X[1]) +
                        (X[2] - pl->X[2]) * (X[2] - pl->X[2]);
            if (dd < bd) {
                bd = dd;
                best = p;
            }
        }
        if (best < 0) continue;
        for (int e = d->Gamma.row_start[best]; e < d->Gamma.row_start[best + 1]; ++e)
            for (int k = 0; k < 3; ++k) f[3 * (size_t)d->Gamma.col[e] + k] += d->Gamma.val[e] * pl->force[k];
    }
}

/* ---------------------------------------------------------------------------------- */
/* steppers                                                                            */

static void gather_free(const object *o, const double *full, double *fr)
{
    for (int c = 0; c < o->n_ctrl; ++c) {
        int f = o->free_index[c];
        if (f < 0) continue;
        for (int k = 0; k < 3; ++k) fr[3 * f + k] = full[3 * c + k];
    }
}

static void scatter_free(const object *o, const double *fr, double *full)
{
    for (int c = 0; c < o->n_ctrl; ++c) {
        int f = o->free_index[c];
        if (f < 0) continue;
        for (int k = 0; k < 3; ++k) full[3 * c + k] = fr[3 * f + k];
    }
}

static int finite_vec(const double *x, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(x[i])) return 0;
    return 1;
}

/* (M + h C + h^2 K) v+ = M v + h f(q), q+ = q + h v+ (the paper's step). */
static sem_status step_linearly_implicit(sem_world *w, object *o, sem_error *err)
{
    double h = w->def.dt, t1 = w->time + h;
    size_t n = 3 * (size_t)o->n_ctrl;
    double a = w->def.rayleigh_mass, b = w->def.rayleigh_stiffness;
    double *f = malloc(n * sizeof(double)), *g = malloc(n * sizeof(double));
    double *rhs = malloc(n * sizeof(double)), *tmp = malloc(n * sizeof(double));
    double *vp = calloc(n, sizeof(double));
    double *fr = malloc(3 * (size_t)o->n_free * sizeof(double) + 1);
    sem_status st = SEM_OK;
    if (!f || !g || !rhs || !tmp || !vp || !fr) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* the system matrix's values are written as its K blocks are formed */
    const double coef[4] = {1.0 + h * a, h * h * o->gamma, h * h, h * b};
    if ((st = assemble_elastic(o, o->q, 1, g, o->n_free > 0 ? coef : NULL, err)) != SEM_OK) goto done;
    external_force(o, w->time, f);
    /* f_total = f_ext - grad V - 2 gamma M_eps q */
    error_term(o, o->q, tmp);
    for (size_t i = 0; i < n; ++i) f[i] -= g[i] + tmp[i];
    /* rhs = M v + h f - h C v ... damping enters the matrix: (M + hC + h^2K) v+ = M v + h f */
    blocks_multiply(o, 1.0, 0, 0, 0, o->v, rhs);
    for (size_t i = 0; i < n; ++i) rhs[i] += h * f[i];
    /* prescribed velocities of pinned points */
    int any_pinned = 0;
    for (int c = 0; c < o->n_ctrl; ++c) {
        if (!o->pinned[c]) continue;
        double x1[3];
        prescribed_position(o, t1, c, x1);
        for (int k = 0; k < 3; ++k) vp[3 * c + k] = (x1[k] - o->q[3 * c + k]) / h;
        any_pinned = 1;
    }
    if (any_pinned) {
        blocks_multiply(o, 1.0 + h * a, h * h * o->gamma, h * h, h * b, vp, tmp);
        for (size_t i = 0; i < n; ++i) rhs[i] -= tmp[i];
    }
    if (o->n_free > 0) {
        if ((st = sem_linear_solver_factorize(o->solver, err)) != SEM_OK) goto done;
        w->last_factor_s += sem_linear_solver_last_factor_seconds(o->solver);
        gather_free(o, rhs, fr);
        if ((st = sem_linear_solver_solve(o->solver, fr, fr, err)) != SEM_OK) goto done;
        scatter_free(o, fr, vp);
    }
    if (!finite_vec(vp, n)) {
        st = sem_error_set(err, SEM_ERR_NUMERIC, "the state became non-finite (NaN) at t = %g", t1);
        goto done;
    }
    memcpy(o->v, vp, n * sizeof(double));
    for (size_t i = 0; i < n; ++i) o->q[i] += h * o->v[i];
done:
    free(f);
    free(g);
    free(rhs);
    free(tmp);
    free(vp);
    free(fr);
    return st;
}

/* Newton on E(q) = 1/(2h^2) |q - q_pred|_M^2 + V(q) + gamma q^T M_eps q - f^T q (+ damping),
 * or, when h == 0 (statics), E(q) = V(q) + gamma q^T M_eps q - f^T q. */
static sem_status newton_solve(sem_world *w, object *o, double h, double t1, sem_error *err)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    int dynamic = h > 0;
    double cM = dynamic ? 1.0 / (h * h) + w->def.rayleigh_mass / h : 0.0;
    double cD = dynamic ? w->def.rayleigh_stiffness / h : 0.0;
    double *qn = malloc(n * sizeof(double)), *qpred = malloc(n * sizeof(double));
    double *f = malloc(n * sizeof(double)), *g = malloc(n * sizeof(double));
    double *tmp = malloc(n * sizeof(double)), *dq = calloc(n, sizeof(double));
    double *qtry = malloc(n * sizeof(double));
    double *fr = malloc(3 * (size_t)o->n_free * sizeof(double) + 1);
    sem_status st = SEM_OK;
    if (!qn || !qpred || !f || !g || !tmp || !dq || !qtry || !fr) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    memcpy(qn, o->q, n * sizeof(double));
    for (size_t i = 0; i < n; ++i) qpred[i] = o->q[i] + (dynamic ? h * o->v[i] : 0);
    external_force(o, t1, f);
    /* pinned points go to their prescribed positions at t1 */
    for (int c = 0; c < o->n_ctrl; ++c)
        if (o->pinned[c]) prescribed_position(o, t1, c, o->q + 3 * c);
    if (dynamic)
        for (int c = 0; c < o->n_ctrl; ++c)
            if (!o->pinned[c])
                for (int k = 0; k < 3; ++k) o->q[3 * c + k] = qpred[3 * c + k];

    /* energy of a configuration (free dofs vary); returns +inf if undefined */
#define ENERGY(qq, out)                                                                    \
    do {                                                                                   \
        sem_error e_;                                                                      \
        if (assemble_elastic(o, (qq), 0, NULL, NULL, &e_) != SEM_OK) {                          \
            (out) = INFINITY;                                                              \
        } else {                                                                           \
            double E_ = o->elastic_energy + error_term(o, (qq), tmp);                      \
            for (size_t i_ = 0; i_ < n; ++i_) E_ -= f[i_] * (qq)[i_];                      \
            if (dynamic) {                                                                 \
                for (size_t i_ = 0; i_ < n; ++i_) dq[i_] = (qq)[i_] - qpred[i_];           \
                blocks_multiply(o, 1.0 / (h * h), 0, 0, 0, dq, tmp);                       \
                for (size_t i_ = 0; i_ < n; ++i_) E_ += 0.5 * dq[i_] * tmp[i_];            \
                if (cD > 0 || w->def.rayleigh_mass > 0) {                                  \
                    for (size_t i_ = 0; i_ < n; ++i_) dq[i_] = (qq)[i_] - qn[i_];          \
                    blocks_multiply(o, w->def.rayleigh_mass / h, 0, 0, cD, dq, tmp);       \
                    for (size_t i_ = 0; i_ < n; ++i_) E_ += 0.5 * dq[i_] * tmp[i_];        \
                }                                                                          \
            }                                                                              \
            (out) = E_;                                                                    \
        }                                                                                  \
    } while (0)

    double g0norm = -1;
    int it, full_steps = 0, exact_allowed = exact_hessian_policy;
    o->exact_hessian = 0;
    for (it = 0; it < w->def.newton_max_iterations; ++it) {
        /* the exact Hessian after two full steps in a row (see the file comment) */
        o->exact_hessian = exact_allowed && full_steps >= 2;
        if ((st = assemble_elastic(o, o->q, 1, g, NULL, err)) != SEM_OK) goto done;
        /* gradient: grad V + 2 gamma M_eps q - f + M (q - q_pred)/h^2 + damping */
        error_term(o, o->q, tmp);
        for (size_t i = 0; i < n; ++i) g[i] += tmp[i] - f[i];
        if (dynamic) {
            for (size_t i = 0; i < n; ++i) dq[i] = o->q[i] - qpred[i];
            blocks_multiply(o, 1.0 / (h * h), 0, 0, 0, dq, tmp);
            for (size_t i = 0; i < n; ++i) g[i] += tmp[i];
            if (cD > 0 || w->def.rayleigh_mass > 0) {
                for (size_t i = 0; i < n; ++i) dq[i] = o->q[i] - qn[i];
                blocks_multiply(o, w->def.rayleigh_mass / h, 0, 0, cD, dq, tmp);
                for (size_t i = 0; i < n; ++i) g[i] += tmp[i];
            }
        }
        gather_free(o, g, fr);
        double gnorm = 0, fscale = 0;
        for (int i = 0; i < 3 * o->n_free; ++i) gnorm += fr[i] * fr[i];
        gnorm = sqrt(gnorm);
        for (size_t i = 0; i < n; ++i) fscale += f[i] * f[i];
        fscale = sqrt(fscale);
        if (g0norm < 0) g0norm = gnorm;
        double scale = fmax(g0norm, fscale);
        if (o->n_free == 0 || gnorm <= w->def.newton_tolerance * scale || gnorm == 0) break;
        fill_system(o, cM, o->gamma, 1.0, cD);
        st = sem_linear_solver_factorize(o->solver, err);
        w->last_factor_s += sem_linear_solver_last_factor_seconds(o->solver);
        if (st == SEM_ERR_NUMERIC && o->exact_hessian) {
            /* the exact system is not positive definite (e.g. a buckled or unstable
             * equilibrium): project, for the rest of this solve */
            o->exact_hessian = 0;
            exact_allowed = 0;
            exact_hessian_fallbacks++;
            if ((st = assemble_elastic(o, o->q, 1, NULL, NULL, err)) != SEM_OK) goto done;
            fill_system(o, cM, o->gamma, 1.0, cD);
            st = sem_linear_solver_factorize(o->solver, err);
            w->last_factor_s += sem_linear_solver_last_factor_seconds(o->solver);
        }
        if (st != SEM_OK) goto done;
        if ((st = sem_linear_solver_solve(o->solver, fr, fr, err)) != SEM_OK) goto done;
        memset(dq, 0, n * sizeof(double));
        scatter_free(o, fr, dq);
        double slope = 0;
        for (size_t i = 0; i < n; ++i) slope -= dq[i] * g[i];
        /* ENERGY uses dq as scratch: keep the Newton direction apart */
        double *dir = malloc(n * sizeof(double));
        if (!dir) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto done;
        }
        memcpy(dir, dq, n * sizeof(double));
        double E0;
        ENERGY(o->q, E0);
        double step = 1.0, Et = INFINITY;
        for (int ls = 0; ls < 40; ++ls) {
            for (size_t i = 0; i < n; ++i) qtry[i] = o->q[i] - step * dir[i];
            ENERGY(qtry, Et);
            if (Et <= E0 + 1e-4 * step * slope || (isfinite(Et) && fabs(Et - E0) <= 1e-14 * fabs(E0)))
                break;
            step *= 0.5;
        }
        full_steps = step == 1.0 ? full_steps + 1 : 0;
        double dmax = 0;
        for (size_t i = 0; i < n; ++i) dmax = fmax(dmax, fabs(step * dir[i]));
        if (getenv("SEM_DEBUG_NEWTON"))
            fprintf(stderr, "newton it %d: |g| %.6g E0 %.12g Et %.12g step %g slope %g dmax %g\n", it, gnorm, E0, Et,
                    step, slope, dmax);
        free(dir);
        if (!isfinite(Et)) {
            st = sem_error_set(err, SEM_ERR_NUMERIC,
                               "Newton line search found no valid configuration at t = %g", t1);
            goto done;
        }
        memcpy(o->q, qtry, n * sizeof(double));
        if (dmax <= 1e-14 * (1.0 + fabs(o->q[0]))) {
            ++it;
            break;
        }
    }
#undef ENERGY
    w->last_iterations = it;
    if (!finite_vec(o->q, n)) {
        st = sem_error_set(err, SEM_ERR_NUMERIC, "the state became non-finite (NaN) at t = %g", t1);
        goto done;
    }
    if (dynamic)
        for (size_t i = 0; i < n; ++i) o->v[i] = (o->q[i] - qn[i]) / h;
    else
        memset(o->v, 0, n * sizeof(double));
done:
    o->exact_hessian = 0;
    free(qn);
    free(qpred);
    free(f);
    free(g);
    free(tmp);
    free(dq);
    free(qtry);
    free(fr);
    return st;
}

sem_status sem_world_step(sem_world *w, sem_error *err)
{
    double t0 = omp_get_wtime();
    w->last_factor_s = 0;
    w->last_iterations = 0;
    for (int i = 0; i < w->n_objects; ++i) {
        object *o = w->objects[i];
        sem_status st;
        switch (w->def.integrator) {
        case SEM_LINEARLY_IMPLICIT_EULER: st = step_linearly_implicit(w, o, err); break;
        case SEM_IMPLICIT_EULER: st = newton_solve(w, o, w->def.dt, w->time + w->def.dt, err); break;
        /* quasi-static: equilibrium with the loads and prescribed motion of t + dt */
        default: st = newton_solve(w, o, 0.0, w->time + w->def.dt, err); break;
        }
        if (st != SEM_OK) return st;
    }
    w->time += w->def.dt;
    w->step_index++;
    w->last_step_s = omp_get_wtime() - t0;
    return SEM_OK;
}

sem_status sem_world_solve_static(sem_world *w, sem_error *err)
{
    int saved = w->def.newton_max_iterations;
    if (saved < 200) w->def.newton_max_iterations = 200;
    for (int i = 0; i < w->n_objects; ++i) {
        sem_status st = newton_solve(w, w->objects[i], 0.0, w->time, err);
        if (st != SEM_OK) {
            w->def.newton_max_iterations = saved;
            return st;
        }
    }
    w->def.newton_max_iterations = saved;
    return SEM_OK;
}

/* ---------------------------------------------------------------------------------- */
/* queries                                                                             */

double sem_world_time(const sem_world *w) { return w->time; }
void sem_world_set_time(sem_world *w, double time) { w->time = time; }
int sem_world_object_count(const sem_world *w) { return w->n_objects; }
int sem_world_object_dofs(const sem_world *w, int i) { return 3 * w->objects[i]->n_ctrl; }
const double *sem_world_object_q(const sem_world *w, int i) { return w->objects[i]->q; }
const double *sem_world_object_velocity(const sem_world *w, int i) { return w->objects[i]->v; }
double sem_world_last_step_seconds(const sem_world *w) { return w->last_step_s; }
double sem_world_last_factor_seconds(const sem_world *w) { return w->last_factor_s; }
int sem_world_last_iterations(const sem_world *w) { return w->last_iterations; }

const char *sem_world_solver_name(const sem_world *w, int i)
{
    return w->objects[i]->solver ? sem_linear_solver_name(w->objects[i]->solver) : "none";
}

double sem_world_object_nnz_percent(const sem_world *w, int i)
{
    const object *o = w->objects[i];
    /* full q-space pattern: group-pair blocks x 9 */
    double nnz = 9.0 * (double)o->gpair_offset[o->n_gpairs];
    double n = 3.0 * o->n_ctrl;
    return 100.0 * nnz / (n * n);
}

void sem_world_object_set_state(sem_world *w, int i, const double *q, const double *v)
{
    object *o = w->objects[i];
    size_t n = 3 * (size_t)o->n_ctrl;
    if (q) memcpy(o->q, q, n * sizeof(double));
    if (v) memcpy(o->v, v, n * sizeof(double));
}

void sem_world_object_stats(const sem_world *w, int i, sem_object_stats *s)
{
    object *o = w->objects[i];
    const sem_discretization *d = o->d;
    memset(s, 0, sizeof *s);
    s->volume = o->volume;
    s->mass = o->mass;
    size_t n = 3 * (size_t)o->n_ctrl;
    double *x = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    double *v = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    double *tmp = malloc(n * sizeof(double) + 1);
    if (!x || !v || !tmp) {
        free(x);
        free(v);
        free(tmp);
        return;
    }
    sem_csr_multiply(&d->Gamma, o->q, 3, x);
    sem_csr_multiply(&d->Gamma, o->v, 3, v);
    const double *g = w->def.gravity;
    for (int p = 0; p < o->n_quad; ++p) {
        double rv = o->point_rho_vol[p];
        const double *xp = x + 3 * p, *vp = v + 3 * p;
        for (int k = 0; k < 3; ++k) {
            s->center_of_mass[k] += rv * xp[k];
            s->linear_momentum[k] += rv * vp[k];
        }
        s->angular_momentum[0] += rv * (xp[1] * vp[2] - xp[2] * vp[1]);
        s->angular_momentum[1] += rv * (xp[2] * vp[0] - xp[0] * vp[2]);
        s->angular_momentum[2] += rv * (xp[0] * vp[1] - xp[1] * vp[0]);
        s->gravity_energy -= rv * (g[0] * xp[0] + g[1] * xp[1] + g[2] * xp[2]);
    }
    if (o->mass > 0)
        for (int k = 0; k < 3; ++k) s->center_of_mass[k] /= o->mass;
    /* kinetic energy 1/2 v^T M v; error energy gamma q^T M_eps q */
    blocks_multiply(o, 1.0, 0, 0, 0, o->v, tmp);
    for (size_t k = 0; k < n; ++k) s->kinetic_energy += 0.5 * o->v[k] * tmp[k];
    s->error_energy = error_term(o, o->q, tmp);
    sem_error e;
    if (assemble_elastic(o, o->q, 0, NULL, NULL, &e) == SEM_OK)
        s->elastic_energy = o->elastic_energy;
    else
        s->elastic_energy = INFINITY;
    free(x);
    free(v);
    free(tmp);
}
