/*
 * cmd_render.c - `sem render OUT_DIR | MODEL_FILE [options]`: pictures and videos.
 *
 * A run folder: every frame (or --frames A:B) becomes OUT_DIR/render/frame_NNNN.png (-o
 * names another folder), and --mp4 FILE encodes them with ffmpeg. A model file: one
 * picture of the model at rest (-o PICTURE.png, default MODEL.png in the current folder).
 * See docs/render.md for the options and what the colourings show.
 *
 * Work: the frames are read and tessellated once to find the box the camera must frame
 * (render_input.c), colours are computed once at rest (render_colors.c), then frames are
 * rendered in parallel, one per thread, each thread with its own mesh and picture
 * buffers; a single picture uses every thread for its rows instead. Each PNG is written
 * atomically as soon as its frame is done, so an interrupted render leaves complete
 * pictures. ffmpeg is looked up before any work, so a missing ffmpeg costs nothing.
 */
#include <errno.h>
#include <math.h>
#include <omp.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include "cli.h"
#include "render_input.h"
#include "sem/render.h"
#include "util/make_dirs.h"

#define CMD "render"

extern char **environ;

typedef struct render_options {
    const char *input, *output, *mp4, *disc;
    int width, height;
    int first, last; /* -1: from the start / to the end */
    sem_camera camera;
    render_color_mode color;
    int part;
    int resolution;
    int quiet;
} render_options;

/* "A:B", "A:", ":B" or "A" */
static int parse_frames(const char *text, int *first, int *last)
{
    const char *colon = strchr(text, ':');
    char a[64] = "", b[64] = "";
    if (strlen(text) >= sizeof a) return cli_usage(CMD, "--frames: '%s' is not A:B", text);
    if (!colon) {
        snprintf(a, sizeof a, "%s", text);
        snprintf(b, sizeof b, "%s", text);
    } else {
        snprintf(a, sizeof a, "%.*s", (int)(colon - text), text);
        snprintf(b, sizeof b, "%s", colon + 1);
    }
    *first = 0;
    *last = -1;
    if (a[0] && cli_parse_int(CMD, "--frames", a, first) != CLI_OK) return CLI_USAGE;
    if (b[0] && cli_parse_int(CMD, "--frames", b, last) != CLI_OK) return CLI_USAGE;
    if (*first < 0 || (b[0] && *last < *first))
        return cli_usage(CMD, "--frames %s: need 0 <= A <= B", text);
    return CLI_OK;
}

/* "AZ,EL", "AZ,EL,DIST" or "EX,EY,EZ,TX,TY,TZ" */
static int parse_camera(const char *text, sem_camera *c)
{
    double v[7];
    int n = 0;
    const char *p = text;
    while (*p && n < 7) {
        char *end;
        errno = 0;
        v[n] = strtod(p, &end);
        if (end == p || errno == ERANGE || !isfinite(v[n]) || (*end && *end != ',')) break;
        n++;
        p = *end ? end + 1 : end;
    }
    if (*p || (n != 2 && n != 3 && n != 6))
        return cli_usage(CMD, "--camera: '%s' is not AZIMUTH,ELEVATION[,DISTANCE] or EX,EY,EZ,TX,TY,TZ", text);
    if (n == 6) {
        c->look_at = 1;
        for (int k = 0; k < 3; ++k) {
            c->eye[k] = v[k];
            c->target[k] = v[k + 3];
        }
        return CLI_OK;
    }
    if (v[1] < -90 || v[1] > 90) return cli_usage(CMD, "--camera: elevation %g must be in [-90, 90]", v[1]);
    c->look_at = 0;
    c->azimuth = v[0];
    c->elevation = v[1];
    c->distance = n == 3 ? v[2] : 0;
    if (n == 3 && !(v[2] > 0)) return cli_usage(CMD, "--camera: distance %g must be positive", v[2]);
    return CLI_OK;
}

static int parse_options(int argc, char **argv, render_options *o)
{
    memset(o, 0, sizeof *o);
    sem_render_def defaults = sem_default_render_def();
    o->width = defaults.width;
    o->height = defaults.height;
    o->camera = defaults.camera;
    o->first = 0;
    o->last = -1;
    o->color = RENDER_COLOR_PART;
    o->part = -1;
    o->resolution = 8;
    for (int i = 1; i < argc; ++i) {
        const char *a = argv[i];
        if (!strcmp(a, "-o") || !strcmp(a, "--output")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            o->output = argv[++i];
        } else if (!strcmp(a, "--mp4")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            o->mp4 = argv[++i];
        } else if (!strcmp(a, "--disc")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            o->disc = argv[++i];
        } else if (!strcmp(a, "--size")) {
            if (cli_need_values(CMD, argc, argv, i, 2) != CLI_OK) return CLI_USAGE;
            if (cli_parse_int(CMD, "--size", argv[++i], &o->width) != CLI_OK ||
                cli_parse_int(CMD, "--size", argv[++i], &o->height) != CLI_OK)
                return CLI_USAGE;
            if (o->width < 16 || o->height < 16 || o->width > 16384 || o->height > 16384)
                return cli_usage(CMD, "--size: %d x %d must be 16..16384 pixels each way", o->width, o->height);
        } else if (!strcmp(a, "--frames")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (parse_frames(argv[++i], &o->first, &o->last) != CLI_OK) return CLI_USAGE;
        } else if (!strcmp(a, "--camera")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (parse_camera(argv[++i], &o->camera) != CLI_OK) return CLI_USAGE;
        } else if (!strcmp(a, "--color") || !strcmp(a, "--colour")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (render_colors_parse(argv[++i], &o->color, &o->part) != CLI_OK) return CLI_USAGE;
        } else if (!strcmp(a, "--resolution")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            if (cli_parse_int(CMD, "--resolution", argv[++i], &o->resolution) != CLI_OK) return CLI_USAGE;
            if (o->resolution < 1 || o->resolution > 64) return cli_usage(CMD, "--resolution must be 1..64");
        } else if (!strcmp(a, "--quiet")) {
            o->quiet = 1;
        } else if (a[0] == '-' && a[1]) {
            return cli_usage(CMD, "unknown option %s", a);
        } else if (!o->input) {
            o->input = a;
        } else {
            return cli_usage(CMD, "more than one input given");
        }
    }
    if (!o->input) return cli_usage(CMD, "no run folder or model file given");
    return CLI_OK;
}

/* Is `name` an executable in PATH? */
static int in_path(const char *name)
{
    const char *path = getenv("PATH");
    if (!path || !*path) path = "/usr/local/bin:/usr/bin:/bin";
    char dir[4096];
    while (*path) {
        size_t n = strcspn(path, ":");
        snprintf(dir, sizeof dir, "%.*s/%s", (int)n, path, name);
        if (n > 0 && access(dir, X_OK) == 0) return 1;
        path += n;
        if (*path == ':') path++;
    }
    return 0;
}

/* MODEL.png in the current folder for path/MODEL.ext */
static void default_picture(const char *model, char *out, size_t size)
{
    const char *base = strrchr(model, '/');
    base = base ? base + 1 : model;
    const char *dot = strrchr(base, '.');
    int n = dot && dot != base ? (int)(dot - base) : (int)strlen(base);
    snprintf(out, size, "%.*s.png", n, base);
}

static void log_line(const char *message)
{
    fprintf(stderr, "sem: %s\n", message);
}

/* ffmpeg -framerate FPS -start_number FIRST -i DIR/frame_%04d.png ... into mp4 (atomic). */
static int encode_mp4(const char *dir, int first, int count, double fps, const char *mp4)
{
    char pattern[4200], rate[64], start[32], frames[32], tmp[4200];
    snprintf(pattern, sizeof pattern, "%s/frame_%%04d.png", dir);
    snprintf(rate, sizeof rate, "%.6g", fps);
    snprintf(start, sizeof start, "%d", first);
    snprintf(frames, sizeof frames, "%d", count);
    snprintf(tmp, sizeof tmp, "%s.tmp.%ld", mp4, (long)getpid());
    char *args[] = {"ffmpeg", "-nostdin", "-y", "-loglevel", "error", "-framerate", rate, "-start_number", start,
                    "-i", pattern, "-frames:v", frames, "-vf", "pad=ceil(iw/2)*2:ceil(ih/2)*2", "-c:v", "libx264",
                    "-pix_fmt", "yuv420p", "-crf", "18", "-movflags", "+faststart", "-f", "mp4", tmp, NULL};
    pid_t pid;
    int rc = posix_spawnp(&pid, "ffmpeg", NULL, NULL, args, environ);
    if (rc != 0) return cli_fail("cannot start ffmpeg: %s", strerror(rc));
    int status = 0;
    while (waitpid(pid, &status, 0) < 0)
        if (errno != EINTR) {
            remove(tmp);
            return cli_fail("waiting for ffmpeg: %s", strerror(errno));
        }
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        remove(tmp);
        return cli_fail("ffmpeg failed (status %d) encoding %s", WIFEXITED(status) ? WEXITSTATUS(status) : -1, mp4);
    }
    if (rename(tmp, mp4) != 0) {
        int e = errno;
        remove(tmp);
        return cli_fail("%s: cannot write: %s", mp4, strerror(e));
    }
    return CLI_OK;
}

/* Per-thread buffers for a frame. */
typedef struct frame_work {
    sem_model *model;
    sem_mesh mesh;
    unsigned char *rgb;
    double *points;
} frame_work;

static int frame_work_init(frame_work *w, const render_input *in, const render_colors *c, size_t pixels,
                           sem_error *err)
{
    memset(w, 0, sizeof *w);
    w->model = sem_model_clone(in->rest);
    w->rgb = malloc(3 * pixels);
    w->points = malloc(3 * ((size_t)c->n_points + 1) * sizeof *w->points);
    if (!w->model || !w->rgb || !w->points) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        return 0;
    }
    return sem_mesh_template_mesh(in->tmpl, &w->mesh, err) == SEM_OK;
}

static void frame_work_free(frame_work *w)
{
    sem_model_destroy(w->model);
    sem_mesh_free(&w->mesh);
    free(w->rgb);
    free(w->points);
}

static sem_status render_one(const sem_renderer *r, const render_input *in, const render_colors *c, int k,
                             int threads, const char *path, int width, int height, frame_work *w, sem_error *err)
{
    sem_status st = render_input_mesh(in, k, w->model, &w->mesh, err);
    if (st != SEM_OK) return st;
    sem_render_surface surface = {w->mesh.n_vertices, w->mesh.n_triangles, w->mesh.positions, w->mesh.normals,
                                  w->mesh.triangles, c->vertex_colors, c->opacity, w->mesh.uv,
                                  sem_render_trims_table(in->trims)};
    sem_render_points points = {c->n_points, w->points, c->point_colors, c->point_radius};
    if (c->n_points > 0 && (st = render_colors_points(c, in, k, w->points, err)) != SEM_OK) return st;
    sem_render_frame frame = {1, &surface, c->n_points > 0 ? 1 : 0, &points};
    if ((st = sem_render_image(r, &frame, threads, w->rgb, err)) != SEM_OK) return st;
    return sem_png_write(path, width, height, w->rgb, err);
}

int cmd_render(int argc, char **argv)
{
    render_options o;
    if (parse_options(argc, argv, &o) != CLI_OK) return CLI_USAGE;
    struct stat sb;
    if (stat(o.input, &sb) != 0) return cli_fail("%s: %s", o.input, strerror(errno));
    const int is_run = S_ISDIR(sb.st_mode);
    if (!is_run && o.mp4) return cli_fail("--mp4 needs a run folder (a model file gives one picture)");
    if (!is_run && (o.first != 0 || o.last != -1)) return cli_fail("--frames needs a run folder");
    if (is_run && o.disc) return cli_fail("--disc is for a model file (a run folder has its preprocess_K.semdisc)");
    if (o.mp4 && !in_path("ffmpeg"))
        return cli_fail("--mp4 needs ffmpeg, which is not installed (Debian: apt-get install ffmpeg)");

    render_input in;
    render_colors colors;
    memset(&colors, 0, sizeof colors);
    sem_renderer *renderer = NULL;
    sem_error err;
    sem_status st = is_run ? render_input_open_run(o.input, o.first, o.last, o.resolution, &in, &err)
                           : render_input_open_model(o.input, o.resolution, &in, &err);
    if (st != SEM_OK) return cli_fail_error(NULL, &err);
    int rc = CLI_FAILED;
    if (!is_run) cli_print_model_warnings(in.rest);
    if (render_colors_build(&in, o.color, o.part, o.disc, o.quiet ? NULL : log_line, &colors, &err) != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    sem_render_def def = sem_default_render_def();
    def.width = o.width;
    def.height = o.height;
    def.camera = o.camera;
    memcpy(def.bounds, in.bounds, sizeof def.bounds);
    if (sem_renderer_create(&def, &renderer, &err) != SEM_OK) {
        cli_fail_error(NULL, &err);
        goto done;
    }
    char dir[4200] = "", picture[4200] = "";
    if (is_run) {
        if (o.output)
            snprintf(dir, sizeof dir, "%s", o.output);
        else
            snprintf(dir, sizeof dir, "%s/render", in.run.dir);
        sem_error derr;
        if (sem_make_dirs(dir, &derr) != SEM_OK) {
            cli_fail_error(NULL, &derr);
            goto done;
        }
    } else if (o.output) {
        snprintf(picture, sizeof picture, "%s", o.output);
    } else {
        default_picture(o.input, picture, sizeof picture);
    }

    const size_t pixels = (size_t)o.width * (size_t)o.height;
    const int n = in.count;
    int outer = n > 1 ? omp_get_max_threads() : 1;
    if (outer > n) outer = n;
    if (outer < 1) outer = 1;
    int done_frames = 0, failed = n;
    sem_error first_error;
    sem_error_clear(&first_error);
    if (!o.quiet && n > 1) progress_start("rendering", n);
    double t0 = omp_get_wtime();
#pragma omp parallel num_threads(outer)
    {
        frame_work w;
        sem_error e;
        sem_error_clear(&e);
        int ok = frame_work_init(&w, &in, &colors, pixels, &e);
#pragma omp for schedule(dynamic, 1)
        for (int k = 0; k < n; ++k) {
            int skip;
#pragma omp atomic read
            skip = failed;
            if (skip < k) continue; /* an earlier frame failed: stop soon */
            char path[4400];
            if (is_run)
                snprintf(path, sizeof path, "%s/frame_%04d.png", dir, in.first + k);
            else
                snprintf(path, sizeof path, "%s", picture);
            if (!ok || render_one(renderer, &in, &colors, k, outer > 1 ? 1 : 0, path, o.width, o.height, &w, &e) !=
                           SEM_OK) {
#pragma omp critical(render_error)
                if (k < failed) {
                    first_error = e;
#pragma omp atomic write
                    failed = k;
                }
                continue;
            }
            int now;
#pragma omp atomic capture
            now = ++done_frames;
            if (omp_get_thread_num() == 0 && !o.quiet && n > 1) progress_update(now, NULL);
        }
        frame_work_free(&w);
    }
    double seconds = omp_get_wtime() - t0;
    if (!o.quiet && n > 1) {
        progress_update(done_frames, NULL);
        progress_finish();
    }
    if (failed < n) {
        cli_fail_error(NULL, &first_error);
        goto done;
    }
    if (!o.quiet) {
        if (is_run)
            fprintf(stderr, "sem: %d frame%s rendered to %s/ (%d x %d, %.3g s per frame)\n", n, n == 1 ? "" : "s", dir,
                    o.width, o.height, seconds / n);
        else
            fprintf(stderr, "sem: wrote %s (%d x %d, %.3g s)\n", picture, o.width, o.height, seconds);
    }
    if (o.mp4) {
        if (encode_mp4(dir, in.first, n, in.run.fps, o.mp4) != CLI_OK) goto done;
        if (!o.quiet) fprintf(stderr, "sem: wrote %s (%d frames at %.3g per second)\n", o.mp4, n, in.run.fps);
    }
    rc = CLI_OK;
done:
    sem_renderer_destroy(renderer);
    render_colors_free(&colors, in.n_objects);
    render_input_free(&in);
    return rc;
}
