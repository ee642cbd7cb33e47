/*
 * iges_entities.c - IGES curve and surface entities as NURBS (iges_internal.h).
 *
 *   126 rational B-spline curve            -> a NURBS curve, exactly as written
 *   110 line, 100 circular arc              -> degree 1, rational quadratic (exact)
 *   102 composite curve                     -> its members, in order
 *   128 rational B-spline surface          -> a NURBS surface, exactly as written
 *   108 / 118 / 120 / 122 analytic surfaces -> exact NURBS (bilinear plane, degree-1
 *                                             ruled/extruded, rational quadratic circles)
 *   190-198 analytic surfaces (IGES 5.3)    -> exact NURBS (geometry/analytic_surfaces.c)
 *
 * Each entity is converted where it is used, recursively, in the coordinates of its parent
 * composed with its own transform (iges_enter_entity). Curve and surface entities we cannot
 * convert (parametric splines 112/114, conics, offset curves and surfaces, ...) are skipped
 * with a warning naming them (iges_unsupported). Surfaces whose extent or parameters the
 * file does not give (an unbounded plane, the unbounded analytic surfaces) are built from
 * the boundary of the trimmed entity or face that uses them (surface_hint, iges_parts.c).
 * A parameter range that is empty or leaves the knots (126, 128) is the knots' own, with a
 * warning, as Open CASCADE reads it (issue 29).
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/analytic_surfaces.h"
#include "geometry/curve_tools.h"
#include "geometry/trim_fix.h"
#include "io/iges_internal.h"
#include "sem/limits.h"
#include "sem/nurbs.h"

/* ------------------------------------------------------ curve tools ---- */

sem_status iges_list_push(iges_reader *r, curve_list *l, sem_curve *c)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 8;
        sem_curve *x = realloc(l->c, (size_t)cap * sizeof *x);
        if (!x) {
            sem_curve_free(c);
            return iges_nomem(r);
        }
        l->c = x;
        l->cap = cap;
    }
    l->c[l->n++] = *c;
    memset(c, 0, sizeof *c);
    return SEM_OK;
}

void iges_list_free(curve_list *l)
{
    for (int i = 0; i < l->n; ++i) sem_curve_free(&l->c[i]);
    free(l->c);
    memset(l, 0, sizeof *l);
}

/* Exact reversal (geometry/trim_fix.c). */
static void curve_reverse(sem_curve *c) { sem_curve_reverse(c); }

/* Reverses the run of curves l->c[first..] as a piece of a chain: order and direction. */
void iges_reverse_curves(curve_list *l, int first)
{
    for (int a = first, b = l->n - 1; a < b; ++a, --b) {
        sem_curve t = l->c[a];
        l->c[a] = l->c[b];
        l->c[b] = t;
    }
    for (int a = first; a < l->n; ++a) curve_reverse(&l->c[a]);
}

/* --------------------------------------------------------- curves ---- */

static int is_curve_type(int type)
{
    return type == 100 || type == 102 || type == 104 || type == 106 || type == 110 ||
           type == 112 || type == 126 || type == 130;
}

static sem_status curve_validate(iges_reader *r, int idx, const sem_curve *c)
{
    sem_error e;
    if (sem_curve_validate(c, &e) != SEM_OK)
        return iges_entity_error(r, idx, 0, "%s", e.message);
    return SEM_OK;
}

static sem_status read_nurbs_curve(iges_reader *r, int idx, sem_curve *c)
{
    int K, M;
    sem_status st = iges_param_int(r, idx, 1, &K);
    if (st == SEM_OK) st = iges_param_int(r, idx, 2, &M);
    if (st != SEM_OK) return st;
    if (M < 1 || M > SEM_MAX_DEGREE)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 2),
                                 "degree M = %d out of range 1..%d", M, SEM_MAX_DEGREE);
    if (K < M)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "degree %d too high for %d control points (K = %d)", M, K + 1, K);
    long long n = (long long)K + 1, nk = (long long)K + M + 2;
    st = iges_need(r, idx, 7, nk + n + 3 * n + 2, "rational B-spline curve (K, M)");
    if (st != SEM_OK) return st;
    if (nk > SEM_MAX_KNOTS)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "%lld knots; at most %d per curve "
                                 "(limit SEM_MAX_KNOTS)",
                                 nk, SEM_MAX_KNOTS);
    if ((st = iges_count_points(r, idx, n)) != SEM_OK) return st;
    if (sem_curve_alloc(c, M, (int)n) != SEM_OK) return iges_nomem(r);
    int k = 7;
    for (long long i = 0; st == SEM_OK && i < nk; ++i)
        st = iges_param_real(r, idx, k++, &c->knots[i]);
    for (long long i = 0; st == SEM_OK && i < n; ++i)
        st = iges_param_real(r, idx, k++, &c->weights[i]);
    for (long long i = 0; st == SEM_OK && i < 3 * n; ++i)
        st = iges_param_real(r, idx, k++, &c->ctrl[i]);
    if (st == SEM_OK) st = iges_param_real(r, idx, k++, &c->t0);
    if (st == SEM_OK) st = iges_param_real(r, idx, k++, &c->t1);
    double ka = st == SEM_OK ? c->knots[M] : 0, kb = st == SEM_OK ? c->knots[K + 1] : 0;
    if (st == SEM_OK && !(c->t1 > c->t0) && kb > ka) {
        /* an empty range (Solid Edge writes V0 = V1 = 0: corpus occt_solidedge_deflector) is
         * the knots' own, as Open CASCADE reads it */
        if (!r->entries[idx].repaired)
            sem_model_warn(r->model, "entity 126 (DE %d): parameter range [%g, %g] is empty; the "
                                     "knots' range [%g, %g] is used",
                           iges_de_number(idx), c->t0, c->t1, ka, kb);
        r->entries[idx].repaired = 1;
        c->t0 = ka;
        c->t1 = kb;
    }
    if (st == SEM_OK) st = curve_validate(r, idx, c);
    if (st != SEM_OK) {
        sem_curve_free(c);
        return st;
    }
    r->entries[idx].n_used = k + (iges_remaining(r, idx, k) >= 3 ? 3 : 0); /* unit normal */
    return SEM_OK;
}

static sem_status read_line(iges_reader *r, int idx, double p0[3], double p1[3])
{
    sem_status st = iges_need(r, idx, 1, 6, "line");
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = iges_param_real(r, idx, 1 + k, &p0[k]);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = iges_param_real(r, idx, 4 + k, &p1[k]);
    if (st == SEM_OK) r->entries[idx].n_used = 7;
    return st;
}

/* A circular arc as a rational quadratic: at most 90 degrees per piece, inner control
 * points on the tangent intersections with weight cos(half angle) (Piegl & Tiller A7.1).
 * The end control points are the file's start and end points exactly. */
static sem_status read_arc(iges_reader *r, int idx, sem_curve *c)
{
    double v[7];
    sem_status st = iges_need(r, idx, 1, 7, "circular arc");
    for (int k = 0; st == SEM_OK && k < 7; ++k) st = iges_param_real(r, idx, 1 + k, &v[k]);
    if (st != SEM_OK) return st;
    double zt = v[0], cx = v[1], cy = v[2], sx = v[3], sy = v[4], ex = v[5], ey = v[6];
    double rad = hypot(sx - cx, sy - cy);
    if (!(rad > 0))
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1), "arc radius is zero");
    double a0 = atan2(sy - cy, sx - cx), a1 = atan2(ey - cy, ex - cx);
    int full = sx == ex && sy == ey;
    if (full) a1 = a0 + 2 * M_PI;
    while (a1 <= a0) a1 += 2 * M_PI;
    double sweep = a1 - a0;
    int nseg = (int)ceil(sweep / (M_PI / 2) - 1e-9);
    if (nseg < 1) nseg = 1;
    if (nseg > 4) nseg = 4;
    double d = sweep / nseg, wm = cos(d / 2);
    if (sem_curve_alloc(c, 2, 2 * nseg + 1) != SEM_OK) return iges_nomem(r);
    int m = 0;
    for (int i = 0; i < 3; ++i) c->knots[m++] = 0.0;
    for (int i = 1; i < nseg; ++i) {
        c->knots[m++] = (double)i / nseg;
        c->knots[m++] = (double)i / nseg;
    }
    for (int i = 0; i < 3; ++i) c->knots[m++] = 1.0;
    for (int k = 0; k <= 2 * nseg; ++k) {
        double ang = a0 + k * d / 2, rr = (k % 2) ? rad / wm : rad;
        c->ctrl[3 * k] = cx + rr * cos(ang);
        c->ctrl[3 * k + 1] = cy + rr * sin(ang);
        c->ctrl[3 * k + 2] = zt;
        c->weights[k] = (k % 2) ? wm : 1.0;
    }
    c->ctrl[0] = sx;
    c->ctrl[1] = sy;
    c->ctrl[3 * 2 * nseg] = ex;
    c->ctrl[3 * 2 * nseg + 1] = ey;
    c->t0 = 0.0;
    c->t1 = 1.0;
    r->entries[idx].n_used = 8;
    return SEM_OK;
}

/* Reads any supported curve entity as one or more NURBS curves (a composite curve gives
 * its members in order), in the coordinates of `parent` o (the curve's own transform). */
sem_status iges_read_curves(iges_reader *r, int idx, const double *parent, int depth,
                            curve_list *out)
{
    iges_entry *e = &r->entries[idx];
    double m[12];
    sem_status st = iges_enter_entity(r, idx, parent, depth, m);
    if (st != SEM_OK) return st;
    sem_curve c;
    memset(&c, 0, sizeof c);
    switch (e->type) {
    case 126:
        st = read_nurbs_curve(r, idx, &c);
        break;
    case 110: {
        double p0[3], p1[3];
        st = read_line(r, idx, p0, p1);
        if (st == SEM_OK) st = iges_count_points(r, idx, 2);
        if (st != SEM_OK) return st;
        if (sem_curve_alloc(&c, 1, 2) != SEM_OK) return iges_nomem(r);
        memcpy(c.ctrl, p0, sizeof p0);
        memcpy(c.ctrl + 3, p1, sizeof p1);
        c.knots[2] = c.knots[3] = 1.0;
        c.t1 = 1.0;
        break;
    }
    case 100:
        st = iges_count_points(r, idx, 9);
        if (st == SEM_OK) st = read_arc(r, idx, &c);
        break;
    case 102: {
        int n;
        st = iges_param_int(r, idx, 1, &n);
        if (st == SEM_OK) st = iges_need(r, idx, 2, n, "composite curve (N)");
        if (st != SEM_OK) return st;
        e->busy = 1;
        for (int i = 0; st == SEM_OK && i < n; ++i) {
            int child;
            st = iges_param_ptr(r, idx, 2 + i, 0, &child);
            if (st != SEM_OK) break;
            if (r->entries[child].type == 116) continue; /* a point adds nothing to a loop */
            if (!is_curve_type(r->entries[child].type)) {
                st = iges_entity_error(r, idx, iges_token_line(r, idx, 2 + i),
                                       "member %d points to DE %d, a type-%d entity, not a curve",
                                       i + 1, iges_de_number(child), r->entries[child].type);
                break;
            }
            st = iges_read_curves(r, child, m, depth + 1, out);
        }
        e->busy = 0;
        if (st == SEM_OK) e->n_used = 2 + n;
        return st;
    }
    default:
        if (is_curve_type(e->type)) return iges_unsupported(r, idx, "not supported, skipped");
        return iges_entity_error(r, idx, 0, "a curve was expected here");
    }
    if (st != SEM_OK) return st;
    iges_xf_apply(m, c.ctrl, (size_t)c.n_ctrl);
    st = curve_validate(r, idx, &c);
    if (st != SEM_OK) {
        sem_curve_free(&c);
        return st;
    }
    return iges_list_push(r, out, &c);
}

/* One curve from an entity that must give exactly one (a composite is joined only when it
 * has a single member). */
static sem_status read_single_curve(iges_reader *r, int idx, const double *parent, int depth,
                                    int owner, sem_curve *c)
{
    curve_list l;
    memset(&l, 0, sizeof l);
    sem_status st = iges_read_curves(r, idx, parent, depth, &l);
    if (st != SEM_OK) {
        iges_list_free(&l);
        return st;
    }
    if (l.n != 1) {
        int pieces = l.n;
        iges_list_free(&l);
        sem_model_warn(r->model, "entity %d (DE %d): curve DE %d has %d pieces; only single "
                                 "curves are supported here, surface skipped",
                       r->entries[owner].type, iges_de_number(owner), iges_de_number(idx), pieces);
        return SEM_ERR_UNSUPPORTED;
    }
    *c = l.c[0];
    free(l.c);
    return SEM_OK;
}

/* ------------------------------------------------------- surfaces ---- */

static int is_surface_type(int type)
{
    return type == 108 || type == 114 || type == 118 || type == 120 || type == 122 ||
           type == 128 || type == 140 || (type >= 190 && type <= 198 && type % 2 == 0);
}

static sem_status read_nurbs_surface(iges_reader *r, int idx, sem_surface *s)
{
    int v[9];
    sem_status st = iges_need(r, idx, 1, 9, "rational B-spline surface header");
    for (int k = 0; st == SEM_OK && k < 9; ++k) st = iges_param_int(r, idx, 1 + k, &v[k]);
    if (st != SEM_OK) return st;
    int K1 = v[0], K2 = v[1], M1 = v[2], M2 = v[3];
    if (M1 < 1 || M1 > SEM_MAX_DEGREE || M2 < 1 || M2 > SEM_MAX_DEGREE)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 3),
                                 "degrees M1 = %d, M2 = %d out of "
                                 "range 1..%d",
                                 M1, M2, SEM_MAX_DEGREE);
    if (K1 < M1 || K2 < M2)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "degree (%d, %d) too high for a %d x %d control net", M1, M2,
                                 K1 + 1, K2 + 1);
    long long n1 = (long long)K1 + 1, n2 = (long long)K2 + 1, nw = n1 * n2;
    long long nk1 = n1 + M1 + 1, nk2 = n2 + M2 + 1;
    st = iges_need(r, idx, 10, nk1 + nk2 + 4 * nw + 4,
                   "rational B-spline surface (K1, K2, M1, M2)");
    if (st != SEM_OK) return st;
    if (nk1 > SEM_MAX_KNOTS || nk2 > SEM_MAX_KNOTS)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "%lld x %lld knots; at most %d per "
                                 "direction (limit SEM_MAX_KNOTS)",
                                 nk1, nk2, SEM_MAX_KNOTS);
    if (nw > SEM_MAX_PART_CONTROL_POINTS)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "%lld x %lld control points; at most "
                                 "%d per surface (limit "
                                 "SEM_MAX_PART_CONTROL_POINTS)",
                                 n1, n2, SEM_MAX_PART_CONTROL_POINTS);
    if ((st = iges_count_points(r, idx, nw)) != SEM_OK) return st;
    if (sem_surface_alloc(s, M1, M2, (int)n1, (int)n2) != SEM_OK) return iges_nomem(r);
    s->closed_u = v[4];
    s->closed_v = v[5];
    s->periodic_u = v[7];
    s->periodic_v = v[8];
    int k = 10;
    /* knots S, knots T, weights, points: exactly as written */
    double *dst[4] = {s->knots_u, s->knots_v, s->weights, s->ctrl};
    long long cnt[4] = {nk1, nk2, nw, 3 * nw};
    for (int a = 0; a < 4; ++a)
        for (long long i = 0; st == SEM_OK && i < cnt[a]; ++i)
            st = iges_param_real(r, idx, k++, &dst[a][i]);
    double *range[4] = {&s->u0, &s->u1, &s->v0, &s->v1};
    for (int i = 0; st == SEM_OK && i < 4; ++i) st = iges_param_real(r, idx, k++, range[i]);
    if (st != SEM_OK) {
        sem_surface_free(s);
        return st;
    }
    /* A range that is empty or leaves the knots (Rhino 2001 wrote U0 V0 U1 V1 in the wrong
     * order: corpus occt_rhino_bounded_143) is the knots' own, as Open CASCADE reads it. */
    double ua = s->knots_u[M1], ub = s->knots_u[n1], va = s->knots_v[M2], vb = s->knots_v[n2];
    double tu = 1e-9 * (ub - ua), tv = 1e-9 * (vb - va);
    if (ub > ua && vb > va &&
        (!(s->u1 > s->u0) || !(s->v1 > s->v0) || s->u0 < ua - tu || s->u1 > ub + tu ||
         s->v0 < va - tv || s->v1 > vb + tv)) {
        if (!r->entries[idx].repaired)
            sem_model_warn(r->model, "entity 128 (DE %d): parameter range [%g,%g] x [%g,%g] is "
                                     "empty or outside the knots; the knots' range [%g,%g] x "
                                     "[%g,%g] is used",
                           iges_de_number(idx), s->u0, s->u1, s->v0, s->v1, ua, ub, va, vb);
        r->entries[idx].repaired = 1;
        s->u0 = ua, s->u1 = ub, s->v0 = va, s->v1 = vb;
    }
    r->entries[idx].n_used = k;
    return SEM_OK;
}

static void set_bilinear(sem_surface *s, const double o[3], const double e1[3],
                         const double e2[3], double u0, double u1, double v0, double v1)
{
    double uv[4][2] = {{u0, v0}, {u1, v0}, {u0, v1}, {u1, v1}};
    for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) s->ctrl[3 * k + d] = o[d] + uv[k][0] * e1[d] + uv[k][1] * e2[d];
    s->knots_u[0] = s->knots_u[1] = s->u0 = u0;
    s->knots_u[2] = s->knots_u[3] = s->u1 = u1;
    s->knots_v[0] = s->knots_v[1] = s->v0 = v0;
    s->knots_v[2] = s->knots_v[3] = s->v1 = v1;
}

/* 108: the plane A x + B y + C z = D. A bounded plane (PTR to a closed curve) becomes the
 * bilinear patch over the bounding box of the curve's control points in an orthonormal
 * frame of the plane, trimmed by that curve mapped into the frame (an affine map, so the
 * trim curve is exact). An unbounded plane (PTR = 0) inside a trimmed entity or face with
 * model-space boundary curves is fitted to that boundary (surface_hint); elsewhere, with a
 * display SIZE, it becomes the square of half side SIZE centred at the display point
 * projected onto the plane. */
static sem_status read_plane(iges_reader *r, int idx, int depth, sem_part *part)
{
    double a[4], xyz[3], size;
    int ptr;
    sem_status st = iges_need(r, idx, 1, 9, "plane");
    for (int k = 0; st == SEM_OK && k < 4; ++k) st = iges_param_real(r, idx, 1 + k, &a[k]);
    if (st == SEM_OK) st = iges_param_ptr(r, idx, 5, 1, &ptr);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = iges_param_real(r, idx, 6 + k, &xyz[k]);
    if (st == SEM_OK) st = iges_param_real(r, idx, 9, &size);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 10;
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(len > 0))
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1), "plane normal is zero");
    double n[3] = {a[0] / len, a[1] / len, a[2] / len}, dist = a[3] / len;
    /* e1 = normalize(axis x n) with the axis least aligned with n; e2 = n x e1 */
    int ax = fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0
             : fabs(n[1]) <= fabs(n[2])                           ? 1
                                                                  : 2;
    double axis[3] = {0, 0, 0};
    axis[ax] = 1.0;
    double e1[3] = {axis[1] * n[2] - axis[2] * n[1], axis[2] * n[0] - axis[0] * n[2],
                    axis[0] * n[1] - axis[1] * n[0]};
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int d = 0; d < 3; ++d) e1[d] /= l1;
    double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2],
                    n[0] * e1[1] - n[1] * e1[0]};
    double off = n[0] * xyz[0] + n[1] * xyz[1] + n[2] * xyz[2] - dist;
    double o[3] = {xyz[0] - off * n[0], xyz[1] - off * n[1], xyz[2] - off * n[2]};
    if (sem_surface_alloc(&part->surface, 1, 1, 2, 2) != SEM_OK) return iges_nomem(r);
    if (ptr < 0) {
        /* An unbounded plane inside a trimmed entity or face is sized by that boundary, with
         * or without a display size: SIZE only says how large to draw the plane's symbol
         * (CATIA writes 1.0 whatever the face), and taking it as the extent left the
         * boundary off the surface (occt_cone_catia, occt_cylinder_catia in the corpus). */
        if (r->surface_hint) {
            set_bilinear(&part->surface, o, e1, e2, -1.0, 1.0, -1.0, 1.0);
            r->from_hint = 1;
            r->hint_fit = HINT_PLANE;
            return SEM_OK;
        }
        if (!(size > 0)) {
            sem_surface_free(&part->surface);
            sem_model_warn(r->model, "entity 108 (DE %d): unbounded plane without a display "
                                     "size, skipped",
                           iges_de_number(idx));
            return SEM_ERR_UNSUPPORTED;
        }
        set_bilinear(&part->surface, o, e1, e2, -size, size, -size, size);
        return SEM_OK;
    }
    curve_list l;
    memset(&l, 0, sizeof l);
    st = iges_read_curves(r, ptr, iges_identity_xf, depth + 1, &l);
    if (st != SEM_OK) {
        iges_list_free(&l);
        sem_surface_free(&part->surface);
        return st;
    }
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < l.n; ++i) {
        sem_curve *c = &l.c[i];
        for (int j = 0; j < c->n_ctrl; ++j) {
            double *p = c->ctrl + 3 * j, q[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
            p[0] = q[0] * e1[0] + q[1] * e1[1] + q[2] * e1[2];
            p[1] = q[0] * e2[0] + q[1] * e2[1] + q[2] * e2[2];
            p[2] = 0.0;
            for (int d = 0; d < 2; ++d) {
                lo[d] = fmin(lo[d], p[d]);
                hi[d] = fmax(hi[d], p[d]);
            }
        }
    }
    if (!(hi[0] > lo[0]) || !(hi[1] > lo[1])) {
        iges_list_free(&l);
        sem_surface_free(&part->surface);
        return iges_entity_error(r, idx, 0, "bounding curve DE %d encloses no area",
                                 iges_de_number(ptr));
    }
    set_bilinear(&part->surface, o, e1, e2, lo[0], hi[0], lo[1], hi[1]);
    part->has_outer = 1;
    part->outer.n_curves = l.n;
    part->outer.curves = l.c;
    return SEM_OK;
}

/* 118: the segments between C1(t) and C2(t) for equal relative parameter t. The two curves
 * get one degree and one knot vector, and the surface is degree 1 across: rows C1 and C2. */
static sem_status read_ruled(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int p1, p2, dirflg;
    sem_status st = iges_param_ptr(r, idx, 1, 0, &p1);
    if (st == SEM_OK) st = iges_param_ptr(r, idx, 2, 0, &p2);
    if (st == SEM_OK) st = iges_param_int(r, idx, 3, &dirflg);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = iges_remaining(r, idx, 4) > 0 ? 5 : 4;
    sem_curve a, b;
    st = read_single_curve(r, p1, iges_identity_xf, depth + 1, idx, &a);
    if (st != SEM_OK) return st;
    st = read_single_curve(r, p2, iges_identity_xf, depth + 1, idx, &b);
    if (st != SEM_OK) {
        sem_curve_free(&a);
        return st;
    }
    if (!sem_curve_is_clamped(&a) || !sem_curve_is_clamped(&b)) {
        sem_curve_free(&a);
        sem_curve_free(&b);
        sem_model_warn(r->model, "entity 118 (DE %d): ruled surface over unclamped curves not "
                                 "supported, skipped", iges_de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    if (r->entries[idx].form == 0 && (a.degree > 1 || b.degree > 1 || a.n_ctrl > 2 || b.n_ctrl > 2))
        sem_model_warn(r->model, "entity 118 (DE %d): ruled by equal parameter (form 1); equal "
                                 "arc length (form 0) is not exactly representable",
                       iges_de_number(idx));
    sem_curve_normalize(&a);
    sem_curve_normalize(&b);
    if (dirflg == 1) curve_reverse(&b);
    st = sem_curves_make_compatible(&a, &b);
    if (st == SEM_OK && a.n_ctrl != b.n_ctrl) st = SEM_ERR_INVALID;
    if (st == SEM_ERR_INVALID) {
        sem_curve_free(&a);
        sem_curve_free(&b);
        sem_model_warn(r->model, "entity 118 (DE %d): ruled surface over discontinuous curves "
                                 "not supported, skipped", iges_de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    if (st != SEM_OK) st = iges_nomem(r);
    if (st == SEM_OK && sem_surface_alloc(s, a.degree, 1, a.n_ctrl, 2) != SEM_OK)
        st = iges_nomem(r);
    if (st == SEM_OK) {
        memcpy(s->knots_u, a.knots, (size_t)(a.n_ctrl + a.degree + 1) * sizeof(double));
        s->knots_v[2] = s->knots_v[3] = 1.0;
        memcpy(s->ctrl, a.ctrl, (size_t)a.n_ctrl * 3 * sizeof(double));
        memcpy(s->ctrl + 3 * a.n_ctrl, b.ctrl, (size_t)b.n_ctrl * 3 * sizeof(double));
        memcpy(s->weights, a.weights, (size_t)a.n_ctrl * sizeof(double));
        memcpy(s->weights + a.n_ctrl, b.weights, (size_t)b.n_ctrl * sizeof(double));
        s->u0 = 0.0;
        s->u1 = 1.0;
        s->v0 = 0.0;
        s->v1 = 1.0;
    }
    sem_curve_free(&a);
    sem_curve_free(&b);
    return st;
}

/* 120: the generatrix C(t) rotated about the axis line from angle SA to TA. u is the
 * generatrix parameter, v the angle (knots in radians); each control point sweeps an exact
 * circle as a rational quadratic with pieces of at most 90 degrees (Piegl & Tiller A8.1). */
static sem_status read_revolution(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int pl, pc;
    double sa, ta;
    sem_status st = iges_param_ptr(r, idx, 1, 0, &pl);
    if (st == SEM_OK) st = iges_param_ptr(r, idx, 2, 0, &pc);
    if (st == SEM_OK) st = iges_param_real(r, idx, 3, &sa);
    if (st == SEM_OK) st = iges_param_real(r, idx, 4, &ta);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5;
    if (r->entries[pl].type != 110)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "axis DE %d is a type-%d entity, not a line (110)",
                                 iges_de_number(pl), r->entries[pl].type);
    double sweep = ta - sa;
    if (!(sweep > 0) || sweep > 2 * M_PI * (1 + 1e-12))
        return iges_entity_error(r, idx, iges_token_line(r, idx, 3),
                                 "rotation angles %.17g..%.17g do not give a sweep in (0, 2 pi]",
                                 sa, ta);
    double p0[3], p1[3], m[12];
    st = read_line(r, pl, p0, p1);
    if (st == SEM_OK) st = iges_own_xform(r, pl, iges_identity_xf, m);
    if (st != SEM_OK) return st;
    iges_xf_apply(m, p0, 1);
    iges_xf_apply(m, p1, 1);
    double ax[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    double al = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    if (!(al > 0)) return iges_entity_error(r, pl, 0, "axis line has zero length");
    for (int d = 0; d < 3; ++d) ax[d] /= al;
    sem_curve c;
    st = read_single_curve(r, pc, iges_identity_xf, depth + 1, idx, &c);
    if (st != SEM_OK) return st;
    int nseg = (int)ceil(sweep / (M_PI / 2) - 1e-9);
    if (nseg < 1) nseg = 1;
    if (nseg > 4) nseg = 4;
    double dt = sweep / nseg, wm = cos(dt / 2);
    int nv = 2 * nseg + 1;
    if (sem_surface_alloc(s, c.degree, 2, c.n_ctrl, nv) != SEM_OK) {
        sem_curve_free(&c);
        return iges_nomem(r);
    }
    memcpy(s->knots_u, c.knots, (size_t)(c.n_ctrl + c.degree + 1) * sizeof(double));
    int k = 0;
    for (int i = 0; i < 3; ++i) s->knots_v[k++] = sa;
    for (int i = 1; i < nseg; ++i) {
        s->knots_v[k++] = sa + i * dt;
        s->knots_v[k++] = sa + i * dt;
    }
    for (int i = 0; i < 3; ++i) s->knots_v[k++] = ta;
    for (int i = 0; i < c.n_ctrl; ++i) {
        const double *P = c.ctrl + 3 * i;
        double h = (P[0] - p0[0]) * ax[0] + (P[1] - p0[1]) * ax[1] + (P[2] - p0[2]) * ax[2];
        double O[3] = {p0[0] + h * ax[0], p0[1] + h * ax[1], p0[2] + h * ax[2]};
        double X[3] = {P[0] - O[0], P[1] - O[1], P[2] - O[2]};
        double Y[3] = {ax[1] * X[2] - ax[2] * X[1], ax[2] * X[0] - ax[0] * X[2],
                       ax[0] * X[1] - ax[1] * X[0]};
        for (int j = 0; j < nv; ++j) {
            double ang = sa + j * dt / 2, f = (j % 2) ? 1.0 / wm : 1.0;
            double cs = cos(ang) * f, sn = sin(ang) * f;
            double *Q = s->ctrl + 3 * ((size_t)i + (size_t)c.n_ctrl * j);
            for (int d = 0; d < 3; ++d) Q[d] = O[d] + cs * X[d] + sn * Y[d];
            s->weights[i + c.n_ctrl * j] = c.weights[i] * ((j % 2) ? wm : 1.0);
        }
    }
    s->u0 = c.t0;
    s->u1 = c.t1;
    s->v0 = sa;
    s->v1 = ta;
    sem_curve_free(&c);
    r->inexact_param = 1; /* v: the angle in the file, a rational circle's parameter here */
    return SEM_OK;
}

/* 122: the directrix C(t) swept along L - C(t0): degree 1 in v on [0, 1]. */
static sem_status read_tabulated(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int pc;
    double L[3];
    sem_status st = iges_param_ptr(r, idx, 1, 0, &pc);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = iges_param_real(r, idx, 2 + k, &L[k]);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5;
    sem_curve c;
    st = read_single_curve(r, pc, iges_identity_xf, depth + 1, idx, &c);
    if (st != SEM_OK) return st;
    /* IGES parameterizes a tabulated cylinder by t = t0 + u (t1 - t0), u in [0, 1]: the
     * file's trim curves use that u (corpus dealii_side_inch: a directrix on [0, 3] trimmed
     * in [0, 1] kept a third of the face). An affine map of the knots is exact. */
    if (c.t0 != 0.0 || c.t1 != 1.0) {
        double a = c.t0, b = c.t1;
        for (int i = 0; i < c.n_ctrl + c.degree + 1; ++i) c.knots[i] = (c.knots[i] - a) / (b - a);
        c.t0 = 0.0;
        c.t1 = 1.0;
    }
    double start[3];
    sem_curve_eval(&c, c.t0, start, NULL);
    double d[3] = {L[0] - start[0], L[1] - start[1], L[2] - start[2]};
    if (sem_surface_alloc(s, c.degree, 1, c.n_ctrl, 2) != SEM_OK) {
        sem_curve_free(&c);
        return iges_nomem(r);
    }
    memcpy(s->knots_u, c.knots, (size_t)(c.n_ctrl + c.degree + 1) * sizeof(double));
    s->knots_v[2] = s->knots_v[3] = 1.0;
    for (int i = 0; i < c.n_ctrl; ++i) {
        for (int k = 0; k < 3; ++k) {
            s->ctrl[3 * i + k] = c.ctrl[3 * i + k];
            s->ctrl[3 * (i + c.n_ctrl) + k] = c.ctrl[3 * i + k] + d[k];
        }
        s->weights[i] = s->weights[i + c.n_ctrl] = c.weights[i];
    }
    s->u0 = c.t0;
    s->u1 = c.t1;
    s->v0 = 0.0;
    s->v1 = 1.0;
    sem_curve_free(&c);
    /* u: the directrix's own parameter in the file; ours for lines and B-splines only */
    if (r->entries[pc].type != 110 && r->entries[pc].type != 126) r->inexact_param = 1;
    return SEM_OK;
}

/* A point (116) or direction (123) entity's three coordinates. */
static sem_status read_vector(iges_reader *r, int owner, int k, int want, int allow_null,
                              double out[3], int *present)
{
    int p = -1;
    *present = 0;
    sem_status st = iges_param_ptr(r, owner, k, allow_null, &p);
    if (st != SEM_OK || p < 0) return st;
    if (r->entries[p].type != want)
        return iges_entity_error(
            r, owner, iges_token_line(r, owner, k),
            "parameter %d points to DE %d, a type-%d entity, where a %s (%d) is "
            "expected",
            k, iges_de_number(p), r->entries[p].type, want == 116 ? "point" : "direction", want);
    st = iges_need(r, p, 1, 3, want == 116 ? "point" : "direction");
    for (int d = 0; st == SEM_OK && d < 3; ++d) st = iges_param_real(r, p, 1 + d, &out[d]);
    if (st == SEM_OK) {
        r->entries[p].n_used = 4;
        *present = 1;
    }
    return st;
}

/* 190-198 (IGES 5.3 analytic surfaces) as exact NURBS (geometry/analytic_surfaces.c):
 * plane, right circular cylinder and cone, sphere, torus. Their parameters are ours, not the
 * file's, so their loops come from model space (from_hint); planes, cylinders and cones are
 * unbounded and need the boundary to size them (surface_hint), spheres and tori are whole. */
static sem_status read_analytic(iges_reader *r, int idx, sem_part *part)
{
    const iges_entry *e = &r->entries[idx];
    int type = e->type, form = e->form, have, have_axis = 0, have_ref = 0;
    double loc[3], axis[3] = {0, 0, 1}, ref[3], radius = 0, second = 0;
    sem_status st = read_vector(r, idx, 1, 116, 0, loc, &have);
    int k = 2;
    if (st == SEM_OK && type != 196) {
        st = read_vector(r, idx, 2, 123, 0, axis, &have_axis);
        k = 3;
    }
    if (st == SEM_OK && type != 190) st = iges_param_real(r, idx, k++, &radius);
    if (st == SEM_OK && (type == 194 || type == 198)) st = iges_param_real(r, idx, k++, &second);
    if (st == SEM_OK && type == 196 && form == 1) st = read_vector(r, idx, k++, 123, 1, axis, &have_axis);
    if (st == SEM_OK && form == 1) st = read_vector(r, idx, k++, 123, 1, ref, &have_ref);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = k;
    if (type != 190 && !(radius > 0))
        return iges_entity_error(r, idx, 0, "radius must be positive (got %g)", radius);
    if (type == 198 && !(second > 0 && second < radius))
        return iges_entity_error(r, idx, 0, "minor radius must be in (0, major radius) (got %g)",
                                 second);
    if (type == 194 && !(fabs(second) < 90))
        return iges_entity_error(r, idx, 0, "cone semi-angle must be below 90 degrees (got %g)",
                                 second);
    int bounded = type == 196 || type == 198;
    if (!bounded && !r->surface_hint) {
        const char *d = iges_entity_description(type);
        sem_model_warn(r->model, "entity %d (DE %d): unbounded %s outside a trimmed face, skipped",
                       type, iges_de_number(idx), d ? d : "surface");
        return SEM_ERR_UNSUPPORTED;
    }
    sem_frame f;
    sem_error ferr;
    if (sem_frame_make(loc, axis, have_ref ? ref : NULL, &f, &ferr) != SEM_OK)
        return iges_entity_error(r, idx, 0, "axis or normal direction is zero");
    switch (type) {
    case 190: st = sem_analytic_plane(&part->surface, &f, 1.0, &ferr); break;
    case 192: st = sem_analytic_cone(&part->surface, &f, radius, 0.0, 0.0, 1.0, &ferr); break;
    case 194:
        st = sem_analytic_cone(&part->surface, &f, radius, tan(second * M_PI / 180.0), 0.0, 1.0,
                               &ferr);
        break;
    case 196: st = sem_analytic_sphere(&part->surface, &f, radius, &ferr); break;
    default: st = sem_analytic_torus(&part->surface, &f, radius, second, &ferr); break;
    }
    if (st != SEM_OK) return iges_nomem(r);
    r->from_hint = 1;
    r->hint_fit = type == 190 ? HINT_PLANE : (type == 192 || type == 194) ? HINT_AXIAL : HINT_NONE;
    /* form 0 does not say where the seam is: place it by the face's boundary */
    r->hint_seam = type != 190 && !have_ref;
    return SEM_OK;
}

/* Any surface entity as a NURBS surface in the coordinates parent o (own transform). A
 * bounded plane also fills part->outer. */
sem_status iges_read_surface(iges_reader *r, int idx, const double *parent, int depth,
                             sem_part *part)
{
    iges_entry *e = &r->entries[idx];
    double m[12];
    sem_status st = iges_enter_entity(r, idx, parent, depth, m);
    if (st != SEM_OK) return st;
    e->busy = 1;
    switch (e->type) {
    case 128: st = read_nurbs_surface(r, idx, &part->surface); break;
    case 108: st = read_plane(r, idx, depth, part); break;
    case 118: st = read_ruled(r, idx, depth, &part->surface); break;
    case 120: st = read_revolution(r, idx, depth, &part->surface); break;
    case 122: st = read_tabulated(r, idx, depth, &part->surface); break;
    case 190:
    case 192:
    case 194:
    case 196:
    case 198: st = read_analytic(r, idx, part); break;
    default:
        st = is_surface_type(e->type) ? iges_unsupported(r, idx, "not supported, skipped")
                                      : iges_entity_error(r, idx, 0, "a surface was expected here");
    }
    e->busy = 0;
    sem_surface *s = &part->surface;
    if (st == SEM_OK && e->type != 128) {
        /* analytic surfaces are built from their curves: count the net now */
        st = iges_count_points(r, idx, (long long)s->n_u * s->n_v);
        if (st != SEM_OK) sem_part_free(part);
    }
    if (st != SEM_OK) return st;
    iges_xf_apply(m, s->ctrl, (size_t)s->n_u * (size_t)s->n_v);
    sem_error ve;
    if (sem_surface_validate(s, &ve) != SEM_OK) {
        sem_part_free(part);
        return iges_entity_error(r, idx, 0, "%s", ve.message);
    }
    return SEM_OK;
}

sem_status iges_surface_pointer(iges_reader *r, int idx, int k, int *out)
{
    sem_status st = iges_param_ptr(r, idx, k, 0, out);
    if (st != SEM_OK) return st;
    if (!is_surface_type(r->entries[*out].type))
        return iges_entity_error(
            r, idx, iges_token_line(r, idx, k),
            "parameter %d points to DE %d, a type-%d entity, where a surface is "
            "expected",
            k, iges_de_number(*out), r->entries[*out].type);
    return SEM_OK;
}
