/* test_stay_up.c - real models stay up at default settings (issue 11, "Every part is held").
 *
 * The check of the issue, on a CI-sized subset of ../shared/models: the model at its real size
 * (file units converted to metres), default `sem` settings, pinned in its lowest tenth (every
 * control point below 10 % of its height), stiff (E = 1e7 x its size in Pa, rho 1000, nu 0.4)
 * under gravity, 30 steps of implicit Euler (dt 0.01): the centre of mass drops by less than
 * 5 % of the model's height. Before the object-frame quadrature, the coupled origins, the
 * ties and the volume consistency term, parts of several of these flew off or the whole model
 * kept falling. Measured (docs/validation.md): every shared model drops less than 1 %.
 * Skipped under the sanitizers (the Release run checks it).
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sem/measure.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/scene.h"
#include "sem/simulation.h"
#include "test_util.h"

static void stay_up(const char *relative)
{
    const char *path = test_shared_model(relative);
    if (!path) return;
    char file[4096];
    snprintf(file, sizeof file, "%s", path);
    sem_error err;
    sem_model *m = NULL;
    if (sem_model_load(file, &m, &err) != SEM_OK) {
        CHECK(0, "%s: %s", file, err.message);
        return;
    }
    /* the surface's bounding box (inspect's), in metres */
    sem_part_measure_result total, *per = calloc((size_t)m->n_parts + 1, sizeof *per);
    double lo[3], hi[3];
    int measured = per && sem_model_measure(m, per, &total, &err) == SEM_OK;
    CHECK(measured, "%s: measure: %s", relative, err.message);
    for (int e = 0; e < 3; ++e) {
        lo[e] = total.bbox_min[e] * m->unit_to_meter;
        hi[e] = total.bbox_max[e] * m->unit_to_meter;
    }
    free(per);
    sem_model_destroy(m);
    if (!measured) return;
    double size = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                       (hi[2] - lo[2]) * (hi[2] - lo[2]));
    double height = hi[2] - lo[2];
    char json[8192];
    snprintf(json, sizeof json,
             "{\"objects\": [{\"model\": \"%s\", \"material\": {\"type\": \"neohookean\", \"density\": 1000, "
             "\"youngs_modulus\": %.17g, \"poisson_ratio\": 0.4}, \"pin\": {\"box\": [[%.17g, %.17g, %.17g], "
             "[%.17g, %.17g, %.17g]]}}], \"gravity\": [0, 0, -9.81], "
             "\"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01}, \"frames\": 30}",
             file, 1e7 * size, lo[0] - size, lo[1] - size, lo[2] - size, hi[0] + size, hi[1] + size,
             lo[2] + 0.1 * height);
    sem_scene *scene = NULL;
    sem_scene_world *sw = NULL;
    if (sem_scene_parse(json, relative, "/", &scene, &err) != SEM_OK ||
        sem_scene_world_create(scene, NULL, &sw, &err) != SEM_OK) {
        CHECK(0, "%s: %s", relative, err.message);
        sem_scene_destroy(scene);
        return;
    }
    CHECK(sem_scene_world_spurious_modes(sw, 0) == 0, "%s: %d zero-energy modes", relative,
          sem_scene_world_spurious_modes(sw, 0));
    sem_world *w = sem_scene_world_world(sw);
    sem_object_stats s0, s;
    sem_world_object_stats(w, 0, &s0);
    double drop = 0;
    for (int k = 0; k < 30; ++k) {
        if (sem_world_step(w, &err) != SEM_OK) {
            CHECK(0, "%s: step %d: %s", relative, k + 1, err.message);
            break;
        }
        sem_world_object_stats(w, 0, &s);
        drop = fmax(drop, (s0.center_of_mass[2] - s.center_of_mass[2]) / height);
    }
    printf("%-36s height %.3g m: centre of mass drops at most %.4f of the height\n", relative, height, drop);
    CHECK(drop < 0.05, "%s: the centre of mass drops %.3f of the height", relative, drop);
    sem_scene_world_destroy(sw);
    sem_scene_destroy(scene);
}

static void collect_log(void *user, int level, const char *message)
{
    if (level < 1) return;
    char *buf = user;
    size_t n = strlen(buf);
    snprintf(buf + n, 4096 - n, "%s\n", message);
}

/* A part too small for the default quadrature is named, and a finer spacing gives it its own
 * volume: the mug's 9 cm^2 part 0 (of 323 cm^2). */
static void small_part_named(void)
{
    const char *path = test_shared_model("mugs/mug.iges");
    if (!path) return;
    for (int fine = 0; fine < 2; ++fine) {
        char json[4600], log[4096] = "";
        snprintf(json, sizeof json, "{\"objects\": [{\"model\": \"%s\"%s}], \"frames\": 1}", path,
                 fine ? ", \"sem\": {\"spacing\": 0.004}" : "");
        sem_error err;
        sem_scene *scene = NULL;
        sem_scene_world *sw = NULL;
        sem_scene_world_options o = sem_default_scene_world_options();
        o.log = collect_log;
        o.log_user = log;
        if (sem_scene_parse(json, "mug", "/", &scene, &err) != SEM_OK ||
            sem_scene_world_create(scene, &o, &sw, &err) != SEM_OK) {
            CHECK(0, "mug: %s", err.message);
        } else {
            const sem_discretization *d = sem_scene_world_discretization(sw, 0);
            printf("mug, %s spacing: part 0 %s\n", fine ? "4 mm" : "default",
                   d->part_covered && d->part_covered[0] ? "has no volume of its own" : "has its own volume");
            if (!fine)
                CHECK(d->part_covered && d->part_covered[0] && strstr(log, "part 0 (Body12) is too small or thin"),
                      "the default quadrature misses part 0 and says so: %s", log);
            else
                CHECK(d->part_covered && !d->part_covered[0] && !strstr(log, "too small or thin"),
                      "a 4 mm spacing gives part 0 its own volume: %s", log);
        }
        sem_scene_world_destroy(sw);
        sem_scene_destroy(scene);
    }
}

int main(void)
{
    small_part_named();
    if (!getenv("SEM_SANITIZED")) {
        /* the rocket's fins (once fell off its body), the tire's nested shells, the trimmed
         * mug's handle, the landing starship's legs, the puft's arms */
        stay_up("rocket/rocket.iges");
        stay_up("tire.iges");
        stay_up("mugs/mug_trimmed_complex.iges");
        stay_up("starship/starship_fall_collide.igs");
        stay_up("puft/puft_no_collar.iges");
    }
    return test_finish("test_stay_up");
}
