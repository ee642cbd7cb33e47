/*
 * bench_render.c - `sem render`'s cost per 1280 x 720 frame on the paper's Table 1 models.
 *
 * usage: bench_render [MODELS_DIR] [--frames N] [--size W H] [--only TEXT]
 *
 * For each model (once per file), the work of `sem render` per frame: the tessellation's
 * update for the frame's control points (resolution 8, covering trims), the Embree scene,
 * the picture (antialiased, shadows, exact trims) and the PNG file; N frames (default 8,
 * each with slightly moved control points) one per thread, as `sem render` does for a run,
 * and one picture alone on all threads (the latency of `sem render MODEL`); and the CPU
 * time per frame of the run (all threads), which over the thread count is the wall time a
 * machine doing nothing else would take. Reading the frame files is not included (it is
 * parallel too; see docs/render.md).
 */
#include <math.h>
#include <omp.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "bench/validation.h"
#include "sem/render.h"
#include "sem/tessellate.h"

/* CPU seconds of the whole process (all threads): on a busy machine wall time measures the
 * other programs too; CPU time over the thread count is what an idle machine would take. */
static double cpu_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

typedef struct frame_buffers {
    sem_model *model;
    sem_mesh mesh;
    unsigned char *rgb;
} frame_buffers;

static int render_frame(const sem_renderer *r, const sem_mesh_template *t, const sem_render_trims *trims,
                        const float *colors, const double *q0, size_t n, int k, int threads, int w, int h,
                        const char *path, frame_buffers *b)
{
    double *q = malloc(3 * n * sizeof *q);
    if (!q) return 0;
    for (size_t i = 0; i < 3 * n; ++i) q[i] = q0[i] * (1.0 + 1e-3 * k);
    sem_model_set_q(b->model, q);
    free(q);
    sem_error err;
    if (sem_mesh_update(t, b->model, &b->mesh, &err) != SEM_OK) return 0;
    sem_render_surface s = {b->mesh.n_vertices, b->mesh.n_triangles, b->mesh.positions, b->mesh.normals,
                            b->mesh.triangles, colors, 1.0f, b->mesh.uv, sem_render_trims_table(trims)};
    sem_render_frame frame = {1, &s, 0, NULL};
    if (sem_render_image(r, &frame, threads, b->rgb, &err) != SEM_OK) return 0;
    return sem_png_write(path, w, h, b->rgb, &err) == SEM_OK;
}

int main(int argc, char **argv)
{
    const char *dir_arg = NULL, *only = NULL;
    int frames = 8, width = 1280, height = 720;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "--frames") && i + 1 < argc) frames = atoi(argv[++i]);
        else if (!strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
        else if (!strcmp(argv[i], "--size") && i + 2 < argc) {
            width = atoi(argv[++i]);
            height = atoi(argv[++i]);
        } else if (argv[i][0] == '-') {
            fprintf(stderr, "usage: %s [MODELS_DIR] [--frames N] [--size W H] [--only TEXT]\n", argv[0]);
            return 2;
        } else dir_arg = argv[i];
    }
    if (frames < 1) frames = 1;
    const char *dir = dir_arg ? dir_arg : sem_bench_models_dir();
    if (!sem_bench_is_dir(dir)) {
        fprintf(stderr, "bench_render: models folder %s not found\n", dir ? dir : "../shared/models");
        return 1;
    }
    char out[64];
    snprintf(out, sizeof out, "/tmp/sem_bench_render_XXXXXX");
    if (!mkdtemp(out)) return 1;
    printf("threads: %d; %d x %d pixels; seconds per frame\n", omp_get_max_threads(), width, height);
    printf("%-34s %6s %9s | %12s %12s | %12s\n", "model", "parts", "triangles", "run (frames)", "one picture",
           "CPU / frame");
    int failures = 0;
    for (int c = 0; c < sem_table1_count; ++c) {
        const sem_table1_row *row = &sem_table1[c];
        int seen = 0;
        for (int d = 0; d < c; ++d) seen |= !strcmp(sem_table1[d].file, row->file);
        if (seen || (only && !strstr(row->example, only) && !strstr(row->file, only))) continue;
        char path[4096];
        snprintf(path, sizeof path, "%s/%s", dir, row->file);
        sem_model *m = NULL;
        sem_mesh_template *t = NULL;
        sem_render_trims *trims = NULL;
        sem_renderer *r = NULL;
        sem_error err;
        sem_mesh rest;
        memset(&rest, 0, sizeof rest);
        if (sem_model_load(path, &m, &err) != SEM_OK || sem_mesh_template_build_covering(m, 8, &t, &err) != SEM_OK ||
            sem_mesh_template_mesh(t, &rest, &err) != SEM_OK || sem_mesh_update(t, m, &rest, &err) != SEM_OK ||
            sem_render_trims_build(m, &rest, &trims, &err) != SEM_OK) {
            printf("%-34s failed: %s\n", row->file, err.message);
            failures++;
            sem_model_destroy(m);
            sem_mesh_template_destroy(t);
            sem_mesh_free(&rest);
            continue;
        }
        float *colors = malloc(3 * ((size_t)rest.n_vertices + 1) * sizeof *colors);
        for (int v = 0; v < rest.n_vertices; ++v) sem_render_palette(0, &colors[3 * v]);
        for (int p = 0; p < rest.n_parts; ++p)
            for (int v = rest.part_vertex_start[p]; v < rest.part_vertex_start[p + 1]; ++v)
                sem_render_palette(p, &colors[3 * v]);
        sem_render_def def = sem_default_render_def();
        def.width = width;
        def.height = height;
        for (int k = 0; k < 3; ++k) {
            def.bounds[k] = INFINITY;
            def.bounds[k + 3] = -INFINITY;
        }
        for (int v = 0; v < rest.n_vertices; ++v)
            for (int k = 0; k < 3; ++k) {
                def.bounds[k] = fmin(def.bounds[k], rest.positions[3 * v + k]);
                def.bounds[k + 3] = fmax(def.bounds[k + 3], rest.positions[3 * v + k]);
            }
        for (int k = 0; k < 3; ++k) { /* room for the frames' small growth */
            double grow = 0.01 * (fabs(def.bounds[k]) + fabs(def.bounds[k + 3]));
            def.bounds[k] -= grow;
            def.bounds[k + 3] += grow;
        }
        sem_renderer_create(&def, &r, &err);
        size_t n = sem_model_control_points(m);
        double *q0 = malloc(3 * n * sizeof *q0);
        sem_model_get_q(m, q0);
        int ok = 1;
        double t0 = omp_get_wtime(), c0 = cpu_seconds();
#pragma omp parallel reduction(&& : ok)
        {
            frame_buffers b;
            sem_error e;
            b.model = sem_model_clone(m);
            b.rgb = malloc(3 * (size_t)width * height);
            ok = sem_mesh_template_mesh(t, &b.mesh, &e) == SEM_OK && b.model && b.rgb;
#pragma omp for schedule(dynamic, 1)
            for (int k = 0; k < frames; ++k) {
                char png[128];
                snprintf(png, sizeof png, "%s/frame_%04d.png", out, k);
                if (!render_frame(r, t, trims, colors, q0, n, k, 1, width, height, png, &b)) ok = 0;
            }
            sem_model_destroy(b.model);
            sem_mesh_free(&b.mesh);
            free(b.rgb);
        }
        double per_frame = (omp_get_wtime() - t0) / frames, cpu = (cpu_seconds() - c0) / frames;
        frame_buffers one;
        one.model = sem_model_clone(m);
        one.rgb = malloc(3 * (size_t)width * height);
        sem_mesh_template_mesh(t, &one.mesh, &err);
        char png[128];
        snprintf(png, sizeof png, "%s/one.png", out);
        double t1 = omp_get_wtime();
        ok = ok && render_frame(r, t, trims, colors, q0, n, 0, 0, width, height, png, &one);
        double single = omp_get_wtime() - t1;
        printf("%-34s %6d %9d | %12.3f %12.3f | %12.3f%s\n", row->file, m->n_parts, rest.n_triangles, per_frame,
               single, cpu, ok ? "" : "  (failed)");
        fflush(stdout);
        failures += !ok;
        sem_model_destroy(one.model);
        sem_mesh_free(&one.mesh);
        free(one.rgb);
        free(q0);
        free(colors);
        sem_renderer_destroy(r);
        sem_render_trims_destroy(trims);
        sem_mesh_free(&rest);
        sem_mesh_template_destroy(t);
        sem_model_destroy(m);
    }
    char cmd[128];
    snprintf(cmd, sizeof cmd, "rm -rf %s", out);
    if (system(cmd) != 0) fprintf(stderr, "bench_render: could not remove %s\n", out);
    return failures ? 1 : 0;
}
