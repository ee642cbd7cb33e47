/*
 * loads.c - what acts on an object from outside (see loads.h): gravity, region and point
 * loads, and the prescribed motion of pinned control points.
 */
#include "loads.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* A copy of size bytes at data, or NULL when out of memory. */
static void *copy_of(const void *data, size_t size)
{
    void *copy = malloc(size);
    if (copy) memcpy(copy, data, size);
    return copy;
}

sem_status sem_loads_init(sem_object *o, const sem_object_def *def, sem_error *err)
{
    /* the object keeps copies: the caller's arrays need not outlive sem_world_add_object */
    if (def->n_point_loads > 0) {
        o->def.point_loads = copy_of(def->point_loads, (size_t)def->n_point_loads * sizeof *def->point_loads);
        if (!o->def.point_loads) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        o->def.n_point_loads = def->n_point_loads;
    }
    if (def->n_region_loads > 0) {
        o->def.region_loads = copy_of(def->region_loads, (size_t)def->n_region_loads * sizeof *def->region_loads);
        if (!o->def.region_loads) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        o->def.n_region_loads = def->n_region_loads;
    }
    o->pinned = calloc((size_t)o->n_ctrl + 1, 1);
    if (!o->pinned) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    if (def->pinned) memcpy(o->pinned, def->pinned, (size_t)o->n_ctrl);
    o->presc_index = malloc((size_t)o->n_ctrl * sizeof(int));
    o->n_presc = def->prescribe_group ? def->n_prescribes : 1;
    o->presc = calloc((size_t)(o->n_presc > 0 ? o->n_presc : 1), sizeof(sem_prescribe));
    if (!o->presc_index || !o->presc) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    if (def->prescribe_group) {
        if (def->n_prescribes > 0) memcpy(o->presc, def->prescribes, (size_t)def->n_prescribes * sizeof(sem_prescribe));
        for (int c = 0; c < o->n_ctrl; ++c) {
            int g = def->prescribe_group[c];
            if (g >= def->n_prescribes)
                return sem_error_set(err, SEM_ERR_INVALID,
                                     "control point %d: prescribed group %d does not exist", c, g);
            o->presc_index[c] = g >= 0 ? g : -1;
            if (g >= 0) o->pinned[c] = 1;
        }
    } else {
        o->presc[0] = def->prescribe;
        /* prescribe all control points (an object with material pins moves those instead) */
        if (def->prescribe.type != SEM_PRESCRIBE_NONE && !def->pinned && def->n_pin_regions <= 0)
            memset(o->pinned, 1, (size_t)o->n_ctrl);
        for (int c = 0; c < o->n_ctrl; ++c)
            o->presc_index[c] = def->prescribe.type != SEM_PRESCRIBE_NONE && o->pinned[c] ? 0 : -1;
    }
    return SEM_OK;
}

sem_status sem_loads_gravity(sem_object *o, const double g[3], sem_error *err)
{
    const sem_csr *G = &o->d->Gamma;
    double *fp = malloc(3 * (size_t)o->n_quad * sizeof(double) + 1);
    if (!fp) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    for (int p = 0; p < o->n_quad; ++p)
        for (int k = 0; k < 3; ++k) fp[3 * p + k] = o->point_rho_vol[p] * g[k];
    sem_csr_multiply_transpose(G, fp, 3, o->f_gravity);
    free(fp);
    return SEM_OK;
}

void sem_prescription_apply(const sem_prescribe *pr, double t, const double x0[3], double out[3])
{
    /* rotate and move stop at their duration */
    const double tt = pr->duration > 0 && t > pr->duration ? pr->duration : t;
    if (pr->type == SEM_PRESCRIBE_AFFINE) {
        const double *A = pr->affine;
        for (int r = 0; r < 3; ++r) out[r] = A[4 * r] * x0[0] + A[4 * r + 1] * x0[1] + A[4 * r + 2] * x0[2] + A[4 * r + 3];
        return;
    }
    if (pr->type == SEM_PRESCRIBE_MOVE) {
        for (int i = 0; i < 3; ++i) out[i] = x0[i] + pr->velocity[i] * tt;
        return;
    }
    if (pr->type == SEM_PRESCRIBE_ROTATE) {
        double ang = pr->rate * tt;
        double k[3] = {pr->axis_direction[0], pr->axis_direction[1], pr->axis_direction[2]};
        double kn = sqrt(k[0] * k[0] + k[1] * k[1] + k[2] * k[2]);
        if (kn > 0)
            for (int i = 0; i < 3; ++i) k[i] /= kn;
        double r[3] = {x0[0] - pr->axis_point[0], x0[1] - pr->axis_point[1], x0[2] - pr->axis_point[2]};
        double cs = cos(ang), sn = sin(ang);
        double kxr[3] = {k[1] * r[2] - k[2] * r[1], k[2] * r[0] - k[0] * r[2], k[0] * r[1] - k[1] * r[0]};
        double kdr = k[0] * r[0] + k[1] * r[1] + k[2] * r[2];
        for (int i = 0; i < 3; ++i)
            out[i] = pr->axis_point[i] + r[i] * cs + kxr[i] * sn + k[i] * kdr * (1 - cs);
    }
}

void sem_prescribed_position(const sem_object *o, double t, int c, double out[3])
{
    const double *x0 = o->q0 + 3 * c, *now = o->q + 3 * c;
    if (o->presc_index[c] < 0 || o->presc[o->presc_index[c]].type == SEM_PRESCRIBE_NONE) {
        if (out != now) memcpy(out, now, 3 * sizeof(double));
        return;
    }
    sem_prescription_apply(&o->presc[o->presc_index[c]], t, x0, out);
}

void sem_external_force(const sem_object *o, double t, double *f)
{
    size_t n = 3 * (size_t)o->n_ctrl;
    memcpy(f, o->f_gravity, n * sizeof(double));
    const sem_discretization *d = o->d;
    for (int l = 0; l < o->def.n_region_loads; ++l) {
        const sem_region_load *rl = &o->def.region_loads[l];
        double s = rl->frequency > 0 ? 0.5 * (1 + sin(2 * M_PI * rl->frequency * t + rl->phase)) : 1.0;
        for (int p = 0; p < o->n_quad; ++p) {
            const double *X = d->quad_X + 3 * p;
            if (X[0] < rl->box[0] || X[1] < rl->box[1] || X[2] < rl->box[2] || X[0] > rl->box[3] ||
                X[1] > rl->box[4] || X[2] > rl->box[5])
                continue;
            double vol = d->quad_volume[p];
            for (int e = d->Gamma.row_start[p]; e < d->Gamma.row_start[p + 1]; ++e)
                for (int k = 0; k < 3; ++k)
                    f[3 * (size_t)d->Gamma.col[e] + k] += d->Gamma.val[e] * vol * s * rl->force_density[k];
        }
    }
    for (int l = 0; l < o->def.n_point_loads; ++l) {
        /* the force acts at the quadrature point nearest its rest position */
        const sem_point_load *pl = &o->def.point_loads[l];
        int best = -1;
        double bd = INFINITY;
        for (int p = 0; p < o->n_quad; ++p) {
            const double *X = d->quad_X + 3 * p;
            double dd = (X[0] - pl->X[0]) * (X[0] - pl->X[0]) + (X[1] - pl->X[1]) * (X[1] - pl->X[1]) +
                        (X[2] - pl->X[2]) * (X[2] - pl->X[2]);
            if (dd < bd) {
                bd = dd;
                best = p;
            }
        }
        if (best < 0) continue;
        for (int e = d->Gamma.row_start[best]; e < d->Gamma.row_start[best + 1]; ++e)
            for (int k = 0; k < 3; ++k) f[3 * (size_t)d->Gamma.col[e] + k] += d->Gamma.val[e] * pl->force[k];
    }
}
