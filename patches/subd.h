/* subd.h: subdivision surfaces (Catmull-Clark and bilinear) evaluated per
 * base face through OpenSubdiv's Bfr, behind a C interface (the bridge is
 * patches/subd.cpp, the one C++ file of the module).
 *
 * Patches. Each base face of the cage is cut into patches whose domain is
 * the unit square (u, v) in [0,1]^2, so that the restricted quadtree of
 * tessellate/ can treat every patch alike:
 *  - a quad is one patch, parameterised as Bfr parameterises quads: corner
 *    (0,0) at the face's vertex 0, (1,0) at vertex 1, (1,1) at vertex 2,
 *    (0,1) at vertex 3;
 *  - an N-gon (N != 4) is N patches, Bfr's quad sub-faces: patch k has
 *    corner (0,0) at vertex k, (1,0) at the midpoint of edge k (vertex k to
 *    k+1), (1,1) at the face's centre and (0,1) at the midpoint of edge k-1.
 *    Patch k's (u, v) is Bfr's normalised sub-face coordinate, mapped
 *    through Bfr::Parameterization::ConvertNormalizedSubFaceToCoord.
 * With a cage whose faces are counter-clockwise seen from outside, du x dv
 * points outward on every patch.
 *
 * Patch edges are numbered 0..3 = south (v = 0), east (u = 1), north
 * (v = 1), west (u = 0); bit (1u << e) is the TSR_EDGE_* of
 * tessellate/quadtree.h. Along an edge its parameter t is the coordinate
 * that varies on it (u on south and north, v on east and west), so t runs
 * with the tile's lattice index i or j.
 *
 * Thread safety: a tsr_subd is read-only after creation, except for a
 * small cache of the last face's prepared patch points that is guarded by
 * a mutex (a call that finds it busy prepares its own copy), so every
 * function below may be called on one tsr_subd from several threads at
 * once; create and destroy may not overlap other calls on the same object.
 */
#ifndef TSR_SUBD_H
#define TSR_SUBD_H

#include "patches/patches.h"

#ifdef __cplusplus
extern "C" {
#endif

/* tsr_cage, the polygon cage, is declared in patches/patches.h. */

typedef enum tsr_subd_scheme {
    TSR_SUBD_CATMARK = 0, /* Catmull-Clark */
    TSR_SUBD_BILINEAR = 1
} tsr_subd_scheme;

/* Largest face size accepted (Bfr's sub-face tiling of an N-gon keeps its
 * width, about sqrt(N), in a byte; far below that, an N-gon of a thousand
 * vertices is already no sensible patch), and largest rate of
 * tsr_subd_tessellate_uniform. */
#define TSR_SUBD_MAX_FACE_SIZE 1024u
#define TSR_SUBD_MAX_RATE 4096u

typedef struct tsr_subd tsr_subd;

/* Builds the surface of a cage: OpenSubdiv's topology refiner (with the
 * cage's creases, corners, holes, boundary interpolation, creasing method
 * and triangle weights) and its Bfr surface factory, and finds which faces
 * have a limit surface. The cage's uvs are not used.
 *
 * The cage is copied (points included); it may be freed after the call.
 * alloc (NULL: malloc) serves the handle and Tessera's own tables;
 * OpenSubdiv's refiner and factory use operator new, which OpenSubdiv
 * offers no hook to change.
 *
 * Refused, with *out NULL and err naming the element:
 *  - TSR_ERR_ARGUMENT: cage, out or a needed array NULL; scheme not a
 *    tsr_subd_scheme; boundary_interp outside 0..2, fvar_interp outside
 *    0..5, crease_method or triangle_subdiv outside 0..1;
 *  - TSR_ERR_EMPTY: no points or no faces;
 *  - TSR_ERR_VALUE: a non-finite coordinate; a face of fewer than 3 or
 *    more than TSR_SUBD_MAX_FACE_SIZE vertices; a vertex index >=
 *    num_points; a crease pair that is not an edge of the cage (or names
 *    one vertex twice); a corner or hole index out of range; a sharpness
 *    negative or NaN; a vertex in more than 16384 faces (OpenSubdiv's
 *    valence limit);
 *  - TSR_ERR_TOO_LARGE: counts beyond OpenSubdiv's int indices;
 *  - TSR_ERR_INVALID_MESH: topology OpenSubdiv refuses;
 *  - TSR_ERR_NOMEM.
 * Non-manifold cages (an edge of three faces, a face listing a vertex
 * twice, two faces running along an edge the same way) are accepted as
 * OpenSubdiv accepts them; faces Bfr cannot evaluate get no limit surface
 * and such edges no neighbours (tsr_subd_patch_neighbours).
 * No exception crosses into C. Cost: O(size of the cage) plus one Bfr
 * surface initialisation per face. */
tsr_status tsr_subd_create(const tsr_cage *cage, tsr_subd_scheme scheme, const tsr_allocator *alloc, tsr_subd **out,
                           tsr_error *err);

/* Frees everything; NULL is allowed. */
void tsr_subd_destroy(tsr_subd *s);

/* Number of base faces (the cage's num_faces). */
uint32_t tsr_subd_face_count(const tsr_subd *s);

/* Whether s was made with a caller's allocator (tsr_subd_create's alloc
 * not NULL): evaluations may allocate with it, so callers that would
 * evaluate on several threads can tell whether they may. */
bool tsr_subd_has_allocator(const tsr_subd *s);

/* Vertices of base face `face`; 0 for a face out of range. */
uint32_t tsr_subd_face_size(const tsr_subd *s, uint32_t face);

/* Whether the face has a limit surface: false for holes, for faces
 * touching the boundary when boundary_interp is 0, for faces Bfr cannot
 * evaluate, and for a face out of range. */
bool tsr_subd_face_has_limit(const tsr_subd *s, uint32_t face);

/* Patches of the face: 1 for a quad, N for an N-gon, 0 out of range
 * (whether or not the face has a limit surface). */
uint32_t tsr_subd_face_patches(const tsr_subd *s, uint32_t face);

/* One piece of the correspondence along a patch edge: the part t0 <= t <=
 * t1 of this edge coincides with the part of edge `edge` of patch
 * (face, sub) where its parameter runs from s0 (at t0) to s1 (at t1),
 * linearly: the point at t is the neighbour's point at
 * s = s0 + (t - t0) (s1 - s0) / (t1 - t0). reversed is s1 < s0. The
 * values are exact (0, 1/2 or 1). */
typedef struct tsr_subd_link {
    uint32_t face, sub; /* the neighbouring patch */
    uint32_t edge;      /* its edge, 0..3 */
    bool reversed;
    double t0, t1; /* 0 <= t0 < t1 <= 1, on this edge */
    double s0, s1; /* on the neighbour's edge */
} tsr_subd_link;

/* The neighbours across edge `edge` (0..3) of patch (face, sub), written to
 * out (room for 2, sorted by t0), returning how many:
 *  - 1, covering t in [0,1]:
 *    - inside an N-gon: east of patch k is north of patch k+1 (and north
 *      of k east of k-1), not reversed (both run from the edge midpoint
 *      to the centre);
 *    - across a base edge between two quads: reversed exactly when both
 *      edges are among {south, east} or both among {north, west};
 *    - across a base edge between two N-gons: the south edge of one
 *      sub-patch meets the west edge of the other's, not reversed;
 *  - 2 where a quad's edge meets an N-gon: the quad's edge is split at
 *    t = 1/2 between two sub-patches of the N-gon, each link covering its
 *    half (and each of those sub-patch edges links back with one link
 *    covering t in [0,1] onto s in [0,1/2] or [1/2,1] of the quad's edge);
 *  - 0 on the boundary, where the edge is non-manifold (not exactly two
 *    faces running along it in opposite directions), where the face across
 *    has no limit surface, and for a patch that does not exist.
 * Links are symmetric: the neighbour's edge links back over the same
 * stretch. Points that correspond evaluate equal up to rounding (the
 * limit surface is continuous across base edges; Bfr evaluates the two
 * faces separately, so they may differ in the last bits). O(1). */
uint32_t tsr_subd_patch_neighbours(const tsr_subd *s, uint32_t face, uint32_t sub, uint32_t edge, tsr_subd_link out[2]);

/* How far apart the two sides of every link evaluate the points they
 * share: for each link of each patch, 9 points evenly along its stretch
 * (ends included) are evaluated by this patch and by the neighbour at the
 * corresponding parameter; *gap gets the largest distance and *at (may be
 * NULL) the two patches and parameters where it occurs (the first found).
 * On a consistent limit surface this is rounding (about 1e-16 of the
 * model); where Bfr's surfaces of two faces disagree (OpenSubdiv 3.5.0 on
 * catmark_chaikin1: face 11's four corners against its neighbours',
 * 1.7e-3, where uniform refinement with limit masks agrees with the
 * neighbours to 3e-8), a welded mesh cannot follow both sides, and
 * measuring against each side finds the difference. *gap is 0 when there
 * is no link. TSR_ERR_ARGUMENT for a NULL s or gap; TSR_ERR_NOMEM. */
typedef struct tsr_subd_gap_at {
    uint32_t face, sub, other_face, other_sub;
    double uv[2], other_uv[2];
} tsr_subd_gap_at;
tsr_status tsr_subd_link_gap(const tsr_subd *s, double *gap, tsr_subd_gap_at *at);

/* Limit surface of patch (face, sub) at `count` parameter pairs uv (u, v
 * interleaved, clamped to [0,1]; NaN reads as 0): positions into pos (3
 * per point, not NULL) and, when du / dv are not NULL, the first
 * derivatives with respect to the patch's u and v (for an N-gon's
 * sub-patch, half of Bfr's derivatives with respect to the face's
 * coordinates, since a sub-face spans half a unit of them). Units are the
 * cage's. The face's Bfr surface and patch points are prepared once per
 * call and kept for the next call on the same face. Returns
 * TSR_ERR_ARGUMENT for a face out of range or without limit surface, a sub
 * >= tsr_subd_face_patches or a NULL pointer with count > 0;
 * TSR_ERR_NOMEM. */
tsr_status tsr_subd_eval(const tsr_subd *s, uint32_t face, uint32_t sub, const double *uv, uint32_t count, double *pos,
                         double *du, double *dv);

/* Unit normal du x dv / |du x dv| at one (u, v) of patch (face, sub)
 * (outward for an outward-oriented cage). Where du x dv vanishes or is
 * tiny against |du| |dv| (below 1e-10 of it: a collapsed cage edge, a
 * degenerate corner), the normal is taken at points moved towards the
 * patch centre by 1e-7, 1e-5, then 1e-3 of the patch, the first that is
 * well defined. TSR_ERR_VALUE (n set to 0) when none is; otherwise as
 * tsr_subd_eval. */
tsr_status tsr_subd_normal(const tsr_subd *s, uint32_t face, uint32_t sub, const double uv[2], double n[3]);

/* A box [lo, hi] containing the limit surface of patch (face, sub) as
 * Bfr evaluates it: the box of all the patch points Bfr prepares for the
 * face (see subd.cpp for why it is conservative), padded by a few ulps
 * for the rounding of evaluation. For an N-gon every sub-patch gets the
 * whole face's box. Errors as tsr_subd_eval. */
tsr_status tsr_subd_face_bounds(const tsr_subd *s, uint32_t face, uint32_t sub, double lo[3], double hi[3]);

/* Appends a uniform tessellation of every face with a limit surface to
 * `out` (initialised by tsr_mesh_init; existing content kept): Bfr's
 * Tessellation at `rate` segments per base edge (1..TSR_SUBD_MAX_RATE),
 * triangles counter-clockwise in each face's (u, v), hence seen from
 * outside for an outward-oriented cage. Vertices are welded by the cage's
 * topology: one vertex per cage vertex and per point of a cage edge,
 * evaluated once by the first face that uses it, so faces sharing an edge
 * share its vertices exactly, and a closed manifold cage gives a closed
 * manifold mesh. (Edges that join a vertex to itself are not shared.)
 * Normals, when the mesh has them, are those of tsr_subd_normal; uvs, when
 * it has them, are 0. TSR_ERR_ARGUMENT for a rate out of range or NULL
 * pointers, TSR_ERR_TOO_LARGE when the mesh would exceed 2^32 - 2
 * vertices or triangles, TSR_ERR_NOMEM; on failure `out` keeps its
 * previous counts. Cost: O(rate^2) evaluations per face. */
tsr_status tsr_subd_tessellate_uniform(const tsr_subd *s, uint32_t rate, tsr_mesh *out, tsr_error *err);

/* As tsr_subd_tessellate_uniform, for the faces listed alone: each of
 * faces[0 .. num_faces-1] that has a limit surface, in that order (faces
 * without one are skipped, as there). A face's triangles and points are
 * exactly those tsr_subd_tessellate_uniform gives it, except that
 * vertices are shared only among the listed faces (the first listed face
 * that uses a cage vertex or edge point evaluates it). With every face
 * listed in order 0, 1, ..., the result is tsr_subd_tessellate_uniform's.
 * faces may be NULL when num_faces is 0 (nothing appended). Errors as
 * tsr_subd_tessellate_uniform's, and TSR_ERR_ARGUMENT (err naming it) for
 * a face >= tsr_subd_face_count or one listed twice. Cost: O(rate^2)
 * evaluations per listed face, plus O(size of the cage) for the welding
 * tables. */
tsr_status tsr_subd_tessellate_uniform_faces(const tsr_subd *s, uint32_t rate, const uint32_t *faces,
                                             uint32_t num_faces, tsr_mesh *out, tsr_error *err);

/* ---- Bézier patches as subdivision cages ----------------------------------- */

/* Face of a tsr_subd_cage_from_bezier cage whose limit surface is Bézier
 * patch p: the middle face of its 4 x 4 grid. */
#define TSR_SUBD_BEZIER_FACE(p) (9u * (uint32_t)(p) + 4u)

/* A Catmull-Clark cage whose limit surface is exactly a list of
 * polynomial bicubic Bézier patches, so that Bfr can tessellate them.
 *
 * ctrl holds 48 doubles per patch: its 4 x 4 control points, point (i, j)
 * (i along s, j along t) at ctrl[48 p + 3 (4 j + i)] (the order of
 * patches.h). Each patch becomes the uniform cubic B-spline patch of the
 * same surface over [0,1]^2: per direction, the B-spline points Q of the
 * Bézier points b are (inverting b0 = (Q0 + 4 Q1 + Q2) / 6, b1 = (2 Q1 +
 * Q2) / 3, b2 = (Q1 + 2 Q2) / 3, b3 = (Q1 + 4 Q2 + Q3) / 6)
 *     Q0 = 6 b0 - 7 b1 + 2 b2,  Q1 = 2 b1 - b2,
 *     Q2 = 2 b2 - b1,           Q3 = 2 b1 - 7 b2 + 6 b3.
 * The cage holds one 4 x 4 grid of those points per patch, unconnected:
 * point (i, j) of patch p is cage point 16 p + 4 j + i; face 9 p + 3 j + i
 * (i, j in 0..2) is the quad (i, j), (i+1, j), (i+1, j+1), (i, j+1). The
 * middle face TSR_SUBD_BEZIER_FACE(p) is a regular interior face, whose
 * limit (Stam) is that B-spline patch, with Bfr's (u, v) equal to the
 * Bézier patch's (s, t) (tests/patches/test_subd.c checks both to 1e-12).
 * boundary_interp is 0, so the other eight faces have no limit surface and
 * tsr_subd_tessellate_uniform of the whole cage tessellates exactly the
 * patches. Rational or non-cubic patches have no such cage (convert
 * B-splines with tsr_patch_to_bezier first; rational ones not at all).
 *
 * *out is zeroed first; its arrays come from alloc (NULL: malloc), which
 * the cage keeps for tsr_cage_free. TSR_ERR_ARGUMENT for NULL pointers,
 * TSR_ERR_EMPTY for no patches, TSR_ERR_TOO_LARGE beyond (2^32 - 1) / 36
 * patches (the face-vertex count), TSR_ERR_VALUE (naming the patch) for a non-finite input or
 * B-spline point, TSR_ERR_NOMEM. Thread-safe. */
tsr_status tsr_subd_cage_from_bezier(const double *ctrl, uint32_t num_patches, const tsr_allocator *alloc,
                                     tsr_cage *out, tsr_error *err);

#ifdef __cplusplus
}
#endif
#endif
