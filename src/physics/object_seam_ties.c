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
 * SEM_SEAM_TOLERANCE of the size, or the pair is not a seam), the tie holds the gap as it
 * is: its energy is k E ds |(x_a - x_b) - d0|^2, whose linear part is a constant force
 * f_seam = 2 gamma sum w D^T d0 (o->f_seam, added to the external force), so the rest state
 * is in equilibrium. The tie vanishes for every translation, and for rotations and affine
 * motions of pairs that coincide at rest; a pair with a gap resists turning its gap vector
 * with an energy of order k E ds |d0|^2 per pair (d0 <= 1e-3 of the size: far below the
 * elastic energies of any deformation a run shows). The error energy a run reports is the
 * ties' true energy: gamma q^T M_eps q less f_seam . (q - q0) and the constant gamma sum w
 * |d0|^2 (sem_seam_ties_gap_energy).
 */
#include <math.h>
#include <stdlib.h>

#include "object.h"

sem_status sem_object_find_seam_ties(sem_object *o, double stiffness, sem_error *err)
{
    o->n_seam_ties = 0;
    o->seam_tie_pair = NULL;
    o->seam_tie_weight = NULL;
    o->f_seam = NULL;
    o->seam_c0 = 0;
    if (!(stiffness > 0)) return SEM_OK;
    if (!o->seams_built) {
        sem_status st = sem_seams_build(o->def.model, SEM_SEAM_TOLERANCE, &o->seams, err);
        if (st != SEM_OK) return st;
        o->seams_built = 1;
    }
    const sem_seams *s = &o->seams;
    if (s->n_pairs == 0) return SEM_OK;
    o->seam_tie_pair = malloc((size_t)s->n_pairs * sizeof(int));
    o->seam_tie_weight = malloc((size_t)s->n_pairs * sizeof(double));
    if (!o->seam_tie_pair || !o->seam_tie_weight) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    double E = o->def.material.youngs_modulus;
    for (int k = 0; k < s->n_pairs; ++k) {
        if (!(s->rest_distance[k] <= SEM_SEAM_TIE_GAP * s->size) || !(s->length[k] > 0)) continue;
        o->seam_tie_pair[o->n_seam_ties] = k;
        o->seam_tie_weight[o->n_seam_ties++] = stiffness * E * s->length[k] / o->gamma;
    }
    /* the rest gaps' constant force */
    for (int t = 0; t < o->n_seam_ties; ++t) {
        int k = o->seam_tie_pair[t], a1 = s->row_start[2 * k + 1];
        int e0 = s->row_start[2 * k], e1 = s->row_start[2 * k + 2];
        double d0[3] = {0, 0, 0};
        for (int e = e0; e < e1; ++e) {
            double v = e < a1 ? s->row_w[e] : -s->row_w[e];
            for (int c = 0; c < 3; ++c) d0[c] += v * o->q0[3 * (size_t)s->row_ctrl[e] + c];
        }
        if (d0[0] == 0 && d0[1] == 0 && d0[2] == 0) continue;
        if (!o->f_seam && !(o->f_seam = calloc(3 * (size_t)o->n_ctrl, sizeof(double))))
            return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        double c2 = 2.0 * o->gamma * o->seam_tie_weight[t];
        o->seam_c0 += o->gamma * o->seam_tie_weight[t] * (d0[0] * d0[0] + d0[1] * d0[1] + d0[2] * d0[2]);
        for (int e = e0; e < e1; ++e) {
            double v = e < a1 ? s->row_w[e] : -s->row_w[e];
            for (int c = 0; c < 3; ++c) o->f_seam[3 * (size_t)s->row_ctrl[e] + c] += c2 * v * d0[c];
        }
    }
    return SEM_OK;
}

double sem_seam_ties_gap_energy(const sem_object *o, const double *q)
{
    if (!o->f_seam) return 0;
    double e = -o->seam_c0;
    for (size_t i = 0; i < 3 * (size_t)o->n_ctrl; ++i) e -= o->f_seam[i] * (q[i] - o->q0[i]);
    return e;
}
