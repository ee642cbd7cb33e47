/*
 * object_checks.c - is an object's current state an answer to trust? (sem/simulation.h,
 * sem_world_object_checks; docs/simulation.md, "Trust").
 *
 * Three measurements of the state, none of which the step itself needs:
 *   - seams: the largest opening between points of different parts that meet at rest
 *     (geometry/seams.c). SEM ties its parts only through the blending weights and the error
 *     energy (Eq. 16): a face whose few control points take a load the coupling cannot carry
 *     moves away from its neighbours, and the model the user gets back has holes in it.
 *   - the error energy's share: Eq. 16 is a penalty that should stay small against the
 *     elastic energy (Eq. 15); when it holds as much, the polynomials no longer describe the
 *     surface and the elastic answer is not the body's.
 *   - the volume: sum_p vol_p det F_p against the rest volume, reported (loads and prescribed
 *     motion change it legitimately: the patch test stretches a cube by 10 %), and the
 *     smallest det F: an element turned inside out (materials that allow it) is suspect.
 * And one of the setup: a material pin box that holds all of a part's polynomial while the
 * part reaches beyond it (pins.h, sem_pins_held_parts) makes that material rigid.
 * Each has a limit (sem/simulation.h); a state beyond one is suspect.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "assembly.h"
#include "pins.h"
#include "world.h"

sem_status sem_object_seams(sem_object *o, sem_error *err)
{
    if (o->seams_built) return SEM_OK;
    sem_status st = sem_seams_build(o->def.model, SEM_SEAM_TOLERANCE, &o->seams, err);
    if (st == SEM_OK) o->seams_built = 1;
    return st;
}

sem_status sem_world_object_checks(sem_world *w, int object, sem_object_checks *out, sem_error *err)
{
    memset(out, 0, sizeof *out);
    out->seam_parts[0] = out->seam_parts[1] = -1;
    out->pin_part = -1;
    if (object < 0 || object >= w->n_objects)
        return sem_error_set(err, SEM_ERR_INVALID, "no object %d (the world has %d)", object, w->n_objects);
    sem_object *o = w->objects[object];
    sem_status st = sem_object_seams(o, err);
    if (st != SEM_OK) return st;
    sem_seam_gap gap;
    sem_seams_measure(&o->seams, o->q, &gap);
    out->seam_pairs = o->seams.n_pairs;
    out->seam_gap = gap.gap;
    out->seam_gap_relative = gap.relative;
    if (gap.pair >= 0) {
        out->seam_parts[0] = gap.part_a;
        out->seam_parts[1] = gap.part_b;
        memcpy(out->seam_X, gap.X, sizeof gap.X);
    }
    /* energies: the elastic one is undefined for an inverted state (then it is suspect by
     * its volume) */
    double *work = malloc(3 * (size_t)o->n_ctrl * sizeof(double) + 1);
    if (!work) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    double error = sem_error_energy(o, o->q, work);
    free(work);
    sem_error e;
    double elastic = sem_assemble_elastic(o, o->q, 0, NULL, NULL, &e) == SEM_OK ? o->elastic_energy : INFINITY;
    double floor = SEM_CHECK_ENERGY_FLOOR * o->def.material.youngs_modulus * o->volume;
    if (error > floor || elastic > floor) out->error_share = isfinite(elastic) ? error / (error + elastic) : 0;
    double min_det = 1;
    double volume = sem_deformed_volume(o, o->q, &min_det);
    out->volume_change = o->volume > 0 ? volume / o->volume - 1 : 0;
    out->min_det_f = min_det;
    if (out->seam_gap_relative > SEM_SEAM_GAP_LIMIT) out->suspect |= SEM_SUSPECT_SEAM;
    if (out->error_share > SEM_ERROR_SHARE_LIMIT) out->suspect |= SEM_SUSPECT_ERROR_SHARE;
    if (!(min_det > 0)) out->suspect |= SEM_SUSPECT_INVERTED;
    if (o->pins && o->pins->held_part >= 0) {
        out->pin_part = o->pins->held_part;
        out->pin_outside = o->pins->held_outside;
        out->suspect |= SEM_SUSPECT_PIN;
    }
    return SEM_OK;
}
