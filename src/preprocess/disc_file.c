/*
 * disc_file.c - the preprocessing's result on disk: sem_discretization_save, _load and
 * _load_buffer (sem/preprocess.h), the .semdisc format.
 *
 * File layout (native little-endian doubles/ints; a byte-order mark rejects foreign files):
 *     "SEMDISC\0" | u32 format version | u32 byte-order mark | u64 model/options hash
 *     | i32 sizes | f64 scalars | arrays, each prefixed by its u64 element count
 *     | u64 FNV-1a checksum of everything before it.
 * The reader never trusts a count: every count must equal the one implied by the sizes and
 * fit in the bytes that remain, and every sparse matrix is checked (monotone row starts,
 * sorted in-range columns) before it is used.
 */
#include "sem/preprocess.h"

#include <errno.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "disc_format.h"
#include "io/read_file.h"
#include "sem/limits.h"
#include "util/fnv_hash.h"

/* The file stores int arrays as 32-bit integers and reads them straight into int arrays. */
_Static_assert(sizeof(int) == 4, "sem assumes 32-bit int");

/* ------------------------------------------------------------------------------------ */
/* save                                                                                  */

typedef struct writer {
    FILE *f;
    sem_fnv sum;
    int failed;
} writer;

static void w_bytes(writer *w, const void *data, size_t n)
{
    if (w->failed || n == 0) return;
    sem_fnv_bytes(&w->sum, data, n);
    if (fwrite(data, 1, n, w->f) != n) w->failed = 1;
}

static void w_u32(writer *w, uint32_t v) { w_bytes(w, &v, sizeof v); }
static void w_u64(writer *w, uint64_t v) { w_bytes(w, &v, sizeof v); }
static void w_i32(writer *w, int v)
{
    int32_t x = (int32_t)v;
    w_bytes(w, &x, sizeof x);
}
static void w_f64(writer *w, double v) { w_bytes(w, &v, sizeof v); }

static void w_ints(writer *w, const int *v, size_t n)
{
    w_u64(w, (uint64_t)n);
    if (n && v) {
        w_bytes(w, v, n * sizeof(int));
    }
}

static void w_doubles(writer *w, const double *v, size_t n)
{
    w_u64(w, (uint64_t)n);
    if (n && v) w_bytes(w, v, n * sizeof(double));
}

static void w_csr(writer *w, const sem_csr *m)
{
    size_t nnz = m->row_start ? sem_csr_nnz(m) : 0;
    w_i32(w, m->n_rows);
    w_i32(w, m->n_cols);
    if (!m->row_start) {
        /* an empty matrix: row starts all 0 */
        w_u64(w, (uint64_t)m->n_rows + 1);
        for (int r = 0; r <= m->n_rows; ++r) w_i32(w, 0);
    } else {
        w_ints(w, m->row_start, (size_t)m->n_rows + 1);
    }
    w_ints(w, m->col, nnz);
    w_doubles(w, m->val, nnz);
}

sem_status sem_discretization_save(const sem_discretization *d, const char *path, sem_error *err)
{
    if (!d || !path) return sem_error_set(err, SEM_ERR_INVALID, "sem_discretization_save: NULL argument");
    size_t len = strlen(path);
    char *tmp = malloc(len + 64);
    if (!tmp) return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    snprintf(tmp, len + 64, "%s.tmp%ld", path, (long)getpid());
    writer w = {fopen(tmp, "wb"), {0}, 0};
    if (!w.f) {
        sem_status st = sem_error_set(err, SEM_ERR_IO, "%s: cannot write: %s", path, strerror(errno));
        free(tmp);
        return st;
    }
    sem_fnv_init(&w.sum);
    w_bytes(&w, sem_disc_magic, sizeof sem_disc_magic);
    w_u32(&w, SEM_DISC_FORMAT_VERSION);
    w_u32(&w, SEM_DISC_BYTE_ORDER);
    w_u64(&w, (uint64_t)d->model_hash);
    w_i32(&w, d->order);
    w_i32(&w, d->n_basis);
    w_i32(&w, d->n_parts);
    w_i32(&w, d->n_ctrl);
    w_i32(&w, d->n_samples);
    w_i32(&w, d->n_quad);
    w_i32(&w, d->n_origins);
    w_f64(&w, d->volume);
    w_f64(&w, d->alpha);
    w_f64(&w, d->gamma);
    w_f64(&w, d->length_scale);
    w_f64(&w, d->stiffness_nnz_percent);
    w_f64(&w, d->weight_nonzero_fraction);
    w_f64(&w, d->timings.sample_s);
    w_f64(&w, d->timings.scene_s);
    w_f64(&w, d->timings.quad_s);
    w_f64(&w, d->timings.weights_s);
    w_f64(&w, d->timings.build_pi_s);
    w_f64(&w, d->timings.operators_s);
    w_doubles(&w, d->frame_axes, 9);
    w_doubles(&w, d->frame_center, 3);
    w_doubles(&w, d->frame_lo, 3);
    w_doubles(&w, d->frame_hi, 3);
    w_f64(&w, d->quad_spacing);
    w_i32(&w, d->shared_fit);

    w_ints(&w, d->part_ctrl_offset, d->part_ctrl_offset ? (size_t)d->n_parts + 1 : 0);
    w_ints(&w, d->sample_part, d->sample_part ? (size_t)d->n_samples : 0);
    w_doubles(&w, d->sample_uv, d->sample_uv ? 2 * (size_t)d->n_samples : 0);
    w_doubles(&w, d->sample_X, d->sample_X ? 3 * (size_t)d->n_samples : 0);
    w_doubles(&w, d->sample_area, d->sample_area ? (size_t)d->n_samples : 0);
    w_doubles(&w, d->sample_seam, d->sample_seam ? (size_t)d->n_samples : 0);
    w_csr(&w, &d->J_hat);
    w_doubles(&w, d->quad_X, d->quad_X ? 3 * (size_t)d->n_quad : 0);
    w_doubles(&w, d->quad_volume, d->quad_volume ? (size_t)d->n_quad : 0);
    w_ints(&w, d->quad_part, d->quad_part ? (size_t)d->n_quad : 0);
    w_csr(&w, &d->W);
    w_csr(&w, &d->W_samples);
    w_doubles(&w, d->origin_X, d->origin_X ? 3 * (size_t)d->n_origins : 0);
    w_ints(&w, d->part_origin, d->part_origin ? (size_t)d->n_parts : 0);
    if (d->part_covered) {
        w_ints(&w, d->part_covered, (size_t)d->n_parts);
    } else { /* always n_parts entries: zeros when no part needed covering */
        const int zero = 0;
        w_u64(&w, (uint64_t)d->n_parts);
        for (int i = 0; i < d->n_parts; ++i) w_bytes(&w, &zero, sizeof zero);
    }
    w_csr(&w, &d->Pi);
    w_csr(&w, &d->Gamma);
    w_csr(&w, &d->Grad);
    w_csr(&w, &d->Gamma_samples);
    w_csr(&w, &d->M);
    w_csr(&w, &d->M_eps);
    uint64_t sum = w.sum.h;
    w_u64(&w, sum);

    int failed = w.failed;
    if (fflush(w.f) != 0) failed = 1;
    if (!failed && fsync(fileno(w.f)) != 0) failed = 1;
    if (fclose(w.f) != 0) failed = 1;
    if (failed) {
        sem_status st = sem_error_set(err, SEM_ERR_IO, "%s: write failed: %s", path, strerror(errno));
        remove(tmp);
        free(tmp);
        return st;
    }
    if (rename(tmp, path) != 0) {
        sem_status st =
            sem_error_set(err, SEM_ERR_IO, "%s: cannot replace: %s", path, strerror(errno));
        remove(tmp);
        free(tmp);
        return st;
    }
    free(tmp);
    return SEM_OK;
}

/* ------------------------------------------------------------------------------------ */
/* load                                                                                  */

typedef struct reader {
    const unsigned char *data;
    size_t size, pos;
    const char *path;
    sem_error *err;
    sem_status st;
} reader;

static int r_fail(reader *r, const char *what)
{
    if (r->st == SEM_OK)
        r->st = sem_error_set(r->err, SEM_ERR_PARSE, "%s: corrupt preprocessed data: %s", r->path,
                              what);
    return 0;
}

static int r_bytes(reader *r, void *out, size_t n)
{
    if (r->st != SEM_OK) return 0;
    if (n > r->size - r->pos) return r_fail(r, "file is truncated");
    memcpy(out, r->data + r->pos, n);
    r->pos += n;
    return 1;
}

static uint32_t r_u32(reader *r)
{
    uint32_t v = 0;
    r_bytes(r, &v, sizeof v);
    return v;
}
static uint64_t r_u64(reader *r)
{
    uint64_t v = 0;
    r_bytes(r, &v, sizeof v);
    return v;
}
static int r_i32(reader *r)
{
    int32_t v = 0;
    r_bytes(r, &v, sizeof v);
    return (int)v;
}
static double r_f64(reader *r)
{
    double v = 0;
    r_bytes(r, &v, sizeof v);
    return v;
}

/* Reads an array whose element count must be `expected`; checks the bytes exist before
 * allocating. Returns NULL for an empty array (and on failure, with r->st set). */
static void *r_array(reader *r, size_t expected, size_t elem, const char *what)
{
    uint64_t n = r_u64(r);
    if (r->st != SEM_OK) return NULL;
    if (n != (uint64_t)expected) {
        char msg[160];
        snprintf(msg, sizeof msg, "%s has %llu entries, expected %llu", what,
                 (unsigned long long)n, (unsigned long long)expected);
        r_fail(r, msg);
        return NULL;
    }
    if (n == 0) return NULL;
    if (n > (r->size - r->pos) / elem) {
        r_fail(r, "file is truncated");
        return NULL;
    }
    void *p = malloc((size_t)n * elem);
    if (!p) {
        r->st = sem_error_set(r->err, SEM_ERR_NOMEM, "%s: out of memory", r->path);
        return NULL;
    }
    r_bytes(r, p, (size_t)n * elem);
    return p;
}

static int *r_ints(reader *r, size_t expected, const char *what)
{
    return r_array(r, expected, sizeof(int32_t), what);
}
static double *r_doubles(reader *r, size_t expected, const char *what)
{
    return r_array(r, expected, sizeof(double), what);
}

static void r_csr(reader *r, sem_csr *m, int n_rows, int n_cols, const char *what)
{
    memset(m, 0, sizeof *m);
    int rows = r_i32(r), cols = r_i32(r);
    if (r->st != SEM_OK) return;
    if (rows != n_rows || cols != n_cols) {
        char msg[200];
        snprintf(msg, sizeof msg, "%s is %d x %d, expected %d x %d", what, rows, cols, n_rows,
                 n_cols);
        r_fail(r, msg);
        return;
    }
    m->n_rows = rows;
    m->n_cols = cols;
    m->row_start = r_ints(r, (size_t)rows + 1, what);
    if (r->st != SEM_OK) return;
    if (!m->row_start || m->row_start[0] != 0) {
        r_fail(r, "bad sparse row starts");
        return;
    }
    for (int k = 0; k < rows; ++k)
        if (m->row_start[k + 1] < m->row_start[k]) {
            r_fail(r, "bad sparse row starts");
            return;
        }
    size_t nnz = (size_t)m->row_start[rows];
    m->col = r_ints(r, nnz, what);
    m->val = r_doubles(r, nnz, what);
    if (r->st != SEM_OK) return;
    if (nnz == 0) {
        /* keep the invariant of sem_csr_alloc: col/val are allocated */
        m->col = malloc(sizeof(int));
        m->val = malloc(sizeof(double));
        if (!m->col || !m->val) {
            r->st = sem_error_set(r->err, SEM_ERR_NOMEM, "%s: out of memory", r->path);
            return;
        }
    }
    for (int k = 0; k < rows; ++k)
        for (int j = m->row_start[k]; j < m->row_start[k + 1]; ++j) {
            if (m->col[j] < 0 || m->col[j] >= cols ||
                (j > m->row_start[k] && m->col[j] <= m->col[j - 1])) {
                r_fail(r, "sparse column out of range or unsorted");
                return;
            }
            if (!isfinite(m->val[j])) {
                r_fail(r, "non-finite value");
                return;
            }
        }
}

static int check_index_array(reader *r, const int *v, size_t n, int limit, const char *what)
{
    for (size_t k = 0; k < n && v; ++k)
        if (v[k] < 0 || v[k] >= limit) {
            char msg[160];
            snprintf(msg, sizeof msg, "%s index out of range", what);
            return r_fail(r, msg);
        }
    return 1;
}

sem_status sem_discretization_load(const char *path, unsigned long long expected_hash,
                                   sem_discretization **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!path || !out) return sem_error_set(err, SEM_ERR_INVALID, "sem_discretization_load: NULL argument");
    char *data = NULL;
    size_t size = 0;
    sem_status st = sem_read_file(path, SEM_MAX_CACHE_FILE_BYTES, "SEM_MAX_CACHE_FILE_BYTES", &data,
                                  &size, err);
    if (st != SEM_OK) return st;
    st = sem_discretization_load_buffer(path, data, size, expected_hash, out, err);
    free(data);
    return st;
}

sem_status sem_discretization_load_buffer(const char *name, const void *bytes, size_t size,
                                          unsigned long long expected_hash,
                                          sem_discretization **out, sem_error *err)
{
    if (out) *out = NULL;
    if (!out || (!bytes && size > 0))
        return sem_error_set(err, SEM_ERR_INVALID, "sem_discretization_load_buffer: NULL argument");
    const char *path = name ? name : "<buffer>";
    const unsigned char *data = bytes;
    const size_t header = sizeof sem_disc_magic + 4 + 4 + 8;
    if (size < header + 8)
        return sem_error_set(err, SEM_ERR_PARSE, "%s: not a sem preprocessed file (too short)", path);

    reader r = {data, size, 0, path, err, SEM_OK};
    char magic[8];
    r_bytes(&r, magic, sizeof magic);
    if (memcmp(magic, sem_disc_magic, sizeof magic) != 0) {
        return sem_error_set(err, SEM_ERR_PARSE, "%s: not a sem preprocessed file (bad magic)", path);
    }
    uint32_t version = r_u32(&r);
    uint32_t bom = r_u32(&r);
    if (bom != SEM_DISC_BYTE_ORDER) {
        return sem_error_set(err, SEM_ERR_PARSE, "%s: written on a machine of another byte order",
                             path);
    }
    if (version != SEM_DISC_FORMAT_VERSION) {
        return sem_error_set(err, SEM_ERR_PARSE, "%s: written by format version %u, this sem reads %u",
                             path, (unsigned)version, (unsigned)SEM_DISC_FORMAT_VERSION);
    }
    /* checksum of everything before the last 8 bytes */
    sem_fnv sum;
    sem_fnv_init(&sum);
    sem_fnv_bytes(&sum, data, size - 8);
    uint64_t stored;
    memcpy(&stored, data + size - 8, 8);
    if (stored != sum.h) {
        return sem_error_set(err, SEM_ERR_PARSE,
                             "%s: corrupt preprocessed data: checksum mismatch (truncated or damaged file)",
                             path);
    }
    uint64_t hash = r_u64(&r);
    if (expected_hash != 0 && hash != (uint64_t)expected_hash) {
        return sem_error_set(err, SEM_ERR_INVALID,
                             "%s: preprocessed data is for a different model or settings", path);
    }
    r.size = size - 8; /* the checksum is not content */

    sem_discretization *d = calloc(1, sizeof *d);
    if (!d) {
        return sem_error_set(err, SEM_ERR_NOMEM, "out of memory");
    }
    d->model_hash = hash;
    d->order = r_i32(&r);
    d->n_basis = r_i32(&r);
    d->n_parts = r_i32(&r);
    d->n_ctrl = r_i32(&r);
    d->n_samples = r_i32(&r);
    d->n_quad = r_i32(&r);
    d->n_origins = r_i32(&r);
    if (r.st == SEM_OK &&
        ((d->order != 1 && d->order != 2) || d->n_basis != (d->order == 1 ? 4 : 10) ||
         d->n_parts < 0 || d->n_ctrl < 0 || d->n_samples < 0 || d->n_quad < 0 ||
         d->n_origins < 0 || d->n_quad > INT32_MAX / 3 || d->n_parts > INT32_MAX / 10))
        r_fail(&r, "bad sizes");
    d->volume = r_f64(&r);
    d->alpha = r_f64(&r);
    d->gamma = r_f64(&r);
    d->length_scale = r_f64(&r);
    d->stiffness_nnz_percent = r_f64(&r);
    d->weight_nonzero_fraction = r_f64(&r);
    d->timings.sample_s = r_f64(&r);
    d->timings.scene_s = r_f64(&r);
    d->timings.quad_s = r_f64(&r);
    d->timings.weights_s = r_f64(&r);
    d->timings.build_pi_s = r_f64(&r);
    d->timings.operators_s = r_f64(&r);
    {
        struct {
            double *dst;
            size_t n;
            const char *what;
        } fixed[4] = {{d->frame_axes, 9, "frame_axes"},
                      {d->frame_center, 3, "frame_center"},
                      {d->frame_lo, 3, "frame_lo"},
                      {d->frame_hi, 3, "frame_hi"}};
        for (int k = 0; k < 4 && r.st == SEM_OK; ++k) {
            double *v = r_doubles(&r, fixed[k].n, fixed[k].what);
            if (v) memcpy(fixed[k].dst, v, fixed[k].n * sizeof *v);
            free(v);
        }
    }
    d->quad_spacing = r_f64(&r);
    d->shared_fit = r_i32(&r);
    if (r.st == SEM_OK && d->shared_fit != 0 && d->shared_fit != 1) r_fail(&r, "bad shared_fit");

    if (r.st == SEM_OK) {
        size_t P = (size_t)d->n_parts, S = (size_t)d->n_samples, Q = (size_t)d->n_quad;
        d->part_ctrl_offset = r_ints(&r, P + 1, "part_ctrl_offset");
        d->sample_part = r_ints(&r, S, "sample_part");
        d->sample_uv = r_doubles(&r, 2 * S, "sample_uv");
        d->sample_X = r_doubles(&r, 3 * S, "sample_X");
        d->sample_area = r_doubles(&r, S, "sample_area");
        d->sample_seam = r_doubles(&r, S, "sample_seam");
        r_csr(&r, &d->J_hat, d->n_samples, d->n_ctrl, "J_hat");
        d->quad_X = r_doubles(&r, 3 * Q, "quad_X");
        d->quad_volume = r_doubles(&r, Q, "quad_volume");
        d->quad_part = r_ints(&r, Q, "quad_part");
        r_csr(&r, &d->W, d->n_quad, d->n_parts, "W");
        r_csr(&r, &d->W_samples, d->n_samples, d->n_parts, "W_samples");
        d->origin_X = r_doubles(&r, 3 * (size_t)d->n_origins, "origin_X");
        d->part_origin = r_ints(&r, P, "part_origin");
        d->part_covered = r_ints(&r, P, "part_covered");
        r_csr(&r, &d->Pi, d->n_parts * d->n_basis, d->n_ctrl, "Pi");
        r_csr(&r, &d->Gamma, d->n_quad, d->n_ctrl, "Gamma");
        r_csr(&r, &d->Grad, 3 * d->n_quad, d->n_ctrl, "Grad");
        r_csr(&r, &d->Gamma_samples, d->n_samples, d->n_ctrl, "Gamma_samples");
        r_csr(&r, &d->M, d->n_ctrl, d->n_ctrl, "M");
        r_csr(&r, &d->M_eps, d->n_ctrl, d->n_ctrl, "M_eps");
    }
    if (r.st == SEM_OK && r.pos != r.size) r_fail(&r, "trailing bytes");
    if (r.st == SEM_OK) {
        check_index_array(&r, d->sample_part, (size_t)d->n_samples, d->n_parts, "sample_part");
        check_index_array(&r, d->quad_part, (size_t)d->n_quad, d->n_parts, "quad_part");
        check_index_array(&r, d->part_origin, (size_t)d->n_parts, d->n_origins, "part_origin");
        if (d->part_ctrl_offset) {
            if (d->part_ctrl_offset[0] != 0 || d->part_ctrl_offset[d->n_parts] != d->n_ctrl)
                r_fail(&r, "bad part_ctrl_offset");
            for (int i = 0; i < d->n_parts && r.st == SEM_OK; ++i)
                if (d->part_ctrl_offset[i + 1] < d->part_ctrl_offset[i])
                    r_fail(&r, "bad part_ctrl_offset");
        }
    }
    if (r.st != SEM_OK) {
        sem_discretization_destroy(d);
        return r.st;
    }
    *out = d;
    return SEM_OK;
}
