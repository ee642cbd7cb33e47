/*
 * study_weight_gradient.c - what the deflection study (docs/validation.md, section 2) gives
 * when the deformation gradient keeps the term Eq. 15 drops:
 *
 *     F(X) = sum_i w_i(X) dP_i/dX + P_i(X) (x) grad w_i(X)        (Eq. 15 has the first sum only)
 *
 * grad w_i comes from central differences of the ray-cast weights (Eq. 8-9, sem_blend_weights)
 * over +-delta along each axis, for every part whose weight is non-zero at any of the 7 points.
 * This is a research program, not the simulator: it forms the gradient operator densely
 * (3 points x control points), assembles the dense Hessian and solves the static cantilever
 * of study_deflection (generated beams, sem_default_cantilever_settings: clamped at x = 0,
 * gravity 10 m/s^2 along -z, rho 1000, neo-Hookean E 1e6, nu 0.45, the authors' settings:
 * quadratic, alpha 0.501, rays 3 x 3, 100 points per interval; the same clamp and tip
 * measure, sem_cantilever_clamp and sem_cantilever_tip) with Newton and a backtracking line search, like sem_world_solve_static (PSD
 * projected Hessian, exact once two steps in a row were full). The error energy uses the
 * preprocessing's M_eps. With --delta 0 it solves Eq. 15 itself, a check against
 * study_deflection (10 sections: 3.973578 m from both).
 *
 * usage: study_weight_gradient [--sections LIST] [--delta D] [--gamma G] [--rays N]
 *                              [--fem FILE]
 *   --sections LIST  section counts (default 1,2,4,6,8,10,12,15,20,25,30)
 *   --delta D        difference step for grad w in metres (default 0.1; 0: Eq. 15)
 *   --gamma G        error stiffness (default: the preprocessing default, 1000 E / L)
 *   --rays N         N x N rays across x (default 3)
 *   --fem FILE       FEM reference (default validation/fem_cantilever.json, also tried
 *                    relative to ..)
 * Output: sections dofs delta gamma tip_m percent_of_fem newton, one line per beam.
 */
#include <cblas.h>
#include <lapacke.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "preprocess/raycast.h"
#include "preprocess/steps.h"
#include "sem/material.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"

typedef struct problem {
    const sem_discretization *d;
    int n, N;          /* control points, quadrature points */
    double *G;         /* 3N x n: F_p[c][e] = sum_j G[3p+e][j] Q[j][c] */
    double *Q0, *f;    /* rest control points, gravity force (3n each) */
    unsigned char *pin; /* clamped control points (sem_cantilever_clamp) */
    double gamma;
    sem_material mat;
    int exact;         /* 1: unprojected per-point Hessians */
} problem;

/* Energy; gradient (3n) and Hessian (3n x 3n, index 3 j + c) when non-NULL. */
static double energy(const problem *pb, const double *Q, double *grad, double *K)
{
    const int n = pb->n, N = pb->N;
    double *Fall = malloc(sizeof(double) * 9 * (size_t)N);
    double *Pall = grad ? calloc(9 * (size_t)N, sizeof(double)) : NULL;
    double *Hall = K ? malloc(sizeof(double) * 81 * (size_t)N) : NULL;
    double *MQ = calloc(3 * (size_t)n, sizeof(double));
    double E = 0;
    if (!Fall || (grad && !Pall) || (K && !Hall) || !MQ) {
        E = NAN;
        goto done;
    }
    cblas_dgemm(CblasRowMajor, CblasNoTrans, CblasNoTrans, 3 * N, 3, n, 1.0, pb->G, n, Q, 3, 0.0,
                Fall, 3);
    for (int p = 0; p < N; ++p) {
        double F[9], P[9], H[81];
        for (int c = 0; c < 3; ++c)
            for (int e = 0; e < 3; ++e) F[3 * c + e] = Fall[(3 * p + e) * 3 + c];
        double psi = sem_material_energy(&pb->mat, F, P, H);
        if (!isfinite(psi)) {
            E = INFINITY;
            goto done;
        }
        double v = pb->d->quad_volume[p];
        E += v * psi;
        if (Pall)
            for (int c = 0; c < 3; ++c)
                for (int e = 0; e < 3; ++e) Pall[(3 * p + e) * 3 + c] = v * P[3 * c + e];
        if (Hall) {
            if (!pb->exact) sem_project_psd_9x9(H);
            for (int a = 0; a < 81; ++a) Hall[81 * (size_t)p + a] = v * H[a];
        }
    }
    const sem_csr *M = &pb->d->M_eps;
    for (int r = 0; r < n; ++r)
        for (int k = M->row_start[r]; k < M->row_start[r + 1]; ++k)
            for (int c = 0; c < 3; ++c)
                MQ[3 * r + c] += M->val[k] * (Q[3 * M->col[k] + c] - pb->Q0[3 * M->col[k] + c]);
    for (int i = 0; i < 3 * n; ++i) E += pb->gamma * (Q[i] - pb->Q0[i]) * MQ[i] - pb->f[i] * Q[i];
    if (grad) {
        cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, n, 3, 3 * N, 1.0, pb->G, n, Pall, 3,
                    0.0, grad, 3);
        for (int i = 0; i < 3 * n; ++i) grad[i] += 2 * pb->gamma * MQ[i] - pb->f[i];
    }
    if (K) {
        /* K[(j,c),(j',c')] = sum_p sum_{e,e'} G[pe][j] H_p[(c,e),(c',e')] G[pe'][j'] */
        double *T = malloc(sizeof(double) * 3 * (size_t)N * n), *Kc = malloc(sizeof(double) * n * n);
        if (!T || !Kc) {
            free(T);
            free(Kc);
            E = NAN;
            goto done;
        }
        memset(K, 0, sizeof(double) * 9 * (size_t)n * n);
        for (int c = 0; c < 3; ++c)
            for (int c2 = 0; c2 < 3; ++c2) {
                memset(T, 0, sizeof(double) * 3 * (size_t)N * n);
                for (int p = 0; p < N; ++p)
                    for (int e = 0; e < 3; ++e)
                        for (int e2 = 0; e2 < 3; ++e2) {
                            double h = Hall[81 * (size_t)p + 9 * (3 * c + e) + 3 * c2 + e2];
                            if (h != 0)
                                cblas_daxpy(n, h, pb->G + (size_t)(3 * p + e2) * n, 1,
                                            T + (size_t)(3 * p + e) * n, 1);
                        }
                cblas_dgemm(CblasRowMajor, CblasTrans, CblasNoTrans, n, n, 3 * N, 1.0, pb->G, n, T,
                            n, 0.0, Kc, n);
                for (int j = 0; j < n; ++j)
                    for (int j2 = 0; j2 < n; ++j2)
                        K[(size_t)(3 * j + c) * 3 * n + 3 * j2 + c2] += Kc[(size_t)j * n + j2];
            }
        for (int r = 0; r < n; ++r)
            for (int k = M->row_start[r]; k < M->row_start[r + 1]; ++k)
                for (int c = 0; c < 3; ++c)
                    K[(size_t)(3 * r + c) * 3 * n + 3 * M->col[k] + c] += 2 * pb->gamma * M->val[k];
        free(T);
        free(Kc);
    }
done:
    free(Fall);
    free(Pall);
    free(Hall);
    free(MQ);
    return E;
}

/* G += the grad w term: row (p, e) gets sum_i dw_i/dX_e b(X_p - Xbar_i)^T Pi_i. */
static int add_weight_gradient(problem *pb, const sem_model *m, double delta, sem_error *err)
{
    const sem_discretization *d = pb->d;
    const int N = pb->N, n = pb->n, mb = d->n_basis, np = d->n_parts;
    sem_raycast_scene *scene = NULL;
    if (sem_raycast_scene_build(m, 16, &scene, err) != SEM_OK) return 0;
    double *X = malloc(sizeof(double) * 3 * (size_t)N);
    double *gw = calloc((size_t)N * np * 3, sizeof(double));
    int ok = X && gw;
    for (int e = 0; ok && e < 3; ++e)
        for (int sgn = -1; ok && sgn <= 1; sgn += 2) {
            memcpy(X, d->quad_X, sizeof(double) * 3 * (size_t)N);
            for (int p = 0; p < N; ++p) X[3 * p + e] += sgn * delta;
            sem_csr W;
            memset(&W, 0, sizeof W);
            if (sem_blend_weights(scene, N, X, d->alpha, 1e-4, &W, err) != SEM_OK) {
                ok = 0;
                break;
            }
            for (int p = 0; p < N; ++p)
                for (int k = W.row_start[p]; k < W.row_start[p + 1]; ++k)
                    gw[((size_t)p * np + W.col[k]) * 3 + e] += sgn * W.val[k] / (2 * delta);
            sem_csr_free(&W);
        }
    for (int p = 0; ok && p < N; ++p)
        for (int i = 0; i < np; ++i) {
            const double *g = gw + ((size_t)p * np + i) * 3;
            if (g[0] == 0 && g[1] == 0 && g[2] == 0) continue;
            const double *Xb = d->origin_X + 3 * d->part_origin[i], *Xp = d->quad_X + 3 * p;
            double dX[3] = {Xp[0] - Xb[0], Xp[1] - Xb[1], Xp[2] - Xb[2]}, b[10];
            sem_polynomial_basis(d->order, dX, b, NULL);
            for (int kb = 0; kb < mb; ++kb) {
                int row = i * mb + kb;
                for (int k = d->Pi.row_start[row]; k < d->Pi.row_start[row + 1]; ++k)
                    for (int e = 0; e < 3; ++e)
                        pb->G[(size_t)(3 * p + e) * n + d->Pi.col[k]] += g[e] * b[kb] * d->Pi.val[k];
            }
        }
    if (!X || !gw) sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    free(X);
    free(gw);
    sem_raycast_scene_destroy(scene);
    return ok;
}

/* Newton on the free dofs (the unclamped control points); returns iterations, -1 on
 * failure. */
static int solve(problem *pb, double *Q)
{
    const int n = pb->n;
    int *fidx = malloc(sizeof(int) * 3 * (size_t)n), nf = 0, it = -1;
    for (int j = 0; fidx && j < n; ++j)
        if (!pb->pin[j])
            for (int c = 0; c < 3; ++c) fidx[nf++] = 3 * j + c;
    double *g = malloc(sizeof(double) * 3 * n), *K = malloc(sizeof(double) * 9 * (size_t)n * n);
    double *Kf = malloc(sizeof(double) * (size_t)nf * nf + 1), *r = malloc(sizeof(double) * nf + 1);
    double *Qt = malloc(sizeof(double) * 3 * n);
    if (!fidx || !g || !K || !Kf || !r || !Qt) goto done;
    memcpy(Q, pb->Q0, sizeof(double) * 3 * n);
    double g0 = -1;
    int full = 0, exact_allowed = 1;
    for (it = 0; it < 200; ++it) {
        pb->exact = exact_allowed && full >= 2;
        double E0 = energy(pb, Q, g, K);
        if (!isfinite(E0)) {
            it = -1;
            break;
        }
        double gn = 0;
        for (int a = 0; a < nf; ++a) gn += g[fidx[a]] * g[fidx[a]];
        gn = sqrt(gn);
        if (g0 < 0) g0 = gn;
        if (gn <= 1e-8 * g0) break;
        for (;;) {
            for (int a = 0; a < nf; ++a) {
                r[a] = g[fidx[a]];
                for (int b = 0; b < nf; ++b) Kf[(size_t)a * nf + b] = K[(size_t)fidx[a] * 3 * n + fidx[b]];
            }
            if (LAPACKE_dpotrf(LAPACK_ROW_MAJOR, 'L', nf, Kf, nf) == 0) break;
            if (!pb->exact) {
                it = -1;
                goto done;
            }
            pb->exact = exact_allowed = 0; /* not positive definite: projected from now on */
            energy(pb, Q, g, K);
        }
        LAPACKE_dpotrs(LAPACK_ROW_MAJOR, 'L', nf, 1, Kf, nf, r, 1);
        double slope = 0, step = 1, Et = INFINITY, dmax = 0;
        for (int a = 0; a < nf; ++a) slope -= r[a] * g[fidx[a]];
        for (int ls = 0; ls < 50; ++ls) {
            memcpy(Qt, Q, sizeof(double) * 3 * n);
            for (int a = 0; a < nf; ++a) Qt[fidx[a]] -= step * r[a];
            Et = energy(pb, Qt, NULL, NULL);
            if (Et <= E0 + 1e-4 * step * slope || fabs(Et - E0) <= 1e-14 * fabs(E0)) break;
            step *= 0.5;
        }
        if (!isfinite(Et)) {
            it = -1;
            break;
        }
        for (int a = 0; a < nf; ++a) dmax = fmax(dmax, fabs(step * r[a]));
        full = step == 1 ? full + 1 : 0;
        memcpy(Q, Qt, sizeof(double) * 3 * n);
        if (dmax <= 1e-14 * 5.0) { /* no progress left at round-off (beam length 5 m) */
            ++it;
            break;
        }
    }
done:
    free(fidx);
    free(g);
    free(K);
    free(Kf);
    free(r);
    free(Qt);
    return it;
}

static int run(int sections, double delta, const sem_cantilever_settings *s, double fem)
{
    sem_error err;
    int status = 1;
    sem_model *m = sem_model_create();
    sem_discretization *d = NULL;
    problem pb;
    memset(&pb, 0, sizeof pb);
    double *Q = NULL;
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = sections;
    if (!m || sem_primitive_beam(m, &bd, &err) != SEM_OK) goto fail;
    sem_preprocess_options po = sem_cantilever_preprocess_options(s);
    if (sem_preprocess(m, &po, &d, &err) != SEM_OK) goto fail;
    pb.d = d;
    pb.n = d->n_ctrl;
    pb.N = d->n_quad;
    pb.gamma = d->gamma;
    if (sem_cantilever_material(s, &pb.mat, &err) != SEM_OK) goto fail;
    const int n = pb.n;
    pb.G = calloc(3 * (size_t)pb.N * n, sizeof(double));
    pb.Q0 = malloc(sizeof(double) * 3 * n);
    pb.f = calloc(3 * (size_t)n, sizeof(double));
    pb.pin = malloc((size_t)n);
    Q = malloc(sizeof(double) * 3 * n);
    if (!pb.G || !pb.Q0 || !pb.f || !pb.pin || !Q) {
        sem_error_set(&err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    for (int r = 0; r < 3 * pb.N; ++r)
        for (int k = d->Grad.row_start[r]; k < d->Grad.row_start[r + 1]; ++k)
            pb.G[(size_t)r * n + d->Grad.col[k]] += d->Grad.val[k];
    if (delta > 0 && !add_weight_gradient(&pb, m, delta, &err)) goto fail;
    sem_model_get_q(m, pb.Q0);
    sem_cantilever_clamp(pb.Q0, (size_t)n, pb.pin);
    for (int p = 0; p < pb.N; ++p)
        for (int k = d->Gamma.row_start[p]; k < d->Gamma.row_start[p + 1]; ++k)
            pb.f[3 * d->Gamma.col[k] + 2] -=
                pb.mat.density * s->gravity * d->quad_volume[p] * d->Gamma.val[k];
    int it = solve(&pb, Q);
    if (it < 0) {
        sem_error_set(&err, SEM_ERR_NUMERIC, "Newton failed");
        goto fail;
    }
    double tip = sem_cantilever_tip(m, pb.Q0, Q);
    printf("%3d %5d %6g %10.4g %9.6f %8.3f %4d\n", sections, 3 * n, delta, pb.gamma, tip,
           fem > 0 ? 100 * tip / fem : NAN, it);
    fflush(stdout);
    status = 0;
    goto done;
fail:
    fprintf(stderr, "study_weight_gradient: %d sections: %s\n", sections, err.message);
done:
    free(pb.G);
    free(pb.Q0);
    free(pb.f);
    free(pb.pin);
    free(Q);
    sem_discretization_destroy(d);
    if (m) sem_model_destroy(m);
    return status;
}

int main(int argc, char **argv)
{
    const char *sections = "1,2,4,6,8,10,12,15,20,25,30";
    const char *fem_path = NULL;
    double delta = 0.1;
    sem_cantilever_settings st = sem_default_cantilever_settings();
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--sections") && i + 1 < argc) sections = argv[++i];
        else if (!strcmp(argv[i], "--delta") && i + 1 < argc) delta = atof(argv[++i]);
        else if (!strcmp(argv[i], "--gamma") && i + 1 < argc) st.gamma = atof(argv[++i]);
        else if (!strcmp(argv[i], "--rays") && i + 1 < argc) st.rays[0] = st.rays[1] = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--fem") && i + 1 < argc) fem_path = argv[++i];
        else {
            fprintf(stderr, "usage: %s [--sections LIST] [--delta D] [--gamma G] [--rays N] "
                            "[--fem FILE]\n", argv[0]);
            return 2;
        }
    }
    if (!(delta >= 0) || st.rays[0] < 1 || !(st.gamma >= 0)) {
        fprintf(stderr, "study_weight_gradient: need delta >= 0, gamma >= 0, rays >= 1\n");
        return 2;
    }
    int counts[64];
    int n_counts = sem_parse_count_list(sections, 1000, counts, 64);
    if (n_counts < 0) {
        fprintf(stderr, "study_weight_gradient: bad --sections list %s (up to 64 counts, 1..1000)\n",
                sections);
        return 2;
    }
    double fem = sem_fem_reference_find(fem_path, "study_weight_gradient");
    if (fem <= 0) fprintf(stderr, "study_weight_gradient: no FEM reference; percent column is nan\n");
    printf("# static cantilever with F = sum w_i grad P_i + P_i (x) grad w_i (delta 0: Eq. 15)\n");
    printf("# sections dofs delta gamma tip_m percent_of_fem newton\n");
    int failures = 0;
    for (int j = 0; j < n_counts; ++j) failures += run(counts[j], delta, &st, fem);
    return failures ? 1 : 0;
}
