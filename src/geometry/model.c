/* model.c - life cycle and bookkeeping of NURBS models (see sem/model.h). */
#include "sem/model.h"
#include "sem/limits.h"
#include "util/free_all.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static double *dup_doubles(const double *src, size_t n)
{
    if (!src || n == 0) return NULL;
    double *dst = malloc(n * sizeof *dst);
    if (dst) memcpy(dst, src, n * sizeof *dst);
    return dst;
}

sem_model *sem_model_create(void)
{
    sem_model *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    strcpy(m->units, "M");
    m->unit_to_meter = 1.0;
    return m;
}

void sem_curve_free(sem_curve *c)
{
    if (!c) return;
    free(c->knots);
    free(c->ctrl);
    free(c->weights);
    memset(c, 0, sizeof *c);
}

void sem_surface_free(sem_surface *s)
{
    if (!s) return;
    SEM_FREE_ALL(s->knots_u, s->knots_v, s->ctrl, s->weights);
    memset(s, 0, sizeof *s);
}

static void loop_free(sem_trim_loop *l)
{
    for (int i = 0; i < l->n_curves; ++i) sem_curve_free(&l->curves[i]);
    free(l->curves);
    l->curves = NULL;
    l->n_curves = 0;
}

void sem_part_free(sem_part *p)
{
    if (!p) return;
    sem_surface_free(&p->surface);
    loop_free(&p->outer);
    for (int i = 0; i < p->n_holes; ++i) loop_free(&p->holes[i]);
    free(p->holes);
    memset(p, 0, sizeof *p);
}

void sem_model_destroy(sem_model *m)
{
    if (!m) return;
    for (int i = 0; i < m->n_parts; ++i) sem_part_free(&m->parts[i]);
    free(m->parts);
    for (int i = 0; i < m->n_warnings; ++i) free(m->warnings[i]);
    free(m->warnings);
    free(m);
}

sem_status sem_curve_alloc(sem_curve *c, int degree, int n_ctrl)
{
    memset(c, 0, sizeof *c);
    if (degree < 1 || n_ctrl < degree + 1) return SEM_ERR_INVALID;
    c->degree = degree;
    c->n_ctrl = n_ctrl;
    c->knots = calloc((size_t)(n_ctrl + degree + 1), sizeof(double));
    c->ctrl = calloc((size_t)n_ctrl * 3, sizeof(double));
    c->weights = malloc((size_t)n_ctrl * sizeof(double));
    if (!c->knots || !c->ctrl || !c->weights) {
        sem_curve_free(c);
        return SEM_ERR_NOMEM;
    }
    for (int i = 0; i < n_ctrl; ++i) c->weights[i] = 1.0;
    return SEM_OK;
}

sem_status sem_surface_alloc(sem_surface *s, int degree_u, int degree_v, int n_u, int n_v)
{
    memset(s, 0, sizeof *s);
    if (degree_u < 1 || degree_v < 1 || n_u < degree_u + 1 || n_v < degree_v + 1)
        return SEM_ERR_INVALID;
    s->degree_u = degree_u;
    s->degree_v = degree_v;
    s->n_u = n_u;
    s->n_v = n_v;
    size_t n = (size_t)n_u * (size_t)n_v;
    s->knots_u = calloc((size_t)(n_u + degree_u + 1), sizeof(double));
    s->knots_v = calloc((size_t)(n_v + degree_v + 1), sizeof(double));
    s->ctrl = calloc(3 * n, sizeof(double));
    s->weights = malloc(n * sizeof(double));
    if (!s->knots_u || !s->knots_v || !s->ctrl || !s->weights) {
        sem_surface_free(s);
        return SEM_ERR_NOMEM;
    }
    for (size_t i = 0; i < n; ++i) s->weights[i] = 1.0;
    return SEM_OK;
}

sem_status sem_curve_copy(sem_curve *dst, const sem_curve *src)
{
    *dst = *src;
    size_t n = (size_t)src->n_ctrl;
    dst->knots = dup_doubles(src->knots, n + (size_t)src->degree + 1);
    dst->ctrl = dup_doubles(src->ctrl, 3 * n);
    dst->weights = dup_doubles(src->weights, n);
    if (!dst->knots || !dst->ctrl || !dst->weights) {
        sem_curve_free(dst);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

sem_status sem_surface_copy(sem_surface *dst, const sem_surface *src)
{
    *dst = *src;
    size_t n = (size_t)src->n_u * (size_t)src->n_v;
    dst->knots_u = dup_doubles(src->knots_u, (size_t)(src->n_u + src->degree_u + 1));
    dst->knots_v = dup_doubles(src->knots_v, (size_t)(src->n_v + src->degree_v + 1));
    dst->ctrl = dup_doubles(src->ctrl, 3 * n);
    dst->weights = dup_doubles(src->weights, n);
    if (!dst->knots_u || !dst->knots_v || !dst->ctrl || !dst->weights) {
        sem_surface_free(dst);
        return SEM_ERR_NOMEM;
    }
    return SEM_OK;
}

static sem_status loop_copy(sem_trim_loop *dst, const sem_trim_loop *src)
{
    dst->n_curves = 0;
    dst->curves = NULL;
    if (src->n_curves == 0) return SEM_OK;
    dst->curves = calloc((size_t)src->n_curves, sizeof *dst->curves);
    if (!dst->curves) return SEM_ERR_NOMEM;
    for (int i = 0; i < src->n_curves; ++i) {
        if (sem_curve_copy(&dst->curves[i], &src->curves[i]) != SEM_OK) {
            dst->n_curves = i;
            loop_free(dst);
            return SEM_ERR_NOMEM;
        }
    }
    dst->n_curves = src->n_curves;
    return SEM_OK;
}

sem_status sem_part_copy(sem_part *dst, const sem_part *src)
{
    memset(dst, 0, sizeof *dst);
    memcpy(dst->name, src->name, sizeof dst->name);
    dst->has_outer = src->has_outer;
    dst->source_entity = src->source_entity;
    dst->color = src->color;
    dst->has_rgb = src->has_rgb;
    memcpy(dst->rgb, src->rgb, sizeof dst->rgb);
    if (sem_surface_copy(&dst->surface, &src->surface) != SEM_OK) goto fail;
    if (loop_copy(&dst->outer, &src->outer) != SEM_OK) goto fail;
    if (src->n_holes > 0) {
        dst->holes = calloc((size_t)src->n_holes, sizeof *dst->holes);
        if (!dst->holes) goto fail;
        for (int i = 0; i < src->n_holes; ++i) {
            if (loop_copy(&dst->holes[i], &src->holes[i]) != SEM_OK) goto fail;
            dst->n_holes = i + 1;
        }
    }
    return SEM_OK;
fail:
    sem_part_free(dst);
    return SEM_ERR_NOMEM;
}

static sem_status grow(sem_model *m, sem_error *err)
{
    if (m->n_parts < m->capacity) return SEM_OK;
    int cap = m->capacity ? 2 * m->capacity : 8;
    sem_part *p = realloc(m->parts, (size_t)cap * sizeof *p);
    if (!p) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory adding a part");
    m->parts = p;
    m->capacity = cap;
    return SEM_OK;
}

sem_status sem_model_take_part(sem_model *m, sem_part *part, sem_error *err)
{
    sem_status st = grow(m, err);
    if (st != SEM_OK) return st;
    m->parts[m->n_parts++] = *part;
    memset(part, 0, sizeof *part);
    return SEM_OK;
}

sem_status sem_model_add_part(sem_model *m, const sem_part *part, sem_error *err)
{
    sem_status st = grow(m, err);
    if (st != SEM_OK) return st;
    if (sem_part_copy(&m->parts[m->n_parts], part) != SEM_OK)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory copying a part");
    m->n_parts++;
    return SEM_OK;
}

/* Knot spans in use along one direction (distinct knots strictly inside the range, + 1). */
static long long spans_in_use(int degree, int n, const double *knots, double t0, double t1)
{
    long long spans = 1;
    for (int i = degree + 1; i < n; ++i)
        spans += knots[i] > knots[i - 1] && knots[i] > t0 && knots[i] < t1;
    return spans;
}

sem_status sem_model_check_limits(const sem_model *m, sem_error *err)
{
    if (m->n_parts > SEM_MAX_PARTS)
        return sem_error_set(err, SEM_ERR_INVALID, "the model has %d parts; at most %d are read "
                                                   "(limit SEM_MAX_PARTS)",
                             m->n_parts, SEM_MAX_PARTS);
    /* per span: the basis functions one evaluation touches, times the Gauss points a span
     * gets where it is integrated (measure.c: degree + 6, 8..24 per direction) */
    double work = 0;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        int gu = s->degree_u + 6 < 8 ? 8 : s->degree_u + 6 > 24 ? 24 : s->degree_u + 6;
        int gv = s->degree_v + 6 < 8 ? 8 : s->degree_v + 6 > 24 ? 24 : s->degree_v + 6;
        work += (double)spans_in_use(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1) *
                (double)spans_in_use(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1) *
                (s->degree_u + 1) * (s->degree_v + 1) * gu * gv;
        if (work > SEM_MAX_MODEL_SPAN_WORK)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "the surfaces have too many knot spans for their degrees (part "
                                 "%d reaches %.3g units of evaluation work; limit "
                                 "SEM_MAX_MODEL_SPAN_WORK = %.3g)",
                                 i + 1, work, (double)SEM_MAX_MODEL_SPAN_WORK);
    }
    return SEM_OK;
}

sem_model *sem_model_clone(const sem_model *src)
{
    sem_model *m = sem_model_create();
    if (!m) return NULL;
    memcpy(m->units, src->units, sizeof m->units);
    m->unit_to_meter = src->unit_to_meter;
    for (int i = 0; i < src->n_parts; ++i) {
        if (sem_model_add_part(m, &src->parts[i], NULL) != SEM_OK) {
            sem_model_destroy(m);
            return NULL;
        }
    }
    return m;
}

void sem_model_warn(sem_model *m, const char *fmt, ...)
{
    /* A file can repeat one unsupported entity a million times: keep the first
     * SEM_MODEL_MAX_WARNINGS messages and one line that says how many were dropped. */
    if (m->n_warnings > SEM_MODEL_MAX_WARNINGS) return;
    char buf[512];
    if (m->n_warnings == SEM_MODEL_MAX_WARNINGS) {
        snprintf(buf, sizeof buf, "more than %d warnings; the rest are not shown",
                 SEM_MODEL_MAX_WARNINGS);
    } else {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(buf, sizeof buf, fmt, ap);
        va_end(ap);
        sem_text_sanitize(buf);
    }
    char **w = realloc(m->warnings, (size_t)(m->n_warnings + 1) * sizeof *w);
    if (!w) return;
    m->warnings = w;
    w[m->n_warnings] = malloc(strlen(buf) + 1);
    if (!w[m->n_warnings]) return;
    strcpy(w[m->n_warnings], buf);
    m->n_warnings++;
}

static sem_status check_knots(const double *knots, int n, int degree, const char *what,
                              sem_error *err)
{
    for (int i = 0; i < n; ++i) {
        if (!isfinite(knots[i]))
            return sem_error_set(err, SEM_ERR_INVALID, "%s knot %d is not a finite number", what, i);
        if (i > 0 && knots[i] < knots[i - 1])
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s knots decrease at index %d (%.17g after %.17g)", what, i,
                                 knots[i], knots[i - 1]);
    }
    /* interior multiplicity may not exceed degree + 1 */
    int run = 1;
    for (int i = 1; i < n; ++i) {
        run = knots[i] == knots[i - 1] ? run + 1 : 1;
        if (run > degree + 1)
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "%s knot %.17g repeated more than degree + 1 = %d times", what,
                                 knots[i], degree + 1);
    }
    if (!(knots[n - 1] > knots[0]))
        return sem_error_set(err, SEM_ERR_INVALID, "%s knot vector has zero length", what);
    return SEM_OK;
}

static sem_status check_points(const double *ctrl, const double *w, size_t n, sem_error *err)
{
    for (size_t i = 0; i < n; ++i) {
        if (!isfinite(ctrl[3 * i]) || !isfinite(ctrl[3 * i + 1]) || !isfinite(ctrl[3 * i + 2]))
            return sem_error_set(err, SEM_ERR_INVALID, "control point %zu is not finite", i);
        if (!isfinite(w[i]) || !(w[i] > 0))
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "weight %zu is %g; weights must be positive", i, w[i]);
    }
    return SEM_OK;
}

sem_status sem_curve_validate(const sem_curve *c, sem_error *err)
{
    if (c->degree < 1 || c->degree > 31)
        return sem_error_set(err, SEM_ERR_INVALID, "curve degree %d out of range 1..31", c->degree);
    if (c->n_ctrl < c->degree + 1)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "curve degree %d too high for %d control points", c->degree,
                             c->n_ctrl);
    sem_status st = check_knots(c->knots, c->n_ctrl + c->degree + 1, c->degree, "curve", err);
    if (st != SEM_OK) return st;
    st = check_points(c->ctrl, c->weights, (size_t)c->n_ctrl, err);
    if (st != SEM_OK) return st;
    if (!isfinite(c->t0) || !isfinite(c->t1) || !(c->t1 > c->t0))
        return sem_error_set(err, SEM_ERR_INVALID, "curve parameter range [%g, %g] is empty",
                             c->t0, c->t1);
    return SEM_OK;
}

sem_status sem_surface_validate(const sem_surface *s, sem_error *err)
{
    if (s->degree_u < 1 || s->degree_v < 1 || s->degree_u > 31 || s->degree_v > 31)
        return sem_error_set(err, SEM_ERR_INVALID, "surface degree (%d, %d) out of range 1..31",
                             s->degree_u, s->degree_v);
    if (s->n_u < s->degree_u + 1 || s->n_v < s->degree_v + 1)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "surface degree (%d, %d) too high for a %d x %d control net",
                             s->degree_u, s->degree_v, s->n_u, s->n_v);
    sem_status st = check_knots(s->knots_u, s->n_u + s->degree_u + 1, s->degree_u, "u", err);
    if (st != SEM_OK) return st;
    st = check_knots(s->knots_v, s->n_v + s->degree_v + 1, s->degree_v, "v", err);
    if (st != SEM_OK) return st;
    st = check_points(s->ctrl, s->weights, (size_t)s->n_u * (size_t)s->n_v, err);
    if (st != SEM_OK) return st;
    if (!isfinite(s->u0) || !isfinite(s->u1) || !(s->u1 > s->u0) || !isfinite(s->v0) ||
        !isfinite(s->v1) || !(s->v1 > s->v0))
        return sem_error_set(err, SEM_ERR_INVALID,
                             "surface parameter range [%g,%g] x [%g,%g] is empty", s->u0, s->u1,
                             s->v0, s->v1);
    double ua = s->knots_u[s->degree_u], ub = s->knots_u[s->n_u];
    double va = s->knots_v[s->degree_v], vb = s->knots_v[s->n_v];
    double tu = 1e-9 * (ub - ua), tv = 1e-9 * (vb - va);
    if (s->u0 < ua - tu || s->u1 > ub + tu || s->v0 < va - tv || s->v1 > vb + tv)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "surface parameter range [%g,%g] x [%g,%g] outside the knot range "
                             "[%g,%g] x [%g,%g]",
                             s->u0, s->u1, s->v0, s->v1, ua, ub, va, vb);
    return SEM_OK;
}

size_t sem_model_control_points(const sem_model *m)
{
    size_t n = 0;
    for (int i = 0; i < m->n_parts; ++i)
        n += (size_t)m->parts[i].surface.n_u * (size_t)m->parts[i].surface.n_v;
    return n;
}

void sem_model_part_offsets(const sem_model *m, size_t *out)
{
    out[0] = 0;
    for (int i = 0; i < m->n_parts; ++i)
        out[i + 1] = out[i] + (size_t)m->parts[i].surface.n_u * (size_t)m->parts[i].surface.n_v;
}

void sem_model_get_q(const sem_model *m, double *q)
{
    size_t k = 0;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        size_t n = 3 * (size_t)s->n_u * (size_t)s->n_v;
        memcpy(q + k, s->ctrl, n * sizeof *q);
        k += n;
    }
}

void sem_model_set_q(sem_model *m, const double *q)
{
    size_t k = 0;
    for (int i = 0; i < m->n_parts; ++i) {
        sem_surface *s = &m->parts[i].surface;
        size_t n = 3 * (size_t)s->n_u * (size_t)s->n_v;
        memcpy(s->ctrl, q + k, n * sizeof *q);
        k += n;
    }
}
