/*
 * structured_solver.c - the system of one object's free dofs solved through its structure:
 * Woodbury on c S0 + V^T Mid V with a small dense capacitance matrix, refined by conjugate
 * gradients on the exact products (the design is in structured.h).
 *
 * Reduced rows. Row i m + 0 of Pi is the translation t_j of part i's origin, the same for
 * every part of the group (projection.c), so P has repeated rows; with shared fits every row of
 * a part repeats in the other parts of its origin, and r = origins x m. Only P's row space enters
 * A, so the rows are reduced: P = E P~ with P~ the distinct rows and E the 0/1 expansion;
 * then A = c S0 + P~^T Z~ P~ - c (P~^T G~ + G~^T P~) with Z~ = E^T Z E and G~ = E^T G (the
 * duplicates' rows summed). r = rows of P~ per coordinate.
 *
 * Schur complement. With B = F2 - I, the capacitance (times c) is [[F1, B], [B^T, F3 - Z~/c]].
 * F1 = P~ S0^-1 P~^T is constant, block diagonal by origin group, positive semi-definite and
 * often nearly singular (fits of one origin's parts that are nearly dependent). Each group's
 * block, Jacobi-scaled (the rows of P~ differ in scale by powers of the model size), is
 * decomposed into eigenpairs once; the eigenvectors above F1_CUTOFF of the group's largest
 * eigenvalue give a basis P' = T^T P~ of P~'s row space in which F1 is the identity (the rest
 * are exactly dependent rows: their eigenvalues sit at round-off). With Ep the matching
 * expansion (P~ = Ep P' on the kept space) the capacitance becomes [[I, B'], [B'^T, F3' - Z'/c]]
 * and what is left to factorize at each step is
 *
 *   H' = Z'/c - (F3' - B'^T B'),   Z' = Ep^T Z~ Ep   (3k square, k <= r; the constant part is
 *                                                     precomputed, Z' is formed group pair by
 *                                                     group pair)
 *
 * A is positive definite exactly when H' is (inertia additivity: In(Cap) = In(I) + In(-H'),
 * and A > 0 iff Cap has 3k negative eigenvalues), so H''s Cholesky factorization is the test
 * the q-space Cholesky solvers make, up to round-off: H' is a difference of terms of the error
 * matrix's size, so where A is held by much smaller terms a diagonal shift may be needed
 * (see sem_structured_solver_factorize), and conjugate gradients on the exact products
 * decide.
 *
 * Layout. Free control points f = 0..n-1 (o->free_index); dofs 3 f + d. Coefficient
 * vectors: reduced row rho, coordinate d at 3 rho + d (P~ rows; G~ rows likewise in a second
 * vector). The scalar matrices (S0, V, F) are the same for each coordinate; only Z couples
 * coordinates.
 *
 * Cost per factorization: forming H' (the Kz pair blocks to the parts' own bases, then the
 * group-pair products) and its Cholesky factorization, (3k)^3 / 3 flops. Per solve: two sparse solves with S0 (3
 * right-hand sides), products with V and V^T, small dense solves, then one or two conjugate
 * gradient iterations whose products cost O(nnz Pi + samples). Every sum runs in a fixed
 * order, and OpenBLAS uses a fixed thread count (as linear_solver.c), so the bits do not
 * depend on the thread count.
 */
#include "structured.h"

#include "sem/limits.h"
#include "util/free_all.h"
#include "util/union_find.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <suitesparse/cholmod.h>

/* The fixed OpenBLAS thread count of linear_solver.c (see there). */
#define BLAS_THREADS 2
/* Columns of V^T solved with S0 at a time while forming F. */
#define F_CHUNK 128
/* Conjugate gradient refinement: stop at this relative residual; a solve that cannot reach
 * CG_FAIL within CG_MAX_ITERATIONS is an error, not a quiet wrong answer. */
#define CG_TOLERANCE 1e-12
#define CG_FAIL 1e-7
#define CG_MAX_ITERATIONS 60

struct sem_structured_solver {
    sem_object *o;
    int n;          /* free control points */
    int r0, r;      /* coefficient rows per coordinate: all, distinct */
    int *red;       /* r0: reduced row of each row of P */
    int *p_first;   /* r: a row of P for each reduced row */
    cholmod_common common;
    cholmod_factor *L; /* S0 */
    /* V = [P~; G~] (2 r x n) over the free control points, CSR, and its transpose */
    int *v_start, *v_col;
    double *v_val;
    int *vt_start, *vt_row;
    double *vt_val;
    double *F;      /* 2r x 2r, row-major: V S0^-1 V^T */
    /* the well-conditioned basis of P~'s row space (schur_constants): k of the r rows */
    int k;
    double *T;      /* r x k, row-major: U_k Lambda_k^-1/2 (new P rows = T^T P~) */
    double *Ep;     /* r x k, row-major: U_k Lambda_k^1/2 (P~ = Ep P' on the kept space) */
    double *Bp;     /* k x k, row-major: F2' - I */
    double *Hc;     /* k x k, row-major: F3' - B'^T B' */
    double *C;      /* H' (3k square), column-major, then its Cholesky factor */
    double *H;      /* H' before its factorization (for a shifted retry) */
    double *Zt;     /* 3r square: Z~/c; then 3r x 3k: Z~/c (Ep (x) I3) */
    int n_groups;
    int *grow, *grow_list; /* reduced rows of each origin group (CSR) */
    int *gcol;      /* kept columns of each group: gcol[g] .. gcol[g + 1] */
    double **Ep_blk; /* per group: its rows x its columns of Ep, row-major */
    double *gscratch; /* per group pair products (see factorize) */
    double shift;   /* the diagonal shift the last factorization needed (0: none) */
    /* the rest matrix's factor (integrators.c, "Reusing the rest factor"): C of the
     * coefficients rest_coef with K0 in place of K; rest_ok once made */
    double *C_rest;
    double rest_coef[5];
    int rest_ok;
    const double *Cf; /* the factor the solves use: C, or C_rest while solving with it */
    double coef[5];
    double last_factor_s;
    double *work;
};

void sem_structured_solver_destroy(sem_structured_solver *s)
{
    if (!s) return;
    if (s->L) cholmod_free_factor(&s->L, &s->common);
    cholmod_finish(&s->common);
    SEM_FREE_ALL(s->red, s->p_first, s->v_start, s->v_col, s->v_val, s->vt_start, s->vt_row, s->vt_val, s->F, s->T,
                 s->Ep, s->Bp, s->Hc, s->C, s->C_rest, s->H, s->Zt);
    if (s->Ep_blk)
        for (int g = 0; g < s->n_groups; ++g) free(s->Ep_blk[g]);
    SEM_FREE_ALL(s->Ep_blk, s->grow, s->grow_list, s->gcol, s->gscratch, s->work);
    free(s);
}

/* The distinct rows of P: a part's row equal (bit for bit) to the same row of an earlier part
 * of the same group is that row (the translation row always; every row with shared fits). */
static sem_status reduce_rows(sem_structured_solver *s, sem_error *err)
{
    const sem_object *o = s->o;
    const sem_structured_ops *ops = o->ops;
    int m = o->m;
    s->red = malloc(((size_t)s->r0 + 1) * sizeof(int));
    s->p_first = malloc(((size_t)s->r0 + 1) * sizeof(int));
    if (!s->red || !s->p_first) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    s->r = 0;
    for (int i = 0; i < o->n_parts; ++i)
        for (int k = 0; k < m; ++k) {
            int row = i * m + k, same = -1;
            if (k == 0 || o->d->shared_fit)
                for (int j = 0; j < i && same < 0; ++j) {
                    if (o->d->part_origin[j] != o->d->part_origin[i]) continue;
                    int a = ops->p_start[row], b = ops->p_start[j * m + k];
                    size_t len = (size_t)(ops->p_start[row + 1] - a);
                    if (len == (size_t)(ops->p_start[j * m + k + 1] - b) &&
                        memcmp(ops->p_val + a, ops->p_val + b, len * sizeof(double)) == 0)
                        same = s->red[j * m + k];
                }
            if (same >= 0) {
                s->red[row] = same;
            } else {
                s->p_first[s->r] = row;
                s->red[row] = s->r++;
            }
        }
    return SEM_OK;
}

/* S0 = sum_s a_s J_s^T J_s over the free control points, factorized. */
static sem_status factor_S0(sem_structured_solver *s, sem_error *err)
{
    const sem_object *o = s->o;
    const sem_structured_ops *ops = o->ops;
    size_t nt = 0;
    for (int r = 0; r < ops->n_rows; ++r) {
        size_t k = (size_t)(ops->j_start[r + 1] - ops->j_start[r]);
        nt += k * (k + 1) / 2;
    }
    cholmod_triplet *T = cholmod_allocate_triplet((size_t)s->n, (size_t)s->n, nt + 1, -1, CHOLMOD_REAL, &s->common);
    if (!T) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the sample matrix");
    int *ti = T->i, *tj = T->j;
    double *tx = T->x;
    size_t k = 0;
    for (int r = 0; r < ops->n_rows; ++r)
        for (int a = ops->j_start[r]; a < ops->j_start[r + 1]; ++a) {
            int fa = o->free_index[ops->j_col[a]];
            if (fa < 0) continue;
            for (int b = a; b < ops->j_start[r + 1]; ++b) {
                int fb = o->free_index[ops->j_col[b]];
                if (fb < 0) continue;
                ti[k] = fa > fb ? fa : fb;
                tj[k] = fa > fb ? fb : fa;
                tx[k++] = ops->area[r] * ops->j_val[a] * ops->j_val[b];
            }
        }
    T->nnz = k;
    cholmod_sparse *S0 = cholmod_triplet_to_sparse(T, k, &s->common);
    cholmod_free_triplet(&T, &s->common);
    if (!S0) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the sample matrix");
    s->L = cholmod_analyze(S0, &s->common);
    int ok = s->L && cholmod_factorize(S0, s->L, &s->common) && s->common.status == CHOLMOD_OK;
    cholmod_free_sparse(&S0, &s->common);
    if (!s->L) return sem_error_set(err, SEM_ERR_NOMEM, "CHOLMOD analysis of the sample matrix failed");
    if (!ok)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "a free control point is seen by no boundary sample (sample matrix "
                             "singular, CHOLMOD status %d)",
                             s->common.status);
    return SEM_OK;
}

/* V = [P~; G~] over the free control points (the reduced rows of P; G = sum_s a_s g_s^T J_s
 * with the rows of duplicates summed, G~ = E^T G); and V^T. */
static sem_status build_V(sem_structured_solver *s, sem_error *err)
{
    const sem_object *o = s->o;
    const sem_structured_ops *ops = o->ops;
    int r0 = s->r, n = s->n, nr = ops->n_rows;
    /* samples per reduced coefficient row (transpose of g) */
    int *gt_start = calloc((size_t)r0 + 1, sizeof(int));
    if (!gt_start) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int e = 0; e < ops->g_start[nr]; ++e) gt_start[s->red[ops->g_idx[e]] + 1]++;
    for (int r = 0; r < r0; ++r) gt_start[r + 1] += gt_start[r];
    int *gt_row = malloc(((size_t)gt_start[r0] + 1) * sizeof(int));
    double *gt_val = malloc(((size_t)gt_start[r0] + 1) * sizeof(double));
    int *fill = malloc(((size_t)r0 + 1) * sizeof(int));
    int *row_n = calloc(2 * (size_t)r0 + 1, sizeof(int));
    if (!gt_row || !gt_val || !fill || !row_n) {
        SEM_FREE_ALL(gt_start, gt_row, gt_val, fill, row_n);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    memcpy(fill, gt_start, (size_t)r0 * sizeof(int));
    for (int r = 0; r < nr; ++r)
        for (int e = ops->g_start[r]; e < ops->g_start[r + 1]; ++e) {
            int x = s->red[ops->g_idx[e]];
            gt_row[fill[x]] = r;
            gt_val[fill[x]++] = ops->area[r] * ops->g_val[e];
        }
    free(fill);
    /* G's rows: dense accumulation per row (one per thread), two passes (count, write) */
    double **G_vals = calloc((size_t)r0 + 1, sizeof(double *));
    int **G_cols = calloc((size_t)r0 + 1, sizeof(int *));
    int fail = 0;
    if (!G_vals || !G_cols) fail = 1;
#pragma omp parallel num_threads(o->nthreads) reduction(| : fail)
    {
        double *acc = calloc((size_t)n + 1, sizeof(double));
        int *mark = malloc(((size_t)n + 1) * sizeof(int));
        int *list = malloc(((size_t)n + 1) * sizeof(int));
        if (!acc || !mark || !list) fail = 1;
        if (mark)
            for (int f = 0; f < n; ++f) mark[f] = -1;
#pragma omp for schedule(dynamic, 4)
        for (int rho = 0; rho < r0; ++rho) {
            if (!acc || !mark || !list || !G_vals || !G_cols) continue;
            int cnt = 0;
            for (int t = gt_start[rho]; t < gt_start[rho + 1]; ++t) {
                int r = gt_row[t];
                for (int e = ops->j_start[r]; e < ops->j_start[r + 1]; ++e) {
                    int f = o->free_index[ops->j_col[e]];
                    if (f < 0) continue;
                    if (mark[f] != rho) {
                        mark[f] = rho;
                        acc[f] = 0;
                        list[cnt++] = f;
                    }
                    acc[f] += gt_val[t] * ops->j_val[e];
                }
            }
            /* sorted columns (the sums above are in sample order already) */
            for (int a = 1; a < cnt; ++a) {
                int x = list[a], b = a - 1;
                while (b >= 0 && list[b] > x) {
                    list[b + 1] = list[b];
                    --b;
                }
                list[b + 1] = x;
            }
            G_cols[rho] = malloc(((size_t)cnt + 1) * sizeof(int));
            G_vals[rho] = malloc(((size_t)cnt + 1) * sizeof(double));
            if (!G_cols[rho] || !G_vals[rho]) {
                fail = 1;
                continue;
            }
            for (int a = 0; a < cnt; ++a) {
                G_cols[rho][a] = list[a];
                G_vals[rho][a] = acc[list[a]];
            }
            row_n[r0 + rho] = cnt;
        }
        free(acc);
        free(mark);
        free(list);
    }
    sem_status st = SEM_OK;
    if (fail) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the error matrix's coupling");
        goto done;
    }
    for (int rho = 0; rho < r0; ++rho) {
        int full = s->p_first[rho];
        for (int e = ops->p_start[full]; e < ops->p_start[full + 1]; ++e)
            if (o->free_index[ops->p_col[e]] >= 0) row_n[rho]++;
    }
    s->v_start = malloc((2 * (size_t)r0 + 1) * sizeof(int));
    if (!s->v_start) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    s->v_start[0] = 0;
    for (int r = 0; r < 2 * r0; ++r) s->v_start[r + 1] = s->v_start[r] + row_n[r];
    size_t nnz = (size_t)s->v_start[2 * r0];
    s->v_col = malloc((nnz + 1) * sizeof(int));
    s->v_val = malloc((nnz + 1) * sizeof(double));
    s->vt_start = calloc((size_t)n + 1, sizeof(int));
    s->vt_row = malloc((nnz + 1) * sizeof(int));
    s->vt_val = malloc((nnz + 1) * sizeof(double));
    if (!s->v_col || !s->v_val || !s->vt_start || !s->vt_row || !s->vt_val) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the coupling matrix");
        goto done;
    }
    for (int rho = 0; rho < r0; ++rho) {
        int at = s->v_start[rho], full = s->p_first[rho];
        for (int e = ops->p_start[full]; e < ops->p_start[full + 1]; ++e) {
            int f = o->free_index[ops->p_col[e]];
            if (f < 0) continue;
            s->v_col[at] = f;
            s->v_val[at++] = ops->p_val[e];
        }
        memcpy(s->v_col + s->v_start[r0 + rho], G_cols[rho], (size_t)row_n[r0 + rho] * sizeof(int));
        memcpy(s->v_val + s->v_start[r0 + rho], G_vals[rho], (size_t)row_n[r0 + rho] * sizeof(double));
    }
    for (size_t e = 0; e < nnz; ++e) s->vt_start[s->v_col[e] + 1]++;
    for (int f = 0; f < n; ++f) s->vt_start[f + 1] += s->vt_start[f];
    {
        int *tf = malloc(((size_t)n + 1) * sizeof(int));
        if (!tf) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto done;
        }
        memcpy(tf, s->vt_start, (size_t)n * sizeof(int));
        for (int r = 0; r < 2 * r0; ++r)
            for (int e = s->v_start[r]; e < s->v_start[r + 1]; ++e) {
                s->vt_row[tf[s->v_col[e]]] = r;
                s->vt_val[tf[s->v_col[e]]++] = s->v_val[e];
            }
        free(tf);
    }
done:
    if (G_vals)
        for (int r = 0; r < r0; ++r) free(G_vals[r]);
    if (G_cols)
        for (int r = 0; r < r0; ++r) free(G_cols[r]);
    SEM_FREE_ALL(G_vals, G_cols, gt_start, gt_row, gt_val, row_n);
    return st;
}

/* F = V S0^-1 V^T, F_CHUNK columns at a time. */
static sem_status build_F(sem_structured_solver *s, sem_error *err)
{
    int R = 2 * s->r, n = s->n;
    s->F = malloc(((size_t)R * R + 1) * sizeof(double));
    cholmod_dense *B = cholmod_allocate_dense((size_t)n, F_CHUNK, (size_t)n, CHOLMOD_REAL, &s->common);
    if (!s->F || !B) {
        if (B) cholmod_free_dense(&B, &s->common);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the capacitance matrix");
    }
    for (int c0 = 0; c0 < R; c0 += F_CHUNK) {
        int nc = R - c0 < F_CHUNK ? R - c0 : F_CHUNK;
        double *bx = B->x;
        B->ncol = (size_t)nc;
        memset(bx, 0, (size_t)n * nc * sizeof(double));
        for (int j = 0; j < nc; ++j)
            for (int e = s->v_start[c0 + j]; e < s->v_start[c0 + j + 1]; ++e)
                bx[(size_t)j * n + s->v_col[e]] = s->v_val[e];
        cholmod_dense *X = cholmod_solve(CHOLMOD_A, s->L, B, &s->common);
        if (!X) {
            cholmod_free_dense(&B, &s->common);
            return sem_error_set(err, SEM_ERR_NOMEM, "CHOLMOD solve failed");
        }
        const double *xx = X->x;
#pragma omp parallel for schedule(dynamic, 4) num_threads(s->o->nthreads)
        for (int r = 0; r < R; ++r)
            for (int j = 0; j < nc; ++j) {
                double v = 0;
                const double *col = xx + (size_t)j * n;
                for (int e = s->v_start[r]; e < s->v_start[r + 1]; ++e) v += s->v_val[e] * col[s->v_col[e]];
                s->F[(size_t)r * R + c0 + j] = v;
            }
        cholmod_free_dense(&X, &s->common);
    }
    B->ncol = F_CHUNK;
    cholmod_free_dense(&B, &s->common);
    /* exactly symmetric */
    for (int r = 0; r < R; ++r)
        for (int c = r + 1; c < R; ++c) {
            double v = 0.5 * (s->F[(size_t)r * R + c] + s->F[(size_t)c * R + r]);
            s->F[(size_t)r * R + c] = s->F[(size_t)c * R + r] = v;
        }
    return SEM_OK;
}

/* F1 = P~ S0^-1 P~^T is positive semi-definite but can be nearly singular: parts of one
 * origin whose fits are nearly dependent (a flat face whose linear fit is determined only
 * through its origin). Its eigenvectors give a basis of P~'s row space in which F1 is the
 * identity: P' = T^T P~ with T = U_k Lambda_k^-1/2 over the eigenvalues above
 * F1_CUTOFF x the largest; the others are directions that P~^T barely reaches, whose omission
 * only perturbs the preconditioner (conjugate gradients solve with the exact A). With
 * Ep = U_k Lambda_k^1/2 (P~ = Ep P' on the kept space): F2' = T^T F2 Ep, F3' = Ep^T F3 Ep,
 * B' = F2' - I and the constant Hc = F3' - B'^T B'. */
#define F1_CUTOFF 1e-12
/* The blocks F1 is decomposed in: origin groups, joined where a weld or a seam tie joins them
 * (union-find, each block numbered by its first group). block[g] for every group; returns
 * the number of blocks, -1 when out of memory. */
static int blocks_of(const sem_object *o, int *block)
{
    int ng = o->n_groups, n = 0;
    int *parent = malloc(((size_t)ng + 1) * sizeof *parent);
    if (!parent) return -1;
    for (int g = 0; g < ng; ++g) parent[g] = g;
    for (int k = 0; k < o->n_welds; ++k)
        sem_uf_unite(parent, o->ctrl_group[o->weld_ctrl[2 * k]], o->ctrl_group[o->weld_ctrl[2 * k + 1]]);
    for (int t = 0; t < o->n_seam_ties; ++t) { /* a seam tie's row crosses its two parts' groups */
        int e0, e1;
        seam_tie_row(o, t, &e0, &e1);
        for (int e = e0 + 1; e < e1; ++e)
            sem_uf_unite(parent, o->ctrl_group[o->seams.row_ctrl[e0]], o->ctrl_group[o->seams.row_ctrl[e]]);
    }
    /* a root is the lowest group of its set, so it is numbered before its members */
    for (int g = 0; g < ng; ++g) {
        int root = sem_uf_find(parent, g);
        block[g] = root == g ? n++ : block[root];
    }
    free(parent);
    return n;
}

static sem_status schur_constants(sem_structured_solver *s, sem_error *err)
{
    int r = s->r, R = 2 * r;
    size_t rr = (size_t)r * r;
    double *U = malloc(rr * sizeof(double) + 1), *lam = malloc((size_t)r * sizeof(double) + 1);
    if (!U || !lam) {
        free(U);
        free(lam);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    /* Jacobi scaling first: the rows of P~ differ in scale by powers of the model size (the
     * basis terms 1, X, X^2), so the cut-off applies to D^-1/2 F1 D^-1/2, D = diag F1 */
    double *dsq = malloc((size_t)r * sizeof(double) + 1);
    if (!dsq) {
        free(U);
        free(lam);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int a = 0; a < r; ++a) {
        double v = s->F[(size_t)a * R + a];
        dsq[a] = v > 0 ? sqrt(v) : 0;
    }
    /* F1 is block diagonal by origin group (S0 by part, P~'s rows of a group over the
     * group's control points), so each group's block is decomposed on its own: T and Ep are
     * block diagonal too, the kept columns of group g at gcol[g] .. gcol[g + 1]. A weld
     * (object_welds.c) puts a row across two groups into S0, which couples their blocks of
     * F1: such groups are decomposed together, as one "group" here (blocks_of) */
    const sem_object *o = s->o;
    int m = o->m;
    int *block = malloc(((size_t)o->n_groups + 1) * sizeof *block);
    if (!block) {
        free(U);
        free(lam);
        free(dsq);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    int ng = blocks_of(o, block);
    if (ng < 0) {
        SEM_FREE_ALL(U, lam, dsq, block);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    s->n_groups = ng;
    s->grow = calloc((size_t)ng + 1, sizeof(int));
    s->grow_list = malloc(((size_t)r + 1) * sizeof(int));
    s->gcol = calloc((size_t)ng + 1, sizeof(int));
    s->Ep_blk = calloc((size_t)ng + 1, sizeof(double *));
    if (!s->grow || !s->grow_list || !s->gcol || !s->Ep_blk) {
        SEM_FREE_ALL(U, lam, dsq, block);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int q = 0; q < r; ++q) s->grow[block[o->d->part_origin[s->p_first[q] / m]] + 1]++;
    for (int g = 0; g < ng; ++g) s->grow[g + 1] += s->grow[g];
    {
        int *fill = malloc(((size_t)ng + 1) * sizeof(int));
        if (!fill) {
            SEM_FREE_ALL(U, lam, dsq, block);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        memcpy(fill, s->grow, (size_t)ng * sizeof(int));
        for (int q = 0; q < r; ++q) s->grow_list[fill[block[o->d->part_origin[s->p_first[q] / m]]]++] = q;
        free(fill);
    }
    free(block);
    /* per group: scaled block into U (row-major rg x rg), eigenvalues into lam; the kept
     * eigenpairs are collected into Ucol / lcol (column j of the whole basis) */
    double *Ucol = calloc(rr + 1, sizeof(double)), *lcol = malloc((size_t)r * sizeof(double) + 1);
    int *col_row_group = malloc((size_t)r * sizeof(int) + 1);
    if (!Ucol || !lcol || !col_row_group) {
        SEM_FREE_ALL(U, lam, dsq, Ucol, lcol, col_row_group);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    int k = 0;
    lapack_int info = 0;
    for (int g = 0; g < ng && info == 0; ++g) {
        int r0g = s->grow[g], rg = s->grow[g + 1] - r0g;
        const int *rows = s->grow_list + r0g;
        s->gcol[g] = k;
        if (rg == 0) continue;
        for (int a = 0; a < rg; ++a)
            for (int b = 0; b < rg; ++b) {
                int qa = rows[a], qb = rows[b];
                U[(size_t)a * rg + b] =
                    dsq[qa] > 0 && dsq[qb] > 0 ? s->F[(size_t)qa * R + qb] / (dsq[qa] * dsq[qb]) : 0;
            }
        info = LAPACKE_dsyevd(LAPACK_ROW_MAJOR, 'V', 'L', rg, U, rg, lam);
        if (info != 0) break;
        double lmax = lam[rg - 1];
        for (int j = 0; j < rg; ++j) {
            if (!(lam[j] > F1_CUTOFF * lmax)) continue;
            for (int a = 0; a < rg; ++a) Ucol[(size_t)rows[a] * r + k] = U[(size_t)a * rg + j];
            lcol[k] = lam[j];
            col_row_group[k] = g;
            k++;
        }
    }
    s->gcol[ng] = k;
    (void)col_row_group;
    free(col_row_group);
    if (info != 0) {
        SEM_FREE_ALL(U, lam, dsq, Ucol, lcol);
        return sem_error_set(err, SEM_ERR_NUMERIC, "structured solver: eigenvalues of F1 failed (%d)", (int)info);
    }
    s->k = k;
    s->T = malloc(((size_t)r * k + 1) * sizeof(double));
    s->Ep = malloc(((size_t)r * k + 1) * sizeof(double));
    s->Bp = malloc(((size_t)k * k + 1) * sizeof(double));
    s->Hc = malloc(((size_t)k * k + 1) * sizeof(double));
    double *X = malloc(((size_t)r * k + 1) * sizeof(double));
    if (!s->T || !s->Ep || !s->Bp || !s->Hc || !X) {
        SEM_FREE_ALL(U, lam, X, dsq, Ucol, lcol);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int a = 0; a < r; ++a)
        for (int j = 0; j < k; ++j) {
            double u = Ucol[(size_t)a * r + j], l = lcol[j];
            s->T[(size_t)a * k + j] = dsq[a] > 0 ? u / (dsq[a] * sqrt(l)) : 0;
            s->Ep[(size_t)a * k + j] = u * dsq[a] * sqrt(l);
        }
    free(Ucol);
    free(lcol);
    /* each group's block of Ep (its rows x its kept columns), for forming H' */
    for (int g = 0; g < ng; ++g) {
        int r0g = s->grow[g], rg = s->grow[g + 1] - r0g, c0 = s->gcol[g], kg = s->gcol[g + 1] - c0;
        s->Ep_blk[g] = malloc(((size_t)rg * kg + 1) * sizeof(double));
        if (!s->Ep_blk[g]) {
            SEM_FREE_ALL(U, lam, X, dsq);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        for (int a = 0; a < rg; ++a)
            for (int j = 0; j < kg; ++j)
                s->Ep_blk[g][(size_t)a * kg + j] = s->Ep[(size_t)s->grow_list[r0g + a] * k + c0 + j];
    }
    /* F2' = T^T F2 Ep: X = F2 Ep (r x k), then T^T X */
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, r, k, r, 1.0, s->F + r, R, s->Ep, k, 0.0, X, k);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, k, r, 1.0, s->T, k, X, k, 0.0, s->Bp, k);
    for (int j = 0; j < k; ++j) s->Bp[(size_t)j * k + j] -= 1.0;
    /* F3' = Ep^T F3 Ep, then Hc = F3' - B'^T B' */
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, r, k, r, 1.0, s->F + (size_t)r * R + r, R, s->Ep, k,
                0.0, X, k);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, k, r, 1.0, s->Ep, k, X, k, 0.0, s->Hc, k);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, k, k, -1.0, s->Bp, k, s->Bp, k, 1.0, s->Hc, k);
    for (int a = 0; a < k; ++a)
        for (int b = a + 1; b < k; ++b) {
            double v = 0.5 * (s->Hc[(size_t)a * k + b] + s->Hc[(size_t)b * k + a]);
            s->Hc[(size_t)a * k + b] = s->Hc[(size_t)b * k + a] = v;
        }
    SEM_FREE_ALL(U, lam, X, dsq);
    return SEM_OK;
}

sem_status sem_structured_solver_create(sem_object *o, sem_structured_solver **out, sem_error *err)
{
    *out = NULL;
    sem_structured_solver *s = calloc(1, sizeof *s);
    if (!s) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    s->o = o;
    s->n = o->n_free;
    s->r0 = o->ops->r0;
    cholmod_start(&s->common);
    s->common.print = 0;
    s->common.error_handler = NULL;
    int blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(BLAS_THREADS);
    sem_status st = reduce_rows(s, err);
    if (st == SEM_OK && 3 * (size_t)s->r > SEM_MAX_STRUCTURED_COEFFICIENTS)
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "%d parts make a %d x %d coefficient matrix (limit "
                           "SEM_MAX_STRUCTURED_COEFFICIENTS = %d): use the sparse solver",
                           o->n_parts, 3 * s->r, 3 * s->r, SEM_MAX_STRUCTURED_COEFFICIENTS);
    if (st == SEM_OK) st = factor_S0(s, err);
    if (st == SEM_OK) st = build_V(s, err);
    if (st == SEM_OK) st = build_F(s, err);
    if (st == SEM_OK) st = schur_constants(s, err);
    openblas_set_num_threads(blas_threads);
    if (st == SEM_OK) {
        size_t N = 3 * (size_t)s->k, N3r = 3 * (size_t)s->r;
        s->C = malloc((N * N + 1) * sizeof(double));
        s->H = malloc((N * N + 1) * sizeof(double));
        s->Zt = malloc((N3r * N3r + 1) * sizeof(double));
        /* the largest group's r_g x r_h, r_g x k_h and k_g x k_h blocks */
        size_t rmax = 1, kmax = 1;
        for (int g = 0; g < s->n_groups; ++g) {
            size_t rg = (size_t)(s->grow[g + 1] - s->grow[g]), kg = (size_t)(s->gcol[g + 1] - s->gcol[g]);
            if (rg > rmax) rmax = rg;
            if (kg > kmax) kmax = kg;
        }
        s->gscratch = malloc((rmax * rmax + rmax * kmax + kmax * kmax + 1) * sizeof(double));
        s->work = malloc((6 * (size_t)o->n_ctrl + 12 * (size_t)s->r + 1) * sizeof(double));
        s->Cf = s->C;
        if (!s->C || !s->H || !s->Zt || !s->gscratch || !s->work)
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a %zu x %zu coefficient matrix", N, N);
    }
    if (st != SEM_OK) {
        sem_structured_solver_destroy(s);
        return st;
    }
    *out = s;
    return SEM_OK;
}

void sem_structured_solver_set(sem_structured_solver *s, const double c[5])
{
    memcpy(s->coef, c, sizeof s->coef);
}

double sem_structured_solver_factor_seconds(const sem_structured_solver *s)
{
    return s->last_factor_s;
}

/* T += sign Z~/c with Z~/c = Bb + Bz + (cM Mz + cA Az + cK Kz + cD K0z) / c reduced to the distinct
 * rows; T column-major with leading dimension ld, entry (3 rho + d) at offset off. */
static void add_Z(sem_structured_solver *s, double *T, size_t ld, size_t off, double sign)
{
    const sem_object *o = s->o;
    const sem_structured_ops *ops = o->ops;
    int r0 = s->r0, m = o->m, M3 = 3 * m;
    double c = 2.0 * s->coef[1], cM = s->coef[0] / c, cK = s->coef[2] / c, cD = s->coef[3] / c;
    double cA = ops->Az ? s->coef[4] / c : 0.0;
    /* scalar parts (the same for each coordinate; part-pair blocks, columns ascending);
     * duplicates add up, so serial */
    for (int a = 0; a < r0; ++a) {
        size_t ia = off + 3 * (size_t)s->red[a];
        int pa = a / m, x = a % m;
        for (int e = ops->nb_start[pa]; e < ops->nb_start[pa + 1]; ++e) {
            size_t at = ((size_t)e * m + x) * m;
            for (int y = 0; y < m; ++y) {
                double v = ops->Bb[at + y] + ops->Bz[at + y] + cM * ops->Mz[at + y];
                if (cA != 0) v += cA * ops->Az[at + y];
                if (v == 0) continue;
                size_t ib = off + 3 * (size_t)s->red[ops->nb_part[e] * m + y];
                for (int d = 0; d < 3; ++d) T[(ib + d) * ld + ia + d] += sign * v;
            }
        }
    }
    if (cK == 0 && cD == 0) return;
    /* stiffness: per stored pair (a <= b with points), its own-basis blocks (a, b), (b, a) */
    int ma = o->ma, n3 = 3 * ma;
    size_t bs = (size_t)n3 * n3;
    double Kc[27 * 27], blk[30 * 30];
    for (int pr = 0; pr < o->n_pairs; ++pr) {
        int a = o->pair_a[pr], b = o->pair_b[pr];
        if (a > b || o->plist_start[pr + 1] == o->plist_start[pr]) continue;
        const double *K = o->Kz + (size_t)pr * bs, *K0 = o->K0z + (size_t)pr * bs;
        for (size_t e = 0; e < bs; ++e) Kc[e] = cK * K[e] + cD * K0[e];
        for (int t = 0; t < (a == b ? 1 : 2); ++t) {
            sem_structured_own_basis(o, a, b, Kc, t, blk);
            int pa = t ? b : a, pb = t ? a : b;
            for (int x = 0; x < M3; ++x) {
                size_t ia = off + 3 * (size_t)s->red[pa * m + x / 3] + (size_t)(x % 3);
                for (int y = 0; y < M3; ++y) {
                    size_t ib = off + 3 * (size_t)s->red[pb * m + y / 3] + (size_t)(y % 3);
                    T[ib * ld + ia] += sign * blk[(size_t)x * M3 + y];
                }
            }
        }
    }
}

sem_status sem_structured_solver_factorize(sem_structured_solver *s, sem_error *err)
{
    double t0 = omp_get_wtime();
    if (!(s->coef[1] > 0)) return sem_error_set(err, SEM_ERR_INVALID, "structured solver: no error term");
    int k = s->k;
    size_t N = 3 * (size_t)k, N3r = 3 * (size_t)s->r;
    int blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(BLAS_THREADS);
    /* H' = (Ep (x) I3)^T (Z~/c) (Ep (x) I3) - Hc (x) I3. Ep is block diagonal by origin group
     * and Z~ couples two groups only where their parts share a point or sample, so H' is
     * formed block by block: H'_gh = Ep_g^T Z~_gh Ep_h per coordinate pair, for the group
     * pairs with a non-zero block. */
    memset(s->Zt, 0, N3r * N3r * sizeof(double));
    add_Z(s, s->Zt, N3r, 0, 1.0);
    memset(s->H, 0, N * N * sizeof(double));
    for (int g = 0; g < s->n_groups; ++g)
        for (int h = 0; h < s->n_groups; ++h) {
            int rg = s->grow[g + 1] - s->grow[g], rh = s->grow[h + 1] - s->grow[h];
            int kg = s->gcol[g + 1] - s->gcol[g], kh = s->gcol[h + 1] - s->gcol[h];
            if (!rg || !rh || !kg || !kh) continue;
            const int *rows_g = s->grow_list + s->grow[g], *rows_h = s->grow_list + s->grow[h];
            double *Zb = s->gscratch, *Xb = Zb + (size_t)rg * rh, *Yb = Xb + (size_t)rg * kh;
            for (int d = 0; d < 3; ++d)
                for (int d2 = 0; d2 < 3; ++d2) {
                    int any = 0;
                    for (int a2 = 0; a2 < rg; ++a2)
                        for (int b2 = 0; b2 < rh; ++b2) {
                            double v = s->Zt[(3 * (size_t)rows_h[b2] + d2) * N3r + 3 * (size_t)rows_g[a2] + d];
                            Zb[(size_t)a2 * rh + b2] = v;
                            any |= v != 0;
                        }
                    if (!any) continue;
                    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, rg, kh, rh, 1.0, Zb, rh, s->Ep_blk[h], kh,
                                0.0, Xb, kh);
                    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, kg, kh, rg, 1.0, s->Ep_blk[g], kg, Xb, kh,
                                0.0, Yb, kh);
                    for (int i2 = 0; i2 < kg; ++i2)
                        for (int j2 = 0; j2 < kh; ++j2)
                            s->H[(3 * (size_t)(s->gcol[h] + j2) + d2) * N + 3 * (size_t)(s->gcol[g] + i2) + d] =
                                Yb[(size_t)i2 * kh + j2];
                }
        }
    for (int a = 0; a < k; ++a)
        for (int b = 0; b < k; ++b) {
            double v = s->Hc[(size_t)a * k + b];
            for (int d = 0; d < 3; ++d) s->H[(3 * (size_t)b + d) * N + 3 * (size_t)a + d] -= v;
        }
    /* exactly symmetric */
    for (size_t a = 0; a < N; ++a)
        for (size_t b = a + 1; b < N; ++b) {
            double v = 0.5 * (s->H[b * N + a] + s->H[a * N + b]);
            s->H[b * N + a] = s->H[a * N + b] = v;
        }
    /* H' is formed by differences of terms of the error matrix's size (c = 2 gamma is
     * large), so where A is held only by terms far below that its round-off can leave H'
     * slightly indefinite although A is positive definite. Then H' gets the smallest
     * diagonal shift (1e-13 of its largest diagonal, times 100 per try) that factorizes: it
     * is the preconditioner of conjugate gradients on the exact A, which decide (a solve
     * that meets a non-positive curvature fails as not positive definite). */
    s->shift = 0;
    double dmax = 0;
    for (size_t q = 0; q < N; ++q) dmax = fmax(dmax, fabs(s->H[q * N + q]));
    memcpy(s->C, s->H, N * N * sizeof(double));
    lapack_int info = N > 0 ? LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'L', (lapack_int)N, s->C, (lapack_int)N) : 0;
    for (int t = 0; info != 0 && t < 6; ++t) {
        s->shift = (s->shift > 0 ? 100 * s->shift : 1e-13 * dmax);
        memcpy(s->C, s->H, N * N * sizeof(double));
        for (size_t q = 0; q < N; ++q) s->C[q * N + q] += s->shift;
        info = LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'L', (lapack_int)N, s->C, (lapack_int)N);
    }
    openblas_set_num_threads(blas_threads);
    s->last_factor_s = omp_get_wtime() - t0;
    if (info != 0)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "system matrix is not positive definite (coefficient-space pivot %d): "
                             "the state may have exploded or the object is not held",
                             (int)info);
    return SEM_OK;
}

/* w = Cap^-1 v in place; v = [v1; v2], 3r each (index 3 rho + d), in the rows of P~, G~.
 * In the basis P' = T^T P~, G' = Ep^T G~ the capacitance is [[I, B'], [B'^T, F3' - Z'/c]]:
 * w2' = -H'^-1 (v2' - B'^T v1'), w1' = v1' - B' w2', then back: w1 = T w1', w2 = Ep w2'. */
static void capacitance_solve(sem_structured_solver *s, double *v)
{
    int r = s->r, k = s->k;
    double *v1 = v, *v2 = v + 3 * (size_t)r;
    double *a1 = s->work + 6 * (size_t)s->o->n_ctrl + 6 * (size_t)r, *a2 = a1 + 3 * (size_t)k;
    /* v1' = T^T v1, v2' = Ep^T v2 (r x 3 row-major blocks) */
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, 3, r, 1.0, s->T, k, v1, 3, 0.0, a1, 3);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, 3, r, 1.0, s->Ep, k, v2, 3, 0.0, a2, 3);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, k, 3, k, -1.0, s->Bp, k, a1, 3, 1.0, a2, 3);
    lapack_int info = 0, one = 1, N = 3 * k;
    char uplo = 'L';
    if (N > 0) LAPACK_dpotrs(&uplo, &N, &one, (double *)s->Cf, &N, a2, &N, &info);
    for (int q = 0; q < 3 * k; ++q) a2[q] = -a2[q];
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, k, 3, k, -1.0, s->Bp, k, a2, 3, 1.0, a1, 3);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, r, 3, k, 1.0, s->T, k, a1, 3, 0.0, v1, 3);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, r, 3, k, 1.0, s->Ep, k, a2, 3, 0.0, v2, 3);
}

/* x = A^-1 b by Woodbury (to round-off of the factored form); b, x: 3n free values. */
static void woodbury(sem_structured_solver *s, const double *b, double *x)
{
    int n = s->n, r = s->r, R = 2 * r;
    double c = 2.0 * s->coef[1];
    cholmod_dense *B = cholmod_allocate_dense((size_t)n, 3, (size_t)n, CHOLMOD_REAL, &s->common);
    if (!B) return;
    double *bx = B->x;
    for (int f = 0; f < n; ++f)
        for (int d = 0; d < 3; ++d) bx[(size_t)d * n + f] = b[3 * (size_t)f + d];
    cholmod_dense *T = cholmod_solve(CHOLMOD_A, s->L, B, &s->common);
    double *w = s->work + 6 * (size_t)s->o->n_ctrl;
    const double *t = T ? T->x : NULL;
    if (!t) {
        cholmod_free_dense(&B, &s->common);
        return;
    }
    /* w = V t: rows of P~ then of G~, 3 rho + d each */
#pragma omp parallel for schedule(static) num_threads(s->o->nthreads)
    for (int row = 0; row < R; ++row) {
        double a[3] = {0, 0, 0};
        for (int e = s->v_start[row]; e < s->v_start[row + 1]; ++e)
            for (int d = 0; d < 3; ++d) a[d] += s->v_val[e] * t[(size_t)d * n + s->v_col[e]];
        for (int d = 0; d < 3; ++d) w[3 * (size_t)row + d] = a[d];
    }
    capacitance_solve(s, w);
    /* B = V^T w */
#pragma omp parallel for schedule(static) num_threads(s->o->nthreads)
    for (int f = 0; f < n; ++f) {
        double a[3] = {0, 0, 0};
        for (int e = s->vt_start[f]; e < s->vt_start[f + 1]; ++e) {
            const double *wr = w + 3 * (size_t)s->vt_row[e];
            for (int d = 0; d < 3; ++d) a[d] += s->vt_val[e] * wr[d];
        }
        for (int d = 0; d < 3; ++d) bx[(size_t)d * n + f] = a[d];
    }
    cholmod_dense *X = cholmod_solve(CHOLMOD_A, s->L, B, &s->common);
    const double *xx = X ? X->x : NULL;
    for (int f = 0; f < n; ++f)
        for (int d = 0; d < 3; ++d)
            x[3 * (size_t)f + d] = (t[(size_t)d * n + f] - (xx ? xx[(size_t)d * n + f] : 0)) / c;
    cholmod_free_dense(&B, &s->common);
    cholmod_free_dense(&T, &s->common);
    if (X) cholmod_free_dense(&X, &s->common);
}

/* y = A x over the free dofs (the exact products of structured_operators.c). */
static void apply_A(sem_structured_solver *s, const double *x, double *y)
{
    const sem_object *o = s->o;
    size_t nf = 3 * (size_t)o->n_ctrl;
    double *xf = s->work, *yf = s->work + nf;
    memset(xf, 0, nf * sizeof(double));
    for (int c = 0; c < o->n_ctrl; ++c) {
        int f = o->free_index[c];
        if (f >= 0)
            for (int d = 0; d < 3; ++d) xf[3 * (size_t)c + d] = x[3 * (size_t)f + d];
    }
    sem_structured_multiply(o, s->coef[0], s->coef[1], s->coef[2], s->coef[3], s->coef[4], xf, yf);
    for (int c = 0; c < o->n_ctrl; ++c) {
        int f = o->free_index[c];
        if (f >= 0)
            for (int d = 0; d < 3; ++d) y[3 * (size_t)f + d] = yf[3 * (size_t)c + d];
    }
}

static double dot(const double *a, const double *b, size_t n)
{
    double s0 = 0, s1 = 0, s2 = 0, s3 = 0;
    size_t i = 0;
    for (; i + 3 < n; i += 4) {
        s0 += a[i] * b[i];
        s1 += a[i + 1] * b[i + 1];
        s2 += a[i + 2] * b[i + 2];
        s3 += a[i + 3] * b[i + 3];
    }
    for (; i < n; ++i) s0 += a[i] * b[i];
    return (s0 + s1) + (s2 + s3);
}

/* CG on the exact A preconditioned by the Woodbury solve with the factor Cf, at most max_it
 * iterations; *converged says whether it reached CG_TOLERANCE (soft: not an error). */
static sem_status cg_solve(sem_structured_solver *s, const double *b, double *x, int max_it, int *converged,
                           sem_error *err)
{
    *converged = 0;
    size_t n3 = 3 * (size_t)s->n;
    if (n3 == 0) return SEM_OK;
    /* b, the residual, the preconditioned residual, the direction and A p */
    double *bb = malloc(5 * n3 * sizeof(double));
    if (!bb) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory in the solve");
    double *rr = bb + n3, *zz = rr + n3, *p = zz + n3, *q = p + n3;
    int blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(BLAS_THREADS);
    memcpy(bb, b, n3 * sizeof(double));
    double bnorm = sqrt(dot(bb, bb, n3));
    sem_status st = SEM_OK;
    woodbury(s, bb, x);
    if (bnorm == 0) {
        *converged = 1;
        goto done;
    }
    apply_A(s, x, q);
    for (size_t i = 0; i < n3; ++i) rr[i] = bb[i] - q[i];
    double rnorm = sqrt(dot(rr, rr, n3));
    if (rnorm <= CG_TOLERANCE * bnorm) {
        *converged = 1;
        goto done;
    }
    woodbury(s, rr, zz);
    memcpy(p, zz, n3 * sizeof(double));
    double rz = dot(rr, zz, n3);
    int it;
    for (it = 0; it < max_it; ++it) {
        apply_A(s, p, q);
        double pq = dot(p, q, n3);
        if (!(pq > 0)) {
            if (max_it != CG_MAX_ITERATIONS) goto done; /* the rest factor's try: soft */
            st = sem_error_set(err, SEM_ERR_NUMERIC,
                               "system matrix is not positive definite (a direction of non-positive "
                               "curvature): the state may have exploded or the object is not held");
            goto done;
        }
        double alpha = rz / pq;
        for (size_t i = 0; i < n3; ++i) {
            x[i] += alpha * p[i];
            rr[i] -= alpha * q[i];
        }
        rnorm = sqrt(dot(rr, rr, n3));
        if (rnorm <= CG_TOLERANCE * bnorm) {
            *converged = 1;
            break;
        }
        woodbury(s, rr, zz);
        double rz1 = dot(rr, zz, n3);
        double beta = rz1 / rz;
        rz = rz1;
        for (size_t i = 0; i < n3; ++i) p[i] = zz[i] + beta * p[i];
    }
    if (!*converged && rnorm <= CG_FAIL * bnorm && max_it == CG_MAX_ITERATIONS) *converged = 1;
    if (!*converged && max_it == CG_MAX_ITERATIONS)
        st = sem_error_set(err, SEM_ERR_NUMERIC,
                           "the structured solve did not converge (relative residual %.2g after %d "
                           "refinement iterations)",
                           rnorm / bnorm, it);
done:
    openblas_set_num_threads(blas_threads);
    free(bb);
    return st;
}

sem_status sem_structured_solver_solve(sem_structured_solver *s, const double *b, double *x,
                                       sem_error *err)
{
    int converged = 0;
    s->Cf = s->C;
    return cg_solve(s, b, x, CG_MAX_ITERATIONS, &converged, err);
}

sem_status sem_structured_solver_factorize_rest(sem_structured_solver *s, int *factored, sem_error *err)
{
    const double rc[5] = {s->coef[0], s->coef[1], 0.0, s->coef[2] + s->coef[3], s->coef[4]};
    *factored = 0;
    if (s->rest_ok && memcmp(rc, s->rest_coef, sizeof rc) == 0) return SEM_OK;
    s->rest_ok = 0;
    size_t N = 3 * (size_t)s->k;
    if (!s->C_rest && !(s->C_rest = malloc((N * N + 1) * sizeof(double))))
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the rest factor");
    /* factorize with K0 in place of K, then keep that factor apart */
    double now[5];
    memcpy(now, s->coef, sizeof now);
    memcpy(s->coef, rc, sizeof rc);
    sem_status st = sem_structured_solver_factorize(s, err);
    memcpy(s->coef, now, sizeof now);
    if (st != SEM_OK) return st;
    double *t = s->C_rest;
    s->C_rest = s->C;
    s->C = t;
    s->Cf = s->C;
    memcpy(s->rest_coef, rc, sizeof rc);
    s->rest_ok = 1;
    *factored = 1;
    return SEM_OK;
}

sem_status sem_structured_solver_solve_rest(sem_structured_solver *s, const double *b, double *x, int max_it,
                                            int *solved, sem_error *err)
{
    *solved = 0;
    if (!s->rest_ok) return SEM_OK;
    s->Cf = s->C_rest;
    sem_status st = cg_solve(s, b, x, max_it, solved, err);
    s->Cf = s->C;
    return st;
}

int sem_structured_solver_coefficients(const sem_structured_solver *s)
{
    return 3 * s->k;
}
