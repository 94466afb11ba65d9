/* rqt.c: the quadtree method's default mesh (tessera mesh --method
 * quadtree): a restricted quadtree triangulation with exact errors.
 *
 * The tree is over the cells: a node of level l covers a square of
 * 2^(levels-l) cells a side (clipped at the heightfield's border), the
 * deepest nodes single cells. A leaf is drawn as two triangles split by
 * one of its diagonals, chosen per leaf (a data-dependent choice), or as
 * four from its centre (half a level between two triangles and four
 * children). A side gets its midpoint, which splits the triangle on that
 * side in two, where the neighbour across is finer, or where either leaf
 * asked for it (a leaf that fails as two triangles may ask for the
 * midpoints of one or two sides before it is split: 3 or 4 triangles and
 * one more in each neighbour, against 8 or more; a fan may too, 5 or
 * 6). Edge neighbours differ by at most one level (the restriction), and
 * a leaf asking for a midpoint brings the neighbour of its level into the
 * cut, so the two sides of a shared side always have the same vertices:
 * the mesh is conforming, with no T-junction.
 *
 * The error is exact. A node is kept as a leaf only when every sample of
 * its closed square lies within the tolerance of its triangles, for every
 * set of midpoints it could get (a side has a midpoint or not depending on
 * neighbours decided later): every sample of both halves is measured
 * against the triangles with and without each midpoint, and one beyond
 * the tolerance rejects the diagonal. So no leaf of the final cut, whatever its
 * neighbours, is farther than the tolerance from any of its samples, and
 * the measured max error is within the bound by construction, not by a
 * conservative estimate (lod.c's pyramid bounds a tile's error by sums
 * over levels, which on smooth terrain is several times the true error).
 *
 * Selection is top-down from the root: a node failing the test is split.
 * Splitting a node first splits the parents of its edge neighbours that
 * are coarser (recursively), which keeps the restriction; the children of
 * every split node are tested in turn, so a node split only to keep the
 * restriction still gets exactly tested children. A node with a no-data
 * sample never passes, so no-data is refined to single cells, and a cell
 * with a no-data corner is a hole (as for the other methods).
 *
 * Cost: each half a leaf tries is scanned once, for all four ways its
 * midpoints may split it at once (half_ok: the split triangles are the
 * half's plane plus the midpoints' offsets times their hat functions), a
 * rejected one until every way has a sample beyond the tolerance; a big
 * half is first probed at a few dozen samples, which rejects most failing
 * ones at once (the nodes near the root, and a leaf's other half); 2x2-cell
 * nodes, the most numerous, in closed form. Per node only bits are kept (split,
 * diagonal, fan, midpoints asked for), plus, on several threads, a byte
 * for the verdict judged ahead (select_cut), all in one block (its pages
 * mapped at once, not faulted one by one). */
#include "terrain_internal.h"

#include <math.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>

#define RQT_MAX_LEVELS 21 /* sides up to 2^20 samples */

typedef struct rnode {
    uint32_t x, y, l;
} rnode;

typedef struct vtx {
    int64_t i, j;
    double z;
} vtx;

typedef struct rqt {
    const float *h;
    size_t w; /* row stride */
    int64_t cx, cy;
    uint32_t levels;
    uint32_t nx[RQT_MAX_LEVELS + 1], ny[RQT_MAX_LEVELS + 1];
    uint64_t *split[RQT_MAX_LEVELS], *diag[RQT_MAX_LEVELS], *fan[RQT_MAX_LEVELS];
    uint64_t *vol[4][RQT_MAX_LEVELS]; /* a midpoint the leaf asks for on side k (S, E, N, W) */
    size_t words[RQT_MAX_LEVELS];
    double tol;
    bool full_border;
    rnode *stack;
    size_t sn, scap;
    /* verdicts judged ahead on several threads, a byte per node (0: not
     * judged); NULL on one thread */
    unsigned char *verdicts[RQT_MAX_LEVELS];
    uint32_t threads;
    void *arena; /* the block holding the arrays above */
    uint64_t leaves, fans, mids, vols; /* in the cut: leaves, fans among them, midpoints on their sides */
    const tsr_allocator *a;
    bool nomem;
} rqt;

/* ---- the tree ------------------------------------------------------------ */

static size_t bit_of(const rqt *q, rnode n) { return (size_t)n.y * q->nx[n.l] + n.x; }

static bool get_bit(uint64_t *const *set, const rqt *q, rnode n)
{
    if (n.l >= q->levels)
        return false;
    size_t b = bit_of(q, n);
    return set[n.l][b >> 6] >> (b & 63) & 1;
}

static void put_bit(uint64_t **set, const rqt *q, rnode n, bool v)
{
    size_t b = bit_of(q, n);
    if (v)
        set[n.l][b >> 6] |= (uint64_t)1 << (b & 63);
    else
        set[n.l][b >> 6] &= ~((uint64_t)1 << (b & 63));
}

static bool is_split(const rqt *q, rnode n) { return get_bit(q->split, q, n); }

static bool exists(const rqt *q, rnode n) { return n.x < q->nx[n.l] && n.y < q->ny[n.l]; }

/* The node of n's level across side k (S, E, N, W), and whether it
 * exists. */
static bool neighbour(const rqt *q, rnode n, int k, rnode *nb)
{
    static const int ox[4] = {0, 1, 0, -1}, oy[4] = {-1, 0, 1, 0};
    if ((ox[k] < 0 && n.x == 0) || (oy[k] < 0 && n.y == 0))
        return false;
    *nb = (rnode){n.x + (uint32_t)ox[k], n.y + (uint32_t)oy[k], n.l};
    return exists(q, *nb);
}

static void push(rqt *q, rnode n)
{
    if (q->sn == q->scap) {
        size_t cap = q->scap ? 2 * q->scap : 256;
        rnode *s = tsr_realloc(q->a, q->stack, cap * sizeof *s);
        if (!s) {
            q->nomem = true;
            return;
        }
        q->stack = s;
        q->scap = cap;
    }
    q->stack[q->sn++] = n;
}

/* Splits n, after the coarser parents of its edge neighbours (so that
 * its children will differ from their neighbours by one level at most),
 * and queues its children for the test. */
static void split(rqt *q, rnode n)
{
    if (is_split(q, n))
        return;
    rnode nb;
    if (n.l > 0)
        for (int k = 0; k < 4; k++) {
            if (!neighbour(q, n, k, &nb))
                continue;
            rnode p = {nb.x >> 1, nb.y >> 1, n.l - 1};
            if (!is_split(q, p))
                split(q, p);
        }
    /* the counts: n is a leaf no more; each neighbour of its level that
     * is a leaf gets a midpoint toward it, and n's own midpoints toward
     * split neighbours go */
    if (n.l > 0)
        for (int k = 0; k < 4; k++)
            if (neighbour(q, n, k, &nb))
                q->mids += is_split(q, nb) ? -1 : 1;
    if (get_bit(q->fan, q, n))
        q->fans--;
    put_bit(q->split, q, n, true);
    q->leaves--;
    for (uint32_t k = 0; k < 4; k++) {
        rnode c = {2 * n.x + (k & 1), 2 * n.y + (k >> 1), n.l + 1};
        if (exists(q, c)) {
            push(q, c);
            q->leaves++;
        }
    }
}

/* A node's square, clipped, and which sides could get a midpoint (a
 * neighbour exists across the side, and the midpoint falls inside it). */
typedef struct box {
    int64_t x0, y0, x1, y1, xm, ym;
    bool ms, me, mn, mw;
} box;

static box node_box(const rqt *q, rnode n)
{
    box b;
    int64_t s = (int64_t)1 << (q->levels - n.l);
    b.x0 = (int64_t)n.x * s;
    b.y0 = (int64_t)n.y * s;
    b.x1 = b.x0 + s < q->cx ? b.x0 + s : q->cx;
    b.y1 = b.y0 + s < q->cy ? b.y0 + s : q->cy;
    b.xm = b.x0 + s / 2;
    b.ym = b.y0 + s / 2;
    bool wide = s >= 2;
    b.ms = wide && b.y0 > 0 && b.xm < b.x1;
    b.mn = wide && b.y0 + s < q->cy && b.xm < b.x1;
    b.mw = wide && b.x0 > 0 && b.ym < b.y1;
    b.me = wide && b.x0 + s < q->cx && b.ym < b.y1;
    return b;
}

static vtx at(const rqt *q, int64_t i, int64_t j) { return (vtx){i, j, q->h[(size_t)j * q->w + (size_t)i]}; }

/* ---- the exact test -------------------------------------------------- */

static int64_t floor_div(int64_t a, int64_t b) /* b > 0 */
{
    return a >= 0 ? a / b : -((-a + b - 1) / b);
}

/* The gradient (dz/di, dz/dj) of the plane through a, b and c. */
static void gradient(vtx a, vtx b, vtx c, double *gx, double *gy)
{
    double det = (double)((b.i - a.i) * (c.j - a.j) - (c.i - a.i) * (b.j - a.j));
    *gx = ((b.z - a.z) * (double)(c.j - a.j) - (c.z - a.z) * (double)(b.j - a.j)) / det;
    *gy = ((double)(b.i - a.i) * (c.z - a.z) - (double)(c.i - a.i) * (b.z - a.z)) / det;
}

/* A half and its variants. A leaf's half (a, b, c), counter-clockwise,
 * may get a midpoint p on its side ab and m on bc (where its neighbours
 * will be finer, or where a leaf asks for them), so it is drawn in one of
 * four ways: abc itself (variant 0), split at p into (a, p, c), (p, b, c)
 * (variant 1), split at m into (a, b, m), (a, m, c) (variant 2), or at
 * both into (a, p, c), (p, b, m), (p, m, c) (variant 3). Each is abc's
 * plane L plus the midpoints' offsets from it times their hat functions,
 * which are piecewise linear in the barycentric coordinates (la, lb, lc)
 * of abc: with p = a + t (b - a) and m = b + s (c - b),
 *   variant 1: L + op * min(lb / t, la / (1 - t))
 *   variant 2: L + om * min(lc / s, lb / (1 - s))
 *   variant 3: L + op * min(lb / t, la / (1 - t))
 *                + om * max(0, min(lc / s, (lb - t la / (1 - t)) / (1 - s)))
 * (the hat of m in (p, b, m), (p, m, c), zero in (a, p, c)). One scan of
 * abc's samples gives all four largest distances, where the triangles of
 * each variant took a scan of their own. The barycentric coordinates are
 * kept as their numerators (integers, exact in doubles: the 2x the areas
 * of the sub-triangles with the sample), variant 0 is the same expression
 * as the measurement's (base + gx i), and the others differ from a scan
 * of their own triangles' planes by roundings only.
 *
 * A scan stops at the first row after which every variant has a sample
 * beyond the tolerance, or at a no-data sample (NaN), where none passes. */
enum { V_NONE = 1, V_P = 2, V_M = 4, V_PM = 8 };

/* The parameter of p on the segment from a to b (an axis-parallel side). */
static double edge_param(vtx a, vtx b, vtx p)
{
    return b.i != a.i ? (double)(p.i - a.i) / (double)(b.i - a.i) : (double)(p.j - a.j) / (double)(b.j - a.j);
}

/* One half's coefficients: the plane, the hats' factors (0 where the
 * midpoint is absent) and the midpoints' offsets. */
typedef struct half_k {
    double gx, gy, kpa, kpb, op, kmc, kmb, kab, om;
} half_k;

#ifdef TSR_VECTORS
/* lane-wise max and min of a and b (neither NaN), and |a| */
#define V4_SEL(m, a, b) ((tsr_v4d)(((tsr_v4l)(a) & (m)) | ((tsr_v4l)(b) & ~(m))))
#define V4_MAX(a, b) V4_SEL((a) > (b), a, b)
#define V4_MIN(a, b) V4_SEL((a) < (b), a, b)
#define V4_ABS(a) ((tsr_v4d)((tsr_v4l)(a) & (tsr_v4l){INT64_MAX, INT64_MAX, INT64_MAX, INT64_MAX}))
#endif

/* The distances of sample x of a row from the four variants, into the
 * running maxima mx (the scalar form of the vector loop below, with the
 * same operations in the same order). */
static TSR_ALWAYS_INLINE void sample_err(const half_k *k, double h, double base, double x, double na, double nb,
                                         double nc, double mx[4], bool *nan)
{
    double px = k->gx * x;
    double r = h - (base + px);
    double u = nb * k->kpb, v = na * k->kpa, phi = u < v ? u : v;
    double w = nc * k->kmc, y = nb * k->kmb, psi = w < y ? w : y;
    double z = y - na * k->kab, psi2 = w < z ? w : z;
    psi2 = psi2 > 0 ? psi2 : 0;
    double t1 = r - k->op * phi;
    double e[4] = {fabs(r), fabs(t1), fabs(r - k->om * psi), fabs(t1 - k->om * psi2)};
    *nan |= r != r;
    for (int v4 = 0; v4 < 4; v4++)
        mx[v4] = e[v4] > mx[v4] ? e[v4] : mx[v4];
}

/* Row j's start at column lo: the plane's base (its value minus gx i)
 * and the barycentric numerators (exact integers) at (lo, j). The probe
 * and the full scan take the same values from here. */
typedef struct row_start {
    double base, na, nb, nc;
} row_start;

static TSR_ALWAYS_INLINE row_start row_at(const half_k *k, vtx a, vtx b, vtx c, int64_t j, int64_t lo)
{
    return (row_start){a.z + k->gy * (double)(j - a.j) - k->gx * (double)a.i,
                       (double)((c.i - b.i) * (j - b.j) - (c.j - b.j) * (lo - b.i)),
                       (double)((a.i - c.i) * (j - c.j) - (a.j - c.j) * (lo - c.i)),
                       (double)((b.i - a.i) * (j - a.j) - (b.j - a.j) * (lo - a.i))};
}

/* The variants among want whose largest distances mx are within tol. */
static unsigned within(unsigned want, const double mx[4], double tol)
{
    return want & ((mx[0] <= tol ? V_NONE : 0) | (mx[1] <= tol ? V_P : 0) | (mx[2] <= tol ? V_M : 0) |
                   (mx[3] <= tol ? V_PM : 0));
}

/* A half is probed (half_probe) when its box is at least PROBE_MIN
 * cells on both sides, at about PROBE_STEPS x PROBE_STEPS samples;
 * PROBED marks a memo holding a probe's answer (memo_probe). */
enum { PROBE_MIN = 32, PROBE_STEPS = 6, PROBED = 16 };

/* The variants of half (a, b, c) within the tolerance, among those in
 * mask: a set of V_* bits, V_P and V_PM only with p, V_M and V_PM only
 * with m. With probe, only a lattice of about PROBE_STEPS x PROBE_STEPS
 * of the half's samples is measured (the same expression on the same
 * samples as the full scan's), so the answer holds every variant the full
 * scan would find within the tolerance, and maybe more: a variant it
 * rejects, the full scan rejects too. */
static TSR_ALWAYS_INLINE unsigned half_ok_body(const rqt *q, vtx a, vtx b, vtx c, const vtx *p, const vtx *m,
                                               unsigned mask, bool probe)
{
    half_k k = {0};
    gradient(a, b, c, &k.gx, &k.gy);
    if (!isfinite(k.gx) || !isfinite(k.gy) || !isfinite(a.z))
        return 0;
    double det = (double)((b.i - a.i) * (c.j - a.j) - (c.i - a.i) * (b.j - a.j));
    unsigned want = V_NONE;
    double t = 0;
    if (p) {
        t = edge_param(a, b, *p);
        k.kpa = 1 / ((1 - t) * det);
        k.kpb = 1 / (t * det);
        k.op = p->z - ((1 - t) * a.z + t * b.z);
        if (isfinite(k.op))
            want |= V_P;
        else
            k.op = 0; /* (no-data: the variants with p fail) */
    }
    if (m) {
        double s = edge_param(b, c, *m);
        k.kmc = 1 / (s * det);
        k.kmb = 1 / ((1 - s) * det);
        k.om = m->z - ((1 - s) * b.z + s * c.z);
        if (isfinite(k.om)) {
            want |= V_M;
            if (want & V_P)
                want |= V_PM;
        } else
            k.om = 0;
        if (p)
            k.kab = t / ((1 - t) * (1 - s) * det);
    }
    want &= mask;
    int64_t j0 = a.j < b.j ? a.j : b.j, j1 = a.j > b.j ? a.j : b.j;
    j0 = c.j < j0 ? c.j : j0;
    j1 = c.j > j1 ? c.j : j1;
    int64_t imin = a.i < b.i ? a.i : b.i, imax = a.i > b.i ? a.i : b.i;
    imin = c.i < imin ? c.i : imin;
    imax = c.i > imax ? c.i : imax;
    /* the numerators' steps in i (below) */
    int64_t dna = -(c.j - b.j), dnb = -(a.j - c.j), dnc = -(b.j - a.j);
    const vtx *e[3][2] = {{&a, &b}, {&b, &c}, {&c, &a}};
    if (probe) {
        /* rows and columns a PROBE_STEPS-th of the box apart, from half
         * a step in; a row's span from each sloped edge's column there,
         * as the scan's stepping gives it */
        double mx[4] = {0, 0, 0, 0};
        bool nan = false;
        int64_t sj = (j1 - j0) / PROBE_STEPS, si = (imax - imin) / PROBE_STEPS;
        sj = sj > 1 ? sj : 1, si = si > 1 ? si : 1;
        for (int64_t j = j0 + sj / 2; j <= j1; j += sj) {
            int64_t lo = imin, hi = imax;
            for (int n = 0; n < 3; n++) {
                const vtx *u = e[n][0], *v = e[n][1];
                int64_t dx = v->i - u->i, dy = v->j - u->j;
                if (dy > 0) {
                    int64_t col = u->i + floor_div(dx * (j - u->j), dy);
                    hi = col < hi ? col : hi;
                } else if (dy < 0) {
                    int64_t col = u->i - floor_div(dx * (j - u->j), -dy);
                    lo = col > lo ? col : lo;
                } else if (dx * (j - u->j) < 0)
                    hi = lo - 1;
            }
            const float *row = q->h + (size_t)j * q->w;
            row_start r0 = row_at(&k, a, b, c, j, lo);
            double base = r0.base, na0 = r0.na, nb0 = r0.nb, nc0 = r0.nc;
            for (int64_t x = si / 2; lo + x <= hi; x += si)
                sample_err(&k, row[lo + x], base, (double)(lo + x), na0 + (double)dna * (double)x,
                           nb0 + (double)dnb * (double)x, nc0 + (double)dnc * (double)x, mx, &nan);
        }
        return nan ? 0 : within(want, mx, q->tol);
    }
    /* each sloped edge's column at row j: p.i + F(j) bounding the row
     * from above (dy > 0) or p.i - F(j) from below (dy < 0), with F(j) =
     * floor(dx (j - p.j) / |dy|), stepped from row to row as a quotient
     * and remainder (no division per row) */
    int64_t col[3], quo[3], rem[3], den[3] = {1, 1, 1}, step_q[3] = {0, 0, 0}, step_r[3] = {0, 0, 0};
    int sign[3];
    for (int n = 0; n < 3; n++) {
        const vtx *u = e[n][0], *v = e[n][1];
        int64_t dx = v->i - u->i, dy = v->j - u->j;
        sign[n] = dy > 0 ? 1 : dy < 0 ? -1 : 0;
        col[n] = u->i;
        if (!dy) { /* a horizontal edge: rows on its outer side are empty */
            quo[n] = dx;
            rem[n] = u->j;
            continue;
        }
        den[n] = dy > 0 ? dy : -dy;
        if (dx == 0 || dx == den[n] || dx == -den[n]) {
            /* upright or at 45 degrees, as every edge of an unclipped
             * node's triangles: whole columns a row, no division */
            step_q[n] = dx == 0 ? 0 : dx > 0 ? 1 : -1;
            quo[n] = step_q[n] * (j0 - u->j);
            rem[n] = 0;
            continue;
        }
        int64_t num = dx * (j0 - u->j);
        quo[n] = floor_div(num, den[n]);
        rem[n] = num - quo[n] * den[n];
        step_q[n] = floor_div(dx, den[n]);
        step_r[n] = dx - step_q[n] * den[n];
    }
    double tol = q->tol, mx[4] = {0, 0, 0, 0};
    bool nan = false;
#ifdef TSR_VECTORS
    /* the vector rows' running maxima, folded into mx every few rows */
    tsr_v4d m0 = {0, 0, 0, 0}, m1 = m0, m2 = m0, m3 = m0;
    tsr_v4l bad = {0, 0, 0, 0};
#endif
    /* the numerators of (la, lb, lc) at (i, j): (c - b) x (s - b),
     * (a - c) x (s - c), (b - a) x (s - a); each steps by -(dj) in i
     * (dna, dnb, dnc above) */
    for (int64_t j = j0; j <= j1; j++) {
        int64_t lo = imin, hi = imax;
        for (int n = 0; n < 3; n++) {
            if (sign[n] > 0) {
                int64_t v = col[n] + quo[n];
                hi = v < hi ? v : hi;
            } else if (sign[n] < 0) {
                int64_t v = col[n] - quo[n];
                lo = v > lo ? v : lo;
            } else {
                if (quo[n] * (j - rem[n]) < 0)
                    hi = lo - 1;
                continue;
            }
            quo[n] += step_q[n];
            rem[n] += step_r[n];
            if (rem[n] >= den[n]) {
                rem[n] -= den[n];
                quo[n]++;
            }
        }
        if (lo <= hi) {
            const float *row = q->h + (size_t)j * q->w;
            row_start r0 = row_at(&k, a, b, c, j, lo);
            double base = r0.base, na0 = r0.na, nb0 = r0.nb, nc0 = r0.nc;
            int64_t n = hi - lo + 1;
#ifdef TSR_VECTORS
            if (n >= 4) {
                const tsr_v4d lane = {0, 1, 2, 3}, zero = {0, 0, 0, 0};
                for (int64_t x = 0;; x += 4) {
                    if (x + 4 > n)
                        x = n - 4; /* (the last four overlap the ones before) */
                    tsr_v4f f;
                    memcpy(&f, row + lo + x, sizeof f);
                    tsr_v4d xs = (double)x + lane;
                    tsr_v4d px = k.gx * ((double)(lo + x) + lane);
                    tsr_v4d r = __builtin_convertvector(f, tsr_v4d) - (base + px);
                    tsr_v4d na = na0 + (double)dna * xs, nb = nb0 + (double)dnb * xs, nc = nc0 + (double)dnc * xs;
                    tsr_v4d u = nb * k.kpb, v = na * k.kpa, phi = V4_MIN(u, v);
                    tsr_v4d w = nc * k.kmc, y = nb * k.kmb, psi = V4_MIN(w, y);
                    tsr_v4d z = y - na * k.kab, psi2 = V4_MIN(w, z);
                    psi2 = V4_MAX(psi2, zero);
                    tsr_v4d t1 = r - k.op * phi;
                    tsr_v4d e0 = V4_ABS(r), e1 = V4_ABS(t1), e2 = V4_ABS(r - k.om * psi),
                            e3 = V4_ABS(t1 - k.om * psi2);
                    bad |= r != r;
                    m0 = V4_MAX(e0, m0);
                    m1 = V4_MAX(e1, m1);
                    m2 = V4_MAX(e2, m2);
                    m3 = V4_MAX(e3, m3);
                    if (x + 4 >= n)
                        break;
                }
            } else
#endif
                for (int64_t x = 0; x < n; x++)
                    sample_err(&k, row[lo + x], base, (double)(lo + x), na0 + (double)dna * (double)x,
                               nb0 + (double)dnb * (double)x, nc0 + (double)dnc * (double)x, mx, &nan);
        }
        if ((j - j0) % 4 != 3 && j != j1)
            continue;
        /* every fourth row and the last: a no-data sample fails every
         * variant, and so does a scan after which none is left */
#ifdef TSR_VECTORS
        nan |= (bad[0] | bad[1] | bad[2] | bad[3]) != 0;
        const tsr_v4d *mv[4] = {&m0, &m1, &m2, &m3};
        for (int v4 = 0; v4 < 4; v4++) {
            const tsr_v4d *mm = mv[v4];
            double s01 = (*mm)[0] > (*mm)[1] ? (*mm)[0] : (*mm)[1], s23 = (*mm)[2] > (*mm)[3] ? (*mm)[2] : (*mm)[3];
            double sv = s01 > s23 ? s01 : s23;
            mx[v4] = sv > mx[v4] ? sv : mx[v4];
        }
#endif
        if (nan)
            return 0;
        unsigned alive = within(want, mx, tol);
        if (!alive || j == j1)
            return alive;
    }
    return 0; /* (no row: not reached for a triangle) */
}

#ifdef TSR_AVX2_DISPATCH
__attribute__((target("avx2"))) static unsigned half_ok_avx2(const rqt *q, vtx a, vtx b, vtx c, const vtx *p,
                                                             const vtx *m, unsigned mask)
{
    return half_ok_body(q, a, b, c, p, m, mask, false);
}
#endif

static unsigned half_ok(const rqt *q, vtx a, vtx b, vtx c, const vtx *p, const vtx *m, unsigned mask)
{
#ifdef TSR_AVX2_DISPATCH
    if (__builtin_cpu_supports("avx2"))
        return half_ok_avx2(q, a, b, c, p, m, mask);
#endif
    return half_ok_body(q, a, b, c, p, m, mask, false);
}

/* The probe of a half (half_ok_body's probe; scalar: few samples) or,
 * for a half too small to be worth one, the full scan; either way a set
 * of variants holding those within the tolerance. */
static unsigned half_probe(const rqt *q, vtx a, vtx b, vtx c, const vtx *p, const vtx *m)
{
    int64_t imin = a.i < b.i ? a.i : b.i, imax = a.i > b.i ? a.i : b.i;
    int64_t jmin = a.j < b.j ? a.j : b.j, jmax = a.j > b.j ? a.j : b.j;
    imin = c.i < imin ? c.i : imin, imax = c.i > imax ? c.i : imax;
    jmin = c.j < jmin ? c.j : jmin, jmax = c.j > jmax ? c.j : jmax;
    if (imax - imin < PROBE_MIN || jmax - jmin < PROBE_MIN)
        return half_ok(q, a, b, c, p, m, 15);
    return PROBED | half_ok_body(q, a, b, c, p, m, 15, true);
}

/* A half's memo (a signed char): -1 nothing known yet; else its variants
 * within the tolerance or, with PROBED, the probe's set holding them (the
 * full scan still to come). The probes of a leaf's halves come before
 * any full scan, so a half the probe rejects spares the others' scans. */
static unsigned memo_probe(const rqt *q, signed char *r, vtx a, vtx b, vtx c, const vtx *p, const vtx *m)
{
    if (*r < 0)
        *r = (signed char)half_probe(q, a, b, c, p, m);
    return (unsigned)*r & 15;
}

static unsigned memo_full(const rqt *q, signed char *r, vtx a, vtx b, vtx c, const vtx *p, const vtx *m)
{
    if (*r < 0 || *r & PROBED)
        *r = (signed char)half_ok(q, a, b, c, p, m, *r < 0 ? 15 : (unsigned)*r & 15);
    return (unsigned)*r;
}

static unsigned half_hook(const tsr_heightfield *hf, double tol, const int64_t v[3][2], const int64_t *p,
                          const int64_t *m, bool probe)
{
    rqt q = {.h = hf->data, .w = hf->width, .cx = (int64_t)hf->width - 1, .cy = (int64_t)hf->height - 1, .tol = tol};
    vtx t[3], pv, mv;
    for (int k = 0; k < 3; k++)
        t[k] = at(&q, v[k][0], v[k][1]);
    if (p)
        pv = at(&q, p[0], p[1]);
    if (m)
        mv = at(&q, m[0], m[1]);
    return probe ? half_probe(&q, t[0], t[1], t[2], p ? &pv : NULL, m ? &mv : NULL) & 15
                 : half_ok(&q, t[0], t[1], t[2], p ? &pv : NULL, m ? &mv : NULL, 15);
}

unsigned tsr__rqt_half_variants(const tsr_heightfield *hf, double tol, const int64_t v[3][2], const int64_t *p,
                                const int64_t *m)
{
    return half_hook(hf, tol, v, p, m, false);
}

unsigned tsr__rqt_half_probe(const tsr_heightfield *hf, double tol, const int64_t v[3][2], const int64_t *p,
                             const int64_t *m)
{
    return half_hook(hf, tol, v, p, m, true);
}

/* From a half's variants within the tolerance (ok), whether it passes
 * with any midpoints that may come (hp: p may, hm: m may), those asked
 * for always there (np, nm). */
static bool half_passes(unsigned ok, bool hp, bool hm, bool np, bool nm)
{
    if (np && nm)
        return ok & V_PM;
    if (np)
        return (ok & V_P) && (!hm || (ok & V_PM));
    if (nm)
        return (ok & V_M) && (!hp || (ok & V_PM));
    return (ok & V_NONE) && (!hp || (ok & V_P)) && (!hm || (ok & V_M)) && (!(hp && hm) || (ok & V_PM));
}

/* The corners and midpoints of a box. */
typedef struct corners {
    vtx sw, se, ne, nw, s, e, n, w;
} corners;

static corners corners_of(const rqt *q, const box *b)
{
    corners c;
    c.sw = at(q, b->x0, b->y0);
    c.se = at(q, b->x1, b->y0);
    c.ne = at(q, b->x1, b->y1);
    c.nw = at(q, b->x0, b->y1);
    c.s = b->ms ? at(q, b->xm, b->y0) : c.sw;
    c.e = b->me ? at(q, b->x1, b->ym) : c.se;
    c.n = b->mn ? at(q, b->xm, b->y1) : c.nw;
    c.w = b->mw ? at(q, b->x0, b->ym) : c.sw;
    return c;
}

/* The halves of diagonal d (0: from south-west to north-east, 1: from
 * south-east to north-west): (a, b, c) with the midpoints p of ab and m
 * of bc where they may come, and the bits of their sides (S 1, E 2, N 4,
 * W 8) in a set of midpoints asked for. */
typedef struct halves {
    const vtx *v[2][3], *p[2], *m[2];
    unsigned char pbit[2], mbit[2];
} halves;

static halves diag_halves(const box *b, const corners *c, int d)
{
    const vtx *s = b->ms ? &c->s : NULL, *e = b->me ? &c->e : NULL, *n = b->mn ? &c->n : NULL,
              *w = b->mw ? &c->w : NULL;
    if (d == 0)
        return (halves){{{&c->sw, &c->se, &c->ne}, {&c->ne, &c->nw, &c->sw}}, {s, n}, {e, w}, {1, 4}, {2, 8}};
    return (halves){{{&c->se, &c->ne, &c->nw}, {&c->nw, &c->sw, &c->se}}, {e, w}, {n, s}, {2, 8}, {4, 1}};
}

/* Whether half h of hv passes with the variants ok (any midpoints, those
 * in need always there). */
static bool halves_pass(const halves *hv, int h, unsigned ok, unsigned need)
{
    return half_passes(ok, hv->p[h] != NULL, hv->m[h] != NULL, need & hv->pbit[h], need & hv->mbit[h]);
}

/* Half h's variants (full: memo_full) or the probe's set (memo_probe). */
static unsigned diag_half(const rqt *q, const halves *hv, int h, signed char *r, bool full)
{
    return full ? memo_full(q, r, *hv->v[h][0], *hv->v[h][1], *hv->v[h][2], hv->p[h], hv->m[h])
                : memo_probe(q, r, *hv->v[h][0], *hv->v[h][1], *hv->v[h][2], hv->p[h], hv->m[h]);
}

/* Whether the two triangles of a diagonal's halves hv are within the
 * tolerance with any midpoints, those of the sides in need always there.
 * Each half's variants are kept in memo (memo_probe), as the sets of
 * midpoints share halves; with probe, both halves are probed before
 * either is scanned in full. */
static bool diag_ok_v(const rqt *q, const halves *hv, unsigned need, signed char memo[2], bool probe)
{
    if (probe)
        for (int h = 0; h < 2; h++)
            if (!halves_pass(hv, h, diag_half(q, hv, h, &memo[h], false), need))
                return false;
    for (int h = 0; h < 2; h++)
        if (!halves_pass(hv, h, diag_half(q, hv, h, &memo[h], true), need))
            return false;
    return true;
}

/* The fan from the centre c: a triangle (a, b, c) per side, split at the
 * side's midpoint m in (a, m, c), (m, b, c) where one may come; each
 * side's variants are kept (-1: not scanned yet), as fan_ok and fan_need
 * ask the same. */
typedef struct fan {
    const vtx *ring[4][3]; /* a, b, m (NULL: no midpoint can come) */
    vtx c;
    signed char ok[4];
} fan;

static fan fan_of(const box *b, const corners *k, vtx c)
{
    fan f = {{{&k->sw, &k->se, b->ms ? &k->s : NULL},
              {&k->se, &k->ne, b->me ? &k->e : NULL},
              {&k->ne, &k->nw, b->mn ? &k->n : NULL},
              {&k->nw, &k->sw, b->mw ? &k->w : NULL}},
             c,
             {-1, -1, -1, -1}};
    return f;
}

/* Side i's triangle's variants (V_NONE, and V_P split at its midpoint):
 * all of them (full) or a set holding them (the probe's). */
static unsigned fan_variants(const rqt *q, fan *f, int i, bool full)
{
    return full ? memo_full(q, &f->ok[i], *f->ring[i][0], *f->ring[i][1], f->c, f->ring[i][2], NULL)
                : memo_probe(q, &f->ok[i], *f->ring[i][0], *f->ring[i][1], f->c, f->ring[i][2], NULL);
}

/* Whether side i's triangle is within the tolerance with or without its
 * midpoint (or may be, from the probe). */
static bool fan_side(const rqt *q, fan *f, int i, bool full)
{
    return half_passes(fan_variants(q, f, i, full), f->ring[i][2] != NULL, false, false, false);
}

static bool fan_ok(const rqt *q, fan *f, bool probe)
{
    for (int full = !probe; full < 2; full++)
        for (int i = 0; i < 4; i++)
            if (!fan_side(q, f, i, full))
                return false;
    return true;
}

/* The sides' midpoints fan_need would ask for, from the variants (full)
 * or the probes' sets: 0 when there is no such set. From the probes, a
 * side failing is failing in full too, and a side that cannot pass split
 * cannot in full either, so 0 there is 0 in full. */
static unsigned fan_need_of(const rqt *q, fan *f, bool full)
{
    unsigned need = 0;
    for (int i = 0; i < 4; i++)
        if (!fan_side(q, f, i, full)) {
            if (!f->ring[i][2] || __builtin_popcount(need) == 2 || !(fan_variants(q, f, i, full) & V_P))
                return 0;
            need |= 1u << i;
        }
    return need;
}

/* The fan with the midpoints of one or two sides always there (the leaf
 * asks for them): the sides whose triangle fails without its midpoint,
 * when they can have one, are no more than two, and pass split at it; 0
 * when there is no such set. Called after fan_ok failed. */
static unsigned fan_need(const rqt *q, fan *f, bool probe)
{
    return !probe || fan_need_of(q, f, false) ? fan_need_of(q, f, true) : 0;
}

/* n asks for the midpoints of the sides in need: the node of its level
 * across each must be in the cut (split its coarser parent if not). */
static void accept_vol(rqt *q, rnode n, unsigned need)
{
    rnode nb;
    for (int k = 0; k < 4; k++)
        if (need >> k & 1 && neighbour(q, n, k, &nb)) { /* (a side in need always has one) */
            put_bit(q->vol[k], q, n, true);
            q->vols += 2;
            rnode p = {nb.x >> 1, nb.y >> 1, n.l - 1};
            if (!is_split(q, p))
                split(q, p);
        }
}

/* Whether n may be a leaf, and how it is drawn (diagonal, fan, midpoints
 * asked for): a function of the node alone (its square, the heightfield
 * and the tolerance) that reads nothing of the tree, so a batch of nodes
 * can be judged on several threads and the verdicts applied in order. */
typedef struct verdict {
    unsigned char ok, diag, fan, need;
} verdict;

static verdict judge(const rqt *q, rnode n)
{
    const verdict no = {0, 0, 0, 0};
    if (n.l == q->levels)
        return (verdict){1, 0, 0, 0};
    box b = node_box(q, n);
    if (q->full_border && (b.x0 == 0 || b.y0 == 0 || b.x1 == q->cx || b.y1 == q->cy))
        return no;
    if (n.l + 1 == q->levels && b.x1 - b.x0 == 2 && b.y1 - b.y0 == 2) {
        /* (2 x 2 cells unclipped: a bigger node clipped to 2 x 2 has its
         * centre elsewhere and takes the general test) */
        /* the most common test, in closed form: every sample of the node
         * is a vertex or the middle of a side or of the diagonal, where a
         * midpoint's triangles interpolate as the halves do */
        const float *r0 = q->h + (size_t)b.y0 * q->w + b.x0, *r1 = r0 + q->w, *r2 = r1 + q->w;
        double sw = r0[0], se = r0[2], nw = r2[0], ne = r2[2], cc = r1[1], tol = q->tol;
        double d0 = fabs(cc - 0.5 * (sw + ne)), d1 = fabs(cc - 0.5 * (se + nw));
        if (isnan(sw + se + nw + ne + cc + r0[1] + r2[1] + r1[0] + r1[2]))
            return no;
        /* a side's middle sample beyond the tolerance: the leaf asks for
         * that midpoint (one or two sides, where a neighbour can share
         * it), which makes the sample a vertex */
        unsigned need = (fabs(r0[1] - 0.5 * (sw + se)) > tol ? 1u : 0) | (fabs(r1[2] - 0.5 * (se + ne)) > tol ? 2u : 0) |
                        (fabs(r2[1] - 0.5 * (nw + ne)) > tol ? 4u : 0) | (fabs(r1[0] - 0.5 * (sw + nw)) > tol ? 8u : 0);
        unsigned avail = (b.ms ? 1u : 0) | (b.me ? 2u : 0) | (b.mn ? 4u : 0) | (b.mw ? 8u : 0);
        if ((need & ~avail) || __builtin_popcount(need) > 2)
            return no;
        int d = d0 <= d1 ? 0 : 1;
        if ((d ? d1 : d0) <= tol)
            return (verdict){1, (unsigned char)d, 0, (unsigned char)need};
        return (verdict){1, 0, 1, (unsigned char)need};
    }
    corners c = corners_of(q, &b);
    /* try first the diagonal nearer the sample at the centre (where the
     * node has one: clipped nodes may not) */
    bool centred = b.xm < b.x1 && b.ym < b.y1;
    vtx centre = centred ? at(q, b.xm, b.ym) : c.sw;
    int first = 0;
    if (centred)
        first = fabs(centre.z - 0.5 * (c.sw.z + c.ne.z)) <= fabs(centre.z - 0.5 * (c.se.z + c.nw.z)) ? 0 : 1;
    /* (halves probed first only in nodes big enough for a probe) */
    bool probe = b.x1 - b.x0 >= PROBE_MIN && b.y1 - b.y0 >= PROBE_MIN;
    signed char memo[2][2]; /* halves' variants, shared with the sets of midpoints below */
    halves hv[2] = {diag_halves(&b, &c, 0), diag_halves(&b, &c, 1)};
    memset(memo, -1, sizeof memo);
    for (int t = 0; t < 2; t++) {
        int d = first ^ t;
        if (diag_ok_v(q, &hv[d], 0, memo[d], probe))
            return (verdict){1, (unsigned char)d, 0, 0};
    }
    /* four triangles from the centre: half a level between the two
     * triangles and the four children */
    fan f = fan_of(&b, &c, centre);
    if (centred && fan_ok(q, &f, probe))
        return (verdict){1, 0, 1, 0};
    /* two triangles with the midpoints of one or two sides, which the
     * neighbours there (of this level: they allow any midpoint) share */
    unsigned avail = (b.ms ? 1u : 0) | (b.me ? 2u : 0) | (b.mn ? 4u : 0) | (b.mw ? 8u : 0);
    static const unsigned sets[] = {1, 2, 4, 8, 3, 6, 12, 9, 5, 10};
    for (size_t k = 0; k < sizeof sets / sizeof sets[0]; k++) {
        if ((sets[k] & avail) != sets[k])
            continue;
        for (int t = 0; t < 2; t++) {
            int d = first ^ t;
            if (diag_ok_v(q, &hv[d], sets[k], memo[d], probe))
                return (verdict){1, (unsigned char)d, 0, (unsigned char)sets[k]};
        }
    }
    /* the fan with one or two midpoints asked for (6 or 8 triangles with
     * the neighbours' share, against 8 or more for a split) */
    unsigned need;
    if (centred && (need = fan_need(q, &f, probe)) != 0)
        return (verdict){1, 0, 1, (unsigned char)need};
    return no;
}

/* Makes n a leaf drawn as v says, or returns false when v rejects it. */
static bool apply(rqt *q, rnode n, verdict v)
{
    if (!v.ok)
        return false;
    if (v.diag)
        put_bit(q->diag, q, n, true);
    if (v.fan) {
        put_bit(q->fan, q, n, true);
        q->fans++;
    }
    if (v.need)
        accept_vol(q, n, v.need);
    return true;
}

/* ---- selection ---------------------------------------------------------- */

/* A verdict in a byte: bit 0 ok, 1 diag, 2 fan, 3-6 need, 7 judged. */
static unsigned char pack(verdict v)
{
    return (unsigned char)(0x80 | v.ok | v.diag << 1 | v.fan << 2 | v.need << 3);
}

static verdict unpack(unsigned char b)
{
    return (verdict){b & 1, b >> 1 & 1, b >> 2 & 1, b >> 3 & 15};
}

/* Judges n and, where it fails, its children, down to the nodes of two
 * cells a side (the verdicts the walk of select_cut will mostly ask for). */
static void judge_down(rqt *q, rnode n)
{
    verdict v = judge(q, n);
    q->verdicts[n.l][bit_of(q, n)] = pack(v);
    if (v.ok || n.l + 1 >= q->levels)
        return;
    for (uint32_t k = 0; k < 4; k++) {
        rnode c = {2 * n.x + (k & 1), 2 * n.y + (k >> 1), n.l + 1};
        if (exists(q, c))
            judge_down(q, c);
    }
}

typedef struct ahead_job {
    rqt *q;
    uint32_t l; /* the level of the subtrees' roots */
    size_t n;
    atomic_size_t next;
} ahead_job;

static void *ahead_worker(void *arg)
{
    ahead_job *j = arg;
    const rqt *q = j->q;
    for (size_t k; (k = atomic_fetch_add(&j->next, 1)) < j->n;) {
        rnode r = {(uint32_t)(k % q->nx[j->l]), (uint32_t)(k / q->nx[j->l]), j->l};
        /* a subtree only under failed ancestors: the walk may reach it */
        bool reached = true;
        for (rnode p = r; reached && p.l > 0;) {
            p = (rnode){p.x >> 1, p.y >> 1, p.l - 1};
            unsigned char b = q->verdicts[p.l][bit_of(q, p)];
            reached = b && !(b & 1);
        }
        if (reached)
            judge_down(j->q, r);
    }
    return NULL;
}

/* Judges ahead, on several threads, the nodes the walk will reach through
 * failed ancestors: the levels above l0 here, then each subtree of level
 * l0 on whichever thread is free (depth first, so a subtree's samples stay
 * in cache from a node to its children). Every verdict depends on its
 * node alone, so the walk that applies them in its order makes the same
 * cut whatever the thread count; nodes it reaches otherwise (the children
 * of a leaf split for the restriction) it judges itself. */
static void judge_ahead(rqt *q)
{
    uint32_t l0 = 0;
    while (l0 + 1 < q->levels && (uint64_t)q->nx[l0] * q->ny[l0] < 256)
        l0++;
    for (uint32_t l = 0; l <= l0 && l < q->levels; l++)
        memset(q->verdicts[l], 0, (size_t)q->nx[l] * q->ny[l]);
    for (uint32_t l = 0; l < l0; l++) /* few nodes: here */
        for (uint32_t y = 0; y < q->ny[l]; y++)
            for (uint32_t x = 0; x < q->nx[l]; x++) {
                rnode n = {x, y, l}, p = {x >> 1, y >> 1, l - 1};
                if (l == 0 || (q->verdicts[l - 1][bit_of(q, p)] & 0x81) == 0x80)
                    q->verdicts[l][bit_of(q, n)] = pack(judge(q, n));
            }
    for (uint32_t l = l0 + 1; l < q->levels; l++) /* (only under failed nodes) */
        memset(q->verdicts[l], 0, (size_t)q->nx[l] * q->ny[l]);
    ahead_job j = {.q = q, .l = l0, .n = (size_t)q->nx[l0] * q->ny[l0]};
    atomic_init(&j.next, 0);
    tsr__run_threads(ahead_worker, &j, q->threads, (uint32_t)j.n);
}

/* Selects the cut: a walk from the root, depth first, that splits each
 * node failing the test (after the coarser parents of its edge
 * neighbours, for the restriction) and tests its children in turn. */
static bool select_cut(rqt *q, double tol)
{
    q->tol = tol;
    for (uint32_t l = 0; l < q->levels; l++) {
        memset(q->split[l], 0, q->words[l] * sizeof(uint64_t));
        memset(q->diag[l], 0, q->words[l] * sizeof(uint64_t));
        memset(q->fan[l], 0, q->words[l] * sizeof(uint64_t));
        for (int k = 0; k < 4; k++)
            memset(q->vol[k][l], 0, q->words[l] * sizeof(uint64_t));
    }
    if (q->verdicts[0])
        judge_ahead(q);
    q->sn = 0;
    q->leaves = 1;
    q->fans = q->mids = q->vols = 0;
    push(q, (rnode){0, 0, 0});
    while (q->sn && !q->nomem) {
        rnode n = q->stack[--q->sn];
        if (is_split(q, n))
            continue;
        unsigned char b = q->verdicts[0] && n.l < q->levels ? q->verdicts[n.l][bit_of(q, n)] : 0;
        if (!apply(q, n, b ? unpack(b) : judge(q, n)))
            split(q, n);
    }
    return !q->nomem;
}

/* ---- the mesh of the cut ------------------------------------------------ */

/* The cut is walked to count its triangles, or to write them. A dense
 * mesh numbers its vertices as they come, in an array with one entry per
 * sample; a sparse one (where that array would be mostly empty) is walked
 * twice: first marking the samples its triangles use (a bit per sample),
 * then writing the triangles, each vertex numbered by the rank of its bit
 * (the marked samples before it in row order: a count per 64-bit word
 * plus a popcount), with its vertices written in row order in between. */
typedef struct emit {
    rqt *q;
    tsr_mesh *m;     /* NULL: count only */
    double dx, dy, dz;
    uint32_t *dense; /* dense: the vertex of each sample (UINT32_MAX: none yet) */
    bool mark;       /* sparse: mark the vertices' bits, write nothing */
    uint64_t *bits;
    uint32_t *rank; /* marked bits in the words before */
    uint64_t triangles;
    tsr_status st;
} emit;

/* Appends the vertex of sample (i, j) to m; false when out of memory. */
static bool new_vertex(tsr_mesh *m, const rqt *q, int64_t i, int64_t j, double dx, double dy, double dz, uint32_t *id)
{
    float p[3] = {(float)((double)i * dx), (float)((double)j * dy),
                  (float)((double)q->h[(size_t)j * q->w + (size_t)i] * dz)};
    if (!m->normals && !m->uvs && m->vertex_count < m->vertex_capacity) { /* the common case, inline */
        memcpy(m->positions + 3 * (size_t)m->vertex_count, p, sizeof p);
        *id = m->vertex_count++;
    } else if ((*id = tsr_mesh_add_vertex(m, p, NULL, NULL)) == UINT32_MAX)
        return false;
    return true;
}

/* The vertex of sample (i, j). */
static uint32_t vertex(emit *e, int64_t i, int64_t j)
{
    uint64_t key = (uint64_t)j * (uint64_t)(e->q->cx + 1) + (uint64_t)i;
    if (e->dense) {
        uint32_t *slot = &e->dense[key];
        if (*slot == UINT32_MAX && !new_vertex(e->m, e->q, i, j, e->dx, e->dy, e->dz, slot)) {
            e->st = TSR_ERR_NOMEM;
            *slot = 0;
        }
        return *slot;
    }
    uint64_t bit = (uint64_t)1 << (key & 63);
    if (e->mark) {
        e->bits[key >> 6] |= bit;
        return 0;
    }
    return e->rank[key >> 6] + (uint32_t)__builtin_popcountll(e->bits[key >> 6] & (bit - 1));
}

static void tri(emit *e, uint32_t a, uint32_t b, uint32_t c)
{
    if (e->mark)
        return;
    e->triangles++;
    tsr_mesh *m = e->m;
    if (!m)
        return;
    if (m->triangle_count < m->triangle_capacity) {
        uint32_t *t = m->indices + 3 * (size_t)m->triangle_count++;
        t[0] = a;
        t[1] = b;
        t[2] = c;
    } else if (!tsr_mesh_add_triangle(m, a, b, c))
        e->st = TSR_ERR_NOMEM;
}

/* The half abc (right angle at b), with the midpoint p of ab and r of
 * bc where they are (UINT32_MAX: none). */
static void emit_half(emit *e, uint32_t a, uint32_t b, uint32_t c, uint32_t p, uint32_t r)
{
    if (p == UINT32_MAX && r == UINT32_MAX)
        tri(e, a, b, c);
    else if (r == UINT32_MAX) {
        tri(e, a, p, c);
        tri(e, p, b, c);
    } else if (p == UINT32_MAX) {
        tri(e, a, b, r);
        tri(e, a, r, c);
    } else {
        tri(e, a, p, c);
        tri(e, p, b, r);
        tri(e, p, r, c);
    }
}

/* Whether leaf n has the midpoint of side k (S, E, N, W): the neighbour
 * of its level there is split, or either asked for it. */
static bool mid_at(const rqt *q, rnode n, int k)
{
    if (get_bit(q->vol[k], q, n))
        return true;
    rnode nb;
    return neighbour(q, n, k, &nb) && (is_split(q, nb) || get_bit(q->vol[(k + 2) & 3], q, nb));
}

static void emit_leaf(emit *e, rnode n)
{
    rqt *q = e->q;
    box b = node_box(q, n);
    bool counting = !e->m;
    if (n.l == q->levels) { /* a single cell: a hole if a corner is no-data */
        const float *r0 = q->h + (size_t)b.y0 * q->w, *r1 = r0 + q->w;
        if (isnan(r0[b.x0]) || isnan(r0[b.x1]) || isnan(r1[b.x0]) || isnan(r1[b.x1]))
            return;
        if (counting) {
            e->triangles += 2;
            return;
        }
        uint32_t sw = vertex(e, b.x0, b.y0), se = vertex(e, b.x1, b.y0), ne = vertex(e, b.x1, b.y1),
                 nw = vertex(e, b.x0, b.y1);
        tri(e, sw, se, ne);
        tri(e, ne, nw, sw);
        return;
    }
    /* midpoints where the neighbour is finer or either side asked */
    bool ms = b.ms && mid_at(q, n, 0), me = b.me && mid_at(q, n, 1), mn = b.mn && mid_at(q, n, 2),
         mw = b.mw && mid_at(q, n, 3);
    bool fan = get_bit(q->fan, q, n);
    if (counting) {
        e->triangles += (fan ? 4 : 2) + ms + me + mn + mw;
        return;
    }
    const uint32_t none = UINT32_MAX;
    uint32_t sw = vertex(e, b.x0, b.y0), se = vertex(e, b.x1, b.y0), ne = vertex(e, b.x1, b.y1),
             nw = vertex(e, b.x0, b.y1);
    uint32_t s = ms ? vertex(e, b.xm, b.y0) : none, ea = me ? vertex(e, b.x1, b.ym) : none,
             nn = mn ? vertex(e, b.xm, b.y1) : none, w = mw ? vertex(e, b.x0, b.ym) : none;
    if (fan) {
        uint32_t c = vertex(e, b.xm, b.ym);
        uint32_t ring[4][3] = {{sw, se, s}, {se, ne, ea}, {ne, nw, nn}, {nw, sw, w}};
        for (int i = 0; i < 4; i++)
            if (ring[i][2] != none) {
                tri(e, c, ring[i][0], ring[i][2]);
                tri(e, c, ring[i][2], ring[i][1]);
            } else
                tri(e, c, ring[i][0], ring[i][1]);
    } else if (!get_bit(q->diag, q, n)) {
        emit_half(e, sw, se, ne, s, ea);
        emit_half(e, ne, nw, sw, nn, w);
    } else {
        emit_half(e, se, ne, nw, ea, nn);
        emit_half(e, nw, sw, se, w, s);
    }
}

static void walk(emit *e, rnode n)
{
    if (e->st != TSR_OK)
        return;
    if (!is_split(e->q, n)) {
        emit_leaf(e, n);
        return;
    }
    for (uint32_t k = 0; k < 4; k++) {
        rnode c = {2 * n.x + (k & 1), 2 * n.y + (k >> 1), n.l + 1};
        if (exists(e->q, c))
            walk(e, c);
    }
}

/* Triangles of the cut (an upper bound: no-data cells drop out). */
static uint64_t count_cut(rqt *q)
{
    emit e = {.q = q, .st = TSR_OK};
    walk(&e, (rnode){0, 0, 0});
    return e.triangles;
}

/* The budget search's count: the cut at tol and its triangles. */
static bool count_at(void *user, double tol, uint64_t *n)
{
    rqt *q = user;
    if (!select_cut(q, tol))
        return false;
    *n = count_cut(q);
    return true;
}

/* The mesh of the cut, with room for its triangles reserved by the
 * caller; vertices: about how many there will be. */
static tsr_status emit_cut(rqt *q, const tsr_heightfield *hf, tsr_mesh *m, uint64_t vertices)
{
    uint64_t cols = (uint64_t)(q->cx + 1), lattice = cols * (uint64_t)(q->cy + 1), words = (lattice + 63) / 64;
    emit e = {.q = q, .m = m, .dx = hf->dx, .dy = hf->dy, .dz = hf->dz, .st = TSR_OK};
    /* dense: up to 2^25 samples (a 4097^2 terrain), a vertex for at most
     * 16 samples (filling the array costs more than the sparse walks) */
    if (lattice <= (1u << 25) && lattice <= 16 * vertices) {
        if (tsr_mesh_reserve_dense(m, (uint32_t)vertices, 0) != TSR_OK ||
            !(e.dense = tsr_alloc_dense(q->a, (size_t)lattice * sizeof *e.dense)))
            return TSR_ERR_NOMEM;
        memset(e.dense, 0xff, (size_t)lattice * sizeof *e.dense);
        walk(&e, (rnode){0, 0, 0});
        tsr_free(q->a, e.dense);
        return e.st;
    }
    e.mark = true;
    e.bits = tsr_alloc_dense(q->a, (size_t)words * sizeof *e.bits);
    e.rank = tsr_alloc_dense(q->a, (size_t)words * sizeof *e.rank);
    if (!e.bits || !e.rank) {
        e.st = TSR_ERR_NOMEM;
        goto done;
    }
    memset(e.bits, 0, (size_t)words * sizeof *e.bits);
    walk(&e, (rnode){0, 0, 0});
    uint64_t n = 0;
    for (uint64_t w = 0; w < words; w++) {
        e.rank[w] = (uint32_t)n;
        n += (uint64_t)__builtin_popcountll(e.bits[w]);
    }
    if (n >= UINT32_MAX || tsr_mesh_reserve_dense(m, (uint32_t)n, 0) != TSR_OK) {
        e.st = TSR_ERR_NOMEM;
        goto done;
    }
    for (uint64_t w = 0; w < words; w++)
        for (uint64_t b = e.bits[w]; b; b &= b - 1) {
            uint64_t key = w * 64 + (uint64_t)__builtin_ctzll(b), j = key / cols, i = key - j * cols;
            uint32_t id;
            new_vertex(m, q, (int64_t)i, (int64_t)j, hf->dx, hf->dy, hf->dz, &id); /* (room reserved) */
        }
    e.mark = false;
    walk(&e, (rnode){0, 0, 0});
done:
    tsr_free(q->a, e.bits);
    tsr_free(q->a, e.rank);
    return e.st;
}

/* ---- the entry point ------------------------------------------------- */

static void rqt_free(rqt *q)
{
    tsr_free(q->a, q->arena);
    tsr_free(q->a, q->stack);
}

tsr_status tsr__rqt_mesh(const tsr_heightfield *hf, double tol, double range, bool full_border, uint32_t max_tri,
                         uint32_t max_vert, uint32_t threads, tsr_mesh *mesh, tsr_tin_report *rep, tsr_error *err)
{
    rqt q = {.h = hf->data, .w = hf->width, .cx = (int64_t)hf->width - 1, .cy = (int64_t)hf->height - 1,
             .full_border = full_border, .threads = threads, .a = hf->alloc.realloc ? &hf->alloc : NULL};
    while (((int64_t)1 << q.levels) < (q.cx > q.cy ? q.cx : q.cy))
        q.levels++;
    for (uint32_t l = 0; l <= q.levels; l++) {
        int64_t s = (int64_t)1 << (q.levels - l);
        q.nx[l] = (uint32_t)((q.cx + s - 1) / s);
        q.ny[l] = (uint32_t)((q.cy + s - 1) / s);
    }
    tsr_status st = TSR_OK;
    /* The per-node bits (7 sets a level) and, with several threads, the
     * verdicts judged ahead (a byte per node: a third of a byte per
     * sample), in one dense block: the default allocator maps it with its
     * pages at once (huge where the kernel allows), where some twenty
     * blocks of a few MiB each took a page fault per 4 KiB (on the
     * generated 4097^2 at 12 m, a third of the time on two threads). */
    bool ahead = tsr__thread_count(threads) > 1 && q.levels > 4;
    size_t bytes = 0;
    for (uint32_t l = 0; l < q.levels; l++) {
        q.words[l] = ((size_t)q.nx[l] * q.ny[l] + 63) / 64;
        bytes += 7 * q.words[l] * sizeof(uint64_t) + (ahead ? q.words[l] * 64 : 0);
    }
    unsigned char *arena = q.arena = tsr_alloc_dense(q.a, bytes);
    if (!arena)
        return tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
    for (uint32_t l = 0; l < q.levels; l++) {
        size_t n = q.words[l] * sizeof(uint64_t);
        uint64_t **sets[7] = {&q.split[l], &q.diag[l], &q.fan[l], &q.vol[0][l], &q.vol[1][l], &q.vol[2][l],
                              &q.vol[3][l]};
        for (int k = 0; k < 7; k++, arena += n)
            *sets[k] = (uint64_t *)(void *)arena;
        if (ahead) {
            q.verdicts[l] = arena;
            arena += n * 8;
        }
    }
    if (!select_cut(&q, tol)) {
        st = tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
        goto done;
    }
    uint64_t budget = max_tri ? max_tri : UINT64_MAX;
    if (max_vert) /* about 2 V triangles; V is checked exactly below */
        budget = budget < 2ull * max_vert ? budget : 2ull * max_vert;
    for (int attempt = 0;; attempt++) {
        if (budget != UINT64_MAX && count_cut(&q) > budget) {
            /* the finest cut within the budget */
            double lo = tol > 0 ? tol : 1e-9;
            if ((st = tsr__budget_tolerance(lo, fmax(range * 2, lo * 2) + 1, budget, count_at, &q, &q.tol, err)) !=
                TSR_OK)
                goto done;
            rep->budget_reached = true;
        }
        rep->target_error = q.tol * hf->dz;
        /* room at once (growing by doubling would copy the mesh about
         * twice over): the triangles the counts give (no-data cells drop
         * out), and by Euler about half as many vertices plus the border
         * (counted exactly for a sparse mesh) */
        uint64_t nt = 2 * q.leaves + 2 * q.fans + q.mids + q.vols, nv = nt / 2 + 2 * (uint64_t)(q.cx + q.cy) + 4096;
        if (nt < UINT32_MAX / 2 && tsr_mesh_reserve_dense(mesh, 0, (uint32_t)nt) != TSR_OK) {
            st = tsr_error_set(err, TSR_ERR_NOMEM, "quadtree mesh: out of memory");
            goto done;
        }
        if ((st = emit_cut(&q, hf, mesh, nv < UINT32_MAX / 2 ? nv : UINT32_MAX / 2)) != TSR_OK) {
            tsr_error_set(err, st, "quadtree mesh: %s", tsr_status_str(st));
            goto done;
        }
        if (!max_vert || mesh->vertex_count <= max_vert)
            break;
        /* the vertices of a triangle budget vary with the boundary and
         * the no-data: tighten the triangle budget and bisect again */
        uint32_t got = mesh->vertex_count;
        uint64_t t = (uint64_t)((double)(budget < mesh->triangle_count ? budget : mesh->triangle_count) * 0.97 *
                                max_vert / got);
        mesh->vertex_count = mesh->triangle_count = 0;
        if (t < 2 || attempt >= 8) {
            st = tsr_error_set(err, TSR_ERR_ARGUMENT, "the budget is below the coarsest quadtree mesh (%u vertices)",
                               got);
            goto done;
        }
        budget = t;
    }
done:
    rqt_free(&q);
    return st;
}
