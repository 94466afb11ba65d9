/* make_fixtures DIR: writes the bad and odd input files the CLI tests use.
 * Made here, from their definitions, rather than committed as binaries. */
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

static uint32_t crc32_png(const unsigned char *p, size_t n)
{
    /* PNG's CRC-32 (ISO 3309), bit by bit */
    uint32_t c = 0xFFFFFFFFu;
    for (size_t i = 0; i < n; i++) {
        c ^= p[i];
        for (int k = 0; k < 8; k++)
            c = (c >> 1) ^ (0xEDB88320u & (0u - (c & 1)));
    }
    return c ^ 0xFFFFFFFFu;
}

static void be32(unsigned char *b, uint32_t v)
{
    b[0] = (unsigned char)(v >> 24);
    b[1] = (unsigned char)(v >> 16);
    b[2] = (unsigned char)(v >> 8);
    b[3] = (unsigned char)v;
}

static void chunk(FILE *f, const char *type, const unsigned char *data, uint32_t n)
{
    unsigned char buf[256];
    be32(buf, n);
    fwrite(buf, 1, 4, f);
    memcpy(buf, type, 4);
    if (n)
        memcpy(buf + 4, data, n);
    fwrite(buf, 1, 4 + n, f);
    be32(buf, crc32_png(buf, 4 + n));
    fwrite(buf, 1, 4, f);
}

/* A 4 x 4 Terrain-RGB PNG, RGBA 8-bit, every pixel height 100 m (R 1, G
 * 138, B 136), its rows' alpha 0, 128, 255, 255: alpha is no height (0
 * is no-data). The
 * IDAT is a zlib stream of one stored block. */
static void alpha_png(FILE *f)
{
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    fwrite(sig, 1, 8, f);
    unsigned char ihdr[13] = {0};
    be32(ihdr, 4);
    be32(ihdr + 4, 4);
    ihdr[8] = 8; /* bit depth */
    ihdr[9] = 6; /* RGBA */
    chunk(f, "IHDR", ihdr, 13);
    unsigned char raw[4 * 17], z[2 + 5 + sizeof raw + 4];
    static const unsigned char alpha[4] = {0, 128, 255, 255};
    for (int y = 0; y < 4; y++) {
        raw[17 * y] = 0; /* no filter */
        for (int x = 0; x < 4; x++) {
            unsigned char *p = raw + 17 * y + 1 + 4 * x;
            p[0] = 1, p[1] = 138, p[2] = 136, p[3] = alpha[y];
        }
    }
    uint32_t a = 1, b = 0; /* Adler-32 */
    for (size_t i = 0; i < sizeof raw; i++) {
        a = (a + raw[i]) % 65521;
        b = (b + a) % 65521;
    }
    z[0] = 0x78, z[1] = 0x01;
    z[2] = 1; /* the final block, stored */
    z[3] = sizeof raw & 0xFF, z[4] = sizeof raw >> 8;
    z[5] = (unsigned char)~z[3], z[6] = (unsigned char)~z[4];
    memcpy(z + 7, raw, sizeof raw);
    be32(z + 7 + sizeof raw, b << 16 | a);
    chunk(f, "IDAT", z, sizeof z);
    chunk(f, "IEND", NULL, 0);
}

static FILE *open_in(const char *dir, const char *name)
{
    char p[1024];
    snprintf(p, sizeof p, "%s/%s", dir, name);
    FILE *f = fopen(p, "wb");
    if (!f)
        perror(p);
    return f;
}

static void raw_f32(const char *dir, const char *name, int n, int special_at, float special, int all)
{
    FILE *f = open_in(dir, name);
    for (int i = 0; i < n; i++) {
        float v = all || i == special_at ? special : (float)i;
        unsigned char b[4];
        uint32_t u;
        memcpy(&u, &v, 4);
        for (int k = 0; k < 4; k++)
            b[k] = (unsigned char)(u >> (8 * k));
        fwrite(b, 1, 4, f);
    }
    fclose(f);
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: make_fixtures DIR\n");
        return 2;
    }
    const char *dir = argv[1];
    fclose(open_in(dir, "empty.png"));

    FILE *f = open_in(dir, "random.png");
    uint32_t s = 0xC0FFEEu;
    for (int i = 0; i < 4096; i++) {
        s = s * 1664525u + 1013904223u;
        fputc((int)(s >> 24), f);
    }
    fclose(f);

    /* a valid PNG header announcing 1,000,000 x 1,000,000 16-bit grey
     * pixels, followed by a token IDAT: the header alone must be refused */
    f = open_in(dir, "huge.png");
    static const unsigned char sig[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1A, '\n'};
    fwrite(sig, 1, 8, f);
    unsigned char ihdr[13];
    be32(ihdr, 1000000);
    be32(ihdr + 4, 1000000);
    ihdr[8] = 16; /* bit depth */
    ihdr[9] = 0;  /* greyscale */
    ihdr[10] = ihdr[11] = ihdr[12] = 0;
    chunk(f, "IHDR", ihdr, 13);
    static const unsigned char idat[] = {0x78, 0x9C, 0x03, 0x00, 0x00, 0x00, 0x00, 0x01};
    chunk(f, "IDAT", idat, sizeof idat);
    chunk(f, "IEND", NULL, 0);
    fclose(f);

    raw_f32(dir, "nan.f32", 16, 5, NAN, 0);
    raw_f32(dir, "inf.f32", 16, 9, INFINITY, 0);
    raw_f32(dir, "allnan.f32", 16, 0, NAN, 1);
    f = open_in(dir, "alpha.png");
    alpha_png(f);
    fclose(f);
    return 0;
}
