/* fuzz_triangulate.c: tsr_triangulate on small graphs decoded from bytes,
 * every result judged by the independent checker tsr_triangulation_check.
 *
 * Layout (missing bytes read as 0):
 *   0  flags: bit 0 quadtree; bits 1-2 region (3: HULL); bit 3 conforming;
 *      bit 4 min_angle; bit 5 max_area; bit 6 shallow quadtree (max_depth
 *      2..9, forcing fallback cells); bit 7 allow invalid input (non-
 *      finite or too large coordinates, segment indices out of range)
 *   1  min_angle = (b % 61) / 2 degrees (0 .. 30)
 *   2  max_area from a table (1/16 .. 64); b >> 4 the quadtree max_depth
 *   3  points (b % 48), 4 segments (b % 64), 5 hole seeds (b % 4)
 *   then 2 bytes per point (x, y), 2 per segment (a, b), 2 per hole (x, y),
 *   then regions (b % 4), 3 bytes each: x, y, and the maximum area from
 *   the table (b & 15; none when b & 16); a seed exactly on a segment or
 *   a point is dropped (its side is unspecified, so kernel and checker may
 *   rightly take different ones).
 * A coordinate byte: low 5 bits k give k - 16 (-16 .. 15), the top 3 a
 * form: integer (0-3), k/2, k/4, k/1024, or k * (1 + 2^-40) (almost
 * collinear). So duplicates, collinear runs, crossing and overlapping
 * segments and points on segments are common. With bit 7, byte 0xff is
 * NaN, 0xfe +inf, 0xfd -2^250 (too large), and a segment index byte
 * >= 0xf0 is out of range.
 *
 * Checked: no allocation above 256 MiB; valid input gives TSR_OK (or
 * NOMEM), invalid input TSR_ERR_ARGUMENT with a message; every result
 * passes fuzz_check_triangulation (fuzz.h), the independent checker among
 * others; an affine field given at the input points comes out the same
 * field at every output vertex (tsr_tri_interpolate); a quadtree result keeps the area the Delaunay method keeps on
 * the same input (within 1e-8 of the box diagonal squared: slivers of
 * rounding), which the checker cannot see where segments dangle, unless
 * a hole seed lies on a segment or point (its side is unspecified), or,
 * under the even-odd rule, segments dangle and quadtree cells went to the
 * Delaunay fallback (features within rounding of each other merged there
 * can change the least number crossed on the way in; triangulate.h).
 * max_steiner is 4000 so that every run stays short. */
#include "fuzz.h"
#include "tessellate/predicates.h"

#include <math.h>
#include <string.h>

#define MAX_POINTS 48
#define MAX_SEGMENTS 64
#define MAX_HOLES 4
#define MAX_REGIONS 3

typedef struct reader {
    const uint8_t *p;
    size_t n, at;
} reader;

static uint8_t byte(reader *r)
{
    return r->at < r->n ? r->p[r->at++] : 0;
}

static double coordinate(uint8_t b, bool invalid, bool *bad)
{
    if (invalid && b == 0xff) {
        *bad = true;
        return NAN;
    }
    if (invalid && b == 0xfe) {
        *bad = true;
        return INFINITY;
    }
    if (invalid && b == 0xfd) {
        *bad = true;
        return -0x1p250; /* beyond the exact predicates */
    }
    double k = (double)(b & 31) - 16;
    switch (b >> 5) {
    case 4:
        return k / 2;
    case 5:
        return k / 4;
    case 6:
        return k / 1024;
    case 7:
        return k * (1 + 0x1p-40);
    default:
        return k;
    }
}

/* Is q exactly on a segment or an input point? */
static bool on_feature(const tsr_pslg *in, const double *q)
{
    for (uint32_t i = 0; i < in->nv; i++)
        if (in->xy[2 * (size_t)i] == q[0] && in->xy[2 * (size_t)i + 1] == q[1])
            return true;
    for (uint32_t s = 0; s < in->nseg; s++) {
        const double *a = in->xy + 2 * (size_t)in->seg[2 * (size_t)s],
                     *b = in->xy + 2 * (size_t)in->seg[2 * (size_t)s + 1];
        if (tsr_orient2d(a, b, q) == 0 && fmin(a[0], b[0]) <= q[0] && q[0] <= fmax(a[0], b[0]) &&
            fmin(a[1], b[1]) <= q[1] && q[1] <= fmax(a[1], b[1]))
            return true;
    }
    return false;
}

/* A hole seed exactly on a segment or an input point: its region is
 * unspecified (triangulate.h), so the methods may rightly differ. */
static bool seed_on_feature(const tsr_pslg *in)
{
    for (uint32_t h = 0; h < in->nholes; h++)
        if (on_feature(in, in->holes + 2 * (size_t)h))
            return true;
    return false;
}

/* Do the segments close (every distinct point meets an even number of
 * segment ends, each copy counted)? Under the even-odd rule an open input's
 * region is the least number of segments crossed on the way in, which
 * features closer than rounding can change (triangulate.h). */
static bool closed_input(const tsr_pslg *in)
{
    for (uint32_t i = 0; i < in->nv; i++) {
        const double *p = in->xy + 2 * (size_t)i;
        uint32_t ends = 0;
        for (uint32_t s = 0; s < in->nseg; s++) {
            const double *a = in->xy + 2 * (size_t)in->seg[2 * (size_t)s], *b = in->xy + 2 * (size_t)in->seg[2 * (size_t)s + 1];
            if (a[0] == b[0] && a[1] == b[1])
                continue; /* degenerate: ignored */
            ends += (a[0] == p[0] && a[1] == p[1]) + (b[0] == p[0] && b[1] == p[1]);
        }
        if (ends % 2)
            return false;
    }
    return true;
}

/* Sum of the kept triangles' areas. */
static double kept_area(const tsr_triangulation *t)
{
    double a = 0;
    for (uint32_t k = 0; k < t->nt; k++) {
        const double *p = t->xy + 2 * (size_t)t->tri[3 * k], *q = t->xy + 2 * (size_t)t->tri[3 * k + 1],
                     *r = t->xy + 2 * (size_t)t->tri[3 * k + 2];
        a += 0.5 * ((q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]));
    }
    return a;
}

int fuzz_triangulate(const uint8_t *data, size_t size)
{
    reader r = {data, size, 0};
    uint8_t flags = byte(&r), angle = byte(&r), area = byte(&r);
    uint32_t nv = byte(&r) % MAX_POINTS, ns = byte(&r) % MAX_SEGMENTS, nh = byte(&r) % MAX_HOLES;
    bool invalid = flags & 0x80, bad = false;
    static const double areas[16] = {0.0625, 0.125, 0.25, 0.5, 1, 1.5, 2, 3, 4, 6, 8, 12, 16, 24, 32, 64};

    tsr_tri_options o = {0};
    o.method = flags & 1 ? TSR_TRI_QUADTREE : TSR_TRI_DELAUNAY;
    o.region = ((flags >> 1) & 3) == 3 ? TSR_REGION_HULL : (tsr_region)((flags >> 1) & 3);
    o.conforming = flags & 8;
    o.min_angle = flags & 16 ? (angle % 61) / 2.0 : 0;
    o.max_area = flags & 32 ? areas[area & 15] : 0;
    o.max_depth = flags & 64 ? 2 + (area >> 4) % 8 : 0;
    o.max_steiner = 4000; /* keeps every run short; steiner_limited says when it bit */

    double xy[2 * MAX_POINTS + 1], holes[2 * MAX_HOLES + 1];
    uint32_t seg[2 * MAX_SEGMENTS + 1];
    for (uint32_t i = 0; i < 2 * nv; i++)
        xy[i] = coordinate(byte(&r), invalid, &bad);
    for (uint32_t i = 0; i < 2 * ns; i++) {
        uint8_t b = byte(&r);
        if (invalid && b >= 0xf0) {
            seg[i] = nv + (b - 0xf0);
            bad = true;
        } else {
            seg[i] = nv ? b % nv : 0;
            bad = bad || nv == 0;
        }
    }
    for (uint32_t i = 0; i < 2 * nh; i++)
        holes[i] = coordinate(byte(&r), invalid, &bad);

    tsr_pslg in = {xy, nv, seg, ns, holes, nh};
    double regions[3 * MAX_REGIONS + 1];
    uint32_t nr = byte(&r) % (MAX_REGIONS + 1);
    o.regions = regions;
    for (uint32_t i = 0; i < nr; i++) {
        double *g = &regions[3 * o.nregions];
        g[0] = coordinate(byte(&r), false, &bad);
        g[1] = coordinate(byte(&r), false, &bad);
        uint8_t b = byte(&r);
        g[2] = b & 16 ? 0 : areas[b & 15];
        if (bad || !on_feature(&in, g)) /* (bad: the segments are not checked, so neither is this) */
            o.nregions++;
    }
    tsr_triangulation t;
    tsr_error err = {0};
    size_t limit = (size_t)256 << 20; /* far above what 48 points and 4000 Steiner points need */
    tsr_allocator alloc;
    fuzz_limited_allocator(&alloc, &limit);
    tsr_status s = tsr_triangulate(&in, &o, &t, &alloc, &err);
    if (s == TSR_ERR_NOMEM)
        return 0;
    if (bad) {
        if (s != TSR_ERR_ARGUMENT || !err.message[0])
            fuzz_fail("triangulate: invalid input gave status %d (%s), not TSR_ERR_ARGUMENT", (int)s, err.message);
        return 0;
    }
    if (s != TSR_OK)
        fuzz_fail("triangulate: valid input refused, status %d: %s", (int)s, err.message);

    fuzz_check_triangulation(&in, &o, &t, "triangulate");
    /* values carried to the vertices: an affine field at the input points
     * comes out as the same field at every vertex (linear interpolation
     * reproduces it; rounding aside) */
    if (nv > 0) {
        double iv[MAX_POINTS], *ov = tsr_alloc(&alloc, ((size_t)t.nv + 1) * sizeof *ov);
        for (uint32_t i = 0; i < nv; i++)
            iv[i] = 1 + 2 * xy[2 * i] - 3 * xy[2 * i + 1];
        tsr_status si = ov ? tsr_tri_interpolate(&in, iv, 1, &t, ov, &alloc, &err) : TSR_ERR_NOMEM;
        if (si != TSR_OK && si != TSR_ERR_NOMEM)
            fuzz_fail("triangulate: tsr_tri_interpolate refused, status %d: %s", (int)si, err.message);
        for (uint32_t v = 0; si == TSR_OK && v < t.nv; v++) {
            double want = 1 + 2 * t.xy[2 * (size_t)v] - 3 * t.xy[2 * (size_t)v + 1];
            if (!(fabs(ov[v] - want) <= 1e-9 * 100))
                fuzz_fail("triangulate: vertex %u (%.17g, %.17g) carries %.17g, the affine field is %.17g", v,
                          t.xy[2 * (size_t)v], t.xy[2 * (size_t)v + 1], ov[v], want);
        }
        tsr_free(&alloc, ov);
    }
    /* the quadtree method keeps the Delaunay method's region: same area
     * (within slivers of rounding), whatever the refinement */
    if (o.method == TSR_TRI_QUADTREE && !seed_on_feature(&in) &&
        (o.region != TSR_REGION_EVEN_ODD || t.fallback_cells == 0 || closed_input(&in))) {
        tsr_tri_options od = o;
        od.method = TSR_TRI_DELAUNAY;
        tsr_triangulation td;
        size_t limit2 = (size_t)256 << 20;
        tsr_allocator alloc2;
        fuzz_limited_allocator(&alloc2, &limit2);
        tsr_status sd = tsr_triangulate(&in, &od, &td, &alloc2, &err);
        if (sd == TSR_OK) {
            double aq = kept_area(&t), ad = kept_area(&td), lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
            for (uint32_t i = 0; i < nv; i++)
                for (int k = 0; k < 2; k++) {
                    lo[k] = fmin(lo[k], xy[2 * i + k]);
                    hi[k] = fmax(hi[k], xy[2 * i + k]);
                }
            double d2 = (hi[0] - lo[0]) * (hi[0] - lo[0]) + (hi[1] - lo[1]) * (hi[1] - lo[1]);
            if (fabs(aq - ad) > 1e-8 * d2)
                fuzz_fail("triangulate: quadtree keeps area %.17g, the Delaunay method %.17g (box diagonal^2 %g)", aq,
                          ad, d2);
            tsr_triangulation_free(&td);
        } else if (sd != TSR_ERR_NOMEM) {
            fuzz_fail("triangulate: the Delaunay method refused what the quadtree took: status %d: %s", (int)sd,
                      err.message);
        }
    }
    tsr_triangulation_free(&t);
    return 0;
}

#ifdef TSR_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_triangulate(data, size);
}
#endif
