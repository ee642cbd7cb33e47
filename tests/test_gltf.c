/* test_gltf.c - animation.glb (src/output/gltf.c through sem_animation): the container
 * (header, chunks, lengths), and that every frame played back from the file - the base
 * mesh plus that frame's morph target - is the tessellation of that frame's control
 * points, at the frame's time; per-part materials in the palette's colours; the output key
 * of scenes. The Khronos validator runs on sem run's files in tests/js (gltf_validator). */
#include <cjson/cJSON.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "sem/animation.h"
#include "sem/primitives.h"
#include "sem/render.h"
#include "sem/scene.h"
#include "sem/tessellate.h"
#include "test_util.h"

typedef struct glb {
    unsigned char *data;
    size_t size;
    cJSON *json;
    const unsigned char *bin;
    size_t bin_size;
} glb;

static uint32_t u32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Reads and checks the container; 0 when it is not a valid glb. */
static int glb_read(const char *path, glb *g)
{
    memset(g, 0, sizeof *g);
    FILE *f = fopen(path, "rb");
    CHECK(f != NULL, "cannot open %s", path);
    if (!f) return 0;
    fseek(f, 0, SEEK_END);
    g->size = (size_t)ftell(f);
    fseek(f, 0, SEEK_SET);
    g->data = malloc(g->size + 1);
    CHECK(fread(g->data, 1, g->size, f) == g->size, "short read");
    fclose(f);
    CHECK(g->size >= 28 && !memcmp(g->data, "glTF", 4) && u32(g->data + 4) == 2, "glb header");
    CHECK(u32(g->data + 8) == g->size, "glb length %u, file %zu", u32(g->data + 8), g->size);
    uint32_t json_len = u32(g->data + 12);
    CHECK(!memcmp(g->data + 16, "JSON", 4) && json_len % 4 == 0, "JSON chunk");
    size_t bin_at = 20 + (size_t)json_len;
    CHECK(bin_at + 8 <= g->size && !memcmp(g->data + bin_at + 4, "BIN\0", 4), "BIN chunk");
    if (bin_at + 8 > g->size) return 0;
    g->bin_size = u32(g->data + bin_at);
    g->bin = g->data + bin_at + 8;
    CHECK(g->bin_size % 4 == 0 && bin_at + 8 + g->bin_size == g->size, "BIN chunk length");
    char *text = malloc(json_len + 1);
    memcpy(text, g->data + 20, json_len);
    text[json_len] = '\0';
    g->json = cJSON_Parse(text);
    free(text);
    CHECK(g->json != NULL, "JSON chunk does not parse");
    const cJSON *buffers = cJSON_GetObjectItem(g->json, "buffers");
    CHECK(cJSON_GetArraySize(buffers) == 1 &&
              (size_t)cJSON_GetObjectItem(cJSON_GetArrayItem(buffers, 0), "byteLength")->valuedouble == g->bin_size,
          "buffer byteLength");
    return g->json != NULL;
}

static void glb_free(glb *g)
{
    cJSON_Delete(g->json);
    free(g->data);
}

static int get_int(const cJSON *o, const char *key)
{
    const cJSON *x = cJSON_GetObjectItem(o, key);
    return cJSON_IsNumber(x) ? (int)x->valuedouble : -1;
}

/* Float data of accessor `index` (no sparse), count x components values. */
static const float *accessor_floats(const glb *g, int index, int *count)
{
    const cJSON *a = cJSON_GetArrayItem(cJSON_GetObjectItem(g->json, "accessors"), index);
    const cJSON *v = cJSON_GetArrayItem(cJSON_GetObjectItem(g->json, "bufferViews"), get_int(a, "bufferView"));
    *count = get_int(a, "count");
    CHECK(get_int(a, "componentType") == 5126, "accessor %d is not float", index);
    size_t offset = (size_t)get_int(v, "byteOffset");
    CHECK(offset % 4 == 0 && offset + (size_t)get_int(v, "byteLength") <= g->bin_size, "view bounds");
    return (const float *)(g->bin + offset);
}

/* Frame k of a rigid motion: rotate by 0.3 k about z, lift by 0.2 k, stretch x by 1 + 0.1 k. */
static void frame_q(const double *q0, size_t n, int k, double *q)
{
    double c = cos(0.3 * k), s = sin(0.3 * k), sx = 1 + 0.1 * k;
    for (size_t i = 0; i < n; ++i) {
        double x = sx * q0[3 * i], y = q0[3 * i + 1], z = q0[3 * i + 2];
        q[3 * i] = c * x - s * y;
        q[3 * i + 1] = s * x + c * y;
        q[3 * i + 2] = z + 0.2 * k;
    }
}

static void test_frames_play_back(void)
{
    sem_model *beam = sem_model_create(), *ball = sem_model_create();
    sem_error err;
    sem_beam_def bd = sem_default_beam_def();
    bd.sections = 2;
    CHECK(sem_primitive_beam(beam, &bd, &err) == SEM_OK, "%s", err.message);
    sem_sphere_def sd = sem_default_sphere_def();
    sd.center[0] = 8;
    CHECK(sem_primitive_sphere(ball, &sd, &err) == SEM_OK, "%s", err.message);
    const sem_model *models[2] = {beam, ball};
    char dir[512];
    snprintf(dir, sizeof dir, "%s/glb", test_tmpdir());
    sem_animation_def def;
    memset(&def, 0, sizeof def);
    def.dir = dir;
    def.write_glb = 1;
    def.mesh_resolution = 3;
    def.frames_per_second = 8;
    sem_animation *anim = NULL;
    CHECK(sem_animation_create(&def, 2, models, &anim, &err) == SEM_OK, "%s", err.message);
    if (!anim) return;
    const int n_frames = 6;
    size_t n0 = sem_model_control_points(beam), n1 = sem_model_control_points(ball);
    double *q0a = malloc(3 * n0 * sizeof(double)), *q0b = malloc(3 * n1 * sizeof(double));
    double *qa = malloc(3 * n0 * sizeof(double)), *qb = malloc(3 * n1 * sizeof(double));
    sem_model_get_q(beam, q0a);
    sem_model_get_q(ball, q0b);
    for (int k = 0; k < n_frames; ++k) {
        frame_q(q0a, n0, k, qa);
        frame_q(q0b, n1, k, qb);
        const double *qs[2] = {qa, qb};
        CHECK(sem_animation_add_frame(anim, k, qs, &err) == SEM_OK, "%s", err.message);
    }
    CHECK(sem_animation_finish(anim, &err) == SEM_OK, "%s", err.message);
    glb g;
    if (!glb_read(sem_animation_glb_path(anim), &g)) return;
    const cJSON *j = g.json;
    CHECK(!strcmp(cJSON_GetObjectItem(cJSON_GetObjectItem(j, "asset"), "version")->valuestring, "2.0"), "version");
    /* materials: one per part, in the palette's colours, double-sided */
    const cJSON *materials = cJSON_GetObjectItem(j, "materials");
    CHECK(cJSON_GetArraySize(materials) == beam->n_parts + ball->n_parts, "%d materials",
          cJSON_GetArraySize(materials));
    for (int p = 0; p < cJSON_GetArraySize(materials); ++p) {
        const cJSON *m = cJSON_GetArrayItem(materials, p);
        const cJSON *c = cJSON_GetObjectItem(cJSON_GetObjectItem(m, "pbrMetallicRoughness"), "baseColorFactor");
        float rgb[3];
        sem_render_palette(p, rgb);
        for (int k = 0; k < 3; ++k) CHECK_NEAR(cJSON_GetArrayItem(c, k)->valuedouble, rgb[k], 1e-7);
        CHECK(cJSON_IsTrue(cJSON_GetObjectItem(m, "doubleSided")), "double-sided");
    }
    /* the animation: times k / fps, one sparse non-zero per frame */
    const cJSON *anims = cJSON_GetObjectItem(j, "animations");
    CHECK(cJSON_GetArraySize(anims) == 1, "one animation");
    const cJSON *sampler = cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(anims, 0), "samplers"), 0);
    int count;
    const float *times = accessor_floats(&g, get_int(sampler, "input"), &count);
    CHECK(count == n_frames, "%d keys", count);
    for (int k = 0; k < count && k < n_frames; ++k) CHECK_NEAR(times[k], k / 8.0, 1e-7);
    CHECK(cJSON_GetArraySize(cJSON_GetObjectItem(cJSON_GetArrayItem(anims, 0), "channels")) == 2, "a channel per object");
    const cJSON *out = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "accessors"), get_int(sampler, "output"));
    CHECK(get_int(out, "count") == n_frames * (n_frames - 1), "weights count");
    const cJSON *sparse = cJSON_GetObjectItem(out, "sparse");
    CHECK(get_int(sparse, "count") == n_frames - 1, "sparse count");
    const cJSON *iv = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "bufferViews"),
                                         get_int(cJSON_GetObjectItem(sparse, "indices"), "bufferView"));
    const uint32_t *idx = (const uint32_t *)(g.bin + get_int(iv, "byteOffset"));
    for (int f = 1; f < n_frames; ++f)
        CHECK(idx[f - 1] == (uint32_t)(f * (n_frames - 1) + f - 1), "sparse index of frame %d", f);
    /* every frame: base + target = the tessellation of that frame */
    const cJSON *meshes = cJSON_GetObjectItem(j, "meshes");
    CHECK(cJSON_GetArraySize(meshes) == 2, "a mesh per object");
    double worst_p = 0, worst_n = 0;
    for (int o = 0; o < 2; ++o) {
        const cJSON *prims = cJSON_GetObjectItem(cJSON_GetArrayItem(meshes, o), "primitives");
        CHECK(cJSON_GetArraySize(prims) == models[o]->n_parts, "a primitive per part");
        const cJSON *prim = cJSON_GetArrayItem(prims, 0);
        const cJSON *attr = cJSON_GetObjectItem(prim, "attributes");
        int nv, nn;
        const float *base = accessor_floats(&g, get_int(attr, "POSITION"), &nv);
        const float *nbase = accessor_floats(&g, get_int(attr, "NORMAL"), &nn);
        const cJSON *targets = cJSON_GetObjectItem(prim, "targets");
        CHECK(cJSON_GetArraySize(targets) == n_frames - 1, "%d targets", cJSON_GetArraySize(targets));
        for (int k = 0; k < n_frames; ++k) {
            sem_model *copy = sem_model_clone(models[o]);
            double *q = malloc(3 * sem_model_control_points(copy) * sizeof *q);
            frame_q(o == 0 ? q0a : q0b, sem_model_control_points(copy), k, q);
            sem_model_set_q(copy, q);
            sem_mesh mesh;
            CHECK(sem_mesh_from_model(copy, 3, &mesh, &err) == SEM_OK, "%s", err.message);
            CHECK(mesh.n_vertices == nv, "vertices %d vs %d", mesh.n_vertices, nv);
            const float *dp = NULL, *dn = NULL;
            if (k > 0) {
                const cJSON *t = cJSON_GetArrayItem(targets, k - 1);
                int c1, c2;
                dp = accessor_floats(&g, get_int(t, "POSITION"), &c1);
                dn = accessor_floats(&g, get_int(t, "NORMAL"), &c2);
            }
            for (int v = 0; v < nv && v < mesh.n_vertices; ++v)
                for (int c = 0; c < 3; ++c) {
                    double p = base[3 * v + c] + (dp ? dp[3 * v + c] : 0.0f);
                    double nrm = nbase[3 * v + c] + (dn ? dn[3 * v + c] : 0.0f);
                    worst_p = fmax(worst_p, fabs(p - mesh.positions[3 * v + c]));
                    worst_n = fmax(worst_n, fabs(nrm - mesh.normals[3 * v + c]));
                }
            sem_mesh_free(&mesh);
            free(q);
            sem_model_destroy(copy);
        }
    }
    CHECK(worst_p < 1e-5, "positions played back off by %g", worst_p);
    CHECK(worst_n < 1e-5, "normals played back off by %g", worst_n);
    /* z up in sem, y up in glTF: the root turns -90 degrees about x */
    const cJSON *root = cJSON_GetArrayItem(cJSON_GetObjectItem(j, "nodes"), 0);
    const cJSON *rot = cJSON_GetObjectItem(root, "rotation");
    CHECK_NEAR(cJSON_GetArrayItem(rot, 0)->valuedouble, -sqrt(0.5), 1e-12);
    CHECK_NEAR(cJSON_GetArrayItem(rot, 3)->valuedouble, sqrt(0.5), 1e-12);
    glb_free(&g);
    sem_animation_destroy(anim);
    free(q0a);
    free(q0b);
    free(qa);
    free(qb);
    sem_model_destroy(beam);
    sem_model_destroy(ball);
}

/* One frame: a still model, no targets and no animation (valid glTF needs none). Off: no
 * file. */
static void test_still_and_off(void)
{
    sem_model *m = sem_model_create();
    sem_error err;
    sem_box_def bd = sem_default_box_def();
    CHECK(sem_primitive_box(m, &bd, &err) == SEM_OK, "%s", err.message);
    const sem_model *models[1] = {m};
    char dir[512];
    snprintf(dir, sizeof dir, "%s/still", test_tmpdir());
    sem_animation_def def;
    memset(&def, 0, sizeof def);
    def.dir = dir;
    def.write_glb = 1;
    sem_animation *anim = NULL;
    CHECK(sem_animation_create(&def, 1, models, &anim, &err) == SEM_OK, "%s", err.message);
    double *q = malloc(3 * sem_model_control_points(m) * sizeof *q);
    sem_model_get_q(m, q);
    const double *qs[1] = {q};
    CHECK(sem_animation_add_frame(anim, 0, qs, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_animation_finish(anim, &err) == SEM_OK, "%s", err.message);
    glb g;
    if (glb_read(sem_animation_glb_path(anim), &g)) {
        CHECK(cJSON_GetObjectItem(g.json, "animations") == NULL, "no animation for one frame");
        const cJSON *prim = cJSON_GetArrayItem(cJSON_GetObjectItem(cJSON_GetArrayItem(cJSON_GetObjectItem(g.json, "meshes"), 0), "primitives"), 0);
        CHECK(cJSON_GetObjectItem(prim, "targets") == NULL, "no targets for one frame");
        glb_free(&g);
    }
    sem_animation_destroy(anim);
    snprintf(dir, sizeof dir, "%s/off", test_tmpdir());
    def.write_glb = 0;
    def.write_iges = 1;
    CHECK(sem_animation_create(&def, 1, models, &anim, &err) == SEM_OK, "%s", err.message);
    CHECK(sem_animation_add_frame(anim, 0, qs, &err) == SEM_OK && sem_animation_finish(anim, &err) == SEM_OK, "%s",
          err.message);
    struct stat st;
    CHECK(stat(sem_animation_glb_path(anim), &st) != 0, "output.glb false writes no glb");
    sem_animation_destroy(anim);
    free(q);
    sem_model_destroy(m);
}

/* output.glb: on by default, a bool. */
static void test_scene_key(void)
{
    sem_scene *s = NULL;
    sem_error err;
    const char *base = "{\"objects\": [{\"primitive\": {\"type\": \"box\"}}]%s}";
    char text[512];
    snprintf(text, sizeof text, base, "");
    CHECK(sem_scene_parse(text, "t.json", ".", &s, &err) == SEM_OK && s->write_glb == 1, "default on");
    sem_scene_destroy(s);
    snprintf(text, sizeof text, base, ", \"output\": {\"glb\": false}");
    CHECK(sem_scene_parse(text, "t.json", ".", &s, &err) == SEM_OK && s->write_glb == 0, "glb false");
    sem_scene_destroy(s);
    snprintf(text, sizeof text, base, ", \"output\": {\"glb\": 3}");
    CHECK(sem_scene_parse(text, "t.json", ".", &s, &err) != SEM_OK && strstr(err.message, "glb"), "glb: 3 -> %s",
          err.message);
}

int main(void)
{
    test_frames_play_back();
    test_still_and_off();
    test_scene_key();
    return test_finish("test_gltf");
}
