/*
 * tessellate.c - triangle meshes of NURBS parts (see sem/tessellate.h for the design).
 *
 * The template stores, for every kept sample (u,v), the non-zero rational basis functions
 * phi_k(u,v) and their u- and v-derivatives (Eq. 1 of the paper and its derivatives), so
 * that a frame costs (p_u+1)(p_v+1) multiply-adds per coordinate and vertex:
 *     x = sum_k phi_k P_k,   x_u = sum_k phi_u,k P_k,   x_v = sum_k phi_v,k P_k,
 *     n = x_u x x_v / |x_u x x_v|.
 * This is exact for moving control points because the weights and knots never change.
 * Where x_u x x_v vanishes (a collapsed edge, e.g. a sphere's pole) the normal comes from
 * sem_surface_normal, which takes the limit from inside the domain.
 */
#include "sem/tessellate.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/trim.h"

typedef struct part_template {
    int first_vertex, n_vertices;
    int first_triangle, n_triangles;
    int degree_u, degree_v, n_u, n_v;
    int n_basis;         /* (degree_u + 1)(degree_v + 1) */
    size_t basis_offset; /* first basis entry of the part's first vertex */
} part_template;

struct sem_mesh_template {
    int n_parts;
    part_template *parts;
    int n_vertices, n_triangles;
    double *uv;          /* 2 per vertex */
    int *vertex_part;
    int *triangles;      /* 3 per triangle */
    int *triangle_part;
    int *basis_index;    /* control point index within the part */
    double *phi, *phi_u, *phi_v;
};

void sem_mesh_template_destroy(sem_mesh_template *t)
{
    if (!t) return;
    free(t->parts);
    free(t->uv);
    free(t->vertex_part);
    free(t->triangles);
    free(t->triangle_part);
    free(t->basis_index);
    free(t->phi);
    free(t->phi_u);
    free(t->phi_v);
    free(t);
}

/* Sample values along one direction: `resolution` steps in every non-empty knot span. */
static double *samples(int degree, int n_ctrl, const double *knots, double t0, double t1,
                       int resolution, int *count)
{
    int max_breaks = n_ctrl + 2;
    double *breaks = malloc((size_t)max_breaks * sizeof *breaks);
    if (!breaks) return NULL;
    int nb = sem_knot_breaks(degree, n_ctrl, knots, t0, t1, breaks, max_breaks);
    if (nb < 2) {
        free(breaks);
        return NULL;
    }
    int n = (nb - 1) * resolution + 1;
    double *t = malloc((size_t)n * sizeof *t);
    if (t) {
        int k = 0;
        for (int s = 0; s + 1 < nb; ++s)
            for (int r = 0; r < resolution; ++r)
                t[k++] = breaks[s] + (breaks[s + 1] - breaks[s]) * r / resolution;
        t[k] = breaks[nb - 1];
        *count = n;
    }
    free(breaks);
    return t;
}

/* Capacity of the triangle array while parts are added. */
typedef struct growing {
    size_t triangle_cap;
} growing;

static int grow_exact(void **p, size_t n, size_t elem)
{
    void *q = realloc(*p, (n ? n : 1) * elem);
    if (!q) return 0;
    *p = q;
    return 1;
}

static int reserve(void **p, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return 1;
    size_t nc = *cap ? *cap : 1024;
    while (nc < need) nc *= 2;
    void *q = realloc(*p, nc * elem);
    if (!q) return 0;
    *p = q;
    *cap = nc;
    return 1;
}

static sem_status add_part(sem_mesh_template *t, growing *g, int part_index, const sem_part *part,
                           int resolution, sem_error *err)
{
    const sem_surface *s = &part->surface;
    part_template *pt = &t->parts[part_index];
    pt->first_vertex = t->n_vertices;
    pt->first_triangle = t->n_triangles;
    pt->degree_u = s->degree_u;
    pt->degree_v = s->degree_v;
    pt->n_u = s->n_u;
    pt->n_v = s->n_v;
    pt->n_basis = (s->degree_u + 1) * (s->degree_v + 1);
    pt->basis_offset = part_index == 0
                           ? 0
                           : t->parts[part_index - 1].basis_offset +
                                 (size_t)t->parts[part_index - 1].n_vertices *
                                     (size_t)t->parts[part_index - 1].n_basis;

    int nu = 0, nv = 0;
    double *us = samples(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, resolution, &nu);
    double *vs = samples(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, resolution, &nv);
    int *node = NULL;
    sem_trim_region *region = NULL;
    sem_status st = SEM_OK;
    if (!us || !vs) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory (part %d)", part_index);
        goto done;
    }
    if ((double)nu * (double)nv > (double)(INT_MAX / 8)) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "tessellation: part %d '%s' would need %d x %d samples; lower the "
                           "resolution",
                           part_index, part->name, nu, nv);
        goto done;
    }
    int trimmed = part->has_outer || part->n_holes > 0;
    if (trimmed) {
        sem_error terr;
        if (sem_trim_region_build(part, &region, &terr) != SEM_OK) {
            st = sem_error_set(err, terr.status, "tessellation: part %d '%s': %s", part_index,
                               part->name, terr.message);
            goto done;
        }
    }
    /* node (i,j) -> vertex number, -1 while unused */
    node = malloc((size_t)nu * (size_t)nv * sizeof *node);
    if (!node) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory (part %d)", part_index);
        goto done;
    }
    for (size_t k = 0; k < (size_t)nu * (size_t)nv; ++k) node[k] = -1;

    for (int j = 0; j + 1 < nv; ++j) {
        for (int i = 0; i + 1 < nu; ++i) {
            /* cell corners a=(i,j) b=(i+1,j) c=(i+1,j+1) d=(i,j+1); triangles abc, acd */
            int a = i + nu * j, b = a + 1, c = b + nu, d = a + nu;
            int tri[2][3] = {{a, b, c}, {a, c, d}};
            for (int h = 0; h < 2; ++h) {
                if (region) {
                    double cu = 0, cv = 0;
                    for (int k = 0; k < 3; ++k) {
                        cu += us[tri[h][k] % nu];
                        cv += vs[tri[h][k] / nu];
                    }
                    if (!sem_trim_region_inside(region, cu / 3.0, cv / 3.0)) continue;
                }
                if (t->n_triangles >= INT_MAX / 4 ||
                    !reserve((void **)&t->triangles, &g->triangle_cap,
                             3 * ((size_t)t->n_triangles + 1), sizeof(int))) {
                    st = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
                    goto done;
                }
                for (int k = 0; k < 3; ++k) {
                    int n = tri[h][k];
                    if (node[n] < 0) node[n] = t->n_vertices + pt->n_vertices++;
                    t->triangles[3 * (size_t)t->n_triangles + (size_t)k] = node[n];
                }
                t->n_triangles++;
                pt->n_triangles++;
            }
        }
    }

    /* vertex (u,v) and basis rows: the arrays grow once per part, to the exact size */
    size_t nvert = (size_t)t->n_vertices + (size_t)pt->n_vertices;
    size_t nbasis = pt->basis_offset + (size_t)pt->n_vertices * (size_t)pt->n_basis;
    int ok = grow_exact((void **)&t->uv, 2 * nvert, sizeof(double)) &&
             grow_exact((void **)&t->vertex_part, nvert, sizeof(int)) &&
             grow_exact((void **)&t->basis_index, nbasis, sizeof(int)) &&
             grow_exact((void **)&t->phi, nbasis, sizeof(double)) &&
             grow_exact((void **)&t->phi_u, nbasis, sizeof(double)) &&
             grow_exact((void **)&t->phi_v, nbasis, sizeof(double));
    if (!ok) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
        goto done;
    }
    for (int j = 0; j < nv; ++j) {
        for (int i = 0; i < nu; ++i) {
            int vtx = node[i + nu * j];
            if (vtx < 0) continue;
            t->uv[2 * (size_t)vtx] = us[i];
            t->uv[2 * (size_t)vtx + 1] = vs[j];
            t->vertex_part[vtx] = part_index;
        }
    }
    int first = t->n_vertices, count = pt->n_vertices;
#pragma omp parallel for schedule(static)
    for (int k = 0; k < count; ++k) {
        size_t off = pt->basis_offset + (size_t)k * (size_t)pt->n_basis;
        int vtx = first + k;
        sem_surface_basis(s, t->uv[2 * (size_t)vtx], t->uv[2 * (size_t)vtx + 1],
                          t->basis_index + off, t->phi + off, t->phi_u + off, t->phi_v + off);
    }
    t->n_vertices += pt->n_vertices;

done:
    sem_trim_region_destroy(region);
    free(node);
    free(us);
    free(vs);
    return st;
}

sem_status sem_mesh_template_build(const sem_model *model, int resolution,
                                   sem_mesh_template **out, sem_error *err)
{
    *out = NULL;
    if (!model) return sem_error_set(err, SEM_ERR_INVALID, "tessellation: NULL model");
    if (resolution < 1 || resolution > 4096)
        return sem_error_set(err, SEM_ERR_INVALID, "tessellation: resolution %d out of range 1..4096",
                             resolution);
    for (int i = 0; i < model->n_parts; ++i) {
        sem_error e;
        if (sem_surface_validate(&model->parts[i].surface, &e) != SEM_OK)
            return sem_error_set(err, SEM_ERR_INVALID, "tessellation: part %d '%s': %.900s", i,
                                 model->parts[i].name, e.message);
    }
    sem_mesh_template *t = calloc(1, sizeof *t);
    if (!t) return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    t->n_parts = model->n_parts;
    t->parts = calloc((size_t)(model->n_parts > 0 ? model->n_parts : 1), sizeof *t->parts);
    if (!t->parts) {
        sem_mesh_template_destroy(t);
        return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    }
    growing g = {0};
    for (int i = 0; i < model->n_parts; ++i) {
        sem_status st = add_part(t, &g, i, &model->parts[i], resolution, err);
        if (st != SEM_OK) {
            sem_mesh_template_destroy(t);
            return st;
        }
    }
    t->triangle_part = malloc(((size_t)t->n_triangles + 1) * sizeof *t->triangle_part);
    if (!t->triangle_part) {
        sem_mesh_template_destroy(t);
        return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    }
    for (int i = 0; i < t->n_parts; ++i)
        for (int k = 0; k < t->parts[i].n_triangles; ++k)
            t->triangle_part[t->parts[i].first_triangle + k] = i;
    *out = t;
    return SEM_OK;
}

void sem_mesh_free(sem_mesh *m)
{
    if (!m) return;
    free(m->positions);
    free(m->normals);
    free(m->uv);
    free(m->triangles);
    free(m->triangle_part);
    free(m->part_vertex_start);
    free(m->part_triangle_start);
    memset(m, 0, sizeof *m);
}

sem_status sem_mesh_template_mesh(const sem_mesh_template *t, sem_mesh *m, sem_error *err)
{
    memset(m, 0, sizeof *m);
    size_t nv = (size_t)t->n_vertices, nt = (size_t)t->n_triangles;
    m->n_vertices = t->n_vertices;
    m->n_triangles = t->n_triangles;
    m->n_parts = t->n_parts;
    m->positions = calloc(3 * nv + 1, sizeof(double));
    m->normals = calloc(3 * nv + 1, sizeof(double));
    m->uv = malloc((2 * nv + 1) * sizeof(double));
    m->triangles = malloc((3 * nt + 1) * sizeof(int));
    m->triangle_part = malloc((nt + 1) * sizeof(int));
    m->part_vertex_start = malloc(((size_t)t->n_parts + 1) * sizeof(int));
    m->part_triangle_start = malloc(((size_t)t->n_parts + 1) * sizeof(int));
    if (!m->positions || !m->normals || !m->uv || !m->triangles || !m->triangle_part ||
        !m->part_vertex_start || !m->part_triangle_start) {
        sem_mesh_free(m);
        return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    }
    if (nv) memcpy(m->uv, t->uv, 2 * nv * sizeof(double));
    if (nt) {
        memcpy(m->triangles, t->triangles, 3 * nt * sizeof(int));
        memcpy(m->triangle_part, t->triangle_part, nt * sizeof(int));
    }
    for (int i = 0; i < t->n_parts; ++i) {
        m->part_vertex_start[i] = t->parts[i].first_vertex;
        m->part_triangle_start[i] = t->parts[i].first_triangle;
    }
    m->part_vertex_start[t->n_parts] = t->n_vertices;
    m->part_triangle_start[t->n_parts] = t->n_triangles;
    return SEM_OK;
}

sem_status sem_mesh_update(const sem_mesh_template *t, const sem_model *model, sem_mesh *m,
                           sem_error *err)
{
    if (model->n_parts != t->n_parts || m->n_vertices != t->n_vertices)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "tessellation: the model (%d parts) or mesh (%d vertices) does not "
                             "match the template (%d parts, %d vertices)",
                             model->n_parts, m->n_vertices, t->n_parts, t->n_vertices);
    for (int i = 0; i < t->n_parts; ++i) {
        const sem_surface *s = &model->parts[i].surface;
        const part_template *pt = &t->parts[i];
        if (s->degree_u != pt->degree_u || s->degree_v != pt->degree_v || s->n_u != pt->n_u ||
            s->n_v != pt->n_v)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "tessellation: part %d changed size since the template was built",
                                 i);
    }
    const int n = t->n_vertices;
#pragma omp parallel for schedule(static)
    for (int vtx = 0; vtx < n; ++vtx) {
        int p = t->vertex_part[vtx];
        const part_template *pt = &t->parts[p];
        const sem_surface *s = &model->parts[p].surface;
        size_t off = pt->basis_offset + (size_t)(vtx - pt->first_vertex) * (size_t)pt->n_basis;
        double x[3] = {0, 0, 0}, xu[3] = {0, 0, 0}, xv[3] = {0, 0, 0};
        for (int k = 0; k < pt->n_basis; ++k) {
            const double *P = s->ctrl + 3 * (size_t)t->basis_index[off + k];
            double f = t->phi[off + k], fu = t->phi_u[off + k], fv = t->phi_v[off + k];
            for (int d = 0; d < 3; ++d) {
                x[d] += f * P[d];
                xu[d] += fu * P[d];
                xv[d] += fv * P[d];
            }
        }
        double nrm[3] = {xu[1] * xv[2] - xu[2] * xv[1], xu[2] * xv[0] - xu[0] * xv[2],
                         xu[0] * xv[1] - xu[1] * xv[0]};
        double len = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
        /* Degenerate when |x_u x x_v| is tiny against the larger tangent squared: at a
         * collapsed edge one tangent is rounding noise (its basis derivatives sum to ~1e-16,
         * not 0), so a test relative to |x_u||x_v| would accept a noise normal. */
        double su = xu[0] * xu[0] + xu[1] * xu[1] + xu[2] * xu[2];
        double sv = xv[0] * xv[0] + xv[1] * xv[1] + xv[2] * xv[2];
        if (len > 1e-10 * fmax(su, sv) && len > 0.0) {
            for (int d = 0; d < 3; ++d) nrm[d] /= len;
        } else {
            sem_surface_normal(s, t->uv[2 * (size_t)vtx], t->uv[2 * (size_t)vtx + 1], nrm);
        }
        for (int d = 0; d < 3; ++d) {
            m->positions[3 * (size_t)vtx + (size_t)d] = x[d];
            m->normals[3 * (size_t)vtx + (size_t)d] = nrm[d];
        }
    }
    return SEM_OK;
}

sem_status sem_mesh_from_model(const sem_model *model, int resolution, sem_mesh *out,
                               sem_error *err)
{
    memset(out, 0, sizeof *out);
    sem_mesh_template *t;
    sem_status st = sem_mesh_template_build(model, resolution, &t, err);
    if (st != SEM_OK) return st;
    st = sem_mesh_template_mesh(t, out, err);
    if (st == SEM_OK) st = sem_mesh_update(t, model, out, err);
    if (st != SEM_OK) sem_mesh_free(out);
    sem_mesh_template_destroy(t);
    return st;
}

double sem_mesh_area(const sem_mesh *m)
{
    double area = 0.0;
    for (int k = 0; k < m->n_triangles; ++k) {
        const double *a = m->positions + 3 * (size_t)m->triangles[3 * k];
        const double *b = m->positions + 3 * (size_t)m->triangles[3 * k + 1];
        const double *c = m->positions + 3 * (size_t)m->triangles[3 * k + 2];
        double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
        double e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
        double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                       e1[0] * e2[1] - e1[1] * e2[0]};
        area += 0.5 * sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
    }
    return area;
}
