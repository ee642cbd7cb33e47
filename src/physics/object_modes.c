/*
 * object_modes.c - zero-energy (spurious) modes of an object: the motions of the free
 * object, beyond the 6 rigid ones, that its rest-state stiffness does not resist.
 *
 * What is counted. The generalized eigenproblem K x = lambda M x of the object with every
 * control point free, K = K0 + 2 gamma M_eps (the elastic stiffness at rest plus the error
 * matrix, which holds the volume consistency term of sem_object_def.blend), M the mass
 * matrix. Its 6 rigid motions (translations, infinitesimal rotations of the control points)
 * have lambda = 0 exactly and are projected out. Every other eigenvalue is made
 * dimensionless with the object's own scale, lambda_hat = lambda rho L^2 / E (L the
 * preprocessing length, the bounding-box diagonal; E, rho the object's material): a body's
 * first elastic modes have lambda_hat above about 2 / a^2 for aspect ratio a (a free-free
 * beam: 22.4 / (12 a^2); 5e-3 at 1:20; the Table 1 models 0.01 .. 2), while a mode nothing
 * resists is zero up to round-off (1e-12 .. 1e-9) or nearly so (a motion only the error
 * energy's weak coupling resists: 1e-7 .. 1e-6 on the turned beam of test_trust.c).
 * Modes with lambda_hat < SEM_SPURIOUS_MODE_TOLERANCE (1e-5) are spurious.
 *
 * Values above 100 x that tolerance need only 4 digits (SEM_MODES_COARSE): they are reported,
 * not counted, and converging them to 1e-8 took twice the iterations (an 11,439-dof CAD part:
 * 15 iterations of 12 solves instead of ~35).
 *
 * How. Shift-invert subspace iteration (lowest_modes.c) with the shift sigma = 1e-3 E /
 * (rho L^2) and the solves through a system of the object's matrices (system.h) with every
 * control point free: a shallow copy of the object with its own free numbering, so the
 * object's own system (pins, factorization) is untouched. A spurious mode moves some parts
 * against the rest; the parts holding at least a quarter of the largest part share of a
 * spurious mode's kinetic energy (x^T M x summed over their control points) are the ones
 * reported as not held.
 */
#include "world.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "assembly.h"
#include "lowest_modes.h"
#include "util/free_all.h"

enum { MODES_WANT = 8, MODES_BLOCK = 12, MODES_MAX_ITER = 80 };

typedef struct modes_ctx {
    sem_object *o;     /* the all-free copy */
    sem_system *s;
    double *fa, *fb;   /* free-dof scratch */
    sem_error *err;
} modes_ctx;

static int mult_M(void *u, const double *x, double *y)
{
    modes_ctx *c = u;
    sem_blocks_multiply(c->o, 1.0, 0, 0, 0, 0, x, y);
    return 0;
}

static int mult_K(void *u, const double *x, double *y)
{
    modes_ctx *c = u;
    sem_blocks_multiply(c->o, 0, c->o->gamma, 0, 1.0, 0, x, y);
    return 0;
}

static int solve_shifted(void *u, const double *b, double *x)
{
    modes_ctx *c = u;
    sem_system_gather_free(c->s, b, c->fa);
    if (sem_system_solve(c->s, c->fa, c->fb, c->err) != SEM_OK) return 1;
    sem_system_scatter_free(c->s, c->fb, x);
    return 0;
}

sem_status sem_world_object_modes(sem_world *w, int object, sem_object_modes *out, int *part_flags,
                                  sem_error *err)
{
    if (!w || !out || object < 0 || object >= w->n_objects)
        return sem_error_set(err, SEM_ERR_INVALID, "sem_world_object_modes: bad object %d", object);
    memset(out, 0, sizeof *out);
    const sem_object *o = w->objects[object];
    size_t n = 3 * (size_t)o->n_ctrl;
    if (part_flags) memset(part_flags, 0, (size_t)o->n_parts * sizeof *part_flags);
    double rho = o->mass > 0 && o->volume > 0 ? o->mass / o->volume : o->def.material.density;
    double L = o->d->length_scale > 0 ? o->d->length_scale : 1.0;
    double lref = o->def.material.youngs_modulus / (rho * L * L);
    if (n <= 6 || !(lref > 0) || !isfinite(lref)) return SEM_OK;

    sem_object tmp = *o;
    tmp.pinned = calloc((size_t)o->n_ctrl + 1, 1);
    tmp.free_index = NULL;
    tmp.system = NULL;
    sem_system *s = NULL;
    modes_ctx c = {&tmp, NULL, NULL, NULL, err};
    double *R = calloc(6 * n, sizeof *R), *vals = malloc(MODES_WANT * sizeof *vals);
    double *vec = malloc(MODES_WANT * n * sizeof *vec), *Mv = malloc(n * sizeof *Mv);
    double *share = calloc((size_t)o->n_parts + 1, sizeof *share);
    c.fa = malloc(n * sizeof(double));
    c.fb = malloc(n * sizeof(double));
    sem_status st = SEM_OK;
    if (!tmp.pinned || !R || !vals || !vec || !Mv || !share || !c.fa || !c.fb) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto done;
    }
    if ((st = sem_object_free_dofs(&tmp, err)) != SEM_OK) goto done;
    sem_object *list[1] = {&tmp};
    if ((st = sem_system_create(list, 1, w->def.solver, &s, err)) != SEM_OK) goto done;
    c.s = s;
    double sigma = 1e-3 * lref;
    /* the free object: no pins of any kind (the anchor's coefficient is 0) */
    sem_system_fill(s, sigma, 1.0, 0, 1.0, 0);
    if ((st = sem_system_factorize(s, err)) != SEM_OK) {
        /* K + sigma M is singular: motions with neither mass nor stiffness */
        if (st == SEM_ERR_NUMERIC)
            sem_error_set(err, st,
                          "some motions have neither mass nor stiffness (%d quadrature points for %d control "
                          "points, volume %.3g): the surfaces enclose too little volume (open surfaces?) or the "
                          "quadrature is too coarse (a smaller sem.spacing)",
                          o->n_quad, o->n_ctrl, o->volume);
        goto done;
    }

    /* the rigid motions of the control points, about their mean */
    double cen[3] = {0, 0, 0};
    for (int p = 0; p < o->n_ctrl; ++p)
        for (int d = 0; d < 3; ++d) cen[d] += o->q0[3 * (size_t)p + d] / o->n_ctrl;
    for (int p = 0; p < o->n_ctrl; ++p) {
        const double *x = o->q0 + 3 * (size_t)p;
        double r[3] = {x[0] - cen[0], x[1] - cen[1], x[2] - cen[2]};
        size_t i = 3 * (size_t)p;
        for (int d = 0; d < 3; ++d) R[(size_t)d * n + i + d] = 1.0;
        double *rx = R + 3 * n, *ry = R + 4 * n, *rz = R + 5 * n;
        rx[i + 1] = -r[2], rx[i + 2] = r[1];
        ry[i + 0] = r[2], ry[i + 2] = -r[0];
        rz[i + 0] = -r[1], rz[i + 1] = r[0];
    }
    sem_mode_operator op = {&c, mult_M, mult_K, solve_shifted};
    int want = n - 6 < MODES_WANT ? (int)(n - 6) : MODES_WANT;
    int block = n - 6 < MODES_BLOCK ? (int)(n - 6) : MODES_BLOCK;
    /* values far above the spurious level only need to be known to be there (4 digits) */
    int rc = sem_lowest_modes(&op, n, block, want, MODES_MAX_ITER, 100 * SEM_SPURIOUS_MODE_TOLERANCE * lref, R, 6,
                              vals, vec);
    if (rc < 0) {
        st = err && err->status != SEM_OK ? err->status
                                          : sem_error_set(err, SEM_ERR_NUMERIC, "lowest modes: the iteration failed");
        goto done;
    }
    out->converged = rc == 0;
    out->n_values = want;
    for (int k = 0; k < want; ++k) {
        out->values[k] = vals[k] / lref;
        if (!(out->values[k] < SEM_SPURIOUS_MODE_TOLERANCE)) continue;
        out->spurious++;
        /* the parts that move in it */
        const double *v = vec + (size_t)k * n;
        mult_M(&c, v, Mv);
        double total = 0;
        memset(share, 0, (size_t)o->n_parts * sizeof *share);
        for (int i = 0; i < o->n_parts; ++i)
            for (int p = o->d->part_ctrl_offset[i]; p < o->d->part_ctrl_offset[i + 1]; ++p)
                for (int d = 0; d < 3; ++d) share[i] += v[3 * (size_t)p + d] * Mv[3 * (size_t)p + d];
        for (int i = 0; i < o->n_parts; ++i) total = fmax(total, fabs(share[i]));
        if (part_flags && total > 0)
            for (int i = 0; i < o->n_parts; ++i)
                if (fabs(share[i]) >= 0.25 * total) part_flags[i] = 1;
    }
done:
    sem_system_destroy(s);
    SEM_FREE_ALL(tmp.free_index, tmp.pinned, R, vals, vec, Mv, share, c.fa, c.fb);
    return st;
}
