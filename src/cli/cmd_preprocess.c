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
#include <string.h>

#include "cli.h"
#include "sem/cache.h"
#include "sem/preprocess.h"

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
    cJSON_AddNumberToObject(j, "alpha", d->alpha);
    cJSON_AddNumberToObject(j, "weight_nonzero_fraction", d->weight_nonzero_fraction);
    cJSON_AddNumberToObject(j, "pi_nonzeros", (double)sem_csr_nnz(&d->Pi));
    cJSON_AddNumberToObject(j, "stiffness_nnz_percent", d->stiffness_nnz_percent);
    cJSON_AddNumberToObject(j, "boundary_samples", d->n_samples);
    cJSON_AddNumberToObject(j, "gamma", d->gamma);
    cJSON_AddNumberToObject(j, "length_scale", d->length_scale);
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
    int json = 0, have_alpha = 0, have_sparsity = 0, use_cache = 1;
    double alpha = 0, sparsity = 0;
    sem_preprocess_options o = sem_default_preprocess_options();
    int rc = CLI_OK;
    for (int i = 1; i < argc && rc == CLI_OK; ++i) {
        const char *a = argv[i];
        if (strcmp(a, "--json") == 0) {
            json = 1;
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

    if (save && sem_discretization_save(d, save, &err) != SEM_OK) {
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
        rc = cli_print_json(to_json(d, total_s));
    } else {
        print_human(path, d, total_s);
        if (save) printf("  saved                 %s\n", save);
        if (cache[0]) printf("  cached in             %s (sem run reuses it)\n", cache);
    }
    sem_discretization_destroy(d);
    return rc;
}
