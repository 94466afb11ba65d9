/* bench.h: what the benchmarks share: an allocator that counts current and
 * peak bytes, and the entry points of the benchmarks kept in their own
 * files. */
#ifndef TSR_BENCH_H
#define TSR_BENCH_H

#include "cli.h"

typedef struct bench_counting {
    size_t now, peak;
} bench_counting;

/* An allocator over malloc that adds every live byte to c->now and keeps
 * the maximum in c->peak (c must outlive every block). */
tsr_allocator bench_counting_allocator(bench_counting *c);

/* qsort's comparison of doubles, ascending. */
int bench_cmp_double(const void *a, const void *b);

/* `tessera bench mesh` (bench_mesh.c); argv[1] is "mesh". */
int cli_bench_mesh(int argc, char **argv);

/* `tessera bench fly` (bench_fly.c); argv[1] is "fly". */
int cli_bench_fly(int argc, char **argv);

/* `tessera bench patch` (bench_patch.c); argv[1] is "patch". */
int cli_bench_patch(int argc, char **argv);

#endif
