/*
 * cmd_run.c - `sem run [SCENE] [--frames N] [--out DIR] [--json] [--no-cache]`.
 *
 * Loads a scene (or the embedded default when no SCENE is given), preprocesses every
 * object (reusing a cached discretization keyed by the model's content and the SEM
 * settings), steps the world and writes the animation: per frame the deformed NURBS
 * (IGES, optionally OBJ free-form) and a render mesh, one USD file, and summary.json.
 * If a step fails (NaN, explosion), everything written so far stays on disk, the USD and
 * summary are written with the frames done, and the exit status is 1.
 */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "io/atomic_file.h"
#include "sem/animation.h"
#include "sem/preprocess.h"
#include "sem/scene.h"
#include "sem/simulation.h"

static void cache_dir(char *out, size_t size)
{
    const char *d = getenv("SEM_CACHE_DIR");
    if (d && *d) {
        snprintf(out, size, "%s", d);
        return;
    }
    const char *x = getenv("XDG_CACHE_HOME");
    if (x && *x) {
        snprintf(out, size, "%s/sem", x);
        return;
    }
    const char *h = getenv("HOME");
    snprintf(out, size, "%s/.cache/sem", h && *h ? h : "/tmp");
}

static cJSON *vec3(const double v[3])
{
    return cJSON_CreateDoubleArray(v, 3);
}

typedef struct run_state {
    sem_scene *scene;
    sem_scene_world *sw;
    int n;
    sem_world *world;
    sem_animation *anim;
    cJSON *frames;
    int steps;
    double step_sum, step_max, factor_sum;
} run_state;

static void add_frame_stats(run_state *r, double t)
{
    sem_object_stats tot;
    memset(&tot, 0, sizeof tot);
    for (int i = 0; i < r->n; ++i) {
        sem_object_stats s;
        sem_world_object_stats(r->world, i, &s);
        tot.kinetic_energy += s.kinetic_energy;
        tot.elastic_energy += s.elastic_energy;
        tot.gravity_energy += s.gravity_energy;
        tot.error_energy += s.error_energy;
        for (int k = 0; k < 3; ++k) {
            tot.center_of_mass[k] += s.mass * s.center_of_mass[k];
            tot.linear_momentum[k] += s.linear_momentum[k];
            tot.angular_momentum[k] += s.angular_momentum[k];
        }
        tot.mass += s.mass;
    }
    if (tot.mass > 0)
        for (int k = 0; k < 3; ++k) tot.center_of_mass[k] /= tot.mass;
    cJSON *f = cJSON_CreateObject();
    cJSON_AddNumberToObject(f, "time", t);
    cJSON_AddNumberToObject(f, "kinetic_energy", tot.kinetic_energy);
    cJSON_AddNumberToObject(f, "elastic_energy", tot.elastic_energy);
    cJSON_AddNumberToObject(f, "gravity_energy", tot.gravity_energy);
    cJSON_AddNumberToObject(f, "error_energy", tot.error_energy);
    cJSON_AddItemToObject(f, "center_of_mass", vec3(tot.center_of_mass));
    cJSON_AddItemToObject(f, "linear_momentum", vec3(tot.linear_momentum));
    cJSON_AddItemToObject(f, "angular_momentum", vec3(tot.angular_momentum));
    cJSON_AddItemToArray(r->frames, f);
}

/* What `sem render` needs to know about object i beside its frames (docs/render.md): its
 * preprocessing file and each part's material (-1: the object's own, k: part_materials[k]). */
static void add_render_info(run_state *r, int i, cJSON *o)
{
    char name[64];
    snprintf(name, sizeof name, "preprocess_%d.semdisc", i);
    cJSON_AddStringToObject(o, "preprocess_file", name);
    int *part_material = NULL;
    sem_material *materials = NULL;
    sem_error err;
    const sem_model *model = sem_scene_world_model(r->sw, i);
    if (sem_scene_object_part_materials(&r->scene->objects[i], model, &part_material, &materials, &err) != SEM_OK)
        return;
    cJSON *list = cJSON_AddArrayToObject(o, "part_material");
    for (int p = 0; p < model->n_parts && list; ++p)
        cJSON_AddItemToArray(list, cJSON_CreateNumber(part_material ? part_material[p] : -1));
    free(part_material);
    free(materials);
}

static cJSON *summary(run_state *r, const char *status, const char *error)
{
    cJSON *s = cJSON_CreateObject();
    double volume = 0, mass = 0;
    int dofs = 0;
    cJSON *objs = cJSON_CreateArray();
    for (int i = 0; i < r->n && r->world && i < sem_world_object_count(r->world); ++i) {
        sem_object_stats st;
        sem_world_object_stats(r->world, i, &st);
        volume += st.volume;
        mass += st.mass;
        dofs += sem_world_object_dofs(r->world, i);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddNumberToObject(o, "volume", st.volume);
        cJSON_AddNumberToObject(o, "mass", st.mass);
        cJSON_AddNumberToObject(o, "dofs", sem_world_object_dofs(r->world, i));
        cJSON_AddNumberToObject(o, "parts", sem_scene_world_model(r->sw, i)->n_parts);
        cJSON_AddNumberToObject(o, "quadrature_points", sem_scene_world_discretization(r->sw, i)->n_quad);
        cJSON_AddStringToObject(o, "solver", sem_world_solver_name(r->world, i));
        cJSON_AddNumberToObject(o, "nnz_percent", sem_world_object_nnz_percent(r->world, i));
        cJSON_AddStringToObject(o, "file_units", sem_scene_world_file_units(r->sw, i));
        cJSON_AddNumberToObject(o, "file_unit_to_meter", sem_scene_world_file_unit_to_meter(r->sw, i));
        add_render_info(r, i, o);
        cJSON_AddItemToArray(objs, o);
    }
    cJSON_AddStringToObject(s, "status", status);
    /* every number below is SI (metres, kg, s); frame files are in frame_units */
    cJSON_AddStringToObject(s, "units", "SI (m, kg, s)");
    cJSON_AddStringToObject(s, "frame_units", sem_scene_world_file_units(r->sw, 0));
    cJSON_AddNumberToObject(s, "frame_unit_to_meter", sem_scene_world_file_unit_to_meter(r->sw, 0));
    if (error) cJSON_AddStringToObject(s, "error", error);
    cJSON_AddNumberToObject(s, "volume", volume);
    cJSON_AddNumberToObject(s, "mass", mass);
    cJSON_AddNumberToObject(s, "dofs", dofs);
    cJSON_AddNumberToObject(s, "steps", r->steps);
    cJSON_AddNumberToObject(s, "dt", r->scene->world.dt);
    cJSON_AddNumberToObject(s, "mean_step_s", r->steps ? r->step_sum / r->steps : 0.0);
    cJSON_AddNumberToObject(s, "max_step_s", r->step_max);
    cJSON_AddNumberToObject(s, "mean_factor_s", r->steps ? r->factor_sum / r->steps : 0.0);
    cJSON_AddNumberToObject(s, "preprocess_s", sem_scene_world_preprocess_seconds(r->sw));
    cJSON_AddBoolToObject(s, "preprocess_cached", sem_scene_world_all_cached(r->sw));
    cJSON_AddStringToObject(s, "output_dir", r->scene->output_dir);
    if (r->anim && r->scene->write_usd) cJSON_AddStringToObject(s, "usd", sem_animation_usd_path(r->anim));
    if (r->anim && r->scene->write_glb) cJSON_AddStringToObject(s, "glb", sem_animation_glb_path(r->anim));
    cJSON_AddNumberToObject(s, "frames_per_second", 1.0 / (r->scene->world.dt * r->scene->steps_per_frame));
    cJSON_AddItemToObject(s, "objects", objs);
    cJSON_AddItemReferenceToObject(s, "frames", r->frames);
    return s;
}

static int write_summary(run_state *r, const char *status, const char *error, int print_json)
{
    cJSON *s = summary(r, status, error);
    char *text = cJSON_Print(s);
    int rc = CLI_OK;
    if (text) {
        char path[4200];
        snprintf(path, sizeof path, "%s/summary.json", r->scene->output_dir);
        sem_atomic_file f;
        sem_error err;
        if (sem_atomic_open(&f, path, &err) == SEM_OK) {
            fputs(text, f.fp);
            fputc('\n', f.fp);
            if (sem_atomic_commit(&f, &err) != SEM_OK) rc = cli_fail_error(NULL, &err);
        } else {
            rc = cli_fail_error(NULL, &err);
        }
        if (print_json) printf("%s\n", text);
        free(text);
    }
    cJSON_Delete(s);
    return rc;
}

static void run_free(run_state *r)
{
    sem_animation_destroy(r->anim);
    sem_scene_world_destroy(r->sw);
    cJSON_Delete(r->frames);
    sem_scene_destroy(r->scene);
}

/* Log lines of the scene world: information unless --quiet, warnings always. */
static void run_log(void *user, int level, const char *message)
{
    const int *quiet = user;
    if (level > 0)
        cli_warn("%s", message);
    else if (!*quiet)
        fprintf(stderr, "sem: %s\n", message);
}

/* The world's log: Newton's trace (SEM_DEBUG_NEWTON) on stderr. */
static void world_log(void *user, int level, const char *message)
{
    (void)user;
    (void)level;
    fprintf(stderr, "%s\n", message);
}

int cmd_run(int argc, char **argv)
{
    const char *scene_path = NULL, *out_dir = NULL;
    int frames = -1, json = 0, use_cache = 1, quiet = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else if (!strcmp(argv[i], "--no-cache")) {
            use_cache = 0;
        } else if (!strcmp(argv[i], "--quiet")) {
            quiet = 1;
        } else if (!strcmp(argv[i], "--frames")) {
            if (cli_need_values("run", argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (cli_parse_int("run", "--frames", argv[++i], &frames) != CLI_OK) return CLI_USAGE;
            if (frames < 0) return cli_usage("run", "--frames must be >= 0");
        } else if (!strcmp(argv[i], "--out")) {
            if (cli_need_values("run", argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            out_dir = argv[++i];
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return cli_usage("run", "unknown option %s", argv[i]);
        } else if (!scene_path) {
            scene_path = argv[i];
        } else {
            return cli_usage("run", "more than one scene given");
        }
    }
    run_state r;
    memset(&r, 0, sizeof r);
    sem_error err;
    sem_status st;
    if (scene_path)
        st = sem_scene_load(scene_path, &r.scene, &err);
    else
        st = sem_scene_parse(sem_scene_default_json(), "default scene", ".", &r.scene, &err);
    if (st != SEM_OK) return cli_fail_error(NULL, &err);
    if (frames >= 0) r.scene->frames = frames;
    if (out_dir) snprintf(r.scene->output_dir, sizeof r.scene->output_dir, "%s", out_dir);
    /* the library reads no environment: the command line turns SEM_DEBUG_NEWTON into the
     * world's trace setting */
    const char *trace = getenv("SEM_DEBUG_NEWTON");
    if (trace && *trace && strcmp(trace, "0") != 0) {
        r.scene->world.advanced.trace_newton = 1;
        r.scene->world.log = world_log;
    }
    if (!scene_path && !quiet) fprintf(stderr, "sem: no scene given; running the embedded default scene (%s)\n", "rubber beam clamped at x = 0");
    r.frames = cJSON_CreateArray();
    int rc = CLI_FAILED;
    if (!r.frames) {
        cli_fail("out of memory");
        goto done;
    }
    char cache[4096];
    cache_dir(cache, sizeof cache);
    sem_scene_world_options wo = sem_default_scene_world_options();
    wo.cache_dir = cache;
    wo.read_cache = use_cache;
    wo.write_cache = use_cache;
    wo.log = run_log;
    wo.log_user = &quiet;
    if (sem_scene_world_create(r.scene, &wo, &r.sw, &err) != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    r.n = sem_scene_world_object_count(r.sw);
    r.world = sem_scene_world_world(r.sw);
    const sem_model **models = malloc((size_t)r.n * sizeof *models);
    if (!models) {
        cli_fail("out of memory");
        goto done;
    }
    for (int i = 0; i < r.n; ++i) models[i] = sem_scene_world_model(r.sw, i);
    sem_animation_def ad;
    memset(&ad, 0, sizeof ad);
    ad.dir = r.scene->output_dir;
    ad.write_iges = r.scene->write_iges;
    ad.write_obj = r.scene->write_obj;
    ad.write_mesh = r.scene->write_mesh;
    ad.write_usd = r.scene->write_usd;
    ad.write_glb = r.scene->write_glb;
    ad.mesh_resolution = r.scene->mesh_resolution;
    ad.frames_per_second = 1.0 / (r.scene->world.dt * r.scene->steps_per_frame);
    /* frames in the first object's file units (one unit per frame file) */
    ad.frame_units = sem_scene_world_file_units(r.sw, 0);
    ad.frame_unit_to_meter = sem_scene_world_file_unit_to_meter(r.sw, 0);
    st = sem_animation_create(&ad, r.n, models, &r.anim, &err);
    free(models);
    for (int i = 0; i < r.n && st == SEM_OK; ++i)
        st = sem_animation_write_preprocess(r.anim, i, sem_scene_world_discretization(r.sw, i), &err);
    if (st != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    const double **qs = malloc((size_t)r.n * sizeof *qs);
    if (!qs) {
        cli_fail("out of memory");
        goto done;
    }
    for (int i = 0; i < r.n; ++i) qs[i] = sem_world_object_q(r.world, i);
    if (sem_animation_add_frame(r.anim, 0, qs, &err) != SEM_OK) {
        free(qs);
        cli_fail_error(NULL, &err);
        goto done;
    }
    add_frame_stats(&r, 0.0);
    long total = (long)r.scene->frames * r.scene->steps_per_frame;
    if (!quiet) progress_start("simulating", total);
    double t_run = omp_get_wtime();
    char failure[1100] = "";
    for (int f = 1; f <= r.scene->frames && !failure[0]; ++f) {
        for (int s = 0; s < r.scene->steps_per_frame; ++s) {
            if (sem_world_step(r.world, &err) != SEM_OK) {
                snprintf(failure, sizeof failure, "step %d (t = %g): %s", r.steps + 1,
                         sem_world_time(r.world) + r.scene->world.dt, err.message);
                break;
            }
            double dt = sem_world_last_step_seconds(r.world);
            r.steps++;
            r.step_sum += dt;
            r.factor_sum += sem_world_last_factor_seconds(r.world);
            if (dt > r.step_max) r.step_max = dt;
            if (!quiet) {
                double el = omp_get_wtime() - t_run, rate = r.steps / (el > 0 ? el : 1e-9);
                char extra[128];
                snprintf(extra, sizeof extra, "frame %d/%d, %.1f steps/s, %.0f s left", f, r.scene->frames, rate,
                         (total - r.steps) / rate);
                progress_update(r.steps, extra);
            }
        }
        if (failure[0]) break;
        if (sem_animation_add_frame(r.anim, f, qs, &err) != SEM_OK) {
            snprintf(failure, sizeof failure, "frame %d: %s", f, err.message);
            break;
        }
        add_frame_stats(&r, sem_world_time(r.world));
    }
    free(qs);
    if (!quiet) progress_finish();
    sem_error ferr;
    if (sem_animation_finish(r.anim, &ferr) != SEM_OK && !failure[0])
        snprintf(failure, sizeof failure, "%s", ferr.message);
    if (write_summary(&r, failure[0] ? "failed" : "ok", failure[0] ? failure : NULL, json) != CLI_OK) goto done;
    if (failure[0]) {
        cli_fail("%s (frames written so far are kept in %s)", failure, r.scene->output_dir);
        goto done;
    }
    if (!quiet && !json) {
        fprintf(stderr, "sem: %d steps, mean %.3g s per step\n", r.steps, r.steps ? r.step_sum / r.steps : 0.0);
        fprintf(stderr,
                "sem: animation written to %s/: frame_NNNN.igs (NURBS for Rhino/Fusion 360), "
                "frame_NNNN_mesh.obj (render meshes), animation.usda (open with Blender: File > Import > "
                "Universal Scene Description, or usdview), animation.glb (glTF: Blender, three.js), summary.json; "
                "to look at it: sem render %s --mp4 %s/anim.mp4, or sem view %s\n",
                r.scene->output_dir, r.scene->output_dir, r.scene->output_dir, r.scene->output_dir);
    }
    rc = CLI_OK;
done:
    run_free(&r);
    return rc;
}
