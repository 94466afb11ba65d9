/* ptess.c: the patch tessellator of ptess.h. One restricted quadtree per
 * piece, with the piece's own tile size; linked edges sampled by both
 * sides' border samples (fans); vertices welded through the links;
 * trimmed sources triangulated in (u, v) by tsr_triangulate.
 *
 * Units along an edge. A piece of quadtree depth L and tile size N has a
 * lattice of Z = N << L points per side; its edge is cut into 2^L
 * *segments* of N lattice units, the span of a deepest node. A leaf of
 * level l covers 2^(L-l) segments of each edge it touches; its "span log"
 * is L - l. A link maps its range of one side's edge linearly onto the
 * other's; where the lattices differ (other N or depth), a point of one
 * is a point of the other only where the map gives an integer. */
#define _POSIX_C_SOURCE 200809L
#include "patches/ptess.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

enum { KIND_BEZIER = 0, KIND_SUBD = 1 };
#ifndef SUBD_MARGIN
#define SUBD_MARGIN 1.0
#endif

typedef struct plink {
    uint32_t piece;
    uint8_t edge;
    uint8_t reversed;
    uint8_t t0, t1; /* halves (0, 1, 2 = 0, 1/2, 1) on this edge */
    uint8_t s0, s1; /* on the neighbour's edge, s0 at t0 */
    uint8_t nonmanifold; /* one of two links of an edge three patches share */
} plink;

typedef struct piece {
    uint32_t source;
    uint8_t kind;
    uint8_t collapsed; /* bit e: edge e collapsed to a point */
    uint8_t mirrored;
    uint8_t levels;    /* quadtree depth */
    uint8_t nlinks[4];
    plink link[4][2];
    tsr_patch bez;     /* KIND_BEZIER: the piece over [0,1]^2 */
    uint32_t face, sub;
    double rect[4];    /* in the source's (u, v) */
    double lo[3], hi[3];
} piece;

typedef struct psource {
    uint32_t patch, sub;
    double domain[4];
    uint32_t first_piece, pu, pv;
    bool trimmed;
} psource;

/* A tile size's patterns and which tile vertices each uses: made on first
 * use and kept with the model (every run, every camera, uses them). */
typedef struct patcache {
    tsr_tile_patterns pat;
    uint8_t *used;       /* per stitch mask, per tile vertex */
    uint64_t used_n[16]; /* how many per mask */
    uint16_t *on[16];    /* per mask, per triangle: bits 4k .. 4k+3, the tile
                            edges its edge k (corner k to k + 1) lies on */
    uint16_t *on_store;
} patcache;

enum { NPAT = TSR_TILE_MAX / 2 + 1 };

/* The tile edges (bit e: edge e, 0 south, 1 east, 2 north, 3 west) that
 * tile vertex (i, j) of an N-quad tile lies on. */
static inline unsigned tile_onmask(uint32_t i, uint32_t j, uint32_t N)
{
    return (unsigned)((j == 0) | (i == N) << 1 | (j == N) << 2 | (i == 0) << 3);
}


struct tsr_pmodel {
    tsr_allocator alloc;
    /* logically const: filled at most once per tile size, by whichever run
     * gets there first (compare-and-swap, so runs may share the model) */
    _Atomic(patcache *) pats[NPAT];
    const tsr_patch_set *set;
    const tsr_subd *subd;
    uint32_t npieces, nsources;
    piece *pieces;
    psource *sources;
    double *values; /* control points and weights of the pieces */
    double lo[3], hi[3];
    uint32_t links, collapsed, mirrored, trimmed;
    uint32_t void_loops;     /* loops along their patch's whole border: no trim */
    double link_tol;         /* the distance edges were linked within (model units) */
    uint32_t flat;           /* subd patches without area, left out */
    uint32_t conform_breaks; /* breakpoints a patch took from a neighbour */
    uint32_t partial_unlinked; /* partial overlaps left unlinked (the breakpoint budget) */
    uint32_t split_breaks;   /* breakpoints cut across curved directions */
};

static const tsr_allocator *ma(const tsr_pmodel *m) { return m->alloc.realloc ? &m->alloc : NULL; }

/* ---- model ---------------------------------------------------------------- */

static tsr_pmodel *model_new(const tsr_allocator *alloc)
{
    tsr_pmodel *m = tsr_alloc(alloc, sizeof *m);
    if (!m)
        return NULL;
    memset(m, 0, sizeof *m);
    if (alloc)
        m->alloc = *alloc;
    for (int c = 0; c < 3; c++) {
        m->lo[c] = INFINITY;
        m->hi[c] = -INFINITY;
    }
    return m;
}

void tsr_pmodel_destroy(tsr_pmodel *m)
{
    if (!m)
        return;
    const tsr_allocator *a = ma(m);
    for (int k = 0; k < NPAT; k++) {
        patcache *pc = atomic_load(&m->pats[k]);
        if (pc) {
            tsr_tile_patterns_free(&pc->pat);
            tsr_free(a, pc->used);
            tsr_free(a, pc->on_store);
            tsr_free(a, pc);
        }
    }
    tsr_free(a, m->pieces);
    tsr_free(a, m->sources);
    tsr_free(a, m->values);
    tsr_allocator copy = m->alloc;
    tsr_free(copy.realloc ? &copy : NULL, m);
}

static void box_add(double lo[3], double hi[3], const double p[3])
{
    for (int c = 0; c < 3; c++) {
        lo[c] = p[c] < lo[c] ? p[c] : lo[c];
        hi[c] = p[c] > hi[c] ? p[c] : hi[c];
    }
}

static double model_diag(const tsr_pmodel *m)
{
    double d = 0;
    for (int c = 0; c < 3; c++)
        d += (m->hi[c] - m->lo[c]) * (m->hi[c] - m->lo[c]);
    return sqrt(d);
}

static void add_link(tsr_pmodel *m, uint32_t p, int e, uint32_t q, int f, bool rev, int t0, int t1, int s0, int s1)
{
    piece *pp = &m->pieces[p];
    if (pp->nlinks[e] >= 2)
        return;
    pp->link[e][pp->nlinks[e]++] = (plink){q, (uint8_t)f, rev, (uint8_t)t0, (uint8_t)t1, (uint8_t)s0, (uint8_t)s1, 0};
    m->links++;
}

/* Edge direction along the counter-clockwise boundary of (s, t). */
static int edge_dir(int e) { return e < 2 ? 1 : -1; }

/* Orients pieces consistently through their links (breadth first from
 * each unvisited piece, which keeps its own orientation). */
static tsr_status orient(tsr_pmodel *m)
{
    const tsr_allocator *a = ma(m);
    uint32_t *queue = tsr_alloc(a, (size_t)m->npieces * sizeof *queue);
    uint8_t *seen = tsr_alloc(a, m->npieces);
    if (!queue || !seen) {
        tsr_free(a, queue);
        tsr_free(a, seen);
        return TSR_ERR_NOMEM;
    }
    memset(seen, 0, m->npieces);
    for (uint32_t start = 0; start < m->npieces; start++) {
        if (seen[start])
            continue;
        uint32_t head = 0, tail = 0;
        queue[tail++] = start;
        seen[start] = 1;
        while (head < tail) {
            uint32_t p = queue[head++];
            piece *pp = &m->pieces[p];
            for (int e = 0; e < 4; e++)
                for (int k = 0; k < pp->nlinks[e]; k++) {
                    const plink *l = &pp->link[e][k];
                    if (l->nonmanifold)
                        continue; /* no orientation agrees with two others */
                    int sign = edge_dir(e) * edge_dir(l->edge) * (l->reversed ? -1 : 1);
                    uint8_t want = sign < 0 ? pp->mirrored : !pp->mirrored;
                    if (!seen[l->piece]) {
                        seen[l->piece] = 1;
                        m->pieces[l->piece].mirrored = want;
                        queue[tail++] = l->piece;
                    }
                }
        }
    }
    m->mirrored = 0;
    for (uint32_t p = 0; p < m->npieces; p++)
        m->mirrored += m->pieces[p].mirrored;
    tsr_free(a, queue);
    tsr_free(a, seen);
    return TSR_OK;
}

/* ---- Bézier pieces of a patch set ------------------------------------------ */

/* Control point k (0..count-1) along edge e of a Bézier piece. */
static uint32_t edge_ctrl_index(const tsr_patch *b, int e, uint32_t k)
{
    uint32_t nu = (uint32_t)b->degree_u + 1, nv = (uint32_t)b->degree_v + 1;
    switch (e) {
    case 0: return k;
    case 1: return k * nu + (nu - 1);
    case 2: return (nv - 1) * nu + k;
    default: return k * nu;
    }
}

static uint32_t edge_ctrl_count(const tsr_patch *b, int e) { return (uint32_t)(e & 1 ? b->degree_v : b->degree_u) + 1; }

/* max and min for finite values, inlined (fmax and fmin are calls) */
static inline double dmax(double a, double b)
{
    return a > b ? a : b;
}
static inline double dmin(double a, double b)
{
    return a < b ? a : b;
}

static double dist3(const double *a, const double *b)
{
    double d0 = a[0] - b[0], d1 = a[1] - b[1], d2 = a[2] - b[2];
    return sqrt(d0 * d0 + d1 * d1 + d2 * d2);
}

/* Where the midpoint of an edge's ends lies along a direction no model is
 * aligned with (axis-aligned grids put hundreds of edges at one x): edges
 * whose ends agree within tol have keys within tol, so candidates are
 * looked for in a window of the keys sorted. */
static double edge_key(const double *a, const double *b)
{
    static const double d[3] = {0.7265173980555677, 0.5484317579318064, 0.41399888552313313}; /* unit */
    return 0.5 * (d[0] * (a[0] + b[0]) + d[1] * (a[1] + b[1]) + d[2] * (a[2] + b[2]));
}

typedef struct edge_rec {
    uint32_t piece;
    int edge;
    double key; /* edge_key of its ends */
} edge_rec;

static int cmp_edge_rec(const void *a, const void *b)
{
    double x = ((const edge_rec *)a)->key, y = ((const edge_rec *)b)->key;
    return x < y ? -1 : x > y;
}

/* The control row of edge e of piece p as homogeneous points (w x, w y,
 * w z, w), raised to degree deg (at least the row's own): a row of degree
 * d becomes one of degree d + 1 with Q_k = k/(d+1) P_(k-1) + (1 - k/(d+1))
 * P_k, the same curve. */
static void edge_row(const piece *p, int e, int deg, double h[][4])
{
    uint32_t n = edge_ctrl_count(&p->bez, e);
    for (uint32_t k = 0; k < n; k++) {
        uint32_t i = edge_ctrl_index(&p->bez, e, k);
        double w = p->bez.weights ? p->bez.weights[i] : 1;
        for (int c = 0; c < 3; c++)
            h[k][c] = w * p->bez.ctrl[3 * i + c];
        h[k][3] = w;
    }
    for (int d = (int)n - 1; d < deg; d++) {
        memcpy(h[d + 1], h[d], sizeof h[d]);
        for (int k = d; k >= 1; k--) {
            double a = (double)k / (d + 1);
            for (int c = 0; c < 4; c++)
                h[k][c] = a * h[k - 1][c] + (1 - a) * h[k][c];
        }
    }
}

/* Whether edge e of piece p and edge f of piece q coincide (the same
 * points, and weights up to a common factor, once the row of lower degree
 * is raised to the other's degree), and in which direction. */
static bool edges_match(const piece *p, int e, const piece *q, int f, double tol, bool *rev)
{
    int dp = (int)edge_ctrl_count(&p->bez, e) - 1, dq = (int)edge_ctrl_count(&q->bez, f) - 1;
    int deg = dp > dq ? dp : dq;
    /* the ends first (raising the degree keeps them) */
    const double *p0 = p->bez.ctrl + 3 * edge_ctrl_index(&p->bez, e, 0),
                 *p1 = p->bez.ctrl + 3 * edge_ctrl_index(&p->bez, e, (uint32_t)dp),
                 *q0 = q->bez.ctrl + 3 * edge_ctrl_index(&q->bez, f, 0),
                 *q1 = q->bez.ctrl + 3 * edge_ctrl_index(&q->bez, f, (uint32_t)dq);
    if (!(dist3(p0, q0) <= tol && dist3(p1, q1) <= tol) && !(dist3(p0, q1) <= tol && dist3(p1, q0) <= tol))
        return false;
    double hp[TSR_PATCH_MAX_DEGREE + 1][4], hq[TSR_PATCH_MAX_DEGREE + 1][4];
    edge_row(p, e, deg, hp);
    edge_row(q, f, deg, hq);
    for (int dir = 0; dir < 2; dir++) {
        bool ok = true;
        double ratio = 0;
        for (int k = 0; k <= deg && ok; k++) {
            const double *a = hp[k], *b = hq[dir ? deg - k : k];
            double pa[3], pb[3];
            for (int c = 0; c < 3; c++) {
                pa[c] = a[c] / a[3];
                pb[c] = b[c] / b[3];
            }
            ok = dist3(pa, pb) <= tol;
            double r = a[3] / b[3];
            if (k == 0)
                ratio = r;
            else if (ok)
                ok = fabs(r - ratio) <= 1e-9 * ratio;
        }
        if (ok) {
            *rev = dir == 1;
            return true;
        }
    }
    return false;
}

static bool edge_collapsed(const piece *p, int e, double tol)
{
    uint32_t n = edge_ctrl_count(&p->bez, e);
    const double *c0 = p->bez.ctrl + 3 * edge_ctrl_index(&p->bez, e, 0);
    for (uint32_t k = 1; k < n; k++)
        if (dist3(c0, p->bez.ctrl + 3 * edge_ctrl_index(&p->bez, e, k)) > tol)
            return false;
    return true;
}

static tsr_status link_set_edges(tsr_pmodel *m, double link_tol)
{
    double tol = link_tol > 0 ? link_tol : TSR_PMODEL_LINK_TOL * model_diag(m);
    m->link_tol = tol;
    const tsr_allocator *a = ma(m);
    /* collapsed edges first; they take no links */
    for (uint32_t p = 0; p < m->npieces; p++)
        for (int e = 0; e < 4; e++)
            if (edge_collapsed(&m->pieces[p], e, tol)) {
                m->pieces[p].collapsed |= (uint8_t)(1u << e);
                m->collapsed++;
            }
    /* candidate edges: on the border of their source, not collapsed */
    edge_rec *rec = tsr_alloc(a, (size_t)m->npieces * 4 * sizeof *rec);
    uint8_t *used = tsr_alloc(a, (size_t)m->npieces * 4);
    if (!rec || !used) {
        tsr_free(a, rec);
        tsr_free(a, used);
        return TSR_ERR_NOMEM;
    }
    uint32_t n = 0;
    for (uint32_t p = 0; p < m->npieces; p++) {
        const piece *pp = &m->pieces[p];
        for (int e = 0; e < 4; e++) {
            if (pp->nlinks[e] || (pp->collapsed >> e & 1))
                continue;
            const double *a0 = pp->bez.ctrl + 3 * edge_ctrl_index(&pp->bez, e, 0),
                         *a1 = pp->bez.ctrl + 3 * edge_ctrl_index(&pp->bez, e, edge_ctrl_count(&pp->bez, e) - 1);
            rec[n++] = (edge_rec){p, e, edge_key(a0, a1)};
        }
    }
    qsort(rec, n, sizeof *rec, cmp_edge_rec);
    memset(used, 0, (size_t)m->npieces * 4);
    for (uint32_t i = 0; i < n; i++) {
        /* an edge links when exactly one other edge matches it, or, three
         * patches sharing it (a fin on a plate), to both others when these
         * match each other */
        uint32_t found = UINT32_MAX, matches = 0, all[2];
        bool rev = false, revs[2];
        for (uint32_t j = i + 1; j < n && rec[j].key - rec[i].key <= tol; j++) {
            bool r;
            if (edges_match(&m->pieces[rec[i].piece], rec[i].edge, &m->pieces[rec[j].piece], rec[j].edge, tol, &r)) {
                if (matches < 2)
                    all[matches] = j, revs[matches] = r;
                matches++;
                found = j;
                rev = r;
            }
        }
        for (uint32_t j = i; j-- > 0 && rec[i].key - rec[j].key <= tol;) {
            bool r;
            if (edges_match(&m->pieces[rec[i].piece], rec[i].edge, &m->pieces[rec[j].piece], rec[j].edge, tol, &r)) {
                if (matches < 2)
                    all[matches] = j, revs[matches] = r;
                matches++;
            }
        }
        if (matches == 2 && all[0] > i && all[1] > i) {
            /* the first of three: links each pair of them once */
            uint32_t t[3] = {i, all[0], all[1]};
            bool r12;
            if (!edges_match(&m->pieces[rec[t[1]].piece], rec[t[1]].edge, &m->pieces[rec[t[2]].piece], rec[t[2]].edge,
                             tol, &r12))
                continue;
            bool ok = true;
            for (int k = 0; k < 3; k++)
                ok &= !used[4 * rec[t[k]].piece + rec[t[k]].edge] &&
                      m->pieces[rec[t[k]].piece].nlinks[rec[t[k]].edge] == 0;
            if (!ok || rec[t[0]].piece == rec[t[1]].piece || rec[t[0]].piece == rec[t[2]].piece ||
                rec[t[1]].piece == rec[t[2]].piece)
                continue;
            bool rr[3][3] = {{false, revs[0], revs[1]}, {revs[0], false, r12}, {revs[1], r12, false}};
            for (int x = 0; x < 3; x++) {
                used[4 * rec[t[x]].piece + rec[t[x]].edge] = 1;
                for (int y = 0; y < 3; y++) {
                    if (x == y)
                        continue;
                    piece *px = &m->pieces[rec[t[x]].piece];
                    int ex = rec[t[x]].edge;
                    bool rv = rr[x][y];
                    add_link(m, rec[t[x]].piece, ex, rec[t[y]].piece, rec[t[y]].edge, rv, 0, 2, rv ? 2 : 0, rv ? 0 : 2);
                    px->link[ex][px->nlinks[ex] - 1].nonmanifold = 1;
                }
            }
            continue;
        }
        if (matches != 1 || found == UINT32_MAX)
            continue;
        uint32_t p = rec[i].piece, q = rec[found].piece;
        int e = rec[i].edge, f = rec[found].edge;
        if (used[4 * p + e] || used[4 * q + f] || (p == q && e == f))
            continue;
        used[4 * p + e] = used[4 * q + f] = 1;
        add_link(m, p, e, q, f, rev, 0, 2, rev ? 2 : 0, rev ? 0 : 2);
        add_link(m, q, f, p, e, rev, 0, 2, rev ? 2 : 0, rev ? 0 : 2);
    }
    tsr_free(a, rec);
    tsr_free(a, used);
    return TSR_OK;
}

/* ---- breakpoints shared through patch edges ------------------------------- */

/* The breakpoints of one patch along one axis, ascending: its domain's
 * ends, its knots inside, and those its neighbours gave it. */
typedef struct brk {
    double *b;
    uint32_t n, cap;
} brk;

/* A whole edge of a patch: patch i, edge e (0 south v = v0, 1 east u =
 * u1, 2 north v = v1, 3 west u = u0), its parameter t in [0, 1] running
 * with u (south, north) or v (east, west) across the domain. */
typedef struct pedge {
    uint32_t patch;
    int edge;
    double key; /* edge_key of its ends */
    double end[2][3], mid[3]; /* points at t = 0, 1, 1/2 */
} pedge;

/* Two edges lying along one curve. Whole edges whose ends meet: ends bit
 * 0 forwards, bit 1 reversed; partial overlaps (ends 0): fractions ta[0]
 * < ta[1] of a's parameter are tb[0], tb[1] of b's, in proportion between
 * (once state is 1 or 2, whole pairs too; tb[0] > tb[1] when b runs the
 * other way). state 0 not yet compared, -1 not one curve; for whole
 * pairs 1 one curve forwards, 2 reversed (t on a is 1 - t on b); for
 * partial ones 1 one curve, either way (tb says which). */
typedef struct epair {
    uint32_t a, b; /* into the pedge list */
    uint8_t ends;
    int8_t state;
    double ta[2], tb[2];
} epair;

static void edge_at(const tsr_patch *p, const double dom[4], int e, double t, double pos[3])
{
    double u = e == 1 ? dom[1] : e == 3 ? dom[0] : dom[0] + t * (dom[1] - dom[0]);
    double v = e == 0 ? dom[2] : e == 2 ? dom[3] : dom[2] + t * (dom[3] - dom[2]);
    tsr_patch_eval(p, u, v, pos, NULL, NULL, NULL);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static int cmp_pedge(const void *a, const void *b)
{
    double x = ((const pedge *)a)->key, y = ((const pedge *)b)->key;
    return x < y ? -1 : x > y;
}

/* Breakpoint k of patch i's axis as a fraction of its domain. */
static double brk_frac(const brk *br, const double dom[4], int axis, uint32_t k)
{
    double lo = dom[2 * axis], hi = dom[2 * axis + 1];
    return k == 0 ? 0 : k + 1 == br->n ? 1 : (br->b[k] - lo) / (hi - lo);
}

/* Fraction t of edge a's parameter as a fraction of b's, through the
 * pair's proportion (to_b), or back (!to_b). */
static double pair_map(const epair *pr, double t, bool to_b)
{
    const double *f = to_b ? pr->ta : pr->tb, *g = to_b ? pr->tb : pr->ta;
    return g[0] + (t - f[0]) * (g[1] - g[0]) / (f[1] - f[0]);
}

/* Whether edges x and y are one curve over the pair's overlap with
 * proportional parameters (pr->ta, pr->tb set): within tol at every
 * breakpoint of either side inside it, at its ends, and at 7 points
 * inside every span between them. scratch holds both sides' breakpoints
 * and 2 more. */
static bool edges_coincide(const tsr_patch_set *set, const double *doms, const brk *brks, const pedge *x,
                           const pedge *y, const epair *pr, double tol, double *scratch)
{
    const tsr_patch *pa = &set->patches[x->patch], *pb = &set->patches[y->patch];
    const double *da = doms + 4 * x->patch, *db = doms + 4 * y->patch;
    const brk *ba = &brks[2 * x->patch + (x->edge & 1)], *bb = &brks[2 * y->patch + (y->edge & 1)];
    double lo = pr->ta[0], hi = pr->ta[1];
    uint32_t n = 0;
    scratch[n++] = lo;
    scratch[n++] = hi;
    for (uint32_t k = 0; k < ba->n; k++) {
        double t = brk_frac(ba, da, x->edge & 1, k);
        if (t > lo && t < hi)
            scratch[n++] = t;
    }
    for (uint32_t k = 0; k < bb->n; k++) {
        double t = pair_map(pr, brk_frac(bb, db, y->edge & 1, k), false);
        if (t > lo && t < hi)
            scratch[n++] = t;
    }
    qsort(scratch, n, sizeof *scratch, cmp_double);
    for (uint32_t k = 0; k + 1 < n; k++) {
        if (!(scratch[k + 1] > scratch[k]))
            continue;
        for (int m = 0; m < 8; m++) {
            double t = scratch[k] + (scratch[k + 1] - scratch[k]) * m / 8.0, P[3], Q[3];
            edge_at(pa, da, x->edge, t, P);
            edge_at(pb, db, y->edge, pair_map(pr, t, true), Q);
            if (!(dist3(P, Q) <= tol))
                return false;
        }
    }
    double P[3], Q[3];
    edge_at(pa, da, x->edge, hi, P);
    edge_at(pb, db, y->edge, pr->tb[1], Q);
    return dist3(P, Q) <= tol;
}

/* Inserts fraction t of the domain into br unless a breakpoint lies within
 * 1e-9 of the domain of it; returns whether it did (-1: out of memory). */
static int brk_insert(brk *br, const double dom[4], int axis, double t, const tsr_allocator *a)
{
    double lo = dom[2 * axis], hi = dom[2 * axis + 1], x = lo + t * (hi - lo), near = 1e-9 * (hi - lo);
    if (!(x - lo > near && hi - x > near))
        return 0;
    uint32_t k = 0;
    while (k < br->n && br->b[k] < x)
        k++;
    if ((k < br->n && br->b[k] - x <= near) || (k > 0 && x - br->b[k - 1] <= near))
        return 0;
    if (br->n == br->cap) {
        uint32_t nc = br->cap * 2;
        double *nb = tsr_realloc(a, br->b, (size_t)nc * sizeof *nb);
        if (!nb)
            return -1;
        br->b = nb;
        br->cap = nc;
    }
    memmove(br->b + k + 1, br->b + k, (size_t)(br->n - k) * sizeof *br->b);
    br->b[k] = x;
    br->n++;
    return 1;
}

/* Whether edges x and y have the same breakpoints (as fractions of their
 * domains; y's reversed when rev). */
static bool same_breaks(const double *doms, const brk *brks, const pedge *x, const pedge *y, bool rev)
{
    const brk *bx = &brks[2 * x->patch + (x->edge & 1)], *by = &brks[2 * y->patch + (y->edge & 1)];
    if (bx->n != by->n)
        return false;
    for (uint32_t k = 0; k < bx->n; k++) {
        double t = brk_frac(bx, doms + 4 * x->patch, x->edge & 1, k);
        double r = brk_frac(by, doms + 4 * y->patch, y->edge & 1, rev ? bx->n - 1 - k : k);
        if (!(fabs(t - (rev ? 1 - r : r)) <= 1e-9))
            return false;
    }
    return true;
}

/* Appends a pair; false when out of memory. */
static bool pair_push(epair **pairs, uint32_t *n, uint32_t *cap, epair p, const tsr_allocator *a)
{
    if (*n == *cap) {
        epair *q = tsr_realloc(a, *pairs, (size_t)*cap * 2 * sizeof *q);
        if (!q)
            return false;
        *pairs = q;
        *cap *= 2;
    }
    (*pairs)[(*n)++] = p;
    return true;
}

/* Partial overlaps: an edge's end lying on another edge's curve inside it
 * (one long edge against two shorter ones, a T-configuration; edges
 * staggered along one curve). */
#define EDGE_SAMPLES 4
typedef struct ecorr {
    uint32_t a, b; /* pedge indices, a < b */
    double ta, tb; /* one point: fraction ta of a is fraction tb of b */
} ecorr;

typedef struct eend {
    uint64_t cell;
    uint32_t edge;
    int k;
} eend;

static int cmp_eend(const void *x, const void *y)
{
    uint64_t a = ((const eend *)x)->cell, b = ((const eend *)y)->cell;
    return a < b ? -1 : a > b;
}

static int cmp_ecorr(const void *x, const void *y)
{
    const ecorr *a = x, *b = y;
    if (a->a != b->a)
        return a->a < b->a ? -1 : 1;
    if (a->b != b->b)
        return a->b < b->b ? -1 : 1;
    return a->ta < b->ta ? -1 : a->ta > b->ta;
}

/* The fraction of edge x nearest P, from its samples S (EDGE_SAMPLES + 1
 * points) refined by golden-section search on the true curve; *d its
 * distance. */
static double edge_project(const tsr_patch_set *set, const double *doms, const pedge *x, const double *S,
                           const double P[3], double *d)
{
    int best = 0;
    double bd = INFINITY;
    for (int k = 0; k < EDGE_SAMPLES; k++) {
        const double *A = S + 3 * k, *B = A + 3;
        double ab[3] = {B[0] - A[0], B[1] - A[1], B[2] - A[2]}, ap[3] = {P[0] - A[0], P[1] - A[1], P[2] - A[2]};
        double l2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2], f = 0;
        if (l2 > 0)
            f = dmin(1, dmax(0, (ab[0] * ap[0] + ab[1] * ap[1] + ab[2] * ap[2]) / l2));
        double Q[3] = {A[0] + f * ab[0], A[1] + f * ab[1], A[2] + f * ab[2]}, dq = dist3(P, Q);
        if (dq < bd) {
            bd = dq;
            best = k;
        }
    }
    const tsr_patch *p = &set->patches[x->patch];
    const double *dom = doms + 4 * x->patch, g = 0.6180339887498949;
    double lo = dmax(0, (best - 1.0) / EDGE_SAMPLES), hi = dmin(1, (best + 2.0) / EDGE_SAMPLES), Q[3];
    double c = hi - g * (hi - lo), e = lo + g * (hi - lo), fc, fe;
    edge_at(p, dom, x->edge, c, Q);
    fc = dist3(P, Q);
    edge_at(p, dom, x->edge, e, Q);
    fe = dist3(P, Q);
    for (int it = 0; it < 64; it++) {
        if (fc <= fe) {
            hi = e;
            e = c;
            fe = fc;
            c = hi - g * (hi - lo);
            edge_at(p, dom, x->edge, c, Q);
            fc = dist3(P, Q);
        } else {
            lo = c;
            c = e;
            fc = fe;
            e = lo + g * (hi - lo);
            edge_at(p, dom, x->edge, e, Q);
            fe = dist3(P, Q);
        }
    }
    double t = 0.5 * (lo + hi);
    edge_at(p, dom, x->edge, t, Q);
    *d = dist3(P, Q);
    return t;
}

/* The cell of a point in a grid of spacing h from org (21 bits an axis). */
static uint64_t end_cell(const double P[3], const double org[3], double h)
{
    uint64_t key = 0;
    for (int c = 0; c < 3; c++) {
        double f = floor((P[c] - org[c]) / h);
        uint64_t i = f < 0 ? 0 : f > 2097151 ? 2097151 : (uint64_t)f;
        key = key << 21 | i;
    }
    return key;
}

/* Appends a correspondence; false when out of memory. */
static bool corr_push(ecorr **co, uint32_t *n, uint32_t *cap, ecorr c, const tsr_allocator *a)
{
    if (*n == *cap) {
        ecorr *c2 = tsr_realloc(a, *co, (size_t)*cap * 2 * sizeof *c2);
        if (!c2)
            return false;
        *co = c2;
        *cap *= 2;
    }
    (*co)[(*n)++] = c;
    return true;
}

/* Finds the partial overlaps among the edges ed (not poles) and appends
 * them to pairs: pairs of edges where an end of one lies on the other
 * inside it (within tol), meeting at exactly two points (such ends, and
 * ends that coincide). Whether they are one curve between those points is
 * decided later (edges_coincide). Each edge's end is looked for in a grid
 * of cells of an edge's mean size, over the edge's box (the box
 * of EDGE_SAMPLES + 1 samples, padded by the longest step between them
 * and tol: the curve is taken to stray no farther from its samples). */
static tsr_status find_partial_pairs(const tsr_patch_set *set, const double *doms, const pedge *ed, uint32_t ne,
                                     double tol, const tsr_allocator *a, epair **pairs, uint32_t *npairs,
                                     uint32_t *cappairs)
{
    if (ne < 2)
        return TSR_OK;
    const uint32_t ns = EDGE_SAMPLES + 1;
    double *S = tsr_alloc(a, (size_t)ne * ns * 3 * sizeof *S), *box = tsr_alloc(a, (size_t)ne * 6 * sizeof *box);
    eend *ends = tsr_alloc(a, (size_t)ne * 2 * sizeof *ends);
    uint32_t nc = 0, capc = 16;
    ecorr *co = tsr_alloc(a, capc * sizeof *co);
    tsr_status st = S && box && ends && co ? TSR_OK : TSR_ERR_NOMEM;
    double org[3] = {INFINITY, INFINITY, INFINITY}, size = 0;
    for (uint32_t i = 0; i < ne && st == TSR_OK; i++) {
        double *s = S + (size_t)i * ns * 3, *b = box + 6 * i, seg = 0, ext = 0;
        for (uint32_t k = 0; k < ns; k++) {
            const double *known = k == 0            ? ed[i].end[0]
                                  : k == ns - 1     ? ed[i].end[1]
                                  : 2 * k == ns - 1 ? ed[i].mid
                                                    : NULL;
            if (known)
                memcpy(s + 3 * k, known, 3 * sizeof *s);
            else
                edge_at(&set->patches[ed[i].patch], doms + 4 * ed[i].patch, ed[i].edge, (double)k / EDGE_SAMPLES,
                        s + 3 * k);
            if (k)
                seg = dmax(seg, dist3(s + 3 * k, s + 3 * k - 3));
        }
        for (int c = 0; c < 3; c++) {
            b[c] = INFINITY;
            b[3 + c] = -INFINITY;
            for (uint32_t k = 0; k < ns; k++) {
                b[c] = dmin(b[c], s[3 * k + c]);
                b[3 + c] = dmax(b[3 + c], s[3 * k + c]);
            }
            b[c] -= seg + tol;
            b[3 + c] += seg + tol;
            org[c] = dmin(org[c], b[c]);
            ext = dmax(ext, b[3 + c] - b[c]);
        }
        size += ext;
    }
    double h = size / (ne ? ne : 1);
    if (!(h > 0) || !isfinite(h))
        h = 1;
    for (uint32_t i = 0; i < ne && st == TSR_OK; i++)
        for (int k = 0; k < 2; k++)
            ends[2 * i + (uint32_t)k] = (eend){end_cell(ed[i].end[k], org, h), i, k};
    if (st == TSR_OK)
        qsort(ends, (size_t)ne * 2, sizeof *ends, cmp_eend);
    for (uint32_t i = 0; i < ne && st == TSR_OK; i++) {
        const double *b = box + 6 * i;
        uint64_t c0 = end_cell(b, org, h), c1 = end_cell(b + 3, org, h);
        uint64_t lo[3], hi[3], cells = 1;
        for (int c = 0; c < 3; c++) {
            lo[c] = c0 >> (21 * (2 - c)) & 2097151;
            hi[c] = c1 >> (21 * (2 - c)) & 2097151;
            cells *= hi[c] - lo[c] + 1;
        }
        bool scan = cells > 4096; /* a long edge across a fine grid: every end */
        for (uint64_t x = lo[0]; x <= hi[0] && st == TSR_OK; x++)
            for (uint64_t y = lo[1]; y <= hi[1] && st == TSR_OK; y++)
                for (uint64_t z = lo[2]; z <= hi[2] && st == TSR_OK; z++) {
                    uint64_t key = x << 42 | y << 21 | z;
                    uint32_t l = 0, r = 2 * ne;
                    if (!scan)
                        while (l < r) {
                            uint32_t mid = l + (r - l) / 2;
                            if (ends[mid].cell < key)
                                l = mid + 1;
                            else
                                r = mid;
                        }
                    for (uint32_t q = l; q < 2 * ne && (scan || ends[q].cell == key) && st == TSR_OK; q++) {
                        uint32_t j = ends[q].edge;
                        int k = ends[q].k;
                        const double *P = ed[j].end[k];
                        double d;
                        if (j == i || P[0] < b[0] || P[0] > b[3] || P[1] < b[1] || P[1] > b[4] || P[2] < b[2] ||
                            P[2] > b[5] || dist3(P, ed[i].end[0]) <= tol || dist3(P, ed[i].end[1]) <= tol)
                            continue;
                        double t = edge_project(set, doms, &ed[i], S + (size_t)i * ns * 3, P, &d);
                        if (d <= tol &&
                            !corr_push(&co, &nc, &capc, i < j ? (ecorr){i, j, t, k} : (ecorr){j, i, k, t}, a))
                            st = TSR_ERR_NOMEM;
                    }
                    if (scan)
                        x = hi[0], y = hi[1], z = hi[2];
                }
    }
    if (st == TSR_OK)
        qsort(co, nc, sizeof *co, cmp_ecorr);
    for (uint32_t g = 0; g < nc && st == TSR_OK;) {
        uint32_t hgt = g;
        while (hgt < nc && co[hgt].a == co[g].a && co[hgt].b == co[g].b)
            hgt++;
        /* the pair's distinct points: ends inside the other edge, and ends
         * that coincide */
        double pt[4][2];
        uint32_t n = 0;
        const pedge *x = &ed[co[g].a], *y = &ed[co[g].b];
        for (int p = 0; p < 2; p++)
            for (int q = 0; q < 2; q++)
                if (n < 4 && dist3(x->end[p], y->end[q]) <= tol) {
                    pt[n][0] = p;
                    pt[n][1] = q;
                    n++;
                }
        for (uint32_t k = g; k < hgt && n < 4; k++) {
            bool dup = false;
            for (uint32_t q = 0; q < n && !dup; q++)
                dup = fabs(pt[q][0] - co[k].ta) <= 1e-7 && fabs(pt[q][1] - co[k].tb) <= 1e-7;
            if (!dup) {
                pt[n][0] = co[k].ta;
                pt[n][1] = co[k].tb;
                n++;
            }
        }
        if (n == 2 && pt[1][0] < pt[0][0]) {
            double t0 = pt[0][0], t1 = pt[0][1];
            pt[0][0] = pt[1][0];
            pt[0][1] = pt[1][1];
            pt[1][0] = t0;
            pt[1][1] = t1;
        }
        if (n == 2 && pt[1][0] - pt[0][0] > 1e-7 && fabs(pt[1][1] - pt[0][1]) > 1e-7 &&
            !pair_push(pairs, npairs, cappairs,
                       (epair){co[g].a, co[g].b, 0, 0, {pt[0][0], pt[1][0]}, {pt[0][1], pt[1][1]}}, a))
            st = TSR_ERR_NOMEM;
        g = hgt;
    }
    tsr_free(a, S);
    tsr_free(a, box);
    tsr_free(a, ends);
    tsr_free(a, co);
    return st;
}

/* The patches' edges (not poles) and the pairs of them that may share
 * their curve, whole or in part: what share_breaks works on, found once
 * for the several layouts of breakpoints tried. */
typedef struct edge_pairs {
    pedge *ed;
    epair *pairs;
    uint32_t ne, npairs;
    uint32_t nwhole; /* pairs[0, nwhole) whole, the rest partial */
} edge_pairs;

static void edge_pairs_free(edge_pairs *ep, const tsr_allocator *a)
{
    tsr_free(a, ep->ed);
    tsr_free(a, ep->pairs);
    memset(ep, 0, sizeof *ep);
}

static tsr_status find_edge_pairs(const tsr_patch_set *set, const double *doms, double tol, const tsr_allocator *a,
                                  edge_pairs *out)
{
    uint32_t np = set->num_patches, ne = 0, npairs = 0, cappairs = 16;
    pedge *ed = tsr_alloc(a, (size_t)np * 4 * sizeof *ed);
    epair *pairs = tsr_alloc(a, cappairs * sizeof *pairs);
    tsr_status st = ed && pairs ? TSR_OK : TSR_ERR_NOMEM;
    for (uint32_t i = 0; i < np && st == TSR_OK; i++)
        for (int e = 0; e < 4; e++) {
            pedge *x = &ed[ne];
            x->patch = i;
            x->edge = e;
            edge_at(&set->patches[i], doms + 4 * i, e, 0, x->end[0]);
            edge_at(&set->patches[i], doms + 4 * i, e, 1, x->end[1]);
            edge_at(&set->patches[i], doms + 4 * i, e, 0.5, x->mid);
            if (dist3(x->end[0], x->end[1]) <= tol && dist3(x->end[0], x->mid) <= tol)
                continue; /* collapsed to a point (a pole) */
            x->key = edge_key(x->end[0], x->end[1]);
            ne++;
        }
    if (st == TSR_OK)
        qsort(ed, ne, sizeof *ed, cmp_pedge);
    for (uint32_t i = 0; i < ne && st == TSR_OK; i++)
        for (uint32_t j = i + 1; j < ne && ed[j].key - ed[i].key <= tol; j++) {
            const pedge *x = &ed[i], *y = &ed[j];
            bool fwd = dist3(x->end[0], y->end[0]) <= tol && dist3(x->end[1], y->end[1]) <= tol;
            bool bwd = dist3(x->end[0], y->end[1]) <= tol && dist3(x->end[1], y->end[0]) <= tol;
            if ((fwd || bwd) &&
                !pair_push(&pairs, &npairs, &cappairs, (epair){i, j, (uint8_t)(fwd | bwd << 1), 0, {0, 1}, {0, 1}}, a))
                st = TSR_ERR_NOMEM;
        }
    uint32_t nwhole = npairs;
    if (st == TSR_OK)
        st = find_partial_pairs(set, doms, ed, ne, tol, a, &pairs, &npairs, &cappairs);
    if (st != TSR_OK) {
        tsr_free(a, ed);
        tsr_free(a, pairs);
        return st;
    }
    *out = (edge_pairs){ed, pairs, ne, npairs, nwhole};
    return TSR_OK;
}

/* The pieces a breakpoint more on edge e's axis adds: the spans of its
 * patch's other axis. */
static inline uint64_t other_spans(const brk *brks, const pedge *e)
{
    return brks[2 * e->patch + 1 - (e->edge & 1)].n - 1;
}

/* Gives every pair of ep whose edges coincide, whole or in part, each
 * other's breakpoints (an edge sharing part of its curve with another
 * also takes the ends of that part), until none gains one, `budget` were
 * added, or the pieces (*pieces, the sum over patches of their u spans
 * times their v spans, updated) reach `piece_budget`: a patch's pieces
 * are the product of its two axes' spans, so breakpoints alone do not
 * bound them (a patch whose edges lie along each other cut both of its
 * axes in turn: 2 KB of fuzzed OBJ made 8,460 pieces). Whole pairs are
 * compared as curves only once their breakpoints differ (most never do:
 * the teapot, a grid of Bézier patches). */
static tsr_status share_breaks(const tsr_patch_set *set, const double *doms, const edge_pairs *ep, brk *brks,
                               double tol, uint32_t budget, uint64_t piece_budget, const tsr_allocator *a,
                               uint32_t *added, uint64_t *pieces)
{
    *added = 0;
    const pedge *ed = ep->ed;
    uint32_t npairs = ep->npairs;
    epair *pairs = tsr_alloc(a, (npairs ? npairs : 1) * sizeof *pairs);
    tsr_status st = pairs ? TSR_OK : TSR_ERR_NOMEM;
    if (pairs && npairs)
        memcpy(pairs, ep->pairs, npairs * sizeof *pairs);
    /* hand breakpoints across until nothing changes (each side's list is
     * copied first: both sides may be one list, a patch's seam) */
    bool changed = true;
    double *copy = NULL;
    uint32_t capcopy = 0;
#define WITHIN (*added < budget && *pieces < piece_budget)
    while (changed && st == TSR_OK && WITHIN) {
        changed = false;
        for (uint32_t k = 0; k < npairs && st == TSR_OK && WITHIN; k++) {
            epair *pr = &pairs[k];
            const pedge *x = &ed[pr->a], *y = &ed[pr->b];
            if (pr->state < 0)
                continue;
            uint32_t need = brks[2 * x->patch + (x->edge & 1)].n + brks[2 * y->patch + (y->edge & 1)].n + 2;
            if (need > capcopy) {
                double *c = tsr_realloc(a, copy, (size_t)2 * need * sizeof *c);
                if (!c) {
                    st = TSR_ERR_NOMEM;
                    break;
                }
                copy = c;
                capcopy = 2 * need;
            }
            if (pr->state == 0 && pr->ends) {
                if ((!(pr->ends & 1) || same_breaks(doms, brks, x, y, false)) &&
                    (!(pr->ends & 2) || same_breaks(doms, brks, x, y, true)))
                    continue; /* nothing to hand across, yet */
                pr->state = -1;
                for (int r = 0; r < 2 && pr->state < 0; r++) {
                    pr->tb[0] = r;
                    pr->tb[1] = 1 - r;
                    if ((pr->ends >> r & 1) && edges_coincide(set, doms, brks, x, y, pr, tol, copy))
                        pr->state = (int8_t)(r + 1);
                }
                if (pr->state < 0)
                    continue;
            } else if (pr->state == 0) {
                pr->state = edges_coincide(set, doms, brks, x, y, pr, tol, copy) ? 1 : -1;
                if (pr->state < 0)
                    continue;
                /* each side is cut where the shared part ends */
                for (int q = 0; q < 2 && st == TSR_OK; q++) {
                    int r1 =
                        brk_insert(&brks[2 * x->patch + (x->edge & 1)], doms + 4 * x->patch, x->edge & 1, pr->ta[q], a);
                    int r2 =
                        brk_insert(&brks[2 * y->patch + (y->edge & 1)], doms + 4 * y->patch, y->edge & 1, pr->tb[q], a);
                    if (r1 < 0 || r2 < 0)
                        st = TSR_ERR_NOMEM;
                    *added += (uint32_t)(r1 > 0) + (uint32_t)(r2 > 0);
                    *pieces += (r1 > 0 ? other_spans(brks, x) : 0) + (r2 > 0 ? other_spans(brks, y) : 0);
                    changed |= r1 > 0 || r2 > 0;
                }
            }
            for (int side = 0; side < 2 && st == TSR_OK; side++) {
                const pedge *from = side ? y : x, *to = side ? x : y;
                const brk *bf = &brks[2 * from->patch + (from->edge & 1)];
                brk *bt = &brks[2 * to->patch + (to->edge & 1)];
                uint32_t n = bf->n;
                for (uint32_t q = 0; q < n; q++)
                    copy[q] = brk_frac(bf, doms + 4 * from->patch, from->edge & 1, q);
                for (uint32_t q = 1; q + 1 < n && WITHIN; q++) {
                    int r = brk_insert(bt, doms + 4 * to->patch, to->edge & 1, pair_map(pr, copy[q], side == 0), a);
                    if (r < 0) {
                        st = TSR_ERR_NOMEM;
                        break;
                    }
                    *added += (uint32_t)r;
                    *pieces += r > 0 ? other_spans(brks, to) : 0;
                    changed |= r > 0;
                }
            }
        }
    }
#undef WITHIN
    tsr_free(a, copy);
    tsr_free(a, pairs);
    return st;
}

static void bezier_second(int du, int dv, const double *P, const double *W, double M[3]);

/* The fewest quads a piece of tile size N can be drawn with when it needs
 * `need` (about (1 / h)^2 at spacing h): the tile sizes choose_tile tries
 * (N / 2 when even, N, N + 2, ..., 4 N - 2), each times the powers of 4
 * its levels add. */
static double tile_quads(double need, double N)
{
    int n = (int)N, half = n / 2, tmax = (int)TSR_TILE_MAX, top = 4 * n - 2 < tmax ? 4 * n - 2 : tmax;
    double best = INFINITY;
    for (int t = half >= (int)TSR_TILE_MIN && !(half & 1) ? half : n; t <= (top > n ? top : n); t = t < n ? n : t + 2) {
        double q = (double)t * t;
        for (int l = 0; q < need && l < 20; l++)
            q *= 4;
        best = dmin(best, q);
    }
    return best;
}

/* Quads a piece of second-derivative bounds M needs at max_error E, cut
 * into k along `axis` (tsr_pmodel_set_options.split_error). */
static double split_cost(const double M[3], double E, double N, int axis, double k)
{
    double m = axis == 0 ? M[0] / (k * k) + 2 * M[1] / k + M[2] : M[0] + 2 * M[1] / k + M[2] / (k * k);
    return k * tile_quads(m / (8 * E), N);
}

/* Second-derivative bounds M of patch p over [ua, ub] x [va, vb] (a
 * rectangle without a knot inside), its Bézier piece's; false when the
 * piece cannot be made or a bound is not finite. */
static bool span_second(const tsr_patch *p, double ua, double ub, double va, double vb, double M[3])
{
    double ctrl[3 * TSR_BEZIER_MAX_POINTS], w[TSR_BEZIER_MAX_POINTS];
    tsr_patch piece;
    if (tsr_patch_bezier_piece(p, ua, ub, va, vb, ctrl, w, &piece) != TSR_OK)
        return false;
    bezier_second(piece.degree_u, piece.degree_v, ctrl, p->weights ? w : NULL, M);
    return isfinite(M[0]) && isfinite(M[1]) && isfinite(M[2]);
}

/* Quads the k pieces of a span [u0, u1] x [v0, v1] cut along `axis` need
 * at max_error E by their own bounds, each piece's tiles counted whole (N
 * x N quads times a power of 4); INFINITY when a bound fails. */
static double cut_cost(const tsr_patch *p, double u0, double u1, double v0, double v1, int axis, uint32_t k,
                       double E, double N)
{
    double total = 0;
    for (uint32_t q = 0; q < k; q++) {
        double M[3];
        bool ok = axis == 0 ? span_second(p, u0 + (u1 - u0) * q / k, u0 + (u1 - u0) * (q + 1) / k, v0, v1, M)
                            : span_second(p, u0, u1, v0 + (v1 - v0) * q / k, v0 + (v1 - v0) * (q + 1) / k, M);
        if (!ok)
            return INFINITY;
        total += tile_quads((M[0] + 2 * M[1] + M[2]) / (8 * E), N);
    }
    return total;
}

/* Cuts the knot spans of patch p (breakpoints bu, bv) across their curved
 * direction where that saves half the quads at max_error E. */
static tsr_status split_patch(const tsr_patch *p, const double dom[4], brk *bu, brk *bv, double E, double N,
                              const tsr_allocator *a, uint32_t *added)
{
    uint32_t nu = bu->n - 1, nv = bv->n - 1;
    uint32_t *ku = tsr_alloc(a, (size_t)(nu + nv) * sizeof *ku), *kv = ku ? ku + nu : NULL;
    if (!ku)
        return TSR_ERR_NOMEM;
    for (uint32_t i = 0; i < nu + nv; i++)
        ku[i] = 1;
    for (uint32_t b = 0; b < nv; b++)
        for (uint32_t a2 = 0; a2 < nu; a2++) {
            double M[3];
            if (!span_second(p, bu->b[a2], bu->b[a2 + 1], bv->b[b], bv->b[b + 1], M))
                continue;
            double base = split_cost(M, E, N, 0, 1), best = base;
            uint32_t bk = 1;
            int baxis = 0;
            for (int axis = 0; axis < 2; axis++)
                for (uint32_t k = 2; k <= 64; k++) {
                    double c = split_cost(M, E, N, axis, k);
                    if (c < best) {
                        best = c;
                        bk = k;
                        baxis = axis;
                    }
                }
            /* the whole span's bounds overstate its pieces' (a rational
             * piece's quotient-rule terms shrink faster than 1 / k^2): from
             * the k chosen, fewer pieces while their own bounds say that
             * costs no more quads, tiles counted whole (cut_cost) */
            if (bk > 1) {
                double u0 = bu->b[a2], u1 = bu->b[a2 + 1], v0 = bv->b[b], v1 = bv->b[b + 1];
                double cur = cut_cost(p, u0, u1, v0, v1, baxis, bk, E, N);
                while (bk > 2) {
                    double c = cut_cost(p, u0, u1, v0, v1, baxis, bk - 1, E, N);
                    if (!(c <= cur))
                        break;
                    cur = c;
                    bk--;
                }
                best = cur;
            }
            if (bk > 1 && 2 * best <= base) {
                uint32_t *kk = baxis == 0 ? &ku[a2] : &kv[b];
                *kk = bk > *kk ? bk : *kk;
            }
        }
    tsr_status st = TSR_OK;
    for (int axis = 0; axis < 2 && st == TSR_OK; axis++) {
        brk *br = axis == 0 ? bu : bv;
        uint32_t n = axis == 0 ? nu : nv;
        const uint32_t *k = axis == 0 ? ku : kv;
        double lo = dom[2 * axis], hi = dom[2 * axis + 1];
        /* the cuts of every span first (inserting moves the spans) */
        uint32_t total = 0;
        for (uint32_t i = 0; i < n; i++)
            total += k[i] - 1;
        if (!total)
            continue;
        double *cuts = tsr_alloc(a, (size_t)total * sizeof *cuts);
        if (!cuts) {
            st = TSR_ERR_NOMEM;
            break;
        }
        uint32_t c = 0;
        for (uint32_t i = 0; i < n; i++)
            for (uint32_t m = 1; m < k[i]; m++)
                cuts[c++] = br->b[i] + (br->b[i + 1] - br->b[i]) * m / k[i];
        for (uint32_t i = 0; i < c && st == TSR_OK; i++) {
            int r = brk_insert(br, dom, axis, (cuts[i] - lo) / (hi - lo), a);
            if (r < 0)
                st = TSR_ERR_NOMEM;
            else
                *added += (uint32_t)r;
        }
        tsr_free(a, cuts);
    }
    tsr_free(a, ku);
    return st;
}

static void free_breaks(brk *brks, uint32_t np, const tsr_allocator *a)
{
    for (uint32_t i = 0; brks && i < 2 * np; i++)
        tsr_free(a, brks[i].b);
    tsr_free(a, brks);
}

/* The breakpoints of every patch (2 per patch, u then v): its knots, cuts
 * for split_error (when > 0; *split counts them), and those shared
 * through whole edges and partial overlaps (*shared). When sharing
 * reaches its budget with partial overlaps among the pairs (staggered
 * rows spread every row's breakpoints through all: rows^2 of them), it
 * starts again with whole edges only, as before they were linked, and
 * *dropped (may be NULL) counts the partial pairs so left unlinked. */
static tsr_status make_breaks_pairs(const tsr_patch_set *set, const double *doms, const uint8_t *trimmed,
                                    const edge_pairs *ep, double tol, double split_error, double N,
                                    const tsr_allocator *a, brk **out, uint32_t *split, uint32_t *shared, bool *full);

static tsr_status make_breaks(const tsr_patch_set *set, const double *doms, const uint8_t *trimmed,
                              const edge_pairs *ep, double tol, double split_error, double N, const tsr_allocator *a,
                              brk **out, uint32_t *split, uint32_t *shared, uint32_t *dropped)
{
    bool full = false;
    if (dropped)
        *dropped = 0;
    tsr_status st = make_breaks_pairs(set, doms, trimmed, ep, tol, split_error, N, a, out, split, shared, &full);
    if (st != TSR_OK || !full || ep->nwhole == ep->npairs)
        return st;
    free_breaks(*out, set->num_patches, a);
    *out = NULL;
    edge_pairs whole = *ep;
    whole.npairs = ep->nwhole;
    if (dropped)
        *dropped = ep->npairs - ep->nwhole;
    return make_breaks_pairs(set, doms, trimmed, &whole, tol, split_error, N, a, out, split, shared, &full);
}

static tsr_status make_breaks_pairs(const tsr_patch_set *set, const double *doms, const uint8_t *trimmed,
                                    const edge_pairs *ep, double tol, double split_error, double N,
                                    const tsr_allocator *a, brk **out, uint32_t *split, uint32_t *shared, bool *full)
{
    uint32_t np = set->num_patches, nsplit = 0;
    brk *brks = tsr_alloc(a, (size_t)np * 2 * sizeof *brks);
    if (!brks)
        return TSR_ERR_NOMEM;
    memset(brks, 0, (size_t)np * 2 * sizeof *brks);
    tsr_status st = TSR_OK;
    uint64_t nbreaks = 0, pieces = 0;
    for (uint32_t i = 0; i < np && st == TSR_OK; i++) {
        const tsr_patch *p = &set->patches[i];
        for (int axis = 0; axis < 2 && st == TSR_OK; axis++) {
            brk *br = &brks[2 * i + axis];
            uint32_t n = tsr_patch_spans(p, axis, NULL, 0) + 1;
            br->cap = n < 4 ? 4 : n;
            br->b = tsr_alloc(a, (size_t)br->cap * sizeof *br->b);
            if (!br->b) {
                st = TSR_ERR_NOMEM;
                break;
            }
            br->n = n;
            tsr_patch_spans(p, axis, br->b, n);
        }
        if (st == TSR_OK && split_error > 0 && !trimmed[i])
            st = split_patch(p, doms + 4 * i, &brks[2 * i], &brks[2 * i + 1], split_error, N, a, &nsplit);
        nbreaks += brks[2 * i].n + brks[2 * i + 1].n;
        if (st == TSR_OK)
            pieces += (uint64_t)(brks[2 * i].n - 1) * (brks[2 * i + 1].n - 1);
    }
    /* the budget of pieces holds only while partial pairs take part: they
     * have a fall-back (whole pairs alone); whole pairs of patches whose
     * knots differ multiply pieces by design (a grid of such patches, K x K:
     * about K^2 times), and stopping them part way would leave cracks */
    uint64_t budget = 4 * nbreaks + 1024, piece_budget = ep->npairs > ep->nwhole ? 4 * pieces + 1024 : UINT64_MAX;
    if (budget > (1u << 24))
        budget = 1u << 24;
    if (st == TSR_OK)
        st = share_breaks(set, doms, ep, brks, tol, (uint32_t)budget, piece_budget, a, shared, &pieces);
    *full = st == TSR_OK && (*shared >= budget || pieces >= piece_budget);
    if (st != TSR_OK) {
        free_breaks(brks, np, a);
        return st;
    }
    if (split)
        *split = nsplit;
    *out = brks;
    return TSR_OK;
}

/* The quads the pieces of a breakpoint layout need at max_error E by
 * split_cost's estimate. */
static double breaks_cost(const tsr_patch_set *set, const brk *brks, double E, double N)
{
    double total = 0;
    for (uint32_t i = 0; i < set->num_patches; i++) {
        const tsr_patch *p = &set->patches[i];
        const brk *bu = &brks[2 * i], *bv = &brks[2 * i + 1];
        for (uint32_t b = 0; b + 1 < bv->n; b++)
            for (uint32_t a2 = 0; a2 + 1 < bu->n; a2++) {
                double M[3];
                double c = span_second(p, bu->b[a2], bu->b[a2 + 1], bv->b[b], bv->b[b + 1], M)
                               ? split_cost(M, E, N, 0, 1)
                               : 0;
                total += isfinite(c) ? c : 0;
            }
    }
    return total;
}

/* Whether patch i's trim loops trim nothing (*nothing): one outer loop
 * and no hole, the loop around the domain's centre and nowhere farther
 * into the domain than TSR_PMODEL_VOID_TRIM of its sides (CAD files trim
 * faces by their whole border; such a patch is meshed as untrimmed, cut
 * and linked as the others). A coarse sampling first: a loop that
 * reaches deeper than its tolerance is no such loop; then one fine enough
 * that the curve's depth is within the hair. */
static tsr_status trims_nothing(const tsr_patch_set *set, uint32_t i, const double dom[4], const tsr_allocator *a,
                                bool *nothing)
{
    *nothing = false;
    uint32_t l0 = set->first_loop[i];
    if (set->first_loop[i + 1] != l0 + 1 || set->loops[l0].hole)
        return TSR_OK;
    double side = fmin(dom[1] - dom[0], dom[3] - dom[2]);
    const double coarse = 1e-3, fine = 0.25 * TSR_PMODEL_VOID_TRIM;
    tsr_trim_loop_info info;
    tsr_status st = tsr_trim_loop_check(set, l0, coarse * side, a, &info);
    if (st != TSR_OK || !info.encloses_centre || info.points < 3 || !(info.depth <= coarse + TSR_PMODEL_VOID_TRIM))
        return st == TSR_ERR_NOMEM ? st : TSR_OK;
    if ((st = tsr_trim_loop_check(set, l0, fine * side, a, &info)) != TSR_OK)
        return st == TSR_ERR_NOMEM ? st : TSR_OK;
    *nothing = info.encloses_centre && info.points >= 3 && info.depth <= TSR_PMODEL_VOID_TRIM - fine;
    return TSR_OK;
}

tsr_status tsr_pmodel_from_set(const tsr_patch_set *set, const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err)
{
    return tsr_pmodel_from_set_tol(set, 0, alloc, out, err);
}

tsr_status tsr_pmodel_from_set_tol(const tsr_patch_set *set, double link_tol, const tsr_allocator *alloc,
                                   tsr_pmodel **out, tsr_error *err)
{
    tsr_pmodel_set_options o = {link_tol, 0, 0};
    return tsr_pmodel_from_set_opts(set, &o, alloc, out, err);
}

tsr_status tsr_pmodel_from_set_opts(const tsr_patch_set *set, const tsr_pmodel_set_options *opt,
                                    const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err)
{
    double link_tol = opt ? opt->link_tol : 0, split_error = opt ? opt->split_error : 0;
    uint32_t tile = opt && opt->split_tile ? opt->split_tile : 4;
    /* the smallest tile a small tree of an untrimmed piece may take
     * (choose_tile's half tiles): the cuts are planned for it */
    double split_tile = tile / 2 >= TSR_TILE_MIN && !((tile / 2) & 1) ? tile / 2 : tile;
    if (!(link_tol > 0) || !isfinite(link_tol))
        link_tol = 0;
    if (!(split_error > 0) || !isfinite(split_error))
        split_error = 0;
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "patch model: no output");
    *out = NULL;
    if (!set)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "patch model: no patch set");
    if (set->num_patches == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "patch model: the set has no patch");
    tsr_pmodel *m = model_new(alloc);
    if (!m)
        return tsr_error_set(err, TSR_ERR_NOMEM, "patch model: out of memory");
    m->set = set;
    const tsr_allocator *a = ma(m);
    uint32_t np = set->num_patches;
    double *doms = tsr_alloc(a, (size_t)np * 4 * sizeof *doms);
    brk *brks = NULL;
    tsr_status st = doms ? TSR_OK : TSR_ERR_NOMEM;
    /* the patches' domains and the box of all control points */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t i = 0; i < np && st == TSR_OK; i++) {
        const tsr_patch *p = &set->patches[i];
        uint32_t c = 0;
        double plo[3], phi[3];
        if (tsr_patch_to_bezier(p, NULL, 0, NULL, NULL, &c) != TSR_OK || tsr_patch_bounds(p, plo, phi) != TSR_OK) {
            tsr_free(a, doms);
            tsr_pmodel_destroy(m);
            return tsr_error_set(err, TSR_ERR_ARGUMENT, "patch model: patch %u is invalid", i);
        }
        box_add(lo, hi, plo);
        box_add(lo, hi, phi);
        tsr_patch_domain(p, doms + 4 * i);
    }
    /* which patches their loops trim (a CAD file's loop along a face's
     * whole border trims nothing) */
    uint8_t *trimmed = st == TSR_OK ? tsr_alloc(a, np) : NULL;
    if (st == TSR_OK && !trimmed)
        st = TSR_ERR_NOMEM;
    for (uint32_t i = 0; i < np && st == TSR_OK; i++) {
        bool nothing = false;
        trimmed[i] = set->first_loop && set->first_loop[i + 1] > set->first_loop[i];
        if (trimmed[i] && (st = trims_nothing(set, i, doms + 4 * i, a, &nothing)) == TSR_OK && nothing) {
            trimmed[i] = 0;
            m->void_loops++;
        }
    }
    /* the breakpoints: knots, those of neighbours sharing an edge, and, for
     * split_error, cuts across curves where the whole model's estimate
     * says they save quads (a neighbour curved the other way that takes
     * the cuts may cost more than they save) */
    if (st == TSR_OK) {
        double diag = sqrt((hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]) +
                           (hi[2] - lo[2]) * (hi[2] - lo[2]));
        double tol = link_tol > 0 ? link_tol : TSR_PMODEL_LINK_TOL * diag;
        edge_pairs ep = {0};
        st = find_edge_pairs(set, doms, tol, a, &ep);
        if (st == TSR_OK)
            st = make_breaks(set, doms, trimmed, &ep, tol, 0, split_tile, a, &brks, NULL, &m->conform_breaks,
                             &m->partial_unlinked);
        if (st == TSR_OK && split_error > 0) {
            brk *cut = NULL;
            uint32_t split = 0, shared = 0;
            uint32_t dropped = 0;
            st = make_breaks(set, doms, trimmed, &ep, tol, split_error, split_tile, a, &cut, &split, &shared, &dropped);
            /* trimmed patches are triangulated in (u, v) from their pieces'
             * lattice points; cuts make those far from evenly spread */
            bool trims_cut = false;
            for (uint32_t i = 0; st == TSR_OK && split && i < np && !trims_cut; i++)
                trims_cut = trimmed[i] && (cut[2 * i].n != brks[2 * i].n || cut[2 * i + 1].n != brks[2 * i + 1].n);
            if (st == TSR_OK && split && !trims_cut &&
                breaks_cost(set, cut, split_error, split_tile) < 0.9 * breaks_cost(set, brks, split_error, split_tile)) {
                free_breaks(brks, np, a);
                brks = cut;
                m->split_breaks = split;
                m->conform_breaks = shared;
                m->partial_unlinked = dropped;
            } else {
                free_breaks(cut, np, a);
            }
        }
        edge_pairs_free(&ep, a);
    }
    /* count pieces and values */
    uint64_t npieces = 0, nvalues = 0;
    for (uint32_t i = 0; i < np && st == TSR_OK; i++) {
        uint64_t per = (uint64_t)(set->patches[i].degree_u + 1) * (uint64_t)(set->patches[i].degree_v + 1);
        uint64_t c = (uint64_t)(brks[2 * i].n - 1) * (brks[2 * i + 1].n - 1);
        npieces += c;
        nvalues += c * per * 4;
    }
    if (st == TSR_OK && npieces >= (1u << 24)) {
        free_breaks(brks, np, a);
        tsr_free(a, doms);
        tsr_free(a, trimmed);
        tsr_pmodel_destroy(m);
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "patch model: %llu Bézier pieces, more than 2^24",
                             (unsigned long long)npieces);
    }
    if (st == TSR_OK) {
        m->npieces = (uint32_t)npieces;
        m->nsources = np;
        m->pieces = tsr_alloc(a, (size_t)npieces * sizeof *m->pieces);
        m->sources = tsr_alloc(a, (size_t)m->nsources * sizeof *m->sources);
        m->values = tsr_alloc(a, (size_t)nvalues * sizeof *m->values);
        if (!m->pieces || !m->sources || !m->values)
            st = TSR_ERR_NOMEM;
    }
    if (st == TSR_OK)
        memset(m->pieces, 0, (size_t)npieces * sizeof *m->pieces);
    double *v = m->values;
    uint32_t next = 0;
    for (uint32_t i = 0; i < np && st == TSR_OK; i++) {
        const tsr_patch *p = &set->patches[i];
        const brk *bu = &brks[2 * i], *bv = &brks[2 * i + 1];
        uint32_t per = (uint32_t)(p->degree_u + 1) * (uint32_t)(p->degree_v + 1);
        psource *s = &m->sources[i];
        memset(s, 0, sizeof *s);
        s->patch = i;
        memcpy(s->domain, doms + 4 * i, sizeof s->domain);
        s->first_piece = next;
        s->pu = bu->n - 1;
        s->pv = bv->n - 1;
        s->trimmed = trimmed[i];
        m->trimmed += s->trimmed;
        for (uint32_t b = 0; b < s->pv && st == TSR_OK; b++)
            for (uint32_t a2 = 0; a2 < s->pu; a2++) {
                piece *pc = &m->pieces[next + b * s->pu + a2];
                double *ctrl = v, *w = p->weights ? v + 3 * (size_t)per : NULL;
                v += (size_t)per * (p->weights ? 4 : 3);
                if (tsr_patch_bezier_piece(p, bu->b[a2], bu->b[a2 + 1], bv->b[b], bv->b[b + 1], ctrl, w, &pc->bez) !=
                    TSR_OK) {
                    st = TSR_ERR_ARGUMENT;
                    break;
                }
                pc->source = i;
                pc->kind = KIND_BEZIER;
                tsr_patch_domain(&pc->bez, pc->rect);
                pc->bez.u0 = pc->bez.v0 = 0;
                pc->bez.u1 = pc->bez.v1 = 1;
                for (int q = 0; q < 3; q++) {
                    pc->lo[q] = INFINITY;
                    pc->hi[q] = -INFINITY;
                }
                for (uint32_t j = 0; j < per; j++)
                    box_add(pc->lo, pc->hi, pc->bez.ctrl + 3 * j);
                box_add(m->lo, m->hi, pc->lo);
                box_add(m->lo, m->hi, pc->hi);
            }
        /* links between the pieces of one patch */
        for (uint32_t b = 0; b < s->pv; b++)
            for (uint32_t a2 = 0; a2 < s->pu; a2++) {
                uint32_t k = next + b * s->pu + a2;
                if (a2 + 1 < s->pu) {
                    add_link(m, k, 1, k + 1, 3, false, 0, 2, 0, 2);
                    add_link(m, k + 1, 3, k, 1, false, 0, 2, 0, 2);
                }
                if (b + 1 < s->pv) {
                    add_link(m, k, 2, k + s->pu, 0, false, 0, 2, 0, 2);
                    add_link(m, k + s->pu, 0, k, 2, false, 0, 2, 0, 2);
                }
            }
        next += s->pu * s->pv;
    }
    free_breaks(brks, np, a);
    tsr_free(a, doms);
    tsr_free(a, trimmed);
    if (st == TSR_OK)
        st = link_set_edges(m, link_tol);
    if (st == TSR_OK)
        st = orient(m);
    if (st != TSR_OK) {
        tsr_pmodel_destroy(m);
        return st == TSR_ERR_NOMEM ? tsr_error_set(err, st, "patch model: out of memory")
                                   : tsr_error_set(err, st, "patch model: a patch could not be cut into pieces");
    }
    *out = m;
    return TSR_OK;
}

/* ---- subdivision surfaces --------------------------------------------------- */

static int half_of(double x) { return x <= 0.25 ? 0 : x <= 0.75 ? 1 : 2; }

/* Whether the limit of patch (face, sub) has area: |du x dv| beyond 1e-10
 * of the squared diagonal of the face's box plus 1e-20 of the model's
 * (diag2; the face's box may be a point) somewhere on a 7 x 7 grid inside
 * the patch (the centre first, where a patch with area nearly always
 * shows it, so most patches cost one evaluation). A cage face whose
 * vertices repeat so that its limit is a curve (67 67 68 68, or 81 81 81
 * 82 along a non-manifold edge) or a point (110 110 110 110) has du x dv
 * zero up to rounding everywhere; a patch with one collapsed edge, or a
 * real sliver, has it far beyond the threshold inside. */
static bool subd_patch_has_area(const tsr_subd *subd, uint32_t face, uint32_t sub, double diag2)
{
    double lo[3], hi[3];
    if (tsr_subd_face_bounds(subd, face, sub, lo, hi) != TSR_OK)
        return true;
    double l2 = 0;
    for (int c = 0; c < 3; c++)
        l2 += (hi[c] - lo[c]) * (hi[c] - lo[c]);
    double tol = 1e-10 * l2 + 1e-20 * diag2;
    for (int k = -1; k < 49; k++) {
        if (k == 24)
            continue; /* the centre, done first */
        int kk = k < 0 ? 24 : k;
        double uv[2] = {(kk % 7 + 1) / 8.0, (kk / 7 + 1) / 8.0}, pos[3], du[3], dv[3];
        if (tsr_subd_eval(subd, face, sub, uv, 1, pos, du, dv) != TSR_OK)
            return true;
        double n[3] = {du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2], du[0] * dv[1] - du[1] * dv[0]};
        if (!(sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]) <= tol))
            return true;
    }
    return false;
}

tsr_status tsr_pmodel_from_subd(const tsr_subd *subd, const tsr_allocator *alloc, tsr_pmodel **out, tsr_error *err)
{
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "patch model: no output");
    *out = NULL;
    if (!subd)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "patch model: no subdivision surface");
    uint32_t nf = tsr_subd_face_count(subd);
    uint64_t all = 0;
    for (uint32_t f = 0; f < nf; f++)
        if (tsr_subd_face_has_limit(subd, f))
            all += tsr_subd_face_patches(subd, f);
    if (all == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "patch model: no face has a limit surface");
    if (all >= (1u << 24))
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "patch model: %llu patches, more than 2^24",
                             (unsigned long long)all);
    tsr_pmodel *m = model_new(alloc);
    if (!m)
        return tsr_error_set(err, TSR_ERR_NOMEM, "patch model: out of memory");
    const tsr_allocator *a = ma(m);
    m->subd = subd;
    /* piece_of[first[f] + s]: the piece of patch (f, s), UINT32_MAX for a
     * patch whose limit has no area (a curve or a point: nothing a
     * triangle could cover without zero area), which gets none */
    uint32_t *first = tsr_alloc(a, ((size_t)nf + 1) * sizeof *first);
    uint32_t *piece_of = tsr_alloc(a, (size_t)all * sizeof *piece_of);
    if (!first || !piece_of) {
        tsr_free(a, first);
        tsr_free(a, piece_of);
        tsr_pmodel_destroy(m);
        return tsr_error_set(err, TSR_ERR_NOMEM, "patch model: out of memory");
    }
    double blo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, bhi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, diag2 = 0;
    for (uint32_t f = 0; f < nf; f++) {
        double lo[3], hi[3];
        if (tsr_subd_face_has_limit(subd, f) && tsr_subd_face_bounds(subd, f, 0, lo, hi) == TSR_OK) {
            box_add(blo, bhi, lo);
            box_add(blo, bhi, hi);
        }
    }
    for (int c = 0; c < 3; c++)
        diag2 += bhi[c] >= blo[c] ? (bhi[c] - blo[c]) * (bhi[c] - blo[c]) : 0;
    uint32_t n = 0, slot = 0;
    for (uint32_t f = 0; f < nf; f++) {
        first[f] = slot;
        if (!tsr_subd_face_has_limit(subd, f))
            continue;
        uint32_t np = tsr_subd_face_patches(subd, f);
        for (uint32_t s = 0; s < np; s++, slot++) {
            piece_of[slot] = subd_patch_has_area(subd, f, s, diag2) ? n++ : UINT32_MAX;
            m->flat += piece_of[slot] == UINT32_MAX;
        }
    }
    first[nf] = slot;
    if (n == 0) {
        tsr_free(a, first);
        tsr_free(a, piece_of);
        tsr_pmodel_destroy(m);
        return tsr_error_set(err, TSR_ERR_EMPTY, "patch model: no face has a limit surface with area");
    }
    m->npieces = m->nsources = n;
    m->pieces = tsr_alloc(a, (size_t)n * sizeof *m->pieces);
    m->sources = tsr_alloc(a, (size_t)n * sizeof *m->sources);
    if (!m->pieces || !m->sources) {
        tsr_free(a, first);
        tsr_free(a, piece_of);
        tsr_pmodel_destroy(m);
        return tsr_error_set(err, TSR_ERR_NOMEM, "patch model: out of memory");
    }
    memset(m->pieces, 0, (size_t)n * sizeof *m->pieces);
    uint32_t k = 0;
    for (uint32_t f = 0; f < nf; f++) {
        if (!tsr_subd_face_has_limit(subd, f))
            continue;
        uint32_t np = tsr_subd_face_patches(subd, f);
        for (uint32_t s = 0; s < np; s++) {
            if (piece_of[first[f] + s] == UINT32_MAX)
                continue;
            piece *pc = &m->pieces[k];
            pc->source = k;
            pc->kind = KIND_SUBD;
            pc->face = f;
            pc->sub = s;
            pc->rect[1] = pc->rect[3] = 1;
            pc->levels = np != 1; /* marks N-gon sub-patches (one level less deep) */
            tsr_subd_face_bounds(subd, f, s, pc->lo, pc->hi);
            box_add(m->lo, m->hi, pc->lo);
            box_add(m->lo, m->hi, pc->hi);
            psource *src = &m->sources[k];
            memset(src, 0, sizeof *src);
            src->patch = f;
            src->sub = s;
            src->domain[1] = src->domain[3] = 1;
            src->first_piece = k;
            src->pu = src->pv = 1;
            k++;
        }
    }
    /* collapsed edges (a cage face with a repeated vertex): the limit along
     * the patch edge is one point, as a Bézier edge whose control points
     * coincide; sampled at 9 points, within 1e-9 of the diagonal. Only a
     * piece with one such edge (a triangle in space, like the teapot's
     * lid) gets it (one with more, like a face 1 1 2 2, has no area and
     * no piece) */
    double ctol = 1e-9 * model_diag(m);
    for (uint32_t p = 0; p < m->npieces; p++) {
        piece *pc = &m->pieces[p];
        uint8_t mask = 0;
        for (int e = 0; e < 4; e++) {
            double uv[18], pos[27];
            for (int i = 0; i < 9; i++) {
                double t = i / 8.0;
                uv[2 * i] = e == 0 ? t : e == 1 ? 1 : e == 2 ? 1 - t : 0;
                uv[2 * i + 1] = e == 0 ? 0 : e == 1 ? t : e == 2 ? 1 : 1 - t;
            }
            if (tsr_subd_eval(subd, pc->face, pc->sub, uv, 9, pos, NULL, NULL) != TSR_OK)
                continue;
            bool one = true;
            for (int i = 1; i < 9 && one; i++)
                one = dist3(pos, pos + 3 * i) <= ctol;
            mask |= (uint8_t)(one << e);
        }
        if (mask && !(mask & (mask - 1))) {
            pc->collapsed = mask;
            m->collapsed++;
        }
    }
    for (uint32_t p = 0; p < m->npieces; p++) {
        piece *pc = &m->pieces[p];
        for (int e = 0; e < 4; e++) {
            if (pc->collapsed >> e & 1)
                continue; /* a collapsed edge takes no links */
            tsr_subd_link l[2];
            uint32_t c = tsr_subd_patch_neighbours(subd, pc->face, pc->sub, (uint32_t)e, l);
            for (uint32_t i = 0; i < c; i++) {
                if (!tsr_subd_face_has_limit(subd, l[i].face) || piece_of[first[l[i].face] + l[i].sub] == UINT32_MAX)
                    continue;
                add_link(m, p, e, piece_of[first[l[i].face] + l[i].sub], (int)l[i].edge, l[i].reversed,
                         half_of(l[i].t0), half_of(l[i].t1), half_of(l[i].s0), half_of(l[i].s1));
            }
        }
    }
    tsr_free(a, first);
    tsr_free(a, piece_of);
    tsr_status st = orient(m);
    if (st != TSR_OK) {
        tsr_pmodel_destroy(m);
        return tsr_error_set(err, st, "patch model: out of memory");
    }
    *out = m;
    return TSR_OK;
}

/* ---- queries ------------------------------------------------------------------ */

void tsr_pmodel_get_info(const tsr_pmodel *m, tsr_pmodel_info *info)
{
    memset(info, 0, sizeof *info);
    if (!m)
        return;
    info->sources = m->nsources;
    info->pieces = m->npieces;
    info->links = m->links;
    info->collapsed_edges = m->collapsed;
    info->mirrored = m->mirrored;
    info->trimmed_sources = m->trimmed;
    info->void_loops = m->void_loops;
    info->flat_patches = m->flat;
    info->conform_breaks = m->conform_breaks;
    info->partial_unlinked = m->partial_unlinked;
    info->split_breaks = m->split_breaks;
    memcpy(info->lo, m->lo, sizeof info->lo);
    memcpy(info->hi, m->hi, sizeof info->hi);
    info->own_alloc = m->alloc.realloc != NULL || (m->subd && tsr_subd_has_allocator(m->subd));
}

bool tsr_pmodel_source_info(const tsr_pmodel *m, uint32_t src, tsr_psource_info *info)
{
    if (!m || !info || src >= m->nsources)
        return false;
    const psource *s = &m->sources[src];
    info->patch = s->patch;
    info->sub = s->sub;
    memcpy(info->domain, s->domain, sizeof info->domain);
    info->first_piece = s->first_piece;
    info->pieces_u = s->pu;
    info->pieces_v = s->pv;
    info->trimmed = s->trimmed;
    info->mirrored = m->pieces[s->first_piece].mirrored != 0;
    return true;
}

static tsr_status subd_point(const tsr_subd *s, uint32_t face, uint32_t sub, double u, double v, double pos[3],
                             double normal[3])
{
    double uv[2] = {u, v}, du[3], dv[3];
    tsr_status st = tsr_subd_eval(s, face, sub, uv, 1, pos, normal ? du : NULL, normal ? dv : NULL);
    if (st != TSR_OK || !normal)
        return st;
    double n[3] = {du[1] * dv[2] - du[2] * dv[1], du[2] * dv[0] - du[0] * dv[2], du[0] * dv[1] - du[1] * dv[0]};
    double ln = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]), lu = sqrt(du[0] * du[0] + du[1] * du[1] + du[2] * du[2]),
           lv = sqrt(dv[0] * dv[0] + dv[1] * dv[1] + dv[2] * dv[2]);
    if (ln > 1e-10 * lu * lv && ln > 0) {
        for (int c = 0; c < 3; c++)
            normal[c] = n[c] / ln;
        return TSR_OK;
    }
    if (tsr_subd_normal(s, face, sub, uv, normal) != TSR_OK) {
        normal[0] = normal[1] = 0;
        normal[2] = 1;
    }
    return TSR_OK;
}

tsr_status tsr_pmodel_eval(const tsr_pmodel *m, uint32_t src, double u, double v, double pos[3], double normal[3])
{
    if (!m || src >= m->nsources || !pos)
        return TSR_ERR_ARGUMENT;
    const psource *s = &m->sources[src];
    tsr_status st;
    if (m->set)
        st = tsr_patch_eval(&m->set->patches[s->patch], u, v, pos, NULL, NULL, normal);
    else
        st = subd_point(m->subd, s->patch, s->sub, u, v, pos, normal);
    if (st == TSR_OK && normal && m->pieces[s->first_piece].mirrored)
        for (int c = 0; c < 3; c++)
            normal[c] = -normal[c];
    return st;
}

tsr_status tsr_pmodel_eval_points(const tsr_pmodel *m, uint32_t src, const double *uv, uint32_t count, double *pos)
{
    if (!m || src >= m->nsources || (count && (!uv || !pos)))
        return TSR_ERR_ARGUMENT;
    const psource *s = &m->sources[src];
    if (!m->set)
        return tsr_subd_eval(m->subd, s->patch, s->sub, uv, count, pos, NULL, NULL);
    for (uint32_t k = 0; k < count; k++) {
        tsr_status st = tsr_patch_eval(&m->set->patches[s->patch], uv[2 * (size_t)k], uv[2 * (size_t)k + 1],
                                       pos + 3 * (size_t)k, NULL, NULL, NULL);
        if (st != TSR_OK)
            return st;
    }
    return TSR_OK;
}

uint32_t tsr_pmodel_source_kinks(const tsr_pmodel *m, uint32_t src, int axis, double *out, uint32_t cap)
{
    if (!m || !m->set || src >= m->nsources || axis < 0 || axis > 1)
        return 0;
    const psource *s = &m->sources[src];
    const tsr_patch *p = &m->set->patches[s->patch];
    if (p->kind == TSR_PATCH_BEZIER)
        return 0;
    const double *k = axis ? p->knots_v : p->knots_u;
    uint32_t deg = (uint32_t)(axis ? p->degree_v : p->degree_u), cnt = (axis ? p->count_v : p->count_u) + deg + 1,
             n = 0;
    double lo = s->domain[2 * axis], hi = s->domain[2 * axis + 1];
    for (uint32_t i = 0, j; i < cnt; i = j) {
        for (j = i + 1; j < cnt && k[j] == k[i];)
            j++;
        if (j - i >= deg && k[i] > lo && k[i] < hi) {
            if (n < cap)
                out[n] = k[i];
            n++;
        }
    }
    return n;
}

/* ---- error bounds --------------------------------------------------------- */

/* Linear interpolation on a tile's triangles, from bounds a, b, c of
 * |D^2 S[v, v]|'s three terms at the tile's spacing h (a = h^2 M_ss,
 * b = h^2 M_st, c = h^2 M_tt, M bounds of |S_ss|, |S_st|, |S_tt|). The
 * error at x of a triangle with vertices x_i is -1/2 sum l_i D^2 S(xi_i)
 * [v_i, v_i], v_i = x_i - x, so it is within 1/2 (a V_s + 2 b sqrt(V_s
 * V_t) + c V_t) with V the barycentric variances of the v_i's components
 * (in units of h^2). Interior triangles (legs h): V_s, V_t <= 1/4, both at
 * the hypotenuse midpoint: (a + 2b + c) / 8. A stitched triangle (base 2h
 * on the tile edge, apex h above its middle, the only shape stitching
 * makes): on the apex column, V_s = 1 - tau, V_t = tau (1 - tau) at
 * height tau h, and the maximum over tau is bounded by that of (1 - tau)
 * (a + c tau) plus 2b max (1 - tau) sqrt(tau) = 2b * 2 / (3 sqrt 3). */
static void shape_bounds(double a, double b, double c, double out[3])
{
    out[0] = (a + 2 * b + c) / 8;
    double gs = c <= a ? a : (a + c) * (a + c) / (4 * c), gt = a <= c ? c : (a + c) * (a + c) / (4 * a);
    out[1] = 0.5 * (gs + 0.7698004 * b); /* stitched along s (south, north edges) */
    out[2] = 0.5 * (gt + 0.7698004 * b); /* stitched along t (east, west edges) */
}

static double norm3(double x, double y, double z) { return sqrt(x * x + y * y + z * z); }

/* The bounds of ptess.h for a Bézier net over its own [0,1]^2, tiles of N
 * quads: out[0] for interior triangles, out[1], out[2] for triangles
 * stitched along s and t. Second-derivative bounds from the net's second
 * differences, as vectors (|sum B_k X_k| <= max |X_k|); when rational,
 * through the quotient rule (S_s = (Q_s - w_s (S - c)) / w, S_ss = (Q_ss -
 * w_ss (S - c) - 2 w_s S_s) / w, Q = w (S - c)) with c the centre of the
 * net's box, which is free: interpolation error does not change under
 * translation. */
static inline double sq_second(const double *a, const double *b, const double *c, const double *d)
{
    /* |a - b - c + d|^2 */
    double x = a[0] - b[0] - c[0] + d[0], y = a[1] - b[1] - c[1] + d[1], z = a[2] - b[2] - c[2] + d[2];
    return x * x + y * y + z * z;
}

/* The rational basis' derivative sum over [0,1] for weights a_0..a_n:
 * with alpha_k = a_k B_k / sum a_i B_i, C_i = sum_{k <= i} alpha_k', the
 * distribution alpha_k(s) is an exponential family in log(s / (1 - s)),
 * so every C_i <= 0 and sum |C_i| = E' where E = sum k alpha_k, a rational
 * Bézier function with values 0..n; E' = (N' - E D') / D gives, with D >=
 * min a, E' <= n (max a + n max |a_{k+1} - a_k|) / min a (n for equal
 * weights). */
static double rational_basis_slope(int n, const double *a, int stride)
{
    double amin = INFINITY, amax = 0, da = 0;
    for (int k = 0; k <= n; k++) {
        amin = dmin(amin, a[k * stride]);
        amax = dmax(amax, a[k * stride]);
        if (k < n)
            da = dmax(da, fabs(a[(k + 1) * stride] - a[k * stride]));
    }
    return n * (amax + n * da) / amin;
}

/* The centre of the box of points P[0..n] (stride ps doubles). */
static void box_centre(int n, const double *P, int ps, double c[3])
{
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (int k = 0; k <= n; k++)
        for (int q = 0; q < 3; q++) {
            lo[q] = dmin(lo[q], P[k * ps + q]);
            hi[q] = dmax(hi[q], P[k * ps + q]);
        }
    for (int q = 0; q < 3; q++)
        c[q] = 0.5 * (lo[q] + hi[q]);
}

/* A bound of the second derivative's length of the rational Bézier
 * curve of degree n with points P (stride ps doubles) and weights W
 * (stride ws), over [0,1]: the quotient rule about the centre c of the
 * points' box (S_s = (Q_s - w_s (S - c)) / w, S_ss = (Q_ss - w_ss (S - c)
 * - 2 w_s S_s) / w, Q = w (P - c)), with |S_s| also within the basis'
 * slope times the largest step of the points (S_s = -sum C_i (p_{i+1} -
 * p_i), C as above). */
static double rational_curve_second(int n, const double *P, int ps, const double *W, int wst)
{
    if (n < 2 && W[0] == W[wst])
        return 0;
    double c[3];
    box_centre(n, P, ps, c);
    double A = 0, wmin = INFINITY, qs = 0, qss = 0, ps1 = 0, dw = 0, dww = 0;
    for (int k = 0; k <= n; k++) {
        const double *p0 = P + k * ps;
        double w0 = W[k * wst];
        wmin = dmin(wmin, w0);
        A = dmax(A, norm3(p0[0] - c[0], p0[1] - c[1], p0[2] - c[2]));
        if (k + 1 <= n) {
            const double *p1 = p0 + ps;
            double w1 = W[(k + 1) * wst];
            dw = dmax(dw, fabs(w1 - w0));
            qs = dmax(qs, norm3(w1 * (p1[0] - c[0]) - w0 * (p0[0] - c[0]), w1 * (p1[1] - c[1]) - w0 * (p0[1] - c[1]),
                                w1 * (p1[2] - c[2]) - w0 * (p0[2] - c[2])));
            ps1 = dmax(ps1, norm3(p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]));
        }
        if (k + 2 <= n) {
            const double *p1 = p0 + ps, *p2 = p1 + ps;
            double w1 = W[(k + 1) * wst], w2 = W[(k + 2) * wst], d[3];
            dww = dmax(dww, fabs(w2 - 2 * w1 + w0));
            for (int q = 0; q < 3; q++)
                d[q] = w2 * (p2[q] - c[q]) - 2 * w1 * (p1[q] - c[q]) + w0 * (p0[q] - c[q]);
            qss = dmax(qss, norm3(d[0], d[1], d[2]));
        }
    }
    double fn = n, fnn = n * (n - 1.0);
    double Bs = dmin(fn * (qs + dw * A) / wmin, rational_basis_slope(n, W, wst) * ps1);
    return (fnn * qss + 2 * fn * dw * Bs + fnn * dww * A) / wmin;
}

#define BERN_MAX (3 * TSR_BEZIER_MAX_DEGREE) /* the largest degree a curve bound's products reach */

static double binomial_table[BERN_MAX + 1][BERN_MAX + 1];
static pthread_once_t binomial_once = PTHREAD_ONCE_INIT;

static void make_binomials(void)
{
    for (int n = 0; n <= BERN_MAX; n++) {
        double c = 1;
        for (int k = 0; k <= n; k++) {
            binomial_table[n][k] = c;
            c = c * (n - k) / (k + 1);
        }
    }
}

/* C(n, k) for n <= BERN_MAX (rows of BERN_MAX + 1), exact in doubles. */
static const double *binomials(void)
{
    pthread_once(&binomial_once, make_binomials);
    return &binomial_table[0][0];
}

/* Bernstein coefficients of the product of two polynomials in Bernstein
 * form, degrees p and q: out has p + q + 1 (C(p, i) C(q, j) a_i b_j summed
 * at i + j, over C(p + q, i + j)). */
static void bern_mul(const double *a, int p, const double *b, int q, double *out)
{
    const double *C = binomials(), *cp = C + p * (BERN_MAX + 1), *cq = C + q * (BERN_MAX + 1),
                 *cpq = C + (p + q) * (BERN_MAX + 1);
    double sa[BERN_MAX + 1], sb[BERN_MAX + 1];
    for (int j = 0; j <= q; j++)
        sb[j] = cq[j] * b[j];
    for (int i = 0; i <= p; i++)
        sa[i] = cp[i] * a[i];
    for (int k = 0; k <= p + q; k++)
        out[k] = 0;
    for (int i = 0; i <= p; i++)
        for (int j = 0; j <= q; j++)
            out[i + j] += sa[i] * sb[j];
    for (int k = 0; k <= p + q; k++)
        out[k] /= cpq[k];
}

/* The coefficients of a polynomial of degree n in Bernstein form over
 * each quarter of its interval (de Casteljau at 1/2, then at 1/2 of each
 * half): q[k] over [k/4, (k+1)/4]. */
static void bern_quarters(const double *c, int n, double q[4][BERN_MAX + 1])
{
    double half[2][BERN_MAX + 1], t[BERN_MAX + 1];
    for (int level = 0; level < 3; level++) {
        const double *src = level == 0 ? c : half[level - 1];
        double *left = level == 0 ? half[0] : q[2 * (level - 1)], *right = level == 0 ? half[1] : q[2 * level - 1];
        memcpy(t, src, (size_t)(n + 1) * sizeof *t);
        left[0] = t[0];
        right[n] = t[n];
        for (int r = 1; r <= n; r++) {
            for (int i = 0; i <= n - r; i++)
                t[i] = 0.5 * (t[i] + t[i + 1]);
            left[r] = t[0];
            right[n - r] = t[n - r];
        }
    }
}

/* N = ww Q2 - 2 wwd Q1 - wwdd Q + 2 wdwd Q of degree 3n - 2 (the
 * weights' products given): C'''s numerator below. */
static void curve_numerator(int n, const double *ww, const double *wwd, const double *wwdd, const double *wdwd,
                            const double *Q, const double *Q1, const double *Q2, double *out)
{
    double t[3 * TSR_BEZIER_MAX_DEGREE + 1];
    int dn = 3 * n - 2;
    bern_mul(ww, 2 * n, Q2, n - 2, out);
    bern_mul(wwd, 2 * n - 1, Q1, n - 1, t);
    for (int k = 0; k <= dn; k++)
        out[k] -= 2 * t[k];
    bern_mul(wwdd, 2 * n - 2, Q, n, t);
    for (int k = 0; k <= dn; k++)
        out[k] -= t[k];
    bern_mul(wdwd, 2 * n - 2, Q, n, t);
    for (int k = 0; k <= dn; k++)
        out[k] += 2 * t[k];
}

#define CURVE_PIECES 4 /* a rational curve's bound is the largest of its quarters' (bern_quarters) */

/* A tighter bound of |C''| for the rational Bézier curve of degree n with
 * points P and weights W over [0, 1] (strides as rational_curve_second),
 * or INFINITY: C'' = N / w^3 with N = w^2 Q'' - 2 w w' Q' - w w'' Q + 2 w'^2
 * Q, Q = w (P - c), a polynomial of degree 3n - 2 whose Bernstein
 * coefficients bound it (convex hull), and w^3 >= the least of its own; on
 * each of CURVE_PIECES parts, where the coefficients are close to the
 * values. The quotient rule's bound above takes the largest |Q''| and the
 * smallest w together, 3.3 times a quarter circle's |C''| (this: 1.12);
 * on random curves this
 * is within 10 % of the true maximum more often than not. */
static double rational_curve_second_tight(int n, const double *P, int ps, const double *W, int wst)
{
    enum { MAXC = 3 * TSR_BEZIER_MAX_DEGREE + 1 };
    if (n < 2 || n > TSR_BEZIER_MAX_DEGREE)
        return INFINITY;
    double c[3];
    box_centre(n, P, ps, c);
    double w[MAXC], w1[MAXC], w2[MAXC], Q[3][MAXC], Q1[3][MAXC], Q2[3][MAXC];
    for (int k = 0; k <= n; k++) {
        w[k] = W[k * wst];
        if (!(w[k] > 0))
            return INFINITY;
        for (int q = 0; q < 3; q++)
            Q[q][k] = w[k] * (P[k * ps + q] - c[q]);
    }
    for (int k = 0; k < n; k++) {
        w1[k] = n * (w[k + 1] - w[k]);
        for (int q = 0; q < 3; q++)
            Q1[q][k] = n * (Q[q][k + 1] - Q[q][k]);
    }
    for (int k = 0; k + 1 < n; k++) {
        w2[k] = (n - 1) * (w1[k + 1] - w1[k]);
        for (int q = 0; q < 3; q++)
            Q2[q][k] = (n - 1) * (Q1[q][k + 1] - Q1[q][k]);
    }
    /* the weights' products, then N's terms, all of degree 3n - 2 */
    double ww[MAXC], wwd[MAXC], wwdd[MAXC], wdwd[MAXC], D[MAXC], N[3][MAXC];
    bern_mul(w, n, w, n, ww);             /* 2n */
    bern_mul(w, n, w1, n - 1, wwd);       /* 2n - 1 */
    bern_mul(w, n, w2, n - 2, wwdd);      /* 2n - 2 */
    bern_mul(w1, n - 1, w1, n - 1, wdwd); /* 2n - 2 */
    bern_mul(ww, 2 * n, w, n, D);         /* 3n */
    int dn = 3 * n - 2;
    for (int q = 0; q < 3; q++)
        curve_numerator(n, ww, wwd, wwdd, wdwd, Q[q], Q1[q], Q2[q], N[q]);
    /* the rounding of N's coefficients is absolute, up to some eps times
     * the sizes of the terms that cancel in them: bounded by the same
     * terms with every factor at its largest absolute value (a Bernstein
     * product's coefficients are weighted means of its factors' products),
     * and added whole */
    double mw = 0, mw1 = 0, mw2 = 0, mww = 0, big = 0;
    for (int k = 0; k <= n; k++)
        mw = dmax(mw, w[k]);
    for (int k = 0; k < n; k++)
        mw1 = dmax(mw1, fabs(w1[k]));
    for (int k = 0; k + 1 < n; k++)
        mw2 = dmax(mw2, fabs(w2[k]));
    for (int k = 0; k <= 2 * n; k++)
        mww = dmax(mww, ww[k]);
    for (int q = 0; q < 3; q++) {
        double mq = 0, mq1 = 0, mq2 = 0;
        for (int k = 0; k <= n; k++)
            mq = dmax(mq, fabs(Q[q][k]));
        for (int k = 0; k < n; k++)
            mq1 = dmax(mq1, fabs(Q1[q][k]));
        for (int k = 0; k + 1 < n; k++)
            mq2 = dmax(mq2, fabs(Q2[q][k]));
        big = dmax(big, mww * mq2 + 2 * mw * mw1 * mq1 + mw * mw2 * mq + 2 * mw1 * mw1 * mq);
    }
    double slack = 64.0 * (3 * n + 4) * DBL_EPSILON * sqrt(3.0) * big;
    double bound = 0, dq[4][BERN_MAX + 1], mq[3][4][BERN_MAX + 1];
    bern_quarters(D, 3 * n, dq);
    for (int q = 0; q < 3; q++)
        bern_quarters(N[q], dn, mq[q]);
    for (int piece = 0; piece < CURVE_PIECES; piece++) {
        double dmin_ = INFINITY, nmax = 0;
        for (int k = 0; k <= 3 * n; k++)
            dmin_ = dmin(dmin_, dq[piece][k]);
        for (int k = 0; k <= dn; k++)
            nmax = dmax(nmax, norm3(mq[0][piece][k], mq[1][piece][k], mq[2][piece][k]));
        if (!(dmin_ > 0))
            return INFINITY;
        bound = dmax(bound, (nmax + slack) / dmin_);
    }
    /* the rest of the arithmetic's rounding, generously */
    return bound * (1 + 1e-9) + 1e-300;
}

/* The largest squared mixed difference |p_{i+1,j+1} - p_{i+1,j} - p_{i,j+1}
 * + p_ij|^2 of a net of nu x nv points. */
static double max_mixed_sq(int nu, int nv, const double *P)
{
    double q = 0;
    for (int j = 0; j + 1 < nv; j++)
        for (int i = 0; i + 1 < nu; i++) {
            const double *p0 = P + 3 * (j * nu + i), *p1 = p0 + 3 * nu;
            q = dmax(q, sq_second(p1 + 3, p1, p0 + 3, p0));
        }
    return q;
}

/* Bounds for a rational net whose weights are a product w_ij = a_i b_j
 * (surfaces of revolution, extrusions, tori, spheres): false for other
 * weights. Then S = sum alpha_i(s) beta_j(t) p_ij with rational bases
 * alpha, beta of their own (each >= 0, summing to 1), so S_ss = sum_j
 * beta_j(t) c_j''(s) with c_j the net's rows as rational curves: M_ss is
 * the largest of the rows' bounds (each about its own centre: the net's
 * extent across the rows no longer counts), M_tt likewise by columns; and
 * summing by parts in i and j, S_st = sum C_i(s) D_j(t) (p_{i+1,j+1} -
 * p_{i+1,j} - p_{i,j+1} + p_ij) (C, D as above): at most the largest
 * mixed difference of the net times the two slopes. The quotient rule
 * bounds the mixed term through w_s S_t and loses the cancellation: a
 * cylinder's mixed differences are all zero. */
static bool separable_second(int du, int dv, const double *P, const double *W, double M[3])
{
    int nu = du + 1, nv = dv + 1;
    for (int j = 1; j < nv; j++)
        for (int i = 1; i < nu; i++) {
            double lhs = W[j * nu + i] * W[0], rhs = W[i] * W[j * nu];
            if (!(fabs(lhs - rhs) <= 1e-12 * lhs))
                return false;
        }
    M[1] = sqrt(max_mixed_sq(nu, nv, P)) * rational_basis_slope(du, W, 1) * rational_basis_slope(dv, W, nu);
    M[0] = M[2] = 0;
    for (int j = 0; j < nv; j++)
        M[0] = dmax(M[0], dmin(rational_curve_second(du, P + 3 * j * nu, 3, W + j * nu, 1),
                               rational_curve_second_tight(du, P + 3 * j * nu, 3, W + j * nu, 1)));
    for (int i = 0; i < nu; i++)
        M[2] = dmax(M[2], dmin(rational_curve_second(dv, P + 3 * i, 3 * nu, W + i, nu),
                               rational_curve_second_tight(dv, P + 3 * i, 3 * nu, W + i, nu)));
    return true;
}

/* Bounds M = {M_ss, M_st, M_tt} of the lengths of the second derivatives
 * of a Bézier net over [0,1]^2 (above). */
static void bezier_second(int du, int dv, const double *P, const double *W, double M[3])
{
    int nu = du + 1, nv = dv + 1;
    if (!W) { /* polynomial: the second differences of the net itself */
        double qss = 0, qtt = 0, qst = max_mixed_sq(nu, nv, P);
        for (int j = 0; j < nv; j++)
            for (int i = 0; i + 2 < nu; i++) {
                const double *p0 = P + 3 * (j * nu + i);
                double x = p0[6] - 2 * p0[3] + p0[0], y = p0[7] - 2 * p0[4] + p0[1], z = p0[8] - 2 * p0[5] + p0[2];
                qss = dmax(qss, x * x + y * y + z * z);
            }
        for (int j = 0; j + 2 < nv; j++)
            for (int i = 0; i < nu; i++) {
                const double *p0 = P + 3 * (j * nu + i), *p1 = p0 + 3 * nu, *p2 = p1 + 3 * nu;
                double x = p2[0] - 2 * p1[0] + p0[0], y = p2[1] - 2 * p1[1] + p0[1], z = p2[2] - 2 * p1[2] + p0[2];
                qtt = dmax(qtt, x * x + y * y + z * z);
            }
        double fuu = du * (du - 1.0), fvv = dv * (dv - 1.0), fuv = (double)du * dv;
        M[0] = fuu * sqrt(qss);
        M[1] = fuv * sqrt(qst);
        M[2] = fvv * sqrt(qtt);
        return;
    }
    double c[3];
    box_centre(nu * nv - 1, P, 3, c);
    double Q[3 * TSR_BEZIER_MAX_POINTS], A = 0, wmin = INFINITY;
    for (int k = 0; k < nu * nv; k++) {
        double w = W ? W[k] : 1;
        wmin = dmin(wmin, w);
        for (int q = 0; q < 3; q++)
            Q[3 * k + q] = w * (P[3 * k + q] - c[q]);
        if (W)
            A = dmax(A, norm3(P[3 * k] - c[0], P[3 * k + 1] - c[1], P[3 * k + 2] - c[2]));
    }
#define QD(i, j, q) Q[3 * ((j) * nu + (i)) + (q)]
#define WW(i, j) (W ? W[(j) * nu + (i)] : 1.0)
    double qs = 0, qt = 0, qss = 0, qtt = 0, qst = 0, ws = 0, wt = 0, wss = 0, wtt = 0, wst = 0;
    for (int j = 0; j < nv; j++)
        for (int i = 0; i < nu; i++) {
            double w = WW(i, j), d[3];
            if (i + 1 < nu) {
                ws = dmax(ws, fabs(WW(i + 1, j) - w));
                for (int q = 0; q < 3; q++)
                    d[q] = QD(i + 1, j, q) - QD(i, j, q);
                qs = dmax(qs, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            if (j + 1 < nv) {
                wt = dmax(wt, fabs(WW(i, j + 1) - w));
                for (int q = 0; q < 3; q++)
                    d[q] = QD(i, j + 1, q) - QD(i, j, q);
                qt = dmax(qt, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            if (i + 2 < nu) {
                wss = dmax(wss, fabs(WW(i + 2, j) - 2 * WW(i + 1, j) + w));
                for (int q = 0; q < 3; q++)
                    d[q] = QD(i + 2, j, q) - 2 * QD(i + 1, j, q) + QD(i, j, q);
                qss = dmax(qss, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            if (j + 2 < nv) {
                wtt = dmax(wtt, fabs(WW(i, j + 2) - 2 * WW(i, j + 1) + w));
                for (int q = 0; q < 3; q++)
                    d[q] = QD(i, j + 2, q) - 2 * QD(i, j + 1, q) + QD(i, j, q);
                qtt = dmax(qtt, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
            if (i + 1 < nu && j + 1 < nv) {
                wst = dmax(wst, fabs(WW(i + 1, j + 1) - WW(i + 1, j) - WW(i, j + 1) + w));
                for (int q = 0; q < 3; q++)
                    d[q] = QD(i + 1, j + 1, q) - QD(i + 1, j, q) - QD(i, j + 1, q) + QD(i, j, q);
                qst = dmax(qst, d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
            }
        }
#undef QD
#undef WW
    /* the largest lengths, from the largest squares */
    qs = sqrt(qs), qt = sqrt(qt), qss = sqrt(qss), qtt = sqrt(qtt), qst = sqrt(qst);
    double fu = du, fv = dv, fuu = du * (du - 1.0), fvv = dv * (dv - 1.0), fuv = fu * fv, Mss, Mst, Mtt;
    if (!W) {
        Mss = fuu * qss;
        Mtt = fvv * qtt;
        Mst = fuv * qst;
    } else {
        double Bs = (fu * qs + fu * ws * A) / wmin, Bt = (fv * qt + fv * wt * A) / wmin;
        Mss = (fuu * qss + 2 * fu * ws * Bs + fuu * wss * A) / wmin;
        Mtt = (fvv * qtt + 2 * fv * wt * Bt + fvv * wtt * A) / wmin;
        Mst = (fuv * qst + fuv * wst * A + fu * ws * Bt + fv * wt * Bs) / wmin;
        double Ms[3];
        if (separable_second(du, dv, P, W, Ms)) {
            Mss = dmin(Mss, Ms[0]);
            Mst = dmin(Mst, Ms[1]);
            Mtt = dmin(Mtt, Ms[2]);
        }
    }
    M[0] = Mss;
    M[1] = Mst;
    M[2] = Mtt;
}

static void bezier_delta(int du, int dv, const double *P, const double *W, double N, double out[3])
{
    double M[3];
    bezier_second(du, dv, P, W, M);
    double h2 = 1.0 / (N * N);
    shape_bounds(h2 * M[0], h2 * M[1], h2 * M[2], out);
    for (int k = 0; k < 3; k++)
        out[k] = out[k] * (1 + 1e-12) + 1e-300;
}

/* Bernstein polynomials of degree d at t (d + 1 values). */
static void bernstein(int d, double t, double *B)
{
    double s = 1 - t;
    B[0] = 1;
    for (int k = 1; k <= d; k++) {
        double saved = 0;
        for (int i = 0; i < k; i++) {
            double tmp = B[i];
            B[i] = saved + s * tmp;
            saved = t * tmp;
        }
        B[k] = saved;
    }
}

/* Homogeneous control points (w x, w y, w z, w), 4 doubles each. */
static void homogeneous(const tsr_patch *p, double *h)
{
    uint32_t cnt = (uint32_t)(p->degree_u + 1) * (uint32_t)(p->degree_v + 1);
    for (uint32_t k = 0; k < cnt; k++) {
        double w = p->weights ? p->weights[k] : 1;
        h[4 * k] = w * p->ctrl[3 * k];
        h[4 * k + 1] = w * p->ctrl[3 * k + 1];
        h[4 * k + 2] = w * p->ctrl[3 * k + 2];
        h[4 * k + 3] = w;
    }
}

/* De Casteljau at 1/2 of d + 1 homogeneous points at stride (in points):
 * the halves over [0, 1/2] and [1/2, 1], at the same stride. */
static void halve(const double *src, double *lo, double *hi, int d, int stride)
{
    double t[TSR_PATCH_MAX_DEGREE + 1][4];
    size_t s4 = 4 * (size_t)stride;
    for (int i = 0; i <= d; i++)
        memcpy(t[i], src + s4 * (size_t)i, sizeof t[i]);
    memcpy(lo, t[0], sizeof t[0]);
    memcpy(hi + s4 * (size_t)d, t[d], sizeof t[d]);
    for (int k = 1; k <= d; k++) {
        for (int i = 0; i <= d - k; i++)
            for (int c = 0; c < 4; c++)
                t[i][c] = 0.5 * (t[i][c] + t[i + 1][c]);
        memcpy(lo + s4 * (size_t)k, t[0], sizeof t[0]);
        memcpy(hi + s4 * (size_t)(d - k), t[d - k], sizeof t[0]);
    }
}

/* The four quarter nets of a homogeneous net: kid[cx + 2 cy] over
 * [cx/2, (cx+1)/2] x [cy/2, (cy+1)/2]. */
static void split4(const double *h, int du, int dv, double kid[4][4 * TSR_BEZIER_MAX_POINTS])
{
    int nu = du + 1, nv = dv + 1;
    double L[4 * TSR_BEZIER_MAX_POINTS], R[4 * TSR_BEZIER_MAX_POINTS];
    for (int j = 0; j < nv; j++)
        halve(h + 4 * j * nu, L + 4 * j * nu, R + 4 * j * nu, du, 1);
    for (int i = 0; i < nu; i++) {
        halve(L + 4 * i, kid[0] + 4 * i, kid[2] + 4 * i, dv, nu);
        halve(R + 4 * i, kid[1] + 4 * i, kid[3] + 4 * i, dv, nu);
    }
}

/* ---- tessellation context ----------------------------------------------- */

/* What a node's bounds and errors are, kept once computed: the passes
 * select each piece's tree again and again. */
typedef struct nodeval {
    float lo[3], hi[3];
    float d[3];    /* interior, stitched along s, stitched along t: for a
                      Bézier piece per unit tile (N = 1; node_d scales), for
                      a subd piece at the piece's N */
    float cam;     /* with a camera: pixels per unit of error (its
                      tsr_camera_box_factor, rounded up); else 1 */
    uint8_t force; /* split it: a finer neighbour's stitched tile needs it */
    uint8_t level;
    uint32_t tile; /* subd: its tile's (N + 1)^2 points are pts[tidx[tile (N + 1)^2 + k]];
                      UINT32_MAX: not kept (Bézier, or out of memory) */
} nodeval;

/* The nets of the four children of one node (level l - 1) of one piece,
 * homogeneous: kept per level l, so the top-down selection, which visits
 * a node's children together, makes each child's net from its parent's by
 * one midpoint split, not from the piece's net. */
typedef struct kidnets {
    uint64_t key; /* 1 + the parent's tsr_qnode_key; 0: empty */
    uint32_t piece;
    double h[4][4 * TSR_BEZIER_MAX_POINTS];
} kidnets;

typedef struct pctx {
    const tsr_pmodel *m;
    const tsr_ptess_options *opt;
    uint32_t piece;
    uint32_t N;      /* quads per tile side: the piece's own (choose_tile) */
    double inv_n2;   /* 1 / N^2 */
    double tol; /* max_error or pixel_error, times the piece's scale */
    uint8_t *act[4]; /* per segment of a linked edge (after selection, collect_spans):
                        span log of the leaf there; segments of the deepest leaf's size,
                        each 2^act_shift of the finest level's */
    uint8_t act_shift;
    tsr_surface surf;
    tsr_quadtree *qt;
    const tsr_allocator *alloc;
    tsr_keymap memo; /* node key -> index in nv */
    nodeval *nv;
    uint32_t nnv, capnv;
    nodeval cur;     /* the last node asked about */
    uint64_t cur_key;
    bool nomem;      /* the memo could not grow */
    uint64_t *evaluations;
    double *scratch; /* subd tile positions */
    double *uv;
    uint32_t *idx;   /* subd: subd_points' points in pts */
    uint32_t *ij;    /* subd: a tile's lattice pairs */
    uint32_t *tix;   /* subd: a tile's points in pts (subd_tile), and 4 more */
    uint32_t *tat;   /* subd: where in the tile subd_tile's lookups go */
    kidnets *kids;   /* per level, shared by all pieces (selected in turn) */
    /* subd piece: every lattice point evaluated so far (a node's tile
     * shares its points with its parent's, its siblings' and, for a leaf,
     * with the mesh), so each is evaluated once per run */
    tsr_keymap pmemo; /* lattice key (lkey's j, i) -> index in pts */
    double *pts;      /* 3 per point */
    uint32_t *vid;    /* per point: its mesh vertex (emission), UINT32_MAX before */
    uint32_t npts, cappts;
    uint32_t *tidx;   /* per node computed: its tile's points (indices in pts), so
                         emission reads a leaf's points without looking them up */
    uint32_t ntidx, captidx; /* in tiles */
} pctx;

static void node_rect(const pctx *c, tsr_qnode n, double r[4])
{
    double w = 1.0 / (double)(1u << n.level);
    r[0] = n.x * w;
    r[1] = (n.x + 1) * w;
    r[2] = n.y * w;
    r[3] = (n.y + 1) * w;
    (void)c;
}

/* The next float towards +infinity (dir 1) or -infinity (dir -1) of a
 * finite f: nextafterf without the call. */
static inline float f_step(float f, int dir)
{
    if (f == 0)
        return dir > 0 ? FLT_TRUE_MIN : -FLT_TRUE_MIN;
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    u = ((u >> 31) != 0) == (dir > 0) ? u - 1 : u + 1; /* away from zero: +1 */
    memcpy(&f, &u, sizeof f);
    return f;
}

/* Floats at or beyond a double, on the side asked. */
static inline float f_up(double x)
{
    float f = (float)x;
    return (double)f < x && isfinite(f) ? f_step(f, 1) : f;
}

static inline float f_down(double x)
{
    float f = (float)x;
    return (double)f > x && isfinite(f) ? f_step(f, -1) : f;
}

/* The homogeneous net of a Bézier piece's node: from the cache of its
 * level, or its parent's (recursively) split in four and kept. */
static const double *node_net(pctx *c, tsr_qnode n)
{
    const piece *p = &c->m->pieces[c->piece];
    kidnets *k = &c->kids[n.level];
    tsr_qnode up = {n.x >> 1, n.y >> 1, (uint8_t)(n.level ? n.level - 1 : 0)};
    uint64_t key = n.level ? tsr_qnode_key(up) + 1 : 1;
    if (k->piece != c->piece || k->key != key) {
        if (!n.level)
            homogeneous(&p->bez, k->h[0]);
        else
            split4(node_net(c, up), p->bez.degree_u, p->bez.degree_v, k->h);
        k->piece = c->piece;
        k->key = key;
    }
    return k->h[n.level ? (n.x & 1) + 2 * (n.y & 1) : 0];
}

/* Lattice key of a subd piece's point (i, j) of its lattice (lkey's
 * layout without the piece). */
static inline uint64_t pkey(uint32_t i, uint32_t j) { return (uint64_t)j << 20 | i; }

/* Room in a subd piece's memo for extra more points. */
static bool memo_room(pctx *c, uint32_t extra)
{
    if (c->npts + extra <= c->cappts)
        return true;
    uint32_t cap = c->cappts ? 2 * c->cappts : 64;
    while (cap < c->npts + extra)
        cap *= 2;
    double *np = tsr_realloc(c->alloc, c->pts, (size_t)cap * 3 * sizeof *np);
    if (!np)
        return false;
    c->pts = np;
    uint32_t *nv = tsr_realloc(c->alloc, c->vid, (size_t)cap * sizeof *nv);
    if (!nv)
        return false;
    c->vid = nv;
    c->cappts = cap;
    return true;
}

/* Points of a subd piece's lattice into P (3 each): from the piece's memo,
 * the missing ones evaluated in one batch at (i / Z, j / Z) and kept.
 * ij holds count lattice pairs; their indices in pts into c->idx. P NULL:
 * the indices only. false when out of memory (nomem set) or when the
 * evaluation fails. */
static bool subd_points(pctx *c, const uint32_t *ij, uint32_t count, double *P)
{
    const piece *p = &c->m->pieces[c->piece];
    double Z = (double)(c->N << c->surf.levels);
    uint32_t miss = 0;
    if (!memo_room(c, count)) { /* before any key goes in: none is left without its point */
        c->nomem = true;
        return false;
    }
    for (uint32_t k = 0; k < count; k++) {
        bool found;
        uint32_t *slot = tsr_keymap_slot(&c->pmemo, pkey(ij[2 * k], ij[2 * k + 1]), &found, c->alloc);
        if (!slot) {
            c->nomem = true;
            return false;
        }
        if (!found) {
            *slot = c->npts + miss;
            c->uv[2 * miss] = ij[2 * k] / Z;
            c->uv[2 * miss + 1] = ij[2 * k + 1] / Z;
            miss++;
        }
        c->idx[k] = *slot;
    }
    if (miss) {
        if (tsr_subd_eval(c->m->subd, p->face, p->sub, c->uv, miss, c->pts + 3 * (size_t)c->npts, NULL, NULL) !=
            TSR_OK) {
            c->nomem = true; /* (only NOMEM can fail here: the piece's patch exists) */
            return false;
        }
        for (uint32_t k = 0; k < miss; k++)
            c->vid[c->npts + k] = UINT32_MAX;
        c->npts += miss;
        *c->evaluations += miss;
    }
    for (uint32_t k = 0; P && k < count; k++)
        memcpy(P + 3 * k, c->pts + 3 * (size_t)c->idx[k], 3 * sizeof *P);
    return true;
}

/* Indices kept per subd node (nodeval.tile): its tile's (N + 1)^2 points,
 * then the centres of its four corner cells (node_compute; UINT32_MAX
 * until found). */
static inline size_t tile_stride(const pctx *c) { return (size_t)(c->N + 1) * (c->N + 1) + 4; }

/* The (N + 1)^2 points of node n's tile of a subd piece into P, their
 * indices in pts into c->tix. A child's even points are its parent's tile
 * points, and the point next to its corner of the parent the centre of the
 * parent's corner cell: taken from the parent's kept indices, so only the
 * others are looked up (15 of 25 at N = 4). */
static bool subd_tile(pctx *c, tsr_qnode n, double *P)
{
    uint32_t N = c->N, row = N + 1, sh = c->surf.levels - n.level;
    uint32_t *ij = c->ij, *tix = c->tix, *at = c->tat, cnt = 0;
    const uint32_t *up = NULL;
    if (n.level > 0) {
        tsr_qnode pn = {n.x >> 1, n.y >> 1, (uint8_t)(n.level - 1)};
        const uint32_t *slot = tsr_keymap_find(&c->memo, tsr_qnode_key(pn));
        if (slot && c->nv[*slot].tile != UINT32_MAX)
            up = c->tidx + (size_t)c->nv[*slot].tile * tile_stride(c);
    }
    uint32_t cx = n.x & 1, cy = n.y & 1, ox = cx * N / 2, oy = cy * N / 2;
    uint32_t ci = cx ? N - 1 : 1, cj = cy ? N - 1 : 1; /* the parent's corner-cell centre */
    for (uint32_t j = 0; j <= N; j++)
        for (uint32_t i = 0; i <= N; i++) {
            uint32_t k = j * row + i, known = UINT32_MAX;
            if (up && !(i & 1) && !(j & 1))
                known = up[(oy + j / 2) * row + ox + i / 2];
            else if (up && i == ci && j == cj)
                known = up[row * row + cx + 2 * cy];
            tix[k] = known;
            if (known == UINT32_MAX) {
                ij[2 * cnt] = (n.x * N + i) << sh;
                ij[2 * cnt + 1] = (n.y * N + j) << sh;
                at[cnt++] = k;
            }
        }
    if (cnt && !subd_points(c, ij, cnt, NULL))
        return false;
    for (uint32_t k = 0; k < cnt; k++)
        tix[at[k]] = c->idx[k];
    for (uint32_t k = 0; k < row * row; k++)
        memcpy(P + 3 * k, c->pts + 3 * (size_t)tix[k], 3 * sizeof *P);
    return true;
}

/* A node whose points could not be had (out of memory; refine then stops
 * and the run fails): an unknown error, the piece's box. */
static void node_unknown(const piece *p, nodeval *out)
{
    for (int k = 0; k < 3; k++) {
        out->d[k] = INFINITY;
        out->lo[k] = (float)p->lo[k];
        out->hi[k] = (float)p->hi[k];
    }
}

/* Keeps the indices of the tile subd_tile just read (c->tix) for node
 * value v, its corner-cell centres unknown; without memory v keeps none
 * (its children and the emission look them up). */
static void keep_tile(pctx *c, nodeval *v)
{
    size_t rr = (size_t)(c->N + 1) * (c->N + 1), st = tile_stride(c);
    if (c->ntidx == c->captidx) {
        uint32_t cap = c->captidx ? 2 * c->captidx : 8;
        uint32_t *nt = tsr_realloc(c->alloc, c->tidx, cap * st * sizeof *nt);
        if (!nt)
            return;
        c->tidx = nt;
        c->captidx = cap;
    }
    uint32_t *t = c->tidx + c->ntidx * st;
    memcpy(t, c->tix, rr * sizeof *t);
    t[rr] = t[rr + 1] = t[rr + 2] = t[rr + 3] = UINT32_MAX;
    v->tile = c->ntidx++;
}

static void node_compute(pctx *c, tsr_qnode n, nodeval *out)
{
    const piece *p = &c->m->pieces[c->piece];
    double r[4], d[3];
    node_rect(c, n, r);
    memset(out, 0, sizeof *out);
    out->tile = UINT32_MAX;
    if (p->kind == KIND_BEZIER) {
        double ctrl[3 * TSR_BEZIER_MAX_POINTS], w[TSR_BEZIER_MAX_POINTS];
        tsr_patch sub = p->bez;
        uint32_t cnt = (uint32_t)(sub.degree_u + 1) * (uint32_t)(sub.degree_v + 1);
        if (n.level > 0) {
            const double *h = node_net(c, n);
            for (uint32_t k = 0; k < cnt; k++) {
                double wk = h[4 * k + 3];
                if (p->bez.weights) {
                    ctrl[3 * k] = h[4 * k] / wk;
                    ctrl[3 * k + 1] = h[4 * k + 1] / wk;
                    ctrl[3 * k + 2] = h[4 * k + 2] / wk;
                    w[k] = wk;
                } else {
                    memcpy(ctrl + 3 * k, h + 4 * k, 3 * sizeof *ctrl);
                }
            }
            sub.ctrl = ctrl;
            sub.weights = p->bez.weights ? w : NULL;
        }
        double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
        for (uint32_t i = 0; i < cnt; i++)
            box_add(lo, hi, sub.ctrl + 3 * i);
        for (int k = 0; k < 3; k++) {
            out->lo[k] = f_down(lo[k]);
            out->hi[k] = f_up(hi[k]);
        }
        bezier_delta(sub.degree_u, sub.degree_v, sub.ctrl, sub.weights, 1, d);
        /* the parent's bounds hold for the child at a quarter (the same
         * derivative bounds over a part, half the spacing): monotone */
        if (n.level > 0) {
            tsr_qnode up = {n.x >> 1, n.y >> 1, (uint8_t)(n.level - 1)};
            const uint32_t *slot = tsr_keymap_find(&c->memo, tsr_qnode_key(up));
            if (slot)
                for (int k = 0; k < 3; k++)
                    d[k] = dmin(d[k], 0.25 * c->nv[*slot].d[k]);
        }
        for (int k = 0; k < 3; k++)
            out->d[k] = f_up(d[k]);
        return;
    }
    /* subd: the tile's vertices, second differences, an estimate */
    uint32_t N = c->N, row = N + 1;
    double *P = c->scratch;
    if (!subd_tile(c, n, P)) {
        node_unknown(p, out);
        return;
    }
    keep_tile(c, out);
    double a[3] = {0}, b[3] = {0}, cc[3] = {0}, lo[3] = {INFINITY, INFINITY, INFINITY},
           hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (uint32_t j = 0; j <= N; j++)
        for (uint32_t i = 0; i <= N; i++) {
            const double *p0 = P + 3 * (j * row + i);
            box_add(lo, hi, p0);
            for (int k = 0; k < 3; k++) {
                if (i + 2 <= N)
                    a[k] = dmax(a[k], fabs(p0[6 + k] - 2 * p0[3 + k] + p0[k]));
                if (j + 2 <= N)
                    cc[k] = dmax(cc[k], fabs(p0[6 * row + k] - 2 * p0[3 * row + k] + p0[k]));
                if (i + 1 <= N && j + 1 <= N)
                    b[k] = dmax(b[k], fabs(p0[3 * row + 3 + k] - p0[3 * row + k] - p0[3 + k] + p0[k]));
            }
        }
    double sum[3] = {0};
    for (int k = 0; k < 3; k++) {
        double e[3];
        shape_bounds(a[k], b[k], cc[k], e);
        for (int q = 0; q < 3; q++)
            sum[q] += e[q] * e[q];
    }
    for (int q = 0; q < 3; q++)
        d[q] = SUBD_MARGIN * sqrt(sum[q]);
    /* and the distance found at the centres of the tile's four corner
     * cells (children's lattice points, so a node that splits pays nothing
     * for them): a feature at a corner of the face, where Bfr's surface is
     * least smooth (an extraordinary or creased vertex), narrower than the
     * tile's spacing escapes the second differences but shows there (on
     * catmark_cube_creases1 at 3e-3 of the diagonal, and
     * catmark_cubes_semisharp at 1e-3, the measured error fell from 1.8
     * and 3.2 times the tolerance to 0.93 and 0.90; checking every cell's
     * centre found nothing more on the cages of tessera bench patch) */
    uint32_t sh = c->surf.levels - n.level;
    if (sh > 0) {
        static const uint8_t corner[4][2] = {{0, 0}, {1, 0}, {0, 1}, {1, 1}};
        uint32_t *ij = c->ij;
        double *C = c->scratch + 5 * (size_t)row * row;
        for (int k = 0; k < 4; k++) {
            uint32_t i = corner[k][0] * (N - 1), j = corner[k][1] * (N - 1);
            ij[2 * k] = (2 * (n.x * N + i) + 1) << (sh - 1);
            ij[2 * k + 1] = (2 * (n.y * N + j) + 1) << (sh - 1);
        }
        if (!subd_points(c, ij, 4, C)) {
            node_unknown(p, out);
            return;
        }
        if (out->tile != UINT32_MAX)
            memcpy(c->tidx + out->tile * tile_stride(c) + (size_t)row * row, c->idx, 4 * sizeof *c->idx);
        double worst = 0;
        for (int k = 0; k < 4; k++) {
            uint32_t i = corner[k][0] * (N - 1), j = corner[k][1] * (N - 1);
            const double *p00 = P + 3 * (j * row + i), *p10 = p00 + 3, *p01 = p00 + 3 * row, *p11 = p01 + 3,
                         *q = C + 3 * k;
            double e1 = 0, e2 = 0; /* against either diagonal of the cell */
            for (int x = 0; x < 3; x++) {
                double y1 = q[x] - 0.5 * (p00[x] + p11[x]), y2 = q[x] - 0.5 * (p10[x] + p01[x]);
                e1 += y1 * y1;
                e2 += y2 * y2;
            }
            worst = dmax(worst, sqrt(dmax(e1, e2)));
        }
        for (int q = 0; q < 3; q++)
            d[q] = dmax(d[q], worst);
    }
    for (int q = 0; q < 3; q++)
        out->d[q] = (float)d[q];
    for (int k = 0; k < 3; k++) {
        double l = lo[k] - 2 * d[1 + (d[2] > d[1])], h = hi[k] + 2 * d[1 + (d[2] > d[1])];
        l = l < p->lo[k] ? p->lo[k] : l;
        h = h > p->hi[k] ? p->hi[k] : h;
        if (l > h)
            l = h = 0.5 * (lo[k] + hi[k]);
        out->lo[k] = f_down(l);
        out->hi[k] = f_up(h);
    }
}

/* The node's values, from the memo or computed and kept. */
static const nodeval *node_info(pctx *c, tsr_qnode n)
{
    uint64_t key = tsr_qnode_key(n);
    if (key + 1 == c->cur_key)
        return &c->cur;
    const uint32_t *have = tsr_keymap_find(&c->memo, key);
    if (have) {
        c->cur = c->nv[*have];
    } else {
        node_compute(c, n, &c->cur);
        c->cur.level = n.level;
        c->cur.cam = c->opt->camera ? f_up(tsr_camera_box_factor(c->opt->camera, c->cur.lo, c->cur.hi,
                                                                   c->surf.error_isotropic))
                                    : 1;
        if (c->nnv == c->capnv) {
            uint32_t cap = c->capnv ? 2 * c->capnv : 16;
            nodeval *nv = cap > c->capnv ? tsr_realloc(c->alloc, c->nv, (size_t)cap * sizeof *nv) : NULL;
            if (nv) {
                c->nv = nv;
                c->capnv = cap;
            }
        }
        bool found;
        uint32_t *slot = c->nnv < c->capnv ? tsr_keymap_slot(&c->memo, key, &found, c->alloc) : NULL;
        if (slot) {
            *slot = c->nnv;
            c->nv[c->nnv++] = c->cur;
        } else {
            c->nomem = true; /* the answer stands, but forcing would fail */
        }
    }
    c->cur_key = key + 1;
    return &c->cur;
}

/* Marks a node and its ancestors to be split. */
static void node_force(pctx *c, tsr_qnode n)
{
    for (;;) {
        node_info(c, n);
        const uint32_t *slot = tsr_keymap_find(&c->memo, tsr_qnode_key(n));
        if (slot)
            c->nv[*slot].force = 1;
        else
            c->nomem = true;
        c->cur.force = 1;
        if (!n.level)
            return;
        n = (tsr_qnode){n.x >> 1, n.y >> 1, (uint8_t)(n.level - 1)};
        c->cur_key = 0;
    }
}

/* Figure k of a node's values at the piece's tile size. */
static float node_d(const pctx *c, const nodeval *v, int k)
{
    if (c->m->pieces[c->piece].kind != KIND_BEZIER)
        return v->d[k];
    return f_up((double)v->d[k] * c->inv_n2);
}

static bool surf_evaluate(void *user, uint32_t i, uint32_t j, float pos[3], float normal[3])
{
    (void)user, (void)i, (void)j, (void)pos, (void)normal;
    return false; /* the tessellator evaluates vertices itself */
}

static void surf_bounds(void *user, tsr_qnode n, float lo[3], float hi[3])
{
    pctx *c = user;
    const nodeval *v = node_info(c, n);
    memcpy(lo, v->lo, sizeof v->lo);
    memcpy(hi, v->hi, sizeof v->hi);
}

/* The error of the node's tile without stitching (tsr_ptess_run checks
 * stitched tiles after selection, and splits their coarse neighbours where
 *  the stitched bound is beyond the tolerance). */
static float surf_error(void *user, tsr_qnode n)
{
    pctx *c = user;
    return node_d(c, node_info(c, n), 0);
}

/* The node's error against the tolerance: model units or pixels (as
 * tsr_camera_node_error, with the factor kept per node). */
static double node_measure(const pctx *c, const nodeval *v, float delta)
{
    if (!c->opt->camera)
        return delta;
    if (v->cam == 0)
        return 0;
    return isinf(delta) ? INFINITY : (double)v->cam * delta;
}

/* Segment range [k0, k1) of edge e covered by node n, or false. */
static bool node_edge_range(const pctx *c, tsr_qnode n, int e, uint32_t *k0, uint32_t *k1)
{
    uint32_t L = c->surf.levels, side = 1u << n.level, span = 1u << (L - n.level);
    bool on = e == 0 ? n.y == 0 : e == 1 ? n.x == side - 1 : e == 2 ? n.y == side - 1 : n.x == 0;
    if (!on)
        return false;
    uint32_t pos = (e & 1) ? n.y : n.x;
    *k0 = pos * span;
    *k1 = *k0 + span;
    return true;
}

static bool refine(void *user, const tsr_surface *s, tsr_qnode n)
{
    pctx *c = user;
    (void)s;
    const nodeval *v = node_info(c, n);
    if (c->nomem)
        return false; /* the run fails: refining on (a node without its points
                         reads as infinitely far off) would only take time */
    return v->force || node_measure(c, v, node_d(c, v, 0)) > c->tol;
}

/* Nodes split in the subtree of n by a selection at the current tile
 * size (c->N) whose deepest level is last, counted from the node values
 * (computed where not yet known). */
static uint64_t splits_below(pctx *c, tsr_qnode n, uint32_t last)
{
    const nodeval *v = node_info(c, n);
    if (c->nomem || n.level >= last || node_measure(c, v, node_d(c, v, 0)) <= c->tol)
        return 0;
    uint64_t s = 1;
    for (uint32_t k = 0; k < 4; k++)
        s += splits_below(c, (tsr_qnode){2 * n.x + (k & 1), 2 * n.y + (k >> 1), (uint8_t)(n.level + 1)}, last);
    return s;
}

#define HALF_TRIAL_LEAVES 16u       /* subd trees up to this many tiles try half tiles */
#define BEZIER_HALF_TRIAL_LEAVES 1u /* Bézier trees likewise */

/* A Bézier piece's tile size N: of tile, tile + 2, ... up to maxN (4 tile
 * - 2), the one whose selection (without the stitched check and the 2:1
 * balance) has the fewest quads (ties: the smallest). The rates N 2^l of
 * the pieces then step by (N + 2) / N, not by 2, and linked edges of
 * different rates meet through fans (emit_piece). One selection at N =
 * tile computes the values of every node any larger N visits (node values
 * are per unit tile; a node's error only falls with depth, so a larger N
 * splits a subset of the nodes tile splits): each N's split count then
 * comes from the memo, and its leaves are 1 + 3 splits.
 * Where that selection has at most BEZIER_HALF_TRIAL_LEAVES leaves (one:
 * at 16, as for subd trees, the teapot's camera runs took 1.8 times as
 * long for 2-4 % fewer triangles), also tiles of
 * half (tile / 2 when even, >= TSR_TILE_MIN) with one level more, the
 * same lattice: its splits are counted down from the root (the nodes that
 * pass at tile but not at half tile have their children's values
 * computed), and it is taken when it has fewer quads. A piece that one
 * tile covers but half a tile would too (a cut piece of a cylinder, whose
 * straight direction needs one quad) then makes a quarter of the quads. */
static tsr_status choose_tile(pctx *c, uint32_t tile, uint32_t maxN)
{
    c->N = tile;
    c->inv_n2 = 1.0 / ((double)tile * tile);
    c->cur_key = 0;
    uint32_t half = tile / 2;
    bool try_half = half >= TSR_TILE_MIN && !(half & 1);
    if (tile >= maxN && !try_half)
        return TSR_OK; /* (else maxN == tile: the loop below tries tile alone) */
    tsr_status st = tsr_quadtree_select(c->qt, refine, c);
    if (st != TSR_OK)
        return st;
    uint64_t best = UINT64_MAX;
    uint32_t bestN = tile, deepest = c->surf.levels;
    for (uint32_t N = tile; N <= maxN; N += 2) {
        c->N = N;
        c->inv_n2 = 1.0 / ((double)N * N);
        uint64_t splits = 0;
        for (uint32_t k = 0; k < c->nnv; k++) {
            const nodeval *v = &c->nv[k];
            splits += v->level < deepest && node_measure(c, v, node_d(c, v, 0)) > c->tol;
        }
        uint64_t cost = (1 + 3 * splits) * N * N;
        if (cost < best) {
            best = cost;
            bestN = N;
        }
    }
    if (try_half && tsr_quadtree_leaf_count(c->qt) <= BEZIER_HALF_TRIAL_LEAVES) {
        /* one level more where the quadtree has one (at the deepest
         * allowed, the same depth: the finest lattice then halves, which
         * costs nothing where the root passes, the only way half tiles
         * win on a one-tile piece) */
        uint32_t levels = c->surf.levels + 1 < TSR_QUADTREE_MAX_LEVELS ? c->surf.levels + 1 : c->surf.levels;
        c->N = half;
        c->inv_n2 = 1.0 / ((double)half * half);
        c->cur_key = 0;
        uint64_t splits = splits_below(c, (tsr_qnode){0, 0, 0}, levels);
        if (c->nomem)
            return TSR_ERR_NOMEM;
        if ((1 + 3 * splits) * half * half < best) {
            tsr_surface surf = c->surf;
            surf.tile_n = half;
            surf.levels = levels;
            surf.extent_x = surf.extent_y = half << levels;
            tsr_quadtree *qt = tsr_quadtree_create(&surf, c->alloc);
            if (!qt)
                return TSR_ERR_NOMEM;
            tsr_quadtree_destroy(c->qt);
            c->qt = qt;
            c->surf = surf;
            c->cur_key = 0;
            return TSR_OK;
        }
    }
    c->N = bestN;
    c->inv_n2 = 1.0 / ((double)bestN * bestN);
    c->cur_key = 0;
    return TSR_OK;
}

/* The tree state of a piece (its tiles' size, quadtree, node values and
 * kept tile indices, linked-edge spans), apart from its points. */
typedef struct ptree {
    uint32_t N;
    double inv_n2;
    tsr_surface surf;
    tsr_quadtree *qt;
    tsr_keymap memo;
    nodeval *nv;
    uint32_t nnv, capnv;
    uint32_t *tidx;
    uint32_t ntidx, captidx;
} ptree;

static ptree tree_take(pctx *c)
{
    ptree t = {c->N, c->inv_n2, c->surf, c->qt, c->memo, c->nv,
               c->nnv, c->capnv, c->tidx, c->ntidx, c->captidx};
    return t;
}

static void tree_put(pctx *c, const ptree *t)
{
    c->N = t->N;
    c->inv_n2 = t->inv_n2;
    c->surf = t->surf;
    c->qt = t->qt;
    c->memo = t->memo;
    c->nv = t->nv;
    c->nnv = t->nnv;
    c->capnv = t->capnv;
    c->tidx = t->tidx;
    c->ntidx = t->ntidx;
    c->captidx = t->captidx;
    c->cur_key = 0;
}

static void tree_free(ptree *t, const tsr_allocator *a)
{
    tsr_quadtree_destroy(t->qt);
    tsr_keymap_free(&t->memo, a);
    tsr_free(a, t->nv);
    tsr_free(a, t->tidx);
    memset(t, 0, sizeof *t);
}

static uint64_t tree_quads(const pctx *c)
{
    return (uint64_t)tsr_quadtree_leaf_count(c->qt) * c->N * c->N;
}

/* A subd piece's tile size: its tile (c->N, selected here) or half that
 * (half; 0: none) with one level more, the same lattice (so the same points, evaluated
 * once), whichever selection has fewer quads (ties: the tile). Subd node
 * values are not per unit tile (they come from the tile's own points), so
 * each size takes a selection of its own. Near a tolerance the coarser
 * tiles often hold where the larger split in four: a face of a cube
 * meshed in one tile of 2 x 2 quads rather than four of 4 x 4. */
static tsr_status subd_choose_tile(pctx *c, uint32_t half)
{
    c->cur_key = 0;
    tsr_status st = tsr_quadtree_select(c->qt, refine, c);
    if (st != TSR_OK || c->nomem)
        return st != TSR_OK ? st : TSR_ERR_NOMEM;
    uint64_t full = tree_quads(c);
    uint32_t leaves = tsr_quadtree_leaf_count(c->qt);
    if (leaves <= 1 && full <= (uint64_t)half * half)
        return TSR_OK; /* one tile already: no fewer quads below */
    if (!half || leaves > HALF_TRIAL_LEAVES || c->surf.levels + 1 >= TSR_QUADTREE_MAX_LEVELS)
        return TSR_OK;
    ptree keep = tree_take(c), trial;
    memset(&trial, 0, sizeof trial);
    trial.N = half;
    trial.inv_n2 = 1.0 / ((double)half * half);
    trial.surf = keep.surf;
    trial.surf.tile_n = half;
    trial.surf.levels = keep.surf.levels + 1;
    trial.qt = tsr_quadtree_create(&trial.surf, c->alloc);
    st = trial.qt ? TSR_OK : TSR_ERR_NOMEM;
    if (st == TSR_OK) {
        tree_put(c, &trial);
        st = tsr_quadtree_select(c->qt, refine, c);
        if (st == TSR_OK && c->nomem)
            st = TSR_ERR_NOMEM;
        trial = tree_take(c);
    }
    if (st == TSR_OK && tree_quads(c) < full) {
        tree_free(&keep, c->alloc);
        return TSR_OK;
    }
    tree_free(&trial, c->alloc);
    tree_put(c, &keep);
    return st;
}

/* After selection: every stitched tile's bound against the tolerance.
 * Where it fails, the coarse neighbour is marked to split (the finer tile
 * is then not stitched there); returns how many were marked. Adds the
 * bound of every leaf as its tile is drawn to *bound. */
static uint32_t check_stitched(pctx *c, double *bound)
{
    uint32_t nl = tsr_quadtree_leaf_count(c->qt), marked = 0;
    const tsr_qleaf *lv = tsr_quadtree_leaves(c->qt);
    for (uint32_t i = 0; i < nl; i++) {
        tsr_qnode n = lv[i].node;
        nodeval v = *node_info(c, n);
        double d = node_d(c, &v, 0);
        for (int e = 0; e < 4; e++) {
            if (!(lv[i].stitch & (1u << e)))
                continue;
            float ds = node_d(c, &v, e & 1 ? 2 : 1);
            if (node_measure(c, &v, ds) > c->tol && n.level > 0) {
                tsr_qnode up = {n.x >> 1, n.y >> 1, (uint8_t)(n.level - 1)};
                int dx = e == 1 ? 1 : e == 3 ? -1 : 0, dy = e == 0 ? -1 : e == 2 ? 1 : 0;
                if ((dx < 0 && up.x == 0) || (dy < 0 && up.y == 0))
                    continue; /* no neighbour: cannot be stitched */
                node_force(c, (tsr_qnode){up.x + (uint32_t)dx, up.y + (uint32_t)dy, up.level});
                marked++;
            }
            d = fmax(d, ds);
        }
        *bound = fmax(*bound, d);
    }
    return marked;
}

/* Makes act[] of the linked edges from the leaves, at the resolution of
 * the deepest leaf (a small tree's arrays stay small). false: out of
 * memory. */
static bool collect_spans(pctx *c)
{
    uint32_t nl = tsr_quadtree_leaf_count(c->qt), deepest = 0;
    const tsr_qleaf *lv = tsr_quadtree_leaves(c->qt);
    const piece *p = &c->m->pieces[c->piece];
    for (uint32_t i = 0; i < nl; i++)
        deepest = lv[i].node.level > deepest ? lv[i].node.level : deepest;
    c->act_shift = (uint8_t)(c->surf.levels - deepest);
    for (int e = 0; e < 4; e++) {
        tsr_free(c->alloc, c->act[e]);
        c->act[e] = NULL;
        if (p->nlinks[e] && !(c->act[e] = tsr_alloc(c->alloc, (size_t)1 << deepest)))
            return false;
        if (c->act[e])
            memset(c->act[e], 0, (size_t)1 << deepest);
    }
    for (uint32_t i = 0; i < nl; i++)
        for (int e = 0; e < 4; e++) {
            uint32_t k0, k1;
            if (c->act[e] && node_edge_range(c, lv[i].node, e, &k0, &k1))
                memset(c->act[e] + (k0 >> c->act_shift), (int)(c->surf.levels - lv[i].node.level),
                       (k1 - k0) >> c->act_shift);
        }
    return true;
}

/* ---- vertex welding ------------------------------------------------------------ */

typedef struct lpoint {
    uint32_t piece, i, j;
} lpoint;

static uint64_t lkey(lpoint p) { return (uint64_t)p.piece << 40 | (uint64_t)p.j << 20 | p.i; }

static uint32_t lattice_size(const pctx *ctx, uint32_t piece) { return ctx[piece].N << ctx[piece].surf.levels; }

static lpoint edge_point(const pctx *ctx, uint32_t piece, int e, uint32_t T)
{
    uint32_t Z = lattice_size(ctx, piece);
    switch (e) {
    case 0: return (lpoint){piece, T, 0};
    case 1: return (lpoint){piece, Z, T};
    case 2: return (lpoint){piece, T, Z};
    default: return (lpoint){piece, 0, T};
    }
}

enum { CANON_CACHE = 256 };

typedef struct canon_buf {
    lpoint *p;
    uint32_t n, cap;
    /* the last answers of the general case (corners, collapsed edges),
     * direct-mapped by the start's key: every tile at a corner asks */
    struct {
        uint64_t key; /* 1 + lkey of the start; 0: empty */
        lpoint out;
    } cache[CANON_CACHE];
} canon_buf;

/* The neighbour's lattice point S along its edge for point T of edge e
 * (lattice size Zq) through link l, if the neighbour's lattice has one
 * there (the two lattices may differ in density). */
static bool link_map(const pctx *ctx, const plink *l, uint32_t Zq, uint32_t T, uint32_t *S)
{
    uint32_t t0 = l->t0 * Zq / 2, t1 = l->t1 * Zq / 2;
    if (T < t0 || T > t1)
        return false;
    uint32_t Zn = lattice_size(ctx, l->piece), s0 = l->s0 * Zn / 2;
    uint64_t B = (uint64_t)(l->s0 > l->s1 ? l->s0 - l->s1 : l->s1 - l->s0) * Zn / 2, num = (uint64_t)(T - t0) * B;
    if (num % (t1 - t0))
        return false;
    uint32_t d = (uint32_t)(num / (t1 - t0));
    *S = l->reversed ? s0 - d : s0 + d;
    return true;
}

static bool canon_push(canon_buf *b, lpoint q, const tsr_allocator *a)
{
    for (uint32_t i = 0; i < b->n; i++)
        if (b->p[i].piece == q.piece && b->p[i].i == q.i && b->p[i].j == q.j)
            return true;
    if (b->n == b->cap) {
        uint32_t cap = b->cap ? 2 * b->cap : 32;
        lpoint *np = tsr_realloc(a, b->p, cap * sizeof *np);
        if (!np)
            return false;
        b->p = np;
        b->cap = cap;
    }
    b->p[b->n++] = q;
    return true;
}

/* The canonical lattice point of (piece, i, j): the smallest key among all
 * the points the links and collapsed edges make equal to it. */
static bool canonical(const tsr_pmodel *m, const pctx *ctx, lpoint start, canon_buf *b, const tsr_allocator *a,
                      lpoint *out)
{
    uint32_t Z = lattice_size(ctx, start.piece);
    if (start.i > 0 && start.i < Z && start.j > 0 && start.j < Z) {
        *out = start;
        return true;
    }
    /* a point on a collapsed edge stands for the edge's first corner */
    const piece *ps = &m->pieces[start.piece];
    bool moved = false;
    for (int e = 0; e < 4; e++) {
        bool on = e == 0 ? start.j == 0 : e == 1 ? start.i == Z : e == 2 ? start.j == Z : start.i == 0;
        if (on && (ps->collapsed >> e & 1)) {
            start = edge_point(ctx, start.piece, e, 0);
            moved = true;
            break;
        }
    }
    if (!moved) {
        /* the common case: inside one edge, one link each way, the
         * neighbour's point inside its edge: the two points, or one */
        int on = 0, e1 = -1;
        for (int e = 0; e < 4; e++)
            if (e == 0 ? start.j == 0 : e == 1 ? start.i == Z : e == 2 ? start.j == Z : start.i == 0)
                on++, e1 = e;
        if (on == 1 && ps->nlinks[e1] <= 1) {
            uint32_t T = (e1 & 1) ? start.j : start.i, S;
            if (!ps->nlinks[e1] || !link_map(ctx, &ps->link[e1][0], Z, T, &S)) {
                *out = start;
                return true;
            }
            const plink *l = &ps->link[e1][0];
            const piece *pn = &m->pieces[l->piece];
            if (S > 0 && S < lattice_size(ctx, l->piece) && !(pn->collapsed >> l->edge & 1) &&
                pn->nlinks[l->edge] == 1 && pn->link[l->edge][0].piece == start.piece &&
                pn->link[l->edge][0].edge == e1) {
                lpoint q = edge_point(ctx, l->piece, l->edge, S);
                *out = lkey(q) < lkey(start) ? q : start;
                return true;
            }
        }
    }
    uint64_t ck = lkey(start) + 1;
    uint32_t slot = (uint32_t)((ck * 0x9E3779B97F4A7C15ull) >> 56) & (CANON_CACHE - 1);
    if (b->cache[slot].key == ck) {
        *out = b->cache[slot].out;
        return true;
    }
    b->n = 0;
    if (!canon_push(b, start, a))
        return false;
    for (uint32_t h = 0; h < b->n; h++) {
        lpoint q = b->p[h];
        const piece *pq = &m->pieces[q.piece];
        uint32_t Zq = lattice_size(ctx, q.piece);
        for (int e = 0; e < 4; e++) {
            bool on = e == 0 ? q.j == 0 : e == 1 ? q.i == Zq : e == 2 ? q.j == Zq : q.i == 0;
            if (!on)
                continue;
            uint32_t T = (e & 1) ? q.j : q.i, S;
            if (pq->collapsed >> e & 1) {
                if (!canon_push(b, edge_point(ctx, q.piece, e, 0), a) || !canon_push(b, edge_point(ctx, q.piece, e, Zq), a))
                    return false;
                continue;
            }
            for (int k = 0; k < pq->nlinks[e]; k++) {
                const plink *l = &pq->link[e][k];
                if (link_map(ctx, l, Zq, T, &S) && !canon_push(b, edge_point(ctx, l->piece, l->edge, S), a))
                    return false;
            }
        }
    }
    lpoint best = b->p[0];
    for (uint32_t h = 1; h < b->n; h++)
        if (lkey(b->p[h]) < lkey(best))
            best = b->p[h];
    *out = best;
    b->cache[slot].key = ck;
    b->cache[slot].out = best;
    return true;
}

/* ---- run ------------------------------------------------------------------- */

static double now_s(void)
{
    struct timespec t;
    clock_gettime(CLOCK_MONOTONIC, &t);
    return (double)t.tv_sec + 1e-9 * (double)t.tv_nsec;
}

typedef struct builder {
    const tsr_pmodel *m;
    const tsr_ptess_options *opt;
    pctx *ctx;
    tsr_ptess_result *out;
    const tsr_allocator *a;
    tsr_keymap map;
    canon_buf cb;
    uint32_t tri_cap;
    uint8_t *used; /* per stitch mask, per tile vertex: used by the pattern */
    double *tile_pos; /* 3 (N+1)^2 */
    double *tile_tmp; /* 3 (N+1)^2, and 2 (N+1) (MAX_DEGREE+1) Bernstein values */
    double *vert_uv;  /* 2 (N+1)^2: the source's (u, v) of the tile's vertices */
    uint32_t *tile_idx; /* (N+1)^2: a subd tile's points in its piece's memo */
    struct fpoint *fp; /* a neighbour's samples on a border segment (edge_foreign) */
    uint32_t nfp, capfp;
    struct pvert *pv;  /* their vertices */
    uint32_t cappv;
    uint8_t *onmask;   /* per tile vertex: bit e set when on the tile's edge e */
    /* the Bézier piece being emitted: the mesh vertex of each lattice
     * point inside it (not on its border: no other piece has those), at
     * the spacing of its finest leaves (UINT32_MAX: none yet); NULL when
     * such a grid would be too sparse, and the map serves */
    uint32_t *grid, *grid_mem; /* (grid_mem: the block, grid_cap entries) */
    size_t grid_cap;
    uint32_t grid_row, grid_shift, grid_piece;
    /* trim points of trimmed sources on a linked border (where a hole
     * crosses a patch edge): welded to the other side's (weld_trim_points) */
    struct etrim *et;
    uint32_t net, capet;
} builder;

typedef struct etrim {
    uint32_t v, src;
    int side; /* of the source's domain (piece edge numbering) */
    float p[3];
} etrim;

static uint32_t new_vertex(builder *b, const piece *p, const double pos[3], const double *nrm)
{
    double nr[3] = {0, 0, 1};
    if (nrm)
        for (int k = 0; k < 3; k++)
            nr[k] = p->mirrored ? -nrm[k] : nrm[k];
    float fp[3] = {(float)pos[0], (float)pos[1], (float)pos[2]}, fn[3] = {(float)nr[0], (float)nr[1], (float)nr[2]};
    return tsr_mesh_add_vertex(&b->out->mesh, fp, b->opt->normals ? fn : NULL, NULL);
}

/* A Bézier piece's point at (s, t): the tensor-product Bernstein sum. */
static void bez_point(const tsr_patch *p, double s, double t, double pos[3])
{
    double Bu[TSR_PATCH_MAX_DEGREE + 1], Bv[TSR_PATCH_MAX_DEGREE + 1], h[4] = {0, 0, 0, 0};
    int nu = p->degree_u + 1;
    bernstein(p->degree_u, s, Bu);
    bernstein(p->degree_v, t, Bv);
    for (int j = 0; j <= p->degree_v; j++)
        for (int i = 0; i < nu; i++) {
            int k = j * nu + i;
            double f = Bu[i] * Bv[j] * (p->weights ? p->weights[k] : 1);
            h[0] += f * p->ctrl[3 * k];
            h[1] += f * p->ctrl[3 * k + 1];
            h[2] += f * p->ctrl[3 * k + 2];
            h[3] += f;
        }
    for (int c = 0; c < 3; c++)
        pos[c] = p->weights ? h[c] / h[3] : h[c];
}

/* Position and normal of a subd piece's lattice point q, evaluated (and
 * counted). */
static void subd_lattice_eval(builder *b, lpoint q, double pos[3], double nr[3])
{
    const piece *p = &b->m->pieces[q.piece];
    uint32_t Z = lattice_size(b->ctx, q.piece);
    subd_point(b->m->subd, p->face, p->sub, (double)q.i / Z, (double)q.j / Z, pos, nr);
    b->out->evaluations++;
}

/* Mesh vertex of lattice point q of a subd piece, qi its index in the
 * piece's memo (UINT32_MAX: not known): as vertex_of, kept with the
 * canonical point's memo entry (vid) instead of in the builder's map, so
 * a point inside a piece costs no lookup. The position: pre, else the
 * canonical point's from the memo (evaluated when missing); with normals
 * evaluated there with its normal. */
static uint32_t subd_vertex(builder *b, lpoint q, uint32_t qi, const double *pre)
{
    uint32_t Zq = lattice_size(b->ctx, q.piece);
    if (qi != UINT32_MAX && q.i > 0 && q.j > 0 && q.i < Zq && q.j < Zq) {
        /* inside its piece: its own canonical point, vertex made or kept */
        pctx *c = &b->ctx[q.piece];
        if (c->vid[qi] == UINT32_MAX && pre && !b->opt->normals)
            c->vid[qi] = new_vertex(b, &b->m->pieces[q.piece], pre, NULL);
        if (c->vid[qi] != UINT32_MAX)
            return c->vid[qi];
    }
    lpoint cq;
    if (!canonical(b->m, b->ctx, q, &b->cb, b->a, &cq))
        return UINT32_MAX;
    pctx *c = &b->ctx[cq.piece];
    const piece *p = &b->m->pieces[cq.piece];
    bool want_n = b->opt->normals, evaluated = false;
    double pos[3], nr[3] = {0, 0, 1};
    uint32_t ci = qi;
    if (ci == UINT32_MAX || cq.piece != q.piece || cq.i != q.i || cq.j != q.j) {
        if (!pre && !want_n) { /* the canonical point's position, from the memo or evaluated */
            uint32_t ij[2] = {cq.i, cq.j};
            if (!subd_points(c, ij, 1, pos))
                return UINT32_MAX;
            ci = c->idx[0];
        } else {
            bool found;
            uint32_t *slot = memo_room(c, 1) ? tsr_keymap_slot(&c->pmemo, pkey(cq.i, cq.j), &found, b->a) : NULL;
            if (!slot)
                return UINT32_MAX;
            if (!found) { /* not read by its piece's selection: kept at pre, or evaluated */
                if (want_n) {
                    subd_lattice_eval(b, cq, pos, nr);
                    evaluated = true;
                }
                memcpy(c->pts + 3 * (size_t)c->npts, want_n ? pos : pre, 3 * sizeof *pos);
                c->vid[c->npts] = UINT32_MAX;
                *slot = c->npts++;
            }
            ci = *slot;
        }
    }
    if (c->vid[ci] != UINT32_MAX)
        return c->vid[ci];
    if (want_n && !evaluated) {
        subd_lattice_eval(b, cq, pos, nr);
    } else if (!want_n) {
        memcpy(pos, pre ? pre : c->pts + 3 * (size_t)ci, sizeof pos);
    }
    c->vid[ci] = new_vertex(b, p, pos, want_n ? nr : NULL);
    return c->vid[ci];
}

/* Mesh vertex of lattice point q: made once, for its canonical point, at
 * pre when not NULL (q's own position: the points a link or collapsed edge
 * makes equal differ by rounding only), else evaluated at the canonical
 * point. qi: for a subd piece, q's index in its memo, or UINT32_MAX. */
static uint32_t bez_vertex(builder *b, lpoint c, const double *pre);

static uint32_t vertex_of(builder *b, lpoint q, const double *pre, uint32_t qi)
{
    if (b->m->pieces[q.piece].kind == KIND_SUBD)
        return subd_vertex(b, q, qi, pre);
    uint32_t Z = lattice_size(b->ctx, q.piece);
    if (b->grid && q.piece == b->grid_piece && q.i > 0 && q.j > 0 && q.i < Z && q.j < Z) { /* its own canonical point */
        uint32_t *slot = b->grid + (size_t)(q.j >> b->grid_shift) * b->grid_row + (q.i >> b->grid_shift);
        if (*slot == UINT32_MAX)
            *slot = bez_vertex(b, q, pre);
        return *slot;
    }
    lpoint c;
    if (!canonical(b->m, b->ctx, q, &b->cb, b->a, &c))
        return UINT32_MAX;
    bool found;
    uint32_t *slot = tsr_keymap_slot(&b->map, lkey(c), &found, b->a);
    if (!slot)
        return UINT32_MAX;
    if (!found)
        *slot = bez_vertex(b, c, pre);
    return *slot;
}

/* A new mesh vertex for canonical lattice point c of a Bézier piece: at
 * pre, else evaluated there (with its normal when the run makes them). */
static uint32_t bez_vertex(builder *b, lpoint c, const double *pre)
{
    const piece *p = &b->m->pieces[c.piece];
    bool want_n = b->opt->normals;
    double pos[3], nr[3] = {0, 0, 1};
    if (pre && !want_n) {
        memcpy(pos, pre, sizeof pos);
    } else {
        uint32_t Z = lattice_size(b->ctx, c.piece);
        double s = (double)c.i / Z, t = (double)c.j / Z;
        if (!want_n) /* a Bézier piece: subd pieces are subd_vertex's */
            bez_point(&p->bez, s, t, pos);
        else
            tsr_patch_eval(&p->bez, s, t, pos, NULL, NULL, nr);
        b->out->evaluations++;
    }
    return new_vertex(b, p, pos, want_n ? nr : NULL);
}

/* The tensor-product sums of tile_positions: per row j the column sums
 * Q_a = sum_b Bv_b w_ab P_ab (homogeneous), then per used vertex sum_a
 * Bu_a Q_a. Inlined, so that constant degrees unroll. */
static inline void bez_tile(const double *C, const double *W, int du, int dv, const double *Bu, const double *Bv,
                            uint32_t N, const uint8_t *used, double *P)
{
    uint32_t row = N + 1;
    int nu = du + 1;
    for (uint32_t j = 0; j <= N; j++) {
        double Q[TSR_PATCH_MAX_DEGREE + 1][4];
        const double *bv = Bv + (size_t)j * (TSR_PATCH_MAX_DEGREE + 1);
        for (int a2 = 0; a2 < nu; a2++) {
            double q0 = 0, q1 = 0, q2 = 0, q3 = 0;
            for (int b2 = 0; b2 <= dv; b2++) {
                double w = W ? W[b2 * nu + a2] : 1, f = bv[b2] * w;
                const double *c = C + 3 * (b2 * nu + a2);
                q0 += f * c[0];
                q1 += f * c[1];
                q2 += f * c[2];
                q3 += f;
            }
            Q[a2][0] = q0;
            Q[a2][1] = q1;
            Q[a2][2] = q2;
            Q[a2][3] = q3;
        }
        for (uint32_t i = 0; i <= N; i++) {
            if (!used[j * row + i])
                continue;
            const double *bu = Bu + (size_t)i * (TSR_PATCH_MAX_DEGREE + 1);
            double x = 0, y = 0, z = 0, w = 0;
            for (int a2 = 0; a2 < nu; a2++) {
                x += bu[a2] * Q[a2][0];
                y += bu[a2] * Q[a2][1];
                z += bu[a2] * Q[a2][2];
                if (W)
                    w += bu[a2] * Q[a2][3];
            }
            double *o = P + 3 * (j * row + i);
            if (W) {
                o[0] = x / w;
                o[1] = y / w;
                o[2] = z / w;
            } else {
                o[0] = x;
                o[1] = y;
                o[2] = z;
            }
        }
    }
}

/* Positions of a leaf's tile vertices (those used set in used) into P
 * (3 per vertex, (N+1)^2): a tensor-product evaluation for a Bézier piece
 * (the Bernstein values of the tile's columns and rows, then per vertex
 * one (du+1)(dv+1) sum); for a subdivision face from the piece's memo
 * (the tile's indices kept with the node, else looked up, the missing
 * points evaluated in one batch), their indices into b->tile_idx. */
static bool tile_positions(builder *b, uint32_t pi, tsr_qnode n, double r[4], uint32_t N, const uint8_t *used,
                           double *P)
{
    const piece *p = &b->m->pieces[pi];
    uint32_t row = N + 1;
    if (p->kind == KIND_SUBD) {
        pctx *c = &b->ctx[pi];
        const nodeval *v = node_info(c, n);
        if (v->tile != UINT32_MAX) { /* kept when the node was computed */
            const uint32_t *ti = c->tidx + (size_t)v->tile * tile_stride(c);
            for (uint32_t k = 0; k < row * row; k++)
                if (used[k]) {
                    memcpy(P + 3 * k, c->pts + 3 * (size_t)ti[k], 3 * sizeof *P);
                    b->tile_idx[k] = ti[k];
                }
            return true;
        }
        uint32_t cnt = 0, sh = c->surf.levels - n.level, *ij = c->ij;
        for (uint32_t j = 0; j <= N; j++)
            for (uint32_t i = 0; i <= N; i++)
                if (used[j * row + i]) {
                    ij[2 * cnt] = (n.x * N + i) << sh;
                    ij[2 * cnt + 1] = (n.y * N + j) << sh;
                    cnt++;
                }
        if (!subd_points(c, ij, cnt, b->tile_tmp))
            return false;
        cnt = 0;
        for (uint32_t k = 0; k < row * row; k++)
            if (used[k]) {
                memcpy(P + 3 * k, b->tile_tmp + 3 * cnt, 3 * sizeof *P);
                b->tile_idx[k] = c->idx[cnt];
                cnt++;
            }
        return true;
    }
    int du = p->bez.degree_u, dv = p->bez.degree_v;
    double *Bu = b->tile_tmp, *Bv = Bu + (size_t)row * (TSR_PATCH_MAX_DEGREE + 1);
    for (uint32_t i = 0; i <= N; i++) {
        double s = r[0] + (r[1] - r[0]) * i / N;
        if (i == N)
            s = r[1];
        bernstein(du, s, Bu + (size_t)i * (TSR_PATCH_MAX_DEGREE + 1));
    }
    for (uint32_t j = 0; j <= N; j++) {
        double t = r[2] + (r[3] - r[2]) * j / N;
        if (j == N)
            t = r[3];
        bernstein(dv, t, Bv + (size_t)j * (TSR_PATCH_MAX_DEGREE + 1));
    }
    if (!p->bez.weights && du == 3 && dv == 3)
        bez_tile(p->bez.ctrl, NULL, 3, 3, Bu, Bv, N, used, P); /* constants: unrolled */
    else
        bez_tile(p->bez.ctrl, p->bez.weights, du, dv, Bu, Bv, N, used, P);
    b->out->evaluations += row * row;
    return true;
}

static bool add_tri(builder *b, uint32_t source, const uint32_t v[3], const double uv[6])
{
    tsr_ptess_result *r = b->out;
    if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
        return true;
    if (r->mesh.triangle_count >= b->tri_cap) {
        uint32_t cap = b->tri_cap ? 2 * b->tri_cap : 4096;
        uint32_t *ns = tsr_realloc(b->a, r->tri_source, (size_t)cap * sizeof *ns);
        if (!ns)
            return false;
        r->tri_source = ns;
        double *nu = tsr_realloc(b->a, r->tri_uv, (size_t)cap * 6 * sizeof *nu);
        if (!nu)
            return false;
        r->tri_uv = nu;
        b->tri_cap = cap;
    }
    uint32_t k = r->mesh.triangle_count;
    if (!tsr_mesh_add_triangle(&r->mesh, v[0], v[1], v[2]))
        return false;
    r->tri_source[k] = source;
    memcpy(r->tri_uv + 6 * (size_t)k, uv, 6 * sizeof *uv);
    return true;
}

/* The source's (u, v) of (s, t) on piece p (the rectangle's ends exact). */
static void piece_uv(const piece *p, double s, double t, double uv[2])
{
    uv[0] = s == 1 ? p->rect[1] : p->rect[0] + s * (p->rect[1] - p->rect[0]);
    uv[1] = t == 1 ? p->rect[3] : p->rect[2] + t * (p->rect[3] - p->rect[2]);
}

/* ---- linked borders: the neighbour's samples too --------------------------- */

/* A sample of a linked neighbour strictly inside a border segment of a
 * tile: its lattice point, and its parameter T along the edge in this
 * piece's lattice units (not an integer where the lattices differ). */
typedef struct fpoint {
    double T;
    lpoint q;
} fpoint;

static bool fp_push(builder *b, fpoint x)
{
    if (b->nfp == b->capfp) {
        uint32_t cap = b->capfp ? 2 * b->capfp : 64;
        fpoint *np = tsr_realloc(b->a, b->fp, (size_t)cap * sizeof *np);
        if (!np)
            return false;
        b->fp = np;
        b->capfp = cap;
    }
    b->fp[b->nfp++] = x;
    return true;
}

/* Appends to b->fp, in increasing T, the samples of the leaves of the
 * pieces linked along edge e of piece pi that lie strictly between Ta <
 * Tb (lattice units of pi along e). A neighbour's edge samples are its
 * border leaves' lattice points (a border leaf is never stitched there:
 * it has no neighbour in its own tree), every 2^w units in a leaf of span
 * log w (act[]). Exact: positions compare in integers. */
static bool edge_foreign(builder *b, uint32_t pi, int e, uint32_t Ta, uint32_t Tb)
{
    const piece *p = &b->m->pieces[pi];
    uint32_t Z = lattice_size(b->ctx, pi), start = b->nfp;
    for (int k = 0; k < p->nlinks[e]; k++) {
        const plink *l = &p->link[e][k];
        const pctx *q = &b->ctx[l->piece];
        const uint8_t *act = q->act[l->edge];
        uint64_t t0 = (uint64_t)l->t0 * Z / 2, t1 = (uint64_t)l->t1 * Z / 2;
        uint64_t lo = Ta > t0 ? Ta : t0, hi = Tb < t1 ? Tb : t1;
        if (!act || lo >= hi)
            continue;
        uint64_t Zq = lattice_size(b->ctx, l->piece), Nq = q->N, Mq = (uint64_t)1 << q->surf.levels;
        uint64_t A = t1 - t0, B = (uint64_t)(l->s0 > l->s1 ? l->s0 - l->s1 : l->s1 - l->s0) * Zq / 2,
                 s0 = (uint64_t)l->s0 * Zq / 2;
        /* d = (T - t0) B / A from s0 along the neighbour's edge */
        uint64_t dlo = (lo - t0) * B / A, dhi = ((hi - t0) * B + A - 1) / A;
        uint64_t Slo = l->reversed ? s0 - dhi : s0 + dlo, Shi = l->reversed ? s0 - dlo : s0 + dhi;
        uint32_t before = b->nfp;
        for (uint64_t S = Slo; S <= Shi;) {
            uint64_t g = S / Nq < Mq ? S / Nq : Mq - 1, step = (uint64_t)1 << act[g >> q->act_shift];
            if (S % step) {
                S = (S / step + 1) * step;
                continue;
            }
            uint64_t d = l->reversed ? s0 - S : S - s0;
            if (d * A > (lo - t0) * B && d * A < (hi - t0) * B &&
                !fp_push(b, (fpoint){(double)t0 + (double)d * (double)A / (double)B,
                                     edge_point(b->ctx, l->piece, l->edge, (uint32_t)S)}))
                return false;
            S += step;
        }
        if (l->reversed)
            for (uint32_t i = before, j = b->nfp; i + 1 < j; i++, j--) {
                fpoint t = b->fp[i];
                b->fp[i] = b->fp[j - 1];
                b->fp[j - 1] = t;
            }
    }
    for (uint32_t i = start + 1; i < b->nfp; i++) /* links in any order */
        for (uint32_t j = i; j > start && b->fp[j - 1].T > b->fp[j].T; j--) {
            fpoint t = b->fp[j];
            b->fp[j] = b->fp[j - 1];
            b->fp[j - 1] = t;
        }
    return true;
}

typedef struct pvert {
    uint32_t v;
    double uv[2];
} pvert;

typedef struct pchain {
    const pvert *p;
    uint32_t n;
} pchain;

/* Triangle t (emitted order) with extra points ch[k] on its edge t[k] ->
 * t[k+1], in that order: split into a fan from the opposite corner, the
 * first and last parts taking the chains of the other edges. Every part
 * lies within t in (u, v), so its interpolation error is within t's
 * bound (the barycentric variances of a part's corners are at most t's:
 * each corner is a mean of t's). */
static bool emit_split(builder *b, uint32_t source, const pvert t[3], const pchain ch[3])
{
    int k = 0;
    while (k < 3 && !ch[k].n)
        k++;
    if (k == 3) {
        uint32_t v[3] = {t[0].v, t[1].v, t[2].v};
        double uv[6] = {t[0].uv[0], t[0].uv[1], t[1].uv[0], t[1].uv[1], t[2].uv[0], t[2].uv[1]};
        return add_tri(b, source, v, uv);
    }
    const pchain *c = &ch[k];
    pvert a = t[k], z = t[(k + 1) % 3], o = t[(k + 2) % 3];
    pvert t1[3] = {a, c->p[0], o}, t2[3] = {c->p[c->n - 1], z, o};
    pchain c1[3] = {{NULL, 0}, {NULL, 0}, ch[(k + 2) % 3]}, c2[3] = {{NULL, 0}, ch[(k + 1) % 3], {NULL, 0}};
    if (!emit_split(b, source, t1, c1))
        return false;
    for (uint32_t i = 0; i + 1 < c->n; i++) {
        pvert tm[3] = {c->p[i], c->p[i + 1], o};
        pchain cm[3] = {{NULL, 0}, {NULL, 0}, {NULL, 0}};
        if (!emit_split(b, source, tm, cm))
            return false;
    }
    return emit_split(b, source, t2, c2);
}

/* Sets up b->grid for a Bézier piece of lattice size Z with leaves lv:
 * at the spacing of its finest leaves when that grid has at most 16 times
 * the points its tiles have (else NULL: the map serves); false when out
 * of memory. */
static bool grid_of(builder *b, uint32_t pi, const tsr_qleaf *lv, uint32_t nl, uint32_t Z)
{
    const pctx *c = &b->ctx[pi];
    b->grid_piece = pi;
    uint32_t deepest = 0, row = c->N + 1;
    for (uint32_t li = 0; li < nl; li++)
        deepest = lv[li].node.level > deepest ? lv[li].node.level : deepest;
    b->grid = NULL;
    b->grid_shift = c->surf.levels - deepest;
    b->grid_row = (Z >> b->grid_shift) + 1;
    size_t n = (size_t)b->grid_row * b->grid_row;
    if (n > (size_t)16 * nl * row * row || n > ((size_t)1 << 22))
        return true;
    if (n > b->grid_cap) {
        tsr_free(b->a, b->grid_mem);
        b->grid_cap = 0;
        if (!(b->grid_mem = tsr_alloc(b->a, n * sizeof *b->grid_mem)))
            return false;
        b->grid_cap = n;
    }
    b->grid = b->grid_mem;
    memset(b->grid, 0xff, n * sizeof *b->grid);
    return true;
}

static tsr_status emit_piece(builder *b, uint32_t pi, const patcache *pc, uint32_t *local)
{
    const tsr_tile_patterns *pat = &pc->pat;
    pctx *c = &b->ctx[pi];
    const piece *p = &b->m->pieces[pi];
    uint32_t N = c->N, row = N + 1, Z = lattice_size(b->ctx, pi);
    uint32_t nl = tsr_quadtree_leaf_count(c->qt);
    const tsr_qleaf *lv = tsr_quadtree_leaves(c->qt);
    for (uint32_t j = 0; j <= N; j++)
        for (uint32_t i = 0; i <= N; i++)
            b->onmask[j * row + i] = (uint8_t)tile_onmask(i, j, N);
    if (p->kind != KIND_SUBD && !grid_of(b, pi, lv, nl, Z))
        return TSR_ERR_NOMEM;
    for (uint32_t li = 0; li < nl; li++) {
        tsr_qnode n = lv[li].node;
        uint32_t w = N << (c->surf.levels - n.level), step = w / N, x0 = n.x * w, y0 = n.y * w;
        unsigned mask = lv[li].stitch & 15;
        const uint8_t *used = b->used + (size_t)mask * row * row;
        double r[4];
        node_rect(c, n, r);
        bool subd = p->kind == KIND_SUBD;
        bool have = (subd || !b->opt->normals) && tile_positions(b, pi, n, r, N, used, b->tile_pos);
        if (subd && !have)
            return TSR_ERR_NOMEM; /* (the only way a subd tile's points fail) */
        bool pre = have && !b->opt->normals;
        double *vuv = b->vert_uv;
        for (uint32_t j = 0; j <= N; j++)
            for (uint32_t i = 0; i <= N; i++) {
                if (!used[j * row + i])
                    continue;
                const double *pp = pre ? b->tile_pos + 3 * (j * row + i) : NULL;
                uint32_t v;
                if (pre && i > 0 && j > 0 && i < N && j < N)
                    v = new_vertex(b, p, pp, NULL); /* inside the tile: no other tile has it */
                else
                    v = vertex_of(b, (lpoint){pi, x0 + i * step, y0 + j * step}, pp,
                                  subd ? b->tile_idx[j * row + i] : UINT32_MAX);
                if (v == UINT32_MAX)
                    return TSR_ERR_NOMEM;
                local[j * row + i] = v;
                double s = (double)(x0 + i * step) / Z, tt = (double)(y0 + j * step) / Z;
                double *o = vuv + 2 * (j * row + i);
                piece_uv(p, s, tt, o);
            }
        /* tile edges on a linked border: the neighbour's samples there too */
        unsigned lmask = 0;
        for (int e = 0; e < 4; e++) {
            uint32_t k0, k1;
            if (c->act[e] && node_edge_range(c, n, e, &k0, &k1))
                lmask |= 1u << e;
        }
        const uint32_t *tri = pat->tri[mask];
        if (!lmask) { /* no linked piece edge: the pattern's triangles as they are */
            int i1 = p->mirrored ? 2 : 1, i2 = p->mirrored ? 1 : 2;
            for (uint32_t t = 0; t < pat->count[mask]; t++) {
                uint32_t a0 = tri[3 * t], a1 = tri[3 * t + i1], a2 = tri[3 * t + i2];
                uint32_t v[3] = {local[a0], local[a1], local[a2]};
                double uv[6] = {vuv[2 * a0], vuv[2 * a0 + 1], vuv[2 * a1], vuv[2 * a1 + 1], vuv[2 * a2], vuv[2 * a2 + 1]};
                if (!add_tri(b, p->source, v, uv))
                    return TSR_ERR_NOMEM;
            }
            continue;
        }
        const uint16_t *ton = pc->on[mask];
        unsigned lmask3 = lmask | lmask << 4 | lmask << 8;
        for (uint32_t t = 0; t < pat->count[mask]; t++) {
            uint32_t idx[3] = {tri[3 * t], tri[3 * t + 1], tri[3 * t + 2]};
            if (p->mirrored) {
                uint32_t tmp = idx[1];
                idx[1] = idx[2];
                idx[2] = tmp;
            }
            if (!(ton[t] & lmask3)) { /* no edge on a linked tile edge */
                uint32_t v[3] = {local[idx[0]], local[idx[1]], local[idx[2]]};
                double uv[6] = {vuv[2 * idx[0]], vuv[2 * idx[0] + 1], vuv[2 * idx[1]],
                                vuv[2 * idx[1] + 1], vuv[2 * idx[2]], vuv[2 * idx[2] + 1]};
                if (!add_tri(b, p->source, v, uv))
                    return TSR_ERR_NOMEM;
                continue;
            }
            pvert tv[3];
            for (int k = 0; k < 3; k++)
                tv[k] = (pvert){local[idx[k]], {vuv[2 * idx[k]], vuv[2 * idx[k] + 1]}};
            uint32_t off[3] = {0}, cnt[3] = {0};
            int ek[3] = {0, 0, 0};
            b->nfp = 0;
            for (int k = 0; lmask && k < 3; k++) {
                unsigned on = b->onmask[idx[k]] & b->onmask[idx[(k + 1) % 3]] & lmask;
                if (!on)
                    continue;
                int e = on & 1 ? 0 : on & 2 ? 1 : on & 4 ? 2 : 3;
                uint32_t i0 = idx[k] % row, j0 = idx[k] / row, i1 = idx[(k + 1) % 3] % row, j1 = idx[(k + 1) % 3] / row;
                uint32_t T0 = e & 1 ? y0 + j0 * step : x0 + i0 * step, T1 = e & 1 ? y0 + j1 * step : x0 + i1 * step;
                off[k] = b->nfp;
                ek[k] = e;
                if (!edge_foreign(b, pi, e, T0 < T1 ? T0 : T1, T0 < T1 ? T1 : T0))
                    return TSR_ERR_NOMEM;
                cnt[k] = b->nfp - off[k];
                if (T0 > T1) /* ordered from corner k to corner k + 1 */
                    for (uint32_t x = off[k], y = b->nfp; x + 1 < y; x++, y--) {
                        fpoint tmp = b->fp[x];
                        b->fp[x] = b->fp[y - 1];
                        b->fp[y - 1] = tmp;
                    }
            }
            if (!b->nfp) {
                uint32_t v[3] = {tv[0].v, tv[1].v, tv[2].v};
                double uv[6] = {tv[0].uv[0], tv[0].uv[1], tv[1].uv[0], tv[1].uv[1], tv[2].uv[0], tv[2].uv[1]};
                if (!add_tri(b, p->source, v, uv))
                    return TSR_ERR_NOMEM;
                continue;
            }
            if (b->nfp > b->cappv) {
                pvert *np = tsr_realloc(b->a, b->pv, (size_t)b->nfp * sizeof *np);
                if (!np)
                    return TSR_ERR_NOMEM;
                b->pv = np;
                b->cappv = b->nfp;
            }
            for (uint32_t x = 0; x < b->nfp; x++) {
                const fpoint *f = &b->fp[x];
                pvert *o = &b->pv[x];
                o->v = vertex_of(b, f->q, NULL, UINT32_MAX);
                if (o->v == UINT32_MAX)
                    return TSR_ERR_NOMEM;
                /* on the piece edge of its chain */
                int k = x >= off[2] && cnt[2] ? 2 : x >= off[1] && cnt[1] ? 1 : 0, e = ek[k];
                double T = f->T / Z, s = e == 1 ? 1 : e == 3 ? 0 : T, tt = e == 0 ? 0 : e == 2 ? 1 : T;
                piece_uv(p, s, tt, o->uv);
            }
            pchain ch[3];
            for (int k = 0; k < 3; k++)
                ch[k] = (pchain){b->pv + off[k], cnt[k]};
            uint32_t before = b->out->mesh.triangle_count;
            if (!emit_split(b, p->source, tv, ch))
                return TSR_ERR_NOMEM;
            b->out->fan_triangles += b->out->mesh.triangle_count - before - (b->out->mesh.triangle_count > before);
        }
    }
    return TSR_OK;
}

/* A lattice point of a trimmed source's triangulation, at (s, t) of piece
 * p, once per canonical point (seen): its (u, v) into xy, its canonical
 * key + 1 into key; both grown together (capacity *cap points). */
static tsr_status add_lattice_point(builder *b, tsr_keymap *seen, lpoint q, const piece *p, double s, double t,
                                    double **xy, uint64_t **key, size_t *np, size_t *cap)
{
    lpoint cq;
    if (!canonical(b->m, b->ctx, q, &b->cb, b->a, &cq))
        return TSR_ERR_NOMEM;
    bool found;
    uint32_t *slot = tsr_keymap_slot(seen, lkey(cq), &found, b->a);
    if (!slot)
        return TSR_ERR_NOMEM;
    double uv[2];
    piece_uv(p, s, t, uv);
    /* a point already there is not added again, but another (u, v) image
     * of it is: across a seam of the source (a closed surface's two linked
     * edges) or along a collapsed edge (a pole), both sides keep their
     * border points, welded through the key, so the triangulated domain
     * reaches the whole border */
    if (found && (*xy)[2 * *slot] == uv[0] && (*xy)[2 * *slot + 1] == uv[1])
        return TSR_OK;
    if (!found)
        *slot = (uint32_t)*np;
    if (*np + 1 > *cap) {
        double *nx = tsr_realloc(b->a, *xy, 2 * *cap * 2 * sizeof *nx);
        if (!nx)
            return TSR_ERR_NOMEM;
        *xy = nx;
        uint64_t *nk = tsr_realloc(b->a, *key, 2 * *cap * sizeof *nk);
        if (!nk)
            return TSR_ERR_NOMEM;
        *key = nk;
        *cap *= 2;
    }
    (*xy)[2 * *np] = uv[0];
    (*xy)[2 * *np + 1] = uv[1];
    (*key)[*np] = lkey(cq) + 1;
    (*np)++;
    return TSR_OK;
}

/* A trimmed source's lattice points, bucketed by cells of its finest
 * tile spacing, so that its trim loops can meet them: a loop point within
 * a hair of a lattice point becomes that point, and a loop edge passing
 * within a hair of one goes through it. Otherwise the triangulation gets
 * two vertices a rounding apart (a zero-area triangle, the point twice in
 * the mesh) or a sliver between the edge and the point (a trim edge along
 * a lattice diagonal, as u + v = 1 from (0.5, 0.5)). */
typedef struct lat_grid {
    double *xy;            /* the points (a copy) */
    double u0, v0, cu, cv; /* the domain's corner, the cells' sizes */
    tsr_keymap head;       /* cell -> its first point */
    uint32_t *next;        /* per point: the next in its cell, UINT32_MAX at the end */
} lat_grid;

static uint64_t lat_cell(const lat_grid *g, double u, double v, int64_t di, int64_t dj)
{
    double fu = floor((u - g->u0) / g->cu), fv = floor((v - g->v0) / g->cv);
    int64_t i = (fu > -1e9 && fu < 1e9 ? (int64_t)fu : 0) + di, j = (fv > -1e9 && fv < 1e9 ? (int64_t)fv : 0) + dj;
    /* (biased: no cell's key is the keymap's forbidden UINT64_MAX) */
    return (uint64_t)((uint32_t)i + 0x80000000u) << 32 | ((uint32_t)j + 0x80000000u);
}

static bool lat_build(lat_grid *g, const double *xy, uint32_t n, const double dom[4], double hu, double hv,
                      const tsr_allocator *a)
{
    memset(g, 0, sizeof *g);
    g->u0 = dom[0];
    g->v0 = dom[2];
    g->cu = hu > 0 && isfinite(hu) ? hu : dom[1] - dom[0];
    g->cv = hv > 0 && isfinite(hv) ? hv : dom[3] - dom[2];
    g->next = tsr_alloc(a, ((size_t)n + 1) * sizeof *g->next);
    g->xy = tsr_alloc(a, ((size_t)n + 1) * 2 * sizeof *g->xy);
    if (!g->next || !g->xy || !tsr_keymap_reserve(&g->head, n, a))
        return false;
    memcpy(g->xy, xy, (size_t)n * 2 * sizeof *xy);
    for (uint32_t k = 0; k < n; k++) {
        bool found;
        uint32_t *slot = tsr_keymap_slot(&g->head, lat_cell(g, xy[2 * k], xy[2 * k + 1], 0, 0), &found, a);
        if (!slot)
            return false;
        g->next[k] = found ? *slot : UINT32_MAX;
        *slot = k;
    }
    return true;
}

static void lat_free(lat_grid *g, const tsr_allocator *a)
{
    tsr_free(a, g->next);
    tsr_free(a, g->xy);
    tsr_keymap_free(&g->head, a);
}

/* The lattice point within (eu, ev) of p (each way), or UINT32_MAX. */
static uint32_t lat_near(const lat_grid *g, const double p[2], double eu, double ev)
{
    for (int dj = -1; dj <= 1; dj++)
        for (int di = -1; di <= 1; di++) {
            const uint32_t *h = tsr_keymap_find(&g->head, lat_cell(g, p[0], p[1], di, dj));
            for (uint32_t k = h ? *h : UINT32_MAX; k != UINT32_MAX; k = g->next[k])
                if (fabs(g->xy[2 * k] - p[0]) <= eu && fabs(g->xy[2 * k + 1] - p[1]) <= ev)
                    return k;
        }
    return UINT32_MAX;
}

/* A lattice point met by a loop edge: its index and where along the edge. */
typedef struct lat_hit {
    double t;
    uint32_t k;
} lat_hit;

static int cmp_hit(const void *x, const void *y)
{
    double a = ((const lat_hit *)x)->t, b = ((const lat_hit *)y)->t;
    return a < b ? -1 : a > b;
}

/* The lattice points within a hair (eu, ev) of edge p0-p1 strictly
 * between its ends, into hits (at most cap), in order along the edge;
 * returns how many. Distances in units of (eu, ev). */
static uint32_t lat_on_edge(const lat_grid *g, const double p0[2], const double p1[2], double eu, double ev,
                            lat_hit *hits, uint32_t cap)
{
    double dx = (p1[0] - p0[0]) / eu, dy = (p1[1] - p0[1]) / ev, len2 = dx * dx + dy * dy;
    if (!(len2 > 4))
        return 0;
    double lo[2] = {dmin(p0[0], p1[0]) - eu, dmin(p0[1], p1[1]) - ev};
    double hi[2] = {dmax(p0[0], p1[0]) + eu, dmax(p0[1], p1[1]) + ev};
    uint64_t c0 = lat_cell(g, lo[0], lo[1], 0, 0), c1 = lat_cell(g, hi[0], hi[1], 0, 0);
    uint32_t i0 = (uint32_t)(c0 >> 32), j0 = (uint32_t)c0, i1 = (uint32_t)(c1 >> 32), j1 = (uint32_t)c1, n = 0;
    if (i1 - i0 > 64 || j1 - j0 > 64) /* (loop edges are cut to the finest spacing: not met) */
        return 0;
    for (uint32_t j = j0; j != j1 + 1; j++)
        for (uint32_t i = i0; i != i1 + 1; i++) {
            const uint32_t *h = tsr_keymap_find(&g->head, (uint64_t)i << 32 | j);
            for (uint32_t k = h ? *h : UINT32_MAX; k != UINT32_MAX; k = g->next[k]) {
                const double *q = g->xy + 2 * k;
                double qx = (q[0] - p0[0]) / eu, qy = (q[1] - p0[1]) / ev;
                double t = (qx * dx + qy * dy) / len2, cross = qx * dy - qy * dx;
                /* off the ends' own hair, within the edge's */
                if (t * t * len2 > 1 && (1 - t) * (1 - t) * len2 > 1 && t > 0 && t < 1 && cross * cross <= len2 &&
                    n < cap)
                    hits[n++] = (lat_hit){t, k};
            }
        }
    qsort(hits, n, sizeof *hits, cmp_hit);
    return n;
}

/* Meets loop pts (cnt points, owned, may be replaced) with the lattice
 * points of g: see lat_grid. false when out of memory. */
static bool lat_meet(const lat_grid *g, double **pts, uint32_t *cnt, double eu, double ev, const tsr_allocator *a)
{
    double *p = *pts;
    uint32_t n = *cnt, extra = 0;
    enum { CAP = 64 };
    lat_hit hits[CAP];
    for (uint32_t k = 0; k < n; k++) {
        uint32_t q = lat_near(g, p + 2 * k, eu, ev);
        if (q != UINT32_MAX)
            memcpy(p + 2 * k, g->xy + 2 * q, 2 * sizeof *p);
    }
    for (uint32_t k = 0; k < n; k++)
        extra += lat_on_edge(g, p + 2 * k, p + 2 * ((k + 1) % n), eu, ev, hits, CAP);
    double *out = tsr_alloc(a, ((size_t)n + extra) * 2 * sizeof *out);
    if (!out)
        return false;
    uint32_t m = 0;
    for (uint32_t k = 0; k < n; k++) {
        const double *p0 = p + 2 * k, *p1 = p + 2 * ((k + 1) % n);
        uint32_t h = extra ? lat_on_edge(g, p0, p1, eu, ev, hits, CAP) : 0;
        memcpy(out + 2 * m++, p0, 2 * sizeof *out);
        for (uint32_t x = 0; x < h; x++)
            memcpy(out + 2 * m++, g->xy + 2 * hits[x].k, 2 * sizeof *out);
    }
    /* points made equal: once */
    uint32_t w = 0;
    for (uint32_t k = 0; k < m; k++)
        if (!w || out[2 * k] != out[2 * (w - 1)] || out[2 * k + 1] != out[2 * (w - 1) + 1]) {
            out[2 * w] = out[2 * k];
            out[2 * w + 1] = out[2 * k + 1];
            w++;
        }
    while (w > 1 && out[0] == out[2 * (w - 1)] && out[1] == out[2 * (w - 1) + 1])
        w--;
    tsr_free(a, p);
    *pts = out;
    *cnt = w;
    return true;
}

/* A trim loop's polyline in (u, v), as the triangulation has it. */
typedef struct tloop {
    double *p;    /* its n points (owned) */
    uint32_t n;
    bool hole;
    double area;  /* |signed area| */
    double lo[2], hi[2];
} tloop;

static void loop_add(tloop *l, double *p, uint32_t n, bool hole)
{
    double area = 0;
    l->p = p;
    l->n = n;
    l->hole = hole;
    l->lo[0] = l->lo[1] = INFINITY;
    l->hi[0] = l->hi[1] = -INFINITY;
    for (uint32_t k = 0; k < n; k++) {
        const double *a = p + 2 * k, *b = p + 2 * ((k + 1) % n);
        area += a[0] * b[1] - a[1] * b[0];
        for (int d = 0; d < 2; d++) {
            l->lo[d] = dmin(l->lo[d], a[d]);
            l->hi[d] = dmax(l->hi[d], a[d]);
        }
    }
    l->area = 0.5 * fabs(area);
}

/* Whether c lies inside the closed polyline (crossing number). */
static bool loop_inside(const tloop *l, const double c[2])
{
    if (c[0] < l->lo[0] || c[0] > l->hi[0] || c[1] < l->lo[1] || c[1] > l->hi[1])
        return false;
    const double *p = l->p;
    bool in = false;
    for (uint32_t k = 0; k < l->n; k++) {
        const double *a = p + 2 * k, *b = p + 2 * ((k + 1) % l->n);
        if ((a[1] > c[1]) != (b[1] > c[1]) && c[0] < a[0] + (c[1] - a[1]) * (b[0] - a[0]) / (b[1] - a[1]))
            in = !in;
    }
    return in;
}

/* Whether the trimmed domain holds the point c (the centroid of a
 * triangle, which lies on one side of every loop, the loops being edges):
 * the innermost loop around it (the smallest) decides, an outer loop (OBJ
 * `trim`) keeping and a hole removing; where no loop is around it, it is
 * kept unless the patch has an outer loop (outer; one that encloses none
 * of the domain, left out of loops, still counts: it keeps nothing). So holes remove their inside
 * whether or not an outer loop is given, a hole given twice or two
 * overlapping holes remove their union, a hole reaching past the outer
 * loop adds nothing outside it, and an island (an outer loop inside a
 * hole) is kept. */
static bool trim_keeps(const tloop *loops, uint32_t n, bool outer, const double c[2])
{
    const tloop *best = NULL;
    for (uint32_t k = 0; k < n; k++)
        if ((!best || loops[k].area < best->area) && loop_inside(&loops[k], c))
            best = &loops[k];
    return best ? !best->hole : !outer;
}

static int cmp_u64_asc(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* keep[t] for every triangle of tr: trim_keeps at the centroid of each
 * region's largest triangle, a region being the triangles reached from one another across
 * edges that are no constraint (no loop's edge: a loop's polyline lies on
 * constrained edges and the domain's border, so no loop separates two
 * triangles of one region). A centroid test per triangle costs every
 * loop point each: dense loops (CAD exports of 10^5 points) made that
 * quadratic. False when out of memory. */
static bool trim_regions(const tsr_triangulation *tr, const tloop *loops, uint32_t nloops, bool outer, uint8_t *keep,
                         const tsr_allocator *a)
{
    tsr_mesh view = {0};
    view.indices = tr->tri;
    view.triangle_count = tr->nt;
    view.vertex_count = tr->nv;
    tsr_halfedges he;
    uint64_t *cons = tsr_alloc(a, ((size_t)tr->nedge + 1) * sizeof *cons);
    uint8_t *seen = tsr_alloc(a, (size_t)tr->nt + 1); /* reached by some region's flood */
    uint32_t *stack = tsr_alloc(a, ((size_t)tr->nt + 1) * sizeof *stack);
    bool ok = cons && seen && stack && tsr_halfedges_build(&he, &view, a) == TSR_OK;
    if (ok) {
        for (uint32_t e = 0; e < tr->nedge; e++) {
            uint32_t u = tr->edge[2 * e], v = tr->edge[2 * e + 1];
            cons[e] = u < v ? (uint64_t)u << 32 | v : (uint64_t)v << 32 | u;
        }
        qsort(cons, tr->nedge, sizeof *cons, cmp_u64_asc);
        memset(seen, 0, tr->nt);
        for (uint32_t seed = 0; seed < tr->nt; seed++) {
            if (seen[seed])
                continue;
            /* the region's largest triangle decides: a sliver's centroid
             * beside a rounded crossing may fall on the other side of a
             * loop than the constraint edges put it */
            uint32_t n = 0, m = 0, best = seed;
            double best_area = -1;
            stack[n++] = seed;
            seen[seed] = 1;
            while (m < n) {
                uint32_t t = stack[m++];
                const uint32_t *tv = tr->tri + 3 * (size_t)t;
                const double *p0 = tr->xy + 2 * (size_t)tv[0], *p1 = tr->xy + 2 * (size_t)tv[1],
                             *p2 = tr->xy + 2 * (size_t)tv[2];
                double area = fabs((p1[0] - p0[0]) * (p2[1] - p0[1]) - (p2[0] - p0[0]) * (p1[1] - p0[1]));
                if (area > best_area) {
                    best_area = area;
                    best = t;
                }
                for (int k = 0; k < 3; k++) {
                    uint32_t h = 3 * t + (uint32_t)k, tw = he.twin[h];
                    if (tw == TSR_NO_TWIN || tw == TSR_NONMANIFOLD || seen[tw / 3])
                        continue;
                    uint32_t u = tr->tri[h], v = tr->tri[3 * t + (uint32_t)(k + 1) % 3];
                    uint64_t key = u < v ? (uint64_t)u << 32 | v : (uint64_t)v << 32 | u;
                    if (bsearch(&key, cons, tr->nedge, sizeof *cons, cmp_u64_asc))
                        continue;
                    seen[tw / 3] = 1;
                    stack[n++] = tw / 3;
                }
            }
            const uint32_t *tv = tr->tri + 3 * (size_t)best;
            double cen[2] = {(tr->xy[2 * tv[0]] + tr->xy[2 * tv[1]] + tr->xy[2 * tv[2]]) / 3,
                             (tr->xy[2 * tv[0] + 1] + tr->xy[2 * tv[1] + 1] + tr->xy[2 * tv[2] + 1]) / 3};
            uint8_t k0 = trim_keeps(loops, nloops, outer, cen);
            for (uint32_t i = 0; i < n; i++)
                keep[stack[i]] = k0;
        }
        tsr_halfedges_free(&he);
    }
    tsr_free(a, cons);
    tsr_free(a, seen);
    tsr_free(a, stack);
    return ok;
}

/* Trimmed source: lattice points of its pieces' leaves plus the sampled
 * trim loops, triangulated in (u, v) with the loops as constraints, the
 * triangles the loops keep (trim_keeps, once per region: trim_regions)
 * lifted. */
/* The side of source s's domain (0 south, 1 east, 2 north, 3 west) that
 * (u, v) lies on where a piece's edge there is linked; -1 for none. */
static int on_linked_border(const tsr_pmodel *m, const psource *s, const double uv[2])
{
    for (int e = 0; e < 4; e++) {
        bool on = e == 0   ? uv[1] == s->domain[2]
                  : e == 1 ? uv[0] == s->domain[1]
                  : e == 2 ? uv[1] == s->domain[3]
                           : uv[0] == s->domain[0];
        if (!on)
            continue;
        uint32_t n = e & 1 ? s->pv : s->pu;
        for (uint32_t k = 0; k < n; k++) {
            uint32_t a2 = e == 1 ? s->pu - 1 : e == 3 ? 0 : k, b2 = e == 0 ? 0 : e == 2 ? s->pv - 1 : k;
            const piece *p = &m->pieces[s->first_piece + b2 * s->pu + a2];
            double lo = e & 1 ? p->rect[2] : p->rect[0], hi = e & 1 ? p->rect[3] : p->rect[1], x = uv[(e & 1) ? 1 : 0];
            if (x >= lo && x <= hi && p->nlinks[e])
                return e;
        }
    }
    return -1;
}

static bool push_etrim(builder *b, uint32_t v, uint32_t src, int side, const float p[3])
{
    if (b->net == b->capet) {
        uint32_t cap = b->capet ? 2 * b->capet : 64;
        etrim *n = tsr_realloc(b->a, b->et, (size_t)cap * sizeof *n);
        if (!n)
            return false;
        b->et = n;
        b->capet = cap;
    }
    b->et[b->net++] = (etrim){v, src, side, {p[0], p[1], p[2]}};
    return true;
}

static int etrim_cmp(const void *x, const void *y)
{
    const etrim *a = x, *c = y;
    return a->p[0] < c->p[0] ? -1 : a->p[0] > c->p[0] ? 1 : (a->v > c->v) - (a->v < c->v);
}

static uint32_t uf_find(uint32_t *par, uint32_t i)
{
    while (par[i] != i)
        i = par[i] = par[par[i]];
    return i;
}

/* Where a trim loop crosses a linked patch edge (a hole across the edge
 * between two faces), each side made its own vertex there: those within
 * the link distance become one (the lowest-numbered), at most one of each
 * side of each source (two crossings of one side stay apart, however
 * near), triangles left with a repeated corner are dropped and the
 * vertices no triangle uses removed. */
static tsr_status weld_trim_points(builder *b)
{
    uint32_t n = b->net;
    if (n < 2)
        return TSR_OK;
    const tsr_allocator *a = b->a;
    tsr_ptess_result *r = b->out;
    double tol = b->m->link_tol;
    qsort(b->et, n, sizeof *b->et, etrim_cmp);
    uint32_t *par = tsr_alloc(a, (size_t)2 * n * sizeof *par);
    if (!par)
        return TSR_ERR_NOMEM;
    uint32_t *next = par + n; /* the members of a cluster, from its root, UINT32_MAX ending */
    for (uint32_t i = 0; i < n; i++)
        par[i] = i, next[i] = UINT32_MAX;
    bool any = false;
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n && (double)b->et[j].p[0] - b->et[i].p[0] <= tol; j++) {
            double d2 = 0;
            for (int c = 0; c < 3; c++)
                d2 += ((double)b->et[j].p[c] - b->et[i].p[c]) * ((double)b->et[j].p[c] - b->et[i].p[c]);
            if (d2 > tol * tol)
                continue;
            uint32_t x = uf_find(par, i), y = uf_find(par, j);
            bool clash = x == y;
            for (uint32_t p = x; p != UINT32_MAX && !clash; p = next[p])
                for (uint32_t q = y; q != UINT32_MAX && !clash; q = next[q])
                    clash = b->et[p].src == b->et[q].src && b->et[p].side == b->et[q].side;
            if (clash)
                continue;
            if (b->et[y].v < b->et[x].v) {
                uint32_t t = x;
                x = y, y = t;
            }
            par[y] = x; /* y's members after x's */
            uint32_t last = x;
            while (next[last] != UINT32_MAX)
                last = next[last];
            next[last] = y;
            any = true;
        }
    if (!any) {
        tsr_free(a, par);
        return TSR_OK;
    }
    uint32_t nv = r->mesh.vertex_count;
    uint32_t *to = tsr_alloc(a, (size_t)nv * sizeof *to);
    if (!to) {
        tsr_free(a, par);
        return TSR_ERR_NOMEM;
    }
    for (uint32_t v = 0; v < nv; v++)
        to[v] = v;
    for (uint32_t i = 0; i < n; i++)
        to[b->et[i].v] = b->et[uf_find(par, i)].v;
    tsr_free(a, par);
    uint32_t kept = 0, first = UINT32_MAX;
    for (uint32_t t = 0; t < r->mesh.triangle_count; t++) {
        uint32_t *tv = r->mesh.indices + 3 * (size_t)t, w[3] = {to[tv[0]], to[tv[1]], to[tv[2]]};
        for (int k = 0; k < 3; k++)
            if (w[k] != tv[k] && tv[k] < first)
                first = tv[k];
        if (w[0] == w[1] || w[1] == w[2] || w[2] == w[0])
            continue;
        memcpy(r->mesh.indices + 3 * (size_t)kept, w, sizeof w);
        r->tri_source[kept] = r->tri_source[t];
        memmove(r->tri_uv + 6 * (size_t)kept, r->tri_uv + 6 * (size_t)t, 6 * sizeof *r->tri_uv);
        kept++;
    }
    r->mesh.triangle_count = kept;
    tsr_free(a, to);
    if (first != UINT32_MAX && tsr_mesh_drop_unused(&r->mesh, first) == UINT32_MAX)
        return TSR_ERR_NOMEM;
    return TSR_OK;
}

static tsr_status emit_trimmed(builder *b, uint32_t src, double trim_tol_uv, tsr_error *err)
{
    const tsr_pmodel *m = b->m;
    const psource *s = &m->sources[src];
    const tsr_allocator *a = b->a;
    size_t np = 0, cap = 1024, nseg = 0, segcap = 1024;
    double *xy = tsr_alloc(a, cap * 2 * sizeof *xy);
    uint64_t *key = tsr_alloc(a, cap * sizeof *key); /* canonical lattice key + 1, 0 for trim points */
    uint32_t *seg = tsr_alloc(a, segcap * 2 * sizeof *seg);
    tsr_status st = (xy && key && seg) ? TSR_OK : TSR_ERR_NOMEM;
    tsr_keymap seen = {0};
#define GROW(ptr, n, c, per)                                                                                          \
    if (st == TSR_OK && (n) + 1 > (c)) {                                                                              \
        size_t nc = 2 * (c);                                                                                          \
        void *q = tsr_realloc(a, (ptr), nc * (per) * sizeof *(ptr));                                                  \
        if (!q)                                                                                                       \
            st = TSR_ERR_NOMEM;                                                                                       \
        else {                                                                                                        \
            (ptr) = q;                                                                                                \
        }                                                                                                             \
    }
    for (uint32_t k = 0; k < s->pu * s->pv && st == TSR_OK; k++) {
        uint32_t pi = s->first_piece + k;
        pctx *c = &b->ctx[pi];
        const piece *p = &m->pieces[pi];
        uint32_t N = c->N, Z = lattice_size(b->ctx, pi);
        uint32_t nl = tsr_quadtree_leaf_count(c->qt);
        const tsr_qleaf *lv = tsr_quadtree_leaves(c->qt);
        for (uint32_t li = 0; li < nl && st == TSR_OK; li++) {
            tsr_qnode n = lv[li].node;
            uint32_t w = N << (c->surf.levels - n.level), step = w / N;
            for (uint32_t j = 0; j <= N && st == TSR_OK; j++)
                for (uint32_t i = 0; i <= N && st == TSR_OK; i++) {
                    lpoint q = {pi, n.x * w + i * step, n.y * w + j * step};
                    st = add_lattice_point(b, &seen, q, p, (double)q.i / Z, (double)q.j / Z, &xy, &key, &np, &cap);
                }
        }
        /* along linked edges, the neighbours' samples too (as the fans of
         * emit_piece): both sides then sample the edge alike */
        for (int e = 0; e < 4 && st == TSR_OK; e++) {
            b->nfp = 0;
            if (!c->act[e])
                continue;
            if (!edge_foreign(b, pi, e, 0, Z)) {
                st = TSR_ERR_NOMEM;
                break;
            }
            for (uint32_t x = 0; x < b->nfp && st == TSR_OK; x++) {
                double T = b->fp[x].T / Z, ss = e == 1 ? 1 : e == 3 ? 0 : T, tt = e == 0 ? 0 : e == 2 ? 1 : T;
                st = add_lattice_point(b, &seen, b->fp[x].q, p, ss, tt, &xy, &key, &np, &cap);
            }
        }
    }
    tsr_keymap_free(&seen, a);
    double hu = INFINITY, hv = INFINITY;
    for (uint32_t k = 0; k < s->pu * s->pv; k++) {
        const pctx *c = &b->ctx[s->first_piece + k];
        const piece *p = &m->pieces[s->first_piece + k];
        const tsr_qleaf *lv = tsr_quadtree_leaves(c->qt);
        for (uint32_t li = 0; li < tsr_quadtree_leaf_count(c->qt); li++) {
            double f = 1.0 / ((double)c->N * (double)(1u << lv[li].node.level));
            hu = fmin(hu, f * (p->rect[1] - p->rect[0]));
            hv = fmin(hv, f * (p->rect[3] - p->rect[2]));
        }
    }
    /* the trim loops, meeting the lattice points where they pass within
     * a hair of them (lat_grid) */
    double hair_u = 1e-9 * (s->domain[1] - s->domain[0]), hair_v = 1e-9 * (s->domain[3] - s->domain[2]);
    /* loop points this near the domain's border go onto it: a CAD file's
     * loop along a face's own boundary is accurate to 1e-6 to 1e-4 of it,
     * and a loop 1e-6 inside left a sliver of the face out, a crack beside
     * its neighbour. Moving a point by trim_tol_uv at most moves the
     * surface by half the bound (trim_tol_uv's own derivation), within what
     * the trimmed boundary may deviate anyway; and 1e-3 of the domain at
     * most */
    double snap_u = fmax(hair_u, fmin(trim_tol_uv, 1e-3 * (s->domain[1] - s->domain[0]))),
           snap_v = fmax(hair_v, fmin(trim_tol_uv, 1e-3 * (s->domain[3] - s->domain[2])));
    lat_grid lg;
    if (!lat_build(&lg, xy, (uint32_t)np, s->domain, hu, hv, a) && st == TSR_OK)
        st = TSR_ERR_NOMEM;
    const tsr_patch_set *set = m->set;
    uint32_t l0 = set->first_loop[s->patch], nloops = set->first_loop[s->patch + 1] - l0, nkept = 0;
    tloop *loops = tsr_alloc(a, (nloops ? nloops : 1) * sizeof *loops);
    bool has_outer = false;
    for (uint32_t l = l0; l < l0 + nloops; l++)
        has_outer |= !set->loops[l].hole;
    if (!loops)
        st = TSR_ERR_NOMEM;
    for (uint32_t l = l0; l < l0 + nloops && st == TSR_OK; l++) {
        uint32_t cnt = 0;
        if (tsr_trim_loop_sample(set, l, trim_tol_uv, NULL, 0, &cnt) != TSR_OK || cnt < 3)
            continue;
        double *pts = tsr_alloc(a, (size_t)cnt * 2 * sizeof *pts);
        if (!pts) {
            st = TSR_ERR_NOMEM;
            break;
        }
        tsr_trim_loop_sample(set, l, trim_tol_uv, pts, cnt, &cnt);
        /* a chord straight in (u, v) is not straight on the surface: cut
         * loop edges to the finest tile spacing of the source */
        uint32_t extra = 0;
        for (uint32_t k = 0; k < cnt; k++) {
            const double *p0 = pts + 2 * k, *p1 = pts + 2 * ((k + 1) % cnt);
            double len = fmax(fabs(p1[0] - p0[0]) / hu, fabs(p1[1] - p0[1]) / hv);
            extra += len > 1 ? (uint32_t)fmin(ceil(len), 65536.0) - 1 : 0;
        }
        if (extra) {
            double *more = tsr_alloc(a, ((size_t)cnt + extra) * 2 * sizeof *more);
            if (!more) {
                tsr_free(a, pts);
                st = TSR_ERR_NOMEM;
                break;
            }
            uint32_t n2 = 0;
            for (uint32_t k = 0; k < cnt; k++) {
                const double *p0 = pts + 2 * k, *p1 = pts + 2 * ((k + 1) % cnt);
                double len = fmax(fabs(p1[0] - p0[0]) / hu, fabs(p1[1] - p0[1]) / hv);
                uint32_t parts = len > 1 ? (uint32_t)fmin(ceil(len), 65536.0) : 1;
                for (uint32_t q = 0; q < parts; q++) {
                    double f = (double)q / parts;
                    more[2 * n2] = p0[0] + f * (p1[0] - p0[0]);
                    more[2 * n2 + 1] = p0[1] + f * (p1[1] - p0[1]);
                    n2++;
                }
            }
            tsr_free(a, pts);
            pts = more;
            cnt = n2;
        }
        /* Clamped to the domain, points within a hair of its border
         * snapped onto it. Runs of the loop along the border (both ends on
         * one side: CAD files trim every face by its own boundary) add no
         * points or segments: the border is the hull already, sampled by
         * the lattice and the linked neighbours' points, and extra points
         * there would open T-junctions with the neighbour. The loop's whole
         * polyline still decides which triangles are kept (trim_keeps). */
        /* the wider snap only for runs: a point with a neighbour along the
         * loop near the same side (a lone point near the border, a bolt
         * hole's or a tangent curve's, put onto it would be a vertex there
         * that the linked neighbour lacks) */
        /* (the neighbour before may be snapped already: onto the side it
         * was near, so it is near the same sides) */
#define NEAR_SIDES(q)                                                                                                  \
    ((unsigned)((q)[0] < s->domain[0] + snap_u) | (unsigned)((q)[0] > s->domain[1] - snap_u) << 1 |                    \
     (unsigned)((q)[1] < s->domain[2] + snap_v) << 2 | (unsigned)((q)[1] > s->domain[3] - snap_v) << 3)
        for (uint32_t k = 0; k < cnt; k++) {
            double *u = pts + 2 * k, *v = u + 1;
            unsigned run =
                NEAR_SIDES(u) & (NEAR_SIDES(pts + 2 * ((k + cnt - 1) % cnt)) | NEAR_SIDES(pts + 2 * ((k + 1) % cnt)));
            double su = run & 3 ? snap_u : hair_u, sv = run & 12 ? snap_v : hair_v;
            *u = *u < s->domain[0] + su ? s->domain[0] : *u > s->domain[1] - su ? s->domain[1] : *u;
            *v = *v < s->domain[2] + sv ? s->domain[2] : *v > s->domain[3] - sv ? s->domain[3] : *v;
        }
#undef NEAR_SIDES
        uint8_t *side = NULL;
        if (!lat_meet(&lg, &pts, &cnt, hair_u, hair_v, a) || !(side = tsr_alloc(a, cnt ? cnt : 1))) {
            tsr_free(a, pts);
            st = TSR_ERR_NOMEM;
            break;
        }
        if (cnt < 3) {
            tsr_free(a, side);
            tsr_free(a, pts);
            continue;
        }
        for (uint32_t k = 0; k < cnt; k++) {
            const double *u = pts + 2 * k, *v = u + 1;
            side[k] = (uint8_t)((*u == s->domain[0]) | (*u == s->domain[1]) << 1 | (*v == s->domain[2]) << 2 |
                                (*v == s->domain[3]) << 3);
        }
        size_t first = np;
        for (uint32_t k = 0; k < cnt && st == TSR_OK; k++) {
            uint32_t k1 = (k + 1) % cnt, k0 = (k + cnt - 1) % cnt;
            bool run_out = (side[k] & side[k1]) != 0, run_in = (side[k0] & side[k]) != 0;
            if (run_in && run_out)
                continue; /* inside a run along the border */
            GROW(xy, np, cap, 2)
            GROW(key, np, cap, 1)
            if (st != TSR_OK)
                break;
            if (np + 1 > cap)
                cap *= 2;
            xy[2 * np] = pts[2 * k];
            xy[2 * np + 1] = pts[2 * k + 1];
            key[np] = 0;
            np++;
            if (run_out)
                continue;
            /* a segment to the next point, which is kept too (its
             * incoming segment is this one, not on the border): its index
             * is the next one, or the loop's first kept point */
            GROW(seg, nseg, segcap, 2)
            if (st != TSR_OK)
                break;
            if (nseg + 1 > segcap)
                segcap *= 2;
            seg[2 * nseg] = (uint32_t)(np - 1);
            seg[2 * nseg + 1] = k1 == 0 ? (uint32_t)first : (uint32_t)np;
            nseg++;
        }
        tsr_free(a, side);
        if (st == TSR_OK)
            loop_add(&loops[nkept++], pts, cnt, set->loops[l].hole);
        else
            tsr_free(a, pts);
    }
#undef GROW
    lat_free(&lg, a);
    tsr_triangulation tr = {0};
    if (st == TSR_OK) {
        /* the whole domain, every loop's polyline an edge; the region is
         * chosen below, triangle by triangle (trim_keeps) */
        tsr_pslg in = {xy, (uint32_t)np, seg, (uint32_t)nseg, NULL, 0};
        tsr_tri_options to = {0};
        to.region = TSR_REGION_HULL;
        tsr_error e2 = {0};
        st = tsr_triangulate(&in, &to, &tr, a, &e2);
        if (st != TSR_OK)
            tsr_error_set(err, st, "patch %u: triangulating the trimmed domain: %s", s->patch, e2.message);
    }
    /* lift: output vertex -> mesh vertex */
    uint32_t *mv = st == TSR_OK ? tsr_alloc(a, ((size_t)tr.nv + 1) * sizeof *mv) : NULL;
    if (st == TSR_OK && !mv)
        st = TSR_ERR_NOMEM;
    if (st == TSR_OK) {
        for (uint32_t i = 0; i < tr.nv; i++)
            mv[i] = UINT32_MAX;
        bool mirrored = m->pieces[s->first_piece].mirrored;
        uint32_t *inv_key = tsr_alloc(a, ((size_t)tr.nv + 1) * sizeof *inv_key);
        if (!inv_key)
            st = TSR_ERR_NOMEM;
        for (uint32_t i = 0; inv_key && i < tr.nv; i++)
            inv_key[i] = UINT32_MAX;
        for (size_t i = 0; inv_key && i < np; i++)
            if (key[i])
                inv_key[tr.vertex_of_input[i]] = (uint32_t)i;
        uint8_t *keep = st == TSR_OK ? tsr_alloc(a, (size_t)tr.nt + 1) : NULL;
        if (st == TSR_OK && (!keep || !trim_regions(&tr, loops, nkept, has_outer, keep, a)))
            st = TSR_ERR_NOMEM;
        for (uint32_t t = 0; t < tr.nt && st == TSR_OK; t++) {
            uint32_t v[3];
            double uv[6];
            if (!keep[t])
                continue;
            for (int k = 0; k < 3 && st == TSR_OK; k++) {
                uint32_t o = tr.tri[3 * t + (mirrored && k ? 3 - k : k)];
                uv[2 * k] = tr.xy[2 * o];
                uv[2 * k + 1] = tr.xy[2 * o + 1];
                if (mv[o] >= UINT32_MAX - 1) {
                    if (inv_key[o] != UINT32_MAX) {
                        uint64_t kk = key[inv_key[o]] - 1;
                        lpoint q = {(uint32_t)(kk >> 40), (uint32_t)(kk & 0xFFFFF), (uint32_t)((kk >> 20) & 0xFFFFF)};
                        mv[o] = vertex_of(b, q, NULL, UINT32_MAX);
                    } else {
                        double pos[3], nr[3] = {0, 0, 1};
                        tsr_pmodel_eval(m, src, uv[2 * k], uv[2 * k + 1], pos, b->opt->normals ? nr : NULL);
                        b->out->evaluations++;
                        float fp[3] = {(float)pos[0], (float)pos[1], (float)pos[2]},
                              fn[3] = {(float)nr[0], (float)nr[1], (float)nr[2]};
                        mv[o] = tsr_mesh_add_vertex(&b->out->mesh, fp, b->opt->normals ? fn : NULL, NULL);
                        int side = mv[o] != UINT32_MAX ? on_linked_border(m, s, uv + 2 * k) : -1;
                        if (side >= 0 && !push_etrim(b, mv[o], src, side, fp))
                            st = TSR_ERR_NOMEM;
                    }
                    if (mv[o] == UINT32_MAX)
                        st = TSR_ERR_NOMEM;
                }
                v[k] = mv[o];
            }
            /* two corners welded into one vertex (along a collapsed edge,
             * or across the seam): no triangle */
            if (st == TSR_OK && (v[0] == v[1] || v[1] == v[2] || v[2] == v[0]))
                continue;
            if (st == TSR_OK && !add_tri(b, src, v, uv))
                st = TSR_ERR_NOMEM;
        }
        tsr_free(a, keep);
        tsr_free(a, inv_key);
    }
    tsr_free(a, mv);
    tsr_triangulation_free(&tr);
    for (uint32_t k = 0; k < nkept; k++)
        tsr_free(a, loops[k].p);
    tsr_free(a, loops);
    tsr_free(a, xy);
    tsr_free(a, key);
    tsr_free(a, seg);
    return st;
}

void tsr_ptess_result_free(tsr_ptess_result *r)
{
    if (!r)
        return;
    const tsr_allocator *a = r->alloc.realloc ? &r->alloc : NULL;
    tsr_mesh_free(&r->mesh);
    tsr_free(a, r->tri_source);
    tsr_free(a, r->tri_uv);
    memset(r, 0, sizeof *r);
}

/* The patterns of tile size N, from the model's cache or made and put
 * there; NULL when out of memory. */
static const patcache *patterns_of(const tsr_pmodel *cm, uint32_t N)
{
    tsr_pmodel *m = (tsr_pmodel *)cm; /* the cache only: see struct tsr_pmodel */
    patcache *pc = atomic_load_explicit(&m->pats[N / 2], memory_order_acquire);
    if (pc)
        return pc;
    const tsr_allocator *a = ma(m);
    uint32_t r2 = (N + 1) * (N + 1);
    pc = tsr_alloc(a, sizeof *pc);
    if (!pc)
        return NULL;
    memset(pc, 0, sizeof *pc);
    pc->used = tsr_alloc(a, (size_t)16 * r2);
    if (!pc->used || tsr_tile_patterns_init(&pc->pat, N, a) != TSR_OK) {
        tsr_free(a, pc->used);
        tsr_free(a, pc);
        return NULL;
    }
    memset(pc->used, 0, (size_t)16 * r2);
    size_t total = 0;
    for (unsigned mk = 0; mk < 16; mk++) {
        for (uint32_t t = 0; t < 3 * pc->pat.count[mk]; t++)
            pc->used[(size_t)mk * r2 + pc->pat.tri[mk][t]] = 1;
        for (uint32_t k = 0; k < r2; k++)
            pc->used_n[mk] += pc->used[(size_t)mk * r2 + k];
        total += pc->pat.count[mk];
    }
    pc->on_store = tsr_alloc(a, (total + 1) * sizeof *pc->on_store);
    if (!pc->on_store) {
        tsr_tile_patterns_free(&pc->pat);
        tsr_free(a, pc->used);
        tsr_free(a, pc);
        return NULL;
    }
    uint16_t *on = pc->on_store;
    for (unsigned mk = 0; mk < 16; mk++) {
        pc->on[mk] = on;
        for (uint32_t t = 0; t < pc->pat.count[mk]; t++) {
            unsigned bits = 0;
            for (int k = 0; k < 3; k++) {
                uint32_t va = pc->pat.tri[mk][3 * t + k], vb = pc->pat.tri[mk][3 * t + (k + 1) % 3];
                unsigned ea = tile_onmask(va % (N + 1), va / (N + 1), N), eb = tile_onmask(vb % (N + 1), vb / (N + 1), N);
                bits |= (ea & eb) << (4 * k);
            }
            *on++ = (uint16_t)bits;
        }
    }
    patcache *expected = NULL;
    if (!atomic_compare_exchange_strong_explicit(&m->pats[N / 2], &expected, pc, memory_order_acq_rel,
                                                 memory_order_acquire)) {
        tsr_tile_patterns_free(&pc->pat); /* another run was first */
        tsr_free(a, pc->used);
        tsr_free(a, pc->on_store);
        tsr_free(a, pc);
        pc = expected;
    }
    return pc;
}

tsr_status tsr_ptess_run(const tsr_pmodel *m, const tsr_ptess_options *opt_in, const tsr_allocator *alloc,
                         tsr_ptess_result *out, tsr_error *err)
{
    if (!out)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: no output");
    memset(out, 0, sizeof *out);
    if (alloc)
        out->alloc = *alloc;
    if (!m || !opt_in)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: no model or no options");
    tsr_ptess_options opt = *opt_in;
    if (!opt.tile_n)
        opt.tile_n = 4;
    if (!opt.max_level)
        opt.max_level = 10;
    if (opt.tile_n < TSR_TILE_MIN || opt.tile_n > TSR_TILE_MAX || (opt.tile_n & 1))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: tile size %u is not even in %u..%u",
                             opt.tile_n, TSR_TILE_MIN, TSR_TILE_MAX);
    if (opt.max_level < 1 || opt.max_level > 12)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: max level %u is outside 1..12",
                             opt.max_level);
    if (!opt.camera && !(opt.max_error > 0 && isfinite(opt.max_error)))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: max error %g is not a positive number",
                             opt.max_error);
    if (opt.camera && !(opt.camera->pixel_error > 0 && isfinite(opt.camera->pixel_error)))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: pixel error %g is not a positive number",
                             opt.camera->pixel_error);
    if (opt.piece_scale)
        for (uint32_t p = 0; p < m->npieces; p++)
            if (!(opt.piece_scale[p] > 0 && opt.piece_scale[p] <= 1))
                return tsr_error_set(err, TSR_ERR_ARGUMENT, "tessellate patches: piece scale %g of piece %u is "
                                                            "outside (0, 1]",
                                     opt.piece_scale[p], p);
    if (m->subd && opt.max_level < 2)
        opt.max_level = 2; /* N-gon sub-patches need a level less than quads */
    double t_start = now_s();
    const tsr_allocator *a = alloc;
    tsr_mesh_init(&out->mesh, opt.normals ? TSR_MESH_NORMALS : 0, alloc);
    pctx *ctx = tsr_alloc(a, (size_t)m->npieces * sizeof *ctx);
    uint32_t row = opt.tile_n + 1, maxN = 4 * opt.tile_n - 2;
    maxN = maxN < opt.tile_n ? opt.tile_n : maxN > TSR_TILE_MAX ? TSR_TILE_MAX : maxN;
    double *scratch = tsr_alloc(a, ((size_t)row * row * 5 + 12) * sizeof *scratch);
    uint32_t *iscratch = tsr_alloc(a, ((size_t)row * row * 5 + 4) * sizeof *iscratch);
    /* (a level more for half tiles: choose_tile) */
    kidnets *kids = tsr_alloc(a, ((size_t)opt.max_level + 2) * sizeof *kids);
    uint64_t evals = 0;
    tsr_status st = ctx && scratch && iscratch && kids ? TSR_OK : TSR_ERR_NOMEM;
    for (uint32_t l = 0; kids && l <= opt.max_level + 1; l++)
        kids[l].key = 0, kids[l].piece = UINT32_MAX;
    if (ctx)
        memset(ctx, 0, (size_t)m->npieces * sizeof *ctx);
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++) {
        pctx *c = &ctx[p];
        const piece *pc = &m->pieces[p];
        c->m = m;
        c->opt = &opt;
        c->piece = p;
        c->N = opt.tile_n;
        c->inv_n2 = 1.0 / ((double)opt.tile_n * opt.tile_n);
        double scale = opt.piece_scale ? opt.piece_scale[p] : 1;
        c->tol = (opt.camera ? opt.camera->pixel_error : opt.max_error) * scale;
        c->scratch = scratch;
        c->uv = scratch + 3 * (size_t)row * row;
        c->idx = iscratch;
        c->ij = iscratch + (size_t)row * row;
        c->tix = iscratch + (size_t)row * row * 3;
        c->tat = iscratch + (size_t)row * row * 4 + 4;
        c->kids = kids;
        c->evaluations = &evals;
        c->alloc = a;
        uint32_t L = opt.max_level - (pc->kind == KIND_SUBD && pc->levels ? 1 : 0);
        c->surf = (tsr_surface){c, opt.tile_n, L, opt.tile_n << L, opt.tile_n << L, surf_evaluate, surf_bounds,
                                surf_error, true};
        c->qt = tsr_quadtree_create(&c->surf, a);
        if (!c->qt) {
            st = TSR_ERR_NOMEM;
            break;
        }
    }
    /* select; then stitched tiles within the bound, or their coarse
     * neighbours split, until none fails. Linked edges need no agreement:
     * each side's border tiles take the other side's samples too (fans,
     * emit_piece) */
    uint8_t *dirty = st == TSR_OK ? tsr_alloc(a, m->npieces) : NULL;
    if (st == TSR_OK && !dirty)
        st = TSR_ERR_NOMEM;
    if (dirty)
        memset(dirty, 1, m->npieces);
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++)
        if (m->pieces[p].kind == KIND_BEZIER && !m->sources[m->pieces[p].source].trimmed && !opt.fixed_tile)
            if ((st = choose_tile(&ctx[p], opt.tile_n, maxN)) == TSR_OK && ctx[p].nomem)
                st = TSR_ERR_NOMEM;
    /* subd pieces: selected here, with tiles of tile_n or of half that
     * (when even). A piece's point map starts at the size its
     * predecessor's reached (the faces of one cage are alike) rather than
     * rehashing up from 16 slots */
    uint32_t half = opt.tile_n / 2 >= TSR_TILE_MIN && !((opt.tile_n / 2) & 1) && !opt.fixed_tile ? opt.tile_n / 2 : 0;
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++)
        if (m->pieces[p].kind == KIND_SUBD) {
            if (p > 0 && !ctx[p].npts && ctx[p - 1].npts >= 512 &&
                !tsr_keymap_reserve(&ctx[p].pmemo, ctx[p - 1].npts, a))
                st = TSR_ERR_NOMEM;
            if (st == TSR_OK)
                st = subd_choose_tile(&ctx[p], half);
            dirty[p] = 0;
        }
    double bound = 0;
    for (bool again = true; again && st == TSR_OK;) {
        out->passes++;
        for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++) {
            if (!dirty[p])
                continue;
            ctx[p].cur_key = 0;
            st = tsr_quadtree_select(ctx[p].qt, refine, &ctx[p]);
            if (st == TSR_OK && ctx[p].nomem)
                st = TSR_ERR_NOMEM; /* stop at once (refine gave up) */
            dirty[p] = 0;
        }
        again = false;
        bound = 0;
        for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++) {
            double pb = 0; /* the bound holds for Bézier pieces only */
            if (check_stitched(&ctx[p], &pb)) {
                dirty[p] = 1;
                again = true;
            }
            if (ctx[p].nomem)
                st = TSR_ERR_NOMEM;
            if (m->pieces[p].kind == KIND_BEZIER)
                bound = fmax(bound, pb);
        }
    }
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++)
        if (!collect_spans(&ctx[p]))
            st = TSR_ERR_NOMEM;
    tsr_free(a, dirty);
    /* assemble */
    builder b = {.m = m, .opt = &opt, .ctx = ctx, .out = out, .a = a};
    /* the tile patterns of every tile size in use, and which of a tile's
     * vertices each uses */
    const patcache *pats[NPAT] = {NULL};
    uint32_t *local = NULL, mrow = maxN + 1;
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++)
        if (!pats[ctx[p].N / 2] && !(pats[ctx[p].N / 2] = patterns_of(m, ctx[p].N)))
            st = TSR_ERR_NOMEM;
    if (st == TSR_OK) {
        local = tsr_alloc(a, (size_t)mrow * mrow * sizeof *local);
        b.tile_pos = tsr_alloc(a, (size_t)3 * mrow * mrow * sizeof(double));
        b.tile_tmp = tsr_alloc(a, ((size_t)3 * mrow * mrow + 2 * (size_t)mrow * (TSR_PATCH_MAX_DEGREE + 1)) * sizeof(double));
        b.vert_uv = tsr_alloc(a, (size_t)2 * mrow * mrow * sizeof(double));
        b.tile_idx = tsr_alloc(a, (size_t)mrow * mrow * sizeof *b.tile_idx);
        b.onmask = tsr_alloc(a, (size_t)mrow * mrow);
        if (!local || !b.tile_pos || !b.tile_tmp || !b.vert_uv || !b.tile_idx || !b.onmask)
            st = TSR_ERR_NOMEM;
    }
    /* room for everything at once: triangles exactly (but fans), vertices at most */
    uint64_t want_t = 0, want_v = 0, want_border = 0;
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++) {
        if (m->sources[m->pieces[p].source].trimmed)
            continue;
        uint32_t N = ctx[p].N;
        const tsr_qleaf *lv = tsr_quadtree_leaves(ctx[p].qt);
        for (uint32_t i = 0; i < tsr_quadtree_leaf_count(ctx[p].qt); i++) {
            want_t += pats[N / 2]->pat.count[lv[i].stitch & 15];
            want_v += pats[N / 2]->used_n[lv[i].stitch & 15];
            want_border += 4 * N;
        }
    }
    if (st == TSR_OK && (want_t >= UINT32_MAX - 2 || want_v >= ((uint64_t)1 << 33)))
        st = TSR_ERR_TOO_LARGE;
    if (st == TSR_OK && want_t) {
        uint32_t vres = want_v >= UINT32_MAX - 2 ? UINT32_MAX - 2 : (uint32_t)(want_v / 2 + 16);
        st = tsr_mesh_reserve(&out->mesh, vres, (uint32_t)want_t);
        /* and a quarter more for the fans at linked borders */
        uint64_t cap = want_t + want_t / 4 + 64;
        cap = cap > UINT32_MAX - 2 ? UINT32_MAX - 2 : cap;
        out->tri_source = st == TSR_OK ? tsr_alloc(a, (size_t)cap * sizeof *out->tri_source) : NULL;
        out->tri_uv = out->tri_source ? tsr_alloc(a, (size_t)cap * 6 * sizeof *out->tri_uv) : NULL;
        if (st == TSR_OK && !out->tri_uv)
            st = TSR_ERR_NOMEM;
        b.tri_cap = (uint32_t)cap;
        /* tile-border vertices of Bézier pieces go through the map: 4N
         * of a tile's (subd pieces keep theirs with their memo) */
        if (st == TSR_OK && !m->subd && !tsr_keymap_reserve(&b.map, (size_t)(want_border / 2) + 64, a))
            st = TSR_ERR_NOMEM;
    }
    for (uint32_t p = 0; p < m->npieces && st == TSR_OK; p++) {
        out->leaves += tsr_quadtree_leaf_count(ctx[p].qt);
        if (m->sources[m->pieces[p].source].trimmed)
            continue;
        b.used = pats[ctx[p].N / 2]->used;
        st = emit_piece(&b, p, pats[ctx[p].N / 2], local);
        b.grid = NULL; /* (a piece's own) */
    }
    /* trimmed sources: the loops sampled finely enough in (u, v) */
    for (uint32_t s = 0; s < m->nsources && st == TSR_OK; s++) {
        if (!m->sources[s].trimmed)
            continue;
        const psource *src = &m->sources[s];
        /* |dS| <= G |d(u,v)|: G from the pieces' derivative bounds; the loop
         * is within tol_uv of the curve in (u, v), so within G tol_uv on
         * the surface */
        double G = 0;
        for (uint32_t k = 0; k < src->pu * src->pv; k++) {
            const piece *pc = &m->pieces[src->first_piece + k];
            double ext = 0;
            for (int c = 0; c < 3; c++)
                ext += (pc->hi[c] - pc->lo[c]) * (pc->hi[c] - pc->lo[c]);
            double wspan = fmin(pc->rect[1] - pc->rect[0], pc->rect[3] - pc->rect[2]);
            int deg = pc->bez.degree_u > pc->bez.degree_v ? pc->bez.degree_u : pc->bez.degree_v;
            double wratio = 1;
            if (pc->bez.weights) {
                double wmin = INFINITY, wmax = 0;
                for (uint32_t i = 0; i < (uint32_t)(pc->bez.degree_u + 1) * (uint32_t)(pc->bez.degree_v + 1); i++) {
                    wmin = fmin(wmin, pc->bez.weights[i]);
                    wmax = fmax(wmax, pc->bez.weights[i]);
                }
                wratio = wmax / wmin;
            }
            double g = deg * sqrt(ext) * wratio * wratio / wspan;
            G = g > G ? g : G;
        }
        double tol3 = opt.camera ? 0 : opt.max_error;
        if (opt.camera) {
            /* the pixel error at the nearest point of the source's box */
            double dmin = INFINITY;
            for (uint32_t k = 0; k < src->pu * src->pv; k++) {
                const piece *pc = &m->pieces[src->first_piece + k];
                double d2 = 0;
                for (int c = 0; c < 3; c++) {
                    double x = opt.camera->eye[c], dd = x < pc->lo[c] ? pc->lo[c] - x : x > pc->hi[c] ? x - pc->hi[c] : 0;
                    d2 += dd * dd;
                }
                dmin = fmin(dmin, sqrt(d2));
            }
            dmin = fmax(dmin, opt.camera->near_dist);
            tol3 = opt.camera->pixel_error * dmin / (opt.camera->K * 1.75);
        }
        double tol_uv = 0.5 * tol3 / (G > 0 ? G : 1);
        double dom = fmax(src->domain[1] - src->domain[0], src->domain[3] - src->domain[2]);
        tol_uv = fmax(tol_uv, 1e-9 * dom);
        st = emit_trimmed(&b, s, tol_uv, err);
        if (st != TSR_OK && st != TSR_ERR_NOMEM)
            goto done;
    }
    if (st == TSR_OK)
        st = weld_trim_points(&b);
    if (st == TSR_OK && (out->mesh.vertex_count >= UINT32_MAX - 2 || out->mesh.triangle_count >= UINT32_MAX - 2))
        st = TSR_ERR_TOO_LARGE;
    out->bound = bound;
    out->evaluations += (uint32_t)(evals > UINT32_MAX ? UINT32_MAX : evals);
    if (st == TSR_ERR_NOMEM)
        tsr_error_set(err, st, "tessellate patches: out of memory");
    else if (st == TSR_ERR_TOO_LARGE)
        tsr_error_set(err, st, "tessellate patches: the mesh would pass 2^32 - 2 vertices or triangles");
done:
    tsr_free(a, local);
    tsr_free(a, b.tile_pos);
    tsr_free(a, b.tile_tmp);
    tsr_free(a, b.vert_uv);
    tsr_free(a, b.tile_idx);
    tsr_free(a, b.fp);
    tsr_free(a, b.onmask);
    tsr_free(a, b.pv);
    tsr_free(a, b.grid_mem);
    tsr_keymap_free(&b.map, a);
    tsr_free(a, b.cb.p);
    tsr_free(a, b.et);
    for (uint32_t p = 0; ctx && p < m->npieces; p++) {
        tsr_quadtree_destroy(ctx[p].qt);
        tsr_keymap_free(&ctx[p].memo, a);
        tsr_keymap_free(&ctx[p].pmemo, a);
        tsr_free(a, ctx[p].pts);
        tsr_free(a, ctx[p].vid);
        tsr_free(a, ctx[p].tidx);
        tsr_free(a, ctx[p].nv);
        for (int e = 0; e < 4; e++) {
            tsr_free(a, ctx[p].act[e]);
        }
    }
    tsr_free(a, ctx);
    tsr_free(a, scratch);
    tsr_free(a, iscratch);
    tsr_free(a, kids);
    out->seconds = now_s() - t_start;
    return st;
}
