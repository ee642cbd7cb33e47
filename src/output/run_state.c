/* run_state.c - run identity, per-frame state files, folder checks (see output/run_state.h). */
#include "output/run_state.h"

#include <cjson/cJSON.h>
#include <ctype.h>
#include <dirent.h>
#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "io/atomic_file.h"
#include "io/read_file.h"
#include "util/fnv_hash.h"

static const char state_magic[8] = {'S', 'E', 'M', 'S', 'T', 'A', 'T', 'E'};
#define STATE_VERSION 1u
#define STATE_BYTE_ORDER 0x01020304u
#define MAX_STATE_BYTES (2LL << 30)
#define MAX_INFO_BYTES (1LL << 20)

int sem_run_frame_digits(int frames)
{
    int d = 1;
    for (long long x = frames; x >= 10; x /= 10) d++;
    return d < 4 ? 4 : d;
}


unsigned long long sem_run_text_hash(const char *text, size_t len)
{
    sem_fnv f;
    sem_fnv_init(&f);
    sem_fnv_bytes(&f, text, len);
    return f.h;
}

unsigned long long sem_run_id(const sem_run_info *info)
{
    sem_fnv f;
    sem_fnv_init(&f);
    sem_fnv_bytes(&f, info->scene_path, strlen(info->scene_path));
    sem_fnv_bytes(&f, &info->scene_hash, sizeof info->scene_hash);
    int sizes[4] = {info->frames, info->steps_per_frame, info->digits, info->n_objects};
    sem_fnv_bytes(&f, sizes, sizeof sizes);
    int n = info->n_objects < 64 ? info->n_objects : 64;
    sem_fnv_bytes(&f, info->object_hash, (size_t)n * sizeof info->object_hash[0]);
    return f.h;
}

/* ---- run.json ---- */

static void state_dir(const char *dir, char *out, size_t size)
{
    snprintf(out, size, "%s/state", dir);
}

sem_status sem_run_info_write(const char *dir, const sem_run_info *info, sem_error *err)
{
    char sdir[4200], path[4300], hex[32];
    state_dir(dir, sdir, sizeof sdir);
    if (mkdir(sdir, 0777) != 0 && errno != EEXIST)
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot create folder: %s", sdir, strerror(errno));
    snprintf(path, sizeof path, "%s/run.json", sdir);
    cJSON *o = cJSON_CreateObject();
    if (!o) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    cJSON_AddNumberToObject(o, "format", 1);
    if (info->scene_path[0]) cJSON_AddStringToObject(o, "scene", info->scene_path);
    else cJSON_AddNullToObject(o, "scene");
    snprintf(hex, sizeof hex, "%016llx", info->scene_hash);
    cJSON_AddStringToObject(o, "scene_hash", hex);
    cJSON_AddNumberToObject(o, "frames", info->frames);
    cJSON_AddNumberToObject(o, "steps_per_frame", info->steps_per_frame);
    cJSON_AddNumberToObject(o, "frame_digits", info->digits);
    cJSON *objs = cJSON_AddArrayToObject(o, "object_hashes");
    for (int i = 0; i < info->n_objects && i < 64; ++i) {
        snprintf(hex, sizeof hex, "%016llx", info->object_hash[i]);
        cJSON_AddItemToArray(objs, cJSON_CreateString(hex));
    }
    char *text = cJSON_Print(o);
    cJSON_Delete(o);
    if (!text) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_atomic_file f;
    sem_status st = sem_atomic_open(&f, path, err);
    if (st == SEM_OK) {
        fputs(text, f.fp);
        fputc('\n', f.fp);
        st = sem_atomic_commit(&f, err);
    }
    free(text);
    return st;
}

static int parse_hex(const cJSON *v, unsigned long long *out)
{
    if (!cJSON_IsString(v) || strlen(v->valuestring) != 16) return 0;
    char *end;
    errno = 0;
    *out = strtoull(v->valuestring, &end, 16);
    return errno == 0 && *end == '\0';
}

static int get_int(const cJSON *o, const char *key, int lo, int hi, int *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, key);
    if (!cJSON_IsNumber(v) || v->valuedouble != floor(v->valuedouble) || v->valuedouble < lo ||
        v->valuedouble > hi)
        return 0;
    *out = (int)v->valuedouble;
    return 1;
}

sem_status sem_run_info_read(const char *dir, sem_run_info *info, sem_error *err)
{
    memset(info, 0, sizeof *info);
    char path[4300];
    snprintf(path, sizeof path, "%s/state/run.json", dir);
    char *text = NULL;
    size_t len = 0;
    sem_status st = sem_read_file(path, MAX_INFO_BYTES, "1 MiB for run.json", &text, &len, err);
    if (st != SEM_OK) {
        if (st == SEM_ERR_IO && access(path, F_OK) != 0)
            return sem_error_set(err, SEM_ERR_IO, "%s: no run to resume here (%s is missing)", dir,
                                 path);
        return st;
    }
    cJSON *o = cJSON_Parse(text);
    free(text);
    const cJSON *scene = o ? cJSON_GetObjectItemCaseSensitive(o, "scene") : NULL;
    const cJSON *objs = o ? cJSON_GetObjectItemCaseSensitive(o, "object_hashes") : NULL;
    int format = 0, ok = o && get_int(o, "format", 1, 1, &format) &&
                         (cJSON_IsNull(scene) || (cJSON_IsString(scene) &&
                                                  strlen(scene->valuestring) < sizeof info->scene_path)) &&
                         parse_hex(cJSON_GetObjectItemCaseSensitive(o, "scene_hash"), &info->scene_hash) &&
                         get_int(o, "frames", 0, 1000000000, &info->frames) &&
                         get_int(o, "steps_per_frame", 1, 1000000000, &info->steps_per_frame) &&
                         get_int(o, "frame_digits", 4, 10, &info->digits) && cJSON_IsArray(objs) &&
                         cJSON_GetArraySize(objs) <= 64;
    if (ok) {
        if (cJSON_IsString(scene)) snprintf(info->scene_path, sizeof info->scene_path, "%s", scene->valuestring);
        for (const cJSON *it = objs->child; it && ok; it = it->next)
            ok = parse_hex(it, &info->object_hash[info->n_objects++]);
    }
    cJSON_Delete(o);
    if (!ok) return sem_error_set(err, SEM_ERR_PARSE, "%s: not a run description written by sem", path);
    return SEM_OK;
}

/* ---- frame state files ---- */

static void state_path(const char *dir, int digits, int frame, char *out, size_t size)
{
    snprintf(out, size, "%s/state/frame_%0*d.state", dir, digits, frame);
}

static void put(FILE *f, sem_fnv *sum, const void *data, size_t n)
{
    fwrite(data, 1, n, f);
    sem_fnv_bytes(sum, data, n);
}

sem_status sem_run_state_write(const char *dir, int digits, unsigned long long run_id,
                               const sem_run_frame_state *s, sem_error *err)
{
    char path[4400];
    state_path(dir, digits, s->frame, path, sizeof path);
    sem_atomic_file f;
    sem_status st = sem_atomic_open(&f, path, err);
    if (st != SEM_OK) return st;
    sem_fnv sum;
    sem_fnv_init(&sum);
    uint32_t version = STATE_VERSION, bom = STATE_BYTE_ORDER;
    uint64_t id = run_id;
    int32_t frame = s->frame, n_objects = s->n_objects, n_stats = s->n_stats;
    int64_t steps = s->steps;
    put(f.fp, &sum, state_magic, sizeof state_magic);
    put(f.fp, &sum, &version, sizeof version);
    put(f.fp, &sum, &bom, sizeof bom);
    put(f.fp, &sum, &id, sizeof id);
    put(f.fp, &sum, &frame, sizeof frame);
    put(f.fp, &sum, &n_objects, sizeof n_objects);
    put(f.fp, &sum, &steps, sizeof steps);
    put(f.fp, &sum, &s->time, sizeof s->time);
    put(f.fp, &sum, &n_stats, sizeof n_stats);
    put(f.fp, &sum, s->stats, (size_t)s->n_stats * sizeof(double));
    for (int i = 0; i < s->n_objects; ++i) {
        uint64_t n = s->n[i];
        put(f.fp, &sum, &n, sizeof n);
        put(f.fp, &sum, s->q[i], s->n[i] * sizeof(double));
        put(f.fp, &sum, s->v[i], s->n[i] * sizeof(double));
    }
    uint64_t h = sum.h;
    fwrite(&h, 1, sizeof h, f.fp);
    return sem_atomic_commit(&f, err);
}

typedef struct reader {
    const unsigned char *p;
    size_t left;
} reader;

static int take(reader *r, void *out, size_t n)
{
    if (n > r->left) return 0;
    memcpy(out, r->p, n);
    r->p += n;
    r->left -= n;
    return 1;
}

void sem_run_frame_state_free(sem_run_frame_state *s)
{
    for (int i = 0; i < s->n_objects; ++i) {
        if (s->q) free(s->q[i]);
        if (s->v) free(s->v[i]);
    }
    free(s->q);
    free(s->v);
    free(s->n);
    memset(s, 0, sizeof *s);
}

sem_status sem_run_state_read(const char *dir, int digits, int frame, unsigned long long run_id,
                              int n_objects, const size_t *dofs, sem_run_frame_state *s,
                              sem_error *err)
{
    memset(s, 0, sizeof *s);
    char path[4400];
    state_path(dir, digits, frame, path, sizeof path);
    char *data = NULL;
    size_t size = 0;
    sem_status st = sem_read_file(path, MAX_STATE_BYTES, "2 GiB for a state file", &data, &size, err);
    if (st != SEM_OK) return st;
    const char *bad = NULL;
    if (size < sizeof state_magic + 8 || memcmp(data, state_magic, sizeof state_magic) != 0) {
        bad = "not a sem state file";
    } else {
        sem_fnv sum;
        sem_fnv_init(&sum);
        sem_fnv_bytes(&sum, data, size - 8);
        uint64_t stored;
        memcpy(&stored, data + size - 8, 8);
        if (stored != sum.h) bad = "damaged or incomplete (checksum mismatch)";
    }
    reader r = {(const unsigned char *)data + sizeof state_magic, size - 8 - sizeof state_magic};
    uint32_t version = 0, bom = 0;
    uint64_t id = 0;
    int32_t fr = 0, no = 0, ns = 0;
    int64_t steps = 0;
    if (!bad && !(take(&r, &version, 4) && take(&r, &bom, 4) && take(&r, &id, 8) &&
                  take(&r, &fr, 4) && take(&r, &no, 4) && take(&r, &steps, 8) &&
                  take(&r, &s->time, 8) && take(&r, &ns, 4)))
        bad = "truncated";
    if (!bad && (version != STATE_VERSION || bom != STATE_BYTE_ORDER))
        bad = "written by another version of sem or another byte order";
    if (!bad && id != run_id) bad = "belongs to another run";
    if (!bad && (fr != frame || no != n_objects || ns < 0 || ns > SEM_RUN_MAX_STATS || steps < 0))
        bad = "inconsistent header";
    if (!bad && !take(&r, s->stats, (size_t)ns * sizeof(double))) bad = "truncated";
    if (!bad) {
        s->frame = fr;
        s->steps = steps;
        s->n_stats = ns;
        s->n = calloc((size_t)n_objects + 1, sizeof *s->n);
        s->q = calloc((size_t)n_objects + 1, sizeof *s->q);
        s->v = calloc((size_t)n_objects + 1, sizeof *s->v);
        if (!s->n || !s->q || !s->v) {
            free(data);
            sem_run_frame_state_free(s);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        s->n_objects = n_objects;
        for (int i = 0; i < n_objects && !bad; ++i) {
            uint64_t n = 0;
            if (!take(&r, &n, 8) || n != dofs[i]) {
                bad = "sizes do not match the scene's objects";
                break;
            }
            s->n[i] = (size_t)n;
            s->q[i] = malloc(n * sizeof(double) + 1);
            s->v[i] = malloc(n * sizeof(double) + 1);
            if (!s->q[i] || !s->v[i]) {
                free(data);
                sem_run_frame_state_free(s);
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            }
            if (!take(&r, s->q[i], n * sizeof(double)) || !take(&r, s->v[i], n * sizeof(double)))
                bad = "truncated";
        }
        if (!bad && r.left != 0) bad = "trailing bytes";
    }
    free(data);
    if (bad) {
        sem_run_frame_state_free(s);
        return sem_error_set(err, SEM_ERR_PARSE, "%s: %s", path, bad);
    }
    return SEM_OK;
}

/* ---- the folder ---- */

/* Files a run writes into its folder: frame_<digit>..., animation.<ext> (USD, glTF),
 * preprocess_<digit>....semdisc (what sem render colours by), summary.json, and their
 * temporaries (NAME.tmp.XXXXXX). */
static int run_file(const char *name)
{
    if (strncmp(name, "frame_", 6) == 0 && isdigit((unsigned char)name[6])) return 1;
    if (strncmp(name, "preprocess_", 11) == 0 && isdigit((unsigned char)name[11])) return 1;
    if (strncmp(name, "animation.", 10) == 0) return 1;
    if (strncmp(name, "summary.json", 12) == 0) return 1;
    return 0;
}

int sem_run_folder_in_use(const char *dir, char *example, size_t size)
{
    if (example && size) example[0] = '\0';
    DIR *d = opendir(dir);
    if (!d) return 0;
    int found = 0;
    for (struct dirent *e; !found && (e = readdir(d));) {
        if (run_file(e->d_name) || strcmp(e->d_name, "state") == 0) {
            found = 1;
            if (example) snprintf(example, size, "%s", e->d_name);
        }
    }
    closedir(d);
    return found;
}

static sem_status clear_matching(const char *dir, int in_state, sem_error *err)
{
    DIR *d = opendir(dir);
    if (!d) {
        if (errno == ENOENT) return SEM_OK;
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot list: %s", dir, strerror(errno));
    }
    sem_status st = SEM_OK;
    for (struct dirent *e; st == SEM_OK && (e = readdir(d));) {
        const char *n = e->d_name;
        int ours = in_state ? (strncmp(n, "frame_", 6) == 0 || strncmp(n, "run.json", 8) == 0)
                            : run_file(n);
        if (!ours) continue;
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, n);
        struct stat sb;
        if (lstat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) continue;
        if (unlink(path) != 0 && errno != ENOENT)
            st = sem_error_set(err, SEM_ERR_IO, "%s: cannot remove: %s", path, strerror(errno));
    }
    closedir(d);
    return st;
}

sem_status sem_run_folder_clear(const char *dir, sem_error *err)
{
    char sdir[4200];
    state_dir(dir, sdir, sizeof sdir);
    sem_status st = clear_matching(sdir, 1, err);
    if (st == SEM_OK && rmdir(sdir) != 0 && errno != ENOENT && errno != ENOTEMPTY && errno != EEXIST)
        st = sem_error_set(err, SEM_ERR_IO, "%s: cannot remove: %s", sdir, strerror(errno));
    if (st == SEM_OK) st = clear_matching(dir, 0, err);
    return st;
}
