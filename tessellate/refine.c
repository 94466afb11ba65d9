/* refine.c: conforming and quality Delaunay refinement.
 *
 * Ruppert's algorithm (J. Ruppert, "A Delaunay refinement algorithm for
 * quality 2-dimensional mesh generation", J. Algorithms 1995) as refined
 * by Shewchuk ("Delaunay refinement algorithms for triangular mesh
 * generation", CGTA 2002):
 *  - a constrained edge is encroached when the apex of a triangle beside
 *    it (inside the domain) lies strictly inside its diametral circle; in
 *    a constrained Delaunay triangulation that is the only vertex that
 *    needs testing. Encroached edges are split first;
 *  - an edge with exactly one end at an "apex" vertex (one not made by
 *    splitting a segment: an input vertex or a segment crossing) is split where a circle of power-of-two radius
 *    around that end cuts it ("concentric shells"), so that splits on two
 *    segments meeting at a small angle stay at equal distances and do not
 *    chase each other; other edges are split at the midpoint;
 *  - a bad triangle (smallest angle below the bound, or area above the
 *    maximum) gets a vertex at its circumcentre, unless the circumcentre
 *    would encroach a constrained edge (then those edges are split and the
 *    triangle waits) or lies behind one (the walk towards it meets a
 *    constrained edge first; that edge is split);
 *  - the terminator: a triangle whose shortest edge joins points on two
 *    segments that share an input vertex, where they meet at less than
 *    60 degrees, is left alone (it cannot be improved without an endless
 *    cascade) and counted in small_angle_exempt.
 * Only triangles with tf 0 (the domain) are refined; the domain's
 * boundary is constrained, so walks and flips never leave it. */
#include "tessellate/cdt_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define P cdt_P

typedef struct refiner {
    tsr_cdt *d;
    const tsr_tri_options *opt;
    uint32_t ninput;
    double cos_min; /* cosine of the minimum angle; 2 when none */
    uint32_t *vend; /* per vertex: see on_segment */
    uint32_t cap_vend;
    uint32_t *tq; /* bad triangle queue: slot, v0, v1, v2 */
    uint32_t ntq, cap_tq, htq;
    uint32_t *sq; /* segment queue: slot, from, to */
    uint32_t nsq, cap_sq, hsq;
    uint32_t *cav; /* scratch: cavity */
    uint32_t ncav, cap_cav;
    uint32_t steiner, limit;
    tsr_triangulation *res;
} refiner;

static bool in_domain(const refiner *r, uint32_t t)
{
    return !r->d->tf[t];
}

static double dot_at(const double *c, const double *u, const double *w)
{
    return (u[0] - c[0]) * (w[0] - c[0]) + (u[1] - c[1]) * (w[1] - c[1]);
}

/* Ends of the original segment (or boundary edge) a vertex made by a
 * segment split lies on; (0, 0) for the other vertices ("apexes"). */
static bool on_segment(const refiner *r, uint32_t v)
{
    return v < r->cap_vend && r->vend[2 * (size_t)v];
}

static bool set_vend(refiner *r, uint32_t v, uint32_t e0, uint32_t e1)
{
    if (v >= r->cap_vend) {
        uint32_t cap = r->cap_vend ? r->cap_vend : 1024;
        while (cap <= v)
            cap *= 2;
        uint32_t *a = tsr_realloc(tsr__cdt_alloc(r->d), r->vend, 2 * (size_t)cap * sizeof *a);
        if (!a)
            return false;
        memset(a + 2 * (size_t)r->cap_vend, 0, 2 * (size_t)(cap - r->cap_vend) * sizeof *a);
        r->vend = a;
        r->cap_vend = cap;
    }
    r->vend[2 * (size_t)v] = e0;
    r->vend[2 * (size_t)v + 1] = e1;
    return true;
}

/* The original segment's ends of the sub-edge u-w. */
static void original_ends(const refiner *r, uint32_t u, uint32_t w, uint32_t e[2])
{
    if (on_segment(r, u)) {
        e[0] = r->vend[2 * (size_t)u];
        e[1] = r->vend[2 * (size_t)u + 1];
    } else if (on_segment(r, w)) {
        e[0] = r->vend[2 * (size_t)w];
        e[1] = r->vend[2 * (size_t)w + 1];
    } else {
        e[0] = u;
        e[1] = w;
    }
}

/* Is edge k of t (constrained) encroached by the apex on either side? */
static bool encroached(const refiner *r, uint32_t t, int k)
{
    const tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    const double *u = P(d, v[k]), *w = P(d, v[(k + 1) % 3]);
    if (in_domain(r, t) && dot_at(P(d, v[(k + 2) % 3]), u, w) < 0)
        return true;
    uint32_t s = d->tn[3 * (size_t)t + k];
    if (!in_domain(r, s) || cdt_is_ghost(d, s))
        return false;
    const uint32_t *x = d->tv + 3 * (size_t)s;
    uint32_t q = x[0] != v[k] && x[0] != v[(k + 1) % 3] ? x[0] : x[1] != v[k] && x[1] != v[(k + 1) % 3] ? x[1] : x[2];
    return dot_at(P(d, q), u, w) < 0;
}

/* Bad: 1 for quality (smallest angle), 2 for area, 0 good. Exempt
 * (terminator) triangles are 0 and counted when count is set. */
static int bad(refiner *r, uint32_t t, bool count)
{
    const tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    const double *p[3] = {P(d, v[0]), P(d, v[1]), P(d, v[2])};
    double l[3]; /* l[k]: squared length of edge k (from v[k] to v[k+1]) */
    for (int k = 0; k < 3; k++) {
        double dx = p[(k + 1) % 3][0] - p[k][0], dy = p[(k + 1) % 3][1] - p[k][1];
        l[k] = dx * dx + dy * dy;
    }
    if (r->opt->max_area > 0) {
        double area = 0.5 * tsr_orient2d(p[0], p[1], p[2]);
        if (area > r->opt->max_area)
            return 2;
    }
    if (r->cos_min > 1)
        return 0;
    int s = l[0] <= l[1] && l[0] <= l[2] ? 0 : l[1] <= l[2] ? 1 : 2; /* shortest edge */
    double b2 = l[(s + 1) % 3], c2 = l[(s + 2) % 3];
    double cosa = (b2 + c2 - l[s]) / (2 * sqrt(b2 * c2));
    if (!(cosa > r->cos_min))
        return 0;
    /* terminator: the shortest edge joins two segments meeting at a small
     * input angle */
    uint32_t pa = v[s], pb = v[(s + 1) % 3];
    if (on_segment(r, pa) && on_segment(r, pb)) {
        const uint32_t *ea = r->vend + 2 * (size_t)pa, *eb = r->vend + 2 * (size_t)pb;
        for (int i = 0; i < 2; i++)
            for (int j = 0; j < 2; j++)
                if (ea[i] == eb[j] && ea[1 - i] != eb[1 - j]) {
                    const double *o = P(d, ea[i]), *x = P(d, ea[1 - i]), *y = P(d, eb[1 - j]);
                    double dxo = x[0] - o[0], dyo = x[1] - o[1], exo = y[0] - o[0], eyo = y[1] - o[1];
                    double c = (dxo * exo + dyo * eyo) / sqrt((dxo * dxo + dyo * dyo) * (exo * exo + eyo * eyo));
                    if (c > 0.5) { /* below 60 degrees */
                        if (count)
                            r->res->small_angle_exempt++;
                        return 0;
                    }
                }
    }
    return 1;
}

static bool push_tri(refiner *r, uint32_t t)
{
    const uint32_t *v = r->d->tv + 3 * (size_t)t;
    return tsr__cdt_append(r->d, &r->tq, &r->ntq, &r->cap_tq, t) &&
           tsr__cdt_append(r->d, &r->tq, &r->ntq, &r->cap_tq, v[0]) &&
           tsr__cdt_append(r->d, &r->tq, &r->ntq, &r->cap_tq, v[1]) &&
           tsr__cdt_append(r->d, &r->tq, &r->ntq, &r->cap_tq, v[2]);
}

static bool push_seg(refiner *r, uint32_t t, int k)
{
    const uint32_t *v = r->d->tv + 3 * (size_t)t;
    return tsr__cdt_append(r->d, &r->sq, &r->nsq, &r->cap_sq, t) &&
           tsr__cdt_append(r->d, &r->sq, &r->nsq, &r->cap_sq, v[k]) &&
           tsr__cdt_append(r->d, &r->sq, &r->nsq, &r->cap_sq, v[(k + 1) % 3]);
}

/* Looks at what the last operation wrote: new bad triangles and
 * encroached constrained edges join the queues. */
static bool take_changes(refiner *r)
{
    tsr_cdt *d = r->d;
    uint32_t n;
    const uint32_t *ch = tsr_cdt_changes(d, &n);
    bool ok = true;
    for (uint32_t i = 0; i < n && ok; i++) {
        uint32_t t = ch[i];
        if (!in_domain(r, t) || cdt_is_ghost(d, t))
            continue;
        for (int k = 0; k < 3 && ok; k++)
            if (cdt_mark(d, t, k) && encroached(r, t, k))
                ok = push_seg(r, t, k);
        if (ok && bad(r, t, false))
            ok = push_tri(r, t);
    }
    tsr_cdt_clear_changes(d);
    return ok;
}

/* Splits constrained edge k of t. Returns 1 split, 0 could not (a sliver
 * below the resolution of doubles), -1 out of memory. */
static int split_segment(refiner *r, uint32_t t, int k)
{
    tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t u = v[k], w = v[(k + 1) % 3], ends[2];
    original_ends(r, u, w, ends);
    const double *U = P(d, u), *W = P(d, w);
    bool apex_u = !on_segment(r, u), apex_w = !on_segment(r, w);
    double len = hypot(W[0] - U[0], W[1] - U[1]);
    double f = 0.5;
    if (apex_u != apex_w) {
        double shell = exp2(nearbyint(log2(0.5 * len)));
        f = apex_u ? shell / len : 1 - shell / len;
    }
    double tries[2] = {f, 0.5};
    for (int i = 0; i < (f == 0.5 ? 1 : 2); i++) {
        U = P(d, u), W = P(d, w);
        double x = U[0] + tries[i] * (W[0] - U[0]), y = U[1] + tries[i] * (W[1] - U[1]);
        if (tries[i] == 0.5) {
            x = 0.5 * (U[0] + W[0]);
            y = 0.5 * (U[1] + W[1]);
        }
        uint32_t pv = tsr__cdt_add_vertex(d, x, y);
        if (pv == CDT_NONE)
            return -1;
        bool nomem;
        if (tsr__cdt_split_edge(d, t, k, pv, &nomem)) {
            r->steiner++;
            if (!set_vend(r, pv, ends[0], ends[1]))
                return -1;
            return take_changes(r) ? 1 : -1;
        }
        d->nv--;
        if (nomem)
            return -1;
    }
    return 0;
}

/* Walks from the centroid of t towards c, not crossing constrained edges.
 * Returns the triangle holding c, or CDT_NONE with (*block_t, *block_k) the
 * constrained edge in the way. */
static uint32_t walk_to(refiner *r, uint32_t t, const double c[2], uint32_t *block_t, int *block_k)
{
    tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    double s0[2] = {(P(d, v[0])[0] + P(d, v[1])[0] + P(d, v[2])[0]) / 3,
                    (P(d, v[0])[1] + P(d, v[1])[1] + P(d, v[2])[1]) / 3};
    for (uint32_t steps = 0; steps <= d->nt; steps++) {
        v = d->tv + 3 * (size_t)t;
        int exit = -1;
        for (int k = 0; k < 3 && exit < 0; k++) {
            const double *a = P(d, v[k]), *b = P(d, v[(k + 1) % 3]);
            if (tsr_orient2d(a, b, c) < 0 && tsr_orient2d(s0, c, a) <= 0 && tsr_orient2d(s0, c, b) >= 0)
                exit = k;
        }
        if (exit < 0)
            return t;
        if (cdt_mark(d, t, exit)) {
            *block_t = t;
            *block_k = exit;
            return CDT_NONE;
        }
        t = d->tn[3 * (size_t)t + exit];
        if (cdt_is_ghost(d, t) || !in_domain(r, t))
            break; /* cannot happen: the domain is closed by marks */
    }
    *block_t = CDT_NONE;
    return CDT_NONE;
}

/* Handles bad triangle t: returns 1 when something changed, 0 when the
 * triangle is left as it is, -1 out of memory. */
static int split_triangle(refiner *r, uint32_t t)
{
    tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    const double *a = P(d, v[0]), *b = P(d, v[1]), *cc = P(d, v[2]);
    double bx = b[0] - a[0], by = b[1] - a[1], cx = cc[0] - a[0], cy = cc[1] - a[1];
    double det = 2 * tsr_orient2d(a, b, cc), bl = bx * bx + by * by, cl = cx * cx + cy * cy;
    double c[2] = {a[0] + (cy * bl - by * cl) / det, a[1] + (bx * cl - cx * bl) / det};
    if (!isfinite(c[0]) || !isfinite(c[1]))
        return 0;
    uint32_t bt = CDT_NONE;
    int bk = 0;
    uint32_t home = walk_to(r, t, c, &bt, &bk);
    if (home == CDT_NONE) {
        if (bt == CDT_NONE)
            return 0;
        int s = split_segment(r, bt, bk);
        return s < 0 ? -1 : s > 0 ? (push_tri(r, t) ? 1 : -1) : 0;
    }
    /* the cavity: would c encroach a constrained edge on its boundary? */
    r->ncav = 0;
    if (!tsr__cdt_append(d, &r->cav, &r->ncav, &r->cap_cav, home))
        return -1;
    uint32_t enc_t[8];
    int enc_k[8], nenc = 0;
    for (uint32_t i = 0; i < r->ncav && nenc < 8; i++) {
        uint32_t x = r->cav[i];
        const uint32_t *w = d->tv + 3 * (size_t)x;
        for (int k = 0; k < 3; k++) {
            if (cdt_mark(d, x, k)) {
                if (dot_at(c, P(d, w[k]), P(d, w[(k + 1) % 3])) < 0 && nenc < 8) {
                    enc_t[nenc] = x;
                    enc_k[nenc++] = k;
                }
                continue;
            }
            uint32_t n = d->tn[3 * (size_t)x + k];
            if (cdt_is_ghost(d, n) || !in_domain(r, n))
                continue;
            bool seen = false;
            for (uint32_t j = 0; j < r->ncav && !seen; j++)
                seen = r->cav[j] == n;
            const uint32_t *nv = d->tv + 3 * (size_t)n;
            if (!seen && r->ncav < 64 && tsr_incircle(P(d, nv[0]), P(d, nv[1]), P(d, nv[2]), c) > 0 &&
                !tsr__cdt_append(d, &r->cav, &r->ncav, &r->cap_cav, n))
                return -1;
        }
    }
    if (nenc > 0) {
        /* split the first; the others are found again through the queue */
        int s = split_segment(r, enc_t[0], enc_k[0]);
        if (s < 0)
            return -1;
        if (s == 0)
            return 0;
        return push_tri(r, t) ? 1 : -1;
    }
    const uint32_t *w = d->tv + 3 * (size_t)home;
    double o[3];
    for (int k = 0; k < 3; k++)
        o[k] = tsr_orient2d(P(d, w[k]), P(d, w[(k + 1) % 3]), c);
    int zeros = (o[0] == 0) + (o[1] == 0) + (o[2] == 0);
    if (zeros > 1)
        return 0; /* on a vertex: cannot happen for an empty circumcircle */
    int kind = zeros ? CDT_ON_EDGE : CDT_IN_TRIANGLE, which = o[0] == 0 ? 0 : o[1] == 0 ? 1 : 2;
    if (kind == CDT_ON_EDGE && cdt_mark(d, home, which))
        return 0; /* on a constrained edge: it would have been encroached */
    uint32_t pv = tsr__cdt_add_vertex(d, c[0], c[1]);
    if (pv == CDT_NONE || tsr__cdt_insert_at(d, pv, home, kind, which) == CDT_NONE)
        return -1;
    r->steiner++;
    return take_changes(r) ? 1 : -1;
}

tsr_status tsr__cdt_refine(tsr_cdt *d, const tsr_tri_options *opt, uint32_t ninput, const uint32_t *segends,
                           uint32_t nseg, tsr_triangulation *res)
{
    refiner r = {0};
    r.d = d;
    r.opt = opt;
    r.ninput = ninput;
    (void)segends, (void)nseg;
    r.res = res;
    r.cos_min = opt->min_angle > 0 ? cos(opt->min_angle * (3.14159265358979323846 / 180)) : 2;
    double area = 0;
    for (uint32_t t = 0; t < d->nt; t++)
        if (in_domain(&r, t) && !cdt_is_ghost(d, t)) {
            const uint32_t *v = d->tv + 3 * (size_t)t;
            area += 0.5 * tsr_orient2d(P(d, v[0]), P(d, v[1]), P(d, v[2]));
        }
    double limit = opt->max_steiner ? opt->max_steiner : 20.0 * (d->nv - 1) + 100000;
    if (!opt->max_steiner && opt->max_area > 0)
        limit += 4 * area / opt->max_area;
    r.limit = limit > UINT32_MAX / 4 ? UINT32_MAX / 4 : (uint32_t)limit;
    tsr_status st = TSR_ERR_NOMEM;
    bool was_tracking = d->track;
    tsr_cdt_track_changes(d, true);
    /* every triangle of the domain is "changed" to begin with */
    for (uint32_t t = 0; t < d->nt; t++)
        if (!tsr__cdt_append(d, &d->changed, &d->nchanged, &d->cap_changed, t))
            goto done;
    if (!take_changes(&r))
        goto done;
    bool quality = opt->min_angle > 0 || opt->max_area > 0;
    for (;;) {
        if (r.steiner >= r.limit) {
            res->quality_limited = true;
            break;
        }
        if (r.hsq < r.nsq) {
            uint32_t t = r.sq[r.hsq], u = r.sq[r.hsq + 1], w = r.sq[r.hsq + 2];
            r.hsq += 3;
            const uint32_t *v = d->tv + 3 * (size_t)t;
            int k = v[0] == u && v[1] == w ? 0 : v[1] == u && v[2] == w ? 1 : v[2] == u && v[0] == w ? 2 : -1;
            if (k < 0 || !cdt_mark(d, t, k) || !encroached(&r, t, k))
                continue;
            if (split_segment(&r, t, k) < 0)
                goto done;
            continue;
        }
        if (quality && r.htq < r.ntq) {
            uint32_t t = r.tq[r.htq];
            const uint32_t *v = d->tv + 3 * (size_t)t;
            bool fresh = v[0] == r.tq[r.htq + 1] && v[1] == r.tq[r.htq + 2] && v[2] == r.tq[r.htq + 3];
            r.htq += 4;
            if (r.htq > (1u << 20) && r.htq * 2 > r.ntq) { /* compact the queue */
                memmove(r.tq, r.tq + r.htq, (size_t)(r.ntq - r.htq) * sizeof *r.tq);
                r.ntq -= r.htq;
                r.htq = 0;
            }
            if (!fresh || !in_domain(&r, t) || !bad(&r, t, false))
                continue;
            if (split_triangle(&r, t) < 0)
                goto done;
            continue;
        }
        break;
    }
    /* count what stays bad because of small input angles */
    if (opt->min_angle > 0)
        for (uint32_t t = 0; t < d->nt; t++)
            if (in_domain(&r, t) && !cdt_is_ghost(d, t))
                (void)bad(&r, t, true);
    st = TSR_OK;
done:
    tsr_cdt_track_changes(d, was_tracking);
    const tsr_allocator *a = tsr__cdt_alloc(d);
    tsr_free(a, r.vend);
    tsr_free(a, r.tq);
    tsr_free(a, r.sq);
    tsr_free(a, r.cav);
    return st;
}
