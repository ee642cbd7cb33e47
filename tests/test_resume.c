/*
 * test_resume.c - reproducible runs, interrupted runs, resumed runs (docs/reliability.md).
 *
 * Properties, each compared byte for byte over every file a run writes (frames, meshes,
 * animation.usda, animation.glb, the preprocessing file, state files) and number for number over summary.json (timings aside):
 *  - two runs of the same scene with SOURCE_DATE_EPOCH set are identical, and so are runs
 *    on 1 and 2 threads;
 *  - Ctrl-C (SIGINT) and SIGTERM stop a run with status 130 / 143, one message, and
 *    summary.json ("interrupted", the signal) and animation.usda for the frames written;
 *  - `sem run --resume` after SIGINT or kill -9 gives exactly the uninterrupted run;
 *  - a folder holding another run's files is refused without --overwrite; --overwrite
 *    removes that run's files (not others) before writing;
 *  - frame names are as wide as the largest frame number needs.
 * The signals are sent when the run has written a given frame's state, so the test does not
 * depend on the machine's speed.
 */
#include <cjson/cJSON.h>
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include "output/run_state.h"
#include "test_util.h"

static char g_scene[600];

/* A small scene that takes a few seconds: the default beam, 40 frames of 2 steps. */
static void write_scene(const char *tmp)
{
    snprintf(g_scene, sizeof g_scene, "%s/scene.json", tmp);
    FILE *f = fopen(g_scene, "w");
    if (!f) return;
    fputs("{\"objects\": [{\"primitive\": {\"type\": \"beam\", \"sections\": 3, \"length\": 1.5, "
          "\"width\": 0.3, \"height\": 0.3},\n"
          "  \"material\": {\"density\": 1100, \"youngs_modulus\": 2e6, \"poisson_ratio\": 0.45},\n"
          "  \"sem\": {\"order\": 2, \"rays\": [4, 4], \"points_per_interval\": 6},\n"
          "  \"pin\": {\"box\": [[-0.01, -1, -1], [0.01, 1, 1]]}}],\n"
          " \"integrator\": {\"type\": \"implicit_euler\", \"dt\": 0.01},\n"
          " \"frames\": 40, \"steps_per_frame\": 2, \"output\": {\"obj\": true}}\n",
          f);
    fclose(f);
}

/* Starts `sem ARGS` (stdout/stderr to files in dir); returns the pid. */
static pid_t start_sem(const char *const *args, const char *log_prefix)
{
    pid_t pid = fork();
    if (pid == 0) {
        char path[700];
        snprintf(path, sizeof path, "%s.out", log_prefix);
        int out = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        snprintf(path, sizeof path, "%s.err", log_prefix);
        int err = open(path, O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (out >= 0) dup2(out, 1);
        if (err >= 0) dup2(err, 2);
        const char *argv[16];
        int n = 0;
        argv[n++] = SEM_BINARY;
        for (int i = 0; args[i] && n < 15; ++i) argv[n++] = args[i];
        argv[n] = NULL;
        execv(SEM_BINARY, (char *const *)argv);
        _exit(127);
    }
    return pid;
}

/* Exit status, or 128 + signal when killed. */
static int wait_sem(pid_t pid)
{
    int status = 0;
    waitpid(pid, &status, 0);
    if (WIFEXITED(status)) return WEXITSTATUS(status);
    if (WIFSIGNALED(status)) return 128 + WTERMSIG(status);
    return -1;
}

static int run_sem(const char *const *args, const char *log_prefix)
{
    return wait_sem(start_sem(args, log_prefix));
}

static int exists(const char *path)
{
    struct stat sb;
    return stat(path, &sb) == 0;
}

/* Runs the scene into dir, sending `sig` once frame `frame`'s state file exists. Returns
 * the exit status (128 + 9 for SIGKILL). */
static int run_and_stop(const char *dir, int frame, int sig, const char *log_prefix)
{
    const char *args[] = {"run", g_scene, "--out", dir, "--quiet", NULL};
    pid_t pid = start_sem(args, log_prefix);
    char state[700];
    snprintf(state, sizeof state, "%s/state/frame_%04d.state", dir, frame);
    int status = -1;
    for (int i = 0; i < 600000; ++i) {
        if (exists(state)) {
            kill(pid, sig);
            break;
        }
        if (waitpid(pid, &status, WNOHANG) == pid) /* finished before the frame: a failure */
            return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
        struct timespec ts = {0, 200000};
        nanosleep(&ts, NULL);
    }
    return wait_sem(pid);
}


/* Every regular file of a's folder (and its state folder) is in b with the same bytes;
 * summary.json is compared without its timings and folder names. Returns files compared. */
static int same_files(const char *a, const char *b, const char *what);

static int same_folder(const char *a, const char *b, const char *what)
{
    DIR *d = opendir(a);
    if (!d) {
        CHECK(0, "%s: cannot list %s", what, a);
        return 0;
    }
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) {
        if (e->d_name[0] == '.' || strcmp(e->d_name, "summary.json") == 0) continue;
        char pa[1200], pb[1200];
        snprintf(pa, sizeof pa, "%s/%s", a, e->d_name);
        snprintf(pb, sizeof pb, "%s/%s", b, e->d_name);
        struct stat sb;
        if (stat(pa, &sb) != 0) continue;
        if (S_ISDIR(sb.st_mode)) {
            n += same_folder(pa, pb, what);
            continue;
        }
        size_t la = 0, lb = 0;
        char *x = test_slurp(pa, &la), *y = test_slurp(pb, &lb);
        CHECK(x && y && la == lb && memcmp(x, y, la) == 0, "%s: %s differs from %s", what, pa, pb);
        free(x);
        free(y);
        n++;
    }
    closedir(d);
    return n;
}

/* summary.json numbers that do not depend on the machine's speed (nor on what a process
 * took: peak_memory_bytes) */
static void same_summary(const char *a, const char *b, const char *what)
{
    char pa[700], pb[700];
    snprintf(pa, sizeof pa, "%s/summary.json", a);
    snprintf(pb, sizeof pb, "%s/summary.json", b);
    size_t la, lb;
    char *x = test_slurp(pa, &la), *y = test_slurp(pb, &lb);
    cJSON *ja = x ? cJSON_Parse(x) : NULL, *jb = y ? cJSON_Parse(y) : NULL;
    free(x);
    free(y);
    CHECK(ja && jb, "%s: summaries readable", what);
    if (ja && jb) {
        static const char *const drop[] = {"mean_step_s", "max_step_s", "mean_factor_s",
                                           "preprocess_s", "preprocess_cached", "output_dir", "usd",
                                           "glb", "peak_memory_bytes"};
        for (size_t k = 0; k < sizeof drop / sizeof drop[0]; ++k) {
            cJSON_DeleteItemFromObjectCaseSensitive(ja, drop[k]);
            cJSON_DeleteItemFromObjectCaseSensitive(jb, drop[k]);
        }
        char *ta = cJSON_PrintUnformatted(ja), *tb = cJSON_PrintUnformatted(jb);
        CHECK(ta && tb && strcmp(ta, tb) == 0, "%s: summaries differ:\n%.400s\n%.400s", what, ta, tb);
        free(ta);
        free(tb);
    }
    cJSON_Delete(ja);
    cJSON_Delete(jb);
}

static int same_files(const char *a, const char *b, const char *what)
{
    int n = same_folder(a, b, what);
    same_summary(a, b, what);
    return n;
}

static const char *summary_status(const char *dir, char *signal_name, size_t size)
{
    static char status[64];
    status[0] = '\0';
    if (signal_name) signal_name[0] = '\0';
    char path[700];
    snprintf(path, sizeof path, "%s/summary.json", dir);
    size_t len;
    char *text = test_slurp(path, &len);
    cJSON *j = text ? cJSON_Parse(text) : NULL;
    free(text);
    const cJSON *s = j ? cJSON_GetObjectItemCaseSensitive(j, "status") : NULL;
    const cJSON *g = j ? cJSON_GetObjectItemCaseSensitive(j, "signal") : NULL;
    if (cJSON_IsString(s)) snprintf(status, sizeof status, "%s", s->valuestring);
    if (signal_name && cJSON_IsString(g)) snprintf(signal_name, size, "%s", g->valuestring);
    cJSON_Delete(j);
    return status;
}

int main(void)
{
    const char *tmp = test_tmpdir();
    char cache[600], path[700], ref[600], dir[600], log[700];
    snprintf(cache, sizeof cache, "%s/cache", tmp);
    setenv("SEM_CACHE_DIR", cache, 1);
    setenv("SOURCE_DATE_EPOCH", "1700000000", 1);
    write_scene(tmp);

    /* the reference: an uninterrupted run on 2 threads */
    setenv("OMP_NUM_THREADS", "2", 1);
    snprintf(ref, sizeof ref, "%s/ref", tmp);
    snprintf(log, sizeof log, "%s/ref", tmp);
    const char *args_ref[] = {"run", g_scene, "--out", ref, "--quiet", NULL};
    int rc = run_sem(args_ref, log);
    CHECK(rc == 0, "reference run exit %d", rc);
    snprintf(path, sizeof path, "%s/frame_0040.igs", ref);
    CHECK(exists(path), "40 frames written");

    /* the same run again, and on one thread */
    for (int threads = 2; threads >= 1; --threads) {
        char t[8];
        snprintf(t, sizeof t, "%d", threads);
        setenv("OMP_NUM_THREADS", t, 1);
        snprintf(dir, sizeof dir, "%s/again%d", tmp, threads);
        const char *args[] = {"run", g_scene, "--out", dir, "--quiet", NULL};
        rc = run_sem(args, log);
        CHECK(rc == 0, "run on %d threads exit %d", threads, rc);
        char what[64];
        snprintf(what, sizeof what, "run again on %d thread(s)", threads);
        int n = same_files(ref, dir, what);
        /* per frame IGES, OBJ free-form, mesh and state; animation.usda, animation.glb,
         * preprocess_0.semdisc, state/run.json */
        CHECK(n == 41 * 4 + 4, "%s: %d files compared", what, n);
    }
    setenv("OMP_NUM_THREADS", "2", 1);

    /* Ctrl-C after frame 5: status 130, summary and USD written, then resumed */
    snprintf(dir, sizeof dir, "%s/sigint", tmp);
    snprintf(log, sizeof log, "%s/sigint", tmp);
    rc = run_and_stop(dir, 5, SIGINT, log);
    CHECK(rc == 130, "SIGINT exit %d", rc);
    char sig[32];
    CHECK(strcmp(summary_status(dir, sig, sizeof sig), "interrupted") == 0 && !strcmp(sig, "SIGINT"),
          "summary status after SIGINT: %s %s", summary_status(dir, NULL, 0), sig);
    snprintf(path, sizeof path, "%s/animation.usda", dir);
    CHECK(exists(path), "animation.usda after SIGINT");
    size_t len;
    snprintf(path, sizeof path, "%s.err", log);
    char *err = test_slurp(path, &len);
    CHECK(err && strstr(err, "interrupted by SIGINT after frame") && strstr(err, "--resume"),
          "message: %s", err ? err : "");
    free(err);
    snprintf(path, sizeof path, "%s/frame_0040.igs", dir);
    CHECK(!exists(path), "the interrupted run stopped early");
    const char *args_resume[] = {"run", "--resume", dir, "--quiet", NULL};
    rc = run_sem(args_resume, log);
    CHECK(rc == 0, "resume after SIGINT exit %d", rc);
    same_files(ref, dir, "resumed after SIGINT");

    /* SIGTERM: status 143 */
    snprintf(dir, sizeof dir, "%s/sigterm", tmp);
    rc = run_and_stop(dir, 3, SIGTERM, log);
    CHECK(rc == 143, "SIGTERM exit %d", rc);
    CHECK(strcmp(summary_status(dir, sig, sizeof sig), "interrupted") == 0 && !strcmp(sig, "SIGTERM"),
          "summary status after SIGTERM");

    /* kill -9 after frame 7: no summary of its own; resume gives the reference */
    snprintf(dir, sizeof dir, "%s/sigkill", tmp);
    rc = run_and_stop(dir, 7, SIGKILL, log);
    CHECK(rc == 128 + 9, "SIGKILL exit %d", rc);
    rc = run_sem((const char *[]){"run", "--resume", dir, "--quiet", NULL}, log);
    CHECK(rc == 0, "resume after kill -9 exit %d", rc);
    same_files(ref, dir, "resumed after kill -9");
    /* resuming a complete run writes the same again */
    rc = run_sem((const char *[]){"run", "--resume", dir, "--quiet", NULL}, log);
    CHECK(rc == 0, "resume of a complete run exit %d", rc);
    same_files(ref, dir, "resumed twice");

    /* another run's folder: refused, then replaced with --overwrite (other files kept) */
    snprintf(path, sizeof path, "%s/notes.txt", ref);
    FILE *f = fopen(path, "w");
    if (f) {
        fputs("mine\n", f);
        fclose(f);
    }
    /* as a run with a second object would have left it (sem render reads these) */
    snprintf(path, sizeof path, "%s/preprocess_1.semdisc", ref);
    f = fopen(path, "w");
    if (f) fclose(f);
    rc = run_sem((const char *[]){"run", g_scene, "--out", ref, "--frames", "3", "--quiet", NULL}, log);
    snprintf(path, sizeof path, "%s.err", log);
    err = test_slurp(path, &len);
    CHECK(rc == 1 && err && strstr(err, "holds another run") && strstr(err, "--overwrite"),
          "run into a used folder: exit %d: %s", rc, err ? err : "");
    free(err);
    rc = run_sem((const char *[]){"run", g_scene, "--out", ref, "--frames", "3", "--quiet",
                                  "--overwrite", NULL},
                 log);
    CHECK(rc == 0, "--overwrite exit %d", rc);
    snprintf(path, sizeof path, "%s/frame_0003.igs", ref);
    CHECK(exists(path), "new frames written");
    snprintf(path, sizeof path, "%s/frame_0004.igs", ref);
    CHECK(!exists(path), "the old run's later frames removed");
    snprintf(path, sizeof path, "%s/state/frame_0004.state", ref);
    CHECK(!exists(path), "the old run's state removed");
    snprintf(path, sizeof path, "%s/preprocess_1.semdisc", ref);
    CHECK(!exists(path), "the old run's preprocessing file removed");
    snprintf(path, sizeof path, "%s/notes.txt", ref);
    CHECK(exists(path), "files of the user kept");

    /* resume errors: nothing to resume, options that do not go with --resume */
    snprintf(dir, sizeof dir, "%s/empty", tmp);
    mkdir(dir, 0755);
    rc = run_sem((const char *[]){"run", "--resume", dir, NULL}, log);
    snprintf(path, sizeof path, "%s.err", log);
    err = test_slurp(path, &len);
    CHECK(rc == 1 && err && strstr(err, "no run to resume"), "resume of an empty folder: %s",
          err ? err : "");
    free(err);
    rc = run_sem((const char *[]){"run", g_scene, "--resume", dir, NULL}, log);
    CHECK(rc == 2, "SCENE with --resume is a usage error (%d)", rc);

    /* frame names as wide as the largest frame number */
    CHECK(sem_run_frame_digits(0) == 4 && sem_run_frame_digits(9999) == 4 &&
              sem_run_frame_digits(10000) == 5 && sem_run_frame_digits(123456) == 6 &&
              sem_run_frame_digits(100000000) == 9,
          "frame digits");
    return test_finish("test_resume");
}
