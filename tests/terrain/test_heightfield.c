/* Heightfields: loading every format, raw files, no-data, saving and
 * reading back, statistics, the generator, and the grid mesh. Files are
 * written by independent means where it matters (PGM and raw bytes by
 * hand here; 8-bit PNG, 16-bit TIFF and friends by oiiotool in
 * tests/tools/formats.sh). */
#include "check.h"
#include "terrain/terrain.h"

static char path_buf[512];
static const char *tmp_path(const char *dir, const char *name)
{
    snprintf(path_buf, sizeof path_buf, "%s/%s", dir, name);
    return path_buf;
}

static void write_bytes(const char *path, const void *b, size_t n)
{
    FILE *f = fopen(path, "wb");
    fwrite(b, 1, n, f);
    fclose(f);
}

/* A smooth, non-integer test field with known values. */
static float field(uint32_t c, uint32_t r) { return (float)(100.0 + 37.25 * sin(c * 0.3) + 0.5 * r - 0.01 * c * r); }

static tsr_heightfield *make_field(uint32_t w, uint32_t h)
{
    tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < h; r++)
        for (uint32_t c = 0; c < w; c++)
            d[r * w + c] = field(c, r);
    return hf;
}

TEST(save_and_load_float_formats)
{
    const char *dir = check_temp_dir();
    const char *names[] = {"f.tif", "f.exr"};
    for (int k = 0; k < 2; k++) {
        tsr_heightfield *hf = make_field(37, 23); /* not 2^k+1 */
        tsr_heightfield_data(hf)[5] = NAN;
        tsr_error err = {0};
        const char *p = tmp_path(dir, names[k]);
        CHECK_MSG(tsr_heightfield_save(hf, p, NULL, &err) == TSR_OK, "%s", err.message);
        tsr_heightfield *back = NULL;
        CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &back, &err) == TSR_OK, "%s", err.message);
        if (!back)
            continue;
        CHECK(tsr_heightfield_width(back) == 37 && tsr_heightfield_height(back) == 23);
        const float *a = tsr_heightfield_cdata(hf), *b = tsr_heightfield_cdata(back);
        int mismatches = 0;
        for (int i = 0; i < 37 * 23; i++)
            mismatches += isnan(a[i]) ? !isnan(b[i]) : a[i] != b[i];
        CHECK_MSG(mismatches == 0, "%s: %d samples differ", names[k], mismatches);
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(back, &st);
        CHECK(st.nodata == 1 && st.valid == 37 * 23 - 1);
        tsr_heightfield_destroy(hf);
        tsr_heightfield_destroy(back);
    }
}

TEST(png16_keeps_scale_and_offset)
{
    const char *dir = check_temp_dir();
    tsr_heightfield *hf = make_field(64, 48);
    tsr_save_info info;
    tsr_error err = {0};
    const char *p = tmp_path(dir, "h.png");
    CHECK(tsr_heightfield_save(hf, p, &info, &err) == TSR_OK);
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    CHECK_NEAR(info.offset, st.min, 1e-9);
    CHECK_NEAR(info.scale, (st.max - st.min) / 65535, 1e-12);
    tsr_heightfield *back = NULL;
    CHECK(tsr_heightfield_load(p, NULL, NULL, &back, &err) == TSR_OK);
    double worst = 0;
    for (int i = 0; i < 64 * 48; i++) {
        double d = fabs(tsr_heightfield_cdata(back)[i] - tsr_heightfield_cdata(hf)[i]);
        worst = d > worst ? d : worst;
    }
    /* quantisation: half a step, plus float rounding of the heights */
    CHECK_MSG(worst <= info.scale * 0.5 + 1e-4, "worst %g, step %g", worst, info.scale);
    CHECK(strstr(tsr_heightfield_source_format(back), "png uint16") != NULL);
    /* --nodata names a stored value, before the scale: 0 marks the
     * samples at the lowest height, and only those */
    tsr_load_options o = {.has_nodata = true, .nodata = 0};
    tsr_heightfield *holed = NULL;
    CHECK(tsr_heightfield_load(p, &o, NULL, &holed, &err) == TSR_OK);
    size_t lowest = 0, agree = 0;
    for (int i = 0; i < 64 * 48; i++) {
        bool low = tsr_heightfield_cdata(back)[i] == (float)info.offset;
        float h = tsr_heightfield_cdata(holed)[i];
        lowest += low;
        agree += low ? isnan(h) : h == tsr_heightfield_cdata(back)[i];
    }
    CHECK_MSG(lowest >= 1 && agree == 64 * 48, "%zu lowest samples, %zu of %d as expected", lowest, agree, 64 * 48);
    tsr_heightfield_destroy(holed);
    tsr_heightfield_destroy(back);

    /* integer heights 0..65535 are written as they are (scale 1) */
    float *d = tsr_heightfield_data(hf);
    for (int i = 0; i < 64 * 48; i++)
        d[i] = (float)((i * 37) % 65536);
    CHECK(tsr_heightfield_save(hf, p, &info, &err) == TSR_OK);
    CHECK(info.scale == 1 && info.offset == 0);
    CHECK(tsr_heightfield_load(p, NULL, NULL, &back, &err) == TSR_OK);
    CHECK(memcmp(tsr_heightfield_cdata(back), d, 64 * 48 * sizeof(float)) == 0);
    tsr_heightfield_destroy(back);
    tsr_heightfield_destroy(hf);
}

TEST(pgm_16bit_written_by_hand)
{
    /* binary PGM, maxval 65535, big-endian samples (Netpbm's definition) */
    const char *dir = check_temp_dir();
    const uint32_t w = 5, h = 3;
    unsigned char buf[64 + 2 * 15];
    int n = snprintf((char *)buf, 64, "P5\n%u %u\n65535\n", w, h);
    for (uint32_t i = 0; i < w * h; i++) {
        uint16_t v = (uint16_t)(i * 4000 + 7);
        buf[n + 2 * i] = (unsigned char)(v >> 8);
        buf[n + 2 * i + 1] = (unsigned char)v;
    }
    const char *p = tmp_path(dir, "a.pgm");
    write_bytes(p, buf, (size_t)n + 2 * w * h);
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    if (hf) {
        for (uint32_t i = 0; i < w * h; i++)
            CHECK(tsr_heightfield_cdata(hf)[i] == (float)(i * 4000 + 7));
        tsr_heightfield_destroy(hf);
    }
}

TEST(raw_types)
{
    const char *dir = check_temp_dir();
    const uint32_t w = 7, h = 4;
    unsigned char b[7 * 4 * 4];
    tsr_error err = {0};
    tsr_heightfield *hf;
    /* u16 */
    for (uint32_t i = 0; i < w * h; i++) {
        uint16_t v = (uint16_t)(60000 + i);
        b[2 * i] = (unsigned char)v;
        b[2 * i + 1] = (unsigned char)(v >> 8);
    }
    write_bytes(tmp_path(dir, "u.raw"), b, 2 * w * h);
    tsr_load_options o = {0};
    o.raw_type = tsr_raw_type_parse("u16");
    o.raw_width = w;
    o.raw_height = h;
    CHECK(tsr_heightfield_load(path_buf, &o, NULL, &hf, &err) == TSR_OK);
    CHECK(hf && tsr_heightfield_cdata(hf)[27] == 60027.0f);
    tsr_heightfield_destroy(hf);
    /* the same bytes as i16 are negative */
    o.raw_type = tsr_raw_type_parse("i16");
    CHECK(tsr_heightfield_load(path_buf, &o, NULL, &hf, &err) == TSR_OK);
    CHECK(hf && tsr_heightfield_cdata(hf)[0] == (float)(int16_t)60000);
    tsr_heightfield_destroy(hf);
    /* f32 with a no-data value */
    for (uint32_t i = 0; i < w * h; i++) {
        float v = i == 3 ? -9999.0f : (float)i * 0.5f;
        uint32_t u;
        memcpy(&u, &v, 4);
        for (int k = 0; k < 4; k++)
            b[4 * i + k] = (unsigned char)(u >> (8 * k));
    }
    write_bytes(tmp_path(dir, "f.raw"), b, 4 * w * h);
    o.raw_type = tsr_raw_type_parse("f32");
    o.has_nodata = true;
    o.nodata = -9999;
    CHECK(tsr_heightfield_load(path_buf, &o, NULL, &hf, &err) == TSR_OK);
    if (hf) {
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        CHECK(st.nodata == 1 && isnan(tsr_heightfield_cdata(hf)[3]));
        CHECK(st.min == 0 && st.max == 13.5);
        CHECK(strcmp(tsr_heightfield_source_format(hf), "raw f32") == 0);
        tsr_heightfield_destroy(hf);
    }
    /* wrong size: one sample short, one byte long */
    o.has_nodata = false;
    o.raw_width = w + 1;
    CHECK(tsr_heightfield_load(path_buf, &o, NULL, &hf, &err) == TSR_ERR_TRUNCATED && hf == NULL);
    CHECK(strstr(err.message, "f.raw") != NULL);
    o.raw_width = w;
    o.raw_height = h - 1;
    CHECK(tsr_heightfield_load(path_buf, &o, NULL, &hf, &err) == TSR_ERR_FORMAT && hf == NULL);
    CHECK(tsr_raw_type_parse("u8") == TSR_RAW_NONE);
}

TEST(nan_height_is_nodata_and_inf_height_is_refused)
{
    const char *dir = check_temp_dir();
    tsr_heightfield *hf = make_field(10, 10);
    tsr_heightfield_data(hf)[42] = NAN;
    tsr_error err = {0};
    CHECK(tsr_heightfield_save(hf, tmp_path(dir, "nan.tif"), NULL, &err) == TSR_OK);
    tsr_heightfield *back = NULL;
    CHECK(tsr_heightfield_load(path_buf, NULL, NULL, &back, &err) == TSR_OK);
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(back, &st);
    CHECK(st.nodata == 1 && st.valid == 99);
    tsr_heightfield_destroy(back);
    tsr_heightfield_data(hf)[42] = INFINITY;
    CHECK(tsr_heightfield_save(hf, tmp_path(dir, "inf.tif"), NULL, &err) == TSR_OK);
    CHECK(tsr_heightfield_load(path_buf, NULL, NULL, &back, &err) == TSR_ERR_VALUE && back == NULL);
    CHECK(strstr(err.message, "inf.tif") && strstr(err.message, "column 2, row 4"));
    for (int i = 0; i < 100; i++)
        tsr_heightfield_data(hf)[i] = NAN;
    CHECK(tsr_heightfield_save(hf, tmp_path(dir, "allnan.tif"), NULL, &err) == TSR_OK);
    CHECK(tsr_heightfield_load(path_buf, NULL, NULL, &back, &err) == TSR_ERR_VALUE);
    CHECK(strstr(err.message, "no-data") != NULL);
    tsr_heightfield_destroy(hf);
}

TEST(size_limits)
{
    CHECK(tsr_heightfield_create(1, 5, NULL) == NULL);
    CHECK(tsr_heightfield_create(TSR_HEIGHTFIELD_MAX_SIDE + 1, 2, NULL) == NULL);
    tsr_heightfield *hf = tsr_heightfield_create(2, 2, NULL);
    CHECK(hf != NULL);
    tsr_heightfield_destroy(hf);
}

TEST(data_terrain_rgb_real_tile)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    char p[5000];
    snprintf(p, sizeof p, "%s/terrain/bayhills-14-2625-6369-terrainrgb.png", data);
    tsr_load_options o = {0};
    o.decode = TSR_DECODE_TERRAIN_RGB;
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, &o, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    if (!hf)
        return;
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    /* the data README: 512x512, 19 to 251.8 m */
    CHECK(tsr_heightfield_width(hf) == 512 && tsr_heightfield_height(hf) == 512);
    CHECK_NEAR(st.min, 19.0, 0.051);
    CHECK_NEAR(st.max, 251.8, 0.051);
    tsr_heightfield_destroy(hf);
    /* without --decode a colour tile is refused, with a hint */
    CHECK(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_ERR_FORMAT);
    CHECK(strstr(err.message, "terrain-rgb") != NULL);
}

TEST(data_real_float_tiffs)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    char p[5000];
    snprintf(p, sizeof p, "%s/terrain/valid_raster-float32.tif", data);
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    CHECK(hf && tsr_heightfield_width(hf) == 100 && tsr_heightfield_height(hf) == 80);
    tsr_heightfield_destroy(hf);
    snprintf(p, sizeof p, "%s/terrain/egm84-epsg3857-float32.tif", data);
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    CHECK(hf && tsr_heightfield_width(hf) == 624 && tsr_heightfield_height(hf) == 510);
    tsr_heightfield_destroy(hf);
}

TEST(generator_is_deterministic_and_terrain_like)
{
    tsr_heightfield *a = tsr_heightfield_create(129, 97, NULL), *b = tsr_heightfield_create(129, 97, NULL),
                    *c = tsr_heightfield_create(129, 97, NULL);
    tsr_generate_options o = {0};
    o.seed = 7;
    tsr_terrain_generate(a, &o);
    tsr_terrain_generate(b, &o);
    o.seed = 8;
    tsr_terrain_generate(c, &o);
    size_t n = 129 * 97;
    CHECK(memcmp(tsr_heightfield_cdata(a), tsr_heightfield_cdata(b), n * sizeof(float)) == 0);
    CHECK(memcmp(tsr_heightfield_cdata(a), tsr_heightfield_cdata(c), n * sizeof(float)) != 0);
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(a, &st);
    CHECK(st.nodata == 0 && st.min == 0 && fabs(st.max - 1200) < 1e-3);
    CHECK(st.mean > 100 && st.mean < 1100);
    /* terrain-like: neighbouring samples are close (smooth at the sample
     * scale) yet the field varies at large scale */
    const float *d = tsr_heightfield_cdata(a);
    double mean_step = 0;
    for (uint32_t r = 0; r < 97; r++)
        for (uint32_t col = 0; col + 1 < 129; col++)
            mean_step += fabs(d[r * 129 + col + 1] - d[r * 129 + col]);
    mean_step /= 97.0 * 128;
    CHECK_MSG(mean_step < 0.05 * 1200, "mean step %g", mean_step);
    CHECK_MSG(mean_step > 1e-4 * 1200, "mean step %g", mean_step);
    tsr_heightfield_destroy(a);
    tsr_heightfield_destroy(b);
    tsr_heightfield_destroy(c);
}

typedef struct progress_log {
    int calls;
    double last;
    bool backwards, outside;
} progress_log;

static void log_progress(void *user, double f)
{
    progress_log *l = user;
    l->backwards |= f < l->last;
    l->outside |= !(f >= 0 && f <= 1);
    l->last = f;
    l->calls++;
}

/* The noise runs in bands on threads: any thread count gives the same
 * bits. Progress goes from 0 to 1 without stepping back. */
TEST(generator_same_on_any_thread_count_with_progress)
{
    uint32_t w = 203, h = 150; /* bands of 16 rows: a short last one */
    tsr_heightfield *a = tsr_heightfield_create(w, h, NULL), *b = tsr_heightfield_create(w, h, NULL);
    progress_log la = {0, 0, false, false}, lb = {0, 0, false, false};
    tsr_generate_options o = {.seed = 3, .threads = 1, .progress = log_progress, .progress_user = &la};
    tsr_terrain_generate(a, &o);
    o.threads = 5;
    o.progress_user = &lb;
    tsr_terrain_generate(b, &o);
    CHECK(memcmp(tsr_heightfield_cdata(a), tsr_heightfield_cdata(b), (size_t)w * h * sizeof(float)) == 0);
    const progress_log *logs[2] = {&la, &lb};
    for (int k = 0; k < 2; k++) {
        CHECK_MSG(logs[k]->calls >= 10, "%d progress calls", logs[k]->calls);
        CHECK(!logs[k]->backwards && !logs[k]->outside && logs[k]->last == 1);
    }
    tsr_heightfield_destroy(a);
    tsr_heightfield_destroy(b);
}

/* tsr_heightfield_save stores a spacing other than 1 x 1 (the attribute in
 * PNG and EXR, the image description in TIFF), and loading gives it back
 * as the file's ground spacing; the default spacing is not stored. */
TEST(saved_spacing_comes_back)
{
    const char *dir = check_temp_dir();
    const char *names[] = {"s.png", "s.tif", "s.exr"};
    for (int k = 0; k < 3; k++)
        for (int spaced = 0; spaced < 2; spaced++) {
            tsr_heightfield *hf = make_field(9, 7);
            if (spaced)
                tsr_heightfield_set_spacing(hf, 12.5, 30.25, 1);
            const char *p = tmp_path(dir, names[k]);
            tsr_error err = {0};
            CHECK_MSG(tsr_heightfield_save(hf, p, NULL, &err) == TSR_OK, "%s", err.message);
            tsr_heightfield *back = NULL;
            CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &back, &err) == TSR_OK, "%s", err.message);
            const tsr_georef *g = back ? tsr_heightfield_georef(back) : NULL;
            if (spaced)
                CHECK_MSG(g && g->has_spacing && g->spacing[0] == 12.5 && g->spacing[1] == 30.25, "%s: spacing %s",
                          names[k], g ? "not as saved" : "lost");
            else
                CHECK_MSG(!g || !g->has_spacing, "%s: a spacing read where none was saved", names[k]);
            tsr_heightfield_destroy(hf);
            tsr_heightfield_destroy(back);
            remove(p);
        }
}

TEST(grid_mesh_is_valid_and_exact)
{
    tsr_heightfield *hf = make_field(23, 17);
    tsr_heightfield_set_spacing(hf, 2.0, 3.0, 0.5);
    for (uint32_t step = 1; step <= 5; step++) {
        tsr_mesh m;
        tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
        tsr_error err = {0};
        CHECK(tsr_terrain_grid_mesh(hf, step, true, &m, &err) == TSR_OK);
        uint32_t nc = (22 + step - 1) / step + 1, nr = (16 + step - 1) / step + 1;
        CHECK(m.vertex_count == nc * nr && m.triangle_count == 2 * (nc - 1) * (nr - 1));
        tsr_validation v;
        tsr_validate_options vo = {0};
        vo.expect_up = vo.height_field = true;
        CHECK(tsr_mesh_validate(&m, &vo, &v) == TSR_OK);
        char msg[512];
        tsr_validation_describe(&v, msg, sizeof msg);
        CHECK_MSG(tsr_validation_ok(&v), "step %u: %s", step, msg);
        CHECK(v.boundary_loops == 1 && v.euler == 1);
        CHECK(tsr_mesh_boundary_is_rect(&m, 0, 0, 22 * 2.0, 16 * 3.0, 1e-4, NULL));
        /* every vertex is a sample, at x = c dx, y = r dy, z = h dz */
        for (uint32_t i = 0; i < m.vertex_count; i++) {
            const float *p = m.positions + 3 * i;
            uint32_t c = (uint32_t)lround(p[0] / 2.0), r = (uint32_t)lround(p[1] / 3.0);
            CHECK_NEAR(p[2], field(c, r) * 0.5, 1e-4);
        }
        tsr_mesh_free(&m);
    }
    tsr_heightfield_destroy(hf);
}

TEST(nodata_becomes_hole)
{
    tsr_heightfield *hf = make_field(12, 12);
    float *d = tsr_heightfield_data(hf);
    d[5 * 12 + 5] = NAN; /* one interior sample */
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    CHECK(tsr_terrain_grid_mesh(hf, 1, false, &m, NULL) == TSR_OK);
    for (uint32_t i = 0; i < 3 * m.vertex_count; i++)
        CHECK(!isnan(m.positions[i]));
    tsr_validation v;
    CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
    CHECK(tsr_validation_ok(&v));
    CHECK(v.boundary_loops == 2); /* the border and the hole's rim */
    CHECK(m.vertex_count == 143);
    /* the six triangles around the sample are gone; the four cells around
     * it keep the triangle of their other three corners */
    CHECK(m.triangle_count == 2 * 11 * 11 - 4);
    tsr_mesh_free(&m);
    tsr_heightfield_destroy(hf);
}

/* With a step above 1, no-data between the lattice samples (pinholes, a
 * one-sample crack) must stay uncovered: against a plain point-in-closed-
 * triangle test of every no-data sample against every triangle (dx = dy =
 * 1: integer positions, exact). Every vertex is used by a triangle. */
TEST(grid_step_leaves_nodata_uncovered)
{
    srand(5);
    for (int t = 0; t < 24; t++) {
        uint32_t w = 9 + (uint32_t)(rand() % 30), h = 9 + (uint32_t)(rand() % 25);
        tsr_heightfield *hf = make_field(w, h);
        float *d = tsr_heightfield_data(hf);
        for (uint32_t k = 0; k < 1 + (uint32_t)(rand() % 6); k++)
            d[(size_t)(rand() % (int)h) * w + (uint32_t)(rand() % (int)w)] = NAN;
        if (t % 3 == 0) /* a crack one sample wide, down a column */
            for (uint32_t r = 0; r < h; r++)
                d[(size_t)r * w + w / 2] = NAN;
        if (t % 4 == 1) /* a valid sample alone in no-data: in no triangle */
            for (uint32_t r = 2; r < 7; r++)
                for (uint32_t c = 2; c < 7; c++)
                    d[(size_t)r * w + c] = r == 4 && c == 4 ? 1.0f : NAN;
        uint32_t step = 1 + (uint32_t)(t % 7);
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        CHECK(tsr_terrain_grid_mesh(hf, step, false, &m, NULL) == TSR_OK);
        bool *used = calloc(m.vertex_count + 1, 1);
        int covered = 0;
        for (uint32_t i = 0; i < m.triangle_count; i++) {
            const float *p[3];
            for (int k = 0; k < 3; k++) {
                used[m.indices[3 * i + k]] = true;
                p[k] = m.positions + 3 * m.indices[3 * i + k];
            }
            for (uint32_t r = 0; r < h; r++)
                for (uint32_t c = 0; c < w; c++) {
                    if (!isnan(d[(size_t)r * w + c]))
                        continue;
                    bool in = true;
                    for (int k = 0; k < 3 && in; k++) {
                        const float *u = p[k], *v = p[(k + 1) % 3];
                        in = (v[0] - u[0]) * ((double)r - u[1]) - (v[1] - u[1]) * ((double)c - u[0]) >= 0;
                    }
                    covered += in;
                }
        }
        uint32_t unused = 0;
        for (uint32_t i = 0; i < m.vertex_count; i++)
            unused += !used[i];
        CHECK_MSG(covered == 0 && unused == 0, "%ux%u step %u: %d no-data samples covered, %u vertices unused", w, h,
                  step, covered, unused);
        tsr_validation v;
        CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
        CHECK(tsr_validation_ok(&v));
        free(used);
        tsr_mesh_free(&m);
        tsr_heightfield_destroy(hf);
    }
}

/* tsr_heightfield_stats_compute (eight lanes in vectors) against a plain
 * scan: minimum, maximum and no-data count exactly, the mean within
 * rounding of a long double sum; sizes of every remainder mod 8, NaN,
 * negative zero, all no-data. */
TEST(stats_against_a_plain_scan)
{
    srand(11);
    for (int t = 0; t < 300; t++) {
        uint32_t w = 2 + (uint32_t)(rand() % 200), h = 2 + (uint32_t)(rand() % 120);
        tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
        float *d = tsr_heightfield_data(hf);
        size_t n = (size_t)w * h, nan = 0;
        int kind = t % 10;
        float mn = INFINITY, mx = -INFINITY;
        long double sum = 0;
        for (size_t i = 0; i < n; i++) {
            int r = rand() % 100;
            float v = kind == 0 ? NAN : r < 6 ? NAN : r < 8 ? -0.0f : (float)((rand() - RAND_MAX / 2) * 1e-3 * (kind + 1));
            d[i] = v;
            if (v != v) {
                nan++;
                continue;
            }
            mn = v < mn ? v : mn;
            mx = v > mx ? v : mx;
            sum += v;
        }
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        CHECK_MSG(st.nodata == nan && st.valid == n - nan, "%ux%u: %llu no-data counted, %zu there", w, h,
                  (unsigned long long)st.nodata, nan);
        if (nan == n)
            CHECK(isnan(st.min) && isnan(st.max) && isnan(st.mean));
        else {
            CHECK_MSG(st.min == mn && st.max == mx, "%ux%u: min %g max %g, a plain scan %g %g", w, h, st.min, st.max,
                      mn, mx);
            double mean = (double)(sum / (long double)(n - nan));
            CHECK_MSG(fabs(st.mean - mean) <= 1e-12 * (fabs(mean) + 1000), "%ux%u: mean %.17g, a plain scan %.17g", w, h,
                      st.mean, mean);
        }
        tsr_heightfield_destroy(hf);
    }
}

TEST_MAIN(T(save_and_load_float_formats), T(png16_keeps_scale_and_offset), T(pgm_16bit_written_by_hand), T(raw_types),
          T(nan_height_is_nodata_and_inf_height_is_refused), T(size_limits), T(data_terrain_rgb_real_tile),
          T(data_real_float_tiffs), T(generator_is_deterministic_and_terrain_like),
          T(generator_same_on_any_thread_count_with_progress), T(saved_spacing_comes_back), T(grid_mesh_is_valid_and_exact), T(nodata_becomes_hole),
          T(grid_step_leaves_nodata_uncovered),
          T(stats_against_a_plain_scan))
