/*
 * memory_estimate.c - how much memory a run of an object needs, estimated from the sizes of
 * its discretization before the world allocates anything large (sem_world_estimate_memory).
 *
 * Why an estimate and not a measurement: `sem run` must warn before it starts, on a machine
 * that may not hold the run at all, so the figure comes from counts alone (control points,
 * parts, groups, quadrature points, samples, weights) in one cheap pass over the weights.
 *
 * Every term below mirrors an allocation of the code that exists today; when a file changes
 * what it allocates (the linear solver above all), change its term here, and
 * tests/test_memory.c checks the total against the measured peak of a real run (within a
 * factor 2). Sizes: double 8 bytes, int 4.
 *
 *   discretization  the preprocessed data the run keeps: every array and sparse matrix of
 *                   sem_discretization, counted exactly.
 *   preprocessing   what sem_preprocess holds beyond its result while it runs: the factored
 *                   operators (G, G' at the points and samples, the Gustavson accumulators)
 *                   and the ray-cast scene (tessellation of every knot span, Embree's BVH).
 *                   Not needed when the discretization comes from the cache, counted anyway
 *                   (a cold cache is the case that matters).
 *   blocks          the dense group-pair blocks (object.h): K and K0 (9 scalars per entry,
 *                   one per coordinate pair), M and M_eps (1 each), their CSR copy (2
 *                   doubles + 1 int) and the system's map of every K entry into the sparse
 *                   pattern (9 ints). 216 bytes per entry, entries = sum over the ordered
 *                   group pairs coupled by a quadrature point or a sample of |Ga| |Gb|. This
 *                   is the dominant term of models whose weights couple most parts.
 *   assembly        per part pair Kz ((3 ma)^2 doubles, ma = m - 1) and its running sum
 *                   (packed), the per-point chunk N (at most assembly_chunk points), the
 *                   per-point basis gradients, weight products and pair lists, Pi per part
 *                   as dense matrices, and the n_parts^2 / n_groups^2 lookup tables.
 *   solver          the system matrix (lower triangle of the 3 n_ctrl x 3 n_ctrl pattern, its
 *                   CHOLMOD copy, sort keys and maps: ~40 bytes per entry) and the Cholesky
 *                   factor: dense n^2 doubles up to SEM_DENSE_MAX_DOFS, else CHOLMOD's
 *                   supernodal factor, estimated as 4 x the matrix's entries (measured fill
 *                   on the Table 1 models: 1.3 - 3.4, with supernode padding) and never more
 *                   than the dense lower triangle. Counted three times: the world keeps
 *                   the rest matrix's factor beside the step's (integrators.c, "Reusing the
 *                   rest factor"; with its own copy of the values), and the zero-energy mode
 *                   check factors the free object while the world's own solver is made later
 *                   (freed memory is not always returned to the system). The q-space path
 *                   also keeps every quadrature point's 9 x 9 Hessian, now and at rest.
 *   structured      instead of blocks and solver, when the discretization has no q-space
 *                   operators (the structured solver, physics/structured.h): Pi over the
 *                   control points and its reduced copy in V with G (the same size again) and
 *                   V's transpose, the sample rows (J-hat and the coefficient rows g),
 *                   coefficient matrices (Mz, Bb, Bz by part-pair blocks, F and the Schur
 *                   complement with its scratch: about 10 (3 n_parts m)^2 doubles; with shared
 *                   fits 10 (3 n_origins m)^2), S0 and its factor (about 8
 *                   entries per J-hat entry) and the chunk of F's sparse solves.
 *   base            the program itself with its libraries (OpenBLAS buffers, Embree,
 *                   CHOLMOD, OpenMP stacks): 60 MB, measured as sem run's peak on a box.
 *
 * Peak = base + discretization + max(preprocessing, blocks + assembly + solver): the
 * preprocessing's temporaries are freed before the world is built.
 */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "sem/simulation.h"

#define BYTES_DOUBLE 8.0
#define BYTES_INT 4.0
/* Dense solver up to this many dofs (linear_solver.c, SEM_DENSE_MAX_DOFS). */
#define DENSE_MAX_DOFS 500.0
/* Points per stiffness chunk (assembly.c default). */
#define ASSEMBLY_CHUNK 8192.0
/* CHOLMOD factor entries per system matrix entry (see the opening comment). */
#define FACTOR_FILL 4.0
/* The program and its libraries (see the opening comment). */
#define BASE_BYTES (60.0 * 1024 * 1024)

static double csr_bytes(const sem_csr *a)
{
    return (double)sem_csr_nnz(a) * (BYTES_DOUBLE + BYTES_INT) + ((double)a->n_rows + 1) * BYTES_INT;
}

static double discretization_bytes(const sem_discretization *d)
{
    double b = 0;
    b += ((double)d->n_parts + 1) * BYTES_INT * 3; /* ctrl offsets, origins, covered */
    b += (double)d->n_samples * (BYTES_INT + 7 * BYTES_DOUBLE); /* part, uv, X, area, seam */
    b += (double)d->n_quad * (BYTES_INT + 4 * BYTES_DOUBLE);    /* part, X, volume */
    b += (double)d->n_origins * 3 * BYTES_DOUBLE;
    const sem_csr *mats[] = {&d->J_hat, &d->W, &d->W_samples, &d->Pi, &d->Gamma,
                             &d->Grad,  &d->Gamma_samples, &d->M, &d->M_eps};
    for (size_t k = 0; k < sizeof mats / sizeof mats[0]; ++k) b += csr_bytes(mats[k]);
    return b;
}

/* Sets bit (a, b) of an n x n bitmap; returns 1 when it was clear. */
static int mark(uint64_t *bits, size_t n, int a, int b)
{
    size_t k = (size_t)a * n + (size_t)b;
    uint64_t m = (uint64_t)1 << (k & 63);
    if (bits[k >> 6] & m) return 0;
    bits[k >> 6] |= m;
    return 1;
}

sem_status sem_world_estimate_memory(const sem_discretization *d, sem_memory_estimate *out,
                                     sem_error *err)
{
    if (!d || !out) return sem_error_set(err, SEM_ERR_INVALID, "memory estimate: NULL argument");
    memset(out, 0, sizeof *out);
    const int np = d->n_parts, ng = d->n_origins, m = d->n_basis > 0 ? d->n_basis : 10;
    if (np <= 0 || ng <= 0 || !d->part_origin || !d->part_ctrl_offset)
        return sem_error_set(err, SEM_ERR_INVALID, "memory estimate: the discretization has no parts or origins");
    for (int i = 0; i < np; ++i)
        if (d->part_origin[i] < 0 || d->part_origin[i] >= ng)
            return sem_error_set(err, SEM_ERR_INVALID, "memory estimate: part %d has no valid origin", i);
    /* group sizes (control points of the parts sharing an origin) */
    double *group_size = calloc((size_t)ng, sizeof *group_size);
    uint64_t *part_bits = calloc(((size_t)np * np + 63) / 64, sizeof *part_bits);
    uint64_t *group_bits = calloc(((size_t)ng * ng + 63) / 64, sizeof *group_bits);
    if (!group_size || !part_bits || !group_bits) {
        free(group_size);
        free(part_bits);
        free(group_bits);
        return sem_error_set(err, SEM_ERR_NOMEM, "memory estimate: out of memory");
    }
    for (int i = 0; i < np; ++i)
        group_size[d->part_origin[i]] += d->part_ctrl_offset[i + 1] - d->part_ctrl_offset[i];
    double pi_dense = 0;
    for (int i = 0; i < np; ++i) pi_dense += group_size[d->part_origin[i]];

    /* part pairs and group pairs coupled by a quadrature point or a boundary sample; block
     * entries; the per-point pair lists of the assembly */
    double entries = 0, part_pairs = 0, point_pairs = 0, plist = 0;
    const sem_csr *Ws[2] = {&d->W, &d->W_samples};
    for (int w = 0; w < 2; ++w) {
        const sem_csr *W = Ws[w];
        if (!W->row_start) continue;
        for (int p = 0; p < W->n_rows; ++p) {
            int r0 = W->row_start[p], r1 = W->row_start[p + 1];
            if (w == 0) {
                double k = r1 - r0;
                point_pairs += k * k;
                plist += k * (k + 1) / 2;
            }
            for (int a = r0; a < r1; ++a)
                for (int b = r0; b < r1; ++b) {
                    int i = W->col[a], j = W->col[b];
                    if (i < 0 || i >= np || j < 0 || j >= np || !mark(part_bits, (size_t)np, i, j)) continue;
                    part_pairs++;
                    int ga = d->part_origin[i], gb = d->part_origin[j];
                    if (mark(group_bits, (size_t)ng, ga, gb)) entries += group_size[ga] * group_size[gb];
                }
        }
    }
    free(part_bits);
    free(group_bits);
    free(group_size);

    const double n_quad = d->n_quad, ma = m - 1, n3 = 3 * ma, packed = n3 * (n3 + 1) / 2;
    const double w_nnz = (double)sem_csr_nnz(&d->W) + (double)sem_csr_nnz(&d->W_samples);

    out->discretization = discretization_bytes(d);
    /* the factored operators G and G' (1 + 3 rows per point or sample, m columns per weight
     * entry) and their transposes, the products' dense accumulators (n_ctrl per thread, two
     * threads), and the tessellation with its BVH: about 32 KB per knot span (16 x 16 cells,
     * two triangles each, ~64 bytes per triangle with the BVH), a span holding about 9
     * samples (biquadratic) */
    const double spans = (double)d->n_samples / 9 > np ? (double)d->n_samples / 9 : np;
    out->preprocessing = 2 * 4 * w_nnz * m * (BYTES_DOUBLE + BYTES_INT) +
                         4 * (double)d->n_ctrl * (BYTES_DOUBLE + BYTES_INT) + spans * 16 * 16 * 2 * 64;
    out->blocks = entries * (20 * BYTES_DOUBLE + 2 * BYTES_DOUBLE + BYTES_INT + 9 * BYTES_INT);
    out->assembly = part_pairs * (n3 * n3 + (n_quad > ASSEMBLY_CHUNK ? packed : 0)) * BYTES_DOUBLE +
                    (n_quad < ASSEMBLY_CHUNK ? n_quad : ASSEMBLY_CHUNK) * packed * BYTES_DOUBLE +
                    n_quad * (3 * ma + 2) * BYTES_DOUBLE + plist * (BYTES_DOUBLE + BYTES_INT) +
                    point_pairs * BYTES_INT + (double)sem_csr_nnz(&d->W) * m * BYTES_DOUBLE +
                    pi_dense * (m + ma) * BYTES_DOUBLE + (double)np * np * BYTES_INT +
                    (double)ng * ng * BYTES_INT;
    /* the system: lower triangle of the 3 x 3 blocks of every entry, plus the diagonal */
    const double n_dofs = 3.0 * d->n_ctrl, matrix = (9 * entries + n_dofs) / 2;
    const double dense_lower = n_dofs * (n_dofs + 1) / 2;
    double factor = n_dofs <= DENSE_MAX_DOFS ? n_dofs * n_dofs
                                             : (FACTOR_FILL * matrix < dense_lower ? FACTOR_FILL * matrix
                                                                                   : dense_lower);
    out->solver = matrix * (40 + BYTES_DOUBLE) + 3 * factor * BYTES_DOUBLE;
    /* the q-space path's point Hessians, now and at rest */
    out->assembly += 162 * n_quad * BYTES_DOUBLE;
    if (sem_csr_nnz(&d->M) == 0 && d->n_ctrl > 0) {
        out->assembly -= 162 * n_quad * BYTES_DOUBLE;
        /* the structured solver (see the opening comment): no q-space blocks */
        /* with shared fits the dense matrices are over the distinct rows (origins x m) */
        const double r0 = d->shared_fit ? (double)ng * m : (double)np * m;
        const double j_nnz = (double)sem_csr_nnz(&d->J_hat);
        const double ws_nnz = (double)sem_csr_nnz(&d->W_samples);
        out->blocks = 0;
        out->solver = 5 * pi_dense * m * (BYTES_DOUBLE + BYTES_INT) + (j_nnz + ws_nnz * m) * (BYTES_DOUBLE + BYTES_INT) +
                      10 * 9 * r0 * r0 * BYTES_DOUBLE + 8 * j_nnz * (BYTES_DOUBLE + BYTES_INT) +
                      (3 * r0 <= 2000 ? 9 * r0 * r0 * BYTES_DOUBLE : 0) + /* the rest factor */
                      2 * 128 * (double)d->n_ctrl * BYTES_DOUBLE;
    }
    double run = out->blocks + out->assembly + out->solver;
    out->base = BASE_BYTES;
    out->total = out->base + out->discretization + (out->preprocessing > run ? out->preprocessing : run);
    return SEM_OK;
}
