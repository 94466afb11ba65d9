/* cmd_triangulate.c: `tessera triangulate IN -o OUT`: constrained
 * triangulation of a planar straight-line graph, with the independent
 * checker on request. */
#include "cli.h"
#include "pslg_io.h"
#include "tessellate/predicates.h"

#include <cjson/cJSON.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera triangulate IN [-o OUT] [options]\n\n"
               "Triangulates a planar straight-line graph (points, segments, hole seeds): a constrained\n"
               "Delaunay triangulation, or a quadtree triangulation, optionally refined for quality.\n\n"
               "input (format from the extension, or --format):\n"
               "  .node, .poly          Triangle's formats (a .poly listing 0 points reads the .node\n"
               "                        file of the same name); point attributes (up to 64), markers\n"
               "                        and a .poly's regional attributes are carried to a Triangle-\n"
               "                        format output (a mesh takes one attribute, --z-attribute)\n"
               "  .json                 an array of rings, each an array of [x, y]; the first ring is\n"
               "                        the outer boundary, the others holes (earcut's test format)\n"
               "  .txt                  'nV nE', then nV lines 'x y', then nE lines 'i j' (0-based)\n\n"
               "output (format from OUT's extension):\n"
               "  .node, .ele, .poly    all three of Triangle's files: OUT's base name .node (vertices,\n"
               "                        numbered from 0 or 1 as a Triangle input is, else from 1: the\n"
               "                        k-th input point is vertex k, a repeated one too, then the\n"
               "                        Steiner points; the input's attributes, interpolated\n"
               "                        linearly at Steiner points over the input's own triangulation;\n"
               "                        boundary markers: a point's own, else that of a segment it is\n"
               "                        on, else 1 on the boundary), .ele (triangles; with a .poly's\n"
               "                        regions, the attribute of the region each lies in), .poly\n"
               "                        (constrained edges; marker = the input segment's marker, or its\n"
               "                        index + 1 when the input gives none)\n"
               "  .obj, .ply, .stl, .glb  a mesh with z = 0, or an attribute (--z-attribute;\n"
               "                        coordinates rounded to float32)\n\n"
               "options:\n"
               "  -o, --output OUT      file to write; optional with --check or --json\n"
               "  --method M            delaunay (default) or quadtree (for the enclosed and evenodd\n"
               "                        regions, without -q or --conforming; otherwise it falls back to\n"
               "                        delaunay, and the summary says why)\n"
               "  --region R            what is kept: hull (the convex hull), enclosed (what segments\n"
               "                        enclose) or evenodd (inside an odd number of loops); hole seeds\n"
               "                        always apply. Default: evenodd for .json, enclosed for a .poly\n"
               "                        with segments, hull otherwise\n"
               "  -q ANGLE              refine until no angle is below ANGLE degrees (0 < ANGLE < 60;\n"
               "                        above about 34 termination is not guaranteed)\n"
               "  -a AREA               refine until no triangle is larger than AREA\n"
               "  --region-areas        refine each region of a .poly to its own maximum area (Triangle's\n"
               "                        -a without a number; with -a, the smaller bound applies)\n"
               "  --conforming          split segments until every edge is Delaunay (delaunay method)\n"
               "  --max-steiner N       stop refining after N Steiner points (default: 20 per input point\n"
               "                        plus 100,000, plus 4 per -a AREA of the region; an -a asking for\n"
               "                        more than 5e7 triangles is refused without --max-steiner)\n"
               "  --check               check the result independently (orientation, topology, Delaunay\n"
               "                        property, segments, area, Euler characteristic, angle and area\n"
               "                        bounds) and print what was checked; exit 1 if it fails (OUT is\n"
               "                        still written)\n"
               "  --json                print statistics (and the check's results) as JSON on stdout\n"
               "  --z-attribute K       mesh output: z = the K-th .node attribute (1-based), interpolated\n"
               "                        at Steiner points as above (e.g. elevations: a TIN)\n"
               "  --format F            read IN as node, poly, json or txt whatever its extension\n"
               "  --quiet               no summary line on stderr\n"
               "  -h, --help            this help\n\n"
               "exit status: 0 success, 1 bad input (also: no triangle), failed output or failed check, 2 bad\n"
               "usage, 3 written, but -q, -a or --conforming not met everywhere (refinement stopped at the\n"
               "Steiner limit, or stuck; a warning says which)\n");
}

static const char *region_name(tsr_region r)
{
    return r == TSR_REGION_HULL ? "hull" : r == TSR_REGION_ENCLOSED ? "enclosed" : "evenodd";
}

/* The check's report, one line per rule. */
static void print_check(FILE *f, const tsr_tri_options *opt, const tsr_triangulation *t, const tsr_tri_check *c)
{
    bool delaunay = opt->method == TSR_TRI_DELAUNAY || t->fell_back;
    fprintf(f, "check: %u triangles strictly counter-clockwise (exact orient2d): %s\n", t->nt,
            c->not_ccw ? "FAIL" : "ok");
    if (c->not_ccw)
        fprintf(f, "       %u not\n", c->not_ccw);
    fprintf(f, "check: topology (edges in at most two triangles, opposite ways; constrained edges on their "
               "segments): %s\n",
            c->bad_topology ? "FAIL" : "ok");
    if (delaunay)
        fprintf(f, "check: Delaunay (exact incircle on every interior edge%s): %s (%u failing)\n",
                opt->conforming ? ", constrained ones included" : " not on a segment",
                c->not_delaunay ? "FAIL" : "ok", c->not_delaunay);
    else
        fprintf(f, "check: Delaunay: not applicable (quadtree method)\n");
    fprintf(f, "check: input segments present as chains of constrained edges: %s (%u missing)\n",
            c->missing_segments ? "FAIL" : "ok", c->missing_segments);
    if (isnan(c->expected_area))
        fprintf(f, "check: area %.17g: no expected value for this input and region (not checked)\n", c->area);
    else
        fprintf(f, "check: area %.17g, expected %.17g (from the input alone): %s\n", c->area, c->expected_area,
                c->area_ok ? "ok" : "FAIL");
    fprintf(f, "check: no overlap (area, angles around each vertex): %s\n", c->overlapping ? "FAIL" : "ok");
    if (c->expected_euler == LONG_MIN)
        fprintf(f, "check: Euler characteristic %ld: no expected value for this input and region (not checked)\n",
                c->euler);
    else
        fprintf(f, "check: Euler characteristic %ld, expected %ld: %s\n", c->euler, c->expected_euler,
                c->euler == c->expected_euler ? "ok" : "FAIL");
    if (opt->min_angle > 0)
        fprintf(f,
                "check: smallest angle %.6g degrees; %u triangles below %g not excused by a small input angle%s: %s\n",
                c->min_angle, c->below_min_angle, opt->min_angle,
                c->below_resolution_excused ? " or as below the resolution of doubles" : "",
                c->below_min_angle ? "FAIL" : "ok");
    if (c->below_resolution_excused)
        fprintf(f,
                "check: %u triangles below %g degrees excused as below the resolution of doubles (height under 8 "
                "ulps; reported by the result: quality limited)\n",
                c->below_resolution_excused, opt->min_angle);
    if (!(opt->min_angle > 0))
        fprintf(f, "check: smallest angle %.6g degrees (no bound asked)\n", c->min_angle);
    if (opt->nregions)
        fprintf(f, "check: %u triangles above their area bound (%s the regions' own): %s\n", c->above_max_area,
                opt->max_area > 0 ? "-a or" : "", c->above_max_area ? "FAIL" : "ok");
    else if (opt->max_area > 0)
        fprintf(f, "check: %u triangles above area %g: %s\n", c->above_max_area, opt->max_area,
                c->above_max_area ? "FAIL" : "ok");
    if (c->ok)
        fprintf(f, "check: PASS\n");
    else
        fprintf(f, "check: FAIL: %s\n", c->first_problem);
}

/* The smallest angle of the output, for the summary when no check ran. */
static double smallest_angle(const tsr_triangulation *t)
{
    double best = 180;
    for (uint32_t i = 0; i < t->nt; i++)
        for (int k = 0; k < 3; k++) {
            const double *o = t->xy + 2 * (size_t)t->tri[3 * (size_t)i + k];
            const double *p = t->xy + 2 * (size_t)t->tri[3 * (size_t)i + (k + 1) % 3];
            const double *q = t->xy + 2 * (size_t)t->tri[3 * (size_t)i + (k + 2) % 3];
            double ux = p[0] - o[0], uy = p[1] - o[1], vx = q[0] - o[0], vy = q[1] - o[1];
            best = fmin(best, atan2(fabs(ux * vy - uy * vx), ux * vx + uy * vy) * (180.0 / 3.14159265358979323846));
        }
    return t->nt ? best : 0;
}

static void add_count(cJSON *j, const char *k, double v) { cJSON_AddNumberToObject(j, k, v); }

static void print_json(const char *in_path, const cli_pslg *g, const tsr_tri_options *opt, const tsr_triangulation *t,
                       double seconds, const tsr_tri_check *c, double check_seconds)
{
    cJSON *j = cJSON_CreateObject();
    cJSON *in = cJSON_AddObjectToObject(j, "input");
    cJSON_AddStringToObject(in, "file", in_path);
    cJSON_AddStringToObject(in, "format", cli_pslg_format_name(g->format));
    add_count(in, "points", g->nv);
    add_count(in, "segments", g->nseg);
    add_count(in, "holes", g->nholes);
    add_count(in, "attributes", g->nattr);
    add_count(in, "regions", g->nregions);
    if (g->format == CLI_PSLG_JSON)
        add_count(in, "rings", g->rings);
    cJSON_AddStringToObject(j, "method", opt->method == TSR_TRI_QUADTREE ? "quadtree" : "delaunay");
    cJSON_AddStringToObject(j, "region", region_name(opt->region));
    cJSON_AddBoolToObject(j, "conforming", opt->conforming);
    add_count(j, "min_angle_bound", opt->min_angle);
    add_count(j, "max_area_bound", opt->max_area);
    add_count(j, "vertices", t->nv);
    add_count(j, "triangles", t->nt);
    add_count(j, "constrained_edges", t->nedge);
    add_count(j, "duplicates", t->duplicates);
    add_count(j, "intersections", t->intersections);
    add_count(j, "steiner", t->steiner);
    add_count(j, "degenerate_segments", t->degenerate_segments);
    add_count(j, "fallback_cells", t->fallback_cells);
    cJSON_AddBoolToObject(j, "fell_back", t->fell_back);
    if (t->fallback_reason)
        cJSON_AddStringToObject(j, "fallback_reason", t->fallback_reason);
    else
        cJSON_AddNullToObject(j, "fallback_reason");
    cJSON_AddBoolToObject(j, "quality_limited", t->quality_limited);
    cJSON_AddBoolToObject(j, "steiner_limited", t->steiner_limited);
    add_count(j, "unrefined", t->unrefined);
    add_count(j, "small_angle_exempt", t->small_angle_exempt);
    add_count(j, "below_resolution", t->below_resolution);
    add_count(j, "min_angle", c ? c->min_angle : smallest_angle(t));
    add_count(j, "seconds", seconds);
    if (c) {
        cJSON *k = cJSON_AddObjectToObject(j, "check");
        cJSON_AddBoolToObject(k, "ok", c->ok);
        add_count(k, "not_ccw", c->not_ccw);
        add_count(k, "bad_topology", c->bad_topology);
        add_count(k, "not_delaunay", c->not_delaunay);
        add_count(k, "missing_segments", c->missing_segments);
        add_count(k, "overlapping", c->overlapping);
        add_count(k, "area", c->area);
        if (isnan(c->expected_area))
            cJSON_AddNullToObject(k, "expected_area");
        else
            add_count(k, "expected_area", c->expected_area);
        cJSON_AddBoolToObject(k, "area_ok", c->area_ok);
        add_count(k, "euler", (double)c->euler);
        if (c->expected_euler == LONG_MIN)
            cJSON_AddNullToObject(k, "expected_euler");
        else
            add_count(k, "expected_euler", (double)c->expected_euler);
        add_count(k, "min_angle", c->min_angle);
        add_count(k, "below_min_angle", c->below_min_angle);
        add_count(k, "below_resolution_excused", c->below_resolution_excused);
        add_count(k, "above_max_area", c->above_max_area);
        cJSON_AddStringToObject(k, "first_problem", c->first_problem);
        add_count(k, "seconds", check_seconds);
    }
    char *s = cJSON_Print(j);
    if (s)
        printf("%s\n", s);
    free(s);
    cJSON_Delete(j);
}

/* Whether every point lies on one line (exactly), so no triangle exists. */
static bool collinear(const cli_pslg *g)
{
    uint32_t a = 0, b = 1;
    while (b < g->nv && g->xy[2 * b] == g->xy[0] && g->xy[2 * b + 1] == g->xy[1])
        b++;
    for (uint32_t k = b + 1; k < g->nv; k++)
        if (tsr_orient2d(g->xy + 2 * a, g->xy + 2 * b, g->xy + 2 * k) != 0)
            return false;
    return true;
}

static int run(int argc, char **argv)
{
    const char *in_path = NULL, *out_path = NULL;
    tsr_tri_options opt = {0};
    bool check = false, json = false, quiet = false, region_given = false;
    cli_pslg_format fmt = CLI_PSLG_UNKNOWN;
    uint32_t z_attr = 0; /* 1-based; 0: z = 0 */
    bool region_areas = false;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        }
        bool has_value = i + 1 < argc;
        if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_value)
            out_path = argv[++i];
        else if (!strcmp(a, "--method") && has_value) {
            const char *v = argv[++i];
            if (!strcmp(v, "delaunay"))
                opt.method = TSR_TRI_DELAUNAY;
            else if (!strcmp(v, "quadtree"))
                opt.method = TSR_TRI_QUADTREE;
            else {
                cli_error("triangulate", "--method %s: unknown method (use delaunay or quadtree)", v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--region") && has_value) {
            const char *v = argv[++i];
            if (!strcmp(v, "hull"))
                opt.region = TSR_REGION_HULL;
            else if (!strcmp(v, "enclosed"))
                opt.region = TSR_REGION_ENCLOSED;
            else if (!strcmp(v, "evenodd") || !strcmp(v, "even-odd"))
                opt.region = TSR_REGION_EVEN_ODD;
            else {
                cli_error("triangulate", "--region %s: unknown region (use hull, enclosed or evenodd)", v);
                return CLI_USAGE;
            }
            region_given = true;
        } else if (!strcmp(a, "-q") && has_value) {
            const char *v = argv[++i];
            if (!cli_parse_double(v, &opt.min_angle) || !(opt.min_angle > 0 && opt.min_angle < 60)) {
                cli_error("triangulate", "-q %s: the minimum angle must be a number of degrees above 0 and below 60",
                          v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "-a") && has_value) {
            const char *v = argv[++i];
            if (!cli_parse_double(v, &opt.max_area) || !(opt.max_area > 0)) {
                cli_error("triangulate", "-a %s: the maximum area must be a positive number", v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--max-steiner") && has_value) {
            const char *v = argv[++i];
            if (!cli_parse_u32(v, 1, UINT32_MAX, &opt.max_steiner)) {
                cli_error("triangulate", "--max-steiner %s: must be a positive integer", v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--z-attribute") && has_value) {
            const char *v = argv[++i];
            if (!cli_parse_u32(v, 1, 64, &z_attr)) {
                cli_error("triangulate", "--z-attribute %s: must be an attribute number from 1 to 64", v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--format") && has_value) {
            const char *v = argv[++i];
            fmt = cli_pslg_format_parse(v);
            if (fmt == CLI_PSLG_UNKNOWN) {
                cli_error("triangulate", "--format %s: unknown input format (use node, poly, json or txt)", v);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--conforming"))
            opt.conforming = true;
        else if (!strcmp(a, "--region-areas"))
            region_areas = true;
        else if (!strcmp(a, "--check"))
            check = true;
        else if (!strcmp(a, "--json"))
            json = true;
        else if (!strcmp(a, "--quiet"))
            quiet = true;
        else if (a[0] == '-' && a[1] != '\0') {
            cli_option_error("triangulate", NULL, a, help);
            return CLI_USAGE;
        } else if (in_path) {
            cli_error("triangulate", "one input at a time ('%s' and '%s' given)", in_path, a);
            return CLI_USAGE;
        } else
            in_path = a;
    }
    if (!in_path) {
        cli_error("triangulate", "no input file (see tessera triangulate --help)");
        return CLI_USAGE;
    }
    if (!out_path && !check && !json) {
        cli_error("triangulate", "no output: give -o OUT, --check or --json (see tessera triangulate --help)");
        return CLI_USAGE;
    }
    cli_tri_output out_kind = out_path ? cli_tri_output_from_path(out_path) : CLI_OUT_UNKNOWN;
    if (out_path && out_kind == CLI_OUT_UNKNOWN) {
        cli_error("triangulate", "%s: unknown output format (use .node, .ele, .poly, .obj, .ply, .stl or .glb)",
                  out_path);
        return CLI_USAGE;
    }
    if (fmt == CLI_PSLG_UNKNOWN && cli_pslg_format_from_path(in_path) == CLI_PSLG_UNKNOWN) {
        cli_error("triangulate", "%s: unknown input format (use .node, .poly, .json or .txt, or --format)", in_path);
        return CLI_USAGE;
    }
    /* the input never among the outputs: Triangle's three files share
     * OUT's base name (the .node a .poly of 0 points reads: below) */
    char outs[3][4096];
    const char *out_names[4] = {"the input", "the output", "the output", "the output"};
    const char *out_paths[4] = {in_path, out_path, NULL, NULL};
    if (out_kind == CLI_OUT_TRIANGLE && cli_tri_output_names(out_path, outs))
        out_paths[1] = outs[0], out_paths[2] = outs[1], out_paths[3] = outs[2];
    if (!cli_paths_distinct("triangulate", 4, out_names, out_paths))
        return CLI_USAGE;
    if (z_attr && out_kind != CLI_OUT_MESH) {
        cli_error("triangulate", "--z-attribute applies to a mesh output (.obj, .ply, .stl, .glb)");
        return CLI_USAGE;
    }
    if (opt.conforming && opt.method == TSR_TRI_QUADTREE) {
        cli_error("triangulate", "--conforming applies to --method delaunay only");
        return CLI_USAGE;
    }

    cli_pslg g;
    tsr_error err = {0};
    if (cli_pslg_read(in_path, fmt, &g, &err) != TSR_OK) {
        cli_error("triangulate", "%s", err.message);
        return CLI_FAIL;
    }
    if (g.points_file) {
        out_names[0] = "the points' file";
        out_paths[0] = g.points_file;
        if (!cli_paths_distinct("triangulate", 4, out_names, out_paths)) {
            cli_pslg_free(&g);
            return CLI_USAGE;
        }
    }
    if (z_attr > g.nattr) {
        cli_error("triangulate", "--z-attribute %u: %s has %s%u attribute%s per point", z_attr, in_path,
                  g.nattr ? "only " : "", g.nattr, g.nattr == 1 ? "" : "s");
        cli_pslg_free(&g);
        return CLI_USAGE;
    }
    /* the regions' maximum areas (Triangle's -a without a number) */
    double *bounds = NULL;
    bool has_bounds = false;
    for (uint32_t r = 0; r < g.nregions; r++)
        has_bounds = has_bounds || g.regions[4 * (size_t)r + 3] > 0;
    if (region_areas && !has_bounds) {
        cli_error("triangulate", "--region-areas: %s gives no region a maximum area", in_path);
        cli_pslg_free(&g);
        return CLI_USAGE;
    }
    if (region_areas) {
        if (!(bounds = malloc(3 * (size_t)g.nregions * sizeof *bounds))) {
            cli_error("triangulate", "out of memory");
            cli_pslg_free(&g);
            return CLI_FAIL;
        }
        for (uint32_t r = 0; r < g.nregions; r++)
            for (int k = 0; k < 3; k++)
                bounds[3 * (size_t)r + k] = g.regions[4 * (size_t)r + (k < 2 ? k : 3)];
        opt.regions = bounds;
        opt.nregions = g.nregions;
    } else if (has_bounds && !quiet)
        fprintf(stderr, "tessera triangulate: note: %s gives regions maximum areas; --region-areas applies them\n",
                in_path);
    if (!region_given)
        opt.region = g.format == CLI_PSLG_JSON                   ? TSR_REGION_EVEN_ODD
                     : g.format == CLI_PSLG_POLY && g.nseg > 0 ? TSR_REGION_ENCLOSED
                                                               : TSR_REGION_HULL;
    tsr_pslg in = cli_pslg_view(&g);
    tsr_triangulation t;
    double t0 = cli_now();
    tsr_status s = tsr_triangulate(&in, &opt, &t, NULL, &err);
    double seconds = cli_now() - t0;
    if (s != TSR_OK) {
        cli_error("triangulate", "%s: %s", in_path, err.message[0] ? err.message : tsr_status_str(s));
        free(bounds);
        cli_pslg_free(&g);
        return CLI_FAIL;
    }

    if (t.nt == 0 && collinear(&g)) { /* no triangle can exist: said, nothing written (an empty region,
                                          as of a polygon given twice under even-odd, is a valid answer) */
        cli_error("triangulate", "%s: no triangle: %s", in_path,
                  t.input_vertices < 3 ? "fewer than 3 distinct points" : "the points are all on one line");
        tsr_triangulation_free(&t);
        free(bounds);
        cli_pslg_free(&g);
        return CLI_FAIL;
    }
    int rc = CLI_OK;
    tsr_tri_check c;
    double check_seconds = 0;
    if (check) {
        t0 = cli_now();
        s = tsr_triangulation_check(&in, &opt, &t, &c);
        check_seconds = cli_now() - t0;
        if (s != TSR_OK) {
            cli_error("triangulate", "%s: the check could not run: %s", in_path, tsr_status_str(s));
            rc = CLI_FAIL;
            check = false;
        } else {
            if (!json)
                print_check(stdout, &opt, &t, &c);
            if (!c.ok)
                rc = CLI_FAIL;
        }
    }
    /* the attributes are written (Triangle's files) or give z */
    bool with_attrs = out_path && g.nattr && (out_kind == CLI_OUT_TRIANGLE || z_attr);
    /* a point given again with other attributes: the first's are used */
    if (with_attrs) {
        uint32_t *first = malloc(((size_t)t.nv + 1) * sizeof *first), count = 0, fi = 0, fj = 0;
        for (uint32_t v = 0; first && v < t.nv; v++)
            first[v] = UINT32_MAX;
        for (uint32_t i = 0; first && i < g.nv; i++) {
            uint32_t *f = &first[t.vertex_of_input[i]];
            if (*f == UINT32_MAX)
                *f = i;
            else if (memcmp(&g.attr[(size_t)i * g.nattr], &g.attr[(size_t)*f * g.nattr], g.nattr * sizeof *g.attr) &&
                     !count++)
                fi = i, fj = *f;
        }
        if (count)
            fprintf(stderr,
                    "tessera triangulate: warning: %s: %u point%s repeat%s an earlier point with other attributes (the "
                    "first: point %u repeats point %u); the triangles use the earlier's\n",
                    in_path, count, count == 1 ? "" : "s", count == 1 ? "s" : "", fi + g.first_index,
                    fj + g.first_index);
        free(first);
    }
    double *vals = NULL; /* the attributes at every output vertex, when written */
    if (with_attrs) {
        vals = malloc(((size_t)t.nv * g.nattr + 1) * sizeof *vals);
        s = vals ? tsr_tri_interpolate(&in, g.attr, g.nattr, &t, vals, NULL, &err)
                 : tsr_error_set(&err, TSR_ERR_NOMEM, "out of memory");
        if (s != TSR_OK) {
            cli_error("triangulate", "%s: the attributes: %s", in_path, err.message);
            rc = CLI_FAIL;
            out_path = NULL;
        }
        /* z of a mesh is float32 */
        for (uint32_t v = 0; s == TSR_OK && z_attr && v < t.nv; v++) {
            double z = vals[(size_t)v * g.nattr + z_attr - 1];
            if (fabs(z) > FLT_MAX) {
                cli_error("triangulate",
                          "%s: --z-attribute %u: %.17g at (%.17g, %.17g) is beyond float32, the mesh's "
                          "precision (scale the attribute)",
                          in_path, z_attr, z, t.xy[2 * (size_t)v], t.xy[2 * (size_t)v + 1]);
                rc = CLI_FAIL;
                out_path = NULL;
                break;
            }
        }
    }
    if (out_path) {
        s = out_kind == CLI_OUT_TRIANGLE
                ? cli_tri_write_triangle(out_path, &t, &g, vals, &err)
                : cli_tri_write_mesh(out_path, &t, vals, g.nattr, z_attr ? z_attr - 1 : 0, &err);
        if (s != TSR_OK) {
            cli_error("triangulate", "%s", err.message);
            rc = CLI_FAIL;
            out_path = NULL;
        }
    }
    if (json)
        print_json(in_path, &g, &opt, &t, seconds, check ? &c : NULL, check_seconds);
    if (!quiet && (rc == CLI_OK || (check && !c.ok))) {
        char extra[256] = "";
        size_t n = 0;
        if (t.fell_back)
            n += (size_t)snprintf(extra, sizeof extra, "; the quadtree fell back to Delaunay (%s)",
                                  t.fallback_reason ? t.fallback_reason : "no reason given");
        else if (t.fallback_cells)
            n += (size_t)snprintf(extra, sizeof extra, "; %u quadtree cells went to Delaunay", t.fallback_cells);
        if (t.below_resolution && n < sizeof extra)
            n += (size_t)snprintf(extra + n, sizeof extra - n,
                                  "; %u triangle%s below the angle bound, below the resolution of doubles",
                                  t.below_resolution, t.below_resolution == 1 ? "" : "s");
        if (check && n < sizeof extra)
            snprintf(extra + n, sizeof extra - n, "; check %s", c.ok ? "passed" : "FAILED");
        char dups[64] = ""; /* a point given again is one vertex (Triangle's files keep its number) */
        if (t.duplicates)
            snprintf(dups, sizeof dups, " (%u repeated)", t.duplicates);
        fprintf(stderr,
                "tessera triangulate: %s: %u points%s, %u segments -> %u vertices (%u Steiner), %u triangles, %u "
                "constrained edges, min angle %.3g deg, %.3f s (%s, %s)%s%s%s\n",
                in_path, g.nv, dups, g.nseg, t.nv, t.steiner, t.nt, t.nedge, check ? c.min_angle : smallest_angle(&t),
                seconds, opt.method == TSR_TRI_QUADTREE && !t.fell_back ? "quadtree" : "delaunay",
                region_name(opt.region), extra, out_path ? "; wrote " : "", out_path ? out_path : "");
    }
    /* bounds asked for and not met (refinement stopped at the Steiner
     * limit, or stuck): a warning, even with --quiet, and exit 3; the
     * triangulation written is valid and holds the segments. Triangles
     * below the resolution of doubles are allowed by the contract. */
    if (rc == CLI_OK && t.unrefined) {
        char asked[64] = "";
        snprintf(asked, sizeof asked, "%s%s%s%s%s", opt.min_angle > 0 ? "-q" : "",
                 opt.min_angle > 0 && (opt.max_area > 0 || opt.conforming) ? ", " : "", opt.max_area > 0 ? "-a" : "",
                 opt.max_area > 0 && opt.conforming ? ", " : "", opt.conforming ? "--conforming" : "");
        fprintf(stderr,
                "tessera triangulate: warning: %s: the bounds asked for (%s) are not met everywhere: %u triangle%s or "
                "edge%s left, %s\n",
                in_path, asked, t.unrefined, t.unrefined == 1 ? "" : "s", t.unrefined == 1 ? "" : "s",
                t.steiner_limited ? "refinement stopped at the Steiner limit"
                                  : "where no usable vertex position could mend them");
        rc = CLI_UNMET;
    }
    free(vals);
    tsr_triangulation_free(&t);
    free(bounds);
    cli_pslg_free(&g);
    return rc;
}

const cli_command cli_cmd_triangulate = {"triangulate", "triangulate points and segments (constrained Delaunay, quadtree)",
                                         run, help};
