/*
 * cmd_view.c - `sem view OUT_DIR [-o FILE]`: the animation of a run in the browser.
 *
 * Writes OUT_DIR/viewer.html: one self-contained page that needs no network and no other
 * file, so it opens from file://, can be mailed, and works offline. It holds
 *   - the viewer's own page and script (viewer/viewer.html, viewer/viewer.js, built into
 *     this binary by viewer/embed.cmake);
 *   - three.js, GLTFLoader and OrbitControls (MIT), read from the system when the page is
 *     written: Debian's libjs-three (/usr/share/javascript/three, r111, whose examples/js
 *     are plain scripts that attach to the global THREE; SEM_THREE_DIR names another folder
 *     with the same layout). Nothing third-party is part of sem itself;
 *   - OUT_DIR/animation.glb (base64) and OUT_DIR/summary.json (the energy plot).
 * The template's @SEM_NAME@ markers are replaced while the page is streamed to disk
 * (atomically). A page is about 1.2 MB plus 4/3 of the glb.
 */
#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "cli.h"
#include "io/atomic_file.h"
#include "run_folder.h"
#include "util/free_all.h"

#define CMD "view"

extern const unsigned char sem_viewer_html[];
extern const size_t sem_viewer_html_size;
extern const unsigned char sem_viewer_js[];
extern const size_t sem_viewer_js_size;

typedef struct view_assets {
    char *three, *gltf_loader, *orbit_controls; /* file contents */
    char *summary;                              /* summary.json, or NULL */
    unsigned char *glb;
    size_t glb_size;
    char title[256];
} view_assets;

static void assets_free(view_assets *a)
{
    SEM_FREE_ALL(a->three, a->gltf_loader, a->orbit_controls, a->summary, a->glb);
}

/* Reads dir/name (first of the candidates that exists); NULL and a message when none. */
static char *read_three_file(const char *dir, const char *const *names, int n, char *tried, size_t size)
{
    for (int i = 0; i < n; ++i) {
        char path[4400];
        snprintf(path, sizeof path, "%s/%s", dir, names[i]);
        char *text = read_text_file(path, NULL);
        if (text) return text;
        if (i == 0) snprintf(tried, size, "%s", path);
    }
    return NULL;
}

/* A script inlined in <script> must not contain "</script" (it would end the element). */
static int has_script_end(const char *text)
{
    for (const char *p = strchr(text, '<'); p; p = strchr(p + 1, '<'))
        if (p[1] == '/' && strncasecmp(p + 2, "script", 6) == 0) return 1;
    return 0;
}

static int load_three(view_assets *a)
{
    const char *dir = getenv("SEM_THREE_DIR");
    if (!dir || !*dir) dir = "/usr/share/javascript/three";
    static const char *const three[] = {"build/three.min.js", "three.min.js"};
    static const char *const loader[] = {"examples/js/loaders/GLTFLoader.js"};
    static const char *const controls[] = {"examples/js/controls/OrbitControls.js"};
    char tried[4400] = "";
    a->three = read_three_file(dir, three, 2, tried, sizeof tried);
    if (a->three) a->gltf_loader = read_three_file(dir, loader, 1, tried, sizeof tried);
    if (a->gltf_loader) a->orbit_controls = read_three_file(dir, controls, 1, tried, sizeof tried);
    if (!a->orbit_controls)
        return cli_fail("%s: not found: the viewer bundles three.js r111 with its examples/js scripts from the "
                        "Debian package libjs-three (apt-get install libjs-three), or from the folder in "
                        "SEM_THREE_DIR",
                        tried);
    if (has_script_end(a->three) || has_script_end(a->gltf_loader) || has_script_end(a->orbit_controls))
        return cli_fail("%s: a three.js file contains \"</script\" and cannot be inlined in a page", dir);
    return CLI_OK;
}

static int load_run(const char *dir, view_assets *a)
{
    struct stat st;
    if (stat(dir, &st) != 0) return cli_fail("%s: %s", dir, strerror(errno));
    if (!S_ISDIR(st.st_mode)) return cli_fail("%s: not a folder (sem view takes the output folder of sem run)", dir);
    char path[4400];
    snprintf(path, sizeof path, "%s/animation.glb", dir);
    a->glb = (unsigned char *)read_text_file(path, &a->glb_size);
    if (!a->glb)
        return cli_fail("%s: cannot read: %s (sem run writes it unless the scene sets output.glb to false)", path,
                        strerror(errno));
    if (a->glb_size < 12 || memcmp(a->glb, "glTF", 4) != 0) return cli_fail("%s: not a glTF binary file", path);
    snprintf(path, sizeof path, "%s/summary.json", dir);
    a->summary = read_text_file(path, NULL);
    /* the folder's name, for the title */
    char name[4096];
    snprintf(name, sizeof name, "%s", dir);
    size_t len = strlen(name);
    while (len > 1 && name[len - 1] == '/') name[--len] = '\0';
    const char *base = strrchr(name, '/');
    snprintf(a->title, sizeof a->title, "%s", base && base[1] ? base + 1 : name);
    return CLI_OK;
}

static void put_html_escaped(FILE *f, const char *s)
{
    for (; *s; ++s) {
        if (*s == '<') fputs("&lt;", f);
        else if (*s == '>') fputs("&gt;", f);
        else if (*s == '&') fputs("&amp;", f);
        else if (*s == '"') fputs("&quot;", f);
        else fputc(*s, f);
    }
}

/* JSON inside <script type="application/json">: "</" becomes "<\/", the same string in JSON. */
static void put_json(FILE *f, const char *s)
{
    if (!s) {
        fputs("null", f);
        return;
    }
    for (; *s; ++s) {
        if (s[0] == '<' && s[1] == '/') {
            fputs("<\\/", f);
            ++s;
        } else {
            fputc(*s, f);
        }
    }
}

static void put_base64(FILE *f, const unsigned char *data, size_t n)
{
    static const char digits[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    char line[101];
    int used = 0;
    for (size_t i = 0; i < n; i += 3) {
        unsigned v = (unsigned)data[i] << 16;
        if (i + 1 < n) v |= (unsigned)data[i + 1] << 8;
        if (i + 2 < n) v |= data[i + 2];
        line[used++] = digits[(v >> 18) & 63];
        line[used++] = digits[(v >> 12) & 63];
        line[used++] = i + 1 < n ? digits[(v >> 6) & 63] : '=';
        line[used++] = i + 2 < n ? digits[v & 63] : '=';
        if (used == 100 || i + 3 >= n) {
            line[used] = '\0';
            fputs(line, f);
            fputc('\n', f);
            used = 0;
        }
    }
}

/* The template with every @SEM_NAME@ replaced. Returns 0 for an unknown marker. */
static int write_page(FILE *f, const view_assets *a)
{
    const char *t = (const char *)sem_viewer_html, *end = t + sem_viewer_html_size;
    while (t < end) {
        const char *at = memchr(t, '@', (size_t)(end - t));
        if (!at || strncmp(at, "@SEM_", 5) != 0) {
            const char *stop = at ? at + 1 : end;
            fwrite(t, 1, (size_t)(stop - t), f);
            t = stop;
            continue;
        }
        fwrite(t, 1, (size_t)(at - t), f);
        const char *close = memchr(at + 1, '@', (size_t)(end - at - 1));
        if (!close) return 0;
        size_t len = (size_t)(close + 1 - at);
        if (len == 11 && !strncmp(at, "@SEM_TITLE@", len)) put_html_escaped(f, a->title);
        else if (len == 13 && !strncmp(at, "@SEM_SUMMARY@", len)) put_json(f, a->summary);
        else if (len == 9 && !strncmp(at, "@SEM_GLB@", len)) put_base64(f, a->glb, a->glb_size);
        else if (len == 11 && !strncmp(at, "@SEM_THREE@", len)) fputs(a->three, f);
        else if (len == 17 && !strncmp(at, "@SEM_GLTF_LOADER@", len)) fputs(a->gltf_loader, f);
        else if (len == 20 && !strncmp(at, "@SEM_ORBIT_CONTROLS@", len)) fputs(a->orbit_controls, f);
        else if (len == 15 && !strncmp(at, "@SEM_VIEWER_JS@", len)) fwrite(sem_viewer_js, 1, sem_viewer_js_size, f);
        else return 0;
        t = close + 1;
    }
    return 1;
}

int cmd_view(int argc, char **argv)
{
    const char *dir = NULL, *output = NULL;
    for (int i = 1; i < argc; ++i) {
        if (!strcmp(argv[i], "-o") || !strcmp(argv[i], "--output")) {
            if (cli_need_values(CMD, argc, argv, i, 1) != CLI_OK) return CLI_USAGE;
            output = argv[++i];
        } else if (argv[i][0] == '-' && argv[i][1]) {
            return cli_usage(CMD, "unknown option %s", argv[i]);
        } else if (!dir) {
            dir = argv[i];
        } else {
            return cli_usage(CMD, "more than one folder given");
        }
    }
    if (!dir) return cli_usage(CMD, "no run folder given");
    view_assets a;
    memset(&a, 0, sizeof a);
    int rc = load_run(dir, &a);
    if (rc == CLI_OK) rc = load_three(&a);
    if (rc != CLI_OK) {
        assets_free(&a);
        return rc;
    }
    char path[4400];
    if (output)
        snprintf(path, sizeof path, "%s", output);
    else
        snprintf(path, sizeof path, "%s/viewer.html", dir);
    sem_atomic_file file;
    sem_error err;
    if (sem_atomic_open(&file, path, &err) != SEM_OK) {
        assets_free(&a);
        return cli_fail_error(NULL, &err);
    }
    int ok = write_page(file.fp, &a);
    assets_free(&a);
    if (!ok) {
        sem_atomic_abort(&file);
        return cli_fail("the built-in viewer template has an unknown @SEM_...@ marker");
    }
    if (sem_atomic_commit(&file, &err) != SEM_OK) return cli_fail_error(NULL, &err);
    fprintf(stderr, "sem: wrote %s (open it in a browser; it needs no network)\n", path);
    return CLI_OK;
}
