/* test_table1_modes.c - every Table 1 model at default settings has no zero-energy modes
 * (sem_world_object_modes; issue 11). Needs ../shared/models; skipped under the sanitizers
 * (minutes there; the Release run checks it). Before the volume consistency term
 * (sem_object_def.blend) the tire, chicken, castle and starship had 8 or more. */
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/simulation.h"
#include "bench/validation.h"
#include "test_util.h"

/* Every Table 1 model at defaults: no zero-energy modes. */
static void check_models(void)
{
    for (int k = 0; k < sem_table1_count; ++k) {
        const sem_table1_row *r = &sem_table1[k];
        const char *shared = test_shared_model(r->file);
        if (!shared) return;
        char path[4096];
        snprintf(path, sizeof path, "%s", shared);
        sem_model *m = NULL;
        sem_discretization *d = NULL;
        sem_world *w = NULL;
        sem_error err;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            CHECK(0, "%s: %s", path, err.message);
            continue;
        }
        sem_preprocess_options o = sem_default_preprocess_options();
        o.youngs_modulus = r->youngs_modulus;
        if (sem_preprocess(m, &o, &d, &err) != SEM_OK) {
            CHECK(0, "%s: %s", path, err.message);
            sem_model_destroy(m);
            continue;
        }
        sem_world_def wd = sem_default_world_def();
        w = sem_world_create(&wd, &err);
        sem_object_def od = sem_default_object_def();
        od.model = m;
        od.disc = d;
        od.material.density = r->density;
        od.material.youngs_modulus = r->youngs_modulus;
        od.material.poisson_ratio = r->poisson_ratio;
        sem_object_modes md;
        memset(&md, 0, sizeof md);
        if (!w || sem_world_add_object(w, &od, &err) < 0 || sem_world_object_modes(w, 0, &md, NULL, &err) != SEM_OK)
            CHECK(0, "%s: %s", r->file, err.message);
        else {
            printf("%-24s %5d dofs: %d spurious modes, lowest %.3g\n", r->example, 3 * d->n_ctrl, md.spurious,
                   md.values[0]);
            CHECK(md.spurious == 0, "%s: %d zero-energy modes at defaults", r->file, md.spurious);
        }
        sem_world_destroy(w);
        sem_discretization_destroy(d);
        sem_model_destroy(m);
    }
}

int main(void)
{
    if (!getenv("SEM_SANITIZED")) check_models();
    return test_finish("test_table1_modes");
}
