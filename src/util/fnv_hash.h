/*
 * fnv_hash.h - FNV-1a, 64 bits: the hash of the preprocessing cache's keys and files
 * (preprocess.c) and of the runs a stopped run may be resumed from (output/run_state.c).
 * Not for security: fast, and the same bits on every machine for the same bytes.
 */
#ifndef SEM_UTIL_FNV_HASH_H
#define SEM_UTIL_FNV_HASH_H

#include <stddef.h>
#include <stdint.h>

typedef struct sem_fnv {
    uint64_t h;
} sem_fnv;

static inline void sem_fnv_init(sem_fnv *f) { f->h = 14695981039346656037ull; }

static inline void sem_fnv_bytes(sem_fnv *f, const void *data, size_t n)
{
    const unsigned char *p = data;
    uint64_t h = f->h;
    for (size_t k = 0; k < n; ++k) {
        h ^= p[k];
        h *= 1099511628211ull;
    }
    f->h = h;
}

#endif
