/* terrain.h: heightfields. Loading (through OpenImageIO, or raw files),
 * saving, statistics, a deterministic sample-terrain generator, and the
 * regular-grid mesh of a heightfield.
 *
 * Coordinate convention, kept everywhere in Tessera:
 *   sample (column c, row r), 0 <= c < width, 0 <= r < height, sits at
 *       x = c * dx,   y = r * dy,   z = h(c, r) * dz
 *   Row 0 is the first row of the image file (its top line). Samples are
 *   stored row-major: h(c, r) = data[r * width + c].
 *   A NaN height marks no-data: such samples are holes, never zeros.
 *
 * Heights are float32 in the file's own units: 8- and 16-bit integer images
 * give their integer values (0..255, 0..65535), not OpenImageIO's
 * normalised 0..1, unless the file carries a Tessera scale and offset (see
 * tsr_heightfield_save), which are then applied.
 */
#ifndef TSR_TERRAIN_H
#define TSR_TERRAIN_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tsr_heightfield tsr_heightfield;

/* Sizes Tessera accepts: each side at least 2 and at most 1,048,576
 * samples, and at most 2^31 samples in all (8 GiB of float32). */
#define TSR_HEIGHTFIELD_MIN_SIDE 2u
#define TSR_HEIGHTFIELD_MAX_SIDE (1u << 20)
#define TSR_HEIGHTFIELD_MAX_SAMPLES ((uint64_t)1 << 31)

typedef enum tsr_decode {
    TSR_DECODE_NONE = 0,    /* one channel, or several equal ones (grey as RGB) */
    TSR_DECODE_TERRAIN_RGB  /* h = (R*65536 + G*256 + B) * 0.1 - 10000 */
} tsr_decode;

typedef enum tsr_raw_type {
    TSR_RAW_NONE = 0, /* not raw: the format comes from the file's bytes */
    TSR_RAW_U16,      /* little-endian unsigned 16-bit */
    TSR_RAW_I16,      /* little-endian signed 16-bit */
    TSR_RAW_F32       /* little-endian IEEE float32 */
} tsr_raw_type;

/* Zero means default for every field. */
typedef struct tsr_load_options {
    tsr_decode decode;
    tsr_raw_type raw_type;  /* when set, the file is headerless samples ... */
    uint32_t raw_width;     /* ... of exactly raw_width * raw_height values */
    uint32_t raw_height;
    bool has_nodata; /* samples storing nodata become NaN (compared
                        before a scale and offset the file names) */
    double nodata;
    bool all_nodata_ok;     /* accept a file with no valid sample (the caller
                               handles a heightfield of no-data only) */
} tsr_load_options;

/* Parses "u16", "i16" or "f32" (also "uint16", "int16", "float32"). */
tsr_raw_type tsr_raw_type_parse(const char *s);

/* Loads a heightfield. Formats: PNG (8/16-bit grey, or RGB(A) with
 * decode), TIFF and GeoTIFF (8/16-bit integer, float32), OpenEXR, PGM, and
 * anything else OpenImageIO reads as one channel; raw samples when
 * opts->raw_type is set; and, through GDAL, the GIS rasters OpenImageIO
 * does not read (band 1, its scale and offset applied): SRTM .hgt, Esri
 * ASCII grids (.asc), ESRI .bil/.flt (EHdr), Erdas .img, USGS .dem, VTP
 * .bt and XYZ grids. A GeoTIFF's georeferencing and no-data value
 * (GDAL_NODATA) are read through GDAL too (tsr_heightfield_georef).
 * Rejects sizes outside the limits above, infinite heights, and files
 * with no valid (non-NaN) sample (unless opts->all_nodata_ok). No-data:
 * samples equal to opts->nodata when given, else to the file's own no-data
 * value, both compared with the stored values before a scale and offset
 * the file names (GDAL's, a tessera PNG's), as GDAL does; also
 * +-3.4028235e38 (FLT_MAX, what GIS tools write for no-data when the file
 * names none). Values are compared as float32 (the samples' type). On
 * success *out owns the samples; on failure *out is NULL and err names
 * path and problem. */
tsr_status tsr_heightfield_load(const char *path, const tsr_load_options *opts,
                                const tsr_allocator *alloc, tsr_heightfield **out, tsr_error *err);

/* ---- Georeferencing ---------------------------------------------------- */

typedef enum tsr_crs_kind {
    TSR_CRS_NONE = 0,   /* the file names no coordinate system */
    TSR_CRS_PROJECTED,  /* map coordinates in a linear unit (UTM, national grids, Web Mercator) */
    TSR_CRS_GEOGRAPHIC, /* longitude and latitude */
    TSR_CRS_OTHER       /* named, but neither (a local or geocentric system) */
} tsr_crs_kind;

/* Where a GIS file says its samples lie, as GDAL reads it (GeoTIFF tags,
 * the headers of the other GIS formats). */
typedef struct tsr_georef {
    bool rotated;       /* the file's grid is rotated or sheared: not followed (no transform) */
    bool has_transform; /* a north-up grid: the centre of sample (c, r) is at */
    double origin[2];   /*   (origin[0] + c pixel[0], origin[1] + r pixel[1]) */
    double pixel[2];    /*   in CRS units; pixel[1] < 0 when row 0 is north */
    tsr_crs_kind crs;
    char crs_name[96];  /* e.g. "WGS 84 / UTM zone 33N"; "" when none */
    char z_unit[24];    /* the heights' unit where the file names one ("metre", "ft"); "" */
    bool has_nodata;    /* the file's no-data value (compared with the stored samples) */
    double nodata;
    double z_scale, z_offset; /* height = stored * z_scale + z_offset (already applied); 1, 0 */
    /* Spacing of the samples in metres. The ground spacing at the raster's
     * middle (ground): one pixel step in x and in y taken to longitude and
     * latitude and measured on the CRS's ellipsoid, so a projection's own
     * scale (Web Mercator's 1 / cos(latitude)) is taken out. spacing is
     * that, except for a projected CRS within 1 % of true scale at the
     * middle and at the first sample (UTM, state plane, national grids):
     * there it is |pixel| in metres (spacing_crs), so the mesh registers
     * with other data of that CRS (UTM's 30 m pixel, 30.012 m on the
     * ground off its central meridian, stays 30). With no CRS, |pixel| in
     * the file's unknown unit. */
    bool has_spacing;
    bool spacing_approx;   /* the ground spacing differs by over 0.1 % at the first sample */
    bool spacing_unitless; /* no CRS: the unit is unknown */
    bool spacing_crs;      /* spacing is the CRS's pixel size, not the ground's */
    double spacing[2];
    double ground[2]; /* the ground spacing at the middle (has_spacing and a CRS) */
} tsr_georef;

/* The georeferencing of the file hf was loaded from; NULL when it named
 * none (or hf was not loaded from a file). */
const tsr_georef *tsr_heightfield_georef(const tsr_heightfield *hf);

/* A width × height heightfield of zeros with dx = dy = dz = 1; NULL when
 * out of memory or outside the size limits. */
tsr_heightfield *tsr_heightfield_create(uint32_t width, uint32_t height, const tsr_allocator *alloc);
void tsr_heightfield_destroy(tsr_heightfield *hf);

uint32_t tsr_heightfield_width(const tsr_heightfield *hf);
uint32_t tsr_heightfield_height(const tsr_heightfield *hf);
/* Row-major samples, width * height floats; valid until destroy. */
float *tsr_heightfield_data(tsr_heightfield *hf);
const float *tsr_heightfield_cdata(const tsr_heightfield *hf);
/* Sample spacing and height scale (the convention above); default 1. */
void tsr_heightfield_set_spacing(tsr_heightfield *hf, double dx, double dy, double dz);
void tsr_heightfield_spacing(const tsr_heightfield *hf, double *dx, double *dy, double *dz);
/* What the samples were read from, e.g. "png uint16" or "raw f32". */
const char *tsr_heightfield_source_format(const tsr_heightfield *hf);

typedef struct tsr_heightfield_stats {
    double min, max, mean; /* over valid samples, in file units (before dz) */
    uint64_t valid;        /* samples that are not NaN */
    uint64_t nodata;       /* NaN samples */
} tsr_heightfield_stats;

void tsr_heightfield_stats_compute(const tsr_heightfield *hf, tsr_heightfield_stats *st);

/* What tsr_heightfield_save used for a 16-bit PNG: the file's integer q
 * stands for h = q * scale + offset. For float formats scale 1, offset 0. */
typedef struct tsr_save_info {
    double scale, offset;
} tsr_save_info;

/* Saves by path's extension: .png (16-bit grey, the valid range mapped onto
 * 0..65535 unless the heights are already integers in 0..65535, the
 * scale and offset stored in the file's metadata and returned in *info),
 * .tif/.tiff (float32) or .exr (float32). NaN is written as NaN in float
 * formats and as 0 in PNG (PNG has no no-data). Written to a temporary
 * and renamed, so failure leaves no file. info may be NULL. */
tsr_status tsr_heightfield_save(const tsr_heightfield *hf, const char *path, tsr_save_info *info,
                                tsr_error *err);
/* Whether tsr_heightfield_save would take path: its extension names a
 * format it writes and a file can be made there (tsr_atomic_probe). */
tsr_status tsr_heightfield_save_check(const char *path, tsr_error *err);

/* ---- Sample terrain ---------------------------------------------------- */

/* Zero means default for every field. */
typedef struct tsr_generate_options {
    uint32_t seed;               /* any value; same seed, same terrain */
    double relief;               /* height range in metres; default 1200 */
    double feature_size;         /* largest features, in samples; default width / 3 */
    uint32_t erosion_iterations; /* thermal erosion passes; default 40 */
    uint32_t threads;            /* for the noise; 0: one per processor */
    /* Called now and then with the fraction done (0..1, non-decreasing),
     * one call at a time but maybe from another thread; NULL: none. */
    void (*progress)(void *user, double fraction);
    void *progress_user;
} tsr_generate_options;

/* Fills hf with a realistic terrain: domain-warped fractal noise blended
 * with ridged multifractal mountains, then hydraulic erosion (droplets)
 * and thermal erosion that relaxes slopes above the talus angle.
 * Deterministic for a given seed and size, the same whatever the thread
 * count (integer hashing, no library random numbers). */
void tsr_terrain_generate(tsr_heightfield *hf, const tsr_generate_options *opts);

/* A fast fractal terrain for benchmarks at large sizes: midpoint
 * displacement (diamond-square, Fournier, Fussell & Carpenter 1982) with
 * hashed, seed-determined offsets, roughness 0.5, heights 0..relief; no
 * erosion. Sizes other than a (2^k + 1) square are cropped from one,
 * made in a temporary. */
void tsr_terrain_generate_fast(tsr_heightfield *hf, uint32_t seed, double relief);

/* ---- Grid mesh --------------------------------------------------------- */

/* The regular-grid mesh of the samples at every step-th column and row
 * (the last column and row always included), in world coordinates
 * (x = c*dx, y = r*dy, z = h*dz), triangles counter-clockwise from +z,
 * two per cell along its top-left to bottom-right diagonal. No-data
 * becomes a hole: a cell with one no-data corner keeps the triangle of its
 * other three, one with more keeps none, and no triangle touches a no-data
 * sample, also one between the lattice samples (step above 1). Only
 * samples some triangle uses become vertices. Normals, when asked, come
 * from central differences of the full heightfield. The mesh must be
 * initialised (tsr_mesh_init) and empty. */
tsr_status tsr_terrain_grid_mesh(const tsr_heightfield *hf, uint32_t step, bool normals,
                                 tsr_mesh *mesh, tsr_error *err);

/* ---- Error-bounded mesh (tessera mesh) ---------------------------------- */

typedef enum tsr_tin_method {
    TSR_TIN_DELAUNAY = 0, /* greedy insertion on the constrained-Delaunay kernel */
    TSR_TIN_QUADTREE,     /* the restricted quadtree's cut at a view-independent tolerance */
    TSR_TIN_GRID          /* every step-th sample */
} tsr_tin_method;

/* Zero means default for every field. Errors are vertical, in world
 * units (z = h dz). */
typedef struct tsr_tin_options {
    tsr_tin_method method;
    /* The bound: no valid sample farther from the mesh than this. 0 means
     * 0.1% of the whole heightfield's height range (with a window too, so
     * adjacent windows get the same bound and border), unless a budget is
     * given, in which case the budget alone stops refinement. Must be >= 0. */
    double max_error;
    /* Budgets: the mesh has at most this many triangles / vertices (0:
     * none); refinement stops before the next step would exceed one. */
    uint32_t max_triangles, max_vertices;
    /* delaunay: tolerance for the simplification of the outer border and
     * of the no-data boundaries, fixed before the greedy pass
     * (Douglas-Peucker along each straight run, the same way whatever the
     * interior, so adjacent windows share their border vertices); 0:
     * max_error, or 0.1% of the range when that is 0 too and there is no
     * budget. With a budget and neither bound, nothing is fixed: the
     * border is refined by the greedy pass like the interior. */
    double border_error;
    uint32_t grid_step;           /* grid: keep every step-th column and row (default 1) */
    /* quadtree: 0 (default): each leaf is two triangles on its chosen
     * diagonal or four from its centre, plus the midpoints of sides with a
     * finer neighbour, kept only where every sample is within the bound
     * (rqt.c); 2..128, a power of 2: each leaf the terrain LOD's grid tile
     * of that size, selected by the LOD pyramid's conservative error */
    uint32_t tile_n;
    bool full_border;             /* quadtree: outer border at full resolution (for seams) */
    bool normals;                 /* per-vertex normals from the heightfield's gradients */
    /* delaunay: skip the data-dependent edge flips made after each
     * insertion (they lower the errors, so the same bound needs about a
     * fifth fewer triangles, in 1.3-2x the time); without them the
     * triangulation is (constrained) Delaunay */
    bool no_flip;
    /* delaunay with a bound and no budget: the window is cut into blocks
     * of about block x block cells, each meshed on its own with its border
     * fixed as a window's is (so blocks meet with identical vertices and
     * the mesh is conforming across them), on up to `threads` threads at
     * once. The blocks depend on the window's size and `block` alone, so
     * the mesh is the same whatever the thread count. block 0: 256;
     * block >= the window's size: one block (the whole window). threads
     * 0: tsr_cpu_count(). With a budget (or no bound) the window
     * is one block on one thread: a budget is global. The heightfield's
     * allocator is then called from several threads at once. quadtree
     * (tile_n 0): nodes are tested on up to `threads` threads; the mesh
     * is the same whatever the count. */
    uint32_t block, threads;
    /* A window: mesh only columns x .. x+w-1, rows y .. y+h-1 (w = h = 0:
     * everything). Vertices keep the whole heightfield's coordinates, so
     * meshes of adjacent windows (sharing their border row or column)
     * fit together; their border vertices are identical for the delaunay
     * method (the same border_error on both sides), the grid method and
     * the quadtree method with full_border. */
    uint32_t window_x, window_y, window_w, window_h;
    /* Called now and then with the fraction done (0..1); may be NULL. */
    void (*progress)(void *user, double fraction);
    void *progress_user;
} tsr_tin_options;

typedef struct tsr_tin_report {
    double target_error;      /* the tolerance refinement worked to (world units) */
    double bound;             /* the max error asked for, else the default (0.1 % of the whole
                                 heightfield's height range) when no budget is given either; 0 with a
                                 budget alone */
    double border_error;      /* the border simplification's tolerance */
    double estimated_error;   /* the mesher's own estimate of the max error (not measured) */
    uint32_t border_vertices; /* vertices fixed on the border, no-data boundaries and block seams (per block) */
    uint32_t insertions;      /* delaunay: points inserted by the greedy pass */
    uint32_t flips;           /* delaunay: data-dependent edge flips made */
    uint32_t blocks;          /* delaunay: blocks meshed (tsr_tin_options.block) */
    bool budget_reached;      /* a budget stopped refinement */
    tsr_heightfield_stats window; /* the window's samples (the whole heightfield's without one) */
} tsr_tin_report;

/* Meshes the heightfield by opts->method into mesh (initialised, empty;
 * TSR_MESH_NORMALS when opts->normals). Triangles counter-clockwise seen
 * from +z; cells with a no-data corner are holes, never zeros. The
 * delaunay method (Garland & Heckbert 1995) inserts, greedily, the sample
 * farthest from the current mesh until every sample is within the target
 * (or a budget is reached), flipping edges after each insertion where that
 * lowers the error (unless no_flip); the outer border and no-data boundaries are
 * fixed first by Douglas-Peucker so they depend only on their own
 * samples. Does not measure the result: see tsr_terrain_measure. Fails
 * with TSR_ERR_ARGUMENT for bad options (among them a delaunay
 * border_error above the bound, given or the default), a budget smaller
 * than the fixed border needs (err says how many), or heights times dz or
 * the window's extents beyond float (the vertices' type); TSR_ERR_VALUE
 * for a window without a valid sample; TSR_ERR_NOMEM, TSR_ERR_TOO_LARGE.
 * Nothing is meshed when the options are refused. */
tsr_status tsr_terrain_mesh(const tsr_heightfield *hf, const tsr_tin_options *opts, tsr_mesh *mesh,
                            tsr_tin_report *report, tsr_error *err);

/* A copy of the w x h window at column x, row y (same spacing and source
 * format); NULL when out of memory or the window is not inside hf or
 * smaller than 2 x 2. */
tsr_heightfield *tsr_heightfield_crop(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w, uint32_t h,
                                      const tsr_allocator *alloc);

/* ---- Level of detail ---------------------------------------------------- */

/* A terrain for level of detail: a heightfield (borrowed: it must outlive
 * the terrain and not change) and its pyramid:
 *  - maximum mipmaps: for mip level k >= 1, the min and max height of each
 *    block of 2^k x 2^k cells, closed (its border samples included), NaN
 *    ignored, plus a no-data flag per block;
 *  - per quadtree node, a conservative, monotone geometric error delta:
 *    no full-resolution sample in the node is farther, vertically, from
 *    the node's grid tile (with any stitch mask) than delta.
 * The quadtree lattice is the samples: (i, j) = (column, row); node
 * (level, x, y) covers tile_n << (levels - level) cells. */
typedef struct tsr_terrain tsr_terrain;

typedef struct tsr_terrain_options {
    uint32_t tile_n; /* quads per tile side: 2, 4, ..., 128 (default 16) */
} tsr_terrain_options;

/* Builds the pyramid in one bottom-up pass. Fails on a bad tile size or
 * spacing (dx, dy, dz must be positive) or out of memory. */
tsr_status tsr_terrain_create(const tsr_heightfield *hf, const tsr_terrain_options *opts, const tsr_allocator *alloc,
                              tsr_terrain **out, tsr_error *err);
void tsr_terrain_destroy(tsr_terrain *t);

/* The terrain behind the generic surface interface (valid while t lives).
 * evaluate gives (c dx, r dy, h dz) and the normal from central
 * differences; false at NaN samples. bounds are world boxes; error is
 * delta * dz (INFINITY for a node above the deepest level that covers a
 * no-data sample, so holes are always meshed at full resolution). */
const tsr_surface *tsr_terrain_surface(const tsr_terrain *t);
const tsr_heightfield *tsr_terrain_heightfield(const tsr_terrain *t);

/* Min and max height (file units) of a node; min > max when it has no
 * valid sample. */
void tsr_terrain_node_range(const tsr_terrain *t, tsr_qnode n, float *min, float *max);

/* Bytes the terrain keeps beyond the heightfield itself. */
size_t tsr_terrain_extra_bytes(const tsr_terrain *t);

/* Ray picking: the first intersection, at parameter t >= 0 along
 * origin + t dir (world coordinates), with the full-resolution surface:
 * each cell between four valid samples split into two triangles along the
 * same diagonal as the finest grid tiles (from (c, r) to (c+1, r+1) when
 * c + r is even, else from (c+1, r) to (c, r+1)). Descends the max mipmap
 * and skips blocks the ray passes over or under. Returns false when the ray
 * misses (cells with a NaN corner are holes). */
bool tsr_terrain_pick(const tsr_terrain *t, const double origin[3], const double dir[3], double *t_hit);

/* ---- Images --------------------------------------------------------------- */

/* Writes 8-bit pixels (channels 1 to 4 interleaved, row 0 first) to path,
 * the format chosen by its extension, under a temporary name beside it
 * renamed when complete: on failure no file is left. Checks the extension
 * before touching the disk (TSR_ERR_UNSUPPORTED); messages name path. */
tsr_status tsr_image_save_u8(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                             const uint8_t *pixels, tsr_error *err);
/* The same, the pixels made a band of rows at a time, so a big image is
 * never whole in memory: fill(user, y0, y1, rows) writes rows y0 .. y1 - 1
 * (channels interleaved, width * channels bytes a row) into rows; the
 * bands come in order, at most TSR_IMAGE_BAND_ROWS rows each. */
enum { TSR_IMAGE_BAND_ROWS = 64 };
tsr_status tsr_image_save_u8_rows(const char *path, uint32_t width, uint32_t height, uint32_t channels,
                                  void (*fill)(void *user, uint32_t y0, uint32_t y1, uint8_t *rows), void *user,
                                  tsr_error *err);
/* Whether tsr_image_save_u8 would take path: an image writer for its
 * extension, and a file can be made there (tsr_atomic_probe). */
tsr_status tsr_image_save_check(const char *path, tsr_error *err);

/* ---- Independent error measurement -------------------------------------- */

/* What an output mesh does to the samples, measured by brute force from
 * the heightfield and the mesh alone (no pyramid, no quadtree): the oracle
 * of `tessera check terrain` and of the tests. */
typedef struct tsr_error_report {
    double max_vertical;    /* max |h dz - z of the mesh above or below| */
    double rms_vertical;    /* root mean square of the same, over the covered samples */
    uint64_t covered;       /* valid samples with the mesh above or below */
    double max_pixels;      /* max screen error (with a camera) */
    uint64_t counted;       /* samples counted for max_pixels */
    uint64_t uncovered;     /* valid samples with no mesh above or below */
    uint32_t worst_c, worst_r; /* the sample of max_pixels (or max_vertical) */
} tsr_error_report;

/* For every valid sample s = (c dx, r dy, h dz): the point m of the mesh
 * vertically above or below s; max_vertical over all of them; with a
 * camera (prepared, may be NULL), the distance in pixels between the
 * projections of s and m, counted where both lie beyond the near plane and
 * at least one projects inside the viewport. The mesh must be a height
 * field over the (x, y) plane. */
tsr_status tsr_terrain_measure(const tsr_heightfield *hf, const tsr_mesh *mesh, const tsr_camera *cam,
                               tsr_error_report *out);
/* The same over the samples of the window (x0, y0, w, h) only; the mesh in
 * the whole heightfield's coordinates. TSR_ERR_ARGUMENT for a window not
 * inside hf, TSR_ERR_NOMEM. Both run in bands of rows on every processor,
 * each band with its own scratch (a few of its rows: not a copy of the
 * heightfield), made with the heightfield's allocator from those threads;
 * the figures do not depend on the threads. */
tsr_status tsr_terrain_measure_window(const tsr_heightfield *hf, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h,
                                      const tsr_mesh *mesh, const tsr_camera *cam, tsr_error_report *out);

#ifdef __cplusplus
}
#endif
#endif /* TSR_TERRAIN_H */
