/* make_dirs.c - mkdir -p (see util/make_dirs.h). */
#include "util/make_dirs.h"

#include <errno.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>

sem_status sem_make_dirs(const char *path, sem_error *err)
{
    char tmp[4096];
    if (!path || !path[0]) return sem_error_set(err, SEM_ERR_INVALID, "no folder name");
    if (strlen(path) >= sizeof tmp)
        return sem_error_set(err, SEM_ERR_INVALID, "folder name too long (%zu characters)", strlen(path));
    snprintf(tmp, sizeof tmp, "%s", path);
    for (char *p = tmp + 1; *p; ++p) {
        if (*p != '/') continue;
        *p = '\0';
        if (mkdir(tmp, 0777) != 0 && errno != EEXIST)
            return sem_error_set(err, SEM_ERR_IO, "%s: cannot create folder: %s", tmp, strerror(errno));
        *p = '/';
    }
    if (mkdir(tmp, 0777) != 0 && errno != EEXIST)
        return sem_error_set(err, SEM_ERR_IO, "%s: cannot create folder: %s", tmp, strerror(errno));
    struct stat st;
    if (stat(tmp, &st) != 0 || !S_ISDIR(st.st_mode))
        return sem_error_set(err, SEM_ERR_IO, "%s: exists and is not a folder", tmp);
    return SEM_OK;
}
