/* triangulate.h: (included by tessellate.h) constrained triangulation of a
 * planar straight-line graph (PSLG): points, segments, hole seeds.
 *
 * Two methods return the same result type:
 *  - TSR_TRI_DELAUNAY: constrained Delaunay triangulation (cdt.h) with
 *    segment recovery, robust crossing splits, region removal, and
 *    optional conforming / quality refinement (Ruppert's algorithm with
 *    concentric-shell segment splitting, like Triangle's -D, -q, -a);
 *  - TSR_TRI_QUADTREE: a balanced quadtree subdivided until every cell is
 *    simple (at most one vertex, or one segment, or two boundary
 *    crossings), each cell triangulated by fixed rules; cells that cannot
 *    become simple within the depth limit fall back to the Delaunay path
 *    (reported in fallback_cells).
 *
 * The region kept (tsr_region) is decided from the constrained edges of
 * the final triangulation by flood fill, identically for both methods.
 *
 * Output vertices: every distinct input point first (exact duplicates are
 * merged; vertex_of_input maps input index to output index), then Steiner
 * points (segment intersections, refinement). Triangles counter-clockwise.
 * Every output edge that lies on an input segment is listed in edge[], with
 * the id of the input segment it came from (the lowest id where
 * overlapping collinear segments were merged). */
#ifndef TSR_TRIANGULATE_H
#define TSR_TRIANGULATE_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tsr_pslg {
    const double *xy; /* 2 per point */
    uint32_t nv;
    const uint32_t *seg; /* 2 point indices per segment (< nv) */
    uint32_t nseg;
    const double *holes; /* 2 per hole seed point; a seed exactly on a
                            segment (or on an input point) names no side:
                            it removes one of the regions it touches,
                            which one is unspecified (the two methods may
                            differ), so place seeds off the segments */
    uint32_t nholes;
} tsr_pslg;

typedef enum tsr_region {
    /* the whole convex hull of the points, minus the regions of hole
     * seeds (a seed's region: the triangles reachable from it without
     * crossing a segment) */
    TSR_REGION_HULL = 0,
    /* also remove what is reachable from outside the hull without
     * crossing a segment (Triangle's -p without -c) */
    TSR_REGION_ENCLOSED,
    /* keep what lies inside an odd number of closed segment loops:
     * counted by the segments crossed on the way in from outside (rings
     * with holes, nested islands); hole seeds also apply. An edge covered
     * by an even number of segments does not count. Where segments do
     * not close (a point met by an odd number of segment ends, each copy
     * counted), the count is the least on any way in, which features
     * closer than rounding can change: the quadtree method's fallback
     * cells may merge such features onto one edge, and then keep another
     * region than the Delaunay method. Closed input is not affected. */
    TSR_REGION_EVEN_ODD,
} tsr_region;

typedef enum tsr_tri_method { TSR_TRI_DELAUNAY = 0, TSR_TRI_QUADTREE } tsr_tri_method;

typedef struct tsr_tri_options {
    tsr_tri_method method;
    tsr_region region;
    /* Delaunay method: split segments (Steiner points on them) until every
     * edge, constrained or not, is Delaunay */
    bool conforming;
    /* quality refinement: minimum angle in degrees (0: none; above about
     * 34 termination is not guaranteed and max_steiner applies) */
    double min_angle;
    /* maximum triangle area (0: none) */
    double max_area;
    /* regional maximum areas (Delaunay method; Triangle's -a with a .poly's
     * regions): 3 per region, x, y and its bound (0 or less: none). A
     * region is the part of the domain reachable from its seed point
     * without crossing a segment (a later seed in the same part wins; a
     * seed on a segment or outside the domain names no part, or an
     * unspecified one of those it touches); a triangle there is refined to
     * the smaller of max_area and the region's bound. */
    const double *regions;
    uint32_t nregions;
    /* refinement stops after this many Steiner points (0: 20 * nv +
     * 100,000, plus 4 * domain area / max_area when max_area is set);
     * steiner_limited (and quality_limited) say so */
    uint32_t max_steiner;
    /* quadtree method: deepest level (0: 24) */
    uint32_t max_depth;
} tsr_tri_options;

/* What was built. Arrays are owned; free with tsr_triangulation_free. */
typedef struct tsr_triangulation {
    double *xy; /* 2 per output vertex */
    uint32_t nv;
    uint32_t *tri; /* 3 per triangle, counter-clockwise */
    uint32_t nt;
    uint32_t *edge;         /* 2 output vertex ids per constrained edge */
    uint32_t *edge_segment; /* input segment id per constrained edge */
    uint32_t nedge;
    uint32_t *vertex_of_input; /* pslg.nv entries */
    uint32_t input_vertices;   /* distinct input points: output [0, this) */
    uint32_t duplicates;       /* input points merged into an earlier equal one */
    uint32_t intersections;    /* segment crossings split at a new vertex */
    uint32_t steiner;          /* output vertices beyond the distinct inputs */
    uint32_t degenerate_segments; /* segments with both ends equal (ignored) */
    uint32_t fallback_cells;   /* quadtree: cells given to the Delaunay path */
    bool fell_back;            /* quadtree: the whole input went to Delaunay */
    const char *fallback_reason; /* static text, or NULL */
    bool quality_limited;      /* the bounds asked for are not met everywhere:
                                  refinement stopped at max_steiner
                                  (steiner_limited), got stuck (unrefined),
                                  or left triangles below the resolution of
                                  doubles (below_resolution) */
    bool steiner_limited;      /* refinement stopped at max_steiner */
    uint32_t unrefined;        /* triangles still bad and not exempt, and,
                                  when conforming, constrained edges still
                                  encroached, where refinement stopped (at
                                  max_steiner, or where rounding left no
                                  usable position for a new vertex, such as
                                  an edge with a flat triangle beyond it) */
    uint32_t small_angle_exempt; /* triangles below min_angle left because an
                                    input angle is smaller (terminator rule);
                                    the contract allows them */
    uint32_t below_resolution; /* triangles below min_angle left because they
                                  are below the resolution of doubles
                                  (tsr_tri_below_resolution: features closer
                                  than a few ulps that do not meet, where no
                                  vertex can be placed to mend them); they
                                  set quality_limited */
    double refined_area;       /* the area of the region refinement worked on
                                  (0 without min_angle or max_area) */
    double asked_triangles;    /* the triangles the area bounds ask for at
                                  least: the sum over the refined region of
                                  each triangle's area over its bound */
    tsr_allocator alloc;
} tsr_triangulation;

/* Refinement to a maximum area that would need more triangles than this
 * (the region's area over max_area), with no max_steiner given, is
 * refused (TSR_ERR_TOO_LARGE) rather than run out of memory. */
#define TSR_TRI_MAX_AREA_TRIANGLES 5e7

/* Triangulates in. On failure out is empty (nothing to free). Errors:
 * TSR_ERR_ARGUMENT for a coordinate that is not 0 or of magnitude in
 * [2^-128, 2^250) (non-finite, subnormal-small or so large the exact
 * predicates would overflow) or a segment index out of range (message
 * names it), TSR_ERR_TOO_LARGE for a max_area that asks for more than
 * TSR_TRI_MAX_AREA_TRIANGLES triangles without a max_steiner (message gives
 * the region's area), TSR_ERR_NOMEM. Input that has no triangle
 * (fewer than 3 distinct points, all collinear) is TSR_OK with nt = 0. */
tsr_status tsr_triangulate(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                           const tsr_allocator *alloc, tsr_error *err);
void tsr_triangulation_free(tsr_triangulation *t);

/* ---- Values carried to the output vertices ------------------------------- */

/* Values at every output vertex of out, a triangulation of in (vals: out->nv
 * rows of n doubles) from values at the input points (in_vals: in->nv rows
 * of n), as Triangle carries a .node file's attributes:
 *  - an input point keeps its own row (a point given twice: its first row);
 *  - a vertex the triangulator added takes the piecewise-linear interpolant
 *    of the input values over the input's own constrained Delaunay
 *    triangulation (the convex hull, no refinement): barycentric in the
 *    triangle that contains it, so linear along the piece of segment or
 *    edge it lies on;
 *  - a crossing of two segments (a vertex of that triangulation too) takes
 *    the value linear along the lower-numbered segment between the nearest
 *    input points on it (its own ends at the latest).
 * The result does not depend on how refinement placed or ordered its
 * vertices. The barycentric coordinates come from nearly exact areas, so
 * an affine field comes out affine to rounding even in slivers; each value
 * is kept within those it interpolates (a constant stays exact, a value
 * near the largest double does not round to infinity). A vertex
 * that rounding put just outside every triangle takes the values at the
 * nearest point of the nearest triangle's edges. n must be at least 1; in
 * must be the input out was made from. Errors: TSR_ERR_ARGUMENT (n = 0, or out not from in),
 * TSR_ERR_NOMEM. */
tsr_status tsr_tri_interpolate(const tsr_pslg *in, const double *in_vals, uint32_t n, const tsr_triangulation *out,
                               double *vals, const tsr_allocator *alloc, tsr_error *err);

/* The region of every triangle of t (region: t->nt entries) from seed
 * points (seeds: 2 per seed), as Triangle's regional attributes: a seed's
 * region is the triangles reachable from the one that contains it without
 * crossing a constrained edge; a triangle in the regions of several seeds
 * gets the last seed's index, one in none UINT32_MAX. A seed on an edge or
 * a vertex starts from one of the triangles there; a seed in no triangle
 * (outside, or in a hole) labels nothing. Errors: TSR_ERR_NOMEM. */
tsr_status tsr_tri_regions(const tsr_triangulation *t, const double *seeds, uint32_t nseeds, uint32_t *region,
                           const tsr_allocator *alloc, tsr_error *err);

/* ---- Independent checker ------------------------------------------------ */

/* What tsr_triangulation_check found. It uses only exact predicates, the
 * input and the output (none of the triangulator's code). */
typedef struct tsr_tri_check {
    uint32_t not_ccw;          /* triangles not strictly counter-clockwise */
    uint32_t bad_topology;     /* edges with more than two triangles, or
                                  two triangles using an edge the same way */
    uint32_t not_delaunay;     /* interior edges failing the exact incircle
                                  test (all edges when conforming; otherwise
                                  edges not on an input segment) */
    uint32_t missing_segments; /* input segments not a chain of output edges */
    uint32_t overlapping;      /* triangles overlapping (area mismatch) */
    double area, expected_area; /* expected_area NAN when not known */
    bool area_ok;
    long euler, expected_euler; /* expected LONG_MIN when not known */
    double min_angle;          /* degrees, smallest in the output */
    uint32_t below_min_angle;  /* triangles below opt->min_angle not
                                  excused by a small input angle, nor below
                                  the resolution of doubles and reported */
    uint32_t below_resolution_excused; /* triangles below opt->min_angle
                                  excused as below the resolution of doubles
                                  (tsr_tri_below_resolution), which the
                                  result reports (quality_limited, and at
                                  least this many in below_resolution) */
    uint32_t above_max_area;   /* triangles above opt->max_area */
    bool ok;
    char first_problem[256];   /* a sentence on the first failure */
} tsr_tri_check;

/* Is the triangle a, b, c below the resolution of doubles: is its height
 * over its longest edge less than 8 DBL_EPSILON times the largest
 * magnitude of its coordinates (8 to 16 units in the last place)? A vertex
 * placed to mend its angles would be rounded by a good part of its height;
 * such triangles arise where input features lie a few ulps apart without
 * meeting (a vertex or segment that close to a segment or hull edge), and
 * the angle bound cannot be met there at double resolution. The one definition used
 * by refinement (which leaves such triangles, counts them in
 * below_resolution and sets quality_limited) and by the checker (which
 * excuses them only when the result reports them). Orientation-agnostic;
 * thread-safe. */
bool tsr_tri_below_resolution(const double a[2], const double b[2], const double c[2]);

/* Checks out against in and opt (method, region, conforming, min_angle,
 * max_area). Returns TSR_OK when it could run (then res->ok is the
 * verdict), TSR_ERR_NOMEM otherwise. */
tsr_status tsr_triangulation_check(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *out,
                                   tsr_tri_check *res);

#ifdef __cplusplus
}
#endif
#endif
