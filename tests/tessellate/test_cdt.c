/* Delaunay triangulation: checked with the exact predicates, independently
 * of how it was built: every triangle counter-clockwise, every interior edge
 * locally Delaunay (so the whole is Delaunay), the triangle count 2n - h - 2
 * with h the hull's vertices from this test's own monotone chain, and the
 * area equal to the hull's. */
#include "check.h"
#include "tessellate/tessellate.h"

#include <stdint.h>

static uint64_t rs = 42;
static double urand(void)
{
    rs = rs * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(rs >> 11) * (1.0 / 9007199254740992.0);
}

typedef struct edge_rec {
    uint64_t key; /* directed edge a -> b */
    uint32_t opp; /* the third vertex */
} edge_rec;

static int edge_cmp(const void *a, const void *b)
{
    const edge_rec *x = a, *y = b;
    return x->key < y->key ? -1 : x->key > y->key;
}

static int pt_cmp(const void *a, const void *b)
{
    const double *x = a, *y = b;
    if (x[0] != y[0])
        return x[0] < y[0] ? -1 : 1;
    return x[1] < y[1] ? -1 : x[1] > y[1];
}

/* Hull vertices (collinear ones on the boundary included) and area, by
 * Andrew's monotone chain with exact orientation. */
static void hull(const double *pts_in, uint32_t n, uint32_t *h_count, double *area)
{
    double *p = malloc(2 * (size_t)n * sizeof *p), *h = malloc(4 * ((size_t)n + 1) * sizeof *h);
    memcpy(p, pts_in, 2 * (size_t)n * sizeof *p);
    qsort(p, n, 2 * sizeof(double), pt_cmp);
    uint32_t m = 0;
    for (uint32_t i = 0; i < n; i++) { /* distinct only */
        if (m && p[2 * (m - 1)] == p[2 * i] && p[2 * (m - 1) + 1] == p[2 * i + 1])
            continue;
        p[2 * m] = p[2 * i];
        p[2 * m + 1] = p[2 * i + 1];
        m++;
    }
    uint32_t k = 0;
    for (int pass = 0; pass < 2; pass++) {
        uint32_t start = k;
        for (uint32_t j = 0; j < m; j++) {
            uint32_t i = pass == 0 ? j : m - 1 - j;
            while (k >= start + 2 && tsr_orient2d(h + 2 * (k - 2), h + 2 * (k - 1), p + 2 * i) < 0)
                k--; /* keep collinear points */
            h[2 * k] = p[2 * i];
            h[2 * k + 1] = p[2 * i + 1];
            k++;
        }
        k--; /* the last point starts the other chain */
    }
    double a = 0;
    for (uint32_t i = 0; i < k; i++) {
        const double *u = h + 2 * i, *v = h + 2 * ((i + 1) % k);
        a += u[0] * v[1] - u[1] * v[0];
    }
    *h_count = k;
    *area = a / 2;
    free(p);
    free(h);
}

/* Checks the triangulation of pts (the distinct inserted points). */
static void check_delaunay(tsr_cdt *d, const char *what)
{
    uint32_t nv = tsr_cdt_vertex_count(d), nt = tsr_cdt_triangle_count(d);
    double *pts = malloc(2 * ((size_t)nv + 1) * sizeof *pts);
    for (uint32_t v = 0; v < nv; v++)
        tsr_cdt_vertex(d, v, pts + 2 * v);
    uint32_t *tri = malloc(3 * ((size_t)nt + 1) * sizeof *tri);
    CHECK(tsr_cdt_triangles(d, tri, nt) == nt);
    int bad_ccw = 0, bad_delaunay = 0, bad_edges = 0;
    double area = 0;
    edge_rec *e = malloc(3 * ((size_t)nt + 1) * sizeof *e);
    for (uint32_t t = 0; t < nt; t++) {
        const double *a = pts + 2 * tri[3 * t], *b = pts + 2 * tri[3 * t + 1], *c = pts + 2 * tri[3 * t + 2];
        bad_ccw += !(tsr_orient2d(a, b, c) > 0);
        area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
        for (int k = 0; k < 3; k++) {
            e[3 * t + k].key = (uint64_t)tri[3 * t + k] << 32 | tri[3 * t + (k + 1) % 3];
            e[3 * t + k].opp = tri[3 * t + (k + 2) % 3];
        }
    }
    qsort(e, 3 * (size_t)nt, sizeof *e, edge_cmp);
    for (uint32_t t = 0; t < 3 * nt; t++) {
        if (t > 0 && e[t].key == e[t - 1].key)
            bad_edges++; /* a directed edge used twice: overlap */
        uint32_t a = (uint32_t)(e[t].key >> 32), b = (uint32_t)e[t].key;
        edge_rec want = {(uint64_t)b << 32 | a, 0};
        edge_rec *twin = bsearch(&want, e, 3 * (size_t)nt, sizeof *e, edge_cmp);
        if (twin && tsr_incircle(pts + 2 * a, pts + 2 * b, pts + 2 * e[t].opp, pts + 2 * twin->opp) > 0)
            bad_delaunay++;
    }
    uint32_t h;
    double harea;
    hull(pts, nv, &h, &harea);
    uint32_t want_t = nv >= 3 && harea != 0 ? 2 * nv - h - 2 : 0;
    CHECK_MSG(bad_ccw == 0 && bad_delaunay == 0 && bad_edges == 0, "%s: %d not ccw, %d not Delaunay, %d overlaps", what,
              bad_ccw, bad_delaunay, bad_edges);
    CHECK_MSG(nt == want_t, "%s: %u triangles, want 2n - h - 2 = %u (n %u, h %u)", what, nt, want_t, nv, h);
    CHECK_MSG(fabs(area - harea) <= 1e-9 * fabs(harea) + 1e-12, "%s: area %.17g, hull %.17g", what, area, harea);
    free(e);
    free(tri);
    free(pts);
}

TEST(random_points)
{
    for (uint32_t n = 3; n <= 20000; n = n * 7 + 1) {
        double *xy = malloc(2 * (size_t)n * sizeof *xy);
        for (uint32_t i = 0; i < 2 * n; i++)
            xy[i] = urand() * 100 - 50;
        tsr_cdt *d = tsr_cdt_create(NULL);
        CHECK(tsr_cdt_insert_points(d, xy, n, NULL) == TSR_OK);
        CHECK(tsr_cdt_vertex_count(d) == n);
        char what[64];
        snprintf(what, sizeof what, "%u random points", n);
        check_delaunay(d, what);
        /* locate: every query inside the hull lands in a triangle holding it */
        for (int q = 0; q < 200; q++) {
            double p[2] = {urand() * 100 - 50, urand() * 100 - 50};
            uint32_t t[3];
            if (tsr_cdt_locate(d, p[0], p[1], t)) {
                double a[2], b[2], c[2];
                tsr_cdt_vertex(d, t[0], a);
                tsr_cdt_vertex(d, t[1], b);
                tsr_cdt_vertex(d, t[2], c);
                CHECK(tsr_orient2d(a, b, p) >= 0 && tsr_orient2d(b, c, p) >= 0 && tsr_orient2d(c, a, p) >= 0);
            }
        }
        tsr_cdt_destroy(d);
        free(xy);
    }
}

TEST(exact_duplicates)
{
    tsr_cdt *d = tsr_cdt_create(NULL);
    double xy[2 * 300];
    for (int i = 0; i < 100; i++) {
        xy[2 * i] = xy[2 * (i + 100)] = xy[2 * (i + 200)] = (double)(i % 10);
        xy[2 * i + 1] = xy[2 * (i + 100) + 1] = xy[2 * (i + 200) + 1] = (double)(i / 10);
    }
    uint32_t ids[300];
    CHECK(tsr_cdt_insert_points(d, xy, 300, ids) == TSR_OK);
    CHECK(tsr_cdt_vertex_count(d) == 100 && tsr_cdt_duplicate_count(d) == 200);
    for (int i = 0; i < 100; i++)
        CHECK(ids[i] == ids[i + 100] && ids[i] == ids[i + 200]);
    check_delaunay(d, "duplicates");
    tsr_cdt_destroy(d);
}

TEST(all_collinear)
{
    tsr_cdt *d = tsr_cdt_create(NULL);
    for (int i = 0; i < 1000; i++)
        CHECK(tsr_cdt_insert(d, i, 3.0 * i) != UINT32_MAX); /* exactly collinear */
    CHECK(tsr_cdt_triangle_count(d) == 0 && tsr_cdt_vertex_count(d) == 1000);
    /* one point off the line: the fan of 999 triangles */
    tsr_cdt_insert(d, 0, 1);
    CHECK(tsr_cdt_triangle_count(d) == 999);
    check_delaunay(d, "collinear then one off");
    tsr_cdt_destroy(d);
}

TEST(integer_grid_and_circle)
{
    uint32_t m = 100;
    double *xy = malloc(2 * (size_t)m * m * sizeof *xy);
    for (uint32_t i = 0; i < m * m; i++) {
        xy[2 * i] = i % m;
        xy[2 * i + 1] = i / m;
    }
    tsr_cdt *d = tsr_cdt_create(NULL);
    CHECK(tsr_cdt_insert_points(d, xy, m * m, NULL) == TSR_OK);
    CHECK(tsr_cdt_triangle_count(d) == 2 * (m - 1) * (m - 1));
    check_delaunay(d, "100x100 grid");
    tsr_cdt_destroy(d);
    free(xy);
    /* 512 cocircular points (exactly: on the circle of radius 2^20 up to
     * rounding, perturbing nothing) and the centre */
    d = tsr_cdt_create(NULL);
    for (int i = 0; i < 512; i++)
        tsr_cdt_insert(d, ldexp(cos(i * 0.01227184630308513), 20), ldexp(sin(i * 0.01227184630308513), 20));
    tsr_cdt_insert(d, 0, 0);
    check_delaunay(d, "circle and centre");
    tsr_cdt_destroy(d);
}

TEST(order_independent_in_general_position)
{
    uint32_t n = 2000;
    double *xy = malloc(2 * (size_t)n * sizeof *xy);
    for (uint32_t i = 0; i < 2 * n; i++)
        xy[i] = urand();
    tsr_cdt *a = tsr_cdt_create(NULL), *b = tsr_cdt_create(NULL);
    uint32_t *ida = malloc(n * sizeof *ida), *idb = malloc(n * sizeof *idb);
    tsr_cdt_insert_points(a, xy, n, ida);
    for (uint32_t i = n; i-- > 0;) /* reverse order, one at a time */
        idb[i] = tsr_cdt_insert(b, xy[2 * i], xy[2 * i + 1]);
    uint32_t nt = tsr_cdt_triangle_count(a);
    CHECK(nt == tsr_cdt_triangle_count(b));
    /* the Delaunay triangulation is unique: compare as sets of input-index
     * triples (rotated so the smallest comes first) */
    uint32_t *ta = malloc(3 * (size_t)nt * sizeof *ta), *tb = malloc(3 * (size_t)nt * sizeof *tb);
    tsr_cdt_triangles(a, ta, nt);
    tsr_cdt_triangles(b, tb, nt);
    uint32_t *inva = malloc(n * sizeof *inva), *invb = malloc(n * sizeof *invb);
    for (uint32_t i = 0; i < n; i++) {
        inva[ida[i]] = i;
        invb[idb[i]] = i;
    }
    uint64_t *ka = malloc(nt * sizeof *ka), *kb = malloc(nt * sizeof *kb);
    for (uint32_t t = 0; t < nt; t++) {
        uint32_t x[3] = {inva[ta[3 * t]], inva[ta[3 * t + 1]], inva[ta[3 * t + 2]]};
        uint32_t y[3] = {invb[tb[3 * t]], invb[tb[3 * t + 1]], invb[tb[3 * t + 2]]};
        int rx = x[0] < x[1] ? (x[0] < x[2] ? 0 : 2) : (x[1] < x[2] ? 1 : 2);
        int ry = y[0] < y[1] ? (y[0] < y[2] ? 0 : 2) : (y[1] < y[2] ? 1 : 2);
        ka[t] = (uint64_t)x[rx] << 42 | (uint64_t)x[(rx + 1) % 3] << 21 | x[(rx + 2) % 3];
        kb[t] = (uint64_t)y[ry] << 42 | (uint64_t)y[(ry + 1) % 3] << 21 | y[(ry + 2) % 3];
    }
    for (uint32_t i = 1; i < nt; i++) { /* insertion sort is fine for 4000 */
        uint64_t v = ka[i];
        uint32_t j = i;
        while (j > 0 && ka[j - 1] > v) {
            ka[j] = ka[j - 1];
            j--;
        }
        ka[j] = v;
        v = kb[i];
        j = i;
        while (j > 0 && kb[j - 1] > v) {
            kb[j] = kb[j - 1];
            j--;
        }
        kb[j] = v;
    }
    CHECK(memcmp(ka, kb, nt * sizeof *ka) == 0);
    free(ka); free(kb); free(inva); free(invb); free(ta); free(tb); free(ida); free(idb); free(xy);
    tsr_cdt_destroy(a);
    tsr_cdt_destroy(b);
}

TEST(non_finite_refused)
{
    tsr_cdt *d = tsr_cdt_create(NULL);
    double xy[6] = {0, 0, 1, NAN, 2, 2};
    CHECK(tsr_cdt_insert_points(d, xy, 3, NULL) == TSR_ERR_ARGUMENT);
    CHECK(tsr_cdt_vertex_count(d) == 0);
    CHECK(tsr_cdt_insert(d, INFINITY, 0) == UINT32_MAX);
    tsr_cdt_destroy(d);
}

TEST_MAIN(T(random_points), T(exact_duplicates), T(all_collinear), T(integer_grid_and_circle),
          T(order_independent_in_general_position), T(non_finite_refused))
