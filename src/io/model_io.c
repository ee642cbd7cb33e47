/*
 * model_io.c - sem_model_load / sem_model_save: pick the format from the file name and
 * call its reader or writer. The writers share the atomic output of io/atomic_file.c.
 *
 * Formats: .igs / .iges (any case) -> IGES 5.3, .obj -> Wavefront OBJ free-form,
 * .step / .stp -> STEP through Open CASCADE (step_occt.cpp, or step_stub.c without it).
 */
#include "sem/model.h"

#include <string.h>
#include <strings.h>

typedef enum model_format { FORMAT_UNKNOWN, FORMAT_IGES, FORMAT_OBJ, FORMAT_STEP } model_format;

static const char *extension_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot && dot != base ? dot : NULL;
}

static model_format format_of(const char *path)
{
    const char *ext = extension_of(path);
    if (!ext) return FORMAT_UNKNOWN;
    if (strcasecmp(ext, ".igs") == 0 || strcasecmp(ext, ".iges") == 0) return FORMAT_IGES;
    if (strcasecmp(ext, ".obj") == 0) return FORMAT_OBJ;
    if (strcasecmp(ext, ".step") == 0 || strcasecmp(ext, ".stp") == 0) return FORMAT_STEP;
    return FORMAT_UNKNOWN;
}

static sem_status unknown_format(const char *path, sem_error *err)
{
    const char *ext = extension_of(path);
    return sem_error_set(err, SEM_ERR_UNSUPPORTED,
                         "%s: unknown model file extension '%s' (expected .igs, .iges, .obj, "
                         ".step or .stp)",
                         path, ext ? ext : "");
}

sem_status sem_model_load(const char *path, sem_model **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!path || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_model_load: NULL argument");
    switch (format_of(path)) {
    case FORMAT_IGES: return sem_iges_read(path, out, err);
    case FORMAT_OBJ: return sem_obj_read(path, out, err);
    case FORMAT_STEP: return sem_step_read(path, out, err);
    default: return unknown_format(path, err);
    }
}

sem_status sem_model_save(const sem_model *model, const char *path, sem_error *err)
{
    if (!path || !model) return sem_error_set(err, SEM_ERR_INVALID, "sem_model_save: NULL argument");
    switch (format_of(path)) {
    case FORMAT_IGES: return sem_iges_write(model, path, err);
    case FORMAT_OBJ: return sem_obj_write(model, path, err);
    case FORMAT_STEP: return sem_step_write(model, path, err);
    default: return unknown_format(path, err);
    }
}
