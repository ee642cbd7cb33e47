/*
 * contact_barrier.c - the barrier contact model: IPC's log barrier between the collision
 * surfaces, and the continuous collision check that bounds Newton's steps (contact.model
 * "barrier"; docs/simulation.md, "The barrier model").
 *
 * Pairs. The collision surfaces are the objects' collision meshes (collision_mesh.h, their
 * vertices linear in the control points), the colliders' triangle meshes and planes. Two
 * surfaces are kept apart by the barrier (contact/barrier.h) on the distances of
 *   - each collision point to the nearest triangle of every other object, of its own object
 *     beyond the self-contact exclusion rule, and of each collider mesh; to each plane;
 *   - each collider vertex to the nearest triangle of each object;
 *   - each edge to the nearest edge of every other object, of its own object beyond the
 *     exclusion rule, and of each collider mesh (mollified where they turn parallel).
 * One pair per primitive and surface (the nearest, as the penalty springs take it), so that a
 * point near an edge or vertex of a surface is not counted once per triangle there; the
 * energy is continuous, and its gradient is exact where the nearest feature is one.
 * Stiffness: kappa = stiffness per area (the penalty's: 1000 E / L by default) x the point's
 * rest area share (an edge: a third of its ends' mean share); reach dhat = the thickness
 * (1e-3 L by default) of the point's or edge's object.
 *
 * The collision check. Every Newton step (and the step's first iterate) moves the points
 * linearly from x0 = J q to x1 = J (q + dq). sem_contact_max_step finds the largest fraction
 * t <= 1 of it that no pair crosses: the trees of the objects' triangles and edges are
 * refitted to the swept boxes, every primitive's swept box is run against them, and each
 * candidate pair gets additive CCD (contact/ccd.h), which is conservative. The exclusion
 * rule of self-contact holds here too: parts of one object within 2 search radii of each
 * other at rest (a seam, the two sheets of a thin wall) are not checked against each
 * other. Results do not depend on the thread count: pairs are gathered in primitive order,
 * and the smallest t is the same in any order (ccd.h).
 */
#include "contact_internal.h"

#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "contact/barrier.h"
#include "contact/ccd.h"
#include "contact/collision_topology.h"
#include "contact/narrow_phase.h"
#include "geometry/vector3.h"
#include "util/grow.h"

#define EDGE_SHARE (1.0 / 3.0) /* an edge pair's stiffness: this x its ends' mean area share */
#define MOLLIFIER_EPS 1e-3     /* eps_x = this x |e0|^2 |e1|^2 at rest (barrier.h) */

sem_status sem_barrier_collider_edges(collider *k, sem_error *err)
{
    sem_status st = sem_collision_edges(k->triangles, k->n_triangles, NULL, &k->edge_tri, &k->n_edges, err);
    if (st == SEM_OK) st = sem_bvh_build(&k->edge_bvh, k->vertices, k->edge_tri, k->n_edges, err);
    if (st == SEM_OK && !(k->mark = calloc((size_t)k->n_vertices + 1, sizeof(int))))
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collider");
    return st;
}

/* How far a detection looks: the reach dhat, and margin x the search radius beyond it */
static double object_reach(const contact_object *co, double margin)
{
    return co->thickness + margin * (co->thickness + SEARCH_DEPTH * co->length);
}

static double exclusion_radius(const contact_object *co)
{
    return SELF_EXCLUSION * (co->thickness + SEARCH_DEPTH * co->length);
}

/* ---------------------------------------------------------------------------------- */
/* detection                                                                           */

/* A thread's pairs, in the order its primitives were visited. With schedule(static) the
 * threads take contiguous runs of primitives in thread order, so their lists one after the
 * other are the primitives' order on any thread count. */
typedef struct pair_list {
    barrier_pair *a;
    int n, cap, failed;
} pair_list;

static void list_push(pair_list *l, const barrier_pair *p)
{
    if (l->failed) return;
    if (!sem_grow((void **)&l->a, &l->cap, l->n + 1, sizeof *l->a, 64, INT_MAX)) {
        l->failed = 1;
        return;
    }
    l->a[l->n++] = *p;
}

/* What a primitive's tree visit needs: the primitive, the surface it is run against, and
 * the pair template (object, point, other object or collider, stiffness, reach, mu). */
typedef struct query {
    const sem_contact *c;
    pair_list *out;
    int edges;                 /* 0: a point against triangles; 1: an edge against edges */
    const double *a0, *a1;     /* the point (a0), or the edge's ends */
    int k, pa[2];              /* its system object (-1: a collider's vertex) and points */
    int other, collider;       /* the surface: a system object, or a collider (-1: none) */
    const double *x;           /* the surface's vertices */
    const int *items;          /* its triangles, or its edges as triangles (a, b, b) */
    const sem_collision_mesh *mesh; /* the surface's mesh (NULL: a collider) */
    const double *rest0, *rest1; /* self pairs: the primitive at rest (NULL: not self) */
    double radius2;            /* self pairs: the exclusion radius, squared */
    int skip_below;            /* edges of the same object: only those after this one */
    double reach2;
    double kappa, dhat, mu;
    const double *ra0, *ra1;   /* edges: the primitive at rest (the mollifier's eps_x) */
} query;

static void visit_point(int t, void *context)
{
    const query *q = context;
    const int *tri = q->items + 3 * (size_t)t;
    const double *x[3] = {q->x + 3 * (size_t)tri[0], q->x + 3 * (size_t)tri[1], q->x + 3 * (size_t)tri[2]};
    sem_tri_closest cl;
    if (sem_ccd_degenerate(x[0], x[1], x[2])) {
        /* a sliver (a pole's fan at rest, opening as its corners' control points part): the
         * distance to its nearest edge, so that the energy stays continuous as it opens */
        cl.dist2 = INFINITY;
        for (int e = 0; e < 3; ++e) {
            double s, u, d2 = sem_segment_closest(q->a0, q->a0, x[e], x[(e + 1) % 3], &s, &u);
            if (!(d2 < cl.dist2)) continue;
            cl.dist2 = d2;
            cl.bary[e] = 1 - u;
            cl.bary[(e + 1) % 3] = u;
            cl.bary[(e + 2) % 3] = 0;
            for (int k = 0; k < 3; ++k) cl.point[k] = x[e][k] + u * (x[(e + 1) % 3][k] - x[e][k]);
        }
    } else
        sem_point_triangle_closest(q->a0, x[0], x[1], x[2], &cl);
    if (!(cl.dist2 < q->reach2)) return;
    if (q->rest0) {
        const double *r = q->mesh->x0;
        double d = sem_ccd_triangle_distance(q->rest0, r + 3 * (size_t)tri[0], r + 3 * (size_t)tri[1], r + 3 * (size_t)tri[2]);
        if (!(d * d >= q->radius2)) return;
    }
    barrier_pair p;
    memset(&p, 0, sizeof p);
    p.nv = 4;
    p.object[0] = q->k;
    p.point[0] = q->pa[0];
    p.coef[0] = 1;
    for (int i = 0; i < 3; ++i) {
        p.object[1 + i] = q->other;
        p.point[1 + i] = tri[i];
        p.coef[1 + i] = -cl.bary[i];
    }
    p.collider = q->collider;
    p.mollifier = 1;
    double r[3] = {q->a0[0] - cl.point[0], q->a0[1] - cl.point[1], q->a0[2] - cl.point[2]};
    p.d = sqrt(cl.dist2);
    for (int k = 0; k < 3; ++k) p.n[k] = p.d > 0 ? r[k] / p.d : 0;
    p.kappa = q->kappa;
    if (q->k < 0 && q->mesh) {
        /* a collider's vertex against an object's triangle: the triangle's area shares */
        double area = 0;
        for (int i = 0; i < 3; ++i) area += cl.bary[i] * q->mesh->area[tri[i]];
        p.kappa *= area;
    }
    p.dhat = q->dhat;
    p.mu = q->mu;
    list_push(q->out, &p);
}

static void visit_edge(int e, void *context)
{
    const query *q = context;
    if (e <= q->skip_below) return;
    const int *eb = q->items + 3 * (size_t)e;
    const double *b0 = q->x + 3 * (size_t)eb[0], *b1 = q->x + 3 * (size_t)eb[1];
    double s, t;
    double d2 = sem_segment_closest(q->a0, q->a1, b0, b1, &s, &t);
    if (!(d2 < q->reach2)) return;
    const double *rb0 = q->mesh ? q->mesh->x0 + 3 * (size_t)eb[0] : b0;
    const double *rb1 = q->mesh ? q->mesh->x0 + 3 * (size_t)eb[1] : b1;
    if (q->rest0) {
        double rs, rt;
        if (!(sem_segment_closest(q->rest0, q->rest1, rb0, rb1, &rs, &rt) >= q->radius2)) return;
    }
    barrier_pair p;
    memset(&p, 0, sizeof p);
    p.nv = 4;
    p.edge = 1;
    p.object[0] = p.object[1] = q->k;
    p.point[0] = q->pa[0];
    p.point[1] = q->pa[1];
    p.object[2] = p.object[3] = q->other;
    p.point[2] = eb[0];
    p.point[3] = eb[1];
    p.coef[0] = 1 - s;
    p.coef[1] = s;
    p.coef[2] = -(1 - t);
    p.coef[3] = -t;
    p.collider = q->collider;
    double r[3];
    for (int k = 0; k < 3; ++k) r[k] = q->a0[k] + s * (q->a1[k] - q->a0[k]) - b0[k] - t * (b1[k] - b0[k]);
    p.d = sqrt(d2);
    for (int k = 0; k < 3; ++k) p.n[k] = p.d > 0 ? r[k] / p.d : 0;
    double la = 0, lb = 0;
    for (int k = 0; k < 3; ++k) {
        la += (q->ra1[k] - q->ra0[k]) * (q->ra1[k] - q->ra0[k]);
        lb += (rb1[k] - rb0[k]) * (rb1[k] - rb0[k]);
    }
    p.mollifier = sem_edge_mollifier(q->a0, q->a1, b0, b1, MOLLIFIER_EPS * la * lb, p.dm);
    p.kappa = q->kappa;
    p.dhat = q->dhat;
    p.mu = q->mu;
    list_push(q->out, &p);
}

/* Runs the query against a tree: every item within reach becomes a pair. */
static void run_query(query *q, const sem_bvh *tree, double reach)
{
    double lo[3], hi[3];
    const double *a1 = q->edges ? q->a1 : q->a0;
    for (int k = 0; k < 3; ++k) {
        lo[k] = fmin(q->a0[k], a1[k]) - reach;
        hi[k] = fmax(q->a0[k], a1[k]) + reach;
    }
    q->reach2 = reach * reach;
    sem_bvh_overlap(tree, lo, hi, q->edges ? visit_edge : visit_point, q);
}

/* The pairs of point p of system object k. */
static void point_pairs(const sem_contact *c, const sem_system *s, int k, int p, double margin, pair_list *out)
{
    const contact_object *co = &c->objects[c->sys_to_contact[k]];
    const sem_collision_mesh *m = &co->mesh;
    const double *x = m->x + 3 * (size_t)p;
    double dhat = co->thickness, reach = object_reach(co, margin);
    double own = sem_contact_stiffness(c, co->youngs, co->length) * m->area[p];
    for (int i = 0; i < c->n_colliders; ++i) {
        const collider *col = &c->colliders[i];
        double mu = sqrt(co->friction * col->friction);
        if (col->type == SEM_COLLIDER_PLANE) {
            double diff[3] = {x[0] - col->point[0], x[1] - col->point[1], x[2] - col->point[2]};
            double d = dot3(diff, col->normal);
            if (!(d < reach)) continue;
            barrier_pair r;
            memset(&r, 0, sizeof r);
            r.nv = 1;
            r.object[0] = k;
            r.point[0] = p;
            r.coef[0] = 1;
            r.collider = i;
            r.mollifier = 1;
            r.d = d;
            memcpy(r.n, col->normal, sizeof r.n);
            r.kappa = own;
            r.dhat = dhat;
            r.mu = mu;
            list_push(out, &r);
            continue;
        }
        query q = {c, out, 0, x, NULL, k, {p, -1}, -1, i, col->vertices, col->triangles, NULL, NULL, NULL, 0, -1, 0,
                   own, dhat, mu, NULL, NULL};
        run_query(&q, &col->bvh, reach);
    }
    for (int j = 0; j < s->n_objects; ++j) {
        int self = j == k;
        if (self && (!sem_contact_self_on(c) || co->self_far)) continue;
        const contact_object *cj = &c->objects[c->sys_to_contact[j]];
        double radius = exclusion_radius(co);
        query q = {c, out, 0, x, NULL, k, {p, -1}, j, -1, cj->mesh.x, cj->mesh.triangles, &cj->mesh,
                   self ? m->x0 + 3 * (size_t)p : NULL, NULL, radius * radius, -1, 0,
                   sem_contact_stiffness(c, fmin(co->youngs, cj->youngs), co->length) * m->area[p], dhat,
                   self ? co->friction : sqrt(co->friction * cj->friction), NULL, NULL};
        run_query(&q, &cj->mesh.bvh, reach);
    }
}

/* The pairs of edge e of system object k: against the colliders' edges, the edges of the
 * objects after it, and its own object's edges after it (each pair once). */
static void edge_pairs(const sem_contact *c, const sem_system *s, int k, int e, double margin, pair_list *out)
{
    const contact_object *co = &c->objects[c->sys_to_contact[k]];
    const sem_collision_mesh *m = &co->mesh;
    const int *ea = m->edge_tri + 3 * (size_t)e;
    const double *a0 = m->x + 3 * (size_t)ea[0], *a1 = m->x + 3 * (size_t)ea[1];
    const double *r0 = m->x0 + 3 * (size_t)ea[0], *r1 = m->x0 + 3 * (size_t)ea[1];
    double dhat = co->thickness, reach = object_reach(co, margin);
    double share = EDGE_SHARE * 0.5 * (m->area[ea[0]] + m->area[ea[1]]);
    for (int i = 0; i < c->n_colliders; ++i) {
        const collider *col = &c->colliders[i];
        if (col->type != SEM_COLLIDER_MESH) continue;
        query q = {c, out, 1, a0, a1, k, {ea[0], ea[1]}, -1, i, col->vertices, col->edge_tri, NULL, NULL, NULL, 0, -1,
                   0, sem_contact_stiffness(c, co->youngs, co->length) * share, dhat, sqrt(co->friction * col->friction), r0, r1};
        run_query(&q, &col->edge_bvh, reach);
    }
    for (int j = k; j < s->n_objects; ++j) {
        int self = j == k;
        if (self && (!sem_contact_self_on(c) || co->self_far)) continue;
        const contact_object *cj = &c->objects[c->sys_to_contact[j]];
        double radius = exclusion_radius(co);
        query q = {c, out, 1, a0, a1, k, {ea[0], ea[1]}, j, -1, cj->mesh.x, cj->mesh.edge_tri, &cj->mesh,
                   self ? r0 : NULL, self ? r1 : NULL, radius * radius, self ? e : -1, 0,
                   sem_contact_stiffness(c, fmin(co->youngs, cj->youngs), co->length) * share, dhat,
                   self ? co->friction : sqrt(co->friction * cj->friction), r0, r1};
        run_query(&q, &cj->mesh.edge_bvh, reach);
    }
}

/* The threads' lists into c->pairs, in thread order (see pair_list). */
static sem_status gather(sem_contact *c, pair_list *lists, int n_lists, sem_error *err)
{
    sem_status st = SEM_OK;
    for (int t = 0; t < n_lists; ++t) {
        pair_list *l = &lists[t];
        if (l->failed && st == SEM_OK) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
        for (int i = 0; i < l->n && st == SEM_OK; ++i) {
            if (!sem_grow((void **)&c->pairs, &c->cap_pairs, c->n_pairs + 1, sizeof *c->pairs, 256, INT_MAX)) {
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
                break;
            }
            c->pairs[c->n_pairs++] = l->a[i];
            if (l->a[i].d < c->min_gap) c->min_gap = l->a[i].d;
        }
        l->n = 0;
        l->failed = 0;
    }
    return st;
}

/* Vertices of collider col within the box [lo, hi], in index order, into c->candidates;
 * returns their count (-1: out of memory). */
typedef struct vertex_collect {
    collider *col;
    const double *lo, *hi;
    sem_contact *c;
    int n, failed;
} vertex_collect;

static void collect_vertices(int t, void *context)
{
    vertex_collect *v = context;
    const int *tri = v->col->triangles + 3 * (size_t)t;
    for (int i = 0; i < 3; ++i) {
        int id = tri[i];
        if (v->col->mark[id]) continue;
        const double *x = v->col->vertices + 3 * (size_t)id;
        int inside = 1;
        for (int k = 0; k < 3; ++k) inside &= x[k] >= v->lo[k] && x[k] <= v->hi[k];
        if (!inside) continue;
        v->col->mark[id] = 1;
        if (!sem_grow((void **)&v->c->candidates, &v->c->cap_candidates, v->n + 1, sizeof *v->c->candidates, 256,
                      INT_MAX)) {
            v->failed = 1;
            continue;
        }
        v->c->candidates[v->n++] = id;
    }
}

static int compare_int(const void *a, const void *b)
{
    int x = *(const int *)a, y = *(const int *)b;
    return (x > y) - (x < y);
}

static int near_vertices(sem_contact *c, collider *col, const double lo[3], const double hi[3])
{
    vertex_collect v = {col, lo, hi, c, 0, 0};
    sem_bvh_overlap(&col->bvh, lo, hi, collect_vertices, &v);
    for (int i = 0; i < v.n; ++i) col->mark[c->candidates[i]] = 0;
    if (v.failed) return -1;
    qsort(c->candidates, (size_t)v.n, sizeof *c->candidates, compare_int);
    return v.n;
}

void sem_barrier_free_lists(sem_contact *c)
{
    for (int t = 0; t < c->n_lists; ++t) free(c->lists[t].a);
    free(c->lists);
    c->lists = NULL;
    c->n_lists = 0;
}

/* The threads' pair lists (kept between detections) */
static pair_list *thread_lists(sem_contact *c, int n)
{
    if (c->n_lists < n) {
        pair_list *l = realloc(c->lists, (size_t)n * sizeof *l);
        if (!l) return NULL;
        memset(l + c->n_lists, 0, (size_t)(n - c->n_lists) * sizeof *l);
        c->lists = l;
        c->n_lists = n;
    }
    return c->lists;
}

sem_status sem_barrier_detect(sem_contact *c, const sem_system *s, const double *q, double margin, sem_error *err)
{
    sem_status st = sem_contact_map_system(c, s, err);
    if (st != SEM_OK) return st;
    c->n_pairs = 0;
    c->min_gap = INFINITY;
    if (c->def.disabled) return SEM_OK;
    for (int k = 0; k < s->n_objects; ++k) {
        contact_object *co = &c->objects[c->sys_to_contact[k]];
        sem_collision_mesh_update(&co->mesh, q + s->dof_offset[k], 1);
        sem_bvh_refit(&co->mesh.edge_bvh, co->mesh.x, co->mesh.edge_tri);
        co->self_far = sem_contact_self_on(c) &&
                       sem_contact_self_far_apart(&co->mesh, co->thickness + SEARCH_DEPTH * co->length);
    }
    int nthreads = s->n_objects > 0 ? s->objects[0]->nthreads : 1;
    if (nthreads < 1) nthreads = 1;
    pair_list *lists = thread_lists(c, nthreads);
    if (!lists) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
    for (int k = 0; k < s->n_objects && st == SEM_OK; ++k) {
        contact_object *co = &c->objects[c->sys_to_contact[k]];
        const sem_collision_mesh *m = &co->mesh;
        /* points against colliders and triangles; edges against edges */
#pragma omp parallel num_threads(nthreads)
        {
            pair_list *mine = &lists[omp_get_thread_num()];
#pragma omp for schedule(static)
            for (int p = 0; p < m->n_points; ++p)
                if (m->area[p] > 0) point_pairs(c, s, k, p, margin, mine);
        }
        if ((st = gather(c, lists, nthreads, err)) != SEM_OK) break;
#pragma omp parallel num_threads(nthreads)
        {
            pair_list *mine = &lists[omp_get_thread_num()];
#pragma omp for schedule(static)
            for (int e = 0; e < m->n_edges; ++e) edge_pairs(c, s, k, e, margin, mine);
        }
        if ((st = gather(c, lists, nthreads, err)) != SEM_OK) break;
        /* collider vertices against the object's triangles */
        double reach = object_reach(co, margin);
        for (int i = 0; i < c->n_colliders && st == SEM_OK; ++i) {
            collider *col = &c->colliders[i];
            if (col->type != SEM_COLLIDER_MESH) continue;
            double lo[3], hi[3];
            sem_collision_mesh_box(m, NULL, reach, lo, hi);
            int nv = near_vertices(c, col, lo, hi);
            if (nv < 0) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
            double kappa = sem_contact_stiffness(c, co->youngs, co->length), mu = sqrt(co->friction * col->friction);
#pragma omp parallel num_threads(nthreads)
            {
                pair_list *mine = &lists[omp_get_thread_num()];
#pragma omp for schedule(static)
                for (int a = 0; a < nv; ++a) {
                    int v = c->candidates[a];
                    query qv = {c, mine, 0, col->vertices + 3 * (size_t)v, NULL, -1, {v, -1}, k, i, m->x, m->triangles,
                                m, NULL, NULL, 0, -1, 0, kappa, co->thickness, mu, NULL, NULL};
                    run_query(&qv, &m->bvh, reach);
                }
            }
            st = gather(c, lists, nthreads, err);
        }
    }
    return st;
}

/* ---------------------------------------------------------------------------------- */
/* energy                                                                              */

int sem_barrier_weights(const sem_contact *c, const barrier_pair *p, sem_point_weight *w)
{
    int n = 0;
    for (int i = 0; i < p->nv; ++i) {
        if (p->object[i] < 0 || p->coef[i] == 0) continue;
        const sem_collision_mesh *m = &c->objects[c->sys_to_contact[p->object[i]]].mesh;
        for (int e = m->row_start[p->point[i]]; e < m->row_start[p->point[i] + 1] && n < MAX_WEIGHTS; ++e)
            w[n++] = (sem_point_weight){p->object[i], m->row_ctrl[e], p->coef[i] * m->row_w[e]};
    }
    return n;
}

sem_status sem_barrier_energy(sem_contact *c, const sem_system *s, double *grad, sem_point_terms *terms,
                              double *energy, sem_error *err)
{
    sem_point_weight w[MAX_WEIGHTS];
    double E = 0;
    for (int i = 0; i < c->n_pairs; ++i) {
        const barrier_pair *p = &c->pairs[i];
        double db, d2b;
        double b = sem_barrier(p->d, p->dhat, &db, &d2b);
        if (b == 0 && db == 0) continue;
        E += p->kappa * p->mollifier * b;
        if (!grad || !isfinite(b)) continue;
        int n = sem_barrier_weights(c, p, w);
        double slope = p->kappa * p->mollifier * db, f[3] = {slope * p->n[0], slope * p->n[1], slope * p->n[2]};
        sem_contact_add_gradient(s, w, n, f, grad);
        if (p->mollifier < 1)
            for (int v = 0; v < p->nv; ++v) {
                if (p->object[v] < 0) continue;
                const sem_collision_mesh *m = &c->objects[c->sys_to_contact[p->object[v]]].mesh;
                double g[3] = {p->kappa * b * p->dm[v][0], p->kappa * b * p->dm[v][1], p->kappa * b * p->dm[v][2]};
                for (int e = m->row_start[p->point[v]]; e < m->row_start[p->point[v] + 1]; ++e) {
                    double *gq = grad + s->dof_offset[p->object[v]] + 3 * (size_t)m->row_ctrl[e];
                    for (int k = 0; k < 3; ++k) gq[k] += m->row_w[e] * g[k];
                }
            }
        double H[9], curv = p->kappa * p->mollifier * d2b;
        for (int a = 0; a < 3; ++a)
            for (int b2 = 0; b2 < 3; ++b2) H[3 * a + b2] = curv * p->n[a] * p->n[b2];
        sem_status st = sem_point_terms_push(terms, w, n, H, err);
        if (st != SEM_OK) return st;
    }
    *energy = E;
    return SEM_OK;
}

/* ---------------------------------------------------------------------------------- */
/* the collision check                                                                 */

/* A swept primitive against the triangles or edges of a swept tree: the visit of
 * sem_bvh_overlap, lowering t. */
typedef struct sweep {
    int edges;                  /* 0: a point against triangles; 1: an edge against edges */
    const double *x0[2], *x1[2]; /* the primitive's vertices at both ends */
    const double *tx0, *tx1;    /* the tree's vertices at both ends (tx1 NULL: static) */
    const int *items;           /* the tree's triangles or edge triangles */
    const sem_collision_mesh *mesh; /* the tree's mesh (NULL: a collider): its rest positions */
    const double *rest[2];      /* self pairs: the primitive at rest, and the rule's radius */
    double radius2;
    int skip_below;             /* edges: those with index <= this are left out; -1 */
    double t;
} sweep;

static void visit_sweep(int item, void *context)
{
    sweep *w = context;
    if (w->edges && item <= w->skip_below) return;
    const int *v = w->items + 3 * (size_t)item;
    if (w->rest[0]) {
        const double *r = w->mesh->x0;
        if (w->edges) {
            double s, t;
            if (!(sem_segment_closest(w->rest[0], w->rest[1], r + 3 * (size_t)v[0], r + 3 * (size_t)v[1], &s, &t) >=
                  w->radius2))
                return;
        } else {
            double d = sem_ccd_triangle_distance(w->rest[0], r + 3 * (size_t)v[0], r + 3 * (size_t)v[1], r + 3 * (size_t)v[2]);
            if (!(d * d >= w->radius2)) return;
        }
    }
    double p[4][3], zero[3] = {0, 0, 0};
    const double *x[4], *dp[4];
    int np = w->edges ? 2 : 1, nt = w->edges ? 2 : 3;
    for (int i = 0; i < np; ++i) {
        x[i] = w->x0[i];
        for (int k = 0; k < 3; ++k) p[i][k] = w->x1[i][k] - w->x0[i][k];
        dp[i] = p[i];
    }
    for (int i = 0; i < nt; ++i) {
        const double *a = w->tx0 + 3 * (size_t)v[i];
        x[np + i] = a;
        if (w->tx1) {
            const double *b = w->tx1 + 3 * (size_t)v[i];
            for (int k = 0; k < 3; ++k) p[np + i][k] = b[k] - a[k];
            dp[np + i] = p[np + i];
        } else
            dp[np + i] = zero;
    }
    double t = w->edges ? sem_ccd_edge_edge(x, dp, w->t) : sem_ccd_point_triangle(x, dp, w->t);
    if (t < w->t) w->t = t;
}

static void sweep_box(const sweep *w, double lo[3], double hi[3])
{
    int np = w->edges ? 2 : 1;
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
        for (int i = 0; i < np; ++i) {
            lo[k] = fmin(lo[k], fmin(w->x0[i][k], w->x1[i][k]));
            hi[k] = fmax(hi[k], fmax(w->x0[i][k], w->x1[i][k]));
        }
    }
}

/* The largest t <= t_max that point p of system object k reaches without touching. */
static double point_step(const sem_contact *c, const sem_system *s, int k, int p, double t_max)
{
    const contact_object *co = &c->objects[c->sys_to_contact[k]];
    const sem_collision_mesh *m = &co->mesh;
    const double *x0 = m->x + 3 * (size_t)p, *x1 = co->x1 + 3 * (size_t)p;
    sweep w = {0, {x0, NULL}, {x1, NULL}, NULL, NULL, NULL, NULL, {NULL, NULL}, 0, -1, t_max};
    double lo[3], hi[3];
    sweep_box(&w, lo, hi);
    for (int i = 0; i < c->n_colliders; ++i) {
        const collider *col = &c->colliders[i];
        if (col->type == SEM_COLLIDER_PLANE) {
            double diff[3] = {x0[0] - col->point[0], x0[1] - col->point[1], x0[2] - col->point[2]};
            double move[3] = {x1[0] - x0[0], x1[1] - x0[1], x1[2] - x0[2]};
            w.t = sem_ccd_point_plane(dot3(diff, col->normal), dot3(move, col->normal), w.t);
            continue;
        }
        w.tx0 = col->vertices;
        w.tx1 = NULL;
        w.items = col->triangles;
        w.mesh = NULL;
        w.rest[0] = NULL;
        sem_bvh_overlap(&col->bvh, lo, hi, visit_sweep, &w);
    }
    for (int j = 0; j < s->n_objects; ++j) {
        if (j == k && (!sem_contact_self_on(c) || co->sweep_far)) continue;
        const contact_object *cj = &c->objects[c->sys_to_contact[j]];
        w.tx0 = cj->mesh.x;
        w.tx1 = cj->x1;
        w.items = cj->mesh.triangles;
        w.mesh = &cj->mesh;
        w.rest[0] = j == k ? m->x0 + 3 * (size_t)p : NULL;
        double radius = exclusion_radius(co);
        w.radius2 = radius * radius;
        sem_bvh_overlap(&cj->mesh.bvh, lo, hi, visit_sweep, &w);
    }
    return w.t;
}

/* The same for edge e of system object k (against the edges of the objects after it, its
 * own after it, and the colliders'). */
static double edge_step(const sem_contact *c, const sem_system *s, int k, int e, double t_max)
{
    const contact_object *co = &c->objects[c->sys_to_contact[k]];
    const sem_collision_mesh *m = &co->mesh;
    const int *ea = m->edge_tri + 3 * (size_t)e;
    sweep w = {1,
               {m->x + 3 * (size_t)ea[0], m->x + 3 * (size_t)ea[1]},
               {co->x1 + 3 * (size_t)ea[0], co->x1 + 3 * (size_t)ea[1]},
               NULL, NULL, NULL, NULL, {NULL, NULL}, 0, -1, t_max};
    double lo[3], hi[3];
    sweep_box(&w, lo, hi);
    for (int i = 0; i < c->n_colliders; ++i) {
        const collider *col = &c->colliders[i];
        if (col->type != SEM_COLLIDER_MESH) continue;
        w.tx0 = col->vertices;
        w.tx1 = NULL;
        w.items = col->edge_tri;
        w.mesh = NULL;
        w.rest[0] = w.rest[1] = NULL;
        w.skip_below = -1;
        sem_bvh_overlap(&col->edge_bvh, lo, hi, visit_sweep, &w);
    }
    for (int j = k; j < s->n_objects; ++j) {
        int self = j == k;
        if (self && (!sem_contact_self_on(c) || co->sweep_far)) continue;
        const contact_object *cj = &c->objects[c->sys_to_contact[j]];
        w.tx0 = cj->mesh.x;
        w.tx1 = cj->x1;
        w.items = cj->mesh.edge_tri;
        w.mesh = &cj->mesh;
        w.rest[0] = self ? m->x0 + 3 * (size_t)ea[0] : NULL;
        w.rest[1] = self ? m->x0 + 3 * (size_t)ea[1] : NULL;
        double radius = exclusion_radius(co);
        w.radius2 = radius * radius;
        w.skip_below = self ? e : -1;
        sem_bvh_overlap(&cj->mesh.edge_bvh, lo, hi, visit_sweep, &w);
    }
    return w.t;
}

/* Can no point of the object meet its own surface beyond the exclusion rule on the way from
 * x to x1? Yes when at both ends it is near a rigid motion of its rest shape (self_far_apart:
 * x = c + R r + e, |e| < 0.495 radius, radius the search radius) and the two rotations differ
 * by less than 90 degrees: on the way x(t) = c(t) + ((1 - t) R0 + t R1) r + e(t), where
 * (1 - t) I + t R0^T R1 shrinks no vector below cos(45 deg) = 0.71 of its length and |e(t)| <
 * 0.495 radius, so points (and triangles) at least 2 radii apart at rest stay more than
 * 2 (0.71 - 0.495) radius apart. A falling or tumbling object then skips the self part of
 * the check. */
static int sweep_far_apart(const contact_object *co)
{
    double R0[9], R1[9], radius = co->thickness + SEARCH_DEPTH * co->length;
    if (!sem_contact_self_far_apart_at(&co->mesh, co->mesh.x, radius, R0) ||
        !sem_contact_self_far_apart_at(&co->mesh, co->x1, radius, R1))
        return 0;
    double trace = 0; /* tr(R0^T R1) = 1 + 2 cos(angle) */
    for (int i = 0; i < 9; ++i) trace += R0[i] * R1[i];
    return trace >= 1.0;
}

sem_status sem_contact_max_step(sem_contact *c, const sem_system *s, const double *q, const double *dq, double scale,
                                double *t_out, sem_error *err)
{
    *t_out = 1;
    if (!sem_contact_barrier(c)) return SEM_OK;
    double t0 = omp_get_wtime();
    sem_status st = sem_contact_map_system(c, s, err);
    if (st != SEM_OK) return st;
    double *q1 = malloc(s->n_dofs * sizeof(double) + 1);
    if (!q1) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (size_t i = 0; i < s->n_dofs; ++i) q1[i] = q[i] + scale * dq[i];
    for (int k = 0; k < s->n_objects && st == SEM_OK; ++k) {
        contact_object *co = &c->objects[c->sys_to_contact[k]];
        sem_collision_mesh *m = &co->mesh;
        if (!co->x1 && !(co->x1 = malloc(3 * (size_t)m->n_points * sizeof(double) + 1)))
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        if (st != SEM_OK) break;
        sem_collision_mesh_update(m, q + s->dof_offset[k], 0);
        sem_collision_mesh_positions(m, q1 + s->dof_offset[k], co->x1);
        sem_bvh_refit_swept(&m->bvh, m->x, co->x1, m->triangles);
        sem_bvh_refit_swept(&m->edge_bvh, m->x, co->x1, m->edge_tri);
        co->sweep_far = sem_contact_self_on(c) && sweep_far_apart(co);
    }
    free(q1);
    if (st != SEM_OK) return st;
    int nthreads = s->n_objects > 0 ? s->objects[0]->nthreads : 1;
    double t = 1;
    for (int k = 0; k < s->n_objects; ++k) {
        contact_object *co = &c->objects[c->sys_to_contact[k]];
        const sem_collision_mesh *m = &co->mesh;
        double tk = t;
#pragma omp parallel for schedule(dynamic, 64) reduction(min : tk) num_threads(nthreads)
        for (int p = 0; p < m->n_points; ++p) tk = fmin(tk, point_step(c, s, k, p, t));
        t = fmin(t, tk);
        tk = t;
#pragma omp parallel for schedule(dynamic, 64) reduction(min : tk) num_threads(nthreads)
        for (int e = 0; e < m->n_edges; ++e) tk = fmin(tk, edge_step(c, s, k, e, t));
        t = fmin(t, tk);
        /* collider vertices against the object's swept triangles */
        for (int i = 0; i < c->n_colliders; ++i) {
            collider *col = &c->colliders[i];
            if (col->type != SEM_COLLIDER_MESH) continue;
            double lo[3], hi[3];
            sem_collision_mesh_box(m, co->x1, 0, lo, hi);
            int nv = near_vertices(c, col, lo, hi);
            if (nv < 0) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
            tk = t;
#pragma omp parallel for schedule(dynamic, 64) reduction(min : tk) num_threads(nthreads)
            for (int a = 0; a < nv; ++a) {
                const double *x = col->vertices + 3 * (size_t)c->candidates[a];
                /* the triangles move; the vertex does not: the triangle's motion seen from
                 * the vertex is the same check with the roles kept (ccd.h takes any motion) */
                sweep w = {0, {x, NULL}, {x, NULL}, m->x, co->x1, m->triangles, m, {NULL, NULL}, 0, -1, t};
                double vlo[3], vhi[3];
                sweep_box(&w, vlo, vhi);
                sem_bvh_overlap(&m->bvh, vlo, vhi, visit_sweep, &w);
                tk = fmin(tk, w.t);
            }
            t = fmin(t, tk);
        }
    }
    *t_out = t;
    c->stats.seconds += omp_get_wtime() - t0;
    return SEM_OK;
}
