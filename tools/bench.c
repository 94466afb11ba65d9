/* bench.c: the counting allocator of the benchmarks. */
#include "bench.h"

#include <pthread.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <sys/stat.h>
#include <unistd.h>

/* The mesher calls it from several threads (tsr_tin_options.threads). */
static pthread_mutex_t counting_lock = PTHREAD_MUTEX_INITIALIZER;

/* Each block carries its size in front, 32 bytes, which keeps the
 * default allocator's alignment. */
enum { PREFIX = 32 / sizeof(size_t) };

/* Block p (NULL: none was made) now holds size bytes where it held old:
 * its prefix and the counts updated, the user's pointer returned. */
static void *counted(bench_counting *c, size_t *p, size_t size, size_t old)
{
    if (!p)
        return NULL;
    p[0] = size;
    pthread_mutex_lock(&counting_lock);
    c->now += size - old;
    if (c->now > c->peak)
        c->peak = c->now;
    pthread_mutex_unlock(&counting_lock);
    return p + PREFIX;
}

static void *counting_realloc(void *user, void *ptr, size_t size)
{
    bench_counting *c = user;
    size_t old = ptr ? ((size_t *)ptr)[-PREFIX] : 0;
    if (size == 0) {
        if (ptr) {
            pthread_mutex_lock(&counting_lock);
            c->now -= old;
            pthread_mutex_unlock(&counting_lock);
            tsr_free(NULL, (size_t *)ptr - PREFIX);
        }
        return NULL;
    }
    if (size > SIZE_MAX - PREFIX * sizeof(size_t))
        return NULL;
    return counted(c, tsr_realloc(NULL, ptr ? (size_t *)ptr - PREFIX : NULL, size + PREFIX * sizeof(size_t)), size,
                   old);
}

static void *counting_alloc_dense(void *user, size_t size)
{
    if (size > SIZE_MAX - PREFIX * sizeof(size_t))
        return NULL;
    return counted(user, tsr_alloc_dense(NULL, size + PREFIX * sizeof(size_t)), size, 0);
}

tsr_allocator bench_counting_allocator(bench_counting *c)
{
    return (tsr_allocator){counting_realloc, c, counting_alloc_dense};
}

const char *bench_data_dir(const char *cmd)
{
    const char *data = getenv("TESSERA_DATA");
    bool given = data && *data;
    if (!given)
        data = "../shared/data";
    struct stat st;
    if (stat(data, &st) != 0 || !S_ISDIR(st.st_mode)) {
        char cwd[4096];
        bool relative = data[0] != '/' && getcwd(cwd, sizeof cwd);
        fprintf(stderr,
                "tessera %s: note: no data folder %s%s%s%s: its inputs are skipped (set TESSERA_DATA to the shared "
                "data folder)\n",
                cmd, data, given ? " (TESSERA_DATA)" : "", relative ? " from " : "", relative ? cwd : "");
    }
    return data;
}

int bench_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
