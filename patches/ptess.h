/* ptess.h: adaptive, crack-free tessellation of a set of patches on the
 * restricted quadtree of tessellate/, and its independent measurement.
 *
 * The model. A tsr_pmodel is a list of *pieces*: surfaces over the unit
 * square (s, t) in [0,1]^2, each one quadtree. A piece belongs to a
 * *source*, the unit the user knows:
 *  - from a tsr_patch_set, a source is a patch of the set and its
 *    pieces are its Bézier pieces (tsr_patch_to_bezier), piece (a, b)
 *    covering the source's rectangle rect = {u0, u1, v0, v1} of the
 *    patch's own (u, v) parameters: u = u0 + s (u1 - u0), v likewise;
 *  - from a tsr_subd, a source is a patch (face, sub) of subd.h, with one
 *    piece over the whole [0,1]^2 (rect {0, 1, 0, 1}); a patch whose
 *    limit has no area (du x dv vanishes all over it: a cage face whose
 *    repeated vertices make its limit a curve, like 1 1 2 2 or 1 1 1 2,
 *    or a point, 1 1 1 1) is no source: no triangle could cover it
 *    without zero area, so it is left out (counted in flat_patches), and
 *    its curve or point is drawn only where the faces around it reach it.
 *
 * Links. Piece edges are numbered as in subd.h: 0 south (t = 0), 1 east
 * (s = 1), 2 north (t = 1), 3 west (s = 0), the parameter along an edge
 * running with s (south, north) or t (east, west). Two pieces are linked
 * along an edge where they share it:
 *  - pieces of one B-spline patch, by construction;
 *  - pieces of different patches of a set when their boundary rows of
 *    control points coincide, forwards or reversed, within
 *    TSR_PMODEL_LINK_TOL of the model's box diagonal, and their weights
 *    up to a common factor, the row of lower degree raised to the other's
 *    degree first (the .bpt teapot: body, lid, handle, spout rings; a
 *    plane's straight edge of degree 1 against a bicubic fillet's). So
 *    that pieces meet piece to piece, the pieces of a patch are cut not
 *    only at its own knots but at its neighbours': two patch edges (whole
 *    sides of the patches' domains) that coincide as curves, with their
 *    parameters in proportion (within the same distance at the ends and at
 *    7 points inside every span between the breakpoints of either side,
 *    forwards or reversed), give each other their breakpoints, repeated
 *    until no patch gains one (CAD files join faces whose knot vectors
 *    differ: one side with knots inserted, or of a higher degree). Edges
 *    that share only part of their curve do the same over that part, and
 *    each is cut where the part ends: one long edge against two or more
 *    shorter ones (a T-configuration: a sheet against a row of patches
 *    cut finer), or edges staggered along one curve. Such a part is found
 *    where an end of one edge lies on the other, inside it, within the
 *    distance (golden-section search from 5 samples of the edge), and
 *    the two edges meet at exactly two such points or shared ends; its
 *    parameters must be in proportion as above. Parts whose parameters
 *    are not in proportion (two rational parameterisations of one arc)
 *    stay unlinked and leave gaps (tsr_mesh_find_gaps finds them); so do
 *    all partial overlaps when sharing breakpoints through them passes
 *    the budget of 4 per breakpoint of the patches' own plus 1024, or
 *    makes more than 4 times their pieces plus 1024 (a brick wall of many
 *    staggered rows: tsr_pmodel_info.partial_unlinked);
 *    tsr_pmodel_info.conform_breaks counts the breakpoints so added;
 *  - subd patches as tsr_subd_patch_neighbours says (a quad edge meeting
 *    an N-gon links each half to one sub-patch).
 * A piece edge whose control points all coincide (within the same
 * tolerance: the teapot's lid top and bottom centre), or a subd patch
 * edge whose limit is one point at 9 samples (a cage face with a repeated
 * vertex, like 1 2 3 3), when it is the piece's only such edge, is *collapsed*: all its
 * points are one vertex and it takes no links. Pieces are oriented consistently through
 * their links (a piece whose (s, t) orientation disagrees with the first
 * piece of its connected part is *mirrored*: its triangles are emitted
 * reversed and its normals negated), so the welded mesh is oriented.
 *
 * The tessellation. Every piece has a quadtree of tiles of N quads with
 * max_level levels (lattice size N << max_level). N is the piece's own:
 * for a Bézier piece of an untrimmed source, of tile_n, tile_n + 2, ...,
 * 4 tile_n - 2 (at most TSR_TILE_MAX) the one whose selection has the
 * fewest quads, so rates N 2^l step by (N + 2) / N rather than by 2, or,
 * where that selection is one tile, tile_n / 2 (when even) with one level
 * more (none at depth 12) if the piece then needs fewer quads (a plane, or a cut piece of a
 * cylinder whose straight direction needs one quad: 2 x 2 quads, not
 * 4 x 4); for
 * a subd piece whose selection at tile_n has at most 16 tiles, tile_n or
 * tile_n / 2 (when even) with one level more (the same lattice, the same
 * points), whichever selection has fewer quads (a face near the
 * tolerance is often one tile of 2 x 2 quads where 4 x 4 ones would
 * split in four; larger trees keep tile_n, as a second selection there
 * costs more time than it saves triangles); for trimmed pieces tile_n.
 * A node's error delta is:
 *  - for a Bézier piece (polynomial or rational), a bound that holds: the
 *    node's Bézier sub-patch (blossoming) gives bounds M of the second
 *    derivatives' lengths (control-net differences as vectors; for
 *    rational pieces through the quotient rule with the smallest weight,
 *    about the centre of the sub-net's box, and where the weights are a
 *    product a_i b_j, as for surfaces of revolution, extrusions, tori
 *    and spheres, the smaller of that and a bound through the rational
 *    bases: rows and columns as curves about their own centres, and the
 *    mixed term from the net's mixed differences, zero on a cylinder),
 *    and linear interpolation on
 *    the tile's triangles is within (h_s^2 M_ss + 2 h_s h_t M_st + h_t^2
 *    M_tt) / 8 for its interior (right) triangles, and within a larger
 *    figure (ptess.c, shape_bounds) for a stitched triangle (base 2h on a
 *    tile edge); a child's bounds are at most a quarter of its parent's.
 *    A node is split while the interior figure is beyond the tolerance;
 *    after selection every stitched tile is checked with the stitched
 *    figure, and where it fails the coarse neighbour is split too (until
 *    none fails), so no point of any drawn triangle lies farther than
 *    delta from S at the same (s, t); bounds are the box of the
 *    sub-patch's control points (convex hull);
 *  - for a subd piece, an estimate: the same figures (interior, and
 *    stitched, checked the same way) with the second differences of the
 *    tile's vertices per coordinate for h^2 M, raised to the distance
 *    between the surface and the tile's cell at the centres of its four
 *    corner cells (a feature at a face corner, an extraordinary or
 *    creased vertex, narrower than the tile's spacing shows there and
 *    not in the differences); points are evaluated by Bfr, each lattice
 *    point once per run (parents, children, siblings and the mesh share
 *    them). Bounds are the box of those vertices padded by twice the
 *    estimate, within the face's box (tsr_subd_face_bounds). Not a
 *    proof: the measurement (tsr_ptess_measure) is the arbiter, and
 *    `tessera patch` re-tessellates the pieces it finds beyond the
 *    tolerance (piece_scale) until they hold (`tessera check patches` on
 *    OpenSubdiv's 81 Catmull-Clark shapes, 9 runs each: 28 of the 729
 *    runs needed more than one round, 125 pieces rescaled in all).
 * Refinement splits while delta > max_error (view-independent) or while
 * the screen error of delta exceeds the camera's pixel_error (any
 * direction of displacement, tsr_surface.error_isotropic). Each piece is
 * selected on its own: along a linked edge both sides sample the union
 * of the two sides' border samples. A border triangle of a tile whose
 * edge holds samples of the neighbour is split into a fan at them; every
 * part lies within the triangle in (s, t), so its interpolation error is
 * within the triangle's (the barycentric variances of a part are at most
 * the triangle's), and the bound stands (fan_triangles counts them).
 * Vertices are welded through the links (a lattice point of one side that
 * is a lattice point of the other is one vertex, evaluated once by the
 * lowest piece that owns it), collapsed edges become one vertex, and
 * triangles with a repeated vertex are dropped, so a closed model gives a
 * closed, oriented, conforming mesh.
 *
 * Trimmed sources (patches with trim loops, but for a lone loop along the
 * whole border: TSR_PMODEL_VOID_TRIM) are meshed differently: the
 * lattice points of their pieces' leaves that lie inside the trimmed
 * region, the linked neighbours' samples along linked edges, and the trim
 * loops, sampled so that the loop lies within
 * max_error of the true curve on the surface (for a camera: within the
 * pixel error at the camera's nearest distance), are triangulated in the
 * source's (u, v) by tsr_triangulate with the loops as constraints, and
 * the triangles of the trimmed region lifted: the innermost loop around a
 * triangle decides, an outer loop (OBJ `trim`) keeping it and a hole
 * (`hole`) removing it, and a triangle inside no loop is kept unless the
 * patch has an outer loop (so holes alone cut into the whole domain, a
 * repeated or overlapping hole removes the union, a hole reaching past the
 * outer loop adds nothing outside it, and islands inside holes stay).
 * Their error is measured, not bounded; edges across trim curves are not
 * matched with neighbours.
 */
#ifndef TSR_PTESS_H
#define TSR_PTESS_H

#include "patches/patches.h"
#include "patches/subd.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tsr_pmodel tsr_pmodel;

/* Builds the model of a patch set (which must outlive the model: trim
 * loops are read from it). TSR_ERR_ARGUMENT for NULL pointers,
 * TSR_ERR_EMPTY for a set without patches, TSR_ERR_TOO_LARGE beyond
 * 2^24 pieces, TSR_ERR_NOMEM. Two piece edges are linked (sampled alike,
 * their vertices welded) when their boundary control points coincide
 * within TSR_PMODEL_LINK_TOL of the model's box diagonal (after the
 * pieces are cut at the breakpoints of the patches sharing an edge:
 * Links, above), and an edge whose control points all lie that close
 * together is collapsed. An edge three patches share (a fin on a plate) is
 * linked to both others, which then sample it alike too; these links
 * orient no piece (no orientation agrees with both). */
#define TSR_PMODEL_LINK_TOL 1e-6
/* A patch whose trim loops are one outer loop around its whole domain,
 * nowhere farther inside than this fraction of the domain's sides (a CAD
 * file trims every face by its own border), and no hole is untrimmed: cut,
 * linked and meshed as the others (tsr_pmodel_info.void_loops counts
 * them). */
#define TSR_PMODEL_VOID_TRIM 1e-9
tsr_status tsr_pmodel_from_set(const tsr_patch_set *set, const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err);
/* The same with another distance for linking and collapsing, in model
 * units (CAD files leave gaps of 1e-6 to 1e-3 between faces that meet);
 * link_tol <= 0 or NaN: the default. A vertex shared by linked edges takes
 * one side's surface point, so the other side's error may grow by up to
 * the gap: the measurement sees it. */
tsr_status tsr_pmodel_from_set_tol(const tsr_patch_set *set, double link_tol, const tsr_allocator *alloc,
                                   tsr_pmodel **out, tsr_error *err);

/* Options of tsr_pmodel_from_set_opts (zeroed: tsr_pmodel_from_set).
 *  - link_tol: as tsr_pmodel_from_set_tol (<= 0: the default).
 *  - split_error: > 0, the max_error the model will be tessellated at
 *    (model units). Every piece's quadtree samples it alike along s and
 *    t, so a piece curved one way and straight the other (an extrusion,
 *    a cylinder, a fillet) gets as many samples along its straight
 *    direction as along its curved one. With split_error, a knot span is
 *    cut into k equal pieces across the curved direction where that
 *    needs fewer triangles by the estimate below (by half at least):
 *    with M = {M_ss, M_st, M_tt}, the second-derivative bounds of the
 *    pieces of the span (Tessellation, below), a piece cut into k along
 *    s needs about n = max(tile, sqrt((M_ss/k^2 + 2 M_st/k + M_tt) / (8
 *    split_error))) samples a side (tile: the smallest tile a one-tile
 *    piece may take, split_tile / 2 when even, else split_tile), k * n^2
 *    quads in all (likewise along
 *    t); k <= 64. From that k, fewer pieces are taken while the pieces'
 *    own bounds (a rational piece's fall faster than 1/k^2), with each
 *    piece's tiles counted whole, say they cost no more quads. The cuts are breakpoints like knots, shared with the
 *    neighbours (Links, above), so the mesh stays conforming; coarser
 *    bounds than split_error leave more triangles than needed, finer
 *    ones as many as without. The cuts are kept only where the whole
 *    model's estimate (the pieces' quads, uncut) falls by a tenth at
 *    least (a neighbour curved the other way takes the cuts as well and
 *    may cost more than they save), and trimmed patches are neither cut
 *    nor given cuts (their (u, v) triangulation wants their lattice
 *    points evenly spread). NaN or <= 0: no cuts.
 *  - split_tile: the tile size the runs will use (0: 4). */
typedef struct tsr_pmodel_set_options {
    double link_tol;
    double split_error;
    uint32_t split_tile;
} tsr_pmodel_set_options;
tsr_status tsr_pmodel_from_set_opts(const tsr_patch_set *set, const tsr_pmodel_set_options *opt,
                                    const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err);

/* Builds the model of a subdivision surface (which must outlive the
 * model): one source per patch (face, sub) of every face with a limit
 * surface, numbered face by face, except the patches whose limit has no
 * area (above; tsr_pmodel_info.flat_patches counts them): |du x dv| at
 * most 1e-10 of the squared diagonal of tsr_subd_face_bounds plus 1e-20
 * of the squared diagonal of all faces' bounds, at every point of a 7 x 7
 * grid inside the patch. Links to them are dropped. Errors as
 * above (TSR_ERR_EMPTY when no face has a limit surface with area). Cost:
 * one tsr_subd_eval with derivatives per patch with area (49 for one
 * without), besides 36 for the collapsed edges. */
tsr_status tsr_pmodel_from_subd(const tsr_subd *subd, const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err);

void tsr_pmodel_destroy(tsr_pmodel *m);

typedef struct tsr_pmodel_info {
    uint32_t sources, pieces;
    uint32_t links;           /* linked piece edges (each side counted) */
    uint32_t collapsed_edges; /* piece edges collapsed to a point */
    uint32_t mirrored;        /* pieces flipped to agree with their neighbours */
    uint32_t trimmed_sources;
    uint32_t void_loops;   /* trim loops that trim nothing (TSR_PMODEL_VOID_TRIM): their patches untrimmed */
    uint32_t flat_patches; /* subd patches left out: their limit has no area */
    uint32_t conform_breaks;   /* breakpoints added to patches of a set where a neighbour
                                  sharing all or part of an edge has them (Links, above) */
    uint32_t partial_unlinked; /* pairs of edges sharing part of their curve left unlinked:
                                  sharing breakpoints through them passed its budget (4 per
                                  breakpoint of the patches' own plus 1024, and 4 times their
                                  pieces plus 1024; staggered rows spreading each row's
                                  through all), so only whole edges share them */
    uint32_t split_breaks;   /* breakpoints added across curved directions (split_error) */
    double lo[3], hi[3];   /* box of the model */
    bool own_alloc;        /* made with a caller's allocator, or from a tsr_subd that was
                              (tsr_subd_has_allocator): evaluating may call it */
} tsr_pmodel_info;

void tsr_pmodel_get_info(const tsr_pmodel *m, tsr_pmodel_info *info);

/* What a source is: for a set, patch = its index and sub = 0; for a subd,
 * (face, sub). domain: the source's (u, v) parameter range {u0, u1, v0,
 * v1}. first_piece, pieces_u, pieces_v: its pieces are first_piece + b *
 * pieces_u + a. false for src out of range. */
typedef struct tsr_psource_info {
    uint32_t patch, sub;
    double domain[4];
    uint32_t first_piece, pieces_u, pieces_v;
    bool trimmed, mirrored;
} tsr_psource_info;

bool tsr_pmodel_source_info(const tsr_pmodel *m, uint32_t src, tsr_psource_info *info);

/* The true surface of source src at (u, v) of its domain (clamped onto
 * it): position and, when normal is not NULL, the unit normal as the mesh
 * orients it (negated for a mirrored source). Evaluated by the source
 * itself (tsr_patch_eval or tsr_subd_eval), independently of the pieces;
 * the oracle of tsr_ptess_measure. TSR_ERR_ARGUMENT for src out of range. */
tsr_status tsr_pmodel_eval(const tsr_pmodel *m, uint32_t src, double u, double v, double pos[3], double normal[3]);

/* Positions only, as tsr_pmodel_eval, of count points of source src
 * (uv: u, v each; pos: 3 each), the source prepared once for them all
 * (a subdivision face's Bfr surface): what a caller evaluating many points
 * of one source, or sources on several threads, should use.
 * TSR_ERR_ARGUMENT for src out of range or NULL arrays with count > 0. */
tsr_status tsr_pmodel_eval_points(const tsr_pmodel *m, uint32_t src, const double *uv, uint32_t count, double *pos);

/* The parameters strictly inside source src's domain, along u (axis 0)
 * or v (axis 1), where its surface may crease: the knots of a B-spline or
 * NURBS source of multiplicity at least its degree that way (the surface
 * is only C0 there, a kink unless its control points line up). Up to cap
 * values go to out (which may be NULL when cap is 0), ascending; returns
 * how many there are (0 for Bézier and subdivision sources, or src out of
 * range). */
uint32_t tsr_pmodel_source_kinks(const tsr_pmodel *m, uint32_t src, int axis, double *out, uint32_t cap);

/* Options of tsr_ptess_run. Zero-initialised fields take the defaults. */
typedef struct tsr_ptess_options {
    /* View-independent: the largest distance allowed between S(u, v) and
     * the mesh's point at the same (u, v), in model units. Used when
     * camera is NULL; must then be positive. */
    double max_error;
    /* View-dependent: a prepared camera (tsr_camera_prepare) whose
     * pixel_error is the screen error allowed. */
    const tsr_camera *camera;
    uint32_t tile_n;    /* quads per tile side, even, 2..TSR_TILE_MAX; 0: 4. Bézier pieces
                           choose theirs in tile_n .. 4 tile_n - 2 (one-tile ones also
                           tile_n / 2), small subd trees tile_n or tile_n / 2 (see above) */
    uint32_t max_level; /* quadtree depth per piece, 1..12; 0: 10 */
    bool normals;       /* per-vertex normals of the true surface */
    bool fixed_tile;    /* every piece's tiles are tile_n quads a side (no choice: a uniform
                           tessellation at one tile per piece, as `tessera bench patch` runs) */
    /* Optional per-piece factor (0 < f <= 1) on the tolerance (max_error
     * or pixel_error), for re-tessellating pieces that measured beyond it;
     * NULL: all 1. */
    const double *piece_scale;
} tsr_ptess_options;

/* The tessellation. The mesh is welded; triangle k lies on source
 * tri_source[k] and its corners have parameters tri_uv[6k .. 6k+5] (u, v
 * of each corner, in that source's domain), so the mesh's point at any
 * (u, v) of a source is found by interpolation in its triangles. */
typedef struct tsr_ptess_result {
    tsr_mesh mesh;
    uint32_t *tri_source;
    double *tri_uv;
    uint32_t leaves;        /* tiles over all pieces */
    uint32_t passes;        /* selection rounds: 1, and one more each time stitched tiles
                               beyond the bound split their coarse neighbours */
    uint32_t evaluations;   /* surface points evaluated (vertices of the mesh and error estimates;
                               a subd piece's lattice point once per run, as the selection's
                               tiles and the mesh share it) */
    uint32_t fan_triangles; /* triangles added by splitting border triangles at a linked
                               neighbour's samples (linked edges of different rates) */
    double bound;           /* a bound of delta over the leaves of Bézier pieces, model units:
                               the largest of the leaves' figures for their tiles as drawn
                               (interior, or stitched along the stitched edges) */
    double seconds;
    tsr_allocator alloc;
} tsr_ptess_result;

/* Tessellates m into *out (zeroed first; free with tsr_ptess_result_free
 * also after a failure). TSR_ERR_ARGUMENT (err says which) for NULL
 * pointers, a non-positive or non-finite max_error without camera or
 * pixel_error with one, a
 * tile_n or max_level out of range, a piece_scale outside (0, 1];
 * TSR_ERR_TOO_LARGE when the mesh would pass 2^32 - 2 vertices or
 * triangles; TSR_ERR_NOMEM. A trimmed source whose triangulation fails
 * gives that error naming the patch. Runs may share m, also from several
 * threads at once: the tile patterns a run makes are kept with m (made
 * with m's allocator, freed by tsr_pmodel_destroy) and reused. */
tsr_status tsr_ptess_run(const tsr_pmodel *m, const tsr_ptess_options *opt, const tsr_allocator *alloc,
                         tsr_ptess_result *out, tsr_error *err);

void tsr_ptess_result_free(tsr_ptess_result *r);

/* ---- Normals at creases ------------------------------------------------- */

/* The welded mesh has one normal per vertex, so where surfaces meet at an
 * angle (an infinitely sharp subdivision crease or corner, the faces of a
 * box of patches, a B-spline's knot of full multiplicity) one side's
 * normal would be drawn on both, and shading would smear across the
 * crease. This makes a copy of r's mesh (r made with
 * tsr_ptess_options.normals) for drawing. A vertex may sit on a crease
 * where triangles of several sources share it, or where it lies on a kink
 * of its source (tsr_pmodel_source_kinks) with triangles on either side.
 * There each side's normal is evaluated once (tsr_pmodel_eval at the
 * (u, v) of its first corner, moved a hair, 1e-9 of the domain, off a kink
 * towards its triangle), and the sides are grouped, each joining the
 * first group whose first normal is within crease_deg degrees of its own.
 * Each group gets its own vertex (the first group keeps the vertex's
 * index, the others are appended, at the same position), with the unit
 * mean of the group's normals, and the group's corners use it. Other
 * vertices keep their normals; positions, uvs and triangles are r's, so
 * welding by index is given up at creases only. crease_deg in [0, 180];
 * 180 splits nothing (such a vertex gets the mean of its sides' normals).
 * A side is a source, and a side of one of its kinks: where a closed
 * source meets itself (the seam of a periodic surface) it is one side,
 * never split.
 * *added (may be NULL): the vertices appended. out is zeroed first and
 * left empty on failure. TSR_ERR_ARGUMENT (err says which) for NULL
 * pointers, a result without normals, or crease_deg out of range;
 * TSR_ERR_TOO_LARGE past 2^32 - 2 vertices; TSR_ERR_NOMEM; an evaluation's
 * error, naming the source. */
tsr_status tsr_ptess_crease_normals(const tsr_pmodel *m, const tsr_ptess_result *r, double crease_deg,
                                    const tsr_allocator *alloc, tsr_mesh *out, uint32_t *added, tsr_error *err);

/* ---- Measurement (the independent oracle) -------------------------------- */

/* What tsr_ptess_measure found. error: the largest distance between
 * S(u, v) (tsr_pmodel_eval) and the mesh's point at the same (u, v) (the
 * welded positions of the mesh, interpolated linearly in the triangle of
 * that source containing (u, v)), in model units, or in pixels between
 * their projections when a camera is given (samples with both points
 * beyond the near plane and one inside the viewport). */
typedef struct tsr_ptess_measure_result {
    double max_error, rms_error;
    uint64_t samples;          /* samples measured */
    uint64_t uncovered;        /* samples of untrimmed sources in no triangle: gaps (must be 0) */
    uint64_t trimmed_out;      /* samples of trimmed sources in no triangle (outside the trimmed region) */
    uint32_t worst_source;
    double worst_uv[2];
    double *source_error;      /* per source max error (num sources), or NULL when not asked */
} tsr_ptess_measure_result;

/* Measures r against m at a grid of samples over every source, spread
 * evenly over its (u, v) domain, ends included: (per_side pieces_u) x
 * (per_side pieces_v) points, the density of per_side x per_side per piece
 * (measure.c says why not per piece), thinned where that is more than 64
 * per triangle of the source's mesh, but never below per_side x per_side
 * per source, plus the midpoint of every triangle edge. The mesh's positions are floats, so expect rounding of a few
 * ulps of the coordinates' magnitude in the figures. camera: NULL for model units. per_source_error: when true, fills
 * out->source_error (allocated with alloc; caller frees with tsr_free).
 * Independent of how r was built: it reads only the mesh, tri_source,
 * tri_uv and tsr_pmodel_eval_points. With some 10^5 samples or more,
 * alloc NULL and a model made without a caller's allocator
 * (tsr_pmodel_info.own_alloc), the sources are measured on a thread per
 * core, else on the calling thread alone; each source is measured on its
 * own and the figures merged in source order, so they do not depend on
 * the threads. TSR_ERR_ARGUMENT for NULL pointers or per_side < 2,
 * TSR_ERR_NOMEM. */
tsr_status tsr_ptess_measure(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t per_side,
                             const tsr_camera *camera, bool per_source_error, const tsr_allocator *alloc,
                             tsr_ptess_measure_result *out);

/* As tsr_ptess_measure, telling progress (when not NULL) the fraction of
 * the sources measured so far, now and then, always from the calling
 * thread. */
tsr_status tsr_ptess_measure_progress(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t per_side,
                                      const tsr_camera *camera, bool per_source_error, const tsr_allocator *alloc,
                                      void (*progress)(void *user, double fraction), void *user,
                                      tsr_ptess_measure_result *out);

#ifdef __cplusplus
}
#endif
#endif
