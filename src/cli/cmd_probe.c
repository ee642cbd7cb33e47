/*
 * cmd_probe.c - `sem probe REST FRAME POINTS`: a deformed model evaluated at the rest
 * parameters of given points (hidden helper of `sem validate`, tools/fem/validate.py).
 *
 * Every frame sem writes is the rest model with moved control points (the same parts, knots,
 * weights and trims), so a point X of the rest surface has a part and (u,v) that the frame
 * maps to x = J(u,v) q: sem's deformation map restricted to the surface. For each point of
 * POINTS (three numbers a line, in the files' units; '#' lines and blank lines skipped) this
 * finds the closest point of REST (geometry/model_locator.h) and prints one line
 *
 *     part u v distance inside x y z
 *
 * distance: from the point to REST (so a point off the surface shows), inside: 1 when (u,v)
 * is inside the part's trims, x y z: FRAME's surface point at (part, u, v).
 */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "run_folder.h"
#include "geometry/model_locator.h"
#include "sem/nurbs.h"

#define CMD "probe"
#define MAX_POINTS 50000000L

/* Reads POINTS into *xyz (3 per point); returns CLI_OK or a printed failure. */
static int read_points(const char *path, double **xyz, long *count)
{
    *xyz = NULL;
    *count = 0;
    FILE *f = fopen(path, "r");
    if (!f) return cli_fail("%s: cannot open: %s", path, strerror(errno));
    long cap = 0, n = 0, line_no = 0;
    double *p = NULL;
    char line[512];
    int rc = CLI_OK;
    while (fgets(line, sizeof line, f)) {
        ++line_no;
        if (!strchr(line, '\n') && !feof(f)) {
            rc = cli_fail("%s:%ld: line too long", path, line_no);
            break;
        }
        char *s = line;
        while (*s == ' ' || *s == '\t') ++s;
        if (*s == '#' || *s == '\n' || *s == '\r' || *s == '\0') continue;
        double x[3];
        char extra;
        if (sscanf(s, "%lf %lf %lf %c", &x[0], &x[1], &x[2], &extra) != 3 || !isfinite(x[0]) ||
            !isfinite(x[1]) || !isfinite(x[2])) {
            rc = cli_fail("%s:%ld: expected three numbers", path, line_no);
            break;
        }
        if (n == cap) {
            if (cap >= MAX_POINTS) {
                rc = cli_fail("%s: more than %ld points", path, MAX_POINTS);
                break;
            }
            cap = cap ? 2 * cap : 1024;
            double *q = realloc(p, (size_t)cap * 3 * sizeof *q);
            if (!q) {
                rc = cli_fail("out of memory reading %s", path);
                break;
            }
            p = q;
        }
        memcpy(p + 3 * n++, x, sizeof x);
    }
    if (rc == CLI_OK && ferror(f)) rc = cli_fail("%s: read error", path);
    fclose(f);
    if (rc != CLI_OK) {
        free(p);
        return rc;
    }
    *xyz = p;
    *count = n;
    return CLI_OK;
}

int cmd_probe(int argc, char **argv)
{
    const char *files[3] = {NULL, NULL, NULL};
    int n = 0;
    double slack = 0;
    for (int i = 1; i < argc; ++i) {
        if (strcmp(argv[i], "--slack") == 0) {
            int rc = cli_need_values(CMD, argc, argv, i, 1);
            if (rc == CLI_OK) rc = cli_parse_double(CMD, argv[i], argv[i + 1], &slack);
            if (rc != CLI_OK) return rc;
            if (slack < 0) return cli_usage(CMD, "--slack must be >= 0");
            ++i;
        } else {
            int rc = cli_take_file(CMD, argv[i], files, &n, 3);
            if (rc != CLI_OK) return rc;
        }
    }
    if (n < 3) return cli_usage(CMD, "need REST, FRAME and POINTS");

    sem_error err;
    sem_error_clear(&err);
    sem_model *rest = NULL, *frame = NULL;
    sem_model_locator *loc = NULL;
    double *xyz = NULL;
    sem_model_location *found = NULL;
    long count = 0;
    int rc = CLI_OK;
    if (sem_model_load(files[0], &rest, &err) != SEM_OK) return cli_fail_error(files[0], &err);
    if (sem_model_load(files[1], &frame, &err) != SEM_OK) {
        rc = cli_fail_error(files[1], &err);
        goto done;
    }
    if (!run_frame_matches(rest, frame)) {
        rc = cli_fail("%s: not a frame of %s (different parts or control grids)", files[1], files[0]);
        goto done;
    }
    if ((rc = read_points(files[2], &xyz, &count)) != CLI_OK) goto done;
    if (sem_model_locator_build(rest, &loc, &err) != SEM_OK) {
        rc = cli_fail_error(files[0], &err);
        goto done;
    }
    found = malloc((size_t)(count > 0 ? count : 1) * sizeof *found);
    if (!found) {
        rc = cli_fail("out of memory");
        goto done;
    }
#pragma omp parallel for schedule(dynamic, 64)
    for (long k = 0; k < count; ++k) {
        sem_model_locator_find(loc, xyz + 3 * k, slack, &found[k]);
        if (found[k].part >= 0)
            sem_surface_eval(&frame->parts[found[k].part].surface, found[k].uv[0], found[k].uv[1], found[k].point,
                             NULL, NULL, NULL);
    }
    for (long k = 0; k < count; ++k) {
        const sem_model_location *f = &found[k];
        printf("%d %.17g %.17g %.17g %d %.17g %.17g %.17g\n", f->part, f->uv[0], f->uv[1], f->distance,
               f->inside_trim, f->point[0], f->point[1], f->point[2]);
    }
done:
    free(found);
    free(xyz);
    sem_model_locator_destroy(loc);
    sem_model_destroy(frame);
    sem_model_destroy(rest);
    return rc;
}
