/* hw.h: the GPU layer. Three parts:
 *
 *  1. The backend table: buffers, uploads, and frames of grid-tile draws.
 *     The null backend (no device) validates and counts every call; the
 *     Vulkan backend (Mesa's lavapipe or a real GPU) renders them.
 *  2. The tile renderer: device-independent logic on top of the table (a
 *     tile cache with a byte budget, compact height upload, the shared
 *     stitch index patterns, draw lists), unit-tested with the null
 *     backend (../shared/STYLE.md item 7).
 *  3. The Vulkan backend's constructor.
 *
 * hw/ takes grid tiles (heights, origin, spacing, stitch mask, morph),
 * never a terrain or a patch (../shared/DESIGN.md). A tile of n x n quads
 * has (n+1)^2 samples, vertex (i, j) at index j*(n+1)+i, i along +x and j
 * along +y; its triangles are tessellate/'s stitch patterns
 * (tsr_tile_pattern), counter-clockwise seen from +z.
 *
 * Coordinates. The world has +z up. A frame carries the eye position in
 * double; everything sent to the device is relative to the eye, in float,
 * so a terrain kilometres wide keeps centimetre precision near the eye.
 * Clip space is Vulkan's: y down, depth in [0, 1], here reversed and with
 * an infinite far plane (depth = near / distance along the view axis, 0
 * at infinity, cleared to 0), which gives float depth buffers uniform
 * relative precision. */
#ifndef TSR_HW_H
#define TSR_HW_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ====================================================================== */
/* 1. The backend table                                                    */
/* ====================================================================== */

typedef uint32_t tsr_hw_buffer; /* 0 is never a valid buffer */

/* VERTEX: samples read by the vertex shader (a storage buffer, addressed
 * in bytes, 4-byte aligned); INDEX: 32-bit triangle indices; STAGING:
 * host-side scratch (backends may ignore it). */
typedef enum tsr_hw_buffer_kind { TSR_HW_VERTEX = 1, TSR_HW_INDEX = 2, TSR_HW_STAGING = 3 } tsr_hw_buffer_kind;

/* How a tile's samples are stored. U16: two samples per 32-bit word, the
 * first in the low half; the code 0xFFFF is no-data. F32: one float per
 * sample, NaN is no-data. */
typedef enum tsr_hw_height_format { TSR_HW_HEIGHT_U16 = 1, TSR_HW_HEIGHT_F32 = 2 } tsr_hw_height_format;

enum {
    TSR_HW_FRAME_WIREFRAME = 1, /* overlay edges, coloured by LOD level, tile borders bright */
    TSR_HW_FRAME_GEOMORPH = 2,  /* apply the tiles' morph weights */
    TSR_HW_FRAME_NORMALS = 4    /* colour = the shading normal n as (n + 1) / 2, unlit, no fog (a debug view) */
};

/* Everything a frame needs besides its tiles. */
typedef struct tsr_hw_frame {
    double eye[3];         /* world position of the eye */
    float view_proj[16];   /* column-major; maps (world - eye, 1) to clip space (see top) */
    float sun[3];          /* unit vector towards the sun (world) */
    float fog_distance;    /* fog reaches 1 - 1/e of the sky colour here (world units); 0: none */
    float zmin, zmax;      /* world height range, for the colour ramp */
    float spacing_min;     /* world spacing of the finest samples (normals' scale) */
    uint32_t flags;        /* TSR_HW_FRAME_* */
} tsr_hw_frame;

/* One tile draw: which samples, which stitch pattern, where. World
 * position of vertex (i, j) before morphing:
 *   x = eye_x + min(origin[0] + i * spacing[0], limit[0]),  likewise y with j,
 *   z = eye_z + z_base + z_step * s(i, j)
 * with s the stored sample (the U16 code, or the F32 value). With
 * TSR_HW_FRAME_GEOMORPH, odd vertices inside the tile move towards where
 * the parent tile puts them (the mean of the two even neighbours along the
 * parent's edge or diagonal) by the weight `morph`; edge vertices never
 * move, so morphing opens no crack.
 *
 * Watertight borders. A vertex on the border is placed by one of the
 * drawn tiles that have it (found through `neighbour`, below): the
 * coarsest, then the one of the lowest draw number, with that tile's
 * stored sample, origin and spacing in the formula above. So every tile
 * puts a shared vertex at the same float position, to the bit, though
 * each quantises its own 16-bit samples (offset and scale per tile) and
 * rounds its own origin: without that, the rasteriser left pinholes along
 * borders (0-7 a frame at 1280 x 720 on the demo terrain). This holds
 * when the links are symmetric (a tile names each drawn tile across its
 * edges, as that one names it) and tiles that share vertices have the
 * same `limit`; tiles drawn without neighbours place their border
 * vertices themselves.
 *
 * Normals. Vertex (i, j) is shaded with normalize(-dz/dx, -dz/dy, 1) from
 * central differences of the stored heights at (i +- r, j) and (i, j +- r),
 * with r = 1 inside the tile. At the border r is the coarsest spacing of
 * the drawn tiles that meet at the vertex, over this tile's: on an edge,
 * 2 towards a coarser neighbour, else 1; at a corner 1, 2 or 4, from the
 * tiles across its two edges and the one across the corner (found through
 * those two's neighbours). The samples beyond an edge are the neighbour's.
 * So every drawn tile at a vertex takes the same differences of the same
 * samples, and their lighting meets without a seam (next to a tile not
 * drawn, e.g. culled off screen, or beyond a tile of n = 2, they may
 * differ). A difference whose
 * far sample is missing (no neighbour, no-data, or not on the neighbour's
 * lattice, e.g. beyond a tile of n = 2) is one-sided; with none on either
 * side, that slope is 0. With TSR_HW_FRAME_GEOMORPH, a vertex inside the
 * tile moves its normal as its height, by `morph`, towards what the parent
 * tile draws there: at an even vertex the parent's normal (differences at
 * r = 2, its spacing), at an odd one the mean of the parent's normals at
 * the two even vertices whose mean its height goes to (not renormalised:
 * the fragment shader normalises after interpolating, as for the parent).
 * The neighbours are read from the pool where they already are: no bytes
 * are uploaded for them. */
typedef struct tsr_hw_tile_draw {
    tsr_hw_buffer samples;  /* a VERTEX buffer */
    uint64_t samples_offset; /* byte offset of the word holding sample 0, a multiple of 4 */
    uint32_t first_sample;   /* U16: 1 when sample 0 is the word's high half (tiles of an odd
                              * sample count pack without padding); F32: 0 */
    tsr_hw_height_format format;
    tsr_hw_buffer indices;  /* an INDEX buffer */
    uint32_t first_index, index_count; /* index_count a multiple of 3 */
    uint32_t n;             /* quads per side, even, 2..TSR_TILE_MAX */
    float origin[2];        /* world x, y of vertex (0, 0) minus the eye's */
    float spacing[2];       /* world distance between vertices along x and y, > 0 */
    float limit[2];         /* x, y (minus the eye's) beyond which vertices are clamped onto it:
                             * a tile overhanging the surface's extent folds onto its border */
    float z_base, z_step;   /* see above; z_base is relative to the eye's z */
    float morph;            /* in [0, 1] */
    uint8_t level;          /* quadtree level (wireframe colour) */
    uint8_t parity;         /* bit 0: node x odd, bit 1: node y odd (its quarter of the parent) */
    /* The draws across the edges (normals, above): 1 + the neighbour's
     * draw number in this frame (0 for the frame's first draw_tile), 0 for
     * none, per half edge: neighbour[2 e + h] for edge e in the order of
     * TSR_EDGE_* (0 south j = 0, 1 east i = n, 2 north j = n, 3 west
     * i = 0) and half h (0 towards smaller i or j). A neighbour at the same
     * level or coarser covers both halves; finer ones one half each. A
     * neighbour must share the edge and its vertices (spacing 1/2, 1 or 2
     * times this tile's, lattices aligned): one that does not only loses
     * the central differences, never the draw. */
    uint32_t neighbour[8];
} tsr_hw_tile_draw;

/* What one frame cost the device. */
typedef struct tsr_hw_frame_stats {
    uint64_t triangles;     /* triangles assembled: the GPU's pipeline-statistics count, or the null backend's sum */
    double gpu_ms;          /* device time of the frame from timestamps; 0 when unknown; in a window, whose
                             * frames are in flight when end_frame returns, the latest finished frame's */
    double submit_wait_ms;  /* host time end_frame spent waiting for the device */
} tsr_hw_frame_stats;

/* Counters every backend keeps, so tests and HUDs can see what happened. */
typedef struct tsr_hw_stats {
    uint64_t buffers_live;
    uint64_t bytes_live;
    uint64_t bytes_uploaded;
    uint64_t draws;
    uint64_t triangles_drawn;
    uint64_t frames;
    uint64_t upload_stalls;       /* uploads that had to wait for the device (staging ring full) */
    uint64_t validation_messages; /* warnings and errors from the validation layers */
} tsr_hw_stats;

typedef struct tsr_hw_backend tsr_hw_backend;

/* The table. Every function receives the backend itself. Not
 * thread-safe: one thread drives one backend.
 *  - create_buffer: a buffer of `size` bytes (> 0); 0 on failure.
 *  - upload: writes `size` bytes at `offset`; false outside the buffer.
 *    Inside a frame the copy happens before the frame's draws (through a
 *    staging ring, without waiting for the device unless the ring is
 *    full); outside a frame it is complete when upload returns.
 *  - begin_frame / draw_tile / end_frame: one frame. draw_tile validates
 *    the draw (buffers of the right kind, ranges inside them) and returns
 *    false, drawing nothing, when it is invalid. When a draw names a
 *    neighbour beyond the frame's draws (or itself), a draw's buffer was
 *    destroyed since draw_tile, or the backend has no memory for the
 *    frame's draw records, end_frame draws none of the
 *    frame's tiles (its uploads still happen, the frame counts, *stats
 *    says 0 triangles) and returns false. Otherwise end_frame submits and,
 *    for an offscreen target, waits for the image; it fills *stats when
 *    not NULL. A frame must be ended before the next begins.
 *  - read_color: the last frame's colour, width*height RGBA8 pixels, row
 *    0 at the top; read_depth: its depth, width*height floats (reversed:
 *    near/distance, 0 where nothing was drawn). False when the backend
 *    has no image (the null backend, a windowed frame). */
struct tsr_hw_backend {
    const char *name;        /* "null", or the Vulkan device's name */
    uint32_t width, height;  /* the render target, pixels */
    tsr_hw_buffer (*create_buffer)(tsr_hw_backend *self, tsr_hw_buffer_kind kind, uint64_t size);
    bool (*upload)(tsr_hw_backend *self, tsr_hw_buffer buf, uint64_t offset, const void *data, uint64_t size);
    void (*destroy_buffer)(tsr_hw_backend *self, tsr_hw_buffer buf);
    bool (*begin_frame)(tsr_hw_backend *self, const tsr_hw_frame *frame);
    bool (*draw_tile)(tsr_hw_backend *self, const tsr_hw_tile_draw *draw);
    bool (*end_frame)(tsr_hw_backend *self, tsr_hw_frame_stats *stats);
    bool (*read_color)(tsr_hw_backend *self, uint8_t *rgba);
    bool (*read_depth)(tsr_hw_backend *self, float *depth);
    void (*destroy)(tsr_hw_backend *self);
    tsr_hw_stats stats;
};

/* A backend that keeps no data, only sizes and counters, with a render
 * target of width x height (which it never draws); NULL when out of
 * memory. alloc may be NULL. Destroy it with backend->destroy(backend). */
tsr_hw_backend *tsr_hw_null_create(uint32_t width, uint32_t height, const tsr_allocator *alloc);

/* Bytes a draw reads from samples_offset: (n+1)^2 samples of the format
 * after first_sample; 0 when the format, n or first_sample is invalid. */
uint64_t tsr_hw_draw_sample_bytes(tsr_hw_height_format format, uint32_t n, uint32_t first_sample);

/* The rules of a valid draw that every backend checks once it has found
 * the draw's buffers and their kinds right: n, format and first_sample,
 * the samples inside a samples buffer of samples_size bytes from a
 * 4-byte aligned offset, whole triangles inside an index buffer of
 * indices_size bytes, spacing > 0 and finite, origin finite, morph in
 * [0, 1] (NaN fails). */
bool tsr_hw_draw_fits(const tsr_hw_tile_draw *d, uint64_t samples_size, uint64_t indices_size);

/* The view-projection matrix of a prepared camera (see tsr_camera in
 * tessellate/quadtree.h): column-major, for positions relative to the
 * eye, reversed infinite depth with the camera's near plane, so a world
 * point p lands on pixel tsr_camera_project(p) (x right, y down from the
 * top-left corner). */
void tsr_hw_view_proj(const tsr_camera *cam, float m[16]);

/* ====================================================================== */
/* 2. The tile renderer                                                    */
/* ====================================================================== */

/* Stores (n+1)^2 = count samples compactly into dst (tsr_hw_encode_bound
 * bytes): as U16 when that loses at most max_error (in sample units) —
 * always when the valid samples are integers spanning at most 65534 —
 * else as F32. NaN samples are no-data. The stored code c stands for the
 * sample offset + scale * c. Returns the bytes written (a multiple of 4). */
typedef struct tsr_hw_encoding {
    tsr_hw_height_format format;
    double offset, scale;
    uint32_t bytes;
} tsr_hw_encoding;
uint32_t tsr_hw_encode_bound(uint32_t count);
tsr_hw_encoding tsr_hw_encode_samples(const float *samples, uint32_t count, double max_error, void *dst);

/* A tile of the cut as the caller sees it. */
typedef struct tsr_hw_tile {
    uint64_t key;           /* identifies the tile's samples (e.g. tsr_qnode_key): same key, same samples */
    double origin[2];       /* world x, y of vertex (0, 0) */
    double spacing[2];      /* world spacing of the vertices */
    double limit[2];        /* world x, y clamp (the extent's far border); 0 or INFINITY: none */
    double z_scale;         /* world z = z_scale * sample */
    double max_quantization; /* sample units a U16 encoding may move a sample of this tile;
                              * 0: the renderer's max_quantization */
    float morph;
    uint8_t stitch;         /* TSR_EDGE_* bits */
    uint8_t level, parity;  /* as in tsr_hw_tile_draw */
    uint32_t neighbour[8];  /* as in tsr_hw_tile_draw, numbering this frame's tiles: 1 + index, 0 none
                             * (all 0: the tile's border normals are one-sided) */
} tsr_hw_tile;

/* Fills the tile's (n+1)^2 samples (index j*(n+1)+i; NaN for no-data);
 * false on failure, which fails the frame. */
typedef bool (*tsr_hw_fetch_fn)(void *user, const tsr_hw_tile *tile, float *samples);

typedef struct tsr_hw_renderer_options {
    uint32_t tile_n;          /* quads per tile side: even, 2..TSR_TILE_MAX (default 16) */
    uint64_t cache_bytes;     /* resident samples budget, bytes (default 256 MiB) */
    double max_quantization;  /* sample units a U16 tile may move a sample (default 0: lossless only) */
} tsr_hw_renderer_options;

/* What one frame did on the host side. */
typedef struct tsr_hw_render_stats {
    uint32_t tiles;           /* tiles drawn */
    uint32_t tiles_uploaded;  /* tiles that entered the cache this frame */
    uint32_t tiles_evicted;
    uint32_t tiles_u16;       /* resident tiles stored as U16 */
    uint32_t tiles_resident;
    uint64_t triangles;       /* triangles submitted, counted on the host */
    uint64_t bytes_uploaded;  /* sample bytes uploaded this frame */
    uint64_t bytes_resident;  /* sample bytes of the resident tiles */
    double upload_ms, record_ms; /* host time fetching+encoding+uploading, and recording draws */
    tsr_hw_frame_stats device;
} tsr_hw_render_stats;

typedef struct tsr_hw_renderer tsr_hw_renderer;

/* Creates the renderer on a backend (borrowed; it must outlive the
 * renderer): uploads the 16 stitch patterns of tile_n once, and allocates
 * the sample pool of cache_bytes. */
tsr_status tsr_hw_renderer_create(tsr_hw_backend *backend, const tsr_hw_renderer_options *opts,
                                  const tsr_allocator *alloc, tsr_hw_renderer **out, tsr_error *err);
void tsr_hw_renderer_destroy(tsr_hw_renderer *r);

/* Draws one frame of `count` tiles: tiles already resident are drawn from
 * the cache; the others are fetched, encoded and uploaded (evicting the
 * least recently drawn tiles that this frame does not use), then drawn.
 * Draw k is tile k, so a tile's neighbour numbers pass to its draw as they
 * are. Fails with TSR_ERR_ARGUMENT for a tile naming a neighbour beyond
 * `count` or itself, with TSR_ERR_TOO_LARGE when the frame's tiles alone
 * exceed the cache budget (the renderer stays usable: a coarser cut of
 * the same view may fit), with TSR_ERR_NOMEM when host memory runs out,
 * and with the fetch's or the backend's failure otherwise. */
tsr_status tsr_hw_renderer_frame(tsr_hw_renderer *r, const tsr_hw_frame *frame, const tsr_hw_tile *tiles,
                                 uint32_t count, tsr_hw_fetch_fn fetch, void *user, tsr_hw_render_stats *stats,
                                 tsr_error *err);

/* Drops every resident tile (e.g. after the samples changed). */
void tsr_hw_renderer_flush(tsr_hw_renderer *r);

/* ====================================================================== */
/* 3. Vulkan                                                               */
/* ====================================================================== */

typedef struct tsr_hw_vulkan_options {
    uint32_t width, height; /* render target; default 1280 x 720 */
    /* Device: a name substring or an index into the physical devices;
     * NULL: the environment variable TESSERA_VK_DEVICE, else the first
     * discrete GPU, else integrated, else virtual, else CPU (lavapipe). */
    const char *device;
    /* Validation layers: 0 default (on in debug builds when installed, or
     * when TESSERA_VK_VALIDATION=1), 1 required, -1 off. Messages are
     * printed to stderr and counted in stats.validation_messages. */
    int validation;
    /* A GLFWwindow * to present into (the frame is rendered offscreen
     * and blitted to the swapchain); NULL: offscreen only. */
    void *window;
    bool vsync;
} tsr_hw_vulkan_options;

/* Creates the Vulkan backend. Fails with TSR_ERR_UNSUPPORTED and a clear
 * detail when no Vulkan driver or no suitable device is installed. */
tsr_status tsr_hw_vulkan_create(const tsr_hw_vulkan_options *opts, const tsr_allocator *alloc,
                                tsr_hw_backend **out, tsr_error *err);

#ifdef __cplusplus
}
#endif
#endif
