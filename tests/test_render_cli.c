/* test_render_cli.c - `sem render` and `sem view` end to end with the built binary: pictures
 * of a run (every frame, a range, the same bytes again and for a frame drawn alone), the
 * diagnostic colourings, a model at rest, the MP4 (when ffmpeg is installed), the viewer
 * page, and bad input: one line "sem: ...", exit 1 (2 for a malformed command line), nothing
 * half-written. The browser test of the page is tests/js (viewer_browser). */
#include <dirent.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "test_util.h"

static char g_out[65536], g_err[65536];


static int same_file(const char *a, const char *b)
{
    size_t na, nb;
    char *x = test_slurp(a, &na), *y = test_slurp(b, &nb);
    int same = x && y && na == nb && memcmp(x, y, na) == 0;
    free(x);
    free(y);
    return same;
}

/* PNG width and height from the IHDR chunk; 0 when not a PNG. */
static int png_size(const char *path, int *w, int *h)
{
    size_t n;
    unsigned char *b = (unsigned char *)test_slurp(path, &n);
    int ok = b && n > 24 && !memcmp(b, "\x89PNG\r\n\x1a\n", 8) && !memcmp(b + 12, "IHDR", 4);
    if (ok) {
        *w = b[16] << 24 | b[17] << 16 | b[18] << 8 | b[19];
        *h = b[20] << 24 | b[21] << 16 | b[22] << 8 | b[23];
    }
    free(b);
    return ok;
}

static int one_error_line(const char *text)
{
    return !strncmp(text, "sem: ", 5) && strchr(text, '\n') == text + strlen(text) - 1;
}

/* No temporary file of an atomic write left in dir. */
static int tmp_files(const char *dir)
{
    DIR *d = opendir(dir);
    int n = 0;
    struct dirent *e;
    while (d && (e = readdir(d)) != NULL) n += strstr(e->d_name, ".tmp") != NULL;
    if (d) closedir(d);
    return n;
}

static int run(const char *fmt, const char *a, const char *b, const char *c)
{
    char args[4096];
    snprintf(args, sizeof args, fmt, a, b, c);
    return test_run_cli(args, g_out, sizeof g_out, g_err, sizeof g_err);
}

int main(void)
{
    const char *tmp = test_tmpdir();
    char cache[600], dir[600], path[700], other[700];
    snprintf(cache, sizeof cache, "%s/cache", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    snprintf(dir, sizeof dir, "%s/run", tmp);
    CHECK(run("run --frames 4 --out %s --quiet%s%s", dir, "", "") == 0, "sem run: %s", g_err);

    /* every frame of the run, at the asked size */
    CHECK(run("render %s --size 96 54 --quiet%s%s", dir, "", "") == 0, "%s", g_err);
    int w = 0, h = 0;
    for (int k = 0; k <= 4; ++k) {
        snprintf(path, sizeof path, "%s/render/frame_%04d.png", dir, k);
        CHECK(png_size(path, &w, &h) && w == 96 && h == 54, "%s: %d x %d", path, w, h);
    }
    snprintf(path, sizeof path, "%s/render/frame_0000.png", dir);
    snprintf(other, sizeof other, "%s/render/frame_0004.png", dir);
    CHECK(!same_file(path, other), "the beam moves between frame 0 and 4");
    /* the same bytes again, and for frame 2 drawn alone (the camera frames the whole run) */
    char again[600];
    snprintf(again, sizeof again, "%s/again", tmp);
    CHECK(run("render %s --size 96 54 --quiet -o %s%s", dir, again, "") == 0, "%s", g_err);
    CHECK(run("render %s --size 96 54 --quiet --frames 2:2 -o %s/alone%s", dir, tmp, "") == 0, "%s", g_err);
    for (int k = 0; k <= 4; ++k) {
        snprintf(path, sizeof path, "%s/render/frame_%04d.png", dir, k);
        snprintf(other, sizeof other, "%s/frame_%04d.png", again, k);
        CHECK(same_file(path, other), "frame %d differs between two renders", k);
    }
    snprintf(path, sizeof path, "%s/render/frame_0002.png", dir);
    snprintf(other, sizeof other, "%s/alone/frame_0002.png", tmp);
    CHECK(same_file(path, other), "frame 2 drawn alone differs from frame 2 of the whole run");
    snprintf(other, sizeof other, "%s/alone/frame_0001.png", tmp);
    CHECK(access(other, F_OK) != 0, "--frames 2:2 drew frame 1");

    /* the colourings */
    const char *colors[] = {"material", "quadrature", "origins", "weights:3"};
    for (int c = 0; c < 4; ++c) {
        CHECK(run("render %s --size 64 36 --quiet --frames 4 --color %s -o %s/colors", dir, colors[c], tmp) == 0,
              "--color %s: %s", colors[c], g_err);
        snprintf(path, sizeof path, "%s/colors/frame_0004.png", tmp);
        CHECK(png_size(path, &w, &h) && w == 64, "--color %s wrote no picture", colors[c]);
    }

    /* a model at rest, with its diagnostic colours from default preprocessing */
    snprintf(path, sizeof path, "%s/model.png", tmp);
    CHECK(run("render %s/iges_brep.igs -o %s --size 80 60 --quiet%s", SEM_TEST_DATA, path, "") == 0, "%s", g_err);
    CHECK(png_size(path, &w, &h) && w == 80 && h == 60, "model picture %d x %d", w, h);
    snprintf(path, sizeof path, "%s/beam.igs", tmp);
    CHECK(run("primitive beam --sections 2 -o %s%s%s", path, "", "") == 0, "%s", g_err);
    snprintf(other, sizeof other, "%s/beam_q.png", tmp);
    CHECK(run("render %s --color quadrature --size 64 48 -o %s --quiet%s", path, other, "") == 0, "%s", g_err);
    CHECK(png_size(other, &w, &h), "quadrature picture of a model");

    /* bad input: one line, exit 1 */
    char empty[600];
    snprintf(empty, sizeof empty, "%s/empty", tmp);
    mkdir(empty, 0777);
    CHECK(run("render %s%s%s", empty, "", "") == 1 && one_error_line(g_err) && strstr(g_err, "no frames"),
          "empty folder: %s", g_err);
    char holed[600];
    snprintf(holed, sizeof holed, "%s/holed", tmp);
    char cmd[2000];
    snprintf(cmd, sizeof cmd, "cp -r %s %s && rm %s/frame_0002.igs", dir, holed, holed);
    CHECK(system(cmd) == 0, "cannot copy the run");
    CHECK(run("render %s --quiet%s%s", holed, "", "") == 1 && one_error_line(g_err) &&
              strstr(g_err, "frame_0002.igs is missing"),
          "missing frame: %s", g_err);
    CHECK(run("render %s --color weights:18 --quiet%s%s", dir, "", "") == 1 && one_error_line(g_err) &&
              strstr(g_err, "0..17"),
          "part out of range: %s", g_err);
    CHECK(run("render %s --frames 3:9 --quiet%s%s", dir, "", "") == 1 && one_error_line(g_err), "range: %s", g_err);
    CHECK(run("render %s/nothing.igs%s%s", tmp, "", "") == 1 && one_error_line(g_err), "no model: %s", g_err);
    CHECK(run("render %s/beam.igs --mp4 %s/x.mp4%s", tmp, tmp, "") == 1 && one_error_line(g_err),
          "mp4 of a model: %s", g_err);
    CHECK(run("render %s --camera 1,2,3,4%s%s", dir, "", "") == 2, "--camera with 4 numbers: %s", g_err);
    CHECK(run("render %s --color weight%s%s", dir, "", "") == 2, "--color weight: %s", g_err);
    /* a run written before this version: no preprocess file for the diagnostic colours */
    snprintf(cmd, sizeof cmd, "cp -r %s %s/old && rm %s/old/preprocess_0.semdisc", dir, tmp, tmp);
    CHECK(system(cmd) == 0, "cannot copy the run");
    CHECK(run("render %s/old --color origins --quiet%s%s", tmp, "", "") == 1 && one_error_line(g_err) &&
              strstr(g_err, "preprocess_0.semdisc"),
          "no preprocess file: %s", g_err);
    snprintf(path, sizeof path, "%s/render", dir);
    CHECK(tmp_files(path) == 0, "temporary files left in %s", path);

    /* the video: ffmpeg missing is a clear error before any work; present: an MP4 */
    const char *saved = getenv("PATH");
    char *path_env = saved ? strdup(saved) : NULL;
    setenv("PATH", "/nonexistent", 1);
    CHECK(run("render %s --mp4 %s/a.mp4 --quiet%s", dir, tmp, "") == 1 && one_error_line(g_err) &&
              strstr(g_err, "ffmpeg"),
          "no ffmpeg: %s", g_err);
    if (path_env) setenv("PATH", path_env, 1);
    free(path_env);
    if (system("command -v ffmpeg >/dev/null 2>&1") == 0) {
        snprintf(path, sizeof path, "%s/anim.mp4", tmp);
        CHECK(run("render %s --size 64 36 --quiet --mp4 %s%s", dir, path, "") == 0, "%s", g_err);
        size_t n;
        char *mp4 = test_slurp(path, &n);
        CHECK(mp4 && n > 100 && !memcmp(mp4 + 4, "ftyp", 4), "%s is not an MP4", path);
        free(mp4);
        CHECK(tmp_files(tmp) == 0, "temporary files left in %s", tmp);
    } else {
        printf("ffmpeg not installed: the MP4 encoding is not tested\n");
    }

    /* the viewer page: self-contained (three.js, the glb and the energies inline) */
    CHECK(run("view %s%s%s", dir, "", "") == 0, "%s", g_err);
    snprintf(path, sizeof path, "%s/viewer.html", dir);
    size_t n = 0;
    char *html = test_slurp(path, &n);
    CHECK(html && strstr(html, "REVISION") && strstr(html, "GLTFLoader") && strstr(html, "kinetic_energy") &&
              !strstr(html, "@SEM_") && !strstr(html, "src=\"http"),
          "viewer.html is not self-contained");
    free(html);
    setenv("SEM_THREE_DIR", "/nonexistent", 1);
    CHECK(run("view %s%s%s", dir, "", "") == 1 && one_error_line(g_err) && strstr(g_err, "libjs-three"),
          "no three.js: %s", g_err);
    unsetenv("SEM_THREE_DIR");
    CHECK(run("view %s%s%s", empty, "", "") == 1 && one_error_line(g_err) && strstr(g_err, "animation.glb"),
          "no glb: %s", g_err);
    return test_finish("test_render_cli");
}
