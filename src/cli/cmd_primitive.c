/*
 * cmd_primitive.c - `sem primitive SHAPE [options] -o FILE`: exact NURBS solids
 * (sem/primitives.h) written in any format sem_model_save knows.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "sem/primitives.h"

#define CMD "primitive"

typedef enum shape { BOX, BEAM, SPHERE, CYLINDER, TORUS } shape;

static const char *const shape_names[] = {"box", "beam", "sphere", "cylinder", "torus"};

/* Which options each shape takes (bit per shape). */
typedef struct option_spec {
    const char *name;
    int values;
    unsigned shapes;
} option_spec;

#define S(x) (1u << (x))
static const option_spec options[] = {
    {"--size", 3, S(BOX)},
    {"--center", 3, S(BOX) | S(SPHERE) | S(CYLINDER) | S(TORUS)},
    {"--degree", 1, S(BOX) | S(BEAM)},
    {"--sections", 1, S(BEAM)},
    {"--length", 1, S(BEAM)},
    {"--width", 1, S(BEAM)},
    {"--height", 1, S(BEAM) | S(CYLINDER)},
    {"--radius", 1, S(SPHERE) | S(CYLINDER)},
    {"--major", 1, S(TORUS)},
    {"--minor", 1, S(TORUS)},
};

typedef struct values {
    double size[3], center[3];
    int degree, sections;
    double length, width, height, radius, major, minor;
    unsigned given; /* bit per options[] entry */
} values;

static int parse_option(int k, char **args, values *v)
{
    const char *opt = options[k].name;
    int rc = CLI_OK;
    switch (k) {
    case 0:
        for (int d = 0; d < 3 && rc == CLI_OK; ++d) rc = cli_parse_double(CMD, opt, args[d], &v->size[d]);
        break;
    case 1:
        for (int d = 0; d < 3 && rc == CLI_OK; ++d)
            rc = cli_parse_double(CMD, opt, args[d], &v->center[d]);
        break;
    case 2: rc = cli_parse_int(CMD, opt, args[0], &v->degree); break;
    case 3: rc = cli_parse_int(CMD, opt, args[0], &v->sections); break;
    case 4: rc = cli_parse_double(CMD, opt, args[0], &v->length); break;
    case 5: rc = cli_parse_double(CMD, opt, args[0], &v->width); break;
    case 6: rc = cli_parse_double(CMD, opt, args[0], &v->height); break;
    case 7: rc = cli_parse_double(CMD, opt, args[0], &v->radius); break;
    case 8: rc = cli_parse_double(CMD, opt, args[0], &v->major); break;
    case 9: rc = cli_parse_double(CMD, opt, args[0], &v->minor); break;
    default: break;
    }
    return rc;
}

#define GIVEN(k) (v.given & (1u << (k)))

static sem_status build(shape sh, const values v, sem_model *model, sem_error *err)
{
    switch (sh) {
    case BOX: {
        sem_box_def def = sem_default_box_def();
        if (GIVEN(0)) memcpy(def.size, v.size, sizeof def.size);
        if (GIVEN(1)) memcpy(def.center, v.center, sizeof def.center);
        if (GIVEN(2)) def.degree = v.degree;
        return sem_primitive_box(model, &def, err);
    }
    case BEAM: {
        sem_beam_def def = sem_default_beam_def();
        if (GIVEN(2)) def.degree = v.degree;
        if (GIVEN(3)) def.sections = v.sections;
        if (GIVEN(4)) def.length = v.length;
        if (GIVEN(5)) def.width = v.width;
        if (GIVEN(6)) def.height = v.height;
        return sem_primitive_beam(model, &def, err);
    }
    case SPHERE: {
        sem_sphere_def def = sem_default_sphere_def();
        if (GIVEN(1)) memcpy(def.center, v.center, sizeof def.center);
        if (GIVEN(7)) def.radius = v.radius;
        return sem_primitive_sphere(model, &def, err);
    }
    case CYLINDER: {
        sem_cylinder_def def = sem_default_cylinder_def();
        if (GIVEN(1)) memcpy(def.center, v.center, sizeof def.center);
        if (GIVEN(6)) def.height = v.height;
        if (GIVEN(7)) def.radius = v.radius;
        return sem_primitive_cylinder(model, &def, err);
    }
    case TORUS: {
        sem_torus_def def = sem_default_torus_def();
        if (GIVEN(1)) memcpy(def.center, v.center, sizeof def.center);
        if (GIVEN(8)) def.major = v.major;
        if (GIVEN(9)) def.minor = v.minor;
        return sem_primitive_torus(model, &def, err);
    }
    }
    return sem_error_set(err, SEM_ERR_INVALID, "unknown shape");
}

int cmd_primitive(int argc, char **argv)
{
    if (argc < 2) return cli_usage(CMD, "which shape? box, beam, sphere, cylinder or torus");
    int sh = -1;
    for (int s = 0; s < 5; ++s)
        if (strcmp(argv[1], shape_names[s]) == 0) sh = s;
    if (sh < 0)
        return cli_usage(CMD, "unknown shape '%s' (box, beam, sphere, cylinder, torus)", argv[1]);
    values v;
    memset(&v, 0, sizeof v);
    const char *output = NULL;
    for (int i = 2; i < argc; ++i) {
        const char *arg = argv[i];
        if (strcmp(arg, "-o") == 0 || strcmp(arg, "--output") == 0) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            output = argv[++i];
            continue;
        }
        int k = -1;
        for (int o = 0; o < (int)(sizeof options / sizeof options[0]); ++o)
            if (strcmp(arg, options[o].name) == 0) k = o;
        if (k < 0) {
            if (arg[0] == '-') return cli_usage(CMD, "unknown option '%s'", arg);
            return cli_usage(CMD, "unexpected argument '%s'", arg);
        }
        if (!(options[k].shapes & (1u << sh)))
            return cli_usage(CMD, "%s does not apply to a %s", arg, shape_names[sh]);
        if (cli_need_values(CMD, argc, argv, i, options[k].values) != CLI_OK) return CLI_USAGE;
        if (parse_option(k, argv + i + 1, &v) != CLI_OK) return CLI_USAGE;
        v.given |= 1u << k;
        i += options[k].values;
    }
    if (!output) return cli_usage(CMD, "missing -o FILE");

    sem_error err;
    sem_error_clear(&err);
    sem_model *model = sem_model_create();
    if (!model) return cli_fail("out of memory");
    sem_status st = build((shape)sh, v, model, &err);
    if (st != SEM_OK) {
        sem_model_destroy(model);
        return cli_fail_error(NULL, &err);
    }
    st = sem_model_save(model, output, &err);
    if (st != SEM_OK) {
        sem_model_destroy(model);
        return cli_fail_error(output, &err);
    }
    size_t n_ctrl = sem_model_control_points(model);
    printf("%s: %s, %d parts, %zu control points (%zu dofs)\n", output, shape_names[sh],
           model->n_parts, n_ctrl, 3 * n_ctrl);
    sem_model_destroy(model);
    return CLI_OK;
}
