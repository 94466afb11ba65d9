/* fuzz_pslg_io.c: the PSLG readers of `tessera triangulate`
 * (tools/pslg_io.c): Triangle's .node and .poly, JSON rings, nV nE text.
 *
 * Input: byte 0 picks the format (low two bits: node, poly, json, txt);
 * the rest is the file. For .poly, text after a line "@node" goes to the
 * .node file of the same name (read when the .poly says 0 points); without
 * it no such file exists. The readers take paths, so the bytes go through
 * a temporary file.
 *
 * Checked: a failure returns a status other than TSR_OK with a message and
 * leaves the graph empty; a success has at least one point, finite
 * coordinates and hole seeds, and segment indices below the point count.
 * Small successful graphs are then triangulated (Delaunay, region HULL):
 * refused (TSR_ERR_ARGUMENT) only for a nonzero coordinate outside
 * 2^-128 <= |x| < 2^250, else the result must pass
 * fuzz_check_triangulation. The readers accept any finite double, so this
 * reaches coordinates the triangulate target never makes (1e300,
 * subnormals). */
#include "fuzz.h"
#include "pslg_io.h"

#include <math.h>
#include <string.h>

#define MAX_TRIANGULATED_POINTS 64

static const char *const names[4] = {"in.node", "in.poly", "in.json", "in.txt"};
static const cli_pslg_format formats[4] = {CLI_PSLG_NODE, CLI_PSLG_POLY, CLI_PSLG_JSON, CLI_PSLG_TXT};

static const uint8_t *find(const uint8_t *p, size_t n, const char *needle)
{
    size_t k = strlen(needle);
    for (size_t i = 0; i + k <= n; i++)
        if (!memcmp(p + i, needle, k))
            return p + i;
    return NULL;
}

static void check_graph(const cli_pslg *g)
{
    if (g->nv == 0 || !g->xy)
        fuzz_fail("pslg_io: success with no points");
    for (size_t i = 0; i < 2 * (size_t)g->nv; i++)
        if (!isfinite(g->xy[i]))
            fuzz_fail("pslg_io: point %zu has a non-finite coordinate", i / 2);
    for (size_t i = 0; i < 2 * (size_t)g->nholes; i++)
        if (!isfinite(g->holes[i]))
            fuzz_fail("pslg_io: hole %zu has a non-finite coordinate", i / 2);
    for (size_t i = 0; i < 2 * (size_t)g->nseg; i++)
        if (g->seg[i] >= g->nv)
            fuzz_fail("pslg_io: segment %zu names point %u of %u", i / 2, g->seg[i], g->nv);
}

/* A coordinate outside the range where the exact predicates are exact
 * (nonzero below 2^-128, or 2^250 and beyond), which tsr_triangulate
 * refuses. */
static bool out_of_range(double x)
{
    return x != 0 && !(fabs(x) >= 0x1p-128 && fabs(x) < 0x1p250);
}

static bool beyond_predicates(const cli_pslg *g)
{
    for (size_t i = 0; i < 2 * (size_t)g->nv; i++)
        if (out_of_range(g->xy[i]))
            return true;
    for (size_t i = 0; i < 2 * (size_t)g->nholes; i++)
        if (out_of_range(g->holes[i]))
            return true;
    return false;
}

static void triangulate_graph(const cli_pslg *g)
{
    if (g->nv > MAX_TRIANGULATED_POINTS || g->nseg > MAX_TRIANGULATED_POINTS)
        return;
    tsr_pslg in = cli_pslg_view(g);
    tsr_tri_options o = {0};
    o.max_steiner = 1000;
    tsr_triangulation t;
    tsr_error err = {0};
    tsr_status s = tsr_triangulate(&in, &o, &t, NULL, &err);
    if (s == TSR_ERR_NOMEM)
        return;
    if (s == TSR_ERR_ARGUMENT && beyond_predicates(g))
        return; /* the readers take any finite number; the triangulator less */
    if (s != TSR_OK)
        fuzz_fail("pslg_io: a graph the reader accepted was refused by tsr_triangulate: %s", err.message);
    fuzz_check_triangulation(&in, &o, &t, "pslg_io");
    tsr_triangulation_free(&t);
}

int fuzz_pslg_io(const uint8_t *data, size_t size)
{
    if (size < 1)
        return 0;
    int f = data[0] & 3;
    const uint8_t *body = data + 1, *end = data + size;
    fuzz_remove_temp("in.node");
    if (formats[f] == CLI_PSLG_POLY) {
        const uint8_t *sep = find(body, (size_t)(end - body), "\n@node\n");
        if (sep) {
            const uint8_t *node = sep + 7;
            fuzz_write_temp("in.node", node, (size_t)(end - node));
            end = sep + 1;
        }
    }
    const char *path = fuzz_write_temp(names[f], body, (size_t)(end - body));
    cli_pslg g;
    tsr_error err = {0};
    tsr_status s = cli_pslg_read(path, formats[f], &g, &err);
    if (s != TSR_OK) {
        if (s >= TSR_STATUS_COUNT || err.status != s || !err.message[0])
            fuzz_fail("pslg_io: failure %d without its message", (int)s);
        if (g.xy || g.seg || g.holes || g.nv || g.nseg || g.nholes)
            fuzz_fail("pslg_io: failure %d leaves a graph behind", (int)s);
        return 0;
    }
    if (g.format != formats[f])
        fuzz_fail("pslg_io: read as format %d, asked for %d", (int)g.format, (int)formats[f]);
    check_graph(&g);
    triangulate_graph(&g);
    cli_pslg_free(&g);
    return 0;
}

#ifdef TSR_LIBFUZZER
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);
int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    return fuzz_pslg_io(data, size);
}
#endif
