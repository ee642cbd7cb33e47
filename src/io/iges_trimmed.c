/*
 * iges_trimmed.c - trimmed surfaces (iges_internal.h), each one trimmed part:
 *
 *   144 trimmed surface  -> its surface, the outer loop and the holes of its 142 curves
 *   143 bounded surface  -> its surface and the loops of its 141 boundaries
 *
 * A curve on a surface (142) or a boundary (141) gives its loop in parameter space, in
 * model space, or both: the (u,v) curves are taken as written, and the model-space curves
 * are projected onto the surface (iges_parts.c) where there are no (u,v) curves or the
 * surface's parameters are not the file's. A trim loop that cannot be built leaves its part
 * untrimmed with a warning rather than losing the part.
 */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "io/iges_internal.h"

/* Moves every curve of `from` to the end of `to`, leaving `from` empty. Best effort, for
 * hints: a curve that cannot be added is freed. */
static void move_curves(iges_reader *r, curve_list *to, curve_list *from)
{
    for (int j = 0; j < from->n; ++j)
        if (iges_list_push(r, to, &from->c[j]) != SEM_OK) sem_curve_free(&from->c[j]);
    free(from->c);
    memset(from, 0, sizeof *from);
}

/* The 142 at parameter k of owner, checked. */
static sem_status curve_on_surface_entity(iges_reader *r, int owner, int k, int *p)
{
    sem_status st = iges_param_ptr(r, owner, k, 0, p);
    if (st != SEM_OK) return st;
    if (r->entries[*p].type != 142)
        return iges_entity_error(
            r, owner, iges_token_line(r, owner, k),
            "parameter %d points to DE %d, a type-%d entity, where a curve on a "
            "surface (142) is expected",
            k, iges_de_number(*p), r->entries[*p].type);
    st = iges_need(r, *p, 1, 5, "curve on a parametric surface");
    if (st == SEM_OK) r->entries[*p].n_used = 6;
    return st;
}

/* The loop of a 142 (parameter k of owner) into l: its parameter-space curve (BPTR); or,
 * when it has none or model_space is 1 (the surface is an unbounded plane fitted to the
 * boundary, whose (u,v) the file's curves do not know) or 2 and there is one (the surface's
 * parameters are not the file's), its model-space curve (CPTR, in the coordinates m)
 * projected onto the part's surface. SEM_ERR_UNSUPPORTED (with a warning)
 * when neither works. *border: the loop is the surface's own border. */
static sem_status curve_on_surface(iges_reader *r, int owner, int k, int depth, const double *m,
                                   const sem_part *part, int model_space, curve_list *l,
                                   int *border)
{
    *border = 0;
    int p, bptr, cptr;
    sem_status st = curve_on_surface_entity(r, owner, k, &p);
    if (st == SEM_OK) st = iges_param_ptr(r, p, 3, 1, &bptr);
    if (st == SEM_OK) st = iges_param_ptr(r, p, 4, 1, &cptr);
    if (st != SEM_OK) return st;
    /* model_space 2 (inexact parameters): the model-space curve when there is one */
    if (bptr >= 0 && (!model_space || (model_space == 2 && cptr < 0)))
        return iges_read_curves(r, bptr, iges_identity_xf, depth + 1, l);
    if (cptr < 0) {
        sem_model_warn(r->model, "entity 142 (DE %d): no parameter-space curve (BPTR = 0) and no "
                                 "model-space curve (CPTR = 0); the loop is left out",
                       iges_de_number(p));
        return SEM_ERR_UNSUPPORTED;
    }
    curve_list c;
    memset(&c, 0, sizeof c);
    st = iges_read_curves(r, cptr, m, depth + 1, &c);
    if (st == SEM_OK) st = iges_project_model_space_loop(r, p, part, &c, l, border);
    iges_list_free(&c);
    return st;
}

/* The model-space curves (CPTR) of every 142 of a 144, for fitting an unbounded plane.
 * Best effort: a curve that cannot be read is left out of the hint (its loop reports it). */
static void trimmed_hint(iges_reader *r, int idx, int n1, int n2, const double *m, int depth,
                         curve_list *hint)
{
    for (int i = n1 != 0 ? 0 : 1; i <= n2; ++i) {
        int p, cptr;
        if (curve_on_surface_entity(r, idx, 4 + i, &p) != SEM_OK) continue;
        if (iges_param_ptr(r, p, 4, 1, &cptr) != SEM_OK || cptr < 0) continue;
        curve_list c;
        memset(&c, 0, sizeof c);
        if (iges_read_curves(r, cptr, m, depth + 1, &c) != SEM_OK) {
            iges_list_free(&c); /* a composite that failed part-way keeps the members it read */
            continue;
        }
        move_curves(r, hint, &c);
    }
}

sem_status iges_emit_trimmed(iges_reader *r, int idx, const double *parent, int depth)
{
    int surf, n1, n2;
    sem_status st = iges_surface_pointer(r, idx, 1, &surf);
    if (st == SEM_OK) st = iges_param_int(r, idx, 2, &n1);
    if (st == SEM_OK) st = iges_param_int(r, idx, 3, &n2);
    if (st == SEM_OK) st = iges_need(r, idx, 5, n2, "trimmed surface (N2 inner boundaries)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5 + n2;
    double m[12];
    st = iges_own_xform(r, idx, parent, m);
    curve_list hint;
    memset(&hint, 0, sizeof hint);
    if (st == SEM_OK && iges_needs_hint(r, surf)) trimmed_hint(r, idx, n1, n2, m, depth, &hint);
    sem_part part;
    memset(&part, 0, sizeof part);
    int model_space = 0;
    if (st == SEM_OK) st = iges_read_trimmed_surface(r, surf, m, depth, &hint, &part, &model_space);
    iges_list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    curve_list l;
    memset(&l, 0, sizeof l);
    int border = 0;
    if (n1 != 0) {
        st = curve_on_surface(r, idx, 4, depth, m, &part, model_space, &l, &border);
        if (st == SEM_OK && !border) iges_set_outer(&part, &l);
    }
    for (int i = 0; (st == SEM_OK || st == SEM_ERR_UNSUPPORTED) && i < n2; ++i) {
        iges_list_free(&l);
        st = curve_on_surface(r, idx, 5 + i, depth, m, &part, model_space, &l, &border);
        if (st == SEM_OK && !border) st = iges_add_hole(r, &part, &l);
    }
    iges_list_free(&l);
    if (st != SEM_OK && st != SEM_ERR_UNSUPPORTED) {
        sem_part_free(&part);
        return st;
    }
    return iges_finish_part(r, &part, idx, surf);
}

/* One 141 boundary: its parameter-space curves, reversed where SENSE = 2; when some curve
 * has none, the model-space curves (in the coordinates m of the surface) projected onto the
 * part's surface instead. */
static sem_status boundary_loop(iges_reader *r, int idx, const double *m, int depth,
                                const sem_part *part, int model_space, curve_list *l, int *border)
{
    *border = 0;
    if (r->entries[idx].type != 141)
        return iges_entity_error(r, idx, 0, "a boundary entity (141) was expected here");
    int type, n;
    sem_status st = iges_param_int(r, idx, 1, &type);
    if (st == SEM_OK) st = iges_param_int(r, idx, 4, &n);
    if (st == SEM_OK) st = iges_need(r, idx, 5, 3LL * n, "boundary (N curves)");
    if (st != SEM_OK) return st;
    int k = 5, missing = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int sense, kk;
        st = iges_param_int(r, idx, k + 1, &sense);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 2, &kk);
        if (st == SEM_OK) st = iges_need(r, idx, k + 3, kk, "boundary curve (K parameter curves)");
        if (st != SEM_OK) break;
        if (kk == 0) missing = 1;
        int first = l->n;
        for (int j = 0; st == SEM_OK && j < kk; ++j) {
            int p = -1;
            st = iges_param_ptr(r, idx, k + 3 + j, 0, &p);
            if (st == SEM_OK) st = iges_read_curves(r, p, iges_identity_xf, depth + 1, l);
        }
        if (st == SEM_OK && sense == 2) iges_reverse_curves(l, first);
        k += 3 + kk;
    }
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = k;
    if (!missing && n > 0 && !model_space) return SEM_OK;
    iges_list_free(l);

    /* the model-space curves (parameter 5, 5 + 3 + K1, ...) in loop order */
    curve_list model_curves;
    memset(&model_curves, 0, sizeof model_curves);
    k = 5;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int crv, sense, kk = 0, first = model_curves.n;
        st = iges_param_ptr(r, idx, k, 0, &crv);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 1, &sense);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 2, &kk);
        if (st == SEM_OK) st = iges_read_curves(r, crv, m, depth + 1, &model_curves);
        if (st == SEM_OK && sense == 2) iges_reverse_curves(&model_curves, first);
        k += 3 + kk;
    }
    if (st == SEM_OK && !part) {
        /* only the curves are wanted (a hint for the surface) */
        move_curves(r, l, &model_curves);
        return SEM_OK;
    }
    if (st == SEM_OK) st = iges_project_model_space_loop(r, idx, part, &model_curves, l, border);
    iges_list_free(&model_curves);
    return st;
}

/* The box of a (u,v) loop's control points: u0, u1, v0, v1 (it holds the loop's curves). */
static void loop_box(const curve_list *l, double box[4])
{
    box[0] = box[2] = INFINITY;
    box[1] = box[3] = -INFINITY;
    for (int i = 0; i < l->n; ++i)
        for (int j = 0; j < l->c[i].n_ctrl; ++j) {
            const double *p = l->c[i].ctrl + 3 * j;
            box[0] = fmin(box[0], p[0]), box[1] = fmax(box[1], p[0]);
            box[2] = fmin(box[2], p[1]), box[3] = fmax(box[3], p[1]);
        }
}

sem_status iges_emit_bounded(iges_reader *r, int idx, const double *parent, int depth)
{
    int surf, n;
    sem_status st = iges_surface_pointer(r, idx, 2, &surf);
    if (st == SEM_OK) st = iges_param_int(r, idx, 3, &n);
    if (st == SEM_OK) st = iges_need(r, idx, 4, n, "bounded surface (N boundaries)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 4 + n;
    double m[12];
    st = iges_own_xform(r, idx, parent, m);
    /* a surface that needs its boundary to be sized: every boundary's model-space curves */
    curve_list hint;
    memset(&hint, 0, sizeof hint);
    for (int i = 0; st == SEM_OK && iges_needs_hint(r, surf) && i < n; ++i) {
        int b, border;
        curve_list one; /* boundary_loop starts its list afresh: one boundary at a time */
        memset(&one, 0, sizeof one);
        if (iges_param_ptr(r, idx, 4 + i, 0, &b) == SEM_OK)
            (void)boundary_loop(r, b, m, depth + 1, NULL, 1, &one, &border);
        move_curves(r, &hint, &one);
    }
    sem_part part;
    memset(&part, 0, sizeof part);
    int model_space = 0;
    if (st == SEM_OK) st = iges_read_trimmed_surface(r, surf, m, depth, &hint, &part, &model_space);
    iges_list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    /* The loops first, then which one is outer: a 143 does not say (I-DEAS lists a plate's
     * hole before its border: corpus occt_ideas_simple1_143), so the outer loop is the one
     * whose (u,v) box holds every other loop's (the first when none does, as written), and
     * none when a boundary is the surface's own border (the others are holes in it). */
    curve_list *loops = calloc((size_t)(n > 0 ? n : 1), sizeof *loops);
    if (!loops) {
        sem_part_free(&part);
        return iges_nomem(r);
    }
    int n_loops = 0, no_outer = 0;
    for (int i = 0; (st == SEM_OK || st == SEM_ERR_UNSUPPORTED) && i < n; ++i) {
        int b, border = 0;
        st = iges_param_ptr(r, idx, 4 + i, 0, &b);
        if (st == SEM_OK)
            st = boundary_loop(r, b, m, depth + 1, &part, model_space, &loops[n_loops], &border);
        /* border: the surface's own, nothing to trim; a first boundary left out (warned):
         * the rest are taken as holes, as written */
        if ((st == SEM_OK && border) || (i == 0 && st != SEM_OK)) no_outer = 1;
        if (st == SEM_OK && !border && loops[n_loops].n > 0) n_loops++;
        else iges_list_free(&loops[n_loops]);
    }
    int outer = no_outer || n_loops == 0 ? -1 : 0;
    for (int a = 0; outer >= 0 && a < n_loops; ++a) {
        double box_a[4], box_b[4];
        loop_box(&loops[a], box_a);
        int holds_all = 1;
        for (int b = 0; b < n_loops && holds_all; ++b) {
            if (b == a) continue;
            loop_box(&loops[b], box_b);
            holds_all = box_a[0] <= box_b[0] && box_a[1] >= box_b[1] && box_a[2] <= box_b[2] &&
                        box_a[3] >= box_b[3];
        }
        if (holds_all) {
            outer = a;
            break;
        }
    }
    if (outer >= 0) iges_set_outer(&part, &loops[outer]);
    for (int a = 0; a < n_loops; ++a) {
        if (a != outer && (st == SEM_OK || st == SEM_ERR_UNSUPPORTED))
            st = iges_add_hole(r, &part, &loops[a]);
        iges_list_free(&loops[a]);
    }
    free(loops);
    if (st != SEM_OK && st != SEM_ERR_UNSUPPORTED) {
        sem_part_free(&part);
        return st;
    }
    return iges_finish_part(r, &part, idx, surf);
}
