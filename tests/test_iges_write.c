/*
 * test_iges_write.c - the IGES writer produces files that follow IGES 5.3 to the column:
 * 80-character lines, section letters and sequence numbers, DE/PD pointers and line
 * counts, parameters never split inside a token, T-section counts, Global units, status
 * flags of dependent entities; and file output is atomic and reproducible.
 */
#define _POSIX_C_SOURCE 200809L
#include <ctype.h>
#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "sem/model.h"
#include "test_util.h"

/* ---- a model with every entity the writer emits ---- */

static void line_curve(sem_curve *c, double u0, double v0, double u1, double v1)
{
    sem_curve_alloc(c, 1, 2);
    c->knots[2] = c->knots[3] = 1;
    c->ctrl[0] = u0;
    c->ctrl[1] = v0;
    c->ctrl[3] = u1;
    c->ctrl[4] = v1;
    c->t1 = 1;
}

static sem_model *build_model(const char *units, double unit_to_meter)
{
    sem_model *m = sem_model_create();
    snprintf(m->units, sizeof m->units, "%s", units);
    m->unit_to_meter = unit_to_meter;
    /* a large untrimmed patch: many parameter lines, a name longer than 8 characters */
    sem_part p;
    memset(&p, 0, sizeof p);
    strcpy(p.name, "A rather long part name that cannot fit in a DE label");
    sem_surface_alloc(&p.surface, 3, 3, 12, 9);
    for (int i = 0; i < 16; ++i) p.surface.knots_u[i] = i < 4 ? 0 : i > 11 ? 9 : (i - 3) / 9.0 * 9;
    for (int i = 0; i < 13; ++i) p.surface.knots_v[i] = i < 4 ? 0 : i > 8 ? 1 : (i - 3) / 6.0;
    for (int k = 0; k < 12 * 9; ++k) {
        p.surface.ctrl[3 * k] = (k % 12) / 7.0 - 1e-17;
        p.surface.ctrl[3 * k + 1] = (k / 12) / 3.0 + 1e22;
        p.surface.ctrl[3 * k + 2] = -sin(k) * 1e-9;
        p.surface.weights[k] = 1.0 + (k % 5) / 3.0;
    }
    p.surface.u1 = 9;
    p.surface.v1 = 1;
    sem_model_take_part(m, &p, NULL);
    /* trimmed: outer loop of 4 lines (a 102 composite), a hole of one closed polyline */
    memset(&p, 0, sizeof p);
    strcpy(p.name, "Face");
    sem_surface_alloc(&p.surface, 1, 1, 2, 2);
    p.surface.knots_u[2] = p.surface.knots_u[3] = 1;
    p.surface.knots_v[2] = p.surface.knots_v[3] = 1;
    double sq[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    memcpy(p.surface.ctrl, sq, sizeof sq);
    p.surface.u1 = p.surface.v1 = 1;
    p.has_outer = 1;
    p.outer.n_curves = 4;
    p.outer.curves = calloc(4, sizeof(sem_curve));
    line_curve(&p.outer.curves[0], 0, 0, 1, 0);
    line_curve(&p.outer.curves[1], 1, 0, 1, 1);
    line_curve(&p.outer.curves[2], 1, 1, 0, 1);
    line_curve(&p.outer.curves[3], 0, 1, 0, 0);
    p.n_holes = 1;
    p.holes = calloc(1, sizeof(sem_trim_loop));
    p.holes[0].n_curves = 1;
    p.holes[0].curves = calloc(1, sizeof(sem_curve));
    sem_curve *h = &p.holes[0].curves[0];
    sem_curve_alloc(h, 1, 4);
    double kh[6] = {0, 0, 1, 2, 3, 3};
    double ph[12] = {0.25, 0.25, 0, 0.75, 0.25, 0, 0.5, 0.75, 0, 0.25, 0.25, 0};
    memcpy(h->knots, kh, sizeof kh);
    memcpy(h->ctrl, ph, sizeof ph);
    h->t1 = 3;
    sem_model_take_part(m, &p, NULL);
    return m;
}

/* ---- a small IGES checker ---- */

typedef struct entity_info {
    int type, form, pd, count, de;
    char status[9];
    char label[9];
    int n_tokens;
    char tokens[2048][80];
} entity_info;

typedef struct iges_file {
    int n_lines;
    char (*lines)[128];
    int n_entities;
    entity_info *entities;
    char global[4096];
} iges_file;

static int read_lines(const char *path, iges_file *f)
{
    FILE *fp = fopen(path, "rb");
    if (!fp) return 0;
    f->lines = calloc(20000, sizeof *f->lines);
    f->n_lines = 0;
    while (f->n_lines < 20000 && fgets(f->lines[f->n_lines], 128, fp)) {
        char *nl = strchr(f->lines[f->n_lines], '\n');
        CHECK(nl != NULL, "line %d has no newline", f->n_lines + 1);
        if (nl) *nl = '\0';
        f->n_lines++;
    }
    fclose(fp);
    return 1;
}

static int field(const char *line, int index) /* 8-column integer field, 0-based */
{
    char t[9];
    memcpy(t, line + 8 * index, 8);
    t[8] = '\0';
    return atoi(t);
}

static int is_integer(const char *t)
{
    if (*t == '-' || *t == '+') ++t;
    if (!*t) return 0;
    for (; *t; ++t)
        if (!isdigit((unsigned char)*t)) return 0;
    return 1;
}

static int is_real(const char *t)
{
    char *end;
    strtod(t, &end);
    return *end == '\0' && strchr(t, '.') != NULL && strchr(t, 'e') == NULL && end != t;
}

/* Splits parameter text into tokens, honouring Hollerith strings. Returns the count or -1. */
static int tokenize(const char *text, char tokens[][80], int max)
{
    int n = 0;
    const char *p = text;
    while (*p) {
        char tok[80];
        int k = 0;
        /* Hollerith: digits then H */
        const char *q = p;
        while (isdigit((unsigned char)*q)) ++q;
        if (q > p && *q == 'H') {
            int len = atoi(p);
            const char *s = q + 1;
            if ((int)strlen(s) < len || len > 70) return -1;
            k = snprintf(tok, sizeof tok, "%.*s", (int)(s - p) + len, p);
            p = s + len;
        } else {
            while (*p && *p != ',' && *p != ';' && k < 79) tok[k++] = *p++;
            tok[k] = '\0';
        }
        if (n >= max) return -1;
        snprintf(tokens[n++], 80, "%s", tok);
        if (*p == ';') return n;
        if (*p != ',') return -1;
        ++p;
    }
    return -1; /* no record delimiter */
}

static void check_structure(const char *path, iges_file *f)
{
    CHECK(read_lines(path, f), "cannot read %s", path);
    const char order[] = "SGDPT";
    int section = 0, seq = 0, counts[5] = {0, 0, 0, 0, 0};
    for (int i = 0; i < f->n_lines; ++i) {
        const char *l = f->lines[i];
        CHECK(strlen(l) == 80, "line %d has %zu characters", i + 1, strlen(l));
        if (strlen(l) != 80) continue;
        const char *s = strchr(order, l[72]);
        CHECK(s != NULL, "line %d: section letter '%c'", i + 1, l[72]);
        if (!s) continue;
        int sec = (int)(s - order);
        CHECK(sec >= section, "line %d: section %c after %c", i + 1, l[72], order[section]);
        if (sec != section) seq = 0;
        section = sec;
        seq++;
        counts[sec]++;
        CHECK(atoi(l + 73) == seq, "line %d: sequence number %d, expected %d", i + 1, atoi(l + 73),
              seq);
    }
    CHECK(counts[4] == 1, "one T line, got %d", counts[4]);
    const char *t = f->lines[f->n_lines - 1];
    char expect[40];
    snprintf(expect, sizeof expect, "S%07dG%07dD%07dP%07d", counts[0], counts[1], counts[2],
             counts[3]);
    CHECK(strncmp(t, expect, 32) == 0, "T section '%.32s', expected '%s'", t, expect);
    CHECK(counts[2] % 2 == 0, "odd number of DE lines %d", counts[2]);

    /* global text */
    int g0 = counts[0];
    f->global[0] = '\0';
    for (int i = 0; i < counts[1]; ++i) strncat(f->global, f->lines[g0 + i], 72);

    /* DE pairs and their parameter records */
    int d0 = counts[0] + counts[1], p0 = d0 + counts[2];
    f->n_entities = counts[2] / 2;
    f->entities = calloc((size_t)f->n_entities + 1, sizeof *f->entities);
    for (int e = 0; e < f->n_entities; ++e) {
        const char *l1 = f->lines[d0 + 2 * e], *l2 = f->lines[d0 + 2 * e + 1];
        entity_info *en = &f->entities[e];
        en->de = 2 * e + 1;
        en->type = field(l1, 0);
        en->pd = field(l1, 1);
        memcpy(en->status, l1 + 64, 8);
        en->status[8] = '\0';
        CHECK(field(l2, 0) == en->type, "DE %d: types %d and %d", en->de, en->type, field(l2, 0));
        en->count = field(l2, 3);
        en->form = field(l2, 4);
        memcpy(en->label, l2 + 56, 8);
        en->label[8] = '\0';
        for (int k = 0; k < 8; ++k)
            CHECK(isdigit((unsigned char)en->status[k]), "DE %d status '%s'", en->de, en->status);
        CHECK(en->pd >= 1 && en->count >= 1 && en->pd + en->count - 1 <= counts[3],
              "DE %d: PD pointer %d, %d lines", en->de, en->pd, en->count);
        if (!(en->pd >= 1 && en->count >= 1 && en->pd + en->count - 1 <= counts[3])) continue;
        static char text[200000];
        text[0] = '\0';
        size_t len = 0;
        for (int k = 0; k < en->count; ++k) {
            const char *pl = f->lines[p0 + en->pd - 1 + k];
            CHECK(atoi(pl + 65) == en->de, "P line %d points to DE %d, expected %d",
                  en->pd + k, atoi(pl + 65), en->de);
            CHECK(pl[64] == ' ', "P line %d column 65 is '%c'", en->pd + k, pl[64]);
            int n = 64;
            while (n > 0 && pl[n - 1] == ' ') --n;
            /* never split inside a token: a line's data ends with a delimiter */
            CHECK(n > 0 && (pl[n - 1] == ',' || pl[n - 1] == ';'),
                  "P line %d does not end at a delimiter: '%.64s'", en->pd + k, pl);
            CHECK((pl[n - 1] == ';') == (k == en->count - 1),
                  "P line %d: record delimiter misplaced", en->pd + k);
            memcpy(text + len, pl, (size_t)n);
            len += (size_t)n;
            text[len] = '\0';
        }
        /* P lines of consecutive entities follow each other */
        if (e + 1 < f->n_entities)
            CHECK(field(f->lines[d0 + 2 * e + 2], 1) == en->pd + en->count,
                  "DE %d: next PD pointer", en->de);
        en->n_tokens = tokenize(text, en->tokens, 2048);
        CHECK(en->n_tokens > 0, "DE %d: parameters do not tokenize: %.200s", en->de, text);
        if (en->n_tokens <= 0) continue;
        CHECK(atoi(en->tokens[0]) == en->type, "DE %d: first parameter %s", en->de, en->tokens[0]);
        for (int k = 0; k < en->n_tokens; ++k) {
            const char *tk = en->tokens[k];
            int ok = is_integer(tk) || is_real(tk) || strchr(tk, 'H') != NULL;
            CHECK(ok, "DE %d parameter %d '%s' is not an IGES integer, real or string", en->de, k,
                  tk);
        }
    }
    CHECK(f->entities[f->n_entities - 1].pd + f->entities[f->n_entities - 1].count - 1 == counts[3],
          "P lines after the last entity");
}

static entity_info *entity_at(iges_file *f, int de)
{
    if (de < 1 || de % 2 == 0 || (de - 1) / 2 >= f->n_entities) return NULL;
    return &f->entities[(de - 1) / 2];
}

static void free_file(iges_file *f)
{
    free(f->lines);
    free(f->entities);
    memset(f, 0, sizeof *f);
}

/* ---- tests ---- */

static void test_structure(void)
{
    sem_model *m = build_model("MM", 0.001);
    char path[512];
    snprintf(path, sizeof path, "%s/structure.igs", test_tmpdir());
    sem_error err;
    CHECK(sem_iges_write(m, path, &err) == SEM_OK, "%s", err.message);
    iges_file f;
    memset(&f, 0, sizeof f);
    check_structure(path, &f);

    /* expected entities: 406 128 | 406 128 126x4 102 142 126 142 144 */
    int expect[] = {406, 128, 406, 128, 126, 126, 126, 126, 102, 142, 126, 142, 144};
    int n_expect = (int)(sizeof expect / sizeof expect[0]);
    CHECK(f.n_entities == n_expect, "%d entities, expected %d", f.n_entities, n_expect);
    for (int i = 0; i < f.n_entities && i < n_expect; ++i)
        CHECK(f.entities[i].type == expect[i], "entity %d type %d, expected %d", i,
              f.entities[i].type, expect[i]);
    if (f.n_entities == n_expect) {
        entity_info *e = f.entities;
        /* independent untrimmed surface, dependent surface/curves under the 144 */
        CHECK(strcmp(e[1].status, "00000000") == 0, "free 128 status %s", e[1].status);
        CHECK(strncmp(e[3].status, "0001", 4) == 0, "trimmed 128 status %s", e[3].status);
        for (int i = 4; i <= 8; ++i)
            CHECK(strcmp(e[i].status, "00010500") == 0, "parameter-space curve status %s",
                  e[i].status);
        CHECK(strncmp(e[9].status, "0001", 4) == 0, "142 status %s", e[9].status);
        CHECK(strcmp(e[12].status, "00000000") == 0, "144 status %s", e[12].status);
        CHECK(strcmp(e[1].label, "A rather") == 0, "label '%s'", e[1].label);
        CHECK(strcmp(e[12].label, "    Face") == 0, "label '%s'", e[12].label);
        CHECK(e[0].form == 15 && e[2].form == 15, "406 forms %d %d", e[0].form, e[2].form);
        /* 128: 10 + knots + 4 per control point + 4 range + 3 property pointers */
        int n128 = 10 + (12 + 4) + (9 + 4) + 4 * 12 * 9 + 4 + 3;
        CHECK(e[1].n_tokens == n128, "128 has %d parameters, expected %d", e[1].n_tokens, n128);
        CHECK(atoi(e[1].tokens[n128 - 1]) == 1 && atoi(e[1].tokens[n128 - 2]) == 1 &&
                  atoi(e[1].tokens[n128 - 3]) == 0,
              "128 property pointers");
        /* 102 lists the four 126s */
        CHECK(e[8].n_tokens == 6 && atoi(e[8].tokens[1]) == 4, "102 parameters");
        for (int k = 0; k < 4 && e[8].n_tokens == 6; ++k) {
            entity_info *c = entity_at(&f, atoi(e[8].tokens[2 + k]));
            CHECK(c && c->type == 126, "102 member %d", k);
        }
        /* 142: CRTN, SPTR -> the 128, BPTR -> the 102, CPTR = 0, PREF = 1 */
        CHECK(e[9].n_tokens == 6, "142 has %d parameters", e[9].n_tokens);
        if (e[9].n_tokens == 6) {
            CHECK(atoi(e[9].tokens[2]) == e[3].de, "SPTR %s", e[9].tokens[2]);
            CHECK(atoi(e[9].tokens[3]) == e[8].de, "BPTR %s", e[9].tokens[3]);
            CHECK(atoi(e[9].tokens[4]) == 0 && atoi(e[9].tokens[5]) == 1, "CPTR/PREF %s %s",
                  e[9].tokens[4], e[9].tokens[5]);
        }
        /* 144: PTS, N1 = 1, N2 = 1, PTO, PTI, then the name property */
        CHECK(e[12].n_tokens == 9, "144 has %d parameters", e[12].n_tokens);
        if (e[12].n_tokens == 9) {
            CHECK(atoi(e[12].tokens[1]) == e[3].de, "PTS");
            CHECK(atoi(e[12].tokens[2]) == 1 && atoi(e[12].tokens[3]) == 1, "N1 N2");
            CHECK(atoi(e[12].tokens[4]) == e[9].de && atoi(e[12].tokens[5]) == e[11].de, "PTO PTI");
            CHECK(atoi(e[12].tokens[8]) == e[2].de, "name property");
        }
        /* 126 of the hole: K=3, M=1, planar, closed (first point = last) */
        CHECK(atoi(e[10].tokens[1]) == 3 && atoi(e[10].tokens[2]) == 1 &&
                  atoi(e[10].tokens[3]) == 1 && atoi(e[10].tokens[4]) == 1,
              "hole 126 header %s %s %s %s", e[10].tokens[1], e[10].tokens[2], e[10].tokens[3],
              e[10].tokens[4]);
    }
    /* Global: delimiters, units MM (flag 2), IGES 5.3 (version flag 11) */
    iges_file g = f;
    char toks[32][80];
    int n = tokenize(g.global, toks, 32);
    CHECK(n == 25, "Global has %d parameters", n);
    if (n == 25) {
        CHECK(strcmp(toks[0], "1H,") == 0 && strcmp(toks[1], "1H;") == 0, "delimiters");
        CHECK(atoi(toks[13]) == 2 && strcmp(toks[14], "2HMM") == 0, "units %s %s", toks[13],
              toks[14]);
        CHECK(atoi(toks[22]) == 11, "version flag %s", toks[22]);
    }
    free_file(&f);

    /* the reader sees the same thing, name included */
    sem_model *back = NULL;
    CHECK(sem_iges_read(path, &back, &err) == SEM_OK, "%s", err.message);
    if (back) {
        CHECK(back->n_parts == 2, "%d parts read back", back->n_parts);
        if (back->n_parts == 2) {
            CHECK(strcmp(back->parts[0].name, m->parts[0].name) == 0, "name '%s'",
                  back->parts[0].name);
            CHECK(strcmp(back->parts[1].name, "Face") == 0, "name '%s'", back->parts[1].name);
            CHECK(back->parts[1].has_outer == 1 && back->parts[1].n_holes == 1 &&
                      back->parts[1].outer.n_curves == 4,
                  "trims read back");
        }
        sem_model_destroy(back);
    }
    sem_model_destroy(m);
}

static int unit_flag_of(const char *units, double meters, char *name_out)
{
    sem_model *m = build_model(units, meters);
    char path[512];
    snprintf(path, sizeof path, "%s/units.igs", test_tmpdir());
    sem_error err;
    int flag = -1;
    if (sem_iges_write(m, path, &err) == SEM_OK) {
        iges_file f;
        memset(&f, 0, sizeof f);
        check_structure(path, &f);
        char toks[32][80];
        if (tokenize(f.global, toks, 32) == 25) {
            flag = atoi(toks[13]);
            strcpy(name_out, toks[14]);
        }
        free_file(&f);
    }
    sem_model_destroy(m);
    return flag;
}

static void test_units(void)
{
    char name[80] = "";
    CHECK(unit_flag_of("IN", 0.0254, name) == 1 && strcmp(name, "4HINCH") == 0, "IN -> %s", name);
    CHECK(unit_flag_of("M", 1.0, name) == 6 && strcmp(name, "1HM") == 0, "M -> %s", name);
    CHECK(unit_flag_of("cm", 0.01, name) == 10 && strcmp(name, "2HCM") == 0, "cm -> %s", name);
    CHECK(unit_flag_of("", 0.3048, name) == 4 && strcmp(name, "2HFT") == 0, "0.3048 m -> %s", name);
    CHECK(unit_flag_of("FURLONG", 201.168, name) == 3 && strcmp(name, "7HFURLONG") == 0,
          "FURLONG -> %s", name);
}

static int count_temp_files(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL)
        if (strstr(e->d_name, ".tmp.")) n++;
    if (d) closedir(d);
    return n;
}

static void test_errors_and_atomicity(void)
{
    sem_error err;
    char path[512], dir[512];
    snprintf(dir, sizeof dir, "%s/atomic", test_tmpdir());
    mkdir(dir, 0755);
    snprintf(path, sizeof path, "%s/model.igs", dir);
    FILE *f = fopen(path, "w");
    fputs("old content\n", f);
    fclose(f);

    /* an invalid model is rejected before anything is written: the old file stays */
    sem_model *m = build_model("MM", 0.001);
    m->parts[1].surface.ctrl[4] = NAN;
    CHECK(sem_model_save(m, path, &err) == SEM_ERR_INVALID, "NaN control point accepted");
    CHECK(strstr(err.message, "part 1") != NULL, "message: %s", err.message);
    m->parts[1].surface.ctrl[4] = 0;
    m->parts[1].holes[0].curves[0].weights[1] = 0;
    CHECK(sem_model_save(m, path, &err) == SEM_ERR_INVALID, "zero weight accepted");
    m->parts[1].holes[0].curves[0].weights[1] = 1;
    char buf[64] = "";
    f = fopen(path, "r");
    CHECK(f && fgets(buf, sizeof buf, f) && strcmp(buf, "old content\n") == 0,
          "the old file was touched");
    if (f) fclose(f);
    CHECK(count_temp_files(dir) == 0, "temporary files left behind");

    /* a folder that does not exist */
    CHECK(sem_model_save(m, "/nonexistent-folder-sem/x.igs", &err) == SEM_ERR_IO, "no IO error");
    CHECK(strstr(err.message, "/nonexistent-folder-sem/x.igs") != NULL, "message: %s", err.message);
    /* a read-only folder (skipped when running as root, who may write anyway) */
    char ro[512];
    snprintf(ro, sizeof ro, "%s/readonly", test_tmpdir());
    mkdir(ro, 0555);
    if (access(ro, W_OK) != 0) {
        char rp[600];
        snprintf(rp, sizeof rp, "%s/x.obj", ro);
        CHECK(sem_model_save(m, rp, &err) == SEM_ERR_IO, "read-only folder accepted");
    }

    /* unknown extensions */
    CHECK(sem_model_save(m, "/tmp/x.stl", &err) == SEM_ERR_UNSUPPORTED, "stl accepted");
    CHECK(strstr(err.message, ".stl") != NULL, "message: %s", err.message);
    sem_model *back = NULL;
    CHECK(sem_model_load("/tmp/model", &back, &err) == SEM_ERR_UNSUPPORTED && back == NULL,
          "no extension accepted");

    /* the successful save replaces the old content; upper-case extension is IGES */
    snprintf(path, sizeof path, "%s/MODEL.IGES", dir);
    CHECK(sem_model_save(m, path, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_model_load(path, &back, &err) == SEM_OK && back && back->n_parts == 2,
          "upper-case .IGES");
    sem_model_destroy(back);
    CHECK(count_temp_files(dir) == 0, "temporary files left behind");

    /* reproducible bytes with SOURCE_DATE_EPOCH */
    setenv("SOURCE_DATE_EPOCH", "1600000000", 1);
    mode_t old_mask = umask(022);
    char p1[600], p2[600];
    snprintf(p1, sizeof p1, "%s/a.igs", dir);
    snprintf(p2, sizeof p2, "%s/b.igs", dir);
    CHECK(sem_iges_write(m, p1, &err) == SEM_OK, "%s", err.message);
    CHECK(rename(p1, p2) == 0, "rename");
    CHECK(sem_iges_write(m, p1, &err) == SEM_OK, "%s", err.message);
    unsetenv("SOURCE_DATE_EPOCH");
    FILE *a = fopen(p1, "rb"), *b = fopen(p2, "rb");
    int same = a && b;
    while (same) {
        int ca = fgetc(a), cb = fgetc(b);
        if (ca != cb) same = 0;
        if (ca == EOF || cb == EOF) break;
    }
    CHECK(same, "two writes of one model differ");
    if (a) fclose(a);
    if (b) fclose(b);
    struct stat st;
    /* the temporary file's 0600 does not leak into the result */
    CHECK(stat(p1, &st) == 0 && (st.st_mode & 0777) == 0644, "mode %o", (unsigned)st.st_mode);
    umask(old_mask);
    sem_model_destroy(m);
}

static void test_empty_model(void)
{
    sem_model *m = sem_model_create();
    char path[512];
    snprintf(path, sizeof path, "%s/empty.igs", test_tmpdir());
    sem_error err;
    CHECK(sem_iges_write(m, path, &err) == SEM_OK, "%s", err.message);
    iges_file f;
    memset(&f, 0, sizeof f);
    if (read_lines(path, &f)) {
        CHECK(f.n_lines == 1 + 3 + 1 || f.n_lines == 1 + 4 + 1 || f.n_lines >= 5,
              "%d lines", f.n_lines);
        CHECK(strncmp(f.lines[f.n_lines - 1], "S0000001G", 9) == 0, "T line %s",
              f.lines[f.n_lines - 1]);
    }
    free(f.lines);
    sem_model_destroy(m);
}

int main(void)
{
    test_structure();
    test_units();
    test_errors_and_atomicity();
    test_empty_model();
    return test_finish("test_iges_write");
}
