/* lod.c: the terrain pyramid (maximum mipmaps and per-node error) and the
 * terrain behind the generic surface interface.
 *
 * Maximum mipmaps after Tevs, Ihrke & Seidel 2008, "Maximum mipmaps for
 * fast, accurate, and scalable dynamic height field rendering": min and
 * max per block of 2^k cells, built bottom-up, closed blocks so the
 * bilinear or triangulated surface of the block lies within them.
 *
 * The error delta is built bottom-up too, conservatively. A parent tile P
 * and its children's tiles C are nested: each parent quad is split along
 * the diagonal through its 2x2 block's centre, and the four child quads it
 * becomes have their diagonals through that same centre, so every parent
 * triangle (and every merged triangle of a stitched edge, the union of
 * two) is a union of child triangles. On a child triangle both C and P are
 * linear, so |C - P| is largest at child vertices, where C = h. Hence
 *     |h - P| <= |h - C| + |C - P| <= delta_u(C) + max over child vertices |h - P|
 * (delta_u: the bound for the unstitched tile), and likewise for the
 * stitched variants, whose merged triangles only cover the band of quads
 * along each edge. This costs 4/3 of one pass over the samples instead of
 * one pass per level. Nodes clipped by the heightfield's far border are not
 * nested (their outer quads are narrowed), so their error is scanned
 * exactly over all samples while tiles are fine (spacing <= 8), and above
 * that bounded by the node's height range (a tile only interpolates
 * heights of the node). Finally delta = max(own, children's), monotone. */
#include "terrain_internal.h"

#include <math.h>
#include <string.h>

struct tsr_terrain {
    const tsr_heightfield *hf;
    tsr_allocator alloc;
    tsr_surface surface;
    uint32_t tile_log2;   /* log2(tile_n) */
    uint32_t mip_levels;  /* K: mip levels 1..K */
    uint32_t mw[40], mh[40];
    float *mip_min[40], *mip_max[40];
    uint64_t *mip_nan[40]; /* bit per block: covers a NaN sample */
    float *delta[TSR_QUADTREE_MAX_LEVELS + 1];   /* per node, file units */
    float *delta_u[TSR_QUADTREE_MAX_LEVELS + 1]; /* unstitched bound */
    size_t extra_bytes;
};

static const tsr_allocator *ta(const tsr_terrain *t) { return t->alloc.realloc ? &t->alloc : NULL; }

static inline float H(const tsr_heightfield *hf, uint32_t c, uint32_t r) { return hf->data[(size_t)r * hf->width + c]; }

static bool nan_bit(const tsr_terrain *t, uint32_t k, uint32_t bx, uint32_t by)
{
    size_t i = (size_t)by * t->mw[k] + bx;
    return (t->mip_nan[k][i >> 6] >> (i & 63)) & 1;
}

static uint32_t mip_of(const tsr_terrain *t, tsr_qnode n) { return t->tile_log2 + t->surface.levels - n.level; }

void tsr_terrain_node_range(const tsr_terrain *t, tsr_qnode n, float *mn, float *mx)
{
    uint32_t k = mip_of(t, n);
    if (k > t->mip_levels || n.x >= t->mw[k] || n.y >= t->mh[k]) {
        *mn = INFINITY;
        *mx = -INFINITY;
        return;
    }
    size_t i = (size_t)n.y * t->mw[k] + n.x;
    *mn = t->mip_min[k][i];
    *mx = t->mip_max[k][i];
}

/* ---- tile interpolation (any node, any stitch mask, clamped) -------- */

typedef struct tile_geom {
    uint32_t x0, y0, s, n, ex, ey;
} tile_geom;

static uint32_t clampu(uint64_t v, uint32_t hi) { return v > hi ? hi : (uint32_t)v; }

/* The height of the node's tile (stitched on the edges in mask) at lattice
 * point (px, py) inside the node and the extent. */
static double tile_interp(const tsr_heightfield *hf, const tile_geom *g, unsigned mask, uint32_t px, uint32_t py)
{
    uint32_t n = g->n;
    uint32_t qi = px == g->x0 ? 0 : (px - g->x0 - 1) / g->s, qj = py == g->y0 ? 0 : (py - g->y0 - 1) / g->s;
    qi = qi >= n ? n - 1 : qi;
    qj = qj >= n ? n - 1 : qj;
    uint32_t X0 = clampu((uint64_t)g->x0 + (uint64_t)qi * g->s, g->ex), X1 = clampu((uint64_t)g->x0 + (uint64_t)(qi + 1) * g->s, g->ex);
    uint32_t Y0 = clampu((uint64_t)g->y0 + (uint64_t)qj * g->s, g->ey), Y1 = clampu((uint64_t)g->y0 + (uint64_t)(qj + 1) * g->s, g->ey);
    double fx = X1 > X0 ? (double)(px - X0) / (X1 - X0) : 0, fy = Y1 > Y0 ? (double)(py - Y0) / (Y1 - Y0) : 0;
    /* triangle as local vertex coordinates (i, j) of the tile */
    uint32_t v[3][2];
    uint32_t a[2] = {qi, qj}, b[2] = {qi + 1, qj}, c[2] = {qi, qj + 1}, d[2] = {qi + 1, qj + 1};
    const uint32_t *tri[3];
    if (((qi + qj) & 1) == 0) {
        if (fx >= fy) { tri[0] = a; tri[1] = b; tri[2] = d; }
        else { tri[0] = a; tri[1] = d; tri[2] = c; }
    } else {
        if (fx + fy <= 1) { tri[0] = a; tri[1] = b; tri[2] = c; }
        else { tri[0] = b; tri[1] = d; tri[2] = c; }
    }
    for (int k = 0; k < 3; k++) {
        v[k][0] = tri[k][0];
        v[k][1] = tri[k][1];
    }
    /* a dropped odd edge vertex is replaced: the merged triangle is
     * (vertex before, vertex after, inner vertex) */
    if (mask) {
        for (int k = 0; k < 3; k++) {
            uint32_t i = v[k][0], j = v[k][1];
            bool south = j == 0 && (i & 1) && (mask & TSR_EDGE_SOUTH), north = j == n && (i & 1) && (mask & TSR_EDGE_NORTH);
            bool west = i == 0 && (j & 1) && (mask & TSR_EDGE_WEST), east = i == n && (j & 1) && (mask & TSR_EDGE_EAST);
            if (!(south || north || west || east))
                continue;
            /* the triangle's other two vertices: one on the edge (before or
             * after v), one inner; rebuild as before, after, inner */
            int o1 = (k + 1) % 3, o2 = (k + 2) % 3;
            bool o1_on_edge = (south || north) ? v[o1][1] == j : v[o1][0] == i;
            int inner = o1_on_edge ? o2 : o1;
            uint32_t in[2] = {v[inner][0], v[inner][1]};
            if (south || north) {
                v[0][0] = i - 1; v[0][1] = j;
                v[1][0] = i + 1; v[1][1] = j;
            } else {
                v[0][0] = i; v[0][1] = j - 1;
                v[1][0] = i; v[1][1] = j + 1;
            }
            v[2][0] = in[0];
            v[2][1] = in[1];
            break;
        }
    }
    double P[3][2], h[3];
    for (int k = 0; k < 3; k++) {
        uint32_t cx = clampu((uint64_t)g->x0 + (uint64_t)v[k][0] * g->s, g->ex);
        uint32_t cy = clampu((uint64_t)g->y0 + (uint64_t)v[k][1] * g->s, g->ey);
        P[k][0] = cx;
        P[k][1] = cy;
        h[k] = H(hf, cx, cy);
    }
    double det = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[1][1] - P[0][1]) * (P[2][0] - P[0][0]);
    if (det == 0)
        return h[0];
    double l1 = ((px - P[0][0]) * (P[2][1] - P[0][1]) - (py - P[0][1]) * (P[2][0] - P[0][0])) / det;
    double l2 = ((P[1][0] - P[0][0]) * (py - P[0][1]) - (P[1][1] - P[0][1]) * (px - P[0][0])) / det;
    return h[0] + l1 * (h[1] - h[0]) + l2 * (h[2] - h[0]);
}

/* Max |h - tile| over lattice points at `step` within the node (clipped to
 * the extent). bands: only the band of quads along each edge in mask. */
static double scan_error(const tsr_heightfield *hf, const tile_geom *g, unsigned mask, uint32_t step, bool bands)
{
    uint32_t w = g->s * g->n;
    uint32_t xe = clampu((uint64_t)g->x0 + w, g->ex), ye = clampu((uint64_t)g->y0 + w, g->ey);
    double worst = 0;
    for (uint32_t py = g->y0; py <= ye; py += step) {
        bool in_sn = (mask & TSR_EDGE_SOUTH && py <= g->y0 + g->s) || (mask & TSR_EDGE_NORTH && py + g->s >= g->y0 + w);
        for (uint32_t px = g->x0; px <= xe; px += step) {
            if (bands) {
                bool in_we = (mask & TSR_EDGE_WEST && px <= g->x0 + g->s) || (mask & TSR_EDGE_EAST && px + g->s >= g->x0 + w);
                if (!in_sn && !in_we)
                    continue;
            }
            float hv = H(hf, px, py);
            if (isnan(hv))
                continue;
            double e = fabs(hv - tile_interp(hf, g, mask, px, py));
            worst = e > worst || isnan(e) ? (isnan(e) ? worst : e) : worst;
        }
    }
    return worst;
}

/* The unstitched error of an interior node's tile at its children's
 * vertices: each quad's edge midpoints and centre (corners are exact). */
static double midpoint_error(const tsr_heightfield *hf, const tile_geom *g)
{
    uint32_t s = g->s, hs = s / 2, n = g->n;
    double worst = 0;
    for (uint32_t qj = 0; qj <= n; qj++) {
        uint32_t y = g->y0 + qj * s;
        for (uint32_t qi = 0; qi <= n; qi++) {
            uint32_t x = g->x0 + qi * s;
            float a = H(hf, x, y);
            if (qi < n) { /* midpoint of the quad's south edge */
                float b = H(hf, x + s, y), m = H(hf, x + hs, y);
                double e = fabs(m - 0.5 * ((double)a + b));
                worst = e > worst ? e : worst;
            }
            if (qj < n) { /* west edge */
                float c = H(hf, x, y + s), m = H(hf, x, y + hs);
                double e = fabs(m - 0.5 * ((double)a + c));
                worst = e > worst ? e : worst;
            }
            if (qi < n && qj < n) { /* centre, on the quad's diagonal */
                float ctr = H(hf, x + hs, y + hs);
                double e;
                if (((qi + qj) & 1) == 0)
                    e = fabs(ctr - 0.5 * ((double)a + H(hf, x + s, y + s)));
                else
                    e = fabs(ctr - 0.5 * ((double)H(hf, x + s, y) + H(hf, x, y + s)));
                worst = e > worst ? e : worst;
            }
        }
    }
    return worst;
}

/* The stitched error of an interior node's tile at its children's
 * vertices: each merged triangle (A, B on the edge around the dropped odd
 * vertex, C the inner vertex) contains six child vertices off its
 * corners, at fixed barycentric weights (lambda_C = y, lambda_B =
 * (x - y) / 2 in units of the tile spacing from A, x along the edge and y
 * inwards). */
static double band_error(const tsr_heightfield *hf, const tile_geom *g)
{
    static const double pts[6][2] = {{1, 0}, {0.5, 0}, {1.5, 0}, {1, 0.5}, {0.5, 0.5}, {1.5, 0.5}};
    uint32_t s = g->s, hs = s / 2, n = g->n;
    double worst = 0;
    for (int e = 0; e < 4; e++) {
        /* origin of the edge and unit steps along it and inwards */
        int64_t ox = e == 1 ? g->x0 + n * s : g->x0, oy = e == 2 ? g->y0 + n * s : g->y0;
        int ax = e == 0 || e == 2, ay = !ax, ix = e == 3 ? 1 : e == 1 ? -1 : 0, iy = e == 0 ? 1 : e == 2 ? -1 : 0;
        for (uint32_t k = 0; k + 1 < n; k += 2) {
            int64_t Ax = ox + (int64_t)ax * k * s, Ay = oy + (int64_t)ay * k * s;
            int64_t Bx = Ax + (int64_t)ax * 2 * s, By = Ay + (int64_t)ay * 2 * s;
            int64_t Cx = Ax + (int64_t)ax * s + (int64_t)ix * s, Cy = Ay + (int64_t)ay * s + (int64_t)iy * s;
            double ha = H(hf, (uint32_t)Ax, (uint32_t)Ay), hb = H(hf, (uint32_t)Bx, (uint32_t)By),
                   hc = H(hf, (uint32_t)Cx, (uint32_t)Cy);
            for (int p = 0; p < 6; p++) {
                double x = pts[p][0], y = pts[p][1];
                double lc = y, lb = (x - y) / 2, la = 1 - lb - lc;
                int64_t px = Ax + (int64_t)(ax * x * 2) * hs + (int64_t)(ix * y * 2) * hs;
                int64_t py = Ay + (int64_t)(ay * x * 2) * hs + (int64_t)(iy * y * 2) * hs;
                double err = fabs(H(hf, (uint32_t)px, (uint32_t)py) - (la * ha + lb * hb + lc * hc));
                worst = err > worst ? err : worst;
            }
        }
    }
    return worst;
}

/* Streaming part of the error, run on every block row of the sample pass
 * (rows y = 2 by, y + 1, y + 2 as a, b, c): the two deepest levels' errors
 * need only these three rows, so they cost no extra pass over memory.
 *  - deepest level (spacing 1): a stitched edge moves only its odd
 *    samples, to the mean of their two neighbours along the edge;
 *  - the level above (spacing 2): its tile's error at its children's
 *    vertices is at the quads' edge midpoints and centres (corners are
 *    exact); the centre lies on the quad's union-jack diagonal.
 * Each value goes to every node whose closed region holds the sample.
 * Clipped and no-data nodes are recomputed or overridden later. */
static inline void upd(float *arr, size_t i, float e)
{
    arr[i] = e > arr[i] ? e : arr[i]; /* NaN e compares false: ignored */
}

static inline float err3(float m, float p, float q)
{
    /* in double: exact for floats of similar magnitude, then rounded up */
    double e = fabs((double)m - 0.5 * ((double)p + (double)q));
    float f = (float)e;
    return (double)f < e ? nextafterf(f, INFINITY) : f;
}

static void edge_errors(tsr_terrain *t, uint32_t by, const float *a, const float *b, const float *c)
{
    const tsr_heightfield *hf = t->hf;
    uint32_t L = t->surface.levels, N = t->surface.tile_n, ex = hf->width - 1, ey = hf->height - 1;
    uint32_t y = 2 * by;
    bool full = y + 2 <= ey;
    float *fin = t->delta[L];
    /* deepest level, vertical edges (x a multiple of N, the domain's
     * borders included: the contract covers every stitch mask) at the odd
     * row y + 1 */
    if (full) {
        size_t row = (size_t)((y + 1) / N) << L;
        for (uint32_t x = 0; x <= ex; x += N) {
            float e = err3(b[x], a[x], c[x]);
            if (x < ex)
                upd(fin, row + x / N, e);
            if (x > 0)
                upd(fin, row + x / N - 1, e);
        }
    }
    /* deepest level, horizontal edges: row y a multiple of N */
    if (y % N == 0) {
        size_t up = (size_t)(y / N) << L, down = y > 0 ? (size_t)(y / N - 1) << L : 0;
        for (uint32_t x = 1; x + 1 <= ex; x += 2) {
            float e = err3(a[x], a[x - 1], a[x + 1]);
            if (y < ey)
                upd(fin, up + x / N, e);
            if (y > 0)
                upd(fin, down + x / N, e);
        }
    }
    if (L == 0 || !full)
        return;
    /* the level above: quads of 2 x 2 cells with corners at even x, y */
    float *mid = t->delta_u[L - 1];
    uint32_t M = 2 * N, ny = y / M;
    size_t row = (size_t)ny << (L - 1), row_below = ny > 0 ? (size_t)(ny - 1) << (L - 1) : 0;
    bool on_south_edge = y % M == 0 && ny > 0;
    bool even_row = (by & 1) == 0;
    for (uint32_t x = 0; x + 2 <= ex; x += 2) {
        float e1 = err3(a[x + 1], a[x], a[x + 2]);
        float e2 = err3(b[x], a[x], c[x]);
        bool diag_ad = (((x >> 1) & 1) == 0) == even_row;
        float e3 = diag_ad ? err3(b[x + 1], a[x], c[x + 2]) : err3(b[x + 1], a[x + 2], c[x]);
        uint32_t nx = x / M;
        float e = e1 > e2 ? e1 : e2;
        e = e3 > e ? e3 : e;
        upd(mid, row + nx, e);
        if (on_south_edge)
            upd(mid, row_below + nx, e1); /* the node below's top edge */
        if (x % M == 0 && nx > 0)
            upd(mid, row + nx - 1, e2); /* the node to the left's east edge */
    }
    if (ex % M == 0) /* the east edge of the last node column */
        upd(mid, row + ex / M - 1, err3(b[ex], a[ex], c[ex]));
}

/* The last row, ey, is never the first row of a block row: its odd samples
 * for the deepest level's north edges and the level above's top edges. */
static void last_row_errors(tsr_terrain *t)
{
    const tsr_heightfield *hf = t->hf;
    uint32_t L = t->surface.levels, N = t->surface.tile_n, M = 2 * N, ex = hf->width - 1, ey = hf->height - 1;
    if (ey % 2 != 0)
        return; /* odd: never a tile edge, and its nodes are clipped (scanned) */
    const float *a = hf->data + (size_t)ey * hf->width;
    if (ey % N == 0) {
        size_t down = (size_t)(ey / N - 1) << L;
        for (uint32_t x = 1; x + 1 <= ex; x += 2)
            upd(t->delta[L], down + x / N, err3(a[x], a[x - 1], a[x + 1]));
    }
    if (L > 0 && ey % M == 0) {
        size_t row = (size_t)(ey / M - 1) << (L - 1);
        for (uint32_t x = 0; x + 2 <= ex; x += 2)
            upd(t->delta_u[L - 1], row + x / M, err3(a[x + 1], a[x], a[x + 2]));
    }
}

/* The sample pass's two kernels, apart so restrict tells the compiler
 * the arrays do not alias (it then vectorises them). "x < lo ? x : lo" is
 * the minss instruction, which keeps lo when x is NaN; starting from +inf
 * (-inf for the max) makes NaN samples vanish without a branch. */
static void column_pass(const float *restrict a, const float *restrict b, const float *restrict c,
                        float *restrict cmin, float *restrict cmax, unsigned char *restrict cnan, uint32_t w)
{
    for (uint32_t x = 0; x < w; x++) {
        float va = a[x], vb = b[x], vc = c[x], lo = INFINITY, hi = -INFINITY;
        lo = va < lo ? va : lo;
        lo = vb < lo ? vb : lo;
        lo = vc < lo ? vc : lo;
        hi = va > hi ? va : hi;
        hi = vb > hi ? vb : hi;
        hi = vc > hi ? vc : hi;
        cmin[x] = lo;
        cmax[x] = hi;
        cnan[x] = (unsigned char)((va != va) | (vb != vb) | (vc != vc));
    }
}

/* Blocks of three columns (the last one clamped to the extent); an empty
 * block gets the empty range +inf..-inf. */
static void block_pass(const float *restrict cmin, const float *restrict cmax, float *restrict mn, float *restrict mx,
                       uint32_t mw, uint32_t ex)
{
    uint32_t full = ex / 2; /* blocks whose third column exists */
    full = full < mw ? full : mw;
    for (uint32_t bx = 0; bx < full; bx++) {
        uint32_t c0 = 2 * bx;
        float lo = cmin[c0], hi = cmax[c0];
        lo = cmin[c0 + 1] < lo ? cmin[c0 + 1] : lo;
        lo = cmin[c0 + 2] < lo ? cmin[c0 + 2] : lo;
        hi = cmax[c0 + 1] > hi ? cmax[c0 + 1] : hi;
        hi = cmax[c0 + 2] > hi ? cmax[c0 + 2] : hi;
        mn[bx] = lo;
        mx[bx] = hi;
    }
    for (uint32_t bx = full; bx < mw; bx++) { /* a last block of two columns */
        uint32_t c0 = 2 * bx, c1 = c0 + 1 > ex ? ex : c0 + 1;
        mn[bx] = cmin[c1] < cmin[c0] ? cmin[c1] : cmin[c0];
        mx[bx] = cmax[c1] > cmax[c0] ? cmax[c1] : cmax[c0];
    }
}

/* ---- surface callbacks ------------------------------------------------ */

static bool surf_evaluate(void *user, uint32_t i, uint32_t j, float pos[3], float normal[3])
{
    const tsr_terrain *t = user;
    const tsr_heightfield *hf = t->hf;
    float h = H(hf, i, j);
    if (isnan(h))
        return false;
    pos[0] = (float)(i * hf->dx);
    pos[1] = (float)(j * hf->dy);
    pos[2] = (float)(h * hf->dz);
    if (normal)
        tsr_heightfield_normal_at(hf, i, j, normal);
    return true;
}

static void surf_bounds(void *user, tsr_qnode n, float lo[3], float hi[3])
{
    const tsr_terrain *t = user;
    const tsr_heightfield *hf = t->hf;
    float mn, mx;
    tsr_terrain_node_range(t, n, &mn, &mx);
    uint64_t w = (uint64_t)t->surface.tile_n << (t->surface.levels - n.level);
    uint32_t x0 = clampu(n.x * w, hf->width - 1), x1 = clampu((n.x + 1) * w, hf->width - 1);
    uint32_t y0 = clampu(n.y * w, hf->height - 1), y1 = clampu((n.y + 1) * w, hf->height - 1);
    lo[0] = (float)(x0 * hf->dx);
    hi[0] = (float)(x1 * hf->dx);
    lo[1] = (float)(y0 * hf->dy);
    hi[1] = (float)(y1 * hf->dy);
    lo[2] = (float)(mn * hf->dz);
    hi[2] = (float)(mx * hf->dz);
}

static float surf_error(void *user, tsr_qnode n)
{
    const tsr_terrain *t = user;
    float d = t->delta[n.level][((size_t)n.y << n.level) + n.x];
    return isinf(d) ? INFINITY : (float)(d * t->hf->dz);
}

const tsr_surface *tsr_terrain_surface(const tsr_terrain *t) { return &t->surface; }
const tsr_heightfield *tsr_terrain_heightfield(const tsr_terrain *t) { return t->hf; }
size_t tsr_terrain_extra_bytes(const tsr_terrain *t) { return t->extra_bytes; }

/* ---- building ----------------------------------------------------------- */

void tsr_terrain_destroy(tsr_terrain *t)
{
    if (!t)
        return;
    const tsr_allocator *a = ta(t);
    for (uint32_t k = 0; k < 40; k++) {
        tsr_free(a, t->mip_min[k]);
        tsr_free(a, t->mip_max[k]);
        tsr_free(a, t->mip_nan[k]);
    }
    for (uint32_t l = 0; l <= TSR_QUADTREE_MAX_LEVELS; l++) {
        tsr_free(a, t->delta[l]);
        tsr_free(a, t->delta_u[l]);
    }
    tsr_allocator copy = t->alloc;
    tsr_free(copy.realloc ? &copy : NULL, t);
}

static void *talloc(tsr_terrain *t, size_t bytes)
{
    void *p = tsr_alloc(ta(t), bytes);
    if (p)
        t->extra_bytes += bytes;
    return p;
}

tsr_status tsr_terrain_create(const tsr_heightfield *hf, const tsr_terrain_options *opts, const tsr_allocator *alloc,
                              tsr_terrain **out, tsr_error *err)
{
    *out = NULL;
    uint32_t n = opts && opts->tile_n ? opts->tile_n : 16;
    if (n < 2 || n > 128 || (n & (n - 1)))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "tile size %u: must be 2, 4, 8, 16, 32, 64 or 128", n);
    if (!(hf->dx > 0 && hf->dy > 0 && hf->dz > 0))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "spacing dx, dy, dz must be positive");
    uint32_t W = hf->width, Hh = hf->height, ex = W - 1, ey = Hh - 1;
    uint32_t levels = tsr_quadtree_levels_for(n, ex, ey);
    if (levels >= TSR_QUADTREE_MAX_LEVELS)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "heightfield too large for tile size %u (use a larger --tile)", n);
    tsr_terrain *t = tsr_alloc(alloc, sizeof *t);
    if (!t)
        return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory");
    memset(t, 0, sizeof *t);
    if (alloc)
        t->alloc = *alloc;
    t->hf = hf;
    t->tile_log2 = 0;
    while ((1u << t->tile_log2) < n)
        t->tile_log2++;
    t->surface = (tsr_surface){t, n, levels, ex, ey, surf_evaluate, surf_bounds, surf_error, false};
    t->mip_levels = t->tile_log2 + levels;

    /* per-node errors; the two deepest levels are filled during the
     * sample pass below, the rest bottom-up afterwards */
    for (uint32_t l = 0; l <= levels; l++) {
        size_t cnt = (size_t)1 << (2 * l);
        t->delta[l] = talloc(t, cnt * sizeof(float));
        t->delta_u[l] = talloc(t, cnt * sizeof(float));
        if (!t->delta[l] || !t->delta_u[l]) {
            tsr_terrain_destroy(t);
            return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for the terrain pyramid");
        }
        for (size_t i = 0; i < cnt; i++)
            t->delta[l][i] = t->delta_u[l][i] = 0;
    }
    /* mip level 1 from the samples: closed 3x3-sample blocks */
    for (uint32_t k = 1; k <= t->mip_levels; k++) {
        uint64_t cells = (uint64_t)1 << k;
        t->mw[k] = (uint32_t)((ex + cells - 1) / cells);
        t->mh[k] = (uint32_t)((ey + cells - 1) / cells);
        size_t cnt = (size_t)t->mw[k] * t->mh[k];
        t->mip_min[k] = talloc(t, cnt * sizeof(float));
        t->mip_max[k] = talloc(t, cnt * sizeof(float));
        t->mip_nan[k] = talloc(t, ((cnt + 63) / 64) * sizeof(uint64_t));
        if (!t->mip_min[k] || !t->mip_max[k] || !t->mip_nan[k]) {
            tsr_terrain_destroy(t);
            return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for the terrain pyramid");
        }
        memset(t->mip_nan[k], 0, ((cnt + 63) / 64) * sizeof(uint64_t));
    }
    {
        /* two passes per block row: the min/max down the block's three
         * sample rows for every column (a straight, vectorisable loop),
         * then across each block's three columns */
        uint32_t mw = t->mw[1], mh = t->mh[1];
        float *cmin = tsr_alloc(ta(t), 2 * (size_t)W * sizeof(float)), *cmax = cmin ? cmin + W : NULL;
        unsigned char *cnan = tsr_alloc(ta(t), W);
        if (!cmin || !cnan) {
            tsr_free(ta(t), cmin);
            tsr_free(ta(t), cnan);
        last_row_errors(t);
            tsr_terrain_destroy(t);
            return tsr_error_set(err, TSR_ERR_NOMEM, "out of memory for the terrain pyramid");
        }
        for (uint32_t by = 0; by < mh; by++) {
            uint32_t r0 = 2 * by, r1 = r0 + 2 > ey ? ey : r0 + 2;
            const float *a = hf->data + (size_t)r0 * W, *b = hf->data + (size_t)(r0 + 1) * W,
                        *cc = hf->data + (size_t)r1 * W;
            column_pass(a, b, cc, cmin, cmax, cnan, W);
            edge_errors(t, by, a, b, cc);
            float *mn = t->mip_min[1] + (size_t)by * mw, *mx = t->mip_max[1] + (size_t)by * mw;
            block_pass(cmin, cmax, mn, mx, mw, ex);
            for (uint32_t bx = 0; bx < mw; bx++) {
                uint32_t c0 = 2 * bx, c2 = c0 + 2 > ex ? ex : c0 + 2;
                if (cnan[c0] | cnan[c0 + 1] | cnan[c2]) {
                    size_t i = (size_t)by * mw + bx;
                    t->mip_nan[1][i >> 6] |= 1ull << (i & 63);
                }
            }
        }
        tsr_free(ta(t), cnan);
        last_row_errors(t);
        tsr_free(ta(t), cmin);
    }
    for (uint32_t k = 2; k <= t->mip_levels; k++) {
        uint32_t mw = t->mw[k], mh = t->mh[k], pw = t->mw[k - 1], ph = t->mh[k - 1];
        for (uint32_t by = 0; by < mh; by++)
            for (uint32_t bx = 0; bx < mw; bx++) {
                float lo = INFINITY, hi = -INFINITY;
                bool has_nan = false;
                for (uint32_t q = 0; q < 4; q++) {
                    uint32_t cx = 2 * bx + (q & 1), cy = 2 * by + (q >> 1);
                    if (cx >= pw || cy >= ph)
                        continue;
                    size_t ci = (size_t)cy * pw + cx;
                    float a = t->mip_min[k - 1][ci], b = t->mip_max[k - 1][ci];
                    lo = a < lo ? a : lo;
                    hi = b > hi ? b : hi;
                    has_nan |= nan_bit(t, k - 1, cx, cy);
                }
                size_t i = (size_t)by * mw + bx;
                t->mip_min[k][i] = lo;
                t->mip_max[k][i] = hi;
                if (has_nan)
                    t->mip_nan[k][i >> 6] |= 1ull << (i & 63);
            }
    }

    /* per-node error, deepest level first */
    for (uint32_t l = levels + 1; l-- > 0;) {
        uint32_t side = 1u << l, k = t->tile_log2 + levels - l;
        uint64_t w = (uint64_t)n << (levels - l);
        uint32_t s = (uint32_t)(w / n);
        for (uint32_t y = 0; y < side; y++)
            for (uint32_t x = 0; x < side; x++) {
                tsr_qnode node = {x, y, (uint8_t)l};
                if (!tsr_quadtree_node_exists(&t->surface, node))
                    continue;
                size_t idx = ((size_t)y << l) + x;
                tile_geom g = {(uint32_t)(x * w), (uint32_t)(y * w), s, n, ex, ey};
                bool clipped = x * w + w > ex || y * w + w > ey;
                bool has_nan = nan_bit(t, k, x, y);
                double du = 0, d = 0, child_u = 0, child_d = 0;
                if (l < levels)
                    for (unsigned q = 0; q < 4; q++) {
                        tsr_qnode c = {2 * x + (q & 1), 2 * y + (q >> 1), (uint8_t)(l + 1)};
                        if (!tsr_quadtree_node_exists(&t->surface, c))
                            continue;
                        size_t ci = ((size_t)c.y << c.level) + c.x;
                        child_u = fmax(child_u, t->delta_u[l + 1][ci]);
                        child_d = fmax(child_d, t->delta[l + 1][ci]);
                    }
                if (l == levels) {
                    du = 0; /* the finest tile is the surface */
                    /* its stitch error: from the sample pass, or scanned
                     * when the node is clipped (its edges are clamped) */
                    d = clipped ? fmax(t->delta[l][idx], scan_error(hf, &g, 15, 1, true)) : t->delta[l][idx];
                } else if (has_nan) {
                    du = d = INFINITY;
                } else if (clipped) {
                    if (s <= 8) {
                        du = scan_error(hf, &g, 0, 1, false);
                        d = fmax(du, scan_error(hf, &g, 15, 1, true));
                    } else {
                        size_t mi = (size_t)y * t->mw[k] + x;
                        du = d = (double)t->mip_max[k][mi] - t->mip_min[k][mi];
                    }
                } else {
                    double mid = l + 1 == levels ? t->delta_u[l][idx] /* from the sample pass */
                                                 : midpoint_error(hf, &g);
                    du = child_u + mid;
                    d = fmax(du, child_u + band_error(hf, &g));
                }
                du = fmax(du, child_u);
                d = fmax(fmax(d, du), child_d);
                /* round up so float storage never understates */
                t->delta_u[l][idx] = isinf(du) ? INFINITY : nextafterf((float)du, INFINITY);
                t->delta[l][idx] = isinf(d) ? INFINITY : nextafterf((float)d, INFINITY);
            }
    }
    *out = t;
    return TSR_OK;
}

bool tsr_terrain_pick_view(const tsr_terrain *t, pick_view *v)
{
    v->hf = t->hf;
    v->mip_levels = t->mip_levels;
    v->mw = t->mw;
    v->mh = t->mh;
    v->mip_min = t->mip_min;
    v->mip_max = t->mip_max;
    return t->mip_levels >= 1;
}
