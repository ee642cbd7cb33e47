/*
 * ccd.h - continuous collision detection: how far two primitives moving linearly can go
 * before they touch (internal to src/contact/).
 *
 * Additive CCD (Li, Kaufman, Jiang, "Codimensional Incremental Potential Contact", 2021,
 * Algorithm 1). Over a step the vertices move as x_i + t p_i, t in [0, t_max]. With the
 * common motion taken out, the distance between the primitives shrinks no faster than
 * l_p = |p_point| + max |p_triangle| (point-triangle) or max |p_edge a| + max |p_edge b|
 * (edge-edge) per unit t, so advancing by (1 - s) d / l_p, then by 0.9 d / l_p at each new
 * distance d, cannot make them touch. The advance stops when the distance falls below
 * s d_0 (s = SEM_CCD_SEPARATION of the distance at t = 0) and returns the t reached before
 * that: at the returned t the pair is at least s d_0 apart, never in contact. Conservative
 * by construction (it may stop earlier than the true first contact, never later), and a
 * pair at distance 0 at t = 0 returns 0. The number of advances is capped; a pair that
 * reaches the cap returns the t reached, which is still safe.
 */
#ifndef SEM_CONTACT_CCD_H
#define SEM_CONTACT_CCD_H

#define SEM_CCD_SEPARATION 0.1
#define SEM_CCD_MAX_ADVANCES 20000

/* The distance of p to triangle (a, b, c); a degenerate one (a sliver whose area is below
 * 1e-10 of its longest edge squared: a pole of a sphere opening up) as its three edges. */
double sem_ccd_triangle_distance(const double p[3], const double a[3], const double b[3], const double c[3]);
/* Is triangle (a, b, c) degenerate in that sense? */
int sem_ccd_degenerate(const double a[3], const double b[3], const double c[3]);

/* Point x[0] against triangle x[1], x[2], x[3], moving by p[0..3] per unit t. */
double sem_ccd_point_triangle(const double *const x[4], const double *const p[4], double t_max);
/* Edge x[0]-x[1] against edge x[2]-x[3]. */
double sem_ccd_edge_edge(const double *const x[4], const double *const p[4], double t_max);
/* A point at signed distance d (> 0) from a plane, approaching it at the normal speed
 * v (< 0: towards it): the exact time to s d; t_max when it does not approach. */
double sem_ccd_point_plane(double d, double v, double t_max);

#endif
