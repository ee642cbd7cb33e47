/*
 * atomic_file.c - all-or-nothing file output (temporary file, fsync, rename); see
 * io/atomic_file.h for why. Used by every writer (IGES, OBJ, meshes, USD, summaries).
 */
#include "io/atomic_file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

static void release(sem_atomic_file *f)
{
    free(f->path);
    free(f->tmp_path);
    f->path = f->tmp_path = NULL;
    f->fp = NULL;
}

sem_status sem_atomic_open(sem_atomic_file *f, const char *path, sem_error *err)
{
    memset(f, 0, sizeof *f);
    size_t n = strlen(path);
    f->path = dup_string(path);
    f->tmp_path = malloc(n + sizeof ".tmp.XXXXXX");
    if (!f->path || !f->tmp_path) {
        release(f);
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
    }
    memcpy(f->tmp_path, path, n);
    memcpy(f->tmp_path + n, ".tmp.XXXXXX", sizeof ".tmp.XXXXXX");
    int fd = mkstemp(f->tmp_path);
    if (fd < 0) {
        int e = errno;
        release(f);
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot create a temporary file: %s", path,
                             strerror(e));
    }
    /* mkstemp makes the file 0600; give the result the permissions a plain fopen would
     * (or those of the file it replaces). */
    struct stat st;
    mode_t mode;
    if (stat(path, &st) == 0) {
        mode = st.st_mode & 07777;
    } else {
        mode_t mask = umask(0);
        umask(mask);
        mode = 0666 & ~mask;
    }
    (void)fchmod(fd, mode);
    f->fp = fdopen(fd, "w");
    if (!f->fp) {
        int e = errno;
        close(fd);
        unlink(f->tmp_path);
        release(f);
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot open a temporary file: %s", path,
                             strerror(e));
    }
    return SEM_OK;
}

void sem_atomic_abort(sem_atomic_file *f)
{
    if (f->fp) fclose(f->fp);
    if (f->tmp_path) unlink(f->tmp_path);
    release(f);
}

static void sync_folder(const char *path)
{
    /* make the rename itself durable; best effort */
    char *dir = dup_string(path);
    if (!dir) return;
    char *slash = strrchr(dir, '/');
    if (slash == dir) slash[1] = '\0';
    else if (slash) *slash = '\0';
    else strcpy(dir, ".");
    int fd = open(dir, O_RDONLY);
    if (fd >= 0) {
        (void)fsync(fd);
        close(fd);
    }
    free(dir);
}

sem_status sem_atomic_commit(sem_atomic_file *f, sem_error *err)
{
    if (!f->fp) return sem_error_set(err, SEM_ERR_IO, "atomic file is not open");
    int failed = ferror(f->fp) != 0;
    int e = failed ? EIO : 0;
    if (!failed && fflush(f->fp) != 0) failed = 1, e = errno;
    if (!failed && fsync(fileno(f->fp)) != 0 && errno != EINVAL) failed = 1, e = errno;
    if (fclose(f->fp) != 0 && !failed) failed = 1, e = errno;
    f->fp = NULL;
    if (!failed && rename(f->tmp_path, f->path) != 0) failed = 1, e = errno;
    if (failed) {
        sem_status st = sem_error_set(err, SEM_ERR_IO, "%s: write failed: %s", f->path,
                                      strerror(e));
        unlink(f->tmp_path);
        release(f);
        return st;
    }
    sync_folder(f->path);
    release(f);
    return SEM_OK;
}
