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
#include "geometry/tessellate_threads.h"
#include "util/free_all.h"
#include "util/threads.h"

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
    int threads;         /* of the parallel loops over parts and vertices (0: OpenMP's default) */
};

void sem_mesh_template_destroy(sem_mesh_template *t)
{
    if (!t) return;
    SEM_FREE_ALL(t->parts, t->uv, t->vertex_part, t->triangles, t->triangle_part, t->basis_index, t->phi, t->phi_u,
                 t->phi_v);
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

/* One part's topology, built independently of the other parts (so parts are tessellated
 * in parallel) and then placed at its offsets in the shared arrays. */
typedef struct part_topology {
    int nu, nv;
    double *us, *vs;      /* sample values */
    int n_vertices, n_triangles;
    int *node;            /* nu x nv: (i,j) -> local vertex number, -1 while unused */
    int *triangles;       /* 3 local vertex numbers per triangle */
    int *vertex_node;     /* n_vertices: node (i + nu j) of each local vertex */
    sem_status status;
    sem_error err;
} part_topology;

static void part_topology_free(part_topology *pt)
{
    SEM_FREE_ALL(pt->us, pt->vs, pt->node, pt->triangles, pt->vertex_node);
    memset(pt, 0, sizeof *pt);
}

/* Does a triangle (3 sample nodes) reach into the trimmed domain: a corner, an edge
 * midpoint or the centroid inside? */
static int reaches_inside(const sem_trim_region *region, const part_topology *pt, const int node[3])
{
    double u[3], v[3];
    for (int k = 0; k < 3; ++k) {
        u[k] = pt->us[node[k] % pt->nu];
        v[k] = pt->vs[node[k] / pt->nu];
        if (sem_trim_region_inside(region, u[k], v[k])) return 1;
    }
    for (int k = 0; k < 3; ++k)
        if (sem_trim_region_inside(region, 0.5 * (u[k] + u[(k + 1) % 3]), 0.5 * (v[k] + v[(k + 1) % 3])))
            return 1;
    return sem_trim_region_inside(region, (u[0] + u[1] + u[2]) / 3.0, (v[0] + v[1] + v[2]) / 3.0);
}

/* Samples and kept triangles of one part. The triangle and vertex numbering (cells in
 * row-major order, vertices numbered when first used) is the same for any thread count. */
static void part_topology_build(const sem_part *part, int part_index, int resolution,
                                int covering, part_topology *pt)
{
    const sem_surface *s = &part->surface;
    sem_error *err = &pt->err;
    sem_trim_region *region = NULL;
    pt->status = SEM_OK;
    pt->us = samples(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, resolution, &pt->nu);
    pt->vs = samples(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, resolution, &pt->nv);
    int nu = pt->nu, nv = pt->nv;
    if (!pt->us || !pt->vs) {
        pt->status = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory (part %d)",
                                   part_index);
        return;
    }
    if ((double)nu * (double)nv > (double)(INT_MAX / 8)) {
        pt->status = sem_error_set(err, SEM_ERR_INVALID,
                                   "tessellation: part %d '%s' would need %d x %d samples; lower "
                                   "the resolution",
                                   part_index, part->name, nu, nv);
        return;
    }
    int trimmed = part->has_outer || part->n_holes > 0;
    if (trimmed) {
        sem_error terr;
        if (sem_trim_region_build(part, &region, &terr) != SEM_OK) {
            pt->status = sem_error_set(err, terr.status, "tessellation: part %d '%s': %s",
                                       part_index, part->name, terr.message);
            return;
        }
    }
    size_t n_nodes = (size_t)nu * (size_t)nv;
    size_t max_tri = 2 * (size_t)(nu - 1) * (size_t)(nv - 1);
    pt->node = malloc(n_nodes * sizeof *pt->node);
    pt->triangles = malloc((3 * max_tri + 1) * sizeof *pt->triangles);
    pt->vertex_node = malloc((n_nodes + 1) * sizeof *pt->vertex_node);
    if (!pt->node || !pt->triangles || !pt->vertex_node) {
        sem_trim_region_destroy(region);
        pt->status = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory (part %d)",
                                   part_index);
        return;
    }
    for (size_t k = 0; k < n_nodes; ++k) pt->node[k] = -1;
    int n_tri = 0, n_vert = 0;
    for (int j = 0; j + 1 < nv; ++j) {
        for (int i = 0; i + 1 < nu; ++i) {
            /* cell corners a=(i,j) b=(i+1,j) c=(i+1,j+1) d=(i,j+1); triangles abc, acd */
            int a = i + nu * j, b = a + 1, c = b + nu, d = a + nu;
            int tri[2][3] = {{a, b, c}, {a, c, d}};
            for (int h = 0; h < 2; ++h) {
                if (region && !covering) {
                    double cu = 0, cv = 0;
                    for (int k = 0; k < 3; ++k) {
                        cu += pt->us[tri[h][k] % nu];
                        cv += pt->vs[tri[h][k] / nu];
                    }
                    if (!sem_trim_region_inside(region, cu / 3.0, cv / 3.0)) continue;
                } else if (region && !reaches_inside(region, pt, tri[h])) {
                    continue;
                }
                for (int k = 0; k < 3; ++k) {
                    int n = tri[h][k];
                    if (pt->node[n] < 0) {
                        pt->node[n] = n_vert;
                        pt->vertex_node[n_vert++] = n;
                    }
                    pt->triangles[3 * (size_t)n_tri + (size_t)k] = pt->node[n];
                }
                n_tri++;
            }
        }
    }
    sem_trim_region_destroy(region);
    pt->n_vertices = n_vert;
    pt->n_triangles = n_tri;
}

/* Non-rational basis values and first derivatives at every sample of one direction, so a
 * vertex costs no basis evaluation: the same numbers sem_surface_basis computes. */
typedef struct direction_basis {
    int *span;
    double *N; /* 2 (degree + 1) per sample: values, then derivatives */
} direction_basis;

static int direction_basis_build(int degree, int n_ctrl, const double *knots, const double *t,
                                 int n, direction_basis *b)
{
    b->span = malloc((size_t)n * sizeof *b->span);
    b->N = malloc((size_t)n * 2 * (size_t)(degree + 1) * sizeof *b->N);
    if (!b->span || !b->N) return 0;
    for (int i = 0; i < n; ++i) {
        b->span[i] = sem_bspline_span(degree, n_ctrl, knots, t[i]);
        sem_bspline_basis(degree, knots, b->span[i], t[i], 1,
                          b->N + (size_t)i * 2 * (size_t)(degree + 1));
    }
    return 1;
}

static void direction_basis_free(direction_basis *b)
{
    free(b->span);
    free(b->N);
}

/* Position and unit normal from a basis row (the per-frame update's arithmetic). */
static void vertex_frame(const sem_surface *s, int n_basis, const int *index, const double *phi,
                         const double *phi_u, const double *phi_v, double u, double v,
                         double *position, double *normal)
{
    double x[3] = {0, 0, 0}, xu[3] = {0, 0, 0}, xv[3] = {0, 0, 0};
    for (int k = 0; k < n_basis; ++k) {
        const double *P = s->ctrl + 3 * (size_t)index[k];
        double f = phi[k], fu = phi_u[k], fv = phi_v[k];
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
        sem_surface_normal(s, u, v, nrm);
    }
    for (int d = 0; d < 3; ++d) {
        position[d] = x[d];
        normal[d] = nrm[d];
    }
}

/* Topology of every part, in parallel over parts; first error in part order. */
static sem_status build_topologies(const sem_model *model, int resolution, int covering,
                                   int threads, part_topology **out, sem_error *err)
{
    int n_parts = model->n_parts;
    part_topology *tp = calloc((size_t)(n_parts > 0 ? n_parts : 1), sizeof *tp);
    if (!tp) return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
#pragma omp parallel for schedule(dynamic, 1) num_threads(sem_threads(threads)) if (n_parts > 1)
    for (int i = 0; i < n_parts; ++i)
        part_topology_build(&model->parts[i], i, resolution, covering, &tp[i]);
    for (int i = 0; i < n_parts; ++i)
        if (tp[i].status != SEM_OK) {
            if (err) *err = tp[i].err;
            sem_status st = tp[i].status;
            for (int k = 0; k < n_parts; ++k) part_topology_free(&tp[k]);
            free(tp);
            return st;
        }
    *out = tp;
    return SEM_OK;
}

static void free_topologies(part_topology *tp, int n_parts)
{
    if (!tp) return;
    for (int k = 0; k < n_parts; ++k) part_topology_free(&tp[k]);
    free(tp);
}

/* Shared arrays from the part topologies: offsets, uv, vertex_part, triangles. */
static sem_status place_topologies(sem_mesh_template *t, const sem_model *model,
                                   const part_topology *tp, sem_error *err)
{
    size_t nvert = 0, ntri = 0, nbasis = 0;
    for (int i = 0; i < t->n_parts; ++i) {
        const sem_surface *s = &model->parts[i].surface;
        part_template *pt = &t->parts[i];
        pt->first_vertex = (int)nvert;
        pt->first_triangle = (int)ntri;
        pt->n_vertices = tp[i].n_vertices;
        pt->n_triangles = tp[i].n_triangles;
        pt->degree_u = s->degree_u;
        pt->degree_v = s->degree_v;
        pt->n_u = s->n_u;
        pt->n_v = s->n_v;
        pt->n_basis = (s->degree_u + 1) * (s->degree_v + 1);
        pt->basis_offset = nbasis;
        nvert += (size_t)tp[i].n_vertices;
        ntri += (size_t)tp[i].n_triangles;
        nbasis += (size_t)tp[i].n_vertices * (size_t)pt->n_basis;
        if (nvert > (size_t)INT_MAX / 4 || ntri > (size_t)INT_MAX / 4)
            return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    }
    t->n_vertices = (int)nvert;
    t->n_triangles = (int)ntri;
    t->uv = malloc((2 * nvert + 1) * sizeof *t->uv);
    t->vertex_part = malloc((nvert + 1) * sizeof *t->vertex_part);
    t->triangles = malloc((3 * ntri + 1) * sizeof *t->triangles);
    t->triangle_part = malloc((ntri + 1) * sizeof *t->triangle_part);
    if (!t->uv || !t->vertex_part || !t->triangles || !t->triangle_part)
        return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    for (int i = 0; i < t->n_parts; ++i) {
        const part_template *pt = &t->parts[i];
        const part_topology *p = &tp[i];
        for (int k = 0; k < p->n_vertices; ++k) {
            int n = p->vertex_node[k];
            size_t vtx = (size_t)pt->first_vertex + (size_t)k;
            t->uv[2 * vtx] = p->us[n % p->nu];
            t->uv[2 * vtx + 1] = p->vs[n / p->nu];
            t->vertex_part[vtx] = i;
        }
        for (int k = 0; k < 3 * p->n_triangles; ++k)
            t->triangles[3 * (size_t)pt->first_triangle + (size_t)k] =
                pt->first_vertex + p->triangles[k];
        for (int k = 0; k < p->n_triangles; ++k)
            t->triangle_part[(size_t)pt->first_triangle + (size_t)k] = i;
    }
    return SEM_OK;
}

/* Basis rows (template) or positions and normals (mesh, when m != NULL) of one part's
 * vertices, with the direction bases cached per sample column and row. Returns 0 when
 * out of memory. */
static int evaluate_part(const sem_mesh_template *t, const sem_model *model, int i,
                         const part_topology *p, sem_mesh *m)
{
    const sem_surface *s = &model->parts[i].surface;
    const part_template *pt = &t->parts[i];
    if (p->n_vertices == 0) return 1;
    direction_basis bu, bv;
    memset(&bu, 0, sizeof bu);
    memset(&bv, 0, sizeof bv);
    int ok = direction_basis_build(s->degree_u, s->n_u, s->knots_u, p->us, p->nu, &bu) &&
             direction_basis_build(s->degree_v, s->n_v, s->knots_v, p->vs, p->nv, &bv);
    int nb = pt->n_basis;
    int *index = NULL;
    double *phi = NULL;
    if (ok && m) {
        index = malloc((size_t)nb * sizeof *index);
        phi = malloc(3 * (size_t)nb * sizeof *phi);
        ok = index && phi;
    }
    if (ok) {
        const int su_len = 2 * (s->degree_u + 1), sv_len = 2 * (s->degree_v + 1);
        for (int k = 0; k < p->n_vertices; ++k) {
            int n = p->vertex_node[k], iu = n % p->nu, iv = n / p->nu;
            const double *Nu = bu.N + (size_t)iu * (size_t)su_len;
            const double *Nv = bv.N + (size_t)iv * (size_t)sv_len;
            size_t vtx = (size_t)pt->first_vertex + (size_t)k;
            if (m) {
                sem_surface_basis_from_spans(s, bu.span[iu], Nu, bv.span[iv], Nv, index, phi, phi + nb, phi + 2 * nb);
                vertex_frame(s, nb, index, phi, phi + nb, phi + 2 * nb, p->us[iu], p->vs[iv],
                             m->positions + 3 * vtx, m->normals + 3 * vtx);
            } else {
                size_t off = pt->basis_offset + (size_t)k * (size_t)nb;
                sem_surface_basis_from_spans(s, bu.span[iu], Nu, bv.span[iv], Nv, t->basis_index + off, t->phi + off,
                          t->phi_u + off, t->phi_v + off);
            }
        }
    }
    free(index);
    free(phi);
    direction_basis_free(&bu);
    direction_basis_free(&bv);
    return ok;
}

static sem_status evaluate_parts(const sem_mesh_template *t, const sem_model *model,
                                 const part_topology *tp, sem_mesh *m, sem_error *err)
{
    int failed = 0;
#pragma omp parallel for schedule(dynamic, 1) reduction(| : failed) \
    num_threads(sem_threads(t->threads)) if (t->n_parts > 1)
    for (int i = 0; i < t->n_parts; ++i)
        if (!evaluate_part(t, model, i, &tp[i], m)) failed |= 1;
    if (failed) return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    return SEM_OK;
}

static sem_status check_tessellation_input(const sem_model *model, int resolution, sem_error *err)
{
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
    return SEM_OK;
}

/* Template topology (and, unless skip_basis, its basis rows); *tp_out keeps the part
 * topologies when non-NULL. */
static sem_status template_build(const sem_model *model, int resolution, int skip_basis,
                                 int covering, int threads, sem_mesh_template **out,
                                 part_topology **tp_out, sem_error *err)
{
    *out = NULL;
    sem_status st = check_tessellation_input(model, resolution, err);
    if (st != SEM_OK) return st;
    sem_mesh_template *t = calloc(1, sizeof *t);
    if (!t) return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    t->n_parts = model->n_parts;
    t->threads = threads;
    t->parts = calloc((size_t)(model->n_parts > 0 ? model->n_parts : 1), sizeof *t->parts);
    if (!t->parts) {
        sem_mesh_template_destroy(t);
        return sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
    }
    part_topology *tp = NULL;
    st = build_topologies(model, resolution, covering, threads, &tp, err);
    if (st == SEM_OK) st = place_topologies(t, model, tp, err);
    if (st == SEM_OK && !skip_basis) {
        size_t nbasis = 0;
        for (int i = 0; i < t->n_parts; ++i)
            nbasis += (size_t)t->parts[i].n_vertices * (size_t)t->parts[i].n_basis;
        t->basis_index = malloc((nbasis + 1) * sizeof *t->basis_index);
        t->phi = malloc((nbasis + 1) * sizeof *t->phi);
        t->phi_u = malloc((nbasis + 1) * sizeof *t->phi_u);
        t->phi_v = malloc((nbasis + 1) * sizeof *t->phi_v);
        if (!t->basis_index || !t->phi || !t->phi_u || !t->phi_v)
            st = sem_error_set(err, SEM_ERR_NOMEM, "tessellation: out of memory");
        else
            st = evaluate_parts(t, model, tp, NULL, err);
    }
    if (st != SEM_OK) {
        free_topologies(tp, model->n_parts);
        sem_mesh_template_destroy(t);
        return st;
    }
    if (tp_out)
        *tp_out = tp;
    else
        free_topologies(tp, model->n_parts);
    *out = t;
    return SEM_OK;
}

sem_status sem_mesh_template_build(const sem_model *model, int resolution,
                                   sem_mesh_template **out, sem_error *err)
{
    return template_build(model, resolution, 0, 0, 0, out, NULL, err);
}

sem_status sem_mesh_template_build_covering(const sem_model *model, int resolution,
                                            sem_mesh_template **out, sem_error *err)
{
    return template_build(model, resolution, 0, 1, 0, out, NULL, err);
}

void sem_mesh_free(sem_mesh *m)
{
    if (!m) return;
    SEM_FREE_ALL(m->positions, m->normals, m->uv, m->triangles, m->triangle_part, m->part_vertex_start,
                 m->part_triangle_start);
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
#pragma omp parallel for schedule(static) num_threads(sem_threads(t->threads))
    for (int vtx = 0; vtx < n; ++vtx) {
        int p = t->vertex_part[vtx];
        const part_template *pt = &t->parts[p];
        const sem_surface *s = &model->parts[p].surface;
        size_t off = pt->basis_offset + (size_t)(vtx - pt->first_vertex) * (size_t)pt->n_basis;
        vertex_frame(s, pt->n_basis, t->basis_index + off, t->phi + off, t->phi_u + off,
                     t->phi_v + off, t->uv[2 * (size_t)vtx], t->uv[2 * (size_t)vtx + 1],
                     m->positions + 3 * (size_t)vtx, m->normals + 3 * (size_t)vtx);
    }
    return SEM_OK;
}

sem_status sem_mesh_from_model(const sem_model *model, int resolution, sem_mesh *out,
                               sem_error *err)
{
    return sem_mesh_from_model_threads(model, resolution, 0, out, err);
}

sem_status sem_mesh_from_model_threads(const sem_model *model, int resolution, int threads,
                                       sem_mesh *out, sem_error *err)
{
    /* topology only, then positions and normals straight from cached direction bases:
     * the template's basis rows are never stored (same arithmetic as template + update,
     * so the result is bitwise the same) */
    memset(out, 0, sizeof *out);
    sem_mesh_template *t;
    part_topology *tp = NULL;
    sem_status st = template_build(model, resolution, 1, 0, threads, &t, &tp, err);
    if (st != SEM_OK) return st;
    st = sem_mesh_template_mesh(t, out, err);
    if (st == SEM_OK) st = evaluate_parts(t, model, tp, out, err);
    if (st != SEM_OK) sem_mesh_free(out);
    free_topologies(tp, model->n_parts);
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
