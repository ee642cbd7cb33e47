/*
 * threads.h - how many threads a parallel region of the library uses (internal).
 *
 * The library never changes OpenMP's settings for the process (no omp_set_num_threads): a
 * caller's thread count travels as an argument, and every parallel region that should honour
 * it says num_threads(sem_threads(requested)). Results do not depend on the count.
 */
#ifndef SEM_UTIL_THREADS_H
#define SEM_UTIL_THREADS_H

#ifdef _OPENMP
#include <omp.h>
#endif

/* The caller's count when positive, else OpenMP's default (OMP_NUM_THREADS or the cores). */
static inline int sem_threads(int requested)
{
#ifdef _OPENMP
    return requested > 0 ? requested : omp_get_max_threads();
#else
    (void)requested;
    return 1;
#endif
}

#endif
