/* fuzz_common.c: temporary files for the fuzz entry points whose parsers
 * read paths (tools/pslg_io.c, terrain/). One folder per process, so
 * parallel runs (ctest -j, libFuzzer -jobs) never share a file. */
#define _POSIX_C_SOURCE 200809L
#include "fuzz.h"

#include <dirent.h>
#include <stdbool.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char temp_dir[4096];
static char temp_path[4096 + 256];

static void remove_temp_dir(void)
{
    DIR *d = opendir(temp_dir);
    if (d) {
        struct dirent *e;
        while ((e = readdir(d)) != NULL) {
            if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, ".."))
                continue;
            char p[sizeof temp_dir + 260];
            if (snprintf(p, sizeof p, "%s/%s", temp_dir, e->d_name) < (int)sizeof p)
                remove(p);
        }
        closedir(d);
    }
    rmdir(temp_dir);
}

void fuzz_fail(const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    fputs("fuzz: ", stderr);
    vfprintf(stderr, fmt, ap);
    fputc('\n', stderr);
    va_end(ap);
    if (temp_dir[0]) /* abort() skips atexit */
        remove_temp_dir();
    abort();
}

const char *fuzz_temp_path(const char *name)
{
    if (!temp_dir[0]) {
        const char *t = getenv("TMPDIR");
        if (snprintf(temp_dir, sizeof temp_dir, "%s/tsr-fuzz-XXXXXX", t && *t ? t : "/tmp") >= (int)sizeof temp_dir ||
            !mkdtemp(temp_dir))
            fuzz_fail("cannot make a temporary folder %s", temp_dir);
        atexit(remove_temp_dir);
    }
    if (snprintf(temp_path, sizeof temp_path, "%s/%s", temp_dir, name) >= (int)sizeof temp_path)
        fuzz_fail("temporary path too long for %s", name);
    return temp_path;
}

const char *fuzz_write_temp(const char *name, const void *data, size_t size)
{
    const char *path = fuzz_temp_path(name);
    FILE *f = fopen(path, "wb");
    if (!f)
        fuzz_fail("cannot write %s", path);
    bool bad = size > 0 && fwrite(data, 1, size, f) != size;
    if (fclose(f) != 0 || bad)
        fuzz_fail("cannot write %s", path);
    return path;
}

static void *limited_realloc(void *user, void *ptr, size_t size)
{
    if (size == 0) {
        free(ptr);
        return NULL;
    }
    if (size > *(const size_t *)user)
        fuzz_fail("an allocation of %zu bytes, above the %zu this input allows", size, *(const size_t *)user);
    return realloc(ptr, size);
}

void fuzz_limited_allocator(tsr_allocator *a, const size_t *limit)
{
    a->realloc = limited_realloc;
    a->user = (void *)limit;
}

void fuzz_remove_temp(const char *name)
{
    remove(fuzz_temp_path(name));
}

/* Three input points not on one line, by the exact predicate. */
static bool has_area(const tsr_pslg *in)
{
    uint32_t a = 0, b = UINT32_MAX;
    for (uint32_t i = 1; i < in->nv && b == UINT32_MAX; i++)
        if (in->xy[2 * i] != in->xy[0] || in->xy[2 * i + 1] != in->xy[1])
            b = i;
    for (uint32_t c = 0; b != UINT32_MAX && c < in->nv; c++)
        if (tsr_orient2d(in->xy + 2 * a, in->xy + 2 * (size_t)b, in->xy + 2 * (size_t)c) != 0)
            return true;
    return false;
}

void fuzz_check_triangulation(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *t,
                              const char *what)
{
    for (uint32_t i = 0; i < in->nv; i++) {
        uint32_t v = t->vertex_of_input[i];
        if (v >= t->nv || t->xy[2 * (size_t)v] != in->xy[2 * (size_t)i] ||
            t->xy[2 * (size_t)v + 1] != in->xy[2 * (size_t)i + 1])
            fuzz_fail("%s: input point %u maps to output vertex %u, not at its coordinates", what, i, v);
    }
    bool area = has_area(in);
    if (t->nt == 0 && !area)
        return;
    if (t->nt == 0 && opt->region == TSR_REGION_HULL && in->nholes == 0)
        fuzz_fail("%s: no triangle, but the input points span an area", what);
    tsr_tri_options judged = *opt;
    /* stopped at max_steiner, or stuck: what refinement promises is void.
     * Where the only shortfall reported is triangles below the resolution
     * of doubles, the promises stand and the checker excuses just those. */
    if (t->steiner_limited || t->unrefined) {
        judged.min_angle = judged.max_area = 0;
        judged.conforming = false;
        judged.nregions = 0;
    }
    tsr_tri_check c;
    if (tsr_triangulation_check(in, &judged, t, &c) == TSR_OK && !c.ok)
        fuzz_fail("%s: the checker rejects the result (method %s, region %d%s, min_angle %g, max_area %g, "
                  "max_depth %u; %u points, %u segments, %u holes; out: %u triangles, %u Steiner points%s): %s",
                  what, opt->method == TSR_TRI_QUADTREE ? "quadtree" : "delaunay", (int)opt->region,
                  opt->conforming ? ", conforming" : "", judged.min_angle, judged.max_area, opt->max_depth, in->nv,
                  in->nseg, in->nholes, t->nt, t->steiner, t->quality_limited ? ", quality_limited" : "",
                  c.first_problem);
}
