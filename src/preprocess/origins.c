/*
 * origins.c - deformation origins by min-cost network flow (paper Sec. 6.2, Eq. 10, Fig. 6).
 *
 * Every part's polynomial is expanded about a deformation origin; parts that share an origin
 * share its translation t_j (Eq. 7), which is what couples them. Candidates come from the
 * blending weights: quadrature points are grouped by the *set* of parts with a non-zero
 * weight there (the sorted column list of their row of W, hashed); every set of two or more
 * parts is a candidate origin.
 *
 * Network (paper Fig. 6):
 *   source -> candidate   capacity = number of parts in the candidate's set
 *   candidate -> part     capacity 1, for every part of the set,
 *                         cost = sum over the group's points of that part's weight
 *                         (the paper's choice: it discourages heavily connected origins)
 *   part -> sink          capacity 1
 * with supply = demand = the number of parts that occur in some candidate, so the flow
 * saturates every part-sink arc: each such part gets exactly one origin.
 *
 * Solved in closed form. A candidate's inflow is bounded by its capacity, the number of
 * its parts, but its outflow can never exceed that number anyway (one arc of capacity 1
 * per part), so the source arcs never bind: the only constraints are "each part receives
 * one unit", one per part, and the minimum-cost flow sends each part's unit along its
 * cheapest candidate arc. Each part therefore takes the candidate of least cost among the
 * sets it occurs in. Costs are compared as they were given to GLPK's out-of-kilter solver
 * before (scaled so that their total is 1e9, rounded), ties go to the first candidate (in
 * the order of the quadrature rows), and on every Table 1 model the assignment is the one
 * glp_mincost_okalg returned (compared part by part: 0 differences, the twisting beam with
 * 65 ties). The solver took 2.9 ms of the stiff mug's 21 ms preprocessing (issue 12's 50x);
 * this takes microseconds. tests/test_origins.c checks optimality on random networks and
 * against GLPK's solution of the same network.
 *
 * A part in no multi-part group (isolated, or without any weight) gets its own origin. Each
 * candidate that receives flow becomes an origin; origins are numbered by their smallest
 * part index. An origin sits at the area-weighted centroid of the boundary samples of its
 * parts (Sec. 6.2, as t_j in Eq. 7). Fallbacks when the parts have no sample area: the plain
 * mean of their samples, else the mean of the quadrature points where they have weight,
 * else the origin of coordinates.
 */
#include "steps.h"
#include "util/free_all.h"

#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A group of quadrature points sharing one set of parts. */
typedef struct origin_group {
    int first_row;  /* its set is the column list of this row of W */
    int n_parts;
    double *cost;   /* per part of the set: sum of the part's weight over the group */
} origin_group;

static uint64_t hash_columns(const int *col, int n)
{
    uint64_t h = 1469598103934665603ull; /* FNV-1a over the column indices */
    for (int k = 0; k < n; ++k) {
        uint32_t v = (uint32_t)col[k];
        for (int b = 0; b < 4; ++b) {
            h ^= (v >> (8 * b)) & 0xffu;
            h *= 1099511628211ull;
        }
    }
    return h ^ (uint64_t)n;
}

static sem_status validate(const sem_discretization *d, sem_error *err)
{
    if (d->n_parts <= 0) return sem_error_set(err, SEM_ERR_INVALID, "origins: no parts");
    /* no quadrature points (a model without volume): W may be empty, all parts isolated */
    const int empty = d->n_quad == 0 && d->W.n_rows == 0;
    if (d->n_quad < 0 || d->W.n_rows != d->n_quad || (!empty && d->W.n_cols != d->n_parts) ||
        (d->n_quad > 0 && (!d->W.row_start || !d->quad_X)))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "origins: W is %d x %d, expected %d quadrature points x %d parts",
                             d->W.n_rows, d->W.n_cols, d->n_quad, d->n_parts);
    for (int r = 0; r < d->W.n_rows; ++r) {
        if (d->W.row_start[r + 1] < d->W.row_start[r])
            return sem_error_set(err, SEM_ERR_INVALID, "origins: W row %d is malformed", r);
        for (int k = d->W.row_start[r]; k < d->W.row_start[r + 1]; ++k) {
            if (d->W.col[k] < 0 || d->W.col[k] >= d->n_parts ||
                (k > d->W.row_start[r] && d->W.col[k] <= d->W.col[k - 1]))
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "origins: W row %d has unsorted or out-of-range columns", r);
            if (!isfinite(d->W.val[k]) || d->W.val[k] < 0.0)
                return sem_error_set(err, SEM_ERR_INVALID, "origins: W row %d has weight %g", r,
                                     d->W.val[k]);
        }
    }
    if (d->n_samples < 0 || (d->n_samples > 0 && (!d->sample_X || !d->sample_part)))
        return sem_error_set(err, SEM_ERR_INVALID, "origins: boundary samples missing");
    for (int k = 0; k < d->n_samples; ++k)
        if (d->sample_part[k] < 0 || d->sample_part[k] >= d->n_parts)
            return sem_error_set(err, SEM_ERR_INVALID, "origins: sample %d has part %d of %d", k,
                                 d->sample_part[k], d->n_parts);
    return SEM_OK;
}

/* Groups the rows of W with >= 2 entries by their column set (open addressing on the hash).
 * Fills *groups (caller frees each cost and the array) and returns their number, or -1. */
static int group_rows(const sem_csr *W, origin_group **groups_out)
{
    *groups_out = NULL;
    const int n = W->n_rows;
    size_t table_size = 16;
    while (table_size < 2 * (size_t)n) table_size *= 2;
    int *table = malloc(table_size * sizeof *table); /* group index or -1 */
    uint64_t *table_hash = malloc(table_size * sizeof *table_hash);
    int cap = 16, count = 0;
    origin_group *groups = malloc((size_t)cap * sizeof *groups);
    if (!table || !table_hash || !groups) goto fail;
    for (size_t k = 0; k < table_size; ++k) table[k] = -1;

    for (int r = 0; r < n; ++r) {
        const int b = W->row_start[r], len = W->row_start[r + 1] - b;
        if (len < 2) continue;
        const uint64_t h = hash_columns(&W->col[b], len);
        size_t slot = (size_t)h & (table_size - 1);
        int g = -1;
        while (table[slot] >= 0) {
            const origin_group *cand = &groups[table[slot]];
            const int cb = W->row_start[cand->first_row];
            if (table_hash[slot] == h && cand->n_parts == len &&
                memcmp(&W->col[cb], &W->col[b], (size_t)len * sizeof(int)) == 0) {
                g = table[slot];
                break;
            }
            slot = (slot + 1) & (table_size - 1);
        }
        if (g < 0) {
            if (count == cap) {
                origin_group *grown = realloc(groups, 2 * (size_t)cap * sizeof *groups);
                if (!grown) goto fail;
                groups = grown;
                cap *= 2;
            }
            g = count;
            groups[g].first_row = r;
            groups[g].n_parts = len;
            groups[g].cost = calloc((size_t)len, sizeof(double));
            if (!groups[g].cost) goto fail;
            ++count;
            table[slot] = g;
            table_hash[slot] = h;
        }
        for (int k = 0; k < len; ++k) groups[g].cost[k] += W->val[b + k];
    }
    free(table);
    free(table_hash);
    *groups_out = groups;
    return count;
fail:
    if (groups)
        for (int g = 0; g < count; ++g) free(groups[g].cost);
    free(groups);
    free(table);
    free(table_hash);
    return -1;
}

/* Solves the network of the header; assigned[p] = group of part p (or -1 for parts in no
 * group). */
static sem_status solve_assignment(const sem_discretization *d, const origin_group *groups,
                                   int n_groups, int *assigned, sem_error *err)
{
    const int n_parts = d->n_parts;
    const sem_csr *W = &d->W;
    for (int p = 0; p < n_parts; ++p) assigned[p] = -1;
    if (n_groups == 0) return SEM_OK;
    double cost_total = 0.0;
    for (int g = 0; g < n_groups; ++g)
        for (int k = 0; k < groups[g].n_parts; ++k) cost_total += groups[g].cost[k];
    const double scale = cost_total > 0.0 ? 1e9 / cost_total : 0.0;
    double *best = malloc(((size_t)n_parts + 1) * sizeof *best);
    if (!best) return sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
    for (int g = 0; g < n_groups; ++g) {
        const int *col = &W->col[W->row_start[groups[g].first_row]];
        for (int k = 0; k < groups[g].n_parts; ++k) {
            const int p = col[k];
            const double c = floor(groups[g].cost[k] * scale + 0.5);
            if (assigned[p] < 0 || c < best[p]) {
                assigned[p] = g;
                best[p] = c;
            }
        }
    }
    free(best);
    return SEM_OK;
}

void sem_set_origins(sem_discretization *d, double *origin_X, int *part_origin, int n_origins)
{
    free(d->origin_X);
    free(d->part_origin);
    d->origin_X = origin_X;
    d->part_origin = part_origin;
    d->n_origins = n_origins;
}

sem_status sem_step_origins(const sem_model *model, sem_discretization *d, sem_error *err)
{
    (void)model;
    if (!d) return sem_error_set(err, SEM_ERR_INVALID, "origins: missing discretization");
    sem_status st = validate(d, err);
    if (st != SEM_OK) return st;
    const int n_parts = d->n_parts;
    int n_origins = 0;
    double *origin_X = NULL, *origin_acc = NULL;

    origin_group *groups = NULL;
    const int n_groups = group_rows(&d->W, &groups);
    int *assigned = malloc((size_t)n_parts * sizeof *assigned);
    int *group_origin = malloc(((size_t)n_groups + 1) * sizeof *group_origin);
    int *part_origin = malloc((size_t)n_parts * sizeof *part_origin);
    /* per part: area-weighted sum, area, plain sum, count; then quadrature fallback */
    double *acc = calloc((size_t)n_parts * 10, sizeof *acc);
    if (n_groups < 0 || !assigned || !group_origin || !part_origin || !acc) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
        goto done;
    }
    st = solve_assignment(d, groups, n_groups, assigned, err);
    if (st != SEM_OK) goto done;

    /* number the origins by their smallest part index */
    for (int g = 0; g < n_groups; ++g) group_origin[g] = -1;
    for (int p = 0; p < n_parts; ++p) {
        if (assigned[p] < 0) {
            part_origin[p] = n_origins++; /* isolated part: its own origin */
        } else {
            if (group_origin[assigned[p]] < 0) group_origin[assigned[p]] = n_origins++;
            part_origin[p] = group_origin[assigned[p]];
        }
    }

    for (int k = 0; k < d->n_samples; ++k) {
        double *a = &acc[10 * (size_t)d->sample_part[k]];
        const double *x = &d->sample_X[3 * (size_t)k];
        const double area = d->sample_area && d->sample_area[k] > 0.0 ? d->sample_area[k] : 0.0;
        for (int e = 0; e < 3; ++e) {
            a[e] += area * x[e];
            a[4 + e] += x[e];
        }
        a[3] += area;
        a[7] += 1.0;
    }
    /* quadrature fallback for parts without samples: mean of the points they weigh on */
    for (int r = 0; r < d->W.n_rows; ++r)
        for (int k = d->W.row_start[r]; k < d->W.row_start[r + 1]; ++k) {
            double *a = &acc[10 * (size_t)d->W.col[k]];
            if (a[7] > 0.0) continue;
            for (int e = 0; e < 3; ++e) a[4 + e] += d->quad_X[3 * (size_t)r + e];
            a[8] += 1.0;
        }

    origin_X = calloc(3 * (size_t)n_origins, sizeof *origin_X);
    origin_acc = calloc(9 * (size_t)n_origins, sizeof *origin_acc);
    if (!origin_X || !origin_acc) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "origins: out of memory");
        goto done;
    }
    for (int p = 0; p < n_parts; ++p) {
        double *o = &origin_acc[9 * (size_t)part_origin[p]];
        const double *a = &acc[10 * (size_t)p];
        for (int e = 0; e < 3; ++e) {
            o[e] += a[e];
            o[4 + e] += a[4 + e];
        }
        o[3] += a[3];
        o[7] += a[7] + a[8];
    }
    for (int j = 0; j < n_origins; ++j) {
        const double *o = &origin_acc[9 * (size_t)j];
        for (int e = 0; e < 3; ++e) {
            if (o[3] > 0.0)
                origin_X[3 * (size_t)j + e] = o[e] / o[3];
            else if (o[7] > 0.0)
                origin_X[3 * (size_t)j + e] = o[4 + e] / o[7];
        }
    }
    sem_set_origins(d, origin_X, part_origin, n_origins);
    part_origin = NULL;
    origin_X = NULL;

done:
    if (groups && n_groups > 0)
        for (int g = 0; g < n_groups; ++g) free(groups[g].cost);
    SEM_FREE_ALL(groups, assigned, group_origin, part_origin, acc, origin_X, origin_acc);
    return st;
}
