/* cache.c - the bounded preprocessing cache (see sem/cache.h). */
#include "sem/cache.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "util/make_dirs.h"

#define ENTRY_SUFFIX ".semdisc"
/* a temporary older than this was left by a writer that was killed */
#define STALE_TEMPORARY_SECONDS 3600

void sem_cache_entry_path(const char *dir, const sem_model *model,
                          const sem_preprocess_options *options, char *out, size_t size)
{
    snprintf(out, size, "%s/%016llx" ENTRY_SUFFIX, dir, sem_preprocess_hash(model, options));
}

/* The discretization must be the model's: a forged entry with the right hash but other
 * sizes would index past the model's arrays. */
static int fits_model(const sem_discretization *d, const sem_model *model)
{
    if (d->n_parts != model->n_parts || (size_t)d->n_ctrl != sem_model_control_points(model))
        return 0;
    long long offset = 0;
    for (int i = 0; i < model->n_parts; ++i) {
        if (d->part_ctrl_offset[i] != offset) return 0;
        offset += (long long)model->parts[i].surface.n_u * model->parts[i].surface.n_v;
    }
    return d->part_ctrl_offset[model->n_parts] == offset;
}

sem_status sem_cache_load(const char *dir, const sem_model *model,
                          const sem_preprocess_options *options, sem_discretization **out,
                          sem_error *err)
{
    *out = NULL;
    char path[4200];
    sem_cache_entry_path(dir, model, options, path, sizeof path);
    sem_status st = sem_discretization_load(path, sem_preprocess_hash(model, options), out, err);
    if (st != SEM_OK) return st;
    if (!(*out)->part_ctrl_offset || !fits_model(*out, model)) {
        sem_discretization_destroy(*out);
        *out = NULL;
        return sem_error_set(err, SEM_ERR_INVALID, "%s: cached data does not fit the model", path);
    }
    /* a hit makes the entry the most recently used one */
    utimensat(AT_FDCWD, path, NULL, 0);
    return SEM_OK;
}

sem_status sem_cache_store(const char *dir, long long max_bytes, const sem_model *model,
                           const sem_preprocess_options *options, const sem_discretization *d,
                           sem_error *err)
{
    /* a folder that cannot be made fails the store below, naming the file */
    sem_error ignored;
    sem_make_dirs(dir, &ignored);
    char path[4200];
    sem_cache_entry_path(dir, model, options, path, sizeof path);
    sem_status st = sem_discretization_save(d, path, err);
    if (st != SEM_OK) return st;
    const char *name = strrchr(path, '/') + 1;
    struct stat sb;
    if (max_bytes > 0 && stat(path, &sb) == 0 && sb.st_size > max_bytes) {
        unlink(path);
        return sem_error_set(err, SEM_ERR_IO, "%s: %lld bytes is more than the whole cache may "
                                              "hold (%lld bytes; SEM_CACHE_MAX_MB); not cached",
                             path, (long long)sb.st_size, max_bytes);
    }
    return sem_cache_trim(dir, max_bytes, name, err);
}

typedef struct entry {
    char name[64];
    long long size;
    struct timespec mtime;
} entry;

static int older_first(const void *a, const void *b)
{
    const entry *x = a, *y = b;
    if (x->mtime.tv_sec != y->mtime.tv_sec) return x->mtime.tv_sec < y->mtime.tv_sec ? -1 : 1;
    if (x->mtime.tv_nsec != y->mtime.tv_nsec) return x->mtime.tv_nsec < y->mtime.tv_nsec ? -1 : 1;
    return strcmp(x->name, y->name);
}

/* 16 hex digits + ".semdisc": an entry; with ".tmp." after it: a temporary. */
static int entry_kind(const char *name)
{
    size_t n = strlen(name), k = 0;
    while (k < 16 && ((name[k] >= '0' && name[k] <= '9') || (name[k] >= 'a' && name[k] <= 'f'))) ++k;
    if (k != 16 || strncmp(name + 16, ENTRY_SUFFIX, strlen(ENTRY_SUFFIX)) != 0) return 0;
    size_t end = 16 + strlen(ENTRY_SUFFIX);
    if (n == end) return 1;
    return strncmp(name + end, ".tmp.", 5) == 0 ? 2 : 0;
}

sem_status sem_cache_trim(const char *dir, long long max_bytes, const char *keep, sem_error *err)
{
    DIR *d = opendir(dir);
    if (!d) return errno == ENOENT ? SEM_OK : sem_error_set(err, SEM_ERR_IO, "%s: %s", dir, strerror(errno));
    entry *list = NULL;
    size_t n = 0, cap = 0;
    long long total = 0;
    time_t now = time(NULL);
    for (struct dirent *e; (e = readdir(d));) {
        int kind = entry_kind(e->d_name);
        if (!kind || strlen(e->d_name) >= sizeof list[0].name) continue;
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat sb;
        if (lstat(path, &sb) != 0 || !S_ISREG(sb.st_mode)) continue;
        if (kind == 2) {
            if (now - sb.st_mtime > STALE_TEMPORARY_SECONDS) unlink(path);
            continue;
        }
        if (n == cap) {
            cap = cap ? 2 * cap : 64;
            entry *x = realloc(list, cap * sizeof *x);
            if (!x) {
                free(list);
                closedir(d);
                return sem_error_set(err, SEM_ERR_NOMEM, "out of memory listing %s", dir);
            }
            list = x;
        }
        snprintf(list[n].name, sizeof list[n].name, "%s", e->d_name);
        list[n].size = (long long)sb.st_size;
        list[n].mtime = sb.st_mtim;
        total += list[n].size;
        n++;
    }
    closedir(d);
    if (max_bytes > 0 && total > max_bytes) {
        qsort(list, n, sizeof *list, older_first);
        for (size_t i = 0; i < n && total > max_bytes; ++i) {
            if (keep && strcmp(list[i].name, keep) == 0) continue;
            char path[4400];
            snprintf(path, sizeof path, "%s/%s", dir, list[i].name);
            if (unlink(path) == 0 || errno == ENOENT) total -= list[i].size;
        }
    }
    free(list);
    return SEM_OK;
}
