/*
 * cmd_inspect.c - `sem inspect FILE [--json]`: what a model is made of (parts, control
 * points, degrees of freedom q = 3 x control points as in the paper's Table 1, trims) and
 * its measures (area, bounding box of the surface itself, sem/measure.h).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "sem/measure.h"

#define CMD "inspect"

static cJSON *json_vec3(const double x[3])
{
    return cJSON_CreateDoubleArray(x, 3);
}

/* [[xmin,ymin,zmin],[xmax,ymax,zmax]], or null when there is no box */
static cJSON *json_bbox(const sem_part_measure_result *r)
{
    if (!(r->bbox_min[0] <= r->bbox_max[0])) return cJSON_CreateNull();
    cJSON *b = cJSON_CreateArray();
    cJSON_AddItemToArray(b, json_vec3(r->bbox_min));
    cJSON_AddItemToArray(b, json_vec3(r->bbox_max));
    return b;
}

static cJSON *json_number_or_null(double x)
{
    return isfinite(x) ? cJSON_CreateNumber(x) : cJSON_CreateNull();
}

static cJSON *inspect_json(const char *path, const sem_model *m,
                           const sem_part_measure_result *per, const sem_part_measure_result *total,
                           const char *measure_warning)
{
    size_t n_ctrl = sem_model_control_points(m);
    int trimmed = 0;
    for (int i = 0; i < m->n_parts; ++i)
        trimmed += m->parts[i].has_outer || m->parts[i].n_holes > 0;
    cJSON *o = cJSON_CreateObject();
    cJSON_AddStringToObject(o, "file", path);
    cJSON_AddNumberToObject(o, "parts", m->n_parts);
    cJSON_AddNumberToObject(o, "control_points", (double)n_ctrl);
    cJSON_AddNumberToObject(o, "dofs", 3.0 * (double)n_ctrl);
    cJSON_AddNumberToObject(o, "trimmed_parts", trimmed);
    cJSON_AddItemToObject(o, "bbox", json_bbox(total));
    cJSON_AddItemToObject(o, "area", json_number_or_null(total->area));
    cJSON_AddStringToObject(o, "units", m->units);
    cJSON_AddNumberToObject(o, "unit_to_meter", m->unit_to_meter);
    cJSON *w = cJSON_AddArrayToObject(o, "warnings");
    for (int i = 0; i < m->n_warnings; ++i)
        if (m->warnings[i]) cJSON_AddItemToArray(w, cJSON_CreateString(m->warnings[i]));
    if (measure_warning) cJSON_AddItemToArray(w, cJSON_CreateString(measure_warning));
    cJSON *parts = cJSON_AddArrayToObject(o, "part_details");
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_part *p = &m->parts[i];
        cJSON *d = cJSON_CreateObject();
        cJSON_AddNumberToObject(d, "index", i);
        cJSON_AddStringToObject(d, "name", p->name);
        int deg[2] = {p->surface.degree_u, p->surface.degree_v};
        int grid[2] = {p->surface.n_u, p->surface.n_v};
        cJSON_AddItemToObject(d, "degree", cJSON_CreateIntArray(deg, 2));
        cJSON_AddItemToObject(d, "control_grid", cJSON_CreateIntArray(grid, 2));
        cJSON_AddBoolToObject(d, "trimmed", p->has_outer || p->n_holes > 0);
        cJSON_AddNumberToObject(d, "holes", p->n_holes);
        cJSON_AddItemToObject(d, "area", json_number_or_null(per[i].area));
        cJSON_AddItemToObject(d, "bbox", json_bbox(&per[i]));
        cJSON_AddNumberToObject(d, "source_entity", p->source_entity);
        cJSON_AddItemToArray(parts, d);
    }
    return o;
}

static void inspect_text(const char *path, const sem_model *m, const sem_part_measure_result *per,
                         const sem_part_measure_result *total)
{
    size_t n_ctrl = sem_model_control_points(m);
    int trimmed = 0, holes = 0;
    for (int i = 0; i < m->n_parts; ++i) {
        trimmed += m->parts[i].has_outer || m->parts[i].n_holes > 0;
        holes += m->parts[i].n_holes;
    }
    printf("file            %s\n", path);
    printf("units           %s (1 unit = %g m)\n", m->units, m->unit_to_meter);
    printf("parts           %d (%d trimmed, %d holes)\n", m->n_parts, trimmed, holes);
    printf("control points  %zu (dofs q = %zu)\n", n_ctrl, 3 * n_ctrl);
    printf("area            %.10g\n", total->area);
    if (total->bbox_min[0] <= total->bbox_max[0]) {
        printf("bbox            [%.10g, %.10g, %.10g] .. [%.10g, %.10g, %.10g]\n",
               total->bbox_min[0], total->bbox_min[1], total->bbox_min[2], total->bbox_max[0],
               total->bbox_max[1], total->bbox_max[2]);
        printf("size            %.10g x %.10g x %.10g\n", total->bbox_max[0] - total->bbox_min[0],
               total->bbox_max[1] - total->bbox_min[1], total->bbox_max[2] - total->bbox_min[2]);
    }
    if (m->n_parts == 0) return;
    printf("\n%5s  %-20s %-7s %-8s %-7s %-13s %s\n", "part", "name", "degree", "grid", "trim",
           "area", "entity");
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_part *p = &m->parts[i];
        char deg[32], grid[32], trim[32];
        snprintf(deg, sizeof deg, "%dx%d", p->surface.degree_u, p->surface.degree_v);
        snprintf(grid, sizeof grid, "%dx%d", p->surface.n_u, p->surface.n_v);
        if (p->has_outer || p->n_holes > 0) snprintf(trim, sizeof trim, "yes/%d", p->n_holes);
        else snprintf(trim, sizeof trim, "no");
        printf("%5d  %-20.20s %-7s %-8s %-7s %-13.7g %d\n", i, p->name[0] ? p->name : "-", deg,
               grid, trim, per[i].area, p->source_entity);
    }
}

int cmd_inspect(int argc, char **argv)
{
    const char *path = NULL;
    int json = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--json") == 0) json = 1;
        else if (argv[i][0] == '-' && argv[i][1] != '\0')
            return cli_usage(CMD, "unknown option '%s'", argv[i]);
        else if (path) return cli_usage(CMD, "one FILE only ('%s' and '%s')", path, argv[i]);
        else path = argv[i];
    }
    if (!path) return cli_usage(CMD, "missing FILE");

    sem_error err;
    sem_error_clear(&err);
    sem_model *m = NULL;
    if (sem_model_load(path, &m, &err) != SEM_OK) return cli_fail_error(path, &err);
    cli_print_model_warnings(m);

    sem_part_measure_result *per = calloc((size_t)(m->n_parts > 0 ? m->n_parts : 1), sizeof *per);
    if (!per) {
        sem_model_destroy(m);
        return cli_fail("out of memory");
    }
    sem_part_measure_result total;
    /* a part that cannot be measured (open trim loop) is reported, not fatal: inspect is
     * how one finds such parts */
    char *measure_warning = NULL;
    if (sem_model_measure(m, per, &total, &err) != SEM_OK) {
        cli_warn("%s: %s", path, err.message);
        measure_warning = err.message;
    }
    int rc = CLI_OK;
    if (json) rc = cli_print_json(inspect_json(path, m, per, &total, measure_warning));
    else inspect_text(path, m, per, &total);
    free(per);
    sem_model_destroy(m);
    return rc;
}
