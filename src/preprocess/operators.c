/*
 * operators.c - the SEM discrete operators (paper Sec. 7, Eq. 12-16).
 *
 * The SEM map at a point X is x(X) = sum_i w_i(X) b(X - Xbar_i)^T Pi_i Q (Eq. 6, 12), so every
 * operator factors through the small "polynomial space" of dimension n_parts * m (m = 4 or
 * 10 basis terms per part):
 *
 *     Gamma = G Pi,        G[p, i*m+k]       = w_pi b_k(X_p - Xbar_i)          (Eq. 12-13)
 *     Grad  = G' Pi,       G'[3p+e, i*m+k]   = w_pi d b_k / d X_e (X_p - Xbar_i) (Eq. 15,
 *                                              weights held constant near each point)
 *     M     = Pi^T (G^T V G) Pi                                                 (Eq. 14)
 *     M_eps = (Gs Pi - J)^T A (Gs Pi - J)
 *           = Pi^T (Hs Pi - K) - K^T Pi + J^T A J,   Hs = Gs^T A Gs, K = Gs^T A J  (Eq. 16)
 *
 * with V = diag(quadrature volumes), A = diag(sample areas), Gs = G at the boundary samples.
 * Forming M as sum_p vol_p Gamma_p^T Gamma_p directly costs sum_p nnz(Gamma_p)^2, which is
 * n_quad x n_ctrl^2 for models whose weights couple every part (Table 1: Nnz% = 100); the
 * factored products cost sum_p (parts at p x m)^2 plus two sparse products with Pi, which is
 * what the paper means by Pi being sparse. No dense matrix of size dofs x points is formed.
 *
 * All products are row-parallel (Gustavson with a dense accumulator of n_cols per thread),
 * each row computed by one thread in a fixed order: results do not depend on the thread
 * count. M and M_eps are formed as upper triangles (half the work) and mirrored, so they are
 * exactly symmetric.
 *
 * Nnz% (Table 1): the q-space stiffness pattern is the union over points of
 * cols(Grad rows of p) x cols(Grad rows of p), Kronecker I3; every scalar non-zero becomes a
 * 3x3 block so the percentage of the scalar pattern over n_ctrl^2 is the q-space figure. It
 * is computed structurally as the pattern of Pi^T (U^T U) Pi, U the per-point union of the
 * G' rows, with all values 1 so no cancellation can hide an entry.
 *
 * Default gamma (Sec. 7.6): the error energy gamma * integral_boundary |Gamma q - J q|^2 dA has
 * units gamma x m^4 while elastic energy is Pa x m^3, so gamma must be a stiffness per length:
 * gamma = kappa E / L, L = bounding-box diagonal of the boundary samples, kappa = 1000. See
 * docs/preprocessing.md for the reasoning and for converting the paper's unweighted gammas.
 */
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "steps.h"
#include "util/threads.h"

/* ------------------------------------------------------------------------------------ */
/* sparse helpers                                                                        */

/* Multiply-adds below which a product runs on one thread. */
#define PARALLEL_WORK 200000

static int int_cmp(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

/* First position in B's row a with column >= c (rows are sorted). */
static int row_lower_bound(const sem_csr *B, int a, int c)
{
    int lo = B->row_start[a], hi = B->row_start[a + 1];
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (B->col[mid] < c) lo = mid + 1;
        else hi = mid;
    }
    return lo;
}

/* C = A B (structural: entries that sum to zero are kept). Two passes: count, then fill;
 * rows in parallel, each row by one thread, so the result is deterministic. When
 * count_only is set, only *nnz_out is computed and C is untouched. With upper_only, only
 * the entries with column >= row are formed: the upper triangle of a product known to be
 * symmetric (Eq. 14, 16), half the work. */
static sem_status csr_product_ex(const sem_csr *A, const sem_csr *B, sem_csr *C, int count_only,
                                 size_t *nnz_out, int upper_only, int threads)
{
    const int n_rows = A->n_rows, n_cols = B->n_cols;
    int *count = calloc((size_t)n_rows + 1, sizeof(int));
    if (!count) return SEM_ERR_NOMEM;
    int failed = 0;
    size_t total = 0;
    /* Threads only pay off for real work: a parallel region costs a barrier, which on a
     * loaded machine can take longer than a small product. */
    size_t work = 0;
    for (size_t k = 0; k < sem_csr_nnz(A); ++k)
        work += (size_t)(B->row_start[A->col[k] + 1] - B->row_start[A->col[k]]);
    const int parallel = work > PARALLEL_WORK;
#pragma omp parallel num_threads(threads) if (parallel) reduction(| : failed)
    {
        int *mark = malloc((size_t)(n_cols > 0 ? n_cols : 1) * sizeof(int));
        if (!mark) failed = 1;
        if (mark)
            for (int j = 0; j < n_cols; ++j) mark[j] = -1;
#pragma omp for schedule(dynamic, 32)
        for (int r = 0; r < n_rows; ++r) {
            if (!mark) continue;
            int c = 0;
            for (int k = A->row_start[r]; k < A->row_start[r + 1]; ++k) {
                int a = A->col[k];
                int l0 = upper_only ? row_lower_bound(B, a, r) : B->row_start[a];
                for (int l = l0; l < B->row_start[a + 1]; ++l) {
                    int j = B->col[l];
                    if (mark[j] != r) {
                        mark[j] = r;
                        c++;
                    }
                }
            }
            count[r + 1] = c;
        }
        free(mark);
    }
    if (failed) {
        free(count);
        return SEM_ERR_NOMEM;
    }
    for (int r = 0; r < n_rows; ++r) total += (size_t)count[r + 1];
    if (nnz_out) *nnz_out = total;
    if (count_only) {
        free(count);
        return SEM_OK;
    }
    if (total > (size_t)0x7fffffff) {
        free(count);
        return SEM_ERR_NOMEM;
    }
    for (int r = 0; r < n_rows; ++r) count[r + 1] += count[r];
    if (sem_csr_alloc(C, n_rows, n_cols, total) != SEM_OK) {
        free(count);
        return SEM_ERR_NOMEM;
    }
    memcpy(C->row_start, count, ((size_t)n_rows + 1) * sizeof(int));
    free(count);
#pragma omp parallel num_threads(threads) if (parallel) reduction(| : failed)
    {
        int *mark = malloc((size_t)(n_cols > 0 ? n_cols : 1) * sizeof(int));
        double *acc = malloc((size_t)(n_cols > 0 ? n_cols : 1) * sizeof(double));
        if (!mark || !acc) failed = 1;
        if (mark)
            for (int j = 0; j < n_cols; ++j) mark[j] = -1;
#pragma omp for schedule(dynamic, 32)
        for (int r = 0; r < n_rows; ++r) {
            if (!mark || !acc) continue;
            int *cols = C->col + C->row_start[r];
            int c = 0;
            for (int k = A->row_start[r]; k < A->row_start[r + 1]; ++k) {
                int a = A->col[k];
                double va = A->val[k];
                int l0 = upper_only ? row_lower_bound(B, a, r) : B->row_start[a];
                for (int l = l0; l < B->row_start[a + 1]; ++l) {
                    int j = B->col[l];
                    if (mark[j] != r) {
                        mark[j] = r;
                        acc[j] = va * B->val[l];
                        cols[c++] = j;
                    } else {
                        acc[j] += va * B->val[l];
                    }
                }
            }
            /* a dense row is cheaper to collect by scanning than by sorting */
            if ((size_t)c * 16 > (size_t)n_cols) {
                int o = 0;
                for (int j = 0; j < n_cols && o < c; ++j)
                    if (mark[j] == r) cols[o++] = j;
            } else {
                qsort(cols, (size_t)c, sizeof(int), int_cmp);
            }
            double *vals = C->val + C->row_start[r];
            for (int k = 0; k < c; ++k) vals[k] = acc[cols[k]];
        }
        free(mark);
        free(acc);
    }
    if (failed) {
        sem_csr_free(C);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

static sem_status csr_product(const sem_csr *A, const sem_csr *B, sem_csr *C, int count_only,
                              size_t *nnz_out, int threads)
{
    return csr_product_ex(A, B, C, count_only, nnz_out, 0, threads);
}

/* T = A^T with entry (r, c) of A multiplied by row_scale[r] (NULL: 1). Serial counting
 * sort: columns of T come out sorted because rows of A are visited in order. */
static sem_status csr_transpose(const sem_csr *A, const double *row_scale, sem_csr *T)
{
    size_t nnz = sem_csr_nnz(A);
    if (sem_csr_alloc(T, A->n_cols, A->n_rows, nnz) != SEM_OK) return SEM_ERR_NOMEM;
    for (size_t k = 0; k < nnz; ++k) T->row_start[A->col[k] + 1]++;
    for (int c = 0; c < A->n_cols; ++c) T->row_start[c + 1] += T->row_start[c];
    int *fill = malloc(((size_t)A->n_cols + 1) * sizeof(int));
    if (!fill) {
        sem_csr_free(T);
        return SEM_ERR_NOMEM;
    }
    memcpy(fill, T->row_start, ((size_t)A->n_cols + 1) * sizeof(int));
    for (int r = 0; r < A->n_rows; ++r) {
        double s = row_scale ? row_scale[r] : 1.0;
        for (int k = A->row_start[r]; k < A->row_start[r + 1]; ++k) {
            int dst = fill[A->col[k]]++;
            T->col[dst] = r;
            T->val[dst] = s * A->val[k];
        }
    }
    free(fill);
    return SEM_OK;
}

/* C = a A + b B (same shape, sorted rows merged). */
static sem_status csr_add(const sem_csr *A, double a, const sem_csr *B, double b, sem_csr *C)
{
    const int n = A->n_rows;
    size_t total = 0;
    for (int r = 0; r < n; ++r) {
        int i = A->row_start[r], ie = A->row_start[r + 1];
        int j = B->row_start[r], je = B->row_start[r + 1];
        while (i < ie || j < je) {
            if (j >= je || (i < ie && A->col[i] < B->col[j])) i++;
            else if (i >= ie || B->col[j] < A->col[i]) j++;
            else i++, j++;
            total++;
        }
    }
    if (total > (size_t)0x7fffffff) return SEM_ERR_NOMEM;
    if (sem_csr_alloc(C, n, A->n_cols, total) != SEM_OK) return SEM_ERR_NOMEM;
    size_t o = 0;
    for (int r = 0; r < n; ++r) {
        int i = A->row_start[r], ie = A->row_start[r + 1];
        int j = B->row_start[r], je = B->row_start[r + 1];
        while (i < ie || j < je) {
            if (j >= je || (i < ie && A->col[i] < B->col[j])) {
                C->col[o] = A->col[i];
                C->val[o] = a * A->val[i++];
            } else if (i >= ie || B->col[j] < A->col[i]) {
                C->col[o] = B->col[j];
                C->val[o] = b * B->val[j++];
            } else {
                C->col[o] = A->col[i];
                C->val[o] = a * A->val[i++] + b * B->val[j++];
            }
            o++;
        }
        C->row_start[r + 1] = (int)o;
    }
    return SEM_OK;
}

/* Upper triangle U (columns >= row) -> the full symmetric matrix U + strict(U)^T: exactly
 * symmetric, whatever the rounding of the products. */
static sem_status csr_mirror_upper(sem_csr *U)
{
    sem_csr T, S;
    if (csr_transpose(U, NULL, &T) != SEM_OK) return SEM_ERR_NOMEM;
    /* drop the diagonal of T (it is kept once, from U) */
    size_t o = 0;
    int start = 0;
    for (int r = 0; r < T.n_rows; ++r) {
        int end = T.row_start[r + 1];
        for (int k = start; k < end; ++k)
            if (T.col[k] != r) {
                T.col[o] = T.col[k];
                T.val[o++] = T.val[k];
            }
        start = end;
        T.row_start[r + 1] = (int)o;
    }
    sem_status st = csr_add(U, 1.0, &T, 1.0, &S);
    sem_csr_free(&T);
    if (st != SEM_OK) return st;
    sem_csr_free(U);
    *U = S;
    return SEM_OK;
}

/* ------------------------------------------------------------------------------------ */
/* polynomial-space matrices                                                             */

/* G (rows_per_point = 1: values w b_k) or G' (rows_per_point = 3: values w d b_k / d X_e)
 * at n points X with weights Wt. With skip_constant, the k = 0 term is left out (used for
 * the stiffness pattern: the constant has no gradient). Row p*rows + e holds, for each part
 * i of Wt row p in order, the m (or m - 1) consecutive columns i*m + k: sorted. */
static sem_status build_poly_rows(const sem_discretization *d, const sem_csr *Wt, const double *X,
                                  int rows_per_point, int skip_constant, int threads, sem_csr *G)
{
    const int m = d->n_basis, n = Wt->n_rows;
    const int k0 = skip_constant ? 1 : 0, per_part = m - k0;
    size_t nnz = (size_t)sem_csr_nnz(Wt) * (size_t)per_part * (size_t)rows_per_point;
    if (nnz > (size_t)0x7fffffff) return SEM_ERR_NOMEM;
    if (sem_csr_alloc(G, n * rows_per_point, d->n_parts * m, nnz) != SEM_OK) return SEM_ERR_NOMEM;
    for (int p = 0; p < n; ++p) {
        int cnt = (Wt->row_start[p + 1] - Wt->row_start[p]) * per_part;
        for (int e = 0; e < rows_per_point; ++e) {
            int row = p * rows_per_point + e;
            G->row_start[row + 1] = G->row_start[row] + cnt;
        }
    }
#pragma omp parallel for schedule(static) num_threads(threads) if (nnz > PARALLEL_WORK)
    for (int p = 0; p < n; ++p) {
        double b[10], db[30];
        for (int e = 0; e < rows_per_point; ++e) {
            int o = G->row_start[p * rows_per_point + e];
            for (int k = Wt->row_start[p]; k < Wt->row_start[p + 1]; ++k) {
                int i = Wt->col[k];
                double w = Wt->val[k];
                const double *Xbar = d->origin_X + 3 * (size_t)d->part_origin[i];
                const double dX[3] = {X[3 * (size_t)p] - Xbar[0], X[3 * (size_t)p + 1] - Xbar[1],
                                      X[3 * (size_t)p + 2] - Xbar[2]};
                sem_polynomial_basis(d->order, dX, b, db);
                for (int kk = k0; kk < m; ++kk) {
                    G->col[o] = i * m + kk;
                    G->val[o] = w * (rows_per_point == 1 ? b[kk] : db[e * m + kk]);
                    o++;
                }
            }
        }
    }
    return SEM_OK;
}

/* Per-point union of the rows of G' (3 rows per point) with all values 1. */
static sem_status union_rows_of_points(const sem_csr *Gd, int rows_per_point, sem_csr *U)
{
    const int n = Gd->n_rows / rows_per_point;
    size_t nnz = sem_csr_nnz(Gd); /* upper bound; our G' rows of one point share columns */
    if (sem_csr_alloc(U, n, Gd->n_cols, nnz) != SEM_OK) return SEM_ERR_NOMEM;
    /* G' rows of one point have identical column lists (same parts, same k range), so the
     * union is the first row's list. */
    size_t o = 0;
    for (int p = 0; p < n; ++p) {
        int r = p * rows_per_point;
        for (int k = Gd->row_start[r]; k < Gd->row_start[r + 1]; ++k) {
            U->col[o] = Gd->col[k];
            U->val[o++] = 1.0;
        }
        U->row_start[p + 1] = (int)o;
    }
    return SEM_OK;
}

/* 1 when, for every part, cols(Pi row i*m) is inside the union of cols(Pi rows i*m+k, k>0). */
/* An empty n_rows x n_cols matrix (row starts only). */
static sem_status empty_rows(sem_csr *A, int n_rows, int n_cols)
{
    memset(A, 0, sizeof *A);
    A->row_start = calloc((size_t)n_rows + 1, sizeof(int));
    if (!A->row_start) return SEM_ERR_NOMEM;
    A->n_rows = n_rows;
    A->n_cols = n_cols;
    return SEM_OK;
}

/* Nnz% without forming M: every row of Pi_i spans the control points of part i's origin
 * group, so the pattern of Pi^T (G^T G) Pi is the union of |Ga| x |Gb| blocks over the
 * origin pairs of the parts that share a quadrature point (the constant rows' columns are
 * the other rows' columns too: constant_rows_covered, below). */
static double group_pattern_percent(const sem_discretization *d)
{
    int ng = d->n_origins;
    if (ng <= 0 || d->n_ctrl <= 0) return 0;
    unsigned char *pair = calloc((size_t)ng * ng, 1);
    double *size = calloc((size_t)ng, sizeof(double));
    if (!pair || !size) {
        free(pair);
        free(size);
        return 0;
    }
    /* a group's control points: those of its parts */
    for (int i = 0; i < d->n_parts; ++i)
        size[d->part_origin[i]] += d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i];
    const sem_csr *W = &d->W;
    for (int p = 0; p < W->n_rows; ++p)
        for (int a = W->row_start[p]; a < W->row_start[p + 1]; ++a)
            for (int b = W->row_start[p]; b < W->row_start[p + 1]; ++b)
                pair[(size_t)d->part_origin[W->col[a]] * ng + d->part_origin[W->col[b]]] = 1;
    double nnz = 0;
    for (int a = 0; a < ng; ++a)
        for (int b = 0; b < ng; ++b)
            if (pair[(size_t)a * ng + b]) nnz += size[a] * size[b];
    free(pair);
    free(size);
    return 100.0 * nnz / ((double)d->n_ctrl * (double)d->n_ctrl);
}

static int constant_rows_covered(const sem_discretization *d)
{
    const sem_csr *Pi = &d->Pi;
    const int m = d->n_basis;
    int *mark = malloc((size_t)(d->n_ctrl > 0 ? d->n_ctrl : 1) * sizeof(int));
    if (!mark) return 0;
    for (int j = 0; j < d->n_ctrl; ++j) mark[j] = -1;
    int ok = 1;
    for (int i = 0; i < d->n_parts && ok; ++i) {
        for (int k = 1; k < m; ++k)
            for (int l = Pi->row_start[i * m + k]; l < Pi->row_start[i * m + k + 1]; ++l)
                mark[Pi->col[l]] = i;
        for (int l = Pi->row_start[i * m]; l < Pi->row_start[i * m + 1]; ++l)
            if (mark[Pi->col[l]] != i) ok = 0;
    }
    free(mark);
    return ok;
}

static void set_all_ones(sem_csr *A)
{
    size_t nnz = sem_csr_nnz(A);
    for (size_t k = 0; k < nnz; ++k) A->val[k] = 1.0;
}

/* ------------------------------------------------------------------------------------ */

static sem_status check_inputs(const sem_discretization *d, sem_error *err)
{
    if (d->order != 1 && d->order != 2)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: order must be 1 or 2");
    if (d->n_basis != (d->order == 1 ? 4 : 10))
        return sem_error_set(err, SEM_ERR_INVALID, "operators: n_basis does not match the order");
    if (d->n_parts < 1 || d->n_ctrl < 1)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: no parts or control points");
    if (!d->Pi.row_start || d->Pi.n_rows != d->n_parts * d->n_basis || d->Pi.n_cols != d->n_ctrl)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: Pi missing or of the wrong size");
    if (!d->W.row_start || d->W.n_rows != d->n_quad || d->W.n_cols != d->n_parts)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: W missing or of the wrong size");
    if (!d->W_samples.row_start || d->W_samples.n_rows != d->n_samples ||
        d->W_samples.n_cols != d->n_parts)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "operators: W_samples missing or of the wrong size");
    if (!d->J_hat.row_start || d->J_hat.n_rows != d->n_samples || d->J_hat.n_cols != d->n_ctrl)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: J_hat missing or of the wrong size");
    if (!d->part_origin || !d->origin_X || d->n_origins < 1)
        return sem_error_set(err, SEM_ERR_INVALID, "operators: deformation origins missing");
    for (int i = 0; i < d->n_parts; ++i)
        if (d->part_origin[i] < 0 || d->part_origin[i] >= d->n_origins)
            return sem_error_set(err, SEM_ERR_INVALID, "operators: part %d has no valid origin", i);
    if ((d->n_quad > 0 && (!d->quad_X || !d->quad_volume)) ||
        (d->n_samples > 0 && (!d->sample_X || !d->sample_area)))
        return sem_error_set(err, SEM_ERR_INVALID, "operators: points missing");
    return SEM_OK;
}

sem_status sem_step_operators(const sem_preprocess_options *o, sem_discretization *d,
                              sem_error *err)
{
    if (!d) return sem_error_set(err, SEM_ERR_INVALID, "operators: NULL discretization");
    sem_status st = check_inputs(d, err);
    if (st != SEM_OK) return st;

    sem_csr_free(&d->Gamma);
    sem_csr_free(&d->Grad);
    sem_csr_free(&d->Gamma_samples);
    sem_csr_free(&d->M);
    sem_csr_free(&d->M_eps);

    sem_csr G = {0}, Gd = {0}, Gs = {0}, PiT = {0}, GtV = {0}, H = {0}, HPi = {0};
    sem_csr GstA = {0}, Hs = {0}, K = {0}, HsPi = {0}, X = {0}, M1 = {0}, KT = {0}, KtPi = {0};
    sem_csr JtA = {0}, JAJ = {0}, tmp = {0}, U = {0}, UT = {0}, S = {0}, Pi1 = {0}, Pi1T = {0};
    sem_csr SPi = {0};
    const int threads = sem_threads(o ? o->threads : 0);
    st = SEM_OK;

#define TRY(call)                                                                          \
    do {                                                                                   \
        if ((call) != SEM_OK) {                                                            \
            st = sem_error_set(err, SEM_ERR_NOMEM, "operators: out of memory");            \
            goto done;                                                                     \
        }                                                                                  \
    } while (0)

    /* Eq. 12-13 */
    TRY(build_poly_rows(d, &d->W, d->quad_X, 1, 0, threads, &G));
    TRY(csr_product(&G, &d->Pi, &d->Gamma, 0, NULL, threads));
    if (!o || !o->q_space_operators) {
        /* Gamma only: the rest are dense blocks over control points that the structured
         * solver never forms (physics/structured.h); they stay empty, with their rows */
        TRY(empty_rows(&d->Grad, 3 * d->n_quad, d->n_ctrl));
        TRY(empty_rows(&d->Gamma_samples, d->n_samples, d->n_ctrl));
        TRY(empty_rows(&d->M, d->n_ctrl, d->n_ctrl));
        TRY(empty_rows(&d->M_eps, d->n_ctrl, d->n_ctrl));
        d->stiffness_nnz_percent = group_pattern_percent(d);
        goto gamma;
    }
    /* Eq. 15: the gradient rows over control points only when asked for (level 2): no
     * solver reads them (the stiffness is assembled in coefficient space, assembly.h), and
     * they are the largest operator (3 rows per point: 1.7 GB of a 11,439-dof CAD part's
     * 2.4 GB) */
    if (o->q_space_operators >= 2) {
        TRY(build_poly_rows(d, &d->W, d->quad_X, 3, 0, threads, &Gd));
        TRY(csr_product(&Gd, &d->Pi, &d->Grad, 0, NULL, threads));
    } else {
        TRY(empty_rows(&d->Grad, 3 * d->n_quad, d->n_ctrl));
    }
    TRY(build_poly_rows(d, &d->W_samples, d->sample_X, 1, 0, threads, &Gs));
    TRY(csr_product(&Gs, &d->Pi, &d->Gamma_samples, 0, NULL, threads));

    /* Eq. 14: M = Pi^T (G^T V G) Pi, unit density */
    TRY(csr_transpose(&d->Pi, NULL, &PiT));
    TRY(csr_transpose(&G, d->quad_volume, &GtV));
    TRY(csr_product(&GtV, &G, &H, 0, NULL, threads));
    TRY(csr_product(&H, &d->Pi, &HPi, 0, NULL, threads));
    TRY(csr_product_ex(&PiT, &HPi, &d->M, 0, NULL, 1, threads));
    TRY(csr_mirror_upper(&d->M));

    /* Eq. 16: M_eps = Pi^T (Hs Pi - K) - K^T Pi + J^T A J */
    TRY(csr_transpose(&Gs, d->sample_area, &GstA));
    TRY(csr_product(&GstA, &Gs, &Hs, 0, NULL, threads));
    TRY(csr_product(&GstA, &d->J_hat, &K, 0, NULL, threads));
    TRY(csr_product(&Hs, &d->Pi, &HsPi, 0, NULL, threads));
    TRY(csr_add(&HsPi, 1.0, &K, -1.0, &X));
    /* M_eps is symmetric, so the upper triangles of its three terms define it */
    TRY(csr_product_ex(&PiT, &X, &M1, 0, NULL, 1, threads));
    TRY(csr_transpose(&K, NULL, &KT));
    TRY(csr_product_ex(&KT, &d->Pi, &KtPi, 0, NULL, 1, threads));
    TRY(csr_transpose(&d->J_hat, d->sample_area, &JtA));
    TRY(csr_product_ex(&JtA, &d->J_hat, &JAJ, 0, NULL, 1, threads));
    TRY(csr_add(&M1, 1.0, &KtPi, -1.0, &tmp));
    TRY(csr_add(&tmp, 1.0, &JAJ, 1.0, &d->M_eps));
    TRY(csr_mirror_upper(&d->M_eps));

    /* Table 1 Nnz%: structural pattern of sum_p Grad_p^T Grad_p = Pi^T (U^T U) Pi. It
     * equals M's pattern (Pi^T (G^T G) Pi) when each part's constant row of Pi (k = 0, no
     * gradient) touches no column its other rows miss: the usual case, checked here. */
    if (constant_rows_covered(d)) {
        d->stiffness_nnz_percent =
            100.0 * (double)sem_csr_nnz(&d->M) / ((double)d->n_ctrl * (double)d->n_ctrl);
    } else {
        sem_csr_free(&Gd);
        TRY(build_poly_rows(d, &d->W, d->quad_X, 3, 1, threads, &Gd));
        TRY(union_rows_of_points(&Gd, 3, &U));
        TRY(csr_transpose(&U, NULL, &UT));
        TRY(csr_product(&UT, &U, &S, 0, NULL, threads));
        TRY(sem_csr_copy(&Pi1, &d->Pi));
        set_all_ones(&Pi1);
        TRY(csr_transpose(&Pi1, NULL, &Pi1T));
        TRY(csr_product(&S, &Pi1, &SPi, 0, NULL, threads));
        size_t nnz = 0;
        TRY(csr_product(&Pi1T, &SPi, NULL, 1, &nnz, threads));
        d->stiffness_nnz_percent = 100.0 * (double)nnz / ((double)d->n_ctrl * (double)d->n_ctrl);
    }

gamma:
    /* default gamma = kappa E / L (Sec. 7.6; see the file comment) */
    {
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (int s = 0; s < d->n_samples; ++s) {
            double Y[3]; /* in the object's frame: L does not change when it is turned */
            sem_frame_coordinates(d, d->sample_X + 3 * (size_t)s, Y);
            for (int e = 0; e < 3; ++e) {
                lo[e] = fmin(lo[e], Y[e]);
                hi[e] = fmax(hi[e], Y[e]);
            }
        }
        double L2 = 0;
        if (d->n_samples > 0)
            for (int e = 0; e < 3; ++e) L2 += (hi[e] - lo[e]) * (hi[e] - lo[e]);
        d->length_scale = sqrt(L2);
        const double kappa = 1000.0; /* see docs/preprocessing.md, "Default gamma" */
        double E = (o && o->youngs_modulus > 0) ? o->youngs_modulus : 1e6;
        if (o && o->gamma > 0)
            d->gamma = o->gamma;
        else
            d->gamma = d->length_scale > 0 ? kappa * E / d->length_scale : E;
    }

done:
#undef TRY
    sem_csr_free(&G);
    sem_csr_free(&Gd);
    sem_csr_free(&Gs);
    sem_csr_free(&PiT);
    sem_csr_free(&GtV);
    sem_csr_free(&H);
    sem_csr_free(&HPi);
    sem_csr_free(&GstA);
    sem_csr_free(&Hs);
    sem_csr_free(&K);
    sem_csr_free(&HsPi);
    sem_csr_free(&X);
    sem_csr_free(&M1);
    sem_csr_free(&KT);
    sem_csr_free(&KtPi);
    sem_csr_free(&JtA);
    sem_csr_free(&JAJ);
    sem_csr_free(&tmp);
    sem_csr_free(&U);
    sem_csr_free(&UT);
    sem_csr_free(&S);
    sem_csr_free(&Pi1);
    sem_csr_free(&Pi1T);
    sem_csr_free(&SPi);
    if (st != SEM_OK) {
        sem_csr_free(&d->Gamma);
        sem_csr_free(&d->Grad);
        sem_csr_free(&d->Gamma_samples);
        sem_csr_free(&d->M);
        sem_csr_free(&d->M_eps);
    }
    return st;
}
