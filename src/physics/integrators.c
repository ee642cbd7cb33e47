/*
 * integrators.c - sem_world_step and sem_world_solve_static: every system of the world
 * advanced by the world's integrator (see integrators.h); the linearly implicit Euler step.
 */
#include "integrators.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "assembly.h"
#include "contact_world.h"
#include "loads.h"
#include "pins.h"
#include "runaway.h"
#include "util/free_all.h"

/*
 * Reusing the rest factor. The step's matrix is A = R + h^2 (K(q_n) - K0) with the rest matrix
 * R = (1 + h a) M + 2 h^2 gamma M_eps + (h^2 + h b) K0 + h^2 A_pin: everything but the stiffness is
 * constant, and a stiff object (steel, the stiff mug) barely changes its stiffness from its
 * rest shape. Factorizing A every step (the paper's way; 80 % of the stiff mug's step) is
 * then wasted: R is factorized once, and the step solves A v = b by iterative refinement with
 * R's factor: r = b - R v - h^2 (K - K0) v, v += R^-1 r, until the componentwise backward
 * error max_i |r_i| / (|R| |v| + |h^2 (K - K0) v| + |b|)_i is below REST_TOLERANCE (4e-14,
 * some 200 units of round-off: the first solve's own error on the stiff mug is 4e-15 to
 * 1.2e-14, and a stricter bound only bought a correction on a quarter of its steps). The products
 * with K - K0 are matrix-free, point by point from the kept point Hessians (assembly.h,
 * SEM_HESSIAN_POINTS), so such a step forms neither K's coefficient-space blocks nor its
 * q-space ones. Each pass shrinks the error by about |R^-1 h^2 (K - K0)|; when that is not
 * fast (a large deformation or rotation) the step forms K and factorizes A, as before.
 *
 * Whether a step tries R is decided from the state alone (the relative change of the point
 * Hessians from rest, at most REST_MAX_CHANGE), and R is a function of the scene, not of the
 * run's history: a resumed run takes the same path step by step and gives the same bits
 * (docs/scenes.md, "Interrupted runs"). Structured systems keep their rest Schur factor
 * beside the current one and use it to precondition their conjugate gradients (structured.h;
 * change measured on Kz). Systems with contact (point terms in the matrix) always factorize.
 */
#define REST_MAX_CHANGE 0.5
#define REST_TOLERANCE 4e-14
#define REST_INNER_REDUCTION 1e-6
#define REST_MAX_SOLVES 24
/* structured systems: CG iterations with the rest factor, and the largest coefficient-space
 * factor (its order) that gets a second, rest copy */
#define REST_STRUCTURED_ITERATIONS 20
#define REST_STRUCTURED_MAX_ORDER 2000

/* |Kz - K0z|_F / |K0z|_F over the object's part pairs (structured objects keep Kz). */
static double kz_change(const sem_object *o)
{
    size_t bs = 9 * (size_t)o->ma * o->ma;
    double dn = 0, rn = 0;
    for (int pr = 0; pr < o->n_pairs; ++pr) {
        if (o->pair_a[pr] > o->pair_b[pr] || o->plist_start[pr + 1] == o->plist_start[pr]) continue;
        const double *K = o->Kz + pr * bs, *K0 = o->K0z + pr * bs;
        for (size_t i = 0; i < bs; ++i) {
            double d = K[i] - K0[i];
            dn += d * d;
            rn += K0[i] * K0[i];
        }
    }
    return rn > 0 ? sqrt(dn / rn) : (dn > 0 ? INFINITY : 0.0);
}

/* Doubles of work space sem_point_hessian_multiply needs for the largest object. */
static size_t point_work_size(const sem_system *s)
{
    size_t wz = 0;
    for (int k = 0; k < s->n_objects; ++k) {
        size_t need = (1 + GRADIENT_SHARES) * (size_t)s->objects[k]->n_parts * 3 * s->objects[k]->ma;
        if (need > wz) wz = need;
    }
    return wz;
}

/* In index order: the same bits on any thread count. */
static double dot(const double *a, const double *b, size_t n)
{
    double s = 0;
    for (size_t i = 0; i < n; ++i) s += a[i] * b[i];
    return s;
}

/* y = h^2 (K - K0) x over the free dofs (x, y free vectors; full and work scratch). */
static void stiffness_change_multiply(sem_system *s, double h, const double *x, double *y, double *full,
                                      double *yfull, double *work)
{
    memset(full, 0, s->n_dofs * sizeof(double));
    memset(yfull, 0, s->n_dofs * sizeof(double));
    sem_system_scatter_free(s, x, full);
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k];
        sem_point_hessian_multiply(o, h * h, 1, full + off, yfull + off, work);
    }
    sem_system_gather_free(s, yfull, y);
}

/* Solves A x = b by refinement with the rest factor (see above). *solved = 0 when it did not
 * converge (x is then undefined and the caller factorizes A); errors are real failures. */
static sem_status solve_with_rest(sem_world *w, sem_system *s, const double *b, double *x, int *solved,
                                  sem_error *err)
{
    double h = w->def.dt, a = w->def.rayleigh_mass, bd = w->def.rayleigh_stiffness;
    size_t nf = 3 * (size_t)s->n_free;
    *solved = 0;
    int factored = 0;
    sem_status st = sem_system_factorize_rest(s, 1.0 + h * a, h * h, h * h + h * bd, h * h, &factored, err);
    if (factored) {
        w->last_factor_s += sem_system_rest_factor_seconds(s);
        w->counters.factorizations++;
    }
    if (st != SEM_OK) return st;
    size_t wz = point_work_size(s);
    double *r = malloc((9 * nf + 2 * s->n_dofs + wz + 1) * sizeof(double));
    if (!r) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    double *y = r + nf, *sc = y + nf, *d = sc + nf, *rr = d + nf, *z = rr + nf, *p = z + nf, *q = p + nf;
    double *zero = q + nf, *full = zero + nf, *yfull = full + s->n_dofs, *work = yfull + s->n_dofs;
    memset(zero, 0, nf * sizeof(double));
    int solves = 1;
    if ((st = sem_system_solve_rest(s, b, x, err)) != SEM_OK) goto done;
    for (;;) {
        /* r = b - R x - h^2 (K - K0) x, and its componentwise backward error
         * max_i |r_i| / (|R| |x| + |h^2 (K - K0) x| + |b|)_i (the second term a lower bound
         * of |h^2 (K - K0)| |x|, which is not formed) */
        sem_system_residual_rest(s, b, x, r, sc);
        stiffness_change_multiply(s, h, x, y, full, yfull, work);
        double berr = 0;
        for (size_t i = 0; i < nf; ++i) {
            r[i] -= y[i];
            double den = sc[i] + fabs(y[i]) + fabs(b[i]);
            double e = den > 0 ? fabs(r[i]) / den : (r[i] != 0 ? INFINITY : 0.0);
            if (!(e <= berr)) berr = e;
        }
        if (!isfinite(berr)) break;
        if (berr <= REST_TOLERANCE) {
            *solved = 1;
            break;
        }
        if (solves >= REST_MAX_SOLVES) break;
        /* the correction: A d = r by conjugate gradients preconditioned with R's factor, to
         * REST_INNER_REDUCTION of |r| (then the exact residual again, above) */
        memset(d, 0, nf * sizeof(double));
        memcpy(rr, r, nf * sizeof(double));
        if ((st = sem_system_solve_rest(s, rr, z, err)) != SEM_OK) goto done;
        solves++;
        memcpy(p, z, nf * sizeof(double));
        double rz = dot(rr, z, nf), r0 = sqrt(dot(r, r, nf)), rn = r0;
        while (rn > REST_INNER_REDUCTION * r0 && solves < REST_MAX_SOLVES) {
            /* q = A p = R p + h^2 (K - K0) p */
            sem_system_residual_rest(s, zero, p, q, NULL);
            stiffness_change_multiply(s, h, p, y, full, yfull, work);
            for (size_t i = 0; i < nf; ++i) q[i] = y[i] - q[i];
            double pq = dot(p, q, nf);
            if (!(pq > 0)) break;
            double alpha = rz / pq;
            for (size_t i = 0; i < nf; ++i) {
                d[i] += alpha * p[i];
                rr[i] -= alpha * q[i];
            }
            rn = sqrt(dot(rr, rr, nf));
            if (rn <= REST_INNER_REDUCTION * r0) break;
            if ((st = sem_system_solve_rest(s, rr, z, err)) != SEM_OK) goto done;
            solves++;
            double rz1 = dot(rr, z, nf), beta = rz1 / rz;
            rz = rz1;
            for (size_t i = 0; i < nf; ++i) p[i] = z[i] + beta * p[i];
        }
        if (!(rn <= REST_INNER_REDUCTION * r0) && solves >= REST_MAX_SOLVES) break;
        if (!(rn < r0)) break;
        for (size_t i = 0; i < nf; ++i) x[i] += d[i];
    }
done:
    free(r);
    return st;
}

/* (M + h C + h^2 K) v+ = M v + h f(q), q+ = q + h v+ (the paper's step), over the system's
 * vectors (its objects' values one after the other). */
static sem_status step_linearly_implicit(sem_world *w, sem_system *s, sem_error *err)
{
    double h = w->def.dt, t1 = w->time + h;
    size_t n = s->n_dofs;
    double a = w->def.rayleigh_mass, b = w->def.rayleigh_stiffness;
    double *f = malloc(n * sizeof(double) + 1), *g = malloc(n * sizeof(double) + 1);
    double *rhs = malloc(n * sizeof(double) + 1), *tmp = malloc(n * sizeof(double) + 1);
    double *vp = calloc(n + 1, sizeof(double));
    double *fr = malloc(3 * (size_t)s->n_free * sizeof(double) + 1);
    double *xr = malloc(3 * (size_t)s->n_free * sizeof(double) + 1);
    size_t wz = point_work_size(s);
    double *work = malloc((wz + 1) * sizeof(double));
    sem_status st = SEM_OK;
    if (!f || !g || !rhs || !tmp || !vp || !fr || !xr || !work) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    /* q-space systems without contact form the coefficient-space stiffness first, and its
     * q-space blocks only when A is factorized (see "Reusing the rest factor") */
    int lazy = s->n_free > 0 && !s->structured && !sem_contact_active(w->contact) && s->n_couplings == 0 &&
               !w->def.advanced.refactorize;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k], no = 3 * (size_t)o->n_ctrl;
        double *fk = f + off, *gk = g + off, *rk = rhs + off, *tk = tmp + off, *vk = vp + off;
        /* otherwise the system's values are written as K's blocks are formed (structured
         * systems: the matrix's coefficients are recorded) */
        const sem_fill_target fill = {s, k, {1.0 + h * a, h * h * o->gamma, h * h, h * b, h * h}};
        if ((st = sem_assemble_elastic(o, o->q, lazy ? SEM_HESSIAN_POINTS : SEM_HESSIAN_FULL, gk,
                                       s->n_free > 0 && !lazy ? &fill : NULL, err)) != SEM_OK)
            goto done;
        sem_external_force(o, w->time, fk);
        /* f_total = f_ext - grad V - 2 gamma M_eps q - grad E_pin; the pins' anchor is a
         * quadratic with targets at t1, so with h^2 A in the matrix the step treats it exactly
         * as backward Euler does (pins.h) */
        sem_error_energy(o, o->q, tk);
        sem_pins_energy(o, o->q, t1, tk);
        for (size_t i = 0; i < no; ++i) fk[i] -= gk[i] + tk[i];
        /* rhs = M v + h f; damping enters the matrix: (M + hC + h^2K) v+ = M v + h f */
        sem_blocks_multiply(o, 1.0, 0, 0, 0, 0, o->v, rk);
        for (size_t i = 0; i < no; ++i) rk[i] += h * fk[i];
        /* prescribed velocities of pinned points, through A_fp */
        int any_pinned = 0;
        for (int c = 0; c < o->n_ctrl; ++c) {
            if (!o->pinned[c]) continue;
            double x1[3];
            sem_prescribed_position(o, t1, c, x1);
            for (int d = 0; d < 3; ++d) vk[3 * c + d] = (x1[d] - o->q[3 * c + d]) / h;
            any_pinned = 1;
        }
        if (any_pinned) {
            if (lazy) {
                /* K from the coefficient space (its q-space blocks are not formed yet) */
                sem_blocks_multiply(o, 1.0 + h * a, h * h * o->gamma, 0, h * b, h * h, vk, tk);
                sem_point_hessian_multiply(o, h * h, 0, vk, tk, work);
            } else {
                sem_blocks_multiply(o, 1.0 + h * a, h * h * o->gamma, h * h, h * b, h * h, vk, tk);
            }
            for (size_t i = 0; i < no; ++i) rk[i] -= tk[i];
        }
    }
    /* contact: springs and friction into the matrix and the right-hand side */
    if (s->n_free > 0 && (st = sem_contact_linearized(w->contact, s, h, rhs, err)) != SEM_OK) goto done;
    if (s->n_free > 0) {
        sem_system_gather_free(s, rhs, fr);
        int solved = 0;
        if (lazy) {
            double change = 0;
            for (int k = 0; k < s->n_objects; ++k) {
                double c = sem_point_hessian_change(s->objects[k]);
                if (c > change) change = c;
            }
            if (change <= REST_MAX_CHANGE && (st = solve_with_rest(w, s, fr, xr, &solved, err)) != SEM_OK)
                goto done;
        }
        if (s->structured && !sem_contact_active(w->contact) && s->n_couplings == 0 &&
            !w->def.advanced.refactorize) {
            double change = 0;
            for (int k = 0; k < s->n_objects; ++k) change = fmax(change, kz_change(s->objects[k]));
            long nf = 0;
            double fs = 0;
            if (change <= REST_MAX_CHANGE) {
                st = sem_system_solve_structured_rest(s, REST_STRUCTURED_MAX_ORDER, REST_STRUCTURED_ITERATIONS, fr, xr,
                                                      &solved, &nf, &fs, err);
                w->counters.factorizations += nf;
                w->last_factor_s += fs;
                if (st != SEM_OK) goto done;
            }
        }
        if (solved) {
            memcpy(fr, xr, 3 * (size_t)s->n_free * sizeof(double));
        } else {
            if (lazy)
                for (int k = 0; k < s->n_objects; ++k) {
                    sem_object *o = s->objects[k];
                    const sem_fill_target fill = {s, k, {1.0 + h * a, h * h * o->gamma, h * h, h * b, h * h}};
                    sem_assemble_kz_from_points(o);
                    if ((st = sem_assemble_stiffness_blocks(o, &fill, err)) != SEM_OK) goto done;
                }
            st = sem_system_factorize(s, err);
            w->last_factor_s += sem_system_factor_seconds(s);
            w->counters.factorizations++;
            if (st != SEM_OK) goto done;
            if ((st = sem_system_solve(s, fr, fr, err)) != SEM_OK) goto done;
        }
        sem_system_scatter_free(s, fr, vp);
    }
    if ((st = sem_runaway_check_finite(vp, n, t1, err)) != SEM_OK) goto done;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t no = 3 * (size_t)o->n_ctrl;
        memcpy(o->v, vp + s->dof_offset[k], no * sizeof(double));
        for (size_t i = 0; i < no; ++i) o->q[i] += h * o->v[i];
    }
done:
    SEM_FREE_ALL(f, g, rhs, tmp, vp, fr, xr, work);
    return st;
}

sem_status sem_world_step(sem_world *w, sem_error *err)
{
    double t0 = omp_get_wtime();
    w->last_factor_s = 0;
    w->last_iterations = 0;
    double h = w->def.dt, t1 = w->time + h;
    sem_contact_begin_world_step(w->contact);
    /* objects that may touch in this step are solved together, the others apart */
    sem_status rs = sem_world_regroup(w, w->def.integrator == SEM_STATIC ? 0.0 : h, err);
    if (rs != SEM_OK) return rs;
    for (int i = 0; i < w->n_systems; ++i) {
        /* contact: friction lagged at q_n, coupling blocks between objects near each other
         * (contact_world.h; may make the system again) */
        sem_status st = sem_contact_begin_step(w->contact, &w->systems[i],
                                               w->def.integrator == SEM_STATIC ? 0.0 : h, w->def.solver, err);
        if (st != SEM_OK) return st;
        sem_system *s = w->systems[i];
        switch (w->def.integrator) {
        case SEM_LINEARLY_IMPLICIT_EULER: st = step_linearly_implicit(w, s, err); break;
        case SEM_IMPLICIT_EULER: st = sem_newton_solve(w, s, h, t1, w->def.newton_max_iterations, err); break;
        /* quasi-static: equilibrium with the loads and prescribed motion of t + dt */
        default: st = sem_newton_solve(w, s, 0.0, t1, w->def.newton_max_iterations, err); break;
        }
        if (st == SEM_OK) st = sem_contact_end_step(w->contact, s, err);
        if (st != SEM_OK) return st;
    }
    if (w->n_systems > 1) {
        sem_status st = sem_contact_check_islands(w->contact, w->objects, w->n_objects, err);
        if (st != SEM_OK) return st;
    }
    for (int k = 0; k < w->n_objects; ++k) {
        sem_status st = sem_runaway_check(w->objects[k], w->def.integrator == SEM_STATIC, t1, err);
        if (st != SEM_OK) return st;
    }
    w->time += w->def.dt;
    w->step_index++;
    w->counters.steps++;
    w->last_step_s = omp_get_wtime() - t0;
    return SEM_OK;
}

sem_status sem_world_solve_static(sem_world *w, sem_error *err)
{
    int max_iterations = w->def.newton_max_iterations < 200 ? 200 : w->def.newton_max_iterations;
    sem_contact_begin_world_step(w->contact);
    sem_status rs = sem_world_regroup(w, 0.0, err);
    if (rs != SEM_OK) return rs;
    for (int i = 0; i < w->n_systems; ++i) {
        sem_status st = sem_contact_begin_step(w->contact, &w->systems[i], 0.0, w->def.solver, err);
        if (st == SEM_OK) st = sem_newton_solve(w, w->systems[i], 0.0, w->time, max_iterations, err);
        if (st == SEM_OK) st = sem_contact_end_step(w->contact, w->systems[i], err);
        if (st != SEM_OK) return st;
    }
    for (int k = 0; k < w->n_objects; ++k) {
        sem_status st = sem_runaway_check(w->objects[k], 1, w->time, err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}
