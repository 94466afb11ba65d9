/* pslg_io.c: PSLG readers (Triangle's .node/.poly, JSON rings, the nV nE
 * text) and triangulation writers. Every reader first loads the whole file
 * (so counts can be checked against its size before allocating) and
 * reports the first problem with the file name and line. */
#define _POSIX_C_SOURCE 200809L
#include "pslg_io.h"

#include <cjson/cJSON.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#define MAX_FILE_BYTES ((uint64_t)1 << 31)

/* ---- Formats ---------------------------------------------------------------- */

/* The extension of path (from its last dot), or its end: a pointer into
 * path either way. */
static const char *extension(const char *path)
{
    const char *slash = strrchr(path, '/'), *dot = strrchr(path, '.');
    return dot && (!slash || dot > slash) ? dot : path + strlen(path);
}

cli_pslg_format cli_pslg_format_from_path(const char *path)
{
    const char *e = extension(path);
    return !strcasecmp(e, ".node")   ? CLI_PSLG_NODE
           : !strcasecmp(e, ".poly") ? CLI_PSLG_POLY
           : !strcasecmp(e, ".json") ? CLI_PSLG_JSON
           : !strcasecmp(e, ".txt")  ? CLI_PSLG_TXT
                                     : CLI_PSLG_UNKNOWN;
}

cli_pslg_format cli_pslg_format_parse(const char *name)
{
    return !strcmp(name, "node")   ? CLI_PSLG_NODE
           : !strcmp(name, "poly") ? CLI_PSLG_POLY
           : !strcmp(name, "json") ? CLI_PSLG_JSON
           : !strcmp(name, "txt")  ? CLI_PSLG_TXT
                                   : CLI_PSLG_UNKNOWN;
}

const char *cli_pslg_format_name(cli_pslg_format f)
{
    switch (f) {
    case CLI_PSLG_NODE: return "node";
    case CLI_PSLG_POLY: return "poly";
    case CLI_PSLG_JSON: return "json";
    case CLI_PSLG_TXT: return "txt";
    default: return "unknown";
    }
}

cli_tri_output cli_tri_output_from_path(const char *path)
{
    const char *e = extension(path);
    if (!strcasecmp(e, ".node") || !strcasecmp(e, ".ele") || !strcasecmp(e, ".poly"))
        return CLI_OUT_TRIANGLE;
    return tsr_mesh_format_from_path(path) != TSR_FORMAT_UNKNOWN ? CLI_OUT_MESH : CLI_OUT_UNKNOWN;
}

void cli_pslg_free(cli_pslg *p)
{
    free(p->xy);
    free(p->seg);
    free(p->holes);
    free(p->attr);
    free(p->marker);
    free(p->seg_marker);
    free(p->regions);
    free(p->points_file);
    memset(p, 0, sizeof *p);
}

tsr_pslg cli_pslg_view(const cli_pslg *p)
{
    tsr_pslg v = {p->xy, p->nv, p->seg, p->nseg, p->holes, p->nholes};
    return v;
}

/* ---- Whole files ---------------------------------------------------------- */

/* ---- Line records ------------------------------------------------------------ */

typedef struct token {
    const char *s;
    size_t n;
} token;

#define MAX_TOKENS 68 /* index x y, 64 attributes, marker */

typedef struct text {
    const char *path;
    const char *p, *end;
    uint32_t line;      /* line of the record last read */
    uint32_t next_line; /* line where p is */
    int ntok;           /* values in the record record() read last */
} text;

/* The length of a UTF-8 byte order mark at the start (editors on Windows
 * write one), or 0. */
static size_t bom_length(const char *buf, size_t len)
{
    const unsigned char *d = (const unsigned char *)buf;
    return len >= 3 && d[0] == 0xEF && d[1] == 0xBB && d[2] == 0xBF ? 3 : 0;
}

static bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\v' || c == '\f'; }

/* Reads the next line holding tokens ('#' comments and blank lines are
 * skipped). Stores up to MAX_TOKENS tokens; returns how many the line has,
 * or -1 at the end of the file. */
static int next_record(text *t, token *tok)
{
    while (t->p < t->end) {
        int n = 0;
        t->line = t->next_line;
        while (t->p < t->end && *t->p != '\n') {
            char c = *t->p;
            if (is_space(c)) {
                t->p++;
            } else if (c == '#') {
                while (t->p < t->end && *t->p != '\n')
                    t->p++;
            } else {
                const char *s = t->p;
                while (t->p < t->end && *t->p != '\n' && *t->p != '#' && !is_space(*t->p))
                    t->p++;
                if (n < MAX_TOKENS)
                    tok[n] = (token){s, (size_t)(t->p - s)};
                n++;
            }
        }
        if (t->p < t->end) {
            t->p++;
            t->next_line++;
        }
        if (n > 0)
            return n;
    }
    return -1;
}

/* A token as the message shows it. */
static const char *shown(const token *k, char *buf, size_t cap) { return tsr_quote_bytes(k->s, k->n, buf, cap); }

/* A decimal number (no hex, no nan/inf spellings); finite. */
static tsr_status parse_number(const text *t, const token *k, const char *what, double *v, tsr_error *err)
{
    char buf[128], shownbuf[128];
    bool syntax = k->n > 0 && k->n < sizeof buf;
    for (size_t i = 0; syntax && i < k->n; i++)
        syntax = strchr("0123456789+-.eE", k->s[i]) != NULL && k->s[i] != '\0';
    if (syntax) {
        memcpy(buf, k->s, k->n);
        buf[k->n] = '\0';
        char *end;
        errno = 0;
        *v = strtod(buf, &end);
        if (end != buf + k->n)
            syntax = false;
        else if (!isfinite(*v) || (errno == ERANGE && fabs(*v) > 1))
            return tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: %s '%s' is not a finite number", t->path, t->line, what,
                                 shown(k, shownbuf, sizeof shownbuf));
    }
    if (!syntax) {
        bool word = k->n >= 3 && (!strncasecmp(k->s, "nan", 3) || !strncasecmp(k->s, "inf", 3) ||
                                  ((k->s[0] == '-' || k->s[0] == '+') && k->n >= 4 &&
                                   (!strncasecmp(k->s + 1, "nan", 3) || !strncasecmp(k->s + 1, "inf", 3))));
        return tsr_error_set(err, word ? TSR_ERR_VALUE : TSR_ERR_FORMAT, "%s:%u: %s '%s' is not %s", t->path, t->line,
                             what, shown(k, shownbuf, sizeof shownbuf), word ? "a finite number" : "a number");
    }
    return TSR_OK;
}

/* A non-negative decimal integer below 2^32. */
static tsr_status parse_u32(const text *t, const token *k, const char *what, uint32_t *v, tsr_error *err)
{
    char shownbuf[128];
    bool digits = k->n > 0;
    for (size_t i = 0; digits && i < k->n; i++)
        digits = k->s[i] >= '0' && k->s[i] <= '9';
    if (!digits)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: %s '%s' is not a non-negative integer", t->path, t->line,
                             what, shown(k, shownbuf, sizeof shownbuf));
    uint64_t x = 0;
    for (size_t i = 0; i < k->n; i++) {
        x = x * 10 + (uint64_t)(k->s[i] - '0');
        if (x > UINT32_MAX)
            return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s:%u: %s '%s' is beyond 4294967295", t->path, t->line,
                                 what, shown(k, shownbuf, sizeof shownbuf));
    }
    *v = (uint32_t)x;
    return TSR_OK;
}

/* A boundary marker: an integer (as Triangle reads them), within int32. */
static tsr_status parse_marker(const text *t, const token *k, int32_t *m, tsr_error *err)
{
    double v;
    tsr_status s = parse_number(t, k, "marker", &v, err);
    if (s != TSR_OK)
        return s;
    if (v != floor(v) || v < INT32_MIN || v > INT32_MAX) {
        char shownbuf[128];
        return tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: marker '%s' is not an integer from -2147483648 to 2147483647",
                             t->path, t->line, shown(k, shownbuf, sizeof shownbuf));
    }
    *m = (int32_t)v;
    return TSR_OK;
}

/* Could n more records fit in the rest of the file? Each needs at least
 * a one-byte value and a line end; checked before allocating, so absurd
 * counts cost nothing (records short of values are caught line by line). */
static tsr_status fits(const text *t, uint64_t n, const char *what, tsr_error *err)
{
    uint64_t left = (uint64_t)(t->end - t->p);
    if (n > (left + 1) / 2)
        return tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s:%u: %llu %s cannot fit in the %llu bytes left in the file",
                             t->path, t->line, (unsigned long long)n, what, (unsigned long long)left);
    return TSR_OK;
}

static tsr_status record(text *t, token *tok, int want_min, int want_max, uint32_t i, uint32_t n, const char *what,
                         const char *layout, tsr_error *err)
{
    int got = t->ntok = next_record(t, tok);
    if (got < 0)
        return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s:%u: the file ends after %u of %u %s", t->path, t->next_line,
                             i, n, what);
    if (got < want_min || got > want_max) {
        if (want_min == want_max)
            return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected %d values (%s), found %d", t->path, t->line,
                                 want_min, layout, got);
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected %d to %d values (%s), found %d", t->path, t->line,
                             want_min, want_max, layout, got);
    }
    return TSR_OK;
}

/* The running index of Triangle's files: the first sets the base (0 or
 * 1), the others follow it. */
static tsr_status check_index(const text *t, const token *k, uint32_t i, uint32_t *base, const char *what,
                              tsr_error *err)
{
    uint32_t v;
    tsr_status s = parse_u32(t, k, what, &v, err);
    if (s != TSR_OK)
        return s;
    if (*base == UINT32_MAX) {
        if (v > 1)
            return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: the first %s is numbered %u; numbering starts at 0 or 1",
                                 t->path, t->line, what, v);
        *base = v;
    }
    if ((uint64_t)v != (uint64_t)*base + i)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: %s numbered %u, expected %llu", t->path, t->line, what, v,
                             (unsigned long long)*base + i);
    return TSR_OK;
}

/* ---- Triangle's .node and .poly ---------------------------------------------- */

/* A node section: header and points. *none is set (and nothing read) when
 * allow_none and the header says 0 points. */
static tsr_status read_node_section(text *t, cli_pslg *g, uint32_t *base, bool allow_none, bool *none,
                                    tsr_error *err)
{
    token tok[MAX_TOKENS];
    int n = next_record(t, tok);
    if (n < 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: no header line (points, dimension, attributes, markers)",
                             t->path);
    if (n > 4)
        return tsr_error_set(err, TSR_ERR_FORMAT,
                             "%s:%u: the header has %d values; expected at most 4 (points, dimension, attributes, "
                             "markers)",
                             t->path, t->line, n);
    uint32_t v[4] = {0, 2, 0, 0};
    static const char *names[4] = {"point count", "dimension", "attribute count", "marker count"};
    for (int i = 0; i < n; i++) {
        tsr_status s = parse_u32(t, &tok[i], names[i], &v[i], err);
        if (s != TSR_OK)
            return s;
    }
    if (v[1] != 2)
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s:%u: dimension %u; only 2 is supported", t->path, t->line,
                             v[1]);
    if (v[3] > 1)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: marker count %u; it is 0 or 1", t->path, t->line, v[3]);
    if (v[2] > MAX_TOKENS - 4)
        return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "%s:%u: %u attributes per point; at most %d are read", t->path,
                             t->line, v[2], MAX_TOKENS - 4);
    *none = v[0] == 0;
    if (v[0] == 0) {
        if (allow_none)
            return TSR_OK;
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s:%u: no points", t->path, t->line);
    }
    int k = 3 + (int)v[2] + (int)v[3];
    tsr_status s = fits(t, v[0], "points", err);
    if (s != TSR_OK)
        return s;
    g->xy = malloc(2 * (size_t)v[0] * sizeof *g->xy);
    if (!g->xy)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u points", t->path, v[0]);
    g->nv = v[0];
    g->nattr = v[2];
    if ((v[2] && !(g->attr = malloc((size_t)v[0] * v[2] * sizeof *g->attr))) ||
        (v[3] && !(g->marker = malloc((size_t)v[0] * sizeof *g->marker))))
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u points' attributes", t->path, v[0]);
    char layout[64];
    snprintf(layout, sizeof layout, "index x y%s%s", v[2] ? " attributes" : "", v[3] ? " marker" : "");
    for (uint32_t i = 0; i < v[0]; i++) {
        if ((s = record(t, tok, k, k, i, v[0], "points", layout, err)) != TSR_OK ||
            (s = check_index(t, &tok[0], i, base, "point", err)) != TSR_OK ||
            (s = parse_number(t, &tok[1], "x", &g->xy[2 * (size_t)i], err)) != TSR_OK ||
            (s = parse_number(t, &tok[2], "y", &g->xy[2 * (size_t)i + 1], err)) != TSR_OK)
            return s;
        for (uint32_t a = 0; a < v[2]; a++)
            if ((s = parse_number(t, &tok[3 + a], "attribute", &g->attr[(size_t)i * v[2] + a], err)) != TSR_OK)
                return s;
        if (v[3] && (s = parse_marker(t, &tok[3 + v[2]], &g->marker[i], err)) != TSR_OK)
            return s;
    }
    return TSR_OK;
}

static tsr_status read_node_text(const char *path, const char *buf, size_t len, cli_pslg *g, uint32_t *base,
                                 tsr_error *err)
{
    text t = {path, buf + bom_length(buf, len), buf + len, 1, 1, 0};
    bool none;
    tsr_status s = read_node_section(&t, g, base, false, &none, err);
    if (s != TSR_OK)
        return s;
    token tok[MAX_TOKENS];
    if (next_record(&t, tok) >= 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: more points than the %u the header gives", path, t.line,
                             g->nv);
    return TSR_OK;
}

void cli_pslg_node_path(const char *poly, char *buf, size_t cap)
{
    const char *e = extension(poly);
    snprintf(buf, cap, "%.*s.node", (int)(e - poly), poly);
}

static tsr_status read_poly_text(const char *path, const char *buf, size_t len, cli_pslg *g, tsr_error *err)
{
    text t = {path, buf + bom_length(buf, len), buf + len, 1, 1, 0};
    uint32_t base = UINT32_MAX;
    bool none;
    tsr_status s = read_node_section(&t, g, &base, true, &none, err);
    if (s != TSR_OK)
        return s;
    if (none) {
        char node[4096];
        cli_pslg_node_path(path, node, sizeof node);
        char *nb;
        size_t nl;
        if ((s = tsr_read_file(node, MAX_FILE_BYTES, NULL, &nb, &nl, err)) != TSR_OK) {
            if (s == TSR_ERR_NOT_FOUND)
                tsr_error_set(err, s, "%s:%u: 0 points, meaning they are in %s, which does not exist", path, t.line,
                              node);
            return s;
        }
        s = read_node_text(node, nb, nl, g, &base, err);
        tsr_free(NULL, nb);
        if (s != TSR_OK)
            return s;
        if (!(g->points_file = strdup(node)))
            return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    token tok[MAX_TOKENS];
    int n = next_record(&t, tok);
    if (n < 0)
        return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s:%u: the file ends before the segment count", path,
                             t.next_line);
    if (n > 2)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: the segment header has %d values; expected 1 or 2", path,
                             t.line, n);
    uint32_t ns, nb = 0;
    if ((s = parse_u32(&t, &tok[0], "segment count", &ns, err)) != TSR_OK ||
        (n == 2 && (s = parse_u32(&t, &tok[1], "marker count", &nb, err)) != TSR_OK))
        return s;
    if (nb > 1)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: marker count %u; it is 0 or 1", path, t.line, nb);
    int k = 3 + (int)nb;
    if ((s = fits(&t, ns, "segments", err)) != TSR_OK)
        return s;
    g->seg = malloc((2 * (size_t)ns + 1) * sizeof *g->seg);
    if (!g->seg)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u segments", path, ns);
    g->nseg = ns;
    if (nb && !(g->seg_marker = malloc(((size_t)ns + 1) * sizeof *g->seg_marker)))
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u segment markers", path, ns);
    for (uint32_t i = 0; i < ns; i++) {
        if ((s = record(&t, tok, k, k, i, ns, "segments", nb ? "index a b marker" : "index a b", err)) != TSR_OK ||
            (s = check_index(&t, &tok[0], i, &base, "segment", err)) != TSR_OK)
            return s;
        for (int e = 0; e < 2; e++) {
            uint32_t v;
            if ((s = parse_u32(&t, &tok[1 + e], "point index", &v, err)) != TSR_OK)
                return s;
            if (v < base || v - base >= g->nv)
                return tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: segment %u names point %u; points are %u to %llu",
                                     path, t.line, base + i, v, base, (unsigned long long)base + g->nv - 1);
            g->seg[2 * (size_t)i + e] = v - base;
        }
        if (nb && (s = parse_marker(&t, &tok[3], &g->seg_marker[i], err)) != TSR_OK)
            return s;
    }
    n = next_record(&t, tok);
    if (n < 0)
        return tsr_error_set(err, TSR_ERR_TRUNCATED, "%s:%u: the file ends before the hole count", path, t.next_line);
    if (n != 1)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected the hole count alone, found %d values", path,
                             t.line, n);
    uint32_t nh;
    if ((s = parse_u32(&t, &tok[0], "hole count", &nh, err)) != TSR_OK ||
        (s = fits(&t, nh, "holes", err)) != TSR_OK)
        return s;
    g->holes = malloc((2 * (size_t)nh + 1) * sizeof *g->holes);
    if (!g->holes)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u holes", path, nh);
    g->nholes = nh;
    for (uint32_t i = 0; i < nh; i++)
        if ((s = record(&t, tok, 3, 3, i, nh, "holes", "index x y", err)) != TSR_OK ||
            (s = check_index(&t, &tok[0], i, &base, "hole", err)) != TSR_OK ||
            (s = parse_number(&t, &tok[1], "x", &g->holes[2 * (size_t)i], err)) != TSR_OK ||
            (s = parse_number(&t, &tok[2], "y", &g->holes[2 * (size_t)i + 1], err)) != TSR_OK)
            return s;
    g->first_index = base;
    /* the regional attributes (Triangle's -A and -a), if any */
    if ((n = next_record(&t, tok)) < 0)
        return TSR_OK;
    if (n != 1)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected the region count alone, found %d values", path,
                             t.line, n);
    uint32_t nr;
    if ((s = parse_u32(&t, &tok[0], "region count", &nr, err)) != TSR_OK ||
        (s = fits(&t, nr, "regions", err)) != TSR_OK)
        return s;
    g->regions = malloc((4 * (size_t)nr + 1) * sizeof *g->regions);
    if (!g->regions)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u regions", path, nr);
    g->nregions = nr;
    for (uint32_t i = 0; i < nr; i++) {
        double *r = &g->regions[4 * (size_t)i];
        r[3] = -1;
        if ((s = record(&t, tok, 4, 5, i, nr, "regions", "index x y attribute [maximum-area]", err)) != TSR_OK ||
            (s = check_index(&t, &tok[0], i, &base, "region", err)) != TSR_OK ||
            (s = parse_number(&t, &tok[1], "x", &r[0], err)) != TSR_OK ||
            (s = parse_number(&t, &tok[2], "y", &r[1], err)) != TSR_OK ||
            (s = parse_number(&t, &tok[3], "attribute", &r[2], err)) != TSR_OK ||
            (t.ntok == 5 && (s = parse_number(&t, &tok[4], "maximum area", &r[3], err)) != TSR_OK))
            return s;
    }
    if (next_record(&t, tok) >= 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: more records than the %u regions the count gives", path,
                             t.line, nr);
    return TSR_OK;
}

/* ---- nV nE text ---------------------------------------------------------------- */

static tsr_status read_txt_text(const char *path, const char *buf, size_t len, cli_pslg *g, tsr_error *err)
{
    text t = {path, buf + bom_length(buf, len), buf + len, 1, 1, 0};
    token tok[MAX_TOKENS];
    int n = next_record(&t, tok);
    if (n < 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s: no header line (nV nE)", path);
    if (n != 2)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: expected the header 'nV nE', found %d values", path, t.line,
                             n);
    uint32_t nv, ne;
    tsr_status s;
    if ((s = parse_u32(&t, &tok[0], "vertex count", &nv, err)) != TSR_OK ||
        (s = parse_u32(&t, &tok[1], "edge count", &ne, err)) != TSR_OK)
        return s;
    if (nv == 0)
        return tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s:%u: no points", path, t.line);
    if ((s = fits(&t, (uint64_t)nv + ne, "points and edges", err)) != TSR_OK)
        return s;
    g->xy = malloc(2 * (size_t)nv * sizeof *g->xy);
    g->seg = malloc((2 * (size_t)ne + 1) * sizeof *g->seg);
    if (!g->xy || !g->seg)
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %u points and %u edges", path, nv, ne);
    g->nv = nv;
    g->nseg = ne;
    for (uint32_t i = 0; i < nv; i++)
        if ((s = record(&t, tok, 2, 2, i, nv, "points", "x y", err)) != TSR_OK ||
            (s = parse_number(&t, &tok[0], "x", &g->xy[2 * (size_t)i], err)) != TSR_OK ||
            (s = parse_number(&t, &tok[1], "y", &g->xy[2 * (size_t)i + 1], err)) != TSR_OK)
            return s;
    for (uint32_t i = 0; i < ne; i++) {
        if ((s = record(&t, tok, 2, 2, i, ne, "edges", "i j", err)) != TSR_OK)
            return s;
        for (int e = 0; e < 2; e++) {
            uint32_t v;
            if ((s = parse_u32(&t, &tok[e], "vertex index", &v, err)) != TSR_OK)
                return s;
            if (v >= nv)
                return tsr_error_set(err, TSR_ERR_VALUE, "%s:%u: edge %u names vertex %u; there are %u (0 to %u)",
                                     path, t.line, i, v, nv, nv - 1);
            g->seg[2 * (size_t)i + e] = v;
        }
    }
    if (next_record(&t, tok) >= 0)
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u: more lines than the %u points and %u edges of the header",
                             path, t.line, nv, ne);
    return TSR_OK;
}

/* ---- JSON rings -------------------------------------------------------------- */

static const char *json_kind(const cJSON *j)
{
    return cJSON_IsObject(j)   ? "an object"
           : cJSON_IsArray(j)  ? "an array"
           : cJSON_IsString(j) ? "a string"
           : cJSON_IsNumber(j) ? "a number"
           : cJSON_IsBool(j)   ? "a boolean"
           : cJSON_IsNull(j)   ? "null"
                               : "something else";
}

static bool same_point(const cJSON *a, const cJSON *b)
{
    return cJSON_GetArrayItem(a, 0)->valuedouble == cJSON_GetArrayItem(b, 0)->valuedouble &&
           cJSON_GetArrayItem(a, 1)->valuedouble == cJSON_GetArrayItem(b, 1)->valuedouble;
}

static tsr_status read_json_text(const char *path, const char *buf, size_t len, cli_pslg *g, tsr_error *err)
{
    const char *end = NULL;
    size_t bom = bom_length(buf, len);
    cJSON *root = cJSON_ParseWithLengthOpts(buf + bom, len - bom, &end, false);
    size_t off = end && end >= buf && end <= buf + len ? (size_t)(end - buf) : bom;
    if (root) /* only white space may follow the value */
        while (off < len && (buf[off] == ' ' || buf[off] == '\t' || buf[off] == '\r' || buf[off] == '\n'))
            off++;
    if (!root || off < len) {
        uint32_t line = 1, col = 1;
        for (size_t i = 0; i < off; i++) {
            if (buf[i] == '\n')
                line++, col = 1;
            else
                col++;
        }
        cJSON_Delete(root);
        return tsr_error_set(err, TSR_ERR_FORMAT, "%s:%u:%u: %s (byte %zu)", path, line, col,
                             root ? "unexpected data after the JSON value" : "not valid JSON", off);
    }
    tsr_status s = TSR_OK;
    if (!cJSON_IsArray(root)) {
        s = tsr_error_set(err, TSR_ERR_FORMAT, "%s: $: not a polygon: expected an array of rings, found %s", path,
                          json_kind(root));
        goto done;
    }
    /* count and validate first */
    uint64_t np = 0, ns = 0;
    uint32_t r = 0;
    for (const cJSON *ring = root->child; ring; ring = ring->next, r++) {
        if (!cJSON_IsArray(ring)) {
            s = tsr_error_set(err, TSR_ERR_FORMAT, "%s: $[%u]: ring %u is %s, not an array of [x, y] points", path, r,
                              r, json_kind(ring));
            goto done;
        }
        uint32_t p = 0;
        for (const cJSON *pt = ring->child; pt; pt = pt->next, p++) {
            const cJSON *x = cJSON_GetArrayItem(pt, 0), *y = cJSON_GetArrayItem(pt, 1);
            if (!cJSON_IsArray(pt) || cJSON_GetArraySize(pt) != 2 || !cJSON_IsNumber(x) || !cJSON_IsNumber(y)) {
                s = tsr_error_set(err, TSR_ERR_FORMAT, "%s: $[%u][%u]: ring %u, point %u is %s, not [x, y]", path, r, p,
                                  r, p, cJSON_IsArray(pt) ? "an array of other than two numbers" : json_kind(pt));
                goto done;
            }
            if (!isfinite(x->valuedouble) || !isfinite(y->valuedouble)) {
                s = tsr_error_set(err, TSR_ERR_VALUE, "%s: $[%u][%u]: ring %u, point %u has a non-finite coordinate",
                                  path, r, p, r, p);
                goto done;
            }
        }
        int n = cJSON_GetArraySize(ring);
        if (n > 1 && same_point(cJSON_GetArrayItem(ring, 0), cJSON_GetArrayItem(ring, n - 1)))
            n--;
        np += (uint64_t)n;
        ns += n > 1 ? (uint64_t)n : 0;
    }
    if (np == 0) {
        s = tsr_error_set(err, TSR_ERR_TOO_SMALL, "%s: no points", path);
        goto done;
    }
    if (np > UINT32_MAX || ns > UINT32_MAX) {
        s = tsr_error_set(err, TSR_ERR_TOO_LARGE, "%s: %llu points, beyond 2^32 - 1", path, (unsigned long long)np);
        goto done;
    }
    g->xy = malloc(2 * (size_t)np * sizeof *g->xy);
    g->seg = malloc((2 * (size_t)ns + 1) * sizeof *g->seg);
    if (!g->xy || !g->seg) {
        s = tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory for %llu points", path, (unsigned long long)np);
        goto done;
    }
    for (const cJSON *ring = root->child; ring; ring = ring->next) {
        int n = cJSON_GetArraySize(ring);
        if (n > 1 && same_point(cJSON_GetArrayItem(ring, 0), cJSON_GetArrayItem(ring, n - 1)))
            n--;
        uint32_t first = g->nv;
        int k = 0;
        for (const cJSON *pt = ring->child; pt && k < n; pt = pt->next, k++) {
            g->xy[2 * (size_t)g->nv] = cJSON_GetArrayItem(pt, 0)->valuedouble;
            g->xy[2 * (size_t)g->nv + 1] = cJSON_GetArrayItem(pt, 1)->valuedouble;
            g->nv++;
        }
        for (int i = 0; n > 1 && i < n; i++) {
            g->seg[2 * (size_t)g->nseg] = first + (uint32_t)i;
            g->seg[2 * (size_t)g->nseg + 1] = first + (uint32_t)((i + 1) % n);
            g->nseg++;
        }
        g->rings++;
    }
done:
    cJSON_Delete(root);
    return s;
}

/* ---- Reading ---------------------------------------------------------------- */

tsr_status cli_pslg_read(const char *path, cli_pslg_format f, cli_pslg *out, tsr_error *err)
{
    memset(out, 0, sizeof *out);
    if (f == CLI_PSLG_UNKNOWN)
        f = cli_pslg_format_from_path(path);
    if (f == CLI_PSLG_UNKNOWN)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "%s: unknown input format (use .node, .poly, .json or .txt, or --format)", path);
    char *buf;
    size_t len;
    tsr_status s = tsr_read_file(path, MAX_FILE_BYTES, NULL, &buf, &len, err);
    if (s != TSR_OK)
        return s;
    uint32_t base = UINT32_MAX;
    switch (f) {
    case CLI_PSLG_NODE:
        s = read_node_text(path, buf, len, out, &base, err);
        out->first_index = base;
        break;
    case CLI_PSLG_POLY: s = read_poly_text(path, buf, len, out, err); break;
    case CLI_PSLG_JSON: s = read_json_text(path, buf, len, out, err); break;
    default: s = read_txt_text(path, buf, len, out, err); break;
    }
    tsr_free(NULL, buf);
    if (s != TSR_OK) {
        cli_pslg_free(out);
        return s;
    }
    out->format = f;
    if (f != CLI_PSLG_NODE && f != CLI_PSLG_POLY)
        out->first_index = 1;
    return TSR_OK;
}

/* ---- Writers ----------------------------------------------------------------- */

/* File numbers (from base) of the output vertices: an input point's is its
 * input number (a point given twice: the first's), a Steiner point's
 * follows the ninput input points. */
static uint32_t *file_numbers(const tsr_triangulation *t, uint32_t ninput, uint32_t base)
{
    uint32_t *num = malloc(((size_t)t->nv + 1) * sizeof *num);
    if (!num)
        return NULL;
    for (uint32_t v = 0; v < t->nv; v++)
        num[v] = v < t->input_vertices ? 0 : ninput + base + (v - t->input_vertices);
    for (uint32_t i = ninput; i-- > 0;) /* from the end: the first occurrence wins */
        num[t->vertex_of_input[i]] = i + base;
    return num;
}

/* Triangles at each vertex (CSR), for the boundary tests. */
typedef struct vtris {
    uint32_t *first, *list;
} vtris;

static bool vtris_build(vtris *c, const tsr_triangulation *t)
{
    c->first = calloc((size_t)t->nv + 2, sizeof *c->first);
    c->list = malloc((3 * (size_t)t->nt + 1) * sizeof *c->list);
    if (!c->first || !c->list)
        return false;
    for (size_t i = 0; i < 3 * (size_t)t->nt; i++)
        c->first[t->tri[i] + 2]++;
    for (uint32_t v = 0; v < t->nv; v++)
        c->first[v + 2] += c->first[v + 1];
    for (size_t i = 0; i < 3 * (size_t)t->nt; i++)
        c->list[c->first[t->tri[i] + 1]++] = (uint32_t)(i / 3);
    return true;
}

/* How many triangles have the edge u-w (either way). */
static uint32_t edge_triangles(const vtris *c, const tsr_triangulation *t, uint32_t u, uint32_t w)
{
    uint32_t n = 0;
    for (uint32_t j = c->first[u]; j < c->first[u + 1]; j++) {
        const uint32_t *q = &t->tri[3 * (size_t)c->list[j]];
        n += q[0] == w || q[1] == w || q[2] == w;
    }
    return n;
}

/* Boundary markers of the output vertices (vm, t->nv) and of the
 * constrained edges (em, t->nedge), as cli_tri_write_triangle says. */
static bool markers(const tsr_triangulation *t, const cli_pslg *g, int32_t *vm, int32_t *em)
{
    vtris c;
    if (!vtris_build(&c, t)) {
        free(c.first);
        free(c.list);
        return false;
    }
    memset(vm, 0, (size_t)t->nv * sizeof *vm);
    for (uint32_t i = 0; g->marker && i < g->nv; i++)
        if (!vm[t->vertex_of_input[i]])
            vm[t->vertex_of_input[i]] = g->marker[i];
    for (uint32_t e = 0; e < t->nedge; e++) {
        int32_t m = g->seg_marker ? g->seg_marker[t->edge_segment[e]] : 0;
        for (int k = 0; k < 2 && m; k++)
            if (!vm[t->edge[2 * (size_t)e + k]])
                vm[t->edge[2 * (size_t)e + k]] = m;
        em[e] = !g->seg_marker ? (int32_t)(t->edge_segment[e] + 1)
                : m            ? m
                               : edge_triangles(&c, t, t->edge[2 * (size_t)e], t->edge[2 * (size_t)e + 1]) == 1;
    }
    for (uint32_t i = 0; i < t->nt; i++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = t->tri[3 * (size_t)i + k], w = t->tri[3 * (size_t)i + (k + 1) % 3];
            if ((!vm[u] || !vm[w]) && edge_triangles(&c, t, u, w) == 1) {
                vm[u] = vm[u] ? vm[u] : 1;
                vm[w] = vm[w] ? vm[w] : 1;
            }
        }
    free(c.first);
    free(c.list);
    return true;
}

static void write_row(FILE *f, uint32_t num, const double *xy, const double *attr, uint32_t nattr, int32_t marker)
{
    fprintf(f, "%u %.17g %.17g", num, xy[0], xy[1]);
    for (uint32_t a = 0; a < nattr; a++)
        fprintf(f, " %.17g", attr[a]);
    fprintf(f, " %d\n", (int)marker);
}

static void write_node(FILE *f, const tsr_triangulation *t, const cli_pslg *g, const double *vals, const int32_t *vm)
{
    uint32_t ninput = g->nv, steiner = t->nv - t->input_vertices, n = ninput + steiner, na = g->nattr;
    uint32_t base = g->first_index;
    fprintf(f,
            "# Tessera triangulation: %u vertices (%u-based, as the input), x y%s boundary-marker: the %u input "
            "points in input order (the k-th is vertex k), then %u Steiner points%s\n%u 2 %u 1\n",
            n, base, na ? " attributes" : "", ninput, steiner,
            na ? " (their attributes interpolated linearly over the input's triangulation)" : "", n, na);
    for (uint32_t i = 0; i < ninput; i++) {
        uint32_t v = t->vertex_of_input[i];
        write_row(f, i + base, t->xy + 2 * (size_t)v, na ? g->attr + (size_t)i * na : NULL, na,
                  g->marker && g->marker[i] ? g->marker[i] : vm[v]);
    }
    for (uint32_t v = t->input_vertices; v < t->nv; v++)
        write_row(f, ninput + base + (v - t->input_vertices), t->xy + 2 * (size_t)v, na ? vals + (size_t)v * na : NULL,
                  na, vm[v]);
}

static void write_ele(FILE *f, const tsr_triangulation *t, const uint32_t *num, const cli_pslg *g,
                      const uint32_t *region)
{
    fprintf(f, "# Tessera triangulation: %u triangles, counter-clockwise, vertices of the .node%s\n%u 3 %d\n", t->nt,
            region ? "; the regional attribute of each" : "", t->nt, region != NULL);
    for (uint32_t i = 0; i < t->nt; i++) {
        fprintf(f, "%u %u %u %u", i + g->first_index, num[t->tri[3 * (size_t)i]], num[t->tri[3 * (size_t)i + 1]],
                num[t->tri[3 * (size_t)i + 2]]);
        if (region)
            fprintf(f, " %.17g", region[i] == UINT32_MAX ? 0.0 : g->regions[4 * (size_t)region[i] + 2]);
        fputc('\n', f);
    }
}

static void write_poly(FILE *f, const tsr_triangulation *t, const uint32_t *num, const cli_pslg *g, const int32_t *em)
{
    fprintf(f,
            "# Tessera triangulation: constrained edges; marker = %s\n"
            "# 0 points: they are in the .node file of the same name\n0 2 0 0\n%u 1\n",
            g->seg_marker ? "the input segment's marker (1 for a 0 on the boundary)" : "input segment number",
            t->nedge);
    for (uint32_t e = 0; e < t->nedge; e++)
        fprintf(f, "%u %u %u %d\n", e + g->first_index, num[t->edge[2 * (size_t)e]], num[t->edge[2 * (size_t)e + 1]],
                (int)em[e]);
    fprintf(f, "%u\n", g->nholes);
    for (uint32_t h = 0; h < g->nholes; h++)
        fprintf(f, "%u %.17g %.17g\n", h + g->first_index, g->holes[2 * (size_t)h], g->holes[2 * (size_t)h + 1]);
    if (g->nregions)
        fprintf(f, "%u\n", g->nregions);
    for (uint32_t r = 0; r < g->nregions; r++) {
        const double *q = &g->regions[4 * (size_t)r];
        fprintf(f, "%u %.17g %.17g %.17g %.17g\n", r + g->first_index, q[0], q[1], q[2], q[3]);
    }
}

bool cli_tri_output_names(const char *path, char (*names)[4096])
{
    static const char *const ext[3] = {".node", ".ele", ".poly"};
    size_t base = (size_t)(extension(path) - path);
    for (int i = 0; i < 3; i++)
        if (snprintf(names[i], 4096, "%.*s%s", (int)base, path, ext[i]) >= 4096)
            return false;
    return true;
}

tsr_status cli_tri_write_triangle(const char *path, const tsr_triangulation *t, const cli_pslg *g, const double *vals,
                                  tsr_error *err)
{
    char name[3][4096], tmp[3][4200];
    int begun = 0;
    tsr_status s = TSR_OK;
    if (!cli_tri_output_names(path, name))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "%s: output path too long", path);
    uint32_t *num = file_numbers(t, g->nv, g->first_index), *region = NULL;
    int32_t *vm = malloc(((size_t)t->nv + 1) * sizeof *vm), *em = malloc(((size_t)t->nedge + 1) * sizeof *em);
    double *seeds = g->nregions ? malloc(2 * (size_t)g->nregions * sizeof *seeds) : NULL;
    for (uint32_t r = 0; seeds && r < g->nregions; r++)
        seeds[2 * r] = g->regions[4 * (size_t)r], seeds[2 * r + 1] = g->regions[4 * (size_t)r + 1];
    if (g->nregions && (!seeds || !(region = malloc(((size_t)t->nt + 1) * sizeof *region)) ||
                        tsr_tri_regions(t, seeds, g->nregions, region, NULL, err) != TSR_OK))
        s = TSR_ERR_NOMEM;
    free(seeds);
    if (s != TSR_OK || !num || !vm || !em || !markers(t, g, vm, em)) {
        free(num);
        free(vm);
        free(em);
        free(region);
        return tsr_error_set(err, TSR_ERR_NOMEM, "%s: out of memory", path);
    }
    for (; begun < 3; begun++)
        if ((s = tsr_atomic_begin(name[begun], tmp[begun], sizeof tmp[begun], err)) != TSR_OK)
            goto fail;
    for (int i = 0; i < 3; i++) {
        FILE *f = fopen(tmp[i], "w");
        if (!f) {
            s = tsr_error_set(err, TSR_ERR_IO, "%s: cannot write: %s", name[i], strerror(errno));
            goto fail;
        }
        if (i == 0)
            write_node(f, t, g, vals, vm);
        else if (i == 1)
            write_ele(f, t, num, g, region);
        else
            write_poly(f, t, num, g, em);
        bool bad = ferror(f) != 0;
        int saved = errno;
        if (fclose(f) != 0 && !bad) {
            bad = true;
            saved = errno;
        }
        if (bad) {
            s = tsr_error_set(err, TSR_ERR_IO, "%s: write failed: %s", name[i], strerror(saved ? saved : EIO));
            goto fail;
        }
    }
    for (int i = 0; i < 3; i++)
        if ((s = tsr_atomic_commit(tmp[i], name[i], err)) != TSR_OK) {
            /* leave no half set: the ones renamed already go too */
            for (int j = 0; j < i; j++)
                remove(name[j]);
            for (int j = i + 1; j < 3; j++)
                tsr_atomic_abort(tmp[j]);
            goto done;
        }
    goto done;
fail:
    for (int i = 0; i < begun; i++)
        tsr_atomic_abort(tmp[i]);
done:
    free(num);
    free(vm);
    free(em);
    free(region);
    return s;
}

tsr_status cli_tri_write_mesh(const char *path, const tsr_triangulation *t, const double *vals, uint32_t nvals,
                              uint32_t z_col, tsr_error *err)
{
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_status s = tsr_mesh_reserve(&m, t->nv, t->nt);
    if (s != TSR_OK) {
        tsr_mesh_free(&m);
        return tsr_error_set(err, s, "%s: out of memory for the mesh", path);
    }
    for (uint32_t v = 0; v < t->nv; v++) {
        float p[3] = {(float)t->xy[2 * (size_t)v], (float)t->xy[2 * (size_t)v + 1],
                      vals ? (float)vals[(size_t)v * nvals + z_col] : 0.0f};
        tsr_mesh_add_vertex(&m, p, NULL, NULL);
    }
    for (uint32_t i = 0; i < t->nt; i++)
        tsr_mesh_add_triangle(&m, t->tri[3 * (size_t)i], t->tri[3 * (size_t)i + 1], t->tri[3 * (size_t)i + 2]);
    s = tsr_mesh_write(&m, path, TSR_FORMAT_UNKNOWN, err);
    tsr_mesh_free(&m);
    return s;
}
