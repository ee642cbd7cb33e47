/*
 * obj_freeform.c - Wavefront OBJ free-form geometry (the "surf" / "curv2" part of the
 * OBJ specification, Appendix B1 of the Advanced Visualizer manual) read and written.
 *
 * Written form, per part:
 *     o <name>
 *     v x y z [w]                 control vertices, u index fastest (w when rational)
 *     vp u v [w]                  control points of the part's trim curves
 *     cstype [rat] bspline        per curve, then
 *     deg p / curv2 i1 i2 ... / parm u k0 k1 ... / end
 *     cstype [rat] bspline / deg pu pv
 *     surf u0 u1 v0 v1 i1 i2 ... / parm u ... / parm v ...
 *     trim t0 t1 c1 t0 t1 c2 ...  the outer loop (one statement)
 *     hole t0 t1 c ...            one statement per hole
 *     end
 * plus a comment "# sem units NAME METERS" that this reader understands and others skip.
 *
 * Read: the same, and "cstype bezier" (converted exactly to a B-spline by repeating every
 * interior break point degree times), non-rational types without weights, negative
 * (relative) indices, "v/vt/vn" references, '#' comments and '\' line continuation.
 * Polygon statements (f, l, p, vt, vn ...) and 3D curves are skipped with a warning.
 * Every error names the file and line: "FILE:LINE: what is wrong".
 *
 * Bounds (sem/limits.h): the file size, the knots per direction, the control points of a
 * surface and of the model. Trim references copy their curve, so the copies count against
 * SEM_MAX_MODEL_CONTROL_POINTS like the surfaces do (one large curv2 referenced by many
 * trim statements would otherwise multiply the memory). Every trim loop must close, as
 * the IGES reader requires.
 */
#include "sem/model.h"

#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/atomic_file.h"
#include "io/read_file.h"
#include "io/real_format.h"
#include "sem/limits.h"
#include "sem/nurbs.h"
#include "sem/trim.h"

/* ------------------------------------------------------------------------------------ */
/* reading                                                                              */
/* ------------------------------------------------------------------------------------ */

typedef struct double_array {
    double *x;
    size_t n, cap;
} double_array;

static int push_double(double_array *a, double v)
{
    if (a->n == a->cap) {
        size_t nc = a->cap ? 2 * a->cap : 64;
        double *x = realloc(a->x, nc * sizeof *x);
        if (!x) return 0;
        a->x = x;
        a->cap = nc;
    }
    a->x[a->n++] = v;
    return 1;
}

typedef enum basis_type { BASIS_NONE, BASIS_BEZIER, BASIS_BSPLINE, BASIS_OTHER } basis_type;

typedef enum element_kind { ELEMENT_NONE, ELEMENT_SURF, ELEMENT_CURV2, ELEMENT_SKIP } element_kind;

/* A reference to a trim curve inside a trim/hole statement. */
typedef struct trim_ref {
    double t0, t1;
    int curve; /* 0-based index into the curv2 list */
} trim_ref;

typedef struct pending_loop {
    int is_hole;
    int line;
    int n_refs;
    trim_ref *refs;
} pending_loop;

/* A finished surface waiting for its trim curves (curv2 may follow the surf). */
typedef struct pending_surface {
    sem_part part; /* surface and name; loops filled at the end */
    int line;
    int n_loops;
    pending_loop *loops;
} pending_surface;

typedef struct element {
    element_kind kind;
    int line;
    int rational;
    basis_type basis;
    int deg_u, deg_v;
    double range[4];
    double_array points; /* 4 per vertex (x,y,z,w) for surf, 3 per point (u,v,w) for curv2 */
    double_array parm_u, parm_v;
    int has_parm_u, has_parm_v;
    int n_loops;
    pending_loop *loops;
} element;

typedef struct obj_reader {
    const char *path;
    int line;
    sem_error *err;
    sem_model *model;
    double_array v;  /* 4 per vertex */
    double_array vp; /* 3 per point */
    int rational;
    basis_type basis;
    char basis_name[32];
    int deg_u, deg_v; /* 0 = not given */
    char name[64];
    element current;
    sem_curve *curves;
    int n_curves, cap_curves;
    pending_surface *surfaces;
    int n_surfaces, cap_surfaces;
    int n_polygon_statements, n_skipped_curves, n_ignored;
    long long built_points; /* control points referenced so far (SEM_MAX_MODEL_CONTROL_POINTS) */
} obj_reader;

static sem_status parse_error(obj_reader *r, sem_status st, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;

static sem_status parse_error(obj_reader *r, sem_status st, const char *fmt, ...)
{
    char place[1024];
    snprintf(place, sizeof place, "%s:%d", r->path, r->line);
    va_list ap;
    va_start(ap, fmt);
    sem_status status = sem_error_vset(r->err, st, place, fmt, ap);
    va_end(ap);
    return status;
}

static sem_status no_memory(obj_reader *r)
{
    return parse_error(r, SEM_ERR_NOMEM, "out of memory");
}

/* Counts n control points (surface vertices, curve points, trim copies) against the model
 * budget. */
static sem_status count_points(obj_reader *r, long long n)
{
    r->built_points += n;
    if (r->built_points <= SEM_MAX_MODEL_CONTROL_POINTS) return SEM_OK;
    return parse_error(r, SEM_ERR_PARSE, "the model would have more than %d control points "
                                         "(surfaces and trim curves, every trim reference "
                                         "counted; limit SEM_MAX_MODEL_CONTROL_POINTS)",
                       SEM_MAX_MODEL_CONTROL_POINTS);
}

static sem_status parse_real(obj_reader *r, const char *tok, double *out)
{
    char *end;
    errno = 0;
    double x = strtod(tok, &end);
    if (end == tok || *end != '\0')
        return parse_error(r, SEM_ERR_PARSE, "'%s' is not a number", tok);
    if (!isfinite(x))
        return parse_error(r, SEM_ERR_PARSE, "'%s' is not a finite number", tok);
    *out = x;
    return SEM_OK;
}

static sem_status parse_int(obj_reader *r, const char *tok, long *out)
{
    char *end;
    errno = 0;
    long x = strtol(tok, &end, 10);
    if (end == tok || (*end != '\0' && *end != '/'))
        return parse_error(r, SEM_ERR_PARSE, "'%s' is not an integer", tok);
    if (errno == ERANGE || x > INT_MAX || x < -INT_MAX)
        return parse_error(r, SEM_ERR_PARSE, "index '%s' is out of range", tok);
    *out = x;
    return SEM_OK;
}

/* Resolves a 1-based or negative (relative) index into [0, count). */
static sem_status resolve_index(obj_reader *r, const char *tok, size_t count, const char *what,
                                int *out)
{
    long i = 0;
    sem_status st = parse_int(r, tok, &i);
    if (st != SEM_OK) return st;
    long resolved = i > 0 ? i - 1 : (long)count + i;
    if (i == 0 || resolved < 0 || resolved >= (long)count)
        return parse_error(r, SEM_ERR_PARSE, "%s index %ld out of range (%zu defined so far)",
                           what, i, count);
    *out = (int)resolved;
    return SEM_OK;
}

static void element_free(element *e)
{
    free(e->points.x);
    free(e->parm_u.x);
    free(e->parm_v.x);
    for (int i = 0; i < e->n_loops; ++i) free(e->loops[i].refs);
    free(e->loops);
    memset(e, 0, sizeof *e);
}

static void reader_free(obj_reader *r)
{
    free(r->v.x);
    free(r->vp.x);
    element_free(&r->current);
    for (int i = 0; i < r->n_curves; ++i) sem_curve_free(&r->curves[i]);
    free(r->curves);
    for (int i = 0; i < r->n_surfaces; ++i) {
        sem_part_free(&r->surfaces[i].part);
        for (int l = 0; l < r->surfaces[i].n_loops; ++l) free(r->surfaces[i].loops[l].refs);
        free(r->surfaces[i].loops);
    }
    free(r->surfaces);
}

/* Knot vector from a "parm" list: as is for B-splines, break points repeated for Bezier.
 * n_ctrl_out is the number of control points that the knots imply. */
static sem_status knots_from_parm(obj_reader *r, const element *e, const double_array *parm,
                                  int degree, const char *dir, double **knots_out, int *n_ctrl_out)
{
    *knots_out = NULL;
    size_t np = parm->n;
    for (size_t i = 1; i < np; ++i)
        if (parm->x[i] < parm->x[i - 1])
            return parse_error(r, SEM_ERR_PARSE, "parm %s values decrease (%.17g after %.17g)",
                               dir, parm->x[i], parm->x[i - 1]);
    if (e->basis == BASIS_BEZIER) {
        if (np < 2)
            return parse_error(r, SEM_ERR_PARSE, "parm %s of a Bezier needs at least 2 values",
                               dir);
        for (size_t i = 1; i < np; ++i)
            if (!(parm->x[i] > parm->x[i - 1]))
                return parse_error(r, SEM_ERR_PARSE, "parm %s of a Bezier repeats %.17g", dir,
                                   parm->x[i]);
        size_t segments = np - 1;
        if (segments > (size_t)(SEM_MAX_KNOTS - 2 * degree - 2) / (size_t)degree)
            return parse_error(r, SEM_ERR_PARSE, "parm %s: %zu Bezier segments of degree %d "
                                                 "need more than %d knots (limit SEM_MAX_KNOTS)",
                               dir, segments, degree, SEM_MAX_KNOTS);
        int n_ctrl = (int)segments * degree + 1;
        double *k = malloc((size_t)(n_ctrl + degree + 1) * sizeof *k);
        if (!k) return no_memory(r);
        int m = 0;
        for (size_t i = 0; i < np; ++i) {
            int mult = (i == 0 || i == np - 1) ? degree + 1 : degree;
            for (int j = 0; j < mult; ++j) k[m++] = parm->x[i];
        }
        *knots_out = k;
        *n_ctrl_out = n_ctrl;
        return SEM_OK;
    }
    if (np < (size_t)(2 * degree + 2))
        return parse_error(r, SEM_ERR_PARSE,
                           "parm %s has %zu knots; degree %d needs at least %d", dir, np, degree,
                           2 * degree + 2);
    if (np > (size_t)SEM_MAX_KNOTS)
        return parse_error(r, SEM_ERR_PARSE, "parm %s has %zu knots; at most %d (limit "
                                             "SEM_MAX_KNOTS)", dir, np, SEM_MAX_KNOTS);
    double *k = malloc(np * sizeof *k);
    if (!k) return no_memory(r);
    memcpy(k, parm->x, np * sizeof *k);
    *knots_out = k;
    *n_ctrl_out = (int)np - degree - 1;
    return SEM_OK;
}

static sem_status check_basis(obj_reader *r, const element *e, const char *what)
{
    if (e->basis == BASIS_NONE)
        return parse_error(r, SEM_ERR_PARSE, "%s before any cstype statement", what);
    if (e->basis == BASIS_OTHER)
        return parse_error(r, SEM_ERR_UNSUPPORTED,
                           "cstype %s is not supported (only bezier and bspline)", r->basis_name);
    if (e->deg_u < 1) return parse_error(r, SEM_ERR_PARSE, "%s before any deg statement", what);
    return SEM_OK;
}

static sem_status finish_surface(obj_reader *r)
{
    element *e = &r->current;
    int line = r->line;
    r->line = e->line; /* report problems at the surf statement */
    sem_status st = check_basis(r, e, "surf");
    if (st != SEM_OK) return st;
    if (e->deg_v < 1)
        return parse_error(r, SEM_ERR_PARSE, "surf needs two degrees ('deg du dv'), got one");
    if (!e->has_parm_u || !e->has_parm_v)
        return parse_error(r, SEM_ERR_PARSE, "surf without 'parm %s' before its end",
                           e->has_parm_u ? "v" : "u");
    double *ku = NULL, *kv = NULL;
    int n_u = 0, n_v = 0;
    st = knots_from_parm(r, e, &e->parm_u, e->deg_u, "u", &ku, &n_u);
    if (st == SEM_OK) st = knots_from_parm(r, e, &e->parm_v, e->deg_v, "v", &kv, &n_v);
    size_t n_given = e->points.n / 4;
    if (st == SEM_OK && (size_t)n_u * (size_t)n_v != n_given)
        st = parse_error(r, SEM_ERR_PARSE,
                         "surf has %zu control vertices; degree (%d, %d) with %zu and %zu parm "
                         "values needs %d x %d = %lld",
                         n_given, e->deg_u, e->deg_v, e->parm_u.n, e->parm_v.n, n_u, n_v,
                         (long long)n_u * n_v);
    if (st == SEM_OK && (long long)n_u * n_v > SEM_MAX_PART_CONTROL_POINTS)
        st = parse_error(r, SEM_ERR_PARSE, "surf has %d x %d control vertices; at most %d per "
                                           "surface (limit SEM_MAX_PART_CONTROL_POINTS)",
                         n_u, n_v, SEM_MAX_PART_CONTROL_POINTS);
    if (st == SEM_OK && r->n_surfaces >= SEM_MAX_PARTS)
        st = parse_error(r, SEM_ERR_PARSE, "more than %d surfaces (limit SEM_MAX_PARTS)",
                         SEM_MAX_PARTS);
    pending_surface ps;
    memset(&ps, 0, sizeof ps);
    if (st == SEM_OK && sem_surface_alloc(&ps.part.surface, e->deg_u, e->deg_v, n_u, n_v) != SEM_OK)
        st = no_memory(r);
    if (st != SEM_OK) {
        free(ku);
        free(kv);
        return st;
    }
    sem_surface *s = &ps.part.surface;
    memcpy(s->knots_u, ku, (size_t)(n_u + e->deg_u + 1) * sizeof *ku);
    memcpy(s->knots_v, kv, (size_t)(n_v + e->deg_v + 1) * sizeof *kv);
    free(ku);
    free(kv);
    for (size_t i = 0; i < n_given; ++i) {
        memcpy(s->ctrl + 3 * i, e->points.x + 4 * i, 3 * sizeof(double));
        s->weights[i] = e->rational ? e->points.x[4 * i + 3] : 1.0;
    }
    s->u0 = e->range[0];
    s->u1 = e->range[1];
    s->v0 = e->range[2];
    s->v1 = e->range[3];
    sem_error verr;
    if (sem_surface_validate(s, &verr) != SEM_OK) {
        sem_surface_free(s);
        return parse_error(r, SEM_ERR_PARSE, "surf: %s", verr.message);
    }
    snprintf(ps.part.name, sizeof ps.part.name, "%s", r->name);
    ps.line = e->line;
    ps.n_loops = e->n_loops;
    ps.loops = e->loops;
    e->loops = NULL;
    e->n_loops = 0;
    if (r->n_surfaces == r->cap_surfaces) {
        int nc = r->cap_surfaces ? 2 * r->cap_surfaces : 16;
        pending_surface *p = realloc(r->surfaces, (size_t)nc * sizeof *p);
        if (!p) {
            sem_part_free(&ps.part);
            for (int l = 0; l < ps.n_loops; ++l) free(ps.loops[l].refs);
            free(ps.loops);
            return no_memory(r);
        }
        r->surfaces = p;
        r->cap_surfaces = nc;
    }
    r->surfaces[r->n_surfaces++] = ps;
    r->line = line;
    return SEM_OK;
}

static sem_status finish_curve(obj_reader *r)
{
    element *e = &r->current;
    int line = r->line;
    r->line = e->line;
    sem_status st = check_basis(r, e, "curv2");
    if (st != SEM_OK) return st;
    if (!e->has_parm_u) return parse_error(r, SEM_ERR_PARSE, "curv2 without 'parm u' before its end");
    double *k = NULL;
    int n = 0;
    st = knots_from_parm(r, e, &e->parm_u, e->deg_u, "u", &k, &n);
    if (st != SEM_OK) return st;
    size_t n_given = e->points.n / 3;
    if ((size_t)n != n_given) {
        free(k);
        return parse_error(r, SEM_ERR_PARSE,
                           "curv2 has %zu control points; degree %d with %zu parm values needs %d",
                           n_given, e->deg_u, e->parm_u.n, n);
    }
    sem_curve c;
    if (sem_curve_alloc(&c, e->deg_u, n) != SEM_OK) {
        free(k);
        return no_memory(r);
    }
    memcpy(c.knots, k, (size_t)(n + e->deg_u + 1) * sizeof *k);
    free(k);
    for (int i = 0; i < n; ++i) {
        c.ctrl[3 * i] = e->points.x[3 * i];
        c.ctrl[3 * i + 1] = e->points.x[3 * i + 1];
        c.ctrl[3 * i + 2] = 0.0;
        c.weights[i] = e->rational ? e->points.x[3 * i + 2] : 1.0;
    }
    c.t0 = c.knots[c.degree];
    c.t1 = c.knots[c.n_ctrl];
    sem_error verr;
    if (sem_curve_validate(&c, &verr) != SEM_OK) {
        sem_curve_free(&c);
        return parse_error(r, SEM_ERR_PARSE, "curv2: %s", verr.message);
    }
    if (r->n_curves == r->cap_curves) {
        int nc = r->cap_curves ? 2 * r->cap_curves : 16;
        sem_curve *p = realloc(r->curves, (size_t)nc * sizeof *p);
        if (!p) {
            sem_curve_free(&c);
            return no_memory(r);
        }
        r->curves = p;
        r->cap_curves = nc;
    }
    r->curves[r->n_curves++] = c;
    r->line = line;
    return SEM_OK;
}

static sem_status begin_element(obj_reader *r, element_kind kind)
{
    if (r->current.kind != ELEMENT_NONE)
        return parse_error(r, SEM_ERR_PARSE, "new element before the 'end' of the one at line %d",
                           r->current.line);
    element *e = &r->current;
    memset(e, 0, sizeof *e);
    e->kind = kind;
    e->line = r->line;
    e->rational = r->rational;
    e->basis = r->basis;
    e->deg_u = r->deg_u;
    e->deg_v = r->deg_v;
    return SEM_OK;
}

static sem_status statement_surf(obj_reader *r, int ntok, char **tok)
{
    sem_status st = begin_element(r, ELEMENT_SURF);
    if (st != SEM_OK) return st;
    if (ntok < 6) return parse_error(r, SEM_ERR_PARSE, "surf needs s0 s1 t0 t1 and control vertices");
    for (int i = 0; i < 4; ++i) {
        st = parse_real(r, tok[1 + i], &r->current.range[i]);
        if (st != SEM_OK) return st;
    }
    if ((st = count_points(r, ntok - 5)) != SEM_OK) return st;
    for (int i = 5; i < ntok; ++i) {
        int idx = 0;
        st = resolve_index(r, tok[i], r->v.n / 4, "vertex", &idx);
        if (st != SEM_OK) return st;
        for (int k = 0; k < 4; ++k)
            if (!push_double(&r->current.points, r->v.x[4 * (size_t)idx + k])) return no_memory(r);
    }
    return SEM_OK;
}

static sem_status statement_curv2(obj_reader *r, int ntok, char **tok)
{
    sem_status st = begin_element(r, ELEMENT_CURV2);
    if (st != SEM_OK) return st;
    if (ntok < 3) return parse_error(r, SEM_ERR_PARSE, "curv2 needs at least 2 control points");
    if ((st = count_points(r, ntok - 1)) != SEM_OK) return st;
    for (int i = 1; i < ntok; ++i) {
        int idx = 0;
        st = resolve_index(r, tok[i], r->vp.n / 3, "parameter vertex (vp)", &idx);
        if (st != SEM_OK) return st;
        for (int k = 0; k < 3; ++k)
            if (!push_double(&r->current.points, r->vp.x[3 * (size_t)idx + k])) return no_memory(r);
    }
    return SEM_OK;
}

static sem_status statement_parm(obj_reader *r, int ntok, char **tok)
{
    element *e = &r->current;
    if (e->kind == ELEMENT_NONE) return parse_error(r, SEM_ERR_PARSE, "parm outside a surf or curv2");
    if (e->kind == ELEMENT_SKIP) return SEM_OK;
    if (ntok < 3) return parse_error(r, SEM_ERR_PARSE, "parm needs a direction and values");
    double_array *a;
    if (strcmp(tok[1], "u") == 0) {
        a = &e->parm_u;
        e->has_parm_u = 1;
    } else if (strcmp(tok[1], "v") == 0 && e->kind == ELEMENT_SURF) {
        a = &e->parm_v;
        e->has_parm_v = 1;
    } else {
        return parse_error(r, SEM_ERR_PARSE, "parm direction '%s' (expected u%s)", tok[1],
                           e->kind == ELEMENT_SURF ? " or v" : "");
    }
    a->n = 0;
    for (int i = 2; i < ntok; ++i) {
        double x = 0.0;
        sem_status st = parse_real(r, tok[i], &x);
        if (st != SEM_OK) return st;
        if (!push_double(a, x)) return no_memory(r);
    }
    return SEM_OK;
}

static sem_status statement_trim(obj_reader *r, int ntok, char **tok, int is_hole)
{
    element *e = &r->current;
    if (e->kind == ELEMENT_SKIP) return SEM_OK;
    if (e->kind != ELEMENT_SURF)
        return parse_error(r, SEM_ERR_PARSE, "%s outside a surf", is_hole ? "hole" : "trim");
    if (ntok < 4 || (ntok - 1) % 3 != 0)
        return parse_error(r, SEM_ERR_PARSE, "%s needs groups of 'u0 u1 curv2' (got %d values)",
                           is_hole ? "hole" : "trim", ntok - 1);
    if (!is_hole)
        for (int l = 0; l < e->n_loops; ++l)
            if (!e->loops[l].is_hole)
                return parse_error(r, SEM_ERR_UNSUPPORTED,
                                   "a second outer 'trim' loop (line %d had one); one outer "
                                   "loop per surface is supported",
                                   e->loops[l].line);
    pending_loop *loops = realloc(e->loops, (size_t)(e->n_loops + 1) * sizeof *loops);
    if (!loops) return no_memory(r);
    e->loops = loops;
    pending_loop *l = &e->loops[e->n_loops++];
    memset(l, 0, sizeof *l);
    l->is_hole = is_hole;
    l->line = r->line;
    int n = (ntok - 1) / 3;
    l->refs = calloc((size_t)n, sizeof *l->refs);
    if (!l->refs) return no_memory(r);
    l->n_refs = n;
    for (int i = 0; i < n; ++i) {
        trim_ref *t = &l->refs[i];
        sem_status st = parse_real(r, tok[1 + 3 * i], &t->t0);
        if (st == SEM_OK) st = parse_real(r, tok[2 + 3 * i], &t->t1);
        if (st != SEM_OK) return st;
        long idx = 0;
        st = parse_int(r, tok[3 + 3 * i], &idx);
        if (st != SEM_OK) return st;
        if (idx == 0)
            return parse_error(r, SEM_ERR_PARSE, "curv2 index 0 (indices start at 1)");
        if (idx < 0) {
            /* relative: counts back from the curves defined so far */
            if (-idx > r->n_curves)
                return parse_error(r, SEM_ERR_PARSE,
                                   "curv2 index %ld out of range (%d defined so far)", idx,
                                   r->n_curves);
            t->curve = r->n_curves + (int)idx;
        } else {
            t->curve = (int)idx - 1; /* checked when the file is complete */
        }
    }
    return SEM_OK;
}

static sem_status statement_end(obj_reader *r)
{
    element *e = &r->current;
    sem_status st = SEM_OK;
    switch (e->kind) {
    case ELEMENT_NONE: return parse_error(r, SEM_ERR_PARSE, "'end' without a surf or curv2");
    case ELEMENT_SURF: st = finish_surface(r); break;
    case ELEMENT_CURV2: st = finish_curve(r); break;
    case ELEMENT_SKIP: break;
    }
    element_free(e);
    return st;
}

static sem_status statement_vertex(obj_reader *r, int ntok, char **tok, int parametric)
{
    double x[4] = {0, 0, 0, 1};
    int need = parametric ? 1 : 3;
    if (ntok - 1 < need)
        return parse_error(r, SEM_ERR_PARSE, "%s needs at least %d coordinates",
                           parametric ? "vp" : "v", need);
    int n = ntok - 1;
    /* "v x y z r g b" (vertex colours, a common mesh extension) carries no weight */
    int max = parametric ? 3 : (n >= 6 ? 3 : 4);
    for (int i = 0; i < n && i < max; ++i) {
        sem_status st = parse_real(r, tok[1 + i], &x[i]);
        if (st != SEM_OK) return st;
    }
    if (parametric) {
        if (n < 3) x[2] = 1.0;
        if (!(x[2] > 0))
            return parse_error(r, SEM_ERR_PARSE, "vp weight %.17g must be positive", x[2]);
        for (int i = 0; i < 3; ++i)
            if (!push_double(&r->vp, x[i])) return no_memory(r);
    } else {
        if (!(x[3] > 0))
            return parse_error(r, SEM_ERR_PARSE, "v weight %.17g must be positive", x[3]);
        for (int i = 0; i < 4; ++i)
            if (!push_double(&r->v, x[i])) return no_memory(r);
    }
    return SEM_OK;
}

static sem_status statement_cstype(obj_reader *r, int ntok, char **tok)
{
    int i = 1;
    r->rational = 0;
    if (i < ntok && strcmp(tok[i], "rat") == 0) {
        r->rational = 1;
        ++i;
    }
    if (i != ntok - 1) return parse_error(r, SEM_ERR_PARSE, "cstype needs '[rat] type'");
    snprintf(r->basis_name, sizeof r->basis_name, "%s", tok[i]);
    if (strcmp(tok[i], "bspline") == 0) r->basis = BASIS_BSPLINE;
    else if (strcmp(tok[i], "bezier") == 0) r->basis = BASIS_BEZIER;
    else if (strcmp(tok[i], "bmatrix") == 0 || strcmp(tok[i], "cardinal") == 0 ||
             strcmp(tok[i], "taylor") == 0)
        r->basis = BASIS_OTHER;
    else return parse_error(r, SEM_ERR_PARSE, "unknown cstype '%s'", tok[i]);
    return SEM_OK;
}

static sem_status statement_deg(obj_reader *r, int ntok, char **tok)
{
    if (ntok < 2 || ntok > 3) return parse_error(r, SEM_ERR_PARSE, "deg needs 'du [dv]'");
    int d[2] = {0, 0};
    for (int i = 1; i < ntok; ++i) {
        long x = 0;
        sem_status st = parse_int(r, tok[i], &x);
        if (st != SEM_OK) return st;
        if (strchr(tok[i], '/') || x < 1 || x > SEM_MAX_DEGREE)
            return parse_error(r, SEM_ERR_PARSE, "degree '%s' out of range 1..%d", tok[i],
                               SEM_MAX_DEGREE);
        d[i - 1] = (int)x;
    }
    r->deg_u = d[0];
    r->deg_v = d[1];
    return SEM_OK;
}

/* The rest of the line after the keyword, trimmed: an object or group name. */
static void set_name(obj_reader *r, const char *rest)
{
    while (*rest && isspace((unsigned char)*rest)) ++rest;
    size_t n = strlen(rest);
    while (n > 0 && isspace((unsigned char)rest[n - 1])) --n;
    if (n >= sizeof r->name) n = sizeof r->name - 1;
    memcpy(r->name, rest, n);
    r->name[n] = '\0';
}

/* "# sem units MM 0.001": the units of the model, written by sem_obj_write. */
static void units_comment(obj_reader *r, const char *line)
{
    char units[16];
    double meters;
    if (sscanf(line, " # sem units %15s %lf", units, &meters) == 2 && isfinite(meters) &&
        meters > 0) {
        snprintf(r->model->units, sizeof r->model->units, "%s", units);
        r->model->unit_to_meter = meters;
    }
}

#define MAX_TOKENS_START 64

static sem_status process_line(obj_reader *r, char *line, char ***tokens, int *cap_tokens)
{
    char *hash = strchr(line, '#');
    if (hash) {
        units_comment(r, hash);
        *hash = '\0';
    }
    /* keep the raw text after the keyword for names */
    char *p = line;
    while (*p && isspace((unsigned char)*p)) ++p;
    if (!*p) return SEM_OK;
    char *kw_end = p;
    while (*kw_end && !isspace((unsigned char)*kw_end)) ++kw_end;
    if ((kw_end - p == 1 && (*p == 'o' || *p == 'g'))) {
        set_name(r, kw_end);
        return SEM_OK;
    }
    int ntok = 0;
    char *save = NULL;
    for (char *s = strtok_r(p, " \t\r\v\f", &save); s; s = strtok_r(NULL, " \t\r\v\f", &save)) {
        if (ntok == *cap_tokens) {
            int nc = 2 * *cap_tokens;
            char **t = realloc(*tokens, (size_t)nc * sizeof *t);
            if (!t) return no_memory(r);
            *tokens = t;
            *cap_tokens = nc;
        }
        (*tokens)[ntok++] = s;
    }
    char **tok = *tokens;
    const char *kw = tok[0];
    if (strcmp(kw, "v") == 0) return statement_vertex(r, ntok, tok, 0);
    if (strcmp(kw, "vp") == 0) return statement_vertex(r, ntok, tok, 1);
    if (strcmp(kw, "cstype") == 0) return statement_cstype(r, ntok, tok);
    if (strcmp(kw, "deg") == 0) return statement_deg(r, ntok, tok);
    if (strcmp(kw, "surf") == 0) return statement_surf(r, ntok, tok);
    if (strcmp(kw, "curv2") == 0) return statement_curv2(r, ntok, tok);
    if (strcmp(kw, "parm") == 0) return statement_parm(r, ntok, tok);
    if (strcmp(kw, "trim") == 0) return statement_trim(r, ntok, tok, 0);
    if (strcmp(kw, "hole") == 0) return statement_trim(r, ntok, tok, 1);
    if (strcmp(kw, "end") == 0) return statement_end(r);
    if (strcmp(kw, "curv") == 0) {
        r->n_skipped_curves++;
        return begin_element(r, ELEMENT_SKIP);
    }
    if (strcmp(kw, "f") == 0 || strcmp(kw, "l") == 0 || strcmp(kw, "p") == 0) {
        r->n_polygon_statements++;
        return SEM_OK;
    }
    /* attributes without effect on the geometry we keep */
    static const char *ignored[] = {"vt", "vn", "s", "usemtl", "mtllib", "lod", "shadow_obj",
                                    "trace_obj", "bevel", "c_interp", "d_interp", "maplib",
                                    "usemap", "mg", "ctech", "stech", "step", "bmat", "sp",
                                    "scrv", "con", "call", "csh"};
    for (size_t i = 0; i < sizeof ignored / sizeof ignored[0]; ++i)
        if (strcmp(kw, ignored[i]) == 0) {
            if (strcmp(kw, "sp") == 0 || strcmp(kw, "scrv") == 0 || strcmp(kw, "con") == 0)
                r->n_ignored++;
            return SEM_OK;
        }
    return parse_error(r, SEM_ERR_PARSE, "unknown statement '%s'", kw);
}

/* Attaches the trim curves to the surfaces once every curv2 is known. */
static sem_status resolve_trims(obj_reader *r)
{
    for (int i = 0; i < r->n_surfaces; ++i) {
        pending_surface *ps = &r->surfaces[i];
        sem_part *part = &ps->part;
        int n_holes = 0;
        for (int l = 0; l < ps->n_loops; ++l) n_holes += ps->loops[l].is_hole;
        if (n_holes > 0) {
            part->holes = calloc((size_t)n_holes, sizeof *part->holes);
            if (!part->holes) return no_memory(r);
        }
        for (int l = 0; l < ps->n_loops; ++l) {
            pending_loop *pl = &ps->loops[l];
            r->line = pl->line;
            sem_trim_loop *loop = pl->is_hole ? &part->holes[part->n_holes++] : &part->outer;
            if (!pl->is_hole) part->has_outer = 1;
            loop->curves = calloc((size_t)pl->n_refs, sizeof *loop->curves);
            if (!loop->curves) return no_memory(r);
            for (int c = 0; c < pl->n_refs; ++c) {
                trim_ref *t = &pl->refs[c];
                if (t->curve < 0 || t->curve >= r->n_curves)
                    return parse_error(r, SEM_ERR_PARSE,
                                       "curv2 index %d out of range (the file has %d)",
                                       t->curve + 1, r->n_curves);
                sem_curve *cv = &loop->curves[c];
                sem_status st = count_points(r, r->curves[t->curve].n_ctrl);
                if (st != SEM_OK) return st;
                if (sem_curve_copy(cv, &r->curves[t->curve]) != SEM_OK) return no_memory(r);
                loop->n_curves = c + 1;
                /* a reversed range only says which way the loop runs: inside/outside does
                 * not depend on it, and the model keeps t0 < t1 */
                cv->t0 = fmin(t->t0, t->t1);
                cv->t1 = fmax(t->t0, t->t1);
                double a = cv->knots[cv->degree], b = cv->knots[cv->n_ctrl];
                double tol = 1e-9 * (b - a);
                if (!(cv->t1 > cv->t0) || cv->t0 < a - tol || cv->t1 > b + tol)
                    return parse_error(r, SEM_ERR_PARSE,
                                       "trim range [%.17g, %.17g] of curv2 %d is empty or "
                                       "outside its knots [%.17g, %.17g]",
                                       t->t0, t->t1, t->curve + 1, a, b);
            }
        }
        if (ps->n_loops > 0) {
            /* loops must close (as in IGES): an open loop has no inside, and every measure
             * of the part (area, quadrature) would be meaningless */
            sem_error verr;
            sem_status st = sem_part_validate_trims(part, &verr);
            if (st != SEM_OK) {
                r->line = ps->line;
                return parse_error(r, st == SEM_ERR_NOMEM ? SEM_ERR_NOMEM : SEM_ERR_PARSE,
                                   "surf: %s", verr.message);
            }
        }
    }
    return SEM_OK;
}

static sem_status read_text(obj_reader *r, const char *text, size_t len)
{
    int cap_tokens = MAX_TOKENS_START;
    char **tokens = malloc((size_t)cap_tokens * sizeof *tokens);
    char *logical = malloc(len + 1);
    if (!tokens || !logical) {
        free(tokens);
        free(logical);
        return no_memory(r);
    }
    sem_status st = SEM_OK;
    size_t pos = 0;
    int physical = 0;
    while (pos < len && st == SEM_OK) {
        /* join continuation lines (a backslash before the line end) into one logical line */
        size_t n = 0;
        r->line = physical + 1;
        for (;;) {
            size_t start = pos;
            while (pos < len && text[pos] != '\n') ++pos;
            size_t end = pos;
            if (pos < len) ++pos;
            ++physical;
            while (end > start && (text[end - 1] == '\r' || text[end - 1] == ' ' ||
                                   text[end - 1] == '\t'))
                --end;
            int continued = end > start && text[end - 1] == '\\';
            if (continued) --end;
            memcpy(logical + n, text + start, end - start);
            n += end - start;
            if (continued) logical[n++] = ' ';
            if (!continued || pos >= len) break;
        }
        logical[n] = '\0';
        if (memchr(logical, '\0', n))
            st = parse_error(r, SEM_ERR_PARSE, "NUL byte in the file (not a text file?)");
        else st = process_line(r, logical, &tokens, &cap_tokens);
    }
    free(tokens);
    free(logical);
    if (st != SEM_OK) return st;
    if (r->current.kind != ELEMENT_NONE) {
        r->line = r->current.line;
        return parse_error(r, SEM_ERR_PARSE, "%s without 'end'",
                           r->current.kind == ELEMENT_SURF ? "surf" : "curve");
    }
    return resolve_trims(r);
}

static sem_status obj_read_text(const char *path, const char *text, size_t len, sem_model **out,
                                sem_error *err)
{
    obj_reader r;
    memset(&r, 0, sizeof r);
    r.path = path;
    r.err = err;
    r.model = sem_model_create();
    if (!r.model) return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    strcpy(r.model->units, "");
    sem_status st = read_text(&r, text, len);
    if (st == SEM_OK && r.n_surfaces == 0)
        st = sem_error_set(err, SEM_ERR_PARSE,
                           "%s:%d: no free-form surfaces ('surf') in the file", path, r.line);
    for (int i = 0; st == SEM_OK && i < r.n_surfaces; ++i)
        st = sem_model_take_part(r.model, &r.surfaces[i].part, err);
    if (st == SEM_OK) {
        sem_error e;
        st = sem_model_check_limits(r.model, &e);
        if (st != SEM_OK) sem_error_set(err, st, "%s: %s", path, e.message);
    }
    if (st == SEM_OK) {
        if (!r.model->units[0]) strcpy(r.model->units, "M");
        if (r.n_polygon_statements)
            sem_model_warn(r.model, "%s: %d polygon statements (f/l/p) ignored", path,
                           r.n_polygon_statements);
        if (r.n_skipped_curves)
            sem_model_warn(r.model, "%s: %d 3D curves (curv) ignored", path, r.n_skipped_curves);
        if (r.n_ignored)
            sem_model_warn(r.model, "%s: %d special points/curves or connections ignored", path,
                           r.n_ignored);
        *out = r.model;
        r.model = NULL;
    }
    reader_free(&r);
    sem_model_destroy(r.model);
    return st;
}

sem_status sem_obj_read(const char *path, sem_model **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!path || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_obj_read: NULL argument");
    char *text = NULL;
    size_t len = 0;
    sem_status st = sem_read_file(path, SEM_MAX_MODEL_FILE_BYTES, "SEM_MAX_MODEL_FILE_BYTES",
                                  &text, &len, err);
    if (st != SEM_OK) return st;
    st = obj_read_text(path, text, len, out, err);
    free(text);
    return st;
}

sem_status sem_obj_read_buffer(const char *name, const char *data, size_t len, sem_model **out,
                               sem_error *err)
{
    if (out) *out = NULL;
    if (!out || (!data && len > 0))
        return sem_error_set(err, SEM_ERR_INVALID, "sem_obj_read_buffer: NULL argument");
    return obj_read_text(name ? name : "<buffer>", data ? data : "", len, out, err);
}

/* ------------------------------------------------------------------------------------ */
/* writing                                                                              */
/* ------------------------------------------------------------------------------------ */

/* Statements are wrapped with '\' continuations to keep lines readable. */
typedef struct obj_line {
    FILE *f;
    int column;
} obj_line;

static void line_begin(obj_line *l, const char *keyword)
{
    l->column = fprintf(l->f, "%s", keyword);
}

static void line_token(obj_line *l, const char *token)
{
    int n = (int)strlen(token);
    if (l->column + 1 + n > 100) {
        fputs(" \\\n ", l->f);
        l->column = 1;
    }
    l->column += fprintf(l->f, " %s", token);
}

static void line_real(obj_line *l, double x)
{
    char t[40];
    sem_format_real(x, t);
    line_token(l, t);
}

static void line_int(obj_line *l, long x)
{
    char t[32];
    snprintf(t, sizeof t, "%ld", x);
    line_token(l, t);
}

static void line_end(obj_line *l)
{
    fputc('\n', l->f);
    l->column = 0;
}

static int any_weight_not_one(const double *w, size_t n)
{
    for (size_t i = 0; i < n; ++i)
        if (w[i] != 1.0) return 1;
    return 0;
}

static void write_curve(FILE *f, const sem_curve *c, long first_vp)
{
    int rational = any_weight_not_one(c->weights, (size_t)c->n_ctrl);
    obj_line l = {f, 0};
    fprintf(f, "cstype %sbspline\ndeg %d\n", rational ? "rat " : "", c->degree);
    line_begin(&l, "curv2");
    for (int i = 0; i < c->n_ctrl; ++i) line_int(&l, first_vp + i);
    line_end(&l);
    line_begin(&l, "parm u");
    for (int i = 0; i < c->n_ctrl + c->degree + 1; ++i) line_real(&l, c->knots[i]);
    line_end(&l);
    fputs("end\n", f);
}

static void write_loop_statement(FILE *f, const char *keyword, const sem_trim_loop *loop,
                                 long first_curve)
{
    obj_line l = {f, 0};
    line_begin(&l, keyword);
    for (int i = 0; i < loop->n_curves; ++i) {
        line_real(&l, loop->curves[i].t0);
        line_real(&l, loop->curves[i].t1);
        line_int(&l, first_curve + i);
    }
    line_end(&l);
}

static void write_part(FILE *f, const sem_part *p, long *n_v, long *n_vp, long *n_curv2)
{
    const sem_surface *s = &p->surface;
    size_t n = (size_t)s->n_u * (size_t)s->n_v;
    char name[64];
    snprintf(name, sizeof name, "%s", p->name);
    for (char *c = name; *c; ++c)
        if (*c == '\n' || *c == '\r' || *c == '#' || *c == '\\') *c = '_';
    fprintf(f, "o %s\n", name);
    int rational = any_weight_not_one(s->weights, n);
    long first_v = *n_v + 1;
    obj_line l = {f, 0};
    for (size_t i = 0; i < n; ++i) {
        line_begin(&l, "v");
        for (int k = 0; k < 3; ++k) line_real(&l, s->ctrl[3 * i + k]);
        if (rational) line_real(&l, s->weights[i]);
        line_end(&l);
    }
    *n_v += (long)n;

    /* trim curves: the outer loop's, then each hole's */
    int n_loops = (p->has_outer ? 1 : 0) + p->n_holes;
    long first_curve = *n_curv2 + 1;
    for (int li = 0; li < n_loops; ++li) {
        const sem_trim_loop *loop = p->has_outer && li == 0 ? &p->outer
                                                            : &p->holes[li - (p->has_outer ? 1 : 0)];
        for (int c = 0; c < loop->n_curves; ++c) {
            const sem_curve *cv = &loop->curves[c];
            int crat = any_weight_not_one(cv->weights, (size_t)cv->n_ctrl);
            for (int i = 0; i < cv->n_ctrl; ++i) {
                line_begin(&l, "vp");
                line_real(&l, cv->ctrl[3 * i]);
                line_real(&l, cv->ctrl[3 * i + 1]);
                if (crat) line_real(&l, cv->weights[i]);
                line_end(&l);
            }
            write_curve(f, cv, *n_vp + 1);
            *n_vp += cv->n_ctrl;
            *n_curv2 += 1;
        }
    }

    fprintf(f, "cstype %sbspline\ndeg %d %d\n", rational ? "rat " : "", s->degree_u, s->degree_v);
    line_begin(&l, "surf");
    line_real(&l, s->u0);
    line_real(&l, s->u1);
    line_real(&l, s->v0);
    line_real(&l, s->v1);
    for (size_t i = 0; i < n; ++i) line_int(&l, first_v + (long)i);
    line_end(&l);
    line_begin(&l, "parm u");
    for (int i = 0; i < s->n_u + s->degree_u + 1; ++i) line_real(&l, s->knots_u[i]);
    line_end(&l);
    line_begin(&l, "parm v");
    for (int i = 0; i < s->n_v + s->degree_v + 1; ++i) line_real(&l, s->knots_v[i]);
    line_end(&l);
    for (int li = 0; li < n_loops; ++li) {
        int is_outer = p->has_outer && li == 0;
        const sem_trim_loop *loop = is_outer ? &p->outer : &p->holes[li - (p->has_outer ? 1 : 0)];
        write_loop_statement(f, is_outer ? "trim" : "hole", loop, first_curve);
        first_curve += loop->n_curves;
    }
    fputs("end\n", f);
}

sem_status sem_obj_write(const sem_model *model, const char *path, sem_error *err)
{
    if (!model || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_obj_write: NULL argument");
    sem_error e;
    for (int i = 0; i < model->n_parts; ++i) {
        const sem_part *p = &model->parts[i];
        if (sem_surface_validate(&p->surface, &e) != SEM_OK)
            return sem_error_set(err, SEM_ERR_INVALID, "part %d '%s': %.900s", i, p->name,
                                 e.message);
        int n_loops = (p->has_outer ? 1 : 0) + p->n_holes;
        for (int li = 0; li < n_loops; ++li) {
            const sem_trim_loop *loop = p->has_outer && li == 0
                                            ? &p->outer
                                            : &p->holes[li - (p->has_outer ? 1 : 0)];
            if (loop->n_curves < 1)
                return sem_error_set(err, SEM_ERR_INVALID, "part %d '%s': trim loop %d is empty",
                                     i, p->name, li);
            for (int c = 0; c < loop->n_curves; ++c)
                if (sem_curve_validate(&loop->curves[c], &e) != SEM_OK)
                    return sem_error_set(err, SEM_ERR_INVALID,
                                         "part %d '%s': trim loop %d curve %d: %.900s", i,
                                         p->name, li, c, e.message);
        }
    }
    sem_atomic_file file;
    sem_status st = sem_atomic_open(&file, path, err);
    if (st != SEM_OK) return st;
    FILE *f = file.fp;
    fprintf(f, "# sem: %d NURBS part%s as OBJ free-form surfaces\n", model->n_parts,
            model->n_parts == 1 ? "" : "s");
    char meters[40];
    sem_format_real(model->unit_to_meter, meters);
    fprintf(f, "# sem units %s %s\n", model->units[0] ? model->units : "M", meters);
    long n_v = 0, n_vp = 0, n_curv2 = 0;
    for (int i = 0; i < model->n_parts; ++i) write_part(f, &model->parts[i], &n_v, &n_vp, &n_curv2);
    return sem_atomic_commit(&file, err);
}
