/* test_simulation.c - elastodynamics against closed forms and conservation laws (issue 4). */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/material.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/simulation.h"
#include "test_util.h"

/* A 2 x 1 x 1 box (beam_sections 0) or a 1 x 1 x 1 m per section beam along x, preprocessed
 * with 4 x 4 rays, into s->model and s->disc. */
static int make_model(test_setup *s, int beam_sections, int order, int points_per_interval)
{
    memset(s, 0, sizeof *s);
    sem_error err;
    s->model = sem_model_create();
    if (beam_sections > 0) {
        sem_beam_def bm = sem_default_beam_def();
        bm.sections = beam_sections;
        bm.length = beam_sections;
        if (sem_primitive_beam(s->model, &bm, &err) != SEM_OK) {
            CHECK(0, "beam: %s", err.message);
            return 0;
        }
    } else {
        sem_box_def bd = sem_default_box_def();
        bd.size[0] = 2.0;
        bd.center[2] = 1.0;
        if (sem_primitive_box(s->model, &bd, &err) != SEM_OK) {
            CHECK(0, "box: %s", err.message);
            return 0;
        }
    }
    sem_preprocess_options po = sem_default_preprocess_options();
    po.order = order;
    po.rays[0] = po.rays[1] = 4;
    po.points_per_interval = points_per_interval;
    if (sem_preprocess(s->model, &po, &s->disc, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        return 0;
    }
    return 1;
}

/* make_model (4 points per interval) in a world of its own */
static int make_world(test_setup *s, int beam_sections, int order, const sem_world_def *wd,
                      const sem_object_def *od_in)
{
    if (!make_model(s, beam_sections, order, 4)) return 0;
    sem_error err;
    s->world = sem_world_create(wd, &err);
    CHECK(s->world != NULL, "world: %s", err.message);
    if (!s->world) return 0;
    sem_object_def od = od_in ? *od_in : sem_default_object_def();
    od.model = s->model;
    od.disc = s->disc;
    int id = sem_world_add_object(s->world, &od, &err);
    CHECK(id == 0, "add object: %s", err.message);
    return id == 0;
}

static int make_box_world(test_setup *s, int order, const sem_world_def *wd, const sem_object_def *od_in)
{
    return make_world(s, 0, order, wd, od_in);
}

/* Rotation of a make_model beam about its axis (y = z = 0.5) at rate rad/s. */
static sem_prescribe beam_axis_rotation(double rate)
{
    sem_prescribe pr;
    memset(&pr, 0, sizeof pr);
    pr.type = SEM_PRESCRIBE_ROTATE;
    pr.axis_point[1] = pr.axis_point[2] = 0.5;
    pr.axis_direction[0] = 1.0;
    pr.rate = rate;
    return pr;
}

/* Free fall with the linearly implicit Euler step: z_n = z0 - g h^2 n(n+1)/2 exactly,
 * because M (1 x g) = f_g and translations carry no elastic or error force. */
static void test_free_fall(void)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -9.81;
    wd.dt = 0.01;
    wd.integrator = SEM_LINEARLY_IMPLICIT_EULER;
    test_setup s;
    if (!make_box_world(&s, 2, &wd, NULL)) {
        test_setup_free(&s);
        return;
    }
    sem_object_stats st0, st;
    sem_world_object_stats(s.world, 0, &st0);
    sem_error err;
    int n = 50;
    for (int k = 0; k < n; ++k) CHECK(sem_world_step(s.world, &err) == SEM_OK, "%s", err.message);
    sem_world_object_stats(s.world, 0, &st);
    double drop = 9.81 * wd.dt * wd.dt * n * (n + 1) / 2.0;
    CHECK_REL(st0.center_of_mass[2] - st.center_of_mass[2], drop, 1e-9);
    CHECK_NEAR(st.center_of_mass[0], st0.center_of_mass[0], 1e-9 * drop);
    CHECK_REL(st.linear_momentum[2], -st.mass * 9.81 * wd.dt * n, 1e-9);
    CHECK_REL(st0.volume, 2.0, 1e-12);
    test_setup_free(&s);
}

/* Zero gravity: linear momentum is conserved to round-off by the linearly implicit step
 * (1^T K = 0 and internal forces sum to zero); a spinning body stays bounded; with
 * implicit Euler the total energy never increases. */
static void test_momentum_and_spin(void)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.dt = 0.01;
    sem_object_def od = sem_default_object_def();
    od.initial_velocity[0] = 1.0;
    od.initial_velocity[1] = -0.5;
    od.initial_angular_velocity[2] = 2.0;
    test_setup s;
    if (!make_box_world(&s, 2, &wd, &od)) {
        test_setup_free(&s);
        return;
    }
    sem_object_stats st0, st;
    sem_world_object_stats(s.world, 0, &st0);
    sem_error err;
    int steps = getenv("SEM_SANITIZED") ? 100 : 500, ok = 1;
    for (int k = 0; k < steps && ok; ++k) ok = sem_world_step(s.world, &err) == SEM_OK;
    CHECK(ok, "step failed: %s", err.message);
    sem_world_object_stats(s.world, 0, &st);
    double pnorm = st0.mass * hypot(1.0, 0.5);
    for (int k = 0; k < 3; ++k) CHECK_NEAR(st.linear_momentum[k], st0.linear_momentum[k], 1e-10 * pnorm);
    CHECK(isfinite(st.kinetic_energy) && st.kinetic_energy <= 1.01 * st0.kinetic_energy,
          "spinning body blew up: KE %g -> %g", st0.kinetic_energy, st.kinetic_energy);
    CHECK(st.kinetic_energy > 0.5 * st0.kinetic_energy, "spin died out: KE %g -> %g", st0.kinetic_energy,
          st.kinetic_energy);
    test_setup_free(&s);

    wd.integrator = SEM_IMPLICIT_EULER;
    if (!make_box_world(&s, 2, &wd, &od)) {
        test_setup_free(&s);
        return;
    }
    sem_world_object_stats(s.world, 0, &st0);
    double E_prev = st0.kinetic_energy + st0.elastic_energy + st0.error_energy;
    int increases = 0;
    steps = getenv("SEM_SANITIZED") ? 30 : 150;
    for (int k = 0; k < steps && ok; ++k) {
        ok = sem_world_step(s.world, &err) == SEM_OK;
        sem_world_object_stats(s.world, 0, &st);
        double E = st.kinetic_energy + st.elastic_energy + st.error_energy;
        if (E > E_prev * (1 + 1e-9)) increases++;
        E_prev = E;
    }
    CHECK(ok, "implicit step failed: %s", err.message);
    CHECK(increases == 0, "total energy increased in %d implicit Euler steps", increases);
    test_setup_free(&s);
}

/* Patch test (Fig. 9): every control point prescribed by an affine map; the elastic
 * energy equals psi(A) x volume; zero for a rotation. */
static void patch_test(sem_model *model, const char *what)
{
    sem_error err;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.order = 2;
    sem_discretization *disc = NULL;
    if (sem_preprocess(model, &po, &disc, &err) != SEM_OK) {
        CHECK(0, "%s: preprocess: %s", what, err.message);
        return;
    }
    double A[3][12] = {
        {1.2, 0.1, 0.0, 0.3, 0.05, 0.9, 0.1, -0.2, 0.0, 0.02, 1.1, 0.5}, /* stretch + shear */
        {1.0, 0.3, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0},   /* simple shear */
        {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0},                           /* rotation, below */
    };
    double ang = 0.7, c = cos(ang), s = sin(ang);
    double R[12] = {c, -s, 0, 1.0, s, c, 0, 2.0, 0, 0, 1, -0.5};
    memcpy(A[2], R, sizeof R);
    for (int k = 0; k < 3; ++k) {
        sem_world_def wd = sem_default_world_def();
        wd.gravity[2] = 0;
        wd.integrator = SEM_STATIC;
        sem_world *w = sem_world_create(&wd, &err);
        sem_object_def od = sem_default_object_def();
        od.model = model;
        od.disc = disc;
        od.prescribe.type = SEM_PRESCRIBE_AFFINE;
        memcpy(od.prescribe.affine, A[k], sizeof R);
        int id = sem_world_add_object(w, &od, &err);
        CHECK(id == 0, "%s: %s", what, err.message);
        if (id == 0) {
            CHECK(sem_world_solve_static(w, &err) == SEM_OK, "%s: %s", what, err.message);
            sem_object_stats st;
            sem_world_object_stats(w, 0, &st);
            sem_material mat = od.material;
            sem_material_init(&mat, &err);
            double F[9] = {A[k][0], A[k][1], A[k][2], A[k][4], A[k][5], A[k][6], A[k][8], A[k][9], A[k][10]};
            double psi = sem_material_energy(&mat, F, NULL, NULL);
            if (k < 2)
                CHECK_REL(st.elastic_energy, psi * st.volume, 1e-8);
            else
                CHECK_NEAR(st.elastic_energy, 0.0, 1e-10 * mat.mu * st.volume);
            CHECK_NEAR(st.error_energy, 0.0, 1e-10 * (st.elastic_energy + mat.mu * st.volume));
        }
        sem_world_destroy(w);
    }
    sem_discretization_destroy(disc);
}

static void test_patch(void)
{
    sem_error err;
    sem_model *box = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    if (sem_primitive_box(box, &bd, &err) == SEM_OK) patch_test(box, "box");
    sem_model_destroy(box);
    const char *path = test_shared_model("rounded_cube.iges");
    if (path) {
        sem_model *m = NULL;
        if (sem_model_load(path, &m, &err) == SEM_OK)
            patch_test(m, "rounded_cube");
        else
            CHECK(0, "rounded_cube: %s", err.message);
        sem_model_destroy(m);
    }
}


/* Twisting beam (Fig. 12): left end fixed, right end rotated 90 degrees about the beam
 * axis, static solve. The fixed end stays, the rotated end follows the prescribed
 * rotation exactly, and by symmetry of uniform torsion the middle section turns about half. */
static void test_twist(void)
{
    sem_error err;
    test_setup s;
    if (!make_model(&s, 4, 2, 8)) {
        test_setup_free(&s);
        return;
    }
    sem_model *m = s.model;
    size_t nc = sem_model_control_points(m);
    double *q0 = malloc(3 * nc * sizeof(double));
    int *group = malloc(nc * sizeof(int));
    sem_model_get_q(m, q0);
    for (size_t c = 0; c < nc; ++c) group[c] = fabs(q0[3 * c]) < 1e-9 ? 0 : fabs(q0[3 * c] - 4.0) < 1e-9 ? 1 : -1;
    sem_prescribe pr[2];
    memset(pr, 0, sizeof pr);
    pr[0].type = SEM_PRESCRIBE_AFFINE; /* identity: fixed */
    pr[0].affine[0] = pr[0].affine[5] = pr[0].affine[10] = 1.0;
    pr[1] = beam_axis_rotation(M_PI / 2); /* 90 degrees after 1 s */
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.integrator = SEM_STATIC;
    wd.dt = 1.0;
    sem_world *w = s.world = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = m;
    od.disc = s.disc;
    od.prescribe_group = group;
    od.prescribes = pr;
    od.n_prescribes = 2;
    CHECK(sem_world_add_object(w, &od, &err) == 0, "%s", err.message);
    CHECK(sem_world_step(w, &err) == SEM_OK, "static twist: %s", err.message);
    const double *q = sem_world_object_q(w, 0);
    double worst_fixed = 0, worst_rot = 0, mid_angle = 0;
    int n_mid = 0;
    for (size_t c = 0; c < nc; ++c) {
        const double *x0 = q0 + 3 * c, *x = q + 3 * c;
        const double *ax = pr[1].axis_point;
        double y0 = x0[1] - ax[1], z0 = x0[2] - ax[2];
        double y = x[1] - ax[1], z = x[2] - ax[2];
        if (group[c] == 0) worst_fixed = fmax(worst_fixed, fabs(x[0] - x0[0]) + fabs(x[1] - x0[1]) + fabs(x[2] - x0[2]));
        if (group[c] == 1) worst_rot = fmax(worst_rot, fabs(y - (-z0)) + fabs(z - y0) + fabs(x[0] - x0[0]));
        if (fabs(x0[0] - 2.0) < 1e-9 && hypot(y0, z0) > 0.3) {
            double a = atan2(z, y) - atan2(z0, y0);
            while (a > M_PI) a -= 2 * M_PI;
            while (a < -M_PI) a += 2 * M_PI;
            mid_angle += a;
            n_mid++;
        }
    }
    CHECK(worst_fixed < 1e-12, "fixed end moved by %g", worst_fixed);
    CHECK(worst_rot < 1e-12, "rotated end off its prescribed rotation by %g", worst_rot);
    CHECK(n_mid > 0, "no control points at the middle section");
    if (n_mid > 0) {
        mid_angle /= n_mid;
        printf("twist: middle section turned %.2f degrees for 90 at the end\n", mid_angle * 180 / M_PI);
        CHECK(mid_angle > 35 * M_PI / 180 && mid_angle < 55 * M_PI / 180, "middle section turned %g degrees",
              mid_angle * 180 / M_PI);
    }
    test_setup_free(&s);
    free(group);
    free(q0);
}

/* Bad world definitions are errors. */
static void test_bad_world(void)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.dt = 0;
    CHECK(sem_world_create(&wd, &err) == NULL, "dt = 0 accepted");
    CHECK(strstr(err.message, "dt") != NULL, "%s", err.message);
    wd.dt = -1;
    CHECK(sem_world_create(&wd, &err) == NULL, "dt < 0 accepted");
}

/* Per-part materials: the object keeps initialized copies, so the caller may pass materials
 * with only E and nu set and free its arrays right after adding the object. All parts on a
 * copy of the default material move exactly as with the default material; a copy of twice
 * the density doubles the mass. */
static double spin_elastic_energy(int n_part_materials, double density_factor, double *mass)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.dt = 0.01;
    /* one solver for both runs: the automatic choice times both, and under load could
     * pick dense for one run and sparse for the other (round-off differs) */
    wd.solver = SEM_SOLVER_SPARSE;
    sem_object_def od = sem_default_object_def();
    od.initial_angular_velocity[2] = 3.0;
    enum { BOX_PARTS = 6 }; /* sem_primitive_box's patches */
    int *pm = NULL;
    sem_material *mats = NULL;
    if (n_part_materials > 0) {
        pm = malloc(BOX_PARTS * sizeof *pm);
        mats = calloc(1, sizeof *mats);
        if (!pm || !mats) {
            free(pm);
            free(mats);
            return -1;
        }
        for (int p = 0; p < BOX_PARTS; ++p) pm[p] = 0;
        mats[0].type = od.material.type;
        mats[0].density = density_factor * od.material.density;
        mats[0].youngs_modulus = od.material.youngs_modulus;
        mats[0].poisson_ratio = od.material.poisson_ratio; /* mu, lambda left 0 */
        od.part_material = pm;
        od.part_materials = mats;
        od.n_part_materials = 1;
    }
    test_setup s;
    int ok = make_box_world(&s, 2, &wd, &od);
    free(pm); /* the object must not need them after it is added */
    free(mats);
    if (ok) CHECK(s.model->n_parts == BOX_PARTS, "box has %d parts", s.model->n_parts);
    sem_error err;
    for (int k = 0; k < 20 && ok; ++k) ok = sem_world_step(s.world, &err) == SEM_OK;
    double e = -1;
    if (ok) {
        sem_object_stats st;
        sem_world_object_stats(s.world, 0, &st);
        e = st.elastic_energy;
        *mass = st.mass;
    } else {
        CHECK(0, "spinning box failed");
    }
    test_setup_free(&s);
    return e;
}

/* The stiffness is summed over the points in chunks (8192 points each by default); a
 * chunk of 7 points gives the same state bit for bit after a few steps of a spinning,
 * falling soft box on one thread (the per-pair sums run in point order either way).
 * Returns the final control points (malloc'd, *n values) or NULL. */
static double *chunked_run(int chunk, size_t *n)
{
    sem_world_def wd = sem_default_world_def();
    wd.threads = 1;
    wd.solver = SEM_SOLVER_SPARSE;
    sem_object_def od = sem_default_object_def();
    od.initial_angular_velocity[0] = 2.0;
    od.initial_angular_velocity[2] = 3.0;
    od.material.youngs_modulus = 1e5;
    wd.advanced.assembly_chunk = chunk;
    test_setup s;
    int ok = make_box_world(&s, 2, &wd, &od);
    sem_error err;
    for (int k = 0; k < 5 && ok; ++k) ok = sem_world_step(s.world, &err) == SEM_OK;
    double *q = NULL;
    if (ok) {
        CHECK(s.disc->n_quad > 5 * 7, "only %d points", s.disc->n_quad);
        *n = (size_t)sem_world_object_dofs(s.world, 0);
        q = malloc(*n * sizeof(double));
        if (q) memcpy(q, sem_world_object_q(s.world, 0), *n * sizeof(double));
    } else {
        CHECK(0, "chunked box run failed");
    }
    test_setup_free(&s);
    return q;
}

static void test_assembly_chunks(void)
{
    size_t na = 0, nb = 0;
    double *qa = chunked_run(0, &na), *qb = chunked_run(7, &nb);
    if (qa && qb && na == nb) {
        size_t differ = 0;
        for (size_t i = 0; i < na; ++i) differ += qa[i] != qb[i];
        CHECK(differ == 0, "%zu of %zu coordinates differ between chunks of 8192 and of 7 points",
              differ, na);
    } else {
        CHECK(0, "chunked runs failed");
    }
    free(qa);
    free(qb);
}

/* The driven-beam set-up: a 3-section make_model beam whose x = 0 end cap follows pr, in a
 * world without gravity (dt 0.01), E 1e7, rho 1000, starting at angular velocity spin about x.
 * *q0 gets the rest control points and *group the cap (0) and the rest (-1), both freed by the
 * caller. Returns 1 when the object is in the world. */
static int driven_beam(test_setup *s, const sem_prescribe *pr, double spin, double **q0, int **group,
                       size_t *nc)
{
    sem_error err;
    *q0 = NULL;
    *group = NULL;
    if (!make_model(s, 3, 2, 6)) return 0;
    *nc = sem_model_control_points(s->model);
    *q0 = malloc(3 * *nc * sizeof(double));
    *group = malloc(*nc * sizeof(int));
    if (!*q0 || !*group) return 0;
    sem_model_get_q(s->model, *q0);
    for (size_t c = 0; c < *nc; ++c) (*group)[c] = fabs((*q0)[3 * c]) < 1e-9 ? 0 : -1;
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.dt = 0.01;
    s->world = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = s->model;
    od.disc = s->disc;
    od.prescribe_group = *group;
    od.prescribes = pr;
    od.n_prescribes = 1;
    od.material.youngs_modulus = 1e7;
    od.material.density = 1000;
    od.initial_angular_velocity[0] = spin;
    int ok = s->world && sem_world_add_object(s->world, &od, &err) == 0;
    CHECK(ok, "%s", err.message);
    return ok;
}

/* A pinned end moved at a constant velocity (SEM_PRESCRIBE_MOVE): the pinned control points
 * are at x0 + v min(t, duration) after every step, exactly, and the beam they pull follows
 * (its centre of mass moves by most of v t). */
static void test_driven_move(void)
{
    sem_error err;
    test_setup s;
    size_t nc = 0;
    double *q0 = NULL;
    int *group = NULL;
    sem_prescribe pr;
    memset(&pr, 0, sizeof pr);
    pr.type = SEM_PRESCRIBE_MOVE;
    pr.velocity[0] = 0.3;
    pr.velocity[2] = -0.4;
    pr.duration = 0.2;
    int ok = driven_beam(&s, &pr, 0, &q0, &group, &nc);
    sem_object_stats st0, st;
    if (ok) sem_world_object_stats(s.world, 0, &st0);
    double worst = 0;
    for (int k = 0; k < 30 && ok; ++k) {
        ok = sem_world_step(s.world, &err) == SEM_OK;
        CHECK(ok, "step %d: %s", k, err.message);
        const double t = sem_world_time(s.world), tt = t < pr.duration ? t : pr.duration;
        const double *q = sem_world_object_q(s.world, 0);
        for (size_t c = 0; ok && c < nc; ++c)
            for (int i = 0; group[c] == 0 && i < 3; ++i)
                worst = fmax(worst, fabs(q[3 * c + i] - (q0[3 * c + i] + pr.velocity[i] * tt)));
    }
    if (ok) sem_world_object_stats(s.world, 0, &st);
    double moved = ok ? st.center_of_mass[0] - st0.center_of_mass[0] : 0;
    printf("driven move: pinned points %.3e m from x0 + v min(t, duration); centre of mass moved %.4f m "
           "along x (the end %.4f m)\n",
           worst, moved, pr.velocity[0] * pr.duration);
    CHECK(ok && worst <= 1e-12, "pinned points are %g m off their prescribed path", worst);
    CHECK(ok && moved > 0.5 * pr.velocity[0] * pr.duration, "the beam does not follow its end (%g m)", moved);
    test_setup_free(&s);
    free(q0);
    free(group);
}

/* Driven rotation with the paper's linearly implicit step: the x = 0 end cap of a
 * 3-section beam turns about the beam's axis at a constant rate (zero gravity) and the
 * whole beam starts with that angular velocity. A rigid rotation is a zero mode of K, so
 * the free rows of (M + h^2 K) v+ = M v are solved by the rigid velocity only if the
 * pinned points' velocities enter the right-hand side through the right stiffness block
 * A_fp (kept for one triangle of group pairs, the other being its transpose). After 0.4 s
 * (0.2 rad) every free control point of the 1 m wide beam is within 1.5e-4 m of the rigidly rotated
 * rest position (3.4e-5 measured; the tangential steps drift off the circle). Without
 * the transposed blocks the worst point is 9e-4 off, without A_fp's stiffness 3.9e-3. */
static void test_driven_rotation(void)
{
    sem_error err;
    test_setup s;
    size_t nc = 0;
    double *q0 = NULL;
    int *group = NULL;
    sem_prescribe pr = beam_axis_rotation(0.5);
    /* the whole beam already turns with its cap */
    int ok = driven_beam(&s, &pr, pr.rate, &q0, &group, &nc);
    for (int k = 0; k < 40 && ok; ++k) {
        ok = sem_world_step(s.world, &err) == SEM_OK;
        CHECK(ok, "step %d: %s", k, err.message);
    }
    if (ok) {
        const double *q = sem_world_object_q(s.world, 0);
        double ang = pr.rate * sem_world_time(s.world), cs = cos(ang), sn = sin(ang), worst = 0;
        for (size_t c = 0; c < nc; ++c) {
            if (group[c] == 0) continue;
            const double *x0 = q0 + 3 * c, *x = q + 3 * c;
            double y0 = x0[1] - pr.axis_point[1], z0 = x0[2] - pr.axis_point[2];
            double ry = pr.axis_point[1] + cs * y0 - sn * z0, rz = pr.axis_point[2] + sn * y0 + cs * z0;
            worst = fmax(worst, sqrt((x[0] - x0[0]) * (x[0] - x0[0]) + (x[1] - ry) * (x[1] - ry) +
                                     (x[2] - rz) * (x[2] - rz)));
        }
        printf("driven rotation: worst free point %.3e m from the rigid rotation (%.3f rad)\n", worst, ang);
        CHECK(worst < 1.5e-4, "free points are up to %g m off the rigid rotation (beam width 1 m)", worst);
    }
    test_setup_free(&s);
    free(q0);
    free(group);
}

/* Rayleigh damping C = a M + b K0 in the linearly implicit step: translation is a zero
 * mode of K and K0 (of every group-pair block: a translation has no polynomial
 * coefficient with a gradient), and internal forces sum to zero, so summing the rows of
 * (M + h C + h^2 K) v+ = M v + h f gives p+ = p / (1 + h a) exactly, for a spinning,
 * deforming 3-section beam too. Checks the mass-proportional damping in the system
 * matrix against that closed form. */
static void test_rayleigh_momentum(void)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.dt = 0.01;
    wd.rayleigh_mass = 0.5;
    wd.rayleigh_stiffness = 0.002;
    sem_object_def od = sem_default_object_def();
    od.initial_velocity[0] = 1.0;
    od.initial_velocity[1] = -0.5;
    od.initial_velocity[2] = 0.25;
    od.initial_angular_velocity[2] = 2.0;
    test_setup s;
    if (!make_world(&s, 3, 2, &wd, &od)) {
        test_setup_free(&s);
        return;
    }
    CHECK(s.disc->n_origins > 1, "the beam has %d origin(s)", s.disc->n_origins);
    sem_object_stats st0, st;
    sem_world_object_stats(s.world, 0, &st0);
    sem_error err;
    int steps = 100, ok = 1;
    for (int k = 0; k < steps && ok; ++k) ok = sem_world_step(s.world, &err) == SEM_OK;
    CHECK(ok, "damped step failed: %s", err.message);
    sem_world_object_stats(s.world, 0, &st);
    double decay = pow(1.0 + wd.dt * wd.rayleigh_mass, -steps);
    double pnorm = sqrt(st0.linear_momentum[0] * st0.linear_momentum[0] + st0.linear_momentum[1] * st0.linear_momentum[1] +
                        st0.linear_momentum[2] * st0.linear_momentum[2]);
    CHECK(pnorm > 0.5 * st0.mass, "no initial momentum (%g)", pnorm);
    for (int k = 0; k < 3; ++k) CHECK_NEAR(st.linear_momentum[k], decay * st0.linear_momentum[k], 1e-9 * pnorm);
    test_setup_free(&s);
}

static void test_part_materials(void)
{
    double m_default = 0, m_copy = 0, m_dense = 0;
    double e_default = spin_elastic_energy(0, 1.0, &m_default);
    double e_copy = spin_elastic_energy(1, 1.0, &m_copy);
    spin_elastic_energy(1, 2.0, &m_dense);
    CHECK(e_default > 0, "spinning box has no elastic energy (%g)", e_default);
    CHECK_REL(e_copy, e_default, 1e-12);
    CHECK_REL(m_copy, m_default, 1e-14);
    CHECK_REL(m_dense, 2.0 * m_default, 1e-14);
}

/* Log callback of test_counters: counts Newton's trace lines. */
static void count_lines(void *user, int level, const char *message)
{
    int *lines = user;
    if (level == 0 && strncmp(message, "newton it ", 10) == 0) ++*lines;
}

/* The linearly implicit step's rest factor (integrators.c, "Reusing the rest factor"),
 * against factorizing every step (advanced.refactorize). A cantilever 3 m long, clamped at
 * x = 0, sagging under gravity (E 1e8: 1.6 cm in 0.3 s): the rest factor serves every step
 * (one factorization in all). A box spinning at 10 rad/s: its stiffness rotates away from the
 * rest one, and once the change passes the threshold the step factorizes again. Both give the
 * states of the factorizing step to round-off (1e-10 of the motion here), with CHOLMOD and with
 * the structured solver (whose rest factor preconditions its conjugate gradients). */
static void test_rest_factor(void)
{
    for (int run = 0; run < 4; ++run) {
        int spin = run % 2, structured = run / 2;
        double *q[2] = {NULL, NULL}, *q0 = NULL;
        unsigned char *pin = NULL;
        long factorizations[2] = {0, 0};
        int steps = spin ? 20 : 30;
        size_t nc = 0;
        for (int refactorize = 0; refactorize < 2; ++refactorize) {
            test_setup s;
            if (!make_model(&s, spin ? 0 : 3, 2, 4)) {
                test_setup_free(&s);
                goto done;
            }
            nc = sem_model_control_points(s.model);
            if (!q0) {
                q0 = malloc(3 * nc * sizeof(double));
                pin = calloc(nc, 1);
                sem_model_get_q(s.model, q0);
                for (size_t c = 0; c < nc && !spin; ++c) pin[c] = fabs(q0[3 * c]) < 1e-9;
            }
            sem_error err;
            sem_world_def wd = sem_default_world_def();
            wd.gravity[2] = spin ? 0.0 : -9.81;
            wd.dt = 0.01;
            wd.integrator = SEM_LINEARLY_IMPLICIT_EULER;
            wd.solver = structured ? SEM_SOLVER_STRUCTURED : SEM_SOLVER_SPARSE;
            wd.advanced.refactorize = refactorize;
            s.world = sem_world_create(&wd, &err);
            sem_object_def od = sem_default_object_def();
            od.model = s.model;
            od.disc = s.disc;
            od.pinned = spin ? NULL : pin;
            od.material.youngs_modulus = spin ? 1e5 : 1e8;
            od.initial_angular_velocity[2] = spin ? 10.0 : 0.0;
            int ok = s.world && sem_world_add_object(s.world, &od, &err) == 0;
            CHECK(ok, "world: %s", err.message);
            for (int k = 0; k < steps && ok; ++k) {
                ok = sem_world_step(s.world, &err) == SEM_OK;
                CHECK(ok, "spin %d refactorize %d step %d: %s", spin, refactorize, k, err.message);
            }
            if (ok) {
                q[refactorize] = malloc(3 * nc * sizeof(double));
                memcpy(q[refactorize], sem_world_object_q(s.world, 0), 3 * nc * sizeof(double));
                factorizations[refactorize] = sem_world_get_counters(s.world).factorizations;
            }
            test_setup_free(&s);
        }
        if (q[0] && q[1]) {
            double motion = 0, diff = 0;
            for (size_t i = 0; i < 3 * nc; ++i) {
                motion = fmax(motion, fabs(q[1][i] - q0[i]));
                diff = fmax(diff, fabs(q[0][i] - q[1][i]));
            }
            printf("rest factor, %s, %s: motion %.3g m, rest factor vs factorizing %.3g m, %ld factorizations "
                   "(%ld factorizing every step)\n",
                   spin ? "spinning box" : "cantilever", structured ? "structured" : "cholmod", motion, diff,
                   factorizations[0], factorizations[1]);
            CHECK(motion > (spin ? 0.5 : 1e-3) && motion < (spin ? 3.0 : 0.05), "spin %d: motion %g m", spin, motion);
            CHECK(diff <= 1e-10 * motion, "spin %d: rest factor vs factorizing: %g m of %g m", spin, diff, motion);
            CHECK(factorizations[1] == steps, "spin %d: %ld factorizations", spin, factorizations[1]);
            if (spin)
                CHECK(factorizations[0] > 2 && factorizations[0] <= steps + 1,
                      "spinning: %ld factorizations with the rest factor", factorizations[0]);
            else
                CHECK(factorizations[0] == 1, "cantilever: %ld factorizations with the rest factor",
                      factorizations[0]);
        }
    done:
        free(q[0]);
        free(q[1]);
        free(q0);
        free(pin);
    }
}

/* The world's counters (sem_world_get_counters) and Newton's trace: the linearly implicit
 * step factorizes once per step and runs no Newton iteration; Newton factorizes once per
 * iteration plus once per fallback to the projected Hessian, and traces one line per
 * iteration to the world's log; the trace changes no bit of the result. */
static void test_counters(void)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -9.81;
    wd.integrator = SEM_LINEARLY_IMPLICIT_EULER;
    wd.solver = SEM_SOLVER_SPARSE;
    wd.advanced.refactorize = 1; /* (test_rest_factor: otherwise the rest factor serves) */
    test_setup s;
    if (make_box_world(&s, 2, &wd, NULL)) {
        for (int k = 0; k < 3; ++k) CHECK(sem_world_step(s.world, &err) == SEM_OK, "%s", err.message);
        sem_world_counters c = sem_world_get_counters(s.world);
        CHECK(c.steps == 3 && c.factorizations == 3 && c.newton_iterations == 0,
              "linearly implicit: %ld steps, %ld factorizations, %ld Newton iterations", c.steps,
              c.factorizations, c.newton_iterations);
    }
    test_setup_free(&s);
    /* implicit Euler on a soft box, without and with the trace */
    double *q[2] = {NULL, NULL};
    size_t n = 0;
    for (int trace = 0; trace < 2; ++trace) {
        int lines = 0;
        wd.integrator = SEM_IMPLICIT_EULER;
        wd.log = count_lines;
        wd.log_user = &lines;
        wd.advanced.trace_newton = trace;
        sem_object_def od = sem_default_object_def();
        od.material.youngs_modulus = 1e5;
        if (!make_box_world(&s, 2, &wd, &od)) {
            test_setup_free(&s);
            break;
        }
        long iterations = 0;
        for (int k = 0; k < 3; ++k) {
            CHECK(sem_world_step(s.world, &err) == SEM_OK, "%s", err.message);
            iterations += sem_world_last_iterations(s.world);
        }
        sem_world_counters c = sem_world_get_counters(s.world);
        CHECK(c.steps == 3, "%ld steps", c.steps);
        CHECK(c.newton_iterations == iterations && iterations >= 3,
              "%ld Newton iterations counted, %ld reported by the steps", c.newton_iterations,
              iterations);
        CHECK(c.factorizations == c.newton_iterations + c.exact_hessian_fallbacks,
              "%ld factorizations, %ld iterations, %ld fallbacks", c.factorizations,
              c.newton_iterations, c.exact_hessian_fallbacks);
        CHECK(lines == (trace ? iterations : 0), "trace %d: %d lines for %ld iterations", trace,
              lines, iterations);
        n = (size_t)sem_world_object_dofs(s.world, 0);
        q[trace] = malloc(n * sizeof(double));
        if (q[trace]) memcpy(q[trace], sem_world_object_q(s.world, 0), n * sizeof(double));
        test_setup_free(&s);
    }
    if (q[0] && q[1]) CHECK(memcmp(q[0], q[1], n * sizeof(double)) == 0, "the trace changed the result");
    free(q[0]);
    free(q[1]);
}

/* Two objects in a world, each in its own system or both in one (advanced.solve_together,
 * the layout contact will need): a falling, spinning box and a 2-section beam clamped at
 * x = 0 sagging under gravity. The one system has both matrices as diagonal blocks, its
 * free dofs numbered object after object (the beam's pinned points left out), so the
 * motion must be the same up to round-off (linearly implicit Euler: one factorization per
 * step instead of two) and up to Newton's joint stopping test (implicit Euler). Returns
 * the largest difference of a control point between the two worlds, NaN on failure. */
static double together_difference(sem_integrator integrator, int steps)
{
    test_setup box, beam;
    int ok = make_model(&box, 0, 2, 4);
    ok = make_model(&beam, 2, 2, 4) && ok;
    size_t nc = ok ? sem_model_control_points(beam.model) : 0;
    double *q0 = malloc(3 * nc * sizeof(double) + 1);
    unsigned char *pin = calloc(nc + 1, 1);
    sem_world *world[2] = {NULL, NULL};
    double worst = NAN;
    if (!ok || !q0 || !pin) goto done;
    sem_model_get_q(beam.model, q0);
    for (size_t c = 0; c < nc; ++c) pin[c] = fabs(q0[3 * c]) < 1e-9;
    for (int together = 0; together < 2; ++together) {
        sem_error err;
        sem_world_def wd = sem_default_world_def();
        wd.integrator = integrator;
        wd.solver = SEM_SOLVER_SPARSE;
        wd.advanced.solve_together = together;
        /* the two overlap: without contact they pass through each other (with it, contact
         * would also put them in one system) */
        wd.contact.disabled = 1;
        world[together] = sem_world_create(&wd, &err);
        sem_object_def od = sem_default_object_def();
        od.model = box.model;
        od.disc = box.disc;
        od.material.youngs_modulus = 1e5;
        od.initial_angular_velocity[1] = 2.0;
        ok = world[together] && sem_world_add_object(world[together], &od, &err) == 0;
        od = sem_default_object_def();
        od.model = beam.model;
        od.disc = beam.disc;
        od.pinned = pin;
        ok = ok && sem_world_add_object(world[together], &od, &err) == 1;
        CHECK(ok, "together %d: %s", together, err.message);
        for (int k = 0; k < steps && ok; ++k) {
            ok = sem_world_step(world[together], &err) == SEM_OK;
            CHECK(ok, "together %d, step %d: %s", together, k, err.message);
        }
        if (!ok) goto done;
    }
    sem_world_counters c[2] = {sem_world_get_counters(world[0]), sem_world_get_counters(world[1])};
    /* (one factorization per step and system, or fewer where the rest factor serves:
     * test_rest_factor; the objects touch, so together is never cheaper than apart) */
    if (integrator == SEM_LINEARLY_IMPLICIT_EULER)
        CHECK(c[0].factorizations <= 2 * steps && c[1].factorizations <= steps &&
                  c[1].factorizations >= 1 && c[0].factorizations >= c[1].factorizations,
              "%ld factorizations apart, %ld together, %d steps", c[0].factorizations,
              c[1].factorizations, steps);
    CHECK(strcmp(sem_world_solver_name(world[1], 0), "cholmod") == 0 &&
              strcmp(sem_world_solver_name(world[1], 1), "cholmod") == 0,
          "solver names");
    worst = 0;
    for (int i = 0; i < 2; ++i) {
        const double *qa = sem_world_object_q(world[0], i), *qb = sem_world_object_q(world[1], i);
        for (int k = 0; k < sem_world_object_dofs(world[0], i); ++k) worst = fmax(worst, fabs(qa[k] - qb[k]));
    }
    /* the beam's clamped end stays put in the one system too */
    const double *qb = sem_world_object_q(world[1], 1);
    size_t moved = 0;
    for (size_t c2 = 0; c2 < nc; ++c2) moved += pin[c2] && memcmp(qb + 3 * c2, q0 + 3 * c2, 3 * sizeof(double)) != 0;
    CHECK(moved == 0, "%zu pinned points moved", moved);
done:
    sem_world_destroy(world[0]);
    sem_world_destroy(world[1]);
    free(q0);
    free(pin);
    test_setup_free(&box);
    test_setup_free(&beam);
    return worst;
}

static void test_solve_together(void)
{
    double linear = together_difference(SEM_LINEARLY_IMPLICIT_EULER, 5);
    double newton = together_difference(SEM_IMPLICIT_EULER, 3);
    printf("solved together: control points differ by %.3g m (linearly implicit), %.3g m "
           "(implicit Euler)\n", linear, newton);
    CHECK(linear <= 1e-10, "linearly implicit: %g m apart", linear);
    CHECK(newton <= 1e-6, "implicit Euler: %g m apart", newton);
}

int main(void)
{
    test_free_fall();
    test_part_materials();
    test_assembly_chunks();
    test_counters();
    test_rest_factor();
    test_solve_together();
    test_driven_rotation();
    test_driven_move();
    test_rayleigh_momentum();
    test_momentum_and_spin();
    test_patch();
    test_twist();
    test_bad_world();
    return test_finish("test_simulation");
}
