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
 * A triangle's samples are found by exact integer edge functions on the
 * lattice (vertices are samples), so the scan never misses or adds one.
 * Errors are in file units inside (h), world units (h dz) outside.
 *
 * quadtree: the restricted quadtree's cut (lod.c's pyramid) with
 * error(node) <= the bound, each leaf a grid tile; grid: every step-th
 * sample (grid.c). */
#include "terrain_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

/* ---- the candidate queue: an indexed 4-ary max-heap over triangle slots
 * (four children share a cache line, halving the depth a pop walks) */

typedef struct hent {
    float key;
    uint32_t slot;
    uint32_t cand; /* the triangle's candidate sample (r * w + c) */
} hent;

typedef struct heap {
    hent *e; /* heap order: only the triangles that have a candidate */
    uint32_t n, cap;
    uint32_t *pos; /* per slot: index in the heap or UINT32_MAX */
    uint32_t nslots, cap_slots;
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

static bool heap_slots(heap *h, const tsr_allocator *a, uint32_t n)
{
    if (n <= h->nslots)
        return true;
    if (!grow_u32(a, (void **)&h->pos, &h->cap_slots, n, sizeof *h->pos))
        return false;
    for (uint32_t i = h->nslots; i < n; i++)
        h->pos[i] = UINT32_MAX;
    h->nslots = n;
    return true;
}

static void heap_up(heap *h, uint32_t i)
{
    hent x = h->e[i];
    while (i > 0) {
        uint32_t p = (i - 1) / 4;
        if (h->e[p].key >= x.key)
            break;
        h->e[i] = h->e[p];
        h->pos[h->e[i].slot] = i;
        i = p;
    }
    h->e[i] = x;
    h->pos[x.slot] = i;
}

static void heap_down(heap *h, uint32_t i)
{
    hent x = h->e[i];
    for (;;) {
        uint32_t l = 4 * i + 1, best = i, end = l + 4 < h->n ? l + 4 : h->n;
        float bk = x.key;
        for (uint32_t k = l; k < end; k++)
            if (h->e[k].key > bk) {
                best = k;
                bk = h->e[k].key;
            }
        if (best == i)
            break;
        h->e[i] = h->e[best];
        h->pos[h->e[i].slot] = i;
        i = best;
    }
    h->e[i] = x;
    h->pos[x.slot] = i;
}

static void heap_remove(heap *h, uint32_t s)
{
    uint32_t i = h->pos[s];
    if (i == UINT32_MAX)
        return;
    h->pos[s] = UINT32_MAX;
    h->n--;
    if (i == h->n)
        return;
    h->e[i] = h->e[h->n];
    h->pos[h->e[i].slot] = i;
    if (i > 0 && h->e[(i - 1) / 4].key < h->e[i].key)
        heap_up(h, i);
    else
        heap_down(h, i);
}

/* Sets slot s's key and candidate; false when out of memory. */
static bool heap_set(heap *h, const tsr_allocator *a, uint32_t s, float k, uint32_t cand)
{
    uint32_t i = h->pos[s];
    if (i == UINT32_MAX) {
        if (h->n == h->cap && !grow_u32(a, (void **)&h->e, &h->cap, h->n + 1, sizeof *h->e))
            return false;
        i = h->n++;
        h->e[i] = (hent){k, s, cand};
        h->pos[s] = i;
        heap_up(h, i);
        return true;
    }
    float old = h->e[i].key;
    h->e[i].key = k;
    h->e[i].cand = cand;
    if (k > old)
        heap_up(h, i);
    else if (k < old)
        heap_down(h, i);
    return true;
}

static void heap_free(heap *h, const tsr_allocator *a)
{
    tsr_free(a, h->e);
    tsr_free(a, h->pos);
}

/* ---- the greedy mesher ------------------------------------------------- */

typedef struct tin {
    const float *data;
    uint32_t w, h;
    const tsr_allocator *a;
    tsr_cdt *cdt;
    heap q;
    /* per vertex id: its column and row */
    uint32_t *vc;
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

/* floor(a / b) for b > 0 and |a| < 2^50: the double quotient, then an
 * exact integer correction (an integer division costs far more). */
static inline int64_t floor_div_fast(int64_t a, int64_t b)
{
    int64_t q = (int64_t)floor((double)a / (double)b);
    while (q * b > a)
        q--;
    while ((q + 1) * b <= a)
        q++;
    return q;
}

/* max over x < n of |rp[x] - (base + ga x)| */
static double row_max(const float *restrict rp, int64_t n, double base, double ga)
{
    double m = -1;
    for (int64_t x = 0; x < n; x++) {
        double e = fabs((double)rp[x] - (base + ga * (double)x));
        m = e > m ? e : m;
    }
    return m;
}

/* The lattice positions and heights of vertices v[3]; false when one is
 * no-data (the triangle is outside the domain). */
static inline bool tri_load(const tin *t, const uint32_t v[3], int64_t c[3], int64_t r[3], double z[3])
{
    for (int k = 0; k < 3; k++) {
        c[k] = t->vc[2 * (size_t)v[k]];
        r[k] = t->vc[2 * (size_t)v[k] + 1];
        z[k] = t->data[(size_t)r[k] * t->w + (size_t)c[k]];
    }
    return !isnan(z[0]) && !isnan(z[1]) && !isnan(z[2]);
}

/* The worst candidate sample of the triangle (c, r, z), counter-clockwise
 * and not degenerate: its error into *best (-1 when the triangle has no
 * candidate), its index into *best_s. Stops early once a row's error
 * exceeds stop (then *best > stop, *best_s may be any sample of it); stop
 * = INFINITY scans it all. */
static void tri_worst(const tin *t, const int64_t c[3], const int64_t r[3], const double z[3], double stop,
                      double *best_out, uint32_t *best_s_out)
{
    int64_t det = (c[1] - c[0]) * (r[2] - r[0]) - (c[2] - c[0]) * (r[1] - r[0]);
    double ga = ((z[1] - z[0]) * (double)(r[2] - r[0]) - (z[2] - z[0]) * (double)(r[1] - r[0])) / (double)det;
    double gb = ((double)(c[1] - c[0]) * (z[2] - z[0]) - (double)(c[2] - c[0]) * (z[1] - z[0])) / (double)det;
    int64_t r0 = r[0] < r[1] ? r[0] : r[1], r1 = r[0] > r[1] ? r[0] : r[1];
    r0 = r[2] < r0 ? r[2] : r0;
    r1 = r[2] > r1 ? r[2] : r1;
    int64_t cmin = c[0] < c[1] ? c[0] : c[1], cmax = c[0] > c[1] ? c[0] : c[1];
    cmin = c[2] < cmin ? c[2] : cmin;
    cmax = c[2] > cmax ? c[2] : cmax;
    /* the outer border is no candidate when fixed */
    if (t->fixed_border) {
        if (r0 < 1)
            r0 = 1;
        if (r1 > (int64_t)t->h - 2)
            r1 = (int64_t)t->h - 2;
        if (cmin < 1)
            cmin = 1;
        if (cmax > (int64_t)t->w - 2)
            cmax = (int64_t)t->w - 2;
    }
    double best = -1;
    uint32_t best_s = UINT32_MAX;
    for (int64_t y = r0; y <= r1 && best <= stop; y++) {
        int64_t lo = cmin, hi = cmax;
        for (int k = 0; k < 3 && lo <= hi; k++) {
            int64_t x0 = c[k], y0 = r[k], x1 = c[(k + 1) % 3], y1 = r[(k + 1) % 3];
            int64_t dy = y1 - y0, num = (x1 - x0) * (y - y0);
            /* inside (left of or on x0->x1): dy (cc - x0) <= num */
            if (dy > 0) {
                int64_t m = x0 + floor_div_fast(num, dy);
                hi = m < hi ? m : hi;
            } else if (dy < 0) {
                int64_t m = x0 - floor_div_fast(num, -dy); /* ceil(num / dy) */
                lo = m > lo ? m : lo;
            } else if (num < 0)
                hi = lo - 1;
        }
        if (lo > hi)
            continue;
        const float *row = t->data + (size_t)y * t->w;
        double base = z[0] + ga * (double)(lo - c[0]) + gb * (double)(y - r[0]);
        if (!t->nodata) {
            /* the row's max first (a branch-free loop the compiler
             * vectorises), then its position only when it beats best */
            const float *rp = row + lo;
            int64_t n = hi - lo + 1;
            double m = row_max(rp, n, base, ga);
            if (m > best) {
                for (int64_t x = 0; x < n; x++)
                    if (fabs((double)rp[x] - (base + ga * (double)x)) == m) {
                        best = m;
                        best_s = (uint32_t)((size_t)y * t->w + (size_t)(lo + x));
                        break;
                    }
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
    *best_out = best;
    *best_s_out = best_s;
}

/* Puts slot s in the queue with error best at sample best_s, or takes it
 * out when it has no candidate. */
static void queue_set(tin *t, uint32_t s, double best, uint32_t best_s)
{
    if (best_s == UINT32_MAX) {
        heap_remove(&t->q, s);
        return;
    }
    float key = (float)best; /* rounded up, so a key at or below the target means the error is */
    if ((double)key < best)
        key = nextafterf(key, INFINITY);
    if (!heap_set(&t->q, t->a, s, key, best_s))
        t->nomem = true;
}

/* Scans the triangle in slot s: its worst candidate sample into the queue,
 * or out of the queue when it has none. */
static void scan(tin *t, uint32_t s)
{
    uint32_t v[3];
    int64_t c[3], r[3];
    double z[3];
    if (!tsr_cdt_triangle(t->cdt, s, v) || !tri_load(t, v, c, r, z)) { /* a ghost, or outside the domain */
        heap_remove(&t->q, s);
        return;
    }
    int64_t det = (c[1] - c[0]) * (r[2] - r[0]) - (c[2] - c[0]) * (r[1] - r[0]);
    if (det <= 0) {
        heap_remove(&t->q, s);
        return;
    }
    double best;
    uint32_t best_s;
    tri_worst(t, c, r, z, INFINITY, &best, &best_s);
    queue_set(t, s, best, best_s);
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
    uint32_t i = s < t->q.nslots ? t->q.pos[s] : UINT32_MAX;
    return i == UINT32_MAX ? 0 : t->q.e[i].key;
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
            c[i] = t->vc[2 * (size_t)id[i]];
            r[i] = t->vc[2 * (size_t)id[i] + 1];
            z[i] = t->data[(size_t)r[i] * t->w + (size_t)c[i]];
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
            uint32_t i = t->q.pos[j ? n : s];
            if (i == UINT32_MAX)
                continue;
            uint32_t smp = t->q.e[i].cand;
            int64_t cc[3] = {c[0], c[3], smp % t->w}, rr[3] = {r[0], r[3], smp / t->w};
            int side = orient(cc, rr, 0, 1, 2) > 0; /* left of p->q: in (0 3 2) */
            double e = fabs(t->data[smp] - plane_at(side ? c2 : c1, side ? r2 : r1, side ? z2 : z1, cc[2], rr[2]));
            lb[side] = fmax(lb[side], excess(e, target));
        }
        if (lb[0] + lb[1] >= cost)
            continue;
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
            uint32_t *p = tsr_realloc(t->a, t->vc, 2 * (size_t)cap * sizeof *p);
            if (!p)
                return UINT32_MAX;
            t->vc = p;
            t->cap_v = cap;
        }
        t->vc[2 * (size_t)id] = smp % t->w;
        t->vc[2 * (size_t)id + 1] = smp / t->w;
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
static inline bool run_crossed(const tin *t, int axis, uint32_t line, uint32_t i)
{
    return axis ? hedge(t, line, i) || hedge(t, (int64_t)line - 1, i) : vedge(t, i, line) || vedge(t, i, (int64_t)line - 1);
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
        cx += t->vc[2 * (size_t)v[k]];
        cy += t->vc[2 * (size_t)v[k] + 1];
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
    tsr_free(t->a, t->vc);
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

static tsr_status mesh_delaunay(const tsr_heightfield *hf, double target, double btol, bool fixed_border,
                                uint32_t max_tri, uint32_t max_vert, const tsr_tin_options *o, tsr_mesh *mesh,
                                tsr_tin_report *rep, tsr_error *err)
{
    tin t = {0};
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
    for (size_t i = 0; i < ns && !t.nodata; i++)
        t.nodata = isnan(t.data[i]);
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
    uint32_t nh = tsr_cdt_handle_count(t.cdt);
    if (!heap_slots(&t.q, t.a, nh))
        goto fail;
    for (uint32_t s = 0; s < nh; s++)
        scan(&t, s);
    if (t.nomem)
        goto fail;
    double first = t.q.n ? t.q.e[0].key : 0;
    uint32_t steps = 0;
    for (;;) {
        if (t.q.n == 0)
            break;
        uint32_t s = t.q.e[0].slot;
        double e = t.q.e[0].key;
        if (e <= target)
            break;
        uint32_t cand = t.q.e[0].cand;
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
            heap_remove(&t.q, s);
            tsr_cdt_clear_changes(t.cdt);
            continue;
        }
        ntri += grow;
        nvert += 1;
        rep->insertions++;
        uint32_t nc;
        const uint32_t *ch = tsr_cdt_changes(t.cdt, &nc);
        if (!heap_slots(&t.q, t.a, tsr_cdt_handle_count(t.cdt)))
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
            scan(&t, cs);
        }
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
                    bool inner = false;
                    for (uint32_t j = 0; j < nseen && !inner; j++)
                        inner = t.seen[j] == nb;
                    if (!inner || v[k] < v[(k + 1) % 3])
                        push_edge(&t, t.seen[i], v[k], v[(k + 1) % 3]);
                }
            }
            /* with a budget alone, the target is unknown: half the worst
             * error so far stands for it */
            flip_pass(&t, target > 0 ? target : 0.5 * (t.q.n ? t.q.e[0].key : 0));
            tsr_cdt_clear_changes(t.cdt);
        }
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
    rep->estimated_error = fmax(t.q.n ? fmax(t.q.e[0].key, 0) : 0, 0) * hf->dz;
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
                    uint32_t smp = t.vc[2 * (size_t)v[k] + 1] * t.w + t.vc[2 * (size_t)v[k]];
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

static tsr_status mesh_quadtree_budget(const tsr_heightfield *hf, double tol, uint32_t max_tri, uint32_t max_vert,
                                       const tsr_tin_options *o, tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err,
                                       int attempt)
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
        /* bisect the tolerance (in log scale) for the finest cut within
         * the budget */
        double lo = tol > 0 ? tol : 1e-9, hi = lo;
        tsr_heightfield_stats hs;
        tsr_heightfield_stats_compute(hf, &hs);
        hi = fmax((hs.max - hs.min) * hf->dz * 2, lo * 2) + 1;
        p.tol = hi;
        if ((st = tsr_quadtree_select(qt, qt_refine, &p)) != TSR_OK)
            goto done;
        if (cut_triangles(qt, &pat) > budget) {
            st = tsr_error_set(err, TSR_ERR_ARGUMENT, "the budget is below the coarsest quadtree mesh (%llu triangles)",
                               (unsigned long long)cut_triangles(qt, &pat));
            goto done;
        }
        for (int it = 0; it < 40; it++) {
            double mid = sqrt(lo * hi);
            p.tol = mid;
            if ((st = tsr_quadtree_select(qt, qt_refine, &p)) != TSR_OK)
                goto done;
            if (cut_triangles(qt, &pat) > budget)
                lo = mid;
            else
                hi = mid;
        }
        p.tol = hi;
        if ((st = tsr_quadtree_select(qt, qt_refine, &p)) != TSR_OK)
            goto done;
        rep->budget_reached = true;
    }
    rep->target_error = p.tol;
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
        return mesh_quadtree_budget(hf, tol, max_tri && max_tri < tri ? max_tri : (uint32_t)tri, max_vert, o, mesh,
                                    rep, err, attempt + 1);
    }
done:
    if (have_pat)
        tsr_tile_patterns_free(&pat);
    tsr_quadtree_destroy(qt);
    tsr_terrain_destroy(ter);
    return st;
}

static tsr_status mesh_quadtree(const tsr_heightfield *hf, double tol, uint32_t max_tri, uint32_t max_vert,
                                const tsr_tin_options *o, tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err)
{
    return mesh_quadtree_budget(hf, tol, max_tri, max_vert, o, mesh, rep, err, 0);
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
                return tsr_error_set(err, TSR_ERR_ARGUMENT, "the budget is below the coarsest grid (2 triangles)");
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
    double range = hs.valid ? (hs.max - hs.min) * hf->dz : 0;
    double deflt = range > 0 ? range * 1e-3 : 1e-3 * hf->dz;
    bool budget = o.max_triangles || o.max_vertices;
    double target = o.max_error > 0 ? o.max_error : budget ? 0 : deflt;
    double btol = o.border_error > 0 ? o.border_error : o.max_error > 0 ? o.max_error : deflt;
    rep->target_error = target;
    rep->border_error = btol;
    tsr_status st;
    if (hs.valid == 0)
        st = tsr_error_set(err, TSR_ERR_VALUE, "mesh: no valid sample in the window");
    else if (o.method == TSR_TIN_DELAUNAY) {
        /* a hair below the bound, for the float rounding of the output */
        double margin = 1e-6 * target + 4 * 6e-8 * fmax(fabs(hs.max), fabs(hs.min)) * hf->dz;
        double t = target > margin ? target - margin : target;
        double b = btol > margin ? btol - margin : btol;
        /* with a bound, the border is fixed first (seams); with a budget
         * alone, it is refined by the greedy pass like the interior */
        bool fixed = target > 0 || o.border_error > 0;
        if (!fixed)
            rep->border_error = 0;
        st = mesh_delaunay(src, t / hf->dz, b / hf->dz, fixed, o.max_triangles, o.max_vertices, &o, mesh, rep,
                           err);
    } else if (o.method == TSR_TIN_QUADTREE)
        st = mesh_quadtree(src, target, o.max_triangles, o.max_vertices, &o, mesh, rep, err);
    else
        st = mesh_grid(src, o.grid_step ? o.grid_step : 1, o.max_triangles, o.max_vertices, mesh, rep, err);
    /* into the whole heightfield's coordinates, with normals from its
     * gradients (the same on both sides of a seam), in place */
    for (uint32_t i = 0; st == TSR_OK && i < mesh->vertex_count; i++) {
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
