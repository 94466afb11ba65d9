/* terrain_internal.h: shared between terrain/ files; not public. */
#ifndef TSR_TERRAIN_INTERNAL_H
#define TSR_TERRAIN_INTERNAL_H

#include "terrain/terrain.h"

#ifdef __cplusplus
extern "C" {
#endif

/* Hot scans are compiled twice, for AVX2 and for the baseline, and the
 * running processor's version is called after a test of the CPU's
 * feature bits per call (__builtin_cpu_supports), not through an ifunc
 * (target_clones): an ifunc's resolver runs before a sanitizer's runtime
 * is up, and ThreadSanitizer crashes there. The body is an always-inline
 * function, so each caller's copy is built for its own target. */
#if defined(__GNUC__) && !defined(__clang__) && defined(__x86_64__)
#define TSR_AVX2_DISPATCH 1
#define TSR_ALWAYS_INLINE inline __attribute__((always_inline))
#else
#define TSR_ALWAYS_INLINE inline
#endif

/* Vectors of the scans (GCC's and clang's vector extensions): each
 * operation lane by lane, as the scalar expression would be. */
#if defined(__GNUC__) || defined(__clang__)
#define TSR_VECTORS 1
typedef double tsr_v4d __attribute__((vector_size(32)));
typedef int64_t tsr_v4l __attribute__((vector_size(32)));
typedef float tsr_v4f __attribute__((vector_size(16)));
typedef float tsr_v8f __attribute__((vector_size(32)));
typedef int32_t tsr_v8i __attribute__((vector_size(32)));
#endif

struct tsr_heightfield {
    uint32_t width, height;
    double dx, dy, dz;
    float *data;
    char source_format[64];
    tsr_allocator alloc;
    bool has_georef;
    tsr_georef georef;
};

/* What the image bridge found in a file. */
typedef struct tsr_image_info {
    uint32_t width, height, channels;
    int alpha_channel; /* the channel the file marks as alpha (OpenImageIO's spec), or -1 */
    char format[16]; /* OpenImageIO's format name: "png", "tiff", "openexr"... */
    char type[16];   /* sample type: "uint8", "uint16", "float"... */
    bool has_scale;  /* a Tessera scale/offset found in the metadata */
    double scale, offset;
    bool has_spacing; /* a Tessera sample spacing found in the metadata */
    double spacing[2];
} tsr_image_info;

/* Reads every channel of the first subimage as float values in the file's
 * own units (uint8 0..255, uint16 0..65535, int16 -32768..32767, floats as
 * they are) into *pixels (width*height*channels, from alloc). Refuses
 * images over max_samples pixels or with more than 4 channels before
 * allocating anything. Implemented in C++ over OpenImageIO (image_io.cpp),
 * in the I/O module that io_loader.c opens on first use (io_module.h):
 * when the module cannot be loaded, these fail with TSR_ERR_UNSUPPORTED and
 * a message naming where it was looked for. */
tsr_status tsr_image_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                          tsr_image_info *info, tsr_error *err);

/* Writes one channel to `tmp` (whose extension picks the format); messages
 * name `path`. float32 unless as_u16, in which case the values are rounded
 * and clamped to 0..65535 and scale/offset are stored in the metadata.
 * With dx, dy > 0, the sample spacing is stored in the metadata too (the
 * Tessera:Spacing attribute, and the image description, which TIFF keeps);
 * tsr_image_read gives it back. */
tsr_status tsr_image_write(const char *path, const char *tmp, uint32_t width, uint32_t height,
                           const float *values, bool as_u16, double scale, double offset, double dx, double dy,
                           tsr_error *err);


/* GIS rasters through GDAL (gdal_io.c, in the I/O module like
 * tsr_image_read). Only the drivers named in terrain.h are registered,
 * once, and GDAL writes no side files (.aux.xml) and prints nothing: its
 * messages become err's.
 *
 * The georeferencing GDAL finds in path for a w x h raster; false, with *g
 * zeroed (z_scale 1), where it finds none (or cannot open the file). */
bool tsr_gdal_georef(const char *path, uint32_t w, uint32_t h, tsr_georef *g);

/* Reads band 1 of a raster OpenImageIO could not open: its stored values
 * as float32 (no-data and scale not applied: tsr_georef_apply) into
 * *pixels (w * h from alloc), the format ("srtmhgt int16") into format,
 * the georeferencing into *g. TSR_ERR_FORMAT when no registered driver
 * recognises the file; sizes over max_samples or the side limits are
 * refused before allocating. */
tsr_status tsr_gdal_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                         uint32_t *w, uint32_t *h, char format[64], tsr_georef *g, tsr_error *err);

/* Stored values to heights: the no-data samples to NaN (those equal to
 * *nodata when given, else to the file's own value: both compared with
 * the stored values, before the scale, as GDAL does) and the others
 * scaled by z_scale, z_offset. */
void tsr_georef_apply(const tsr_georef *g, const double *nodata, float *px, size_t n);

/* The unit normal at sample (c, r) from central differences of the
 * heights (one-sided at borders and next to no-data), in world units. */
void tsr_heightfield_normal_at(const tsr_heightfield *hf, uint32_t c, uint32_t r, float n[3]);

/* The maximum mipmap of a terrain, as pick.c reads it (lod.c owns it). */
typedef struct pick_view {
    const tsr_heightfield *hf;
    uint32_t mip_levels; /* levels 1..mip_levels; level k: blocks of 2^k cells */
    const uint32_t *mw, *mh;
    float *const *mip_min, *const *mip_max;
} pick_view;

bool tsr_terrain_pick_view(const tsr_terrain *t, pick_view *v);

/* The quadtree method's default mesh (rqt.c): a restricted quadtree over
 * the cells (a node of level l covers 2^(levels-l) cells a side, clipped
 * at the border; edge neighbours differ by at most one level), each leaf
 * drawn as two triangles on the diagonal it chooses or four from its
 * centre, plus the midpoint of each side whose neighbour is finer or
 * where either side asked for one (2 to 8 triangles; the mesh is
 * conforming). A leaf is kept only when every valid sample of its closed
 * square lies within tol (file units, vertically) of its triangles,
 * whichever sides get midpoints: the error is exact, not an estimate.
 * Cells with a no-data corner are refined to single cells, which are
 * holes (as in the delaunay method's domain; grid.c alone draws the
 * triangle of three valid corners). full_border: the
 * outer border at full resolution (window seams). With a budget
 * (max_tri, max_vert not 0), the smallest tolerance whose mesh fits is
 * found by bisection up to the height range `range` (file units) and
 * rep->budget_reached set. rep->target_error gets the tolerance used, in
 * world units (h dz). The nodes are tested on up to `threads` threads (0:
 * tsr_cpu_count()); the mesh is the same whatever the count. */
tsr_status tsr__rqt_mesh(const tsr_heightfield *hf, double tol, double range, bool full_border, uint32_t max_tri,
                         uint32_t max_vert, uint32_t threads, tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err);

/* For tests: half_ok of rqt.c on hf's samples at tolerance tol (file
 * units): triangle v (three lattice points (i, j), counter-clockwise),
 * with p (NULL: none) a lattice point inside side v0 v1 and m (NULL:
 * none) inside side v1 v2. Returns the ways of drawing it within tol, a
 * set of bits: 1 the triangle, 2 split at p, 4 split at m, 8 split at
 * both (into (v0, p, v2), (p, v1, m), (p, m, v2)); bits 2 and 8 only with
 * p, 4 and 8 only with m; 0 where a sample is no-data. */
unsigned tsr__rqt_half_variants(const tsr_heightfield *hf, double tol, const int64_t v[3][2], const int64_t *p,
                                const int64_t *m);
/* The same half's probe (a lattice of its samples, for halves of 16 cells
 * a side or more; the full scan below that): a set of bits holding every
 * one tsr__rqt_half_variants gives. */
unsigned tsr__rqt_half_probe(const tsr_heightfield *hf, double tol, const int64_t v[3][2], const int64_t *p,
                             const int64_t *m);

/* The budget search of both quadtree methods: the smallest tolerance in
 * [lo, hi], bisected in log scale (40 steps), at which the cut has at
 * most `budget` triangles. count(user, tol, &n) selects the cut at tol
 * and gives its triangles (false: out of memory). On success *tol is that
 * tolerance and the cut is left selected at it; TSR_ERR_ARGUMENT (err
 * says the count) when even hi's cut is over the budget; TSR_ERR_NOMEM. */
tsr_status tsr__budget_tolerance(double lo, double hi, uint64_t budget,
                                 bool (*count)(void *user, double tol, uint64_t *n), void *user, double *tol,
                                 tsr_error *err);

/* Runs work(arg) on up to `threads` threads at once (0: one per online
 * processor), never more than `jobs`, the caller's thread among them, and
 * returns when all have returned: work takes its jobs from arg itself
 * (under a lock) until none is left. Where a thread cannot be started,
 * fewer run. */
void tsr__run_threads(void *(*work)(void *), void *arg, uint32_t threads, uint32_t jobs);
/* The threads that `threads` asks for (0: tsr_cpu_count()). */
uint32_t tsr__thread_count(uint32_t threads);

/* Greyscale Netpbm (P2, P5) read exactly (pnm.c). */
bool tsr_pnm_is_grey(const char *path);
tsr_status tsr_pnm_read(const char *path, const tsr_allocator *alloc, tsr_heightfield **out, tsr_error *err);

#ifdef __cplusplus
}
#endif
#endif
