/*
 * sampling.c - boundary samples of the parts, J-hat and the area weights S (paper Sec. 5).
 *
 * Shape matching (Eq. 4-5) fits a polynomial to each part in the least-squares sense over its
 * surface, so the fit needs a surface quadrature: on every non-empty knot span of the part's
 * parameter range, in each direction, (degree + 1) Gauss-Lobatto points (at least 2), with
 * weight w_a w_b (h_u / 2)(h_v / 2) |x_u x x_v| at rest. Inside a span the surface is smooth
 * (polynomial for non-rational patches), so a per-span rule is accurate; Lobatto points
 * include the span ends, so neighbouring spans share their boundary points. A shared point is
 * stored once per span (with that span's weight): the count is simply
 * parts x spans x (p_u + 1)(p_v + 1) for untrimmed parts, and the weights sum to the area.
 *
 * Trimmed parts keep only the samples inside their trim loops (sem_trim_region_inside).
 * The paper's rule alone can miss a trimmed part entirely: a bilinear plane of one knot span
 * trimmed to a disc has its 2 x 2 Lobatto points at the corners, all outside (the lamppost
 * has such a part). For trimmed parts only, we therefore split each knot span into equal
 * sub-spans so that every direction has at least SEM_TRIM_MIN_POINTS points over the part
 * (24: 12 sub-spans for degree 1, 6 for degree 3), each sub-span with the same Lobatto rule.
 * Untrimmed parts keep exactly the paper's count.
 * Lobatto end points lie exactly on span edges, which are often also trim edges (an outer
 * loop that is the domain rectangle, a loop through a knot line); an even-odd test is
 * ambiguous exactly there. We therefore test the point nudged by 1e-9 of the span width
 * towards the span centre: a point on the trim curve then counts with the side its own span
 * lies on, so a span fully inside keeps all its points and one fully outside drops them.
 *
 * J-hat (Eq. 2 stacked over the samples): row s holds the rational basis values phi_ij at
 * sample s, columns are global control point indices (part offset + i + n_u j), exact zeros
 * (B-spline functions vanishing at a knot) are not stored. sample_X is J-hat q0 evaluated
 * in the same order, so J-hat q0 reproduces it to rounding.
 *
 * Threads: one part per task; each part fills its own buffers, which are then concatenated
 * in part order, so the result does not depend on the thread count.
 */
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/nurbs.h"
#include "sem/trim.h"
#include "steps.h"
#include "util/free_all.h"
#include "util/threads.h"

/* Relative shift of a trim test point towards its span centre (see the opening comment). */
#define SEM_TRIM_NUDGE 1e-9
/* Minimum points per direction over a trimmed part (see the opening comment). */
#define SEM_TRIM_MIN_POINTS 24

/* The samples of one part, before concatenation. */
typedef struct part_samples {
    int n;          /* samples */
    size_t nnz;     /* J-hat entries */
    double *uv;     /* 2n */
    double *X;      /* 3n */
    double *area;   /* n */
    double *seam;   /* n: sample_seam (see sem_discretization) */
    int *row_nnz;   /* n */
    int *col;       /* nnz, local control point index */
    double *val;    /* nnz */
    sem_status status;
    sem_error err;
} part_samples;

static void part_samples_free(part_samples *p)
{
    SEM_FREE_ALL(p->uv, p->X, p->area, p->seam, p->row_nnz, p->col, p->val);
}

static int lobatto_points(int degree)
{
    int n = degree + 1;
    return n < 2 ? 2 : n;
}

/* Splits each of the n_breaks - 1 spans of breaks into `pieces` equal sub-spans; out must
 * hold (n_breaks - 1) * pieces + 1 values. Returns the new count. */
static int subdivide_breaks(const double *breaks, int n_breaks, int pieces, double *out)
{
    int n = 0;
    for (int a = 0; a + 1 < n_breaks; ++a)
        for (int k = 0; k < pieces; ++k)
            out[n++] = k == 0 ? breaks[a] : breaks[a] + (breaks[a + 1] - breaks[a]) * k / pieces;
    out[n++] = breaks[n_breaks - 1];
    return n;
}

/* Breaks of a trimmed part's direction, refined to at least SEM_TRIM_MIN_POINTS points.
 * Returns the count, or -1 when out of memory (*breaks is replaced). */
static int refine_for_trim(double **breaks, int n_breaks, int points)
{
    int spans = n_breaks - 1;
    int want = (SEM_TRIM_MIN_POINTS + points - 1) / points;
    int pieces = (want + spans - 1) / spans;
    if (pieces <= 1) return n_breaks;
    double *out = malloc(((size_t)spans * (size_t)pieces + 1) * sizeof *out);
    if (!out) return -1;
    int n = subdivide_breaks(*breaks, n_breaks, pieces, out);
    free(*breaks);
    *breaks = out;
    return n;
}

/* Samples part `index` of the model into out (out->status tells the outcome). */
static void sample_part(const sem_part *part, int index, part_samples *out)
{
    const sem_surface *s = &part->surface;
    memset(out, 0, sizeof *out);
    out->status = sem_surface_validate(s, &out->err);
    if (out->status != SEM_OK) {
        char msg[sizeof out->err.message];
        memcpy(msg, out->err.message, sizeof msg);
        sem_error_set(&out->err, out->status, "part %d: %.900s", index, msg);
        return;
    }
    sem_trim_region *trim = NULL;
    if (part->has_outer || part->n_holes > 0) {
        out->status = sem_trim_region_build(part, &trim, &out->err);
        if (out->status != SEM_OK) {
            char msg[sizeof out->err.message];
            memcpy(msg, out->err.message, sizeof msg);
            sem_error_set(&out->err, out->status, "part %d: %.900s", index, msg);
            return;
        }
    }
    const int nu = lobatto_points(s->degree_u), nv = lobatto_points(s->degree_v);
    const int basis_max = (s->degree_u + 1) * (s->degree_v + 1);
    double xu[SEM_MAX_DEGREE + 2], wu[SEM_MAX_DEGREE + 2], xv[SEM_MAX_DEGREE + 2],
        wv[SEM_MAX_DEGREE + 2];
    sem_gauss_lobatto(nu, xu, wu);
    sem_gauss_lobatto(nv, xv, wv);

    /* sem_knot_breaks returns at most the number of distinct knots in range */
    int max_bu = s->n_u + s->degree_u + 2, max_bv = s->n_v + s->degree_v + 2;
    double *bu = malloc((size_t)max_bu * sizeof *bu);
    double *bv = malloc((size_t)max_bv * sizeof *bv);
    int *index_buf = malloc((size_t)basis_max * sizeof *index_buf);
    double *phi = malloc(3 * (size_t)basis_max * sizeof *phi);
    if (!bu || !bv || !index_buf || !phi) goto nomem;
    double *phi_u = phi + basis_max, *phi_v = phi + 2 * basis_max;
    int n_bu = sem_knot_breaks(s->degree_u, s->n_u, s->knots_u, s->u0, s->u1, bu, max_bu);
    int n_bv = sem_knot_breaks(s->degree_v, s->n_v, s->knots_v, s->v0, s->v1, bv, max_bv);
    if (trim) {
        n_bu = refine_for_trim(&bu, n_bu, nu);
        n_bv = n_bu < 0 ? -1 : refine_for_trim(&bv, n_bv, nv);
        if (n_bu < 0 || n_bv < 0) goto nomem;
    }
    size_t capacity = (size_t)(n_bu - 1) * (size_t)(n_bv - 1) * (size_t)nu * (size_t)nv;
    if (capacity > (size_t)INT_MAX / 4) {
        out->status = sem_error_set(&out->err, SEM_ERR_INVALID,
                                    "part %d: too many boundary samples (%zu)", index, capacity);
        goto done;
    }
    if (capacity == 0) capacity = 1;
    out->uv = malloc(2 * capacity * sizeof *out->uv);
    out->X = malloc(3 * capacity * sizeof *out->X);
    out->area = malloc(capacity * sizeof *out->area);
    out->seam = malloc(capacity * sizeof *out->seam);
    out->row_nnz = malloc(capacity * sizeof *out->row_nnz);
    out->col = malloc(capacity * (size_t)basis_max * sizeof *out->col);
    out->val = malloc(capacity * (size_t)basis_max * sizeof *out->val);
    if (!out->uv || !out->X || !out->area || !out->seam || !out->row_nnz || !out->col || !out->val) goto nomem;

    for (int b = 0; b + 1 < n_bv; ++b) {
        double v_mid = 0.5 * (bv[b] + bv[b + 1]), v_half = 0.5 * (bv[b + 1] - bv[b]);
        for (int a = 0; a + 1 < n_bu; ++a) {
            double u_mid = 0.5 * (bu[a] + bu[a + 1]), u_half = 0.5 * (bu[a + 1] - bu[a]);
            for (int l = 0; l < nv; ++l) {
                /* the ends exactly on the break values, not mid + half * (+-1) rounded */
                double v = l == 0 ? bv[b] : (l == nv - 1 ? bv[b + 1] : v_mid + v_half * xv[l]);
                for (int k = 0; k < nu; ++k) {
                    double u =
                        k == 0 ? bu[a] : (k == nu - 1 ? bu[a + 1] : u_mid + u_half * xu[k]);
                    if (trim) {
                        double ut = u + SEM_TRIM_NUDGE * (u_mid - u);
                        double vt = v + SEM_TRIM_NUDGE * (v_mid - v);
                        if (!sem_trim_region_inside(trim, ut, vt)) continue;
                    }
                    /* one rational basis row gives the point, its J row and the area
                     * element |S_u x S_v| */
                    int nb = sem_surface_basis(s, u, v, index_buf, phi, phi_u, phi_v);
                    int n = out->n;
                    double X[3] = {0.0, 0.0, 0.0}, Su[3] = {0.0, 0.0, 0.0}, Sv[3] = {0.0, 0.0, 0.0};
                    int kept = 0;
                    for (int r = 0; r < nb; ++r) {
                        const double *P = s->ctrl + 3 * (size_t)index_buf[r];
                        for (int c = 0; c < 3; ++c) {
                            Su[c] += phi_u[r] * P[c];
                            Sv[c] += phi_v[r] * P[c];
                        }
                        if (phi[r] == 0.0) continue;
                        X[0] += phi[r] * P[0];
                        X[1] += phi[r] * P[1];
                        X[2] += phi[r] * P[2];
                        out->col[out->nnz + (size_t)kept] = index_buf[r];
                        out->val[out->nnz + (size_t)kept] = phi[r];
                        ++kept;
                    }
                    double nrm[3] = {Su[1] * Sv[2] - Su[2] * Sv[1], Su[2] * Sv[0] - Su[0] * Sv[2],
                                     Su[0] * Sv[1] - Su[1] * Sv[0]};
                    double jac = sqrt(nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2]);
                    double area = wu[k] * wv[l] * u_half * v_half * jac;
                    if (!isfinite(area)) {
                        out->status = sem_error_set(
                            &out->err, SEM_ERR_NUMERIC,
                            "part %d: non-finite area element at (u,v) = (%g, %g)", index, u, v);
                        goto done;
                    }
                    out->nnz += (size_t)kept;
                    out->row_nnz[n] = kept;
                    out->uv[2 * n] = u;
                    out->uv[2 * n + 1] = v;
                    memcpy(out->X + 3 * (size_t)n, X, sizeof X);
                    out->area[n] = area;
                    /* the weight this sample would have, were the part one span across
                     * each side of its range it lies on */
                    double seam = 1.0;
                    if ((k == 0 && a == 0) || (k == nu - 1 && a == n_bu - 2))
                        seam *= (bu[n_bu - 1] - bu[0]) / (2.0 * u_half);
                    if ((l == 0 && b == 0) || (l == nv - 1 && b == n_bv - 2))
                        seam *= (bv[n_bv - 1] - bv[0]) / (2.0 * v_half);
                    out->seam[n] = area * seam;
                    out->n++;
                }
            }
        }
    }
    goto done;
nomem:
    out->status = sem_error_set(&out->err, SEM_ERR_NOMEM, "out of memory sampling part %d", index);
done:
    SEM_FREE_ALL(bu, bv, index_buf, phi);
    sem_trim_region_destroy(trim);
}

sem_status sem_step_sample(const sem_model *model, int threads, sem_discretization *d,
                           sem_error *err)
{
    if (!model || !d) return sem_error_set(err, SEM_ERR_INVALID, "sampling: null argument");
    if (model->n_parts <= 0)
        return sem_error_set(err, SEM_ERR_INVALID, "empty model: no parts to sample");
    const int n_parts = model->n_parts;
    size_t *offsets = malloc(((size_t)n_parts + 1) * sizeof *offsets);
    part_samples *parts = calloc((size_t)n_parts, sizeof *parts);
    int *ctrl_offset = malloc(((size_t)n_parts + 1) * sizeof *ctrl_offset);
    if (!offsets || !parts || !ctrl_offset) {
        free(offsets);
        free(parts);
        free(ctrl_offset);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_status st = SEM_OK;
    sem_model_part_offsets(model, offsets);
    if (offsets[n_parts] > (size_t)INT_MAX / 3) {
        st = sem_error_set(err, SEM_ERR_INVALID, "too many control points (%zu)",
                           offsets[n_parts]);
        free(offsets);
        free(parts);
        free(ctrl_offset);
        return st;
    }
    for (int i = 0; i <= n_parts; ++i) ctrl_offset[i] = (int)offsets[i];
    free(offsets);

    /* Threads only pay off beyond a few thousand samples: below that the fork/join (and,
     * on a busy machine, waiting for the second thread to be scheduled) costs more than the
     * work. The estimate counts spans from the control nets (an upper bound). */
    double work = 0.0;
    for (int i = 0; i < n_parts; ++i) {
        const sem_part *part = &model->parts[i];
        const sem_surface *s = &part->surface;
        double spans = (double)(s->n_u - s->degree_u) * (double)(s->n_v - s->degree_v);
        double points = (double)lobatto_points(s->degree_u) * lobatto_points(s->degree_v);
        int trimmed = part->has_outer || part->n_holes > 0;
        work += trimmed ? fmax(spans * points, SEM_TRIM_MIN_POINTS * SEM_TRIM_MIN_POINTS)
                        : spans * points;
    }
    const int parallel = work > 4000.0 && n_parts > 1;
#pragma omp parallel for schedule(dynamic, 1) num_threads(sem_threads(threads)) if (parallel)
    for (int i = 0; i < n_parts; ++i) sample_part(&model->parts[i], i, &parts[i]);

    /* first failure in part order, so the message does not depend on scheduling */
    size_t n_samples = 0, nnz = 0;
    double total_area = 0.0;
    for (int i = 0; i < n_parts && st == SEM_OK; ++i) {
        if (parts[i].status != SEM_OK) {
            st = parts[i].status;
            if (err) *err = parts[i].err;
            break;
        }
        n_samples += (size_t)parts[i].n;
        nnz += parts[i].nnz;
        for (int k = 0; k < parts[i].n; ++k) total_area += parts[i].area[k];
    }
    if (st == SEM_OK && (n_samples > (size_t)INT_MAX / 3 || nnz > (size_t)INT_MAX))
        st = sem_error_set(err, SEM_ERR_INVALID, "too many boundary samples (%zu)", n_samples);
    if (st == SEM_OK && !(total_area > 0.0))
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "empty model: the boundary samples have zero total area "
                           "(%zu samples; every part trimmed away or degenerate)",
                           n_samples);

    int *sample_part_idx = NULL;
    double *uv = NULL, *X = NULL, *area = NULL, *seam = NULL;
    sem_csr J;
    memset(&J, 0, sizeof J);
    if (st == SEM_OK) {
        size_t ns = n_samples ? n_samples : 1;
        sample_part_idx = malloc(ns * sizeof *sample_part_idx);
        uv = malloc(2 * ns * sizeof *uv);
        X = malloc(3 * ns * sizeof *X);
        area = malloc(ns * sizeof *area);
        seam = malloc(ns * sizeof *seam);
        if (!sample_part_idx || !uv || !X || !area || !seam ||
            sem_csr_alloc(&J, (int)n_samples, ctrl_offset[n_parts], nnz) != SEM_OK)
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    if (st == SEM_OK) {
        size_t s0 = 0, e0 = 0;
        for (int i = 0; i < n_parts; ++i) {
            const part_samples *p = &parts[i];
            size_t n = (size_t)p->n;
            if (n) {
                memcpy(uv + 2 * s0, p->uv, 2 * n * sizeof *uv);
                memcpy(X + 3 * s0, p->X, 3 * n * sizeof *X);
                memcpy(area + s0, p->area, n * sizeof *area);
                memcpy(seam + s0, p->seam, n * sizeof *seam);
            }
            for (size_t k = 0; k < n; ++k) {
                sample_part_idx[s0 + k] = i;
                J.row_start[s0 + k + 1] = J.row_start[s0 + k] + p->row_nnz[k];
            }
            for (size_t k = 0; k < p->nnz; ++k) {
                J.col[e0 + k] = ctrl_offset[i] + p->col[k];
                J.val[e0 + k] = p->val[k];
            }
            s0 += n;
            e0 += p->nnz;
        }
    }
    for (int i = 0; i < n_parts; ++i) part_samples_free(&parts[i]);
    free(parts);
    if (st != SEM_OK) {
        SEM_FREE_ALL(sample_part_idx, uv, X, area, seam, ctrl_offset);
        sem_csr_free(&J);
        return st;
    }
    d->n_parts = n_parts;
    d->n_ctrl = ctrl_offset[n_parts];
    d->part_ctrl_offset = ctrl_offset;
    d->n_samples = (int)n_samples;
    d->sample_part = sample_part_idx;
    d->sample_uv = uv;
    d->sample_X = X;
    d->sample_area = area;
    d->sample_seam = seam;
    d->J_hat = J;
    return SEM_OK;
}

int sem_samples_by_part(const sem_discretization *d, int **start, int **index)
{
    int np = d->n_parts;
    *start = calloc((size_t)np + 2, sizeof **start);
    *index = malloc(((size_t)d->n_samples + 1) * sizeof **index);
    if (!*start || !*index) {
        free(*start);
        free(*index);
        *start = *index = NULL;
        return 0;
    }
    int *st = *start;
    /* counts at i + 2, prefix sums shifted by one, then filling through st[i + 1] leaves
     * st[i] at part i's first sample */
    for (int s = 0; s < d->n_samples; ++s) st[d->sample_part[s] + 2]++;
    for (int i = 0; i < np; ++i) st[i + 2] += st[i + 1];
    for (int s = 0; s < d->n_samples; ++s) (*index)[st[d->sample_part[s] + 1]++] = s;
    return 1;
}
