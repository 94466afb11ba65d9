/* check.h: the test harness. A test file defines TEST(name) functions and
 * ends with TEST_MAIN(list of names). CHECK failures print file:line and
 * the expression, and the test continues; the program exits 1 when any
 * check failed and 77 (CTest's skip) when a test asked to skip and none
 * failed. */
#ifndef TSR_TEST_CHECK_H
#define TSR_TEST_CHECK_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static int check_failures;
static int check_skipped;
static const char *check_current;

#define CHECK(cond)                                                                                \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            check_failures++;                                                                      \
            fprintf(stderr, "%s:%d: %s: CHECK failed: %s\n", __FILE__, __LINE__, check_current, #cond); \
        }                                                                                          \
    } while (0)

#define CHECK_MSG(cond, ...)                                                                       \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            check_failures++;                                                                      \
            fprintf(stderr, "%s:%d: %s: CHECK failed: %s: ", __FILE__, __LINE__, check_current, #cond); \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
        }                                                                                          \
    } while (0)

#define CHECK_NEAR(a, b, tol) CHECK_MSG(fabs((double)(a) - (double)(b)) <= (tol), "%.17g vs %.17g", (double)(a), (double)(b))

#define SKIP(...)                                                                                  \
    do {                                                                                           \
        fprintf(stderr, "%s: skipped: ", check_current);                                          \
        fprintf(stderr, __VA_ARGS__);                                                              \
        fputc('\n', stderr);                                                                       \
        check_skipped++;                                                                           \
        return;                                                                                    \
    } while (0)

#define TEST(name) static void test_##name(void)

typedef struct check_entry {
    const char *name;
    void (*fn)(void);
} check_entry;

#define T(name) {#name, test_##name}

/* With no arguments, runs every test except those whose name begins with
 * "data_" (they read ../shared/data and are registered as their own CTest
 * entry, so a missing data folder skips them alone); with arguments, runs
 * the tests named. */
#define TEST_MAIN(...)                                                                             \
    int main(int argc, char **argv)                                                                \
    {                                                                                              \
        static const check_entry tests[] = {__VA_ARGS__};                                          \
        int ran = 0;                                                                               \
        for (size_t i = 0; i < sizeof tests / sizeof tests[0]; i++) {                              \
            bool named = false;                                                                    \
            for (int a = 1; a < argc; a++)                                                         \
                named = named || !strcmp(argv[a], tests[i].name);                                  \
            if (argc > 1 ? !named : !strncmp(tests[i].name, "data_", 5))                           \
                continue;                                                                          \
            check_current = tests[i].name;                                                         \
            int before = check_failures, skipped = check_skipped;                                  \
            tests[i].fn();                                                                         \
            ran++;                                                                                 \
            fprintf(stderr, "%s %s\n",                                                            \
                    check_failures > before ? "FAIL" : check_skipped > skipped ? "skip" : "ok  ",  \
                    tests[i].name);                                                                \
        }                                                                                          \
        if (ran == 0 || (argc > 1 && ran != argc - 1)) {                                           \
            fprintf(stderr, "unknown test name among the arguments\n");                           \
            return 1;                                                                              \
        }                                                                                          \
        if (check_failures)                                                                        \
            return 1;                                                                              \
        return check_skipped ? 77 : 0;                                                             \
    }

/* The folder of shared test data: $TESSERA_DATA, else ../shared/data
 * relative to the source tree (TSR_SOURCE_DIR is set by CMake). NULL when
 * it does not exist. */
#include <sys/stat.h>
static inline const char *check_data_dir(void)
{
    static char buf[4096];
    const char *env = getenv("TESSERA_DATA");
    if (env && *env)
        snprintf(buf, sizeof buf, "%s", env);
    else
        snprintf(buf, sizeof buf, "%s/../shared/data", TSR_SOURCE_DIR);
    struct stat st;
    return stat(buf, &st) == 0 && S_ISDIR(st.st_mode) ? buf : NULL;
}

/* An allocator for tests (tsr_allocator {check_realloc, &a}): counts the
 * blocks alive and the requests (frees not counted), keeps the largest
 * request, and fails the fail_at-th request (1-based; 0: none) and, when
 * sticky, every later request of that size too (a retry of the same
 * growth fails again), and the fail_also-th request (0: none). */
typedef struct check_alloc {
    long live, calls, fail_at, fail_also;
    bool sticky;
    size_t fail_size; /* the failed request's size, when sticky */
    size_t largest;
} check_alloc;

static inline void *check_realloc(void *user, void *ptr, size_t size)
{
    check_alloc *c = user;
    if (size == 0) {
        if (ptr)
            c->live--;
        free(ptr);
        return NULL;
    }
    if (++c->calls == c->fail_at || (c->sticky && c->fail_size && size == c->fail_size)) {
        c->fail_size = c->sticky ? size : 0;
        return NULL;
    }
    if (c->calls == c->fail_also)
        return NULL;
    if (size > c->largest)
        c->largest = size;
    void *p = realloc(ptr, size);
    if (p && !ptr)
        c->live++;
    return p;
}

/* A fresh temporary folder for the test's files (under $TMPDIR or /tmp). */
static inline const char *check_temp_dir(void)
{
    static char buf[256];
    const char *t = getenv("TMPDIR");
    snprintf(buf, sizeof buf, "%s/tsr-test-XXXXXX", t && *t ? t : "/tmp");
    extern char *mkdtemp(char *);
    return mkdtemp(buf);
}

#endif
