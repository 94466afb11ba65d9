/* Normal maps and hillshades, read back through OpenImageIO and compared
 * with closed-form oracles: the exact normal of a plane, the exact central
 * (and one-sided) differences of a paraboloid, and GDAL's slope/aspect form
 * of the hillshade. */
#include "check.h"
#include "terrain/shade.h"
#include "terrain/terrain.h"
#include "terrain/terrain_internal.h" /* tsr_image_read, to read back */

#include <dirent.h>
#include <sys/stat.h>
#include <unistd.h>

static const char *tmp_path(const char *dir, const char *name)
{
    static char buf[8][1024];
    static int k;
    char *b = buf[k++ % 8];
    int n = snprintf(b, sizeof buf[0], "%s/%s", dir, name);
    if (n < 0 || (size_t)n >= sizeof buf[0])
        abort();
    return b;
}

/* Entries of dir other than . and .. */
static int dir_entries(const char *dir)
{
    DIR *d = opendir(dir);
    if (!d)
        return -1;
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d)))
        n += strcmp(e->d_name, ".") && strcmp(e->d_name, "..");
    closedir(d);
    return n;
}

static float *read_back(const char *path, uint32_t w, uint32_t h, uint32_t channels)
{
    float *px = NULL;
    tsr_image_info info;
    tsr_error err = {0};
    tsr_status s = tsr_image_read(path, NULL, (uint64_t)1 << 30, &px, &info, &err);
    CHECK_MSG(s == TSR_OK, "%s", err.message);
    if (s != TSR_OK)
        return NULL;
    CHECK(info.width == w && info.height == h && info.channels == channels);
    CHECK_MSG(!strcmp(info.type, "uint8"), "%s", info.type);
    return px;
}

static double enc(double v)
{
    return (v * 0.5 + 0.5) * 255.0;
}

/* A w x h heightfield of the world-space function f(x, y) = z, stored as
 * h = f / dz. */
static tsr_heightfield *make_hf(uint32_t w, uint32_t h, double dx, double dy, double dz,
                                double (*f)(double x, double y, const double *k), const double *k)
{
    tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
    tsr_heightfield_set_spacing(hf, dx, dy, dz);
    float *d = tsr_heightfield_data(hf);
    for (uint32_t r = 0; r < h; r++)
        for (uint32_t c = 0; c < w; c++)
            d[(size_t)r * w + c] = (float)(f(c * dx, r * dy, k) / dz);
    return hf;
}

static double plane(double x, double y, const double *k)
{
    return k[0] * x + k[1] * y + k[2];
}
static double paraboloid(double x, double y, const double *k)
{
    return k[0] * ((x - k[1]) * (x - k[1]) + (y - k[2]) * (y - k[2]));
}

/* Checks pixel i against the world normal of gradient (gx, gy). */
static void check_normal_px(const float *p, double gx, double gy, uint32_t c, uint32_t r)
{
    double len = sqrt(gx * gx + gy * gy + 1);
    double want[3] = {enc(-gx / len), enc(gy / len), enc(1 / len)}; /* east, north = -y, up */
    for (int j = 0; j < 3; j++)
        CHECK_MSG(fabs(p[j] - want[j]) <= 0.51, "pixel (%u, %u) channel %d: %g, want %g", c, r, j, p[j], want[j]);
}

TEST(plane_normal_map_exact)
{
    const char *dir = check_temp_dir();
    const double k[3] = {0.3, -0.7, 5};
    uint32_t w = 17, h = 13;
    tsr_heightfield *hf = make_hf(w, h, 2.0, 3.0, 0.5, plane, k);
    const char *names[] = {"n.png", "n.tif", "N.TIFF"};
    for (int f = 0; f < 3; f++) {
        const char *p = tmp_path(dir, names[f]);
        tsr_error err = {0};
        CHECK_MSG(tsr_heightfield_normal_map(hf, p, &err) == TSR_OK, "%s", err.message);
        float *px = read_back(p, w, h, 3);
        for (uint32_t i = 0; px && i < w * h; i++)
            check_normal_px(px + 3 * i, k[0], k[1], i % w, i / w);
        tsr_free(NULL, px);
    }
    CHECK(dir_entries(dir) == 3); /* no temporary left */
    tsr_heightfield_destroy(hf);
}

TEST(flat_normal_map_is_128_128_255)
{
    const char *dir = check_temp_dir();
    tsr_heightfield *hf = tsr_heightfield_create(4, 3, NULL);
    const char *p = tmp_path(dir, "flat.png");
    CHECK(tsr_heightfield_normal_map(hf, p, NULL) == TSR_OK);
    float *px = read_back(p, 4, 3, 3);
    for (int i = 0; px && i < 12; i++)
        CHECK(px[3 * i] == 128 && px[3 * i + 1] == 128 && px[3 * i + 2] == 255);
    tsr_free(NULL, px);
    tsr_heightfield_destroy(hf);
}

TEST(paraboloid_normal_map)
{
    /* f = s ((x-x0)^2 + (y-y0)^2): central differences are exact inside;
     * the one-sided ones at the borders are 2 s (x - x0) +- s dx. */
    const char *dir = check_temp_dir();
    const double k[3] = {0.02, 11.0, 7.5};
    const double dx = 1.5, dy = 1.0;
    uint32_t w = 15, h = 16;
    tsr_heightfield *hf = make_hf(w, h, dx, dy, 0.25, paraboloid, k);
    const char *p = tmp_path(dir, "para.png");
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_normal_map(hf, p, &err) == TSR_OK, "%s", err.message);
    float *px = read_back(p, w, h, 3);
    for (uint32_t r = 0; px && r < h; r++)
        for (uint32_t c = 0; c < w; c++) {
            double x = c * dx, y = r * dy;
            double gx = 2 * k[0] * (x - k[1]) + (c == 0 ? k[0] * dx : c == w - 1 ? -k[0] * dx : 0);
            double gy = 2 * k[0] * (y - k[2]) + (r == 0 ? k[0] * dy : r == h - 1 ? -k[0] * dy : 0);
            check_normal_px(px + 3 * ((size_t)r * w + c), gx, gy, c, r);
        }
    tsr_free(NULL, px);
    tsr_heightfield_destroy(hf);
}

TEST(nan_height_normal_map)
{
    const char *dir = check_temp_dir();
    const double k[3] = {-0.4, 0.25, 1};
    uint32_t w = 9, h = 7;
    tsr_heightfield *hf = make_hf(w, h, 1.0, 1.0, 1.0, plane, k);
    float *d = tsr_heightfield_data(hf);
    /* scattered no-data; sample (4, 3) keeps no horizontal neighbour */
    const uint32_t holes[][2] = {{0, 0}, {3, 3}, {5, 3}, {8, 6}, {2, 5}, {7, 1}};
    for (size_t i = 0; i < sizeof holes / sizeof holes[0]; i++)
        d[holes[i][1] * w + holes[i][0]] = NAN;
    const char *p = tmp_path(dir, "nan.png");
    tsr_error err = {0};
    CHECK_MSG(tsr_heightfield_normal_map(hf, p, &err) == TSR_OK, "%s", err.message);
    float *px = read_back(p, w, h, 3);
    for (uint32_t r = 0; px && r < h; r++)
        for (uint32_t c = 0; c < w; c++) {
            const float *q = px + 3 * ((size_t)r * w + c);
            if (isnan(d[r * w + c])) {
                CHECK(q[0] == 0 && q[1] == 0 && q[2] == 0);
                continue;
            }
            /* a direction with a valid neighbour on either side has the
             * exact slope (one-sided differences of a plane are exact);
             * with none, it counts as flat */
            bool hx = (c > 0 && !isnan(d[r * w + c - 1])) || (c + 1 < w && !isnan(d[r * w + c + 1]));
            bool hy = (r > 0 && !isnan(d[(r - 1) * w + c])) || (r + 1 < h && !isnan(d[(r + 1) * w + c]));
            CHECK(!(c == 4 && r == 3) || !hx);
            check_normal_px(q, hx ? k[0] : 0, hy ? k[1] : 0, c, r);
        }
    tsr_free(NULL, px);
    tsr_heightfield_destroy(hf);
}

/* GDAL's hillshade from slope and aspect (aspect: the compass direction the
 * slope faces, clockwise from north), for the plane z = a x + b y with
 * north = -y: an oracle written differently from the code's n . L. */
static double gdal_shade(double a, double b, double az_deg, double alt_deg)
{
    const double rad = 3.14159265358979323846 / 180;
    double de = a, dn = -b; /* dz/d east, dz/d north */
    double slope = atan(hypot(de, dn));
    double aspect = atan2(-de, -dn); /* downhill, as (east, north) -> clockwise from north */
    double v = sin(alt_deg * rad) * cos(slope) + cos(alt_deg * rad) * sin(slope) * cos(az_deg * rad - aspect);
    return 255 * (v > 0 ? v : 0);
}

static float *shade_plane(const char *dir, double a, double b, double az, double alt, uint32_t w, uint32_t h)
{
    const double k[3] = {a, b, 10};
    tsr_heightfield *hf = make_hf(w, h, 2.0, 1.0, 0.1, plane, k);
    const char *p = tmp_path(dir, "hs.png");
    tsr_error err = {0};
    tsr_status s = tsr_heightfield_hillshade(hf, p, az, alt, &err);
    CHECK_MSG(s == TSR_OK, "%s", err.message);
    tsr_heightfield_destroy(hf);
    return s == TSR_OK ? read_back(p, w, h, 1) : NULL;
}

static void check_all(const float *px, uint32_t n, double want, double tol, const char *what)
{
    for (uint32_t i = 0; px && i < n; i++)
        CHECK_MSG(fabs(px[i] - want) <= tol, "%s: pixel %u is %g, want %g", what, i, px[i], want);
}

TEST(hillshade_flat_facing_and_away)
{
    const char *dir = check_temp_dir();
    const double rad = 3.14159265358979323846 / 180;
    double alts[] = {45, 30, 60, 90, 0};
    for (int i = 0; i < 5; i++) {
        float *px = shade_plane(dir, 0, 0, 123, alts[i], 6, 5);
        check_all(px, 30, 255 * sin(alts[i] * rad), 0.5 + 1e-6, "flat");
        tsr_free(NULL, px);
    }
    /* defaults (NAN): azimuth 315, altitude 45; flat is 255 sin 45 = 180 */
    float *px = shade_plane(dir, 0, 0, NAN, NAN, 6, 5);
    check_all(px, 30, 180, 0, "flat, defaults");
    tsr_free(NULL, px);
    /* facing the sun in the north-west (up-left in the image): rising to
     * the east (+x) and to the south (+y, down the image) */
    double t = 1 / tan(45 * rad);                /* slope angle 45 degrees... */
    double a = t * sqrt(0.5), b = t * sqrt(0.5); /* ...facing north-west */
    px = shade_plane(dir, a, b, NAN, NAN, 6, 5);
    check_all(px, 30, 255, 0, "facing the sun");
    tsr_free(NULL, px);
    px = shade_plane(dir, -1.5, -1.5, 315, 45, 6, 5);
    check_all(px, 30, 0, 0, "facing away");
    tsr_free(NULL, px);
}

TEST(hillshade_azimuth_convention)
{
    /* planes facing each way, suns from each way: against GDAL's formula;
     * a slope faces the sun when it rises away from it */
    const char *dir = check_temp_dir();
    const double slopes[][2] = {{0, 0.5}, {0, -0.5}, {0.5, 0}, {-0.5, 0}, {0.3, -0.8}, {-1.2, 0.4}};
    const double suns[][2] = {{0, 30}, {90, 30}, {180, 60}, {270, 20}, {315, 45}, {-45, 45}, {405, 50}};
    for (size_t s = 0; s < sizeof slopes / sizeof slopes[0]; s++)
        for (size_t l = 0; l < sizeof suns / sizeof suns[0]; l++) {
            float *px = shade_plane(dir, slopes[s][0], slopes[s][1], suns[l][0], suns[l][1], 5, 4);
            check_all(px, 20, gdal_shade(slopes[s][0], slopes[s][1], suns[l][0], suns[l][1]), 0.5 + 1e-4, "plane");
            tsr_free(NULL, px);
        }
    /* north is row 0: with the sun in the north, the slope rising toward
     * the bottom of the image (b > 0, facing up the image) is the lit one */
    float *n = shade_plane(dir, 0, 0.5, 0, 30, 5, 4), *s = shade_plane(dir, 0, -0.5, 0, 30, 5, 4);
    CHECK(n && s && n[0] > s[0] + 50);
    tsr_free(NULL, n);
    tsr_free(NULL, s);
    /* east is +column: with the sun in the east, the slope rising toward
     * the left (a < 0) is lit */
    float *e = shade_plane(dir, -0.5, 0, 90, 30, 5, 4), *wst = shade_plane(dir, 0.5, 0, 90, 30, 5, 4);
    CHECK(e && wst && e[0] > wst[0] + 50);
    tsr_free(NULL, e);
    tsr_free(NULL, wst);
}

/* No-data is black, as full shadow is, so where the format keeps it an
 * alpha channel tells them apart: 0 at no-data, 255 elsewhere. */
TEST(hillshade_nan_is_zero)
{
    const char *dir = check_temp_dir();
    tsr_heightfield *hf = tsr_heightfield_create(5, 4, NULL);
    float *d = tsr_heightfield_data(hf);
    d[7] = NAN;
    d[0] = NAN;
    const char *names[] = {"nan.tif", "nan.png"};
    for (int f = 0; f < 2; f++) {
        const char *p = tmp_path(dir, names[f]);
        CHECK(tsr_heightfield_hillshade(hf, p, 315, 45, NULL) == TSR_OK);
        float *px = read_back(p, 5, 4, 2);
        for (int i = 0; px && i < 20; i++) {
            bool hole = i == 7 || i == 0;
            CHECK_MSG(px[2 * i] == (hole ? 0 : 180) && px[2 * i + 1] == (hole ? 0 : 255), "%s pixel %d: %g %g",
                      names[f], i, px[2 * i], px[2 * i + 1]);
        }
        tsr_free(NULL, px);
    }
    tsr_heightfield_destroy(hf);
}

/* A window's images are the whole heightfield's pixels there (a window
 * inside: its border normals use the samples beyond it; one at the
 * corner), checked against a crop of the whole image; the hillshade gets
 * its alpha channel only where the window holds no-data. */
TEST(window_images_are_crops)
{
    const char *dir = check_temp_dir();
    const double k[3] = {0.02, 9, 6};
    uint32_t w = 23, h = 19;
    tsr_heightfield *hf = make_hf(w, h, 1.5, 1.0, 0.25, paraboloid, k);
    tsr_heightfield_data(hf)[17 * w + 20] = NAN; /* inside the second window only */
    const char *fn = tmp_path(dir, "fn.png"), *fh = tmp_path(dir, "fh.png");
    CHECK(tsr_heightfield_normal_map(hf, fn, NULL) == TSR_OK);
    CHECK(tsr_heightfield_hillshade(hf, fh, 315, 45, NULL) == TSR_OK);
    float *full_n = read_back(fn, w, h, 3), *full_h = read_back(fh, w, h, 2);
    const uint32_t wins[2][4] = {{4, 3, 9, 7}, {14, 10, 9, 9}};
    for (int k2 = 0; k2 < 2 && full_n && full_h; k2++) {
        const uint32_t *v = wins[k2];
        const char *wn = tmp_path(dir, "wn.png"), *wh = tmp_path(dir, "wh.png");
        tsr_error err = {0};
        CHECK_MSG(tsr_heightfield_normal_map_window(hf, v[0], v[1], v[2], v[3], wn, &err) == TSR_OK, "%s",
                  err.message);
        CHECK_MSG(tsr_heightfield_hillshade_window(hf, v[0], v[1], v[2], v[3], wh, NAN, NAN, &err) == TSR_OK, "%s",
                  err.message);
        uint32_t hc = k2 == 0 ? 1 : 2; /* alpha where the window has no-data */
        float *pn = read_back(wn, v[2], v[3], 3), *ph = read_back(wh, v[2], v[3], hc);
        int bad = 0;
        for (uint32_t j = 0; pn && ph && j < v[3]; j++)
            for (uint32_t i = 0; i < v[2]; i++) {
                size_t f = (size_t)(v[1] + j) * w + v[0] + i, q = (size_t)j * v[2] + i;
                for (int c = 0; c < 3; c++)
                    bad += pn[3 * q + c] != full_n[3 * f + c];
                bad += ph[hc * q] != full_h[2 * f];
                if (hc == 2)
                    bad += ph[2 * q + 1] != full_h[2 * f + 1];
            }
        CHECK_MSG(bad == 0, "window %u,%u,%u,%u: %d values differ from the whole image's", v[0], v[1], v[2], v[3],
                  bad);
        tsr_free(NULL, pn);
        tsr_free(NULL, ph);
    }
    tsr_free(NULL, full_n);
    tsr_free(NULL, full_h);
    const char *bad_path = tmp_path(dir, "out.png");
    CHECK(tsr_heightfield_hillshade_window(hf, 20, 0, 4, 5, bad_path, 315, 45, NULL) == TSR_ERR_ARGUMENT);
    CHECK(tsr_heightfield_normal_map_window(hf, 0, 0, 0, 5, bad_path, NULL) == TSR_ERR_ARGUMENT);
    tsr_heightfield_destroy(hf);
}

/* ---- Failures leave nothing behind ----------------------------------------- */

static void check_fails(const tsr_heightfield *hf, const char *path, bool hillshade, double az, double alt,
                        tsr_status want, const char *word)
{
    tsr_error err = {0};
    tsr_status s =
        hillshade ? tsr_heightfield_hillshade(hf, path, az, alt, &err) : tsr_heightfield_normal_map(hf, path, &err);
    CHECK_MSG(s == want, "%s: status %d (%s)", path, (int)s, err.message);
    CHECK_MSG(strstr(err.message, path) != NULL, "message \"%s\" does not name the path", err.message);
    CHECK_MSG(strstr(err.message, word) != NULL, "message \"%s\" lacks \"%s\"", err.message, word);
    struct stat st;
    CHECK(stat(path, &st) != 0);
}

TEST(bad_paths_and_arguments)
{
    const char *dir = check_temp_dir();
    tsr_heightfield *hf = tsr_heightfield_create(3, 3, NULL);
    check_fails(hf, tmp_path(dir, "no/such/folder/n.png"), false, 0, 0, TSR_ERR_IO, "No such file");
    check_fails(hf, tmp_path(dir, "n.xyz"), false, 0, 0, TSR_ERR_UNSUPPORTED, ".xyz");
    check_fails(hf, tmp_path(dir, "noextension"), true, 0, 45, TSR_ERR_UNSUPPORTED, "extension");
    check_fails(hf, tmp_path(dir, "h.png"), true, 0, 95, TSR_ERR_ARGUMENT, "altitude");
    check_fails(hf, tmp_path(dir, "h.png"), true, 0, -1, TSR_ERR_ARGUMENT, "altitude");
    check_fails(hf, tmp_path(dir, "h.png"), true, INFINITY, 45, TSR_ERR_ARGUMENT, "azimuth");
    tsr_heightfield_set_spacing(hf, 0, 1, 1);
    check_fails(hf, tmp_path(dir, "h.png"), true, 0, 45, TSR_ERR_ARGUMENT, "spacing");
    tsr_heightfield_set_spacing(hf, 1, 1, 1);
    CHECK(tsr_heightfield_normal_map(NULL, tmp_path(dir, "x.png"), NULL) == TSR_ERR_ARGUMENT);
    CHECK(tsr_heightfield_hillshade(hf, NULL, 0, 45, NULL) == TSR_ERR_ARGUMENT);
    CHECK(dir_entries(dir) == 0);

    /* an unwritable folder (not testable as root, who may write anyway) */
    char ro[512];
    if (snprintf(ro, sizeof ro, "%s/ro", dir) >= (int)sizeof ro)
        abort();
    mkdir(ro, 0555);
    if (access(ro, W_OK) != 0) {
        check_fails(hf, tmp_path(ro, "n.png"), false, 0, 0, TSR_ERR_IO, "cannot write");
        CHECK(dir_entries(ro) == 0);
    }
    chmod(ro, 0755);
    tsr_heightfield_destroy(hf);
}

/* Images made a band of rows at a time (tsr_image_save_u8_rows): taller
 * than several bands, the last one partial, every pixel lands where it
 * belongs (RGB: two channels would be grey and alpha, which readers may
 * unpremultiply); so does a tall normal map's. */
static void pattern_rows(void *user, uint32_t y0, uint32_t y1, uint8_t *rows)
{
    const uint32_t *w = user;
    for (uint32_t r = y0; r < y1; r++)
        for (uint32_t c = 0; c < *w; c++)
            for (uint32_t k = 0; k < 3; k++)
                rows[((size_t)(r - y0) * *w + c) * 3 + k] = (uint8_t)((r * 7 + c * 3 + k * 101) & 255);
}

TEST(images_in_bands_of_rows)
{
    const char *dir = check_temp_dir();
    uint32_t w = 9, h = 3 * TSR_IMAGE_BAND_ROWS + 5;
    const char *p = tmp_path(dir, "bands.png");
    tsr_error err = {0};
    CHECK_MSG(tsr_image_save_u8_rows(p, w, h, 3, pattern_rows, &w, &err) == TSR_OK, "%s", err.message);
    float *px = read_back(p, w, h, 3);
    uint32_t wrong = 0;
    for (uint32_t r = 0; px && r < h; r++)
        for (uint32_t c = 0; c < w; c++)
            for (uint32_t k = 0; k < 3; k++)
                wrong += px[((size_t)r * w + c) * 3 + k] != (float)((r * 7 + c * 3 + k * 101) & 255);
    CHECK_MSG(px && wrong == 0, "%u pixels wrong", wrong);
    tsr_free(NULL, px);
    const double k[3] = {0.3, -0.7, 5};
    tsr_heightfield *hf = make_hf(5, h, 2.0, 3.0, 0.5, plane, k);
    p = tmp_path(dir, "tall.png");
    CHECK_MSG(tsr_heightfield_normal_map(hf, p, &err) == TSR_OK, "%s", err.message);
    px = read_back(p, 5, h, 3);
    for (uint32_t i = 0; px && i < 5 * h; i++)
        check_normal_px(px + 3 * i, k[0], k[1], i % 5, i / 5);
    tsr_free(NULL, px);
    tsr_heightfield_destroy(hf);
    CHECK(dir_entries(dir) == 2); /* no temporary left */
}

TEST_MAIN(T(plane_normal_map_exact), T(flat_normal_map_is_128_128_255), T(paraboloid_normal_map),
          T(nan_height_normal_map), T(hillshade_flat_facing_and_away), T(hillshade_azimuth_convention),
          T(hillshade_nan_is_zero), T(window_images_are_crops), T(bad_paths_and_arguments),
          T(images_in_bands_of_rows))
