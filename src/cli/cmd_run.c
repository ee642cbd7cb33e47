/*
 * cmd_run.c - `sem run [SCENE] [--frames N] [--out DIR] [--json] [--no-cache] [--overwrite]
 * [--strict]` and `sem run --resume DIR`.
 *
 * Loads a scene (or the embedded default when no SCENE is given), preprocesses every
 * object (reusing a cached discretization keyed by the model's content and the SEM
 * settings), steps the world and writes the animation: per frame the deformed NURBS
 * (IGES, optionally OBJ free-form) and a render mesh, one USD file, and summary.json.
 *
 * Stopping. After every frame's files, the state the next steps start from (time, q, v,
 * the frame's summary numbers) is written atomically to DIR/state/ (output/run_state.h).
 * Ctrl-C or SIGTERM lets the step in progress finish, drops the steps of the unfinished
 * frame, writes animation.usda and summary.json (status "interrupted") for the frames that
 * exist, and exits with 128 + the signal number (130, 143); a second signal ends the
 * process at once. `--resume DIR` rebuilds the world from the recorded scene, restores the
 * last complete frame's state and continues: the frames, the USD file and the summary
 * numbers are the bits an uninterrupted run writes (timings aside), also after kill -9.
 * If a step fails (NaN, explosion), everything written so far stays on disk, the USD and
 * summary are written with the frames done, and the exit status is 1.
 *
 * Trust. Every frame, each object's checks (sem_world_object_checks: seam openings, the error
 * energy's share, the volume) go into summary.json; the first frame that passes a limit gets
 * a one-line warning naming the object, the parts and the frame, and the run's status is
 * "suspect" instead of "ok". With --strict that frame ends the run as a failure (exit 1,
 * frames kept).
 *
 * A folder that holds another run's files is refused unless --overwrite is given, which
 * first removes exactly those files (frames, animation, preprocess_K.semdisc, summary,
 * state).
 */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "cli.h"
#include "io/atomic_file.h"
#include "io/read_file.h"
#include "output/run_state.h"
#include "sem/animation.h"
#include "sem/limits.h"
#include "sem/preprocess.h"
#include "sem/scene.h"
#include "sem/simulation.h"

/* The signal that asked the run to stop (0: none). Set by the handler, read between steps. */
static volatile sig_atomic_t stop_signal = 0;

static void on_stop_signal(int sig)
{
    stop_signal = sig;
}

/* SIGINT and SIGTERM stop the run after the current step; SA_RESETHAND gives a second one
 * its default effect (the user insists), SA_RESTART keeps file writes from failing with
 * EINTR. */
static void catch_stop_signals(void)
{
    struct sigaction sa;
    memset(&sa, 0, sizeof sa);
    sa.sa_handler = on_stop_signal;
    sigemptyset(&sa.sa_mask);
    sa.sa_flags = SA_RESTART | SA_RESETHAND;
    sigaction(SIGINT, &sa, NULL);
    sigaction(SIGTERM, &sa, NULL);
}

static void release_stop_signals(void)
{
    signal(SIGINT, SIG_DFL);
    signal(SIGTERM, SIG_DFL);
}

static cJSON *vec3(const double v[3])
{
    return cJSON_CreateDoubleArray(v, 3);
}

/* The numbers of one frame in summary.json, in this order in a state file. */
enum { STAT_TIME, STAT_KINETIC, STAT_ELASTIC, STAT_GRAVITY, STAT_ERROR, STAT_COM,
       STAT_LINEAR = STAT_COM + 3, STAT_ANGULAR = STAT_LINEAR + 3, STAT_CONTACTS = STAT_ANGULAR + 3,
       STAT_MIN_GAP, STAT_SELF_CONTACTS, STAT_COUNT };

typedef struct run_state {
    sem_scene *scene;
    sem_scene_world *sw;
    int n;
    sem_world *world;
    sem_animation *anim;
    cJSON *frames;
    long long steps;
    double step_sum, step_max, factor_sum, contact_sum;
    int steps_timed;
    sem_run_info info;
    unsigned long long run_id;
    size_t *dofs; /* doubles in q per object */
    /* what the frames show (sem_scene_world_output_model): per object the world's q, or with
     * sem.resolution the file's parts gathered from the patches into frame_q */
    const double **qs;
    double **frame_q;
    /* the trust checks (sem_world_object_checks) over the frames so far: the worst of each
     * kind, and for each limit passed the first frame and object that passed it */
    double worst_seam, worst_share, worst_volume;
    int suspect;                      /* SEM_SUSPECT_* flags passed so far */
    char suspect_message[SEM_SUSPECT_COUNT][512];     /* per flag bit: the warning of its first frame */
    int strict;                       /* --strict: the first suspect frame fails the run */
} run_state;

/* r->qs for the world's current state (see run_state). */
static const double **frame_points(run_state *r)
{
    for (int i = 0; i < r->n; ++i)
        if (r->frame_q[i]) sem_scene_world_output_q(r->sw, i, sem_world_object_q(r->world, i), r->frame_q[i]);
    return r->qs;
}

static void frame_stats(run_state *r, double t, double *x)
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
    x[STAT_TIME] = t;
    x[STAT_KINETIC] = tot.kinetic_energy;
    x[STAT_ELASTIC] = tot.elastic_energy;
    x[STAT_GRAVITY] = tot.gravity_energy;
    x[STAT_ERROR] = tot.error_energy;
    for (int k = 0; k < 3; ++k) {
        x[STAT_COM + k] = tot.center_of_mass[k];
        x[STAT_LINEAR + k] = tot.linear_momentum[k];
        x[STAT_ANGULAR + k] = tot.angular_momentum[k];
    }
    sem_contact_stats cs;
    sem_world_contact_stats(r->world, &cs);
    x[STAT_CONTACTS] = cs.contacts;
    x[STAT_MIN_GAP] = cs.min_gap;
    x[STAT_SELF_CONTACTS] = cs.self_contacts;
}

/* "part 3 (Face3)" or "part 3" */
static void part_label(const sem_model *m, int part, char *out, size_t size)
{
    if (part >= 0 && part < m->n_parts && m->parts[part].name[0])
        snprintf(out, size, "part %d (%s)", part, m->parts[part].name);
    else
        snprintf(out, size, "part %d", part);
}

/* The trust checks of object i at this frame (sem_world_object_checks) into its frame entry
 * o, and the run's record of the limits passed (docs/scenes.md, "Trust"). */
static void add_object_checks(run_state *r, int i, int frame, cJSON *o)
{
    sem_object_checks c;
    sem_error err;
    if (sem_world_object_checks(r->world, i, &c, &err) != SEM_OK) {
        cJSON_AddStringToObject(o, "checks_error", err.message);
        return;
    }
    cJSON_AddNumberToObject(o, "seam_gap", c.seam_gap_relative);
    if (c.seam_parts[0] >= 0) {
        int parts[2] = {c.seam_parts[0], c.seam_parts[1]};
        cJSON_AddItemToObject(o, "seam_parts", cJSON_CreateIntArray(parts, 2));
    }
    cJSON_AddNumberToObject(o, "error_share", c.error_share);
    cJSON_AddNumberToObject(o, "volume_change", c.volume_change);
    if (c.seam_gap_relative > r->worst_seam) r->worst_seam = c.seam_gap_relative;
    if (c.error_share > r->worst_share) r->worst_share = c.error_share;
    if (fabs(c.volume_change) > fabs(r->worst_volume) || !isfinite(c.volume_change)) r->worst_volume = c.volume_change;
    const sem_model *m = sem_scene_world_model(r->sw, i);
    for (int bit = 0; bit < SEM_SUSPECT_COUNT; ++bit) {
        int flag = 1 << bit;
        if (!(c.suspect & flag) || (r->suspect & flag)) continue;
        r->suspect |= flag;
        char *msg = r->suspect_message[bit];
        size_t size = sizeof r->suspect_message[bit];
        if (flag == SEM_SUSPECT_SEAM) {
            char a[96], b[96];
            part_label(m, c.seam_parts[0], a, sizeof a);
            part_label(m, c.seam_parts[1], b, sizeof b);
            snprintf(msg, size,
                     "object %d, frame %d: the seam between %s and %s opened by %.3g %% of the "
                     "object's size (limit %g %%): its faces are coming apart; the answer is suspect "
                     "(docs/scenes.md, \"When the answer is suspect\")",
                     i, frame, a, b, 100 * c.seam_gap_relative, 100 * SEM_SEAM_GAP_LIMIT);
        } else if (flag == SEM_SUSPECT_ERROR_SHARE) {
            snprintf(msg, size,
                     "object %d, frame %d: the error energy (Eq. 16) is %.3g %% of the energy "
                     "stored (limit %g %%): the polynomials no longer follow the surface; the "
                     "answer is suspect (sem.resolution gives each face more polynomials)",
                     i, frame, 100 * c.error_share, 100 * SEM_ERROR_SHARE_LIMIT);
        } else if (flag == SEM_SUSPECT_PIN) {
            char a[96];
            part_label(m, c.pin_part, a, sizeof a);
            snprintf(msg, size,
                     "object %d: its pin box holds all of %s's polynomial, and %.0f %% of that "
                     "part's material lies outside the box and cannot deform (one polynomial per "
                     "part, Eq. 7): the answer is stiffer than the body; the answer is suspect (pin "
                     "a thin slab at a face, or cut the parts into patches with sem.resolution)",
                     i, a, 100 * c.pin_outside);
        } else {
            snprintf(msg, size,
                     "object %d, frame %d: an element turned inside out (smallest det F %.3g): the "
                     "answer is suspect",
                     i, frame, c.min_det_f);
        }
        cli_warn("%s", msg);
    }
}

static void add_frame_stats(run_state *r, const double *x)
{
    cJSON *f = cJSON_CreateObject();
    cJSON_AddNumberToObject(f, "time", x[STAT_TIME]);
    cJSON_AddNumberToObject(f, "kinetic_energy", x[STAT_KINETIC]);
    cJSON_AddNumberToObject(f, "elastic_energy", x[STAT_ELASTIC]);
    cJSON_AddNumberToObject(f, "gravity_energy", x[STAT_GRAVITY]);
    cJSON_AddNumberToObject(f, "error_energy", x[STAT_ERROR]);
    cJSON_AddItemToObject(f, "center_of_mass", vec3(x + STAT_COM));
    cJSON_AddItemToObject(f, "linear_momentum", vec3(x + STAT_LINEAR));
    cJSON_AddItemToObject(f, "angular_momentum", vec3(x + STAT_ANGULAR));
    cJSON_AddNumberToObject(f, "contacts", x[STAT_CONTACTS]);
    cJSON_AddNumberToObject(f, "self_contacts", x[STAT_SELF_CONTACTS]);
    if (isfinite(x[STAT_MIN_GAP]))
        cJSON_AddNumberToObject(f, "min_gap", x[STAT_MIN_GAP]);
    else
        cJSON_AddNullToObject(f, "min_gap"); /* no surface near any contact point */
    /* per object (the world holds this frame's state, also when a run is resumed) */
    cJSON *objs = cJSON_AddArrayToObject(f, "objects");
    for (int i = 0; i < r->n; ++i) {
        sem_object_stats st;
        sem_world_object_stats(r->world, i, &st);
        cJSON *o = cJSON_CreateObject();
        cJSON_AddItemToObject(o, "center_of_mass", vec3(st.center_of_mass));
        cJSON_AddItemToObject(o, "linear_momentum", vec3(st.linear_momentum));
        cJSON_AddItemToObject(o, "angular_momentum", vec3(st.angular_momentum));
        cJSON_AddNumberToObject(o, "kinetic_energy", st.kinetic_energy);
        add_object_checks(r, i, (int)lround(x[STAT_TIME] / (r->scene->world.dt * r->scene->steps_per_frame)), o);
        cJSON_AddItemToArray(objs, o);
    }
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
    const sem_model *model = sem_scene_world_output_model(r->sw, i);
    if (sem_scene_object_part_materials(&r->scene->objects[i], model, &part_material, &materials, &err) != SEM_OK)
        return;
    cJSON *list = cJSON_AddArrayToObject(o, "part_material");
    for (int p = 0; p < model->n_parts && list; ++p)
        cJSON_AddItemToArray(list, cJSON_CreateNumber(part_material ? part_material[p] : -1));
    free(part_material);
    free(materials);
}

static cJSON *summary(run_state *r, const char *status, const char *error, const char *signal_name)
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
        cJSON_AddNumberToObject(o, "origins", sem_scene_world_discretization(r->sw, i)->n_origins);
        /* one polynomial per part (the paper) or per origin (shared fits, sem_fit_rule) */
        cJSON_AddStringToObject(o, "fits", sem_scene_world_discretization(r->sw, i)->shared_fit ? "origins" : "parts");
        cJSON_AddNumberToObject(o, "nnz_percent", sem_world_object_nnz_percent(r->world, i));
        cJSON_AddNumberToObject(o, "spurious_modes", sem_scene_world_spurious_modes(r->sw, i));
        cJSON_AddStringToObject(o, "file_units", sem_scene_world_file_units(r->sw, i));
        cJSON_AddNumberToObject(o, "file_unit_to_meter", sem_scene_world_file_unit_to_meter(r->sw, i));
        add_render_info(r, i, o);
        cJSON_AddItemToArray(objs, o);
    }
    cJSON_AddStringToObject(s, "status", status);
    /* the trust checks over every frame written (docs/scenes.md, "Trust") */
    cJSON *checks = cJSON_AddObjectToObject(s, "checks");
    cJSON_AddNumberToObject(checks, "seam_gap_max", r->worst_seam);
    cJSON_AddNumberToObject(checks, "seam_gap_limit", SEM_SEAM_GAP_LIMIT);
    cJSON_AddNumberToObject(checks, "error_share_max", r->worst_share);
    cJSON_AddNumberToObject(checks, "error_share_limit", SEM_ERROR_SHARE_LIMIT);
    if (isfinite(r->worst_volume))
        cJSON_AddNumberToObject(checks, "volume_change_max", r->worst_volume);
    else
        cJSON_AddNullToObject(checks, "volume_change_max");
    cJSON *why = cJSON_AddArrayToObject(checks, "suspect");
    for (int bit = 0; bit < SEM_SUSPECT_COUNT; ++bit)
        if (r->suspect & (1 << bit)) cJSON_AddItemToArray(why, cJSON_CreateString(r->suspect_message[bit]));
    /* every number below is SI (metres, kg, s); frame files are in frame_units */
    cJSON_AddStringToObject(s, "units", "SI (m, kg, s)");
    cJSON_AddStringToObject(s, "frame_units", sem_scene_world_file_units(r->sw, 0));
    cJSON_AddNumberToObject(s, "frame_unit_to_meter", sem_scene_world_file_unit_to_meter(r->sw, 0));
    if (error) cJSON_AddStringToObject(s, "error", error);
    if (signal_name) cJSON_AddStringToObject(s, "signal", signal_name);
    cJSON_AddNumberToObject(s, "volume", volume);
    cJSON_AddNumberToObject(s, "mass", mass);
    cJSON_AddNumberToObject(s, "dofs", dofs);
    cJSON_AddNumberToObject(s, "steps", (double)r->steps);
    cJSON_AddNumberToObject(s, "dt", r->scene->world.dt);
    cJSON_AddNumberToObject(s, "mean_step_s", r->steps_timed ? r->step_sum / r->steps_timed : 0.0);
    cJSON_AddNumberToObject(s, "max_step_s", r->step_max);
    cJSON_AddNumberToObject(s, "mean_factor_s", r->steps_timed ? r->factor_sum / r->steps_timed : 0.0);
    cJSON_AddNumberToObject(s, "contact_s", r->steps_timed ? r->contact_sum / r->steps_timed : 0.0);
    cJSON_AddNumberToObject(s, "preprocess_s", sem_scene_world_preprocess_seconds(r->sw));
    cJSON_AddBoolToObject(s, "preprocess_cached", sem_scene_world_all_cached(r->sw));
    /* the process's peak resident memory until now (getrusage), and what was estimated
     * before the world was built (sem_scene_world_estimated_memory) */
    cJSON_AddNumberToObject(s, "peak_memory_bytes", cli_peak_memory());
    cJSON_AddNumberToObject(s, "estimated_memory_bytes", sem_scene_world_estimated_memory(r->sw));
    cJSON_AddStringToObject(s, "output_dir", r->scene->output_dir);
    if (r->anim && r->scene->write_usd) cJSON_AddStringToObject(s, "usd", sem_animation_usd_path(r->anim));
    if (r->anim && r->scene->write_glb) cJSON_AddStringToObject(s, "glb", sem_animation_glb_path(r->anim));
    cJSON_AddNumberToObject(s, "frames_per_second", 1.0 / (r->scene->world.dt * r->scene->steps_per_frame));
    cJSON_AddItemToObject(s, "objects", objs);
    cJSON_AddItemReferenceToObject(s, "frames", r->frames);
    return s;
}

static int write_summary(run_state *r, const char *status, const char *error,
                         const char *signal_name, int print_json)
{
    cJSON *s = summary(r, status, error, signal_name);
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
    free(r->dofs);
    for (int i = 0; r->frame_q && i < r->n; ++i) free(r->frame_q[i]);
    free(r->frame_q);
    free(r->qs);
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

/* The scene's text hash and absolute path, which identify the run (run.json). */
static int describe_scene(const char *scene_path, sem_run_info *info)
{
    if (!scene_path) {
        const char *text = sem_scene_default_json();
        info->scene_hash = sem_run_text_hash(text, strlen(text));
        info->scene_path[0] = '\0';
        return CLI_OK;
    }
    char *abs = realpath(scene_path, NULL);
    if (!abs) return cli_fail("%s: %s", scene_path, strerror(errno));
    snprintf(info->scene_path, sizeof info->scene_path, "%s", abs);
    free(abs);
    char *text = NULL;
    size_t len = 0;
    sem_error err;
    if (sem_read_file(scene_path, SEM_MAX_SCENE_FILE_BYTES, "SEM_MAX_SCENE_FILE_BYTES", &text, &len,
                      &err) != SEM_OK)
        return cli_fail_error(NULL, &err);
    info->scene_hash = sem_run_text_hash(text, len);
    free(text);
    return CLI_OK;
}

/* The state of the world after frame `frame` (q, v, time, steps, the frame's numbers). */
static sem_status save_state(run_state *r, int frame, const double *stats, sem_error *err)
{
    sem_run_frame_state s;
    memset(&s, 0, sizeof s);
    s.frame = frame;
    s.steps = r->steps;
    s.time = sem_world_time(r->world);
    s.n_objects = r->n;
    s.n = r->dofs;
    double *q[64], *v[64];
    double **qp = r->n <= 64 ? q : malloc((size_t)r->n * sizeof *qp);
    double **vp = r->n <= 64 ? v : malloc((size_t)r->n * sizeof *vp);
    if (!qp || !vp) {
        if (qp != q) free(qp);
        if (vp != v) free(vp);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < r->n; ++i) {
        qp[i] = (double *)sem_world_object_q(r->world, i);
        vp[i] = (double *)sem_world_object_velocity(r->world, i);
    }
    s.q = qp;
    s.v = vp;
    s.n_stats = STAT_COUNT;
    memcpy(s.stats, stats, STAT_COUNT * sizeof(double));
    sem_status st = sem_run_state_write(r->scene->output_dir, r->info.digits, r->run_id, &s, err);
    if (qp != q) free(qp);
    if (vp != v) free(vp);
    return st;
}

/* Frames 0..last of a stopped run: their USD points and summary numbers, then the world
 * at frame last. Returns the last complete frame (-1: none) or -2 on an error. */
static int restore_frames(run_state *r, sem_error *err)
{
    const char *dir = r->scene->output_dir;
    int last = -1;
    for (int f = 0; f <= r->info.frames; ++f) {
        sem_run_frame_state s;
        if (sem_run_state_read(dir, r->info.digits, f, r->run_id, r->n, r->dofs, &s, err) != SEM_OK)
            break;
        if (s.n_stats != STAT_COUNT) {
            sem_run_frame_state_free(&s);
            break;
        }
        for (int i = 0; i < r->n; ++i) sem_world_object_set_state(r->world, i, s.q[i], s.v[i]);
        sem_world_set_time(r->world, s.time);
        r->steps = s.steps;
        add_frame_stats(r, s.stats);
        sem_run_frame_state_free(&s);
        if (sem_animation_restore_frame(r->anim, f, frame_points(r), err) != SEM_OK) return -2;
        last = f;
    }
    return last;
}

int cmd_run(int argc, char **argv)
{
    const char *scene_path = NULL, *out_dir = NULL, *resume_dir = NULL;
    int frames = -1, json = 0, use_cache = 1, quiet = 0, overwrite = 0, strict = 0;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--json")) {
            json = 1;
        } else if (!strcmp(argv[i], "--no-cache")) {
            use_cache = 0;
        } else if (!strcmp(argv[i], "--quiet")) {
            quiet = 1;
        } else if (!strcmp(argv[i], "--overwrite")) {
            overwrite = 1;
        } else if (!strcmp(argv[i], "--strict")) {
            strict = 1;
        } else if (!strcmp(argv[i], "--frames")) {
            if (cli_need_values("run", argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (cli_parse_int("run", "--frames", argv[++i], &frames) != CLI_OK) return CLI_USAGE;
            if (frames < 0) return cli_usage("run", "--frames must be >= 0");
            if (frames > SEM_MAX_FRAMES)
                return cli_usage("run", "--frames %d is too large (at most %d)", frames, SEM_MAX_FRAMES);
        } else if (!strcmp(argv[i], "--out")) {
            if (cli_need_values("run", argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            out_dir = argv[++i];
        } else if (!strcmp(argv[i], "--resume")) {
            if (cli_need_values("run", argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            resume_dir = argv[++i];
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return cli_usage("run", "unknown option %s", argv[i]);
        } else if (!scene_path) {
            scene_path = argv[i];
        } else {
            return cli_usage("run", "more than one scene given");
        }
    }
    if (resume_dir && (scene_path || out_dir || frames >= 0 || overwrite))
        return cli_usage("run", "--resume DIR takes the scene, frames and folder of the run it "
                                "continues (no SCENE, --out, --frames or --overwrite)");
    run_state r;
    memset(&r, 0, sizeof r);
    r.strict = strict;
    sem_error err;
    sem_status st;
    if (resume_dir) {
        if (sem_run_info_read(resume_dir, &r.info, &err) != SEM_OK) return cli_fail_error(NULL, &err);
        scene_path = r.info.scene_path[0] ? r.info.scene_path : NULL;
        sem_run_info now = r.info;
        if (describe_scene(scene_path, &now) != CLI_OK) return CLI_FAILED;
        if (now.scene_hash != r.info.scene_hash)
            return cli_fail("%s: the scene %s changed since the run started; it cannot be resumed "
                            "(run it again with --overwrite)",
                            resume_dir, scene_path ? scene_path : "(default)");
    }
    if (scene_path)
        st = sem_scene_load(scene_path, &r.scene, &err);
    else
        st = sem_scene_parse(sem_scene_default_json(), "default scene", ".", &r.scene, &err);
    if (st != SEM_OK) return cli_fail_error(NULL, &err);
    if (resume_dir) {
        r.scene->frames = r.info.frames;
        snprintf(r.scene->output_dir, sizeof r.scene->output_dir, "%s", resume_dir);
        if (r.scene->steps_per_frame != r.info.steps_per_frame) {
            run_free(&r);
            return cli_fail("%s: steps_per_frame changed since the run started", resume_dir);
        }
    } else {
        if (frames >= 0) r.scene->frames = frames;
        if (out_dir) snprintf(r.scene->output_dir, sizeof r.scene->output_dir, "%s", out_dir);
        if (describe_scene(scene_path, &r.info) != CLI_OK) {
            run_free(&r);
            return CLI_FAILED;
        }
        r.info.frames = r.scene->frames;
        r.info.steps_per_frame = r.scene->steps_per_frame;
        r.info.digits = sem_run_frame_digits(r.scene->frames);
        char example[512];
        if (sem_run_folder_in_use(r.scene->output_dir, example, sizeof example)) {
            if (!overwrite) {
                int rc = cli_fail("%s holds another run (%s); use --overwrite to replace its files, "
                                  "or sem run --resume %s to continue it",
                                  r.scene->output_dir, example, r.scene->output_dir);
                run_free(&r);
                return rc;
            }
            if (sem_run_folder_clear(r.scene->output_dir, &err) != SEM_OK) {
                run_free(&r);
                return cli_fail_error(NULL, &err);
            }
        }
    }
    /* a folder that cannot take the frames is refused now, not after preprocessing */
    if (sem_animation_check_dir(r.scene->output_dir, &err) != SEM_OK) {
        run_free(&r);
        return cli_fail_error(NULL, &err);
    }
    /* the library reads no environment: the command line turns SEM_DEBUG_NEWTON into the
     * world's trace setting */
    const char *trace = getenv("SEM_DEBUG_NEWTON");
    if (trace && *trace && strcmp(trace, "0") != 0) {
        r.scene->world.advanced.trace_newton = 1;
        r.scene->world.log = world_log;
    }
    int procs = omp_get_num_procs();
    if (r.scene->world.threads > procs) {
        cli_warn("threads %d is more than the %d processors of this machine; using %d",
                 r.scene->world.threads, procs, procs);
        r.scene->world.threads = procs;
    }
    if (!scene_path && !quiet && !resume_dir)
        fprintf(stderr, "sem: no scene given; running the embedded default scene (%s)\n",
                "rubber beam clamped at x = 0");
    r.frames = cJSON_CreateArray();
    int rc = CLI_FAILED;
    if (!r.frames) {
        cli_fail("out of memory");
        goto done;
    }
    char cache[4096];
    cli_cache_dir(cache, sizeof cache);
    sem_scene_world_options wo = sem_default_scene_world_options();
    wo.cache_dir = cache;
    wo.read_cache = use_cache;
    wo.write_cache = use_cache;
    wo.cache_max_bytes = cli_cache_max_bytes();
    wo.log = run_log;
    wo.log_user = &quiet;
    wo.memory_available = cli_memory_available();
    if (sem_scene_world_create(r.scene, &wo, &r.sw, &err) != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    r.n = sem_scene_world_object_count(r.sw);
    r.world = sem_scene_world_world(r.sw);
    r.dofs = malloc((size_t)r.n * sizeof *r.dofs);
    const sem_model **models = malloc((size_t)r.n * sizeof *models);
    r.qs = malloc((size_t)r.n * sizeof *r.qs);
    r.frame_q = calloc((size_t)r.n, sizeof *r.frame_q);
    if (!r.dofs || !models || !r.qs || !r.frame_q) {
        free(models);
        cli_fail("out of memory");
        goto done;
    }
    unsigned long long hashes[64];
    int n_hashes = r.n < 64 ? r.n : 64;
    for (int i = 0; i < r.n; ++i) {
        models[i] = sem_scene_world_output_model(r.sw, i);
        r.dofs[i] = (size_t)sem_world_object_dofs(r.world, i);
        r.qs[i] = sem_world_object_q(r.world, i);
        if (models[i] != sem_scene_world_model(r.sw, i)) {
            r.frame_q[i] = malloc(3 * sem_model_control_points(models[i]) * sizeof(double) + 1);
            if (!r.frame_q[i]) {
                free(models);
                cli_fail("out of memory");
                goto done;
            }
            r.qs[i] = r.frame_q[i];
        }
        if (i < 64) hashes[i] = sem_scene_world_discretization(r.sw, i)->model_hash;
    }
    if (resume_dir) {
        int same = r.info.n_objects == n_hashes;
        for (int i = 0; same && i < n_hashes; ++i) same = r.info.object_hash[i] == hashes[i];
        if (!same) {
            free(models);
            cli_fail("%s: a model or its settings changed since the run started; it cannot be "
                     "resumed (run it again with --overwrite)", resume_dir);
            goto done;
        }
    } else {
        r.info.n_objects = n_hashes;
        memcpy(r.info.object_hash, hashes, (size_t)n_hashes * sizeof hashes[0]);
    }
    r.run_id = sem_run_id(&r.info);
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
    ad.frame_digits = r.info.digits;
    st = sem_animation_create(&ad, r.n, models, &r.anim, &err);
    free(models);
    for (int i = 0; i < r.n && st == SEM_OK; ++i)
        st = sem_animation_write_preprocess(r.anim, i, sem_scene_world_discretization(r.sw, i), &err);
    if (st != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    int first = 1;
    if (resume_dir) {
        sem_error rerr;
        int last = restore_frames(&r, &rerr);
        if (last == -2) {
            cli_fail_error(NULL, &rerr);
            goto done;
        }
        if (last < 0) {
            cli_fail("%s: no complete frame to resume from (%s); run it again with --overwrite",
                     resume_dir, rerr.message);
            goto done;
        }
        if (!quiet) {
            if (last == r.scene->frames)
                fprintf(stderr, "sem: %s: the run is complete (%d frames); summary and animation "
                                "written again\n", resume_dir, last);
            else
                fprintf(stderr, "sem: resuming %s after frame %d of %d\n", resume_dir, last,
                        r.scene->frames);
        }
        first = last + 1;
    } else {
        if (sem_run_info_write(r.scene->output_dir, &r.info, &err) != SEM_OK) {
            cli_fail_error(NULL, &err);
            goto done;
        }
        double stats[STAT_COUNT];
        frame_stats(&r, 0.0, stats);
        if (sem_animation_add_frame(r.anim, 0, frame_points(&r), &err) != SEM_OK ||
            save_state(&r, 0, stats, &err) != SEM_OK) {
            cli_fail_error(NULL, &err);
            goto done;
        }
        add_frame_stats(&r, stats);
    }
    long long total = (long long)(r.scene->frames - first + 1) * r.scene->steps_per_frame;
    if (!quiet && total > 0) progress_start("simulating", (long)total);
    catch_stop_signals();
    double t_run = omp_get_wtime();
    char failure[1100] = "";
    int stopped_after = -1; /* last complete frame when a signal stopped the run */
    for (int f = first; f <= r.scene->frames && !failure[0]; ++f) {
        int done_in_frame = 0;
        double frame_gap = INFINITY; /* the smallest gap over the frame's steps */
        for (int s = 0; s < r.scene->steps_per_frame; ++s) {
            if (sem_world_step(r.world, &err) != SEM_OK) {
                snprintf(failure, sizeof failure, "step %lld (t = %g): %s", r.steps + 1,
                         sem_world_time(r.world) + r.scene->world.dt, err.message);
                break;
            }
            double dt = sem_world_last_step_seconds(r.world);
            r.steps++;
            r.steps_timed++;
            r.step_sum += dt;
            r.factor_sum += sem_world_last_factor_seconds(r.world);
            sem_contact_stats cs;
            sem_world_contact_stats(r.world, &cs);
            r.contact_sum += cs.seconds;
            frame_gap = fmin(frame_gap, cs.min_gap);
            if (dt > r.step_max) r.step_max = dt;
            done_in_frame++;
            if (stop_signal) break;
            if (!quiet) {
                double el = omp_get_wtime() - t_run, rate = r.steps_timed / (el > 0 ? el : 1e-9);
                char extra[128];
                snprintf(extra, sizeof extra, "frame %d/%d, %.1f steps/s, %.0f s left", f,
                         r.scene->frames, rate, (total - r.steps_timed) / rate);
                progress_update(r.steps_timed, extra);
            }
        }
        if (failure[0]) break;
        if (done_in_frame < r.scene->steps_per_frame) {
            /* stopped: the unfinished frame's steps are dropped (its state is not a frame;
             * a resumed run does them again, with the same bits) */
            stopped_after = f - 1;
            break;
        }
        double stats[STAT_COUNT];
        frame_stats(&r, sem_world_time(r.world), stats);
        stats[STAT_MIN_GAP] = frame_gap;
        if (sem_animation_add_frame(r.anim, f, frame_points(&r), &err) != SEM_OK ||
            save_state(&r, f, stats, &err) != SEM_OK) {
            snprintf(failure, sizeof failure, "frame %d: %s", f, err.message);
            break;
        }
        add_frame_stats(&r, stats);
        if (r.strict && r.suspect) {
            for (int bit = 0; bit < SEM_SUSPECT_COUNT; ++bit)
                if (r.suspect & (1 << bit)) {
                    snprintf(failure, sizeof failure, "--strict: %s", r.suspect_message[bit]);
                    break;
                }
            break;
        }
        if (stop_signal) {
            stopped_after = f;
            break;
        }
    }
    if (!quiet && total > 0) progress_finish();
    sem_error ferr;
    if (sem_animation_finish(r.anim, &ferr) != SEM_OK && !failure[0])
        snprintf(failure, sizeof failure, "%s", ferr.message);
    int sig = stop_signal;
    const char *sig_name = sig == SIGINT ? "SIGINT" : sig == SIGTERM ? "SIGTERM" : NULL;
    const char *status = failure[0] ? "failed" : sig ? "interrupted" : r.suspect ? "suspect" : "ok";
    if (write_summary(&r, status, failure[0] ? failure : NULL, sig ? sig_name : NULL, json) != CLI_OK)
        goto done;
    if (failure[0]) {
        cli_fail("%s (frames written so far are kept in %s)", failure, r.scene->output_dir);
        goto done;
    }
    if (sig) {
        fprintf(stderr,
                "sem: interrupted by %s after frame %d of %d; frames, animation.usda and "
                "summary.json are in %s; continue with: sem run --resume %s\n",
                sig_name, stopped_after, r.scene->frames, r.scene->output_dir,
                r.scene->output_dir);
        rc = 128 + sig;
        goto done;
    }
    if (!quiet && !json) {
        char peak[32];
        cli_format_bytes(cli_peak_memory(), peak, sizeof peak);
        fprintf(stderr, "sem: %lld steps, mean %.3g s per step, peak memory %s\n", r.steps,
                r.steps_timed ? r.step_sum / r.steps_timed : 0.0, peak);
        fprintf(stderr,
                "sem: animation written to %s/: frame_NNNN.igs (NURBS for Rhino/Fusion 360), "
                "frame_NNNN_mesh.obj (render meshes), animation.usda (open with Blender: File > Import > "
                "Universal Scene Description, or usdview), animation.glb (glTF: Blender, three.js), summary.json; "
                "to look at it: sem render %s --mp4 %s/anim.mp4, or sem view %s\n",
                r.scene->output_dir, r.scene->output_dir, r.scene->output_dir, r.scene->output_dir);
    }
    rc = CLI_OK;
done:
    release_stop_signals();
    run_free(&r);
    return rc;
}
