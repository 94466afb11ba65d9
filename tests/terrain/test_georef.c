/* GIS rasters: the georeferencing and no-data value of GeoTIFFs, and the
 * formats read through GDAL (SRTM .hgt, Esri ASCII grids). The .hgt and
 * .asc files are written by hand here, byte by byte from their published
 * layouts; the GeoTIFF by GDAL's writer (our reader takes its tags through
 * GDAL too, but what is checked is ours: the no-data samples, the sample
 * centres, the ground spacing). Ground spacings are checked against
 * independent geodesy: UTM's scale k0 = 0.9996 on its central meridian,
 * the standard series for the length of a degree on WGS 84, and the
 * spherical Web Mercator's scale 1 / cos(latitude). */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "terrain/terrain.h"

#include <gdal.h>
#include <gdal_frmts.h>
#include <ogr_srs_api.h>
#include <unistd.h>

static char path_buf[512];
static const char *tmp_path(const char *dir, const char *name)
{
    snprintf(path_buf, sizeof path_buf, "%s/%s", dir, name);
    return path_buf;
}

static const double PI = 3.14159265358979323846;

/* Metres in one degree of latitude and of longitude at latitude phi
 * (degrees) on WGS 84, from the usual series (not the closed-form radii
 * the loader uses). */
static double deg_lat_m(double phi)
{
    double p = phi * PI / 180;
    return 111132.954 - 559.822 * cos(2 * p) + 1.175 * cos(4 * p);
}
static double deg_lon_m(double phi)
{
    double p = phi * PI / 180;
    return 111412.84 * cos(p) - 93.5 * cos(3 * p) + 0.118 * cos(5 * p);
}

static float utm_value(uint32_t c, uint32_t r) { return (float)(250.0 + 12.5 * sin(c * 0.2) + 0.75 * r); }

TEST(geotiff_utm_georef_and_nodata)
{
    const char *dir = check_temp_dir();
    const char *p = tmp_path(dir, "utm.tif");
    const uint32_t W = 40, H = 30;
    float v[40 * 30];
    size_t holes = 0;
    for (uint32_t r = 0; r < H; r++)
        for (uint32_t c = 0; c < W; c++) {
            bool hole = (r * W + c) % 7 == 3;
            v[r * W + c] = hole ? -9999.0f : utm_value(c, r);
            holes += hole;
        }
    GDALRegister_GTiff();
    GDALDatasetH d = GDALCreate(GDALGetDriverByName("GTiff"), p, (int)W, (int)H, 1, GDT_Float32, NULL);
    CHECK(d != NULL);
    /* the raster's middle column on UTM 33N's central meridian (x 500000) */
    double gt[6] = {499400, 30, 0, 5000450, 0, -30};
    GDALSetGeoTransform(d, gt);
    OGRSpatialReferenceH srs = OSRNewSpatialReference(NULL);
    CHECK(OSRImportFromEPSG(srs, 32633) == OGRERR_NONE);
    GDALSetSpatialRef(d, srs);
    OSRRelease(srs);
    GDALRasterBandH b = GDALGetRasterBand(d, 1);
    GDALSetRasterNoDataValue(b, -9999);
    CHECK(GDALRasterIO(b, GF_Write, 0, 0, (int)W, (int)H, v, (int)W, (int)H, GDT_Float32, 0, 0) == CE_None);
    GDALClose(d);

    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    CHECK(tsr_heightfield_width(hf) == W && tsr_heightfield_height(hf) == H);
    const float *s = tsr_heightfield_cdata(hf);
    size_t nan = 0, same = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        nan += isnan(s[i]);
        same += !isnan(s[i]) && s[i] == v[i];
    }
    CHECK(nan == holes && same == (size_t)W * H - holes);
    const tsr_georef *g = tsr_heightfield_georef(hf);
    CHECK(g && g->has_transform && g->crs == TSR_CRS_PROJECTED);
    CHECK_MSG(g && strstr(g->crs_name, "UTM zone 33N"), "%s", g ? g->crs_name : "(none)");
    CHECK(g && g->origin[0] == gt[0] + 15 && g->origin[1] == gt[3] - 15);
    CHECK(g && g->pixel[0] == 30 && g->pixel[1] == -30);
    CHECK(g && g->has_nodata && g->nodata == -9999);
    /* 30 grid metres on the central meridian are 30 / 0.9996 on the ground;
     * within 1 % of true scale, the spacing is the CRS's own 30 m, so the
     * mesh registers with other UTM data */
    CHECK(g && g->has_spacing && !g->spacing_approx && !g->spacing_unitless && g->spacing_crs);
    CHECK_NEAR(g->ground[0], 30 / 0.9996, 30e-6);
    CHECK_NEAR(g->ground[1], 30 / 0.9996, 30e-6);
    CHECK(g->spacing[0] == 30 && g->spacing[1] == 30);
    tsr_heightfield_destroy(hf);

    /* a no-data value asked for replaces the file's */
    tsr_load_options o = {0};
    o.has_nodata = true;
    o.nodata = utm_value(5, 5);
    CHECK_MSG(tsr_heightfield_load(p, &o, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    s = tsr_heightfield_cdata(hf);
    size_t minus = 0;
    nan = 0;
    for (size_t i = 0; i < (size_t)W * H; i++) {
        nan += isnan(s[i]);
        minus += s[i] == -9999.0f;
    }
    CHECK(minus == holes && nan >= 1 && isnan(s[5 * W + 5]));
    tsr_heightfield_destroy(hf);
}

TEST(geotiff_int16_scale_offset_and_nodata)
{
    /* heights stored as int16 tenths of a metre above -100, -32768 for
     * no-data, the scale and offset in GDAL's metadata: OpenImageIO reads
     * the integers, the loader applies the file's scale */
    const char *dir = check_temp_dir();
    const char *p = tmp_path(dir, "scaled.tif");
    const int W = 9, H = 7;
    int16_t v[9 * 7];
    for (int i = 0; i < W * H; i++)
        v[i] = i % 5 == 2 ? (int16_t)-32768 : (int16_t)(i * 37 - 900);
    GDALRegister_GTiff();
    GDALDatasetH d = GDALCreate(GDALGetDriverByName("GTiff"), p, W, H, 1, GDT_Int16, NULL);
    CHECK(d != NULL);
    GDALRasterBandH b = GDALGetRasterBand(d, 1);
    GDALSetRasterNoDataValue(b, -32768);
    GDALSetRasterScale(b, 0.1);
    GDALSetRasterOffset(b, -100);
    CHECK(GDALRasterIO(b, GF_Write, 0, 0, W, H, v, W, H, GDT_Int16, 0, 0) == CE_None);
    GDALClose(d);
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    const float *s = tsr_heightfield_cdata(hf);
    size_t good = 0;
    for (int i = 0; i < W * H; i++)
        good += i % 5 == 2 ? isnan(s[i]) : s[i] == (float)(v[i] * 0.1 - 100);
    CHECK_MSG(good == (size_t)(W * H), "%zu of %d samples as expected", good, W * H);
    const tsr_georef *g = tsr_heightfield_georef(hf);
    CHECK(g && g->z_scale == 0.1 && g->z_offset == -100 && g->has_nodata && !g->has_transform);
    tsr_heightfield_destroy(hf);
    /* a no-data value asked for is a stored value too, as GDAL takes it:
     * the file's -32768 given again, and then a value only real samples
     * store (its height, -190, marks nothing) */
    const int16_t asked[2] = {-32768, (int16_t)(1 * 37 - 900)};
    for (int k = 0; k < 2; k++) {
        tsr_load_options o = {.has_nodata = true, .nodata = asked[k]};
        CHECK_MSG(tsr_heightfield_load(p, &o, NULL, &hf, &err) == TSR_OK, "%s", err.message);
        s = tsr_heightfield_cdata(hf);
        good = 0;
        for (int i = 0; i < W * H; i++)
            good += v[i] == asked[k] ? isnan(s[i]) : s[i] == (float)(v[i] * 0.1 - 100);
        CHECK_MSG(good == (size_t)(W * H), "--nodata %d: %zu of %d samples as expected", asked[k], good, W * H);
        tsr_heightfield_destroy(hf);
        o.nodata = asked[k] * 0.1 - 100; /* the height, not the stored value */
        CHECK_MSG(tsr_heightfield_load(p, &o, NULL, &hf, &err) == TSR_OK, "%s", err.message);
        s = tsr_heightfield_cdata(hf);
        size_t holes = 0;
        for (int i = 0; i < W * H; i++)
            holes += isnan(s[i]);
        CHECK_MSG(holes == 0, "--nodata at a height: %zu holes", holes);
        tsr_heightfield_destroy(hf);
    }
}

static void put_be16(unsigned char *b, int16_t v)
{
    uint16_t u = (uint16_t)v;
    b[0] = (unsigned char)(u >> 8);
    b[1] = (unsigned char)(u & 0xff);
}

static int16_t hgt_value(uint32_t c, uint32_t r) { return (int16_t)((c * 3 + r * 7) % 1000) - 100; }
static bool hgt_void(uint32_t c, uint32_t r) { return c % 97 == 5 && r % 89 == 11; }

TEST(srtm_hgt_written_by_hand)
{
    const char *dir = check_temp_dir();
    const uint32_t N = 1201; /* 3 arc-seconds: 1201 x 1201 big-endian int16, row 0 the north edge */
    size_t bytes = (size_t)N * N * 2;
    unsigned char *buf = malloc(bytes);
    CHECK(buf != NULL);
    size_t voids = 0;
    for (uint32_t r = 0; r < N; r++)
        for (uint32_t c = 0; c < N; c++) {
            bool v = hgt_void(c, r);
            put_be16(buf + 2 * ((size_t)r * N + c), v ? (int16_t)-32768 : hgt_value(c, r));
            voids += v;
        }
    char p[600];
    snprintf(p, sizeof p, "%s/N45E007.hgt", dir);
    FILE *f = fopen(p, "wb");
    CHECK(f && fwrite(buf, 1, bytes, f) == bytes);
    fclose(f);
    free(buf);

    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    CHECK(tsr_heightfield_width(hf) == N && tsr_heightfield_height(hf) == N);
    CHECK_MSG(strstr(tsr_heightfield_source_format(hf), "srtmhgt"), "%s", tsr_heightfield_source_format(hf));
    const float *s = tsr_heightfield_cdata(hf);
    size_t nan = 0, same = 0;
    for (uint32_t r = 0; r < N; r++)
        for (uint32_t c = 0; c < N; c++) {
            float x = s[(size_t)r * N + c];
            nan += isnan(x) && hgt_void(c, r);
            same += !isnan(x) && x == (float)hgt_value(c, r);
        }
    CHECK(nan == voids && same == (size_t)N * N - voids);
    const tsr_georef *g = tsr_heightfield_georef(hf);
    CHECK(g && g->crs == TSR_CRS_GEOGRAPHIC && g->has_transform);
    /* sample (0, 0) is the tile's north-west corner point, 7 E 46 N */
    CHECK_NEAR(g->origin[0], 7.0, 1e-9);
    CHECK_NEAR(g->origin[1], 46.0, 1e-9);
    CHECK_NEAR(g->pixel[0], 1.0 / 1200, 1e-12);
    CHECK_NEAR(g->pixel[1], -1.0 / 1200, 1e-12);
    CHECK(g->has_nodata && g->nodata == -32768);
    /* three arc-seconds on the ground at the tile's middle, 45.5 N; a
     * degree tile's spacing changes across it */
    CHECK(g->has_spacing && g->spacing_approx && !g->spacing_unitless && !g->spacing_crs);
    double ex = deg_lon_m(45.5) / 1200, ey = deg_lat_m(45.5) / 1200;
    CHECK_MSG(fabs(g->spacing[0] / ex - 1) < 1e-4 && fabs(g->spacing[1] / ey - 1) < 1e-4, "%.6f %.6f against %.6f %.6f",
              g->spacing[0], g->spacing[1], ex, ey);
    tsr_heightfield_destroy(hf);

    /* cut short, the file is no SRTM tile: refused, named */
    f = fopen(p, "r+b");
    CHECK(f != NULL);
    CHECK(ftruncate(fileno(f), 1000) == 0);
    fclose(f);
    CHECK(tsr_heightfield_load(p, NULL, NULL, &hf, &err) != TSR_OK && hf == NULL);
    CHECK_MSG(strstr(err.message, "N45E007.hgt: ") != NULL, "%s", err.message);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

TEST(esri_ascii_grid_written_by_hand)
{
    const char *dir = check_temp_dir();
    const char *p = tmp_path(dir, "dem.asc");
    write_text(p, "ncols 5\n"
                  "nrows 4\n"
                  "xllcorner 1000\n"
                  "yllcorner 2000\n"
                  "cellsize 10\n"
                  "NODATA_value -9999\n"
                  "1 2 3 4 5\n"
                  "6 7 -9999 9 10\n"
                  "11 12 13 14 15.5\n"
                  "16 17 18 19 -20.25\n");
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
    CHECK(tsr_heightfield_width(hf) == 5 && tsr_heightfield_height(hf) == 4);
    const float *s = tsr_heightfield_cdata(hf);
    CHECK(s[0] == 1 && s[4] == 5 && s[5] == 6 && isnan(s[7]) && s[14] == 15.5f && s[19] == -20.25f);
    const tsr_georef *g = tsr_heightfield_georef(hf);
    /* no .prj: no CRS, the cell size in the file's own unit; row 0 is the
     * top, its centres half a cell below the grid's top edge (2000 + 40) */
    CHECK(g && g->crs == TSR_CRS_NONE && g->has_transform);
    CHECK(g->origin[0] == 1005 && g->origin[1] == 2035 && g->pixel[0] == 10 && g->pixel[1] == -10);
    CHECK(g->has_spacing && g->spacing_unitless && g->spacing[0] == 10 && g->spacing[1] == 10);
    tsr_heightfield_destroy(hf);

    /* bad grids: named, refused, nothing returned */
    struct {
        const char *name, *text;
    } bad[] = {
        {"short.asc", "ncols 5\nnrows 4\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3 4 5\n6 7 8 9 10\n"},
        {"huge.asc", "ncols 2000000\nnrows 2000000\nxllcorner 0\nyllcorner 0\ncellsize 1\n1 2 3\n"},
        {"one.asc", "ncols 1\nnrows 1\nxllcorner 0\nyllcorner 0\ncellsize 1\n7\n"},
        {"words.asc", "ncols 2\nnrows 2\nxllcorner 0\nyllcorner 0\ncellsize 1\nsky blue\nsea green\n"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        const char *q = tmp_path(dir, bad[k].name);
        write_text(q, bad[k].text);
        tsr_status st = tsr_heightfield_load(q, NULL, NULL, &hf, &err);
        CHECK_MSG(st != TSR_OK && hf == NULL, "%s loaded", bad[k].name);
        CHECK_MSG(strstr(err.message, bad[k].name) != NULL, "%s: %s", bad[k].name, err.message);
    }
}

/* Web Mercator's y to latitude (degrees), on its sphere. */
static double mercator_lat(double y) { return (2 * atan(exp(y / 6378137.0)) - PI / 2) * 180 / PI; }

TEST(data_real_geotiffs)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    const char *files[] = {"valid_raster-float32.tif", "egm84-epsg3857-float32.tif"};
    for (int k = 0; k < 2; k++) {
        char p[5000];
        snprintf(p, sizeof p, "%s/terrain/%s", data, files[k]);
        tsr_heightfield *hf = NULL;
        tsr_error err = {0};
        CHECK_MSG(tsr_heightfield_load(p, NULL, NULL, &hf, &err) == TSR_OK, "%s", err.message);
        const tsr_georef *g = tsr_heightfield_georef(hf);
        CHECK_MSG(g && g->crs == TSR_CRS_PROJECTED && strstr(g->crs_name, "Pseudo-Mercator"), "%s",
                  g ? g->crs_name : "(none)");
        CHECK(g->has_transform && g->has_nodata && g->has_spacing && g->pixel[0] > 0 && g->pixel[1] < 0);
        /* Web Mercator's metres are the ground's times 1 / cos(latitude):
         * at the middle row's latitude, a pixel is |pixel| cos(lat) on the
         * ground (on the sphere; the ellipsoid moves it by under 1 %:
         * 0.67 % along the meridian at the equator) */
        double lat = mercator_lat(g->origin[1] + 0.5 * (tsr_heightfield_height(hf) - 1) * g->pixel[1]);
        double e = g->pixel[0] * cos(lat * PI / 180);
        CHECK(!g->spacing_crs && g->spacing[0] == g->ground[0] && g->spacing[1] == g->ground[1]);
        CHECK_MSG(fabs(g->spacing[0] / e - 1) < 1e-2 && fabs(g->spacing[1] / e - 1) < 1e-2,
                  "%s: %.6f x %.6f against %.6f (latitude %.3f)", files[k], g->spacing[0], g->spacing[1], e, lat);
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        /* valid_raster writes its no-data as -FLT_MAX and names it */
        if (k == 0)
            CHECK(g->nodata == -3.4028234663852886e38 && st.nodata > 0 && st.valid > 0);
        tsr_heightfield_destroy(hf);
    }
}

TEST_MAIN(T(geotiff_utm_georef_and_nodata), T(geotiff_int16_scale_offset_and_nodata), T(srtm_hgt_written_by_hand), T(esri_ascii_grid_written_by_hand),
          T(data_real_geotiffs))
