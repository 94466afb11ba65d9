/* test_tin.c: tsr_terrain_mesh (tessera mesh's library). Properties, each
 * against an oracle written here, independent of the meshers and of
 * measure.c: the measured max error never exceeds the bound (brute force
 * over every sample and every triangle), budgets are respected, meshes are
 * valid (oriented, manifold, conforming), no-data becomes holes (no
 * triangle covers a no-data sample, every cell of four valid samples is
 * covered), and adjacent windows share their border vertices exactly. */
#include "check.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h" /* tsr__rqt_half_variants */

/* ---- the oracle ----------------------------------------------------------- */

typedef struct oracle {
    double max_error;
    uint64_t covered, uncovered_cells_samples; /* valid samples covered / valid corners of valid cells uncovered */
    uint64_t nodata_covered;                   /* no-data samples strictly inside or on a triangle */
} oracle;

/* Every sample against every triangle whose bounding box holds it: exact
 * enough in double (barycentric with a 1e-9 tolerance); window-aware. */
static void brute(const tsr_heightfield *hf, uint32_t x0, uint32_t y0, uint32_t w, uint32_t h, const tsr_mesh *m,
                  oracle *o)
{
    memset(o, 0, sizeof *o);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    uint32_t W = tsr_heightfield_width(hf);
    const float *d = tsr_heightfield_cdata(hf);
    uint8_t *hit = calloc((size_t)w * h, 1);
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = m->positions + 3 * (size_t)m->indices[3 * (size_t)t + k];
        double area = ((double)p[1][0] - p[0][0]) * ((double)p[2][1] - p[0][1]) -
                      ((double)p[1][1] - p[0][1]) * ((double)p[2][0] - p[0][0]);
        if (area <= 0)
            continue; /* the validation catches these */
        double lo_c = INFINITY, hi_c = -INFINITY, lo_r = INFINITY, hi_r = -INFINITY;
        for (int k = 0; k < 3; k++) {
            lo_c = fmin(lo_c, p[k][0] / dx);
            hi_c = fmax(hi_c, p[k][0] / dx);
            lo_r = fmin(lo_r, p[k][1] / dy);
            hi_r = fmax(hi_r, p[k][1] / dy);
        }
        for (int64_t r = (int64_t)ceil(lo_r - 1e-6); r <= (int64_t)floor(hi_r + 1e-6); r++)
            for (int64_t c = (int64_t)ceil(lo_c - 1e-6); c <= (int64_t)floor(hi_c + 1e-6); c++) {
                if (c < x0 || r < y0 || c >= x0 + w || r >= y0 + h)
                    continue;
                double x = c * dx, y = r * dy, b[3];
                for (int k = 0; k < 3; k++) {
                    const float *a = p[(k + 1) % 3], *e = p[(k + 2) % 3];
                    b[k] = (((double)e[0] - a[0]) * (y - a[1]) - ((double)e[1] - a[1]) * (x - a[0])) / area;
                }
                if (b[0] < -1e-9 || b[1] < -1e-9 || b[2] < -1e-9)
                    continue;
                float hv = d[(size_t)r * W + (size_t)c];
                if (isnan(hv)) {
                    o->nodata_covered++;
                    continue;
                }
                double z = b[0] * p[0][2] + b[1] * p[1][2] + b[2] * p[2][2];
                o->max_error = fmax(o->max_error, fabs(z - hv * dz));
                hit[(size_t)(r - y0) * w + (size_t)(c - x0)] = 1;
            }
    }
    /* every corner of a cell with four valid corners must be covered */
    for (uint32_t r = 0; r < h; r++)
        for (uint32_t c = 0; c < w; c++) {
            if (isnan(d[(size_t)(y0 + r) * W + x0 + c]))
                continue;
            bool in_cell = false;
            for (int dr = -1; dr <= 0 && !in_cell; dr++)
                for (int dc = -1; dc <= 0 && !in_cell; dc++) {
                    int64_t cc = (int64_t)c + dc, rr = (int64_t)r + dr;
                    if (cc < 0 || rr < 0 || cc + 1 >= w || rr + 1 >= h)
                        continue;
                    const float *q = d + (size_t)(y0 + rr) * W + x0 + (size_t)cc;
                    in_cell = !isnan(q[0]) && !isnan(q[1]) && !isnan(q[W]) && !isnan(q[W + 1]);
                }
            if (hit[(size_t)r * w + c])
                o->covered++;
            else if (in_cell)
                o->uncovered_cells_samples++;
        }
    free(hit);
}

static bool valid_mesh_3d(const tsr_mesh *m, const char *what)
{
    tsr_validation v;
    tsr_validate_options vo = {0};
    vo.expect_up = vo.height_field = true;
    if (tsr_mesh_validate(m, &vo, &v) != TSR_OK)
        return false;
    if (!tsr_validation_ok(&v) || v.downward_triangles) {
        char buf[256];
        tsr_validation_describe(&v, buf, sizeof buf);
        fprintf(stderr, "validation%s: %s\n", what, buf);
        return false;
    }
    return true;
}

/* Valid, and so is its projection on the xy plane: a height-field mesh
 * with a crack (two sides of a seam with different vertices) passes in 3D,
 * where the vertex of one side is off the other's edge, but flat it is a
 * T-junction. */
static bool valid_mesh(const tsr_mesh *m)
{
    if (!valid_mesh_3d(m, ""))
        return false;
    tsr_mesh f = *m;
    f.positions = malloc(12 * ((size_t)m->vertex_count + 1));
    if (!f.positions)
        return false;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        f.positions[3 * i] = m->positions[3 * i];
        f.positions[3 * i + 1] = m->positions[3 * i + 1];
        f.positions[3 * i + 2] = 0;
    }
    f.normals = NULL;
    f.uvs = NULL;
    bool ok = valid_mesh_3d(&f, " (flattened)");
    free(f.positions);
    return ok;
}

static tsr_heightfield *terrain(uint32_t w, uint32_t h, uint32_t seed)
{
    tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
    tsr_generate_options g = {0};
    g.seed = seed;
    g.relief = 500;
    g.erosion_iterations = 5;
    tsr_terrain_generate(hf, &g);
    return hf;
}

static tsr_tin_method methods[] = {TSR_TIN_DELAUNAY, TSR_TIN_QUADTREE};
static const char *mname[] = {"delaunay", "quadtree"};

/* Meshes hf with the options and checks bound, validity and holes. */
static void bound_case(const tsr_heightfield *hf, tsr_tin_options o, const char *what)
{
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    tsr_tin_report rep;
    tsr_status st = tsr_terrain_mesh(hf, &o, &m, &rep, &err);
    CHECK_MSG(st == TSR_OK, "%s: %s", what, err.message);
    if (st != TSR_OK)
        return;
    oracle or;
    uint32_t w = o.window_w ? o.window_w : tsr_heightfield_width(hf), h = o.window_h ? o.window_h : tsr_heightfield_height(hf);
    brute(hf, o.window_x, o.window_y, w, h, &m, &or);
    double bound = rep.target_error;
    CHECK_MSG(or.max_error <= bound, "%s (%s): max error %.9g > bound %.9g", what, mname[o.method], or.max_error, bound);
    CHECK_MSG(or.nodata_covered == 0, "%s (%s): %llu no-data samples covered", what, mname[o.method],
              (unsigned long long)or.nodata_covered);
    CHECK_MSG(or.uncovered_cells_samples == 0, "%s (%s): %llu samples of valid cells uncovered", what,
              mname[o.method], (unsigned long long)or.uncovered_cells_samples);
    CHECK_MSG(valid_mesh(&m), "%s (%s): invalid mesh", what, mname[o.method]);
    /* the library's own oracle agrees */
    tsr_error_report er;
    CHECK(tsr_terrain_measure_window(hf, o.window_x, o.window_y, w, h, &m, NULL, &er) == TSR_OK);
    CHECK_MSG(er.max_vertical <= bound, "%s: measure %.9g > %.9g", what, er.max_vertical, bound);
    tsr_mesh_free(&m);
}

TEST(error_bound_generated)
{
    uint32_t sizes[][2] = {{65, 65}, {100, 77}, {33, 120}, {2, 2}, {3, 40}};
    double errors[] = {0.5, 2, 20, 200};
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++) {
        tsr_heightfield *hf = terrain(sizes[s][0], sizes[s][1], (uint32_t)s + 1);
        for (size_t e = 0; e < sizeof errors / sizeof errors[0]; e++)
            for (int mth = 0; mth < 2; mth++) {
                tsr_tin_options o = {0};
                o.method = methods[mth];
                o.max_error = errors[e];
                char what[64];
                snprintf(what, sizeof what, "%ux%u E=%g", sizes[s][0], sizes[s][1], errors[e]);
                bound_case(hf, o, what);
            }
        /* the default bound: 0.1% of the range */
        tsr_tin_options o = {0};
        bound_case(hf, o, "default bound");
        tsr_heightfield_destroy(hf);
    }
}

/* The data-dependent flips (on by default) against plain greedy Delaunay
 * insertion (no_flip), at the same bound: both within it by the oracle,
 * valid, holes intact, and the flips never need more triangles; over all
 * cases, at least 10 % fewer (they save about a fifth on real terrains). */
static uint32_t flip_case(const tsr_heightfield *hf, double e, bool no_flip, uint32_t *flips)
{
    tsr_tin_options o = {0};
    o.max_error = e;
    o.no_flip = no_flip;
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    tsr_tin_report rep;
    tsr_status st = tsr_terrain_mesh(hf, &o, &m, &rep, &err);
    CHECK_MSG(st == TSR_OK, "%s", err.message);
    oracle or;
    brute(hf, 0, 0, tsr_heightfield_width(hf), tsr_heightfield_height(hf), &m, &or);
    CHECK_MSG(or.max_error <= e, "E=%g no_flip=%d: max error %.9g", e, (int)no_flip, or.max_error);
    CHECK(or.nodata_covered == 0 && or.uncovered_cells_samples == 0);
    CHECK(valid_mesh(&m));
    uint32_t n = m.triangle_count;
    *flips = rep.flips;
    tsr_mesh_free(&m);
    return n;
}

TEST(flips_fewer_triangles)
{
    uint64_t sum_flip = 0, sum_plain = 0;
    for (uint32_t seed = 1; seed <= 4; seed++) {
        tsr_heightfield *hf = terrain(97 + 8 * seed, 90, seed + 20);
        if (seed == 4) { /* no-data: its boundaries are constrained, never flipped */
            float *d = tsr_heightfield_data(hf);
            for (uint32_t r = 30; r < 50; r++)
                for (uint32_t c = 40; c < 70; c++)
                    if ((c - 55.0) * (c - 55.0) + (r - 40.0) * (r - 40.0) < 80)
                        d[r * tsr_heightfield_width(hf) + c] = NAN;
        }
        double errors[] = {2, 6, 20};
        for (size_t i = 0; i < 3; i++) {
            uint32_t fl, fl0;
            uint32_t plain = flip_case(hf, errors[i], true, &fl0);
            uint32_t flip = flip_case(hf, errors[i], false, &fl);
            CHECK_MSG(fl0 == 0 && fl > 0, "flips: %u with no_flip, %u without", fl0, fl);
            CHECK_MSG(flip <= plain, "seed %u E=%g: %u triangles with flips, %u without", seed, errors[i], flip,
                      plain);
            sum_flip += flip;
            sum_plain += plain;
        }
        tsr_heightfield_destroy(hf);
    }
    CHECK_MSG(sum_flip * 10 <= sum_plain * 9, "flips: %llu triangles in all, plain %llu",
              (unsigned long long)sum_flip, (unsigned long long)sum_plain);
}

TEST(spacing_and_scale)
{
    tsr_heightfield *hf = terrain(50, 60, 9);
    tsr_heightfield_set_spacing(hf, 30, 12.5, 0.1);
    for (int mth = 0; mth < 2; mth++) {
        tsr_tin_options o = {0};
        o.method = methods[mth];
        o.max_error = 0.7;
        bound_case(hf, o, "dx 30 dy 12.5 dz 0.1");
    }
    tsr_heightfield_destroy(hf);
}

/* Spacings of EPSG:3857 metres (the egm84 file's, 64 km): the vertices'
 * float coordinates lie up to a few tenths of a unit from the samples'
 * (c dx, r dy) at the far rows and columns, and the measurement left the
 * last row out as "no cell of four valid samples" (624 samples of egm84).
 * Every sample must be measured. */
TEST(measure_far_from_the_origin)
{
    tsr_heightfield *hf = terrain(61, 53, 4);
    tsr_heightfield_set_spacing(hf, 64187.4593, 63757.0968, 1);
    for (int mth = 0; mth < 2; mth++) {
        tsr_tin_options o = {0};
        o.method = methods[mth];
        o.max_error = 2;
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        tsr_error err = {0};
        tsr_tin_report rep;
        CHECK_MSG(tsr_terrain_mesh(hf, &o, &m, &rep, &err) == TSR_OK, "%s", err.message);
        tsr_error_report er;
        CHECK(tsr_terrain_measure(hf, &m, NULL, &er) == TSR_OK);
        CHECK_MSG(er.uncovered == 0 && er.covered == 61 * 53 && er.max_vertical <= rep.target_error,
                  "%s: %llu samples left out, %llu measured, max %g (bound %g)", mname[mth],
                  (unsigned long long)er.uncovered, (unsigned long long)er.covered, er.max_vertical, rep.target_error);
        tsr_mesh_free(&m);
    }
    tsr_heightfield_destroy(hf);
}

TEST(flat_and_planar)
{
    /* a plane needs its four corners only, whatever the bound */
    tsr_heightfield *hf = tsr_heightfield_create(40, 30, NULL);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < 30; r++)
        for (uint32_t c = 0; c < 40; c++)
            d[r * 40 + c] = 3.0f * c - 2.0f * r + 7;
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_tin_options o = {0};
    o.max_error = 1e-3;
    tsr_error err;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_OK);
    CHECK_MSG(m.vertex_count == 4 && m.triangle_count == 2, "%u vertices, %u triangles", m.vertex_count,
              m.triangle_count);
    tsr_mesh_free(&m);
    tsr_heightfield_destroy(hf);
}

TEST(budgets)
{
    tsr_heightfield *hf = terrain(129, 129, 4);
    uint32_t budgets[] = {2, 10, 101, 1000, 5000};
    for (size_t i = 0; i < sizeof budgets / sizeof budgets[0]; i++)
        for (int mth = 0; mth < 2; mth++)
            for (int kind = 0; kind < 2; kind++) {
                tsr_tin_options o = {0};
                o.method = methods[mth];
                if (kind == 0)
                    o.max_triangles = budgets[i];
                else
                    o.max_vertices = budgets[i];
                tsr_mesh m;
                tsr_mesh_init(&m, 0, NULL);
                tsr_error err = {0};
                tsr_status st = tsr_terrain_mesh(hf, &o, &m, NULL, &err);
                if (mth == 0 && kind == 1 && budgets[i] < 4) { /* the four corners are a must */
                    CHECK(st == TSR_ERR_ARGUMENT);
                    tsr_mesh_free(&m);
                    continue;
                }
                if (mth == 1 && st == TSR_ERR_ARGUMENT) { /* the quadtree's coarsest mesh is bigger */
                    tsr_mesh_free(&m);
                    continue;
                }
                CHECK_MSG(st == TSR_OK, "budget %u: %s", budgets[i], err.message);
                uint32_t got = kind == 0 ? m.triangle_count : m.vertex_count;
                CHECK_MSG(got <= budgets[i], "%s: %u %s for a budget of %u", mname[mth], got,
                          kind == 0 ? "triangles" : "vertices", budgets[i]);
                /* the greedy method stops at the budget, not before (a last
                 * insertion adds at most 2 triangles, or 1 vertex) */
                if (mth == 0)
                    CHECK_MSG(got + (kind == 0 ? 2 : 1) > budgets[i], "delaunay: %u for a budget of %u", got,
                              budgets[i]);
                /* the quadtree, within a factor (its steps are whole tiles) */
                if (mth == 1)
                    CHECK_MSG(got * 8 >= budgets[i] || got >= 50, "quadtree: %u for a budget of %u", got, budgets[i]);
                CHECK(valid_mesh(&m));
                tsr_mesh_free(&m);
            }
    /* a budget below the fixed border is refused with a message */
    tsr_tin_options o = {0};
    o.max_triangles = 4;
    o.border_error = 1e-6;
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK(strstr(err.message, "budget") != NULL);
    tsr_mesh_free(&m);
    tsr_heightfield_destroy(hf);
}

TEST(nodata_holes)
{
    tsr_heightfield *hf = terrain(90, 70, 5);
    float *d = tsr_heightfield_data(hf);
    /* a disc, a single sample, a border notch, a checkerboard patch (diagonal
     * touching cells) and an isolated valid sample inside a hole */
    for (uint32_t r = 0; r < 70; r++)
        for (uint32_t c = 0; c < 90; c++) {
            double dx = c - 30.0, dy = r - 30.0;
            if (dx * dx + dy * dy < 100 && !(c == 30 && r == 30))
                d[r * 90 + c] = NAN;
            if (c == 60 && r == 20)
                d[r * 90 + c] = NAN;
            if (c >= 80 && r >= 40 && r < 50)
                d[r * 90 + c] = NAN;
            if (c >= 50 && c < 58 && r >= 50 && r < 58 && (c + r) % 2 == 0)
                d[r * 90 + c] = NAN;
        }
    d[0] = NAN; /* a corner */
    double errors[] = {0.5, 5, 50};
    for (size_t e = 0; e < 3; e++)
        for (int mth = 0; mth < 2; mth++) {
            tsr_tin_options o = {0};
            o.method = methods[mth];
            o.max_error = errors[e];
            bound_case(hf, o, "no-data");
        }
    tsr_heightfield_destroy(hf);
}

/* Whether a and b are the same mesh, byte for byte (vertices, triangles). */
static bool same_mesh(const tsr_mesh *a, const tsr_mesh *b)
{
    return a->vertex_count == b->vertex_count && a->triangle_count == b->triangle_count &&
           memcmp(a->positions, b->positions, 12 * (size_t)a->vertex_count) == 0 &&
           memcmp(a->indices, b->indices, 12 * (size_t)a->triangle_count) == 0;
}

/* The quadtree's two kinds of leaf: its default (exact errors, leaves of
 * two or four triangles) and grid tiles over the LOD pyramid (tile_n).
 * Both hold the bound by the oracle, with and without no-data, and are
 * valid (bound_case); the exact errors need fewer triangles in all, and
 * their mesh is the same whatever the thread count. */
/* Vertices of m that no triangle uses. */
static uint32_t unreferenced(const tsr_mesh *m)
{
    uint8_t *used = calloc(m->vertex_count + 1, 1);
    for (size_t i = 0; i < 3 * (size_t)m->triangle_count; i++)
        used[m->indices[i]] = 1;
    uint32_t n = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        n += !used[v];
    free(used);
    return n;
}

static uint32_t quadtree_case(const tsr_heightfield *hf, uint32_t tile_n, double e, const char *what)
{
    tsr_tin_options o = {0};
    o.method = TSR_TIN_QUADTREE;
    o.tile_n = tile_n;
    o.max_error = e;
    bound_case(hf, o, what);
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    o.threads = 1;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_OK);
    uint32_t n = m.triangle_count, lone = unreferenced(&m);
    /* grid tiles over no-data left their points there, in no triangle */
    CHECK_MSG(lone == 0, "%s, tile %u: %u vertices in no triangle", what, tile_n, lone);
    if (tile_n == 0) { /* nodes tested on several threads: the same mesh */
        tsr_mesh m3;
        tsr_mesh_init(&m3, 0, NULL);
        o.threads = 3;
        CHECK(tsr_terrain_mesh(hf, &o, &m3, NULL, &err) == TSR_OK);
        CHECK_MSG(same_mesh(&m3, &m), "%s: 3 threads, not the mesh of one", what);
        tsr_mesh_free(&m3);
    }
    tsr_mesh_free(&m);
    return n;
}

TEST(quadtree_leaves_and_tiles)
{
    uint32_t sizes[][2] = {{129, 129}, {100, 77}, {33, 120}, {2, 2}, {3, 40}, {257, 5}, {11, 19}};
    double errors[] = {0.5, 5, 50};
    uint64_t exact = 0, tiles = 0;
    for (size_t s = 0; s < sizeof sizes / sizeof sizes[0]; s++)
        for (int holes = 0; holes < 2; holes++) {
            tsr_heightfield *hf = terrain(sizes[s][0], sizes[s][1], (uint32_t)s + 11);
            if (holes) { /* a hole across the middle and a lone no-data sample */
                float *d = tsr_heightfield_data(hf);
                uint32_t w = sizes[s][0], h = sizes[s][1];
                for (uint32_t r = h / 3; r < h / 2; r++)
                    for (uint32_t c = w / 4; c < w / 2; c++)
                        d[r * w + c] = NAN;
                d[(h - 1) * w + w - 1] = NAN;
            }
            for (size_t e = 0; e < sizeof errors / sizeof errors[0]; e++) {
                char what[64];
                snprintf(what, sizeof what, "%ux%u%s E=%g", sizes[s][0], sizes[s][1], holes ? " holes" : "",
                         errors[e]);
                exact += quadtree_case(hf, 0, errors[e], what);
                tiles += quadtree_case(hf, 2, errors[e], what);
                quadtree_case(hf, 8, errors[e], what);
            }
            tsr_heightfield_destroy(hf);
        }
    /* bigger and smoother, where leaves are large and ask for midpoints */
    for (int k = 0; k < 2; k++) {
        uint32_t w = 300, h = 257;
        tsr_heightfield *hf = k ? terrain(w, h, 7) : tsr_heightfield_create(w, h, NULL);
        float *d = tsr_heightfield_data(hf);
        if (!k)
            for (uint32_t r = 0; r < h; r++)
                for (uint32_t c = 0; c < w; c++)
                    d[r * w + c] = (float)(40 * sin(c / 23.0) * cos(r / 31.0) + 0.05 * c + 10 * sin((c + 2.0 * r) / 57.0));
        double errs[] = {0.05, 0.2, 1, 4};
        for (size_t e = 0; e < 4; e++) {
            char what[64];
            snprintf(what, sizeof what, "%s %ux%u E=%g", k ? "terrain" : "waves", w, h, errs[e]);
            exact += quadtree_case(hf, 0, errs[e], what);
            tiles += quadtree_case(hf, 2, errs[e], what);
        }
        tsr_heightfield_destroy(hf);
    }
    CHECK_MSG(exact < tiles, "exact errors %llu triangles, grid tiles %llu", (unsigned long long)exact,
              (unsigned long long)tiles);
    /* sides of 2^k + 3 samples: the border clips nodes of 4 and more
     * cells to 2 x 2, whose centre is not the middle sample (once drawn as
     * a fan about the wrong point: the bound broken, or a vertex read past
     * the heightfield). A lone spike near the far corner, flat elsewhere. */
    uint32_t clipped[] = {7, 11, 19, 35};
    for (size_t k = 0; k < sizeof clipped / sizeof clipped[0]; k++) {
        uint32_t n = clipped[k];
        tsr_heightfield *hf = tsr_heightfield_create(n, n, NULL);
        float *d = tsr_heightfield_data(hf);
        for (uint32_t i = 0; i < n * n; i++)
            d[i] = 0;
        d[(n - 2) * n + n - 2] = 1;
        char what[64];
        snprintf(what, sizeof what, "spike %ux%u", n, n);
        quadtree_case(hf, 0, 0.5, what);
        tsr_heightfield_destroy(hf);
    }
}

/* The vertices of m on the line x = X (or y = Y), sorted. */
static int cmp3(const void *a, const void *b)
{
    const float *p = a, *q = b;
    for (int k = 0; k < 3; k++)
        if (p[k] != q[k])
            return p[k] < q[k] ? -1 : 1;
    return 0;
}

static uint32_t on_line(const tsr_mesh *m, int axis, float v, float *out)
{
    uint32_t n = 0;
    for (uint32_t i = 0; i < m->vertex_count; i++)
        if (m->positions[3 * (size_t)i + axis] == v) {
            memcpy(out + 3 * (size_t)n, m->positions + 3 * (size_t)i, 3 * sizeof(float));
            n++;
        }
    qsort(out, n, 3 * sizeof(float), cmp3);
    return n;
}

static void seam_case(const tsr_heightfield *hf, tsr_tin_method method, double e, bool vertical)
{
    uint32_t W = tsr_heightfield_width(hf), H = tsr_heightfield_height(hf);
    tsr_mesh a, b;
    tsr_mesh_init(&a, 0, NULL);
    tsr_mesh_init(&b, 0, NULL);
    tsr_tin_options o = {0};
    o.method = method;
    o.max_error = e;
    o.full_border = true;
    uint32_t split = vertical ? W / 2 + 3 : H / 2 - 5;
    tsr_tin_options oa = o, ob = o;
    if (vertical) { /* a: columns 0..split, b: split..W-1: column split shared */
        oa.window_w = split + 1;
        oa.window_h = H;
        ob.window_x = split;
        ob.window_w = W - split;
        ob.window_h = H;
    } else {
        oa.window_w = W;
        oa.window_h = split + 1;
        ob.window_y = split;
        ob.window_w = W;
        ob.window_h = H - split;
    }
    tsr_error err = {0};
    tsr_tin_report ra = {0}, rb = {0};
    CHECK_MSG(tsr_terrain_mesh(hf, &oa, &a, &ra, &err) == TSR_OK, "%s", err.message);
    CHECK_MSG(tsr_terrain_mesh(hf, &ob, &b, &rb, &err) == TSR_OK, "%s", err.message);
    if (e == 0) { /* the default bound: the whole heightfield's, the same for both */
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        double sdx, sdy, sdz;
        tsr_heightfield_spacing(hf, &sdx, &sdy, &sdz);
        double want = 1e-3 * (st.max - st.min) * sdz;
        CHECK_MSG(ra.bound == rb.bound && fabs(ra.bound - want) <= 1e-12 * want, "%s: default bounds %g and %g, "
                  "not the heightfield's %g", mname[method], ra.bound, rb.bound, want);
        e = ra.bound;
    }
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    float line = vertical ? (float)(split * dx) : (float)(split * dy);
    float *pa = malloc(sizeof(float) * 3 * (a.vertex_count + 1)), *pb = malloc(sizeof(float) * 3 * (b.vertex_count + 1));
    uint32_t na = on_line(&a, vertical ? 0 : 1, line, pa), nb = on_line(&b, vertical ? 0 : 1, line, pb);
    CHECK_MSG(na == nb && na >= 2, "%s seam: %u vs %u vertices", mname[method], na, nb);
    if (na == nb)
        CHECK_MSG(memcmp(pa, pb, sizeof(float) * 3 * na) == 0, "%s seam: vertices differ", mname[method]);
    /* the interiors differ (else the test proves little) */
    CHECK(a.vertex_count != b.vertex_count || memcmp(a.positions, b.positions, 12) != 0);
    /* each window within the bound */
    oracle or;
    brute(hf, oa.window_x, oa.window_y, oa.window_w, oa.window_h, &a, &or);
    CHECK(or.max_error <= e);
    brute(hf, ob.window_x, ob.window_y, ob.window_w, ob.window_h, &b, &or);
    CHECK(or.max_error <= e);
    free(pa);
    free(pb);
    tsr_mesh_free(&a);
    tsr_mesh_free(&b);
}

/* Two windows' meshes welded where their vertices coincide (exactly, as
 * seam vertices must): the union is a valid mesh, flat too (no crack). */
static void windows_weld(const tsr_mesh *a, const tsr_mesh *b, const char *what)
{
    tsr_mesh u;
    tsr_mesh_init(&u, 0, NULL);
    for (uint32_t i = 0; i < a->vertex_count; i++)
        tsr_mesh_add_vertex(&u, a->positions + 3 * (size_t)i, NULL, NULL);
    uint32_t *map = malloc(sizeof(uint32_t) * (b->vertex_count + 1));
    for (uint32_t i = 0; i < b->vertex_count; i++) {
        const float *p = b->positions + 3 * (size_t)i;
        map[i] = UINT32_MAX;
        for (uint32_t k = 0; k < a->vertex_count && map[i] == UINT32_MAX; k++)
            if (memcmp(p, a->positions + 3 * (size_t)k, 12) == 0)
                map[i] = k;
        if (map[i] == UINT32_MAX)
            map[i] = tsr_mesh_add_vertex(&u, p, NULL, NULL);
    }
    for (uint32_t t = 0; t < a->triangle_count; t++)
        tsr_mesh_add_triangle(&u, a->indices[3 * t], a->indices[3 * t + 1], a->indices[3 * t + 2]);
    for (uint32_t t = 0; t < b->triangle_count; t++)
        tsr_mesh_add_triangle(&u, map[b->indices[3 * t]], map[b->indices[3 * t + 1]], map[b->indices[3 * t + 2]]);
    CHECK_MSG(valid_mesh(&u), "%s: the two windows do not fit", what);
    free(map);
    tsr_mesh_free(&u);
}

/* Adjacent windows with no-data beside their seam on one side only: the
 * other side cuts its border where the first's cells change, so the two
 * fit (seam_case's identical vertex lists do not hold here: where only one
 * side has cells, only it has vertices). */
static void seam_nodata_case(const tsr_heightfield *hf, double e, uint32_t split)
{
    uint32_t W = tsr_heightfield_width(hf), H = tsr_heightfield_height(hf);
    tsr_tin_options oa = {0}, ob;
    oa.max_error = e;
    ob = oa;
    oa.window_w = split + 1;
    oa.window_h = H;
    ob.window_x = split;
    ob.window_w = W - split;
    ob.window_h = H;
    tsr_mesh a, b;
    tsr_mesh_init(&a, 0, NULL);
    tsr_mesh_init(&b, 0, NULL);
    CHECK(tsr_terrain_mesh(hf, &oa, &a, NULL, NULL) == TSR_OK);
    CHECK(tsr_terrain_mesh(hf, &ob, &b, NULL, NULL) == TSR_OK);
    char what[64];
    snprintf(what, sizeof what, "no-data seam E=%g", e);
    windows_weld(&a, &b, what);
    tsr_mesh_free(&a);
    tsr_mesh_free(&b);
}

/* ---- the quadtree's halves ------------------------------------------------ */

/* The largest distance of a sample of hf in the closed triangles tri[0..n)
 * (lattice points, counter-clockwise) from the triangle's own plane
 * through its corners' samples; NaN where one is no-data. Membership by
 * exact integer orientations, the plane by barycentric weights in long
 * double. */
static double subtri_max(const tsr_heightfield *hf, const int64_t (*tri)[3][2], int n)
{
    const float *d = tsr_heightfield_cdata(hf);
    int64_t w = tsr_heightfield_width(hf);
    double mx = 0;
    for (int t = 0; t < n; t++) {
        const int64_t(*v)[2] = tri[t];
        int64_t i0 = v[0][0], i1 = v[0][0], j0 = v[0][1], j1 = v[0][1];
        for (int k = 1; k < 3; k++) {
            i0 = v[k][0] < i0 ? v[k][0] : i0, i1 = v[k][0] > i1 ? v[k][0] : i1;
            j0 = v[k][1] < j0 ? v[k][1] : j0, j1 = v[k][1] > j1 ? v[k][1] : j1;
        }
        int64_t det = (v[1][0] - v[0][0]) * (v[2][1] - v[0][1]) - (v[2][0] - v[0][0]) * (v[1][1] - v[0][1]);
        for (int64_t j = j0; j <= j1; j++)
            for (int64_t i = i0; i <= i1; i++) {
                int64_t nw[3];
                bool in = true;
                for (int k = 0; k < 3; k++) { /* the weight of corner k: the sample against the opposite side */
                    const int64_t *a = v[(k + 1) % 3], *b = v[(k + 2) % 3];
                    nw[k] = (b[0] - a[0]) * (j - a[1]) - (b[1] - a[1]) * (i - a[0]);
                    in = in && nw[k] >= 0;
                }
                if (!in)
                    continue;
                long double z = 0;
                for (int k = 0; k < 3; k++)
                    z += (long double)nw[k] * d[v[k][1] * w + v[k][0]];
                double e = fabsl((long double)d[j * w + i] - z / det);
                if (e != e)
                    return NAN;
                mx = e > mx ? e : mx;
            }
    }
    return mx;
}

/* Random halves and fan triangles of boxes of 2^pmin .. 2^pmax cells a
 * side in hf (w x w samples), clipped ones (midpoints off the sides'
 * middles) included, with no-data from iteration nodata_from on, each at
 * tolerances a hair above and below its ways' largest distances (each
 * way's triangles scanned on their own planes, in long double). Without
 * probe, tsr__rqt_half_variants must give exactly the ways within the
 * tolerance; with it, tsr__rqt_half_probe must give every one of them
 * (and may give more). Counts the cases, the ways within and beyond the
 * tolerance, the cases with no-data and, for the probe, the ways it
 * rejected. */
typedef struct half_counts {
    uint64_t cases, pass, fail, nans, rejected;
} half_counts;

static half_counts half_cases(tsr_heightfield *hf, int64_t w, int pmin, int pmax, int iterations, int nodata_from,
                              bool probe)
{
    half_counts k = {0};
    float *d = tsr_heightfield_data(hf);
    for (int it = 0; it < iterations; it++) {
        if (it == nodata_from) /* a few no-data samples for the last cases */
            for (int n = 0; n < 40; n++)
                d[(rand() % w) * w + rand() % w] = NAN;
        int64_t s = (int64_t)1 << (pmin + rand() % (pmax - pmin + 1));
        int64_t x0 = rand() % (w - 1 - s / 2), y0 = rand() % (w - 1 - s / 2);
        int64_t x1 = x0 + 1 + rand() % s, y1 = y0 + 1 + rand() % s; /* clipped or whole */
        if (probe && rand() % 2) /* (the probe needs 32 cells or more both ways) */
            x1 = x0 + s, y1 = y0 + s;
        x1 = x1 > w - 1 ? w - 1 : x1, y1 = y1 > w - 1 ? w - 1 : y1;
        int64_t xm = x0 + s / 2, ym = y0 + s / 2;
        int64_t sw[2] = {x0, y0}, se[2] = {x1, y0}, ne[2] = {x1, y1}, nw[2] = {x0, y1};
        int64_t ms[2] = {xm, y0}, me[2] = {x1, ym}, mn[2] = {xm, y1}, mw[2] = {x0, ym}, cc[2] = {xm, ym};
        bool hs = xm < x1, hn = xm < x1, he = ym < y1, hw = ym < y1;
        /* (a, b, c) and the midpoints of ab and bc: the four halves, and a
         * fan triangle (a, b, centre) with ab's midpoint */
        const int64_t *tv[3], *p = NULL, *m = NULL;
        int kind = rand() % 6;
        if (kind == 0)
            tv[0] = sw, tv[1] = se, tv[2] = ne, p = hs ? ms : NULL, m = he ? me : NULL;
        else if (kind == 1)
            tv[0] = ne, tv[1] = nw, tv[2] = sw, p = hn ? mn : NULL, m = hw ? mw : NULL;
        else if (kind == 2)
            tv[0] = se, tv[1] = ne, tv[2] = nw, p = he ? me : NULL, m = hn ? mn : NULL;
        else if (kind == 3)
            tv[0] = nw, tv[1] = sw, tv[2] = se, p = hw ? mw : NULL, m = hs ? ms : NULL;
        else {
            if (!(xm < x1 && ym < y1))
                continue;
            tv[0] = kind == 4 ? sw : ne, tv[1] = kind == 4 ? se : nw, tv[2] = cc;
            p = kind == 4 ? (hs ? ms : NULL) : (hn ? mn : NULL);
        }
        if (rand() % 4 == 0)
            p = NULL;
        if (rand() % 4 == 0)
            m = NULL;
        int64_t v[3][2], P[2], M[2];
        for (int n = 0; n < 3; n++)
            v[n][0] = tv[n][0], v[n][1] = tv[n][1];
        if (p)
            P[0] = p[0], P[1] = p[1];
        if (m)
            M[0] = m[0], M[1] = m[1];
        /* each way's triangles */
        int64_t w0[1][3][2] = {{{v[0][0], v[0][1]}, {v[1][0], v[1][1]}, {v[2][0], v[2][1]}}};
        int64_t w1[2][3][2] = {{{v[0][0], v[0][1]}, {P[0], P[1]}, {v[2][0], v[2][1]}},
                               {{P[0], P[1]}, {v[1][0], v[1][1]}, {v[2][0], v[2][1]}}};
        int64_t w2[2][3][2] = {{{v[0][0], v[0][1]}, {v[1][0], v[1][1]}, {M[0], M[1]}},
                               {{v[0][0], v[0][1]}, {M[0], M[1]}, {v[2][0], v[2][1]}}};
        int64_t w3[3][3][2] = {{{v[0][0], v[0][1]}, {P[0], P[1]}, {v[2][0], v[2][1]}},
                               {{P[0], P[1]}, {v[1][0], v[1][1]}, {M[0], M[1]}},
                               {{P[0], P[1]}, {M[0], M[1]}, {v[2][0], v[2][1]}}};
        double e[4] = {subtri_max(hf, w0, 1), p ? subtri_max(hf, w1, 2) : NAN, m ? subtri_max(hf, w2, 2) : NAN,
                       p && m ? subtri_max(hf, w3, 3) : NAN};
        bool nodata = e[0] != e[0];
        unsigned ways = 1u | (p ? 2u : 0) | (m ? 4u : 0) | (p && m ? 8u : 0);
        /* tolerances a hair above and below each largest distance, so a
         * way measured wrong by more than 1e-6 of it gets the wrong bit */
        for (int t = 0; t < 9; t++) {
            double tol = t == 8 ? 1.0 : e[t / 2] * (t % 2 ? 1 + 1e-6 : 1 - 1e-6);
            if (tol != tol || !(tol > 0))
                continue;
            bool near = false;
            for (int n = 0; n < 4; n++)
                near = near || (e[n] == e[n] && fabs(e[n] - tol) <= 1e-9 * tol);
            if (near)
                continue;
            unsigned want = 0;
            if (!nodata)
                want = (e[0] <= tol ? 1u : 0) | (p && e[1] <= tol ? 2u : 0) | (m && e[2] <= tol ? 4u : 0) |
                       (p && m && e[3] <= tol ? 8u : 0);
            unsigned got = probe ? tsr__rqt_half_probe(hf, tol, (const int64_t(*)[2])v, p ? P : NULL, m ? M : NULL)
                                 : tsr__rqt_half_variants(hf, tol, (const int64_t(*)[2])v, p ? P : NULL, m ? M : NULL);
            CHECK_MSG(probe ? (want & ~got) == 0 && (got & ~ways) == 0 : got == want,
                      "box %lld,%lld-%lld,%lld side %lld kind %d p %d m %d tol %.9g: %s %#x, their triangles "
                      "%#x (largest distances %.9g %.9g %.9g %.9g)",
                      (long long)x0, (long long)y0, (long long)x1, (long long)y1, (long long)s, kind, p != NULL,
                      m != NULL, tol, probe ? "probe" : "variants", got, want, e[0], e[1], e[2], e[3]);
            k.cases++;
            k.pass += (unsigned)__builtin_popcount(want);
            k.fail += (unsigned)__builtin_popcount(ways) - (unsigned)__builtin_popcount(want);
            k.rejected += (unsigned)__builtin_popcount(ways & ~got);
            k.nans += nodata;
        }
    }
    return k;
}

/* tsr__rqt_half_variants (the quadtree's test of a leaf's half, all four
 * ways its midpoints may split it in one scan, from hat functions) against
 * each way's triangles scanned on their own planes, on halves and fan
 * triangles of random boxes of 2 to 32 cells. */
TEST(quadtree_half_variants_against_their_triangles)
{
    tsr_heightfield *hf = terrain(70, 70, 5);
    srand(17);
    half_counts k = half_cases(hf, 70, 1, 5, 3000, 2500, false);
    /* the cases cover passing and failing ways, and no-data */
    CHECK_MSG(k.cases > 8000 && k.pass > 8000 && k.fail > 8000 && k.nans > 50,
              "%llu cases, %llu ways passing, %llu failing, %llu with no-data", (unsigned long long)k.cases,
              (unsigned long long)k.pass, (unsigned long long)k.fail, (unsigned long long)k.nans);
    tsr_heightfield_destroy(hf);
}

/* The probe of a big half (a lattice of its samples, which lets a failing
 * half fail without its full scan) never rejects a way that is within the
 * tolerance, and does reject ways beyond it: halves of 32 to 128 cells. */
TEST(quadtree_half_probe_holds_the_variants)
{
    tsr_heightfield *hf = terrain(260, 260, 9);
    srand(23);
    half_counts k = half_cases(hf, 260, 5, 7, 600, 500, true);
    /* the probe rejects a good share of the failing ways (the tolerances
     * a hair below a largest distance are the ones it cannot see) */
    CHECK_MSG(k.cases > 1500 && k.pass > 1500 && k.rejected > k.fail / 4 && k.nans > 10,
              "%llu cases, %llu ways passing, %llu failing, %llu rejected by the probe, %llu with no-data",
              (unsigned long long)k.cases, (unsigned long long)k.pass, (unsigned long long)k.fail,
              (unsigned long long)k.rejected, (unsigned long long)k.nans);
    tsr_heightfield_destroy(hf);
}

TEST(window_seams)
{
    tsr_heightfield *hf = terrain(120, 97, 6);
    /* rough left of column 40, smooth right of it: the vertical seam (column
     * 63) has a smooth profile that leaves room for different choices, the
     * horizontal one crosses both */
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < 97; r++)
        for (uint32_t c = 40; c < 120; c++)
            d[r * 120 + c] = (float)(50 * sin(r / 15.0) + 0.02 * (c - 40.0) * (c - 40.0) + 20 * cos(c / 9.0));
    double errors[] = {1.5, 15};
    for (int mth = 0; mth < 3; mth++)
        for (int v = 0; v < 2; v++)
            for (int e = 0; e < 2; e++)
                seam_case(hf, mth == 2 ? TSR_TIN_GRID : methods[mth], mth == 2 ? 1e9 : errors[e], v);
    /* no bound given: the default is the whole heightfield's, so the
     * windows still share their border (it was each window's own) */
    for (int v = 0; v < 2; v++)
        seam_case(hf, TSR_TIN_DELAUNAY, 0, v);
    /* no-data right of the seam at column 63 (rows 20..40), left of it
     * (rows 60..70) */
    for (uint32_t r = 0; r < 97; r++)
        for (uint32_t c = 0; c < 120; c++)
            if ((c >= 64 && c <= 66 && r >= 20 && r <= 40) || (c >= 60 && c <= 62 && r >= 60 && r <= 70))
                d[r * 120 + c] = NAN;
    for (int e = 0; e < 2; e++)
        seam_nodata_case(hf, errors[e] * 10, 63);
    tsr_heightfield_destroy(hf);
}

/* Windows whose heights lie far apart (one holds a plateau 3e5 up, away
 * from the seam) still share their border: the bound's margin for float
 * rounding came from each window's own largest height, so the two sides
 * simplified the same border profile with tolerances 0.1 apart (a GIS
 * audit found cracks between tiles of a 4097 terrain). */
TEST(window_seams_heights_apart)
{
    tsr_heightfield *hf = terrain(120, 97, 6);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < 97; r++)
        for (uint32_t c = 40; c < 120; c++)
            d[r * 120 + c] = (float)(50 * sin(r / 15.0) + 0.02 * (c - 40.0) * (c - 40.0) + 20 * cos(c / 9.0));
    for (uint32_t r = 10; r < 30; r++)
        for (uint32_t c = 10; c < 30; c++)
            d[r * 120 + c] += 3e5f;
    double errors[] = {0.3, 1.5};
    for (int mth = 0; mth < 2; mth++)
        for (int v = 0; v < 2; v++)
            for (int e = 0; e < 2; e++)
                seam_case(hf, methods[mth], errors[e], v);
    tsr_heightfield_destroy(hf);
}

/* The blocks tsr_terrain_mesh cuts hf into with o (0 when it fails). */
static uint32_t blocks_of(const tsr_heightfield *hf, const tsr_tin_options *o)
{
    tsr_tin_report rep = {0};
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_status st = tsr_terrain_mesh(hf, o, &m, &rep, NULL);
    tsr_mesh_free(&m);
    return st == TSR_OK ? rep.blocks : 0;
}

/* Blocks (tsr_tin_options.block): the window cut into blocks meshed on
 * their own, on several threads. The welded mesh is within the bound,
 * covers every valid cell, is conforming across the seams (no T-junction,
 * no crack: tsr_mesh_validate) and the same whatever the thread count.
 * With no-data crossing the seams, each side cuts its border where the
 * other side's cells change too, so the seams still match. */
static void blocks_case(const tsr_heightfield *hf, uint32_t block, double e, const char *what)
{
    tsr_mesh ref;
    tsr_mesh_init(&ref, 0, NULL);
    for (uint32_t threads = 1; threads <= 3; threads++) {
        tsr_tin_options o = {0};
        o.max_error = e;
        o.block = block;
        o.threads = threads;
        char w[96];
        snprintf(w, sizeof w, "%s block %u E=%g threads %u", what, block, e, threads);
        bound_case(hf, o, w);
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        tsr_tin_report rep;
        CHECK(tsr_terrain_mesh(hf, &o, &m, &rep, NULL) == TSR_OK);
        uint32_t cells_x = tsr_heightfield_width(hf) - 1, cells_y = tsr_heightfield_height(hf) - 1;
        CHECK_MSG(rep.blocks == ((cells_x + block - 1) / block) * ((cells_y + block - 1) / block), "%s: %u blocks",
                  w, rep.blocks);
        if (threads == 1) {
            ref = m;
            continue;
        }
        CHECK_MSG(same_mesh(&m, &ref), "%s: not the mesh of one thread", w);
        tsr_mesh_free(&m);
    }
    tsr_mesh_free(&ref);
}

TEST(blocks)
{
    tsr_heightfield *hf = terrain(150, 131, 9);
    blocks_case(hf, 16, 2, "generated");
    blocks_case(hf, 37, 0.5, "generated");
    blocks_case(hf, 64, 20, "generated");
    /* one block: the mesh without blocks */
    tsr_tin_options o = {0};
    o.max_error = 2;
    o.block = 149;
    CHECK(blocks_of(hf, &o) == 1);
    /* no-data across the seams. With blocks of 37 cells the 149 x 130
     * cells split into 5 x 4 blocks: column seams at 29, 59, 89, 119 (k
     * 149 / 5), row seams at 32, 65, 97. On one side of a seam only: cells
     * right of column 59 (rows 10..30) and left of 89 (rows 40..60), above
     * row 65 (columns 5..25) and below 97 (columns 100..115); the other
     * side cuts its border there too, or the seam gets T-junctions. Plus
     * discs and a checkerboard over seams and a seam corner. */
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < 131; r++)
        for (uint32_t c = 0; c < 150; c++) {
            double dx = c - 32.0, dy = r - 40.0, ex = c - 119.0, ey = r - 74.0;
            bool hole = dx * dx + dy * dy < 90 || ex * ex + ey * ey < 30;
            hole |= c >= 60 && c <= 62 && r >= 10 && r <= 30;
            hole |= c >= 86 && c <= 88 && r >= 40 && r <= 60;
            hole |= r >= 66 && r <= 67 && c >= 5 && c <= 25;
            hole |= r >= 95 && r <= 96 && c >= 100 && c <= 115;
            hole |= c >= 86 && c < 94 && r >= 94 && r < 100 && (c + r) % 2 == 0;
            if (hole)
                d[r * 150 + c] = NAN;
        }
    blocks_case(hf, 16, 2, "no-data");
    blocks_case(hf, 37, 0.5, "no-data");
    blocks_case(hf, 37, 20, "no-data");
    tsr_heightfield_destroy(hf);
}

/* Meshes a copy of src made through a counting allocator that fails its
 * k-th call, for every k up to the calls a mesh takes (every one of the
 * first 40, then about 60 spread over the rest): each run gives TSR_OK or
 * TSR_ERR_NOMEM with a message and leaves no block behind; with no failure
 * the mesh is the one made through the default allocator. Returns how
 * many runs reported TSR_ERR_NOMEM, and the calls in *calls. */
static uint32_t fail_each_allocation(const tsr_heightfield *src, const tsr_tin_options *o, const char *what,
                                     long *calls)
{
    uint32_t w = tsr_heightfield_width(src), h = tsr_heightfield_height(src);
    check_alloc f = {0};
    tsr_allocator al = {check_realloc, &f, NULL};
    tsr_heightfield *hf = tsr_heightfield_create(w, h, &al);
    memcpy(tsr_heightfield_data(hf), tsr_heightfield_cdata(src), (size_t)w * h * sizeof(float));
    tsr_mesh want, m;
    tsr_mesh_init(&want, 0, NULL);
    CHECK(tsr_terrain_mesh(src, o, &want, NULL, NULL) == TSR_OK);
    long live = f.live, start = f.calls;
    tsr_mesh_init(&m, 0, &al);
    CHECK(tsr_terrain_mesh(hf, o, &m, NULL, NULL) == TSR_OK);
    *calls = f.calls - start;
    CHECK_MSG(m.vertex_count == want.vertex_count && m.triangle_count == want.triangle_count &&
                  !memcmp(m.positions, want.positions, 3 * sizeof(float) * want.vertex_count) &&
                  !memcmp(m.indices, want.indices, 3 * sizeof(uint32_t) * want.triangle_count),
              "%s: the mesh differs from the default allocator's", what);
    tsr_mesh_free(&m);
    CHECK(f.live == live);
    uint32_t nomem = 0;
    for (long k = 1; k <= *calls; k += k < 40 ? 1 : *calls / 60 + 1) {
        f.fail_at = f.calls + k;
        tsr_error err = {0};
        tsr_mesh_init(&m, 0, &al);
        tsr_status st = tsr_terrain_mesh(hf, o, &m, NULL, &err);
        CHECK_MSG(st == TSR_OK || st == TSR_ERR_NOMEM, "%s, failure at allocation %ld: status %d", what, k, (int)st);
        if (st == TSR_ERR_NOMEM) {
            nomem++;
            CHECK_MSG(err.message[0], "%s, failure at allocation %ld: no message", what, k);
        }
        tsr_mesh_free(&m);
        CHECK_MSG(f.live == live, "%s, failure at allocation %ld: %ld blocks left", what, k, f.live - live);
    }
    f.fail_at = 0;
    tsr_mesh_free(&want);
    tsr_heightfield_destroy(hf);
    return nomem;
}

/* Blocks are welded into the output as they finish (in block order):
 * an allocation failing anywhere (a block's mesher, its crop, a weld's
 * map, the output's growth) gives TSR_ERR_NOMEM with a message and leaves
 * nothing behind; with no failure the mesh is the one made through the
 * default allocator. One thread: the test's allocator counts unlocked. */
TEST(blocks_allocation_failures)
{
    tsr_heightfield *src = terrain(150, 131, 9);
    tsr_tin_options o = {0};
    o.max_error = 2;
    o.block = 37;
    o.threads = 1;
    CHECK(blocks_of(src, &o) == 20);
    long calls;
    uint32_t nomem = fail_each_allocation(src, &o, "blocks", &calls);
    CHECK_MSG(calls > 40 && nomem > 40, "only %u of the failed allocations were reported (%ld calls)", nomem, calls);
    tsr_heightfield_destroy(src);
}

/* The quadtree method's allocations (its block of per-node bits, its
 * stack, the mesh) failing one at a time, as above, with a bound and with
 * a budget (which selects cuts again in the same block), on one thread and
 * on two (the workers judge only: they allocate nothing). */
TEST(quadtree_allocation_failures)
{
    tsr_heightfield *src = terrain(150, 131, 9);
    for (int c = 0; c < 4; c++) {
        tsr_tin_options o = {0};
        o.method = TSR_TIN_QUADTREE;
        o.threads = 1 + (uint32_t)(c & 1);
        if (c < 2)
            o.max_error = 2;
        else
            o.max_triangles = 3000;
        char what[32];
        snprintf(what, sizeof what, "quadtree case %d", c);
        long calls;
        uint32_t nomem = fail_each_allocation(src, &o, what, &calls);
        CHECK_MSG(calls >= 3 && nomem >= 3, "%s: only %u of %ld failed allocations were reported", what, nomem,
                  calls);
    }
    tsr_heightfield_destroy(src);
}

/* tessera mesh --base: the mesher's output (with no-data holes) closed
 * into a solid: no boundary edge left, every edge used once each way, and
 * the signed volume equal to the prisms under the top. */
TEST(closed_solid)
{
    tsr_heightfield *hf = terrain(80, 60, 8);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 20; r < 30; r++)
        for (uint32_t c = 30; c < 45; c++)
            d[r * 80 + c] = NAN;
    for (int mth = 0; mth < 2; mth++) {
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        tsr_tin_options o = {0};
        o.method = methods[mth];
        o.max_error = 4;
        tsr_error err;
        CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_OK);
        double zmin = INFINITY, prisms = 0, base;
        for (uint32_t i = 0; i < m.vertex_count; i++)
            zmin = fmin(zmin, m.positions[3 * (size_t)i + 2]);
        base = zmin - 10;
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            const float *p[3];
            for (int k = 0; k < 3; k++)
                p[k] = m.positions + 3 * (size_t)m.indices[3 * (size_t)t + k];
            double area = 0.5 * (((double)p[1][0] - p[0][0]) * ((double)p[2][1] - p[0][1]) -
                                 ((double)p[1][1] - p[0][1]) * ((double)p[2][0] - p[0][0]));
            prisms += area * (((double)p[0][2] + p[1][2] + p[2][2]) / 3 - base);
        }
        uint32_t top = m.triangle_count;
        CHECK_MSG(tsr_mesh_add_base(&m, base, &err) == TSR_OK, "%s", err.message);
        CHECK(m.triangle_count > top);
        tsr_validation v;
        CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
        CHECK_MSG(tsr_validation_ok(&v) && v.boundary_edges == 0, "%s: %u boundary edges", mname[mth],
                  v.boundary_edges);
        double vol = 0; /* divergence theorem over the closed surface */
        for (uint32_t t = 0; t < m.triangle_count; t++) {
            const float *a = m.positions + 3 * (size_t)m.indices[3 * (size_t)t],
                        *b = m.positions + 3 * (size_t)m.indices[3 * (size_t)t + 1],
                        *c = m.positions + 3 * (size_t)m.indices[3 * (size_t)t + 2];
            vol += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
                    (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
                    (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) / 6;
        }
        CHECK_MSG(fabs(vol - prisms) <= 1e-6 * fabs(prisms), "%s: volume %.9g, prisms %.9g", mname[mth], vol, prisms);
        tsr_mesh_free(&m);
    }
    tsr_heightfield_destroy(hf);
}

TEST(bad_options)
{
    tsr_heightfield *hf = terrain(20, 20, 7);
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err;
    tsr_tin_options o = {0};
    o.max_error = -1;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    o.max_error = NAN;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    o.max_error = 1;
    o.window_x = 15;
    o.window_w = 10;
    o.window_h = 5;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK(strstr(err.message, "window") != NULL);
    o.window_x = 0;
    o.window_w = 1;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK(m.vertex_count == 0 && m.triangle_count == 0);
    /* a border tolerance above the bound, given or the default; a budget
     * alone has no bound to exceed */
    o = (tsr_tin_options){0};
    o.max_error = 1;
    o.border_error = 1.5;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK_MSG(strstr(err.message, "border tolerance 1.5 exceeds the bound 1") != NULL, "%s", err.message);
    o.max_error = 0;
    o.border_error = 1e6;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK_MSG(strstr(err.message, "(the default") != NULL, "%s", err.message);
    o.max_triangles = 100;
    tsr_status st = tsr_terrain_mesh(hf, &o, &m, NULL, &err);
    CHECK_MSG(st == TSR_OK && m.triangle_count <= 100, "%s", err.message);
    tsr_mesh_free(&m);
    tsr_mesh_init(&m, 0, NULL);
    /* vertices are floats: heights times dz, or extents, beyond them */
    o = (tsr_tin_options){0};
    double dz = hf->dz, dx = hf->dx;
    hf->dz = 1e38;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK_MSG(strstr(err.message, "heights times dz pass the largest float") != NULL, "%s", err.message);
    hf->dz = dz;
    hf->dx = 1e38;
    CHECK(tsr_terrain_mesh(hf, &o, &m, NULL, &err) == TSR_ERR_ARGUMENT);
    CHECK_MSG(strstr(err.message, "the extents") != NULL, "%s", err.message);
    hf->dx = dx;
    CHECK(m.vertex_count == 0 && m.triangle_count == 0);
    tsr_mesh_free(&m);
    tsr_heightfield_destroy(hf);
}

static void data_file(const char *name, const tsr_load_options *lo, double e)
{
    const char *data = check_data_dir();
    char path[8192];
    snprintf(path, sizeof path, "%s/terrain/%s", data, name);
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(path, lo, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    if (!hf)
        return;
    for (int mth = 0; mth < 2; mth++) {
        tsr_tin_options o = {0};
        o.method = methods[mth];
        o.max_error = e;
        bound_case(hf, o, name);
    }
    /* seams on real data */
    for (int v = 0; v < 2; v++)
        seam_case(hf, TSR_TIN_DELAUNAY, e, v);
    tsr_heightfield_destroy(hf);
}

TEST(data_real_terrain)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    tsr_load_options rgb = {0};
    rgb.decode = TSR_DECODE_TERRAIN_RGB;
    data_file("bayhills-14-2625-6369-terrainrgb.png", &rgb, 1.0);
    data_file("bayhills-14-2625-6369-terrainrgb.png", &rgb, 0.2);
    data_file("valid_raster-float32.tif", NULL, 0.5);
    data_file("egm84-epsg3857-float32.tif", NULL, 0.05);
}

/* tsr_terrain_measure_window in bands of rows, each with scratch of its
 * own: over a field of several bands (with no-data), its max and count of
 * covered samples are the brute-force oracle's; and a failed allocation
 * (the band's scratch) is TSR_ERR_NOMEM with nothing left. */
TEST(measure_bands_agree_with_brute_force)
{
    tsr_heightfield *hf = terrain(90, 400, 7);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 150; r < 170; r++) /* a hole across a band's edge (row 128 .. 255) */
        for (uint32_t c = 30; c < 45; c++)
            d[(size_t)r * 90 + c] = NAN;
    tsr_tin_options o = {0};
    o.max_error = 5;
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    tsr_tin_report rep;
    CHECK_MSG(tsr_terrain_mesh(hf, &o, &m, &rep, &err) == TSR_OK, "%s", err.message);
    oracle or;
    brute(hf, 0, 0, 90, 400, &m, &or);
    tsr_error_report er;
    CHECK(tsr_terrain_measure_window(hf, 0, 0, 90, 400, &m, NULL, &er) == TSR_OK);
    CHECK_MSG(fabs(er.max_vertical - or.max_error) <= 1e-6 * 500, "bands %.9g, brute force %.9g", er.max_vertical,
              or.max_error);
    CHECK_MSG(er.covered == or.covered && er.uncovered == 0, "covered %llu vs %llu, uncovered %llu",
              (unsigned long long)er.covered, (unsigned long long)or.covered, (unsigned long long)er.uncovered);
    tsr_mesh_free(&m);
    /* one band, its heightfield's allocator failing at the band's scratch */
    check_alloc f = {0};
    tsr_allocator al = {check_realloc, &f, NULL};
    tsr_heightfield *small = tsr_heightfield_create(40, 40, &al);
    tsr_heightfield *src = terrain(40, 40, 3);
    memcpy(tsr_heightfield_data(small), tsr_heightfield_cdata(src), 40 * 40 * sizeof(float));
    tsr_mesh_init(&m, 0, NULL);
    o.method = TSR_TIN_DELAUNAY;
    CHECK(tsr_terrain_mesh(src, &o, &m, &rep, &err) == TSR_OK);
    long live = f.live;
    CHECK(tsr_terrain_measure_window(small, 0, 0, 40, 40, &m, NULL, &er) == TSR_OK);
    long calls = f.calls;
    CHECK(f.live == live && calls > 0);
    uint32_t nomem = 0;
    for (long k = 1; k <= 8; k++) {
        f.fail_at = f.calls + k;
        tsr_status st = tsr_terrain_measure_window(small, 0, 0, 40, 40, &m, NULL, &er);
        CHECK(st == TSR_OK || st == TSR_ERR_NOMEM);
        nomem += st == TSR_ERR_NOMEM;
        CHECK_MSG(f.live == live, "failure at allocation %ld: %ld blocks left", k, f.live - live);
        if (st == TSR_ERR_NOMEM)
            CHECK(er.covered == 0 && er.max_vertical == 0);
    }
    CHECK_MSG(nomem > 0, "no allocation of the measurement failed");
    f.fail_at = 0;
    tsr_mesh_free(&m);
    tsr_heightfield_destroy(small);
    tsr_heightfield_destroy(src);
    tsr_heightfield_destroy(hf);
}

TEST_MAIN(T(error_bound_generated), T(measure_bands_agree_with_brute_force), T(flips_fewer_triangles),
          T(spacing_and_scale), T(measure_far_from_the_origin), T(flat_and_planar), T(budgets), T(nodata_holes),
          T(quadtree_leaves_and_tiles), T(quadtree_half_variants_against_their_triangles),
          T(quadtree_half_probe_holds_the_variants), T(window_seams), T(window_seams_heights_apart), T(blocks),
          T(blocks_allocation_failures), T(quadtree_allocation_failures), T(closed_solid), T(bad_options),
          T(data_real_terrain))
