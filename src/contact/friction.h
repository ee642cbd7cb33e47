/*
 * friction.h - Coulomb friction of one contact as a lagged, smoothed potential (IPC: Li et
 * al. 2020, Sec. 5; internal to src/contact/).
 *
 * At the start of a step every active contact fixes its normal force lambda (its spring's
 * force at q_n), its tangent plane T (3 x 2, orthonormal) and its relative point X_n. Over
 * the step the tangential displacement u = T^T (X(q) - X_n) has the friction potential
 *     D(u) = mu lambda f0(|u|),   f0(y) = -y^3 / (3 eps^2) + y^2 / eps + eps / 3  (y < eps),
 *                                 f0(y) = y                                      (y >= eps),
 * eps = eps_v h: below the sliding speed eps_v the friction force mu lambda f1(|u|) grows
 * from zero (sticking is a very stiff spring), beyond it is exactly mu lambda against the
 * motion (Coulomb). Its Hessian mu lambda [f1(y)/y (I - u u^T/y^2) + f1'(y) u u^T/y^2] is
 * positive semi-definite for every u (f1 >= 0, f1' >= 0), so no projection is needed.
 */
#ifndef SEM_CONTACT_FRICTION_H
#define SEM_CONTACT_FRICTION_H

/* D(u) for mu_lambda = mu lambda; g (2) and H (2 x 2 row-major) its gradient and Hessian
 * (either may be NULL). */
double sem_friction_potential(double mu_lambda, const double u[2], double eps, double g[2], double H[4]);
/* mu lambda f1(|u|) / |u|: the curvature of the quadratic c |u'|^2 / 2 + const that touches
 * D at u and lies above it everywhere (D is a concave function of |u|^2, so its tangent in
 * |u|^2 bounds it from above). A Newton step that takes c I for D's Hessian minimizes that
 * bound: it lowers D even where D's own Hessian has no curvature along u (sliding), which
 * is what lets Newton cross the sticking zone, eps wide, in a few steps instead of many
 * tiny ones (contact_world.c). */
double sem_friction_curvature(double mu_lambda, const double u[2], double eps);
/* Two unit vectors T = [t1 t2], 3 x 2 row-major (coordinate k of t_c at T[2 k + c]),
 * orthogonal to the unit vector n and to each other. */
void sem_tangent_basis(const double n[3], double T[6]);

#endif
