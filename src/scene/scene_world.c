/*
 * scene_world.c - a scene turned into a world (see sem/scene.h).
 *
 * For every object of a scene: load or generate its model and apply its transform,
 * preprocess it (or reuse a discretization cached under its hash, sem_preprocess_hash),
 * resolve its pins, part materials and prescribed groups against the model, and add it to
 * a world made from the scene's world settings. Everything the world points into (models,
 * discretizations, pin flags, material tables) is owned here and lives as long as the
 * world, so any program - the command line, a viewer, a binding - runs a scene the same way.
 * Every object is preprocessed before any is added to the world, so that the run's memory
 * can be estimated (and a run too large for the machine announced) before the world
 * allocates the matrices (sem_world_estimate_memory).
 *
 * The cache folder is a setting (the command line picks it from the environment); nothing
 * here reads the environment or prints: information and warnings go to the log callback.
 */
#include <math.h>
#include <omp.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sem/cache.h"
#include "sem/refine.h"
#include "sem/scene.h"
#include "sem/tessellate.h"
#include "util/free_all.h"

struct sem_scene_world {
    const sem_scene *scene;
    int n;
    sem_model **models;
    sem_patches *patches;      /* per object: sem.resolution's cut (model NULL: none) */
    sem_discretization **discs;
    unsigned char **pins;
    int **part_material;
    int **prescribe_group;
    sem_prescribe **prescribes;
    sem_material **materials;
    double *file_unit_to_meter;
    char (*file_units)[16];
    sem_world *world;
    int *spurious;             /* per object: zero-energy modes, -1 not looked for */
    int all_cached;
    double preprocess_s;
    double estimated_memory;   /* bytes (sem_scene_world_estimated_memory) */
};

sem_scene_world_options sem_default_scene_world_options(void)
{
    sem_scene_world_options o;
    memset(&o, 0, sizeof o);
    o.cache_max_bytes = SEM_CACHE_DEFAULT_MAX_BYTES;
    return o;
}

static void logf_(const sem_scene_world_options *o, int level, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void logf_(const sem_scene_world_options *o, int level, const char *fmt, ...)
{
    if (!o->log) return;
    char msg[1200];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    o->log(o->log_user, level, msg);
}

/* Prefixes err's message with "NAME: objects[I]SEP" (copied first: the message is both the
 * source and the destination). */
static sem_status prefix_error(sem_error *err, sem_status st, const char *name, int i,
                               const char *sep)
{
    if (!err) return st;
    char msg[sizeof err->message];
    snprintf(msg, sizeof msg, "%s", err->message);
    return sem_error_set(err, st, "%s: objects[%d]%s%s", name, i, sep, msg);
}

/* The scene's world settings. Contact: the structured solver takes no contact terms yet
 * (point_terms.h), so a scene where contact can happen (colliders, two objects or more, or
 * self-contact asked for) keeps the q-space solvers. */
static sem_world_def scene_world_def(const sem_scene *scene)
{
    sem_world_def d = scene->world;
    if (!d.contact.disabled && (scene->n_colliders > 0 || scene->n_objects >= 2 || d.contact.self > 0))
        d.advanced.q_space_solvers = 1;
    return d;
}

/* Preprocesses, or loads from the cache; *cached tells which. */
static sem_status preprocess_cached(const sem_model *model, const sem_preprocess_options *opt,
                                    const sem_scene_world_options *o, sem_discretization **out,
                                    int *cached, sem_error *err)
{
    *cached = 0;
    int have_dir = o->cache_dir && o->cache_dir[0];
    if (have_dir && o->read_cache) {
        sem_error e;
        if (sem_cache_load(o->cache_dir, model, opt, out, &e) == SEM_OK) {
            *cached = 1;
            return SEM_OK;
        }
    }
    sem_status st = sem_preprocess(model, opt, out, err);
    if (st != SEM_OK) return st;
    if (have_dir && o->write_cache) {
        sem_error e;
        if (sem_cache_store(o->cache_dir, o->cache_max_bytes, model, opt, *out, &e) != SEM_OK)
            logf_(o, 1, "cannot write the cache: %s", e.message);
    }
    return SEM_OK;
}

void sem_scene_world_destroy(sem_scene_world *sw)
{
    if (!sw) return;
    sem_world_destroy(sw->world);
    for (int i = 0; i < sw->n; ++i) {
        if (sw->discs) sem_discretization_destroy(sw->discs[i]);
        if (sw->models) sem_model_destroy(sw->models[i]);
        if (sw->patches) {
            sw->patches[i].model = NULL; /* owned by models[i] */
            sem_patches_free(&sw->patches[i]);
        }
        if (sw->pins) free(sw->pins[i]);
        if (sw->part_material) free(sw->part_material[i]);
        if (sw->prescribe_group) free(sw->prescribe_group[i]);
        if (sw->prescribes) free(sw->prescribes[i]);
        if (sw->materials) free(sw->materials[i]);
    }
    SEM_FREE_ALL(sw->models, sw->patches, sw->discs, sw->pins, sw->part_material, sw->prescribe_group, sw->prescribes,
                 sw->materials, sw->file_unit_to_meter, sw->file_units, sw->spurious);
    free(sw);
}

/* The parts with marks[k] != 0 for a warning, "k (name)" after ", ", the first 12 of them
 * (*listed; *more are left out) into parts; returns the length written. with_counts: each
 * also says how many of the part's control points marks[k] counts ("k (name; c of its n)"). */
static size_t list_parts(const sem_model *model, const int *marks, int with_counts, char *parts, size_t size,
                         int *listed, int *more)
{
    size_t len = 0;
    parts[0] = '\0';
    *listed = *more = 0;
    for (int k = 0; k < model->n_parts; ++k) {
        if (!marks[k]) continue;
        if (*listed == 12) {
            (*more)++;
            continue;
        }
        const char *nm = model->parts[k].name, *sep = *listed ? ", " : "";
        int of = model->parts[k].surface.n_u * model->parts[k].surface.n_v, w;
        if (with_counts)
            w = nm[0] ? snprintf(parts + len, size - len, "%s%d (%s; %d of its %d)", sep, k, nm, marks[k], of)
                      : snprintf(parts + len, size - len, "%s%d (%d of its %d)", sep, k, marks[k], of);
        else
            w = nm[0] ? snprintf(parts + len, size - len, "%s%d (%s)", sep, k, nm)
                      : snprintf(parts + len, size - len, "%s%d", sep, k);
        if (w > 0 && (size_t)w < size - len) len += (size_t)w;
        (*listed)++;
    }
    return len;
}

/* Control points the boundary samples do not determine (sem_world_object_tied_points): one
 * warning per object naming the parts, so that a face kept untrimmed or trimmed to a sliver
 * of its surface is seen; the run goes on with them tied to their parts' fits. */
static void warn_tied_points(sem_scene_world *sw, int i, int id, const sem_scene_world_options *o)
{
    const sem_model *model = sw->models[i];
    int *counts = calloc((size_t)model->n_parts + 1, sizeof *counts);
    if (!counts) return;
    int total = sem_world_object_tied_points(sw->world, id, counts);
    if (total > 0) {
        char parts[600];
        int listed, more;
        size_t len = list_parts(model, counts, 1, parts, sizeof parts, &listed, &more);
        if (more) snprintf(parts + len, sizeof parts - len, " and %d more part%s", more, more == 1 ? "" : "s");
        logf_(o, 1,
              "objects[%d]: %d control point%s seen by no boundary sample (outside the part's trim or "
              "parameter range), tied to %s part's polynomial fit: part%s %s",
              i, total, total == 1 ? " is" : "s are", total == 1 ? "its" : "their", listed + more == 1 ? "" : "s",
              parts);
    }
    free(counts);
}

/* Zero-energy modes of object i: a warning naming the parts that are not held. */
static sem_status check_modes(sem_scene_world *sw, int i, int id, const sem_scene_world_options *o,
                              sem_error *err)
{
    const sem_model *model = sw->models[i];
    int *flags = calloc((size_t)model->n_parts + 1, sizeof *flags);
    if (!flags) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_object_modes m;
    sem_status st = sem_world_object_modes(sw->world, id, &m, flags, err);
    if (st != SEM_OK) {
        free(flags);
        return prefix_error(err, st, sw->scene->path[0] ? sw->scene->path : "scene", i, ": zero-energy modes: ");
    }
    sw->spurious[i] = m.spurious;
    if (m.spurious > 0) {
        char parts[600];
        int listed, more;
        size_t len = list_parts(model, flags, 0, parts, sizeof parts, &listed, &more);
        if (more) snprintf(parts + len, sizeof parts - len, " and %d more", more);
        logf_(o, 1,
              "objects[%d]: %s%d zero-energy mode%s beyond the rigid motions: part%s %s %s not held by the "
              "discretization and may drift or fall off (raise sem.blend or refine sem.spacing)",
              i, m.spurious == m.n_values ? "at least " : "", m.spurious, m.spurious == 1 ? "" : "s",
              listed + more == 1 ? "" : "s", parts, listed + more == 1 ? "is" : "are");
    } else {
        logf_(o, 0, "objects[%d]: no zero-energy modes (lowest elastic mode %.3g E / (rho L^2))%s", i,
              m.n_values > 0 ? m.values[0] : 0.0, m.converged ? "" : " (iteration not converged)");
    }
    free(flags);
    return SEM_OK;
}

/* sem.resolution: object i's model cut into patches of at most L / resolution (L the
 * diagonal of its tessellation's box, which follows the trims), which the world simulates;
 * the patches keep the file's parts for the frames (sem_scene_world_output_model). */
static sem_status cut_patches(sem_scene_world *sw, int i, const sem_scene_world_options *o, sem_error *err)
{
    const sem_scene_object *so = &sw->scene->objects[i];
    sem_mesh mesh;
    memset(&mesh, 0, sizeof mesh);
    sem_status st = sem_mesh_from_model(sw->models[i], 2, &mesh, err);
    if (st != SEM_OK) return st;
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int v = 0; v < mesh.n_vertices; ++v)
        for (int k = 0; k < 3; ++k) {
            lo[k] = fmin(lo[k], mesh.positions[3 * v + k]);
            hi[k] = fmax(hi[k], mesh.positions[3 * v + k]);
        }
    sem_mesh_free(&mesh);
    double L = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) + (hi[2] - lo[2]) * (hi[2] - lo[2]));
    if (!(L > 0)) return SEM_OK;
    double size = L / so->resolution;
    if ((st = sem_model_patches(sw->models[i], size, &sw->patches[i], err)) != SEM_OK) return st;
    int parts = sw->models[i]->n_parts;
    sem_model_destroy(sw->models[i]);
    sw->models[i] = sw->patches[i].model;
    logf_(o, 0, "object %d: %d parts cut into %d patches of at most %.3g m (sem.resolution %g)", i, parts,
          sw->models[i]->n_parts, size, so->resolution);
    return SEM_OK;
}

/* Loads object i's model and preprocesses it (or reads the cache). */
static sem_status prepare_object(sem_scene_world *sw, int i, const sem_scene_world_options *o,
                                 sem_error *err)
{
    const sem_scene *scene = sw->scene;
    const char *name = scene->path[0] ? scene->path : "default scene";
    const sem_scene_object *so = &scene->objects[i];
    sem_status st = sem_scene_object_model_units(scene, i, &sw->models[i],
                                                 &sw->file_unit_to_meter[i], sw->file_units[i], err);
    if (st != SEM_OK) return st;
    const sem_model *model = sw->models[i];
    for (int k = 0; k < model->n_warnings; ++k)
        if (model->warnings[k]) logf_(o, 1, "%s", model->warnings[k]);
    if (sw->file_unit_to_meter[i] != 1.0)
        logf_(o, 0, "object %d: model file in %s: simulated in metres (x %g), frames written in %s",
              i, sw->file_units[i], sw->file_unit_to_meter[i], sw->file_units[i]);
    if (so->resolution > 0) {
        if ((st = cut_patches(sw, i, o, err)) != SEM_OK) return prefix_error(err, st, name, i, ".sem.resolution: ");
        model = sw->models[i];
    }
    logf_(o, 0, "object %d: %d parts, %zu dofs; preprocessing...", i, model->n_parts,
          3 * sem_model_control_points(model));
    int cached = 0;
    /* the q-space operators only for the solvers that use them */
    sem_preprocess_options popt = so->sem;
    sem_world_def wdef = scene_world_def(scene);
    popt.q_space_operators = !sem_world_def_structured(&wdef, sem_model_control_points(model),
                                                       model->n_parts, popt.order == 1 ? 4 : 10,
                                                       sem_preprocess_shared_fit(model, &popt));
    st = preprocess_cached(model, &popt, o, &sw->discs[i], &cached, err);
    if (st != SEM_OK) return prefix_error(err, st, name, i, ": ");
    sw->all_cached &= cached;
    logf_(o, 0, "object %d: %s: %d quadrature points, volume %.6g", i,
          cached ? "preprocessed data reused from the cache" : "preprocessed", sw->discs[i]->n_quad,
          sw->discs[i]->volume);
    const sem_discretization *d = sw->discs[i];
    for (int k = 0; d->part_covered && k < d->n_parts; ++k)
        if (d->part_covered[k])
            logf_(o, 1,
                  "objects[%d]: part %d%s%s%s is too small or thin for the volume quadrature: it has no volume "
                  "of its own and moves with the points nearest it (a smaller sem.spacing gives it its own)",
                  i, k, model->parts[k].name[0] ? " (" : "", model->parts[k].name,
                  model->parts[k].name[0] ? ")" : "");
    return SEM_OK;
}

/* The run's estimated peak memory (sem_scene_world_estimated_memory), and the warning when
 * it exceeds what the machine has: before the world allocates the objects' matrices, which
 * is where a run that does not fit would be killed. */
static sem_status check_memory(sem_scene_world *sw, const sem_scene_world_options *o, sem_error *err)
{
    double base = 0, kept = 0, largest_transient = 0;
    for (int i = 0; i < sw->n; ++i) {
        sem_memory_estimate e;
        sem_status st = sem_world_estimate_memory(sw->discs[i], &e, err);
        if (st != SEM_OK) return st;
        base = e.base;
        /* what stays until the end, and the largest of what the preprocessing holds only
         * while it runs: objects are preprocessed one after the other */
        double run = e.blocks + e.assembly + e.solver;
        kept += e.discretization + run;
        if (e.preprocessing - run > largest_transient) largest_transient = e.preprocessing - run;
    }
    sw->estimated_memory = base + kept + largest_transient;
    const double gb = 1024.0 * 1024.0 * 1024.0;
    if (o->memory_available > 0 && sw->estimated_memory > o->memory_available)
        logf_(o, 1, "this run needs about %.3g GB and the machine has %.3g GB available",
              sw->estimated_memory / gb, o->memory_available / gb);
    return SEM_OK;
}

/* Part indices of the file (n_file parts) in a selection, as the patches cut from them:
 * *out (caller frees) lists every patch whose parent is listed. */
static sem_status patch_list(const sem_patches *p, int n_file, const int *parts, int n, const char *what, int **out,
                             int *n_out, sem_error *err)
{
    *out = NULL;
    *n_out = 0;
    if (n == 0) return SEM_OK;
    for (int k = 0; k < n; ++k)
        if (parts[k] < 0 || parts[k] >= n_file)
            return sem_error_set(err, SEM_ERR_INVALID, "%s: part %d does not exist (model has %d parts)", what, parts[k],
                                 n_file);
    int np = p->model->n_parts;
    *out = malloc(((size_t)np + 1) * sizeof **out);
    if (!*out) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int j = 0; j < np; ++j)
        for (int k = 0; k < n; ++k)
            if (p->part_parent[j] == parts[k]) {
                (*out)[(*n_out)++] = j;
                break;
            }
    return SEM_OK;
}

/* The scene object with its part selections (pin.parts, part_materials by index, prescribe
 * groups' parts) turned into the patches of sem.resolution; control point indices refer to
 * the file's points, which the patches refine, and are refused. release() frees it. */
typedef struct patched_object {
    sem_scene_object o;
    int *pin_parts;
    sem_scene_part_material *part_materials;
    sem_scene_prescribe_group *groups;
    int **group_parts;
} patched_object;

static void release(patched_object *po)
{
    free(po->pin_parts);
    free(po->part_materials);
    for (int g = 0; po->group_parts && g < po->o.n_prescribe_groups; ++g) free(po->group_parts[g]);
    free(po->group_parts);
    free(po->groups);
}

static sem_status patch_object(const sem_scene_object *so, const sem_patches *p, int n_file, patched_object *po,
                               sem_error *err)
{
    memset(po, 0, sizeof *po);
    po->o = *so;
    int points = so->n_pin_points > 0;
    for (int g = 0; g < so->n_prescribe_groups; ++g) points |= so->prescribe_groups[g].n_points > 0;
    if (points)
        return sem_error_set(err, SEM_ERR_INVALID,
                             "pin.points selects control points of the file, which sem.resolution refines: "
                             "select by box or parts instead");
    sem_status st = patch_list(p, n_file, so->pin_parts, so->n_pin_parts, "pin.parts", &po->pin_parts,
                               &po->o.n_pin_parts, err);
    if (st != SEM_OK) return st;
    po->o.pin_parts = po->pin_parts;
    if (so->n_part_materials > 0) {
        int np = p->model->n_parts, n = 0;
        po->part_materials = malloc(((size_t)so->n_part_materials * (size_t)np + 1) * sizeof *po->part_materials);
        if (!po->part_materials) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int k = 0; k < so->n_part_materials; ++k) {
            const sem_scene_part_material *pm = &so->part_materials[k];
            if (pm->part < 0) { /* by name: the patches keep their part's name */
                po->part_materials[n++] = *pm;
                continue;
            }
            if (pm->part >= n_file)
                return sem_error_set(err, SEM_ERR_INVALID, "part_materials: part %d does not exist (model has %d parts)",
                                     pm->part, n_file);
            for (int j = 0; j < np; ++j)
                if (p->part_parent[j] == pm->part) {
                    po->part_materials[n] = *pm;
                    po->part_materials[n++].part = j;
                }
        }
        po->o.part_materials = po->part_materials;
        po->o.n_part_materials = n;
    }
    if (so->n_prescribe_groups > 0) {
        po->groups = malloc((size_t)so->n_prescribe_groups * sizeof *po->groups);
        po->group_parts = calloc((size_t)so->n_prescribe_groups, sizeof *po->group_parts);
        if (!po->groups || !po->group_parts) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        for (int g = 0; g < so->n_prescribe_groups; ++g) {
            po->groups[g] = so->prescribe_groups[g];
            char what[64];
            snprintf(what, sizeof what, "prescribe[%d].pin.parts", g);
            st = patch_list(p, n_file, so->prescribe_groups[g].parts, so->prescribe_groups[g].n_parts, what,
                            &po->group_parts[g], &po->groups[g].n_parts, err);
            if (st != SEM_OK) return st;
            po->groups[g].parts = po->group_parts[g];
        }
        po->o.prescribe_groups = po->groups;
    }
    return SEM_OK;
}

/* Whether any of the discretization's material points - quadrature points, boundary samples -
 * lies in box at rest (what a material pin holds, sem_pin_region). */
static int material_in_box(const sem_discretization *d, const double b[6])
{
    for (int t = 0; t < 2; ++t) {
        const double *X = t ? d->sample_X : d->quad_X;
        int n = t ? d->n_samples : d->n_quad;
        for (int k = 0; k < n; ++k, X += 3)
            if (X[0] >= b[0] && X[1] >= b[1] && X[2] >= b[2] && X[0] <= b[3] && X[1] <= b[4] && X[2] <= b[5])
                return 1;
    }
    return 0;
}

/* The object's material pins (sem_scene_object_pin_regions), each checked to hold some
 * material, so that the error names its key. */
static sem_status pin_regions(const sem_scene_object *so, const sem_discretization *d, sem_pin_region **out, int *n,
                              sem_error *err)
{
    sem_status st = sem_scene_object_pin_regions(so, out, n, err);
    if (st != SEM_OK) return st;
    int r = 0;
    for (int g = -1; g < so->n_prescribe_groups; ++g) {
        if (!(g < 0 ? so->has_pin_box : so->prescribe_groups[g].has_box)) continue;
        double b[6];
        memcpy(b, (*out)[r++].box, sizeof b);
        if (material_in_box(d, b)) continue;
        char key[64];
        if (g < 0)
            snprintf(key, sizeof key, "pin.box");
        else
            snprintf(key, sizeof key, "prescribe[%d].pin.box", g);
        free(*out);
        *out = NULL;
        *n = 0;
        return sem_error_set(err, SEM_ERR_INVALID,
                             "%s: [[%g, %g, %g], [%g, %g, %g]] holds none of the model's material (no quadrature "
                             "point or boundary sample lies in it, after its transform)",
                             key, b[0], b[1], b[2], b[3], b[4], b[5]);
    }
    return SEM_OK;
}

/* Adds object i (preprocessed by prepare_object) to the world. */
static sem_status add_object(sem_scene_world *sw, int i, const sem_scene_world_options *o,
                             sem_error *err)
{
    const sem_scene *scene = sw->scene;
    const char *name = scene->path[0] ? scene->path : "default scene";
    const sem_scene_object *so = &scene->objects[i];
    const sem_model *model = sw->models[i];
    sem_status st;
    patched_object po;
    memset(&po, 0, sizeof po);
    if (sw->patches[i].refined) {
        if ((st = patch_object(so, &sw->patches[i], sw->patches[i].refined->n_parts, &po, err)) != SEM_OK) {
            release(&po);
            return prefix_error(err, st, name, i, ".");
        }
        so = &po.o;
    }
    sem_pin_region *regions = NULL;
    int n_regions = 0;
    if ((st = sem_scene_object_pins(so, model, &sw->pins[i], err)) != SEM_OK ||
        (st = pin_regions(so, sw->discs[i], &regions, &n_regions, err)) != SEM_OK ||
        (st = sem_scene_object_part_materials(so, model, &sw->part_material[i], &sw->materials[i],
                                              err)) != SEM_OK ||
        (st = sem_scene_object_prescribe_groups(so, model, &sw->prescribe_group[i], err)) != SEM_OK) {
        free(regions);
        release(&po);
        return prefix_error(err, st, name, i, ".");
    }

    sem_object_def od = sem_default_object_def();
    od.model = model;
    od.disc = sw->discs[i];
    od.material = so->material;
    od.blend = so->blend;
    od.seam_ties = so->seam_ties;
    od.seams = so->seams;
    od.weld = so->weld >= 0 ? so->weld : so->resolution > 0;
    od.part_material = sw->part_material[i];
    od.part_materials = sw->materials[i];
    od.n_part_materials = so->n_part_materials;
    od.pinned = sw->pins[i];
    od.prescribe = so->prescribe;
    if (sw->prescribe_group[i]) {
        sw->prescribes[i] = malloc((size_t)so->n_prescribe_groups * sizeof(sem_prescribe));
        if (!sw->prescribes[i]) {
            free(regions);
            release(&po);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        for (int g = 0; g < so->n_prescribe_groups; ++g)
            sw->prescribes[i][g] = so->prescribe_groups[g].prescribe;
        od.prescribe_group = sw->prescribe_group[i];
        od.prescribes = sw->prescribes[i];
        od.n_prescribes = so->n_prescribe_groups;
    }
    memcpy(od.initial_velocity, so->initial_velocity, sizeof od.initial_velocity);
    memcpy(od.initial_angular_velocity, so->initial_angular_velocity,
           sizeof od.initial_angular_velocity);
    od.point_loads = so->point_loads;
    od.n_point_loads = so->n_point_loads;
    od.region_loads = so->region_loads;
    od.n_region_loads = so->n_region_loads;
    od.friction = so->friction;
    od.pin_regions = regions; /* copied by the world */
    od.n_pin_regions = n_regions;
    int id = sem_world_add_object(sw->world, &od, err);
    free(regions);
    release(&po);
    if (id < 0) return prefix_error(err, err ? err->status : SEM_ERR_INVALID, name, i, ": ");
    warn_tied_points(sw, i, id, o);
    return o->skip_modes ? SEM_OK : check_modes(sw, i, id, o, err);
}

/* The scene's collider i into the world. */
static sem_status add_collider(sem_scene_world *sw, int i, sem_error *err)
{
    sem_collider_def def;
    double *vertices = NULL;
    int *triangles = NULL;
    sem_status st = sem_scene_collider_def(sw->scene, i, &def, &vertices, &triangles, err);
    if (st == SEM_OK && sem_world_add_collider(sw->world, &def, err) < 0) {
        st = err ? err->status : SEM_ERR_INVALID;
        if (err) {
            char msg[sizeof err->message];
            snprintf(msg, sizeof msg, "%s", err->message);
            sem_error_set(err, st, "%s: colliders[%d]: %s", sw->scene->path[0] ? sw->scene->path : "scene", i, msg);
        }
    }
    free(vertices);
    free(triangles);
    return st;
}

sem_status sem_scene_world_create(const sem_scene *scene, const sem_scene_world_options *options,
                                  sem_scene_world **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!scene || !out)
        return sem_error_set(err, SEM_ERR_INVALID, "sem_scene_world_create: NULL argument");
    sem_scene_world_options o = options ? *options : sem_default_scene_world_options();
    sem_scene_world *sw = calloc(1, sizeof *sw);
    if (!sw) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sw->scene = scene;
    sw->n = scene->n_objects;
    size_t n = (size_t)(sw->n > 0 ? sw->n : 1);
    sw->models = calloc(n, sizeof *sw->models);
    sw->discs = calloc(n, sizeof *sw->discs);
    sw->pins = calloc(n, sizeof *sw->pins);
    sw->part_material = calloc(n, sizeof *sw->part_material);
    sw->prescribe_group = calloc(n, sizeof *sw->prescribe_group);
    sw->prescribes = calloc(n, sizeof *sw->prescribes);
    sw->materials = calloc(n, sizeof *sw->materials);
    sw->file_unit_to_meter = calloc(n, sizeof *sw->file_unit_to_meter);
    sw->file_units = calloc(n, sizeof *sw->file_units);
    sw->spurious = malloc(n * sizeof *sw->spurious);
    sw->patches = calloc(n, sizeof *sw->patches);
    sem_status st = SEM_OK;
    for (size_t k = 0; sw->spurious && k < n; ++k) sw->spurious[k] = -1;
    if (!sw->models || !sw->discs || !sw->pins || !sw->part_material || !sw->prescribe_group ||
        !sw->prescribes || !sw->materials || !sw->file_unit_to_meter || !sw->file_units || !sw->spurious || !sw->patches) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    sem_world_def wdef = scene_world_def(scene);
    sw->world = sem_world_create(&wdef, err);
    if (!sw->world) {
        st = err ? err->status : SEM_ERR_INVALID;
        if (err && scene->path[0] && !strstr(err->message, scene->path)) {
            char msg[sizeof err->message];
            snprintf(msg, sizeof msg, "%s", err->message);
            sem_error_set(err, st, "%s: %s", scene->path, msg);
        }
        goto fail;
    }
    /* static colliders first: a bad one fails before any preprocessing */
    for (int i = 0; i < scene->n_colliders; ++i)
        if ((st = add_collider(sw, i, err)) != SEM_OK) goto fail;
    sw->all_cached = 1;
    double t0 = omp_get_wtime();
    for (int i = 0; i < sw->n; ++i)
        if ((st = prepare_object(sw, i, &o, err)) != SEM_OK) goto fail;
    sw->preprocess_s = omp_get_wtime() - t0;
    if ((st = check_memory(sw, &o, err)) != SEM_OK) goto fail;
    for (int i = 0; i < sw->n; ++i)
        if ((st = add_object(sw, i, &o, err)) != SEM_OK) goto fail;
    *out = sw;
    return SEM_OK;
fail:
    sem_scene_world_destroy(sw);
    return st;
}

sem_world *sem_scene_world_world(sem_scene_world *sw) { return sw ? sw->world : NULL; }

const sem_scene *sem_scene_world_scene(const sem_scene_world *sw) { return sw ? sw->scene : NULL; }

int sem_scene_world_object_count(const sem_scene_world *sw) { return sw ? sw->n : 0; }

const sem_model *sem_scene_world_model(const sem_scene_world *sw, int object)
{
    return sw && object >= 0 && object < sw->n ? sw->models[object] : NULL;
}

const sem_model *sem_scene_world_output_model(const sem_scene_world *sw, int object)
{
    if (!sw || object < 0 || object >= sw->n) return NULL;
    return sw->patches[object].refined ? sw->patches[object].refined : sw->models[object];
}

void sem_scene_world_output_q(const sem_scene_world *sw, int object, const double *q, double *q_frame)
{
    if (sw->patches[object].refined)
        sem_patches_gather(&sw->patches[object], q, q_frame);
    else
        memcpy(q_frame, q, 3 * sem_model_control_points(sw->models[object]) * sizeof(double));
}

const sem_discretization *sem_scene_world_discretization(const sem_scene_world *sw, int object)
{
    return sw && object >= 0 && object < sw->n ? sw->discs[object] : NULL;
}

const char *sem_scene_world_file_units(const sem_scene_world *sw, int object)
{
    return sw && object >= 0 && object < sw->n ? sw->file_units[object] : "M";
}

double sem_scene_world_file_unit_to_meter(const sem_scene_world *sw, int object)
{
    return sw && object >= 0 && object < sw->n && sw->file_unit_to_meter[object] > 0
               ? sw->file_unit_to_meter[object]
               : 1.0;
}

sem_status sem_scene_world_frame_model(const sem_scene_world *sw, int object, sem_model **out,
                                       sem_error *err)
{
    if (!out) return sem_error_set(err, SEM_ERR_INVALID, "sem_scene_world_frame_model: no output");
    *out = NULL;
    if (!sw || object < 0 || object >= sw->n)
        return sem_error_set(err, SEM_ERR_INVALID, "object %d of a scene world with %d objects", object,
                             sw ? sw->n : 0);
    const sem_model *shown = sem_scene_world_output_model(sw, object);
    sem_model *m = sem_model_clone(shown);
    size_t n = 3 * sem_model_control_points(shown);
    double *x = malloc(n * sizeof *x + 1);
    if (!m || !x) {
        sem_model_destroy(m);
        free(x);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    /* the animation writer's arithmetic (output/animation.c), so the numbers are the frame's */
    const double to_file = 1.0 / sem_scene_world_file_unit_to_meter(sw, object);
    sem_scene_world_output_q(sw, object, sem_world_object_q(sw->world, object), x);
    for (size_t i = 0; i < n; ++i) x[i] *= to_file;
    sem_model_set_q(m, x);
    free(x);
    snprintf(m->units, sizeof m->units, "%s", sem_scene_world_file_units(sw, object));
    m->unit_to_meter = sem_scene_world_file_unit_to_meter(sw, object);
    *out = m;
    return SEM_OK;
}

int sem_scene_world_all_cached(const sem_scene_world *sw) { return sw ? sw->all_cached : 0; }

int sem_scene_world_spurious_modes(const sem_scene_world *sw, int object)
{
    return sw && object >= 0 && object < sw->n ? sw->spurious[object] : -1;
}

double sem_scene_world_preprocess_seconds(const sem_scene_world *sw)
{
    return sw ? sw->preprocess_s : 0.0;
}

double sem_scene_world_estimated_memory(const sem_scene_world *sw)
{
    return sw ? sw->estimated_memory : 0.0;
}
