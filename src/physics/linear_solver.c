/* linear_solver.c - CHOLMOD and dense LAPACK Cholesky behind one interface (see header). */
#include "linear_solver.h"

#include <lapacke.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>
#include <suitesparse/cholmod.h>

struct sem_linear_solver {
    int n;
    size_t nnz;
    sem_solver_choice choice; /* resolved to SPARSE or DENSE after the first factorization */
    int decided;
    cholmod_common common;
    cholmod_sparse *A;
    cholmod_factor *L;
    double *dense; /* n x n column-major, upper triangle factor */
    double last_factor_s;
};

sem_status sem_linear_solver_create(int n, const int *col_start, const int *row,
                                    sem_solver_choice choice, sem_linear_solver **out,
                                    sem_error *err)
{
    *out = NULL;
    sem_linear_solver *s = calloc(1, sizeof *s);
    if (!s) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory creating the solver");
    s->n = n;
    s->nnz = (size_t)col_start[n];
    s->choice = choice;
    s->decided = choice != SEM_SOLVER_AUTO;
    cholmod_start(&s->common);
    s->common.print = 0;
    s->common.error_handler = NULL;
    s->A = cholmod_allocate_sparse((size_t)n, (size_t)n, s->nnz, 1, 1, 1, CHOLMOD_REAL, &s->common);
    if (!s->A) {
        sem_linear_solver_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a %d x %d system", n, n);
    }
    memcpy(s->A->p, col_start, ((size_t)n + 1) * sizeof(int));
    memcpy(s->A->i, row, s->nnz * sizeof(int));
    memset(s->A->x, 0, s->nnz * sizeof(double));
    *out = s;
    return SEM_OK;
}

void sem_linear_solver_destroy(sem_linear_solver *s)
{
    if (!s) return;
    if (s->L) cholmod_free_factor(&s->L, &s->common);
    if (s->A) cholmod_free_sparse(&s->A, &s->common);
    cholmod_finish(&s->common);
    free(s->dense);
    free(s);
}

double *sem_linear_solver_values(sem_linear_solver *s)
{
    return (double *)s->A->x;
}

static sem_status factor_sparse(sem_linear_solver *s, sem_error *err)
{
    if (!s->L) {
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
    lapack_int info = LAPACKE_dpotrf(LAPACK_COL_MAJOR, 'U', (lapack_int)n, s->dense, (lapack_int)n);
    if (info != 0)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "system matrix is not positive definite (LAPACK dpotrf info %d): "
                             "the state may have exploded or the object is not held",
                             (int)info);
    return SEM_OK;
}

sem_status sem_linear_solver_factorize(sem_linear_solver *s, sem_error *err)
{
    if (!s->decided) {
        /* Measure both once (the sparse one after its one-off analysis) and keep the faster. */
        sem_status st = factor_sparse(s, err);
        if (st != SEM_OK) return st;
        double t0 = omp_get_wtime();
        st = factor_sparse(s, err);
        double t_sparse = omp_get_wtime() - t0;
        if (st != SEM_OK) return st;
        double t_dense = 1e300;
        if ((double)s->n * s->n * sizeof(double) < 2e9) {
            t0 = omp_get_wtime();
            st = factor_dense(s, err);
            t_dense = omp_get_wtime() - t0;
            if (st != SEM_OK) return st;
        }
        s->choice = t_dense < t_sparse ? SEM_SOLVER_DENSE : SEM_SOLVER_SPARSE;
        s->decided = 1;
        s->last_factor_s = t_dense < t_sparse ? t_dense : t_sparse;
        if (s->choice == SEM_SOLVER_SPARSE) {
            free(s->dense);
            s->dense = NULL;
        } else if (s->L) {
            cholmod_free_factor(&s->L, &s->common);
        }
        return SEM_OK;
    }
    double t0 = omp_get_wtime();
    sem_status st = s->choice == SEM_SOLVER_DENSE ? factor_dense(s, err) : factor_sparse(s, err);
    s->last_factor_s = omp_get_wtime() - t0;
    return st;
}

static sem_status solve_once(sem_linear_solver *s, const double *b, double *x, sem_error *err);

/* One step of iterative refinement: SEM systems mix the mass matrix with the stiff error
 * term (Eq. 16), and the refinement recovers the digits the factorization loses, so that
 * conserved quantities (momentum) hold to round-off. */
sem_status sem_linear_solver_solve(sem_linear_solver *s, const double *b, double *x,
                                   sem_error *err)
{
    size_t n = (size_t)s->n;
    double *b0 = malloc(n * sizeof(double) + 1), *r = malloc(n * sizeof(double) + 1);
    if (!b0 || !r) {
        free(b0);
        free(r);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory in the solve");
    }
    memcpy(b0, b, n * sizeof(double));
    sem_status st = solve_once(s, b0, x, err);
    if (st == SEM_OK) {
        /* r = b - A x with the stored upper triangle (symmetric) */
        memcpy(r, b0, n * sizeof(double));
        const int *p = s->A->p, *ri = s->A->i;
        const double *v = s->A->x;
        for (size_t c = 0; c < n; ++c)
            for (int k = p[c]; k < p[c + 1]; ++k) {
                size_t i = (size_t)ri[k];
                r[i] -= v[k] * x[c];
                if (i != c) r[c] -= v[k] * x[i];
            }
        st = solve_once(s, r, r, err);
        if (st == SEM_OK)
            for (size_t i = 0; i < n; ++i) x[i] += r[i];
    }
    free(b0);
    free(r);
    return st;
}

static sem_status solve_once(sem_linear_solver *s, const double *b, double *x, sem_error *err)
{
    size_t n = (size_t)s->n;
    if (s->choice == SEM_SOLVER_DENSE) {
        if (x != b) memcpy(x, b, n * sizeof(double));
        lapack_int info = LAPACKE_dpotrs(LAPACK_COL_MAJOR, 'U', (lapack_int)n, 1, s->dense,
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
