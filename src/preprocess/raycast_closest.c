/*
 * raycast_closest.c - the closest point of each part of the tessellation to a point, within
 * a radius (raycast.h); the weights and the boundary samples ask for it.
 *
 * Design
 * - Closest parts: exact double-precision point-triangle distances (Ericson, Real-Time
 *   Collision Detection, 5.1.5), minimum per part within the radius. The public query walks
 *   a small box tree per part (built on first use) with a radius that shrinks to the best
 *   distance so far; the component search at scene build uses one Embree rtcPointQuery
 *   (its radius is tiny).
 */
#include "raycast_scene.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/point_triangle.h"

/* Closest point on triangle abc to p: the region tests of geometry/point_triangle.h, the
 * point placed from a vertex along the edge vectors (a + t ab, ...; in the face
 * a + v ab + w ac with v, w from one reciprocal), as this file always has: the barycentric
 * blend of sem_point_triangle_closest rounds differently, and these points and distances
 * feed the weights. */
static void closest_point_triangle(const double *p, const double *a, const double *b,
                                   const double *c, double *q)
{
    sem_tri_region r;
    sem_point_triangle_region(p, a, b, c, &r);
    if (r.feature == SEM_TRI_VERTEX) {
        memcpy(q, r.index == 0 ? a : r.index == 1 ? b : c, 3 * sizeof *q);
        return;
    }
    double ab[3], ac[3];
    sub3(b, a, ab);
    sub3(c, a, ac);
    if (r.feature == SEM_TRI_EDGE) {
        if (r.index == 0)
            for (int k = 0; k < 3; k++) q[k] = a[k] + r.t * ab[k];
        else if (r.index == 2)
            for (int k = 0; k < 3; k++) q[k] = a[k] + r.t * ac[k];
        else
            for (int k = 0; k < 3; k++) q[k] = b[k] + r.t * (c[k] - b[k]);
        return;
    }
    double denom = 1.0 / (r.va + r.vb + r.vc);
    double v = r.vb * denom, w = r.vc * denom;
    for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
}

typedef struct closest_context {
    const sem_raycast_scene *scene;
    double X[3];
    double radius;
    int *slot;      /* n_parts: index into the found list or -1 */
    int n_found;
    int *parts;
    double *dist;
    double *points;
} closest_context;

static bool closest_callback(struct RTCPointQueryFunctionArguments *args)
{
    closest_context *c = (closest_context *)args->userPtr;
    const sem_raycast_scene *s = c->scene;
    if (args->geomID >= (unsigned)s->n_parts) return false;
    int part = (int)args->geomID;
    int global = s->part_tri_offset[part] + (int)args->primID;
    if (global >= s->part_tri_offset[part + 1]) return false;
    const double *v = s->tri + 9 * (size_t)global;
    double q[3], w[3];
    closest_point_triangle(c->X, v, v + 3, v + 6, q);
    sub3(q, c->X, w);
    double dist = sqrt(dot3(w, w));
    if (dist > c->radius) return false;
    int k = c->slot[part];
    if (k < 0) {
        k = c->n_found++;
        c->slot[part] = k;
        c->parts[k] = part;
        c->dist[k] = INFINITY;
    }
    if (dist < c->dist[k]) {
        c->dist[k] = dist;
        if (c->points) memcpy(c->points + 3 * k, q, sizeof q);
    }
    return false; /* never shrink the radius: every part within it is wanted */
}

/* Closest parts by one Embree point query over the whole scene (cost: every triangle within
 * the radius); used for the small radii of the component search. */
int sem_raycast_closest_parts_embree(const sem_raycast_scene *scene, const double X[3],
                                     double radius, int *out_parts, double *out_dist,
                                     double *out_points)
{
    if (!scene || !X || !out_parts || !out_dist || scene->n_triangles == 0 || !(radius >= 0))
        return 0;
    int n_parts = scene->n_parts;
    int slot_local[512];
    int *slot = n_parts <= 512 ? slot_local : malloc((size_t)n_parts * sizeof *slot);
    if (!slot) return 0;
    for (int i = 0; i < n_parts; i++) slot[i] = -1;
    closest_context c;
    c.scene = scene;
    memcpy(c.X, X, sizeof c.X);
    c.radius = radius;
    c.slot = slot;
    c.n_found = 0;
    c.parts = out_parts;
    c.dist = out_dist;
    c.points = out_points;

    struct RTCPointQuery q;
    q.x = (float)X[0];
    q.y = (float)X[1];
    q.z = (float)X[2];
    q.time = 0.0f;
    /* float radius padded so float rounding of X and of the boxes never loses a triangle
     * that is within the exact (double) radius */
    double r = radius + 1e-6 * scene->scale + 1e-6 * (fabs(X[0]) + fabs(X[1]) + fabs(X[2]));
    q.radius = r < 3e38 ? (float)r : INFINITY;
    struct RTCPointQueryContext context;
    rtcInitPointQueryContext(&context);
    rtcPointQuery(scene->scene, &q, &context, closest_callback, &c);

    /* deterministic output: sorted by part index (insertion sort: small counts) */
    for (int i = 1; i < c.n_found; i++) {
        int p = out_parts[i];
        double dd = out_dist[i], pt[3] = {0, 0, 0};
        if (out_points) memcpy(pt, out_points + 3 * i, sizeof pt);
        int j = i - 1;
        while (j >= 0 && out_parts[j] > p) {
            out_parts[j + 1] = out_parts[j];
            out_dist[j + 1] = out_dist[j];
            if (out_points) memcpy(out_points + 3 * (j + 1), out_points + 3 * j, sizeof pt);
            j--;
        }
        out_parts[j + 1] = p;
        out_dist[j + 1] = dd;
        if (out_points) memcpy(out_points + 3 * (j + 1), pt, sizeof pt);
    }
    if (slot != slot_local) free(slot);
    return c.n_found;
}

/* Per-part trees for closest-point queries. One Embree query over the whole scene visits
 * every triangle within the radius, which for the weights' radius alpha (often half the
 * model) is most of the model per point. Instead each part gets its own small tree of
 * axis-aligned boxes (in double), and a tree over the parts' boxes finds the parts whose
 * box is within the radius (a boundary sample's tiny radius meets one to three of them, so
 * a model of many parts does not cost a box test per part and sample); those are searched in
 * index order, each shrinking its search radius to the best distance so far (nearer child
 * first, a child beyond it not visited): about log(triangles) work per part found. */
#define PART_LEAF 4

typedef struct part_node {
    double lo[3], hi[3];
    int left, right;  /* children, -1 for a leaf */
    int first, count; /* leaf: range in part_tri_order */
} part_node;

/* Reorders the triangle indices o[0..count) so that o[count / 2] has the median centroid
 * along axis, smaller ones before it and larger ones after (quickselect): the split of both
 * bounding-volume trees below. */
void sem_raycast_select_median(int *o, int count, const double *centroid, int axis)
{
    int half = count / 2;
    int l = 0, r = count - 1;
    while (l < r) {
        double pivot = centroid[3 * (size_t)o[(l + r) / 2] + axis];
        int i = l, j = r;
        while (i <= j) {
            while (centroid[3 * (size_t)o[i] + axis] < pivot) i++;
            while (centroid[3 * (size_t)o[j] + axis] > pivot) j--;
            if (i <= j) {
                int tmp = o[i];
                o[i] = o[j];
                o[j] = tmp;
                i++;
                j--;
            }
        }
        if (half <= j)
            r = j;
        else if (half >= i)
            l = i;
        else
            break;
    }
}

/* A tree node over items order[first .. first + count) (triangles of a part, or parts):
 * box[6 i .. 6 i + 6) is item i's box (lo, hi), centre[3 i ..] the point it is split by: at
 * the median along the widest extent of the centres, leaves of at most PART_LEAF items.
 * Returns the node's index in nodes. */
static int build_box_node(part_node *nodes, int *order, const double *box, const double *centre, int *n_nodes,
                          int first, int count)
{
    int id = (*n_nodes)++;
    part_node *node = &nodes[id];
    int *o = order + first;
    double clo[3], chi[3];
    for (int d = 0; d < 3; d++) {
        node->lo[d] = clo[d] = INFINITY;
        node->hi[d] = chi[d] = -INFINITY;
    }
    for (int k = 0; k < count; k++) {
        const double *b = box + 6 * (size_t)o[k], *c = centre + 3 * (size_t)o[k];
        for (int d = 0; d < 3; d++) {
            if (b[d] < node->lo[d]) node->lo[d] = b[d];
            if (b[3 + d] > node->hi[d]) node->hi[d] = b[3 + d];
            if (c[d] < clo[d]) clo[d] = c[d];
            if (c[d] > chi[d]) chi[d] = c[d];
        }
    }
    node->first = first;
    node->count = count;
    node->left = node->right = -1;
    if (count <= PART_LEAF) return id;
    int axis = 0;
    for (int d = 1; d < 3; d++)
        if (chi[d] - clo[d] > chi[axis] - clo[axis]) axis = d;
    int half = count / 2;
    sem_raycast_select_median(o, count, centre, axis);
    int left = build_box_node(nodes, order, box, centre, n_nodes, first, half);
    int right = build_box_node(nodes, order, box, centre, n_nodes, first + half, count - half);
    nodes[id].left = left;
    nodes[id].right = right;
    return id;
}

void sem_raycast_free_part_trees(sem_raycast_scene *s)
{
    free(s->part_nodes);
    free(s->part_tri_order);
    free(s->part_root);
    free(s->top_nodes);
    free(s->top_order);
    s->part_nodes = s->top_nodes = NULL;
    s->part_tri_order = s->part_root = s->top_order = NULL;
}

static int build_part_trees(sem_raycast_scene *s)
{
    int n = s->n_triangles, np = s->n_parts;
    s->part_nodes = malloc((size_t)(2 * n + np) * sizeof *s->part_nodes);
    s->part_tri_order = malloc((size_t)n * sizeof *s->part_tri_order);
    s->part_root = malloc(((size_t)np + 1) * sizeof *s->part_root);
    s->top_nodes = malloc((2 * (size_t)np + 1) * sizeof *s->top_nodes);
    s->top_order = malloc(((size_t)np + 1) * sizeof *s->top_order);
    s->top_root = -1;
    /* boxes and centres of the triangles, then of the parts */
    size_t items = (size_t)(n > np ? n : np) + 1;
    double *box = malloc(6 * items * sizeof *box), *centre = malloc(3 * items * sizeof *centre);
    if (!s->part_nodes || !s->part_tri_order || !s->part_root || !s->top_nodes || !s->top_order || !box ||
        !centre) {
        free(box);
        free(centre);
        sem_raycast_free_part_trees(s);
        return 0;
    }
    for (int t = 0; t < n; t++) {
        s->part_tri_order[t] = t;
        const double *v = s->tri + 9 * (size_t)t;
        for (int d = 0; d < 3; d++) {
            box[6 * (size_t)t + d] = fmin(fmin(v[d], v[3 + d]), v[6 + d]);
            box[6 * (size_t)t + 3 + d] = fmax(fmax(v[d], v[3 + d]), v[6 + d]);
            centre[3 * (size_t)t + d] = (v[d] + v[3 + d] + v[6 + d]) / 3;
        }
    }
    int n_nodes = 0;
    for (int p = 0; p < np; p++) {
        int t0 = s->part_tri_offset[p], t1 = s->part_tri_offset[p + 1];
        s->part_root[p] = t1 > t0 ? build_box_node(s->part_nodes, s->part_tri_order, box, centre, &n_nodes, t0, t1 - t0)
                                  : -1;
    }
    /* the tree over the parts that have triangles (by their boxes' centres) */
    int n_top = 0;
    for (int p = 0; p < np; p++) {
        if (s->part_root[p] < 0) continue;
        const part_node *r = &s->part_nodes[s->part_root[p]];
        for (int d = 0; d < 3; d++) {
            box[6 * (size_t)p + d] = r->lo[d];
            box[6 * (size_t)p + 3 + d] = r->hi[d];
            centre[3 * (size_t)p + d] = 0.5 * (r->lo[d] + r->hi[d]);
        }
        s->top_order[n_top++] = p;
    }
    int n_top_nodes = 0;
    if (n_top > 0) s->top_root = build_box_node(s->top_nodes, s->top_order, box, centre, &n_top_nodes, 0, n_top);
    free(box);
    free(centre);
    return 1;
}

static int ensure_part_trees(const sem_raycast_scene *scene)
{
    if (__atomic_load_n(&scene->parts_built, __ATOMIC_ACQUIRE)) return !scene->parts_failed;
    sem_raycast_scene *s = (sem_raycast_scene *)scene; /* lazily filled cache */
#pragma omp critical(sem_raycast_part_trees)
    {
        if (!__atomic_load_n(&s->parts_built, __ATOMIC_ACQUIRE)) {
            s->parts_failed = !build_part_trees(s);
            __atomic_store_n(&s->parts_built, 1, __ATOMIC_RELEASE);
        }
    }
    return !scene->parts_failed;
}

static double box_distance2(const part_node *node, const double *X)
{
    double d2 = 0;
    for (int d = 0; d < 3; d++) {
        double e = 0;
        if (X[d] < node->lo[d]) e = node->lo[d] - X[d];
        else if (X[d] > node->hi[d]) e = X[d] - node->hi[d];
        d2 += e * e;
    }
    return d2;
}

/* Closest point of one part within radius: returns 1 and fills *dist and q when found.
 * Ties go to the lowest triangle index, so the answer does not depend on the walk. */
static int closest_in_part(const sem_raycast_scene *s, int part, const double *X, double radius,
                           double *dist, double *q)
{
    int root = s->part_root[part];
    if (root < 0) return 0;
    double best = radius, best_q[3] = {0, 0, 0};
    int best_t = -1;
    /* nodes with their box distances (each box is measured once, when pushed) */
    int stack[128], top = 0;
    double stack_d2[128];
    stack_d2[top] = box_distance2(&s->part_nodes[root], X);
    stack[top++] = root;
    while (top > 0) {
        --top;
        const part_node *node = &s->part_nodes[stack[top]];
        if (stack_d2[top] > best * best) continue;
        if (node->left < 0 || top + 2 > 128) {
            for (int k = node->first; k < node->first + node->count; k++) {
                int t = s->part_tri_order[k];
                const double *v = s->tri + 9 * (size_t)t;
                double c[3], w[3];
                closest_point_triangle(X, v, v + 3, v + 6, c);
                sub3(c, X, w);
                double dd = sqrt(dot3(w, w));
                if (dd < best || (dd == best && (best_t < 0 || t < best_t))) {
                    best = dd;
                    best_t = t;
                    memcpy(best_q, c, sizeof c);
                }
            }
            if (node->left >= 0) { /* stack full (never for sane depths): finish exactly */
                stack_d2[top] = box_distance2(&s->part_nodes[node->right], X);
                stack[top++] = node->right;
                stack_d2[top] = box_distance2(&s->part_nodes[node->left], X);
                stack[top++] = node->left;
            }
            continue;
        }
        const part_node *L = &s->part_nodes[node->left], *R = &s->part_nodes[node->right];
        double dl = box_distance2(L, X), dr = box_distance2(R, X);
        /* push the farther child first so the nearer one is searched first (a child beyond
         * the best distance is not pushed at all) */
        double b2 = best * best;
        int near = dl <= dr ? node->left : node->right, far = dl <= dr ? node->right : node->left;
        double dn = fmin(dl, dr), df = dl <= dr ? dr : dl;
        if (df <= b2) {
            stack_d2[top] = df;
            stack[top++] = far;
        }
        if (dn <= b2) {
            stack_d2[top] = dn;
            stack[top++] = near;
        }
    }
    if (best_t < 0) return 0;
    *dist = best;
    if (q) memcpy(q, best_q, sizeof best_q);
    return 1;
}

int sem_raycast_closest_parts(const sem_raycast_scene *scene, const double X[3], double radius,
                              int *out_parts, double *out_dist, double *out_points)
{
    return sem_raycast_closest_parts_except(scene, X, radius, -1, out_parts, out_dist, out_points);
}

int sem_raycast_closest_parts_except(const sem_raycast_scene *scene, const double X[3], double radius,
                                     int exclude, int *out_parts, double *out_dist, double *out_points)
{
    if (!scene || !X || !out_parts || !out_dist || scene->n_triangles == 0 || !(radius >= 0))
        return 0;
    if (!ensure_part_trees(scene)) {
        int found = sem_raycast_closest_parts_embree(scene, X, radius, out_parts, out_dist,
                                                     out_points);
        int n = 0;
        for (int k = 0; k < found; ++k) {
            if (out_parts[k] == exclude) continue;
            out_parts[n] = out_parts[k];
            out_dist[n] = out_dist[k];
            if (out_points) memmove(out_points + 3 * (size_t)n, out_points + 3 * (size_t)k, 3 * sizeof(double));
            n++;
        }
        return n;
    }
    /* the parts whose root box is within the radius, from the tree over parts, in index
     * order (out_parts is their scratch until the results overwrite it in place) */
    int n_cand = 0;
    if (scene->top_root >= 0) {
        int stack[128], top = 0;
        stack[top++] = scene->top_root;
        while (top > 0) {
            const part_node *node = &scene->top_nodes[stack[--top]];
            if (box_distance2(node, X) > radius * radius) continue;
            if (node->left < 0 || top + 2 > 128) {
                for (int k = node->first; k < node->first + node->count; k++) {
                    int p = scene->top_order[k];
                    if (p != exclude && box_distance2(&scene->part_nodes[scene->part_root[p]], X) <= radius * radius)
                        out_parts[n_cand++] = p;
                }
                if (node->left >= 0) { /* stack full (never for sane depths): finish exactly */
                    stack[top++] = node->right;
                    stack[top++] = node->left;
                }
                continue;
            }
            stack[top++] = node->right;
            stack[top++] = node->left;
        }
    }
    for (int a = 1; a < n_cand; ++a) { /* insertion sort: few candidates */
        int v = out_parts[a], c = a - 1;
        while (c >= 0 && out_parts[c] > v) {
            out_parts[c + 1] = out_parts[c];
            --c;
        }
        out_parts[c + 1] = v;
    }
    int n = 0;
    for (int k = 0; k < n_cand; k++) {
        int p = out_parts[k];
        double d, q[3];
        if (!closest_in_part(scene, p, X, radius, &d, q)) continue;
        out_parts[n] = p;
        out_dist[n] = d;
        if (out_points) memcpy(out_points + 3 * (size_t)n, q, sizeof q);
        n++;
    }
    return n;
}
