/*
 * fuzz/fuzz_model.h - what the model harnesses do with a model the reader accepted.
 *
 * A full area measure (what `sem inspect` prints) costs milliseconds per part, which would
 * cut the executions per second by a factor of twenty; instead every part's trim region is
 * built and queried on a 5 x 5 grid over its domain and at its corners (the point-in-loop
 * code that once converted NaN to int), and every surface is evaluated at its corners.
 */
#ifndef SEM_FUZZ_MODEL_H
#define SEM_FUZZ_MODEL_H

#include "fuzz.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/trim.h"

static inline void fuzz_use_model(const sem_model *m)
{
    volatile int inside = 0;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_part *p = &m->parts[i];
        const sem_surface *s = &p->surface;
        sem_trim_region *region = NULL;
        sem_error err;
        sem_status st = sem_trim_region_build(p, &region, &err);
        fuzz_check_error(st, &err);
        for (int a = 0; a <= 4; ++a)
            for (int b = 0; b <= 4; ++b) {
                double u = s->u0 + (s->u1 - s->u0) * a / 4, v = s->v0 + (s->v1 - s->v0) * b / 4;
                if (region) inside += sem_trim_region_inside(region, u, v);
                if ((a == 0 || a == 4) && (b == 0 || b == 4)) {
                    double x[3];
                    sem_surface_eval(s, u, v, x, NULL, NULL, NULL);
                }
            }
        sem_trim_region_destroy(region);
    }
    (void)inside;
}

#endif
