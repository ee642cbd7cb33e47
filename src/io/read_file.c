/* read_file.c - regular files only, size checked before reading (see io/read_file.h). */
#include "io/read_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *kind_of(mode_t mode)
{
    if (S_ISDIR(mode)) return "a folder";
    if (S_ISFIFO(mode)) return "a FIFO";
    if (S_ISCHR(mode)) return "a character device";
    if (S_ISBLK(mode)) return "a block device";
    if (S_ISSOCK(mode)) return "a socket";
    return "a special file";
}

/* Opens path without blocking (a FIFO with no writer would wait) and checks that it is a
 * regular file of at most max_bytes: *fd and *st on success, nothing open on failure. */
static sem_status open_regular(const char *path, long long max_bytes, const char *limit_name,
                               int *fd, struct stat *st, sem_error *err)
{
    *fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC);
    if (*fd < 0) return sem_error_set(err, SEM_ERR_IO, "%s: cannot open: %s", path, strerror(errno));
    sem_status status = SEM_OK;
    if (fstat(*fd, st) != 0)
        status = sem_error_set(err, SEM_ERR_IO, "%s: cannot read: %s", path, strerror(errno));
    else if (!S_ISREG(st->st_mode))
        status = sem_error_set(err, SEM_ERR_IO, "%s: not a regular file (%s); only regular files "
                                                "are read", path, kind_of(st->st_mode));
    else if ((long long)st->st_size > max_bytes)
        status = sem_error_set(err, SEM_ERR_IO, "%s: file of %lld bytes is larger than %lld bytes "
                                                "(limit %s)",
                               path, (long long)st->st_size, max_bytes, limit_name);
    if (status != SEM_OK) {
        close(*fd);
        *fd = -1;
    }
    return status;
}

sem_status sem_check_regular_file(const char *path, long long max_bytes, const char *limit_name,
                                  sem_error *err)
{
    int fd;
    struct stat st;
    sem_status status = open_regular(path, max_bytes, limit_name, &fd, &st, err);
    if (status == SEM_OK) close(fd);
    return status;
}

sem_status sem_read_file(const char *path, long long max_bytes, const char *limit_name,
                         char **data, size_t *len, sem_error *err)
{
    *data = NULL;
    *len = 0;
    int fd;
    struct stat st;
    sem_status status = open_regular(path, max_bytes, limit_name, &fd, &st, err);
    if (status != SEM_OK) return status;
    /* the file may still grow while we read: read at most max_bytes + 1 and fail then */
    size_t cap = (size_t)st.st_size + 1, n = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        close(fd);
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory reading %zu bytes", path, cap);
    }
    for (;;) {
        if (n == cap) {
            if ((long long)cap > max_bytes) {
                free(buf);
                close(fd);
                return sem_error_set(err, SEM_ERR_IO, "%s: file grew beyond %lld bytes while "
                                                      "being read (limit %s)",
                                     path, max_bytes, limit_name);
            }
            size_t nc = cap * 2 > (size_t)max_bytes + 1 ? (size_t)max_bytes + 1 : cap * 2;
            char *b = realloc(buf, nc + 1);
            if (!b) {
                free(buf);
                close(fd);
                return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
            }
            buf = b;
            cap = nc;
        }
        ssize_t got = read(fd, buf + n, cap - n);
        if (got < 0) {
            if (errno == EINTR) continue;
            int e = errno;
            free(buf);
            close(fd);
            return sem_error_set(err, SEM_ERR_IO, "%s: read error: %s", path, strerror(e));
        }
        if (got == 0) break;
        n += (size_t)got;
    }
    close(fd);
    buf[n] = '\0';
    *data = buf;
    *len = n;
    return SEM_OK;
}
