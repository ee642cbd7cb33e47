/*
 * fuzz_cache.c - the preprocessing cache file (.semdisc) reader.
 *
 * The file ends with an FNV-1a 64 checksum of everything before it, which random changes
 * almost never match; the harness writes the right checksum into the last 8 bytes first,
 * so that the fuzzer explores the structure checks behind it (counts, sparse patterns,
 * index ranges), as a deliberately forged cache file would.
 */
#include "fuzz.h"
#include "sem/preprocess.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    unsigned char *copy = malloc(size + 1);
    if (!copy) return 0;
    memcpy(copy, data, size);
    if (size >= 16) {
        uint64_t h = 14695981039346656037ull;
        for (size_t i = 0; i + 8 < size; ++i) {
            h ^= copy[i];
            h *= 1099511628211ull;
        }
        memcpy(copy + size - 8, &h, 8);
    }
    sem_discretization *d = NULL;
    sem_error err;
    sem_error_clear(&err);
    sem_status st = sem_discretization_load_buffer("fuzz.semdisc", copy, size, 0, &d, &err);
    fuzz_check_error(st, &err);
    sem_discretization_destroy(d);
    free(copy);
    return 0;
}
