/*
 * sem/sparse.h - compressed sparse rows, the one sparse format of the preprocessing data.
 *
 * The SEM operators act identically on the x, y and z coordinates of the control points
 * (every fit in Eq. 4-7 is per coordinate with one matrix), so they are stored as *scalar*
 * matrices over control points; the 3D operator is the Kronecker product with I3.
 * Columns within a row are sorted and unique.
 */
#ifndef SEM_SPARSE_H
#define SEM_SPARSE_H

#include <stddef.h>

#include "sem/status.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct sem_csr {
    int n_rows, n_cols;
    int *row_start; /* n_rows + 1 */
    int *col;       /* row_start[n_rows] */
    double *val;
} sem_csr;

void sem_csr_free(sem_csr *m);
/* Allocates an n_rows x n_cols matrix with room for nnz entries (row_start zeroed). */
sem_status sem_csr_alloc(sem_csr *m, int n_rows, int n_cols, size_t nnz);
/* Builds from triplets (duplicates summed, columns sorted). */
sem_status sem_csr_from_triplets(sem_csr *m, int n_rows, int n_cols, size_t n, const int *rows,
                                 const int *cols, const double *vals);
/* y = A x (x has n_cols entries, y n_rows). stride: apply to `width` interleaved columns,
 * i.e. X is n_cols x width row-major (e.g. width 3 for control points). */
void sem_csr_multiply(const sem_csr *a, const double *x, int width, double *y);
/* The same with its rows split over `threads` OpenMP threads (the same bits on any count). */
void sem_csr_multiply_threads(const sem_csr *a, const double *x, int width, double *y, int threads);
/* y = A^T x, same conventions. */
void sem_csr_multiply_transpose(const sem_csr *a, const double *x, int width, double *y);
size_t sem_csr_nnz(const sem_csr *m);
sem_status sem_csr_copy(sem_csr *dst, const sem_csr *src);

#ifdef __cplusplus
}
#endif
#endif
