/* cdt.c: incremental Delaunay triangulation with ghost triangles.
 *
 * Lawson's insertion (locate, split, restore the Delaunay property by edge
 * flips; Lawson 1977, Guibas & Stolfi 1985 for the local test). The convex
 * hull is closed by "ghost" triangles sharing a vertex at infinity
 * (internal vertex 0), so points outside the hull, on it, or collinear
 * with it need no special cases beyond the conflict test: a point conflicts
 * with a ghost triangle when it lies strictly outside its hull edge.
 * Points arrive in BRIO order (Amenta, Choi & Rote 2003) with each round
 * sorted along a Hilbert curve, so the visibility walk from the last
 * triangle is short. Every geometric decision uses the exact predicates.
 *
 * Triangle t has vertices tv[3t..3t+2], counter-clockwise; edge k runs
 * from tv[3t+k] to tv[3t+(k+1)%3] and tn[3t+k] is the triangle across it. */
#include "tessellate/cdt_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GHOST CDT_GHOST
#define NONE CDT_NONE
#define P cdt_P
#define is_ghost cdt_is_ghost

const tsr_allocator *tsr__cdt_alloc(const tsr_cdt *d)
{
    return d->alloc.realloc ? &d->alloc : NULL;
}
#define da tsr__cdt_alloc

tsr_cdt *tsr_cdt_create(const tsr_allocator *alloc)
{
    tsr_cdt *d = tsr_alloc(alloc, sizeof *d);
    if (!d)
        return NULL;
    memset(d, 0, sizeof *d);
    if (alloc)
        d->alloc = *alloc;
    d->cap_v = 64;
    d->xy = tsr_alloc(alloc, 2 * (size_t)d->cap_v * sizeof(double));
    if (!d->xy) {
        tsr_free(alloc, d);
        return NULL;
    }
    d->nv = 1; /* vertex 0 is the point at infinity */
    d->xy[0] = d->xy[1] = 0;
    return d;
}

void tsr_cdt_destroy(tsr_cdt *d)
{
    if (!d)
        return;
    const tsr_allocator *a = da(d);
    void *blocks[] = {d->xy,      d->tv,   d->tn,  d->tc,  d->tf,      d->pending, d->stack,
                      d->changed, d->work, d->chl, d->chr, d->targets, d->nwt};
    for (size_t i = 0; i < sizeof blocks / sizeof blocks[0]; i++)
        tsr_free(a, blocks[i]);
    tsr_allocator copy = d->alloc;
    tsr_free(copy.realloc ? &copy : NULL, d);
}

static bool grow_vertices(tsr_cdt *d, uint32_t cap)
{
    if (cap <= d->cap_v)
        return true;
    double *xy = tsr_realloc(da(d), d->xy, 2 * (size_t)cap * sizeof(double));
    if (!xy)
        return false;
    d->xy = xy;
    d->cap_v = cap;
    return true;
}

uint32_t tsr__cdt_add_vertex(tsr_cdt *d, double x, double y)
{
    /* growth by half: with realloc's in-place growth of large blocks the
     * copies stay rare, and the slack (the peak memory of a mesher that
     * cannot know its final size) is a third of doubling's */
    if (d->nv == d->cap_v &&
        (d->cap_v >= UINT32_MAX / 3 || !grow_vertices(d, d->cap_v + d->cap_v / 2 + 16)))
        return NONE;
    d->xy[2 * (size_t)d->nv] = x;
    d->xy[2 * (size_t)d->nv + 1] = y;
    return d->nv++;
}
#define add_vertex tsr__cdt_add_vertex

static bool grow_triangles(tsr_cdt *d, uint32_t cap)
{
    if (cap <= d->cap_t)
        return true;
    uint32_t *tv = tsr_realloc(da(d), d->tv, 3 * (size_t)cap * sizeof *tv);
    if (!tv)
        return false;
    d->tv = tv;
    uint32_t *tn = tsr_realloc(da(d), d->tn, 3 * (size_t)cap * sizeof *tn);
    if (!tn)
        return false;
    d->tn = tn;
    if (d->tc) {
        uint32_t *tc = tsr_realloc(da(d), d->tc, 3 * (size_t)cap * sizeof *tc);
        if (!tc)
            return false;
        memset(tc + 3 * (size_t)d->cap_t, 0, 3 * (size_t)(cap - d->cap_t) * sizeof *tc);
        d->tc = tc;
    }
    if (d->tf) {
        uint32_t *tf = tsr_realloc(da(d), d->tf, (size_t)cap * sizeof *tf);
        if (!tf)
            return false;
        memset(tf + d->cap_t, 0, (size_t)(cap - d->cap_t) * sizeof *tf);
        d->tf = tf;
    }
    d->cap_t = cap;
    return true;
}

static uint32_t new_triangle(tsr_cdt *d)
{
    if (d->nt == d->cap_t && (d->cap_t >= UINT32_MAX / 3 || !grow_triangles(d, d->cap_t + d->cap_t / 2 + 64)))
        return NONE;
    if (d->tc)
        memset(d->tc + 3 * (size_t)d->nt, 0, 3 * sizeof *d->tc);
    return d->nt++;
}

bool tsr__cdt_enable_marks(tsr_cdt *d, bool flags)
{
    size_t cap = d->cap_t ? d->cap_t : 1;
    if (!d->tc) {
        d->tc = tsr_alloc(da(d), 3 * cap * sizeof *d->tc);
        if (!d->tc)
            return false;
        memset(d->tc, 0, 3 * cap * sizeof *d->tc);
    }
    if (flags && !d->tf) {
        d->tf = tsr_alloc(da(d), cap * sizeof *d->tf);
        if (!d->tf)
            return false;
        memset(d->tf, 0, cap * sizeof *d->tf);
    }
    return true;
}

/* The index in t of the edge from x to y, or -1. */
static int edge_index(const tsr_cdt *d, uint32_t t, uint32_t x, uint32_t y)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    for (int k = 0; k < 3; k++)
        if (v[k] == x && v[(k + 1) % 3] == y)
            return k;
    return -1;
}

void tsr__cdt_mark_edge(tsr_cdt *d, uint32_t t, int k, uint32_t m)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t s = d->tn[3 * (size_t)t + k];
    d->tc[3 * (size_t)t + k] = m;
    int j = edge_index(d, s, v[(k + 1) % 3], v[k]);
    if (j >= 0)
        d->tc[3 * (size_t)s + j] = m;
}

bool tsr__cdt_append(const tsr_cdt *d, uint32_t **arr, uint32_t *n, uint32_t *cap, uint32_t v)
{
    if (*n == *cap) {
        uint32_t c = *cap ? 2 * *cap : 64;
        uint32_t *a = tsr_realloc(da(d), *arr, (size_t)c * sizeof *a);
        if (!a)
            return false;
        *arr = a;
        *cap = c;
    }
    (*arr)[(*n)++] = v;
    return true;
}
#define append tsr__cdt_append

/* ---- local retriangulation ------------------------------------------- */

typedef struct link_rec {
    uint64_t key; /* undirected edge */
    uint32_t t;
    int k;
} link_rec;

static int link_cmp(const void *a, const void *b)
{
    const link_rec *x = a, *y = b;
    if (x->key != y->key)
        return x->key < y->key ? -1 : 1;
    return x->t < y->t ? -1 : x->t > y->t;
}

static int u32_cmp(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return x < y ? -1 : x > y;
}

/* Links every edge of the triangles in slots[0..n) (already written) to
 * its twin: another of them, or the triangle that was across that edge of
 * the cavity before (outside[] lists the cavity's boundary as (triangle,
 * edge) pairs). Large cavities only (segment recovery): by sorting. */
static bool link_big(tsr_cdt *d, const uint32_t *slots, uint32_t n, const link_rec *outside, uint32_t nout)
{
    size_t m = 3 * (size_t)n + nout;
    link_rec *r = tsr_alloc(da(d), m * sizeof *r);
    if (!r)
        return false;
    size_t q = 0;
    for (uint32_t i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            const uint32_t *v = d->tv + 3 * (size_t)slots[i];
            r[q].key = cdt_edge_key(v[k], v[(k + 1) % 3]);
            r[q].t = slots[i];
            r[q].k = k;
            q++;
        }
    for (uint32_t i = 0; i < nout; i++)
        r[q++] = outside[i];
    qsort(r, m, sizeof *r, link_cmp);
    for (size_t i = 0; i + 1 < m; i++) {
        if (r[i].key != r[i + 1].key)
            continue;
        link_rec *a = &r[i], *b = &r[i + 1];
        d->tn[3 * (size_t)a->t + a->k] = b->t;
        d->tn[3 * (size_t)b->t + b->k] = a->t;
        i++;
    }
    tsr_free(da(d), r);
    return true;
}

/* Marked edges inside a cavity (both triangles in it), to be kept. */
typedef struct slit {
    uint32_t a, b, m;
} slit;

/* Marks again, in the new triangles out[0..n), the edges of slits[] that
 * are still edges. */
static void remark_slits(tsr_cdt *d, const uint32_t *out, uint32_t n, const slit *slits, uint32_t ns)
{
    for (uint32_t e = 0; e < ns; e++)
        for (uint32_t i = 0; i < n; i++) {
            int k = edge_index(d, out[i], slits[e].a, slits[e].b);
            if (k < 0)
                k = edge_index(d, out[i], slits[e].b, slits[e].a);
            if (k >= 0) {
                tsr__cdt_mark_edge(d, out[i], k, slits[e].m);
                break;
            }
        }
}

/* Replaces the triangles old[0..nold) (a cavity) by the triangles given as
 * vertex triples in nw[0..nnew) (nnew >= nold), reusing the old slots
 * first, and links every edge: to the other new triangles, or to what was
 * across that edge of the cavity before. Marks on the cavity's boundary are
 * kept; so are marks on edges inside it (a constrained edge dangling into
 * the region a segment sweeps: the segment passes by it, through the
 * triangles on both its sides, and the pseudo-polygon walks along both
 * sides of it) where the new triangles still have that edge; other
 * interior edges are unmarked. New triangles take old[0]'s flag.
 * Out: the new triangles' slots. */
static bool retriangulate(tsr_cdt *d, const uint32_t *old, uint32_t nold, const uint32_t (*nw)[3], uint32_t nnew,
                          uint32_t *out)
{
    uint32_t flag = d->tf ? d->tf[old[0]] : 0;
    if (nold > 5 || nnew > 8) {
        /* the cavity's boundary, as the outside triangles' edges; cavity
         * membership by binary search in a sorted copy of old */
        link_rec *bnd = tsr_alloc(da(d), 3 * (size_t)nold * sizeof *bnd);
        uint32_t *sorted = tsr_alloc(da(d), (size_t)nold * sizeof *sorted);
        slit *slits = NULL;
        bool ok = bnd && sorted;
        uint32_t nb = 0, nsl = 0;
        if (ok) {
            memcpy(sorted, old, (size_t)nold * sizeof *sorted);
            qsort(sorted, nold, sizeof *sorted, u32_cmp);
            for (uint32_t i = 0; i < nold && ok; i++)
                for (int k = 0; k < 3; k++) {
                    uint32_t nbr = d->tn[3 * (size_t)old[i] + k];
                    if (bsearch(&nbr, sorted, nold, sizeof *sorted, u32_cmp)) {
                        uint32_t m = cdt_mark(d, old[i], k);
                        if (m && old[i] < nbr) { /* once per edge */
                            if (!slits)
                                slits = tsr_alloc(da(d), 3 * (size_t)nold * sizeof *slits);
                            if (!slits) {
                                ok = false;
                                break;
                            }
                            const uint32_t *v = d->tv + 3 * (size_t)old[i];
                            slits[nsl++] = (slit){v[k], v[(k + 1) % 3], m};
                        }
                        continue;
                    }
                    const uint32_t *v = d->tv + 3 * (size_t)old[i];
                    bnd[nb].key = cdt_edge_key(v[k], v[(k + 1) % 3]);
                    bnd[nb].t = nbr;
                    bnd[nb].k = edge_index(d, nbr, v[(k + 1) % 3], v[k]);
                    nb++;
                }
        }
        for (uint32_t i = 0; i < nnew && ok; i++) {
            out[i] = i < nold ? old[i] : new_triangle(d);
            ok = out[i] != NONE;
        }
        if (ok) {
            for (uint32_t i = 0; i < nnew; i++)
                for (int k = 0; k < 3; k++) {
                    d->tv[3 * (size_t)out[i] + k] = nw[i][k];
                    if (d->tc)
                        d->tc[3 * (size_t)out[i] + k] = 0;
                }
            ok = link_big(d, out, nnew, bnd, nb);
        }
        if (ok && d->tc) /* boundary marks, from the outside */
            for (uint32_t e = 0; e < nb; e++) {
                const uint32_t *v = d->tv + 3 * (size_t)bnd[e].t;
                uint32_t in = d->tn[3 * (size_t)bnd[e].t + bnd[e].k];
                int j = edge_index(d, in, v[(bnd[e].k + 1) % 3], v[bnd[e].k]);
                if (j >= 0)
                    d->tc[3 * (size_t)in + j] = d->tc[3 * (size_t)bnd[e].t + bnd[e].k];
            }
        if (ok && nsl)
            remark_slits(d, out, nnew, slits, nsl);
        tsr_free(da(d), bnd);
        tsr_free(da(d), sorted);
        tsr_free(da(d), slits);
        if (!ok)
            return false;
    } else {
        typedef struct {
            uint32_t a, b, t, m;
        } bedge;
        bedge bnd[15];
        slit slits[8];
        int nb = 0;
        uint32_t nsl = 0;
        for (uint32_t i = 0; i < nold; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t nbr = d->tn[3 * (size_t)old[i] + k];
                bool inside = false;
                for (uint32_t j = 0; j < nold; j++)
                    inside |= nbr == old[j];
                uint32_t m = inside && old[i] < nbr ? cdt_mark(d, old[i], k) : 0;
                if (m && nsl < 8) {
                    const uint32_t *v = d->tv + 3 * (size_t)old[i];
                    slits[nsl++] = (slit){v[k], v[(k + 1) % 3], m};
                }
                if (!inside) {
                    bnd[nb].a = d->tv[3 * (size_t)old[i] + k];
                    bnd[nb].b = d->tv[3 * (size_t)old[i] + (k + 1) % 3];
                    bnd[nb].t = nbr;
                    bnd[nb].m = cdt_mark(d, old[i], k);
                    nb++;
                }
            }
        for (uint32_t i = 0; i < nnew; i++) {
            out[i] = i < nold ? old[i] : new_triangle(d);
            if (out[i] == NONE)
                return false;
        }
        for (uint32_t i = 0; i < nnew; i++)
            for (int k = 0; k < 3; k++)
                d->tv[3 * (size_t)out[i] + k] = nw[i][k];
        for (uint32_t i = 0; i < nnew; i++)
            for (int k = 0; k < 3; k++) {
                uint32_t x = nw[i][k], y = nw[i][(k + 1) % 3], across = NONE, m = 0;
                for (uint32_t j = 0; j < nnew && across == NONE; j++)
                    for (int q = 0; q < 3; q++)
                        if (nw[j][q] == y && nw[j][(q + 1) % 3] == x) {
                            across = out[j];
                            break;
                        }
                if (across == NONE)
                    for (int e = 0; e < nb; e++)
                        if (bnd[e].a == x && bnd[e].b == y) {
                            across = bnd[e].t;
                            m = bnd[e].m;
                            /* and the outside triangle points back here */
                            int q = edge_index(d, across, y, x);
                            if (q >= 0)
                                d->tn[3 * (size_t)across + q] = out[i];
                            break;
                        }
                d->tn[3 * (size_t)out[i] + k] = across;
                if (d->tc)
                    d->tc[3 * (size_t)out[i] + k] = m;
            }
        if (nsl)
            remark_slits(d, out, nnew, slits, nsl);
    }
    for (uint32_t i = 0; i < nnew; i++) {
        if (d->tf)
            d->tf[out[i]] = flag;
        if (d->track && !append(d, &d->changed, &d->nchanged, &d->cap_changed, out[i]))
            return false;
    }
    return true;
}

/* In triangle n, the edge from x to y now faces triangle t. */
static void repoint(tsr_cdt *d, uint32_t n, uint32_t x, uint32_t y, uint32_t t)
{
    int k = edge_index(d, n, x, y);
    if (k >= 0)
        d->tn[3 * (size_t)n + k] = t;
}

static void set_tri(tsr_cdt *d, uint32_t t, uint32_t a, uint32_t b, uint32_t c, uint32_t na, uint32_t nb, uint32_t nc)
{
    uint32_t *v = d->tv + 3 * (size_t)t, *n = d->tn + 3 * (size_t)t;
    v[0] = a, v[1] = b, v[2] = c;
    n[0] = na, n[1] = nb, n[2] = nc;
}

/* Flips the edge between t1 = (p, x, y) (p at index i) and t2 = (y, x, q):
 * t1 becomes (p, x, q) and t2 (p, q, y). The fast path of legalize. */
static bool flip(tsr_cdt *d, uint32_t t1, int i, uint32_t t2)
{
    uint32_t *v = d->tv + 3 * (size_t)t1;
    uint32_t p = v[i], x = v[(i + 1) % 3], y = v[(i + 2) % 3];
    uint32_t n_px = d->tn[3 * (size_t)t1 + i], n_yp = d->tn[3 * (size_t)t1 + (i + 2) % 3];
    int j = edge_index(d, t2, y, x);
    uint32_t q = d->tv[3 * (size_t)t2 + (j + 2) % 3];
    uint32_t n_xq = d->tn[3 * (size_t)t2 + (j + 1) % 3], n_qy = d->tn[3 * (size_t)t2 + (j + 2) % 3];
    if (d->tc) {
        uint32_t *c1 = d->tc + 3 * (size_t)t1, *c2 = d->tc + 3 * (size_t)t2;
        uint32_t m_px = c1[i], m_yp = c1[(i + 2) % 3], m_xq = c2[(j + 1) % 3], m_qy = c2[(j + 2) % 3];
        c1[0] = m_px, c1[1] = m_xq, c1[2] = 0;
        c2[0] = 0, c2[1] = m_qy, c2[2] = m_yp;
    }
    set_tri(d, t1, p, x, q, n_px, n_xq, t2);
    set_tri(d, t2, p, q, y, t1, n_qy, n_yp);
    repoint(d, n_xq, q, x, t1);
    repoint(d, n_yp, p, y, t2);
    if (d->track)
        return append(d, &d->changed, &d->nchanged, &d->cap_changed, t1) &&
               append(d, &d->changed, &d->nchanged, &d->cap_changed, t2);
    return true;
}

/* Splits t = (a, b, c) at pv into (a, b, pv), (b, c, pv), (c, a, pv); out
 * receives the three slots (t first). */
static bool split3(tsr_cdt *d, uint32_t t, uint32_t pv, uint32_t out[3])
{
    uint32_t t1 = new_triangle(d), t2 = t1 == NONE ? NONE : new_triangle(d);
    if (t2 == NONE)
        return false;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t a = v[0], b = v[1], c = v[2];
    uint32_t n_ab = d->tn[3 * (size_t)t], n_bc = d->tn[3 * (size_t)t + 1], n_ca = d->tn[3 * (size_t)t + 2];
    if (d->tc) {
        uint32_t m_bc = d->tc[3 * (size_t)t + 1], m_ca = d->tc[3 * (size_t)t + 2];
        d->tc[3 * (size_t)t + 1] = d->tc[3 * (size_t)t + 2] = 0;
        d->tc[3 * (size_t)t1] = m_bc, d->tc[3 * (size_t)t1 + 1] = d->tc[3 * (size_t)t1 + 2] = 0;
        d->tc[3 * (size_t)t2] = m_ca, d->tc[3 * (size_t)t2 + 1] = d->tc[3 * (size_t)t2 + 2] = 0;
    }
    if (d->tf)
        d->tf[t1] = d->tf[t2] = d->tf[t];
    set_tri(d, t, a, b, pv, n_ab, t1, t2);
    set_tri(d, t1, b, c, pv, n_bc, t2, t);
    set_tri(d, t2, c, a, pv, n_ca, t, t1);
    repoint(d, n_bc, c, b, t1);
    repoint(d, n_ca, a, c, t2);
    out[0] = t, out[1] = t1, out[2] = t2;
    if (d->track)
        for (int k = 0; k < 3; k++)
            if (!append(d, &d->changed, &d->nchanged, &d->cap_changed, out[k]))
                return false;
    return true;
}

/* ---- location ----------------------------------------------------------- */

#define IN_TRIANGLE CDT_IN_TRIANGLE
#define ON_EDGE CDT_ON_EDGE
#define ON_VERTEX CDT_ON_VERTEX
#define IN_GHOST CDT_IN_GHOST

/* The finite edge (w, u) of ghost t, in the ghost's orientation: points
 * strictly outside the hull there have orient2d(w, u, p) > 0. */
static int ghost_edge(const tsr_cdt *d, uint32_t t)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    for (int k = 0; k < 3; k++)
        if (v[k] != GHOST && v[(k + 1) % 3] != GHOST)
            return k;
    return 0;
}

uint32_t tsr__cdt_locate(tsr_cdt *d, const double p[2], int *kind, int *which)
{
    uint32_t t = d->last < d->nt ? d->last : 0;
    uint64_t steps = 0, limit = 4ull * d->nt + 16;
    for (;;) {
        if (++steps > limit) {
            /* a walk that does not end (it cannot in a Delaunay
             * triangulation, but be safe): scan every triangle */
            for (uint32_t s = 0; s < d->nt; s++) {
                if (is_ghost(d, s))
                    continue;
                const uint32_t *v = d->tv + 3 * (size_t)s;
                double o[3];
                for (int k = 0; k < 3; k++)
                    o[k] = tsr_orient2d(P(d, v[k]), P(d, v[(k + 1) % 3]), p);
                if (o[0] >= 0 && o[1] >= 0 && o[2] >= 0) {
                    t = s;
                    steps = 0;
                    limit = UINT64_MAX;
                    break;
                }
            }
            if (steps != 0) { /* outside: find a ghost that sees p */
                for (uint32_t s = 0; s < d->nt; s++)
                    if (is_ghost(d, s)) {
                        int k = ghost_edge(d, s);
                        const uint32_t *v = d->tv + 3 * (size_t)s;
                        if (tsr_orient2d(P(d, v[k]), P(d, v[(k + 1) % 3]), p) > 0) {
                            *kind = IN_GHOST;
                            *which = k;
                            return s;
                        }
                    }
            }
        }
        const uint32_t *v = d->tv + 3 * (size_t)t;
        if (is_ghost(d, t)) {
            int k = ghost_edge(d, t);
            if (tsr_orient2d(P(d, v[k]), P(d, v[(k + 1) % 3]), p) > 0) {
                *kind = IN_GHOST;
                *which = k;
                return t;
            }
            t = d->tn[3 * (size_t)t + k];
            continue;
        }
        double o[3];
        for (int k = 0; k < 3; k++)
            o[k] = tsr_orient2d(P(d, v[k]), P(d, v[(k + 1) % 3]), p);
        int start = (int)(d->walk_turn++ % 3), next = -1;
        for (int j = 0; j < 3; j++) {
            int k = (start + j) % 3;
            if (o[k] < 0) {
                next = k;
                break;
            }
        }
        if (next >= 0) {
            t = d->tn[3 * (size_t)t + next];
            continue;
        }
        int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
        if (zeros == 0) {
            *kind = IN_TRIANGLE;
            *which = 0;
        } else if (zeros == 1) {
            *kind = ON_EDGE;
            *which = o[0] == 0 ? 0 : o[1] == 0 ? 1 : 2;
        } else {
            *kind = ON_VERTEX;
            /* the vertex shared by the two zero edges: edge k and k+1 share
             * vertex k+1 */
            *which = o[0] != 0 ? 2 : o[1] != 0 ? 0 : 1;
        }
        return t;
    }
}

/* ---- insertion -------------------------------------------------------- */

/* Does p conflict with triangle t (lie in its circumcircle, or strictly
 * outside the hull edge of a ghost)? */
static bool conflict(const tsr_cdt *d, uint32_t t, const double p[2])
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    if (is_ghost(d, t)) {
        int k = ghost_edge(d, t);
        return tsr_orient2d(P(d, v[k]), P(d, v[(k + 1) % 3]), p) > 0;
    }
    return tsr_incircle(P(d, v[0]), P(d, v[1]), P(d, v[2]), p) > 0;
}

static bool push(tsr_cdt *d, uint32_t t)
{
    return append(d, &d->stack, &d->nstack, &d->cap_stack, t);
}

static bool legalize(tsr_cdt *d, uint32_t pv)
{
    const double *p = P(d, pv);
    while (d->nstack > 0) {
        uint32_t t1 = d->stack[--d->nstack];
        const uint32_t *v = d->tv + 3 * (size_t)t1;
        int i = v[0] == pv ? 0 : v[1] == pv ? 1 : 2;
        uint32_t t2 = d->tn[3 * (size_t)t1 + (i + 1) % 3];
        if (cdt_mark(d, t1, (i + 1) % 3) || !conflict(d, t2, p))
            continue;
        if (!flip(d, t1, i, t2) || !push(d, t1) || !push(d, t2))
            return false;
    }
    return true;
}

static bool start_triangulation(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t c)
{
    if (tsr_orient2d(P(d, a), P(d, b), P(d, c)) < 0) {
        uint32_t s = b;
        b = c;
        c = s;
    }
    uint32_t t0 = new_triangle(d), g0 = new_triangle(d), g1 = new_triangle(d), g2 = new_triangle(d);
    if (g2 == NONE || g1 == NONE || g0 == NONE || t0 == NONE)
        return false;
    uint32_t tris[4][3] = {{a, b, c}, {b, a, GHOST}, {c, b, GHOST}, {a, c, GHOST}};
    uint32_t nbrs[4][3] = {{g0, g1, g2}, {t0, g2, g1}, {t0, g0, g2}, {t0, g1, g0}};
    uint32_t idx[4] = {t0, g0, g1, g2};
    for (int i = 0; i < 4; i++)
        for (int k = 0; k < 3; k++) {
            d->tv[3 * (size_t)idx[i] + k] = tris[i][k];
            d->tn[3 * (size_t)idx[i] + k] = nbrs[i][k];
        }
    d->started = true;
    d->last = t0;
    return true;
}

/* The vertex of s that is neither x nor y. */
static uint32_t apex(const tsr_cdt *d, uint32_t s, uint32_t x, uint32_t y)
{
    const uint32_t *w = d->tv + 3 * (size_t)s;
    return w[0] != x && w[0] != y ? w[0] : w[1] != x && w[1] != y ? w[1] : w[2];
}

/* Splits edge k of t (shared with s) at pv: four triangles, the halves of
 * a constrained edge keep its mark, each side keeps its flag. */
static bool split_edge_at(tsr_cdt *d, uint32_t t, int k, uint32_t pv)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
    uint32_t s = d->tn[3 * (size_t)t + k];
    uint32_t q = apex(d, s, a, b);
    uint32_t m = cdt_mark(d, t, k);
    uint32_t ft = d->tf ? d->tf[t] : 0, fs = d->tf ? d->tf[s] : 0;
    uint32_t old[2] = {t, s}, nw[4][3] = {{a, pv, c}, {pv, b, c}, {b, pv, q}, {pv, a, q}}, out[4];
    if (!retriangulate(d, old, 2, nw, 4, out))
        return false;
    if (d->tf) {
        d->tf[out[0]] = d->tf[out[1]] = ft;
        d->tf[out[2]] = d->tf[out[3]] = fs;
    }
    if (m) {
        tsr__cdt_mark_edge(d, out[0], 0, m);
        tsr__cdt_mark_edge(d, out[1], 0, m);
    }
    for (int i = 0; i < 4; i++) /* triangles outside a domain being refined are left alone */
        if ((!d->tf || d->tf[out[i]] != CDT_OUTSIDE) && !push(d, out[i]))
            return false;
    return true;
}

static bool restore_delaunay(tsr_cdt *d, uint32_t t, int k);
static uint32_t triangle_at(tsr_cdt *d, uint32_t a, int *ia);

/* Lawson's flips from the new vertex's star test the edges opposite it
 * only; that the edges at it are Delaunay follows where it lies on the
 * edge it split, or inside the triangle it split. A rounded crossing lies
 * an ulp beside the split edge, perhaps inside the triangle beyond it,
 * whose circle then holds the far apex: the edge from the new vertex to
 * the near apex, between the sliver at the edge's end and its neighbour,
 * may not be Delaunay (a vertex an ulp from the edge's end made one a
 * unit long, found by fuzzing). Such edges at pv are flipped, and the
 * flips carried outwards. */
static bool settle_star(tsr_cdt *d, uint32_t pv)
{
    for (int round = 0; round < 64; round++) {
        int ip;
        uint32_t t0 = triangle_at(d, pv, &ip), t = t0, bad = NONE;
        int bk = 0;
        for (uint32_t guard = 0; t != NONE && guard <= d->nt; guard++) {
            const uint32_t *v = d->tv + 3 * (size_t)t;
            uint32_t s = d->tn[3 * (size_t)t + ip];
            if (!cdt_mark(d, t, ip) && !is_ghost(d, t) && !is_ghost(d, s) &&
                tsr_incircle(P(d, v[0]), P(d, v[1]), P(d, v[2]), P(d, apex(d, s, v[ip], v[(ip + 1) % 3]))) > 0) {
                bad = t, bk = ip;
                break;
            }
            t = d->tn[3 * (size_t)t + (ip + 2) % 3];
            const uint32_t *w = d->tv + 3 * (size_t)t;
            ip = w[0] == pv ? 0 : w[1] == pv ? 1 : 2;
            if (t == t0)
                break;
        }
        if (bad == NONE)
            return true;
        if (!restore_delaunay(d, bad, bk))
            return false;
    }
    return true;
}

bool tsr__cdt_split_edge(tsr_cdt *d, uint32_t t, int k, uint32_t pv, bool *nomem)
{
    *nomem = false;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t a = v[k], b = v[(k + 1) % 3], c = v[(k + 2) % 3];
    uint32_t s = d->tn[3 * (size_t)t + k];
    uint32_t q = apex(d, s, a, b);
    const double *p = P(d, pv);
    if (a == GHOST || b == GHOST || c == GHOST)
        return false;
    if (tsr_orient2d(P(d, a), p, P(d, c)) <= 0 || tsr_orient2d(p, P(d, b), P(d, c)) <= 0)
        return false;
    bool outside = d->tf && d->tf[s] == CDT_OUTSIDE; /* never looked at again: its shape does not matter */
    if (q != GHOST && !outside && (tsr_orient2d(P(d, b), p, P(d, q)) <= 0 || tsr_orient2d(p, P(d, a), P(d, q)) <= 0))
        return false;
    /* on a hull edge (q the ghost), a point rounded off the edge's line
     * leaves the hull very slightly non-convex; only refinement, which
     * walks inside marked boundaries, splits hull edges, and it leaves the
     * triangles outside its domain unflipped */
    d->nstack = 0;
    if (!split_edge_at(d, t, k, pv) || !legalize(d, pv) || (!d->tf && !settle_star(d, pv))) {
        *nomem = true;
        return false;
    }
    d->last = t;
    return true;
}

uint32_t tsr__cdt_insert_at(tsr_cdt *d, uint32_t pv, uint32_t t, int kind, int which)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    d->nstack = 0;
    if (kind == ON_VERTEX) {
        d->dups++;
        if (pv == d->nv - 1)
            d->nv--; /* pv was the last vertex stored */
        return v[which];
    }
    if (kind == IN_TRIANGLE || kind == IN_GHOST) {
        uint32_t out[3];
        if (!split3(d, t, pv, out))
            return NONE;
        for (int i = 0; i < 3; i++)
            if (!push(d, out[i]))
                return NONE;
    } else if (!split_edge_at(d, t, which, pv)) /* on edge `which` of finite t */
        return NONE;
    if (!legalize(d, pv))
        return NONE;
    d->last = t; /* its slot now holds a triangle at pv: the next walk starts there */
    return pv;
}

/* Inserts internal vertex pv (already stored) into a started
 * triangulation. Returns the vertex to report: pv, or an existing vertex
 * when pv duplicates it (then pv is dropped). */
static uint32_t insert_vertex(tsr_cdt *d, uint32_t pv)
{
    int kind, which;
    uint32_t t = tsr__cdt_locate(d, P(d, pv), &kind, &which);
    return tsr__cdt_insert_at(d, pv, t, kind, which);
}

uint32_t tsr_cdt_insert(tsr_cdt *d, double x, double y)
{
    if (!isfinite(x) || !isfinite(y))
        return NONE;
    if (!d->started) {
        for (uint32_t i = 0; i < d->npending; i++) {
            const double *q = P(d, d->pending[i]);
            if (q[0] == x && q[1] == y) {
                d->dups++;
                return d->pending[i] - 1;
            }
        }
        uint32_t v = add_vertex(d, x, y);
        if (v == NONE)
            return NONE;
        if (d->npending >= 2 && tsr_orient2d(P(d, d->pending[0]), P(d, d->pending[1]), P(d, v)) != 0) {
            if (!start_triangulation(d, d->pending[0], d->pending[1], v))
                return NONE;
            for (uint32_t i = 2; i < d->npending; i++)
                if (insert_vertex(d, d->pending[i]) == NONE)
                    return NONE;
            d->npending = 0;
            return v - 1;
        }
        if (!append(d, &d->pending, &d->npending, &d->cap_pending, v))
            return NONE;
        return v - 1;
    }
    uint32_t v = add_vertex(d, x, y);
    if (v == NONE)
        return NONE;
    uint32_t r = insert_vertex(d, v);
    return r == NONE ? NONE : r - 1;
}

uint32_t tsr_cdt_insert_near(tsr_cdt *d, double x, double y, uint32_t near)
{
    if (near < d->nt)
        d->last = near;
    return tsr_cdt_insert(d, x, y);
}

/* ---- segments --------------------------------------------------------- */

/* Triangulates the pseudo-polygon c[0..m) (c[0] and c[m-1] the ends of the
 * new edge, the chain on its left when left, else on its right) by the
 * recursive rule of Anglada (1997): the base's third vertex is the chain
 * vertex whose circle with the base holds no other; appends triangles to
 * d->nwt (3 per triangle). */
static bool pseudo_polygon(tsr_cdt *d, const uint32_t *c, uint32_t m, bool left)
{
    if (m < 3)
        return true;
    /* explicit stack of (lo, hi) ranges */
    uint32_t *st = NULL, nst = 0, cap = 0;
    bool ok = append(d, &st, &nst, &cap, 0) && append(d, &st, &nst, &cap, m - 1);
    while (ok && nst > 0) {
        uint32_t hi = st[--nst], lo = st[--nst];
        if (hi - lo < 2)
            continue;
        uint32_t k = lo + 1;
        for (uint32_t j = lo + 2; j < hi; j++) {
            const double *A = P(d, c[lo]), *B = P(d, c[hi]), *K = P(d, c[k]), *J = P(d, c[j]);
            double in = left ? tsr_incircle(A, B, K, J) : tsr_incircle(B, A, K, J);
            if (in > 0)
                k = j;
        }
        uint32_t t0 = left ? c[lo] : c[hi], t1 = left ? c[hi] : c[lo];
        ok = append(d, &d->nwt, &d->nnwt, &d->cap_nwt, t0) && append(d, &d->nwt, &d->nnwt, &d->cap_nwt, t1) &&
             append(d, &d->nwt, &d->nnwt, &d->cap_nwt, c[k]) && append(d, &st, &nst, &cap, lo) &&
             append(d, &st, &nst, &cap, k) && append(d, &st, &nst, &cap, k) && append(d, &st, &nst, &cap, hi);
    }
    tsr_free(da(d), st);
    return ok;
}

/* The triangle around vertex a (index *ia in it), found by location. */
static uint32_t triangle_at(tsr_cdt *d, uint32_t a, int *ia)
{
    int kind;
    uint32_t t = tsr__cdt_locate(d, P(d, a), &kind, ia);
    if (kind != ON_VERTEX)
        return NONE;
    /* the next walk starts here: a chain's next segment begins at this
     * one's end, an edge or so away (a loop of 10^5 points had each of its
     * walks start where the last point was inserted) */
    d->last = t;
    return t;
}

/* STEP_GIVE_UP: a nested insertion passed its step limit (TSR_ERR_VALUE) */
typedef enum { STEP_DONE, STEP_AGAIN, STEP_NOMEM, STEP_GIVE_UP } step_result;

static step_result step_of(tsr_status st)
{
    return st == TSR_OK ? STEP_AGAIN : st == TSR_ERR_VALUE ? STEP_GIVE_UP : STEP_NOMEM;
}

static tsr_status insert_chain(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t mark, int depth);

/* Lawson's flips from edge k of t outwards, after that edge lost its
 * constraint: every unconstrained edge reached is made locally Delaunay
 * again. */
static bool restore_delaunay(tsr_cdt *d, uint32_t t, int k)
{
    uint32_t *st = NULL, n = 0, cap = 0;
    bool ok = append(d, &st, &n, &cap, 3 * t + (uint32_t)k);
    for (uint64_t guard = 0; ok && n > 0 && guard < 64ull * d->nt + 64; guard++) {
        uint32_t e = st[--n], t1 = e / 3;
        int k1 = (int)(e % 3);
        uint32_t t2 = d->tn[3 * (size_t)t1 + k1];
        if (cdt_mark(d, t1, k1) || is_ghost(d, t1) || is_ghost(d, t2))
            continue;
        const uint32_t *v = d->tv + 3 * (size_t)t1;
        int i = (k1 + 2) % 3; /* the apex opposite edge k1 */
        if (tsr_incircle(P(d, v[0]), P(d, v[1]), P(d, v[2]), P(d, apex(d, t2, v[k1], v[(k1 + 1) % 3]))) <= 0)
            continue;
        if (!flip(d, t1, i, t2))
            ok = false;
        /* t1 = (p, x, q), t2 = (p, q, y): their four outer edges */
        ok = ok && append(d, &st, &n, &cap, 3 * t1) && append(d, &st, &n, &cap, 3 * t1 + 1) &&
             append(d, &st, &n, &cap, 3 * t2 + 1) && append(d, &st, &n, &cap, 3 * t2 + 2);
    }
    tsr_free(da(d), st);
    return ok;
}

/* orient2d(a, b, c) with an accurate magnitude, for lengths and
 * parameters (its sign is tsr_orient2d's, exact). tsr_orient2d's value is
 * the floating-point determinant about its third point, whose error is
 * eps times the product of the two sides at that point: about a point far
 * from the other two (a segment's end at 1e22 beside points near 1) that
 * is 1e22 times the determinant's own size, and a crossing computed from
 * it strays 1e-7 off its segment. About the vertex opposite the longest
 * side the product is least: the error is then eps over the sine of the
 * triangle's largest angle. */
static double orient_value(const double *a, const double *b, const double *c)
{
    double ab = (b[0] - a[0]) * (b[0] - a[0]) + (b[1] - a[1]) * (b[1] - a[1]);
    double bc = (c[0] - b[0]) * (c[0] - b[0]) + (c[1] - b[1]) * (c[1] - b[1]);
    double ca = (a[0] - c[0]) * (a[0] - c[0]) + (a[1] - c[1]) * (a[1] - c[1]);
    if (ab >= bc && ab >= ca)
        return tsr_orient2d(a, b, c);
    return bc >= ca ? tsr_orient2d(b, c, a) : tsr_orient2d(c, a, b);
}

/* The triangle with the directed edge x -> y (its index in *k), or NONE. */
static uint32_t edge_triangle(tsr_cdt *d, uint32_t x, uint32_t y, int *k)
{
    int ix;
    uint32_t t0 = triangle_at(d, x, &ix), t = t0;
    for (uint32_t guard = 0; t != NONE && guard <= d->nt; guard++) {
        const uint32_t *v = d->tv + 3 * (size_t)t;
        if (v[(ix + 1) % 3] == y) {
            *k = ix;
            return t;
        }
        t = d->tn[3 * (size_t)t + (ix + 2) % 3];
        const uint32_t *w = d->tv + 3 * (size_t)t;
        ix = w[0] == x ? 0 : w[1] == x ? 1 : 2;
        if (t == t0)
            break;
    }
    return NONE;
}

/* The constrained edge k of t (x-y, mark m) bent through vertex w: its
 * constraint dropped (and the Delaunay property restored around it), then
 * x-w and w-y inserted with the same mark. */
static tsr_status bend_through(tsr_cdt *d, uint32_t t, int k, uint32_t w, uint32_t m, int depth)
{
    uint32_t x = d->tv[3 * (size_t)t + k], y = d->tv[3 * (size_t)t + (k + 1) % 3];
    tsr__cdt_mark_edge(d, t, k, 0);
    if (!restore_delaunay(d, t, k))
        return TSR_ERR_NOMEM;
    tsr_status st = insert_chain(d, x, w, m, depth + 1);
    return st == TSR_OK ? insert_chain(d, w, y, m, depth + 1) : st;
}

/* split_crossing's last resort before a far vertex: the rounded crossing
 * R of a segment and the constrained edge x-y (mark m), inserted wherever
 * it falls (into a triangle, onto an edge, constrained or not, or onto a
 * vertex there), x-y bent through it, and it pushed as the segment's next
 * target. STEP_DONE: not done (R falls outside the hull), the caller goes
 * on. */
static step_result through_rounded(tsr_cdt *d, uint32_t x, uint32_t y, uint32_t m, const double R[2], int depth)
{
    int kind, which;
    uint32_t lt = tsr__cdt_locate(d, R, &kind, &which), w;
    if (kind == IN_GHOST)
        return STEP_DONE;
    if (kind == ON_VERTEX)
        w = d->tv[3 * (size_t)lt + which];
    else {
        w = add_vertex(d, R[0], R[1]);
        if (w == NONE || tsr__cdt_insert_at(d, w, lt, kind, which) == NONE)
            return STEP_NOMEM;
        d->intersections++;
    }
    int k;
    uint32_t t = w == x || w == y ? NONE : edge_triangle(d, x, y, &k);
    /* still an edge (else w fell on it and split it, marks kept) */
    if (t != NONE) {
        step_result r = step_of(bend_through(d, t, k, w, m, depth));
        if (r != STEP_AGAIN)
            return r;
    }
    return append(d, &d->targets, &d->ntargets, &d->cap_targets, w) ? STEP_AGAIN : STEP_NOMEM;
}

/* Segment a-b crosses the constrained edge k of t (x-y): splits that edge
 * at (about) the crossing point, and pushes the new vertex as the next
 * target. Where the rounded crossing cannot be used (it falls on or
 * within rounding of a vertex, or would invert a triangle: a sliver beside
 * the edge), the vertex whose use moves the geometry least takes its
 * place: an end of the crossed edge (the segment is routed through it), or
 * an end of the segment or the apex of a triangle beside the edge (the
 * crossed edge is bent through it: its constraint is replaced by two
 * constrained edges to that vertex). */
static step_result split_crossing(tsr_cdt *d, uint32_t t, int k, uint32_t a, uint32_t b, int depth)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t x = v[k], y = v[(k + 1) % 3];
    const double *A = P(d, a), *B = P(d, b), *X = P(d, x), *Y = P(d, y);
    /* the crossing, computed from whichever of the four ends is nearest to
     * it: its error is then a few ulps of that distance, where a parameter
     * along the whole edge would carry an error of the edge's length (an
     * end at 1e30 moves a crossing near 1 by 1e14). x and y lie strictly on
     * either side of a-b, a and b of x-y. */
    double ox = orient_value(A, B, X), oy = orient_value(A, B, Y);
    double oa = orient_value(X, Y, A), ob = orient_value(X, Y, B);
    double lab = hypot(B[0] - A[0], B[1] - A[1]), lxy = hypot(Y[0] - X[0], Y[1] - X[1]);
    const double *from[4] = {X, Y, A, B}, *to[4] = {Y, X, B, A};
    double f[4] = {ox / (ox - oy), oy / (oy - ox), oa / (oa - ob), ob / (ob - oa)};
    int e = 0;
    for (int i = 1; i < 4; i++)
        if (f[i] * (i < 2 ? lxy : lab) < f[e] * (e < 2 ? lxy : lab))
            e = i;
    double R[2] = {NAN, NAN}; /* the rounded crossing, when it is one */
    if (f[e] > 0 && f[e] < 1) {
        const double *E = from[e], *F = to[e];
        R[0] = E[0] + f[e] * (F[0] - E[0]);
        R[1] = E[1] + f[e] * (F[1] - E[1]);
        uint32_t pv = add_vertex(d, R[0], R[1]);
        if (pv == NONE)
            return STEP_NOMEM;
        bool nomem;
        if (tsr__cdt_split_edge(d, t, k, pv, &nomem)) {
            d->intersections++;
            return append(d, &d->targets, &d->ntargets, &d->cap_targets, pv) ? STEP_AGAIN : STEP_NOMEM;
        }
        d->nv--;
        if (nomem)
            return STEP_NOMEM;
        A = P(d, a), B = P(d, b), X = P(d, x), Y = P(d, y); /* add_vertex may move the array */
    }
    d->snapped++;
    /* the vertex that moves the geometry least: an end of the crossed edge
     * (the segment bends through it: it moves by its distance from a-b), or
     * a vertex strictly beside the crossed edge's span, within the two
     * triangles' corners or the segment's ends (the crossed constraint
     * bends through it). Nearness to the rounded crossing alone can pick an
     * end of a long crossed edge far from the segment, where the split
     * failed on a sliver beside the edge, whose apex is the vertex to use. */
    uint32_t c = v[(k + 2) % 3], q = apex(d, d->tn[3 * (size_t)t + k], x, y);
    uint32_t cand[6] = {x, y, a, b, c, q}, best = NONE;
    double best_dev = INFINITY;
    /* an end of the crossed edge behind a or beyond b along the segment
     * would run its chain backwards (found by a reviewer's stress test:
     * once the crossing was placed exactly, its split failed on a sliver
     * and the nearest end lay behind the segment's start): such ends are
     * taken only where nothing else is left */
    bool plain = depth >= 8 || d->plain;
    for (int relaxed = 0; relaxed < 2 && best == NONE; relaxed++)
        for (uint32_t i = 0; i < (relaxed ? 2u : 6u); i++) {
            uint32_t w = cand[i];
            if (w == GHOST || (i >= 2 && (plain || w == x || w == y)))
                continue;
            const double *W = P(d, w);
            double dev;
            if (i < 2) {
                if (!relaxed && !((W[0] - A[0]) * (B[0] - A[0]) + (W[1] - A[1]) * (B[1] - A[1]) > 0 &&
                                  (W[0] - B[0]) * (A[0] - B[0]) + (W[1] - B[1]) * (A[1] - B[1]) > 0))
                    continue;
                dev = fabs(orient_value(A, B, W)) / lab;
            } else {
                /* from either end: one sum near |x-y|^2 would round away a
                 * vertex just inside the far end */
                if (!((W[0] - X[0]) * (Y[0] - X[0]) + (W[1] - X[1]) * (Y[1] - X[1]) > 0 &&
                      (W[0] - Y[0]) * (X[0] - Y[0]) + (W[1] - Y[1]) * (X[1] - Y[1]) > 0))
                    continue;
                dev = fabs(orient_value(X, Y, W)) / lxy;
            }
            if (dev < best_dev)
                best = i, best_dev = dev;
        }
    if (!plain && isfinite(R[0])) {
        /* the rounded crossing bends both the segment and the crossed
         * edge by rounding only: where it lies beyond the two triangles
         * beside the edge (on a third constraint an ulp away, as where
         * nearly collinear edges meet), it is inserted as it falls and
         * both are routed through it, rather than through a vertex far
         * from one of them */
        double dev = fmax(fabs(orient_value(A, B, R)) / lab, fabs(orient_value(X, Y, R)) / lxy);
        if (dev < best_dev) {
            step_result r = through_rounded(d, x, y, cdt_mark(d, t, k), R, depth);
            if (r != STEP_DONE)
                return r;
        }
    }
    if (best >= 2)
        return step_of(bend_through(d, t, k, cand[best], cdt_mark(d, t, k), depth));
    return append(d, &d->targets, &d->ntargets, &d->cap_targets, cand[best]) ? STEP_AGAIN : STEP_NOMEM;
}

/* Is q exactly on the open input segment oa-ob, and strictly between a
 * and b along it? */
static bool on_original(const tsr_cdt *d, uint32_t oa, uint32_t ob, uint32_t a, uint32_t b, uint32_t q)
{
    const double *OA = P(d, oa), *OB = P(d, ob), *Q = P(d, q), *A = P(d, a), *B = P(d, b);
    if (q == oa || q == ob || tsr_orient2d(OA, OB, Q) != 0)
        return false;
    double ux = B[0] - A[0], uy = B[1] - A[1];
    double t = (Q[0] - A[0]) * ux + (Q[1] - A[1]) * uy;
    return t > 0 && t < ux * ux + uy * uy;
}

/* Is q, not exactly on the input segment oa-ob, within rounding of it (a
 * few units in the last place of the coordinates: where a rounded crossing
 * of that segment or of one collinear with it lies) and strictly between a
 * and b along it? */
static bool near_original(const tsr_cdt *d, uint32_t oa, uint32_t ob, uint32_t a, uint32_t b, uint32_t q)
{
    const double *OA = P(d, oa), *OB = P(d, ob), *Q = P(d, q), *A = P(d, a), *B = P(d, b);
    if (q == oa || q == ob || q == GHOST)
        return false;
    /* a crossing is computed from the end nearest to it (split_crossing):
     * its error is a few ulps of its coordinates and of that distance */
    double lx = OB[0] - OA[0], ly = OB[1] - OA[1];
    double m =
        fmax(fabs(Q[0]), fabs(Q[1])) + fmin(hypot(Q[0] - OA[0], Q[1] - OA[1]), hypot(Q[0] - OB[0], Q[1] - OB[1]));
    if (fabs(tsr_orient2d(OA, OB, Q)) > 4 * DBL_EPSILON * m * sqrt(lx * lx + ly * ly))
        return false;
    /* between a and b along the piece, farther than that rounding from
     * either (a vertex an ulp beside an end is at the end, not on the way
     * to it), and between the input segment's ends along the segment (a
     * vertex an ulp beyond its end, though between the piece's ends, is no
     * vertex of it) */
    double ux = B[0] - A[0], uy = B[1] - A[1], margin = 4 * DBL_EPSILON * m * sqrt(ux * ux + uy * uy);
    return (Q[0] - A[0]) * ux + (Q[1] - A[1]) * uy > margin && (B[0] - Q[0]) * ux + (B[1] - Q[1]) * uy > margin &&
           (Q[0] - OA[0]) * lx + (Q[1] - OA[1]) * ly > 0 && (OB[0] - Q[0]) * lx + (OB[1] - Q[1]) * ly > 0;
}

/* May the piece end at q instead: is every chain vertex strictly on its
 * side of a-q? */
static bool chains_fit(const tsr_cdt *d, uint32_t a, uint32_t q)
{
    const double *A = P(d, a), *Q = P(d, q);
    for (uint32_t i = 1; i < d->nchl; i++)
        if (tsr_orient2d(A, Q, P(d, d->chl[i])) <= 0)
            return false;
    for (uint32_t i = 1; i < d->nchr; i++)
        if (tsr_orient2d(A, Q, P(d, d->chr[i])) >= 0)
            return false;
    return true;
}

/* Edge k of t covered by one more segment with the given mark: the lower
 * label, and the parity of the number of segments covering it (a first
 * cover takes the mark as it is). */
static void cover_edge(tsr_cdt *d, uint32_t t, int k, uint32_t mark)
{
    uint32_t old = cdt_mark(d, t, k);
    uint32_t lo = CDT_LABEL(old) < CDT_LABEL(mark) ? CDT_LABEL(old) : CDT_LABEL(mark);
    tsr__cdt_mark_edge(d, t, k, old ? lo | (~(old ^ mark) & CDT_EVEN) : mark);
}

static step_result recover_piece(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t oa, uint32_t ob, uint32_t mark, int depth,
                                 uint32_t *reached)
{
    int ia;
    uint32_t t0 = triangle_at(d, a, &ia);
    if (t0 == NONE)
        return STEP_NOMEM; /* cannot happen: a is a vertex */
    const double *A = P(d, a), *B = P(d, b);
    /* turn around a until the segment's direction is inside a triangle's
     * angle at a, or along one of its edges */
    uint32_t t = t0, x = NONE, y = NONE;
    for (uint64_t guard = 0;; guard++) {
        const uint32_t *v = d->tv + 3 * (size_t)t;
        x = v[(ia + 1) % 3], y = v[(ia + 2) % 3];
        if (x != GHOST) {
            double ox = tsr_orient2d(A, B, P(d, x));
            const double *X = P(d, x);
            /* along the piece, or (for a piece starting or ending at a
             * rounded crossing) ending exactly on the input segment */
            if ((ox == 0 && (X[0] - A[0]) * (B[0] - A[0]) + (X[1] - A[1]) * (B[1] - A[1]) > 0) ||
                on_original(d, oa, ob, a, b, x)) {
                cover_edge(d, t, ia, mark);
                *reached = x;
                return STEP_DONE;
            }
            if (y != GHOST && ox < 0 && tsr_orient2d(A, B, P(d, y)) > 0) {
                /* a constrained edge beside the direction to b whose far
                 * end lies within rounding of the input segment: the chain
                 * of a segment given before along the same line, through
                 * its rounded crossings (a segment given twice, or
                 * overlapping collinear ones). Following it covers that
                 * chain again; walking past it would cross the same
                 * constraint again and make a second crossing vertex an
                 * ulp from the first. */
                int ky = (ia + 2) % 3;
                if (on_original(d, oa, ob, a, b, y)) {
                    /* y, beside the piece from a rounded crossing, lies
                     * exactly on the input segment: the piece ends there
                     * (the walk below starts past y and would leave it
                     * beside the segment, a sliver off it) */
                    cover_edge(d, t, ky, mark);
                    *reached = y;
                    return STEP_DONE;
                }
                bool nx = cdt_mark(d, t, ia) && near_original(d, oa, ob, a, b, x);
                bool ny = cdt_mark(d, t, ky) && near_original(d, oa, ob, a, b, y);
                if (nx && ny) /* both: the one nearer the line */
                    nx = fabs(ox) <= fabs(tsr_orient2d(A, B, P(d, y)));
                if (nx || ny) {
                    cover_edge(d, t, nx ? ia : ky, mark); /* marked: covered again */
                    *reached = nx ? x : y;
                    return STEP_DONE;
                }
                break;
            }
        }
        t = d->tn[3 * (size_t)t + (ia + 2) % 3];
        const uint32_t *w = d->tv + 3 * (size_t)t;
        ia = w[0] == a ? 0 : w[1] == a ? 1 : 2;
        if (t == t0 || guard > d->nt)
            return STEP_NOMEM; /* cannot happen with exact predicates */
    }
    /* walk along the segment through the triangles it crosses */
    d->nwork = d->nchl = d->nchr = 0;
    if (!append(d, &d->work, &d->nwork, &d->cap_work, t) || !append(d, &d->chl, &d->nchl, &d->cap_chl, a) ||
        !append(d, &d->chr, &d->nchr, &d->cap_chr, a) || !append(d, &d->chl, &d->nchl, &d->cap_chl, y) ||
        !append(d, &d->chr, &d->nchr, &d->cap_chr, x))
        return STEP_NOMEM;
    uint32_t end;
    for (;;) {
        int k = edge_index(d, t, x, y);
        if (cdt_mark(d, t, k))
            return split_crossing(d, t, k, a, b, depth);
        uint32_t s = d->tn[3 * (size_t)t + k];
        uint32_t q = apex(d, s, x, y);
        if (!append(d, &d->work, &d->nwork, &d->cap_work, s))
            return STEP_NOMEM;
        double o = q == b ? 0 : tsr_orient2d(A, B, P(d, q));
        if (o == 0 || (on_original(d, oa, ob, a, b, q) && chains_fit(d, a, q))) {
            end = q;
            break;
        }
        if (o < 0) {
            if (!append(d, &d->chr, &d->nchr, &d->cap_chr, q))
                return STEP_NOMEM;
            x = q;
        } else {
            if (!append(d, &d->chl, &d->nchl, &d->cap_chl, q))
                return STEP_NOMEM;
            y = q;
        }
        t = s;
    }
    if (!append(d, &d->chl, &d->nchl, &d->cap_chl, end) || !append(d, &d->chr, &d->nchr, &d->cap_chr, end))
        return STEP_NOMEM;
    d->nnwt = 0;
    if (!pseudo_polygon(d, d->chl, d->nchl, true) || !pseudo_polygon(d, d->chr, d->nchr, false))
        return STEP_NOMEM;
    uint32_t n = d->nwork, *out = tsr_alloc(da(d), (size_t)n * sizeof *out);
    if (!out)
        return STEP_NOMEM;
    bool ok = d->nnwt == 3 * n && retriangulate(d, d->work, n, (const uint32_t(*)[3])d->nwt, n, out);
    if (ok) { /* the left polygon's first triangle has the new edge a -> end as edge 0 */
        tsr__cdt_mark_edge(d, out[0], 0, mark);
        d->last = out[0];
    }
    tsr_free(da(d), out);
    *reached = end;
    return ok ? STEP_DONE : STEP_NOMEM;
}

/* Recovers a-b with the given mark; the targets above the current top of
 * the stack are this call's. */
static tsr_status insert_chain(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t mark, int depth)
{
    uint32_t oa = a, ob = b, base = d->ntargets;
    if (!append(d, &d->targets, &d->ntargets, &d->cap_targets, b))
        return TSR_ERR_NOMEM;
    while (d->ntargets > base) {
        uint32_t target = d->targets[d->ntargets - 1];
        if (a == target) {
            d->ntargets--;
            continue;
        }
        if (++d->steps > d->step_limit) {
            /* constraints bending each other back and forth through the
             * same vertices (a reviewer's stress test: coordinates near 1
             * beside others near 1e20 to 1e34) */
            if (d->plain)
                return TSR_ERR_VALUE;
            d->plain = true;
            d->steps = 0;
        }
        uint32_t reached = a;
        step_result r = recover_piece(d, a, target, oa, ob, mark, depth, &reached);
        if (r == STEP_NOMEM || r == STEP_GIVE_UP)
            return r == STEP_NOMEM ? TSR_ERR_NOMEM : TSR_ERR_VALUE;
        if (r == STEP_DONE)
            a = reached;
    }
    return TSR_OK;
}

tsr_status tsr_cdt_insert_segment(tsr_cdt *d, uint32_t a, uint32_t b, uint32_t id)
{
    if (a >= d->nv - 1 || b >= d->nv - 1 || id >= CDT_BOUNDARY - 1)
        return TSR_ERR_ARGUMENT;
    if (!d->started || a == b)
        return TSR_OK;
    if (!tsr__cdt_enable_marks(d, false))
        return TSR_ERR_NOMEM;
    d->ntargets = 0;
    d->steps = 0;
    d->step_limit = 64 * (uint64_t)d->nv + 1024;
    d->plain = false;
    return insert_chain(d, a + 1, b + 1, id + 1, 0);
}

uint32_t tsr_cdt_intersection_count(const tsr_cdt *d)
{
    return d->intersections;
}

bool tsr_cdt_edge_constrained(const tsr_cdt *d, uint32_t a, uint32_t b, uint32_t *id)
{
    int ia;
    a++, b++;
    uint32_t t0 = triangle_at((tsr_cdt *)d, a, &ia);
    if (t0 == NONE)
        return false;
    uint32_t t = t0;
    do {
        const uint32_t *v = d->tv + 3 * (size_t)t;
        if (v[(ia + 1) % 3] == b) {
            uint32_t m = cdt_mark(d, t, ia);
            if (m && id)
                *id = CDT_LABEL(m) - 1;
            return m != 0;
        }
        t = d->tn[3 * (size_t)t + (ia + 2) % 3];
        const uint32_t *w = d->tv + 3 * (size_t)t;
        ia = w[0] == a ? 0 : w[1] == a ? 1 : 2;
    } while (t != t0);
    return false;
}

/* ---- triangle handles -------------------------------------------------- */

uint32_t tsr_cdt_handle_count(const tsr_cdt *d)
{
    return d->nt;
}

bool tsr_cdt_triangle(const tsr_cdt *d, uint32_t h, uint32_t v[3])
{
    if (h >= d->nt || is_ghost(d, h))
        return false;
    for (int k = 0; k < 3; k++)
        v[k] = d->tv[3 * (size_t)h + k] - 1;
    return true;
}

void tsr_cdt_track_changes(tsr_cdt *d, bool on)
{
    d->track = on;
    d->nchanged = 0;
}

const uint32_t *tsr_cdt_changes(const tsr_cdt *d, uint32_t *n)
{
    *n = d->nchanged;
    return d->changed;
}

void tsr_cdt_clear_changes(tsr_cdt *d)
{
    d->nchanged = 0;
}

uint32_t tsr_cdt_locate_handle(const tsr_cdt *d, double x, double y)
{
    if (!d->started)
        return NONE;
    double p[2] = {x, y};
    int kind, which;
    uint32_t t = tsr__cdt_locate((tsr_cdt *)d, p, &kind, &which);
    return kind == IN_GHOST ? NONE : t;
}

uint32_t tsr_cdt_vertex_count(const tsr_cdt *d)
{
    return d->nv - 1;
}
uint32_t tsr_cdt_duplicate_count(const tsr_cdt *d)
{
    return d->dups;
}

void tsr_cdt_vertex(const tsr_cdt *d, uint32_t v, double xy[2])
{
    xy[0] = d->xy[2 * ((size_t)v + 1)];
    xy[1] = d->xy[2 * ((size_t)v + 1) + 1];
}

uint32_t tsr_cdt_triangle_count(const tsr_cdt *d)
{
    uint32_t n = 0;
    for (uint32_t t = 0; t < d->nt; t++)
        n += !is_ghost(d, t);
    return n;
}

uint32_t tsr_cdt_triangles(const tsr_cdt *d, uint32_t *tri, uint32_t cap)
{
    uint32_t n = 0;
    for (uint32_t t = 0; t < d->nt && n < cap; t++) {
        if (is_ghost(d, t))
            continue;
        for (int k = 0; k < 3; k++)
            tri[3 * (size_t)n + k] = d->tv[3 * (size_t)t + k] - 1;
        n++;
    }
    return n;
}

bool tsr_cdt_locate(const tsr_cdt *d, double x, double y, uint32_t tri[3])
{
    if (!d->started)
        return false;
    double p[2] = {x, y};
    int kind, which;
    /* the walk only moves the start hint, which is not part of the result */
    uint32_t t = tsr__cdt_locate((tsr_cdt *)d, p, &kind, &which);
    if (kind == IN_GHOST)
        return false;
    for (int k = 0; k < 3; k++)
        tri[k] = d->tv[3 * (size_t)t + k] - 1;
    return true;
}

/* ---- bulk insertion in BRIO order ------------------------------------- */

/* Position along a Hilbert curve of order 16 (our own rotate-and-flip
 * formulation of the classic recursion). */
static uint32_t hilbert(uint32_t x, uint32_t y)
{
    uint32_t d = 0;
    for (uint32_t s = 1u << 15; s > 0; s >>= 1) {
        uint32_t rx = (x & s) > 0, ry = (y & s) > 0;
        d += s * s * ((3 * rx) ^ ry);
        if (ry == 0) {
            if (rx == 1) {
                x = s - 1 - x;
                y = s - 1 - y;
            }
            uint32_t t = x;
            x = y;
            y = t;
        }
    }
    return d;
}

typedef struct keyed {
    uint64_t key; /* round in the high bits, Hilbert position below */
    uint32_t index;
} keyed;

/* Sorts by key: LSD radix sort in 11-bit digits over the bits in use
 * (round and Hilbert position, under 48 bits); tmp holds n entries. */
static void radix_sort(keyed *a, keyed *tmp, uint32_t n)
{
    uint64_t all = 0;
    for (uint32_t i = 0; i < n; i++)
        all |= a[i].key;
    for (int shift = 0; shift < 64 && (all >> shift) != 0; shift += 11) {
        uint32_t count[2048] = {0};
        for (uint32_t i = 0; i < n; i++)
            count[(a[i].key >> shift) & 2047]++;
        uint32_t sum = 0;
        for (int b = 0; b < 2048; b++) {
            uint32_t c = count[b];
            count[b] = sum;
            sum += c;
        }
        for (uint32_t i = 0; i < n; i++)
            tmp[count[(a[i].key >> shift) & 2047]++] = a[i];
        memcpy(a, tmp, (size_t)n * sizeof *a);
    }
}

tsr_status tsr_cdt_insert_points(tsr_cdt *d, const double *xy, uint32_t n, uint32_t *ids)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (uint32_t i = 0; i < n; i++)
        for (int k = 0; k < 2; k++) {
            double v = xy[2 * (size_t)i + k];
            if (!isfinite(v))
                return TSR_ERR_ARGUMENT;
            lo[k] = v < lo[k] ? v : lo[k];
            hi[k] = v > hi[k] ? v : hi[k];
        }
    /* exact capacities: n points make at most 2n - 2 triangles with ghosts */
    uint64_t want_v = (uint64_t)d->nv + n + 1, want_t = 2 * want_v + 8;
    if (want_t > UINT32_MAX / 3)
        return TSR_ERR_NOMEM;
    if (!grow_vertices(d, (uint32_t)want_v) || !grow_triangles(d, (uint32_t)want_t))
        return TSR_ERR_NOMEM;
    keyed *order = tsr_alloc(da(d), ((size_t)n + 1) * sizeof *order);
    if (!order)
        return TSR_ERR_NOMEM;
    /* BRIO rounds: each point draws its round from a hash of its index,
     * geometrically: half the points go to the last round, a quarter to
     * the one before, and so on (the same distribution as cutting a random
     * permutation into rounds of doubling size, computed in index order so
     * that the points are read sequentially) */
    double sx = hi[0] > lo[0] ? 65535.0 / (hi[0] - lo[0]) : 0, sy = hi[1] > lo[1] ? 65535.0 / (hi[1] - lo[1]) : 0;
    for (uint32_t i = 0; i < n; i++) {
        uint64_t h = ((uint64_t)i + 0x9E3779B97F4A7C15ull) * 0xBF58476D1CE4E5B9ull;
        h ^= h >> 31;
        h *= 0x94D049BB133111EBull;
        h ^= h >> 29;
        int zeros = 0;
        while (zeros < 40 && (h & 1)) {
            h >>= 1;
            zeros++;
        }
        uint32_t round = 40 - (uint32_t)zeros;
        const double *p = xy + 2 * (size_t)i;
        uint32_t hx = (uint32_t)((p[0] - lo[0]) * sx), hy = (uint32_t)((p[1] - lo[1]) * sy);
        order[i].index = i;
        order[i].key = (uint64_t)round << 32 | hilbert(hx > 65535 ? 65535 : hx, hy > 65535 ? 65535 : hy);
    }
    keyed *tmp = tsr_alloc(da(d), ((size_t)n + 1) * sizeof *tmp);
    if (!tmp) {
        tsr_free(da(d), order);
        return TSR_ERR_NOMEM;
    }
    radix_sort(order, tmp, n);
    tsr_free(da(d), tmp);
    tsr_status st = TSR_OK;
    for (uint32_t i = 0; i < n; i++) {
#if defined(__GNUC__)
        if (i + 16 < n) /* the input is read in curve order: fetch ahead */
            __builtin_prefetch(xy + 2 * (size_t)order[i + 16].index);
#endif
        const double *p = xy + 2 * (size_t)order[i].index;
        uint32_t id = tsr_cdt_insert(d, p[0], p[1]);
        if (id == NONE) {
            st = TSR_ERR_NOMEM;
            break;
        }
        if (ids)
            ids[order[i].index] = id;
    }
    tsr_free(da(d), order);
    return st;
}

/* ---- edge flips (data-dependent triangulations) ------------------------- */

uint32_t tsr_cdt_neighbor(const tsr_cdt *d, uint32_t h, int k, bool *constrained)
{
    if (constrained)
        *constrained = false;
    if (h >= d->nt || k < 0 || k > 2 || is_ghost(d, h))
        return NONE;
    uint32_t n = d->tn[3 * (size_t)h + k];
    if (constrained)
        *constrained = cdt_mark(d, h, k) != 0;
    return is_ghost(d, n) ? NONE : n;
}

tsr_status tsr_cdt_flip(tsr_cdt *d, uint32_t h, int k)
{
    uint32_t n = tsr_cdt_neighbor(d, h, k, NULL);
    if (n == NONE || cdt_mark(d, h, k) || (d->tf && d->tf[h] != d->tf[n]))
        return TSR_ERR_ARGUMENT;
    const uint32_t *v = d->tv + 3 * (size_t)h;
    int i = (k + 2) % 3;
    uint32_t p = v[i], x = v[(i + 1) % 3], y = v[(i + 2) % 3];
    if (edge_index(d, n, y, x) < 0)
        return TSR_ERR_ARGUMENT;
    uint32_t q = apex(d, n, x, y);
    if (tsr_orient2d(P(d, p), P(d, x), P(d, q)) <= 0 || tsr_orient2d(P(d, p), P(d, q), P(d, y)) <= 0)
        return TSR_ERR_ARGUMENT;
    return flip(d, h, i, n) ? TSR_OK : TSR_ERR_NOMEM;
}
