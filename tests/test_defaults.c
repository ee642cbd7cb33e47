/* test_defaults.c - trustworthy physics at default settings (issue 11).
 *
 * The cantilever of docs/validation.md (5 x 1 x 1 m, 10 sections, clamped at x = 0, gravity 10,
 * neo-Hookean rho 1000, E 1e6, nu 0.45, static) with *default* `sem` settings:
 * - same problem, same answer: turned about several axes with its gravity and pins, the tip
 *   deflection changes by at most 3 % and the volume by at most 0.5 % (the quadrature is laid in
 *   the object's own frame; before, a turn of 90 degrees about z collapsed it);
 * - within 12 % of the FEM reference (4.238 m; 89.2 % measured, 99.3 % with 20 sections), and
 *   a load symmetric about the beam's planes of symmetry moves the tip sideways by less than
 *   1 % of the deflection (the origins of Sec. 6.2 are chosen symmetrically);
 * - the deflection rises towards FEM as sections are added (paper Fig. 10), now at defaults;
 * - a point takes the material of the solid it lies in whatever the ray direction:
 *   examples/two_materials.json has mass 496 kg (it was 640: every point took the material of
 *   the end cap its ray entered through);
 * - units: an IGES file in millimetres is simulated at its real size, and "as_metres" keeps the
 *   paper's reading of the numbers.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/scene.h"
#include "sem/simulation.h"
#include "bench/validation.h"
#include "test_util.h"

#define FEM_JSON SEM_TEST_DATA "/../../validation/fem_cantilever.json"
#define EXAMPLES SEM_TEST_DATA "/../../examples"

/* Rotation matrix about a unit axis (right-handed), row-major. */
static void rotation(const double axis[3], double degrees, double R[9])
{
    double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
    double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n, t = degrees * M_PI / 180.0;
    double c = cos(t), s = sin(t), C = 1 - c;
    double M[9] = {c + x * x * C,     x * y * C - z * s, x * z * C + y * s,
                   y * x * C + z * s, c + y * y * C,     y * z * C - x * s,
                   z * x * C - y * s, z * y * C + x * s, c + z * z * C};
    memcpy(R, M, sizeof M);
}

typedef struct beam_result {
    double tip, side, volume;
    int ok;
} beam_result;

/* The cantilever with `sections` sections, turned by R, solved statically at default settings
 * (or with the options given). tip: mean displacement of the free end cap's control points
 * along the gravity direction; side: along the turned y axis. */
static beam_result solve_beam(int sections, const double R[9], const sem_preprocess_options *opt)
{
    beam_result out = {0, 0, 0, 0};
    sem_error err;
    sem_model *m = sem_model_create();
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = sections;
    bd.length = 5;
    bd.width = 1;
    bd.height = 1;
    if (sem_primitive_beam(m, &bd, &err) != SEM_OK) {
        CHECK(0, "beam: %s", err.message);
        sem_model_destroy(m);
        return out;
    }
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof *q0), *qr = malloc(3 * nc * sizeof *qr);
    unsigned char *pin = calloc(nc, 1);
    sem_model_get_q(m, q0);
    for (size_t c = 0; c < nc; ++c) {
        for (int r = 0; r < 3; ++r)
            qr[3 * c + r] = R[3 * r] * q0[3 * c] + R[3 * r + 1] * q0[3 * c + 1] + R[3 * r + 2] * q0[3 * c + 2];
        pin[c] = fabs(q0[3 * c]) < 1e-12;
    }
    sem_model_set_q(m, qr);
    sem_preprocess_options o = opt ? *opt : sem_default_preprocess_options();
    sem_discretization *d = NULL;
    sem_world *w = NULL;
    if (sem_preprocess(m, &o, &d, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        goto done;
    }
    sem_world_def wd = sem_default_world_def();
    const double g[3] = {0, 0, -10};
    for (int r = 0; r < 3; ++r) wd.gravity[r] = R[3 * r] * g[0] + R[3 * r + 1] * g[1] + R[3 * r + 2] * g[2];
    wd.integrator = SEM_STATIC;
    w = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = d;
    od.material = sem_default_material(); /* neo-Hookean, rho 1000, E 1e6, nu 0.45 */
    if (opt && opt->origin_rule == SEM_ORIGINS_PAPER) { /* the authors' settings */
        od.blend = 0;
        od.seams = SEM_SEAMS_PAPER;
    }
    od.pinned = pin;
    if (!w || sem_world_add_object(w, &od, &err) < 0 || sem_world_solve_static(w, &err) != SEM_OK) {
        CHECK(0, "solve (%d sections): %s", sections, err.message);
        goto done;
    }
    const double *q = sem_world_object_q(w, 0);
    double ey[3] = {R[1], R[4], R[7]}, eg[3] = {-R[2], -R[5], -R[8]};
    double tip = 0, side = 0;
    int n = 0;
    /* the free end cap: the part whose control points all lie at x = 5 (as study_deflection) */
    size_t *off = malloc(((size_t)m->n_parts + 1) * sizeof *off);
    sem_model_part_offsets(m, off);
    unsigned char *cap = calloc(nc, 1);
    for (int p = 0; p < m->n_parts; ++p) {
        int all = 1;
        for (size_t c = off[p]; c < off[p + 1] && all; ++c) all = fabs(q0[3 * c] - 5.0) < 1e-12;
        for (size_t c = off[p]; c < off[p + 1] && all; ++c) cap[c] = 1;
    }
    free(off);
    for (size_t c = 0; c < nc; ++c) {
        if (!cap[c]) continue;
        double u[3] = {q[3 * c] - qr[3 * c], q[3 * c + 1] - qr[3 * c + 1], q[3 * c + 2] - qr[3 * c + 2]};
        tip += u[0] * eg[0] + u[1] * eg[1] + u[2] * eg[2];
        side += u[0] * ey[0] + u[1] * ey[1] + u[2] * ey[2];
        n++;
    }
    free(cap);
    out.tip = tip / n;
    out.side = side / n;
    out.volume = d->volume;
    out.ok = 1;
done:
    sem_world_destroy(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
    free(q0);
    free(qr);
    free(pin);
    return out;
}

static double fem_tip(void)
{
    double tip = 0;
    sem_error err;
    CHECK(sem_fem_reference_read(FEM_JSON, &tip, &err) == SEM_OK, "%s", err.message);
    return tip;
}

static void test_same_problem_same_answer(double fem)
{
    static const struct {
        double axis[3], degrees;
    } turns[] = {{{0, 0, 1}, 0},   {{0, 0, 1}, 90},  {{0, 0, 1}, 30},
                 {{1, 1, 1}, 37},  {{0, 1, 0}, 90},  {{1, 0, 0}, 45},
                 {{1, -2, 0.5}, 123}};
    const int n = getenv("SEM_SANITIZED") ? 3 : (int)(sizeof turns / sizeof turns[0]);
    beam_result ref = {0, 0, 0, 0};
    for (int k = 0; k < n; ++k) {
        double R[9];
        rotation(turns[k].axis, turns[k].degrees, R);
        beam_result r = solve_beam(10, R, NULL);
        if (!r.ok) return;
        printf("b10 turned %5.1f deg about (%g, %g, %g): tip %.6f m (%.2f %% of FEM), side %.2e m, "
               "volume %.8f\n",
               turns[k].degrees, turns[k].axis[0], turns[k].axis[1], turns[k].axis[2], r.tip,
               100 * r.tip / fem, r.side, r.volume);
        if (k == 0) {
            ref = r;
            /* 89.2 % measured (96.7 % before the geometric seams, a figure that depended on the
             * control net: refined by 4 the same beam gave 107.6 %; docs/refine.md) */
            CHECK(fabs(r.tip / fem - 1) <= 0.12, "default b10 tip %.4f m, FEM %.4f m", r.tip, fem);
            CHECK_REL(r.volume, 5.0, 1e-6);
        }
        CHECK(fabs(r.tip / ref.tip - 1) <= 0.03, "turned tip %.6f vs %.6f", r.tip, ref.tip);
        CHECK(fabs(r.volume / ref.volume - 1) <= 0.005, "turned volume %.8f vs %.8f", r.volume,
              ref.volume);
        CHECK(fabs(r.side) < 0.01 * fabs(r.tip), "sideways %.3g m for a tip of %.3g m", r.side, r.tip);
    }
}

/* The paper's Fig. 10 at defaults: the deflection rises towards FEM as sections are added.
 * Measured: 40.3, 76.5, 85.7, 84.9, 85.5, 89.2, 99.3 % for 1, 2, 3, 4, 6, 10, 20 sections (with
 * the paper's seam weighting: 42.7, 82.3, 90.7, 89.6, 92.3, 96.7, 107.9 %, overshooting). */
static void test_deflection_rises(double fem)
{
    const int sections[] = {1, 2, 3, 4, 6, 10, 20};
    const int n = getenv("SEM_SANITIZED") ? 3 : 7;
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    double pct[7] = {0}, best = 0;
    for (int k = 0; k < n; ++k) {
        beam_result r = solve_beam(sections[k], I, NULL);
        if (!r.ok) return;
        pct[k] = 100 * r.tip / fem;
        printf("default settings, %2d sections: tip %.4f m = %.1f %% of FEM\n", sections[k], r.tip,
               pct[k]);
        if (k > 0 && k < 3) CHECK(pct[k] > pct[k - 1] + 5, "%d sections %.1f %% after %.1f %%", sections[k], pct[k], pct[k - 1]);
        /* then it stays at the FEM figure within the method's error, never falling back */
        if (k >= 3) CHECK(pct[k] >= best - 3 && pct[k] <= 110, "%d sections %.1f %% (best before %.1f %%)", sections[k], pct[k], best);
        if (pct[k] > best) best = pct[k];
    }
    if (n == 7) {
        CHECK(fabs(pct[5] - 100) <= 12, "10 sections at %.1f %% of FEM", pct[5]);
        CHECK(fabs(pct[6] - 100) <= 3, "20 sections at %.1f %% of FEM", pct[6]);
    }
}

/* The explicit settings of the paper still work as before (authors' b10 figure). */
static void test_authors_settings(double fem)
{
    if (getenv("SEM_SANITIZED")) return;
    sem_preprocess_options o = sem_default_preprocess_options();
    o.rays[0] = o.rays[1] = 3;
    o.points_per_interval = 100;
    o.alpha = 0.501;
    o.origin_rule = SEM_ORIGINS_PAPER;
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    beam_result r = solve_beam(10, I, &o);
    printf("authors' settings: tip %.6f m = %.2f %% of FEM\n", r.tip, 100 * r.tip / fem);
    CHECK_NEAR(r.tip, 3.973578, 2e-6);
}

/* Shared fits (sem_fit_rule, docs/preprocessing.md "Shared fits"): the cantilever with one
 * polynomial per origin instead of per part, default settings otherwise. The coupled origins
 * group a section's faces, so it becomes one quadratic per section: stiffer than the paper's
 * per-part fits by the amounts measured here, and like them it rises towards FEM with the
 * sections. The automatic rule never takes it for the cantilever or a Table 1 model (all
 * well under its 12,000 dofs). */
static void test_shared_fits(double fem)
{
    const int sections[] = {4, 10, 20};
    const int n = getenv("SEM_SANITIZED") ? 1 : 3;
    const double I[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    sem_preprocess_options o = sem_default_preprocess_options();
    o.fit_rule = SEM_FIT_ORIGINS;
    double pct[3] = {0};
    for (int k = 0; k < n; ++k) {
        beam_result own = solve_beam(sections[k], I, NULL), shared = solve_beam(sections[k], I, &o);
        if (!own.ok || !shared.ok) return;
        pct[k] = 100 * shared.tip / fem;
        printf("shared fits, %2d sections: tip %.4f m = %.1f %% of FEM (per part %.1f %%)\n",
               sections[k], shared.tip, pct[k], 100 * own.tip / fem);
        CHECK(shared.tip <= own.tip * 1.001, "%d sections: shared fits %.4f m, per part %.4f m",
              sections[k], shared.tip, own.tip);
        CHECK(fabs(shared.side) <= 0.01 * shared.tip, "%d sections: side %.3g m", sections[k], shared.side);
    }
    if (n == 3) {
        CHECK(pct[1] > pct[0] && pct[2] > pct[1], "rises: %.1f %.1f %.1f %%", pct[0], pct[1], pct[2]);
        /* measured: 47.3, 74.7, 80.3 % (per part 84.9, 89.2, 99.3 %) */
        CHECK(fabs(pct[1] - 74.7) <= 2 && fabs(pct[2] - 80.3) <= 2, "10, 20 sections at %.1f, %.1f %% of FEM",
              pct[1], pct[2]);
    }
    /* the automatic rule */
    sem_preprocess_options d = sem_default_preprocess_options();
    for (int sec = 1; sec <= 20; sec *= 20) {
        sem_model *m = sem_model_create();
        sem_beam_def bd = sem_default_beam_def();
        bd.sections = sec;
        if (sem_primitive_beam(m, &bd, NULL) == SEM_OK)
            CHECK(sem_preprocess_shared_fit(m, &d) == 0, "auto: per part for %d sections", sec);
        sem_model_destroy(m);
    }
    {   /* many small faces: 400 sections (1,602 parts of 9 control points, > 10,000 dofs) */
        sem_model *m = sem_model_create();
        sem_beam_def bd = sem_default_beam_def();
        bd.sections = 400;
        if (sem_primitive_beam(m, &bd, NULL) == SEM_OK)
            CHECK(sem_preprocess_shared_fit(m, &d) == 1, "auto: per origin for 400 sections (%zu dofs)",
                  3 * sem_model_control_points(m));
        sem_model_destroy(m);
    }
    const char *castle = test_shared_model("castle/castle.iges");
    sem_model *cm = NULL;
    if (castle && sem_model_load(castle, &cm, NULL) == SEM_OK)
        CHECK(sem_preprocess_shared_fit(cm, &d) == 0, "auto: per part for castle.iges");
    sem_model_destroy(cm);
    for (int r = 0; r < sem_table1_count; ++r) {
        const char *path = test_shared_model(sem_table1[r].file);
        sem_model *m = NULL;
        if (!path || sem_model_load(path, &m, NULL) != SEM_OK) continue;
        sem_preprocess_options t = sem_table1_options(&sem_table1[r]);
        CHECK(sem_preprocess_shared_fit(m, &d) == 0 && sem_preprocess_shared_fit(m, &t) == 0,
              "auto: per part for %s", sem_table1[r].file);
        sem_model_destroy(m);
    }
}

static double scene_mass(const char *json, const char *name, const char *base, char *units,
                         double *unit_to_meter, double size[3])
{
    sem_scene *s = NULL;
    sem_error err;
    if (sem_scene_parse(json, name, base, &s, &err) != SEM_OK) {
        CHECK(0, "%s", err.message);
        return 0;
    }
    sem_scene_world *sw = NULL;
    double mass = 0;
    if (sem_scene_world_create(s, NULL, &sw, &err) != SEM_OK) {
        CHECK(0, "%s", err.message);
    } else {
        sem_object_stats st;
        sem_world_object_stats(sem_scene_world_world(sw), 0, &st);
        mass = st.mass;
        if (units) snprintf(units, 16, "%s", sem_scene_world_file_units(sw, 0));
        if (unit_to_meter) *unit_to_meter = sem_scene_world_file_unit_to_meter(sw, 0);
        if (size) {
            const sem_model *m = sem_scene_world_model(sw, 0);
            size_t nc = sem_model_control_points(m);
            double *q = malloc(3 * nc * sizeof *q);
            sem_model_get_q(m, q);
            for (int e = 0; e < 3; ++e) {
                double lo = INFINITY, hi = -INFINITY;
                for (size_t c = 0; c < nc; ++c) {
                    lo = fmin(lo, q[3 * c + e]);
                    hi = fmax(hi, q[3 * c + e]);
                }
                size[e] = hi - lo;
            }
            free(q);
        }
    }
    sem_scene_world_destroy(sw);
    sem_scene_destroy(s);
    return mass;
}

static char *read_text(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *buf = malloc((size_t)n + 1);
    if (buf && fread(buf, 1, (size_t)n, f) != (size_t)n) {
        free(buf);
        buf = NULL;
    }
    if (buf) buf[n] = '\0';
    fclose(f);
    return buf;
}

/* Sections 1-2 of the 2 x 0.4 x 0.4 m beam are 2000 kg/m^3, sections 3-4 1100 kg/m^3:
 * 0.16 m^3 x 2000 + 0.16 m^3 x 1100 = 496 kg, whatever the quadrature grid. */
static void test_part_materials(void)
{
    char *json = read_text(EXAMPLES "/two_materials.json");
    CHECK(json != NULL, "examples/two_materials.json");
    if (!json) return;
    double mass = scene_mass(json, "two_materials.json", EXAMPLES, NULL, NULL, NULL);
    printf("two_materials.json (its explicit rays along x): mass %.6f kg\n", mass);
    CHECK_REL(mass, 496.0, 1e-6);
    /* the same object with the default quadrature */
    char *sem = strstr(json, "\"sem\"");
    CHECK(sem != NULL, "sem key");
    if (sem) {
        char *end = strchr(sem, '}');
        memmove(sem, end + 2, strlen(end + 2) + 1); /* drop "sem": {...}, */
        mass = scene_mass(json, "two_materials.json", EXAMPLES, NULL, NULL, NULL);
        printf("two_materials.json with the default quadrature: mass %.6f kg\n", mass);
        /* one point per cell: the cells that straddle the plane between the materials (x = 1)
         * take one material, so up to half a cell (0.1 m of 2 m) may go either way */
        CHECK(fabs(mass - 496.0) <= 0.5 * 0.11 * 0.16 * 900, "mass %g kg, 496 expected", mass);
    }
    free(json);
}

/* A 20 x 10 x 5 mm box written in millimetres: simulated as 0.02 x 0.01 x 0.005 m, frames in
 * millimetres; "as_metres" reads the numbers as metres (the paper's reading). */
static void test_units(void)
{
    sem_error err;
    sem_model *m = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = 20;
    bd.size[1] = 10;
    bd.size[2] = 5;
    CHECK(sem_primitive_box(m, &bd, &err) == SEM_OK, "%s", err.message);
    snprintf(m->units, sizeof m->units, "MM");
    m->unit_to_meter = 1e-3;
    char path[512], json[1024];
    snprintf(path, sizeof path, "%s/box_mm.igs", test_tmpdir());
    CHECK(sem_model_save(m, path, &err) == SEM_OK, "%s", err.message);
    sem_model_destroy(m);
    const char *fmt = "{\"objects\": [{\"model\": \"%s\"%s, \"material\": {\"density\": 1000}}],"
                      " \"frames\": 0}";
    char units[16] = "";
    double to_m = 0, size[3];
    snprintf(json, sizeof json, fmt, path, "");
    double mass = scene_mass(json, "units.json", ".", units, &to_m, size);
    printf("box in MM: %s (x %g), size %g x %g x %g m, mass %g kg\n", units, to_m, size[0], size[1],
           size[2], mass);
    CHECK(!strcmp(units, "MM") && to_m == 1e-3, "file units %s %g", units, to_m);
    CHECK_REL(size[0], 0.02, 1e-12);
    CHECK_REL(mass, 1000 * 0.02 * 0.01 * 0.005, 1e-6);
    snprintf(json, sizeof json, fmt, path, ", \"units\": \"as_metres\"");
    mass = scene_mass(json, "units.json", ".", units, &to_m, size);
    CHECK(!strcmp(units, "MM") && to_m == 1.0, "as_metres: %s %g", units, to_m);
    CHECK_REL(size[0], 20, 1e-12);
    CHECK_REL(mass, 1000 * 20 * 10 * 5, 1e-6);
    snprintf(json, sizeof json, fmt, path, ", \"units\": \"in\"");
    mass = scene_mass(json, "units.json", ".", units, &to_m, size);
    CHECK(!strcmp(units, "IN") && to_m == 0.0254, "in: %s %g", units, to_m);
    CHECK_REL(size[0], 20 * 0.0254, 1e-12);
    /* a bad unit name is a scene error naming the key */
    sem_scene *s = NULL;
    snprintf(json, sizeof json, fmt, path, ", \"units\": \"furlong\"");
    CHECK(sem_scene_parse(json, "units.json", ".", &s, &err) != SEM_OK &&
              strstr(err.message, "objects[0].units"),
          "bad unit: %s", err.message);
    sem_scene_destroy(s);
}

int main(void)
{
    double fem = fem_tip();
    if (fem > 0) {
        test_same_problem_same_answer(fem);
        test_deflection_rises(fem);
        test_authors_settings(fem);
        test_shared_fits(fem);
    }
    test_part_materials();
    test_units();
    return test_finish("test_defaults");
}
