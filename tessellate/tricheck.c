/* tricheck.c: the independent checker of a constrained triangulation.
 *
 * It reads only the input PSLG, the options and the output arrays, and
 * decides with the exact predicates of predicates.h (Shewchuk 1997); none
 * of the triangulator's code is used, so a bug there cannot hide itself.
 *
 * The rules, in the order first_problem reports them:
 *
 *  - Triangles: vertex ids in range, coordinates finite, exact orient2d > 0.
 *    Input points map (vertex_of_input) to output vertices at exactly the
 *    same coordinates; for region HULL without hole seeds each of them is
 *    a corner of some triangle (counted in bad_topology).
 *  - Topology: each undirected edge is used by at most two triangles, and
 *    by two only in opposite directions. Every listed constrained edge is
 *    an edge of a triangle and lies on the input segment it names (within
 *    the tolerance below). These defects are counted in bad_topology.
 *  - Delaunay (method Delaunay, or a quadtree run that fell back whole):
 *    for every edge shared by two counter-clockwise triangles, the far
 *    vertex of one is not strictly inside the other's circumcircle (exact
 *    incircle <= 0). Listed constrained edges are exempt unless conforming.
 *  - Segments: each non-degenerate input segment a-b must be a chain of
 *    listed constrained edges from a to b whose vertices lie within
 *    tol = 1e-9 |b - a| + 8 eps max|coordinate| of the line ab (vertices
 *    exactly on it always qualify: rounding error is far below tol) and
 *    strictly further along it: (q - p).d > 0 for a step p -> q, exact
 *    for nearby points, so Steiner points ulps apart still progress; or q
 *    within 8 ulps of p's coordinates either way (one point rounded twice,
 *    as the crossings of a segment with two segments along one line, in
 *    whichever order the rounding put them). The
 *    chain is found by a depth-first search (each vertex
 *    entered once per segment) over a vertex -> neighbours adjacency, so
 *    nearly coincident segments, whose chains are both within tolerance,
 *    cannot mislead it. Where the kept region may be smaller than the
 *    hull (not HULL, or hole seeds), the chain may have gaps: from p,
 *    when no kept triangle at p covers the direction to b, it may jump to
 *    a vertex q near the line and further along it (the used vertices so
 *    placed in order of progress, then b; the first that qualifies) when
 *    the straight piece p-q lies outside the kept region, decided exactly
 *    (gap_clear): no kept triangle at p or q covers its direction (closed
 *    wedges, so a kept edge along it counts), no kept triangle's interior
 *    meets it, and no used vertex strictly between them lying exactly on
 *    the segment's line or on the piece has a kept triangle covering the
 *    direction to p or q. The vertices the piece merely passes, within the
 *    tolerance, do not refuse it: a crossing of a segment beside this one,
 *    or the other rounding of one crossing, whose sliver the segment
 *    enters by an ulp or whose triangles cover the direction back, while
 *    the piece from p onwards stays outside. The piece stands for the
 *    segment within the tolerance: a kept sliver thinner than that between
 *    the two is not seen, as a chain vertex off the line by as much is
 *    accepted.
 *  - Area: the sum of triangle areas (Neumaier's compensated sum) against
 *    an expected area computed from the input alone, when it can be:
 *      HULL, no hole seeds: the convex hull of the points (monotone chain
 *        with exact orientation);
 *      EVEN_ODD, no hole seeds, every point of even segment degree (so the
 *        segments are a union of closed loops and parity is well defined):
 *        a vertical slab sweep; events at every endpoint x and at every x
 *        where two segments cross; within a slab the segments do not cross,
 *        the odd-parity length is linear in x, and width times the length at
 *        the slab's middle is the slab's area;
 *      ENCLOSED, no hole seeds, segments forming disjoint simple loops: the
 *        sum of the areas of the loops that no other loop contains;
 *      otherwise NAN (not checked).
 *    Tolerance: 1e-12 of the expected area, plus, for every Steiner point,
 *    4 ulps of the largest coordinate times the bounding box diagonal (a
 *    rounded crossing or split point moves the boundary that much).
 *    More area than expected counts as overlapping, less as area_ok false.
 *    Independently, a vertex whose triangles' angles add up to more than
 *    2 pi (they wind around it more than once) counts as overlapping.
 *  - Euler characteristic V - E + F over the vertices used by triangles,
 *    against: HULL without seeds: 1 when the hull has area, else 0;
 *    EVEN_ODD / ENCLOSED without seeds when the segments form disjoint
 *    simple loops (every point of degree 0 or 2, no two segments meeting
 *    except consecutive ones at their shared end): for EVEN_ODD the loops
 *    contained in an even number of other loops bound components (+1) and
 *    the others bound holes (-1); for ENCLOSED, 1 per outermost loop.
 *    Otherwise LONG_MIN (not checked).
 *  - Minimum angle: the smallest angle of every triangle, atan2(|cross|,
 *    dot) in degrees. With opt->min_angle > 0, a triangle with an angle
 *    below min_angle (1e-9 relative slack) fails unless excused: its
 *    shortest edge joins a vertex lying on input feature f1 and a vertex on
 *    feature f2 != f1, where f1 and f2 meet (a shared endpoint, a crossing
 *    or a touch) at an angle below 60 degrees. Features are the input
 *    segments (a vertex lies on those whose chains pass through it, and on
 *    the segment named by a listed constrained edge ending at it, once that
 *    edge is found to lie on it: where nearly coincident segments leave
 *    several chains within tolerance, the search records only one) and,
 *    for region HULL, the convex hull's edges. This covers both a small
 *    input angle inside the triangle and Shewchuk's terminator / Miller-
 *    Pav-Walkington rule (skinny triangles whose shortest edge subtends a
 *    small input angle are left alone). A triangle whose three corners
 *    all lie on two such features (it lies inside the small wedge) is
 *    excused too. So is a triangle below the resolution of doubles
 *    (tsr_tri_below_resolution: height under 8 DBL_EPSILON times its
 *    largest coordinate), but only when the result reports such triangles
 *    (quality_limited, and below_resolution at least as many as found
 *    here); more than it reports all count as failing. The one definition
 *    is shared with refinement, which leaves them; the rule itself is
 *    plain geometry, so the check stays independent of how they arose.
 *  - Maximum area: triangles whose area exceeds opt->max_area, or their
 *    region's bound when smaller (the region grown over the output from
 *    the seeds, tsr_tri_regions), by more than 1e-9 relative.
 *
 * The sweeps give up (NAN / LONG_MIN, noted in first_problem only when
 * something else fails) beyond about 4e8 elementary steps, so a check of a
 * pathological input still ends.
 */
#include "tessellate/tessellate.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define WORK_BUDGET 400000000.0

/* ---- Small helpers -------------------------------------------------------- */

typedef struct ksum {
    double s, c;
} ksum;

/* Neumaier's variant of Kahan summation. */
static void kadd(ksum *k, double x)
{
    double t = k->s + x;
    if (fabs(k->s) >= fabs(x))
        k->c += (k->s - t) + x;
    else
        k->c += (x - t) + k->s;
    k->s = t;
}

static double kval(const ksum *k) { return k->s + k->c; }

static int sgn(double v) { return (v > 0) - (v < 0); }

static void problem(tsr_tri_check *r, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void problem(tsr_tri_check *r, const char *fmt, ...)
{
    if (r->first_problem[0])
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(r->first_problem, sizeof r->first_problem, fmt, ap);
    va_end(ap);
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return x < y ? -1 : x > y;
}

static uint64_t edge_key(uint32_t a, uint32_t b)
{
    return a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
}

static bool sorted_has(const uint64_t *keys, size_t n, uint64_t k)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (keys[mid] < k)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < n && keys[lo] == k;
}

/* Angle in degrees between vectors u and v, in [0, 180]. */
static double angle_deg(double ux, double uy, double vx, double vy)
{
    return atan2(fabs(ux * vy - uy * vx), ux * vx + uy * vy) * (180.0 / 3.14159265358979323846);
}

/* ---- Input geometry: hull, loops, even-odd area --------------------------- */

/* Distinct input points (exact coordinates) and the non-degenerate input
 * segments between them. */
typedef struct geom {
    const double *xy;   /* input points */
    uint32_t np;        /* distinct points */
    uint32_t *rep;      /* distinct id -> an input index */
    uint32_t *id;       /* input index -> distinct id */
    uint32_t ns;        /* non-degenerate segments with valid indices */
    uint32_t *s;        /* 2 distinct ids per segment */
    uint32_t *sid;      /* input segment id per segment */
    bool bad_index;     /* a segment index out of range */
} geom;

static const double *gp(const geom *g, uint32_t d) { return g->xy + 2 * (size_t)g->rep[d]; }

/* Sort records: qsort has no context argument, so the keys travel with
 * the indices (no file-scope state: two checks may run at once). */
typedef struct point_rec {
    double x, y;
    uint32_t i;
} point_rec;

static int cmp_point_rec(const void *a, const void *b)
{
    const point_rec *p = a, *q = b;
    if (p->x != q->x)
        return p->x < q->x ? -1 : 1;
    if (p->y != q->y)
        return p->y < q->y ? -1 : 1;
    return p->i < q->i ? -1 : p->i > q->i;
}

typedef struct seg_rec {
    double xmin;
    uint32_t s;
} seg_rec;

static int cmp_seg_rec(const void *a, const void *b)
{
    const seg_rec *p = a, *q = b;
    if (p->xmin != q->xmin)
        return p->xmin < q->xmin ? -1 : 1;
    return p->s < q->s ? -1 : p->s > q->s;
}

static void geom_free(geom *g)
{
    free(g->rep);
    free(g->id);
    free(g->s);
    free(g->sid);
    memset(g, 0, sizeof *g);
}

static tsr_status geom_build(geom *g, const tsr_pslg *in)
{
    memset(g, 0, sizeof *g);
    g->xy = in->xy;
    size_t n = in->nv;
    point_rec *order = malloc((n ? n : 1) * sizeof *order);
    g->rep = malloc((n ? n : 1) * sizeof *g->rep);
    g->id = malloc((n ? n : 1) * sizeof *g->id);
    g->s = malloc(2 * ((size_t)in->nseg + 1) * sizeof *g->s);
    g->sid = malloc(((size_t)in->nseg + 1) * sizeof *g->sid);
    if (!order || !g->rep || !g->id || !g->s || !g->sid) {
        free(order);
        geom_free(g);
        return TSR_ERR_NOMEM;
    }
    for (uint32_t i = 0; i < n; i++)
        order[i] = (point_rec){in->xy[2 * (size_t)i], in->xy[2 * (size_t)i + 1], i};
    qsort(order, n, sizeof *order, cmp_point_rec);
    for (size_t k = 0; k < n; k++) {
        if (k == 0 || order[k - 1].x != order[k].x || order[k - 1].y != order[k].y)
            g->rep[g->np++] = order[k].i;
        g->id[order[k].i] = g->np - 1;
    }
    free(order);
    for (uint32_t s = 0; s < in->nseg; s++) {
        uint32_t a = in->seg[2 * (size_t)s], b = in->seg[2 * (size_t)s + 1];
        if (a >= in->nv || b >= in->nv) {
            g->bad_index = true;
            continue;
        }
        if (g->id[a] == g->id[b])
            continue;
        g->s[2 * (size_t)g->ns] = g->id[a];
        g->s[2 * (size_t)g->ns + 1] = g->id[b];
        g->sid[g->ns++] = s;
    }
    return TSR_OK;
}

/* Convex hull of the distinct points (counter-clockwise, collinear points
 * dropped) by Andrew's monotone chain; fills hull (distinct ids, capacity
 * 2 np + 2) and returns its size; *area is the hull's area. */
static uint32_t hull_build(const geom *g, uint32_t *hull, double *area)
{
    /* distinct ids are already in (x, y) order */
    uint32_t k = 0;
    for (int pass = 0; pass < 2; pass++) {
        uint32_t start = k;
        for (uint32_t j = 0; j < g->np; j++) {
            uint32_t i = pass == 0 ? j : g->np - 1 - j;
            while (k >= start + 2 && tsr_orient2d(gp(g, hull[k - 2]), gp(g, hull[k - 1]), gp(g, i)) <= 0)
                k--;
            hull[k++] = i;
        }
        k--; /* the last point starts the other chain */
    }
    if (g->np < 3 || k < 3) {
        *area = 0;
        return g->np == 0 ? 0 : k;
    }
    ksum a = {0, 0};
    const double *o = gp(g, hull[0]);
    for (uint32_t i = 1; i + 1 < k; i++) {
        const double *p = gp(g, hull[i]), *q = gp(g, hull[i + 1]);
        kadd(&a, 0.5 * ((p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])));
    }
    *area = kval(&a);
    return k;
}

static double seg_xmin(const geom *g, uint32_t s)
{
    return fmin(gp(g, g->s[2 * (size_t)s])[0], gp(g, g->s[2 * (size_t)s + 1])[0]);
}
static double seg_xmax(const geom *g, uint32_t s)
{
    return fmax(gp(g, g->s[2 * (size_t)s])[0], gp(g, g->s[2 * (size_t)s + 1])[0]);
}

static bool on_closed_segment(const double *a, const double *b, const double *c)
{
    /* c is known to be collinear with a, b */
    return fmin(a[0], b[0]) <= c[0] && c[0] <= fmax(a[0], b[0]) && fmin(a[1], b[1]) <= c[1] &&
           c[1] <= fmax(a[1], b[1]);
}

/* What the input's segments are, from the pairs of segments that meet. */
typedef struct topo {
    bool simple;         /* no two segments meet except consecutive ones at a shared end */
    bool even;           /* every distinct point has even degree */
    bool all_two;        /* every distinct point has degree 0 or 2 */
    bool gave_up;        /* the work budget ran out */
    double *xs;          /* event abscissae (endpoints and crossings) */
    size_t nxs;
    uint32_t *by_xmin;   /* segments ordered by smallest x */
} topo;

static void topo_free(topo *t)
{
    free(t->xs);
    free(t->by_xmin);
    memset(t, 0, sizeof *t);
}

static tsr_status topo_build(topo *t, const geom *g)
{
    memset(t, 0, sizeof *t);
    t->simple = t->even = t->all_two = true;
    uint32_t *deg = calloc((size_t)g->np + 1, sizeof *deg);
    seg_rec *order = malloc(((size_t)g->ns + 1) * sizeof *order);
    size_t cap = 2 * (size_t)g->ns + 16;
    t->xs = malloc(cap * sizeof *t->xs);
    t->by_xmin = malloc(((size_t)g->ns + 1) * sizeof *t->by_xmin);
    if (!deg || !order || !t->xs || !t->by_xmin) {
        free(deg);
        free(order);
        topo_free(t);
        return TSR_ERR_NOMEM;
    }
    for (uint32_t s = 0; s < g->ns; s++) {
        deg[g->s[2 * (size_t)s]]++;
        deg[g->s[2 * (size_t)s + 1]]++;
        t->xs[t->nxs++] = gp(g, g->s[2 * (size_t)s])[0];
        t->xs[t->nxs++] = gp(g, g->s[2 * (size_t)s + 1])[0];
        order[s] = (seg_rec){seg_xmin(g, s), s};
    }
    for (uint32_t p = 0; p < g->np; p++) {
        if (deg[p] & 1)
            t->even = false;
        if (deg[p] != 0 && deg[p] != 2)
            t->all_two = false;
    }
    free(deg);
    qsort(order, g->ns, sizeof *order, cmp_seg_rec);
    for (uint32_t s = 0; s < g->ns; s++)
        t->by_xmin[s] = order[s].s;
    free(order);
    double work = 0;
    for (uint32_t i = 0; i < g->ns && !t->gave_up; i++) {
        uint32_t si = t->by_xmin[i];
        uint32_t a = g->s[2 * (size_t)si], b = g->s[2 * (size_t)si + 1];
        const double *pa = gp(g, a), *pb = gp(g, b);
        double xmax = fmax(pa[0], pb[0]), ylo = fmin(pa[1], pb[1]), yhi = fmax(pa[1], pb[1]);
        for (uint32_t j = i + 1; j < g->ns; j++) {
            uint32_t sj = t->by_xmin[j];
            if (seg_xmin(g, sj) > xmax)
                break;
            if (++work > WORK_BUDGET) {
                t->gave_up = true;
                break;
            }
            uint32_t c = g->s[2 * (size_t)sj], d = g->s[2 * (size_t)sj + 1];
            const double *pc = gp(g, c), *pd = gp(g, d);
            if (fmax(pc[1], pd[1]) < ylo || fmin(pc[1], pd[1]) > yhi)
                continue;
            int o1 = sgn(tsr_orient2d(pa, pb, pc)), o2 = sgn(tsr_orient2d(pa, pb, pd));
            int o3 = sgn(tsr_orient2d(pc, pd, pa)), o4 = sgn(tsr_orient2d(pc, pd, pb));
            bool shared = a == c || a == d || b == c || b == d;
            if (shared) {
                if ((a == c && b == d) || (a == d && b == c)) {
                    t->simple = false; /* the same segment twice */
                    continue;
                }
                /* one end shared: they overlap only when collinear and the
                 * free ends go the same way from the shared one */
                uint32_t m = (a == c || a == d) ? a : b;
                const double *pm = gp(g, m), *po = gp(g, m == a ? b : a), *pq = gp(g, (c == m) ? d : c);
                if (tsr_orient2d(pm, po, pq) == 0 && (po[0] - pm[0]) * (pq[0] - pm[0]) + (po[1] - pm[1]) * (pq[1] - pm[1]) > 0)
                    t->simple = false;
                continue;
            }
            if (o1 * o2 < 0 && o3 * o4 < 0) {
                t->simple = false;
                /* a proper crossing: its abscissa is an event */
                double rx = pb[0] - pa[0], ry = pb[1] - pa[1], sx = pd[0] - pc[0], sy = pd[1] - pc[1];
                double den = rx * sy - ry * sx;
                double u = ((pc[0] - pa[0]) * sy - (pc[1] - pa[1]) * sx) / den;
                double x = pa[0] + u * rx;
                if (!(x >= fmin(pa[0], pb[0])))
                    x = fmin(pa[0], pb[0]);
                if (!(x <= xmax))
                    x = xmax;
                if (t->nxs == cap) {
                    double *nx = realloc(t->xs, 2 * cap * sizeof *nx);
                    if (!nx) {
                        topo_free(t);
                        return TSR_ERR_NOMEM;
                    }
                    t->xs = nx;
                    cap *= 2;
                }
                t->xs[t->nxs++] = x;
                continue;
            }
            if ((o1 == 0 && on_closed_segment(pa, pb, pc)) || (o2 == 0 && on_closed_segment(pa, pb, pd)) ||
                (o3 == 0 && on_closed_segment(pc, pd, pa)) || (o4 == 0 && on_closed_segment(pc, pd, pb)))
                t->simple = false; /* a touch or a collinear overlap */
        }
    }
    return TSR_OK;
}

/* Area of the points inside an odd number of segments (crossing parity of
 * a vertical line), by the slab sweep. NAN when the budget runs out or a
 * slab has an odd number of segments (cannot happen for even degrees). */
static double even_odd_area(const geom *g, topo *t)
{
    if (t->gave_up)
        return NAN;
    qsort(t->xs, t->nxs, sizeof *t->xs, cmp_double);
    size_t nx = 0;
    for (size_t i = 0; i < t->nxs; i++)
        if (nx == 0 || t->xs[i] != t->xs[nx - 1])
            t->xs[nx++] = t->xs[i];
    uint32_t *active = malloc(((size_t)g->ns + 1) * sizeof *active);
    double *ys = malloc(((size_t)g->ns + 1) * sizeof *ys);
    if (!active || !ys) {
        free(active);
        free(ys);
        return NAN;
    }
    size_t na = 0, next = 0;
    ksum area = {0, 0};
    double work = 0;
    bool ok = true;
    for (size_t k = 0; k + 1 < nx && ok; k++) {
        double x0 = t->xs[k], x1 = t->xs[k + 1], xm = 0.5 * (x0 + x1);
        while (next < g->ns && seg_xmin(g, t->by_xmin[next]) <= x0) {
            uint32_t s = t->by_xmin[next++];
            if (seg_xmax(g, s) > x0)
                active[na++] = s;
        }
        size_t m = 0;
        for (size_t i = 0; i < na; i++)
            if (seg_xmax(g, active[i]) > x0)
                active[m++] = active[i];
        na = m;
        work += (double)na * 4 + 1;
        if (work > WORK_BUDGET) {
            ok = false;
            break;
        }
        for (size_t i = 0; i < na; i++) {
            const double *p = gp(g, g->s[2 * (size_t)active[i]]), *q = gp(g, g->s[2 * (size_t)active[i] + 1]);
            if (p[0] > q[0]) {
                const double *tmp = p;
                p = q;
                q = tmp;
            }
            ys[i] = p[1] + (xm - p[0]) * ((q[1] - p[1]) / (q[0] - p[0]));
        }
        if (na & 1) {
            ok = false;
            break;
        }
        qsort(ys, na, sizeof *ys, cmp_double);
        double len = 0;
        for (size_t i = 0; i + 1 < na; i += 2)
            len += ys[i + 1] - ys[i];
        kadd(&area, (x1 - x0) * len);
    }
    free(active);
    free(ys);
    return ok ? kval(&area) : NAN;
}

/* Disjoint simple loops: their nesting gives the Euler characteristic of
 * the even-odd region and the area of the enclosed one. */
static bool loops_analyse(const geom *g, long *euler_even_odd, long *outer_count, double *outer_area)
{
    uint32_t *adj = malloc(2 * ((size_t)g->np + 1) * sizeof *adj);
    uint32_t *cnt = calloc((size_t)g->np + 1, sizeof *cnt);
    uint32_t *loop_of = malloc(((size_t)g->np + 1) * sizeof *loop_of);
    uint32_t *seq = malloc(((size_t)g->ns + 1) * sizeof *seq);      /* points, loop after loop */
    uint32_t *start = malloc(((size_t)g->ns + 2) * sizeof *start); /* loop l: seq[start[l], start[l+1]) */
    double *bbox = malloc(4 * ((size_t)g->ns + 1) * sizeof *bbox);
    bool ok = adj && cnt && loop_of && seq && start && bbox;
    if (!ok)
        goto done;
    for (uint32_t s = 0; s < g->ns; s++)
        for (int e = 0; e < 2; e++) {
            uint32_t p = g->s[2 * (size_t)s + e], q = g->s[2 * (size_t)s + 1 - e];
            adj[2 * (size_t)p + cnt[p]++] = q;
        }
    for (uint32_t p = 0; p < g->np; p++)
        loop_of[p] = UINT32_MAX;
    uint32_t nl = 0, n = 0;
    for (uint32_t p0 = 0; p0 < g->np; p0++) {
        if (cnt[p0] != 2 || loop_of[p0] != UINT32_MAX)
            continue;
        start[nl] = n;
        uint32_t prev = UINT32_MAX, p = p0;
        double *bb = bbox + 4 * (size_t)nl;
        bb[0] = bb[2] = INFINITY;
        bb[1] = bb[3] = -INFINITY;
        do {
            loop_of[p] = nl;
            seq[n++] = p;
            const double *xy = gp(g, p);
            bb[0] = fmin(bb[0], xy[0]);
            bb[1] = fmax(bb[1], xy[0]);
            bb[2] = fmin(bb[2], xy[1]);
            bb[3] = fmax(bb[3], xy[1]);
            uint32_t nx = adj[2 * (size_t)p] != prev ? adj[2 * (size_t)p] : adj[2 * (size_t)p + 1];
            prev = p;
            p = nx;
        } while (p != p0);
        nl++;
    }
    start[nl] = n;
    long euler = 0, outer = 0;
    ksum area = {0, 0};
    double work = 0;
    for (uint32_t l = 0; l < nl && ok; l++) {
        const double *pt = gp(g, seq[start[l]]);
        uint32_t depth = 0;
        for (uint32_t m = 0; m < nl; m++) {
            const double *bb = bbox + 4 * (size_t)m;
            if (m == l || pt[0] < bb[0] || pt[0] > bb[1] || pt[1] < bb[2] || pt[1] > bb[3])
                continue;
            work += start[m + 1] - start[m];
            if (work > WORK_BUDGET) {
                ok = false;
                break;
            }
            bool inside = false;
            for (uint32_t k = start[m]; k < start[m + 1]; k++) {
                const double *u = gp(g, seq[k]), *v = gp(g, seq[k + 1 < start[m + 1] ? k + 1 : start[m]]);
                if ((u[1] > pt[1]) != (v[1] > pt[1])) {
                    /* the edge crosses the horizontal line; is the crossing right of pt? */
                    double o = tsr_orient2d(u, v, pt);
                    if ((o > 0) == (v[1] > u[1]))
                        inside = !inside;
                }
            }
            depth += inside;
        }
        euler += depth % 2 == 0 ? 1 : -1;
        if (depth == 0) {
            outer++;
            ksum a = {0, 0};
            const double *o = gp(g, seq[start[l]]);
            for (uint32_t k = start[l] + 1; k + 1 < start[l + 1]; k++) {
                const double *p = gp(g, seq[k]), *q = gp(g, seq[k + 1]);
                kadd(&a, 0.5 * ((p[0] - o[0]) * (q[1] - o[1]) - (p[1] - o[1]) * (q[0] - o[0])));
            }
            kadd(&area, fabs(kval(&a)));
        }
    }
    *euler_even_odd = euler;
    *outer_count = outer;
    *outer_area = kval(&area);
done:
    free(adj);
    free(cnt);
    free(loop_of);
    free(seq);
    free(start);
    free(bbox);
    return ok;
}

/* ---- The output's structure ----------------------------------------------- */

typedef struct hedge {
    uint32_t lo, hi, h; /* undirected edge, half-edge 3t + k */
} hedge;

static int cmp_hedge(const void *a, const void *b)
{
    const hedge *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    if (x->hi != y->hi)
        return x->hi < y->hi ? -1 : 1;
    return x->h < y->h ? -1 : x->h > y->h;
}

/* hull edges remembered per output vertex (features_at) */
#define HULL_MEMO 4

typedef struct ck {
    const tsr_pslg *in;
    const tsr_tri_options *opt;
    const tsr_triangulation *out;
    tsr_tri_check *res;
    unsigned char *tri_state; /* 0 unusable, 1 usable but not ccw, 2 ccw */
    bool *used;               /* vertex used by a usable triangle */
    uint64_t *edges;          /* distinct undirected triangle edges, sorted */
    size_t nedges;
    uint64_t *cons;           /* listed constrained edges, sorted */
    size_t ncons;
    uint32_t *adj_off, *adj;  /* vertex -> neighbours along triangle edges */
    uint32_t *vt_off, *vt;    /* vertex -> corners 3t + k of ccw triangles */
    uint64_t *feat;           /* (vertex << 32 | input segment) on segment chains */
    size_t nfeat, feat_cap;
    struct frame *stack;      /* the segment search */
    size_t nstack, stack_cap;
    uint32_t *seen, stamp;    /* vertex -> last search that entered it */
    struct cand *cand;        /* a gap's candidate ends */
    size_t ncand, cand_cap;
    uint32_t *corr;           /* kept triangles near the segment searched */
    size_t ncorr, corr_cap;
    uint32_t corr_stamp;      /* the search corr was gathered for (0: none) */
    /* the used vertex and the kept triangle (index in corr) that last
     * refused a gap of this search, tried first on the next candidate;
     * UINT32_MAX: none */
    uint32_t block_v, block_t;
    bool *boundary;           /* vertex on an edge of one triangle */
    uint32_t *hull_memo;      /* HULL_MEMO per vertex: hull edges through it */
    double maxabs;            /* largest output coordinate magnitude */
} ck;

static const double *vxy(const ck *c, uint32_t v) { return c->out->xy + 2 * (size_t)v; }

static void ck_free(ck *c)
{
    free(c->tri_state);
    free(c->used);
    free(c->edges);
    free(c->cons);
    free(c->adj_off);
    free(c->adj);
    free(c->vt_off);
    free(c->vt);
    free(c->feat);
    free(c->stack);
    free(c->seen);
    free(c->cand);
    free(c->corr);
    free(c->boundary);
    free(c->hull_memo);
}

/* A segment's line, for the nearness test of chain vertices. */
typedef struct line {
    double a[2], b[2], dx, dy, len2, len, tol;
} line;

/* The largest coordinate magnitude of a and b: the scale of the rounding
 * of points computed on the segment a-b (its crossings and splits are
 * computed from its ends or from nearer points), so that one far point
 * elsewhere does not loosen every segment's tolerance. */
static double seg_scale(const double *a, const double *b)
{
    return fmax(fmax(fabs(a[0]), fabs(a[1])), fmax(fabs(b[0]), fabs(b[1])));
}

static void line_init(line *l, const double *a, const double *b, double maxabs)
{
    l->a[0] = a[0], l->a[1] = a[1], l->b[0] = b[0], l->b[1] = b[1];
    l->dx = b[0] - a[0], l->dy = b[1] - a[1];
    l->len2 = l->dx * l->dx + l->dy * l->dy;
    l->len = sqrt(l->len2);
    l->tol = 1e-9 * l->len + 8 * DBL_EPSILON * maxabs;
}

/* Progress along a -> b, measured from the nearer end so that it keeps
 * full relative precision at both ends (refinement splits segments down
 * to 1e-29 near a small angle; a parameter in [0, 1] would round to 1).
 * ta = (q - a).d and tb = (b - q).d, d = b - a. */
typedef struct pos {
    int half;  /* 0: nearer a, v = ta; 1: nearer b, v = -tb */
    double v, ta, tb;
} pos;

static bool pos_gt(pos x, pos y) { return x.half != y.half ? x.half > y.half : x.v > y.v; }

/* A candidate end of a gap: a vertex and its progress. */
typedef struct cand {
    uint32_t v;
    pos t;
} cand;

/* Is q further along the segment than p? Decided on q - p, which is
 * exact for nearby points: Steiner points a few ulps apart in the middle
 * of a long segment have the same rounded progress from either end. */
static bool forward(const line *l, const double *p, const double *q)
{
    return (q[0] - p[0]) * l->dx + (q[1] - p[1]) * l->dy > 0;
}

/* May a chain step from p to q: further along, or (either way) to a point
 * within rounding of p, a few ulps of its coordinates? Two crossings of
 * one segment with two segments along one line (given twice, or
 * overlapping) are the same point rounded twice; which comes first along
 * the segment is the rounding's choice. */
static bool ahead(const line *l, const double *p, const double *q)
{
    double r = 8 * DBL_EPSILON * fmax(fabs(p[0]), fabs(p[1]));
    return forward(l, p, q) || (fabs(q[0] - p[0]) <= r && fabs(q[1] - p[1]) <= r);
}

static pos pos_start(const line *l) { return (pos){0, 0, 0, l->len2}; }
static pos pos_end(const line *l) { return (pos){1, 0, l->len2, 0}; }

/* True when q is within tolerance of the line; *t is its progress and
 * *dist its distance. */
static bool line_near(const line *l, const double *q, pos *t, double *dist)
{
    double ex = q[0] - l->a[0], ey = q[1] - l->a[1], fx = q[0] - l->b[0], fy = q[1] - l->b[1];
    t->ta = l->dx * ex + l->dy * ey;
    t->tb = -(l->dx * fx + l->dy * fy);
    double cr;
    if (t->ta <= t->tb) {
        t->half = 0, t->v = t->ta;
        cr = l->dx * ey - l->dy * ex;
    } else {
        t->half = 1, t->v = -t->tb;
        cr = l->dx * fy - l->dy * fx;
    }
    *dist = fabs(cr) / l->len;
    if (*dist <= l->tol)
        return true;
    if (*dist <= 1e-6 * l->len && tsr_orient2d(l->a, l->b, q) == 0) {
        *dist = 0;
        return true;
    }
    return false;
}

/* True when a kept (ccw) triangle at vertex p covers the direction from p
 * to the point z (closed wedge). */
static bool covers(const ck *c, uint32_t p, const double *z)
{
    const uint32_t *tri = c->out->tri;
    for (uint32_t i = c->vt_off[p]; i < c->vt_off[p + 1]; i++) {
        uint32_t h = c->vt[i], t = h / 3, k = h % 3;
        const double *q = vxy(c, tri[3 * (size_t)t + (k + 1) % 3]), *r = vxy(c, tri[3 * (size_t)t + (k + 2) % 3]);
        const double *pp = vxy(c, p);
        if (tsr_orient2d(pp, q, z) >= 0 && tsr_orient2d(pp, z, r) >= 0)
            return true;
    }
    return false;
}

static bool feat_add(ck *c, uint32_t v, uint32_t s)
{
    if (c->nfeat == c->feat_cap) {
        size_t cap = c->feat_cap ? 2 * c->feat_cap : 1024;
        uint64_t *f = realloc(c->feat, cap * sizeof *f);
        if (!f)
            return false;
        c->feat = f;
        c->feat_cap = cap;
    }
    c->feat[c->nfeat++] = (uint64_t)v << 32 | s;
    return true;
}

/* Does the open interior of kept triangle t meet the closed segment
 * a-b? Exact: they are disjoint exactly when the line of one of the
 * triangle's edges, or the segment's own line, separates them (weakly). */
static bool meets_interior(const ck *c, uint32_t t, const double *a, const double *b)
{
    const uint32_t *tri = c->out->tri + 3 * (size_t)t;
    const double *p[3] = {vxy(c, tri[0]), vxy(c, tri[1]), vxy(c, tri[2])};
    int pos = 0, neg = 0;
    for (int k = 0; k < 3; k++) {
        if (tsr_orient2d(p[k], p[(k + 1) % 3], a) <= 0 && tsr_orient2d(p[k], p[(k + 1) % 3], b) <= 0)
            return false;
        double o = tsr_orient2d(a, b, p[k]);
        pos += o > 0;
        neg += o < 0;
    }
    return pos > 0 && neg > 0;
}

/* The kept (ccw) triangles near the segment of l, in c->corr, gathered
 * once per search: those whose bounding box meets the segment's, grown by
 * its tolerance, and that do not lie wholly beyond twice the tolerance on
 * one side of its line (a floating-point filter with room to spare: a gap
 * runs between vertices within the tolerance). False when out of memory. */
static bool corridor(ck *c, const line *l)
{
    if (c->corr_stamp == c->stamp)
        return true;
    c->corr_stamp = c->stamp;
    c->ncorr = 0;
    c->block_v = c->block_t = UINT32_MAX;
    double x0 = fmin(l->a[0], l->b[0]) - l->tol, x1 = fmax(l->a[0], l->b[0]) + l->tol;
    double y0 = fmin(l->a[1], l->b[1]) - l->tol, y1 = fmax(l->a[1], l->b[1]) + l->tol;
    double far = 2 * l->tol * l->len; /* in units of the cross product */
    for (uint32_t t = 0; t < c->out->nt; t++) {
        if (c->tri_state[t] != 2)
            continue;
        const uint32_t *v = c->out->tri + 3 * (size_t)t;
        int above = 0, below = 0;
        double tx0 = INFINITY, tx1 = -INFINITY, ty0 = INFINITY, ty1 = -INFINITY;
        for (int k = 0; k < 3; k++) {
            const double *q = vxy(c, v[k]);
            tx0 = fmin(tx0, q[0]), tx1 = fmax(tx1, q[0]), ty0 = fmin(ty0, q[1]), ty1 = fmax(ty1, q[1]);
            double cr = l->dx * (q[1] - l->a[1]) - l->dy * (q[0] - l->a[0]);
            above += cr > far;
            below += cr < -far;
        }
        if (above == 3 || below == 3 || tx1 < x0 || tx0 > x1 || ty1 < y0 || ty0 > y1)
            continue;
        if (c->ncorr == c->corr_cap) {
            size_t cap = c->corr_cap ? 2 * c->corr_cap : 256;
            uint32_t *n = realloc(c->corr, cap * sizeof *n);
            if (!n)
                return false;
            c->corr = n;
            c->corr_cap = cap;
        }
        c->corr[c->ncorr++] = t;
    }
    return true;
}

/* May the search jump from p over a gap to candidate k (of c->cand)? The
 * straight piece p-q between the two output vertices (both within the
 * segment's tolerance) must lie outside the kept region, decided exactly:
 * no kept triangle at p or q covers its direction (closed wedges, so a
 * kept edge along it counts), no kept triangle's interior meets it, and no
 * used vertex between them (strictly further along than p, short of q)
 * lying exactly on the segment's line or on the piece has a kept triangle
 * covering the direction to p or to q (the segment would run along a kept
 * edge, or into the region, there). Vertices the piece only passes near,
 * within the tolerance, need not refuse it: the piece itself is tested. */
/* Does used vertex r, strictly between p and q along the segment and on
 * its line or on the piece p-q, have a kept triangle covering the
 * direction to p or to q (gap_clear)? */
static bool vertex_refuses(const ck *c, const line *l, uint32_t p, uint32_t q, uint32_t r)
{
    const double *pp = vxy(c, p), *qq = vxy(c, q), *rr = vxy(c, r);
    if (r == q || r == p || !c->used[r] || !forward(l, pp, rr) || !forward(l, rr, qq))
        return false;
    if (tsr_orient2d(l->a, l->b, rr) != 0 && tsr_orient2d(pp, qq, rr) != 0)
        return false;
    return covers(c, r, pp) || covers(c, r, qq);
}

/* Does the interior of kept triangle corr[i] meet the piece p-q, whose
 * box is x0..x1, y0..y1 (gap_clear)? */
static bool triangle_refuses(const ck *c, size_t i, const double *pp, const double *qq, double x0, double x1, double y0,
                             double y1)
{
    const uint32_t *v = c->out->tri + 3 * (size_t)c->corr[i];
    const double *a = vxy(c, v[0]), *b = vxy(c, v[1]), *d = vxy(c, v[2]);
    if (fmax(fmax(a[0], b[0]), d[0]) < x0 || fmin(fmin(a[0], b[0]), d[0]) > x1 || fmax(fmax(a[1], b[1]), d[1]) < y0 ||
        fmin(fmin(a[1], b[1]), d[1]) > y1)
        return false;
    return meets_interior(c, c->corr[i], pp, qq);
}

static bool gap_clear(ck *c, const line *l, uint32_t p, size_t k)
{
    uint32_t q = c->cand[k].v;
    const double *pp = vxy(c, p), *qq = vxy(c, q);
    if (covers(c, p, qq) || (c->used[q] && covers(c, q, pp)))
        return false;
    /* the tests below are a conjunction, so their order is free: the last
     * refusal's vertex and triangle first (the candidates come in order of
     * progress, and what refused one usually refuses the next: trying
     * them first keeps a long run of refused candidates linear), then the
     * vertices between, then the triangles */
    if (c->block_v != UINT32_MAX && vertex_refuses(c, l, p, q, c->block_v))
        return false;
    for (size_t i = 0; i < c->ncand; i++)
        if (vertex_refuses(c, l, p, q, c->cand[i].v)) {
            c->block_v = c->cand[i].v;
            return false;
        }
    double x0 = fmin(pp[0], qq[0]), x1 = fmax(pp[0], qq[0]), y0 = fmin(pp[1], qq[1]), y1 = fmax(pp[1], qq[1]);
    if (c->block_t < c->ncorr && triangle_refuses(c, c->block_t, pp, qq, x0, x1, y0, y1))
        return false;
    for (size_t i = 0; i < c->ncorr; i++)
        if (triangle_refuses(c, i, pp, qq, x0, x1, y0, y1)) {
            c->block_t = (uint32_t)i;
            return false;
        }
    return true;
}

static int cmp_cand(const void *x, const void *y)
{
    const cand *a = x, *b = y;
    if (pos_gt(a->t, b->t))
        return 1;
    if (pos_gt(b->t, a->t))
        return -1;
    return (a->v > b->v) - (a->v < b->v);
}

/* The candidates for a gap from p (in c->cand, by progress): the used
 * vertices near the line and further along it than p, short of vb, then
 * vb. False when out of memory. */
static bool gap_candidates(ck *c, const line *l, uint32_t p, uint32_t vb)
{
    const double *pp = vxy(c, p);
    double bx0 = fmin(pp[0], l->b[0]) - l->tol, bx1 = fmax(pp[0], l->b[0]) + l->tol;
    double by0 = fmin(pp[1], l->b[1]) - l->tol, by1 = fmax(pp[1], l->b[1]) + l->tol;
    c->ncand = 0;
    for (uint32_t v = 0; v <= c->out->nv; v++) {
        pos t = pos_end(l);
        double d;
        if (v < c->out->nv) {
            const double *xy = vxy(c, v);
            if (!c->used[v] || v == p || v == vb || xy[0] < bx0 || xy[0] > bx1 || xy[1] < by0 || xy[1] > by1)
                continue;
            if (!line_near(l, xy, &t, &d) || !ahead(l, pp, xy) || !pos_gt(pos_end(l), t))
                continue;
        }
        if (c->ncand == c->cand_cap) {
            size_t cap = c->cand_cap ? 2 * c->cand_cap : 64;
            cand *n = realloc(c->cand, cap * sizeof *n);
            if (!n)
                return false;
            c->cand = n;
            c->cand_cap = cap;
        }
        c->cand[c->ncand++] = (cand){v < c->out->nv ? v : vb, t};
    }
    qsort(c->cand, c->ncand - 1, sizeof *c->cand, cmp_cand); /* vb stays last */
    return true;
}

typedef struct frame {
    uint32_t v, next;
    pos t;
    uint32_t gap_next; /* the next gap candidate to try; GAPS_DONE when none is left */
} frame;

#define GAPS_DONE UINT32_MAX

static bool push_frame(ck *c, uint32_t v, pos t)
{
    if (c->nstack == c->stack_cap) {
        size_t cap = c->stack_cap ? 2 * c->stack_cap : 256;
        frame *f = realloc(c->stack, cap * sizeof *f);
        if (!f)
            return false;
        c->stack = f;
        c->stack_cap = cap;
    }
    c->stack[c->nstack++] = (frame){v, c->adj_off[v], t, 0};
    c->seen[v] = c->stamp;
    return true;
}

/* Looks for input segment s as a chain from output vertex va to vb (see
 * the header comment): a depth-first search over listed constrained edges
 * to vertices near the line and further along it, and, where the region
 * allows, gap jumps (gap_clear; one per vertex). Every vertex is entered
 * at most once, so the search costs the neighbourhoods of the vertices
 * near the segment, plus, per gap tried, the kept triangles near it. Returns 1 when
 * found (its vertices recorded as lying on s), 0 when missing (problem
 * noted at the furthest vertex reached), -1 when out of memory. */
static int walk_segment(ck *c, uint32_t s, uint32_t va, uint32_t vb, bool gaps)
{
    line l;
    line_init(&l, vxy(c, va), vxy(c, vb), seg_scale(vxy(c, va), vxy(c, vb)));
    c->stamp++;
    c->nstack = 0;
    if (!push_frame(c, va, pos_start(&l)))
        return -1;
    uint32_t far_v = va;
    pos far_t = pos_start(&l);
    while (c->nstack) {
        frame *f = &c->stack[c->nstack - 1];
        if (f->v == vb) {
            for (size_t i = 0; i < c->nstack; i++)
                if (!feat_add(c, c->stack[i].v, s))
                    return -1;
            return 1;
        }
        if (pos_gt(f->t, far_t))
            far_v = f->v, far_t = f->t;
        bool pushed = false;
        while (f->next < c->adj_off[f->v + 1]) {
            uint32_t q = c->adj[f->next++];
            pos t = pos_end(&l);
            double d;
            if (c->seen[q] == c->stamp || !sorted_has(c->cons, c->ncons, edge_key(f->v, q)))
                continue;
            if (q != vb && (!line_near(&l, vxy(c, q), &t, &d) || !ahead(&l, vxy(c, f->v), vxy(c, q)) || t.tb < 0))
                continue;
            if (!push_frame(c, q, t))
                return -1;
            pushed = true;
            break;
        }
        if (pushed)
            continue;
        if (gaps && f->gap_next != GAPS_DONE) {
            /* a jump that leads nowhere is backed out of and the next
             * candidate tried: the nearest clear one may be a vertex
             * within the tolerance that is no point of the segment */
            if (f->gap_next == 0 && covers(c, f->v, l.b))
                f->gap_next = GAPS_DONE;
            else {
                if (!gap_candidates(c, &l, f->v, vb) || !corridor(c, &l))
                    return -1;
                uint32_t v = f->v, from = f->gap_next;
                f->gap_next = GAPS_DONE;
                bool jumped = false;
                for (size_t i = from; i < c->ncand && !jumped; i++) {
                    uint32_t q = c->cand[i].v;
                    if (c->seen[q] != c->stamp && gap_clear(c, &l, v, i)) {
                        c->stack[c->nstack - 1].gap_next = (uint32_t)i + 1;
                        if (!push_frame(c, q, c->cand[i].t))
                            return -1;
                        jumped = true;
                    }
                }
                if (jumped)
                    continue;
            }
        }
        c->nstack--;
    }
    /* missing: say why at the furthest vertex reached */
    const double *pp = vxy(c, far_v);
    for (uint32_t i = c->adj_off[far_v]; i < c->adj_off[far_v + 1]; i++) {
        uint32_t q = c->adj[i];
        pos t = pos_end(&l);
        double d;
        if (q != vb && (!line_near(&l, vxy(c, q), &t, &d) || !ahead(&l, pp, vxy(c, q)) || t.tb < 0))
            continue;
        if (!sorted_has(c->cons, c->ncons, edge_key(far_v, q))) {
            problem(c->res,
                    "input segment %u (%.17g, %.17g)-(%.17g, %.17g): its output edge %u-%u is not listed as "
                    "constrained",
                    s, l.a[0], l.a[1], l.b[0], l.b[1], far_v, q);
            return 0;
        }
    }
    problem(c->res,
            "input segment %u (%.17g, %.17g)-(%.17g, %.17g) is missing: no output edge continues it from vertex %u "
            "(%.17g, %.17g)%s",
            s, l.a[0], l.a[1], l.b[0], l.b[1], far_v, pp[0], pp[1],
            gaps ? " inside the kept region" : "");
    return 0;
}

/* Do input features f1 and f2 (segments, or hull edges given by their
 * points) meet at an angle below 60 degrees? */
static bool small_meeting(const double *a1, const double *b1, const double *a2, const double *b2)
{
    const double *p = NULL, *q1 = NULL, *q2 = NULL;
    if (a1[0] == a2[0] && a1[1] == a2[1])
        p = a1, q1 = b1, q2 = b2;
    else if (a1[0] == b2[0] && a1[1] == b2[1])
        p = a1, q1 = b1, q2 = a2;
    else if (b1[0] == a2[0] && b1[1] == a2[1])
        p = b1, q1 = a1, q2 = b2;
    else if (b1[0] == b2[0] && b1[1] == b2[1])
        p = b1, q1 = a1, q2 = a2;
    if (p) {
        if (tsr_orient2d(p, q1, q2) == 0)
            return false; /* collinear: overlapping or opposite, no small angle */
        return angle_deg(q1[0] - p[0], q1[1] - p[1], q2[0] - p[0], q2[1] - p[1]) < 60;
    }
    int o1 = sgn(tsr_orient2d(a1, b1, a2)), o2 = sgn(tsr_orient2d(a1, b1, b2));
    int o3 = sgn(tsr_orient2d(a2, b2, a1)), o4 = sgn(tsr_orient2d(a2, b2, b1));
    if (o1 == 0 && o2 == 0)
        return false; /* collinear */
    bool meet = (o1 * o2 < 0 && o3 * o4 < 0) || (o1 == 0 && on_closed_segment(a1, b1, a2)) ||
                (o2 == 0 && on_closed_segment(a1, b1, b2)) || (o3 == 0 && on_closed_segment(a2, b2, a1)) ||
                (o4 == 0 && on_closed_segment(a2, b2, b1));
    if (!meet)
        return false;
    double ang = angle_deg(b1[0] - a1[0], b1[1] - a1[1], b2[0] - a2[0], b2[1] - a2[1]);
    return fmin(ang, 180 - ang) < 60;
}

/* The features through output vertex v: input segments from the chains,
 * plus hull edges (as point pairs) for region HULL. Fills up to cap. */
typedef struct feature {
    const double *a, *b;
} feature;

static uint32_t features_at(ck *c, uint32_t v, const double *hull_xy, uint32_t nh, feature *f, uint32_t cap)
{
    uint32_t n = 0;
    size_t lo = 0, hi = c->nfeat;
    uint64_t key = (uint64_t)v << 32;
    while (lo < hi) {
        size_t mid = lo + (hi - lo) / 2;
        if (c->feat[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    for (size_t i = lo; i < c->nfeat && c->feat[i] >> 32 == v && n < cap; i++) {
        uint32_t s = (uint32_t)c->feat[i];
        f[n].a = c->in->xy + 2 * (size_t)c->in->seg[2 * (size_t)s];
        f[n].b = c->in->xy + 2 * (size_t)c->in->seg[2 * (size_t)s + 1];
        n++;
    }
    /* hull edges: only a vertex on the output's boundary can lie on one;
     * those found (at most HULL_MEMO) are remembered per vertex. A hull
     * corner's own two edges go first: within the tolerance it may lie on
     * a neighbour's too (beside a hull edge 1e-11 long), and that one must
     * not crowd its own out */
    if (nh == 0 || !c->boundary[v])
        return n;
    uint32_t *memo = c->hull_memo + HULL_MEMO * (size_t)v;
    if (memo[0] == UINT32_MAX - 1) {
        uint32_t k = 0;
        const double *q = vxy(c, v);
        for (uint32_t h = 0; h < nh && k == 0; h++) {
            const double *a = hull_xy + 2 * (size_t)h;
            if (a[0] == q[0] && a[1] == q[1]) {
                memo[k++] = h;
                if ((h + nh - 1) % nh != h)
                    memo[k++] = (h + nh - 1) % nh;
            }
        }
        for (uint32_t h = 0; h < nh && k < HULL_MEMO; h++) {
            if ((k > 0 && memo[0] == h) || (k > 1 && memo[1] == h))
                continue;
            const double *a = hull_xy + 2 * (size_t)h, *b = hull_xy + 2 * (size_t)((h + 1) % nh);
            line l;
            line_init(&l, a, b, c->maxabs);
            if (q[0] < fmin(a[0], b[0]) - l.tol || q[0] > fmax(a[0], b[0]) + l.tol || q[1] < fmin(a[1], b[1]) - l.tol ||
                q[1] > fmax(a[1], b[1]) + l.tol)
                continue;
            pos t;
            double d;
            if (line_near(&l, q, &t, &d) && t.ta >= -1e-12 * l.len2 && t.tb >= -1e-12 * l.len2)
                memo[k++] = h;
        }
        while (k < HULL_MEMO)
            memo[k++] = UINT32_MAX;
    }
    for (int k = 0; k < HULL_MEMO && memo[k] != UINT32_MAX && n < cap; k++) {
        f[n].a = hull_xy + 2 * (size_t)memo[k];
        f[n].b = hull_xy + 2 * (size_t)((memo[k] + 1) % nh);
        n++;
    }
    return n;
}

/* ---- Below the resolution of doubles ----------------------------------------- */

bool tsr_tri_below_resolution(const double a[2], const double b[2], const double c[2])
{
    const double *p[3] = {a, b, c};
    double l2 = 0, m = 0;
    for (int k = 0; k < 3; k++) {
        double dx = p[(k + 1) % 3][0] - p[k][0], dy = p[(k + 1) % 3][1] - p[k][1];
        l2 = fmax(l2, dx * dx + dy * dy);
        m = fmax(m, fmax(fabs(p[k][0]), fabs(p[k][1])));
    }
    /* twice the area over the longest edge: the height, times that edge */
    return fabs(tsr_orient2d(a, b, c)) < 8 * DBL_EPSILON * m * sqrt(l2);
}

/* ---- The check -------------------------------------------------------------- */

static tsr_status run_check(ck *c, geom *g)
{
    const tsr_pslg *in = c->in;
    const tsr_tri_options *opt = c->opt;
    const tsr_triangulation *out = c->out;
    tsr_tri_check *res = c->res;
    const uint32_t *tri = out->tri;
    uint32_t nv = out->nv, nt = out->nt;

    /* Vertices: magnitude, and the input points' images. */
    for (uint32_t v = 0; v < nv; v++)
        for (int k = 0; k < 2; k++)
            if (isfinite(out->xy[2 * (size_t)v + k]))
                c->maxabs = fmax(c->maxabs, fabs(out->xy[2 * (size_t)v + k]));
    for (uint32_t i = 0; i < in->nv; i++) {
        uint32_t v = out->vertex_of_input ? out->vertex_of_input[i] : UINT32_MAX;
        if (v >= nv || out->xy[2 * (size_t)v] != in->xy[2 * (size_t)i] ||
            out->xy[2 * (size_t)v + 1] != in->xy[2 * (size_t)i + 1]) {
            res->bad_topology++;
            problem(res, "input point %u (%.17g, %.17g) maps to output vertex %u %s", i, in->xy[2 * (size_t)i],
                    in->xy[2 * (size_t)i + 1], v, v >= nv ? "(out of range)" : "at other coordinates");
        }
    }

    /* Triangles: ids, finiteness, orientation. */
    c->tri_state = calloc((size_t)nt + 1, 1);
    c->used = calloc((size_t)nv + 1, sizeof *c->used);
    if (!c->tri_state || !c->used)
        return TSR_ERR_NOMEM;
    for (uint32_t t = 0; t < nt; t++) {
        const uint32_t *v = tri + 3 * (size_t)t;
        if (v[0] >= nv || v[1] >= nv || v[2] >= nv) {
            res->not_ccw++;
            problem(res, "triangle %u (%u, %u, %u) has a vertex id out of range (%u vertices)", t, v[0], v[1], v[2],
                    nv);
            continue;
        }
        const double *a = vxy(c, v[0]), *b = vxy(c, v[1]), *d = vxy(c, v[2]);
        if (!isfinite(a[0]) || !isfinite(a[1]) || !isfinite(b[0]) || !isfinite(b[1]) || !isfinite(d[0]) ||
            !isfinite(d[1])) {
            res->not_ccw++;
            problem(res, "triangle %u has a non-finite vertex coordinate", t);
            continue;
        }
        c->tri_state[t] = 1;
        if (v[0] != v[1] && v[1] != v[2] && v[0] != v[2])
            for (int k = 0; k < 3; k++)
                c->used[v[k]] = true;
        if (tsr_orient2d(a, b, d) > 0)
            c->tri_state[t] = 2;
        else {
            res->not_ccw++;
            problem(res, "triangle %u (%.17g, %.17g) (%.17g, %.17g) (%.17g, %.17g) is not counter-clockwise", t, a[0],
                    a[1], b[0], b[1], d[0], d[1]);
        }
    }

    /* Edges: sort half-edges of usable triangles with distinct corners. */
    hedge *he = malloc((3 * (size_t)nt + 1) * sizeof *he);
    if (!he)
        return TSR_ERR_NOMEM;
    size_t nh = 0;
    for (uint32_t t = 0; t < nt; t++) {
        const uint32_t *v = tri + 3 * (size_t)t;
        if (!c->tri_state[t] || v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (uint32_t k = 0; k < 3; k++) {
            uint32_t a = v[k], b = v[(k + 1) % 3];
            he[nh++] = (hedge){a < b ? a : b, a < b ? b : a, 3 * t + k};
        }
    }
    qsort(he, nh, sizeof *he, cmp_hedge);
    c->edges = malloc((nh + 1) * sizeof *c->edges);
    c->boundary = calloc((size_t)nv + 1, sizeof *c->boundary);
    c->hull_memo = malloc((HULL_MEMO * (size_t)nv + HULL_MEMO) * sizeof *c->hull_memo);
    if (!c->boundary || !c->hull_memo) {
        free(he);
        return TSR_ERR_NOMEM;
    }
    for (size_t i = 0; i < HULL_MEMO * (size_t)nv; i++)
        c->hull_memo[i] = UINT32_MAX - 1;
    c->ncons = 0;
    c->cons = malloc(((size_t)out->nedge + 1) * sizeof *c->cons);
    if (!c->edges || !c->cons) {
        free(he);
        return TSR_ERR_NOMEM;
    }
    for (uint32_t e = 0; e < out->nedge; e++) {
        uint32_t a = out->edge[2 * (size_t)e], b = out->edge[2 * (size_t)e + 1];
        if (a < nv && b < nv && a != b)
            c->cons[c->ncons++] = edge_key(a, b);
    }
    qsort(c->cons, c->ncons, sizeof *c->cons, cmp_u64);

    bool check_delaunay = opt->method == TSR_TRI_DELAUNAY || out->fell_back;
    for (size_t i = 0; i < nh;) {
        size_t j = i + 1;
        while (j < nh && he[j].lo == he[i].lo && he[j].hi == he[i].hi)
            j++;
        c->edges[c->nedges++] = (uint64_t)he[i].lo << 32 | he[i].hi;
        const double *pa = vxy(c, he[i].lo), *pb = vxy(c, he[i].hi);
        if (j - i == 1) {
            c->boundary[he[i].lo] = c->boundary[he[i].hi] = true;
        } else if (j - i > 2) {
            res->bad_topology++;
            problem(res, "edge (%.17g, %.17g)-(%.17g, %.17g) is used by %zu triangles", pa[0], pa[1], pb[0], pb[1],
                    j - i);
        } else if (j - i == 2) {
            uint32_t h1 = he[i].h, h2 = he[i + 1].h, t1 = h1 / 3, t2 = h2 / 3;
            bool same = tri[h1] == tri[h2];
            if (same) {
                res->bad_topology++;
                problem(res, "edge (%.17g, %.17g)-(%.17g, %.17g) is used in the same direction by triangles %u and %u",
                        pa[0], pa[1], pb[0], pb[1], t1, t2);
            } else if (check_delaunay && c->tri_state[t1] == 2 && c->tri_state[t2] == 2 &&
                       (opt->conforming || !sorted_has(c->cons, c->ncons, edge_key(he[i].lo, he[i].hi)))) {
                const uint32_t *v1 = tri + 3 * (size_t)t1;
                uint32_t d = tri[3 * (size_t)t2 + (h2 % 3 + 2) % 3];
                if (tsr_incircle(vxy(c, v1[0]), vxy(c, v1[1]), vxy(c, v1[2]), vxy(c, d)) > 0) {
                    res->not_delaunay++;
                    problem(res,
                            "edge (%.17g, %.17g)-(%.17g, %.17g) is not Delaunay: vertex %u of triangle %u lies inside "
                            "the circumcircle of triangle %u",
                            pa[0], pa[1], pb[0], pb[1], d, t2, t1);
                }
            }
        }
        i = j;
    }

    /* Listed constrained edges: ids, a triangle edge, on their segment. */
    for (uint32_t e = 0; e < out->nedge; e++) {
        uint32_t a = out->edge[2 * (size_t)e], b = out->edge[2 * (size_t)e + 1];
        uint32_t s = out->edge_segment ? out->edge_segment[e] : UINT32_MAX;
        if (a >= nv || b >= nv || a == b || s >= in->nseg || in->seg[2 * (size_t)s] >= in->nv ||
            in->seg[2 * (size_t)s + 1] >= in->nv) {
            res->bad_topology++;
            problem(res, "constrained edge %u (%u-%u, segment %u) has an id out of range", e, a, b, s);
            continue;
        }
        if (!sorted_has(c->edges, c->nedges, edge_key(a, b))) {
            res->bad_topology++;
            problem(res, "constrained edge %u (%.17g, %.17g)-(%.17g, %.17g) is not an edge of any triangle", e,
                    vxy(c, a)[0], vxy(c, a)[1], vxy(c, b)[0], vxy(c, b)[1]);
            continue;
        }
        line l;
        const double *sa = in->xy + 2 * (size_t)in->seg[2 * (size_t)s], *sb = in->xy + 2 * (size_t)in->seg[2 * (size_t)s + 1];
        line_init(&l, sa, sb, seg_scale(sa, sb));
        pos ta, tb;
        double d, slack = l.tol * l.len;
        bool ok = l.len2 > 0 && line_near(&l, vxy(c, a), &ta, &d) && line_near(&l, vxy(c, b), &tb, &d);
        if (!ok || fmin(ta.ta, tb.ta) < -slack || fmin(ta.tb, tb.tb) < -slack) {
            res->bad_topology++;
            problem(res, "constrained edge %u (%.17g, %.17g)-(%.17g, %.17g) does not lie on input segment %u", e,
                    vxy(c, a)[0], vxy(c, a)[1], vxy(c, b)[0], vxy(c, b)[1], s);
        } else if (!feat_add(c, a, s) || !feat_add(c, b, s)) /* its ends lie on s */
            return TSR_ERR_NOMEM;
    }

    /* Adjacency: vertex -> neighbours, vertex -> ccw triangle corners. */
    c->adj_off = calloc((size_t)nv + 2, sizeof *c->adj_off);
    c->vt_off = calloc((size_t)nv + 2, sizeof *c->vt_off);
    c->adj = malloc((2 * c->nedges + 1) * sizeof *c->adj);
    c->vt = malloc((3 * (size_t)nt + 1) * sizeof *c->vt);
    if (!c->adj_off || !c->vt_off || !c->adj || !c->vt) {
        free(he);
        return TSR_ERR_NOMEM;
    }
    for (size_t e = 0; e < c->nedges; e++) {
        c->adj_off[(c->edges[e] >> 32) + 1]++;
        c->adj_off[(uint32_t)c->edges[e] + 1]++;
    }
    for (uint32_t t = 0; t < nt; t++)
        if (c->tri_state[t] == 2)
            for (int k = 0; k < 3; k++)
                c->vt_off[tri[3 * (size_t)t + k] + 1]++;
    for (uint32_t v = 0; v < nv; v++) {
        c->adj_off[v + 1] += c->adj_off[v];
        c->vt_off[v + 1] += c->vt_off[v];
    }
    free(he);
    uint32_t *pos = malloc(((size_t)nv + 1) * sizeof *pos);
    if (!pos)
        return TSR_ERR_NOMEM;
    memcpy(pos, c->adj_off, (size_t)nv * sizeof *pos);
    for (size_t e = 0; e < c->nedges; e++) {
        uint32_t a = (uint32_t)(c->edges[e] >> 32), b = (uint32_t)c->edges[e];
        c->adj[pos[a]++] = b;
        c->adj[pos[b]++] = a;
    }
    memcpy(pos, c->vt_off, (size_t)nv * sizeof *pos);
    for (uint32_t t = 0; t < nt; t++)
        if (c->tri_state[t] == 2)
            for (uint32_t k = 0; k < 3; k++)
                c->vt[pos[tri[3 * (size_t)t + k]]++] = 3 * t + k;
    free(pos);

    /* Segments. */
    c->seen = calloc((size_t)nv + 1, sizeof *c->seen);
    if (!c->seen)
        return TSR_ERR_NOMEM;
    bool gaps = opt->region != TSR_REGION_HULL || in->nholes > 0;
    for (uint32_t s = 0; s < in->nseg; s++) {
        uint32_t a = in->seg[2 * (size_t)s], b = in->seg[2 * (size_t)s + 1];
        if (a >= in->nv || b >= in->nv) {
            res->missing_segments++;
            problem(res, "input segment %u has a point index out of range", s);
            continue;
        }
        if (!out->vertex_of_input)
            continue;
        uint32_t va = out->vertex_of_input[a], vb = out->vertex_of_input[b];
        if (va >= nv || vb >= nv || va == vb)
            continue; /* mapping already reported, or degenerate */
        int r = walk_segment(c, s, va, vb, gaps);
        if (r < 0)
            return TSR_ERR_NOMEM;
        if (r == 0)
            res->missing_segments++;
    }
    if (c->nfeat) { /* sorted, each (vertex, segment) once */
        qsort(c->feat, c->nfeat, sizeof *c->feat, cmp_u64);
        size_t n = 1;
        for (size_t i = 1; i < c->nfeat; i++)
            if (c->feat[i] != c->feat[n - 1])
                c->feat[n++] = c->feat[i];
        c->nfeat = n;
    }

    /* Expected area and Euler characteristic from the input alone. */
    double expected = NAN;
    long expected_euler = LONG_MIN;
    double *hull_xy = NULL;
    uint32_t nhull = 0;
    if (!g->bad_index) {
        if (opt->region == TSR_REGION_HULL) {
            uint32_t *hull = malloc((2 * (size_t)g->np + 2) * sizeof *hull);
            if (!hull)
                return TSR_ERR_NOMEM;
            double ha;
            nhull = hull_build(g, hull, &ha);
            hull_xy = malloc((2 * (size_t)nhull + 2) * sizeof *hull_xy);
            if (!hull_xy) {
                free(hull);
                return TSR_ERR_NOMEM;
            }
            for (uint32_t i = 0; i < nhull; i++)
                memcpy(hull_xy + 2 * (size_t)i, gp(g, hull[i]), 2 * sizeof(double));
            free(hull);
            /* degenerate or not from the exact hull (three corners found
             * with exact orientation), not from its area: summed in
             * floating point, that can cancel to 0 (a point at 1e30 beside
             * others at 1) */
            bool solid = nhull >= 3;
            if (!solid)
                nhull = 0;
            if (in->nholes == 0) {
                expected = solid ? fmax(ha, 0) : 0;
                expected_euler = solid ? 1 : 0;
                /* the whole hull is kept, so every input point is a corner */
                for (uint32_t i = 0; solid && out->vertex_of_input && i < in->nv; i++) {
                    uint32_t v = out->vertex_of_input[i];
                    if (v < nv && !c->used[v]) {
                        res->bad_topology++;
                        problem(res, "input point %u (%.17g, %.17g) is inside the hull but no triangle uses it", i,
                                in->xy[2 * (size_t)i], in->xy[2 * (size_t)i + 1]);
                    }
                }
            }
        } else if (in->nholes == 0) {
            topo t;
            if (topo_build(&t, g) != TSR_OK)
                return TSR_ERR_NOMEM;
            if (opt->region == TSR_REGION_EVEN_ODD && t.even)
                expected = even_odd_area(g, &t);
            if (t.simple && t.all_two && !t.gave_up) {
                long eo, outer;
                double oa;
                if (loops_analyse(g, &eo, &outer, &oa)) {
                    expected_euler = opt->region == TSR_REGION_EVEN_ODD ? eo : outer;
                    if (opt->region == TSR_REGION_ENCLOSED)
                        expected = oa;
                }
            }
            topo_free(&t);
        }
    }

    /* Area, angles, Euler, overlap around vertices. */
    ksum area = {0, 0};
    double *angsum = calloc((size_t)nv + 1, sizeof *angsum);
    if (!angsum) {
        free(hull_xy);
        return TSR_ERR_NOMEM;
    }
    double min_angle = nt ? 180 : 0;
    uint32_t below = 0, excused = 0, above = 0, first_below = UINT32_MAX, first_above = UINT32_MAX;
    uint32_t sub = 0, first_sub = UINT32_MAX; /* below the resolution of doubles */
    double bound = opt->min_angle * (1 - 1e-9), first_bound = opt->max_area;
    /* the regions' bounds: each triangle's region grown from the seeds
     * over the output (tsr_tri_regions), as the contract defines them */
    uint32_t *region = NULL;
    bool region_areas = false;
    for (uint32_t r = 0; r < opt->nregions; r++)
        region_areas = region_areas || opt->regions[3 * (size_t)r + 2] > 0;
    if (region_areas) {
        double *seeds = malloc(2 * (size_t)opt->nregions * sizeof *seeds);
        region = malloc(((size_t)out->nt + 1) * sizeof *region);
        for (uint32_t r = 0; seeds && r < opt->nregions; r++)
            seeds[2 * r] = opt->regions[3 * (size_t)r], seeds[2 * r + 1] = opt->regions[3 * (size_t)r + 1];
        bool ok = seeds && region && tsr_tri_regions(out, seeds, opt->nregions, region, NULL, NULL) == TSR_OK;
        free(seeds);
        if (!ok) {
            free(region);
            free(angsum);
            free(hull_xy);
            return TSR_ERR_NOMEM;
        }
    }
    uint32_t faces = 0;
    double bx0 = INFINITY, bx1 = -INFINITY, by0 = INFINITY, by1 = -INFINITY;
    for (uint32_t t = 0; t < nt; t++) {
        if (!c->tri_state[t])
            continue;
        const uint32_t *v = tri + 3 * (size_t)t;
        const double *p[3] = {vxy(c, v[0]), vxy(c, v[1]), vxy(c, v[2])};
        double ta = 0.5 * ((p[1][0] - p[0][0]) * (p[2][1] - p[0][1]) - (p[1][1] - p[0][1]) * (p[2][0] - p[0][0]));
        kadd(&area, ta);
        if (v[0] != v[1] && v[1] != v[2] && v[0] != v[2])
            faces++;
        for (int k = 0; k < 3; k++) {
            bx0 = fmin(bx0, p[k][0]), bx1 = fmax(bx1, p[k][0]);
            by0 = fmin(by0, p[k][1]), by1 = fmax(by1, p[k][1]);
        }
        if (c->tri_state[t] != 2)
            continue;
        double tmin = 180;
        for (int k = 0; k < 3; k++) {
            const double *o = p[k], *q = p[(k + 1) % 3], *r = p[(k + 2) % 3];
            double ang = angle_deg(q[0] - o[0], q[1] - o[1], r[0] - o[0], r[1] - o[1]);
            angsum[v[k]] += ang;
            tmin = fmin(tmin, ang);
        }
        min_angle = fmin(min_angle, tmin);
        double ab = opt->max_area;
        if (region && region[t] != UINT32_MAX) {
            double rb = opt->regions[3 * (size_t)region[t] + 2];
            if (rb > 0 && !(ab > 0 && ab <= rb))
                ab = rb;
        }
        if (ab > 0 && ta > ab * (1 + 1e-9)) {
            if (above++ == 0)
                first_above = t, first_bound = ab;
        }
        if (opt->min_angle > 0 && tmin < bound) {
            /* the shortest edge (k, k+1) */
            int ks = 0;
            double best = INFINITY;
            for (int k = 0; k < 3; k++) {
                double dx = p[(k + 1) % 3][0] - p[k][0], dy = p[(k + 1) % 3][1] - p[k][1];
                if (dx * dx + dy * dy < best)
                    best = dx * dx + dy * dy, ks = k;
            }
            feature f1[64], f2[64], f3[64];
            uint32_t n1 = features_at(c, v[ks], hull_xy, nhull, f1, 64);
            uint32_t n2 = features_at(c, v[(ks + 1) % 3], hull_xy, nhull, f2, 64);
            uint32_t n3 = features_at(c, v[(ks + 2) % 3], hull_xy, nhull, f3, 64);
            bool ok = false;
            for (uint32_t i = 0; i < n1 && !ok; i++)
                for (uint32_t j = 0; j < n2 && !ok; j++)
                    if ((f1[i].a != f2[j].a || f1[i].b != f2[j].b) && small_meeting(f1[i].a, f1[i].b, f2[j].a, f2[j].b))
                        ok = true;
            /* or all three corners on two features meeting at a small
             * angle: the triangle lies in the small wedge itself */
            for (uint32_t i = 0; i < n3 && !ok; i++)
                for (uint32_t j = 0; j < n1 + n2 && !ok; j++) {
                    const feature *g = j < n1 ? &f1[j] : &f2[j - n1];
                    if ((f3[i].a == g->a && f3[i].b == g->b) || !small_meeting(f3[i].a, f3[i].b, g->a, g->b))
                        continue;
                    bool on1 = false, on2 = false; /* the shortest edge's ends on f3[i] or g */
                    for (uint32_t k = 0; k < n1; k++)
                        on1 = on1 || (f1[k].a == f3[i].a && f1[k].b == f3[i].b) || (f1[k].a == g->a && f1[k].b == g->b);
                    for (uint32_t k = 0; k < n2; k++)
                        on2 = on2 || (f2[k].a == f3[i].a && f2[k].b == f3[i].b) || (f2[k].a == g->a && f2[k].b == g->b);
                    ok = on1 && on2;
                }
            if (ok)
                excused++;
            else if (tsr_tri_below_resolution(p[0], p[1], p[2]) && out->quality_limited) {
                if (sub++ == 0)
                    first_sub = t;
            } else if (below++ == 0)
                first_below = t;
        }
    }
    /* excused only as far as the result reports them */
    bool unreported = sub > out->below_resolution;
    if (unreported) {
        if (below == 0)
            first_below = first_sub;
        below += sub;
        sub = 0;
    }
    res->area = kval(&area);
    res->min_angle = min_angle;
    res->below_min_angle = below;
    res->below_resolution_excused = sub;
    res->above_max_area = above;

    uint32_t vcount = 0;
    uint32_t first_wound = UINT32_MAX;
    for (uint32_t v = 0; v < nv; v++) {
        vcount += c->used[v];
        if (angsum[v] > 360 + 1e-4) {
            if (res->overlapping++ == 0)
                first_wound = v;
        }
    }
    if (first_wound != UINT32_MAX)
        problem(res, "the triangles around vertex %u (%.17g, %.17g) turn %.3f times around it (they overlap)",
                first_wound, vxy(c, first_wound)[0], vxy(c, first_wound)[1], angsum[first_wound] / 360);
    free(angsum);
    free(region);
    free(hull_xy);

    res->expected_area = expected;
    res->area_ok = true;
    if (!isnan(expected)) {
        double diag = nt ? hypot(bx1 - bx0, by1 - by0) : 0;
        uint32_t steiner = nv > out->input_vertices ? nv - out->input_vertices : 0;
        double tol = 1e-12 * fabs(expected) + ((double)steiner + 1) * 4 * DBL_EPSILON * c->maxabs * diag;
        if (res->area > expected + tol) {
            res->overlapping++;
            res->area_ok = false;
            problem(res, "the triangles cover %.17g, more than the expected area %.17g (overlapping triangles or a wrong region)", res->area,
                    expected);
        } else if (res->area < expected - tol) {
            res->area_ok = false;
            problem(res, "the triangles cover %.17g, less than the expected area %.17g (missing triangles or a wrong region)", res->area,
                    expected);
        }
    }

    res->euler = (long)vcount - (long)c->nedges + (long)faces;
    res->expected_euler = expected_euler;
    if (expected_euler != LONG_MIN && res->euler != expected_euler)
        problem(res, "Euler characteristic V - E + F = %ld - %zu + %u = %ld, expected %ld from the input", (long)vcount,
                c->nedges, faces, res->euler, expected_euler);

    if (below) {
        const uint32_t *v = tri + 3 * (size_t)first_below;
        problem(res,
                "%u triangle%s an angle below %g degrees (%u more excused by small input angles, %u as below the "
                "resolution of doubles%s); first: triangle %u (%.17g, %.17g) (%.17g, %.17g) (%.17g, %.17g)",
                below, below == 1 ? " has" : "s have", opt->min_angle, excused, sub,
                unreported ? "; more below it than the result reports" : "", first_below, vxy(c, v[0])[0],
                vxy(c, v[0])[1], vxy(c, v[1])[0], vxy(c, v[1])[1], vxy(c, v[2])[0], vxy(c, v[2])[1]);
    }
    if (above) {
        const uint32_t *v = tri + 3 * (size_t)first_above;
        problem(res,
                "%u triangle%s an area above %g; first: triangle %u (%.17g, %.17g) (%.17g, %.17g) (%.17g, "
                "%.17g)",
                above, above == 1 ? " has" : "s have", first_bound, first_above, vxy(c, v[0])[0], vxy(c, v[0])[1],
                vxy(c, v[1])[0], vxy(c, v[1])[1], vxy(c, v[2])[0], vxy(c, v[2])[1]);
    }
    return TSR_OK;
}

tsr_status tsr_triangulation_check(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *out,
                                   tsr_tri_check *res)
{
    memset(res, 0, sizeof *res);
    res->expected_area = NAN;
    res->expected_euler = LONG_MIN;
    tsr_tri_options defaults = {0};
    if (!opt)
        opt = &defaults;
    ck c = {.in = in, .opt = opt, .out = out, .res = res};
    geom g;
    tsr_status s = geom_build(&g, in);
    if (s == TSR_OK)
        s = run_check(&c, &g);
    geom_free(&g);
    ck_free(&c);
    if (s != TSR_OK) {
        memset(res, 0, sizeof *res);
        return s;
    }
    res->ok = res->not_ccw == 0 && res->bad_topology == 0 && res->not_delaunay == 0 && res->missing_segments == 0 &&
              res->overlapping == 0 && res->area_ok &&
              (res->expected_euler == LONG_MIN || res->euler == res->expected_euler) && res->below_min_angle == 0 &&
              res->above_max_area == 0;
    if (res->ok)
        res->first_problem[0] = '\0';
    return TSR_OK;
}
