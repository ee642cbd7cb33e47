/*
 * iges_parts.c - a surface and its trim loops made one part of the model (iges_internal.h):
 * the surface of a trimmed entity or face read with the boundary it needs, loops given in
 * model space projected into its (u,v) domain, the loops repaired, and the part named,
 * coloured, checked and taken into the model. Trimmed surfaces (iges_trimmed.c), B-rep
 * faces (iges_brep.c) and untrimmed surfaces (iges_read.c) all end here.
 *
 * Boundaries given in model space only (141 type 0 without parameter-space curves, 508
 * edges whose 504 curve has no parameter-space curve, as castle.iges writes them) are
 * projected into the surface's (u,v) domain by closest-point inversion along each curve
 * (geometry/trim_projection.c), so those faces are trimmed as the file means; an outer loop
 * that turns out to be the domain's own border leaves the part untrimmed (nothing to trim).
 * So are the loops of surfaces whose parameters are not the file's (inexact_param: a surface
 * of revolution's angle), where the file gives them in model space too.
 *
 * What Open CASCADE reads, we read (issue 29, docs/validation.md 3d): every part's loops go
 * through geometry/trim_fix.c before they are checked (gaps closed or bridged within the
 * file's resolution, loops across a closed surface's seam unwrapped and the seam moved out of
 * their way).
 */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/analytic_surfaces.h"
#include "geometry/trim_fix.h"
#include "geometry/trim_projection.h"
#include "io/iges_internal.h"
#include "sem/limits.h"
#include "sem/nurbs.h"
#include "sem/trim.h"

/* The name property (406 form 15) among the entity's trailing property pointers. */
static int property_name(const iges_reader *r, int idx, char *name, size_t size)
{
    const iges_entry *e = &r->entries[idx];
    int k = e->n_used, na, np;
    if (k <= 0 || !iges_peek_int(r, idx, k, &na) || na < 0 || na > iges_remaining(r, idx, k))
        return 0;
    k += 1 + na;
    if (!iges_peek_int(r, idx, k, &np) || np < 0 || np > iges_remaining(r, idx, k)) return 0;
    for (int j = 0; j < np; ++j) {
        int p;
        if (!iges_peek_ptr(r, idx, k + 1 + j, &p)) continue;
        const iges_entry *q = &r->entries[p];
        if (q->type != 406 || q->form != 15) continue;
        const char *s;
        int len;
        iges_param_string(r, p, 2, &s, &len);
        if (len <= 0) continue;
        snprintf(name, size, "%.*s", len, s);
        return 1;
    }
    return 0;
}

static int label_name(const iges_reader *r, int idx, char *name, size_t size)
{
    const iges_entry *e = &r->entries[idx];
    if (!e->label[0]) return 0;
    if (e->subscript != 0)
        snprintf(name, size, "%s%d", e->label, e->subscript);
    else
        snprintf(name, size, "%s", e->label);
    return 1;
}

/* An IGES colour as red, green, blue in 0..1: a colour number (1 black, 2 red, 3 green,
 * 4 blue, 5 yellow, 6 magenta, 7 cyan, 8 white) or -DE of a 314 colour definition (its first
 * three parameters: percentages). Returns 0 when there is none or it cannot be read: a colour
 * is not worth refusing a file. */
static int color_rgb(const iges_reader *r, int color, float rgb[3])
{
    static const float numbered[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1},
                                         {1, 1, 0}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
    if (color >= 1 && color <= 8) {
        memcpy(rgb, numbered[color - 1], sizeof numbered[0]);
        return 1;
    }
    if (color >= 0 || color == INT_MIN || (-color) % 2 == 0) return 0;
    int idx = (-color - 1) / 2;
    if (idx >= r->n_entries || r->entries[idx].type != 314 || r->entries[idx].n_params < 4) return 0;
    for (int k = 0; k < 3; ++k) {
        const iges_token *t = &r->tokens[r->entries[idx].first_token + (size_t)(k + 1)];
        double percent;
        if (t->is_string || iges_parse_real(r->ptext + t->offset, t->length, 0.0, &percent) != 1)
            return 0;
        rgb[k] = (float)(percent < 0 ? 0 : percent > 100 ? 1 : percent / 100);
    }
    return 1;
}

/* A part's trim loops made usable (geometry/trim_fix.h), with a warning for each repair that
 * is not exact: a bridged gap, a loop left out. Nothing changes for loops that need nothing
 * (every shared model). */
static sem_status fix_loops(iges_reader *r, sem_part *part, int top)
{
    sem_loop_fix fix;
    memset(&fix, 0, sizeof fix);
    fix.bridge = r->resolution; /* the gaps the file allows (or 1e-4 of the surface) */
    sem_status st = sem_part_fix_loops(part, &fix);
    if (st != SEM_OK) return iges_nomem(r);
    int type = r->entries[top].type;
    if (fix.widest_gap > 0)
        sem_model_warn(r->model, "entity %d (DE %d): a gap of %.3g between trim curves is bridged "
                                 "(allowed %.3g: the file's resolution or 1e-4 of the surface)",
                       type, iges_de_number(top), fix.widest_gap, fix.gap_limit);
    if (fix.outer_dropped)
        sem_model_warn(r->model, "entity %d (DE %d): the outer trim loop does not close (a gap "
                                 "wider than %.3g); that loop is left out",
                       type, iges_de_number(top), fix.gap_limit);
    if (fix.holes_dropped)
        sem_model_warn(r->model,
                       "entity %d (DE %d): %d hole trim loop%s not close (a gap wider "
                       "than %.3g); left out",
                       type, iges_de_number(top), fix.holes_dropped,
                       fix.holes_dropped == 1 ? " does" : "s do", fix.gap_limit);
    if (fix.wound)
        sem_model_warn(r->model, "entity %d (DE %d): the trim loops wind around the closed "
                                 "surface and cannot share one period of it; they are kept as "
                                 "written",
                       type, iges_de_number(top));
    return SEM_OK;
}

/* Names, colour and source, then the checks every part must pass, then into the model. */
sem_status iges_finish_part(iges_reader *r, sem_part *part, int top, int surf)
{
    if (!property_name(r, top, part->name, sizeof part->name) &&
        !property_name(r, surf, part->name, sizeof part->name) &&
        !label_name(r, top, part->name, sizeof part->name))
        label_name(r, surf, part->name, sizeof part->name);
    part->source_entity = iges_de_number(surf);
    part->color = r->entries[top].color ? r->entries[top].color : r->entries[surf].color;
    part->has_rgb = color_rgb(r, part->color, part->rgb);
    if (r->model->n_parts >= SEM_MAX_PARTS) {
        sem_part_free(part);
        return iges_entity_error(r, top, 0,
                                 "the model would have more than %d parts (limit "
                                 "SEM_MAX_PARTS)",
                                 SEM_MAX_PARTS);
    }
    sem_status fs = fix_loops(r, part, top);
    if (fs != SEM_OK) {
        sem_part_free(part);
        return fs;
    }
    sem_error ve;
    if (sem_part_validate_trims(part, &ve) != SEM_OK) {
        sem_part_free(part);
        return iges_entity_error(r, top, 0, "surface DE %d: %s", iges_de_number(surf), ve.message);
    }
    sem_status st = sem_model_take_part(r->model, part, r->err);
    if (st != SEM_OK) sem_part_free(part);
    return st;
}

sem_status iges_add_hole(iges_reader *r, sem_part *part, curve_list *l)
{
    sem_trim_loop *h = realloc(part->holes, (size_t)(part->n_holes + 1) * sizeof *h);
    if (!h) return iges_nomem(r);
    part->holes = h;
    h[part->n_holes].n_curves = l->n;
    h[part->n_holes].curves = l->c;
    part->n_holes++;
    memset(l, 0, sizeof *l);
    return SEM_OK;
}

void iges_set_outer(sem_part *part, curve_list *l)
{
    for (int i = 0; i < part->outer.n_curves; ++i) sem_curve_free(&part->outer.curves[i]);
    free(part->outer.curves);
    part->has_outer = 1;
    part->outer.n_curves = l->n;
    part->outer.curves = l->c;
    memset(l, 0, sizeof *l);
}

/* A loop known only in model space (curves in loop order, in the surface's coordinates)
 * projected into the part's (u,v) domain. SEM_ERR_UNSUPPORTED (with a warning naming the
 * entity and why) when it cannot be. */
sem_status iges_project_model_space_loop(iges_reader *r, int idx, const sem_part *part,
                                         curve_list *model_space, curve_list *l, int *border)
{
    *border = 0;
    if (model_space->n == 0) {
        sem_model_warn(r->model, "entity %d (DE %d): boundary has neither parameter-space nor "
                                 "model-space curves; that loop is left out",
                       r->entries[idx].type, iges_de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    sem_surface_sampler sampler;
    sem_error perr;
    sem_status st = sem_surface_sampler_build(&part->surface, &sampler, &perr);
    if (st == SEM_ERR_NOMEM) return iges_nomem(r);
    sem_trim_projection_settings settings = sem_default_trim_projection_settings(&part->surface);
    /* gaps between the curves: up to the file's own resolution, or 1e-4 of the surface */
    settings.max_gap = fmax(settings.max_gap, r->resolution);
    sem_trim_loop loop;
    double gap = 0;
    if (st == SEM_OK)
        st = sem_trim_project_loop(&sampler, model_space->c, model_space->n, &settings, &loop,
                                   border, &gap, &perr);
    if (st == SEM_OK && gap > 0)
        sem_model_warn(r->model, "entity %d (DE %d): a gap of %.3g between boundary curves is "
                                 "bridged (allowed %.3g: the file's resolution or 1e-4 of the "
                                 "surface)",
                       r->entries[idx].type, iges_de_number(idx), gap, settings.max_gap);
    sem_surface_sampler_free(&sampler);
    if (st == SEM_ERR_NOMEM) return iges_nomem(r);
    if (st != SEM_OK) {
        sem_model_warn(r->model, "entity %d (DE %d): boundary given in model space only could "
                                 "not be projected onto its surface (%s); that loop is left out",
                       r->entries[idx].type, iges_de_number(idx), perr.message);
        return SEM_ERR_UNSUPPORTED;
    }
    iges_list_free(l);
    l->n = l->cap = loop.n_curves;
    l->c = loop.curves;
    return SEM_OK;
}

/* Reads the surface of a trimmed entity; an unbounded plane is fitted to the hint curves.
 * *from_hint: 1 it was (its loops must then come from model space); 2 the surface's
 * parameters are not the file's (inexact_param: its loops come from model space where the
 * file gives them there). */
sem_status iges_read_trimmed_surface(iges_reader *r, int surf, const double *m, int depth,
                                     const curve_list *hint, sem_part *part, int *from_hint)
{
    r->surface_hint = hint->n > 0;
    r->from_hint = 0;
    r->hint_fit = HINT_NONE;
    r->hint_seam = 0;
    r->inexact_param = 0;
    sem_status st = iges_read_surface(r, surf, m, depth + 1, part);
    r->surface_hint = 0;
    /* 1: the loops must come from model space; 2: better from there (inexact_param) */
    *from_hint = st != SEM_OK ? 0 : r->from_hint ? 1 : r->inexact_param ? 2 : 0;
    if (*from_hint == 1 && (r->hint_fit != HINT_NONE || r->hint_seam) && hint->n > 0) {
        size_t n = 0;
        for (int i = 0; i < hint->n; ++i) n += (size_t)hint->c[i].n_ctrl;
        double *points = malloc((n ? n : 1) * 3 * sizeof *points);
        if (!points) {
            sem_part_free(part);
            return iges_nomem(r);
        }
        size_t k = 0;
        for (int i = 0; i < hint->n; ++i) {
            memcpy(points + 3 * k, hint->c[i].ctrl, (size_t)hint->c[i].n_ctrl * 3 * sizeof *points);
            k += (size_t)hint->c[i].n_ctrl;
        }
        if (r->hint_seam) {
            /* the seam needs points on the curves (control points of arcs leave gaps) */
            size_t ns = 0;
            for (int i = 0; i < hint->n; ++i) ns += 16 * (size_t)(hint->c[i].n_ctrl + 1) + 1;
            double *samples = malloc(ns * 3 * sizeof *samples);
            size_t *offsets = malloc(((size_t)hint->n + 1) * sizeof *offsets);
            if (samples && offsets) {
                size_t k = 0;
                for (int i = 0; i < hint->n; ++i) {
                    const sem_curve *c = &hint->c[i];
                    int steps = 16 * (c->n_ctrl + 1);
                    offsets[i] = k;
                    for (int j = 0; j <= steps; ++j)
                        sem_curve_eval(c, c->t0 + (c->t1 - c->t0) * j / steps, samples + 3 * k++,
                                       NULL);
                }
                offsets[hint->n] = k;
                sem_surface_place_seam(&part->surface, samples, offsets, hint->n);
            }
            free(samples);
            free(offsets);
        }
        if (r->hint_fit == HINT_PLANE) sem_surface_fit_plane_rectangle(&part->surface, points, n);
        else if (r->hint_fit == HINT_AXIAL) sem_surface_fit_axial_range(&part->surface, points, n);
        free(points);
    }
    return st;
}

/* Surfaces that need their boundary to be read (see iges_reader.surface_hint). */
int iges_needs_hint(const iges_reader *r, int surf)
{
    int t = r->entries[surf].type;
    return t == 108 || (t >= 190 && t <= 198 && t % 2 == 0);
}
