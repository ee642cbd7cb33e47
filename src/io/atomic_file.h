/*
 * io/atomic_file.h - all-or-nothing file output for every writer (IGES, OBJ, meshes).
 *
 * Why: a simulation writes a frame file while a viewer or CAD tool may be reading the
 * previous one, and a crash or a full disk must never leave a truncated model behind.
 * The data goes to "path.tmp.XXXXXX" in the same folder (same file system, so the final
 * rename is atomic), is flushed and fsync'ed, then renamed over path. On any failure the
 * temporary file is removed and path is left untouched.
 * Implemented in atomic_file.c.
 */
#ifndef SEM_IO_ATOMIC_FILE_H
#define SEM_IO_ATOMIC_FILE_H

#include <stdio.h>

#include "sem/status.h"

typedef struct sem_atomic_file {
    FILE *fp;        /* write here */
    char *path;      /* final name */
    char *tmp_path;  /* temporary name */
} sem_atomic_file;

/* Creates the temporary file. On failure nothing exists on disk. */
sem_status sem_atomic_open(sem_atomic_file *file, const char *path, sem_error *err);
/* Flushes, syncs, closes and renames over path; on failure removes the temporary file. */
sem_status sem_atomic_commit(sem_atomic_file *file, sem_error *err);
/* Closes and removes the temporary file (after a write error). Safe to call twice. */
void sem_atomic_abort(sem_atomic_file *file);

#endif
