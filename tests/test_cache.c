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
 *  - `sem preprocess` fills the entry that `sem run` then reads (preprocess_cached);
 *  - corrupted files with a valid checksum (every size field near INT32_MAX, NaN values,
 *    flipped bytes all over the file) fail with one line, or load a consistent object.
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

static unsigned long long fnv(const unsigned char *p, size_t n)
{
    unsigned long long h = 14695981039346656037ull;
    for (size_t i = 0; i < n; ++i) {
        h ^= p[i];
        h *= 1099511628211ull;
    }
    return h;
}

/* Loads a variant of `good` (the checksum recomputed, as a forger would) and checks that it
 * fails with a message or loads; the sanitized build checks the memory accesses. */
static void load_variant(unsigned char *data, size_t size, const char *what)
{
    unsigned long long h = fnv(data, size - 8);
    memcpy(data + size - 8, &h, 8);
    sem_discretization *d = NULL;
    sem_error err;
    sem_error_clear(&err);
    sem_status st = sem_discretization_load_buffer(what, data, size, 0, &d, &err);
    CHECK(st == SEM_OK ? d != NULL : (d == NULL && err.message[0] != '\0'), "%s: status %d, '%s'",
          what, (int)st, err.message);
    if (st == SEM_OK) CHECK(d->n_ctrl >= 0 && d->n_quad >= 0, "%s: sizes", what);
    sem_discretization_destroy(d);
}

static void test_corrupted(void)
{
    char path[700];
    snprintf(path, sizeof path, "%s/../../fuzz/corpus/cache/sphere_order2.semdisc", SEM_TEST_DATA);
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL, "%s", path);
    if (!f) return;
    fseek(f, 0, SEEK_END);
    size_t size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    unsigned char *good = malloc(size), *v = malloc(size);
    size_t got = good ? fread(good, 1, size, f) : 0;
    fclose(f);
    if (!good || !v || got != size) {
        CHECK(0, "read %s", path);
        free(good);
        free(v);
        return;
    }
    /* the seed itself loads: it must be of the current format, or every variant below would
     * stop at the version check (the seeds are remade by the commands in docs/reliability.md
     * "Fuzzing" when the format changes) */
    {
        sem_discretization *d = NULL;
        sem_error err;
        CHECK(sem_discretization_load_buffer("seed", good, size, 0, &d, &err) == SEM_OK && d && d->n_parts == 1 &&
                  d->order == 2 && d->n_quad > 0 && sem_csr_nnz(&d->Pi) > 0,
              "the seed sphere_order2.semdisc loads: %s", d ? "" : err.message);
        sem_discretization_destroy(d);
    }
    /* the 7 int32 sizes after magic, version, byte order and hash */
    static const int32_t huge[] = {0x7fffffff, -1, 0x40000000, 3};
    for (int k = 0; k < 7; ++k)
        for (size_t h = 0; h < sizeof huge / sizeof huge[0]; ++h) {
            memcpy(v, good, size);
            memcpy(v + 24 + 4 * k, &huge[h], 4);
            char what[64];
            snprintf(what, sizeof what, "size field %d = %d", k, huge[h]);
            load_variant(v, size, what);
        }
    /* every 8-byte word in turn set to NaN, then to an all-ones count (sampled every 97
     * words: every array of the file gets hits) */
    static const unsigned char nan[8] = {0, 0, 0, 0, 0, 0, 0xf8, 0x7f};
    for (size_t at = 24; at + 16 <= size; at += 8 * 97) {
        memcpy(v, good, size);
        memcpy(v + at, nan, 8);
        load_variant(v, size, "NaN word");
        memcpy(v, good, size);
        memset(v + at, 0xff, 8);
        load_variant(v, size, "all-ones word");
    }
    /* truncated at many lengths */
    for (size_t n = 16; n < size; n += size / 53 + 1) {
        memcpy(v, good, n);
        load_variant(v, n, "truncated");
    }
    free(good);
    free(v);
}

int main(void)
{
    test_corrupted();
    const char *tmp = test_tmpdir();
    test_library(tmp);
    test_commands(tmp);
    return test_finish("test_cache");
}
