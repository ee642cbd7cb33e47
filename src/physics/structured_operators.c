/*
 * structured_operators.c - an object's matrices as part-sparse terms plus products through
 * Pi (structured.h): the sample rows of the error matrix, P, coefficient-space Mz, Bb and Bz
 * (by part-pair blocks: a part's coefficients meet only those of the parts it shares a point or
 * a sample with, so a dense r0 x r0 matrix would be mostly zeros; NIST CTC-02 has 637 parts:
 * 325 MB each, scanned whole by every product), and the products with M, M_eps, K and K0 that
 * never form a q-space matrix (and Az, the material pins' anchor, pins.h).
 *
 * Products are summed in a fixed order whatever the thread count: P x by rows (one part's
 * rows per task), P^T y by groups (every control point is in one group, and a group sums its
 * parts in order), the sample residuals by samples, and their scatter serially.
 */
#include "structured.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "shared_kernels.h"
#include "util/free_all.h"

void sem_structured_free(sem_object *o)
{
    sem_structured_ops *s = o->ops;
    if (!s) return;
    SEM_FREE_ALL(s->p_start, s->p_col, s->p_val, s->area, s->j_start, s->j_col, s->j_val, s->g_start, s->g_idx,
                 s->g_val, s->nb_start, s->nb_part, s->Mz, s->Bb, s->Bz, s->Az);
    free(s);
    o->ops = NULL;
}

/* P from pi_dense: part i's rows over its group's control points (group order). */
static sem_status build_P(sem_object *o, sem_structured_ops *s, sem_error *err)
{
    int m = o->m, r0 = s->r0;
    s->p_start = malloc(((size_t)r0 + 1) * sizeof(int));
    if (!s->p_start) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    s->p_start[0] = 0;
    for (int i = 0; i < o->n_parts; ++i) {
        size_t n = sem_group_size(o, o->d->part_origin[i]);
        for (int k = 0; k < m; ++k) s->p_start[i * m + k + 1] = s->p_start[i * m + k] + (int)n;
    }
    size_t nnz = (size_t)s->p_start[r0];
    s->p_col = malloc((nnz + 1) * sizeof(int));
    s->p_val = malloc((nnz + 1) * sizeof(double));
    if (!s->p_col || !s->p_val) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for Pi");
    for (int i = 0; i < o->n_parts; ++i) {
        int g = o->d->part_origin[i];
        size_t n = sem_group_size(o, g);
        const int *ctrl = o->group_ctrl + o->group_start[g];
        for (int k = 0; k < m; ++k) {
            size_t at = (size_t)s->p_start[i * m + k];
            memcpy(s->p_col + at, ctrl, n * sizeof(int));
            memcpy(s->p_val + at, o->pi_dense[i] + (size_t)k * n, n * sizeof(double));
        }
    }
    return SEM_OK;
}

/* The sample rows (the error rows of sem_error_rows, then ties, then welds, then seam ties)
 * and Bb. */
static sem_status build_samples(sem_object *o, sem_structured_ops *s, int n_ties, const int *tie_ctrl,
                                const int *tie_part, double tie_weight, double weld_weight, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *J = &d->J_hat, *Ws = &d->W_samples;
    sem_error_row *rows = NULL;
    int n_err = 0;
    sem_status st = sem_error_rows(o, &rows, &n_err, err);
    if (st != SEM_OK) return st;
    int m = o->m, ns = n_err, nw = o->n_welds, nst = o->n_seam_ties, nr = ns + n_ties + nw + nst;
    int r_seam = ns + n_ties + nw; /* the seam ties' first row */
    s->n_rows = nr;
    s->area = malloc(((size_t)nr + 1) * sizeof(double));
    s->j_start = malloc(((size_t)nr + 1) * sizeof(int));
    s->g_start = malloc(((size_t)nr + 1) * sizeof(int));
    if (!s->area || !s->j_start || !s->g_start) {
        free(rows);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int t = 0; t < ns; ++t) s->area[t] = rows[t].weight;
    for (int t = 0; t < n_ties; ++t) s->area[ns + t] = tie_weight;
    for (int t = 0; t < nw; ++t) s->area[ns + n_ties + t] = weld_weight;
    for (int t = 0; t < nst; ++t) s->area[r_seam + t] = o->seam_tie_weight[t];
    s->j_start[0] = s->g_start[0] = 0;
    for (int t = 0; t < ns; ++t) {
        int r = rows[t].sample;
        int parts = rows[t].entry < 0 ? Ws->row_start[r + 1] - Ws->row_start[r] : 1;
        s->j_start[t + 1] = s->j_start[t] + (J->row_start[r + 1] - J->row_start[r]);
        s->g_start[t + 1] = s->g_start[t] + m * parts;
    }
    for (int t = 0; t < n_ties; ++t) {
        s->j_start[ns + t + 1] = s->j_start[ns + t] + 1;
        s->g_start[ns + t + 1] = s->g_start[ns + t] + m;
    }
    for (int t = ns + n_ties; t < r_seam; ++t) {
        s->j_start[t + 1] = s->j_start[t] + 2;
        s->g_start[t + 1] = s->g_start[t];
    }
    for (int t = 0; t < nst; ++t) {
        int e0, e1;
        seam_tie_row(o, t, &e0, &e1);
        s->j_start[r_seam + t + 1] = s->j_start[r_seam + t] + (e1 - e0);
        s->g_start[r_seam + t + 1] = s->g_start[r_seam + t];
    }
    size_t nj = (size_t)s->j_start[nr], ng = (size_t)s->g_start[nr];
    s->j_col = malloc((nj + 1) * sizeof(int));
    s->j_val = malloc((nj + 1) * sizeof(double));
    s->g_idx = malloc((ng + 1) * sizeof(int));
    s->g_val = malloc((ng + 1) * sizeof(double));
    if (!s->j_col || !s->j_val || !s->g_idx || !s->g_val) {
        free(rows);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the error matrix's samples");
    }
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int t = 0; t < ns; ++t) {
        int r = rows[t].sample;
        size_t len = (size_t)(J->row_start[r + 1] - J->row_start[r]);
        memcpy(s->j_col + s->j_start[t], J->col + J->row_start[r], len * sizeof(int));
        memcpy(s->j_val + s->j_start[t], J->val + J->row_start[r], len * sizeof(double));
        int at = s->g_start[t];
        int e0 = rows[t].entry < 0 ? Ws->row_start[r] : rows[t].entry;
        int e1 = rows[t].entry < 0 ? Ws->row_start[r + 1] : rows[t].entry + 1;
        for (int e = e0; e < e1; ++e) {
            int i = Ws->col[e];
            const double *X = d->sample_X + 3 * (size_t)r, *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
            double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, b[10];
            sem_polynomial_basis(d->order, dX, b, NULL);
            double w = rows[t].entry < 0 ? Ws->val[e] : 1.0;
            for (int k = 0; k < m; ++k) {
                s->g_idx[at] = i * m + k;
                s->g_val[at++] = w * b[k];
            }
        }
    }
    free(rows);
    for (int t = 0; t < n_ties; ++t) {
        int c = tie_ctrl[t], i = tie_part[t], r = ns + t;
        s->j_col[s->j_start[r]] = c;
        s->j_val[s->j_start[r]] = 1.0;
        const double *X = o->q0 + 3 * (size_t)c, *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
        double dX[3] = {X[0] - Xb[0], X[1] - Xb[1], X[2] - Xb[2]}, b[10];
        sem_polynomial_basis(d->order, dX, b, NULL);
        for (int k = 0; k < m; ++k) {
            s->g_idx[s->g_start[r] + k] = i * m + k;
            s->g_val[s->g_start[r] + k] = b[k];
        }
    }
    /* welds: the two points, ascending (rows of J are sorted) */
    for (int t = 0; t < nw; ++t) {
        int r = ns + n_ties + t, a = o->weld_ctrl[2 * t], b = o->weld_ctrl[2 * t + 1];
        int lo = a < b ? a : b, hi = a < b ? b : a;
        s->j_col[s->j_start[r]] = lo;
        s->j_val[s->j_start[r]] = lo == a ? 1.0 : -1.0;
        s->j_col[s->j_start[r] + 1] = hi;
        s->j_val[s->j_start[r] + 1] = hi == a ? 1.0 : -1.0;
    }
    /* seam ties (object_seam_ties.c): J_a - J_b, the two parts' points, ascending */
    for (int t = 0; t < nst; ++t) {
        int *col = s->j_col + s->j_start[r_seam + t];
        double *val = s->j_val + s->j_start[r_seam + t];
        int n = 0, e0, e1;
        seam_tie_row(o, t, &e0, &e1);
        for (int e = e0; e < e1; ++e, ++n) {
            int c = o->seams.row_ctrl[e];
            double v = seam_tie_value(o, t, e);
            int j = n;
            while (j > 0 && col[j - 1] > c) {
                col[j] = col[j - 1];
                val[j] = val[j - 1];
                --j;
            }
            col[j] = c;
            val[j] = v;
        }
    }
    return SEM_OK;
}

static int cmp_u64(const void *a, const void *b)
{
    unsigned long long x = *(const unsigned long long *)a, y = *(const unsigned long long *)b;
    return x < y ? -1 : x > y;
}

/* The part pairs of the block storage: the pairs of Mz and Bz (o->pair_a, pair_b) and every
 * pair of parts that meet in a sample row (Bb). */
static sem_status build_neighbours(const sem_object *o, sem_structured_ops *s, sem_error *err)
{
    int m = o->m, np = o->n_parts;
    size_t n_keys = (size_t)o->n_pairs;
    for (int r = 0; r < s->n_rows; ++r) {
        size_t k = (size_t)(s->g_start[r + 1] - s->g_start[r]) / (size_t)m;
        n_keys += k * k;
    }
    unsigned long long *keys = malloc((n_keys + 1) * sizeof *keys);
    s->nb_start = calloc((size_t)np + 1, sizeof(int));
    if (!keys || !s->nb_start) {
        free(keys);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    size_t nk = 0;
    for (int k = 0; k < o->n_pairs; ++k)
        keys[nk++] = (unsigned long long)o->pair_a[k] * (unsigned)np + (unsigned)o->pair_b[k];
    for (int r = 0; r < s->n_rows; ++r)
        for (int x = s->g_start[r]; x < s->g_start[r + 1]; x += m)
            for (int y = s->g_start[r]; y < s->g_start[r + 1]; y += m)
                keys[nk++] = (unsigned long long)(s->g_idx[x] / m) * (unsigned)np + (unsigned)(s->g_idx[y] / m);
    qsort(keys, nk, sizeof *keys, cmp_u64);
    size_t nu = 0;
    for (size_t k = 0; k < nk; ++k)
        if (nu == 0 || keys[k] != keys[nu - 1]) keys[nu++] = keys[k];
    s->nb_part = malloc((nu + 1) * sizeof(int));
    size_t nb = nu * (size_t)m * m;
    s->Mz = calloc(nb + 1, sizeof(double));
    s->Bb = calloc(nb + 1, sizeof(double));
    s->Bz = calloc(nb + 1, sizeof(double));
    if (o->pins) s->Az = calloc(nb + 1, sizeof(double));
    if (!s->nb_part || !s->Mz || !s->Bb || !s->Bz || (o->pins && !s->Az)) {
        free(keys);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the coefficient-space matrices");
    }
    for (size_t k = 0; k < nu; ++k) {
        s->nb_start[keys[k] / (unsigned)np + 1]++;
        s->nb_part[k] = (int)(keys[k] % (unsigned)np);
    }
    for (int a = 0; a < np; ++a) s->nb_start[a + 1] += s->nb_start[a];
    free(keys);
    return SEM_OK;
}

/* The block of pair (a, b) in the block storage D (the pair is always there). */
static double *block_of(const sem_structured_ops *s, double *D, int m, int a, int b)
{
    int lo = s->nb_start[a], hi = s->nb_start[a + 1] - 1;
    while (lo < hi) {
        int mid = (lo + hi) / 2;
        if (s->nb_part[mid] < b) lo = mid + 1;
        else hi = mid;
    }
    return D + (size_t)lo * m * m;
}

/* Mz, Bz, Az from the pair blocks (n_pairs x m x m, own bases), Bb = sum_s a_s g_s^T g_s
 * (samples in order: each entry sums as the dense matrix did). */
static void fill_blocks(const sem_object *o, sem_structured_ops *s, const double *Mz_pairs,
                        const double *Bz_pairs, const double *Az_pairs)
{
    int m = o->m;
    for (int k = 0; k < o->n_pairs; ++k) {
        int a = o->pair_a[k], b = o->pair_b[k];
        for (int t = 0; t < 3; ++t) {
            const double *src = t == 2 ? Az_pairs : t ? Bz_pairs : Mz_pairs;
            double *dst = t == 2 ? s->Az : t ? s->Bz : s->Mz;
            if (!src || !dst) continue;
            double *blk = block_of(s, dst, m, a, b);
            src += (size_t)k * m * m;
            for (int e = 0; e < m * m; ++e) blk[e] += src[e];
        }
    }
    for (int r = 0; r < s->n_rows; ++r)
        for (int x = s->g_start[r]; x < s->g_start[r + 1]; ++x) {
            double ax = s->area[r] * s->g_val[x];
            int a = s->g_idx[x] / m, xa = s->g_idx[x] % m;
            for (int y = s->g_start[r]; y < s->g_start[r + 1]; y += m) {
                double *blk = block_of(s, s->Bb, m, a, s->g_idx[y] / m) + (size_t)xa * m;
                for (int yy = y; yy < y + m; ++yy) blk[s->g_idx[yy] % m] += ax * s->g_val[yy];
            }
        }
}

sem_status sem_structured_init(sem_object *o, const double *Mz_pairs, const double *Bz_pairs,
                               const double *Az_pairs, int n_ties, const int *tie_ctrl, const int *tie_part,
                               double tie_weight, double weld_weight, sem_error *err)
{
    sem_structured_ops *s = calloc(1, sizeof *s);
    if (!s) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    o->ops = s;
    s->r0 = o->n_parts * o->m;
    sem_status st = build_P(o, s, err);
    if (st == SEM_OK) st = build_samples(o, s, n_ties, tie_ctrl, tie_part, tie_weight, weld_weight, err);
    if (st == SEM_OK) st = build_neighbours(o, s, err);
    if (st != SEM_OK) return st;
    fill_blocks(o, s, Mz_pairs, Bz_pairs, Az_pairs);
    o->K0z = malloc(((size_t)o->n_pairs * 9 * o->ma * o->ma + 1) * sizeof(double));
    if (!o->K0z)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the coefficient-space matrices");
    return SEM_OK;
}

/* yz = P x (r0 x 3, interleaved), x over all control points. */
static void apply_P(const sem_object *o, const double *x, double *yz)
{
    const sem_structured_ops *s = o->ops;
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int r = 0; r < s->r0; ++r) {
        double a0 = 0, a1 = 0, a2 = 0;
        for (int e = s->p_start[r]; e < s->p_start[r + 1]; ++e) {
            const double *xc = x + 3 * (size_t)s->p_col[e];
            double v = s->p_val[e];
            a0 += v * xc[0];
            a1 += v * xc[1];
            a2 += v * xc[2];
        }
        yz[3 * r + 0] = a0;
        yz[3 * r + 1] = a1;
        yz[3 * r + 2] = a2;
    }
}

/* y += P^T yz, group by group (a control point belongs to one group). */
static void apply_Pt(const sem_object *o, const double *yz, double *y)
{
    const sem_structured_ops *s = o->ops;
    int m = o->m;
#pragma omp parallel for schedule(dynamic, 1) num_threads(o->nthreads)
    for (int g = 0; g < o->n_groups; ++g)
        for (int i = 0; i < o->n_parts; ++i) {
            if (o->d->part_origin[i] != g) continue;
            for (int k = 0; k < m; ++k) {
                int r = i * m + k;
                const double *z = yz + 3 * (size_t)r;
                for (int e = s->p_start[r]; e < s->p_start[r + 1]; ++e) {
                    double *yc = y + 3 * (size_t)s->p_col[e];
                    double v = s->p_val[e];
                    yc[0] += v * z[0];
                    yc[1] += v * z[1];
                    yc[2] += v * z[2];
                }
            }
        }
}

/* out += c D yz for D (r0 x r0, part-pair blocks; the same for each coordinate). Columns in
 * ascending order, zeros skipped. */
static void dense_multiply(const sem_object *o, const double *D, double c, const double *yz, double *out)
{
    const sem_structured_ops *s = o->ops;
    int r0 = s->r0, m = o->m;
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int r = 0; r < r0; ++r) {
        int a = r / m, x = r % m;
        double a0 = 0, a1 = 0, a2 = 0;
        for (int e = s->nb_start[a]; e < s->nb_start[a + 1]; ++e) {
            const double *row = D + ((size_t)e * m + x) * m;
            int c0 = s->nb_part[e] * m;
            for (int y = 0; y < m; ++y) {
                double v = row[y];
                if (v == 0) continue;
                int c2 = c0 + y;
                a0 += v * yz[3 * c2 + 0];
                a1 += v * yz[3 * c2 + 1];
                a2 += v * yz[3 * c2 + 2];
            }
        }
        out[3 * r + 0] += c * a0;
        out[3 * r + 1] += c * a1;
        out[3 * r + 2] += c * a2;
    }
}

/* y += Kc x for Kc = cK K + cD K0 in the shared basis: z' = pi_shared x, per stored pair
 * (a <= b) out_a += Kc_ab z'_b and out_b += Kc_ab^T z'_a, then pi_shared^T out. */
void sem_structured_multiply(const sem_object *o, double cM, double cE, double cK, double cD, double cA,
                             const double *x, double *y)
{
    const sem_structured_ops *s = o->ops;
    int r0 = s->r0;
    memset(y, 0, 3 * (size_t)o->n_ctrl * sizeof(double));
    double *yz = calloc(6 * (size_t)r0 + 3 * (size_t)s->n_rows + 1, sizeof(double));
    if (!yz) return;
    double *oz = yz + 3 * (size_t)r0, *res = oz + 3 * (size_t)r0;
    apply_P(o, x, yz);
    if (cM != 0) dense_multiply(o, s->Mz, cM, yz, oz);
    if (cA != 0 && s->Az) dense_multiply(o, s->Az, cA, yz, oz);
    if (cE != 0) {
        double c = 2.0 * cE;
        dense_multiply(o, s->Bz, c, yz, oz);
        /* per sample: res_s = a_s (g_s P x - J_s x) */
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
        for (int r = 0; r < s->n_rows; ++r) {
            double a[3] = {0, 0, 0};
            for (int e = s->g_start[r]; e < s->g_start[r + 1]; ++e)
                for (int d = 0; d < 3; ++d) a[d] += s->g_val[e] * yz[3 * (size_t)s->g_idx[e] + d];
            for (int e = s->j_start[r]; e < s->j_start[r + 1]; ++e)
                for (int d = 0; d < 3; ++d) a[d] -= s->j_val[e] * x[3 * (size_t)s->j_col[e] + d];
            for (int d = 0; d < 3; ++d) res[3 * (size_t)r + d] = c * s->area[r] * a[d];
        }
        /* M_eps x = sum_s (g_s P - J_s)^T res_s: the g part in coefficient space (then P^T
         * below), the J part straight onto the control points; serial, in sample order */
        for (int r = 0; r < s->n_rows; ++r) {
            const double *rs = res + 3 * (size_t)r;
            for (int e = s->g_start[r]; e < s->g_start[r + 1]; ++e)
                for (int d = 0; d < 3; ++d) oz[3 * (size_t)s->g_idx[e] + d] += s->g_val[e] * rs[d];
            for (int e = s->j_start[r]; e < s->j_start[r + 1]; ++e)
                for (int d = 0; d < 3; ++d) y[3 * (size_t)s->j_col[e] + d] -= s->j_val[e] * rs[d];
        }
    }
    apply_Pt(o, oz, y);
    free(yz);
    if (cK != 0 || cD != 0) {
        double *work = malloc((2 * (size_t)o->n_parts * 3 * o->ma + 1) * sizeof(double));
        if (!work) return; /* unreachable in practice; the product is then incomplete */
        sem_stiffness_z_multiply(o, cK, o->Kz, cD, cD != 0 ? o->K0z : NULL, x, y, work);
        free(work);
    }
}

void sem_structured_own_basis(const sem_object *o, int a, int b, const double *Kz_ab, int transpose,
                              double *out)
{
    int m = o->m, ma = o->ma, n3 = 3 * ma, M3 = 3 * m;
    double Ta[100], Tb[100];
    const double *Xa = o->d->origin_X + 3 * (size_t)o->d->part_origin[a];
    const double *Xb = o->d->origin_X + 3 * (size_t)o->d->part_origin[b];
    double sa[3] = {o->ref_X[0] - Xa[0], o->ref_X[1] - Xa[1], o->ref_X[2] - Xa[2]};
    double sb[3] = {o->ref_X[0] - Xb[0], o->ref_X[1] - Xb[1], o->ref_X[2] - Xb[2]};
    sem_basis_shift(m, sa, Ta);
    sem_basis_shift(m, sb, Tb);
    /* R_i[p][k] = T_i[k][p + 1]: shared coefficient p (basis p + 1) from own coefficient k */
    double Y[27 * 30]; /* Y[(3p + d)][(3l + d')] = sum_p' Kz[(3p+d)][(d' ma + p')] R_b[p'][l] */
    for (int r = 0; r < n3; ++r)
        for (int l = 0; l < m; ++l)
            for (int d2 = 0; d2 < 3; ++d2) {
                double v = 0;
                for (int p2 = 0; p2 < ma; ++p2) v += Kz_ab[(size_t)r * n3 + d2 * ma + p2] * Tb[l * m + p2 + 1];
                Y[r * M3 + 3 * l + d2] = v;
            }
    for (int k = 0; k < m; ++k)
        for (int d = 0; d < 3; ++d)
            for (int c = 0; c < M3; ++c) {
                double v = 0;
                for (int p = 0; p < ma; ++p) v += Ta[k * m + p + 1] * Y[(3 * p + d) * M3 + c];
                if (transpose)
                    out[(size_t)c * M3 + 3 * k + d] = v;
                else
                    out[(size_t)(3 * k + d) * M3 + c] = v;
            }
}
