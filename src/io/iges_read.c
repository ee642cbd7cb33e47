/*
 * iges_read.c - IGES 5.3 reader: every surface the file describes becomes one NURBS part.
 *
 * Design. The file is read into directory entries and tokenised parameters (iges_lexer.c).
 * Entities are then converted on demand, recursively, with a depth limit, from the
 * top-level entities in directory order:
 *
 *   128 rational B-spline surface          -> a part, stored exactly as written
 *   108 / 118 / 120 / 122 analytic surfaces -> exact NURBS (bilinear plane, degree-1
 *                                             ruled/extruded, rational quadratic circles)
 *   143 (141 boundaries) / 144 (142 curves) -> trimmed part with parameter-space loops
 *   186 -> 514 -> 510 -> 508                -> one trimmed part per B-rep face
 *   408 instance of a 308 definition        -> the definition's surfaces, transformed
 *
 * Surfaces referenced by a trimming entity, a face, a subfigure definition, or any other
 * entity we understand are never emitted again on their own (the status "physically
 * dependent" flags are not trusted alone: a referenced surface is dependent whatever its
 * flags say). Transformation matrices (124, chained through their own DE field) apply to
 * model-space geometry only; trim curves live in the surface's (u,v) domain and keep
 * their coordinates exactly as written.
 *
 * Robustness. Sharing is what multiplies: a subfigure definition (308) may list the same
 * member many times and be instanced by 408s inside other definitions, and a composite
 * curve (102) may repeat one member, so a few kilobytes can describe 10^8 surfaces. The
 * busy flags only stop cycles; what bounds the work is a budget (sem/limits.h): every
 * entity conversion counts against SEM_MAX_IGES_EXPANSION, every control point built
 * (surfaces and curves, copies included) against SEM_MAX_MODEL_CONTROL_POINTS, and the file
 * itself against SEM_MAX_MODEL_FILE_BYTES and SEM_MAX_IGES_ENTITIES. Recursion is bounded.
 * Entities we cannot convert (parametric splines 112/114, conics, offset and analytic
 * 190-198 surfaces, ...) are skipped with a warning naming them.
 *
 * The reader, one step a file, each file calling only those listed before it
 * (iges_internal.h holds what they share):
 *   iges_lexer.c     sections, directory, parameters; errors, budgets, transforms
 *   iges_entities.c  curve and surface entities as NURBS
 *   iges_parts.c     a surface and its loops made a part of the model
 *   iges_trimmed.c   trimmed surfaces (144 with 142, 143 with 141)
 *   iges_brep.c      B-rep solids, shells and faces (186, 514, 510, 508, 504)
 *   iges_read.c      which entities become parts, subfigure instances (408), the API
 */
#include <stdlib.h>
#include <string.h>

#include "io/iges_internal.h"
#include "io/read_file.h"
#include "sem/limits.h"
#include "sem/model.h"

static sem_status emit_entity(iges_reader *r, int idx, const double *parent, int depth);

/* 408: the members of a 308 definition, scaled by S, moved by (X, Y, Z), then transformed
 * by the instance's own matrix (and the definition's). */
static sem_status emit_instance(iges_reader *r, int idx, const double *parent, int depth)
{
    int def;
    double x[3], s;
    sem_status st = iges_param_ptr(r, idx, 1, 0, &def);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = iges_param_real(r, idx, 2 + k, &x[k]);
    s = 1.0; /* IGES default scale when the parameter is absent or empty */
    if (st == SEM_OK && iges_remaining(r, idx, 5) > 0) st = iges_param_real_def(r, idx, 5, 1.0, &s);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 6;
    iges_entry *d = &r->entries[def];
    if (d->type != 308)
        return iges_entity_error(r, idx, iges_token_line(r, idx, 1),
                                 "parameter 1 points to DE %d, a type-%d entity, where a subfigure "
                                 "definition (308) is expected",
                                 iges_de_number(def), d->type);
    if (!(s != 0))
        return iges_entity_error(r, idx, iges_token_line(r, idx, 5), "scale factor is zero");
    if (d->busy || depth > IGES_MAX_DEPTH)
        return iges_entity_error(r, idx, 0, "subfigure instances nest cyclically or deeper than %d",
                                 IGES_MAX_DEPTH);
    double own[12], place[12] = {s, 0, 0, x[0], 0, s, 0, x[1], 0, 0, s, x[2]}, m[12];
    st = iges_own_xform(r, idx, parent, own);
    if (st != SEM_OK) return st;
    iges_xf_compose(own, place, m);
    st = iges_own_xform(r, def, m, m);
    int n;
    if (st == SEM_OK) st = iges_param_int(r, def, 3, &n);
    if (st == SEM_OK) st = iges_need(r, def, 4, n, "subfigure definition (N entities)");
    if (st != SEM_OK) return st;
    d->n_used = 4 + n;
    d->busy = 1;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int child;
        st = iges_param_ptr(r, def, 4 + i, 0, &child);
        if (st == SEM_OK && !r->entries[child].self_ref) st = emit_entity(r, child, m, depth + 1);
    }
    d->busy = 0;
    return st;
}

static sem_status emit_entity(iges_reader *r, int idx, const double *parent, int depth)
{
    if (depth > IGES_MAX_DEPTH)
        return iges_entity_error(r, idx, 0, "entities nest deeper than %d", IGES_MAX_DEPTH);
    sem_status cst = iges_count_conversion(r, idx);
    if (cst != SEM_OK) return cst;
    int type = r->entries[idx].type;
    switch (type) {
    case 108:
    case 118:
    case 120:
    case 122:
    case 128:
    case 190:
    case 192:
    case 194:
    case 196:
    case 198: {
        sem_part part;
        memset(&part, 0, sizeof part);
        sem_status st = iges_read_surface(r, idx, parent, depth, &part);
        if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
        if (st != SEM_OK) return st;
        return iges_finish_part(r, &part, idx, idx);
    }
    case 143: return iges_emit_bounded(r, idx, parent, depth);
    case 144: return iges_emit_trimmed(r, idx, parent, depth);
    case 186: return iges_emit_solid(r, idx, parent, depth);
    case 514: return iges_emit_shell(r, idx, parent, depth);
    case 510: return iges_emit_face(r, idx, parent, depth);
    case 408: return emit_instance(r, idx, parent, depth);
    default:
        if (iges_entity_description(type)) iges_unsupported(r, idx, "not supported, skipped");
        return SEM_OK;
    }
}

/* Marks every entity pointed to by an entity we understand (silently: errors in the
 * pointers are reported when the parent is read). */
static void mark_references(iges_reader *r)
{
    for (int i = 0; i < r->n_entries; ++i) {
        const iges_entry *e = &r->entries[i];
        int n = 0, p, k, kk, self = 0;
        int list[8], nl = 0;
        /* a pointer to the entity itself is not a reference: it would hide the entity
         * (referenced entities are not emitted on their own) without a word */
#define MARK(K)                                                                          \
    do {                                                                                 \
        if (iges_peek_ptr(r, i, (K), &p)) {                                              \
            if (p == i) self = 1;                                                        \
            else r->entries[p].referenced = 1;                                           \
        }                                                                                \
    } while (0)
        /* parameter COUNT says how many pointers follow, from parameter FIRST, STEP apart */
#define MARK_LIST(COUNT, FIRST, STEP)                                                    \
    do {                                                                                 \
        if (iges_peek_int(r, i, (COUNT), &n))                                            \
            for (int j = 0; j < n && j < e->n_params; ++j) MARK((FIRST) + (STEP) * j);   \
    } while (0)
        switch (e->type) {
        case 102: MARK_LIST(1, 2, 1); break;
        case 108: list[nl++] = 5; break;
        case 118: list[nl++] = 1; list[nl++] = 2; break;
        case 120: list[nl++] = 1; list[nl++] = 2; break;
        case 122: list[nl++] = 1; break;
        case 140: list[nl++] = 5; break;
        case 141:
            MARK(3);
            if (!iges_peek_int(r, i, 4, &n)) break;
            k = 5;
            for (int j = 0; j < n && k < e->n_params; ++j) {
                MARK(k);
                if (!iges_peek_int(r, i, k + 2, &kk) || kk < 0) break;
                for (int q = 0; q < kk && q < e->n_params; ++q) MARK(k + 3 + q);
                k += 3 + kk;
            }
            break;
        case 142: list[nl++] = 2; list[nl++] = 3; list[nl++] = 4; break;
        case 143:
            MARK(2);
            MARK_LIST(3, 4, 1);
            break;
        case 144:
            MARK(1);
            MARK(4);
            MARK_LIST(3, 5, 1);
            break;
        case 186:
            MARK(1);
            MARK_LIST(3, 4, 2);
            break;
        case 514: MARK_LIST(1, 2, 2); break;
        case 510:
            MARK(1);
            MARK_LIST(2, 4, 1);
            break;
        case 508:
            if (!iges_peek_int(r, i, 1, &n)) break;
            k = 2;
            for (int j = 0; j < n && k < e->n_params; ++j) {
                MARK(k + 1);
                if (!iges_peek_int(r, i, k + 4, &kk) || kk < 0) break;
                for (int q = 0; q < kk && q < e->n_params; ++q) MARK(k + 6 + 2 * q);
                k += 5 + 2 * kk;
            }
            break;
        case 504: MARK_LIST(1, 2, 5); break;
        case 308:
            if (iges_peek_int(r, i, 3, &n))
                for (int j = 0; j < n && j < e->n_params; ++j)
                    if (iges_peek_ptr(r, i, 4 + j, &p)) {
                        if (p == i) {
                            self = 1;
                            continue;
                        }
                        r->entries[p].referenced = 1;
                        r->entries[p].in_definition = 1;
                    }
            break;
        case 408: list[nl++] = 1; break;
        default: break;
        }
        for (int j = 0; j < nl; ++j) MARK(list[j]);
#undef MARK_LIST
#undef MARK
        if (self) {
            r->entries[i].self_ref = 1;
            if (e->type == 308)
                sem_model_warn(r->model, "entity 308 (DE %d): subfigure definition lists itself; "
                                         "that member is ignored", iges_de_number(i));
            else
                sem_model_warn(r->model, "entity %d (DE %d) points to itself; skipped", e->type,
                               iges_de_number(i));
        }
    }
}

/* ------------------------------------------------------------- API ---- */

static sem_status check_model(iges_reader *r)
{
    sem_error e;
    sem_status st = sem_model_check_limits(r->model, &e);
    if (st != SEM_OK) return sem_error_set(r->err, st, "%s: %s", r->name, e.message);
    return SEM_OK;
}

sem_status sem_iges_read_buffer(const char *name, const char *data, size_t len,
                                sem_model **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!out || (!data && len > 0))
        return sem_error_set(err, SEM_ERR_INVALID, "sem_iges_read_buffer: NULL argument");
    iges_reader r;
    memset(&r, 0, sizeof r);
    r.name = name ? name : "<buffer>";
    r.err = err;
    r.model = sem_model_create();
    if (!r.model) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    sem_status st = iges_read_sections(&r, data ? data : "", len);
    if (st == SEM_OK) mark_references(&r);
    for (int i = 0; st == SEM_OK && i < r.n_entries; ++i) {
        const iges_entry *e = &r.entries[i];
        if (e->type == 0 || e->referenced || e->in_definition || e->type == 308 || e->self_ref)
            continue;
        st = emit_entity(&r, i, iges_identity_xf, 0);
    }
    free(r.lines);
    free(r.ptext);
    free(r.tokens);
    free(r.entries);
    if (st == SEM_OK) st = check_model(&r);
    if (st != SEM_OK) {
        sem_model_destroy(r.model);
        return st;
    }
    *out = r.model;
    return SEM_OK;
}

sem_status sem_iges_read(const char *path, sem_model **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!path || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_iges_read: NULL argument");
    char *buf = NULL;
    size_t len = 0;
    sem_status st = sem_read_file(path, SEM_MAX_MODEL_FILE_BYTES, "SEM_MAX_MODEL_FILE_BYTES", &buf,
                                  &len, err);
    if (st != SEM_OK) return st;
    st = sem_iges_read_buffer(path, buf, len, out, err);
    free(buf);
    return st;
}
