/*
 * iges_read.c - IGES 5.3 reader: every surface the file describes becomes one NURBS part.
 *
 * Design. The file is read in one linear pass into lines, classified by the section letter
 * in column 73 (Start, Global, Directory Entry, Parameter Data, Terminate). The Global
 * section gives the delimiters and units. The Parameter section is concatenated into one
 * text, each line's columns 1-64 padded to exactly 64 characters, so that the file line of
 * any parameter is first_line + offset / 64; every entity's parameters are tokenised once
 * (Hollerith strings may hold delimiters and span lines). Entities are then converted on
 * demand, recursively, with a depth limit, from the top-level entities in directory order:
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
 * Robustness. Any count read from the file is checked against the number of parameters the
 * entity actually has before anything is allocated, so one entity cannot ask for more
 * than the file holds. Sharing is what multiplies: a subfigure definition (308) may list
 * the same member many times and be instanced by 408s inside other definitions, and a
 * composite curve (102) may repeat one member, so a few kilobytes can describe 10^8
 * surfaces. The busy flags only stop cycles; what bounds the work is a budget
 * (sem/limits.h): every entity conversion counts against SEM_MAX_IGES_EXPANSION, every
 * control point built (surfaces and curves, copies included) against
 * SEM_MAX_MODEL_CONTROL_POINTS, and the file itself against SEM_MAX_MODEL_FILE_BYTES and
 * SEM_MAX_IGES_ENTITIES. Recursion is bounded; malformed data ends the read with
 * SEM_ERR_PARSE and "FILE:LINE: entity T (DE n): what is wrong". Entities we cannot convert (parametric
 * splines 112/114, conics, offset and analytic 190-198 surfaces, ...) are skipped with a
 * warning naming them, and a trim loop that cannot be built leaves its part untrimmed with
 * a warning rather than losing the part.
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
 * their way), and header or range defects that Open CASCADE reads past (a unit flag of 0, a
 * parameter line count past the section, empty or swapped parameter ranges) are repaired with
 * a warning instead of refusing the file.
 */
#include <ctype.h>
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/analytic_surfaces.h"
#include "geometry/curve_tools.h"
#include "geometry/trim_fix.h"
#include "geometry/trim_projection.h"
#include "io/read_file.h"
#include "sem/limits.h"
#include "sem/model.h"
#include "sem/nurbs.h"
#include "sem/trim.h"

#define IGES_MAX_DEPTH 32
#define PLINE_WIDTH 64
#define GLINE_WIDTH 72

enum { SEC_S, SEC_G, SEC_D, SEC_P, SEC_T, SEC_COUNT };

typedef struct iges_line {
    const char *text;
    int len;    /* characters before the section letter (at most 72) */
    int number; /* line number in the file, from 1 */
} iges_line;

typedef struct iges_token {
    size_t offset; /* into the section text */
    int length;
    int is_string; /* Hollerith string */
} iges_token;

typedef struct iges_entry {
    int type, form;
    int pd_pointer, pd_count;
    int xform;       /* DE number of a 124, or 0 */
    int color;
    int subordinate; /* status digits 3-4 */
    char label[9];
    int subscript;
    int line;        /* file line of the entry's first DE line */
    size_t first_token;
    int n_params;    /* tokens, including the leading entity type */
    int n_used;      /* parameters of the definition (property pointers follow), 0 = unknown */
    unsigned char referenced;  /* pointed to by an entity we understand */
    unsigned char in_definition; /* member of a 308 subfigure definition */
    unsigned char busy;        /* recursion guard (stops cycles, not repeated sharing) */
    unsigned char self_ref;    /* points to itself: skipped with a warning */
    unsigned char repaired;    /* a repair was warned about (once per entity, however often
                                  it is used) */
} iges_entry;

typedef struct curve_list {
    int n, cap;
    sem_curve *c;
} curve_list;

typedef struct iges_reader {
    const char *name;
    sem_model *model;
    sem_error *err;
    char param_delim, record_delim;
    iges_line *lines;
    int n_lines;
    int sec_first[SEC_COUNT], sec_count[SEC_COUNT];
    char *ptext;
    size_t ptext_len;
    iges_token *tokens;
    size_t n_tokens, cap_tokens;
    iges_entry *entries;
    int n_entries;
    /* Surfaces whose extent or parameters the file does not give (an unbounded plane, 108
     * without a display size; the analytic surfaces 190-198, unbounded or parameterized
     * differently from our NURBS): when a trimmed entity or face that uses one has
     * model-space boundary curves, it sets surface_hint; the surface comes out as a NURBS
     * with from_hint = 1 and hint_fit saying how to size it to those curves (HINT_*), and
     * its loops come from projecting them. */
    int surface_hint;
    int from_hint;
    int hint_fit;
    int hint_seam; /* the surface's seam may be turned to suit the boundary */
    /* The surface's NURBS parameters are not the file's (a surface of revolution's angle is
     * not the parameter of our rational circle, nor an arc's angle that of its NURBS): its
     * loops are better taken from model space when the file gives them there too. */
    int inexact_param;
    double resolution;        /* Global parameter 19, the file's own tolerance (model units),
                                 or 0 */
    long long conversions;    /* entity conversions so far (SEM_MAX_IGES_EXPANSION) */
    long long built_points;   /* control points built so far (SEM_MAX_MODEL_CONTROL_POINTS) */
} iges_reader;

enum { HINT_NONE, HINT_PLANE, HINT_AXIAL };


/* ---------------------------------------------------------------- errors ---- */

static sem_status parse_error(iges_reader *r, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static sem_status parse_error(iges_reader *r, int line, const char *fmt, ...)
{
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    return sem_error_set(r->err, SEM_ERR_PARSE, "%s:%d: %s", r->name, line, msg);
}

static int de_number(int index) { return 2 * index + 1; }

static sem_status entity_error(iges_reader *r, int idx, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static sem_status entity_error(iges_reader *r, int idx, int line, const char *fmt, ...)
{
    char msg[640];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    const iges_entry *e = &r->entries[idx];
    return sem_error_set(r->err, SEM_ERR_PARSE, "%s:%d: entity %d (DE %d): %s", r->name,
                         line > 0 ? line : e->line, e->type, de_number(idx), msg);
}

static sem_status nomem(iges_reader *r)
{
    return sem_error_set(r->err, SEM_ERR_NOMEM, "%s: out of memory", r->name);
}

/* Counts one conversion of entity idx against the expansion budget. */
static sem_status count_conversion(iges_reader *r, int idx)
{
    if (++r->conversions <= SEM_MAX_IGES_EXPANSION) return SEM_OK;
    return entity_error(r, idx, 0, "more than %d entity conversions (subfigure instances and "
                                   "shared members count each time they are used; limit "
                                   "SEM_MAX_IGES_EXPANSION)",
                        SEM_MAX_IGES_EXPANSION);
}

/* Counts n control points about to be built against the model budget. */
static sem_status count_points(iges_reader *r, int idx, long long n)
{
    r->built_points += n;
    if (r->built_points <= SEM_MAX_MODEL_CONTROL_POINTS) return SEM_OK;
    return entity_error(r, idx, 0, "the model would have more than %d control points (surfaces "
                                   "and trim curves, every instance counted; limit "
                                   "SEM_MAX_MODEL_CONTROL_POINTS)",
                        SEM_MAX_MODEL_CONTROL_POINTS);
}

static const char *entity_description(int type)
{
    switch (type) {
    case 104: return "conic arc";
    case 106: return "copious data";
    case 112: return "parametric spline curve";
    case 114: return "parametric spline surface";
    case 130: return "offset curve";
    case 140: return "offset surface";
    case 180: return "boolean tree";
    case 182: return "selected component";
    case 184: return "solid assembly";
    case 190: return "plane surface";
    case 192: return "right circular cylindrical surface";
    case 194: return "right circular conical surface";
    case 196: return "spherical surface";
    case 198: return "toroidal surface";
    case 430: return "solid instance";
    default: break;
    }
    if (type >= 150 && type <= 168) return "CSG primitive";
    return NULL;
}

/* Adds "entity T (DE n): <type> not supported, skipped" and returns SEM_ERR_UNSUPPORTED,
 * which callers turn into "leave this piece out" rather than a failure. */
static sem_status unsupported(iges_reader *r, int idx, const char *what)
{
    const iges_entry *e = &r->entries[idx];
    const char *d = entity_description(e->type);
    sem_model_warn(r->model, "entity %d (DE %d): %s%s%s", e->type, de_number(idx),
                   d ? d : "", d ? " " : "", what);
    return SEM_ERR_UNSUPPORTED;
}

/* ------------------------------------------------------------- lines ---- */

static int section_of(char c)
{
    switch (c) {
    case 'S': return SEC_S;
    case 'G': return SEC_G;
    case 'D': return SEC_D;
    case 'P': return SEC_P;
    case 'T': return SEC_T;
    default: return -1;
    }
}

/* Finds the section letter: column 73, or (for lines cut shorter than standard) the
 * letter before a trailing sequence number. Returns the section and the data length. */
static int classify_line(const char *s, int n, int *data_len)
{
    if (n >= 73) {
        int sec = section_of(s[72]);
        if (sec >= 0) {
            *data_len = 72;
            return sec;
        }
    }
    int i = n - 1;
    while (i >= 0 && (s[i] == ' ' || s[i] == '\t')) --i;
    int digits_end = i;
    while (i >= 0 && isdigit((unsigned char)s[i])) --i;
    if (i == digits_end) return -1; /* no sequence number */
    while (i >= 0 && s[i] == ' ') --i;
    if (i < 0) return -1;
    int sec = section_of(s[i]);
    if (sec < 0) return -1;
    *data_len = i < 72 ? i : 72;
    return sec;
}

static sem_status split_lines(iges_reader *r, const char *data, size_t len)
{
    size_t cap = len / 81 + 16;
    r->lines = malloc(cap * sizeof *r->lines);
    if (!r->lines) return nomem(r);
    int line_no = 0, current = SEC_S;
    static const char names[] = "SGDPT";
    size_t pos = 0;
    while (pos < len) {
        size_t end = pos;
        while (end < len && data[end] != '\n' && data[end] != '\r') ++end;
        size_t next = end;
        if (next < len && data[next] == '\r') ++next;
        if (next < len && data[next] == '\n' && (next == end || data[end] == '\r')) ++next;
        if (next == end) next = end + 1; /* lone '\n' */
        ++line_no;
        const char *s = data + pos;
        int n = end - pos > 100000 ? 100000 : (int)(end - pos);
        pos = next;
        int blank = 1;
        for (int i = 0; i < n; ++i)
            if (s[i] != ' ' && s[i] != '\t' && s[i] != '\f' && s[i] != '\x1a') blank = 0;
        if (blank) continue;
        if (n >= 73 && (s[72] == 'C' || s[72] == 'B') && r->n_lines == 0)
            return parse_error(r, line_no, "compressed or binary IGES (column 73 '%c') is not "
                                           "supported", s[72]);
        int data_len = 0;
        int sec = classify_line(s, n, &data_len);
        if (sec < 0)
            return parse_error(r, line_no, "no section letter (S, G, D, P or T) in column 73");
        if (sec < current)
            return parse_error(r, line_no, "%c line after the %c section (sections must come "
                                           "in the order S, G, D, P, T)",
                               names[sec], names[current]);
        if (current == SEC_T && r->sec_count[SEC_T] > 0)
            return parse_error(r, line_no, "text after the Terminate line");
        if (sec != current || r->sec_count[sec] == 0) {
            current = sec;
            if (r->sec_count[sec] == 0) r->sec_first[sec] = r->n_lines;
        }
        if ((size_t)r->n_lines == cap) {
            cap *= 2;
            iges_line *l = realloc(r->lines, cap * sizeof *l);
            if (!l) return nomem(r);
            r->lines = l;
        }
        r->lines[r->n_lines].text = s;
        r->lines[r->n_lines].len = data_len;
        r->lines[r->n_lines].number = line_no;
        r->n_lines++;
        r->sec_count[sec]++;
    }
    if (r->n_lines == 0) return parse_error(r, line_no > 0 ? line_no : 1, "empty file");
    int last = r->lines[r->n_lines - 1].number;
    if (r->sec_count[SEC_G] == 0) return parse_error(r, last, "no Global section");
    if (r->sec_count[SEC_D] == 0) return parse_error(r, last, "no Directory Entry section");
    if (r->sec_count[SEC_P] == 0)
        return parse_error(r, last, "no Parameter Data section (file truncated?)");
    if (r->sec_count[SEC_T] == 0)
        return parse_error(r, last, "no Terminate section (file truncated?)");
    return SEM_OK;
}

/* ----------------------------------------------------------- tokens ---- */

static int push_token(iges_reader *r, size_t off, int len, int is_string)
{
    if (r->n_tokens == r->cap_tokens) {
        size_t cap = r->cap_tokens ? 2 * r->cap_tokens : 1024;
        iges_token *t = realloc(r->tokens, cap * sizeof *t);
        if (!t) return 0;
        r->tokens = t;
        r->cap_tokens = cap;
    }
    r->tokens[r->n_tokens].offset = off;
    r->tokens[r->n_tokens].length = len;
    r->tokens[r->n_tokens].is_string = is_string;
    r->n_tokens++;
    return 1;
}

/* Tokenises text[begin, limit) up to the record delimiter. Strings "nH..." take exactly
 * n characters whatever they contain. *line_of maps an offset to a file line (errors). On
 * success *end is the offset after the record delimiter. */
typedef int (*line_of_fn)(const iges_reader *r, size_t offset);

static int pline_of(const iges_reader *r, size_t offset)
{
    size_t i = offset / PLINE_WIDTH;
    if (i >= (size_t)r->sec_count[SEC_P]) i = (size_t)r->sec_count[SEC_P] - 1;
    return r->lines[r->sec_first[SEC_P] + (int)i].number;
}

static int gline_of(const iges_reader *r, size_t offset)
{
    size_t i = offset / GLINE_WIDTH;
    if (i >= (size_t)r->sec_count[SEC_G]) i = (size_t)r->sec_count[SEC_G] - 1;
    return r->lines[r->sec_first[SEC_G] + (int)i].number;
}

static sem_status tokenize(iges_reader *r, const char *text, size_t begin, size_t limit,
                           line_of_fn line_of, const char *what, size_t *end)
{
    size_t pos = begin;
    for (;;) {
        while (pos < limit && (text[pos] == ' ' || text[pos] == '\t')) ++pos;
        if (pos >= limit)
            return parse_error(r, line_of(r, limit > begin ? limit - 1 : begin),
                               "%s ends without the record delimiter '%c'", what,
                               r->record_delim);
        size_t start = pos;
        size_t digits = pos;
        while (digits < limit && isdigit((unsigned char)text[digits])) ++digits;
        if (digits > pos && digits < limit && (text[digits] == 'H' || text[digits] == 'h')) {
            /* Hollerith string */
            if (digits - pos > 9)
                return parse_error(r, line_of(r, pos), "%s: Hollerith length too large", what);
            long n = strtol(text + pos, NULL, 10);
            size_t s = digits + 1;
            if ((size_t)n > limit - s)
                return parse_error(r, line_of(r, pos),
                                   "%s: Hollerith string of %ld characters runs past the end "
                                   "of the data",
                                   what, n);
            if (!push_token(r, s, (int)n, 1)) return nomem(r);
            pos = s + (size_t)n;
            while (pos < limit && (text[pos] == ' ' || text[pos] == '\t')) ++pos;
            if (pos >= limit)
                return parse_error(r, line_of(r, limit - 1),
                                   "%s ends without the record delimiter '%c'", what,
                                   r->record_delim);
            if (text[pos] != r->param_delim && text[pos] != r->record_delim)
                return parse_error(r, line_of(r, pos),
                                   "%s: unexpected character '%c' after a Hollerith string",
                                   what, text[pos]);
        } else {
            while (pos < limit && text[pos] != r->param_delim && text[pos] != r->record_delim)
                ++pos;
            if (pos >= limit)
                return parse_error(r, line_of(r, limit - 1),
                                   "%s ends without the record delimiter '%c'", what,
                                   r->record_delim);
            size_t e = pos;
            while (e > start && (text[e - 1] == ' ' || text[e - 1] == '\t')) --e;
            if (e - start > 4096)
                return parse_error(r, line_of(r, start), "%s: parameter too long", what);
            if (!push_token(r, start, (int)(e - start), 0)) return nomem(r);
        }
        if (text[pos] == r->record_delim) {
            *end = pos + 1;
            return SEM_OK;
        }
        ++pos; /* parameter delimiter */
    }
}

/* Parses a number: optional sign, digits, '.', exponent with E or D. Empty -> default. */
static int parse_real(const char *s, int len, double def, double *out)
{
    while (len > 0 && (*s == ' ' || *s == '\t')) ++s, --len;
    while (len > 0 && (s[len - 1] == ' ' || s[len - 1] == '\t')) --len;
    if (len == 0) {
        *out = def;
        return 1;
    }
    char buf[96];
    if (len < 0 || len >= (int)sizeof buf) return 0;
    int digits = 0;
    for (int i = 0; i < len; ++i) {
        char c = s[i];
        if (c == 'D' || c == 'd') c = 'E';
        if (isdigit((unsigned char)c)) digits++;
        else if (c != '+' && c != '-' && c != '.' && c != 'E' && c != 'e') return 0;
        buf[i] = c;
    }
    buf[len] = '\0';
    if (!digits) return 0;
    char *end;
    errno = 0;
    double v = strtod(buf, &end);
    if (end != buf + len) return 0;
    if (!isfinite(v)) return -1;
    *out = v;
    return 1;
}

/* ------------------------------------------------------------ global ---- */

static sem_status read_global(iges_reader *r)
{
    int ng = r->sec_count[SEC_G];
    size_t glen = (size_t)ng * GLINE_WIDTH;
    char *g = malloc(glen + 1);
    if (!g) return nomem(r);
    for (int i = 0; i < ng; ++i) {
        const iges_line *l = &r->lines[r->sec_first[SEC_G] + i];
        memset(g + (size_t)i * GLINE_WIDTH, ' ', GLINE_WIDTH);
        memcpy(g + (size_t)i * GLINE_WIDTH, l->text, (size_t)l->len);
    }
    g[glen] = '\0';
    sem_status st = SEM_OK;
    size_t pos = 0;
    /* parameter 1: the parameter delimiter, "1Hx" or empty (default ',') */
    r->param_delim = ',';
    r->record_delim = ';';
    while (pos < glen && g[pos] == ' ') ++pos;
    if (pos + 2 < glen && g[pos] == '1' && (g[pos + 1] == 'H' || g[pos + 1] == 'h')) {
        r->param_delim = g[pos + 2];
        pos += 3;
        while (pos < glen && g[pos] == ' ') ++pos;
    }
    if (pos >= glen || g[pos] != r->param_delim) {
        st = parse_error(r, gline_of(r, pos < glen ? pos : glen - 1),
                         "Global section: parameter delimiter must be given as 1Hx or left empty");
        goto done;
    }
    ++pos;
    /* parameter 2: the record delimiter */
    while (pos < glen && g[pos] == ' ') ++pos;
    if (pos + 2 < glen && g[pos] == '1' && (g[pos + 1] == 'H' || g[pos + 1] == 'h')) {
        r->record_delim = g[pos + 2];
        pos += 3;
        while (pos < glen && g[pos] == ' ') ++pos;
        if (pos < glen && g[pos] == r->record_delim) {
            goto done; /* nothing else in the Global section */
        }
    }
    if (r->record_delim == r->param_delim) {
        st = parse_error(r, gline_of(r, pos), "Global section: record and parameter delimiters "
                                              "are the same character '%c'", r->param_delim);
        goto done;
    }
    if (pos >= glen || g[pos] != r->param_delim) {
        if (pos < glen && g[pos] == r->record_delim) goto done;
        st = parse_error(r, gline_of(r, pos < glen ? pos : glen - 1),
                         "Global section: record delimiter must be given as 1Hx or left empty");
        goto done;
    }
    ++pos;
    {
        size_t first = r->n_tokens, end = 0;
        st = tokenize(r, g, pos, glen, gline_of, "Global section", &end);
        if (st != SEM_OK) goto done;
        /* parameter k (from 1) is token first + k - 3 */
        int unit_flag = 1, bad_flag = 0;
        double v;
        size_t k14 = first + 11, k15 = first + 12, k19 = first + 16;
        /* parameter 19: the minimum user-intended resolution, the gaps the file tolerates */
        if (k19 < r->n_tokens && !r->tokens[k19].is_string &&
            parse_real(g + r->tokens[k19].offset, r->tokens[k19].length, 0.0, &v) == 1 && v > 0 &&
            isfinite(v))
            r->resolution = v;
        if (k14 < r->n_tokens) {
            const iges_token *t = &r->tokens[k14];
            int ok = parse_real(g + t->offset, t->length, 1.0, &v);
            if (ok != 1 || v != floor(v) || v < 1 || v > 11) {
                /* Rhino 1998 wrote 0 (corpus occt_rhino_bad_header); Open CASCADE reads such
                 * a file, and so do we: the unit name decides (flag 3), else the default */
                sem_model_warn(r->model, "Global section: unit flag (parameter 14) '%.*s' is not "
                                         "1..11; the unit name decides, else inches (the IGES "
                                         "default)",
                               t->length < 20 ? t->length : 20, g + t->offset);
                v = 3;
                bad_flag = 1;
            }
            unit_flag = (int)v;
        }
        char uname[16] = "";
        if (k15 < r->n_tokens && r->tokens[k15].is_string) {
            const iges_token *t = &r->tokens[k15];
            int n = t->length < 15 ? t->length : 15;
            for (int i = 0; i < n; ++i) uname[i] = (char)toupper((unsigned char)g[t->offset + i]);
            uname[n] = '\0';
        }
        static const struct { const char *name; double m; } units[] = {
            {"IN", 0.0254},  {"MM", 0.001}, {"", 1.0},      {"FT", 0.3048},
            {"MI", 1609.344}, {"M", 1.0},    {"KM", 1000.0}, {"MIL", 2.54e-5},
            {"UM", 1e-6},     {"CM", 0.01},  {"UIN", 2.54e-8}};
        if (unit_flag == 3) {
            static const struct { const char *name; int flag; } alias[] = {
                {"IN", 1}, {"INCH", 1}, {"MM", 2}, {"FT", 4}, {"MI", 5}, {"M", 6}, {"KM", 7},
                {"MIL", 8}, {"UM", 9}, {"MICRON", 9}, {"CM", 10}, {"UIN", 11}};
            int found = 0;
            for (size_t i = 0; i < sizeof alias / sizeof alias[0]; ++i)
                if (strcmp(uname, alias[i].name) == 0) {
                    unit_flag = alias[i].flag;
                    found = 1;
                }
            if (!found && bad_flag && uname[0] == '\0') {
                unit_flag = 1; /* no name either (an invalid flag above): the IGES default */
            } else if (!found) {
                sem_model_warn(r->model, "unknown unit name '%s' (unit flag 3); assuming metres",
                               uname);
                strcpy(r->model->units, "M");
                r->model->unit_to_meter = 1.0;
            }
        }
        if (unit_flag != 3) {
            snprintf(r->model->units, sizeof r->model->units, "%s", units[unit_flag - 1].name);
            r->model->unit_to_meter = units[unit_flag - 1].m;
        }
        r->n_tokens = first; /* Global tokens are not kept */
    }
done:
    free(g);
    return st;
}

/* ---------------------------------------------------------- directory ---- */

/* Field f (1..9) of a DE line as an integer; blank is 0. */
static int de_field(const iges_line *l, int f, int *out)
{
    int c0 = 8 * (f - 1);
    char buf[9];
    int n = 0;
    for (int i = c0; i < c0 + 8; ++i) {
        char c = i < l->len ? l->text[i] : ' ';
        if (c != ' ') buf[n++] = c;
    }
    buf[n] = '\0';
    if (n == 0) {
        *out = 0;
        return 1;
    }
    char *end;
    long v = strtol(buf, &end, 10);
    if (*end != '\0') return 0;
    *out = (int)v;
    return 1;
}

/* The directory entry a Parameter line points back to (columns 66-72), or -1. */
static int p_back_pointer(const iges_reader *r, int line)
{
    const iges_line *l = &r->lines[r->sec_first[SEC_P] + line];
    if (l->len < 72) return -1;
    char buf[8];
    int n = 0;
    for (int c = 65; c < 72; ++c)
        if (l->text[c] != ' ') buf[n++] = l->text[c];
    buf[n] = '\0';
    char *end;
    long back = strtol(buf, &end, 10);
    return n > 0 && *end == '\0' && back > 0 && back < INT32_MAX ? (int)back : -1;
}

static sem_status read_directory(iges_reader *r)
{
    int nd = r->sec_count[SEC_D];
    if (nd % 2 != 0)
        return parse_error(r, r->lines[r->sec_first[SEC_D] + nd - 1].number,
                           "odd number of Directory Entry lines (%d): each entry has 2", nd);
    if (nd / 2 > SEM_MAX_IGES_ENTITIES)
        return parse_error(r, r->lines[r->sec_first[SEC_D]].number,
                           "%d directory entries; at most %d are read (limit "
                           "SEM_MAX_IGES_ENTITIES)", nd / 2, SEM_MAX_IGES_ENTITIES);
    r->n_entries = nd / 2;
    r->entries = calloc((size_t)r->n_entries, sizeof *r->entries);
    if (!r->entries) return nomem(r);
    for (int i = 0; i < r->n_entries; ++i) {
        const iges_line *l1 = &r->lines[r->sec_first[SEC_D] + 2 * i];
        const iges_line *l2 = l1 + 1;
        iges_entry *e = &r->entries[i];
        e->line = l1->number;
        int type2 = 0;
        static const int f1[] = {1, 2, 7}, f2[] = {1, 3, 4, 5};
        int *d1[] = {&e->type, &e->pd_pointer, &e->xform};
        int *d2[] = {&type2, &e->color, &e->pd_count, &e->form};
        for (int k = 0; k < 3; ++k)
            if (!de_field(l1, f1[k], d1[k]))
                return parse_error(r, l1->number, "directory entry field %d '%.8s' is not an "
                                                  "integer", f1[k], l1->text + 8 * (f1[k] - 1));
        for (int k = 0; k < 4; ++k)
            if (!de_field(l2, f2[k], d2[k]))
                return parse_error(r, l2->number, "directory entry field %d '%.8s' is not an "
                                                  "integer", 9 + f2[k], l2->text + 8 * (f2[k] - 1));
        if (type2 != e->type)
            return parse_error(r, l2->number, "directory entry %d: entity type %d on the first "
                                              "line but %d on the second", de_number(i), e->type,
                               type2);
        /* status "bbssuuhh": subordinate switch in digits 3-4 */
        if (l1->len >= 68 && isdigit((unsigned char)l1->text[66]) &&
            isdigit((unsigned char)l1->text[67]))
            e->subordinate = (l1->text[66] - '0') * 10 + (l1->text[67] - '0');
        int n = 0;
        for (int c = 56; c < 64 && c < l2->len; ++c)
            if (l2->text[c] != ' ' || n > 0) e->label[n++] = l2->text[c];
        while (n > 0 && e->label[n - 1] == ' ') --n;
        e->label[n] = '\0';
        if (l2->len >= 72) {
            int sub = 0;
            if (de_field(l2, 9, &sub)) e->subscript = sub;
        }
        if (e->type == 0) continue; /* null entity */
        int np = r->sec_count[SEC_P];
        if (e->pd_pointer >= 1 && e->pd_pointer <= np &&
            (e->pd_count < 1 || e->pd_count > np - e->pd_pointer + 1) &&
            p_back_pointer(r, e->pd_pointer - 1) == de_number(i)) {
            /* a line count that runs past the Parameter section (Rhino 1998 wrote 20 for a
             * 7-line surface: corpus occt_rhino_bad_header): the lines that point back to
             * this entry are its lines, as Open CASCADE reads them */
            int count = 0;
            while (e->pd_pointer - 1 + count < np &&
                   p_back_pointer(r, e->pd_pointer - 1 + count) == de_number(i))
                ++count;
            sem_model_warn(r->model, "entity %d (DE %d): parameter line count %d runs past the "
                                     "Parameter section; its %d lines that point back to it are "
                                     "read",
                           e->type, de_number(i), e->pd_count, count);
            e->pd_count = count;
        }
        if (e->pd_pointer < 1 || e->pd_pointer > np || e->pd_count < 1 ||
            e->pd_count > np - e->pd_pointer + 1)
            return parse_error(r, l1->number,
                               "entity %d (DE %d): parameter data lines %d..%d are outside the "
                               "Parameter section (%d lines; file truncated?)",
                               e->type, de_number(i), e->pd_pointer,
                               e->pd_pointer + e->pd_count - 1, np);
        if (e->xform < 0 || e->xform > 2 * r->n_entries)
            return parse_error(r, l1->number, "entity %d (DE %d): transformation matrix "
                                              "pointer %d out of range",
                               e->type, de_number(i), e->xform);
    }
    return SEM_OK;
}

static sem_status read_parameters(iges_reader *r)
{
    int np = r->sec_count[SEC_P];
    r->ptext_len = (size_t)np * PLINE_WIDTH;
    r->ptext = malloc(r->ptext_len + 1);
    if (!r->ptext) return nomem(r);
    for (int i = 0; i < np; ++i) {
        const iges_line *l = &r->lines[r->sec_first[SEC_P] + i];
        char *dst = r->ptext + (size_t)i * PLINE_WIDTH;
        memset(dst, ' ', PLINE_WIDTH);
        memcpy(dst, l->text, (size_t)(l->len < PLINE_WIDTH ? l->len : PLINE_WIDTH));
    }
    r->ptext[r->ptext_len] = '\0';
    for (int i = 0; i < r->n_entries; ++i) {
        iges_entry *e = &r->entries[i];
        if (e->type == 0) continue;
        const iges_line *first = &r->lines[r->sec_first[SEC_P] + e->pd_pointer - 1];
        if (first->len >= 72) {
            /* columns 66-72: back pointer to the directory entry */
            char buf[8];
            int n = 0;
            for (int c = 65; c < 72; ++c)
                if (first->text[c] != ' ') buf[n++] = first->text[c];
            buf[n] = '\0';
            char *end;
            long back = strtol(buf, &end, 10);
            if (n > 0 && *end == '\0' && back != de_number(i))
                return parse_error(r, first->number,
                                   "parameter line %d belongs to DE %ld, but DE %d (entity %d) "
                                   "points to it",
                                   e->pd_pointer, back, de_number(i), e->type);
        }
        char what[64];
        snprintf(what, sizeof what, "entity %d (DE %d)", e->type, de_number(i));
        size_t begin = (size_t)(e->pd_pointer - 1) * PLINE_WIDTH;
        size_t limit = (size_t)(e->pd_pointer - 1 + e->pd_count) * PLINE_WIDTH;
        e->first_token = r->n_tokens;
        size_t end;
        sem_status st = tokenize(r, r->ptext, begin, limit, pline_of, what, &end);
        if (st != SEM_OK) return st;
        size_t nt = r->n_tokens - e->first_token;
        if (nt > INT32_MAX / 2) return entity_error(r, i, first->number, "too many parameters");
        e->n_params = (int)nt;
        const iges_token *t = &r->tokens[e->first_token];
        double ty;
        if (t->is_string || parse_real(r->ptext + t->offset, t->length, -1, &ty) != 1 ||
            ty != e->type)
            return parse_error(r, first->number,
                               "parameter data starts with '%.*s' but directory entry %d says "
                               "entity type %d",
                               t->length > 20 ? 20 : t->length, r->ptext + t->offset,
                               de_number(i), e->type);
    }
    return SEM_OK;
}

static sem_status check_terminate(iges_reader *r)
{
    const iges_line *t = &r->lines[r->sec_first[SEC_T]];
    static const char letters[] = "SGDP";
    for (int k = 0; k < 4; ++k) {
        int c0 = 8 * k;
        if (t->len < c0 + 8 || t->text[c0] != letters[k]) continue;
        char buf[8];
        int n = 0;
        for (int i = c0 + 1; i < c0 + 8; ++i)
            if (t->text[i] != ' ') buf[n++] = t->text[i];
        buf[n] = '\0';
        char *end;
        long v = strtol(buf, &end, 10);
        if (n == 0 || *end != '\0') continue;
        if ((k == 2 || k == 3) && v != r->sec_count[k])
            return parse_error(r, t->number,
                               "Terminate section counts %ld %c lines but the file has %d "
                               "(file truncated or damaged?)",
                               v, letters[k], r->sec_count[k]);
    }
    return SEM_OK;
}

/* ------------------------------------------------------ parameters ---- */

static int token_line(const iges_reader *r, int idx, int k)
{
    const iges_entry *e = &r->entries[idx];
    if (k < 0 || k >= e->n_params) k = e->n_params - 1;
    return pline_of(r, r->tokens[e->first_token + (size_t)k].offset);
}

static int remaining(const iges_reader *r, int idx, int k)
{
    int n = r->entries[idx].n_params - k;
    return n > 0 ? n : 0;
}

static sem_status param_real_def(iges_reader *r, int idx, int k, double def, double *out)
{
    const iges_entry *e = &r->entries[idx];
    if (k >= e->n_params)
        return entity_error(r, idx, token_line(r, idx, e->n_params - 1),
                            "parameter %d is missing (the entity has %d parameters)", k,
                            e->n_params - 1);
    const iges_token *t = &r->tokens[e->first_token + (size_t)k];
    int ok = t->is_string ? 0 : parse_real(r->ptext + t->offset, t->length, def, out);
    if (ok == 1) return SEM_OK;
    int n = t->length > 40 ? 40 : t->length;
    if (ok < 0)
        return entity_error(r, idx, pline_of(r, t->offset),
                            "parameter %d '%.*s' is not a finite number", k, n,
                            r->ptext + t->offset);
    return entity_error(r, idx, pline_of(r, t->offset), "parameter %d '%.*s' is not a number",
                        k, n, r->ptext + t->offset);
}

static sem_status param_real(iges_reader *r, int idx, int k, double *out)
{
    return param_real_def(r, idx, k, 0.0, out);
}

static sem_status param_int(iges_reader *r, int idx, int k, int *out)
{
    double v;
    sem_status st = param_real(r, idx, k, &v);
    if (st != SEM_OK) return st;
    if (v != floor(v) || fabs(v) > 1e9) {
        const iges_token *t = &r->tokens[r->entries[idx].first_token + (size_t)k];
        return entity_error(r, idx, pline_of(r, t->offset), "parameter %d '%.*s' is not an "
                                                            "integer", k,
                            t->length > 40 ? 40 : t->length, r->ptext + t->offset);
    }
    *out = (int)v;
    return SEM_OK;
}

/* A pointer parameter: *out is the entry index, or -1 for 0 when allow_null. */
static sem_status param_ptr(iges_reader *r, int idx, int k, int allow_null, int *out)
{
    int v = 0;
    sem_status st = param_int(r, idx, k, &v);
    if (st != SEM_OK) return st;
    if (v < 0) v = -v;
    if (v == 0 && allow_null) {
        *out = -1;
        return SEM_OK;
    }
    if (v < 1 || v > 2 * r->n_entries - 1 || v % 2 == 0 || r->entries[(v - 1) / 2].type == 0)
        return entity_error(r, idx, token_line(r, idx, k),
                            "parameter %d: pointer %d is not a directory entry (DE 1..%d)", k, v,
                            2 * r->n_entries - 1);
    *out = (v - 1) / 2;
    return SEM_OK;
}

static void param_string(const iges_reader *r, int idx, int k, const char **s, int *len)
{
    const iges_entry *e = &r->entries[idx];
    *s = "";
    *len = 0;
    if (k >= e->n_params) return;
    const iges_token *t = &r->tokens[e->first_token + (size_t)k];
    if (!t->is_string) return;
    *s = r->ptext + t->offset;
    *len = t->length;
}

static sem_status need(iges_reader *r, int idx, int k, long long count, const char *what)
{
    if (count < 0 || count > remaining(r, idx, k))
        return entity_error(r, idx, token_line(r, idx, k),
                            "%s needs %lld parameters from parameter %d, but the entity has "
                            "only %d",
                            what, count, k, remaining(r, idx, k));
    return SEM_OK;
}

/* -------------------------------------------------------- transforms ---- */

/* 3x4 matrices [R | t], x' = R x + t, row-major. */
static const double identity_xf[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

static void xf_compose(const double *a, const double *b, double *out)
{
    double m[12];
    for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j)
            m[4 * i + j] = a[4 * i] * b[j] + a[4 * i + 1] * b[4 + j] + a[4 * i + 2] * b[8 + j];
        m[4 * i + 3] = a[4 * i] * b[3] + a[4 * i + 1] * b[7] + a[4 * i + 2] * b[11] + a[4 * i + 3];
    }
    memcpy(out, m, sizeof m);
}

static int xf_is_identity(const double *m)
{
    return memcmp(m, identity_xf, sizeof identity_xf) == 0;
}

static void xf_apply(const double *m, double *p, size_t n)
{
    if (xf_is_identity(m)) return;
    for (size_t i = 0; i < n; ++i) {
        double x = p[3 * i], y = p[3 * i + 1], z = p[3 * i + 2];
        p[3 * i] = m[0] * x + m[1] * y + m[2] * z + m[3];
        p[3 * i + 1] = m[4] * x + m[5] * y + m[6] * z + m[7];
        p[3 * i + 2] = m[8] * x + m[9] * y + m[10] * z + m[11];
    }
}

/* out = parent o (the entity's own chain of 124 matrices). */
static sem_status own_xform(iges_reader *r, int idx, const double *parent, double *out)
{
    double m[12];
    memcpy(m, identity_xf, sizeof m);
    int ptr = r->entries[idx].xform, from = idx;
    for (int depth = 0; ptr != 0; ++depth) {
        if (depth >= IGES_MAX_DEPTH)
            return entity_error(r, idx, 0, "transformation matrix chain is cyclic or deeper "
                                           "than %d", IGES_MAX_DEPTH);
        if (ptr < 0 || ptr > 2 * r->n_entries - 1 || ptr % 2 == 0)
            return entity_error(r, from, 0, "transformation matrix pointer %d is not a "
                                            "directory entry",
                                ptr);
        int t = (ptr - 1) / 2;
        if (r->entries[t].type != 124)
            return entity_error(r, from, 0, "transformation matrix pointer %d points to a "
                                            "type-%d entity, not a 124",
                                ptr, r->entries[t].type);
        double x[12];
        sem_status st = need(r, t, 1, 12, "transformation matrix");
        for (int k = 0; st == SEM_OK && k < 12; ++k) st = param_real(r, t, 1 + k, &x[k]);
        if (st != SEM_OK) return st;
        xf_compose(x, m, m);
        from = t;
        ptr = r->entries[t].xform;
    }
    xf_compose(parent, m, out);
    return SEM_OK;
}

/* ------------------------------------------------------ curve tools ---- */

static sem_status list_push(iges_reader *r, curve_list *l, sem_curve *c)
{
    if (l->n == l->cap) {
        int cap = l->cap ? 2 * l->cap : 8;
        sem_curve *x = realloc(l->c, (size_t)cap * sizeof *x);
        if (!x) {
            sem_curve_free(c);
            return nomem(r);
        }
        l->c = x;
        l->cap = cap;
    }
    l->c[l->n++] = *c;
    memset(c, 0, sizeof *c);
    return SEM_OK;
}

static void list_free(curve_list *l)
{
    for (int i = 0; i < l->n; ++i) sem_curve_free(&l->c[i]);
    free(l->c);
    memset(l, 0, sizeof *l);
}

/* Exact reversal (geometry/trim_fix.c). */
static void curve_reverse(sem_curve *c) { sem_curve_reverse(c); }

/* Reverses the run of curves l->c[first..] as a piece of a chain: order and direction. */
static void reverse_curves(curve_list *l, int first)
{
    for (int a = first, b = l->n - 1; a < b; ++a, --b) {
        sem_curve t = l->c[a];
        l->c[a] = l->c[b];
        l->c[b] = t;
    }
    for (int a = first; a < l->n; ++a) curve_reverse(&l->c[a]);
}

/* --------------------------------------------------------- curves ---- */

static sem_status read_curves(iges_reader *r, int idx, const double *parent, int depth,
                              curve_list *out);

static int is_curve_type(int type)
{
    return type == 100 || type == 102 || type == 104 || type == 106 || type == 110 ||
           type == 112 || type == 126 || type == 130;
}

static sem_status curve_validate(iges_reader *r, int idx, const sem_curve *c)
{
    sem_error e;
    if (sem_curve_validate(c, &e) != SEM_OK)
        return entity_error(r, idx, 0, "%s", e.message);
    return SEM_OK;
}

static sem_status read_nurbs_curve(iges_reader *r, int idx, sem_curve *c)
{
    int K, M;
    sem_status st = param_int(r, idx, 1, &K);
    if (st == SEM_OK) st = param_int(r, idx, 2, &M);
    if (st != SEM_OK) return st;
    if (M < 1 || M > SEM_MAX_DEGREE)
        return entity_error(r, idx, token_line(r, idx, 2), "degree M = %d out of range 1..%d", M,
                            SEM_MAX_DEGREE);
    if (K < M)
        return entity_error(r, idx, token_line(r, idx, 1),
                            "degree %d too high for %d control points (K = %d)", M, K + 1, K);
    long long n = (long long)K + 1, nk = (long long)K + M + 2;
    st = need(r, idx, 7, nk + n + 3 * n + 2, "rational B-spline curve (K, M)");
    if (st != SEM_OK) return st;
    if (nk > SEM_MAX_KNOTS)
        return entity_error(r, idx, token_line(r, idx, 1), "%lld knots; at most %d per curve "
                                                           "(limit SEM_MAX_KNOTS)",
                            nk, SEM_MAX_KNOTS);
    if ((st = count_points(r, idx, n)) != SEM_OK) return st;
    if (sem_curve_alloc(c, M, (int)n) != SEM_OK) return nomem(r);
    int k = 7;
    for (long long i = 0; st == SEM_OK && i < nk; ++i) st = param_real(r, idx, k++, &c->knots[i]);
    for (long long i = 0; st == SEM_OK && i < n; ++i) st = param_real(r, idx, k++, &c->weights[i]);
    for (long long i = 0; st == SEM_OK && i < 3 * n; ++i) st = param_real(r, idx, k++, &c->ctrl[i]);
    if (st == SEM_OK) st = param_real(r, idx, k++, &c->t0);
    if (st == SEM_OK) st = param_real(r, idx, k++, &c->t1);
    double ka = st == SEM_OK ? c->knots[M] : 0, kb = st == SEM_OK ? c->knots[K + 1] : 0;
    if (st == SEM_OK && !(c->t1 > c->t0) && kb > ka) {
        /* an empty range (Solid Edge writes V0 = V1 = 0: corpus occt_solidedge_deflector) is
         * the knots' own, as Open CASCADE reads it */
        if (!r->entries[idx].repaired)
            sem_model_warn(r->model, "entity 126 (DE %d): parameter range [%g, %g] is empty; the "
                                     "knots' range [%g, %g] is used",
                           de_number(idx), c->t0, c->t1, ka, kb);
        r->entries[idx].repaired = 1;
        c->t0 = ka;
        c->t1 = kb;
    }
    if (st == SEM_OK) st = curve_validate(r, idx, c);
    if (st != SEM_OK) {
        sem_curve_free(c);
        return st;
    }
    r->entries[idx].n_used = k + (remaining(r, idx, k) >= 3 ? 3 : 0); /* unit normal */
    return SEM_OK;
}

static sem_status read_line(iges_reader *r, int idx, double p0[3], double p1[3])
{
    sem_status st = need(r, idx, 1, 6, "line");
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = param_real(r, idx, 1 + k, &p0[k]);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = param_real(r, idx, 4 + k, &p1[k]);
    if (st == SEM_OK) r->entries[idx].n_used = 7;
    return st;
}

/* A circular arc as a rational quadratic: at most 90 degrees per piece, inner control
 * points on the tangent intersections with weight cos(half angle) (Piegl & Tiller A7.1).
 * The end control points are the file's start and end points exactly. */
static sem_status read_arc(iges_reader *r, int idx, sem_curve *c)
{
    double v[7];
    sem_status st = need(r, idx, 1, 7, "circular arc");
    for (int k = 0; st == SEM_OK && k < 7; ++k) st = param_real(r, idx, 1 + k, &v[k]);
    if (st != SEM_OK) return st;
    double zt = v[0], cx = v[1], cy = v[2], sx = v[3], sy = v[4], ex = v[5], ey = v[6];
    double rad = hypot(sx - cx, sy - cy);
    if (!(rad > 0))
        return entity_error(r, idx, token_line(r, idx, 1), "arc radius is zero");
    double a0 = atan2(sy - cy, sx - cx), a1 = atan2(ey - cy, ex - cx);
    int full = sx == ex && sy == ey;
    if (full) a1 = a0 + 2 * M_PI;
    while (a1 <= a0) a1 += 2 * M_PI;
    double sweep = a1 - a0;
    int nseg = (int)ceil(sweep / (M_PI / 2) - 1e-9);
    if (nseg < 1) nseg = 1;
    if (nseg > 4) nseg = 4;
    double d = sweep / nseg, wm = cos(d / 2);
    if (sem_curve_alloc(c, 2, 2 * nseg + 1) != SEM_OK) return nomem(r);
    int m = 0;
    for (int i = 0; i < 3; ++i) c->knots[m++] = 0.0;
    for (int i = 1; i < nseg; ++i) {
        c->knots[m++] = (double)i / nseg;
        c->knots[m++] = (double)i / nseg;
    }
    for (int i = 0; i < 3; ++i) c->knots[m++] = 1.0;
    for (int k = 0; k <= 2 * nseg; ++k) {
        double ang = a0 + k * d / 2, rr = (k % 2) ? rad / wm : rad;
        c->ctrl[3 * k] = cx + rr * cos(ang);
        c->ctrl[3 * k + 1] = cy + rr * sin(ang);
        c->ctrl[3 * k + 2] = zt;
        c->weights[k] = (k % 2) ? wm : 1.0;
    }
    c->ctrl[0] = sx;
    c->ctrl[1] = sy;
    c->ctrl[3 * 2 * nseg] = ex;
    c->ctrl[3 * 2 * nseg + 1] = ey;
    c->t0 = 0.0;
    c->t1 = 1.0;
    r->entries[idx].n_used = 8;
    return SEM_OK;
}

/* What every curve and surface entity does first: refuse a cycle or too deep a nesting,
 * count the conversion (SEM_MAX_* budgets), and compose its own transform with its parent's
 * into m. */
static sem_status enter_entity(iges_reader *r, int idx, const double *parent, int depth, double m[12])
{
    if (depth > IGES_MAX_DEPTH || r->entries[idx].busy)
        return entity_error(r, idx, 0, "entity references itself (cycle or nesting deeper than "
                                       "%d)", IGES_MAX_DEPTH);
    sem_status st = count_conversion(r, idx);
    if (st != SEM_OK) return st;
    return own_xform(r, idx, parent, m);
}

/* Reads any supported curve entity as one or more NURBS curves (a composite curve gives
 * its members in order), in the coordinates of `parent` o (the curve's own transform). */
static sem_status read_curves(iges_reader *r, int idx, const double *parent, int depth,
                              curve_list *out)
{
    iges_entry *e = &r->entries[idx];
    double m[12];
    sem_status st = enter_entity(r, idx, parent, depth, m);
    if (st != SEM_OK) return st;
    sem_curve c;
    memset(&c, 0, sizeof c);
    switch (e->type) {
    case 126:
        st = read_nurbs_curve(r, idx, &c);
        break;
    case 110: {
        double p0[3], p1[3];
        st = read_line(r, idx, p0, p1);
        if (st == SEM_OK) st = count_points(r, idx, 2);
        if (st != SEM_OK) return st;
        if (sem_curve_alloc(&c, 1, 2) != SEM_OK) return nomem(r);
        memcpy(c.ctrl, p0, sizeof p0);
        memcpy(c.ctrl + 3, p1, sizeof p1);
        c.knots[2] = c.knots[3] = 1.0;
        c.t1 = 1.0;
        break;
    }
    case 100:
        st = count_points(r, idx, 9);
        if (st == SEM_OK) st = read_arc(r, idx, &c);
        break;
    case 102: {
        int n;
        st = param_int(r, idx, 1, &n);
        if (st == SEM_OK) st = need(r, idx, 2, n, "composite curve (N)");
        if (st != SEM_OK) return st;
        e->busy = 1;
        for (int i = 0; st == SEM_OK && i < n; ++i) {
            int child;
            st = param_ptr(r, idx, 2 + i, 0, &child);
            if (st != SEM_OK) break;
            if (r->entries[child].type == 116) continue; /* a point adds nothing to a loop */
            if (!is_curve_type(r->entries[child].type)) {
                st = entity_error(r, idx, token_line(r, idx, 2 + i),
                                  "member %d points to DE %d, a type-%d entity, not a curve",
                                  i + 1, de_number(child), r->entries[child].type);
                break;
            }
            st = read_curves(r, child, m, depth + 1, out);
        }
        e->busy = 0;
        if (st == SEM_OK) e->n_used = 2 + n;
        return st;
    }
    default:
        if (is_curve_type(e->type)) return unsupported(r, idx, "not supported, skipped");
        return entity_error(r, idx, 0, "a curve was expected here");
    }
    if (st != SEM_OK) return st;
    xf_apply(m, c.ctrl, (size_t)c.n_ctrl);
    st = curve_validate(r, idx, &c);
    if (st != SEM_OK) {
        sem_curve_free(&c);
        return st;
    }
    return list_push(r, out, &c);
}

/* One curve from an entity that must give exactly one (a composite is joined only when it
 * has a single member). */
static sem_status read_single_curve(iges_reader *r, int idx, const double *parent, int depth,
                                    int owner, sem_curve *c)
{
    curve_list l;
    memset(&l, 0, sizeof l);
    sem_status st = read_curves(r, idx, parent, depth, &l);
    if (st != SEM_OK) {
        list_free(&l);
        return st;
    }
    if (l.n != 1) {
        int pieces = l.n;
        list_free(&l);
        sem_model_warn(r->model, "entity %d (DE %d): curve DE %d has %d pieces; only single "
                                 "curves are supported here, surface skipped",
                       r->entries[owner].type, de_number(owner), de_number(idx), pieces);
        return SEM_ERR_UNSUPPORTED;
    }
    *c = l.c[0];
    free(l.c);
    return SEM_OK;
}

/* ------------------------------------------------------- surfaces ---- */

static int is_surface_type(int type)
{
    return type == 108 || type == 114 || type == 118 || type == 120 || type == 122 ||
           type == 128 || type == 140 || (type >= 190 && type <= 198 && type % 2 == 0);
}

static sem_status read_nurbs_surface(iges_reader *r, int idx, sem_surface *s)
{
    int v[9];
    sem_status st = need(r, idx, 1, 9, "rational B-spline surface header");
    for (int k = 0; st == SEM_OK && k < 9; ++k) st = param_int(r, idx, 1 + k, &v[k]);
    if (st != SEM_OK) return st;
    int K1 = v[0], K2 = v[1], M1 = v[2], M2 = v[3];
    if (M1 < 1 || M1 > SEM_MAX_DEGREE || M2 < 1 || M2 > SEM_MAX_DEGREE)
        return entity_error(r, idx, token_line(r, idx, 3), "degrees M1 = %d, M2 = %d out of "
                                                           "range 1..%d", M1, M2, SEM_MAX_DEGREE);
    if (K1 < M1 || K2 < M2)
        return entity_error(r, idx, token_line(r, idx, 1),
                            "degree (%d, %d) too high for a %d x %d control net", M1, M2, K1 + 1,
                            K2 + 1);
    long long n1 = (long long)K1 + 1, n2 = (long long)K2 + 1, nw = n1 * n2;
    long long nk1 = n1 + M1 + 1, nk2 = n2 + M2 + 1;
    st = need(r, idx, 10, nk1 + nk2 + 4 * nw + 4, "rational B-spline surface (K1, K2, M1, M2)");
    if (st != SEM_OK) return st;
    if (nk1 > SEM_MAX_KNOTS || nk2 > SEM_MAX_KNOTS)
        return entity_error(r, idx, token_line(r, idx, 1), "%lld x %lld knots; at most %d per "
                                                           "direction (limit SEM_MAX_KNOTS)",
                            nk1, nk2, SEM_MAX_KNOTS);
    if (nw > SEM_MAX_PART_CONTROL_POINTS)
        return entity_error(r, idx, token_line(r, idx, 1), "%lld x %lld control points; at most "
                                                           "%d per surface (limit "
                                                           "SEM_MAX_PART_CONTROL_POINTS)",
                            n1, n2, SEM_MAX_PART_CONTROL_POINTS);
    if ((st = count_points(r, idx, nw)) != SEM_OK) return st;
    if (sem_surface_alloc(s, M1, M2, (int)n1, (int)n2) != SEM_OK) return nomem(r);
    s->closed_u = v[4];
    s->closed_v = v[5];
    s->periodic_u = v[7];
    s->periodic_v = v[8];
    int k = 10;
    /* knots S, knots T, weights, points: exactly as written */
    double *dst[4] = {s->knots_u, s->knots_v, s->weights, s->ctrl};
    long long cnt[4] = {nk1, nk2, nw, 3 * nw};
    for (int a = 0; a < 4; ++a)
        for (long long i = 0; st == SEM_OK && i < cnt[a]; ++i)
            st = param_real(r, idx, k++, &dst[a][i]);
    double *range[4] = {&s->u0, &s->u1, &s->v0, &s->v1};
    for (int i = 0; st == SEM_OK && i < 4; ++i) st = param_real(r, idx, k++, range[i]);
    if (st != SEM_OK) {
        sem_surface_free(s);
        return st;
    }
    /* A range that is empty or leaves the knots (Rhino 2001 wrote U0 V0 U1 V1 in the wrong
     * order: corpus occt_rhino_bounded_143) is the knots' own, as Open CASCADE reads it. */
    double ua = s->knots_u[M1], ub = s->knots_u[n1], va = s->knots_v[M2], vb = s->knots_v[n2];
    double tu = 1e-9 * (ub - ua), tv = 1e-9 * (vb - va);
    if (ub > ua && vb > va &&
        (!(s->u1 > s->u0) || !(s->v1 > s->v0) || s->u0 < ua - tu || s->u1 > ub + tu ||
         s->v0 < va - tv || s->v1 > vb + tv)) {
        if (!r->entries[idx].repaired)
            sem_model_warn(r->model, "entity 128 (DE %d): parameter range [%g,%g] x [%g,%g] is "
                                     "empty or outside the knots; the knots' range [%g,%g] x "
                                     "[%g,%g] is used",
                           de_number(idx), s->u0, s->u1, s->v0, s->v1, ua, ub, va, vb);
        r->entries[idx].repaired = 1;
        s->u0 = ua, s->u1 = ub, s->v0 = va, s->v1 = vb;
    }
    r->entries[idx].n_used = k;
    return SEM_OK;
}

static void set_bilinear(sem_surface *s, const double o[3], const double e1[3],
                         const double e2[3], double u0, double u1, double v0, double v1)
{
    double uv[4][2] = {{u0, v0}, {u1, v0}, {u0, v1}, {u1, v1}};
    for (int k = 0; k < 4; ++k)
        for (int d = 0; d < 3; ++d) s->ctrl[3 * k + d] = o[d] + uv[k][0] * e1[d] + uv[k][1] * e2[d];
    s->knots_u[0] = s->knots_u[1] = s->u0 = u0;
    s->knots_u[2] = s->knots_u[3] = s->u1 = u1;
    s->knots_v[0] = s->knots_v[1] = s->v0 = v0;
    s->knots_v[2] = s->knots_v[3] = s->v1 = v1;
}

/* 108: the plane A x + B y + C z = D. A bounded plane (PTR to a closed curve) becomes the
 * bilinear patch over the bounding box of the curve's control points in an orthonormal
 * frame of the plane, trimmed by that curve mapped into the frame (an affine map, so the
 * trim curve is exact). An unbounded plane (PTR = 0) inside a trimmed entity or face with
 * model-space boundary curves is fitted to that boundary (surface_hint); elsewhere, with a
 * display SIZE, it becomes the square of half side SIZE centred at the display point
 * projected onto the plane. */
static sem_status read_plane(iges_reader *r, int idx, int depth, sem_part *part)
{
    double a[4], xyz[3], size;
    int ptr;
    sem_status st = need(r, idx, 1, 9, "plane");
    for (int k = 0; st == SEM_OK && k < 4; ++k) st = param_real(r, idx, 1 + k, &a[k]);
    if (st == SEM_OK) st = param_ptr(r, idx, 5, 1, &ptr);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = param_real(r, idx, 6 + k, &xyz[k]);
    if (st == SEM_OK) st = param_real(r, idx, 9, &size);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 10;
    double len = sqrt(a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
    if (!(len > 0)) return entity_error(r, idx, token_line(r, idx, 1), "plane normal is zero");
    double n[3] = {a[0] / len, a[1] / len, a[2] / len}, dist = a[3] / len;
    /* e1 = normalize(axis x n) with the axis least aligned with n; e2 = n x e1 */
    int ax = fabs(n[0]) <= fabs(n[1]) && fabs(n[0]) <= fabs(n[2]) ? 0
             : fabs(n[1]) <= fabs(n[2])                           ? 1
                                                                  : 2;
    double axis[3] = {0, 0, 0};
    axis[ax] = 1.0;
    double e1[3] = {axis[1] * n[2] - axis[2] * n[1], axis[2] * n[0] - axis[0] * n[2],
                    axis[0] * n[1] - axis[1] * n[0]};
    double l1 = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
    for (int d = 0; d < 3; ++d) e1[d] /= l1;
    double e2[3] = {n[1] * e1[2] - n[2] * e1[1], n[2] * e1[0] - n[0] * e1[2],
                    n[0] * e1[1] - n[1] * e1[0]};
    double off = n[0] * xyz[0] + n[1] * xyz[1] + n[2] * xyz[2] - dist;
    double o[3] = {xyz[0] - off * n[0], xyz[1] - off * n[1], xyz[2] - off * n[2]};
    if (sem_surface_alloc(&part->surface, 1, 1, 2, 2) != SEM_OK) return nomem(r);
    if (ptr < 0) {
        /* An unbounded plane inside a trimmed entity or face is sized by that boundary, with
         * or without a display size: SIZE only says how large to draw the plane's symbol
         * (CATIA writes 1.0 whatever the face), and taking it as the extent left the
         * boundary off the surface (occt_cone_catia, occt_cylinder_catia in the corpus). */
        if (r->surface_hint) {
            set_bilinear(&part->surface, o, e1, e2, -1.0, 1.0, -1.0, 1.0);
            r->from_hint = 1;
            r->hint_fit = HINT_PLANE;
            return SEM_OK;
        }
        if (!(size > 0)) {
            sem_surface_free(&part->surface);
            sem_model_warn(r->model, "entity 108 (DE %d): unbounded plane without a display "
                                     "size, skipped",
                           de_number(idx));
            return SEM_ERR_UNSUPPORTED;
        }
        set_bilinear(&part->surface, o, e1, e2, -size, size, -size, size);
        return SEM_OK;
    }
    curve_list l;
    memset(&l, 0, sizeof l);
    st = read_curves(r, ptr, identity_xf, depth + 1, &l);
    if (st != SEM_OK) {
        list_free(&l);
        sem_surface_free(&part->surface);
        return st;
    }
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (int i = 0; i < l.n; ++i) {
        sem_curve *c = &l.c[i];
        for (int j = 0; j < c->n_ctrl; ++j) {
            double *p = c->ctrl + 3 * j, q[3] = {p[0] - o[0], p[1] - o[1], p[2] - o[2]};
            p[0] = q[0] * e1[0] + q[1] * e1[1] + q[2] * e1[2];
            p[1] = q[0] * e2[0] + q[1] * e2[1] + q[2] * e2[2];
            p[2] = 0.0;
            for (int d = 0; d < 2; ++d) {
                lo[d] = fmin(lo[d], p[d]);
                hi[d] = fmax(hi[d], p[d]);
            }
        }
    }
    if (!(hi[0] > lo[0]) || !(hi[1] > lo[1])) {
        list_free(&l);
        sem_surface_free(&part->surface);
        return entity_error(r, idx, 0, "bounding curve DE %d encloses no area", de_number(ptr));
    }
    set_bilinear(&part->surface, o, e1, e2, lo[0], hi[0], lo[1], hi[1]);
    part->has_outer = 1;
    part->outer.n_curves = l.n;
    part->outer.curves = l.c;
    return SEM_OK;
}

/* 118: the segments between C1(t) and C2(t) for equal relative parameter t. The two curves
 * get one degree and one knot vector, and the surface is degree 1 across: rows C1 and C2. */
static sem_status read_ruled(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int p1, p2, dirflg;
    sem_status st = param_ptr(r, idx, 1, 0, &p1);
    if (st == SEM_OK) st = param_ptr(r, idx, 2, 0, &p2);
    if (st == SEM_OK) st = param_int(r, idx, 3, &dirflg);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = remaining(r, idx, 4) > 0 ? 5 : 4;
    sem_curve a, b;
    st = read_single_curve(r, p1, identity_xf, depth + 1, idx, &a);
    if (st != SEM_OK) return st;
    st = read_single_curve(r, p2, identity_xf, depth + 1, idx, &b);
    if (st != SEM_OK) {
        sem_curve_free(&a);
        return st;
    }
    if (!sem_curve_is_clamped(&a) || !sem_curve_is_clamped(&b)) {
        sem_curve_free(&a);
        sem_curve_free(&b);
        sem_model_warn(r->model, "entity 118 (DE %d): ruled surface over unclamped curves not "
                                 "supported, skipped", de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    if (r->entries[idx].form == 0 && (a.degree > 1 || b.degree > 1 || a.n_ctrl > 2 || b.n_ctrl > 2))
        sem_model_warn(r->model, "entity 118 (DE %d): ruled by equal parameter (form 1); equal "
                                 "arc length (form 0) is not exactly representable",
                       de_number(idx));
    sem_curve_normalize(&a);
    sem_curve_normalize(&b);
    if (dirflg == 1) curve_reverse(&b);
    st = sem_curves_make_compatible(&a, &b);
    if (st == SEM_OK && a.n_ctrl != b.n_ctrl) st = SEM_ERR_INVALID;
    if (st == SEM_ERR_INVALID) {
        sem_curve_free(&a);
        sem_curve_free(&b);
        sem_model_warn(r->model, "entity 118 (DE %d): ruled surface over discontinuous curves "
                                 "not supported, skipped", de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    if (st != SEM_OK) st = nomem(r);
    if (st == SEM_OK && sem_surface_alloc(s, a.degree, 1, a.n_ctrl, 2) != SEM_OK) st = nomem(r);
    if (st == SEM_OK) {
        memcpy(s->knots_u, a.knots, (size_t)(a.n_ctrl + a.degree + 1) * sizeof(double));
        s->knots_v[2] = s->knots_v[3] = 1.0;
        memcpy(s->ctrl, a.ctrl, (size_t)a.n_ctrl * 3 * sizeof(double));
        memcpy(s->ctrl + 3 * a.n_ctrl, b.ctrl, (size_t)b.n_ctrl * 3 * sizeof(double));
        memcpy(s->weights, a.weights, (size_t)a.n_ctrl * sizeof(double));
        memcpy(s->weights + a.n_ctrl, b.weights, (size_t)b.n_ctrl * sizeof(double));
        s->u0 = 0.0;
        s->u1 = 1.0;
        s->v0 = 0.0;
        s->v1 = 1.0;
    }
    sem_curve_free(&a);
    sem_curve_free(&b);
    return st;
}

/* 120: the generatrix C(t) rotated about the axis line from angle SA to TA. u is the
 * generatrix parameter, v the angle (knots in radians); each control point sweeps an exact
 * circle as a rational quadratic with pieces of at most 90 degrees (Piegl & Tiller A8.1). */
static sem_status read_revolution(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int pl, pc;
    double sa, ta;
    sem_status st = param_ptr(r, idx, 1, 0, &pl);
    if (st == SEM_OK) st = param_ptr(r, idx, 2, 0, &pc);
    if (st == SEM_OK) st = param_real(r, idx, 3, &sa);
    if (st == SEM_OK) st = param_real(r, idx, 4, &ta);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5;
    if (r->entries[pl].type != 110)
        return entity_error(r, idx, token_line(r, idx, 1),
                            "axis DE %d is a type-%d entity, not a line (110)", de_number(pl),
                            r->entries[pl].type);
    double sweep = ta - sa;
    if (!(sweep > 0) || sweep > 2 * M_PI * (1 + 1e-12))
        return entity_error(r, idx, token_line(r, idx, 3),
                            "rotation angles %.17g..%.17g do not give a sweep in (0, 2 pi]", sa,
                            ta);
    double p0[3], p1[3], m[12];
    st = read_line(r, pl, p0, p1);
    if (st == SEM_OK) st = own_xform(r, pl, identity_xf, m);
    if (st != SEM_OK) return st;
    xf_apply(m, p0, 1);
    xf_apply(m, p1, 1);
    double ax[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]};
    double al = sqrt(ax[0] * ax[0] + ax[1] * ax[1] + ax[2] * ax[2]);
    if (!(al > 0)) return entity_error(r, pl, 0, "axis line has zero length");
    for (int d = 0; d < 3; ++d) ax[d] /= al;
    sem_curve c;
    st = read_single_curve(r, pc, identity_xf, depth + 1, idx, &c);
    if (st != SEM_OK) return st;
    int nseg = (int)ceil(sweep / (M_PI / 2) - 1e-9);
    if (nseg < 1) nseg = 1;
    if (nseg > 4) nseg = 4;
    double dt = sweep / nseg, wm = cos(dt / 2);
    int nv = 2 * nseg + 1;
    if (sem_surface_alloc(s, c.degree, 2, c.n_ctrl, nv) != SEM_OK) {
        sem_curve_free(&c);
        return nomem(r);
    }
    memcpy(s->knots_u, c.knots, (size_t)(c.n_ctrl + c.degree + 1) * sizeof(double));
    int k = 0;
    for (int i = 0; i < 3; ++i) s->knots_v[k++] = sa;
    for (int i = 1; i < nseg; ++i) {
        s->knots_v[k++] = sa + i * dt;
        s->knots_v[k++] = sa + i * dt;
    }
    for (int i = 0; i < 3; ++i) s->knots_v[k++] = ta;
    for (int i = 0; i < c.n_ctrl; ++i) {
        const double *P = c.ctrl + 3 * i;
        double h = (P[0] - p0[0]) * ax[0] + (P[1] - p0[1]) * ax[1] + (P[2] - p0[2]) * ax[2];
        double O[3] = {p0[0] + h * ax[0], p0[1] + h * ax[1], p0[2] + h * ax[2]};
        double X[3] = {P[0] - O[0], P[1] - O[1], P[2] - O[2]};
        double Y[3] = {ax[1] * X[2] - ax[2] * X[1], ax[2] * X[0] - ax[0] * X[2],
                       ax[0] * X[1] - ax[1] * X[0]};
        for (int j = 0; j < nv; ++j) {
            double ang = sa + j * dt / 2, f = (j % 2) ? 1.0 / wm : 1.0;
            double cs = cos(ang) * f, sn = sin(ang) * f;
            double *Q = s->ctrl + 3 * ((size_t)i + (size_t)c.n_ctrl * j);
            for (int d = 0; d < 3; ++d) Q[d] = O[d] + cs * X[d] + sn * Y[d];
            s->weights[i + c.n_ctrl * j] = c.weights[i] * ((j % 2) ? wm : 1.0);
        }
    }
    s->u0 = c.t0;
    s->u1 = c.t1;
    s->v0 = sa;
    s->v1 = ta;
    sem_curve_free(&c);
    r->inexact_param = 1; /* v: the angle in the file, a rational circle's parameter here */
    return SEM_OK;
}

/* 122: the directrix C(t) swept along L - C(t0): degree 1 in v on [0, 1]. */
static sem_status read_tabulated(iges_reader *r, int idx, int depth, sem_surface *s)
{
    int pc;
    double L[3];
    sem_status st = param_ptr(r, idx, 1, 0, &pc);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = param_real(r, idx, 2 + k, &L[k]);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5;
    sem_curve c;
    st = read_single_curve(r, pc, identity_xf, depth + 1, idx, &c);
    if (st != SEM_OK) return st;
    /* IGES parameterizes a tabulated cylinder by t = t0 + u (t1 - t0), u in [0, 1]: the
     * file's trim curves use that u (corpus dealii_side_inch: a directrix on [0, 3] trimmed
     * in [0, 1] kept a third of the face). An affine map of the knots is exact. */
    if (c.t0 != 0.0 || c.t1 != 1.0) {
        double a = c.t0, b = c.t1;
        for (int i = 0; i < c.n_ctrl + c.degree + 1; ++i) c.knots[i] = (c.knots[i] - a) / (b - a);
        c.t0 = 0.0;
        c.t1 = 1.0;
    }
    double start[3];
    sem_curve_eval(&c, c.t0, start, NULL);
    double d[3] = {L[0] - start[0], L[1] - start[1], L[2] - start[2]};
    if (sem_surface_alloc(s, c.degree, 1, c.n_ctrl, 2) != SEM_OK) {
        sem_curve_free(&c);
        return nomem(r);
    }
    memcpy(s->knots_u, c.knots, (size_t)(c.n_ctrl + c.degree + 1) * sizeof(double));
    s->knots_v[2] = s->knots_v[3] = 1.0;
    for (int i = 0; i < c.n_ctrl; ++i) {
        for (int k = 0; k < 3; ++k) {
            s->ctrl[3 * i + k] = c.ctrl[3 * i + k];
            s->ctrl[3 * (i + c.n_ctrl) + k] = c.ctrl[3 * i + k] + d[k];
        }
        s->weights[i] = s->weights[i + c.n_ctrl] = c.weights[i];
    }
    s->u0 = c.t0;
    s->u1 = c.t1;
    s->v0 = 0.0;
    s->v1 = 1.0;
    sem_curve_free(&c);
    /* u: the directrix's own parameter in the file; ours for lines and B-splines only */
    if (r->entries[pc].type != 110 && r->entries[pc].type != 126) r->inexact_param = 1;
    return SEM_OK;
}

/* A point (116) or direction (123) entity's three coordinates. */
static sem_status read_vector(iges_reader *r, int owner, int k, int want, int allow_null,
                              double out[3], int *present)
{
    int p = -1;
    *present = 0;
    sem_status st = param_ptr(r, owner, k, allow_null, &p);
    if (st != SEM_OK || p < 0) return st;
    if (r->entries[p].type != want)
        return entity_error(r, owner, token_line(r, owner, k),
                            "parameter %d points to DE %d, a type-%d entity, where a %s (%d) is "
                            "expected",
                            k, de_number(p), r->entries[p].type,
                            want == 116 ? "point" : "direction", want);
    st = need(r, p, 1, 3, want == 116 ? "point" : "direction");
    for (int d = 0; st == SEM_OK && d < 3; ++d) st = param_real(r, p, 1 + d, &out[d]);
    if (st == SEM_OK) {
        r->entries[p].n_used = 4;
        *present = 1;
    }
    return st;
}

/* 190-198 (IGES 5.3 analytic surfaces) as exact NURBS (geometry/analytic_surfaces.c):
 * plane, right circular cylinder and cone, sphere, torus. Their parameters are ours, not the
 * file's, so their loops come from model space (from_hint); planes, cylinders and cones are
 * unbounded and need the boundary to size them (surface_hint), spheres and tori are whole. */
static sem_status read_analytic(iges_reader *r, int idx, sem_part *part)
{
    const iges_entry *e = &r->entries[idx];
    int type = e->type, form = e->form, have, have_axis = 0, have_ref = 0;
    double loc[3], axis[3] = {0, 0, 1}, ref[3], radius = 0, second = 0;
    sem_status st = read_vector(r, idx, 1, 116, 0, loc, &have);
    int k = 2;
    if (st == SEM_OK && type != 196) {
        st = read_vector(r, idx, 2, 123, 0, axis, &have_axis);
        k = 3;
    }
    if (st == SEM_OK && type != 190) st = param_real(r, idx, k++, &radius);
    if (st == SEM_OK && (type == 194 || type == 198)) st = param_real(r, idx, k++, &second);
    if (st == SEM_OK && type == 196 && form == 1) st = read_vector(r, idx, k++, 123, 1, axis, &have_axis);
    if (st == SEM_OK && form == 1) st = read_vector(r, idx, k++, 123, 1, ref, &have_ref);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = k;
    if (type != 190 && !(radius > 0))
        return entity_error(r, idx, 0, "radius must be positive (got %g)", radius);
    if (type == 198 && !(second > 0 && second < radius))
        return entity_error(r, idx, 0, "minor radius must be in (0, major radius) (got %g)", second);
    if (type == 194 && !(fabs(second) < 90))
        return entity_error(r, idx, 0, "cone semi-angle must be below 90 degrees (got %g)", second);
    int bounded = type == 196 || type == 198;
    if (!bounded && !r->surface_hint) {
        const char *d = entity_description(type);
        sem_model_warn(r->model, "entity %d (DE %d): unbounded %s outside a trimmed face, skipped",
                       type, de_number(idx), d ? d : "surface");
        return SEM_ERR_UNSUPPORTED;
    }
    sem_frame f;
    sem_error ferr;
    if (sem_frame_make(loc, axis, have_ref ? ref : NULL, &f, &ferr) != SEM_OK)
        return entity_error(r, idx, 0, "axis or normal direction is zero");
    switch (type) {
    case 190: st = sem_analytic_plane(&part->surface, &f, 1.0, &ferr); break;
    case 192: st = sem_analytic_cone(&part->surface, &f, radius, 0.0, 0.0, 1.0, &ferr); break;
    case 194:
        st = sem_analytic_cone(&part->surface, &f, radius, tan(second * M_PI / 180.0), 0.0, 1.0,
                               &ferr);
        break;
    case 196: st = sem_analytic_sphere(&part->surface, &f, radius, &ferr); break;
    default: st = sem_analytic_torus(&part->surface, &f, radius, second, &ferr); break;
    }
    if (st != SEM_OK) return nomem(r);
    r->from_hint = 1;
    r->hint_fit = type == 190 ? HINT_PLANE : (type == 192 || type == 194) ? HINT_AXIAL : HINT_NONE;
    /* form 0 does not say where the seam is: place it by the face's boundary */
    r->hint_seam = type != 190 && !have_ref;
    return SEM_OK;
}

/* Any surface entity as a NURBS surface in the coordinates parent o (own transform). A
 * bounded plane also fills part->outer. */
static sem_status read_surface(iges_reader *r, int idx, const double *parent, int depth,
                               sem_part *part)
{
    iges_entry *e = &r->entries[idx];
    double m[12];
    sem_status st = enter_entity(r, idx, parent, depth, m);
    if (st != SEM_OK) return st;
    e->busy = 1;
    switch (e->type) {
    case 128: st = read_nurbs_surface(r, idx, &part->surface); break;
    case 108: st = read_plane(r, idx, depth, part); break;
    case 118: st = read_ruled(r, idx, depth, &part->surface); break;
    case 120: st = read_revolution(r, idx, depth, &part->surface); break;
    case 122: st = read_tabulated(r, idx, depth, &part->surface); break;
    case 190:
    case 192:
    case 194:
    case 196:
    case 198: st = read_analytic(r, idx, part); break;
    default:
        st = is_surface_type(e->type) ? unsupported(r, idx, "not supported, skipped")
                                      : entity_error(r, idx, 0, "a surface was expected here");
    }
    e->busy = 0;
    sem_surface *s = &part->surface;
    if (st == SEM_OK && e->type != 128) {
        /* analytic surfaces are built from their curves: count the net now */
        st = count_points(r, idx, (long long)s->n_u * s->n_v);
        if (st != SEM_OK) sem_part_free(part);
    }
    if (st != SEM_OK) return st;
    xf_apply(m, s->ctrl, (size_t)s->n_u * (size_t)s->n_v);
    sem_error ve;
    if (sem_surface_validate(s, &ve) != SEM_OK) {
        sem_part_free(part);
        return entity_error(r, idx, 0, "%s", ve.message);
    }
    return SEM_OK;
}

static sem_status surface_pointer(iges_reader *r, int idx, int k, int *out)
{
    sem_status st = param_ptr(r, idx, k, 0, out);
    if (st != SEM_OK) return st;
    if (!is_surface_type(r->entries[*out].type))
        return entity_error(r, idx, token_line(r, idx, k),
                            "parameter %d points to DE %d, a type-%d entity, where a surface is "
                            "expected",
                            k, de_number(*out), r->entries[*out].type);
    return SEM_OK;
}

/* ----------------------------------------------------------- parts ---- */

static int peek_int(const iges_reader *r, int idx, int k, int *out)
{
    const iges_entry *e = &r->entries[idx];
    if (k < 1 || k >= e->n_params) return 0;
    const iges_token *t = &r->tokens[e->first_token + (size_t)k];
    double v;
    if (t->is_string || parse_real(r->ptext + t->offset, t->length, 0.0, &v) != 1) return 0;
    if (v != floor(v) || fabs(v) > 1e9) return 0;
    *out = (int)v;
    return 1;
}

static int peek_ptr(const iges_reader *r, int idx, int k, int *out)
{
    int v;
    if (!peek_int(r, idx, k, &v)) return 0;
    if (v < 0) v = -v;
    if (v < 1 || v > 2 * r->n_entries - 1 || v % 2 == 0) return 0;
    *out = (v - 1) / 2;
    return 1;
}

/* The name property (406 form 15) among the entity's trailing property pointers. */
static int property_name(const iges_reader *r, int idx, char *name, size_t size)
{
    const iges_entry *e = &r->entries[idx];
    int k = e->n_used, na, np;
    if (k <= 0 || !peek_int(r, idx, k, &na) || na < 0 || na > remaining(r, idx, k)) return 0;
    k += 1 + na;
    if (!peek_int(r, idx, k, &np) || np < 0 || np > remaining(r, idx, k)) return 0;
    for (int j = 0; j < np; ++j) {
        int p;
        if (!peek_ptr(r, idx, k + 1 + j, &p)) continue;
        const iges_entry *q = &r->entries[p];
        if (q->type != 406 || q->form != 15) continue;
        const char *s;
        int len;
        param_string(r, p, 2, &s, &len);
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
        if (t->is_string || parse_real(r->ptext + t->offset, t->length, 0.0, &percent) != 1) return 0;
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
    if (st != SEM_OK) return nomem(r);
    int type = r->entries[top].type;
    if (fix.widest_gap > 0)
        sem_model_warn(r->model, "entity %d (DE %d): a gap of %.3g between trim curves is bridged "
                                 "(allowed %.3g: the file's resolution or 1e-4 of the surface)",
                       type, de_number(top), fix.widest_gap, fix.gap_limit);
    if (fix.outer_dropped)
        sem_model_warn(r->model, "entity %d (DE %d): the outer trim loop does not close (a gap "
                                 "wider than %.3g); that loop is left out",
                       type, de_number(top), fix.gap_limit);
    if (fix.holes_dropped)
        sem_model_warn(r->model, "entity %d (DE %d): %d hole trim loop%s not close (a gap wider "
                                 "than %.3g); left out",
                       type, de_number(top), fix.holes_dropped, fix.holes_dropped == 1 ? " does" : "s do",
                       fix.gap_limit);
    if (fix.wound)
        sem_model_warn(r->model, "entity %d (DE %d): the trim loops wind around the closed "
                                 "surface and cannot share one period of it; they are kept as "
                                 "written",
                       type, de_number(top));
    return SEM_OK;
}

/* Names, colour and source, then the checks every part must pass, then into the model. */
static sem_status finish_part(iges_reader *r, sem_part *part, int top, int surf)
{
    if (!property_name(r, top, part->name, sizeof part->name) &&
        !property_name(r, surf, part->name, sizeof part->name) &&
        !label_name(r, top, part->name, sizeof part->name))
        label_name(r, surf, part->name, sizeof part->name);
    part->source_entity = de_number(surf);
    part->color = r->entries[top].color ? r->entries[top].color : r->entries[surf].color;
    part->has_rgb = color_rgb(r, part->color, part->rgb);
    if (r->model->n_parts >= SEM_MAX_PARTS) {
        sem_part_free(part);
        return entity_error(r, top, 0, "the model would have more than %d parts (limit "
                                       "SEM_MAX_PARTS)", SEM_MAX_PARTS);
    }
    sem_status fs = fix_loops(r, part, top);
    if (fs != SEM_OK) {
        sem_part_free(part);
        return fs;
    }
    sem_error ve;
    if (sem_part_validate_trims(part, &ve) != SEM_OK) {
        sem_part_free(part);
        return entity_error(r, top, 0, "surface DE %d: %s", de_number(surf), ve.message);
    }
    sem_status st = sem_model_take_part(r->model, part, r->err);
    if (st != SEM_OK) sem_part_free(part);
    return st;
}

static sem_status add_hole(iges_reader *r, sem_part *part, curve_list *l)
{
    sem_trim_loop *h = realloc(part->holes, (size_t)(part->n_holes + 1) * sizeof *h);
    if (!h) return nomem(r);
    part->holes = h;
    h[part->n_holes].n_curves = l->n;
    h[part->n_holes].curves = l->c;
    part->n_holes++;
    memset(l, 0, sizeof *l);
    return SEM_OK;
}

static void set_outer(sem_part *part, curve_list *l)
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
static sem_status project_model_space_loop(iges_reader *r, int idx, const sem_part *part,
                                           curve_list *model_space, curve_list *l, int *border)
{
    *border = 0;
    if (model_space->n == 0) {
        sem_model_warn(r->model, "entity %d (DE %d): boundary has neither parameter-space nor "
                                 "model-space curves; that loop is left out",
                       r->entries[idx].type, de_number(idx));
        return SEM_ERR_UNSUPPORTED;
    }
    sem_surface_sampler sampler;
    sem_error perr;
    sem_status st = sem_surface_sampler_build(&part->surface, &sampler, &perr);
    if (st == SEM_ERR_NOMEM) return nomem(r);
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
                       r->entries[idx].type, de_number(idx), gap, settings.max_gap);
    sem_surface_sampler_free(&sampler);
    if (st == SEM_ERR_NOMEM) return nomem(r);
    if (st != SEM_OK) {
        sem_model_warn(r->model, "entity %d (DE %d): boundary given in model space only could "
                                 "not be projected onto its surface (%s); that loop is left out",
                       r->entries[idx].type, de_number(idx), perr.message);
        return SEM_ERR_UNSUPPORTED;
    }
    list_free(l);
    l->n = l->cap = loop.n_curves;
    l->c = loop.curves;
    return SEM_OK;
}

/* The 142 at parameter k of owner, checked. */
static sem_status curve_on_surface_entity(iges_reader *r, int owner, int k, int *p)
{
    sem_status st = param_ptr(r, owner, k, 0, p);
    if (st != SEM_OK) return st;
    if (r->entries[*p].type != 142)
        return entity_error(r, owner, token_line(r, owner, k),
                            "parameter %d points to DE %d, a type-%d entity, where a curve on a "
                            "surface (142) is expected",
                            k, de_number(*p), r->entries[*p].type);
    st = need(r, *p, 1, 5, "curve on a parametric surface");
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
    if (st == SEM_OK) st = param_ptr(r, p, 3, 1, &bptr);
    if (st == SEM_OK) st = param_ptr(r, p, 4, 1, &cptr);
    if (st != SEM_OK) return st;
    /* model_space 2 (inexact parameters): the model-space curve when there is one */
    if (bptr >= 0 && (!model_space || (model_space == 2 && cptr < 0)))
        return read_curves(r, bptr, identity_xf, depth + 1, l);
    if (cptr < 0) {
        sem_model_warn(r->model, "entity 142 (DE %d): no parameter-space curve (BPTR = 0) and no "
                                 "model-space curve (CPTR = 0); the loop is left out",
                       de_number(p));
        return SEM_ERR_UNSUPPORTED;
    }
    curve_list c;
    memset(&c, 0, sizeof c);
    st = read_curves(r, cptr, m, depth + 1, &c);
    if (st == SEM_OK) st = project_model_space_loop(r, p, part, &c, l, border);
    list_free(&c);
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
        if (param_ptr(r, p, 4, 1, &cptr) != SEM_OK || cptr < 0) continue;
        curve_list c;
        memset(&c, 0, sizeof c);
        if (read_curves(r, cptr, m, depth + 1, &c) != SEM_OK) {
            list_free(&c); /* a composite that failed part-way keeps the members it read */
            continue;
        }
        for (int j = 0; j < c.n; ++j)
            if (list_push(r, hint, &c.c[j]) != SEM_OK) sem_curve_free(&c.c[j]);
        free(c.c);
    }
}

/* Reads the surface of a trimmed entity; an unbounded plane is fitted to the hint curves.
 * *from_hint: 1 it was (its loops must then come from model space); 2 the surface's
 * parameters are not the file's (inexact_param: its loops come from model space where the
 * file gives them there). */
static sem_status read_trimmed_surface(iges_reader *r, int surf, const double *m, int depth,
                                       const curve_list *hint, sem_part *part, int *from_hint)
{
    r->surface_hint = hint->n > 0;
    r->from_hint = 0;
    r->hint_fit = HINT_NONE;
    r->hint_seam = 0;
    r->inexact_param = 0;
    sem_status st = read_surface(r, surf, m, depth + 1, part);
    r->surface_hint = 0;
    /* 1: the loops must come from model space; 2: better from there (inexact_param) */
    *from_hint = st != SEM_OK ? 0 : r->from_hint ? 1 : r->inexact_param ? 2 : 0;
    if (*from_hint == 1 && (r->hint_fit != HINT_NONE || r->hint_seam) && hint->n > 0) {
        size_t n = 0;
        for (int i = 0; i < hint->n; ++i) n += (size_t)hint->c[i].n_ctrl;
        double *points = malloc((n ? n : 1) * 3 * sizeof *points);
        if (!points) {
            sem_part_free(part);
            return nomem(r);
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
static int needs_hint(const iges_reader *r, int surf)
{
    int t = r->entries[surf].type;
    return t == 108 || (t >= 190 && t <= 198 && t % 2 == 0);
}

static sem_status emit_trimmed(iges_reader *r, int idx, const double *parent, int depth)
{
    int surf, n1, n2;
    sem_status st = surface_pointer(r, idx, 1, &surf);
    if (st == SEM_OK) st = param_int(r, idx, 2, &n1);
    if (st == SEM_OK) st = param_int(r, idx, 3, &n2);
    if (st == SEM_OK) st = need(r, idx, 5, n2, "trimmed surface (N2 inner boundaries)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 5 + n2;
    double m[12];
    st = own_xform(r, idx, parent, m);
    curve_list hint;
    memset(&hint, 0, sizeof hint);
    if (st == SEM_OK && needs_hint(r, surf)) trimmed_hint(r, idx, n1, n2, m, depth, &hint);
    sem_part part;
    memset(&part, 0, sizeof part);
    int model_space = 0;
    if (st == SEM_OK) st = read_trimmed_surface(r, surf, m, depth, &hint, &part, &model_space);
    list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    curve_list l;
    memset(&l, 0, sizeof l);
    int border = 0;
    if (n1 != 0) {
        st = curve_on_surface(r, idx, 4, depth, m, &part, model_space, &l, &border);
        if (st == SEM_OK && !border) set_outer(&part, &l);
    }
    for (int i = 0; (st == SEM_OK || st == SEM_ERR_UNSUPPORTED) && i < n2; ++i) {
        list_free(&l);
        st = curve_on_surface(r, idx, 5 + i, depth, m, &part, model_space, &l, &border);
        if (st == SEM_OK && !border) st = add_hole(r, &part, &l);
    }
    list_free(&l);
    if (st != SEM_OK && st != SEM_ERR_UNSUPPORTED) {
        sem_part_free(&part);
        return st;
    }
    return finish_part(r, &part, idx, surf);
}

/* One 141 boundary: its parameter-space curves, reversed where SENSE = 2; when some curve
 * has none, the model-space curves (in the coordinates m of the surface) projected onto the
 * part's surface instead. */
static sem_status boundary_loop(iges_reader *r, int idx, const double *m, int depth,
                                const sem_part *part, int model_space, curve_list *l, int *border)
{
    *border = 0;
    if (r->entries[idx].type != 141)
        return entity_error(r, idx, 0, "a boundary entity (141) was expected here");
    int type, n;
    sem_status st = param_int(r, idx, 1, &type);
    if (st == SEM_OK) st = param_int(r, idx, 4, &n);
    if (st == SEM_OK) st = need(r, idx, 5, 3LL * n, "boundary (N curves)");
    if (st != SEM_OK) return st;
    int k = 5, missing = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int sense, kk;
        st = param_int(r, idx, k + 1, &sense);
        if (st == SEM_OK) st = param_int(r, idx, k + 2, &kk);
        if (st == SEM_OK) st = need(r, idx, k + 3, kk, "boundary curve (K parameter curves)");
        if (st != SEM_OK) break;
        if (kk == 0) missing = 1;
        int first = l->n;
        for (int j = 0; st == SEM_OK && j < kk; ++j) {
            int p = -1;
            st = param_ptr(r, idx, k + 3 + j, 0, &p);
            if (st == SEM_OK) st = read_curves(r, p, identity_xf, depth + 1, l);
        }
        if (st == SEM_OK && sense == 2) reverse_curves(l, first);
        k += 3 + kk;
    }
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = k;
    if (!missing && n > 0 && !model_space) return SEM_OK;
    list_free(l);

    /* the model-space curves (parameter 5, 5 + 3 + K1, ...) in loop order */
    curve_list model_curves;
    memset(&model_curves, 0, sizeof model_curves);
    k = 5;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int crv, sense, kk = 0, first = model_curves.n;
        st = param_ptr(r, idx, k, 0, &crv);
        if (st == SEM_OK) st = param_int(r, idx, k + 1, &sense);
        if (st == SEM_OK) st = param_int(r, idx, k + 2, &kk);
        if (st == SEM_OK) st = read_curves(r, crv, m, depth + 1, &model_curves);
        if (st == SEM_OK && sense == 2) reverse_curves(&model_curves, first);
        k += 3 + kk;
    }
    if (st == SEM_OK && !part) {
        /* only the curves are wanted (a hint for the surface) */
        for (int i = 0; i < model_curves.n; ++i)
            if (list_push(r, l, &model_curves.c[i]) != SEM_OK) sem_curve_free(&model_curves.c[i]);
        free(model_curves.c);
        return SEM_OK;
    }
    if (st == SEM_OK) st = project_model_space_loop(r, idx, part, &model_curves, l, border);
    list_free(&model_curves);
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

static sem_status emit_bounded(iges_reader *r, int idx, const double *parent, int depth)
{
    int surf, n;
    sem_status st = surface_pointer(r, idx, 2, &surf);
    if (st == SEM_OK) st = param_int(r, idx, 3, &n);
    if (st == SEM_OK) st = need(r, idx, 4, n, "bounded surface (N boundaries)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 4 + n;
    double m[12];
    st = own_xform(r, idx, parent, m);
    /* a surface that needs its boundary to be sized: every boundary's model-space curves */
    curve_list hint;
    memset(&hint, 0, sizeof hint);
    for (int i = 0; st == SEM_OK && needs_hint(r, surf) && i < n; ++i) {
        int b, border;
        if (param_ptr(r, idx, 4 + i, 0, &b) == SEM_OK)
            (void)boundary_loop(r, b, m, depth + 1, NULL, 1, &hint, &border);
    }
    sem_part part;
    memset(&part, 0, sizeof part);
    int model_space = 0;
    if (st == SEM_OK) st = read_trimmed_surface(r, surf, m, depth, &hint, &part, &model_space);
    list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    /* The loops first, then which one is outer: a 143 does not say (I-DEAS lists a plate's
     * hole before its border: corpus occt_ideas_simple1_143), so the outer loop is the one
     * whose (u,v) box holds every other loop's (the first when none does, as written), and
     * none when a boundary is the surface's own border (the others are holes in it). */
    curve_list *loops = calloc((size_t)(n > 0 ? n : 1), sizeof *loops);
    if (!loops) {
        sem_part_free(&part);
        return nomem(r);
    }
    int n_loops = 0, no_outer = 0;
    for (int i = 0; (st == SEM_OK || st == SEM_ERR_UNSUPPORTED) && i < n; ++i) {
        int b, border = 0;
        st = param_ptr(r, idx, 4 + i, 0, &b);
        if (st == SEM_OK)
            st = boundary_loop(r, b, m, depth + 1, &part, model_space, &loops[n_loops], &border);
        /* border: the surface's own, nothing to trim; a first boundary left out (warned):
         * the rest are taken as holes, as written */
        if ((st == SEM_OK && border) || (i == 0 && st != SEM_OK)) no_outer = 1;
        if (st == SEM_OK && !border && loops[n_loops].n > 0) n_loops++;
        else list_free(&loops[n_loops]);
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
    if (outer >= 0) set_outer(&part, &loops[outer]);
    for (int a = 0; a < n_loops; ++a) {
        if (a != outer && (st == SEM_OK || st == SEM_ERR_UNSUPPORTED)) st = add_hole(r, &part, &loops[a]);
        list_free(&loops[a]);
    }
    free(loops);
    if (st != SEM_OK && st != SEM_ERR_UNSUPPORTED) {
        sem_part_free(&part);
        return st;
    }
    return finish_part(r, &part, idx, surf);
}

/* Model-space curve of edge `index` (1-based) of a 504 edge list, in the coordinates m. */
static sem_status edge_curve(iges_reader *r, int owner, int k, int list, int index,
                             const double *m, int depth, curve_list *l)
{
    int n, crv;
    sem_status st = param_int(r, list, 1, &n);
    if (st == SEM_OK) st = need(r, list, 2, 5LL * n, "edge list (N edges)");
    if (st != SEM_OK) return st;
    if (index < 1 || index > n)
        return entity_error(r, owner, token_line(r, owner, k),
                            "edge index %d is outside edge list DE %d (%d edges)", index,
                            de_number(list), n);
    r->entries[list].n_used = 2 + 5 * n;
    st = param_ptr(r, list, 2 + 5 * (index - 1), 0, &crv);
    if (st == SEM_OK) st = read_curves(r, crv, m, depth + 1, l);
    return st;
}

/* A 508 loop: the parameter-space curves of its edges in order into l, and (for faces
 * whose edges lack them) the edges' model-space curves, in the coordinates m, into
 * model_space. *missing: some edge had no parameter-space curve. */
static sem_status face_loop(iges_reader *r, int idx, const double *m, int depth, curve_list *l,
                            curve_list *model_space, int force_model_space, int *missing)
{
    if (r->entries[idx].type != 508)
        return entity_error(r, idx, 0, "a loop entity (508) was expected here");
    int n;
    sem_status st = param_int(r, idx, 1, &n);
    if (st == SEM_OK) st = need(r, idx, 2, 5LL * n, "loop (N edges)");
    int k = 2;
    *missing = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int type, edge, kk;
        st = need(r, idx, k, 5, "loop edge");
        if (st == SEM_OK) st = param_int(r, idx, k, &type);
        if (st == SEM_OK) st = param_ptr(r, idx, k + 1, 0, &edge);
        if (st == SEM_OK) st = param_int(r, idx, k + 4, &kk);
        if (st == SEM_OK) st = need(r, idx, k + 5, 2LL * kk, "loop edge (K parameter curves)");
        if (st != SEM_OK) break;
        int want = type == 1 ? 502 : 504;
        if (r->entries[edge].type != want) {
            st = entity_error(r, idx, token_line(r, idx, k + 1),
                              "edge %d points to DE %d, a type-%d entity, where a %d is expected",
                              i + 1, de_number(edge), r->entries[edge].type, want);
            break;
        }
        if (type != 1 && kk == 0) *missing = 1;
        for (int j = 0; st == SEM_OK && j < kk; ++j) {
            int p = -1;
            st = param_ptr(r, idx, k + 6 + 2 * j, 0, &p);
            if (st == SEM_OK) st = read_curves(r, p, identity_xf, depth + 1, l);
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
        st = param_int(r, idx, k, &type);
        if (st == SEM_OK) st = param_ptr(r, idx, k + 1, 0, &edge);
        if (st == SEM_OK) st = param_int(r, idx, k + 2, &index);
        if (st == SEM_OK) st = param_int(r, idx, k + 3, &forward);
        if (st == SEM_OK) st = param_int(r, idx, k + 4, &kk);
        int first = model_space->n;
        if (st == SEM_OK && type != 1)
            st = edge_curve(r, idx, k + 2, edge, index, m, depth, model_space);
        /* OF = 0: the loop runs the edge backwards (this matters for closed edges, whose
         * direction cannot be told from their ends) */
        if (st == SEM_OK && !forward) reverse_curves(model_space, first);
        k += 5 + 2 * kk;
    }
    return st;
}

static sem_status emit_face(iges_reader *r, int idx, const double *parent, int depth)
{
    if (r->entries[idx].type != 510)
        return entity_error(r, idx, 0, "a face entity (510) was expected here");
    int surf, n, of;
    sem_status st = surface_pointer(r, idx, 1, &surf);
    if (st == SEM_OK) st = param_int(r, idx, 2, &n);
    if (st == SEM_OK) st = param_int(r, idx, 3, &of);
    if (st == SEM_OK) st = need(r, idx, 4, n, "face (N loops)");
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 4 + n;
    double m[12];
    st = own_xform(r, idx, parent, m);
    curve_list l, model_space, hint;
    memset(&l, 0, sizeof l);
    memset(&model_space, 0, sizeof model_space);
    memset(&hint, 0, sizeof hint);
    /* a surface that needs its boundary to be sized: every loop's edges */
    for (int i = 0; st == SEM_OK && needs_hint(r, surf) && i < n; ++i) {
        int p, missing;
        list_free(&l);
        if (param_ptr(r, idx, 4 + i, 0, &p) == SEM_OK)
            (void)face_loop(r, p, m, depth + 1, &l, &hint, 1, &missing);
    }
    list_free(&l);
    sem_part part;
    memset(&part, 0, sizeof part);
    int from_hint = 0;
    if (st == SEM_OK) st = read_trimmed_surface(r, surf, m, depth, &hint, &part, &from_hint);
    list_free(&hint);
    if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
    if (st != SEM_OK) return st;
    int failed = 0;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int p, missing = 0, border = 0;
        list_free(&l);
        list_free(&model_space);
        st = param_ptr(r, idx, 4 + i, 0, &p);
        if (st == SEM_OK) st = face_loop(r, p, m, depth + 1, &l, &model_space, from_hint, &missing);
        if (st == SEM_OK && (missing || from_hint)) {
            /* no (u,v) curves for this loop: project its edges' model-space curves */
            st = project_model_space_loop(r, p, &part, &model_space, &l, &border);
        }
        if (st == SEM_ERR_UNSUPPORTED) {
            failed = 1;
            st = SEM_OK;
            continue;
        }
        if (st != SEM_OK) break;
        if (border) continue; /* the surface's own border: nothing to trim */
        if (i == 0 && of == 1)
            set_outer(&part, &l);
        else
            st = add_hole(r, &part, &l);
    }
    list_free(&l);
    list_free(&model_space);
    if (st != SEM_OK) {
        sem_part_free(&part);
        return st;
    }
    if (failed) {
        /* without every loop the face cannot be trimmed consistently (the failing loop
         * said why) */
        sem_model_warn(r->model, "entity 510 (DE %d): a loop of the face could not be built; "
                                 "the face is kept untrimmed",
                       de_number(idx));
        sem_part keep;
        memset(&keep, 0, sizeof keep);
        keep.surface = part.surface;
        memset(&part.surface, 0, sizeof part.surface);
        sem_part_free(&part);
        part = keep;
    }
    return finish_part(r, &part, idx, surf);
}

static sem_status emit_shell(iges_reader *r, int idx, const double *parent, int depth)
{
    if (r->entries[idx].type != 514)
        return entity_error(r, idx, 0, "a shell entity (514) was expected here");
    int n;
    sem_status st = param_int(r, idx, 1, &n);
    if (st == SEM_OK) st = need(r, idx, 2, 2LL * n, "shell (N faces)");
    double m[12];
    if (st == SEM_OK) st = own_xform(r, idx, parent, m);
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int f = -1;
        st = param_ptr(r, idx, 2 + 2 * i, 0, &f);
        if (st == SEM_OK) st = emit_face(r, f, m, depth + 1);
    }
    if (st == SEM_OK) r->entries[idx].n_used = 2 + 2 * n;
    return st;
}

static sem_status emit_solid(iges_reader *r, int idx, const double *parent, int depth)
{
    int shell, nvoid;
    sem_status st = param_ptr(r, idx, 1, 0, &shell);
    if (st == SEM_OK) st = param_int(r, idx, 3, &nvoid);
    if (st == SEM_OK) st = need(r, idx, 4, 2LL * nvoid, "B-rep solid (N voids)");
    double m[12];
    if (st == SEM_OK) st = own_xform(r, idx, parent, m);
    if (st == SEM_OK) st = emit_shell(r, shell, m, depth + 1);
    for (int i = 0; st == SEM_OK && i < nvoid; ++i) {
        int v;
        st = param_ptr(r, idx, 4 + 2 * i, 0, &v);
        if (st == SEM_OK) st = emit_shell(r, v, m, depth + 1);
    }
    if (st == SEM_OK) r->entries[idx].n_used = 4 + 2 * nvoid;
    return st;
}

static sem_status emit_entity(iges_reader *r, int idx, const double *parent, int depth);

/* 408: the members of a 308 definition, scaled by S, moved by (X, Y, Z), then transformed
 * by the instance's own matrix (and the definition's). */
static sem_status emit_instance(iges_reader *r, int idx, const double *parent, int depth)
{
    int def;
    double x[3], s;
    sem_status st = param_ptr(r, idx, 1, 0, &def);
    for (int k = 0; st == SEM_OK && k < 3; ++k) st = param_real(r, idx, 2 + k, &x[k]);
    s = 1.0; /* IGES default scale when the parameter is absent or empty */
    if (st == SEM_OK && remaining(r, idx, 5) > 0) st = param_real_def(r, idx, 5, 1.0, &s);
    if (st != SEM_OK) return st;
    r->entries[idx].n_used = 6;
    iges_entry *d = &r->entries[def];
    if (d->type != 308)
        return entity_error(r, idx, token_line(r, idx, 1),
                            "parameter 1 points to DE %d, a type-%d entity, where a subfigure "
                            "definition (308) is expected",
                            de_number(def), d->type);
    if (!(s != 0)) return entity_error(r, idx, token_line(r, idx, 5), "scale factor is zero");
    if (d->busy || depth > IGES_MAX_DEPTH)
        return entity_error(r, idx, 0, "subfigure instances nest cyclically or deeper than %d",
                            IGES_MAX_DEPTH);
    double own[12], place[12] = {s, 0, 0, x[0], 0, s, 0, x[1], 0, 0, s, x[2]}, m[12];
    st = own_xform(r, idx, parent, own);
    if (st != SEM_OK) return st;
    xf_compose(own, place, m);
    st = own_xform(r, def, m, m);
    int n;
    if (st == SEM_OK) st = param_int(r, def, 3, &n);
    if (st == SEM_OK) st = need(r, def, 4, n, "subfigure definition (N entities)");
    if (st != SEM_OK) return st;
    d->n_used = 4 + n;
    d->busy = 1;
    for (int i = 0; st == SEM_OK && i < n; ++i) {
        int child;
        st = param_ptr(r, def, 4 + i, 0, &child);
        if (st == SEM_OK && !r->entries[child].self_ref) st = emit_entity(r, child, m, depth + 1);
    }
    d->busy = 0;
    return st;
}

static sem_status emit_entity(iges_reader *r, int idx, const double *parent, int depth)
{
    if (depth > IGES_MAX_DEPTH)
        return entity_error(r, idx, 0, "entities nest deeper than %d", IGES_MAX_DEPTH);
    sem_status cst = count_conversion(r, idx);
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
        sem_status st = read_surface(r, idx, parent, depth, &part);
        if (st == SEM_ERR_UNSUPPORTED) return SEM_OK;
        if (st != SEM_OK) return st;
        return finish_part(r, &part, idx, idx);
    }
    case 143: return emit_bounded(r, idx, parent, depth);
    case 144: return emit_trimmed(r, idx, parent, depth);
    case 186: return emit_solid(r, idx, parent, depth);
    case 514: return emit_shell(r, idx, parent, depth);
    case 510: return emit_face(r, idx, parent, depth);
    case 408: return emit_instance(r, idx, parent, depth);
    default:
        if (entity_description(type)) unsupported(r, idx, "not supported, skipped");
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
        if (peek_ptr(r, i, (K), &p)) {                                                   \
            if (p == i) self = 1;                                                        \
            else r->entries[p].referenced = 1;                                           \
        }                                                                                \
    } while (0)
        switch (e->type) {
        case 102:
            if (peek_int(r, i, 1, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(2 + j);
            break;
        case 108: list[nl++] = 5; break;
        case 118: list[nl++] = 1; list[nl++] = 2; break;
        case 120: list[nl++] = 1; list[nl++] = 2; break;
        case 122: list[nl++] = 1; break;
        case 140: list[nl++] = 5; break;
        case 141:
            MARK(3);
            if (!peek_int(r, i, 4, &n)) break;
            k = 5;
            for (int j = 0; j < n && k < e->n_params; ++j) {
                MARK(k);
                if (!peek_int(r, i, k + 2, &kk) || kk < 0) break;
                for (int q = 0; q < kk && q < e->n_params; ++q) MARK(k + 3 + q);
                k += 3 + kk;
            }
            break;
        case 142: list[nl++] = 2; list[nl++] = 3; list[nl++] = 4; break;
        case 143:
            MARK(2);
            if (peek_int(r, i, 3, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(4 + j);
            break;
        case 144:
            MARK(1);
            MARK(4);
            if (peek_int(r, i, 3, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(5 + j);
            break;
        case 186:
            MARK(1);
            if (peek_int(r, i, 3, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(4 + 2 * j);
            break;
        case 514:
            if (peek_int(r, i, 1, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(2 + 2 * j);
            break;
        case 510:
            MARK(1);
            if (peek_int(r, i, 2, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(4 + j);
            break;
        case 508:
            if (!peek_int(r, i, 1, &n)) break;
            k = 2;
            for (int j = 0; j < n && k < e->n_params; ++j) {
                MARK(k + 1);
                if (!peek_int(r, i, k + 4, &kk) || kk < 0) break;
                for (int q = 0; q < kk && q < e->n_params; ++q) MARK(k + 6 + 2 * q);
                k += 5 + 2 * kk;
            }
            break;
        case 504:
            if (peek_int(r, i, 1, &n))
                for (int j = 0; j < n && j < e->n_params; ++j) MARK(2 + 5 * j);
            break;
        case 308:
            if (peek_int(r, i, 3, &n))
                for (int j = 0; j < n && j < e->n_params; ++j)
                    if (peek_ptr(r, i, 4 + j, &p)) {
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
#undef MARK
        if (self) {
            r->entries[i].self_ref = 1;
            if (e->type == 308)
                sem_model_warn(r->model, "entity 308 (DE %d): subfigure definition lists itself; "
                                         "that member is ignored", de_number(i));
            else
                sem_model_warn(r->model, "entity %d (DE %d) points to itself; skipped", e->type,
                               de_number(i));
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
    sem_status st = split_lines(&r, data ? data : "", len);
    if (st == SEM_OK) st = read_global(&r);
    if (st == SEM_OK) st = read_directory(&r);
    if (st == SEM_OK) st = check_terminate(&r);
    if (st == SEM_OK) st = read_parameters(&r);
    if (st == SEM_OK) mark_references(&r);
    for (int i = 0; st == SEM_OK && i < r.n_entries; ++i) {
        const iges_entry *e = &r.entries[i];
        if (e->type == 0 || e->referenced || e->in_definition || e->type == 308 || e->self_ref)
            continue;
        st = emit_entity(&r, i, identity_xf, 0);
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
