/*
 * iges_brep.c - B-rep topology (iges_internal.h): one trimmed part per face.
 *
 *   186 -> 514 -> 510 -> 508                -> one trimmed part per B-rep face
 *
 * A manifold solid (186) lists its shells (514), a shell its faces (510), a face its
 * surface and loops (508), and a loop the edges (504, or a vertex 502 for a collapsed edge)
 * it runs along. A loop's (u,v) curves are taken as written; an edge that has none (as
 * castle.iges writes them), or a surface whose parameters are not the file's, makes the
 * loop come from the edges' model-space curves projected onto the surface (iges_parts.c).
 * A face one of whose loops cannot be built is kept untrimmed, with a warning.
 */
#include <string.h>

#include "geometry/trim_fix.h"
#include "io/iges_internal.h"

/* Model-space curve of edge `index` (1-based) of a 504 edge list, in the coordinates m. */
static sem_status edge_curve(iges_reader *r, int owner, int k, int list, int index,
                             const double *m, int depth, curve_list *l)
{
    int n, crv;
    sem_status st = iges_param_int(r, list, 1, &n);
    if (st == SEM_OK) st = iges_need(r, list, 2, 5LL * n, "edge list (N edges)");
    if (st != SEM_OK) return st;
    if (index < 1 || index > n)
        return iges_entity_error(r, owner, iges_token_line(r, owner, k),
                                 "edge index %d is outside edge list DE %d (%d edges)", index,
                                 iges_de_number(list), n);
    r->entries[list].n_used = 2 + 5 * n;
    st = iges_param_ptr(r, list, 2 + 5 * (index - 1), 0, &crv);
    if (st == SEM_OK) st = iges_read_curves(r, crv, m, depth + 1, l);
    return st;
}

/* A 508 loop: the parameter-space curves of its edges in order into l, and (for faces
 * whose edges lack them) the edges' model-space curves, in the coordinates m, into
 * model_space. *missing: some edge had no parameter-space curve. */
static sem_status face_loop(iges_reader *r, int idx, const double *m, int depth, curve_list *l,
                            curve_list *model_space, int force_model_space, int *missing)
{
    if (r->entries[idx].type != 508)
        return iges_entity_error(r, idx, 0, "a loop entity (508) was expected here");
    int n;
    sem_status st = iges_param_int(r, idx, 1, &n);
    if (st == SEM_OK) st = iges_need(r, idx, 2, 5LL * n, "loop (N edges)");
    int k = 2;
    *missing = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int type, edge, kk;
        st = iges_need(r, idx, k, 5, "loop edge");
        if (st == SEM_OK) st = iges_param_int(r, idx, k, &type);
        if (st == SEM_OK) st = iges_param_ptr(r, idx, k + 1, 0, &edge);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 4, &kk);
        if (st == SEM_OK) st = iges_need(r, idx, k + 5, 2LL * kk, "loop edge (K parameter curves)");
        if (st != SEM_OK) break;
        int want = type == 1 ? 502 : 504;
        if (r->entries[edge].type != want) {
            st = iges_entity_error(
                r, idx, iges_token_line(r, idx, k + 1),
                "edge %d points to DE %d, a type-%d entity, where a %d is expected", i + 1,
                iges_de_number(edge), r->entries[edge].type, want);
            break;
        }
        if (type != 1 && kk == 0) *missing = 1;
        for (int j = 0; st == SEM_OK && j < kk; ++j) {
            int p = -1;
            st = iges_param_ptr(r, idx, k + 6 + 2 * j, 0, &p);
            if (st == SEM_OK) st = iges_read_curves(r, p, iges_identity_xf, depth + 1, l);
        }
        k += 5 + 2 * kk;
    }
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = k;
    if (!*missing && !force_model_space) return SEM_OK;
    /* the edges' model-space curves, in loop order (a vertex "edge", type 1, adds none: it
     * is a collapsed edge) */
    k = 2;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int type, edge, index, forward, kk = 0;
        st = iges_param_int(r, idx, k, &type);
        if (st == SEM_OK) st = iges_param_ptr(r, idx, k + 1, 0, &edge);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 2, &index);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 3, &forward);
        if (st == SEM_OK) st = iges_param_int(r, idx, k + 4, &kk);
        int first = model_space->n;
        if (st == SEM_OK && type != 1)
            st = edge_curve(r, idx, k + 2, edge, index, m, depth, model_space);
        /* OF = 0: the loop runs the edge backwards (this matters for closed edges, whose
         * direction cannot be told from their ends) */
        if (st == SEM_OK && !forward) iges_reverse_curves(model_space, first);
        k += 5 + 2 * kk;
    }
    return st;
}

sem_status iges_emit_face(iges_reader *r, int idx, const double *parent, int depth)
{
    if (r->entries[idx].type != 510)
        return iges_entity_error(r, idx, 0, "a face entity (510) was expected here");
    int surf, n, of;
    sem_status st = iges_surface_pointer(r, idx, 1, &surf);
    if (st == SEM_OK) st = iges_param_int(r, idx, 2, &n);
    if (st == SEM_OK) st = iges_param_int(r, idx, 3, &of);
    if (st == SEM_OK) st = iges_need(r, idx, 4, n, "face (N loops)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 4 + n;
    double m[12];
    st = iges_own_xform(r, idx, parent, m);
    curve_list l, model_space, hint;
    memset(&l, 0, sizeof l);
    memset(&model_space, 0, sizeof model_space);
    memset(&hint, 0, sizeof hint);
    /* a surface that needs its boundary to be sized: every loop's edges */
    for (int i = 0; st == SEM_OK && iges_needs_hint(r, surf) && i < n; ++i) {
        int p, missing;
        iges_list_free(&l);
        if (iges_param_ptr(r, idx, 4 + i, 0, &p) == SEM_OK)
            (void)face_loop(r, p, m, depth + 1, &l, &hint, 1, &missing);
    }
    iges_list_free(&l);
    sem_part part;
    memset(&part, 0, sizeof part);
    int from_hint = 0;
    if (st == SEM_OK) st = iges_read_trimmed_surface(r, surf, m, depth, &hint, &part, &from_hint);
    iges_list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    int failed = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int p, missing = 0, border = 0;
        iges_list_free(&l);
        iges_list_free(&model_space);
        st = iges_param_ptr(r, idx, 4 + i, 0, &p);
        if (st == SEM_OK) st = face_loop(r, p, m, depth + 1, &l, &model_space, from_hint, &missing);
        if (st == SEM_OK && (missing || from_hint)) {
            /* no (u,v) curves for this loop: project its edges' model-space curves */
            st = iges_project_model_space_loop(r, p, &part, &model_space, &l, &border);
        }
        if (st == SEM_ERR_UNSUPPORTED) {
            failed = 1;
            st = SEM_OK;
            continue;
        }
        if (st != SEM_OK) break;
        if (border) continue; /* the surface's own border: nothing to trim */
        if (i == 0 && of == 1)
            iges_set_outer(&part, &l);
        else
            st = iges_add_hole(r, &part, &l);
    }
    iges_list_free(&l);
    iges_list_free(&model_space);
    if (st != SEM_OK) {
        sem_part_free(&part);
        return st;
    }
    if (failed) {
        /* without every loop the face cannot be trimmed consistently (the failing loop
         * said why) */
        sem_model_warn(r->model, "entity 510 (DE %d): a loop of the face could not be built; "
                                 "the face is kept untrimmed",
                       iges_de_number(idx));
        sem_part_untrim(&part);
    }
    return iges_finish_part(r, &part, idx, surf);
}

sem_status iges_emit_shell(iges_reader *r, int idx, const double *parent, int depth)
{
    if (r->entries[idx].type != 514)
        return iges_entity_error(r, idx, 0, "a shell entity (514) was expected here");
    int n;
    sem_status st = iges_param_int(r, idx, 1, &n);
    if (st == SEM_OK) st = iges_need(r, idx, 2, 2LL * n, "shell (N faces)");
    double m[12];
    if (st == SEM_OK) st = iges_own_xform(r, idx, parent, m);
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int f = -1;
        st = iges_param_ptr(r, idx, 2 + 2 * i, 0, &f);
        if (st == SEM_OK) st = iges_emit_face(r, f, m, depth + 1);
    }
    if (st == SEM_OK) r->entries[idx].n_used = 2 + 2 * n;
    return st;
}

sem_status iges_emit_solid(iges_reader *r, int idx, const double *parent, int depth)
{
    int shell, nvoid;
    sem_status st = iges_param_ptr(r, idx, 1, 0, &shell);
    if (st == SEM_OK) st = iges_param_int(r, idx, 3, &nvoid);
    if (st == SEM_OK) st = iges_need(r, idx, 4, 2LL * nvoid, "B-rep solid (N voids)");
    double m[12];
    if (st == SEM_OK) st = iges_own_xform(r, idx, parent, m);
    if (st == SEM_OK) st = iges_emit_shell(r, shell, m, depth + 1);
    for (int i = 0; st == SEM_OK && i < nvoid; ++i) {
        int v;
        st = iges_param_ptr(r, idx, 4 + 2 * i, 0, &v);
        if (st == SEM_OK) st = iges_emit_shell(r, v, m, depth + 1);
    }
    if (st == SEM_OK) r->entries[idx].n_used = 4 + 2 * nvoid;
    return st;
}
