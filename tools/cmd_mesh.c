/* cmd_mesh.c: `tessera mesh IN -o OUT`: a heightmap in, the fewest
 * triangles that stay within a stated vertical error out. The mesher
 * (terrain/tin.c) builds; the bound is then measured independently
 * (tsr_terrain_measure_window) and the measured figures are the ones
 * reported. */
#define _DEFAULT_SOURCE /* realpath, strdup */
#include "cli.h"
#include "terrain/shade.h"

#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <signal.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera mesh IN -o OUT [options]\n\n"
               "Converts a heightfield into a triangle mesh whose vertical error is bounded: after building,\n"
               "every valid sample is measured against the mesh, and the measured max error never exceeds\n"
               "--max-error. OUT's extension picks the format: .obj, .ply (binary), .stl (binary) or .glb\n"
               "(glTF 2.0, +y up). Sample (c, r) becomes the vertex (c*dx, r*dy, h*dz) (--north-up:\n"
               "(c*dx, -r*dy, h*dz)); no-data samples become holes, never zeros: delaunay and quadtree mesh\n"
               "the cells whose four corners are valid, grid also the triangle of a cell with three.\n\n"
               "options:\n"
               "  -o, --output OUT      mesh file to write (required)\n"
               "  --max-error E         the bound on the vertical error, in output z units\n"
               "                        (default: 0.1%% of the heightfield's height range, also with\n"
               "                        --window, unless a budget is given)\n"
               "  --triangles N         a budget: at most N triangles (stops when reached; the error\n"
               "                        achieved is reported; with --max-error as for --vertices)\n"
               "  --vertices N          a budget: at most N vertices (with --max-error too, both must\n"
               "                        hold: exit 1, nothing written, when the budget is reached\n"
               "                        above the bound; exit 2 when it cannot hold even the border\n"
               "                        fixed at the bound)\n"
               "  --method M            delaunay (default): greedy insertion of the worst sample\n"
               "                        (Garland-Heckbert) on the constrained-Delaunay kernel, with\n"
               "                        data-dependent edge flips after each insertion;\n"
               "                        quadtree: a restricted quadtree, each leaf two triangles\n"
               "                        on its better diagonal or four from its centre, plus side\n"
               "                        midpoints, kept only where every sample is within the\n"
               "                        bound: 2.4-11x faster, 1.2-3x the triangles;\n"
               "                        grid: every --step-th sample\n"
               "  --no-flip             delaunay: no data-dependent flips: a Delaunay triangulation,\n"
               "                        1.3-2x faster, about a quarter more triangles for the bound\n"
               "                        (--flip, the default, flips an edge when that lowers its two\n"
               "                        triangles' error above the bound)\n"
               "  --block N             delaunay with a bound: mesh blocks of about N x N cells on\n"
               "                        their own, their seams fixed like window borders (default\n"
               "                        256, at least 16; the mesh depends on N, not on --threads)\n"
               "  --threads N           delaunay: blocks meshed at once; quadtree (without --tile):\n"
               "                        nodes tested at once (default: one per processor this process\n"
               "                        may use, by its CPU affinity and cgroup CPU limit; the mesh is\n"
               "                        the same)\n"
               "  --step N              grid: keep every N-th column and row (default 1)\n"
               "  --tile N              quadtree: draw each leaf as an N x N grid tile instead (2, 4,\n"
               "                        8, ..., 128; the terrain LOD's tiles and error pyramid: more\n"
               "                        triangles)\n"
               "  --border-error E      delaunay: tolerance of the border and no-data boundary\n"
               "                        simplification (default: the --max-error; with a budget\n"
               "                        and no bound, the border is refined like the interior)\n"
               "  --window X,Y,W,H      mesh only W x H samples from column X, row Y; vertices keep the\n"
               "                        whole heightfield's coordinates, and adjacent windows (sharing\n"
               "                        a border row or column, same options, --block included, a bound\n"
               "                        rather than a budget) have identical border vertices, so tiles\n"
               "                        meshed as separate jobs fit exactly (quadtree: its window borders\n"
               "                        are kept at full resolution)\n"
               "  --base DEPTH          a closed solid for 3D printing: walls down to a flat bottom\n"
               "                        DEPTH below the heightfield's lowest sample (the whole\n"
               "                        heightfield's, also with --window: tiles share the bottom);\n"
               "                        --triangles and --vertices count the walls and bottom too\n"
               "  --north-up            y = -r*dy: +y is the image's up (north in a north-up GIS raster),\n"
               "                        so x east, y north, z up is right-handed and the terrain is not\n"
               "                        mirrored in a z-up viewer (the default's y runs down the rows);\n"
               "                        in a .glb (glTF viewers: +y up) the default shows the map\n"
               "                        mirrored, its first row nearest the viewer; --north-up puts\n"
               "                        the first row (north) at the back, as a map reads\n"
               "  --normals             per-vertex normals from the heightfield's gradients (with --base,\n"
               "                        the walls and bottom flat-shaded: their vertices are written apart\n"
               "                        from the top's, except in .stl, which has facet normals)\n"
               "  --normal-map FILE     a normal map image, one pixel per sample (.png, .tif, or another\n"
               "                        format OpenImageIO writes; RGB, no-data pixels black, 0 0 0, which\n"
               "                        no normal encodes; object space: the normals relative to the flat\n"
               "                        xy plane, green north); with --window, of the window (the whole\n"
               "                        map's pixels there)\n"
               "  --hillshade FILE      a hillshade image, one pixel per sample (as --normal-map; with\n"
               "                        no-data, an alpha channel: 0 there); with --window, of the window\n"
               "  --uvs                 texture coordinates that put those images' pixel centres on the\n"
               "                        samples (u across the columns; v down the rows in .glb, whose uv\n"
               "                        origin is the image's top-left, up in .obj and .ply); given with\n"
               "                        --normal-map or --hillshade unless the output is .stl (which\n"
               "                        has none: --uvs with .stl is refused)\n"
               "  --stats FILE.json     vertices, triangles, measured max_error and rms_error, seconds,\n"
               "                        peak_bytes, method, the input's size, range, no-data count and\n"
               "                        dz (with --nodata, its value), and the window's own range\n"
               "  --quiet               no summary, notes or progress bar (warnings about the input still\n"
               "                        go to stderr)\n" CLI_HEIGHTFIELD_HELP "  -h, --help            this help\n\n"
               "exit status: 0 written, 1 bad input or failed output, 2 bad usage, 3 nothing to mesh\n"
               "(the heightfield or window all no-data, or no triangle of valid samples; nothing written)\n");
}

/* --north-up: y = -r dy instead of r dy, so +y is the image's up (north
 * in a north-up raster) and (x, y, z) a right-handed east-north-up frame;
 * the reflection reverses every triangle, so each is turned back to face
 * as before (a solid stays closed and outward-facing). */
static void mirror_rows(tsr_mesh *m)
{
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        float *p = m->positions + 3 * (size_t)i;
        p[1] = p[1] == 0 ? 0.0f : -p[1];
        if (m->normals)
            m->normals[3 * (size_t)i + 1] = -m->normals[3 * (size_t)i + 1];
    }
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        uint32_t *v = m->indices + 3 * (size_t)t, k = v[1];
        v[1] = v[2];
        v[2] = k;
    }
}

/* Texture coordinates that put the pixel centres of an image of the
 * window win (x, y, w, h samples, one pixel each: --normal-map,
 * --hillshade) on the samples: u across the columns, v down the rows from
 * the image's top (glTF's origin) when top_down, else up from its bottom
 * (OBJ's and PLY's). The vertices lie at x = c dx, y = r dy (before
 * --north-up). */
static bool add_uvs(tsr_mesh *m, double dx, double dy, const uint32_t win[4], bool top_down)
{
    size_t cap = m->vertex_capacity > m->vertex_count ? m->vertex_capacity : m->vertex_count;
    float *uv = tsr_alloc(m->alloc.realloc ? &m->alloc : NULL, (cap ? cap : 1) * 2 * sizeof *uv);
    if (!uv)
        return false;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * (size_t)i;
        double u = (p[0] / dx - win[0] + 0.5) / win[2], v = (p[1] / dy - win[1] + 0.5) / win[3];
        uv[2 * (size_t)i] = (float)u;
        uv[2 * (size_t)i + 1] = (float)(top_down ? v : 1 - v);
    }
    tsr_free(m->alloc.realloc ? &m->alloc : NULL, m->uvs);
    m->uvs = uv;
    m->attributes |= TSR_MESH_UVS;
    return true;
}

/* Peak resident memory of this process, from /proc (0 when unknown). */
static double peak_bytes(void)
{
    FILE *f = fopen("/proc/self/status", "r");
    if (!f)
        return 0;
    char line[256];
    double kb = 0;
    while (fgets(line, sizeof line, f))
        if (!strncmp(line, "VmHWM:", 6)) {
            kb = strtod(line + 6, NULL);
            break;
        }
    fclose(f);
    return kb * 1024;
}

static bool parse_window(const char *s, uint32_t w[4])
{
    for (int k = 0; k < 4; k++) {
        const char *end = strchr(s, ',');
        size_t n = end ? (size_t)(end - s) : strlen(s);
        char buf[32];
        if ((k < 3) != (end != NULL) || n == 0 || n >= sizeof buf)
            return false;
        memcpy(buf, s, n);
        buf[n] = '\0';
        if (!cli_parse_u32(buf, 0, UINT32_MAX - 1, &w[k]))
            return false;
        s = end ? end + 1 : s + n;
    }
    return true;
}

/* The outputs written so far (the normal map, the hillshade, the mesh),
 * as the files they landed in (an output path that is a symbolic link
 * writes the file it points to, which stays a link): removed by a signal
 * before the last is written (cli_signal_cleanup; unlink is
 * async-signal-safe) or by a later failure. Volatile, so each path is
 * stored before the count that makes the handler read it. */
static char *volatile written[3];
static volatile sig_atomic_t nwritten;

/* Records output path, written: the file it resolves to (itself if that
 * cannot be found). */
static void add_written(const char *path)
{
    char *real = realpath(path, NULL);
    written[nwritten] = real ? real : strdup(path);
    if (written[nwritten])
        nwritten = nwritten + 1;
}

static void remove_written(void)
{
    for (int k = 0; k < nwritten; k++)
        unlink(written[k]);
}

static const char *method_name(tsr_tin_method m)
{
    return m == TSR_TIN_DELAUNAY ? "delaunay" : m == TSR_TIN_QUADTREE ? "quadtree" : "grid";
}

static int write_stats(const char *path, const tsr_mesh *mesh, const tsr_error_report *er, double secs,
                       const tsr_tin_options *to, const tsr_heightfield *hf, const cli_heightfield_options *o,
                       const tsr_heightfield_stats *st, double max_error, const tsr_tin_report *rep)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddNumberToObject(j, "vertices", mesh->vertex_count);
    cJSON_AddNumberToObject(j, "triangles", mesh->triangle_count);
    cJSON_AddNumberToObject(j, "max_error", er->max_vertical);
    cJSON_AddNumberToObject(j, "rms_error", er->rms_vertical);
    cJSON_AddNumberToObject(j, "seconds", secs);
    cJSON_AddNumberToObject(j, "peak_bytes", peak_bytes());
    cJSON_AddStringToObject(j, "method", method_name(to->method));
    if (max_error > 0)
        cJSON_AddNumberToObject(j, "requested_max_error", max_error);
    if (to->max_triangles)
        cJSON_AddNumberToObject(j, "budget_triangles", to->max_triangles);
    if (to->max_vertices)
        cJSON_AddNumberToObject(j, "budget_vertices", to->max_vertices);
    cJSON_AddBoolToObject(j, "budget_reached", rep->budget_reached);
    if (to->method == TSR_TIN_DELAUNAY) {
        cJSON_AddNumberToObject(j, "border_error", rep->border_error);
        cJSON_AddNumberToObject(j, "flips", rep->flips);
        cJSON_AddNumberToObject(j, "blocks", rep->blocks);
    }
    cJSON_AddNumberToObject(j, "uncovered_samples", (double)er->uncovered);
    cJSON *inp = cJSON_AddObjectToObject(j, "input");
    cJSON_AddNumberToObject(inp, "width", tsr_heightfield_width(hf));
    cJSON_AddNumberToObject(inp, "height", tsr_heightfield_height(hf));
    cJSON_AddNumberToObject(inp, "min", st->min);
    cJSON_AddNumberToObject(inp, "max", st->max);
    cJSON_AddNumberToObject(inp, "nodata", (double)st->nodata);
    if (o->load.has_nodata) /* the --nodata value (a file's own is in georef) */
        cJSON_AddNumberToObject(inp, "nodata_value", o->load.nodata);
    double sdx, sdy, sdz;
    tsr_heightfield_spacing(hf, &sdx, &sdy, &sdz);
    cJSON_AddNumberToObject(inp, "dz", sdz); /* z = sample * dz: min and max are samples, errors in z */
    cli_georef_json(inp, hf, o);
    if (to->window_w) {
        cJSON *w = cJSON_AddObjectToObject(j, "window");
        cJSON_AddNumberToObject(w, "x", to->window_x);
        cJSON_AddNumberToObject(w, "y", to->window_y);
        cJSON_AddNumberToObject(w, "width", to->window_w);
        cJSON_AddNumberToObject(w, "height", to->window_h);
        /* the window's own range and no-data count, as the input's */
        cJSON_AddNumberToObject(w, "min", rep->window.min);
        cJSON_AddNumberToObject(w, "max", rep->window.max);
        cJSON_AddNumberToObject(w, "nodata", (double)rep->window.nodata);
    }
    char *s = cJSON_Print(j);
    cJSON_Delete(j);
    if (!s) {
        cli_error("mesh", "out of memory");
        return CLI_FAIL;
    }
    size_t n = strlen(s);
    char *text = malloc(n + 2);
    tsr_error err = {0};
    int rc = CLI_OK;
    if (text) {
        memcpy(text, s, n);
        text[n] = '\n';
        text[n + 1] = '\0';
    }
    if (!text || cli_write_text(path, text, &err) != TSR_OK) {
        cli_error("mesh", "%s", text ? err.message : "out of memory");
        rc = CLI_FAIL;
    }
    free(text);
    free(s);
    return rc;
}

/* Builds the mesh and measures it (window mx, my, mw, mh). The mesher
 * works a hair inside the bound; if the float output still lands beyond
 * it, builds again tighter. *bound is the bound held (the default one when
 * none was given and no budget). */
static int build_measured(const tsr_heightfield *hf, tsr_tin_options *to, double max_error, double ztop,
                          const char *in, uint32_t mx, uint32_t my, uint32_t mw, uint32_t mh, tsr_mesh *mesh,
                          tsr_tin_report *rep, tsr_error_report *er, double *bound)
{
    tsr_error err = {0};
    *bound = max_error;
    to->max_error = max_error;
    for (int attempt = 0;; attempt++) {
        if (tsr_terrain_mesh(hf, to, mesh, rep, &err) != TSR_OK) {
            if (err.status == TSR_ERR_VALUE) { /* no valid sample */
                cli_error("mesh", "%s: nothing to mesh: no valid sample in the %s (all no-data); nothing written", in,
                          to->window_w ? "window" : "heightfield");
                return CLI_EMPTY;
            }
            cli_error("mesh", "%s: %s", in, err.message);
            return err.status == TSR_ERR_ARGUMENT ? CLI_USAGE : CLI_FAIL;
        }
        if (mesh->triangle_count == 0) {
            if (to->method == TSR_TIN_GRID)
                cli_error("mesh",
                          "%s: nothing to mesh: the valid samples of the %s form no triangle (no cell has "
                          "three valid corners); nothing written",
                          in, to->window_w ? "window" : "heightfield");
            else
                cli_error("mesh",
                          "%s: nothing to mesh: the valid samples of the %s form no triangle (no cell has "
                          "four valid corners, which --method %s needs; --method grid meshes cells with three); "
                          "nothing written",
                          in, to->window_w ? "window" : "heightfield", method_name(to->method));
            return CLI_EMPTY;
        }
        if (tsr_terrain_measure_window(hf, mx, my, mw, mh, mesh, NULL, er) != TSR_OK) {
            cli_error("mesh", "%s: out of memory measuring the error", in);
            return CLI_FAIL;
        }
        if (*bound == 0 && !to->max_triangles && !to->max_vertices && to->method != TSR_TIN_GRID)
            *bound = rep->bound; /* the default bound */
        if (*bound == 0 || er->max_vertical <= *bound || to->method == TSR_TIN_GRID)
            return CLI_OK;
        if (rep->budget_reached) {
            cli_error("mesh", "%s: the budget of %u %s is reached at a measured max error %g, above the bound %g", in,
                      to->max_triangles ? to->max_triangles : to->max_vertices,
                      to->max_triangles ? "triangles" : "vertices", er->max_vertical, *bound);
            return CLI_FAIL;
        }
        if (attempt == 3) {
            cli_error("mesh", "%s: the measured error %g exceeds the bound %g (please report this)", in,
                      er->max_vertical, *bound);
            return CLI_FAIL;
        }
        to->max_error = rep->target_error - 2 * (er->max_vertical - *bound);
        if (!(to->max_error > 0)) {
            double ulp = ztop * FLT_EPSILON; /* float's spacing at the highest height */
            if (*bound < ulp)
                cli_error("mesh", "%s: cannot meet the bound %g: heights up to %g are floats %g apart in a mesh", in,
                          *bound, ztop, ulp);
            else
                cli_error("mesh", "%s: cannot meet the bound %g", in, *bound);
            return CLI_FAIL;
        }
        tsr_mesh_free(mesh);
        tsr_mesh_init(mesh, to->normals ? TSR_MESH_NORMALS : 0, NULL);
    }
}

/* Whether the mesh is within the budgets (0: none). */
static bool solid_fits(const tsr_mesh *m, uint32_t max_t, uint32_t max_v)
{
    return (!max_t || m->triangle_count <= max_t) && (!max_v || m->vertex_count <= max_v);
}

/* Vertices where the surface's boundary passes more than once (two
 * no-data holes, or a hole and the edge, meeting at a sample's corner):
 * a solid's walls touch themselves along the vertical edge below. */
static uint32_t count_pinches(const tsr_mesh *m)
{
    tsr_halfedges he;
    uint8_t *seen = calloc((size_t)m->vertex_count + 1, 1);
    uint32_t n = 0;
    if (!seen || tsr_halfedges_build(&he, m, NULL) != TSR_OK) {
        free(seen);
        return 0;
    }
    for (uint32_t h = 0; h < he.count; h++)
        if (he.twin[h] == TSR_NO_TWIN && m->indices[h] < m->vertex_count && seen[m->indices[h]]++ == 1)
            n++;
    tsr_halfedges_free(&he);
    free(seen);
    return n;
}

/* build_measured, then with base_z the walls and bottom down to it (split:
 * flat-shaded, their vertices apart from the top's). */
static int build_solid(const tsr_heightfield *hf, tsr_tin_options *to, double max_error, double ztop, const char *in,
                       const uint32_t win[4], const double *base_z, bool split, tsr_mesh *mesh, tsr_tin_report *rep,
                       tsr_error_report *er, double *bound, uint32_t *pinches)
{
    int rc = build_measured(hf, to, max_error, ztop, in, win[0], win[1], win[2], win[3], mesh, rep, er, bound);
    if (rc != CLI_OK || !base_z)
        return rc;
    uint32_t top = mesh->triangle_count;
    *pinches = count_pinches(mesh);
    tsr_error err = {0};
    if (tsr_mesh_add_base(mesh, *base_z, &err) != TSR_OK || (split && tsr_mesh_split_flat(mesh, top, 30, &err) != TSR_OK)) {
        cli_error("mesh", "--base: %s", err.message);
        return CLI_FAIL;
    }
    return CLI_OK;
}

static int run(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    const char *in = NULL, *out = NULL, *stats = NULL, *normal_map = NULL, *hillshade = NULL;
    tsr_tin_options to = {0};
    double max_error = 0, base = 0;
    bool quiet = false, has_base = false, has_window = false, no_flip_given = false, north_up = false, want_uvs = false;
    uint32_t win[4] = {0};
    uint32_t pinches = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        }
        int r = cli_heightfield_option("mesh", argc, argv, &i, &o);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        bool has_value = i + 1 < argc;
        if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_value)
            out = argv[++i];
        else if (!strcmp(a, "--stats") && has_value)
            stats = argv[++i];
        else if (!strcmp(a, "--normal-map") && has_value)
            normal_map = argv[++i];
        else if (!strcmp(a, "--hillshade") && has_value)
            hillshade = argv[++i];
        else if (!strcmp(a, "--method") && has_value) {
            const char *m = argv[++i];
            if (!strcmp(m, "delaunay"))
                to.method = TSR_TIN_DELAUNAY;
            else if (!strcmp(m, "quadtree"))
                to.method = TSR_TIN_QUADTREE;
            else if (!strcmp(m, "grid"))
                to.method = TSR_TIN_GRID;
            else {
                cli_error("mesh", "--method %s: use delaunay, quadtree or grid", m);
                return CLI_USAGE;
            }
        } else if ((!strcmp(a, "--max-error") || !strcmp(a, "--border-error")) && has_value) {
            double v;
            if (!cli_parse_double(argv[++i], &v) || !(v > 0)) {
                cli_error("mesh", "%s %s: must be a positive number", a, argv[i]);
                return CLI_USAGE;
            }
            if (!strcmp(a, "--max-error"))
                max_error = v;
            else
                to.border_error = v;
        } else if (!strcmp(a, "--base") && has_value) {
            if (!cli_parse_double(argv[++i], &base) || !(base > 0)) {
                cli_error("mesh", "--base %s: must be a positive depth", argv[i]);
                return CLI_USAGE;
            }
            has_base = true;
        } else if ((!strcmp(a, "--triangles") || !strcmp(a, "--vertices") || !strcmp(a, "--step") ||
                    !strcmp(a, "--tile") || !strcmp(a, "--block") || !strcmp(a, "--threads")) &&
                   has_value) {
            uint32_t v;
            if (!cli_parse_u32(argv[++i], 1, UINT32_MAX - 1, &v)) {
                cli_error("mesh", "%s %s: must be a whole number from 1 to %u", a, argv[i], UINT32_MAX - 1);
                return CLI_USAGE;
            }
            if (!strcmp(a, "--triangles"))
                to.max_triangles = v;
            else if (!strcmp(a, "--vertices"))
                to.max_vertices = v;
            else if (!strcmp(a, "--step"))
                to.grid_step = v;
            else if (!strcmp(a, "--block") && v < 16) {
                cli_error("mesh", "--block %s: at least 16 (cells a side; smaller blocks are mostly seams)", argv[i]);
                return CLI_USAGE;
            } else if (!strcmp(a, "--block"))
                to.block = v;
            else if (!strcmp(a, "--threads"))
                to.threads = v;
            else if (v != 2 && v != 4 && v != 8 && v != 16 && v != 32 && v != 64 && v != 128) {
                cli_error("mesh", "--tile %s: must be 2, 4, 8, 16, 32, 64 or 128", argv[i]);
                return CLI_USAGE;
            } else
                to.tile_n = v;
        } else if (!strcmp(a, "--window") && has_value) {
            if (!parse_window(argv[++i], win) || win[2] < 2 || win[3] < 2) {
                cli_error("mesh",
                          "--window %s: give X,Y,W,H in samples: whole numbers below 2^32, X and Y 0 or more (the "
                          "first column and row), W and H 2 or more",
                          argv[i]);
                return CLI_USAGE;
            }
            has_window = true;
        } else if (!strcmp(a, "--normals"))
            to.normals = true;
        else if (!strcmp(a, "--flip") || !strcmp(a, "--no-flip")) {
            to.no_flip = !strcmp(a, "--no-flip");
            no_flip_given = to.no_flip;
        }
        else if (!strcmp(a, "--north-up"))
            north_up = true;
        else if (!strcmp(a, "--uvs"))
            want_uvs = true;
        else if (!strcmp(a, "--quiet") || !strcmp(a, "-q"))
            quiet = true;
        else if (a[0] == '-' && a[1] != '\0') {
            cli_option_error("mesh", NULL, a, help);
            return CLI_USAGE;
        } else if (in) {
            cli_error("mesh", "one input at a time ('%s' and '%s' given)", in, a);
            return CLI_USAGE;
        } else
            in = a;
    }
    if (!in || !out) {
        cli_error("mesh", "%s (see tessera mesh --help)", !in ? "no input file" : "no output file: give -o OUT");
        return CLI_USAGE;
    }
    if (tsr_mesh_format_from_path(out) == TSR_FORMAT_UNKNOWN) {
        cli_error("mesh", "%s: unknown mesh format (use .obj, .ply, .stl or .glb)", out);
        return CLI_USAGE;
    }
    if (want_uvs && tsr_mesh_format_from_path(out) == TSR_FORMAT_STL) {
        cli_error("mesh", "--uvs: %s: STL has no texture coordinates (use .obj, .ply or .glb)", out);
        return CLI_USAGE;
    }
    if (to.grid_step && to.method != TSR_TIN_GRID) {
        cli_error("mesh", "--step applies to --method grid only");
        return CLI_USAGE;
    }
    if (no_flip_given && to.method != TSR_TIN_DELAUNAY) {
        cli_error("mesh", "--no-flip applies to --method delaunay only");
        return CLI_USAGE;
    }
    if (to.border_error > 0 && to.method != TSR_TIN_DELAUNAY) {
        cli_error("mesh", "--border-error applies to --method delaunay only");
        return CLI_USAGE;
    }
    if (to.border_error > 0 && max_error > 0 && to.border_error > max_error) {
        cli_error("mesh", "--border-error %g: the border is part of the mesh, so it must be within --max-error %g",
                  to.border_error, max_error);
        return CLI_USAGE;
    }
    if (has_window && !quiet && to.method == TSR_TIN_DELAUNAY && (to.max_triangles || to.max_vertices) &&
        !(max_error > 0) && !(to.border_error > 0))
        fprintf(stderr, "tessera mesh: note: with a budget and no bound the window's border is refined like its "
                        "interior, so adjacent windows' borders will not match; give --max-error or --border-error "
                        "for tiles that fit together\n");
    if (to.block && to.method != TSR_TIN_DELAUNAY) {
        cli_error("mesh", "--block applies to --method delaunay only");
        return CLI_USAGE;
    }
    if (to.threads && to.method != TSR_TIN_DELAUNAY && !(to.method == TSR_TIN_QUADTREE && !to.tile_n)) {
        cli_error("mesh", "--threads applies to --method delaunay and quadtree (without --tile) only");
        return CLI_USAGE;
    }
    if (to.tile_n && to.method != TSR_TIN_QUADTREE) {
        cli_error("mesh", "--tile applies to --method quadtree only");
        return CLI_USAGE;
    }
    if (to.method == TSR_TIN_GRID && max_error > 0) {
        cli_error("mesh", "--max-error: the grid method keeps every --step-th sample and bounds nothing; use "
                          "--method delaunay or quadtree");
        return CLI_USAGE;
    }
    /* Outputs are checked before the work, not after it. */
    const char *names[5] = {"the input", "-o", "--stats", "--normal-map", "--hillshade"};
    const char *files[5] = {in, out, stats, normal_map, hillshade};
    if (!cli_paths_distinct("mesh", 5, names, files))
        return CLI_USAGE;
    const char *images[2] = {normal_map, hillshade};
    for (int k = 0; k < 2; k++) {
        tsr_error ierr = {0};
        tsr_status is = images[k] ? tsr_image_save_check(images[k], &ierr) : TSR_OK;
        if (is != TSR_OK) {
            cli_error("mesh", "%s %s", k ? "--hillshade:" : "--normal-map:", ierr.message);
            return is == TSR_ERR_IO ? CLI_FAIL : CLI_USAGE;
        }
    }
    const char *outputs[2] = {out, stats};
    if (!cli_outputs_writable("mesh", 2, outputs))
        return CLI_FAIL;
    double t0 = cli_now();
    o.load.all_nodata_ok = true; /* nothing to mesh: exit 3, not a bad file */
    tsr_heightfield *hf = cli_load_heightfield("mesh", in, &o);
    if (!hf)
        return CLI_FAIL;
    cli_georef_warnings("mesh", in, hf, &o); /* warnings: also with --quiet */
    uint32_t W = tsr_heightfield_width(hf), H = tsr_heightfield_height(hf);
    if (has_window) {
        if (win[0] >= W || win[1] >= H || win[2] > W - win[0] || win[3] > H - win[1]) {
            cli_error("mesh", "--window %u,%u,%u,%u: not inside the %ux%u heightfield %s", win[0], win[1], win[2],
                      win[3], W, H, in);
            tsr_heightfield_destroy(hf);
            return CLI_USAGE;
        }
        to.window_x = win[0];
        to.window_y = win[1];
        to.window_w = win[2];
        to.window_h = win[3];
        to.full_border = true;
    }
    uint32_t mx = has_window ? win[0] : 0, my = has_window ? win[1] : 0, mw = has_window ? win[2] : W,
             mh = has_window ? win[3] : H;
    cli_progress pr;
    cli_progress_start(&pr, "mesh", !quiet);
    pr.t0 = t0;
    to.progress = cli_progress_cb;
    to.progress_user = &pr;
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    double sdx, sdy, sdz;
    tsr_heightfield_spacing(hf, &sdx, &sdy, &sdz);
    double ztop = fmax(fabs(st.min), fabs(st.max)) * fabs(sdz); /* for the float spacing below */

    tsr_mesh mesh;
    tsr_mesh_init(&mesh, to.normals ? TSR_MESH_NORMALS : 0, NULL);
    tsr_error err = {0};
    tsr_tin_report rep = {0};
    tsr_error_report er = {0};
    int rc = CLI_OK;
    double bound = max_error;
    /* The bottom of a solid: DEPTH below the whole heightfield's lowest
     * sample, the same plane for every method and every window. */
    double base_z = fmin(st.min * sdz, st.max * sdz) - base;
    /* the vertices are float, as for --dz: the bottom must lie within the
     * float range and below the lowest height as a float (no valid sample:
     * nothing to mesh, below) */
    float zlow = (float)fmin(st.min * sdz, st.max * sdz);
    if (has_base && st.valid && (!(fabs(base_z) <= FLT_MAX) || !((float)base_z < zlow))) {
        if (!(fabs(base_z) <= FLT_MAX))
            cli_error("mesh", "%s: --base %g: the bottom at z = %g would lie past the largest float (%g)", in, base,
                      base_z, (double)FLT_MAX);
        else
            cli_error("mesh",
                      "%s: --base %g: the bottom rounds to the lowest height, z = %.9g, in float32 (the "
                      "vertices' type): give a depth of at least %g",
                      in, base, (double)zlow, (double)(zlow - nextafterf(nextafterf(zlow, -INFINITY), -INFINITY)));
        cli_progress_end(&pr);
        tsr_heightfield_destroy(hf);
        return CLI_FAIL;
    }
    /* with normals (not in .stl: facet normals), the walls and the bottom
     * shade flat, their vertices apart from the top's; turns of the
     * outline under 30 degrees stay smooth */
    bool split = to.normals && tsr_mesh_format_from_path(out) != TSR_FORMAT_STL;
    const uint32_t win4[4] = {mx, my, mw, mh};
    /* With --base, a budget covers the solid as written (walls and bottom
     * too): the top's budgets are scaled by x in (0, 1], searched for the
     * largest x whose solid fits (within 0.5 % of the budget). */
    uint32_t budget_t = to.max_triangles, budget_v = to.max_vertices;
    rc = build_solid(hf, &to, max_error, ztop, in, win4, has_base ? &base_z : NULL, split, &mesh, &rep, &er, &bound,
                     &pinches);
    if (rc == CLI_OK && has_base && (budget_t || budget_v) && !solid_fits(&mesh, budget_t, budget_v)) {
        double lo = 0, hi = 1, x = 1;
        bool have_lo = false, last_fits = false;
        uint32_t most = budget_t > budget_v ? budget_t : budget_v;
        for (int round = 0; rc == CLI_OK && round < 20; round++) {
            if (!have_lo) { /* scale by the excess, until one fits */
                double f = 1;
                if (budget_t && mesh.triangle_count > budget_t)
                    f = fmin(f, (double)budget_t / mesh.triangle_count);
                if (budget_v && mesh.vertex_count > budget_v)
                    f = fmin(f, (double)budget_v / mesh.vertex_count);
                x *= 0.95 * f;
            } else
                x = (lo + hi) / 2;
            uint32_t tt = budget_t ? (uint32_t)fmax(2, floor(budget_t * x)) : 0;
            uint32_t tv = budget_v ? (uint32_t)fmax(4, floor(budget_v * x)) : 0;
            if (!have_lo && tt == to.max_triangles && tv == to.max_vertices) {
                char b[64];
                if (budget_t && budget_v)
                    snprintf(b, sizeof b, "%u triangles, %u vertices", budget_t, budget_v);
                else
                    snprintf(b, sizeof b, "%u %s", budget_t ? budget_t : budget_v, budget_t ? "triangles" : "vertices");
                cli_error("mesh", "%s: the budget (%s) is below the smallest closed solid: %u triangles, %u "
                          "vertices with its walls and bottom", in, b, mesh.triangle_count, mesh.vertex_count);
                rc = CLI_USAGE;
                break;
            }
            to.max_triangles = tt;
            to.max_vertices = tv;
            tsr_mesh_free(&mesh);
            tsr_mesh_init(&mesh, to.normals ? TSR_MESH_NORMALS : 0, NULL);
            rc = build_solid(hf, &to, max_error, ztop, in, win4, &base_z, split, &mesh, &rep, &er, &bound, &pinches);
            last_fits = rc == CLI_OK && solid_fits(&mesh, budget_t, budget_v);
            if (last_fits) {
                lo = x;
                have_lo = true;
            } else
                hi = x;
            if (have_lo && (hi - lo) * most <= fmax(1, most / 200.0))
                break;
        }
        if (rc == CLI_OK && !have_lo) {
            cli_error("mesh", "%s: no closed solid within the budget found", in);
            rc = CLI_USAGE;
        } else if (rc == CLI_OK && !last_fits) { /* the last fitting one again */
            to.max_triangles = budget_t ? (uint32_t)fmax(2, floor(budget_t * lo)) : 0;
            to.max_vertices = budget_v ? (uint32_t)fmax(4, floor(budget_v * lo)) : 0;
            tsr_mesh_free(&mesh);
            tsr_mesh_init(&mesh, to.normals ? TSR_MESH_NORMALS : 0, NULL);
            rc = build_solid(hf, &to, max_error, ztop, in, win4, &base_z, split, &mesh, &rep, &er, &bound, &pinches);
        }
    }
    to.max_triangles = budget_t; /* the stats give the budget asked for */
    to.max_vertices = budget_v;
    cli_progress_end(&pr);
    /* the files written so far, removed when a later one fails or a signal
     * stops the command: no partial set of outputs is left behind */
    nwritten = 0;
    cli_signal_cleanup = remove_written;
    if (rc == CLI_OK && normal_map) {
        cli_progress_phase(&pr, "writing the normal map");
        tsr_status s = tsr_heightfield_normal_map_window(hf, mx, my, mw, mh, normal_map, &err);
        cli_progress_end(&pr);
        if (s != TSR_OK) {
            cli_error("mesh", "%s", err.message);
            rc = CLI_FAIL;
        } else
            add_written(normal_map);
    }
    if (rc == CLI_OK && hillshade) {
        cli_progress_phase(&pr, "writing the hillshade");
        tsr_status s = tsr_heightfield_hillshade_window(hf, mx, my, mw, mh, hillshade, 315, 45, &err);
        cli_progress_end(&pr);
        if (s != TSR_OK) {
            cli_error("mesh", "%s", err.message);
            rc = CLI_FAIL;
        } else
            add_written(hillshade);
    }
    tsr_mesh_format fmt = tsr_mesh_format_from_path(out);
    if (rc == CLI_OK && (want_uvs || normal_map || hillshade) && fmt != TSR_FORMAT_STL &&
        !add_uvs(&mesh, sdx, sdy, win4, fmt == TSR_FORMAT_GLB)) {
        cli_error("mesh", "out of memory for the texture coordinates");
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK && north_up)
        mirror_rows(&mesh);
    if (rc == CLI_OK) {
        cli_progress_phase(&pr, "writing the mesh");
        tsr_status s = tsr_mesh_write(&mesh, out, TSR_FORMAT_UNKNOWN, &err);
        cli_progress_end(&pr);
        if (s != TSR_OK) {
            cli_error("mesh", "%s", err.message);
            rc = CLI_FAIL;
        } else
            add_written(out);
    }
    double secs = cli_now() - t0;
    if (rc == CLI_OK && stats)
        rc = write_stats(stats, &mesh, &er, secs, &to, hf, &o, &st, bound, &rep);
    cli_signal_cleanup = NULL;
    for (int k = 0; k < nwritten; k++) {
        if (rc != CLI_OK)
            unlink(written[k]);
        free(written[k]);
    }
    nwritten = 0;
    if (rc == CLI_OK && !quiet) {
        fprintf(stderr, "tessera mesh: wrote %s (%s, %s, %u vertices, %u triangles", out,
                tsr_mesh_format_name(tsr_mesh_format_from_path(out)), method_name(to.method), mesh.vertex_count,
                mesh.triangle_count);
        if (has_base)
            fprintf(stderr, ", closed with a base at z = %g", base_z);
        fprintf(stderr, "); measured max error %g", er.max_vertical);
        if (bound > 0)
            fprintf(stderr, " (bound %g)", bound);
        fprintf(stderr, ", rms %g%s in %.2f s\n", er.rms_vertical, rep.budget_reached ? ", budget reached" : "", secs);
        double dx, dy;
        if (cli_spacing(hf, &o, &dx, &dy)) {
            char sp[256];
            cli_georef_describe(hf, &o, sp, sizeof sp);
            fprintf(stderr, "tessera mesh: spacing %s (--dx and --dy override it)\n", sp);
        }
        if (er.uncovered)
            fprintf(stderr,
                    "tessera mesh: note: %llu valid samples lie in no triangle (next to no-data) and are not measured\n",
                    (unsigned long long)er.uncovered);
        if (has_base && pinches && tsr_mesh_format_from_path(out) == TSR_FORMAT_STL)
            fprintf(stderr,
                    "tessera mesh: warning: the valid region pinches at %u sample%s (no-data meeting at a corner): "
                    "the solid touches itself along the wall edge below, which an STL (no shared vertices) makes "
                    "a non-manifold edge for slicers; .obj, .ply and .glb keep the two sides apart\n",
                    pinches, pinches == 1 ? "" : "s");
    }
    tsr_mesh_free(&mesh);
    tsr_heightfield_destroy(hf);
    return rc;
}

const cli_command cli_cmd_mesh = {"mesh", "convert a heightfield into a mesh with a bounded error (OBJ, PLY, STL, glTF)",
                                  run, help};
