/* tin.c: error-bounded meshes of a heightfield (tessera mesh).
 *
 * delaunay: greedy insertion after M. Garland and P. S. Heckbert, "Fast
 * polygonal approximation of terrains and height fields" (CMU-CS-95-181,
 * 1995), their algorithm III: every triangle of the (constrained) Delaunay
 * triangulation keeps its worst sample, the sample farthest vertically from
 * the triangle's plane, as a candidate in a priority queue; the worst
 * candidate overall is inserted, and only the triangles the insertion
 * created are scanned again (the kernel lists the slots it rewrote).
 *
 * Beyond the greedy baseline (on by default, tsr_tin_options.no_flip turns
 * it off): after each insertion, the new triangles' edges are flipped
 * where that lowers the error above the target of the two triangles
 * sharing the edge: a data-dependent triangulation (N. Dyn, D. Levin and
 * S. Rippa 1990; Garland and Heckbert offer it beside Delaunay updates),
 * interleaved with the insertions, so that the loop, which stops once every triangle
 * is within the target, stops sooner: a fifth fewer triangles for the
 * same bound on real terrains. Both new triangles are scanned before a
 * flip, so the queue's keys stay exact and the bound as real as before;
 * constrained edges (the fixed boundaries) and hull edges never flip.
 *
 * Before the greedy pass, the outer border and the boundaries of no-data
 * (the union of cells whose four corners are valid is the domain) are
 * fixed: each straight run of boundary is simplified by Douglas-Peucker
 * (D. Douglas and T. Peucker 1973) on its height profile with the border
 * tolerance, its kept samples inserted and joined by constrained edges,
 * and no sample on it is ever a candidate. The border of a window thus
 * depends on its own samples alone, and two adjacent windows mesh their
 * shared side identically, whatever their interiors. Every sample of a run
 * lies within the tolerance of the edge above it, because the edges are
 * constrained and interpolate linearly along the run.
 *
 * A triangle's samples are found exactly on the lattice (vertices are
 * samples): each row's span between the triangle's edges is stepped in
 * integers (a quotient and a remainder per edge, no division per row), so
 * the scan never misses or adds one; its rows' lines are asked for before
 * it starts, and the triangles an insertion rewrote are loaded together
 * before any is scanned, so that cache misses overlap (the pass is bound
 * by them: the greedy order jumps across the heightfield). Errors are in
 * file units inside (h), world units (h dz) outside.
 *
 * quadtree: by default rqt.c's restricted quadtree with exact errors
 * (leaves of two or four triangles); with a tile size, the restricted
 * quadtree's cut of lod.c's pyramid with error(node) <= the bound, each
 * leaf a grid tile; grid: every step-th sample (grid.c). */
#include "terrain_internal.h"

#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

/* ---- the candidate queue: an 8-ary max-heap of (key, slot) words with
 * lazy deletion. Each triangle slot keeps its own record (error and
 * candidate sample, rec[] below); the heap holds a word for every slot
 * whose error is above the target (the ones still to refine; the others
 * never enter it) and perhaps stale words of slots rescanned since, which
 * are dropped when they surface: a word is live when its key is its
 * slot's current error. A word is the key's bits (keys are positive
 * floats, whose bits order as integers) above the slot, so one integer
 * compare orders the heap and no position index is written on every move
 * (the indexed heap's scattered writes were its cost); a node's eight
 * children fill one 64-byte line, so a pop misses the cache once a level
 * of a tree a third as deep as a binary one. The words of one insertion
 * are pushed once at its end (a slot rescanned, then flipped, gets one). */

typedef struct trec {
    float err;     /* the error of the slot's worst candidate (rounded up) */
    uint32_t cand; /* that candidate (r * w + c), UINT32_MAX: none */
    float wkey;    /* the key of the slot's last word pushed, 0 when none
                    * (or dropped) */
} trec;

typedef struct heap {
    uint64_t *e; /* e[1] on a 64-byte line: children of i are 8i+1..8i+8 */
    void *block; /* the allocation e lies in */
    uint32_t n, cap;
} heap;

static bool grow_u32(const tsr_allocator *a, void **arr, uint32_t *cap, uint32_t need, size_t elem)
{
    if (need <= *cap)
        return true;
    uint64_t c = *cap ? *cap : 1024;
    while (c < need)
        c += c / 2;
    if (c > UINT32_MAX)
        c = UINT32_MAX;
    void *p = tsr_realloc(a, *arr, (size_t)c * elem);
    if (!p)
        return false;
    *arr = p;
    *cap = (uint32_t)c;
    return true;
}

static bool heap_grow(heap *h, const tsr_allocator *a)
{
    uint64_t c = h->cap ? h->cap + h->cap / 2 : 4096;
    if (c > UINT32_MAX - 16)
        return false;
    void *b = tsr_alloc(a, (size_t)(c + 16) * sizeof *h->e);
    if (!b)
        return false;
    uintptr_t p = ((uintptr_t)b + 8 + 63) & ~(uintptr_t)63; /* &e[1] */
    uint64_t *e = (uint64_t *)(p - 8);
    if (h->n)
        memcpy(e, h->e, (size_t)h->n * sizeof *e);
    tsr_free(a, h->block);
    h->block = b;
    h->e = e;
    h->cap = (uint32_t)c;
    return true;
}

static inline uint32_t f32_bits(float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    return u;
}

static inline float bits_f32(uint32_t u)
{
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static void heap_up(heap *h, uint32_t i)
{
    uint64_t x = h->e[i];
    while (i > 0) {
        uint32_t p = (i - 1) / 8;
        if (h->e[p] >= x)
            break;
        h->e[i] = h->e[p];
        i = p;
    }
    h->e[i] = x;
}

static void heap_down(heap *h, uint32_t i)
{
    uint64_t x = h->e[i];
    uint64_t *e = h->e;
    for (;;) {
        uint32_t l = 8 * i + 1;
        if (l >= h->n)
            break;
        uint32_t best = l;
        uint64_t bk = e[l];
        if (l + 8 <= h->n) {
            for (uint32_t k = l + 1; k < l + 8; k++)
                if (e[k] > bk) {
                    best = k;
                    bk = e[k];
                }
        } else
            for (uint32_t k = l + 1; k < h->n; k++)
                if (e[k] > bk) {
                    best = k;
                    bk = e[k];
                }
        if (bk <= x)
            break;
        e[i] = bk;
        i = best;
    }
    e[i] = x;
}

static bool heap_push(heap *h, const tsr_allocator *a, uint64_t x)
{
    if (h->n == h->cap && !heap_grow(h, a))
        return false;
    h->e[h->n] = x;
    heap_up(h, h->n++);
    return true;
}

static void heap_pop(heap *h)
{
    h->e[0] = h->e[--h->n];
    if (h->n > 1)
        heap_down(h, 0);
}

static void heap_free(heap *h, const tsr_allocator *a)
{
    tsr_free(a, h->block);
}

/* ---- the greedy mesher ------------------------------------------------- */

/* a vertex: its lattice position and height, read together */
typedef struct tvx {
    uint32_t c, r;
    float z;
} tvx;

/* Where a block lies: the whole heightfield (row stride w), the block's
 * origin in it, and whether the block or the ring of samples around it
 * has no-data (then its border is cut into runs as no-data boundaries
 * are, at the same points as its neighbours cut theirs). */
typedef struct tin_ctx {
    const float *data;
    uint32_t w, h, x, y;
    bool nodata;
} tin_ctx;

typedef struct tin {
    const float *data;
    uint32_t w, h;
    tin_ctx ctx;
    const tsr_allocator *a;
    tsr_cdt *cdt;
    heap q;
    trec *rec; /* per triangle slot */
    uint32_t nrec, cap_rec;
    uint32_t live; /* slots whose error is above thr */
    float thr;     /* the heap holds the slots whose error is above it */
    uint32_t *dirty; /* slots whose record changed in this insertion */
    uint32_t ndirty, cap_dirty;
    tvx *vx; /* per vertex id */
    uint32_t nv, cap_v;
    /* when the heightfield has no-data: 1 bit per sample, set when the
     * sample may not be a candidate (not inside the domain's interior) */
    uint8_t *excl;
    bool nodata;
    /* the border and no-data boundaries fixed first (their samples never
     * candidates), or refined by the greedy pass like the rest (budgets
     * without a bound) */
    bool fixed_border;
    uint32_t seen[64]; /* the slots rescanned for the current insertion */
    bool nomem;        /* the queue could not grow */
    /* the data-dependent flips: edges to test, 3 words each (slot, and the
     * edge's vertices as that slot lists them) */
    bool flip;
    uint32_t *fstack;
    uint32_t nfs, cap_fs;
    uint32_t flips;
} tin;

static bool rec_slots(tin *t, uint32_t n)
{
    if (n <= t->nrec)
        return true;
    if (!grow_u32(t->a, (void **)&t->rec, &t->cap_rec, n, sizeof *t->rec))
        return false;
    for (uint32_t i = t->nrec; i < n; i++)
        t->rec[i] = (trec){-1.0f, UINT32_MAX, 0.0f};
    t->nrec = n;
    return true;
}

static inline bool rec_above(const tin *t, trec r)
{
    return r.cand != UINT32_MAX && r.err > t->thr;
}

/* Is word x live? Else, when x is the slot's last word, the slot has none
 * now. */
static inline bool word_live(tin *t, uint64_t x)
{
    trec *r = t->rec + (uint32_t)x;
    uint32_t k = (uint32_t)(x >> 32);
    if (rec_above(t, *r) && f32_bits(r->err) == k)
        return true;
    if (f32_bits(r->wkey) == k)
        r->wkey = 0;
    return false;
}

/* Drops the stale words (when they outnumber the live ones) and rebuilds
 * the heap from the rest. */
static void heap_compact(tin *t)
{
    heap *h = &t->q;
    uint32_t m = 0;
    for (uint32_t i = 0; i < h->n; i++)
        if (word_live(t, h->e[i]))
            h->e[m++] = h->e[i];
    h->n = m;
    for (uint32_t i = m / 8 + 1; i-- > 0;)
        if (i < m)
            heap_down(h, i);
}

/* Sets slot s's record (its word follows at the next flush). */
static void rec_set(tin *t, uint32_t s, float err, uint32_t cand)
{
    trec *r = t->rec + s;
    bool was = rec_above(t, *r);
    r->err = err;
    r->cand = cand;
    bool is = rec_above(t, *r);
    t->live += (uint32_t)is - (uint32_t)was;
    if (is && err != r->wkey) {
        if (t->ndirty == t->cap_dirty &&
            !grow_u32(t->a, (void **)&t->dirty, &t->cap_dirty, t->ndirty + 1, sizeof *t->dirty)) {
            t->nomem = true;
            return;
        }
        t->dirty[t->ndirty++] = s;
    }
}

/* Pushes a word for every changed slot above thr that lacks a live one. */
static void flush(tin *t)
{
    for (uint32_t i = 0; i < t->ndirty; i++) {
        trec *r = t->rec + t->dirty[i];
        if (!rec_above(t, *r) || r->err == r->wkey)
            continue; /* below, or pushed already (listed twice) */
        if (t->q.n == t->q.cap && t->q.n >= 2 * t->live + 4096)
            heap_compact(t);
        if (!heap_push(&t->q, t->a, (uint64_t)f32_bits(r->err) << 32 | t->dirty[i])) {
            t->nomem = true;
            break;
        }
        r->wkey = r->err;
    }
    t->ndirty = 0;
}

/* The top live word (stale ones on the way dropped), or false. */
static bool heap_top(tin *t, uint32_t *slot, float *key)
{
    heap *h = &t->q;
    while (h->n) {
        uint64_t x = h->e[0];
        if (word_live(t, x)) {
            *slot = (uint32_t)x;
            *key = bits_f32((uint32_t)(x >> 32));
            return true;
        }
        heap_pop(h);
    }
    return false;
}

static inline bool excluded(const tin *t, uint32_t s)
{
    return t->excl[s >> 3] >> (s & 7) & 1;
}

static inline bool cell_ok(const tin *t, int64_t c, int64_t r)
{
    if (c < 0 || r < 0 || c + 1 >= t->w || r + 1 >= t->h)
        return false;
    const float *p = t->data + (size_t)r * t->w + (size_t)c;
    return !isnan(p[0]) && !isnan(p[1]) && !isnan(p[t->w]) && !isnan(p[t->w + 1]);
}

/* cell_ok, but for cells outside the block from the whole heightfield */
static inline bool cell_ctx(const tin *t, int64_t c, int64_t r)
{
    if (c >= 0 && r >= 0 && c + 1 < t->w && r + 1 < t->h)
        return cell_ok(t, c, r);
    int64_t gc = c + t->ctx.x, gr = r + t->ctx.y;
    if (gc < 0 || gr < 0 || gc + 1 >= t->ctx.w || gr + 1 >= t->ctx.h)
        return false;
    const float *p = t->ctx.data + (size_t)gr * t->ctx.w + (size_t)gc;
    return !isnan(p[0]) && !isnan(p[1]) && !isnan(p[t->ctx.w]) && !isnan(p[t->ctx.w + 1]);
}

/* floor(a / b) for b > 0 and |a| < 2^50: the double quotient truncated,
 * then an exact integer correction (an integer division, or a call to
 * floor, costs more). */
static inline int64_t floor_div_fast(int64_t a, int64_t b)
{
    int64_t q = (int64_t)((double)a / (double)b);
    while (q * b > a)
        q--;
    while ((q + 1) * b <= a)
        q++;
    return q;
}

/* A hint to fetch the line at p (a no-op where the compiler has none). */
#if defined(__GNUC__) || defined(__clang__)
#define PREFETCH(p) __builtin_prefetch(p)
#else
#define PREFETCH(p) ((void)(p))
#endif

/* The scan is compiled twice, for AVX2 and for the baseline, and the
 * running processor's version is called (TSR_AVX2_DISPATCH,
 * terrain_internal.h). The scans' four lanes of doubles become one
 * vector. No FMA: the same roundings, so the same results, on either. */

/* |rp[x] - (base + ga x)| */
static inline double err_at(const float *rp, int64_t x, double base, double ga)
{
    return fabs((double)rp[x] - (base + ga * (double)x));
}

/* max over x < n (n >= 1) of err_at, four samples at a time in a vector
 * of doubles (two SSE2 registers, or one AVX register in the AVX2 clone
 * of the caller); the last four overlap the previous ones rather than a
 * scalar tail. Each lane computes exactly err_at's expression. */
#ifdef TSR_VECTORS
static inline double row_max(const float *restrict rp, int64_t n, double base, double ga)
{
    if (n < 4) {
        double m = err_at(rp, 0, base, ga);
        for (int64_t x = 1; x < n; x++) {
            double e = err_at(rp, x, base, ga);
            m = e > m ? e : m;
        }
        return m;
    }
    const tsr_v4l abs_mask = {INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX};
    const tsr_v4d lane = {0, 1, 2, 3};
    tsr_v4d m = {-1, -1, -1, -1};
    for (int64_t x = 0;; x += 4) {
        if (x + 4 > n)
            x = n - 4;
        tsr_v4f f;
        memcpy(&f, rp + x, sizeof f);
        tsr_v4d xs = (double)x + lane;
        tsr_v4d d = __builtin_convertvector(f, tsr_v4d) - (base + ga * xs);
        tsr_v4d e = (tsr_v4d)((tsr_v4l)d & abs_mask);
        tsr_v4l gt = e > m;
        m = (tsr_v4d)(((tsr_v4l)e & gt) | ((tsr_v4l)m & ~gt));
        if (x + 4 >= n)
            break;
    }
    double m0 = m[1] > m[0] ? m[1] : m[0], m2 = m[3] > m[2] ? m[3] : m[2];
    return m2 > m0 ? m2 : m0;
}
#else
static inline double row_max(const float *restrict rp, int64_t n, double base, double ga)
{
    double m = err_at(rp, 0, base, ga);
    for (int64_t x = 1; x < n; x++) {
        double e = err_at(rp, x, base, ga);
        m = e > m ? e : m;
    }
    return m;
}
#endif

/* The lattice positions and heights of vertices v[3]; false when one is
 * no-data (the triangle is outside the domain). */
static inline bool tri_load(const tin *t, const uint32_t v[3], int64_t c[3], int64_t r[3], double z[3])
{
    for (int k = 0; k < 3; k++) {
        const tvx *p = t->vx + v[k];
        c[k] = p->c;
        r[k] = p->r;
        z[k] = p->z;
    }
    return !isnan(z[0]) && !isnan(z[1]) && !isnan(z[2]);
}

/* An edge's column on successive rows, without a division per row: at row
 * y, x = x0 + floor((x1 - x0) (y - y0) / dy), rem the division's
 * remainder (in [0, dy)), so the ceiling is x + (rem != 0). */
typedef struct dda {
    int64_t x, rem, dy, q, r;
} dda;

static inline void dda_init(dda *e, int64_t x0, int64_t y0, int64_t x1, int64_t y1, int64_t y)
{
    int64_t dy = y1 - y0, dx = x1 - x0;
    if (dy <= 0) { /* a row of its own: used on row y0 only */
        *e = (dda){x0, 0, 1, 0, 0};
        return;
    }
    int64_t num = dx * (y - y0), f = y == y0 ? 0 : floor_div_fast(num, dy), q = floor_div_fast(dx, dy);
    *e = (dda){x0 + f, num - f * dy, dy, q, dx - q * dy};
}

static inline void dda_step(dda *e)
{
    e->x += e->q;
    e->rem += e->r;
    if (e->rem >= e->dy) {
        e->x++;
        e->rem -= e->dy;
    }
}

/* Asks for the lines of the triangle's first rows (up to 32) at once, so
 * that their misses overlap (the rows lie w samples apart: each its own
 * line, often its own page) rather than stall a scan one after another. */
static inline void prefetch_tri(const tin *t, const int64_t c[3], const int64_t r[3])
{
    int64_t x0 = c[0] < c[1] ? c[0] : c[1], x1 = c[0] > c[1] ? c[0] : c[1];
    x0 = c[2] < x0 ? c[2] : x0;
    x1 = c[2] > x1 ? c[2] : x1;
    int64_t y0 = r[0] < r[1] ? r[0] : r[1], y1 = r[0] > r[1] ? r[0] : r[1];
    y0 = r[2] < y0 ? r[2] : y0;
    y1 = r[2] > y1 ? r[2] : y1;
    if (y1 - y0 > 32)
        y1 = y0 + 32;
    for (int64_t y = y0; y <= y1; y++) {
        const float *row = t->data + (size_t)y * t->w;
        PREFETCH(row + x0);
        if (x1 - x0 >= 16)
            PREFETCH(row + x1);
    }
}

/* The worst candidate sample of the triangle (c, r, z), counter-clockwise
 * and not degenerate: its error into *best (-1 when the triangle has no
 * candidate), its index into *best_s. Stops early once a row's error
 * exceeds stop (then *best > stop, *best_s may be any sample of it); stop
 * = INFINITY scans it all. Rows top to bottom, each the lattice points
 * inside or on the triangle, between its edges' columns stepped exactly
 * in integers (the vertices sorted by row: the long edge from the top to
 * the bottom one on one side, the two short ones on the other). */
static TSR_ALWAYS_INLINE void tri_worst_body(const tin *t, const int64_t c[3], const int64_t r[3], const double z[3],
                                             double stop, double *best_out, uint32_t *best_s_out)
{
    int64_t det = (c[1] - c[0]) * (r[2] - r[0]) - (c[2] - c[0]) * (r[1] - r[0]);
    double ga = ((z[1] - z[0]) * (double)(r[2] - r[0]) - (z[2] - z[0]) * (double)(r[1] - r[0])) / (double)det;
    double gb = ((double)(c[1] - c[0]) * (z[2] - z[0]) - (double)(c[2] - c[0]) * (z[1] - z[0])) / (double)det;
    /* top, middle, bottom by row */
    int a = 0, b = 1, d = 2, s;
    if (r[b] < r[a])
        s = a, a = b, b = s;
    if (r[d] < r[b]) {
        s = b, b = d, d = s;
        if (r[b] < r[a])
            s = a, a = b, b = s;
    }
    int64_t ra = r[a], rb = r[b], rd = r[d];
    /* the middle vertex left of the long edge (a, d)? */
    bool mid_left = (c[d] - c[a]) * (rb - ra) - (c[b] - c[a]) * (rd - ra) > 0;
    int64_t y0 = ra, y1 = rd, clo = INT64_MIN, chi = INT64_MAX;
    /* the outer border is no candidate when fixed */
    if (t->fixed_border) {
        if (y0 < 1)
            y0 = 1;
        if (y1 > (int64_t)t->h - 2)
            y1 = (int64_t)t->h - 2;
        clo = 1;
        chi = (int64_t)t->w - 2;
    }
    double best = -1;
    uint32_t best_s = UINT32_MAX;
    /* the row holding the worst sample so far (its position found once,
     * at the end) */
    const float *best_rp = NULL;
    int64_t best_n = 0, best_x0 = 0, best_y = 0;
    double best_base = 0;
    if (y0 > y1) {
        *best_out = best;
        *best_s_out = best_s;
        return;
    }
    prefetch_tri(t, c, r);
    dda el, es;
    dda_init(&el, c[a], ra, c[d], rd, y0);
    bool lower = y0 >= rb;
    if (lower)
        dda_init(&es, c[b], rb, c[d], rd, y0);
    else
        dda_init(&es, c[a], ra, c[b], rb, y0);
    for (int64_t y = y0; y <= y1 && best <= stop; y++) {
        if (!lower && y == rb) {
            dda_init(&es, c[b], rb, c[d], rd, y);
            lower = true;
        }
        int64_t lo, hi;
        if (mid_left) {
            lo = es.x + (es.rem != 0);
            hi = el.x;
        } else {
            lo = el.x + (el.rem != 0);
            hi = es.x;
        }
        dda_step(&el);
        dda_step(&es);
        lo = lo > clo ? lo : clo;
        hi = hi < chi ? hi : chi;
        if (lo > hi)
            continue;
        const float *row = t->data + (size_t)y * t->w;
        double base = z[0] + ga * (double)(lo - c[0]) + gb * (double)(y - r[0]);
        if (!t->nodata) {
            /* the row's max; the row kept when it beats best */
            const float *rp = row + lo;
            int64_t n = hi - lo + 1;
            double m = row_max(rp, n, base, ga);
            if (m > best) {
                best = m;
                best_rp = rp;
                best_n = n;
                best_x0 = lo;
                best_y = y;
                best_base = base;
            }
        } else {
            for (int64_t x = lo; x <= hi; x++) {
                uint32_t smp = (uint32_t)((size_t)y * t->w + (size_t)x);
                if (excluded(t, smp))
                    continue;
                double e = fabs((double)row[x] - (base + ga * (double)(x - lo)));
                if (e > best) {
                    best = e;
                    best_s = smp;
                }
            }
        }
    }
    if (best_rp) /* the first sample of the row at its max */
        for (int64_t x = 0; x < best_n; x++)
            if (err_at(best_rp, x, best_base, ga) == best) {
                best_s = (uint32_t)((size_t)best_y * t->w + (size_t)(best_x0 + x));
                break;
            }
    *best_out = best;
    *best_s_out = best_s;
}

#ifdef TSR_AVX2_DISPATCH
__attribute__((target("avx2"))) static void tri_worst_avx2(const tin *t, const int64_t c[3], const int64_t r[3],
                                                          const double z[3], double stop, double *best_out,
                                                          uint32_t *best_s_out)
{
    tri_worst_body(t, c, r, z, stop, best_out, best_s_out);
}
#endif

/* The worst candidate sample of the triangle (c, r, z) (none: best -1,
 * UINT32_MAX), scanning no further once best exceeds stop. */
static void tri_worst(const tin *t, const int64_t c[3], const int64_t r[3], const double z[3], double stop,
                      double *best_out, uint32_t *best_s_out)
{
#ifdef TSR_AVX2_DISPATCH
    if (__builtin_cpu_supports("avx2")) {
        tri_worst_avx2(t, c, r, z, stop, best_out, best_s_out);
        return;
    }
#endif
    tri_worst_body(t, c, r, z, stop, best_out, best_s_out);
}

/* Sets slot s's record to error best at sample best_s (none when best_s
 * is UINT32_MAX). */
static void queue_set(tin *t, uint32_t s, double best, uint32_t best_s)
{
    if (best_s == UINT32_MAX) {
        rec_set(t, s, -1.0f, UINT32_MAX);
        return;
    }
    float key = (float)best; /* rounded up, so a key at or below the target means the error is */
    if ((double)key < best) /* the next float up (best >= 0 and finite) */
        key = bits_f32(f32_bits(key) + 1);
    rec_set(t, s, key, best_s);
}

/* Scans the triangle in slot s: its worst candidate sample into its
 * record (and the queue when above the target), none when it has none. */
static void scan(tin *t, uint32_t s)
{
    uint32_t v[3];
    int64_t c[3], r[3];
    double z[3];
    if (!tsr_cdt_triangle(t->cdt, s, v) || !tri_load(t, v, c, r, z)) { /* a ghost, or outside the domain */
        rec_set(t, s, -1.0f, UINT32_MAX);
        return;
    }
    int64_t det = (c[1] - c[0]) * (r[2] - r[0]) - (c[2] - c[0]) * (r[1] - r[0]);
    if (det <= 0) {
        rec_set(t, s, -1.0f, UINT32_MAX);
        return;
    }
    double best;
    uint32_t best_s;
    tri_worst(t, c, r, z, INFINITY, &best, &best_s);
    queue_set(t, s, best, best_s);
}

/* Scans the slots s[0..n): first every triangle's vertices loaded and its
 * rows and record asked for, then the scans, so that the misses of one
 * triangle overlap those of the others. */
static void scan_batch(tin *t, const uint32_t *s, uint32_t n)
{
    struct {
        int64_t c[3], r[3];
        double z[3];
        bool ok;
    } b[64];
    for (uint32_t i = 0; i < n && i < 64; i++) {
        uint32_t v[3];
        b[i].ok = tsr_cdt_triangle(t->cdt, s[i], v);
        if (!b[i].ok)
            continue;
        for (int k = 0; k < 3; k++) {
            const tvx *p = t->vx + v[k];
            b[i].c[k] = p->c;
            b[i].r[k] = p->r;
            b[i].z[k] = p->z;
        }
    }
    for (uint32_t i = 0; i < n && i < 64; i++) {
        PREFETCH(t->rec + s[i]);
        if (!b[i].ok)
            continue;
        b[i].ok = !isnan(b[i].z[0]) && !isnan(b[i].z[1]) && !isnan(b[i].z[2]) &&
                  (b[i].c[1] - b[i].c[0]) * (b[i].r[2] - b[i].r[0]) - (b[i].c[2] - b[i].c[0]) * (b[i].r[1] - b[i].r[0]) > 0;
        if (b[i].ok)
            prefetch_tri(t, b[i].c, b[i].r);
    }
    for (uint32_t i = 0; i < n && i < 64; i++) {
        if (!b[i].ok) { /* a ghost, outside the domain, or degenerate */
            rec_set(t, s[i], -1.0f, UINT32_MAX);
            continue;
        }
        double best;
        uint32_t best_s;
        tri_worst(t, b[i].c, b[i].r, b[i].z, INFINITY, &best, &best_s);
        queue_set(t, s[i], best, best_s);
    }
}

/* ---- data-dependent flips ------------------------------------------------ */

/* Which edges are worth a flip test: those whose worse triangle's error e
 * lies in (target, FLIP_WINDOW target]. Triangles far above the target
 * are split again soon whatever their shape, and testing them (big quads,
 * early in the pass) costs more than it saves: against no window, 4 made
 * as many triangles (-3 % to +4 % on the bench inputs) in 0.6-0.8x the
 * time. */
#define FLIP_WINDOW 4.0
/* Flips per insertion at most (the cascade is short: about 1.3 a point). */
#define FLIP_MAX 64

static bool in_domain(const tin *t, const uint32_t v[3]);

static void push_edge(tin *t, uint32_t s, uint32_t a, uint32_t b)
{
    if (t->nfs + 3 > t->cap_fs && !grow_u32(t->a, (void **)&t->fstack, &t->cap_fs, t->nfs + 3, sizeof *t->fstack)) {
        t->nomem = true;
        return;
    }
    t->fstack[t->nfs++] = s;
    t->fstack[t->nfs++] = a;
    t->fstack[t->nfs++] = b;
}

/* The queue's error of slot s (its key, rounded up), 0 without candidate. */
static inline double slot_error(const tin *t, uint32_t s)
{
    trec r = t->rec[s];
    return r.cand == UINT32_MAX ? 0 : r.err;
}

/* The height at lattice point (x, y) of the plane through (c, r, z). */
static inline double plane_at(const int64_t c[3], const int64_t r[3], const double z[3], int64_t x, int64_t y)
{
    double det = (double)((c[1] - c[0]) * (r[2] - r[0]) - (c[2] - c[0]) * (r[1] - r[0]));
    double ga = ((z[1] - z[0]) * (double)(r[2] - r[0]) - (z[2] - z[0]) * (double)(r[1] - r[0])) / det;
    double gb = ((double)(c[1] - c[0]) * (z[2] - z[0]) - (double)(c[2] - c[0]) * (z[1] - z[0])) / det;
    return z[0] + ga * (double)(x - c[0]) + gb * (double)(y - r[0]);
}

/* Twice the signed area of lattice points i, j, k (exact). */
static inline int64_t orient(const int64_t *c, const int64_t *r, int i, int j, int k)
{
    return (c[j] - c[i]) * (r[k] - r[i]) - (c[k] - c[i]) * (r[j] - r[i]);
}

/* The flip cost of a triangle: its error above the target. */
static inline double excess(double e, double target)
{
    return e > target ? e - target : 0;
}

/* Tests the edges on the stack. An edge shared by two triangles (p, x, y)
 * and (y, x, q) of the domain, not constrained, whose quad is strictly
 * convex and whose worse triangle's error is in (target, FLIP_WINDOW
 * target], is flipped to (p, x, q), (p, q, y) when that lowers the sum of
 * the two triangles' errors above the target (a data-dependent
 * triangulation, after N. Dyn, D. Levin and S. Rippa, "Data dependent
 * triangulations for piecewise linear interpolation", IMA J. Numer. Anal.
 * 10, 1990, with a cost made for the greedy pass: what is above the target
 * is what more insertions must remove; the max error, or the plain sum,
 * made up to 6 % more triangles). The quad's four sides are then tested in
 * turn. Every flip lowers the sum over all triangles by a margin, so the
 * pass ends; FLIP_MAX bounds its work. The queue's keys stay exact: both
 * new triangles are scanned in full before a flip is made. */
static void flip_pass(tin *t, double target)
{
    uint32_t done = 0;
    double window = FLIP_WINDOW * target;
    while (t->nfs && done < FLIP_MAX && !t->nomem) {
        t->nfs -= 3;
        uint32_t s = t->fstack[t->nfs], a = t->fstack[t->nfs + 1], b = t->fstack[t->nfs + 2];
        uint32_t v[3], w[3];
        if (!tsr_cdt_triangle(t->cdt, s, v))
            continue;
        int k = v[0] == a && v[1] == b ? 0 : v[1] == a && v[2] == b ? 1 : v[2] == a && v[0] == b ? 2 : -1;
        if (k < 0)
            continue; /* the slot was rewritten since */
        bool constrained;
        uint32_t n = tsr_cdt_neighbor(t->cdt, s, k, &constrained);
        if (n == UINT32_MAX || constrained || !tsr_cdt_triangle(t->cdt, n, w))
            continue;
        double es = slot_error(t, s), en = slot_error(t, n), cur = fmax(es, en);
        if (cur <= target || cur > window)
            continue;
        /* the quad: 0 p, 1 x, 2 y, 3 q; after the flip (0 1 3) and (0 3 2) */
        uint32_t id[4] = {v[(k + 2) % 3], a, b, w[0] != a && w[0] != b ? w[0] : w[1] != a && w[1] != b ? w[1] : w[2]};
        int64_t c[4], r[4];
        double z[4];
        bool valid = true;
        for (int i = 0; i < 4; i++) {
            const tvx *p = t->vx + id[i];
            c[i] = p->c;
            r[i] = p->r;
            z[i] = p->z;
            valid = valid && !isnan(z[i]);
        }
        if (!valid || orient(c, r, 0, 1, 3) <= 0 || orient(c, r, 0, 3, 2) <= 0)
            continue;
        if (t->nodata && (!in_domain(t, v) || !in_domain(t, w)))
            continue;
        int64_t c1[3] = {c[0], c[1], c[3]}, r1[3] = {r[0], r[1], r[3]}, c2[3] = {c[0], c[3], c[2]},
                r2[3] = {r[0], r[3], r[2]};
        double z1[3] = {z[0], z[1], z[3]}, z2[3] = {z[0], z[3], z[2]};
        /* the flip must beat the cost by a hair (no cycling on ties) */
        double cost = (excess(es, target) + excess(en, target)) * (1 - 1e-6);
        /* first, in O(1): the two worst samples' errors after the flip
         * bound the new cost from below */
        double lb[2] = {0, 0};
        for (int j = 0; j < 2; j++) {
            uint32_t smp = t->rec[j ? n : s].cand;
            if (smp == UINT32_MAX)
                continue;
            int64_t cc[3] = {c[0], c[3], smp % t->w}, rr[3] = {r[0], r[3], smp / t->w};
            int side = orient(cc, rr, 0, 1, 2) > 0; /* left of p->q: in (0 3 2) */
            double e = fabs(t->data[smp] - plane_at(side ? c2 : c1, side ? r2 : r1, side ? z2 : z1, cc[2], rr[2]));
            lb[side] = fmax(lb[side], excess(e, target));
        }
        if (lb[0] + lb[1] >= cost)
            continue;
        prefetch_tri(t, c2, r2); /* the first triangle's rows follow in tri_worst */
        double e1, e2;
        uint32_t s1, s2;
        tri_worst(t, c1, r1, z1, target + cost - lb[1], &e1, &s1);
        double left = cost - excess(e1, target);
        if (left <= lb[1])
            continue;
        tri_worst(t, c2, r2, z2, target + left, &e2, &s2);
        if (excess(e2, target) >= left)
            continue;
        tsr_status st = tsr_cdt_flip(t->cdt, s, k);
        if (st == TSR_ERR_NOMEM)
            t->nomem = true;
        if (st != TSR_OK)
            continue;
        done++;
        t->flips++;
        queue_set(t, s, e1, s1); /* s holds (p, x, q) now, n (p, q, y) */
        queue_set(t, n, e2, s2);
        push_edge(t, s, id[0], id[1]);
        push_edge(t, s, id[1], id[3]);
        push_edge(t, n, id[3], id[2]);
        push_edge(t, n, id[2], id[0]);
    }
    t->nfs = 0;
}

/* Inserts sample smp (hint: a slot near it); its vertex id, or UINT32_MAX
 * when out of memory. */
static uint32_t add_sample(tin *t, uint32_t smp, uint32_t hint)
{
    double x = smp % t->w, y = smp / t->w;
    uint32_t id = hint == UINT32_MAX ? tsr_cdt_insert(t->cdt, x, y) : tsr_cdt_insert_near(t->cdt, x, y, hint);
    if (id == UINT32_MAX)
        return id;
    if (id >= t->nv) {
        if (id >= t->cap_v) {
            uint32_t cap = t->cap_v ? t->cap_v + t->cap_v / 2 : 4096;
            while (cap <= id)
                cap += cap / 2;
            tvx *p = tsr_realloc(t->a, t->vx, (size_t)cap * sizeof *p);
            if (!p)
                return UINT32_MAX;
            t->vx = p;
            t->cap_v = cap;
        }
        t->vx[id] = (tvx){smp % t->w, smp / t->w, t->data[smp]};
        t->nv = id + 1;
    }
    return id;
}

/* Douglas-Peucker over the samples pts[0..n) of one straight run (heights
 * along it): marks the kept ones in keep[] (the ends always). */
static void dp(const float *data, const uint32_t *pts, uint32_t n, double tol, uint8_t *keep, uint32_t *stack)
{
    keep[0] = keep[n - 1] = 1;
    uint32_t top = 0;
    stack[top++] = 0;
    stack[top++] = n - 1;
    while (top) {
        uint32_t j = stack[--top], i = stack[--top];
        if (j - i < 2)
            continue;
        double zi = data[pts[i]], zj = data[pts[j]];
        double worst = -1;
        uint32_t wk = i;
        for (uint32_t k = i + 1; k < j; k++) {
            double z = zi + (zj - zi) * (double)(k - i) / (double)(j - i);
            double e = fabs((double)data[pts[k]] - z);
            if (e > worst) {
                worst = e;
                wk = k;
            }
        }
        if (worst > tol) {
            keep[wk] = 1;
            stack[top++] = i;
            stack[top++] = wk;
            stack[top++] = wk;
            stack[top++] = j;
        }
    }
}

typedef struct run_buf {
    uint32_t *pts, *stack;
    uint8_t *keep;
    uint32_t cap;
} run_buf;

/* Simplifies the run pts[0..n) and inserts it (constrained when
 * constrain); false when out of memory. */
static bool add_run(tin *t, run_buf *b, uint32_t n, double tol, bool constrain)
{
    if (n < 2)
        return true;
    memset(b->keep, 0, n);
    dp(t->data, b->pts, n, tol, b->keep, b->stack);
    uint32_t prev = UINT32_MAX;
    for (uint32_t k = 0; k < n; k++) {
        if (!b->keep[k])
            continue;
        uint32_t id = add_sample(t, b->pts[k], UINT32_MAX);
        if (id == UINT32_MAX)
            return false;
        if (constrain && prev != UINT32_MAX && tsr_cdt_insert_segment(t->cdt, prev, id, 0) != TSR_OK)
            return false;
        prev = id;
    }
    return true;
}

/* Is lattice edge (c, r)-(c+1, r) on the domain's boundary? */
static inline bool hedge(const tin *t, int64_t c, int64_t r)
{
    return cell_ok(t, c, r - 1) != cell_ok(t, c, r);
}
/* (c, r)-(c, r+1)? */
static inline bool vedge(const tin *t, int64_t c, int64_t r)
{
    return cell_ok(t, c - 1, r) != cell_ok(t, c, r);
}

/* Along line `line` of an axis (0: row `line`, 1: column `line`), the
 * sample at position i, whether the lattice edge from i to i + 1 is on the
 * boundary, and whether a boundary edge of the other axis meets point i. */
static inline uint32_t run_sample(const tin *t, int axis, uint32_t line, uint32_t i)
{
    return axis ? i * t->w + line : line * t->w + i;
}
static inline bool run_edge(const tin *t, int axis, uint32_t line, uint32_t i)
{
    return axis ? vedge(t, line, i) : hedge(t, i, line);
}
/* Crossings count on both sides of the line, outside the block too: a
 * block's side is cut where its neighbour's cells change (the same points
 * the neighbour cuts its side at), so both mesh their shared part alike. */
static inline bool hedge_ctx(const tin *t, int64_t c, int64_t r)
{
    return cell_ctx(t, c, r - 1) != cell_ctx(t, c, r);
}
static inline bool vedge_ctx(const tin *t, int64_t c, int64_t r)
{
    return cell_ctx(t, c - 1, r) != cell_ctx(t, c, r);
}
static inline bool run_crossed(const tin *t, int axis, uint32_t line, uint32_t i)
{
    return axis ? hedge_ctx(t, line, i) || hedge_ctx(t, (int64_t)line - 1, i)
                : vedge_ctx(t, i, line) || vedge_ctx(t, i, (int64_t)line - 1);
}

/* The boundary: the outer border's four sides, or, with no-data, every
 * maximal straight run of boundary edges (split where another boundary
 * edge meets it). Horizontal runs in increasing c, vertical in increasing
 * r, whichever side the domain is on, so both windows of a seam see the
 * same sequence. */
static bool add_boundary(tin *t, double tol)
{
    uint32_t cap = (t->w > t->h ? t->w : t->h) + 2;
    run_buf b = {0};
    b.cap = cap;
    b.pts = tsr_alloc(t->a, (size_t)cap * sizeof *b.pts);
    b.stack = tsr_alloc(t->a, (size_t)cap * 4 * sizeof *b.stack);
    b.keep = tsr_alloc(t->a, cap);
    bool ok = b.pts && b.stack && b.keep;
    uint32_t w = t->w, h = t->h;
    /* the corners first, so the hull is the rectangle at once */
    uint32_t corners[4] = {0, w - 1, (h - 1) * w, (h - 1) * w + w - 1};
    for (int k = 0; k < 4 && ok; k++)
        ok = add_sample(t, corners[k], UINT32_MAX) != UINT32_MAX;
    if (!t->nodata) {
        for (int side = 0; side < 4 && ok; side++) {
            uint32_t n = side < 2 ? w : h;
            for (uint32_t i = 0; i < n; i++)
                b.pts[i] = side == 0 ? i : side == 1 ? (h - 1) * w + i : side == 2 ? i * w : i * w + w - 1;
            ok = add_run(t, &b, n, tol, false);
        }
    }
    /* with no-data: horizontal runs along each row (axis 0), vertical runs
     * along each column (axis 1) */
    for (int axis = 0; axis < 2 && ok && t->nodata; axis++) {
        uint32_t lines = axis ? w : h, len = axis ? h : w;
        for (uint32_t line = 0; line < lines && ok; line++) {
            uint32_t n = 0;
            for (uint32_t i = 0; i + 1 < len && ok; i++) {
                if (!run_edge(t, axis, line, i)) {
                    ok = add_run(t, &b, n, tol, true);
                    n = 0;
                    continue;
                }
                if (n == 0)
                    b.pts[n++] = run_sample(t, axis, line, i);
                else if (run_crossed(t, axis, line, i)) { /* a junction: break */
                    ok = add_run(t, &b, n, tol, true);
                    n = 0;
                    b.pts[n++] = run_sample(t, axis, line, i);
                }
                b.pts[n++] = run_sample(t, axis, line, i + 1);
            }
            if (ok)
                ok = add_run(t, &b, n, tol, true);
        }
    }
    tsr_free(t->a, b.pts);
    tsr_free(t->a, b.stack);
    tsr_free(t->a, b.keep);
    return ok;
}

/* Is the triangle in slot s inside the domain? Every triangle is wholly in
 * or out (the boundary is made of constrained edges), so its centroid
 * decides: inside when a cell whose closure holds it is valid. */
static bool in_domain(const tin *t, const uint32_t v[3])
{
    if (!t->nodata)
        return true;
    double cx = 0, cy = 0;
    for (int k = 0; k < 3; k++) {
        cx += t->vx[v[k]].c;
        cy += t->vx[v[k]].r;
    }
    cx /= 3;
    cy /= 3;
    int64_t c0 = (int64_t)floor(cx), r0 = (int64_t)floor(cy);
    bool onx = cx == (double)c0, ony = cy == (double)r0;
    for (int64_t dr = ony ? -1 : 0; dr <= 0; dr++)
        for (int64_t dc = onx ? -1 : 0; dc <= 0; dc++)
            if (cell_ok(t, c0 + dc, r0 + dr))
                return true;
    return false;
}

static void tin_free(tin *t)
{
    tsr_cdt_destroy(t->cdt);
    heap_free(&t->q, t->a);
    tsr_free(t->a, t->vx);
    tsr_free(t->a, t->rec);
    tsr_free(t->a, t->dirty);
    tsr_free(t->a, t->excl);
    tsr_free(t->a, t->fstack);
}

/* Counts the triangles inside the domain and the vertices they use. */
static bool count_domain(tin *t, uint32_t *ntri, uint32_t *nvert)
{
    uint8_t *used = tsr_alloc(t->a, (size_t)t->nv + 1);
    if (!used)
        return false;
    memset(used, 0, (size_t)t->nv + 1);
    uint32_t nh = tsr_cdt_handle_count(t->cdt), nt = 0, nu = 0;
    for (uint32_t s = 0; s < nh; s++) {
        uint32_t v[3];
        if (!tsr_cdt_triangle(t->cdt, s, v) || !in_domain(t, v))
            continue;
        nt++;
        for (int k = 0; k < 3; k++)
            if (!used[v[k]]) {
                used[v[k]] = 1;
                nu++;
            }
    }
    tsr_free(t->a, used);
    *ntri = nt;
    *nvert = nu;
    return true;
}

/* Is sample smp on the domain's boundary (an insertion there adds one
 * triangle to the domain, not two)? */
static bool on_boundary(const tin *t, uint32_t smp)
{
    int64_t c = smp % t->w, r = smp / t->w;
    if (c == 0 || r == 0 || c == (int64_t)t->w - 1 || r == (int64_t)t->h - 1)
        return true;
    return t->nodata && !(cell_ok(t, c, r) && cell_ok(t, c - 1, r) && cell_ok(t, c, r - 1) && cell_ok(t, c - 1, r - 1));
}

static tsr_status mesh_delaunay(const tsr_heightfield *hf, const tin_ctx *ctx, double target, double btol,
                                bool fixed_border, uint32_t max_tri, uint32_t max_vert, const tsr_tin_options *o,
                                tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err)
{
    tin t = {0};
    t.ctx = *ctx;
    t.fixed_border = fixed_border;
    t.flip = !o->no_flip;
    t.data = hf->data;
    t.w = hf->width;
    t.h = hf->height;
    t.a = hf->alloc.realloc ? &hf->alloc : NULL;
    size_t ns = (size_t)t.w * t.h;
    if (ns >= UINT32_MAX)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "delaunay mesh: %ux%u samples exceed 32-bit sample indices",
                             t.w, t.h);
    t.nodata = ctx->nodata;
    t.cdt = tsr_cdt_create(t.a);
    if (!t.cdt)
        return tsr_error_set(err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
    tsr_status st = TSR_ERR_NOMEM;
    if (t.nodata) {
        t.excl = tsr_alloc(t.a, ns / 8 + 1);
        if (!t.excl)
            goto fail;
        memset(t.excl, 0, ns / 8 + 1);
        /* a candidate needs its four cells valid (fixed boundaries), or one
         * (boundaries refined too) */
        for (uint32_t r = 0; r < t.h; r++)
            for (uint32_t c = 0; c < t.w; c++) {
                bool k0 = cell_ok(&t, c, r), k1 = cell_ok(&t, (int64_t)c - 1, r), k2 = cell_ok(&t, c, (int64_t)r - 1),
                     k3 = cell_ok(&t, (int64_t)c - 1, (int64_t)r - 1);
                bool in = fixed_border ? k0 && k1 && k2 && k3 : k0 || k1 || k2 || k3;
                if (!in) {
                    size_t s = (size_t)r * t.w + c;
                    t.excl[s >> 3] |= (uint8_t)(1u << (s & 7));
                }
            }
    }
    if (!add_boundary(&t, fixed_border ? btol : INFINITY))
        goto fail;
    rep->border_vertices = t.nv;
    uint32_t ntri, nvert;
    if (!count_domain(&t, &ntri, &nvert))
        goto fail;
    if ((max_tri && ntri > max_tri) || (max_vert && nvert > max_vert)) {
        if (fixed_border)
            st = tsr_error_set(err, TSR_ERR_ARGUMENT,
                               "the budget is below what the fixed border needs (%u vertices, %u triangles at border "
                               "tolerance %g); raise the budget or the border tolerance (--max-error)",
                               nvert, ntri, btol * hf->dz);
        else
            st = tsr_error_set(err, TSR_ERR_ARGUMENT,
                               "the budget is below the smallest mesh (%u vertices, %u triangles: the corners of the "
                               "border and of the no-data boundaries)",
                               nvert, ntri);
        goto fail;
    }
    tsr_cdt_track_changes(t.cdt, true);
    /* the heap holds the slots whose error is above the target: thr is
     * the largest float at or below it */
    t.thr = (float)target;
    if ((double)t.thr > target)
        t.thr = nextafterf(t.thr, -INFINITY);
    uint32_t nh = tsr_cdt_handle_count(t.cdt);
    if (!rec_slots(&t, nh))
        goto fail;
    for (uint32_t s = 0; s < nh; s++)
        scan(&t, s);
    flush(&t);
    if (t.nomem)
        goto fail;
    uint32_t s;
    float key;
    double first = heap_top(&t, &s, &key) ? key : 0;
    uint32_t steps = 0;
    for (;;) {
        if (!heap_top(&t, &s, &key))
            break;
        double e = key;
        if (e <= target)
            break;
        uint32_t cand = t.rec[s].cand;
        uint32_t grow = !fixed_border && on_boundary(&t, cand) ? 1 : 2;
        if ((max_tri && ntri + grow > max_tri) || (max_vert && nvert + 1 > max_vert)) {
            rep->budget_reached = true;
            break;
        }
        uint32_t before = tsr_cdt_vertex_count(t.cdt);
        uint32_t id = add_sample(&t, cand, s);
        if (id == UINT32_MAX)
            goto fail;
        if (tsr_cdt_vertex_count(t.cdt) == before) {
            /* the candidate was a vertex already (a rounding residue) */
            rec_set(&t, s, -1.0f, UINT32_MAX);
            flush(&t);
            tsr_cdt_clear_changes(t.cdt);
            continue;
        }
        ntri += grow;
        nvert += 1;
        rep->insertions++;
        uint32_t nc;
        const uint32_t *ch = tsr_cdt_changes(t.cdt, &nc);
        if (!rec_slots(&t, tsr_cdt_handle_count(t.cdt)))
            goto fail;
        uint32_t nseen = 0;
        for (uint32_t i = 0; i < nc; i++) {
            uint32_t cs = ch[i];
            bool again = false; /* listed twice (flipped again): scan once */
            for (uint32_t j = 0; j < nseen && !again; j++)
                again = t.seen[j] == cs;
            if (again)
                continue;
            if (nseen < sizeof t.seen / sizeof t.seen[0])
                t.seen[nseen++] = cs;
            else
                scan(&t, cs);
        }
        scan_batch(&t, t.seen, nseen);
        tsr_cdt_clear_changes(t.cdt);
        if (t.flip) {
            /* the new triangles' edges: the star's outer edges and its
             * spokes (once each) */
            for (uint32_t i = 0; i < nseen; i++) {
                uint32_t v[3];
                if (!tsr_cdt_triangle(t.cdt, t.seen[i], v))
                    continue;
                for (int k = 0; k < 3; k++) {
                    uint32_t nb = tsr_cdt_neighbor(t.cdt, t.seen[i], k, NULL);
                    if (nb != UINT32_MAX) /* its record: read by the flip test */
                        PREFETCH(t.rec + nb);
                    bool inner = false;
                    for (uint32_t j = 0; j < nseen && !inner; j++)
                        inner = t.seen[j] == nb;
                    if (!inner || v[k] < v[(k + 1) % 3])
                        push_edge(&t, t.seen[i], v[k], v[(k + 1) % 3]);
                }
            }
            /* with a budget alone, the target is unknown: half the worst
             * error so far stands for it */
            if (!(target > 0))
                flush(&t);
            flip_pass(&t, target > 0 ? target : 0.5 * (heap_top(&t, &s, &key) ? key : 0));
            tsr_cdt_clear_changes(t.cdt);
        }
        flush(&t);
        if (t.nomem)
            goto fail;
        if (o->progress && (++steps & 4095) == 0) {
            double f = 0;
            if (max_tri)
                f = (double)ntri / max_tri;
            if (max_vert)
                f = fmax(f, (double)nvert / max_vert);
            if (target > 0 && first > target && e > 0)
                f = fmax(f, log(first / e) / log(first / target));
            o->progress(o->progress_user, f < 1 ? f : 1);
        }
    }
    rep->flips = t.flips;
    /* the worst error left: the records' (the heap holds only those above
     * the target) */
    double worst = 0;
    for (uint32_t i = 0; i < t.nrec; i++)
        if (t.rec[i].cand != UINT32_MAX && t.rec[i].err > worst)
            worst = t.rec[i].err;
    rep->estimated_error = worst * hf->dz;
    tsr_free(t.a, t.rec); /* with the heap, before the output, to lower the peak */
    t.rec = NULL;
    heap_free(&t.q, t.a); /* before the output, to lower the peak */
    memset(&t.q, 0, sizeof t.q);
    /* the mesh: triangles inside the domain, their vertices compacted */
    {
        uint32_t *map = tsr_alloc(t.a, ((size_t)t.nv + 1) * sizeof *map);
        if (!map)
            goto fail;
        for (uint32_t i = 0; i < t.nv; i++)
            map[i] = UINT32_MAX;
        if (tsr_mesh_reserve(mesh, nvert, ntri) != TSR_OK) {
            tsr_free(t.a, map);
            goto fail;
        }
        nh = tsr_cdt_handle_count(t.cdt);
        for (uint32_t s = 0; s < nh; s++) {
            uint32_t v[3], m[3];
            if (!tsr_cdt_triangle(t.cdt, s, v) || !in_domain(&t, v))
                continue;
            for (int k = 0; k < 3; k++) {
                if (map[v[k]] == UINT32_MAX) {
                    uint32_t smp = t.vx[v[k]].r * t.w + t.vx[v[k]].c;
                    float p[3] = {(float)((smp % t.w) * hf->dx), (float)((smp / t.w) * hf->dy),
                                  (float)(t.data[smp] * hf->dz)};
                    map[v[k]] = tsr_mesh_add_vertex(mesh, p, NULL, NULL);
                }
                m[k] = map[v[k]];
            }
            if (m[0] == UINT32_MAX || m[1] == UINT32_MAX || m[2] == UINT32_MAX ||
                !tsr_mesh_add_triangle(mesh, m[0], m[1], m[2])) {
                tsr_free(t.a, map);
                goto fail;
            }
        }
        tsr_free(t.a, map);
    }
    tin_free(&t);
    return TSR_OK;
fail:
    tin_free(&t);
    if (st == TSR_ERR_NOMEM)
        return tsr_error_set(err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
    return st;
}

/* ---- blocks: the delaunay mesh of a window, cut into blocks ---------- */

/* Whether the window x, y, w, h or the ring of samples around it (inside
 * the heightfield) has no-data. */
static bool ring_nodata(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w, uint32_t h)
{
    uint32_t x0 = x ? x - 1 : 0, y0 = y ? y - 1 : 0;
    uint32_t x1 = x + w < hf->width ? x + w : hf->width - 1, y1 = y + h < hf->height ? y + h : hf->height - 1;
    for (uint32_t r = y0; r <= y1; r++) {
        const float *row = hf->data + (size_t)r * hf->width;
        for (uint32_t c = x0; c <= x1; c++)
            if (isnan(row[c]))
                return true;
    }
    return false;
}

typedef struct tin_block {
    uint32_t x, y, w, h; /* in the whole heightfield */
    bool finished;       /* meshed (or failed): may be welded */
    tsr_mesh mesh;       /* window coordinates (x - window x) dx, ... */
    tsr_tin_report rep;
    tsr_status st;
    tsr_error err;
    double done; /* progress, 0..1 */
} tin_block;

typedef struct tin_job {
    const tsr_heightfield *hf;
    const tsr_tin_options *o;
    double target, btol;
    uint32_t wx, wy; /* the window's origin */
    tin_block *b;
    uint32_t nb, next;
    bool failed;
    bool clean; /* the heightfield has no no-data at all: no block's ring either */
    double cells; /* in all blocks */
    pthread_mutex_t lock;
    /* welding, in block order, as the blocks finish (under lock: which
     * blocks are finished, whether a thread is welding, the next to weld;
     * the welding thread alone touches the output and the seams) */
    bool welding;
    uint32_t next_weld;
    tsr_status weld_st;
    tsr_error weld_err;
    const struct seams *seams;
    tsr_mesh *out;
    tsr_tin_report *rep;
} tin_job;

typedef struct block_progress_user {
    tin_job *job;
    uint32_t i;
} block_progress_user;

/* A block's progress into the window's (serialised: the caller's
 * function need not be thread-safe). */
static void block_progress(void *user, double f)
{
    block_progress_user *u = user;
    tin_job *j = u->job;
    pthread_mutex_lock(&j->lock);
    j->b[u->i].done = f;
    double sum = 0;
    for (uint32_t i = 0; i < j->nb; i++)
        sum += j->b[i].done * (double)(j->b[i].w - 1) * (j->b[i].h - 1);
    j->o->progress(j->o->progress_user, sum / j->cells);
    pthread_mutex_unlock(&j->lock);
}

static void mesh_block(tin_job *j, uint32_t i)
{
    tin_block *b = &j->b[i];
    const tsr_heightfield *hf = j->hf;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    tsr_mesh_init(&b->mesh, 0, a);
    tin_ctx ctx = {hf->data, hf->width, hf->height, b->x, b->y,
                   !j->clean && ring_nodata(hf, b->x, b->y, b->w, b->h)};
    bool any = !ctx.nodata;
    for (uint32_t r = b->y; r + 1 < b->y + b->h && !any; r++)
        for (uint32_t c = b->x; c + 1 < b->x + b->w && !any; c++) {
            const float *p = hf->data + (size_t)r * hf->width + c;
            any = !isnan(p[0]) && !isnan(p[1]) && !isnan(p[hf->width]) && !isnan(p[hf->width + 1]);
        }
    if (!any) { /* no cell: no triangle */
        b->st = TSR_OK;
        return;
    }
    /* a copy of the block: its rows contiguous (blocks are used only when
     * there are several, so never the whole heightfield) */
    tsr_heightfield *crop = tsr_heightfield_crop(hf, b->x, b->y, b->w, b->h, a);
    if (!crop) {
        b->st = tsr_error_set(&b->err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
        return;
    }
    tsr_tin_options o = *j->o;
    block_progress_user pu = {j, i};
    if (o.progress) {
        o.progress = block_progress;
        o.progress_user = &pu;
    }
    b->st = mesh_delaunay(crop, &ctx, j->target, j->btol, true, 0, 0, &o, &b->mesh, &b->rep, &b->err);
    tsr_heightfield_destroy(crop);
    /* block coordinates to the window's */
    double ox = (double)(b->x - j->wx), oy = (double)(b->y - j->wy);
    for (uint32_t k = 0; b->st == TSR_OK && k < b->mesh.vertex_count; k++) {
        float *pp = b->mesh.positions + 3 * (size_t)k;
        pp[0] = (float)((lround(pp[0] / hf->dx) + ox) * hf->dx);
        pp[1] = (float)((lround(pp[1] / hf->dy) + oy) * hf->dy);
    }
    if (o.progress)
        block_progress(&pu, 1);
}

/* The vertex of window sample (c, r) on a seam, or a new one: seam
 * vertices are shared by the blocks on both sides (and at a corner by
 * four). vcol[k]: the column seam k's vertices by row, vrow[k] the row
 * seam's by column (UINT32_MAX: none yet). */
typedef struct seams {
    uint32_t nx, ny;         /* blocks across and down */
    const uint32_t *sx, *sy; /* block k spans window columns sx[k]..sx[k+1] */
    uint32_t **vcol, **vrow;
} seams;

static uint32_t *seam_slot(const seams *s, uint32_t bi, uint32_t bj, uint32_t c, uint32_t r, uint32_t *slots[4])
{
    uint32_t n = 0;
    if (bi > 0 && c == s->sx[bi])
        slots[n++] = &s->vcol[bi][r];
    if (bi + 1 < s->nx && c == s->sx[bi + 1])
        slots[n++] = &s->vcol[bi + 1][r];
    if (bj > 0 && r == s->sy[bj])
        slots[n++] = &s->vrow[bj][c];
    if (bj + 1 < s->ny && r == s->sy[bj + 1])
        slots[n++] = &s->vrow[bj + 1][c];
    for (uint32_t k = n; k < 4; k++)
        slots[k] = NULL;
    return n ? slots[0] : NULL;
}

/* Appends block i's mesh to the output, its seam vertices shared with
 * the blocks welded before it, and frees the block's mesh. */
static tsr_status weld_block(tin_job *j, uint32_t i)
{
    const tsr_heightfield *hf = j->hf;
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    const seams *sm = j->seams;
    tin_block *bk = &j->b[i];
    uint32_t bi = i % sm->nx, bj = i / sm->nx;
    tsr_status st = bk->st;
    if (st != TSR_OK)
        j->weld_err = bk->err;
    uint32_t *map = st == TSR_OK ? tsr_alloc(a, ((size_t)bk->mesh.vertex_count + 1) * sizeof *map) : NULL;
    if (st == TSR_OK && !map)
        st = tsr_error_set(&j->weld_err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
    for (uint32_t k = 0; st == TSR_OK && k < bk->mesh.vertex_count; k++) {
        const float *p = bk->mesh.positions + 3 * (size_t)k;
        uint32_t c = (uint32_t)lround(p[0] / hf->dx), r = (uint32_t)lround(p[1] / hf->dy);
        uint32_t *slots[4];
        uint32_t *first = seam_slot(sm, bi, bj, c, r, slots);
        uint32_t id = first ? *first : UINT32_MAX;
        if (id == UINT32_MAX && (id = tsr_mesh_add_vertex(j->out, p, NULL, NULL)) == UINT32_MAX)
            st = tsr_error_set(&j->weld_err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
        for (int q = 0; q < 4 && slots[q]; q++)
            *slots[q] = id;
        map[k] = id;
    }
    for (uint32_t k = 0; st == TSR_OK && k < bk->mesh.triangle_count; k++) {
        const uint32_t *t = bk->mesh.indices + 3 * (size_t)k;
        if (!tsr_mesh_add_triangle(j->out, map[t[0]], map[t[1]], map[t[2]]))
            st = tsr_error_set(&j->weld_err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
    }
    tsr_free(a, map);
    if (st == TSR_OK) {
        tsr_tin_report *rep = j->rep;
        rep->border_vertices += bk->rep.border_vertices;
        rep->insertions += bk->rep.insertions;
        rep->flips += bk->rep.flips;
        rep->estimated_error = fmax(rep->estimated_error, bk->rep.estimated_error);
    }
    tsr_mesh_free(&bk->mesh);
    return st;
}

/* Marks block i finished and, unless another thread is at it, welds the
 * finished blocks that follow the welded ones, in block order, so that a
 * block's mesh lives only until the blocks before it are done (at 16k,
 * all the blocks' meshes and the welded mesh used to coexist). */
static void block_finished(tin_job *j, uint32_t i)
{
    pthread_mutex_lock(&j->lock);
    j->b[i].finished = true;
    if (j->b[i].st != TSR_OK)
        j->failed = true;
    if (!j->welding) {
        j->welding = true;
        while (j->weld_st == TSR_OK && j->next_weld < j->nb && j->b[j->next_weld].finished) {
            uint32_t k = j->next_weld++;
            pthread_mutex_unlock(&j->lock);
            tsr_status st = weld_block(j, k);
            pthread_mutex_lock(&j->lock);
            if (st != TSR_OK) {
                j->weld_st = st;
                j->failed = true;
            }
        }
        j->welding = false;
    }
    pthread_mutex_unlock(&j->lock);
}

static void *block_worker(void *arg)
{
    tin_job *j = arg;
    for (;;) {
        pthread_mutex_lock(&j->lock);
        uint32_t i = j->next++;
        bool stop = j->failed || i >= j->nb;
        pthread_mutex_unlock(&j->lock);
        if (stop)
            return NULL;
        mesh_block(j, i);
        block_finished(j, i);
    }
}

/* clean: hf has no no-data sample at all (its stats say so), so no ring
 * needs scanning for it. */
static tsr_status mesh_delaunay_blocks(const tsr_heightfield *hf, const tsr_heightfield *win, bool clean,
                                       uint32_t wx, uint32_t wy, uint32_t ww, uint32_t wh, double target, double btol,
                                       bool fixed, const tsr_tin_options *o, tsr_mesh *mesh, tsr_tin_report *rep,
                                       tsr_error *err)
{
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    bool cut = fixed && !o->max_triangles && !o->max_vertices;
    uint32_t B = o->block ? o->block : 256;
    uint32_t nx = cut ? (ww - 1 + B - 1) / B : 1, ny = cut ? (wh - 1 + B - 1) / B : 1;
    if (nx * ny <= 1 || !cut) {
        /* one block: the window itself (the heightfield when whole) */
        tin_ctx ctx = {hf->data, hf->width, hf->height, wx, wy, !clean && ring_nodata(hf, wx, wy, ww, wh)};
        tsr_status st = mesh_delaunay(win, &ctx, target, btol, fixed, o->max_triangles, o->max_vertices, o, mesh,
                                      rep, err);
        rep->blocks = 1;
        return st;
    }
    tsr_status st = TSR_OK;
    uint32_t *sx = tsr_alloc(a, ((size_t)nx + 1) * sizeof *sx), *sy = tsr_alloc(a, ((size_t)ny + 1) * sizeof *sy);
    tin_block *b = tsr_alloc(a, (size_t)nx * ny * sizeof *b);
    uint32_t **vcol = tsr_alloc(a, (size_t)nx * sizeof *vcol), **vrow = tsr_alloc(a, (size_t)ny * sizeof *vrow);
    if (!sx || !sy || !b || !vcol || !vrow) {
        tsr_free(a, sx), tsr_free(a, sy), tsr_free(a, b), tsr_free(a, vcol), tsr_free(a, vrow);
        return tsr_error_set(err, TSR_ERR_NOMEM, "delaunay mesh: out of memory");
    }
    memset(b, 0, (size_t)nx * ny * sizeof *b);
    memset(vcol, 0, (size_t)nx * sizeof *vcol);
    memset(vrow, 0, (size_t)ny * sizeof *vrow);
    /* blocks of even size: cells split as evenly as the integers allow */
    for (uint32_t k = 0; k <= nx; k++)
        sx[k] = (uint32_t)((uint64_t)k * (ww - 1) / nx);
    for (uint32_t k = 0; k <= ny; k++)
        sy[k] = (uint32_t)((uint64_t)k * (wh - 1) / ny);
    tin_job j;
    memset(&j, 0, sizeof j);
    j.hf = hf, j.o = o, j.target = target, j.btol = btol, j.wx = wx, j.wy = wy, j.b = b, j.nb = nx * ny;
    j.cells = (double)(ww - 1) * (wh - 1);
    j.clean = clean;
    for (uint32_t by = 0; by < ny; by++)
        for (uint32_t bx = 0; bx < nx; bx++) {
            tin_block *bk = &b[by * nx + bx];
            bk->x = wx + sx[bx], bk->y = wy + sy[by];
            bk->w = sx[bx + 1] - sx[bx] + 1, bk->h = sy[by + 1] - sy[by] + 1;
        }
    /* the seams' vertex arrays first: blocks are welded as they finish */
    for (uint32_t k = 1; k < nx && st == TSR_OK; k++) {
        if (!(vcol[k] = tsr_alloc(a, (size_t)wh * sizeof **vcol)))
            st = TSR_ERR_NOMEM;
        else
            memset(vcol[k], 0xff, (size_t)wh * sizeof **vcol);
    }
    for (uint32_t k = 1; k < ny && st == TSR_OK; k++) {
        if (!(vrow[k] = tsr_alloc(a, (size_t)ww * sizeof **vrow)))
            st = TSR_ERR_NOMEM;
        else
            memset(vrow[k], 0xff, (size_t)ww * sizeof **vrow);
    }
    seams sm = {nx, ny, sx, sy, vcol, vrow};
    j.seams = &sm;
    j.out = mesh;
    j.rep = rep;
    if (st == TSR_OK) {
        pthread_mutex_init(&j.lock, NULL);
        tsr__run_threads(block_worker, &j, o->threads, j.nb);
        pthread_mutex_destroy(&j.lock);
        /* the first failure in block order (welding stops there): the
         * block's own error, or the weld's */
        st = j.weld_st;
        if (st != TSR_OK && err)
            *err = j.weld_err;
        else if (st == TSR_OK && j.next_weld < j.nb) /* a block failed: the first in order */
            for (uint32_t i = 0; i < j.nb; i++)
                if (b[i].finished && b[i].st != TSR_OK) {
                    st = b[i].st;
                    if (err)
                        *err = b[i].err;
                    break;
                }
    } else
        tsr_error_set(err, st, "delaunay mesh: out of memory");
    rep->blocks = j.nb;
    for (uint32_t i = 0; i < j.nb; i++)
        tsr_mesh_free(&b[i].mesh);
    for (uint32_t k = 0; k < nx; k++)
        tsr_free(a, vcol[k]);
    for (uint32_t k = 0; k < ny; k++)
        tsr_free(a, vrow[k]);
    tsr_free(a, sx), tsr_free(a, sy), tsr_free(a, b), tsr_free(a, vcol), tsr_free(a, vrow);
    return st;
}

/* ---- quadtree and grid ------------------------------------------------- */

typedef struct qt_pred {
    double tol;
    bool full_border;
    uint32_t tile_n, levels, ex, ey;
} qt_pred;

static bool qt_refine(void *user, const tsr_surface *s, tsr_qnode n)
{
    const qt_pred *p = user;
    if (p->full_border) {
        uint32_t wdt = (p->tile_n << p->levels) >> n.level;
        uint64_t x0 = (uint64_t)n.x * wdt, y0 = (uint64_t)n.y * wdt, x1 = x0 + wdt, y1 = y0 + wdt;
        if (x0 == 0 || y0 == 0 || x1 >= p->ex || y1 >= p->ey)
            return true;
    }
    return s->error(s->user, n) > p->tol;
}

/* Triangles the cut would have (an upper bound: clipped and no-data
 * triangles drop out of the mesh). */
static uint64_t cut_triangles(const tsr_quadtree *qt, const tsr_tile_patterns *pat)
{
    uint32_t n = tsr_quadtree_leaf_count(qt);
    const tsr_qleaf *l = tsr_quadtree_leaves(qt);
    uint64_t sum = 0;
    for (uint32_t i = 0; i < n; i++)
        sum += pat->count[l[i].stitch & 15];
    return sum;
}

tsr_status tsr__budget_tolerance(double lo, double hi, uint64_t budget,
                                 bool (*count)(void *user, double tol, uint64_t *n), void *user, double *tol,
                                 tsr_error *err)
{
    uint64_t n;
    if (!count(user, hi, &n))
        return tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
    if (n > budget)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "the budget is below the coarsest quadtree mesh (%llu triangles, about %llu vertices)",
                             (unsigned long long)n, (unsigned long long)(n / 2 + 2));
    for (int it = 0; it < 40; it++) {
        double mid = sqrt(lo * hi);
        if (!count(user, mid, &n))
            return tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
        if (n > budget)
            lo = mid;
        else
            hi = mid;
    }
    if (!count(user, hi, &n))
        return tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
    *tol = hi;
    return TSR_OK;
}

typedef struct tile_count {
    tsr_quadtree *qt;
    qt_pred *p;
    const tsr_tile_patterns *pat;
} tile_count;

static bool count_tiles(void *user, double tol, uint64_t *n)
{
    tile_count *c = user;
    c->p->tol = tol;
    if (tsr_quadtree_select(c->qt, qt_refine, c->p) != TSR_OK)
        return false;
    *n = cut_triangles(c->qt, c->pat);
    return true;
}

/* range: the height range in world units (the budget search's top) */
static tsr_status mesh_quadtree_budget(const tsr_heightfield *hf, double tol, double range, uint32_t max_tri,
                                       uint32_t max_vert, const tsr_tin_options *o, tsr_mesh *mesh,
                                       tsr_tin_report *rep, tsr_error *err, int attempt)
{
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    tsr_terrain_options to = {o->tile_n ? o->tile_n : 2};
    tsr_terrain *ter = NULL;
    tsr_status st = tsr_terrain_create(hf, &to, a, &ter, err);
    if (st != TSR_OK)
        return st;
    const tsr_surface *s = tsr_terrain_surface(ter);
    tsr_quadtree *qt = tsr_quadtree_create(s, a);
    tsr_tile_patterns pat;
    bool have_pat = false;
    if (!qt) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
        goto done;
    }
    if (tsr_tile_patterns_init(&pat, s->tile_n, a) != TSR_OK) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
        goto done;
    }
    have_pat = true;
    qt_pred p = {tol, o->full_border, s->tile_n, s->levels, s->extent_x, s->extent_y};
    uint64_t budget = max_tri ? max_tri : UINT64_MAX;
    if (max_vert && attempt == 0) /* about 2 V triangles; V is checked exactly below */
        budget = budget < 2ull * max_vert ? budget : 2ull * max_vert;
    if ((st = tsr_quadtree_select(qt, qt_refine, &p)) != TSR_OK)
        goto done;
    if (budget != UINT64_MAX && cut_triangles(qt, &pat) > budget) {
        /* the finest cut within the budget */
        double lo = tol > 0 ? tol : 1e-9;
        tile_count tc = {qt, &p, &pat};
        if ((st = tsr__budget_tolerance(lo, fmax(range * 2, lo * 2) + 1, budget, count_tiles, &tc, &p.tol, err)) !=
            TSR_OK)
            goto done;
        rep->budget_reached = true;
    }
    rep->target_error = p.tol;
    /* room for the cut at once (growing by doubling copied the mesh about
     * twice over): its triangles, and about half as many vertices */
    uint64_t nt = cut_triangles(qt, &pat);
    if (nt < UINT32_MAX / 2 && tsr_mesh_reserve(mesh, (uint32_t)(nt / 2 + 4096), (uint32_t)nt) != TSR_OK) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
        goto done;
    }
    if ((st = tsr_quadtree_mesh(qt, false, mesh)) != TSR_OK) {
        tsr_error_set(err, st, "quadtree mesh: %s", tsr_status_str(st));
        goto done;
    }
    if (max_vert && mesh->vertex_count > max_vert) {
        /* the vertices a triangle budget gives vary with the mesh's
         * boundary: tighten the triangle budget and bisect again */
        uint32_t nv = mesh->vertex_count;
        mesh->vertex_count = mesh->triangle_count = 0;
        uint64_t tri = (uint64_t)((double)budget * 0.97 * max_vert / nv);
        if (tri < 2 || attempt >= 8) {
            st = tsr_error_set(err, TSR_ERR_ARGUMENT, "the budget is below the coarsest quadtree mesh (%u vertices)", nv);
            goto done;
        }
        tsr_quadtree_destroy(qt);
        qt = NULL;
        tsr_tile_patterns_free(&pat);
        have_pat = false;
        tsr_terrain_destroy(ter);
        return mesh_quadtree_budget(hf, tol, range, max_tri && max_tri < tri ? max_tri : (uint32_t)tri, max_vert, o,
                                    mesh, rep, err, attempt + 1);
    }
done:
    if (have_pat)
        tsr_tile_patterns_free(&pat);
    tsr_quadtree_destroy(qt);
    tsr_terrain_destroy(ter);
    return st;
}



static tsr_status mesh_grid(const tsr_heightfield *hf, uint32_t step, uint32_t max_tri, uint32_t max_vert,
                            tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err)
{
    if (max_tri || max_vert) {
        /* the smallest step within the budget (counts for full cells; cells
         * with no-data only lower them) */
        for (;; step++) {
            uint64_t nc = (hf->width - 1 + step - 1) / step, nr = (hf->height - 1 + step - 1) / step;
            if ((!max_tri || 2 * nc * nr <= max_tri) && (!max_vert || (nc + 1) * (nr + 1) <= max_vert))
                break;
            if (nc == 1 && nr == 1)
                return tsr_error_set(err, TSR_ERR_ARGUMENT,
                                     "the budget is below the coarsest grid (2 triangles, 4 vertices)");
            rep->budget_reached = true;
        }
    }
    rep->target_error = NAN;
    return tsr_terrain_grid_mesh(hf, step, false, mesh, err);
}

/* ---- the entry point --------------------------------------------------- */

tsr_heightfield *tsr_heightfield_crop(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w, uint32_t h,
                                      const tsr_allocator *alloc)
{
    if (w < 2 || h < 2 || x >= hf->width || y >= hf->height || w > hf->width - x || h > hf->height - y)
        return NULL;
    tsr_heightfield *c = tsr_heightfield_create(w, h, alloc);
    if (!c)
        return NULL;
    for (uint32_t r = 0; r < h; r++)
        memcpy(c->data + (size_t)r * w, hf->data + (size_t)(y + r) * hf->width + x, (size_t)w * sizeof(float));
    c->dx = hf->dx;
    c->dy = hf->dy;
    c->dz = hf->dz;
    memcpy(c->source_format, hf->source_format, sizeof c->source_format);
    return c;
}

tsr_status tsr_terrain_mesh(const tsr_heightfield *hf, const tsr_tin_options *opts, tsr_mesh *mesh,
                            tsr_tin_report *report, tsr_error *err)
{
    tsr_tin_options o = opts ? *opts : (tsr_tin_options){0};
    tsr_tin_report rep_local;
    tsr_tin_report *rep = report ? report : &rep_local;
    memset(rep, 0, sizeof *rep);
    if (!(o.max_error >= 0) || !isfinite(o.max_error) || !(o.border_error >= 0) || !isfinite(o.border_error))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: the error bounds must be finite and >= 0");
    if (!(hf->dx > 0) || !(hf->dy > 0) || !(hf->dz > 0))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: the spacing (dx, dy, dz) must be positive");
    if (o.method > TSR_TIN_GRID)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: unknown method %d", (int)o.method);
    if (mesh->vertex_count || mesh->triangle_count)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: the output mesh must be empty");
    if (o.normals && !(mesh->attributes & TSR_MESH_NORMALS))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: normals asked but the mesh was initialised without them");
    bool windowed = o.window_w || o.window_h;
    uint32_t wx = windowed ? o.window_x : 0, wy = windowed ? o.window_y : 0;
    uint32_t ww = windowed ? o.window_w : hf->width, wh = windowed ? o.window_h : hf->height;
    if (ww < 2 || wh < 2 || wx >= hf->width || wy >= hf->height || ww > hf->width - wx || wh > hf->height - wy)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "mesh: window %u,%u,%u,%u is not a rectangle of at least 2x2 samples inside the %ux%u "
                             "heightfield",
                             wx, wy, ww, wh, hf->width, hf->height);
    const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
    const tsr_heightfield *src = hf;
    tsr_heightfield *crop = NULL;
    if (wx || wy || ww != hf->width || wh != hf->height) {
        crop = tsr_heightfield_crop(hf, wx, wy, ww, wh, a);
        if (!crop)
            return tsr_error_set(err, TSR_ERR_NOMEM, "mesh: out of memory for the window");
        src = crop;
    }
    tsr_heightfield_stats hs;
    tsr_heightfield_stats_compute(src, &hs);
    rep->window = hs;
    double range = hs.valid ? (hs.max - hs.min) * hf->dz : 0;
    /* the default bound from the whole heightfield's range, so windows
     * meshed with the same options get the same bound, and so the same
     * border vertices */
    tsr_heightfield_stats whole = hs;
    if (src != hf)
        tsr_heightfield_stats_compute(hf, &whole);
    double wrange = whole.valid ? (whole.max - whole.min) * hf->dz : 0;
    double deflt = wrange > 0 ? wrange * 1e-3 : 1e-3 * hf->dz;
    bool budget = o.max_triangles || o.max_vertices;
    double target = o.max_error > 0 ? o.max_error : budget ? 0 : deflt;
    double btol = o.border_error > 0 ? o.border_error : o.max_error > 0 ? o.max_error : deflt;
    rep->target_error = target;
    rep->bound = target;
    rep->border_error = btol;
    /* vertices are floats: the window's heights and extents must fit */
    double ztop = fmax(fabs(hs.min), fabs(hs.max)) * hf->dz;
    bool ext_ok = (double)(wx + ww - 1) * hf->dx <= FLT_MAX && (double)(wy + wh - 1) * hf->dy <= FLT_MAX;
    tsr_status st;
    if (hs.valid == 0)
        st = tsr_error_set(err, TSR_ERR_VALUE, "mesh: no valid sample in the window");
    else if (!(ztop <= FLT_MAX) || !ext_ok)
        st = tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: %s pass the largest float (%.3g), which mesh vertices are "
                           "written in", ext_ok ? "the heights times dz" : "the extents (columns times dx, rows "
                           "times dy)", FLT_MAX);
    else if (o.method == TSR_TIN_DELAUNAY && o.border_error > 0 && target > 0 && o.border_error > target)
        st = tsr_error_set(err, TSR_ERR_ARGUMENT, "mesh: the border tolerance %g exceeds the bound %g%s: the border "
                           "is part of the mesh", o.border_error, target,
                           o.max_error > 0 ? "" : " (the default, 0.1% of the heightfield's height range)");
    else if (o.method == TSR_TIN_DELAUNAY) {
        /* a hair below the bound, for the float rounding of the output:
         * from the whole heightfield's heights, so that windows meshed with
         * the same options simplify their common border alike (each
         * window's own heights gave tolerances apart: cracks) */
        double margin = 1e-6 * target + 4 * 6e-8 * fmax(fabs(whole.max), fabs(whole.min)) * hf->dz;
        double t = target > margin ? target - margin : 0.5 * target; /* (the same for every window) */
        double b = btol > margin ? btol - margin : 0.5 * btol;
        /* with a bound, the border is fixed first (seams); with a budget
         * alone, it is refined by the greedy pass like the interior */
        bool fixed = target > 0 || o.border_error > 0;
        if (!fixed)
            rep->border_error = 0;
        /* the stats of the whole heightfield (no window) tell whether any
         * block can meet no-data */
        bool clean = src == hf && hs.nodata == 0;
        st = mesh_delaunay_blocks(hf, src, clean, wx, wy, ww, wh, t / hf->dz, b / hf->dz, fixed, &o, mesh, rep,
                                  err);
    } else if (o.method == TSR_TIN_QUADTREE && o.tile_n == 0) {
        double margin = 1e-6 * target + 4 * 6e-8 * fmax(fabs(whole.max), fabs(whole.min)) * hf->dz;
        double t = target > margin ? target - margin : 0.5 * target; /* (the same for every window) */
        st = tsr__rqt_mesh(src, t / hf->dz, hs.max - hs.min, o.full_border, o.max_triangles, o.max_vertices,
                           o.threads, mesh, rep, err);
    } else if (o.method == TSR_TIN_QUADTREE)
        st = mesh_quadtree_budget(src, target, range, o.max_triangles, o.max_vertices, &o, mesh, rep, err, 0);
    else
        st = mesh_grid(src, o.grid_step ? o.grid_step : 1, o.max_triangles, o.max_vertices, mesh, rep, err);
    /* into the whole heightfield's coordinates, with normals from its
     * gradients (the same on both sides of a seam), in place (nothing to
     * do without a window or normals: every method writes a sample's
     * position as this loop would) */
    bool place = crop || mesh->normals;
    for (uint32_t i = 0; place && st == TSR_OK && i < mesh->vertex_count; i++) {
        float *p = mesh->positions + 3 * (size_t)i;
        uint32_t c = (uint32_t)lround(p[0] / hf->dx), r = (uint32_t)lround(p[1] / hf->dy);
        if (c >= ww)
            c = ww - 1;
        if (r >= wh)
            r = wh - 1;
        uint32_t gc = wx + c, gr = wy + r;
        p[0] = (float)(gc * hf->dx);
        p[1] = (float)(gr * hf->dy);
        p[2] = (float)(hf->data[(size_t)gr * hf->width + gc] * hf->dz);
        if (mesh->normals)
            tsr_heightfield_normal_at(hf, gc, gr, mesh->normals + 3 * (size_t)i);
    }
    tsr_heightfield_destroy(crop);
    return st;
}
