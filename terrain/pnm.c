/* pnm.c: our own reader of greyscale Netpbm files (P2 plain and P5 binary
 * PGM, maxval up to 65535). OpenImageIO reads them too, but rescales
 * 16-bit samples through a normalised float and comes back one unit off
 * for some values; a heightfield must keep its exact integers. Format:
 * Netpbm's pgm(5) page. */
#include "terrain_internal.h"

#include <ctype.h>
#include <errno.h>
#include <stdio.h>
#include <string.h>

/* Next header token as an unsigned integer, skipping whitespace and
 * comments; -1 at end of file or on a non-digit. */
static long long next_uint(FILE *f)
{
    int ch;
    for (;;) {
        ch = fgetc(f);
        if (ch == '#') {
            while ((ch = fgetc(f)) != EOF && ch != '\n' && ch != '\r')
                ;
            continue;
        }
        if (ch == EOF || !isspace(ch))
            break;
    }
    if (ch == EOF || !isdigit(ch))
        return -1;
    long long v = 0;
    while (ch != EOF && isdigit(ch)) {
        v = v * 10 + (ch - '0');
        if (v > (1ll << 40))
            return -1;
        ch = fgetc(f);
    }
    if (ch != EOF && !isspace(ch))
        return -1;
    return v; /* the single whitespace after the token is consumed */
}

bool tsr_pnm_is_grey(const char *path)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return false;
    char m[2] = {0};
    bool yes = fread(m, 1, 2, f) == 2 && m[0] == 'P' && (m[1] == '2' || m[1] == '5');
    fclose(f);
    return yes;
}

tsr_status tsr_pnm_read(const char *path, const tsr_allocator *alloc, tsr_heightfield **out, tsr_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return tsr_error_set(err, errno == ENOENT ? TSR_ERR_NOT_FOUND : TSR_ERR_IO, "%s: %s", path, strerror(errno));
    char m[2];
    if (fread(m, 1, 2, f) != 2) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: not a PGM file", path);
    }
    bool plain = m[1] == '2';
    long long w = next_uint(f), h = next_uint(f), maxval = next_uint(f);
    if (w < 0 || h < 0 || maxval < 0) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: PGM header is incomplete or malformed", path);
    }
    if (maxval < 1 || maxval > 65535) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: PGM maxval %lld is outside 1..65535", path, maxval);
    }
    if (w < TSR_HEIGHTFIELD_MIN_SIDE || h < TSR_HEIGHTFIELD_MIN_SIDE) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s: image is %lldx%lld; a heightfield needs at least 2x2 samples",
                             path, w, h);
    }
    if (w > TSR_HEIGHTFIELD_MAX_SIDE || h > TSR_HEIGHTFIELD_MAX_SIDE ||
        (uint64_t)w * (uint64_t)h > TSR_HEIGHTFIELD_MAX_SAMPLES) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s: image is %lldx%lld; Tessera accepts at most %u per side and %llu samples",
                             path, w, h, TSR_HEIGHTFIELD_MAX_SIDE, (unsigned long long)TSR_HEIGHTFIELD_MAX_SAMPLES);
    }
    size_t n = (size_t)w * (size_t)h, bytes = maxval > 255 ? 2 : 1;
    /* The file's size bounds the samples before anything is allocated (a
     * 20-byte header must not cost gigabytes): P5 has bytes per sample, P2
     * at least a digit per sample and a separator between two. */
    long here = ftell(f), size = fseek(f, 0, SEEK_END) == 0 ? ftell(f) : -1;
    if (here < 0 || size < 0 || fseek(f, here, SEEK_SET) != 0) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_IO, "%s: cannot seek: %s", path, strerror(errno));
    }
    uint64_t need = plain ? 2 * (uint64_t)n - 1 : (uint64_t)n * bytes;
    if ((uint64_t)(size - here) < need) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_TRUNCATED,
                             "%s: truncated PGM: %lldx%lld samples need at least %llu bytes, %ld follow the header",
                             path, w, h, (unsigned long long)need, size - here);
    }
    tsr_heightfield *hf = tsr_heightfield_create((uint32_t)w, (uint32_t)h, alloc);
    if (!hf) {
        fclose(f);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    for (size_t i = 0; i < n; i++) {
        long long v;
        if (plain) {
            v = next_uint(f);
        } else {
            int b0 = fgetc(f), b1 = bytes == 2 ? fgetc(f) : 0;
            v = b0 == EOF || b1 == EOF ? -1 : bytes == 2 ? (b0 << 8 | b1) : b0; /* big-endian */
        }
        if (v < 0 || v > maxval) {
            fclose(f);
            tsr_heightfield_destroy(hf);
            if (v < 0)
                return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s: truncated PGM: %zu of %zu samples", path, i, n);
            return tsr_error_set(err, TSR_ERR_FORMAT, "%s: PGM sample %lld above maxval %lld at column %zu, row %zu",
                                 path, v, maxval, i % (size_t)w, i / (size_t)w);
        }
        hf->data[i] = (float)v;
    }
    fclose(f);
    snprintf(hf->source_format, sizeof hf->source_format, "pgm %s%s", bytes == 2 ? "uint16" : "uint8",
             plain ? " plain" : "");
    *out = hf;
    return TSR_OK;
}
