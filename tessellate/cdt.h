/* cdt.h: (included by tessellate.h) incremental Delaunay triangulation in
 * the plane, the kernel of the constrained triangulator and of the
 * heightmap mesher. Exact predicates (predicates.h): the result is the
 * Delaunay triangulation of the input doubles, whatever their degeneracy
 * (cocircular points get one of their valid triangulations).
 *
 * Vertices are numbered 0, 1, ... in insertion order of distinct points;
 * exact duplicates map to the first vertex at that position. Triangles are
 * counter-clockwise. Not thread-safe for one object; objects independent. */
#ifndef TSR_CDT_H
#define TSR_CDT_H

#ifdef __cplusplus
extern "C" {
#endif

typedef struct tsr_cdt tsr_cdt;

tsr_cdt *tsr_cdt_create(const tsr_allocator *alloc);
void tsr_cdt_destroy(tsr_cdt *d);

/* Inserts n points (x, y pairs, finite) in a spatially coherent random
 * order (BRIO over a Hilbert curve), writing each input's vertex id into
 * ids (may be NULL). Returns TSR_OK, TSR_ERR_ARGUMENT for a non-finite
 * coordinate (nothing inserted), or TSR_ERR_NOMEM. */
tsr_status tsr_cdt_insert_points(tsr_cdt *d, const double *xy, uint32_t n, uint32_t *ids);

/* Inserts one point; returns its vertex id (an existing id for an exact
 * duplicate), or UINT32_MAX when out of memory or not finite. */
uint32_t tsr_cdt_insert(tsr_cdt *d, double x, double y);
/* The same, starting the point location at triangle slot `near` (see the
 * handles below; any value is safe): fast when the point lies in or near
 * that triangle, as when a mesher inserts the sample it found in it. */
uint32_t tsr_cdt_insert_near(tsr_cdt *d, double x, double y, uint32_t near);

uint32_t tsr_cdt_vertex_count(const tsr_cdt *d);
/* Exact duplicates merged so far. */
uint32_t tsr_cdt_duplicate_count(const tsr_cdt *d);
/* Position of vertex v. */
void tsr_cdt_vertex(const tsr_cdt *d, uint32_t v, double xy[2]);

/* Number of (finite) triangles; 0 while all points are collinear. */
uint32_t tsr_cdt_triangle_count(const tsr_cdt *d);
/* Writes the triangles as 3 vertex ids each into tri (capacity cap
 * triangles); returns the count written. */
uint32_t tsr_cdt_triangles(const tsr_cdt *d, uint32_t *tri, uint32_t cap);

/* The triangle (as its 3 vertex ids, counter-clockwise) containing (x, y),
 * or false when the point is outside the convex hull (or there is none). */
bool tsr_cdt_locate(const tsr_cdt *d, double x, double y, uint32_t tri[3]);

/* ---- Constraints ----------------------------------------------------- */

/* Inserts the segment between vertices a and b (ids from the insert
 * functions) as a constrained edge labelled id (< UINT32_MAX - 1). Vertices
 * lying exactly on it split it there; a constrained edge crossing it is
 * split at a new vertex at the crossing point (rounded to doubles; counted
 * by tsr_cdt_intersection_count); where an edge already constrained lies
 * along it, the lower label is kept. Nothing happens while the points are
 * all collinear (no triangle yet) or when a == b. Returns TSR_OK,
 * TSR_ERR_ARGUMENT (unknown vertex), TSR_ERR_NOMEM. */
tsr_status tsr_cdt_insert_segment(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t id);
/* Vertices created at segment crossings so far. */
uint32_t tsr_cdt_intersection_count(const tsr_cdt *d);
/* True when the edge a-b exists and is constrained; *id (may be NULL)
 * receives its label. */
bool tsr_cdt_edge_constrained(const tsr_cdt *d, uint32_t a, uint32_t b, uint32_t *id);

/* ---- Incremental use (the heightmap mesher) ---------------------------- */

/* Triangles live in slots ("handles") 0 .. tsr_cdt_handle_count() - 1; a
 * slot keeps its triangle until an insertion rewrites it, and slots are
 * never freed. Some slots hold ghost triangles (outside the hull):
 * tsr_cdt_triangle returns false for them. */
uint32_t tsr_cdt_handle_count(const tsr_cdt *d);
/* The vertex ids of the triangle in slot h (counter-clockwise); false for
 * a ghost or an unused slot. */
bool tsr_cdt_triangle(const tsr_cdt *d, uint32_t h, uint32_t v[3]);
/* The slot of the triangle containing (x, y) (on its boundary counts),
 * or UINT32_MAX outside the hull. */
uint32_t tsr_cdt_locate_handle(const tsr_cdt *d, double x, double y);
/* While tracking is on, every slot written by an insertion is recorded:
 * tsr_cdt_changes lists those since the last clear (a slot may appear more
 * than once; the triangles they held before are the destroyed ones, and
 * what they hold now the created ones). Turning tracking on clears it. The
 * pointer is valid until the next insertion or clear. */
void tsr_cdt_track_changes(tsr_cdt *d, bool on);
const uint32_t *tsr_cdt_changes(const tsr_cdt *d, uint32_t *n);
void tsr_cdt_clear_changes(tsr_cdt *d);

/* ---- Edge flips (data-dependent triangulations, the heightmap mesher) --- */

/* The slot of the triangle across edge k (from v[k] to v[(k+1) % 3] as
 * tsr_cdt_triangle lists them) of the triangle in slot h, or UINT32_MAX
 * when that side is the hull (a ghost), h holds no finite triangle or k is
 * not 0..2. *constrained (may be NULL) says whether the edge is
 * constrained. */
uint32_t tsr_cdt_neighbor(const tsr_cdt *d, uint32_t h, int k, bool *constrained);
/* Flips edge k of the triangle (p, x, y) in slot h (edge k from x to y, p
 * the third vertex) shared with (y, x, q): slot h then holds (p, x, q) and
 * the neighbour's slot (p, q, y), both recorded while tracking changes.
 * Returns TSR_OK, TSR_ERR_ARGUMENT (nothing changed) for a hull edge, a
 * constrained edge or a quad that is not strictly convex (exact test), or
 * TSR_ERR_NOMEM (the flip is done, the change list short). The result
 * need not be Delaunay: later insertions keep it a valid triangulation
 * (Lawson's flips only meet convex quads) but may flip such edges back;
 * point location may be slower unless started near the point. */
tsr_status tsr_cdt_flip(tsr_cdt *d, uint32_t h, int k);

#ifdef __cplusplus
}
#endif
#endif
