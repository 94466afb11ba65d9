/* tile.c: grid tiles and their 16 stitch patterns.
 *
 * The "union jack" split (each quad's diagonal through the centre of its
 * 2x2 block) is the classic choice of restricted-quadtree terrain
 * renderers (e.g. Pajarola 1998, "Large scale terrain visualization using
 * the restricted quadtree triangulation"; Lindstrom et al. 1996): an odd
 * vertex of a tile edge then touches exactly two triangles, which merge
 * into one when the vertex is dropped, and triangles touching odd
 * vertices of different edges are disjoint, so the four edges stitch
 * independently. */
#include "tessellate/tessellate.h"

#include <string.h>

uint32_t tsr_tile_pattern_bound(uint32_t n) { return 2 * n * n; }

/* Is local vertex (i, j) an odd vertex of an edge whose bit is in mask?
 * Returns that edge's bit, or 0. */
static unsigned dropped_edge(uint32_t n, unsigned mask, uint32_t i, uint32_t j)
{
    if (j == 0 && (i & 1) && (mask & TSR_EDGE_SOUTH))
        return TSR_EDGE_SOUTH;
    if (j == n && (i & 1) && (mask & TSR_EDGE_NORTH))
        return TSR_EDGE_NORTH;
    if (i == 0 && (j & 1) && (mask & TSR_EDGE_WEST))
        return TSR_EDGE_WEST;
    if (i == n && (j & 1) && (mask & TSR_EDGE_EAST))
        return TSR_EDGE_EAST;
    return 0;
}

uint32_t tsr_tile_pattern(uint32_t n, unsigned mask, uint32_t *dst)
{
    uint32_t count = 0, row = n + 1;
#define EMIT(a, b, c)                                                                              \
    do {                                                                                           \
        if (dst) {                                                                                 \
            dst[3 * count] = (a);                                                                  \
            dst[3 * count + 1] = (b);                                                              \
            dst[3 * count + 2] = (c);                                                              \
        }                                                                                          \
        count++;                                                                                   \
    } while (0)
    for (uint32_t qj = 0; qj < n; qj++)
        for (uint32_t qi = 0; qi < n; qi++) {
            uint32_t a = qj * row + qi, b = a + 1, c = a + row, d = c + 1;
            uint32_t t[2][3];
            if (((qi + qj) & 1) == 0) {
                uint32_t t0[3] = {a, b, d}, t1[3] = {a, d, c};
                memcpy(t[0], t0, sizeof t0);
                memcpy(t[1], t1, sizeof t1);
            } else {
                uint32_t t0[3] = {a, b, c}, t1[3] = {b, d, c};
                memcpy(t[0], t0, sizeof t0);
                memcpy(t[1], t1, sizeof t1);
            }
            for (int k = 0; k < 2; k++) {
                /* a triangle touching a dropped vertex v: of the two such
                 * triangles, the one in the quad before v (lower i or j)
                 * emits the merged triangle, the other emits nothing */
                int drop = -1;
                for (int e = 0; e < 3; e++) {
                    uint32_t v = t[k][e];
                    if (dropped_edge(n, mask, v % row, v / row))
                        drop = e;
                }
                if (drop < 0) {
                    EMIT(t[k][0], t[k][1], t[k][2]);
                    continue;
                }
                uint32_t v = t[k][drop], vi = v % row, vj = v / row;
                bool along_i = vj == 0 || vj == n; /* south or north edge */
                bool first = along_i ? qi + 1 == vi : qj + 1 == vj;
                if (!first)
                    continue;
                /* replace v by the next even vertex along the edge: the
                 * merged triangle keeps the winding of the original */
                uint32_t next = along_i ? v + 1 : v + row;
                uint32_t tri[3] = {t[k][0], t[k][1], t[k][2]};
                tri[drop] = next;
                /* the original triangle (before, v, inner) becomes
                 * (before, next, inner) which is the union of both */
                EMIT(tri[0], tri[1], tri[2]);
            }
        }
#undef EMIT
    return count;
}

tsr_status tsr_tile_patterns_init(tsr_tile_patterns *p, uint32_t n, const tsr_allocator *alloc)
{
    memset(p, 0, sizeof *p);
    if (alloc)
        p->alloc = *alloc;
    if (n < TSR_TILE_MIN || n > TSR_TILE_MAX || (n & 1))
        return TSR_ERR_ARGUMENT;
    p->n = n;
    size_t total = 0;
    for (unsigned m = 0; m < 16; m++) {
        p->count[m] = tsr_tile_pattern(n, m, NULL);
        total += p->count[m];
    }
    p->storage = tsr_alloc(alloc, total * 3 * sizeof *p->storage);
    if (!p->storage)
        return TSR_ERR_NOMEM;
    uint32_t *w = p->storage;
    for (unsigned m = 0; m < 16; m++) {
        tsr_tile_pattern(n, m, w);
        p->tri[m] = w;
        w += 3 * p->count[m];
    }
    return TSR_OK;
}

void tsr_tile_patterns_free(tsr_tile_patterns *p)
{
    tsr_allocator a = p->alloc;
    tsr_free(a.realloc ? &a : NULL, p->storage);
    memset(p, 0, sizeof *p);
}
