/* cdt_internal.h: the triangulation's flat arrays, shared by cdt.c (the
 * kernel and segment recovery), refine.c (conforming and quality
 * refinement) and triangulate.c (the driver). Not installed.
 *
 * Internal vertex ids are public ids + 1; vertex 0 is the point at
 * infinity that closes the hull with ghost triangles. Triangle t has
 * vertices tv[3t..3t+2], counter-clockwise; edge k runs from tv[3t+k] to
 * tv[3t+(k+1)%3] and tn[3t+k] is the triangle across it. tc[3t+k] (when
 * allocated) marks a constrained edge on both sides: 0 for none, else the
 * label CDT_LABEL(m): the input segment id + 1, or CDT_BOUNDARY for a
 * domain boundary that is no input segment; the bit CDT_EVEN says that an
 * even number of input segments cover the edge (overlapping segments, a
 * ring given twice), which the even-odd rule crosses without counting. tf[t] (when allocated) is CDT_OUTSIDE for
 * triangles outside the domain being refined (ghosts included), 0 inside,
 * or, inside, CDT_REGION0 + r for a triangle of region r (a bound of its
 * own on the area); new triangles take the flag of those they replace. */
#ifndef TSR_CDT_INTERNAL_H
#define TSR_CDT_INTERNAL_H

#include "tessellate/tessellate.h"

#define CDT_GHOST 0u
#define CDT_NONE UINT32_MAX
#define CDT_BOUNDARY 0x7FFFFFFFu
#define CDT_EVEN 0x80000000u
#define CDT_LABEL(m) ((m)&0x7FFFFFFFu)
#define CDT_OUTSIDE 1u
#define CDT_REGION0 2u

struct tsr_cdt {
    tsr_allocator alloc;
    double *xy; /* 2 per internal vertex; vertex 0 (infinity) unused */
    uint32_t nv, cap_v;
    uint32_t *tv, *tn, *tc;
    uint32_t *tf;
    uint32_t nt, cap_t;
    uint32_t last;
    uint32_t dups;
    uint32_t intersections, snapped;
    /* steps of the segment being inserted, the limit past which crossings
     * are only routed through the crossed edges' ends (plain: no constraint
     * is bent, so no two can bend each other back and forth), and past
     * twice which the insertion gives up */
    uint64_t steps, step_limit;
    bool plain;
    uint32_t walk_turn;
    bool started;
    bool track;
    uint32_t *pending; /* distinct vertices waiting for a non-collinear third */
    uint32_t npending, cap_pending;
    uint32_t *stack; /* triangles whose edge opposite the new vertex is to check */
    uint32_t nstack, cap_stack;
    uint32_t *changed; /* triangles written since the last take (track) */
    uint32_t nchanged, cap_changed;
    /* scratch for segment recovery: crossed triangles, the chains left and
     * right of the segment, the pending targets, new triangles */
    uint32_t *work, *chl, *chr, *targets, *nwt;
    uint32_t nwork, cap_work, nchl, cap_chl, nchr, cap_chr, ntargets, cap_targets, nnwt, cap_nwt;
};

enum { CDT_IN_TRIANGLE, CDT_ON_EDGE, CDT_ON_VERTEX, CDT_IN_GHOST };

static inline const double *cdt_P(const tsr_cdt *d, uint32_t v)
{
    return d->xy + 2 * (size_t)v;
}
static inline bool cdt_is_ghost(const tsr_cdt *d, uint32_t t)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    return v[0] == CDT_GHOST || v[1] == CDT_GHOST || v[2] == CDT_GHOST;
}
/* The key of the undirected edge a-b, for sorting edge records. */
static inline uint64_t cdt_edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}
static inline uint32_t cdt_mark(const tsr_cdt *d, uint32_t t, int k)
{
    return d->tc ? d->tc[3 * (size_t)t + k] : 0;
}

const tsr_allocator *tsr__cdt_alloc(const tsr_cdt *d);
/* Appends v to a growable array; false when out of memory. */
bool tsr__cdt_append(const tsr_cdt *d, uint32_t **arr, uint32_t *n, uint32_t *cap, uint32_t v);
/* Stores a new vertex (no insertion); CDT_NONE when out of memory. */
uint32_t tsr__cdt_add_vertex(tsr_cdt *d, double x, double y);
/* Allocates tc (and tf when flags) if absent; false when out of memory. */
bool tsr__cdt_enable_marks(tsr_cdt *d, bool flags);
/* Marks edge k of t (and its twin) with value m. */
void tsr__cdt_mark_edge(tsr_cdt *d, uint32_t t, int k, uint32_t m);
/* Inserts stored vertex pv in triangle t located as kind/which (see
 * locate); new triangles take t's flag, except that splitting a
 * constrained edge keeps each side's flag and marks both halves. Returns
 * pv or CDT_NONE when out of memory. */
uint32_t tsr__cdt_insert_at(tsr_cdt *d, uint32_t pv, uint32_t t, int kind, int which);
/* Visibility walk from the last triangle; kind and which as above. */
uint32_t tsr__cdt_locate(tsr_cdt *d, const double p[2], int *kind, int *which);
/* Splits edge k of finite triangle t at stored vertex pv without locating
 * it; false (nothing changed, pv still stored) when one of the four
 * triangles would not be strictly counter-clockwise. Marks propagate. */
bool tsr__cdt_split_edge(tsr_cdt *d, uint32_t t, int k, uint32_t pv, bool *nomem);

/* Conforming / quality refinement (refine.c) of the triangles with tf 0,
 * whose boundary edges must all be marked. ninput: vertices [1, ninput]
 * are input vertices; segends: the internal ids of input segment s's ends
 * at 2s, 2s+1 (nseg segments). Updates the result's quality_limited,
 * steiner_limited, unrefined, small_angle_exempt and below_resolution. */
tsr_status tsr__cdt_refine(tsr_cdt *d, const tsr_tri_options *opt, uint32_t ninput, const uint32_t *segends,
                           uint32_t nseg, tsr_triangulation *res);

#endif
