/*
 * fuzz_scene.c - the scene reader (JSON syntax, every key and value check). Model files
 * are not opened: the scene's folder does not exist.
 */
#include "fuzz.h"
#include "sem/scene.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* sem_scene_load refuses a NUL byte inside the file; the text it parses never has one */
    if (memchr(data, 0, size)) return 0;
    char *json = malloc(size + 1);
    if (!json) return 0;
    memcpy(json, data, size);
    json[size] = '\0';
    sem_scene *scene = NULL;
    sem_error err;
    sem_error_clear(&err);
    sem_status st = sem_scene_parse(json, "fuzz.json", "/nonexistent-sem-fuzz", &scene, &err);
    fuzz_check_error(st, &err);
    sem_scene_destroy(scene);
    free(json);
    return 0;
}
