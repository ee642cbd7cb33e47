/*
 * object_frame.c - the object's own frame, in which the volume quadrature is laid (Sec. 6.3).
 *
 * Why: the paper shoots its ray grid along the world x axis. The same object turned in its
 * file then gets another quadrature: a beam along y is sampled across its length by the
 * "along the ray" points and along its length by the few rays of the grid, and a beam at
 * 30 degrees loses volume at its slanted ends. A grid laid in a frame that turns with the
 * object gives the same quadrature, turned, however the object lies in its file.
 *
 * The frame (rest state, model coordinates):
 * - centre: the area centroid of the tessellated surface;
 * - axes: the eigenvectors of the surface's second moment C = int (x - c)(x - c)^T dA, summed
 *   per triangle by the rule on its edge midpoints (exact for quadratics on a triangle);
 * - degenerate eigenvalues (a beam with a square cross-section, a cube, a cylinder, a
 *   sphere) leave the axes of that eigenspace to round-off. There the axes are fixed by the
 *   geometry instead: the direction u of the plane (or of space) that maximizes the fourth
 *   moment of the surface normals f(u) = sum_t A_t (n_t . u)^4, i.e. the direction most
 *   faces look along (a box's face normals). f turns with the object, so the choice does
 *   too. In a plane f is a trigonometric polynomial of degree 4 in the angle: sampled at 1
 *   degree, then refined by golden-section search. In space (all three equal) the
 *   candidates are the normals of the 32 largest triangles. Where f is flat as well (a
 *   cylinder's cross-section), every choice is equivalent by symmetry and the eigen-solver's
 *   is kept;
 * - order: axes by decreasing extent of the tessellation in the frame (ties: the eigen
 *   order), right-handed;
 * - bounds: the tessellation's extent along each axis, relative to the centre.
 * The frame depends on the tessellation, which is in parameter space, so turning the
 * control points turns the frame exactly (to rounding).
 */
#include <lapacke.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/vector3.h"
#include "steps.h"

/* Relative gap below which two eigenvalues of C count as equal. */
#define FRAME_DEGENERATE 1e-6
/* Relative spread of f below which a direction search has no preferred direction. */
#define FRAME_FLAT 1e-9

static void normalize3(double *a)
{
    double n = sqrt(dot3(a, a));
    if (n > 0)
        for (int k = 0; k < 3; ++k) a[k] /= n;
}

/* f(u) = sum A (n . u)^4 */
static double normal_moment(int n, const double *area, const double *normal, const double u[3])
{
    double f = 0;
    for (int t = 0; t < n; ++t) {
        double c = dot3(normal + 3 * (size_t)t, u);
        c *= c;
        f += area[t] * c * c;
    }
    return f;
}

/* f(cos a p + sin a q) from the sums S_k (see best_in_plane). */
static double plane_moment(const double S[5], double a)
{
    static const double binom[5] = {1, 4, 6, 4, 1};
    double c = cos(a), s = sin(a), cp[5], sp[5];
    cp[0] = sp[0] = 1;
    for (int k = 1; k < 5; ++k) {
        cp[k] = cp[k - 1] * c;
        sp[k] = sp[k - 1] * s;
    }
    double v = 0;
    for (int k = 0; k < 5; ++k) v += binom[k] * cp[4 - k] * sp[k] * S[k];
    return v;
}

/* In the plane spanned by orthonormal p, q: the angle maximizing f(cos a p + sin a q), from
 * the five sums S_k = sum A (n.p)^(4-k) (n.q)^k. Writes the chosen axes to p, q (rotated);
 * leaves them when f is flat. */
static void best_in_plane(int n, const double *area, const double *normal, double p[3], double q[3])
{
    double S[5] = {0, 0, 0, 0, 0};
    for (int t = 0; t < n; ++t) {
        double a = dot3(normal + 3 * (size_t)t, p), b = dot3(normal + 3 * (size_t)t, q);
        double a2 = a * a, b2 = b * b, w = area[t];
        S[0] += w * a2 * a2;
        S[1] += w * a2 * a * b;
        S[2] += w * a2 * b2;
        S[3] += w * a * b2 * b;
        S[4] += w * b2 * b2;
    }
    const int samples = 180;
    double best = -INFINITY, worst = INFINITY, best_a = 0;
    for (int k = 0; k < samples; ++k) {
        double a = M_PI * k / samples, v = plane_moment(S, a);
        if (v > best) {
            best = v;
            best_a = a;
        }
        worst = fmin(worst, v);
    }
    if (!(best > 0) || (best - worst) <= FRAME_FLAT * best) return;
    /* golden-section search in the bracket around the best sample */
    double lo = best_a - M_PI / samples, hi = best_a + M_PI / samples;
    const double g = 0.5 * (sqrt(5.0) - 1.0);
    double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = plane_moment(S, x1), f2 = plane_moment(S, x2);
    for (int it = 0; it < 60; ++it) {
        if (f1 >= f2) {
            hi = x2;
            x2 = x1;
            f2 = f1;
            x1 = hi - g * (hi - lo);
            f1 = plane_moment(S, x1);
        } else {
            lo = x1;
            x1 = x2;
            f1 = f2;
            x2 = lo + g * (hi - lo);
            f2 = plane_moment(S, x2);
        }
    }
    double a = 0.5 * (lo + hi), c = cos(a), s = sin(a);
    double np[3], nq[3];
    for (int k = 0; k < 3; ++k) {
        np[k] = c * p[k] + s * q[k];
        nq[k] = -s * p[k] + c * q[k];
    }
    memcpy(p, np, sizeof np);
    memcpy(q, nq, sizeof nq);
}

/* Some unit vector perpendicular to unit u. */
static void perpendicular(const double u[3], double p[3])
{
    int k = fabs(u[0]) <= fabs(u[1]) && fabs(u[0]) <= fabs(u[2]) ? 0 : (fabs(u[1]) <= fabs(u[2]) ? 1 : 2);
    double e[3] = {0, 0, 0};
    e[k] = 1;
    cross3(u, e, p);
    normalize3(p);
}

/* All three second moments equal: the normal of one of the largest triangles maximizing f. */
static void best_in_space(int n, const double *area, const double *normal, double u[3])
{
    enum { CANDIDATES = 32 };
    int top[CANDIDATES], m = 0;
    for (int t = 0; t < n; ++t) {
        if (!(area[t] > 0)) continue;
        int j = m < CANDIDATES ? m++ : CANDIDATES;
        if (j == CANDIDATES && !(area[t] > area[top[CANDIDATES - 1]])) continue;
        if (j == CANDIDATES) j = CANDIDATES - 1;
        while (j > 0 && area[top[j - 1]] < area[t]) {
            top[j] = top[j - 1];
            --j;
        }
        top[j] = t;
    }
    double best = -INFINITY;
    for (int k = 0; k < m; ++k) {
        double v = normal_moment(n, area, normal, normal + 3 * (size_t)top[k]);
        if (v > best * (1 + 1e-12)) {
            best = v;
            memcpy(u, normal + 3 * (size_t)top[k], 3 * sizeof *u);
        }
    }
}

sem_status sem_step_frame(const sem_raycast_scene *scene, sem_discretization *d, sem_error *err)
{
    const double *tri, *area, *normal;
    int n = sem_raycast_triangles(scene, &tri, &area, &normal, NULL);
    memset(d->frame_axes, 0, sizeof d->frame_axes);
    for (int k = 0; k < 3; ++k) d->frame_axes[4 * k] = 1.0;
    memset(d->frame_center, 0, sizeof d->frame_center);
    if (n <= 0 || !tri || !area || !normal)
        return sem_error_set(err, SEM_ERR_INVALID, "frame: the model has no surface to sample");

    /* centre */
    double A = 0, c[3] = {0, 0, 0};
    for (int t = 0; t < n; ++t) {
        const double *v = tri + 9 * (size_t)t;
        A += area[t];
        for (int k = 0; k < 3; ++k) c[k] += area[t] * (v[k] + v[3 + k] + v[6 + k]) / 3.0;
    }
    if (!(A > 0) || !isfinite(A))
        return sem_error_set(err, SEM_ERR_INVALID, "frame: the model's surface has no area");
    for (int k = 0; k < 3; ++k) c[k] /= A;

    /* second moment about the centre (edge-midpoint rule, exact for quadratics) */
    double C[9] = {0};
    for (int t = 0; t < n; ++t) {
        const double *v = tri + 9 * (size_t)t;
        for (int e = 0; e < 3; ++e) {
            const double *a = v + 3 * e, *b = v + 3 * ((e + 1) % 3);
            double m[3];
            for (int k = 0; k < 3; ++k) m[k] = 0.5 * (a[k] + b[k]) - c[k];
            for (int i = 0; i < 3; ++i)
                for (int j = 0; j < 3; ++j) C[3 * i + j] += area[t] / 3.0 * m[i] * m[j];
        }
    }
    double w[3];
    lapack_int info = LAPACKE_dsyev(LAPACK_ROW_MAJOR, 'V', 'U', 3, C, 3, w);
    double axis[3][3]; /* columns of C are eigenvectors, ascending eigenvalues */
    for (int a = 0; a < 3; ++a)
        for (int k = 0; k < 3; ++k) axis[a][k] = info == 0 ? C[3 * k + a] : (a == k ? 1.0 : 0.0);
    if (info == 0 && w[2] > 0) {
        int eq01 = (w[1] - w[0]) <= FRAME_DEGENERATE * w[2];
        int eq12 = (w[2] - w[1]) <= FRAME_DEGENERATE * w[2];
        if (eq01 && eq12) {
            double u[3] = {axis[2][0], axis[2][1], axis[2][2]}, p[3], q[3];
            best_in_space(n, area, normal, u);
            normalize3(u);
            perpendicular(u, p);
            cross3(u, p, q);
            best_in_plane(n, area, normal, p, q);
            memcpy(axis[0], u, sizeof u);
            memcpy(axis[1], p, sizeof p);
            memcpy(axis[2], q, sizeof q);
        } else if (eq01) {
            best_in_plane(n, area, normal, axis[0], axis[1]);
        } else if (eq12) {
            best_in_plane(n, area, normal, axis[1], axis[2]);
        }
    }

    /* extents along each axis; order by decreasing extent (stable) */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t k = 0; k < 3 * (size_t)n; ++k) {
        const double *v = tri + 3 * k;
        double r[3] = {v[0] - c[0], v[1] - c[1], v[2] - c[2]};
        for (int a = 0; a < 3; ++a) {
            double x = dot3(axis[a], r);
            lo[a] = fmin(lo[a], x);
            hi[a] = fmax(hi[a], x);
        }
    }
    int order[3] = {0, 1, 2};
    for (int i = 1; i < 3; ++i)
        for (int j = i; j > 0 && hi[order[j]] - lo[order[j]] > hi[order[j - 1]] - lo[order[j - 1]]; --j) {
            int t = order[j];
            order[j] = order[j - 1];
            order[j - 1] = t;
        }
    for (int a = 0; a < 3; ++a) {
        memcpy(d->frame_axes + 3 * a, axis[order[a]], 3 * sizeof(double));
        d->frame_lo[a] = lo[order[a]];
        d->frame_hi[a] = hi[order[a]];
    }
    /* right-handed: e2 = e0 x e1 (flipping an axis does not move the grid's lines) */
    double e2[3];
    cross3(d->frame_axes, d->frame_axes + 3, e2);
    if (dot3(e2, d->frame_axes + 6) < 0) {
        for (int k = 0; k < 3; ++k) d->frame_axes[6 + k] = -d->frame_axes[6 + k];
        double t = d->frame_lo[2];
        d->frame_lo[2] = -d->frame_hi[2];
        d->frame_hi[2] = -t;
    }
    memcpy(d->frame_center, c, sizeof c);
    return SEM_OK;
}

void sem_frame_coordinates(const sem_discretization *d, const double X[3], double Y[3])
{
    double r[3] = {X[0] - d->frame_center[0], X[1] - d->frame_center[1], X[2] - d->frame_center[2]};
    int have = 0;
    for (int k = 0; k < 9; ++k) have |= d->frame_axes[k] != 0.0;
    for (int a = 0; a < 3; ++a) Y[a] = have ? dot3(d->frame_axes + 3 * a, r) : r[a];
}

/* qsort comparator for doubles */
static int double_cmp(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

void sem_part_frame_boxes(const sem_discretization *d, double *box)
{
    for (int i = 0; i < d->n_parts; ++i)
        for (int e = 0; e < 3; ++e) {
            box[6 * i + e] = INFINITY;
            box[6 * i + 3 + e] = -INFINITY;
        }
    for (int k = 0; k < d->n_samples; ++k) {
        double Y[3];
        sem_frame_coordinates(d, d->sample_X + 3 * (size_t)k, Y);
        double *b = box + 6 * (size_t)d->sample_part[k];
        for (int e = 0; e < 3; ++e) {
            b[e] = fmin(b[e], Y[e]);
            b[3 + e] = fmax(b[3 + e], Y[e]);
        }
    }
}

sem_status sem_part_sizes(const sem_discretization *d, double *size, double *median)
{
    int np = d->n_parts;
    double *box = malloc(6 * (size_t)(np > 0 ? np : 1) * sizeof *box);
    double *sorted = malloc((size_t)(np > 0 ? np : 1) * sizeof *sorted);
    if (!box || !sorted) {
        free(box);
        free(sorted);
        return SEM_ERR_NOMEM;
    }
    sem_part_frame_boxes(d, box);
    int n = 0;
    for (int i = 0; i < np; ++i) {
        const double *b = box + 6 * (size_t)i;
        double s2 = 0;
        for (int e = 0; e < 3; ++e) s2 += (b[3 + e] - b[e]) * (b[3 + e] - b[e]);
        double s = b[3] >= b[0] ? sqrt(s2) : 0.0; /* a part without samples: 0 */
        if (size) size[i] = s;
        if (s > 0) sorted[n++] = s;
    }
    if (n > 0) qsort(sorted, (size_t)n, sizeof *sorted, double_cmp);
    if (median) *median = n > 0 ? sorted[n / 2] : 0.0;
    free(box);
    free(sorted);
    return SEM_OK;
}
