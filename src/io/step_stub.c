/*
 * step_stub.c - sem_step_read / sem_step_write when libsem is built without Open CASCADE
 * (SEM_WITH_OCCT=OFF): they report that STEP is not compiled in. With Open CASCADE the
 * real ones are in step_occt.cpp and this file is empty.
 */
#include "sem/model.h"

#ifndef SEM_HAVE_OCCT

static sem_status not_compiled_in(const char *path, sem_error *err)
{
    return sem_error_set(err, SEM_ERR_UNSUPPORTED,
                         "%s: STEP files are not supported by this build of sem (it was built "
                         "without Open CASCADE: SEM_WITH_OCCT=OFF)",
                         path ? path : "(null)");
}

sem_status sem_step_read(const char *path, sem_model **out, sem_error *err)
{
    if (out) *out = NULL;
    return not_compiled_in(path, err);
}

sem_status sem_step_write(const sem_model *model, const char *path, sem_error *err)
{
    (void)model;
    return not_compiled_in(path, err);
}

#else
/* ISO C forbids an empty translation unit */
typedef int sem_step_stub_unused;
#endif
