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
#include "tessellate/tessellate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define GHOST 0u
#define NONE UINT32_MAX

struct tsr_cdt {
    tsr_allocator alloc;
    double *xy; /* 2 per internal vertex; vertex 0 (infinity) unused */
    uint32_t nv, cap_v;
    uint32_t *tv, *tn;
    uint32_t nt, cap_t;
    uint32_t last;
    uint32_t dups;
    uint32_t walk_turn;
    bool started;
    uint32_t *pending; /* distinct vertices waiting for a non-collinear third */
    uint32_t npending, cap_pending;
    uint32_t *stack; /* triangles whose edge opposite the new vertex is to check */
    uint32_t nstack, cap_stack;
};

static const tsr_allocator *da(const tsr_cdt *d) { return d->alloc.realloc ? &d->alloc : NULL; }
static const double *P(const tsr_cdt *d, uint32_t v) { return d->xy + 2 * (size_t)v; }
static bool is_ghost(const tsr_cdt *d, uint32_t t)
{
    const uint32_t *v = d->tv + 3 * (size_t)t;
    return v[0] == GHOST || v[1] == GHOST || v[2] == GHOST;
}

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
    tsr_free(a, d->xy);
    tsr_free(a, d->tv);
    tsr_free(a, d->tn);
    tsr_free(a, d->pending);
    tsr_free(a, d->stack);
    tsr_allocator copy = d->alloc;
    tsr_free(copy.realloc ? &copy : NULL, d);
}

static uint32_t add_vertex(tsr_cdt *d, double x, double y)
{
    if (d->nv == d->cap_v) {
        uint32_t cap = d->cap_v * 2;
        double *xy = tsr_realloc(da(d), d->xy, 2 * (size_t)cap * sizeof(double));
        if (!xy)
            return NONE;
        d->xy = xy;
        d->cap_v = cap;
    }
    d->xy[2 * (size_t)d->nv] = x;
    d->xy[2 * (size_t)d->nv + 1] = y;
    return d->nv++;
}

static uint32_t new_triangle(tsr_cdt *d)
{
    if (d->nt == d->cap_t) {
        uint32_t cap = d->cap_t ? d->cap_t * 2 : 64;
        uint32_t *tv = tsr_realloc(da(d), d->tv, 3 * (size_t)cap * sizeof *tv);
        if (!tv)
            return NONE;
        d->tv = tv;
        uint32_t *tn = tsr_realloc(da(d), d->tn, 3 * (size_t)cap * sizeof *tn);
        if (!tn)
            return NONE;
        d->tn = tn;
        d->cap_t = cap;
    }
    return d->nt++;
}

/* ---- local retriangulation ------------------------------------------- */

/* Replaces the triangles old[0..nold) (a cavity) by the triangles given as
 * vertex triples in nw[0..nnew), reusing the old slots first, and links
 * every edge: to the other new triangles, or to what was across that edge
 * of the cavity before. Out: the new triangles' indices. */
static bool retriangulate(tsr_cdt *d, const uint32_t *old, int nold, const uint32_t (*nw)[3], int nnew, uint32_t *out)
{
    typedef struct {
        uint32_t a, b, t;
    } bedge;
    bedge bnd[16];
    int nb = 0;
    for (int i = 0; i < nold; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t nbr = d->tn[3 * (size_t)old[i] + k];
            bool inside = false;
            for (int j = 0; j < nold; j++)
                inside |= nbr == old[j];
            if (!inside) {
                bnd[nb].a = d->tv[3 * (size_t)old[i] + k];
                bnd[nb].b = d->tv[3 * (size_t)old[i] + (k + 1) % 3];
                bnd[nb].t = nbr;
                nb++;
            }
        }
    for (int i = 0; i < nnew; i++) {
        out[i] = i < nold ? old[i] : new_triangle(d);
        if (out[i] == NONE)
            return false;
    }
    for (int i = 0; i < nnew; i++)
        for (int k = 0; k < 3; k++)
            d->tv[3 * (size_t)out[i] + k] = nw[i][k];
    for (int i = 0; i < nnew; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t x = nw[i][k], y = nw[i][(k + 1) % 3], across = NONE;
            for (int j = 0; j < nnew && across == NONE; j++)
                for (int q = 0; q < 3; q++)
                    if (nw[j][q] == y && nw[j][(q + 1) % 3] == x) {
                        across = out[j];
                        break;
                    }
            if (across == NONE)
                for (int e = 0; e < nb; e++)
                    if (bnd[e].a == x && bnd[e].b == y) {
                        across = bnd[e].t;
                        /* and the outside triangle points back here */
                        for (int q = 0; q < 3; q++)
                            if (d->tv[3 * (size_t)across + q] == y && d->tv[3 * (size_t)across + (q + 1) % 3] == x)
                                d->tn[3 * (size_t)across + q] = out[i];
                        break;
                    }
            d->tn[3 * (size_t)out[i] + k] = across;
        }
    return true;
}

/* ---- location ----------------------------------------------------------- */

enum { IN_TRIANGLE, ON_EDGE, ON_VERTEX, IN_GHOST };

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

static uint32_t locate(tsr_cdt *d, const double p[2], int *kind, int *which)
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

/* Appends v to a growable array (*arr, *n, *cap); false when out of memory. */
static bool append(const tsr_cdt *d, uint32_t **arr, uint32_t *n, uint32_t *cap, uint32_t v)
{
    if (*n == *cap) {
        uint32_t c = *cap ? 2 * *cap : 64;
        uint32_t *a = tsr_realloc(da(d), *arr, c * sizeof *a);
        if (!a)
            return false;
        *arr = a;
        *cap = c;
    }
    (*arr)[(*n)++] = v;
    return true;
}

static bool push(tsr_cdt *d, uint32_t t) { return append(d, &d->stack, &d->nstack, &d->cap_stack, t); }

static bool legalize(tsr_cdt *d, uint32_t pv)
{
    const double *p = P(d, pv);
    while (d->nstack > 0) {
        uint32_t t1 = d->stack[--d->nstack];
        const uint32_t *v = d->tv + 3 * (size_t)t1;
        int i = v[0] == pv ? 0 : v[1] == pv ? 1 : 2;
        uint32_t x = v[(i + 1) % 3], y = v[(i + 2) % 3];
        uint32_t t2 = d->tn[3 * (size_t)t1 + (i + 1) % 3];
        if (!conflict(d, t2, p))
            continue;
        const uint32_t *w = d->tv + 3 * (size_t)t2;
        uint32_t q = w[0] != x && w[0] != y ? w[0] : w[1] != x && w[1] != y ? w[1] : w[2];
        uint32_t old[2] = {t1, t2}, nw[2][3] = {{pv, x, q}, {pv, q, y}}, out[2];
        if (!retriangulate(d, old, 2, nw, 2, out) || !push(d, out[0]) || !push(d, out[1]))
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

/* Inserts internal vertex pv (already stored) into a started
 * triangulation. Returns the vertex to report: pv, or an existing vertex
 * when pv duplicates it (then pv is dropped). */
static uint32_t insert_vertex(tsr_cdt *d, uint32_t pv)
{
    int kind, which;
    const double *p = P(d, pv);
    uint32_t t = locate(d, p, &kind, &which);
    const uint32_t *v = d->tv + 3 * (size_t)t;
    d->nstack = 0;
    if (kind == ON_VERTEX) {
        d->dups++;
        d->nv--; /* pv was the last vertex stored */
        return v[which];
    }
    if (kind == IN_TRIANGLE || kind == IN_GHOST) {
        uint32_t a = v[0], b = v[1], c = v[2];
        uint32_t old[1] = {t}, nw[3][3] = {{a, b, pv}, {b, c, pv}, {c, a, pv}}, out[3];
        if (!retriangulate(d, old, 1, nw, 3, out))
            return NONE;
        for (int i = 0; i < 3; i++)
            if (!push(d, out[i]))
                return NONE;
    } else { /* on edge `which` of finite t, shared with s */
        uint32_t a = v[which], b = v[(which + 1) % 3], c = v[(which + 2) % 3];
        uint32_t s = d->tn[3 * (size_t)t + which];
        const uint32_t *w = d->tv + 3 * (size_t)s;
        uint32_t q = w[0] != a && w[0] != b ? w[0] : w[1] != a && w[1] != b ? w[1] : w[2];
        uint32_t old[2] = {t, s}, nw[4][3] = {{a, pv, c}, {pv, b, c}, {b, pv, q}, {pv, a, q}}, out[4];
        if (!retriangulate(d, old, 2, nw, 4, out))
            return NONE;
        for (int i = 0; i < 4; i++)
            if (!push(d, out[i]))
                return NONE;
    }
    if (!legalize(d, pv))
        return NONE;
    d->last = t; /* its slot now holds a triangle at pv: the next walk starts there */
    return pv;
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

uint32_t tsr_cdt_vertex_count(const tsr_cdt *d) { return d->nv - 1; }
uint32_t tsr_cdt_duplicate_count(const tsr_cdt *d) { return d->dups; }

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
    uint32_t t = locate((tsr_cdt *)d, p, &kind, &which);
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

static int keyed_cmp(const void *a, const void *b)
{
    const keyed *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key;
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
    keyed *order = tsr_alloc(da(d), ((size_t)n + 1) * sizeof *order);
    if (!order)
        return TSR_ERR_NOMEM;
    /* BRIO rounds: a random permutation cut into rounds of doubling size;
     * the last round holds half of the points */
    uint64_t rng = 0x9E3779B97F4A7C15ull ^ n;
    for (uint32_t i = 0; i < n; i++)
        order[i].index = i;
    for (uint32_t i = n; i > 1; i--) {
        rng = rng * 6364136223846793005ull + 1442695040888963407ull;
        uint32_t j = (uint32_t)((rng >> 33) % i);
        uint32_t t = order[i - 1].index;
        order[i - 1].index = order[j].index;
        order[j].index = t;
    }
    double sx = hi[0] > lo[0] ? 65535.0 / (hi[0] - lo[0]) : 0, sy = hi[1] > lo[1] ? 65535.0 / (hi[1] - lo[1]) : 0;
    uint32_t round_start = n, round = 40;
    for (uint32_t i = n; i-- > 0;) {
        if (i < round_start / 2 && round > 0 && round_start > 64) {
            round_start = i + 1;
            round--;
        }
        const double *p = xy + 2 * (size_t)order[i].index;
        uint32_t hx = (uint32_t)((p[0] - lo[0]) * sx), hy = (uint32_t)((p[1] - lo[1]) * sy);
        order[i].key = (uint64_t)round << 32 | hilbert(hx > 65535 ? 65535 : hx, hy > 65535 ? 65535 : hy);
    }
    qsort(order, n, sizeof *order, keyed_cmp);
    tsr_status st = TSR_OK;
    for (uint32_t i = 0; i < n; i++) {
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
