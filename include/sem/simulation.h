/*
 * sem/simulation.h - elastodynamics of preprocessed SEM objects (paper Sec. 7, Alg. 2).
 *
 * A world holds objects; each object is a NURBS model with its discretization
 * (sem/preprocess.h), materials, pinned control points and loads. The state of an object
 * is its control points q (3 per control point) and their velocities. A step advances
 * every object by dt with the chosen integrator; objects touching each other or a static
 * collider are kept apart by contact springs with friction (sem/contact.h).
 *
 * Usage: def = sem_default_world_def(); edit; world = sem_world_create(&def, &err);
 * obj = sem_default_object_def(); edit; sem_world_add_object(world, &obj, &err);
 * loop sem_world_step(world, &err); read sem_world_object_q(world, i), destroy.
 */
#ifndef SEM_SIMULATION_H
#define SEM_SIMULATION_H

#include "sem/contact.h"
#include "sem/material.h"
#include "sem/model.h"
#include "sem/preprocess.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef enum sem_integrator {
    SEM_LINEARLY_IMPLICIT_EULER, /* the paper's: one linear solve per step */
    SEM_IMPLICIT_EULER,          /* Newton on the incremental potential with line search */
    SEM_STATIC                   /* Newton to equilibrium (each "step" solves statics) */
} sem_integrator;

typedef enum sem_solver_choice {
    SEM_SOLVER_AUTO,   /* a fixed rule: structured when the control points are at least twice the
                          coefficients (n_parts m), else dense up to 500 dofs, CHOLMOD above */
    SEM_SOLVER_SPARSE, /* CHOLMOD */
    SEM_SOLVER_DENSE,  /* LAPACK dpotrf */
    SEM_SOLVER_STRUCTURED /* part-sparse plus low rank through Pi (Woodbury); no q-space matrix */
} sem_solver_choice;

/* Messages of a world: level 0 information (Newton's trace, when asked for), 1 warning. */
typedef void (*sem_world_log_fn)(void *user, int level, const char *message);

/* Settings for tests, studies and debugging; zero (the default) suits every other use. */
typedef struct sem_world_advanced {
    int assembly_chunk;    /* quadrature points per stiffness assembly chunk; <= 0: 8192 */
    int projected_hessian; /* 1: Newton keeps the PSD-projected Hessian throughout; 0: it
                              switches to the exact one once two steps in a row are full */
    int trace_newton;      /* 1: one log line per Newton iteration */
    int solve_together;    /* 1: every object in one linear system at every step; 0: with
                              contact between objects, one system per island (objects that
                              may touch within the step), without, one per object */
    int q_space_solvers;   /* 1: the sparse or dense solver, never the structured one (a
                              world with contact: its terms go into the q-space matrix) */
    int refactorize;       /* 1: the linearly implicit step factorizes its matrix every step
                              (the paper's way); 0 (default): it reuses the rest matrix's
                              factor while the stiffness stays near its rest value
                              (src/physics/integrators.c, "Reusing the rest factor") */
} sem_world_advanced;

typedef struct sem_world_def {
    double gravity[3];
    sem_integrator integrator;
    double dt;
    double rayleigh_mass, rayleigh_stiffness; /* damping C = a M + b K */
    double newton_tolerance;   /* relative gradient norm; default 1e-8 */
    int newton_max_iterations; /* default 50 (static: 200) */
    sem_solver_choice solver;
    int threads;               /* 0: OpenMP default */
    int accept_unconverged;    /* 1: a Newton solve that misses its tolerance within
                                  newton_max_iterations keeps its last iterate (counted in
                                  sem_world_counters.unconverged_solves, logged); 0 (default):
                                  it fails with SEM_ERR_NUMERIC */
    sem_world_log_fn log;      /* may be NULL */
    void *log_user;
    sem_world_advanced advanced;
    sem_contact_def contact;   /* contact settings (sem/contact.h); zero: the defaults */
} sem_world_def;

sem_world_def sem_default_world_def(void);
/* 1 when a world with these settings solves an object of n_ctrl control points, n_parts
 * parts and n_basis polynomial terms (4 or 10) with the structured solver (the rule of
 * SEM_SOLVER_AUTO); its discretization then needs no q-space operators
 * (sem_preprocess_options.q_space_operators), which the other solvers do. shared_fit: the
 * parts of an origin share one polynomial (sem_preprocess_shared_fit): made for the structured
 * solver, which AUTO then always picks (unless objects are solved together). */
int sem_world_def_structured(const sem_world_def *def, size_t n_ctrl, int n_parts, int n_basis,
                             int shared_fit);

typedef enum sem_prescribe_type {
    SEM_PRESCRIBE_NONE,
    SEM_PRESCRIBE_AFFINE, /* pinned points go to A x0 + b (reached at once) */
    SEM_PRESCRIBE_ROTATE, /* pinned points rotate about an axis at a rate (rad/s) */
    SEM_PRESCRIBE_MOVE    /* pinned points move at a constant velocity (m/s) */
} sem_prescribe_type;

typedef struct sem_prescribe {
    sem_prescribe_type type;
    double affine[12];      /* 3 x 4 row-major [A | b] */
    double axis_point[3];
    double axis_direction[3];
    double rate;            /* rad/s */
    double duration;        /* rotate or move only until this time (<= 0: forever) */
    double velocity[3];     /* move: x0 + velocity min(t, duration) */
} sem_prescribe;

/* A load on the material of a region: force per unit volume (N/m^3) on the volume quadrature
 * points whose rest position lies in the box (x = Gamma q there, so the force reaches the
 * control points as Gamma^T f: the material is loaded, whatever control points lie in the
 * box), scaled by (1 + sin(2 pi frequency t + phase)) / 2 when frequency > 0, or constant. */
typedef struct sem_region_load {
    double box[6];          /* lo[3], hi[3] */
    double force_density[3];
    double frequency, phase;
} sem_region_load;

/* A material pin: the material inside the box - the volume quadrature points and boundary
 * samples whose rest position lies in it (inclusive) - is held at its rest position, or moved
 * by a prescription, as the fixed nodes of a finite element mesh are. Each such point X_a is
 * tied to its target X_a(t) by the stiff anchor k / 2 w_a |x(X_a) - X_a(t)|^2 (w_a its volume,
 * or for a sample its area times half the quadrature spacing h), k = SEM_PIN_STIFFNESS E / h^2
 * (E the object's largest Young's modulus): the material moves about SEM_PIN_STIFFNESS times
 * less than the body strains it to (src/physics/pins.h). Unlike a pinned control point
 * (sem_object_def.pinned), it holds what lies in the box and nothing else: the control nets of
 * trimmed faces reach far outside the faces. A box that holds no material is an error. */
typedef struct sem_pin_region {
    double box[6];          /* lo[3], hi[3], in the model's coordinates at rest */
    int prescribe;          /* -1: held at rest; k >= 0: moves by prescribes[k] (with
                               n_prescribes > 0), or by prescribe (k = 0, no prescribes) */
} sem_pin_region;

#ifndef SEM_PIN_STIFFNESS
#define SEM_PIN_STIFFNESS 1e3
#endif

typedef struct sem_point_load {
    double X[3];            /* rest position where the force acts */
    double force[3];
} sem_point_load;

typedef struct sem_object_def {
    const sem_model *model;              /* rest geometry (already transformed) */
    const sem_discretization *disc;      /* preprocessed data of that model */
    sem_material material;               /* default for every part */
    const int *part_material;            /* per part index into part_materials, or -1; may be NULL */
    const sem_material *part_materials;
    int n_part_materials;
    double gamma;                        /* error stiffness; <= 0: disc->gamma scaled by E */
    /* Volume consistency stiffness c (dimensionless; sem_default_object_def: SEM_DEFAULT_BLEND,
     * 0: none): adds c E / alpha^2 sum_p vol_p sum_i w_pi |P_i(X_p) - x(X_p)|^2, the spread of
     * the overlapping parts' polynomials around the blended position at every quadrature point
     * (alpha the weights' cut-off distance). It vanishes for every motion all parts agree on
     * (rigid, affine), so it leaves the patch test and momentum alone; it stiffens the motions
     * Eq. 15 leaves free (see docs/simulation.md, "Zero-energy modes"). */
    double blend;
    /* How the error energy (Eq. 16) treats a boundary sample shared by several parts (on a
     * seam): SEM_SEAMS_GEOMETRIC (0, the default) or SEM_SEAMS_PAPER (docs/refine.md,
     * "Seams"). */
    int seams;
    /* Welds (1; sem_default_object_def: 0): control points that coincide at rest (within
     * SEM_WELD_TOLERANCE of the model's size) are held together - where a model was cut into
     * patches (sem_model_patches), where a B-rep's faces share an edge, at a collapsed edge (a
     * pole), on the seam of a closed surface - by a tie in the error matrix SEM_WELD_STIFFNESS
     * times a control point's typical error weight (together to about 1e-6 of the size).
     * Without them only the error energy (Eq. 16) keeps such seams shut, softly. The ties are
     * stiff: the sums that conserve momentum and the error energy then carry round-off of
     * about 1e-5 of their size (1e-7 without), so they are off by default (the paper's
     * discretization) and on for patches (scene key sem.weld, default: with
     * sem.resolution). */
    int weld;
    const unsigned char *pinned;         /* per control point, 1 = pinned; may be NULL */
    sem_prescribe prescribe;             /* motion of every pinned point (all points when
                                            pinned is NULL and there are no pin_regions),
                                            unless prescribe_group is given */
    /* Several prescribed groups (e.g. a twisting beam: one end fixed, the other rotating):
     * prescribe_group[c] indexes prescribes (-1: none). A point with a group is pinned and
     * follows that group's motion; other pinned points stay where they are. */
    const int *prescribe_group;
    const sem_prescribe *prescribes;
    int n_prescribes;
    /* Material pins (sem_pin_region; copied): the material in each box held, or moved by its
     * prescription. */
    const sem_pin_region *pin_regions;
    int n_pin_regions;
    double initial_velocity[3];
    double initial_angular_velocity[3];  /* about the centre of mass */
    const sem_point_load *point_loads;
    int n_point_loads;
    const sem_region_load *region_loads;
    int n_region_loads;
    double friction;                     /* Coulomb coefficient of its surface
                                            (sem_default_object_def: SEM_DEFAULT_FRICTION) */
    /* Seam ties k (dimensionless; sem_default_object_def: 0, the paper's coupling; scenes:
     * SEM_DEFAULT_SEAM_TIES): points where two parts meet at rest (the seam monitor's pairs,
     * sem/measure.h) are held together by the energy k E sum ds |x_a - x_b - d0|^2 (ds the
     * boundary length a pair stands for, d0 its rest gap), a penalty coupling of the faces
     * along their shared edges (docs/simulation.md, "Seam ties"). It vanishes for every
     * motion of the body as a whole, so the patch test and momentum stay. */
    double seam_ties;
} sem_object_def;

#define SEM_DEFAULT_BLEND 0.02
/* The scenes' seam tie stiffness (sem_object_def.seam_ties; docs/simulation.md). */
#define SEM_DEFAULT_SEAM_TIES 30.0
#define SEM_WELD_TOLERANCE 1e-9
#ifndef SEM_WELD_STIFFNESS
#define SEM_WELD_STIFFNESS 1e3
#endif

/* sem_object_def.seams. PAPER: the residual of the blended map, |sum_i w_i P_i(X) - x|^2,
 * weighted by the sample's area in its knot span (Eq. 16 as written). GEOMETRIC: the
 * partition form sum_i w_i |P_i(X) - x|^2 (which adds the spread of the polynomials about
 * their blend), weighted as if each part were one knot span across the seam, so that the
 * coupling of two parts depends on their geometry and not on their control nets: a model
 * refined by knot insertion deflects as the original. Samples of one part are the same in
 * both. */
#define SEM_SEAMS_GEOMETRIC 0
#define SEM_SEAMS_PAPER 1

/* Default material, blend SEM_DEFAULT_BLEND, friction SEM_DEFAULT_FRICTION, everything else
 * zero / NULL. */
sem_object_def sem_default_object_def(void);

typedef struct sem_world sem_world;

sem_world *sem_world_create(const sem_world_def *def, sem_error *err);
void sem_world_destroy(sem_world *world);
/* Returns the object index or -1 (err set). */
int sem_world_add_object(sem_world *world, const sem_object_def *def, sem_error *err);
sem_status sem_world_step(sem_world *world, sem_error *err);
/* Solves statics for every object (Newton on V - f^T q), whatever the integrator. */
sem_status sem_world_solve_static(sem_world *world, sem_error *err);

double sem_world_time(const sem_world *world);
/* Sets the time (with sem_world_object_set_state: continuing a stopped run exactly). */
void sem_world_set_time(sem_world *world, double time);
int sem_world_object_count(const sem_world *world);
int sem_world_object_dofs(const sem_world *world, int object);
const double *sem_world_object_q(const sem_world *world, int object);
const double *sem_world_object_velocity(const sem_world *world, int object);
/* Sets q and velocity (3 * control points each; NULL leaves that unchanged). */
void sem_world_object_set_state(sem_world *world, int object, const double *q, const double *v);

typedef struct sem_object_stats {
    double volume, mass;
    double kinetic_energy, elastic_energy, gravity_energy, error_energy;
    double center_of_mass[3], linear_momentum[3], angular_momentum[3];
} sem_object_stats;

/* Quantities computed from the quadrature (momenta through Gamma: x and v at each
 * quadrature point). gravity_energy = -sum rho vol g . x. */
void sem_world_object_stats(const sem_world *world, int object, sem_object_stats *stats);
/* Checks of an object's current state that tell when its answer cannot be trusted
 * (src/physics/object_checks.c; docs/simulation.md, "Trust"). SEM couples its parts only
 * softly (Eq. 16), and where that coupling is too weak the faces of a body come apart while
 * every energy stays finite; these numbers make it visible. */
typedef struct sem_object_checks {
    double seam_gap;          /* largest opening of a seam, m: how much farther apart two
                                 points of different parts are than at rest, over the points
                                 where parts meet at rest (sem/measure.h, "Seams") */
    double seam_gap_relative; /* seam_gap / the object's size (its surface's box diagonal) */
    int seam_parts[2];        /* the two parts of that seam; -1 when none opened */
    double seam_X[3];         /* where (m) */
    int seam_pairs;           /* point pairs watched (0: no part meets another) */
    double error_share;       /* error energy / (elastic + error energy) (Eq. 16 against
                                 Eq. 15); 0 while both are below SEM_CHECK_ENERGY_FLOOR E V */
    double volume_change;     /* sum_p vol_p det F_p / rest volume - 1 (reported only: loads
                                 and prescribed motion change a body's volume legitimately) */
    double min_det_f;         /* smallest det F over the quadrature points */
    int pin_part;             /* a part whose whole polynomial a material pin box holds while
                                 pin_outside of its material lies outside every box (the
                                 largest such share); -1 when none (src/physics/pins.h) */
    double pin_outside;
    int suspect;              /* SEM_SUSPECT_* flags of the limits below that are passed */
} sem_object_checks;

/* Limits beyond which a state is suspect. Measured on the paper's scenes and the public
 * corpus (docs/validation.md, "Seams and trust"). */
#define SEM_SEAM_GAP_LIMIT 0.01      /* seam_gap_relative */
#define SEM_ERROR_SHARE_LIMIT 0.5    /* error_share */
#define SEM_CHECK_ENERGY_FLOOR 1e-9  /* x E V: energies below are noise for error_share */
#define SEM_SUSPECT_SEAM 1
#define SEM_SUSPECT_ERROR_SHARE 2
#define SEM_SUSPECT_INVERTED 4       /* min_det_f <= 0: an element turned inside out (a
                                        material that allows it: linear, St. Venant-Kirchhoff) */
#define SEM_SUSPECT_PIN 8            /* pin_part >= 0: a pin box holds material beyond itself */
#define SEM_SUSPECT_COUNT 4          /* flags above: bits 0 .. SEM_SUSPECT_COUNT - 1 */

/* The checks of object `object` now. The first call finds the object's seams (a pass over
 * its parts' boundaries, about the cost of a few steps); later calls cost about one
 * evaluation of the elastic energy. */
sem_status sem_world_object_checks(sem_world *world, int object, sem_object_checks *out, sem_error *err);

/* Timing of the last step and the solver in use ("cholmod" or "dense"). */
double sem_world_last_step_seconds(const sem_world *world);
double sem_world_last_factor_seconds(const sem_world *world);
const char *sem_world_solver_name(const sem_world *world, int object);
/* Percentage of non-zeros of the q-space system matrix (Table 1's Nnz). */
double sem_world_object_nnz_percent(const sem_world *world, int object);
/* Newton iterations of the last step (implicit/static). */
int sem_world_last_iterations(const sem_world *world);

/* Control points of an object that its boundary samples do not determine (supported only
 * where a trim removed the surface, or too many for the few samples a small trim keeps):
 * each is tied to its part's polynomial fit at its rest position (docs/simulation.md,
 * "Robustness choices"). part_counts (the model's n_parts, may be NULL) receives how many
 * per part. Returns the total. */
int sem_world_object_tied_points(const sem_world *world, int object, int *part_counts);

/* Zero-energy (spurious) modes of an object: motions of the free object, beyond the 6
 * rigid ones, that its rest stiffness (elastic + error energy) does not resist. values are
 * the lowest non-rigid eigenvalues of K x = lambda M x as lambda rho L^2 / E (L the
 * preprocessing length scale): a body's elastic modes are above about 2 / a^2 (a its aspect
 * ratio: 5e-3 for a 1:20 beam), spurious ones below SEM_SPURIOUS_MODE_TOLERANCE (so bodies
 * thinner than about 1:400 would be counted too). spurious == n_values means at least that
 * many. */
#define SEM_SPURIOUS_MODE_TOLERANCE 1e-5
#define SEM_MODES_MAX 8
typedef struct sem_object_modes {
    int spurious;
    int n_values;
    double values[SEM_MODES_MAX];
    int converged;                /* 1: the iteration met its tolerance */
} sem_object_modes;
/* Computes them (one factorization of the object's matrix with every point free, and a
 * subspace iteration: about the cost of a few steps). part_flags (n_parts, may be NULL)
 * receives 1 for each part that moves in a spurious mode (a part not held). */
sem_status sem_world_object_modes(sem_world *world, int object, sem_object_modes *out, int *part_flags,
                                  sem_error *err);

/* What a world has done since it was created (as Box2D's b2World_GetCounters). */
typedef struct sem_world_counters {
    long steps;                   /* successful sem_world_step calls */
    long newton_iterations;       /* Newton iterations of every step and static solve */
    long factorizations;          /* system matrices factorized (an automatic solver choice
                                     tries both solvers on the first one: counted once) */
    long exact_hessian_fallbacks; /* Newton solves whose exact Hessian was not positive
                                     definite, so that went back to the projected one */
    long unconverged_solves;      /* Newton solves kept without reaching the tolerance
                                     (sem_world_def.accept_unconverged) */
    long newton_stalls;           /* Newton solves ended as converged because their full steps
                                     stopped moving while the gradient stayed at its round-off
                                     (src/physics/newton.c, NEWTON_STALL_*) */
    long regroupings;             /* times the objects were put in new systems because the
                                     islands of objects that may touch changed */
    int systems;                  /* linear systems the last step solved (one per island) */
} sem_world_counters;

sem_world_counters sem_world_get_counters(const sem_world *world);

/* A static collider (sem/contact.h), copied. Returns its index or -1 (err set: a zero
 * normal, a mesh with no triangle or a vertex index out of range, a negative friction). */
int sem_world_add_collider(sem_world *world, const sem_collider_def *def, sem_error *err);
/* Contact of the last step (contacts, smallest gap, time). */
void sem_world_contact_stats(const sem_world *world, sem_contact_stats *stats);
/* Memory a run of one object needs, in bytes, estimated from its discretization's sizes
 * (control points, parts, groups, quadrature points, samples, weights) in one cheap pass,
 * before anything large is allocated. src/physics/memory_estimate.c explains every term. */
typedef struct sem_memory_estimate {
    double base;           /* the program and its libraries */
    double discretization; /* the preprocessed data kept during the run (exact) */
    double preprocessing;  /* what sem_preprocess holds beyond its result while it runs */
    double blocks;         /* dense group-pair blocks of M, M_eps, K, K0 and their maps */
    double assembly;       /* per-point and per-part-pair work of the stiffness */
    double solver;         /* system matrix and Cholesky factor */
    double total;          /* base + discretization + max(preprocessing, the three above):
                              the expected peak resident memory of a run of this object */
} sem_memory_estimate;
sem_status sem_world_estimate_memory(const sem_discretization *disc, sem_memory_estimate *out,
                                     sem_error *err);

#ifdef __cplusplus
}
#endif
#endif
