/*
 * collision_mesh.c - an object's contact points as rows of x = J q (see collision_mesh.h).
 */
#include "collision_mesh.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/tessellate.h"

#include "collision_topology.h"
#include "geometry/weld_points.h"
#include "narrow_phase.h"
#include "util/free_all.h"

/* Points closer than this x the object size at rest are one point of the surface. */
#define WELD_TOLERANCE 1e-4

/* Cells per knot span so that triangle edges are at most about L / 16 (2..16). */
static int automatic_resolution(const sem_model *model, double L, sem_error *err, int *out)
{
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    sem_status st = sem_mesh_from_model(model, 1, &mesh, err);
    if (st != SEM_OK) return st;
    double longest = 0;
    for (int t = 0; t < mesh.n_triangles; ++t)
        for (int e = 0; e < 3; ++e) {
            const double *a = mesh.positions + 3 * (size_t)mesh.triangles[3 * t + e];
            const double *b = mesh.positions + 3 * (size_t)mesh.triangles[3 * t + (e + 1) % 3];
            double d = sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                            (a[2] - b[2]) * (a[2] - b[2]));
            if (d > longest) longest = d;
        }
    sem_mesh_free(&mesh);
    int r = L > 0 ? (int)ceil(longest / (L / 16.0)) : 2;
    *out = r < 2 ? 2 : r > 16 ? 16 : r;
    return SEM_OK;
}

/* Signed volume of triangle t seen from centre (x 6). */
static double triangle_volume(const sem_collision_mesh *m, int t, const double centre[3])
{
    const int *tri = m->triangles + 3 * (size_t)t;
    double a[3], b[3], c[3];
    for (int k = 0; k < 3; ++k) {
        a[k] = m->x[3 * (size_t)tri[0] + k] - centre[k];
        b[k] = m->x[3 * (size_t)tri[1] + k] - centre[k];
        c[k] = m->x[3 * (size_t)tri[2] + k] - centre[k];
    }
    return a[0] * (b[1] * c[2] - b[2] * c[1]) + a[1] * (b[2] * c[0] - b[0] * c[2]) + a[2] * (b[0] * c[1] - b[1] * c[0]);
}

/* 1 when triangle u runs through the welded edge a -> b in the same direction */
static int same_direction(const sem_collision_mesh *m, int u, int a, int b)
{
    const int *tri = m->triangles + 3 * (size_t)u;
    for (int v = 0; v < 3; ++v)
        if (m->weld[tri[v]] == a && m->weld[tri[(v + 1) % 3]] == b) return 1;
    return 0;
}

typedef struct part_link {
    int p, q, vote; /* parts p < q sharing an edge; +1 consistent, -1 opposite */
} part_link;

static int compare_link(const void *x, const void *y)
{
    const part_link *a = x, *b = y;
    if (a->p != b->p) return (a->p > b->p) - (a->p < b->p);
    return (a->q > b->q) - (a->q < b->q);
}

/* Each point's copies (copy_start, copy_point): the points of its weld group on its own part.
 * The weld groups are gathered first (a counting sort by representative), then each point
 * lists the members of its group with its part. */
static sem_status find_copies(sem_collision_mesh *m, const int *point_part, sem_error *err)
{
    const int n = m->n_points;
    int *group_start = calloc((size_t)n + 2, sizeof(int)), *group_member = malloc(((size_t)n + 1) * sizeof(int));
    int *fill = malloc(((size_t)n + 1) * sizeof(int));
    m->copy_start = calloc((size_t)n + 2, sizeof(int));
    if (!group_start || !group_member || !fill || !m->copy_start) {
        SEM_FREE_ALL(group_start, group_member, fill);
        return sem_error_set(err, SEM_ERR_NOMEM, "contact: out of memory");
    }
    for (int p = 0; p < n; ++p) group_start[m->weld[p] + 1]++;
    for (int p = 0; p < n; ++p) group_start[p + 1] += group_start[p];
    memcpy(fill, group_start, (size_t)n * sizeof(int));
    for (int p = 0; p < n; ++p) group_member[fill[m->weld[p]]++] = p;
    for (int pass = 0; pass < 2; ++pass) {
        for (int p = 0; p < n; ++p) {
            int g = m->weld[p], count = 0;
            for (int k = group_start[g]; k < group_start[g + 1]; ++k) {
                int q = group_member[k];
                if (point_part[q] != point_part[p]) continue;
                if (pass == 1) m->copy_point[m->copy_start[p] + count] = q;
                ++count;
            }
            if (pass == 0) m->copy_start[p + 1] = m->copy_start[p] + count;
        }
        if (pass == 0 && !(m->copy_point = malloc(((size_t)m->copy_start[n] + 1) * sizeof(int)))) {
            SEM_FREE_ALL(group_start, group_member, fill);
            return sem_error_set(err, SEM_ERR_NOMEM, "contact: out of memory");
        }
    }
    SEM_FREE_ALL(group_start, group_member, fill);
    return SEM_OK;
}

/* One row for every copy: the mean of the copies' rows (entries by control point, in order of
 * control point). At rest the copies are one point; with their own rows they move apart as the
 * control points of a collapsed edge do (a sphere's pole, whose control points are free), so
 * the fan of triangles at the pole opens into slivers whose orientation is noise and the copy
 * a query finds changes from one Newton iterate to the next (a ball pressed pole-first onto a
 * box did not converge: relative gradient 0.85). With one row they stay one point: the
 * collision surface at the pole follows the mean of the collapsed control points. Points
 * without copies keep their rows as they are. */
static sem_status merge_copy_rows(sem_collision_mesh *m, sem_error *err)
{
    const int n = m->n_points;
    int widest = 0; /* the most row entries of one point's copies; 0: no point has copies */
    for (int p = 0; p < n; ++p) {
        int count = m->copy_start[p + 1] - m->copy_start[p], entries = 0;
        if (count < 2) continue;
        for (int k = m->copy_start[p]; k < m->copy_start[p + 1]; ++k)
            entries += m->row_start[m->copy_point[k] + 1] - m->row_start[m->copy_point[k]];
        if (entries > widest) widest = entries;
    }
    if (widest == 0) return SEM_OK;
    int *start = malloc(((size_t)n + 1) * sizeof(int)), *ctrl = NULL, *tmp_ctrl = malloc(((size_t)widest + 1) * sizeof(int));
    double *w = NULL, *tmp_w = malloc(((size_t)widest + 1) * sizeof(double));
    size_t total = 0;
    int ok = start && tmp_ctrl && tmp_w;
    for (int pass = 0; ok && pass < 2; ++pass) {
        total = 0;
        for (int p = 0; p < n; ++p) {
            int count = m->copy_start[p + 1] - m->copy_start[p], len = 0;
            if (count < 2) {
                len = m->row_start[p + 1] - m->row_start[p];
                if (pass == 1) {
                    memcpy(ctrl + total, m->row_ctrl + m->row_start[p], (size_t)len * sizeof(int));
                    memcpy(w + total, m->row_w + m->row_start[p], (size_t)len * sizeof(double));
                }
            } else {
                /* the union of the copies' control points, sorted (insertion: a few dozen) */
                for (int k = m->copy_start[p]; k < m->copy_start[p + 1]; ++k) {
                    int q = m->copy_point[k];
                    for (int e = m->row_start[q]; e < m->row_start[q + 1]; ++e) {
                        int c = m->row_ctrl[e], at = len;
                        while (at > 0 && tmp_ctrl[at - 1] > c) --at;
                        if (at > 0 && tmp_ctrl[at - 1] == c) {
                            tmp_w[at - 1] += m->row_w[e];
                            continue;
                        }
                        memmove(tmp_ctrl + at + 1, tmp_ctrl + at, (size_t)(len - at) * sizeof(int));
                        memmove(tmp_w + at + 1, tmp_w + at, (size_t)(len - at) * sizeof(double));
                        tmp_ctrl[at] = c;
                        tmp_w[at] = m->row_w[e];
                        ++len;
                    }
                }
                if (pass == 1)
                    for (int e = 0; e < len; ++e) {
                        ctrl[total + (size_t)e] = tmp_ctrl[e];
                        w[total + (size_t)e] = tmp_w[e] / count;
                    }
            }
            if (pass == 0) start[p] = (int)total;
            total += (size_t)len;
        }
        if (pass == 0) {
            start[n] = (int)total;
            ctrl = malloc((total + 1) * sizeof(int));
            w = malloc((total + 1) * sizeof(double));
            ok = ctrl && w && total <= INT_MAX;
        }
    }
    SEM_FREE_ALL(tmp_ctrl, tmp_w);
    if (!ok) {
        SEM_FREE_ALL(start, ctrl, w);
        return sem_error_set(err, SEM_ERR_NOMEM, "contact: out of memory");
    }
    SEM_FREE_ALL(m->row_start, m->row_ctrl, m->row_w);
    m->row_start = start;
    m->row_ctrl = ctrl;
    m->row_w = w;
    return SEM_OK;
}

/* Turns parts so that they face away from the object's inside. A part's (u, v) orientation
 * is the modeller's; the signs of distances need outward normals. Parts that share edges
 * are first made consistent with each other (the majority of their shared edges decides),
 * then each group of connected parts is turned as a whole when it encloses a negative volume
 * seen from the surface's point centroid (exact for a closed group; for a part alone it is
 * the heuristic it always was, exact for star-shaped bodies). The preprocessing's own
 * orientation fix is not part of the discretization. Leaves edge_other for the turned
 * triangles. */
static sem_status orient_parts(sem_collision_mesh *m, const sem_mesh *mesh, sem_error *err)
{
    int np = mesh->n_parts, nt = m->n_triangles;
    int *tri_part = malloc(((size_t)nt + 1) * sizeof(int));
    int *flip = malloc(((size_t)np + 1) * sizeof(int)), *group = malloc(((size_t)np + 1) * sizeof(int));
    int *queue = malloc(((size_t)np + 1) * sizeof(int)), *first = malloc(((size_t)np + 2) * sizeof(int));
    double *volume = calloc((size_t)np + 1, sizeof(double));
    part_link *links = malloc((3 * (size_t)nt + 1) * sizeof *links);
    sem_status st = SEM_OK;
    if (!tri_part || !flip || !group || !queue || !first || !volume || !links) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collision mesh");
        goto done;
    }
    if ((st = sem_collision_edge_neighbours(m->triangles, nt, m->weld, m->edge_other, err)) != SEM_OK) goto done;
    for (int p = 0; p < np; ++p)
        for (int t = mesh->part_triangle_start[p]; t < mesh->part_triangle_start[p + 1]; ++t) tri_part[t] = p;
    /* the votes of the edges between parts, summed per pair of parts */
    size_t nl = 0;
    for (int t = 0; t < nt; ++t)
        for (int e = 0; e < 3; ++e) {
            int u = m->edge_other[3 * (size_t)t + (size_t)e];
            if (u < 0 || tri_part[u] == tri_part[t] || tri_part[u] < tri_part[t]) continue;
            int a = m->weld[m->triangles[3 * (size_t)t + (size_t)e]];
            int b = m->weld[m->triangles[3 * (size_t)t + (size_t)(e + 1) % 3]];
            links[nl++] = (part_link){tri_part[t], tri_part[u], same_direction(m, u, a, b) ? -1 : 1};
        }
    qsort(links, nl, sizeof *links, compare_link);
    size_t nk = 0;
    for (size_t i = 0; i < nl;) {
        size_t j = i;
        int vote = 0;
        while (j < nl && links[j].p == links[i].p && links[j].q == links[i].q) vote += links[j++].vote;
        if (vote != 0) links[nk++] = (part_link){links[i].p, links[i].q, vote > 0 ? 1 : -1};
        i = j;
    }
    /* both directions of each link, grouped by part (first[p] .. first[p + 1]) */
    part_link *adj = malloc((2 * nk + 1) * sizeof *adj);
    if (!adj) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collision mesh");
        goto done;
    }
    for (size_t i = 0; i < nk; ++i) {
        adj[2 * i] = links[i];
        adj[2 * i + 1] = (part_link){links[i].q, links[i].p, links[i].vote};
    }
    qsort(adj, 2 * nk, sizeof *adj, compare_link);
    for (int p = 0, i = 0; p <= np; ++p) {
        while ((size_t)i < 2 * nk && adj[i].p < p) ++i;
        first[p] = i;
    }
    /* connected parts: relative turns by breadth-first search */
    for (int p = 0; p < np; ++p) group[p] = -1;
    for (int root = 0; root < np; ++root) {
        if (group[root] >= 0) continue;
        int head = 0, tail = 0;
        group[root] = root;
        flip[root] = 0;
        queue[tail++] = root;
        while (head < tail) {
            int p = queue[head++];
            for (int i = first[p]; i < first[p + 1]; ++i) {
                int q = adj[i].q;
                if (group[q] >= 0) continue;
                group[q] = root;
                flip[q] = flip[p] ^ (adj[i].vote < 0);
                queue[tail++] = q;
            }
        }
    }
    free(adj);
    /* each group's volume with its relative turns, seen from the points' centroid */
    double centre[3] = {0, 0, 0};
    for (int i = 0; i < m->n_points; ++i)
        for (int k = 0; k < 3; ++k) centre[k] += m->x[3 * (size_t)i + k];
    for (int k = 0; k < 3 && m->n_points > 0; ++k) centre[k] /= m->n_points;
    for (int t = 0; t < nt; ++t) {
        int p = tri_part[t];
        volume[group[p]] += (flip[p] ? -1 : 1) * triangle_volume(m, t, centre);
    }
    int turned = 0;
    for (int p = 0; p < np; ++p) {
        if (volume[group[p]] < 0) flip[p] ^= 1;
        if (!flip[p]) continue;
        turned = 1;
        for (int t = mesh->part_triangle_start[p]; t < mesh->part_triangle_start[p + 1]; ++t) {
            int x = m->triangles[3 * t + 1];
            m->triangles[3 * t + 1] = m->triangles[3 * t + 2];
            m->triangles[3 * t + 2] = x;
        }
    }
    if (turned) st = sem_collision_edge_neighbours(m->triangles, nt, m->weld, m->edge_other, err);
done:
    SEM_FREE_ALL(tri_part, flip, group, queue, first, volume, links);
    return st;
}

void sem_collision_mesh_positions(const sem_collision_mesh *m, const double *q, double *out)
{
    for (int p = 0; p < m->n_points; ++p) {
        double x[3] = {0, 0, 0};
        for (int e = m->row_start[p]; e < m->row_start[p + 1]; ++e) {
            const double *qc = q + 3 * (size_t)m->row_ctrl[e];
            for (int k = 0; k < 3; ++k) x[k] += m->row_w[e] * qc[k];
        }
        memcpy(out + 3 * (size_t)p, x, sizeof x);
    }
}

/* x = J q for every point */
static void update_positions(sem_collision_mesh *m, const double *q) { sem_collision_mesh_positions(m, q, m->x); }

/* Face normals at the current x, and each corner's angle x its face normal summed at its
 * welded point (the angle-weighted pseudonormal) */
static void update_normals(sem_collision_mesh *m)
{
    memset(m->pseudo_normal, 0, 3 * (size_t)m->n_points * sizeof(double));
    for (int t = 0; t < m->n_triangles; ++t) {
        const int *tri = m->triangles + 3 * t;
        const double *x[3] = {m->x + 3 * (size_t)tri[0], m->x + 3 * (size_t)tri[1], m->x + 3 * (size_t)tri[2]};
        double e1[3] = {x[1][0] - x[0][0], x[1][1] - x[0][1], x[1][2] - x[0][2]};
        double e2[3] = {x[2][0] - x[0][0], x[2][1] - x[0][1], x[2][2] - x[0][2]};
        double *n = m->face_normal + 3 * (size_t)t;
        n[0] = e1[1] * e2[2] - e1[2] * e2[1];
        n[1] = e1[2] * e2[0] - e1[0] * e2[2];
        n[2] = e1[0] * e2[1] - e1[1] * e2[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        if (!(l > 0)) continue; /* a degenerate triangle has no direction */
        for (int k = 0; k < 3; ++k) n[k] /= l;
        for (int v = 0; v < 3; ++v) {
            const double *o = x[v], *a = x[(v + 1) % 3], *b = x[(v + 2) % 3];
            double u[3] = {a[0] - o[0], a[1] - o[1], a[2] - o[2]}, w[3] = {b[0] - o[0], b[1] - o[1], b[2] - o[2]};
            double c[3] = {u[1] * w[2] - u[2] * w[1], u[2] * w[0] - u[0] * w[2], u[0] * w[1] - u[1] * w[0]};
            double angle = atan2(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]), u[0] * w[0] + u[1] * w[1] + u[2] * w[2]);
            double *pn = m->pseudo_normal + 3 * (size_t)m->weld[tri[v]];
            for (int k = 0; k < 3; ++k) pn[k] += angle * n[k];
        }
    }
    for (int p = 0; p < m->n_points; ++p)
        if (m->weld[p] != p) memcpy(m->pseudo_normal + 3 * (size_t)p, m->pseudo_normal + 3 * (size_t)m->weld[p],
                                    3 * sizeof(double));
}

void sem_collision_mesh_free(sem_collision_mesh *m)
{
    SEM_FREE_ALL(m->row_start, m->row_ctrl, m->row_w, m->area, m->triangles, m->x, m->x0, m->pseudo_normal,
                 m->face_normal, m->weld, m->edge_other, m->copy_start, m->copy_point, m->edge_tri);
    sem_bvh_free(&m->bvh);
    sem_bvh_free(&m->edge_bvh);
    memset(m, 0, sizeof *m);
}

sem_status sem_collision_mesh_build(const sem_model *model, int resolution, sem_collision_mesh *out,
                                    sem_error *err)
{
    memset(out, 0, sizeof *out);
    size_t n_ctrl = sem_model_control_points(model);
    double *q = malloc(3 * n_ctrl * sizeof(double) + 1);
    size_t *part_offset = malloc(((size_t)model->n_parts + 1) * sizeof(size_t));
    if (!q || !part_offset) {
        free(q);
        free(part_offset);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_model_get_q(model, q);
    sem_model_part_offsets(model, part_offset);
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t c = 0; c < n_ctrl; ++c)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], q[3 * c + k]);
            hi[k] = fmax(hi[k], q[3 * c + k]);
        }
    out->length = n_ctrl ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                (hi[2] - lo[2]) * (hi[2] - lo[2]))
                         : 0;
    sem_status st = SEM_OK;
    sem_mesh_template *tmpl = NULL;
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    int *index = NULL, *used = NULL;
    double *phi = NULL;
    int *point_part = NULL;
    if (resolution <= 0 && (st = automatic_resolution(model, out->length, err, &resolution)) != SEM_OK)
        goto done;
    out->resolution = resolution;
    if ((st = sem_mesh_template_build(model, resolution, &tmpl, err)) != SEM_OK) goto done;
    if ((st = sem_mesh_template_mesh(tmpl, &mesh, err)) != SEM_OK) goto done;
    int max_basis = 1;
    for (int p = 0; p < model->n_parts; ++p) {
        const sem_surface *s = &model->parts[p].surface;
        int nb = (s->degree_u + 1) * (s->degree_v + 1);
        if (nb > max_basis) max_basis = nb;
    }
    index = malloc((size_t)max_basis * sizeof(int));
    phi = malloc((size_t)max_basis * sizeof(double));
    used = malloc(((size_t)mesh.n_vertices + 1) * sizeof(int));
    if (!index || !phi || !used) goto nomem;
    /* points: the vertices some triangle uses, numbered in vertex order */
    for (int v = 0; v < mesh.n_vertices; ++v) used[v] = -1;
    for (int t = 0; t < 3 * mesh.n_triangles; ++t) used[mesh.triangles[t]] = 0;
    for (int v = 0; v < mesh.n_vertices; ++v)
        if (used[v] == 0) used[v] = out->n_points++;
    size_t np = (size_t)out->n_points + 1;
    out->row_start = malloc((np + 1) * sizeof(int));
    out->row_ctrl = malloc(np * (size_t)max_basis * sizeof(int));
    out->row_w = malloc(np * (size_t)max_basis * sizeof(double));
    out->area = calloc(np, sizeof(double));
    out->x = calloc(3 * np, sizeof(double));
    out->pseudo_normal = calloc(3 * np, sizeof(double));
    out->weld = malloc(np * sizeof(int));
    point_part = malloc(np * sizeof(int));
    out->face_normal = calloc(3 * (size_t)mesh.n_triangles + 1, sizeof(double));
    out->edge_other = malloc((3 * (size_t)mesh.n_triangles + 1) * sizeof(int));
    out->n_triangles = mesh.n_triangles;
    out->triangles = malloc((3 * (size_t)mesh.n_triangles + 1) * sizeof(int));
    if (!out->row_start || !out->row_ctrl || !out->row_w || !out->area || !out->x || !out->pseudo_normal ||
        !out->triangles || !out->weld || !out->face_normal || !out->edge_other || !point_part)
        goto nomem;
    out->row_start[0] = 0;
    int part = 0;
    for (int v = 0; v < mesh.n_vertices; ++v) {
        if (used[v] < 0) continue;
        while (part + 1 < mesh.n_parts && v >= mesh.part_vertex_start[part + 1]) ++part;
        const sem_surface *s = &model->parts[part].surface;
        int n = sem_surface_basis(s, mesh.uv[2 * v], mesh.uv[2 * v + 1], index, phi, NULL, NULL);
        int r = used[v], start = out->row_start[r], kept = 0;
        point_part[r] = part;
        for (int k = 0; k < n; ++k) {
            if (phi[k] == 0) continue;
            out->row_ctrl[start + kept] = (int)part_offset[part] + index[k];
            out->row_w[start + kept] = phi[k];
            ++kept;
        }
        out->row_start[r + 1] = start + kept;
    }
    for (int t = 0; t < 3 * mesh.n_triangles; ++t) out->triangles[t] = used[mesh.triangles[t]];
    update_positions(out, q);
    if ((st = sem_weld_points(out->x, out->n_points, WELD_TOLERANCE * out->length, out->weld, err)) != SEM_OK ||
        (st = orient_parts(out, &mesh, err)) != SEM_OK || (st = find_copies(out, point_part, err)) != SEM_OK ||
        (st = merge_copy_rows(out, err)) != SEM_OK)
        goto done;
    update_positions(out, q); /* the copies at their one row */
    update_normals(out); /* of the turned triangles */
    for (int t = 0; t < out->n_triangles; ++t) {
        const int *tri = out->triangles + 3 * t;
        const double *a = out->x + 3 * (size_t)tri[0], *b = out->x + 3 * (size_t)tri[1], *c = out->x + 3 * (size_t)tri[2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
        double area = 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; ++k) out->area[tri[k]] += area / 3;
    }
    out->x0 = malloc(3 * (size_t)out->n_points * sizeof(double) + 1);
    if (!out->x0) goto nomem;
    memcpy(out->x0, out->x, 3 * (size_t)out->n_points * sizeof(double));
    if ((st = sem_bvh_build(&out->bvh, out->x, out->triangles, out->n_triangles, err)) != SEM_OK) goto done;
    if ((st = sem_collision_edges(out->triangles, out->n_triangles, out->weld, &out->edge_tri, &out->n_edges, err)) !=
        SEM_OK)
        goto done;
    st = sem_bvh_build(&out->edge_bvh, out->x, out->edge_tri, out->n_edges, err);
    goto done;
nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory for a collision mesh");
done:
    if (st != SEM_OK) sem_collision_mesh_free(out);
    sem_mesh_free(&mesh);
    sem_mesh_template_destroy(tmpl);
    SEM_FREE_ALL(index, phi, used, q, part_offset, point_part);
    return st;
}

void sem_collision_mesh_update(sem_collision_mesh *m, const double *q, int between)
{
    update_positions(m, q);
    if (!between) return;
    update_normals(m);
    sem_bvh_refit(&m->bvh, m->x, m->triangles);
}

void sem_collision_mesh_box(const sem_collision_mesh *m, const double *x1, double grow, double lo[3], double hi[3])
{
    for (int k = 0; k < 3; ++k) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (int p = 0; p < m->n_points; ++p)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], m->x[3 * (size_t)p + k]);
            hi[k] = fmax(hi[k], m->x[3 * (size_t)p + k]);
            if (!x1) continue;
            lo[k] = fmin(lo[k], x1[3 * (size_t)p + k]);
            hi[k] = fmax(hi[k], x1[3 * (size_t)p + k]);
        }
    for (int k = 0; k < 3; ++k) {
        lo[k] -= grow;
        hi[k] += grow;
    }
}

void sem_collision_mesh_outward(const sem_collision_mesh *m, int t, int feature, int index, double out[3])
{
    const double *n = m->face_normal + 3 * (size_t)t;
    if (feature == SEM_TRI_VERTEX) {
        memcpy(out, m->pseudo_normal + 3 * (size_t)m->triangles[3 * (size_t)t + (size_t)index], 3 * sizeof(double));
        return;
    }
    memcpy(out, n, 3 * sizeof(double));
    if (feature == SEM_TRI_EDGE) {
        int u = m->edge_other[3 * (size_t)t + (size_t)index];
        if (u >= 0)
            for (int k = 0; k < 3; ++k) out[k] += m->face_normal[3 * (size_t)u + k];
    }
}
