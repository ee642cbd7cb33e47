#define _POSIX_C_SOURCE 200809L
#include "test_util.h"

#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cjson/cJSON.h>

int test_failures = 0;
int test_checks = 0;
static int test_skips = 0;

int test_finish(const char *name)
{
    printf("%s: %d passed, %d failed\n", name, test_checks - test_failures, test_failures);
    if (test_failures) return 1;
    if (test_skips) {
        /* CTest reports exit status 77 as "skipped" (SKIP_RETURN_CODE), not "passed" */
        printf("%s: skipped in part: %d shared model lookups failed (set SEM_SHARED_MODELS to "
               "the folder of the paper's models)\n",
               name, test_skips);
        return TEST_SKIPPED;
    }
    return 0;
}

const char *test_shared_model(const char *relative)
{
    static char path[4096];
    const char *root = getenv("SEM_SHARED_MODELS");
    if (!root) root = SEM_SHARED_MODELS;
    snprintf(path, sizeof path, "%s/%s", root, relative);
    struct stat st;
    if (stat(path, &st) != 0) {
        test_skips++;
        return NULL;
    }
    return path;
}

cJSON *test_read_summary(const char *dir)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/summary.json", dir);
    char *text = test_slurp(path, NULL);
    cJSON *s = text ? cJSON_Parse(text) : NULL;
    free(text);
    return s;
}

const char *test_tmpdir(void)
{
    static char dir[256];
    if (dir[0]) return dir;
    snprintf(dir, sizeof dir, "/tmp/sem_test_XXXXXX");
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        exit(2);
    }
    return dir;
}

static void slurp(const char *path, char *buf, size_t size)
{
    if (!buf || size == 0) return;
    buf[0] = '\0';
    FILE *f = fopen(path, "rb");
    if (!f) return;
    size_t n = fread(buf, 1, size - 1, f);
    buf[n] = '\0';
    fclose(f);
}

int test_run_cli(const char *args, char *out, size_t out_size, char *errbuf, size_t err_size)
{
    const char *dir = test_tmpdir();
    char cmd[8192], out_path[512], err_path[512];
    snprintf(out_path, sizeof out_path, "%s/cli_stdout.txt", dir);
    snprintf(err_path, sizeof err_path, "%s/cli_stderr.txt", dir);
    snprintf(cmd, sizeof cmd, "%s %s >%s 2>%s </dev/null", SEM_BINARY, args, out_path, err_path);
    int rc = system(cmd);
    slurp(out_path, out, out_size);
    slurp(err_path, errbuf, err_size);
    if (rc == -1) return -1;
    return WIFEXITED(rc) ? WEXITSTATUS(rc) : 128;
}

void test_setup_free(test_setup *s)
{
    sem_world_destroy(s->world);
    sem_discretization_destroy(s->disc);
    sem_model_destroy(s->model);
    memset(s, 0, sizeof *s);
}

char *test_slurp(const char *path, size_t *size)
{
    FILE *f = fopen(path, "rb");
    if (!f) return NULL;
    fseek(f, 0, SEEK_END);
    long n = ftell(f);
    fseek(f, 0, SEEK_SET);
    char *b = malloc((size_t)(n > 0 ? n : 0) + 1);
    size_t got = b ? fread(b, 1, (size_t)(n > 0 ? n : 0), f) : 0;
    if (b) b[got] = '\0';
    fclose(f);
    if (size) *size = got;
    return b;
}

double test_uniform(unsigned long long *state)
{
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    return (double)(*state >> 11) / 9007199254740992.0;
}
