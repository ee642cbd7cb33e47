/*
 * trim_fix.c - a part's trim loops made usable as the readers find them (geometry/trim_fix.h).
 *
 * Why. CAD files give loops that Open CASCADE closes or unwraps with its shape fixing and that
 * our trim regions (trim.c: one even-odd polygon set inside the domain rectangle) cannot take
 * as they are: a sphere's pole edge left out (SolidWorks, Solid Edge), loop curves a few
 * micrometres apart (within the file's resolution), a (u,v) loop that runs across the seam of
 * a closed surface and so leaves its domain (a periodic torus, a STEP cylinder whose pcurves
 * start elsewhere than the converted surface's seam). Each is repaired exactly where it can be
 * (reversal, shifts by whole periods, connectors along collapsed edges, a moved seam) and
 * within the file's tolerance where it cannot (a short connector, which the caller warns
 * about). Loops that need nothing are not touched, so well-formed files read bit for bit as
 * before.
 */
#include "geometry/trim_fix.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/seam.h"
#include "sem/nurbs.h"

void sem_curve_reverse(sem_curve *c)
{
    int n = c->n_ctrl, m = c->n_ctrl + c->degree + 1;
    for (int i = 0, j = n - 1; i < j; ++i, --j) {
        for (int k = 0; k < 3; ++k) {
            double t = c->ctrl[3 * i + k];
            c->ctrl[3 * i + k] = c->ctrl[3 * j + k];
            c->ctrl[3 * j + k] = t;
        }
        double w = c->weights[i];
        c->weights[i] = c->weights[j];
        c->weights[j] = w;
    }
    double a = c->knots[0], b = c->knots[m - 1];
    for (int i = 0, j = m - 1; i <= j; ++i, --j) {
        double ki = c->knots[i], kj = c->knots[j];
        c->knots[i] = a + b - kj;
        c->knots[j] = a + b - ki;
    }
    double t0 = c->t0;
    c->t0 = a + b - c->t1;
    c->t1 = a + b - t0;
}

/* What closing a part's trim loops needs (fix_loops). */
typedef struct loop_fixer {
    const sem_surface *s;
    double size;        /* the surface's control-box diagonal */
    double period[2];   /* the domain's length in a closed direction, 0 in an open one */
    double closure;     /* (u,v) gaps trim.c closes on its own */
    double collapsed;   /* a (u,v) segment whose image stays this close is a single point */
    double bridge;      /* model-space gaps bridged with a warning */
    double worst_gap;   /* the largest gap bridged */
} loop_fixer;

/* The surface point at (u,v), taken modulo the period in a closed direction (loops that
 * crossed the seam are unwrapped). */
static void fixer_eval(const loop_fixer *f, const double uv[2], double x[3])
{
    const sem_surface *s = f->s;
    double w[2] = {uv[0], uv[1]}, lo[2] = {s->u0, s->v0}, hi[2] = {s->u1, s->v1};
    for (int d = 0; d < 2; ++d) {
        if (f->period[d] > 0) w[d] -= f->period[d] * floor((w[d] - lo[d]) / f->period[d]);
        w[d] = fmin(fmax(w[d], lo[d]), hi[d]);
    }
    sem_surface_eval(s, w[0], w[1], x, NULL, NULL, NULL);
}

static void curve_end(const sem_curve *c, int end, double uv[2])
{
    double x[3];
    sem_curve_eval(c, end ? c->t1 : c->t0, x, NULL);
    uv[0] = x[0];
    uv[1] = x[1];
}

static void curve_shift(sem_curve *c, int dir, double by)
{
    for (int i = 0; i < c->n_ctrl; ++i) c->ctrl[3 * i + dir] += by;
}

/* The (u,v) segment a-b on the surface: 0 when its image leaves both ends by more than the
 * bridge, 1 when it is a single point (a collapsed edge: a pole, a cone's apex), 2 when it is
 * a small gap (*gap: its length in model space). */
static int gap_kind(loop_fixer *f, const double a[2], const double b[2], double *gap)
{
    double xa[3], xb[3], x[3], far = 0;
    fixer_eval(f, a, xa);
    fixer_eval(f, b, xb);
    for (int k = 1; k < 8; ++k) {
        double uv[2] = {a[0] + (b[0] - a[0]) * k / 8.0, a[1] + (b[1] - a[1]) * k / 8.0};
        fixer_eval(f, uv, x);
        double da = sqrt((x[0] - xa[0]) * (x[0] - xa[0]) + (x[1] - xa[1]) * (x[1] - xa[1]) +
                         (x[2] - xa[2]) * (x[2] - xa[2]));
        double db = sqrt((x[0] - xb[0]) * (x[0] - xb[0]) + (x[1] - xb[1]) * (x[1] - xb[1]) +
                         (x[2] - xb[2]) * (x[2] - xb[2]));
        far = fmax(far, fmin(da, db));
    }
    *gap = sqrt((xb[0] - xa[0]) * (xb[0] - xa[0]) + (xb[1] - xa[1]) * (xb[1] - xa[1]) +
                (xb[2] - xa[2]) * (xb[2] - xa[2]));
    if (far <= f->collapsed && *gap <= f->collapsed) return 1;
    return far <= f->bridge && *gap <= f->bridge ? 2 : 0;
}

/* A degree-1 curve from a to b in (u,v). */
static sem_status connector(const double a[2], const double b[2], sem_curve *c)
{
    if (sem_curve_alloc(c, 1, 2) != SEM_OK) return SEM_ERR_NOMEM;
    const double k[4] = {0, 0, 1, 1};
    memcpy(c->knots, k, sizeof k);
    c->ctrl[0] = a[0], c->ctrl[1] = a[1], c->ctrl[2] = 0;
    c->ctrl[3] = b[0], c->ctrl[4] = b[1], c->ctrl[5] = 0;
    c->weights[0] = c->weights[1] = 1;
    c->t0 = 0;
    c->t1 = 1;
    return SEM_OK;
}

/* Whether a loop needs fix_loop: a gap between curves (chained as trim.c chains them) wider
 * than trim.c closes, or a curve outside the domain in a closed direction. */
static int loop_needs_fixing(const loop_fixer *f, const sem_trim_loop *loop)
{
    const sem_surface *s = f->s;
    double last[2], first[2];
    for (int k = 0; k < loop->n_curves; ++k) {
        const sem_curve *c = &loop->curves[k];
        double a[2], b[2];
        curve_end(c, 0, a);
        curve_end(c, 1, b);
        int rev;
        if (k == 0) {
            rev = 0;
            if (loop->n_curves > 1) {
                double c0[2], c1[2];
                curve_end(&loop->curves[1], 0, c0);
                curve_end(&loop->curves[1], 1, c1);
                rev = fmin(hypot(a[0] - c0[0], a[1] - c0[1]), hypot(a[0] - c1[0], a[1] - c1[1])) <
                      fmin(hypot(b[0] - c0[0], b[1] - c0[1]), hypot(b[0] - c1[0], b[1] - c1[1]));
            }
            memcpy(first, rev ? b : a, sizeof first);
        } else {
            double ds = hypot(last[0] - a[0], last[1] - a[1]), de = hypot(last[0] - b[0], last[1] - b[1]);
            rev = de < ds;
            if (fmin(ds, de) > f->closure) return 1;
        }
        memcpy(last, rev ? a : b, sizeof last);
        for (int i = 0; i < c->n_ctrl; ++i) {
            double u = c->ctrl[3 * i], v = c->ctrl[3 * i + 1];
            /* past the domain by more than 1e-6 of the period (STEP pcurves run past it by
             * their tolerance, 2e-6 in corpus occt_k1_ug_unsewn: that is nothing) */
            if ((f->period[0] > 0 && (u < s->u0 - 1e-6 * f->period[0] || u > s->u1 + 1e-6 * f->period[0])) ||
                (f->period[1] > 0 && (v < s->v0 - 1e-6 * f->period[1] || v > s->v1 + 1e-6 * f->period[1])))
                return 1;
        }
    }
    return hypot(last[0] - first[0], last[1] - first[1]) > f->closure;
}

/* Closes one loop: curves turned head to tail (exact reversal), a jump of one period across
 * the seam of a closed surface taken away (the rest of the loop shifted by the period), and
 * each remaining gap bridged by a straight (u,v) connector when its image is one point (a
 * collapsed edge the file leaves out: Solid Edge and SolidWorks omit a sphere's pole edge,
 * corpus occt_solidworks_tube) or a gap within the bridge (warned by the caller). 0 when a
 * gap is wider. */
static int fix_loop(loop_fixer *f, sem_trim_loop *loop, sem_status *st)
{
    int n = loop->n_curves;
    /* head to tail, as trim.c would chain them */
    for (int k = 0; k < n; ++k) {
        double a[2], b[2], last[2];
        curve_end(&loop->curves[k], 0, a);
        curve_end(&loop->curves[k], 1, b);
        int rev = 0;
        if (k == 0 && n > 1) {
            double c0[2], c1[2];
            curve_end(&loop->curves[1], 0, c0);
            curve_end(&loop->curves[1], 1, c1);
            rev = fmin(hypot(a[0] - c0[0], a[1] - c0[1]), hypot(a[0] - c1[0], a[1] - c1[1])) <
                  fmin(hypot(b[0] - c0[0], b[1] - c0[1]), hypot(b[0] - c1[0], b[1] - c1[1]));
        } else if (k > 0) {
            curve_end(&loop->curves[k - 1], 1, last);
            rev = hypot(last[0] - b[0], last[1] - b[1]) < hypot(last[0] - a[0], last[1] - a[1]);
        }
        if (rev) sem_curve_reverse(&loop->curves[k]);
    }
    /* unwrap: a jump of whole periods between curves (not along a collapsed edge: at a pole
     * every u is the same point, and the jump is that edge) */
    for (int k = 1; k < n; ++k)
        for (int d = 0; d < 2; ++d) {
            if (!(f->period[d] > 0)) continue;
            double a[2], b[2], gap;
            curve_end(&loop->curves[k - 1], 1, a);
            curve_end(&loop->curves[k], 0, b);
            if (gap_kind(f, a, b, &gap) == 1) continue;
            double jump = b[d] - a[d], turns = round(jump / f->period[d]);
            if (turns == 0 || fabs(jump - turns * f->period[d]) > f->closure) continue;
            for (int j = k; j < n; ++j) curve_shift(&loop->curves[j], d, -turns * f->period[d]);
        }
    /* the gaps left, the closing one included */
    sem_curve *out = calloc((size_t)(2 * n), sizeof *out);
    if (!out) {
        *st = SEM_ERR_NOMEM;
        return 0;
    }
    int m = 0, ok = 1;
    for (int k = 0; k < n && ok; ++k) {
        out[m++] = loop->curves[k];
        double a[2], b[2], gap;
        curve_end(&loop->curves[k], 1, a);
        curve_end(&loop->curves[(k + 1) % n], 0, b);
        if (hypot(b[0] - a[0], b[1] - a[1]) <= f->closure) continue;
        int kind = gap_kind(f, a, b, &gap);
        if (kind == 0) {
            ok = 0;
            break;
        }
        if (kind == 2) f->worst_gap = fmax(f->worst_gap, gap);
        if (connector(a, b, &out[m]) != SEM_OK) {
            *st = SEM_ERR_NOMEM;
            ok = 0;
            break;
        }
        m++;
    }
    if (!ok) {
        /* free only the connectors: the loop's own curves stay with the loop */
        for (int k = 0; k < m; ++k) {
            int owned = 0;
            for (int j = 0; j < n && !owned; ++j) owned = out[k].knots == loop->curves[j].knots;
            if (!owned) sem_curve_free(&out[k]);
        }
        free(out);
        return 0;
    }
    free(loop->curves);
    loop->curves = out;
    loop->n_curves = m;
    return 1;
}

/* The loops' extent in closed direction d all within one period of the domain: the seam is
 * moved (sem_surface_move_seam, exact) to where no loop crosses it, in the middle of the
 * widest such stretch (at a loop's own seam edge when a loop spans the whole period: a band
 * around a cylinder whose pcurves start elsewhere than the surface's seam, as Open CASCADE's
 * NURBS conversion leaves STEP cylinders: corpus nist_ctc_05, chrono_assembly), and each loop
 * is shifted by whole periods into the new domain. 0 when the loops leave no such place. */
static int fit_loops_in_period(loop_fixer *f, sem_surface *s, sem_trim_loop **loops, int n_loops,
                               int d, sem_status *st)
{
    double P = f->period[d], lo0 = d ? s->v0 : s->u0, hi0 = d ? s->v1 : s->u1, eps = 1e-9 * P;
    double slack = 1e-6 * P; /* what counts as outside (loop_needs_fixing) */
    double *iv = malloc((size_t)(n_loops > 0 ? n_loops : 1) * 2 * sizeof *iv);
    if (!iv) {
        *st = SEM_ERR_NOMEM;
        return 0;
    }
    int outside = 0, n = 0;
    for (int l = 0; l < n_loops; ++l) {
        if (loops[l]->n_curves == 0) continue;
        double lo = INFINITY, hi = -INFINITY;
        for (int k = 0; k < loops[l]->n_curves; ++k)
            for (int i = 0; i < loops[l]->curves[k].n_ctrl; ++i) {
                lo = fmin(lo, loops[l]->curves[k].ctrl[3 * i + d]);
                hi = fmax(hi, loops[l]->curves[k].ctrl[3 * i + d]);
            }
        iv[2 * n] = lo;
        iv[2 * n + 1] = hi;
        n++;
        outside |= lo < lo0 - slack || hi > hi0 + slack;
        if (!(hi - lo <= P + slack)) {
            free(iv);
            return !outside;
        }
    }
    if (!outside) {
        free(iv);
        return 1;
    }
    /* candidate seams: the ends of every loop; one that no loop runs over, with the most
     * room after it before the next loop starts */
    double best = -1, seam = lo0;
    for (int c = 0; c < 2 * n; ++c) {
        double from = iv[c], room = P;
        int inside = 0;
        for (int j = 0; j < n && !inside; ++j) {
            double len = iv[2 * j + 1] - iv[2 * j];
            if (len < eps) continue;
            double a = iv[2 * j] - from; /* where loop j starts, from `from` on, in [0, P) */
            a -= P * floor(a / P);
            if (a > P - eps) a = 0;
            double b = a <= eps ? 0 : P - a; /* how far into loop j `from` is */
            if (b > eps && b < len - eps) inside = 1;
            room = fmin(room, a <= eps ? 0 : a);
        }
        if (!inside && room > best) {
            best = room;
            seam = from + 0.5 * (room < P ? room : 0);
        }
    }
    if (best < 0) {
        free(iv);
        return 0;
    }
    /* the new start within one period of the old one, nearest it */
    double start = seam - P * round((seam - lo0) / P);
    if (fabs(start - lo0) > 1e-12 * P) {
        sem_error e;
        sem_status ms = sem_surface_move_seam(s, d, start, &e);
        if (ms != SEM_OK) {
            if (ms == SEM_ERR_NOMEM) *st = ms;
            free(iv);
            return 0;
        }
    }
    lo0 = d ? s->v0 : s->u0;
    n = 0;
    for (int l = 0; l < n_loops; ++l) {
        if (loops[l]->n_curves == 0) continue;
        double turns = floor((iv[2 * n] - lo0 + eps) / P);
        n++;
        if (turns != 0)
            for (int k = 0; k < loops[l]->n_curves; ++k) curve_shift(&loops[l]->curves[k], d, -turns * P);
    }
    free(iv);
    return 1;
}

sem_status sem_part_fix_loops(sem_part *part, sem_loop_fix *fix)
{
    fix->widest_gap = 0;
    fix->gap_limit = fix->bridge;
    fix->outer_dropped = fix->holes_dropped = fix->wound = fix->changed = 0;
    int n_loops = (part->has_outer ? 1 : 0) + part->n_holes;
    if (n_loops == 0) return SEM_OK;
    loop_fixer f;
    memset(&f, 0, sizeof f);
    sem_surface *s = &part->surface;
    f.s = s;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < (size_t)s->n_u * (size_t)s->n_v; ++i)
        for (int d = 0; d < 3; ++d) {
            lo[d] = fmin(lo[d], s->ctrl[3 * i + d]);
            hi[d] = fmax(hi[d], s->ctrl[3 * i + d]);
        }
    f.size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                  (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(f.size > 0) || !isfinite(f.size)) return SEM_OK;
    f.closure = 1e-3 * hypot(s->u1 - s->u0, s->v1 - s->v0); /* trim.c's closure tolerance */
    f.collapsed = 2e-5 * f.size;                          /* the projection's tolerance */
    /* the gaps the file allows, or 1e-4 of the surface (the model's size is not known while
     * its faces are read) */
    f.bridge = fmax(fix->bridge, 1e-4 * f.size);
    fix->gap_limit = f.bridge;
    for (int d = 0; d < 2; ++d)
        f.period[d] = sem_surface_is_closed(s, d, f.collapsed) ? (d ? s->v1 - s->v0 : s->u1 - s->u0) : 0;
    sem_trim_loop **loops = malloc((size_t)n_loops * sizeof *loops);
    if (!loops) return SEM_ERR_NOMEM;
    for (int l = 0; l < n_loops; ++l)
        loops[l] = part->has_outer && l == 0 ? &part->outer : &part->holes[l - part->has_outer];
    int any = 0;
    for (int l = 0; l < n_loops; ++l) any |= loops[l]->n_curves > 0 && loop_needs_fixing(&f, loops[l]);
    fix->changed = any;
    sem_status st = SEM_OK;
    int dropped = 0;
    /* the loops as they came, to go back to when they cannot share one period: then they are
     * kept as they were (trim.c judges them, as before) */
    sem_trim_loop *saved = any ? calloc((size_t)n_loops, sizeof *saved) : NULL;
    if (any && !saved) {
        free(loops);
        return SEM_ERR_NOMEM;
    }
    for (int l = 0; any && l < n_loops && st == SEM_OK; ++l) {
        saved[l].curves = calloc((size_t)(loops[l]->n_curves > 0 ? loops[l]->n_curves : 1), sizeof(sem_curve));
        if (!saved[l].curves) st = SEM_ERR_NOMEM;
        for (int k = 0; st == SEM_OK && k < loops[l]->n_curves; ++k, ++saved[l].n_curves)
            st = sem_curve_copy(&saved[l].curves[k], &loops[l]->curves[k]);
    }
    for (int l = 0; any && st == SEM_OK && l < n_loops; ++l) {
        if (loops[l]->n_curves == 0 || !loop_needs_fixing(&f, loops[l])) continue;
        if (fix_loop(&f, loops[l], &st) || st != SEM_OK) continue;
        if (part->has_outer && l == 0) fix->outer_dropped = 1;
        else fix->holes_dropped++;
        for (int k = 0; k < loops[l]->n_curves; ++k) sem_curve_free(&loops[l]->curves[k]);
        free(loops[l]->curves);
        loops[l]->curves = NULL;
        loops[l]->n_curves = 0;
        dropped = 1;
    }
    fix->widest_gap = f.worst_gap;
    for (int d = 0; any && st == SEM_OK && d < 2; ++d) {
        if (!(f.period[d] > 0)) continue;
        if (!fit_loops_in_period(&f, s, loops, n_loops, d, &st) && st == SEM_OK) {
            fix->wound = 1;
            fix->outer_dropped = fix->holes_dropped = 0;
            fix->widest_gap = 0;
            dropped = 0;
            for (int l = 0; l < n_loops; ++l) {
                for (int k = 0; k < loops[l]->n_curves; ++k) sem_curve_free(&loops[l]->curves[k]);
                free(loops[l]->curves);
                *loops[l] = saved[l];
                saved[l].curves = NULL;
                saved[l].n_curves = 0;
            }
            break;
        }
    }
    for (int l = 0; saved && l < n_loops; ++l) {
        for (int k = 0; k < saved[l].n_curves; ++k) sem_curve_free(&saved[l].curves[k]);
        free(saved[l].curves);
    }
    free(saved);
    free(loops);
    if (dropped) {
        /* loops left empty: an outer one trims nothing, holes go */
        if (part->has_outer && part->outer.n_curves == 0) part->has_outer = 0;
        int k = 0;
        for (int h = 0; h < part->n_holes; ++h)
            if (part->holes[h].n_curves > 0) part->holes[k++] = part->holes[h];
        part->n_holes = k;
    }
    return st;
}

void sem_part_untrim(sem_part *part)
{
    sem_part keep;
    memset(&keep, 0, sizeof keep);
    keep.surface = part->surface;
    memset(&part->surface, 0, sizeof part->surface);
    sem_part_free(part);
    *part = keep;
}
