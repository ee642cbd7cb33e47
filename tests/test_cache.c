/*
 * test_cache.c - the bounded preprocessing cache (sem/cache.h).
 *
 * Properties:
 *  - a stored discretization is loaded back for the same model and settings, and missed for
 *    other settings;
 *  - the folder stays within its bound: the least recently used entry goes first (a hit
 *    refreshes an entry), an entry larger than the whole bound is not stored;
 *  - a damaged entry (one flipped byte) and a forged one (right checksum and hash, sizes of
 *    another model) are misses with a reason, never a crash;
 *  - `sem preprocess` fills the entry that `sem run` then reads (preprocess_cached).
 */
#include <cjson/cJSON.h>
#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <time.h>
#include <utime.h>

#include "sem/cache.h"
#include "sem/primitives.h"
#include "test_util.h"

static long long folder_bytes(const char *dir, int *entries)
{
    long long total = 0;
    *entries = 0;
    DIR *d = opendir(dir);
    if (!d) return 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (!strstr(e->d_name, ".semdisc")) continue;
        char path[1024];
        snprintf(path, sizeof path, "%s/%s", dir, e->d_name);
        struct stat sb;
        if (stat(path, &sb) == 0) {
            total += sb.st_size;
            (*entries)++;
        }
    }
    closedir(d);
    return total;
}

static long long file_size(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0 ? (long long)sb.st_size : -1;
}

/* Sets a file's modification time to `t` seconds after 2020 (LRU order without sleeping). */
static void set_age(const char *path, long t)
{
    struct utimbuf u = {1577836800 + t, 1577836800 + t};
    utime(path, &u);
}

static void test_library(const char *tmp)
{
    char dir[600];
    snprintf(dir, sizeof dir, "%s/lib_cache", tmp);
    sem_error err;
    sem_model *box = sem_model_create();
    sem_box_def bd = sem_default_box_def();
    CHECK(box && sem_primitive_box(box, &bd, &err) == SEM_OK, "box: %s", err.message);
    if (!box) return;
    sem_preprocess_options o[3];
    sem_discretization *d[3] = {NULL, NULL, NULL};
    char path[3][700];
    for (int k = 0; k < 3; ++k) {
        o[k] = sem_default_preprocess_options();
        o[k].order = 1;
        o[k].rays[0] = o[k].rays[1] = 2 + k;
        o[k].points_per_interval = 1;
        CHECK(sem_preprocess(box, &o[k], &d[k], &err) == SEM_OK, "preprocess: %s", err.message);
        sem_cache_entry_path(dir, box, &o[k], path[k], sizeof path[k]);
    }
    if (!d[0] || !d[1] || !d[2]) goto done;

    /* store and load back; other settings miss */
    CHECK(sem_cache_store(dir, 0, box, &o[0], d[0], &err) == SEM_OK, "store: %s", err.message);
    sem_discretization *got = NULL;
    CHECK(sem_cache_load(dir, box, &o[0], &got, &err) == SEM_OK && got && got->n_quad == d[0]->n_quad,
          "load: %s", err.message);
    sem_discretization_destroy(got);
    got = NULL;
    CHECK(sem_cache_load(dir, box, &o[1], &got, &err) != SEM_OK && !got, "other settings miss");

    /* bound: room for two entries; storing a third removes the least recently used */
    long long size = file_size(path[0]);
    CHECK(size > 0, "entry size %lld", size);
    long long bound = 2 * size + size / 2;
    CHECK(sem_cache_store(dir, bound, box, &o[1], d[1], &err) == SEM_OK, "store 1: %s", err.message);
    set_age(path[0], 100);
    set_age(path[1], 200);
    /* a hit on entry 0 makes it the most recent one */
    CHECK(sem_cache_load(dir, box, &o[0], &got, &err) == SEM_OK, "hit: %s", err.message);
    sem_discretization_destroy(got);
    got = NULL;
    CHECK(sem_cache_store(dir, bound, box, &o[2], d[2], &err) == SEM_OK, "store 2: %s", err.message);
    int entries = 0;
    long long total = folder_bytes(dir, &entries);
    CHECK(total <= bound && entries == 2, "folder %lld bytes in %d entries, bound %lld", total, entries,
          bound);
    CHECK(file_size(path[0]) > 0 && file_size(path[1]) < 0 && file_size(path[2]) > 0,
          "the least recently used entry (1) went: %lld %lld %lld", file_size(path[0]),
          file_size(path[1]), file_size(path[2]));

    /* an entry larger than the whole bound is not stored (and nothing else is removed) */
    CHECK(sem_cache_store(dir, size / 2, box, &o[1], d[1], &err) != SEM_OK &&
              strstr(err.message, "not cached"),
          "oversized entry: %s", err.message);
    CHECK(file_size(path[1]) < 0, "oversized entry not kept");

    /* a damaged entry is a miss with a reason */
    FILE *f = fopen(path[0], "r+b");
    if (f) {
        fseek(f, 200, SEEK_SET);
        int c = fgetc(f);
        fseek(f, 200, SEEK_SET);
        fputc(c ^ 0x40, f);
        fclose(f);
    }
    CHECK(sem_cache_load(dir, box, &o[0], &got, &err) != SEM_OK && !got &&
              strstr(err.message, "checksum"),
          "damaged entry: %s", err.message);

    /* a forged entry: another model's data under this model's name, valid in itself */
    sem_model *sphere = sem_model_create();
    sem_sphere_def sd = sem_default_sphere_def();
    CHECK(sphere && sem_primitive_sphere(sphere, &sd, &err) == SEM_OK, "sphere");
    sem_discretization *ds = NULL;
    if (sphere && sem_preprocess(sphere, &o[0], &ds, &err) == SEM_OK) {
        ds->model_hash = sem_preprocess_hash(box, &o[0]);
        CHECK(sem_discretization_save(ds, path[0], &err) == SEM_OK, "forge: %s", err.message);
        CHECK(sem_cache_load(dir, box, &o[0], &got, &err) != SEM_OK && !got &&
                  strstr(err.message, "does not fit"),
              "forged entry: %s", err.message);
    } else {
        CHECK(0, "sphere preprocess: %s", err.message);
    }
    sem_discretization_destroy(ds);
    sem_model_destroy(sphere);
done:
    for (int k = 0; k < 3; ++k) sem_discretization_destroy(d[k]);
    sem_model_destroy(box);
}

/* sem preprocess fills the entry sem run reads */
static void test_commands(const char *tmp)
{
    char cache[600], model[600], scene[600], args[2400], out[8192], errb[8192];
    snprintf(cache, sizeof cache, "%s/cli_cache", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    snprintf(model, sizeof model, "%s/box.igs", tmp);
    snprintf(args, sizeof args, "primitive box -o %s", model);
    CHECK(test_run_cli(args, out, sizeof out, errb, sizeof errb) == 0, "primitive: %s", errb);
    snprintf(args, sizeof args, "preprocess %s --order 1 --rays 3 3 --points-per-interval 2 -E 2e6",
             model);
    int rc = test_run_cli(args, out, sizeof out, errb, sizeof errb);
    CHECK(rc == 0 && strstr(out, "cached in"), "preprocess exit %d: %s%s", rc, out, errb);
    snprintf(scene, sizeof scene, "%s/scene.json", tmp);
    FILE *f = fopen(scene, "w");
    if (f) {
        fprintf(f, "{\"objects\": [{\"model\": \"box.igs\", \"material\": {\"youngs_modulus\": 2e6},"
                   " \"sem\": {\"order\": 1, \"rays\": [3, 3], \"points_per_interval\": 2},"
                   " \"pin\": {\"box\": [[-1, -1, -0.6], [1, 1, -0.4]]}}], \"frames\": 1}\n");
        fclose(f);
    }
    snprintf(args, sizeof args, "run %s --out %s/run --json --quiet", scene, tmp);
    rc = test_run_cli(args, out, sizeof out, errb, sizeof errb);
    cJSON *j = rc == 0 ? cJSON_Parse(out) : NULL;
    const cJSON *c = j ? cJSON_GetObjectItemCaseSensitive(j, "preprocess_cached") : NULL;
    CHECK(cJSON_IsTrue(c), "sem run reuses what sem preprocess stored (exit %d): %s", rc, errb);
    cJSON_Delete(j);
    /* --no-cache stores nothing */
    snprintf(cache, sizeof cache, "%s/cli_cache2", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    snprintf(args, sizeof args, "preprocess %s --order 1 --rays 3 3 --no-cache", model);
    rc = test_run_cli(args, out, sizeof out, errb, sizeof errb);
    int entries = 0;
    folder_bytes(cache, &entries);
    CHECK(rc == 0 && entries == 0, "--no-cache: exit %d, %d entries", rc, entries);
}

int main(void)
{
    const char *tmp = test_tmpdir();
    test_library(tmp);
    test_commands(tmp);
    return test_finish("test_cache");
}
