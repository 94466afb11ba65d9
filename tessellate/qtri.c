/* qtri.c: the quadtree method of tsr_triangulate.
 *
 * Quadtree meshing in the manner of Yerry and Shephard ("A modified
 * quadtree approach to finite element mesh generation", IEEE CG&A 1983)
 * and Bern, Eppstein and Gilbert ("Provably good mesh generation", JCSS
 * 1994), with simpler cell rules and no angle guarantee: a 2:1 balanced
 * quadtree is split until every leaf is simple, then every leaf is
 * triangulated by a fixed rule from its own features and which of its four
 * neighbours are finer, so that two leaves agree on their shared side.
 *
 * The square: the points' bounding box made square, grown to a power of
 * two S >= 1.25 times its larger side and shifted by an irrational-looking
 * fraction of S (at most 0.05 S), so that round input coordinates miss the
 * grid lines; a point exactly on a line of level <= depth makes it try the
 * next shift. Grid coordinates are ox + u * S with u dyadic: u * S is exact,
 * so every cell computes a shared corner or midpoint as the same double, and
 * integer keys (coordinates at level depth + 1; for a side crossing, piece
 * and line) give shared points one output vertex without a coordinate hash.
 *
 * Features: the distinct points (exact duplicates merged) and the segments
 * as pieces between vertices. Pieces between the same two vertices merge,
 * keeping every segment that covers them. In small non-simple leaves every
 * pair is tested with exact predicates: a proper crossing gets a new vertex,
 * a vertex inside a piece or a collinear overlap splits the pieces there,
 * and the tree is built again (at most ROUNDS builds).
 *
 * Where a piece meets a side is decided exactly: its ends lie strictly on
 * both sides of the side's line and orient2d changes sign, or is zero, at
 * the grid points along the side (corners, and the midpoint where the
 * neighbour is finer). The crossing's coordinate comes from one function of
 * (piece, line), clamped into the open interval between the grid points
 * the predicates chose; both cells of the side see the same interval.
 *
 * A leaf is simple when its neighbours are at most one level finer, it is
 * at least at the level max_area asks for, and
 *  (a) no vertex and no piece enters it: two triangles, or a fan from the
 *      first midpoint of a side with a finer neighbour (no Steiner point);
 *  (b) one vertex, VERTEX_MARGIN of the cell off its sides (a quarter of
 *      that in the two levels above the depth limit, anything inside at
 *      the limit), and every piece entering has it as an end and leaves
 *      through one ring point: a fan from the vertex (the cell's centre
 *      moved onto it), the edges to the exit points constrained;
 *  (c) no vertex, and the pieces entering cross it as chords between two
 *      ring points each, no two crossing or sharing a point: the chords cut
 *      the convex ring into convex faces, each fanned from the first of its
 *      points giving only counter-clockwise triangles, else from the mean of
 *      its points (a Steiner point). A piece touching only a corner counts
 *      as nothing.
 * Any number of chords may share a leaf: pieces that part at a small angle
 * from one vertex cannot be separated by splitting, and separating all the
 * pieces would cost cells along their whole length. Every triangle is
 * checked with orient2d; a leaf whose rule fails is not simple.
 *
 * Fallback: a leaf that is not simple at the depth limit, or whose chords
 * only clash by rounding (they neither cross nor touch, yet their side
 * points coincide or interleave, which no split changes), is triangulated by
 * the Delaunay method, region ENCLOSED: the pieces clipped to the cell as
 * chains (listed first, so an edge on both keeps its segment), the ring
 * (corners, midpoints, every side crossing, vertices on the sides; points
 * at one place take one id, chosen alike by both cells) and the vertices
 * inside. Its vertices map back by id, new ones are appended, its
 * constrained edges go back to the segments of their pieces.
 *
 * Constrained edges are listed once per input segment covering them, ids
 * ascending, so region selection can count even-odd parity.
 * Not served, TSR_ERR_UNSUPPORTED with the reason: the hull region (the
 * quadtree covers the square), conforming or quality refinement, fewer than
 * three distinct points, collinear input, a max_area below the depth limit
 * or above 4^12 cells, inputs on the grid for every shift, trees beyond the
 * cell budget. */
#include "tessellate/triangulate_internal.h"

#include <assert.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define NONE UINT32_MAX
#define PIECE_BIT 0x80000000u
#define DEPTH_DEFAULT 24
#define DEPTH_MAX 29    /* integer grid keys: coordinates at level depth + 1 in 31 bits */
#define PAIR_TEST_MAX 8 /* non-simple leaves with at most this many features test their pairs */
#define ROUNDS 4        /* tree builds that may still split pieces at what they found */
#define SHIFT_TRIES 8
#define AREA_LEVEL_MAX 12
#define GRID_NONE 255
#define VERTEX_MARGIN 0.0625 /* of the cell; 1/8 gave 60% more triangles and no better angles */
#define KCACHE_BITS 12       /* recent grid keys: most lookups repeat a corner just seen */

enum { R_SIMPLE, R_SPLIT, R_FALLBACK, R_INTERACT, R_ERROR };

typedef struct qpiece {
    uint32_t a, b;      /* vertex ids; the crossing function uses this order */
    uint32_t seg;       /* the lowest input segment covering it */
    uint32_t cov, ncov; /* all of them: seg alone when ncov is 1, else q->cov[cov..] */
} qpiece;

typedef struct qnode {
    uint32_t parent, child; /* child: first of four (quadrant x + 2y); 0 for a leaf */
    uint32_t ix, iy;
    uint32_t f, nf;              /* features: vertex ids, then PIECE_BIT | piece */
    uint8_t level, queued, fine; /* fine: sides with a finer neighbour, from the last build look */
} qnode;

typedef struct qinter {
    uint32_t kind; /* 0: vertex `other` lies inside piece p; 1: pieces p < other cross */
    uint32_t p, other;
} qinter;

/* A piece meeting a leaf: its points on the ring and which ends lie in the closed cell. */
typedef struct qmeet {
    uint32_t piece;
    uint8_t n, ends, use, pad;
    uint8_t grid[4], side[4];
    double w[4];    /* crossing: the coordinate along its side */
    uint32_t ri[4]; /* ring index of each point */
} qmeet;

typedef struct qpt {
    double p[2], key;
    uint64_t ik;   /* grid point or crossing: its integer key, the same in every cell */
    uint32_t id;   /* output vertex, NONE until known */
    uint32_t meet; /* crossing: meet index, else NONE */
    uint8_t grid, side, k, keyed;
} qpt;

typedef struct qcell {
    uint32_t n;
    int level;
    double xs[3], ys[3];   /* x0 xm x1, y0 ym y1 */
    double g[8][2];        /* BL BR TR TL, then midpoints of bottom right top left */
    uint64_t gk[8];        /* their integer keys */
    uint64_t lx[3], ly[3]; /* integer coordinates of xs, ys at level depth + 1 */
    double vx[2], vy[2];   /* where a lone vertex may lie */
    bool fine[4];          /* sides: bottom right top left */
} qcell;

typedef struct qsplit {
    uint32_t p, v;
    double t;
} qsplit;

typedef struct qslot {
    double x, y;
    uint32_t id; /* NONE: empty */
    uint32_t pad;
} qslot;

typedef struct qkslot {
    uint64_t key;
    uint32_t id; /* NONE: empty */
    uint32_t pad;
} qkslot;

typedef struct qt {
    const tsr_allocator *al;
    double *xy; /* output vertices: distinct inputs, crossings, then the rest */
    size_t nxy, capxy;
    qslot *hs; /* coordinate hash: inputs and crossings */
    size_t hcap;
    qkslot *ks; /* integer-key hash: grid points and side crossings */
    size_t kcap, nks;
    int kbits;
    qkslot *kc;        /* direct-mapped cache in front of it, 1 << KCACHE_BITS */
    uint32_t nin, nfv; /* distinct inputs; feature vertices (inputs and crossings) */
    qpiece *pc;
    size_t npc, cappc;
    uint32_t *cov; /* cover lists of merged pieces, ascending segment ids */
    size_t ncov, capcov;
    qnode *nd;
    size_t nnd, capnd, budget;
    uint32_t *ft;
    size_t nft, capft;
    uint32_t *stk;
    size_t nstk, capstk;
    uint8_t *mask;
    size_t capmask;
    double ox, oy, S, h[DEPTH_MAX + 2];
    int depth, min_level;
    bool detect;
    qinter *it;
    size_t nit, capit;
    /* one leaf's scratch */
    uint32_t *sv;
    size_t nsv, capsv;
    qmeet *sm;
    size_t nsm, capsm;
    qpt *ring;
    size_t nring, npt, capring;
    uint32_t *idx;
    size_t capidx;
    uint32_t *stri;
    size_t nstri, capstri;
    uint32_t *sedge;
    size_t nsedge, capsedge;
    /* results */
    uint32_t *tri;
    size_t ntri, captri;
    uint32_t *edge; /* a, b, segment */
    size_t nedge, capedge;
    uint32_t intersections, fallback_cells;
    const char *why_not;
    tsr_status status;
    tsr_error *err;
} qt;

/* ---- growable arrays, coordinate hash ------------------------------- */

static bool reserve_(const tsr_allocator *al, void *slot, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    size_t nc = *cap < 16 ? 16 : *cap;
    while (nc < need)
        nc *= 2;
    if (nc > SIZE_MAX / elem)
        return false;
    void *p;
    memcpy(&p, slot, sizeof p);
    void *np = tsr_realloc(al, p, nc * elem);
    if (!np)
        return false;
    memcpy(slot, &np, sizeof np);
    *cap = nc;
    return true;
}
#define RESERVE(q, arr, cap, need) reserve_((q)->al, &(arr), &(cap), (need), sizeof *(arr))

static const double *V(const qt *q, uint32_t v)
{
    return q->xy + 2 * (size_t)v;
}

static uint64_t hash_xy(double x, double y)
{
    uint64_t a, b;
    x += 0.0; /* -0 and +0 are one point */
    y += 0.0;
    memcpy(&a, &x, sizeof a);
    memcpy(&b, &y, sizeof b);
    uint64_t h = (a ^ (b * 0x9E3779B97F4A7C15ull)) * 0xBF58476D1CE4E5B9ull;
    h ^= h >> 31;
    h *= 0x94D049BB133111EBull;
    return h ^ (h >> 29);
}

static bool hash_grow(qt *q, size_t need)
{
    size_t nc = q->hcap ? q->hcap : 1024;
    while (nc < 2 * need)
        nc *= 2;
    if (nc == q->hcap)
        return true;
    qslot *hs = tsr_alloc(q->al, nc * sizeof *hs);
    if (!hs)
        return false;
    for (size_t i = 0; i < nc; i++)
        hs[i].id = NONE;
    for (size_t k = 0; k < q->hcap; k++) {
        if (q->hs[k].id == NONE)
            continue;
        size_t i = hash_xy(q->hs[k].x, q->hs[k].y) & (nc - 1);
        while (hs[i].id != NONE)
            i = (i + 1) & (nc - 1);
        hs[i] = q->hs[k];
    }
    tsr_free(q->al, q->hs);
    q->hs = hs;
    q->hcap = nc;
    return true;
}

/* The vertex at exactly (x, y), added when new (*added says so); NONE when
 * out of memory. */
static uint32_t vertex_id(qt *q, double x, double y, bool *added)
{
    if (added)
        *added = false;
    if (2 * (q->nxy + 1) > q->hcap && !hash_grow(q, q->nxy + 1))
        return NONE;
    size_t mask = q->hcap - 1, i = hash_xy(x, y) & mask;
    for (; q->hs[i].id != NONE; i = (i + 1) & mask)
        if (q->hs[i].x == x && q->hs[i].y == y)
            return q->hs[i].id;
    if (q->nxy >= UINT32_MAX - 2 || !RESERVE(q, q->xy, q->capxy, 2 * (q->nxy + 1)))
        return NONE;
    q->xy[2 * q->nxy] = x;
    q->xy[2 * q->nxy + 1] = y;
    q->hs[i] = (qslot){x, y, (uint32_t)q->nxy, 0};
    if (added)
        *added = true;
    return (uint32_t)q->nxy++;
}

static bool khash_grow(qt *q, size_t need)
{
    if (!q->kc) {
        q->kc = tsr_alloc(q->al, ((size_t)1 << KCACHE_BITS) * sizeof *q->kc);
        if (!q->kc)
            return false;
        for (size_t i = 0; i < (size_t)1 << KCACHE_BITS; i++)
            q->kc[i].id = NONE;
    }
    size_t nc = q->kcap ? q->kcap : 1024;
    while (3 * nc < 4 * need)
        nc *= 2;
    if (nc == q->kcap)
        return true;
    qkslot *ks = tsr_alloc(q->al, nc * sizeof *ks);
    if (!ks)
        return false;
    for (size_t i = 0; i < nc; i++)
        ks[i].id = NONE;
    int bits = 0;
    while ((size_t)1 << bits < nc)
        bits++;
    for (size_t k = 0; k < q->kcap; k++) {
        if (q->ks[k].id == NONE)
            continue;
        size_t i = (size_t)((q->ks[k].key * 0x9E3779B97F4A7C15ull) >> (64 - bits));
        while (ks[i].id != NONE)
            i = (i + 1) & (nc - 1);
        ks[i] = q->ks[k];
    }
    tsr_free(q->al, q->ks);
    q->ks = ks;
    q->kcap = nc;
    q->kbits = bits;
    return true;
}

/* The output vertex of the grid point or crossing with integer key `key`
 * at (x, y), appended when new; NONE when out of memory. */
static uint32_t point_id(qt *q, uint64_t key, double x, double y)
{
    if (4 * (q->nks + 1) > 3 * q->kcap && !khash_grow(q, q->nks + 1))
        return NONE;
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    qkslot *c = &q->kc[h >> (64 - KCACHE_BITS)];
    if (c->id != NONE && c->key == key)
        return c->id;
    size_t mask = q->kcap - 1, i = (size_t)(h >> (64 - q->kbits));
    for (; q->ks[i].id != NONE; i = (i + 1) & mask)
        if (q->ks[i].key == key) {
            *c = q->ks[i];
            return c->id;
        }
    if (q->nxy >= UINT32_MAX - 2 || !RESERVE(q, q->xy, q->capxy, 2 * (q->nxy + 1)))
        return NONE;
    q->xy[2 * q->nxy] = x;
    q->xy[2 * q->nxy + 1] = y;
    q->ks[i] = (qkslot){key, (uint32_t)q->nxy, 0};
    *c = q->ks[i];
    q->nks++;
    return (uint32_t)q->nxy++;
}

/* A new output vertex at (x, y) (a point inside one cell). */
static uint32_t new_vertex(qt *q, double x, double y)
{
    if (q->nxy >= UINT32_MAX - 2 || !RESERVE(q, q->xy, q->capxy, 2 * (q->nxy + 1)))
        return NONE;
    q->xy[2 * q->nxy] = x;
    q->xy[2 * q->nxy + 1] = y;
    return (uint32_t)q->nxy++;
}

/* The output vertex of ring point p. */
static uint32_t ring_id(qt *q, qpt *p)
{
    if (p->id == NONE)
        p->id = p->keyed ? point_id(q, p->ik, p->p[0], p->p[1]) : new_vertex(q, p->p[0], p->p[1]);
    return p->id;
}

static int nomem(qt *q)
{
    q->status = TSR_ERR_NOMEM;
    return R_ERROR;
}

/* ---- pieces -------------------------------------------------------- */

static int piece_cmp(const void *x, const void *y)
{
    const qpiece *a = x, *b = y;
    uint32_t a0 = a->a < a->b ? a->a : a->b, a1 = a->a ^ a->b ^ a0;
    uint32_t b0 = b->a < b->b ? b->a : b->b, b1 = b->a ^ b->b ^ b0;
    if (a0 != b0)
        return a0 < b0 ? -1 : 1;
    if (a1 != b1)
        return a1 < b1 ? -1 : 1;
    return (a->seg > b->seg) - (a->seg < b->seg);
}

static const uint32_t *cover(const qt *q, const qpiece *p)
{
    return p->ncov == 1 ? &p->seg : q->cov + p->cov;
}

static int u32_cmp(const void *x, const void *y)
{
    uint32_t a = *(const uint32_t *)x, b = *(const uint32_t *)y;
    return (a > b) - (a < b);
}

/* Sorts the pieces and merges those between the same two vertices, keeping
 * every segment that covers them (the region's even-odd rule counts them). */
static bool pieces_normalise(qt *q)
{
    if (q->npc > 1)
        qsort(q->pc, q->npc, sizeof *q->pc, piece_cmp);
    size_t m = 0;
    for (size_t i = 0, j; i < q->npc; i = j) {
        qpiece p = q->pc[i];
        size_t n = p.ncov;
        for (j = i + 1;
             j < q->npc && ((q->pc[j].a == p.a && q->pc[j].b == p.b) || (q->pc[j].a == p.b && q->pc[j].b == p.a)); j++)
            n += q->pc[j].ncov;
        if (j > i + 1) {
            if (!RESERVE(q, q->cov, q->capcov, q->ncov + n))
                return false;
            uint32_t *list = q->cov + q->ncov;
            size_t k = 0;
            for (size_t r = i; r < j; r++) {
                const uint32_t *c = cover(q, &q->pc[r]);
                for (uint32_t t = 0; t < q->pc[r].ncov; t++)
                    list[k++] = c[t];
            }
            qsort(list, k, sizeof *list, u32_cmp);
            size_t u = 0;
            for (size_t r = 0; r < k; r++)
                if (!u || list[u - 1] != list[r])
                    list[u++] = list[r];
            p.seg = list[0];
            p.cov = (uint32_t)q->ncov;
            p.ncov = (uint32_t)u;
            q->ncov += u;
        }
        q->pc[m++] = p;
    }
    q->npc = m;
    return true;
}

/* Appends edge a-b of piece pi: once per segment covering it. */
static bool add_edge(qt *q, uint32_t a, uint32_t b, uint32_t pi)
{
    const qpiece *p = &q->pc[pi];
    if (!RESERVE(q, q->edge, q->capedge, q->nedge + 3 * (size_t)p->ncov))
        return false;
    const uint32_t *c = cover(q, p);
    for (uint32_t t = 0; t < p->ncov; t++) {
        q->edge[q->nedge++] = a;
        q->edge[q->nedge++] = b;
        q->edge[q->nedge++] = c[t];
    }
    return true;
}

/* The other coordinate where the line of piece (A, B) meets the line
 * {axis ax = c}. One function for every cell, so both sides of a shared
 * side compute the same double. */
static double cross_coord(const double *A, const double *B, int ax, double c)
{
    double t = (c - A[ax]) / (B[ax] - A[ax]);
    return A[1 - ax] + t * (B[1 - ax] - A[1 - ax]);
}

static int sgn(double v)
{
    return (v > 0) - (v < 0);
}

/* Position of P along piece (A, B), for ordering points on it. */
static double along(const double *A, const double *B, const double *P)
{
    int ax = fabs(B[0] - A[0]) >= fabs(B[1] - A[1]) ? 0 : 1;
    return (P[ax] - A[ax]) / (B[ax] - A[ax]);
}

/* P strictly inside segment AB (exactly on it). */
static bool on_open_segment(const double *A, const double *B, const double *P)
{
    if (tsr_orient2d(A, B, P) != 0)
        return false;
    int ax = A[0] != B[0] ? 0 : 1;
    return (A[ax] < P[ax] && P[ax] < B[ax]) || (B[ax] < P[ax] && P[ax] < A[ax]);
}

/* ---- tree ---------------------------------------------------------- */

static bool is_leaf(const qt *q, uint32_t n)
{
    return q->nd[n].child == 0;
}

/* The node of n's level across side s (0 bottom, 1 right, 2 top, 3 left),
 * or the coarser leaf there; NONE at the border of the square. */
static uint32_t neighbour(const qt *q, uint32_t n, int s)
{
    static const uint8_t bit[4] = {2, 1, 2, 1};
    static const uint8_t inside[4] = {2, 0, 0, 1};
    uint8_t path[DEPTH_MAX + 2];
    int k = 0;
    uint32_t cur = n;
    for (;;) {
        if (cur == 0)
            return NONE;
        const qnode *c = &q->nd[cur];
        unsigned quad = (c->ix & 1) | ((c->iy & 1) << 1);
        if ((quad & bit[s]) == inside[s]) {
            cur = q->nd[c->parent].child + (quad ^ bit[s]);
            break;
        }
        path[k++] = (uint8_t)quad;
        cur = c->parent;
    }
    while (k > 0 && !is_leaf(q, cur))
        cur = q->nd[cur].child + (path[--k] ^ bit[s]);
    return cur;
}

static bool push(qt *q, uint32_t n)
{
    if (q->nd[n].queued)
        return true;
    if (!RESERVE(q, q->stk, q->capstk, q->nstk + 1))
        return false;
    q->nd[n].queued = 1;
    q->stk[q->nstk++] = n;
    return true;
}

static double gcoord(const qt *q, double o, int level, double u)
{
    return o + u * q->h[level];
}

static void cell_geometry(const qt *q, uint32_t n, qcell *c)
{
    const qnode *d = &q->nd[n];
    int L = d->level;
    double fx = d->ix, fy = d->iy;
    c->n = n;
    c->level = L;
    for (int i = 0; i < 3; i++) {
        c->xs[i] = gcoord(q, q->ox, L, fx + 0.5 * i);
        c->ys[i] = gcoord(q, q->oy, L, fy + 0.5 * i);
    }
    /* a vertex keeps VERTEX_MARGIN of the cell from its sides, less in the last
     * levels before the depth limit, and at the limit only off them */
    double m = L < q->depth - 2 ? VERTEX_MARGIN : L < q->depth ? VERTEX_MARGIN / 4 : 0;
    c->vx[0] = gcoord(q, q->ox, L, fx + m);
    c->vx[1] = gcoord(q, q->ox, L, fx + 1 - m);
    c->vy[0] = gcoord(q, q->oy, L, fy + m);
    c->vy[1] = gcoord(q, q->oy, L, fy + 1 - m);
    if (m == 0) {
        c->vx[0] = nextafter(c->vx[0], INFINITY);
        c->vx[1] = nextafter(c->vx[1], -INFINITY);
        c->vy[0] = nextafter(c->vy[0], INFINITY);
        c->vy[1] = nextafter(c->vy[1], -INFINITY);
    }
    int sh = q->depth - L; /* half a cell at level depth + 1 */
    for (int i = 0; i < 3; i++) {
        c->lx[i] = ((uint64_t)2 * d->ix + (unsigned)i) << sh;
        c->ly[i] = ((uint64_t)2 * d->iy + (unsigned)i) << sh;
    }
    static const uint8_t gi[8][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}};
    for (int k = 0; k < 8; k++) {
        c->g[k][0] = c->xs[gi[k][0]];
        c->g[k][1] = c->ys[gi[k][1]];
        c->gk[k] = c->lx[gi[k][0]] << 31 | c->ly[gi[k][1]];
    }
}

/* Splits leaf n into four, handing each child the features meeting its
 * closed square; queues the children and n's leaf neighbours. */
static int split(qt *q, uint32_t n)
{
    if (q->nnd + 4 > q->budget) {
        q->why_not = "the quadtree would need too many cells (features too close together for its depth)";
        q->status = TSR_ERR_UNSUPPORTED;
        return R_ERROR;
    }
    uint32_t nf = q->nd[n].nf, f0 = q->nd[n].f;
    if (!RESERVE(q, q->nd, q->capnd, q->nnd + 4) || !RESERVE(q, q->ft, q->capft, q->nft + 4 * (size_t)nf) ||
        !RESERVE(q, q->mask, q->capmask, nf))
        return nomem(q);
    if (q->nft + 4 * (size_t)nf >= UINT32_MAX) {
        q->why_not = "the quadtree's feature lists would be too long";
        q->status = TSR_ERR_UNSUPPORTED;
        return R_ERROR;
    }
    qcell c;
    cell_geometry(q, n, &c);
    const uint32_t *list = q->ft + f0;
    for (uint32_t i = 0; i < nf; i++) {
        uint32_t f = list[i];
        unsigned m = 0;
        if (!(f & PIECE_BIT)) {
            const double *P = V(q, f);
            unsigned wx = P[0] <= c.xs[1], ex = P[0] >= c.xs[1], sy = P[1] <= c.ys[1], ny = P[1] >= c.ys[1];
            m = (wx && sy) | (ex && sy) << 1 | (wx && ny) << 2 | (ex && ny) << 3;
        } else {
            const qpiece *p = &q->pc[f & ~PIECE_BIT];
            const double *A = V(q, p->a), *B = V(q, p->b);
            double lx = A[0] < B[0] ? A[0] : B[0];
            double ux = A[0] < B[0] ? B[0] : A[0], ly = A[1] < B[1] ? A[1] : B[1], uy = A[1] < B[1] ? B[1] : A[1];
            int o[9];
            bool have[9] = {false};
            for (unsigned quad = 0; quad < 4; quad++) {
                unsigned cx = quad & 1, cy = quad >> 1;
                if (ux < c.xs[cx] || lx > c.xs[cx + 1] || uy < c.ys[cy] || ly > c.ys[cy + 1])
                    continue;
                int pos = 0, neg = 0;
                for (unsigned k = 0; k < 4; k++) {
                    unsigned gx = cx + (k & 1), gy = cy + (k >> 1), g = gy * 3 + gx;
                    if (!have[g]) {
                        double P[2] = {c.xs[gx], c.ys[gy]};
                        o[g] = sgn(tsr_orient2d(A, B, P));
                        have[g] = true;
                    }
                    pos += o[g] > 0;
                    neg += o[g] < 0;
                }
                if (pos < 4 && neg < 4)
                    m |= 1u << quad;
            }
        }
        q->mask[i] = (uint8_t)m;
    }
    uint32_t first = (uint32_t)q->nnd;
    q->nnd += 4;
    qnode *d = &q->nd[n];
    d->child = first;
    for (unsigned quad = 0; quad < 4; quad++) {
        qnode *ch = &q->nd[first + quad];
        ch->parent = n;
        ch->child = 0;
        ch->ix = 2 * d->ix + (quad & 1);
        ch->iy = 2 * d->iy + (quad >> 1);
        ch->level = (uint8_t)(d->level + 1);
        ch->queued = 0;
        ch->fine = 0;
        ch->f = (uint32_t)q->nft;
        for (uint32_t i = 0; i < nf; i++)
            if (q->mask[i] >> quad & 1)
                q->ft[q->nft++] = q->ft[f0 + i];
        ch->nf = (uint32_t)(q->nft - ch->f);
    }
    for (unsigned quad = 0; quad < 4; quad++)
        if (!push(q, first + quad))
            return nomem(q);
    for (int s = 0; s < 4; s++) {
        uint32_t m = neighbour(q, n, s);
        if (m != NONE && is_leaf(q, m) && !push(q, m))
            return nomem(q);
    }
    return R_SPLIT;
}

/* ---- one leaf ------------------------------------------------------ */

static bool in_closed(const qcell *c, const double *P)
{
    return P[0] >= c->xs[0] && P[0] <= c->xs[2] && P[1] >= c->ys[0] && P[1] <= c->ys[2];
}

/* Where piece pi meets the closed cell: false when it does not. */
static bool piece_meet(const qt *q, const qcell *c, uint32_t pi, qmeet *m)
{
    const qpiece *p = &q->pc[pi];
    const double *A = V(q, p->a), *B = V(q, p->b);
    double x0 = c->xs[0], x1 = c->xs[2], y0 = c->ys[0], y1 = c->ys[2];
    if ((A[0] < x0 && B[0] < x0) || (A[0] > x1 && B[0] > x1) || (A[1] < y0 && B[1] < y0) || (A[1] > y1 && B[1] > y1))
        return false;
    int o[8];
    for (int k = 0; k < 4; k++)
        o[k] = sgn(tsr_orient2d(A, B, c->g[k]));
    if ((o[0] > 0 && o[1] > 0 && o[2] > 0 && o[3] > 0) || (o[0] < 0 && o[1] < 0 && o[2] < 0 && o[3] < 0))
        return false;
    m->piece = pi;
    m->n = 0;
    m->use = 0;
    m->ends = (uint8_t)(in_closed(c, A) | in_closed(c, B) << 1);
    unsigned hits = 0;
    for (int s = 0; s < 4; s++) {
        int ax = (s & 1) ? 0 : 1; /* the axis held constant on side s */
        double cv = s == 0 ? y0 : s == 1 ? x1 : s == 2 ? y1 : x0;
        if (!((A[ax] < cv && B[ax] > cv) || (A[ax] > cv && B[ax] < cv)))
            continue;
        int k1 = s, k2 = (s + 1) & 3, km = 4 + s;
        int s1 = o[k1], s2 = o[k2], sm = 0;
        if (c->fine[s])
            sm = o[km] = sgn(tsr_orient2d(A, B, c->g[km]));
        if (s1 == 0)
            hits |= 1u << k1;
        else if (s2 == 0)
            hits |= 1u << k2;
        else if (c->fine[s] && sm == 0)
            hits |= 1u << km;
        else if (s1 != s2) {
            double a1 = c->g[k1][1 - ax], a2 = c->g[k2][1 - ax];
            if (c->fine[s]) {
                if (s1 != sm)
                    a2 = c->g[km][1 - ax];
                else
                    a1 = c->g[km][1 - ax];
            }
            double lo = a1 < a2 ? a1 : a2, hi = a1 < a2 ? a2 : a1;
            double w = cross_coord(A, B, ax, cv);
            if (!(w > lo))
                w = nextafter(lo, hi);
            if (!(w < hi))
                w = nextafter(hi, lo);
            if (m->n < 4) {
                m->grid[m->n] = GRID_NONE;
                m->side[m->n] = (uint8_t)s;
                m->w[m->n] = w;
                m->n++;
            }
        }
    }
    for (int g = 0; g < 8; g++)
        if (hits >> g & 1 && m->n < 4) {
            m->grid[m->n] = (uint8_t)g;
            m->side[m->n] = (uint8_t)(g & 3);
            m->w[m->n] = 0;
            m->n++;
        }
    return m->n > 0 || m->ends;
}

static int qpt_cmp(const void *x, const void *y)
{
    const qpt *a = x, *b = y;
    return (a->key > b->key) - (a->key < b->key);
}

static void sort_pts(qpt *p, size_t n)
{
    if (n > 16) {
        qsort(p, n, sizeof *p, qpt_cmp);
        return;
    }
    for (size_t i = 1; i < n; i++) {
        qpt t = p[i];
        size_t j = i;
        while (j > 0 && p[j - 1].key > t.key) {
            p[j] = p[j - 1];
            j--;
        }
        p[j] = t;
    }
}

static qpt grid_pt(const qcell *c, int g)
{
    qpt p;
    p.p[0] = c->g[g][0];
    p.p[1] = c->g[g][1];
    p.id = NONE;
    p.meet = NONE;
    p.grid = (uint8_t)g;
    p.side = (uint8_t)(g & 3);
    p.k = 0;
    p.keyed = 1;
    p.ik = c->gk[g];
    p.key = 0;
    return p;
}

static double side_key(int s, double x, double y)
{
    return s == 0 ? x : s == 1 ? y : s == 2 ? -x : -y;
}

/* Builds the ring of cell c: per side its start corner, its midpoint when
 * the neighbour is finer, the crossings of the meets marked `use` (all
 * meets when all_meets) and, when with_vertices, the vertices of q->sv on
 * the side. Fills meet ring indices. False on two points at one place. */
static bool build_ring(qt *q, const qcell *c, bool all_meets, bool with_vertices)
{
    q->nring = 0;
    uint32_t gidx[8];
    for (int g = 0; g < 8; g++)
        gidx[g] = NONE;
    bool ok = true;
    for (int s = 0; s < 4; s++) {
        size_t start = q->nring;
        size_t need = start + 2 + 2 * q->nsm + q->nsv;
        if (!RESERVE(q, q->ring, q->capring, need + 8)) {
            q->status = TSR_ERR_NOMEM;
            return false;
        }
        q->ring[q->nring] = grid_pt(c, s);
        q->ring[q->nring].key = side_key(s, c->g[s][0], c->g[s][1]);
        q->nring++;
        if (c->fine[s]) {
            qpt p = grid_pt(c, 4 + s);
            p.key = side_key(s, p.p[0], p.p[1]);
            q->ring[q->nring++] = p;
        }
        for (size_t i = 0; i < q->nsm; i++) {
            qmeet *m = &q->sm[i];
            if (!m->use && !all_meets)
                continue;
            for (int k = 0; k < m->n; k++) {
                if (m->grid[k] != GRID_NONE || m->side[k] != s)
                    continue;
                qpt p;
                if (s & 1) {
                    p.p[0] = c->g[s][0];
                    p.p[1] = m->w[k];
                } else {
                    p.p[0] = m->w[k];
                    p.p[1] = c->g[s][1];
                }
                p.key = side_key(s, p.p[0], p.p[1]);
                p.id = NONE;
                p.meet = (uint32_t)i;
                p.grid = GRID_NONE;
                p.side = (uint8_t)s;
                p.k = (uint8_t)k;
                p.keyed = 1;
                uint64_t line = s == 0 ? c->ly[0] : s == 1 ? c->lx[2] : s == 2 ? c->ly[2] : c->lx[0];
                p.ik = 1ull << 63 | (uint64_t)m->piece << 32 | (uint64_t)(~s & 1) << 31 | line;
                q->ring[q->nring++] = p;
            }
        }
        if (with_vertices) {
            for (size_t i = 0; i < q->nsv; i++) {
                const double *P = V(q, q->sv[i]);
                bool on = s == 0   ? P[1] == c->ys[0]
                          : s == 1 ? P[0] == c->xs[2]
                          : s == 2 ? P[1] == c->ys[2]
                                   : P[0] == c->xs[0];
                if (!on)
                    continue;
                qpt p = grid_pt(c, s);
                p.p[0] = P[0];
                p.p[1] = P[1];
                p.key = side_key(s, p.p[0], p.p[1]);
                p.grid = GRID_NONE;
                p.keyed = 0;
                p.id = q->sv[i];
                double kc = side_key(s, c->g[s][0], c->g[s][1]);
                double ke = side_key(s, c->g[(s + 1) & 3][0], c->g[(s + 1) & 3][1]);
                if (p.key > kc && p.key < ke)
                    q->ring[q->nring++] = p;
                else if (p.key == kc) { /* a vertex on the corner is the corner */
                    q->ring[start].keyed = 0;
                    q->ring[start].id = q->sv[i];
                }
            }
        }
        sort_pts(q->ring + start + 1, q->nring - start - 1);
        for (size_t i = start + 1; i < q->nring; i++)
            if (q->ring[i].key == q->ring[i - 1].key)
                ok = false;
    }
    for (size_t i = 0; i < q->nring; i++) {
        qpt *p = &q->ring[i];
        if (p->grid != GRID_NONE)
            gidx[p->grid] = (uint32_t)i;
        else if (p->meet != NONE)
            q->sm[p->meet].ri[p->k] = (uint32_t)i;
    }
    for (size_t i = 0; i < q->nsm; i++) {
        qmeet *m = &q->sm[i];
        for (int k = 0; k < m->n; k++)
            if (m->grid[k] != GRID_NONE)
                m->ri[k] = gidx[m->grid[k]];
    }
    q->npt = q->nring;
    return ok;
}

static bool add_tri(qt *q, uint32_t a, uint32_t b, uint32_t c)
{
    if (!RESERVE(q, q->stri, q->capstri, q->nstri + 3))
        return false;
    q->stri[q->nstri++] = a;
    q->stri[q->nstri++] = b;
    q->stri[q->nstri++] = c;
    return true;
}

static bool add_sedge(qt *q, uint32_t a, uint32_t b, uint32_t piece)
{
    if (!RESERVE(q, q->sedge, q->capsedge, q->nsedge + 3))
        return false;
    q->sedge[q->nsedge++] = a;
    q->sedge[q->nsedge++] = b;
    q->sedge[q->nsedge++] = piece;
    return true;
}

static const double *pt_xy(const qt *q, uint32_t i)
{
    return q->ring[i].p;
}

static bool ccw(const qt *q, uint32_t a, uint32_t b, uint32_t c)
{
    return tsr_orient2d(pt_xy(q, a), pt_xy(q, b), pt_xy(q, c)) > 0;
}

/* Shape of triangle abc: 4 sqrt(3) area / (sum of squared sides), 1 when
 * equilateral, 0 when flat. */
static double shape(const double *a, const double *b, const double *c)
{
    double ux = b[0] - a[0], uy = b[1] - a[1], vx = c[0] - a[0], vy = c[1] - a[1], wx = c[0] - b[0], wy = c[1] - b[1];
    double s2 = ux * ux + uy * uy + vx * vx + vy * vy + wx * wx + wy * wy;
    return s2 > 0 ? 3.4641016151377544 * (ux * vy - uy * vx) / s2 : 0;
}

/* The sides of the cell a ring point lies on (bits 0-3; a corner lies on
 * two), 0 for a point inside. */
static unsigned side_mask(const qpt *p)
{
    if (p->grid < 4)
        return 1u << p->grid | 1u << ((p->grid + 3) & 3);
    return p->grid != GRID_NONE || p->meet != NONE ? 1u << p->side : 0;
}

/* Fans the convex polygon idx[0..k) (ring points, counter-clockwise; its
 * points lie on the cell's sides, so three are collinear exactly when they
 * share a side) from the point whose fan has the best worst triangle,
 * checked with orient2d, else from the mean of its points. False when
 * neither works (or out of memory: q->status). */
static bool fan_part(qt *q, const uint32_t *idx, size_t k)
{
    if (k < 3)
        return false;
    size_t best = k, tries = k == 3 ? 1 : k == 4 ? 2 : k; /* in a quad, apex 2 repeats apex 0 */
    double best_shape = -1;
    for (size_t a = 0; a < tries; a++) {
        unsigned ma = side_mask(&q->ring[idx[a]]);
        double worst = 1;
        for (size_t e = 0; e < k && worst >= 0; e++) {
            size_t f = (e + 1) % k;
            if (e == a || f == a)
                continue;
            if (ma & side_mask(&q->ring[idx[e]]) & side_mask(&q->ring[idx[f]]))
                worst = -1; /* flat */
            else {
                double sh = shape(pt_xy(q, idx[a]), pt_xy(q, idx[e]), pt_xy(q, idx[f]));
                worst = sh < worst ? sh : worst;
            }
        }
        if (worst >= 0 && worst > best_shape) {
            best = a;
            best_shape = worst;
        }
    }
    bool good = best < k;
    for (size_t e = 0; e < k && good; e++) {
        size_t f = (e + 1) % k;
        if (e != best && f != best)
            good = ccw(q, idx[best], idx[e], idx[f]);
    }
    if (good) {
        for (size_t e = 0; e < k; e++) {
            size_t f = (e + 1) % k;
            if (e != best && f != best && !add_tri(q, idx[best], idx[e], idx[f])) {
                q->status = TSR_ERR_NOMEM;
                return false;
            }
        }
        return true;
    }
    double sx = 0, sy = 0;
    for (size_t e = 0; e < k; e++) {
        sx += q->ring[idx[e]].p[0];
        sy += q->ring[idx[e]].p[1];
    }
    if (!RESERVE(q, q->ring, q->capring, q->npt + 1)) {
        q->status = TSR_ERR_NOMEM;
        return false;
    }
    uint32_t m = (uint32_t)q->npt++;
    q->ring[m] = q->ring[idx[0]];
    q->ring[m].p[0] = sx / (double)k;
    q->ring[m].p[1] = sy / (double)k;
    q->ring[m].id = NONE;
    q->ring[m].grid = GRID_NONE;
    q->ring[m].meet = NONE;
    q->ring[m].keyed = 0;
    for (size_t e = 0; e < k; e++)
        if (!ccw(q, m, idx[e], idx[(e + 1) % k]))
            return false;
    for (size_t e = 0; e < k; e++)
        if (!add_tri(q, m, idx[e], idx[(e + 1) % k])) {
            q->status = TSR_ERR_NOMEM;
            return false;
        }
    return true;
}

/* Tests every pair of features in the leaf's scratch; records what meets. */
static bool pair_tests(qt *q)
{
    bool found = false;
    for (size_t i = 0; i < q->nsv; i++) {
        uint32_t v = q->sv[i];
        for (size_t j = 0; j < q->nsm; j++) {
            const qpiece *p = &q->pc[q->sm[j].piece];
            if (p->a == v || p->b == v || !on_open_segment(V(q, p->a), V(q, p->b), V(q, v)))
                continue;
            if (!RESERVE(q, q->it, q->capit, q->nit + 1))
                return nomem(q), false;
            q->it[q->nit++] = (qinter){0, q->sm[j].piece, v};
            found = true;
        }
    }
    for (size_t i = 0; i < q->nsm; i++)
        for (size_t j = i + 1; j < q->nsm; j++) {
            uint32_t pi = q->sm[i].piece, pj = q->sm[j].piece;
            const qpiece *p = &q->pc[pi], *r = &q->pc[pj];
            const double *A = V(q, p->a), *B = V(q, p->b), *C = V(q, r->a), *D = V(q, r->b);
            int o1 = sgn(tsr_orient2d(A, B, C)), o2 = sgn(tsr_orient2d(A, B, D));
            if (o1 == 0 && o2 == 0) { /* collinear: split each at the other's ends inside it */
                const uint32_t ends[4][2] = {{pi, r->a}, {pi, r->b}, {pj, p->a}, {pj, p->b}};
                for (int k = 0; k < 4; k++) {
                    const qpiece *h = &q->pc[ends[k][0]];
                    if (!on_open_segment(V(q, h->a), V(q, h->b), V(q, ends[k][1])))
                        continue;
                    if (!RESERVE(q, q->it, q->capit, q->nit + 1))
                        return nomem(q), false;
                    q->it[q->nit++] = (qinter){0, ends[k][0], ends[k][1]};
                    found = true;
                }
                continue;
            }
            if (o1 * o2 >= 0 || p->a == r->a || p->a == r->b || p->b == r->a || p->b == r->b)
                continue;
            int o3 = sgn(tsr_orient2d(C, D, A)), o4 = sgn(tsr_orient2d(C, D, B));
            if (o3 * o4 >= 0)
                continue;
            if (!RESERVE(q, q->it, q->capit, q->nit + 1))
                return nomem(q), false;
            q->it[q->nit++] = (qinter){1, pi < pj ? pi : pj, pi < pj ? pj : pi};
            found = true;
        }
    return found;
}

static tsr_status fallback(qt *q, const qcell *c);

/* The ring cut by the chords (meets with use 1; they must not cross: their
 * ring intervals nest) into convex faces, each fanned from the first of its
 * points that serves, except the face holding the apex (ring index `apex`,
 * or NONE), which is fanned from it: the exits of the apex's pieces (meets
 * with use 2) must lie on that face. Chords and apex-to-exit edges become
 * constrained edges. R_SIMPLE, R_SPLIT (chords cross or share a point, an
 * exit lies beyond a chord, a face cannot be fanned) or R_ERROR. */
static int chord_faces(qt *q, uint32_t nr, uint32_t apex)
{
    /* partner[i]: the other end of the chord at ring position i */
    if (!RESERVE(q, q->idx, q->capidx, 10 * (size_t)nr + 8))
        return nomem(q);
    uint32_t *partner = q->idx, *stack = partner + nr, *exit = stack + nr + 1, *start = exit + nr;
    uint32_t *pairs = start + nr + 2, *poly = pairs + 4 * (size_t)nr, nface = 0;
    /* pairs: (face, position), at most 2 per position; poly: faces' points
     * grouped by face, face f at poly[start[f] .. start[f + 1]) */
    size_t nexit = 0;
    for (uint32_t i = 0; i < nr; i++)
        partner[i] = NONE;
    for (size_t i = 0; i < q->nsm; i++) {
        const qmeet *m = &q->sm[i];
        if (m->use == 2) {
            exit[nexit++] = m->ri[0];
            if (!add_sedge(q, apex, m->ri[0], m->piece))
                return nomem(q);
        }
        if (m->use != 1)
            continue;
        uint32_t u = m->ri[0], v = m->ri[1];
        if (u == v || partner[u] != NONE || partner[v] != NONE)
            return R_SPLIT;
        partner[u] = v;
        partner[v] = u;
        if (!add_sedge(q, u, v, m->piece))
            return nomem(q);
    }
    for (size_t e = 0; e < nexit; e++)
        if (partner[exit[e]] != NONE)
            return R_SPLIT;
    /* one pass around the ring: a chord opens a face, its far end closes it */
    size_t np = 0, depth = 0;
    stack[depth++] = nface++;
    for (uint32_t i = 0; i < nr; i++) {
        uint32_t j = partner[i];
        pairs[2 * np] = stack[depth - 1];
        pairs[2 * np++ + 1] = i;
        if (j == NONE)
            continue;
        if (j > i) {
            stack[depth++] = nface++;
            pairs[2 * np] = stack[depth - 1];
            pairs[2 * np++ + 1] = i;
        } else {
            if (depth < 2)
                return R_SPLIT;
            depth--;
            pairs[2 * np] = stack[depth - 1];
            pairs[2 * np++ + 1] = i;
        }
    }
    if (depth != 1)
        return R_SPLIT;
    for (uint32_t f = 0; f <= nface; f++)
        start[f] = 0;
    for (size_t e = 0; e < np; e++)
        start[pairs[2 * e] + 1]++;
    for (uint32_t f = 0; f < nface; f++)
        start[f + 1] += start[f];
    for (size_t e = 0; e < np; e++) /* stable: each face keeps ring order */
        poly[start[pairs[2 * e]]++] = pairs[2 * e + 1];
    for (uint32_t f = nface; f > 0; f--)
        start[f] = start[f - 1];
    start[0] = 0;
    bool placed = apex == NONE;
    for (uint32_t f = 0; f < nface; f++) {
        const uint32_t *face = poly + start[f];
        size_t k = start[f + 1] - start[f];
        if (f > 0 && (k < 2 || partner[face[0]] != face[k - 1]))
            return R_SPLIT; /* chords interleave */
        bool inside = !placed && k >= 3;
        for (size_t e = 0; e < k && inside; e++)
            inside = ccw(q, apex, face[e], face[(e + 1) % k]);
        if (inside) {
            for (size_t x = 0; x < nexit; x++) {
                size_t e = 0;
                while (e < k && face[e] != exit[x])
                    e++;
                if (e == k)
                    return R_SPLIT; /* a chord between the vertex and its exit */
            }
            for (size_t e = 0; e < k; e++)
                if (!add_tri(q, apex, face[e], face[(e + 1) % k]))
                    return nomem(q);
            placed = true;
            continue;
        }
        if (!fan_part(q, face, k))
            return q->status != TSR_OK ? R_ERROR : R_SPLIT;
    }
    return placed ? R_SIMPLE : R_SPLIT;
}

/* Decides leaf n (and with emit, triangulates it into the results). */
static int eval(qt *q, uint32_t n, bool emit)
{
    qcell c;
    const qnode *d = &q->nd[n];
    int L = d->level;
    static const uint8_t adj[4][2] = {{2, 3}, {0, 2}, {0, 1}, {1, 3}};
    if (emit) { /* the tree is final: the build's last look at n saw these neighbours */
        for (int s = 0; s < 4; s++)
            c.fine[s] = d->fine >> s & 1;
    } else {
        unsigned fine = 0;
        for (int s = 0; s < 4; s++) {
            uint32_t m = neighbour(q, n, s);
            c.fine[s] = m != NONE && !is_leaf(q, m);
            if (c.fine[s]) {
                uint32_t ch = q->nd[m].child;
                if (!is_leaf(q, ch + adj[s][0]) || !is_leaf(q, ch + adj[s][1]))
                    return R_SPLIT;
                fine |= 1u << s;
            }
        }
        q->nd[n].fine = (uint8_t)fine;
    }
    if (L < q->min_level)
        return R_SPLIT;
    d = &q->nd[n];
    if (!emit && d->nf == 0)
        return R_SIMPLE; /* rule (a) never fails */
    const uint32_t *list = q->ft + d->f;
    uint32_t nf = d->nf, nvert = 0;
    while (nvert < nf && !(list[nvert] & PIECE_BIT))
        nvert++;
    bool test_pairs = q->detect && (nf <= PAIR_TEST_MAX || L >= q->depth);
    if (nvert >= 2 && L < q->depth && !test_pairs)
        return R_SPLIT;
    cell_geometry(q, n, &c);
    if (!RESERVE(q, q->sv, q->capsv, nvert) || !RESERVE(q, q->sm, q->capsm, nf - nvert))
        return nomem(q);
    q->nsv = 0;
    q->nsm = 0;
    for (uint32_t i = 0; i < nvert; i++)
        q->sv[q->nsv++] = list[i];
    for (uint32_t i = nvert; i < nf; i++)
        if (piece_meet(q, &c, list[i] & ~PIECE_BIT, &q->sm[q->nsm]))
            q->nsm++;

    bool ok = true;
    uint32_t apex = NONE, nchord = 0;
    if (q->nsv >= 2)
        ok = false;
    else if (q->nsv == 1) {
        apex = q->sv[0];
        const double *P = V(q, apex);
        if (P[0] < c.vx[0] || P[0] > c.vx[1] || P[1] < c.vy[0] || P[1] > c.vy[1])
            ok = false;
        /* its pieces leave through one point each; others may pass as chords */
        for (size_t i = 0; i < q->nsm && ok; i++) {
            qmeet *m = &q->sm[i];
            const qpiece *p = &q->pc[m->piece];
            if (p->a == apex || p->b == apex) {
                m->use = 2;
                ok = m->n == 1;
            } else if (m->n <= 1)
                ok = !m->ends && (m->n == 0 || m->grid[0] != GRID_NONE);
            else {
                m->use = 1;
                nchord++;
                ok = m->n == 2 && !m->ends;
            }
        }
    } else {
        /* chords: any number, as long as they do not cross (chord_faces) */
        for (size_t i = 0; i < q->nsm && ok; i++) {
            qmeet *m = &q->sm[i];
            if (m->n <= 1) {
                ok = m->n == 0 || m->grid[0] != GRID_NONE; /* a touch at a grid point */
                continue;
            }
            nchord++;
            m->use = 1;
            ok = m->n == 2;
        }
    }
    q->nstri = 0;
    q->nsedge = 0;
    /* chords that would be fine but for where their side points fell */
    bool conflict = ok && q->nsv == 0 && nchord > 0;
    if (ok && !build_ring(q, &c, false, false)) {
        if (q->status != TSR_OK)
            return R_ERROR;
        ok = false;
    }
    if (ok) {
        uint32_t nr = (uint32_t)q->nring;
        if (apex != NONE) {
            if (!RESERVE(q, q->ring, q->capring, q->npt + 1))
                return nomem(q);
            uint32_t a = (uint32_t)q->npt++;
            q->ring[a] = q->ring[0];
            q->ring[a].p[0] = V(q, apex)[0];
            q->ring[a].p[1] = V(q, apex)[1];
            q->ring[a].id = apex;
            q->ring[a].grid = GRID_NONE;
            q->ring[a].keyed = 0;
            q->ring[a].meet = NONE;
            if (nchord) {
                int r = chord_faces(q, nr, a);
                if (r == R_ERROR)
                    return R_ERROR;
                ok = r == R_SIMPLE;
            }
            for (uint32_t i = 0; i < nr && ok && !nchord; i++) {
                uint32_t j = i + 1 == nr ? 0 : i + 1;
                ok = ccw(q, a, i, j);
                if (ok && !add_tri(q, a, i, j))
                    return nomem(q);
            }
            for (size_t i = 0; i < q->nsm && ok && !nchord; i++)
                if (q->sm[i].use && !add_sedge(q, a, q->sm[i].ri[0], q->sm[i].piece))
                    return nomem(q);
        } else if (nchord) {
            int r = chord_faces(q, nr, NONE);
            if (r == R_ERROR)
                return R_ERROR;
            ok = r == R_SIMPLE;
            conflict = !ok;
        } else if (!c.fine[0] && !c.fine[1] && !c.fine[2] && !c.fine[3]) {
            if (!add_tri(q, 0, 1, 2) || !add_tri(q, 0, 2, 3))
                return nomem(q);
        } else {
            uint32_t w = 0;
            while (q->ring[w].grid < 4)
                w++; /* the first midpoint: every other point on its side is its ring neighbour */
            for (uint32_t i = 0; i < nr; i++) {
                uint32_t j = i + 1 == nr ? 0 : i + 1;
                if (i != w && j != w && !add_tri(q, w, i, j))
                    return nomem(q);
            }
        }
    }
    if (!ok) {
        if (test_pairs && pair_tests(q))
            return R_INTERACT;
        if (q->status != TSR_OK)
            return R_ERROR;
        /* Chords that neither cross nor touch, yet coincide or interleave
         * on the sides: their pieces are a rounding error apart (two
         * crossings an ulp apart joined to one vertex, say), which
         * splitting does not change along their whole length. */
        bool rounding = conflict && (test_pairs || !q->detect);
        if (L < q->depth && !rounding)
            return R_SPLIT;
        if (emit && fallback(q, &c) != TSR_OK)
            return R_ERROR;
        return R_FALLBACK;
    }
    if (!emit)
        return R_SIMPLE;
    for (size_t i = 0; i < q->npt; i++)
        if (ring_id(q, &q->ring[i]) == NONE)
            return nomem(q);
    if (!RESERVE(q, q->tri, q->captri, q->ntri + q->nstri))
        return nomem(q);
    for (size_t i = 0; i < q->nstri; i++)
        q->tri[q->ntri++] = q->ring[q->stri[i]].id;
    for (size_t i = 0; i < q->nsedge; i += 3)
        if (!add_edge(q, q->ring[q->sedge[i]].id, q->ring[q->sedge[i + 1]].id, q->sedge[i + 2]))
            return nomem(q);
    return R_SIMPLE;
}

/* ---- fallback: one cell through the Delaunay method ------------------ */

typedef struct qchain {
    double t;
    uint32_t id;
} qchain;

static int chain_cmp(const void *x, const void *y)
{
    const qchain *a = x, *b = y;
    return (a->t > b->t) - (a->t < b->t);
}

static uint32_t local_of(const uint32_t *lid, size_t n, uint32_t id)
{
    for (size_t i = 0; i < n; i++)
        if (lid[i] == id)
            return (uint32_t)i;
    return NONE;
}

static tsr_status fallback(qt *q, const qcell *c)
{
    tsr_status st = TSR_ERR_NOMEM;
    q->fallback_cells++;
    if (!build_ring(q, c, true, true) && q->status != TSR_OK)
        return q->status;
    size_t nr = q->nring, cap = nr + q->nsv + 1;
    double *lxy = tsr_alloc(q->al, 2 * cap * sizeof *lxy);
    uint32_t *lid = tsr_alloc(q->al, cap * sizeof *lid);
    uint32_t *seg = tsr_alloc(q->al, 2 * (cap + 4 * q->nsm + 1) * sizeof *seg);
    uint32_t *sseg = tsr_alloc(q->al, (4 * q->nsm + 1) * sizeof *sseg); /* chain -> piece */
    uint32_t *map = NULL, *inv = NULL;
    tsr_triangulation res;
    memset(&res, 0, sizeof res);
    if (!lxy || !lid || !seg || !sseg)
        goto done;
    size_t np = 0, ns = 0;
    /* Points at one place (sorted along each side, so adjacent): a vertex
     * there, else the crossing with the least key, speaks for all; the cell
     * across the side has the same points and makes the same choice. */
    for (size_t i = 0, j; i < nr; i = j) {
        const qpt *a = &q->ring[i];
        uint64_t k = a->ik;
        uint32_t vid = a->keyed ? NONE : a->id;
        for (j = i + 1; j < nr && q->ring[j].p[0] == a->p[0] && q->ring[j].p[1] == a->p[1]; j++) {
            k = q->ring[j].ik < k ? q->ring[j].ik : k;
            vid = q->ring[j].keyed ? vid : q->ring[j].id;
        }
        for (size_t m = i; m < j && j > i + 1; m++) {
            q->ring[m].ik = k;
            q->ring[m].keyed = vid == NONE;
            q->ring[m].id = vid;
        }
    }
    for (size_t i = 0; i < nr; i++) {
        qpt *p = &q->ring[i];
        if (ring_id(q, p) == NONE)
            goto done;
        if (local_of(lid, np, p->id) != NONE)
            continue;
        lid[np] = p->id;
        lxy[2 * np] = p->p[0];
        lxy[2 * np + 1] = p->p[1];
        np++;
    }
    size_t nring_local = np;
    for (size_t i = 0; i < q->nsv; i++) {
        if (local_of(lid, np, q->sv[i]) != NONE)
            continue;
        lid[np] = q->sv[i];
        lxy[2 * np] = V(q, q->sv[i])[0];
        lxy[2 * np + 1] = V(q, q->sv[i])[1];
        np++;
    }
    /* the pieces, clipped: their points in the cell in order along them */
    for (size_t i = 0; i < q->nsm; i++) {
        const qmeet *m = &q->sm[i];
        const qpiece *p = &q->pc[m->piece];
        const double *A = V(q, p->a), *B = V(q, p->b);
        qchain ch[6];
        int k = 0;
        for (int j = 0; j < m->n; j++) {
            const qpt *r = &q->ring[m->ri[j]];
            ch[k].t = along(A, B, r->p);
            ch[k++].id = r->id;
        }
        if (m->ends & 1) {
            ch[k].t = 0;
            ch[k++].id = p->a;
        }
        if (m->ends & 2) {
            ch[k].t = 1;
            ch[k++].id = p->b;
        }
        qsort(ch, (size_t)k, sizeof *ch, chain_cmp);
        for (int j = 1; j < k; j++) {
            if (ch[j].id == ch[j - 1].id)
                continue;
            uint32_t a = local_of(lid, np, ch[j - 1].id), b = local_of(lid, np, ch[j].id);
            if (a == NONE || b == NONE)
                continue;
            seg[2 * ns] = a;
            seg[2 * ns + 1] = b;
            sseg[ns++] = m->piece;
        }
    }
    size_t nchain = ns;
    for (size_t i = 0; i < nring_local; i++) {
        seg[2 * ns] = (uint32_t)i;
        seg[2 * ns + 1] = (uint32_t)((i + 1) % nring_local);
        ns++;
    }
    tsr_pslg sub = {lxy, (uint32_t)np, seg, (uint32_t)ns, NULL, 0};
    tsr_tri_options so;
    memset(&so, 0, sizeof so);
    so.method = TSR_TRI_DELAUNAY;
    so.region = TSR_REGION_ENCLOSED;
    tsr_error e;
    st = tsr_triangulate(&sub, &so, &res, q->al, &e);
    if (st != TSR_OK) {
        if (st == TSR_ERR_UNSUPPORTED)
            q->why_not = "a cell needed the Delaunay fallback, which refused it";
        else if (q->err)
            *q->err = e;
        q->status = st;
        goto done;
    }
    q->intersections += res.intersections; /* pieces crossing there, unsplit by the rounds */
    st = TSR_ERR_NOMEM;
    map = tsr_alloc(q->al, ((size_t)res.nv + 1) * sizeof *map);
    inv = tsr_alloc(q->al, ((size_t)res.nv + 1) * sizeof *inv);
    if (!map || !inv)
        goto done;
    for (uint32_t v = 0; v < res.nv; v++)
        inv[v] = NONE;
    for (size_t i = 0; i < np; i++)
        if (res.vertex_of_input[i] < res.nv)
            inv[res.vertex_of_input[i]] = (uint32_t)i;
    for (uint32_t v = 0; v < res.nv; v++) {
        map[v] = inv[v] != NONE ? lid[inv[v]] : new_vertex(q, res.xy[2 * (size_t)v], res.xy[2 * (size_t)v + 1]);
        if (map[v] == NONE)
            goto done;
    }
    if (!RESERVE(q, q->tri, q->captri, q->ntri + 3 * (size_t)res.nt))
        goto done;
    for (size_t i = 0; i < 3 * (size_t)res.nt; i++)
        q->tri[q->ntri++] = map[res.tri[i]];
    for (uint32_t i = 0; i < res.nedge; i++) {
        uint32_t s = res.edge_segment[i];
        if (s >= nchain)
            continue; /* the cell's own boundary */
        if (!add_edge(q, map[res.edge[2 * (size_t)i]], map[res.edge[2 * (size_t)i + 1]], sseg[s]))
            goto done;
    }
    st = TSR_OK;
done:
    if (st == TSR_ERR_NOMEM)
        q->status = st;
    tsr_triangulation_free(&res);
    tsr_free(q->al, lxy);
    tsr_free(q->al, lid);
    tsr_free(q->al, seg);
    tsr_free(q->al, sseg);
    tsr_free(q->al, map);
    tsr_free(q->al, inv);
    return st;
}

/* ---- building ------------------------------------------------------ */

/* Builds the tree over the current features until every leaf is simple,
 * at the depth limit, or (when detecting) found features meeting. */
static tsr_status build(qt *q)
{
    q->nnd = 0;
    q->nft = 0;
    q->nstk = 0;
    q->nit = 0;
    size_t nf = q->nfv + q->npc;
    if (nf >= UINT32_MAX / 4 || q->npc >= PIECE_BIT) {
        q->why_not = "too many points and segments for the quadtree's feature lists";
        return q->status = TSR_ERR_UNSUPPORTED;
    }
    if (!RESERVE(q, q->nd, q->capnd, 1) || !RESERVE(q, q->ft, q->capft, nf))
        return q->status = TSR_ERR_NOMEM;
    q->nd[0] = (qnode){NONE, 0, 0, 0, 0, (uint32_t)nf, 0, 0, 0};
    q->nnd = 1;
    for (uint32_t v = 0; v < q->nfv; v++)
        q->ft[q->nft++] = v;
    for (size_t p = 0; p < q->npc; p++)
        q->ft[q->nft++] = PIECE_BIT | (uint32_t)p;
    if (!push(q, 0))
        return q->status = TSR_ERR_NOMEM;
    while (q->nstk) {
        uint32_t n = q->stk[--q->nstk];
        q->nd[n].queued = 0;
        if (!is_leaf(q, n))
            continue;
        int r = eval(q, n, false);
        if (r == R_SPLIT)
            r = split(q, n);
        if (r == R_ERROR)
            return q->status;
    }
    return TSR_OK;
}

static int split_cmp(const void *x, const void *y)
{
    const qsplit *a = x, *b = y;
    if (a->p != b->p)
        return a->p < b->p ? -1 : 1;
    if (a->t != b->t)
        return a->t < b->t ? -1 : 1;
    return (a->v > b->v) - (a->v < b->v);
}

static int inter_cmp(const void *x, const void *y)
{
    const qinter *a = x, *b = y;
    if (a->kind != b->kind)
        return a->kind < b->kind ? -1 : 1;
    if (a->p != b->p)
        return a->p < b->p ? -1 : 1;
    return (a->other > b->other) - (a->other < b->other);
}

static double clampd(double v, double lo, double hi)
{
    return v < lo ? lo : v > hi ? hi : v;
}

/* Splits the pieces at the points and crossings found by a build. */
static tsr_status apply_interactions(qt *q)
{
    qsort(q->it, q->nit, sizeof *q->it, inter_cmp);
    qsplit *sp = tsr_alloc(q->al, (2 * q->nit + 1) * sizeof *sp);
    qpiece *np = NULL;
    if (!sp)
        return q->status = TSR_ERR_NOMEM;
    size_t ns = 0;
    for (size_t i = 0; i < q->nit; i++) {
        const qinter *it = &q->it[i];
        if (i && inter_cmp(it, it - 1) == 0)
            continue;
        const qpiece *p = &q->pc[it->p];
        const double *A = V(q, p->a), *B = V(q, p->b);
        if (it->kind == 0) {
            sp[ns++] = (qsplit){it->p, it->other, along(A, B, V(q, it->other))};
            continue;
        }
        const qpiece *r = &q->pc[it->other];
        double a[2] = {A[0], A[1]}, b[2] = {B[0], B[1]}, cc[2], dd[2];
        memcpy(cc, V(q, r->a), sizeof cc);
        memcpy(dd, V(q, r->b), sizeof dd);
        double ux = b[0] - a[0], uy = b[1] - a[1], vx = dd[0] - cc[0], vy = dd[1] - cc[1];
        double den = ux * vy - uy * vx;
        double t = ((cc[0] - a[0]) * vy - (cc[1] - a[1]) * vx) / den;
        if (!(t >= 0))
            t = 0;
        if (!(t <= 1))
            t = 1;
        double X[2] = {a[0] + t * ux, a[1] + t * uy};
        for (int k = 0; k < 2; k++) {
            double lo1 = a[k] < b[k] ? a[k] : b[k], hi1 = a[k] < b[k] ? b[k] : a[k];
            double lo2 = cc[k] < dd[k] ? cc[k] : dd[k], hi2 = cc[k] < dd[k] ? dd[k] : cc[k];
            X[k] = clampd(X[k], lo1 > lo2 ? lo1 : lo2, hi1 < hi2 ? hi1 : hi2);
        }
        bool added;
        uint32_t v = vertex_id(q, X[0], X[1], &added);
        if (v == NONE)
            goto fail;
        /* the vertex array may have moved */
        const qpiece *p2 = &q->pc[it->p], *r2 = &q->pc[it->other];
        q->intersections += added;
        sp[ns++] = (qsplit){it->p, v, along(V(q, p2->a), V(q, p2->b), V(q, v))};
        sp[ns++] = (qsplit){it->other, v, along(V(q, r2->a), V(q, r2->b), V(q, v))};
    }
    qsort(sp, ns, sizeof *sp, split_cmp);
    size_t cap = q->npc + ns + 1;
    np = tsr_alloc(q->al, cap * sizeof *np);
    if (!np)
        goto fail;
    size_t m = 0, j = 0;
    for (size_t i = 0; i < q->npc; i++) {
        qpiece p = q->pc[i];
        uint32_t prev = p.a;
        for (; j < ns && sp[j].p == i; j++) {
            uint32_t v = sp[j].v;
            if (v == prev || v == p.b || v == p.a)
                continue;
            np[m++] = (qpiece){prev, v, p.seg, p.cov, p.ncov};
            prev = v;
        }
        np[m++] = (qpiece){prev, p.b, p.seg, p.cov, p.ncov};
    }
    tsr_free(q->al, q->pc);
    q->pc = np;
    q->npc = m;
    q->cappc = cap;
    q->nfv = (uint32_t)q->nxy;
    tsr_free(q->al, sp);
    if (!pieces_normalise(q))
        return q->status = TSR_ERR_NOMEM;
    return TSR_OK;
fail:
    tsr_free(q->al, sp);
    return q->status = TSR_ERR_NOMEM;
}

/* ---- the square ---------------------------------------------------- */

static bool on_grid(double x, double o, double hD)
{
    double k = floor((x - o) / hD);
    for (double j = k - 1; j <= k + 1; j++)
        if (o + j * hD == x)
            return true;
    return false;
}

/* Places the square (ox, oy, S, depth, h[]); false when every shift puts
 * a vertex on a grid line. */
static bool place_square(qt *q, int want_depth)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t v = 0; v < q->nxy; v++)
        for (int k = 0; k < 2; k++) {
            double c = q->xy[2 * v + k];
            lo[k] = c < lo[k] ? c : lo[k];
            hi[k] = c > hi[k] ? c : hi[k];
        }
    double w = hi[0] - lo[0], h = hi[1] - lo[1], E = w > h ? w : h;
    int e;
    q->S = INFINITY;
    if (!isfinite(1.25 * E) || !(E > 0))
        return false;
    frexp(1.25 * E, &e);
    q->S = ldexp(1.0, e);
    if (!isfinite(q->S))
        return false;
    for (int t = 0; t < SHIFT_TRIES; t++) {
        /* shifts of at most 0.05 S, with no short binary expansion */
        double fx = fmod(0.6180339887498949 * (t + 1) + 0.3183098861837907, 1.0) * 0.1 - 0.05;
        double fy = fmod(0.7548776662466927 * (t + 1) + 0.1415926535897932, 1.0) * 0.1 - 0.05;
        q->ox = lo[0] - (q->S - w) / 2 + fx * q->S;
        q->oy = lo[1] - (q->S - h) / 2 + fy * q->S;
        double M = fabs(q->ox);
        double cand[3] = {fabs(q->ox + q->S), fabs(q->oy), fabs(q->oy + q->S)};
        for (int k = 0; k < 3; k++)
            M = cand[k] > M ? cand[k] : M;
        double ulp = nextafter(M, INFINITY) - M;
        int D = want_depth;
        while (D > 1 && ldexp(q->S, -D) < 64 * ulp)
            D--;
        q->depth = D;
        for (int L = 0; L <= DEPTH_MAX + 1; L++)
            q->h[L] = ldexp(q->S, -L);
        double hD = q->h[D];
        bool clash = false;
        for (size_t v = 0; v < q->nxy && !clash; v++)
            clash = on_grid(q->xy[2 * v], q->ox, hD) || on_grid(q->xy[2 * v + 1], q->oy, hD);
        if (!clash)
            return true;
    }
    return false;
}

/* ---- entry --------------------------------------------------------- */

static int edge3_cmp(const void *x, const void *y)
{
    const uint32_t *a = x, *b = y;
    uint32_t a0 = a[0] < a[1] ? a[0] : a[1], a1 = a[0] ^ a[1] ^ a0;
    uint32_t b0 = b[0] < b[1] ? b[0] : b[1], b1 = b[0] ^ b[1] ^ b0;
    if (a0 != b0)
        return a0 < b0 ? -1 : 1;
    if (a1 != b1)
        return a1 < b1 ? -1 : 1;
    return (a[2] > b[2]) - (a[2] < b[2]);
}

static void qt_free(qt *q)
{
    tsr_free(q->al, q->xy);
    tsr_free(q->al, q->hs);
    tsr_free(q->al, q->ks);
    tsr_free(q->al, q->kc);
    tsr_free(q->al, q->pc);
    tsr_free(q->al, q->cov);
    tsr_free(q->al, q->nd);
    tsr_free(q->al, q->ft);
    tsr_free(q->al, q->stk);
    tsr_free(q->al, q->mask);
    tsr_free(q->al, q->it);
    tsr_free(q->al, q->sv);
    tsr_free(q->al, q->sm);
    tsr_free(q->al, q->ring);
    tsr_free(q->al, q->idx);
    tsr_free(q->al, q->stri);
    tsr_free(q->al, q->sedge);
    tsr_free(q->al, q->tri);
    tsr_free(q->al, q->edge);
}

static tsr_status unsupported(qt *q, const char **why_not, const char *why, tsr_error *err)
{
    *why_not = why;
    qt_free(q);
    return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "quadtree method: %s", why);
}

tsr_status tsr__tri_quadtree(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                             const tsr_allocator *alloc, const char **why_not, tsr_error *err)
{
    static const tsr_tri_options defaults;
    if (!opt)
        opt = &defaults;
    memset(out, 0, sizeof *out);
    *why_not = NULL;
    qt q;
    memset(&q, 0, sizeof q);
    q.al = alloc;
    q.err = err;
    for (size_t i = 0; i < 2 * (size_t)in->nv; i++)
        if (!isfinite(in->xy[i]))
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "point %zu has a non-finite coordinate", i / 2);
    for (uint32_t s = 0; s < in->nseg; s++)
        for (int k = 0; k < 2; k++)
            if (in->seg[2 * (size_t)s + k] >= in->nv)
                return tsr_error_set(err, TSR_ERR_ARGUMENT, "segment %u refers to point %u, but there are %u points", s,
                                     in->seg[2 * (size_t)s + k], in->nv);
    if (opt->region == TSR_REGION_HULL)
        return unsupported(&q, why_not, "the quadtree covers the bounding square, not the convex hull", err);
    if (opt->conforming)
        return unsupported(&q, why_not, "conforming Delaunay refinement belongs to the Delaunay method", err);
    if (opt->min_angle > 0)
        return unsupported(&q, why_not, "a minimum angle needs the Delaunay method's quality refinement", err);

    uint32_t *voi = tsr_alloc(alloc, ((size_t)in->nv + 1) * sizeof *voi);
    if (!voi)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
    tsr_status st = TSR_ERR_NOMEM;
    for (uint32_t i = 0; i < in->nv; i++)
        if ((voi[i] = vertex_id(&q, in->xy[2 * (size_t)i], in->xy[2 * (size_t)i + 1], NULL)) == NONE)
            goto fail;
    q.nin = q.nfv = (uint32_t)q.nxy;
    const char *why = NULL;
    if (q.nin < 3)
        why = "fewer than three distinct points";
    else {
        uint32_t v = 2;
        while (v < q.nin && tsr_orient2d(V(&q, 0), V(&q, 1), V(&q, v)) == 0)
            v++;
        if (v == q.nin)
            why = "all points are collinear";
    }
    int want = opt->max_depth ? (int)(opt->max_depth < DEPTH_MAX ? opt->max_depth : DEPTH_MAX) : DEPTH_DEFAULT;
    if (!why && !place_square(&q, want))
        why = isfinite(q.S) ? "the input's coordinates lie on the quadtree's grid lines for every shift tried"
                            : "the input's extent is beyond the range of doubles once squared and grown";
    if (!why && opt->max_area > 0) {
        int L = 0;
        while (L < q.depth && q.h[L] * q.h[L] > 2 * opt->max_area)
            L++;
        if (q.h[L] * q.h[L] > 2 * opt->max_area)
            why = "the maximum area needs cells below the depth limit";
        else if (L > AREA_LEVEL_MAX)
            why = "the maximum area would need more than 16 million quadtree cells";
        q.min_level = L;
    }
    if (why) {
        tsr_free(alloc, voi);
        return unsupported(&q, why_not, why, err);
    }
    uint32_t degenerate = 0;
    if (!RESERVE(&q, q.pc, q.cappc, (size_t)in->nseg + 1))
        goto fail;
    for (uint32_t s = 0; s < in->nseg; s++) {
        uint32_t a = voi[in->seg[2 * (size_t)s]], b = voi[in->seg[2 * (size_t)s + 1]];
        if (a == b)
            degenerate++;
        else
            q.pc[q.npc++] = (qpiece){a, b, s, 0, 1};
    }
    if (!pieces_normalise(&q))
        goto fail;
    size_t area_cells = ((size_t)1 << (2 * q.min_level)) * 4 / 3 + 1;
    q.budget = area_cells + ((size_t)1 << 20) + 256 * ((size_t)q.nin + in->nseg);
    if (q.budget > UINT32_MAX / 2)
        q.budget = UINT32_MAX / 2;

    for (int round = 0;; round++) {
        q.detect = round < ROUNDS - 1;
        st = build(&q);
        if (st != TSR_OK)
            goto fail;
        if (q.nit == 0)
            break;
        st = apply_interactions(&q);
        if (st != TSR_OK)
            goto fail;
    }
    /* triangulate the leaves in depth-first (Z) order, so the corners
     * they share are looked up close together in time */
    q.detect = false;
    size_t leaves = (q.nnd - 1) / 4 * 3 + 1;
    if (!RESERVE(&q, q.tri, q.captri, 9 * leaves) || !RESERVE(&q, q.xy, q.capxy, 2 * (q.nxy + leaves + leaves / 4)) ||
        !khash_grow(&q, leaves + leaves / 4) || !RESERVE(&q, q.stk, q.capstk, 4 * (DEPTH_MAX + 2))) {
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    q.nstk = 0;
    q.stk[q.nstk++] = 0;
    while (q.nstk) {
        uint32_t n = q.stk[--q.nstk];
        if (!is_leaf(&q, n)) {
            for (uint32_t k = 4; k-- > 0;)
                q.stk[q.nstk++] = q.nd[n].child + k; /* at most 3 per level and 4 more */
            continue;
        }
        int r = eval(&q, n, true);
        if (r == R_ERROR) {
            st = q.status;
            goto fail;
        }
        assert(r == R_SIMPLE || r == R_FALLBACK); /* the build left every leaf decided */
    }
    if (q.ntri / 3 > UINT32_MAX || q.nedge / 3 > UINT32_MAX) {
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    /* constrained edges: one per undirected edge and covering segment,
     * ascending ids (an edge seen from two cells is listed once) */
    size_t ne = q.nedge / 3, m = 0;
    if (ne > 1)
        qsort(q.edge, ne, 3 * sizeof *q.edge, edge3_cmp);
    uint32_t *edge = tsr_alloc(alloc, (2 * ne + 1) * sizeof *edge), *eseg = tsr_alloc(alloc, (ne + 1) * sizeof *eseg);
    if (!edge || !eseg) {
        tsr_free(alloc, edge);
        tsr_free(alloc, eseg);
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    for (size_t i = 0; i < ne; i++) {
        const uint32_t *e = q.edge + 3 * i;
        if (m && eseg[m - 1] == e[2] &&
            ((e[0] == edge[2 * m - 2] && e[1] == edge[2 * m - 1]) ||
             (e[0] == edge[2 * m - 1] && e[1] == edge[2 * m - 2])))
            continue;
        edge[2 * m] = e[0];
        edge[2 * m + 1] = e[1];
        eseg[m++] = e[2];
    }
    if (alloc)
        out->alloc = *alloc;
    out->xy = q.xy;
    out->nv = (uint32_t)q.nxy;
    out->tri = q.tri;
    out->nt = (uint32_t)(q.ntri / 3);
    out->edge = edge;
    out->edge_segment = eseg;
    out->nedge = (uint32_t)m;
    out->vertex_of_input = voi;
    out->input_vertices = q.nin;
    out->duplicates = in->nv - q.nin;
    out->intersections = q.intersections;
    out->steiner = out->nv - q.nin;
    out->degenerate_segments = degenerate;
    out->fallback_cells = q.fallback_cells;
    if (q.fallback_cells)
        out->fallback_reason = "near-coincident features: some quadtree cells were triangulated by the Delaunay method";
    q.xy = NULL;
    q.tri = NULL;
    qt_free(&q);
    return TSR_OK;
fail:
    tsr_free(alloc, voi);
    if (st == TSR_ERR_UNSUPPORTED || q.status == TSR_ERR_UNSUPPORTED) {
        const char *w = q.why_not ? q.why_not : "the quadtree method failed";
        return unsupported(&q, why_not, w, err);
    }
    qt_free(&q);
    if (st == TSR_ERR_NOMEM || q.status == TSR_ERR_NOMEM)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory in the quadtree triangulation of %u points", in->nv);
    if (err && err->status == st)
        return st; /* the Delaunay fallback's own message */
    return tsr_error_set(err, st, "quadtree triangulation failed: %s", tsr_status_str(st));
}
