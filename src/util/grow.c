/* grow.c - see grow.h. */
#include "grow.h"

#include <stdlib.h>

int sem_grow(void **p, int *cap, int need, size_t elem, int first, int max)
{
    if (need <= *cap) return 1;
    if (need > max) return 0;
    int nc = *cap ? *cap : first;
    while (nc < need) nc = nc > max / 2 ? max : 2 * nc;
    void *q = realloc(*p, (size_t)nc * elem);
    if (!q) return 0;
    *p = q;
    *cap = nc;
    return 1;
}

int sem_resize(void **p, size_t count, size_t elem)
{
    void *q = realloc(*p, count * elem);
    if (!q) return 0;
    *p = q;
    return 1;
}
