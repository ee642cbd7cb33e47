/*
 * collision_topology.c - which points of a collision mesh are one point of the surface, and
 * which triangles share an edge (see collision_topology.h).
 *
 * Welding the points is geometry/weld_points.c; here the triangles on either side of each
 * welded edge are found.
 */
#include "collision_topology.h"

#include <stdlib.h>
#include <string.h>


int sem_compare_edge_slot(const void *x, const void *y)
{
    const sem_edge_slot *p = x, *q = y;
    if (p->a != q->a) return (p->a > q->a) - (p->a < q->a);
    if (p->b != q->b) return (p->b > q->b) - (p->b < q->b);
    return (p->slot > q->slot) - (p->slot < q->slot);
}

sem_status sem_collision_edge_neighbours(const int *triangles, int n_triangles, const int *weld, int *edge_other,
                                         sem_error *err)
{
    size_t ne = 3 * (size_t)n_triangles;
    for (size_t e = 0; e < ne; ++e) edge_other[e] = -1;
    sem_edge_slot *edges = malloc((ne + 1) * sizeof *edges);
    if (!edges) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collision mesh");
    size_t m = 0;
    for (size_t e = 0; e < ne; ++e) {
        int t = (int)(e / 3), v = (int)(e % 3);
        int a = weld[triangles[3 * (size_t)t + (size_t)v]], b = weld[triangles[3 * (size_t)t + (size_t)(v + 1) % 3]];
        if (a == b) continue; /* a collapsed edge (a pole) */
        edges[m++] = (sem_edge_slot){a < b ? a : b, a < b ? b : a, (int)e};
    }
    qsort(edges, m, sizeof *edges, sem_compare_edge_slot);
    for (size_t i = 0; i < m;) {
        size_t j = i;
        while (j < m && edges[j].a == edges[i].a && edges[j].b == edges[i].b) ++j;
        if (j - i == 2) { /* a manifold edge; more triangles on one edge: left open */
            edge_other[edges[i].slot] = edges[i + 1].slot / 3;
            edge_other[edges[i + 1].slot] = edges[i].slot / 3;
        }
        i = j;
    }
    free(edges);
    return SEM_OK;
}

sem_status sem_collision_edges(const int *triangles, int n_triangles, const int *weld, int **out, int *n_edges,
                               sem_error *err)
{
    size_t n = 3 * (size_t)(n_triangles > 0 ? n_triangles : 0);
    sem_edge_slot *e = malloc((n + 1) * sizeof *e);
    int *edges = malloc((3 * n + 1) * sizeof(int));
    if (!e || !edges) {
        free(e);
        free(edges);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for collision edges");
    }
    for (size_t i = 0; i < n; ++i) {
        int p = triangles[i], q = triangles[i - i % 3 + (i % 3 + 1) % 3];
        e[i] = (sem_edge_slot){p < q ? p : q, p < q ? q : p, (int)i};
    }
    qsort(e, n, sizeof *e, sem_compare_edge_slot);
    int count = 0;
    for (size_t i = 0; i < n; ++i) {
        if (i > 0 && e[i].a == e[i - 1].a && e[i].b == e[i - 1].b) continue;
        if (e[i].a == e[i].b || (weld && weld[e[i].a] == weld[e[i].b])) continue;
        edges[3 * count] = e[i].a;
        edges[3 * count + 1] = edges[3 * count + 2] = e[i].b;
        ++count;
    }
    free(e);
    *out = edges;
    *n_edges = count;
    return SEM_OK;
}
