/*
 * pins.c - material pins (see pins.h): the anchored points of an object's pin regions, their
 * z-space blocks, and the anchor's energy, gradient and products.
 */
#include "pins.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include <lapacke.h>

#include "loads.h"
#include "shared_kernels.h"
#include "util/free_all.h"

static int in_box(const double box[6], const double X[3])
{
    return X[0] >= box[0] && X[1] >= box[1] && X[2] >= box[2] && X[0] <= box[3] && X[1] <= box[4] &&
           X[2] <= box[5];
}

void sem_pins_free(sem_object *o)
{
    sem_pins *p = o->pins;
    if (!p) return;
    SEM_FREE_ALL(p->weight, p->X, p->presc, p->start, p->part, p->basis, p->prescribes, p->touched, p->touched_slot);
    free(p);
    o->pins = NULL;
}

/* The stiffest material of the object: the anchor must dominate every part it holds. */
static double largest_modulus(const sem_object *o)
{
    double E = o->def.material.youngs_modulus;
    for (int k = 0; k < o->def.n_part_materials && o->part_mats; ++k) E = fmax(E, o->part_mats[k].youngs_modulus);
    return E;
}

/* Appends anchored point (X, weight, prescription) with the parts of row r of W (a quadrature
 * point's or a sample's blending weights). */
static void add_point(sem_pins *p, const sem_object *o, const sem_csr *W, int r, const double X[3], double weight,
                      int presc)
{
    const sem_discretization *d = o->d;
    int a = p->n_points++, at = p->start[a], m = o->m;
    p->weight[a] = weight;
    memcpy(p->X + 3 * (size_t)a, X, 3 * sizeof(double));
    p->presc[a] = presc;
    for (int e = W->row_start[r]; e < W->row_start[r + 1]; ++e) {
        int i = W->col[e];
        const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
        double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, b[10];
        sem_polynomial_basis(d->order, dX, b, NULL);
        p->part[at] = i;
        for (int k = 0; k < m; ++k) p->basis[(size_t)at * m + k] = W->val[e] * b[k];
        at++;
    }
    p->start[a + 1] = at;
}

sem_status sem_pins_init(sem_object *o, const sem_object_def *def, sem_error *err)
{
    o->pins = NULL;
    if (def->n_pin_regions <= 0) return SEM_OK;
    if (!def->pin_regions) return sem_error_set(err, SEM_ERR_INVALID, "n_pin_regions > 0 but no pin_regions");
    const sem_discretization *d = o->d;
    const int nr = def->n_pin_regions, m = o->m;
    /* each region's prescription, resolved against the definition (pins.h) */
    for (int r = 0; r < nr; ++r) {
        const sem_pin_region *pr = &def->pin_regions[r];
        const double *b = pr->box;
        for (int k = 0; k < 6; ++k)
            if (!isfinite(b[k])) return sem_error_set(err, SEM_ERR_INVALID, "pin region %d: the box is not finite", r);
        if (b[0] > b[3] || b[1] > b[4] || b[2] > b[5])
            return sem_error_set(err, SEM_ERR_INVALID, "pin region %d: the box's lower corner is above its upper one", r);
        int limit = def->n_prescribes > 0 ? def->n_prescribes : 1;
        if (pr->prescribe >= limit)
            return sem_error_set(err, SEM_ERR_INVALID, "pin region %d: prescription %d does not exist (%d given)", r,
                                 pr->prescribe, def->n_prescribes > 0 ? def->n_prescribes : 1);
    }
    sem_pins *p = calloc(1, sizeof *p);
    if (!p) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    o->pins = p;
    p->n_presc = def->n_prescribes > 0 ? def->n_prescribes : 1;
    p->prescribes = calloc((size_t)p->n_presc, sizeof *p->prescribes);
    if (!p->prescribes) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    if (def->n_prescribes > 0 && def->prescribes)
        memcpy(p->prescribes, def->prescribes, (size_t)def->n_prescribes * sizeof *p->prescribes);
    else
        p->prescribes[0] = def->prescribe;
    /* The spacing of the quadrature grid; a discretization without it (an explicit ray grid of
     * an old file) gets the cell of its mean volume. */
    double h = d->quad_spacing > 0 ? d->quad_spacing : (d->n_quad > 0 ? cbrt(d->volume / d->n_quad) : d->length_scale);
    if (!(h > 0)) h = 1;
    p->spacing = h;
    p->stiffness = SEM_PIN_STIFFNESS * largest_modulus(o) / (h * h);
    /* A point lies in the last region whose box holds it (as a later prescribe group wins
     * for control points). Count first, then fill. */
    const sem_csr *Wq = &d->W, *Ws = &d->W_samples;
    size_t n_pts = 0, n_entries = 0;
    for (int pass = 0; pass < 2; ++pass) {
        if (pass == 1) {
            p->weight = malloc((n_pts + 1) * sizeof(double));
            p->X = malloc((3 * n_pts + 1) * sizeof(double));
            p->presc = malloc((n_pts + 1) * sizeof(int));
            p->start = calloc(n_pts + 1, sizeof(int));
            p->part = malloc((n_entries + 1) * sizeof(int));
            p->basis = malloc((n_entries * (size_t)m + 1) * sizeof(double));
            if (!p->weight || !p->X || !p->presc || !p->start || !p->part || !p->basis)
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the pins");
        }
        for (int t = 0; t < 2; ++t) {
            const sem_csr *W = t ? Ws : Wq;
            int n = t ? d->n_samples : d->n_quad;
            const double *XX = t ? d->sample_X : d->quad_X;
            for (int q = 0; q < n; ++q) {
                const double *X = XX + 3 * (size_t)q;
                int region = -1;
                for (int r = 0; r < nr; ++r)
                    if (in_box(def->pin_regions[r].box, X)) region = r;
                if (region < 0) continue;
                double w = t ? 0.5 * h * d->sample_area[q] : d->quad_volume[q];
                if (!(w > 0)) continue; /* a collapsed edge's samples: nothing to hold */
                if (pass == 0) {
                    n_pts++;
                    n_entries += (size_t)(W->row_start[q + 1] - W->row_start[q]);
                    continue;
                }
                int pr = def->pin_regions[region].prescribe;
                if (pr >= 0 && p->prescribes[pr].type == SEM_PRESCRIBE_NONE) pr = -1;
                add_point(p, o, W, q, X, p->stiffness * w, pr);
            }
        }
    }
    /* every region must hold some material */
    for (int r = 0; r < nr; ++r) {
        int any = 0;
        for (int a = 0; a < p->n_points && !any; ++a) {
            int last = -1;
            for (int r2 = 0; r2 < nr; ++r2)
                if (in_box(def->pin_regions[r2].box, p->X + 3 * (size_t)a)) last = r2;
            any = last == r;
        }
        if (!any) {
            const double *b = def->pin_regions[r].box;
            return sem_error_set(err, SEM_ERR_INVALID,
                                 "pin region %d: [[%g, %g, %g], [%g, %g, %g]] holds none of the object's material "
                                 "(no quadrature point or boundary sample lies in it)",
                                 r, b[0], b[1], b[2], b[3], b[4], b[5]);
        }
    }
    for (int a = 0; a < p->n_points; ++a) p->moves |= p->presc[a] >= 0;
    sem_pins_held_parts(o, def);
    /* the parts the anchors touch, for the products */
    p->touched_slot = malloc(((size_t)o->n_parts + 1) * sizeof(int));
    p->touched = malloc(((size_t)o->n_parts + 1) * sizeof(int));
    if (!p->touched_slot || !p->touched) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < o->n_parts; ++i) p->touched_slot[i] = -1;
    for (int e = 0; e < p->start[p->n_points]; ++e) p->touched_slot[p->part[e]] = 1;
    for (int i = 0; i < o->n_parts; ++i)
        if (p->touched_slot[i] > 0) {
            p->touched_slot[i] = p->n_touched;
            p->touched[p->n_touched++] = i;
        }
    return SEM_OK;
}

/* Adds point X (weight w) to part i's form H += w e e^T, e = b(X - Xbar_i). */
static void add_form(const sem_object *o, int i, const double X[3], double w, double *H)
{
    const sem_discretization *d = o->d;
    const int m = o->m;
    const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
    double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, e[10];
    sem_polynomial_basis(d->order, dX, e, NULL);
    for (int r = 0; r < m; ++r)
        for (int c = 0; c < m; ++c) H[r * m + c] += w * e[r] * e[c];
}

void sem_pins_held_parts(const sem_object *o, const sem_object_def *def)
{
    sem_pins *p = o->pins;
    const sem_discretization *d = o->d;
    const int m = o->m, np = o->n_parts, mm = m * m;
    p->held_part = -1;
    p->held_outside = 0;
    if (m > 10) return;
    /* per part: its material's form (every quadrature point and sample it blends into), the
     * held part of it, and the material's weight inside and outside the boxes */
    double *all = calloc((size_t)np * mm + 1, sizeof(double)), *held = calloc((size_t)np * mm + 1, sizeof(double));
    double *total = calloc((size_t)np + 1, sizeof(double)), *outside = calloc((size_t)np + 1, sizeof(double));
    double *lo = malloc((size_t)np * 3 * sizeof(double) + 1), *hi = malloc((size_t)np * 3 * sizeof(double) + 1);
    if (!all || !held || !total || !outside || !lo || !hi) goto done; /* a check only */
    for (int i = 0; i < 3 * np; ++i) lo[i] = INFINITY, hi[i] = -INFINITY;
    /* held: the anchored points (quadrature points and samples), from their basis rows as
     * sem_pins_init keeps them (w_ai b(X_a - Xbar_i), weight k w_a) */
    for (int a = 0; a < p->n_points; ++a)
        for (int e = p->start[a]; e < p->start[a + 1]; ++e) {
            const double *b = p->basis + (size_t)e * m;
            double *H = held + (size_t)p->part[e] * mm, w = p->weight[a] / p->stiffness;
            for (int r = 0; r < m; ++r)
                for (int c = 0; c < m; ++c) H[r * m + c] += w * b[r] * b[c];
        }
    /* all: each part's own surface (its samples, its own polynomial), which is what the user
     * sees move, with the samples' anchor weight a_s h / 2 */
    for (int q = 0; q < d->n_samples; ++q) {
        const double *X = d->sample_X + 3 * (size_t)q;
        double w = 0.5 * p->spacing * d->sample_area[q];
        if (!(w > 0)) continue;
        int in = 0, i = d->sample_part[q];
        for (int r = 0; r < def->n_pin_regions && !in; ++r) in = in_box(def->pin_regions[r].box, X);
        add_form(o, i, X, w, all + (size_t)i * mm);
        total[i] += w;
        if (!in) outside[i] += w;
        for (int k = 0; k < 3; ++k) {
            lo[3 * i + k] = fmin(lo[3 * i + k], X[k]);
            hi[3 * i + k] = fmax(hi[3 * i + k], X[k]);
        }
    }
    /* Part i is held whole when every motion of its polynomial costs the anchor more than the
     * part's own stiffness for a motion of its size: k lambda_min > E / L_i^2, lambda_min the
     * smallest generalized eigenvalue of (held, all) (the held share of the least-held motion
     * of its surface), L_i the diagonal of its surface. */
    const double E = largest_modulus(o);
    for (int i = 0; i < np; ++i) {
        if (!(total[i] > 0)) continue;
        double share = outside[i] / total[i];
        if (share <= SEM_PIN_HELD_OUTSIDE || share <= p->held_outside) continue;
        const double *A = held + (size_t)i * mm, *B = all + (size_t)i * mm;
        if (!(A[0] > 0)) continue; /* nothing of this part held */
        /* lambda_min over the motions the surface shows: B's range (a planar face's samples
         * do not see the polynomial's terms across its plane), by B = V mu V^T, then the
         * eigenvalues of mu^-1/2 V^T A V mu^-1/2 */
        double mu[10], V[100], C[100], AV[100], lambda[10];
        memcpy(V, B, (size_t)mm * sizeof(double));
        if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', m, V, m, mu) != 0) continue;
        int r0 = 0; /* eigenvalues ascend: the range starts at the first above round-off */
        while (r0 < m && !(mu[r0] > 1e-10 * mu[m - 1])) r0++;
        int nr = m - r0;
        if (nr <= 0) continue;
        for (int r = 0; r < m; ++r) /* AV = A V (the range's columns) */
            for (int c = 0; c < nr; ++c) {
                double v = 0;
                for (int k = 0; k < m; ++k) v += A[r * m + k] * V[k * m + r0 + c];
                AV[r * nr + c] = v;
            }
        for (int r = 0; r < nr; ++r)
            for (int c = 0; c < nr; ++c) {
                double v = 0;
                for (int k = 0; k < m; ++k) v += V[k * m + r0 + r] * AV[k * nr + c];
                C[r * nr + c] = v / sqrt(mu[r0 + r] * mu[r0 + c]);
            }
        if (LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'N', 'U', nr, C, nr, lambda) != 0) continue;
        double L2 = 0;
        for (int k = 0; k < 3; ++k) L2 += (hi[3 * i + k] - lo[3 * i + k]) * (hi[3 * i + k] - lo[3 * i + k]);
        if (!(p->stiffness * lambda[0] * L2 > E)) continue;
        p->held_part = i;
        p->held_outside = share;
    }
done:
    SEM_FREE_ALL(all, held, total, outside, lo, hi);
}

void sem_pins_add_pair_blocks(const sem_object *o, double *pairs)
{
    const sem_pins *p = o->pins;
    if (!p) return;
    int m = o->m;
    for (int a = 0; a < p->n_points; ++a)
        for (int x = p->start[a]; x < p->start[a + 1]; ++x)
            for (int y = p->start[a]; y < p->start[a + 1]; ++y) {
                int pair = o->pair_lookup[(size_t)p->part[x] * o->n_parts + p->part[y]];
                double *blk = pairs + (size_t)pair * m * m;
                const double *bx = p->basis + (size_t)x * m, *by = p->basis + (size_t)y * m;
                for (int k = 0; k < m; ++k)
                    for (int l = 0; l < m; ++l) blk[k * m + l] += p->weight[a] * bx[k] * by[l];
            }
}

/* z = Pi_i x (m x 3, coordinates interleaved) for every touched part i, in touched order. */
static void touched_coefficients(const sem_object *o, const double *x, double *z)
{
    const sem_pins *p = o->pins;
    for (int t = 0; t < p->n_touched; ++t)
        sem_part_rows_multiply(o, p->touched[t], o->pi_dense[p->touched[t]], o->m, x, z + 3 * (size_t)t * o->m);
}

/* y += c Pi_i^T zg_i over the touched parts. */
static void touched_add_transpose(const sem_object *o, double c, const double *zg, double *y)
{
    const sem_pins *p = o->pins;
    int m = o->m;
    for (int t = 0; t < p->n_touched; ++t) {
        int i = p->touched[t], g = o->d->part_origin[i];
        size_t n = sem_group_size(o, g);
        const int *ctrl = o->group_ctrl + o->group_start[g];
        const double *zi = zg + 3 * (size_t)t * m;
        for (int k = 0; k < m; ++k) {
            const double *row = o->pi_dense[i] + (size_t)k * n;
            for (size_t l = 0; l < n; ++l) {
                double *yc = y + 3 * (size_t)ctrl[l];
                double v = c * row[l];
                yc[0] += v * zi[3 * k];
                yc[1] += v * zi[3 * k + 1];
                yc[2] += v * zi[3 * k + 2];
            }
        }
    }
}

/* x(X_a) = sum_i e_ai^T z_i from the touched coefficients. */
static void point_position(const sem_object *o, int a, const double *z, double out[3])
{
    const sem_pins *p = o->pins;
    int m = o->m;
    out[0] = out[1] = out[2] = 0;
    for (int e = p->start[a]; e < p->start[a + 1]; ++e) {
        const double *b = p->basis + (size_t)e * m, *zi = z + 3 * (size_t)p->touched_slot[p->part[e]] * m;
        for (int k = 0; k < m; ++k)
            for (int c = 0; c < 3; ++c) out[c] += b[k] * zi[3 * k + c];
    }
}

/* The target of anchored point a at time t. */
static void target(const sem_pins *p, int a, double t, double out[3])
{
    const double *X = p->X + 3 * (size_t)a;
    memcpy(out, X, 3 * sizeof(double));
    if (p->presc[a] >= 0) sem_prescription_apply(&p->prescribes[p->presc[a]], t, X, out);
}

/* Work: the touched parts' coefficients, twice. */
static double *work(const sem_object *o)
{
    return calloc(6 * (size_t)o->pins->n_touched * o->m + 1, sizeof(double));
}

double sem_pins_energy(const sem_object *o, const double *q, double t, double *grad)
{
    const sem_pins *p = o->pins;
    if (!p) return 0;
    double *z = work(o);
    if (!z) return NAN; /* (out of memory: the step's checks stop on a NaN energy) */
    double *zg = z + 3 * (size_t)p->n_touched * o->m;
    touched_coefficients(o, q, z);
    int m = o->m;
    double e = 0;
    for (int a = 0; a < p->n_points; ++a) {
        double x[3], X[3];
        point_position(o, a, z, x);
        target(p, a, t, X);
        double r[3] = {x[0] - X[0], x[1] - X[1], x[2] - X[2]};
        e += 0.5 * p->weight[a] * (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
        if (!grad) continue;
        for (int en = p->start[a]; en < p->start[a + 1]; ++en) {
            const double *b = p->basis + (size_t)en * m;
            double *zi = zg + 3 * (size_t)p->touched_slot[p->part[en]] * m;
            for (int k = 0; k < m; ++k)
                for (int c = 0; c < 3; ++c) zi[3 * k + c] += p->weight[a] * b[k] * r[c];
        }
    }
    if (grad) touched_add_transpose(o, 1.0, zg, grad);
    free(z);
    return e;
}

void sem_pins_multiply(const sem_object *o, double c, const double *x, double *y)
{
    const sem_pins *p = o->pins;
    if (!p || c == 0) return;
    double *z = work(o);
    if (!z) return; /* unreachable in practice; the product is then incomplete */
    double *zg = z + 3 * (size_t)p->n_touched * o->m;
    touched_coefficients(o, x, z);
    int m = o->m;
    for (int a = 0; a < p->n_points; ++a) {
        double xa[3];
        point_position(o, a, z, xa);
        for (int en = p->start[a]; en < p->start[a + 1]; ++en) {
            const double *b = p->basis + (size_t)en * m;
            double *zi = zg + 3 * (size_t)p->touched_slot[p->part[en]] * m;
            for (int k = 0; k < m; ++k)
                for (int cc = 0; cc < 3; ++cc) zi[3 * k + cc] += p->weight[a] * b[k] * xa[cc];
        }
    }
    touched_add_transpose(o, c, zg, y);
    free(z);
}

double sem_pins_residual(const sem_object *o, const double *q, double t)
{
    const sem_pins *p = o->pins;
    if (!p) return 0;
    double *z = work(o);
    if (!z) return NAN;
    touched_coefficients(o, q, z);
    double worst = 0;
    for (int a = 0; a < p->n_points; ++a) {
        double x[3], X[3];
        point_position(o, a, z, x);
        target(p, a, t, X);
        worst = fmax(worst, sqrt((x[0] - X[0]) * (x[0] - X[0]) + (x[1] - X[1]) * (x[1] - X[1]) +
                                 (x[2] - X[2]) * (x[2] - X[2])));
    }
    free(z);
    return worst;
}
