/*
 * cmd_validate.c - `sem validate MODEL [SCENE] [options]`: sem against a finite element
 * solution of the same static problem (gmsh + CalculiX), on the user's own model.
 *
 * The work is done by tools/fem/validate.py (Python standard library only: it drives gmsh,
 * CalculiX and this same sem binary through files, so neither FEM program is ever linked
 * into libsem). This command finds the script and replaces itself with
 *
 *     python3 SCRIPT --sem THIS_BINARY ARGS...
 *
 * Where the script is looked for, first found wins:
 *   $SEM_VALIDATE_SCRIPT                             (tests, development)
 *   <dir of the binary>/../share/sem/fem/validate.py (an installed sem: cmake --install)
 *   SEM_SOURCE_FEM_DIR/validate.py                   (the source tree of this build)
 * python3 is taken from the PATH ($SEM_PYTHON overrides).
 */
#include <errno.h>
#include <limits.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "cli.h"

#define CMD "validate"

static int is_file(const char *path)
{
    return access(path, R_OK) == 0;
}

/* The script's path into out; 0 when none is found. */
static int find_script(const char *self, char *out, size_t size)
{
    const char *env = getenv("SEM_VALIDATE_SCRIPT");
    if (env && *env) {
        snprintf(out, size, "%s", env);
        return is_file(out);
    }
    if (self[0]) {
        char dir[PATH_MAX];
        snprintf(dir, sizeof dir, "%s", self);
        char *slash = strrchr(dir, '/');
        if (slash) {
            *slash = '\0';
            if ((size_t)snprintf(out, size, "%s/../share/sem/fem/validate.py", dir) < size && is_file(out))
                return 1;
        }
    }
#ifdef SEM_SOURCE_FEM_DIR
    if ((size_t)snprintf(out, size, "%s/validate.py", SEM_SOURCE_FEM_DIR) < size && is_file(out)) return 1;
#endif
    return 0;
}

int cmd_validate(int argc, char **argv)
{
    char self[PATH_MAX] = "";
    if (!realpath("/proc/self/exe", self)) self[0] = '\0';
    char script[PATH_MAX + 64];
    if (!find_script(self, script, sizeof script))
        return cli_fail("validate: cannot find validate.py (looked in $SEM_VALIDATE_SCRIPT, "
                        "<bin>/../share/sem/fem and the source tree); reinstall sem");
    const char *python = getenv("SEM_PYTHON");
    if (!python || !*python) python = "python3";
    /* python3 SCRIPT --sem SELF argv[1..] NULL */
    char **args = calloc((size_t)argc + 5, sizeof *args);
    if (!args) return cli_fail("out of memory");
    int k = 0;
    args[k++] = (char *)python;
    args[k++] = script;
    if (self[0]) {
        args[k++] = "--sem";
        args[k++] = self;
    }
    for (int i = 1; i < argc; ++i) args[k++] = argv[i];
    args[k] = NULL;
    fflush(stdout);
    execvp(python, args);
    int e = errno;
    free(args);
    if (e == ENOENT) return cli_fail("validate needs %s, which is not installed (Debian: apt-get install python3)", python);
    return cli_fail("validate: cannot run %s: %s", python, strerror(e));
}
