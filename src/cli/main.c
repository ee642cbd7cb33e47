/*
 * main.c - `sem <command> [options]`: the table of commands and the shared CLI helpers.
 *
 * Each command lives in its own cmd_NAME.c; this file only dispatches, prints help and
 * holds the message/parsing helpers declared in cli.h, so that every command reports
 * errors the same way (one "sem: ..." line, exit 1; usage errors exit 2).
 */
#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <unistd.h>

#include "cli.h"
#include "sem/cache.h"
#include "sem/version.h"

typedef struct cli_command {
    const char *name;
    int (*run)(int argc, char **argv);
    const char *usage;   /* arguments after "sem NAME" */
    const char *summary; /* one line for `sem --help` */
    const char *help;    /* options, for `sem NAME --help` */
} cli_command;

static const cli_command commands[] = {
    {"primitive", cmd_primitive, "box|beam|sphere|cylinder|torus [options] -o FILE",
     "build an exact NURBS solid and save it (format by extension)",
     "Shapes and options (lengths in model units, metres by default):\n"
     "  box       --size X Y Z (1 1 1)  --center X Y Z (0 0 0)  --degree D (3)\n"
     "            6 Bezier patches, bicubic by default\n"
     "  beam      --sections N (1)  --length L (5)  --width W (1)  --height H (1)\n"
     "            --degree D (2)   box beam along x from 0 to L, 6 + 4(N-1) patches,\n"
     "            biquadratic like the paper's beams/perf files; x = 0 is the clamped end\n"
     "  sphere    --radius R (1)  --center X Y Z\n"
     "  cylinder  --radius R (1)  --height H (2)  --center X Y Z   (axis z, closed)\n"
     "  torus     --major R (1)  --minor r (0.25)  --center X Y Z   (axis z)\n"
     "  -o, --output FILE   where to write (.igs/.iges, .obj, .step/.stp)\n"},
    {"inspect", cmd_inspect, "FILE [--json]",
     "sizes, degrees of freedom, area, bounding box and warnings of a model",
     "  --json   print one JSON object (file, parts, control_points, dofs, trimmed_parts,\n"
     "           bbox, area, units, warnings, part_details) instead of text\n"},
    {"convert", cmd_convert, "IN OUT", "convert a model between formats (by extension)",
     "  IN and OUT: .igs/.iges (IGES 5.3), .obj (OBJ free-form), .step/.stp (STEP, through\n"
     "  Open CASCADE; `sem --version` says when this build has no STEP support)\n"},
    {"refine", cmd_refine, "IN OUT --factor K",
     "the same model with more control points: exact knot insertion (about K^2 times per part)",
     "  --factor K, -k K  split every non-empty knot span of every part into K equal parts in u\n"
     "                    and in v (1..64); a direction with n control points and s spans gets\n"
     "                    n + (K - 1) s. The surfaces are unchanged up to round-off (rational\n"
     "                    ones too); trims, part names and units are kept.\n"
     "  IN and OUT: any model format (by extension, as sem convert). The result is refused when\n"
     "  it would exceed what the readers accept (include/sem/limits.h).\n"},
    {"preprocess", cmd_preprocess, "FILE [--order 1|2] [--spacing H | --rays N1 N2 [--axis x|y|z]] [--points-per-interval N] [--alpha A | --sparsity T] [--origins coupled|paper] [--fit auto|parts|origins] [--gamma G] [-E E] [--blend C] [--tessellation N] [--threads N] [--json] [--save OUT] [--no-cache] [--no-modes]", "SEM preprocessing (samples, quadrature, weights, Pi, operators) with Table 1 timings and zero-energy modes", "  --order 1|2 (2)  --spacing H quadrature cell size (automatic: object-frame cells)\n  --rays N1 N2 the paper's explicit ray grid along --axis (x)  --points-per-interval N (automatic)\n  --alpha A (> 0, model units) or --sparsity T in (0,1); neither: alpha = half the median part size\n  --origins coupled|paper (coupled)  --fit auto|parts|origins: one polynomial per part or per origin (auto)\n  --gamma G (default 1000 E / bbox diagonal)  -E, --youngs-modulus E (1e6)\n  --blend C volume consistency stiffness for the mode check (0.02)  --no-modes skip the zero-energy mode check\n  --tessellation N (16)  --threads N (0: OpenMP default)  --json  --save OUT (binary file, versioned)\n  The result goes into the cache sem run reads ($SEM_CACHE_DIR, see sem run --help) unless --no-cache.\n"},
    {"run", cmd_run, "[SCENE] [--frames N] [--out DIR] [--overwrite] [--strict] [--json] [--no-cache] [--quiet] | --resume DIR [--strict]",
     "simulate a scene and write the animation (NURBS per frame, meshes, USD, summary.json)",
     "  SCENE        a scene file (JSON, see docs/scenes.md); without it the embedded default\n"
     "               scene runs: a rubber beam clamped at x = 0 swinging under gravity\n"
     "  --frames N   override the scene's frame count    --out DIR  override the output folder\n"
     "  --overwrite  replace the files of another run in the output folder (else an error)\n"
     "  --resume DIR continue the run in DIR (stopped by Ctrl-C, SIGTERM, kill -9, a crash) from\n"
     "               its last complete frame; the result is that of an uninterrupted run\n"
     "  --json       print summary.json on stdout        --no-cache recompute the preprocessing\n"
     "  --quiet      no progress output\n"
     "  --strict     a suspect answer is an error: the run stops at the first frame whose seams\n"
     "               open, error energy or volume pass their limits (exit 1, frames kept);\n"
     "               without it such a run ends with status suspect and a warning\n"
     "  Ctrl-C or SIGTERM: the frames so far, animation.usda and summary.json (status\n"
     "  interrupted) are written, exit status 130 / 143. Preprocessed data is cached by model\n"
     "  content and settings in $SEM_CACHE_DIR (default $XDG_CACHE_HOME/sem or ~/.cache/sem),\n"
     "  at most $SEM_CACHE_MAX_MB megabytes (2048), least recently used entries removed first.\n"},
    {"bench", cmd_bench, "[--json] [--defaults] [--models DIR] [--steps N] [--repeat N] [--solver S] [--only TEXT]", "the paper's Table 1 timings on the shared models, beside the paper's figures", "  --models DIR  shared models folder (default $SEM_SHARED_MODELS, ../shared/models, ../../shared/models)\n  --steps N     timed linearly implicit Euler steps per row after one warm-up step (20)\n  --solver S    auto (the fixed rule, default), sparse (CHOLMOD) or dense (LAPACK)\n  --repeat N    preprocessing runs per row; each phase reports its fastest run (5)\n  --only TEXT   rows whose example name or file contains TEXT\n  --defaults    sem's default settings instead of the authors' (quadrature, origins, blend)\n  --json        a list of objects: example, file, dofs, sample_s, quad_s, weights_s, build_pi_s,\n                step_s, factor_s, nnz_percent (+ order, solver, scene_s, paper)\n"},
    {"render", cmd_render, "OUT_DIR | MODEL_FILE [-o OUT] [--mp4 FILE] [--size W H] [--frames A:B] [--camera AZ,EL[,DIST] | --camera EX,EY,EZ,TX,TY,TZ] [--color part|material|weights:PART|origins|quadrature]",
     "ray-traced pictures of a run's frames (PNG, optionally an MP4 video) or of a model at rest",
     "  OUT_DIR      a folder written by sem run: every frame -> OUT_DIR/render/frame_NNNN.png\n"
     "  MODEL_FILE   a model (.igs/.iges, .obj): one picture of it at rest (default MODEL.png)\n"
     "  -o OUT       the pictures' folder (a run) or the picture's file (a model)\n"
     "  --mp4 FILE   also encode the frames as an H.264 video with ffmpeg\n"
     "  --size W H   picture size in pixels (1280 720)\n"
     "  --frames A:B only frames A..B (A:, :B and A also work)\n"
     "  --camera AZ,EL[,DIST]       orbit camera: azimuth and elevation in degrees (-60,25), distance\n"
     "                              (default: the whole animation fills the picture)\n"
     "  --camera EX,EY,EZ,TX,TY,TZ  look-at camera: eye and target points\n"
     "  --color MODE part (default), material, weights:PART (blending weights of one part),\n"
     "               origins (deformation origins), quadrature (volume quadrature points)\n"
     "  --disc FILE  preprocessed data for a model's diagnostic colours (sem preprocess --save);\n"
     "               without it the model is preprocessed with the default settings\n"
     "  --resolution N  tessellation cells per knot span (8)   --quiet  no progress output\n"},
    {"view", cmd_view, "OUT_DIR [-o FILE]",
     "write OUT_DIR/viewer.html: the animation in the browser (offline, self-contained)",
     "  OUT_DIR   a folder written by sem run (needs its animation.glb; summary.json gives the\n"
     "            energy plot)\n"
     "  -o FILE   write the page there instead of OUT_DIR/viewer.html\n"
     "  The page bundles three.js from the Debian package libjs-three\n"
     "  (/usr/share/javascript/three; SEM_THREE_DIR overrides the folder).\n"},
    {"validate", cmd_validate,
     "MODEL [SCENE] [--json] [--tolerance T] [--workdir DIR] [--keep] [--no-install] [--max-levels N] [--max-nodes N] [--h0 H] [-E E] [--resolutions R1,R2,...] [--quiet]",
     "sem against a converged FEM solution (gmsh + CalculiX) of the same static sag",
     "  Meshes MODEL with gmsh (Open CASCADE, faces sewn into solids) into quadratic tetrahedra,\n"
     "  solves the static sag under gravity with CalculiX (neo-Hookean, NLGEOM), refining the mesh\n"
     "  until the answer changes by less than T, runs the same problem through sem (integrator\n"
     "  static) and compares the two at the FEM surface nodes: relative L2 error of the displacement\n"
     "  (area-weighted) and the largest displacement of each. Needs python3; gmsh and calculix-ccx\n"
     "  come from Debian and are installed with apt-get when missing (docs/validation.md).\n"
     "  Problem without SCENE: the model in metres (its file's units), gravity 9.81 m/s^2 along -z,\n"
     "  neo-Hookean density 1000 kg/m^3, nu 0.45, E chosen so that the largest displacement is\n"
     "  about 1 % of the model's largest dimension, pinned where z is in the lowest 10 % of the\n"
     "  height. SCENE (one object; its model is replaced by MODEL): its units, transform, material,\n"
     "  gravity, pin box and sem settings instead.\n"
     "  --json          print one JSON object (the report) on stdout\n"
     "  --tolerance T   FEM refinement stops when the L2 norm and the largest surface displacement\n"
     "                  change by less than T between two meshes (0.005)\n"
     "  --max-levels N  at most N meshes (5), the characteristic length x 0.7 per mesh\n"
     "  --max-nodes N   no mesh with more than N nodes (40000)\n"
     "  --h0 H          first characteristic length, metres (the largest dimension / 10)\n"
     "  -E, --youngs-modulus E   Young's modulus, Pa, instead of the 1 % rule or the scene's\n"
     "  --resolutions R1,R2,...  sem solved again at each sem.resolution (the accuracy setting),\n"
     "                  each against the same FEM answer: dofs, L2 error, largest-displacement ratio\n"
     "  --workdir DIR   work in DIR (meshes, CalculiX files, sem's frames, surface_nodes.csv and\n"
     "                  surface_faces.csv); kept. Default: a temporary folder, removed unless --keep\n"
     "  --no-install    fail instead of installing gmsh or calculix-ccx    --quiet  no progress\n"
     "  Exit status: 0 done, 1 failure (one line: e.g. gmsh could not make a solid of the faces),\n"
     "  2 bad command line, 3 gmsh or CalculiX missing and not installable.\n"},
    {"probe", cmd_probe, "REST FRAME POINTS [--slack D]",
     "a deformed frame at the rest (part, u, v) of points (helper of sem validate)",
     "  For each point of POINTS (x y z a line, in the files' units): the closest point of REST\n"
     "  and FRAME's surface point at the same part and (u,v). Prints one line per point:\n"
     "  part u v distance inside_trim x y z. --slack D: prefer a point inside the trims that is at\n"
     "  most D farther than the closest (0).\n"},
};

/* helpers of other commands: runnable, not listed by `sem --help` */
static int is_hidden(const cli_command *c)
{
    return strcmp(c->name, "probe") == 0;
}

static const int n_commands = (int)(sizeof commands / sizeof commands[0]);

static const cli_command *find_command(const char *name)
{
    for (int i = 0; i < n_commands; ++i)
        if (strcmp(commands[i].name, name) == 0) return &commands[i];
    return NULL;
}

/* ---- messages ---- */

/* "sem: ", the prefix, then the message on one line, whatever it contains. */
static void print_one_line(const char *prefix, const char *fmt, va_list ap)
{
    char buf[2048];
    vsnprintf(buf, sizeof buf, fmt, ap);
    for (char *c = buf; *c; ++c)
        if (*c == '\n' || *c == '\r') *c = ' ';
    fprintf(stderr, "sem: %s%s\n", prefix, buf);
}

int cli_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    print_one_line("", fmt, ap);
    va_end(ap);
    return CLI_FAILED;
}

int cli_fail_error(const char *path, const sem_error *err)
{
    const char *msg = err && err->message[0] ? err->message : "unknown error";
    if (path && !strstr(msg, path)) return cli_fail("%s: %s", path, msg);
    return cli_fail("%s", msg);
}

int cli_usage(const char *command, const char *fmt, ...)
{
    char buf[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(buf, sizeof buf, fmt, ap);
    va_end(ap);
    fprintf(stderr, "sem: %s\n", buf);
    const cli_command *c = command ? find_command(command) : NULL;
    if (c)
        fprintf(stderr, "usage: sem %s %s  (sem %s --help for more)\n", c->name, c->usage,
                c->name);
    else
        fprintf(stderr, "usage: sem <command> [options]  (sem --help for the commands)\n");
    return CLI_USAGE;
}

void cli_warn(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    print_one_line("warning: ", fmt, ap);
    va_end(ap);
}

void cli_print_model_warnings(const sem_model *model)
{
    for (int i = 0; i < model->n_warnings; ++i)
        if (model->warnings[i]) cli_warn("%s", model->warnings[i]);
}

int cli_print_json(cJSON *json)
{
    if (!json) return cli_fail("out of memory building JSON output");
    char *text = cJSON_Print(json);
    cJSON_Delete(json);
    if (!text) return cli_fail("out of memory printing JSON output");
    fputs(text, stdout);
    fputc('\n', stdout);
    free(text);
    return CLI_OK;
}

/* ---- parsing ---- */

int cli_parse_double(const char *command, const char *option, const char *text, double *out)
{
    char *end;
    errno = 0;
    double x = strtod(text, &end);
    if (end == text || *end != '\0' || errno == ERANGE || !isfinite(x))
        return cli_usage(command, "%s: '%s' is not a number", option, text);
    *out = x;
    return CLI_OK;
}

void cli_cache_dir(char *out, size_t size)
{
    const char *d = getenv("SEM_CACHE_DIR");
    if (d && *d) {
        snprintf(out, size, "%s", d);
        return;
    }
    const char *x = getenv("XDG_CACHE_HOME");
    if (x && *x) {
        snprintf(out, size, "%s/sem", x);
        return;
    }
    const char *h = getenv("HOME");
    snprintf(out, size, "%s/.cache/sem", h && *h ? h : "/tmp");
}

long long cli_cache_max_bytes(void)
{
    const char *v = getenv("SEM_CACHE_MAX_MB");
    if (v && *v) {
        char *end;
        errno = 0;
        long long mb = strtoll(v, &end, 10);
        if (errno == 0 && *end == '\0' && mb >= 0 && mb < (1LL << 40)) return mb << 20;
        cli_warn("SEM_CACHE_MAX_MB='%s' is not a number of megabytes; using %lld", v,
                 SEM_CACHE_DEFAULT_MAX_BYTES >> 20);
    }
    return SEM_CACHE_DEFAULT_MAX_BYTES;
}

int cli_parse_int(const char *command, const char *option, const char *text, int *out)
{
    char *end;
    errno = 0;
    long x = strtol(text, &end, 10);
    if (end == text || *end != '\0' || errno == ERANGE || x < INT_MIN || x > INT_MAX) {
        /* "1e12" or 99999999999: an integer, only too large for the option */
        errno = 0;
        double d = strtod(text, &end);
        if (end != text && *end == '\0' && isfinite(d) && d == floor(d) && fabs(d) > INT_MAX)
            return cli_usage(command, "%s: %s is too large", option, text);
        return cli_usage(command, "%s: '%s' is not an integer", option, text);
    }
    *out = (int)x;
    return CLI_OK;
}

int cli_need_values(const char *command, int argc, char **argv, int i, int count)
{
    if (i + count >= argc)
        return cli_usage(command, "%s needs %d value%s", argv[i], count, count == 1 ? "" : "s");
    return CLI_OK;
}

int cli_take_file(const char *command, const char *arg, const char **files, int *n, int most)
{
    if (arg[0] == '-' && arg[1] != '\0') return cli_usage(command, "unknown option '%s'", arg);
    if (*n == most) return cli_usage(command, "too many arguments ('%s')", arg);
    files[(*n)++] = arg;
    return CLI_OK;
}

int cli_is_help(const char *arg)
{
    return strcmp(arg, "--help") == 0 || strcmp(arg, "-h") == 0;
}

/* ---- help ---- */

static void print_help(FILE *f)
{
    fprintf(f,
            "sem %s - Shape Matching Element Method: animate NURBS CAD models directly\n"
            "\n"
            "usage: sem <command> [options]\n"
            "       sem <command> --help\n"
            "       sem --version\n"
            "\n"
            "commands:\n",
            sem_version());
    for (int i = 0; i < n_commands; ++i)
        if (!is_hidden(&commands[i])) fprintf(f, "  %-10s %s\n", commands[i].name, commands[i].summary);
}

static void print_command_help(const cli_command *c)
{
    printf("usage: sem %s %s\n\n%s\n\n%s", c->name, c->usage, c->summary, c->help);
}

/* OpenMP threads that spin-wait after a parallel region take the second core from
 * OpenBLAS's threads in the factorization that follows, and OpenBLAS's spinning threads
 * take it back from the next parallel region: on 2 cores that made a 650-dof step (4 ms
 * of factorization) take 14-20 ms instead of 7-11 (sem bench, rockets). OpenBLAS's idle
 * threads spin (sched_yield) for 2^28 cycles, 0.13 s, before they sleep, i.e. through
 * every step's assembly: on the 1800-dof mug the step took 46-52 ms instead of 40-42
 * (sem bench, OPENBLAS_THREAD_TIMEOUT 28 against 18-22). Both runtimes read these settings
 * once, from the environment, before main runs; so sem restarts itself once with
 * OMP_WAIT_POLICY=passive (sleeping OpenMP threads) and OPENBLAS_THREAD_TIMEOUT=20 (2^20
 * cycles, about 0.5 ms: OpenBLAS's threads stay awake through a factorization's BLAS
 * calls and sleep during assembly), each unless the user set it. SEM_NO_RESTART=1 turns
 * the restart off, and it is skipped under valgrind. Programs using libsem directly can
 * set the variables themselves. */
static void prefer_passive_threads(char **argv)
{
#if defined(__linux__)
    if (getenv("SEM_NO_RESTART")) return;
    int set_omp = !getenv("OMP_WAIT_POLICY") && !getenv("GOMP_SPINCOUNT");
    int set_blas = !getenv("OPENBLAS_THREAD_TIMEOUT") && !getenv("GOTO_THREAD_TIMEOUT");
    if (!set_omp && !set_blas) return;
    /* under valgrind the restarted process would run outside it */
    const char *preload = getenv("LD_PRELOAD");
    if (preload && strstr(preload, "vgpreload")) return;
    if (set_omp && setenv("OMP_WAIT_POLICY", "passive", 1) != 0) return;
    if (set_blas && setenv("OPENBLAS_THREAD_TIMEOUT", "20", 1) != 0) return;
    execv("/proc/self/exe", argv);
    /* exec failed: carry on as we are */
    if (set_omp) unsetenv("OMP_WAIT_POLICY");
    if (set_blas) unsetenv("OPENBLAS_THREAD_TIMEOUT");
#else
    (void)argv;
#endif
}

int main(int argc, char **argv)
{
    prefer_passive_threads(argv);
    if (argc < 2) {
        print_help(stderr);
        return CLI_USAGE;
    }
    const char *name = argv[1];
    if (cli_is_help(name) || strcmp(name, "help") == 0) {
        const cli_command *c = argc > 2 ? find_command(argv[2]) : NULL;
        if (c) print_command_help(c);
        else print_help(stdout);
        return CLI_OK;
    }
    if (strcmp(name, "--version") == 0 || strcmp(name, "version") == 0) {
        printf("sem %s%s\n", sem_version(), sem_has_step() ? "" : " (without STEP: built without Open CASCADE)");
        return CLI_OK;
    }
    const cli_command *c = find_command(name);
    if (!c) {
        if (name[0] == '-') return cli_usage(NULL, "unknown option '%s'", name);
        return cli_usage(NULL, "unknown command '%s'", name);
    }
    for (int i = 2; i < argc; ++i) {
        if (cli_is_help(argv[i])) {
            print_command_help(c);
            return CLI_OK;
        }
    }
    int rc = c->run(argc - 1, argv + 1);
    if (fflush(stdout) != 0 && rc == CLI_OK) return cli_fail("cannot write to standard output");
    return rc;
}
