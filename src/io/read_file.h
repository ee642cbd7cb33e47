/*
 * io/read_file.h - the one way every reader takes a file into memory.
 *
 * Why: fopen + fread loops read whatever the path names. A model path that is a link to
 * /dev/zero reads until memory runs out, a FIFO blocks forever with no message, and a
 * folder fails with a confusing read error. Here the file is opened without blocking
 * (O_NONBLOCK: opening a FIFO with no writer would wait), checked with fstat to be a
 * regular file no larger than the caller's limit, and read whole; nothing is allocated
 * before those checks pass.
 */
#ifndef SEM_IO_READ_FILE_H
#define SEM_IO_READ_FILE_H

#include <stddef.h>

#include "sem/status.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Reads the regular file `path` into a malloc'ed buffer (NUL-terminated, *len bytes
 * before the NUL). Fails with one line naming the path: cannot open, not a regular file,
 * larger than max_bytes ("... (limit LIMIT_NAME)"), read error. */
sem_status sem_read_file(const char *path, long long max_bytes, const char *limit_name,
                         char **data, size_t *len, sem_error *err);
/* The same checks without reading, for a reader that opens the file itself (STEP through
 * Open CASCADE): cannot open, not a regular file, larger than max_bytes. */
sem_status sem_check_regular_file(const char *path, long long max_bytes, const char *limit_name,
                                  sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
