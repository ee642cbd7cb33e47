/*
 * newton.c - Newton's method on a system's incremental potential (implicit Euler) or
 * potential energy (statics), with a backtracking line search and the switch to the exact
 * Hessian (see integrators.h).
 *
 * The solve works on the system's vectors: its objects' 3 n_ctrl values one after the
 * other (system.h). The objects' own q are read at the start and written back at the end.
 */
#include "integrators.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "assembly.h"
#include "contact_world.h"
#include "loads.h"
#include "pins.h"
#include "point_terms.h"
#include "runaway.h"
#include "util/free_all.h"

/* Newton stops as converged after NEWTON_STALL_ITERATIONS iterations in a row whose Newton
 * step (the full one, whatever the line search then takes of it) moves no coordinate by more
 * than NEWTON_STALL_MOVE of the largest coordinate, without halving the gradient: the gradient
 * is at its own round-off, or at the kinks of the contact springs, and q is the solution to
 * NEWTON_STALL_MOVE of its size. */
#define NEWTON_STALL_ITERATIONS 8
#define NEWTON_STALL_MOVE 1e-7
/* The barrier model also stops, as IPC does (Li et al. 2020, Sec. 5: the Newton increment),
 * when a full Newton step moves no coordinate by more than BARRIER_NEWTON_MOVE of the
 * system's size while the gradient falls by less than 10x per iteration: the barrier's
 * Hessian is only its PSD part (contact/barrier.h), so near a contact at a vertex or edge
 * Newton converges linearly, and its last iterations move the surfaces by nanometres while
 * the relative gradient is still above 1e-8 (a ball shot pole-first onto a plate: moves of
 * 1e-7 m, the gradient falling by 0.88 per iteration at 1e-6 of its first value). Where
 * Newton converges quadratically it goes on to the tolerance (the momentum of two spheres
 * meeting head-on stays zero to 1e-9). */
#define BARRIER_NEWTON_MOVE 1e-7

/* One solve: the world's settings, the system, and its vectors (n_dofs each). */
typedef struct newton {
    sem_world *w;
    sem_system *s;
    double h, cD, t1;             /* t1: the time solved for (the pins' targets) */
    int dynamic;
    const double *qn, *qpred, *f; /* the step's start, prediction q_n + h v_n, loads */
    double *tmp, *dq;             /* scratch */
} newton;

/* The line search compares energies by their differences. The potential is the elastic
 * energy V and the contact potential Ec (sums of small non-negative terms, accurate to
 * round-off of their size) plus a quadratic Q(q) = 1/2 q^T A q - b^T q: inertia, damping,
 * loads, the error energy and the material pins' anchor (A = cM M + 2 gamma M_eps + cD K0 +
 * A_pin, pins.h). Q itself is a sum of large
 * terms that cancel (gamma M_eps has entries far larger than the energy, since gamma is
 * stiff), so evaluating it at two points and subtracting loses the few digits a converging
 * Newton step changes (measured: 1e-9 of an energy of 1 on a refined box, where a step
 * changes it by 1e-9; the search then halved the step to nothing and stalled at a relative
 * gradient of 1.6e-4). Its change along a step d is exact instead:
 * Q(q + d) - Q(q) = d . grad Q(q) + 1/2 d . A d, with grad Q(q) from the gradient and A d one
 * product. */

/* V + Ec at q (the non-quadratic part of the potential); +inf where undefined (an inverted
 * element). */
static double nonquadratic(const newton *nt, const double *q)
{
    const sem_system *s = nt->s;
    double total = 0;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_error e;
        if (sem_assemble_elastic(s->objects[k], q + s->dof_offset[k], 0, NULL, NULL, &e) != SEM_OK) return INFINITY;
        total += s->objects[k]->elastic_energy;
    }
    /* contact: springs and friction (contact_world.h) */
    sem_error e;
    double Ec = sem_contact_potential(nt->w->contact, s, q, nt->h, NULL, &e);
    return isnan(Ec) ? INFINITY : total + Ec;
}

/* y = A x, the quadratic part's matrix (see above), over the system's vectors. */
static void quadratic_multiply(const newton *nt, double cM, const double *x, double *y)
{
    const sem_system *s = nt->s;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k];
        sem_blocks_multiply(o, cM, o->gamma, 0, nt->cD, 1.0, x + off, y + off);
    }
}

/* The gradient g of E at q and, with the objects' K blocks, the Hessian's stiffness part:
 * grad V + 2 gamma M_eps q + grad E_pin - f + M (q - q_pred) / h^2 + damping + contact. gq: the gradient of
 * the quadratic part alone; *vc: V + Ec at q. */
static sem_status gradient(const newton *nt, const double *q, double *g, double *gq, double *vc,
                           sem_error *err)
{
    const sem_system *s = nt->s;
    const sem_world *w = nt->w;
    double h = nt->h;
    *vc = 0;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k], n = 3 * (size_t)o->n_ctrl;
        const double *x = q + off, *f = nt->f + off, *qpred = nt->qpred + off, *qn = nt->qn + off;
        double *gk = g + off, *qk = gq + off, *tmp = nt->tmp + off, *dq = nt->dq + off;
        sem_status st = sem_assemble_elastic(o, x, 1, gk, NULL, err);
        if (st != SEM_OK) return st;
        *vc += o->elastic_energy;
        sem_error_energy(o, x, qk);
        sem_pins_energy(o, x, nt->t1, qk);
        for (size_t i = 0; i < n; ++i) qk[i] -= f[i];
        if (nt->dynamic) {
            for (size_t i = 0; i < n; ++i) dq[i] = x[i] - qpred[i];
            sem_blocks_multiply(o, 1.0 / (h * h), 0, 0, 0, 0, dq, tmp);
            for (size_t i = 0; i < n; ++i) qk[i] += tmp[i];
            if (nt->cD > 0 || w->def.rayleigh_mass > 0) {
                for (size_t i = 0; i < n; ++i) dq[i] = x[i] - qn[i];
                sem_blocks_multiply(o, w->def.rayleigh_mass / h, 0, 0, nt->cD, 0, dq, tmp);
                for (size_t i = 0; i < n; ++i) qk[i] += tmp[i];
            }
        }
        for (size_t i = 0; i < n; ++i) gk[i] += qk[i];
    }
    /* contact: its gradient, and its Hessian's point terms for factorize() */
    double Ec = sem_contact_potential(w->contact, s, q, h, g, err);
    if (isnan(Ec)) return err ? err->status : SEM_ERR_NOMEM;
    *vc += Ec;
    return SEM_OK;
}

static void set_exact_hessian(sem_system *s, int on)
{
    for (int k = 0; k < s->n_objects; ++k) s->objects[k]->exact_hessian = on;
}

/* Fills the system's matrix with the Hessian, factorizes it and counts that. */
static sem_status factorize(sem_world *w, sem_system *s, double cM, double cD, sem_error *err)
{
    sem_system_fill(s, cM, 1.0, 1.0, cD, 1.0);
    /* contact: its Hessian (point_terms.h) */
    const sem_point_terms *contact = sem_contact_terms(w->contact);
    const double one = 1.0;
    sem_system_set_point_terms(s, &contact, &one, 1);
    sem_status st = sem_system_factorize(s, err);
    w->last_factor_s += sem_system_factor_seconds(s);
    w->counters.factorizations++;
    return st;
}

/* Free control points of q back to where they are in qn (pinned ones keep their targets). */
static void free_points_at(const sem_system *s, double *q, const double *qn)
{
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k];
        for (int c = 0; c < o->n_ctrl; ++c)
            if (!o->pinned[c]) memcpy(q + off + 3 * (size_t)c, qn + off + 3 * (size_t)c, 3 * sizeof(double));
    }
}

/* The barrier model's first iterate (q, pinned points at their targets): kept if the
 * straight move from q_n reaches it without a crossing; otherwise free points start at q_n,
 * and a crossing then is the pins' (prescribed motion into a surface): an error. scratch:
 * n_dofs. */
static sem_status barrier_start(sem_world *w, sem_system *s, double *q, const double *qn, double *scratch, double t1,
                                sem_error *err)
{
    for (int pass = 0; pass < 2; ++pass) {
        for (size_t i = 0; i < s->n_dofs; ++i) scratch[i] = q[i] - qn[i];
        double t = 1;
        sem_status st = sem_contact_max_step(w->contact, s, qn, scratch, 1.0, &t, err);
        if (st != SEM_OK || t >= 1) return st;
        if (pass == 1) break;
        free_points_at(s, q, qn);
    }
    return sem_error_set(err, SEM_ERR_NUMERIC,
                         "contact (barrier): the prescribed motion of pinned points takes a surface into another "
                         "within the step to t = %g",
                         t1);
}

sem_status sem_newton_solve(sem_world *w, sem_system *s, double h, double t1, int max_iterations,
                            sem_error *err)
{
    size_t n = s->n_dofs;
    int dynamic = h > 0;
    double cM = dynamic ? 1.0 / (h * h) + w->def.rayleigh_mass / h : 0.0;
    double cD = dynamic ? w->def.rayleigh_stiffness / h : 0.0;
    double *q = malloc(n * sizeof(double) + 1);
    double *qn = malloc(n * sizeof(double) + 1), *qpred = malloc(n * sizeof(double) + 1);
    double *f = malloc(n * sizeof(double) + 1), *g = malloc(n * sizeof(double) + 1);
    double *tmp = malloc(n * sizeof(double) + 1), *dq = calloc(n + 1, sizeof(double));
    double *qtry = malloc(n * sizeof(double) + 1), *dir = malloc(n * sizeof(double) + 1);
    double *gq = malloc(n * sizeof(double) + 1), *adir = malloc(n * sizeof(double) + 1);
    double *fr = malloc(3 * (size_t)s->n_free * sizeof(double) + 1);
    sem_status st = SEM_OK;
    int gathered = 0;
    if (!q || !qn || !qpred || !f || !g || !tmp || !dq || !qtry || !dir || !gq || !adir || !fr) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    for (int k = 0; k < s->n_objects; ++k) {
        const sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k], no = 3 * (size_t)o->n_ctrl;
        memcpy(q + off, o->q, no * sizeof(double));
        memcpy(qn + off, o->q, no * sizeof(double));
        for (size_t i = 0; i < no; ++i) qpred[off + i] = o->q[i] + (dynamic ? h * o->v[i] : 0);
        sem_external_force(o, t1, f + off);
        /* pinned points go to their prescribed positions at t1, free ones (dynamics) to
         * the prediction */
        for (int c = 0; c < o->n_ctrl; ++c) {
            double *x = q + off + 3 * (size_t)c;
            if (o->pinned[c])
                sem_prescribed_position(o, t1, c, x);
            else if (dynamic)
                memcpy(x, qpred + off + 3 * (size_t)c, 3 * sizeof(double));
        }
    }
    gathered = 1;
    /* the barrier model: the first iterate is reached from q_n without any surface crossing
     * another (the prediction may carry one through: free points then start at q_n) */
    int barrier = sem_contact_barrier(w->contact);
    if (barrier && (st = barrier_start(w, s, q, qn, dir, t1, err)) != SEM_OK) goto done;
    double qscale = 0, lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = 0; i < n; ++i) {
        qscale = fmax(qscale, fabs(q[i]));
        lo[i % 3] = fmin(lo[i % 3], q[i]);
        hi[i % 3] = fmax(hi[i % 3], q[i]);
    }
    const double size = n >= 3 ? sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                                      (hi[2] - lo[2]) * (hi[2] - lo[2]))
                               : 0;
    const newton nt = {w, s, h, cD, t1, dynamic, qn, qpred, f, tmp, dq};
    double g0norm = -1, last_rel = 0, prev_gnorm = INFINITY, slope0 = 0, stall_gnorm = INFINITY;
    int stalled = 0;
    int it, full_steps = 0, exact_allowed = !w->def.advanced.projected_hessian, converged = 0, search_failed = 0;
    set_exact_hessian(s, 0);
    for (it = 0; it < max_iterations; ++it) {
        /* the exact Hessian after two full steps in a row (see integrators.h) */
        int exact = exact_allowed && full_steps >= 2;
        set_exact_hessian(s, exact);
        double vc0 = 0;
        st = gradient(&nt, q, g, gq, &vc0, err);
        if (st != SEM_OK && it == 0 && dynamic) {
            /* The prediction q_n + h v_n is the usual first iterate, but at an impact it can
             * carry a part through the contact springs far enough to invert an element
             * (infinite energy, no gradient). Newton then starts from q_n instead (free points
             * where they were), which is valid: it is the last accepted state. */
            free_points_at(s, q, qn);
            st = gradient(&nt, q, g, gq, &vc0, err);
        }
        if (st != SEM_OK) goto done;
        sem_system_gather_free(s, g, fr);
        double gnorm = 0, fscale = 0;
        for (int i = 0; i < 3 * s->n_free; ++i) gnorm += fr[i] * fr[i];
        gnorm = sqrt(gnorm);
        for (size_t i = 0; i < n; ++i) fscale += f[i] * f[i];
        fscale = sqrt(fscale);
        if (g0norm < 0) g0norm = gnorm;
        double scale = fmax(g0norm, fscale);
        last_rel = scale > 0 ? gnorm / scale : 0;
        if (s->n_free == 0 || gnorm <= w->def.newton_tolerance * scale || gnorm == 0) {
            converged = 1;
            break;
        }
        st = factorize(w, s, cM, cD, err);
        /* (the structured solver may find indefiniteness only while solving) */
        if (st == SEM_OK) st = sem_system_solve(s, fr, fr, err);
        if (st == SEM_ERR_NUMERIC && exact) {
            /* the exact system is not positive definite (e.g. a buckled or unstable
             * equilibrium): project, for the rest of this solve */
            set_exact_hessian(s, 0);
            exact_allowed = 0;
            w->counters.exact_hessian_fallbacks++;
            for (int k = 0; k < s->n_objects; ++k)
                if ((st = sem_assemble_elastic(s->objects[k], q + s->dof_offset[k], 1, NULL, NULL,
                                               err)) != SEM_OK)
                    goto done;
            st = factorize(w, s, cM, cD, err);
            sem_system_gather_free(s, g, fr);
            if (st == SEM_OK) st = sem_system_solve(s, fr, fr, err);
        }
        if (st != SEM_OK) goto done;
        memset(dir, 0, n * sizeof(double));
        sem_system_scatter_free(s, fr, dir);
        /* along -dir: E(q - t dir) - E(q) = [V + Ec](q - t dir) - vc0 - t dir.gq + t^2/2 dir.A dir */
        quadratic_multiply(&nt, cM, dir, adir);
        double slope = 0, lin = 0, curv = 0;
        for (size_t i = 0; i < n; ++i) {
            slope -= dir[i] * g[i];
            lin += dir[i] * gq[i];
            curv += dir[i] * adir[i];
        }
        /* The Newton decrement (-slope: the decrease the step promises) below what the energy
         * resolves (1e-14 of V + Ec, or of the first iteration's decrement, the size of the
         * solve's energy change): the energy cannot judge the step, but the quadratic model is
         * exact there,
         * so the full step is taken, for as long as it halves the gradient. When it no longer
         * does, q is an equilibrium to round-off (a relative gradient cannot tell when the
         * first gradient is round-off itself, e.g. a static step that nothing moves). */
        if (it == 0) slope0 = -slope;
        int unresolved = -slope <= 1e-14 * fmax(fabs(vc0), slope0);
        if (unresolved && gnorm >= 0.5 * prev_gnorm) {
            ++it;
            converged = 1;
            break;
        }
        const double last_gnorm = prev_gnorm; /* the previous iteration's */
        prev_gnorm = gnorm;
        double step = 1.0, dE = INFINITY;
        if (barrier) {
            /* the barrier model: no step takes a surface through another (contact_world.h) */
            double t_max = 1;
            if ((st = sem_contact_max_step(w->contact, s, q, dir, -1.0, &t_max, err)) != SEM_OK) goto done;
            if (!(t_max > 0)) {
                st = sem_error_set(err, SEM_ERR_NUMERIC,
                                   "contact (barrier): two surfaces touch at t = %g; no step keeps them apart", t1);
                goto done;
            }
            step = t_max;
        }
        for (int ls = 0; ls < 40; ++ls) {
            for (size_t i = 0; i < n; ++i) qtry[i] = q[i] - step * dir[i];
            dE = nonquadratic(&nt, qtry) - vc0 - step * lin + 0.5 * step * step * curv;
            /* (or, valid, a change the non-quadratic part's round-off cannot resolve) */
            if (dE <= 1e-4 * step * slope || (isfinite(dE) && (unresolved || fabs(dE) <= 1e-14 * fabs(vc0))))
                break;
            step *= 0.5;
        }
        /* no step along the Newton direction lowers the energy (the potential jumps there,
         * or the direction is not one of descent): the step is not taken, and the solve
         * stops unconverged rather than accept a higher energy */
        if (isfinite(dE) && !(dE <= 1e-4 * step * slope) && !unresolved && !(fabs(dE) <= 1e-14 * fabs(vc0))) {
            if (w->def.advanced.trace_newton && w->def.log)
                w->def.log(w->def.log_user, 0, "newton: the line search found no lower energy");
            search_failed = 1;
            break;
        }
        full_steps = step == 1.0 ? full_steps + 1 : 0;
        double dir_max = 0; /* the Newton step's largest move; the step taken is step x it */
        for (size_t i = 0; i < n; ++i) dir_max = fmax(dir_max, fabs(dir[i]));
        const double dmax = step * dir_max;
        if (w->def.advanced.trace_newton && w->def.log) {
            char line[256];
            snprintf(line, sizeof line, "newton it %d: |g| %.6g dE %.6g step %g slope %g dmax %g", it, gnorm,
                     dE, step, slope, dmax);
            w->def.log(w->def.log_user, 0, line);
        }
        if (!isfinite(dE)) {
            st = sem_error_set(err, SEM_ERR_NUMERIC,
                               "Newton line search found no valid configuration at t = %g", t1);
            goto done;
        }
        memcpy(q, qtry, n * sizeof(double));
        /* stalled at round-off: the energy cannot decrease any more; or a full Newton step
         * (the quadratic model trusted) that moves no coordinate by more than 1e-13 of the
         * largest: q is the solution to the round-off of q itself (an object at rest with
         * nothing acting on it, whose gradient is round-off from its first iteration) */
        if (dmax <= 1e-14 * (1.0 + fabs(q[0])) || (step == 1.0 && dmax <= 1e-13 * qscale) ||
            (barrier && step == 1.0 && dmax <= BARRIER_NEWTON_MOVE * size && gnorm > 0.1 * last_gnorm)) {
            ++it;
            converged = 1;
            break;
        }
        /* stalled at the gradient's round-off: Newton steps that would move no coordinate by
         * more than NEWTON_STALL_MOVE of the largest coordinate, NEWTON_STALL_ITERATIONS in a
         * row without halving the gradient. Large CAD models far from the origin compute their
         * gradient to about 1e-7 of its scale (corpus occt_c3d_subfigures: 22 m at 23 m from
         * the origin, E 1.3e7: relative gradient 2.4e-7 against the 1e-8 tolerance while its
         * steps moved it by 2e-11 of its size), so the relative tolerance cannot be met. A
         * resting contact between objects stalls the same way with partial steps: springs
         * switch on and off between iterates (d = thickness is a kink of the C1 penalty), the
         * line search takes 1/128 to 1/512 of Newton steps of a few nanometres, and the
         * gradient stays at 4e-8 to 5e-6 of its first value (two 0.4 m rubber boxes stacked,
         * tests/test_contact.c). */
        if (dir_max <= NEWTON_STALL_MOVE * qscale) {
            if (gnorm < 0.5 * stall_gnorm) {
                stall_gnorm = gnorm;
                stalled = 0;
            } else if (++stalled >= NEWTON_STALL_ITERATIONS) {
                ++it;
                converged = 1;
                w->counters.newton_stalls++;
                break;
            }
        } else {
            stall_gnorm = INFINITY;
            stalled = 0;
        }
    }
    w->last_iterations = it;
    w->counters.newton_iterations += it;
    if (!converged) {
        if (!w->def.accept_unconverged) {
            st = sem_error_set(err, SEM_ERR_NUMERIC,
                               "%s did not converge in %d Newton iterations at t = %g (relative gradient %.2g, "
                               "tolerance %.2g): %s; set integrator.accept_unconverged to keep such steps",
                               dynamic ? "the implicit Euler step" : "the static solve", it, t1, last_rel,
                               w->def.newton_tolerance,
                               search_failed ? "no step along Newton's direction lowered the energy (a contact "
                                               "potential that jumps, or a Hessian far from the energy's)"
                                             : "no equilibrium was found (a part free to move: unpinned, or "
                                               "zero-energy modes; or loads too large for the material)");
            goto done;
        }
        w->counters.unconverged_solves++;
        if (w->def.log) {
            char line[256];
            snprintf(line, sizeof line,
                     "Newton did not converge in %d iterations at t = %g (relative gradient %.2g); kept "
                     "(accept_unconverged)", it, t1, last_rel);
            w->def.log(w->def.log_user, 1, line);
        }
    }
    if ((st = sem_runaway_check_finite(q, n, t1, err)) != SEM_OK) goto done;
    for (int k = 0; k < s->n_objects; ++k) {
        sem_object *o = s->objects[k];
        size_t off = s->dof_offset[k], no = 3 * (size_t)o->n_ctrl;
        if (dynamic)
            for (size_t i = 0; i < no; ++i) o->v[i] = (q[off + i] - qn[off + i]) / h;
        else
            memset(o->v, 0, no * sizeof(double));
    }
done:
    set_exact_hessian(s, 0);
    /* the objects take the last iterate, also when the solve failed */
    if (gathered)
        for (int k = 0; k < s->n_objects; ++k)
            memcpy(s->objects[k]->q, q + s->dof_offset[k], 3 * (size_t)s->objects[k]->n_ctrl * sizeof(double));
    SEM_FREE_ALL(q, qn, qpred, f, g, tmp, dq, qtry, dir, gq, adir, fr);
    return st;
}
