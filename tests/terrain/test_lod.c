/* Terrain level of detail: the pyramid against brute force, the error
 * bound (per node against every stitch variant, and of whole cuts against
 * the independent measurement, vertical and on screen), meshes of cuts
 * (watertight, conforming, 2:1, holes at no-data), and picking against a
 * test of every cell. */
#include "check.h"
#include "terrain/terrain.h"

static uint32_t rng_state = 12345;
static double urand(void)
{
    rng_state = rng_state * 1664525u + 1013904223u;
    return (rng_state >> 8) * (1.0 / 16777216.0);
}

static tsr_heightfield *terrain(uint32_t w, uint32_t h, uint32_t seed, double relief)
{
    tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
    tsr_generate_options o = {0};
    o.seed = seed;
    o.relief = relief;
    o.erosion_iterations = 5;
    tsr_terrain_generate(hf, &o);
    return hf;
}

static void punch_holes(tsr_heightfield *hf)
{
    uint32_t w = tsr_heightfield_width(hf), h = tsr_heightfield_height(hf);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < h; r++)
        for (uint32_t c = 0; c < w; c++) {
            double a = (c - 0.3 * w) / (0.08 * w), b = (r - 0.6 * h) / (0.05 * h);
            if (a * a + b * b < 1 || (c == w / 2 && r == h / 3))
                d[r * w + c] = NAN;
        }
}

/* ---- pyramid ---------------------------------------------------------- */

static uint32_t node_width(const tsr_surface *s, tsr_qnode n) { return s->tile_n << (s->levels - n.level); }

TEST(pyramid_ranges_match_brute_force)
{
    tsr_heightfield *hf = terrain(203, 97, 4, 500);
    punch_holes(hf);
    tsr_terrain *t = NULL;
    tsr_terrain_options o = {8};
    CHECK(tsr_terrain_create(hf, &o, NULL, &t, NULL) == TSR_OK);
    const tsr_surface *s = tsr_terrain_surface(t);
    CHECK(s->levels == 5 && s->extent_x == 202 && s->extent_y == 96);
    const float *d = tsr_heightfield_cdata(hf);
    for (uint32_t l = 0; l <= s->levels; l++)
        for (uint32_t y = 0; y < (1u << l); y++)
            for (uint32_t x = 0; x < (1u << l); x++) {
                tsr_qnode n = {x, y, (uint8_t)l};
                if (!tsr_quadtree_node_exists(s, n))
                    continue;
                uint32_t w = node_width(s, n);
                float mn = INFINITY, mx = -INFINITY;
                for (uint32_t r = y * w; r <= (y + 1) * w && r < 97; r++)
                    for (uint32_t c = x * w; c <= (x + 1) * w && c < 203; c++)
                        if (!isnan(d[r * 203 + c])) {
                            mn = fminf(mn, d[r * 203 + c]);
                            mx = fmaxf(mx, d[r * 203 + c]);
                        }
                float a, b;
                tsr_terrain_node_range(t, n, &a, &b);
                CHECK_MSG(a == mn && b == mx, "node %u,%u,%u: %g..%g vs %g..%g", l, x, y, a, b, mn, mx);
            }
    /* memory beyond the heightfield: the mipmap is about 2/3 of it */
    CHECK(tsr_terrain_extra_bytes(t) < 203 * 97 * sizeof(float));
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
}

/* The exact error of a node's tile with a stitch mask, computed here from
 * the library's index pattern and the samples alone: each sample is
 * located in the tile's triangles (vertices clamped onto the extent). */
static double exact_tile_error(const tsr_heightfield *hf, const tsr_surface *s, tsr_qnode n, unsigned mask)
{
    uint32_t N = s->tile_n, w = node_width(s, n), st = w / N, W = tsr_heightfield_width(hf);
    uint32_t ex = s->extent_x, ey = s->extent_y;
    const float *d = tsr_heightfield_cdata(hf);
    uint32_t *tri = malloc(3 * tsr_tile_pattern_bound(N) * sizeof *tri);
    uint32_t cnt = tsr_tile_pattern(N, mask, tri);
    double worst = 0;
    for (uint32_t r = n.y * w; r <= (n.y + 1) * w && r <= ey; r++)
        for (uint32_t c = n.x * w; c <= (n.x + 1) * w && c <= ex; c++) {
            double h = d[r * W + c];
            if (isnan(h))
                continue;
            for (uint32_t k = 0; k < cnt; k++) {
                double P[3][2], z[3];
                for (int v = 0; v < 3; v++) {
                    uint32_t li = tri[3 * k + v] % (N + 1), lj = tri[3 * k + v] / (N + 1);
                    uint32_t gc = n.x * w + li * st, gr = n.y * w + lj * st;
                    gc = gc > ex ? ex : gc;
                    gr = gr > ey ? ey : gr;
                    P[v][0] = gc;
                    P[v][1] = gr;
                    z[v] = d[gr * W + gc];
                }
                double det = (P[1][0] - P[0][0]) * (P[2][1] - P[0][1]) - (P[1][1] - P[0][1]) * (P[2][0] - P[0][0]);
                if (det == 0)
                    continue;
                double l1 = ((c - P[0][0]) * (P[2][1] - P[0][1]) - (r - P[0][1]) * (P[2][0] - P[0][0])) / det;
                double l2 = ((P[1][0] - P[0][0]) * (r - P[0][1]) - (P[1][1] - P[0][1]) * (c - P[0][0])) / det;
                if (l1 < -1e-12 || l2 < -1e-12 || l1 + l2 > 1 + 1e-12)
                    continue;
                double e = fabs(h - (z[0] + l1 * (z[1] - z[0]) + l2 * (z[2] - z[0])));
                if (!isnan(e))
                    worst = e > worst ? e : worst;
                break;
            }
        }
    free(tri);
    return worst;
}

static void check_delta(uint32_t w, uint32_t h, uint32_t tile, bool holes)
{
    tsr_heightfield *hf = terrain(w, h, w * 31 + h, 300);
    if (holes)
        punch_holes(hf);
    tsr_heightfield_set_spacing(hf, 10, 10, 2);
    tsr_terrain *t = NULL;
    tsr_terrain_options o = {tile};
    CHECK(tsr_terrain_create(hf, &o, NULL, &t, NULL) == TSR_OK);
    const tsr_surface *s = tsr_terrain_surface(t);
    double slack_sum = 0;
    int counted = 0;
    for (uint32_t l = 0; l <= s->levels; l++)
        for (uint32_t y = 0; y < (1u << l); y++)
            for (uint32_t x = 0; x < (1u << l); x++) {
                tsr_qnode n = {x, y, (uint8_t)l};
                if (!tsr_quadtree_node_exists(s, n))
                    continue;
                double delta = s->error(s->user, n);
                if (l < s->levels)
                    for (unsigned q = 0; q < 4; q++) {
                        tsr_qnode c = {2 * x + (q & 1), 2 * y + (q >> 1), (uint8_t)(l + 1)};
                        if (tsr_quadtree_node_exists(s, c))
                            CHECK_MSG(delta >= s->error(s->user, c), "not monotone at %u,%u,%u", l, x, y);
                    }
                if (isinf(delta))
                    continue;
                double worst = 0;
                for (unsigned mask = 0; mask < 16; mask++)
                    worst = fmax(worst, exact_tile_error(hf, s, n, mask) * 2 /* dz */);
                CHECK_MSG(worst <= delta, "%ux%u tile %u node %u,%u,%u: exact %g > delta %g", w, h, tile, l, x, y,
                          worst, delta);
                if (worst > 0) {
                    slack_sum += delta / worst;
                    counted++;
                }
            }
    if (counted)
        fprintf(stderr, "  %ux%u tile %u%s: delta / exact error = %.2f on average over %d nodes\n", w, h, tile,
                holes ? " holes" : "", slack_sum / counted, counted);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
}

TEST(delta_bounds_every_stitch_variant)
{
    check_delta(129, 129, 8, false); /* aligned: 2^k + 1 */
    check_delta(100, 71, 8, false);  /* clipped nodes */
    check_delta(150, 90, 16, true);  /* no-data holes */
    check_delta(2, 2, 8, false);
    check_delta(9, 300, 8, false);
    check_delta(65, 47, 2, false);   /* the smallest tiles (tessera mesh --method quadtree) */
    check_delta(70, 33, 4, true);
}

/* ---- cuts and their meshes ------------------------------------------- */

/* 2:1 by rasterising leaf levels onto the deepest level's grid. */
static bool balanced(const tsr_quadtree *qt, const tsr_surface *s)
{
    uint32_t side = 1u << s->levels;
    int *lev = malloc((size_t)side * side * sizeof *lev);
    for (size_t i = 0; i < (size_t)side * side; i++)
        lev[i] = -1;
    const tsr_qleaf *L = tsr_quadtree_leaves(qt);
    for (uint32_t i = 0; i < tsr_quadtree_leaf_count(qt); i++) {
        uint32_t span = 1u << (s->levels - L[i].node.level);
        for (uint32_t y = L[i].node.y * span; y < (L[i].node.y + 1) * span; y++)
            for (uint32_t x = L[i].node.x * span; x < (L[i].node.x + 1) * span; x++)
                lev[y * side + x] = L[i].node.level;
    }
    bool ok = true;
    for (uint32_t y = 0; y < side; y++)
        for (uint32_t x = 0; x < side; x++) {
            int a = lev[y * side + x];
            if (a < 0)
                continue;
            if (x + 1 < side && lev[y * side + x + 1] >= 0 && abs(a - lev[y * side + x + 1]) > 1)
                ok = false;
            if (y + 1 < side && lev[(y + 1) * side + x] >= 0 && abs(a - lev[(y + 1) * side + x]) > 1)
                ok = false;
        }
    free(lev);
    return ok;
}

static void check_mesh(const tsr_heightfield *hf, const tsr_quadtree *qt, const tsr_surface *s, bool holes,
                       const char *what)
{
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
    CHECK(tsr_quadtree_mesh(qt, false, &m) == TSR_OK);
    tsr_validation v;
    tsr_validate_options vo = {0};
    vo.expect_up = vo.height_field = true;
    CHECK(tsr_mesh_validate(&m, &vo, &v) == TSR_OK);
    char msg[512];
    tsr_validation_describe(&v, msg, sizeof msg);
    CHECK_MSG(tsr_validation_ok(&v), "%s: %s", what, msg);
    CHECK_MSG(balanced(qt, s), "%s: not 2:1", what);
    double dx, dy;
    tsr_heightfield_spacing(hf, &dx, &dy, NULL);
    if (!holes)
        CHECK_MSG(tsr_mesh_boundary_is_rect(&m, 0, 0, s->extent_x * dx, s->extent_y * dy, 1e-3, NULL),
                  "%s: boundary is not the rectangle", what);
    else
        CHECK_MSG(v.boundary_loops > 1, "%s: no hole in the mesh", what);
    for (uint32_t i = 0; i < 3 * m.vertex_count; i++)
        CHECK(!isnan(m.positions[i]));
    tsr_mesh_free(&m);
}

TEST(tolerance_cuts_hold_the_bound)
{
    for (int holes = 0; holes < 2; holes++) {
        tsr_heightfield *hf = terrain(301, 177, 11, 800);
        if (holes)
            punch_holes(hf);
        tsr_heightfield_set_spacing(hf, 30, 30, 1.5);
        tsr_terrain *t = NULL;
        tsr_terrain_options o = {16};
        CHECK(tsr_terrain_create(hf, &o, NULL, &t, NULL) == TSR_OK);
        const tsr_surface *s = tsr_terrain_surface(t);
        tsr_quadtree *qt = tsr_quadtree_create(s, NULL);
        const double tols[] = {100, 20, 5, 1, 0.2, 0.01};
        for (int k = 0; k < 6; k++) {
            double tol = tols[k];
            CHECK(tsr_quadtree_select(qt, tsr_refine_tolerance, &tol) == TSR_OK);
            char what[64];
            snprintf(what, sizeof what, "tol %g%s", tol, holes ? " holes" : "");
            check_mesh(hf, qt, s, holes, what);
            tsr_mesh m;
            tsr_mesh_init(&m, 0, NULL);
            tsr_quadtree_mesh(qt, false, &m);
            tsr_error_report rep;
            CHECK(tsr_terrain_measure(hf, &m, NULL, &rep) == TSR_OK);
            CHECK_MSG(rep.max_vertical <= tol * (1 + 1e-6) + 1e-4, "%s: measured %g", what, rep.max_vertical);
            if (!holes)
                CHECK(rep.uncovered == 0);
            fprintf(stderr, "  %-16s leaves %5u triangles %7u measured max %.4g\n", what, tsr_quadtree_leaf_count(qt),
                    m.triangle_count, rep.max_vertical);
            tsr_mesh_free(&m);
        }
        tsr_quadtree_destroy(qt);
        tsr_terrain_destroy(t);
        tsr_heightfield_destroy(hf);
    }
}

static void random_camera(tsr_camera *c, double sx, double sy, double zmin, double zmax, bool grazing)
{
    memset(c, 0, sizeof *c);
    do {
        c->eye[0] = urand() * sx;
        c->eye[1] = urand() * sy;
        c->eye[2] = grazing ? zmax + 5 + urand() * 30 : zmax + urand() * (zmax - zmin + sx * 0.3);
        double a = urand() * 6.283185307, pitch = grazing ? -0.02 - urand() * 0.1 : -0.1 - urand() * 1.2;
        c->target[0] = c->eye[0] + cos(a) * cos(pitch);
        c->target[1] = c->eye[1] + sin(a) * cos(pitch);
        c->target[2] = c->eye[2] + sin(pitch);
        c->fovy_deg = 30 + urand() * 60;
        c->width = 640 + (int)(urand() * 1280);
        c->height = 360 + (int)(urand() * 720);
        c->near_dist = 1;
        c->pixel_error = 0.5 + urand() * 2;
    } while (!tsr_camera_prepare(c));
}

TEST(camera_cuts_hold_the_screen_bound)
{
    tsr_heightfield *hf = terrain(257, 257, 21, 1200);
    tsr_heightfield_set_spacing(hf, 30, 30, 1);
    tsr_terrain *t = NULL;
    CHECK(tsr_terrain_create(hf, NULL, NULL, &t, NULL) == TSR_OK);
    const tsr_surface *s = tsr_terrain_surface(t);
    tsr_quadtree *qt = tsr_quadtree_create(s, NULL);
    double worst_ratio = 0;
    for (int k = 0; k < 40; k++) {
        tsr_camera cam;
        random_camera(&cam, 256 * 30, 256 * 30, 0, 1200, k % 3 == 0);
        CHECK(tsr_quadtree_select(qt, tsr_refine_camera, &cam) == TSR_OK);
        tsr_quadtree_apply_camera(qt, &cam);
        char what[64];
        snprintf(what, sizeof what, "camera %d", k);
        check_mesh(hf, qt, s, false, what);
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        tsr_quadtree_mesh(qt, false, &m);
        tsr_error_report rep;
        CHECK(tsr_terrain_measure(hf, &m, &cam, &rep) == TSR_OK);
        CHECK_MSG(rep.max_pixels <= cam.pixel_error * (1 + 1e-6), "camera %d: %g px > tau %g at sample %u,%u", k,
                  rep.max_pixels, cam.pixel_error, rep.worst_c, rep.worst_r);
        worst_ratio = fmax(worst_ratio, rep.max_pixels / cam.pixel_error);
        for (uint32_t i = 0; i < tsr_quadtree_leaf_count(qt); i++) {
            float mo = tsr_quadtree_leaves(qt)[i].morph;
            CHECK(mo >= 0 && mo <= 1);
        }
        tsr_mesh_free(&m);
    }
    fprintf(stderr, "  worst measured / tau over 40 cameras: %.3f\n", worst_ratio);
    CHECK(worst_ratio > 0.1); /* the bound is not vacuous: errors are visible */
    tsr_quadtree_destroy(qt);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
}

TEST(geomorphed_cuts_hold_five_fourths_of_the_bound)
{
    /* The mesh the renderer draws with geomorphing: the same vertices and
     * triangles as the cut's, odd interior vertices moved part of the way
     * to the parent's surface. Conforming and watertight as the cut is,
     * and within 1.25 tau on screen (measured over every sample, 16 cameras, with
     * holes and with a size that clamps tiles at the extent). */
    for (int holes = 0; holes < 2; holes++) {
        tsr_heightfield *hf = terrain(301, 177, 31, 1200);
        if (holes)
            punch_holes(hf);
        tsr_heightfield_set_spacing(hf, 30, 30, 1);
        tsr_terrain *t = NULL;
        CHECK(tsr_terrain_create(hf, NULL, NULL, &t, NULL) == TSR_OK);
        const tsr_surface *s = tsr_terrain_surface(t);
        tsr_quadtree *qt = tsr_quadtree_create(s, NULL);
        double worst = 0, worst_plain = 0;
        int moved = 0;
        for (int k = 0; k < 16; k++) {
            tsr_camera cam;
            random_camera(&cam, 300 * 30, 176 * 30, 0, 1200, k % 3 == 0);
            CHECK(tsr_quadtree_select(qt, tsr_refine_camera, &cam) == TSR_OK);
            tsr_quadtree_apply_camera(qt, &cam);
            tsr_mesh plain, mo;
            tsr_mesh_init(&plain, 0, NULL);
            tsr_mesh_init(&mo, 0, NULL);
            CHECK(tsr_quadtree_mesh(qt, false, &plain) == TSR_OK);
            CHECK(tsr_quadtree_mesh_geomorphed(qt, false, &mo) == TSR_OK);
            CHECK(mo.vertex_count == plain.vertex_count && mo.triangle_count == plain.triangle_count);
            CHECK(!memcmp(mo.indices, plain.indices, 3 * sizeof *mo.indices * mo.triangle_count));
            bool differ = false;
            for (uint32_t i = 0; i < mo.vertex_count; i++) {
                CHECK(mo.positions[3 * i] == plain.positions[3 * i] &&
                      mo.positions[3 * i + 1] == plain.positions[3 * i + 1]);
                differ = differ || mo.positions[3 * i + 2] != plain.positions[3 * i + 2];
            }
            moved += differ;
            tsr_validation v;
            tsr_validate_options vo = {.expect_up = true, .height_field = true};
            CHECK(tsr_mesh_validate(&mo, &vo, &v) == TSR_OK);
            char msg[512];
            tsr_validation_describe(&v, msg, sizeof msg);
            CHECK_MSG(tsr_validation_ok(&v), "camera %d: %s", k, msg);
            tsr_error_report rep, rp;
            CHECK(tsr_terrain_measure(hf, &mo, &cam, &rep) == TSR_OK);
            CHECK(tsr_terrain_measure(hf, &plain, &cam, &rp) == TSR_OK);
            CHECK_MSG(rep.max_pixels <= 1.25 * cam.pixel_error * (1 + 1e-6), "camera %d: %g px > 1.25 tau (%g)", k,
                      rep.max_pixels, 1.25 * cam.pixel_error);
            worst = fmax(worst, rep.max_pixels / cam.pixel_error);
            worst_plain = fmax(worst_plain, rp.max_pixels / cam.pixel_error);
            tsr_mesh_free(&plain);
            tsr_mesh_free(&mo);
        }
        fprintf(stderr, "  %s: geomorphed worst / tau %.3f (unmorphed %.3f), %d of 16 cameras moved vertices\n",
                holes ? "holes" : "whole", worst, worst_plain, moved);
        CHECK(moved > 6); /* not vacuous: the morph moves vertices */
        tsr_quadtree_destroy(qt);
        tsr_terrain_destroy(t);
        tsr_heightfield_destroy(hf);
    }
}

/* ---- picking ---------------------------------------------------------- */

static bool ray_tri(const double o[3], const double d[3], const double a[3], const double b[3], const double c[3], double *t)
{
    /* plane intersection then an inside test by edge signs: a different
     * method from the library's Moller-Trumbore */
    double e1[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]}, e2[3] = {c[0] - a[0], c[1] - a[1], c[2] - a[2]};
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double den = n[0] * d[0] + n[1] * d[1] + n[2] * d[2];
    if (den == 0)
        return false;
    double tt = (n[0] * (a[0] - o[0]) + n[1] * (a[1] - o[1]) + n[2] * (a[2] - o[2])) / den;
    if (tt < 0)
        return false;
    double p[3] = {o[0] + tt * d[0], o[1] + tt * d[1], o[2] + tt * d[2]};
    const double *v[3] = {a, b, c};
    for (int k = 0; k < 3; k++) {
        const double *p0 = v[k], *p1 = v[(k + 1) % 3];
        double ed[3] = {p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]}, w[3] = {p[0] - p0[0], p[1] - p0[1], p[2] - p0[2]};
        double cr[3] = {ed[1] * w[2] - ed[2] * w[1], ed[2] * w[0] - ed[0] * w[2], ed[0] * w[1] - ed[1] * w[0]};
        if (cr[0] * n[0] + cr[1] * n[1] + cr[2] * n[2] < -1e-9 * (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]))
            return false;
    }
    *t = tt;
    return true;
}

static bool pick_brute(const tsr_heightfield *hf, const double o[3], const double d[3], double *t_hit)
{
    uint32_t W = tsr_heightfield_width(hf), Hh = tsr_heightfield_height(hf);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    const float *h = tsr_heightfield_cdata(hf);
    double best = INFINITY;
    for (uint32_t r = 0; r + 1 < Hh; r++)
        for (uint32_t c = 0; c + 1 < W; c++) {
            double P[4][3];
            float hv[4] = {h[r * W + c], h[r * W + c + 1], h[(r + 1) * W + c], h[(r + 1) * W + c + 1]};
            for (int k = 0; k < 4; k++) {
                P[k][0] = (c + (k & 1)) * dx;
                P[k][1] = (r + (k >> 1)) * dy;
                P[k][2] = hv[k] * dz;
            }
            int tris[2][3];
            if (((c + r) & 1) == 0) {
                int a[2][3] = {{0, 1, 3}, {0, 3, 2}};
                memcpy(tris, a, sizeof a);
            } else {
                int a[2][3] = {{0, 1, 2}, {1, 3, 2}};
                memcpy(tris, a, sizeof a);
            }
            for (int k = 0; k < 2; k++) {
                if (isnan(hv[tris[k][0]]) || isnan(hv[tris[k][1]]) || isnan(hv[tris[k][2]]))
                    continue;
                double t;
                if (ray_tri(o, d, P[tris[k][0]], P[tris[k][1]], P[tris[k][2]], &t) && t < best)
                    best = t;
            }
        }
    if (best == INFINITY)
        return false;
    *t_hit = best;
    return true;
}

TEST(picking_matches_every_cell_test)
{
    tsr_heightfield *hf = terrain(97, 61, 5, 400);
    punch_holes(hf);
    tsr_heightfield_set_spacing(hf, 10, 12, 1);
    tsr_terrain *t = NULL;
    CHECK(tsr_terrain_create(hf, NULL, NULL, &t, NULL) == TSR_OK);
    int hits = 0, misses = 0, mismatches = 0;
    for (int k = 0; k < 3000; k++) {
        double o[3], d[3];
        int kind = k % 4;
        o[0] = -100 + urand() * 1160;
        o[1] = -100 + urand() * 920;
        if (kind == 0) { /* from above, steep */
            o[2] = 500 + urand() * 500;
            d[0] = urand() - 0.5;
            d[1] = urand() - 0.5;
            d[2] = -1;
        } else if (kind == 1) { /* grazing, just above the terrain's top */
            o[2] = 300 + urand() * 120;
            d[0] = urand() - 0.5;
            d[1] = urand() - 0.5;
            d[2] = -(urand() * 0.05);
        } else if (kind == 2) { /* from inside the height range, any way */
            o[2] = urand() * 400;
            d[0] = urand() - 0.5;
            d[1] = urand() - 0.5;
            d[2] = urand() - 0.5;
        } else { /* exactly horizontal */
            o[2] = urand() * 400;
            d[0] = urand() - 0.5;
            d[1] = urand() - 0.5;
            d[2] = 0;
        }
        double ta = 0, tb = 0;
        bool a = tsr_terrain_pick(t, o, d, &ta), b = pick_brute(hf, o, d, &tb);
        if (a != b || (a && fabs(ta - tb) > 1e-7 * (1 + tb))) {
            mismatches++;
            if (mismatches < 5)
                fprintf(stderr, "  ray %d kind %d: pick %d %.9g, brute %d %.9g\n", k, kind, a, ta, b, tb);
        }
        hits += b;
        misses += !b;
    }
    fprintf(stderr, "  3000 rays: %d hits, %d misses, %d mismatches\n", hits, misses, mismatches);
    CHECK(mismatches == 0);
    CHECK(hits > 500 && misses > 200);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
}

TEST(geomorph_weights)
{
    /* each leaf's weight follows its parent's screen error e: 1 just past
     * the split (e = tau), 0 from 2 tau on; per vertex, only odd interior
     * vertices move, so tile edges never open */
    tsr_heightfield *hf = terrain(257, 257, 3, 600);
    tsr_heightfield_set_spacing(hf, 20, 20, 1);
    tsr_terrain *t = NULL;
    CHECK(tsr_terrain_create(hf, NULL, NULL, &t, NULL) == TSR_OK);
    const tsr_surface *s = tsr_terrain_surface(t);
    tsr_quadtree *qt = tsr_quadtree_create(s, NULL);
    int partial = 0;
    for (int k = 0; k < 10; k++) {
        tsr_camera cam;
        random_camera(&cam, 256 * 20, 256 * 20, 0, 600, k % 2 == 0);
        tsr_quadtree_select(qt, tsr_refine_camera, &cam);
        tsr_quadtree_apply_camera(qt, &cam);
        const tsr_qleaf *L = tsr_quadtree_leaves(qt);
        for (uint32_t i = 0; i < tsr_quadtree_leaf_count(qt); i++) {
            if (L[i].node.level == 0)
                continue;
            tsr_qnode p = {L[i].node.x / 2, L[i].node.y / 2, (uint8_t)(L[i].node.level - 1)};
            double e = tsr_camera_node_error(&cam, s, p), want = 2 - e / cam.pixel_error;
            /* the per-box factor times the node's error is the same figure */
            float lo[3], hi[3];
            s->bounds(s->user, p, lo, hi);
            double f = tsr_camera_box_factor(&cam, lo, hi, s->error_isotropic) * s->error(s->user, p);
            CHECK_MSG(fabs(f - e) <= 1e-12 * e, "box factor times error %.17g, node error %.17g", f, e);
            want = want < 0 ? 0 : want > 1 ? 1 : want;
            CHECK_NEAR(L[i].morph, want, 1e-6);
            partial += L[i].morph > 0 && L[i].morph < 1;
            uint32_t n = s->tile_n;
            for (uint32_t j = 0; j <= n; j++)
                for (uint32_t ii = 0; ii <= n; ii++) {
                    float w = tsr_quadtree_vertex_morph(&L[i], n, ii, j);
                    bool edge = ii == 0 || j == 0 || ii == n || j == n, even = !(ii & 1) && !(j & 1);
                    CHECK(edge || even ? w == 0 : w == L[i].morph);
                }
        }
    }
    CHECK(partial > 0); /* some tiles are mid-morph */
    tsr_quadtree_destroy(qt);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
}

TEST(bad_options)
{
    tsr_heightfield *hf = terrain(20, 20, 1, 10);
    tsr_terrain *t = NULL;
    tsr_terrain_options o = {12};
    tsr_error err;
    CHECK(tsr_terrain_create(hf, &o, NULL, &t, &err) == TSR_ERR_ARGUMENT && t == NULL);
    CHECK(strstr(err.message, "tile size 12") != NULL);
    tsr_heightfield_set_spacing(hf, 1, 1, -1);
    CHECK(tsr_terrain_create(hf, NULL, NULL, &t, &err) == TSR_ERR_ARGUMENT);
    tsr_heightfield_destroy(hf);
}

TEST_MAIN(T(pyramid_ranges_match_brute_force), T(delta_bounds_every_stitch_variant), T(tolerance_cuts_hold_the_bound),
          T(geomorphed_cuts_hold_five_fourths_of_the_bound), T(camera_cuts_hold_the_screen_bound), T(picking_matches_every_cell_test), T(geomorph_weights), T(bad_options))
