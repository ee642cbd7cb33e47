/*
 * test_soak.c - a long run stays healthy: memory flat, energy bounded (docs/reliability.md).
 *
 * The default scene's soft beam (clamped at x = 0, 2 m long, swinging under gravity with
 * implicit Euler) with a floor 0.3 m below it, so that its free end strikes, slides and rests
 * on the plane: contact is found, made and lost over and over (springs, friction, the contact
 * point lists). Stepped SEM_SOAK_STEPS times (default 150 in the test suite, 100 under the
 * sanitizers; scripts/fuzz.sh --soak runs 10,000). Properties:
 *  - the resident memory after the first 50 steps does not grow by more than 2 MB until the
 *    end (a per-step leak of 200 bytes would show over 10,000 steps); skipped under the
 *    sanitizers, whose quarantine holds freed memory on purpose;
 *  - every step succeeds and the total energy (kinetic + elastic + gravity + error) stays
 *    finite and never exceeds its starting value by more than 1e-6 of the energy scale
 *    (implicit Euler and friction only dissipate; the floor does no work over a cycle, and
 *    the energy its springs hold is not counted, which can only lower the sum);
 *  - contact happened: the floor was touched, and the free end never sank into it by more
 *    than 2 % of the beam's thickness.
 */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "sem/contact.h"
#include "sem/scene.h"
#include "sem/simulation.h"
#include "test_util.h"

static long resident_kb(void)
{
    FILE *f = fopen("/proc/self/statm", "r");
    long size = 0, resident = 0;
    if (f) {
        if (fscanf(f, "%ld %ld", &size, &resident) != 2) resident = 0;
        fclose(f);
    }
    return resident * (sysconf(_SC_PAGESIZE) / 1024);
}

static double total_energy(sem_world *w, double *scale)
{
    sem_object_stats s;
    sem_world_object_stats(w, 0, &s);
    *scale = fabs(s.kinetic_energy) + fabs(s.elastic_energy) + fabs(s.gravity_energy) +
             fabs(s.error_energy);
    return s.kinetic_energy + s.elastic_energy + s.gravity_energy + s.error_energy;
}

int main(void)
{
    const char *v = getenv("SEM_SOAK_STEPS");
    int sanitized = getenv("SEM_SANITIZED") != NULL;
    long steps = v ? atol(v) : sanitized ? 100 : 150; /* the floor is reached near step 50 */
    if (steps < 100) steps = 100;
    char cache[600];
    snprintf(cache, sizeof cache, "%s/cache", test_tmpdir());

    static const char *json =
        "{\"objects\": [{"
        "  \"primitive\": {\"type\": \"beam\", \"sections\": 4, \"length\": 2.0, \"width\": 0.4, \"height\": 0.4},"
        "  \"material\": {\"type\": \"neohookean\", \"density\": 1100, \"youngs_modulus\": 2e6, \"poisson_ratio\": 0.45},"
        "  \"pin\": {\"box\": [[-0.01, -1, -1], [0.01, 1, 1]]}}],"
        " \"colliders\": [{\"plane\": {\"point\": [0, 0, -0.3], \"normal\": [0, 0, 1]}, \"friction\": 0.5}],"
        " \"gravity\": [0, 0, -9.81],"
        " \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01},"
        " \"frames\": 100, \"output\": {\"dir\": \"out\"}}";
    sem_error err;
    sem_scene *scene = NULL;
    CHECK(sem_scene_parse(json, "soak scene", ".", &scene, &err) == SEM_OK, "%s", err.message);
    sem_scene_world_options o = sem_default_scene_world_options();
    sem_scene_world *sw = NULL;
    if (scene) CHECK(sem_scene_world_create(scene, &o, &sw, &err) == SEM_OK, "%s", err.message);
    if (!sw) {
        sem_scene_destroy(scene);
        return test_finish("test_soak");
    }
    sem_world *w = sem_scene_world_world(sw);
    double scale0, e0 = total_energy(w, &scale0), e_max = e0, scale = scale0;
    long rss_start = 0, rss_max = 0, failed_at = -1, touched = 0;
    double min_gap = INFINITY;
    for (long k = 1; k <= steps; ++k) {
        if (sem_world_step(w, &err) != SEM_OK) {
            failed_at = k;
            break;
        }
        sem_contact_stats cs;
        sem_world_contact_stats(w, &cs);
        if (cs.contacts > 0) {
            touched++;
            if (cs.min_gap < min_gap) min_gap = cs.min_gap;
        }
        if (k % 25 == 0) {
            double sc, e = total_energy(w, &sc);
            if (!isfinite(e)) {
                failed_at = k;
                break;
            }
            if (e > e_max) e_max = e;
            if (sc > scale) scale = sc;
        }
        if (k == 50) rss_start = resident_kb();
        if (k > 50 && k % 25 == 0) {
            long r = resident_kb();
            if (r > rss_max) rss_max = r;
        }
    }
    CHECK(failed_at < 0, "step %ld failed: %s", failed_at, failed_at >= 0 ? err.message : "");
    CHECK(e_max <= e0 + 1e-6 * scale, "energy grew from %.17g to %.17g (scale %.3g)", e0, e_max,
          scale);
    double sc_end, e_end = total_energy(w, &sc_end);
    printf("test_soak: %ld steps, t = %g s; energy %.10g -> %.10g (max %.10g); in contact in %ld "
           "steps, smallest gap %.3g m; resident %ld KB after 50 steps, at most %ld KB after\n",
           steps, sem_world_time(w), e0, e_end, e_max, touched, min_gap, rss_start, rss_max);
    CHECK(touched > 0, "the beam never touched the floor");
    CHECK(min_gap > -0.02 * 0.4, "the beam sank %.3g m into the floor", -min_gap);
    if (!sanitized)
        CHECK(rss_max - rss_start <= 2048, "resident memory grew by %ld KB after step 50",
              rss_max - rss_start);
    sem_scene_world_destroy(sw);
    sem_scene_destroy(scene);
    return test_finish("test_soak");
}
