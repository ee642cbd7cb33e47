/*
 * run_folder.c - reading the output folder of `sem run` (see run_folder.h).
 *
 * Frames are found by listing the folder: names of exactly the form frame_<digits><suffix>.
 * The run writes frames 0, 1, 2, ... in order and summary.json records how many, so the
 * frames are 0..count-1 (without summary.json: 0 to the highest found). Any gap is an
 * error naming the first missing file: rendering around it would make a video that skips
 * time.
 */
#include "run_folder.h"

#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

int run_frame_matches(const sem_model *rest, const sem_model *frame)
{
    if (rest->n_parts != frame->n_parts) return 0;
    for (int i = 0; i < rest->n_parts; ++i) {
        const sem_surface *a = &rest->parts[i].surface, *b = &frame->parts[i].surface;
        if (a->degree_u != b->degree_u || a->degree_v != b->degree_v || a->n_u != b->n_u || a->n_v != b->n_v)
            return 0;
    }
    return 1;
}

char *read_text_file(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    struct stat st;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        return NULL;
    }
    size_t n = (size_t)st.st_size;
    char *text = malloc(n + 1);
    if (!text) {
        fclose(f);
        return NULL;
    }
    size_t got = fread(text, 1, n, f);
    fclose(f);
    if (got != n) {
        free(text);
        return NULL;
    }
    text[n] = '\0';
    if (size) *size = n;
    return text;
}

/* frame number of "frame_<digits><suffix>", or -1 */
static int frame_number(const char *name, const char *suffix)
{
    if (strncmp(name, "frame_", 6) != 0) return -1;
    const char *p = name + 6;
    if (!isdigit((unsigned char)*p)) return -1;
    long n = 0;
    while (isdigit((unsigned char)*p)) {
        n = 10 * n + (*p - '0');
        if (n > 99999999) return -1;
        p++;
    }
    return strcmp(p, suffix) == 0 ? (int)n : -1;
}

/* Highest frame number found and how many, for one suffix; *seen marks which exist. */
static int scan(const char *dir, const char *suffix, unsigned char **seen, int *count, sem_error *err)
{
    DIR *d = opendir(dir);
    if (!d) {
        sem_error_set(err, SEM_ERR_IO, "%s: cannot open folder: %s", dir, strerror(errno));
        return -2;
    }
    int max = -1, cap = 0;
    *seen = NULL;
    *count = 0;
    struct dirent *e;
    while ((e = readdir(d)) != NULL) {
        int n = frame_number(e->d_name, suffix);
        if (n < 0) continue;
        if (n >= cap) {
            int nc = cap ? cap : 256;
            while (nc <= n) nc *= 2;
            unsigned char *s = realloc(*seen, (size_t)nc);
            if (!s) {
                closedir(d);
                sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                return -2;
            }
            memset(s + cap, 0, (size_t)(nc - cap));
            *seen = s;
            cap = nc;
        }
        if (!(*seen)[n]) (*count)++;
        (*seen)[n] = 1;
        if (n > max) max = n;
    }
    closedir(d);
    return max;
}

static double number(const cJSON *o, const char *key, double fallback)
{
    const cJSON *x = cJSON_GetObjectItemCaseSensitive(o, key);
    return cJSON_IsNumber(x) ? x->valuedouble : fallback;
}

static void read_summary(run_folder *rf)
{
    char path[4200];
    snprintf(path, sizeof path, "%s/summary.json", rf->dir);
    char *text = read_text_file(path, NULL);
    rf->summary = text ? cJSON_Parse(text) : NULL;
    free(text);
    if (!rf->summary) return;
    double fps = number(rf->summary, "frames_per_second", 0);
    const cJSON *frames = cJSON_GetObjectItemCaseSensitive(rf->summary, "frames");
    if (!(fps > 0) && cJSON_GetArraySize(frames) >= 2) {
        double dt = number(cJSON_GetArrayItem(frames, 1), "time", 0) -
                    number(cJSON_GetArrayItem(frames, 0), "time", 0);
        if (dt > 0) fps = 1.0 / dt;
    }
    if (fps > 0 && fps < 1e6) rf->fps = fps;
    const cJSON *objects = cJSON_GetObjectItemCaseSensitive(rf->summary, "objects");
    int n = cJSON_GetArraySize(objects);
    if (n < 1) return;
    int *parts = calloc((size_t)n, sizeof *parts);
    if (!parts) return;
    for (int i = 0; i < n; ++i) parts[i] = (int)number(cJSON_GetArrayItem(objects, i), "parts", 0);
    free(rf->object_parts);
    rf->object_parts = parts;
    rf->n_objects = n;
}

sem_status run_folder_open(const char *dir, run_folder *rf, sem_error *err)
{
    memset(rf, 0, sizeof *rf);
    snprintf(rf->dir, sizeof rf->dir, "%s", dir);
    size_t len = strlen(rf->dir);
    while (len > 1 && rf->dir[len - 1] == '/') rf->dir[--len] = '\0';
    rf->fps = 24;
    rf->n_objects = 1;
    rf->object_parts = calloc(1, sizeof *rf->object_parts);
    if (!rf->object_parts) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    unsigned char *seen = NULL;
    int count = 0;
    rf->suffix = ".igs";
    int max = scan(rf->dir, rf->suffix, &seen, &count, err);
    if (max == -1) {
        free(seen);
        rf->suffix = "_nurbs.obj";
        max = scan(rf->dir, rf->suffix, &seen, &count, err);
    }
    if (max == -2) {
        run_folder_close(rf);
        return err ? err->status : SEM_ERR_IO;
    }
    if (max < 0) {
        free(seen);
        run_folder_close(rf);
        return sem_error_set(err, SEM_ERR_INVALID,
                             "%s: no frames (frame_NNNN.igs or frame_NNNN_nurbs.obj): not an output folder of sem run",
                             dir);
    }
    read_summary(rf);
    /* summary.json counts the frames of the last run (files beyond it are left over from
     * an earlier, longer run in the same folder) */
    int expected = max + 1;
    const cJSON *frames = rf->summary ? cJSON_GetObjectItemCaseSensitive(rf->summary, "frames") : NULL;
    if (cJSON_IsArray(frames) && cJSON_GetArraySize(frames) > 0) expected = cJSON_GetArraySize(frames);
    for (int n = 0; n < expected; ++n)
        if (n > max || !seen[n]) {
            char name[64];
            snprintf(name, sizeof name, "frame_%04d%s", n, rf->suffix);
            free(seen);
            sem_status st = sem_error_set(err, SEM_ERR_INVALID, "%s: %s is missing (the run has frames 0..%d)",
                                          rf->dir, name, expected - 1);
            run_folder_close(rf);
            return st;
        }
    free(seen);
    rf->n_frames = expected;
    return SEM_OK;
}

void run_folder_close(run_folder *rf)
{
    cJSON_Delete(rf->summary);
    free(rf->object_parts);
    rf->summary = NULL;
    rf->object_parts = NULL;
}

void run_folder_frame_path(const run_folder *rf, int frame, char *out, size_t size)
{
    snprintf(out, size, "%s/frame_%04d%s", rf->dir, frame, rf->suffix);
}

const cJSON *run_folder_object(const run_folder *rf, int object)
{
    if (!rf->summary) return NULL;
    return cJSON_GetArrayItem(cJSON_GetObjectItemCaseSensitive(rf->summary, "objects"), object);
}
