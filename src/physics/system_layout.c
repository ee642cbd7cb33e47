/*
 * system_layout.c - free dofs, the sparse pattern of a set of objects' system and the maps
 * from their blocks into it; filling, factorizing and solving (see system.h).
 */
#include "system.h"

#include "structured.h"
#include "util/free_all.h"

#include <stdlib.h>
#include <string.h>

sem_status sem_object_free_dofs(sem_object *o, sem_error *err)
{
    o->free_index = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
    if (!o->free_index) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    o->n_free = 0;
    for (int c = 0; c < o->n_ctrl; ++c) o->free_index[c] = o->pinned[c] ? -1 : o->n_free++;
    return SEM_OK;
}

/* Visits every entry of the objects' K blocks (9 per scalar entry). pass 0 counts the
 * entries of each column of the upper triangle (count[c + 1]); pass 1 writes each entry's
 * row into rows at fill[c] and its position into the object's map (-1: not in the upper
 * triangle of the free dofs). */
static void visit_entries(sem_system *s, int pass, int *count, int *rows, int *fill)
{
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        int *map = s->map[k];
        int first = s->free_offset[k];
        for (int g = 0; g < o->n_gpairs; ++g) {
            int ga = o->gpair_a[g], gb = o->gpair_b[g];
            size_t na = sem_group_size(o, ga), nb = sem_group_size(o, gb);
            for (size_t la = 0; la < na; ++la) {
                int fa = o->free_index[o->group_ctrl[o->group_start[ga] + la]];
                for (size_t lb = 0; lb < nb; ++lb) {
                    int fb = o->free_index[o->group_ctrl[o->group_start[gb] + lb]];
                    for (int dd = 0; dd < 9; ++dd) {
                        int d1 = dd / 3, d2 = dd % 3;
                        size_t idx = 9 * o->gpair_offset[g] + (la * 9 + (size_t)dd) * nb + lb;
                        if (fa < 0 || fb < 0) {
                            if (pass == 1) map[idx] = -1;
                            continue;
                        }
                        int r = 3 * (first + fa) + d1, c = 3 * (first + fb) + d2;
                        if (ga > gb || (ga == gb && r > c)) {
                            if (pass == 1) map[idx] = -1;
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
                            map[idx] = fill[c]++;
                        }
                    }
                }
            }
        }
    }
    /* contact: coupling blocks between objects (object a < b, so every entry is in the
     * upper triangle) */
    for (int i = 0; i < s->n_couplings; ++i) {
        const sem_system_coupling *cp = &s->couplings[i];
        const sem_object *oa = s->objects[cp->a], *ob = s->objects[cp->b];
        size_t na = sem_group_size(oa, cp->ga), nb = sem_group_size(ob, cp->gb);
        int *map = s->coupling_map[i];
        for (size_t la = 0; la < na; ++la) {
            int fa = oa->free_index[oa->group_ctrl[oa->group_start[cp->ga] + la]];
            for (size_t lb = 0; lb < nb; ++lb) {
                int fb = ob->free_index[ob->group_ctrl[ob->group_start[cp->gb] + lb]];
                for (int dd = 0; dd < 9; ++dd) {
                    size_t idx = (la * 9 + (size_t)dd) * nb + lb;
                    if (fa < 0 || fb < 0) {
                        if (pass == 1) map[idx] = -1;
                        continue;
                    }
                    int r = 3 * (s->free_offset[cp->a] + fa) + dd / 3, c = 3 * (s->free_offset[cp->b] + fb) + dd % 3;
                    if (pass == 0)
                        count[c + 1]++;
                    else {
                        rows[fill[c]] = r;
                        map[idx] = fill[c]++;
                    }
                }
            }
        }
    }
}

static size_t coupling_entries(const sem_system *s, int i)
{
    const sem_system_coupling *cp = &s->couplings[i];
    return 9 * sem_group_size(s->objects[cp->a], cp->ga) * sem_group_size(s->objects[cp->b], cp->gb);
}

/* CSC pattern of the free dofs (upper triangle), the maps and the solver. */
static sem_status build_pattern(sem_system *s, sem_solver_choice choice, sem_error *err)
{
    int nf = 3 * s->n_free;
    sem_status st = SEM_OK;
    int *count = calloc((size_t)nf + 1, sizeof(int));
    int *rows = NULL, *fill = NULL, *perm = NULL, *inv = NULL, *sorted = NULL;
    if (!count) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        s->map[k] = malloc((9 * o->gpair_offset[o->n_gpairs] + 1) * sizeof(int));
        if (!s->map[k]) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
            goto done;
        }
    }
    for (int i = 0; i < s->n_couplings; ++i) {
        s->coupling_map[i] = malloc((coupling_entries(s, i) + 1) * sizeof(int));
        if (!s->coupling_map[i]) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
            goto done;
        }
    }
    visit_entries(s, 0, count, NULL, NULL);
    for (int c = 0; c < nf; ++c) count[c + 1] += count[c];
    rows = malloc(((size_t)count[nf] + 1) * sizeof(int));
    fill = malloc(((size_t)nf + 1) * sizeof(int));
    if (!rows || !fill) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the system pattern");
        goto done;
    }
    memcpy(fill, count, (size_t)nf * sizeof(int));
    visit_entries(s, 1, count, rows, fill);
    /* Each (r,c) occurs once: group pairs are distinct, a control point is in one group and
     * objects have disjoint dofs. Sort rows within columns and remap positions. */
    perm = malloc(((size_t)count[nf] + 1) * sizeof(int));
    inv = malloc(((size_t)count[nf] + 1) * sizeof(int));
    sorted = malloc(((size_t)count[nf] + 1) * sizeof(int));
    if (!perm || !inv || !sorted) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* rows sorted within every column in O(nnz), by a counting sort on the row: entries are
     * bucketed by row (columns in increasing order within a bucket), then the buckets are
     * dealt out to their columns in row order (perm holds each entry's column, sorted the
     * bucketed entries). A column of the 30 % dense system of an 11,439-dof CAD part holds
     * ~3,400 rows, where an insertion sort per column took most of a minute. */
    {
        int *rstart = calloc((size_t)nf + 2, sizeof(int)), *cpos = malloc(((size_t)nf + 1) * sizeof(int));
        if (!rstart || !cpos) {
            free(rstart);
            free(cpos);
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto done;
        }
        for (int k = 0; k < count[nf]; ++k) rstart[rows[k] + 1]++;
        for (int r = 0; r < nf; ++r) rstart[r + 1] += rstart[r];
        for (int c = 0; c < nf; ++c)
            for (int k = count[c]; k < count[c + 1]; ++k) {
                perm[k] = c;
                sorted[rstart[rows[k]]++] = k;
            }
        memcpy(cpos, count, (size_t)nf * sizeof(int));
        for (int j = 0; j < count[nf]; ++j) {
            int k = sorted[j];
            inv[k] = cpos[perm[k]]++;
        }
        free(rstart);
        free(cpos);
    }
    for (int k = 0; k < count[nf]; ++k) sorted[inv[k]] = rows[k];
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        size_t n = 9 * o->gpair_offset[o->n_gpairs];
        for (size_t e = 0; e < n; ++e)
            if (s->map[k][e] >= 0) s->map[k][e] = inv[s->map[k][e]];
    }
    for (int i = 0; i < s->n_couplings; ++i)
        for (size_t e = 0, n = coupling_entries(s, i); e < n; ++e)
            if (s->coupling_map[i][e] >= 0) s->coupling_map[i][e] = inv[s->coupling_map[i][e]];
    st = sem_linear_solver_create(nf, count, sorted, choice, &s->solver, err);
    if (st == SEM_OK)
        for (int k = 0; k < s->n_objects; ++k) {
            const sem_object *o = s->objects[k];
            sem_linear_solver_remap(s->solver, s->map[k], 9 * o->gpair_offset[o->n_gpairs]);
        }
    if (st == SEM_OK)
        for (int i = 0; i < s->n_couplings; ++i)
            sem_linear_solver_remap(s->solver, s->coupling_map[i], coupling_entries(s, i));
done:
    SEM_FREE_ALL(sorted, perm, inv, rows, fill, count);
    return st;
}

static int compare_coupling(const void *x, const void *y)
{
    const sem_system_coupling *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    if (p->ga != q->ga) return (p->ga > q->ga) - (p->ga < q->ga);
    if (p->b != q->b) return (p->b > q->b) - (p->b < q->b);
    return (p->gb > q->gb) - (p->gb < q->gb);
}

int sem_system_find_coupling(const sem_system *s, int a, int ga, int b, int gb)
{
    const sem_system_coupling key = {a, ga, b, gb};
    int lo = 0, hi = s->n_couplings - 1;
    while (lo <= hi) {
        int mid = (lo + hi) / 2, c = compare_coupling(&s->couplings[mid], &key);
        if (c == 0) return mid;
        if (c < 0)
            lo = mid + 1;
        else
            hi = mid - 1;
    }
    return -1;
}

sem_status sem_system_create(sem_object **objects, int n_objects, sem_solver_choice choice,
                             sem_system **out, sem_error *err)
{
    return sem_system_create_coupled(objects, n_objects, NULL, 0, choice, out, err);
}

sem_status sem_system_create_coupled(sem_object **objects, int n_objects, const sem_system_coupling *couplings,
                                     int n_couplings, sem_solver_choice choice, sem_system **out, sem_error *err)
{
    *out = NULL;
    sem_system *s = calloc(1, sizeof *s);
    if (!s) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    size_t n = n_objects > 0 ? (size_t)n_objects : 1;
    s->n_objects = n_objects;
    s->objects = malloc(n * sizeof *s->objects);
    s->free_offset = calloc(n + 1, sizeof *s->free_offset);
    s->dof_offset = calloc(n + 1, sizeof *s->dof_offset);
    s->map = calloc(n, sizeof *s->map);
    if (!s->objects || !s->free_offset || !s->dof_offset || !s->map) {
        sem_system_destroy(s);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < n_objects; ++k) {
        sem_object *o = objects[k];
        s->objects[k] = o;
        s->free_offset[k + 1] = s->free_offset[k] + o->n_free;
        s->dof_offset[k + 1] = s->dof_offset[k] + 3 * (size_t)o->n_ctrl;
    }
    s->n_free = s->free_offset[n_objects];
    s->n_dofs = s->dof_offset[n_objects];
    /* contact's coupling blocks: sorted, without duplicates, a < b */
    if (n_couplings > 0) {
        s->couplings = malloc((size_t)n_couplings * sizeof *s->couplings);
        s->coupling_map = calloc((size_t)n_couplings, sizeof *s->coupling_map);
        if (!s->couplings || !s->coupling_map) {
            sem_system_destroy(s);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        for (int i = 0; i < n_couplings; ++i) {
            sem_system_coupling cp = couplings[i];
            if (cp.a > cp.b) cp = (sem_system_coupling){cp.b, cp.gb, cp.a, cp.ga};
            if (cp.a == cp.b || cp.a < 0 || cp.b >= n_objects) continue;
            s->couplings[s->n_couplings++] = cp;
        }
        qsort(s->couplings, (size_t)s->n_couplings, sizeof *s->couplings, compare_coupling);
        int kept = 0;
        for (int i = 0; i < s->n_couplings; ++i)
            if (kept == 0 || compare_coupling(&s->couplings[kept - 1], &s->couplings[i]) != 0)
                s->couplings[kept++] = s->couplings[i];
        s->n_couplings = kept;
    }
    s->structured = n_objects > 0 && objects[0]->structured;
    if (s->structured) {
        s->ssolver = calloc(n, sizeof *s->ssolver);
        if (!s->ssolver) {
            sem_system_destroy(s);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        for (int k = 0; k < n_objects; ++k) {
            if (objects[k]->n_free == 0) continue;
            sem_status st = sem_structured_solver_create(objects[k], &s->ssolver[k], err);
            if (st != SEM_OK) {
                sem_system_destroy(s);
                return st;
            }
        }
    } else if (s->n_free > 0) {
        sem_status st = build_pattern(s, choice, err);
        if (st != SEM_OK) {
            sem_system_destroy(s);
            return st;
        }
    }
    for (int k = 0; k < n_objects; ++k) objects[k]->system = s;
    *out = s;
    return SEM_OK;
}

void sem_system_destroy(sem_system *s)
{
    if (!s) return;
    if (s->map)
        for (int k = 0; k < s->n_objects; ++k) free(s->map[k]);
    free(s->map);
    if (s->coupling_map)
        for (int i = 0; i < s->n_couplings; ++i) free(s->coupling_map[i]);
    free(s->coupling_map);
    free(s->couplings);
    if (s->ssolver)
        for (int k = 0; k < s->n_objects; ++k) sem_structured_solver_destroy(s->ssolver[k]);
    free(s->ssolver);
    sem_linear_solver_destroy(s->solver);
    sem_linear_solver_destroy(s->rest);
    free(s->objects);
    free(s->free_offset);
    free(s->dof_offset);
    free(s);
}

void sem_system_fill_gpair(sem_system *s, int k, int g, const double c[5], double *val)
{
    const sem_object *o = s->objects[k];
    if (o->gpair_a[g] > o->gpair_b[g]) return; /* mapped nowhere (see system.h) */
    size_t na = sem_group_size(o, o->gpair_a[g]), nb = sem_group_size(o, o->gpair_b[g]);
    size_t off = o->gpair_offset[g];
    for (size_t la = 0; la < na; ++la) {
        const double *Ms = o->M_blocks + off + la * nb, *Es = o->E_blocks + off + la * nb;
        const double *As = o->A_blocks && c[4] != 0 ? o->A_blocks + off + la * nb : NULL;
        for (int dd = 0; dd < 9; ++dd) {
            int diag = dd / 3 == dd % 3;
            size_t row = 9 * off + (la * 9 + (size_t)dd) * nb;
            const int *map = s->map[k] + row;
            const double *K = o->K_blocks + row, *K0 = o->K0_blocks + row;
            for (size_t lb = 0; lb < nb; ++lb) {
                int pos = map[lb];
                if (pos < 0) continue;
                double v = c[2] * K[lb] + c[3] * K0[lb];
                if (diag) v += c[0] * Ms[lb] + 2.0 * c[1] * Es[lb] + (As ? c[4] * As[lb] : 0.0);
                val[pos] = v;
            }
        }
    }
}

void sem_system_set_object(sem_system *s, int k, const double c[5])
{
    if (s->ssolver && s->ssolver[k]) sem_structured_solver_set(s->ssolver[k], c);
}

void sem_system_fill(sem_system *s, double cM, double cE, double cK, double cD, double cA)
{
    if (s->structured) {
        for (int k = 0; k < s->n_objects; ++k) {
            const double c[5] = {cM, cE * s->objects[k]->gamma, cK, cD, cA};
            sem_system_set_object(s, k, c);
        }
        return;
    }
    double *val = sem_linear_solver_values(s->solver);
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        const double c[5] = {cM, cE * o->gamma, cK, cD, cA};
#pragma omp parallel for schedule(dynamic, 8) num_threads(o->nthreads)
        for (int g = 0; g < o->n_gpairs; ++g) sem_system_fill_gpair(s, k, g, c, val);
    }
}

sem_status sem_system_factorize_rest(sem_system *s, double cM, double cE, double cD, double cA, int *factored,
                                    sem_error *err)
{
    *factored = 0;
    if (s->rest && s->rest_coef[0] == cM && s->rest_coef[1] == cE && s->rest_coef[2] == cD && s->rest_coef[3] == cA)
        return SEM_OK;
    if (!s->rest) {
        sem_status st = sem_linear_solver_clone_pattern(s->solver, &s->rest, err);
        if (st != SEM_OK) return st;
    }
    double *val = sem_linear_solver_values(s->rest);
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        const double c[5] = {cM, cE * o->gamma, 0.0, cD, cA};
#pragma omp parallel for schedule(dynamic, 8) num_threads(o->nthreads)
        for (int g = 0; g < o->n_gpairs; ++g) sem_system_fill_gpair(s, k, g, c, val);
    }
    s->rest_coef[0] = -1; /* not valid until factored */
    sem_status st = sem_linear_solver_factorize(s->rest, err);
    if (st != SEM_OK) return st;
    s->rest_coef[0] = cM;
    s->rest_coef[1] = cE;
    s->rest_coef[2] = cD;
    s->rest_coef[3] = cA;
    *factored = 1;
    return SEM_OK;
}

double sem_system_rest_factor_seconds(const sem_system *s)
{
    return s->rest ? sem_linear_solver_last_factor_seconds(s->rest) : 0.0;
}

sem_status sem_system_solve_rest(sem_system *s, const double *b, double *x, sem_error *err)
{
    return sem_linear_solver_solve_plain(s->rest, b, x, err);
}

void sem_system_residual_rest(sem_system *s, const double *b, const double *x, double *r, double *scale)
{
    sem_linear_solver_residual(s->rest, b, x, r, scale);
}

sem_status sem_system_solve_structured_rest(sem_system *s, int max_order, int max_it, const double *b, double *x,
                                           int *solved, long *factorizations, double *factor_s, sem_error *err)
{
    *solved = 0;
    for (int k = 0; k < s->n_objects; ++k)
        if (s->ssolver[k] && sem_structured_solver_coefficients(s->ssolver[k]) > max_order) return SEM_OK;
    for (int k = 0; k < s->n_objects; ++k) {
        if (!s->ssolver[k]) continue;
        int factored = 0;
        sem_status st = sem_structured_solver_factorize_rest(s->ssolver[k], &factored, err);
        if (factored) {
            (*factorizations)++;
            *factor_s += sem_structured_solver_factor_seconds(s->ssolver[k]);
        }
        if (st != SEM_OK) return st;
        size_t off = 3 * (size_t)s->free_offset[k];
        int ok = 0;
        if ((st = sem_structured_solver_solve_rest(s->ssolver[k], b + off, x + off, max_it, &ok, err)) != SEM_OK)
            return st;
        if (!ok) return SEM_OK;
    }
    *solved = 1;
    return SEM_OK;
}

double *sem_system_values(sem_system *s)
{
    return s->solver ? sem_linear_solver_values(s->solver) : NULL;
}

sem_status sem_system_factorize(sem_system *s, sem_error *err)
{
    if (s->structured) {
        s->factor_s = 0;
        for (int k = 0; k < s->n_objects; ++k) {
            if (!s->ssolver[k]) continue;
            sem_status st = sem_structured_solver_factorize(s->ssolver[k], err);
            s->factor_s += sem_structured_solver_factor_seconds(s->ssolver[k]);
            if (st != SEM_OK) return st;
        }
        return SEM_OK;
    }
    return sem_linear_solver_factorize(s->solver, err);
}

double sem_system_factor_seconds(const sem_system *s)
{
    if (s->structured) return s->factor_s;
    return sem_linear_solver_last_factor_seconds(s->solver);
}

sem_status sem_system_solve(sem_system *s, const double *b, double *x, sem_error *err)
{
    if (s->structured) {
        for (int k = 0; k < s->n_objects; ++k) {
            if (!s->ssolver[k]) continue;
            size_t off = 3 * (size_t)s->free_offset[k];
            sem_status st = sem_structured_solver_solve(s->ssolver[k], b + off, x + off, err);
            if (st != SEM_OK) return st;
        }
        return SEM_OK;
    }
    return sem_linear_solver_solve(s->solver, b, x, err);
}

void sem_system_gather_free(const sem_system *s, const double *full, double *free_values)
{
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        const double *x = full + s->dof_offset[k];
        double *y = free_values + 3 * (size_t)s->free_offset[k];
        for (int c = 0; c < o->n_ctrl; ++c) {
            int f = o->free_index[c];
            if (f < 0) continue;
            for (int d = 0; d < 3; ++d) y[3 * f + d] = x[3 * c + d];
        }
    }
}

void sem_system_scatter_free(const sem_system *s, const double *free_values, double *full)
{
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        const double *y = free_values + 3 * (size_t)s->free_offset[k];
        double *x = full + s->dof_offset[k];
        for (int c = 0; c < o->n_ctrl; ++c) {
            int f = o->free_index[c];
            if (f < 0) continue;
            for (int d = 0; d < 3; ++d) x[3 * c + d] = y[3 * f + d];
        }
    }
}
