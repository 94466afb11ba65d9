/* quadtree.c: the restricted quadtree over a tsr_surface: selection,
 * 2:1 balancing, stitch masks, camera error, and the mesh of a cut.
 *
 * Split flags live in one bitset per level (complete levels, node (x, y)
 * of level l at bit y * 2^l + x), so "is this node split?" is one bit
 * test and neighbours are found by arithmetic on (level, x, y) rather than
 * by pointers. Balancing (after Sivan & Samet's restricted quadtrees)
 * walks the split nodes from the deepest level up: a split node's
 * same-level edge neighbours must exist, so their parents get split (and
 * those parents' ancestors), which the next, shallower level then
 * balances in turn; one pass suffices because splitting at level l-1
 * never creates work at level l or below. */
#include "tessellate/tessellate.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

typedef struct node_list {
    uint32_t *xy; /* pairs x, y */
    uint32_t count, cap;
} node_list;

struct tsr_quadtree {
    tsr_surface s;
    tsr_allocator alloc;
    uint64_t *split[TSR_QUADTREE_MAX_LEVELS]; /* levels 0 .. s.levels-1 */
    node_list lists[TSR_QUADTREE_MAX_LEVELS];
    tsr_qleaf *leaves;
    uint32_t leaf_count, leaf_cap;
    uint32_t balance_splits;
};

static const tsr_allocator *qa(const tsr_quadtree *qt) { return qt->alloc.realloc ? &qt->alloc : NULL; }

uint32_t tsr_quadtree_levels_for(uint32_t tile_n, uint32_t extent_x, uint32_t extent_y)
{
    uint32_t levels = 0;
    uint64_t size = tile_n;
    while (size < extent_x || size < extent_y) {
        size <<= 1;
        levels++;
    }
    return levels;
}

bool tsr_quadtree_node_exists(const tsr_surface *s, tsr_qnode n)
{
    if (n.level > s->levels)
        return false;
    uint64_t side = 1ull << n.level;
    if (n.x >= side || n.y >= side)
        return false;
    uint64_t w = (uint64_t)s->tile_n << (s->levels - n.level);
    return (uint64_t)n.x * w < s->extent_x && (uint64_t)n.y * w < s->extent_y;
}

/* The low 28 bits of v, spread to the even bits. */
static uint64_t spread_bits(uint64_t v)
{
    v &= 0xFFFFFFFull;
    v = (v | v << 16) & 0x0000FFFF0000FFFFull;
    v = (v | v << 8) & 0x00FF00FF00FF00FFull;
    v = (v | v << 4) & 0x0F0F0F0F0F0F0F0Full;
    v = (v | v << 2) & 0x3333333333333333ull;
    v = (v | v << 1) & 0x5555555555555555ull;
    return v;
}

uint64_t tsr_qnode_key(tsr_qnode n)
{
    return (uint64_t)n.level << 56 | spread_bits(n.x) | spread_bits(n.y) << 1;
}

tsr_quadtree *tsr_quadtree_create(const tsr_surface *s, const tsr_allocator *alloc)
{
    if (s->tile_n < TSR_TILE_MIN || s->tile_n > TSR_TILE_MAX || (s->tile_n & 1) ||
        s->levels >= TSR_QUADTREE_MAX_LEVELS || s->extent_x == 0 || s->extent_y == 0 ||
        s->extent_x > (s->tile_n << s->levels) || s->extent_y > (s->tile_n << s->levels))
        return NULL;
    tsr_quadtree *qt = tsr_alloc(alloc, sizeof *qt);
    if (!qt)
        return NULL;
    memset(qt, 0, sizeof *qt);
    qt->s = *s;
    if (alloc)
        qt->alloc = *alloc;
    return qt; /* split flags are allocated per level on first use (mark_split) */
}

void tsr_quadtree_destroy(tsr_quadtree *qt)
{
    if (!qt)
        return;
    const tsr_allocator *a = qa(qt);
    for (uint32_t l = 0; l < TSR_QUADTREE_MAX_LEVELS; l++) {
        tsr_free(a, qt->split[l]);
        tsr_free(a, qt->lists[l].xy);
    }
    tsr_free(a, qt->leaves);
    tsr_allocator copy = qt->alloc;
    tsr_free(copy.realloc ? &copy : NULL, qt);
}

static size_t bit_index(tsr_qnode n) { return ((size_t)n.y << n.level) + n.x; }

bool tsr_quadtree_is_split(const tsr_quadtree *qt, tsr_qnode n)
{
    if (n.level >= qt->s.levels)
        return false;
    uint64_t side = 1ull << n.level;
    if (n.x >= side || n.y >= side)
        return false;
    size_t b = bit_index(n);
    return qt->split[n.level] && (qt->split[n.level][b >> 6] >> (b & 63)) & 1;
}

/* Sets the split flag; appends the node to its level's list when new.
 * Returns 1 if newly split, 0 if it already was, -1 out of memory. */
static int mark_split(tsr_quadtree *qt, tsr_qnode n)
{
    size_t b = bit_index(n);
    if (!qt->split[n.level]) {
        size_t words = (((size_t)1 << (2 * n.level)) + 63) / 64;
        qt->split[n.level] = tsr_alloc(qa(qt), words * sizeof(uint64_t));
        if (!qt->split[n.level])
            return -1;
        memset(qt->split[n.level], 0, words * sizeof(uint64_t));
    }
    uint64_t *w = &qt->split[n.level][b >> 6], m = 1ull << (b & 63);
    if (*w & m)
        return 0;
    node_list *L = &qt->lists[n.level];
    if (L->count == L->cap) {
        uint32_t cap = L->cap ? 2 * L->cap : 16;
        uint32_t *xy = tsr_realloc(qa(qt), L->xy, (size_t)cap * 2 * sizeof *xy);
        if (!xy)
            return -1;
        L->xy = xy;
        L->cap = cap;
    }
    L->xy[2 * L->count] = n.x;
    L->xy[2 * L->count + 1] = n.y;
    L->count++;
    *w |= m;
    return 1;
}

static tsr_qnode child(tsr_qnode n, unsigned k)
{
    tsr_qnode c = {2 * n.x + (k & 1), 2 * n.y + (k >> 1), (uint8_t)(n.level + 1)};
    return c;
}

static tsr_qnode parent(tsr_qnode n)
{
    tsr_qnode p = {n.x >> 1, n.y >> 1, (uint8_t)(n.level - 1)};
    return p;
}

/* Edge neighbour at the same level in direction d (0 south: y-1, 1 east:
 * x+1, 2 north: y+1, 3 west: x-1); false when outside the level's grid. */
static bool neighbour(tsr_qnode n, int d, tsr_qnode *out)
{
    int64_t x = n.x, y = n.y, side = (int64_t)1 << n.level;
    if (d == 0)
        y--;
    else if (d == 1)
        x++;
    else if (d == 2)
        y++;
    else
        x--;
    if (x < 0 || y < 0 || x >= side || y >= side)
        return false;
    out->x = (uint32_t)x;
    out->y = (uint32_t)y;
    out->level = n.level;
    return true;
}

static bool push_leaf(tsr_quadtree *qt, tsr_qnode n)
{
    if (qt->leaf_count == qt->leaf_cap) {
        uint32_t cap = qt->leaf_cap ? 2 * qt->leaf_cap : 16;
        tsr_qleaf *l = tsr_realloc(qa(qt), qt->leaves, (size_t)cap * sizeof *l);
        if (!l)
            return false;
        qt->leaves = l;
        qt->leaf_cap = cap;
    }
    tsr_qleaf *leaf = &qt->leaves[qt->leaf_count++];
    leaf->node = n;
    leaf->stitch = 0;
    leaf->culled = 0;
    leaf->morph = 0;
    return true;
}

tsr_status tsr_quadtree_select(tsr_quadtree *qt, tsr_refine_fn refine, void *user)
{
    const tsr_surface *s = &qt->s;
    /* clear the previous cut's flags, touching only what was set */
    for (uint32_t l = 0; l < s->levels; l++) {
        node_list *L = &qt->lists[l];
        for (uint32_t i = 0; i < L->count; i++) {
            tsr_qnode n = {L->xy[2 * i], L->xy[2 * i + 1], (uint8_t)l};
            size_t b = bit_index(n);
            qt->split[l][b >> 6] &= ~(1ull << (b & 63));
        }
        L->count = 0;
    }
    qt->leaf_count = 0;
    qt->balance_splits = 0;

    /* refine top-down: the level lists double as the work queues */
    tsr_qnode root = {0, 0, 0};
    if (s->levels > 0 && refine(user, s, root) && mark_split(qt, root) < 0)
        return TSR_ERR_NOMEM;
    for (uint32_t l = 0; l + 1 < s->levels; l++) {
        node_list *L = &qt->lists[l];
        for (uint32_t i = 0; i < L->count; i++) {
            tsr_qnode n = {L->xy[2 * i], L->xy[2 * i + 1], (uint8_t)l};
            for (unsigned k = 0; k < 4; k++) {
                tsr_qnode c = child(n, k);
                if (tsr_quadtree_node_exists(s, c) && refine(user, s, c) && mark_split(qt, c) < 0)
                    return TSR_ERR_NOMEM;
            }
        }
    }

    /* 2:1 balance, deepest split level first */
    for (uint32_t l = s->levels; l-- > 1;) {
        node_list *L = &qt->lists[l];
        for (uint32_t i = 0; i < L->count; i++) {
            tsr_qnode n = {L->xy[2 * i], L->xy[2 * i + 1], (uint8_t)l};
            for (int d = 0; d < 4; d++) {
                tsr_qnode q;
                if (!neighbour(n, d, &q) || !tsr_quadtree_node_exists(s, q))
                    continue;
                for (tsr_qnode p = parent(q);; p = parent(p)) {
                    int r = mark_split(qt, p);
                    if (r < 0)
                        return TSR_ERR_NOMEM;
                    qt->balance_splits += (uint32_t)r;
                    if (r == 0 || p.level == 0)
                        break;
                }
            }
        }
    }

    /* leaves and stitch masks */
    if (s->levels == 0 || !tsr_quadtree_is_split(qt, root)) {
        if (!push_leaf(qt, root))
            return TSR_ERR_NOMEM;
    } else {
        for (uint32_t l = 0; l < s->levels; l++) {
            node_list *L = &qt->lists[l];
            for (uint32_t i = 0; i < L->count; i++) {
                tsr_qnode n = {L->xy[2 * i], L->xy[2 * i + 1], (uint8_t)l};
                for (unsigned k = 0; k < 4; k++) {
                    tsr_qnode c = child(n, k);
                    if (tsr_quadtree_node_exists(s, c) && !tsr_quadtree_is_split(qt, c) && !push_leaf(qt, c))
                        return TSR_ERR_NOMEM;
                }
            }
        }
    }
    static const uint8_t bits[4] = {TSR_EDGE_SOUTH, TSR_EDGE_EAST, TSR_EDGE_NORTH, TSR_EDGE_WEST};
    for (uint32_t i = 0; i < qt->leaf_count; i++) {
        tsr_qleaf *leaf = &qt->leaves[i];
        if (leaf->node.level == 0)
            continue;
        for (int d = 0; d < 4; d++) {
            tsr_qnode q;
            if (neighbour(leaf->node, d, &q) && tsr_quadtree_node_exists(s, q) &&
                !tsr_quadtree_is_split(qt, parent(q)))
                leaf->stitch |= bits[d];
        }
    }
    return TSR_OK;
}

uint32_t tsr_quadtree_leaf_count(const tsr_quadtree *qt) { return qt->leaf_count; }
const tsr_qleaf *tsr_quadtree_leaves(const tsr_quadtree *qt) { return qt->leaves; }
uint32_t tsr_quadtree_balance_splits(const tsr_quadtree *qt) { return qt->balance_splits; }

/* ---- criteria ---------------------------------------------------------- */

bool tsr_refine_tolerance(void *tolerance_ptr, const tsr_surface *s, tsr_qnode node)
{
    return s->error(s->user, node) > *(const double *)tolerance_ptr;
}

static void cross3(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

static bool normalize3(double v[3])
{
    double l = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(l > 0) || !isfinite(l))
        return false;
    v[0] /= l;
    v[1] /= l;
    v[2] /= l;
    return true;
}

bool tsr_camera_prepare(tsr_camera *c)
{
    double f[3] = {c->target[0] - c->eye[0], c->target[1] - c->eye[1], c->target[2] - c->eye[2]};
    if (!normalize3(f) || !(c->fovy_deg > 0 && c->fovy_deg < 179) || !(c->width > 0) || !(c->height > 0) ||
        !(c->near_dist > 0))
        return false;
    /* the screen's up is +z's projection; looking (nearly) straight up or
     * down, +y's (a plan view with +y up the screen) */
    double zup[3] = {0, 0, 1}, yup[3] = {0, 1, 0}, r[3], u[3];
    cross3(f, fabs(f[2]) > 0.99999 ? yup : zup, r);
    if (!normalize3(r))
        return false;
    cross3(r, f, u);
    memcpy(c->fwd, f, sizeof f);
    memcpy(c->right, r, sizeof r);
    memcpy(c->up, u, sizeof u);
    c->tan_y = tan(c->fovy_deg * 3.14159265358979323846 / 360.0);
    c->tan_x = c->tan_y * c->width / c->height;
    c->K = c->height / (2 * c->tan_y);
    return true;
}

void tsr_camera_project(const tsr_camera *c, const double p[3], double *sx, double *sy, double *depth)
{
    double d[3] = {p[0] - c->eye[0], p[1] - c->eye[1], p[2] - c->eye[2]};
    double r = d[0] * c->right[0] + d[1] * c->right[1] + d[2] * c->right[2];
    double u = d[0] * c->up[0] + d[1] * c->up[1] + d[2] * c->up[2];
    double f = d[0] * c->fwd[0] + d[1] * c->fwd[1] + d[2] * c->fwd[2];
    *depth = f;
    *sx = c->width / 2 + c->K * r / f;
    *sy = c->height / 2 - c->K * u / f;
}

/* The 8 corners of a box in camera coordinates (r, u, f), and whether the
 * box lies wholly outside one plane of the view frustum. */
static bool box_to_camera(const tsr_camera *c, const float lo[3], const float hi[3], double rr[8], double uu[8],
                          double ff[8])
{
    int out[5] = {0};
    for (int k = 0; k < 8; k++) {
        double d[3] = {(k & 1 ? hi[0] : lo[0]) - c->eye[0], (k & 2 ? hi[1] : lo[1]) - c->eye[1],
                       (k & 4 ? hi[2] : lo[2]) - c->eye[2]};
        double r = d[0] * c->right[0] + d[1] * c->right[1] + d[2] * c->right[2];
        double u = d[0] * c->up[0] + d[1] * c->up[1] + d[2] * c->up[2];
        double f = d[0] * c->fwd[0] + d[1] * c->fwd[1] + d[2] * c->fwd[2];
        rr[k] = r;
        uu[k] = u;
        ff[k] = f;
        out[0] += f < c->near_dist;
        out[1] += r > c->tan_x * f;
        out[2] += r < -c->tan_x * f;
        out[3] += u > c->tan_y * f;
        out[4] += u < -c->tan_y * f;
    }
    return out[0] == 8 || out[1] == 8 || out[2] == 8 || out[3] == 8 || out[4] == 8;
}

/* Why this bounds the error. A sample p and the mesh point q = p + d
 * above or below it differ by d = (0, 0, e), |e| <= delta = error(node),
 * and both lie in the node's bounds. In camera coordinates (r, u, f) the
 * projections differ by
 *     pi(q) - pi(p) = K (d_r - xi_p d_f, d_u - eta_p d_f) / q_f,
 * with (xi_p, eta_p) = (p_r, p_u) / p_f, and symmetrically with p and q
 * swapped. Counted samples have both points beyond the near plane and one
 * of them, say p, inside the viewport: |xi_p| <= tan_x, |eta_p| <= tan_y,
 * and (xi_p, eta_p) also lies in the range of r/f, u/f over the bounds'
 * corners (a linear-fractional map attains its extremes over a box at the
 * corners when f > 0 there). So the error is at most
 *     K delta max |(z_r - xi z_f, z_u - eta z_f)| / max(near, min f)
 * over that (xi, eta) rectangle, z being world +z in camera coordinates;
 * the norm is convex in (xi, eta), so its maximum is at the rectangle's
 * corners. The usual K delta / z omits the factor, which reaches
 * sqrt(1 + tan_x^2 + tan_y^2) (1.54 at the corner of a 60-degree 16:9
 * view) when vertical displacements are seen obliquely near the edges,
 * and is as small as |xi| near the centre of a top-down view. For a
 * displacement d in any direction (error_isotropic), |(d_r - xi d_f,
 * d_u - eta d_f)| <= |d| sqrt(1 + xi^2 + eta^2), the largest singular
 * value of that linear map, again largest at a corner of the rectangle. */
static bool camera_box(const tsr_camera *c, const float lo[3], const float hi[3], bool isotropic, double *factor_out,
                       double *z_out)
{
    if (!(lo[0] <= hi[0] && lo[1] <= hi[1] && lo[2] <= hi[2]))
        return false;
    double rr[8], uu[8], ff[8];
    if (box_to_camera(c, lo, hi, rr, uu, ff))
        return false;
    double fmin = INFINITY, xi0 = INFINITY, xi1 = -INFINITY, eta0 = INFINITY, eta1 = -INFINITY;
    bool all_front = true;
    for (int k = 0; k < 8; k++) {
        double r = rr[k], u = uu[k], f = ff[k];
        fmin = f < fmin ? f : fmin;
        if (f > 0) {
            double xi = r / f, eta = u / f;
            xi0 = xi < xi0 ? xi : xi0;
            xi1 = xi > xi1 ? xi : xi1;
            eta0 = eta < eta0 ? eta : eta0;
            eta1 = eta > eta1 ? eta : eta1;
        } else {
            all_front = false;
        }
    }
    if (!all_front) {
        xi0 = eta0 = -INFINITY;
        xi1 = eta1 = INFINITY;
    }
    xi0 = xi0 < -c->tan_x ? -c->tan_x : xi0;
    xi1 = xi1 > c->tan_x ? c->tan_x : xi1;
    eta0 = eta0 < -c->tan_y ? -c->tan_y : eta0;
    eta1 = eta1 > c->tan_y ? c->tan_y : eta1;
    if (xi0 > xi1 || eta0 > eta1)
        return false;
    double zr = c->right[2], zu = c->up[2], zf = c->fwd[2], factor = 0;
    for (int k = 0; k < 4; k++) {
        double xi = k & 1 ? xi1 : xi0, eta = k & 2 ? eta1 : eta0;
        /* isotropic: the largest singular value of [[1, 0, -xi], [0, 1, -eta]] */
        double a = zr - xi * zf, b = zu - eta * zf,
               m = isotropic ? sqrt(1 + xi * xi + eta * eta) : sqrt(a * a + b * b);
        factor = m > factor ? m : factor;
    }
    *z_out = fmin > c->near_dist ? fmin : c->near_dist;
    *factor_out = factor;
    return true;
}

double tsr_camera_node_error(const tsr_camera *c, const tsr_surface *s, tsr_qnode node)
{
    float lo[3], hi[3];
    double factor, z;
    s->bounds(s->user, node, lo, hi);
    if (!camera_box(c, lo, hi, s->error_isotropic, &factor, &z))
        return 0;
    double delta = s->error(s->user, node);
    if (isinf(delta))
        return INFINITY;
    return c->K * delta * factor / z;
}

double tsr_camera_box_factor(const tsr_camera *c, const float lo[3], const float hi[3], bool isotropic)
{
    double factor, z;
    return camera_box(c, lo, hi, isotropic, &factor, &z) ? c->K * factor / z : 0;
}

bool tsr_refine_camera(void *camera, const tsr_surface *s, tsr_qnode node)
{
    const tsr_camera *c = camera;
    return tsr_camera_node_error(c, s, node) > c->pixel_error;
}

void tsr_quadtree_apply_camera(tsr_quadtree *qt, const tsr_camera *c)
{
    for (uint32_t i = 0; i < qt->leaf_count; i++) {
        tsr_qleaf *leaf = &qt->leaves[i];
        float lo[3], hi[3];
        qt->s.bounds(qt->s.user, leaf->node, lo, hi);
        /* culled when wholly outside one frustum plane */
        double rr[8], uu[8], ff[8];
        leaf->culled = !(lo[0] <= hi[0]) || box_to_camera(c, lo, hi, rr, uu, ff);
        /* morph: 1 when the parent's error is just above tau (the split
         * has just happened, so look like the parent), 0 from 2 tau on */
        if (leaf->node.level > 0 && c->pixel_error > 0) {
            double ep = tsr_camera_node_error(c, &qt->s, parent(leaf->node));
            double k = 2.0 - ep / c->pixel_error;
            leaf->morph = (float)(k < 0 ? 0 : k > 1 ? 1 : k);
        }
    }
}

float tsr_quadtree_vertex_morph(const tsr_qleaf *leaf, uint32_t n, uint32_t i, uint32_t j)
{
    if (i == 0 || j == 0 || i == n || j == n)
        return 0;
    if (!(i & 1) && !(j & 1))
        return 0;
    return leaf->morph;
}

/* ---- mesh ---------------------------------------------------------------- */

/* Moves leaf's odd interior vertices (those this tile made: from
 * first_new on) by its morph weight towards the mean of their two even
 * neighbours along the parent's edge or union-jack diagonal (tile.c's
 * diagonal of the parent's quad pqi, pqj: through its centre, (i-1, j-1)
 * to (i+1, j+1) when pqi + pqj is even), as terrain.vert does. Points
 * whose neighbours are clamped to the extent stay. */
static void morph_tile(const tsr_surface *s, const tsr_qleaf *leaf, const uint32_t *local, uint32_t first_new,
                       uint64_t x0, uint64_t y0, uint64_t step, tsr_mesh *m)
{
    uint32_t n = s->tile_n, row = n + 1;
    float w = leaf->morph;
    for (uint32_t j = 1; j < n; j++)
        for (uint32_t i = 1; i < n; i++) {
            if (!((i | j) & 1) || x0 + (i + 1) * step > s->extent_x || y0 + (j + 1) * step > s->extent_y)
                continue;
            uint32_t ai, aj, bi, bj;
            if (!(j & 1)) {
                ai = i - 1, aj = j, bi = i + 1, bj = j;
            } else if (!(i & 1)) {
                ai = i, aj = j - 1, bi = i, bj = j + 1;
            } else {
                uint32_t pqi = (leaf->node.x & 1) * (n / 2) + (i - 1) / 2;
                uint32_t pqj = (leaf->node.y & 1) * (n / 2) + (j - 1) / 2;
                if (!((pqi + pqj) & 1))
                    ai = i - 1, aj = j - 1, bi = i + 1, bj = j + 1;
                else
                    ai = i + 1, aj = j - 1, bi = i - 1, bj = j + 1;
            }
            uint32_t v = local[j * row + i], va = local[aj * row + ai], vb = local[bj * row + bi];
            if (v >= UINT32_MAX - 1 || va >= UINT32_MAX - 1 || vb >= UINT32_MAX - 1 || v < first_new)
                continue;
            float *z = &m->positions[3 * (size_t)v + 2];
            float target = 0.5f * (m->positions[3 * (size_t)va + 2] + m->positions[3 * (size_t)vb + 2]);
            *z = *z + (target - *z) * w;
        }
}

static tsr_status mesh_cut(const tsr_quadtree *qt, bool skip_culled, bool morph, tsr_mesh *m)
{
    const tsr_surface *s = &qt->s;
    const tsr_allocator *a = qa(qt);
    uint32_t n = s->tile_n, row = n + 1;
    tsr_tile_patterns pat;
    tsr_status st = tsr_tile_patterns_init(&pat, n, a);
    if (st != TSR_OK)
        return st;
    uint32_t *local = tsr_alloc(a, (size_t)row * row * sizeof *local);
    tsr_keymap map = {0};
    /* the vertex of each lattice point: an array while it is small (up to
     * 2^25 points, 128 MB: a 4097^2 terrain), else a hash map; the array
     * is the faster by far (no hashing, no probing, no rehash) */
    uint64_t lattice = ((uint64_t)s->extent_x + 1) * ((uint64_t)s->extent_y + 1);
    uint32_t *dense = lattice <= (1u << 25) ? tsr_alloc(a, (size_t)lattice * sizeof *dense) : NULL;
    if (dense)
        memset(dense, 0xff, (size_t)lattice * sizeof *dense);
    if (!local) {
        tsr_free(a, dense);
        tsr_tile_patterns_free(&pat);
        return TSR_ERR_NOMEM;
    }
    bool normals = (m->attributes & TSR_MESH_NORMALS) != 0;
    uint32_t first = m->vertex_count;
    for (uint32_t li = 0; li < qt->leaf_count && st == TSR_OK; li++) {
        const tsr_qleaf *leaf = &qt->leaves[li];
        if (skip_culled && leaf->culled)
            continue;
        uint64_t w = (uint64_t)n << (s->levels - leaf->node.level), step = w / n;
        uint64_t x0 = leaf->node.x * w, y0 = leaf->node.y * w;
        uint32_t first_new = m->vertex_count;
        for (uint32_t j = 0; j <= n && st == TSR_OK; j++)
            for (uint32_t i = 0; i <= n; i++) {
                uint64_t gi = x0 + i * step, gj = y0 + j * step;
                gi = gi > s->extent_x ? s->extent_x : gi;
                gj = gj > s->extent_y ? s->extent_y : gj;
                bool found;
                uint64_t key = gj * ((uint64_t)s->extent_x + 1) + gi;
                uint32_t *slot = dense ? &dense[key] : tsr_keymap_slot(&map, key, &found, a);
                if (dense)
                    found = *slot != UINT32_MAX;
                if (!slot) {
                    st = TSR_ERR_NOMEM;
                    break;
                }
                if (!found) {
                    float p[3], nr[3];
                    bool ok = s->evaluate(s->user, (uint32_t)gi, (uint32_t)gj, p, normals ? nr : NULL);
                    *slot = ok ? tsr_mesh_add_vertex(m, p, normals ? nr : NULL, NULL) : UINT32_MAX - 1;
                    if (*slot == UINT32_MAX) {
                        st = TSR_ERR_NOMEM;
                        break;
                    }
                }
                local[j * row + i] = *slot;
            }
        if (morph && leaf->morph > 0 && leaf->node.level > 0 && st == TSR_OK)
            morph_tile(s, leaf, local, first_new, x0, y0, step, m);
        const uint32_t *tri = pat.tri[leaf->stitch & 15];
        for (uint32_t t = 0; t < pat.count[leaf->stitch & 15] && st == TSR_OK; t++) {
            uint32_t va = local[tri[3 * t]], vb = local[tri[3 * t + 1]], vc = local[tri[3 * t + 2]];
            if (va >= UINT32_MAX - 1 || vb >= UINT32_MAX - 1 || vc >= UINT32_MAX - 1 || va == vb || vb == vc ||
                va == vc)
                continue;
            if (!tsr_mesh_add_triangle(m, va, vb, vc))
                st = TSR_ERR_NOMEM;
        }
    }
    /* the tiles' points no triangle uses: stitched away, or with a no-data
     * neighbour on every side */
    if (st == TSR_OK && tsr_mesh_drop_unused(m, first) == UINT32_MAX)
        st = TSR_ERR_NOMEM;
    tsr_free(a, local);
    tsr_free(a, dense);
    tsr_keymap_free(&map, a);
    tsr_tile_patterns_free(&pat);
    return st;
}

tsr_status tsr_quadtree_mesh(const tsr_quadtree *qt, bool skip_culled, tsr_mesh *m)
{
    return mesh_cut(qt, skip_culled, false, m);
}

tsr_status tsr_quadtree_mesh_geomorphed(const tsr_quadtree *qt, bool skip_culled, tsr_mesh *m)
{
    return mesh_cut(qt, skip_culled, true, m);
}

bool tsr_quadtree_leaves_balanced(const tsr_quadtree *qt)
{
    const tsr_surface *s = &qt->s;
    size_t side = (size_t)1 << s->levels;
    signed char *lev = tsr_alloc(qa(qt), side * side);
    if (!lev)
        return false;
    memset(lev, -1, side * side);
    for (uint32_t i = 0; i < qt->leaf_count; i++) {
        tsr_qnode n = qt->leaves[i].node;
        size_t span = (size_t)1 << (s->levels - n.level);
        for (size_t y = n.y * span; y < (n.y + 1) * span; y++)
            memset(lev + y * side + n.x * span, n.level, span);
    }
    bool ok = true;
    for (size_t y = 0; y < side && ok; y++)
        for (size_t x = 0; x < side; x++) {
            int a = lev[y * side + x];
            if (a < 0)
                continue;
            int r = x + 1 < side ? lev[y * side + x + 1] : -1, u = y + 1 < side ? lev[(y + 1) * side + x] : -1;
            if ((r >= 0 && abs(a - r) > 1) || (u >= 0 && abs(a - u) > 1)) {
                ok = false;
                break;
            }
        }
    tsr_free(qa(qt), lev);
    return ok;
}
