/*
 * point_terms.c - point terms into today's linear system (see point_terms.h): entries of one
 * object's group through the system's map, entries between objects through its coupling
 * blocks, terms whose coupling blocks are missing bounded from above by their sets' own
 * blocks.
 */
#include "point_terms.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "util/grow.h"

void sem_point_terms_init(sem_point_terms *t) { memset(t, 0, sizeof *t); }

void sem_point_terms_free(sem_point_terms *t)
{
    free(t->terms);
    free(t->weights);
    memset(t, 0, sizeof *t);
}

void sem_point_terms_clear(sem_point_terms *t)
{
    t->n = 0;
    t->n_weights = 0;
}

sem_status sem_point_terms_push(sem_point_terms *t, const sem_point_weight *weights, int count,
                                const double H[9], sem_error *err)
{
    if (!sem_grow((void **)&t->terms, &t->cap, t->n + 1, sizeof *t->terms, 256, INT_MAX) ||
        !sem_grow((void **)&t->weights, &t->cap_weights, t->n_weights + count, sizeof *t->weights, 4096, INT_MAX))
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contact terms");
    sem_point_term *term = &t->terms[t->n++];
    term->first = t->n_weights;
    term->count = count;
    memcpy(term->H, H, sizeof term->H);
    memcpy(t->weights + t->n_weights, weights, (size_t)count * sizeof *weights);
    t->n_weights += count;
    return SEM_OK;
}

/* The (object, group) set of each weight of a term, numbered 0..m-1 in order of first
 * appearance; returns m. Pinned control points are in no set (-2): they drop out, and a
 * term whose other side is all pinned (a plate held in place) goes in exactly. */
static int term_sets(const sem_system *s, const sem_point_term *term, const sem_point_weight *wt,
                     int *set)
{
    int m = 0;
    for (int i = 0; i < term->count; ++i) {
        const sem_point_weight *a = &wt[i];
        int ga = s->objects[a->object]->ctrl_group[a->ctrl];
        set[i] = -1;
        if (s->objects[a->object]->free_index[a->ctrl] < 0) {
            set[i] = -2;
            continue;
        }
        for (int j = 0; j < i; ++j) {
            const sem_point_weight *b = &wt[j];
            if (set[j] >= 0 && b->object == a->object && s->objects[b->object]->ctrl_group[b->ctrl] == ga) {
                set[i] = set[j];
                break;
            }
        }
        if (set[i] < 0) set[i] = m++;
    }
    return m;
}

/* Position in the solver's values of the upper-triangle entry of object k between
 * (c1, d1) and (c2, d2) (both free, system row of (c1, d1) <= that of (c2, d2)); -1 when the
 * pattern does not hold it. */
static int position(const sem_system *s, int k, int c1, int d1, int c2, int d2)
{
    const sem_object *o = s->objects[k];
    int g1 = o->ctrl_group[c1], g2 = o->ctrl_group[c2];
    if (g1 > g2) {
        int t = c1;
        c1 = c2;
        c2 = t;
        t = d1;
        d1 = d2;
        d2 = t;
        t = g1;
        g1 = g2;
        g2 = t;
    }
    int g = o->gpair_lookup[(size_t)g1 * o->n_groups + g2];
    if (g < 0) return -1;
    size_t nb = sem_group_size(o, g2);
    size_t idx = 9 * o->gpair_offset[g] + ((size_t)o->ctrl_local[c1] * 9 + 3 * (size_t)d1 + (size_t)d2) * nb +
                 (size_t)o->ctrl_local[c2];
    return s->map[k][idx];
}

/* Position of the entry between (object a, c1, d1) and (object b, c2, d2), a < b, through
 * coupling block cp. */
static int coupling_position(const sem_system *s, int cp, int c1, int d1, int c2, int d2)
{
    const sem_system_coupling *k = &s->couplings[cp];
    const sem_object *oa = s->objects[k->a], *ob = s->objects[k->b];
    size_t nb = sem_group_size(ob, k->gb);
    return s->coupling_map[cp][((size_t)oa->ctrl_local[c1] * 9 + 3 * (size_t)d1 + (size_t)d2) * nb +
                               (size_t)ob->ctrl_local[c2]];
}

#define MAX_TERM_WEIGHTS 256
#define MAX_TERM_SETS 8

/* For a term with m sets: coupling[i * m + j] = the coupling block between sets i < j of
 * different objects. Returns 1 when every pair of sets of different objects has one (the
 * term goes in exactly), 0 otherwise. */
static int term_couplings(const sem_system *s, const sem_point_weight *wt, int count, const int *set, int m,
                          int *coupling)
{
    if (m > MAX_TERM_SETS) return 0;
    int first[MAX_TERM_SETS];
    for (int i = 0; i < m; ++i) first[i] = -1;
    for (int i = 0; i < count; ++i)
        if (set[i] >= 0 && first[set[i]] < 0) first[set[i]] = i;
    for (int i = 0; i < m; ++i)
        for (int j = 0; j < m; ++j) {
            coupling[i * m + j] = -1;
            if (i == j) continue;
            const sem_point_weight *a = &wt[first[i]], *b = &wt[first[j]];
            int ga = s->objects[a->object]->ctrl_group[a->ctrl], gb = s->objects[b->object]->ctrl_group[b->ctrl];
            if (a->object == b->object) {
                /* two groups of one object (self-contact): exact where the object's own
                 * pattern has their block */
                const sem_object *o = s->objects[a->object];
                int lo = ga < gb ? ga : gb, hi = ga < gb ? gb : ga;
                if (o->gpair_lookup[(size_t)lo * o->n_groups + hi] < 0) return 0;
                continue;
            }
            if (a->object > b->object) continue;
            coupling[i * m + j] = sem_system_find_coupling(s, a->object, ga, b->object, gb);
            if (coupling[i * m + j] < 0) return 0;
        }
    return 1;
}

/* Adds scale x the terms of t to the values. */
static void add_terms(sem_system *s, const sem_point_terms *t, double scale, double *val)
{
    int set[MAX_TERM_WEIGHTS], row[MAX_TERM_WEIGHTS], coupling[MAX_TERM_SETS * MAX_TERM_SETS];
    for (int n = 0; n < t->n; ++n) {
        const sem_point_term *term = &t->terms[n];
        const sem_point_weight *wt = t->weights + term->first;
        if (term->count > MAX_TERM_WEIGHTS) continue; /* contact's terms have <= 3 x 64 */
        int m = term_sets(s, term, wt, set);
        int exact = m <= 1 || term_couplings(s, wt, term->count, set, m, coupling);
        double c = scale * (exact ? 1 : m);
        for (int i = 0; i < term->count; ++i) {
            const sem_object *o = s->objects[wt[i].object];
            int f = o->free_index[wt[i].ctrl];
            row[i] = f < 0 ? -1 : 3 * (s->free_offset[wt[i].object] + f);
        }
        for (int i = 0; i < term->count; ++i) {
            if (row[i] < 0) continue;
            for (int j = 0; j < term->count; ++j) {
                if (row[j] < 0 || (set[j] != set[i] && !exact)) continue;
                double wij = c * wt[i].w * wt[j].w;
                for (int d1 = 0; d1 < 3; ++d1)
                    for (int d2 = 0; d2 < 3; ++d2) {
                        /* each ordered contribution once, into the upper triangle */
                        if (row[i] + d1 > row[j] + d2) continue;
                        int pos;
                        if (set[j] == set[i] || wt[i].object == wt[j].object)
                            pos = position(s, wt[i].object, wt[i].ctrl, d1, wt[j].ctrl, d2);
                        else /* i's object comes first: its rows are smaller */
                            pos = coupling_position(s, coupling[set[i] * m + set[j]], wt[i].ctrl, d1, wt[j].ctrl, d2);
                        if (pos >= 0) val[pos] += wij * term->H[3 * d1 + d2];
                    }
            }
        }
    }
}

void sem_system_set_point_terms(sem_system *s, const sem_point_terms *const *lists, const double *scale,
                                int n_lists)
{
    if (!s->solver) return;
    double *val = sem_system_values(s);
    for (int i = 0; i < s->n_couplings; ++i) {
        const sem_system_coupling *k = &s->couplings[i];
        size_t n = 9 * sem_group_size(s->objects[k->a], k->ga) * sem_group_size(s->objects[k->b], k->gb);
        for (size_t e = 0; e < n; ++e)
            if (s->coupling_map[i][e] >= 0) val[s->coupling_map[i][e]] = 0;
    }
    for (int l = 0; l < n_lists; ++l) add_terms(s, lists[l], scale[l], val);
}

void sem_point_terms_multiply(const sem_system *s, const sem_point_terms *t, double scale,
                              const double *x, double *y)
{
    int set[MAX_TERM_WEIGHTS], coupling[MAX_TERM_SETS * MAX_TERM_SETS];
    double Jx[3 * MAX_TERM_WEIGHTS];
    for (int n = 0; n < t->n; ++n) {
        const sem_point_term *term = &t->terms[n];
        const sem_point_weight *wt = t->weights + term->first;
        if (term->count > MAX_TERM_WEIGHTS) continue;
        int m = term_sets(s, term, wt, set);
        double c = scale * m;
        if (m > 1 && term_couplings(s, wt, term->count, set, m, coupling)) {
            /* in the matrix exactly: J^T H J with the whole J */
            for (int i = 0; i < term->count; ++i) set[i] = 0;
            m = 1;
            c = scale;
        }
        memset(Jx, 0, 3 * (size_t)m * sizeof(double));
        for (int i = 0; i < term->count; ++i) {
            const double *xi = x + s->dof_offset[wt[i].object] + 3 * (size_t)wt[i].ctrl;
            for (int d = 0; d < 3; ++d) Jx[3 * set[i] + d] += wt[i].w * xi[d];
        }
        for (int i = 0; i < term->count; ++i) {
            const double *v = Jx + 3 * set[i];
            double *yi = y + s->dof_offset[wt[i].object] + 3 * (size_t)wt[i].ctrl;
            double ci = c * wt[i].w;
            for (int d = 0; d < 3; ++d)
                yi[d] += ci * (term->H[3 * d] * v[0] + term->H[3 * d + 1] * v[1] + term->H[3 * d + 2] * v[2]);
        }
    }
}
