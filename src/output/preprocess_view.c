/*
 * preprocess_view.c - what of the preprocessing a run folder keeps.
 *
 * `sem render --color` shows the preprocessing of a run (blending weights, deformation
 * origins, quadrature points, moved by the SEM map frame by frame), and the scene that
 * made the run may no longer be at hand. The run therefore keeps, per object, the parts of
 * its discretization those views need: the quadrature points, W, the origins and Pi. The
 * boundary samples and the operators (J-hat, Gamma, Grad, Gamma_samples, M, M_eps) are
 * left out: they are most of the size (Gamma alone is n_quad x n_ctrl, dense when every
 * part blends with every other) and can be rebuilt from the model. The file is the usual
 * versioned discretization file (sem_discretization_save), with those matrices empty.
 */
#include "preprocess_view.h"

#include <string.h>

/* An empty matrix of the same shape (the file records shapes, and the loader checks them). */
static sem_csr empty_like(const sem_csr *m, int n_rows)
{
    sem_csr e;
    memset(&e, 0, sizeof e);
    e.n_rows = n_rows;
    e.n_cols = m->n_cols;
    return e;
}

sem_status output_write_preprocess(const char *path, const sem_discretization *d, sem_error *err)
{
    sem_discretization light = *d;
    light.n_samples = 0;
    light.sample_part = NULL;
    light.sample_uv = NULL;
    light.sample_X = NULL;
    light.sample_area = NULL;
    light.sample_seam = NULL;
    light.J_hat = empty_like(&d->J_hat, 0);
    light.W_samples = empty_like(&d->W_samples, 0);
    light.Gamma = empty_like(&d->Gamma, d->n_quad);
    light.Grad = empty_like(&d->Grad, 3 * d->n_quad);
    light.Gamma_samples = empty_like(&d->Gamma_samples, 0);
    light.M = empty_like(&d->M, d->n_ctrl);
    light.M_eps = empty_like(&d->M_eps, d->n_ctrl);
    light.J_hat.n_cols = d->n_ctrl;
    light.W_samples.n_cols = d->n_parts;
    light.Gamma.n_cols = d->n_ctrl;
    light.Grad.n_cols = d->n_ctrl;
    light.Gamma_samples.n_cols = d->n_ctrl;
    light.M.n_cols = d->n_ctrl;
    light.M_eps.n_cols = d->n_ctrl;
    return sem_discretization_save(&light, path, err);
}
