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
 *  (b) one vertex, strictly inside, and every piece entering that has it
 *      as an end leaves through one ring point (others pass as chords, as
 *      in (c)): a fan from the vertex (the cell's centre moved onto it), the
 *      edges to the exit points constrained. No margin from the sides is
 *      asked: a vertex near a grid line stays near it at every finer level,
 *      so a margin split such cells down to the depth limit, with the
 *      balancing around them (twice the triangles on the bench's polygon),
 *      and chords give no angle bound anyway;
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
 * Building: the tree is split first by what is cheap to decide (two
 * vertices, balance, the area's level), then every leaf with features gets
 * the full rules, which also triangulate it into the results as a record
 * (triangles, constrained edges, faces); a leaf whose neighbours change
 * afterwards is looked at, and recorded, again. Leaves without features are
 * triangulated last, in Z order, their finer sides found top down.
 *
 * Region (tsr__tri_quadtree_region, when no hole seed applies and no cell
 * went to the fallback): each leaf's rule knows the parts of the leaf
 * between constrained edges that count (faces: between chords, sectors of
 * a vertex fan), and which face each ring segment of its sides belongs to.
 * Faces that meet across a side are joined (union-find, each shared side
 * once, its lists paired segment by segment), then a breadth-first search
 * over the joined parts from the square's border, a counted constrained
 * edge costing one, gives every face the depth region_keep would give its
 * triangles, without sorting a record per triangle; only kept faces are
 * written. Where two lists do not pair up the general pass decides.
 *
 * Constrained edges are listed once per input segment covering them, ids
 * ascending, so region selection can count even-odd parity (once, with the
 * lowest id, when the region was chosen here).
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
#define DONE 0x10
#define PAIRED 0x20
#define KCACHE_BITS 12 /* recent grid keys: most lookups repeat a corner just seen */

enum { R_SIMPLE, R_SPLIT, R_FALLBACK, R_INTERACT, R_ERROR };

typedef struct qpiece {
    uint32_t a, b;      /* vertex ids; the crossing function uses this order */
    uint32_t seg;       /* the lowest input segment covering it */
    uint32_t cov, ncov; /* all of them: seg alone when ncov is 1, else q->cov[cov..] */
} qpiece;

/* Nodes: the root, then the children of each split node, four by four
 * (quadrant x + 2y): node 1 + 4g + k is child k of group g, which holds
 * what the four share (their parent and its place). */
typedef struct qnode {
    uint32_t child;              /* the first of four; 0 for a leaf */
    uint32_t f, nf;              /* features: vertex ids, then PIECE_BIT | piece */
    uint8_t level, queued, fine; /* fine: sides with a finer neighbour, from the last build look */
    uint8_t done;                /* DONE | fine: the full rules found it simple with those neighbours (and emitted it
                                    as rec); PAIRED: its features' pairs were tested and nothing met */
    uint32_t rec;                /* its triangles in the results, NONE until emitted */
} qnode;

typedef struct qgroup {
    uint32_t parent, ix, iy; /* the parent and its column and row at its level */
} qgroup;

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
    bool fine[4];          /* sides: bottom right top left */
} qcell;

typedef struct qsplit {
    uint32_t p, v;
    double t;
} qsplit;

typedef struct qkslot {
    uint64_t key;
    uint32_t id; /* NONE: empty */
    uint32_t pad;
} qkslot;

/* A leaf's triangles in q->tri, its constrained edges in q->edge, and
 * (when choosing the region) its faces (parts between counted constrained
 * edges) and side lists in q->sl. */
typedef struct qrec {
    uint32_t tri, ntri, edge, nedge;
    uint32_t side;  /* byte offset of its lists in q->sl; NONE when not choosing */
    uint32_t nface; /* its faces: face .. face + nface */
    uint32_t face;  /* NONE for a record a later look replaced */
} qrec;

typedef struct qt {
    const tsr_allocator *al;
    double *xy; /* output vertices: distinct inputs, crossings, then the rest */
    size_t nxy, capxy;
    uint32_t *hs; /* coordinate hash: inputs and crossings (vertex ids, NONE: empty) */
    size_t hcap;
    uint32_t *ks; /* integer-key hash: grid points and side crossings (vertex ids, NONE: empty) */
    size_t kcap, nks;
    int kbits;
    uint64_t *vkey; /* the key of each vertex in ks */
    size_t capvkey;
    qkslot *kc;        /* direct-mapped cache in front of it, 1 << KCACHE_BITS */
    uint32_t nin, nfv; /* distinct inputs; feature vertices (inputs and crossings) */
    qpiece *pc;
    size_t npc, cappc;
    uint32_t *cov; /* cover lists of merged pieces, ascending segment ids */
    size_t ncov, capcov;
    qnode *nd;
    size_t nnd, capnd, budget;
    qgroup *grp;
    size_t capgrp;
    uint32_t *ft;
    size_t nft, capft, ftlive; /* ftlive: entries in leaves' lists */
    uint32_t *stk;
    size_t nstk, capstk;
    uint8_t *mask;
    size_t capmask;
    double ox, oy, S, h[DEPTH_MAX + 2];
    int depth, min_level;
    bool detect;
    bool cheap; /* first pass of a build: split by vertex count and balance only */
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
    /* labels of parts of the leaf (faces before merging across constrained
     * edges that do not count): of each triangle, ring segment i -> i + 1,
     * and both sides of each constrained edge */
    uint32_t *stlab, *slab, *elab;
    size_t capstlab, capslab, capelab;
    uint32_t nlab, curlab;
    /* results */
    uint32_t *tri;
    size_t ntri, captri;
    uint32_t *edge; /* a, b, segment */
    size_t nedge, capedge;
    uint32_t intersections, fallback_cells;
    /* emission; the region chosen from the cells (fast: no hole seeds, no
     * fallback cell, every side matched) */
    bool fast;
    tsr_region region;
    uint8_t *sl; /* per leaf with features: 4 x (n, mid, n faces) from side 0, then npair, npair x (face, face) */
    size_t nsl, capsl;
    uint8_t *tface; /* face of each triangle in q->tri, within its leaf */
    size_t captface;
    uint8_t *ef; /* faces on both sides of each entry of edge[], within its leaf */
    size_t capef;
    qrec *rec;
    size_t nrec, caprec;
    uint32_t nface;
    uint32_t *lfs; /* one leaf's faces */
    size_t caplfs;
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
    uint32_t *hs = tsr_alloc(q->al, nc * sizeof *hs);
    if (!hs)
        return false;
    for (size_t i = 0; i < nc; i++)
        hs[i] = NONE;
    for (size_t k = 0; k < q->hcap; k++) {
        if (q->hs[k] == NONE)
            continue;
        const double *P = V(q, q->hs[k]);
        size_t i = hash_xy(P[0], P[1]) & (nc - 1);
        while (hs[i] != NONE)
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
    for (; q->hs[i] != NONE; i = (i + 1) & mask)
        if (V(q, q->hs[i])[0] == x && V(q, q->hs[i])[1] == y)
            return q->hs[i];
    if (q->nxy >= UINT32_MAX - 2 || !RESERVE(q, q->xy, q->capxy, 2 * (q->nxy + 1)))
        return NONE;
    q->xy[2 * q->nxy] = x;
    q->xy[2 * q->nxy + 1] = y;
    q->hs[i] = (uint32_t)q->nxy;
    if (added)
        *added = true;
    return (uint32_t)q->nxy++;
}

/* Sizes the key hash for `need` keys (at most half full: every probe reads
 * the key of a vertex). */
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
    while (nc < 2 * need)
        nc *= 2;
    if (nc == q->kcap)
        return true;
    uint32_t *ks = tsr_alloc(q->al, nc * sizeof *ks);
    if (!ks)
        return false;
    for (size_t i = 0; i < nc; i++)
        ks[i] = NONE;
    int bits = 0;
    while ((size_t)1 << bits < nc)
        bits++;
    for (size_t k = 0; k < q->kcap; k++) {
        if (q->ks[k] == NONE)
            continue;
        size_t i = (size_t)((q->vkey[q->ks[k]] * 0x9E3779B97F4A7C15ull) >> (64 - bits));
        while (ks[i] != NONE)
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
    if (2 * (q->nks + 1) > q->kcap && !khash_grow(q, q->nks + 1))
        return NONE;
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    qkslot *c = &q->kc[h >> (64 - KCACHE_BITS)];
    if (c->id != NONE && c->key == key)
        return c->id;
    size_t mask = q->kcap - 1, i = (size_t)(h >> (64 - q->kbits));
    for (; q->ks[i] != NONE; i = (i + 1) & mask)
        if (q->vkey[q->ks[i]] == key) {
            *c = (qkslot){key, q->ks[i], 0};
            return c->id;
        }
    if (q->nxy >= UINT32_MAX - 2 || !RESERVE(q, q->xy, q->capxy, 2 * (q->nxy + 1)) ||
        !RESERVE(q, q->vkey, q->capvkey, q->nxy + 1))
        return NONE;
    q->xy[2 * q->nxy] = x;
    q->xy[2 * q->nxy + 1] = y;
    q->vkey[q->nxy] = key;
    q->ks[i] = (uint32_t)q->nxy;
    *c = (qkslot){key, q->ks[i], 0};
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

/* Node n's column and row at its level. */
static void node_at(const qt *q, uint32_t n, uint32_t *ix, uint32_t *iy)
{
    if (n == 0) {
        *ix = *iy = 0;
        return;
    }
    const qgroup *g = &q->grp[(n - 1) >> 2];
    unsigned quad = (n - 1) & 3;
    *ix = 2 * g->ix + (quad & 1);
    *iy = 2 * g->iy + (quad >> 1);
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
        uint32_t g = (cur - 1) >> 2;
        unsigned quad = (cur - 1) & 3;
        if ((quad & bit[s]) == inside[s]) {
            cur = 1 + 4 * g + (quad ^ bit[s]); /* a sibling */
            break;
        }
        path[k++] = (uint8_t)quad;
        cur = q->grp[g].parent;
    }
    while (k > 0 && !is_leaf(q, cur))
        cur = q->nd[cur].child + (path[--k] ^ bit[s]);
    return cur;
}

/* The node across a side from the child `quad` of a node whose neighbour
 * there is m: m's child when m is an inner node of the same level. */
static uint32_t down(const qt *q, uint32_t m, unsigned quad)
{
    return m != NONE && !is_leaf(q, m) ? q->nd[m].child + quad : m;
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
    uint32_t ix, iy;
    node_at(q, n, &ix, &iy);
    double fx = ix, fy = iy;
    c->n = n;
    c->level = L;
    for (int i = 0; i < 3; i++) {
        c->xs[i] = gcoord(q, q->ox, L, fx + 0.5 * i);
        c->ys[i] = gcoord(q, q->oy, L, fy + 0.5 * i);
    }
    int sh = q->depth - L; /* half a cell at level depth + 1 */
    for (int i = 0; i < 3; i++) {
        c->lx[i] = ((uint64_t)2 * ix + (unsigned)i) << sh;
        c->ly[i] = ((uint64_t)2 * iy + (unsigned)i) << sh;
    }
    static const uint8_t gi[8][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}};
    for (int k = 0; k < 8; k++) {
        c->g[k][0] = c->xs[gi[k][0]];
        c->g[k][1] = c->ys[gi[k][1]];
        c->gk[k] = c->lx[gi[k][0]] << 31 | c->ly[gi[k][1]];
    }
}

/* Moves the leaves' feature lists to the front of q->ft, dropping those of
 * inner nodes (lists lie in node order). */
static void compact_features(qt *q)
{
    size_t w = 0;
    for (size_t n = 0; n < q->nnd; n++) {
        qnode *d = &q->nd[n];
        if (d->child != 0) {
            d->f = (uint32_t)w;
            d->nf = 0;
            continue;
        }
        memmove(q->ft + w, q->ft + d->f, d->nf * sizeof *q->ft);
        d->f = (uint32_t)w;
        w += d->nf;
    }
    q->nft = w;
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
    uint32_t nf = q->nd[n].nf;
    if (q->nft + 4 * (size_t)nf > q->capft && 2 * q->ftlive < q->nft)
        compact_features(q);
    uint32_t f0 = q->nd[n].f;
    if (!RESERVE(q, q->nd, q->capnd, q->nnd + 4) || !RESERVE(q, q->ft, q->capft, q->nft + 4 * (size_t)nf) ||
        !RESERVE(q, q->mask, q->capmask, nf))
        return nomem(q);
    if (q->nft + 4 * (size_t)nf >= UINT32_MAX) {
        q->why_not = "the quadtree's feature lists would be too long";
        q->status = TSR_ERR_UNSUPPORTED;
        return R_ERROR;
    }
    const qnode *pd = &q->nd[n];
    int L = pd->level;
    uint32_t pix, piy;
    node_at(q, n, &pix, &piy);
    double xs[3], ys[3];
    for (int i = 0; i < 3; i++) {
        xs[i] = gcoord(q, q->ox, L, pix + 0.5 * i);
        ys[i] = gcoord(q, q->oy, L, piy + 0.5 * i);
    }
    static const uint8_t only[9] = {0, 0, 1, 0, 2, 0, 0, 0, 3}; /* the quadrant of a one-bit mask */
    const uint32_t *list = q->ft + f0;
    uint32_t count[4] = {0, 0, 0, 0}, nvert[4] = {0, 0, 0, 0};
    for (uint32_t i = 0; i < nf; i++) {
        uint32_t f = list[i];
        unsigned m = 0;
        if (!(f & PIECE_BIT)) {
            const double *P = V(q, f);
            unsigned wx = P[0] <= xs[1], ex = P[0] >= xs[1], sy = P[1] <= ys[1], ny = P[1] >= ys[1];
            m = (wx & sy) | (ex & sy) << 1 | (wx & ny) << 2 | (ex & ny) << 3;
            if (m == 1 || m == 2 || m == 4 || m == 8)
                nvert[only[m]]++;
            else
                for (unsigned quad = 0; quad < 4; quad++)
                    nvert[quad] += m >> quad & 1;
        } else {
            const qpiece *p = &q->pc[f & ~PIECE_BIT];
            const double *A = V(q, p->a), *B = V(q, p->b);
            double lx = A[0] < B[0] ? A[0] : B[0];
            double ux = A[0] < B[0] ? B[0] : A[0], ly = A[1] < B[1] ? A[1] : B[1], uy = A[1] < B[1] ? B[1] : A[1];
            /* the quadrants its box meets; the piece meets the closed cell, so
             * one quadrant alone is met (the common case, with no predicate) */
            unsigned bx = (lx <= xs[1]) | (ux >= xs[1]) << 1, by = (ly <= ys[1]) | (uy >= ys[1]) << 1;
            unsigned box =
                (bx & 1 && by & 1) | (bx >> 1 && by & 1) << 1 | (bx & 1 && by >> 1) << 2 | (bx >> 1 && by >> 1) << 3;
            if ((box & (box - 1)) == 0)
                m = box;
            else {
                int o[9];
                bool have[9] = {false};
                for (unsigned quad = 0; quad < 4; quad++) {
                    unsigned cx = quad & 1, cy = quad >> 1;
                    if (!(box >> quad & 1))
                        continue;
                    int pos = 0, neg = 0;
                    for (unsigned k = 0; k < 4; k++) {
                        unsigned gx = cx + (k & 1), gy = cy + (k >> 1), g = gy * 3 + gx;
                        if (!have[g]) {
                            double P[2] = {xs[gx], ys[gy]};
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
        }
        q->mask[i] = (uint8_t)m;
        if (m == 1 || m == 2 || m == 4 || m == 8)
            count[only[m]]++;
        else
            for (unsigned quad = 0; quad < 4; quad++)
                count[quad] += m >> quad & 1;
    }
    uint32_t first = (uint32_t)q->nnd, at[4];
    if (!RESERVE(q, q->grp, q->capgrp, (first - 1) / 4 + 1))
        return nomem(q);
    q->grp[(first - 1) / 4] = (qgroup){n, pix, piy};
    q->nnd += 4;
    qnode *d = &q->nd[n];
    d->child = first;
    for (unsigned quad = 0; quad < 4; quad++) {
        qnode *ch = &q->nd[first + quad];
        ch->child = 0;
        ch->level = (uint8_t)(d->level + 1);
        ch->queued = 0;
        ch->fine = 0;
        ch->done = d->done & PAIRED; /* a subset of the features: their pairs are tested */
        ch->rec = NONE;
        ch->f = at[quad] = (uint32_t)q->nft;
        ch->nf = count[quad];
        q->nft += count[quad];
        q->ftlive += count[quad];
    }
    q->ftlive -= nf;
    for (uint32_t i = 0; i < nf; i++) { /* in order: vertices stay first */
        unsigned m = q->mask[i];
        uint32_t f = q->ft[f0 + i];
        if (m & 1)
            q->ft[at[0]++] = f;
        if (m & 2)
            q->ft[at[1]++] = f;
        if (m & 4)
            q->ft[at[2]++] = f;
        if (m & 8)
            q->ft[at[3]++] = f;
    }
    uint32_t nb[4];
    for (int s = 0; s < 4; s++)
        nb[s] = neighbour(q, n, s);
    /* the children to look at: those the rules may split (two vertices,
     * the area's level, a neighbour two levels finer: balance is checked
     * here from n's neighbours), and with the full rules those with
     * features */
    static const uint8_t adj[4][2] = {{2, 3}, {0, 2}, {0, 1}, {1, 3}};
    for (unsigned quad = 0; quad < 4; quad++) {
        const qnode *ch = &q->nd[first + quad];
        bool look = nvert[quad] >= 2 || ch->level < q->min_level || (!q->cheap && ch->nf > 0);
        for (int s = 0; s < 4 && !look; s++) {
            unsigned x = quad & 1, y = quad >> 1;
            bool out = s == 0 ? !y : s == 1 ? x : s == 2 ? y : !x;
            if (!out)
                continue; /* a sibling: a leaf */
            uint32_t m = down(q, nb[s], s == 0 ? quad + 2 : s == 1 ? quad - 1 : s == 2 ? quad - 2 : quad + 1);
            if (m != NONE && !is_leaf(q, m) && q->nd[m].level == ch->level) {
                uint32_t c2 = q->nd[m].child;
                look = !is_leaf(q, c2 + adj[s][0]) || !is_leaf(q, c2 + adj[s][1]);
            }
        }
        if (look && !push(q, first + quad))
            return nomem(q);
    }
    /* neighbours to look at again: a coarser leaf may now be out of
     * balance; one of the same level has a finer side now, which matters to
     * a leaf with features, emitted by the full rules (a leaf without
     * features finds its finer sides when emitted) */
    for (int s = 0; s < 4; s++) {
        uint32_t m = nb[s];
        if (m != NONE && is_leaf(q, m) && (q->nd[m].level < q->nd[n].level || (!q->cheap && q->nd[m].nf > 0)) &&
            !push(q, m))
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
    if (!RESERVE(q, q->stri, q->capstri, q->nstri + 3) || !RESERVE(q, q->stlab, q->capstlab, q->nstri / 3 + 1))
        return false;
    q->stlab[q->nstri / 3] = q->curlab;
    q->stri[q->nstri++] = a;
    q->stri[q->nstri++] = b;
    q->stri[q->nstri++] = c;
    return true;
}

static bool add_sedge(qt *q, uint32_t a, uint32_t b, uint32_t piece)
{
    if (!RESERVE(q, q->sedge, q->capsedge, q->nsedge + 3) || !RESERVE(q, q->elab, q->capelab, 2 * (q->nsedge / 3 + 1)))
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
        for (size_t e = 0; e < k && worst >= 0 && worst > best_shape; e++) { /* stop once it cannot win */
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
            int o1, o2;
            if (r->a == p->a || r->a == p->b) { /* a shared end gives an exact zero, which the filter cannot certify */
                o1 = 0;
                o2 = sgn(tsr_orient2d(A, B, D));
            } else if (r->b == p->a || r->b == p->b) {
                o1 = sgn(tsr_orient2d(A, B, C));
                o2 = 0;
            } else {
                o1 = sgn(tsr_orient2d(A, B, C));
                o2 = sgn(tsr_orient2d(A, B, D));
            }
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

/* Does crossing piece pi count for the region (the even-odd rule skips
 * pieces covered by an even number of segments)? */
static bool piece_counts(const qt *q, uint32_t pi)
{
    return q->region != TSR_REGION_EVEN_ODD || (q->pc[pi].ncov & 1);
}

/* Fans face[0 .. k) (ring positions, counter-clockwise) from ring point a,
 * labelled by sector: the constrained edges from a to its exits (xse[pos]:
 * the sedge of the exit at ring position pos, or NONE) that count part it.
 * The face's ring segments get the labels of their triangles; a chord on
 * the face (cse[pos]: the sedge of the chord from pos, partner[pos] its
 * other end) has its side `flab` relabelled. */
static bool apex_fan(qt *q, uint32_t a, const uint32_t *face, size_t k, const uint32_t *xse, const uint32_t *cse,
                     const uint32_t *partner, uint32_t flab)
{
    uint32_t cnt = 0, base = q->nlab, sec = 0, first = NONE, prev = NONE;
    for (size_t e = 0; e < k; e++)
        cnt += xse[face[e]] != NONE && piece_counts(q, q->sedge[3 * xse[face[e]] + 2]);
    if (cnt > 0)
        q->nlab += cnt;
    for (size_t e = 0; e < k; e++) {
        uint32_t u = face[e], v = face[e + 1 == k ? 0 : e + 1], x = xse[u];
        if (e > 0 && x != NONE && piece_counts(q, q->sedge[3 * x + 2]))
            sec++;
        uint32_t lab = cnt ? base + sec % cnt : flab;
        q->curlab = lab;
        if (!add_tri(q, a, u, v))
            return false;
        if (partner && partner[u] == v) { /* a chord: this side of it */
            uint32_t c = cse[u];
            q->elab[2 * c + (q->elab[2 * c] == flab ? 0 : 1)] = lab;
        } else
            q->slab[u] = lab;
        if (x != NONE) {
            q->elab[2 * x + 1] = lab;
            if (e > 0)
                q->elab[2 * x] = prev;
        }
        if (e == 0)
            first = x;
        prev = lab;
    }
    if (first != NONE)
        q->elab[2 * first] = prev; /* the last triangle is before the first */
    return true;
}

/* The ring cut by the chords (meets with use 1; they must not cross: their
 * ring intervals nest) into convex faces, each fanned from the first of its
 * points that serves, except the face holding the apex (ring index `apex`,
 * or NONE), which is fanned from it: the exits of the apex's pieces (meets
 * with use 2) must lie on that face. Chords and apex-to-exit edges become
 * constrained edges. Labels the parts (q->stlab, slab, elab). R_SIMPLE,
 * R_SPLIT (chords cross or share a point, an exit lies beyond a chord, a
 * face cannot be fanned) or R_ERROR. */
static int chord_faces(qt *q, uint32_t nr, uint32_t apex)
{
    /* partner[i]: the other end of the chord at ring position i */
    if (!RESERVE(q, q->idx, q->capidx, 12 * (size_t)nr + 8))
        return nomem(q);
    uint32_t *partner = q->idx, *stack = partner + nr, *exit = stack + nr + 1, *start = exit + nr;
    uint32_t *pairs = start + nr + 2, *poly = pairs + 4 * (size_t)nr, *cse = poly + 2 * (size_t)nr, *xse = cse + nr;
    uint32_t nface = 0;
    /* pairs: (face, position), at most 2 per position; poly: faces' points
     * grouped by face, face f at poly[start[f] .. start[f + 1]) */
    size_t nexit = 0;
    for (uint32_t i = 0; i < nr; i++)
        partner[i] = xse[i] = NONE;
    for (size_t i = 0; i < q->nsm; i++) {
        const qmeet *m = &q->sm[i];
        if (m->use == 2) {
            exit[nexit++] = m->ri[0];
            if (xse[m->ri[0]] != NONE)
                q->fast = false; /* two exits at one point: one edge, covered twice */
            else
                xse[m->ri[0]] = (uint32_t)(q->nsedge / 3);
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
        cse[u] = cse[v] = (uint32_t)(q->nsedge / 3);
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
        if (j != NONE && j > i) {
            q->elab[2 * cse[i]] = stack[depth - 1];
            q->elab[2 * cse[i] + 1] = nface;
            stack[depth++] = nface++;
            pairs[2 * np] = stack[depth - 1];
            pairs[2 * np++ + 1] = i;
        } else if (j != NONE) {
            if (depth < 2)
                return R_SPLIT;
            depth--;
            pairs[2 * np] = stack[depth - 1];
            pairs[2 * np++ + 1] = i;
        }
        q->slab[i] = stack[depth - 1]; /* the segment i -> i + 1 */
    }
    if (depth != 1)
        return R_SPLIT;
    q->nlab = nface;
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
            if (!apex_fan(q, apex, face, k, xse, cse, partner, f))
                return nomem(q);
            placed = true;
            continue;
        }
        q->curlab = f;
        if (!fan_part(q, face, k))
            return q->status != TSR_OK ? R_ERROR : R_SPLIT;
    }
    return placed ? R_SIMPLE : R_SPLIT;
}

/* The faces of the leaf just triangulated, from the labels its rules gave
 * (q->stlab, slab, elab): labels joined across constrained edges that do
 * not count. Leaves in q->lfs the face of each triangle, then of both sides
 * of each constrained edge; appends to q->sl its side lists (each side's
 * ring segments in ascending coordinate order: how many, how many lie below
 * the midpoint, and their faces) and its pairs of faces across counted
 * constrained edges, all in bytes. False on running out of memory
 * (q->status), or with q->fast cleared for a leaf too big for bytes. */
static bool cell_faces(qt *q, qrec *lf, const qcell *c)
{
    uint32_t T = (uint32_t)(q->nstri / 3), nr = (uint32_t)q->nring, ns = (uint32_t)(q->nsedge / 3), nl = q->nlab;
    if (!RESERVE(q, q->lfs, q->caplfs, (size_t)T + 2 * (size_t)ns + 2 * (size_t)nl + 8)) {
        q->status = TSR_ERR_NOMEM;
        return false;
    }
    uint32_t *face = q->lfs, *sface = face + T, *par = sface + 2 * ns, *lface = par + nl;
    for (uint32_t l = 0; l < nl; l++) {
        par[l] = l;
        lface[l] = NONE;
    }
    for (uint32_t e = 0; e < ns; e++)
        if (!piece_counts(q, q->sedge[3 * e + 2]))
            par[tsr__uf_find(par, q->elab[2 * e])] = tsr__uf_find(par, q->elab[2 * e + 1]);
    uint32_t nf = 0;
    for (uint32_t l = 0; l < nl; l++) {
        uint32_t r = tsr__uf_find(par, l);
        if (lface[r] == NONE)
            lface[r] = nf++;
        lface[l] = lface[r];
    }
    for (uint32_t t = 0; t < T; t++)
        face[t] = lface[q->stlab[t]];
    uint32_t cs[5], mid[4] = {NONE, NONE, NONE, NONE}, npair = 0;
    for (uint32_t i = 0; i < nr; i++) {
        uint8_t g = q->ring[i].grid;
        if (g < 4)
            cs[g] = i;
        else if (g < 8)
            mid[g - 4] = i;
    }
    cs[4] = nr;
    for (uint32_t e = 0; e < ns; e++) {
        sface[2 * e] = lface[q->elab[2 * e]];
        sface[2 * e + 1] = lface[q->elab[2 * e + 1]];
        npair += piece_counts(q, q->sedge[3 * e + 2]) && sface[2 * e] != sface[2 * e + 1];
    }
    bool small = nf < 255 && npair < 255;
    for (int s = 0; s < 4; s++)
        small &= cs[s + 1] - cs[s] < 255;
    if (!small) {
        q->fast = false;
        return false;
    }
    if (!RESERVE(q, q->sl, q->capsl, q->nsl + 9 + (size_t)nr + 2 * (size_t)npair)) {
        q->status = TSR_ERR_NOMEM;
        return false;
    }
    lf->nface = nf;
    lf->side = (uint32_t)q->nsl;
    uint8_t *o = q->sl + q->nsl;
    for (int s = 0; s < 4; s++) {
        uint32_t a = cs[s], b = cs[s + 1], n = b - a;
        *o++ = (uint8_t)n;
        *o++ = (uint8_t)(!c->fine[s] ? 255 : s < 2 ? mid[s] - a : b - mid[s]);
        for (uint32_t j = 0; j < n; j++)
            *o++ = (uint8_t)lface[q->slab[s < 2 ? a + j : b - 1 - j]]; /* the segment i -> i + 1 */
    }
    *o++ = (uint8_t)npair;
    for (uint32_t e = 0; e < ns; e++)
        if (piece_counts(q, q->sedge[3 * e + 2]) && sface[2 * e] != sface[2 * e + 1]) {
            *o++ = (uint8_t)sface[2 * e];
            *o++ = (uint8_t)sface[2 * e + 1];
        }
    q->nsl = (size_t)(o - q->sl);
    return true;
}

/* Writes the leaf just found simple (q->ring, q->stri, q->sedge) into the
 * results as record q->nd[n].rec: vertex ids, triangles, constrained edges,
 * and when choosing the region its faces and side lists. False when out of
 * memory. */
static bool emit_cell(qt *q, uint32_t n, const qcell *c)
{
    for (size_t i = 0; i < q->npt; i++)
        if (ring_id(q, &q->ring[i]) == NONE)
            return false;
    qrec r = {(uint32_t)(q->ntri / 3), (uint32_t)(q->nstri / 3), (uint32_t)(q->nedge / 3), 0, NONE, 1, NONE};
    if (q->fast && !cell_faces(q, &r, c) && q->status != TSR_OK)
        return false; /* else, when it failed, q->fast is now false */
    if (!RESERVE(q, q->tri, q->captri, q->ntri + q->nstri) || !RESERVE(q, q->rec, q->caprec, q->nrec + 1))
        return false;
    if (q->fast) {
        if (!RESERVE(q, q->tface, q->captface, (q->ntri + q->nstri) / 3))
            return false;
        for (size_t i = 0; i < q->nstri / 3; i++)
            q->tface[q->ntri / 3 + i] = (uint8_t)q->lfs[i];
    }
    for (size_t i = 0; i < q->nstri; i++)
        q->tri[q->ntri++] = q->ring[q->stri[i]].id;
    for (size_t i = 0; i < q->nsedge; i += 3) {
        size_t e0 = q->nedge / 3;
        if (!add_edge(q, q->ring[q->sedge[i]].id, q->ring[q->sedge[i + 1]].id, q->sedge[i + 2]))
            return false;
        if (q->fast) {
            if (!RESERVE(q, q->ef, q->capef, 2 * (q->nedge / 3)))
                return false;
            for (size_t e = e0; e < q->nedge / 3; e++) {
                q->ef[2 * e] = (uint8_t)q->lfs[q->nstri / 3 + 2 * (i / 3)];
                q->ef[2 * e + 1] = (uint8_t)q->lfs[q->nstri / 3 + 2 * (i / 3) + 1];
            }
        }
    }
    r.nedge = (uint32_t)(q->nedge / 3) - r.edge;
    q->rec[q->nrec] = r;
    q->nd[n].rec = (uint32_t)q->nrec++;
    return true;
}

/* Decides leaf n; when the full rules find it simple, triangulates it into
 * the results (emit_cell). emit: the tree is final (the leaf's finer sides
 * are those its last look saw), and a leaf that is not simple goes to the
 * Delaunay fallback. */
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
        if ((q->nd[n].done & (DONE | 15)) == (DONE | fine))
            return R_SIMPLE; /* nothing it depends on changed since */
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
    bool test_pairs = q->detect && !(d->done & PAIRED) && (nf <= PAIR_TEST_MAX || L >= q->depth);
    if (!RESERVE(q, q->sv, q->capsv, nvert) || !RESERVE(q, q->sm, q->capsm, nf - nvert))
        return nomem(q);
    q->nsv = 0;
    q->nsm = 0;
    for (uint32_t i = 0; i < nvert; i++)
        q->sv[q->nsv++] = list[i];
    if (nvert >= 2 && L < q->depth) { /* not simple: only the pairs are of interest */
        if (!test_pairs)
            return R_SPLIT;
        for (uint32_t i = nvert; i < nf; i++) /* every listed piece meets the closed cell */
            q->sm[q->nsm++].piece = list[i] & ~PIECE_BIT;
        if (pair_tests(q))
            return R_INTERACT;
        if (q->status != TSR_OK)
            return R_ERROR;
        q->nd[n].done |= PAIRED;
        return R_SPLIT;
    }
    if (q->cheap)
        return R_SIMPLE; /* for now: the second pass applies the full rules */
    cell_geometry(q, n, &c);
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
        if (!(P[0] > c.xs[0] && P[0] < c.xs[2] && P[1] > c.ys[0] && P[1] < c.ys[2]))
            ok = false; /* on a side: the fan would be flat there */
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
                /* a chord exactly through the vertex is not simple (the
                 * pair tests split its piece there): its rounded side
                 * points can leave the vertex a sliver off it, and the
                 * fan's flat triangle under the vertex would join the
                 * sectors on both sides */
                m->use = 1;
                nchord++;
                ok = m->n == 2 && !m->ends && tsr_orient2d(V(q, p->a), V(q, p->b), P) != 0;
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
    q->nlab = 1;
    q->curlab = 0;
    /* chords that would be fine but for where their side points fell */
    bool conflict = ok && q->nsv == 0 && nchord > 0;
    if (ok && !build_ring(q, &c, false, false)) {
        if (q->status != TSR_OK)
            return R_ERROR;
        ok = false;
    }
    if (ok) {
        uint32_t nr = (uint32_t)q->nring;
        if (!RESERVE(q, q->slab, q->capslab, nr))
            return nomem(q);
        for (uint32_t i = 0; i < nr; i++)
            q->slab[i] = 0;
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
            for (uint32_t i = 0; i < nr && ok && !nchord; i++)
                ok = ccw(q, a, i, i + 1 == nr ? 0 : i + 1);
            if (ok && !nchord) {
                if (!RESERVE(q, q->idx, q->capidx, 2 * (size_t)nr))
                    return nomem(q);
                uint32_t *face = q->idx, *xse = face + nr;
                for (uint32_t i = 0; i < nr; i++) {
                    face[i] = i;
                    xse[i] = NONE;
                }
                for (size_t i = 0; i < q->nsm; i++) {
                    const qmeet *m = &q->sm[i];
                    if (!m->use)
                        continue;
                    if (xse[m->ri[0]] != NONE)
                        q->fast = false; /* two exits at one point: one edge, covered twice */
                    else
                        xse[m->ri[0]] = (uint32_t)(q->nsedge / 3);
                    if (!add_sedge(q, a, m->ri[0], m->piece))
                        return nomem(q);
                }
                if (!apex_fan(q, a, face, nr, xse, NULL, NULL, 0))
                    return nomem(q);
            }
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
        if (test_pairs)
            q->nd[n].done |= PAIRED;
        /* Chords that neither cross nor touch, yet coincide or interleave
         * on the sides: their pieces are a rounding error apart (two
         * crossings an ulp apart joined to one vertex, say), which
         * splitting does not change along their whole length. */
        bool rounding = conflict && (test_pairs || (q->nd[n].done & PAIRED) || !q->detect);
        if (L < q->depth && !rounding)
            return R_SPLIT;
        if (emit && fallback(q, &c) != TSR_OK)
            return R_ERROR;
        return R_FALLBACK;
    }
    /* simple: into the results now (a later look that finds it changed or
     * splits it leaves this record unused), unless features met: then the
     * build starts again */
    if (q->nit == 0 && !emit_cell(q, n, &c))
        return nomem(q);
    q->nd[n].done = (uint8_t)(DONE | q->nd[n].fine | (q->nd[n].done & PAIRED));
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
    q->fast = false; /* its triangles come from elsewhere: the general region pass decides */
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
        uint32_t s = res.edge_segment[i], u = map[res.edge[2 * (size_t)i]], w = map[res.edge[2 * (size_t)i + 1]];
        if (s >= nchain)
            continue; /* the cell's own boundary */
        if (!add_edge(q, u, w, sseg[s]))
            goto done;
        /* The Delaunay method names only the lowest of the chains merged
         * on this edge (overlapping, exactly collinear: two pieces a
         * rounding apart whose clipped ends fell on one ring point, say).
         * The others cover it too, and even-odd counts every cover. */
        const double *S0 = lxy + 2 * (size_t)seg[2 * (size_t)s], *S1 = lxy + 2 * (size_t)seg[2 * (size_t)s + 1];
        const double *E0 = res.xy + 2 * (size_t)res.edge[2 * (size_t)i],
                     *E1 = res.xy + 2 * (size_t)res.edge[2 * (size_t)i + 1];
        double mid[2] = {0.5 * (E0[0] + E1[0]), 0.5 * (E0[1] + E1[1])}, tm = along(S0, S1, mid);
        for (size_t t = 0; t < nchain; t++) {
            const double *T0 = lxy + 2 * (size_t)seg[2 * t], *T1 = lxy + 2 * (size_t)seg[2 * t + 1];
            if (t == s || tsr_orient2d(S0, S1, T0) != 0 || tsr_orient2d(S0, S1, T1) != 0)
                continue;
            double t0 = along(S0, S1, T0), t1 = along(S0, S1, T1);
            if (tm > fmin(t0, t1) && tm < fmax(t0, t1) && !add_edge(q, u, w, sseg[t]))
                goto done;
        }
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
    q->nd[0] = (qnode){0, 0, (uint32_t)nf, 0, 0, 0, 0, NONE};
    q->nnd = 1;
    for (uint32_t v = 0; v < q->nfv; v++)
        q->ft[q->nft++] = v;
    for (size_t p = 0; p < q->npc; p++)
        q->ft[q->nft++] = PIECE_BIT | (uint32_t)p;
    q->ftlive = q->nft;
    /* first split by what is cheap to decide (two vertices, balance), then
     * apply the full rules to every leaf with features: most leaves then
     * see their final neighbours at their first full look */
    for (int pass = 0; pass < 2; pass++) {
        q->cheap = pass == 0;
        for (size_t n = 0; n < (pass ? q->nnd : 1); n++)
            if (is_leaf(q, (uint32_t)n) && (pass == 0 || q->nd[n].nf > 0) && !push(q, (uint32_t)n))
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
    }
    q->cheap = false;
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

/* The part of piece pi around parameter t (0 at its end a, 1 at b)
 * between the points that split it, sp[0..n) sorted by split_cmp: its
 * ends, the lower vertex id first. */
static void sub_piece(const qt *q, const qsplit *sp, size_t n, uint32_t pi, double t, uint32_t e[2])
{
    const qpiece *p = &q->pc[pi];
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (sp[mid].p < pi)
            lo = mid + 1;
        else
            hi = mid;
    }
    uint32_t u = p->a, w = p->b;
    for (size_t i = lo; i < n && sp[i].p == pi; i++) {
        if (sp[i].t <= t)
            u = sp[i].v;
        else {
            w = sp[i].v;
            break;
        }
    }
    e[0] = u < w ? u : w;
    e[1] = u < w ? w : u;
}

/* Splits the pieces at the points and crossings found by a build. A
 * crossing is computed from the parts of the two pieces between the points
 * that split them in this round, each from its lower vertex id, the part
 * with the lower ids first, so that it depends on those parts alone: two
 * collinear overlapping pieces, one split at the other's end inside it,
 * become one piece there (segments counted twice, which the even-odd rule
 * does not count), and a third piece crossing both must cross that one
 * piece at one vertex. Computed from each whole piece, the two crossings
 * fell an ulp apart, the pieces stayed apart, two chains with slivers or
 * fallback cells between them, each counted by the region: crossing them
 * cost two where the Delaunay method, whose later segment follows the
 * earlier's chain, counts none, and a region behind them reached at depth
 * one from elsewhere was kept. */
static tsr_status apply_interactions(qt *q)
{
    qsort(q->it, q->nit, sizeof *q->it, inter_cmp);
    qsplit *sp = tsr_alloc(q->al, (2 * q->nit + 1) * sizeof *sp);
    qpiece *np = NULL;
    if (!sp)
        return q->status = TSR_ERR_NOMEM;
    size_t ns = 0, n0;
    for (size_t i = 0; i < q->nit && q->it[i].kind == 0; i++) { /* the points first (inter_cmp) */
        const qinter *it = &q->it[i];
        if (i && inter_cmp(it, it - 1) == 0)
            continue;
        const qpiece *p = &q->pc[it->p];
        sp[ns++] = (qsplit){it->p, it->other, along(V(q, p->a), V(q, p->b), V(q, it->other))};
    }
    qsort(sp, ns, sizeof *sp, split_cmp);
    n0 = ns;
    for (size_t i = 0; i < q->nit; i++) {
        const qinter *it = &q->it[i];
        if (it->kind == 0 || (i && inter_cmp(it, it - 1) == 0))
            continue;
        const qpiece *p = &q->pc[it->p], *r = &q->pc[it->other];
        const double *A = V(q, p->a), *B = V(q, p->b), *C = V(q, r->a), *D = V(q, r->b);
        /* where along each piece, roughly: which part of it crosses */
        double ux = B[0] - A[0], uy = B[1] - A[1], vx = D[0] - C[0], vy = D[1] - C[1];
        double den = ux * vy - uy * vx;
        double tp = ((C[0] - A[0]) * vy - (C[1] - A[1]) * vx) / den;
        double tr = ((C[0] - A[0]) * uy - (C[1] - A[1]) * ux) / den;
        uint32_t e[2][2];
        sub_piece(q, sp, n0, it->p, tp, e[0]);
        sub_piece(q, sp, n0, it->other, tr, e[1]);
        int f = e[1][0] < e[0][0] || (e[1][0] == e[0][0] && e[1][1] < e[0][1]);
        double a[2], b[2], cc[2], dd[2];
        memcpy(a, V(q, e[f][0]), sizeof a);
        memcpy(b, V(q, e[f][1]), sizeof b);
        memcpy(cc, V(q, e[!f][0]), sizeof cc);
        memcpy(dd, V(q, e[!f][1]), sizeof dd);
        ux = b[0] - a[0], uy = b[1] - a[1], vx = dd[0] - cc[0], vy = dd[1] - cc[1];
        den = ux * vy - uy * vx;
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

/* Forgets what a build emitted: the pieces are about to change. */
static void reset_results(qt *q)
{
    q->ntri = q->nedge = q->nrec = q->nsl = 0;
    q->nxy = q->nfv;
    for (size_t i = 0; i < q->kcap; i++)
        q->ks[i] = NONE;
    q->nks = 0;
    for (size_t i = 0; q->kc && i < (size_t)1 << KCACHE_BITS; i++)
        q->kc[i].id = NONE;
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

/* ---- emission and the region ------------------------------------ */

/* Rule (a) for a leaf without features, into the results: two triangles,
 * or a fan from the first midpoint of a side with a finer neighbour (bits
 * of fine). The same points and keys as cell_geometry's. */
static bool emit_empty(qt *q, uint32_t n, unsigned fine)
{
    static const uint8_t gi[8][2] = {{0, 0}, {2, 0}, {2, 2}, {0, 2}, {1, 0}, {2, 1}, {1, 2}, {0, 1}};
    const qnode *d = &q->nd[n];
    int L = d->level, sh = q->depth - L;
    uint32_t ix, iy;
    node_at(q, n, &ix, &iy);
    double fx = ix, fy = iy;
    uint32_t ring[8], k = 0, w = NONE;
    for (int s = 0; s < 4; s++)
        for (int g = s; g < 8; g += 4) {
            if (g >= 4 && !(fine >> s & 1))
                break;
            if (g >= 4 && w == NONE)
                w = k;
            uint64_t lx = ((uint64_t)2 * ix + gi[g][0]) << sh, ly = ((uint64_t)2 * iy + gi[g][1]) << sh;
            ring[k] = point_id(q, lx << 31 | ly, gcoord(q, q->ox, L, fx + 0.5 * gi[g][0]),
                               gcoord(q, q->oy, L, fy + 0.5 * gi[g][1]));
            if (ring[k++] == NONE)
                return false;
        }
    if (!RESERVE(q, q->tri, q->captri, q->ntri + 3 * (size_t)k))
        return false;
    uint32_t *t = q->tri + q->ntri;
    if (w == NONE) {
        t[0] = ring[0], t[1] = ring[1], t[2] = ring[2], t[3] = ring[0], t[4] = ring[2], t[5] = ring[3];
        q->ntri += 6;
        return true;
    }
    for (uint32_t i = 0; i < k; i++) {
        uint32_t j = i + 1 == k ? 0 : i + 1;
        if (i != w && j != w) {
            *t++ = ring[w];
            *t++ = ring[i];
            *t++ = ring[j];
        }
    }
    q->ntri += 3 * (size_t)(k - 2);
    return true;
}

/* A leaf's first face, once number_faces has run: its feature list's
 * place, no longer needed, holds it. */
static uint32_t face_of(const qt *q, uint32_t n)
{
    return q->nd[n].f;
}

/* Numbers the faces, leaf by leaf (face_of, the records' face); a leaf
 * with features the build did not emit goes to the Delaunay fallback now. */
static tsr_status number_faces(qt *q)
{
    q->nface = 0;
    for (size_t n = 0; n < q->nnd; n++) {
        qnode *d = &q->nd[n];
        if (!is_leaf(q, (uint32_t)n))
            continue;
        if (d->nf == 0) {
            d->f = q->nface++;
            continue;
        }
        if (d->rec == NONE) {
            size_t t0 = q->ntri / 3, e0 = q->nedge / 3;
            int r = eval(q, (uint32_t)n, true);
            if (r == R_ERROR)
                return q->status;
            assert(r == R_FALLBACK || r == R_SIMPLE); /* the build emitted every other leaf */
            if (!RESERVE(q, q->rec, q->caprec, q->nrec + 1))
                return q->status = TSR_ERR_NOMEM;
            q->rec[q->nrec] = (qrec){
                (uint32_t)t0, (uint32_t)(q->ntri / 3 - t0), (uint32_t)e0, (uint32_t)(q->nedge / 3 - e0), NONE, 1, NONE};
            q->nd[n].rec = (uint32_t)q->nrec++;
        }
        qrec *r = &q->rec[q->nd[n].rec];
        r->face = q->nd[n].f = q->nface;
        q->nface += r->nface;
    }
    return TSR_OK;
}

typedef struct qvisit {
    uint32_t n, nb[4]; /* nb: across each side, the node of n's level, or the coarser leaf; NONE: the border */
} qvisit;

/* Pushes the children of inner node v, their neighbours found from v's,
 * so that they come off the stack in Z order (at most 3 per level and 4
 * more on it). */
static void push_children(const qt *q, qvisit *stack, size_t *top, const qvisit *v)
{
    uint32_t c = q->nd[v->n].child;
    for (unsigned k = 4; k-- > 0;) {
        unsigned x = k & 1, y = k >> 1;
        stack[(*top)++] =
            (qvisit){c + k,
                     {y ? c + k - 2 : down(q, v->nb[0], k + 2), x ? down(q, v->nb[1], k - 1) : c + k + 1,
                      y ? down(q, v->nb[2], k - 2) : c + k + 2, x ? c + k - 1 : down(q, v->nb[3], k + 1)}};
    }
}

/* Leaf n's list for side s (s == 4: its face pairs); NULL for a leaf
 * without features. */
static const uint8_t *side_list(const qt *q, uint32_t n, int s)
{
    if (q->nd[n].nf == 0)
        return NULL;
    const uint8_t *p = q->sl + q->rec[q->nd[n].rec].side;
    for (int k = 0; k < s; k++)
        p += 2 + (size_t)p[0];
    return p;
}

static uint32_t uf_root(uint32_t *par, uint32_t x)
{
    while (par[x] != x)
        x = par[x] = par[par[x]];
    return x;
}

/* Joins the faces on both sides of a shared side: leaf c's list cl[c0 ..
 * c0 + cn) (NULL: c's one face) with leaf x's xl[x0 .. x0 + xn) (c's
 * faces from fc on, x's from fx on). False when the lists do not pair up. */
static bool join_across(uint32_t *par, uint32_t fc, const uint8_t *cl, uint32_t c0, uint32_t cn, uint32_t fx,
                        const uint8_t *xl, uint32_t x0, uint32_t xn)
{
    if (!cl || !xl) {
        if ((cl ? cn : xn) != 1) /* a leaf without features has no point inside its sides */
            return false;
        uint32_t a = fc + (cl ? cl[2 + c0] : 0), b = fx + (xl ? xl[2 + x0] : 0);
        par[uf_root(par, a)] = uf_root(par, b);
        return true;
    }
    if (cn != xn)
        return false;
    for (uint32_t j = 0; j < cn; j++)
        par[uf_root(par, fc + cl[2 + c0 + j])] = uf_root(par, fx + xl[2 + x0 + j]);
    return true;
}

/* The region from the cells, as region_keep chooses it over triangles:
 * faces that meet across a cell's side are joined (crossing there costs
 * nothing), then a breadth-first search over the joined parts, a counted
 * constrained edge costing one, from those on the square's border. Sets
 * keep[face]; clears q->fast when two cells' lists of a shared side do not
 * pair up (the general pass decides then). */
static tsr_status choose_region(qt *q, uint8_t *keep)
{
    uint32_t nf = q->nface, npart = 0, nedge = 0;
    size_t nborder = 0, capborder = 0;
    uint32_t *depth = NULL, *start = NULL, *to = NULL, *queue = NULL, *border = NULL;
    tsr_status st = TSR_ERR_NOMEM;
    bool ok = true;
    qvisit stack[4 * (DEPTH_MAX + 3)];
    size_t top = 0;
    if (nf >= PIECE_BIT) { /* parts are marked with that bit below */
        q->fast = false;
        return TSR_OK;
    }
    if (!RESERVE(q, q->ft, q->capft, nf)) /* the feature lists are done with */
        goto done;
    uint32_t *par = q->ft;
    for (uint32_t i = 0; i < nf; i++)
        par[i] = i;
    /* each shared side once: from the finer leaf, or from the left or lower
     * of two of one level; neighbours found top down */
    stack[top++] = (qvisit){0, {NONE, NONE, NONE, NONE}};
    while (top && ok) {
        qvisit v = stack[--top];
        const qnode *cn = &q->nd[v.n];
        if (!is_leaf(q, v.n)) {
            push_children(q, stack, &top, &v);
            continue;
        }
        for (int s = 0; s < 4 && ok; s++) {
            uint32_t m = v.nb[s];
            const uint8_t *cl = side_list(q, v.n, s);
            if (m == NONE) { /* on the border: outside */
                if (!RESERVE(q, border, capborder, nborder + 256))
                    goto done;
                for (uint32_t j = 0; j < (cl ? cl[0] : 1); j++)
                    border[nborder++] = face_of(q, v.n) + (cl ? cl[2 + j] : 0);
                continue;
            }
            if (!is_leaf(q, m))
                continue; /* finer leaves join from their side */
            bool coarser = q->nd[m].level < cn->level;
            if (!coarser && (s == 0 || s == 3))
                continue;
            const uint8_t *xl = side_list(q, m, s ^ 2);
            uint32_t x0 = 0, xn = xl ? xl[0] : 1;
            if (xl && coarser) {                                                          /* the half beside c */
                uint32_t mid = xl[1], upper = ((s & 1) ? (v.n - 1) >> 1 : (v.n - 1)) & 1; /* v.n is a child */
                if (mid == 255 || mid > xl[0]) {
                    ok = false;
                    break;
                }
                x0 = upper ? mid : 0;
                xn = upper ? xl[0] - mid : mid;
            }
            ok = join_across(par, face_of(q, v.n), cl, 0, cl ? cl[0] : 1, face_of(q, m), xl, x0, xn);
        }
    }
    if (!ok) {
        q->fast = false;
        st = TSR_OK;
        goto done;
    }
    /* parts: par[] becomes the part of each face (roots numbered first,
     * marked with PIECE_BIT, then every face takes its root's number) */
    for (uint32_t i = 0; i < nf; i++)
        par[i] = uf_root(par, i);
    for (uint32_t i = 0; i < nf; i++)
        if (par[i] == i)
            par[i] = PIECE_BIT | npart++;
    for (uint32_t i = 0; i < nf; i++)
        if (!(par[i] & PIECE_BIT))
            par[i] = par[par[i]];
    for (uint32_t i = 0; i < nf; i++)
        par[i] &= ~PIECE_BIT;
    depth = tsr_alloc(q->al, ((size_t)npart + 1) * sizeof *depth);
    start = tsr_alloc(q->al, ((size_t)npart + 2) * sizeof *start);
    queue = tsr_alloc(q->al, ((size_t)npart + 1) * sizeof *queue);
    if (!depth || !start || !queue)
        goto done;
    for (uint32_t p = 0; p < npart + 2; p++)
        start[p] = 0;
    /* counted constrained edges between parts */
    for (int pass = 0; pass < 2; pass++) {
        for (size_t i = 0; i < q->nrec; i++) {
            const qrec *r = &q->rec[i];
            if (r->face == NONE || r->side == NONE)
                continue;
            const uint8_t *pl = q->sl + r->side;
            for (int k = 0; k < 4; k++)
                pl += 2 + (size_t)pl[0];
            for (uint32_t j = 0; j < pl[0]; j++) {
                uint32_t u = par[r->face + pl[1 + 2 * j]], w = par[r->face + pl[2 + 2 * j]];
                if (u == w)
                    continue;
                if (pass == 0) {
                    start[u + 1]++;
                    start[w + 1]++;
                } else {
                    to[start[u]++] = w;
                    to[start[w]++] = u;
                }
            }
        }
        if (pass == 0) {
            for (uint32_t p = 0; p < npart; p++)
                start[p + 1] += start[p];
            nedge = start[npart];
            to = tsr_alloc(q->al, ((size_t)nedge + 1) * sizeof *to);
            if (!to)
                goto done;
        } else {
            for (uint32_t p = npart; p > 0; p--)
                start[p] = start[p - 1];
            start[0] = 0;
        }
    }
    /* breadth-first from the parts on the border */
    size_t head = 0, tail = 0;
    for (uint32_t p = 0; p < npart; p++)
        depth[p] = NONE;
    for (size_t i = 0; i < nborder; i++) {
        uint32_t p = par[border[i]];
        if (depth[p] == NONE) {
            depth[p] = 0;
            queue[tail++] = p;
        }
    }
    while (head < tail) {
        uint32_t p = queue[head++];
        for (uint32_t k = start[p]; k < start[p + 1]; k++)
            if (depth[to[k]] == NONE) {
                depth[to[k]] = depth[p] + 1;
                queue[tail++] = to[k];
            }
    }
    for (uint32_t i = 0; i < nf; i++) {
        uint32_t dd = depth[par[i]];
        keep[i] = dd != NONE && (q->region == TSR_REGION_ENCLOSED ? dd >= 1 : dd % 2 == 1);
    }
    st = TSR_OK;
done:
    tsr_free(q->al, depth);
    tsr_free(q->al, start);
    tsr_free(q->al, to);
    tsr_free(q->al, queue);
    tsr_free(q->al, border);
    return st;
}

/* The results: the triangles of the records' kept faces (all when keep is
 * NULL), in place, then the leaves without features, in Z order so that
 * the corners they share are looked up close together in time. */
static bool emit_output(qt *q, const uint8_t *keep)
{
    size_t k = 0;
    for (size_t i = 0; i < q->nrec; i++) { /* records in order: k never passes t */
        const qrec *r = &q->rec[i];
        if (r->face == NONE)
            continue;
        for (size_t t = r->tri; t < (size_t)r->tri + r->ntri; t++)
            if (!keep || keep[r->face + q->tface[t]]) {
                memmove(q->tri + 3 * k, q->tri + 3 * t, 3 * sizeof *q->tri);
                k++;
            }
    }
    q->ntri = 3 * k;
    qvisit stack[4 * (DEPTH_MAX + 3)];
    size_t top = 0;
    stack[top++] = (qvisit){0, {NONE, NONE, NONE, NONE}};
    while (top) {
        qvisit v = stack[--top];
        const qnode *d = &q->nd[v.n];
        if (!is_leaf(q, v.n)) {
            push_children(q, stack, &top, &v);
            continue;
        }
        if (d->nf > 0 || (keep && !keep[face_of(q, v.n)]))
            continue;
        unsigned fine = 0;
        for (int s = 0; s < 4; s++)
            fine |= (unsigned)(v.nb[s] != NONE && !is_leaf(q, v.nb[s])) << s;
        if (!emit_empty(q, v.n, fine))
            return false;
    }
    return true;
}

static unsigned popcount64(uint64_t x)
{
    x -= (x >> 1) & 0x5555555555555555ull;
    x = (x & 0x3333333333333333ull) + ((x >> 2) & 0x3333333333333333ull);
    x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0Full;
    return (unsigned)((x * 0x0101010101010101ull) >> 56);
}

/* Drops the Steiner vertices no output triangle uses (input vertices keep
 * their ids; records a later look replaced left some), renumbering the
 * output triangles and the n edges in edge[]. Which vertices stay is a
 * bitmap, and a vertex's new id its rank in it: a few kilobytes, where a
 * map of ids read in triangle order would miss the cache. */
static bool drop_unused(qt *q, uint32_t *edge, size_t n)
{
    size_t words = q->nxy / 64 + 1;
    uint64_t *bit = tsr_alloc(q->al, words * (sizeof *bit + sizeof(uint32_t)));
    if (!bit)
        return false;
    uint32_t *rank = (uint32_t *)(bit + words);
    for (size_t w = 0; w < words; w++)
        bit[w] = 0;
    for (size_t v = 0; v < q->nin; v++)
        bit[v >> 6] |= 1ull << (v & 63);
    for (size_t i = 0; i < q->ntri; i++)
        bit[q->tri[i] >> 6] |= 1ull << (q->tri[i] & 63);
    uint32_t m = 0;
    for (size_t w = 0; w < words; w++) {
        rank[w] = m;
        for (uint64_t b = bit[w]; b; b &= b - 1, m++) {
            size_t v = 64 * w + popcount64((b & -b) - 1); /* the lowest set bit */
            q->xy[2 * (size_t)m] = q->xy[2 * v];
            q->xy[2 * (size_t)m + 1] = q->xy[2 * v + 1];
        }
    }
    for (size_t i = 0; i < q->ntri; i++) {
        uint32_t v = q->tri[i];
        q->tri[i] = rank[v >> 6] + popcount64(bit[v >> 6] & ((1ull << (v & 63)) - 1));
    }
    for (size_t i = 0; i < 2 * n; i++) {
        uint32_t v = edge[i];
        edge[i] = rank[v >> 6] + popcount64(bit[v >> 6] & ((1ull << (v & 63)) - 1));
    }
    q->nxy = m;
    tsr_free(q->al, bit);
    return true;
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
    tsr_free(q->al, q->vkey);
    tsr_free(q->al, q->kc);
    tsr_free(q->al, q->pc);
    tsr_free(q->al, q->cov);
    tsr_free(q->al, q->nd);
    tsr_free(q->al, q->grp);
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
    tsr_free(q->al, q->stlab);
    tsr_free(q->al, q->slab);
    tsr_free(q->al, q->elab);
    tsr_free(q->al, q->tri);
    tsr_free(q->al, q->edge);
    tsr_free(q->al, q->sl);
    tsr_free(q->al, q->tface);
    tsr_free(q->al, q->rec);
    tsr_free(q->al, q->ef);
    tsr_free(q->al, q->lfs);
}

static tsr_status unsupported(qt *q, const char **why_not, const char *why, tsr_error *err)
{
    *why_not = why;
    qt_free(q);
    return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "quadtree method: %s", why);
}

static tsr_status quadtree(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                           const tsr_allocator *alloc, bool *region_done, const char **why_not, tsr_error *err)
{
    static const tsr_tri_options defaults;
    if (!opt)
        opt = &defaults;
    memset(out, 0, sizeof *out);
    *why_not = NULL;
    if (region_done)
        *region_done = false;
    qt q;
    memset(&q, 0, sizeof q);
    q.al = alloc;
    q.err = err;
    q.region = opt->region;
    q.fast =
        region_done && in->nholes == 0 && (opt->region == TSR_REGION_ENCLOSED || opt->region == TSR_REGION_EVEN_ODD);
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
    if (tsr__tri_region_areas(opt))
        return unsupported(&q, why_not, "regional maximum areas need the Delaunay method's refinement", err);

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

    /* the points the build will key (grid points and crossings): about
     * three per feature on the bench's polygon */
    {
        size_t nf = (size_t)q.nfv + q.npc, guess = 3 * nf + 64;
        if (!khash_grow(&q, guess) || !RESERVE(&q, q.xy, q.capxy, 2 * (q.nxy + guess)) ||
            !RESERVE(&q, q.vkey, q.capvkey, q.nxy + guess))
            goto fail;
        /* and the rest, so that growing them copies nothing (what is not
         * used is not touched); from the same polygon */
        if (!RESERVE(&q, q.nd, q.capnd, 4 * nf + 64) || !RESERVE(&q, q.grp, q.capgrp, nf + 16) ||
            !RESERVE(&q, q.ft, q.capft, 6 * nf + 64) || !RESERVE(&q, q.tri, q.captri, 15 * nf + 64) ||
            !RESERVE(&q, q.edge, q.capedge, 5 * (size_t)q.npc + 64) || !RESERVE(&q, q.rec, q.caprec, nf + 64) ||
            !RESERVE(&q, q.sl, q.capsl, 16 * nf + 64) || !RESERVE(&q, q.tface, q.captface, 4 * nf + 64) ||
            !RESERVE(&q, q.ef, q.capef, 4 * (size_t)q.npc + 64))
            goto fail;
    }
    for (int round = 0;; round++) {
        q.detect = round < ROUNDS - 1;
        st = build(&q);
        if (st != TSR_OK)
            goto fail;
        if (q.nit == 0)
            break;
        reset_results(&q);
        st = apply_interactions(&q);
        if (st != TSR_OK)
            goto fail;
    }
    q.detect = false;
    st = number_faces(&q);
    if (st != TSR_OK)
        goto fail;
    uint8_t *keep = NULL;
    if (q.fast) {
        keep = tsr_alloc(alloc, (size_t)q.nface + 1);
        if (!keep || (st = choose_region(&q, keep)) != TSR_OK) {
            tsr_free(alloc, keep);
            st = TSR_ERR_NOMEM;
            goto fail;
        }
        if (!q.fast) {
            tsr_free(alloc, keep);
            keep = NULL;
        }
    }
    if (!emit_output(&q, keep)) {
        tsr_free(alloc, keep);
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    if (q.ntri / 3 > UINT32_MAX || q.nedge / 3 > UINT32_MAX) {
        tsr_free(alloc, keep);
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    /* constrained edges: one per undirected edge and covering segment,
     * ascending ids (an edge seen from two cells is listed once); with the
     * region chosen, those of kept faces, the lowest id only */
    size_t ne = 0, m = 0;
    for (size_t i = 0; i < q.nrec; i++) {
        const qrec *r = &q.rec[i];
        if (r->face == NONE)
            continue;
        for (size_t e = r->edge; e < (size_t)r->edge + r->nedge; e++)
            if (!keep || keep[r->face + q.ef[2 * e]] || keep[r->face + q.ef[2 * e + 1]]) {
                memmove(q.edge + 3 * ne, q.edge + 3 * e, 3 * sizeof *q.edge); /* ne <= e: records in order */
                ne++;
            }
    }
    if (ne > 1 && !keep)
        qsort(q.edge, ne, 3 * sizeof *q.edge, edge3_cmp);
    uint32_t *edge = tsr_alloc(alloc, (2 * ne + 1) * sizeof *edge), *eseg = tsr_alloc(alloc, (ne + 1) * sizeof *eseg);
    if (!edge || !eseg) {
        tsr_free(alloc, keep);
        tsr_free(alloc, edge);
        tsr_free(alloc, eseg);
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    for (size_t i = 0; i < ne; i++) {
        const uint32_t *e = q.edge + 3 * i;
        if (m && (keep || eseg[m - 1] == e[2]) &&
            ((e[0] == edge[2 * m - 2] && e[1] == edge[2 * m - 1]) ||
             (e[0] == edge[2 * m - 1] && e[1] == edge[2 * m - 2])))
            continue;
        edge[2 * m] = e[0];
        edge[2 * m + 1] = e[1];
        eseg[m++] = e[2];
    }
    if (region_done)
        *region_done = keep != NULL;
    if (!drop_unused(&q, edge, m)) {
        tsr_free(alloc, keep);
        tsr_free(alloc, edge);
        tsr_free(alloc, eseg);
        st = TSR_ERR_NOMEM;
        goto fail;
    }
    tsr_free(alloc, keep);
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

tsr_status tsr__tri_quadtree(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                             const tsr_allocator *alloc, const char **why_not, tsr_error *err)
{
    return quadtree(in, opt, out, alloc, NULL, why_not, err);
}

tsr_status tsr__tri_quadtree_region(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                                    const tsr_allocator *alloc, bool *region_done, const char **why_not, tsr_error *err)
{
    return quadtree(in, opt, out, alloc, region_done, why_not, err);
}
