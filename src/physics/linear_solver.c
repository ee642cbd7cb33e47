/* linear_solver.c - CHOLMOD and dense LAPACK Cholesky behind one interface (see header). */
#include "linear_solver.h"
#include "util/free_all.h"

#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <suitesparse/cholmod.h>

/*
 * Storage: the solver keeps P A P^T, lower triangle in CSC (stype -1), with P the
 * fill-reducing permutation (AMD/METIS plus postorder) of CHOLMOD's first analysis, and
 * factors it in its natural order. For that form CHOLMOD's supernodal factorization reads
 * the matrix as it is; given the upper triangle and a permutation it would build the
 * permuted transpose at every factorization (cholmod_transpose_sym: ~6 ms of a 70 ms step
 * of the 1800-dof mug). The caller's pattern positions are remapped once
 * (sem_linear_solver_remap); solves permute b and x.
 */
/* The rule of SEM_SOLVER_AUTO: dense LAPACK up to this many (free) degrees of freedom,
 * CHOLMOD above. Measured (docs/reliability.md): below ~500 dofs both factor in well under a
 * millisecond and dense has no analysis to amortize; from the paper's smallest Table 1 row
 * (648 dofs, a nearly full factor) on, CHOLMOD's supernodal factorization (BLAS on its
 * supernodes) was as fast or faster on every row, which is also what the former timing
 * rule chose for all twelve rows. */
#define SEM_DENSE_MAX_DOFS 500

/* OpenBLAS threads for the factorizations and solves, whatever the thread setting: its
 * Cholesky (dense, and on CHOLMOD's supernodes) blocks the work by its thread count, so 1
 * and 2 threads give different bits (measured: the default beam's first step). A fixed
 * count makes the result independent of OMP_NUM_THREADS, the scene's threads and the
 * machine's core count (docs/reliability.md); 2 is what the 2-core machines this was tuned
 * on use anyway. */
#define SEM_SOLVER_BLAS_THREADS 2

/* The residual A x is summed in this many column shares, whatever the thread count, so
 * it gives the same bits on any number of threads. */
#define RESIDUAL_SHARES 4

struct sem_linear_solver {
    int n;
    size_t nnz;
    sem_solver_choice choice; /* SPARSE or DENSE (AUTO resolved at creation) */
    cholmod_common common;
    cholmod_sparse *A;  /* P A P^T, lower, sorted */
    int *perm;          /* perm[k] = the caller's index of row/column k of A */
    int *remap;         /* caller position -> position in A */
    cholmod_factor *L;
    double *dense; /* n x n column-major, lower triangle factor */
    double *work;  /* 3 n */
    int col_split[RESIDUAL_SHARES + 1]; /* column shares of about equal entry counts */
    double *partial;  /* RESIDUAL_SHARES x n: each share's part of A x */
    double last_factor_s;
};

typedef struct entry_key {
    int row, pos;
} entry_key;

static int compare_entry(const void *a, const void *b)
{
    const entry_key *x = a, *y = b;
    return (x->row > y->row) - (x->row < y->row);
}

sem_status sem_linear_solver_create(int n, const int *col_start, const int *row,
                                    sem_solver_choice choice, sem_linear_solver **out,
                                    sem_error *err)
{
    *out = NULL;
    sem_linear_solver *s = calloc(1, sizeof *s);
    if (!s) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory creating the solver");
    s->n = n;
    s->nnz = (size_t)col_start[n];
    /* SEM_SOLVER_AUTO is a fixed rule, never a timing: the same system gets the same solver,
     * and so the same bits, on every run and machine (docs/reliability.md). */
    s->choice = choice != SEM_SOLVER_AUTO ? choice
                : n <= SEM_DENSE_MAX_DOFS    ? SEM_SOLVER_DENSE
                                             : SEM_SOLVER_SPARSE;
    cholmod_start(&s->common);
    s->common.print = 0;
    s->common.error_handler = NULL;
    size_t nn = (size_t)n, nz = s->nnz;
    s->perm = malloc((nn + 1) * sizeof(int));
    s->remap = malloc((nz + 1) * sizeof(int));
    s->work = malloc((3 * nn + 1) * sizeof(double));
    s->partial = malloc((RESIDUAL_SHARES * nn + 1) * sizeof(double));
    int *invp = malloc((nn + 1) * sizeof(int));
    int *count = calloc(nn + 1, sizeof(int));
    entry_key *keys = malloc((nz + 1) * sizeof *keys);
    cholmod_sparse *U = cholmod_allocate_sparse(nn, nn, nz, 1, 1, 1, CHOLMOD_PATTERN, &s->common);
    s->A = cholmod_allocate_sparse(nn, nn, nz, 1, 1, -1, CHOLMOD_REAL, &s->common);
    sem_status st = SEM_OK;
    if (!s->perm || !s->remap || !s->work || !s->partial || !invp || !count ||
        !keys || !U || !s->A) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a %d x %d system", n, n);
        goto done;
    }
    /* the fill-reducing order of the caller's upper pattern */
    memcpy(U->p, col_start, (nn + 1) * sizeof(int));
    memcpy(U->i, row, nz * sizeof(int));
    cholmod_factor *L0 = cholmod_analyze(U, &s->common);
    if (!L0) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "CHOLMOD analysis failed (status %d)", s->common.status);
        goto done;
    }
    memcpy(s->perm, L0->Perm, nn * sizeof(int));
    cholmod_free_factor(&L0, &s->common);
    for (int k = 0; k < n; ++k) invp[s->perm[k]] = k;
    /* P A P^T, lower: caller entry (r, c), r <= c, goes to (max, min) of (invp r, invp c) */
    for (int c = 0; c < n; ++c)
        for (int k = col_start[c]; k < col_start[c + 1]; ++k) {
            int a = invp[row[k]], b = invp[c];
            count[(a < b ? a : b) + 1]++;
        }
    for (int c = 0; c < n; ++c) count[c + 1] += count[c];
    int *Ap = s->A->p, *Ai = s->A->i;
    memcpy(Ap, count, (nn + 1) * sizeof(int));
    for (int c = 0; c < n; ++c)
        for (int k = col_start[c]; k < col_start[c + 1]; ++k) {
            int a = invp[row[k]], b = invp[c];
            int lo = a < b ? a : b, hi = a < b ? b : a;
            keys[count[lo]].row = hi;
            keys[count[lo]].pos = k;
            count[lo]++;
        }
    for (int c = 0; c < n; ++c) {
        qsort(keys + Ap[c], (size_t)(Ap[c + 1] - Ap[c]), sizeof *keys, compare_entry);
        for (int q = Ap[c]; q < Ap[c + 1]; ++q) {
            Ai[q] = keys[q].row;
            s->remap[keys[q].pos] = q;
        }
    }
    memset(s->A->x, 0, nz * sizeof(double));
    for (int t = 0, c = 0; t <= RESIDUAL_SHARES; ++t) {
        size_t target = nz * (size_t)t / RESIDUAL_SHARES;
        while (c < n && (size_t)Ap[c] < target) ++c;
        s->col_split[t] = t == RESIDUAL_SHARES ? n : c;
    }
done:
    free(invp);
    free(count);
    free(keys);
    if (U) cholmod_free_sparse(&U, &s->common);
    if (st != SEM_OK) {
        sem_linear_solver_destroy(s);
        return st;
    }
    *out = s;
    return SEM_OK;
}

sem_status sem_linear_solver_clone_pattern(const sem_linear_solver *s, sem_linear_solver **out, sem_error *err)
{
    *out = NULL;
    sem_linear_solver *c = calloc(1, sizeof *c);
    if (!c) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory creating the solver");
    size_t nn = (size_t)s->n, nz = s->nnz;
    c->n = s->n;
    c->nnz = s->nnz;
    c->choice = s->choice;
    cholmod_start(&c->common);
    c->common.print = 0;
    c->common.error_handler = NULL;
    memcpy(c->col_split, s->col_split, sizeof c->col_split);
    c->perm = malloc((nn + 1) * sizeof(int));
    c->remap = malloc((nz + 1) * sizeof(int));
    c->work = malloc((3 * nn + 1) * sizeof(double));
    c->partial = malloc((RESIDUAL_SHARES * nn + 1) * sizeof(double));
    c->A = cholmod_copy_sparse(s->A, &c->common);
    if (!c->perm || !c->remap || !c->work || !c->partial || !c->A) {
        sem_linear_solver_destroy(c);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a second %d x %d factor", s->n, s->n);
    }
    memcpy(c->perm, s->perm, nn * sizeof(int));
    memcpy(c->remap, s->remap, nz * sizeof(int));
    memset(c->A->x, 0, nz * sizeof(double));
    *out = c;
    return SEM_OK;
}

void sem_linear_solver_remap(const sem_linear_solver *s, int *positions, size_t count)
{
    for (size_t k = 0; k < count; ++k)
        if (positions[k] >= 0) positions[k] = s->remap[positions[k]];
}

void sem_linear_solver_destroy(sem_linear_solver *s)
{
    if (!s) return;
    if (s->L) cholmod_free_factor(&s->L, &s->common);
    if (s->A) cholmod_free_sparse(&s->A, &s->common);
    cholmod_finish(&s->common);
    SEM_FREE_ALL(s->dense, s->perm, s->remap, s->work, s->partial);
    free(s);
}

double *sem_linear_solver_values(sem_linear_solver *s)
{
    return (double *)s->A->x;
}

static sem_status factor_sparse(sem_linear_solver *s, sem_error *err)
{
    if (!s->L) {
        /* A is already in its fill-reducing (and postordered) order */
        s->common.nmethods = 1;
        s->common.method[0].ordering = CHOLMOD_NATURAL;
        s->common.postorder = 0;
        s->L = cholmod_analyze(s->A, &s->common);
        if (!s->L) return sem_error_set(err, SEM_ERR_NOMEM, "CHOLMOD analysis failed");
    }
    if (!cholmod_factorize(s->A, s->L, &s->common) || s->common.status != CHOLMOD_OK)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "system matrix is not positive definite (CHOLMOD status %d): the "
                             "state may have exploded or the object is not held",
                             s->common.status);
    return SEM_OK;
}

static sem_status factor_dense(sem_linear_solver *s, sem_error *err)
{
    size_t n = (size_t)s->n;
    if (!s->dense) {
        s->dense = malloc(n * n * sizeof(double));
        if (!s->dense)
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a dense %zu x %zu system",
                                 n, n);
    }
    memset(s->dense, 0, n * n * sizeof(double));
    const int *p = s->A->p, *i = s->A->i;
    const double *x = s->A->x;
    for (size_t c = 0; c < n; ++c)
        for (int k = p[c]; k < p[c + 1]; ++k) s->dense[c * n + (size_t)i[k]] = x[k];
    lapack_int info = LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'L', (lapack_int)n, s->dense, (lapack_int)n);
    if (info != 0)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "system matrix is not positive definite (LAPACK dpotrf info %d): "
                             "the state may have exploded or the object is not held",
                             (int)info);
    return SEM_OK;
}

sem_status sem_linear_solver_factorize(sem_linear_solver *s, sem_error *err)
{
    int blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(SEM_SOLVER_BLAS_THREADS);
    double t0 = omp_get_wtime();
    sem_status st = s->choice == SEM_SOLVER_DENSE ? factor_dense(s, err) : factor_sparse(s, err);
    s->last_factor_s = omp_get_wtime() - t0;
    openblas_set_num_threads(blas_threads);
    return st;
}

static sem_status solve_once(sem_linear_solver *s, const double *b, double *x, sem_error *err);

/* y = (columns col_split[t] .. col_split[t+1] of A) x, with A's stored lower triangle
 * read symmetrically: a column's entries scatter (A_ic x_c into y_i), its mirror entries
 * are a dot product (A_ic x_i into y_c) kept in four running sums. Columns are sorted, so
 * a diagonal entry comes first. */
static void share_product(const sem_linear_solver *s, int t, const double *x, double *y)
{
    const int *p = s->A->p, *ri = s->A->i;
    const double *v = s->A->x;
    memset(y, 0, (size_t)s->n * sizeof(double));
    for (int c = s->col_split[t]; c < s->col_split[t + 1]; ++c) {
        double xc = x[c], a0 = 0, a1 = 0, a2 = 0, a3 = 0;
        int k = p[c], end = p[c + 1];
        if (k < end && ri[k] == c) {
            y[c] += v[k] * xc;
            ++k;
        }
        for (; k + 3 < end; k += 4) {
            int i0 = ri[k], i1 = ri[k + 1], i2 = ri[k + 2], i3 = ri[k + 3];
            y[i0] += v[k] * xc;
            y[i1] += v[k + 1] * xc;
            y[i2] += v[k + 2] * xc;
            y[i3] += v[k + 3] * xc;
            a0 += v[k] * x[i0];
            a1 += v[k + 1] * x[i1];
            a2 += v[k + 2] * x[i2];
            a3 += v[k + 3] * x[i3];
        }
        for (; k < end; ++k) {
            y[ri[k]] += v[k] * xc;
            a0 += v[k] * x[ri[k]];
        }
        y[c] += (a0 + a1) + (a2 + a3);
    }
}

/* The same share of |A| |x| (x given as |x|). */
static void share_abs_product(const sem_linear_solver *s, int t, const double *ax, double *y)
{
    const int *p = s->A->p, *ri = s->A->i;
    const double *v = s->A->x;
    memset(y, 0, (size_t)s->n * sizeof(double));
    for (int c = s->col_split[t]; c < s->col_split[t + 1]; ++c) {
        double xc = ax[c], acc = 0;
        int k = p[c], end = p[c + 1];
        if (k < end && ri[k] == c) {
            y[c] += fabs(v[k]) * xc;
            ++k;
        }
        for (; k < end; ++k) {
            double a = fabs(v[k]);
            y[ri[k]] += a * xc;
            acc += a * ax[ri[k]];
        }
        y[c] += acc;
    }
}

/* The column shares in parallel, each into its own vector, summed in share order:
 * out = b - A x, or |A| x when absolute (x given as |x|, b NULL). */
static void share_sum(sem_linear_solver *s, int absolute, const double *b, const double *x, double *out)
{
    size_t n = (size_t)s->n;
#pragma omp parallel
    {
#pragma omp for schedule(static)
        for (int t = 0; t < RESIDUAL_SHARES; ++t) {
            if (absolute)
                share_abs_product(s, t, x, s->partial + (size_t)t * n);
            else
                share_product(s, t, x, s->partial + (size_t)t * n);
        }
#pragma omp for schedule(static)
        for (size_t i = 0; i < n; ++i) {
            double ax = 0;
            for (int t = 0; t < RESIDUAL_SHARES; ++t) ax += s->partial[(size_t)t * n + i];
            out[i] = absolute ? ax : b[i] - ax;
        }
    }
}

static void residual(sem_linear_solver *s, const double *b, const double *x, double *r)
{
    share_sum(s, 0, b, x, r);
}

void sem_linear_solver_residual(sem_linear_solver *s, const double *b, const double *x, double *r,
                                double *scale)
{
    size_t n = (size_t)s->n;
    double *bp = s->work, *xp = s->work + n, *rp = s->work + 2 * n;
    for (size_t k = 0; k < n; ++k) {
        bp[k] = b[s->perm[k]];
        xp[k] = x[s->perm[k]];
    }
    residual(s, bp, xp, rp);
    for (size_t k = 0; k < n; ++k) r[s->perm[k]] = rp[k];
    if (!scale) return;
    for (size_t k = 0; k < n; ++k) xp[k] = fabs(xp[k]);
    share_sum(s, 1, NULL, xp, rp);
    for (size_t k = 0; k < n; ++k) scale[s->perm[k]] = rp[k];
}

/* x = A^-1 b, with one step of iterative refinement when refine is set: SEM systems mix the
 * mass matrix with the stiff error term (Eq. 16), and the refinement recovers the digits the
 * factorization loses, so that conserved quantities (momentum) hold to round-off. Everything
 * runs in the permuted order of A: b is gathered through perm on the way in, x scattered on
 * the way out. */
static sem_status solve_permuted(sem_linear_solver *s, const double *b, double *x, int refine, sem_error *err)
{
    size_t n = (size_t)s->n;
    double *bp = s->work, *xp = s->work + n, *r = s->work + 2 * n;
    int blas_threads = openblas_get_num_threads();
    openblas_set_num_threads(SEM_SOLVER_BLAS_THREADS);
    for (size_t k = 0; k < n; ++k) bp[k] = b[s->perm[k]];
    sem_status st = solve_once(s, bp, xp, err);
    if (st == SEM_OK && refine) {
        residual(s, bp, xp, r);
        st = solve_once(s, r, r, err);
        if (st == SEM_OK)
            for (size_t k = 0; k < n; ++k) xp[k] += r[k];
    }
    if (st == SEM_OK)
        for (size_t k = 0; k < n; ++k) x[s->perm[k]] = xp[k];
    openblas_set_num_threads(blas_threads);
    return st;
}

sem_status sem_linear_solver_solve(sem_linear_solver *s, const double *b, double *x,
                                   sem_error *err)
{
    return solve_permuted(s, b, x, 1, err);
}

sem_status sem_linear_solver_solve_plain(sem_linear_solver *s, const double *b, double *x, sem_error *err)
{
    return solve_permuted(s, b, x, 0, err);
}

static sem_status solve_once(sem_linear_solver *s, const double *b, double *x, sem_error *err)
{
    size_t n = (size_t)s->n;
    if (s->choice == SEM_SOLVER_DENSE) {
        if (x != b) memcpy(x, b, n * sizeof(double));
        lapack_int info = LAPACKE_dpotrs(LAPACK_COL_MAJOR, 'L', (lapack_int)n, 1, s->dense,
                                         (lapack_int)n, x, (lapack_int)n);
        if (info != 0) return sem_error_set(err, SEM_ERR_NUMERIC, "dense solve failed (%d)", (int)info);
        return SEM_OK;
    }
    cholmod_dense *B = cholmod_allocate_dense(n, 1, n, CHOLMOD_REAL, &s->common);
    if (!B) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory in the solve");
    memcpy(B->x, b, n * sizeof(double));
    cholmod_dense *X = cholmod_solve(CHOLMOD_A, s->L, B, &s->common);
    cholmod_free_dense(&B, &s->common);
    if (!X) return sem_error_set(err, SEM_ERR_NUMERIC, "CHOLMOD solve failed");
    memcpy(x, X->x, n * sizeof(double));
    cholmod_free_dense(&X, &s->common);
    return SEM_OK;
}

const char *sem_linear_solver_name(const sem_linear_solver *s)
{
    return s->choice == SEM_SOLVER_DENSE ? "dense" : "cholmod";
}

double sem_linear_solver_last_factor_seconds(const sem_linear_solver *s)
{
    return s->last_factor_s;
}

double sem_linear_solver_nnz_percent(const sem_linear_solver *s)
{
    /* full symmetric count: off-diagonals twice */
    size_t diag = 0;
    const int *p = s->A->p, *i = s->A->i;
    for (int c = 0; c < s->n; ++c)
        for (int k = p[c]; k < p[c + 1]; ++k) diag += i[k] == c;
    double full = 2.0 * (double)(s->nnz - diag) + (double)diag;
    return 100.0 * full / ((double)s->n * s->n);
}
