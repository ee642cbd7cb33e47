/*
 * free_all.h - lets go of a list of buffers in one statement (internal). The destructors of
 * the structs that own many arrays, and the out-of-memory paths that drop several buffers at
 * once, name what they own in one list instead of one free() a line.
 */
#ifndef SEM_UTIL_FREE_ALL_H
#define SEM_UTIL_FREE_ALL_H

#include <stddef.h>
#include <stdlib.h>

/* Frees pointers[0..count-1], in that order (any of them may be NULL). */
static inline void sem_free_each(void *const *pointers, size_t count)
{
    for (size_t i = 0; i < count; ++i) free(pointers[i]);
}

/* SEM_FREE_ALL(a, b, c): free(a); free(b); free(c); */
#define SEM_FREE_ALL(...)                                                                    \
    sem_free_each((void *const[]){__VA_ARGS__}, sizeof((void *const[]){__VA_ARGS__}) / sizeof(void *))

#endif
