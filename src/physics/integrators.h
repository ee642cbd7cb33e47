/*
 * integrators.h - advancing a world in time (internal to src/physics/): sem_world_step and
 * sem_world_solve_static (integrators.c) step every system of the world; Newton's method
 * (newton.c) serves implicit Euler and statics.
 *
 *   linearly implicit Euler (the paper's):  (M + h C + h^2 K) v+ = M v + h f(q),
 *       q+ = q + h v+; one factorization and solve per step. Pinned points move to their
 *       prescriptions: their velocities enter the right-hand side through A_fp v_p.
 *   implicit Euler: Newton on the incremental potential
 *       E(q) = 1/(2h^2) |q - q_n - h v_n|_M^2 + V(q) + gamma q^T M_eps q - f^T q
 *       (+ Rayleigh damping as a potential), backtracking line search on E (an inverted
 *       neo-Hookean element has infinite energy and is rejected), converged to a relative
 *       gradient tolerance.
 *   static: the same Newton on V(q) + gamma q^T M_eps q - f^T q.
 * Rayleigh damping C = a M + b K0 (K0: the rest stiffness).
 *
 * Hessians. Every per-point Hessian is projected to positive semi-definite before
 * assembly, for the linearly implicit step too: the paper's neo-Hookean Hessian becomes
 * indefinite under compression, and then M + h^2 K can lose definiteness and Cholesky
 * fails. Newton switches to the exact Hessian once two steps in a row were full: the
 * clamped eigenvalues are the compressed fibres' geometric stiffness, and without them
 * Newton only converges linearly (by about half per iteration on the bent cantilever). If
 * the exact system is not positive definite, Newton falls back to the projected one for
 * the rest of that solve (the world counts these fallbacks). The world setting
 * advanced.projected_hessian keeps the projected one throughout.
 *
 * The integrators see a system (system.h) and its objects' terms (assembly.h, loads.h),
 * never the linear solver: fill, factorize and solve go through the system.
 */
#ifndef SEM_PHYSICS_INTEGRATORS_H
#define SEM_PHYSICS_INTEGRATORS_H

#include "system.h"
#include "world.h"

/* Newton on the system's E (h > 0: implicit Euler from t1 - h to t1; h == 0: statics with
 * the loads and prescriptions of t1). Moves the objects' q (also when it fails) and sets
 * their velocities ((q - q_n) / h, or zero for statics). */
sem_status sem_newton_solve(sem_world *w, sem_system *s, double h, double t1, int max_iterations,
                            sem_error *err);

#endif
