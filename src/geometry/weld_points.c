/*
 * weld_points.c - points that are one point (see geometry/weld_points.h).
 *
 * Points are put in cells of size tol (a grid), sorted by cell; every point is compared with
 * the points of its cell and the 26 around it (binary search for each), so the cost is
 * O(n log n) for any shape, also for the many points of a flat face that share one
 * coordinate. Groups are joined by union-find (util/union_find.h); a group's representative
 * is its lowest index, so the result does not depend on the order of the comparisons.
 */
#include "geometry/weld_points.h"

#include <math.h>
#include <stdlib.h>

#include "util/union_find.h"

typedef struct cell_point {
    long long cell[3];
    int point;
} cell_point;

static int compare_cell(const long long *a, const long long *b)
{
    for (int k = 0; k < 3; ++k)
        if (a[k] != b[k]) return (a[k] > b[k]) - (a[k] < b[k]);
    return 0;
}

static int compare_cell_point(const void *x, const void *y)
{
    const cell_point *a = x, *b = y;
    int c = compare_cell(a->cell, b->cell);
    return c ? c : (a->point > b->point) - (a->point < b->point);
}

/* first index of sorted[0..n) whose cell is not below key */
static int lower_bound(const cell_point *sorted, int n, const long long key[3])
{
    int lo = 0, hi = n;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (compare_cell(sorted[mid].cell, key) < 0)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo;
}

sem_status sem_weld_points(const double *x, int n, double tol, int *weld, sem_error *err)
{
    for (int i = 0; i < n; ++i) weld[i] = i;
    if (n < 2 || !(tol > 0)) return SEM_OK;
    cell_point *sorted = malloc((size_t)n * sizeof *sorted);
    if (!sorted) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory welding %d points", n);
    for (int i = 0; i < n; ++i) {
        for (int k = 0; k < 3; ++k) {
            double c = floor(x[3 * (size_t)i + k] / tol);
            sorted[i].cell[k] = c > 1e15 ? (long long)1e15 : c < -1e15 ? (long long)-1e15 : (long long)c;
        }
        sorted[i].point = i;
    }
    qsort(sorted, (size_t)n, sizeof *sorted, compare_cell_point);
    double tol2 = tol * tol;
    for (int s = 0; s < n; ++s) {
        int i = sorted[s].point;
        const double *xi = x + 3 * (size_t)i;
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    long long key[3] = {sorted[s].cell[0] + dx, sorted[s].cell[1] + dy, sorted[s].cell[2] + dz};
                    for (int t = lower_bound(sorted, n, key); t < n && !compare_cell(sorted[t].cell, key); ++t) {
                        int j = sorted[t].point;
                        if (j <= i) continue;
                        const double *xj = x + 3 * (size_t)j;
                        double d2 = (xi[0] - xj[0]) * (xi[0] - xj[0]) + (xi[1] - xj[1]) * (xi[1] - xj[1]) +
                                    (xi[2] - xj[2]) * (xi[2] - xj[2]);
                        if (d2 <= tol2) sem_uf_unite(weld, i, j);
                    }
                }
    }
    for (int i = 0; i < n; ++i) weld[i] = sem_uf_find(weld, i);
    free(sorted);
    return SEM_OK;
}
