/* shade.c: normal map and hillshade images of a heightfield.
 *
 * The hillshade is the Lambertian model of cartographic relief shading
 * (Yoëli 1965; Horn 1981, "Hill shading and the reflectance map", Proc.
 * IEEE 69(1)) in the form GDAL's gdaldem uses, with the normals of
 * tsr_heightfield_normal_at (central differences) instead of Horn's 3x3
 * gradient, so the two images and the grid mesh's normals agree. */
#include "terrain/shade.h"
#include "terrain_internal.h"

#include <math.h>
#include <string.h>
#include <strings.h>

static tsr_status check_hf(const tsr_heightfield *hf, const char *path, tsr_error *err)
{
    if (!path || !*path)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "shade: no output path");
    if (!hf || !hf->data)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: no heightfield", path);
    if (!(hf->dx > 0) || !(hf->dy > 0) || !isfinite(hf->dx) || !isfinite(hf->dy) || !isfinite(hf->dz))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: spacing must be positive and finite (dx %g, dy %g, dz %g)",
                             path, hf->dx, hf->dy, hf->dz);
    return TSR_OK;
}

/* [-1, 1] onto 0..255, nearest. */
static uint8_t encode_unit(double v)
{
    double q = floor((v * 0.5 + 0.5) * 255.0 + 0.5);
    return (uint8_t)(q < 0 ? 0 : q > 255 ? 255 : q);
}

/* The window of the heightfield an image covers. */
typedef struct shade_window {
    const tsr_heightfield *hf;
    uint32_t x, y, w, h;
} shade_window;

/* Checks the window (inside the heightfield, not empty). */
static tsr_status check_window(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w, uint32_t h,
                               const char *path, tsr_error *err)
{
    if (w == 0 || h == 0 || x >= hf->width || y >= hf->height || w > hf->width - x || h > hf->height - y)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: window %u,%u,%u,%u is not inside the %ux%u heightfield",
                             path, x, y, w, h, hf->width, hf->height);
    return TSR_OK;
}

/* Rows y0 .. y1 - 1 of the normal map: RGB, no-data black. */
static void normal_rows(void *user, uint32_t y0, uint32_t y1, uint8_t *px)
{
    const shade_window *win = user;
    const tsr_heightfield *hf = win->hf;
    for (uint32_t r = y0; r < y1; r++)
        for (uint32_t i = 0; i < win->w; i++) {
            uint32_t c = win->x + i, hr = win->y + r;
            uint8_t *p = px + 3 * ((size_t)(r - y0) * win->w + i);
            if (isnan(hf->data[(size_t)hr * hf->width + c])) {
                p[0] = p[1] = p[2] = 0;
                continue;
            }
            float n[3];
            tsr_heightfield_normal_at(hf, c, hr, n);
            p[0] = encode_unit(n[0]);
            p[1] = encode_unit(-n[1]); /* north is -y */
            p[2] = encode_unit(n[2]);
        }
}

tsr_status tsr_heightfield_normal_map(const tsr_heightfield *hf, const char *path, tsr_error *err)
{
    tsr_status s = check_hf(hf, path, err);
    if (s != TSR_OK)
        return s;
    return tsr_heightfield_normal_map_window(hf, 0, 0, hf->width, hf->height, path, err);
}

tsr_status tsr_heightfield_normal_map_window(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w,
                                             uint32_t h, const char *path, tsr_error *err)
{
    tsr_status s = check_hf(hf, path, err);
    if (s == TSR_OK)
        s = check_window(hf, x, y, w, h, path, err);
    if (s != TSR_OK)
        return s;
    shade_window win = {hf, x, y, w, h};
    return tsr_image_save_u8_rows(path, w, h, 3, normal_rows, &win, err);
}

typedef struct shade_user {
    shade_window win;
    double le, ln, lu; /* the light: east, north, up */
    uint32_t channels; /* 1: grey; 2: grey and alpha (0 at no-data) */
} shade_user;

/* Rows y0 .. y1 - 1 of the hillshade: grey (no-data black), and alpha
 * (no-data 0, else 255) with two channels. */
static void shade_rows(void *user, uint32_t y0, uint32_t y1, uint8_t *px)
{
    const shade_user *u = user;
    const tsr_heightfield *hf = u->win.hf;
    uint32_t w = u->win.w, nc = u->channels;
    for (uint32_t r = y0; r < y1; r++)
        for (uint32_t i = 0; i < w; i++) {
            uint32_t c = u->win.x + i, hr = u->win.y + r;
            uint8_t *p = px + nc * ((size_t)(r - y0) * w + i);
            if (isnan(hf->data[(size_t)hr * hf->width + c])) {
                p[0] = 0;
                if (nc == 2)
                    p[1] = 0;
                continue;
            }
            float n[3];
            tsr_heightfield_normal_at(hf, c, hr, n);
            double d = n[0] * u->le + (-n[1]) * u->ln + n[2] * u->lu;
            double q = floor(255.0 * (d > 0 ? d : 0) + 0.5);
            p[0] = (uint8_t)(q > 255 ? 255 : q);
            if (nc == 2)
                p[1] = 255;
        }
}

/* Whether path's extension names a format that keeps grey and alpha. */
static bool keeps_grey_alpha(const char *path)
{
    const char *dot = strrchr(path, '.');
    if (!dot || strchr(dot, '/'))
        return false;
    static const char *const ext[] = {".png", ".tif", ".tiff", ".exr"};
    for (size_t k = 0; k < sizeof ext / sizeof ext[0]; k++)
        if (!strcasecmp(dot, ext[k]))
            return true;
    return false;
}

tsr_status tsr_heightfield_hillshade(const tsr_heightfield *hf, const char *path, double azimuth_deg,
                                     double altitude_deg, tsr_error *err)
{
    tsr_status s = check_hf(hf, path, err);
    if (s != TSR_OK)
        return s;
    return tsr_heightfield_hillshade_window(hf, 0, 0, hf->width, hf->height, path, azimuth_deg, altitude_deg, err);
}

tsr_status tsr_heightfield_hillshade_window(const tsr_heightfield *hf, uint32_t x, uint32_t y, uint32_t w,
                                            uint32_t h, const char *path, double azimuth_deg, double altitude_deg,
                                            tsr_error *err)
{
    tsr_status s = check_hf(hf, path, err);
    if (s == TSR_OK)
        s = check_window(hf, x, y, w, h, path, err);
    if (s != TSR_OK)
        return s;
    if (isnan(azimuth_deg))
        azimuth_deg = TSR_HILLSHADE_AZIMUTH;
    if (isnan(altitude_deg))
        altitude_deg = TSR_HILLSHADE_ALTITUDE;
    if (!isfinite(azimuth_deg))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: sun azimuth %g is not finite", path, azimuth_deg);
    if (!(altitude_deg >= 0 && altitude_deg <= 90))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: sun altitude %g is outside 0..90 degrees", path, altitude_deg);
    const double deg = 3.14159265358979323846 / 180.0;
    double az = fmod(azimuth_deg, 360.0) * deg, alt = altitude_deg * deg;
    shade_user u = {{hf, x, y, w, h}, cos(alt) * sin(az), cos(alt) * cos(az), sin(alt), 1};
    if (keeps_grey_alpha(path))
        for (uint32_t r = y; r < y + h && u.channels == 1; r++)
            for (uint32_t c = x; c < x + w && u.channels == 1; c++)
                u.channels = isnan(hf->data[(size_t)r * hf->width + c]) ? 2 : 1;
    return tsr_image_save_u8_rows(path, w, h, u.channels, shade_rows, &u, err);
}
