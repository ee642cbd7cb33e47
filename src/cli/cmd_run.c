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

static void mkdirs(const char *path)
{
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; ++p)
        if (*p == '/') {
            *p = '\0';
            mkdir(tmp, 0777);
            *p = '/';
        }
    mkdir(tmp, 0777);
}

/* Preprocesses or loads from the cache. *cached tells which. */
static sem_status preprocess_cached(const sem_model *model, const sem_preprocess_options *opt, int use_cache,
                                    sem_discretization **out, int *cached, sem_error *err)
{
    *cached = 0;
    unsigned long long hash = sem_preprocess_hash(model, opt);
    char dir[4096], path[4200];
    cache_dir(dir, sizeof dir);
    snprintf(path, sizeof path, "%s/%016llx.semdisc", dir, hash);
    if (use_cache) {
        sem_error e;
        if (sem_discretization_load(path, hash, out, &e) == SEM_OK) {
            *cached = 1;
            return SEM_OK;
        }
    }
    sem_status st = sem_preprocess(model, opt, out, err);
    if (st != SEM_OK) return st;
    if (use_cache) {
        mkdirs(dir);
        sem_error e;
        if (sem_discretization_save(*out, path, &e) != SEM_OK) cli_warn("cannot write the cache: %s", e.message);
    }
    return SEM_OK;
}

static cJSON *vec3(const double v[3])
{
    return cJSON_CreateDoubleArray(v, 3);
}

typedef struct run_state {
    sem_scene *scene;
    int n;
    sem_model **models;
    sem_discretization **discs;
    unsigned char **pins;
    int **part_mat;
    int **presc_group;
    sem_prescribe **prescs;
    sem_material **mats;
    sem_world *world;
    sem_animation *anim;
    cJSON *frames;
    int steps;
    double step_sum, step_max, factor_sum;
    int cached_all;
    double preprocess_s;
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
        cJSON_AddNumberToObject(o, "parts", r->models[i]->n_parts);
        cJSON_AddNumberToObject(o, "quadrature_points", r->discs[i]->n_quad);
        cJSON_AddStringToObject(o, "solver", sem_world_solver_name(r->world, i));
        cJSON_AddNumberToObject(o, "nnz_percent", sem_world_object_nnz_percent(r->world, i));
        cJSON_AddItemToArray(objs, o);
    }
    cJSON_AddStringToObject(s, "status", status);
    if (error) cJSON_AddStringToObject(s, "error", error);
    cJSON_AddNumberToObject(s, "volume", volume);
    cJSON_AddNumberToObject(s, "mass", mass);
    cJSON_AddNumberToObject(s, "dofs", dofs);
    cJSON_AddNumberToObject(s, "steps", r->steps);
    cJSON_AddNumberToObject(s, "dt", r->scene->world.dt);
    cJSON_AddNumberToObject(s, "mean_step_s", r->steps ? r->step_sum / r->steps : 0.0);
    cJSON_AddNumberToObject(s, "max_step_s", r->step_max);
    cJSON_AddNumberToObject(s, "mean_factor_s", r->steps ? r->factor_sum / r->steps : 0.0);
    cJSON_AddNumberToObject(s, "preprocess_s", r->preprocess_s);
    cJSON_AddBoolToObject(s, "preprocess_cached", r->cached_all);
    cJSON_AddStringToObject(s, "output_dir", r->scene->output_dir);
    if (r->anim && r->scene->write_usd) cJSON_AddStringToObject(s, "usd", sem_animation_usd_path(r->anim));
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
    sem_world_destroy(r->world);
    for (int i = 0; i < r->n; ++i) {
        if (r->discs) sem_discretization_destroy(r->discs[i]);
        if (r->models) sem_model_destroy(r->models[i]);
        if (r->pins) free(r->pins[i]);
        if (r->part_mat) free(r->part_mat[i]);
        if (r->presc_group) free(r->presc_group[i]);
        if (r->prescs) free(r->prescs[i]);
        if (r->mats) free(r->mats[i]);
    }
    free(r->models);
    free(r->discs);
    free(r->pins);
    free(r->part_mat);
    free(r->presc_group);
    free(r->prescs);
    free(r->mats);
    cJSON_Delete(r->frames);
    sem_scene_destroy(r->scene);
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
    if (!scene_path && !quiet) fprintf(stderr, "sem: no scene given; running the embedded default scene (%s)\n", "rubber beam clamped at x = 0");
    r.n = r.scene->n_objects;
    r.models = calloc((size_t)r.n, sizeof *r.models);
    r.discs = calloc((size_t)r.n, sizeof *r.discs);
    r.pins = calloc((size_t)r.n, sizeof *r.pins);
    r.part_mat = calloc((size_t)r.n, sizeof *r.part_mat);
    r.presc_group = calloc((size_t)r.n, sizeof *r.presc_group);
    r.prescs = calloc((size_t)r.n, sizeof *r.prescs);
    r.mats = calloc((size_t)r.n, sizeof *r.mats);
    r.frames = cJSON_CreateArray();
    int rc = CLI_FAILED;
    if (!r.models || !r.discs || !r.pins || !r.part_mat || !r.mats || !r.presc_group || !r.prescs || !r.frames) {
        cli_fail("out of memory");
        goto done;
    }
    r.world = sem_world_create(&r.scene->world, &err);
    if (!r.world) {
        cli_fail_error(r.scene->path, &err);
        goto done;
    }
    r.cached_all = 1;
    double t_pre = omp_get_wtime();
    for (int i = 0; i < r.n; ++i) {
        if ((st = sem_scene_object_model(r.scene, i, &r.models[i], &err)) != SEM_OK) {
            cli_fail_error(NULL, &err);
            goto done;
        }
        cli_print_model_warnings(r.models[i]);
        if (!quiet) fprintf(stderr, "sem: object %d: %d parts, %zu dofs; preprocessing...\n", i, r.models[i]->n_parts, 3 * sem_model_control_points(r.models[i]));
        int cached = 0;
        if ((st = preprocess_cached(r.models[i], &r.scene->objects[i].sem, use_cache, &r.discs[i], &cached, &err)) != SEM_OK) {
            cli_fail("%s: objects[%d]: %s", r.scene->path[0] ? r.scene->path : "default scene", i, err.message);
            goto done;
        }
        r.cached_all &= cached;
        if (!quiet)
            fprintf(stderr, "sem: object %d: %s: %d quadrature points, volume %.6g\n", i,
                    cached ? "preprocessed data reused from the cache" : "preprocessed", r.discs[i]->n_quad,
                    r.discs[i]->volume);
        const sem_scene_object *so = &r.scene->objects[i];
        if ((st = sem_scene_object_pins(so, r.models[i], &r.pins[i], &err)) != SEM_OK ||
            (st = sem_scene_object_part_materials(so, r.models[i], &r.part_mat[i], &r.mats[i], &err)) != SEM_OK ||
            (st = sem_scene_object_prescribe_groups(so, r.models[i], &r.presc_group[i], &err)) != SEM_OK) {
            cli_fail("%s: objects[%d].%s", r.scene->path[0] ? r.scene->path : "default scene", i, err.message);
            goto done;
        }
        sem_object_def od = sem_default_object_def();
        od.model = r.models[i];
        od.disc = r.discs[i];
        od.material = so->material;
        od.part_material = r.part_mat[i];
        od.part_materials = r.mats[i];
        od.n_part_materials = so->n_part_materials;
        od.pinned = r.pins[i];
        od.prescribe = so->prescribe;
        if (r.presc_group[i]) {
            r.prescs[i] = malloc((size_t)so->n_prescribe_groups * sizeof(sem_prescribe));
            if (!r.prescs[i]) {
                cli_fail("out of memory");
                goto done;
            }
            for (int g = 0; g < so->n_prescribe_groups; ++g) r.prescs[i][g] = so->prescribe_groups[g].prescribe;
            od.prescribe_group = r.presc_group[i];
            od.prescribes = r.prescs[i];
            od.n_prescribes = so->n_prescribe_groups;
        }
        memcpy(od.initial_velocity, so->initial_velocity, sizeof od.initial_velocity);
        memcpy(od.initial_angular_velocity, so->initial_angular_velocity, sizeof od.initial_angular_velocity);
        od.point_loads = so->point_loads;
        od.n_point_loads = so->n_point_loads;
        od.region_loads = so->region_loads;
        od.n_region_loads = so->n_region_loads;
        if (sem_world_add_object(r.world, &od, &err) < 0) {
            cli_fail("%s: objects[%d]: %s", r.scene->path[0] ? r.scene->path : "default scene", i, err.message);
            goto done;
        }
    }
    r.preprocess_s = omp_get_wtime() - t_pre;
    sem_animation_def ad;
    memset(&ad, 0, sizeof ad);
    ad.dir = r.scene->output_dir;
    ad.write_iges = r.scene->write_iges;
    ad.write_obj = r.scene->write_obj;
    ad.write_mesh = r.scene->write_mesh;
    ad.write_usd = r.scene->write_usd;
    ad.mesh_resolution = r.scene->mesh_resolution;
    ad.frames_per_second = 1.0 / (r.scene->world.dt * r.scene->steps_per_frame);
    if (sem_animation_create(&ad, r.n, (const sem_model *const *)r.models, &r.anim, &err) != SEM_OK) {
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
                "Universal Scene Description, or usdview), summary.json\n",
                r.scene->output_dir);
    }
    rc = CLI_OK;
done:
    run_free(&r);
    return rc;
}
