/* bench.c: the counting allocator of the benchmarks. */
#include "bench.h"

#include <stdlib.h>

static void *counting_realloc(void *user, void *ptr, size_t size)
{
    bench_counting *c = user;
    size_t old = ptr ? ((size_t *)ptr)[-2] : 0;
    if (size == 0) {
        if (ptr) {
            c->now -= old;
            free((size_t *)ptr - 2);
        }
        return NULL;
    }
    size_t *p = realloc(ptr ? (size_t *)ptr - 2 : NULL, size + 2 * sizeof(size_t));
    if (!p)
        return NULL;
    p[0] = size;
    c->now += size - old;
    if (c->now > c->peak)
        c->peak = c->now;
    return p + 2;
}

tsr_allocator bench_counting_allocator(bench_counting *c)
{
    return (tsr_allocator){counting_realloc, c};
}

int bench_cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}
