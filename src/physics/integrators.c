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
#include "contact/contact_world.h"
#include "loads.h"
#include "runaway.h"

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
    sem_status st = SEM_OK;
    if (!f || !g || !rhs || !tmp || !vp || !fr) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k], no = 3 * (size_t)o->n_ctrl;
        double *fk = f + off, *gk = g + off, *rk = rhs + off, *tk = tmp + off, *vk = vp + off;
        /* the system matrix's values are written as its K blocks are formed */
        const sem_fill_target fill = {s, k, {1.0 + h * a, h * h * o->gamma, h * h, h * b}};
        if ((st = sem_assemble_elastic(o, o->q, 1, gk, s->n_free > 0 ? &fill : NULL, err)) != SEM_OK)
            goto done;
        sem_external_force(o, w->time, fk);
        /* f_total = f_ext - grad V - 2 gamma M_eps q */
        sem_error_energy(o, o->q, tk);
        for (size_t i = 0; i < no; ++i) fk[i] -= gk[i] + tk[i];
        /* rhs = M v + h f; damping enters the matrix: (M + hC + h^2K) v+ = M v + h f */
        sem_blocks_multiply(o, 1.0, 0, 0, 0, o->v, rk);
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
            sem_blocks_multiply(o, 1.0 + h * a, h * h * o->gamma, h * h, h * b, vk, tk);
            for (size_t i = 0; i < no; ++i) rk[i] -= tk[i];
        }
    }
    /* contact: springs and friction into the matrix and the right-hand side */
    if (s->n_free > 0 && (st = sem_contact_linearized(w->contact, s, h, rhs, err)) != SEM_OK) goto done;
    if (s->n_free > 0) {
        st = sem_system_factorize(s, err);
        w->last_factor_s += sem_system_factor_seconds(s);
        w->counters.factorizations++;
        if (st != SEM_OK) goto done;
        sem_system_gather_free(s, rhs, fr);
        if ((st = sem_system_solve(s, fr, fr, err)) != SEM_OK) goto done;
        sem_system_scatter_free(s, fr, vp);
    }
    for (size_t i = 0; i < n; ++i)
        if (!isfinite(vp[i])) {
            st = sem_error_set(err, SEM_ERR_NUMERIC, "the state became non-finite (NaN) at t = %g", t1);
            goto done;
        }
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t no = 3 * (size_t)o->n_ctrl;
        memcpy(o->v, vp + s->dof_offset[k], no * sizeof(double));
        for (size_t i = 0; i < no; ++i) o->q[i] += h * o->v[i];
    }
done:
    free(f);
    free(g);
    free(rhs);
    free(tmp);
    free(vp);
    free(fr);
    return st;
}

sem_status sem_world_step(sem_world *w, sem_error *err)
{
    double t0 = omp_get_wtime();
    w->last_factor_s = 0;
    w->last_iterations = 0;
    double h = w->def.dt, t1 = w->time + h;
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
        if (st != SEM_OK) return st;
        sem_contact_end_step(w->contact, s);
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
    for (int i = 0; i < w->n_systems; ++i) {
        sem_status st = sem_contact_begin_step(w->contact, &w->systems[i], 0.0, w->def.solver, err);
        if (st == SEM_OK) st = sem_newton_solve(w, w->systems[i], 0.0, w->time, max_iterations, err);
        if (st != SEM_OK) return st;
        sem_contact_end_step(w->contact, w->systems[i]);
    }
    for (int k = 0; k < w->n_objects; ++k) {
        sem_status st = sem_runaway_check(w->objects[k], 1, w->time, err);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}
