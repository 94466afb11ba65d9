/* Renders a known terrain through the Vulkan backend (lavapipe in CI) and
 * checks the image against independent oracles:
 *  - every pixel's depth against the CPU ray cast (tsr_terrain_pick on the
 *    full-resolution surface) through the pixel's centre: where both hit,
 *    the drawn point and the true surface point vertically below or above
 *    it are at most tau pixels apart on screen (what the cut promises);
 *    where they disagree (sky against terrain), only along silhouettes;
 *  - the GPU's own triangle count (pipeline statistics) against the cut's,
 *    counted here from the quadtree's leaves and tsr_tile_pattern;
 *  - the image has terrain and sky, changes when the camera moves, and
 *    matches a stored reference within a small per-pixel tolerance;
 *  - the validation layers (required here when installed) say nothing.
 * Skipped when no Vulkan device is available. */
#define _GNU_SOURCE /* RTLD_NODELETE */
#include "check.h"
#include "terrain/terrain_internal.h" /* tsr_image_read */
#include "tools/fly.h"

#include <dlfcn.h>

#define W 240
#define H 160

static tsr_heightfield *make_terrain(void)
{
    tsr_heightfield *hf = tsr_heightfield_create(257, 257, NULL);
    tsr_generate_options g = {.seed = 7, .relief = 400};
    tsr_terrain_generate(hf, &g);
    tsr_heightfield_set_spacing(hf, 10, 10, 1);
    return hf;
}

/* The backend, with the validation layers when they are installed. */
static tsr_hw_backend *backend(void)
{
    /* Keep lavapipe loaded after the loader lets it go, so LeakSanitizer
     * can name it (tests/lsan.supp) instead of an unknown module. */
    dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_NODELETE);
    tsr_hw_vulkan_options o = {.width = W, .height = H, .validation = 1};
    tsr_hw_backend *b = NULL;
    tsr_error err = {0};
    if (tsr_hw_vulkan_create(&o, NULL, &b, &err) == TSR_OK)
        return b;
    o.validation = -1;
    if (tsr_hw_vulkan_create(&o, NULL, &b, &err) == TSR_OK) {
        fprintf(stderr, "note: validation layers not installed; rendering without them\n");
        return b;
    }
    fprintf(stderr, "no Vulkan device: %s\n", err.message);
    return NULL;
}

typedef struct view {
    double eye[3], target[3];
} view;

/* A high oblique view, a low grazing one, and one looking across a valley. */
static const view views[] = {
    {{-300, -300, 900}, {1280, 1280, 0}},
    {{1280, 200, 260}, {1280, 2200, 150}},
    {{2400, 2400, 700}, {900, 1100, 100}},
};

static uint8_t *render(fly_ctx *f, const view *v, fly_frame_stats *fs, float *depth)
{
    tsr_camera cam;
    CHECK(fly_camera(f, v->eye, v->target, &cam));
    tsr_error err = {0};
    tsr_status st = fly_frame(f, &cam, fs, &err);
    CHECK_MSG(st == TSR_OK, "%s", err.message);
    uint8_t *rgba = malloc(W * H * 4);
    CHECK(f->backend->read_color(f->backend, rgba));
    if (depth)
        CHECK(f->backend->read_depth(f->backend, depth));
    return rgba;
}

static void ground_below(const tsr_terrain *t, const double p[3], double *z)
{
    *z = ground_height(t, p[0], p[1]);
}

TEST(depth_matches_picking)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = make_terrain();
    /* without geomorphing the cut's bound is tau; with it, a morphing
     * vertex lies between the tile's surface and its parent's, whose
     * screen error is below 2 tau wherever the morph weight is not 0 */
    for (int morph = 0; morph <= 1; morph++) {
        fly_options o = {.tile_n = 8, .pixel_error = 1.5, .fog_distance = -1, .geomorph = morph};
        double bound = (morph ? 2 : 1) * o.pixel_error;
        fly_ctx f;
        tsr_error err = {0};
        CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
        float *depth = malloc(W * H * sizeof *depth);
        for (size_t vi = 0; vi < sizeof views / sizeof views[0]; vi++) {
            fly_frame_stats fs;
            uint8_t *rgba = render(&f, &views[vi], &fs, depth);
            tsr_camera cam;
            fly_camera(&f, views[vi].eye, views[vi].target, &cam);
            uint32_t hits = 0, both = 0, mismatch = 0, far_mismatch = 0, over = 0;
            double worst = 0;
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    /* the ray through the pixel's centre, with unit depth (the
                     * image is the camera's mirrored left to right, so the map
                     * shows the right way round: fly_frame_desc) */
                    double u = -(x + 0.5 - W / 2.0) / cam.K, w = -(y + 0.5 - H / 2.0) / cam.K, dir[3];
                    for (int k = 0; k < 3; k++)
                        dir[k] = cam.fwd[k] + u * cam.right[k] + w * cam.up[k];
                    double t;
                    bool cpu = tsr_terrain_pick(f.terrain, cam.eye, dir, &t);
                    float d = depth[y * W + x];
                    bool gpu = d > 0;
                    hits += gpu;
                    if (gpu != cpu) {
                        mismatch++;
                        /* only along a silhouette: a pixel of the other kind nearby */
                        bool edge = false;
                        for (int dy = -2; dy <= 2 && !edge; dy++)
                            for (int dx = -2; dx <= 2 && !edge; dx++) {
                                int xx = x + dx, yy = y + dy;
                                if (xx >= 0 && yy >= 0 && xx < W && yy < H)
                                    edge = (depth[yy * W + xx] > 0) == cpu;
                            }
                        far_mismatch += !edge;
                        continue;
                    }
                    if (!gpu)
                        continue;
                    both++;
                    double dist = cam.near_dist / d, p[3], q[3];
                    for (int k = 0; k < 3; k++)
                        p[k] = cam.eye[k] + dist * dir[k];
                    double gz;
                    ground_below(f.terrain, p, &gz);
                    if (isnan(gz))
                        continue; /* on the border, outside by rounding */
                    memcpy(q, p, sizeof q);
                    q[2] = gz;
                    double px, py, pd, qx, qy, qd;
                    tsr_camera_project(&cam, p, &px, &py, &pd);
                    tsr_camera_project(&cam, q, &qx, &qy, &qd);
                    double e = hypot(px - qx, py - qy);
                    worst = e > worst ? e : worst;
                    /* tau, plus the rounding of a float depth buffer and a float mesh */
                    over += e > bound * 1.05 + 0.05;
                }
            fprintf(stderr,
                    "view %zu%s: %u terrain pixels, %u checked, worst %.3f px (bound %.1f), %u silhouette "
                    "disagreements\n",
                    vi, morph ? " geomorphed" : "", hits, both, worst, bound, mismatch);
            CHECK(hits > W * H / 5); /* terrain on screen */
            CHECK(hits < W * H);     /* and sky */
            CHECK_MSG(over == 0, "%u pixels beyond tau (worst %.3f px)", over, worst);
            CHECK_MSG(far_mismatch == 0, "%u sky/terrain disagreements away from any silhouette", far_mismatch);
            CHECK(mismatch < W * H / 100);
            free(rgba);
        }
        CHECK_MSG(b->stats.validation_messages == 0, "%llu validation messages",
                  (unsigned long long)b->stats.validation_messages);
        free(depth);
        fly_free(&f);
    }
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

TEST(triangles_drawn_match_cut)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = make_terrain();
    for (uint32_t tile = 4; tile <= 16; tile *= 4) {
        fly_options o = {.tile_n = tile, .pixel_error = 1, .wireframe = tile == 16, .geomorph = true};
        fly_ctx f;
        tsr_error err = {0};
        CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
        for (size_t vi = 0; vi < sizeof views / sizeof views[0]; vi++) {
            fly_frame_stats fs;
            free(render(&f, &views[vi], &fs, NULL));
            /* the cut's triangles, counted from the leaves */
            uint64_t want = 0;
            const tsr_qleaf *L = tsr_quadtree_leaves(f.qt);
            for (uint32_t i = 0; i < tsr_quadtree_leaf_count(f.qt); i++)
                if (!L[i].culled)
                    want += tsr_tile_pattern(tile, L[i].stitch, NULL);
            CHECK(want > 0);
            CHECK_MSG(fs.render.device.triangles == want, "tile %u view %zu: GPU %llu, cut %llu", tile, vi,
                      (unsigned long long)fs.render.device.triangles, (unsigned long long)want);
            CHECK(fs.render.triangles == want);
        }
        fly_free(&f);
    }
    CHECK(b->stats.validation_messages == 0);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

/* The Vulkan backend's end_frame refuses a frame whose draws name
 * neighbours they cannot have, or draw from a buffer destroyed since
 * draw_tile (even when a new buffer took its id), drawing none of it and
 * leaving the next frame unharmed; the GPU's triangle count says so. */
TEST(vulkan_end_frame_refusals)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    uint32_t pat[3 * 32];
    uint32_t tri = tsr_tile_pattern(4, 0, pat);
    CHECK(tri == 32);
    tsr_hw_buffer vb = b->create_buffer(b, TSR_HW_VERTEX, 4096), ib = b->create_buffer(b, TSR_HW_INDEX, sizeof pat);
    float samples[25] = {0};
    CHECK(vb && ib && b->upload(b, vb, 0, samples, sizeof samples) && b->upload(b, ib, 0, pat, sizeof pat));
    tsr_hw_frame frame;
    memset(&frame, 0, sizeof frame);
    frame.view_proj[0] = frame.view_proj[5] = frame.view_proj[15] = 1;
    tsr_hw_tile_draw d;
    memset(&d, 0, sizeof d);
    d.samples = vb;
    d.format = TSR_HW_HEIGHT_F32;
    d.indices = ib;
    d.index_count = 96;
    d.n = 4;
    d.spacing[0] = d.spacing[1] = 1;
    d.limit[0] = d.limit[1] = 1e30f;
    d.z_step = 1;
    tsr_hw_tile_draw e = d; /* next to d, naming it */
    e.origin[0] = 4;
    e.neighbour[6] = e.neighbour[7] = 1;
    d.neighbour[2] = d.neighbour[3] = 2;
    tsr_hw_frame_stats fs;
    for (int round = 0; round < 2; round++) {
        CHECK(b->begin_frame(b, &frame) && b->draw_tile(b, &d) && b->draw_tile(b, &e));
        CHECK(b->end_frame(b, &fs) && fs.triangles == 64);
        tsr_hw_tile_draw bad = e;
        bad.neighbour[0] = 2; /* itself */
        CHECK(b->begin_frame(b, &frame) && b->draw_tile(b, &d) && b->draw_tile(b, &bad));
        CHECK(!b->end_frame(b, &fs) && fs.triangles == 0);
        bad.neighbour[0] = 3; /* a third draw that never comes */
        CHECK(b->begin_frame(b, &frame) && b->draw_tile(b, &d) && b->draw_tile(b, &bad));
        CHECK(!b->end_frame(b, &fs) && fs.triangles == 0);
    }
    /* a buffer destroyed after a draw used it, its id given to a smaller one */
    tsr_hw_buffer vb2 = b->create_buffer(b, TSR_HW_VERTEX, 4096);
    CHECK(vb2 && b->upload(b, vb2, 0, samples, sizeof samples));
    tsr_hw_tile_draw lone = d;
    memset(lone.neighbour, 0, sizeof lone.neighbour);
    tsr_hw_tile_draw f2 = lone;
    f2.samples = vb2;
    f2.samples_offset = 4096 - 100;
    CHECK(b->begin_frame(b, &frame) && b->draw_tile(b, &f2));
    b->destroy_buffer(b, vb2);
    tsr_hw_buffer small = b->create_buffer(b, TSR_HW_VERTEX, 16);
    fprintf(stderr, "destroyed buffer %u, the new one is %u\n", vb2, small);
    CHECK(!b->end_frame(b, &fs) && fs.triangles == 0);
    CHECK(b->begin_frame(b, &frame) && b->draw_tile(b, &lone) && b->end_frame(b, &fs) && fs.triangles == 32);
    CHECK(b->stats.validation_messages == 0);
    b->destroy_buffer(b, small);
    b->destroy_buffer(b, vb);
    b->destroy_buffer(b, ib);
    b->destroy(b);
}

/* The world point drawn at pixel (x, y), from its depth; false where
 * nothing was drawn. */
static bool pixel_point(const tsr_camera *cam, const float *depth, int x, int y, double p[3])
{
    float d = depth[y * W + x];
    if (!(d > 0))
        return false;
    double u = -(x + 0.5 - W / 2.0) / cam->K, w = -(y + 0.5 - H / 2.0) / cam->K; /* mirrored: fly_frame_desc */
    for (int k = 0; k < 3; k++)
        p[k] = cam->eye[k] + cam->near_dist / d * (cam->fwd[k] + u * cam->right[k] + w * cam->up[k]);
    return true;
}

/* fly's neighbours (tsr_hw_tile.neighbour) against geometry, on the null
 * backend (no device needed): across each half edge of each drawn tile,
 * the drawn tile whose rectangle holds the half edge's midpoint moved a
 * little outwards, or none. */
TEST(neighbours_match_geometry)
{
    tsr_hw_backend *b = tsr_hw_null_create(W, H, NULL);
    tsr_heightfield *hf = make_terrain();
    fly_options o = {.tile_n = 8, .pixel_error = 1};
    fly_ctx f;
    tsr_error err = {0};
    CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
    uint32_t relation[3] = {0}; /* half edges whose neighbour is coarser, as fine, finer */
    for (size_t vi = 0; vi < sizeof views / sizeof views[0]; vi++) {
        tsr_camera cam;
        fly_frame_stats fs;
        CHECK(fly_camera(&f, views[vi].eye, views[vi].target, &cam));
        CHECK(fly_frame(&f, &cam, &fs, &err) == TSR_OK);
        uint32_t count = fs.render.tiles, wrong = 0;
        CHECK(count > 50);
        for (uint32_t k = 0; k < count; k++) {
            const tsr_hw_tile *t = &f.tiles[k];
            double side = o.tile_n * t->spacing[0];
            for (int e = 0; e < 4; e++)
                for (int h = 0; h < 2; h++) {
                    double along = (h + 0.5) / 2 * side, out = 1e-3 * t->spacing[0], p[2];
                    p[0] = t->origin[0] + (e == 1 ? side + out : e == 3 ? -out : along);
                    p[1] = t->origin[1] + (e == 2 ? side + out : e == 0 ? -out : along);
                    uint32_t want = 0;
                    for (uint32_t u = 0; u < count; u++) {
                        const tsr_hw_tile *v = &f.tiles[u];
                        double vs = o.tile_n * v->spacing[0];
                        if (u != k && p[0] >= v->origin[0] && p[0] <= v->origin[0] + vs && p[1] >= v->origin[1] &&
                            p[1] <= v->origin[1] + vs) {
                            CHECK_MSG(!want, "two tiles hold one point");
                            want = u + 1;
                        }
                    }
                    wrong += t->neighbour[2 * e + h] != want;
                    if (want)
                        relation[f.tiles[want - 1].level < t->level   ? 0
                                 : f.tiles[want - 1].level == t->level ? 1
                                                                       : 2]++;
                }
        }
        CHECK_MSG(wrong == 0, "view %zu: %u of %u half edges with the wrong neighbour", vi, wrong, 8 * count);
    }
    CHECK(relation[0] > 0 && relation[1] > 0 && relation[2] > 0);
    fly_free(&f);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

/* A quadratic bowl, h = a x^2 + b y^2 + c x y about the centre: central
 * differences of its samples at any step are its exact gradient, and the
 * gradient is linear, so drawn normals interpolated across a triangle
 * stay near the true ones; a one-sided difference is off by a s (s the
 * step) instead. */
#define BOWL_A 2.3e-4
#define BOWL_B 1.5e-4
#define BOWL_C 1.0e-4
static void bowl_gradient(double x, double y, double g[2])
{
    x -= 1280;
    y -= 1280;
    g[0] = 2 * BOWL_A * x + BOWL_C * y;
    g[1] = 2 * BOWL_B * y + BOWL_C * x;
}

static tsr_heightfield *make_bowl(void)
{
    tsr_heightfield *hf = tsr_heightfield_create(257, 257, NULL);
    float *h = tsr_heightfield_data(hf);
    for (int j = 0; j < 257; j++)
        for (int i = 0; i < 257; i++) {
            double x = i * 10.0 - 1280, y = j * 10.0 - 1280;
            h[j * 257 + i] = (float)(BOWL_A * x * x + BOWL_B * y * y + BOWL_C * x * y);
        }
    tsr_heightfield_set_spacing(hf, 10, 10, 1);
    return hf;
}

/* The normals drawn (TSR_HW_FRAME_NORMALS) against the bowl's true normal
 * at every terrain pixel's point (from its depth): with the neighbours'
 * samples at tile borders the whole image is within colour rounding and
 * interpolation; with one-sided border normals (as before neighbours were
 * passed) the borders of the coarse tiles are not, so the check can fail.
 * A cut of several levels (tiles of 8, a low oblique view). */
static void normal_errors(tsr_hw_backend *b, const tsr_heightfield *hf, bool one_sided, double tol, double *worst,
                          uint32_t *over, uint32_t *levels_drawn)
{
    fly_options o = {.tile_n = 8, .pixel_error = 1, .fog_distance = -1, .show_normals = true,
                     .one_sided_normals = one_sided};
    fly_ctx f;
    tsr_error err = {0};
    CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
    view v = {{1280, 300, 350}, {1280, 1600, 50}};
    uint8_t *emap = calloc(W * H, 4);
    float *depth = malloc(W * H * sizeof *depth);
    fly_frame_stats fs;
    uint8_t *rgba = render(&f, &v, &fs, depth);
    tsr_camera cam;
    fly_camera(&f, v.eye, v.target, &cam);
    uint32_t lv = 0, top = f.levels;
    const tsr_qleaf *L = tsr_quadtree_leaves(f.qt);
    for (uint32_t i = 0; i < tsr_quadtree_leaf_count(f.qt); i++)
        if (!L[i].culled) {
            lv |= 1u << L[i].node.level;
            top = L[i].node.level < top ? L[i].node.level : top;
        }
    /* the terrain's own border has no neighbour: its normals stay
     * one-sided, which reaches one cell of the coarsest tile inwards */
    double margin = f.dx * (1u << (f.levels - top));
    *levels_drawn = (uint32_t)__builtin_popcount(lv);
    *worst = 0;
    *over = 0;
    uint32_t hits = 0;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double p[3];
            if (!pixel_point(&cam, depth, x, y, p))
                continue;
            if (fmin(p[0], p[1]) < margin || fmax(p[0], p[1]) > 2560 - margin)
                continue;
            hits++;
            double g[2], n[3], m[3], len = 0, mlen = 0, e = 0;
            bowl_gradient(p[0], p[1], g);
            n[0] = -g[0], n[1] = -g[1], n[2] = 1;
            for (int k = 0; k < 3; k++) {
                m[k] = rgba[4 * (y * W + x) + k] / 255.0 * 2 - 1;
                len += n[k] * n[k];
                mlen += m[k] * m[k];
            }
            for (int k = 0; k < 3; k++)
                e = fmax(e, fabs(n[k] / sqrt(len) - m[k] / sqrt(mlen)));
            *worst = fmax(*worst, e);
            *over += e > tol;
            emap[4 * (y * W + x)] = (uint8_t)fmin(255, e / 0.03 * 255);
            emap[4 * (y * W + x) + 3] = 255;
        }
    if (getenv("TSR_SAVE_NORMALS")) {
        char path[256];
        snprintf(path, sizeof path, "%s_%d.png", getenv("TSR_SAVE_NORMALS"), one_sided);
        tsr_image_save_u8(path, W, H, 4, rgba, &err);
        snprintf(path, sizeof path, "%s_%d_err.png", getenv("TSR_SAVE_NORMALS"), one_sided);
        tsr_image_save_u8(path, W, H, 4, emap, &err);
    }
    free(emap);
    CHECK(hits > W * H / 3);
    CHECK_MSG(b->stats.validation_messages == 0, "%llu validation messages",
              (unsigned long long)b->stats.validation_messages);
    free(rgba);
    free(depth);
    fly_free(&f);
}

TEST(normals_continuous_across_tiles)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = make_bowl();
    double tol = 0.008, worst, worst1;
    uint32_t over, over1, levels, levels1;
    normal_errors(b, hf, false, tol, &worst, &over, &levels);
    normal_errors(b, hf, true, tol, &worst1, &over1, &levels1);
    fprintf(stderr, "normals: %u levels drawn; worst component error %.4f (%u pixels over %.3f); one-sided "
            "borders: %.4f (%u pixels over)\n", levels, worst, over, tol, worst1, over1);
    CHECK(levels >= 3 && levels1 == levels);
    CHECK_MSG(over == 0, "%u pixels' normals off by more than %.3f (worst %.4f)", over, tol, worst);
    CHECK_MSG(over1 > 100, "one-sided border normals: only %u pixels over %.3f: the check cannot see seams", over1,
              tol);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

/* The rule of hw.h for the normals, checked on the GPU's image against
 * an oracle built from geometry alone (not from the neighbour numbers):
 * the step at a vertex is the largest spacing of the drawn tiles whose
 * rectangles hold it, the far samples are the heightfield's where they
 * are vertices of a drawn tile (else the difference is one-sided), inside
 * a morphing tile the normal is blended towards the parent's as the
 * heights are, and a pixel's normal is the triangle's three vertex normals
 * blended by its barycentric coordinates. A wavy terrain of integer heights (stored
 * exactly), so that steps of s and 2 s give clearly different normals: a
 * tile taking another step than its neighbour at a shared vertex, the
 * corner across the diagonal included, shows as pixels off. The view is
 * one with pixels where a shader leaving the diagonal out would be off by
 * more than the tolerance plus colour rounding (checked, not assumed).
 * Tiles next to culled ones are left out: the oracle does not follow what
 * the shader can see there (at the screen's edge, where it cannot show). */
#define WN 257
static float wavy_height(int i, int j)
{
    double x = i * 10.0, y = j * 10.0;
    return (float)floor(60 * sin(x / 60) * cos(y / 50) + 200 * sin((x + y) / 400) + 500 + 0.5);
}

typedef struct rule_ctx {
    const tsr_hw_tile *tiles;
    uint32_t count, n;
    uint8_t *step;    /* per sample: the largest step (in samples) of a drawn tile holding it */
    uint8_t *covered; /* per sample: some drawn tile holds it */
    uint8_t *lattice; /* per sample: it is a vertex of a drawn tile holding it (the shader can read it) */
} rule_ctx;

static int tile_step(const tsr_hw_tile *t) { return (int)lround(t->spacing[0] / 10); }

/* The shader's slopes at sample (X, Y) with step S (in samples): central,
 * else one-sided, else 0. */
static void rule_slopes(const rule_ctx *c, int X, int Y, int S, double g[2])
{
    for (int a = 0; a < 2; a++) {
        int dx = a == 0, dy = a == 1, ax = X - S * dx, ay = Y - S * dy, bx = X + S * dx, by = Y + S * dy;
        bool ha = ax >= 0 && ay >= 0 && c->lattice[ay * WN + ax];
        bool hb = bx < WN && by < WN && c->lattice[by * WN + bx];
        double h0 = wavy_height(X, Y), A = ha ? wavy_height(ax, ay) : h0, B = hb ? wavy_height(bx, by) : h0;
        int span = (ha ? S : 0) + (hb ? S : 0);
        g[a] = span ? (B - A) / (span * 10.0) : 0;
    }
}

/* The normal from slopes g: (-g, 1) normalised. */
static void slope_normal(const double g[2], double nrm[3])
{
    double len = sqrt(g[0] * g[0] + g[1] * g[1] + 1);
    nrm[0] = -g[0] / len, nrm[1] = -g[1] / len, nrm[2] = 1 / len;
}

/* The normal the shader gives vertex (i, j) of tile t: slopes at the
 * rule's step; inside a morphing tile, blended (not renormalised) towards
 * the parent's normal there, at an odd vertex the mean of the parent's
 * normals at the two even vertices whose mean its height morphs to. */
static void rule_vertex(const rule_ctx *c, const tsr_hw_tile *t, int i, int j, double nrm[3])
{
    int S = tile_step(t), n = (int)c->n, X0 = (int)lround(t->origin[0] / 10), Y0 = (int)lround(t->origin[1] / 10);
    int X = X0 + S * i, Y = Y0 + S * j;
    X = X < WN ? X : WN - 1;
    Y = Y < WN ? Y : WN - 1;
    double g[2];
    rule_slopes(c, X, Y, c->step[Y * WN + X], g);
    slope_normal(g, nrm);
    if (!(t->morph > 0) || i <= 0 || j <= 0 || i >= n || j >= n)
        return;
    int pair[2][2] = {{i, j}, {i, j}}; /* even: the vertex itself */
    if ((i & 1) && !(j & 1))
        pair[0][0] = i - 1, pair[1][0] = i + 1;
    else if (!(i & 1) && (j & 1))
        pair[0][1] = j - 1, pair[1][1] = j + 1;
    else if (i & 1) {
        int pqi = (t->parity & 1) * (n / 2) + (i - 1) / 2, pqj = (t->parity >> 1) * (n / 2) + (j - 1) / 2;
        int d = ((pqi + pqj) & 1) == 0 ? 1 : -1;
        pair[0][0] = i - d, pair[0][1] = j - 1, pair[1][0] = i + d, pair[1][1] = j + 1;
    }
    double target[3] = {0};
    for (int e = 0; e < 2; e++) {
        double g2[2], n2[3];
        rule_slopes(c, X0 + S * pair[e][0], Y0 + S * pair[e][1], 2 * S, g2);
        slope_normal(g2, n2);
        for (int a = 0; a < 3; a++)
            target[a] += 0.5 * n2[a];
    }
    for (int a = 0; a < 3; a++)
        nrm[a] += (target[a] - nrm[a]) * t->morph;
}

TEST(border_normals_follow_the_rule)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = tsr_heightfield_create(WN, WN, NULL);
    float *hv = tsr_heightfield_data(hf);
    for (int j = 0; j < WN; j++)
        for (int i = 0; i < WN; i++)
            hv[j * WN + i] = wavy_height(i, j);
    tsr_heightfield_set_spacing(hf, 10, 10, 1);
    fly_options o = {.tile_n = 8, .pixel_error = 2, .fog_distance = -1, .show_normals = true, .geomorph = true};
    fly_ctx f;
    tsr_error err = {0};
    CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
    view v = {{1280, 1280, 1400}, {1500, 1600, 400}};
    float *depth = malloc(W * H * sizeof *depth);
    fly_frame_stats fs;
    uint8_t *rgba = render(&f, &v, &fs, depth);
    tsr_camera cam;
    fly_camera(&f, v.eye, v.target, &cam);
    rule_ctx c = {f.tiles, fs.render.tiles, o.tile_n, calloc(WN * WN, 1), calloc(WN * WN, 1), calloc(WN * WN, 1)};
    uint32_t lv = 0;
    for (uint32_t k = 0; k < c.count; k++) {
        const tsr_hw_tile *t = &c.tiles[k];
        int S = tile_step(t), X0 = (int)lround(t->origin[0] / 10), Y0 = (int)lround(t->origin[1] / 10);
        lv |= 1u << t->level;
        for (int Y = Y0; Y <= Y0 + S * (int)c.n && Y < WN; Y++)
            for (int X = X0; X <= X0 + S * (int)c.n && X < WN; X++) {
                c.covered[Y * WN + X] = 1;
                c.lattice[Y * WN + X] |= (X - X0) % S == 0 && (Y - Y0) % S == 0;
                c.step[Y * WN + X] = (uint8_t)(S > c.step[Y * WN + X] ? S : c.step[Y * WN + X]);
            }
    }
    /* tiles next to culled ones (at the screen's edges) meet no neighbour
     * there, nor through it the tile across a corner: the rule holds
     * among drawn tiles, which this oracle does not follow so far, so
     * their pixels are left out */
    uint8_t *whole = calloc(c.count, 1);
    uint32_t nwhole = 0;
    for (uint32_t k = 0; k < c.count; k++) {
        const tsr_hw_tile *t = &c.tiles[k];
        int S = tile_step(t), X0 = (int)lround(t->origin[0] / 10), Y0 = (int)lround(t->origin[1] / 10);
        whole[k] = 1;
        for (int Y = Y0 - 4 * S; Y <= Y0 + S * ((int)c.n + 4); Y++)
            for (int X = X0 - 4 * S; X <= X0 + S * ((int)c.n + 4); X++)
                if (X >= 0 && Y >= 0 && X < WN && Y < WN && !c.covered[Y * WN + X])
                    whole[k] = 0;
        nwhole += whole[k];
    }
    /* corners where the tile across the diagonal is coarser than the tile
     * and both across its edges (a staircase of levels): there the step
     * comes from the diagonal alone, so the view must have pixels where a
     * shader that left the diagonal out would be off by twice the
     * tolerance (the normal's change there, blended as the pixel is) */
    enum { MAX_STAIR = 64 };
    struct {
        uint32_t k;
        int X, Y;
        double diff; /* the normal there with the step of the edges alone, against the rule's */
    } st[MAX_STAIR];
    uint32_t stair = 0;
    for (uint32_t k = 0; k < c.count; k++) {
        const tsr_hw_tile *t = &c.tiles[k];
        int S = tile_step(t);
        for (int q = 0; q < 4; q++) {
            int ci = q & 1, cj = q >> 1, sx = ci ? 1 : -1, sy = cj ? 1 : -1;
            double vx = t->origin[0] + ci * t->spacing[0] * c.n, vy = t->origin[1] + cj * t->spacing[1] * c.n;
            int across[3] = {0, 0, 0}; /* steps of the tiles across: the x edge, the y edge, the diagonal */
            const double off[3][2] = {{sx, -sy}, {-sx, sy}, {sx, sy}};
            for (int a = 0; a < 3; a++)
                for (uint32_t u = 0; u < c.count; u++) {
                    const tsr_hw_tile *o2 = &c.tiles[u];
                    double px = vx + off[a][0], py = vy + off[a][1], side = o2->spacing[0] * c.n;
                    if (px > o2->origin[0] && py > o2->origin[1] && px < o2->origin[0] + side &&
                        py < o2->origin[1] + side)
                        across[a] = tile_step(o2);
                }
            int X = (int)lround(vx / 10), Y = (int)lround(vy / 10), edges = S;
            edges = across[0] > edges ? across[0] : edges;
            edges = across[1] > edges ? across[1] : edges;
            if (!whole[k] || across[2] <= edges || !across[0] || !across[1] || X >= WN || Y >= WN ||
                stair == MAX_STAIR)
                continue;
            double n1[3], n2[3], g[2];
            rule_slopes(&c, X, Y, c.step[Y * WN + X], g);
            slope_normal(g, n1);
            rule_slopes(&c, X, Y, edges, g);
            slope_normal(g, n2);
            st[stair].k = k, st[stair].X = X, st[stair].Y = Y, st[stair].diff = 0;
            for (int a = 0; a < 3; a++)
                st[stair].diff = fmax(st[stair].diff, fabs(n1[a] - n2[a]));
            stair++;
        }
    }
    static uint32_t pat[16][3 * 2 * 8 * 8];
    uint32_t ntri[16];
    for (unsigned m = 0; m < 16; m++)
        ntri[m] = tsr_tile_pattern(c.n, m, pat[m]);
    uint32_t checked = 0, over = 0, sensitive = 0;
    double worst = 0, tol = 0.008;
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            double p[3];
            if (!pixel_point(&cam, depth, x, y, p))
                continue;
            /* the drawn tile and the triangle of its pattern under the point:
             * the one it is deepest inside */
            double best = -INFINITY, want[3] = {0}, near_stair = 0;
            uint32_t under = UINT32_MAX;
            for (uint32_t k = 0; k < c.count; k++) {
                const tsr_hw_tile *t = &c.tiles[k];
                double lu = (p[0] - t->origin[0]) / t->spacing[0], lw = (p[1] - t->origin[1]) / t->spacing[1];
                if (lu < -0.05 || lw < -0.05 || lu > c.n + 0.05 || lw > c.n + 0.05)
                    continue;
                const uint32_t *tri = pat[t->stitch & 15];
                for (uint32_t q = 0; q < ntri[t->stitch & 15]; q++) {
                    double vx[3], vy[3], bc[3];
                    for (int e = 0; e < 3; e++) {
                        vx[e] = tri[3 * q + e] % (c.n + 1);
                        vy[e] = tri[3 * q + e] / (c.n + 1);
                    }
                    double den = (vy[1] - vy[2]) * (vx[0] - vx[2]) + (vx[2] - vx[1]) * (vy[0] - vy[2]);
                    bc[0] = ((vy[1] - vy[2]) * (lu - vx[2]) + (vx[2] - vx[1]) * (lw - vy[2])) / den;
                    bc[1] = ((vy[2] - vy[0]) * (lu - vx[2]) + (vx[0] - vx[2]) * (lw - vy[2])) / den;
                    bc[2] = 1 - bc[0] - bc[1];
                    double inside = fmin(bc[0], fmin(bc[1], bc[2]));
                    if (inside <= best)
                        continue;
                    best = inside;
                    under = k;
                    double sum[3] = {0};
                    near_stair = 0;
                    for (int e = 0; e < 3; e++) {
                        int S = tile_step(t), X = (int)lround(t->origin[0] / 10) + S * (int)vx[e],
                            Y = (int)lround(t->origin[1] / 10) + S * (int)vy[e];
                        for (uint32_t z = 0; z < stair; z++)
                            if (st[z].k == k && st[z].X == X && st[z].Y == Y)
                                near_stair += bc[e] * st[z].diff;
                        double nv[3];
                        rule_vertex(&c, t, (int)vx[e], (int)vy[e], nv);
                        for (int a = 0; a < 3; a++)
                            sum[a] += bc[e] * nv[a];
                    }
                    double len = sqrt(sum[0] * sum[0] + sum[1] * sum[1] + sum[2] * sum[2]);
                    for (int a = 0; a < 3; a++)
                        want[a] = sum[a] / len;
                }
            }
            if (best < -0.01 || !whole[under])
                continue; /* under no drawn triangle (rounding at the silhouette), or next to culled tiles */
            double e = 0;
            for (int a = 0; a < 3; a++)
                e = fmax(e, fabs(rgba[4 * (y * W + x) + a] / 255.0 * 2 - 1 - want[a]));
            checked++;
            sensitive += near_stair > tol + 0.004; /* beyond colour rounding */
            worst = fmax(worst, e);
            over += e > tol;
            if (e > tol)
                fprintf(stderr, "  pixel %d %d at (%.1f, %.1f, %.1f): off by %.4f (inside %.3f)\n", x, y, p[0], p[1],
                        p[2], e, best);
        }
    fprintf(stderr,
            "rule: %u levels, %u of %u tiles away from culled ones, %u staircase corners (%u pixels where leaving "
            "the diagonal out shows), %u pixels checked, worst component error %.4f, %u over %.3f\n",
            (unsigned)__builtin_popcount(lv), nwhole, c.count, stair, sensitive, checked, worst, over, tol);
    CHECK(__builtin_popcount(lv) >= 2 && sensitive >= 5);
    CHECK(checked > W * H / 3);
    CHECK_MSG(over == 0, "%u pixels' normals off the rule by more than %.3f (worst %.4f)", over, tol, worst);
    CHECK(nwhole > c.count / 2);
    CHECK(b->stats.validation_messages == 0);
    free(whole);
    free(c.step);
    free(c.covered);
    free(c.lattice);
    free(rgba);
    free(depth);
    fly_free(&f);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

static double differing(const uint8_t *a, const uint8_t *b, int tol)
{
    uint32_t n = 0;
    for (int i = 0; i < W * H; i++) {
        int d = 0;
        for (int c = 0; c < 3; c++) {
            int e = abs((int)a[4 * i + c] - (int)b[4 * i + c]);
            d = e > d ? e : d;
        }
        n += d > tol;
    }
    return (double)n / (W * H);
}

/* No pinholes where tiles meet: a pixel of sky whose four neighbours are
 * terrain and whose ray the CPU finds hitting the full-resolution surface,
 * or one of terrain much farther than its four neighbours where the CPU
 * finds the surface as near as they are, is a gap between two tiles'
 * triangles. Adjacent tiles must put their
 * shared vertices at the same float position, to the bit, or the
 * rasteriser leaves such pixels along their borders. They did not: each
 * tile decoded its own 16-bit samples, quantised with its own offset and
 * scale, and added its own rounded origin (0-7 pinholes a frame in
 * `tessera fly` on the demo terrain, 75 in 60 frames; 28 in these frames).
 * Steep terrain (wide 16-bit steps), eyes off the lattice. */
TEST(no_pinholes_between_tiles)
{
    enum { PW = 960, PH = 600 };
    dlopen("libvulkan_lvp.so", RTLD_NOW | RTLD_NODELETE);
    tsr_hw_vulkan_options vo = {.width = PW, .height = PH, .validation = -1};
    tsr_hw_backend *b = NULL;
    tsr_error err = {0};
    if (tsr_hw_vulkan_create(&vo, NULL, &b, &err) != TSR_OK)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = tsr_heightfield_create(257, 257, NULL);
    tsr_generate_options g = {.seed = 11, .relief = 900};
    tsr_terrain_generate(hf, &g);
    tsr_heightfield_set_spacing(hf, 7.3, 7.3, 1);
    /* 12 eyes around the middle of the 1.87 km square at various heights,
     * looking at points across it, off the lattice */
    view pv[12];
    for (int k = 0; k < 12; k++) {
        double a = k * 0.5236 + 0.1, r = 500 + 97.3 * (k % 5), c = 934.4;
        pv[k] = (view){{c + r * cos(a) + 0.37 * k, c + r * sin(a) - 0.61 * k, 380.7 + 53.3 * (k % 4)},
                       {c - 0.8 * r * cos(a + 0.4), c - 0.8 * r * sin(a + 0.4), 60}};
    }
    uint32_t holes = 0, terrain = 0;
    for (int morph = 0; morph <= 1; morph++) {
        fly_options o = {.tile_n = 8, .pixel_error = 1.5, .fog_distance = -1, .geomorph = morph};
        fly_ctx f;
        CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
        float *depth = malloc(PW * PH * sizeof *depth);
        for (size_t vi = 0; vi < sizeof pv / sizeof pv[0]; vi++) {
            tsr_camera cam;
            CHECK(fly_camera(&f, pv[vi].eye, pv[vi].target, &cam));
            fly_frame_stats fs;
            CHECK(fly_frame(&f, &cam, &fs, &err) == TSR_OK);
            CHECK(b->read_depth(b, depth));
            uint32_t here = 0;
            for (int y = 1; y + 1 < PH; y++)
                for (int x = 1; x + 1 < PW; x++) {
                    /* reversed depth: larger is nearer, 0 is sky */
                    float d = depth[y * PW + x], n1 = depth[y * PW + x - 1], n2 = depth[y * PW + x + 1],
                          n3 = depth[(y - 1) * PW + x], n4 = depth[(y + 1) * PW + x];
                    terrain += d > 0;
                    if (n1 <= 0 || n2 <= 0 || n3 <= 0 || n4 <= 0)
                        continue;
                    /* a hole onto the sky, or onto terrain much farther than
                     * four neighbours that agree (seen through the gap) */
                    float mn = fminf(fminf(n1, n2), fminf(n3, n4)), mx = fmaxf(fmaxf(n1, n2), fmaxf(n3, n4));
                    if (d > 0 && !(d < 0.8f * mn && mx <= 1.1f * mn))
                        continue;
                    double u = -(x + 0.5 - PW / 2.0) / cam.K, w = -(y + 0.5 - PH / 2.0) / cam.K, dir[3], t;
                    for (int k = 0; k < 3; k++)
                        dir[k] = cam.fwd[k] + u * cam.right[k] + w * cam.up[k];
                    /* the surface is there, as near as the neighbours */
                    if (tsr_terrain_pick(f.terrain, cam.eye, dir, &t) && (d <= 0 || cam.near_dist / t > 0.9 * mn)) {
                        if (here < 3)
                            fprintf(stderr, "  pinhole at (%d, %d)%s\n", x, y, d > 0 ? ", onto farther terrain" : "");
                        here++;
                    }
                }
            fprintf(stderr, "view %zu%s: %u tiles, %u pinholes\n", vi, morph ? " geomorphed" : "",
                    fs.render.tiles, here);
            holes += here;
        }
        free(depth);
        fly_free(&f);
    }
    CHECK(terrain > PW * PH * 12); /* mostly terrain over the 24 frames */
    CHECK_MSG(holes == 0, "%u pinholes between tiles", holes);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

TEST(image_moves_and_matches_reference)
{
    tsr_hw_backend *b = backend();
    if (!b)
        SKIP("no Vulkan device");
    tsr_heightfield *hf = make_terrain();
    /* fog at 4 km: light over the 2.6 km terrain, so the colours stay */
    fly_options o = {.tile_n = 16, .pixel_error = 2, .geomorph = true, .fog_distance = 4000};
    fly_ctx f;
    tsr_error err = {0};
    CHECK(fly_init(&f, hf, b, &o, &err) == TSR_OK);
    fly_frame_stats fs;
    uint8_t *a = render(&f, &views[0], &fs, NULL);
    /* the fog is drawn: without it, the far terrain is darker and less
     * blue (lavapipe once dropped the fog: the shader read its distance
     * as 0) */
    f.o.fog_distance = -1;
    uint8_t *clear = render(&f, &views[0], &fs, NULL);
    f.o.fog_distance = 4000;
    double fogged = differing(a, clear, 8);
    CHECK_MSG(fogged > 0.2, "fog on and off: only %.3f of the pixels differ", fogged);
    free(clear);
    /* not blank: many distinct colours */
    uint32_t distinct = 0;
    uint8_t *seen = calloc(1 << 15, 1);
    for (int i = 0; i < W * H; i++) {
        uint32_t key = (a[4 * i] >> 3) << 10 | (a[4 * i + 1] >> 3) << 5 | a[4 * i + 2] >> 3;
        distinct += !seen[key];
        seen[key] = 1;
    }
    free(seen);
    CHECK_MSG(distinct > 100, "%u distinct colours", distinct);
    view moved = views[0];
    moved.eye[0] += 60;
    moved.eye[1] -= 30;
    uint8_t *m = render(&f, &moved, &fs, NULL);
    CHECK_MSG(differing(a, m, 8) > 0.05, "%.3f of the pixels changed", differing(a, m, 8));

    char ref[1024];
    snprintf(ref, sizeof ref, "%s/tests/hw/reference/view0_%dx%d.png", TSR_SOURCE_DIR, W, H);
    if (getenv("TSR_UPDATE_REFERENCE")) {
        CHECK(tsr_image_save_u8(ref, W, H, 4, a, &err) == TSR_OK);
        fprintf(stderr, "wrote %s\n", ref);
    }
    float *px = NULL;
    tsr_image_info info;
    tsr_status st = tsr_image_read(ref, NULL, 1 << 24, &px, &info, &err);
    CHECK_MSG(st == TSR_OK, "%s (set TSR_UPDATE_REFERENCE=1 to write it)", err.message);
    if (st == TSR_OK) {
        CHECK(info.width == W && info.height == H && info.channels == 4);
        if (info.width == W && info.height == H && info.channels == 4) {
            uint8_t *r = malloc(W * H * 4);
            for (int i = 0; i < W * H * 4; i++)
                r[i] = (uint8_t)px[i];
            double off = differing(a, r, 6);
            CHECK_MSG(off < 0.002, "%.4f of the pixels differ from %s by more than 6/255", off, ref);
            free(r);
        }
        tsr_free(NULL, px);
    }
    CHECK(b->stats.validation_messages == 0);
    free(a);
    free(m);
    fly_free(&f);
    b->destroy(b);
    tsr_heightfield_destroy(hf);
}

TEST_MAIN(T(neighbours_match_geometry), T(vulkan_end_frame_refusals), T(depth_matches_picking), T(triangles_drawn_match_cut),
          T(normals_continuous_across_tiles), T(border_normals_follow_the_rule), T(no_pinholes_between_tiles),
          T(image_moves_and_matches_reference))
