/* gdal_io.c: GIS rasters through GDAL's C API: the georeferencing and
 * no-data value of the GeoTIFFs OpenImageIO reads (it skips those tags),
 * and whole heightfields in the GIS formats it does not read. Part of the
 * I/O module (io_module.h), with the module's one exported symbol. */
#include "terrain/io_module.h"

#include <ctype.h>
#include <float.h>
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <string.h>

#include <cpl_conv.h>
#include <cpl_error.h>
#include <gdal.h>
#include <gdal_frmts.h>
#include <ogr_srs_api.h>
#include <tiffio.h>

static pthread_once_t registered = PTHREAD_ONCE_INIT;

static void register_drivers(void)
{
    /* a scale, offset, no-data value or CRS kept in a .aux.xml beside an
     * input applies (GDAL writes one only for what a program changes or
     * computes there, and nothing here does: no sidecar appears beside an
     * input that had none); a bounded block cache (the whole raster is
     * read once, straight into the samples) */
    CPLSetConfigOption("GDAL_PAM_ENABLED", "YES");
    GDALSetCacheMax64((GIntBig)64 << 20);
    GDALRegister_GTiff();
    GDALRegister_SRTMHGT();
    GDALRegister_AAIGrid();
    GDALRegister_EHdr();
    GDALRegister_HFA();
    GDALRegister_USGSDEM();
    GDALRegister_BT();
    GDALRegister_XYZ();
}

/* libtiff's error and warning handlers are process-wide, and GDAL's GTiff
 * driver sets its own the first time it is used: every later TIFF that
 * OpenImageIO writes then sent libtiff's messages through GDAL to stderr
 * ("ERROR 1: TIFFSetField: ... Unknown tag 306" for the EXIF directory it
 * tries, a normal step that OpenImageIO's own handler keeps quiet). Each
 * GDAL call here restores the handlers it found (leave_gdal): GDAL's
 * messages are held back anyway (open_quiet). */
typedef struct tiff_handlers {
    TIFFErrorHandler error, warning;
} tiff_handlers;

static tiff_handlers enter_gdal(void)
{
    tiff_handlers t;
    t.error = TIFFSetErrorHandler(NULL);
    TIFFSetErrorHandler(t.error);
    t.warning = TIFFSetWarningHandler(NULL);
    TIFFSetWarningHandler(t.warning);
    return t;
}

static void leave_gdal(tiff_handlers t)
{
    TIFFSetErrorHandler(t.error);
    TIFFSetWarningHandler(t.warning);
}

/* Opens path read-only with GDAL's messages held back (the caller pops
 * the handler); NULL when no registered driver takes it. */
static GDALDatasetH open_quiet(const char *path)
{
    pthread_once(&registered, register_drivers);
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
    return GDALOpenEx(path, GDAL_OF_RASTER | GDAL_OF_READONLY, NULL, NULL, NULL);
}

static void lower_copy(char *dst, size_t cap, const char *a, const char *b)
{
    snprintf(dst, cap, "%s%s%s", a, b ? " " : "", b ? b : "");
    for (char *p = dst; *p; p++)
        *p = (char)tolower((unsigned char)*p);
}

/* Metres per radian of longitude and of latitude at latitude phi on the
 * ellipsoid of semi-major axis a and flattening f: the radii of curvature
 * in the prime vertical (N cos phi) and in the meridian (M). */
static void metres_per_radian(double a, double f, double phi, double *lon, double *lat)
{
    double e2 = f * (2 - f), s = sin(phi), w = 1 - e2 * s * s;
    *lon = a / sqrt(w) * cos(phi);
    *lat = a * (1 - e2) / (w * sqrt(w));
}

/* Ground lengths, in metres, of one pixel step in x and in y from the
 * point (x, y) of the CRS: the three points taken to longitude and
 * latitude (through GDAL's transformation where the CRS is projected) and
 * measured on the ellipsoid's local radii, so the projection's own scale
 * (Web Mercator's 1 / cos(latitude), say) is taken out. */
typedef struct ground {
    OGRCoordinateTransformationH ct; /* NULL: the CRS is geographic */
    double rad, a, f;                /* radians per angular unit; ellipsoid */
} ground;

static bool ground_step(const ground *gr, double x, double y, double px, double py, double out[2])
{
    double X[3] = {x, x + px, x}, Y[3] = {y, y, y + py}, Z[3] = {0, 0, 0};
    int ok[3] = {1, 1, 1};
    if (gr->ct && !OCTTransformEx(gr->ct, 3, X, Y, Z, ok))
        return false;
    for (int k = 0; k < 3; k++)
        if (!ok[k] || !isfinite(X[k]) || !isfinite(Y[k]) || fabs(Y[k] * gr->rad) >= 0.5 * acos(-1.0))
            return false;
    double lon, lat;
    metres_per_radian(gr->a, gr->f, Y[0] * gr->rad, &lon, &lat);
    for (int k = 1; k < 3; k++) {
        double dl = remainder((X[k] - X[0]) * gr->rad, 2 * acos(-1.0)), dp = (Y[k] - Y[0]) * gr->rad;
        out[k - 1] = hypot(dl * lon, dp * lat);
    }
    return out[0] > 0 && out[1] > 0;
}

/* The ground spacing at the raster's middle, approximate where it differs
 * by more than 0.1 % at a corner (a geographic raster, or a projection's
 * scale changing across it). */
static void ground_spacing(OGRSpatialReferenceH s, uint32_t w, uint32_t h, tsr_georef *g)
{
    ground gr = {NULL, 0, 0, 0};
    OGRSpatialReferenceH geog = NULL;
    OGRErr e1 = OGRERR_NONE, e2 = OGRERR_NONE;
    double invf;
    if (g->crs == TSR_CRS_PROJECTED) {
        geog = OSRCloneGeogCS(s);
        if (!geog)
            return;
        OSRSetAxisMappingStrategy(geog, OAMS_TRADITIONAL_GIS_ORDER);
        gr.ct = OCTNewCoordinateTransformation(s, geog);
        gr.rad = OSRGetAngularUnits(geog, NULL);
    } else {
        gr.rad = OSRGetAngularUnits(s, NULL);
    }
    gr.a = OSRGetSemiMajor(s, &e1);
    invf = OSRGetInvFlattening(s, &e2);
    gr.f = invf > 0 ? 1 / invf : 0;
    double mid[2], corner[2];
    if ((g->crs == TSR_CRS_GEOGRAPHIC || gr.ct) && e1 == OGRERR_NONE && e2 == OGRERR_NONE && gr.rad > 0 &&
        gr.a > 0 && ground_step(&gr, g->origin[0] + 0.5 * (w - 1.0) * g->pixel[0],
                                g->origin[1] + 0.5 * (h - 1.0) * g->pixel[1], g->pixel[0], g->pixel[1], mid)) {
        g->spacing[0] = g->ground[0] = mid[0];
        g->spacing[1] = g->ground[1] = mid[1];
        g->has_spacing = true;
        bool at_corner = ground_step(&gr, g->origin[0], g->origin[1], g->pixel[0], g->pixel[1], corner);
        g->spacing_approx = !at_corner || fabs(corner[0] / mid[0] - 1) > 1e-3 || fabs(corner[1] / mid[1] - 1) > 1e-3;
        /* a projection near true scale over the raster: its own metres */
        double lin = g->crs == TSR_CRS_PROJECTED ? OSRGetLinearUnits(s, NULL) : 0;
        double cx = fabs(g->pixel[0]) * lin, cy = fabs(g->pixel[1]) * lin;
        if (lin > 0 && at_corner && fabs(mid[0] / cx - 1) <= 0.01 && fabs(mid[1] / cy - 1) <= 0.01 &&
            fabs(corner[0] / cx - 1) <= 0.01 && fabs(corner[1] / cy - 1) <= 0.01) {
            g->spacing[0] = cx;
            g->spacing[1] = cy;
            g->spacing_crs = true;
        }
    }
    if (gr.ct)
        OCTDestroyCoordinateTransformation(gr.ct);
    if (geog)
        OSRRelease(geog);
}

static void fill_georef(GDALDatasetH d, uint32_t w, uint32_t h, tsr_georef *g)
{
    memset(g, 0, sizeof *g);
    g->z_scale = 1;
    double gt[6];
    bool have_gt = GDALGetGeoTransform(d, gt) == CE_None;
    g->rotated = have_gt && (gt[2] != 0 || gt[4] != 0);
    if (have_gt && gt[2] == 0 && gt[4] == 0 && gt[1] != 0 && gt[5] != 0 &&
        isfinite(gt[0]) && isfinite(gt[1]) && isfinite(gt[3]) && isfinite(gt[5])) {
        g->has_transform = true;
        g->pixel[0] = gt[1];
        g->pixel[1] = gt[5];
        /* GDAL's transform gives the corner of pixel (0, 0); Tessera's
         * samples sit at pixel centres */
        g->origin[0] = gt[0] + 0.5 * gt[1];
        g->origin[1] = gt[3] + 0.5 * gt[5];
    }
    OGRSpatialReferenceH s = GDALGetSpatialRef(d);
    if (s) {
        const char *name = OSRGetName(s);
        snprintf(g->crs_name, sizeof g->crs_name, "%s", name ? name : "unnamed");
        g->crs = OSRIsProjected(s) ? TSR_CRS_PROJECTED : OSRIsGeographic(s) ? TSR_CRS_GEOGRAPHIC : TSR_CRS_OTHER;
    }
    if (GDALGetRasterCount(d) >= 1) {
        GDALRasterBandH b = GDALGetRasterBand(d, 1);
        int has = 0;
        double nd = GDALGetRasterNoDataValue(b, &has);
        g->has_nodata = has != 0;
        g->nodata = has ? nd : 0;
        const char *u = GDALGetRasterUnitType(b);
        snprintf(g->z_unit, sizeof g->z_unit, "%s", u ? u : "");
        int has_scale = 0, has_offset = 0;
        double scale = GDALGetRasterScale(b, &has_scale), offset = GDALGetRasterOffset(b, &has_offset);
        g->z_scale = has_scale && isfinite(scale) && scale != 0 ? scale : 1;
        g->z_offset = has_offset && isfinite(offset) ? offset : 0;
    }
    if (!g->has_transform)
        return;
    if (g->crs == TSR_CRS_PROJECTED || g->crs == TSR_CRS_GEOGRAPHIC) {
        ground_spacing(s, w, h, g);
    } else if (g->crs == TSR_CRS_NONE) {
        g->spacing[0] = fabs(g->pixel[0]);
        g->spacing[1] = fabs(g->pixel[1]);
        g->has_spacing = true;
        g->spacing_unitless = true;
    }
}

bool tsr_io_gdal_georef(const char *path, uint32_t w, uint32_t h, tsr_georef *g)
{
    memset(g, 0, sizeof *g);
    g->z_scale = 1;
    tiff_handlers th = enter_gdal();
    GDALDatasetH d = open_quiet(path);
    if (d) {
        if ((uint32_t)GDALGetRasterXSize(d) == w && (uint32_t)GDALGetRasterYSize(d) == h)
            fill_georef(d, w, h, g);
        GDALClose(d);
    }
    CPLPopErrorHandler();
    leave_gdal(th);
    return g->has_transform || g->crs != TSR_CRS_NONE || g->has_nodata || g->z_scale != 1 || g->z_offset != 0;
}

static const char *gdal_message(const char *fallback)
{
    const char *m = CPLGetLastErrorMsg();
    return m && *m ? m : fallback;
}

static tsr_status read_dataset(GDALDatasetH d, const char *path, const tsr_allocator *alloc, uint64_t max_samples,
                               float **pixels, uint32_t *w, uint32_t *h, char format[64], tsr_georef *g,
                               tsr_error *err)
{
    int xs = GDALGetRasterXSize(d), ys = GDALGetRasterYSize(d);
    if (GDALGetRasterCount(d) < 1 || xs <= 0 || ys <= 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: the file holds no raster band", path);
    GDALRasterBandH b = GDALGetRasterBand(d, 1);
    GDALDataType t = GDALGetRasterDataType(b);
    lower_copy(format, 64, GDALGetDriverShortName(GDALGetDatasetDriver(d)), GDALGetDataTypeName(t));
    if (GDALDataTypeIsComplex(t))
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s: complex samples (%s) are not heights", path,
                             GDALGetDataTypeName(t));
    uint64_t W = (uint64_t)xs, H = (uint64_t)ys;
    if (W < TSR_HEIGHTFIELD_MIN_SIDE || H < TSR_HEIGHTFIELD_MIN_SIDE)
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s: raster is %llux%llu; a heightfield needs at least 2x2 samples",
                             path, (unsigned long long)W, (unsigned long long)H);
    if (W > TSR_HEIGHTFIELD_MAX_SIDE || H > TSR_HEIGHTFIELD_MAX_SIDE || W * H > max_samples)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE,
                             "%s: raster is %llux%llu; Tessera accepts at most %u per side and %llu samples", path,
                             (unsigned long long)W, (unsigned long long)H, TSR_HEIGHTFIELD_MAX_SIDE,
                             (unsigned long long)max_samples);
    size_t n = (size_t)(W * H);
    float *px = tsr_alloc(alloc, n * sizeof *px);
    if (!px)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %llux%llu samples", path,
                             (unsigned long long)W, (unsigned long long)H);
    /* in bands of rows, so a bad row is named */
    for (int y0 = 0; y0 < ys; y0 += 256) {
        int rows = ys - y0 < 256 ? ys - y0 : 256;
        if (GDALRasterIO(b, GF_Read, 0, y0, xs, rows, px + (size_t)y0 * (size_t)xs, xs, rows, GDT_Float32, 0, 0) !=
            CE_None) {
            tsr_free(alloc, px);
            return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: truncated or corrupt samples at row %d (%s)", path, y0,
                                 gdal_message("read failed"));
        }
    }
    fill_georef(d, (uint32_t)W, (uint32_t)H, g);
    *pixels = px;
    *w = (uint32_t)W;
    *h = (uint32_t)H;
    return TSR_OK;
}

tsr_status tsr_io_gdal_read(const char *path, const tsr_allocator *alloc, uint64_t max_samples, float **pixels,
                            uint32_t *w, uint32_t *h, char format[64], tsr_georef *g, tsr_error *err)
{
    *pixels = NULL;
    *w = *h = 0;
    format[0] = '\0';
    memset(g, 0, sizeof *g);
    tiff_handlers th = enter_gdal();
    GDALDatasetH d = open_quiet(path);
    tsr_status s;
    if (!d) {
        s = tsr_error_set(err, TSR_ERR_FORMAT, "%s: not a GIS raster Tessera can read (%s)", path,
                          gdal_message("unknown format"));
    } else {
        s = read_dataset(d, path, alloc, max_samples, pixels, w, h, format, g, err);
        GDALClose(d);
    }
    CPLPopErrorHandler();
    leave_gdal(th);
    return s;
}

__attribute__((visibility("default"))) const tsr_io_api *tsr_io_module_api(void);

const tsr_io_api *tsr_io_module_api(void)
{
    static const tsr_io_api api = {TSR_IO_MODULE_VERSION, sizeof(tsr_io_api),      tsr_io_image_read,
                                   tsr_io_image_write,    tsr_io_image_save_check, tsr_io_image_save_u8_rows,
                                   tsr_io_gdal_georef,    tsr_io_gdal_read,        tsr_atomic_remove_pending};
    return &api;
}
