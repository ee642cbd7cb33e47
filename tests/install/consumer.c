/*
 * consumer.c - a program outside the sem tree, built against an installed libsem by the
 * install test (tests/install/install_test.cmake): once with pkg-config, once with CMake's
 * find_package(sem) (shared and static). It uses only <sem/sem.h> and checks real numbers:
 * the headers' version against the library's, the area of a box against its closed form,
 * and a scene (JSON text) stepped twice by the library's scene world.
 */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include <sem/sem.h>

static int fail(const char *what, const sem_error *err)
{
    fprintf(stderr, "consumer: %s: %s\n", what, err ? err->message : "");
    return 1;
}

int main(void)
{
    if (strcmp(sem_version(), SEM_VERSION_STRING) != 0) {
        fprintf(stderr, "consumer: headers %s, library %s\n", SEM_VERSION_STRING, sem_version());
        return 1;
    }
    sem_error err;
    sem_error_clear(&err);

    /* a 1 x 2 x 3 box: area 2 (1*2 + 2*3 + 1*3) = 22 */
    sem_model *box = sem_model_create();
    sem_box_def def = sem_default_box_def();
    def.size[0] = 1, def.size[1] = 2, def.size[2] = 3;
    if (!box || sem_primitive_box(box, &def, &err) != SEM_OK) return fail("box", &err);
    sem_part_measure_result total;
    if (sem_model_measure(box, NULL, &total, &err) != SEM_OK) return fail("measure", &err);
    sem_model_destroy(box);
    if (fabs(total.area - 22.0) > 1e-9) {
        fprintf(stderr, "consumer: box area %.15g, expected 22\n", total.area);
        return 1;
    }

    /* a small falling beam, two steps */
    const char *json =
        "{\"objects\": [{\"primitive\": {\"type\": \"beam\", \"length\": 2, \"width\": 0.5,"
        " \"height\": 0.5}, \"sem\": {\"order\": 1, \"rays\": [3, 3]}}],"
        " \"integrator\": {\"type\": \"linearly_implicit_euler\", \"dt\": 0.01}}";
    sem_scene *scene = NULL;
    if (sem_scene_parse(json, "consumer", ".", &scene, &err) != SEM_OK) return fail("scene", &err);
    sem_scene_world_options options = sem_default_scene_world_options();
    sem_scene_world *sw = NULL;
    if (sem_scene_world_create(scene, &options, &sw, &err) != SEM_OK) return fail("world", &err);
    sem_world *world = sem_scene_world_world(sw);
    for (int i = 0; i < 2; ++i)
        if (sem_world_step(world, &err) != SEM_OK) return fail("step", &err);
    double t = sem_world_time(world);
    sem_object_stats stats;
    sem_world_object_stats(world, 0, &stats);
    /* nothing is pinned: the beam falls under the default gravity (-z) */
    int ok = fabs(t - 0.02) < 1e-12 && stats.linear_momentum[2] < 0 && isfinite(stats.kinetic_energy);
    printf("consumer: sem %s, box area %.12g, t = %g, volume %.6g, kinetic energy %.6g\n",
           sem_version(), total.area, t, stats.volume, stats.kinetic_energy);
    sem_scene_world_destroy(sw);
    sem_scene_destroy(scene);
    return ok ? 0 : 1;
}
