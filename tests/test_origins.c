/* test_origins.c - deformation origins by min-cost flow (paper Sec. 6.2, Eq. 10): a small
 * case solved by hand, every part gets exactly one origin, isolated parts get their own,
 * the assignment is optimal on random networks and the one GLPK's min-cost flow solver gives
 * there and on the shared models (origins.c solves the network in closed form), origins sit
 * at area-weighted sample centroids, bad input is rejected. */
#include <glpk.h>
#include <math.h>
#include <stddef.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "preprocess/steps.h"
#include "sem/model.h"
#include "sem/preprocess.h"
#include "test_util.h"

static double now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec + 1e-9 * ts.tv_nsec;
}

/* W from dense rows (zeros dropped). */
static void set_W(sem_discretization *d, int n_rows, int n_cols, const double *dense)
{
    int *r = malloc((size_t)n_rows * n_cols * sizeof *r);
    int *c = malloc((size_t)n_rows * n_cols * sizeof *c);
    double *v = malloc((size_t)n_rows * n_cols * sizeof *v);
    size_t n = 0;
    for (int i = 0; i < n_rows; ++i)
        for (int j = 0; j < n_cols; ++j)
            if (dense[(size_t)i * n_cols + j] != 0.0) {
                r[n] = i;
                c[n] = j;
                v[n] = dense[(size_t)i * n_cols + j];
                ++n;
            }
    CHECK(sem_csr_from_triplets(&d->W, n_rows, n_cols, n, r, c, v) == SEM_OK, "triplets");
    free(r);
    free(c);
    free(v);
}

static void free_origins(sem_discretization *d)
{
    free(d->origin_X);
    free(d->part_origin);
    d->origin_X = NULL;
    d->part_origin = NULL;
    d->n_origins = 0;
}

/* Five parts. Groups (sets of parts with weight at a point) and their costs (sum of the
 * part's weight over the group's points):
 *   {0,1}   rows 0,1   costs p0 1.1, p1 0.9
 *   {1,2}   row 2      costs p1 0.5, p2 0.5
 *   {0,1,2} row 3      costs p0 0.2, p1 0.2, p2 0.6
 *   {3}     rows 4,5   (single part: not a candidate)
 *   part 4 has no weight anywhere.
 * Optimum (total 0.9): p0, p1 -> {0,1,2}; p2 -> {1,2}; parts 3 and 4 isolated: 4 origins,
 * numbered by smallest part: 0 = {0,1}, 1 = {2}, 2 = {3}, 3 = {4}. */
static void test_hand_case(void)
{
    const double dense[6 * 5] = {0.5, 0.5, 0, 0, 0,  0.6, 0.4, 0, 0, 0,  0, 0.5, 0.5, 0, 0,
                                 0.2, 0.2, 0.6, 0, 0, 0, 0, 0, 1, 0,     0, 0, 0, 1, 0};
    sem_discretization d;
    memset(&d, 0, sizeof d);
    d.n_parts = 5;
    d.n_quad = 6;
    double quad_X[6 * 3] = {0};
    d.quad_X = quad_X;
    set_W(&d, 6, 5, dense);
    /* samples: part 0 at (0,0,0) area 1 and (2,0,0) area 3; part 1 at (0,4,0) area 2;
     * part 2 at (0,0,5); part 3 at (7,7,7), (9,7,7); part 4 with zero area at (1,1,1),
     * (3,3,3) (the plain mean is the fallback) */
    double sample_X[8 * 3] = {0, 0, 0, 2, 0, 0, 0, 4, 0, 0, 0, 5, 7, 7, 7, 9, 7, 7, 1, 1, 1, 3, 3, 3};
    double sample_area[8] = {1, 3, 2, 1, 0.5, 0.5, 0, 0};
    int sample_part[8] = {0, 0, 1, 2, 3, 3, 4, 4};
    d.n_samples = 8;
    d.sample_X = sample_X;
    d.sample_area = sample_area;
    d.sample_part = sample_part;
    sem_error err;
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.n_origins == 4, "n_origins %d", d.n_origins);
    const int expect[5] = {0, 0, 1, 2, 3};
    for (int p = 0; p < 5; ++p)
        CHECK(d.part_origin && d.part_origin[p] == expect[p], "part %d origin %d, expected %d", p,
              d.part_origin ? d.part_origin[p] : -1, expect[p]);
    if (d.n_origins == 4 && d.origin_X) {
        const double o[4][3] = {{1, 4.0 / 3.0, 0}, {0, 0, 5}, {8, 7, 7}, {2, 2, 2}};
        for (int j = 0; j < 4; ++j)
            for (int e = 0; e < 3; ++e) CHECK_NEAR(d.origin_X[3 * j + e], o[j][e], 1e-12);
    }

    /* raising the cost of {0,1,2} for part 0 moves part 0 to {0,1} (cost 1.1 < 1.2) */
    free_origins(&d);
    sem_csr_free(&d.W);
    double dense2[6 * 5];
    memcpy(dense2, dense, sizeof dense2);
    dense2[3 * 5 + 0] = 0.6; /* row 3: p0 0.6, p1 0.2, p2 0.6 */
    /* and one more point of the set {0,1,2}: p0's cost there becomes 1.2 */
    double dense3[7 * 5];
    memcpy(dense3, dense2, sizeof dense2);
    const double extra[5] = {0.6, 0.2, 0.2, 0, 0};
    memcpy(&dense3[6 * 5], extra, sizeof extra);
    set_W(&d, 7, 5, dense3);
    double quad3[7 * 3] = {0};
    d.quad_X = quad3;
    d.n_quad = 7;
    /* costs: {0,1}: p0 1.1 p1 0.9; {1,2}: p1 0.5 p2 0.5; {0,1,2}: p0 1.2 p1 0.4 p2 0.8
     * optimum: p0 -> {0,1}, p1 -> {0,1,2}, p2 -> {1,2}: origins {0}, {1}, {2}, {3}, {4} */
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.n_origins == 5, "n_origins %d", d.n_origins);
    for (int p = 0; p < 5 && d.part_origin; ++p)
        CHECK(d.part_origin[p] == p, "part %d origin %d", p, d.part_origin[p]);
    if (d.n_origins == 5) {
        CHECK_NEAR(d.origin_X[0], 1.5, 1e-12); /* part 0 alone: (0*1 + 2*3) / 4 */
        CHECK_NEAR(d.origin_X[3 * 1 + 1], 4.0, 1e-12);
    }

    /* bad input: W of the wrong shape, sample of a part out of range */
    free_origins(&d);
    d.n_parts = 4;
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_ERR_INVALID, "W shape");
    d.n_parts = 5;
    sample_part[2] = 9;
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_ERR_INVALID, "sample part");
    CHECK(strstr(err.message, "sample") != NULL, "message: %s", err.message);
    sample_part[2] = 1;
    d.W.col[0] = 7;
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_ERR_INVALID, "W column");
    free_origins(&d);
    sem_csr_free(&d.W);

    /* no quadrature points at all: every part is isolated, at its own sample centroid */
    d.n_quad = 0;
    d.quad_X = NULL;
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_OK, "%s", err.message);
    CHECK(d.n_origins == 5, "empty W: %d origins", d.n_origins);
    if (d.n_origins == 5) CHECK_NEAR(d.origin_X[3 * 3 + 0], 8.0, 1e-12);
    free_origins(&d);
}

/* xorshift: reproducible random numbers */
static unsigned long long rng_state = 88172645463325252ull;
static double rnd(void) { return test_uniform(&rng_state); }

/* Random W over 40 parts; 5 parts never appear, 3 appear only alone. Checks: one origin
 * per part, every origin used, isolated parts alone, and each origin's parts all lie in
 * one group for which each of them pays its minimum cost (the capacities never bind, so
 * the optimum is that per-part minimum). */
/* The network of origins.c's header, built from W and solved by GLPK's out-of-kilter
 * algorithm (the reference: origins.c solves it in closed form). group[p]: the first row of
 * the group (set of parts of a row of W with two parts or more) whose candidate part p takes,
 * or -1. Returns the total (scaled, rounded) cost, or -1 on failure. */
typedef struct ref_vertex {
    double rhs;
} ref_vertex;
typedef struct ref_arc {
    double low, cap, cost, x;
} ref_arc;

static double glpk_assignment(const sem_csr *W, int n_parts, int *group)
{
    int n = W->n_rows;
    int *first = malloc((size_t)n * sizeof *first), n_groups = 0; /* groups by first row */
    int *row_group = malloc((size_t)n * sizeof *row_group);
    for (int r = 0; r < n; ++r) {
        row_group[r] = -1;
        int len = W->row_start[r + 1] - W->row_start[r];
        if (len < 2) continue;
        for (int g = 0; g < n_groups && row_group[r] < 0; ++g) {
            int f = first[g], lf = W->row_start[f + 1] - W->row_start[f];
            if (lf == len && !memcmp(&W->col[W->row_start[f]], &W->col[W->row_start[r]], (size_t)len * sizeof(int)))
                row_group[r] = g;
        }
        if (row_group[r] < 0) {
            first[n_groups] = r;
            row_group[r] = n_groups++;
        }
    }
    double *cost = calloc((size_t)n_groups * n_parts + 1, sizeof *cost);
    double total = 0;
    for (int r = 0; r < n; ++r)
        if (row_group[r] >= 0)
            for (int e = W->row_start[r]; e < W->row_start[r + 1]; ++e) {
                cost[(size_t)row_group[r] * n_parts + W->col[e]] += W->val[e];
                total += W->val[e];
            }
    int *in_some = calloc((size_t)n_parts, sizeof *in_some), n_covered = 0;
    for (int g = 0; g < n_groups; ++g)
        for (int e = W->row_start[first[g]]; e < W->row_start[first[g] + 1]; ++e)
            if (!in_some[W->col[e]]) in_some[W->col[e]] = ++n_covered;
    const int source = 1, first_candidate = 2, first_part = 2 + n_groups, sink = first_part + n_covered;
    int prev = glp_term_out(GLP_OFF);
    glp_graph *G = glp_create_graph((int)sizeof(ref_vertex), (int)sizeof(ref_arc));
    glp_add_vertices(G, sink);
    for (int v = 1; v <= sink; ++v) ((ref_vertex *)G->v[v]->data)->rhs = 0;
    ((ref_vertex *)G->v[source]->data)->rhs = n_covered;
    ((ref_vertex *)G->v[sink]->data)->rhs = -n_covered;
    const double scale = total > 0 ? 1e9 / total : 0;
    for (int g = 0; g < n_groups; ++g) {
        int f = first[g], len = W->row_start[f + 1] - W->row_start[f];
        ref_arc *a = glp_add_arc(G, source, first_candidate + g)->data;
        *a = (ref_arc){0, len, 0, 0};
        for (int e = W->row_start[f]; e < W->row_start[f + 1]; ++e) {
            int p = W->col[e];
            a = glp_add_arc(G, first_candidate + g, first_part + in_some[p] - 1)->data;
            *a = (ref_arc){0, 1, floor(cost[(size_t)g * n_parts + p] * scale + 0.5), 0};
        }
    }
    for (int p = 0; p < n_parts; ++p)
        if (in_some[p]) {
            ref_arc *a = glp_add_arc(G, first_part + in_some[p] - 1, sink)->data;
            *a = (ref_arc){0, 1, 0, 0};
        }
    double opt = -1;
    int ret = glp_mincost_okalg(G, (int)offsetof(ref_vertex, rhs), (int)offsetof(ref_arc, low),
                                (int)offsetof(ref_arc, cap), (int)offsetof(ref_arc, cost), &opt,
                                (int)offsetof(ref_arc, x), -1);
    glp_term_out(prev);
    for (int p = 0; p < n_parts; ++p) group[p] = -1;
    if (ret == 0)
        for (int g = 0; g < n_groups; ++g)
            for (glp_arc *a = G->v[first_candidate + g]->out; a; a = a->t_next)
                if (((ref_arc *)a->data)->x > 0.5)
                    for (int p = 0; p < n_parts; ++p)
                        if (in_some[p] && first_part + in_some[p] - 1 == a->head->i) group[p] = first[g];
    glp_delete_graph(G);
    free(first);
    free(row_group);
    free(cost);
    free(in_some);
    return ret == 0 ? opt : -1;
}

/* origins.c's assignment against GLPK's on d (after sem_step_origins): parts share an origin
 * exactly when GLPK gave them the same candidate (parts of no candidate: alone). */
static void check_against_glpk(const sem_discretization *d, const char *name)
{
    int *group = malloc(((size_t)d->n_parts + 1) * sizeof *group);
    double opt = glpk_assignment(&d->W, d->n_parts, group);
    CHECK(opt >= 0, "%s: GLPK's min-cost flow failed", name);
    int differ = 0;
    for (int p = 0; p < d->n_parts; ++p)
        for (int q = p + 1; q < d->n_parts; ++q) {
            int same_glpk = group[p] >= 0 && group[p] == group[q];
            int same_ours = d->part_origin[p] == d->part_origin[q];
            differ += same_glpk != same_ours;
        }
    printf("%s: origins against GLPK's min-cost flow (cost %.0f): %d part pairs differ\n", name, opt, differ);
    CHECK(differ == 0, "%s: %d part pairs grouped differently from GLPK's min-cost flow", name, differ);
    free(group);
}

static void test_random(void)
{
    const int P = 40, N = 3000, n_sets = 60;
    int set_size[60], set_parts[60][4];
    for (int s = 0; s < n_sets; ++s) {
        set_size[s] = s < 6 ? 1 : 2 + (int)(rnd() * 3);
        for (int k = 0; k < set_size[s]; ++k) {
            int p;
            int dup;
            do {
                p = s < 6 ? 32 + s % 3 : (int)(rnd() * 32);
                dup = 0;
                for (int m = 0; m < k; ++m) dup |= set_parts[s][m] == p;
            } while (dup);
            set_parts[s][k] = p;
        }
    }
    double *dense = calloc((size_t)N * P, sizeof *dense);
    for (int i = 0; i < N; ++i) {
        int s = (int)(rnd() * n_sets);
        double sum = 0, w[4];
        for (int k = 0; k < set_size[s]; ++k) sum += w[k] = 0.05 + rnd();
        for (int k = 0; k < set_size[s]; ++k) dense[(size_t)i * P + set_parts[s][k]] = w[k] / sum;
    }
    sem_discretization d;
    memset(&d, 0, sizeof d);
    d.n_parts = P;
    d.n_quad = N;
    d.quad_X = calloc(3 * (size_t)N, sizeof *d.quad_X);
    for (int i = 0; i < 3 * N; ++i) d.quad_X[i] = rnd();
    set_W(&d, N, P, dense);
    d.n_samples = 2 * P;
    d.sample_X = malloc(3 * (size_t)d.n_samples * sizeof *d.sample_X);
    d.sample_area = malloc((size_t)d.n_samples * sizeof *d.sample_area);
    d.sample_part = malloc((size_t)d.n_samples * sizeof *d.sample_part);
    for (int k = 0; k < d.n_samples; ++k) {
        d.sample_part[k] = k / 2;
        d.sample_area[k] = 0.1 + rnd();
        for (int e = 0; e < 3; ++e) d.sample_X[3 * k + e] = 10 * rnd();
    }
    sem_error err;
    double t0 = now();
    CHECK(sem_step_origins(NULL, &d, &err) == SEM_OK, "%s", err.message);
    printf("random: %d parts, %d points, %d origins, %.4f s\n", P, N, d.n_origins, now() - t0);
    check_against_glpk(&d, "random");

    /* group costs by set: recompute from the dense rows */
    double cost[60][4];
    int set_of_row_ok = 1;
    memset(cost, 0, sizeof cost);
    for (int i = 0; i < N; ++i) {
        int found = -1;
        for (int s = 0; s < n_sets && found < 0; ++s) {
            int nz = 0, match = 1;
            for (int p = 0; p < P; ++p) nz += dense[(size_t)i * P + p] != 0;
            if (nz != set_size[s]) continue;
            for (int k = 0; k < set_size[s]; ++k) match &= dense[(size_t)i * P + set_parts[s][k]] != 0;
            if (match) found = s;
        }
        if (found < 0) {
            set_of_row_ok = 0;
            continue;
        }
        for (int k = 0; k < set_size[found]; ++k)
            cost[found][k] += dense[(size_t)i * P + set_parts[found][k]];
    }
    CHECK(set_of_row_ok, "rows match sets");
    /* minimum cost per part over the distinct multi-part sets it occurs in (duplicate sets
     * share rows, so their recomputed costs coincide and are counted once) */
    double min_cost[40];
    for (int p = 0; p < P; ++p) min_cost[p] = INFINITY;
    for (int s = 6; s < n_sets; ++s)
        for (int k = 0; k < set_size[s]; ++k)
            if (cost[s][k] > 0 && cost[s][k] < min_cost[set_parts[s][k]])
                min_cost[set_parts[s][k]] = cost[s][k];

    int *used = calloc((size_t)d.n_origins + 1, sizeof *used);
    int ok_range = 1;
    for (int p = 0; p < P; ++p) {
        if (!d.part_origin || d.part_origin[p] < 0 || d.part_origin[p] >= d.n_origins) {
            ok_range = 0;
            continue;
        }
        used[d.part_origin[p]]++;
    }
    CHECK(ok_range, "part_origin out of range");
    for (int j = 0; j < d.n_origins; ++j) CHECK(used[j] > 0, "origin %d unused", j);
    /* parts 32..39 never share a group: each alone at its origin */
    for (int p = 32; p < P && ok_range; ++p) CHECK(used[d.part_origin[p]] == 1, "isolated %d", p);
    /* optimality */
    for (int j = 0; j < d.n_origins && ok_range; ++j) {
        int members[40], n_members = 0;
        for (int p = 0; p < P; ++p)
            if (d.part_origin[p] == j) members[n_members++] = p;
        if (members[0] >= 32) continue;
        int good = 0;
        for (int s = 6; s < n_sets && !good; ++s) {
            int all = 1;
            for (int m = 0; m < n_members && all; ++m) {
                int in = -1;
                for (int k = 0; k < set_size[s]; ++k)
                    if (set_parts[s][k] == members[m]) in = k;
                all = in >= 0 && cost[s][in] > 0 && cost[s][in] <= min_cost[members[m]] * (1 + 1e-6);
            }
            good = all;
        }
        CHECK(good, "origin %d (%d parts, first %d) is not an optimal group", j, n_members, members[0]);
    }
    /* positions: area-weighted sample centroids of the origin's parts */
    for (int j = 0; j < d.n_origins && ok_range; ++j) {
        double s[3] = {0, 0, 0}, a = 0;
        for (int k = 0; k < d.n_samples; ++k)
            if (d.part_origin[d.sample_part[k]] == j) {
                for (int e = 0; e < 3; ++e) s[e] += d.sample_area[k] * d.sample_X[3 * k + e];
                a += d.sample_area[k];
            }
        for (int e = 0; e < 3; ++e) CHECK_NEAR(d.origin_X[3 * j + e], s[e] / a, 1e-12);
    }
    free(used);
    free(dense);
    free_origins(&d);
    sem_csr_free(&d.W);
    free(d.quad_X);
    free(d.sample_X);
    free(d.sample_area);
    free(d.sample_part);
}

/* Sampling + quadrature + weights + origins on real models. */
static void test_shared_models(void)
{
    static const char *models[] = {
        "rocket/rocket.iges",       "starship/starship_fall_simpler.igs",
        "beams/beam_cmp3_b.iges",   "lamppost.iges",
        "tire.iges",                "chicken/chicken_simple_closed.iges",
        "mugs/mug_trimmed_complex.iges", "mugs/mug_trimmed_complex_bad.iges",
        "castle/castle_super_simple.iges", "grumpy.iges",
        "puft/puft_full_simpler.iges", "beams/perf/b10.igs",
        "beams/cubes/cube100.iges", "rounded_cube.iges",
        "cylinder.iges",
    };
    const int n_models = (int)(sizeof models / sizeof models[0]);
    if (!test_shared_model("beams/beam_cmp3_b.iges")) {
        printf("skipped: shared models not found\n");
        return;
    }
    const char *only = getenv("SEM_TEST_MODEL"); /* run one model (debugging) */
    setvbuf(stdout, NULL, _IONBF, 0);
    for (int i = 0; i < n_models; ++i) {
        if (only && !strstr(models[i], only)) continue;
        const char *path = test_shared_model(models[i]);
        if (!path) {
            printf("%s: missing\n", models[i]);
            continue;
        }
        sem_model *m = NULL;
        sem_error err;
        if (sem_model_load(path, &m, &err) != SEM_OK) {
            CHECK(0, "%s: %s", models[i], err.message);
            continue;
        }
        sem_preprocess_options o = sem_default_preprocess_options();
        o.sparsity = 0.5; /* keep some weights sparse so groups are many */
        sem_discretization *d = calloc(1, sizeof *d);
        sem_raycast_scene *scene = NULL;
        sem_status st = sem_step_sample(m, 0, d, &err);
        if (st == SEM_OK) st = sem_raycast_scene_build(m, o.tessellation, &scene, &err);
        if (st == SEM_OK) st = sem_step_quadrature(m, scene, &o, d, &err);
        double t0 = now();
        if (st == SEM_OK) st = sem_step_weights(m, scene, &o, d, &err);
        double t1 = now();
        if (st == SEM_OK) st = sem_step_origins(m, d, &err);
        double t2 = now();
        CHECK(st == SEM_OK, "%s: %s", models[i], err.message);
        if (st == SEM_OK) {
            int ok = d->n_origins >= 1 && d->n_origins <= d->n_parts;
            int *used = calloc((size_t)d->n_origins + 1, sizeof *used);
            for (int p = 0; p < d->n_parts && ok; ++p) {
                ok &= d->part_origin[p] >= 0 && d->part_origin[p] < d->n_origins;
                if (ok) used[d->part_origin[p]]++;
            }
            for (int j = 0; j < d->n_origins && ok; ++j)
                ok &= used[j] > 0 && isfinite(d->origin_X[3 * j]) && isfinite(d->origin_X[3 * j + 1]) &&
                      isfinite(d->origin_X[3 * j + 2]);
            free(used);
            CHECK(ok, "%s: bad origins", models[i]);
            if (ok) check_against_glpk(d, models[i]);
            printf("%-36s parts %4d quad %6d  alpha %.4g nnz %.3f  origins %4d  weights %.3f s "
                   "origins %.4f s\n",
                   models[i], d->n_parts, d->n_quad, d->alpha, d->weight_nonzero_fraction,
                   d->n_origins, t1 - t0, t2 - t1);
        }
        sem_raycast_scene_destroy(scene);
        sem_discretization_destroy(d);
        sem_model_destroy(m);
    }
}

int main(void)
{
    test_hand_case();
    test_random();
    test_shared_models();
    return test_finish("test_origins");
}
