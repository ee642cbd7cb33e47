/*
 * contact_world.c - colliders, detection, and the contact potential of a world's system
 * (see contact_world.h; the springs in penalty.c, friction in friction.c).
 */
#include "contact_internal.h"

#include <limits.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "contact/barrier.h"
#include "contact/collision_mesh.h"
#include "contact/collision_topology.h"
#include "contact/friction.h"
#include "contact/penalty.h"
#include "geometry/vector3.h"
#include "util/free_all.h"
#include "util/grow.h"
#include "util/union_find.h"

/* ---------------------------------------------------------------------------------- */
/* life cycle                                                                          */

sem_status sem_contact_create(const sem_contact_def *def, sem_contact **out, sem_error *err)
{
    *out = NULL;
    if (!isfinite(def->stiffness) || !isfinite(def->thickness) || !isfinite(def->friction_velocity))
        return sem_error_set(err, SEM_ERR_INVALID, "contact settings must be finite");
    if (def->self < -1 || def->self > 1)
        return sem_error_set(err, SEM_ERR_INVALID, "contact: self must be -1 (off), 0 (the default: on) or 1 (got %d)",
                             def->self);
    if (def->model != SEM_CONTACT_PENALTY && def->model != SEM_CONTACT_BARRIER)
        return sem_error_set(err, SEM_ERR_INVALID, "contact: unknown model %d", (int)def->model);
    if (def->resolution > 64)
        return sem_error_set(err, SEM_ERR_INVALID, "contact resolution must be at most 64 (got %d)", def->resolution);
    sem_contact *c = calloc(1, sizeof *c);
    if (!c) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    c->def = *def;
    if (!(c->def.friction_velocity > 0)) c->def.friction_velocity = DEFAULT_FRICTION_VELOCITY;
    c->stats.min_gap = INFINITY;
    sem_point_terms_init(&c->terms);
    sem_point_terms_init(&c->friction_terms);
    *out = c;
    return SEM_OK;
}

static void collider_free(collider *k)
{
    SEM_FREE_ALL(k->vertices, k->triangles, k->face_normal, k->edge_normal, k->vertex_normal, k->edge_tri, k->mark);
    sem_bvh_free(&k->bvh);
    sem_bvh_free(&k->edge_bvh);
}

void sem_contact_destroy(sem_contact *c)
{
    if (!c) return;
    for (int i = 0; i < c->n_colliders; ++i) collider_free(&c->colliders[i]);
    for (int i = 0; i < c->n_objects; ++i) {
        sem_collision_mesh_free(&c->objects[i].mesh);
        free(c->objects[i].x1);
    }
    SEM_FREE_ALL(c->colliders, c->objects, c->recs, c->slots, c->slot_count, c->sys_to_contact, c->friction,
                 c->fweights, c->couplings, c->pairs, c->candidates);
    sem_barrier_free_lists(c);
    sem_point_terms_free(&c->terms);
    sem_point_terms_free(&c->friction_terms);
    free(c);
}

static void normalize3(double a[3])
{
    double l = sqrt(dot3(a, a));
    if (l > 0)
        for (int k = 0; k < 3; ++k) a[k] /= l;
}

/* Face, edge and vertex pseudonormals of a collider mesh: the sign of the distance to a
 * closed (or terrain-like) mesh is that of (p - c) . pseudonormal at the closest feature. */
static sem_status mesh_normals(collider *k, sem_error *err)
{
    size_t nt = (size_t)k->n_triangles;
    k->face_normal = calloc(3 * nt + 1, sizeof(double));
    k->edge_normal = calloc(9 * nt + 1, sizeof(double));
    k->vertex_normal = calloc(3 * (size_t)k->n_vertices + 1, sizeof(double));
    sem_edge_slot *edges = malloc((3 * nt + 1) * sizeof *edges);
    if (!k->face_normal || !k->edge_normal || !k->vertex_normal || !edges) {
        free(edges);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collider");
    }
    for (size_t t = 0; t < nt; ++t) {
        const int *tri = k->triangles + 3 * t;
        double *n = k->face_normal + 3 * t;
        const double *x[3] = {k->vertices + 3 * (size_t)tri[0], k->vertices + 3 * (size_t)tri[1],
                              k->vertices + 3 * (size_t)tri[2]};
        double e1[3], e2[3];
        for (int d = 0; d < 3; ++d) {
            e1[d] = x[1][d] - x[0][d];
            e2[d] = x[2][d] - x[0][d];
        }
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        normalize3(n);
        for (int v = 0; v < 3; ++v) {
            /* the triangle's angle at vertex v */
            double a[3], b[3];
            for (int d = 0; d < 3; ++d) {
                a[d] = x[(v + 1) % 3][d] - x[v][d];
                b[d] = x[(v + 2) % 3][d] - x[v][d];
            }
            normalize3(a);
            normalize3(b);
            double cosang = dot3(a, b);
            double angle = acos(cosang < -1 ? -1 : cosang > 1 ? 1 : cosang);
            for (int d = 0; d < 3; ++d) k->vertex_normal[3 * (size_t)tri[v] + d] += angle * n[d];
            int p = tri[v], q = tri[(v + 1) % 3];
            edges[3 * t + (size_t)v] = (sem_edge_slot){p < q ? p : q, p < q ? q : p, (int)(3 * t) + v};
        }
    }
    qsort(edges, 3 * nt, sizeof *edges, sem_compare_edge_slot);
    for (size_t i = 0; i < 3 * nt;) {
        size_t j = i;
        double sum[3] = {0, 0, 0};
        while (j < 3 * nt && edges[j].a == edges[i].a && edges[j].b == edges[i].b) {
            const double *n = k->face_normal + 3 * (size_t)(edges[j].slot / 3);
            for (int d = 0; d < 3; ++d) sum[d] += n[d];
            ++j;
        }
        normalize3(sum);
        for (size_t e = i; e < j; ++e) memcpy(k->edge_normal + 3 * (size_t)edges[e].slot, sum, sizeof sum);
        i = j;
    }
    for (int v = 0; v < k->n_vertices; ++v) normalize3(k->vertex_normal + 3 * (size_t)v);
    free(edges);
    return SEM_OK;
}

static int def_is_barrier(const sem_contact *c) { return c->def.model == SEM_CONTACT_BARRIER; }

sem_status sem_contact_add_collider(sem_contact *c, const sem_collider_def *def, sem_error *err)
{
    if (!(def->friction >= 0) || !isfinite(def->friction))
        return sem_error_set(err, SEM_ERR_INVALID, "collider friction must be >= 0 (got %g)", def->friction);
    collider k;
    memset(&k, 0, sizeof k);
    k.type = def->type;
    k.friction = def->friction;
    if (def->type == SEM_COLLIDER_PLANE) {
        memcpy(k.point, def->point, sizeof k.point);
        memcpy(k.normal, def->normal, sizeof k.normal);
        double l = sqrt(dot3(k.normal, k.normal));
        if (!(l > 0) || !isfinite(l)) return sem_error_set(err, SEM_ERR_INVALID, "plane normal must be non-zero");
        for (int d = 0; d < 3; ++d) {
            k.normal[d] /= l;
            if (!isfinite(k.point[d])) return sem_error_set(err, SEM_ERR_INVALID, "plane point must be finite");
        }
    } else if (def->type == SEM_COLLIDER_MESH) {
        if (def->n_triangles <= 0 || def->n_vertices <= 0 || !def->vertices || !def->triangles)
            return sem_error_set(err, SEM_ERR_INVALID, "collider mesh has no triangle");
        for (int t = 0; t < 3 * def->n_triangles; ++t)
            if (def->triangles[t] < 0 || def->triangles[t] >= def->n_vertices)
                return sem_error_set(err, SEM_ERR_INVALID, "collider mesh triangle %d has a vertex index out of range",
                                     t / 3);
        for (int v = 0; v < 3 * def->n_vertices; ++v)
            if (!isfinite(def->vertices[v]))
                return sem_error_set(err, SEM_ERR_INVALID, "collider mesh vertex %d is not finite", v / 3);
        k.n_vertices = def->n_vertices;
        k.n_triangles = def->n_triangles;
        k.vertices = malloc(3 * (size_t)k.n_vertices * sizeof(double));
        k.triangles = malloc(3 * (size_t)k.n_triangles * sizeof(int));
        if (!k.vertices || !k.triangles) {
            collider_free(&k);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collider");
        }
        memcpy(k.vertices, def->vertices, 3 * (size_t)k.n_vertices * sizeof(double));
        memcpy(k.triangles, def->triangles, 3 * (size_t)k.n_triangles * sizeof(int));
        sem_status st = mesh_normals(&k, err);
        if (st == SEM_OK) st = sem_bvh_build(&k.bvh, k.vertices, k.triangles, k.n_triangles, err);
        if (st == SEM_OK && def_is_barrier(c)) st = sem_barrier_collider_edges(&k, err);
        if (st != SEM_OK) {
            collider_free(&k);
            return st;
        }
    } else
        return sem_error_set(err, SEM_ERR_INVALID, "unknown collider type %d", (int)def->type);
    if (!sem_grow((void **)&c->colliders, &c->cap_colliders, c->n_colliders + 1, sizeof *c->colliders, 4, INT_MAX)) {
        collider_free(&k);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    c->colliders[c->n_colliders++] = k;
    c->stats.colliders = c->n_colliders;
    return SEM_OK;
}

sem_status sem_contact_add_object(sem_contact *c, const sem_object *o, sem_error *err)
{
    if (!sem_grow((void **)&c->objects, &c->cap_objects, c->n_objects + 1, sizeof *c->objects, 4, INT_MAX))
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    contact_object *co = &c->objects[c->n_objects];
    memset(co, 0, sizeof *co);
    co->object = o;
    c->n_objects++;
    return SEM_OK; /* its mesh is built when contact first needs it (mesh_for) */
}

double sem_contact_stiffness(const sem_contact *c, double youngs, double length)
{
    return c->def.stiffness > 0 ? c->def.stiffness : KAPPA * youngs / length;
}

/* The collision mesh of contact object i, built on first use: a world with one object and
 * no collider never pays for it. */
static sem_status mesh_for(sem_contact *c, int i, sem_error *err)
{
    contact_object *co = &c->objects[i];
    if (co->built) return SEM_OK;
    const sem_object *o = co->object;
    sem_status st = sem_collision_mesh_build(o->def.model, c->def.resolution, &co->mesh, err);
    if (st != SEM_OK) return st;
    co->youngs = o->def.material.youngs_modulus;
    co->friction = o->def.friction;
    co->length = co->mesh.length > 0 ? co->mesh.length : 1.0;
    co->thickness = c->def.thickness > 0 ? c->def.thickness : DEFAULT_THICKNESS * co->length;
    co->built = 1;
    return SEM_OK;
}

void sem_contact_remove_last_object(sem_contact *c)
{
    if (c->n_objects > 0) sem_collision_mesh_free(&c->objects[--c->n_objects].mesh);
}

int sem_contact_between_objects(const sem_contact *c) { return !c->def.disabled && c->n_objects >= 2; }

int sem_contact_barrier(const sem_contact *c) { return def_is_barrier(c) && sem_contact_active(c); }

int sem_contact_active(const sem_contact *c)
{
    return !c->def.disabled && (c->n_colliders > 0 || c->n_objects >= 2 || (c->def.self > 0 && c->n_objects > 0));
}

const sem_point_terms *sem_contact_terms(const sem_contact *c) { return &c->terms; }

void sem_contact_get_stats(const sem_contact *c, sem_contact_stats *out) { *out = c->stats; }

/* ---------------------------------------------------------------------------------- */
/* detection                                                                           */

/* Self-contact on (sem_contact_def.self: 0 the default, on; -1 off). */
int sem_contact_self_on(const sem_contact *c) { return !c->def.disabled && c->def.self >= 0; }

/* Is triangle t of the mesh collapsed (two corners one welded point: at a sphere's pole, a
 * cone's tip)? Its copies share one row (collision_mesh.c), so it stays a segment with no
 * normal to sign a distance by; its neighbours, which share that segment, stand in. */
static int collapsed(const sem_collision_mesh *m, int t)
{
    const int *v = m->triangles + 3 * (size_t)t;
    int a = m->weld[v[0]], b = m->weld[v[1]], c = m->weld[v[2]];
    return a == b || b == c || a == c;
}

static int collapsed_excluded(int t, void *context) { return collapsed(context, t); }

/* Self-contact's exclusion rule (SELF_EXCLUSION): is triangle t of the mesh within the
 * excluded rest distance of the point? */
typedef struct self_exclusion {
    const sem_collision_mesh *mesh;
    const double *point;   /* the point's rest position */
    double radius2;
} self_exclusion;

static int self_excluded(int t, void *context)
{
    const self_exclusion *e = context;
    if (collapsed(e->mesh, t)) return 1;
    const int *v = e->mesh->triangles + 3 * (size_t)t;
    const double *x0 = e->mesh->x0;
    sem_tri_closest cl;
    sem_point_triangle_closest(e->point, x0 + 3 * (size_t)v[0], x0 + 3 * (size_t)v[1], x0 + 3 * (size_t)v[2], &cl);
    return !(cl.dist2 >= e->radius2); /* a degenerate triangle (NaN distance) is left out too */
}

/* 3 x 3 determinant, row-major */
static double det3(const double *a)
{
    return a[0] * (a[4] * a[8] - a[5] * a[7]) - a[1] * (a[3] * a[8] - a[5] * a[6]) + a[2] * (a[3] * a[7] - a[4] * a[6]);
}

/* Is the mesh so close to a rigid motion of its rest shape that no point can be within the
 * search radius of a triangle the exclusion rule leaves it? With x_p = c + R (x0_p - c0) +
 * e_p for a rotation R and |e_p| <= D at every point (so at every point of a triangle), two
 * points at rest distance >= SELF_EXCLUSION x radius are now >= that - 2 D apart: beyond the
 * radius when 2 D < (SELF_EXCLUSION - 1) radius (with a 1 % margin for rounding). R is the
 * polar factor of the points' cross-covariance (Higham's iteration), made orthonormal; any
 * rotation makes the bound true, a good one makes it tight. A falling or tumbling object that
 * hardly deforms then pays O(n) per detection for self-contact instead of a tree query per
 * point. 0 when the test cannot tell (a flat or degenerate mesh): the queries run. */
int sem_contact_self_far_apart(const sem_collision_mesh *m, double radius)
{
    return sem_contact_self_far_apart_at(m, m->x, radius, NULL);
}

int sem_contact_self_far_apart_at(const sem_collision_mesh *m, const double *xs, double radius, double rotation[9])
{
    int n = m->n_points;
    if (n <= 0) return 1;
    double c[3] = {0, 0, 0}, c0[3] = {0, 0, 0}, A[9] = {0};
    for (int p = 0; p < n; ++p)
        for (int a = 0; a < 3; ++a) {
            c[a] += xs[3 * (size_t)p + a];
            c0[a] += m->x0[3 * (size_t)p + a];
        }
    for (int a = 0; a < 3; ++a) {
        c[a] /= n;
        c0[a] /= n;
    }
    for (int p = 0; p < n; ++p)
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                A[3 * a + b] += (xs[3 * (size_t)p + a] - c[a]) * (m->x0[3 * (size_t)p + b] - c0[b]);
    double scale = 0;
    for (int i = 0; i < 9; ++i) scale += A[i] * A[i];
    scale = sqrt(scale / 3);
    if (!(scale > 0) || !isfinite(scale)) return 0;
    for (int i = 0; i < 9; ++i) A[i] /= scale;
    for (int it = 0; it < 60; ++it) {
        double det = det3(A);
        if (!(fabs(det) > 1e-12) || !isfinite(det)) return 0;
        /* inverse transpose = cofactor matrix / det */
        double C[9] = {A[4] * A[8] - A[5] * A[7], A[5] * A[6] - A[3] * A[8], A[3] * A[7] - A[4] * A[6],
                       A[2] * A[7] - A[1] * A[8], A[0] * A[8] - A[2] * A[6], A[1] * A[6] - A[0] * A[7],
                       A[1] * A[5] - A[2] * A[4], A[2] * A[3] - A[0] * A[5], A[0] * A[4] - A[1] * A[3]};
        double change = 0;
        for (int i = 0; i < 9; ++i) {
            double next = 0.5 * (A[i] + C[i] / det);
            change += (next - A[i]) * (next - A[i]);
            A[i] = next;
        }
        if (change < 1e-24) break;
    }
    /* rows made orthonormal (Gram-Schmidt) */
    for (int r = 0; r < 3; ++r) {
        double *row = A + 3 * r;
        for (int q = 0; q < r; ++q) {
            double d = dot3(row, A + 3 * q);
            for (int k = 0; k < 3; ++k) row[k] -= d * A[3 * q + k];
        }
        double l = sqrt(dot3(row, row));
        if (!(l > 0.5)) return 0;
        for (int k = 0; k < 3; ++k) row[k] /= l;
    }
    double limit = 0.99 * 0.5 * (SELF_EXCLUSION - 1) * radius, limit2 = limit * limit;
    if (rotation) memcpy(rotation, A, sizeof A);
    for (int p = 0; p < n; ++p) {
        const double *x = xs + 3 * (size_t)p, *x0 = m->x0 + 3 * (size_t)p;
        double r0[3] = {x0[0] - c0[0], x0[1] - c0[1], x0[2] - c0[2]}, e[3];
        for (int a = 0; a < 3; ++a) e[a] = x[a] - c[a] - dot3(A + 3 * a, r0);
        if (!(dot3(e, e) < limit2)) return 0;
    }
    return 1;
}

/* contact_object of each of the system's objects */
sem_status sem_contact_map_system(sem_contact *c, const sem_system *s, sem_error *err)
{
    if (c->n_sys < s->n_objects) {
        int *x = realloc(c->sys_to_contact, (size_t)s->n_objects * sizeof *x);
        if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        c->sys_to_contact = x;
    }
    c->n_sys = s->n_objects;
    for (int k = 0; k < s->n_objects; ++k) {
        c->sys_to_contact[k] = -1;
        for (int i = 0; i < c->n_objects; ++i)
            if (c->objects[i].object == s->objects[k]) c->sys_to_contact[k] = i;
        if (c->sys_to_contact[k] < 0)
            return sem_error_set(err, SEM_ERR_INVALID, "contact: an object of the system is not in the world");
        sem_status st = mesh_for(c, c->sys_to_contact[k], err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

static sem_status push_rec(sem_contact *c, const contact_rec *r, sem_error *err)
{
    if (!sem_grow((void **)&c->recs, &c->cap_recs, c->n_recs + 1, sizeof *c->recs, 256, INT_MAX))
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
    c->recs[c->n_recs++] = *r;
    return SEM_OK;
}

/* The contacts of point p of system object k (thickness + margin x the search radius,
 * margin 0: the active ones) into out (at most n_colliders + n_objects - 1); returns their
 * count and lowers *min_gap. */
static int point_contacts(const sem_contact *c, const sem_system *s, int k, int p, double margin, contact_rec *out,
                          double *min_gap)
{
    const contact_object *co = &c->objects[c->sys_to_contact[k]];
    const sem_collision_mesh *m = &co->mesh;
    double th = co->thickness, L = co->length;
    double own_stiffness = sem_contact_stiffness(c, co->youngs, L);
    double radius = th + SEARCH_DEPTH * L;
    /* how far to look: the search radius, or the contacts within th + margin x radius */
    double reach = margin > 1 ? th + margin * radius : radius, reach2 = reach * reach;
    const double *x = m->x + 3 * (size_t)p;
    int n = 0;
    for (int i = 0; i < c->n_colliders; ++i) {
        const collider *col = &c->colliders[i];
        contact_rec r = {k, p, -1, i, -1, {0, 0, 0}, 0, {0, 0, 0}, 0, th, 0};
        if (col->type == SEM_COLLIDER_PLANE) {
            double diff[3] = {x[0] - col->point[0], x[1] - col->point[1], x[2] - col->point[2]};
            r.d = dot3(diff, col->normal);
            memcpy(r.n, col->normal, sizeof r.n);
        } else {
            sem_tri_closest cl;
            int t = sem_bvh_closest(&col->bvh, col->vertices, col->triangles, x, reach2, &cl);
            if (t < 0) continue;
            const double *outward = cl.feature == SEM_TRI_FACE   ? col->face_normal + 3 * (size_t)t
                                    : cl.feature == SEM_TRI_EDGE ? col->edge_normal + 9 * (size_t)t + 3 * cl.index
                                                                 : col->vertex_normal +
                                                                       3 * (size_t)col->triangles[3 * t + cl.index];
            r.d = sem_signed_distance(x, cl.point, outward, r.n);
        }
        if (r.d < *min_gap && r.d < radius) *min_gap = r.d;
        if (!(r.d < th + margin * radius)) continue;
        r.stiffness = own_stiffness * m->area[p];
        r.mu = sqrt(co->friction * col->friction);
        out[n++] = r;
    }
    if (sem_contact_self_on(c) && !co->self_far) {
        /* the object's own surface beyond the exclusion rule; within the search radius only
         * (self-contact needs no coupling blocks, the margin's only use) */
        self_exclusion ex = {m, m->x0 + 3 * (size_t)p, SELF_EXCLUSION * SELF_EXCLUSION * radius * radius};
        sem_tri_closest cl;
        int t = sem_bvh_closest_except(&m->bvh, m->x, m->triangles, x, fmin(reach2, radius * radius), self_excluded,
                                       &ex, &cl);
        if (t >= 0) {
            contact_rec r = {k, p, k, -1, t, {cl.bary[0], cl.bary[1], cl.bary[2]}, 0, {0, 0, 0}, 0, th, 0};
            double outward[3];
            sem_collision_mesh_outward(m, t, cl.feature, cl.index, outward);
            r.d = sem_signed_distance(x, cl.point, outward, r.n);
            /* a point found deeper than the thickness behind its own surface got there by no
             * fold (an embedded or overlapping part, faces coming apart, a step through a
             * sheet; a resting contact sinks far less): no contact, so that no spring appears
             * at full depth (an energy that jumps by 1/2 k d^2 between Newton's iterates; the
             * chicken's step 37 failed so with 0.01 L as the limit) */
            double deepest = -th;
            if (r.d >= deepest && r.d < *min_gap && r.d < radius) *min_gap = r.d;
            if (r.d >= deepest && r.d < th + margin * radius) {
                r.stiffness = own_stiffness * m->area[p];
                r.mu = co->friction;
                out[n++] = r;
            }
        }
    }
    if (s->n_objects < 2) return n;
    for (int j = 0; j < s->n_objects; ++j) {
        if (j == k) continue;
        const contact_object *cj = &c->objects[c->sys_to_contact[j]];
        const sem_collision_mesh *mj = &cj->mesh;
        sem_tri_closest cl;
        int t = sem_bvh_closest_except(&mj->bvh, mj->x, mj->triangles, x, reach2, collapsed_excluded,
                                       (void *)mj, &cl);
        if (t < 0) continue;
        contact_rec r = {k, p, j, -1, t, {cl.bary[0], cl.bary[1], cl.bary[2]}, 0, {0, 0, 0}, 0, th, 0};
        double outward[3];
        sem_collision_mesh_outward(mj, t, cl.feature, cl.index, outward);
        r.d = sem_signed_distance(x, cl.point, outward, r.n);
        if (r.d < *min_gap && r.d < radius) *min_gap = r.d;
        if (!(r.d < th + margin * radius)) continue;
        double E = co->youngs < cj->youngs ? co->youngs : cj->youngs;
        r.stiffness = sem_contact_stiffness(c, E, L) * m->area[p];
        r.mu = sqrt(co->friction * cj->friction);
        out[n++] = r;
    }
    return n;
}

/* Every contact at the system's vector q closer than thickness + margin x the search
 * radius (margin 0: the active ones) into c->recs, and c->min_gap. Points are tested in
 * parallel, each into slots of its own, and the slots are gathered in point order: the
 * list is the same on any thread count. */
static sem_status detect(sem_contact *c, const sem_system *s, const double *q, double margin, sem_error *err)
{
    sem_status st = sem_contact_map_system(c, s, err);
    if (st != SEM_OK) return st;
    c->n_recs = 0;
    c->min_gap = INFINITY;
    if (c->def.disabled) return SEM_OK;
    int between = s->n_objects >= 2 || sem_contact_self_on(c);
    for (int k = 0; k < s->n_objects; ++k)
        sem_collision_mesh_update(&c->objects[c->sys_to_contact[k]].mesh, q + s->dof_offset[k], between);
    int per_point = c->n_colliders + s->n_objects - 1 + sem_contact_self_on(c);
    for (int k = 0; k < s->n_objects && sem_contact_self_on(c); ++k) {
        contact_object *co = &c->objects[c->sys_to_contact[k]];
        co->self_far = sem_contact_self_far_apart(&co->mesh, co->thickness + SEARCH_DEPTH * co->length);
    }
    if (per_point <= 0) return SEM_OK;
    int nthreads = s->n_objects > 0 ? s->objects[0]->nthreads : 1;
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_collision_mesh *m = &c->objects[c->sys_to_contact[k]].mesh;
        size_t need = (size_t)m->n_points * (size_t)per_point;
        if (need > c->cap_slots) {
            contact_rec *x = realloc(c->slots, need * sizeof *x);
            if (!x) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
            c->slots = x;
            c->cap_slots = need;
        }
        if (m->n_points > c->cap_count) {
            int *y = realloc(c->slot_count, (size_t)m->n_points * sizeof *y);
            if (!y) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for contacts");
            c->slot_count = y;
            c->cap_count = m->n_points;
        }
        double gap = INFINITY;
#pragma omp parallel for schedule(static) reduction(min : gap) num_threads(nthreads)
        for (int p = 0; p < m->n_points; ++p) {
            c->slot_count[p] = 0;
            if (m->area[p] > 0)
                c->slot_count[p] =
                    point_contacts(c, s, k, p, margin, c->slots + (size_t)p * (size_t)per_point, &gap);
        }
        if (gap < c->min_gap) c->min_gap = gap;
        for (int p = 0; p < m->n_points; ++p)
            for (int i = 0; i < c->slot_count[p]; ++i)
                if ((st = push_rec(c, &c->slots[(size_t)p * (size_t)per_point + (size_t)i], err)) != SEM_OK) return st;
    }
    return SEM_OK;
}

/* The weights of a contact's relative point: its point's row (+phi), and for a contact
 * with another object that object's triangle rows (-bary phi). Returns the count. */
static int rec_weights(const sem_contact *c, const contact_rec *r, sem_point_weight *w)
{
    const sem_collision_mesh *m = &c->objects[c->sys_to_contact[r->k]].mesh;
    int n = 0;
    for (int e = m->row_start[r->point]; e < m->row_start[r->point + 1] && n < MAX_WEIGHTS; ++e)
        w[n++] = (sem_point_weight){r->k, m->row_ctrl[e], m->row_w[e]};
    if (r->other >= 0) {
        const sem_collision_mesh *mo = &c->objects[c->sys_to_contact[r->other]].mesh;
        for (int v = 0; v < 3; ++v) {
            if (r->bary[v] == 0) continue;
            int p = mo->triangles[3 * r->triangle + v];
            for (int e = mo->row_start[p]; e < mo->row_start[p + 1] && n < MAX_WEIGHTS; ++e)
                w[n++] = (sem_point_weight){r->other, mo->row_ctrl[e], -r->bary[v] * mo->row_w[e]};
        }
    }
    return n;
}

void sem_contact_add_gradient(const sem_system *s, const sem_point_weight *w, int n, const double f[3], double *grad)
{
    for (int i = 0; i < n; ++i) {
        double *g = grad + s->dof_offset[w[i].object] + 3 * (size_t)w[i].ctrl;
        for (int d = 0; d < 3; ++d) g[d] += w[i].w * f[d];
    }
}

static void relative_point(const sem_system *s, const sem_point_weight *w, int n, const double *q, double X[3])
{
    X[0] = X[1] = X[2] = 0;
    for (int i = 0; i < n; ++i) {
        const double *x = q + s->dof_offset[w[i].object] + 3 * (size_t)w[i].ctrl;
        for (int d = 0; d < 3; ++d) X[d] += w[i].w * x[d];
    }
}

/* Springs at the last detection: energy; gradient into grad and Hessian into terms when
 * grad is given. With v (the linearly implicit step's velocities, h its step), a contact
 * not active yet but predicted to be at q + h v is a speculative one: its spring is the
 * linear extension of the active one (a pull towards the surface, to be reached within
 * the step; Box2D's speculative contacts), so a fast point stops at the surface instead of
 * sinking in for a step and being thrown out by a stiff spring the next. */
static sem_status springs(sem_contact *c, const sem_system *s, double *grad, sem_point_terms *terms, double *energy,
                          const double *v, double h, sem_error *err)
{
    sem_point_weight w[MAX_WEIGHTS];
    double E = 0;
    for (int i = 0; i < c->n_recs; ++i) {
        const contact_rec *r = &c->recs[i];
        double slope;
        E += sem_penalty_energy(r->stiffness, r->d, r->thickness, &slope);
        int n = 0;
        if (v && !(r->d < r->thickness)) {
            double X[3];
            n = rec_weights(c, r, w);
            relative_point(s, w, n, v, X);
            if (!(r->d + h * dot3(X, r->n) < r->thickness)) continue;
            slope = r->stiffness * (r->d - r->thickness);
        } else if (!(r->d < r->thickness))
            continue;
        if (!grad) continue;
        if (n == 0) n = rec_weights(c, r, w);
        double f[3] = {slope * r->n[0], slope * r->n[1], slope * r->n[2]};
        sem_contact_add_gradient(s, w, n, f, grad);
        double H[9] = {0};
        sem_penalty_hessian(r->stiffness, r->n, H);
        sem_status st = sem_point_terms_push(terms, w, n, H, err);
        if (st != SEM_OK) return st;
    }
    *energy = E;
    return SEM_OK;
}

/* Friction of the step at q: energy; gradient and Hessian terms when grad is given. */
static sem_status friction(sem_contact *c, const sem_system *s, const double *q, double *grad,
                           sem_point_terms *terms, double *energy, sem_error *err)
{
    double E = 0;
    if (!(c->friction_eps > 0)) {
        *energy = 0;
        return SEM_OK;
    }
    for (int i = 0; i < c->n_friction; ++i) {
        friction_rec *fr = &c->friction[i];
        const sem_point_weight *w = c->fweights + fr->first;
        double X[3], u[2], g[2], Hu[4];
        relative_point(s, w, fr->count, q, X);
        for (int d = 0; d < 3; ++d) X[d] -= fr->X0[d];
        u[0] = fr->T[0] * X[0] + fr->T[2] * X[1] + fr->T[4] * X[2];
        u[1] = fr->T[1] * X[0] + fr->T[3] * X[1] + fr->T[5] * X[2];
        E += sem_friction_potential(fr->mu_lambda, u, c->friction_eps, grad ? g : NULL, grad ? Hu : NULL);
        if (!grad) continue;
        /* D's own Hessian where the contact stays sliding or sticking since the last iterate;
         * where it changed, the Hessian of the quadratic bound, c I (friction.h) */
        int slipping = u[0] * u[0] + u[1] * u[1] >= c->friction_eps * c->friction_eps;
        if (slipping != fr->slipping || /* (u_last is set once slipping is) */
            !(hypot(u[0] - fr->u_last[0], u[1] - fr->u_last[1]) <= 0.25 * fmax(hypot(u[0], u[1]), c->friction_eps))) {
            double curvature = sem_friction_curvature(fr->mu_lambda, u, c->friction_eps);
            Hu[0] = Hu[3] = curvature;
            Hu[1] = Hu[2] = 0;
        }
        fr->slipping = (signed char)slipping;
        fr->u_last[0] = u[0];
        fr->u_last[1] = u[1];
        double f[3], H[9];
        for (int a = 0; a < 3; ++a) {
            f[a] = fr->T[2 * a] * g[0] + fr->T[2 * a + 1] * g[1];
            for (int b = 0; b < 3; ++b) {
                /* T Hu T^T */
                double ta0 = fr->T[2 * a], ta1 = fr->T[2 * a + 1], tb0 = fr->T[2 * b], tb1 = fr->T[2 * b + 1];
                H[3 * a + b] = ta0 * (Hu[0] * tb0 + Hu[1] * tb1) + ta1 * (Hu[2] * tb0 + Hu[3] * tb1);
            }
        }
        sem_contact_add_gradient(s, w, fr->count, f, grad);
        sem_status st = sem_point_terms_push(terms, w, fr->count, H, err);
        if (st != SEM_OK) return st;
    }
    *energy = E;
    return SEM_OK;
}

/* Friction for the linearly implicit step, as a damper: each contact's tangential motion
 * u = h T^T J v+ over the step meets the force -c u, c = mu lambda f1(y) / y at the slip
 * y = |u| predicted from v_n (friction.h). Sliding steadily, |u| = y and the force is
 * exactly mu lambda (Coulomb); sticking, c = 2 mu lambda / eps holds the contact. Linear in
 * v+ and dissipative, so the step stays stable; the tangent linearization about v_n (the
 * Newton Hessian) instead extrapolates a saturating force and throws objects apart when
 * their relative velocity changes within a step (an impact). Only the matrix changes:
 * h^2 c J^T T T^T J. */
static sem_status friction_damper(sem_contact *c, const sem_system *s, const double *qpred, sem_point_terms *terms,
                                  sem_error *err)
{
    if (!(c->friction_eps > 0)) return SEM_OK;
    for (int i = 0; i < c->n_friction; ++i) {
        const friction_rec *fr = &c->friction[i];
        const sem_point_weight *w = c->fweights + fr->first;
        double X[3], u[2], g[2];
        relative_point(s, w, fr->count, qpred, X);
        for (int d = 0; d < 3; ++d) X[d] -= fr->X0[d];
        u[0] = fr->T[0] * X[0] + fr->T[2] * X[1] + fr->T[4] * X[2];
        u[1] = fr->T[1] * X[0] + fr->T[3] * X[1] + fr->T[5] * X[2];
        double y = sqrt(u[0] * u[0] + u[1] * u[1]), damping;
        if (y > 0) {
            sem_friction_potential(fr->mu_lambda, u, c->friction_eps, g, NULL);
            damping = sqrt(g[0] * g[0] + g[1] * g[1]) / y;
        } else
            damping = 2 * fr->mu_lambda / c->friction_eps;
        double H[9];
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                H[3 * a + b] = damping * (fr->T[2 * a] * fr->T[2 * b] + fr->T[2 * a + 1] * fr->T[2 * b + 1]);
        sem_status st = sem_point_terms_push(terms, w, fr->count, H, err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

/* The system's objects' a q + b v as one vector (the caller frees). */
static double *system_q(const sem_system *s, double a, double b)
{
    double *q = malloc(s->n_dofs * sizeof(double) + 1);
    if (!q) return NULL;
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        double *x = q + s->dof_offset[k];
        for (size_t i = 0; i < 3 * (size_t)o->n_ctrl; ++i) x[i] = a * o->q[i] + b * o->v[i];
    }
    return q;
}

/* ---------------------------------------------------------------------------------- */
/* the step                                                                            */

/* The coupling block that points pa of system object a and pb of object b (a != b) need,
 * into c->couplings once. */
static sem_status need_coupling(sem_contact *c, const sem_system *s, int a, int pa, int b, int pb, sem_error *err)
{
    const sem_collision_mesh *m = &c->objects[c->sys_to_contact[a]].mesh;
    const sem_collision_mesh *mo = &c->objects[c->sys_to_contact[b]].mesh;
    int ga = s->objects[a]->ctrl_group[m->row_ctrl[m->row_start[pa]]];
    int gb = s->objects[b]->ctrl_group[mo->row_ctrl[mo->row_start[pb]]];
    sem_system_coupling cp = a < b ? (sem_system_coupling){a, ga, b, gb} : (sem_system_coupling){b, gb, a, ga};
    for (int j = 0; j < c->n_couplings; ++j)
        if (!memcmp(&c->couplings[j], &cp, sizeof cp)) return SEM_OK;
    if (!sem_grow((void **)&c->couplings, &c->cap_couplings, c->n_couplings + 1, sizeof *c->couplings, 64, INT_MAX))
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    c->couplings[c->n_couplings++] = cp;
    return SEM_OK;
}

/* The coupling blocks contact between objects needs at q (contacts within the search
 * radius, or the barrier's pairs within its margin: a superset of those a step's iterates
 * can activate), in c->couplings. */
static sem_status needed_couplings(sem_contact *c, const sem_system *s, sem_error *err)
{
    c->n_couplings = 0;
    sem_status st = SEM_OK;
    for (int i = 0; i < c->n_recs && st == SEM_OK && !def_is_barrier(c); ++i) {
        const contact_rec *r = &c->recs[i];
        if (r->other < 0 || r->other == r->k) continue; /* self-contact: the object's own blocks */
        const sem_collision_mesh *mo = &c->objects[c->sys_to_contact[r->other]].mesh;
        st = need_coupling(c, s, r->k, r->point, r->other, mo->triangles[3 * r->triangle], err);
    }
    for (int i = 0; i < c->n_pairs && st == SEM_OK && def_is_barrier(c); ++i) {
        const barrier_pair *p = &c->pairs[i];
        for (int u = 0; u < p->nv && st == SEM_OK; ++u)
            for (int v = u + 1; v < p->nv && st == SEM_OK; ++v)
                if (p->object[u] >= 0 && p->object[v] >= 0 && p->object[u] != p->object[v])
                    st = need_coupling(c, s, p->object[u], p->point[u], p->object[v], p->point[v], err);
    }
    return st;
}

/* The step's contacts at q: the springs' (margin x the search radius beyond the thickness)
 * or the barrier's pairs (within margin x its reach, at least 1). */
static sem_status detect_any(sem_contact *c, const sem_system *s, const double *q, double margin, sem_error *err)
{
    if (def_is_barrier(c)) return sem_barrier_detect(c, s, q, margin, err);
    return detect(c, s, q, margin, err);
}

sem_status sem_contact_begin_step(sem_contact *c, sem_system **system, double h, sem_solver_choice solver,
                                  sem_error *err)
{
    const sem_system *s = *system;
    c->n_friction = 0;
    c->n_fweights = 0;
    c->friction_eps = 0;
    if (!sem_contact_active(c)) return SEM_OK;
    /* the structured solver (physics/structured.h) has no matrix to take point terms yet:
     * without the contact Hessian Newton would crawl and the linearly implicit step would
     * be explicit in the springs */
    if (s->structured)
        return sem_error_set(err, SEM_ERR_UNSUPPORTED,
                             "contact needs the sparse or dense solver for now (integrator.solver); the structured "
                             "solver does not take contact terms yet");
    double t0 = omp_get_wtime();
    double *q = system_q(s, 1, 0);
    if (!q) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_status st = detect_any(c, s, q, s->n_objects > 1 ? 1 : 0, err);
    if (st == SEM_OK && def_is_barrier(c) && !(c->min_gap > 0))
        st = sem_error_set(err, SEM_ERR_NUMERIC,
                           "contact (barrier): two surfaces touch or cross at the start of a step (distance %g m); "
                           "the barrier model needs them apart",
                           c->min_gap);
    /* objects near each other: their coupling blocks in the system's pattern (a new system
     * when some are missing; point_terms.h) */
    if (st == SEM_OK && s->n_objects > 1) st = needed_couplings(c, s, err);
    if (st == SEM_OK && s->n_objects > 1) {
        int missing = 0;
        for (int i = 0; i < c->n_couplings && !missing; ++i)
            missing = sem_system_find_coupling(s, c->couplings[i].a, c->couplings[i].ga, c->couplings[i].b,
                                               c->couplings[i].gb) < 0;
        if (missing) {
            /* ask for the blocks of parts up to three search radii apart, so that objects
             * approaching each other do not need a new system every step */
            if ((st = detect_any(c, s, q, 3, err)) == SEM_OK) st = needed_couplings(c, s, err);
            if (st == SEM_OK) st = detect_any(c, s, q, 1, err); /* the step's contacts again */
        }
        if (missing && st == SEM_OK) {
            sem_system *ns = NULL;
            st = sem_system_create_coupled(s->objects, s->n_objects, c->couplings, c->n_couplings, solver, &ns, err);
            if (st == SEM_OK) {
                sem_system_destroy(*system);
                *system = ns;
                s = ns;
                c->rebuilds++;
            } else /* the objects point to the system they had */
                for (int k = 0; k < s->n_objects; ++k) s->objects[k]->system = *system;
        }
    }
    c->friction_eps = h > 0 ? c->def.friction_velocity * h : 0;
    sem_point_weight w[MAX_WEIGHTS];
    int barrier = def_is_barrier(c), n_contacts = barrier ? c->n_pairs : c->n_recs;
    for (int i = 0; st == SEM_OK && c->friction_eps > 0 && i < n_contacts; ++i) {
        double lambda, mu, normal[3];
        int n;
        if (barrier) {
            /* the barrier's force on the pair: kappa m |b'(d)| */
            const barrier_pair *p = &c->pairs[i];
            double db;
            sem_barrier(p->d, p->dhat, &db, NULL);
            lambda = -p->kappa * p->mollifier * db;
            mu = p->mu;
            memcpy(normal, p->n, sizeof normal);
            if (!(mu > 0) || !(lambda > 0)) continue;
            n = sem_barrier_weights(c, p, w);
        } else {
            const contact_rec *r = &c->recs[i];
            lambda = r->stiffness * (r->thickness - r->d);
            mu = r->mu;
            memcpy(normal, r->n, sizeof normal);
            if (!(mu > 0) || !(lambda > 0)) continue;
            n = rec_weights(c, r, w);
        }
        if (!sem_grow((void **)&c->friction, &c->cap_friction, c->n_friction + 1, sizeof *c->friction, 256, INT_MAX) ||
            !sem_grow((void **)&c->fweights, &c->cap_fweights, c->n_fweights + n, sizeof *c->fweights, 4096,
                      INT_MAX)) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for friction");
            break;
        }
        friction_rec *fr = &c->friction[c->n_friction++];
        fr->first = c->n_fweights;
        fr->count = n;
        memcpy(c->fweights + c->n_fweights, w, (size_t)n * sizeof *w);
        c->n_fweights += n;
        sem_tangent_basis(normal, fr->T);
        relative_point(s, w, n, q, fr->X0);
        fr->mu_lambda = mu * lambda;
        fr->slipping = -1;
    }
    free(q);
    c->stats.seconds += omp_get_wtime() - t0;
    return st;
}

double sem_contact_potential(sem_contact *c, const sem_system *s, const double *q, double h, double *grad,
                             sem_error *err)
{
    if (grad) sem_point_terms_clear(&c->terms);
    if (!sem_contact_active(c)) return 0;
    double t0 = omp_get_wtime();
    double Es = 0, Ef = 0;
    sem_status st;
    if (def_is_barrier(c)) {
        st = sem_barrier_detect(c, s, q, 0, err);
        if (st == SEM_OK) st = sem_barrier_energy(c, s, grad, &c->terms, &Es, err);
    } else {
        st = detect(c, s, q, 0, err);
        if (st == SEM_OK) st = springs(c, s, grad, &c->terms, &Es, NULL, 0, err);
    }
    if (st == SEM_OK && h > 0) st = friction(c, s, q, grad, &c->terms, &Ef, err);
    c->stats.seconds += omp_get_wtime() - t0;
    return st == SEM_OK ? Es + Ef : NAN;
}

sem_status sem_contact_linearized(sem_contact *c, sem_system *s, double h, double *rhs, sem_error *err)
{
    if (!sem_contact_active(c)) return SEM_OK;
    if (def_is_barrier(c))
        return sem_error_set(err, SEM_ERR_UNSUPPORTED,
                             "contact.model \"barrier\" needs integrator.type \"implicit_euler\" or \"static\" (its "
                             "collision check bounds Newton's steps; the linearly implicit step has none)");
    double t0 = omp_get_wtime();
    sem_status st = SEM_OK;
    double *q = system_q(s, 1, 0), *qpred = system_q(s, 1, h), *v = system_q(s, 0, 1);
    double *g = calloc(s->n_dofs + 1, sizeof(double));
    double E;
    if (!q || !qpred || !v || !g) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* springs at q_n (as the elastic forces): h^2 H in the matrix, h f on the right */
    sem_point_terms_clear(&c->terms);
    if ((st = detect(c, s, q, 1, err)) != SEM_OK) goto done;
    if ((st = springs(c, s, g, &c->terms, &E, v, h, err)) != SEM_OK) goto done;
    /* friction as a damper lagged from the predicted slip (friction_damper) */
    sem_point_terms_clear(&c->friction_terms);
    if ((st = friction_damper(c, s, qpred, &c->friction_terms, err)) != SEM_OK) goto done;
    {
        const sem_point_terms *lists[2] = {&c->terms, &c->friction_terms};
        const double scale[2] = {h * h, h * h};
        sem_system_set_point_terms(s, lists, scale, 2);
    }
    for (size_t i = 0; i < s->n_dofs; ++i) rhs[i] -= h * g[i];
done:
    SEM_FREE_ALL(q, qpred, v, g);
    c->stats.seconds += omp_get_wtime() - t0;
    return st;
}

sem_status sem_contact_check_islands(sem_contact *c, sem_object *const *objects, int n, sem_error *err)
{
    if (!sem_contact_barrier(c) || n < 2) return SEM_OK;
    double *box = malloc(6 * (size_t)n * sizeof(double) + 1);
    if (!box) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_status st = SEM_OK;
    for (int i = 0; i < n && st == SEM_OK; ++i) {
        int ci = -1;
        for (int k = 0; k < c->n_objects && ci < 0; ++k)
            if (c->objects[k].object == objects[i]) ci = k;
        st = ci < 0 ? sem_error_set(err, SEM_ERR_INVALID, "contact: an object is not in the world")
                    : mesh_for(c, ci, err);
        if (st != SEM_OK) break;
        contact_object *co = &c->objects[ci];
        sem_collision_mesh_update(&co->mesh, objects[i]->q, 0);
        sem_collision_mesh_box(&co->mesh, NULL, co->thickness, box + 6 * (size_t)i, box + 6 * (size_t)i + 3);
    }
    for (int i = 0; i < n && st == SEM_OK; ++i)
        for (int j = i + 1; j < n && st == SEM_OK; ++j) {
            if (objects[i]->system == objects[j]->system) continue;
            const double *a = box + 6 * (size_t)i, *b = box + 6 * (size_t)j;
            int overlap = 1;
            for (int k = 0; k < 3; ++k) overlap &= a[k] <= b[3 + k] && b[k] <= a[3 + k];
            if (overlap)
                st = sem_error_set(err, SEM_ERR_NUMERIC,
                                   "contact (barrier): objects %d and %d, solved apart in this step (they were far "
                                   "apart at its start), came within reach of each other, unchecked; a smaller "
                                   "integrator.dt keeps them in one solve",
                                   i, j);
        }
    free(box);
    return st;
}

void sem_contact_begin_world_step(sem_contact *c)
{
    c->stats.seconds = 0;
    c->stats.contacts = 0;
    c->stats.self_contacts = 0;
    c->stats.min_gap = INFINITY;
}

sem_status sem_contact_islands(sem_contact *c, sem_object *const *objects, int n, double h, int *island,
                               sem_error *err)
{
    double t0 = omp_get_wtime();
    double *box = malloc(6 * (size_t)n * sizeof(double) + 1);
    if (!box) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n; ++i) {
        island[i] = i;
        int ci = -1;
        for (int k = 0; k < c->n_objects && ci < 0; ++k)
            if (c->objects[k].object == objects[i]) ci = k;
        sem_status st = ci < 0 ? sem_error_set(err, SEM_ERR_INVALID, "contact: an object is not in the world")
                               : mesh_for(c, ci, err);
        if (st != SEM_OK) {
            free(box);
            return st;
        }
        const contact_object *co = &c->objects[ci];
        const sem_object *o = objects[i];
        double *b = box + 6 * (size_t)i, speed2 = 0;
        for (int k = 0; k < 3; ++k) {
            b[k] = INFINITY;
            b[3 + k] = -INFINITY;
        }
        for (int p = 0; p < o->n_ctrl; ++p) {
            const double *x = o->q + 3 * (size_t)p, *v = o->v + 3 * (size_t)p;
            for (int k = 0; k < 3; ++k) {
                b[k] = fmin(b[k], x[k]);
                b[3 + k] = fmax(b[3 + k], x[k]);
            }
            speed2 = fmax(speed2, dot3(v, v));
        }
        /* the barrier: twice the predicted move, so that an object thrown back within the
         * step (a bounce) stays in its island (sem_contact_check_islands checks it) */
        double grow = 3 * (co->thickness + SEARCH_DEPTH * co->length) +
                      (def_is_barrier(c) ? 2 : 1) * fabs(h) * sqrt(speed2);
        for (int k = 0; k < 3; ++k) {
            b[k] -= grow;
            b[3 + k] += grow;
        }
    }
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            const double *a = box + 6 * (size_t)i, *b = box + 6 * (size_t)j;
            int overlap = 1;
            for (int k = 0; k < 3; ++k) overlap &= a[k] <= b[3 + k] && b[k] <= a[3 + k];
            if (overlap) sem_uf_unite(island, i, j);
        }
    for (int i = 0; i < n; ++i) island[i] = sem_uf_find(island, i);
    free(box);
    c->stats.seconds += omp_get_wtime() - t0;
    return SEM_OK;
}

sem_status sem_contact_end_step(sem_contact *c, const sem_system *s, sem_error *err)
{
    if (!sem_contact_active(c)) return SEM_OK;
    double t0 = omp_get_wtime();
    double *q = system_q(s, 1, 0);
    sem_error ignored;
    sem_status st = SEM_OK;
    if (!q)
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    else if (def_is_barrier(c)) {
        if ((st = sem_barrier_detect(c, s, q, 0, err)) == SEM_OK) {
            for (int i = 0; i < c->n_pairs; ++i) {
                const barrier_pair *p = &c->pairs[i];
                if (!(p->d < p->dhat)) continue;
                c->stats.contacts++;
                c->stats.self_contacts += p->nv > 1 && p->object[0] >= 0 && p->object[0] == p->object[p->nv - 1];
            }
            c->stats.min_gap = fmin(c->stats.min_gap, c->min_gap);
            if (!(c->min_gap > 0))
                st = sem_error_set(err, SEM_ERR_NUMERIC,
                                   "contact (barrier): two surfaces touch at the end of a step (distance %g m)",
                                   c->min_gap);
        }
    } else if (detect(c, s, q, 0, &ignored) == SEM_OK) {
        c->stats.contacts += c->n_recs;
        for (int i = 0; i < c->n_recs; ++i) c->stats.self_contacts += c->recs[i].other == c->recs[i].k;
        c->stats.min_gap = fmin(c->stats.min_gap, c->min_gap);
    }
    free(q);
    c->stats.seconds += omp_get_wtime() - t0;
    return st;
}

sem_collider_def sem_default_collider_def(void)
{
    sem_collider_def d;
    memset(&d, 0, sizeof d);
    d.type = SEM_COLLIDER_PLANE;
    d.normal[2] = 1;
    d.friction = SEM_DEFAULT_FRICTION;
    return d;
}
