/* fly.h: what `tessera fly`, `tessera bench fly` and the hw tests share:
 * a terrain drawn through hw/'s tile renderer, frame by frame (select the
 * cut for a camera, hand its tiles to the renderer), and the camera paths
 * of a flight. tools/ is the only place where terrain/ and hw/ meet. */
#ifndef TSR_TOOLS_FLY_H
#define TSR_TOOLS_FLY_H

#include "camera.h"
#include "hw/hw.h"

typedef struct fly_options {
    uint32_t tile_n;      /* quads per tile side (default 16) */
    double pixel_error;   /* tau, pixels (default 2) */
    double fovy_deg;      /* default 60 */
    double near_dist;     /* default 1 (world units), or a thousandth of the terrain's size if less */
    bool wireframe, geomorph;
    uint64_t cache_bytes; /* renderer budget (default 256 MiB) */
    double fog_distance;  /* 0: a third of the terrain's diagonal; < 0: none */
    bool show_normals;    /* draw the shading normals as colours (TSR_HW_FRAME_NORMALS) */
    bool one_sided_normals; /* pass no neighbours: border normals from each tile's own samples
                             * (the seams of earlier versions; for comparison); border vertices
                             * are then placed by each tile itself, and pinholes may open */
} fly_options;

typedef struct fly_frame_stats {
    double select_ms;     /* quadtree selection, culling and morph weights */
    uint32_t leaves;      /* leaves of the cut, culled ones included */
    double pixel_error;   /* the pixel error of the cut drawn: the camera's, or more when coarsened */
    uint32_t coarsened;   /* times the cut was coarsened (pixel error x 1.5) to fit the tile cache */
    tsr_hw_render_stats render;
} fly_frame_stats;

typedef struct fly_ctx {
    const tsr_heightfield *hf;
    tsr_terrain *terrain;
    tsr_quadtree *qt;
    tsr_hw_backend *backend; /* borrowed */
    tsr_hw_renderer *renderer;
    tsr_hw_tile *tiles;
    uint32_t tiles_cap;
    tsr_keymap drawn; /* a drawn tile's node key -> 1 + its index in tiles */
    fly_options o;
    double dx, dy, dz, zmin, zmax;
    uint32_t levels;
} fly_ctx;

/* Sets up the terrain pyramid, quadtree and renderer on a backend. */
tsr_status fly_init(fly_ctx *f, const tsr_heightfield *hf, tsr_hw_backend *backend, const fly_options *o,
                    tsr_error *err);
void fly_free(fly_ctx *f);

/* The camera for this context's viewport and options (eye, target in
 * world units); false when degenerate. */
bool fly_camera(const fly_ctx *f, const double eye[3], const double target[3], tsr_camera *cam);

/* Selects the cut for the camera and draws it. When the cut's tiles do not
 * fit the tile cache (o.cache_bytes), draws a coarser cut instead (the
 * pixel error raised until they fit; st says by how much). */
tsr_status fly_frame(fly_ctx *f, const tsr_camera *cam, fly_frame_stats *st, tsr_error *err);

/* The frame description (matrices, sun, fog, flags) fly_frame uses. */
void fly_frame_desc(const fly_ctx *f, const tsr_camera *cam, tsr_hw_frame *frame);

/* ---- flight paths --------------------------------------------------------- */

/* Keyframes of a path: eye positions and, optionally, targets. */
typedef struct fly_path {
    double (*eye)[3], (*target)[3]; /* target NULL: look along the path */
    uint32_t count;
    bool closed;
} fly_path;

/* Reads a path file: one keyframe per line, "EX EY EZ" or
 * "EX EY EZ TX TY TZ" (world units; all lines alike), '#' comments and
 * blank lines ignored, at least 1 keyframe (one alone: a still camera).
 * Errors name the line. */
tsr_status fly_path_read(const char *path, fly_path *p, tsr_error *err);

/* The automatic path: a closed loop of keyframes over the terrain, each
 * well above the highest ground around it. */
tsr_status fly_path_auto(const fly_ctx *f, fly_path *p, tsr_error *err);

void fly_path_free(fly_path *p);

/* The camera at s in [0, 1] along the path (a Catmull-Rom spline through
 * the keyframes; a single keyframe without a target looks at the terrain's
 * centre, from where it stands or was raised to), kept at least `clearance` above the ground (picking);
 * *lifted (when not NULL) says whether it had to be raised. */
bool fly_path_camera(const fly_ctx *f, const fly_path *p, double s, double clearance, tsr_camera *cam,
                     bool *lifted);

#endif
