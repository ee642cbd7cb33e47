/*
 * split.c - every part cut into patches of at most a given size, the same surfaces (see
 * sem/refine.h, sem_model_patches).
 *
 * Why: SEM gives each part one polynomial (Eq. 7), so a large face moves as one quadratic
 * however the body bends under it, and the answer depends on how the file's faces happen to
 * be drawn (a 5 m beam of one section bends 40 % of the FEM figure, of 20 sections 98 %).
 * Cutting the faces into patches of a chosen size gives the method as many polynomials as
 * the accuracy needs, whatever the file: the accuracy setting of docs/simulation.md.
 *
 * How: in each direction the part's used domain (the box of its trim region in (u, v), the
 * whole domain when untrimmed) is cut where an iso-curve through the middle of that box
 * reaches whole multiples of its length / n, n = ceil(length / size); every cut (and the
 * domain's ends, so that unclamped knot vectors work too) is inserted as a knot up to
 * multiplicity degree (Boehm's algorithm: the same surface). The refined surface is then C0
 * at the cuts and each cell between them is a clamped NURBS patch of its own: the sub-grid
 * of the refined control points whose basis is non-zero there, with the knots between the
 * cuts. A patch keeps its part's trim loops (in the same (u, v)), so a trimmed face's
 * patches are trimmed by the same curves; a patch with no trimmed area (no point of an
 * 8 x 8 grid inside the trim) is dropped.
 *
 * Neighbouring patches share the control points on their common cut: the split model holds
 * each as two coincident points, which the simulator welds (sem_object_def.weld). The
 * refined model (one part per input part, knots inserted) is what the patches are cut from:
 * ctrl_refined maps every control point of the split model to its refined control point, so
 * a state of the split model gives the refined model's control points (sem_patches_gather)
 * and the frames of a run hold the parts of the file, not the patches.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/limits.h"
#include "sem/nurbs.h"
#include "sem/refine.h"
#include "sem/trim.h"

/* At most this many patches per direction of one part. */
#define MAX_CUTS 64

/* Length of the iso-curve of s at v (dir 0: along u over [a, b]) or at u (dir 1). */
static double iso_length(const sem_surface *s, int dir, double fixed, double a, double b)
{
    double length = 0, prev[3];
    const int n = 64;
    for (int k = 0; k <= n; ++k) {
        double t = a + (b - a) * k / n, x[3];
        if (dir == 0)
            sem_surface_eval(s, t, fixed, x, NULL, NULL, NULL);
        else
            sem_surface_eval(s, fixed, t, x, NULL, NULL, NULL);
        if (k > 0) length += sqrt((x[0] - prev[0]) * (x[0] - prev[0]) + (x[1] - prev[1]) * (x[1] - prev[1]) +
                                  (x[2] - prev[2]) * (x[2] - prev[2]));
        memcpy(prev, x, sizeof x);
    }
    return length;
}

/* The cuts of one direction inside (a, b): where the iso-curve through `fixed` reaches
 * multiples of its length / n, n = ceil(longest iso-curve / size). Returns their count. */
static int choose_cuts(const sem_surface *s, int dir, double a, double b, double c0, double c1, double size,
                       double *cuts)
{
    double longest = 0;
    for (int k = 0; k <= 4; ++k) {
        double l = iso_length(s, dir, c0 + (c1 - c0) * k / 4.0, a, b);
        if (l > longest) longest = l;
    }
    if (!(longest > size) || !(b > a)) return 0;
    int n = (int)ceil(longest / size);
    if (n > MAX_CUTS) n = MAX_CUTS;
    /* arc length along the middle iso-curve, tabulated */
    const int m = 256;
    double cum[257], prev[3], mid = 0.5 * (c0 + c1);
    cum[0] = 0;
    for (int k = 0; k <= m; ++k) {
        double t = a + (b - a) * k / m, x[3];
        if (dir == 0)
            sem_surface_eval(s, t, mid, x, NULL, NULL, NULL);
        else
            sem_surface_eval(s, mid, t, x, NULL, NULL, NULL);
        if (k > 0)
            cum[k] = cum[k - 1] + sqrt((x[0] - prev[0]) * (x[0] - prev[0]) + (x[1] - prev[1]) * (x[1] - prev[1]) +
                                       (x[2] - prev[2]) * (x[2] - prev[2]));
        memcpy(prev, x, sizeof x);
    }
    int count = 0;
    for (int j = 1; j < n; ++j) {
        double t;
        if (cum[m] > 0) {
            double target = cum[m] * j / n;
            int k = 1;
            while (k < m && cum[k] < target) ++k;
            double f = cum[k] > cum[k - 1] ? (target - cum[k - 1]) / (cum[k] - cum[k - 1]) : 0;
            t = a + (b - a) * (k - 1 + f) / m;
        } else {
            t = a + (b - a) * j / n;
        }
        if (t > a && t < b && (count == 0 || t > cuts[count - 1])) cuts[count++] = t;
    }
    return count;
}

/* Multiplicity of value t in knots[0..n). */
static int multiplicity(const double *knots, int n, double t)
{
    int m = 0;
    for (int i = 0; i < n; ++i) m += knots[i] == t;
    return m;
}

/* Knots to insert so that every cut (sorted, inside the knot domain) reaches multiplicity
 * p; appended to X (ascending). Returns the count. */
static int insertions(const double *knots, int n_ctrl, int p, const double *cuts, int n_cuts, double *X)
{
    int r = 0;
    for (int k = 0; k < n_cuts; ++k) {
        int have = multiplicity(knots, n_ctrl + p + 1, cuts[k]);
        for (int j = have; j < p; ++j) X[r++] = cuts[k];
    }
    return r;
}

/* The control point index range [first, last] of the refined direction (degree p, knots U of
 * n + p + 1 values) whose basis is non-zero on (c0, c1), both cuts of multiplicity >= p. */
static void cell_range(const double *U, int n, int p, double c0, double c1, int *first, int *last)
{
    /* right limit at c0: the run of c0 starts at j0 with r0 copies: point j0 + r0 - p - 1;
     * left limit at c1: the run starts at j1: point j1 - 1 */
    int j0 = 0;
    while (j0 < n + p + 1 && U[j0] < c0) ++j0;
    int r0 = 0;
    while (j0 + r0 < n + p + 1 && U[j0 + r0] == c0) ++r0;
    int j1 = 0;
    while (j1 < n + p + 1 && U[j1] < c1) ++j1;
    *first = j0 + r0 - p - 1;
    *last = j1 - 1;
}

void sem_patches_free(sem_patches *s)
{
    if (!s) return;
    sem_model_destroy(s->model);
    sem_model_destroy(s->refined);
    free(s->part_parent);
    free(s->ctrl_refined);
    memset(s, 0, sizeof *s);
}

/* The cuts of part `part` in u and v (domain ends included) for patches of at most size. */
static sem_status part_cuts(const sem_part *part, double size, double *cu, int *ncu, double *cv, int *ncv,
                            sem_error *err)
{
    const sem_surface *s = &part->surface;
    double ua = s->u0, ub = s->u1, va = s->v0, vb = s->v1;
    /* a trimmed part: the box of its trim region, where its area is */
    if (part->has_outer || part->n_holes > 0) {
        sem_trim_region *r = NULL;
        sem_error e;
        if (sem_trim_region_build(part, &r, &e) == SEM_OK) {
            double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
            for (int l = 0; l < sem_trim_region_loop_count(r); ++l) {
                int n = 0;
                const double *uv = sem_trim_region_loop(r, l, &n);
                for (int i = 0; i < n; ++i)
                    for (int k = 0; k < 2; ++k) {
                        lo[k] = fmin(lo[k], uv[2 * i + k]);
                        hi[k] = fmax(hi[k], uv[2 * i + k]);
                    }
            }
            sem_trim_region_destroy(r);
            if (hi[0] > lo[0] && hi[1] > lo[1]) {
                ua = fmax(ua, lo[0]);
                ub = fmin(ub, hi[0]);
                va = fmax(va, lo[1]);
                vb = fmin(vb, hi[1]);
            }
        }
    }
    (void)err;
    double inner_u[MAX_CUTS], inner_v[MAX_CUTS];
    int nu = choose_cuts(s, 0, ua, ub, va, vb, size, inner_u);
    int nv = choose_cuts(s, 1, va, vb, ua, ub, size, inner_v);
    /* the domain's ends, the used box's ends (when inside), the cuts between */
    *ncu = 0;
    cu[(*ncu)++] = s->u0;
    if (ua > s->u0) cu[(*ncu)++] = ua;
    for (int k = 0; k < nu; ++k) cu[(*ncu)++] = inner_u[k];
    if (ub < s->u1) cu[(*ncu)++] = ub;
    cu[(*ncu)++] = s->u1;
    *ncv = 0;
    cv[(*ncv)++] = s->v0;
    if (va > s->v0) cv[(*ncv)++] = va;
    for (int k = 0; k < nv; ++k) cv[(*ncv)++] = inner_v[k];
    if (vb < s->v1) cv[(*ncv)++] = vb;
    cv[(*ncv)++] = s->v1;
    return SEM_OK;
}

/* 1 when some point of an 8 x 8 grid over [u0,u1] x [v0,v1] is inside the part's trim. */
static int cell_has_area(const sem_trim_region *r, double u0, double u1, double v0, double v1)
{
    if (!r) return 1;
    for (int i = 0; i < 8; ++i)
        for (int j = 0; j < 8; ++j)
            if (sem_trim_region_inside(r, u0 + (u1 - u0) * (i + 0.5) / 8, v0 + (v1 - v0) * (j + 0.5) / 8)) return 1;
    return 0;
}

/* Cuts strictly inside the knot vector's domain (the insertable ones). */
static int interior_cuts(const double *cuts, int n, const double *knots, int n_ctrl, int p, double *out)
{
    int r = 0;
    for (int k = 0; k < n; ++k)
        if (cuts[k] > knots[p] && cuts[k] < knots[n_ctrl]) out[r++] = cuts[k];
    return r;
}

/* Copies the trims (and name, colour, entity) of src into dst, whose surface is set. */
static sem_status copy_trims(sem_part *dst, const sem_part *src)
{
    sem_part tmp;
    if (sem_part_copy(&tmp, src) != SEM_OK) return SEM_ERR_NOMEM;
    sem_surface_free(&tmp.surface);
    tmp.surface = dst->surface;
    *dst = tmp;
    return SEM_OK;
}

/* 1 when the knot vector (degree p, n points) is clamped at the domain's end t (start: 0). */
static int clamped_at(const double *U, int n, int p, double t, int end)
{
    if (!end) return t > U[p] || U[0] == U[p];
    return t < U[n] || U[n + p] == U[n];
}

/* Part `part` cut into patches of at most `size`: the refined part (knots inserted at the
 * cuts) into *refined, the patches appended to cells, and for each patch control point its
 * refined control point (local index) appended to *map (n_map, capacity map_cap). Fails
 * (SEM_ERR_INVALID) where a patch cannot be made, e.g. its trim loops do not close within a
 * patch's (smaller) tolerance; the caller then keeps the part whole. */
static sem_status split_part(const sem_part *part, double size, sem_part *refined, sem_model *cells, int **map,
                             size_t *n_map, size_t *map_cap, sem_error *err)
{
    const sem_surface *s = &part->surface;
    memset(refined, 0, sizeof *refined);
    if (!clamped_at(s->knots_u, s->n_u, s->degree_u, s->u0, 0) ||
        !clamped_at(s->knots_u, s->n_u, s->degree_u, s->u1, 1) ||
        !clamped_at(s->knots_v, s->n_v, s->degree_v, s->v0, 0) ||
        !clamped_at(s->knots_v, s->n_v, s->degree_v, s->v1, 1))
        return sem_error_set(err, SEM_ERR_INVALID, "an unclamped knot vector");
    double cu[MAX_CUTS + 4], cv[MAX_CUTS + 4];
    int ncu = 0, ncv = 0;
    sem_status st = part_cuts(part, size, cu, &ncu, cv, &ncv, err);
    if (st != SEM_OK) return st;
    /* every cut inside the knot domain up to multiplicity degree */
    double iu[MAX_CUTS + 4], iv[MAX_CUTS + 4];
    int niu = interior_cuts(cu, ncu, s->knots_u, s->n_u, s->degree_u, iu);
    int niv = interior_cuts(cv, ncv, s->knots_v, s->n_v, s->degree_v, iv);
    double *Xu = malloc(((size_t)niu * s->degree_u + 1) * sizeof *Xu);
    double *Xv = malloc(((size_t)niv * s->degree_v + 1) * sizeof *Xv);
    if (!Xu || !Xv) {
        free(Xu);
        free(Xv);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
    }
    int ru = insertions(s->knots_u, s->n_u, s->degree_u, iu, niu, Xu);
    int rv = insertions(s->knots_v, s->n_v, s->degree_v, iv, niv, Xv);
    st = sem_surface_insert_knots(s, Xu, ru, Xv, rv, &refined->surface, err);
    free(Xu);
    free(Xv);
    if (st != SEM_OK) return st;
    if (copy_trims(refined, part) != SEM_OK) {
        sem_surface_free(&refined->surface);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
    }
    const sem_surface *R = &refined->surface;
    sem_trim_region *region = NULL;
    if (part->has_outer || part->n_holes > 0) {
        sem_error e;
        if (sem_trim_region_build(part, &region, &e) != SEM_OK) region = NULL;
    }
    for (int a = 0; a + 1 < ncu && st == SEM_OK; ++a)
        for (int b = 0; b + 1 < ncv && st == SEM_OK; ++b) {
            double u0 = cu[a], u1 = cu[a + 1], v0 = cv[b], v1 = cv[b + 1];
            if (!(u1 > u0) || !(v1 > v0) || !cell_has_area(region, u0, u1, v0, v1)) continue;
            int fu, lu, fv, lv;
            cell_range(R->knots_u, R->n_u, R->degree_u, u0, u1, &fu, &lu);
            cell_range(R->knots_v, R->n_v, R->degree_v, v0, v1, &fv, &lv);
            int nu = lu - fu + 1, nv = lv - fv + 1, pu = R->degree_u, pv = R->degree_v;
            if (fu < 0 || fv < 0 || lu >= R->n_u || lv >= R->n_v || nu < pu + 1 || nv < pv + 1) {
                st = sem_error_set(err, SEM_ERR_INVALID, "cannot cut a patch at u [%g, %g], v [%g, %g]", u0, u1, v0, v1);
                break;
            }
            sem_part cell;
            memset(&cell, 0, sizeof cell);
            if (sem_surface_alloc(&cell.surface, pu, pv, nu, nv) != SEM_OK) {
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
                break;
            }
            sem_surface *c = &cell.surface;
            /* knots: the cut repeated p + 1 times, the refined knots between, the cut */
            for (int k = 0; k <= pu; ++k) c->knots_u[k] = u0, c->knots_u[nu + k] = u1;
            for (int k = pu + 1; k < nu; ++k) c->knots_u[k] = R->knots_u[fu + k];
            for (int k = 0; k <= pv; ++k) c->knots_v[k] = v0, c->knots_v[nv + k] = v1;
            for (int k = pv + 1; k < nv; ++k) c->knots_v[k] = R->knots_v[fv + k];
            if (*n_map + (size_t)nu * nv > *map_cap) {
                while (*n_map + (size_t)nu * nv > *map_cap) *map_cap *= 2;
                int *x = realloc(*map, *map_cap * sizeof *x);
                if (!x) {
                    sem_surface_free(c);
                    st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
                    break;
                }
                *map = x;
            }
            for (int j = 0; j < nv; ++j)
                for (int i = 0; i < nu; ++i) {
                    size_t from = (size_t)(fu + i) + (size_t)R->n_u * (size_t)(fv + j), to = (size_t)i + (size_t)nu * j;
                    memcpy(c->ctrl + 3 * to, R->ctrl + 3 * from, 3 * sizeof(double));
                    c->weights[to] = R->weights[from];
                    (*map)[*n_map + to] = (int)from;
                }
            c->u0 = u0, c->u1 = u1, c->v0 = v0, c->v1 = v1;
            sem_error e;
            if (copy_trims(&cell, part) != SEM_OK) {
                sem_surface_free(c);
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
                break;
            }
            if ((cell.has_outer || cell.n_holes > 0) && sem_part_validate_trims(&cell, &e) != SEM_OK) {
                sem_part_free(&cell);
                st = sem_error_set(err, SEM_ERR_INVALID, "a patch's trim: %s", e.message);
            } else if ((st = sem_model_take_part(cells, &cell, err)) != SEM_OK) {
                sem_part_free(&cell);
            } else {
                *n_map += (size_t)nu * nv;
            }
        }
    sem_trim_region_destroy(region);
    if (st == SEM_OK && cells->n_parts == 0) st = sem_error_set(err, SEM_ERR_INVALID, "no patch has area");
    if (st != SEM_OK) sem_part_free(refined);
    return st;
}

sem_status sem_model_patches(const sem_model *in, double size, sem_patches *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    if (!(size > 0) || !isfinite(size))
        return sem_error_set(err, SEM_ERR_INVALID, "patch size must be positive (got %g)", size);
    out->model = sem_model_create();
    out->refined = sem_model_create();
    size_t map_cap = 64, n_ctrl = 0, parts_cap = 64, local_cap = 64;
    int *local = malloc(local_cap * sizeof *local);
    out->ctrl_refined = malloc(map_cap * sizeof *out->ctrl_refined);
    out->part_parent = malloc(parts_cap * sizeof *out->part_parent);
    if (!out->model || !out->refined || !out->ctrl_refined || !out->part_parent || !local) {
        free(local);
        sem_patches_free(out);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
    }
    snprintf(out->model->units, sizeof out->model->units, "%s", in->units);
    snprintf(out->refined->units, sizeof out->refined->units, "%s", in->units);
    out->model->unit_to_meter = out->refined->unit_to_meter = in->unit_to_meter;
    sem_status st = SEM_OK;
    size_t refined_offset = 0;
    for (int p = 0; p < in->n_parts && st == SEM_OK; ++p) {
        sem_part refined;
        sem_model *cells = sem_model_create();
        size_t n_local = 0;
        sem_error e;
        if (!cells) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
            break;
        }
        sem_status ps = split_part(&in->parts[p], size, &refined, cells, &local, &n_local, &local_cap, &e);
        if (ps == SEM_ERR_NOMEM) {
            sem_model_destroy(cells);
            st = sem_error_set(err, SEM_ERR_NOMEM, "%s", e.message);
            break;
        }
        if (ps != SEM_OK) {
            /* kept whole: the part itself, its points in order */
            sem_model_destroy(cells);
            cells = sem_model_create();
            size_t np = (size_t)in->parts[p].surface.n_u * in->parts[p].surface.n_v;
            if (!cells || sem_part_copy(&refined, &in->parts[p]) != SEM_OK ||
                sem_model_add_part(cells, &in->parts[p], err) != SEM_OK) {
                sem_model_destroy(cells);
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
                break;
            }
            while (np > local_cap) local_cap *= 2;
            int *x = realloc(local, local_cap * sizeof *x);
            if (!x) {
                sem_model_destroy(cells);
                sem_part_free(&refined);
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
                break;
            }
            local = x;
            for (size_t c = 0; c < np; ++c) local[c] = (int)c;
            n_local = np;
        }
        /* append the patches and their map */
        while (n_ctrl + n_local > map_cap) map_cap *= 2;
        while ((size_t)(out->model->n_parts + cells->n_parts) > parts_cap) parts_cap *= 2;
        int *x = realloc(out->ctrl_refined, map_cap * sizeof *x);
        if (x) out->ctrl_refined = x;
        int *y = x ? realloc(out->part_parent, parts_cap * sizeof *y) : NULL;
        if (y) out->part_parent = y;
        if (!x || !y) {
            sem_model_destroy(cells);
            sem_part_free(&refined);
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory splitting a model");
            break;
        }
        for (size_t c = 0; c < n_local; ++c) out->ctrl_refined[n_ctrl + c] = (int)(refined_offset + (size_t)local[c]);
        n_ctrl += n_local;
        for (int k = 0; k < cells->n_parts && st == SEM_OK; ++k) {
            out->part_parent[out->model->n_parts] = p;
            st = sem_model_take_part(out->model, &cells->parts[k], err);
        }
        sem_model_destroy(cells);
        refined_offset += (size_t)refined.surface.n_u * refined.surface.n_v;
        if (st == SEM_OK && (st = sem_model_take_part(out->refined, &refined, err)) != SEM_OK) sem_part_free(&refined);
        else if (st != SEM_OK)
            sem_part_free(&refined);
    }
    free(local);
    if (st == SEM_OK) st = sem_model_check_limits(out->model, err);
    if (st != SEM_OK) sem_patches_free(out);
    return st;
}

void sem_patches_gather(const sem_patches *s, const double *q_split, double *q_refined)
{
    /* the refined points no patch holds (outside every trimmed area) keep their rest place */
    sem_model_get_q(s->refined, q_refined);
    size_t n = sem_model_control_points(s->model);
    for (size_t c = 0; c < n; ++c) memcpy(q_refined + 3 * (size_t)s->ctrl_refined[c], q_split + 3 * c, 3 * sizeof(double));
}
