/* test_render.c - the renderer (include/sem/render.h): picture geometry against closed forms
 * (a sphere's silhouette, a trimmed hole, the camera's framing), shadows, determinism over
 * thread counts, sRGB encoding, PNG files, and the diagnostic maps (the SEM map at the
 * quadrature points reproduces affine motions; interpolated weights keep the partition of
 * unity). */
#include <math.h>
#include <png.h>
#include <stdlib.h>
#include <string.h>

#include "sem/preprocess.h"
#include "sem/primitives.h"
#include "sem/render.h"
#include "sem/tessellate.h"
#include "sem/trim.h"
#include "test_util.h"

/* One opaque or see-through surface of a mesh in one colour. */
typedef struct scene_mesh {
    sem_mesh mesh;
    float *colors;
    sem_render_surface surface;
} scene_mesh;

static void scene_mesh_make(scene_mesh *s, const sem_model *m, int resolution, float opacity)
{
    sem_error err;
    CHECK(sem_mesh_from_model(m, resolution, &s->mesh, &err) == SEM_OK, "%s", err.message);
    s->colors = malloc(3 * (size_t)s->mesh.n_vertices * sizeof *s->colors);
    for (int v = 0; v < s->mesh.n_vertices; ++v) sem_render_palette(v % 3 == 0 ? 1 : 1, &s->colors[3 * v]);
    sem_render_surface f = {s->mesh.n_vertices, s->mesh.n_triangles, s->mesh.positions, s->mesh.normals,
                            s->mesh.triangles, s->colors, opacity, NULL, NULL};
    s->surface = f;
}

static void scene_mesh_free(scene_mesh *s)
{
    sem_mesh_free(&s->mesh);
    free(s->colors);
}

/* Renders n surfaces; returns a malloc'd picture. */
static unsigned char *render(const sem_render_def *def, int n, const sem_render_surface *s, int threads)
{
    sem_renderer *r = NULL;
    sem_error err;
    unsigned char *rgb = calloc(3 * (size_t)def->width * def->height, 1);
    CHECK(sem_renderer_create(def, &r, &err) == SEM_OK, "%s", err.message);
    if (!r) return rgb;
    sem_render_frame frame = {n, s, 0, NULL};
    CHECK(sem_render_image(r, &frame, threads, rgb, &err) == SEM_OK, "%s", err.message);
    sem_renderer_destroy(r);
    return rgb;
}

static int differs(const unsigned char *a, const unsigned char *b, size_t p)
{
    return a[3 * p] != b[3 * p] || a[3 * p + 1] != b[3 * p + 1] || a[3 * p + 2] != b[3 * p + 2];
}

/* Pixels where the picture differs from the empty scene's (the object and its shadow). */
static long count_object(const sem_render_def *def, const unsigned char *with, const unsigned char *without)
{
    long n = 0;
    for (size_t p = 0; p < (size_t)def->width * def->height; ++p) n += differs(with, without, p);
    return n;
}

static void box_bounds(const sem_mesh *m, double b[6])
{
    for (int k = 0; k < 3; ++k) {
        b[k] = INFINITY;
        b[k + 3] = -INFINITY;
    }
    for (int v = 0; v < m->n_vertices; ++v)
        for (int k = 0; k < 3; ++k) {
            b[k] = fmin(b[k], m->positions[3 * v + k]);
            b[k + 3] = fmax(b[k + 3], m->positions[3 * v + k]);
        }
}

/* A unit sphere seen from distance D covers a disc of radius tan(asin(1/D)) / tan(fov/2)
 * half-heights: its pixel count is pi r^2 (the tessellation is inscribed, so slightly
 * less). Fails when rays, the camera or the intersection are wrong. */
static void test_sphere_silhouette(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    sem_sphere_def sd = sem_default_sphere_def();
    CHECK(sem_primitive_sphere(m, &sd, &err) == SEM_OK, "%s", err.message);
    scene_mesh s;
    scene_mesh_make(&s, m, 24, 1.0f);
    sem_render_def def = sem_default_render_def();
    def.width = 320;
    def.height = 200;
    def.ground = 0;
    def.antialias = 0;
    def.camera.look_at = 1;
    const double D = 5.0;
    double eye[3] = {D * cos(0.4), D * sin(0.4), 0.0}, target[3] = {0, 0, 0};
    memcpy(def.camera.eye, eye, sizeof eye);
    memcpy(def.camera.target, target, sizeof target);
    double b[6] = {-1, -1, -1, 1, 1, 1};
    memcpy(def.bounds, b, sizeof b);
    unsigned char *with = render(&def, 1, &s.surface, 0);
    unsigned char *without = render(&def, 0, NULL, 0);
    double r = tan(asin(1.0 / D)) / tan(0.5 * def.camera.fov * M_PI / 180.0) * 0.5 * def.height;
    double expected = M_PI * r * r;
    long got = count_object(&def, with, without);
    CHECK_REL((double)got, expected, 0.01);
    /* the disc is centred */
    double cx = 0, cy = 0;
    for (int y = 0; y < def.height; ++y)
        for (int x = 0; x < def.width; ++x)
            if (differs(with, without, (size_t)y * def.width + x)) {
                cx += x + 0.5;
                cy += y + 0.5;
            }
    CHECK_NEAR(cx / (double)got, 0.5 * def.width, 0.5);
    CHECK_NEAR(cy / (double)got, 0.5 * def.height, 0.5);
    free(with);
    free(without);
    scene_mesh_free(&s);
    sem_model_destroy(m);
}

/* The orbit camera's default distance puts the farthest projected corner of the box on the
 * 5% border: the silhouette of a box is the hull of its corners, so its pixels stay inside
 * the border and touch it. */
static void test_framing(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    sem_beam_def bd = sem_default_beam_def();
    bd.length = 2;
    bd.width = 0.4;
    bd.height = 0.4;
    CHECK(sem_primitive_beam(m, &bd, &err) == SEM_OK, "%s", err.message);
    scene_mesh s;
    scene_mesh_make(&s, m, 2, 1.0f);
    int cameras[3][2] = {{-60, 25}, {30, 10}, {120, 60}};
    for (int c = 0; c < 3; ++c) {
        sem_render_def def = sem_default_render_def();
        def.width = 400;
        def.height = 225;
        def.ground = 0;
        def.antialias = 0;
        def.camera.azimuth = cameras[c][0];
        def.camera.elevation = cameras[c][1];
        box_bounds(&s.mesh, def.bounds);
        unsigned char *with = render(&def, 1, &s.surface, 0);
        unsigned char *without = render(&def, 0, NULL, 0);
        int x0 = def.width, x1 = -1, y0 = def.height, y1 = -1;
        for (int y = 0; y < def.height; ++y)
            for (int x = 0; x < def.width; ++x)
                if (differs(with, without, (size_t)y * def.width + x)) {
                    x0 = x < x0 ? x : x0;
                    x1 = x > x1 ? x : x1;
                    y0 = y < y0 ? y : y0;
                    y1 = y > y1 ? y : y1;
                }
        const double bx = 0.05 * def.width, by = 0.05 * def.height;
        CHECK(x0 >= bx - 1 && x1 <= def.width - bx && y0 >= by - 1 && y1 <= def.height - by,
              "camera %d: object pixels %d..%d x %d..%d cross the 5%% border", c, x0, x1, y0, y1);
        double slack = fmin(fmin(x0 - bx, def.width - bx - 1 - x1), fmin(y0 - by, def.height - by - 1 - y1));
        CHECK(slack <= 1.5, "camera %d: the object does not fill the picture (%g pixels from the border)", c, slack);
        free(with);
        free(without);
    }
    scene_mesh_free(&s);
    sem_model_destroy(m);
}

/* A box floating above the ground casts a shadow: ground pixels darker than the lit
 * ground of the same picture without the box. None without the key light's occlusion. */
static void test_shadow(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    sem_box_def bd = sem_default_box_def();
    bd.center[2] = 1.0;
    CHECK(sem_primitive_box(m, &bd, &err) == SEM_OK, "%s", err.message);
    scene_mesh s;
    scene_mesh_make(&s, m, 2, 1.0f);
    sem_render_def def = sem_default_render_def();
    def.width = 240;
    def.height = 160;
    double b[6] = {-1.5, -1.5, 0.0, 1.5, 1.5, 1.5}; /* ground at z = 0, under the box */
    memcpy(def.bounds, b, sizeof b);
    def.antialias = 0;
    unsigned char *with = render(&def, 1, &s.surface, 0);
    unsigned char *without = render(&def, 0, NULL, 0);
    long shadow = 0, object = 0;
    for (size_t p = 0; p < (size_t)def.width * def.height; ++p) {
        int lit = without[3 * p] + without[3 * p + 1] + without[3 * p + 2];
        int now = with[3 * p] + with[3 * p + 1] + with[3 * p + 2];
        if (!differs(with, without, p)) continue;
        object++;
        if (now < 0.75 * lit && abs(with[3 * p] - with[3 * p + 2]) < 40) shadow++; /* darker grey */
    }
    CHECK(shadow > 0.01 * def.width * def.height, "shadow pixels %ld of %ld changed", shadow, object);
    free(with);
    free(without);
    scene_mesh_free(&s);
    sem_model_destroy(m);
}

/* The same frame gives the same bytes on 1 and 2 threads and when rendered again, with
 * antialiasing, shadows, a see-through surface and points. */
static void test_determinism(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    sem_torus_def td = sem_default_torus_def();
    CHECK(sem_primitive_torus(m, &td, &err) == SEM_OK, "%s", err.message);
    scene_mesh s;
    scene_mesh_make(&s, m, 6, 0.4f);
    double pts[3 * 20];
    float cols[3 * 20];
    for (int k = 0; k < 20; ++k) {
        pts[3 * k] = cos(k * 0.314);
        pts[3 * k + 1] = sin(k * 0.314);
        pts[3 * k + 2] = 0.0;
        sem_render_palette(k, &cols[3 * k]);
    }
    sem_render_points points = {20, pts, cols, 0.08};
    sem_render_def def = sem_default_render_def();
    def.width = 160;
    def.height = 90;
    box_bounds(&s.mesh, def.bounds);
    sem_renderer *r = NULL;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_OK, "%s", err.message);
    sem_render_frame frame = {1, &s.surface, 1, &points};
    size_t bytes = 3 * (size_t)def.width * def.height;
    unsigned char *a = malloc(bytes), *b = malloc(bytes), *c = malloc(bytes);
    CHECK(sem_render_image(r, &frame, 1, a, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_render_image(r, &frame, 2, b, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_render_image(r, &frame, 0, c, &err) == SEM_OK, "%s", err.message);
    CHECK(memcmp(a, b, bytes) == 0, "1 and 2 threads differ");
    CHECK(memcmp(a, c, bytes) == 0, "a second render differs");
    /* and antialiasing did refine something: a picture without it differs at edges only */
    sem_renderer_destroy(r);
    def.antialias = 0;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_render_image(r, &frame, 2, c, &err) == SEM_OK, "%s", err.message);
    long changed = 0;
    for (size_t p = 0; p < bytes / 3; ++p) changed += differs(a, c, p);
    CHECK(changed > 50 && changed < (long)(bytes / 3) / 3, "antialiasing changed %ld of %zu pixels", changed, bytes / 3);
    sem_renderer_destroy(r);
    free(a);
    free(b);
    free(c);
    scene_mesh_free(&s);
    sem_model_destroy(m);
}

/* a full circle of radius r about (cu, cv) in a part's (u,v) domain */
static void circle(sem_curve *c, double cu, double cv, double r)
{
    sem_curve_alloc(c, 2, 9);
    double k[12] = {0, 0, 0, 1, 1, 2, 2, 3, 3, 4, 4, 4};
    memcpy(c->knots, k, sizeof k);
    double p[9][2] = {{1, 0}, {1, 1}, {0, 1}, {-1, 1}, {-1, 0}, {-1, -1}, {0, -1}, {1, -1}, {1, 0}};
    for (int i = 0; i < 9; ++i) {
        c->ctrl[3 * i] = cu + r * p[i][0];
        c->ctrl[3 * i + 1] = cv + r * p[i][1];
        c->weights[i] = (i % 2) ? sqrt(0.5) : 1.0;
    }
    c->t0 = 0;
    c->t1 = 4;
}

/* A 2 x 2 plate with a hole of radius 0.5, seen from straight above: with exact trims the
 * hole's pixel count is the disc's area in pixels; the coarse covering mesh without them
 * fills a good part of the hole. */
static void test_exact_trims(void)
{
    sem_part part;
    memset(&part, 0, sizeof part);
    sem_surface_alloc(&part.surface, 1, 1, 2, 2);
    double k[4] = {0, 0, 2, 2};
    memcpy(part.surface.knots_u, k, sizeof k);
    memcpy(part.surface.knots_v, k, sizeof k);
    double P[12] = {0, 0, 0, 2, 0, 0, 0, 2, 0, 2, 2, 0};
    memcpy(part.surface.ctrl, P, sizeof P);
    part.surface.u1 = part.surface.v1 = 2;
    part.n_holes = 1;
    part.holes = calloc(1, sizeof *part.holes);
    part.holes[0].n_curves = 1;
    part.holes[0].curves = calloc(1, sizeof(sem_curve));
    circle(&part.holes[0].curves[0], 1.0, 1.0, 0.5);
    sem_model *m = sem_model_create();
    sem_error err;
    CHECK(sem_model_take_part(m, &part, &err) == SEM_OK, "%s", err.message);
    sem_mesh_template *t = NULL;
    CHECK(sem_mesh_template_build_covering(m, 6, &t, &err) == SEM_OK, "%s", err.message);
    sem_mesh mesh;
    CHECK(sem_mesh_template_mesh(t, &mesh, &err) == SEM_OK && sem_mesh_update(t, m, &mesh, &err) == SEM_OK, "%s",
          err.message);
    sem_render_trims *trims = NULL;
    CHECK(sem_render_trims_build(m, &mesh, &trims, &err) == SEM_OK, "%s", err.message);
    float *colors = malloc(3 * (size_t)mesh.n_vertices * sizeof *colors);
    for (int v = 0; v < mesh.n_vertices; ++v) sem_render_palette(0, &colors[3 * v]);
    sem_render_surface exact = {mesh.n_vertices, mesh.n_triangles, mesh.positions, mesh.normals, mesh.triangles,
                                colors, 1.0f, mesh.uv, sem_render_trims_table(trims)};
    sem_render_surface coarse = exact;
    coarse.triangle_trim = NULL;
    sem_render_def def = sem_default_render_def();
    def.width = def.height = 200;
    def.ground = 0;
    def.antialias = 0;
    def.camera.look_at = 1;
    const double H = 6.0;
    double eye[3] = {1, 1, H}, target[3] = {1, 1, 0}, b[6] = {0, 0, 0, 2, 2, 0};
    memcpy(def.camera.eye, eye, sizeof eye);
    memcpy(def.camera.target, target, sizeof target);
    memcpy(def.bounds, b, sizeof b);
    unsigned char *with = render(&def, 1, &exact, 0);
    unsigned char *rough = render(&def, 1, &coarse, 0);
    unsigned char *without = render(&def, 0, NULL, 0);
    const double pixels_per_unit = 0.5 * def.height / (H * tan(0.5 * def.camera.fov * M_PI / 180.0));
    const double plate = 4.0 * pixels_per_unit * pixels_per_unit, hole = M_PI * 0.25 * pixels_per_unit * pixels_per_unit;
    CHECK_REL((double)count_object(&def, with, without), plate - hole, 0.01);
    const double rough_area = (double)count_object(&def, rough, without);
    CHECK(rough_area > plate - 0.75 * hole, "without the trim test the covering mesh fills a quarter of the hole (%g of %g pixels left)",
          plate - rough_area, hole);
    free(with);
    free(rough);
    free(without);
    free(colors);
    sem_render_trims_destroy(trims);
    sem_mesh_free(&mesh);
    sem_mesh_template_destroy(t);
    sem_model_destroy(m);
}

/* sRGB: every byte survives linear and back; encoding rounds to the nearest byte. */
static void test_srgb(void)
{
    int bad = 0;
    for (int b = 0; b < 256; ++b) bad += sem_linear_to_srgb(sem_srgb_to_linear((unsigned char)b)) != b;
    CHECK(bad == 0, "%d bytes do not round-trip", bad);
    int wrong = 0;
    for (int i = 0; i <= 10000; ++i) {
        double c = i / 10000.0;
        double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1 / 2.4) - 0.055;
        int expected = (int)lround(255.0 * s), got = sem_linear_to_srgb((float)c);
        /* float rounding of the thresholds may move exact halves by one */
        if (abs(got - expected) > 1 || (got != expected && fabs(255.0 * s - floor(255.0 * s) - 0.5) > 1e-4)) wrong++;
    }
    CHECK(wrong == 0, "%d values encode to the wrong byte", wrong);
    CHECK(sem_linear_to_srgb(-1.0f) == 0 && sem_linear_to_srgb(2.0f) == 255 && sem_linear_to_srgb(NAN) == 0,
          "out of range values");
}

/* A PNG written and read back (libpng) gives the same pixels; nothing temporary is left. */
static void test_png(void)
{
    const int w = 37, h = 23;
    unsigned char *rgb = malloc(3 * w * h);
    for (int k = 0; k < 3 * w * h; ++k) rgb[k] = (unsigned char)(k * 7 + k / 5);
    char path[512];
    snprintf(path, sizeof path, "%s/t.png", test_tmpdir());
    sem_error err;
    CHECK(sem_png_write(path, w, h, rgb, &err) == SEM_OK, "%s", err.message);
    png_image image;
    memset(&image, 0, sizeof image);
    image.version = PNG_IMAGE_VERSION;
    CHECK(png_image_begin_read_from_file(&image, path), "cannot read %s", path);
    CHECK(image.width == (unsigned)w && image.height == (unsigned)h, "size %u x %u", image.width, image.height);
    image.format = PNG_FORMAT_RGB;
    unsigned char *back = malloc(PNG_IMAGE_SIZE(image));
    CHECK(png_image_finish_read(&image, NULL, back, 0, NULL), "cannot decode %s", path);
    CHECK(memcmp(back, rgb, 3 * w * h) == 0, "pixels differ after the round trip");
    snprintf(path, sizeof path, "%s/no/such/folder/t.png", test_tmpdir());
    CHECK(sem_png_write(path, w, h, rgb, &err) == SEM_ERR_IO, "writing into a missing folder must fail");
    free(back);
    free(rgb);
}

static sem_discretization *preprocess_box(sem_model **model)
{
    *model = sem_model_create();
    sem_error err;
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 3;
    bd.length = 3;
    CHECK(sem_primitive_beam(*model, &bd, &err) == SEM_OK, "%s", err.message);
    sem_preprocess_options o = sem_default_preprocess_options();
    o.rays[0] = o.rays[1] = 4;
    o.points_per_interval = 6;
    o.alpha = 0.6;
    sem_discretization *d = NULL;
    CHECK(sem_preprocess(*model, &o, &d, &err) == SEM_OK, "%s", err.message);
    return d;
}

/* The SEM map at the quadrature points (Eq. 6) reproduces rest and any affine motion
 * exactly (the fits are affine-exact and the weights sum to one); the origins move with
 * their parts' translation. */
static void test_sem_map(void)
{
    sem_model *m;
    sem_discretization *d = preprocess_box(&m);
    if (!d) return;
    size_t n = sem_model_control_points(m);
    double *q0 = malloc(3 * n * sizeof *q0), *q = malloc(3 * n * sizeof *q);
    double *x = malloc(3 * (size_t)d->n_quad * sizeof *x), *o = malloc(3 * (size_t)d->n_origins * sizeof *o);
    sem_model_get_q(m, q0);
    sem_error err;
    CHECK(sem_render_map_quadrature(d, q0, x, &err) == SEM_OK, "%s", err.message);
    double worst = 0;
    for (int k = 0; k < 3 * d->n_quad; ++k) worst = fmax(worst, fabs(x[k] - d->quad_X[k]));
    CHECK(worst < 1e-9, "rest: quadrature points move by %g", worst);
    const double A[3][3] = {{0.9, -0.3, 0.1}, {0.35, 1.1, 0.0}, {-0.05, 0.2, 0.8}}, t[3] = {0.5, -1.0, 2.0};
    for (size_t c = 0; c < n; ++c)
        for (int i = 0; i < 3; ++i)
            q[3 * c + i] = A[i][0] * q0[3 * c] + A[i][1] * q0[3 * c + 1] + A[i][2] * q0[3 * c + 2] + t[i];
    CHECK(sem_render_map_quadrature(d, q, x, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_render_map_origins(d, q, o, &err) == SEM_OK, "%s", err.message);
    worst = 0;
    for (int p = 0; p < d->n_quad; ++p)
        for (int i = 0; i < 3; ++i) {
            const double *X = &d->quad_X[3 * p];
            worst = fmax(worst, fabs(x[3 * p + i] - (A[i][0] * X[0] + A[i][1] * X[1] + A[i][2] * X[2] + t[i])));
        }
    CHECK(worst < 1e-9, "affine: quadrature points off by %g", worst);
    worst = 0;
    for (int j = 0; j < d->n_origins; ++j)
        for (int i = 0; i < 3; ++i) {
            const double *X = &d->origin_X[3 * j];
            worst = fmax(worst, fabs(o[3 * j + i] - (A[i][0] * X[0] + A[i][1] * X[1] + A[i][2] * X[2] + t[i])));
        }
    CHECK(worst < 1e-9, "affine: origins off by %g", worst);
    /* without Pi the map cannot be evaluated: an error, not a crash */
    sem_csr pi = d->Pi;
    memset(&d->Pi, 0, sizeof d->Pi);
    CHECK(sem_render_map_quadrature(d, q, x, &err) == SEM_ERR_INVALID, "a discretization without Pi must fail");
    d->Pi = pi;
    free(q0);
    free(q);
    free(x);
    free(o);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

/* Weights near the surface: at a quadrature point they are that point's weights; anywhere
 * the parts' weights still sum to one (inverse-distance averaging keeps the partition of
 * unity); a part that does not exist is an error. */
static void test_part_weights(void)
{
    sem_model *m;
    sem_discretization *d = preprocess_box(&m);
    if (!d) return;
    sem_error err;
    float *w = malloc((size_t)d->n_quad * sizeof *w);
    double worst = 0;
    for (int part = 0; part < d->n_parts; ++part) {
        CHECK(sem_render_part_weights(d, part, d->n_quad, d->quad_X, w, &err) == SEM_OK, "%s", err.message);
        for (int p = 0; p < d->n_quad; ++p) {
            double exact = 0;
            for (int s = d->W.row_start[p]; s < d->W.row_start[p + 1]; ++s)
                if (d->W.col[s] == part) exact = d->W.val[s];
            worst = fmax(worst, fabs(w[p] - exact));
        }
    }
    CHECK(worst < 1e-5, "weights at the quadrature points off by %g", worst);
    /* arbitrary points, inside and outside the model */
    const int n = 200;
    double *X = malloc(3 * (size_t)n * sizeof *X), *sum = calloc((size_t)n, sizeof *sum);
    for (int k = 0; k < n; ++k) {
        X[3 * k] = -0.5 + 4.0 * ((k * 37) % 101) / 100.0;
        X[3 * k + 1] = -0.5 + 2.0 * ((k * 53) % 97) / 96.0;
        X[3 * k + 2] = -0.5 + 2.0 * ((k * 71) % 89) / 88.0;
    }
    float *wk = malloc((size_t)n * sizeof *wk);
    for (int part = 0; part < d->n_parts; ++part) {
        CHECK(sem_render_part_weights(d, part, n, X, wk, &err) == SEM_OK, "%s", err.message);
        for (int k = 0; k < n; ++k) sum[k] += wk[k];
    }
    worst = 0;
    for (int k = 0; k < n; ++k) worst = fmax(worst, fabs(sum[k] - 1.0));
    CHECK(worst < 1e-5, "weights at arbitrary points sum to 1 +- %g", worst);
    CHECK(sem_render_part_weights(d, d->n_parts, n, X, wk, &err) == SEM_ERR_INVALID, "part out of range");
    double spacing = sem_render_point_spacing(d->n_quad, d->quad_X);
    CHECK(spacing > 0 && spacing < 1.0, "point spacing %g", spacing);
    free(X);
    free(sum);
    free(wk);
    free(w);
    sem_discretization_destroy(d);
    sem_model_destroy(m);
}

/* Bad definitions and frames are errors, not crashes. */
static void test_errors(void)
{
    sem_render_def def = sem_default_render_def();
    sem_renderer *r = NULL;
    sem_error err;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_OK, "an empty box is a point: fine (%s)", err.message);
    sem_renderer_destroy(r);
    def.width = 0;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_ERR_INVALID && !r, "zero width");
    def = sem_default_render_def();
    def.bounds[0] = 1;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_ERR_INVALID, "inverted box");
    def = sem_default_render_def();
    def.camera.look_at = 1;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_ERR_INVALID, "eye == target");
    def = sem_default_render_def();
    def.width = def.height = 8;
    CHECK(sem_renderer_create(&def, &r, &err) == SEM_OK, "%s", err.message);
    double pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, NAN}, nrm[9] = {0, 0, 1, 0, 0, 1, 0, 0, 1};
    int tri[3] = {0, 1, 2};
    float col[9] = {0};
    sem_render_surface s = {3, 1, pos, nrm, tri, col, 1.0f, NULL, NULL};
    sem_render_frame frame = {1, &s, 0, NULL};
    unsigned char rgb[3 * 64];
    CHECK(sem_render_image(r, &frame, 1, rgb, &err) == SEM_ERR_INVALID, "NaN position");
    pos[8] = 0;
    tri[2] = 3;
    CHECK(sem_render_image(r, &frame, 1, rgb, &err) == SEM_ERR_INVALID, "index out of range");
    tri[2] = 2;
    s.opacity = 0;
    CHECK(sem_render_image(r, &frame, 1, rgb, &err) == SEM_ERR_INVALID, "opacity 0");
    sem_renderer_destroy(r);
}

int main(void)
{
    test_sphere_silhouette();
    test_framing();
    test_shadow();
    test_determinism();
    test_exact_trims();
    test_srgb();
    test_png();
    test_sem_map();
    test_part_weights();
    test_errors();
    return test_finish("test_render");
}
