/* quadtree.h: (included by tessellate.h) the generic restricted quadtree
 * over a surface, grid tiles with stitch patterns, selection (tolerance or
 * camera), and the mesh of a cut. Knows no kind of surface.
 *
 * The lattice. A surface is sampled on an integer lattice (i, j),
 * 0 <= i <= extent_x, 0 <= j <= extent_y, at its finest resolution; for a
 * terrain (i, j) is the sample (column, row), for a patch u = i / size.
 * The quadtree's root covers [0, size]^2 with size = tile_n * 2^levels >=
 * both extents; a node (level, x, y), 0 <= x, y < 2^level, covers
 * [x*w, (x+1)*w] x [y*w, (y+1)*w], w = size >> level, and carries a grid
 * tile of tile_n x tile_n quads with vertex spacing w / tile_n (1 at the
 * deepest level, `levels`). Lattice coordinates beyond the extent are
 * clamped onto it: a node overhanging the extent is clipped at the border,
 * its outer quads collapse and drop out of the mesh. Nodes wholly outside
 * the extent do not exist.
 *
 * Tiles. Each quad (qi, qj) of a tile is split along the diagonal through
 * the centre of its 2x2 block (a "union jack"): corner (qi,qj) to
 * (qi+1,qj+1) when qi+qj is even, else (qi+1,qj) to (qi,qj+1). Then every
 * odd vertex of a tile edge touches exactly two triangles, no triangle
 * touches two, and dropping the odd vertices of any set of edges (merging
 * their two triangles into one) leaves a conforming mesh: the 16 stitch
 * patterns. Stitch bit k (TSR_EDGE_*) is set when the neighbour across edge
 * k is one level coarser. Triangles are counter-clockwise in (i, j) with i
 * to the right and j up (for a terrain: seen from +z).
 */
#ifndef TSR_QUADTREE_H
#define TSR_QUADTREE_H

#ifdef __cplusplus
extern "C" {
#endif

enum { TSR_EDGE_SOUTH = 1, TSR_EDGE_EAST = 2, TSR_EDGE_NORTH = 4, TSR_EDGE_WEST = 8 }; /* j=0, i=max, j=max, i=0 */

#define TSR_TILE_MIN 2u
#define TSR_TILE_MAX 128u
#define TSR_QUADTREE_MAX_LEVELS 13u /* split flags are bitsets: 4^12 bits at the deepest split level */

/* ---- Tile patterns ---------------------------------------------------- */

/* Writes the triangles of an n x n tile with the given stitch mask as
 * indices into its (n+1)^2 vertices (vertex (i, j) is j*(n+1)+i), and
 * returns the triangle count. dst needs 3 * tsr_tile_pattern_bound(n)
 * entries; dst NULL only counts. n must be even, 2..TSR_TILE_MAX. */
uint32_t tsr_tile_pattern_bound(uint32_t n);
uint32_t tsr_tile_pattern(uint32_t n, unsigned mask, uint32_t *dst);

/* The 16 patterns of one tile size, made once and shared by all tiles. */
typedef struct tsr_tile_patterns {
    uint32_t n;
    uint32_t count[16];      /* triangles of pattern m */
    const uint32_t *tri[16]; /* 3 * count[m] local vertex indices */
    uint32_t *storage;
    tsr_allocator alloc;
} tsr_tile_patterns;

tsr_status tsr_tile_patterns_init(tsr_tile_patterns *p, uint32_t n, const tsr_allocator *alloc);
void tsr_tile_patterns_free(tsr_tile_patterns *p);

/* ---- The surface interface ------------------------------------------ */

typedef struct tsr_qnode {
    uint32_t x, y;
    uint8_t level;
} tsr_qnode;

/* What a surface answers for the quadtree (../shared/DESIGN.md). All three
 * functions must be safe to call with any existing node, and:
 *  - evaluate(i, j): position at lattice point (i, j) within the extent,
 *    and its normal when `normal` is not NULL; false for no-data (a hole).
 *  - bounds(node): a box containing the node's part of the surface and of
 *    every tile the node may be drawn with; lo > hi when it has none.
 *  - error(node): a conservative geometric error: no point of the surface
 *    over the node lies farther than this from the node's tile, with any
 *    stitch mask, measured at the lattice points (vertically for a
 *    terrain); monotone (a parent's error >= its children's); INFINITY
 *    where the node must be refined (it covers no-data). */
typedef struct tsr_surface {
    void *user;
    uint32_t tile_n;   /* quads per tile side: even, 2..TSR_TILE_MAX */
    uint32_t levels;   /* depth of the tree; leaves at this level have spacing 1 */
    uint32_t extent_x; /* lattice extent, <= tile_n << levels */
    uint32_t extent_y;
    bool (*evaluate)(void *user, uint32_t i, uint32_t j, float pos[3], float normal[3]);
    void (*bounds)(void *user, tsr_qnode node, float lo[3], float hi[3]);
    float (*error)(void *user, tsr_qnode node);
    /* false: error() bounds a vertical displacement (a terrain); true: a
     * displacement in any direction (a parametric patch), which
     * tsr_camera_node_error projects with its worst obliquity. */
    bool error_isotropic;
} tsr_surface;

/* Smallest levels such that tile_n << levels covers both extents. */
uint32_t tsr_quadtree_levels_for(uint32_t tile_n, uint32_t extent_x, uint32_t extent_y);

/* ---- The restricted quadtree ----------------------------------------- */

/* A leaf of the cut. culled: outside the camera's view (still part of the
 * cut, so the mesh stays whole; a renderer skips it). morph: the tile's
 * geomorph weight in [0, 1], 1 meaning its odd vertices sit where the
 * parent tile would put them (see tsr_quadtree_vertex_morph). */
typedef struct tsr_qleaf {
    tsr_qnode node;
    uint8_t stitch; /* TSR_EDGE_* bits: neighbour one level coarser */
    uint8_t culled;
    float morph;
} tsr_qleaf;

typedef struct tsr_quadtree tsr_quadtree;

tsr_quadtree *tsr_quadtree_create(const tsr_surface *surface, const tsr_allocator *alloc);
void tsr_quadtree_destroy(tsr_quadtree *qt);

/* A refinement predicate: true to split the node. It is only asked about
 * nodes above the deepest level. `user` is the predicate's own. */
typedef bool (*tsr_refine_fn)(void *user, const tsr_surface *s, tsr_qnode node);

/* Selects a cut: refines from the root while refine() says so, then splits
 * leaves until edge neighbours differ by at most one level (2:1), then
 * computes stitch masks. Replaces the previous cut. O(nodes visited). */
tsr_status tsr_quadtree_select(tsr_quadtree *qt, tsr_refine_fn refine, void *user);

uint32_t tsr_quadtree_leaf_count(const tsr_quadtree *qt);
const tsr_qleaf *tsr_quadtree_leaves(const tsr_quadtree *qt);
/* Nodes refined by the balancing step alone in the last select. */
uint32_t tsr_quadtree_balance_splits(const tsr_quadtree *qt);
/* Whether a node is split (has children) in the current cut. */
bool tsr_quadtree_is_split(const tsr_quadtree *qt, tsr_qnode n);
/* Whether a node exists, i.e. overlaps the extent. */
bool tsr_quadtree_node_exists(const tsr_surface *s, tsr_qnode n);

/* Checks the 2:1 restriction from the leaves alone, independently of how
 * the cut was balanced: every leaf is painted onto the deepest level's
 * grid and edge-adjacent cells may differ by at most one level. Needs
 * 4^levels bytes; false also when out of memory. */
bool tsr_quadtree_leaves_balanced(const tsr_quadtree *qt);

/* Morton key of a node: level in the top byte, x and y interleaved below,
 * so keys of one level sort in Z order. */
uint64_t tsr_qnode_key(tsr_qnode n);

/* ---- Refinement criteria --------------------------------------------- */

/* View-independent: split while error(node) > tolerance. */
bool tsr_refine_tolerance(void *tolerance_ptr /* const double * */, const tsr_surface *s, tsr_qnode node);

/* A pinhole camera looking from eye to target with +z up (the view
 * direction must not be vertical), vertical field of view fovy_deg, a
 * viewport of width x height pixels and a near plane at distance near.
 * K = height / (2 tan(fovy/2)) pixels per unit at unit depth. */
typedef struct tsr_camera {
    double eye[3], target[3];
    double fovy_deg;
    double width, height;
    double near_dist;
    double pixel_error; /* tau: the screen-space error allowed, pixels */
    /* derived by tsr_camera_prepare: */
    double fwd[3], right[3], up[3], K, tan_x, tan_y;
} tsr_camera;

/* Computes the derived fields; false when the view is degenerate (eye at
 * target, non-positive sizes or fov). The screen's up is the projection
 * of +z, or of +y for a view straight up or down (a plan view). */
bool tsr_camera_prepare(tsr_camera *c);

/* Projects a point: screen position in pixels (x right, y down, origin at
 * the viewport's top-left corner) and depth along the view direction. */
void tsr_camera_project(const tsr_camera *c, const double p[3], double *sx, double *sy, double *depth);

/* The conservative screen-space error of a node's tile, in pixels, for a
 * displacement of at most error(node), vertical or in any direction as
 * s->error_isotropic says: 0 when the node's bounds
 * are outside the view frustum or behind the near plane. See quadtree.c
 * for why it bounds the projected error of every counted sample. */
double tsr_camera_node_error(const tsr_camera *c, const tsr_surface *s, tsr_qnode node);

/* The same error per unit of displacement, for a box [lo, hi]: the node's
 * error is this times error(node) (0 where tsr_camera_node_error gives 0).
 * For callers that keep it per node and ask again with other errors. */
double tsr_camera_box_factor(const tsr_camera *c, const float lo[3], const float hi[3], bool isotropic);

/* View-dependent: split while tsr_camera_node_error > pixel_error. */
bool tsr_refine_camera(void *camera /* const tsr_camera * (prepared) */, const tsr_surface *s, tsr_qnode node);

/* Marks leaves whose bounds lie outside the camera's frustum as culled and
 * sets each leaf's morph weight from its parent's screen error. */
void tsr_quadtree_apply_camera(tsr_quadtree *qt, const tsr_camera *c);

/* The geomorph weight of a tile vertex (local i, j of its leaf): the
 * leaf's morph for odd interior vertices, 0 for even vertices and for every
 * vertex on the tile's edges, so morphing never opens a crack. */
float tsr_quadtree_vertex_morph(const tsr_qleaf *leaf, uint32_t n, uint32_t i, uint32_t j);

/* ---- Mesh of a cut ---------------------------------------------------- */

/* Appends the mesh of the current cut to m (initialised; normals written
 * when m has them): every leaf's tile with its stitch pattern, lattice
 * points clamped to the extent, vertices welded by lattice point across
 * tiles, triangles with a no-data corner or a repeated (clamped) vertex
 * left out, and the lattice points no triangle uses (stitched away, or
 * only in such triangles) with them. Culled leaves are included unless
 * skip_culled. */
tsr_status tsr_quadtree_mesh(const tsr_quadtree *qt, bool skip_culled, tsr_mesh *m);

/* The same mesh as the renderer draws it with geomorphing (after
 * tsr_quadtree_apply_camera): each leaf's odd interior vertices moved by
 * its morph weight towards where its parent's tile puts them (the mean of
 * their two even neighbours along the parent's edge or union-jack
 * diagonal). Tile edges do not move, so the mesh is as conforming. The
 * heights lie between the leaf's and its parent's surfaces, so a sample's
 * screen error is at most (1 - w) tau + w e_p with e_p the parent's error
 * and w = 2 - e_p / tau: at most 1.25 tau. Normals (when m has them) are
 * the unmorphed ones. */
tsr_status tsr_quadtree_mesh_geomorphed(const tsr_quadtree *qt, bool skip_culled, tsr_mesh *m);

#ifdef __cplusplus
}
#endif
#endif
