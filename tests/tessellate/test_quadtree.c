/* The generic restricted quadtree on two closed-form surfaces behind the
 * surface interface: a height function (as a terrain would be) and a torus
 * patch (as a parametric patch would be). Oracles: the mesh validator,
 * exact areas, a brute-force 2:1 check over all leaf pairs, and brute-force
 * distances from every lattice point of the true surface to the mesh. */
#include "check.h"
#include "tessellate/tessellate.h"

/* ---- tile patterns -------------------------------------------------- */

TEST(patterns_conform_for_every_mask)
{
    for (uint32_t n = 2; n <= TSR_TILE_MAX; n *= 2)
        for (unsigned mask = 0; mask < 16; mask++) {
            tsr_mesh m;
            tsr_mesh_init(&m, 0, NULL);
            for (uint32_t j = 0; j <= n; j++)
                for (uint32_t i = 0; i <= n; i++) {
                    float p[3] = {(float)i, (float)j, 0};
                    tsr_mesh_add_vertex(&m, p, NULL, NULL);
                }
            uint32_t cnt = tsr_tile_pattern(n, mask, NULL);
            CHECK(cnt <= tsr_tile_pattern_bound(n));
            tsr_mesh_reserve(&m, m.vertex_count, cnt);
            CHECK(tsr_tile_pattern(n, mask, m.indices) == cnt);
            m.triangle_count = cnt;
            /* dropping an edge's n/2 odd vertices removes n/2 triangles */
            unsigned edges = (mask & 1) + (mask >> 1 & 1) + (mask >> 2 & 1) + (mask >> 3 & 1);
            CHECK(cnt == 2 * n * n - edges * n / 2);
            /* the area is exactly the square's: no gap, no overlap */
            double area = 0;
            for (uint32_t t = 0; t < cnt; t++) {
                const float *a = m.positions + 3 * m.indices[3 * t], *b = m.positions + 3 * m.indices[3 * t + 1],
                            *c = m.positions + 3 * m.indices[3 * t + 2];
                area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
            }
            CHECK_NEAR(area, (double)n * n, 1e-9);
            /* the odd vertices of stitched edges are unused; keep only used
             * vertices in the check by validating (unreferenced are ignored) */
            tsr_validation v;
            tsr_validate_options o = {0};
            o.expect_up = o.height_field = true;
            CHECK(tsr_mesh_validate(&m, &o, &v) == TSR_OK);
            char msg[512];
            tsr_validation_describe(&v, msg, sizeof msg);
            CHECK_MSG(tsr_validation_ok(&v) && v.boundary_loops == 1 && v.euler == 1, "n %u mask %u: %s", n, mask, msg);
            CHECK(v.vertices == (n + 1) * (n + 1) - edges * n / 2);
            tsr_mesh_free(&m);
        }
}

/* ---- test surfaces ---------------------------------------------------- */

typedef struct test_surface {
    int kind; /* 0 height function, 1 torus patch */
    uint32_t size;
    tsr_surface s;
    float *err; /* per node, all levels, brute force */
    size_t *level_base;
} test_surface;

static void eval_d(const test_surface *t, double i, double j, double p[3])
{
    double u = i / t->size, v = j / t->size;
    if (t->kind == 0) {
        p[0] = i;
        p[1] = j;
        p[2] = 6 * sin(u * 7.0) * cos(v * 5.0) + 3 * exp(-40 * ((u - 0.3) * (u - 0.3) + (v - 0.6) * (v - 0.6))) * 4;
    } else {
        double R = 3, r = 1.2, a = u * 3.14159265358979 * 1.5, b = v * 3.14159265358979 * 1.2 - 0.6;
        p[0] = (R + r * cos(b)) * cos(a);
        p[1] = (R + r * cos(b)) * sin(a);
        p[2] = r * sin(b);
    }
}

static bool ts_evaluate(void *user, uint32_t i, uint32_t j, float pos[3], float normal[3])
{
    double p[3];
    eval_d(user, i, j, p);
    for (int k = 0; k < 3; k++)
        pos[k] = (float)p[k];
    if (normal) {
        normal[0] = normal[1] = 0;
        normal[2] = 1;
    }
    return true;
}

static size_t node_index(const test_surface *t, tsr_qnode n) { return t->level_base[n.level] + ((size_t)n.y << n.level) + n.x; }

static void ts_bounds(void *user, tsr_qnode n, float lo[3], float hi[3])
{
    const test_surface *t = user;
    uint32_t w = t->s.tile_n << (t->s.levels - n.level);
    for (int k = 0; k < 3; k++) {
        lo[k] = INFINITY;
        hi[k] = -INFINITY;
    }
    for (uint32_t j = n.y * w; j <= (n.y + 1) * w; j++)
        for (uint32_t i = n.x * w; i <= (n.x + 1) * w; i++) {
            double p[3];
            eval_d(t, i, j, p);
            for (int k = 0; k < 3; k++) {
                lo[k] = fminf(lo[k], (float)p[k]);
                hi[k] = fmaxf(hi[k], (float)p[k]);
            }
        }
}

static float ts_error(void *user, tsr_qnode n) { return ((test_surface *)user)->err[node_index(user, n)]; }

/* Brute force: for every stitch mask, every lattice point in the node, the
 * distance between the surface and the tile's linear interpolation over the
 * pattern triangle containing the point (in lattice coordinates). */
static double node_error_brute(const test_surface *t, tsr_qnode n)
{
    uint32_t N = t->s.tile_n, w = N << (t->s.levels - n.level), s = w / N;
    uint32_t x0 = n.x * w, y0 = n.y * w;
    uint32_t *tri = malloc(3 * tsr_tile_pattern_bound(N) * sizeof *tri);
    double worst = 0;
    for (unsigned mask = 0; mask < 16; mask++) {
        uint32_t cnt = tsr_tile_pattern(N, mask, tri);
        for (uint32_t j = y0; j <= y0 + w; j++)
            for (uint32_t i = x0; i <= x0 + w; i++) {
                double li = (double)(i - x0) / s, lj = (double)(j - y0) / s, best = INFINITY;
                for (uint32_t k = 0; k < cnt; k++) {
                    double P[3][2];
                    for (int c = 0; c < 3; c++) {
                        P[c][0] = tri[3 * k + c] % (N + 1);
                        P[c][1] = tri[3 * k + c] / (N + 1);
                    }
                    double d = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[1][1] - P[0][1]) * (P[2][0] - P[0][0]);
                    double l1 = ((li - P[0][0]) * (P[2][1] - P[0][1]) - (lj - P[0][1]) * (P[2][0] - P[0][0])) / d;
                    double l2 = ((P[1][0] - P[0][0]) * (lj - P[0][1]) - (P[1][1] - P[0][1]) * (li - P[0][0])) / d;
                    double l0 = 1 - l1 - l2;
                    if (l0 < -1e-12 || l1 < -1e-12 || l2 < -1e-12)
                        continue;
                    double q[3] = {0, 0, 0}, p[3], v[3];
                    for (int c = 0; c < 3; c++) {
                        eval_d(t, x0 + P[c][0] * s, y0 + P[c][1] * s, v);
                        double l = c == 0 ? l0 : c == 1 ? l1 : l2;
                        for (int e = 0; e < 3; e++)
                            q[e] += l * v[e];
                    }
                    eval_d(t, i, j, p);
                    double dist = sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) +
                                       (p[2] - q[2]) * (p[2] - q[2]));
                    best = dist < best ? dist : best;
                    break;
                }
                worst = best > worst ? best : worst;
            }
    }
    free(tri);
    return worst;
}

static void surface_init(test_surface *t, int kind, uint32_t tile_n, uint32_t levels)
{
    memset(t, 0, sizeof *t);
    t->kind = kind;
    t->size = tile_n << levels;
    t->s.user = t;
    t->s.tile_n = tile_n;
    t->s.levels = levels;
    t->s.extent_x = t->s.extent_y = t->size;
    t->s.evaluate = ts_evaluate;
    t->s.bounds = ts_bounds;
    t->s.error = ts_error;
    t->level_base = malloc((levels + 2) * sizeof *t->level_base);
    size_t total = 0;
    for (uint32_t l = 0; l <= levels; l++) {
        t->level_base[l] = total;
        total += (size_t)1 << (2 * l);
    }
    t->err = malloc(total * sizeof *t->err);
    for (uint32_t l = levels + 1; l-- > 0;)
        for (uint32_t y = 0; y < (1u << l); y++)
            for (uint32_t x = 0; x < (1u << l); x++) {
                tsr_qnode n = {x, y, (uint8_t)l};
                double e = node_error_brute(t, n);
                if (l < levels) /* monotone: at least the children's */
                    for (unsigned k = 0; k < 4; k++) {
                        tsr_qnode c = {2 * x + (k & 1), 2 * y + (k >> 1), (uint8_t)(l + 1)};
                        e = fmax(e, t->err[node_index(t, c)]);
                    }
                t->err[node_index(t, n)] = (float)e * 1.0001f;
            }
}

static void surface_free(test_surface *t)
{
    free(t->err);
    free(t->level_base);
}

/* 2:1 by brute force: any two leaves sharing a piece of edge differ by at
 * most one level. */
static bool balanced_brute(const tsr_quadtree *qt, const tsr_surface *s)
{
    uint32_t n = tsr_quadtree_leaf_count(qt);
    const tsr_qleaf *L = tsr_quadtree_leaves(qt);
    for (uint32_t a = 0; a < n; a++)
        for (uint32_t b = a + 1; b < n; b++) {
            uint64_t wa = (uint64_t)s->tile_n << (s->levels - L[a].node.level);
            uint64_t wb = (uint64_t)s->tile_n << (s->levels - L[b].node.level);
            uint64_t ax0 = L[a].node.x * wa, ax1 = ax0 + wa, ay0 = L[a].node.y * wa, ay1 = ay0 + wa;
            uint64_t bx0 = L[b].node.x * wb, bx1 = bx0 + wb, by0 = L[b].node.y * wb, by1 = by0 + wb;
            bool share_x = (ax1 == bx0 || bx1 == ax0) && ay0 < by1 && by0 < ay1;
            bool share_y = (ay1 == by0 || by1 == ay0) && ax0 < bx1 && bx0 < ax1;
            int d = (int)L[a].node.level - (int)L[b].node.level;
            if ((share_x || share_y) && (d > 1 || d < -1))
                return false;
        }
    return true;
}

/* Distance from point p to triangle abc (Ericson's closest-point test). */
static double point_triangle_dist(const double p[3], const float *a, const float *b, const float *c)
{
    double ab[3], ac[3], ap[3];
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ac[k] = c[k] - a[k];
        ap[k] = p[k] - a[k];
    }
#define DOT(u, v) (u[0] * v[0] + u[1] * v[1] + u[2] * v[2])
    double d1 = DOT(ab, ap), d2 = DOT(ac, ap), q[3];
    double bp[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]}, cp[3] = {p[0] - c[0], p[1] - c[1], p[2] - c[2]};
    double d3 = DOT(ab, bp), d4 = DOT(ac, bp), d5 = DOT(ab, cp), d6 = DOT(ac, cp);
    double va = d3 * d6 - d5 * d4, vb = d5 * d2 - d1 * d6, vc = d1 * d4 - d3 * d2;
    if (d1 <= 0 && d2 <= 0)
        for (int k = 0; k < 3; k++) q[k] = a[k];
    else if (d3 >= 0 && d4 <= d3)
        for (int k = 0; k < 3; k++) q[k] = b[k];
    else if (d6 >= 0 && d5 <= d6)
        for (int k = 0; k < 3; k++) q[k] = c[k];
    else if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        double v = d1 / (d1 - d3);
        for (int k = 0; k < 3; k++) q[k] = a[k] + v * ab[k];
    } else if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        double w = d2 / (d2 - d6);
        for (int k = 0; k < 3; k++) q[k] = a[k] + w * ac[k];
    } else if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        for (int k = 0; k < 3; k++) q[k] = b[k] + w * (c[k] - b[k]);
    } else {
        double den = 1 / (va + vb + vc), v = vb * den, w = vc * den;
        for (int k = 0; k < 3; k++) q[k] = a[k] + ab[k] * v + ac[k] * w;
    }
#undef DOT
    return sqrt((p[0] - q[0]) * (p[0] - q[0]) + (p[1] - q[1]) * (p[1] - q[1]) + (p[2] - q[2]) * (p[2] - q[2]));
}

/* Vertices that no triangle uses (the stitched-away tile points, unless
 * tsr_quadtree_mesh drops them). */
static uint32_t unused_vertices(const tsr_mesh *m)
{
    uint32_t n = 0;
    unsigned char *used = calloc(m->vertex_count + 1, 1);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        used[m->indices[i]] = 1;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        n += !used[v];
    free(used);
    return n;
}

static void check_surface(int kind, const double *tols, int ntols)
{
    test_surface t;
    surface_init(&t, kind, 8, 3); /* 64 x 64 lattice */
    tsr_quadtree *qt = tsr_quadtree_create(&t.s, NULL);
    CHECK(qt != NULL);
    uint32_t prev_leaves = 0;
    for (int k = 0; k < ntols; k++) {
        double tol = tols[k];
        CHECK(tsr_quadtree_select(qt, tsr_refine_tolerance, &tol) == TSR_OK);
        uint32_t nl = tsr_quadtree_leaf_count(qt);
        CHECK(nl >= prev_leaves); /* tolerances decrease */
        prev_leaves = nl;
        CHECK_MSG(balanced_brute(qt, &t.s), "kind %d tol %g not 2:1", kind, tol);
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        CHECK(tsr_quadtree_mesh(qt, false, &m) == TSR_OK);
        tsr_validation v;
        tsr_validate_options o = {0};
        o.expect_up = o.height_field = kind == 0;
        CHECK(tsr_mesh_validate(&m, &o, &v) == TSR_OK);
        char msg[512];
        tsr_validation_describe(&v, msg, sizeof msg);
        CHECK_MSG(tsr_validation_ok(&v) && v.boundary_loops == 1 && v.euler == 1 && v.coincident_vertices == 0,
                  "kind %d tol %g: %s", kind, tol, msg);
        if (kind == 0)
            CHECK(tsr_mesh_boundary_is_rect(&m, 0, 0, t.size, t.size, 1e-4, NULL));
        /* the bound: every lattice point of the surface is within tol of
         * the mesh (vertically for the height function) */
        double worst = 0;
        for (uint32_t j = 0; j <= t.size; j++)
            for (uint32_t i = 0; i <= t.size; i++) {
                double p[3], best = INFINITY;
                eval_d(&t, i, j, p);
                for (uint32_t tr = 0; tr < m.triangle_count; tr++) {
                    const float *a = m.positions + 3 * m.indices[3 * tr], *b = m.positions + 3 * m.indices[3 * tr + 1],
                                *c = m.positions + 3 * m.indices[3 * tr + 2];
                    if (kind == 0) {
                        double d = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
                        double l1 = ((p[0] - a[0]) * (c[1] - a[1]) - (p[1] - a[1]) * (c[0] - a[0])) / d;
                        double l2 = ((b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0])) / d;
                        if (l1 < -1e-9 || l2 < -1e-9 || l1 + l2 > 1 + 1e-9)
                            continue;
                        double z = a[2] + l1 * (b[2] - a[2]) + l2 * (c[2] - a[2]);
                        best = fabs(z - p[2]);
                        break;
                    }
                    double d = point_triangle_dist(p, a, b, c);
                    best = d < best ? d : best;
                }
                worst = best > worst ? best : worst;
            }
        CHECK_MSG(worst <= tol * 1.0001 + 1e-5, "kind %d tol %g: worst %g", kind, tol, worst);
        fprintf(stderr, "  kind %d tol %-6g leaves %4u triangles %5u worst %.4g (balance splits %u)\n", kind, tol, nl,
                m.triangle_count, worst, tsr_quadtree_balance_splits(qt));
        tsr_mesh_free(&m);
    }
    tsr_quadtree_destroy(qt);
    surface_free(&t);
}

TEST(height_function_bound_and_watertight)
{
    const double tols[] = {5, 1, 0.3, 0.1, 0.03, 0.01};
    check_surface(0, tols, 6);
}

TEST(torus_patch_bound_and_watertight)
{
    const double tols[] = {0.5, 0.1, 0.03, 0.01, 0.003};
    check_surface(1, tols, 5);
}

static bool refine_random(void *user, const tsr_surface *s, tsr_qnode n)
{
    (void)s;
    unsigned *st = user;
    *st = *st * 1103515245u + 12345u;
    return ((*st >> 16) % 100) < (n.level < 2 ? 90u : 35u);
}

TEST(random_cuts_are_balanced_and_conforming)
{
    /* arbitrary refinement (not error-driven) must still give 2:1 cuts and
     * conforming meshes, including extents that clip nodes */
    uint32_t extents[][2] = {{64, 64}, {50, 64}, {64, 37}, {33, 9}, {2, 63}};
    uint32_t balance_splits = 0;
    for (int e = 0; e < 5; e++)
        for (unsigned seed = 1; seed <= 12; seed++) {
            test_surface t;
            memset(&t, 0, sizeof t);
            t.kind = 0;
            t.size = 64;
            t.s.user = &t;
            t.s.tile_n = 4;
            t.s.levels = 4;
            t.s.extent_x = extents[e][0];
            t.s.extent_y = extents[e][1];
            t.s.evaluate = ts_evaluate;
            t.s.bounds = ts_bounds;
            tsr_quadtree *qt = tsr_quadtree_create(&t.s, NULL);
            unsigned st = seed * 7919u;
            CHECK(tsr_quadtree_select(qt, refine_random, &st) == TSR_OK);
            CHECK(balanced_brute(qt, &t.s));
            balance_splits += tsr_quadtree_balance_splits(qt);
            tsr_mesh m;
            tsr_mesh_init(&m, 0, NULL);
            CHECK(tsr_quadtree_mesh(qt, false, &m) == TSR_OK);
            tsr_validation v;
            tsr_validate_options o = {0};
            o.expect_up = o.height_field = true;
            tsr_mesh_validate(&m, &o, &v);
            char msg[512];
            tsr_validation_describe(&v, msg, sizeof msg);
            CHECK_MSG(tsr_validation_ok(&v) && v.boundary_loops == 1, "extent %ux%u seed %u: %s", extents[e][0],
                      extents[e][1], seed, msg);
            CHECK_MSG(unused_vertices(&m) == 0, "extent %ux%u seed %u: %u vertices no triangle uses", extents[e][0],
                      extents[e][1], seed, unused_vertices(&m));
            CHECK(tsr_mesh_boundary_is_rect(&m, 0, 0, extents[e][0], extents[e][1], 1e-4, NULL));
            /* covers exactly the extent: projected area */
            double area = 0;
            for (uint32_t tr = 0; tr < m.triangle_count; tr++) {
                const float *a = m.positions + 3 * m.indices[3 * tr], *b = m.positions + 3 * m.indices[3 * tr + 1],
                            *c = m.positions + 3 * m.indices[3 * tr + 2];
                area += 0.5 * ((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]));
            }
            CHECK_NEAR(area, (double)extents[e][0] * extents[e][1], 1e-3);
            tsr_mesh_free(&m);
            tsr_quadtree_destroy(qt);
        }
    CHECK(balance_splits > 0); /* the balancing step was exercised */
}

TEST(levels_and_keys)
{
    CHECK(tsr_quadtree_levels_for(16, 16, 16) == 0);
    CHECK(tsr_quadtree_levels_for(16, 17, 3) == 1);
    CHECK(tsr_quadtree_levels_for(16, 16384, 16384) == 10);
    CHECK(tsr_quadtree_levels_for(16, 511, 511) == 5);
    tsr_qnode a = {3, 5, 4}, b = {3, 5, 5};
    CHECK(tsr_qnode_key(a) != tsr_qnode_key(b));
    tsr_qnode c = {1, 0, 4}, d = {0, 1, 4};
    CHECK(tsr_qnode_key(c) == (((uint64_t)4 << 56) | 1) && tsr_qnode_key(d) == (((uint64_t)4 << 56) | 2));
}

/* A camera looking straight down (a plan view) is a camera: +x to the
 * right of the screen, +y up it; straight up mirrors x. */
TEST(plan_view_camera)
{
    for (int down = 0; down < 2; down++) {
        tsr_camera c = {0};
        c.eye[2] = down ? 10 : -10;
        c.fovy_deg = 60;
        c.width = 800;
        c.height = 600;
        c.near_dist = 0.1;
        c.pixel_error = 1;
        CHECK(tsr_camera_prepare(&c));
        double sx, sy, d, px = 1, py = 1;
        tsr_camera_project(&c, (double[3]){0, 0, 0}, &sx, &sy, &d);
        CHECK_NEAR(sx, 400, 1e-9);
        CHECK_NEAR(sy, 300, 1e-9);
        CHECK_NEAR(d, 10, 1e-12);
        tsr_camera_project(&c, (double[3]){px, 0, 0}, &sx, &sy, &d);
        CHECK(down ? sx > 400 : sx < 400);
        CHECK_NEAR(sy, 300, 1e-9);
        tsr_camera_project(&c, (double[3]){0, py, 0}, &sx, &sy, &d);
        CHECK(sy < 300);
        CHECK_NEAR(sx, 400, 1e-9);
    }
}

TEST_MAIN(T(plan_view_camera), T(patterns_conform_for_every_mask), T(height_function_bound_and_watertight),
          T(torus_patch_bound_and_watertight), T(random_cuts_are_balanced_and_conforming), T(levels_and_keys))
