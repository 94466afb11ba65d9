/* fuzz.h: the fuzz entry points and their shared helpers.
 *
 * Each fuzz_<target>() takes arbitrary bytes, drives one parser or the
 * triangulator with them, checks what came back against the contract, and
 * abort()s on a violation, so libFuzzer (and the corpus replay test, which
 * calls the same functions from a plain main()) reports it. They return 0.
 * Built as libFuzzer targets with -DTSR_LIBFUZZER (tests/fuzz/CMakeLists.txt),
 * and without it into fuzz_corpus_replay (tests/CMakeLists.txt). */
#ifndef TSR_FUZZ_H
#define TSR_FUZZ_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

int fuzz_pslg_io(const uint8_t *data, size_t size);
int fuzz_triangulate(const uint8_t *data, size_t size);
int fuzz_heightfield(const uint8_t *data, size_t size);
int fuzz_patch_io(const uint8_t *data, size_t size);

/* A path named name inside a private temporary folder (made on first use
 * under $TMPDIR or /tmp, removed at exit with what is in it). The returned
 * string lives until the next call. */
const char *fuzz_temp_path(const char *name);
/* Writes data (size bytes) to fuzz_temp_path(name) and returns that path;
 * abort()s when the file cannot be written (a harness problem). */
const char *fuzz_write_temp(const char *name, const void *data, size_t size);
/* Removes fuzz_temp_path(name) if it exists. */
void fuzz_remove_temp(const char *name);

/* An allocator (tessellate.h's tsr_allocator) that abort()s on any single
 * request above *limit bytes: a parser must weigh sizes against its input
 * before allocating, so a few bytes never cost gigabytes. limit must
 * outlive the allocator's use. */
void fuzz_limited_allocator(tsr_allocator *a, const size_t *limit);

/* Judges t, what tsr_triangulate made of in with opt: every input point
 * maps to an output vertex at its coordinates; no triangle only where the
 * input has none (fewer than 3 distinct points, or all collinear, by the
 * exact orient2d), which the checker is then not asked about (it would
 * look for the segments among the edges of no triangle); otherwise
 * tsr_triangulation_check must pass, with min_angle, max_area and
 * conforming not required when refinement stopped at max_steiner
 * (steiner_limited) or got stuck (unrefined); triangles below the
 * resolution of doubles are excused by the checker only as far as the
 * result reports them (below_resolution).
 * abort()s naming what on a failure. */
void fuzz_check_triangulation(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *t,
                              const char *what);

/* Prints "fuzz: <message>" to stderr and abort()s. */
void fuzz_fail(const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 1, 2), noreturn))
#endif
    ;

#ifdef __cplusplus
}
#endif
#endif
