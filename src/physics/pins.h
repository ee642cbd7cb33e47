/*
 * pins.h - material pins: the material inside a box held where its pin puts it, as FEM's
 * fixed nodes hold a mesh (internal to src/physics/; API: sem_object_def.pin_regions).
 *
 * Why not control points. A control point pin holds the control points that happen to lie
 * in a box, and the control nets of trimmed CAD faces reach far beyond what the trims keep:
 * "pin the first millimetre" of a part made of trimmed planes held faces that span the whole
 * part (an 11 mm part came out rigid, 0.2 % of FEM's sag). What the user means is the
 * material there: the deformation x(X) = Gamma(X) q (Eq. 12) at the points of the box.
 *
 * The anchor. Every material point a of a pin region - the volume quadrature points whose
 * rest position X_a lies in the box, and the boundary samples in it - is tied to its target
 * X_a(t) (the rest position, or the prescribed motion of the region's prescription) by
 *
 *   E_pin(q, t) = k / 2 sum_a w_a |Gamma_a q - X_a(t)|^2,   w_a = vol_a (quadrature point)
 *                                                               or a_s h / 2 (sample: a skin
 *                                                               of half a quadrature cell),
 *   k = SEM_PIN_STIFFNESS E / h^2 (E the object's largest Young's modulus, h the quadrature
 *   spacing): the stiffness of a cell of material against a displacement of its own size, so
 *   the anchored material moves SEM_PIN_STIFFNESS times less than the body strains it to.
 *
 * The samples matter: a thin box (the usual "the first centimetre") holds no quadrature
 * point, whose first layer lies half a cell inside. They are anchored through the SEM map
 * Gamma_s (the polynomials, like the quadrature points), not through the surface J_s: a
 * trimmed face's J_s at a sample combines control points spread over the whole face, so
 * holding J_s q holds the face - the very problem. The surface follows the polynomials
 * through the error energy (Eq. 16), as everywhere else.
 *
 * Gamma_a = sum_i w_ai b(X_a - Xbar_i)^T Pi_i (Eq. 6-7), so the anchor is a constant quadratic
 * form with Hessian A = k sum_a w_a Gamma_a^T Gamma_a: the mass matrix's form (Eq. 14) with
 * k w_a in place of rho vol_p, built the same way - z-space part-pair blocks sum_a k w_a
 * e_ai e_aj^T (e_ai = w_ai b(X_a - Xbar_i)), taken through Pi into the q-space group-pair blocks
 * (mass_error.c), or kept in z-space as a term of the structured solver's Z (structured.h).
 * Every matrix of an object gets it as a fifth coefficient c_A beside M, M_eps, K and K0: the
 * coefficient of a potential's Hessian (h^2 in the linearly implicit step, 1 in Newton), 0 in
 * the free object's mode search. Its force and energy need the target, which moves with
 * prescribed motion: they are evaluated here, in z-space (Pi_i q for the parts touched, then
 * the few anchored points), which is Gamma's rows without forming them (a structured object
 * has no Gamma at the samples).
 *
 * Momentum is not conserved by an anchored body (the anchors are its supports).
 * Everything runs serially in point order: the same bits on any thread count.
 */
#ifndef SEM_PHYSICS_PINS_H
#define SEM_PHYSICS_PINS_H

#include "object.h"

typedef struct sem_pins {
    int n_points;       /* anchored points: quadrature points, then boundary samples */
    double *weight;     /* k w_a */
    double *X;          /* rest positions, 3 per point */
    int *presc;         /* per point: index into presc, or -1 (held at rest) */
    int *start;         /* per point: its entries (the parts blended there), CSR */
    int *part;
    double *basis;      /* per entry: m values w_ai b(X_a - Xbar_i) in the part's own basis */
    int n_presc;
    sem_prescribe *prescribes; /* the regions' prescriptions, copied */
    int n_touched;      /* parts with an entry, ascending */
    int *touched;
    int *touched_slot;  /* per part: its index in touched, or -1 */
    double stiffness;   /* k */
    double spacing;     /* h, the quadrature spacing k is scaled by */
    int moves;          /* 1: some anchored point follows a motion */
    /* A box that holds all of a part's polynomial while the part's material reaches beyond it
     * (sem_pins_held_parts): the part with the most material outside, -1 when none. */
    int held_part;
    double held_outside; /* that part's share of its material (blended volume) outside */
} sem_pins;

/* The anchored points of def->pin_regions (o->pins stays NULL when there are none). Needs the
 * object's materials and layout (part pairs, pi_dense). A region holding no material is an
 * error naming its box. */
sem_status sem_pins_init(sem_object *o, const sem_object_def *def, sem_error *err);
void sem_pins_free(sem_object *o);
/* pairs (o->n_pairs blocks of m x m, row-major, the parts' own bases) += the anchors' z-space
 * blocks sum_a k w_a e_ai e_aj^T (pair (i, j) = o->pair_lookup[i n_parts + j]). */
void sem_pins_add_pair_blocks(const sem_object *o, double *pairs);
/* E_pin(q, t); grad (may be NULL) += its gradient A q - k sum w_a Gamma_a^T X_a(t). 0 without
 * pins. */
double sem_pins_energy(const sem_object *o, const double *q, double t, double *grad);
/* y += c A x (3 n_ctrl each). */
void sem_pins_multiply(const sem_object *o, double c, const double *x, double *y);
/* Parts whose whole polynomial a box holds. A part has one polynomial over the whole part
 * (Eq. 7), so anchoring material that determines it (a volume of quadrature points; or a 2D
 * stretch of a face's samples, which fixes the polynomial on the face's own surface) holds all
 * of the part, also its material outside the box: that material cannot deform and the answer
 * is stiffer than the body (a 2 cm box pinned over its lowest 10 % sagged 9 % of FEM's
 * answer). Held means: every motion of the part's polynomial costs the anchor more than the
 * part's own stiffness for a motion of its size, k lambda_min > E / L^2, lambda_min the least
 * held share of a motion of the part's surface (generalized eigenvalue of the anchored points'
 * form against the form of the part's own samples), L the size of its surface. A thin
 * slab at a face (the recommended clamp) holds the face's samples only near the slab. Parts
 * with more than SEM_PIN_HELD_OUTSIDE of their surface (by area) outside every box are counted; the run
 * reports the largest share as suspect (object_checks.c). Sets p->held_part, p->held_outside. */
#define SEM_PIN_HELD_OUTSIDE 0.05
void sem_pins_held_parts(const sem_object *o, const sem_object_def *def);
/* Largest distance of an anchored point from its target at time t (0 without pins). */
double sem_pins_residual(const sem_object *o, const double *q, double t);

#endif
