/* test_patches.c - the accuracy setting (sem.resolution): parts cut into patches
 * (sem_model_patches), the same surfaces, and an answer that approaches FEM as they shrink.
 *
 * - Cutting is exact: every patch of a bicubic box, a trimmed CAD file and a model-space
 *   trimmed file evaluates to its part's surface at points of its domain (1e-12 of the size),
 *   the refined parts too; the patches' areas (trims kept) add up to the parts' (1e-12
 *   untrimmed; trimmed to the 1e-4 to which sem_model_measure integrates a trim); the
 *   rest state of the patches gathers into the refined parts' control points exactly; every
 *   patch is at most the size asked for along its iso-curves (5 % for the arc-length cut).
 * - The cantilever of one section (5 x 1 x 1 m, static, gravity, clamped at x = 0, default
 *   settings, FEM 4.2387 m from validation/fem_cantilever.json) bends more as the patches
 *   shrink and comes within 5 % of FEM at 0.5 m patches (measured: 40.2 % whole, 83.3 % at 1 m,
 *   95.7 % at 0.5 m, 98.8 % at 0.25 m).
 * - sem run with sem.resolution writes frames of the file's parts (refined at the cuts),
 *   with the patches welded: no seam opens.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "bench/validation.h"
#include "sem/measure.h"
#include "sem/nurbs.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/refine.h"
#include "sem/simulation.h"
#include "test_util.h"

#define FEM_JSON SEM_TEST_DATA "/../../validation/fem_cantilever.json"

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

/* The checks of the first item on one model cut at size. */
static void check_cut(const char *name, const sem_model *m, double size, int want_patches, double area_tol)
{
    sem_error err;
    sem_patches p;
    if (sem_model_patches(m, size, &p, &err) != SEM_OK) {
        CHECK(0, "%s: %s", name, err.message);
        return;
    }
    CHECK(p.refined->n_parts == m->n_parts, "%s: refined parts %d of %d", name, p.refined->n_parts, m->n_parts);
    if (want_patches > 0) CHECK(p.model->n_parts == want_patches, "%s: %d patches, want %d", name, p.model->n_parts, want_patches);
    sem_part_measure_result whole, cut, refined;
    CHECK(sem_model_measure(m, NULL, &whole, &err) == SEM_OK, "%s: %s", name, err.message);
    CHECK(sem_model_measure(p.model, NULL, &cut, &err) == SEM_OK, "%s: %s", name, err.message);
    CHECK(sem_model_measure(p.refined, NULL, &refined, &err) == SEM_OK, "%s: %s", name, err.message);
    CHECK_REL(cut.area, whole.area, area_tol);
    CHECK_REL(refined.area, whole.area, area_tol);
    double L = dist3(whole.bbox_min, whole.bbox_max), worst = 0, longest = 0;
    unsigned long long rng = 12345;
    for (int k = 0; k < p.model->n_parts; ++k) {
        const sem_surface *s = &p.model->parts[k].surface;
        const sem_surface *ps = &m->parts[p.part_parent[k]].surface;
        const sem_surface *rs = &p.refined->parts[p.part_parent[k]].surface;
        for (int t = 0; t < 20; ++t) {
            double u = s->u0 + (s->u1 - s->u0) * test_uniform(&rng), v = s->v0 + (s->v1 - s->v0) * test_uniform(&rng);
            double a[3], b[3], c[3];
            sem_surface_eval(s, u, v, a, NULL, NULL, NULL);
            sem_surface_eval(ps, u, v, b, NULL, NULL, NULL);
            sem_surface_eval(rs, u, v, c, NULL, NULL, NULL);
            worst = fmax(worst, fmax(dist3(a, b), dist3(c, b)));
        }
        /* the patch's iso-curves through its middle */
        for (int dir = 0; dir < 2; ++dir) {
            double len = 0, prev[3];
            for (int j = 0; j <= 64; ++j) {
                double t = j / 64.0, x[3];
                double u = dir == 0 ? s->u0 + (s->u1 - s->u0) * t : 0.5 * (s->u0 + s->u1);
                double v = dir == 1 ? s->v0 + (s->v1 - s->v0) * t : 0.5 * (s->v0 + s->v1);
                sem_surface_eval(s, u, v, x, NULL, NULL, NULL);
                if (j > 0) len += dist3(x, prev);
                memcpy(prev, x, sizeof x);
            }
            longest = fmax(longest, len);
        }
    }
    CHECK(worst <= 1e-12 * L, "%s: a patch is %g off its part", name, worst);
    CHECK(longest <= 1.05 * size, "%s: a patch is %g long, asked for %g", name, longest, size);
    size_t nc = sem_model_control_points(p.model), nr = sem_model_control_points(p.refined);
    double *q = malloc(3 * nc * sizeof *q), *qr = malloc(3 * nr * sizeof *qr), *q0 = malloc(3 * nr * sizeof *q0);
    sem_model_get_q(p.model, q);
    sem_model_get_q(p.refined, q0);
    sem_patches_gather(&p, q, qr);
    CHECK(memcmp(qr, q0, 3 * nr * sizeof *qr) == 0, "%s: the rest patches do not gather into the refined parts", name);
    printf("%s cut at %g: %d parts -> %d patches, %zu -> %zu control points, area %.9g (whole %.9g), worst %.2g\n", name,
           size, m->n_parts, p.model->n_parts, sem_model_control_points(m), nc, cut.area, whole.area, worst);
    free(q);
    free(qr);
    free(q0);
    sem_patches_free(&p);
}

static void test_cuts(void)
{
    sem_error err;
    sem_model *box = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = 2;
    bd.size[1] = 1;
    bd.size[2] = 0.5;
    if (sem_primitive_box(box, &bd, &err) == SEM_OK)
        /* 0.45: x faces 5 cuts (2 m), y 3 (1 m), z 2 (0.5 m): 2 (5 x 3 + 5 x 2 + 3 x 2) */
        check_cut("box", box, 0.45, 2 * (15 + 10 + 6), 1e-12);
    else
        CHECK(0, "box: %s", err.message);
    sem_model_destroy(box);
    static const char *files[] = {"iges_cad_trimmed.igs", "iges_model_space.igs", "iges_revolution.igs"};
    for (int f = 0; f < 3; ++f) {
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", SEM_TEST_DATA, files[f]);
        sem_model *m = NULL;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            CHECK(0, "%s: %s", files[f], err.message);
            continue;
        }
        /* trimmed areas are measured to about 1e-4 (sem/measure.h) */
        check_cut(files[f], m, 0.3, 0, f < 2 ? 1e-4 : 1e-12);
        sem_model_destroy(m);
    }
    sem_model *m = sem_model_create();
    sem_patches p;
    CHECK(sem_model_patches(m, 0, &p, &err) == SEM_ERR_INVALID, "a zero size is refused");
    CHECK(sem_model_patches(m, -1, &p, &err) == SEM_ERR_INVALID, "a negative size is refused");
    CHECK(sem_model_patches(m, NAN, &p, &err) == SEM_ERR_INVALID, "a NaN size is refused");
    sem_model_destroy(m);
}

/* Tip deflection of the one-section cantilever cut into patches of `size` (0: whole). */
static double cantilever_tip(double size)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    if (sem_primitive_beam(m, &bd, &err) != SEM_OK) {
        CHECK(0, "beam: %s", err.message);
        sem_model_destroy(m);
        return NAN;
    }
    if (size > 0) {
        sem_patches p;
        if (sem_model_patches(m, size, &p, &err) != SEM_OK) {
            CHECK(0, "patches: %s", err.message);
            sem_model_destroy(m);
            return NAN;
        }
        sem_model_destroy(m);
        m = p.model;
        p.model = NULL;
        sem_patches_free(&p);
    }
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof *q0), tip = NAN;
    unsigned char *pin = calloc(nc, 1);
    sem_model_get_q(m, q0);
    for (size_t c = 0; c < nc; ++c) pin[c] = fabs(q0[3 * c]) < 1e-12;
    sem_preprocess_options po = sem_default_preprocess_options();
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -10;
    wd.integrator = SEM_STATIC;
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.pinned = pin;
    od.weld = 1; /* as sem run does with sem.resolution: the cuts' points held together */
    if (sem_preprocess(m, &po, &d, &err) != SEM_OK || !(w = sem_world_create(&wd, &err))) {
        CHECK(0, "%s", err.message);
    } else {
        od.disc = d;
        if (sem_world_add_object(w, &od, &err) < 0 || sem_world_solve_static(w, &err) != SEM_OK) {
            CHECK(0, "patches %g: %s", size, err.message);
        } else {
            const double *q = sem_world_object_q(w, 0);
            int n = 0;
            tip = 0;
            for (size_t c = 0; c < nc; ++c)
                if (fabs(q0[3 * c] - 5) < 1e-12) tip -= q[3 * c + 2] - q0[3 * c + 2], n++;
            tip /= n;
        }
    }
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    free(q0);
    free(pin);
    return tip;
}

static void test_cantilever(void)
{
    double fem = 0;
    sem_error err;
    CHECK(sem_fem_reference_read(FEM_JSON, &fem, &err) == SEM_OK, "%s", err.message);
    const double sizes[] = {0, 1, 0.5};
    const int n = getenv("SEM_SANITIZED") ? 2 : 3;
    double pct[3] = {0};
    for (int k = 0; k < n; ++k) {
        pct[k] = 100 * cantilever_tip(sizes[k]) / fem;
        printf("one-section cantilever, patches of %g m: tip %.2f %% of FEM\n", sizes[k], pct[k]);
        if (k > 0) CHECK(pct[k] > pct[k - 1] + 5, "patches %g: %.1f %% after %.1f %%", sizes[k], pct[k], pct[k - 1]);
    }
    if (n == 3) CHECK(fabs(pct[2] - 100) <= 5, "0.5 m patches at %.1f %% of FEM", pct[2]);
}

int main(void)
{
    test_cuts();
    test_cantilever();
    return test_finish("test_patches");
}
