/* test_pins.c - material pins (sem_pin_region, src/physics/pins.h; issue 28 item 1): a pin box
 * holds the material inside it, as FEM's fixed nodes do, not the control points that happen to
 * lie there.
 *
 * - the cantilever of docs/validation.md (5 x 1 x 1 m, 10 sections, static, gravity 10, E 1e6,
 *   nu 0.45), held by the material of its first centimetre (x <= 0.01: only the boundary
 *   samples of the end face lie there), deflects as the control-point clamp of the same end
 *   (the same material fixed), against the FEM reference; the anchored points stay at their
 *   rest positions to a small fraction of the deflection;
 * - a bar of trimmed planes whose control nets reach half its length beyond each end, held over
 *   its first 10 %: the old control-point box (pin.control_box) holds faces that span the whole
 *   bar, the material pin lets the far end sag as the untrimmed bar held the same way does;
 * - patch test: a rigid motion given as an affine prescription to the material of one end
 *   moves the whole free body rigidly, exactly; a stretch prescribed to all of a body's
 *   material reaches every anchored point to the anchor's compliance;
 * - the structured solver gives the q-space solver's states with a moving material pin
 *   (linearly implicit Euler to round-off, implicit Euler to Newton's tolerance);
 * - a box that holds no material is an error.
 * No shared models needed. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/simulation.h"
#include "test_util.h"

#define FEM_JSON SEM_TEST_DATA "/../../validation/fem_cantilever.json"

/* The largest distance of the anchored material (quadrature points and boundary samples in
 * box) from its target A X + b (A = identity, b = 0 when affine is NULL), measured with the
 * discretization's own Gamma rows: independent of the pins' z-space evaluation. */
static double anchored_motion(const sem_discretization *d, const double box[6], const double *q,
                              const double *affine)
{
    double worst = 0;
    for (int t = 0; t < 2; ++t) {
        const sem_csr *G = t ? &d->Gamma_samples : &d->Gamma;
        const double *XX = t ? d->sample_X : d->quad_X;
        int n = t ? d->n_samples : d->n_quad;
        for (int p = 0; p < n; ++p) {
            const double *X = XX + 3 * (size_t)p;
            if (X[0] < box[0] || X[1] < box[1] || X[2] < box[2] || X[0] > box[3] || X[1] > box[4] || X[2] > box[5])
                continue;
            double x[3] = {0, 0, 0}, T[3] = {X[0], X[1], X[2]};
            for (int e = G->row_start[p]; e < G->row_start[p + 1]; ++e)
                for (int k = 0; k < 3; ++k) x[k] += G->val[e] * q[3 * (size_t)G->col[e] + k];
            if (affine)
                for (int r = 0; r < 3; ++r)
                    T[r] = affine[4 * r] * X[0] + affine[4 * r + 1] * X[1] + affine[4 * r + 2] * X[2] + affine[4 * r + 3];
            worst = fmax(worst, sqrt((x[0] - T[0]) * (x[0] - T[0]) + (x[1] - T[1]) * (x[1] - T[1]) +
                                     (x[2] - T[2]) * (x[2] - T[2])));
        }
    }
    return worst;
}

/* A static solve of the model under gravity (0, 0, -10), E 1e6, held by `pinned` control
 * points and / or `regions`; returns q (caller frees) or NULL. */
static double *solve_static_checked(const sem_model *m, const sem_discretization *d, const unsigned char *pinned,
                                    const sem_pin_region *regions, int n_regions, sem_solver_choice solver,
                                    const char *what, sem_object_checks *checks)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.integrator = SEM_STATIC;
    wd.gravity[2] = -10;
    wd.solver = solver;
    wd.threads = 2;
    sem_world *w = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.material = sem_default_material(); /* neo-Hookean, rho 1000, E 1e6, nu 0.45 */
    od.pinned = pinned;
    od.pin_regions = regions;
    od.n_pin_regions = n_regions;
    double *q = NULL;
    if (!w || sem_world_add_object(w, &od, &err) < 0 || sem_world_solve_static(w, &err) != SEM_OK) {
        CHECK(0, "%s: %s", what, err.message);
    } else {
        size_t n = 3 * (size_t)d->n_ctrl;
        q = malloc(n * sizeof *q);
        if (q) memcpy(q, sem_world_object_q(w, 0), n * sizeof *q);
        if (checks && sem_world_object_checks(w, 0, checks, &err) != SEM_OK) CHECK(0, "%s: checks: %s", what, err.message);
    }
    sem_world_destroy(w);
    return q;
}

static double *solve_static(const sem_model *m, const sem_discretization *d, const unsigned char *pinned,
                            const sem_pin_region *regions, int n_regions, sem_solver_choice solver, const char *what)
{
    return solve_static_checked(m, d, pinned, regions, n_regions, solver, what, NULL);
}

/* Mean -u_z of the control points of the parts that lie wholly at x = L (the free end cap,
 * as test_defaults and study_deflection measure it). */
static double tip_deflection(const sem_model *m, const double *q0, const double *q, double L)
{
    size_t *off = malloc(((size_t)m->n_parts + 1) * sizeof *off);
    if (!off) return NAN;
    sem_model_part_offsets(m, off);
    double tip = 0;
    int n = 0;
    for (int p = 0; p < m->n_parts; ++p) {
        int all = 1;
        for (size_t c = off[p]; c < off[p + 1] && all; ++c) all = fabs(q0[3 * c] - L) < 1e-9;
        for (size_t c = off[p]; c < off[p + 1] && all; ++c, ++n) tip -= q[3 * c + 2] - q0[3 * c + 2];
    }
    free(off);
    return n ? tip / n : NAN;
}

/* The cantilever (10 sections) clamped at x = 0 by its control points, and held by the
 * material of its first centimetre. */
static void test_cantilever(double fem)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 10;
    bd.length = 5;
    bd.width = 1;
    bd.height = 1;
    sem_discretization *d = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1; /* Gamma at the samples, for anchored_motion */
    if (!m || sem_primitive_beam(m, &bd, &err) != SEM_OK || sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "cantilever: %s", err.message);
        sem_model_destroy(m);
        return;
    }
    size_t nc = (size_t)d->n_ctrl;
    double *q0 = malloc(3 * nc * sizeof *q0);
    unsigned char *pin = calloc(nc, 1);
    sem_model_get_q(m, q0);
    sem_cantilever_clamp(q0, nc, pin);
    const sem_pin_region clamp = {{-1, -1, -1, 0.01, 2, 2}, -1};
    double *qc = solve_static(m, d, pin, NULL, 0, SEM_SOLVER_AUTO, "control-point clamp");
    double *qm = solve_static(m, d, NULL, &clamp, 1, SEM_SOLVER_AUTO, "material pin");
    if (qc && qm) {
        double tc = tip_deflection(m, q0, qc, 5), tm = tip_deflection(m, q0, qm, 5);
        double moved = anchored_motion(d, clamp.box, qm, NULL), moved_c = anchored_motion(d, clamp.box, qc, NULL);
        printf("cantilever (10 sections, static): control-point clamp tip %.5f m (%.2f %% of FEM %.4f m), "
               "material pin (x <= 0.01) tip %.5f m (%.2f %%): %+.3f %% of the clamp's\n",
               tc, 100 * tc / fem, fem, tm, 100 * tm / fem, 100 * (tm / tc - 1));
        printf("  anchored material moved at most %.3g m (%.2g of the tip; the control-point clamp's %.3g m)\n", moved,
               moved / tm, moved_c);
        CHECK(fabs(tm / tc - 1) <= 0.01, "material pin tip %.5f vs control-point clamp %.5f", tm, tc);
        CHECK(fabs(tm / fem - 1) <= 0.12, "material pin tip %.5f vs FEM %.5f", tm, fem);
        CHECK(moved <= 2e-3 * tm, "anchored material moved %.3g m of a %.3g m deflection", moved, tm);
    }
    free(qc);
    free(qm);
    free(q0);
    free(pin);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

/* A planar face o + u a + v b (u, v in [0, 1], normal a x b) as the bilinear patch of a plane
 * reaching `ext` times the face's size beyond each edge (the control net of a CAD face
 * trimmed from a larger plane), trimmed back to the face by an outer loop in (u, v). ext = 0:
 * the untrimmed face. */
static sem_status add_face(sem_model *m, const char *name, const double o[3], const double a[3], const double b[3],
                           double ext, sem_error *err)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    const int p = 1, n = p + 1; /* bilinear: a CAD plane */
    if (sem_surface_alloc(&part.surface, p, p, n, n) != SEM_OK) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_surface *s = &part.surface;
    for (int k = 0; k < n; ++k) {
        s->knots_u[k] = s->knots_v[k] = 0;
        s->knots_u[n + k] = s->knots_v[n + k] = 1;
    }
    s->u0 = s->v0 = 0;
    s->u1 = s->v1 = 1;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            double su = -ext + (1 + 2 * ext) * i / (double)p, sv = -ext + (1 + 2 * ext) * j / (double)p;
            for (int d = 0; d < 3; ++d) s->ctrl[3 * (i + n * j) + d] = o[d] + su * a[d] + sv * b[d];
        }
    snprintf(part.name, sizeof part.name, "%s", name);
    if (ext > 0) {
        /* the outer loop: the face's rectangle in (u, v), counter-clockwise, one linear curve */
        double lo = ext / (1 + 2 * ext), hi = (1 + ext) / (1 + 2 * ext);
        const double corner[5][2] = {{lo, lo}, {hi, lo}, {hi, hi}, {lo, hi}, {lo, lo}};
        part.has_outer = 1;
        part.outer.n_curves = 1;
        part.outer.curves = calloc(1, sizeof(sem_curve));
        if (!part.outer.curves || sem_curve_alloc(&part.outer.curves[0], 1, 5) != SEM_OK) {
            sem_part_free(&part);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        sem_curve *c = &part.outer.curves[0];
        const double knots[7] = {0, 0, 1, 2, 3, 4, 4};
        memcpy(c->knots, knots, sizeof knots);
        for (int k = 0; k < 5; ++k) {
            c->ctrl[3 * k] = corner[k][0];
            c->ctrl[3 * k + 1] = corner[k][1];
            c->ctrl[3 * k + 2] = 0;
        }
        c->t0 = 0;
        c->t1 = 4;
    }
    sem_status st = sem_model_take_part(m, &part, err);
    if (st != SEM_OK) sem_part_free(&part);
    return st;
}

/* The one-section L x 1 x 1 bar of the beam primitive (same faces, same orientation), each face
 * trimmed from a plane `ext` times larger beyond each edge. */
static sem_model *bar(double L, double ext)
{
    sem_error err;
    sem_model *m = sem_model_create();
    const double o0[3] = {0, 0, 0}, oL[3] = {L, 0, 0}, oz[3] = {0, 0, 1}, oy[3] = {0, 1, 0};
    const double ex[3] = {L, 0, 0}, ey[3] = {0, 1, 0}, ez[3] = {0, 0, 1};
    if (!m || add_face(m, "end_x0", o0, ez, ey, ext, &err) != SEM_OK || add_face(m, "end_xL", oL, ey, ez, ext, &err) ||
        add_face(m, "bottom", o0, ey, ex, ext, &err) != SEM_OK || add_face(m, "top", oz, ex, ey, ext, &err) != SEM_OK ||
        add_face(m, "front", o0, ex, ez, ext, &err) != SEM_OK || add_face(m, "back", oy, ez, ex, ext, &err) != SEM_OK) {
        CHECK(0, "bar: %s", m ? err.message : "out of memory");
        sem_model_destroy(m);
        return NULL;
    }
    return m;
}

/* Control points in box (the old pin box, now pin.control_box). */
static unsigned char *control_box(const sem_model *m, const double box[6])
{
    size_t nc = sem_model_control_points(m);
    double *q = malloc(3 * nc * sizeof *q);
    unsigned char *pin = calloc(nc + 1, 1);
    if (!q || !pin) {
        free(q);
        free(pin);
        return NULL;
    }
    sem_model_get_q(m, q);
    for (size_t c = 0; c < nc; ++c) {
        const double *x = q + 3 * c;
        pin[c] = x[0] >= box[0] && x[1] >= box[1] && x[2] >= box[2] && x[0] <= box[3] && x[1] <= box[4] &&
                 x[2] <= box[5];
    }
    free(q);
    return pin;
}

/* Mean -u_z of the SEM map at the quadrature points beyond x = 0.9 L (the far end's material:
 * the trimmed bar has no end cap made of control points at x = L). */
static double far_sag(const sem_discretization *d, const double *q, double L)
{
    double s = 0, v = 0;
    for (int p = 0; p < d->n_quad; ++p) {
        if (d->quad_X[3 * (size_t)p] < 0.9 * L) continue;
        double z = 0;
        for (int e = d->Gamma.row_start[p]; e < d->Gamma.row_start[p + 1]; ++e)
            z += d->Gamma.val[e] * q[3 * (size_t)d->Gamma.col[e] + 2];
        s -= d->quad_volume[p] * (z - d->quad_X[3 * (size_t)p + 2]);
        v += d->quad_volume[p];
    }
    return v > 0 ? s / v : NAN;
}

/* The case: a bar of trimmed CAD planes pinned over its first millimetre. */
static void test_trimmed_bar(void)
{
    const double L = 5, ext = 0.5;
    /* everything up to x = 1 mm (the trimmed planes' nets start at x = -2.5) */
    const sem_pin_region held = {{-10, -10, -10, 0.001, 10, 10}, -1};
    sem_model *trimmed = bar(L, ext), *plain = bar(L, 0);
    if (!trimmed || !plain) {
        sem_model_destroy(trimmed);
        sem_model_destroy(plain);
        return;
    }
    sem_error err;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1;
    sem_discretization *dt = NULL, *dp = NULL;
    if (sem_preprocess(trimmed, &po, &dt, &err) != SEM_OK || sem_preprocess(plain, &po, &dp, &err) != SEM_OK) {
        CHECK(0, "bar: %s", err.message);
    } else {
        CHECK_REL(dt->volume, L, 0.02);
        CHECK_REL(dp->volume, L, 0.02);
        unsigned char *old_t = control_box(trimmed, held.box), *old_p = control_box(plain, held.box);
        size_t nt = 0, np = 0;
        for (int c = 0; c < dt->n_ctrl; ++c) nt += old_t[c];
        for (int c = 0; c < dp->n_ctrl; ++c) np += old_p[c];
        double *q_old = solve_static(trimmed, dt, old_t, NULL, 0, SEM_SOLVER_AUTO, "trimmed bar, control box");
        double *q_mat = solve_static(trimmed, dt, NULL, &held, 1, SEM_SOLVER_AUTO, "trimmed bar, material pin");
        double *q_ref = solve_static(plain, dp, NULL, &held, 1, SEM_SOLVER_AUTO, "untrimmed bar, material pin");
        double *q_clamp = solve_static(plain, dp, old_p, NULL, 0, SEM_SOLVER_AUTO, "untrimmed bar, control box");
        if (q_old && q_mat && q_ref && q_clamp) {
            double s_old = far_sag(dt, q_old, L), s_mat = far_sag(dt, q_mat, L), s_ref = far_sag(dp, q_ref, L);
            double s_clamp = far_sag(dp, q_clamp, L);
            printf("trimmed bar (%g x 1 x 1, bilinear planes reaching %g x beyond each edge) held over x <= %g m: "
                   "sag of the far 10 %%: control box (%zu control points, whole faces) %.4f m, material pin %.4f m; "
                   "untrimmed bar: material pin %.4f m, control box (its %zu points at x = 0) %.4f m\n",
                   L, ext, held.box[3], nt, s_old, s_mat, s_ref, np, s_clamp);
            /* the old box held the faces that span the bar: it came out rigid */
            CHECK(s_old <= 0.01 * s_clamp, "control box on the trimmed bar: sag %.4f of %.4f", s_old, s_clamp);
            /* the material pin holds the same material as the untrimmed bar's clamp */
            CHECK(fabs(s_mat / s_ref - 1) <= 0.01, "trimmed %.4f vs untrimmed %.4f (material pins)", s_mat, s_ref);
            CHECK(fabs(s_ref / s_clamp - 1) <= 0.01, "material pin %.4f vs control clamp %.4f", s_ref, s_clamp);
        }
        free(q_old);
        free(q_mat);
        free(q_ref);
        free(q_clamp);
        free(old_t);
        free(old_p);
    }
    sem_discretization_destroy(dt);
    sem_discretization_destroy(dp);
    sem_model_destroy(trimmed);
    sem_model_destroy(plain);
}

/* What a box can hold (docs/scenes.md, pin): a part has one polynomial over the whole part
 * (Eq. 7), so holding the material of a volume holds the polynomials of the parts blended there.
 * The one-section beam (its four side faces run its length) held over its first 10 % hardly
 * moves; held by a thin slab at its end face it sags as its control-point clamp does. */
static void test_volume_hold(void)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def(); /* 5 x 1 x 1, 1 section, biquadratic faces */
    sem_discretization *d = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1;
    if (!m || sem_primitive_beam(m, &bd, &err) != SEM_OK || sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "beam: %s", err.message);
        sem_model_destroy(m);
        return;
    }
    const sem_pin_region slab = {{-1, -1, -1, 0.001, 2, 2}, -1}, tenth = {{-1, -1, -1, 0.5, 2, 2}, -1};
    unsigned char *clamp = control_box(m, slab.box);
    double *qc = solve_static(m, d, clamp, NULL, 0, SEM_SOLVER_AUTO, "one-section beam, clamp");
    sem_object_checks cs, ct;
    cs.pin_part = ct.pin_part = -2;
    double *qs = solve_static_checked(m, d, NULL, &slab, 1, SEM_SOLVER_AUTO, "one-section beam, thin slab", &cs);
    double *qt = solve_static_checked(m, d, NULL, &tenth, 1, SEM_SOLVER_AUTO, "one-section beam, first 10 %", &ct);
    /* the trust check (pins.h, sem_pins_held_parts): the thin slab holds no side face whole;
     * the first 10 % holds the side faces' polynomials, whose faces run the whole length */
    printf("one-section beam: held part (suspect) thin slab %d, first 10 %% %d (%.0f %% of it outside)\n", cs.pin_part,
           ct.pin_part, 100 * ct.pin_outside);
    CHECK(cs.pin_part == -1 && !(cs.suspect & SEM_SUSPECT_PIN), "thin slab flagged: part %d", cs.pin_part);
    CHECK(ct.pin_part >= 0 && (ct.suspect & SEM_SUSPECT_PIN) && ct.pin_outside > 0.7,
          "the first 10 %% holds whole faces but is not flagged (part %d, %.3f outside)", ct.pin_part, ct.pin_outside);
    if (qc && qs && qt) {
        double sc = far_sag(d, qc, 5), ss = far_sag(d, qs, 5), st = far_sag(d, qt, 5);
        printf("one-section beam, sag of the far 10 %%: control-point clamp %.4f m, material of x <= 0.001 %.4f m, "
               "material of x <= 0.5 (volume of faces that run the length) %.4f m\n",
               sc, ss, st);
        CHECK(fabs(ss / sc - 1) <= 0.01, "thin slab %.4f vs clamp %.4f", ss, sc);
        CHECK(st <= 0.01 * sc, "held over a volume of its faces the beam should barely move: %.4f of %.4f", st, sc);
    }
    free(qc);
    free(qs);
    free(qt);
    free(clamp);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

/* A 1 x 0.5 x 0.5 box (bicubic faces) refined by `refine`. */
static sem_model *box(int refine)
{
    sem_error err;
    sem_model *b = sem_model_create(), *fine = NULL;
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = 1;
    bd.size[1] = 0.5;
    bd.size[2] = 0.5;
    if (!b || sem_primitive_box(b, &bd, &err) != SEM_OK || (refine > 1 && sem_model_refine(b, refine, &fine, &err) != SEM_OK)) {
        CHECK(0, "box: %s", err.message);
        sem_model_destroy(b);
        return NULL;
    }
    if (refine > 1) {
        sem_model_destroy(b);
        return fine;
    }
    return b;
}

/* One world of the model with `region` (moved by `presc`), gravity g, stepped `steps` times by
 * `integ` (static: one solve); returns q (caller frees). */
static double *run(const sem_model *m, const sem_discretization *d, const sem_pin_region *region,
                   const sem_prescribe *presc, double g, sem_integrator integ, int steps, sem_solver_choice solver,
                   char *name)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.solver = solver;
    wd.integrator = integ;
    wd.dt = 0.01;
    wd.threads = 2;
    wd.gravity[2] = g;
    wd.newton_tolerance = 1e-12;
    sem_world *w = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.material = sem_default_material();
    od.material.youngs_modulus = 1e5;
    od.pin_regions = region;
    od.n_pin_regions = 1;
    if (presc) od.prescribe = *presc;
    double *q = NULL;
    if (!w || sem_world_add_object(w, &od, &err) < 0) {
        CHECK(0, "add object: %s", w ? err.message : "no world");
        goto done;
    }
    if (name) snprintf(name, 32, "%s", sem_world_solver_name(w, 0));
    for (int s = 0; s < steps; ++s)
        if ((integ == SEM_STATIC ? sem_world_solve_static(w, &err) : sem_world_step(w, &err)) != SEM_OK) {
            CHECK(0, "step %d: %s", s, err.message);
            goto done;
        }
    size_t n = 3 * (size_t)d->n_ctrl;
    q = malloc(n * sizeof *q);
    if (q) memcpy(q, sem_world_object_q(w, 0), n * sizeof *q);
done:
    sem_world_destroy(w);
    return q;
}

/* Rotation by `degrees` about a unit axis, as [R | b] (row-major 3 x 4). */
static void rigid(const double axis[3], double degrees, const double b[3], double A[12])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n, t = degrees * M_PI / 180, c = cos(t), s = sin(t), C = 1 - c;
    const double R[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s, y * x * C + z * s, c + y * y * C,
                         y * z * C - x * s, z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    for (int r = 0; r < 3; ++r) {
        for (int k = 0; k < 3; ++k) A[4 * r + k] = R[3 * r + k];
        A[4 * r + 3] = b[r];
    }
}

/* Patch tests of the anchor: a rigid motion prescribed (as an affine map) to the material of
 * one end moves the free body rigidly, every control point to R x0 + b; a stretch prescribed to
 * all the material of the body is met at every anchored point to the anchor's compliance. */
static void test_patch(void)
{
    sem_model *m = box(1);
    sem_error err;
    sem_discretization *d = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1;
    if (!m || sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "box: %s", m ? err.message : "no model");
        sem_model_destroy(m);
        return;
    }
    size_t n = 3 * (size_t)d->n_ctrl;
    double *q0 = malloc(n * sizeof *q0);
    sem_model_get_q(m, q0);
    sem_prescribe pr;
    memset(&pr, 0, sizeof pr);
    pr.type = SEM_PRESCRIBE_AFFINE;
    const double axis[3] = {1, 2, 0.5}, b[3] = {0.3, -0.2, 0.1};
    rigid(axis, 35, b, pr.affine);
    const sem_pin_region end = {{-1, -1, -1, -0.4, 1, 1}, 0};
    double *q = run(m, d, &end, &pr, 0, SEM_STATIC, 1, SEM_SOLVER_AUTO, NULL);
    if (q) {
        double worst = 0;
        for (int c = 0; c < d->n_ctrl; ++c)
            for (int r = 0; r < 3; ++r) {
                const double *A = pr.affine, *x = q0 + 3 * (size_t)c;
                double t = A[4 * r] * x[0] + A[4 * r + 1] * x[1] + A[4 * r + 2] * x[2] + A[4 * r + 3];
                worst = fmax(worst, fabs(q[3 * (size_t)c + r] - t));
            }
        printf("patch test: a rigid motion (35 deg about (1, 2, 0.5), then (0.3, -0.2, 0.1)) prescribed to the "
               "material of x <= -0.4 moves every control point of the 1 x 0.5 x 0.5 box to R x0 + b within %.3g m\n",
               worst);
        CHECK(worst <= 1e-9, "rigid patch test: control points off by %.3g m", worst);
    }
    free(q);
    /* stretch and shear of all the material */
    const double S[12] = {1.2, 0.1, 0, 0.05, 0, 0.9, 0.05, 0, 0, 0.05, 1.1, -0.02};
    memcpy(pr.affine, S, sizeof S);
    const sem_pin_region all = {{-1, -1, -1, 1, 1, 1}, 0};
    q = run(m, d, &all, &pr, 0, SEM_STATIC, 1, SEM_SOLVER_AUTO, NULL);
    if (q) {
        double moved = anchored_motion(d, all.box, q, S), worst = 0, disp = 0;
        for (int c = 0; c < d->n_ctrl; ++c)
            for (int r = 0; r < 3; ++r) {
                const double *x = q0 + 3 * (size_t)c;
                double t = S[4 * r] * x[0] + S[4 * r + 1] * x[1] + S[4 * r + 2] * x[2] + S[4 * r + 3];
                worst = fmax(worst, fabs(q[3 * (size_t)c + r] - t));
                disp = fmax(disp, fabs(t - x[r]));
            }
        printf("patch test: a stretch and shear prescribed to all the material: anchored points within %.3g m, "
               "control points within %.3g m of A x0 + b (displacements up to %.3g m)\n",
               moved, worst, disp);
        CHECK(moved <= 1e-3 * disp, "stretched material off its targets by %.3g m", moved);
        CHECK(worst <= 3e-3 * disp, "stretched control points off A x0 + b by %.3g m", worst);
    }
    free(q);
    free(q0);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

/* The refined box held by the material of its x <= -0.45 end, which turns about the x axis,
 * under gravity: the structured solver and CHOLMOD give the same states. */
static void test_solvers(void)
{
    sem_model *m = box(3);
    sem_error err;
    sem_discretization *d = NULL;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1; /* both solvers on the same discretization */
    if (!m || sem_preprocess(m, &po, &d, &err) != SEM_OK) {
        CHECK(0, "refined box: %s", m ? err.message : "no model");
        sem_model_destroy(m);
        return;
    }
    size_t n = 3 * (size_t)d->n_ctrl;
    double *q0 = malloc(n * sizeof *q0);
    sem_model_get_q(m, q0);
    sem_prescribe pr;
    memset(&pr, 0, sizeof pr);
    pr.type = SEM_PRESCRIBE_ROTATE;
    pr.axis_direction[0] = 1;
    pr.rate = 2.0;
    const sem_pin_region end = {{-1, -1, -1, -0.45, 1, 1}, 0};
    const sem_integrator integ[3] = {SEM_LINEARLY_IMPLICIT_EULER, SEM_IMPLICIT_EULER, SEM_STATIC};
    const char *names[3] = {"linearly implicit", "implicit Euler", "static"};
    const int steps[3] = {10, 4, 2};
    const double tol[3] = {1e-9, 1e-9, 1e-9};
    for (int t = 0; t < 3; ++t) {
        char na[32] = "", nb[32] = "";
        double *qa = run(m, d, &end, &pr, -9.81, integ[t], steps[t], SEM_SOLVER_SPARSE, na);
        double *qb = run(m, d, &end, &pr, -9.81, integ[t], steps[t], SEM_SOLVER_STRUCTURED, nb);
        if (qa && qb) {
            double diff = 0, scale = 0;
            for (size_t i = 0; i < n; ++i) {
                diff = fmax(diff, fabs(qa[i] - qb[i]));
                scale = fmax(scale, fabs(qa[i] - q0[i]));
            }
            printf("refined box, turning material pin, %s: %s vs %s: displacement %.4g m, states differ by %.3g m "
                   "(%.2g)\n",
                   names[t], na, nb, scale, diff, diff / scale);
            CHECK(scale > 1e-3, "%s: the box should move (%.3g m)", names[t], scale);
            CHECK(diff <= tol[t] * scale, "%s: structured and q-space differ by %.3g of %.3g", names[t], diff, scale);
            CHECK(!strcmp(na, "cholmod") && !strcmp(nb, "structured"), "solvers %s, %s", na, nb);
        }
        free(qa);
        free(qb);
    }
    /* a box that holds no material */
    sem_world_def wd = sem_default_world_def();
    sem_world *w = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    const sem_pin_region nowhere = {{5, 5, 5, 6, 6, 6}, -1};
    od.pin_regions = &nowhere;
    od.n_pin_regions = 1;
    CHECK(w && sem_world_add_object(w, &od, &err) < 0 && err.status == SEM_ERR_INVALID &&
              strstr(err.message, "holds none of the object's material"),
          "an empty pin box: %s", err.message);
    sem_world_destroy(w);
    free(q0);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

int main(void)
{
    double fem = sem_fem_reference_find(FEM_JSON, "test_pins");
    if (!(fem > 0)) fem = 4.2387;
    test_cantilever(fem);
    test_trimmed_bar();
    test_volume_hold();
    test_patch();
    test_solvers();
    return test_finish("test_pins");
}
