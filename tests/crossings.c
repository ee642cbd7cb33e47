/*
 * crossings.c - intersecting triangles of a deformed mesh (see crossings.h).
 */
#include "crossings.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "contact/narrow_phase.h"
#include "geometry/point_triangle.h"
#include "io/mesh_obj_read.h"

typedef struct box {
    double lo[3], hi[3];
    int t;
} box;

static int compare_box(const void *a, const void *b)
{
    double x = ((const box *)a)->lo[0], y = ((const box *)b)->lo[0];
    return (x > y) - (x < y);
}

static void sub(const double *a, const double *b, double *r)
{
    for (int k = 0; k < 3; ++k) r[k] = a[k] - b[k];
}

static void cross(const double *a, const double *b, double *r)
{
    r[0] = a[1] * b[2] - a[2] * b[1];
    r[1] = a[2] * b[0] - a[0] * b[2];
    r[2] = a[0] * b[1] - a[1] * b[0];
}

static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Does the open segment p q pass through the interior or boundary of triangle a b c? */
static int segment_hits(const double *p, const double *q, const double *a, const double *b, const double *c)
{
    double e1[3], e2[3], n[3], dp[3], dq[3];
    sub(b, a, e1);
    sub(c, a, e2);
    cross(e1, e2, n);
    sub(p, a, dp);
    sub(q, a, dq);
    double sp = dot(n, dp), sq = dot(n, dq);
    if ((sp > 0 && sq > 0) || (sp < 0 && sq < 0) || sp == sq) return 0; /* one side, or in the plane */
    double s = sp / (sp - sq), x[3];
    for (int k = 0; k < 3; ++k) x[k] = p[k] + s * (q[k] - p[k]);
    /* x inside a b c: the three sub-triangles turn the way n does */
    const double *v[3] = {a, b, c};
    for (int i = 0; i < 3; ++i) {
        double e[3], w[3], m[3];
        sub(v[(i + 1) % 3], v[i], e);
        sub(x, v[i], w);
        cross(e, w, m);
        if (dot(m, n) < 0) return 0;
    }
    return 1;
}

static int triangles_cross(const double *x, const int *s, const int *t)
{
    for (int pass = 0; pass < 2; ++pass) {
        const int *e = pass ? t : s, *f = pass ? s : t;
        for (int i = 0; i < 3; ++i)
            if (segment_hits(x + 3 * (size_t)e[i], x + 3 * (size_t)e[(i + 1) % 3], x + 3 * (size_t)f[0],
                             x + 3 * (size_t)f[1], x + 3 * (size_t)f[2]))
                return 1;
    }
    return 0;
}

static int touch_at_rest(const double *x0, const int *s, const int *t, double tol2)
{
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double d[3];
            sub(x0 + 3 * (size_t)s[i], x0 + 3 * (size_t)t[j], d);
            if (dot(d, d) <= tol2) return 1;
        }
    return 0;
}

/* The distance between triangles s and t at x (the least of their vertex-triangle and
 * edge-edge distances). */
static double triangle_distance(const double *x, const int *s, const int *t)
{
    double best = INFINITY;
    for (int side = 0; side < 2; ++side) {
        const int *a = side ? t : s, *b = side ? s : t;
        for (int i = 0; i < 3; ++i) {
            sem_tri_closest c;
            sem_point_triangle_closest(x + 3 * (size_t)a[i], x + 3 * (size_t)b[0], x + 3 * (size_t)b[1],
                                       x + 3 * (size_t)b[2], &c);
            best = fmin(best, c.dist2);
        }
    }
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            double u, v;
            best = fmin(best, sem_segment_closest(x + 3 * (size_t)s[i], x + 3 * (size_t)s[(i + 1) % 3],
                                                  x + 3 * (size_t)t[j], x + 3 * (size_t)t[(j + 1) % 3], &u, &v));
        }
    return sqrt(best);
}

long count_crossings(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles)
{
    return count_crossings_apart(x0, x, n_vertices, triangles, n_triangles, 0);
}

long count_crossings_apart(const double *x0, const double *x, int n_vertices, const int *triangles, int n_triangles,
                           double apart)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int v = 0; v < n_vertices; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], x0[3 * v + k]);
            hi[k] = fmax(hi[k], x0[3 * v + k]);
        }
    double size2 = 0;
    for (int k = 0; k < 3; ++k) size2 += (hi[k] - lo[k]) * (hi[k] - lo[k]);
    double tol2 = 1e-18 * size2;
    box *b = malloc(((size_t)n_triangles + 1) * sizeof *b);
    if (!b) return -1;
    for (int t = 0; t < n_triangles; ++t) {
        b[t].t = t;
        for (int k = 0; k < 3; ++k) {
            b[t].lo[k] = INFINITY;
            b[t].hi[k] = -INFINITY;
        }
        for (int i = 0; i < 3; ++i)
            for (int k = 0; k < 3; ++k) {
                double c = x[3 * (size_t)triangles[3 * t + i] + k];
                b[t].lo[k] = fmin(b[t].lo[k], c);
                b[t].hi[k] = fmax(b[t].hi[k], c);
            }
    }
    qsort(b, (size_t)n_triangles, sizeof *b, compare_box);
    long count = 0;
    for (int i = 0; i < n_triangles; ++i)
        for (int j = i + 1; j < n_triangles && b[j].lo[0] <= b[i].hi[0]; ++j) {
            if (b[j].lo[1] > b[i].hi[1] || b[i].lo[1] > b[j].hi[1] || b[j].lo[2] > b[i].hi[2] ||
                b[i].lo[2] > b[j].hi[2])
                continue;
            const int *s = triangles + 3 * (size_t)b[i].t, *t = triangles + 3 * (size_t)b[j].t;
            if (touch_at_rest(x0, s, t, tol2)) continue;
            if (triangles_cross(x, s, t) && !triangles_cross(x0, s, t) &&
                !(apart > 0 && triangle_distance(x0, s, t) < apart))
                ++count;
        }
    free(b);
    return count;
}

/* ---- a run's frames ---- */

/* The part (an OBJ group, numbered across the objects from first) of each of the file's
 * vertices, into part (at most n_max); their count in *n_read; returns the next part number,
 * -1 when unreadable. sem's render meshes write each part's group line, then its vertices
 * and faces. */
static int vertex_parts(const char *path, int first, int *part, int n_max, int *n_read)
{
    FILE *f = fopen(path, "r");
    *n_read = 0;
    if (!f) return -1;
    char line[512];
    int current = first - 1, n = 0;
    while (fgets(line, sizeof line, f)) {
        if (line[0] == 'g' && line[1] == ' ') current++;
        if (line[0] == 'v' && line[1] == ' ' && n < n_max) part[n++] = current < first ? first : current;
    }
    fclose(f);
    *n_read = n;
    return current + 1;
}

/* frame k's mesh of object o of n_objects (sem run's names) */
static void frame_path(const char *dir, int k, int o, int n_objects, char *path, size_t size)
{
    if (n_objects == 1)
        snprintf(path, size, "%s/frame_%04d_mesh.obj", dir, k);
    else
        snprintf(path, size, "%s/frame_%04d_object%d_mesh.obj", dir, k, o);
}

/* Frame k's meshes of all objects as one soup (objects' vertices one after the other). */
static int read_frame(const char *dir, int k, int n_objects, sem_triangle_soup *out)
{
    memset(out, 0, sizeof *out);
    for (int o = 0; o < n_objects; ++o) {
        char path[1200];
        frame_path(dir, k, o, n_objects, path, sizeof path);
        sem_triangle_soup part;
        sem_error err;
        if (sem_obj_triangles_read(path, &part, NULL, &err) != SEM_OK) {
            sem_triangle_soup_free(out);
            return -1;
        }
        double *v = realloc(out->vertices, 3 * (size_t)(out->n_vertices + part.n_vertices) * sizeof(double));
        int *t = realloc(out->triangles, 3 * (size_t)(out->n_triangles + part.n_triangles) * sizeof(int));
        if (v) out->vertices = v;
        if (t) out->triangles = t;
        if (!v || !t) {
            sem_triangle_soup_free(&part);
            sem_triangle_soup_free(out);
            return -1;
        }
        memcpy(out->vertices + 3 * (size_t)out->n_vertices, part.vertices, 3 * (size_t)part.n_vertices * sizeof(double));
        for (int i = 0; i < 3 * part.n_triangles; ++i)
            out->triangles[3 * (size_t)out->n_triangles + (size_t)i] = part.triangles[i] + out->n_vertices;
        out->n_vertices += part.n_vertices;
        out->n_triangles += part.n_triangles;
        sem_triangle_soup_free(&part);
    }
    return 0;
}

long run_crossings(const char *dir, int frames, int n_objects, double apart, int *worst)
{
    sem_triangle_soup rest, frame;
    if (read_frame(dir, 0, n_objects, &rest) != 0) return -1;
    int n = rest.n_vertices, *part = malloc(((size_t)n + 1) * sizeof(int)), *rep = malloc(((size_t)n + 1) * sizeof(int));
    int *count = calloc((size_t)n + 1, sizeof(int));
    double *sum = malloc(3 * ((size_t)n + 1) * sizeof(double));
    if (!part || !rep || !count || !sum) {
        free(part), free(rep), free(count), free(sum);
        sem_triangle_soup_free(&rest);
        return -1;
    }
    for (int o = 0, next = 0, offset = 0; o < n_objects; ++o) {
        char path[1200];
        int nv;
        frame_path(dir, 0, o, n_objects, path, sizeof path);
        next = vertex_parts(path, next, part + offset, n - offset, &nv);
        offset += nv;
    }
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int v = 0; v < n; ++v)
        for (int c = 0; c < 3; ++c) {
            lo[c] = fmin(lo[c], rest.vertices[3 * (size_t)v + c]);
            hi[c] = fmax(hi[c], rest.vertices[3 * (size_t)v + c]);
        }
    double tol = 1e-9 * sqrt(pow(hi[0] - lo[0], 2) + pow(hi[1] - lo[1], 2) + pow(hi[2] - lo[2], 2));
    for (int v = 0; v < n; ++v) {
        rep[v] = v;
        for (int u = 0; u < v && rep[v] == v; ++u) {
            if (part[u] != part[v] || rep[u] != u) continue;
            double d2 = 0;
            for (int c = 0; c < 3; ++c) d2 += pow(rest.vertices[3 * (size_t)u + c] - rest.vertices[3 * (size_t)v + c], 2);
            if (d2 <= tol * tol) rep[v] = u;
        }
    }
    long total = 0, most = 0;
    *worst = -1;
    for (int k = 0; k <= frames; ++k) {
        if (read_frame(dir, k, n_objects, &frame) != 0) {
            total = -1;
            break;
        }
        if (frame.n_vertices == n) {
            memset(count, 0, (size_t)n * sizeof(int));
            memset(sum, 0, 3 * (size_t)n * sizeof(double));
            for (int v = 0; v < n; ++v) {
                count[rep[v]]++;
                for (int c = 0; c < 3; ++c) sum[3 * (size_t)rep[v] + c] += frame.vertices[3 * (size_t)v + c];
            }
            for (int v = 0; v < n; ++v)
                for (int c = 0; c < 3; ++c)
                    frame.vertices[3 * (size_t)v + c] = sum[3 * (size_t)rep[v] + c] / count[rep[v]];
        }
        long c = frame.n_vertices == n ? count_crossings_apart(rest.vertices, frame.vertices, rest.n_vertices,
                                                               rest.triangles, rest.n_triangles, apart)
                                       : -1;
        sem_triangle_soup_free(&frame);
        if (c < 0) {
            total = -1;
            break;
        }
        if (c > most) {
            most = c;
            *worst = k;
        }
        total += c;
    }
    sem_triangle_soup_free(&rest);
    free(part), free(rep), free(count), free(sum);
    return total;
}
