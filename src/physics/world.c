/*
 * world.c - the world API (sem/simulation.h): definitions with defaults, creating and
 * destroying worlds, adding objects (materials, state, and the setup of every other
 * physics file in turn), queries and statistics. Stepping is in integrators.c.
 *
 * Where the simulator lives (paper Sec. 7, Alg. 2; design notes in docs/simulation.md):
 *   object.h         an object and the block structure of its matrices (object_layout.c)
 *   assembly.h       its elastic terms (assembly.c), mass and error matrices (mass_error.c)
 *   loads.h          gravity, region and point loads, prescribed motion (loads.c)
 *   pins.h           material pins: the material of a box held (pins.c)
 *   system.h         free dofs, the sparse system of a set of objects, solves
 *                    (system_layout.c over linear_solver.c)
 *   integrators.h    linearly implicit Euler (integrators.c), Newton for implicit Euler
 *                    and statics (newton.c)
 *   world.h          the world: settings, objects, systems, clock, counters
 */
#include "world.h"

#include <math.h>
#include <omp.h>
#include <stdlib.h>
#include <string.h>

#include "assembly.h"
#include "contact_world.h"
#include "input_scales.h"
#include "runaway.h"
#include "loads.h"
#include "pins.h"
#include "system.h"
#include "sem/limits.h"
#include "structured.h"
#include "util/free_all.h"

sem_world_def sem_default_world_def(void)
{
    sem_world_def d;
    memset(&d, 0, sizeof d);
    d.gravity[2] = -9.81;
    d.integrator = SEM_LINEARLY_IMPLICIT_EULER;
    d.dt = 0.01;
    d.newton_tolerance = 1e-8;
    d.newton_max_iterations = 50;
    d.solver = SEM_SOLVER_AUTO;
    return d;
}

sem_object_def sem_default_object_def(void)
{
    sem_object_def d;
    memset(&d, 0, sizeof d);
    d.material = sem_default_material();
    d.blend = SEM_DEFAULT_BLEND;
    d.friction = SEM_DEFAULT_FRICTION;
    return d;
}

sem_world *sem_world_create(const sem_world_def *def, sem_error *err)
{
    if (!(def->dt > 0) || !isfinite(def->dt)) {
        sem_error_set(err, SEM_ERR_INVALID, "time step dt must be positive (got %g)", def->dt);
        return NULL;
    }
    for (int k = 0; k < 3; ++k)
        if (!isfinite(def->gravity[k])) {
            sem_error_set(err, SEM_ERR_INVALID, "gravity must be finite");
            return NULL;
        }
    if (def->rayleigh_mass < 0 || def->rayleigh_stiffness < 0) {
        sem_error_set(err, SEM_ERR_INVALID, "Rayleigh damping coefficients must be >= 0");
        return NULL;
    }
    sem_world *w = calloc(1, sizeof *w);
    if (!w) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        return NULL;
    }
    w->def = *def;
    if (w->def.newton_tolerance <= 0) w->def.newton_tolerance = 1e-8;
    if (w->def.newton_max_iterations <= 0) w->def.newton_max_iterations = 50;
    if (sem_contact_create(&def->contact, &w->contact, err) != SEM_OK) {
        free(w);
        return NULL;
    }
    return w;
}

static void object_destroy(sem_object *o)
{
    if (!o) return;
    if (o->pi_dense)
        for (int i = 0; i < o->n_parts; ++i) free(o->pi_dense[i]);
    if (o->pi_shared)
        for (int i = 0; i < o->n_parts; ++i) free(o->pi_shared[i]);
    sem_pins_free(o);
    sem_structured_free(o);
    sem_seams_free(&o->seams);
    SEM_FREE_ALL(o->q, o->v, o->q0, o->point_material, o->point_rho_vol, o->entry_basis, o->entry_pair_offset,
                 o->part_mats, o->point_pairs, o->pair_a, o->pair_b, o->pair_lookup, o->group_start, o->group_ctrl,
                 o->ctrl_group, o->ctrl_local, o->part_tied, o->pi_dense, o->pi_shared, o->point_D, o->plist_start,
                 o->plist_point, o->plist_w, o->plist_cursor, o->N_chunk, o->Kz_packed, o->gpair_a, o->gpair_b,
                 o->gpair_lookup, o->gpair_offset, o->part_pair_gpair, o->gpair_pairs_start, o->gpair_pairs,
                 o->K_blocks, o->M_blocks, o->E_blocks, o->me_start, o->me_col, o->me_M, o->me_E, o->K0_blocks,
                 o->A_blocks, o->K0z, o->point_H, o->point_H0, o->f_gravity, o->pinned, o->presc_index, o->presc,
                 o->free_index, o->z, o->grad_z, o->Kz, o->qc, o->weld_ctrl, o->seam_tie_pair, o->seam_tie_weight, o->grad_z_share,
                 (void *)o->def.point_loads, (void *)o->def.region_loads);
    free(o);
}

void sem_world_destroy(sem_world *w)
{
    if (!w) return;
    for (int i = 0; i < w->n_systems; ++i) sem_system_destroy(w->systems[i]);
    for (int i = 0; i < w->n_objects; ++i) object_destroy(w->objects[i]);
    sem_contact_destroy(w->contact);
    free(w->objects);
    free(w->systems);
    free(w);
}

static const sem_material *material_of_part(const sem_object *o, const sem_object_def *def, int part)
{
    if (def->part_material && o->part_mats) {
        int k = def->part_material[part];
        if (k >= 0 && k < def->n_part_materials) return &o->part_mats[k];
    }
    return &o->def.material;
}

int sem_world_def_structured(const sem_world_def *def, size_t n_ctrl, int n_parts, int n_basis,
                             int shared_fit)
{
    size_t r0 = (size_t)n_parts * (size_t)n_basis;
    return def->solver == SEM_SOLVER_STRUCTURED ||
           (def->solver == SEM_SOLVER_AUTO && !def->advanced.solve_together && !def->advanced.q_space_solvers &&
            !(def->contact.self > 0 && !def->contact.disabled) && /* contact takes no structured system */
            (shared_fit || (n_ctrl >= 2 * r0 && 3 * r0 <= SEM_MAX_STRUCTURED_COEFFICIENTS)));
}

int sem_world_add_object(sem_world *w, const sem_object_def *def, sem_error *err)
{
    if (!def->model || !def->disc) {
        sem_error_set(err, SEM_ERR_INVALID, "object needs a model and its discretization");
        return -1;
    }
    if (!(def->friction >= 0) || !isfinite(def->friction)) {
        sem_error_set(err, SEM_ERR_INVALID, "object friction must be >= 0 (got %g)", def->friction);
        return -1;
    }
    const sem_discretization *d = def->disc;
    if ((size_t)d->n_ctrl != sem_model_control_points(def->model) || d->n_parts != def->model->n_parts) {
        sem_error_set(err, SEM_ERR_INVALID, "discretization does not match the model");
        return -1;
    }
    sem_object *o = calloc(1, sizeof *o);
    sem_system *sys;
    if (!o) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        return -1;
    }
    o->def = *def;
    /* the caller's arrays are copied where needed; keep no pointer to them */
    o->def.pinned = NULL;
    o->def.prescribe_group = NULL;
    o->def.prescribes = NULL;
    o->def.point_loads = NULL;
    o->def.region_loads = NULL;
    o->def.pin_regions = NULL; /* pins.c keeps what it needs */
    o->def.n_point_loads = 0;
    o->def.n_region_loads = 0;
    o->d = d;
    o->n_ctrl = d->n_ctrl;
    o->n_parts = d->n_parts;
    o->m = d->n_basis;
    o->n_quad = d->n_quad;
    size_t nq = 3 * (size_t)o->n_ctrl;
    sem_status st = SEM_OK;
    o->q = malloc(nq * sizeof(double));
    o->v = calloc(nq, sizeof(double));
    o->q0 = malloc(nq * sizeof(double));
    o->f_gravity = calloc(nq, sizeof(double));
    o->point_material = malloc(((size_t)o->n_quad + 1) * sizeof(*o->point_material));
    o->point_rho_vol = malloc(((size_t)o->n_quad + 1) * sizeof(double));
    o->z = calloc((size_t)o->n_parts * o->m * 3, sizeof(double));
    o->grad_z = calloc((size_t)o->n_parts * o->m * 3, sizeof(double)); /* room for ma rows */
    if (!o->q || !o->v || !o->q0 || !o->f_gravity || !o->point_material || !o->point_rho_vol ||
        !o->z || !o->grad_z) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    /* materials */
    {
        sem_material mat = def->material;
        if ((st = sem_material_init(&mat, err)) != SEM_OK) goto fail;
        o->def.material = mat;
        /* the object keeps initialized copies: the caller's array need not outlive this
         * call, and its Lame parameters need not be set */
        if (def->part_materials && def->n_part_materials > 0) {
            o->part_mats = malloc((size_t)def->n_part_materials * sizeof *o->part_mats);
            if (!o->part_mats) {
                st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                goto fail;
            }
            for (int k = 0; k < def->n_part_materials; ++k) {
                o->part_mats[k] = def->part_materials[k];
                if ((st = sem_material_init(&o->part_mats[k], err)) != SEM_OK) goto fail;
            }
        }
    }
    /* numbers that make a step meaningless (input_scales.c) */
    if ((st = sem_check_input_scales(&w->def, def, d->length_scale, d->volume, err)) != SEM_OK) goto fail;
    sem_model_get_q(def->model, o->q0);
    memcpy(o->q, o->q0, nq * sizeof(double));
    o->volume = 0;
    o->mass = 0;
    for (int p = 0; p < o->n_quad; ++p) {
        int part = d->quad_part ? d->quad_part[p] : 0;
        if (part < 0 || part >= o->n_parts) part = 0;
        const sem_material *mt = material_of_part(o, def, part);
        o->point_material[p] = mt;
        o->point_rho_vol[p] = mt->density * d->quad_volume[p];
        o->volume += d->quad_volume[p];
        o->mass += o->point_rho_vol[p];
    }
    o->def.part_material = NULL; /* the caller's arrays: read above, not kept */
    o->def.part_materials = NULL;
    if ((st = sem_loads_init(o, def, err)) != SEM_OK) goto fail;
    if ((st = sem_object_free_dofs(o, err)) != SEM_OK) goto fail;
    /* error stiffness: the object's, else the discretization's default */
    o->gamma = def->gamma > 0 ? def->gamma : d->gamma;
    /* the structured solver (structured.h) when asked, and by the fixed rule of
     * SEM_SOLVER_AUTO: when the coefficient space (n_parts m per coordinate) is at most half
     * the control points, where its factorization is far cheaper than the q-space one (the
     * objects of one system must agree, so solving together keeps the q-space solvers) */
    o->structured = sem_world_def_structured(&w->def, (size_t)o->n_ctrl, o->n_parts, o->m, d->shared_fit);
    if (!o->structured && sem_csr_nnz(&d->M) == 0 && o->n_ctrl > 0) {
        st = sem_error_set(err, SEM_ERR_INVALID,
                           "the %s solver needs the q-space operators: preprocess with "
                           "q_space_operators (or use the structured solver)",
                           w->def.solver == SEM_SOLVER_DENSE ? "dense" : "sparse");
        goto fail;
    }
    o->nthreads = w->def.threads > 0 ? w->def.threads : omp_get_max_threads();
    if (def->weld && (st = sem_object_find_welds(o, err)) != SEM_OK) goto fail;
    if (!(def->seam_ties >= 0) || !isfinite(def->seam_ties)) {
        st = sem_error_set(err, SEM_ERR_INVALID, "seam_ties must be >= 0 (got %g)", def->seam_ties);
        goto fail;
    }
    if ((st = sem_object_find_seam_ties(o, def->seam_ties, err)) != SEM_OK) goto fail;
    if ((st = sem_object_layout_init(o, err)) != SEM_OK) goto fail;
    /* material pins (before the constant matrices, which take their anchor) */
    if ((st = sem_pins_init(o, def, err)) != SEM_OK) goto fail;
    if ((st = sem_assembly_init(o, w->def.advanced.assembly_chunk, err)) != SEM_OK) goto fail;
    if ((st = sem_mass_error_init(o, err)) != SEM_OK) goto fail;
    o->grad_z_share =
        malloc(((size_t)GRADIENT_SHARES * o->n_parts * o->ma * 3 + 1) * sizeof(double));
    o->qc = malloc(3 * (size_t)o->n_ctrl * sizeof(double) + 1);
    if (!o->qc || !o->grad_z_share) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    if ((st = sem_loads_gravity(o, w->def.gravity, err)) != SEM_OK) goto fail;
    /* rest stiffness for Rayleigh damping */
    if ((st = sem_assemble_elastic(o, o->q0, 1, NULL, NULL, err)) != SEM_OK) goto fail;
    /* (the q-space solvers use K0z too: the rest matrix they may reuse, integrators.c) */
    if (!o->K0z && !(o->K0z = malloc(((size_t)o->n_pairs * 9 * o->ma * o->ma + 1) * sizeof(double)))) {
        sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        goto fail;
    }
    memcpy(o->K0z, o->Kz, (size_t)o->n_pairs * 9 * o->ma * o->ma * sizeof(double));
    if (!o->structured) {
        memcpy(o->K0_blocks, o->K_blocks, 9 * o->gpair_offset[o->n_gpairs] * sizeof(double));
        /* the point Hessians at rest (the linearly implicit step's products, integrators.c) */
        o->point_H = malloc(81 * (size_t)o->n_quad * sizeof(double) + 1);
        o->point_H0 = malloc(81 * (size_t)o->n_quad * sizeof(double) + 1);
        if (!o->point_H || !o->point_H0) {
            sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto fail;
        }
        if ((st = sem_assemble_elastic(o, o->q0, SEM_HESSIAN_POINTS, NULL, NULL, err)) != SEM_OK) goto fail;
        memcpy(o->point_H0, o->point_H, 81 * (size_t)o->n_quad * sizeof(double));
    }
    /* initial velocity: v = v0 + omega x (x - com) is affine, so exact on control points */
    {
        double com[3] = {0, 0, 0};
        if (o->mass > 0) {
            double *xp = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
            if (!xp) {
                sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
                goto fail;
            }
            sem_csr_multiply_threads(&d->Gamma, o->q, 3, xp, o->nthreads);
            for (int p = 0; p < o->n_quad; ++p)
                for (int k = 0; k < 3; ++k) com[k] += o->point_rho_vol[p] * xp[3 * p + k];
            for (int k = 0; k < 3; ++k) com[k] /= o->mass;
            free(xp);
        }
        const double *v0 = def->initial_velocity, *om = def->initial_angular_velocity;
        for (int c = 0; c < o->n_ctrl; ++c) {
            if (o->pinned[c]) continue;
            const double *x = o->q + 3 * c;
            double r[3] = {x[0] - com[0], x[1] - com[1], x[2] - com[2]};
            o->v[3 * c + 0] = v0[0] + om[1] * r[2] - om[2] * r[1];
            o->v[3 * c + 1] = v0[1] + om[2] * r[0] - om[0] * r[2];
            o->v[3 * c + 2] = v0[2] + om[0] * r[1] - om[1] * r[0];
        }
    }
    if ((st = sem_runaway_init(o, w->def.gravity, err)) != SEM_OK) goto fail;
    if (w->n_objects == w->cap) {
        int nc = w->cap ? 2 * w->cap : 4;
        sem_object **x = realloc(w->objects, (size_t)nc * sizeof *x);
        if (x) w->objects = x;
        sem_system **y = x ? realloc(w->systems, (size_t)nc * sizeof *y) : NULL;
        if (y) w->systems = y;
        if (!x || !y) {
            sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
            goto fail;
        }
        w->cap = nc;
    }
    /* contact: its collision mesh */
    if ((st = sem_contact_add_object(w->contact, o, err)) != SEM_OK) goto fail;
    /* its system: of its own, or (solve_together, or contact between objects: objects that
     * may touch are solved together) the one system of every object, built again with the
     * new one */
    w->objects[w->n_objects] = o;
    if ((w->def.advanced.solve_together || sem_contact_between_objects(w->contact)) && w->n_systems == 1) {
        if ((st = sem_system_create(w->objects, w->n_objects + 1, w->def.solver, &sys, err)) != SEM_OK) {
            sem_contact_remove_last_object(w->contact);
            goto fail;
        }
        sem_system_destroy(w->systems[0]);
        w->systems[0] = sys;
    } else {
        if ((st = sem_system_create(&o, 1, w->def.solver, &sys, err)) != SEM_OK) {
            sem_contact_remove_last_object(w->contact);
            goto fail;
        }
        w->systems[w->n_systems++] = sys;
    }
    return w->n_objects++;
fail:
    object_destroy(o);
    return -1;
}

sem_status sem_world_regroup(sem_world *w, double h, sem_error *err)
{
    int n = w->n_objects;
    if (n < 2 || w->def.advanced.solve_together || !sem_contact_between_objects(w->contact)) return SEM_OK;
    int *island = malloc(2 * (size_t)n * sizeof(int)), *current = island + n;
    if (!island) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_status st = sem_contact_islands(w->contact, w->objects, n, h, island, err);
    /* the grouping now: each object's label is the lowest world index in its system */
    int same = 1;
    for (int i = 0; i < n && st == SEM_OK; ++i) {
        current[i] = i;
        for (int j = 0; j < i; ++j)
            if (w->objects[j]->system == w->objects[i]->system) {
                current[i] = j;
                break;
            }
        same &= current[i] == island[i];
    }
    if (st != SEM_OK || same) {
        free(island);
        return st;
    }
    /* new systems, one per island in the order of their first objects */
    sem_system **systems = calloc((size_t)n, sizeof *systems);
    sem_object **members = malloc((size_t)n * sizeof *members);
    int n_systems = 0;
    if (!systems || !members) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int i = 0; i < n && st == SEM_OK; ++i) {
        if (island[i] != i) continue;
        int m = 0;
        for (int j = i; j < n; ++j)
            if (island[j] == i) members[m++] = w->objects[j];
        st = sem_system_create(members, m, w->def.solver, &systems[n_systems], err);
        if (st == SEM_OK) n_systems++;
    }
    if (st == SEM_OK) {
        for (int i = 0; i < w->n_systems; ++i) sem_system_destroy(w->systems[i]);
        memcpy(w->systems, systems, (size_t)n_systems * sizeof *systems);
        w->n_systems = n_systems;
        w->counters.regroupings++;
    } else {
        for (int i = 0; i < n_systems; ++i) sem_system_destroy(systems[i]);
        /* the objects point to the systems they had */
        for (int i = 0; i < w->n_systems; ++i)
            for (int k = 0; k < w->systems[i]->n_objects; ++k) w->systems[i]->objects[k]->system = w->systems[i];
    }
    free(systems);
    free(members);
    free(island);
    return st;
}

int sem_world_add_collider(sem_world *w, const sem_collider_def *def, sem_error *err)
{
    if (sem_contact_add_collider(w->contact, def, err) != SEM_OK) return -1;
    sem_contact_stats st;
    sem_contact_get_stats(w->contact, &st);
    return st.colliders - 1;
}

void sem_world_contact_stats(const sem_world *w, sem_contact_stats *stats)
{
    sem_contact_get_stats(w->contact, stats);
}

/* ---------------------------------------------------------------------------------- */
/* queries                                                                             */

double sem_world_time(const sem_world *w) { return w->time; }
void sem_world_set_time(sem_world *w, double time) { w->time = time; }
int sem_world_object_count(const sem_world *w) { return w->n_objects; }
int sem_world_object_dofs(const sem_world *w, int i) { return 3 * w->objects[i]->n_ctrl; }
int sem_world_object_tied_points(const sem_world *w, int i, int *part_counts)
{
    const sem_object *o = w->objects[i];
    int total = 0;
    for (int k = 0; k < o->n_parts; ++k) {
        int n = o->part_tied ? o->part_tied[k] : 0;
        if (part_counts) part_counts[k] = n;
        total += n;
    }
    return total;
}
const double *sem_world_object_q(const sem_world *w, int i) { return w->objects[i]->q; }
const double *sem_world_object_velocity(const sem_world *w, int i) { return w->objects[i]->v; }
double sem_world_last_step_seconds(const sem_world *w) { return w->last_step_s; }
double sem_world_last_factor_seconds(const sem_world *w) { return w->last_factor_s; }
int sem_world_last_iterations(const sem_world *w) { return w->last_iterations; }
sem_world_counters sem_world_get_counters(const sem_world *w)
{
    sem_world_counters c = w->counters;
    c.systems = w->n_systems;
    return c;
}

const char *sem_world_solver_name(const sem_world *w, int i)
{
    if (w->objects[i]->structured) return "structured";
    const sem_linear_solver *solver = w->objects[i]->system->solver;
    return solver ? sem_linear_solver_name(solver) : "none";
}

double sem_world_object_nnz_percent(const sem_world *w, int i)
{
    const sem_object *o = w->objects[i];
    /* structured: no q-space matrix exists; the pattern it would have */
    if (o->structured) return o->d->stiffness_nnz_percent;
    /* full q-space pattern: group-pair blocks x 9 */
    double nnz = 9.0 * (double)o->gpair_offset[o->n_gpairs];
    double n = 3.0 * o->n_ctrl;
    return 100.0 * nnz / (n * n);
}

void sem_world_object_set_state(sem_world *w, int i, const double *q, const double *v)
{
    sem_object *o = w->objects[i];
    size_t n = 3 * (size_t)o->n_ctrl;
    if (q) memcpy(o->q, q, n * sizeof(double));
    if (v) memcpy(o->v, v, n * sizeof(double));
}

void sem_world_object_stats(const sem_world *w, int i, sem_object_stats *s)
{
    sem_object *o = w->objects[i];
    memset(s, 0, sizeof *s);
    s->volume = o->volume;
    s->mass = o->mass;
    size_t n = 3 * (size_t)o->n_ctrl;
    double *x = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    double *v = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    double *tmp = malloc(n * sizeof(double) + 1);
    if (!x || !v || !tmp) {
        free(x);
        free(v);
        free(tmp);
        return;
    }
    sem_csr_multiply_threads(&o->d->Gamma, o->q, 3, x, o->nthreads);
    sem_csr_multiply_threads(&o->d->Gamma, o->v, 3, v, o->nthreads);
    const double *g = w->def.gravity;
    for (int p = 0; p < o->n_quad; ++p) {
        double rv = o->point_rho_vol[p];
        const double *xp = x + 3 * p, *vp = v + 3 * p;
        for (int k = 0; k < 3; ++k) {
            s->center_of_mass[k] += rv * xp[k];
            s->linear_momentum[k] += rv * vp[k];
        }
        s->angular_momentum[0] += rv * (xp[1] * vp[2] - xp[2] * vp[1]);
        s->angular_momentum[1] += rv * (xp[2] * vp[0] - xp[0] * vp[2]);
        s->angular_momentum[2] += rv * (xp[0] * vp[1] - xp[1] * vp[0]);
        s->gravity_energy -= rv * (g[0] * xp[0] + g[1] * xp[1] + g[2] * xp[2]);
    }
    if (o->mass > 0)
        for (int k = 0; k < 3; ++k) s->center_of_mass[k] /= o->mass;
    /* kinetic energy 1/2 v^T M v; error energy gamma q^T M_eps q */
    sem_blocks_multiply(o, 1.0, 0, 0, 0, 0, o->v, tmp);
    for (size_t k = 0; k < n; ++k) s->kinetic_energy += 0.5 * o->v[k] * tmp[k];
    s->error_energy = sem_error_energy(o, o->q, tmp);
    sem_error e;
    if (sem_assemble_elastic(o, o->q, 0, NULL, NULL, &e) == SEM_OK)
        s->elastic_energy = o->elastic_energy;
    else
        s->elastic_energy = INFINITY;
    free(x);
    free(v);
    free(tmp);
}
