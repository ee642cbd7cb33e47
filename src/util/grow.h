/*
 * grow.h - a growing array's capacity (internal): the one doubling rule the readers, the
 * quadratures and contact's term lists use for arrays whose length is not known in advance.
 */
#ifndef SEM_UTIL_GROW_H
#define SEM_UTIL_GROW_H

#include <stddef.h>

/* Makes *p (an array of elem-byte items with capacity *cap) hold at least `need` items:
 * capacity `first` at the start, doubled until it holds them; never above `max` items
 * (returns 0 then, and on out of memory, with *p and *cap unchanged). Returns 1 on success. */
int sem_grow(void **p, int *cap, int need, size_t elem, int first, int max);

/* Makes *p an array of `count` elem-byte items (realloc), for the arrays that follow the
 * capacity of another; returns 0 on out of memory, with *p unchanged. */
int sem_resize(void **p, size_t count, size_t elem);

#endif
