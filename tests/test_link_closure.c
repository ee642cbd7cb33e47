/* test_link_closure.c - a program that only simulates links neither Embree nor GLPK.
 *
 * The static linker takes a member of libsem.a when it defines a symbol still undefined.
 * Starting from the members that define the world API (sem_world_*), this follows that
 * rule through `nm -A libsem.a` and checks that no member it reaches needs an Embree
 * (rtc*) or GLPK (glp_*) symbol: the simulator must not pull in the preprocessing
 * (preprocess.c drives the ray casting and the origins' min-cost flow). It failed when
 * the polynomial basis lived in preprocess.c (19 members, Embree and GLPK reached).
 * The same listing shows that no member calls an omp_set_* function: the library never
 * changes OpenMP's settings for the whole process (a thread count travels as an argument to
 * num_threads clauses, src/util/threads.h); it failed while preprocess.c called
 * omp_set_num_threads for its `threads` option. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test_util.h"

typedef struct symbol {
    char *name;
    int member;
} symbol;

static int compare_symbol(const void *a, const void *b)
{
    return strcmp(((const symbol *)a)->name, ((const symbol *)b)->name);
}

static char *dup_string(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d) memcpy(d, s, n);
    return d;
}

typedef struct list {
    symbol *v;
    size_t n, cap;
} list;

static int push(list *l, const char *name, int member)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 1024;
        symbol *v = realloc(l->v, cap * sizeof *v);
        if (!v) return 0;
        l->v = v;
        l->cap = cap;
    }
    l->v[l->n].name = dup_string(name);
    l->v[l->n].member = member;
    return l->v[l->n++].name != NULL;
}

static void list_free(list *l)
{
    for (size_t i = 0; i < l->n; ++i) free(l->v[i].name);
    free(l->v);
}

int main(void)
{
    /* libsem.a sits beside the sem binary in the build folder */
    char lib[4096], cmd[4200], line[1024];
    snprintf(lib, sizeof lib, "%s", SEM_BINARY);
    char *slash = strrchr(lib, '/');
    if (slash) snprintf(slash + 1, sizeof lib - (size_t)(slash + 1 - lib), "libsem.a");
    snprintf(cmd, sizeof cmd, "nm -A '%s' 2>/dev/null", lib);
    FILE *p = popen(cmd, "r");
    CHECK(p != NULL, "cannot run nm");
    if (!p) return test_finish("test_link_closure");
    char members[256][64];
    int n_members = 0;
    list defined = {0}, undefined = {0};
    int ok = 1;
    while (ok && fgets(line, sizeof line, p)) {
        /* "lib.a:member.o:0000000000000000 T name" or "lib.a:member.o:                 U name" */
        char *a = strstr(line, ".a:");
        if (!a) continue;
        char *member = a + 3, *colon = strchr(member, ':');
        if (!colon) continue;
        *colon = '\0';
        char type[8] = "", name[512] = "", addr[64] = "";
        char *rest = colon + 1;
        /* an undefined symbol has no address: the line goes on with blanks */
        int parsed = rest[0] == ' ' ? sscanf(rest, "%7s %511s", type, name) == 2
                                    : sscanf(rest, "%63s %7s %511s", addr, type, name) == 3;
        if (!parsed) continue;
        int m = n_members - 1;
        if (m < 0 || strcmp(members[m], member) != 0) {
            if (n_members == 256) {
                ok = 0;
                break;
            }
            snprintf(members[n_members], sizeof members[0], "%s", member);
            m = n_members++;
        }
        if (strcmp(type, "U") == 0)
            ok = push(&undefined, name, m);
        else if (strchr("TDBRCVWi", type[0]))
            ok = push(&defined, name, m);
    }
    int status = pclose(p);
    CHECK(ok && status == 0 && n_members > 0 && defined.n > 0, "nm -A %s failed (status %d)", lib, status);
    if (!ok || status != 0 || defined.n == 0) goto done;
    qsort(defined.v, defined.n, sizeof *defined.v, compare_symbol);

    int setters = 0;
    for (size_t i = 0; i < undefined.n; ++i)
        if (strncmp(undefined.v[i].name, "omp_set_", 8) == 0 && setters++ < 5)
            fprintf(stderr, "%s calls %s\n", members[undefined.v[i].member], undefined.v[i].name);
    CHECK(setters == 0, "%d members of libsem.a change OpenMP's process-wide settings", setters);

    /* the closure from the world API */
    int linked[256] = {0}, queue[256], head = 0, tail = 0;
    for (size_t i = 0; i < defined.n; ++i)
        if (strncmp(defined.v[i].name, "sem_world_", 10) == 0 && !linked[defined.v[i].member]) {
            linked[defined.v[i].member] = 1;
            queue[tail++] = defined.v[i].member;
        }
    CHECK(tail > 0, "no member defines the world API");
    int foreign = 0;
    while (head < tail) {
        int m = queue[head++];
        for (size_t i = 0; i < undefined.n; ++i) {
            if (undefined.v[i].member != m) continue;
            symbol key = {undefined.v[i].name, 0};
            symbol *d = bsearch(&key, defined.v, defined.n, sizeof key, compare_symbol);
            if (d) {
                if (!linked[d->member]) {
                    linked[d->member] = 1;
                    queue[tail++] = d->member;
                }
            } else if (strncmp(key.name, "rtc", 3) == 0 || strncmp(key.name, "glp_", 4) == 0) {
                if (foreign++ < 5) fprintf(stderr, "%s needs %s\n", members[m], key.name);
            }
        }
    }
    printf("the world API links %d of %d members:", tail, n_members);
    for (int k = 0; k < tail; ++k) printf(" %s", members[queue[k]]);
    printf("\n");
    CHECK(foreign == 0, "the simulator reaches %d Embree / GLPK symbols", foreign);
    int preprocess = 0;
    for (int k = 0; k < tail; ++k) preprocess |= strcmp(members[queue[k]], "preprocess.c.o") == 0;
    CHECK(!preprocess, "the simulator links preprocess.c.o");
done:
    list_free(&defined);
    list_free(&undefined);
    return test_finish("test_link_closure");
}
