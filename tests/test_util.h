/* test_util.h - a small test harness: each CHECK counts, failures print file:line. */
#ifndef SEM_TEST_UTIL_H
#define SEM_TEST_UTIL_H

#include <math.h>
#include <stdio.h>

#include "sem/model.h"
#include "sem/preprocess.h"
#include "sem/simulation.h"

extern int test_failures;
extern int test_checks;

#define CHECK(cond, ...)                                                                  \
    do {                                                                                  \
        test_checks++;                                                                    \
        if (!(cond)) {                                                                    \
            test_failures++;                                                              \
            fprintf(stderr, "%s:%d: CHECK(%s) failed: ", __FILE__, __LINE__, #cond);       \
            fprintf(stderr, __VA_ARGS__);                                                 \
            fprintf(stderr, "\n");                                                        \
        }                                                                                 \
    } while (0)

/* |a - b| <= tol */
#define CHECK_NEAR(a, b, tol)                                                             \
    do {                                                                                  \
        double ca_ = (a), cb_ = (b), ct_ = (tol);                                         \
        CHECK(fabs(ca_ - cb_) <= ct_, "%s = %.17g, %s = %.17g, diff %.3g > %.3g", #a, ca_, \
              #b, cb_, fabs(ca_ - cb_), ct_);                                             \
    } while (0)

/* |a - b| <= tol * max(|b|, tiny) */
#define CHECK_REL(a, b, tol)                                                              \
    do {                                                                                  \
        double ra_ = (a), rb_ = (b), rt_ = (tol);                                         \
        double rs_ = fabs(rb_) > 1e-300 ? fabs(rb_) : 1e-300;                              \
        CHECK(fabs(ra_ - rb_) <= rt_ * rs_, "%s = %.17g, %s = %.17g, rel diff %.3g > %.3g", \
              #a, ra_, #b, rb_, fabs(ra_ - rb_) / rs_, rt_);                              \
    } while (0)

/* Prints "N passed, N failed" and returns the process exit status: 1 on a failure, else
 * TEST_SKIPPED when a shared model was missing (CTest shows the test as skipped), else 0. */
#define TEST_SKIPPED 77
int test_finish(const char *name);
/* xorshift64: reproducible uniform numbers in [0, 1) from *state (non-zero), the same
 * sequence on every machine */
double test_uniform(unsigned long long *state);
/* Path of a shared model (../shared/models/..., or $SEM_SHARED_MODELS/...), or NULL when it
 * is absent; a NULL answer marks the test as skipped (test_finish). */
const char *test_shared_model(const char *relative);
/* The whole file at path, NUL-terminated (caller frees), its length in *size (may be NULL);
 * NULL when it cannot be read. */
char *test_slurp(const char *path, size_t *size);
/* The summary.json of a `sem run` folder, parsed (cJSON; the caller deletes it), or NULL. */
struct cJSON *test_read_summary(const char *dir);
/* A fresh temporary directory for this test (removed by the OS / CI clean clone). */
const char *test_tmpdir(void);
/* Runs the sem CLI with arguments; captures stdout/stderr into the given buffers
 * (may be NULL). Returns the exit status. */
int test_run_cli(const char *args, char *out, size_t out_size, char *errbuf, size_t err_size);

/* A model, its discretization and a world, for tests that build all three;
 * test_setup_free destroys what is set and zeroes the struct. */
typedef struct test_setup {
    sem_model *model;
    sem_discretization *disc;
    sem_world *world;
} test_setup;
void test_setup_free(test_setup *s);

#endif
