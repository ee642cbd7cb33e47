/* sparse.c - compressed sparse rows (see sem/sparse.h). */
#include "sem/sparse.h"

#include <stdlib.h>
#include <string.h>

void sem_csr_free(sem_csr *m)
{
    if (!m) return;
    free(m->row_start);
    free(m->col);
    free(m->val);
    memset(m, 0, sizeof *m);
}

sem_status sem_csr_alloc(sem_csr *m, int n_rows, int n_cols, size_t nnz)
{
    memset(m, 0, sizeof *m);
    m->n_rows = n_rows;
    m->n_cols = n_cols;
    m->row_start = calloc((size_t)n_rows + 1, sizeof(int));
    m->col = malloc((nnz ? nnz : 1) * sizeof(int));
    m->val = malloc((nnz ? nnz : 1) * sizeof(double));
    if (!m->row_start || !m->col || !m->val) {
        sem_csr_free(m);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

size_t sem_csr_nnz(const sem_csr *m)
{
    return m->row_start ? (size_t)m->row_start[m->n_rows] : 0;
}

sem_status sem_csr_copy(sem_csr *dst, const sem_csr *src)
{
    size_t nnz = sem_csr_nnz(src);
    if (sem_csr_alloc(dst, src->n_rows, src->n_cols, nnz) != SEM_OK) return SEM_ERR_NOMEM;
    memcpy(dst->row_start, src->row_start, ((size_t)src->n_rows + 1) * sizeof(int));
    if (nnz) {
        memcpy(dst->col, src->col, nnz * sizeof(int));
        memcpy(dst->val, src->val, nnz * sizeof(double));
    }
    return SEM_OK;
}

typedef struct entry {
    int col;
    double val;
} entry;

static int entry_cmp(const void *a, const void *b)
{
    int ca = ((const entry *)a)->col, cb = ((const entry *)b)->col;
    return (ca > cb) - (ca < cb);
}

sem_status sem_csr_from_triplets(sem_csr *m, int n_rows, int n_cols, size_t n, const int *rows,
                                 const int *cols, const double *vals)
{
    memset(m, 0, sizeof *m);
    int *count = calloc((size_t)n_rows + 1, sizeof(int));
    entry *e = malloc((n ? n : 1) * sizeof *e);
    if (!count || !e) {
        free(count);
        free(e);
        return SEM_ERR_NOMEM;
    }
    for (size_t k = 0; k < n; ++k) count[rows[k] + 1]++;
    for (int r = 0; r < n_rows; ++r) count[r + 1] += count[r];
    int *fill = malloc(((size_t)n_rows + 1) * sizeof(int));
    if (!fill) {
        free(count);
        free(e);
        return SEM_ERR_NOMEM;
    }
    memcpy(fill, count, ((size_t)n_rows + 1) * sizeof(int));
    for (size_t k = 0; k < n; ++k) {
        entry *x = &e[fill[rows[k]]++];
        x->col = cols[k];
        x->val = vals[k];
    }
    free(fill);
    /* sort each row, merge duplicates, compact */
    size_t out = 0;
    for (int r = 0; r < n_rows; ++r) {
        int a = count[r], b = count[r + 1];
        qsort(e + a, (size_t)(b - a), sizeof *e, entry_cmp);
        count[r] = (int)out;
        for (int k = a; k < b; ++k) {
            if (out > (size_t)count[r] && e[out - 1].col == e[k].col)
                e[out - 1].val += e[k].val;
            else
                e[out++] = e[k];
        }
    }
    count[n_rows] = (int)out;
    if (sem_csr_alloc(m, n_rows, n_cols, out) != SEM_OK) {
        free(count);
        free(e);
        return SEM_ERR_NOMEM;
    }
    memcpy(m->row_start, count, ((size_t)n_rows + 1) * sizeof(int));
    for (size_t k = 0; k < out; ++k) {
        m->col[k] = e[k].col;
        m->val[k] = e[k].val;
    }
    free(count);
    free(e);
    return SEM_OK;
}

void sem_csr_multiply_threads(const sem_csr *a, const double *x, int width, double *y, int threads)
{
    /* each row is its own sum in column order: the same bits on any thread count */
#pragma omp parallel for schedule(static) num_threads(threads > 1 ? threads : 1) if (threads > 1)
    for (int r = 0; r < a->n_rows; ++r) {
        double *yr = y + (size_t)r * width;
        for (int w = 0; w < width; ++w) yr[w] = 0.0;
        for (int k = a->row_start[r]; k < a->row_start[r + 1]; ++k) {
            const double *xc = x + (size_t)a->col[k] * width;
            for (int w = 0; w < width; ++w) yr[w] += a->val[k] * xc[w];
        }
    }
}

void sem_csr_multiply(const sem_csr *a, const double *x, int width, double *y)
{
    sem_csr_multiply_threads(a, x, width, y, 1);
}

void sem_csr_multiply_transpose(const sem_csr *a, const double *x, int width, double *y)
{
    memset(y, 0, (size_t)a->n_cols * width * sizeof *y);
    for (int r = 0; r < a->n_rows; ++r) {
        const double *xr = x + (size_t)r * width;
        for (int k = a->row_start[r]; k < a->row_start[r + 1]; ++k) {
            double *yc = y + (size_t)a->col[k] * width;
            for (int w = 0; w < width; ++w) yc[w] += a->val[k] * xr[w];
        }
    }
}
