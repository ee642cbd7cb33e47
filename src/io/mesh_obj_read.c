/*
 * mesh_obj_read.c - triangle meshes from OBJ polygon files (see mesh_obj_read.h).
 */
#include "io/mesh_obj_read.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/read_file.h"
#include "sem/limits.h"
#include "util/grow.h"

void sem_triangle_soup_free(sem_triangle_soup *s)
{
    free(s->vertices);
    free(s->triangles);
    memset(s, 0, sizeof *s);
}

static int grow(void **p, int *cap, int need, size_t elem)
{
    return sem_grow(p, cap, need, elem, 1024, (1 << 29));
}

/* Is the statement at s (after leading blanks) `word` followed by a blank or the end? */
static int keyword(const char *s, const char *word)
{
    size_t n = strlen(word);
    return !strncmp(s, word, n) && (s[n] == ' ' || s[n] == '\t' || s[n] == '\r' || s[n] == '\n' || s[n] == 0);
}

sem_status sem_obj_triangles_read(const char *path, sem_triangle_soup *out, int *freeform, sem_error *err)
{
    memset(out, 0, sizeof *out);
    if (freeform) *freeform = 0;
    char *data = NULL;
    size_t len = 0;
    sem_status st = sem_read_file(path, SEM_MAX_MODEL_FILE_BYTES, "SEM_MAX_MODEL_FILE_BYTES", &data, &len, err);
    if (st != SEM_OK) return st;
    int cap_v = 0, cap_t = 0, line = 0;
    for (char *s = data; *s;) {
        char *eol = strchr(s, '\n');
        if (eol) *eol = 0;
        ++line;
        while (*s == ' ' || *s == '\t') ++s;
        if (keyword(s, "surf")) {
            if (freeform) {
                *freeform = 1;
                sem_triangle_soup_free(out);
                free(data);
                return SEM_OK;
            }
        } else if (keyword(s, "v")) {
            double x[3];
            char *p = s + 1, *end;
            for (int k = 0; k < 3; ++k) {
                x[k] = strtod(p, &end);
                if (end == p || !isfinite(x[k])) {
                    st = sem_error_set(err, SEM_ERR_PARSE, "%s:%d: a vertex needs 3 finite numbers", path, line);
                    goto done;
                }
                p = end;
            }
            if (!grow((void **)&out->vertices, &cap_v, 3 * (out->n_vertices + 1), sizeof(double))) goto nomem;
            memcpy(out->vertices + 3 * (size_t)out->n_vertices, x, sizeof x);
            out->n_vertices++;
        } else if (keyword(s, "f")) {
            int idx[5], n = 0;
            char *p = s + 1;
            for (;;) {
                while (*p == ' ' || *p == '\t' || *p == '\r') ++p;
                if (!*p) break;
                char *end;
                long v = strtol(p, &end, 10);
                if (end == p || v == 0) {
                    st = sem_error_set(err, SEM_ERR_PARSE, "%s:%d: bad face vertex reference", path, line);
                    goto done;
                }
                while (*end && *end != ' ' && *end != '\t' && *end != '\r') ++end; /* "/vt/vn" */
                p = end;
                long i = v > 0 ? v - 1 : out->n_vertices + v;
                if (i < 0 || i >= out->n_vertices) {
                    st = sem_error_set(err, SEM_ERR_PARSE, "%s:%d: face vertex %ld out of range (%d vertices so far)",
                                       path, line, v, out->n_vertices);
                    goto done;
                }
                if (n < 5) idx[n] = (int)i;
                ++n;
            }
            if (n != 3 && n != 4) {
                st = sem_error_set(err, SEM_ERR_PARSE,
                                   "%s:%d: a face with %d vertices (collider meshes take triangles and quads)",
                                   path, line, n);
                goto done;
            }
            /* a quad is two triangles, split along its shorter diagonal (terrains exported
             * from modelling tools mix both) */
            int tri[6] = {idx[0], idx[1], idx[2], 0, 0, 0}, nt = 1;
            if (n == 4) {
                const double *v = out->vertices;
                double d02 = 0, d13 = 0;
                for (int k = 0; k < 3; ++k) {
                    double a = v[3 * (size_t)idx[0] + k] - v[3 * (size_t)idx[2] + k];
                    double b = v[3 * (size_t)idx[1] + k] - v[3 * (size_t)idx[3] + k];
                    d02 += a * a;
                    d13 += b * b;
                }
                if (d02 <= d13) {
                    int t[6] = {idx[0], idx[1], idx[2], idx[0], idx[2], idx[3]};
                    memcpy(tri, t, sizeof t);
                } else {
                    int t[6] = {idx[0], idx[1], idx[3], idx[1], idx[2], idx[3]};
                    memcpy(tri, t, sizeof t);
                }
                nt = 2;
            }
            if (!grow((void **)&out->triangles, &cap_t, 3 * (out->n_triangles + nt), sizeof(int))) goto nomem;
            memcpy(out->triangles + 3 * (size_t)out->n_triangles, tri, 3 * (size_t)nt * sizeof(int));
            out->n_triangles += nt;
        }
        if (!eol) break;
        s = eol + 1;
    }
    if (out->n_triangles == 0) st = sem_error_set(err, SEM_ERR_PARSE, "%s: no triangle (no 'f' statement)", path);
    goto done;
nomem:
    st = sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory", path);
done:
    free(data);
    if (st != SEM_OK) sem_triangle_soup_free(out);
    return st;
}
