/* cli.c: shared helpers of the tessera subcommands. */
#define _POSIX_C_SOURCE 200809L
#define _DEFAULT_SOURCE /* realpath */
#include "cli.h"

#include <cjson/cJSON.h>

#include <errno.h>
#include <float.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>
#include <fcntl.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

void (*volatile cli_signal_cleanup)(void);

void cli_error(const char *cmd, const char *fmt, ...)
{
    fprintf(stderr, "tessera%s%s: ", cmd ? " " : "", cmd ? cmd : "");
    va_list ap;
    va_start(ap, fmt);
    vfprintf(stderr, fmt, ap);
    va_end(ap);
    fputc('\n', stderr);
}

bool cli_parse_double(const char *s, double *out)
{
    if (!s || !*s)
        return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (*end != '\0' || errno == ERANGE || !isfinite(v))
        return false;
    *out = v;
    return true;
}

bool cli_parse_u32(const char *s, uint32_t min, uint32_t max, uint32_t *out)
{
    if (!s || !*s || *s == '-' || *s == '+')
        return false;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, 10);
    if (*end != '\0' || errno == ERANGE || v < min || v > max)
        return false;
    *out = (uint32_t)v;
    return true;
}

bool cli_tile_size_ok(uint32_t n) { return n >= TSR_TILE_MIN && n <= TSR_TILE_MAX && !(n & (n - 1)); }

bool cli_is_help(const char *arg) { return !strcmp(arg, "-h") || !strcmp(arg, "--help"); }

/* Edit distance of a and b (at most 64 characters of each compared). */
static unsigned edit_distance(const char *a, const char *b)
{
    size_t na = strlen(a), nb = strlen(b);
    na = na > 64 ? 64 : na;
    nb = nb > 64 ? 64 : nb;
    unsigned row[65];
    for (size_t j = 0; j <= nb; j++)
        row[j] = (unsigned)j;
    for (size_t i = 1; i <= na; i++) {
        unsigned diag = row[0];
        row[0] = (unsigned)i;
        for (size_t j = 1; j <= nb; j++) {
            unsigned up = row[j];
            unsigned best = diag + (a[i - 1] != b[j - 1]);
            best = up + 1 < best ? up + 1 : best;
            best = row[j - 1] + 1 < best ? row[j - 1] + 1 : best;
            row[j] = best;
            diag = up;
        }
    }
    return row[nb];
}

/* The options a help text lists: lines that begin with spaces and a dash,
 * "--opt VALUE, --alias VALUE  description" (the names and values up to two
 * spaces); where a line's names are followed by a word, they take a value.
 * Calls each(name, length, valued, user) for each. */
static void help_options(const char *text, void (*each)(const char *, size_t, bool, void *), void *user)
{
    for (const char *l = text; l && *l;) {
        const char *eol = strchr(l, '\n');
        const char *end = eol ? eol : l + strlen(l);
        const char *p = l;
        while (p < end && *p == ' ')
            p++;
        if (p > l && p < end && *p == '-') {
            const char *gap = p;
            while (gap < end && !(gap[0] == ' ' && gap + 1 < end && gap[1] == ' '))
                gap++;
            const char *names[8];
            size_t lens[8];
            int n = 0;
            bool valued = false;
            for (const char *q = p; q < gap;) {
                while (q < gap && (*q == ' ' || *q == ','))
                    q++;
                const char *w = q;
                while (q < gap && *q != ' ' && *q != ',')
                    q++;
                if (q == w)
                    continue;
                if (*w != '-')
                    valued = true;
                else if (n < 8) {
                    names[n] = w;
                    lens[n++] = (size_t)(q - w);
                }
            }
            for (int k = 0; k < n; k++)
                each(names[k], lens[k], valued, user);
        }
        l = eol ? eol + 1 : NULL;
    }
}

typedef struct option_match {
    const char *a;
    bool valued;            /* a is listed with a value */
    char best[64];          /* the nearest listed option */
    unsigned best_d;
    int prefixed;           /* how many listed options a is a prefix of */
    char prefix_of[64];
} option_match;

static void match_option(const char *name, size_t len, bool valued, void *user)
{
    option_match *m = user;
    char opt[64];
    if (len >= sizeof opt || len < 2)
        return;
    memcpy(opt, name, len);
    opt[len] = '\0';
    if (!strcmp(opt, m->a)) {
        m->valued |= valued;
        return;
    }
    if (!strncmp(opt, m->a, strlen(m->a)) && strcmp(opt, m->prefix_of)) {
        m->prefixed++;
        memcpy(m->prefix_of, opt, len + 1);
    }
    unsigned d = edit_distance(m->a, opt);
    if (d < m->best_d) {
        m->best_d = d;
        memcpy(m->best, opt, len + 1);
    }
}

void cli_option_error(const char *cmd, const char *sub, const char *a, void (*help)(FILE *))
{
    option_match m = {.a = a, .best_d = UINT32_MAX};
    char *text = NULL;
    size_t size = 0;
    FILE *f = help ? open_memstream(&text, &size) : NULL;
    if (f) {
        help(f);
        if (fclose(f) == 0)
            help_options(text, match_option, &m);
    }
    free(text);
    char pre[64], see[128], hint[96] = "";
    snprintf(pre, sizeof pre, "%s%s", sub ? sub : "", sub ? ": " : "");
    snprintf(see, sizeof see, "see tessera %s%s%s --help", cmd, sub ? " " : "", sub ? sub : "");
    const char *near = m.prefixed == 1 ? m.prefix_of : m.best_d <= 2 && strlen(a) > 3 ? m.best : NULL;
    if (near)
        snprintf(hint, sizeof hint, ": did you mean %s?", near);
    cli_error(cmd, "%s%s '%s'%s (%s)", pre, m.valued ? "missing value for" : "unknown option", a,
              m.valued ? "" : hint, see);
}

double cli_now(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + ts.tv_nsec * 1e-9;
}

int cli_heightfield_option(const char *cmd, int argc, char **argv, int *i, cli_heightfield_options *o)
{
    const char *a = argv[*i];
    if (!strcmp(a, "--decode")) {
        if (*i + 1 >= argc) {
            cli_error(cmd, "--decode needs a value (terrain-rgb)");
            return -1;
        }
        const char *v = argv[++*i];
        if (strcmp(v, "terrain-rgb") && strcmp(v, "terrainrgb")) {
            cli_error(cmd, "--decode %s: unknown decoding (known: terrain-rgb)", v);
            return -1;
        }
        o->load.decode = TSR_DECODE_TERRAIN_RGB;
        return 1;
    }
    if (!strcmp(a, "--raw")) {
        if (*i + 3 >= argc) {
            cli_error(cmd, "--raw needs three values: W H TYPE (TYPE u16, i16 or f32)");
            return -1;
        }
        uint32_t w, h;
        if (!cli_parse_u32(argv[*i + 1], 1, UINT32_MAX, &w) || !cli_parse_u32(argv[*i + 2], 1, UINT32_MAX, &h)) {
            cli_error(cmd, "--raw %s %s: width and height must be positive integers", argv[*i + 1], argv[*i + 2]);
            return -1;
        }
        tsr_raw_type t = tsr_raw_type_parse(argv[*i + 3]);
        if (t == TSR_RAW_NONE) {
            if (argv[*i + 3][0] == '-')
                cli_error(cmd, "--raw %s %s %s: TYPE missing: --raw needs three values, W H TYPE (TYPE u16, i16 or "
                          "f32)", argv[*i + 1], argv[*i + 2], argv[*i + 3]);
            else
                cli_error(cmd, "--raw: unknown sample type '%s' (use u16, i16 or f32)", argv[*i + 3]);
            return -1;
        }
        o->load.raw_type = t;
        o->load.raw_width = w;
        o->load.raw_height = h;
        *i += 3;
        return 1;
    }
    double *target = !strcmp(a, "--nodata") ? &o->load.nodata
                     : !strcmp(a, "--dx")   ? &o->dx
                     : !strcmp(a, "--dy")   ? &o->dy
                     : !strcmp(a, "--dz")   ? &o->dz
                                            : NULL;
    if (!target)
        return 0;
    if (*i + 1 >= argc) {
        cli_error(cmd, "%s needs a number", a);
        return -1;
    }
    double v;
    if (!cli_parse_double(argv[*i + 1], &v)) {
        cli_error(cmd, "%s %s: not a finite number", a, argv[*i + 1]);
        return -1;
    }
    if (target != &o->load.nodata && !(v > 0)) {
        cli_error(cmd, "%s %s: must be positive", a, argv[*i + 1]);
        return -1;
    }
    /* vertices and cameras are floats: a scale beyond these makes samples
     * one point (1e-300 is 0 as a float) or positions infinite */
    if (target != &o->load.nodata && !(v >= 1e-15 && v <= 1e15)) {
        cli_error(cmd, "%s %s: must be between 1e-15 and 1e15", a, argv[*i + 1]);
        return -1;
    }
    if (target == &o->load.nodata)
        o->load.has_nodata = true;
    *target = v;
    ++*i;
    return 1;
}

bool cli_spacing(const tsr_heightfield *hf, const cli_heightfield_options *o, double *dx, double *dy)
{
    const tsr_georef *g = tsr_heightfield_georef(hf);
    bool file = o->dx <= 0 && o->dy <= 0 && g && g->has_spacing;
    *dx = o->dx > 0 ? o->dx : file ? g->spacing[0] : 1;
    *dy = o->dy > 0 ? o->dy : o->dx > 0 ? o->dx : file ? g->spacing[1] : 1;
    return file;
}

void cli_georef_describe(const tsr_heightfield *hf, const cli_heightfield_options *o, char *buf, size_t cap)
{
    const tsr_georef *g = tsr_heightfield_georef(hf);
    double dx, dy;
    bool file = cli_spacing(hf, o, &dx, &dy);
    bool given = o->dx > 0 || o->dy > 0;
    const char *how = !file                 ? (given             ? "as given"
                                               : g && g->rotated ? "default: the file's grid is rotated or "
                                                                   "sheared, which is not followed"
                                                                 : "default")
                      : g->spacing_unitless ? "from the file, in its unknown unit"
                      : g->spacing_crs      ? "metres, the file's pixel in its CRS, within 1 % of the ground's"
                      : g->spacing_approx   ? "ground metres at the file's middle; it varies across"
                                            : "ground metres, from the file";
    int n = snprintf(buf, cap, "%.9g x %.9g (%s)", dx, dy, how);
    if (g && g->crs_name[0] && n >= 0 && (size_t)n < cap)
        snprintf(buf + n, cap - (size_t)n, "; %s", g->crs_name);
}

void cli_georef_warnings(const char *cmd, const char *path, const tsr_heightfield *hf,
                         const cli_heightfield_options *o)
{
    const tsr_georef *g = tsr_heightfield_georef(hf);
    if (!g)
        return;
    if (g->rotated && o->dx <= 0 && o->dy <= 0)
        fprintf(stderr, "tessera %s: %s: warning: the file's grid is rotated or sheared (its geotransform), which "
                "is not followed: samples are placed 1 apart on an axis-aligned grid; give --dx and --dy\n",
                cmd, path);
    const char *u = g->z_unit;
    bool feet = strstr(u, "ft") || strstr(u, "foot") || strstr(u, "feet") || strstr(u, "Foot") || strstr(u, "Feet");
    double dx, dy;
    if (feet && o->dz <= 0 && cli_spacing(hf, o, &dx, &dy) && !g->spacing_unitless)
        fprintf(stderr, "tessera %s: %s: warning: the heights are in %s while x and y are in metres: the relief is "
                "3.28 times too high unless --dz 0.3048 (US survey feet: 0.3048006) is given\n", cmd, path, u);
    /* no CRS, a cell far below a metre at a place that could be a
     * longitude and latitude: most likely degrees (an Esri grid in lon/lat
     * without its .prj), and the relief then some 10^5 times too steep */
    if (g->spacing_unitless && g->has_transform && o->dx <= 0 && o->dy <= 0 &&
        fmax(fabs(g->pixel[0]), fabs(g->pixel[1])) <= 0.01 && fabs(g->origin[0]) <= 180 && fabs(g->origin[1]) <= 90 &&
        fmax(fabs(g->origin[0]), fabs(g->origin[1])) >= 1) /* (not a lab scan's grid at 0, 0) */
        fprintf(stderr,
                "tessera %s: %s: warning: the file names no CRS and its cells are %g x %g at (%g, %g): "
                "likely degrees of longitude and latitude, so x and y come out about 10^5 times too small against "
                "the heights; give --dx and --dy in the heights' unit (a degree of latitude is 111,320 m)\n",
                cmd, path, fabs(g->pixel[0]), fabs(g->pixel[1]), g->origin[0], g->origin[1]);
}

static void add_pair(cJSON *o, const char *key, double a, double b)
{
    cJSON *arr = cJSON_AddArrayToObject(o, key);
    cJSON_AddItemToArray(arr, cJSON_CreateNumber(a));
    cJSON_AddItemToArray(arr, cJSON_CreateNumber(b));
}

void cli_georef_json(cJSON *j, const tsr_heightfield *hf, const cli_heightfield_options *o)
{
    static const char *kinds[] = {"none", "projected", "geographic", "other"};
    const tsr_georef *g = tsr_heightfield_georef(hf);
    double dx, dy;
    bool file = cli_spacing(hf, o, &dx, &dy);
    add_pair(j, "spacing", dx, dy);
    cJSON_AddStringToObject(j, "spacing_from", file ? "file" : o->dx > 0 || o->dy > 0 ? "options" : "default");
    if (!g)
        return;
    cJSON *gj = cJSON_AddObjectToObject(j, "georef");
    cJSON_AddStringToObject(gj, "crs", g->crs_name);
    cJSON_AddStringToObject(gj, "crs_kind", kinds[g->crs]);
    if (g->has_transform) {
        add_pair(gj, "origin", g->origin[0], g->origin[1]);
        add_pair(gj, "pixel", g->pixel[0], g->pixel[1]);
    }
    if (g->has_spacing) {
        if (!g->spacing_unitless)
            add_pair(gj, "ground_spacing", g->ground[0], g->ground[1]);
        cJSON_AddBoolToObject(gj, "ground_spacing_varies", g->spacing_approx);
        cJSON_AddBoolToObject(gj, "ground_spacing_unitless", g->spacing_unitless);
        cJSON_AddBoolToObject(gj, "spacing_crs", g->spacing_crs);
    }
    if (g->has_nodata)
        cJSON_AddNumberToObject(gj, "nodata_value", g->nodata);
    if (g->z_unit[0])
        cJSON_AddStringToObject(gj, "z_unit", g->z_unit);
    if (g->z_scale != 1 || g->z_offset != 0) {
        cJSON_AddNumberToObject(gj, "z_scale", g->z_scale);
        cJSON_AddNumberToObject(gj, "z_offset", g->z_offset);
    }
}

/* A file that names no no-data value (a raw file, a GeoTIFF without
 * GDAL_NODATA) may still hold one of the values GIS tools write for it:
 * warned of when its lowest height is such a value and lies far below the
 * rest (a tenth of their range or more), as no real terrain does. */
static void warn_sentinel(const char *cmd, const char *path, const tsr_heightfield *hf,
                          const cli_heightfield_options *o)
{
    const tsr_georef *g = tsr_heightfield_georef(hf);
    if (o->load.has_nodata || o->load.decode != TSR_DECODE_NONE || (g && g->has_nodata))
        return;
    /* the lowest height first (the statistics' vector pass): most files
     * stop here, without the counting pass below */
    static const float sentinels[] = {-9999.0f, -32768.0f, -32767.0f, -99999.0f};
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    bool common = false;
    for (size_t k = 0; k < sizeof sentinels / sizeof sentinels[0]; k++)
        common |= st.valid && (float)st.min == sentinels[k];
    if (!common)
        return;
    const float *d = tsr_heightfield_cdata(hf);
    size_t n = (size_t)tsr_heightfield_width(hf) * tsr_heightfield_height(hf);
    float lo = INFINITY, next = INFINITY, hi = -INFINITY;
    uint64_t at = 0;
    for (size_t i = 0; i < n; i++) {
        float v = d[i];
        if (v != v)
            continue;
        hi = v > hi ? v : hi;
        if (v < lo) {
            next = lo;
            lo = v;
            at = 1;
        } else if (v == lo)
            at++;
        else if (v < next)
            next = v;
    }
    if (!(next < INFINITY) || !(next - lo >= 0.1 * (hi - next)))
        return;
    fprintf(stderr,
            "tessera %s: warning: %s: %llu sample%s hold%s %g, a value GIS tools write for no-data, far below the "
            "others (from %g); the file names no no-data value, so they are heights: give --nodata %g if they are "
            "holes\n",
            cmd, path, (unsigned long long)at, at == 1 ? "" : "s", at == 1 ? "s" : "", (double)lo, (double)next,
            (double)lo);
}

tsr_heightfield *cli_load_heightfield(const char *cmd, const char *path, const cli_heightfield_options *o)
{
    tsr_heightfield *hf = NULL;
    tsr_error err = {0};
    /* Image libraries underneath (libpng, libtiff) may print their own
     * warnings to stderr; our one-line error says the same with the file
     * name, so their noise is held back while loading. */
    fflush(stderr);
    int saved = dup(2), devnull = open("/dev/null", O_WRONLY);
    if (saved >= 0 && devnull >= 0)
        dup2(devnull, 2);
    tsr_status s = tsr_heightfield_load(path, &o->load, NULL, &hf, &err);
    if (saved >= 0 && devnull >= 0)
        dup2(saved, 2);
    if (saved >= 0)
        close(saved);
    if (devnull >= 0)
        close(devnull);
    if (s != TSR_OK) {
        cli_error(cmd, "%s", err.message);
        return NULL;
    }
    warn_sentinel(cmd, path, hf, o);
    double dx, dy, dz = o->dz > 0 ? o->dz : 1;
    cli_spacing(hf, o, &dx, &dy);
    tsr_heightfield_set_spacing(hf, dx, dy, dz);
    /* positions are floats: the heights times dz must fit (the extents
     * do: at most 65536 samples a side times 1e15) */
    if (dz > 1) {
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        double zmax = st.valid ? fmax(fabs(st.min), fabs(st.max)) * dz : 0;
        if (!(zmax <= FLT_MAX)) {
            cli_error(cmd, "%s: the heights times --dz %g reach %.3g, past the largest float (%.3g) that positions are "
                      "kept in", path, dz, zmax, FLT_MAX);
            tsr_heightfield_destroy(hf);
            return NULL;
        }
    }
    return hf;
}

tsr_status cli_write_text(const char *path, const char *text, tsr_error *err)
{
    char tmp[4096];
    tsr_status s = tsr_atomic_begin(path, tmp, sizeof tmp, err);
    if (s != TSR_OK)
        return s;
    FILE *f = fopen(tmp, "w");
    size_t n = strlen(text);
    bool ok = f && fwrite(text, 1, n, f) == n;
    if (f && fclose(f) != 0)
        ok = false;
    if (!ok) {
        int e = errno;
        tsr_atomic_abort(tmp);
        return tsr_error_set(err, TSR_ERR_IO, "%s: write failed: %s", path, strerror(e ? e : EIO));
    }
    return tsr_atomic_commit(tmp, path, err);
}

void cli_progress_start(cli_progress *p, const char *cmd, bool on)
{
    *p = (cli_progress){cmd, on && isatty(2), false, cli_now(), 0};
}

void cli_progress_cb(void *user, double f)
{
    cli_progress *p = user;
    if (!p->on)
        return;
    double now = cli_now();
    if (now - p->t0 < 1.0 || now - p->last < 0.1)
        return;
    p->last = now;
    f = f < 0 ? 0 : f > 1 ? 1 : f;
    int width = 40, fill = (int)(f * width + 0.5);
    char bar[48];
    for (int i = 0; i < width; i++)
        bar[i] = i < fill ? '#' : '.';
    bar[width] = '\0';
    fprintf(stderr, "\rtessera %s: [%s] %3d%%", p->cmd, bar, (int)(f * 100 + 0.5));
    fflush(stderr);
    p->shown = true;
}

void cli_progress_phase(cli_progress *p, const char *what)
{
    if (!p->on || cli_now() - p->t0 < 1.0)
        return;
    cli_progress_end(p);
    fprintf(stderr, "tessera %s: %.50s ...", p->cmd, what);
    fflush(stderr);
    p->shown = true;
}

void cli_progress_end(cli_progress *p)
{
    if (p->shown)
        fprintf(stderr, "\r%*s\r", (int)strlen(p->cmd) + 66, "");
    p->shown = false;
}

/* path's canonical form: its folder's real path and its name (NULL where
 * the folder does not resolve); free the result. */
static char *canonical_path(const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *base = slash ? slash + 1 : path;
    char dir[4096] = ".";
    if (slash) { /* "/name": the root; "d/name": d */
        size_t dn = slash == path ? 1 : (size_t)(slash - path);
        if (dn >= sizeof dir)
            return NULL;
        memcpy(dir, path, dn);
        dir[dn] = '\0';
    }
    char *real = realpath(dir, NULL);
    if (!real)
        return NULL;
    size_t n = strlen(real) + strlen(base) + 2;
    char *out = malloc(n);
    if (out)
        snprintf(out, n, "%s/%s", real, base);
    free(real);
    return out;
}

static bool same_file(const char *a, const char *b)
{
    struct stat sa, sb;
    if (stat(a, &sa) == 0 && stat(b, &sb) == 0)
        return sa.st_dev == sb.st_dev && sa.st_ino == sb.st_ino;
    char *ca = canonical_path(a), *cb = canonical_path(b);
    bool same = ca && cb ? !strcmp(ca, cb) : !strcmp(a, b);
    free(ca);
    free(cb);
    return same;
}

bool cli_paths_distinct(const char *cmd, int n, const char *const *names, const char *const *paths)
{
    for (int i = 0; i < n; i++)
        for (int j = i + 1; paths[i] && j < n; j++)
            if (paths[j] && same_file(paths[i], paths[j])) {
                cli_error(cmd, "%s %s and %s %s name the same file", names[i], paths[i],
                          names[j], paths[j]);
                return false;
            }
    return true;
}

bool cli_outputs_writable(const char *cmd, int n, const char *const *paths)
{
    for (int i = 0; i < n; i++) {
        tsr_error err = {0};
        if (paths[i] && tsr_atomic_probe(paths[i], &err) != TSR_OK) {
            cli_error(cmd, "%s", err.message);
            return false;
        }
    }
    return true;
}
