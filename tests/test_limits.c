/*
 * test_limits.c - bounded resources (docs/reliability.md, sem/limits.h).
 *
 * Properties:
 *  - only regular files are read: a FIFO, a folder and a link to /dev/zero named like a
 *    model or a scene fail at once with "not a regular file" (no hang, no 4 GB read);
 *  - a file above the size limit fails before it is read, naming the limit;
 *  - every worst case of fuzz/regressions/ (subfigure bombs, repeated composite members,
 *    124 chains, huge degrees and counts, trim loops near the double range, OBJ trim
 *    references) makes `sem inspect` and `sem preprocess` exit with 0 or a one-line error
 *    (never a signal), the expected limit named where one applies, with a peak resident
 *    memory below 1 GB (measured with wait4; skipped under the sanitizers, whose shadow
 *    memory would count). Times are printed, not asserted; a CPU limit of 120 s per run
 *    only turns a hang into a failure.
 */
#define _GNU_SOURCE
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/time.h>
#include <sys/wait.h>
#include <unistd.h>

#include "sem/limits.h"
#include "sem/model.h"
#include "sem/scene.h"
#include "test_util.h"

typedef struct run_result {
    int exited, status, signal;
    long max_rss_kb;
    double seconds, cpu_seconds;
    char err[8192];
} run_result;

/* Runs `sem ARGS...` with stdout discarded and stderr captured, under a CPU limit. */
static void run_sem(const char *const *args, run_result *r)
{
    memset(r, 0, sizeof *r);
    char err_path[512];
    snprintf(err_path, sizeof err_path, "%s/limits_stderr.txt", test_tmpdir());
    struct timeval t0, t1;
    gettimeofday(&t0, NULL);
    pid_t pid = fork();
    if (pid == 0) {
        struct rlimit cpu = {120, 130};
        setrlimit(RLIMIT_CPU, &cpu);
        int out = open("/dev/null", O_WRONLY);
        int err = open(err_path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (out >= 0) dup2(out, 1);
        if (err >= 0) dup2(err, 2);
        const char *argv[16];
        int n = 0;
        argv[n++] = SEM_BINARY;
        for (int i = 0; args[i] && n < 15; ++i) argv[n++] = args[i];
        argv[n] = NULL;
        setenv("SEM_NO_RESTART", "1", 1);
        execv(SEM_BINARY, (char *const *)argv);
        _exit(127);
    }
    int status = 0;
    struct rusage ru;
    memset(&ru, 0, sizeof ru);
    wait4(pid, &status, 0, &ru);
    gettimeofday(&t1, NULL);
    r->seconds = (t1.tv_sec - t0.tv_sec) + 1e-6 * (t1.tv_usec - t0.tv_usec);
    r->max_rss_kb = ru.ru_maxrss;
    r->cpu_seconds = ru.ru_utime.tv_sec + 1e-6 * ru.ru_utime.tv_usec + ru.ru_stime.tv_sec +
                     1e-6 * ru.ru_stime.tv_usec;
    r->exited = WIFEXITED(status);
    r->status = r->exited ? WEXITSTATUS(status) : -1;
    r->signal = WIFSIGNALED(status) ? WTERMSIG(status) : 0;
    FILE *f = fopen(err_path, "rb");
    if (f) {
        size_t n = fread(r->err, 1, sizeof r->err - 1, f);
        r->err[n] = '\0';
        fclose(f);
    }
}

/* Every stderr line is "sem: ..." (an error or a warning), and an exit status of 1 comes
 * with exactly one error line. */
static void check_messages(const char *what, const run_result *r)
{
    int errors = 0;
    for (const char *p = r->err; *p;) {
        const char *nl = strchr(p, '\n');
        size_t len = nl ? (size_t)(nl - p) : strlen(p);
        CHECK(len > 5 && strncmp(p, "sem: ", 5) == 0, "%s: stderr line '%.*s'", what, (int)len, p);
        if (strncmp(p, "sem: warning:", 13) != 0) errors++;
        int control = 0;
        for (size_t i = 0; i < len; ++i) control |= (unsigned char)p[i] < 0x20 || p[i] == 0x7f;
        CHECK(!control, "%s: control byte in '%.*s'", what, (int)len, p);
        p = nl ? nl + 1 : p + len;
    }
    if (r->status == 1) CHECK(errors == 1, "%s: %d error lines:\n%s", what, errors, r->err);
}

static void check_bounded(const char *what, const run_result *r)
{
    CHECK(r->exited && (r->status == 0 || r->status == 1), "%s: exit %d signal %d\n%s", what,
          r->status, r->signal, r->err);
    check_messages(what, r);
    const char *san = getenv("SEM_SANITIZED");
    if (!(san && san[0] == '1'))
        CHECK(r->max_rss_kb < 1024L * 1024L, "%s: peak memory %ld KB", what, r->max_rss_kb);
    printf("  %-52s exit %d  %6.2f s wall %6.2f s cpu %7ld KB\n", what, r->status, r->seconds,
           r->cpu_seconds, r->max_rss_kb);
}

static void special_files(void)
{
    const char *dir = test_tmpdir();
    char fifo[512], zero[512], folder[512], scene_fifo[512], obj_zero[512];
    snprintf(fifo, sizeof fifo, "%s/fifo.igs", dir);
    snprintf(zero, sizeof zero, "%s/zero.igs", dir);
    snprintf(folder, sizeof folder, "%s/folder.iges", dir);
    snprintf(scene_fifo, sizeof scene_fifo, "%s/scene_fifo.json", dir);
    snprintf(obj_zero, sizeof obj_zero, "%s/zero.obj", dir);
    CHECK(mkfifo(fifo, 0644) == 0, "mkfifo");
    CHECK(mkfifo(scene_fifo, 0644) == 0, "mkfifo");
    CHECK(symlink("/dev/zero", zero) == 0, "symlink");
    CHECK(symlink("/dev/zero", obj_zero) == 0, "symlink");
    CHECK(mkdir(folder, 0755) == 0, "mkdir");
    const char *models[] = {fifo, zero, folder, obj_zero};
    for (int i = 0; i < 4; ++i) {
        /* the library call itself */
        sem_model *m = NULL;
        sem_error err;
        sem_status st = sem_model_load(models[i], &m, &err);
        CHECK(st == SEM_ERR_IO && strstr(err.message, "not a regular file"), "%s: %s",
              models[i], err.message);
        sem_model_destroy(m);
        /* and the commands */
        run_result r;
        const char *inspect[] = {"inspect", models[i], NULL};
        run_sem(inspect, &r);
        check_bounded(models[i], &r);
        CHECK(r.status == 1 && strstr(r.err, "not a regular file"), "%s: %s", models[i], r.err);
    }
    sem_scene *scene = NULL;
    sem_error err;
    CHECK(sem_scene_load(scene_fifo, &scene, &err) == SEM_ERR_IO &&
              strstr(err.message, "not a regular file"),
          "scene FIFO: %s", err.message);
    run_result r;
    const char *run[] = {"run", scene_fifo, "--out", dir, NULL};
    run_sem(run, &r);
    check_bounded("sem run FIFO.json", &r);
    CHECK(r.status == 1 && strstr(r.err, "not a regular file"), "run FIFO: %s", r.err);

    /* a sparse file one byte over the limit is refused by its size, not read */
    char big[512];
    snprintf(big, sizeof big, "%s/big.igs", dir);
    int fd = open(big, O_WRONLY | O_CREAT | O_TRUNC, 0644);
    CHECK(fd >= 0 && ftruncate(fd, SEM_MAX_MODEL_FILE_BYTES + 1) == 0, "sparse file");
    if (fd >= 0) close(fd);
    sem_model *m = NULL;
    CHECK(sem_model_load(big, &m, &err) == SEM_ERR_IO &&
              strstr(err.message, "SEM_MAX_MODEL_FILE_BYTES"),
          "big file: %s", err.message);
    sem_model_destroy(m);
}

typedef struct worst_case {
    int heavy;             /* seconds of work: run only without the sanitizers (the replay
                              tests fuzz_regress_* cover these files under them) */
    const char *file;      /* under fuzz/regressions/ */
    const char *inspect;   /* expected in stderr of `sem inspect`, or NULL for success */
    const char *preprocess; /* expected in stderr of `sem preprocess` */
} worst_case;

static void worst_cases(void)
{
    static const worst_case cases[] = {
        {0, "iges/subfigure_fanout.igs", "SEM_MAX_PARTS", "SEM_MAX_PARTS"},
        {0, "iges/subfigure_repeat.igs", "SEM_MAX_PARTS", "SEM_MAX_PARTS"},
        {0, "iges/subfigure_parts.igs", "SEM_MAX_PARTS", "SEM_MAX_PARTS"},
        {0, "iges/composite_repeat.igs", "SEM_MAX_TRIM_SEGMENTS", "SEM_MAX_TRIM_SEGMENTS"},
        {1, "iges/composite_repeat_deep.igs", "SEM_MAX_IGES_EXPANSION", "SEM_MAX_IGES_EXPANSION"},
        {1, "iges/xform_chains.igs", NULL, "encloses no volume"},
        {0, "iges/huge_degree.igs", "SEM_MAX_MODEL_SPAN_WORK", "SEM_MAX_MODEL_SPAN_WORK"},
        {1, "iges/huge_degree_accepted.igs", NULL, "SEM_MAX_BOUNDARY_ENTRIES"},
        {1, "iges/curved_parts.igs", NULL, "SEM_MAX_SHARED_FIT_PARTS"},
        {0, "iges/trim_huge_coordinates.igs", NULL, "encloses no volume"},
        /* its one loop does not close (trim_fix.c leaves it out with a warning) before its
         * spans are counted: the face is untrimmed and flat */
        {0, "iges/trim_many_spans.igs", NULL, "encloses no volume"},
        {0, "iges/trim_many_spans_closed.igs", "SEM_MAX_TRIM_SEGMENTS", "SEM_MAX_TRIM_SEGMENTS"},
        {0, "iges/self_reference.igs", NULL, "encloses no volume"},
        {0, "iges/control_bytes.igs", "is not a number", "is not a number"},
        {1, "obj/trim_references.obj", "SEM_MAX_MODEL_CONTROL_POINTS", "SEM_MAX_MODEL_CONTROL_POINTS"},
        {0, "obj/open_trim.obj", "does not close", "does not close"},
        {0, "obj/trim_huge_coordinates.obj", NULL, "encloses no volume"},
    };
    const char *san = getenv("SEM_SANITIZED");
    int sanitized = san && san[0] == '1';
    {   /* the per-part fits of the same model: the q-space operators' limit */
        char path[1024];
        snprintf(path, sizeof path, "%s/../../fuzz/regressions/iges/curved_parts.igs", SEM_TEST_DATA);
        const char *args[] = {"preprocess", path, "--fit", "parts", NULL};
        run_result r;
        run_sem(args, &r);
        check_bounded("preprocess --fit parts iges/curved_parts.igs", &r);
        CHECK(r.status == 1 && strstr(r.err, "SEM_MAX_PREPROCESS_CONTROL_POINTS"), "--fit parts: got:\n%s", r.err);
    }
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; ++i) {
        if (sanitized && cases[i].heavy) continue;
        char path[1024], what[1200];
        snprintf(path, sizeof path, "%s/../../fuzz/regressions/%s", SEM_TEST_DATA, cases[i].file);
        for (int cmd = 0; cmd < 2; ++cmd) {
            const char *expect = cmd ? cases[i].preprocess : cases[i].inspect;
            const char *args[] = {cmd ? "preprocess" : "inspect", path, NULL};
            run_result r;
            run_sem(args, &r);
            snprintf(what, sizeof what, "%s %s", args[0], cases[i].file);
            check_bounded(what, &r);
            if (expect)
                CHECK(r.status == 1 && strstr(r.err, expect), "%s: expected '%s', got:\n%s", what,
                      expect, r.err);
            else
                CHECK(r.status == 0, "%s: expected success, got:\n%s", what, r.err);
        }
    }
}

int main(void)
{
    signal(SIGPIPE, SIG_IGN);
    special_files();
    worst_cases();
    return test_finish("test_limits");
}
