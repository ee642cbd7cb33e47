/*
 * broad_phase.c - the triangle BVH (see broad_phase.h).
 */
#include "broad_phase.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#define LEAF_SIZE 4

typedef struct build_ctx {
    const double *vertices;
    const int *triangles;
    double *centroid;   /* 3 per triangle */
    struct keyed *keys; /* sort scratch, one per triangle */
} build_ctx;

typedef struct keyed {
    double key;
    int triangle;
} keyed;

static int compare_keyed(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    if (x->key < y->key) return -1;
    if (x->key > y->key) return 1;
    return (x->triangle > y->triangle) - (x->triangle < y->triangle);
}

static void node_box2(sem_bvh *bvh, int node, const double *vertices, const double *moved, const int *triangles);

static void node_box(sem_bvh *bvh, int node, const double *vertices, const int *triangles)
{
    node_box2(bvh, node, vertices, NULL, triangles);
}

/* The node's box over the triangles' vertices at both positions (moved may be NULL) */
static void node_box2(sem_bvh *bvh, int node, const double *vertices, const double *moved, const int *triangles)
{
    sem_bvh_node *n = &bvh->nodes[node];
    for (int k = 0; k < 3; ++k) {
        n->lo[k] = DBL_MAX;
        n->hi[k] = -DBL_MAX;
    }
    if (n->left >= 0) {
        const sem_bvh_node *a = &bvh->nodes[n->left], *b = &bvh->nodes[n->right];
        for (int k = 0; k < 3; ++k) {
            n->lo[k] = a->lo[k] < b->lo[k] ? a->lo[k] : b->lo[k];
            n->hi[k] = a->hi[k] > b->hi[k] ? a->hi[k] : b->hi[k];
        }
        return;
    }
    for (int t = n->first; t < n->first + n->count; ++t) {
        const int *tri = triangles + 3 * (size_t)bvh->order[t];
        for (int v = 0; v < 3; ++v)
            for (int k = 0; k < 3; ++k) {
                double x = vertices[3 * (size_t)tri[v] + k];
                if (x < n->lo[k]) n->lo[k] = x;
                if (x > n->hi[k]) n->hi[k] = x;
                if (!moved) continue;
                x = moved[3 * (size_t)tri[v] + k];
                if (x < n->lo[k]) n->lo[k] = x;
                if (x > n->hi[k]) n->hi[k] = x;
            }
    }
}

/* Builds the subtree of order[first .. first + count) at node index `node`; children are
 * appended. */
static void build(sem_bvh *bvh, build_ctx *c, int node, int first, int count)
{
    sem_bvh_node *n = &bvh->nodes[node];
    n->first = first;
    n->count = count;
    n->left = n->right = -1;
    if (count > LEAF_SIZE) {
        double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
        for (int t = first; t < first + count; ++t)
            for (int k = 0; k < 3; ++k) {
                double x = c->centroid[3 * (size_t)bvh->order[t] + k];
                if (x < lo[k]) lo[k] = x;
                if (x > hi[k]) hi[k] = x;
            }
        int axis = 0;
        for (int k = 1; k < 3; ++k)
            if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
        for (int t = 0; t < count; ++t) {
            int tri = bvh->order[first + t];
            c->keys[t].key = c->centroid[3 * (size_t)tri + axis];
            c->keys[t].triangle = tri;
        }
        qsort(c->keys, (size_t)count, sizeof *c->keys, compare_keyed);
        for (int t = 0; t < count; ++t) bvh->order[first + t] = c->keys[t].triangle;
        int half = count / 2;
        int left = bvh->n_nodes++, right = bvh->n_nodes++;
        n->left = left;
        n->right = right;
        build(bvh, c, left, first, half);
        build(bvh, c, right, first + half, count - half);
    }
    node_box(bvh, node, c->vertices, c->triangles);
}

sem_status sem_bvh_build(sem_bvh *bvh, const double *vertices, const int *triangles, int n_triangles,
                         sem_error *err)
{
    memset(bvh, 0, sizeof *bvh);
    size_t n = n_triangles > 0 ? (size_t)n_triangles : 1;
    bvh->nodes = malloc(2 * n * sizeof *bvh->nodes);
    bvh->order = malloc(n * sizeof(int));
    double *centroid = malloc(3 * n * sizeof(double));
    keyed *keys = malloc(n * sizeof *keys);
    if (!bvh->nodes || !bvh->order || !centroid || !keys) {
        free(centroid);
        free(keys);
        sem_bvh_free(bvh);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a contact tree");
    }
    bvh->n_triangles = n_triangles;
    for (int t = 0; t < n_triangles; ++t) {
        bvh->order[t] = t;
        for (int k = 0; k < 3; ++k) {
            double s = 0;
            for (int v = 0; v < 3; ++v) s += vertices[3 * (size_t)triangles[3 * (size_t)t + v] + k];
            centroid[3 * (size_t)t + k] = s / 3;
        }
    }
    build_ctx c = {vertices, triangles, centroid, keys};
    bvh->n_nodes = 1;
    build(bvh, &c, 0, 0, n_triangles);
    free(centroid);
    free(keys);
    return SEM_OK;
}

void sem_bvh_refit(sem_bvh *bvh, const double *vertices, const int *triangles)
{
    for (int node = bvh->n_nodes - 1; node >= 0; --node) node_box(bvh, node, vertices, triangles);
}

void sem_bvh_refit_swept(sem_bvh *bvh, const double *x0, const double *x1, const int *triangles)
{
    for (int node = bvh->n_nodes - 1; node >= 0; --node) node_box2(bvh, node, x0, x1, triangles);
}

void sem_bvh_overlap(const sem_bvh *bvh, const double lo[3], const double hi[3], void (*visit)(int triangle, void *context),
                     void *context)
{
    if (bvh->n_triangles <= 0) return;
    int stack[128], top = 0;
    stack[top++] = 0;
    while (top > 0) {
        const sem_bvh_node *n = &bvh->nodes[stack[--top]];
        int meets = 1;
        for (int k = 0; k < 3; ++k) meets &= n->lo[k] <= hi[k] && lo[k] <= n->hi[k];
        if (!meets) continue;
        if (n->left < 0) {
            for (int t = n->first; t < n->first + n->count; ++t) visit(bvh->order[t], context);
            continue;
        }
        if (top + 2 > 128) continue; /* depth is about log2(n / 4): never reached */
        stack[top++] = n->right;
        stack[top++] = n->left;
    }
}

void sem_bvh_free(sem_bvh *bvh)
{
    free(bvh->nodes);
    free(bvh->order);
    memset(bvh, 0, sizeof *bvh);
}

static double box_dist2(const sem_bvh_node *n, const double p[3])
{
    double s = 0;
    for (int k = 0; k < 3; ++k) {
        double d = p[k] < n->lo[k] ? n->lo[k] - p[k] : p[k] > n->hi[k] ? p[k] - n->hi[k] : 0;
        s += d * d;
    }
    return s;
}

int sem_bvh_closest(const sem_bvh *bvh, const double *vertices, const int *triangles, const double p[3],
                    double max_dist2, sem_tri_closest *out)
{
    return sem_bvh_closest_except(bvh, vertices, triangles, p, max_dist2, NULL, NULL, out);
}

int sem_bvh_closest_except(const sem_bvh *bvh, const double *vertices, const int *triangles, const double p[3],
                           double max_dist2, int (*skip)(int triangle, void *context), void *context,
                           sem_tri_closest *out)
{
    if (bvh->n_triangles <= 0) return -1;
    int stack[128], top = 0, best = -1;
    double best2 = max_dist2;
    stack[top++] = 0;
    while (top > 0) {
        const sem_bvh_node *n = &bvh->nodes[stack[--top]];
        if (box_dist2(n, p) >= best2) continue;
        if (n->left < 0) {
            for (int t = n->first; t < n->first + n->count; ++t) {
                int tri = bvh->order[t];
                const int *v = triangles + 3 * (size_t)tri;
                sem_tri_closest c;
                sem_point_triangle_closest(p, vertices + 3 * (size_t)v[0], vertices + 3 * (size_t)v[1],
                                           vertices + 3 * (size_t)v[2], &c);
                if (c.dist2 < best2 && !(skip && skip(tri, context))) {
                    best2 = c.dist2;
                    best = tri;
                    *out = c;
                }
            }
            continue;
        }
        /* nearer child last on the stack, so visited first */
        double da = box_dist2(&bvh->nodes[n->left], p), db = box_dist2(&bvh->nodes[n->right], p);
        if (top + 2 > 128) continue; /* depth is about log2(n / 4): never reached */
        if (da < db) {
            stack[top++] = n->right;
            stack[top++] = n->left;
        } else {
            stack[top++] = n->left;
            stack[top++] = n->right;
        }
    }
    return best;
}
