/* refine.c: conforming and quality Delaunay refinement.
 *
 * Ruppert's algorithm (J. Ruppert, "A Delaunay refinement algorithm for
 * quality 2-dimensional mesh generation", J. Algorithms 1995) as refined
 * by Shewchuk ("Delaunay refinement algorithms for triangular mesh
 * generation", CGTA 2002), with Ungor's off-centres (A. Ungor, "Off-centers:
 * a new type of Steiner points for computing size-optimal quality-
 * guaranteed Delaunay triangulations", LATIN 2004):
 *  - conforming: a constrained edge is encroached when the apex of a
 *    triangle beside it (inside the domain) lies strictly inside its
 *    diametral circle (in a constrained Delaunay triangulation that is the
 *    only vertex that needs testing); encroached edges are split first,
 *    since every edge must end up Delaunay;
 *  - quality (not conforming): the output only has to be constrained
 *    Delaunay, so an edge is split only when a bad triangle needs it (as in
 *    Chew's second algorithm): when the new vertex would lie behind it (the
 *    walk towards the vertex meets it first) or inside its diametral lens
 *    (seen from the vertex at more than 180 - 2 min_angle degrees). Eager
 *    splitting of every encroached edge makes two close features that meet
 *    at a small angle, or none, split each other in turn down to the
 *    resolution of doubles;
 *  - where an edge is cut: see split_segment (concentric shells around
 *    small input angles, staggered cuts along thin strips, else midpoints);
 *  - a bad triangle (smallest angle below the bound, or area above the
 *    maximum) gets a vertex at its circumcentre, or at its off-centre when
 *    that is nearer its shortest edge; the worst-shaped triangle goes
 *    first;
 *  - the terminator (see edge_excused): a skinny triangle caused by a
 *    small input angle is left alone, by the same rule as the independent
 *    checker's (tricheck.c) so that what is left is what the checker
 *    excuses (counted in small_angle_exempt); so is one below the
 *    resolution of doubles (tsr_tri_below_resolution, the definition the
 *    checker uses: features closer than a few units in the last place that
 *    do not meet, where no vertex can go between them), counted in
 *    below_resolution and reported by quality_limited, since the bound is
 *    not met there.
 * Only triangles inside the domain (tf not CDT_OUTSIDE) are refined; the
 * domain's boundary is constrained, so walks and flips never leave it. A
 * triangle of a region (tf >= CDT_REGION0) has the smaller of max_area and
 * its region's bound (area_bound). */
#include "tessellate/cdt_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define P cdt_P

typedef struct qent {
    double key;
    uint32_t t, v[3];
} qent;

typedef struct refiner {
    tsr_cdt *d;
    const tsr_tri_options *opt;
    uint32_t ninput;
    double cos_min; /* cosine of the minimum angle; 2 when none */
    uint32_t *vend; /* per vertex: see on_segment */
    uint32_t cap_vend;
    qent *hq; /* bad triangles: a heap on key (tri_key) */
    uint32_t nhq, cap_hq;
    uint32_t *sq; /* segment queue: slot, from, to */
    uint32_t nsq, cap_sq, hsq;
    uint32_t *cav; /* scratch: cavity */
    uint32_t ncav, cap_cav;
    uint32_t steiner, limit;
    /* the features (constrained edges of the domain between apexes, as
     * they were before refinement) through each apex vertex v < nv0:
     * their other ends fto[foff[v] .. foff[v + 1]) */
    uint32_t nv0, *foff, *fto;
    bool eager;     /* split every encroached subsegment (conforming) */
    double off;     /* off-centre height over the shortest edge; 0: none */
    double cot_min; /* cotangent of the minimum angle; 0 when none */
    tsr_triangulation *res;
} refiner;

static bool in_domain(const refiner *r, uint32_t t)
{
    return r->d->tf[t] != CDT_OUTSIDE;
}

/* The bound on triangle t's area: max_area, or its region's when smaller
 * (0: none). */
static double area_bound(const refiner *r, uint32_t t)
{
    double b = r->opt->max_area;
    uint32_t f = r->d->tf[t];
    if (f >= CDT_REGION0) {
        double rb = r->opt->regions[3 * (size_t)(f - CDT_REGION0) + 2];
        if (rb > 0 && !(b > 0 && b <= rb))
            b = rb;
    }
    return b;
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

/* A feature: an input segment or domain boundary piece between two apexes,
 * by its end vertices. */
typedef struct feature {
    uint32_t a, b;
} feature;

#define MAX_FEATURES 64

/* The features through vertex v (at most cap): a segment vertex lies on
 * the one it was split from, an apex on all that end at it. */
static uint32_t features_at(const refiner *r, uint32_t v, feature *f, uint32_t cap)
{
    if (on_segment(r, v)) {
        f[0] = (feature){r->vend[2 * (size_t)v], r->vend[2 * (size_t)v + 1]};
        return 1;
    }
    if (v >= r->nv0 || !r->foff)
        return 0;
    uint32_t n = 0;
    for (uint32_t i = r->foff[v]; i < r->foff[v + 1] && n < cap; i++)
        f[n++] = (feature){v, r->fto[i]};
    return n;
}

static bool same_feature(feature f, feature g)
{
    return (f.a == g.a && f.b == g.b) || (f.a == g.b && f.b == g.a);
}

static bool has_feature(const feature *f, uint32_t n, feature g)
{
    for (uint32_t i = 0; i < n; i++)
        if (same_feature(f[i], g))
            return true;
    return false;
}

/* Do two distinct features meet at an angle below 60 degrees? Features
 * never cross (they are edges of the triangulation before refinement, a
 * crossing being an apex), so they meet only at a shared end. The margin
 * keeps this a subset of the checker's rule (tricheck.c's small_meeting),
 * which measures the same angle between the input segments. */
static bool small_meeting(const refiner *r, feature f, feature g)
{
    uint32_t o, x, y;
    if (f.a == g.a)
        o = f.a, x = f.b, y = g.b;
    else if (f.a == g.b)
        o = f.a, x = f.b, y = g.a;
    else if (f.b == g.a)
        o = f.b, x = f.a, y = g.b;
    else if (f.b == g.b)
        o = f.b, x = f.a, y = g.a;
    else
        return false;
    if (x == y)
        return false;
    const double *po = P(r->d, o), *px = P(r->d, x), *py = P(r->d, y);
    double ux = px[0] - po[0], uy = px[1] - po[1], wx = py[0] - po[0], wy = py[1] - po[1];
    double c = (ux * wx + uy * wy) / sqrt((ux * ux + uy * uy) * (wx * wx + wy * wy));
    return c > 0.5 + 1e-9;
}

/* The terminator, the same rule as the checker's excuse (tricheck.c): a
 * skinny triangle is left alone when its shortest edge pa-pb joins a
 * vertex on feature f1 and one on feature f2 where f1 and f2 meet at a
 * small angle (Shewchuk's terminator, Miller-Pav-Walkington: the triangle
 * subtends a small input angle; splitting it only moves the problem
 * closer to the apex), or when all three corners lie on two such features
 * with the shortest edge's ends on them (the triangle lies inside the
 * small wedge; vertices put inside the wedge would only make smaller
 * wedge triangles). */
static bool edge_excused(const refiner *r, uint32_t pa, uint32_t pb, uint32_t pc)
{
    feature fa[MAX_FEATURES], fb[MAX_FEATURES], fc[MAX_FEATURES];
    uint32_t na = features_at(r, pa, fa, MAX_FEATURES), nb = features_at(r, pb, fb, MAX_FEATURES);
    if (!na && !nb)
        return false;
    for (uint32_t i = 0; i < na; i++)
        for (uint32_t j = 0; j < nb; j++)
            if (!same_feature(fa[i], fb[j]) && small_meeting(r, fa[i], fb[j]))
                return true;
    uint32_t nc = features_at(r, pc, fc, MAX_FEATURES);
    for (uint32_t i = 0; i < nc; i++)
        for (uint32_t j = 0; j < na + nb; j++) {
            feature g = j < na ? fa[j] : fb[j - na];
            if (same_feature(fc[i], g) || !small_meeting(r, fc[i], g))
                continue;
            if ((has_feature(fa, na, fc[i]) || has_feature(fa, na, g)) &&
                (has_feature(fb, nb, fc[i]) || has_feature(fb, nb, g)))
                return true;
        }
    return false;
}

/* Bad: 1 for quality (smallest angle), 2 for area, 0 good. Exempt
 * triangles (the terminator, or below the resolution of doubles) are 0
 * and counted when count is set: in small_angle_exempt (the terminator,
 * which the contract allows) or below_resolution (which sets
 * quality_limited: the bound is not met there). */
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
    double area2 = tsr_orient2d(p[0], p[1], p[2]), bound = area_bound(r, t);
    if (bound > 0 && 0.5 * area2 > bound)
        return 2;
    if (r->cos_min > 1)
        return 0;
    int s = l[0] <= l[1] && l[0] <= l[2] ? 0 : l[1] <= l[2] ? 1 : 2; /* shortest edge */
    double b2 = l[(s + 1) % 3], c2 = l[(s + 2) % 3];
    double cosa = (b2 + c2 - l[s]) / (2 * sqrt(b2 * c2));
    if (!(cosa > r->cos_min))
        return 0;
    /* the terminator; where the shortest edge is tied, the checker may
     * take either, so each must be excused */
    bool excused = true;
    for (int k = 0; k < 3 && excused; k++)
        if (l[k] == l[s])
            excused = edge_excused(r, v[k], v[(k + 1) % 3], v[(k + 2) % 3]);
    if (excused) {
        if (count)
            r->res->small_angle_exempt++;
        return 0;
    }
    /* below the resolution of doubles (the checker's definition): a vertex
     * closer to the opposite edge than a few units in the last place of the
     * coordinates (features of the input nearer than that, not meeting)
     * cannot be separated by vertices between them; splitting would
     * cascade until the Steiner limit */
    if (!tsr_tri_below_resolution(p[0], p[1], p[2]))
        return 1;
    if (count)
        r->res->below_resolution++;
    return 0;
}

/* The queue's order: the worst-shaped triangle first (the cosine of its
 * smallest angle, negated); for area alone, the largest first. Splitting
 * the worst first gives fewer Steiner points (a fifth fewer on thin
 * strips than first come, first served): its new vertex often repairs
 * the milder triangles around it too. */
static double tri_key(const refiner *r, uint32_t t)
{
    const uint32_t *v = r->d->tv + 3 * (size_t)t;
    const double *p[3] = {P(r->d, v[0]), P(r->d, v[1]), P(r->d, v[2])};
    if (r->cos_min > 1)
        return -tsr_orient2d(p[0], p[1], p[2]);
    double l[3];
    for (int k = 0; k < 3; k++) {
        double dx = p[(k + 1) % 3][0] - p[k][0], dy = p[(k + 1) % 3][1] - p[k][1];
        l[k] = dx * dx + dy * dy;
    }
    int s = l[0] <= l[1] && l[0] <= l[2] ? 0 : l[1] <= l[2] ? 1 : 2;
    double b2 = l[(s + 1) % 3], c2 = l[(s + 2) % 3];
    return -(b2 + c2 - l[s]) / (2 * sqrt(b2 * c2));
}

static bool push_tri(refiner *r, uint32_t t)
{
    if (r->nhq == r->cap_hq) {
        uint32_t cap = r->cap_hq ? 2 * r->cap_hq : 1024;
        qent *q = tsr_realloc(tsr__cdt_alloc(r->d), r->hq, (size_t)cap * sizeof *q);
        if (!q)
            return false;
        r->hq = q;
        r->cap_hq = cap;
    }
    const uint32_t *v = r->d->tv + 3 * (size_t)t;
    qent e = {tri_key(r, t), t, {v[0], v[1], v[2]}};
    uint32_t i = r->nhq++;
    while (i > 0 && r->hq[(i - 1) / 2].key > e.key) {
        r->hq[i] = r->hq[(i - 1) / 2];
        i = (i - 1) / 2;
    }
    r->hq[i] = e;
    return true;
}

static qent pop_tri(refiner *r)
{
    qent top = r->hq[0], e = r->hq[--r->nhq];
    uint32_t i = 0, n = r->nhq;
    for (;;) {
        uint32_t c = 2 * i + 1;
        if (c >= n)
            break;
        if (c + 1 < n && r->hq[c + 1].key < r->hq[c].key)
            c++;
        if (!(r->hq[c].key < e.key))
            break;
        r->hq[i] = r->hq[c];
        i = c;
    }
    if (n)
        r->hq[i] = e;
    return top;
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
        for (int k = 0; k < 3 && ok && r->eager; k++)
            if (cdt_mark(d, t, k) && encroached(r, t, k))
                ok = push_seg(r, t, k);
        if (ok && bad(r, t, false))
            ok = push_tri(r, t);
    }
    tsr_cdt_clear_changes(d);
    return ok;
}

/* Is apex v where two features meet at a small angle? */
static bool in_cluster(const refiner *r, uint32_t v)
{
    feature f[MAX_FEATURES];
    uint32_t n = features_at(r, v, f, MAX_FEATURES);
    for (uint32_t i = 0; i < n; i++)
        for (uint32_t j = i + 1; j < n; j++)
            if (small_meeting(r, f[i], f[j]))
                return true;
    return false;
}

/* Splits constrained edge k of t, where the triangle beside it with apex
 * `apex` (CDT_NONE: none in particular) needs it split. Returns 1 split,
 * 0 could not (a sliver below the resolution of doubles), -1 out of
 * memory.
 *
 * Where: an edge with one end at an apex where features meet at a small
 * angle (any apex when there are no features: conforming alone) is cut by
 * a power-of-two circle around that end (concentric shells: splits on the
 * features of the small angle stay at equal distances and do not chase
 * each other). Otherwise, for quality, the apex at height h over the edge
 * gets an edge vertex at 0.95 h cot(bound) beside its foot, where the
 * triangle they make just meets the bound: between two close features
 * that do not meet (a thin strip, which needs vertices all along it) the
 * splits then alternate from side to side, about twice as far apart as
 * midpoint splits leave them (debug2.txt: 280,000 Steiner points instead
 * of 450,000). The cut stays in the middle 60% of the edge; failing that,
 * the midpoint. */
static int split_segment(refiner *r, uint32_t t, int k, uint32_t apex)
{
    tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    uint32_t u = v[k], w = v[(k + 1) % 3], ends[2];
    original_ends(r, u, w, ends);
    const double *U = P(d, u), *W = P(d, w);
    bool apex_u = !on_segment(r, u), apex_w = !on_segment(r, w);
    double len = hypot(W[0] - U[0], W[1] - U[1]);
    double f = 0.5;
    if (apex_u != apex_w && (!r->foff || in_cluster(r, apex_u ? u : w))) {
        double shell = exp2(nearbyint(log2(0.5 * len)));
        f = apex_u ? shell / len : 1 - shell / len;
    } else if (apex != CDT_NONE && r->cot_min > 0) {
        const double *A = P(d, apex);
        double ex = W[0] - U[0], ey = W[1] - U[1], l2 = ex * ex + ey * ey;
        double tau = ((A[0] - U[0]) * ex + (A[1] - U[1]) * ey) / l2;
        double h = fabs(tsr_orient2d(U, W, A)) / sqrt(l2);
        double m = fmax(fmax(fabs(A[0]), fabs(A[1])), fmax(fmax(fabs(U[0]), fabs(U[1])), fmax(fabs(W[0]), fabs(W[1]))));
        /* 0.95: a little inside the bound, so that rounding does not leave
         * the new triangle just below it */
        double dt = 0.95 * h * r->cot_min / sqrt(l2);
        double c0 = tau - dt, c1 = tau + dt;
        double best = fabs(c0 - 0.5) < fabs(c1 - 0.5) ? c0 : c1;
        if (h > 8 * DBL_EPSILON * m && best >= 0.2 && best <= 0.8)
            f = best;
    }
    /* a cut rounded off the edge's line can leave an edge of its star
     * (towards either apex) non-Delaunay where the apex is nearly on that
     * line, and Lawson's flips only look at the edges opposite the new
     * vertex: such cuts are refused and the next one along the edge tried */
    double tries[8] = {f, 0.5, 0.4375, 0.5625, 0.375, 0.625, 0.3125, 0.6875};
    uint32_t c = v[(k + 2) % 3], s = d->tn[3 * (size_t)t + k], q = CDT_NONE;
    if (in_domain(r, s) && !cdt_is_ghost(d, s)) {
        const uint32_t *x = d->tv + 3 * (size_t)s;
        q = x[0] != u && x[0] != w ? x[0] : x[1] != u && x[1] != w ? x[1] : x[2];
    }
    for (int i = f == 0.5 ? 1 : 0; i < 8; i++) {
        U = P(d, u), W = P(d, w);
        double x = U[0] + tries[i] * (W[0] - U[0]), y = U[1] + tries[i] * (W[1] - U[1]);
        if (tries[i] == 0.5) {
            x = 0.5 * (U[0] + W[0]);
            y = 0.5 * (U[1] + W[1]);
        }
        const double p[2] = {x, y};
        if ((in_domain(r, t) && tsr_incircle(U, p, P(d, c), W) > 0) ||
            (q != CDT_NONE && tsr_incircle(W, p, P(d, q), U) > 0))
            continue;
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

/* Would a new vertex at c encroach the constrained edge u-w? Diametral
 * circles when conforming; otherwise Chew's and Shewchuk's diametral lens
 * (the angle at c above 180 - 2 min_angle degrees) */
static bool cc_encroaches(const refiner *r, const double c[2], const double *u, const double *w)
{
    double dt = dot_at(c, u, w);
    if (!(dt < 0))
        return false;
    if (r->eager || r->cos_min > 1)
        return true;
    double g = 2 * r->cos_min * r->cos_min - 1;
    double a2 = (u[0] - c[0]) * (u[0] - c[0]) + (u[1] - c[1]) * (u[1] - c[1]);
    double b2 = (w[0] - c[0]) * (w[0] - c[0]) + (w[1] - c[1]) * (w[1] - c[1]);
    return dt * dt >= g * g * a2 * b2;
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
    if (r->off > 0) {
        /* Ungor's off-centre: on the shortest edge's bisector, where the
         * triangle it makes with that edge just meets the angle bound;
         * taken when nearer to the edge than the circumcentre */
        const double *q[3] = {a, b, cc};
        double l[3];
        for (int k = 0; k < 3; k++) {
            double ex = q[(k + 1) % 3][0] - q[k][0], ey = q[(k + 1) % 3][1] - q[k][1];
            l[k] = ex * ex + ey * ey;
        }
        int s = l[0] < l[1] && l[0] < l[2] ? 0 : l[1] < l[2] ? 1 : 2;
        const double *o = q[s], *e = q[(s + 1) % 3];
        double ex = e[0] - o[0], ey = e[1] - o[1];
        double ox = 0.5 * ex - r->off * ey, oy = 0.5 * ey + r->off * ex;
        double cxo = c[0] - o[0], cyo = c[1] - o[1];
        if (ox * ox + oy * oy < cxo * cxo + cyo * cyo) {
            c[0] = o[0] + ox;
            c[1] = o[1] + oy;
        }
    }
    uint32_t bt = CDT_NONE;
    int bk = 0;
    uint32_t home = walk_to(r, t, c, &bt, &bk);
    if (home == CDT_NONE) {
        if (bt == CDT_NONE)
            return 0;
        int s = split_segment(r, bt, bk, d->tv[3 * (size_t)bt + (bk + 2) % 3]);
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
                if (cc_encroaches(r, c, P(d, w[k]), P(d, w[(k + 1) % 3])) && nenc < 8) {
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
        int s = split_segment(r, enc_t[0], enc_k[0], d->tv[3 * (size_t)enc_t[0] + (enc_k[0] + 2) % 3]);
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

/* Area bound, when the circumcentre cannot be used (the walk towards it,
 * or the cut of the edge in its way, fails on features a few ulps apart):
 * the centroid, strictly inside t, still shrinks what is too large.
 * Returns 1 inserted, 0 not (t below the resolution of doubles), -1 out
 * of memory. */
static int split_centroid(refiner *r, uint32_t t)
{
    tsr_cdt *d = r->d;
    const uint32_t *v = d->tv + 3 * (size_t)t;
    const double *a = P(d, v[0]), *b = P(d, v[1]), *e = P(d, v[2]);
    double c[2] = {(a[0] + b[0] + e[0]) / 3, (a[1] + b[1] + e[1]) / 3};
    if (!(tsr_orient2d(a, b, c) > 0 && tsr_orient2d(b, e, c) > 0 && tsr_orient2d(e, a, c) > 0))
        return 0;
    uint32_t pv = tsr__cdt_add_vertex(d, c[0], c[1]);
    if (pv == CDT_NONE || tsr__cdt_insert_at(d, pv, t, CDT_IN_TRIANGLE, 0) == CDT_NONE)
        return -1;
    r->steiner++;
    return take_changes(r) ? 1 : -1;
}

/* The features through each apex, from the constrained edges beside the
 * domain (hull edges only count for region HULL, as in the checker). */
static bool build_features(refiner *r)
{
    tsr_cdt *d = r->d;
    const tsr_allocator *a = tsr__cdt_alloc(d);
    r->nv0 = d->nv;
    r->foff = tsr_alloc(a, ((size_t)r->nv0 + 1) * sizeof *r->foff);
    if (!r->foff)
        return false;
    memset(r->foff, 0, ((size_t)r->nv0 + 1) * sizeof *r->foff);
    size_t n = 0;
    for (int pass = 0; pass < 2; pass++) {
        for (uint32_t t = 0; t < d->nt; t++) {
            if (!in_domain(r, t) || cdt_is_ghost(d, t))
                continue;
            const uint32_t *v = d->tv + 3 * (size_t)t;
            for (int k = 0; k < 3; k++) {
                uint32_t m = cdt_mark(d, t, k), s = d->tn[3 * (size_t)t + k];
                if (!m || (in_domain(r, s) && s < t))
                    continue; /* not constrained, or seen from s */
                if (CDT_LABEL(m) == CDT_BOUNDARY && r->opt->region != TSR_REGION_HULL)
                    continue;
                uint32_t u = v[k], w = v[(k + 1) % 3];
                if (pass == 0) {
                    r->foff[u + 1]++, r->foff[w + 1]++;
                } else {
                    r->fto[r->foff[u]++] = w;
                    r->fto[r->foff[w]++] = u;
                }
            }
        }
        if (pass == 0) {
            for (uint32_t v = 0; v < r->nv0; v++)
                r->foff[v + 1] += r->foff[v];
            n = r->foff[r->nv0];
            r->fto = tsr_alloc(a, (n + 1) * sizeof *r->fto);
            if (!r->fto)
                return false;
        }
    }
    /* the second pass advanced each start to the next one's: shift back */
    memmove(r->foff + 1, r->foff, (size_t)r->nv0 * sizeof *r->foff);
    r->foff[0] = 0;
    return true;
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
    r.eager = opt->conforming;
    r.cos_min = opt->min_angle > 0 ? cos(opt->min_angle * (3.14159265358979323846 / 180)) : 2;
    if (r.cos_min < 1) {
        /* Triangle's off-centre constant: 0.475 rather than 0.5 cot(bound / 2)
         * keeps the new angle a little above the bound */
        r.off = 0.475 * sqrt((1 + r.cos_min) / (1 - r.cos_min));
        r.cot_min = r.cos_min / sqrt(1 - r.cos_min * r.cos_min);
    }
    /* the area, and the triangles the area bounds ask for at least */
    double area = 0, asked = 0;
    bool area_bounds = opt->max_area > 0;
    for (uint32_t t = 0; t < d->nt; t++)
        if (in_domain(&r, t) && !cdt_is_ghost(d, t)) {
            const uint32_t *v = d->tv + 3 * (size_t)t;
            double at = 0.5 * tsr_orient2d(P(d, v[0]), P(d, v[1]), P(d, v[2])), bt = area_bound(&r, t);
            area += at;
            asked += bt > 0 ? at / bt : 0;
            area_bounds = area_bounds || bt > 0;
        }
    res->refined_area = area;
    res->asked_triangles = asked;
    if (!opt->max_steiner && asked > TSR_TRI_MAX_AREA_TRIANGLES)
        return TSR_ERR_TOO_LARGE;
    double limit = opt->max_steiner ? opt->max_steiner : 20.0 * (d->nv - 1) + 100000;
    if (!opt->max_steiner)
        limit += 4 * asked;
    r.limit = limit > UINT32_MAX / 4 ? UINT32_MAX / 4 : (uint32_t)limit;
    tsr_status st = TSR_ERR_NOMEM;
    bool was_tracking = d->track;
    if (opt->min_angle > 0 && !build_features(&r))
        goto done;
    tsr_cdt_track_changes(d, true);
    /* every triangle of the domain is "changed" to begin with */
    for (uint32_t t = 0; t < d->nt; t++)
        if (!tsr__cdt_append(d, &d->changed, &d->nchanged, &d->cap_changed, t))
            goto done;
    if (!take_changes(&r))
        goto done;
    bool quality = opt->min_angle > 0 || area_bounds;
    for (;;) {
        if (r.steiner >= r.limit) {
            res->quality_limited = res->steiner_limited = true;
            break;
        }
        if (r.hsq < r.nsq) {
            uint32_t t = r.sq[r.hsq], u = r.sq[r.hsq + 1], w = r.sq[r.hsq + 2];
            r.hsq += 3;
            const uint32_t *v = d->tv + 3 * (size_t)t;
            int k = v[0] == u && v[1] == w ? 0 : v[1] == u && v[2] == w ? 1 : v[2] == u && v[0] == w ? 2 : -1;
            if (k < 0 || !cdt_mark(d, t, k) || !encroached(&r, t, k))
                continue;
            if (split_segment(&r, t, k, CDT_NONE) < 0)
                goto done;
            continue;
        }
        if (quality && r.nhq) {
            qent e = pop_tri(&r);
            uint32_t t = e.t;
            const uint32_t *v = d->tv + 3 * (size_t)t;
            bool fresh = v[0] == e.v[0] && v[1] == e.v[1] && v[2] == e.v[2];
            if (!fresh || !in_domain(&r, t) || !bad(&r, t, false))
                continue;
            int done_t = split_triangle(&r, t);
            if (done_t == 0 && bad(&r, t, false) == 2)
                done_t = split_centroid(&r, t);
            if (done_t < 0)
                goto done;
            continue;
        }
        break;
    }
    /* count what stays bad because of small input angles, what stays
     * below the resolution of doubles, and what stays bad otherwise (a
     * split that rounding made impossible: a flat triangle on the far side
     * of the edge to cut) or encroached when conforming; all but the first
     * are reported as degraded (quality_limited), not hidden */
    for (uint32_t t = 0; t < d->nt; t++) {
        if (!in_domain(&r, t) || cdt_is_ghost(d, t))
            continue;
        if (quality && bad(&r, t, opt->min_angle > 0))
            res->unrefined++;
        for (int k = 0; k < 3 && r.eager; k++) {
            uint32_t n = d->tn[3 * (size_t)t + k]; /* each edge once */
            if (cdt_mark(d, t, k) && (t < n || !in_domain(&r, n)) && encroached(&r, t, k))
                res->unrefined++;
        }
    }
    if (res->steiner_limited || res->unrefined || res->below_resolution)
        res->quality_limited = true;
    st = TSR_OK;
done:
    tsr_cdt_track_changes(d, was_tracking);
    const tsr_allocator *a = tsr__cdt_alloc(d);
    tsr_free(a, r.vend);
    tsr_free(a, r.hq);
    tsr_free(a, r.sq);
    tsr_free(a, r.cav);
    tsr_free(a, r.foff);
    tsr_free(a, r.fto);
    return st;
}
