/* test_refine.c - exact refinement by knot insertion (sem/refine.h, `sem refine`):
 * - the same surface: every part evaluated at many (u, v) before and after (points, first
 *   and second derivatives) agrees to 1e-12 relative to the model size (derivatives: to
 *   their own size), for a hand-made rational surface with unclamped and repeated knots, the
 *   rational primitives (points stay on the exact sphere / torus), and the paper's models;
 * - the control points follow n + (K - 1) s per direction, with the knot vector holding the
 *   old knots and the equal split points;
 * - trims, names, colours, units and warnings are kept; factor 1 is a bit-for-bit copy;
 * - an IGES round trip of a refined model gives it back;
 * - bad factors and results beyond the readers' limits are refused with one line;
 * - `sem refine`: the summary line, exit statuses 1 and 2 with one-line errors, no output
 *   file left behind;
 * - the rocket refined to about 1e4, 4e4 and 1e5 dofs (timed, printed), and the b10 beam
 *   refined by 2 solved at default settings beside the unrefined one (printed).
 */
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>

#include "sem/nurbs.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "test_util.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static double norm3(const double *x)
{
    return sqrt(x[0] * x[0] + x[1] * x[1] + x[2] * x[2]);
}

/* Diagonal of the control points' bounding box: the model size. */
static double model_size(const sem_model *m)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int p = 0; p < m->n_parts; ++p) {
        const sem_surface *s = &m->parts[p].surface;
        for (int c = 0; c < s->n_u * s->n_v; ++c)
            for (int e = 0; e < 3; ++e) {
                lo[e] = fmin(lo[e], s->ctrl[3 * c + e]);
                hi[e] = fmax(hi[e], s->ctrl[3 * c + e]);
            }
    }
    double d[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    return norm3(d);
}

/* Largest differences between two surfaces over a grid of n x n parameters of the range in
 * use (ends and quarter points included, so old and new knots are hit) and as many
 * irregular ones: err = {point, first derivatives, second derivatives}; scale = the largest
 * first and second derivatives of `a` seen (err[1] / scale[1] is relative). */
typedef struct surface_diff {
    double err[3], scale[3];
} surface_diff;

static void diff_at(const sem_surface *a, const sem_surface *b, double u, double v,
                    surface_diff *d)
{
    double pa[3], ua[3], va[3], ha[9], pb[3], ub[3], vb[3], hb[9];
    sem_surface_eval(a, u, v, pa, ua, va, ha);
    sem_surface_eval(b, u, v, pb, ub, vb, hb);
    for (int e = 0; e < 3; ++e) {
        d->err[0] = fmax(d->err[0], fabs(pa[e] - pb[e]));
        d->err[1] = fmax(d->err[1], fmax(fabs(ua[e] - ub[e]), fabs(va[e] - vb[e])));
    }
    for (int e = 0; e < 9; ++e) d->err[2] = fmax(d->err[2], fabs(ha[e] - hb[e]));
    d->scale[1] = fmax(d->scale[1], fmax(norm3(ua), norm3(va)));
    d->scale[2] = fmax(d->scale[2], fmax(norm3(ha), fmax(norm3(ha + 3), norm3(ha + 6))));
}

/* The sizes derivatives are measured against: the largest seen, and at least those of the
 * parameter map of a patch of the control net's size over the parameter range (a plane's
 * second derivatives are 0 but its round-off is not). */
static void derivative_scales(const sem_surface *a, surface_diff *d)
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int c = 0; c < a->n_u * a->n_v; ++c)
        for (int e = 0; e < 3; ++e) {
            lo[e] = fmin(lo[e], a->ctrl[3 * c + e]);
            hi[e] = fmax(hi[e], a->ctrl[3 * c + e]);
        }
    double diag[3] = {hi[0] - lo[0], hi[1] - lo[1], hi[2] - lo[2]};
    double range = fmin(a->u1 - a->u0, a->v1 - a->v0);
    d->scale[1] = fmax(d->scale[1], norm3(diag) / range);
    d->scale[2] = fmax(d->scale[2], norm3(diag) / (range * range));
}

static void compare_surfaces(const sem_surface *a, const sem_surface *b, int n, surface_diff *d)
{
    derivative_scales(a, d);
    for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
            double s = (double)i / n, t = (double)j / n;
            diff_at(a, b, a->u0 + s * (a->u1 - a->u0), a->v0 + t * (a->v1 - a->v0), d);
            /* irregular points (golden-ratio sequence) */
            double si = fmod(0.5 + (i * (n + 1) + j) * 0.6180339887498949, 1.0);
            double ti = fmod(0.5 + (i * (n + 1) + j) * 0.7548776662466927, 1.0);
            diff_at(a, b, a->u0 + si * (a->u1 - a->u0), a->v0 + ti * (a->v1 - a->v0), d);
        }
}

/* Compares every part of two models; returns the worst relative errors:
 * point / model size, first and second derivatives / their part's largest. */
static void compare_models(const sem_model *a, const sem_model *b, double rel[3])
{
    rel[0] = rel[1] = rel[2] = 0;
    double size = model_size(a);
    for (int p = 0; p < a->n_parts && p < b->n_parts; ++p) {
        surface_diff d = {{0, 0, 0}, {0, 0, 0}};
        compare_surfaces(&a->parts[p].surface, &b->parts[p].surface, 16, &d);
        rel[0] = fmax(rel[0], d.err[0] / size);
        rel[1] = fmax(rel[1], d.err[1] / fmax(d.scale[1], 1e-300));
        rel[2] = fmax(rel[2], d.err[2] / fmax(d.scale[2], 1e-300));
    }
}

/* Non-empty knot spans of the domain [U[p], U[n]], counted independently of refine.c. */
static int domain_spans(int p, int n, const double *U)
{
    int s = 0;
    for (int i = p; i < n; ++i) s += U[i + 1] > U[i];
    return s;
}

static int curves_equal(const sem_curve *a, const sem_curve *b)
{
    if (a->degree != b->degree || a->n_ctrl != b->n_ctrl || a->t0 != b->t0 || a->t1 != b->t1)
        return 0;
    size_t n = (size_t)a->n_ctrl;
    return !memcmp(a->knots, b->knots, (n + (size_t)a->degree + 1) * sizeof(double)) &&
           !memcmp(a->ctrl, b->ctrl, 3 * n * sizeof(double)) &&
           !memcmp(a->weights, b->weights, n * sizeof(double));
}

static int loops_equal(const sem_trim_loop *a, const sem_trim_loop *b)
{
    if (a->n_curves != b->n_curves) return 0;
    for (int c = 0; c < a->n_curves; ++c)
        if (!curves_equal(&a->curves[c], &b->curves[c])) return 0;
    return 1;
}

/* Everything but the control nets: part count, names, trims, colours and entity numbers (when
 * same_ids), units, warnings, and
 * each surface's degrees, parameter range and counts n + (K - 1) s. */
static void check_kept(const sem_model *in, const sem_model *out, int factor, int same_ids,
                       const char *what)
{
    CHECK(out->n_parts == in->n_parts, "%s: %d parts, %d before", what, out->n_parts, in->n_parts);
    CHECK(!strcmp(out->units, in->units) && out->unit_to_meter == in->unit_to_meter,
          "%s: units %s %g, before %s %g", what, out->units, out->unit_to_meter, in->units,
          in->unit_to_meter);
    CHECK(out->n_warnings == in->n_warnings, "%s: %d warnings, %d before", what, out->n_warnings,
          in->n_warnings);
    int kept = 1, counts = 1;
    for (int p = 0; p < in->n_parts && p < out->n_parts; ++p) {
        const sem_part *a = &in->parts[p], *b = &out->parts[p];
        /* (a file written and read again has new entity numbers, and IGES colours 1..8 only) */
        kept &= !same_ids || (a->color == b->color && a->source_entity == b->source_entity);
        kept &= !strcmp(a->name, b->name) && a->has_outer == b->has_outer &&
                loops_equal(&a->outer, &b->outer) && a->n_holes == b->n_holes;
        for (int h = 0; h < a->n_holes && h < b->n_holes; ++h)
            kept &= loops_equal(&a->holes[h], &b->holes[h]);
        const sem_surface *s = &a->surface, *r = &b->surface;
        kept &= s->degree_u == r->degree_u && s->degree_v == r->degree_v && s->u0 == r->u0 &&
                s->u1 == r->u1 && s->v0 == r->v0 && s->v1 == r->v1;
        int mu = s->n_u + (factor - 1) * domain_spans(s->degree_u, s->n_u, s->knots_u);
        int mv = s->n_v + (factor - 1) * domain_spans(s->degree_v, s->n_v, s->knots_v);
        if (r->n_u != mu || r->n_v != mv) {
            counts = 0;
            fprintf(stderr, "%s part %d: %d x %d control points, expected %d x %d\n", what, p,
                    r->n_u, r->n_v, mu, mv);
        }
    }
    CHECK(kept, "%s: names, colours, trims or parameter ranges changed", what);
    CHECK(counts, "%s: control point counts differ from n + (K - 1) s", what);
}

/* Refines, checks what is kept and the geometry; returns the refined model. */
static sem_model *refine_and_check(const sem_model *m, int factor, const char *what,
                                   double tol_point, double *seconds)
{
    sem_error err;
    sem_model *r = NULL;
    double t0 = now();
    sem_status st = sem_model_refine(m, factor, &r, &err);
    if (seconds) *seconds = now() - t0;
    CHECK(st == SEM_OK && r, "%s refined by %d: %s", what, factor, err.message);
    if (!r) return NULL;
    check_kept(m, r, factor, 1, what);
    double rel[3];
    compare_models(m, r, rel);
    printf("%-36s K=%2d: %5zu -> %6zu control points; max error: point %.1e of the size, "
           "d1 %.1e, d2 %.1e\n",
           what, factor, sem_model_control_points(m), sem_model_control_points(r), rel[0],
           rel[1], rel[2]);
    CHECK(rel[0] <= tol_point, "%s K=%d: point error %.3g of the model size", what, factor, rel[0]);
    CHECK(rel[1] <= 1e-12, "%s K=%d: first derivative error %.3g", what, factor, rel[1]);
    CHECK(rel[2] <= 1e-10, "%s K=%d: second derivative error %.3g", what, factor, rel[2]);
    return r;
}

/* A rational bicubic-by-quadratic surface with an unclamped, non-uniform u knot vector (a
 * double knot, a domain that does not start at 0) and a clamped v one starting at 2. */
static void make_test_surface(sem_surface *s)
{
    static const double ku[] = {-1, -0.5, 0, 0.3, 0.3, 1.1, 2, 2.5, 3.1, 4, 4.2};
    static const double kv[] = {2, 2, 2, 2.7, 3.5, 5, 5, 5};
    sem_surface_alloc(s, 3, 2, 7, 5);
    memcpy(s->knots_u, ku, sizeof ku);
    memcpy(s->knots_v, kv, sizeof kv);
    unsigned x = 12345;
    for (int c = 0; c < 7 * 5; ++c) {
        for (int e = 0; e < 3; ++e) {
            x = x * 1103515245u + 12345u;
            s->ctrl[3 * c + e] = (c % 7) * (e == 0) + (c / 7) * (e == 1) + ((x >> 8) % 1000) / 1000.0;
        }
        x = x * 1103515245u + 12345u;
        s->weights[c] = 0.5 + 1.5 * ((x >> 8) % 1000) / 1000.0;
    }
    s->u0 = 0.3; /* the domain [U[3], U[7]] */
    s->u1 = 2.5;
    s->v0 = 2;
    s->v1 = 5;
}

static void test_hand_made_surface(void)
{
    sem_surface s, r;
    sem_error err;
    make_test_surface(&s);
    CHECK(sem_surface_validate(&s, &err) == SEM_OK, "test surface: %s", err.message);
    /* u: 3 non-empty spans in [0.3, 2.5] (0.3-1.1-2-2.5); v: 3 (2-2.7-3.5-5) */
    static const int factors[][2] = {{2, 2}, {3, 1}, {1, 4}, {7, 5}, {64, 64}};
    for (int k = 0; k < 5; ++k) {
        int fu = factors[k][0], fv = factors[k][1];
        CHECK(sem_surface_refine(&s, fu, fv, &r, &err) == SEM_OK, "refine: %s", err.message);
        CHECK(r.n_u == 7 + 3 * (fu - 1) && r.n_v == 5 + 3 * (fv - 1),
              "(%d, %d): %d x %d control points", fu, fv, r.n_u, r.n_v);
        CHECK(sem_surface_validate(&r, &err) == SEM_OK, "refined: %s", err.message);
        /* the knot vector: the old knots (the double 0.3 too) and the split points */
        int old_kept = 1, splits = 1;
        for (int i = 0; i < 11; ++i) {
            int in_old = 0, in_new = 0;
            for (int j = 0; j < 11; ++j) in_old += s.knots_u[j] == s.knots_u[i];
            for (int j = 0; j < r.n_u + 4; ++j) in_new += r.knots_u[j] == s.knots_u[i];
            old_kept &= in_old == in_new;
        }
        for (int i = 4; i < 7; ++i)
            for (int q = 1; q < fu; ++q) {
                double a = s.knots_u[i], b = s.knots_u[i + 1];
                double t = a + (b - a) * q / fu;
                int found = 0;
                for (int j = 0; j < r.n_u + 4; ++j) found |= fabs(r.knots_u[j] - t) <= 1e-15 * 4;
                splits &= found;
            }
        CHECK(old_kept, "(%d, %d): old knots not all kept with their multiplicity", fu, fv);
        CHECK(splits, "(%d, %d): split points missing", fu, fv);
        surface_diff d = {{0, 0, 0}, {0, 0, 0}};
        compare_surfaces(&s, &r, 40, &d);
        printf("hand-made rational surface (%2d, %2d): %d x %d -> %d x %d; errors %.1e, %.1e "
               "(of %.3g), %.1e (of %.3g)\n",
               fu, fv, s.n_u, s.n_v, r.n_u, r.n_v, d.err[0], d.err[1], d.scale[1], d.err[2],
               d.scale[2]);
        /* the control points lie within [0, 7] x [0, 5] x [0, 1]: size about 8.7 */
        CHECK(d.err[0] <= 1e-12 * 8.7, "(%d, %d): point error %.3g", fu, fv, d.err[0]);
        CHECK(d.err[1] <= 1e-12 * d.scale[1], "(%d, %d): d1 error %.3g", fu, fv, d.err[1]);
        CHECK(d.err[2] <= 1e-10 * d.scale[2], "(%d, %d): d2 error %.3g", fu, fv, d.err[2]);
        sem_surface_free(&r);
    }
    /* factor 1: a bit-for-bit copy */
    CHECK(sem_surface_refine(&s, 1, 1, &r, &err) == SEM_OK, "%s", err.message);
    CHECK(r.n_u == s.n_u && r.n_v == s.n_v &&
              !memcmp(r.ctrl, s.ctrl, 3 * 35 * sizeof(double)) &&
              !memcmp(r.weights, s.weights, 35 * sizeof(double)) &&
              !memcmp(r.knots_u, s.knots_u, 11 * sizeof(double)),
          "factor 1 is not a copy");
    sem_surface_free(&r);
    /* bad factors and a bad surface: refused, out left empty */
    CHECK(sem_surface_refine(&s, 0, 2, &r, &err) == SEM_ERR_INVALID && r.ctrl == NULL &&
              strstr(err.message, "factor 0"),
          "factor 0: %s", err.message);
    CHECK(sem_surface_refine(&s, 2, SEM_MAX_REFINE_FACTOR + 1, &r, &err) == SEM_ERR_INVALID,
          "factor 65 accepted");
    s.weights[3] = -1;
    CHECK(sem_surface_refine(&s, 2, 2, &r, &err) == SEM_ERR_INVALID && strstr(err.message, "weight"),
          "negative weight: %s", err.message);
    sem_surface_free(&s);
}

/* Rational primitives: exact, and the refined points still lie on the exact sphere / torus. */
static void test_primitives(void)
{
    sem_error err;
    sem_model *sphere = sem_model_create(), *torus = sem_model_create();
    sem_model *cylinder = sem_model_create(), *box = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.radius = 2;
    sd.center[0] = 1;
    sem_torus_def td = sem_default_torus_def();
    sem_cylinder_def cd = sem_default_cylinder_def();
    sem_box_def bd = sem_default_box_def();
    CHECK(sem_primitive_sphere(sphere, &sd, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_primitive_torus(torus, &td, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_primitive_cylinder(cylinder, &cd, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_primitive_box(box, &bd, &err) == SEM_OK, "%s", err.message);
    const int factors[] = {2, 5, 16};
    for (int k = 0; k < 3; ++k) {
        sem_model *r = refine_and_check(sphere, factors[k], "sphere (rational)", 1e-12, NULL);
        sem_model *t = refine_and_check(torus, factors[k], "torus (rational)", 1e-12, NULL);
        sem_model *c = refine_and_check(cylinder, factors[k], "cylinder (rational)", 1e-12, NULL);
        sem_model *b = refine_and_check(box, factors[k], "box (bicubic)", 1e-12, NULL);
        if (r && t) {
            /* distance to the exact surfaces at a grid of points */
            double worst_s = 0, worst_t = 0;
            const sem_surface *ss = &r->parts[0].surface, *ts = &t->parts[0].surface;
            for (int i = 0; i <= 50; ++i)
                for (int j = 0; j <= 50; ++j) {
                    double x[3];
                    sem_surface_eval(ss, ss->u0 + (ss->u1 - ss->u0) * i / 50.0,
                                     ss->v0 + (ss->v1 - ss->v0) * j / 50.0, x, NULL, NULL, NULL);
                    x[0] -= 1;
                    worst_s = fmax(worst_s, fabs(norm3(x) - 2));
                    sem_surface_eval(ts, ts->u0 + (ts->u1 - ts->u0) * i / 50.0,
                                     ts->v0 + (ts->v1 - ts->v0) * j / 50.0, x, NULL, NULL, NULL);
                    double rho = hypot(x[0], x[1]) - td.major;
                    worst_t = fmax(worst_t, fabs(hypot(rho, x[2]) - td.minor));
                }
            printf("K=%2d: refined sphere off radius 2 by %.1e, torus off its tube by %.1e\n",
                   factors[k], worst_s, worst_t);
            CHECK(worst_s <= 1e-14 * 8, "sphere K=%d: %.3g off the sphere", factors[k], worst_s);
            CHECK(worst_t <= 1e-14 * 4, "torus K=%d: %.3g off the torus", factors[k], worst_t);
            /* all weights positive, the surfaces valid */
            CHECK(sem_surface_validate(ss, &err) == SEM_OK, "%s", err.message);
        }
        sem_model_destroy(r);
        sem_model_destroy(t);
        sem_model_destroy(c);
        sem_model_destroy(b);
    }
    /* factor 1: a copy, bit for bit */
    sem_model *one = NULL;
    CHECK(sem_model_refine(sphere, 1, &one, &err) == SEM_OK, "%s", err.message);
    if (one) {
        const sem_surface *a = &sphere->parts[0].surface, *b = &one->parts[0].surface;
        CHECK(a->n_u == b->n_u && a->n_v == b->n_v &&
                  !memcmp(a->ctrl, b->ctrl, 3 * (size_t)a->n_u * a->n_v * sizeof(double)) &&
                  !memcmp(a->weights, b->weights, (size_t)a->n_u * a->n_v * sizeof(double)),
              "factor 1 changed the sphere");
    }
    sem_model_destroy(one);
    sem_model_destroy(sphere);
    sem_model_destroy(torus);
    sem_model_destroy(cylinder);
    sem_model_destroy(box);
}

/* Bad factors and results beyond the readers' limits: refused with one line naming the
 * limit, *out NULL. */
static void test_limits(void)
{
    sem_error err;
    sem_model *m = sem_model_create(), *r = (sem_model *)&err;
    CHECK(sem_model_refine(m, 0, &r, &err) == SEM_ERR_INVALID && r == NULL &&
              strstr(err.message, "outside 1..64"),
          "factor 0: %s", err.message);
    CHECK(sem_model_refine(m, 65, &r, &err) == SEM_ERR_INVALID && r == NULL, "factor 65");
    /* an empty model refines to an empty model */
    CHECK(sem_model_refine(m, 3, &r, &err) == SEM_OK && r && r->n_parts == 0, "empty model");
    sem_model_destroy(r);
    /* one bilinear 20 x 20 net (19 x 19 spans): by 64 it would be 1216^2 > 10^6 points */
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface_alloc(&part.surface, 1, 1, 20, 20);
    sem_surface *s = &part.surface;
    for (int i = 0; i < 22; ++i) s->knots_u[i] = s->knots_v[i] = i < 2 ? 0 : i > 19 ? 19 : i - 1;
    for (int j = 0; j < 20; ++j)
        for (int i = 0; i < 20; ++i) {
            s->ctrl[3 * (i + 20 * j)] = i;
            s->ctrl[3 * (i + 20 * j) + 1] = j;
        }
    s->u0 = s->v0 = 0;
    s->u1 = s->v1 = 19;
    CHECK(sem_model_add_part(m, &part, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_model_refine(m, 64, &r, &err) == SEM_ERR_INVALID && r == NULL &&
              strstr(err.message, "SEM_MAX_PART_CONTROL_POINTS") && !strchr(err.message, '\n'),
          "part limit: %s", err.message);
    printf("refused: %s\n", err.message);
    /* 8 such parts by 40: 761^2 each, 4.6 million in all */
    for (int k = 0; k < 7; ++k) sem_model_add_part(m, &part, &err);
    CHECK(sem_model_refine(m, 40, &r, &err) == SEM_ERR_INVALID && r == NULL &&
              strstr(err.message, "SEM_MAX_MODEL_CONTROL_POINTS"),
          "model limit: %s", err.message);
    printf("refused: %s\n", err.message);
    /* by 12: 229^2 points each, within both, but 8 x 228^2 spans of work 256: the span work */
    CHECK(sem_model_refine(m, 12, &r, &err) == SEM_ERR_INVALID && r == NULL &&
              strstr(err.message, "SEM_MAX_MODEL_SPAN_WORK"),
          "span work: %s", err.message);
    printf("refused: %s\n", err.message);
    CHECK(sem_model_refine(m, 3, &r, &err) == SEM_OK && r && r->parts[7].surface.n_u == 58,
          "by 3: %s", err.message);
    sem_model_destroy(r);
    sem_model_destroy(m);
    /* a long bilinear strip of 1999 spans: by 64, 127,937 knots in u */
    m = sem_model_create();
    sem_part_free(&part);
    sem_surface_alloc(&part.surface, 1, 1, 2000, 2);
    s = &part.surface;
    for (int i = 0; i < 2002; ++i) s->knots_u[i] = i < 2 ? 0 : i > 1999 ? 1999 : i - 1;
    s->knots_v[0] = s->knots_v[1] = 0;
    s->knots_v[2] = s->knots_v[3] = 1;
    for (int c = 0; c < 4000; ++c) s->ctrl[3 * c] = c % 2000, s->ctrl[3 * c + 1] = c / 2000;
    s->u1 = 1999;
    s->v1 = 1;
    sem_model_add_part(m, &part, &err);
    CHECK(sem_model_refine(m, 64, &r, &err) == SEM_ERR_INVALID && strstr(err.message, "SEM_MAX_KNOTS"),
          "knots: %s", err.message);
    printf("refused: %s\n", err.message);
    /* an invalid part is named */
    m->parts[0].surface.weights[5] = 0;
    CHECK(sem_model_refine(m, 2, &r, &err) == SEM_ERR_INVALID && strstr(err.message, "part 1"),
          "invalid part: %s", err.message);
    sem_part_free(&part);
    sem_model_destroy(m);
}

/* The paper's models: exact at K = 2 and 3, trims kept (mug: trimmed parts, tire: holes),
 * and an IGES round trip of the refined model gives back the same numbers. */
static void test_shared_models(void)
{
    static const char *files[] = {"mugs/mug_trimmed_complex.iges", "tire.iges",
                                  "rocket/rocket.iges", "lamppost.iges", "chicken/chicken_simple_closed.iges",
                                  "puft/puft_full_simpler.iges"};
    for (int f = 0; f < (int)(sizeof files / sizeof files[0]); ++f) {
        const char *found = test_shared_model(files[f]);
        if (!found) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s", found);
        sem_error err;
        sem_model *m = NULL;
        CHECK(sem_model_load(path, &m, &err) == SEM_OK, "%s", err.message);
        if (!m) continue;
        for (int k = 2; k <= 3; ++k) {
            sem_model *r = refine_and_check(m, k, files[f], 1e-12, NULL);
            if (!r) continue;
            if (k == 3) {
                /* write, read back: the same model (the writer's reals read back exactly) */
                char out[512];
                snprintf(out, sizeof out, "%s/refined_%d.igs", test_tmpdir(), f);
                sem_model *back = NULL;
                CHECK(sem_model_save(r, out, &err) == SEM_OK, "save: %s", err.message);
                CHECK(sem_model_load(out, &back, &err) == SEM_OK, "read back: %s", err.message);
                if (back) {
                    check_kept(r, back, 1, 0, "IGES round trip");
                    double rel[3];
                    compare_models(r, back, rel);
                    CHECK(rel[0] <= 1e-15 && rel[1] <= 1e-14,
                          "%s: round trip changed the geometry (%.3g, %.3g)", files[f], rel[0], rel[1]);
                    size_t n = sem_model_control_points(r);
                    double *qa = malloc(3 * n * sizeof *qa), *qb = malloc(3 * n * sizeof *qb);
                    sem_model_get_q(r, qa);
                    sem_model_get_q(back, qb);
                    CHECK(sem_model_control_points(back) == n &&
                              !memcmp(qa, qb, 3 * n * sizeof *qa),
                          "%s: control points changed in the round trip", files[f]);
                    free(qa);
                    free(qb);
                }
                sem_model_destroy(back);
            }
            sem_model_destroy(r);
        }
        sem_model_destroy(m);
    }
}

/* The rocket (216 control points: 12 bicubic Bezier patches and one 4 x 6 net of 1 x 3
 * spans) refined to about 1e4, 4e4 and 1e5 dofs: 3 (12 (3 + K)^2 + (3 + K)(3 + 3K)). */
static void test_rocket_scaling(void)
{
    const char *found = test_shared_model("rocket/rocket.iges");
    if (!found) return;
    sem_error err;
    sem_model *m = NULL;
    CHECK(sem_model_load(found, &m, &err) == SEM_OK, "%s", err.message);
    if (!m) return;
    static const int factors[] = {12, 27, 44};
    for (int k = 0; k < 3; ++k) {
        int K = factors[k];
        double seconds = 0;
        sem_model *r = refine_and_check(m, K, "rocket", 1e-12, &seconds);
        if (!r) continue;
        size_t expect = 12 * (size_t)(3 + K) * (3 + K) + (size_t)(3 + K) * (3 + 3 * K);
        size_t n = sem_model_control_points(r);
        CHECK(n == expect, "rocket K=%d: %zu control points, %zu expected", K, n, expect);
        printf("rocket refined by %d: %zu dofs in %.2f ms (sem_model_refine)\n", K, 3 * n,
               1e3 * seconds);
        sem_model_destroy(r);
    }
    /* by 51 the rocket's 15 x 51^2 bicubic spans pass the readers' evaluation-work limit */
    sem_model *r = NULL;
    CHECK(sem_model_refine(m, 51, &r, &err) == SEM_ERR_INVALID && r == NULL &&
              strstr(err.message, "SEM_MAX_MODEL_SPAN_WORK"),
          "rocket by 51: %s", err.message);
    sem_model_destroy(m);
}

/* ---- the command ---- */

static char out[1 << 16], errbuf[1 << 16];

static int run(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2)))
#endif
    ;
static int run(const char *fmt, ...)
{
    char args[4096];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(args, sizeof args, fmt, ap);
    va_end(ap);
    return test_run_cli(args, out, sizeof out, errbuf, sizeof errbuf);
}

static int one_error_line(void)
{
    int lines = 0;
    for (const char *c = errbuf; *c; ++c) lines += *c == '\n';
    return strncmp(errbuf, "sem: ", 5) == 0 && lines == 1;
}

static int exists(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0;
}

static void test_cli(void)
{
    const char *dir = test_tmpdir();
    CHECK(run("primitive sphere --radius 2 -o %s/sphere.igs", dir) == 0, "primitive: %s", errbuf);
    int rc = run("refine %s/sphere.igs %s/sphere4.igs --factor 4", dir, dir);
    CHECK(rc == 0, "refine exit %d: %s", rc, errbuf);
    /* sphere: 9 x 5 net, 4 x 2 spans -> 21 x 11 */
    CHECK(strstr(out, "refined by 4, 1 parts, 45 -> 231 control points (dofs 135 -> 693)") != NULL,
          "summary: %s", out);
    char path[512];
    snprintf(path, sizeof path, "%s/sphere4.igs", dir);
    sem_model *m = NULL;
    sem_error err;
    CHECK(sem_model_load(path, &m, &err) == SEM_OK && m && m->parts[0].surface.n_u == 21 &&
              m->parts[0].surface.n_v == 11,
          "refined sphere read back: %s", err.message);
    sem_model_destroy(m);
    /* any format in, any out: OBJ free-form */
    rc = run("refine %s/sphere.igs %s/sphere2.obj -k 2", dir, dir);
    CHECK(rc == 0 && strstr(out, "45 -> 91"), "refine to obj exit %d: %s %s", rc, out, errbuf);
    CHECK(run("help refine") == 0 && strstr(out, "--factor K"), "help refine");
    CHECK(run("--help") == 0 && strstr(out, "refine"), "sem --help lists refine");

    /* usage errors: exit 2, "sem: ..." then the usage line */
    static const char *usage[] = {"refine %s/sphere.igs %s/x.igs",
                                  "refine %s/sphere.igs %s/x.igs --factor 0",
                                  "refine %s/sphere.igs %s/x.igs --factor 65",
                                  "refine %s/sphere.igs %s/x.igs --factor two",
                                  "refine %s/sphere.igs %s/x.igs --factor",
                                  "refine %s/sphere.igs %s/x.igs --fast",
                                  "refine %s/sphere.igs --factor 2 %s"};
    for (int k = 0; k < 7; ++k) {
        char args[1024];
        snprintf(args, sizeof args, usage[k], dir, k == 6 ? "" : dir);
        rc = run("%s", args);
        CHECK(rc == 2 && strncmp(errbuf, "sem: ", 5) == 0 && strstr(errbuf, "usage: sem refine"),
              "'%s': exit %d, %s", args, rc, errbuf);
    }
    snprintf(path, sizeof path, "%s/x.igs", dir);
    CHECK(!exists(path), "a failed refine left %s", path);
    /* failures: exit 1, one line, nothing written */
    rc = run("refine %s/missing.igs %s/x.igs --factor 2", dir, dir);
    CHECK(rc == 1 && one_error_line() && strstr(errbuf, "missing.igs"), "missing file: %d %s", rc,
          errbuf);
    rc = run("refine %s/sphere.igs %s/no/such/dir/x.igs --factor 2", dir, dir);
    CHECK(rc == 1 && one_error_line(), "unwritable output: %d %s", rc, errbuf);
    rc = run("refine %s/sphere.igs %s/x.txt --factor 2", dir, dir);
    CHECK(rc == 1 && one_error_line(), "unknown output format: %d %s", rc, errbuf);
    CHECK(!exists(path), "a failed refine left %s", path);
    const char *rocket = test_shared_model("rocket/rocket.iges");
    if (rocket) {
        rc = run("refine %s %s/x.igs --factor 51", rocket, dir);
        CHECK(rc == 1 && one_error_line() && strstr(errbuf, "SEM_MAX_MODEL_SPAN_WORK"),
              "rocket by 51: %d %s", rc, errbuf);
        printf("sem refine rocket.iges x.igs --factor 51: %s", errbuf);
        CHECK(!exists(path), "a refused refine left %s", path);
    }
}

int main(void)
{
    test_hand_made_surface();
    test_primitives();
    test_limits();
    test_shared_models();
    test_rocket_scaling();
    test_cli();
    return test_finish("test_refine");
}
