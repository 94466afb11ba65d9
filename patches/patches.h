/* patches.h: parametric surfaces. Tensor-product Bézier, B-spline and
 * rational B-spline (NURBS) patches behind one tagged type, their
 * evaluation (position, first derivatives, unit normal), bounds, de
 * Casteljau splitting and conversion to Bézier pieces; trimming curves;
 * and the loaders of the module's inputs: Bézier patch files (.bpt), OBJ
 * free-form surfaces (with trim and hole loops) and polygon OBJ cages
 * for subdivision surfaces (patches/subd.h).
 *
 * Conventions of this header:
 *  - Control nets are stored row by row: point (i, j), the i-th along u
 *    and the j-th along v, is ctrl[3 * (j * count_u + i)] (x, y, z), its
 *    weight weights[j * count_u + i]. This is the order of OBJ's `surf`
 *    (u varies fastest) and of .bpt files.
 *  - Everything is double except the legacy float tsr_bezier_patch.
 *  - The normal is (S_u x S_v) / |S_u x S_v|: right-handed in (u, v). It is
 *    whatever side that is; nothing here re-orients a patch.
 *  - Patches and curves are views: they borrow their arrays, which must
 *    outlive every call that reads them. Functions that take a const
 *    patch never write to it, so one patch may be evaluated from several
 *    threads at once; no function keeps global state.
 *  - Functions that can fail return tsr_status; those that take a
 *    tsr_error (which may be NULL) fill it with a message naming the
 *    file and line, or the patch element, at fault.
 */
#ifndef TSR_PATCHES_H
#define TSR_PATCHES_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

/* ---- Legacy float Bézier evaluator ---------------------------------------- */

#define TSR_BEZIER_MAX_DEGREE 7

/* A Bézier patch of degree (du, dv), 1 <= du, dv <= TSR_BEZIER_MAX_DEGREE,
 * with (du+1)*(dv+1) float control points stored row by row (point (i, j)
 * at ctrl[3 * (j * (du+1) + i)]), over (u, v) in [0,1]^2. */
typedef struct tsr_bezier_patch {
    int du, dv;
    const float *ctrl; /* 3 * (du+1) * (dv+1) floats, borrowed */
} tsr_bezier_patch;

/* Position and first derivatives at (u, v) by de Casteljau's algorithm,
 * in double. du_out and dv_out may be NULL. Returns TSR_ERR_ARGUMENT for a
 * degree outside 1..TSR_BEZIER_MAX_DEGREE. Thread-safe; no allocation. */
tsr_status tsr_bezier_eval(const tsr_bezier_patch *p, double u, double v, double pos[3], double du_out[3],
                           double dv_out[3]);

/* ---- Patches ---------------------------------------------------------------- */

/* Degrees 1..TSR_PATCH_MAX_DEGREE in each direction. */
#define TSR_PATCH_MAX_DEGREE 7
/* The most control points a B-spline patch may have along one direction,
 * and in all (keeps every index computation far from overflow). */
#define TSR_PATCH_MAX_COUNT (1u << 20)
#define TSR_PATCH_MAX_POINTS (1u << 26)
/* Numeric limits that keep every evaluation finite (positions, first
 * derivatives; see tsr_patch_eval): coordinates, knots and domain ends
 * within +-TSR_PATCH_MAX_ABS, weights within [TSR_PATCH_MIN_WEIGHT,
 * TSR_PATCH_MAX_WEIGHT], and every non-empty knot span and every domain
 * at least TSR_PATCH_MIN_SPAN wide. Real data sits far inside them. */
#define TSR_PATCH_MAX_ABS 1e30
#define TSR_PATCH_MIN_WEIGHT 1e-20
#define TSR_PATCH_MAX_WEIGHT 1e20
#define TSR_PATCH_MIN_SPAN 1e-30
/* The most control points of one Bézier net: (MAX_DEGREE + 1)^2. */
#define TSR_BEZIER_MAX_POINTS ((TSR_PATCH_MAX_DEGREE + 1) * (TSR_PATCH_MAX_DEGREE + 1))

typedef enum tsr_patch_kind {
    /* Bernstein basis over the domain: count = degree + 1 each way, no
     * knots. Rational when weights is not NULL. */
    TSR_PATCH_BEZIER = 0,
    /* Polynomial B-spline over knots_u x knots_v; weights must be NULL. */
    TSR_PATCH_BSPLINE = 1,
    /* Rational B-spline: a B-spline with weights (not NULL). */
    TSR_PATCH_NURBS = 2
} tsr_patch_kind;

/* A tensor-product patch (a view: every array is borrowed).
 *
 *   S(u, v) = sum_ij N_i(u) M_j(v) w_ij P_ij / sum_ij N_i(u) M_j(v) w_ij
 *
 * with w_ij = 1 for polynomial patches; N, M are the Bernstein polynomials
 * of the domain (Bézier) or the B-spline basis of the knot vectors.
 *
 * Fields:
 *  - degree_u, degree_v: 1..TSR_PATCH_MAX_DEGREE.
 *  - count_u, count_v: control points along u and v: degree + 1 for a
 *    Bézier patch; at least degree + 1 and at most TSR_PATCH_MAX_COUNT for
 *    a B-spline, with count_u * count_v <= TSR_PATCH_MAX_POINTS.
 *  - ctrl: 3 * count_u * count_v doubles, row by row (point (i, j) at
 *    3 * (j * count_u + i)), within +-TSR_PATCH_MAX_ABS.
 *  - weights: NULL for a polynomial patch; else count_u * count_v weights
 *    in [TSR_PATCH_MIN_WEIGHT, TSR_PATCH_MAX_WEIGHT] (same order). Positive
 *    weights keep the convex hull property that tsr_patch_bounds relies
 *    on.
 *  - knots_u, knots_v: B-spline and NURBS only (NULL for Bézier):
 *    count + degree + 1 non-decreasing values each, within
 *    +-TSR_PATCH_MAX_ABS, any multiplicities up to degree + 1 (clamped or
 *    unclamped alike), every non-empty span at least TSR_PATCH_MIN_SPAN,
 *    with knots[degree] < knots[count] (a non-empty parameter range).
 *  - u0, u1, v0, v1: the domain, the part of (u, v) the patch covers.
 *    All four zero means the natural one: [0,1]^2 for a Bézier patch,
 *    [knots_u[degree_u], knots_u[count_u]] x (the same in v) for a
 *    B-spline. Otherwise u0 < u1 and v0 < v1, within +-TSR_PATCH_MAX_ABS
 *    and at least TSR_PATCH_MIN_SPAN wide; for a B-spline within the
 *    natural range. For a Bézier patch the domain is the
 *    interval the Bernstein basis is stretched over: the patch over
 *    [2, 3] is the same surface as over [0, 1], reparameterised.
 */
typedef struct tsr_patch {
    tsr_patch_kind kind;
    int degree_u, degree_v;
    uint32_t count_u, count_v;
    const double *ctrl;
    const double *weights;
    const double *knots_u;
    const double *knots_v;
    double u0, u1, v0, v1;
} tsr_patch;

/* Checks every rule of tsr_patch above, O(control points + knots).
 * Returns TSR_OK, or TSR_ERR_ARGUMENT with err naming the first broken
 * rule ("patch: degree_u 8 is outside 1..7", "patch: knots_u[5] = 2 is
 * below knots_u[4] = 3", "patch: weight 7 is 0, outside [1e-20, 1e20]").
 * For a patch that passes, tsr_patch_eval's positions and derivatives
 * are finite.
 * p may not be NULL. Thread-safe; no allocation. */
tsr_status tsr_patch_check(const tsr_patch *p, tsr_error *err);

/* The effective domain {u0, u1, v0, v1} (the natural one when the fields
 * are all zero). Assumes the cheap checks of tsr_patch_eval pass; for a
 * patch that fails them, writes {0, 1, 0, 1} and returns
 * TSR_ERR_ARGUMENT. */
tsr_status tsr_patch_domain(const tsr_patch *p, double dom[4]);

/* Evaluates p at (u, v): position pos, first partial derivatives du_out
 * = dS/du and dv_out = dS/dv (in the patch's units per unit of its own
 * parameters), and the unit normal (du x dv normalised). Any output may
 * be NULL. (u, v) outside the domain is clamped onto it; NaN reads as the
 * domain's lower end.
 *
 * At a point where du x dv vanishes (a collapsed edge, as at the Utah
 * teapot's lid top and bottom, a pole, a corner where two edges are
 * parallel) the normal is the limit of the normals at points approaching
 * it along the direction to the domain's centre: the first non-vanishing
 * term of the Taylor expansion of du x dv there, from the second
 * derivatives; failing that, the normal at points moved 1e-6, 1e-4, then
 * 1e-2 of the domain towards its centre or a corner. "Vanishing" is
 * relative: |du x dv| scaled by the knot span is below 1e-10 of the
 * squared size of the span's control points. Only a patch collapsed to a
 * curve or a point around (u, v) has no normal; it gets (0, 0, 1).
 * Normals are never NaN or zero, whatever the patch. Positions and
 * derivatives are finite for a patch that passes tsr_patch_check (they
 * may overflow for one beyond its numeric limits).
 *
 * Returns TSR_ERR_ARGUMENT (outputs untouched) for a patch failing the
 * cheap checks: a kind, degree or count out of range, a NULL array that
 * the kind needs, a weights array on a polynomial B-spline, or, among the
 * O(degree) knots and weights the evaluation reads, a decreasing knot,
 * an empty span or a weight that is not positive. A patch that passes
 * tsr_patch_check never fails here. Thread-safe; no allocation; cost
 * O(degree_u * degree_v) after an O(log count) knot search. */
tsr_status tsr_patch_eval(const tsr_patch *p, double u, double v, double pos[3], double du_out[3], double dv_out[3],
                          double normal[3]);

/* A box [lo, hi] containing the patch over its domain: the bounding box of
 * the control points whose basis functions do not vanish on the domain
 * (all of them for a Bézier patch). Conservative by the convex hull
 * property, which holds for rational patches with positive weights.
 * TSR_ERR_ARGUMENT for a patch failing tsr_patch_eval's cheap checks.
 * O(control points). */
tsr_status tsr_patch_bounds(const tsr_patch *p, double lo[3], double hi[3]);

/* Splits a Bézier patch at t (strictly inside its domain along `axis`: 0
 * splits at u = t, 1 at v = t) by de Casteljau's algorithm (in
 * homogeneous coordinates when rational). The halves are Bézier patches
 * of the same degrees over [u0, t] and [t, u1] (or in v) written as views
 * into lo_ctrl / hi_ctrl (3 * count_u * count_v doubles each) and, for a
 * rational patch, lo_weights / hi_weights (count_u * count_v each; not
 * read otherwise and may be NULL). The output arrays may be p's own
 * (splitting in place), and lo/hi may be p. Exact in exact arithmetic;
 * the halves evaluate as the parent does to rounding.
 * TSR_ERR_ARGUMENT for a non-Bézier or invalid patch, an axis other than
 * 0 or 1, t not strictly inside, or a NULL output. */
tsr_status tsr_patch_split(const tsr_patch *p, int axis, double t, tsr_patch *lo, double *lo_ctrl, double *lo_weights,
                           tsr_patch *hi, double *hi_ctrl, double *hi_weights);

/* The spans of p along `axis` (0: u, 1: v) within its domain: the
 * breakpoints b[0] = u0 < b[1] < ... < b[n] = u1, where b[1..n-1] are the
 * distinct knots strictly inside the domain (none for a Bézier patch).
 * Writes min(n + 1, cap) breakpoints to breaks (which may be NULL with
 * cap 0) and returns n, the number of spans; 0 for a patch failing the
 * cheap checks or an axis other than 0 or 1. O(count). */
uint32_t tsr_patch_spans(const tsr_patch *p, int axis, double *breaks, uint32_t cap);

/* The Bézier patch equal to p over [ua, ub] x [va, vb], a rectangle that
 * lies in p's domain with no knot strictly inside (for example two
 * consecutive breakpoints of tsr_patch_spans in each direction; for a
 * Bézier patch any sub-rectangle). Its control points are the blossom
 * values S(ua^(p-k) ub^k ; va^(q-l) vb^l), which is what inserting ua,
 * ub, va and vb up to multiplicity degree by Boehm's algorithm leaves
 * over that span, computed locally (no scratch memory, unclamped knots
 * alike). Writes 3 * (degree_u+1) * (degree_v+1) doubles to ctrl and, for
 * a rational p, (degree_u+1) * (degree_v+1) weights to weights (not read
 * otherwise; may be NULL then), and sets *piece to a Bézier view of them
 * with domain [ua, ub] x [va, vb].
 * TSR_ERR_ARGUMENT for an invalid patch, an empty or inverted rectangle,
 * one leaving the domain or containing a knot, or a NULL output. */
tsr_status tsr_patch_bezier_piece(const tsr_patch *p, double ua, double ub, double va, double vb, double *ctrl,
                                  double *weights, tsr_patch *piece);

/* All Bézier pieces of p, one per pair of spans (tsr_patch_spans): *count
 * is set to spans_u * spans_v. With pieces NULL nothing else is done (the
 * size query). Otherwise cap must be at least *count: piece (a, b), the
 * a-th span in u and b-th in v, goes to pieces[b * spans_u + a], its
 * control points to ctrl + 3 * N * (b * spans_u + a) and its weights (for
 * a rational p; weights may be NULL otherwise) to weights + N * (same),
 * N = (degree_u+1) * (degree_v+1). A Bézier p gives one piece, a copy.
 * Pieces pass tsr_patch_check, except that where the domain ends closer
 * than TSR_PATCH_MIN_SPAN to a knot the sliver piece between them is
 * narrower than that (its derivatives lose accuracy).
 * TSR_ERR_ARGUMENT (nothing written) for an invalid patch, cap too small
 * or NULL arrays; count may not be NULL. */
tsr_status tsr_patch_to_bezier(const tsr_patch *p, tsr_patch *pieces, uint32_t cap, double *ctrl, double *weights,
                               uint32_t *count);

/* ---- Trimming curves -------------------------------------------------------- */

/* A planar (u, v) curve of the parameter space of a patch: a B-spline of
 * degree 1..TSR_PATCH_MAX_DEGREE with count >= degree + 1 points (2
 * doubles each: u, v), knots as a patch's (count + degree + 1, non-
 * decreasing, knots[degree] < knots[count]) and, when rational, count
 * positive weights (NULL otherwise), within the numeric limits of patches
 * above. Its parameter range is [knots[degree],
 * knots[count]]. A Bézier curve is the B-spline with knots t0 (degree + 1
 * times), t1 (degree + 1 times). A view: every array is borrowed. */
typedef struct tsr_curve2 {
    int degree;
    uint32_t count;
    const double *ctrl;
    const double *weights;
    const double *knots;
} tsr_curve2;

/* Checks every rule above; TSR_ERR_ARGUMENT with err naming the first
 * broken one ("curve: knots[3] = 1 is below knots[2] = 2"). */
tsr_status tsr_curve2_check(const tsr_curve2 *c, tsr_error *err);

/* Point uv (and derivative d, may be NULL) at parameter t, clamped to
 * the parameter range. TSR_ERR_ARGUMENT as tsr_patch_eval's cheap checks.
 * Thread-safe; no allocation. */
tsr_status tsr_curve2_eval(const tsr_curve2 *c, double t, double uv[2], double d[2]);

/* One piece of a trim loop: curve `curve` of the set from parameter t0 to
 * t1 (t0 > t1 runs the curve backwards). */
typedef struct tsr_trim_segment {
    uint32_t curve;
    double t0, t1;
} tsr_trim_segment;

/* A closed loop in a patch's (u, v) domain, its segments in order, each
 * ending where the next begins (else a straight edge joins them). Outer loops (OBJ `trim`) keep the part of
 * the domain inside them, holes (OBJ `hole`) remove the part inside. */
typedef struct tsr_trim_loop {
    uint32_t patch; /* the patch it trims */
    bool hole;
    uint32_t first_segment, num_segments; /* into the set's segments */
    uint32_t line;                        /* the file's line of its statement (0: unknown) */
    /* the file listed its segments out of order or some backwards; the
     * loader put them end to start (the OBJ loader, up to 64 segments,
     * when each step has one segment to go on with) */
    bool reordered;
} tsr_trim_loop;

/* ---- Patch sets (loaded files) ---------------------------------------------- */

/* What a loader makes of a file: patches, their trim loops and the
 * curves these use. Patch i's loops are loops[first_loop[i] ..
 * first_loop[i+1]) (first_loop has num_patches + 1 entries; loops are
 * sorted by patch). Every patch passes tsr_patch_check and every curve
 * tsr_curve2_check; every segment's curve exists and its t0, t1 lie in the
 * curve's parameter range. The views point into `values`, which with the
 * other arrays belongs to the set and is freed by tsr_patch_set_free.
 * Fields may be read freely; treat them as read-only. */
typedef struct tsr_patch_set {
    uint32_t num_patches;
    tsr_patch *patches;
    uint32_t *first_loop;
    uint32_t num_loops;
    tsr_trim_loop *loops;
    uint32_t num_segments;
    tsr_trim_segment *segments;
    uint32_t num_curves;
    tsr_curve2 *curves;
    /* Statements read but not used (OBJ: 3D curves `curv`, `scrv`, `sp`,
     * `con`, polygons, unknown keywords), and the line of the first. */
    uint32_t num_skipped;
    uint32_t first_skipped_line;
    /* Of those, the polygon, line and point statements (OBJ f, fo, l, p):
     * geometry a file with free-form surfaces also holds and the set leaves
     * out, and the line of the first. */
    uint32_t num_polygons;
    uint32_t first_polygon_line;
    /* Of those, statements no OBJ keyword names (a misspelling: `hol` for
     * `hole`), the line of the first and its keyword (quoted, cut to fit);
     * and free-form geometry that is read past, not tessellated (OBJ 3D
     * curves `curv`, special curves `scrv` and points `sp`, connectivity
     * `con`), the line of the first. */
    uint32_t num_unknown;
    uint32_t first_unknown_line;
    char first_unknown[40];
    uint32_t num_unused_freeform;
    uint32_t first_unused_freeform_line;
    double *values; /* storage of every control point, weight and knot */
    size_t num_values;
    tsr_allocator alloc;
} tsr_patch_set;

typedef enum tsr_patch_format {
    TSR_PATCH_FORMAT_UNKNOWN = 0,
    TSR_PATCH_FORMAT_BPT, /* .bpt Bézier patch file */
    TSR_PATCH_FORMAT_OBJ  /* .obj free-form surfaces */
} tsr_patch_format;

/* The format named by a path's extension (.bpt, .obj; case-insensitive),
 * or UNKNOWN. */
tsr_patch_format tsr_patch_format_from_path(const char *path);

/* Largest file the loaders read (bytes). */
#define TSR_PATCH_MAX_FILE_BYTES ((uint64_t)1 << 31)

/* Loads a patch file into *out (zeroed first; freed again on failure, so
 * the caller frees only after TSR_OK). f UNKNOWN picks the format from the
 * extension. alloc (NULL: malloc) serves every array of the set.
 *
 * .bpt: the first line holds the patch count, then per patch a line
 * `du dv` (degrees, 1..7) and (du+1)(dv+1) lines `x y z`, row by row.
 * Patches are TSR_PATCH_BEZIER over [0,1]^2.
 *
 * .obj: the free-form part of Wavefront OBJ: `v x y z [w]` (w, default 1,
 * is the weight of rational surfaces; `v x y z r g b` colours are
 * ignored), `vp u [v [w]]`, `cstype [rat] bezier|bspline`, `deg du [dv]`,
 * `surf s0 s1 t0 t1 v1 v2 ...` (v, v/vt, v/vt/vn or v//vn; negative
 * indices count back from the last vertex read), `curv2 vp1 vp2 ...`, and
 * in their bodies `parm u ...`, `parm v ...`, `trim u0 u1 c ...`, `hole
 * u0 u1 c ...` (c: a curv2, by number in the file, negative relative), and
 * `end`. A backslash ending a line continues the statement. bspline
 * `parm` values are the knots; bezier ones the breakpoints of a composite
 * Bézier (count = (values - 1) * degree + 1; absent: one span over [0, 1]).
 * A surface is TSR_PATCH_BEZIER (rational with weights) when it is one
 * span each way and s0..s1, t0..t1 is the whole span; otherwise a
 * B-spline or NURBS whose knots reproduce it exactly. Its domain is
 * [s0, s1] x [t0, t1]. Every reference must name an element read before
 * it. Other statements are skipped and counted (num_skipped).
 *
 * Errors name the file, the line and the problem
 * ("teapot.bpt:17: expected 3 coordinates, found 2"):
 * TSR_ERR_NOT_FOUND, TSR_ERR_IO, TSR_ERR_EMPTY (no bytes, or no patch at
 * all), TSR_ERR_FORMAT (not a number, wrong count of values, a statement
 * out of place, control point counts that do not match the degrees and
 * parameters), TSR_ERR_TRUNCATED (the file ends inside a patch or an
 * element), TSR_ERR_VALUE (NaN or infinite value, weight <= 0, an index
 * that names nothing, a degree of 0, a knot vector, domain or value
 * beyond the numeric limits that tsr_patch_check refuses),
 * TSR_ERR_UNSUPPORTED (a degree beyond 7, cstype bmatrix, cardinal or
 * taylor), TSR_ERR_TOO_LARGE (counts that cannot fit in the bytes left,
 * checked before allocating, or a file beyond TSR_PATCH_MAX_FILE_BYTES),
 * TSR_ERR_NOMEM. Never crashes on any bytes. Memory is O(file size). */
tsr_status tsr_patch_set_load(const char *path, tsr_patch_format f, const tsr_allocator *alloc, tsr_patch_set *out,
                              tsr_error *err);

/* As tsr_patch_set_load, from size bytes at data (any bytes, NUL
 * included); name stands for the file in messages (NULL: "<memory>").
 * f may not be UNKNOWN. */
tsr_status tsr_patch_set_parse(const void *data, size_t size, const char *name, tsr_patch_format f,
                               const tsr_allocator *alloc, tsr_patch_set *out, tsr_error *err);

/* Frees every array of the set and zeroes it; NULL or a zeroed set is
 * allowed. */
void tsr_patch_set_free(tsr_patch_set *s);

/* Samples trim loop `loop` of s into a closed polyline in (u, v): each
 * segment's curve, cut into its Bézier spans, is subdivided until every
 * control polygon lies within tol of its chord (so, by the convex hull
 * property, every chord is within tol of the curve), depth 24 at most.
 * Points follow the loop's direction; the first is the start of segment
 * 0 and the closing point is not repeated. A segment that does not start
 * where the previous one ended (farther than tol) is joined by a straight
 * edge. Writes min(n, cap) points (2 doubles each) to uv, which may be
 * NULL with cap 0, and sets *count to n, the same n for every cap (call
 * once with cap 0 to size the array). TSR_ERR_ARGUMENT for a loop out of
 * range, tol not positive and finite, or count NULL. Thread-safe. */
tsr_status tsr_trim_loop_sample(const tsr_patch_set *s, uint32_t loop, double tol, double *uv, uint32_t cap,
                                uint32_t *count);

/* What a trim loop's shape means for the region it bounds, for warnings:
 * a file's loop may be open, cross itself, or enclose none of its patch's
 * domain, and the tessellation still does something definite with it
 * (closes it with a straight edge; the crossing-number rule decides its
 * inside; an outer loop keeping none of the domain keeps nothing, a hole
 * removes nothing). Figures of the loop sampled as by
 * tsr_trim_loop_sample at tol. */
typedef struct tsr_trim_loop_info {
    double gap;           /* from the loop's end to its start, (u, v) units: 0 when it closes within tol */
    double area;          /* of the part of the patch's domain inside it; -1 when it crosses itself */
    double domain_area;   /* of the patch's domain */
    bool crosses;         /* two of its edges cross (not at a shared end) */
    double cross_uv[2];   /* where, when they do */
    uint32_t points;      /* of its polyline */
    /* how far the polyline reaches into the domain: the largest, over its
     * points, of min((u - u0) / (u1 - u0), (u1 - u) / (u1 - u0), (v - v0) /
     * (v1 - v0), (v1 - v) / (v1 - v0)); 0 along the border, negative when
     * it stays outside the domain */
    double depth;
    bool encloses_centre; /* the domain's centre is inside it (crossing-number rule) */
} tsr_trim_loop_info;

/* Fills *info for trim loop `loop` of s (sampled at tol: positive and
 * finite). TSR_ERR_ARGUMENT as for tsr_trim_loop_sample, TSR_ERR_NOMEM.
 * The crossing test is exact in the sampled points' coordinates
 * (tsr_orient2d); O(n log n + k) for n points and k pairs of edges whose
 * boxes meet. Thread-safe. */
tsr_status tsr_trim_loop_check(const tsr_patch_set *s, uint32_t loop, double tol, const tsr_allocator *alloc,
                               tsr_trim_loop_info *info);

/* ---- Subdivision cages (polygon OBJ) ---------------------------------------- */

#ifndef TSR_CAGE_DEFINED
#define TSR_CAGE_DEFINED
/* A polygon cage, the control mesh of a subdivision surface, as the
 * polygon-OBJ loader makes it (patches/subd.h consumes it). All indices
 * are 0-based. Face f has face_sizes[f] >= 3 vertices, listed in the
 * file's order (counter-clockwise seen from outside in OpenSubdiv's
 * shapes), faces one after the other in face_verts (num_face_verts in
 * all). Tags are OpenSubdiv's, as parsed:
 *  - creases: vertex pairs (crease_verts, 2 each) naming edges, with a
 *    sharpness each (0 smooth, >= 10 infinitely sharp); the loader checks
 *    the indices name points, not that the pair is an edge;
 *  - corners: vertices with a sharpness;
 *  - holes: faces with no limit surface;
 *  - boundary_interp: Sdc's VtxBoundaryInterpolation, 0 none, 1 edge
 *    only, 2 edge and corner. The file's `t interpolateboundary` uses
 *    RenderMan's numbers (0 none, 1 edge and corner, 2 edge only) and is
 *    mapped; absent, 1 (edge only), OpenSubdiv's regression default;
 *  - fvar_interp: Sdc's FVarLinearInterpolation 0..5 (none, corners only,
 *    corners plus1, corners plus2, boundaries, all), from `t
 *    facevaryinginterpolateboundary`; absent, 5 (all), Sdc's default;
 *  - crease_method: 0 uniform ("normal"), 1 Chaikin (`t creasemethod`);
 *  - triangle_subdiv: 0 Catmark weights, 1 smooth (`t smoothtriangles`).
 * Sharpness values are finite and >= 0. Texture coordinates (`vt`): uvs
 * (2 each, num_uvs) and face_uvs (parallel to face_verts), NULL unless
 * every face corner names one. Tags OpenSubdiv 3 does not use
 * (vertexedit, edgeedit, faceedit: hierarchical edits; unknown names)
 * are counted in num_skipped_tags, the first one's line kept. Every array
 * belongs to the cage and is freed by tsr_cage_free with alloc. */
typedef struct tsr_cage {
    uint32_t num_points;
    double *points; /* 3 each */
    uint32_t num_faces;
    uint32_t *face_sizes;
    uint32_t *face_verts;
    uint32_t num_creases;
    uint32_t *crease_verts; /* 2 each */
    float *crease_sharpness;
    uint32_t num_corners;
    uint32_t *corner_verts;
    float *corner_sharpness;
    uint32_t num_holes;
    uint32_t *hole_faces;
    int boundary_interp; /* 0 none, 1 edge only, 2 edge and corner */
    int fvar_interp;
    /* Beyond the fields above: */
    uint32_t num_face_verts; /* sum of face_sizes */
    int crease_method;       /* 0 uniform, 1 Chaikin */
    int triangle_subdiv;     /* 0 Catmark, 1 smooth */
    uint32_t num_uvs;
    double *uvs;        /* 2 each, NULL when num_uvs is 0 */
    uint32_t *face_uvs; /* num_face_verts indices into uvs, or NULL */
    uint32_t num_skipped_tags;
    uint32_t first_skipped_tag_line;
    tsr_allocator alloc;
} tsr_cage;
#endif

/* Loads a polygon OBJ with OpenSubdiv tag lines into *out (zeroed first,
 * freed again on failure). Reads `v x y z [w]` (w and vertex colours
 * ignored), `vt u [v [w]]`, `f` with v, v/vt, v//vn or v/vt/vn corners
 * (negative indices count back; every index must name an element read
 * before it), and `t NAME nints/nfloats/nstrings ints... floats...
 * strings...` tags: crease (vertex pairs; one sharpness for all or one per
 * pair), corner (vertices; one sharpness or one each), hole (face
 * indices), interpolateboundary, facevaryinginterpolateboundary,
 * creasemethod, smoothtriangles; other tags are skipped and counted, as
 * are other statements (vn, g, s, o, usemtl, mtllib, l, p). Tag indices
 * are 0-based, as in OpenSubdiv.
 * Errors as tsr_patch_set_load's, naming the file and line
 * ("cube.obj:12: face vertex 9 is not defined (8 vertices so far)");
 * TSR_ERR_EMPTY when there is no face. alloc NULL means malloc. Never
 * crashes on any bytes; memory O(file size). */
tsr_status tsr_cage_load(const char *path, const tsr_allocator *alloc, tsr_cage *out, tsr_error *err);

/* As tsr_cage_load, from size bytes at data; name stands for the file in
 * messages (NULL: "<memory>"). */
tsr_status tsr_cage_parse(const void *data, size_t size, const char *name, const tsr_allocator *alloc, tsr_cage *out,
                          tsr_error *err);

/* Orients the faces of a cage consistently: across every edge used by
 * exactly two faces, the two must run it in opposite directions (so
 * OpenSubdiv sees a manifold edge, not a seam it leaves open), unless
 * the two fold onto each other (their centroids less than 60 degrees
 * apart about the edge: overlapping faces), which leaves the edge a seam.
 * Faces are grouped into parts through the other edges; in a part that
 * can be oriented, the faces against the majority are to be reversed
 * (vertex order v0, v_n-1, ..., v1, texture corners alike; creases,
 * corners and holes unchanged), and are when apply is true. A part that
 * cannot be (a Möbius band: some edge disagrees whatever the choice) is
 * left as it is. Edges of one vertex repeated (1 2 3 3) and edges used by
 * three or more faces take no part. *reversed (may be NULL) counts the
 * faces reversed (or to reverse), *first (may be NULL) the first of them
 * (0-based; UINT32_MAX when none), *unorientable the parts left.
 * OpenSubdiv's own non-manifold test shapes list faces against their
 * neighbours on purpose (catmark_nonman_edges): reversing changes the
 * surface they define. TSR_ERR_NOMEM (the cage unchanged). O(face
 * corners log). */
tsr_status tsr_cage_orient(tsr_cage *c, bool apply, uint32_t *reversed, uint32_t *first, uint32_t *unorientable);

/* Frees every array and zeroes the cage; NULL or a zeroed cage is
 * allowed. */
void tsr_cage_free(tsr_cage *c);

#ifdef __cplusplus
}
#endif
#endif
