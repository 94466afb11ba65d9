/* Quadtree triangulation (qtri.c), checked by oracles written here from
 * the input and the output alone: every triangle strictly counter-
 * clockwise (exact orient2d); every edge shared by two triangles in
 * opposite directions except on the border of the square; the areas adding
 * up to the square's; every input point an output vertex at its exact
 * place; every input segment a chain of listed constrained edges along it;
 * crossings counted against an all-pairs count; then, through
 * tsr_triangulate, the kept region's area against the polygon's own and
 * the independent checker tsr_triangulation_check. */
#include "check.h"
#include "tessellate/tessellate.h"
#include "tessellate/triangulate_internal.h"

#include <stdint.h>

#define PI 3.14159265358979323846

static uint64_t rs = 7;
static double urand(void)
{
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rs >> 11) * (1.0 / 9007199254740992.0);
}

/* ---- oracles ---------------------------------------------------------- */

static int u64_cmp(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

typedef struct raw_info {
    double x0, y0, x1, y1; /* the square, from the output */
    bool ok;
} raw_info;

/* A triangulation of a square: CCW triangles, edges matched in opposite
 * pairs, unmatched edges on the square's border, area = the square's. */
static raw_info check_square_mesh(const tsr_triangulation *t, const char *what)
{
    raw_info r = {INFINITY, INFINITY, -INFINITY, -INFINITY, true};
    for (uint32_t v = 0; v < t->nv; v++) {
        double x = t->xy[2 * v], y = t->xy[2 * v + 1];
        r.x0 = fmin(r.x0, x), r.x1 = fmax(r.x1, x), r.y0 = fmin(r.y0, y), r.y1 = fmax(r.y1, y);
    }
    CHECK_MSG(fabs((r.x1 - r.x0) - (r.y1 - r.y0)) <= 1e-12 * (r.x1 - r.x0),
              "%s: the output's bounding box is not a square", what);
    uint32_t bad_index = 0, not_ccw = 0;
    double sum = 0, comp = 0; /* Neumaier */
    uint64_t *e = malloc(3 * (size_t)t->nt * sizeof *e + 1);
    uint8_t *used = calloc((size_t)t->nv + 1, 1);
    for (uint32_t i = 0; i < t->nt; i++) {
        const uint32_t *c = t->tri + 3 * (size_t)i;
        if (c[0] >= t->nv || c[1] >= t->nv || c[2] >= t->nv) {
            bad_index++;
            continue;
        }
        const double *a = t->xy + 2 * c[0], *b = t->xy + 2 * c[1], *d = t->xy + 2 * c[2];
        if (!(tsr_orient2d(a, b, d) > 0))
            not_ccw++;
        double ar = 0.5 * ((b[0] - a[0]) * (d[1] - a[1]) - (b[1] - a[1]) * (d[0] - a[0]));
        double s = sum + ar;
        comp += fabs(sum) >= fabs(ar) ? (sum - s) + ar : (ar - s) + sum;
        sum = s;
        for (int k = 0; k < 3; k++) {
            e[3 * (size_t)i + k] = (uint64_t)c[k] << 32 | c[(k + 1) % 3];
            used[c[k]] = 1;
        }
    }
    CHECK_MSG(bad_index == 0, "%s: %u triangles with bad indices", what, bad_index);
    CHECK_MSG(not_ccw == 0, "%s: %u triangles not counter-clockwise", what, not_ccw);
    double square = (r.x1 - r.x0) * (r.y1 - r.y0);
    CHECK_MSG(fabs(sum + comp - square) <= 1e-12 * square, "%s: area %.17g, square %.17g", what, sum + comp, square);
    /* each directed edge once; its reverse present unless on the border */
    size_t ne = 3 * (size_t)t->nt;
    qsort(e, ne, sizeof *e, u64_cmp);
    uint32_t dup = 0, open_inside = 0;
    for (size_t i = 0; i < ne; i++) {
        if (i && e[i] == e[i - 1])
            dup++;
        uint32_t a = (uint32_t)(e[i] >> 32), b = (uint32_t)e[i];
        uint64_t rev = (uint64_t)b << 32 | a;
        if (bsearch(&rev, e, ne, sizeof *e, u64_cmp))
            continue;
        const double *p = t->xy + 2 * a, *q = t->xy + 2 * b;
        bool border =
            (p[0] == q[0] && (p[0] == r.x0 || p[0] == r.x1)) || (p[1] == q[1] && (p[1] == r.y0 || p[1] == r.y1));
        if (!border)
            open_inside++;
    }
    CHECK_MSG(dup == 0, "%s: %u edges used twice in one direction", what, dup);
    CHECK_MSG(open_inside == 0, "%s: %u unmatched edges inside the square (T-junctions or holes)", what, open_inside);
    uint32_t unused = 0;
    for (uint32_t v = 0; v < t->nv; v++)
        unused += !used[v];
    CHECK_MSG(unused == 0, "%s: %u vertices in no triangle", what, unused);
    r.ok = bad_index == 0 && not_ccw == 0 && dup == 0 && open_inside == 0 && unused == 0;
    free(e);
    free(used);
    return r;
}

static double seg_tol(const double *A, const double *B)
{
    double m = fmax(fmax(fabs(A[0]), fabs(A[1])), fmax(fabs(B[0]), fabs(B[1])));
    return 1e-9 * hypot(B[0] - A[0], B[1] - A[1]) + 1e-13 * m;
}

/* Distance of P from the line AB and its position along AB (0 at A, 1 at B). */
static void on_line(const double *A, const double *B, const double *P, double *dist, double *t)
{
    double ux = B[0] - A[0], uy = B[1] - A[1], L2 = ux * ux + uy * uy;
    double px = P[0] - A[0], py = P[1] - A[1];
    *dist = fabs(ux * py - uy * px) / sqrt(L2);
    *t = (ux * px + uy * py) / L2;
}

typedef struct adj {
    uint32_t *start, *to;
} adj;

/* Input points in place; each constrained edge a triangle edge lying on its
 * segment; each input segment a chain of constrained edges along it. */
static void check_input_kept(const tsr_pslg *in, const tsr_triangulation *t, const char *what)
{
    uint32_t moved = 0;
    for (uint32_t i = 0; i < in->nv; i++) {
        uint32_t v = t->vertex_of_input[i];
        if (v >= t->nv || t->xy[2 * v] != in->xy[2 * i] || t->xy[2 * v + 1] != in->xy[2 * i + 1])
            moved++;
    }
    CHECK_MSG(moved == 0, "%s: %u input points not at their output vertex", what, moved);
    if (moved)
        return;
    size_t ne3 = 3 * (size_t)t->nt;
    uint64_t *te = malloc(ne3 * sizeof *te + 1);
    for (size_t i = 0; i < ne3; i++) {
        uint32_t a = t->tri[i], b = t->tri[i % 3 == 2 ? i - 2 : i + 1];
        te[i] = (uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a);
    }
    qsort(te, ne3, sizeof *te, u64_cmp);
    uint32_t not_edge = 0, off_segment = 0;
    for (uint32_t i = 0; i < t->nedge; i++) {
        uint32_t a = t->edge[2 * i], b = t->edge[2 * i + 1], s = t->edge_segment[i];
        uint64_t k = (uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a);
        if (!bsearch(&k, te, ne3, sizeof *te, u64_cmp))
            not_edge++;
        if (s >= in->nseg) {
            off_segment++;
            continue;
        }
        const double *A = in->xy + 2 * in->seg[2 * s], *B = in->xy + 2 * in->seg[2 * s + 1];
        double tol = seg_tol(A, B), L = hypot(B[0] - A[0], B[1] - A[1]);
        for (int j = 0; j < 2; j++) {
            double d, u;
            on_line(A, B, t->xy + 2 * t->edge[2 * i + j], &d, &u);
            if (d > tol || u < -tol / L || u > 1 + tol / L)
                off_segment++;
        }
    }
    CHECK_MSG(not_edge == 0, "%s: %u constrained edges are not triangle edges", what, not_edge);
    CHECK_MSG(off_segment == 0, "%s: %u constrained edge ends off their segment", what, off_segment);
    /* adjacency over constrained edges */
    adj g;
    g.start = calloc((size_t)t->nv + 2, sizeof *g.start);
    g.to = malloc(2 * (size_t)t->nedge * sizeof *g.to + 1);
    for (uint32_t i = 0; i < 2 * t->nedge; i++)
        g.start[t->edge[i] + 1]++;
    for (uint32_t v = 0; v < t->nv; v++)
        g.start[v + 1] += g.start[v];
    uint32_t *fill = malloc(((size_t)t->nv + 1) * sizeof *fill);
    memcpy(fill, g.start, (size_t)t->nv * sizeof *fill);
    for (uint32_t i = 0; i < t->nedge; i++) {
        g.to[fill[t->edge[2 * i]]++] = t->edge[2 * i + 1];
        g.to[fill[t->edge[2 * i + 1]]++] = t->edge[2 * i];
    }
    /* b reachable from a over constrained edges whose ends lie on ab: a
     * path along the line covers the segment (crossing clusters a few ulps
     * wide may make the path step back, so no monotonicity is asked) */
    uint32_t broken = 0, *queue = malloc(((size_t)t->nv + 1) * sizeof *queue),
             *mark = calloc((size_t)t->nv + 1, sizeof *mark);
    for (uint32_t s = 0; s < in->nseg; s++) {
        uint32_t a = t->vertex_of_input[in->seg[2 * s]], b = t->vertex_of_input[in->seg[2 * s + 1]];
        if (a == b)
            continue;
        const double *A = t->xy + 2 * a, *B = t->xy + 2 * b;
        double tol = seg_tol(A, B), tu = tol / hypot(B[0] - A[0], B[1] - A[1]);
        size_t head = 0, tail = 0;
        queue[tail++] = a;
        mark[a] = s + 1;
        while (head < tail && mark[b] != s + 1) {
            uint32_t cur = queue[head++];
            for (uint32_t k = g.start[cur]; k < g.start[cur + 1]; k++) {
                uint32_t w = g.to[k];
                double d, u;
                on_line(A, B, t->xy + 2 * w, &d, &u);
                if (mark[w] != s + 1 && d <= tol && u >= -tu && u <= 1 + tu) {
                    mark[w] = s + 1;
                    queue[tail++] = w;
                }
            }
        }
        if (mark[b] != s + 1) {
            if (broken < 3)
                fprintf(stderr, "%s: segment %u (%u-%u) is not a chain of constrained edges\n", what, s, a, b);
            broken++;
        }
    }
    free(queue);
    free(mark);
    CHECK_MSG(broken == 0, "%s: %u segments missing", what, broken);
    free(te);
    free(g.start);
    free(g.to);
    free(fill);
}

/* Runs the quadtree method alone (no region removal) and checks it. */
static tsr_status run_raw(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *t, const char *what)
{
    const char *why = NULL;
    tsr_error err;
    tsr_status st = tsr__tri_quadtree(in, opt, t, NULL, &why, &err);
    if (st != TSR_OK) {
        if (st != TSR_ERR_UNSUPPORTED || !why)
            CHECK_MSG(0, "%s: %s", what, err.message);
        return st;
    }
    raw_info r = check_square_mesh(t, what);
    if (r.ok)
        check_input_kept(in, t, what);
    return st;
}

/* Whether the Delaunay method (the fallback of hard cells) is available. */
static bool delaunay_available(void)
{
    static const double xy[] = {0, 0, 1, 0, 0, 1};
    tsr_pslg in = {xy, 3, NULL, 0, NULL, 0};
    tsr_tri_options o = {0};
    tsr_triangulation t;
    if (tsr_triangulate(&in, &o, &t, NULL, NULL) != TSR_OK)
        return false;
    tsr_triangulation_free(&t);
    return true;
}

static double shoelace(const double *xy, const uint32_t *ring, uint32_t n)
{
    double a = 0, ox = xy[2 * ring[0]], oy = xy[2 * ring[0] + 1]; /* relative to a corner: no cancellation */
    for (uint32_t i = 0; i < n; i++) {
        const double *p = xy + 2 * ring[i], *q = xy + 2 * ring[(i + 1) % n];
        a += (p[0] - ox) * (q[1] - oy) - (p[1] - oy) * (q[0] - ox);
    }
    return a / 2;
}

/* Through tsr_triangulate with a region: kept area, fell_back, checker. */
static void check_region(const tsr_pslg *in, tsr_tri_options o, double expect_area, const char *what)
{
    tsr_triangulation t;
    tsr_error err;
    o.method = TSR_TRI_QUADTREE;
    tsr_status st = tsr_triangulate(in, &o, &t, NULL, &err);
    if (st == TSR_ERR_UNSUPPORTED)
        return; /* Delaunay path not there yet */
    CHECK_MSG(st == TSR_OK, "%s: %s", what, err.message);
    if (st != TSR_OK)
        return;
    /* the even-odd rule goes to the Delaunay path for now (tsr_triangulate
     * says why); every other region must stay on the quadtree */
    CHECK_MSG(!t.fell_back || o.region == TSR_REGION_EVEN_ODD, "%s: fell back: %s", what,
              t.fallback_reason ? t.fallback_reason : "?");
    double sum = 0;
    for (uint32_t i = 0; i < t.nt; i++) {
        const double *a = t.xy + 2 * t.tri[3 * i], *b = t.xy + 2 * t.tri[3 * i + 1], *c = t.xy + 2 * t.tri[3 * i + 2];
        sum += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    }
    if (!isnan(expect_area))
        CHECK_MSG(fabs(sum - expect_area) <= 1e-11 * fabs(expect_area), "%s: kept area %.17g, expected %.17g", what,
                  sum, expect_area);
    tsr_tri_check c;
    if (tsr_triangulation_check(in, &o, &t, &c) == TSR_OK)
        CHECK_MSG(c.ok, "%s: checker: %s", what, c.first_problem);
    tsr_triangulation_free(&t);
}

/* ---- inputs ----------------------------------------------------------- */

/* A random star-shaped polygon of n vertices around (cx, cy): angles
 * sorted, radii in [r/3, r]; segments i -> i+1. */
static void star_polygon(uint32_t n, double cx, double cy, double r, double *xy, uint32_t *seg)
{
    double *ang = malloc(n * sizeof *ang);
    for (uint32_t i = 0; i < n; i++)
        ang[i] = 2 * PI * ((double)i + 0.8 * urand()) / n;
    for (uint32_t i = 0; i < n; i++) {
        double rr = r * (1.0 / 3 + 2.0 / 3 * urand());
        xy[2 * i] = cx + rr * cos(ang[i]);
        xy[2 * i + 1] = cy + rr * sin(ang[i]);
        seg[2 * i] = i;
        seg[2 * i + 1] = (i + 1) % n;
    }
    free(ang);
}

/* ---- tests ------------------------------------------------------------ */

TEST(single_triangle)
{
    static const double xy[] = {0, 0, 1, 0, 0.3, 0.8};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 0};
    tsr_pslg in = {xy, 3, seg, 3, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    CHECK(run_raw(&in, &o, &t, "triangle") == TSR_OK);
    CHECK(t.input_vertices == 3 && t.duplicates == 0 && t.intersections == 0 && t.fallback_cells == 0);
    CHECK(t.steiner == t.nv - 3);
    tsr_triangulation_free(&t);
    check_region(&in, o, 0.4, "triangle region");
}

TEST(round_coordinates_square_with_hole)
{
    /* round coordinates: with an unshifted square these sides would lie on grid lines */
    static const double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.25, 0.25, 0.75, 0.25, 0.75, 0.75, 0.25, 0.75};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 6, 6, 7, 7, 4};
    tsr_pslg in = {xy, 8, seg, 8, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_EVEN_ODD};
    tsr_triangulation t;
    CHECK(run_raw(&in, &o, &t, "square with hole") == TSR_OK);
    CHECK(t.nedge >= 8);
    tsr_triangulation_free(&t);
    check_region(&in, o, 0.75, "square with hole, even-odd");
    o.region = TSR_REGION_ENCLOSED;
    check_region(&in, o, 1.0, "square with hole, enclosed");
}

TEST(star_polygons_many_seeds)
{
    for (uint32_t seed = 0; seed < 300; seed++) {
        rs = seed * 2654435761u + 1;
        uint32_t n = 3 + (uint32_t)(urand() * (seed < 270 ? 60 : 400));
        double *xy = malloc(2 * n * sizeof *xy);
        uint32_t *seg = malloc(2 * n * sizeof *seg), *ring = malloc(n * sizeof *ring);
        double scale = pow(10, (double)(seed % 7) - 3), off = (seed % 3) * 1e3 * scale;
        star_polygon(n, off, -off, scale, xy, seg);
        for (uint32_t i = 0; i < n; i++)
            ring[i] = i;
        tsr_pslg in = {xy, n, seg, n, NULL, 0};
        tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
        tsr_triangulation t;
        char what[64];
        snprintf(what, sizeof what, "star seed %u (n %u)", seed, n);
        if (run_raw(&in, &o, &t, what) == TSR_OK) {
            CHECK_MSG(t.intersections == 0 && t.fallback_cells == 0, "%s: %u crossings, %u fallback cells", what,
                      t.intersections, t.fallback_cells);
            tsr_triangulation_free(&t);
        }
        if (seed % 10 == 0)
            check_region(&in, o, shoelace(xy, ring, n), what);
        free(xy);
        free(seg);
        free(ring);
        if (check_failures)
            break;
    }
}

TEST(random_points_many_seeds)
{
    for (uint32_t seed = 0; seed < 200; seed++) {
        rs = seed + 1000;
        uint32_t n = 3 + (uint32_t)(urand() * 300);
        double *xy = malloc(2 * n * sizeof *xy);
        for (uint32_t i = 0; i < 2 * n; i++)
            xy[i] = seed % 2 ? urand() : floor(urand() * 16) / 16; /* also many duplicates on a lattice */
        tsr_pslg in = {xy, n, NULL, 0, NULL, 0};
        tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
        tsr_triangulation t;
        char what[64];
        snprintf(what, sizeof what, "points seed %u", seed);
        tsr_status st = run_raw(&in, &o, &t, what);
        if (st == TSR_OK) {
            CHECK(t.input_vertices + t.duplicates == n);
            tsr_triangulation_free(&t);
        }
        free(xy);
        if (check_failures)
            break;
    }
}

/* k horizontal and k vertical segments: k^2 crossings, each a new vertex. */
TEST(crossing_segments_grid)
{
    enum { K = 7 };
    double xy[8 * K];
    uint32_t seg[4 * K];
    for (uint32_t i = 0; i < K; i++) {
        double c = 0.1 + 0.7 * i / (K - 1) + 0.003 * i * i;
        double *h = xy + 8 * i;
        h[0] = 0, h[1] = c, h[2] = 1, h[3] = c + 0.01 * i; /* nearly horizontal */
        h[4] = c, h[5] = 0, h[6] = c - 0.02 * i, h[7] = 1; /* nearly vertical */
        seg[4 * i] = 4 * i, seg[4 * i + 1] = 4 * i + 1, seg[4 * i + 2] = 4 * i + 2, seg[4 * i + 3] = 4 * i + 3;
    }
    tsr_pslg in = {xy, 4 * K, seg, 2 * K, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "grid of crossings") == TSR_OK) {
        uint32_t expect = 0; /* every pair of one nearly horizontal and one nearly vertical segment */
        for (uint32_t i = 0; i < K; i++)
            for (uint32_t j = 0; j < K; j++) {
                const double *a = xy + 8 * i, *b = a + 2, *c = xy + 8 * j + 4, *d = c + 2;
                expect += tsr_orient2d(a, b, c) * tsr_orient2d(a, b, d) < 0 &&
                          tsr_orient2d(c, d, a) * tsr_orient2d(c, d, b) < 0;
            }
        CHECK(expect == K * K);
        CHECK_MSG(t.intersections == expect, "%u crossings, expected %u", t.intersections, expect);
        tsr_triangulation_free(&t);
    }
}

/* Random segments in general position: crossings against an all-pairs count. */
TEST(random_crossing_segments)
{
    for (uint32_t seed = 0; seed < 40; seed++) {
        rs = seed + 77;
        uint32_t ns = 2 + (uint32_t)(urand() * 40);
        double *xy = malloc(4 * ns * sizeof *xy);
        uint32_t *seg = malloc(2 * ns * sizeof *seg);
        for (uint32_t i = 0; i < 4 * ns; i++)
            xy[i] = urand();
        for (uint32_t i = 0; i < 2 * ns; i++)
            seg[i] = i;
        uint32_t expect = 0;
        for (uint32_t i = 0; i < ns; i++)
            for (uint32_t j = i + 1; j < ns; j++) {
                const double *a = xy + 4 * i, *b = a + 2, *c = xy + 4 * j, *d = c + 2;
                if (tsr_orient2d(a, b, c) * tsr_orient2d(a, b, d) < 0 &&
                    tsr_orient2d(c, d, a) * tsr_orient2d(c, d, b) < 0)
                    expect++;
            }
        tsr_pslg in = {xy, 2 * ns, seg, ns, NULL, 0};
        tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
        tsr_triangulation t;
        char what[64];
        snprintf(what, sizeof what, "random segments seed %u", seed);
        if (run_raw(&in, &o, &t, what) == TSR_OK) {
            CHECK_MSG(t.intersections == expect, "%s: %u crossings, expected %u", what, t.intersections, expect);
            tsr_triangulation_free(&t);
        }
        free(xy);
        free(seg);
        if (check_failures)
            break;
    }
}

TEST(vertex_on_segment_and_collinear_overlap)
{
    /* segment 0 passes through point 4; segments 1 and 2 overlap on [1, 2] x {0} */
    static const double xy[] = {-1, -1, 3, 3, 0, 0, 2, 0, 1, 1, 1, 0, 3, 0, 0, 2};
    static const uint32_t seg[] = {0, 1, 2, 3, 5, 6};
    tsr_pslg in = {xy, 8, seg, 3, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "vertex on segment") != TSR_OK)
        return;
    CHECK(t.intersections == 0);
    /* an edge is listed once per segment covering it, ids ascending: the
     * overlap [1, 2] x {0} carries segments 1 and 2, the rest of y = 0 one */
    uint32_t on_overlap[3] = {0, 0, 0};
    for (uint32_t i = 0; i < t.nedge; i++) {
        double ya = t.xy[2 * t.edge[2 * i] + 1], yb = t.xy[2 * t.edge[2 * i + 1] + 1];
        double xa = t.xy[2 * t.edge[2 * i]], xb = t.xy[2 * t.edge[2 * i + 1]];
        if (ya != 0 || yb != 0)
            continue;
        uint32_t s = t.edge_segment[i];
        if (fmin(xa, xb) >= 1 && fmax(xa, xb) <= 2) {
            CHECK_MSG(s == 1 || s == 2, "overlap edge has segment %u", s);
            on_overlap[s] += s <= 2;
            if (s == 2)
                CHECK_MSG(i > 0 && t.edge_segment[i - 1] == 1 &&
                              t.edge[2 * i - 2] + t.edge[2 * i - 1] == t.edge[2 * i] + t.edge[2 * i + 1],
                          "segment 2's entry does not follow segment 1's");
        } else
            CHECK(s == (fmax(xa, xb) <= 1 ? 1u : 2u));
    }
    CHECK(on_overlap[1] > 0 && on_overlap[1] == on_overlap[2]);
    tsr_triangulation_free(&t);
}

TEST(duplicates_and_degenerate_segments)
{
    static const double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 1, 0, -0.0, 0.0, 0.5, 0.5};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 1, 4, 0, 5, 6, 6, 1, 0};
    tsr_pslg in = {xy, 7, seg, 8, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "duplicates") != TSR_OK)
        return;
    CHECK(t.input_vertices == 5 && t.duplicates == 2);
    CHECK(t.vertex_of_input[4] == t.vertex_of_input[1] && t.vertex_of_input[5] == t.vertex_of_input[0]);
    CHECK(t.degenerate_segments == 3);
    /* segment 7 repeats segment 0 reversed: each of its edges is listed for
     * both, 0 first */
    uint32_t n0 = 0, n7 = 0;
    for (uint32_t i = 0; i < t.nedge; i++) {
        n0 += t.edge_segment[i] == 0;
        n7 += t.edge_segment[i] == 7;
        if (t.edge_segment[i] == 7)
            CHECK(i > 0 && t.edge_segment[i - 1] == 0);
    }
    CHECK(n7 > 0 && n0 == n7);
    tsr_triangulation_free(&t);
    check_region(&in, o, 1.0, "duplicates region");
}

/* The square of a first run, read off its output, places features on and
 * beside its grid lines and corners in a second run with the same box. */
TEST(vertex_near_cell_corner_and_grid_lines)
{
    static const double box[] = {0, 0, 1, 0, 1, 1, 0, 1};
    tsr_pslg in0 = {box, 4, NULL, 0, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in0, &o, &t, "box") != TSR_OK)
        return;
    double x0 = INFINITY, y0 = INFINITY, x1 = -INFINITY;
    for (uint32_t v = 0; v < t.nv; v++)
        x0 = fmin(x0, t.xy[2 * v]), y0 = fmin(y0, t.xy[2 * v + 1]), x1 = fmax(x1, t.xy[2 * v]);
    double S = x1 - x0, cx = x0 + S / 2, cy = y0 + S / 2, qx = x0 + S * 0.375, qy = y0 + S * 0.625;
    tsr_triangulation_free(&t);
    const double eps[] = {1e-3, 1e-6, 1e-9, 1e-12};
    for (int k = 0; k < 4; k++) {
        double e = eps[k] * S;
        double xy[] = {0,      0,
                       1,      0,
                       1,      1,
                       0,      1,
                       cx + e, cy + e,       /* near the centre corner */
                       qx - e, qy + 0.5 * e, /* near a level-3 corner */
                       0.05,   cy + e,
                       0.95,   cy + e, /* horizontal, just above a grid line */
                       qx + e, 0.1,
                       qx + e, 0.9, /* vertical, just right of one */
                       0.1,    0.2,
                       0.2,    0.2}; /* horizontal segment */
        uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 6, 7, 8, 9, 10, 11};
        tsr_pslg in = {xy, 12, seg, 7, NULL, 0};
        char what[64];
        snprintf(what, sizeof what, "near grid, eps %g", eps[k]);
        tsr_status st = run_raw(&in, &o, &t, what);
        if (st != TSR_OK)
            continue;
        /* no refinement along the whole grid-hugging segments */
        CHECK_MSG(t.nt < 200000, "%s: %u triangles", what, t.nt);
        tsr_triangulation_free(&t);
    }
    /* and exactly on grid lines and corners: the square moves off them */
    double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, cx, cy, qx, qy, 0.05, cy, 0.95, cy, qx, 0.1, qx, 0.9};
    uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 6, 7, 8, 9};
    tsr_pslg in = {xy, 10, seg, 6, NULL, 0};
    if (run_raw(&in, &o, &t, "on grid lines") == TSR_OK) {
        CHECK(t.fallback_cells == 0);
        tsr_triangulation_free(&t);
    }
}

TEST(high_degree_vertex)
{
    enum { N = 97 };
    double xy[2 * (N + 1)];
    uint32_t seg[2 * N];
    xy[0] = 0.1, xy[1] = -0.2;
    for (uint32_t i = 0; i < N; i++) {
        double a = 2 * PI * i / N;
        xy[2 * i + 2] = 0.1 + cos(a) * (1 + 0.3 * (i % 3));
        xy[2 * i + 3] = -0.2 + sin(a) * (1 + 0.3 * (i % 3));
        seg[2 * i] = 0, seg[2 * i + 1] = i + 1;
    }
    tsr_pslg in = {xy, N + 1, seg, N, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "high degree") == TSR_OK)
        tsr_triangulation_free(&t);
}

TEST(max_area)
{
    static const double xy[] = {0, 0, 3, 0, 3, 2, 0, 2, 1, 1};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0};
    tsr_pslg in = {xy, 5, seg, 4, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED, .max_area = 0.01};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "max area") != TSR_OK)
        return;
    uint32_t big = 0;
    for (uint32_t i = 0; i < t.nt; i++) {
        const double *a = t.xy + 2 * t.tri[3 * i], *b = t.xy + 2 * t.tri[3 * i + 1], *c = t.xy + 2 * t.tri[3 * i + 2];
        big += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])) > 0.01;
    }
    CHECK_MSG(big == 0, "%u triangles above the maximum area", big);
    tsr_triangulation_free(&t);
    check_region(&in, o, 6.0, "max area region");
}

TEST(near_coincident_features_fall_back)
{
    if (!delaunay_available())
        SKIP("the Delaunay method is not available yet");
    /* two points 1e-12 apart and a segment passing 1e-13 from a third */
    static const double xy[] = {0,   0,           1,   0,   1,   1,   0,           1,   0.3,
                                0.3, 0.3 + 1e-12, 0.3, 0.2, 0.6, 0.8, 0.6 + 1e-13, 0.5, 0.6};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 6, 7, 4, 5};
    tsr_pslg in = {xy, 9, seg, 6, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation t;
    if (run_raw(&in, &o, &t, "near coincident") != TSR_OK)
        return;
    CHECK(t.fallback_cells > 0);
    CHECK(t.fallback_reason != NULL);
    tsr_triangulation_free(&t);
    check_region(&in, o, 1.0, "near coincident region");
    /* a shallow depth limit sends many cells to the fallback */
    rs = 5;
    double pxy[2 * 200];
    uint32_t pseg[2 * 200];
    star_polygon(200, 0, 0, 1, pxy, pseg);
    tsr_pslg star = {pxy, 200, pseg, 200, NULL, 0};
    o.max_depth = 4;
    if (run_raw(&star, &o, &t, "depth 4") == TSR_OK) {
        CHECK(t.fallback_cells > 0);
        tsr_triangulation_free(&t);
    }
}

TEST(segment_hugging_square_side_beside_fallback_cell)
{
    /* The fuzz find quadtree_segment_hugging_square_side_missing: segment 0
     * runs up the quadtree square's right side, 1.4e-11 inside it, to
     * (15 (1 + 2^-40), 15); segments 2 and 3 cross 2.6e-11 left of it,
     * beside two points 1.4e-11 apart (a fallback cell), and with segment
     * 1 they enclose a sliver of area 1e-10 whose corner touches segment 0
     * only at its end. The crossing lies within the checker's tolerance of
     * segment 0 and its kept triangle covers the direction back down the
     * segment, though the segment passes it by: the region is right, and
     * the checker must find segment 0 outside it. */
    const double e = 15 * (1 + 0x1p-40);
    const double xy[] = {15,  -16, e,   15, -0.0029296875, -2.5, -8, -0.0029296875, e, e,   -16, -15,
                         -16, -16, -16, -8, -2.5,          -15,  -8, 0.0068359375,  0, -16, 10,  3.25};
    static const uint32_t seg[] = {0, 1, 1, 2, 3, 1, 4, 2, 5, 0};
    tsr_pslg in = {xy, 12, seg, 5, NULL, 0};
    tsr_tri_options o = {.method = TSR_TRI_QUADTREE, .region = TSR_REGION_ENCLOSED, .max_area = 64};
    tsr_triangulation t;
    tsr_error err;
    CHECK_MSG(tsr_triangulate(&in, &o, &t, NULL, &err) == TSR_OK, "%s", err.message);
    CHECK(t.fallback_cells > 0 && !t.fell_back);
    /* the sliver, and a vertex off segment 0 by less than its tolerance */
    double area = 0;
    for (uint32_t i = 0; i < t.nt; i++) {
        const double *a = t.xy + 2 * t.tri[3 * i], *b = t.xy + 2 * t.tri[3 * i + 1], *c = t.xy + 2 * t.tri[3 * i + 2];
        area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
    }
    CHECK_MSG(area > 0.9e-10 && area < 1.1e-10, "kept area %g", area);
    uint32_t beside = 0;
    for (uint32_t v = 0; v < t.nv; v++) {
        double d, u;
        on_line(xy, xy + 2, t.xy + 2 * v, &d, &u);
        beside += d > 0 && d < 1e-10 && u > 0 && u < 1;
    }
    CHECK_MSG(beside > 0, "no vertex beside segment 0: the case is not exercised");
    tsr_tri_check c;
    CHECK(tsr_triangulation_check(&in, &o, &t, &c) == TSR_OK);
    CHECK_MSG(c.ok && c.missing_segments == 0, "checker: %s", c.first_problem);
    tsr_triangulation_free(&t);
}

TEST(unsupported_inputs)
{
    static const double xy[] = {0, 0, 1, 0, 2, 0, 0, 1};
    tsr_pslg in = {xy, 4, NULL, 0, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_HULL};
    tsr_triangulation t;
    const char *why = NULL;
    CHECK(tsr__tri_quadtree(&in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    CHECK(t.nt == 0 && t.tri == NULL);
    o.region = TSR_REGION_ENCLOSED;
    in.nv = 3; /* collinear */
    why = NULL;
    CHECK(tsr__tri_quadtree(&in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    in.nv = 2;
    why = NULL;
    CHECK(tsr__tri_quadtree(&in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    in.nv = 4;
    o.conforming = true;
    why = NULL;
    CHECK(tsr__tri_quadtree(&in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    o.conforming = false;
    o.min_angle = 20;
    why = NULL;
    CHECK(tsr__tri_quadtree(&in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    /* through tsr_triangulate the whole input goes to the Delaunay method */
    o.min_angle = 0;
    o.region = TSR_REGION_HULL;
    o.method = TSR_TRI_QUADTREE;
    tsr_status st = tsr_triangulate(&in, &o, &t, NULL, NULL);
    if (st == TSR_OK) {
        CHECK(t.fell_back && t.fallback_reason);
        tsr_triangulation_free(&t);
    }
    static const double huge[] = {-1.5e308, 0, 1.5e308, 0, 0, 1}; /* its square would not fit in a double */
    tsr_pslg huge_in = {huge, 3, NULL, 0, NULL, 0};
    why = NULL;
    CHECK(tsr__tri_quadtree(&huge_in, &o, &t, NULL, &why, NULL) == TSR_ERR_UNSUPPORTED && why);
    static const double bad[] = {0, 0, 1, NAN, 0, 1};
    tsr_pslg nan_in = {bad, 3, NULL, 0, NULL, 0};
    o.region = TSR_REGION_ENCLOSED;
    CHECK(tsr__tri_quadtree(&nan_in, &o, &t, NULL, &why, NULL) == TSR_ERR_ARGUMENT);
    static const uint32_t badseg[] = {0, 7};
    tsr_pslg seg_in = {xy, 4, badseg, 1, NULL, 0};
    CHECK(tsr__tri_quadtree(&seg_in, &o, &t, NULL, &why, NULL) == TSR_ERR_ARGUMENT);
}

/* The even-odd area of a raw output by this test's own flood fill from the
 * square's border: crossing an edge flips the parity once per listed entry
 * (one per segment covering it), so doubled segments cancel. */
static double even_odd_area(const tsr_triangulation *t)
{
    size_t m = 3 * (size_t)t->nt, ne = m + t->nedge;
    /* (undirected edge << 1 | listed entry, half-edge or entry index) pairs */
    uint64_t *pk = malloc(ne * 2 * sizeof *pk);
    for (size_t i = 0; i < ne; i++) {
        uint32_t a, b;
        if (i < m)
            a = t->tri[i], b = t->tri[i % 3 == 2 ? i - 2 : i + 1];
        else
            a = t->edge[2 * (i - m)], b = t->edge[2 * (i - m) + 1];
        pk[2 * i] = ((uint64_t)(a < b ? a : b) << 32 | (a < b ? b : a)) << 1 | (i >= m);
        pk[2 * i + 1] = i;
    }
    qsort(pk, ne, 2 * sizeof *pk, u64_cmp);
    uint32_t *nb = malloc(m * sizeof *nb);
    uint8_t *flip = calloc(m, 1);
    for (size_t i = 0; i < m; i++)
        nb[i] = UINT32_MAX;
    for (size_t i = 0, j; i < ne; i = j) {
        uint32_t half[2], n = 0, entries = 0;
        for (j = i; j < ne && pk[2 * j] >> 1 == pk[2 * i] >> 1; j++) {
            if (pk[2 * j] & 1)
                entries++;
            else if (n < 2)
                half[n++] = (uint32_t)pk[2 * j + 1];
        }
        if (n == 2) {
            nb[half[0]] = half[1] / 3;
            nb[half[1]] = half[0] / 3;
            flip[half[0]] = flip[half[1]] = entries & 1;
        }
    }
    uint8_t *par = malloc((size_t)t->nt + 1);
    uint32_t *queue = malloc(((size_t)t->nt + 1) * sizeof *queue);
    size_t head = 0, tail = 0;
    memset(par, 2, t->nt);
    for (uint32_t i = 0; i < t->nt; i++)
        for (int k = 0; k < 3; k++)
            if (nb[3 * i + k] == UINT32_MAX && par[i] == 2) {
                par[i] = 0; /* on the square's border: outside */
                queue[tail++] = i;
            }
    while (head < tail) {
        uint32_t i = queue[head++];
        for (int k = 0; k < 3; k++) {
            uint32_t n = nb[3 * i + k];
            if (n != UINT32_MAX && par[n] == 2) {
                par[n] = par[i] ^ flip[3 * i + k];
                queue[tail++] = n;
            }
        }
    }
    double area = 0;
    for (uint32_t i = 0; i < t->nt; i++)
        if (par[i] == 1) {
            const double *a = t->xy + 2 * t->tri[3 * i], *b = t->xy + 2 * t->tri[3 * i + 1];
            const double *c = t->xy + 2 * t->tri[3 * i + 2];
            area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        }
    free(pk);
    free(nb);
    free(flip);
    free(par);
    free(queue);
    return area;
}

/* A ring given twice, a segment doubling back inside a ring, a hole sharing
 * an edge with the outer ring: even-odd areas from the raw output's edge
 * counts (the region pass of tsr_triangulate needs the same counts). */
TEST(even_odd_parity_of_overlaps)
{
    static const struct {
        const char *what;
        uint32_t nv, nseg;
        double xy[16];
        uint32_t seg[16];
        double area;
    } cases[] = {
        {"ring given twice", 4, 8, {0, 0, 4, 0, 4, 4, 0, 4}, {0, 1, 1, 2, 2, 3, 3, 0, 0, 1, 1, 2, 2, 3, 3, 0}, 0},
        {"segment doubling back",
         6,
         7,
         {0, 0, 4, 0, 4, 4, 0, 4, 1, 1, 3, 2},
         {0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 4, 4, 5},
         16},
        {"hole sharing an edge",
         8,
         8,
         {0, 0, 4, 0, 4, 4, 0, 4, 0, 1, 2, 1, 2, 3, 0, 3},
         {0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 6, 6, 7, 7, 4},
         12},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        tsr_pslg in = {cases[c].xy, cases[c].nv, cases[c].seg, cases[c].nseg, NULL, 0};
        tsr_tri_options o = {.region = TSR_REGION_EVEN_ODD};
        tsr_triangulation t;
        if (run_raw(&in, &o, &t, cases[c].what) != TSR_OK)
            continue;
        double a = even_odd_area(&t);
        CHECK_MSG(fabs(a - cases[c].area) <= 1e-12 * 16, "%s: even-odd area %.17g, expected %g", cases[c].what, a,
                  cases[c].area);
        tsr_triangulation_free(&t);
    }
}

/* Kept area and crossings of both methods on in under region r; the
 * quadtree's result also passes the checker. */
static void both_methods(const tsr_pslg *in, tsr_region r, double area[2], uint32_t crossings[2],
                         uint32_t *fallback_cells)
{
    tsr_tri_options o = {.region = r};
    for (int m = 0; m < 2; m++) {
        tsr_triangulation t;
        tsr_error err;
        area[m] = 0;
        crossings[m] = 0;
        o.method = m ? TSR_TRI_QUADTREE : TSR_TRI_DELAUNAY;
        if (tsr_triangulate(in, &o, &t, NULL, &err) != TSR_OK) {
            CHECK_MSG(false, "method %d: %s", m, err.message);
            continue;
        }
        for (uint32_t i = 0; i < t.nt; i++) {
            const double *a = t.xy + 2 * t.tri[3 * i], *b = t.xy + 2 * t.tri[3 * i + 1];
            const double *c = t.xy + 2 * t.tri[3 * i + 2];
            area[m] += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        }
        crossings[m] = t.intersections;
        CHECK(!t.fell_back);
        if (m)
            *fallback_cells = t.fallback_cells;
        tsr_tri_check c;
        CHECK(tsr_triangulation_check(in, &o, &t, &c) == TSR_OK);
        CHECK_MSG(c.ok, "region %d, method %d: checker: %s", (int)o.region, m, c.first_problem);
        tsr_triangulation_free(&t);
    }
}

/* Under EVEN_ODD and under ENCLOSED, both methods keep the same area
 * (within tol); crossings[r] (may be NULL) gets region r's intersection
 * counts (Delaunay, quadtree), r 0 even-odd, 1 enclosed. */
static void methods_agree(const tsr_pslg *in, double tol, uint32_t crossings[2][2])
{
    for (int r = 0; r < 2; r++) {
        double area[2];
        uint32_t cr[2], fb = 0;
        both_methods(in, r ? TSR_REGION_ENCLOSED : TSR_REGION_EVEN_ODD, area, cr, &fb);
        CHECK_MSG(fabs(area[1] - area[0]) <= tol, "region %d: quadtree kept %.17g, Delaunay %.17g", r, area[1],
                  area[0]);
        if (crossings)
            crossings[r][0] = cr[0], crossings[r][1] = cr[1];
    }
}

/* The fuzz finds quadtree_evenodd_region_kept_where_delaunay_keeps_none and
 * its hole seed sibling, cut down: segment 0 runs along y = x from
 * (-16, -16) to (8, 8), segment 2 from (5, 5) back to (-16, -16) along it,
 * and segment 1 crosses both; segment 3 joins the crossing segment's end
 * to (5, 5). The pair tests split segment 0 at (5, 5), so both cover one
 * piece there, counted twice: the even-odd rule does not count it, nothing
 * is enclosed, and the Delaunay method keeps nothing. The crossing was
 * computed once from each whole segment, two vertices an ulp apart: the
 * two halves stayed two chains (90 fallback cells along them), crossing
 * them cost two, and the triangle between segments 1, 3 and the line,
 * reached across segment 1 alone, was kept (area 39.06). */
TEST(even_odd_overlapping_segments_crossed_at_one_vertex)
{
    static const double xy[] = {5, 5, 8, 0, 8, 8, -16, 3, -16, -16};
    static const uint32_t seg[] = {4, 2, 1, 3, 0, 4, 3, 0};
    tsr_pslg in = {xy, 5, seg, 4, NULL, 0};
    if (!delaunay_available())
        SKIP("the Delaunay method is not available yet");
    uint32_t crossings[2][2];
    methods_agree(&in, 1e-12 * 64, crossings);
    for (int r = 0; r < 2; r++)
        CHECK_MSG(crossings[r][1] == 1 && crossings[r][0] == 1, "region %d: %u crossings (Delaunay %u), not 1", r,
                  crossings[r][1], crossings[r][0]);
}

/* The fuzz find quadtree_evenodd_keeps_less_than_delaunay_2, cut down:
 * segment 0 runs from (2, -14) through the vertex (-7, -15) to (-16, -16);
 * five more segments leave that vertex upwards. In the vertex's leaf the
 * segment passed as a chord between two rounded side points, the vertex
 * 1e-15 above it: the fan from the vertex made a flat triangle under it
 * that joined the sectors left and right of the upward segments, and the
 * triangle enclosed by segments 0, 1 and 3 (area 64.2) was lost. A chord
 * exactly through a leaf's vertex now makes the leaf not simple, and the
 * pair tests split the segment there. */
TEST(chord_through_vertex_split_there)
{
    const double e = 1 + 0x1p-40;
    const double xy[] = {-7, -15, 2, -14, 7 * e, 15 * e, 15, 6 * e, -16, -16, 6, 6, 2, 6, 6, 2, -0.009765625, 5};
    static const uint32_t seg[] = {1, 4, 1, 5, 2, 0, 7, 0, 8, 0, 5, 0, 6, 0};
    tsr_pslg in = {xy, 9, seg, 7, NULL, 0};
    if (!delaunay_available())
        SKIP("the Delaunay method is not available yet");
    methods_agree(&in, 1e-12 * 1024, NULL);
}

/* After the fuzz find quadtree_evenodd_keeps_less_than_delaunay, closed:
 * the triangle (-7, -7), (-1/146.3, -7 - 6.4e-12), (15 + 1.4e-11, 2); the
 * segment from (-7, -7) to (-3 - 2.7e-12, -7 - 6.4e-12), 2.7e-12 below the
 * triangle's side, and from there to (15 + 1.4e-11, 2), both given twice;
 * a lone point 9e-12 from (-7, -7).
 * Near (-7, -7) the cells go to the Delaunay fallback, where the two lines
 * meet a cell side at one rounded point: their chains merge into one edge,
 * which that method names by its lowest chain alone. The edge counted as
 * covered twice (even), the triangle's side had a gap there, and the
 * quadtree kept nothing. Every chain on a merged edge now keeps its cover
 * (three: odd). */
TEST(fallback_keeps_every_cover_of_merged_chains)
{
    const double e = 1 + 0x1p-40;
    const double xy[] = {-7, -7, -0.0068359375, -7 * e, 15 * e, 2, -3 * e, -7 * e, -7 * e, -7 * e};
    static const uint32_t seg[] = {0, 1, 1, 2, 2, 0, 0, 3, 3, 0, 2, 3, 3, 2};
    tsr_pslg in = {xy, 5, seg, 7, NULL, 0};
    if (!delaunay_available())
        SKIP("the Delaunay method is not available yet");
    double area[2];
    uint32_t crossings[2], fb = 0;
    both_methods(&in, TSR_REGION_EVEN_ODD, area, crossings, &fb);
    CHECK_MSG(fabs(area[1] - area[0]) <= 1e-12 * 512, "quadtree kept %.17g, Delaunay %.17g", area[1], area[0]);
    CHECK_MSG(area[0] > 30, "the Delaunay method kept %.17g, not the triangle", area[0]);
    CHECK_MSG(fb > 0, "no cell went to the fallback: the test no longer reaches the merge");
}

/* Points on a small lattice joined at random: duplicates, collinear
 * overlaps, points inside segments, crossings at lattice points and
 * between them; with the default depth and with a shallow one (many
 * cells through the Delaunay fallback). */
TEST(lattice_segments_degenerate)
{
    bool dl = delaunay_available();
    for (uint32_t seed = 0; seed < 120; seed++) {
        rs = seed * 31 + 5;
        uint32_t nv = 4 + (uint32_t)(urand() * 30), ns = (uint32_t)(urand() * 25), side = 3 + seed % 5;
        double *xy = malloc(2 * nv * sizeof *xy);
        uint32_t *seg = malloc(2 * (ns + 1) * sizeof *seg);
        for (uint32_t i = 0; i < 2 * nv; i++)
            xy[i] = floor(urand() * side) * 0.5;
        for (uint32_t i = 0; i < 2 * ns; i++)
            seg[i] = (uint32_t)(urand() * nv);
        tsr_pslg in = {xy, nv, seg, ns, NULL, 0};
        tsr_tri_options o = {.region = TSR_REGION_ENCLOSED, .max_depth = seed % 3 == 2 ? 5 : 0};
        tsr_triangulation t;
        char what[64];
        snprintf(what, sizeof what, "lattice seed %u depth %u", seed, o.max_depth);
        const char *why = NULL;
        tsr_error err;
        tsr_status st = tsr__tri_quadtree(&in, &o, &t, NULL, &why, &err);
        if (st == TSR_OK) {
            raw_info r = check_square_mesh(&t, what);
            if (r.ok)
                check_input_kept(&in, &t, what);
            tsr_triangulation_free(&t);
        } else
            CHECK_MSG(st == TSR_ERR_UNSUPPORTED && why && (!dl || strstr(why, "Delaunay") == NULL), "%s: %s", what,
                      err.message);
        free(xy);
        free(seg);
        if (check_failures)
            break;
    }
}

/* ---- the region chosen from the cells against the general pass -------- */

typedef struct ctri {
    double c[6];
} ctri;

static int ctri_cmp(const void *a, const void *b)
{
    const double *x = ((const ctri *)a)->c, *y = ((const ctri *)b)->c;
    for (int k = 0; k < 6; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

/* The triangles by their corners' coordinates, each starting at its least
 * corner, sorted: equal lists mean the same triangles, whatever the
 * vertex numbering. */
static ctri *canonical(const tsr_triangulation *t)
{
    ctri *c = malloc(((size_t)t->nt + 1) * sizeof *c);
    for (uint32_t i = 0; i < t->nt; i++) {
        int first = 0;
        for (int k = 1; k < 3; k++) {
            const double *p = t->xy + 2 * t->tri[3 * i + k], *f = t->xy + 2 * t->tri[3 * i + first];
            if (p[0] < f[0] || (p[0] == f[0] && p[1] < f[1]))
                first = k;
        }
        for (int k = 0; k < 3; k++) {
            const double *p = t->xy + 2 * t->tri[3 * i + (first + k) % 3];
            c[i].c[2 * k] = p[0];
            c[i].c[2 * k + 1] = p[1];
        }
    }
    qsort(c, t->nt, sizeof *c, ctri_cmp);
    return c;
}

/* The same with the constrained edges: both ends (least first) and the
 * segment. */
static ctri *canonical_edges(const tsr_triangulation *t)
{
    ctri *c = malloc(((size_t)t->nedge + 1) * sizeof *c);
    for (uint32_t i = 0; i < t->nedge; i++) {
        const double *p = t->xy + 2 * t->edge[2 * i], *q = t->xy + 2 * t->edge[2 * i + 1];
        if (q[0] < p[0] || (q[0] == p[0] && q[1] < p[1])) {
            const double *w = p;
            p = q, q = w;
        }
        c[i] = (ctri){{p[0], p[1], q[0], q[1], t->edge_segment[i], 0}};
    }
    qsort(c, t->nedge, sizeof *c, ctri_cmp);
    return c;
}

/* tsr_triangulate's quadtree result (the region chosen from the cells where
 * it can) against the raw method followed by the general region pass: the
 * same triangles, constrained edges and vertices. Returns whether the cells
 * chose (-1: the method did not apply). */
static int same_as_general(const tsr_pslg *in, tsr_tri_options o, const char *what)
{
    o.method = TSR_TRI_QUADTREE;
    tsr_triangulation a, b;
    const char *why = NULL;
    bool done = false;
    tsr_error err;
    tsr_status sa = tsr__tri_quadtree_region(in, &o, &a, NULL, &done, &why, &err);
    tsr_status sb = tsr__tri_quadtree(in, &o, &b, NULL, &why, &err);
    CHECK_MSG(sa == sb, "%s: statuses %d and %d", what, (int)sa, (int)sb);
    if (sa != TSR_OK || sb != TSR_OK) {
        if (sa == TSR_OK)
            tsr_triangulation_free(&a);
        if (sb == TSR_OK)
            tsr_triangulation_free(&b);
        return -1;
    }
    if (!done)
        CHECK(tsr__tri_apply_region(&a, in, &o) == TSR_OK);
    CHECK(tsr__tri_apply_region(&b, in, &o) == TSR_OK);
    CHECK_MSG(a.nt == b.nt && a.nv == b.nv && a.nedge == b.nedge && a.steiner == b.steiner,
              "%s (%s): %u/%u triangles, %u/%u vertices, %u/%u edges", what, done ? "cells" : "general", a.nt, b.nt,
              a.nv, b.nv, a.nedge, b.nedge);
    if (a.nt == b.nt) {
        ctri *ca = canonical(&a), *cb = canonical(&b);
        CHECK_MSG(memcmp(ca, cb, a.nt * sizeof *ca) == 0, "%s: different triangles", what);
        free(ca);
        free(cb);
    }
    if (a.nedge == b.nedge) {
        ctri *ca = canonical_edges(&a), *cb = canonical_edges(&b);
        CHECK_MSG(memcmp(ca, cb, a.nedge * sizeof *ca) == 0, "%s: different constrained edges", what);
        free(ca);
        free(cb);
    }
    for (uint32_t i = 0; i < in->nv; i++)
        CHECK(a.vertex_of_input[i] == b.vertex_of_input[i]);
    tsr_triangulation_free(&a);
    tsr_triangulation_free(&b);
    return done;
}

TEST(region_from_cells_matches_general_pass)
{
    uint32_t cells = 0, runs = 0;
    for (uint32_t seed = 0; seed < 160 && !check_failures; seed++) {
        rs = seed * 7919 + 3;
        uint32_t kind = seed % 4, nv, ns;
        double xy[2 * 400];
        uint32_t seg[2 * 420];
        if (kind == 0) { /* star polygons, some with a ring inside given once or twice */
            nv = 3 + (uint32_t)(urand() * 200);
            star_polygon(nv, 0, 0, 1, xy, seg);
            ns = nv;
            if (seed % 8 == 0) {
                double sq[8] = {-0.1, -0.1, 0.1, -0.1, 0.1, 0.1, -0.1, 0.1};
                for (uint32_t k = 0; k < 4; k++) {
                    xy[2 * (nv + k)] = sq[2 * k], xy[2 * (nv + k) + 1] = sq[2 * k + 1];
                    for (uint32_t r = 0; r < 1 + (seed / 8) % 2; r++) {
                        seg[2 * ns] = nv + k, seg[2 * ns + 1] = nv + (k + 1) % 4;
                        ns++;
                    }
                }
                nv += 4;
            }
        } else if (kind == 1) { /* random crossing segments, open polylines */
            ns = 2 + (uint32_t)(urand() * 30);
            nv = 2 * ns;
            for (uint32_t i = 0; i < 2 * nv; i++)
                xy[i] = urand();
            for (uint32_t i = 0; i < 2 * ns; i++)
                seg[i] = i;
        } else if (kind == 2) { /* lattice: duplicates, overlaps, points on segments */
            nv = 4 + (uint32_t)(urand() * 30);
            ns = (uint32_t)(urand() * 25);
            for (uint32_t i = 0; i < 2 * nv; i++)
                xy[i] = floor(urand() * (3 + seed % 5)) * 0.5;
            for (uint32_t i = 0; i < 2 * ns; i++)
                seg[i] = (uint32_t)(urand() * nv);
        } else { /* a fan of segments from one vertex, with a ring around it */
            nv = 1 + (uint32_t)(3 + urand() * 60);
            xy[0] = 0.01 * urand(), xy[1] = 0.01 * urand();
            ns = 0;
            for (uint32_t i = 1; i < nv; i++) {
                double ang = 2 * PI * (i + 0.5 * urand()) / (nv - 1), r = 0.3 + urand();
                xy[2 * i] = r * cos(ang), xy[2 * i + 1] = r * sin(ang);
                seg[2 * ns] = 0, seg[2 * ns + 1] = i, ns++;
                seg[2 * ns] = i, seg[2 * ns + 1] = i + 1 < nv ? i + 1 : 1, ns++;
            }
        }
        tsr_pslg in = {xy, nv, seg, ns, NULL, 0};
        for (int region = 0; region < 2; region++) {
            tsr_tri_options o = {.region = region ? TSR_REGION_EVEN_ODD : TSR_REGION_ENCLOSED};
            o.max_depth = seed % 9 == 4 ? 6 : 0; /* some cells through the Delaunay fallback */
            o.max_area = seed % 11 == 5 ? 0.01 : 0;
            char what[80];
            snprintf(what, sizeof what, "seed %u kind %u %s", seed, kind, region ? "even-odd" : "enclosed");
            int r = same_as_general(&in, o, what);
            runs += r >= 0;
            cells += r == 1;
        }
    }
    /* most inputs have no fallback cell: the cells chose their region */
    CHECK_MSG(cells * 2 > runs, "the cells chose the region in %u of %u runs", cells, runs);
    /* hole seeds: the general pass */
    static const double hxy[] = {0, 0, 4, 0, 4, 4, 0, 4, 1, 1, 3, 1, 3, 3, 1, 3};
    static const uint32_t hseg[] = {0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 6, 6, 7, 7, 4};
    static const double seed_xy[] = {2, 2};
    tsr_pslg hin = {hxy, 8, hseg, 8, seed_xy, 1};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    CHECK(same_as_general(&hin, o, "hole seed") == 0);
}

/* ---- allocator: everything freed, and every failure handled ----------- */


TEST(allocator_failures)
{
    rs = 99;
    double xy[2 * 60];
    uint32_t seg[2 * 62];
    star_polygon(60, 0, 0, 1, xy, seg);
    seg[120] = 3, seg[121] = 33; /* crossings */
    seg[122] = 10, seg[123] = 50;
    tsr_pslg in = {xy, 60, seg, 62, NULL, 0};
    tsr_tri_options o = {.region = TSR_REGION_ENCLOSED};
    check_alloc c = {0};
    tsr_allocator al = {check_realloc, &c, NULL};
    tsr_triangulation t;
    const char *why;
    CHECK(tsr__tri_quadtree(&in, &o, &t, &al, &why, NULL) == TSR_OK);
    long calls = c.calls;
    tsr_triangulation_free(&t);
    CHECK_MSG(c.live == 0, "%ld blocks leaked", c.live);
    for (long k = 1; k <= calls; k += 1 + calls / 200) {
        c = (check_alloc){.fail_at = k};
        tsr_status st = tsr__tri_quadtree(&in, &o, &t, &al, &why, NULL);
        CHECK_MSG(st == TSR_OK || st == TSR_ERR_NOMEM, "failure at allocation %ld: status %d", k, (int)st);
        if (st == TSR_OK)
            tsr_triangulation_free(&t);
        CHECK_MSG(c.live == 0, "failure at allocation %ld: %ld blocks leaked", k, c.live);
    }
    /* and with the region chosen from the cells */
    bool done = false;
    c = (check_alloc){0};
    CHECK(tsr__tri_quadtree_region(&in, &o, &t, &al, &done, &why, NULL) == TSR_OK && done);
    calls = c.calls;
    tsr_triangulation_free(&t);
    for (long k = 1; k <= calls; k += 1 + calls / 200) {
        c = (check_alloc){.fail_at = k};
        tsr_status st = tsr__tri_quadtree_region(&in, &o, &t, &al, &done, &why, NULL);
        CHECK_MSG(st == TSR_OK || st == TSR_ERR_NOMEM, "region: failure at allocation %ld: status %d", k, (int)st);
        if (st == TSR_OK)
            tsr_triangulation_free(&t);
        CHECK_MSG(c.live == 0, "region: failure at allocation %ld: %ld blocks leaked", k, c.live);
    }
}

TEST_MAIN(T(single_triangle), T(round_coordinates_square_with_hole), T(star_polygons_many_seeds),
          T(random_points_many_seeds), T(crossing_segments_grid), T(random_crossing_segments),
          T(vertex_on_segment_and_collinear_overlap), T(duplicates_and_degenerate_segments),
          T(vertex_near_cell_corner_and_grid_lines), T(high_degree_vertex), T(max_area),
          T(near_coincident_features_fall_back), T(segment_hugging_square_side_beside_fallback_cell),
          T(even_odd_parity_of_overlaps), T(even_odd_overlapping_segments_crossed_at_one_vertex),
          T(chord_through_vertex_split_there), T(fallback_keeps_every_cover_of_merged_chains),
          T(lattice_segments_degenerate), T(unsupported_inputs),
          T(region_from_cells_matches_general_pass), T(allocator_failures))
