/*
 * iges_lexer.c - an IGES file read into sections, directory entries and tokenised
 * parameters, and what every entity conversion does first (iges_internal.h).
 *
 * Design. The file is read in one linear pass into lines, classified by the section letter
 * in column 73 (Start, Global, Directory Entry, Parameter Data, Terminate). The Global
 * section gives the delimiters and units. The Parameter section is concatenated into one
 * text, each line's columns 1-64 padded to exactly 64 characters, so that the file line of
 * any parameter is first_line + offset / 64; every entity's parameters are tokenised once
 * (Hollerith strings may hold delimiters and span lines).
 *
 * The files that convert entities read parameters only through iges_param_* and iges_need:
 * any count read from the file is checked against the number of parameters the entity
 * actually has before anything is allocated, so one entity cannot ask for more than the
 * file holds. Malformed data ends the read with SEM_ERR_PARSE and "FILE:LINE: entity T
 * (DE n): what is wrong" (iges_entity_error). The budgets (iges_count_conversion,
 * iges_count_points; see iges_read.c) and the entity prologue (iges_enter_entity: the
 * recursion guard, the budget, and the chain of 124 transformation matrices) live here
 * too, below every file that converts entities.
 *
 * Header defects that Open CASCADE reads past (issue 29: a unit flag of 0, a parameter line
 * count past the section) are repaired with a warning instead of refusing the file.
 */
#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/iges_internal.h"
#include "sem/limits.h"

#define PLINE_WIDTH 64
#define GLINE_WIDTH 72

/* ---------------------------------------------------------------- errors ---- */

static sem_status parse_error(iges_reader *r, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static sem_status parse_error(iges_reader *r, int line, const char *fmt, ...)
{
    char place[1024];
    snprintf(place, sizeof place, "%s:%d", r->name, line);
    va_list ap;
    va_start(ap, fmt);
    sem_status st = sem_error_vset(r->err, SEM_ERR_PARSE, place, fmt, ap);
    va_end(ap);
    return st;
}

sem_status iges_entity_error(iges_reader *r, int idx, int line, const char *fmt, ...)
{
    const iges_entry *e = &r->entries[idx];
    char place[1024];
    snprintf(place, sizeof place, "%s:%d: entity %d (DE %d)", r->name, line > 0 ? line : e->line,
             e->type, iges_de_number(idx));
    va_list ap;
    va_start(ap, fmt);
    sem_status st = sem_error_vset(r->err, SEM_ERR_PARSE, place, fmt, ap);
    va_end(ap);
    return st;
}

sem_status iges_nomem(iges_reader *r)
{
    return sem_error_set(r->err, SEM_ERR_NOMEM, "%s: out of memory", r->name);
}

/* Counts one conversion of entity idx against the expansion budget. */
sem_status iges_count_conversion(iges_reader *r, int idx)
{
    if (++r->conversions <= SEM_MAX_IGES_EXPANSION) return SEM_OK;
    return iges_entity_error(r, idx, 0,
                             "more than %d entity conversions (subfigure instances and "
                             "shared members count each time they are used; limit "
                             "SEM_MAX_IGES_EXPANSION)",
                             SEM_MAX_IGES_EXPANSION);
}

/* Counts n control points about to be built against the model budget. */
sem_status iges_count_points(iges_reader *r, int idx, long long n)
{
    r->built_points += n;
    if (r->built_points <= SEM_MAX_MODEL_CONTROL_POINTS) return SEM_OK;
    return iges_entity_error(r, idx, 0,
                             "the model would have more than %d control points (surfaces "
                             "and trim curves, every instance counted; limit "
                             "SEM_MAX_MODEL_CONTROL_POINTS)",
                             SEM_MAX_MODEL_CONTROL_POINTS);
}

const char *iges_entity_description(int type)
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
sem_status iges_unsupported(iges_reader *r, int idx, const char *what)
{
    const iges_entry *e = &r->entries[idx];
    const char *d = iges_entity_description(e->type);
    sem_model_warn(r->model, "entity %d (DE %d): %s%s%s", e->type, iges_de_number(idx), d ? d : "",
                   d ? " " : "", what);
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
    if (!r->lines) return iges_nomem(r);
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
            if (!l) return iges_nomem(r);
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
            if (!push_token(r, s, (int)n, 1)) return iges_nomem(r);
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
            if (!push_token(r, start, (int)(e - start), 0)) return iges_nomem(r);
        }
        if (text[pos] == r->record_delim) {
            *end = pos + 1;
            return SEM_OK;
        }
        ++pos; /* parameter delimiter */
    }
}

/* Parses a number: optional sign, digits, '.', exponent with E or D. Empty -> default. */
int iges_parse_real(const char *s, int len, double def, double *out)
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
    if (!g) return iges_nomem(r);
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
            iges_parse_real(g + r->tokens[k19].offset, r->tokens[k19].length, 0.0, &v) == 1 &&
            v > 0 && isfinite(v))
            r->resolution = v;
        if (k14 < r->n_tokens) {
            const iges_token *t = &r->tokens[k14];
            int ok = iges_parse_real(g + t->offset, t->length, 1.0, &v);
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

/* Columns 66-72 of Parameter line `line` (from 0), the back pointer to its directory entry,
 * into *back; 0 when the line is shorter or they hold no integer. */
static int p_back_field(const iges_reader *r, int line, long *back)
{
    const iges_line *l = &r->lines[r->sec_first[SEC_P] + line];
    if (l->len < 72) return 0;
    char buf[8];
    int n = 0;
    for (int c = 65; c < 72; ++c)
        if (l->text[c] != ' ') buf[n++] = l->text[c];
    buf[n] = '\0';
    char *end;
    *back = strtol(buf, &end, 10);
    return n > 0 && *end == '\0';
}

/* The directory entry a Parameter line points back to (columns 66-72), or -1. */
static int p_back_pointer(const iges_reader *r, int line)
{
    long back;
    return p_back_field(r, line, &back) && back > 0 && back < INT32_MAX ? (int)back : -1;
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
    if (!r->entries) return iges_nomem(r);
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
            return parse_error(r, l2->number,
                               "directory entry %d: entity type %d on the first "
                               "line but %d on the second",
                               iges_de_number(i), e->type, type2);
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
            p_back_pointer(r, e->pd_pointer - 1) == iges_de_number(i)) {
            /* a line count that runs past the Parameter section (Rhino 1998 wrote 20 for a
             * 7-line surface: corpus occt_rhino_bad_header): the lines that point back to
             * this entry are its lines, as Open CASCADE reads them */
            int count = 0;
            while (e->pd_pointer - 1 + count < np &&
                   p_back_pointer(r, e->pd_pointer - 1 + count) == iges_de_number(i))
                ++count;
            sem_model_warn(r->model, "entity %d (DE %d): parameter line count %d runs past the "
                                     "Parameter section; its %d lines that point back to it are "
                                     "read",
                           e->type, iges_de_number(i), e->pd_count, count);
            e->pd_count = count;
        }
        if (e->pd_pointer < 1 || e->pd_pointer > np || e->pd_count < 1 ||
            e->pd_count > np - e->pd_pointer + 1)
            return parse_error(r, l1->number,
                               "entity %d (DE %d): parameter data lines %d..%d are outside the "
                               "Parameter section (%d lines; file truncated?)",
                               e->type, iges_de_number(i), e->pd_pointer,
                               e->pd_pointer + e->pd_count - 1, np);
        if (e->xform < 0 || e->xform > 2 * r->n_entries)
            return parse_error(r, l1->number, "entity %d (DE %d): transformation matrix "
                                              "pointer %d out of range",
                               e->type, iges_de_number(i), e->xform);
    }
    return SEM_OK;
}

static sem_status read_parameters(iges_reader *r)
{
    int np = r->sec_count[SEC_P];
    r->ptext_len = (size_t)np * PLINE_WIDTH;
    r->ptext = malloc(r->ptext_len + 1);
    if (!r->ptext) return iges_nomem(r);
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
        long back;
        if (p_back_field(r, e->pd_pointer - 1, &back) && back != iges_de_number(i))
            return parse_error(r, first->number,
                               "parameter line %d belongs to DE %ld, but DE %d (entity %d) "
                               "points to it",
                               e->pd_pointer, back, iges_de_number(i), e->type);
        char what[64];
        snprintf(what, sizeof what, "entity %d (DE %d)", e->type, iges_de_number(i));
        size_t begin = (size_t)(e->pd_pointer - 1) * PLINE_WIDTH;
        size_t limit = (size_t)(e->pd_pointer - 1 + e->pd_count) * PLINE_WIDTH;
        e->first_token = r->n_tokens;
        size_t end;
        sem_status st = tokenize(r, r->ptext, begin, limit, pline_of, what, &end);
        if (st != SEM_OK) return st;
        size_t nt = r->n_tokens - e->first_token;
        if (nt > INT32_MAX / 2)
            return iges_entity_error(r, i, first->number, "too many parameters");
        e->n_params = (int)nt;
        const iges_token *t = &r->tokens[e->first_token];
        double ty;
        if (t->is_string || iges_parse_real(r->ptext + t->offset, t->length, -1, &ty) != 1 ||
            ty != e->type)
            return parse_error(r, first->number,
                               "parameter data starts with '%.*s' but directory entry %d says "
                               "entity type %d",
                               t->length > 20 ? 20 : t->length, r->ptext + t->offset,
                               iges_de_number(i), e->type);
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

/* The whole file into r: its lines by section, the Global section's delimiters and units,
 * the directory entries, the Terminate counts and every entity's parameters, tokenised. */
sem_status iges_read_sections(iges_reader *r, const char *data, size_t len)
{
    sem_status st = split_lines(r, data, len);
    if (st == SEM_OK) st = read_global(r);
    if (st == SEM_OK) st = read_directory(r);
    if (st == SEM_OK) st = check_terminate(r);
    if (st == SEM_OK) st = read_parameters(r);
    return st;
}

/* ------------------------------------------------------ parameters ---- */

int iges_token_line(const iges_reader *r, int idx, int k)
{
    const iges_entry *e = &r->entries[idx];
    if (k < 0 || k >= e->n_params) k = e->n_params - 1;
    return pline_of(r, r->tokens[e->first_token + (size_t)k].offset);
}

int iges_remaining(const iges_reader *r, int idx, int k)
{
    int n = r->entries[idx].n_params - k;
    return n > 0 ? n : 0;
}

sem_status iges_param_real_def(iges_reader *r, int idx, int k, double def, double *out)
{
    const iges_entry *e = &r->entries[idx];
    if (k >= e->n_params)
        return iges_entity_error(r, idx, iges_token_line(r, idx, e->n_params - 1),
                                 "parameter %d is missing (the entity has %d parameters)", k,
                                 e->n_params - 1);
    const iges_token *t = &r->tokens[e->first_token + (size_t)k];
    int ok = t->is_string ? 0 : iges_parse_real(r->ptext + t->offset, t->length, def, out);
    if (ok == 1) return SEM_OK;
    int n = t->length > 40 ? 40 : t->length;
    if (ok < 0)
        return iges_entity_error(r, idx, pline_of(r, t->offset),
                                 "parameter %d '%.*s' is not a finite number", k, n,
                                 r->ptext + t->offset);
    return iges_entity_error(r, idx, pline_of(r, t->offset), "parameter %d '%.*s' is not a number",
                             k, n, r->ptext + t->offset);
}

sem_status iges_param_real(iges_reader *r, int idx, int k, double *out)
{
    return iges_param_real_def(r, idx, k, 0.0, out);
}

sem_status iges_param_int(iges_reader *r, int idx, int k, int *out)
{
    double v;
    sem_status st = iges_param_real(r, idx, k, &v);
    if (st != SEM_OK) return st;
    if (v != floor(v) || fabs(v) > 1e9) {
        const iges_token *t = &r->tokens[r->entries[idx].first_token + (size_t)k];
        return iges_entity_error(r, idx, pline_of(r, t->offset),
                                 "parameter %d '%.*s' is not an "
                                 "integer",
                                 k, t->length > 40 ? 40 : t->length, r->ptext + t->offset);
    }
    *out = (int)v;
    return SEM_OK;
}

/* A pointer parameter: *out is the entry index, or -1 for 0 when allow_null. */
sem_status iges_param_ptr(iges_reader *r, int idx, int k, int allow_null, int *out)
{
    int v = 0;
    sem_status st = iges_param_int(r, idx, k, &v);
    if (st != SEM_OK) return st;
    if (v < 0) v = -v;
    if (v == 0 && allow_null) {
        *out = -1;
        return SEM_OK;
    }
    if (v < 1 || v > 2 * r->n_entries - 1 || v % 2 == 0 || r->entries[(v - 1) / 2].type == 0)
        return iges_entity_error(r, idx, iges_token_line(r, idx, k),
                                 "parameter %d: pointer %d is not a directory entry (DE 1..%d)", k,
                                 v, 2 * r->n_entries - 1);
    *out = (v - 1) / 2;
    return SEM_OK;
}

void iges_param_string(const iges_reader *r, int idx, int k, const char **s, int *len)
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

sem_status iges_need(iges_reader *r, int idx, int k, long long count, const char *what)
{
    if (count < 0 || count > iges_remaining(r, idx, k))
        return iges_entity_error(r, idx, iges_token_line(r, idx, k),
                                 "%s needs %lld parameters from parameter %d, but the entity has "
                                 "only %d",
                                 what, count, k, iges_remaining(r, idx, k));
    return SEM_OK;
}

int iges_peek_int(const iges_reader *r, int idx, int k, int *out)
{
    const iges_entry *e = &r->entries[idx];
    if (k < 1 || k >= e->n_params) return 0;
    const iges_token *t = &r->tokens[e->first_token + (size_t)k];
    double v;
    if (t->is_string || iges_parse_real(r->ptext + t->offset, t->length, 0.0, &v) != 1) return 0;
    if (v != floor(v) || fabs(v) > 1e9) return 0;
    *out = (int)v;
    return 1;
}

int iges_peek_ptr(const iges_reader *r, int idx, int k, int *out)
{
    int v;
    if (!iges_peek_int(r, idx, k, &v)) return 0;
    if (v < 0) v = -v;
    if (v < 1 || v > 2 * r->n_entries - 1 || v % 2 == 0) return 0;
    *out = (v - 1) / 2;
    return 1;
}

/* -------------------------------------------------------- transforms ---- */

/* 3x4 matrices [R | t], x' = R x + t, row-major. */
const double iges_identity_xf[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};

void iges_xf_compose(const double *a, const double *b, double *out)
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
    return memcmp(m, iges_identity_xf, sizeof iges_identity_xf) == 0;
}

void iges_xf_apply(const double *m, double *p, size_t n)
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
sem_status iges_own_xform(iges_reader *r, int idx, const double *parent, double *out)
{
    double m[12];
    memcpy(m, iges_identity_xf, sizeof m);
    int ptr = r->entries[idx].xform, from = idx;
    for (int depth = 0; ptr != 0; ++depth) {
        if (depth >= IGES_MAX_DEPTH)
            return iges_entity_error(r, idx, 0,
                                     "transformation matrix chain is cyclic or deeper "
                                     "than %d",
                                     IGES_MAX_DEPTH);
        if (ptr < 0 || ptr > 2 * r->n_entries - 1 || ptr % 2 == 0)
            return iges_entity_error(r, from, 0,
                                     "transformation matrix pointer %d is not a "
                                     "directory entry",
                                     ptr);
        int t = (ptr - 1) / 2;
        if (r->entries[t].type != 124)
            return iges_entity_error(r, from, 0,
                                     "transformation matrix pointer %d points to a "
                                     "type-%d entity, not a 124",
                                     ptr, r->entries[t].type);
        double x[12];
        sem_status st = iges_need(r, t, 1, 12, "transformation matrix");
        for (int k = 0; st == SEM_OK && k < 12; ++k) st = iges_param_real(r, t, 1 + k, &x[k]);
        if (st != SEM_OK) return st;
        iges_xf_compose(x, m, m);
        from = t;
        ptr = r->entries[t].xform;
    }
    iges_xf_compose(parent, m, out);
    return SEM_OK;
}

/* ---------------------------------------------------- entity prologue ---- */

/* What every curve and surface entity does first: refuse a cycle or too deep a nesting,
 * count the conversion (SEM_MAX_* budgets), and compose its own transform with its parent's
 * into m. */
sem_status iges_enter_entity(iges_reader *r, int idx, const double *parent, int depth,
                             double m[12])
{
    if (depth > IGES_MAX_DEPTH || r->entries[idx].busy)
        return iges_entity_error(r, idx, 0,
                                 "entity references itself (cycle or nesting deeper than "
                                 "%d)",
                                 IGES_MAX_DEPTH);
    sem_status st = iges_count_conversion(r, idx);
    if (st != SEM_OK) return st;
    return iges_own_xform(r, idx, parent, m);
}
