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

#ifdef __cplusplus
}
#endif
#endif
