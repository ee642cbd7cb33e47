/*
 * seam.c - moving the seam of a closed surface (geometry/seam.h).
 *
 * Why. A CAD file may trim a closed surface (a torus, a cylinder, a surface of revolution)
 * with a loop that crosses the surface's seam: its (u,v) curves run continuously over, say,
 * u in [-pi/2, pi/2] while the surface's domain is [0, 2 pi] (corpus occt_torus_periodic),
 * or a model-space loop unwraps that way when it is projected. Open CASCADE takes such
 * parameters modulo the period. Our trim regions and samples live in the domain rectangle,
 * so instead the surface is given a domain that holds the loop: the same surface, cut at the
 * new seam and put together again the other way round. Nothing is approximated: knot
 * insertion (Boehm) is exact in homogeneous coordinates, and the pieces are the surface's
 * own control points.
 *
 * How. Along the direction, the net is a family of curves (one per row across). The knots
 * at the new seam, and at the old domain ends when the knot vector runs past them (an
 * unclamped periodic surface), are inserted up to multiplicity p, so that each is interpolated
 * by one column (the column R(t) = r + m - p - 1 at a knot of first index r and multiplicity
 * m >= p, the last column L(t) = r - 1 of the piece that ends there). The piece before the
 * new seam, [u0, at], and the piece after it, [at, u1], are clamped B-splines of their own;
 * the new net is the second followed by the first, one of them shifted by the period, with
 * the old seam between them as a knot of multiplicity p + 1 (both of its columns kept: they
 * are equal on a closed surface, and keeping both avoids assuming the weights agree).
 */
#include "geometry/seam.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/limits.h"
#include "sem/nurbs.h"
#include "util/free_all.h"

/* Rows of homogeneous points along one direction: row r's point i at H + 4 (r n + i). */
typedef struct family {
    int p, n, m;
    double *U; /* n + p + 1 */
    double *H;
} family;

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                (a[2] - b[2]) * (a[2] - b[2]));
}

int sem_surface_is_closed(const sem_surface *s, int dir, double tol)
{
    for (int k = 0; k <= 8; ++k) {
        double a[3], b[3];
        if (dir == 0) {
            double v = s->v0 + (s->v1 - s->v0) * k / 8.0;
            sem_surface_eval(s, s->u0, v, a, NULL, NULL, NULL);
            sem_surface_eval(s, s->u1, v, b, NULL, NULL, NULL);
        } else {
            double u = s->u0 + (s->u1 - s->u0) * k / 8.0;
            sem_surface_eval(s, u, s->v0, a, NULL, NULL, NULL);
            sem_surface_eval(s, u, s->v1, b, NULL, NULL, NULL);
        }
        if (!(dist3(a, b) <= tol)) return 0;
    }
    return 1;
}

static int multiplicity(const family *f, double t, int *first)
{
    int m = 0;
    *first = -1;
    for (int i = 0; i < f->n + f->p + 1; ++i)
        if (f->U[i] == t) {
            if (*first < 0) *first = i;
            m++;
        }
    return m;
}

/* Inserts t once (Boehm): row points Q_i = P_i (i <= k - p), a_i P_i + (1 - a_i) P_{i-1}
 * (k - p < i <= k), P_{i-1} (i > k), with U_k <= t < U_{k+1}. 0 when out of memory. */
static int insert_once(family *f, double t)
{
    int p = f->p, n = f->n;
    int k = p;
    while (k < n - 1 && f->U[k + 1] <= t) ++k;
    double *U = malloc((size_t)(n + p + 2) * sizeof *U);
    double *H = malloc((size_t)f->m * (size_t)(n + 1) * 4 * sizeof *H);
    if (!U || !H) {
        free(U);
        free(H);
        return 0;
    }
    for (int i = 0; i <= k; ++i) U[i] = f->U[i];
    U[k + 1] = t;
    for (int i = k + 1; i <= n + p; ++i) U[i + 1] = f->U[i];
    for (int r = 0; r < f->m; ++r) {
        const double *P = f->H + 4 * (size_t)r * (size_t)n;
        double *Q = H + 4 * (size_t)r * (size_t)(n + 1);
        for (int i = 0; i <= n; ++i) {
            if (i <= k - p) {
                memcpy(Q + 4 * i, P + 4 * i, 4 * sizeof *Q);
            } else if (i > k) {
                memcpy(Q + 4 * i, P + 4 * (i - 1), 4 * sizeof *Q);
            } else {
                double a = (t - f->U[i]) / (f->U[i + p] - f->U[i]);
                for (int d = 0; d < 4; ++d) Q[4 * i + d] = a * P[4 * i + d] + (1 - a) * P[4 * (i - 1) + d];
            }
        }
    }
    free(f->U);
    free(f->H);
    f->U = U;
    f->H = H;
    f->n = n + 1;
    return 1;
}

/* Inserts t until its multiplicity is at least p. */
static int insert_to_degree(family *f, double t)
{
    int first;
    while (multiplicity(f, t, &first) < f->p)
        if (f->n + f->p + 2 > SEM_MAX_KNOTS || !insert_once(f, t)) return 0;
    return 1;
}

/* The column that interpolates knot t from its right (R) and from its left (L). */
static int column_right(const family *f, double t)
{
    int first, m = multiplicity(f, t, &first);
    return first + m - f->p - 1;
}

static int column_left(const family *f, double t)
{
    int first;
    multiplicity(f, t, &first);
    return first - 1;
}

sem_status sem_surface_move_seam(sem_surface *s, int dir, double start, sem_error *err)
{
    double u0 = dir ? s->v0 : s->u0, u1 = dir ? s->v1 : s->u1, P = u1 - u0;
    if (!(P > 0) || !(fabs(start - u0) < P) || start == u0)
        return sem_error_set(err, SEM_ERR_INVALID, "seam: start %g is not within one period "
                                                   "of the domain [%g, %g]", start, u0, u1);
    double at = start < u0 ? start + P : start; /* the new seam, inside (u0, u1) */
    if (!(at > u0 && at < u1))
        return sem_error_set(err, SEM_ERR_INVALID, "seam: start %g rounds onto the old seam", start);
    family f;
    f.p = dir ? s->degree_v : s->degree_u;
    f.n = dir ? s->n_v : s->n_u;
    f.m = dir ? s->n_u : s->n_v;
    f.U = malloc((size_t)(f.n + f.p + 1) * sizeof *f.U);
    f.H = malloc((size_t)f.m * (size_t)f.n * 4 * sizeof *f.H);
    if (!f.U || !f.H) {
        free(f.U);
        free(f.H);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory moving a seam");
    }
    memcpy(f.U, dir ? s->knots_v : s->knots_u, (size_t)(f.n + f.p + 1) * sizeof *f.U);
    for (int r = 0; r < f.m; ++r)
        for (int i = 0; i < f.n; ++i) {
            size_t c = dir ? (size_t)r + (size_t)s->n_u * (size_t)i : (size_t)i + (size_t)s->n_u * (size_t)r;
            double w = s->weights[c], *h = f.H + 4 * ((size_t)r * (size_t)f.n + (size_t)i);
            for (int d = 0; d < 3; ++d) h[d] = s->ctrl[3 * c + d] * w;
            h[3] = w;
        }
    sem_status st = SEM_OK;
    if (!insert_to_degree(&f, at) || !insert_to_degree(&f, u0) || !insert_to_degree(&f, u1))
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory (or too many knots) moving a seam");
    /* the two pieces: A = [u0, at], B = [at, u1] */
    int a0 = st == SEM_OK ? column_right(&f, u0) : 0, a1 = st == SEM_OK ? column_left(&f, at) : 0;
    int b0 = st == SEM_OK ? column_right(&f, at) : 0, b1 = st == SEM_OK ? column_left(&f, u1) : 0;
    int na = a1 - a0 + 1, nb = b1 - b0 + 1, n = na + nb, p = f.p;
    int int_a = 0, int_b = 0;
    for (int i = 0; st == SEM_OK && i < f.n + p + 1; ++i) {
        int_a += f.U[i] > u0 && f.U[i] < at;
        int_b += f.U[i] > at && f.U[i] < u1;
    }
    if (st == SEM_OK && (a0 < 0 || b1 >= f.n || na != p + 1 + int_a || nb != p + 1 + int_b))
        st = sem_error_set(err, SEM_ERR_INVALID, "seam: the knots around the domain do not "
                                                 "split into two pieces");
    double *U = NULL, *ctrl = NULL, *weights = NULL;
    if (st == SEM_OK) {
        U = malloc((size_t)(n + p + 1) * sizeof *U);
        ctrl = malloc((size_t)n * (size_t)f.m * 3 * sizeof *ctrl);
        weights = malloc((size_t)n * (size_t)f.m * sizeof *weights);
        if (!U || !ctrl || !weights)
            st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory moving a seam");
    }
    if (st == SEM_OK) {
        /* domain [at - P, at]: B shifted down, then A; [at, at + P]: B, then A shifted up */
        int down = start < u0;
        double lo = down ? at - P : at, junction = down ? u0 : u1, hi = down ? at : at + P;
        double shift_b = down ? -P : 0, shift_a = down ? 0 : P;
        int k = 0;
        for (int i = 0; i <= p; ++i) U[k++] = lo;
        for (int i = 0; i < f.n + p + 1; ++i)
            if (f.U[i] > at && f.U[i] < u1) U[k++] = fmin(fmax(f.U[i] + shift_b, lo), junction);
        for (int i = 0; i <= p; ++i) U[k++] = junction;
        for (int i = 0; i < f.n + p + 1; ++i)
            if (f.U[i] > u0 && f.U[i] < at) U[k++] = fmin(fmax(f.U[i] + shift_a, junction), hi);
        for (int i = 0; i <= p; ++i) U[k++] = hi;
        for (int r = 0; r < f.m; ++r)
            for (int i = 0; i < n; ++i) {
                const double *h = f.H + 4 * ((size_t)r * (size_t)f.n + (size_t)(i < nb ? b0 + i : a0 + i - nb));
                size_t c = dir ? (size_t)r + (size_t)s->n_u * (size_t)i : (size_t)i + (size_t)n * (size_t)r;
                weights[c] = h[3];
                for (int d = 0; d < 3; ++d) ctrl[3 * c + d] = h[d] / h[3];
            }
        free(s->ctrl);
        free(s->weights);
        s->ctrl = ctrl;
        s->weights = weights;
        if (dir) {
            free(s->knots_v);
            s->knots_v = U;
            s->n_v = n;
            s->v0 = lo;
            s->v1 = hi;
        } else {
            free(s->knots_u);
            s->knots_u = U;
            s->n_u = n;
            s->u0 = lo;
            s->u1 = hi;
        }
        U = ctrl = weights = NULL;
    }
    SEM_FREE_ALL(U, ctrl, weights, f.U, f.H);
    return st;
}
