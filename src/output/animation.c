/* animation.c - per-frame NURBS and meshes, and the USD animation (see sem/animation.h). */
#include "sem/animation.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "gltf.h"
#include "util/make_dirs.h"
#include "io/atomic_file.h"
#include "preprocess_view.h"
#include "sem/preprocess.h"
#include "sem/tessellate.h"
#include "sem/version.h"

struct sem_animation {
    sem_animation_def def;
    char dir[4096];
    char usd_path[4200];
    char frame_units[16];
    char glb_path[4200];
    int n_objects;
    sem_model *combined;          /* all objects' parts, for the per-frame NURBS files */
    size_t *object_ctrl;          /* control points per object */
    sem_mesh_template **templates;
    sem_mesh *meshes;
    int n_frames, cap_frames;
    int *frame_index;
    float **frame_points;         /* per frame: all objects' mesh points concatenated */
    float **frame_normals;        /* the same for normals (glTF only) */
    size_t points_per_frame;      /* floats */
};

sem_status sem_animation_check_dir(const char *dir, sem_error *err)
{
    if (!dir || !dir[0]) return sem_error_set(err, SEM_ERR_INVALID, "no output folder given");
    char path[4096];
    if (strlen(dir) >= sizeof path)
        return sem_error_set(err, SEM_ERR_INVALID, "output folder name too long (%zu characters)", strlen(dir));
    snprintf(path, sizeof path, "%s", dir);
    for (;;) {
        size_t n = strlen(path);
        while (n > 1 && path[n - 1] == '/') path[--n] = '\0';
        struct stat st;
        if (stat(path, &st) == 0) {
            if (!S_ISDIR(st.st_mode))
                return sem_error_set(err, SEM_ERR_IO, "%s: cannot write the output there: %s is not a folder",
                                     dir, path);
            if (access(path, W_OK | X_OK) != 0)
                return sem_error_set(err, SEM_ERR_IO, "%s: cannot write the output there: %s: %s", dir,
                                     path, strerror(errno));
            return SEM_OK;
        }
        /* ENOTDIR: a file on the way, which the walk up finds and names */
        if ((errno != ENOENT && errno != ENOTDIR) || !strcmp(path, "."))
            return sem_error_set(err, SEM_ERR_IO, "%s: cannot write the output there: %s: %s", dir, path,
                                 strerror(errno));
        /* missing: the folder that would hold it must be writable */
        char *slash = strrchr(path, '/');
        if (!slash)
            snprintf(path, sizeof path, ".");
        else if (slash == path)
            path[1] = '\0';
        else
            *slash = '\0';
    }
}

sem_status sem_animation_create(const sem_animation_def *def, int n_objects,
                                const sem_model *const *models, sem_animation **out, sem_error *err)
{
    *out = NULL;
    sem_animation *a = calloc(1, sizeof *a);
    if (!a) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    a->def = *def;
    snprintf(a->dir, sizeof a->dir, "%s", def->dir);
    a->def.dir = a->dir;
    if (a->def.mesh_resolution < 1) a->def.mesh_resolution = 6;
    if (!(a->def.frames_per_second > 0)) a->def.frames_per_second = 24;
    snprintf(a->usd_path, sizeof a->usd_path, "%s/animation.usda", a->dir);
    snprintf(a->glb_path, sizeof a->glb_path, "%s/animation.glb", a->dir);
    a->n_objects = n_objects;
    sem_status st = sem_make_dirs(a->dir, err);
    if (st != SEM_OK) goto fail;
    a->combined = sem_model_create();
    a->object_ctrl = calloc((size_t)n_objects + 1, sizeof(size_t));
    a->templates = calloc((size_t)n_objects + 1, sizeof *a->templates);
    a->meshes = calloc((size_t)n_objects + 1, sizeof *a->meshes);
    if (!a->combined || !a->object_ctrl || !a->templates || !a->meshes) {
        st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    if (!(a->def.frame_unit_to_meter > 0) || !isfinite(a->def.frame_unit_to_meter) ||
        !a->def.frame_units || !a->def.frame_units[0]) {
        a->def.frame_unit_to_meter = 1.0;
        snprintf(a->frame_units, sizeof a->frame_units, "M");
    } else {
        snprintf(a->frame_units, sizeof a->frame_units, "%s", a->def.frame_units);
    }
    a->def.frame_units = a->frame_units;
    snprintf(a->combined->units, sizeof a->combined->units, "%s", a->frame_units);
    a->combined->unit_to_meter = a->def.frame_unit_to_meter;
    for (int o = 0; o < n_objects; ++o) {
        a->object_ctrl[o] = sem_model_control_points(models[o]);
        for (int i = 0; i < models[o]->n_parts; ++i)
            if ((st = sem_model_add_part(a->combined, &models[o]->parts[i], err)) != SEM_OK) goto fail;
        if (a->def.write_mesh || a->def.write_usd || a->def.write_glb) {
            if ((st = sem_mesh_template_build(models[o], a->def.mesh_resolution, &a->templates[o], err)) != SEM_OK)
                goto fail;
            if ((st = sem_mesh_template_mesh(a->templates[o], &a->meshes[o], err)) != SEM_OK) goto fail;
            a->points_per_frame += 3 * (size_t)a->meshes[o].n_vertices;
        }
    }
    *out = a;
    return SEM_OK;
fail:
    sem_animation_destroy(a);
    return st;
}

void sem_animation_destroy(sem_animation *a)
{
    if (!a) return;
    sem_model_destroy(a->combined);
    for (int o = 0; o < a->n_objects; ++o) {
        if (a->templates) sem_mesh_template_destroy(a->templates[o]);
        if (a->meshes) sem_mesh_free(&a->meshes[o]);
    }
    free(a->templates);
    free(a->meshes);
    free(a->object_ctrl);
    for (int f = 0; f < a->n_frames; ++f) {
        free(a->frame_points[f]);
        if (a->frame_normals) free(a->frame_normals[f]);
    }
    free(a->frame_points);
    free(a->frame_normals);
    free(a->frame_index);
    free(a);
}

const char *sem_animation_usd_path(const sem_animation *a)
{
    return a->usd_path;
}

const char *sem_animation_glb_path(const sem_animation *a)
{
    return a->glb_path;
}

sem_status sem_animation_write_preprocess(const sem_animation *a, int object, const sem_discretization *d,
                                          sem_error *err)
{
    if (!a || !d || object < 0 || object >= a->n_objects)
        return sem_error_set(err, SEM_ERR_INVALID, "sem_animation_write_preprocess: bad object %d", object);
    char path[4400];
    snprintf(path, sizeof path, "%s/preprocess_%d.semdisc", a->dir, object);
    return output_write_preprocess(path, d, err);
}

static sem_status add_frame(sem_animation *a, int frame, const double *const *q, int write_files,
                            sem_error *err);

sem_status sem_animation_add_frame(sem_animation *a, int frame, const double *const *q, sem_error *err)
{
    return add_frame(a, frame, q, 1, err);
}

sem_status sem_animation_restore_frame(sem_animation *a, int frame, const double *const *q,
                                       sem_error *err)
{
    return add_frame(a, frame, q, 0, err);
}

static sem_status add_frame(sem_animation *a, int frame, const double *const *q, int write_files,
                            sem_error *err)
{
    int digits = a->def.frame_digits > 0 ? a->def.frame_digits : 4;
    sem_status st;
    /* the combined model's control points, object after object */
    size_t total = 0;
    for (int o = 0; o < a->n_objects; ++o) total += a->object_ctrl[o];
    double *all = malloc(3 * total * sizeof(double) + 1);
    if (!all) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    size_t k = 0;
    const double to_frame = 1.0 / a->def.frame_unit_to_meter;
    for (int o = 0; o < a->n_objects; ++o) {
        for (size_t c = 0; c < 3 * a->object_ctrl[o]; ++c) all[3 * k + c] = q[o][c] * to_frame;
        k += a->object_ctrl[o];
    }
    sem_model_set_q(a->combined, all);
    free(all);
    char path[4400];
    if (a->def.write_iges && write_files) {
        snprintf(path, sizeof path, "%s/frame_%0*d.igs", a->dir, digits, frame);
        if ((st = sem_model_save(a->combined, path, err)) != SEM_OK) return st;
    }
    if (a->def.write_obj && write_files) {
        snprintf(path, sizeof path, "%s/frame_%0*d_nurbs.obj", a->dir, digits, frame);
        if ((st = sem_model_save(a->combined, path, err)) != SEM_OK) return st;
    }
    if (!a->def.write_mesh && !a->def.write_usd && !a->def.write_glb) return SEM_OK;
    /* meshes: one object model at a time, through the combined model's parts */
    float *pts = NULL, *nrm = NULL;
    if (a->def.write_usd || a->def.write_glb) {
        pts = malloc((a->points_per_frame + 1) * sizeof(float));
        if (!pts) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    if (a->def.write_glb) {
        nrm = malloc((a->points_per_frame + 1) * sizeof(float));
        if (!nrm) {
            free(pts);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
    }
    size_t off = 0;
    int part0 = 0;
    for (int o = 0; o < a->n_objects; ++o) {
        /* a view of the combined model restricted to this object's parts */
        sem_model view = *a->combined;
        view.parts = a->combined->parts + part0;
        int n_parts = 0;
        size_t cp = 0;
        while (cp < a->object_ctrl[o]) {
            const sem_surface *s = &view.parts[n_parts].surface;
            cp += (size_t)s->n_u * (size_t)s->n_v;
            n_parts++;
        }
        view.n_parts = n_parts;
        view.n_warnings = 0;
        view.warnings = NULL;
        part0 += n_parts;
        if ((st = sem_mesh_update(a->templates[o], &view, &a->meshes[o], err)) != SEM_OK) {
            free(pts);
            free(nrm);
            return st;
        }
        if (a->def.write_mesh && write_files) {
            if (a->n_objects == 1)
                snprintf(path, sizeof path, "%s/frame_%0*d_mesh.obj", a->dir, digits, frame);
            else
                snprintf(path, sizeof path, "%s/frame_%0*d_object%d_mesh.obj", a->dir, digits,
                         frame, o);
            if ((st = sem_mesh_write_obj(&a->meshes[o], &view, path, err)) != SEM_OK) {
                free(pts);
                free(nrm);
                return st;
            }
        }
        if (pts) /* USD and glTF are in metres */
            for (int v = 0; v < 3 * a->meshes[o].n_vertices; ++v) {
                if (nrm) nrm[off] = (float)a->meshes[o].normals[v];
                pts[off++] = (float)(a->meshes[o].positions[v] * a->def.frame_unit_to_meter);
            }
    }
    if (!pts) return SEM_OK;
    if (a->n_frames == a->cap_frames) {
        int nc = a->cap_frames ? 2 * a->cap_frames : 64;
        float **fp = realloc(a->frame_points, (size_t)nc * sizeof *fp);
        if (fp) a->frame_points = fp;
        int *fi = fp ? realloc(a->frame_index, (size_t)nc * sizeof *fi) : NULL;
        if (fi) a->frame_index = fi;
        float **fn = fi ? realloc(a->frame_normals, (size_t)nc * sizeof *fn) : NULL;
        if (fn) a->frame_normals = fn;
        if (!fp || !fi || !fn) {
            free(pts);
            free(nrm);
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        }
        a->cap_frames = nc;
    }
    a->frame_points[a->n_frames] = pts;
    a->frame_normals[a->n_frames] = nrm;
    a->frame_index[a->n_frames] = frame;
    a->n_frames++;
    return SEM_OK;
}

/* animation.glb: the frames kept so far (gltf.c). */
static sem_status write_glb(const sem_animation *a, sem_error *err)
{
    gltf_object *objects = calloc((size_t)a->n_objects, sizeof *objects);
    const char **names = calloc((size_t)a->combined->n_parts + 1, sizeof *names);
    double *times = malloc((size_t)a->n_frames * sizeof *times);
    if (!objects || !names || !times) {
        free(objects);
        free(names);
        free(times);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    for (int i = 0; i < a->combined->n_parts; ++i) names[i] = a->combined->parts[i].name;
    int part0 = 0;
    for (int o = 0; o < a->n_objects; ++o) {
        objects[o].mesh = &a->meshes[o];
        objects[o].part_names = names + part0;
        objects[o].first_part = part0;
        part0 += a->meshes[o].n_parts;
    }
    for (int f = 0; f < a->n_frames; ++f) times[f] = a->frame_index[f] / a->def.frames_per_second;
    char generator[64];
    snprintf(generator, sizeof generator, "sem %s", SEM_VERSION_STRING);
    gltf_animation g = {a->n_objects, objects, a->n_frames, times, (const float *const *)a->frame_points,
                        (const float *const *)a->frame_normals,
                        a->combined->unit_to_meter > 0 ? a->combined->unit_to_meter : 1.0, generator};
    sem_status st = gltf_write(a->glb_path, &g, err);
    free(objects);
    free(names);
    free(times);
    return st;
}

sem_status sem_animation_finish(sem_animation *a, sem_error *err)
{
    if (a->n_frames == 0) return SEM_OK;
    if (a->def.write_glb) {
        sem_status st = write_glb(a, err);
        if (st != SEM_OK) return st;
    }
    if (!a->def.write_usd) return SEM_OK;
    sem_atomic_file file;
    sem_status st = sem_atomic_open(&file, a->usd_path, err);
    if (st != SEM_OK) return st;
    FILE *f = file.fp;
    int first = a->frame_index[0], last = a->frame_index[a->n_frames - 1];
    fprintf(f,
            "#usda 1.0\n(\n    defaultPrim = \"World\"\n    startTimeCode = %d\n    endTimeCode = %d\n"
            "    timeCodesPerSecond = %.17g\n    framesPerSecond = %.17g\n    upAxis = \"Z\"\n"
            "    metersPerUnit = %.17g\n    doc = \"sem: Shape Matching Element Method animation\"\n)\n\n",
            first, last, a->def.frames_per_second, a->def.frames_per_second,
            1.0);
    fprintf(f, "def Xform \"World\"\n{\n");
    size_t off = 0;
    for (int o = 0; o < a->n_objects; ++o) {
        const sem_mesh *m = &a->meshes[o];
        fprintf(f, "    def Mesh \"object_%d\"\n    {\n", o);
        fprintf(f, "        uniform token subdivisionScheme = \"none\"\n");
        fprintf(f, "        uniform token orientation = \"rightHanded\"\n");
        fprintf(f, "        int[] faceVertexCounts = [");
        for (int t = 0; t < m->n_triangles; ++t) fprintf(f, t ? ", 3" : "3");
        fprintf(f, "]\n        int[] faceVertexIndices = [");
        for (int t = 0; t < 3 * m->n_triangles; ++t) fprintf(f, t ? ", %d" : "%d", m->triangles[t]);
        fprintf(f, "]\n        point3f[] points.timeSamples = {\n");
        for (int fr = 0; fr < a->n_frames; ++fr) {
            const float *p = a->frame_points[fr] + off;
            fprintf(f, "            %d: [", a->frame_index[fr]);
            for (int v = 0; v < m->n_vertices; ++v)
                fprintf(f, v ? ", (%.7g, %.7g, %.7g)" : "(%.7g, %.7g, %.7g)", p[3 * v], p[3 * v + 1], p[3 * v + 2]);
            fprintf(f, "],\n");
        }
        fprintf(f, "        }\n    }\n");
        off += 3 * (size_t)m->n_vertices;
    }
    fprintf(f, "}\n");
    return sem_atomic_commit(&file, err);
}
