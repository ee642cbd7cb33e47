/*
 * object_seam_ties.c - faces that meet at rest stay together (sem_object_def.seam_ties).
 *
 * Why: SEM moves every part's control points with its own polynomial (Eq. 6-7) and couples
 * the parts only through the blending weights and the error energy (Eq. 16). A relative
 * translation of two neighbouring parts' polynomials costs no elastic energy (Eq. 15 holds
 * the weights constant), and the error energy resists it only where the parts' weights
 * overlap, near their seams. So a face that takes a load its few control points cannot pass
 * on (contact on a large flat face, a soft body landing) moves away from its neighbours:
 * the model comes apart along its seams although the CAD says they are one edge. Welds
 * (object_welds.c) hold control points that coincide; the seams of trimmed faces join parts
 * whose control points do not.
 *
 * What: the seam monitor's pairs (geometry/seams.c: points of two parts' boundaries that
 * coincide at rest, about 1 % of the model's size apart along the boundary) become rows
 * J_a - J_b of the error matrix (the two points' rows of the render map x = J q), each of
 * weight k E ds / gamma, ds the boundary length the pair stands for: the energy
 *   k E sum_pairs ds |x_a - x_b|^2,
 * a penalty coupling of the patches along their shared edges, as isogeometric analysis
 * couples non-matching patches. It is a constant quadratic form, so it joins Eq. 16's matrix
 * and every solver and integrator takes it as it takes that one.
 *
 * Gaps. Where a file leaves a gap between two faces (d0 = x_a - x_b at rest, at most
 * SEM_SEAM_TOLERANCE of the size: farther points are no seam pair), the tie holds the gap as it
 * is: the error energy is measured on the displacement q - q0 (mass_error.c,
 * sem_error_energy), so a row is |D (q - q0)|^2 = |(x_a - x_b) - d0|^2 and the rest state is
 * in equilibrium. The tie vanishes for every translation, and for rotations and affine motions
 * of pairs that coincide at rest; a pair with a gap resists turning its gap vector with an
 * energy of order k E ds |d0|^2 per pair (d0 <= 1e-3 of the size: far below the elastic
 * energies of any deformation a run shows).
 */
#include <math.h>
#include <stdlib.h>

#include "object.h"

sem_status sem_object_find_seam_ties(sem_object *o, double stiffness, sem_error *err)
{
    o->n_seam_ties = 0;
    o->seam_tie_pair = NULL;
    o->seam_tie_weight = NULL;
    if (!(stiffness > 0)) return SEM_OK;
    sem_status st = sem_object_seams(o, err);
    if (st != SEM_OK) return st;
    const sem_seams *s = &o->seams;
    if (s->n_pairs == 0) return SEM_OK;
    o->seam_tie_pair = malloc((size_t)s->n_pairs * sizeof(int));
    o->seam_tie_weight = malloc((size_t)s->n_pairs * sizeof(double));
    if (!o->seam_tie_pair || !o->seam_tie_weight) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    double E = o->def.material.youngs_modulus;
    for (int k = 0; k < s->n_pairs; ++k) {
        if (!(s->length[k] > 0)) continue; /* a pole's single point */
        o->seam_tie_pair[o->n_seam_ties] = k;
        o->seam_tie_weight[o->n_seam_ties++] = stiffness * E * s->length[k] / o->gamma;
    }
    return SEM_OK;
}
