/* test_contact.c - contact and friction (issue 13): a rubber box dropped on a plane comes to
 * rest at the right height without sinking in, a box on a 30-degree incline sticks with
 * mu = 0.8 and slides with a = g (sin 30 - mu cos 30) with mu = 0.2, a sphere dropped into a
 * V-shaped triangle-mesh valley settles at its bottom; colliders and contact settings from
 * scene files, and their errors. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <cjson/cJSON.h>

#include "contact/friction.h"
#include "contact/narrow_phase.h"
#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/scene.h"
#include "sem/simulation.h"
#include "test_util.h"

#define G 9.81

/* A rubber solid (rho 1000, E 1e6, nu 0.45), coarsely preprocessed (4 x 4 rays: the contact
 * numbers do not depend on the quadrature's resolution), in a world with the given gravity
 * and integrator, with friction mu on the object. sphere: radius 0.5 at center, else a 1 m
 * box. */
static int make(test_setup *s, int sphere, const double center[3], const double gravity[3], sem_integrator integ,
                double mu)
{
    memset(s, 0, sizeof *s);
    sem_error err;
    s->model = sem_model_create();
    sem_status st;
    if (sphere) {
        sem_sphere_def sd = sem_default_sphere_def();
        sd.radius = 0.5;
        st = sem_primitive_sphere(s->model, &sd, &err);
        for (size_t c = 0; st == SEM_OK && c < (size_t)s->model->parts[0].surface.n_u * s->model->parts[0].surface.n_v; ++c)
            for (int k = 0; k < 3; ++k) s->model->parts[0].surface.ctrl[3 * c + k] += center[k];
    } else {
        sem_box_def bd = sem_default_box_def();
        memcpy(bd.center, center, sizeof bd.center);
        st = sem_primitive_box(s->model, &bd, &err);
    }
    CHECK(st == SEM_OK, "primitive: %s", err.message);
    if (st != SEM_OK) return 0;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.rays[0] = po.rays[1] = 4;
    po.points_per_interval = 4;
    po.q_space_operators = 1; /* contact needs the q-space solvers (point_terms.h) */
    if (sem_preprocess(s->model, &po, &s->disc, &err) != SEM_OK) {
        CHECK(0, "preprocess: %s", err.message);
        return 0;
    }
    sem_world_def wd = sem_default_world_def();
    memcpy(wd.gravity, gravity, sizeof wd.gravity);
    wd.integrator = integ;
    wd.dt = 0.01;
    wd.contact.resolution = 8;
    wd.advanced.q_space_solvers = 1; /* the structured solver takes no contact terms yet */
    s->world = sem_world_create(&wd, &err);
    CHECK(s->world != NULL, "world: %s", err.message);
    if (!s->world) return 0;
    sem_object_def od = sem_default_object_def();
    od.model = s->model;
    od.disc = s->disc;
    od.friction = mu;
    int id = sem_world_add_object(s->world, &od, &err);
    CHECK(id == 0, "add object: %s", err.message);
    return id == 0;
}

static int add_plane(test_setup *s, double mu)
{
    sem_error err;
    sem_collider_def cd = sem_default_collider_def();
    cd.friction = mu;
    int id = sem_world_add_collider(s->world, &cd, &err);
    CHECK(id == 0, "collider: %s", err.message);
    return id == 0;
}

/* Number 1: the box dropped from 0.5 m (its bottom 0.5 m above the plane). Penetration never
 * beyond 2 % of its size; after 3 s the kinetic energy is below 0.1 % of the drop's energy
 * and the centre of mass is at half the box's height (less the sag under its own weight,
 * rho g h^2 / (4 E) ~ 2.5 mm, plus the spring's rest gap of ~1 mm). */
static void test_rest(sem_integrator integ, const char *name)
{
    test_setup s;
    const double center[3] = {0, 0, 1.0}, gravity[3] = {0, 0, -G};
    if (!make(&s, 0, center, gravity, integ, SEM_DEFAULT_FRICTION) || !add_plane(&s, SEM_DEFAULT_FRICTION)) {
        test_setup_free(&s);
        return;
    }
    sem_object_stats st;
    sem_contact_stats cs;
    sem_world_object_stats(s.world, 0, &st);
    double drop_energy = st.mass * G * 0.5, min_gap = INFINITY;
    int touched = 0;
    sem_error err;
    for (int i = 0; i < 300; ++i) {
        if (sem_world_step(s.world, &err) != SEM_OK) {
            CHECK(0, "%s step %d: %s", name, i, err.message);
            break;
        }
        sem_world_contact_stats(s.world, &cs);
        if (cs.min_gap < min_gap) min_gap = cs.min_gap;
        if (cs.contacts > 0) touched = 1;
    }
    sem_world_object_stats(s.world, 0, &st);
    printf("%s: min gap %.4g m, final KE / drop energy %.3g, com z %.5f, contacts %d\n", name, min_gap,
           st.kinetic_energy / drop_energy, st.center_of_mass[2], cs.contacts);
    CHECK(touched, "%s: no contact", name);
    CHECK(min_gap > -0.02, "%s: penetration %g m (more than 2 %% of 1 m)", name, -min_gap);
    CHECK(st.kinetic_energy < 1e-3 * drop_energy, "%s: KE %g of %g", name, st.kinetic_energy, drop_energy);
    CHECK_NEAR(st.center_of_mass[2], 0.5, 0.005);
    CHECK(cs.contacts > 0, "%s: not resting on the plane", name);
    test_setup_free(&s);
}

/* Without contact the same box falls through the plane: the test above can fail. */
static void test_disabled(void)
{
    test_setup s;
    memset(&s, 0, sizeof s);
    const double center[3] = {0, 0, 1.0}, gravity[3] = {0, 0, -G};
    if (!make(&s, 0, center, gravity, SEM_IMPLICIT_EULER, 0.5)) {
        test_setup_free(&s);
        return;
    }
    sem_world_destroy(s.world);
    sem_world_def wd = sem_default_world_def();
    wd.integrator = SEM_IMPLICIT_EULER;
    wd.contact.disabled = 1;
    wd.advanced.q_space_solvers = 1; /* the structured solver takes no contact terms yet */
    sem_error err;
    s.world = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = s.model;
    od.disc = s.disc;
    CHECK(sem_world_add_object(s.world, &od, &err) == 0, "%s", err.message);
    add_plane(&s, 0.5);
    for (int i = 0; i < 60; ++i) sem_world_step(s.world, &err);
    sem_object_stats st;
    sem_world_object_stats(s.world, 0, &st);
    CHECK(st.center_of_mass[2] < 0, "contact disabled: the box should fall through (com z %g)",
          st.center_of_mass[2]);
    test_setup_free(&s);
}

/* Number 2: the box resting on a 30-degree incline (gravity turned by 30 degrees about y, the
 * plane z = 0). mu = 0.8 > tan 30: once settled (0.3 s) it moves less than 1 cm in 2 s;
 * mu = 0.2: it slides with a = g (sin 30 - 0.2 cos 30) = 3.206 m/s^2 (within 5 %). */
static void test_incline(sem_integrator integ, double mu, const char *name)
{
    test_setup s;
    const double theta = M_PI / 6;
    const double center[3] = {0, 0, 0.5 + 1e-3}, gravity[3] = {G * sin(theta), 0, -G * cos(theta)};
    if (!make(&s, 0, center, gravity, integ, mu) || !add_plane(&s, mu)) {
        test_setup_free(&s);
        return;
    }
    sem_error err;
    sem_object_stats st;
    double x_settled = 0, v_at[2] = {0, 0};
    int steps = mu > 0.5 ? 230 : 120;
    for (int i = 1; i <= steps; ++i) {
        if (sem_world_step(s.world, &err) != SEM_OK) {
            CHECK(0, "%s step %d: %s", name, i, err.message);
            break;
        }
        sem_world_object_stats(s.world, 0, &st);
        if (i == 30) x_settled = st.center_of_mass[0];
        if (i == 60) v_at[0] = st.linear_momentum[0] / st.mass;
        if (i == 120) v_at[1] = st.linear_momentum[0] / st.mass;
    }
    if (mu > 0.5) {
        double moved = st.center_of_mass[0] - x_settled;
        printf("%s: moved %.3g m in 2 s once settled\n", name, moved);
        CHECK(fabs(moved) < 0.01, "%s: slid %g m", name, moved);
    } else {
        double a = (v_at[1] - v_at[0]) / 0.6, expected = G * (sin(theta) - mu * cos(theta));
        printf("%s: a = %.4f m/s^2 (Coulomb: %.4f)\n", name, a, expected);
        CHECK_REL(a, expected, 0.05);
    }
    test_setup_free(&s);
}

/* Number 4: a sphere (r = 0.5) dropped off-centre into a V-shaped valley (two 30-degree
 * slopes meeting along the x axis, an OBJ-like triangle mesh) settles at the bottom: centre
 * at y = 0, z = r / cos 30, never passing through the mesh. */
static void test_valley(void)
{
    test_setup s;
    const double center[3] = {0, 0.3, 1.2}, gravity[3] = {0, 0, -G};
    if (!make(&s, 1, center, gravity, SEM_IMPLICIT_EULER, SEM_DEFAULT_FRICTION)) {
        test_setup_free(&s);
        return;
    }
    /* 3 x 5 vertices over x in [-2, 2], y in {-2, 0, 2}, z = |y| tan 30 */
    double v[3 * 15];
    int t[3 * 16], nt = 0;
    for (int j = 0; j < 3; ++j)
        for (int i = 0; i < 5; ++i) {
            double *x = v + 3 * (j * 5 + i);
            x[0] = -2.0 + i;
            x[1] = -2.0 + 2.0 * j;
            x[2] = fabs(x[1]) * tan(M_PI / 6);
        }
    for (int j = 0; j < 2; ++j)
        for (int i = 0; i < 4; ++i) {
            int a = j * 5 + i, b = a + 1, c = a + 5, d = c + 1; /* counter-clockwise from above */
            t[3 * nt] = a, t[3 * nt + 1] = b, t[3 * nt + 2] = d, ++nt;
            t[3 * nt] = a, t[3 * nt + 1] = d, t[3 * nt + 2] = c, ++nt;
        }
    sem_collider_def cd = sem_default_collider_def();
    cd.type = SEM_COLLIDER_MESH;
    cd.vertices = v;
    cd.n_vertices = 15;
    cd.triangles = t;
    cd.n_triangles = nt;
    sem_error err;
    CHECK(sem_world_add_collider(s.world, &cd, &err) == 0, "valley: %s", err.message);
    sem_object_stats st;
    sem_contact_stats cs;
    double min_gap = INFINITY;
    for (int i = 0; i < 250; ++i) {
        if (sem_world_step(s.world, &err) != SEM_OK) {
            CHECK(0, "valley step %d: %s", i, err.message);
            break;
        }
        sem_world_contact_stats(s.world, &cs);
        if (cs.min_gap < min_gap) min_gap = cs.min_gap;
    }
    sem_world_object_stats(s.world, 0, &st);
    double rest_z = 0.5 / cos(M_PI / 6);
    printf("valley: com (%.4f, %.4f, %.4f) (bottom: 0, 0, %.4f), min gap %.3g, KE %.3g J\n", st.center_of_mass[0],
           st.center_of_mass[1], st.center_of_mass[2], rest_z, min_gap, st.kinetic_energy);
    CHECK(min_gap > -0.01, "valley: penetration %g m (2 %% of the radius: 0.01)", -min_gap);
    CHECK_NEAR(st.center_of_mass[1], 0.0, 0.01);
    CHECK_NEAR(st.center_of_mass[2], rest_z, 0.01);
    CHECK(st.kinetic_energy < 1e-3 * st.mass * G * 0.6, "valley: still moving (KE %g J)", st.kinetic_energy);
    test_setup_free(&s);
}


/* Number 3: two rubber spheres (r = 0.5) meet head-on at 2 m/s in zero gravity: total linear
 * momentum stays zero (to 1e-6 of m v), both rebound, no energy is gained, and they sink into
 * each other by less than 2 % of the radius. The linearly implicit step (the paper's) keeps
 * momentum and rebounds, but during the impact its kinetic + elastic energy rises above the
 * initial one (to about 1.9 x: it linearizes the springs and the elasticity at the step's
 * start; docs/simulation.md): for it only the final energy is checked. */
static void test_two_spheres(sem_integrator integ, const char *name)
{
    test_setup a, b, far;
    const double ca[3] = {-0.52, 0, 0}, cb[3] = {0.52, 0.05, 0}, cf[3] = {0, 5, 0}, zero[3] = {0, 0, 0};
    const double mu0 = SEM_DEFAULT_FRICTION;
    memset(&far, 0, sizeof far);
    if (!make(&a, 1, ca, zero, integ, mu0) || !make(&b, 1, cb, zero, integ, mu0) ||
        !make(&far, 1, cf, zero, integ, mu0)) {
        test_setup_free(&a);
        test_setup_free(&b);
        test_setup_free(&far);
        return;
    }
    /* both in a's world */
    sem_error err;
    sem_world_destroy(a.world);
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = 0;
    wd.integrator = integ;
    wd.contact.resolution = 8;
    wd.advanced.q_space_solvers = 1; /* the structured solver takes no contact terms yet */
    a.world = sem_world_create(&wd, &err);
    sem_object_def od = sem_default_object_def();
    od.model = a.model;
    od.disc = a.disc;
    od.initial_velocity[0] = 1.0;
    od.friction = mu0;
    CHECK(sem_world_add_object(a.world, &od, &err) == 0, "%s", err.message);
    od.model = b.model;
    od.disc = b.disc;
    od.initial_velocity[0] = -1.0;
    CHECK(sem_world_add_object(a.world, &od, &err) == 1, "%s", err.message);
    /* a third sphere at rest 5 m away: an island of its own (solved apart; the pair may split
     * into two islands again once it has rebounded far enough) */
    od.model = far.model;
    od.disc = far.disc;
    od.initial_velocity[0] = 0;
    CHECK(sem_world_add_object(a.world, &od, &err) == 2, "%s", err.message);
    sem_object_stats s0, s1, s2;
    sem_world_object_stats(a.world, 0, &s0);
    sem_world_object_stats(a.world, 1, &s1);
    double E0 = s0.kinetic_energy + s1.kinetic_energy + s0.elastic_energy + s1.elastic_energy + s0.error_energy +
                s1.error_energy;
    double mv = s0.mass * 1.0, min_gap = INFINITY, max_momentum = 0, max_energy = 0, far_momentum = 0;
    int touched = 0, islands_wrong = 0;
    for (int i = 0; i < 60; ++i) {
        if (sem_world_step(a.world, &err) != SEM_OK) {
            CHECK(0, "%s step %d: %s", name, i, err.message);
            break;
        }
        sem_contact_stats cs;
        sem_world_contact_stats(a.world, &cs);
        if (cs.min_gap < min_gap) min_gap = cs.min_gap;
        if (cs.contacts > 0) touched = 1;
        sem_world_counters counters = sem_world_get_counters(a.world);
        if (counters.systems < 2) islands_wrong++;
        sem_world_object_stats(a.world, 2, &s2);
        for (int k = 0; k < 3; ++k) far_momentum = fmax(far_momentum, fabs(s2.linear_momentum[k]));
        sem_world_object_stats(a.world, 0, &s0);
        sem_world_object_stats(a.world, 1, &s1);
        for (int k = 0; k < 3; ++k)
            max_momentum = fmax(max_momentum, fabs(s0.linear_momentum[k] + s1.linear_momentum[k]));
        max_energy = fmax(max_energy, s0.kinetic_energy + s1.kinetic_energy + s0.elastic_energy + s1.elastic_energy +
                                          s0.error_energy + s1.error_energy);
    }
    double va = s0.linear_momentum[0] / s0.mass, vb = s1.linear_momentum[0] / s1.mass;
    printf("%s: velocities after %+.3f %+.3f m/s, |total momentum| <= %.3g (m v = %.4g), energy max %.4g of %.4g, "
           "min gap %.3g m\n",
           name, va, vb, max_momentum, mv, max_energy, E0, min_gap);
    printf("%s: islands: %ld regrouping(s), %d step(s) in fewer than 2 systems, the far sphere's momentum <= %.3g\n",
           name, sem_world_get_counters(a.world).regroupings, islands_wrong, far_momentum);
    CHECK(touched, "%s: never touched", name);
    CHECK(islands_wrong == 0, "%s: %d steps did not solve the pair and the far sphere apart", name, islands_wrong);
    CHECK(sem_world_get_counters(a.world).regroupings >= 1, "%s: %ld regroupings", name,
          sem_world_get_counters(a.world).regroupings);
    CHECK(far_momentum <= 1e-9 * mv, "%s: the far sphere moved (momentum %g)", name, far_momentum);
    CHECK(max_momentum <= 1e-6 * mv, "%s: momentum %g", name, max_momentum);
    CHECK(va < 0 && vb > 0, "%s: no rebound (%g, %g)", name, va, vb);
    if (integ == SEM_IMPLICIT_EULER)
        CHECK(max_energy <= E0 * (1 + 1e-9), "%s: energy gained (%g > %g)", name, max_energy, E0);
    double E1 = s0.kinetic_energy + s1.kinetic_energy + s0.elastic_energy + s1.elastic_energy + s0.error_energy +
                s1.error_energy;
    CHECK(E1 <= E0, "%s: energy gained (%g > %g) after the impact", name, E1, E0);
    CHECK(min_gap > -0.01, "%s: penetration %g m", name, -min_gap);
    test_setup_free(&a);
    test_setup_free(&b);
    test_setup_free(&far);
}

/* A solid of `model` (E, rho 1000, nu 0.45) preprocessed at sem's defaults, added to w. */
static int add_solid(test_setup *s, sem_world *w, double youngs)
{
    sem_error err;
    sem_preprocess_options po = sem_default_preprocess_options();
    po.q_space_operators = 1;
    po.youngs_modulus = youngs;
    sem_status st = sem_preprocess(s->model, &po, &s->disc, &err);
    CHECK(st == SEM_OK, "preprocess: %s", err.message);
    if (st != SEM_OK) return 0;
    sem_object_def od = sem_default_object_def();
    od.material.youngs_modulus = youngs;
    od.model = s->model;
    od.disc = s->disc;
    int id = sem_world_add_object(w, &od, &err);
    CHECK(id >= 0, "add object: %s", err.message);
    return id >= 0;
}

/* A rubber box (rho 1000, E 1e5, nu 0.45) of edge `size` at `center`, preprocessed at sem's
 * defaults, added to world w. */
static int add_box(test_setup *s, sem_world *w, double size, const double center[3])
{
    memset(s, 0, sizeof *s);
    sem_error err;
    s->model = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = bd.size[1] = bd.size[2] = size;
    memcpy(bd.center, center, sizeof bd.center);
    sem_status st = s->model ? sem_primitive_box(s->model, &bd, &err) : SEM_ERR_NOMEM;
    CHECK(st == SEM_OK, "box: %s", err.message);
    return st == SEM_OK && add_solid(s, w, 1e5);
}

/* The world of the drops between objects: gravity, implicit Euler at dt 0.01, every other
 * setting at its default (the q-space solvers, which take contact terms). */
static sem_world *drop_world(void)
{
    sem_error err;
    sem_world_def wd = sem_default_world_def();
    wd.gravity[2] = -G;
    wd.integrator = SEM_IMPLICIT_EULER;
    wd.dt = 0.01;
    wd.advanced.q_space_solvers = 1;
    sem_world *w = sem_world_create(&wd, &err);
    CHECK(w != NULL, "world: %s", err.message);
    return w;
}

/* Two equal rubber boxes (0.4 m, E 1e5) stacked face to face, edges over edges, the upper one
 * dropped 9 mm onto the lower one, which rests on the ground; implicit Euler, every setting at
 * its default. Every step must converge: before Newton's stall rule looked at the Newton step
 * rather than at the part of it the line search took, the run stopped at the first contact
 * step (t = 0.06 s) with a relative gradient of 3.6e-8 against the 1e-8 tolerance (springs
 * switching on and off between iterates at the penalty's kink, line-search steps of 1/128 to
 * 1/512 of Newton steps of nanometres). After 0.3 s the upper box rests on the lower one: its
 * centre 0.4 m above the lower one's, less the sag under the load, plus the springs' gaps. */
static void test_stack(void)
{
    test_setup lo, up;
    memset(&lo, 0, sizeof lo);
    memset(&up, 0, sizeof up);
    const double cl[3] = {0, 0, 0.201}, cu[3] = {0, 0, 0.61};
    sem_error err;
    sem_world *w = drop_world();
    if (!w || !add_box(&lo, w, 0.4, cl) || !add_box(&up, w, 0.4, cu)) {
        sem_world_destroy(w);
        test_setup_free(&lo);
        test_setup_free(&up);
        return;
    }
    lo.world = w;
    CHECK(add_plane(&lo, SEM_DEFAULT_FRICTION), "plane");
    const int steps = 30;
    int done = 0, touched = 0;
    for (; done < steps; ++done) {
        if (sem_world_step(w, &err) != SEM_OK) {
            CHECK(0, "stack step %d: %s", done, err.message);
            break;
        }
        sem_contact_stats cs;
        sem_world_contact_stats(w, &cs);
        touched |= cs.contacts > 0;
    }
    sem_object_stats a, b;
    sem_world_object_stats(w, 0, &a);
    sem_world_object_stats(w, 1, &b);
    sem_world_counters counters = sem_world_get_counters(w);
    double apart = b.center_of_mass[2] - a.center_of_mass[2];
    printf("stack: %d of %d steps, centres %.4f and %.4f m (apart %.4f), %ld Newton iterations, %ld stalls\n", done,
           steps, a.center_of_mass[2], b.center_of_mass[2], apart, counters.newton_iterations,
           counters.newton_stalls);
    CHECK(done == steps && touched, "the stack did not run through its contact");
    CHECK(apart > 0.36 && apart < 0.41, "the upper box is not resting on the lower one (%g m apart)", apart);
    test_setup_free(&lo);
    test_setup_free(&up);
}

/* A rubber ball (r 0.25 m, E 1e5) dropped pole first onto a stiff plate (1.2 x 1.2 x 0.1 m,
 * E 1e8) lying on the ground. The pole is a collapsed edge of the sphere's NURBS: one point at
 * rest, with a tessellation vertex per u, each a different row over the collapsed control
 * points. With their own rows those copies moved apart under the plate's point below them and
 * the step stopped at the first contact (relative gradient 4e-5 here, 0.36 to 0.85 with
 * other sizes and a held plate); now the copies share the mean row (collision_mesh.c,
 * merge_copy_rows). The ball must land and rest on the plate within 0.2 s. */
static void test_pole_first(void)
{
    test_setup ball, plate;
    memset(&ball, 0, sizeof ball);
    memset(&plate, 0, sizeof plate);
    sem_error err;
    sem_world *w = drop_world();
    ball.model = sem_model_create();
    plate.model = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    sd.radius = 0.25;
    sem_box_def bd = sem_default_box_def();
    bd.size[0] = bd.size[1] = 1.2;
    bd.size[2] = 0.1;
    bd.center[2] = 0.05;
    int ok = w && ball.model && plate.model && sem_primitive_sphere(ball.model, &sd, &err) == SEM_OK &&
             sem_primitive_box(plate.model, &bd, &err) == SEM_OK;
    CHECK(ok, "set-up: %s", err.message);
    if (ok) {
        sem_surface *s = &ball.model->parts[0].surface;
        for (size_t c = 0; c < (size_t)s->n_u * s->n_v; ++c) s->ctrl[3 * c + 2] += 0.36;
        ok = add_solid(&ball, w, 1e5) && add_solid(&plate, w, 1e8);
    }
    plate.world = w;
    if (ok) ok = add_plane(&plate, SEM_DEFAULT_FRICTION);
    int done = 0, touched = 0;
    const int steps = 20;
    for (; ok && done < steps; ++done) {
        if (sem_world_step(w, &err) != SEM_OK) {
            CHECK(0, "pole first, step %d: %s", done, err.message);
            break;
        }
        sem_contact_stats cs;
        sem_world_contact_stats(w, &cs);
        touched |= cs.contacts > 0;
    }
    sem_object_stats b;
    if (ok) sem_world_object_stats(w, 0, &b);
    printf("pole first: %d of %d steps, the ball's centre at %.4f m (on the plate: 0.35 less its sag)\n", done, steps,
           ok ? b.center_of_mass[2] : 0.0);
    CHECK(ok && done == steps && touched, "the ball did not land on the plate");
    CHECK(ok && b.center_of_mass[2] > 0.32 && b.center_of_mass[2] < 0.355, "the ball is not on the plate (%g)",
          ok ? b.center_of_mass[2] : 0.0);
    sem_world_destroy(w); /* before the models it holds */
    plate.world = NULL;
    test_setup_free(&ball);
    test_setup_free(&plate);
}

/* Friction's bounded Hessian (friction.h, sem_friction_curvature): the quadratic
 * D(u) + g . d + c |d|^2 / 2 with c = mu lambda f1(|u|)/|u| lies above D(u + d) for every d
 * (D is a concave function of |u|^2), from inside and outside the sticking zone and across
 * it, and c is at least the exact Hessian's curvature along u. On 2,000 random pairs. */
static void test_friction_bound(void)
{
    const double eps = 1e-3, mul = 2.5;
    unsigned long long x = 12345;
    int above = 0, curv = 0;
    double worst = 0;
    for (int i = 0; i < 2000; ++i) {
        double r[4];
        for (int k = 0; k < 4; ++k) {
            x = x * 6364136223846793005ULL + 1442695040888963407ULL;
            r[k] = ((double)(x >> 11) / 9007199254740992.0 - 0.5) * 6 * eps;
        }
        double u[2] = {r[0], r[1]}, d[2] = {r[2], r[3]}, g[2], H[4], un[2] = {u[0] + d[0], u[1] + d[1]};
        double D = sem_friction_potential(mul, u, eps, g, H);
        double c = sem_friction_curvature(mul, u, eps);
        double bound = D + g[0] * d[0] + g[1] * d[1] + 0.5 * c * (d[0] * d[0] + d[1] * d[1]);
        double Dn = sem_friction_potential(mul, un, eps, NULL, NULL);
        worst = fmax(worst, Dn - bound);
        above += Dn <= bound + 1e-15 * mul * eps;
        double y2 = u[0] * u[0] + u[1] * u[1];
        double radial = (u[0] * (H[0] * u[0] + H[1] * u[1]) + u[1] * (H[2] * u[0] + H[3] * u[1])) / y2;
        curv += c >= radial * (1 - 1e-12);
    }
    printf("friction bound: above the potential at %d of 2000 random steps (worst excess %.3g), curvature >= the "
           "exact radial one at %d\n", above, worst, curv);
    CHECK(above == 2000, "the bound is below the friction potential at %d steps", 2000 - above);
    CHECK(curv == 2000, "the bound's curvature is below the exact one at %d points", 2000 - curv);
}

/* The pieces against closed forms and finite differences: the friction potential's gradient
 * and Hessian (inside and outside the smoothing zone), its Coulomb limit, the closest point
 * of a triangle in each region. */
static void test_pieces(void)
{
    const double eps = 1e-3, mul = 2.5;
    const double us[3][2] = {{3e-4, -2e-4}, {2e-3, 1e-3}, {0, 0}};
    for (int c = 0; c < 3; ++c) {
        double g[2], H[4];
        sem_friction_potential(mul, us[c], eps, g, H);
        for (int k = 0; k < 2; ++k) {
            double h = 1e-8, up[2] = {us[c][0], us[c][1]}, um[2] = {us[c][0], us[c][1]}, gp[2], gm[2];
            up[k] += h;
            um[k] -= h;
            double fd = (sem_friction_potential(mul, up, eps, gp, NULL) - sem_friction_potential(mul, um, eps, gm, NULL)) /
                        (2 * h);
            CHECK_NEAR(g[k], fd, 1e-6 * mul);
            if (c == 2) continue; /* the Hessian at u = 0 is 2 mu lambda / eps I (below) */
            for (int j = 0; j < 2; ++j) CHECK_NEAR(H[2 * j + k], (gp[j] - gm[j]) / (2 * h), 1e-4 * mul / eps);
        }
        if (c == 1) CHECK_NEAR(sqrt(g[0] * g[0] + g[1] * g[1]), mul, 1e-12); /* sliding: mu lambda */
        if (c == 2) CHECK(fabs(H[0] - 2 * mul / eps) < 1e-9 && fabs(H[3] - 2 * mul / eps) < 1e-9 && H[1] == 0,
                          "Hessian at rest");
    }
    const double a[3] = {0, 0, 0}, b[3] = {1, 0, 0}, cc[3] = {0, 1, 0};
    sem_tri_closest cl;
    const double p_face[3] = {0.25, 0.25, -0.5}, p_edge[3] = {0.5, -1, 2}, p_vertex[3] = {2, -1, 0};
    sem_point_triangle_closest(p_face, a, b, cc, &cl);
    CHECK(cl.feature == SEM_TRI_FACE && fabs(cl.dist2 - 0.25) < 1e-15 && fabs(cl.bary[1] - 0.25) < 1e-15,
          "face region");
    double outward[3] = {0, 0, 1}, n[3];
    CHECK_NEAR(sem_signed_distance(p_face, cl.point, outward, n), -0.5, 1e-15);
    CHECK_NEAR(n[2], 1.0, 1e-15);
    sem_point_triangle_closest(p_edge, a, b, cc, &cl);
    CHECK(cl.feature == SEM_TRI_EDGE && cl.index == 0 && fabs(cl.dist2 - 5) < 1e-14, "edge region");
    sem_point_triangle_closest(p_vertex, a, b, cc, &cl);
    CHECK(cl.feature == SEM_TRI_VERTEX && cl.index == 1 && fabs(cl.dist2 - 2) < 1e-14, "vertex region");
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return;
    fputs(text, f);
    fclose(f);
}

/* The scene's error for a collider or contact setting: one line naming the key. */
static void expect_scene_error(const char *dir, const char *json, const char *needle)
{
    char path[1024], msg[2048];
    snprintf(path, sizeof path, "%s/bad.json", dir);
    write_text(path, json);
    sem_error err;
    memset(&err, 0, sizeof err);
    sem_scene *scene = NULL;
    sem_scene_world *sw = NULL;
    sem_status st = sem_scene_load(path, &scene, &err);
    if (st == SEM_OK) {
        sem_scene_world_options o = sem_default_scene_world_options();
        o.skip_modes = 1;
        st = sem_scene_world_create(scene, &o, &sw, &err);
    }
    snprintf(msg, sizeof msg, "%s", err.message);
    CHECK(st != SEM_OK, "accepted: %s", json);
    CHECK(strstr(msg, needle) != NULL && !strchr(msg, '\n'), "error \"%s\" lacks \"%s\"", msg, needle);
    sem_scene_world_destroy(sw);
    sem_scene_destroy(scene);
}

#define BOX_OBJECT "\"objects\": [{\"primitive\": {\"type\": \"box\"}, \"sem\": {\"rays\": [4, 4], " \
                   "\"points_per_interval\": 4}, \"transform\": {\"translate\": [0, 0, 0.6]}}]"

/* Scene keys: colliders (plane, OBJ triangle mesh, primitive), contact settings, object
 * friction; bad ones are one-line errors naming the key. A short run through the command
 * line writes the contact numbers into summary.json. */
static void test_scene(void)
{
    const char *dir = test_tmpdir();
    char path[1024];
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"plane\": {\"normal\": [0, 0, 0]}}]}",
                       "colliders[0].plane.normal: must be non-zero");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"model\": \"missing.obj\"}]}",
                       "colliders[0].model: ");
    snprintf(path, sizeof path, "%s/quad.obj", dir);
    write_text(path, "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0.5 0\nf 1 2 3\nf 1 2 3 4\nf 1 2 3 4 5\n");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"model\": \"quad.obj\"}]}",
                       "colliders[0].model: ");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"model\": \"quad.obj\"}]}", "quad.obj:8: a face with 5");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"plane\": {}, \"friction\": -1}]}",
                       "colliders[0].friction: must be >= 0");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"colliders\": [{\"plane\": {}, \"model\": \"quad.obj\"}]}",
                       "colliders[0]: needs exactly one of");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"contact\": {\"self\": 1}}", "contact.self");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"contact\": {\"stiffness\": -3}}", "contact.stiffness: must be positive");
    expect_scene_error(dir, "{" BOX_OBJECT ", \"contact\": {\"stifness\": 3}}", "contact: unknown key \"stifness\"");
    expect_scene_error(dir,
                       "{\"objects\": [{\"primitive\": {\"type\": \"box\"}, \"friction\": -0.1}]}",
                       "objects[0].friction: must be >= 0");

    /* a box resting on a triangle-mesh floor (OBJ) and a plane wall, through `sem run` */
    snprintf(path, sizeof path, "%s/floor.obj", dir);
    write_text(path, "# a 4 x 4 m floor at z = 0\nv -2 -2 0\nv 2 -2 0\nv 2 2 0\nv -2 2 0\nf 1 2 3\nf 1/1 3/3 4/4\n");
    snprintf(path, sizeof path, "%s/floor.json", dir);
    write_text(path, "{\"objects\": [{\"primitive\": {\"type\": \"box\"}, \"sem\": {\"rays\": [4, 4], "
                     "\"points_per_interval\": 4}, \"transform\": {\"translate\": [0, 0, 0.5005]}, \"friction\": 0.6}],\n"
                     " \"colliders\": [{\"model\": \"floor.obj\", \"friction\": 0.6},\n"
                     "               {\"plane\": {\"point\": [5, 0, 0], \"normal\": [-1, 0, 0]}}],\n"
                     " \"contact\": {\"resolution\": 4},\n"
                     " \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01}, \"frames\": 3,\n"
                     " \"output\": {\"iges\": false, \"mesh\": false, \"usd\": false, \"glb\": false}}\n");
    char args[2048], out[1 << 16], errbuf[4096];
    snprintf(args, sizeof args, "run %s --out %s/floor_out --quiet --no-cache", path, dir);
    int rc = test_run_cli(args, out, sizeof out, errbuf, sizeof errbuf);
    CHECK(rc == 0, "sem run floor.json: %d %s", rc, errbuf);
    snprintf(path, sizeof path, "%s/floor_out/summary.json", dir);
    FILE *f = fopen(path, "rb");
    char *text = NULL;
    if (f) {
        fseek(f, 0, SEEK_END);
        long n = ftell(f);
        fseek(f, 0, SEEK_SET);
        text = calloc((size_t)n + 1, 1);
        if (text && fread(text, 1, (size_t)n, f) != (size_t)n) text[0] = 0;
        fclose(f);
    }
    cJSON *j = text ? cJSON_Parse(text) : NULL;
    CHECK(j != NULL, "summary.json unreadable");
    if (j) {
        const cJSON *frames = cJSON_GetObjectItem(j, "frames");
        const cJSON *last = cJSON_GetArrayItem(frames, cJSON_GetArraySize(frames) - 1);
        const cJSON *contacts = cJSON_GetObjectItem(last, "contacts"), *gap = cJSON_GetObjectItem(last, "min_gap");
        const cJSON *objs = cJSON_GetObjectItem(last, "objects");
        const cJSON *o0 = cJSON_GetArrayItem(objs, 0);
        CHECK(cJSON_IsNumber(contacts) && contacts->valuedouble > 0, "summary: contacts");
        CHECK(cJSON_IsNumber(gap) && fabs(gap->valuedouble) < 0.01, "summary: min_gap %g",
              cJSON_IsNumber(gap) ? gap->valuedouble : -1.0);
        CHECK(cJSON_GetArraySize(objs) == 1 && cJSON_GetObjectItem(o0, "center_of_mass") &&
                  cJSON_GetObjectItem(o0, "linear_momentum") && cJSON_GetObjectItem(o0, "angular_momentum") &&
                  cJSON_IsNumber(cJSON_GetObjectItem(o0, "kinetic_energy")),
              "summary: per-object numbers");
        const cJSON *com = cJSON_GetObjectItem(o0, "center_of_mass");
        CHECK(fabs(cJSON_GetArrayItem(com, 2)->valuedouble - 0.5) < 0.01, "box resting on the OBJ floor: com z %g",
              cJSON_GetArrayItem(com, 2)->valuedouble);
        CHECK(cJSON_IsNumber(cJSON_GetObjectItem(j, "contact_s")), "summary: contact_s");
        cJSON_Delete(j);
    }
    free(text);
}

int main(int argc, char **argv)
{
    (void)argc;
    /* as the sem command does (README, "Threads"): sleeping OpenMP threads and a short
     * OpenBLAS spin, else the two runtimes fight over a small machine's cores */
    if (!getenv("OMP_WAIT_POLICY") && !getenv("SEM_NO_RESTART")) {
        setenv("OMP_WAIT_POLICY", "passive", 1);
        setenv("OPENBLAS_THREAD_TIMEOUT", "20", 1);
        setenv("SEM_NO_RESTART", "1", 1);
        execv("/proc/self/exe", argv);
    }
    test_pieces();
    test_friction_bound();
    test_scene();
    test_rest(SEM_IMPLICIT_EULER, "rest (implicit Euler)");
    test_rest(SEM_LINEARLY_IMPLICIT_EULER, "rest (linearly implicit Euler)");
    test_disabled();
    test_incline(SEM_IMPLICIT_EULER, 0.8, "incline mu 0.8");
    test_incline(SEM_IMPLICIT_EULER, 0.2, "incline mu 0.2");
    test_incline(SEM_LINEARLY_IMPLICIT_EULER, 0.2, "incline mu 0.2 (linearly implicit)");
    test_valley();
    test_two_spheres(SEM_IMPLICIT_EULER, "two spheres (implicit Euler)");
    test_two_spheres(SEM_LINEARLY_IMPLICIT_EULER, "two spheres (linearly implicit Euler)");
    test_stack();
    test_pole_first();
    return test_finish("test_contact");
}
