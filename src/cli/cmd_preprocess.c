/*
 * cmd_preprocess.c - `sem preprocess FILE [options]`: run the SEM preprocessing (paper
 * Alg. 1: sampling, quadrature, weights, origins, projection, operators) on a model and
 * report its sizes and per-phase timings (the columns of Table 1); store the result in the
 * preprocessing cache that `sem run` reads (sem/cache.h; --no-cache: not), and optionally
 * save it to a file.
 *
 * Exit status: 0 on success; 1 when an option value is out of range or preprocessing
 * fails; 2 for malformed command lines (unknown option, missing or non-numeric values).
 */
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"
#include "sem/cache.h"
#include "sem/preprocess.h"
#include "sem/simulation.h"

#define CMD "preprocess"

static int parse_axis(const char *text, int *axis)
{
    if (strcmp(text, "x") == 0 || strcmp(text, "X") == 0) *axis = 0;
    else if (strcmp(text, "y") == 0 || strcmp(text, "Y") == 0) *axis = 1;
    else if (strcmp(text, "z") == 0 || strcmp(text, "Z") == 0) *axis = 2;
    else return cli_fail("--axis must be x, y or z (got '%s')", text);
    return CLI_OK;
}

static cJSON *to_json(const sem_discretization *d, double total_s)
{
    cJSON *j = cJSON_CreateObject();
    if (!j) return NULL;
    cJSON_AddNumberToObject(j, "dofs", 3.0 * d->n_ctrl);
    cJSON_AddNumberToObject(j, "control_points", d->n_ctrl);
    cJSON_AddNumberToObject(j, "parts", d->n_parts);
    cJSON_AddNumberToObject(j, "order", d->order);
    cJSON_AddNumberToObject(j, "quadrature_points", d->n_quad);
    cJSON_AddNumberToObject(j, "volume", d->volume);
    cJSON_AddNumberToObject(j, "origins", d->n_origins);
    cJSON_AddStringToObject(j, "fits", d->shared_fit ? "origins" : "parts");
    cJSON_AddNumberToObject(j, "alpha", d->alpha);
    cJSON_AddNumberToObject(j, "weight_nonzero_fraction", d->weight_nonzero_fraction);
    cJSON_AddNumberToObject(j, "pi_nonzeros", (double)sem_csr_nnz(&d->Pi));
    cJSON_AddNumberToObject(j, "stiffness_nnz_percent", d->stiffness_nnz_percent);
    cJSON_AddNumberToObject(j, "boundary_samples", d->n_samples);
    cJSON_AddNumberToObject(j, "gamma", d->gamma);
    cJSON_AddNumberToObject(j, "length_scale", d->length_scale);
    cJSON *cov = cJSON_AddArrayToObject(j, "parts_without_volume");
    for (int i = 0; d->part_covered && i < d->n_parts; ++i)
        if (d->part_covered[i]) cJSON_AddItemToArray(cov, cJSON_CreateNumber(i));
    char hash[32];
    snprintf(hash, sizeof hash, "%016llx", d->model_hash);
    cJSON_AddStringToObject(j, "hash", hash);
    cJSON *t = cJSON_AddObjectToObject(j, "timings");
    if (!t) {
        cJSON_Delete(j);
        return NULL;
    }
    cJSON_AddNumberToObject(t, "sample_s", d->timings.sample_s);
    cJSON_AddNumberToObject(t, "scene_s", d->timings.scene_s);
    cJSON_AddNumberToObject(t, "quad_s", d->timings.quad_s);
    cJSON_AddNumberToObject(t, "weights_s", d->timings.weights_s);
    cJSON_AddNumberToObject(t, "build_pi_s", d->timings.build_pi_s);
    cJSON_AddNumberToObject(t, "operators_s", d->timings.operators_s);
    cJSON_AddNumberToObject(t, "total_s", total_s);
    return j;
}

/* Zero-energy modes of the free object with the default material at E (and the default
 * blend): a throw-away world with the model as its only object. */
static sem_status find_modes(const sem_model *model, const sem_discretization *d, double E, double blend,
                             sem_object_modes *m, int *flags, sem_error *err)
{
    sem_world_def wd = sem_default_world_def();
    wd.gravity[0] = wd.gravity[1] = wd.gravity[2] = 0;
    sem_world *w = sem_world_create(&wd, err);
    if (!w) return err->status != SEM_OK ? err->status : SEM_ERR_INVALID;
    sem_object_def od = sem_default_object_def();
    od.model = model;
    od.disc = d;
    od.material.youngs_modulus = E;
    od.blend = blend;
    sem_status st = sem_material_init(&od.material, err);
    int id = st == SEM_OK ? sem_world_add_object(w, &od, err) : -1;
    if (st == SEM_OK && id < 0) st = err->status != SEM_OK ? err->status : SEM_ERR_INVALID;
    if (st == SEM_OK) st = sem_world_object_modes(w, id, m, flags, err);
    sem_world_destroy(w);
    return st;
}

static void add_modes_json(cJSON *j, const sem_object_modes *m, const int *flags, int n_parts)
{
    cJSON_AddNumberToObject(j, "spurious_modes", m->spurious);
    cJSON *v = cJSON_AddArrayToObject(j, "lowest_modes");
    for (int k = 0; k < m->n_values; ++k) cJSON_AddItemToArray(v, cJSON_CreateNumber(m->values[k]));
    cJSON_AddBoolToObject(j, "modes_converged", m->converged);
    cJSON *p = cJSON_AddArrayToObject(j, "parts_not_held");
    for (int i = 0; i < n_parts; ++i)
        if (flags[i]) cJSON_AddItemToArray(p, cJSON_CreateNumber(i));
}

static void print_human(const char *path, const sem_discretization *d, double total_s)
{
    printf("%s\n", path);
    printf("  parts                 %d\n", d->n_parts);
    printf("  control points        %d (dofs %d)\n", d->n_ctrl, 3 * d->n_ctrl);
    printf("  order                 %d (%d basis terms)\n", d->order, d->n_basis);
    printf("  boundary samples      %d\n", d->n_samples);
    printf("  quadrature points     %d\n", d->n_quad);
    printf("  volume                %.10g\n", d->volume);
    printf("  alpha                 %.6g\n", d->alpha);
    printf("  weight non-zeros      %.2f%%\n", 100.0 * d->weight_nonzero_fraction);
    printf("  deformation origins   %d\n", d->n_origins);
    printf("  polynomials           %s\n", d->shared_fit ? "one per origin (shared fits)" : "one per part");
    printf("  Pi non-zeros          %zu\n", sem_csr_nnz(&d->Pi));
    printf("  stiffness Nnz%%        %.2f%%\n", d->stiffness_nnz_percent);
    printf("  gamma                 %.6g (L = %.6g)\n", d->gamma, d->length_scale);
    printf("  timings (s)           sample %.3g  quad %.3g  weights %.3g  build Pi %.3g  "
           "operators %.3g  total %.3g\n",
           d->timings.sample_s, d->timings.quad_s, d->timings.weights_s, d->timings.build_pi_s,
           d->timings.operators_s, total_s);
}

int cmd_preprocess(int argc, char **argv)
{
    const char *path = NULL, *save = NULL;
    int json = 0, have_alpha = 0, have_sparsity = 0, modes = 1, use_cache = 1;
    double alpha = 0, sparsity = 0, blend = SEM_DEFAULT_BLEND;
    sem_preprocess_options o = sem_default_preprocess_options();
    int rc = CLI_OK;
    for (int i = 1; i < argc && rc == CLI_OK; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "--json") == 0) {
            json = 1;
        } else if (strcmp(a, "--no-modes") == 0) {
            modes = 0;
        } else if (strcmp(a, "--spacing") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &o.spacing);
            if (rc == CLI_OK && !(o.spacing > 0)) rc = cli_fail("--spacing must be > 0 (got %g)", o.spacing);
        } else if (strcmp(a, "--origins") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            const char *v = argv[++i];
            if (strcmp(v, "coupled") == 0) o.origin_rule = SEM_ORIGINS_COUPLED;
            else if (strcmp(v, "paper") == 0) o.origin_rule = SEM_ORIGINS_PAPER;
            else rc = cli_fail("--origins must be coupled or paper (got '%s')", v);
        } else if (strcmp(a, "--fit") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            const char *v = argv[++i];
            if (strcmp(v, "auto") == 0) o.fit_rule = SEM_FIT_AUTO;
            else if (strcmp(v, "parts") == 0) o.fit_rule = SEM_FIT_PARTS;
            else if (strcmp(v, "origins") == 0) o.fit_rule = SEM_FIT_ORIGINS;
            else rc = cli_fail("--fit must be auto, parts or origins (got '%s')", v);
        } else if (strcmp(a, "--blend") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &blend);
            if (rc == CLI_OK && !(blend >= 0 && blend <= 1e6)) rc = cli_fail("--blend must be in 0..1e6 (got %g)", blend);
        } else if (strcmp(a, "--order") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_int(CMD, a, argv[++i], &o.order);
            if (rc == CLI_OK && o.order != 1 && o.order != 2)
                rc = cli_fail("--order must be 1 or 2 (got %d)", o.order);
        } else if (strcmp(a, "--rays") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 2)) != CLI_OK) break;
            rc = cli_parse_int(CMD, a, argv[++i], &o.rays[0]);
            if (rc == CLI_OK) rc = cli_parse_int(CMD, a, argv[++i], &o.rays[1]);
            if (rc == CLI_OK && (o.rays[0] < 1 || o.rays[1] < 1))
                rc = cli_fail("--rays must be positive (got %d %d)", o.rays[0], o.rays[1]);
        } else if (strcmp(a, "--axis") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = parse_axis(argv[++i], &o.ray_axis);
        } else if (strcmp(a, "--points-per-interval") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_int(CMD, a, argv[++i], &o.points_per_interval);
            if (rc == CLI_OK && o.points_per_interval < 1)
                rc = cli_fail("--points-per-interval must be positive (got %d)",
                              o.points_per_interval);
        } else if (strcmp(a, "--alpha") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &alpha);
            have_alpha = 1;
            if (rc == CLI_OK && !(alpha > 0))
                rc = cli_fail("--alpha must be > 0 (got %g)", alpha);
        } else if (strcmp(a, "--sparsity") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &sparsity);
            have_sparsity = 1;
            if (rc == CLI_OK && !(sparsity > 0 && sparsity < 1))
                rc = cli_fail("--sparsity must be in (0,1) (got %g)", sparsity);
        } else if (strcmp(a, "--gamma") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &o.gamma);
            if (rc == CLI_OK && !(o.gamma > 0)) rc = cli_fail("--gamma must be > 0 (got %g)", o.gamma);
        } else if (strcmp(a, "--youngs-modulus") == 0 || strcmp(a, "-E") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_double(CMD, a, argv[++i], &o.youngs_modulus);
            if (rc == CLI_OK && !(o.youngs_modulus > 0))
                rc = cli_fail("%s must be > 0 (got %g)", a, o.youngs_modulus);
        } else if (strcmp(a, "--tessellation") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_int(CMD, a, argv[++i], &o.tessellation);
            if (rc == CLI_OK && o.tessellation < 1)
                rc = cli_fail("--tessellation must be positive (got %d)", o.tessellation);
        } else if (strcmp(a, "--threads") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            rc = cli_parse_int(CMD, a, argv[++i], &o.threads);
            if (rc == CLI_OK && o.threads < 0) rc = cli_fail("--threads must be >= 0 (got %d)", o.threads);
        } else if (strcmp(a, "--no-cache") == 0) {
            use_cache = 0;
        } else if (strcmp(a, "--save") == 0 || strcmp(a, "-o") == 0) {
            if ((rc = cli_need_values(CMD, argc, argv, i, 1)) != CLI_OK) break;
            save = argv[++i];
        } else if (a[0] == '-' && a[1] != '\0') {
            rc = cli_usage(CMD, "unknown option '%s'", a);
        } else if (!path) {
            path = a;
        } else {
            rc = cli_usage(CMD, "more than one input file ('%s' and '%s')", path, a);
        }
    }
    if (rc != CLI_OK) return rc;
    if (!path) return cli_usage(CMD, "no input file");
    if (have_alpha && have_sparsity)
        return cli_fail("give either --alpha or --sparsity, not both");
    if (have_alpha) o.alpha = alpha;
    if (have_sparsity) o.sparsity = sparsity;
    if (o.threads > omp_get_num_procs()) {
        cli_warn("--threads %d is more than the %d processors of this machine; using %d",
                 o.threads, omp_get_num_procs(), omp_get_num_procs());
        o.threads = omp_get_num_procs();
    }

    sem_error err;
    sem_model *model = NULL;
    if (sem_model_load(path, &model, &err) != SEM_OK) return cli_fail_error(path, &err);
    cli_print_model_warnings(model);

    sem_discretization *d = NULL;
    double t0 = omp_get_wtime();
    sem_status st = sem_preprocess(model, &o, &d, &err);
    double total_s = omp_get_wtime() - t0;
    if (st != SEM_OK) {
        sem_model_destroy(model);
        return cli_fail_error(path, &err);
    }
    sem_object_modes m;
    int *flags = calloc((size_t)d->n_parts + 1, sizeof *flags);
    if (!flags) st = sem_error_set(&err, SEM_ERR_NOMEM, "out of memory");
    if (st == SEM_OK && modes) st = find_modes(model, d, o.youngs_modulus, blend, &m, flags, &err);
    if (st != SEM_OK) {
        free(flags);
        sem_model_destroy(model);
        sem_discretization_destroy(d);
        return cli_fail_error(path, &err);
    }

    if (save && sem_discretization_save(d, save, &err) != SEM_OK) {
        free(flags);
        sem_discretization_destroy(d);
        sem_model_destroy(model);
        return cli_fail_error(save, &err);
    }
    char cache[4096] = "";
    if (use_cache) {
        /* the entry `sem run` looks up for this model with these settings */
        cli_cache_dir(cache, sizeof cache);
        if (sem_cache_store(cache, cli_cache_max_bytes(), model, &o, d, &err) != SEM_OK) {
            cli_warn("cannot write the cache: %s", err.message);
            cache[0] = '\0';
        }
    }
    sem_model_destroy(model);
    if (json) {
        cJSON *j = to_json(d, total_s);
        if (modes) add_modes_json(j, &m, flags, d->n_parts);
        rc = cli_print_json(j);
    } else {
        print_human(path, d, total_s);
        if (modes) {
            printf("  zero-energy modes     %d%s (lowest elastic mode %.3g E / (rho L^2))\n", m.spurious,
                   m.spurious == m.n_values ? " or more" : "", m.n_values > m.spurious ? m.values[m.spurious] : 0.0);
            if (m.spurious > 0) {
                printf("  parts not held       ");
                for (int i = 0; i < d->n_parts; ++i)
                    if (flags[i]) printf(" %d", i);
                printf("\n");
            }
        }
        if (save) printf("  saved                 %s\n", save);
        if (cache[0]) printf("  cached in             %s (sem run reuses it)\n", cache);
    }
    free(flags);
    sem_discretization_destroy(d);
    return rc;
}
