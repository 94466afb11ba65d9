/* The tile renderer on the null backend. The oracles are independent of
 * renderer.c: samples are decoded here from the bytes the backend
 * received (a shadow copy of every upload), indices are compared with
 * tsr_tile_pattern, the view-projection matrix with tsr_camera_project,
 * and the cache's uploads and evictions with a brute-force LRU model. */
#include "check.h"
#include "hw/hw.h"

#include <stdint.h>

/* ---- random numbers and deterministic tile samples -------------------- */

static uint64_t rng = 0x2545F4914F6CDD1Dull;
static uint64_t rnd(void)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return rng;
}
static double urand(double lo, double hi) { return lo + (hi - lo) * (double)(rnd() >> 11) / 9007199254740992.0; }

static uint64_t mix(uint64_t x)
{
    x += 0x9E3779B97F4A7C15ull;
    x = (x ^ (x >> 30)) * 0xBF58476D1CE4E5B9ull;
    x = (x ^ (x >> 27)) * 0x94D049BB133111EBull;
    return x ^ (x >> 31);
}

#define FLOAT_KEY (1ull << 62) /* tiles whose samples are fractional (stored F32 when lossless) */

/* Sample (i, j) of the tile with this key: integers spanning < 65535 for
 * ordinary keys, fractional values for FLOAT_KEY ones, and some NaN. */
static float sample_of(uint64_t key, uint32_t i, uint32_t j)
{
    uint64_t h = mix(mix(key) ^ ((uint64_t)i << 32 | j));
    if (h % 23 == 0)
        return NAN;
    if (key & FLOAT_KEY)
        return (float)((double)(h >> 11) / 9007199254740992.0 * 2000 - 1000);
    return (float)((int64_t)(h % 40000) - 20000 + (int64_t)(key % 7) * 1000);
}

static uint32_t g_n; /* tile_n of the renderer under test */
static uint32_t tile_samples(void) { return (g_n + 1) * (g_n + 1); }
static uint32_t u16_bytes(void) { return (tile_samples() + 1) / 2 * 4; } /* two samples per 32-bit word */
static uint32_t f32_bytes(void) { return tile_samples() * 4; }
/* What a U16 tile uploads and occupies: its samples, without padding */
static uint32_t u16_upload_bytes(void) { return tile_samples() * 2; }

typedef struct fetcher {
    uint64_t fail_key;
    uint32_t calls;
} fetcher;

static bool fetch(void *user, const tsr_hw_tile *t, float *s)
{
    fetcher *f = user;
    f->calls++;
    if (f->fail_key && t->key == f->fail_key)
        return false;
    for (uint32_t j = 0; j <= g_n; j++)
        for (uint32_t i = 0; i <= g_n; i++)
            s[j * (g_n + 1) + i] = sample_of(t->key, i, j);
    return true;
}

/* A tile with a key, somewhere near (bx, by), random stitch and morph. */
static tsr_hw_tile make_tile(uint64_t key, double bx, double by)
{
    tsr_hw_tile t;
    memset(&t, 0, sizeof t);
    t.key = key;
    uint64_t h = mix(key);
    t.level = (uint8_t)(h % 12);
    double w = 4096.0 / (1u << t.level);
    t.origin[0] = bx + (double)(h >> 8 & 255) * w + 0.3;
    t.origin[1] = by + (double)(h >> 16 & 255) * w - 0.7;
    t.spacing[0] = t.spacing[1] = w / g_n;
    t.z_scale = 0.5;
    t.stitch = (uint8_t)(h >> 24 & 15);
    t.parity = (uint8_t)(h >> 28 & 3);
    t.morph = (float)((h >> 32 & 255) / 255.0);
    return t;
}

/* ---- a recording wrapper around the null backend ----------------------- */

#define MAX_BUF 16
#define MAX_DRAWS 4096
static struct {
    tsr_hw_backend orig; /* the null backend's own table */
    unsigned char *mem[MAX_BUF + 1];
    uint64_t size[MAX_BUF + 1];
    tsr_hw_tile_draw draws[MAX_DRAWS];
    uint32_t ndraws;
} R;

static tsr_hw_buffer rec_create(tsr_hw_backend *self, tsr_hw_buffer_kind kind, uint64_t size)
{
    tsr_hw_buffer id = R.orig.create_buffer(self, kind, size);
    if (id && id <= MAX_BUF) {
        R.mem[id] = calloc(size, 1);
        R.size[id] = size;
    }
    return id;
}

static bool rec_upload(tsr_hw_backend *self, tsr_hw_buffer id, uint64_t offset, const void *data, uint64_t size)
{
    bool ok = R.orig.upload(self, id, offset, data, size);
    if (ok && id <= MAX_BUF && R.mem[id])
        memcpy(R.mem[id] + offset, data, size);
    return ok;
}

static void rec_destroy_buffer(tsr_hw_backend *self, tsr_hw_buffer id)
{
    if (id && id <= MAX_BUF) {
        free(R.mem[id]);
        R.mem[id] = NULL;
    }
    R.orig.destroy_buffer(self, id);
}

static bool rec_begin(tsr_hw_backend *self, const tsr_hw_frame *f)
{
    R.ndraws = 0;
    return R.orig.begin_frame(self, f);
}

static bool rec_draw(tsr_hw_backend *self, const tsr_hw_tile_draw *d)
{
    bool ok = R.orig.draw_tile(self, d);
    if (ok && R.ndraws < MAX_DRAWS)
        R.draws[R.ndraws++] = *d;
    return ok;
}

static tsr_hw_backend *make_backend(void)
{
    tsr_hw_backend *b = tsr_hw_null_create(800, 600, NULL);
    memset(&R, 0, sizeof R);
    R.orig = *b;
    b->create_buffer = rec_create;
    b->upload = rec_upload;
    b->destroy_buffer = rec_destroy_buffer;
    b->begin_frame = rec_begin;
    b->draw_tile = rec_draw;
    return b;
}

static tsr_hw_renderer *make_renderer(tsr_hw_backend *b, uint32_t n, uint64_t cache_bytes, double max_q)
{
    g_n = n;
    tsr_hw_renderer_options o = {0};
    o.tile_n = n;
    o.cache_bytes = cache_bytes;
    o.max_quantization = max_q;
    tsr_hw_renderer *r = NULL;
    tsr_error err = {0};
    tsr_status st = tsr_hw_renderer_create(b, &o, NULL, &r, &err);
    CHECK_MSG(st == TSR_OK && r, "%s", err.message);
    return r;
}

static tsr_hw_frame make_frame(double ex, double ey, double ez)
{
    tsr_hw_frame f;
    memset(&f, 0, sizeof f);
    f.eye[0] = ex;
    f.eye[1] = ey;
    f.eye[2] = ez;
    return f;
}

static uint64_t pattern_triangles(const tsr_hw_tile *tiles, uint32_t count)
{
    uint64_t t = 0;
    for (uint32_t k = 0; k < count; k++)
        t += tsr_tile_pattern(g_n, tiles[k].stitch, NULL);
    return t;
}

/* Reads stored sample v of a draw from the shadow pool: NaN for no-data. */
static double stored_sample(const tsr_hw_tile_draw *d, uint32_t v)
{
    const unsigned char *p = R.mem[d->samples] + d->samples_offset;
    if (d->format == TSR_HW_HEIGHT_F32) {
        float f;
        memcpy(&f, p + 4 * (size_t)v, 4);
        return f;
    }
    /* little-endian 16-bit samples, sample 0 first_sample halves in */
    uint16_t code;
    memcpy(&code, p + 2 * ((size_t)d->first_sample + v), 2);
    return code == 0xFFFF ? NAN : (double)code;
}

/* Every draw of the last frame against the tiles it was asked for: one
 * draw per tile in order, eye-relative origins computed in double, the
 * tile's stitch pattern in the index buffer, every sample's world height
 * (within max_q world units times z_scale for quantised tiles), and no two
 * tiles' samples overlapping in the pool. */
static void check_draws(const tsr_hw_tile *tiles, uint32_t count, const tsr_hw_frame *f, double max_q)
{
    CHECK(R.ndraws == count);
    static uint32_t pat[3 * 2 * TSR_TILE_MAX * TSR_TILE_MAX];
    for (uint32_t k = 0; k < count && k < R.ndraws; k++) {
        const tsr_hw_tile_draw *d = &R.draws[k];
        const tsr_hw_tile *t = &tiles[k];
        CHECK(d->n == g_n);
        for (int a = 0; a < 2; a++) {
            double want = t->origin[a] - f->eye[a];
            CHECK_NEAR(d->origin[a], want, 1e-6 * fabs(want) + 1e-12);
            CHECK(d->spacing[a] == (float)t->spacing[a]);
        }
        CHECK(d->morph == t->morph && d->level == t->level && d->parity == t->parity);
        CHECK(memcmp(d->neighbour, t->neighbour, sizeof d->neighbour) == 0); /* draw k is tile k */
        uint32_t tri = tsr_tile_pattern(g_n, t->stitch, pat);
        CHECK(d->index_count == 3 * tri);
        CHECK(R.mem[d->indices] && ((uint64_t)d->first_index + d->index_count) * 4 <= R.size[d->indices]);
        if (d->index_count == 3 * tri && R.mem[d->indices])
            CHECK_MSG(memcmp(R.mem[d->indices] + 4 * (size_t)d->first_index, pat, 12 * (size_t)tri) == 0,
                      "tile %u stitch %u", k, t->stitch);
        bool float_tile = (t->key & FLOAT_KEY) != 0;
        if (max_q == 0)
            CHECK(d->format == (float_tile ? TSR_HW_HEIGHT_F32 : TSR_HW_HEIGHT_U16));
        uint64_t bytes = tsr_hw_draw_sample_bytes(d->format, d->n, d->first_sample);
        CHECK(bytes && d->samples_offset % 4 == 0 && R.mem[d->samples] &&
              d->samples_offset + bytes <= R.size[d->samples]);
        if (!bytes || !R.mem[d->samples] || d->samples_offset + bytes > R.size[d->samples])
            continue;
        uint32_t bad = 0;
        for (uint32_t j = 0; j <= g_n; j++)
            for (uint32_t i = 0; i <= g_n; i++) {
                double want = sample_of(t->key, i, j), s = stored_sample(d, j * (g_n + 1) + i);
                if (isnan(want) || isnan(s)) {
                    bad += isnan(want) != isnan(s);
                    continue;
                }
                double z = f->eye[2] + (double)d->z_base + (double)d->z_step * s;
                double tol = 1e-6 * (fabs(f->eye[2]) + fabs(d->z_base) + fabs(d->z_step * s)) + t->z_scale * max_q;
                bad += fabs(z - t->z_scale * want) > tol;
            }
        CHECK_MSG(bad == 0, "tile %u key %#llx: %u samples wrong", k, (unsigned long long)t->key, bad);
        for (uint32_t k2 = 0; k2 < k; k2++) {
            const tsr_hw_tile_draw *e = &R.draws[k2];
            if (tiles[k2].key == t->key) {
                CHECK(e->samples_offset == d->samples_offset);
                continue;
            }
            /* the bytes each tile's samples occupy */
            uint64_t e0 = e->samples_offset + 2 * e->first_sample, d0 = d->samples_offset + 2 * d->first_sample;
            uint64_t eb = e->format == TSR_HW_HEIGHT_U16 ? u16_upload_bytes() : f32_bytes();
            uint64_t db = d->format == TSR_HW_HEIGHT_U16 ? u16_upload_bytes() : f32_bytes();
            CHECK_MSG(e0 + eb <= d0 || d0 + db <= e0, "tiles %u and %u overlap in the pool", k2, k);
        }
    }
}

static tsr_status run_frame(tsr_hw_renderer *r, const tsr_hw_frame *f, const tsr_hw_tile *tiles, uint32_t count,
                            fetcher *fe, tsr_hw_render_stats *st, tsr_error *err)
{
    fe->calls = 0;
    return tsr_hw_renderer_frame(r, f, tiles, count, fetch, fe, st, err);
}

/* ---- encoding --------------------------------------------------------- */

static double decode(const void *buf, tsr_hw_encoding enc, uint32_t k)
{
    const unsigned char *p = buf;
    if (enc.format == TSR_HW_HEIGHT_F32) {
        float f;
        memcpy(&f, p + 4 * (size_t)k, 4);
        return f;
    }
    uint32_t w;
    memcpy(&w, p + 4 * (size_t)(k / 2), 4);
    uint32_t code = (w >> (16 * (k & 1))) & 0xFFFF;
    return code == 0xFFFF ? NAN : enc.offset + enc.scale * code;
}

static uint32_t code_at(const void *buf, uint32_t k)
{
    uint32_t w;
    memcpy(&w, (const unsigned char *)buf + 4 * (size_t)(k / 2), 4);
    return (w >> (16 * (k & 1))) & 0xFFFF;
}

TEST(encode_integer_tiles_lossless)
{
    static float s[129 * 129];
    static unsigned char buf[4 * 129 * 129 + 4];
    const uint32_t counts[] = {9, 16, 25, 289, 290, 4225, 129 * 129};
    const double bases[] = {0, -1000, 1e6, 12345.5, -70000};
    for (int trial = 0; trial < 60; trial++) {
        uint32_t count = counts[trial % 7];
        double base = bases[trial % 5];
        uint32_t span = trial % 3 == 0 ? 65534 : (uint32_t)(rnd() % 65535);
        for (uint32_t k = 0; k < count; k++)
            s[k] = rnd() % 10 == 0 ? NAN : (float)(base + (double)(rnd() % ((uint64_t)span + 1)));
        s[0] = (float)base; /* the full span present */
        s[count - 1] = (float)(base + span);
        CHECK(tsr_hw_encode_bound(count) >= 4 * ((count + 1) / 2));
        memset(buf, 0xAB, sizeof buf);
        tsr_hw_encoding e = tsr_hw_encode_samples(s, count, 0, buf);
        CHECK_MSG(e.format == TSR_HW_HEIGHT_U16, "count %u span %u", count, span);
        CHECK(e.bytes == 4 * ((count + 1) / 2) && e.bytes <= tsr_hw_encode_bound(count));
        uint32_t wrong = 0;
        for (uint32_t k = 0; k < count; k++) {
            double v = decode(buf, e, k);
            wrong += isnan(s[k]) ? !(code_at(buf, k) == 0xFFFF) : !(v == (double)s[k] && code_at(buf, k) <= 65534);
        }
        CHECK_MSG(wrong == 0, "count %u: %u samples not exact", count, wrong);
        if (count & 1)
            CHECK(code_at(buf, count) == 0xFFFF); /* the padding reads as no-data */
        CHECK(buf[e.bytes] == 0xAB);              /* nothing written past bytes */
    }
}

TEST(encode_span_beyond_u16)
{
    static float s[289];
    static unsigned char buf[4 * 289];
    for (uint32_t k = 0; k < 289; k++)
        s[k] = (float)(rnd() % 65536);
    s[0] = 0;
    s[1] = 1;
    s[2] = 65535; /* 65536 distinct integers cannot all have a code */
    tsr_hw_encoding e = tsr_hw_encode_samples(s, 289, 0, buf);
    CHECK(e.format == TSR_HW_HEIGHT_F32 && e.bytes == 4 * 289);
    CHECK(memcmp(buf, s, sizeof s) == 0);
    /* allowed to lose a unit: U16, every sample within it */
    e = tsr_hw_encode_samples(s, 289, 1.0, buf);
    CHECK(e.format == TSR_HW_HEIGHT_U16 && e.bytes == 4 * 145);
    uint32_t wrong = 0;
    for (uint32_t k = 0; k < 289; k++)
        wrong += !(fabs(decode(buf, e, k) - s[k]) <= 1.0);
    CHECK(wrong == 0);
}

TEST(encode_float_tiles)
{
    static float s[4225];
    static unsigned char buf[4 * 4225];
    for (int trial = 0; trial < 20; trial++) {
        uint32_t count = trial % 2 ? 4225 : 289;
        for (uint32_t k = 0; k < count; k++)
            s[k] = rnd() % 8 == 0 ? NAN : (float)urand(-500, 500);
        s[1] = 0.1f;
        /* lossless only: F32, bit for bit, NaN kept */
        tsr_hw_encoding e = tsr_hw_encode_samples(s, count, 0, buf);
        CHECK(e.format == TSR_HW_HEIGHT_F32 && e.bytes == 4 * count);
        uint32_t wrong = 0;
        for (uint32_t k = 0; k < count; k++) {
            double v = decode(buf, e, k);
            wrong += isnan(s[k]) ? !isnan(v) : v != s[k];
        }
        CHECK(wrong == 0);
        /* a range of ~1000 in 65534 steps moves a sample by <= 0.0077 */
        const double tols[] = {0.01, 0.05, 1e9};
        for (int t = 0; t < 3; t++) {
            e = tsr_hw_encode_samples(s, count, tols[t], buf);
            CHECK(e.format == TSR_HW_HEIGHT_U16 && e.bytes == 4 * ((count + 1) / 2));
            wrong = 0;
            for (uint32_t k = 0; k < count; k++) {
                double v = decode(buf, e, k);
                wrong += isnan(s[k]) ? !isnan(v) : !(fabs(v - s[k]) <= tols[t] && fabs(v - s[k]) <= 0.0077);
            }
            CHECK_MSG(wrong == 0, "max_error %g: %u samples off", tols[t], wrong);
        }
        e = tsr_hw_encode_samples(s, count, 0.001, buf); /* finer than a code */
        CHECK(e.format == TSR_HW_HEIGHT_F32);
    }
}

TEST(encode_constant_all_nan_inf)
{
    float s[25];
    unsigned char buf[4 * 25];
    for (int k = 0; k < 25; k++)
        s[k] = 3.7f;
    s[4] = NAN;
    tsr_hw_encoding e = tsr_hw_encode_samples(s, 25, 0, buf);
    CHECK(e.format == TSR_HW_HEIGHT_U16 && e.bytes == 52);
    CHECK(decode(buf, e, 0) == (double)3.7f && decode(buf, e, 24) == (double)3.7f && isnan(decode(buf, e, 4)));

    for (int k = 0; k < 25; k++)
        s[k] = NAN;
    memset(buf, 0, sizeof buf);
    e = tsr_hw_encode_samples(s, 25, 0, buf); /* nothing to store: all codes no-data */
    CHECK(e.format == TSR_HW_HEIGHT_U16 && e.bytes == 52);
    bool all = true;
    for (int k = 0; k < 52; k++)
        all = all && buf[k] == 0xFF;
    CHECK(all);

    for (int k = 0; k < 25; k++)
        s[k] = (float)k;
    s[7] = INFINITY; /* no code for it: F32 keeps it */
    e = tsr_hw_encode_samples(s, 25, 1e9, buf);
    CHECK(e.format == TSR_HW_HEIGHT_F32 && e.bytes == 100 && isinf(decode(buf, e, 7)) && decode(buf, e, 8) == 8);
}

/* ---- view-projection ---------------------------------------------------- */

TEST(view_proj_matches_camera)
{
    int cameras = 0;
    double worst_px = 0, worst_depth = 0;
    while (cameras < 300) {
        tsr_camera c;
        memset(&c, 0, sizeof c);
        for (int a = 0; a < 3; a++) {
            c.eye[a] = urand(-1e5, 1e5);
            c.target[a] = c.eye[a] + urand(-100, 100);
        }
        c.fovy_deg = urand(10, 120);
        c.height = floor(urand(64, 1200));
        c.width = floor(c.height * urand(0.5, 2.5));
        c.near_dist = urand(0.01, 10);
        if (!tsr_camera_prepare(&c))
            continue;
        cameras++;
        float m[16];
        tsr_hw_view_proj(&c, m);
        for (int k = 0; k < 50; k++) {
            double f = c.near_dist * urand(1, 1e4), a = urand(-1.5, 1.5), b = urand(-1.5, 1.5), p[3], d[4];
            for (int q = 0; q < 3; q++) {
                p[q] = c.eye[q] + f * c.fwd[q] + a * f * c.tan_x * c.right[q] + b * f * c.tan_y * c.up[q];
                d[q] = p[q] - c.eye[q];
            }
            d[3] = 1;
            double clip[4] = {0, 0, 0, 0}; /* column-major: element (row, col) at m[col * 4 + row] */
            for (int row = 0; row < 4; row++)
                for (int col = 0; col < 4; col++)
                    clip[row] += (double)m[col * 4 + row] * d[col];
            double px = (clip[0] / clip[3] + 1) / 2 * c.width, py = (clip[1] / clip[3] + 1) / 2 * c.height;
            double sx, sy, depth;
            tsr_camera_project(&c, p, &sx, &sy, &depth);
            double epx = fmax(fabs(px - sx), fabs(py - sy));
            double edepth = fabs(clip[2] / clip[3] - c.near_dist / depth) / (c.near_dist / depth);
            worst_px = fmax(worst_px, epx);
            worst_depth = fmax(worst_depth, edepth);
        }
    }
    CHECK_MSG(worst_px <= 1e-3, "pixel error %g", worst_px);
    CHECK_MSG(worst_depth <= 1e-6, "relative depth error %g", worst_depth);

    /* the orientation spelled out: +z up is up on screen, the near plane at depth 1 */
    tsr_camera c = {
        .eye = {0, 0, 0}, .target = {0, 10, 0}, .fovy_deg = 60, .width = 100, .height = 50, .near_dist = 0.5};
    CHECK(tsr_camera_prepare(&c));
    float m[16];
    tsr_hw_view_proj(&c, m);
    double up_pt[4] = {1, 10, 1, 1}, near_pt[4] = {0, 0.5, 0, 1}, clip_up[4] = {0}, clip_near[4] = {0};
    for (int row = 0; row < 4; row++)
        for (int col = 0; col < 4; col++) {
            clip_up[row] += m[col * 4 + row] * up_pt[col];
            clip_near[row] += m[col * 4 + row] * near_pt[col];
        }
    CHECK(clip_up[0] / clip_up[3] > 0 && clip_up[1] / clip_up[3] < 0); /* right of centre, above it (y down) */
    CHECK_NEAR(clip_near[2] / clip_near[3], 1.0, 1e-6);
}

/* ---- the cache ------------------------------------------------------------ */

TEST(second_frame_uploads_nothing)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 16, 1 << 20, 0);
    enum { N = 40 };
    tsr_hw_tile tiles[N];
    for (uint32_t k = 0; k < N; k++)
        tiles[k] = make_tile(1000 + k, 5000, -3000);
    tsr_hw_frame f = make_frame(5100.25, -2900.5, 812.0);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_error err = {0};
    uint64_t tri = pattern_triangles(tiles, N), up0 = b->stats.bytes_uploaded;

    tsr_status s = run_frame(r, &f, tiles, N, &fe, &st, &err);
    CHECK_MSG(s == TSR_OK, "%s", err.message);
    CHECK(st.tiles == N && st.tiles_uploaded == N && fe.calls == N && st.tiles_evicted == 0);
    CHECK(st.bytes_uploaded == (uint64_t)N * u16_upload_bytes() && b->stats.bytes_uploaded - up0 == st.bytes_uploaded);
    CHECK(st.tiles_resident == N && st.tiles_u16 == N && st.bytes_resident == (uint64_t)N * u16_upload_bytes());
    CHECK(st.triangles == tri && st.device.triangles == tri);
    CHECK(st.upload_ms >= 0 && st.record_ms >= 0);
    check_draws(tiles, N, &f, 0);

    uint64_t up1 = b->stats.bytes_uploaded, drawn1 = b->stats.triangles_drawn;
    f.eye[0] += 17.5; /* the eye moves, the cut does not */
    s = run_frame(r, &f, tiles, N, &fe, &st, &err);
    CHECK(s == TSR_OK && st.tiles == N && st.tiles_uploaded == 0 && st.bytes_uploaded == 0 && fe.calls == 0);
    CHECK(b->stats.bytes_uploaded == up1);
    CHECK(st.triangles == tri && st.device.triangles == tri && b->stats.triangles_drawn - drawn1 == tri);
    CHECK(st.tiles_resident == N && st.tiles_evicted == 0);
    CHECK(b->stats.frames == 2 && b->stats.draws == 2 * N);
    check_draws(tiles, N, &f, 0);

    tsr_hw_renderer_flush(r); /* drops everything: the same frame uploads all again */
    s = run_frame(r, &f, tiles, N, &fe, &st, &err);
    CHECK(s == TSR_OK && st.tiles_uploaded == N && fe.calls == N && st.tiles_resident == N);
    check_draws(tiles, N, &f, 0);

    tsr_hw_renderer_destroy(r);
    CHECK(b->stats.buffers_live == 0 && b->stats.bytes_live == 0);
    b->destroy(b);
}

/* Tiles naming each other as neighbours: the draws carry the numbers as
 * they are (check_draws), resident or not. */
TEST(neighbours_pass_to_draws)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 8, 1 << 20, 0);
    enum { N = 30 };
    tsr_hw_tile tiles[N];
    for (uint32_t k = 0; k < N; k++) {
        tiles[k] = make_tile(700 + k, 0, 0);
        for (int e = 0; e < 8; e++) {
            uint32_t nb = (uint32_t)(rnd() % (N + 1));
            tiles[k].neighbour[e] = nb == k + 1 ? 0 : nb;
        }
    }
    tsr_hw_frame f = make_frame(10, 20, 30);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_error err = {0};
    for (int pass = 0; pass < 2; pass++) {
        tsr_status s = run_frame(r, &f, tiles, N, &fe, &st, &err);
        CHECK_MSG(s == TSR_OK, "%s", err.message);
        CHECK(st.tiles_uploaded == (pass ? 0u : (uint32_t)N));
        check_draws(tiles, N, &f, 0);
        for (uint32_t k = 0; k < N; k++) /* the cut keeps its tiles, the neighbours change */
            tiles[k].neighbour[k % 8] = (k + 1) % N + 1;
    }
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(moving_cut_uploads_one_tile)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 16, 1 << 20, 0);
    enum { N = 24 };
    tsr_hw_tile tiles[N];
    for (uint32_t k = 0; k < N; k++)
        tiles[k] = make_tile(k + 1, 0, 0);
    tsr_hw_frame f = make_frame(100, 200, 300);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    CHECK(run_frame(r, &f, tiles, N, &fe, &st, NULL) == TSR_OK && st.tiles_uploaded == N);
    for (int step = 0; step < 10; step++) {
        uint32_t k = (uint32_t)(rnd() % N);
        tiles[k] = make_tile(500 + step, 0, 0); /* one tile of the cut replaced */
        CHECK(run_frame(r, &f, tiles, N, &fe, &st, NULL) == TSR_OK);
        CHECK(st.tiles_uploaded == 1 && fe.calls == 1 && st.bytes_uploaded == u16_upload_bytes());
        CHECK(st.triangles == pattern_triangles(tiles, N));
        check_draws(tiles, N, &f, 0);
    }
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(lru_evicts_least_recently_drawn)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 4, 3 * 50 + 49, 0); /* three U16 tiles of 4x4 (25 samples, 50 bytes) */
    tsr_hw_tile a = make_tile(11, 0, 0), bb = make_tile(12, 0, 0), c = make_tile(13, 0, 0), d = make_tile(14, 0, 0);
    tsr_hw_frame f = make_frame(0, 0, 0);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    struct {
        tsr_hw_tile t[3];
        uint32_t n, uploads, evicted;
    } seq[] = {
        {{a, bb, c}, 3, 3, 0}, {{a, bb}, 2, 0, 0}, {{a, d}, 2, 1, 1}, /* evicts c, drawn longest ago */
        {{bb}, 1, 0, 0},                                              /* b stayed */
        {{c}, 1, 1, 1}, /* evicts a: a and d were drawn in one frame, a first */
        {{d}, 1, 0, 0},        {{bb}, 1, 0, 0},    {{a}, 1, 1, 1},
    };
    for (size_t k = 0; k < sizeof seq / sizeof seq[0]; k++) {
        CHECK(run_frame(r, &f, seq[k].t, seq[k].n, &fe, &st, NULL) == TSR_OK);
        CHECK_MSG(st.tiles_uploaded == seq[k].uploads && st.tiles_evicted == seq[k].evicted &&
                      fe.calls == seq[k].uploads,
                  "frame %zu: %u uploads, %u evicted", k, st.tiles_uploaded, st.tiles_evicted);
        check_draws(seq[k].t, seq[k].n, &f, 0);
    }
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

/* Random frames of U16 tiles against a brute-force LRU model: uploads,
 * evictions and resident counts agree frame by frame. */
static void lru_model_run(uint32_t keys, uint32_t budget, uint32_t max_frame, int frames)
{
    uint64_t salt = rnd();
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 2, (uint64_t)budget * 18 + 17, 0); /* 9 samples: 18 bytes a tile */
    tsr_hw_frame f = make_frame(3, 4, 5);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    bool *resident = calloc(keys, sizeof *resident), *current = calloc(keys, sizeof *current);
    uint64_t *last = calloc(keys, sizeof *last), clock = 0;
    tsr_hw_tile *tiles = calloc(max_frame, sizeof *tiles);
    uint32_t *key_of = calloc(max_frame, sizeof *key_of), count = 0;
    int wrong = 0;
    for (int frame = 0; frame < frames && wrong < 5; frame++) {
        uint32_t n = 1 + (uint32_t)(rnd() % max_frame);
        memset(current, 0, keys * sizeof *current);
        for (uint32_t k = 0; k < n; k++) {
            key_of[k] = (uint32_t)(rnd() % keys); /* repeats allowed */
            tiles[k] = make_tile(mix(salt + key_of[k]) & ~FLOAT_KEY, 0, 0); /* random homes in the table */
            current[key_of[k]] = true;
            last[key_of[k]] = ++clock;
        }
        uint32_t want_up = 0, want_ev = 0;
        for (uint32_t k = 0; k < n; k++) {
            if (resident[key_of[k]])
                continue;
            if (count == budget) {
                uint32_t victim = UINT32_MAX;
                for (uint32_t q = 0; q < keys; q++)
                    if (resident[q] && !current[q] && (victim == UINT32_MAX || last[q] < last[victim]))
                        victim = q;
                CHECK(victim != UINT32_MAX);
                if (victim == UINT32_MAX)
                    break;
                resident[victim] = false;
                count--;
                want_ev++;
            }
            resident[key_of[k]] = true;
            count++;
            want_up++;
        }
        tsr_status s = run_frame(r, &f, tiles, n, &fe, &st, NULL);
        bool ok = s == TSR_OK && st.tiles_uploaded == want_up && st.tiles_evicted == want_ev &&
                  st.tiles_resident == count && fe.calls == want_up;
        CHECK_MSG(ok, "frame %d: %u/%u uploads, %u/%u evicted", frame, st.tiles_uploaded, want_up, st.tiles_evicted,
                  want_ev);
        wrong += !ok;
        check_draws(tiles, n, &f, 0);
    }
    free(resident);
    free(current);
    free(last);
    free(tiles);
    free(key_of);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(lru_matches_model) { lru_model_run(10, 6, 6, 400); }

/* Thousands of resident tiles: the key table grows and deletes under churn. */
TEST(lru_matches_model_many_tiles)
{
    lru_model_run(4000, 1500, 1200, 25);
    lru_model_run(600, 300, 200, 2000); /* a table of 1024 up to half full, long churn: clusters wrap its end */
}

TEST(frame_over_budget_fails_too_large)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 4, 3 * 50, 0);
    tsr_hw_tile t[4] = {make_tile(1, 0, 0), make_tile(2, 0, 0), make_tile(3, 0, 0), make_tile(4, 0, 0)};
    tsr_hw_frame f = make_frame(0, 0, 0);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_error err = {0};
    CHECK(run_frame(r, &f, t, 4, &fe, &st, &err) == TSR_ERR_TOO_LARGE && err.status == TSR_ERR_TOO_LARGE);
    CHECK_MSG(strstr(err.message, "4 tiles") && strstr(err.message, "3"), "%s", err.message);
    CHECK(fe.calls == 0 && st.tiles == 0); /* known before fetching anything */
    /* the backend is not left inside a frame, and three tiles fit */
    CHECK(run_frame(r, &f, t, 3, &fe, &st, &err) == TSR_OK && st.tiles_uploaded == 3);
    check_draws(t, 3, &f, 0);
    /* one tile repeated is one tile */
    tsr_hw_tile rep[5] = {t[3], t[3], t[0], t[3], t[0]};
    CHECK(run_frame(r, &f, rep, 5, &fe, &st, &err) == TSR_OK && st.tiles_uploaded == 1 && st.tiles == 5);
    check_draws(rep, 5, &f, 0);

    /* F32 tiles take two slots: known only after fetching */
    tsr_hw_tile x[2] = {make_tile(FLOAT_KEY | 1, 0, 0), make_tile(FLOAT_KEY | 2, 0, 0)};
    memset(&err, 0, sizeof err);
    CHECK(run_frame(r, &f, x, 2, &fe, &st, &err) == TSR_ERR_TOO_LARGE);
    CHECK_MSG(strstr(err.message, "2 tiles need at least 4"), "%s", err.message);
    /* a U16 tile and an F32 tile fit three slots (the odd slot pairs with nothing) */
    tsr_hw_tile mixed[2] = {t[1], x[1]};
    CHECK_MSG(run_frame(r, &f, mixed, 2, &fe, &st, &err) == TSR_OK, "%s", err.message);
    check_draws(mixed, 2, &f, 0);
    CHECK(st.tiles_resident <= 2 && st.bytes_resident <= 3 * 52);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

/* Two U16 tiles in two half-filled slot pairs and an F32 tile that needs
 * a whole pair: one U16 tile moves, nothing fails. */
TEST(f32_tile_defragments_pool)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 4, 4 * 50, 0);
    tsr_hw_tile a = make_tile(1, 0, 0), bb = make_tile(2, 0, 0), c = make_tile(3, 0, 0),
                x = make_tile(FLOAT_KEY | 9, 0, 0);
    tsr_hw_frame f = make_frame(0, 0, 0);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_error err = {0};
    tsr_hw_tile f1[3] = {a, bb, c}, f2[3] = {a, c, x};
    CHECK(run_frame(r, &f, f1, 3, &fe, &st, &err) == TSR_OK);
    CHECK_MSG(run_frame(r, &f, f2, 3, &fe, &st, &err) == TSR_OK, "%s", err.message);
    CHECK(st.tiles_uploaded == 1 && st.tiles_evicted == 1 && st.bytes_uploaded >= f32_bytes());
    check_draws(f2, 3, &f, 0);
    CHECK(run_frame(r, &f, f2, 3, &fe, &st, &err) == TSR_OK && st.bytes_uploaded == 0 && fe.calls == 0);
    check_draws(f2, 3, &f, 0);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

/* Random frames of U16 and F32 tiles on an odd number of slots: a frame
 * fails exactly when its distinct tiles need more slots than there are,
 * and every frame that succeeds draws the right samples. */
TEST(mixed_formats_random_frames)
{
    tsr_hw_backend *b = make_backend();
    enum { SLOTS = 7 };
    tsr_hw_renderer *r = make_renderer(b, 2, SLOTS * 18, 0);
    tsr_hw_frame f = make_frame(-1e4, 2e4, 10);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    int failures = 0;
    for (int frame = 0; frame < 500; frame++) {
        tsr_hw_tile tiles[5];
        uint32_t n = 1 + (uint32_t)(rnd() % 5), need = 0;
        for (uint32_t k = 0; k < n; k++) {
            uint64_t key = 1 + rnd() % 12;
            key |= key % 2 ? FLOAT_KEY : 0;
            tiles[k] = make_tile(key, 0, 0);
            bool seen = false;
            for (uint32_t q = 0; q < k; q++)
                seen = seen || tiles[q].key == key;
            need += seen ? 0 : key & FLOAT_KEY ? 2 : 1;
        }
        tsr_error err = {0};
        tsr_status s = run_frame(r, &f, tiles, n, &fe, &st, &err);
        CHECK_MSG((s == TSR_OK) == (need <= SLOTS), "frame %d needs %u slots: %s", frame, need, err.message);
        CHECK(s == TSR_OK || s == TSR_ERR_TOO_LARGE);
        failures += s != TSR_OK;
        if (s == TSR_OK)
            check_draws(tiles, n, &f, 0);
    }
    CHECK(failures > 0); /* both outcomes exercised */
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(eye_relative_origins_far_from_the_origin)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 8, 1 << 20, 0);
    /* float(1e7 + 0.3) - float(1e7) would be 0 or 1: only double keeps 0.3 */
    tsr_hw_frame f = make_frame(1e7, -3e6 + 0.125, 1234.5);
    tsr_hw_tile t[3] = {make_tile(1, 0, 0), make_tile(2, 0, 0), make_tile(FLOAT_KEY | 3, 0, 0)};
    for (int k = 0; k < 3; k++) {
        t[k].origin[0] = 1e7 + 0.3 + k;
        t[k].origin[1] = -3e6 - 0.2 - k;
        t[k].z_scale = 0.25 + k;
    }
    fetcher fe = {0};
    tsr_hw_render_stats st;
    CHECK(run_frame(r, &f, t, 3, &fe, &st, NULL) == TSR_OK);
    check_draws(t, 3, &f, 0);
    CHECK(R.ndraws == 3 && fabs(R.draws[0].origin[0] - 0.3) < 1e-6 && fabs(R.draws[0].origin[1] + 0.325) < 1e-6);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(upload_bytes_are_encoded_bytes)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 16, 1 << 20, 0);
    tsr_hw_tile t[6];
    uint64_t want = 0;
    static float s[17 * 17];
    static unsigned char buf[4 * 17 * 17];
    uint32_t u16 = 0;
    fetcher probe = {0};
    for (int k = 0; k < 6; k++) {
        t[k] = make_tile((uint64_t)k | (k % 3 == 0 ? FLOAT_KEY : 0), 0, 0);
        fetch(&probe, &t[k], s);
        tsr_hw_encoding e = tsr_hw_encode_samples(s, 17 * 17, 0, buf);
        want += e.format == TSR_HW_HEIGHT_U16 ? u16_upload_bytes() : e.bytes;
        u16 += e.format == TSR_HW_HEIGHT_U16;
        CHECK(e.bytes == (e.format == TSR_HW_HEIGHT_U16 ? u16_bytes() : f32_bytes()));
    }
    CHECK(u16 == 4);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_hw_frame f = make_frame(0, 0, 0);
    CHECK(run_frame(r, &f, t, 6, &fe, &st, NULL) == TSR_OK);
    CHECK(st.bytes_uploaded == want && st.bytes_resident == want && st.tiles_u16 == 4 && st.tiles_resident == 6);
    check_draws(t, 6, &f, 0);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(quantised_float_tiles)
{
    tsr_hw_backend *b = make_backend();
    const double max_q = 0.02; /* a range of 2000 in 65534 codes moves a sample by <= 0.0153 */
    tsr_hw_renderer *r = make_renderer(b, 16, 1 << 20, max_q);
    tsr_hw_tile t[4] = {make_tile(FLOAT_KEY | 1, 0, 0), make_tile(FLOAT_KEY | 2, 0, 0), make_tile(3, 0, 0),
                        make_tile(FLOAT_KEY | 4, 0, 0)};
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_hw_frame f = make_frame(50, 60, 70);
    CHECK(run_frame(r, &f, t, 4, &fe, &st, NULL) == TSR_OK);
    CHECK(st.tiles_u16 == 4 && st.bytes_uploaded == 4ull * u16_upload_bytes());
    check_draws(t, 4, &f, max_q);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(fetch_failure_fails_frame)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = make_renderer(b, 8, 1 << 20, 0);
    tsr_hw_tile t[5];
    for (int k = 0; k < 5; k++)
        t[k] = make_tile(70 + (uint64_t)k, 0, 0);
    tsr_hw_frame f = make_frame(0, 0, 0);
    fetcher fe = {.fail_key = 74};
    tsr_hw_render_stats st;
    tsr_error err = {0};
    tsr_status s = run_frame(r, &f, t, 5, &fe, &st, &err);
    CHECK(s != TSR_OK && err.status == s && st.tiles == 0);
    CHECK_MSG(strstr(err.message, "0x4a"), "%s", err.message); /* names the key */
    CHECK(b->stats.frames == 1);                               /* the frame was ended, not left open */
    fe.fail_key = 0;
    CHECK(run_frame(r, &f, t, 5, &fe, &st, &err) == TSR_OK);
    CHECK(st.tiles_uploaded == 1 && fe.calls == 1); /* the four fetched before stayed */
    check_draws(t, 5, &f, 0);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST(bad_tiles_and_options_refused)
{
    tsr_hw_backend *b = make_backend();
    tsr_hw_renderer *r = NULL;
    tsr_error err = {0};
    tsr_hw_renderer_options o = {0};
    o.tile_n = 3;
    CHECK(tsr_hw_renderer_create(b, &o, NULL, &r, &err) == TSR_ERR_ARGUMENT && !r);
    o.tile_n = TSR_TILE_MAX + 2;
    CHECK(tsr_hw_renderer_create(b, &o, NULL, &r, &err) == TSR_ERR_ARGUMENT);
    o.tile_n = 16;
    o.cache_bytes = 577; /* less than one 17x17 U16 tile (578 bytes) */
    CHECK(tsr_hw_renderer_create(b, &o, NULL, &r, &err) == TSR_ERR_ARGUMENT);
    o.cache_bytes = 0;
    o.max_quantization = -1;
    CHECK(tsr_hw_renderer_create(b, &o, NULL, &r, &err) == TSR_ERR_ARGUMENT);
    o.max_quantization = NAN;
    CHECK(tsr_hw_renderer_create(b, &o, NULL, &r, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_hw_renderer_create(NULL, NULL, NULL, &r, &err) == TSR_ERR_ARGUMENT);
    CHECK(b->stats.buffers_live == 0);

    r = make_renderer(b, 4, 1 << 16, 0);
    tsr_hw_frame f = make_frame(0, 0, 0);
    fetcher fe = {0};
    tsr_hw_render_stats st;
    tsr_hw_tile good = make_tile(1, 0, 0), t;
#define REFUSED(change)                                                                            \
    do {                                                                                           \
        t = good;                                                                                  \
        change;                                                                                    \
        CHECK_MSG(run_frame(r, &f, &t, 1, &fe, &st, &err) == TSR_ERR_ARGUMENT, "%s", #change);     \
    } while (0)
    REFUSED(t.spacing[0] = 0);
    REFUSED(t.spacing[1] = -2);
    REFUSED(t.spacing[0] = NAN);
    REFUSED(t.spacing[1] = 1e300);
    REFUSED(t.origin[0] = NAN);
    REFUSED(t.origin[1] = INFINITY);
    REFUSED(t.z_scale = NAN);
    REFUSED(t.z_scale = 1e300);
    REFUSED(t.morph = 1.5f);
    REFUSED(t.morph = NAN);
    REFUSED(t.stitch = 16);
    REFUSED(t.neighbour[5] = 2); /* beyond the frame's one tile */
    REFUSED(t.neighbour[0] = 1); /* itself */
#undef REFUSED
    CHECK(fe.calls == 0 && b->stats.frames == 0);
    t = make_tile(99, 0, 0);
    t.z_scale = 1e36; /* finite, but z_scale times samples of ~2e4 is not a float */
    CHECK(run_frame(r, &f, &t, 1, &fe, &st, &err) == TSR_ERR_VALUE && b->stats.frames == 1 && st.tiles == 0);
    CHECK(tsr_hw_renderer_frame(r, &f, &good, 1, NULL, NULL, &st, &err) ==
          TSR_ERR_ARGUMENT); /* not resident, no fetch */
    CHECK(run_frame(r, &f, &good, 1, &fe, &st, &err) == TSR_OK);
    CHECK(tsr_hw_renderer_frame(r, &f, &good, 1, NULL, NULL, &st, &err) == TSR_OK); /* resident: no fetch needed */
    CHECK(tsr_hw_renderer_frame(r, &f, NULL, 0, NULL, NULL, &st, &err) == TSR_OK && st.tiles == 0);
    tsr_hw_renderer_destroy(r);
    b->destroy(b);
}

TEST_MAIN(T(encode_integer_tiles_lossless), T(encode_span_beyond_u16), T(encode_float_tiles),
          T(encode_constant_all_nan_inf), T(view_proj_matches_camera), T(second_frame_uploads_nothing),
          T(neighbours_pass_to_draws),
          T(moving_cut_uploads_one_tile), T(lru_evicts_least_recently_drawn), T(lru_matches_model),
          T(lru_matches_model_many_tiles), T(frame_over_budget_fails_too_large), T(f32_tile_defragments_pool),
          T(mixed_formats_random_frames), T(eye_relative_origins_far_from_the_origin),
          T(upload_bytes_are_encoded_bytes), T(quantised_float_tiles), T(fetch_failure_fails_frame),
          T(bad_tiles_and_options_refused))
