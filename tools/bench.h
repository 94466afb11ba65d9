/* bench.h: what the benchmarks share: an allocator that counts current and
 * peak bytes, and the entry points of the benchmarks kept in their own
 * files. */
#ifndef TSR_BENCH_H
#define TSR_BENCH_H

#include "cli.h"

typedef struct bench_counting {
    size_t now, peak;
} bench_counting;

/* An allocator over the library's default one (tsr_realloc and
 * tsr_alloc_dense with no allocator: what the tools use, big blocks mapped
 * with their pages at once) that adds every live byte to c->now and keeps
 * the maximum in c->peak (c must outlive every block). */
tsr_allocator bench_counting_allocator(bench_counting *c);

/* The shared data folder: $TESSERA_DATA, else ../shared/data (relative
 * to the working folder). When it is not a folder, a note on stderr (from
 * cmd) says so and how to name it: the inputs in it are skipped. */
const char *bench_data_dir(const char *cmd);

/* qsort's comparison of doubles, ascending. */
int bench_cmp_double(const void *a, const void *b);

/* `tessera bench mesh` (bench_mesh.c); argv[1] is "mesh". */
int cli_bench_mesh(int argc, char **argv);

/* `tessera bench fly` (bench_fly.c); argv[1] is "fly". */
int cli_bench_fly(int argc, char **argv);

/* `tessera bench patch` (bench_patch.c); argv[1] is "patch". */
int cli_bench_patch(int argc, char **argv);

/* ---- Peer meshers (bench_peers.c) ----------------------------------------
 * `tessera bench mesh --peers` runs other people's heightmap meshers on the
 * same heightfield, on the same machine, and measures their meshes with
 * tsr_terrain_measure, as it measures ours: delatin (Garland-Heckbert
 * greedy insertion, the JavaScript port of hmm) and @mapbox/martini
 * (RTIN). They are npm packages that tools/install-deps.sh puts into
 * build/node_modules, run by node through tools/peers/mesh_peer.mjs (found
 * beside the binary, in ../peers/, or at $TSR_PEER_SCRIPT). */
typedef struct bench_peer bench_peer;

typedef struct bench_peer_run {
    uint32_t vertices, triangles;
    double seconds;    /* the peer's own timing of its mesher, best of R (0: not timed) */
    double live_bytes; /* what the peer's mesher still holds after the run (0: unknown) */
} bench_peer_run;

/* Starts node on the script with hf's heights (h dz; hf without no-data).
 * NULL when it cannot run, with why filled (node or the script missing,
 * no-data in hf, out of memory). */
bench_peer *bench_peer_start(const tsr_heightfield *hf, char *why, size_t why_size);
/* Has the peer mesh hf at error e ("delatin", or "martini" with repeat 0
 * reusing its last tile untimed), best of repeat, and fills mesh
 * (initialised, empty; counter-clockwise from +z, at the samples'
 * positions (c dx, r dy, h dz), as tsr_terrain_mesh makes them). false with
 * why filled when the peer refused or failed. */
bool bench_peer_mesh(bench_peer *p, const char *method, double e, uint32_t repeat, tsr_mesh *mesh,
                     bench_peer_run *run, char *why, size_t why_size);
/* Ends the peer process and removes its files; p may be NULL. */
void bench_peer_stop(bench_peer *p);

#endif
