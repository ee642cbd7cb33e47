/*
 * barrier.h - the log barrier of one pair of surface primitives (internal to src/contact/).
 *
 * IPC's barrier (Li et al. 2020, Eq. 6) on the distance d between two primitives:
 *
 *     b(d) = -(d - dhat)^2 ln(d / dhat)   for 0 < d < dhat,   0 for d >= dhat,
 *
 * C2 at dhat (energy, force and stiffness start at zero), infinite at d = 0: a configuration
 * where two surfaces touch has infinite energy, so a minimizer whose every step is checked
 * for collisions (ccd.h) keeps them apart. b'(d) < 0 and b''(d) > 0 on (0, dhat): the
 * energy kappa b(d(x)) has the gradient kappa b' n (n = grad d, a unit vector) and the PSD
 * part of its Hessian kappa b'' n n^T (the distance's own curvature left out, as the
 * penalty's, penalty.h).
 *
 * Edge-edge distances are not smooth where the edges turn parallel (the closest points jump
 * along them); IPC multiplies their barrier by a mollifier of x = |e0 x e1|^2 that goes from
 * 0 at parallel edges to 1 at x >= eps_x (Li et al. 2020, Sec. 4.3), eps_x = 1e-3 |e0|^2
 * |e1|^2 at rest: parallel edges are kept apart by the point-triangle pairs of their
 * triangles instead.
 */
#ifndef SEM_CONTACT_BARRIER_H
#define SEM_CONTACT_BARRIER_H

/* b(d); *db = b'(d), *d2b = b''(d) (either may be NULL). 0 and 0, 0 for d >= dhat;
 * +inf for d <= 0. */
double sem_barrier(double d, double dhat, double *db, double *d2b);

/* The edge-edge mollifier of edges a0-a1 and b0-b1 (eps_x as above, from rest lengths):
 * its value, and with grad (4 x 3, may be NULL) its gradient in a0, a1, b0, b1. */
double sem_edge_mollifier(const double a0[3], const double a1[3], const double b0[3], const double b1[3],
                          double eps_x, double grad[4][3]);

#endif
