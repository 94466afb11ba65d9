/* fuzz_heightfield.c: tsr_heightfield_load on its own parsers: raw samples
 * (heightfield.c) and greyscale Netpbm (pnm.c). Other image formats go to
 * OpenImageIO and are not fuzzed here.
 *
 * Input: byte 0 picks the path: low two bits 0-2 raw u16 / i16 / f32, 3
 * PGM; bit 2 sets a no-data value (0, or -9999 for i16 / f32); bit 3, raw
 * only, sizes the file exactly (the height follows from the length)
 * instead of taking byte 2 as the height.
 *   raw: byte 1 width (b % 64), byte 2 height (b % 64), then the samples;
 *   PGM: bit 4 of byte 0 picks "P5" (binary) over "P2" (plain); the rest
 *   follows that magic in the file (header, then samples).
 * Every input goes through a temporary file.
 *
 * Checked: no single allocation above 1 MiB + 16 bytes per input byte
 * (a heightfield costs 4 bytes a sample, a sample at least 1 file byte);
 * a failure returns no heightfield and a message; a success has
 * sides within the limits, no infinite height, at least one valid
 * sample, and for raw exactly the width and height asked for with the
 * samples of the file. */
#include "fuzz.h"
#include "terrain/terrain.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static float raw_sample(tsr_raw_type type, const uint8_t *b)
{
    if (type == TSR_RAW_F32) {
        uint32_t u = (uint32_t)b[0] | (uint32_t)b[1] << 8 | (uint32_t)b[2] << 16 | (uint32_t)b[3] << 24;
        float v;
        memcpy(&v, &u, 4);
        return v;
    }
    uint16_t u = (uint16_t)(b[0] | b[1] << 8);
    return type == TSR_RAW_U16 ? (float)u : (float)(int16_t)u;
}

static void check_result(tsr_status s, const tsr_heightfield *hf, const tsr_error *err)
{
    if (s != TSR_OK) {
        if (hf || s >= TSR_STATUS_COUNT || err->status != s || !err->message[0])
            fuzz_fail("heightfield: failure %d without its message, or with a heightfield", (int)s);
        return;
    }
    uint32_t w = tsr_heightfield_width(hf), h = tsr_heightfield_height(hf);
    if (w < TSR_HEIGHTFIELD_MIN_SIDE || h < TSR_HEIGHTFIELD_MIN_SIDE || w > TSR_HEIGHTFIELD_MAX_SIDE ||
        h > TSR_HEIGHTFIELD_MAX_SIDE)
        fuzz_fail("heightfield: loaded a %ux%u heightfield", w, h);
    const float *d = tsr_heightfield_cdata(hf);
    size_t valid = 0;
    for (size_t i = 0; i < (size_t)w * h; i++) {
        if (isinf(d[i]))
            fuzz_fail("heightfield: infinite sample %zu loaded", i);
        valid += !isnan(d[i]);
    }
    if (!valid)
        fuzz_fail("heightfield: loaded with no valid sample");
}

int fuzz_heightfield(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    uint8_t mode = data[0];
    tsr_load_options o = {0};
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    tsr_status s;
    size_t limit = ((size_t)1 << 20) + 16 * size;
    tsr_allocator alloc;
    fuzz_limited_allocator(&alloc, &limit);
    if ((mode & 3) == 3) {
        /* the magic is ours, so the loader always takes pnm.c, never OpenImageIO */
        size_t n = size - 1;
        char *buf = malloc(n + 2);
        if (!buf)
            return 0;
        buf[0] = 'P';
        buf[1] = mode & 16 ? '5' : '2';
        if (n)
            memcpy(buf + 2, data + 1, n);
        o.has_nodata = mode & 4;
        o.nodata = 0;
        const char *path = fuzz_write_temp("in.pgm", buf, n + 2);
        free(buf);
        s = tsr_heightfield_load(path, &o, &alloc, &hf, &err);
        check_result(s, hf, &err);
        tsr_heightfield_destroy(hf);
        return 0;
    }

    o.raw_type = (tsr_raw_type)(TSR_RAW_U16 + (mode & 3));
    size_t bytes = o.raw_type == TSR_RAW_F32 ? 4 : 2;
    o.has_nodata = mode & 4;
    o.nodata = o.raw_type == TSR_RAW_U16 ? 0 : -9999;
    o.raw_width = size > 1 ? data[1] % 64 : 0;
    o.raw_height = size > 2 ? data[2] % 64 : 0;
    const uint8_t *body = size > 3 ? data + 3 : data + size;
    size_t n = (size_t)(data + size - body);
    if ((mode & 8) && o.raw_width > 0) {
        o.raw_height = (uint32_t)(n / (bytes * o.raw_width));
        n = (size_t)o.raw_height * o.raw_width * bytes;
    }
    const char *path = fuzz_write_temp("in.raw", body, n);
    s = tsr_heightfield_load(path, &o, &alloc, &hf, &err);
    check_result(s, hf, &err);
    if (s == TSR_OK) {
        if (tsr_heightfield_width(hf) != o.raw_width || tsr_heightfield_height(hf) != o.raw_height)
            fuzz_fail("heightfield: raw %ux%u loaded as %ux%u", o.raw_width, o.raw_height, tsr_heightfield_width(hf),
                      tsr_heightfield_height(hf));
        const float *d = tsr_heightfield_cdata(hf);
        for (size_t i = 0; i < (size_t)o.raw_width * o.raw_height; i++) {
            float v = raw_sample(o.raw_type, body + i * bytes);
            /* no-data (terrain.h): NaN, +-FLT_MAX, and the value asked for */
            bool nodata = isnan(v) || v == FLT_MAX || v == -FLT_MAX || (o.has_nodata && (double)v == o.nodata);
            if (nodata ? !isnan(d[i]) : d[i] != v)
                fuzz_fail("heightfield: raw sample %zu is %g in the file, %g loaded", i, (double)v, (double)d[i]);
        }
    }
    tsr_heightfield_destroy(hf);
    return 0;
}

#ifdef TSR_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_heightfield(data, size);
}
#endif
