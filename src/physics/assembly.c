/*
 * assembly.c - the elastic energy (Eq. 15), its gradient and its Hessian blocks K_q, formed
 * in the three stages described in assembly.h: per quadrature point, per part pair (in one
 * polynomial basis shared by all parts), per group pair.
 */
#include "assembly.h"

#include <cblas.h>
#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

/* Points per assembly chunk when the world's settings give none. */
#define DEFAULT_ASSEMBLY_CHUNK 8192

/* The stiffness in one shared basis. With Eq. 15, a part's contribution to F at point p
 * is w_i (grad b(X_p - Xbar_i))^T z_i = w_i (grad b(X_p - ref))^T (T_i^T z_i): every part
 * at p shares the point's D_p = grad b(X_p - ref), so a part pair's block is
 *   Kz_ab = sum_p w_a w_b N_p,   N_p = vol_p D_p^T (d2psi/dF2) D_p (per coordinate pair),
 * N_p is computed once per point (not once per part pair), and Kz_ab = Kz_ba is symmetric.
 * The change of basis goes into Pi: pi_shared_i = T_i^T Pi_i. The constant basis function
 * has no gradient, so only rows 1..m-1 take part. */
static sem_status setup_stiffness(sem_object *o, int assembly_chunk, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    int m = o->m, ma = m - 1;
    o->ma = ma;
    /* the shared origin: the volume centroid (keeps the monomials small) */
    double vsum = 0;
    for (int k = 0; k < 3; ++k) o->ref_X[k] = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        double v = d->quad_volume[p];
        vsum += v;
        for (int k = 0; k < 3; ++k) o->ref_X[k] += v * d->quad_X[3 * (size_t)p + k];
    }
    for (int k = 0; k < 3; ++k) o->ref_X[k] = vsum > 0 ? o->ref_X[k] / vsum : 0;
    o->pi_shared = calloc((size_t)(o->n_parts > 0 ? o->n_parts : 1), sizeof(double *));
    if (!o->pi_shared) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < o->n_parts; ++i) {
        const double *Xb = d->origin_X + 3 * (size_t)d->part_origin[i];
        double sh[3] = {o->ref_X[0] - Xb[0], o->ref_X[1] - Xb[1], o->ref_X[2] - Xb[2]}, T[100];
        sem_basis_shift(m, sh, T);
        size_t n = sem_group_size(o, d->part_origin[i]);
        double *ps = o->pi_shared[i] = calloc((size_t)ma * n + 1, sizeof(double));
        if (!ps) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int l = 1; l < m; ++l)
            for (int k = 0; k < m; ++k) {
                double t = T[k * m + l];
                if (t == 0) continue;
                const double *src = o->pi_dense[i] + (size_t)k * n;
                double *dst = ps + (size_t)(l - 1) * n;
                for (size_t j = 0; j < n; ++j) dst[j] += t * src[j];
            }
    }
    o->point_D = malloc(((size_t)o->n_quad * ma * 3 + 1) * sizeof(double));
    if (!o->point_D) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int p = 0; p < o->n_quad; ++p) {
        const double *X = d->quad_X + 3 * (size_t)p;
        double y[3] = {X[0] - o->ref_X[0], X[1] - o->ref_X[1], X[2] - o->ref_X[2]}, db[30];
        sem_polynomial_basis(o->d->order, y, NULL, db);
        double *D = o->point_D + (size_t)p * ma * 3;
        for (int k = 1; k < m; ++k)
            for (int e = 0; e < 3; ++e) D[(k - 1) * 3 + e] = db[e * m + k];
    }
    /* the points of each upper part pair, in point order, with w_a w_b */
    o->plist_start = calloc((size_t)o->n_pairs + 1, sizeof(int));
    o->plist_cursor = malloc(((size_t)o->n_pairs + 1) * sizeof(int));
    if (!o->plist_start || !o->plist_cursor) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int p = 0; p < o->n_quad; ++p)
        for (int r = W->row_start[p]; r < W->row_start[p + 1]; ++r)
            for (int r2 = r; r2 < W->row_start[p + 1]; ++r2)
                o->plist_start[o->pair_lookup[(size_t)W->col[r] * o->n_parts + W->col[r2]] + 1]++;
    for (int k = 0; k < o->n_pairs; ++k) o->plist_start[k + 1] += o->plist_start[k];
    size_t nl = (size_t)o->plist_start[o->n_pairs];
    o->plist_point = malloc((nl + 1) * sizeof(int));
    o->plist_w = malloc((nl + 1) * sizeof(double));
    if (!o->plist_point || !o->plist_w) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    memcpy(o->plist_cursor, o->plist_start, (size_t)o->n_pairs * sizeof(int));
    for (int p = 0; p < o->n_quad; ++p)
        for (int r = W->row_start[p]; r < W->row_start[p + 1]; ++r)
            for (int r2 = r; r2 < W->row_start[p + 1]; ++r2) {
                int pr = o->pair_lookup[(size_t)W->col[r] * o->n_parts + W->col[r2]];
                o->plist_point[o->plist_cursor[pr]] = p;
                o->plist_w[o->plist_cursor[pr]++] = W->val[r] * W->val[r2];
            }
    int n3 = 3 * ma;
    o->n_packed = n3 * (n3 + 1) / 2;
    /* points are assembled in chunks so that N stays small (25 MB at most) */
    o->chunk = o->n_quad < assembly_chunk ? (o->n_quad > 0 ? o->n_quad : 1) : assembly_chunk;
    o->N_chunk = malloc(((size_t)o->chunk * o->n_packed + 1) * sizeof(double));
    o->Kz = malloc(((size_t)o->n_pairs * n3 * n3 + 1) * sizeof(double));
    o->Kz_packed = o->chunk < o->n_quad
                       ? malloc(((size_t)o->n_pairs * o->n_packed + 1) * sizeof(double))
                       : calloc(1, sizeof(double));
    if (!o->N_chunk || !o->Kz || !o->Kz_packed)
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory for the stiffness blocks");
    return SEM_OK;
}

sem_status sem_assembly_init(sem_object *o, int assembly_chunk, sem_error *err)
{
    return setup_stiffness(o, assembly_chunk > 0 ? assembly_chunk : DEFAULT_ASSEMBLY_CHUNK, err);
}

/* The kernels below are element-wise (no reordered sums, and ISO C mode keeps the compiler
 * from contracting to FMA), so every clone gives the same bits. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__) && defined(__linux__) && \
    !defined(SEM_NO_CLONES)
#define SEM_VECTOR_CLONES __attribute__((target_clones("avx512f", "avx2", "default")))
#else
#define SEM_VECTOR_CLONES
#endif

/* One point's N = vol D^T (d2psi/dF2) D, rows and columns (d, k) (coordinate d, basis
 * function k = 1..ma), as the packed upper triangle (row by row) of the 3ma x 3ma matrix:
 * N[(d,k),(d',k')] = vol sum_{e,e'} D[k][e] H[(d,e),(d',e')] D[k'][e']. */
SEM_VECTOR_CLONES
static void point_stiffness(int ma, double vol, const double *H, const double *D, double *N)
{
    int n3 = 3 * ma;
    double HD[9 * 27]; /* HD[(d,e)][(d',k')] = sum_e' H[(d,e),(d',e')] D[k'][e'] */
    for (int de = 0; de < 9; ++de)
        for (int d2 = 0; d2 < 3; ++d2) {
            const double *h = H + de * 9 + d2 * 3;
            for (int k2 = 0; k2 < ma; ++k2)
                HD[de * n3 + d2 * ma + k2] = h[0] * D[k2 * 3 + 0] + h[1] * D[k2 * 3 + 1] + h[2] * D[k2 * 3 + 2];
        }
    int idx = 0;
    for (int d1 = 0; d1 < 3; ++d1)
        for (int k1 = 0; k1 < ma; ++k1) {
            double a0 = vol * D[k1 * 3 + 0], a1 = vol * D[k1 * 3 + 1], a2 = vol * D[k1 * 3 + 2];
            const double *h0 = HD + (d1 * 3 + 0) * n3, *h1 = HD + (d1 * 3 + 1) * n3, *h2 = HD + (d1 * 3 + 2) * n3;
            for (int j = d1 * ma + k1; j < n3; ++j) N[idx++] = a0 * h0[j] + a1 * h1[j] + a2 * h2[j];
        }
}

/* acc += sum over the pair's entries [e0, e1) of w_e N_{point e} (points from c0 on). */
SEM_VECTOR_CLONES
static void pair_sum(int np, const int *point, const double *w, int e0, int e1, int c0,
                     const double *N, double *acc)
{
    for (int e = e0; e < e1; ++e) {
        const double *n = N + (size_t)(point[e] - c0) * np;
        double we = w[e];
        for (int x = 0; x < np; ++x) acc[x] += we * n[x];
    }
}

/* Kz from the chunk [c0, c1)'s N_p (in N_chunk), added per upper part pair, each pair
 * summed by one thread in point order (deterministic for any thread count). Called by every
 * thread of a parallel region, chunk after chunk from c0 = 0. */
static void pair_sums(sem_object *o, int c0, int c1)
{
    int ma = o->ma, n3 = 3 * ma, np = o->n_packed;
    size_t bs = (size_t)n3 * n3;
    int first = c0 == 0, last = c1 == o->n_quad;
#pragma omp for schedule(dynamic, 8)
    for (int pr = 0; pr < o->n_pairs; ++pr) {
        if (!sem_pair_has_points(o, pr)) continue;
        double acc[378];
        if (first) {
            memset(acc, 0, (size_t)np * sizeof(double));
            o->plist_cursor[pr] = o->plist_start[pr];
        } else {
            memcpy(acc, o->Kz_packed + (size_t)pr * np, (size_t)np * sizeof(double));
        }
        int e0 = o->plist_cursor[pr], e1 = e0, end = o->plist_start[pr + 1];
        while (e1 < end && o->plist_point[e1] < c1) e1++;
        pair_sum(np, o->plist_point, o->plist_w, e0, e1, c0, o->N_chunk, acc);
        o->plist_cursor[pr] = e1;
        if (!last) {
            memcpy(o->Kz_packed + (size_t)pr * np, acc, (size_t)np * sizeof(double));
            continue;
        }
        /* full matrix, rows (k, d), columns (d', k') (see the projection below) */
        double *K = o->Kz + (size_t)pr * bs;
        int idx = 0;
        for (int i = 0; i < n3; ++i) {
            int ri = (i % ma) * 3 + i / ma;
            for (int j = i; j < n3; ++j) {
                int rj = (j % ma) * 3 + j / ma;
                K[ri * n3 + j] = K[rj * n3 + i] = acc[idx++];
            }
        }
    }
}

void sem_assemble_kz_from_points(sem_object *o)
{
    int ma = o->ma, np = o->n_packed;
#pragma omp parallel num_threads(o->nthreads)
    {
        for (int c0 = 0; c0 < o->n_quad; c0 += o->chunk) {
            int c1 = o->n_quad - c0 > o->chunk ? c0 + o->chunk : o->n_quad;
#pragma omp for schedule(static)
            for (int p = c0; p < c1; ++p)
                point_stiffness(ma, o->d->quad_volume[p], o->point_H + (size_t)p * 81,
                                o->point_D + (size_t)p * ma * 3, o->N_chunk + (size_t)(p - c0) * np);
            pair_sums(o, c0, c1);
        }
    }
}

double sem_point_hessian_change(const sem_object *o)
{
    double dn = 0, rn = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        const double *H = o->point_H + (size_t)p * 81, *H0 = o->point_H0 + (size_t)p * 81;
        double vol = o->d->quad_volume[p], a = 0, b = 0;
        for (int i = 0; i < 81; ++i) {
            double e = H[i] - H0[i];
            a += e * e;
            b += H0[i] * H0[i];
        }
        dn += vol * a;
        rn += vol * b;
    }
    return rn > 0 ? sqrt(dn / rn) : (dn > 0 ? INFINITY : 0.0);
}

void sem_point_hessian_multiply(const sem_object *o, double c, int minus_rest, const double *x, double *y,
                                double *work)
{
    const sem_csr *W = &o->d->W;
    int ma = o->ma, n3 = 3 * ma;
    size_t nz = (size_t)o->n_parts * n3;
    double *z = work, *share = work + nz;
    sem_shared_coefficients(o, x, z);
    const int block = (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES) > 0
                          ? (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES)
                          : 1;
    memset(share, 0, (size_t)GRADIENT_SHARES * nz * sizeof(double));
    /* per point: dF = B_p x, dP = (H_p - H0_p) dF, back through B_p^T into the part
     * coefficients, in the fixed point blocks of the gradient (assembly.h) */
#pragma omp parallel for schedule(static) num_threads(o->nthreads)
    for (int sh = 0; sh < GRADIENT_SHARES; ++sh) {
        double *out = share + (size_t)sh * nz;
        for (int p = sh * block; p < o->n_quad; p += GRADIENT_SHARES * block) {
            int pe = p + block < o->n_quad ? p + block : o->n_quad;
            for (int q = p; q < pe; ++q) {
                int r0 = W->row_start[q], r1 = W->row_start[q + 1];
                const double *D = o->point_D + (size_t)q * ma * 3;
                const double *H = o->point_H + (size_t)q * 81, *H0 = o->point_H0 + (size_t)q * 81;
                double zb[27] = {0};
                for (int r = r0; r < r1; ++r) {
                    const double *zi = z + (size_t)W->col[r] * n3;
                    double w = W->val[r];
                    for (int t = 0; t < n3; ++t) zb[t] += w * zi[t];
                }
                double dF[9], dP[9], v[27];
                for (int dd = 0; dd < 3; ++dd)
                    for (int e = 0; e < 3; ++e) {
                        double f = 0;
                        for (int k = 0; k < ma; ++k) f += zb[k * 3 + dd] * D[k * 3 + e];
                        dF[dd * 3 + e] = f;
                    }
                for (int i = 0; i < 9; ++i) {
                    double a = 0;
                    if (minus_rest)
                        for (int j = 0; j < 9; ++j) a += (H[i * 9 + j] - H0[i * 9 + j]) * dF[j];
                    else
                        for (int j = 0; j < 9; ++j) a += H[i * 9 + j] * dF[j];
                    dP[i] = a;
                }
                double vol = c * o->d->quad_volume[q];
                for (int k = 0; k < ma; ++k)
                    for (int dd = 0; dd < 3; ++dd)
                        v[k * 3 + dd] = vol * (dP[dd * 3 + 0] * D[k * 3 + 0] + dP[dd * 3 + 1] * D[k * 3 + 1] +
                                               dP[dd * 3 + 2] * D[k * 3 + 2]);
                for (int r = r0; r < r1; ++r) {
                    double *oi = out + (size_t)W->col[r] * n3;
                    double w = W->val[r];
                    for (int t = 0; t < n3; ++t) oi[t] += w * v[t];
                }
            }
        }
    }
    for (int sh = 1; sh < GRADIENT_SHARES; ++sh)
        for (size_t k = 0; k < nz; ++k) share[k] += share[(size_t)sh * nz + k];
    sem_shared_add_transpose(o, share, y);
}

/* F at quadrature point p from the current shared-basis coefficients o->z (Eq. 15):
 * F = sum_i w_i z_i^T D_p, the weights constant near the point. */
static inline void point_deformation_gradient(const sem_object *o, int p, double F[9])
{
    const sem_csr *W = &o->d->W;
    int ma = o->ma, n3 = 3 * ma;
    const double *D = o->point_D + (size_t)p * ma * 3;
    double zb[27] = {0}; /* sum_i w_i z_i */
    for (int r = W->row_start[p]; r < W->row_start[p + 1]; ++r) {
        const double *zi = o->z + (size_t)W->col[r] * ma * 3;
        double w = W->val[r];
        for (int x = 0; x < n3; ++x) zb[x] += w * zi[x];
    }
    for (int dd = 0; dd < 3; ++dd)
        for (int e = 0; e < 3; ++e) {
            double f = 0;
            for (int k = 0; k < ma; ++k) f += zb[k * 3 + dd] * D[k * 3 + e];
            F[dd * 3 + e] = f;
        }
}

double sem_deformed_volume(sem_object *o, const double *q, double *min_det)
{
    sem_shared_coefficients(o, sem_centered(o, q, NULL), o->z);
    double volume = 0, lowest = INFINITY;
    for (int p = 0; p < o->n_quad; ++p) {
        double F[9];
        point_deformation_gradient(o, p, F);
        double J = F[0] * (F[4] * F[8] - F[5] * F[7]) - F[1] * (F[3] * F[8] - F[5] * F[6]) +
                   F[2] * (F[3] * F[7] - F[4] * F[6]);
        volume += o->d->quad_volume[p] * J;
        if (J < lowest) lowest = J;
    }
    if (min_det) *min_det = o->n_quad > 0 ? lowest : 1.0;
    return volume;
}

sem_status sem_assemble_elastic(sem_object *o, const double *q, int want_hessian, double *grad_q,
                                   const sem_fill_target *fill, sem_error *err)
{
    const sem_discretization *d = o->d;
    const sem_csr *W = &d->W;
    int ma = o->ma, n3 = 3 * ma, np = o->n_packed;
    size_t nz = (size_t)o->n_parts * ma * 3;
    /* z_i = pi_shared_i Q (shared-basis coefficients), with Q centred (translation
     * invariance; see sem_centered) */
    sem_shared_coefficients(o, sem_centered(o, q, NULL), o->z);
    int nth = o->nthreads;
    double energy_total = 0, share_energy[GRADIENT_SHARES] = {0};
    int bad = 0;
    const int block = (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES) > 0
                          ? (o->n_quad + 4 * GRADIENT_SHARES - 1) / (4 * GRADIENT_SHARES)
                          : 1;
    memset(o->grad_z_share, 0, (size_t)GRADIENT_SHARES * nz * sizeof(double));
#pragma omp parallel num_threads(nth) reduction(| : bad)
    {
        for (int c0 = 0; c0 < o->n_quad; c0 += o->chunk) {
            int c1 = o->n_quad - c0 > o->chunk ? c0 + o->chunk : o->n_quad;
            /* per point: F, psi, P, and N_p. Blocks of `block` points go to the
             * GRADIENT_SHARES accumulators in turn (block b to share b mod S), whatever the
             * thread count and the chunk size; each share sums its points in point order
             * (continued from chunk to chunk), and the shares are added in order below, so
             * the sums are the same bits on any number of threads. */
#pragma omp for schedule(static)
            for (int sh = 0; sh < GRADIENT_SHARES; ++sh) {
                double *gz = o->grad_z_share + (size_t)sh * nz;
                double energy = share_energy[sh];
                for (int p = c0; p < c1; ++p) {
                    if ((p / block) % GRADIENT_SHARES != sh) {
                        /* skip to the next block */
                        p += block - 1 - p % block;
                        continue;
                    }
                    int r0 = W->row_start[p], r1 = W->row_start[p + 1];
                    const double *D = o->point_D + (size_t)p * ma * 3;
                    double F[9];
                    point_deformation_gradient(o, p, F);
                    double P[9], H[81];
                    double vol = d->quad_volume[p];
                    double psi = sem_material_energy(o->point_material[p], F, P, want_hessian ? H : NULL);
                    if (!isfinite(psi)) {
                        bad = 1;
                        if (want_hessian == SEM_HESSIAN_POINTS)
                            memset(o->point_H + (size_t)p * 81, 0, 81 * sizeof(double));
                        else if (want_hessian)
                            memset(o->N_chunk + (size_t)(p - c0) * np, 0, (size_t)np * sizeof(double));
                        continue;
                    }
                    energy += vol * psi;
                    /* d psi / d z_i[k][d] = vol w_i sum_e P[d][e] D[k][e] */
                    double v[27];
                    for (int k = 0; k < ma; ++k)
                        for (int dd = 0; dd < 3; ++dd)
                            v[k * 3 + dd] = vol * (P[dd * 3 + 0] * D[k * 3 + 0] + P[dd * 3 + 1] * D[k * 3 + 1] +
                                                   P[dd * 3 + 2] * D[k * 3 + 2]);
                    for (int r = r0; r < r1; ++r) {
                        double *gzi = gz + (size_t)W->col[r] * ma * 3;
                        double w = W->val[r];
                        for (int x = 0; x < n3; ++x) gzi[x] += w * v[x];
                    }
                    if (!want_hessian) continue;
                    if (!o->exact_hessian) sem_project_psd_9x9(H);
                    if (want_hessian == SEM_HESSIAN_POINTS)
                        memcpy(o->point_H + (size_t)p * 81, H, sizeof H);
                    else
                        point_stiffness(ma, vol, H, D, o->N_chunk + (size_t)(p - c0) * np);
                }
                share_energy[sh] = energy;
            }
            if (want_hessian == SEM_HESSIAN_FULL || want_hessian == SEM_HESSIAN_Z) pair_sums(o, c0, c1);
        }
    }
    for (int sh = 0; sh < GRADIENT_SHARES; ++sh) energy_total += share_energy[sh];
    if (bad)
        return sem_error_set(err, SEM_ERR_NUMERIC,
                             "an element inverted or the state became non-finite (elastic energy "
                             "undefined)");
    o->elastic_energy = energy_total;
    /* reduce in share order */
    memcpy(o->grad_z, o->grad_z_share, nz * sizeof(double));
    for (int sh = 1; sh < GRADIENT_SHARES; ++sh)
        for (size_t k = 0; k < nz; ++k) o->grad_z[k] += o->grad_z_share[(size_t)sh * nz + k];
    if (grad_q) {
        memset(grad_q, 0, 3 * (size_t)o->n_ctrl * sizeof(double));
        sem_shared_add_transpose(o, o->grad_z, grad_q);
    }
    if (want_hessian != SEM_HESSIAN_FULL) return SEM_OK;
    return sem_assemble_stiffness_blocks(o, fill, err);
}

sem_status sem_assemble_stiffness_blocks(sem_object *o, const sem_fill_target *fill, sem_error *err)
{
    int ma = o->ma, n3 = 3 * ma, nth = o->nthreads;
    size_t bs = (size_t)n3 * n3;
    if (o->structured) {
        /* no q-space blocks: the structured solver reads Kz (structured.h) */
        if (fill) sem_system_set_object(fill->system, fill->object, fill->coef);
        return SEM_OK;
    }
    /* K_q blocks = sum over part pairs Pi_a^T Kz Pi_b per coordinate pair. The small dgemm
     * calls run inside our OpenMP threads: OpenBLAS's own threads would only oversubscribe
     * the cores (measured: the rocket's step went from 18 ms to 11 ms), so BLAS is single
     * threaded here and gets its threads back for the factorization. */
    size_t mg = sem_max_group_size(o);
    int fail = 0;
    int blas_threads = openblas_get_num_threads();
    double *val = fill ? sem_system_values(fill->system) : NULL;
    openblas_set_num_threads(1);
#pragma omp parallel num_threads(nth) reduction(| : fail)
    {
        /* Block(ga,gb) = sum_a Pi_a^T (sum_b Kz_ab Pi_b) with the shared-basis Pi: the inner
         * sum first, so the expensive product with Pi_a^T is done once per part a, not per
         * pair. Kz_ab (rows (k, d), columns (d', k')) is read as a (3ma x 3) x ma matrix,
         * rows (k, d, d'), so the inner product is one call:
         * U[(k,d,d')][j] = sum_k' Kz[(k,d),(d',k')] Pi_b[k'][j]; U is then an ma x 9|Gb|
         * matrix, and Pi_a^T U is one call whose rows (la) hold the 9 sub-block rows side by
         * side, the layout of K_blocks.
         * Kz_ba = Kz_ab (symmetric) is stored once, under the pair a <= b. Pairs without a
         * shared quadrature point (only in the error matrix's pattern) have no stiffness.
         * K is symmetric, so only group pairs ga <= gb are formed (see system.h). */
        double *U = malloc(9 * (size_t)ma * mg * sizeof(double));
        if (!U) fail = 1;
#pragma omp for schedule(dynamic, 4)
        for (int g = 0; g < o->n_gpairs; ++g) {
            if (!U || o->gpair_a[g] > o->gpair_b[g]) continue;
            int na = (int)sem_group_size(o, o->gpair_a[g]), nb = (int)sem_group_size(o, o->gpair_b[g]);
            double *blk = o->K_blocks + 9 * o->gpair_offset[g];
            int written = 0; /* the first product overwrites the block (no clearing pass) */
            int k = o->gpair_pairs_start[g], end = o->gpair_pairs_start[g + 1];
            while (k < end) {
                int a = o->pair_a[o->gpair_pairs[k]];
                int any = 0;
                for (; k < end && o->pair_a[o->gpair_pairs[k]] == a; ++k) {
                    int pr = o->gpair_pairs[k], b = o->pair_b[pr];
                    int up = a <= b ? pr : o->pair_lookup[(size_t)b * o->n_parts + a];
                    if (!sem_pair_has_points(o, up)) continue;
                    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, 3 * n3, nb, ma, 1.0,
                                o->Kz + (size_t)up * bs, ma, o->pi_shared[b], nb, any ? 1.0 : 0.0, U, nb);
                    any = 1;
                }
                if (!any) continue;
                cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, na, 9 * nb, ma, 1.0, o->pi_shared[a], na,
                            U, 9 * nb, written ? 1.0 : 0.0, blk, 9 * nb);
                written = 1;
            }
            if (!written) memset(blk, 0, 9 * (size_t)na * nb * sizeof(double));
            if (fill) sem_system_fill_gpair(fill->system, fill->object, g, fill->coef, val);
        }
        free(U);
    }
    openblas_set_num_threads(blas_threads);
    if (fail) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    return SEM_OK;
}
