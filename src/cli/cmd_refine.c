/*
 * cmd_refine.c - `sem refine IN OUT --factor K`: the same model with more control points.
 * Every non-empty knot span of every part is split into K x K by exact knot insertion
 * (sem_model_refine, sem/refine.h); OUT's format goes by its extension as for `sem convert`.
 */
#include <stdio.h>
#include <string.h>

#include "cli.h"
#include "sem/refine.h"

#define CMD "refine"

int cmd_refine(int argc, char **argv)
{
    const char *files[2] = {NULL, NULL};
    int n = 0, factor = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--factor") == 0 || strcmp(argv[i], "-k") == 0) {
            int rc = cli_need_values(CMD, argc, argv, i, 1);
            if (rc == CLI_OK) rc = cli_parse_int(CMD, argv[i], argv[i + 1], &factor);
            if (rc != CLI_OK) return rc;
            if (factor < 1 || factor > SEM_MAX_REFINE_FACTOR)
                return cli_usage(CMD, "%s: %d is outside 1..%d", argv[i], factor,
                                 SEM_MAX_REFINE_FACTOR);
            ++i;
        } else {
            int rc = cli_take_file(CMD, argv[i], files, &n, 2);
            if (rc != CLI_OK) return rc;
        }
    }
    if (n < 2) return cli_usage(CMD, "need IN and OUT files");
    if (factor == 0) return cli_usage(CMD, "need --factor K");

    sem_error err;
    sem_error_clear(&err);
    sem_model *in = NULL, *out = NULL;
    if (sem_model_load(files[0], &in, &err) != SEM_OK) return cli_fail_error(files[0], &err);
    cli_print_model_warnings(in);
    if (sem_model_refine(in, factor, &out, &err) != SEM_OK) {
        sem_model_destroy(in);
        return cli_fail_error(files[0], &err);
    }
    size_t before = sem_model_control_points(in), after = sem_model_control_points(out);
    sem_model_destroy(in);
    if (sem_model_save(out, files[1], &err) != SEM_OK) {
        sem_model_destroy(out);
        return cli_fail_error(files[1], &err);
    }
    printf("%s -> %s: refined by %d, %d parts, %zu -> %zu control points (dofs %zu -> %zu)\n",
           files[0], files[1], factor, out->n_parts, before, after, 3 * before, 3 * after);
    sem_model_destroy(out);
    return CLI_OK;
}
