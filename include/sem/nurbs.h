/*
 * sem/nurbs.h - B-spline and NURBS evaluation (paper Sec. 4, Eq. 1-2).
 *
 * Basis functions follow Piegl & Tiller, The NURBS Book (A2.1 FindSpan, A2.3 DersBasisFuns),
 * valid for any degree, clamped or unclamped knot vectors, repeated interior knots and
 * parameter ranges that do not start at 0. A surface point is x(u,v) = J(u,v) q where the
 * row J has (degree_u+1)(degree_v+1) non-zeros per coordinate: sem_surface_basis returns
 * them with their control point indices.
 */
#ifndef SEM_NURBS_H
#define SEM_NURBS_H

#include "sem/model.h"

#ifdef __cplusplus
extern "C" {
#endif

#define SEM_MAX_DEGREE 31

/* Index of the knot span containing t: knots[span] <= t < knots[span+1], with
 * degree <= span <= n_ctrl-1 (t at the end of the range goes to the last non-empty span). */
int sem_bspline_span(int degree, int n_ctrl, const double *knots, double t);

/* Non-rational basis functions N_{span-degree..span} and derivatives up to n_derivs:
 * ders[k*(degree+1) + r] = d^k/dt^k N_{span-degree+r}(t). n_derivs <= 2 needs no
 * workspace beyond the stack; any n_derivs <= degree+1 is allowed (higher ones are 0). */
void sem_bspline_basis(int degree, const double *knots, int span, double t, int n_derivs,
                       double *ders);

/* Rational surface point and derivatives. Any output pointer may be NULL.
 * d2 = {x_uu, x_uv, x_vv} (9 doubles). */
void sem_surface_eval(const sem_surface *s, double u, double v, double point[3], double du[3],
                      double dv[3], double d2[9]);

/* Rational basis row: the non-zero phi_ij(u,v) (Eq. 1) and optionally their u- and
 * v-derivatives. index[k] is the control point index (i + n_u*j). Arrays need
 * (degree_u+1)*(degree_v+1) entries. Returns the count. */
int sem_surface_basis(const sem_surface *s, double u, double v, int *index, double *phi,
                      double *phi_u, double *phi_v);

/* The same row from precomputed spans and non-rational basis values (Nu, Nv as written by
 * sem_bspline_basis with at least one derivative when phi_u or phi_v is wanted): for
 * callers that evaluate many points on one grid of (u, v) values. */
int sem_surface_basis_from_spans(const sem_surface *s, int su, const double *Nu, int sv,
                                 const double *Nv, int *index, double *phi, double *phi_u,
                                 double *phi_v);

/* Unit normal (x_u x x_v normalised); at a collapsed edge it falls back to a nearby
 * non-degenerate direction. Returns |x_u x x_v| at (u,v) (area element). */
double sem_surface_normal(const sem_surface *s, double u, double v, double normal[3]);

/* Rational curve point and first derivative (either may be NULL). */
void sem_curve_eval(const sem_curve *c, double t, double point[3], double d1[3]);

/* Gauss-Legendre and Gauss-Lobatto rules on [-1,1] with n points (n <= 64 / 2 <= n <= 64). */
void sem_gauss_legendre(int n, double *x, double *w);
void sem_gauss_lobatto(int n, double *x, double *w);

/* Distinct knot values inside [t0,t1] that bound non-empty spans: writes up to
 * max_breaks values, returns the count (>= 2 for a valid range). */
int sem_knot_breaks(int degree, int n_ctrl, const double *knots, double t0, double t1,
                    double *breaks, int max_breaks);

#ifdef __cplusplus
}
#endif
#endif
