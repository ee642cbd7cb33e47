/*
 * cmd_convert.c - `sem convert IN OUT`: read any model format sem_model_load knows and
 * write it in the format of OUT's extension (IGES, OBJ free-form, STEP).
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"

#define CMD "convert"

int cmd_convert(int argc, char **argv)
{
    const char *files[2] = {NULL, NULL};
    int n = 0;
    for (int i = 1; i < argc; ++i) {
        int rc = cli_take_file(CMD, argv[i], files, &n, 2);
        if (rc != CLI_OK) return rc;
    }
    if (n < 2) return cli_usage(CMD, "need IN and OUT files");

    sem_error err;
    sem_error_clear(&err);
    sem_model *m = NULL;
    if (sem_model_load(files[0], &m, &err) != SEM_OK) return cli_fail_error(files[0], &err);
    cli_print_model_warnings(m);
    if (sem_model_save(m, files[1], &err) != SEM_OK) {
        sem_model_destroy(m);
        return cli_fail_error(files[1], &err);
    }
    size_t n_ctrl = sem_model_control_points(m);
    printf("%s -> %s: %d parts, %zu control points\n", files[0], files[1], m->n_parts, n_ctrl);
    sem_model_destroy(m);
    return CLI_OK;
}
