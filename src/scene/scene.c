/*
 * scene.c - scene files (see sem/scene.h and docs/scenes.md).
 *
 * Every JSON object is checked against the keys it may have, so a typo ("desnity") is an
 * error that names the key instead of a silently ignored setting. Messages have the form
 * "FILE: objects[0].material.density: must be positive (got -3)".
 */
#include "sem/scene.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/read_file.h"
#include "sem/limits.h"
#include "sem/primitives.h"
#include "util/free_all.h"

typedef struct ctx {
    const char *name;
    sem_error *err;
} ctx;

static sem_status fail(ctx *c, const char *where, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static sem_status fail(ctx *c, const char *where, const char *fmt, ...)
{
    char place[1024];
    snprintf(place, sizeof place, "%s: %s", c->name, where);
    va_list ap;
    va_start(ap, fmt);
    sem_status st = sem_error_vset(c->err, SEM_ERR_INVALID, place, fmt, ap);
    va_end(ap);
    return st;
}

/* Rejects keys that are not in the NULL-terminated list. */
static sem_status check_keys(ctx *c, const cJSON *obj, const char *where, const char *const *allowed)
{
    if (!cJSON_IsObject(obj)) return fail(c, where, "must be a JSON object");
    for (const cJSON *it = obj->child; it; it = it->next) {
        int ok = 0;
        for (int k = 0; allowed[k]; ++k)
            if (strcmp(it->string, allowed[k]) == 0) ok = 1;
        if (!ok) {
            char list[512] = "";
            for (int k = 0; allowed[k]; ++k) {
                strncat(list, allowed[k], sizeof list - strlen(list) - 1);
                if (allowed[k + 1]) strncat(list, ", ", sizeof list - strlen(list) - 1);
            }
            return fail(c, where, "unknown key \"%s\" (allowed: %s)", it->string, list);
        }
    }
    return SEM_OK;
}

/* The value of an optional key of obj (NULL when it is absent) and, in w, its place
 * "where.key" for the messages about it. */
static const cJSON *find_key(const cJSON *obj, const char *key, const char *where, char w[256])
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (v) snprintf(w, 256, "%s.%s", where, key);
    return v;
}

static sem_status get_number(ctx *c, const cJSON *obj, const char *key, const char *where,
                             double *out)
{
    char w[256];
    const cJSON *v = find_key(obj, key, where, w);
    if (!v) return SEM_OK;
    if (!cJSON_IsNumber(v) || !isfinite(v->valuedouble)) return fail(c, w, "must be a finite number");
    *out = v->valuedouble;
    return SEM_OK;
}

/* An optional number of 0..max, null meaning "the default" (*out left as it is); max_text is
 * how the message writes the bound. */
static sem_status get_number_upto(ctx *c, const cJSON *obj, const char *key, const char *where, double max,
                                  const char *max_text, double *out)
{
    const cJSON *v = cJSON_GetObjectItemCaseSensitive(obj, key);
    if (!v || cJSON_IsNull(v)) return SEM_OK;
    sem_status st = get_number(c, obj, key, where, out);
    if (st != SEM_OK) return st;
    if (!(*out >= 0) || *out > max) {
        char w[300];
        snprintf(w, sizeof w, "%s.%s", where, key);
        return fail(c, w, "must be in 0..%s or null (got %g)", max_text, *out);
    }
    return SEM_OK;
}

static sem_status get_int(ctx *c, const cJSON *obj, const char *key, const char *where, int *out)
{
    char w[256];
    const cJSON *v = find_key(obj, key, where, w);
    if (!v) return SEM_OK;
    if (!cJSON_IsNumber(v) || v->valuedouble != floor(v->valuedouble))
        return fail(c, w, "must be an integer");
    if (fabs(v->valuedouble) > 1e9)
        return fail(c, w, "%g is too large (at most 1000000000)", v->valuedouble);
    *out = (int)v->valuedouble;
    return SEM_OK;
}

static sem_status get_bool(ctx *c, const cJSON *obj, const char *key, const char *where, int *out)
{
    char w[256];
    const cJSON *v = find_key(obj, key, where, w);
    if (!v) return SEM_OK;
    if (!cJSON_IsBool(v)) return fail(c, w, "must be true or false");
    *out = cJSON_IsTrue(v);
    return SEM_OK;
}

/* An optional string key that names one of a few choices: *out = values[k] for names[k] (a
 * NULL-terminated list); otherwise an error that lists the names. */
static sem_status get_choice(ctx *c, const cJSON *obj, const char *key, const char *where,
                             const char *const *names, const int *values, int *out)
{
    char w[256];
    const cJSON *v = find_key(obj, key, where, w);
    if (!v) return SEM_OK;
    for (int k = 0; names[k]; ++k)
        if (cJSON_IsString(v) && !strcmp(v->valuestring, names[k])) {
            *out = values[k];
            return SEM_OK;
        }
    char list[256] = "";
    size_t len = 0;
    for (int k = 0; names[k] && len < sizeof list; ++k)
        len += (size_t)snprintf(list + len, sizeof list - len, "%s\"%s\"", k == 0 ? "" : names[k + 1] ? ", " : " or ",
                                names[k]);
    return fail(c, w, "must be %s", list);
}

static sem_status vec_n(ctx *c, const cJSON *v, const char *where, int n, double *out)
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != n)
        return fail(c, where, "must be an array of %d numbers", n);
    int k = 0;
    for (const cJSON *it = v->child; it; it = it->next, ++k) {
        if (!cJSON_IsNumber(it) || !isfinite(it->valuedouble))
            return fail(c, where, "element %d is not a finite number", k);
        out[k] = it->valuedouble;
    }
    return SEM_OK;
}

static sem_status get_vec(ctx *c, const cJSON *obj, const char *key, const char *where, int n,
                          double *out)
{
    char w[256];
    const cJSON *v = find_key(obj, key, where, w);
    if (!v) return SEM_OK;
    return vec_n(c, v, w, n, out);
}

static sem_status get_box(ctx *c, const cJSON *v, const char *where, double box[6])
{
    if (!cJSON_IsArray(v) || cJSON_GetArraySize(v) != 2)
        return fail(c, where, "must be [[x0,y0,z0],[x1,y1,z1]]");
    char w[256];
    snprintf(w, sizeof w, "%s[0]", where);
    sem_status st = vec_n(c, cJSON_GetArrayItem(v, 0), w, 3, box);
    if (st != SEM_OK) return st;
    snprintf(w, sizeof w, "%s[1]", where);
    st = vec_n(c, cJSON_GetArrayItem(v, 1), w, 3, box + 3);
    if (st != SEM_OK) return st;
    for (int k = 0; k < 3; ++k)
        if (box[k] > box[k + 3]) return fail(c, where, "lower corner exceeds upper corner along axis %d", k);
    return SEM_OK;
}

static sem_status parse_material(ctx *c, const cJSON *m, const char *where, sem_material *out)
{
    static const char *const keys[] = {"type", "density", "youngs_modulus", "poisson_ratio", NULL};
    sem_status st = check_keys(c, m, where, keys);
    if (st != SEM_OK) return st;
    const cJSON *t = cJSON_GetObjectItemCaseSensitive(m, "type");
    if (t) {
        char w[256];
        snprintf(w, sizeof w, "%s.type", where);
        if (!cJSON_IsString(t) || sem_material_parse_type(t->valuestring, &out->type) != SEM_OK)
            return fail(c, w,
                        "unknown material type (use neohookean, stable_neohookean, corotated, "
                        "stvk or linear)");
    }
    if ((st = get_number(c, m, "density", where, &out->density)) != SEM_OK) return st;
    if ((st = get_number(c, m, "youngs_modulus", where, &out->youngs_modulus)) != SEM_OK) return st;
    if ((st = get_number(c, m, "poisson_ratio", where, &out->poisson_ratio)) != SEM_OK) return st;
    sem_error e;
    sem_material tmp = *out;
    if (sem_material_init(&tmp, &e) != SEM_OK) return fail(c, where, "%s", e.message);
    *out = tmp;
    return SEM_OK;
}

static void mat_identity(double T[12])
{
    memset(T, 0, 12 * sizeof(double));
    T[0] = T[5] = T[10] = 1.0;
}

/* T = A * T (both 3x4 affine) */
static void mat_compose(double T[12], const double A[12])
{
    double R[12];
    for (int r = 0; r < 3; ++r) {
        for (int col = 0; col < 4; ++col) {
            double s = col == 3 ? A[4 * r + 3] : 0.0;
            for (int k = 0; k < 3; ++k) s += A[4 * r + k] * T[4 * k + col];
            R[4 * r + col] = s;
        }
    }
    memcpy(T, R, sizeof R);
}

static sem_status parse_transform(ctx *c, const cJSON *t, const char *where, double T[12])
{
    static const char *const keys[] = {"scale", "rotate", "translate", "matrix", NULL};
    sem_status st = check_keys(c, t, where, keys);
    if (st != SEM_OK) return st;
    mat_identity(T);
    char w[256];
    /* order: scale, then rotate, then translate (or a full matrix) */
    const cJSON *m = find_key(t, "matrix", where, w);
    if (m) {
        if (!cJSON_IsArray(m) || cJSON_GetArraySize(m) != 3) return fail(c, w, "must be 3 rows of 4 numbers");
        if (cJSON_GetObjectItemCaseSensitive(t, "scale") || cJSON_GetObjectItemCaseSensitive(t, "rotate") ||
            cJSON_GetObjectItemCaseSensitive(t, "translate"))
            return fail(c, w, "give either \"matrix\" or scale/rotate/translate, not both");
        for (int r = 0; r < 3; ++r) {
            char wr[300];
            snprintf(wr, sizeof wr, "%s[%d]", w, r);
            if ((st = vec_n(c, cJSON_GetArrayItem(m, r), wr, 4, T + 4 * r)) != SEM_OK) return st;
        }
        /* a mirror (det < 0) turns the surfaces inside out; det = 0 flattens the solid */
        double det = T[0] * (T[5] * T[10] - T[6] * T[9]) - T[1] * (T[4] * T[10] - T[6] * T[8]) +
                     T[2] * (T[4] * T[9] - T[5] * T[8]);
        if (!(det > 0))
            return fail(c, w, "the 3x3 part must have a positive determinant (got %g): mirrors and "
                        "flattening maps are not allowed", det);
        return SEM_OK;
    }
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(t, "scale");
    if (s) {
        double sc[3];
        snprintf(w, sizeof w, "%s.scale", where);
        if (cJSON_IsNumber(s))
            sc[0] = sc[1] = sc[2] = s->valuedouble;
        else if ((st = vec_n(c, s, w, 3, sc)) != SEM_OK)
            return st;
        for (int k = 0; k < 3; ++k)
            if (!(sc[k] > 0) || !isfinite(sc[k])) return fail(c, w, "scale factors must be positive");
        double A[12] = {sc[0], 0, 0, 0, 0, sc[1], 0, 0, 0, 0, sc[2], 0};
        mat_compose(T, A);
    }
    const cJSON *r = cJSON_GetObjectItemCaseSensitive(t, "rotate");
    if (r) {
        static const char *const rkeys[] = {"axis", "degrees", NULL};
        snprintf(w, sizeof w, "%s.rotate", where);
        if ((st = check_keys(c, r, w, rkeys)) != SEM_OK) return st;
        double axis[3] = {0, 0, 1}, deg = 0;
        if ((st = get_vec(c, r, "axis", w, 3, axis)) != SEM_OK) return st;
        if ((st = get_number(c, r, "degrees", w, &deg)) != SEM_OK) return st;
        double n = sqrt(axis[0] * axis[0] + axis[1] * axis[1] + axis[2] * axis[2]);
        if (!(n > 0)) return fail(c, w, "axis must not be zero");
        double x = axis[0] / n, y = axis[1] / n, z = axis[2] / n, a = deg * M_PI / 180.0;
        double cs = cos(a), sn = sin(a), C = 1 - cs;
        double A[12] = {cs + x * x * C,     x * y * C - z * sn, x * z * C + y * sn, 0,
                        y * x * C + z * sn, cs + y * y * C,     y * z * C - x * sn, 0,
                        z * x * C - y * sn, z * y * C + x * sn, cs + z * z * C,     0};
        mat_compose(T, A);
    }
    const cJSON *tr = cJSON_GetObjectItemCaseSensitive(t, "translate");
    if (tr) {
        double b[3];
        snprintf(w, sizeof w, "%s.translate", where);
        if ((st = vec_n(c, tr, w, 3, b)) != SEM_OK) return st;
        T[3] += b[0];
        T[7] += b[1];
        T[11] += b[2];
    }
    return SEM_OK;
}

static sem_status parse_sem(ctx *c, const cJSON *s, const char *where, sem_preprocess_options *o)
{
    static const char *const keys[] = {"order", "alpha", "sparsity", "spacing", "rays",
                                       "ray_axis", "points_per_interval", "gamma",
                                       "tessellation", "weight_threshold", "origins", "fit", "blend", "seams", "weld",
                                       "seam_ties", "resolution", NULL};
    sem_status st = check_keys(c, s, where, keys);
    if (st != SEM_OK) return st;
    char w[256];
    if ((st = get_int(c, s, "order", where, &o->order)) != SEM_OK) return st;
    if (o->order != 1 && o->order != 2) {
        snprintf(w, sizeof w, "%s.order", where);
        return fail(c, w, "must be 1 or 2 (got %d)", o->order);
    }
    const cJSON *a = cJSON_GetObjectItemCaseSensitive(s, "alpha");
    if (a && !cJSON_IsNull(a)) {
        if ((st = get_number(c, s, "alpha", where, &o->alpha)) != SEM_OK) return st;
        if (!(o->alpha > 0)) {
            snprintf(w, sizeof w, "%s.alpha", where);
            return fail(c, w, "must be positive (got %g)", o->alpha);
        }
    }
    const cJSON *sp = cJSON_GetObjectItemCaseSensitive(s, "sparsity");
    if (sp && !cJSON_IsNull(sp)) {
        if ((st = get_number(c, s, "sparsity", where, &o->sparsity)) != SEM_OK) return st;
        if (!(o->sparsity > 0 && o->sparsity < 1)) {
            snprintf(w, sizeof w, "%s.sparsity", where);
            return fail(c, w, "must be in (0, 1) (got %g)", o->sparsity);
        }
    }
    if (a && !cJSON_IsNull(a) && sp && !cJSON_IsNull(sp))
        return fail(c, where, "give either \"alpha\" or \"sparsity\", not both");
    const cJSON *r = cJSON_GetObjectItemCaseSensitive(s, "rays");
    if (r) {
        double rr[2];
        snprintf(w, sizeof w, "%s.rays", where);
        if ((st = vec_n(c, r, w, 2, rr)) != SEM_OK) return st;
        if (rr[0] < 1 || rr[1] < 1 || rr[0] > SEM_MAX_RAYS_PER_AXIS ||
            rr[1] > SEM_MAX_RAYS_PER_AXIS || rr[0] != floor(rr[0]) || rr[1] != floor(rr[1]))
            return fail(c, w, "must be two integers in 1..%d", SEM_MAX_RAYS_PER_AXIS);
        o->rays[0] = (int)rr[0];
        o->rays[1] = (int)rr[1];
    }
    static const char *const origin_names[] = {"coupled", "paper", NULL};
    static const int origin_rules[] = {SEM_ORIGINS_COUPLED, SEM_ORIGINS_PAPER};
    if ((st = get_choice(c, s, "origins", where, origin_names, origin_rules, &o->origin_rule)) != SEM_OK) return st;
    static const char *const fit_names[] = {"auto", "parts", "origins", NULL};
    static const int fit_rules[] = {SEM_FIT_AUTO, SEM_FIT_PARTS, SEM_FIT_ORIGINS};
    if ((st = get_choice(c, s, "fit", where, fit_names, fit_rules, &o->fit_rule)) != SEM_OK) return st;
    const cJSON *spc = cJSON_GetObjectItemCaseSensitive(s, "spacing");
    if (spc && !cJSON_IsNull(spc)) {
        if ((st = get_number(c, s, "spacing", where, &o->spacing)) != SEM_OK) return st;
        snprintf(w, sizeof w, "%s.spacing", where);
        if (!(o->spacing > 0)) return fail(c, w, "must be positive or null (got %g)", o->spacing);
        if (r) return fail(c, where, "give either \"spacing\" or \"rays\", not both");
    }
    const cJSON *ax = find_key(s, "ray_axis", where, w);
    if (ax) {
        if (!cJSON_IsString(ax) || strlen(ax->valuestring) != 1 || !strchr("xyz", ax->valuestring[0]))
            return fail(c, w, "must be \"x\", \"y\" or \"z\"");
        o->ray_axis = ax->valuestring[0] - 'x';
        if (!r)
            return fail(c, w, "needs \"rays\" (without rays the grid is laid in the object's "
                              "own frame)");
    }
    const cJSON *ppi = cJSON_GetObjectItemCaseSensitive(s, "points_per_interval");
    if (ppi && !cJSON_IsNull(ppi)) {
        if ((st = get_int(c, s, "points_per_interval", where, &o->points_per_interval)) != SEM_OK)
            return st;
        if (o->points_per_interval < 1 || o->points_per_interval > SEM_MAX_POINTS_PER_INTERVAL) {
            snprintf(w, sizeof w, "%s.points_per_interval", where);
            return fail(c, w, "must be in 1..%d or null (got %d)", SEM_MAX_POINTS_PER_INTERVAL,
                        o->points_per_interval);
        }
    }
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(s, "gamma");
    if (g && !cJSON_IsNull(g)) {
        if ((st = get_number(c, s, "gamma", where, &o->gamma)) != SEM_OK) return st;
        if (!(o->gamma > 0)) {
            snprintf(w, sizeof w, "%s.gamma", where);
            return fail(c, w, "must be positive or null (got %g)", o->gamma);
        }
    }
    if ((st = get_int(c, s, "tessellation", where, &o->tessellation)) != SEM_OK) return st;
    if (o->tessellation < 1 || o->tessellation > 256) {
        snprintf(w, sizeof w, "%s.tessellation", where);
        return fail(c, w, "must be in 1..256");
    }
    if ((st = get_number(c, s, "weight_threshold", where, &o->weight_threshold)) != SEM_OK) return st;
    if (!(o->weight_threshold >= 0 && o->weight_threshold < 0.5)) {
        snprintf(w, sizeof w, "%s.weight_threshold", where);
        return fail(c, w, "must be in [0, 0.5)");
    }
    return SEM_OK;
}

static sem_status parse_int_list(ctx *c, const cJSON *v, const char *where, int **out, int *n)
{
    if (!cJSON_IsArray(v)) return fail(c, where, "must be an array of integers");
    int cnt = cJSON_GetArraySize(v);
    int *a = malloc(((size_t)cnt + 1) * sizeof(int));
    if (!a) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
    int k = 0;
    for (const cJSON *it = v->child; it; it = it->next, ++k) {
        if (!cJSON_IsNumber(it) || it->valuedouble != floor(it->valuedouble) || it->valuedouble < 0 ||
            it->valuedouble > 1e9) {
            free(a);
            return fail(c, where, "element %d is not a non-negative integer", k);
        }
        a[k] = (int)it->valuedouble;
    }
    *out = a;
    *n = cnt;
    return SEM_OK;
}

/* "affine" or "rotate" of a prescription object (keys checked by the caller). */
static sem_status parse_prescription(ctx *c, const cJSON *pr, const char *w, sem_prescribe *out)
{
    sem_status st;
        const cJSON *af = cJSON_GetObjectItemCaseSensitive(pr, "affine");
        const cJSON *ro = cJSON_GetObjectItemCaseSensitive(pr, "rotate");
        const cJSON *mv = cJSON_GetObjectItemCaseSensitive(pr, "move");
        if ((af != NULL) + (ro != NULL) + (mv != NULL) > 1)
            return fail(c, w, "give one of \"affine\", \"rotate\" and \"move\"");
        char w2[300];
        if (af) {
            snprintf(w2, sizeof w2, "%s.affine", w);
            if (!cJSON_IsArray(af) || cJSON_GetArraySize(af) != 3) return fail(c, w2, "must be 3 rows of 4 numbers");
            for (int r = 0; r < 3; ++r) {
                char wr[320];
                snprintf(wr, sizeof wr, "%s[%d]", w2, r);
                if ((st = vec_n(c, cJSON_GetArrayItem(af, r), wr, 4, out->affine + 4 * r)) != SEM_OK)
                    return st;
            }
            out->type = SEM_PRESCRIBE_AFFINE;
        }
        if (ro) {
            static const char *const rkeys[] = {"axis_point", "axis", "degrees_per_second",
                                                "radians_per_second", "duration", NULL};
            snprintf(w2, sizeof w2, "%s.rotate", w);
            if ((st = check_keys(c, ro, w2, rkeys)) != SEM_OK) return st;
            out->type = SEM_PRESCRIBE_ROTATE;
            out->axis_direction[0] = 1;
            if ((st = get_vec(c, ro, "axis_point", w2, 3, out->axis_point)) != SEM_OK) return st;
            if ((st = get_vec(c, ro, "axis", w2, 3, out->axis_direction)) != SEM_OK) return st;
            double dps = 0, rps = 0;
            if ((st = get_number(c, ro, "degrees_per_second", w2, &dps)) != SEM_OK) return st;
            if ((st = get_number(c, ro, "radians_per_second", w2, &rps)) != SEM_OK) return st;
            if (cJSON_GetObjectItemCaseSensitive(ro, "degrees_per_second") &&
                cJSON_GetObjectItemCaseSensitive(ro, "radians_per_second"))
                return fail(c, w2, "give either \"degrees_per_second\" or \"radians_per_second\", not both");
            out->rate = rps != 0 ? rps : dps * M_PI / 180.0;
            if ((st = get_number(c, ro, "duration", w2, &out->duration)) != SEM_OK) return st;
            const double *a = out->axis_direction;
            if (!(a[0] * a[0] + a[1] * a[1] + a[2] * a[2] > 0)) return fail(c, w2, "axis must not be zero");
        }
        if (mv) {
            static const char *const mkeys[] = {"velocity", "duration", NULL};
            snprintf(w2, sizeof w2, "%s.move", w);
            if ((st = check_keys(c, mv, w2, mkeys)) != SEM_OK) return st;
            if (!cJSON_GetObjectItemCaseSensitive(mv, "velocity")) return fail(c, w2, "needs \"velocity\"");
            out->type = SEM_PRESCRIBE_MOVE;
            if ((st = get_vec(c, mv, "velocity", w2, 3, out->velocity)) != SEM_OK) return st;
            if ((st = get_number(c, mv, "duration", w2, &out->duration)) != SEM_OK) return st;
        }
        return SEM_OK;
}

/* A pin selection {box, control_box, parts, points}: box the material in it (material pin,
 * sem_pin_region), the rest control points. */
static sem_status parse_selection(ctx *c, const cJSON *pin, const char *w, int *has_box, double box[6],
                                  int *has_control_box, double control_box[6], int **parts, int *n_parts,
                                  int **points, int *n_points)
{
    static const char *const pkeys[] = {"box", "control_box", "parts", "points", NULL};
    sem_status st = check_keys(c, pin, w, pkeys);
    if (st != SEM_OK) return st;
    char w2[320];
    const cJSON *b = cJSON_GetObjectItemCaseSensitive(pin, "box");
    if (b) {
        snprintf(w2, sizeof w2, "%s.box", w);
        if ((st = get_box(c, b, w2, box)) != SEM_OK) return st;
        *has_box = 1;
    }
    const cJSON *cb = cJSON_GetObjectItemCaseSensitive(pin, "control_box");
    if (cb) {
        snprintf(w2, sizeof w2, "%s.control_box", w);
        if ((st = get_box(c, cb, w2, control_box)) != SEM_OK) return st;
        *has_control_box = 1;
    }
    const cJSON *pp = cJSON_GetObjectItemCaseSensitive(pin, "parts");
    if (pp) {
        snprintf(w2, sizeof w2, "%s.parts", w);
        if ((st = parse_int_list(c, pp, w2, parts, n_parts)) != SEM_OK) return st;
    }
    const cJSON *pt = cJSON_GetObjectItemCaseSensitive(pin, "points");
    if (pt) {
        snprintf(w2, sizeof w2, "%s.points", w);
        if ((st = parse_int_list(c, pt, w2, points, n_points)) != SEM_OK) return st;
    }
    if (!b && !cb && !pp && !pt) return fail(c, w, "selects nothing (give box, control_box, parts or points)");
    return SEM_OK;
}

/* The shape of an object or a collider: "model" (with "units") or "primitive", and
 * "transform" (where: "objects[0]", "colliders[1]"). */
static sem_status parse_shape(ctx *c, const cJSON *o, const char *where, const char *base_dir,
                              sem_scene_object *obj)
{
    char w[256];
    sem_status st;
    mat_identity(obj->transform);
    const cJSON *model = cJSON_GetObjectItemCaseSensitive(o, "model");
    const cJSON *prim = cJSON_GetObjectItemCaseSensitive(o, "primitive");
    const cJSON *units = find_key(o, "units", where, w);
    if (units) {
        if (!cJSON_IsString(units) ||
            (strcmp(units->valuestring, "as_metres") != 0 &&
             !(sem_unit_to_meter(units->valuestring, NULL) > 0)))
            return fail(c, w,
                        "must be \"as_metres\" or a unit name (m, mm, cm, um, km, in, ft, mi, "
                        "mil, uin)");
        if (!model) return fail(c, w, "applies to a \"model\" file (primitives are in metres)");
        snprintf(obj->units, sizeof obj->units, "%s", units->valuestring);
    }
    if (!!model == !!prim) return fail(c, where, "needs exactly one of \"model\" or \"primitive\"");
    if (model) {
        snprintf(w, sizeof w, "%s.model", where);
        if (!cJSON_IsString(model) || !model->valuestring[0]) return fail(c, w, "must be a file path");
        const char *p = model->valuestring;
        if (p[0] == '/' || !base_dir || !base_dir[0])
            snprintf(obj->model_path, sizeof obj->model_path, "%s", p);
        else
            snprintf(obj->model_path, sizeof obj->model_path, "%s/%s", base_dir, p);
    } else {
        /* each shape takes only its own size keys, so "radius" on a box is an error, not a
         * silently ignored setting */
        static const char *const box_keys[] = {"type", "size", NULL};
        static const char *const beam_keys[] = {"type", "size", "length", "width", "height", "sections", NULL};
        static const char *const sphere_keys[] = {"type", "radius", NULL};
        static const char *const cylinder_keys[] = {"type", "radius", "height", NULL};
        static const char *const torus_keys[] = {"type", "major", "minor", NULL};
        snprintf(w, sizeof w, "%s.primitive", where);
        if (!cJSON_IsObject(prim)) return fail(c, w, "must be a JSON object");
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(prim, "type");
        const char *const *pkeys = NULL;
        if (cJSON_IsString(t)) {
            if (!strcmp(t->valuestring, "box")) pkeys = box_keys;
            else if (!strcmp(t->valuestring, "beam")) pkeys = beam_keys;
            else if (!strcmp(t->valuestring, "sphere")) pkeys = sphere_keys;
            else if (!strcmp(t->valuestring, "cylinder")) pkeys = cylinder_keys;
            else if (!strcmp(t->valuestring, "torus")) pkeys = torus_keys;
        }
        if (!pkeys) {
            char wt[300];
            snprintf(wt, sizeof wt, "%s.type", w);
            return fail(c, wt, "must be \"box\", \"beam\", \"sphere\", \"cylinder\" or \"torus\"");
        }
        if ((st = check_keys(c, prim, w, pkeys)) != SEM_OK) return st;
        snprintf(obj->primitive, sizeof obj->primitive, "%s", t->valuestring);
        /* 0 = not given: the builder's default (sem/primitives.h) */
        obj->primitive_size[0] = obj->primitive_size[1] = obj->primitive_size[2] = 0;
        obj->primitive_sections = 0;
        int is_torus = !strcmp(obj->primitive, "torus");
        if ((st = get_vec(c, prim, "size", w, 3, obj->primitive_size)) != SEM_OK) return st;
        for (int k = 0; k < 3; ++k)
            if (cJSON_GetObjectItemCaseSensitive(prim, "size") && !(obj->primitive_size[k] > 0)) {
                char wk[300];
                snprintf(wk, sizeof wk, "%s.size", w);
                return fail(c, wk, "sizes must be positive (got %g along axis %d)", obj->primitive_size[k], k);
            }
        if ((st = get_number(c, prim, "length", w, &obj->primitive_size[0])) != SEM_OK) return st;
        if ((st = get_number(c, prim, "width", w, &obj->primitive_size[1])) != SEM_OK) return st;
        if ((st = get_number(c, prim, "height", w, &obj->primitive_size[2])) != SEM_OK) return st;
        obj->primitive_height = obj->primitive_size[2];
        if ((st = get_int(c, prim, "sections", w, &obj->primitive_sections)) != SEM_OK) return st;
        if ((st = get_number(c, prim, is_torus ? "major" : "radius", w, &obj->primitive_radius)) != SEM_OK)
            return st;
        if ((st = get_number(c, prim, "minor", w, &obj->primitive_radius2)) != SEM_OK) return st;
        /* every given size must be positive (a missing one keeps its default) */
        static const char *const positive_keys[] = {"length", "width", "height", "radius", "major", "minor", NULL};
        for (int k = 0; positive_keys[k]; ++k) {
            const cJSON *v = cJSON_GetObjectItemCaseSensitive(prim, positive_keys[k]);
            if (v && !(v->valuedouble > 0)) {
                char wk[300];
                snprintf(wk, sizeof wk, "%s.%s", w, positive_keys[k]);
                return fail(c, wk, "must be positive (got %g)", v->valuedouble);
            }
        }
        const cJSON *sec = cJSON_GetObjectItemCaseSensitive(prim, "sections");
        if (sec && (obj->primitive_sections < 1 || obj->primitive_sections > SEM_MAX_BEAM_SECTIONS)) {
            char wk[300];
            snprintf(wk, sizeof wk, "%s.sections", w);
            return fail(c, wk, "must be in 1..%d (got %d)", SEM_MAX_BEAM_SECTIONS,
                        obj->primitive_sections);
        }
        if (is_torus) {
            sem_torus_def td = sem_default_torus_def();
            double R = obj->primitive_radius > 0 ? obj->primitive_radius : td.major;
            double r = obj->primitive_radius2 > 0 ? obj->primitive_radius2 : td.minor;
            if (!(r < R)) return fail(c, w, "minor radius %g must be less than major radius %g", r, R);
        }
    }
    const cJSON *t = find_key(o, "transform", where, w);
    if (t) {
        if ((st = parse_transform(c, t, w, obj->transform)) != SEM_OK) return st;
    }
    return SEM_OK;
}

static sem_status parse_object(ctx *c, const cJSON *o, int index, const char *base_dir,
                               sem_scene_object *obj)
{
    static const char *const keys[] = {"model", "primitive", "transform", "material",
                                       "part_materials", "sem", "pin", "prescribe",
                                       "initial_velocity", "initial_angular_velocity",
                                       "point_loads", "region_loads", "gamma", "units", "friction", NULL};
    char where[64], w[256];
    snprintf(where, sizeof where, "objects[%d]", index);
    sem_status st = check_keys(c, o, where, keys);
    if (st != SEM_OK) return st;
    obj->material = sem_default_material();
    obj->sem = sem_default_preprocess_options();
    obj->blend = SEM_DEFAULT_BLEND;
    obj->weld = -1; /* with sem.resolution */
    obj->seam_ties = SEM_DEFAULT_SEAM_TIES;
    if ((st = parse_shape(c, o, where, base_dir, obj)) != SEM_OK) return st;
    obj->friction = SEM_DEFAULT_FRICTION;
    if ((st = get_number(c, o, "friction", where, &obj->friction)) != SEM_OK) return st;
    if (!(obj->friction >= 0)) {
        snprintf(w, sizeof w, "%s.friction", where);
        return fail(c, w, "must be >= 0 (got %g)", obj->friction);
    }
    const cJSON *m = find_key(o, "material", where, w);
    if (m) {
        if ((st = parse_material(c, m, w, &obj->material)) != SEM_OK) return st;
    } else {
        sem_error e;
        sem_material_init(&obj->material, &e);
    }
    const cJSON *pm = find_key(o, "part_materials", where, w);
    if (pm) {
        if (!cJSON_IsObject(pm)) return fail(c, w, "must map part indices or names to materials");
        int n = cJSON_GetArraySize(pm);
        obj->part_materials = calloc((size_t)n + 1, sizeof *obj->part_materials);
        if (!obj->part_materials) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
        for (const cJSON *it = pm->child; it; it = it->next) {
            sem_scene_part_material *spm = &obj->part_materials[obj->n_part_materials++];
            char *end;
            long idx = strtol(it->string, &end, 10);
            if (*it->string && !*end && idx >= 0) {
                spm->part = (int)idx;
            } else {
                spm->part = -1;
                snprintf(spm->name, sizeof spm->name, "%s", it->string);
            }
            spm->material = obj->material;
            char w2[300];
            snprintf(w2, sizeof w2, "%s.%s", w, it->string);
            if ((st = parse_material(c, it, w2, &spm->material)) != SEM_OK) return st;
        }
    }
    const cJSON *s = cJSON_GetObjectItemCaseSensitive(o, "sem");
    obj->sem.youngs_modulus = obj->material.youngs_modulus;
    if (s) {
        snprintf(w, sizeof w, "%s.sem", where);
        if ((st = parse_sem(c, s, w, &obj->sem)) != SEM_OK) return st;
        static const char *const seam_names[] = {"geometric", "paper", NULL};
        static const int seam_rules[] = {SEM_SEAMS_GEOMETRIC, SEM_SEAMS_PAPER};
        if ((st = get_choice(c, s, "seams", w, seam_names, seam_rules, &obj->seams)) != SEM_OK) return st;
        if ((st = get_bool(c, s, "weld", w, &obj->weld)) != SEM_OK) return st;
        char max_res[16];
        snprintf(max_res, sizeof max_res, "%d", SEM_MAX_RESOLUTION);
        if ((st = get_number_upto(c, s, "resolution", w, SEM_MAX_RESOLUTION, max_res, &obj->resolution)) != SEM_OK ||
            (st = get_number_upto(c, s, "seam_ties", w, 1e6, "1e6", &obj->seam_ties)) != SEM_OK ||
            (st = get_number_upto(c, s, "blend", w, 1e6, "1e6", &obj->blend)) != SEM_OK)
            return st;
    }
    const cJSON *pin = find_key(o, "pin", where, w);
    if (pin) {
        if ((st = parse_selection(c, pin, w, &obj->has_pin_box, obj->pin_box, &obj->has_pin_control_box,
                                  obj->pin_control_box, &obj->pin_parts, &obj->n_pin_parts, &obj->pin_points,
                                  &obj->n_pin_points)) != SEM_OK)
            return st;
    }
    const cJSON *pr = cJSON_GetObjectItemCaseSensitive(o, "prescribe");
    if (pr && cJSON_IsArray(pr)) {
        /* several groups, each with its own pin selection and motion */
        snprintf(w, sizeof w, "%s.prescribe", where);
        int n = cJSON_GetArraySize(pr);
        if (n == 0) return fail(c, w, "must not be empty");
        obj->prescribe_groups = calloc((size_t)n, sizeof *obj->prescribe_groups);
        if (!obj->prescribe_groups) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
        int k = 0;
        for (const cJSON *it = pr->child; it; it = it->next, ++k) {
            static const char *const gkeys[] = {"pin", "affine", "rotate", "move", NULL};
            char w2[300], w3[320];
            snprintf(w2, sizeof w2, "%s[%d]", w, k);
            if ((st = check_keys(c, it, w2, gkeys)) != SEM_OK) return st;
            sem_scene_prescribe_group *gr = &obj->prescribe_groups[k];
            obj->n_prescribe_groups = k + 1;
            const cJSON *gp = cJSON_GetObjectItemCaseSensitive(it, "pin");
            if (!gp) return fail(c, w2, "needs \"pin\" (which control points follow this motion)");
            snprintf(w3, sizeof w3, "%s.pin", w2);
            if ((st = parse_selection(c, gp, w3, &gr->has_box, gr->box, &gr->has_control_box, gr->control_box,
                                      &gr->parts, &gr->n_parts, &gr->points, &gr->n_points)) != SEM_OK)
                return st;
            if ((st = parse_prescription(c, it, w2, &gr->prescribe)) != SEM_OK) return st;
            if (gr->prescribe.type == SEM_PRESCRIBE_NONE) return fail(c, w2, "needs \"affine\", \"rotate\" or \"move\"");
        }
    } else if (pr) {
        static const char *const pkeys[] = {"affine", "rotate", "move", NULL};
        snprintf(w, sizeof w, "%s.prescribe", where);
        if ((st = check_keys(c, pr, w, pkeys)) != SEM_OK) return st;
        if ((st = parse_prescription(c, pr, w, &obj->prescribe)) != SEM_OK) return st;
    }
    if (obj->prescribe.type != SEM_PRESCRIBE_NONE && !obj->has_pin_box && !obj->has_pin_control_box &&
        obj->n_pin_parts == 0 && obj->n_pin_points == 0) {
        snprintf(w, sizeof w, "%s.prescribe", where);
        return fail(c, w, "moves what is pinned, but the object has no \"pin\"");
    }
    if ((st = get_vec(c, o, "initial_velocity", where, 3, obj->initial_velocity)) != SEM_OK) return st;
    if ((st = get_vec(c, o, "initial_angular_velocity", where, 3, obj->initial_angular_velocity)) != SEM_OK)
        return st;
    const cJSON *g = cJSON_GetObjectItemCaseSensitive(o, "gamma");
    if (g && !cJSON_IsNull(g)) {
        if ((st = get_number(c, o, "gamma", where, &obj->sem.gamma)) != SEM_OK) return st;
        if (!(obj->sem.gamma > 0)) {
            snprintf(w, sizeof w, "%s.gamma", where);
            return fail(c, w, "must be positive");
        }
    }
    const cJSON *pl = find_key(o, "point_loads", where, w);
    if (pl) {
        if (!cJSON_IsArray(pl)) return fail(c, w, "must be an array");
        int n = cJSON_GetArraySize(pl);
        obj->point_loads = calloc((size_t)n + 1, sizeof *obj->point_loads);
        if (!obj->point_loads) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
        int k = 0;
        for (const cJSON *it = pl->child; it; it = it->next, ++k) {
            static const char *const lkeys[] = {"position", "force", NULL};
            char w2[300];
            snprintf(w2, sizeof w2, "%s[%d]", w, k);
            if ((st = check_keys(c, it, w2, lkeys)) != SEM_OK) return st;
            if (!cJSON_GetObjectItemCaseSensitive(it, "position") || !cJSON_GetObjectItemCaseSensitive(it, "force"))
                return fail(c, w2, "needs \"position\" and \"force\"");
            if ((st = get_vec(c, it, "position", w2, 3, obj->point_loads[k].X)) != SEM_OK) return st;
            if ((st = get_vec(c, it, "force", w2, 3, obj->point_loads[k].force)) != SEM_OK) return st;
            obj->n_point_loads = k + 1;
        }
    }
    const cJSON *rl = find_key(o, "region_loads", where, w);
    if (rl) {
        if (!cJSON_IsArray(rl)) return fail(c, w, "must be an array");
        int n = cJSON_GetArraySize(rl);
        obj->region_loads = calloc((size_t)n + 1, sizeof *obj->region_loads);
        if (!obj->region_loads) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
        int k = 0;
        for (const cJSON *it = rl->child; it; it = it->next, ++k) {
            static const char *const lkeys[] = {"box", "force_density", "frequency", "phase", NULL};
            char w2[300], w3[320];
            snprintf(w2, sizeof w2, "%s[%d]", w, k);
            if ((st = check_keys(c, it, w2, lkeys)) != SEM_OK) return st;
            const cJSON *b = cJSON_GetObjectItemCaseSensitive(it, "box");
            if (!b || !cJSON_GetObjectItemCaseSensitive(it, "force_density"))
                return fail(c, w2, "needs \"box\" and \"force_density\"");
            snprintf(w3, sizeof w3, "%s.box", w2);
            if ((st = get_box(c, b, w3, obj->region_loads[k].box)) != SEM_OK) return st;
            if ((st = get_vec(c, it, "force_density", w2, 3, obj->region_loads[k].force_density)) != SEM_OK)
                return st;
            if ((st = get_number(c, it, "frequency", w2, &obj->region_loads[k].frequency)) != SEM_OK) return st;
            if ((st = get_number(c, it, "phase", w2, &obj->region_loads[k].phase)) != SEM_OK) return st;
            if (obj->region_loads[k].frequency < 0) return fail(c, w2, "frequency must be >= 0");
            obj->n_region_loads = k + 1;
        }
    }
    return SEM_OK;
}

/* "contact": the world's contact settings (sem/contact.h). */
static sem_status parse_contact(ctx *c, const cJSON *root, sem_contact_def *def)
{
    const cJSON *o = cJSON_GetObjectItemCaseSensitive(root, "contact");
    if (!o) return SEM_OK;
    static const char *const keys[] = {"enabled", "stiffness", "thickness", "self", "friction_velocity",
                                       "resolution", "model", NULL};
    const char *w = "contact";
    sem_status st = check_keys(c, o, w, keys);
    if (st != SEM_OK) return st;
    static const char *const models[] = {"penalty", "barrier", NULL};
    static const int model_values[] = {SEM_CONTACT_PENALTY, SEM_CONTACT_BARRIER};
    int model = (int)def->model;
    if ((st = get_choice(c, o, "model", w, models, model_values, &model)) != SEM_OK) return st;
    def->model = (sem_contact_model)model;
    int enabled = 1;
    if ((st = get_bool(c, o, "enabled", w, &enabled)) != SEM_OK) return st;
    def->disabled = !enabled;
    const cJSON *self = cJSON_GetObjectItemCaseSensitive(o, "self");
    if (self && !cJSON_IsNull(self)) { /* null or absent: the default (on wherever contact is) */
        int on = 0;
        if ((st = get_bool(c, o, "self", w, &on)) != SEM_OK) return st;
        def->self = on ? 1 : -1;
    }
    static const char *const positive[] = {"stiffness", "thickness", "friction_velocity", NULL};
    double *values[] = {&def->stiffness, &def->thickness, &def->friction_velocity};
    for (int k = 0; positive[k]; ++k) {
        const cJSON *v = cJSON_GetObjectItemCaseSensitive(o, positive[k]);
        if (!v || cJSON_IsNull(v)) continue; /* null: the default */
        if ((st = get_number(c, o, positive[k], w, values[k])) != SEM_OK) return st;
        if (!(*values[k] > 0)) {
            char wk[64];
            snprintf(wk, sizeof wk, "contact.%s", positive[k]);
            return fail(c, wk, "must be positive or null (got %g)", *values[k]);
        }
    }
    const cJSON *r = cJSON_GetObjectItemCaseSensitive(o, "resolution");
    if (r && !cJSON_IsNull(r)) {
        if ((st = get_int(c, o, "resolution", w, &def->resolution)) != SEM_OK) return st;
        if (def->resolution < 1 || def->resolution > 64)
            return fail(c, "contact.resolution", "must be in 1..64 or null (got %d)", def->resolution);
    }
    return SEM_OK;
}

/* colliders[i]: a plane, a model file or a primitive, with a friction coefficient. */
static sem_status parse_collider(ctx *c, const cJSON *o, int index, const char *base_dir,
                                 sem_scene_collider *col)
{
    static const char *const keys[] = {"plane", "model", "primitive", "units", "transform", "friction", NULL};
    char where[64], w[256];
    snprintf(where, sizeof where, "colliders[%d]", index);
    sem_status st = check_keys(c, o, where, keys);
    if (st != SEM_OK) return st;
    col->friction = SEM_DEFAULT_FRICTION;
    if ((st = get_number(c, o, "friction", where, &col->friction)) != SEM_OK) return st;
    if (!(col->friction >= 0)) {
        snprintf(w, sizeof w, "%s.friction", where);
        return fail(c, w, "must be >= 0 (got %g)", col->friction);
    }
    const cJSON *plane = cJSON_GetObjectItemCaseSensitive(o, "plane");
    int shapes = !!plane + !!cJSON_GetObjectItemCaseSensitive(o, "model") +
                 !!cJSON_GetObjectItemCaseSensitive(o, "primitive");
    if (shapes != 1) return fail(c, where, "needs exactly one of \"plane\", \"model\" or \"primitive\"");
    if (plane) {
        static const char *const pkeys[] = {"point", "normal", NULL};
        snprintf(w, sizeof w, "%s.plane", where);
        if ((st = check_keys(c, plane, w, pkeys)) != SEM_OK) return st;
        if (cJSON_GetObjectItemCaseSensitive(o, "transform") || cJSON_GetObjectItemCaseSensitive(o, "units"))
            return fail(c, where, "a plane takes no \"transform\" or \"units\" (give its point and normal)");
        col->is_plane = 1;
        col->normal[2] = 1;
        if ((st = get_vec(c, plane, "point", w, 3, col->point)) != SEM_OK) return st;
        if ((st = get_vec(c, plane, "normal", w, 3, col->normal)) != SEM_OK) return st;
        double n2 = col->normal[0] * col->normal[0] + col->normal[1] * col->normal[1] + col->normal[2] * col->normal[2];
        if (!(n2 > 0) || !isfinite(n2)) {
            snprintf(w, sizeof w, "%s.plane.normal", where);
            return fail(c, w, "must be non-zero");
        }
        return SEM_OK;
    }
    return parse_shape(c, o, where, base_dir, &col->shape);
}

static sem_status parse_colliders(ctx *c, const cJSON *root, const char *base_dir, sem_scene *s)
{
    const cJSON *cols = cJSON_GetObjectItemCaseSensitive(root, "colliders");
    if (!cols) return SEM_OK;
    if (!cJSON_IsArray(cols)) return fail(c, "colliders", "must be an array of colliders");
    int n = cJSON_GetArraySize(cols);
    s->colliders = calloc((size_t)n + 1, sizeof *s->colliders);
    if (!s->colliders) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
    int k = 0;
    for (const cJSON *it = cols->child; it; it = it->next, ++k) {
        s->n_colliders = k + 1;
        sem_status st = parse_collider(c, it, k, base_dir, &s->colliders[k]);
        if (st != SEM_OK) return st;
    }
    return SEM_OK;
}

static sem_status parse_world(ctx *c, const cJSON *root, sem_scene *s)
{
    sem_status st;
    if ((st = get_vec(c, root, "gravity", "scene", 3, s->world.gravity)) != SEM_OK) return st;
    const cJSON *in = cJSON_GetObjectItemCaseSensitive(root, "integrator");
    if (in) {
        static const char *const keys[] = {"type", "dt", "damping", "tolerance", "max_iterations",
                                           "solver", "accept_unconverged", NULL};
        const char *w = "integrator";
        if ((st = check_keys(c, in, w, keys)) != SEM_OK) return st;
        const cJSON *t = cJSON_GetObjectItemCaseSensitive(in, "type");
        if (t) {
            if (!cJSON_IsString(t)) return fail(c, "integrator.type", "must be a string");
            if (!strcmp(t->valuestring, "linearly_implicit_euler"))
                s->world.integrator = SEM_LINEARLY_IMPLICIT_EULER;
            else if (!strcmp(t->valuestring, "implicit_euler"))
                s->world.integrator = SEM_IMPLICIT_EULER;
            else if (!strcmp(t->valuestring, "static"))
                s->world.integrator = SEM_STATIC;
            else
                return fail(c, "integrator.type",
                            "unknown integrator \"%s\" (use linearly_implicit_euler, implicit_euler "
                            "or static)",
                            t->valuestring);
        }
        if ((st = get_number(c, in, "dt", w, &s->world.dt)) != SEM_OK) return st;
        if (!(s->world.dt > 0)) return fail(c, "integrator.dt", "must be positive (got %g)", s->world.dt);
        const cJSON *d = cJSON_GetObjectItemCaseSensitive(in, "damping");
        if (d) {
            static const char *const dkeys[] = {"mass", "stiffness", NULL};
            if ((st = check_keys(c, d, "integrator.damping", dkeys)) != SEM_OK) return st;
            if ((st = get_number(c, d, "mass", "integrator.damping", &s->world.rayleigh_mass)) != SEM_OK) return st;
            if ((st = get_number(c, d, "stiffness", "integrator.damping", &s->world.rayleigh_stiffness)) != SEM_OK)
                return st;
            if (s->world.rayleigh_mass < 0 || s->world.rayleigh_stiffness < 0)
                return fail(c, "integrator.damping", "coefficients must be >= 0");
        }
        if ((st = get_number(c, in, "tolerance", w, &s->world.newton_tolerance)) != SEM_OK) return st;
        if (!(s->world.newton_tolerance > 0)) return fail(c, "integrator.tolerance", "must be positive");
        if ((st = get_int(c, in, "max_iterations", w, &s->world.newton_max_iterations)) != SEM_OK) return st;
        const cJSON *au = cJSON_GetObjectItemCaseSensitive(in, "accept_unconverged");
        if (au) {
            if (!cJSON_IsBool(au)) return fail(c, "integrator.accept_unconverged", "must be true or false");
            s->world.accept_unconverged = cJSON_IsTrue(au);
        }
        if (s->world.newton_max_iterations < 1) return fail(c, "integrator.max_iterations", "must be >= 1");
        const cJSON *so = cJSON_GetObjectItemCaseSensitive(in, "solver");
        if (so) {
            if (!cJSON_IsString(so)) return fail(c, "integrator.solver", "must be a string");
            if (!strcmp(so->valuestring, "auto")) s->world.solver = SEM_SOLVER_AUTO;
            else if (!strcmp(so->valuestring, "sparse")) s->world.solver = SEM_SOLVER_SPARSE;
            else if (!strcmp(so->valuestring, "dense")) s->world.solver = SEM_SOLVER_DENSE;
            else if (!strcmp(so->valuestring, "structured")) s->world.solver = SEM_SOLVER_STRUCTURED;
            else return fail(c, "integrator.solver", "must be auto, structured, sparse or dense");
        }
    }
    if ((st = get_int(c, root, "frames", "scene", &s->frames)) != SEM_OK) return st;
    if (s->frames < 0) return fail(c, "frames", "must be >= 0");
    if (s->frames > SEM_MAX_FRAMES)
        return fail(c, "frames", "%d is too large (at most %d)", s->frames, SEM_MAX_FRAMES);
    if ((st = get_int(c, root, "steps_per_frame", "scene", &s->steps_per_frame)) != SEM_OK) return st;
    if (s->steps_per_frame < 1) return fail(c, "steps_per_frame", "must be >= 1");
    if ((st = get_int(c, root, "threads", "scene", &s->world.threads)) != SEM_OK) return st;
    if (s->world.threads < 0 || s->world.threads > 4096) return fail(c, "threads", "must be in 0..4096 (0: all cores)");
    const cJSON *desc = cJSON_GetObjectItemCaseSensitive(root, "description");
    if (desc && !cJSON_IsString(desc)) return fail(c, "description", "must be a string");
    const cJSON *out = cJSON_GetObjectItemCaseSensitive(root, "output");
    if (out) {
        static const char *const keys[] = {"dir", "iges", "obj", "mesh", "usd", "glb", "mesh_resolution", NULL};
        if ((st = check_keys(c, out, "output", keys)) != SEM_OK) return st;
        const cJSON *d = cJSON_GetObjectItemCaseSensitive(out, "dir");
        if (d) {
            if (!cJSON_IsString(d) || !d->valuestring[0]) return fail(c, "output.dir", "must be a folder path");
            snprintf(s->output_dir, sizeof s->output_dir, "%s", d->valuestring);
        }
        if ((st = get_bool(c, out, "iges", "output", &s->write_iges)) != SEM_OK) return st;
        if ((st = get_bool(c, out, "obj", "output", &s->write_obj)) != SEM_OK) return st;
        if ((st = get_bool(c, out, "mesh", "output", &s->write_mesh)) != SEM_OK) return st;
        if ((st = get_bool(c, out, "usd", "output", &s->write_usd)) != SEM_OK) return st;
        if ((st = get_bool(c, out, "glb", "output", &s->write_glb)) != SEM_OK) return st;
        if ((st = get_int(c, out, "mesh_resolution", "output", &s->mesh_resolution)) != SEM_OK) return st;
        if (s->mesh_resolution < 1 || s->mesh_resolution > 64) return fail(c, "output.mesh_resolution", "must be in 1..64");
    }
    return SEM_OK;
}

static void object_free(sem_scene_object *o)
{
    SEM_FREE_ALL(o->part_materials, o->pin_parts, o->pin_points, o->point_loads, o->region_loads);
    for (int k = 0; k < o->n_prescribe_groups; ++k) {
        free(o->prescribe_groups[k].parts);
        free(o->prescribe_groups[k].points);
    }
    free(o->prescribe_groups);
}

void sem_scene_destroy(sem_scene *s)
{
    if (!s) return;
    for (int i = 0; i < s->n_objects; ++i) object_free(&s->objects[i]);
    free(s->objects);
    free(s->colliders);
    free(s);
}

/* Line (from 1) of position `at` in text. */
static int line_at(const char *text, const char *at)
{
    int line = 1;
    if (at)
        for (const char *p = text; p < at && *p; ++p) line += *p == '\n';
    return line;
}

static int compare_keys(const void *a, const void *b)
{
    const cJSON *x = *(const cJSON *const *)a, *y = *(const cJSON *const *)b;
    return strcmp(x->string, y->string);
}

/* JSON allows an object to repeat a key, and cJSON keeps both while lookups see only the
 * first: {"frames": 10, "frames": 1000} would silently run 10 frames. Every object of the
 * document is checked (sorted keys, so a part_materials object with many names costs
 * n log n); `where` is the path of `v` and is extended in place while descending. */
static sem_status check_duplicate_keys(ctx *c, const cJSON *v, char *where, size_t size)
{
    size_t len = strlen(where);
    if (cJSON_IsObject(v)) {
        int n = 0;
        for (const cJSON *it = v->child; it; it = it->next) ++n;
        if (n > 1) {
            const cJSON **keys = malloc((size_t)n * sizeof *keys);
            if (!keys) return sem_error_set(c->err, SEM_ERR_NOMEM, "out of memory");
            int k = 0;
            for (const cJSON *it = v->child; it; it = it->next) keys[k++] = it;
            qsort(keys, (size_t)n, sizeof *keys, compare_keys);
            for (k = 1; k < n; ++k)
                if (strcmp(keys[k]->string, keys[k - 1]->string) == 0) {
                    char key[128];
                    snprintf(key, sizeof key, "%s", keys[k]->string);
                    free(keys);
                    return fail(c, where, "key \"%s\" appears more than once", key);
                }
            free(keys);
        }
        for (const cJSON *it = v->child; it; it = it->next) {
            snprintf(where + len, size - len, ".%s", it->string);
            sem_status st = check_duplicate_keys(c, it, where, size);
            where[len] = '\0';
            if (st != SEM_OK) return st;
        }
    } else if (cJSON_IsArray(v)) {
        int k = 0;
        for (const cJSON *it = v->child; it; it = it->next, ++k) {
            snprintf(where + len, size - len, "[%d]", k);
            sem_status st = check_duplicate_keys(c, it, where, size);
            where[len] = '\0';
            if (st != SEM_OK) return st;
        }
    }
    return SEM_OK;
}

sem_status sem_scene_parse(const char *json, const char *name, const char *base_dir,
                           sem_scene **out, sem_error *err)
{
    *out = NULL;
    ctx c = {name, err};
    const char *end = NULL;
    cJSON *root = cJSON_ParseWithOpts(json, &end, 0);
    if (!root) {
        const char *e = cJSON_GetErrorPtr();
        return sem_error_set(err, SEM_ERR_PARSE, "%s:%d: not valid JSON", name, line_at(json, e));
    }
    while (end && (*end == ' ' || *end == '\t' || *end == '\n' || *end == '\r')) ++end;
    if (end && *end) {
        cJSON_Delete(root);
        return sem_error_set(err, SEM_ERR_PARSE, "%s:%d: not valid JSON: text after the end of "
                                                 "the scene object", name, line_at(json, end));
    }
    char where[512];
    snprintf(where, sizeof where, "scene");
    sem_status dst = check_duplicate_keys(&c, root, where, sizeof where);
    if (dst != SEM_OK) {
        cJSON_Delete(root);
        return dst;
    }
    sem_scene *s = calloc(1, sizeof *s);
    if (!s) {
        cJSON_Delete(root);
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    s->world = sem_default_world_def();
    s->frames = 120;
    s->steps_per_frame = 1;
    snprintf(s->output_dir, sizeof s->output_dir, "out");
    s->write_iges = 1;
    s->write_obj = 0;
    s->write_mesh = 1;
    s->write_usd = 1;
    s->write_glb = 1;
    s->mesh_resolution = 6;
    static const char *const keys[] = {"objects", "gravity", "integrator", "frames",
                                       "steps_per_frame", "output", "threads", "description",
                                       "colliders", "contact", NULL};
    sem_status st = check_keys(&c, root, "scene", keys);
    if (st == SEM_OK) st = parse_world(&c, root, s);
    if (st == SEM_OK) st = parse_contact(&c, root, &s->world.contact);
    if (st == SEM_OK && s->world.contact.model == SEM_CONTACT_BARRIER &&
        s->world.integrator == SEM_LINEARLY_IMPLICIT_EULER)
        st = fail(&c, "contact.model",
                  "\"barrier\" needs integrator.type \"implicit_euler\" or \"static\" (its collision check bounds "
                  "Newton's steps; the linearly implicit step takes one unchecked step)");
    if (st == SEM_OK) st = parse_colliders(&c, root, base_dir, s);
    const cJSON *objs = cJSON_GetObjectItemCaseSensitive(root, "objects");
    if (st == SEM_OK && (!cJSON_IsArray(objs) || cJSON_GetArraySize(objs) == 0))
        st = fail(&c, "objects", "must be a non-empty array of objects");
    if (st == SEM_OK) {
        int n = cJSON_GetArraySize(objs);
        s->objects = calloc((size_t)n, sizeof *s->objects);
        if (!s->objects) st = sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
        int k = 0;
        for (const cJSON *it = objs->child; st == SEM_OK && it; it = it->next, ++k) {
            s->n_objects = k + 1;
            st = parse_object(&c, it, k, base_dir, &s->objects[k]);
        }
    }
    cJSON_Delete(root);
    if (st != SEM_OK) {
        sem_scene_destroy(s);
        return st;
    }
    *out = s;
    return SEM_OK;
}

sem_status sem_scene_load(const char *path, sem_scene **out, sem_error *err)
{
    *out = NULL;
    char *buf = NULL;
    size_t got = 0;
    sem_status rst = sem_read_file(path, SEM_MAX_SCENE_FILE_BYTES, "SEM_MAX_SCENE_FILE_BYTES", &buf,
                                   &got, err);
    if (rst != SEM_OK) return rst;
    if (strlen(buf) != got) {
        int line = line_at(buf, buf + strlen(buf));
        free(buf);
        return sem_error_set(err, SEM_ERR_PARSE, "%s:%d: not valid JSON: NUL byte in the file",
                             path, line);
    }
    char base[4096];
    snprintf(base, sizeof base, "%s", path);
    char *slash = strrchr(base, '/');
    if (slash == base)
        base[1] = '\0'; /* scene in "/" */
    else if (slash)
        *slash = '\0';
    else
        base[0] = '\0'; /* scene in the working folder: model paths are used as written */
    sem_status st = sem_scene_parse(buf, path, base, out, err);
    free(buf);
    if (st == SEM_OK) snprintf((*out)->path, sizeof (*out)->path, "%s", path);
    return st;
}

const char *sem_scene_default_json(void)
{
    /* A soft rubber beam (2 m x 0.4 m x 0.4 m, 4 sections) clamped at x = 0, released
     * straight and swinging down under gravity. */
    return "{\n"
           "  \"description\": \"rubber beam clamped at x = 0 swinging under gravity\",\n"
           "  \"objects\": [{\n"
           "    \"primitive\": {\"type\": \"beam\", \"sections\": 4, \"length\": 2.0, \"width\": 0.4, \"height\": 0.4},\n"
           "    \"material\": {\"type\": \"neohookean\", \"density\": 1100, \"youngs_modulus\": 2e6, \"poisson_ratio\": 0.45},\n"
           "    \"pin\": {\"box\": [[-0.01, -1, -1], [0.01, 1, 1]]}\n"
           "  }],\n"
           "  \"gravity\": [0, 0, -9.81],\n"
           "  \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01},\n"
           "  \"frames\": 100,\n"
           "  \"steps_per_frame\": 2,\n"
           "  \"output\": {\"dir\": \"out\"}\n"
           "}\n";
}
