/*
 * make_dirs.h - a folder and every folder above it that is missing (mkdir -p).
 */
#ifndef SEM_UTIL_MAKE_DIRS_H
#define SEM_UTIL_MAKE_DIRS_H

#include "sem/status.h"

/* Creates path and its missing ancestors (mode 0777, less the umask). SEM_ERR_IO, naming the
 * first folder that could not be made, when one cannot be, or when path exists and is not a
 * folder. */
sem_status sem_make_dirs(const char *path, sem_error *err);

#endif
