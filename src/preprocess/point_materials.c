/*
 * point_materials.c - which part's material each volume quadrature point takes.
 *
 * A point takes the material of the solid it lies in (Sec. 7: heterogeneous materials; the
 * tire's steel hub inside its rubber tread). The quadrature step finds, along each ray, the
 * innermost *component* (touching parts, raycast.h) the point lies in; a component entered
 * through one face and left through another is still the same solid, whatever the ray
 * direction. Within that component the point takes the part with the largest blending weight
 * there (Eq. 8-9): in a solid whose faces carry different materials (examples/
 * two_materials.json: the sections near the clamp stiff, the others soft) the material
 * changes where the weights of one section's faces give way to the next one's, which is the
 * plane between the sections for a beam. Earlier, a point took the face its ray entered
 * through, so a beam sampled along its axis was made entirely of its first end cap's
 * material.
 */
#include "steps.h"

sem_status sem_step_point_materials(const sem_raycast_scene *scene, sem_discretization *d,
                                    sem_error *err)
{
    if (!d || d->W.n_rows != d->n_quad || (d->n_quad > 0 && !d->quad_part))
        return sem_error_set(err, SEM_ERR_INVALID, "materials: quadrature or weights missing");
    for (int p = 0; p < d->n_quad; ++p) {
        int comp = sem_raycast_part_component(scene, d->quad_part[p]);
        int best = -1;
        double bw = -1.0;
        for (int k = d->W.row_start[p]; k < d->W.row_start[p + 1]; ++k) {
            int i = d->W.col[k];
            if (sem_raycast_part_component(scene, i) == comp && d->W.val[k] > bw) {
                bw = d->W.val[k];
                best = i;
            }
        }
        if (best >= 0) d->quad_part[p] = best;
    }
    return SEM_OK;
}
