/*
 * refine.c - exact refinement of NURBS surfaces and models by knot insertion (sem/refine.h).
 *
 * Design: a knot inserted into a B-spline changes the basis but not the function (Boehm
 * 1980); inserting r knots at once is Piegl & Tiller's A5.4 (RefineKnotVectCurve), which
 * computes each new control point as one convex combination per inserted knot, O((n + r) p)
 * work for n control points. A rational surface is refined exactly by refining its
 * homogeneous points (w x, w y, w z, w). A tensor-product surface refines one direction at a
 * time (A5.5): in u every row of the control net is a curve; in v the whole row of
 * 4 n_u numbers is one "point", so the same routine runs once over contiguous memory.
 *
 * The split points U[i] + (U[i+1] - U[i]) k / K are computed as ((K - k) U[i] + k U[i+1]) / K,
 * which is exact at both ends and monotone in k, and only points strictly inside the span
 * are kept, so knot multiplicities never grow and the result is always a valid surface.
 *
 * Before anything large is allocated, sem_model_refine computes the refined sizes and knot
 * vectors and checks them against the readers' limits (sem/limits.h), so a refined model can
 * always be saved and read back.
 */
#include "sem/refine.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/limits.h"
#include "sem/nurbs.h"

/* The knots that split every non-empty span of the domain [U[p], U[n]] into `factor` equal
 * parts, ascending; X may be NULL to count them. Returns the count. */
static int split_knots(int p, int n, const double *U, int factor, double *X)
{
    int r = 0;
    for (int i = p; i < n; ++i) {
        double a = U[i], b = U[i + 1], last = a;
        if (!(b > a)) continue;
        for (int k = 1; k < factor; ++k) {
            double t = ((double)(factor - k) * a + (double)k * b) / (double)factor;
            if (!(t > last && t < b)) continue;
            if (X) X[r] = t;
            r++;
            last = t;
        }
    }
    return r;
}

/* Merges the knot vector U (m values) with the ascending new knots X (r values): the refined
 * knot vector, m + r values. */
static void merge_knots(const double *U, int m, const double *X, int r, double *out)
{
    int i = 0, j = 0, k = 0;
    while (i < m || j < r) out[k++] = j >= r || (i < m && U[i] <= X[j]) ? U[i++] : X[j++];
}

/* Piegl & Tiller A5.4 on n points of `dim` doubles each (point i at P + i dim): inserts the r
 * knots X (ascending, each strictly inside a non-empty span of [U[p], U[n]]) into the knot
 * vector U of degree p. Writes the n + r points Q and the refined knot vector Ubar
 * (n + r + p + 1 values; the algorithm reads it as it goes). */
static void refine_points(int p, int n, const double *U, const double *X, int r, const double *P,
                          double *Q, size_t dim, double *Ubar)
{
    /* the book's names: n - 1 = last control point, r - 1 = last new knot, m = last knot */
    const int last = n - 1, rl = r - 1, m = last + p + 1;
    const size_t bytes = dim * sizeof(double);
    int a = sem_bspline_span(p, n, U, X[0]);
    int b = sem_bspline_span(p, n, U, X[rl]) + 1;
    for (int j = 0; j <= a - p; ++j) memcpy(Q + (size_t)j * dim, P + (size_t)j * dim, bytes);
    for (int j = b - 1; j <= last; ++j)
        memcpy(Q + (size_t)(j + r) * dim, P + (size_t)j * dim, bytes);
    for (int j = 0; j <= a; ++j) Ubar[j] = U[j];
    for (int j = b + p; j <= m; ++j) Ubar[j + r] = U[j];
    int i = b + p - 1, k = b + p + rl;
    for (int j = rl; j >= 0; --j) {
        /* the old points right of X[j] move r' places right unchanged */
        while (X[j] <= U[i] && i > a) {
            memcpy(Q + (size_t)(k - p - 1) * dim, P + (size_t)(i - p - 1) * dim, bytes);
            Ubar[k] = U[i];
            k--;
            i--;
        }
        memcpy(Q + (size_t)(k - p - 1) * dim, Q + (size_t)(k - p) * dim, bytes);
        for (int l = 1; l <= p; ++l) {
            int ind = k - p + l;
            double *left = Q + (size_t)(ind - 1) * dim;
            const double *right = Q + (size_t)ind * dim;
            double alpha = Ubar[k + l] - X[j];
            if (alpha == 0.0) {
                memcpy(left, right, bytes);
                continue;
            }
            alpha /= Ubar[k + l] - U[i - p + l];
            for (size_t d = 0; d < dim; ++d) left[d] = alpha * left[d] + (1.0 - alpha) * right[d];
        }
        Ubar[k] = X[j];
        k--;
    }
}

static sem_status check_factor(int factor, sem_error *err)
{
    if (factor < 1 || factor > SEM_MAX_REFINE_FACTOR)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "refinement factor %d is outside 1..%d (SEM_MAX_REFINE_FACTOR)", factor,
                             SEM_MAX_REFINE_FACTOR);
    return SEM_OK;
}

sem_status sem_surface_refine(const sem_surface *in, int factor_u, int factor_v, sem_surface *out,
                              sem_error *err)
{
    memset(out, 0, sizeof *out);
    sem_status st = check_factor(factor_u, err);
    if (st == SEM_OK) st = check_factor(factor_v, err);
    if (st == SEM_OK) st = sem_surface_validate(in, err);
    if (st != SEM_OK) return st;
    const int ru = split_knots(in->degree_u, in->n_u, in->knots_u, factor_u, NULL);
    const int rv = split_knots(in->degree_v, in->n_v, in->knots_v, factor_v, NULL);
    double *Xu = malloc(((size_t)ru + 1) * sizeof *Xu);
    double *Xv = malloc(((size_t)rv + 1) * sizeof *Xv);
    if (!Xu || !Xv) {
        free(Xu);
        free(Xv);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory refining a surface");
    }
    split_knots(in->degree_u, in->n_u, in->knots_u, factor_u, Xu);
    split_knots(in->degree_v, in->n_v, in->knots_v, factor_v, Xv);
    st = sem_surface_insert_knots(in, Xu, ru, Xv, rv, out, err);
    free(Xu);
    free(Xv);
    return st;
}

sem_status sem_surface_insert_knots(const sem_surface *in, const double *Xu, int ru, const double *Xv, int rv,
                                    sem_surface *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    sem_status st = sem_surface_validate(in, err);
    if (st != SEM_OK) return st;
    const int pu = in->degree_u, pv = in->degree_v, nu = in->n_u, nv = in->n_v;
    for (int k = 0; k < ru; ++k)
        if (!(Xu[k] > in->knots_u[pu] && Xu[k] < in->knots_u[nu]) || (k > 0 && Xu[k] < Xu[k - 1]))
            return sem_error_set(err, SEM_ERR_INVALID, "knot %g to insert is outside the u domain or not ascending", Xu[k]);
    for (int k = 0; k < rv; ++k)
        if (!(Xv[k] > in->knots_v[pv] && Xv[k] < in->knots_v[nv]) || (k > 0 && Xv[k] < Xv[k - 1]))
            return sem_error_set(err, SEM_ERR_INVALID, "knot %g to insert is outside the v domain or not ascending", Xv[k]);
    if (ru == 0 && rv == 0) {
        /* nothing to insert: an exact copy, bit for bit (no homogeneous round trip) */
        if (sem_surface_copy(out, in) != SEM_OK)
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory copying a surface");
        return SEM_OK;
    }
    const int mu = nu + ru, mv = nv + rv;
    double *hw = malloc((size_t)nu * nv * 4 * sizeof *hw);       /* input, homogeneous */
    double *rows = malloc((size_t)mu * nv * 4 * sizeof *rows);   /* refined in u */
    double *grid = malloc((size_t)mu * mv * 4 * sizeof *grid);   /* refined in u and v */
    if (!hw || !rows || !grid || sem_surface_alloc(out, pu, pv, mu, mv) != SEM_OK) {
        free(hw);
        free(rows);
        free(grid);
        sem_surface_free(out);
        return sem_error_set(err, SEM_ERR_NOMEM,
                             "out of memory refining a %d x %d surface to %d x %d", nu, nv, mu, mv);
    }
    for (size_t c = 0; c < (size_t)nu * nv; ++c) {
        double w = in->weights[c];
        hw[4 * c] = in->ctrl[3 * c] * w;
        hw[4 * c + 1] = in->ctrl[3 * c + 1] * w;
        hw[4 * c + 2] = in->ctrl[3 * c + 2] * w;
        hw[4 * c + 3] = w;
    }
    /* u: each row j (points i + n_u j) is a curve of 4-vectors */
    if (ru > 0) {
        for (int j = 0; j < nv; ++j)
            refine_points(pu, nu, in->knots_u, Xu, ru, hw + (size_t)4 * nu * j,
                          rows + (size_t)4 * mu * j, 4, out->knots_u);
    } else {
        memcpy(rows, hw, (size_t)nu * nv * 4 * sizeof *rows);
        memcpy(out->knots_u, in->knots_u, (size_t)(nu + pu + 1) * sizeof *out->knots_u);
    }
    /* v: a whole row of the net (4 m_u numbers) is one point */
    if (rv > 0) {
        refine_points(pv, nv, in->knots_v, Xv, rv, rows, grid, (size_t)4 * mu, out->knots_v);
    } else {
        memcpy(grid, rows, (size_t)mu * mv * 4 * sizeof *grid);
        memcpy(out->knots_v, in->knots_v, (size_t)(nv + pv + 1) * sizeof *out->knots_v);
    }
    for (size_t c = 0; c < (size_t)mu * mv; ++c) {
        double w = grid[4 * c + 3];
        out->weights[c] = w;
        out->ctrl[3 * c] = grid[4 * c] / w;
        out->ctrl[3 * c + 1] = grid[4 * c + 1] / w;
        out->ctrl[3 * c + 2] = grid[4 * c + 2] / w;
    }
    out->u0 = in->u0;
    out->u1 = in->u1;
    out->v0 = in->v0;
    out->v1 = in->v1;
    out->closed_u = in->closed_u;
    out->closed_v = in->closed_v;
    out->periodic_u = in->periodic_u;
    out->periodic_v = in->periodic_v;
    free(hw);
    free(rows);
    free(grid);
    return SEM_OK;
}

static long long loop_control_points(const sem_trim_loop *l)
{
    long long n = 0;
    for (int c = 0; c < l->n_curves; ++c) n += l->curves[c].n_ctrl;
    return n;
}

static const char *part_label(const sem_part *p, int index, char *buf, size_t size)
{
    if (p->name[0]) snprintf(buf, size, "part %d (%s)", index + 1, p->name);
    else snprintf(buf, size, "part %d", index + 1);
    return buf;
}

/* The refined sizes of every part against the readers' limits, from the knot vectors alone:
 * control points per part and in all (with the trim curves, as the readers count them),
 * knots per direction, and the evaluation work of the knot spans (sem_model_check_limits on
 * a model that holds only the refined knot vectors, which is all that check reads). */
static sem_status check_refined_limits(const sem_model *in, int factor, sem_error *err)
{
    long long total = 0;
    sem_status st = SEM_OK;
    char label[96];
    sem_part *shape = calloc((size_t)in->n_parts + 1, sizeof *shape);
    if (!shape) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory refining a model");
    for (int i = 0; i < in->n_parts && st == SEM_OK; ++i) {
        const sem_part *p = &in->parts[i];
        const sem_surface *s = &p->surface;
        int ru = split_knots(s->degree_u, s->n_u, s->knots_u, factor, NULL);
        int rv = split_knots(s->degree_v, s->n_v, s->knots_v, factor, NULL);
        long long mu = (long long)s->n_u + ru, mv = (long long)s->n_v + rv;
        long long ku = mu + s->degree_u + 1, kv = mv + s->degree_v + 1;
        part_label(p, i, label, sizeof label);
        if (ku > SEM_MAX_KNOTS || kv > SEM_MAX_KNOTS) {
            st = sem_error_set(err, SEM_ERR_INVALID,
                               "refined by %d, %s would have %lld x %lld knots; at most %d per "
                               "direction are read (limit SEM_MAX_KNOTS)",
                               factor, label, ku, kv, SEM_MAX_KNOTS);
            break;
        }
        if (mu * mv > SEM_MAX_PART_CONTROL_POINTS) {
            st = sem_error_set(err, SEM_ERR_INVALID,
                               "refined by %d, %s would have %lld x %lld = %lld control points; "
                               "at most %d are read (limit SEM_MAX_PART_CONTROL_POINTS)",
                               factor, label, mu, mv, mu * mv, SEM_MAX_PART_CONTROL_POINTS);
            break;
        }
        total += mu * mv + loop_control_points(&p->outer);
        for (int h = 0; h < p->n_holes; ++h) total += loop_control_points(&p->holes[h]);
        if (total > SEM_MAX_MODEL_CONTROL_POINTS) {
            st = sem_error_set(err, SEM_ERR_INVALID,
                               "refined by %d, the model would have more than %d control points "
                               "(surfaces and trim curves; limit SEM_MAX_MODEL_CONTROL_POINTS)",
                               factor, SEM_MAX_MODEL_CONTROL_POINTS);
            break;
        }
        sem_surface *t = &shape[i].surface;
        *t = *s;
        t->n_u = (int)mu;
        t->n_v = (int)mv;
        t->ctrl = t->weights = NULL;
        t->knots_u = malloc((size_t)ku * sizeof *t->knots_u);
        t->knots_v = malloc((size_t)kv * sizeof *t->knots_v);
        double *x = malloc(((size_t)(ru > rv ? ru : rv) + 1) * sizeof *x);
        if (!t->knots_u || !t->knots_v || !x) {
            free(x);
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory refining a model");
            break;
        }
        split_knots(s->degree_u, s->n_u, s->knots_u, factor, x);
        merge_knots(s->knots_u, s->n_u + s->degree_u + 1, x, ru, t->knots_u);
        split_knots(s->degree_v, s->n_v, s->knots_v, factor, x);
        merge_knots(s->knots_v, s->n_v + s->degree_v + 1, x, rv, t->knots_v);
        free(x);
    }
    if (st == SEM_OK) {
        sem_model refined = {0};
        refined.n_parts = in->n_parts;
        refined.parts = shape;
        sem_error lerr;
        if (sem_model_check_limits(&refined, &lerr) != SEM_OK)
            st = sem_error_set(err, SEM_ERR_INVALID, "refined by %d, %s", factor, lerr.message);
    }
    for (int i = 0; i < in->n_parts; ++i) {
        free(shape[i].surface.knots_u);
        free(shape[i].surface.knots_v);
    }
    free(shape);
    return st;
}

sem_status sem_model_refine(const sem_model *in, int factor, sem_model **out, sem_error *err)
{
    *out = NULL;
    sem_status st = check_factor(factor, err);
    if (st != SEM_OK) return st;
    char label[96];
    for (int i = 0; i < in->n_parts; ++i) {
        sem_error serr;
        if (sem_surface_validate(&in->parts[i].surface, &serr) != SEM_OK)
            return sem_error_set(err, SEM_ERR_INVALID, "%s: %s",
                                 part_label(&in->parts[i], i, label, sizeof label), serr.message);
    }
    st = check_refined_limits(in, factor, err);
    if (st != SEM_OK) return st;
    sem_model *m = sem_model_create();
    if (!m) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory refining a model");
    memcpy(m->units, in->units, sizeof m->units);
    m->unit_to_meter = in->unit_to_meter;
    for (int i = 0; i < in->n_parts && st == SEM_OK; ++i) {
        /* the part as it is (name, trims, colour, entity), then its surface refined */
        sem_part part;
        sem_surface refined;
        if (sem_part_copy(&part, &in->parts[i]) != SEM_OK) {
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory refining a model");
            break;
        }
        st = sem_surface_refine(&in->parts[i].surface, factor, factor, &refined, err);
        if (st == SEM_OK) {
            sem_surface_free(&part.surface);
            part.surface = refined;
            st = sem_model_take_part(m, &part, err);
        }
        sem_part_free(&part);
    }
    for (int i = 0; i < in->n_warnings && st == SEM_OK; ++i)
        if (in->warnings[i]) sem_model_warn(m, "%s", in->warnings[i]);
    if (st != SEM_OK) {
        sem_model_destroy(m);
        return st;
    }
    *out = m;
    return SEM_OK;
}
