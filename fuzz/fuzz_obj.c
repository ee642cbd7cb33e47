/*
 * fuzz_obj.c - the OBJ free-form reader, then every part's trim region and surface (fuzz_model.h).
 */
#include "fuzz_model.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    sem_model *m = NULL;
    sem_error err;
    sem_error_clear(&err);
    sem_status st = sem_obj_read_buffer("fuzz.obj", (const char *)data, size, &m, &err);
    fuzz_check_error(st, &err);
    if (st != SEM_OK) return 0;
    fuzz_use_model(m);
    sem_model_destroy(m);
    return 0;
}
