/*
 * mass_error.c - the constant matrices of an object: the mass matrix M with per-point
 * density (Eq. 14), the error matrix M_eps (Eq. 16) with the ties of orphan control points,
 * and the material pins' anchor A (pins.h), as group-pair blocks (object.h) and a CSR copy;
 * the error energy and products with the object's matrices.
 */
#include "assembly.h"
#include "pins.h"
#include "structured.h"
#include "util/free_all.h"

#include <cblas.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Per-point data in z-space: w * b at X_p - Xbar_i for each weight entry (mass), and the
 * point's part pairs. */
static sem_status setup_points(sem_object *o, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    size_t n_entries = sem_csr_nnz(W);
    int m = o->m;
    o->entry_basis = malloc((n_entries * (size_t)m + 1) * sizeof(double));
    o->entry_pair_offset = malloc(((size_t)o->n_quad + 1) * sizeof(int));
    if (!o->entry_basis || !o->entry_pair_offset)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    size_t n_pp = 0;
    o->entry_pair_offset[0] = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        size_t k = (size_t)(W->row_start[p + 1] - W->row_start[p]);
        n_pp += k * k;
        o->entry_pair_offset[p + 1] = (int)n_pp;
    }
    o->point_pairs = malloc((n_pp + 1) * sizeof(int));
    if (!o->point_pairs) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int p = 0; p < o->n_quad; ++p) {
        const double *X = d->quad_X + 3 * (size_t)p;
        int r0 = W->row_start[p], r1 = W->row_start[p + 1];
        int pp = o->entry_pair_offset[p];
        for (int r = r0; r < r1; ++r) {
            int i = W->col[r];
            const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
            double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]};
            double b[10];
            sem_polynomial_basis(o->d->order, dX, b, NULL);
            double w = W->val[r];
            for (int k = 0; k < m; ++k) o->entry_basis[(size_t)r * m + k] = w * b[k];
            for (int r2 = r0; r2 < r1; ++r2)
                o->point_pairs[pp++] = o->pair_lookup[(size_t)i * o->n_parts + W->col[r2]];
        }
    }
    return SEM_OK;
}

/* Adds Pi_a^T X Pi_b for a part pair into its group-pair block. X is m x m with leading
 * dimension ldx; block is |Ga| x |Gb| row-major; tmp has room for m x |Gb|. */
static void add_projected(const sem_object *o, int pa, int pb, const double *X, int ldx, double *block,
                          double *tmp)
{
    int m = o->m;
    int na = (int)sem_group_size(o, o->d->part_origin[pa]), nb = (int)sem_group_size(o, o->d->part_origin[pb]);
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, m, nb, m, 1.0, X, ldx, o->pi_dense[pb],
                nb, 0.0, tmp, nb);
    cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, na, nb, m, 1.0, o->pi_dense[pa], na, tmp,
                nb, 1.0, block, nb);
}

/* Bounds the elimination of one part's sample matrix (n w^2 / 2 multiply-adds, w its band):
 * 5e8 is half a second; larger parts keep the column test only (see find_orphans). */
#define UNSEEN_MAX_WORK 5e8
/* A column whose pivot is at most this fraction of its own weight is taken as dependent on
 * the columns before it: what the samples see of it, the others already show. */
#define UNSEEN_RELATIVE_PIVOT 1e-9

/* Part i's control points that its samples do not determine, by elimination of its sample
 * matrix S_i = sum_s a_s J_s^T J_s (a_s with the error rows' floor, as the solvers see it;
 * banded in the control net's order): column k is tied when its pivot, after the columns
 * before it and the ties so far, is at most UNSEEN_RELATIVE_PIVOT of its diagonal; a tie
 * adds its weight `mean` to the pivot, so S_i plus the ties is positive definite. (Exact
 * dependence leaves pivots at round-off, 1e-13 and below; on the shared models the smallest
 * pivot kept is 1.3e-4 of its diagonal.) Its samples are rows r0..r1-1 (sampling.c stores
 * them part by part). Marks them in tied[] (local indices; columns no sample sees are
 * marked already). Returns 0 when the part is too large to eliminate (its columns keep the
 * column test) or out of memory. */
static int part_unseen_points(const sem_object *o, int i, int r0, int r1, double mean,
                              double floor, unsigned char *tied)
{
    const sem_discretization *d = o->d;
    const sem_csr *J = &d->J_hat;
    int c0 = d->part_ctrl_offset[i], n = d->part_ctrl_offset[i + 1] - c0;
    /* the band: columns a sample couples are at most w apart */
    int w = 0;
    for (int r = r0; r < r1; ++r) {
        if (J->row_start[r + 1] == J->row_start[r]) continue;
        int lo = J->col[J->row_start[r]], hi = lo;
        for (int e = J->row_start[r]; e < J->row_start[r + 1]; ++e) {
            lo = J->col[e] < lo ? J->col[e] : lo;
            hi = J->col[e] > hi ? J->col[e] : hi;
        }
        w = hi - lo > w ? hi - lo : w;
    }
    if ((double)n * w * w / 2 > UNSEEN_MAX_WORK) return 0;
    size_t ld = (size_t)w + 1;
    double *B = calloc((size_t)n * ld + 1, sizeof *B); /* B[a ld + (b - a)], b >= a */
    if (!B) return 0;
    double *diag = malloc((size_t)n * sizeof *diag + 1);
    if (!diag) {
        free(B);
        return 0;
    }
    for (int r = r0; r < r1; ++r) {
        double a_s = fmax(d->sample_area[r], floor);
        for (int e = J->row_start[r]; e < J->row_start[r + 1]; ++e)
            for (int f = J->row_start[r]; f < J->row_start[r + 1]; ++f) {
                int a = J->col[e] - c0, b = J->col[f] - c0;
                if (b >= a) B[(size_t)a * ld + (size_t)(b - a)] += a_s * J->val[e] * J->val[f];
            }
    }
    for (int k = 0; k < n; ++k) diag[k] = B[(size_t)k * ld];
    for (int k = 0; k < n; ++k) {
        double *row = B + (size_t)k * ld;
        if (tied[k] || !(row[0] > UNSEEN_RELATIVE_PIVOT * diag[k])) {
            tied[k] = 1;
            row[0] += mean;
        }
        double l = sqrt(row[0]);
        int last = k + w < n - 1 ? k + w : n - 1;
        for (int j = k + 1; j <= last; ++j) row[j - k] /= l;
        for (int a = k + 1; a <= last; ++a) {
            double f = row[a - k];
            if (f == 0) continue;
            double *ra = B + (size_t)a * ld;
            for (int b = a; b <= last; ++b) ra[b - a] -= f * row[b - k];
        }
    }
    free(B);
    free(diag);
    return 1;
}

/* Control points that the boundary samples do not determine appear in no term of the
 * discretization, so the system would be singular. A column no sample sees (its basis
 * function is supported only where a trim removed the surface, or outside the parameter
 * range) is one; a part whose trim keeps a few samples where many basis functions overlap
 * (a face trimmed to a small region of a large span, far inside its surface) has more
 * columns than its samples can tell apart: those dependent columns are found by eliminating
 * each part's sample matrix (part_unseen_points). Each such point is tied to its own part's
 * polynomial at its rest position: residual q_c - b(X_c - Xbar)^T Pi_i Q, weighted like a
 * typical control point's error term (*mean). It vanishes for every affine motion (the
 * control points of an affinely mapped NURBS are affinely mapped), so the patch test is
 * unaffected; and it only adds to directions the samples hold, so it cannot make the
 * system singular. Lists them (control point, part) in order, and counts them per part in
 * o->part_tied (for the warning that names the parts). */
static sem_status find_orphans(sem_object *o, int **ctrl, int **part, int *n, double *mean,
                               sem_error *err)
{
    const sem_csr *J = &o->d->J_hat;
    *n = 0;
    *ctrl = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
    *part = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
    double *colw = calloc((size_t)o->n_ctrl + 1, sizeof(double));
    unsigned char *tied = calloc((size_t)o->n_ctrl + 1, 1);
    free(o->part_tied);
    o->part_tied = calloc((size_t)o->n_parts + 1, sizeof(int));
    if (!*ctrl || !*part || !colw || !tied || !o->part_tied) {
        free(colw);
        free(tied);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int r = 0; r < J->n_rows; ++r)
        for (int e = J->row_start[r]; e < J->row_start[r + 1]; ++e)
            colw[J->col[e]] += o->d->sample_area[r] * J->val[e] * J->val[e];
    double mn = 0;
    for (int c = 0; c < o->n_ctrl; ++c) mn += colw[c];
    mn /= o->n_ctrl > 0 ? o->n_ctrl : 1;
    for (int c = 0; c < o->n_ctrl; ++c) tied[c] = !(colw[c] > 1e-10 * mn);
    /* each part's sample rows (stored part by part); then the parts in parallel, each
     * writing its own columns of tied[] */
    int *row_start = calloc((size_t)o->n_parts + 2, sizeof(int));
    if (!row_start) {
        free(colw);
        free(tied);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int r = 0; r < J->n_rows; ++r) row_start[o->d->sample_part[r] + 1]++;
    for (int i = 0; i < o->n_parts; ++i) row_start[i + 1] += row_start[i];
    int ordered = 1;
    for (int r = 1; r < J->n_rows; ++r) ordered &= o->d->sample_part[r] >= o->d->sample_part[r - 1];
    double *floors = sem_error_part_floors(o->d, o->n_parts);
#pragma omp parallel for schedule(dynamic, 1) num_threads(o->nthreads)
    for (int i = 0; i < o->n_parts; ++i)
        if (ordered && floors)
            (void)part_unseen_points(o, i, row_start[i], row_start[i + 1], mn, floors[i],
                                     tied + o->d->part_ctrl_offset[i]);
    free(floors);
    free(row_start);
    for (int i = 0; i < o->n_parts; ++i)
        for (int c = o->d->part_ctrl_offset[i]; c < o->d->part_ctrl_offset[i + 1]; ++c) {
            if (!tied[c]) continue;
            (*ctrl)[*n] = c;
            (*part)[(*n)++] = i;
            o->part_tied[i]++;
        }
    *mean = mn;
    free(colw);
    free(tied);
    return SEM_OK;
}

/* Constant blocks: mass with per-point density, and the error matrix. */
static sem_status setup_constant_blocks(sem_object *o, sem_error *err)
{
    int m = o->m, np = o->n_pairs;
    double *Mz = calloc((size_t)np * m * m + 1, sizeof(double));
    if (!Mz) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    /* Volume consistency (sem_object_def.blend): per point with weights w_i summing to S,
     * sum_i w_i |u_i - ubar|^2 = sum_i w_i |u_i|^2 - (2 - S) |ubar|^2, u_i = b_i^T z_i,
     * ubar = sum_j w_j u_j; in z-space the pair block (a, b) is
     * s_p (delta_ab w_a b_a b_a^T - (2 - S) e_a e_b^T), e = w b (entry_basis). It joins the
     * error matrix divided by gamma, since the error energy is gamma q^T E q. */
    double blend = o->def.blend > 0 && o->d->alpha > 0 ? o->def.blend / (o->d->alpha * o->d->alpha) : 0;
    double *Bz = blend > 0 ? calloc((size_t)np * m * m + 1, sizeof(double)) : NULL;
    if (blend > 0 && !Bz) {
        free(Mz);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    /* the material pins' anchor: the mass matrix's form with k w_a for rho vol (pins.h) */
    double *Az = o->pins ? calloc((size_t)np * m * m + 1, sizeof(double)) : NULL;
    if (o->pins && !Az) {
        free(Mz);
        free(Bz);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    sem_pins_add_pair_blocks(o, Az);
    const sem_csr *W = &o->d->W;
    for (int p = 0; p < o->n_quad; ++p) {
        double rv = o->point_rho_vol[p];
        int r0 = W->row_start[p], r1 = W->row_start[p + 1];
        int pp = o->entry_pair_offset[p];
        double S = 0, sp = 0;
        if (Bz) {
            for (int a = r0; a < r1; ++a) S += W->val[a];
            sp = blend * o->point_material[p]->youngs_modulus * o->d->quad_volume[p] / o->gamma;
        }
        for (int a = r0; a < r1; ++a)
            for (int b = r0; b < r1; ++b) {
                size_t pair = (size_t)o->point_pairs[pp++];
                double *blk = Mz + pair * m * m;
                const double *ba = o->entry_basis + (size_t)a * m, *bb = o->entry_basis + (size_t)b * m;
                for (int k = 0; k < m; ++k)
                    for (int l = 0; l < m; ++l) blk[k * m + l] += rv * ba[k] * bb[l];
                if (!Bz) continue;
                double *bz = Bz + pair * m * m;
                double diag = a == b && W->val[a] > 0 ? sp / W->val[a] : 0, off = sp * (2.0 - S);
                for (int k = 0; k < m; ++k)
                    for (int l = 0; l < m; ++l) bz[k * m + l] += (diag - off) * ba[k] * bb[l];
            }
    }
    if (o->structured) {
        /* the pair blocks are the structured form's Mz, Bz and Az (structured.h) */
        int *tie_ctrl = NULL, *tie_part = NULL, n_ties = 0;
        double tie_weight = 0;
        sem_status st = find_orphans(o, &tie_ctrl, &tie_part, &n_ties, &tie_weight, err);
        if (st == SEM_OK)
            st = sem_structured_init(o, Mz, Bz, Az, n_ties, tie_ctrl, tie_part, tie_weight,
                                     SEM_WELD_STIFFNESS * tie_weight, err);
        o->n_orphans = n_ties;
        SEM_FREE_ALL(tie_ctrl, tie_part, Mz, Bz, Az);
        return st;
    }
    size_t mg = sem_max_group_size(o);
    double *tmp = malloc((size_t)m * mg * sizeof(double));
    if (Az) o->A_blocks = calloc(o->gpair_offset[o->n_gpairs] + 1, sizeof(double));
    if (!tmp || (Az && !o->A_blocks)) {
        SEM_FREE_ALL(tmp, Mz, Bz, Az);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int k = 0; k < np; ++k) {
        int g = o->part_pair_gpair[k];
        add_projected(o, o->pair_a[k], o->pair_b[k], Mz + (size_t)k * m * m, m,
                      o->M_blocks + o->gpair_offset[g], tmp);
        if (Bz)
            add_projected(o, o->pair_a[k], o->pair_b[k], Bz + (size_t)k * m * m, m,
                          o->E_blocks + o->gpair_offset[g], tmp);
        if (Az)
            add_projected(o, o->pair_a[k], o->pair_b[k], Az + (size_t)k * m * m, m,
                          o->A_blocks + o->gpair_offset[g], tmp);
    }
    SEM_FREE_ALL(tmp, Mz, Bz, Az);
    /* the orphan control points' ties (find_orphans) */
    {
        int *tie_ctrl = NULL, *tie_part = NULL, n_ties = 0;
        double mean = 0;
        double *row = malloc(mg * sizeof(double) + 1);
        sem_status st = row ? find_orphans(o, &tie_ctrl, &tie_part, &n_ties, &mean, err)
                            : sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        if (st != SEM_OK) {
            free(row);
            free(tie_ctrl);
            free(tie_part);
            return st;
        }
        o->n_orphans = 0;
        for (int t = 0; t < n_ties; ++t) {
            int c = tie_ctrl[t], i = tie_part[t];
            int g = o->d->part_origin[i];
            size_t n = sem_group_size(o, g);
            int gp = o->gpair_lookup[(size_t)g * o->n_groups + g];
            if (gp < 0) continue;
            const double *X = o->q0 + 3 * (size_t)c, *Xb = o->d->origin_X + 3 * (size_t)g;
            double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, b[10];
            sem_polynomial_basis(o->d->order, dX, b, NULL);
            for (size_t l = 0; l < n; ++l) {
                double v = 0;
                for (int k = 0; k < m; ++k) v += b[k] * o->pi_dense[i][(size_t)k * n + l];
                row[l] = -v;
            }
            row[o->ctrl_local[c]] += 1.0;
            double *blk = o->E_blocks + o->gpair_offset[gp];
            for (size_t a = 0; a < n; ++a)
                if (row[a] != 0)
                    for (size_t bb = 0; bb < n; ++bb) blk[a * n + bb] += mean * row[a] * row[bb];
            o->n_orphans++;
        }
        free(row);
        free(tie_ctrl);
        free(tie_part);
        /* the welds' ties (object_welds.c): rows e_a - e_b */
        double wgt = SEM_WELD_STIFFNESS * mean;
        for (int k = 0; k < o->n_welds; ++k) {
            const int cc[2] = {o->weld_ctrl[2 * k], o->weld_ctrl[2 * k + 1]};
            for (int x = 0; x < 2; ++x)
                for (int y = 0; y < 2; ++y) {
                    int gx = o->ctrl_group[cc[x]], gy = o->ctrl_group[cc[y]];
                    int gp = o->gpair_lookup[(size_t)gx * o->n_groups + gy];
                    size_t nb = sem_group_size(o, gy);
                    o->E_blocks[o->gpair_offset[gp] + (size_t)o->ctrl_local[cc[x]] * nb + (size_t)o->ctrl_local[cc[y]]] +=
                        x == y ? wgt : -wgt;
                }
        }
    }
    /* the seam ties (object_seam_ties.c): rows J_a - J_b */
    for (int t = 0; t < o->n_seam_ties; ++t) {
        int e0, e1;
        seam_tie_row(o, t, &e0, &e1);
        double wgt = o->seam_tie_weight[t];
        for (int x = e0; x < e1; ++x) {
            double vx = seam_tie_value(o, t, x);
            int cx = o->seams.row_ctrl[x], gx = o->ctrl_group[cx];
            for (int y = e0; y < e1; ++y) {
                double vy = seam_tie_value(o, t, y);
                int cy = o->seams.row_ctrl[y], gy = o->ctrl_group[cy];
                int gp = o->gpair_lookup[(size_t)gx * o->n_groups + gy];
                size_t nb = sem_group_size(o, gy);
                o->E_blocks[o->gpair_offset[gp] + (size_t)o->ctrl_local[cx] * nb + (size_t)o->ctrl_local[cy]] +=
                    wgt * vx * vy;
            }
        }
    }
    /* Error matrix (Eq. 16) as a sum of outer products of its rows' residuals r (Gamma_s - J_s,
     * or P_i(X_s) Pi_i - J_s on a split seam: sem_error_rows), so it is positive
     * semi-definite by construction. The factored form Pi^T(...)Pi - ... + J^T A J cancels
     * large terms, and its round-off can leave small negative eigenvalues exactly in the
     * directions the mass matrix does not see (M has rank at most the number of quadrature
     * points per coordinate), which makes M + h^2 (K + 2 gamma M_eps) indefinite. */
    {
        const sem_csr *G = &o->d->Gamma_samples, *J = &o->d->J_hat;
        sem_error_row *rows = NULL;
        int n_rows = 0;
        int *rc = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
        double *rv = malloc(((size_t)o->n_ctrl + 1) * sizeof(double));
        int *slot = malloc(((size_t)o->n_ctrl + 1) * sizeof(int));
        sem_status st = rc && rv && slot ? sem_error_rows(o, &rows, &n_rows, err)
                                         : sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        if (st != SEM_OK) {
            free(rc);
            free(rv);
            free(slot);
            return st;
        }
        for (int c = 0; c < o->n_ctrl; ++c) slot[c] = -1;
        for (int t = 0; t < n_rows && st == SEM_OK; ++t) {
            int r = rows[t].sample, n = 0;
            if (rows[t].entry < 0) {
                /* merge the sorted rows of Gamma_s and J_s */
                int a = G->row_start[r], ae = G->row_start[r + 1], b = J->row_start[r], be = J->row_start[r + 1];
                while (a < ae || b < be) {
                    if (b >= be || (a < ae && G->col[a] < J->col[b])) {
                        rc[n] = G->col[a];
                        rv[n++] = G->val[a++];
                    } else if (a >= ae || J->col[b] < G->col[a]) {
                        rc[n] = J->col[b];
                        rv[n++] = -J->val[b++];
                    } else {
                        rc[n] = G->col[a];
                        rv[n++] = G->val[a++] - J->val[b++];
                    }
                }
            } else {
                /* part i's polynomial at the sample, b(X - Xbar)^T Pi_i over its group, minus J_s */
                int i = o->d->W_samples.col[rows[t].entry], g = o->d->part_origin[i];
                size_t ng = sem_group_size(o, g);
                const int *gc = o->group_ctrl + o->group_start[g];
                const double *X = o->d->sample_X + 3 * (size_t)r, *Xb = o->d->origin_X + 3 * (size_t)g;
                double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, bs[10];
                sem_polynomial_basis(o->d->order, dX, bs, NULL);
                for (size_t l = 0; l < ng; ++l) {
                    double v = 0;
                    for (int k = 0; k < m; ++k) v += bs[k] * o->pi_dense[i][(size_t)k * ng + l];
                    slot[gc[l]] = n;
                    rc[n] = gc[l];
                    rv[n++] = v;
                }
                for (int e = J->row_start[r]; e < J->row_start[r + 1]; ++e) {
                    int c = J->col[e];
                    if (slot[c] >= 0) {
                        rv[slot[c]] -= J->val[e];
                    } else {
                        rc[n] = c;
                        rv[n++] = -J->val[e];
                    }
                }
                for (size_t l = 0; l < ng; ++l) slot[gc[l]] = -1;
            }
            double area = rows[t].weight;
            for (int x = 0; x < n && st == SEM_OK; ++x) {
                int gx = o->ctrl_group[rc[x]];
                double ax = area * rv[x];
                if (ax == 0) continue;
                for (int y = 0; y < n; ++y) {
                    int gy = o->ctrl_group[rc[y]];
                    int gp = o->gpair_lookup[(size_t)gx * o->n_groups + gy];
                    if (gp < 0) {
                        st = sem_error_set(err, SEM_ERR_INVALID, "error matrix pattern outside the system pattern");
                        break;
                    }
                    size_t nb = sem_group_size(o, gy);
                    o->E_blocks[o->gpair_offset[gp] + (size_t)o->ctrl_local[rc[x]] * nb + (size_t)o->ctrl_local[rc[y]]] +=
                        ax * rv[y];
                }
            }
        }
        SEM_FREE_ALL(rows, rc, rv, slot);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

/* M and E_blocks as CSR rows over control points, for products with them alone (the
 * right-hand side and the error force of every step) run in parallel by rows. */
static sem_status setup_constant_csr(sem_object *o, sem_error *err)
{
    int nc = o->n_ctrl;
    o->me_start = calloc((size_t)nc + 1, sizeof(int));
    if (!o->me_start) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], nb = (int)sem_group_size(o, o->gpair_b[g]);
        for (int x = o->group_start[ga]; x < o->group_start[ga + 1]; ++x) o->me_start[o->group_ctrl[x] + 1] += nb;
    }
    for (int c = 0; c < nc; ++c) o->me_start[c + 1] += o->me_start[c];
    size_t nnz = (size_t)o->me_start[nc];
    o->me_col = malloc((nnz + 1) * sizeof(int));
    o->me_M = malloc((nnz + 1) * sizeof(double));
    o->me_E = malloc((nnz + 1) * sizeof(double));
    int *fill = malloc(((size_t)nc + 1) * sizeof(int));
    if (!o->me_col || !o->me_M || !o->me_E || !fill) {
        free(fill);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    memcpy(fill, o->me_start, (size_t)nc * sizeof(int));
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], gb = o->gpair_b[g];
        size_t na = sem_group_size(o, ga), nb = sem_group_size(o, gb), off = o->gpair_offset[g];
        const int *ca = o->group_ctrl + o->group_start[ga], *cb = o->group_ctrl + o->group_start[gb];
        for (size_t la = 0; la < na; ++la)
            for (size_t lb = 0; lb < nb; ++lb) {
                int k = fill[ca[la]]++;
                o->me_col[k] = cb[lb];
                o->me_M[k] = o->M_blocks[off + la * nb + lb];
                o->me_E[k] = o->E_blocks[off + la * nb + lb];
            }
    }
    free(fill);
    return SEM_OK;
}

sem_status sem_mass_error_init(sem_object *o, sem_error *err)
{
    sem_status st = setup_points(o, err);
    if (st == SEM_OK) st = setup_constant_blocks(o, err);
    if (st == SEM_OK && !o->structured) st = setup_constant_csr(o, err);
    return st;
}

static void q_space_multiply(const sem_object *o, double cM, double cE, double cK, double cD, const double *x,
                             double *y);

/* The error energy is gamma u^T M_eps u of the displacement u = q - q0 (centred, since M_eps
 * ignores translations): the same as gamma q^T M_eps q wherever M_eps q0 = 0 (Eq. 16, the blend
 * and the orphan ties vanish at rest, being exact for affine motion), and the true energy of
 * the rows that are not zero at rest - a seam tie across a CAD gap (object_seam_ties.c), a weld
 * of points 1e-9 of the size apart - which hold their rest offset. Displacements rather than
 * positions also keep the sum free of the cancellation of large coordinates. */
double sem_error_energy(sem_object *o, const double *q, double *grad)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    const double *u = sem_centered(o, q, o->q0);
    sem_blocks_multiply(o, 0, o->gamma, 0, 0, 0, u, grad);
    double e = 0;
    for (size_t i = 0; i < n; ++i) e += 0.5 * u[i] * grad[i];
    return e;
}

void sem_blocks_multiply(const sem_object *o, double cM, double cE, double cK, double cD, double cA,
                         const double *x, double *y)
{
    if (o->structured) {
        sem_structured_multiply(o, cM, cE, cK, cD, cA, x, y);
        return;
    }
    q_space_multiply(o, cM, cE, cK, cD, x, y);
    /* the pins' anchor through its few points (pins.c), not its blocks */
    sem_pins_multiply(o, cA, x, y);
}

/* y = (cM M + 2 cE M_eps + cK K + cD K0) x from the q-space blocks. */
static void q_space_multiply(const sem_object *o, double cM, double cE, double cK, double cD, const double *x,
                             double *y)
{
    if (cK == 0 && cD == 0) {
        /* mass and error matrix only: by rows in parallel */
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
        for (int c = 0; c < o->n_ctrl; ++c) {
            double y0 = 0, y1 = 0, y2 = 0;
            for (int k = o->me_start[c]; k < o->me_start[c + 1]; ++k) {
                double v = cM * o->me_M[k] + 2.0 * cE * o->me_E[k];
                const double *xb = x + 3 * (size_t)o->me_col[k];
                y0 += v * xb[0];
                y1 += v * xb[1];
                y2 += v * xb[2];
            }
            y[3 * (size_t)c + 0] = y0;
            y[3 * (size_t)c + 1] = y1;
            y[3 * (size_t)c + 2] = y2;
        }
        return;
    }
    memset(y, 0, 3 * (size_t)o->n_ctrl * sizeof(double));
    for (int g = 0; g < o->n_gpairs; ++g) {
        int ga = o->gpair_a[g], gb = o->gpair_b[g];
        size_t na = sem_group_size(o, ga), nb = sem_group_size(o, gb);
        size_t off = o->gpair_offset[g];
        const int *ca = o->group_ctrl + o->group_start[ga], *cb = o->group_ctrl + o->group_start[gb];
        for (size_t la = 0; la < na; ++la) {
            double *ya = y + 3 * (size_t)ca[la];
            for (size_t lb = 0; lb < nb; ++lb) {
                const double *xb = x + 3 * (size_t)cb[lb];
                size_t e = la * nb + lb;
                double s = cM * o->M_blocks[off + e] + 2.0 * cE * o->E_blocks[off + e];
                for (int d = 0; d < 3; ++d) ya[d] += s * xb[d];
                if ((cK != 0 || cD != 0) && ga <= gb) {
                    /* K is kept for ga <= gb; block (gb, ga) is its transpose */
                    const double *xa = x + 3 * (size_t)ca[la];
                    double *yb = y + 3 * (size_t)cb[lb];
                    for (int d1 = 0; d1 < 3; ++d1)
                        for (int d2 = 0; d2 < 3; ++d2) {
                            size_t idx = 9 * off + (la * 9 + (size_t)(d1 * 3 + d2)) * nb + lb;
                            double k = cK * o->K_blocks[idx] + cD * o->K0_blocks[idx];
                            ya[d1] += k * xb[d2];
                            if (ga < gb) yb[d2] += k * xa[d1];
                        }
                }
            }
        }
    }
}
