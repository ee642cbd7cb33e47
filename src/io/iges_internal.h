/*
 * iges_internal.h - what the files of the IGES reader share (src/io/iges_*.c; the design is
 * told at the top of iges_read.c): the reader's state, the directory entries and their
 * tokenised parameters, and the functions one file of the reader offers the others. Not
 * part of the API: only the reader includes it.
 */
#ifndef SEM_IO_IGES_INTERNAL_H
#define SEM_IO_IGES_INTERNAL_H

#include <stddef.h>

#include "sem/model.h"

#define IGES_MAX_DEPTH 32

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

/* Directory entry number (DE n, the file's name for an entity) of entry index. */
static inline int iges_de_number(int index) { return 2 * index + 1; }

/* ------------------------------------------------ iges_lexer.c: errors ---- */

sem_status iges_entity_error(iges_reader *r, int idx, int line, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
sem_status iges_nomem(iges_reader *r);
sem_status iges_count_conversion(iges_reader *r, int idx);
sem_status iges_count_points(iges_reader *r, int idx, long long n);
const char *iges_entity_description(int type);
sem_status iges_unsupported(iges_reader *r, int idx, const char *what);

/* ---------------------------------- iges_lexer.c: sections, parameters ---- */

sem_status iges_read_sections(iges_reader *r, const char *data, size_t len);
int iges_parse_real(const char *s, int len, double def, double *out);
int iges_token_line(const iges_reader *r, int idx, int k);
int iges_remaining(const iges_reader *r, int idx, int k);
sem_status iges_param_real_def(iges_reader *r, int idx, int k, double def, double *out);
sem_status iges_param_real(iges_reader *r, int idx, int k, double *out);
sem_status iges_param_int(iges_reader *r, int idx, int k, int *out);
sem_status iges_param_ptr(iges_reader *r, int idx, int k, int allow_null, int *out);
void iges_param_string(const iges_reader *r, int idx, int k, const char **s, int *len);
sem_status iges_need(iges_reader *r, int idx, int k, long long count, const char *what);
int iges_peek_int(const iges_reader *r, int idx, int k, int *out);
int iges_peek_ptr(const iges_reader *r, int idx, int k, int *out);

/* ---------------------------- iges_lexer.c: transforms, entity prologue ---- */

extern const double iges_identity_xf[12];
void iges_xf_compose(const double *a, const double *b, double *out);
void iges_xf_apply(const double *m, double *p, size_t n);
sem_status iges_own_xform(iges_reader *r, int idx, const double *parent, double *out);
sem_status iges_enter_entity(iges_reader *r, int idx, const double *parent, int depth,
                             double m[12]);

/* ------------------------------------------------------ iges_entities.c ---- */

sem_status iges_list_push(iges_reader *r, curve_list *l, sem_curve *c);
void iges_list_free(curve_list *l);
void iges_reverse_curves(curve_list *l, int first);
sem_status iges_read_curves(iges_reader *r, int idx, const double *parent, int depth,
                            curve_list *out);
sem_status iges_read_surface(iges_reader *r, int idx, const double *parent, int depth,
                             sem_part *part);
sem_status iges_surface_pointer(iges_reader *r, int idx, int k, int *out);

/* --------------------------------------------------------- iges_parts.c ---- */

sem_status iges_finish_part(iges_reader *r, sem_part *part, int top, int surf);
sem_status iges_add_hole(iges_reader *r, sem_part *part, curve_list *l);
void iges_set_outer(sem_part *part, curve_list *l);
sem_status iges_project_model_space_loop(iges_reader *r, int idx, const sem_part *part,
                                         curve_list *model_space, curve_list *l, int *border);
sem_status iges_read_trimmed_surface(iges_reader *r, int surf, const double *m, int depth,
                                     const curve_list *hint, sem_part *part, int *from_hint);
int iges_needs_hint(const iges_reader *r, int surf);

/* ------------------------------------------------------- iges_trimmed.c ---- */

sem_status iges_emit_trimmed(iges_reader *r, int idx, const double *parent, int depth);
sem_status iges_emit_bounded(iges_reader *r, int idx, const double *parent, int depth);

/* ---------------------------------------------------------- iges_brep.c ---- */

sem_status iges_emit_face(iges_reader *r, int idx, const double *parent, int depth);
sem_status iges_emit_shell(iges_reader *r, int idx, const double *parent, int depth);
sem_status iges_emit_solid(iges_reader *r, int idx, const double *parent, int depth);

#endif
