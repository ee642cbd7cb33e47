/*
 * iges_write.c - a model as an IGES 5.3 file (ASCII, fixed 80-column form).
 *
 * Layout: Start (S), Global (G), Directory Entry (D, two lines per entity), Parameter
 * Data (P) and Terminate (T) sections, each line exactly 80 characters with its section
 * letter in column 73 and its sequence number in columns 74-80.
 *
 * Entities per part (all references point backwards, so one pass writes them):
 *   - untrimmed part (no outer loop, no hole): 128 rational B-spline surface;
 *   - trimmed part: 128 (physically dependent), then per loop its curves as 126 in the
 *     (u,v) parameter space of the surface (2D-parametric use flag 05), a 102 composite
 *     when the loop has several curves, a 142 curve on a parametric surface, and last a
 *     144 trimmed surface pointing at the 128 and the 142s (N1 = 0 when only holes trim
 *     the domain rectangle).
 *   - the part name, when there is one, as a 406 form 15 name property referenced by the
 *     independent entity, and its first 8 characters as the DE entity label.
 *
 * 142 CPTR choice: the model-space image C = S o B of a trim curve is not a NURBS of
 * reasonable degree, and approximating it would add a second, inexact copy of the loop.
 * We write CPTR = 0 with PREF = 1 ("S o B preferred"), as many CAD exporters do for
 * parameter-space trims; every reader of 144 must evaluate B on S anyway.
 *
 * Numbers round-trip exactly: reals are printed with the shortest of %.15g..%.17g that
 * strtod reads back to the same double, always with a decimal point (io/real_format.h).
 * P-section data uses columns 1-64 (the DE pointer is in 66-72); parameters are split
 * between lines only at delimiters, never inside a number or string.
 */
#include "sem/model.h"
#include "sem/version.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>

#include "io/atomic_file.h"
#include "io/real_format.h"

#define P_DATA_COLUMNS 64
#define G_DATA_COLUMNS 72

/* Status numbers (blank, subordinate, entity use, hierarchy) of the DE section. */
#define STATUS_INDEPENDENT "00000000"
#define STATUS_DEPENDENT "00010000"
#define STATUS_DEPENDENT_PARAMETRIC "00010500" /* curves in (u,v) space */
#define STATUS_DEPENDENT_DEFINITION "00010300" /* the name property */

typedef struct iges_entity {
    int type, form;
    char status[9];
    char label[9];
    int color;
    int param_start; /* first P line */
    int param_lines;
} iges_entity;

/* Growing text of fixed 80-column lines (plus '\n'). */
typedef struct line_buffer {
    char *text;
    size_t len, cap;
    int lines;
} line_buffer;

typedef struct iges_writer {
    iges_entity *entities;
    int n_entities, cap_entities;
    line_buffer global, params;
    /* the line being filled and the token held back until we know its delimiter */
    char line[G_DATA_COLUMNS + 1];
    int line_len;
    char pending[96];
    int has_pending;
    int width;          /* data columns of the section being filled */
    char section;       /* 'G' or 'P' */
    int current_de;     /* DE number of the entity whose parameters are being written */
    int failed;         /* out of memory */
} iges_writer;

static int buffer_put_line(line_buffer *b, const char *line80)
{
    if (b->len + 82 > b->cap) {
        size_t nc = b->cap ? 2 * b->cap : 8192;
        while (nc < b->len + 82) nc *= 2;
        char *t = realloc(b->text, nc);
        if (!t) return 0;
        b->text = t;
        b->cap = nc;
    }
    memcpy(b->text + b->len, line80, 80);
    b->text[b->len + 80] = '\n';
    b->len += 81;
    b->lines++;
    return 1;
}

static void emit_line(iges_writer *w)
{
    char out[96];
    line_buffer *b = w->section == 'G' ? &w->global : &w->params;
    if (w->section == 'G')
        snprintf(out, sizeof out, "%-72.*sG%7d", w->line_len, w->line, b->lines + 1);
    else
        snprintf(out, sizeof out, "%-64.*s %7dP%7d", w->line_len, w->line, w->current_de,
                 b->lines + 1);
    if (!buffer_put_line(b, out)) w->failed = 1;
    w->line_len = 0;
}

/* Appends the pending token with its delimiter, starting a new line when it would not fit. */
static void flush_pending(iges_writer *w, char delimiter)
{
    if (!w->has_pending) return;
    int n = (int)strlen(w->pending);
    if (w->line_len > 0 && w->line_len + n + 1 > w->width) emit_line(w);
    memcpy(w->line + w->line_len, w->pending, (size_t)n);
    w->line_len += n;
    w->line[w->line_len++] = delimiter;
    w->has_pending = 0;
}

static void put_token(iges_writer *w, const char *token)
{
    flush_pending(w, ',');
    snprintf(w->pending, sizeof w->pending, "%s", token);
    w->has_pending = 1;
}

static void put_int(iges_writer *w, long value)
{
    char t[32];
    snprintf(t, sizeof t, "%ld", value);
    put_token(w, t);
}

static void put_real(iges_writer *w, double value)
{
    char t[40];
    sem_format_iges_real(value, t);
    put_token(w, t);
}

/* Hollerith string nHxxxx; callers keep it short enough for one line. */
static void put_string(iges_writer *w, const char *s)
{
    char t[96];
    size_t n = strlen(s);
    if (n == 0) {
        put_token(w, ""); /* empty field: the default */
        return;
    }
    snprintf(t, sizeof t, "%zuH%s", n, s);
    put_token(w, t);
}

static void end_record(iges_writer *w)
{
    flush_pending(w, ';');
    if (w->line_len > 0) emit_line(w);
}

/* Starts an entity's parameters; returns its DE number (odd, 1-based line of the D section). */
static int begin_entity(iges_writer *w, int type, int form, const char *status, const char *label,
                        int color)
{
    if (w->n_entities == w->cap_entities) {
        int nc = w->cap_entities ? 2 * w->cap_entities : 64;
        iges_entity *e = realloc(w->entities, (size_t)nc * sizeof *e);
        if (!e) {
            w->failed = 1;
            return 0;
        }
        w->entities = e;
        w->cap_entities = nc;
    }
    iges_entity *e = &w->entities[w->n_entities++];
    memset(e, 0, sizeof *e);
    e->type = type;
    e->form = form;
    snprintf(e->status, sizeof e->status, "%s", status);
    snprintf(e->label, sizeof e->label, "%s", label ? label : "");
    e->color = color;
    e->param_start = w->params.lines + 1;
    w->current_de = 2 * w->n_entities - 1;
    w->section = 'P';
    w->width = P_DATA_COLUMNS;
    w->line_len = 0;
    w->has_pending = 0;
    put_int(w, type);
    return w->current_de;
}

/* Ends the parameters, with the optional property pointer (the 406 name) after them. */
static void end_entity(iges_writer *w, int property_de)
{
    if (property_de > 0) {
        put_int(w, 0); /* no associativities */
        put_int(w, 1);
        put_int(w, property_de);
    }
    end_record(w);
    if (w->failed) return;
    iges_entity *e = &w->entities[w->n_entities - 1];
    e->param_lines = w->params.lines + 1 - e->param_start;
}

/* ---- entities ---- */

static int all_equal(const double *x, size_t n)
{
    for (size_t i = 1; i < n; ++i)
        if (x[i] != x[0]) return 0;
    return 1;
}

static int write_name(iges_writer *w, const char *name)
{
    if (!name[0]) return 0;
    /* a Hollerith string may not be split across P lines by every reader: keep the token
     * (nnH + text + delimiter) within one 64-column line */
    char text[64];
    snprintf(text, 61, "%s", name);
    int de = begin_entity(w, 406, 15, STATUS_DEPENDENT_DEFINITION, "", 0);
    put_int(w, 1);
    put_string(w, text);
    end_entity(w, 0);
    return de;
}

static int write_surface(iges_writer *w, const sem_surface *s, const char *status,
                         const char *label, int color, int property_de)
{
    size_t n = (size_t)s->n_u * (size_t)s->n_v;
    int de = begin_entity(w, 128, 0, status, label, color);
    put_int(w, s->n_u - 1);
    put_int(w, s->n_v - 1);
    put_int(w, s->degree_u);
    put_int(w, s->degree_v);
    put_int(w, s->closed_u ? 1 : 0);
    put_int(w, s->closed_v ? 1 : 0);
    put_int(w, all_equal(s->weights, n) ? 1 : 0);
    put_int(w, s->periodic_u ? 1 : 0);
    put_int(w, s->periodic_v ? 1 : 0);
    for (int i = 0; i < s->n_u + s->degree_u + 1; ++i) put_real(w, s->knots_u[i]);
    for (int i = 0; i < s->n_v + s->degree_v + 1; ++i) put_real(w, s->knots_v[i]);
    for (size_t i = 0; i < n; ++i) put_real(w, s->weights[i]);
    for (size_t i = 0; i < 3 * n; ++i) put_real(w, s->ctrl[i]);
    put_real(w, s->u0);
    put_real(w, s->u1);
    put_real(w, s->v0);
    put_real(w, s->v1);
    end_entity(w, property_de);
    return de;
}

/* A trim curve: a planar 126 in the (u,v) plane (normal +z). */
static int write_curve(iges_writer *w, const sem_curve *c, const char *label, int color)
{
    int n = c->n_ctrl;
    const double *first = c->ctrl, *last = c->ctrl + 3 * (n - 1);
    int closed = first[0] == last[0] && first[1] == last[1] && first[2] == last[2];
    int de = begin_entity(w, 126, 0, STATUS_DEPENDENT_PARAMETRIC, label, color);
    put_int(w, n - 1);
    put_int(w, c->degree);
    put_int(w, 1); /* planar */
    put_int(w, closed);
    put_int(w, all_equal(c->weights, (size_t)n) ? 1 : 0);
    put_int(w, 0); /* not periodic */
    for (int i = 0; i < n + c->degree + 1; ++i) put_real(w, c->knots[i]);
    for (int i = 0; i < n; ++i) put_real(w, c->weights[i]);
    for (int i = 0; i < 3 * n; ++i) put_real(w, c->ctrl[i]);
    put_real(w, c->t0);
    put_real(w, c->t1);
    put_real(w, 0.0);
    put_real(w, 0.0);
    put_real(w, 1.0);
    end_entity(w, 0);
    return de;
}

/* One loop: its curves (126 or 102 of 126s) and the 142 that puts them on the surface. */
static int write_loop(iges_writer *w, const sem_trim_loop *loop, int surface_de, const char *label,
                      int color)
{
    if (loop->n_curves < 1) return 0; /* rejected by validate_model before */
    int *curve_de = calloc((size_t)loop->n_curves, sizeof *curve_de);
    if (!curve_de) {
        w->failed = 1;
        return 0;
    }
    for (int i = 0; i < loop->n_curves; ++i)
        curve_de[i] = write_curve(w, &loop->curves[i], label, color);
    int boundary_de = curve_de[0];
    if (loop->n_curves > 1) {
        boundary_de = begin_entity(w, 102, 0, STATUS_DEPENDENT_PARAMETRIC, label, color);
        put_int(w, loop->n_curves);
        for (int i = 0; i < loop->n_curves; ++i) put_int(w, curve_de[i]);
        end_entity(w, 0);
    }
    free(curve_de);
    int de = begin_entity(w, 142, 0, STATUS_DEPENDENT, label, color);
    put_int(w, 0);            /* CRTN: unspecified */
    put_int(w, surface_de);   /* SPTR */
    put_int(w, boundary_de);  /* BPTR */
    put_int(w, 0);            /* CPTR: no model-space copy (see the top of this file) */
    put_int(w, 1);            /* PREF: S o B preferred */
    end_entity(w, 0);
    return de;
}

static sem_status write_part(iges_writer *w, const sem_part *p)
{
    char label[9];
    size_t label_len = strnlen(p->name, 8);
    memcpy(label, p->name, label_len);
    label[label_len] = '\0';
    for (char *c = label; *c; ++c)
        if (!isprint((unsigned char)*c)) *c = '_';
    int color = p->color >= 1 && p->color <= 8 ? p->color : 0;
    int name_de = write_name(w, p->name);
    int trimmed = p->has_outer || p->n_holes > 0;
    if (!trimmed) {
        write_surface(w, &p->surface, STATUS_INDEPENDENT, label, color, name_de);
        return SEM_OK;
    }
    int surface_de = write_surface(w, &p->surface, STATUS_DEPENDENT, label, color, 0);
    int outer_de = p->has_outer ? write_loop(w, &p->outer, surface_de, label, color) : 0;
    int *hole_de = NULL;
    if (p->n_holes > 0) {
        hole_de = malloc((size_t)p->n_holes * sizeof *hole_de);
        if (!hole_de) return SEM_ERR_NOMEM;
        for (int i = 0; i < p->n_holes; ++i)
            hole_de[i] = write_loop(w, &p->holes[i], surface_de, label, color);
    }
    begin_entity(w, 144, 0, STATUS_INDEPENDENT, label, color);
    put_int(w, surface_de);
    put_int(w, p->has_outer ? 1 : 0);
    put_int(w, p->n_holes);
    put_int(w, outer_de);
    for (int i = 0; i < p->n_holes; ++i) put_int(w, hole_de[i]);
    end_entity(w, name_de);
    free(hole_de);
    return SEM_OK;
}

/* ---- Global section ---- */

typedef struct unit_entry {
    const char *name;
    int flag;
    double meters;
} unit_entry;

static const unit_entry UNITS[] = {
    {"IN", 1, 0.0254},    {"INCH", 1, 0.0254}, {"MM", 2, 0.001},  {"FT", 4, 0.3048},
    {"MI", 5, 1609.344},  {"M", 6, 1.0},       {"KM", 7, 1000.0}, {"MIL", 8, 2.54e-5},
    {"UM", 9, 1e-6},      {"CM", 10, 0.01},    {"UIN", 11, 2.54e-8},
};

/* Unit flag and name (IGES 5.3 Global parameters 14 and 15). */
static void units_of(const sem_model *m, int *flag, char name[16])
{
    for (size_t i = 0; i < sizeof UNITS / sizeof UNITS[0]; ++i) {
        if (m->units[0] && strcasecmp(m->units, UNITS[i].name) == 0) {
            *flag = UNITS[i].flag;
            snprintf(name, 16, "%s", UNITS[i].flag == 1 ? "INCH" : UNITS[i].name);
            return;
        }
    }
    if (m->units[0]) {
        *flag = 3; /* "units named in parameter 15" */
        snprintf(name, 16, "%s", m->units);
        for (char *c = name; *c; ++c) *c = (char)toupper((unsigned char)*c);
        return;
    }
    for (size_t i = 0; i < sizeof UNITS / sizeof UNITS[0]; ++i) {
        if (fabs(m->unit_to_meter - UNITS[i].meters) <= 1e-12 * UNITS[i].meters) {
            *flag = UNITS[i].flag;
            snprintf(name, 16, "%s", UNITS[i].flag == 1 ? "INCH" : UNITS[i].name);
            return;
        }
    }
    *flag = 6;
    snprintf(name, 16, "M");
}

static double max_coordinate(const sem_model *m)
{
    double mx = 0.0;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_surface *s = &m->parts[i].surface;
        size_t n = 3 * (size_t)s->n_u * (size_t)s->n_v;
        for (size_t k = 0; k < n; ++k) mx = fmax(mx, fabs(s->ctrl[k]));
    }
    return mx;
}

static void write_global(iges_writer *w, const sem_model *m, const char *path)
{
    const char *slash = strrchr(path, '/');
    char file[48], product[48], date[20];
    snprintf(file, sizeof file, "%s", slash ? slash + 1 : path);
    snprintf(product, sizeof product, "%s", file);
    char *dot = strrchr(product, '.');
    if (dot && dot != product) *dot = '\0';
    /* SOURCE_DATE_EPOCH (seconds since 1970, the reproducible-builds convention) replaces
     * the clock, so that the same model gives the same bytes; a value that is not a plain
     * number of seconds in years 1970..9999 is ignored */
    time_t now = time(NULL);
    const char *epoch = getenv("SOURCE_DATE_EPOCH");
    if (epoch && *epoch) {
        char *end;
        errno = 0;
        long long v = strtoll(epoch, &end, 10);
        if (errno == 0 && *end == '\0' && v >= 0 && v <= 253402300799LL) now = (time_t)v;
    }
    struct tm tm_utc;
    if (!gmtime_r(&now, &tm_utc)) memset(&tm_utc, 0, sizeof tm_utc);
    if (strftime(date, sizeof date, "%Y%m%d.%H%M%S", &tm_utc) == 0)
        snprintf(date, sizeof date, "19700101.000000");
    int unit_flag;
    char unit_name[16];
    units_of(m, &unit_flag, unit_name);
    double mx = max_coordinate(m);
    double resolution = mx > 0 ? 1e-5 * mx : 1e-6;

    w->section = 'G';
    w->width = G_DATA_COLUMNS;
    w->line_len = 0;
    w->has_pending = 0;
    put_token(w, "1H,");             /* 1 parameter delimiter */
    put_token(w, "1H;");             /* 2 record delimiter */
    put_string(w, product);          /* 3 product id (sender) */
    put_string(w, file);             /* 4 file name */
    put_string(w, "sem");            /* 5 native system */
    put_string(w, "sem IGES writer " SEM_VERSION_STRING); /* 6 preprocessor version */
    put_int(w, 32);                  /* 7 integer bits */
    put_int(w, 38);                  /* 8 single precision max power of ten */
    put_int(w, 6);                   /* 9 single precision digits */
    put_int(w, 308);                 /* 10 double precision max power of ten */
    put_int(w, 15);                  /* 11 double precision digits */
    put_string(w, product);          /* 12 product id (receiver) */
    put_real(w, 1.0);                /* 13 model space scale */
    put_int(w, unit_flag);           /* 14 unit flag */
    put_string(w, unit_name);        /* 15 units */
    put_int(w, 1);                   /* 16 line weight gradations */
    put_real(w, 1.0);                /* 17 maximum line width */
    put_string(w, date);             /* 18 date of file generation */
    put_real(w, resolution);         /* 19 minimum resolution */
    put_real(w, mx);                 /* 20 maximum coordinate */
    put_string(w, "sem");            /* 21 author */
    put_token(w, "");                /* 22 organisation */
    put_int(w, 11);                  /* 23 IGES version: 5.3 */
    put_int(w, 0);                   /* 24 drafting standard: none */
    put_string(w, date);             /* 25 date of model creation */
    end_record(w);
}

/* ---- file ---- */

static sem_status validate_model(const sem_model *m, sem_error *err)
{
    char msg[sizeof err->message];
    sem_error e;
    for (int i = 0; i < m->n_parts; ++i) {
        const sem_part *p = &m->parts[i];
        if (sem_surface_validate(&p->surface, &e) != SEM_OK) {
            snprintf(msg, sizeof msg, "%s", e.message);
            return sem_error_set(err, SEM_ERR_INVALID, "part %d '%s': %s", i, p->name, msg);
        }
        int n_loops = (p->has_outer ? 1 : 0) + p->n_holes;
        for (int l = 0; l < n_loops; ++l) {
            const sem_trim_loop *loop = p->has_outer && l == 0 ? &p->outer
                                                               : &p->holes[l - (p->has_outer ? 1 : 0)];
            if (loop->n_curves < 1)
                return sem_error_set(err, SEM_ERR_INVALID, "part %d '%s': trim loop %d is empty",
                                     i, p->name, l);
            for (int c = 0; c < loop->n_curves; ++c) {
                if (sem_curve_validate(&loop->curves[c], &e) != SEM_OK) {
                    snprintf(msg, sizeof msg, "%s", e.message);
                    return sem_error_set(err, SEM_ERR_INVALID,
                                         "part %d '%s': trim loop %d curve %d: %s", i, p->name,
                                         l, c, msg);
                }
            }
        }
    }
    return SEM_OK;
}

static void writer_free(iges_writer *w)
{
    free(w->entities);
    free(w->global.text);
    free(w->params.text);
}

static void write_directory(FILE *f, const iges_writer *w)
{
    for (int i = 0; i < w->n_entities; ++i) {
        const iges_entity *e = &w->entities[i];
        fprintf(f, "%8d%8d%8d%8d%8d%8d%8d%8d%8sD%7d\n", e->type, e->param_start, 0, 0, 0, 0, 0, 0,
                e->status, 2 * i + 1);
        fprintf(f, "%8d%8d%8d%8d%8d%8s%8s%8s%8dD%7d\n", e->type, 0, e->color, e->param_lines,
                e->form, "", "", e->label, 0, 2 * i + 2);
    }
}

sem_status sem_iges_write(const sem_model *model, const char *path, sem_error *err)
{
    if (!model || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_iges_write: NULL argument");
    sem_status st = validate_model(model, err);
    if (st != SEM_OK) return st;

    iges_writer w;
    memset(&w, 0, sizeof w);
    write_global(&w, model, path);
    for (int i = 0; i < model->n_parts && !w.failed; ++i) {
        if (write_part(&w, &model->parts[i]) != SEM_OK) w.failed = 1;
    }
    if (w.failed) {
        writer_free(&w);
        return sem_error_set(err, SEM_ERR_NOMEM, "%s: out of memory writing IGES", path);
    }

    sem_atomic_file file;
    st = sem_atomic_open(&file, path, err);
    if (st != SEM_OK) {
        writer_free(&w);
        return st;
    }
    char start[96];
    snprintf(start, sizeof start, "sem: %d NURBS part%s (IGES 128/144)", model->n_parts,
             model->n_parts == 1 ? "" : "s");
    fprintf(file.fp, "%-72sS%7d\n", start, 1);
    if (w.global.len) fwrite(w.global.text, 1, w.global.len, file.fp);
    write_directory(file.fp, &w);
    if (w.params.len) fwrite(w.params.text, 1, w.params.len, file.fp);
    char terminate[96];
    snprintf(terminate, sizeof terminate, "S%07dG%07dD%07dP%07d", 1, w.global.lines,
             2 * w.n_entities, w.params.lines);
    fprintf(file.fp, "%-72sT%7d\n", terminate, 1);
    writer_free(&w);
    return sem_atomic_commit(&file, err);
}
