/*
 * penalty.h - the contact spring of one point (internal to src/contact/).
 *
 * A point at signed distance d from a surface (d < 0: inside) pushes back with the energy
 * E = 1/2 k (d - thickness)^2 while d < thickness, 0 beyond. E is C1 (its force starts at
 * zero), so Newton's line search sees a smooth landscape. With n = grad d (a unit vector)
 * the gradient in the point is k (d - thickness) n and the Hessian's PSD part k n n^T: the
 * term d2d/dx2 (the curvature of the distance, zero on a face) is left out, which keeps the
 * Hessian positive semi-definite as Newton and the linearly implicit step need.
 */
#ifndef SEM_CONTACT_PENALTY_H
#define SEM_CONTACT_PENALTY_H

/* Energy of the spring; *slope = dE/dd = k (d - thickness) (<= 0), 0 when inactive. */
double sem_penalty_energy(double k, double d, double thickness, double *slope);
/* H += k n n^T */
void sem_penalty_hessian(double k, const double n[3], double H[9]);

#endif
