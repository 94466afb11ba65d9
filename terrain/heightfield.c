/* heightfield.c: the heightfield container, loading (image bridge or raw
 * samples), checks of the values, statistics and saving. */
#include "terrain_internal.h"

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

static bool size_ok(uint64_t w, uint64_t h)
{
    return w >= TSR_HEIGHTFIELD_MIN_SIDE && h >= TSR_HEIGHTFIELD_MIN_SIDE && w <= TSR_HEIGHTFIELD_MAX_SIDE &&
           h <= TSR_HEIGHTFIELD_MAX_SIDE && w * h <= TSR_HEIGHTFIELD_MAX_SAMPLES;
}

/* A heightfield whose samples are `data` (tsr_alloc'd with alloc; owned
 * from now on), or NULL when out of memory (data not freed). */
static tsr_heightfield *adopt(uint32_t width, uint32_t height, float *data, const tsr_allocator *alloc)
{
    tsr_heightfield *hf = tsr_alloc(alloc, sizeof *hf);
    if (!hf)
        return NULL;
    memset(hf, 0, sizeof *hf);
    if (alloc)
        hf->alloc = *alloc;
    hf->width = width;
    hf->height = height;
    hf->dx = hf->dy = hf->dz = 1;
    hf->data = data;
    return hf;
}

tsr_heightfield *tsr_heightfield_create(uint32_t width, uint32_t height, const tsr_allocator *alloc)
{
    if (!size_ok(width, height))
        return NULL;
    size_t n = (size_t)width * height;
    float *data = tsr_alloc(alloc, n * sizeof(float));
    tsr_heightfield *hf = data ? adopt(width, height, data, alloc) : NULL;
    if (!hf) {
        tsr_free(alloc, data);
        return NULL;
    }
    memset(hf->data, 0, n * sizeof(float));
    snprintf(hf->source_format, sizeof hf->source_format, "memory");
    return hf;
}

void tsr_heightfield_destroy(tsr_heightfield *hf)
{
    if (!hf)
        return;
    tsr_allocator a = hf->alloc;
    const tsr_allocator *ap = a.realloc ? &a : NULL;
    tsr_free(ap, hf->data);
    tsr_free(ap, hf);
}

uint32_t tsr_heightfield_width(const tsr_heightfield *hf) { return hf->width; }
uint32_t tsr_heightfield_height(const tsr_heightfield *hf) { return hf->height; }
float *tsr_heightfield_data(tsr_heightfield *hf) { return hf->data; }
const float *tsr_heightfield_cdata(const tsr_heightfield *hf) { return hf->data; }
const char *tsr_heightfield_source_format(const tsr_heightfield *hf) { return hf->source_format; }
const tsr_georef *tsr_heightfield_georef(const tsr_heightfield *hf) { return hf->has_georef ? &hf->georef : NULL; }

void tsr_heightfield_set_spacing(tsr_heightfield *hf, double dx, double dy, double dz)
{
    hf->dx = dx;
    hf->dy = dy;
    hf->dz = dz;
}

void tsr_heightfield_spacing(const tsr_heightfield *hf, double *dx, double *dy, double *dz)
{
    if (dx)
        *dx = hf->dx;
    if (dy)
        *dy = hf->dy;
    if (dz)
        *dz = hf->dz;
}

tsr_raw_type tsr_raw_type_parse(const char *s)
{
    if (!strcasecmp(s, "u16") || !strcasecmp(s, "uint16"))
        return TSR_RAW_U16;
    if (!strcasecmp(s, "i16") || !strcasecmp(s, "int16"))
        return TSR_RAW_I16;
    if (!strcasecmp(s, "f32") || !strcasecmp(s, "float32") || !strcasecmp(s, "float"))
        return TSR_RAW_F32;
    return TSR_RAW_NONE;
}

/* The eight lanes' minima, maxima, sums and no-data counts over the
 * first n - n % 8 samples of d (lane k: the samples i = k mod 8), without
 * branches: a NaN fails both comparisons and adds 0. In vectors of eight
 * floats (one AVX register in the AVX2 build, two SSE registers
 * otherwise), each lane the scalar expression, so either build gives the
 * same sums to the bit. */
/* Sample v into lane k. */
static inline void stats_add(float v, int k, float mn8[8], float mx8[8], double sum8[8], uint64_t nan8[8])
{
    bool ok = v == v;
    mn8[k] = v < mn8[k] ? v : mn8[k];
    mx8[k] = v > mx8[k] ? v : mx8[k];
    sum8[k] += ok ? (double)v : 0.0;
    nan8[k] += !ok;
}

#ifdef TSR_VECTORS
static TSR_ALWAYS_INLINE void stats_lanes_body(const float *d, size_t n, float mn8[8], float mx8[8], double sum8[8],
                                               uint64_t nan8[8])
{
    tsr_v8f mn, mx;
    tsr_v4d s0, s1;
    memcpy(&mn, mn8, sizeof mn);
    memcpy(&mx, mx8, sizeof mx);
    memcpy(&s0, sum8, sizeof s0);
    memcpy(&s1, sum8 + 4, sizeof s1);
    size_t i = 0;
    while (i + 8 <= n) {
        /* no-data counts in 32-bit lanes, added up every 2^24 vectors */
        tsr_v8i cnt = {0, 0, 0, 0, 0, 0, 0, 0};
        for (size_t e = i + ((size_t)1 << 27) < n ? i + ((size_t)1 << 27) : n; i + 8 <= e; i += 8) {
            tsr_v8f v;
            memcpy(&v, d + i, sizeof v);
            tsr_v8i ok = v == v, lt = v < mn, gt = v > mx;
            mn = (tsr_v8f)(((tsr_v8i)v & lt) | ((tsr_v8i)mn & ~lt));
            mx = (tsr_v8f)(((tsr_v8i)v & gt) | ((tsr_v8i)mx & ~gt));
            cnt -= ~ok; /* (a lane's mask is -1 where NaN) */
            tsr_v8f z = (tsr_v8f)((tsr_v8i)v & ok);
            tsr_v4f lo4, hi4;
            memcpy(&lo4, &z, sizeof lo4);
            memcpy(&hi4, (const char *)&z + sizeof lo4, sizeof hi4);
            s0 += __builtin_convertvector(lo4, tsr_v4d);
            s1 += __builtin_convertvector(hi4, tsr_v4d);
        }
        for (int k = 0; k < 8; k++)
            nan8[k] += (uint64_t)cnt[k];
    }
    memcpy(mn8, &mn, sizeof mn);
    memcpy(mx8, &mx, sizeof mx);
    memcpy(sum8, &s0, sizeof s0);
    memcpy(sum8 + 4, &s1, sizeof s1);
}
#else
static void stats_lanes_body(const float *d, size_t n, float mn8[8], float mx8[8], double sum8[8], uint64_t nan8[8])
{
    for (size_t i = 0; i + 8 <= n; i += 8)
        for (int k = 0; k < 8; k++)
            stats_add(d[i + k], k, mn8, mx8, sum8, nan8);
}
#endif

#ifdef TSR_AVX2_DISPATCH
__attribute__((target("avx2"))) static void stats_lanes_avx2(const float *d, size_t n, float mn8[8], float mx8[8],
                                                             double sum8[8], uint64_t nan8[8])
{
    stats_lanes_body(d, n, mn8, mx8, sum8, nan8);
}
#endif

void tsr_heightfield_stats_compute(const tsr_heightfield *hf, tsr_heightfield_stats *st)
{
    memset(st, 0, sizeof *st);
    float mn8[8], mx8[8];
    double sum8[8];
    uint64_t nan8[8];
    for (int k = 0; k < 8; k++) {
        mn8[k] = INFINITY;
        mx8[k] = -INFINITY;
        sum8[k] = 0;
        nan8[k] = 0;
    }
    size_t n = (size_t)hf->width * hf->height, i = n - n % 8;
    const float *d = hf->data;
#ifdef TSR_AVX2_DISPATCH
    if (__builtin_cpu_supports("avx2"))
        stats_lanes_avx2(d, n, mn8, mx8, sum8, nan8);
    else
#endif
        stats_lanes_body(d, n, mn8, mx8, sum8, nan8);
    for (int k = 0; i < n; i++, k++)
        stats_add(d[i], k, mn8, mx8, sum8, nan8);
    double mn = INFINITY, mx = -INFINITY, sum = 0;
    for (int k = 0; k < 8; k++) {
        mn = mn8[k] < mn ? mn8[k] : mn;
        mx = mx8[k] > mx ? mx8[k] : mx;
        sum += sum8[k];
        st->nodata += nan8[k];
    }
    st->valid = n - st->nodata;
    st->min = st->valid ? mn : NAN;
    st->max = st->valid ? mx : NAN;
    st->mean = st->valid ? sum / (double)st->valid : NAN;
}

static tsr_status load_raw(const char *path, const tsr_load_options *o, tsr_heightfield **out, const tsr_allocator *alloc,
                           tsr_error *err)
{
    static const char *names[] = {"", "u16", "i16", "f32"};
    size_t bytes = o->raw_type == TSR_RAW_F32 ? 4 : 2;
    uint64_t w = o->raw_width, h = o->raw_height;
    if (w < TSR_HEIGHTFIELD_MIN_SIDE || h < TSR_HEIGHTFIELD_MIN_SIDE)
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s: raw size %llux%llu is below the 2x2 minimum", path,
                             (unsigned long long)w, (unsigned long long)h);
    if (!size_ok(w, h))
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s: raw size %llux%llu is beyond Tessera's limits", path,
                             (unsigned long long)w, (unsigned long long)h);
    struct stat stt;
    if (stat(path, &stt) != 0)
        return tsr_error_set(err, errno == ENOENT ? TSR_ERR_NOT_FOUND : TSR_ERR_IO, "%s: %s", path, strerror(errno));
    if (S_ISDIR(stt.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: is a folder, not a raw heightfield", path);
    uint64_t want = w * h * bytes;
    if (stt.st_size == 0)
        return tsr_error_set(err, TSR_ERR_EMPTY, "%s: empty file (0 bytes)", path);
    if ((uint64_t)stt.st_size < want)
        return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: raw %s %llux%llu needs %llu bytes but the file has %llu",
                             path, names[o->raw_type], (unsigned long long)w, (unsigned long long)h,
                             (unsigned long long)want, (unsigned long long)stt.st_size);
    if ((uint64_t)stt.st_size > want)
        return tsr_error_set(err, TSR_ERR_FORMAT,
                             "%s: raw %s %llux%llu needs %llu bytes but the file has %llu (wrong size or type?)",
                             path, names[o->raw_type], (unsigned long long)w, (unsigned long long)h,
                             (unsigned long long)want, (unsigned long long)stt.st_size);
    FILE *f = fopen(path, "rb");
    if (!f)
        return tsr_error_set(err, TSR_ERR_IO, "%s: %s", path, strerror(errno));
    tsr_heightfield *hf = tsr_heightfield_create((uint32_t)w, (uint32_t)h, alloc);
    if (!hf) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    unsigned char buf[1 << 15];
    size_t n = (size_t)(w * h), done = 0;
    while (done < n) {
        size_t want_n = n - done;
        if (want_n > sizeof buf / bytes)
            want_n = sizeof buf / bytes;
        if (fread(buf, bytes, want_n, f) != want_n) {
            fclose(f);
            tsr_heightfield_destroy(hf);
            return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: read failed after %zu samples", path, done);
        }
        for (size_t i = 0; i < want_n; i++) {
            const unsigned char *b = buf + i * bytes;
            float v;
            if (o->raw_type == TSR_RAW_F32) {
                uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
                memcpy(&v, &u, 4);
            } else {
                uint16_t u = (uint16_t)(b[0] | b[1] << 8);
                v = o->raw_type == TSR_RAW_U16 ? (float)u : (float)(int16_t)u;
            }
            hf->data[done + i] = v;
        }
        done += want_n;
    }
    fclose(f);
    snprintf(hf->source_format, sizeof hf->source_format, "raw %s", names[o->raw_type]);
    *out = hf;
    return TSR_OK;
}

static tsr_status finish_image(const char *path, const tsr_load_options *o, tsr_heightfield **out,
                               const tsr_allocator *alloc, float *px, const tsr_image_info *ip, bool *nodata_done,
                               tsr_error *err);

/* Whether v can be a float32 sample's no-data value (not NaN, in range). */
static bool nodata_usable(double v)
{
    return !isnan(v) && fabs(v) <= FLT_MAX;
}

void tsr_georef_apply(const tsr_georef *g, const double *nodata, float *px, size_t n)
{
    double v = nodata ? *nodata : g->has_nodata ? g->nodata : NAN;
    bool nd = nodata_usable(v);
    float ndv = nd ? (float)v : 0;
    double scale = g->z_scale, offset = g->z_offset;
    if (!nd && scale == 1 && offset == 0)
        return;
    for (size_t i = 0; i < n; i++) {
        if (nd && px[i] == ndv)
            px[i] = NAN;
        else if (scale != 1 || offset != 0)
            px[i] = (float)(px[i] * scale + offset);
    }
}

/* A GIS raster OpenImageIO could not open, through GDAL; *nodata_done:
 * the no-data samples (the value asked for, else the file's) are NaN
 * already. */
static tsr_status load_gis(const char *path, const tsr_load_options *o, tsr_heightfield **out,
                           const tsr_allocator *alloc, bool *nodata_done, tsr_error *err)
{
    float *px = NULL;
    uint32_t w, h;
    char format[64];
    tsr_georef g;
    tsr_status s = tsr_gdal_read(path, alloc, TSR_HEIGHTFIELD_MAX_SAMPLES, &px, &w, &h, format, &g, err);
    if (s != TSR_OK)
        return s;
    tsr_georef_apply(&g, o->has_nodata ? &o->nodata : NULL, px, (size_t)w * h);
    tsr_heightfield *hf = adopt(w, h, px, alloc);
    if (!hf) {
        tsr_free(alloc, px);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    snprintf(hf->source_format, sizeof hf->source_format, "%s", format);
    hf->georef = g;
    hf->has_georef = g.has_transform || g.crs != TSR_CRS_NONE || g.has_nodata || g.z_scale != 1 || g.z_offset != 0;
    *nodata_done = true;
    *out = hf;
    return TSR_OK;
}

static tsr_status load_image(const char *path, const tsr_load_options *o, tsr_heightfield **out,
                             const tsr_allocator *alloc, bool *nodata_done, tsr_error *err)
{
    float *px = NULL;
    tsr_image_info info;
    tsr_status s = tsr_image_read(path, alloc, TSR_HEIGHTFIELD_MAX_SAMPLES, &px, &info, err);
    if (s == TSR_ERR_FORMAT && !info.format[0] && o->decode == TSR_DECODE_NONE) {
        /* no image reader took it: a GIS raster? If GDAL knows it no
         * better, OpenImageIO's message stands */
        tsr_error gerr = {0};
        tsr_status gs = load_gis(path, o, out, alloc, nodata_done, &gerr);
        if (gs == TSR_ERR_FORMAT)
            return s;
        *err = gerr;
        return gs;
    }
    if (s != TSR_OK)
        return s;
    tsr_status hs = finish_image(path, o, out, alloc, px, &info, nodata_done, err);
    if (hs == TSR_OK && !strcmp(info.format, "tiff") && !info.has_scale && o->decode == TSR_DECODE_NONE) {
        /* a GeoTIFF: its georeferencing, its no-data value and its
         * heights' scale and offset (GDAL's metadata), which OpenImageIO
         * skips */
        tsr_heightfield *hf = *out;
        hf->has_georef = tsr_gdal_georef(path, info.width, info.height, &hf->georef);
        if (hf->has_georef) {
            tsr_georef_apply(&hf->georef, o->has_nodata ? &o->nodata : NULL, hf->data, (size_t)hf->width * hf->height);
            *nodata_done = true;
        }
    }
    if (hs == TSR_OK && info.has_spacing && !(*out)->georef.has_spacing) {
        /* the spacing tsr_heightfield_save stored (tessera generate's) */
        tsr_heightfield *hf = *out;
        if (!hf->has_georef) {
            memset(&hf->georef, 0, sizeof hf->georef);
            hf->georef.z_scale = 1;
        }
        hf->has_georef = true;
        hf->georef.has_spacing = true;
        hf->georef.spacing[0] = hf->georef.ground[0] = info.spacing[0];
        hf->georef.spacing[1] = hf->georef.ground[1] = info.spacing[1];
    }
    return hs;
}

static tsr_status finish_image(const char *path, const tsr_load_options *o, tsr_heightfield **out,
                               const tsr_allocator *alloc, float *px, const tsr_image_info *ip, bool *nodata_done,
                               tsr_error *err)
{
    tsr_image_info info = *ip;
    if (info.width < TSR_HEIGHTFIELD_MIN_SIDE || info.height < TSR_HEIGHTFIELD_MIN_SIDE) {
        tsr_free(alloc, px);
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s: image is %ux%u; a heightfield needs at least 2x2 samples",
                             path, info.width, info.height);
    }
    size_t n = (size_t)info.width * info.height, nch = info.channels;
    if (info.has_scale && o->has_nodata && o->decode == TSR_DECODE_NONE) {
        /* the no-data value asked for is a stored value, as a GIS file's
         * is (tsr_georef_apply): compared before the file's scale */
        size_t colour = nch >= 2 && info.alpha_channel == (int)nch - 1 ? nch - 1 : nch; /* not the alpha */
        if (nodata_usable(o->nodata))
            for (size_t i = 0; i < n; i++)
                for (size_t c = 0; c < colour; c++)
                    if (px[i * nch + c] == (float)o->nodata)
                        px[i * nch + c] = NAN;
        *nodata_done = true;
    }
    if (nch == 1 && o->decode != TSR_DECODE_TERRAIN_RGB) {
        /* one channel: the pixels become the samples where they are (a
         * copy would double the peak: 2 GB more for a 16k float TIFF) */
        tsr_heightfield *hf = adopt(info.width, info.height, px, alloc);
        if (!hf) {
            tsr_free(alloc, px);
            return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
        }
        if (info.has_scale)
            for (size_t i = 0; i < n; i++)
                px[i] = (float)(px[i] * info.scale + info.offset);
        snprintf(hf->source_format, sizeof hf->source_format, "%s %s", info.format, info.type);
        *out = hf;
        return TSR_OK;
    }
    tsr_heightfield *hf = tsr_heightfield_create(info.width, info.height, alloc);
    if (!hf) {
        tsr_free(alloc, px);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    if (o->decode == TSR_DECODE_TERRAIN_RGB) {
        if (nch < 3 || strcmp(info.type, "uint8") != 0) {
            tsr_heightfield_destroy(hf);
            tsr_free(alloc, px);
            return tsr_error_set(err, TSR_ERR_FORMAT,
                                 "%s: Terrain-RGB needs 8-bit RGB or RGBA, but the image has %u channel(s) of %s",
                                 path, info.width ? info.channels : 0, info.type);
        }
        for (size_t i = 0; i < n; i++) {
            const float *p = px + i * nch;
            double code = (double)p[0] * 65536.0 + (double)p[1] * 256.0 + (double)p[2];
            /* a transparent pixel (alpha 0: outside a tile's coverage) is no-data */
            hf->data[i] = nch == 4 && p[3] == 0 ? NAN : (float)(code * 0.1 - 10000.0);
        }
    } else {
        /* Several channels are accepted only when they agree: grey stored
         * as RGB. A last channel the file marks as alpha (a PNG's, a TIFF's
         * extra sample) marks no-data where it is 0 and is otherwise
         * ignored. Anything else is ambiguous: bands of a multi-band GIS
         * raster that differ are refused, not read as the first. */
        bool alpha = nch >= 2 && info.alpha_channel == (int)nch - 1;
        size_t colour = alpha ? nch - 1 : nch;
        for (size_t i = 0; i < n; i++) {
            const float *p = px + i * nch;
            for (size_t c = 1; c < colour; c++)
                if (p[c] != p[0] && !(isnan(p[c]) && isnan(p[0]))) {
                    tsr_heightfield_destroy(hf);
                    tsr_free(alloc, px);
                    if (colour == 3)
                        return tsr_error_set(err, TSR_ERR_FORMAT,
                                             "%s: a colour image (channels differ at column %zu, row %zu); "
                                             "use --decode terrain-rgb for Terrain-RGB tiles",
                                             path, i % info.width, i / info.width);
                    return tsr_error_set(err, TSR_ERR_FORMAT,
                                         "%s: %zu bands that differ (band %zu at column %zu, row %zu); a heightfield "
                                         "has one (extract the band of heights first, e.g. gdal_translate -b 1)",
                                         path, nch, c + 1, i % info.width, i / info.width);
                }
            hf->data[i] = info.has_scale ? (float)(p[0] * info.scale + info.offset) : p[0];
            if (colour < nch && p[colour] == 0)
                hf->data[i] = NAN;
        }
    }
    tsr_free(alloc, px);
    snprintf(hf->source_format, sizeof hf->source_format, "%s %s%s", info.format, info.type,
             o->decode == TSR_DECODE_TERRAIN_RGB ? " terrain-rgb" : "");
    *out = hf;
    return TSR_OK;
}

tsr_status tsr_heightfield_load(const char *path, const tsr_load_options *opts, const tsr_allocator *alloc,
                                tsr_heightfield **out, tsr_error *err)
{
    static const tsr_load_options defaults = {0};
    const tsr_load_options *o = opts ? opts : &defaults;
    *out = NULL;
    if (!path || !*path)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "no input file given");
    tsr_heightfield *hf = NULL;
    tsr_status s;
    bool nodata_done = false;
    /* a missing or unreadable file is said at once, before the image
     * module (some 0.4 s of shared libraries) is opened */
    if (access(path, R_OK) != 0)
        return tsr_error_set(err, TSR_ERR_IO, "%s: %s", path, strerror(errno));
    /* a pipe or device is read by no format here (they seek, or ask the
     * size first): said, rather than "empty file" */
    struct stat ps;
    if (stat(path, &ps) == 0 && !S_ISREG(ps.st_mode) && !S_ISDIR(ps.st_mode))
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: not a regular file (a pipe or device): inputs are read from files; save it to one "
                             "first",
                             path);
    if (o->raw_type != TSR_RAW_NONE)
        s = load_raw(path, o, &hf, alloc, err);
    else if (o->decode == TSR_DECODE_NONE && tsr_pnm_is_grey(path))
        s = tsr_pnm_read(path, alloc, &hf, err);
    else
        s = load_image(path, o, &hf, alloc, &nodata_done, err);
    if (s != TSR_OK)
        return s;
    /* the no-data value asked for, else the file's own (a GeoTIFF's
     * GDAL_NODATA), compared as the float32 the samples are, where the
     * loader did not compare it with the stored values already */
    bool file_nd = !o->has_nodata && !nodata_done && hf->has_georef && hf->georef.has_nodata;
    double ndd = o->has_nodata && !nodata_done ? o->nodata : file_nd ? hf->georef.nodata : NAN;
    bool has_nd = nodata_usable(ndd);
    float nd = has_nd ? (float)ndd : 0;
    size_t n = (size_t)hf->width * hf->height;
    uint64_t valid = 0;
    for (size_t i = 0; i < n; i++) {
        float v = hf->data[i];
        /* the float extremes are what GIS tools write for no-data when the
         * file names none; no terrain is 3.4e38 high */
        if ((has_nd && v == nd) || v == FLT_MAX || v == -FLT_MAX)
            hf->data[i] = v = NAN;
        if (isinf(v)) {
            uint32_t c = (uint32_t)(i % hf->width), r = (uint32_t)(i / hf->width);
            tsr_heightfield_destroy(hf);
            return tsr_error_set(err, TSR_ERR_VALUE, "%s: infinite height at column %u, row %u", path, c, r);
        }
        valid += !isnan(v);
    }
    if (valid == 0 && !o->all_nodata_ok) {
        bool file_value = (file_nd || nodata_done) && hf->has_georef && hf->georef.has_nodata;
        tsr_heightfield_destroy(hf);
        return tsr_error_set(err, TSR_ERR_VALUE, "%s: every sample is no-data (NaN%s)", path,
                             o->has_nodata ? " or the no-data value"
                             : file_value  ? " or the file's no-data value"
                                           : "");
    }
    *out = hf;
    return TSR_OK;
}

/* The format path's extension names: 1 PNG (16-bit), 2 float (TIFF,
 * OpenEXR); 0 (with err set) none that save writes. */
static int save_format(const char *path, tsr_error *err)
{
    const char *slash = strrchr(path, '/'), *dot = strrchr(slash ? slash + 1 : path, '.');
    if (dot && !strcasecmp(dot, ".png"))
        return 1;
    if (dot && (!strcasecmp(dot, ".tif") || !strcasecmp(dot, ".tiff") || !strcasecmp(dot, ".exr")))
        return 2;
    tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: unknown heightfield format (use .png, .tif or .exr)", path);
    return 0;
}

tsr_status tsr_heightfield_save_check(const char *path, tsr_error *err)
{
    if (!save_format(path, err))
        return TSR_ERR_ARGUMENT;
    return tsr_atomic_probe(path, err);
}

tsr_status tsr_heightfield_save(const tsr_heightfield *hf, const char *path, tsr_save_info *info, tsr_error *err)
{
    int format = save_format(path, err);
    if (!format)
        return TSR_ERR_ARGUMENT;
    bool png = format == 1;
    double scale = 1, offset = 0;
    const float *values = hf->data;
    float *q = NULL;
    size_t n = (size_t)hf->width * hf->height;
    if (png) {
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        bool integral = st.valid > 0 && st.min >= 0 && st.max <= 65535;
        for (size_t i = 0; i < n && integral; i++)
            integral = isnan(hf->data[i]) || hf->data[i] == floorf(hf->data[i]);
        if (!integral && st.valid > 0) {
            offset = st.min;
            scale = st.max > st.min ? (st.max - st.min) / 65535.0 : 1.0;
        }
        const tsr_allocator *a = hf->alloc.realloc ? &hf->alloc : NULL;
        q = tsr_alloc(a, n * sizeof(float));
        if (!q)
            return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
        for (size_t i = 0; i < n; i++)
            q[i] = isnan(hf->data[i]) ? NAN : (float)floor((hf->data[i] - offset) / scale + 0.5);
        values = q;
    }
    char tmp[4096];
    tsr_status s = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (s == TSR_OK) {
        bool spaced = hf->dx != 1 || hf->dy != 1; /* the default spacing is not stored */
        s = tsr_image_write(path, tmp, hf->width, hf->height, values, png, scale, offset, spaced ? hf->dx : 0,
                            spaced ? hf->dy : 0, err);
        if (s == TSR_OK)
            s = tsr_atomic_commit(tmp, path, err);
        else
            tsr_atomic_abort(tmp);
    }
    if (q)
        tsr_free(hf->alloc.realloc ? &hf->alloc : NULL, q);
    if (s == TSR_OK && info) {
        info->scale = scale;
        info->offset = offset;
    }
    return s;
}
