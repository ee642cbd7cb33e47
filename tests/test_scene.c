/* test_scene.c - scene files (sem/scene.h): defaults, values, transforms, and errors that
 * name the bad key and say why. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sem/primitives.h"
#include "sem/scene.h"
#include "test_util.h"

/* Parses json; returns the scene or NULL (message in *err). */
static sem_scene *parse(const char *json, sem_error *err)
{
    sem_scene *s = NULL;
    if (sem_scene_parse(json, "t.json", "/base", &s, err) != SEM_OK) return NULL;
    return s;
}

/* A scene with one object whose body is `object` (without braces) and extra top-level keys. */
static sem_scene *parse_object(const char *object, const char *top, sem_error *err)
{
    char json[4096];
    snprintf(json, sizeof json, "{\"objects\": [{%s}]%s%s}", object, top[0] ? ", " : "", top);
    return parse(json, err);
}

/* The scene must fail with a message containing every one of the NULL-terminated needles. */
static void expect_error(const char *object, const char *top, const char *n1, const char *n2)
{
    sem_error err;
    memset(&err, 0, sizeof err);
    sem_scene *s = parse_object(object, top, &err);
    CHECK(s == NULL, "scene {%s} %s parsed but must fail", object, top);
    if (s) {
        sem_scene_destroy(s);
        return;
    }
    CHECK(strncmp(err.message, "t.json: ", 8) == 0, "message names the file: %s", err.message);
    CHECK(strstr(err.message, n1) != NULL, "message \"%s\" lacks \"%s\"", err.message, n1);
    if (n2) CHECK(strstr(err.message, n2) != NULL, "message \"%s\" lacks \"%s\"", err.message, n2);
}

#define BOX "\"primitive\": {\"type\": \"box\"}"

static void test_errors(void)
{
    /* unknown keys at every level name the key and list what is allowed */
    expect_error(BOX, "\"framez\": 3", "scene: unknown key \"framez\"", "allowed:");
    expect_error(BOX ", \"colour\": 1", "", "objects[0]: unknown key \"colour\"", NULL);
    expect_error(BOX ", \"material\": {\"desnity\": 3}", "", "objects[0].material: unknown key \"desnity\"",
                 "density");
    expect_error(BOX ", \"sem\": {\"ordr\": 2}", "", "objects[0].sem: unknown key \"ordr\"", NULL);
    expect_error(BOX, "\"integrator\": {\"typ\": \"static\"}", "integrator: unknown key \"typ\"", NULL);
    expect_error(BOX, "\"output\": {\"folder\": \"x\"}", "output: unknown key \"folder\"", NULL);
    expect_error(BOX ", \"pin\": {\"boxes\": []}", "", "objects[0].pin: unknown key \"boxes\"", NULL);
    expect_error("\"primitive\": {\"type\": \"box\", \"radius\": 2}", "", "objects[0].primitive: unknown key \"radius\"",
                 "type, size");
    expect_error("\"primitive\": {\"type\": \"cube\"}", "", "objects[0].primitive.type", "box");
    /* materials */
    expect_error(BOX ", \"material\": {\"density\": -3}", "", "objects[0].material", "density");
    expect_error(BOX ", \"material\": {\"poisson_ratio\": 0.5}", "", "objects[0].material", "oisson");
    expect_error(BOX ", \"material\": {\"poisson_ratio\": 0.7}", "", "objects[0].material", "oisson");
    expect_error(BOX ", \"material\": {\"youngs_modulus\": 0}", "", "objects[0].material", "oung");
    expect_error(BOX ", \"material\": {\"type\": \"jelly\"}", "", "objects[0].material.type", "neohookean");
    expect_error(BOX ", \"part_materials\": {\"0\": {\"density\": -1}}", "", "objects[0].part_materials.0",
                 "density");
    /* integrator */
    expect_error(BOX, "\"integrator\": {\"dt\": 0}", "integrator.dt", "must be positive");
    expect_error(BOX, "\"integrator\": {\"dt\": -0.01}", "integrator.dt", "must be positive");
    expect_error(BOX, "\"integrator\": {\"type\": \"rk4\"}", "integrator.type", "implicit_euler");
    expect_error(BOX, "\"integrator\": {\"damping\": {\"mass\": -1}}", "integrator.damping", ">= 0");
    /* wrong types */
    expect_error(BOX, "\"integrator\": {\"dt\": \"0.01\"}", "integrator.dt", "finite number");
    expect_error(BOX, "\"frames\": 2.5", "scene.frames", "integer");
    expect_error(BOX, "\"frames\": -1", "frames", ">= 0");
    expect_error(BOX, "\"gravity\": [0, 0]", "scene.gravity", "3 numbers");
    expect_error(BOX, "\"gravity\": \"down\"", "scene.gravity", "3 numbers");
    expect_error(BOX, "\"output\": {\"usd\": 1}", "output.usd", "true or false");
    expect_error(BOX ", \"initial_velocity\": [1, \"a\", 0]", "", "objects[0].initial_velocity", "element 1");
    expect_error(BOX ", \"material\": 5", "", "objects[0].material", "JSON object");
    expect_error(BOX, "\"description\": 5", "description", "string");
    /* objects */
    const char *no_objects[] = {"{\"objects\": []}", "{\"frames\": 1}", "{\"objects\": {}}", "[]"};
    for (int k = 0; k < 4; ++k) {
        sem_error e;
        sem_scene *s = parse(no_objects[k], &e);
        CHECK(s == NULL && strstr(e.message, "t.json: ") && strstr(e.message, k == 3 ? "scene" : "objects"),
              "%s: %s", no_objects[k], s ? "parsed" : e.message);
        sem_scene_destroy(s);
    }
    expect_error("\"sem\": {}", "", "objects[0]", "exactly one of \"model\" or \"primitive\"");
    expect_error(BOX ", \"model\": \"a.igs\"", "", "objects[0]", "exactly one of");
    /* SEM settings */
    expect_error(BOX ", \"sem\": {\"alpha\": 0}", "", "objects[0].sem.alpha", "must be positive");
    expect_error(BOX ", \"sem\": {\"alpha\": -2}", "", "objects[0].sem.alpha", "must be positive");
    expect_error(BOX ", \"sem\": {\"sparsity\": 0}", "", "objects[0].sem.sparsity", "(0, 1)");
    expect_error(BOX ", \"sem\": {\"sparsity\": 1}", "", "objects[0].sem.sparsity", "(0, 1)");
    expect_error(BOX ", \"sem\": {\"order\": 3}", "", "objects[0].sem.order", "1 or 2");
    expect_error(BOX ", \"sem\": {\"seams\": \"blended\"}", "", "objects[0].sem.seams", "\"geometric\" or \"paper\"");
    expect_error(BOX ", \"sem\": {\"resolution\": -1}", "", "objects[0].sem.resolution", "0..1000");
    expect_error(BOX ", \"sem\": {\"resolution\": 1001}", "", "objects[0].sem.resolution", "0..1000");
    expect_error(BOX ", \"sem\": {\"weld\": 1}", "", "objects[0].sem.weld", "true or false");
    expect_error(BOX ", \"sem\": {\"fit\": \"faces\"}", "", "objects[0].sem.fit", "\"auto\", \"parts\" or \"origins\"");
    expect_error(BOX ", \"sem\": {\"alpha\": 1, \"sparsity\": 0.5}", "", "objects[0].sem: give either", "not both");
    expect_error(BOX ", \"sem\": {\"rays\": [0, 4]}", "", "objects[0].sem.rays", NULL);
    expect_error(BOX ", \"sem\": {\"ray_axis\": \"w\"}", "", "objects[0].sem.ray_axis", NULL);
    /* primitives, transforms, pins, prescriptions, loads */
    expect_error("\"primitive\": {\"type\": \"box\", \"size\": [1, -1, 1]}", "", "objects[0].primitive.size",
                 "positive");
    expect_error("\"primitive\": {\"type\": \"sphere\", \"radius\": 0}", "", "objects[0].primitive.radius",
                 "positive");
    expect_error("\"primitive\": {\"type\": \"torus\", \"major\": 1, \"minor\": 2}", "", "objects[0].primitive",
                 "less than major");
    expect_error(BOX ", \"transform\": {\"scale\": -1}", "", "objects[0].transform.scale", "positive");
    expect_error(BOX ", \"transform\": {\"rotate\": {\"axis\": [0, 0, 0], \"degrees\": 3}}", "",
                 "objects[0].transform.rotate", "axis must not be zero");
    expect_error(BOX ", \"transform\": {\"matrix\": [[-1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]]}", "",
                 "objects[0].transform.matrix", "determinant");
    expect_error(BOX ", \"transform\": {\"matrix\": [[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0]], \"scale\": 2}",
                 "", "objects[0].transform.matrix", "not both");
    expect_error(BOX ", \"pin\": {\"box\": [[1, 0, 0], [0, 1, 1]]}", "", "objects[0].pin.box", "lower corner");
    expect_error(BOX ", \"pin\": {\"parts\": [-1]}", "", "objects[0].pin.parts", "non-negative");
    expect_error(BOX ", \"prescribe\": {\"rotate\": {\"degrees_per_second\": 10}}", "", "objects[0].prescribe",
                 "no \"pin\"");
    expect_error(BOX ", \"pin\": {\"parts\": [0]}, \"prescribe\": {\"rotate\": {\"degrees_per_second\": 10, "
                     "\"radians_per_second\": 1}}",
                 "", "objects[0].prescribe.rotate", "not both");
    expect_error(BOX ", \"pin\": {\"parts\": [0]}, \"prescribe\": {\"affine\": [[1, 0, 0, 0]]}", "",
                 "objects[0].prescribe.affine", "3 rows");
    expect_error(BOX ", \"pin\": {\"parts\": [0]}, \"prescribe\": {\"move\": {\"duration\": 1}}", "",
                 "objects[0].prescribe.move", "needs \"velocity\"");
    expect_error(BOX ", \"pin\": {\"parts\": [0]}, \"prescribe\": {\"move\": {\"velocity\": [0, 0, 1]},"
                     " \"rotate\": {\"degrees_per_second\": 10}}",
                 "", "objects[0].prescribe", "one of \"affine\", \"rotate\" and \"move\"");
    {
        sem_error e;
        sem_scene *m = parse_object(BOX ", \"pin\": {\"parts\": [0]}, \"prescribe\": {\"move\": {\"velocity\": "
                                        "[0.5, 0, -0.25], \"duration\": 2}}",
                                    "", &e);
        CHECK(m && m->objects[0].prescribe.type == SEM_PRESCRIBE_MOVE &&
                  m->objects[0].prescribe.velocity[0] == 0.5 && m->objects[0].prescribe.velocity[2] == -0.25 &&
                  m->objects[0].prescribe.duration == 2,
              "move: %s", m ? "wrong values" : e.message);
        sem_scene_destroy(m);
    }
    expect_error(BOX ", \"region_loads\": [{\"box\": [[0, 0, 0], [1, 1, 1]]}]", "", "objects[0].region_loads[0]",
                 "force_density");
    expect_error(BOX ", \"region_loads\": [{\"box\": [[0, 0, 0], [1, 1, 1]], \"force_density\": [1, 0, 0], "
                     "\"frequency\": -1}]",
                 "", "objects[0].region_loads[0]", "frequency");
    expect_error(BOX ", \"point_loads\": [{\"force\": [1, 0, 0]}]", "", "objects[0].point_loads[0]", "position");
    expect_error(BOX ", \"gamma\": 0", "", "objects[0].gamma", "positive");

    /* invalid JSON: file and line */
    sem_error err;
    sem_scene *s = parse("{\n\"objects\": [\n{,]}", &err);
    CHECK(s == NULL && strstr(err.message, "t.json:3: not valid JSON"), "got %s", s ? "a scene" : err.message);
    sem_scene_destroy(s);
}

static void test_defaults_and_values(void)
{
    sem_error err;
    sem_scene *s = parse_object(BOX, "", &err);
    CHECK(s != NULL, "minimal scene: %s", s ? "" : err.message);
    if (!s) return;
    CHECK(s->n_objects == 1, "n_objects %d", s->n_objects);
    CHECK(s->frames == 120 && s->steps_per_frame == 1, "frames %d steps %d", s->frames, s->steps_per_frame);
    CHECK(!strcmp(s->output_dir, "out"), "dir %s", s->output_dir);
    CHECK(s->write_iges && s->write_mesh && s->write_usd && !s->write_obj, "formats");
    CHECK(s->mesh_resolution == 6, "mesh_resolution %d", s->mesh_resolution);
    CHECK_NEAR(s->world.gravity[2], -9.81, 0);
    CHECK_NEAR(s->world.dt, 0.01, 0);
    CHECK(s->world.integrator == SEM_LINEARLY_IMPLICIT_EULER, "integrator %d", (int)s->world.integrator);
    const sem_scene_object *o = &s->objects[0];
    CHECK(!strcmp(o->primitive, "box") && o->model_path[0] == '\0', "primitive %s", o->primitive);
    CHECK(o->material.type == SEM_MATERIAL_NEOHOOKEAN, "material type");
    CHECK_NEAR(o->material.density, 1000, 0);
    CHECK_NEAR(o->material.youngs_modulus, 1e6, 0);
    CHECK_NEAR(o->material.poisson_ratio, 0.45, 0);
    /* Lame parameters are set: mu = E / (2 (1 + nu)) */
    CHECK_REL(o->material.mu, 1e6 / 2.9, 1e-14);
    CHECK(o->sem.order == 2 && o->sem.rays[0] == 0 && o->sem.points_per_interval == 0 &&
              o->sem.spacing == 0 && o->sem.ray_axis == -1,
          "sem defaults");
    CHECK(o->seams == SEM_SEAMS_GEOMETRIC, "seams default");
    CHECK(o->sem.fit_rule == SEM_FIT_AUTO, "fit default");
    CHECK(o->prescribe.type == SEM_PRESCRIBE_NONE && !o->has_pin_box && o->n_pin_parts == 0, "no pins");
    sem_scene_destroy(s);

    const char *full =
        "{\"description\": \"x\", \"objects\": [{\"model\": \"models/a.igs\","
        " \"material\": {\"type\": \"stvk\", \"density\": 7800, \"youngs_modulus\": 2e11, \"poisson_ratio\": 0.3},"
        " \"part_materials\": {\"2\": {\"youngs_modulus\": 1e9}, \"lid\": {\"type\": \"linear\"}},"
        " \"sem\": {\"order\": 1, \"alpha\": 0.25, \"rays\": [3, 7], \"ray_axis\": \"z\", \"points_per_interval\": 9,"
        "  \"gamma\": 5e6, \"tessellation\": 4, \"weight_threshold\": 0.01, \"seams\": \"paper\", \"fit\": \"origins\"},"
        " \"pin\": {\"box\": [[-1, -2, -3], [1, 2, 3]], \"parts\": [4, 1], \"points\": [7]},"
        " \"prescribe\": {\"rotate\": {\"axis_point\": [1, 2, 3], \"axis\": [0, 0, 2], \"degrees_per_second\": 90,"
        "  \"duration\": 2}},"
        " \"initial_velocity\": [1, 2, 3], \"initial_angular_velocity\": [0, 0, 4],"
        " \"point_loads\": [{\"position\": [1, 1, 1], \"force\": [0, 0, -5]}],"
        " \"region_loads\": [{\"box\": [[0, 0, 0], [1, 1, 1]], \"force_density\": [10, 0, 0], \"frequency\": 2,"
        "  \"phase\": 0.5}]},"
        " {\"primitive\": {\"type\": \"beam\", \"length\": 3, \"width\": 0.5, \"height\": 0.25, \"sections\": 2},"
        "  \"sem\": {\"sparsity\": 0.3}, \"pin\": {\"parts\": [0]},"
        "  \"prescribe\": {\"affine\": [[1, 0, 0, 1], [0, 1, 0, 2], [0, 0, 1, 3]]}}],"
        " \"gravity\": [0, -1, 0],"
        " \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.002, \"damping\": {\"mass\": 0.1, \"stiffness\": 0.01},"
        "  \"tolerance\": 1e-6, \"max_iterations\": 7, \"solver\": \"dense\"},"
        " \"frames\": 12, \"steps_per_frame\": 3, \"threads\": 2,"
        " \"output\": {\"dir\": \"res\", \"iges\": false, \"obj\": true, \"mesh\": false, \"usd\": true,"
        "  \"mesh_resolution\": 3}}";
    s = parse(full, &err);
    CHECK(s != NULL, "full scene: %s", s ? "" : err.message);
    if (!s) return;
    CHECK(s->n_objects == 2, "objects %d", s->n_objects);
    o = &s->objects[0];
    CHECK(!strcmp(o->model_path, "/base/models/a.igs"), "relative model path resolved: %s", o->model_path);
    CHECK(o->material.type == SEM_MATERIAL_STVK, "stvk");
    CHECK_NEAR(o->material.density, 7800, 0);
    CHECK_REL(o->material.lambda, 2e11 * 0.3 / (1.3 * 0.4), 1e-14);
    CHECK(o->n_part_materials == 2, "part materials %d", o->n_part_materials);
    if (o->n_part_materials == 2) {
        /* overrides start from the object's material */
        CHECK(o->part_materials[0].part == 2, "index key");
        CHECK_NEAR(o->part_materials[0].material.youngs_modulus, 1e9, 0);
        CHECK_NEAR(o->part_materials[0].material.density, 7800, 0);
        CHECK(o->part_materials[1].part == -1 && !strcmp(o->part_materials[1].name, "lid"), "name key");
        CHECK(o->part_materials[1].material.type == SEM_MATERIAL_LINEAR, "linear");
    }
    CHECK(o->sem.order == 1 && o->sem.rays[0] == 3 && o->sem.rays[1] == 7 && o->sem.ray_axis == 2, "sem ints");
    CHECK(o->sem.points_per_interval == 9 && o->sem.tessellation == 4, "sem ints 2");
    CHECK_NEAR(o->sem.alpha, 0.25, 0);
    CHECK_NEAR(o->sem.gamma, 5e6, 0);
    CHECK_NEAR(o->sem.weight_threshold, 0.01, 0);
    CHECK(o->seams == SEM_SEAMS_PAPER, "seams paper");
    CHECK(o->sem.fit_rule == SEM_FIT_ORIGINS, "fit origins");
    CHECK_NEAR(o->sem.youngs_modulus, 2e11, 0);
    CHECK(o->has_pin_box && o->pin_box[1] == -2 && o->pin_box[5] == 3, "pin box");
    CHECK(o->n_pin_parts == 2 && o->pin_parts[0] == 4 && o->pin_parts[1] == 1, "pin parts");
    CHECK(o->n_pin_points == 1 && o->pin_points[0] == 7, "pin points");
    CHECK(o->prescribe.type == SEM_PRESCRIBE_ROTATE, "rotate");
    CHECK_REL(o->prescribe.rate, M_PI / 2, 1e-15);
    CHECK_NEAR(o->prescribe.duration, 2, 0);
    CHECK_NEAR(o->prescribe.axis_point[2], 3, 0);
    CHECK_NEAR(o->prescribe.axis_direction[2], 2, 0);
    CHECK_NEAR(o->initial_velocity[1], 2, 0);
    CHECK_NEAR(o->initial_angular_velocity[2], 4, 0);
    CHECK(o->n_point_loads == 1 && o->point_loads[0].force[2] == -5 && o->point_loads[0].X[0] == 1, "point load");
    CHECK(o->n_region_loads == 1, "region loads");
    if (o->n_region_loads == 1) {
        CHECK_NEAR(o->region_loads[0].force_density[0], 10, 0);
        CHECK_NEAR(o->region_loads[0].frequency, 2, 0);
        CHECK_NEAR(o->region_loads[0].phase, 0.5, 0);
        CHECK_NEAR(o->region_loads[0].box[3], 1, 0);
    }
    o = &s->objects[1];
    CHECK(!strcmp(o->primitive, "beam"), "beam");
    CHECK(o->primitive_size[0] == 3 && o->primitive_size[1] == 0.5 && o->primitive_size[2] == 0.25, "beam size");
    CHECK(o->primitive_sections == 2, "sections");
    CHECK_NEAR(o->sem.sparsity, 0.3, 0);
    CHECK(o->prescribe.type == SEM_PRESCRIBE_AFFINE && o->prescribe.affine[7] == 2, "affine");
    CHECK_NEAR(s->world.gravity[1], -1, 0);
    CHECK(s->world.integrator == SEM_IMPLICIT_EULER && s->world.solver == SEM_SOLVER_DENSE, "integrator");
    CHECK_NEAR(s->world.dt, 0.002, 0);
    CHECK_NEAR(s->world.rayleigh_mass, 0.1, 0);
    CHECK_NEAR(s->world.rayleigh_stiffness, 0.01, 0);
    CHECK_NEAR(s->world.newton_tolerance, 1e-6, 0);
    CHECK(s->world.newton_max_iterations == 7 && s->world.threads == 2, "newton its, threads");
    CHECK(s->frames == 12 && s->steps_per_frame == 3, "frames");
    CHECK(!strcmp(s->output_dir, "res") && !s->write_iges && s->write_obj && !s->write_mesh && s->write_usd,
          "output");
    CHECK(s->mesh_resolution == 3, "mesh res");
    sem_scene_destroy(s);
}

/* Scale, then rotate, then translate: checked on one point against the closed form. */
static void test_transform(void)
{
    sem_error err;
    sem_scene *s = parse_object("\"primitive\": {\"type\": \"box\", \"size\": [1, 2, 3]},"
                                " \"transform\": {\"scale\": [2, 3, 4], \"rotate\": {\"axis\": [0, 0, 5],"
                                " \"degrees\": 90}, \"translate\": [10, 20, 30]}",
                                "", &err);
    CHECK(s != NULL, "transform scene: %s", s ? "" : err.message);
    if (!s) return;
    const double *T = s->objects[0].transform;
    /* X = (1, 1, 1): scale -> (2, 3, 4); rotate 90 deg about z -> (-3, 2, 4); + t */
    double X[3] = {1, 1, 1}, y[3];
    for (int r = 0; r < 3; ++r) y[r] = T[4 * r] * X[0] + T[4 * r + 1] * X[1] + T[4 * r + 2] * X[2] + T[4 * r + 3];
    CHECK_NEAR(y[0], 7, 1e-13);
    CHECK_NEAR(y[1], 22, 1e-13);
    CHECK_NEAR(y[2], 34, 1e-13);
    /* the generated model is transformed: box corners (+-0.5, +-1, +-1.5) scaled to
     * (+-1, +-3, +-6), rotated to x in [-3, 3], y in [-1, 1], then shifted */
    sem_model *m = NULL;
    CHECK(sem_scene_object_model(s, 0, &m, &err) == SEM_OK, "model: %s", err.message);
    if (m) {
        double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
        for (int i = 0; i < m->n_parts; ++i) {
            const sem_surface *sf = &m->parts[i].surface;
            for (int c = 0; c < sf->n_u * sf->n_v; ++c)
                for (int k = 0; k < 3; ++k) {
                    lo[k] = fmin(lo[k], sf->ctrl[3 * c + k]);
                    hi[k] = fmax(hi[k], sf->ctrl[3 * c + k]);
                }
        }
        CHECK_NEAR(lo[0], 7, 1e-12);
        CHECK_NEAR(hi[0], 13, 1e-12);
        CHECK_NEAR(lo[1], 19, 1e-12);
        CHECK_NEAR(hi[1], 21, 1e-12);
        CHECK_NEAR(lo[2], 24, 1e-12);
        CHECK_NEAR(hi[2], 36, 1e-12);
        CHECK(m->n_parts == 6, "box parts %d", m->n_parts);
        sem_model_destroy(m);
    }
    sem_scene_destroy(s);

    /* a full matrix is used as given; a uniform scale as a number */
    s = parse_object(BOX ", \"transform\": {\"matrix\": [[0, -1, 0, 1], [1, 0, 0, 2], [0, 0, 1, 3]]}", "", &err);
    CHECK(s != NULL, "matrix: %s", s ? "" : err.message);
    if (s) {
        const double *M = s->objects[0].transform;
        CHECK(M[1] == -1 && M[3] == 1 && M[4] == 1 && M[11] == 3, "matrix kept");
        sem_scene_destroy(s);
    }
    s = parse_object(BOX ", \"transform\": {\"scale\": 2.5}", "", &err);
    CHECK(s != NULL && s->objects[0].transform[0] == 2.5 && s->objects[0].transform[5] == 2.5 &&
              s->objects[0].transform[10] == 2.5 && s->objects[0].transform[1] == 0,
          "uniform scale");
    sem_scene_destroy(s);
}

static void test_models_pins_materials(void)
{
    sem_error err;
    /* a missing model file: parsing succeeds (paths resolve lazily), loading names the key and path */
    sem_scene *s = parse_object("\"model\": \"no/such/model.igs\"", "", &err);
    CHECK(s != NULL, "scene with a model: %s", s ? "" : err.message);
    if (s) {
        sem_model *m = NULL;
        CHECK(sem_scene_object_model(s, 0, &m, &err) != SEM_OK && m == NULL, "missing model must fail");
        CHECK(strstr(err.message, "objects[0].model") && strstr(err.message, "/base/no/such/model.igs"),
              "message names key and path: %s", err.message);
        sem_scene_destroy(s);
    }
    /* sem_scene_load resolves model paths relative to the scene file */
    char path[512];
    snprintf(path, sizeof path, "%s/scene_rel.json", test_tmpdir());
    FILE *f = fopen(path, "w");
    if (f) {
        fputs("{\"objects\": [{\"model\": \"sub/m.igs\"}]}", f);
        fclose(f);
    }
    char want[600];
    snprintf(want, sizeof want, "%s/sub/m.igs", test_tmpdir());
    CHECK(sem_scene_load(path, &s, &err) == SEM_OK, "load: %s", err.message);
    if (s) {
        CHECK(!strcmp(s->objects[0].model_path, want), "model path %s, want %s", s->objects[0].model_path, want);
        CHECK(!strcmp(s->path, path), "scene path");
        sem_scene_destroy(s);
    }
    CHECK(sem_scene_load("/nonexistent/scene.json", &s, &err) != SEM_OK && strstr(err.message, "cannot open"),
          "missing scene: %s", err.message);

    /* pins: a control box around the x = 0 end of a 2-section beam selects exactly its control
     * points: end cap 3x3 = 9, plus per side patch of section 1 its 3 points at x = 0: 4 x 3 =
     * 12; a (material) box selects none and becomes a pin region held at rest */
    s = parse_object("\"primitive\": {\"type\": \"beam\", \"sections\": 2, \"length\": 2},"
                     " \"pin\": {\"control_box\": [[-0.01, -1, -1], [0.01, 2, 2]], \"points\": [9],"
                     "          \"box\": [[1.5, -1, -1], [3, 2, 2]]}",
                     "", &err);
    CHECK(s != NULL, "pin scene: %s", s ? "" : err.message);
    if (s) {
        sem_model *m = NULL;
        CHECK(sem_scene_object_model(s, 0, &m, &err) == SEM_OK, "beam: %s", err.message);
        if (m) {
            unsigned char *pin = NULL;
            CHECK(sem_scene_object_pins(&s->objects[0], m, &pin, &err) == SEM_OK, "pins: %s", err.message);
            size_t n = sem_model_control_points(m), count = 0, bad = 0;
            size_t c = 0;
            for (int i = 0; i < m->n_parts; ++i) {
                const sem_surface *sf = &m->parts[i].surface;
                for (int k = 0; k < sf->n_u * sf->n_v; ++k, ++c) {
                    int at0 = fabs(sf->ctrl[3 * k]) < 1e-12;
                    if (pin && pin[c]) count++;
                    if (pin && c != 9 && pin[c] != at0) bad++;
                }
            }
            CHECK(c == n, "counted %zu of %zu", c, n);
            CHECK(count == 9 + 12 + 1, "pinned %zu", count);
            CHECK(bad == 0, "%zu wrongly pinned", bad);
            free(pin);
            sem_pin_region *r = NULL;
            int nr = -1;
            CHECK(sem_scene_object_pin_regions(&s->objects[0], &r, &nr, &err) == SEM_OK && nr == 1 && r &&
                      r[0].box[0] == 1.5 && r[0].box[5] == 2 && r[0].prescribe == -1,
                  "pin region: %d", nr);
            free(r);
            sem_model_destroy(m);
        }
        sem_scene_destroy(s);
    }
    /* a control box that selects nothing, a part or point that does not exist (a material box
     * that holds nothing is found with the discretization: sem_scene_world_create, test_run) */
    const char *bad_pins[][2] = {
        {"\"pin\": {\"control_box\": [[5, 5, 5], [6, 6, 6]]}", "pin.control_box: [[5, 5, 5], [6, 6, 6]] contains no control point"},
        {"\"pin\": {\"parts\": [6]}", "pin.parts: part 6 does not exist"},
        {"\"pin\": {\"points\": [96]}", "pin.points: control point 96 does not exist"},
    };
    for (int t = 0; t < 3; ++t) {
        char obj[512];
        snprintf(obj, sizeof obj, "%s, %s", BOX, bad_pins[t][0]);
        s = parse_object(obj, "", &err);
        CHECK(s != NULL, "%s: %s", obj, s ? "" : err.message);
        if (!s) continue;
        sem_model *m = NULL;
        sem_scene_object_model(s, 0, &m, &err);
        unsigned char *pin = (unsigned char *)1;
        CHECK(m && sem_scene_object_pins(&s->objects[0], m, &pin, &err) == SEM_ERR_INVALID && pin == NULL,
              "%s must fail", obj);
        CHECK(strstr(err.message, bad_pins[t][1]) != NULL, "message %s lacks %s", err.message, bad_pins[t][1]);
        sem_model_destroy(m);
        sem_scene_destroy(s);
    }
    /* part materials by index and name; a name that matches no part is an error */
    s = parse_object("\"primitive\": {\"type\": \"box\"}, \"part_materials\": {\"5\": {\"density\": 10},"
                     " \"box_xmin\": {\"density\": 20}}",
                     "", &err);
    CHECK(s != NULL, "part materials: %s", s ? "" : err.message);
    if (s) {
        sem_model *m = NULL;
        sem_scene_object_model(s, 0, &m, &err);
        int *idx = NULL;
        sem_material *mats = NULL;
        CHECK(m && sem_scene_object_part_materials(&s->objects[0], m, &idx, &mats, &err) == SEM_OK, "pm: %s",
              err.message);
        if (idx && mats) {
            CHECK(idx[0] == 1 && idx[5] == 0 && idx[1] == -1 && idx[2] == -1, "idx %d %d %d", idx[0], idx[5], idx[1]);
            CHECK(mats[0].density == 10 && mats[1].density == 20, "densities");
        }
        free(idx);
        free(mats);
        sem_model_destroy(m);
        sem_scene_destroy(s);
    }
    s = parse_object(BOX ", \"part_materials\": {\"lid\": {\"density\": 10}}", "", &err);
    if (s) {
        sem_model *m = NULL;
        sem_scene_object_model(s, 0, &m, &err);
        int *idx = NULL;
        sem_material *mats = NULL;
        CHECK(m && sem_scene_object_part_materials(&s->objects[0], m, &idx, &mats, &err) != SEM_OK, "no part lid");
        CHECK(strstr(err.message, "no part is named \"lid\"") != NULL, "message %s", err.message);
        sem_model_destroy(m);
        sem_scene_destroy(s);
    }
}

/* Generated primitives take their sizes from the scene. */
static void test_primitives(void)
{
    sem_error err;
    struct {
        const char *prim;
        int parts;
        double lo_z, hi_x;
    } cases[] = {
        {"{\"type\": \"box\", \"size\": [1, 2, 3]}", 6, -1.5, 0.5},
        {"{\"type\": \"beam\", \"size\": [4, 1, 2], \"sections\": 3}", 6 + 4 * 2, 0, 4},
        {"{\"type\": \"sphere\", \"radius\": 2}", 1, -2, 2},
        {"{\"type\": \"cylinder\", \"radius\": 0.5, \"height\": 3}", 3, -1.5, 0.5},
        {"{\"type\": \"torus\", \"major\": 2, \"minor\": 0.5}", 1, -0.5, 2.5},
    };
    for (int t = 0; t < 5; ++t) {
        char obj[256];
        snprintf(obj, sizeof obj, "\"primitive\": %s", cases[t].prim);
        sem_scene *s = parse_object(obj, "", &err);
        CHECK(s != NULL, "%s: %s", obj, s ? "" : err.message);
        if (!s) continue;
        sem_model *m = NULL;
        CHECK(sem_scene_object_model(s, 0, &m, &err) == SEM_OK, "%s: %s", obj, err.message);
        if (m) {
            CHECK(m->n_parts == cases[t].parts, "%s: %d parts", obj, m->n_parts);
            double lo = 1e300, hi = -1e300;
            for (int i = 0; i < m->n_parts; ++i) {
                const sem_surface *sf = &m->parts[i].surface;
                for (int c = 0; c < sf->n_u * sf->n_v; ++c) {
                    lo = fmin(lo, sf->ctrl[3 * c + 2]);
                    hi = fmax(hi, sf->ctrl[3 * c]);
                }
            }
            CHECK_NEAR(lo, cases[t].lo_z, 1e-12);
            CHECK_NEAR(hi, cases[t].hi_x, 1e-12);
            sem_model_destroy(m);
        }
        sem_scene_destroy(s);
    }
}

static void test_default_scene(void)
{
    sem_error err;
    sem_scene *s = NULL;
    CHECK(sem_scene_parse(sem_scene_default_json(), "default", ".", &s, &err) == SEM_OK, "default: %s", err.message);
    if (!s) return;
    CHECK(s->n_objects == 1 && !strcmp(s->objects[0].primitive, "beam"), "beam");
    CHECK(s->world.integrator == SEM_IMPLICIT_EULER && s->frames == 100 && s->steps_per_frame == 2, "world");
    CHECK_NEAR(s->objects[0].material.youngs_modulus, 2e6, 0);
    sem_scene_destroy(s);
    /* examples/default_beam.json is the same scene */
    char path[1024];
    snprintf(path, sizeof path, "%s/../../examples/default_beam.json", SEM_TEST_DATA);
    CHECK(sem_scene_load(path, &s, &err) == SEM_OK, "%s", err.message);
    if (s) {
        CHECK(s->world.integrator == SEM_IMPLICIT_EULER && s->frames == 100 && s->steps_per_frame == 2, "world");
        CHECK(s->objects[0].primitive_sections == 4 && s->objects[0].primitive_size[0] == 2, "beam");
        CHECK_NEAR(s->objects[0].material.youngs_modulus, 2e6, 0);
        CHECK_NEAR(s->objects[0].material.density, 1100, 0);
        CHECK(s->objects[0].has_pin_box && s->objects[0].pin_box[3] == 0.01, "pin");
        sem_scene_destroy(s);
    }
}

/* Strictness beyond the keys: JSON that cJSON accepts but that would run something else than
 * written (a repeated key reads only its first value; text after the object is ignored),
 * integers out of range named as such, limits shared with the preprocessing code. */
static void test_strict_json(void)
{
    expect_error(BOX, "\"frames\": 10, \"frames\": 1000", "scene: key \"frames\" appears more than once",
                 NULL);
    expect_error(BOX ", \"material\": {\"density\": 1, \"density\": 2}", "",
                 "scene.objects[0].material: key \"density\" appears more than once", NULL);
    expect_error(BOX, "\"frames\": 1e12", "frames", "too large");
    expect_error(BOX, "\"frames\": 200000000", "frames", "too large (at most 100000000)");
    expect_error(BOX, "\"frames\": 2.5", "frames", "must be an integer");
    expect_error(BOX ", \"sem\": {\"rays\": [5000, 5]}", "", "objects[0].sem.rays", "1..4096");
    expect_error(BOX ", \"sem\": {\"points_per_interval\": 20000}", "",
                 "objects[0].sem.points_per_interval", "1..10000");
    sem_error err;
    sem_scene *s = parse("{\"objects\": [{" BOX "}]}\n{\"frames\": 3}\n", &err);
    CHECK(!s && strstr(err.message, "t.json:2: not valid JSON: text after the end"), "%s",
          err.message);
    sem_scene_destroy(s);
    /* trailing white space is fine */
    s = parse("{\"objects\": [{" BOX "}]}\n\n  \t\n", &err);
    CHECK(s != NULL, "trailing white space: %s", err.message);
    sem_scene_destroy(s);
    /* a key with control bytes is named without them */
    s = parse("{\"objects\": [{" BOX "}], \"fr\\u001b[2Jmes\": 1}", &err);
    CHECK(!s && strstr(err.message, "unknown key \"fr?[2Jmes\""), "%s", err.message);
    sem_scene_destroy(s);
}

/* sem_scene_world_frame_model: the object's model at its state in its file's units. A beam
 * file read as millimetres ("units": "mm") is simulated in metres (2 mm long), and the frame
 * model has the state's numbers times 1000 exactly (the animation writer's 1 / 0.001), units
 * "MM" - what sem run writes in frame_NNNN.igs. A bad object index is an error. */
static void test_frame_model_units(void)
{
    sem_error err;
    char path[512], json[1024];
    snprintf(path, sizeof path, "%s/beam_mm.igs", test_tmpdir());
    sem_model *beam = sem_model_create();
    sem_beam_def def = sem_default_beam_def();
    def.length = 2, def.width = 0.4, def.height = 0.4;
    CHECK(beam && sem_primitive_beam(beam, &def, &err) == SEM_OK && sem_model_save(beam, path, &err) == SEM_OK,
          "beam file: %s", err.message);
    sem_model_destroy(beam);
    snprintf(json, sizeof json,
             "{\"objects\": [{\"model\": \"%s\", \"units\": \"mm\", \"sem\": {\"order\": 1, \"rays\": [3, 3]},"
             " \"pin\": {\"box\": [[-1e-5, -1, -1], [1e-5, 1, 1]]}}],"
             " \"integrator\": {\"type\": \"linearly_implicit_euler\", \"dt\": 0.01}}",
             path);
    sem_scene *s = parse(json, &err);
    CHECK(s != NULL, "scene: %s", s ? "" : err.message);
    if (!s) return;
    sem_scene_world_options options = sem_default_scene_world_options();
    options.skip_modes = 1;
    sem_scene_world *sw = NULL;
    CHECK(sem_scene_world_create(s, &options, &sw, &err) == SEM_OK, "world: %s", err.message);
    if (sw) {
        sem_world *w = sem_scene_world_world(sw);
        for (int k = 0; k < 3; ++k) CHECK(sem_world_step(w, &err) == SEM_OK, "step: %s", err.message);
        sem_model *frame = NULL;
        CHECK(sem_scene_world_frame_model(sw, 0, &frame, &err) == SEM_OK && frame, "frame model: %s",
              err.message);
        if (frame) {
            size_t n = 3 * sem_model_control_points(frame), off = 0;
            double *x = malloc(n * sizeof *x);
            const double *q = sem_world_object_q(w, 0);
            double lo = INFINITY, hi = -INFINITY, moved = 0;
            const sem_model *rest = sem_scene_world_model(sw, 0);
            if (x) {
                sem_model_get_q(frame, x);
                for (size_t i = 0; i < n; ++i) off += x[i] != q[i] * (1.0 / 0.001);
                for (size_t i = 0; i < n; i += 3) {
                    lo = fmin(lo, q[i]);
                    hi = fmax(hi, q[i]);
                }
                double *r = malloc(n * sizeof *r);
                if (r) {
                    sem_model_get_q(rest, r);
                    for (size_t i = 0; i < n; ++i) moved = fmax(moved, fabs(r[i] - q[i]));
                    free(r);
                }
            }
            CHECK(x && off == 0, "%zu of %zu frame numbers differ from q x 1000", off, n);
            CHECK(fabs(hi - lo - 0.002) < 1e-4, "the beam is %g m long, want 0.002", hi - lo);
            CHECK(moved > 0, "the state did not move");
            CHECK(!strcmp(frame->units, "MM") && frame->unit_to_meter == 0.001, "units %s %g", frame->units,
                  frame->unit_to_meter);
            CHECK(!strcmp(rest->units, "M"), "the simulated model is in metres, not %s", rest->units);
            free(x);
            sem_model_destroy(frame);
        }
        CHECK(sem_scene_world_frame_model(sw, 1, &frame, &err) == SEM_ERR_INVALID && !frame &&
                  strstr(err.message, "object 1"),
              "object 1 of 1: %s", err.message);
        sem_scene_world_destroy(sw);
    }
    sem_scene_destroy(s);
}

/* sem.resolution: the world simulates the patches (welded), the frames show the file's parts
 * refined at the cuts (the patches' points gathered back), part selections name the file's
 * parts, control point selections are refused. */
static void test_resolution(void)
{
    sem_error err;
    const char *json =
        "{\"objects\": [{\"primitive\": {\"type\": \"beam\", \"sections\": 1, \"length\": 2, \"width\": 0.4,"
        " \"height\": 0.4}, \"sem\": {\"resolution\": 4, \"order\": 1},"
        " \"pin\": {\"parts\": [0]}, \"part_materials\": {\"1\": {\"youngs_modulus\": 2e6}}}],"
        " \"integrator\": {\"type\": \"linearly_implicit_euler\", \"dt\": 0.01}}";
    sem_scene *s = parse(json, &err);
    CHECK(s != NULL, "scene: %s", s ? "" : err.message);
    if (!s) return;
    sem_scene_world_options options = sem_default_scene_world_options();
    options.skip_modes = 1;
    sem_scene_world *sw = NULL;
    CHECK(sem_scene_world_create(s, &options, &sw, &err) == SEM_OK, "world: %s", err.message);
    if (sw) {
        const sem_model *sim = sem_scene_world_model(sw, 0), *shown = sem_scene_world_output_model(sw, 0);
        /* 2 x 0.4 x 0.4 beam, diagonal 2.08, patches <= 0.52: each long face 4 x 1 */
        CHECK(shown->n_parts == 6, "frames show %d parts, the file has 6", shown->n_parts);
        CHECK(sim->n_parts == 2 + 4 * 4, "the world simulates %d patches, want 18", sim->n_parts);
        sem_world *w = sem_scene_world_world(sw);
        for (int k = 0; k < 2; ++k) CHECK(sem_world_step(w, &err) == SEM_OK, "step: %s", err.message);
        size_t ns = sem_model_control_points(shown);
        double *x = malloc(3 * ns * sizeof *x);
        sem_model *frame = NULL;
        CHECK(sem_scene_world_frame_model(sw, 0, &frame, &err) == SEM_OK && frame, "frame model: %s", err.message);
        if (x && frame) {
            sem_scene_world_output_q(sw, 0, sem_world_object_q(w, 0), x);
            double *y = malloc(3 * ns * sizeof *y);
            if (y) {
                sem_model_get_q(frame, y);
                int same = sem_model_control_points(frame) == ns;
                for (size_t i = 0; same && i < 3 * ns; ++i) same = y[i] == x[i];
                CHECK(same, "the frame model is not the gathered state");
                free(y);
            }
        }
        sem_model_destroy(frame);
        free(x);
        sem_scene_world_destroy(sw);
    }
    sem_scene_destroy(s);
    /* control points of the file cannot be named: they are refined */
    s = parse("{\"objects\": [{\"primitive\": {\"type\": \"box\"}, \"sem\": {\"resolution\": 4},"
              " \"pin\": {\"points\": [0]}}]}",
              &err);
    if (s) {
        sw = NULL;
        CHECK(sem_scene_world_create(s, &options, &sw, &err) == SEM_ERR_INVALID && !sw &&
                  strstr(err.message, "pin.points") && strstr(err.message, "sem.resolution"),
              "pin.points with a resolution: %s", err.message);
        sem_scene_world_destroy(sw);
        sem_scene_destroy(s);
    }
}

int main(void)
{
    test_resolution();
    test_strict_json();
    test_frame_model_units();
    test_errors();
    test_defaults_and_values();
    test_transform();
    test_models_pins_materials();
    test_primitives();
    test_default_scene();
    return test_finish("test_scene");
}
