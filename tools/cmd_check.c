/* cmd_check.c: tessellation error tests.
 *  - `tessera check terrain IN`: for each camera, select the cut, build
 *    its mesh, and measure with the brute-force oracle
 *    (tsr_terrain_measure: heightfield and mesh only) the worst screen
 *    error, plus validation and the 2:1 restriction.
 *  - `tessera check patches IN`: tessellate a patch model (patches/ptess.h)
 *    view-independently and for each camera, and measure it with the
 *    independent oracle tsr_ptess_measure (mesh, tri_uv and the surface's
 *    own evaluation only), plus validation and a search for cracks. */
#include "camera.h"
#include "patch_cli.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help_terrain(FILE *f)
{
    fprintf(f, "usage: tessera check terrain IN [options]\n\n"
               "Selects the view-dependent tessellation of a heightfield for each camera and measures it\n"
               "independently: the worst screen-space error over all samples (the distance in pixels between\n"
               "a sample and the mesh point above or below it), watertightness, conformity (no T-junctions)\n"
               "and the 2:1 restriction. Exits 1 when any camera exceeds the pixel error or fails a check.\n"
               "With --geomorph it measures the mesh as `tessera fly` draws it while tiles blend into their\n"
               "parents (odd vertices moved part of the way to the parent's surface), whose bound is 1.25 times\n"
               "the pixel error.\n\n"
               "options:\n"
               "  --pixel-error T       screen-space error allowed, pixels (default 1)\n"
               "  --cameras N           N random cameras, a third of them low and grazing (default 20)\n"
               "  --seed S              seed of the random cameras (default 1)\n"
               "  --camera EX,EY,EZ,TX,TY,TZ  a camera at eye E looking at T (world units; repeatable;\n"
               "                        replaces the random cameras)\n"
               "  --tile N              tile size: 2, 4, ..., 128 quads (default 16)\n"
               "  --width W, --height H viewport in pixels (default 1920 x 1080)\n"
               "  --fov DEG             vertical field of view (default 60)\n"
               "  --near D              near plane distance (default 1, or a thousandth of the terrain's\n"
               "                        size where that is less)\n"
               "  --export-mesh F.ply   write the selected mesh of the (single) given camera\n"
               "  --criterion C         exact (default): the conservative screen error of tessera; naive: the\n"
               "                        textbook delta*K/z, which the check shows failing near the viewport's edges\n"
               "  --geomorph            measure the geomorphed mesh, against 1.25 x the pixel error\n"
               "  --json                print the results as JSON\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help            this help\n");
}

/* The textbook criterion, for comparison: delta K / z with z the nearest
 * depth of the node's bounds (no obliquity factor). It is not conservative
 * near the viewport's edges; `--criterion naive` lets the oracle show it. */
static bool refine_naive(void *camera, const tsr_surface *s, tsr_qnode node)
{
    const tsr_camera *c = camera;
    if (tsr_camera_node_error(c, s, node) == 0)
        return false; /* culled, as the exact criterion would */
    float lo[3], hi[3];
    s->bounds(s->user, node, lo, hi);
    double fmin = INFINITY;
    for (int k = 0; k < 8; k++) {
        double p[3] = {k & 1 ? hi[0] : lo[0], k & 2 ? hi[1] : lo[1], k & 4 ? hi[2] : lo[2]}, sx, sy, f;
        tsr_camera_project(c, p, &sx, &sy, &f);
        fmin = f < fmin ? f : fmin;
    }
    double z = fmin > c->near_dist ? fmin : c->near_dist;
    return c->K * s->error(s->user, node) / z > c->pixel_error;
}

typedef struct cam_result {
    double max_px, select_us;
    uint32_t tiles, triangles, worst_c, worst_r;
    bool watertight, conforming, balanced;
} cam_result;

static void help_patches(FILE *f);

static void help(FILE *f)
{
    fprintf(f, "usage: tessera check terrain IN [options]\n"
               "       tessera check patches IN [options]\n\n"
               "Tessellation error tests: each tessellates its input, measures the error independently of\n"
               "how the mesh was made and validates the mesh; exit 1 when a bound or a check fails.\n\n"
               "  terrain   view-dependent terrain cuts for random or given cameras, in pixels\n"
               "  patches   Bezier, NURBS and subdivision surfaces, view-independent and per camera\n\n"
               "'tessera check terrain --help' and 'tessera check patches --help' give their options.\n");
}

static int run_terrain(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    view_options v = {60, 1920, 1080, 0, 1}; /* near 0: terrain_unit */
    const char *in = NULL, *export_mesh = NULL;
    uint32_t ncams = 20, seed = 1, tile = 16;
    bool json = false, naive = false, geomorph = false;
    char **cam_args = calloc((size_t)argc + 1, sizeof *cam_args);
    int ncam_args = 0;
    int rc = CLI_OK;
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help_terrain(stdout);
            free(cam_args);
            return CLI_OK;
        }
        int r = cli_heightfield_option("check", argc, argv, &i, &o);
        if (r < 0) {
            free(cam_args);
            return CLI_USAGE;
        }
        if (r > 0)
            continue;
        bool has_value = i + 1 < argc;
        int vo;
        uint32_t u;
        if (!strcmp(a, "--json"))
            json = true;
        else if (!strcmp(a, "--geomorph"))
            geomorph = true;
        else if (!strcmp(a, "--camera") && has_value)
            cam_args[ncam_args++] = argv[++i];
        else if (!strcmp(a, "--export-mesh") && has_value)
            export_mesh = argv[++i];
        else if (!strcmp(a, "--criterion") && has_value) {
            const char *cr = argv[++i];
            if (strcmp(cr, "exact") && strcmp(cr, "naive")) {
                cli_error("check", "--criterion %s: use exact or naive", cr);
                rc = CLI_USAGE;
                break;
            }
            naive = !strcmp(cr, "naive");
        }
        else if ((!strcmp(a, "--cameras") || !strcmp(a, "--seed") || !strcmp(a, "--tile")) && has_value) {
            if (!cli_parse_u32(argv[++i], !strcmp(a, "--seed") ? 0 : 1, 1000000, &u)) {
                cli_error("check", "%s %s: not a valid count", a, argv[i]);
                rc = CLI_USAGE;
                break;
            }
            if (!strcmp(a, "--tile") && !cli_tile_size_ok(u)) {
                cli_error("check", "--tile %s: must be a power of two from %u to %u", argv[i], TSR_TILE_MIN,
                          TSR_TILE_MAX);
                rc = CLI_USAGE;
                break;
            }
            *(!strcmp(a, "--cameras") ? &ncams : !strcmp(a, "--seed") ? &seed : &tile) = u;
        } else if ((vo = view_option("check", a, has_value ? argv[i + 1] : NULL, &v)) != 0) {
            if (vo < 0) {
                rc = CLI_USAGE;
                break;
            }
            i++;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_option_error("check", "terrain", a, help_terrain);
            rc = CLI_USAGE;
            break;
        } else if (in) {
            cli_error("check", "one input at a time ('%s' and '%s' given)", in, a);
            rc = CLI_USAGE;
            break;
        } else
            in = a;
    }
    if (rc == CLI_OK && !in) {
        cli_error("check", "no input file (see tessera check --help)");
        rc = CLI_USAGE;
    }
    if (rc == CLI_OK && export_mesh && ncam_args != 1) {
        cli_error("check", "--export-mesh needs exactly one --camera");
        rc = CLI_USAGE;
    }
    if (rc == CLI_OK && export_mesh && tsr_mesh_format_from_path(export_mesh) == TSR_FORMAT_UNKNOWN) {
        cli_error("check", "%s: unknown mesh format (use .ply, .obj, .stl or .glb)", export_mesh);
        rc = CLI_USAGE;
    }
    if (rc != CLI_OK) {
        free(cam_args);
        return rc;
    }
    tsr_heightfield *hf = cli_load_heightfield("check", in, &o);
    if (!hf) {
        free(cam_args);
        return CLI_FAIL;
    }
    tsr_terrain *t = NULL;
    tsr_error err = {0};
    tsr_terrain_options to = {tile};
    if (tsr_terrain_create(hf, &to, NULL, &t, &err) != TSR_OK) {
        cli_error("check", "%s: %s", in, err.message);
        tsr_heightfield_destroy(hf);
        free(cam_args);
        return CLI_FAIL;
    }
    if (!(v.near_dist > 0))
        v.near_dist = terrain_unit(t);
    int n = ncam_args ? ncam_args : (int)ncams;
    tsr_camera *cams = calloc((size_t)n, sizeof *cams);
    cam_result *res = calloc((size_t)n, sizeof *res);
    uint64_t rng = 0x9E3779B97F4A7C15ull * (seed + 1);
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        if (ncam_args) {
            if (!parse_camera(cam_args[k], &v, &cams[k])) {
                cli_error("check", "--camera %s: expected EX,EY,EZ,TX,TY,TZ with eye != target", cam_args[k]);
                rc = CLI_USAGE;
            }
        } else
            random_camera(t, &rng, k, &v, &cams[k]);
    }
    const tsr_surface *s = tsr_terrain_surface(t);
    tsr_heightfield_stats hst;
    tsr_heightfield_stats_compute(hf, &hst);
    tsr_quadtree *qt = rc == CLI_OK ? tsr_quadtree_create(s, NULL) : NULL;
    if (rc == CLI_OK && !qt) {
        cli_error("check", "out of memory");
        rc = CLI_FAIL;
    }
    double dx, dy;
    tsr_heightfield_spacing(hf, &dx, &dy, NULL);
    int failures = 0, worst = 0;
    double bound = geomorph ? 1.25 * v.pixel_error : v.pixel_error; /* see tsr_quadtree_mesh_geomorphed */
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        cam_result *r = &res[k];
        double t0 = cli_now();
        tsr_quadtree_select(qt, naive ? refine_naive : tsr_refine_camera, &cams[k]);
        r->select_us = (cli_now() - t0) * 1e6;
        tsr_quadtree_apply_camera(qt, &cams[k]);
        r->tiles = tsr_quadtree_leaf_count(qt);
        r->balanced = tsr_quadtree_leaves_balanced(qt);
        tsr_mesh m;
        tsr_mesh_init(&m, export_mesh ? TSR_MESH_NORMALS : 0, NULL);
        tsr_error_report rep;
        tsr_validation val;
        tsr_validate_options vo = {.height_field = true};
        tsr_status ms = geomorph ? tsr_quadtree_mesh_geomorphed(qt, false, &m) : tsr_quadtree_mesh(qt, false, &m);
        if (ms != TSR_OK || tsr_terrain_measure(hf, &m, &cams[k], &rep) != TSR_OK ||
            tsr_mesh_validate(&m, &vo, &val) != TSR_OK) {
            cli_error("check", "out of memory");
            rc = CLI_FAIL;
            tsr_mesh_free(&m);
            break;
        }
        r->triangles = m.triangle_count;
        r->max_px = rep.max_pixels;
        r->worst_c = rep.worst_c;
        r->worst_r = rep.worst_r;
        r->conforming = val.t_junctions == 0;
        r->watertight = val.nonmanifold_edges == 0 && val.misoriented_edges == 0 && val.degenerate_triangles == 0 &&
                        val.duplicate_triangles == 0 && val.first_bad_triangle == UINT32_MAX &&
                        (hst.nodata > 0 || tsr_mesh_boundary_is_rect(&m, 0, 0, s->extent_x * dx, s->extent_y * dy,
                                                                      1e-6 * (s->extent_x * dx + s->extent_y * dy), NULL));
        bool ok = r->max_px <= bound * (1 + 1e-6) && r->watertight && r->conforming && r->balanced;
        failures += !ok;
        if (r->max_px > res[worst].max_px)
            worst = k;
        if (export_mesh && tsr_mesh_write(&m, export_mesh, TSR_FORMAT_UNKNOWN, &err) != TSR_OK) {
            cli_error("check", "%s", err.message);
            rc = CLI_FAIL;
        }
        tsr_mesh_free(&m);
        if (!json)
            printf("camera %3d  eye %.6g,%.6g,%.6g  max_pixel_error %.4f  tiles %5u  triangles %7u  select_us %8.1f  "
                   "%s%s%s%s\n",
                   k, cams[k].eye[0], cams[k].eye[1], cams[k].eye[2], r->max_px, r->tiles, r->triangles, r->select_us,
                   ok ? "ok" : "FAIL", r->watertight ? "" : " not-watertight", r->conforming ? "" : " t-junctions",
                   r->balanced ? "" : " unbalanced");
    }
    if (rc == CLI_OK) {
        if (json) {
            cJSON *j = cJSON_CreateObject();
            cJSON_AddStringToObject(j, "input", in);
            cJSON_AddNumberToObject(j, "pixel_error", v.pixel_error);
            cJSON_AddBoolToObject(j, "geomorph", geomorph);
            cJSON_AddNumberToObject(j, "near", v.near_dist);
            cJSON_AddNumberToObject(j, "bound", bound);
            cJSON *arr = cJSON_AddArrayToObject(j, "cameras");
            for (int k = 0; k < n; k++) {
                cJSON *c = cJSON_CreateObject();
                cJSON_AddItemToObject(c, "eye", cJSON_CreateDoubleArray(cams[k].eye, 3));
                cJSON_AddItemToObject(c, "target", cJSON_CreateDoubleArray(cams[k].target, 3));
                cJSON_AddNumberToObject(c, "max_pixel_error", res[k].max_px);
                cJSON_AddBoolToObject(c, "watertight", res[k].watertight);
                cJSON_AddBoolToObject(c, "conforming", res[k].conforming);
                cJSON_AddBoolToObject(c, "balanced", res[k].balanced);
                cJSON_AddNumberToObject(c, "tiles", res[k].tiles);
                cJSON_AddNumberToObject(c, "triangles", res[k].triangles);
                cJSON_AddNumberToObject(c, "select_us", res[k].select_us);
                cJSON_AddItemToArray(arr, c);
            }
            cJSON *w = cJSON_AddObjectToObject(j, "worst");
            cJSON_AddNumberToObject(w, "camera", worst);
            cJSON_AddNumberToObject(w, "max_pixel_error", res[worst].max_px);
            cJSON_AddNumberToObject(w, "sample_column", res[worst].worst_c);
            cJSON_AddNumberToObject(w, "sample_row", res[worst].worst_r);
            cJSON_AddNumberToObject(j, "failures", failures);
            char *txt = cJSON_Print(j);
            printf("%s\n", txt);
            free(txt);
            cJSON_Delete(j);
        } else {
            char tau[64];
            if (geomorph)
                snprintf(tau, sizeof tau, "geomorphed: bound %g = 1.25 tau", bound);
            else
                snprintf(tau, sizeof tau, "tau %g", v.pixel_error);
            printf("worst: camera %d, max_pixel_error %.4f px (%s) at sample %u,%u; %d of %d cameras failed\n", worst,
                   res[worst].max_px, tau, res[worst].worst_c, res[worst].worst_r, failures, n);
        }
        if (failures)
            rc = CLI_FAIL;
    }
    tsr_quadtree_destroy(qt);
    free(cams);
    free(res);
    free(cam_args);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
    return rc;
}

/* ---- check patches ------------------------------------------------------ */

static void help_patches(FILE *f)
{
    fprintf(
        f,
        "usage: tessera check patches IN [options]\n\n"
        "Tessellates a patch model as tessera patch does, view-independently and for each camera, and measures\n"
        "every mesh independently of the tessellator: the largest distance between the surface S(u, v), as the patch\n"
        "itself evaluates it, and the mesh's point at the same (u, v), over a grid of samples per piece and the\n"
        "midpoint of every triangle edge; for a camera, in pixels between their projections. Every mesh is also\n"
        "validated (oriented, edge-manifold, no bad, degenerate or duplicate triangles, no T-junctions; an edge\n"
        "of three triangles of three patches that share that patch edge, a fin on a plate, is non-manifold by the\n"
        "input: JSON three_patch_edges) and\n"
        "searched for cracks: boundary edges lying along another boundary edge (within 1e-6 of the model's\n"
        "diagonal), where surfaces that should be joined are not. Along a patch edge without neighbour (for a\n"
        "subdivision cage, as OpenSubdiv's topology says: the boundary, a hole, a non-manifold edge),\n"
        "which the tessellator joins to nothing, such edges count as seams, not cracks, and a T-junction (a vertex,\n"
        "of any sheet, inside an open edge) is no failure: it is reported as unlinked-edge-t-junctions\n"
        "(JSON: unlinked_edge_t_junctions), apart from the T-junctions that fail (JSON: t_junctions), those on\n"
        "any other open edge, such as a linked patch edge left open. A patch set's links are not known to the\n"
        "check: there every T-junction fails. The view-independent run is also searched for gaps (JSON: gaps):\n"
        "open edges whose ends both lie within the tolerance of another open edge running the other way, where\n"
        "surfaces meet along a curve with different vertices (one long edge against two shorter ones) and leave\n"
        "a crack up to the tolerance wide; those along an unlinked cage edge or on a trimmed patch (trim curves\n"
        "are not joined) are reported as unjoined-gaps (JSON: unjoined_gaps), not failed. Exits 1 when a run\n"
        "exceeds its tolerance, leaves a sample of an untrimmed patch uncovered, or fails a check.\n\n"
        "For a cage it first says how far apart linked patches evaluate the points they share (9 points per\n"
        "link, both sides; JSON: model.link_gap): rounding on a consistent surface. Where OpenSubdiv evaluates\n"
        "two faces differently (catmark_chaikin1: 1.7e-3), the welded mesh follows one side, and a run can\n"
        "fail by that much at the other.\n\n"
        "IN is a Bezier patch file (.bpt), an OBJ with free-form surfaces (cstype/surf), or a polygon OBJ read as\n"
        "the cage of a subdivision surface (Catmull-Clark; bilinear when the file name starts with \"bilinear\").\n\n"
        "options:\n"
        "  --max-error E         view-independent tolerance, model units (default 1e-3 of the box diagonal)\n"
        "  --pixel-error T       screen-space tolerance of the camera runs, pixels (default 1)\n"
        "  --cameras N           N random cameras around the model's box: the eye 1.5 to 4 box radii from the\n"
        "                        centre, not straight above or below, looking at a random point of the box\n"
        "                        (default 8; 0 for the view-independent run only)\n"
        "  --seed S              seed of the random cameras (default 1)\n"
        "  --camera EX,EY,EZ,TX,TY,TZ  a camera at eye E looking at T (model units; repeatable; replaces the\n"
        "                        random cameras)\n"
        "  --width W, --height H viewport in pixels (default 1920 x 1080)\n"
        "  --fov DEG             vertical field of view (default 60)\n"
        "  --near D              near plane distance (default 1e-3 of the box diagonal)\n"
        "  --tile N              quads per tile side, even, 2..128 (default 4); Bezier patches\n"
        "                        choose theirs in N..4N-2 (one-tile ones also N/2, when even), the\n"
        "                        one giving the fewest quads; cage faces needing few tiles N or N/2\n"
        "                        (when even), likewise\n"
        "  --max-level L         quadtree depth per piece, 1..12 (default 10; a run measured beyond its\n"
        "                        tolerance is run again at 12, as tessera patch does, unless given)\n"
        "  --samples N           measurement samples per piece side (default 64)\n"
        "  --retries N           re-tessellate the pieces of patches whose error is estimated, not bounded\n"
        "                        (subdivision and trimmed patches) and measured beyond the tolerance, with at\n"
        "                        most half their tolerance, up to N times (default 6; 0: never), as tessera\n"
        "                        patch does; Bezier pieces are never retried, their bound is a proof\n"
        "  --scheme S            catmark or bilinear: the subdivision scheme of a polygon OBJ\n" CLI_WELD_HELP
            CLI_ORIENT_HELP
        "  --assume-linked       take every patch edge as linked: nothing counts as a seam and every\n"
        "                        T-junction fails (what a crack between joined patches would give)\n"
        "  --json                print the results as JSON (each run's watertight: no crack where\n"
        "                        surfaces meet, an open surface's rim being none; closed: no open\n"
        "                        edge at all; bound: null for a subdivision surface)\n"
        "  -h, --help            this help\n");
}

static double urand_patches(uint64_t *s)
{
    *s = *s * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*s >> 11) * (1.0 / 9007199254740992.0);
}

/* A random camera around the box: the eye 1.5 to 4 box radii from its
 * centre in a random direction at most ~64 degrees from horizontal, looking
 * at a random point of the box. */
static void random_patch_camera(const tsr_pmodel_info *info, uint64_t *rng, const view_options *v, tsr_camera *c)
{
    double ctr[3], r = 0;
    for (int k = 0; k < 3; k++) {
        ctr[k] = 0.5 * (info->lo[k] + info->hi[k]);
        r += (info->hi[k] - info->lo[k]) * (info->hi[k] - info->lo[k]);
    }
    r = sqrt(r) / 2;
    for (int tries = 0; tries < 1000; tries++) {
        double z = (2 * urand_patches(rng) - 1) * 0.9, phi = 6.283185307179586 * urand_patches(rng);
        double dist = r * (1.5 + 2.5 * urand_patches(rng)), h = sqrt(1 - z * z);
        double dir[3] = {h * cos(phi), h * sin(phi), z};
        memset(c, 0, sizeof *c);
        c->fovy_deg = v->fovy_deg;
        c->width = v->width;
        c->height = v->height;
        c->near_dist = v->near_dist;
        c->pixel_error = v->pixel_error;
        for (int k = 0; k < 3; k++) {
            c->eye[k] = ctr[k] + dist * dir[k];
            c->target[k] = info->lo[k] + urand_patches(rng) * (info->hi[k] - info->lo[k]);
        }
        if (tsr_camera_prepare(c))
            return;
    }
}

typedef struct boundary_edge {
    double lo[3], hi[3];
    uint32_t a, b;
    bool unlinked;
} boundary_edge;

static int cmp_boundary_edge(const void *x, const void *y)
{
    const boundary_edge *a = x, *b = y;
    return a->lo[0] < b->lo[0] ? -1 : a->lo[0] > b->lo[0];
}

typedef struct vertex_key {
    double x; /* the coordinate along the sweep axis */
    uint32_t v;
} vertex_key;

static int cmp_vertex_key(const void *x, const void *y)
{
    const vertex_key *a = x, *b = y;
    return a->x < b->x ? -1 : a->x > b->x;
}

typedef struct boundary_report {
    uint32_t boundary; /* boundary edges */
    uint32_t cracks;   /* boundary edges along another one, where ptess.h joins surfaces */
    uint32_t seams;    /* the same along unlinked patch edges (no neighbour: boundary, non-manifold cage edge) */
    uint32_t unlinked_junctions; /* (vertex, edge) T-junctions of tsr_mesh_validate whose edge is unlinked */
} boundary_report;

typedef struct tri_edge {
    uint32_t a, b, tri;
} tri_edge;

static int tri_edge_cmp(const void *x, const void *y)
{
    const tri_edge *p = x, *q = y;
    return p->a != q->a ? (p->a < q->a ? -1 : 1) : p->b != q->b ? (p->b < q->b ? -1 : 1) : 0;
}

/* The side of its source's domain (0 u = u0, 1 u = u1, 2 v = v0, 3 v =
 * v1) that both corners va, vb of triangle t lie on; -1 for none. */
static int corner_pair_side(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t t, uint32_t va, uint32_t vb)
{
    tsr_psource_info si;
    if (!tsr_pmodel_source_info(m, r->tri_source[t], &si))
        return -1;
    const uint32_t *tv = r->mesh.indices + 3 * (size_t)t;
    const double *uv[2] = {NULL, NULL};
    for (int k = 0; k < 3; k++)
        if (tv[k] == va || tv[k] == vb)
            uv[tv[k] == vb] = r->tri_uv + 6 * (size_t)t + 2 * k;
    if (!uv[0] || !uv[1])
        return -1;
    for (int side = 0; side < 4; side++) {
        int c = side / 2; /* u sides, then v sides */
        double at = si.domain[side], eps = 1e-9 * (si.domain[2 * c + 1] - si.domain[2 * c]);
        if (fabs(uv[0][c] - at) <= eps && fabs(uv[1][c] - at) <= eps)
            return side;
    }
    return -1;
}

/* Mesh edges of three triangles where three patches of a set meet along
 * one edge (a fin on a plate; ptess.h links them): each triangle with the
 * edge's two corners on one side of its source's domain, the three
 * (source, side) pairs distinct (two may be sides of one closed surface's
 * seam). The validation counts them non-manifold, as the input is.
 * UINT32_MAX when out of memory. */
static uint32_t three_patch_edges(const tsr_pmodel *m, const tsr_ptess_result *r)
{
    const tsr_mesh *me = &r->mesh;
    size_t n = 3 * (size_t)me->triangle_count;
    tri_edge *e = malloc((n ? n : 1) * sizeof *e);
    if (!e)
        return UINT32_MAX;
    for (size_t h = 0; h < n; h++) {
        uint32_t a = me->indices[h], b = me->indices[h - h % 3 + (h % 3 + 1) % 3];
        e[h] = (tri_edge){a < b ? a : b, a < b ? b : a, (uint32_t)(h / 3)};
    }
    qsort(e, n, sizeof *e, tri_edge_cmp);
    uint32_t count = 0;
    for (size_t i = 0, j; i < n; i = j) {
        for (j = i + 1; j < n && e[j].a == e[i].a && e[j].b == e[i].b;)
            j++;
        if (j - i != 3)
            continue;
        /* three distinct patch edges: sources, or sides of one source
         * (a fin along a closed surface's seam) */
        uint64_t key[3];
        bool ok = true;
        for (int k = 0; k < 3 && ok; k++) {
            int side = corner_pair_side(m, r, e[i + k].tri, e[i + k].a, e[i + k].b);
            ok = side >= 0;
            key[k] = (uint64_t)r->tri_source[e[i + k].tri] << 2 | (uint64_t)(side & 3);
        }
        count += ok && key[0] != key[1] && key[0] != key[2] && key[1] != key[2];
    }
    free(e);
    return count;
}

/* Cracks: boundary edges (one triangle) of the welded mesh lying within
 * eps of another boundary edge (both endpoints within eps of its segment),
 * found by a sweep along x. Half-edges marked in `unlinked` (may be NULL)
 * lie on a patch edge that has no neighbour in the model (the cage's
 * boundary, a hole, a non-manifold edge where three or more sheets meet or
 * two run the same way), where ptess.h joins nothing by contract:
 * coincidences among those are seams, not cracks.
 *
 * unlinked_junctions: the T-junctions that tsr_mesh_validate counts (a
 * referenced vertex other than its ends within eps of an open edge,
 * tsr_point_on_open_segment, one per vertex and half-edge) whose open edge
 * is unlinked. Whatever the vertex is (a boundary or an interior vertex of
 * another sheet lying along that edge), nothing was to be joined there and
 * no gap opens: the edge is open because the model says so. These are
 * counted here, on the same terms as the validator, to be discounted from
 * its total; a T-junction on any other open edge (a linked patch edge left
 * open: a crack between joined patches) stays in it. */
static tsr_status check_boundary(const tsr_mesh *m, double eps, const bool *unlinked, boundary_report *rep)
{
    memset(rep, 0, sizeof *rep);
    tsr_halfedges he;
    if (tsr_halfedges_build(&he, m, NULL) != TSR_OK)
        return TSR_ERR_NOMEM;
    uint32_t nb = 0;
    for (uint32_t h = 0; h < he.count; h++)
        nb += he.twin[h] == TSR_NO_TWIN;
    boundary_edge *e = malloc((nb ? nb : 1) * sizeof *e);
    bool *hit = calloc(nb ? nb : 1, sizeof *hit);
    bool *used = calloc((size_t)m->vertex_count + 1, sizeof *used);
    vertex_key *vk = NULL;
    tsr_status st = TSR_OK;
    if (!e || !hit || !used) {
        st = TSR_ERR_NOMEM;
        tsr_halfedges_free(&he);
        goto done;
    }
    nb = 0;
    bool any_unlinked = false;
    for (uint32_t h = 0; h < he.count; h++) {
        if (he.twin[h] != TSR_NO_TWIN)
            continue;
        boundary_edge *b = &e[nb++];
        b->a = m->indices[h];
        b->b = m->indices[3 * (h / 3) + (h % 3 + 1) % 3];
        b->unlinked = unlinked && unlinked[h];
        any_unlinked |= b->unlinked;
        for (int k = 0; k < 3; k++) {
            double pa = m->positions[3 * (size_t)b->a + k], pb = m->positions[3 * (size_t)b->b + k];
            b->lo[k] = (pa < pb ? pa : pb) - eps;
            b->hi[k] = (pa < pb ? pb : pa) + eps;
        }
    }
    tsr_halfedges_free(&he);
    qsort(e, nb, sizeof *e, cmp_boundary_edge);
    double eps2 = eps * eps;
    for (uint32_t i = 0; i < nb; i++)
        for (uint32_t j = i + 1; j < nb && e[j].lo[0] <= e[i].hi[0]; j++) {
            if (e[j].lo[1] > e[i].hi[1] || e[j].hi[1] < e[i].lo[1] || e[j].lo[2] > e[i].hi[2] ||
                e[j].hi[2] < e[i].lo[2])
                continue;
            const float *a0 = m->positions + 3 * (size_t)e[i].a, *a1 = m->positions + 3 * (size_t)e[i].b;
            const float *b0 = m->positions + 3 * (size_t)e[j].a, *b1 = m->positions + 3 * (size_t)e[j].b;
            if (tsr_point_segment_dist2(a0, b0, b1) <= eps2 && tsr_point_segment_dist2(a1, b0, b1) <= eps2)
                hit[i] = true;
            if (tsr_point_segment_dist2(b0, a0, a1) <= eps2 && tsr_point_segment_dist2(b1, a0, a1) <= eps2)
                hit[j] = true;
        }
    for (uint32_t i = 0; i < nb; i++) {
        rep->cracks += hit[i] && !e[i].unlinked;
        rep->seams += hit[i] && e[i].unlinked;
    }
    rep->boundary = nb;
    if (!any_unlinked)
        goto done;
    /* The vertices the triangles use, sorted along the box's longest axis;
     * each unlinked edge tests those within its box along that axis. */
    double lo[3] = {INFINITY, INFINITY, INFINITY}, hi[3] = {-INFINITY, -INFINITY, -INFINITY};
    uint32_t nv = 0;
    for (size_t k = 0; k < 3 * (size_t)m->triangle_count; k++)
        if (m->indices[k] < m->vertex_count && !used[m->indices[k]]) {
            used[m->indices[k]] = true;
            nv++;
            for (int c = 0; c < 3; c++) {
                double x = m->positions[3 * (size_t)m->indices[k] + c];
                lo[c] = x < lo[c] ? x : lo[c];
                hi[c] = x > hi[c] ? x : hi[c];
            }
        }
    int ax = hi[1] - lo[1] > hi[0] - lo[0] ? 1 : 0;
    ax = hi[2] - lo[2] > hi[ax] - lo[ax] ? 2 : ax;
    vk = malloc((nv ? nv : 1) * sizeof *vk);
    if (!vk) {
        st = TSR_ERR_NOMEM;
        goto done;
    }
    nv = 0;
    for (uint32_t v = 0; v < m->vertex_count; v++)
        if (used[v])
            vk[nv++] = (vertex_key){m->positions[3 * (size_t)v + ax], v};
    qsort(vk, nv, sizeof *vk, cmp_vertex_key);
    for (uint32_t i = 0; i < nb; i++) {
        const boundary_edge *E = &e[i];
        if (!E->unlinked || E->a == E->b)
            continue;
        uint32_t l = 0, r = nv; /* first key >= E->lo[ax] */
        while (l < r) {
            uint32_t mid = l + (r - l) / 2;
            if (vk[mid].x < E->lo[ax])
                l = mid + 1;
            else
                r = mid;
        }
        const float *pa = m->positions + 3 * (size_t)E->a, *pb = m->positions + 3 * (size_t)E->b;
        for (uint32_t k = l; k < nv && vk[k].x <= E->hi[ax]; k++) {
            uint32_t v = vk[k].v;
            if (v != E->a && v != E->b && tsr_point_on_open_segment(m->positions + 3 * (size_t)v, pa, pb, eps))
                rep->unlinked_junctions++;
        }
    }
done:
    free(e);
    free(hit);
    free(used);
    free(vk);
    return st;
}

/* For a subdivision model: marks the half-edges of r's mesh that lie on a
 * patch edge without neighbours (tsr_subd_patch_neighbours: the boundary,
 * a non-manifold cage edge, a hole). NULL when out of memory. */
static bool *subd_unlinked_halfedges(const tsr_pmodel *m, const tsr_subd *subd, const tsr_ptess_result *r)
{
    uint32_t nt = r->mesh.triangle_count;
    bool *u = calloc(3 * (size_t)nt + 1, sizeof *u);
    if (!u)
        return NULL;
    for (uint32_t t = 0; t < nt; t++) {
        tsr_psource_info si;
        if (!tsr_pmodel_source_info(m, r->tri_source[t], &si))
            continue;
        const double *uv = r->tri_uv + 6 * (size_t)t;
        for (int k = 0; k < 3; k++) {
            const double *p = uv + 2 * k, *q = uv + 2 * ((k + 1) % 3);
            int edge = fabs(p[1]) < 1e-9 && fabs(q[1]) < 1e-9           ? 0
                       : fabs(p[0] - 1) < 1e-9 && fabs(q[0] - 1) < 1e-9 ? 1
                       : fabs(p[1] - 1) < 1e-9 && fabs(q[1] - 1) < 1e-9 ? 2
                       : fabs(p[0]) < 1e-9 && fabs(q[0]) < 1e-9         ? 3
                                                                        : -1;
            tsr_subd_link links[2];
            if (edge >= 0 && tsr_subd_patch_neighbours(subd, si.patch, si.sub, (uint32_t)edge, links) == 0)
                u[3 * (size_t)t + k] = true;
        }
    }
    return u;
}

/* One tessellation and its measurement. */
typedef struct patch_run {
    bool has_camera;
    tsr_camera cam;
    double tol; /* max_error (model units) or pixel_error */
    tsr_ptess_measure_result meas;
    double bound, seconds; /* bound: of the Bezier pieces; none for a subdivision surface (no_bound) */
    bool no_bound;
    uint32_t triangles, vertices, leaves, rounds, rescaled;
    boundary_report bnd;
    uint32_t t_junctions;            /* counted: failures */
    uint32_t t_junctions_discounted; /* along unlinked patch edges (bnd.unlinked_junctions): no failure */
    uint32_t gaps;                   /* open edges facing another within the tolerance (tsr_mesh_find_gaps): failures */
    uint32_t gaps_open;              /* the same along unlinked patch edges or on trimmed patches: no failure */
    uint32_t three_patch_edges;      /* mesh edges where three patches of a set meet: non-manifold by the input */
    bool watertight, conforming, ok;
    bool deeper;       /* run again at max level 12 (the default depth measured beyond the tolerance) */
    char failed[600];  /* why the tessellation itself failed, or "" */
    char invalid[300]; /* tsr_validation_describe of the mesh */
} patch_run;

/* Runs the tessellator (again, with smaller tolerances for the pieces of
 * sources whose error is an estimate, while they measure beyond it), then
 * validates the final mesh. assume_linked: take every patch edge as
 * linked (nothing is a seam, no T-junction discounted). CLI_FAIL only when
 * out of memory; a failing check is recorded in pr. */
static int patch_run_do(const tsr_pmodel *m, const tsr_pmodel_info *info, const tsr_subd *subd,
                        const tsr_ptess_options *base, uint32_t per_side, uint32_t retries, double crack_eps,
                        bool assume_linked, patch_run *pr)
{
    tsr_ptess_options o = *base;
    o.camera = pr->has_camera ? &pr->cam : NULL;
    double *scale = NULL;
    tsr_ptess_result res;
    tsr_error err = {0};
    for (uint32_t round = 0;; round++) {
        o.piece_scale = scale;
        tsr_status st = tsr_ptess_run(m, &o, NULL, &res, &err);
        if (st != TSR_OK) {
            tsr_ptess_result_free(&res);
            free(scale);
            if (st == TSR_ERR_NOMEM) {
                cli_error("check", "out of memory");
                return CLI_FAIL;
            }
            snprintf(pr->failed, sizeof pr->failed, "tessellation failed: %s",
                     err.message[0] ? err.message : tsr_status_str(st));
            pr->ok = false;
            return CLI_OK;
        }
        st = tsr_ptess_measure(m, &res, per_side, o.camera, true, NULL, &pr->meas);
        if (st != TSR_OK) {
            tsr_ptess_result_free(&res);
            free(scale);
            cli_error("check", "measuring the tessellation: %s", tsr_status_str(st));
            return CLI_FAIL;
        }
        pr->rounds = round + 1;
        uint32_t again = 0;
        if (round < retries && !(pr->meas.max_error <= pr->tol * (1 + 1e-9))) {
            for (uint32_t s = 0; s < info->sources; s++) {
                double e = pr->meas.source_error[s];
                tsr_psource_info si;
                if (!(e <= pr->tol) && tsr_pmodel_source_info(m, s, &si) && (subd || si.trimmed)) {
                    if (!scale) {
                        scale = malloc((info->pieces ? info->pieces : 1) * sizeof *scale);
                        if (!scale) {
                            tsr_free(NULL, pr->meas.source_error);
                            tsr_ptess_result_free(&res);
                            cli_error("check", "out of memory");
                            return CLI_FAIL;
                        }
                        for (uint32_t k = 0; k < info->pieces; k++)
                            scale[k] = 1;
                    }
                    double f = 0.7 * pr->tol / e; /* at least halved each round */
                    f = f > 0.5 ? 0.5 : f >= 1.0 / 64 ? f : 1.0 / 64;
                    for (uint32_t b = 0; b < si.pieces_v; b++)
                        for (uint32_t a = 0; a < si.pieces_u; a++) {
                            size_t k = si.first_piece + (size_t)b * si.pieces_u + a;
                            if (k < info->pieces)
                                scale[k] = scale[k] * f >= 1e-6 ? scale[k] * f : 1e-6;
                        }
                    again += si.pieces_u * si.pieces_v;
                }
            }
        }
        tsr_free(NULL, pr->meas.source_error);
        pr->meas.source_error = NULL;
        if (!again)
            break;
        pr->rescaled += again;
        tsr_ptess_result_free(&res);
    }
    free(scale);
    pr->triangles = res.mesh.triangle_count;
    pr->vertices = res.mesh.vertex_count;
    pr->leaves = res.leaves;
    pr->bound = res.bound;
    pr->no_bound = subd != NULL; /* its pieces' errors are estimates */
    pr->seconds = res.seconds;
    tsr_validation val;
    tsr_validate_options vo = {0};
    vo.epsilon = crack_eps;
    /* Which patch edges have no neighbour is known from the model, apart
     * from the mesh: for a subdivision cage, tsr_subd_patch_neighbours. A
     * patch set's links are not exposed (ptess.h), so there every patch
     * edge counts as linked and nothing is discounted. */
    bool want_unlinked = subd && !assume_linked;
    bool *unlinked = want_unlinked ? subd_unlinked_halfedges(m, subd, &res) : NULL;
    if ((want_unlinked && !unlinked) || tsr_mesh_validate(&res.mesh, &vo, &val) != TSR_OK ||
        check_boundary(&res.mesh, crack_eps, unlinked, &pr->bnd) != TSR_OK) {
        free(unlinked);
        tsr_ptess_result_free(&res);
        cli_error("check", "out of memory");
        return CLI_FAIL;
    }
    /* Gaps: in the view-independent run, open edges facing another within
     * the tolerance (a crack where surfaces meet with different vertices,
     * wider than crack_eps). Along an unlinked patch edge or on a trimmed
     * patch (whose trim curves ptess.h does not join) they are reported,
     * not failed. */
    pr->gaps = pr->gaps_open = 0;
    if (!pr->has_camera && !cli_patch_gaps(m, &res, pr->tol, unlinked, &pr->gaps, &pr->gaps_open)) {
        free(unlinked);
        tsr_ptess_result_free(&res);
        cli_error("check", "out of memory");
        return CLI_FAIL;
    }
    free(unlinked);
    /* three patches along one edge: non-manifold in the input */
    uint32_t fins = !subd && val.nonmanifold_edges ? three_patch_edges(m, &res) : 0;
    tsr_ptess_result_free(&res);
    if (fins == UINT32_MAX) {
        cli_error("check", "out of memory");
        return CLI_FAIL;
    }
    pr->three_patch_edges = fins;
    pr->watertight = val.bad_indices == 0 && val.nonfinite_positions == 0 && val.degenerate_triangles == 0 &&
                     val.duplicate_triangles == 0 && val.nonmanifold_edges == fins && val.misoriented_edges == 0 &&
                     val.first_bad_triangle == UINT32_MAX && pr->bnd.cracks == 0 && pr->gaps == 0;
    /* The rule: a T-junction (a vertex inside an open edge) is a failure
     * unless that open edge lies on a patch edge without neighbour, where
     * ptess.h joins nothing by contract (the edge is open because the
     * model is, whatever sheet the vertex belongs to: coplanar overlapping
     * cage faces put interior vertices of one sheet on the other's open
     * edge, catmark_val2_nonman). A T-junction on an open edge of a linked
     * patch edge (a crack between joined patches) or of no patch edge still
     * fails. The discounted ones are reported apart, not hidden. */
    pr->t_junctions_discounted =
        pr->bnd.unlinked_junctions < val.t_junctions ? pr->bnd.unlinked_junctions : val.t_junctions;
    pr->t_junctions = val.t_junctions - pr->t_junctions_discounted;
    pr->conforming = pr->t_junctions == 0;
    tsr_validation_describe(&val, pr->invalid, sizeof pr->invalid);
    pr->ok = pr->meas.max_error <= pr->tol * (1 + 1e-9) && pr->meas.uncovered == 0 && pr->watertight &&
             pr->conforming && pr->triangles > 0;
    return CLI_OK;
}

/* " beyond-tolerance uncovered 3 cracks 2 ..." */
static void patch_run_reasons(const patch_run *pr, char *buf, size_t cap)
{
    buf[0] = '\0';
    if (pr->failed[0]) {
        snprintf(buf, cap, " %s", pr->failed);
        return;
    }
    size_t n = 0;
    if (!(pr->meas.max_error <= pr->tol * (1 + 1e-9)))
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " beyond-tolerance");
    if (pr->meas.uncovered)
        n +=
            (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " uncovered %llu", (unsigned long long)pr->meas.uncovered);
    if (pr->bnd.cracks)
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " cracks %u", pr->bnd.cracks);
    if (pr->gaps)
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " gaps %u", pr->gaps);
    if (!pr->watertight && !pr->bnd.cracks && !pr->gaps)
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " not-watertight (%s)", pr->invalid);
    if (!pr->conforming)
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " t-junctions %u", pr->t_junctions);
    if (pr->triangles == 0)
        n += (size_t)snprintf(buf + n, n < cap ? cap - n : 0, " no-triangles");
}

static cJSON *patch_run_json(const patch_run *pr)
{
    cJSON *c = cJSON_CreateObject();
    cJSON_AddBoolToObject(c, "max_level_12", pr->deeper);
    if (pr->has_camera) {
        cJSON_AddItemToObject(c, "eye", cJSON_CreateDoubleArray(pr->cam.eye, 3));
        cJSON_AddItemToObject(c, "target", cJSON_CreateDoubleArray(pr->cam.target, 3));
        cJSON_AddNumberToObject(c, "max_pixel_error", pr->meas.max_error);
        cJSON_AddNumberToObject(c, "rms_pixel_error", pr->meas.rms_error);
    } else {
        cJSON_AddNumberToObject(c, "max_error", pr->meas.max_error);
        cJSON_AddNumberToObject(c, "rms_error", pr->meas.rms_error);
        cJSON_AddNumberToObject(c, "tolerance", pr->tol);
        if (pr->no_bound)
            cJSON_AddNullToObject(c, "bound");
        else
            cJSON_AddNumberToObject(c, "bound", pr->bound);
    }
    /* watertight: no crack where surfaces join (an open surface's rim is
     * no crack); closed: no open edge at all */
    cJSON_AddBoolToObject(c, "watertight", pr->watertight);
    cJSON_AddBoolToObject(c, "closed", pr->watertight && pr->bnd.boundary == 0);
    cJSON_AddBoolToObject(c, "conforming", pr->conforming);
    cJSON_AddNumberToObject(c, "triangles", pr->triangles);
    cJSON_AddNumberToObject(c, "vertices", pr->vertices);
    cJSON_AddNumberToObject(c, "leaves", pr->leaves);
    cJSON_AddNumberToObject(c, "seconds", pr->seconds);
    cJSON_AddNumberToObject(c, "samples", (double)pr->meas.samples);
    cJSON_AddNumberToObject(c, "uncovered", (double)pr->meas.uncovered);
    cJSON_AddNumberToObject(c, "trimmed_out", (double)pr->meas.trimmed_out);
    cJSON_AddNumberToObject(c, "cracks", pr->bnd.cracks);
    cJSON_AddNumberToObject(c, "t_junctions", pr->t_junctions);
    if (!pr->has_camera) {
        cJSON_AddNumberToObject(c, "gaps", pr->gaps);
        cJSON_AddNumberToObject(c, "unjoined_gaps", pr->gaps_open);
    }
    cJSON_AddNumberToObject(c, "nonmanifold_seam_edges", pr->bnd.seams);
    cJSON_AddNumberToObject(c, "three_patch_edges", pr->three_patch_edges);
    cJSON_AddNumberToObject(c, "unlinked_edge_t_junctions", pr->t_junctions_discounted);
    cJSON_AddNumberToObject(c, "boundary_edges", pr->bnd.boundary);
    cJSON_AddNumberToObject(c, "rounds", pr->rounds);
    cJSON_AddNumberToObject(c, "rescaled_pieces", pr->rescaled);
    if (pr->meas.worst_source != UINT32_MAX) {
        cJSON_AddNumberToObject(c, "worst_source", pr->meas.worst_source);
        cJSON_AddItemToObject(c, "worst_uv", cJSON_CreateDoubleArray(pr->meas.worst_uv, 2));
    }
    if (pr->failed[0])
        cJSON_AddStringToObject(c, "error", pr->failed);
    cJSON_AddBoolToObject(c, "ok", pr->ok);
    return c;
}

static int run_patches(int argc, char **argv)
{
    view_options v = {60, 1920, 1080, 0, 1};
    const char *in = NULL;
    uint32_t ncams = 8, seed = 1, tile = 4, max_level = 0, per_side = 64, retries = 6;
    double max_error = 0;
    const char *scheme = NULL;
    double weld = 0;
    bool orient = false;
    bool json = false, assume_linked = false;
    char **cam_args = calloc((size_t)argc + 1, sizeof *cam_args);
    int ncam_args = 0, rc = CLI_OK;
    if (!cam_args) {
        cli_error("check", "out of memory");
        return CLI_FAIL;
    }
    for (int i = 2; i < argc && rc == CLI_OK; i++) {
        const char *a = argv[i];
        bool has_value = i + 1 < argc;
        int vo;
        uint32_t u;
        if (cli_is_help(a)) {
            help_patches(stdout);
            free(cam_args);
            return CLI_OK;
        } else if (!strcmp(a, "--json"))
            json = true;
        else if (!strcmp(a, "--assume-linked"))
            assume_linked = true;
        else if (!strcmp(a, "--orient-faces"))
            orient = true;
        else if (!strcmp(a, "--camera") && has_value)
            cam_args[ncam_args++] = argv[++i];
        else if (!strcmp(a, "--weld") && has_value) {
            if (!cli_parse_double(argv[++i], &weld) || !(weld > 0)) {
                cli_error("check", "--weld %s: must be a positive distance", argv[i]);
                rc = CLI_USAGE;
            }
        } else if (!strcmp(a, "--scheme") && has_value) {
            const char *sc = argv[++i];
            if (strcmp(sc, "catmark") && strcmp(sc, "bilinear")) {
                cli_error("check", "--scheme %s: use catmark or bilinear", sc);
                rc = CLI_USAGE;
            }
            scheme = sc;
        } else if ((!strcmp(a, "--cameras") || !strcmp(a, "--seed") || !strcmp(a, "--tile") ||
                    !strcmp(a, "--max-level") || !strcmp(a, "--samples") || !strcmp(a, "--retries")) &&
                   has_value) {
            bool cams = !strcmp(a, "--cameras"), sd = !strcmp(a, "--seed"), tl = !strcmp(a, "--tile");
            bool ml = !strcmp(a, "--max-level"), sm = !strcmp(a, "--samples");
            uint32_t lo = cams || sd || !strcmp(a, "--retries") ? 0 : tl || sm ? 2 : 1;
            uint32_t hi = tl ? TSR_TILE_MAX : ml ? 12 : sm ? 4096 : cams ? 100000 : sd ? UINT32_MAX : 100;
            if (!cli_parse_u32(argv[++i], lo, hi, &u) || (tl && u % 2)) {
                cli_error("check", "%s %s: expected %s %u..%u", a, argv[i], tl ? "an even number in" : "a number in",
                          lo, hi);
                rc = CLI_USAGE;
                break;
            }
            *(cams ? &ncams : sd ? &seed : tl ? &tile : ml ? &max_level : sm ? &per_side : &retries) = u;
        } else if (!strcmp(a, "--max-error") && has_value) {
            if (!cli_parse_double(argv[++i], &max_error) || !(max_error > 0)) {
                cli_error("check", "%s %s: must be a positive number", a, argv[i]);
                rc = CLI_USAGE;
                break;
            }
        } else if ((vo = view_option("check", a, has_value ? argv[i + 1] : NULL, &v)) != 0) {
            if (vo < 0) {
                rc = CLI_USAGE;
                break;
            }
            i++;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_option_error("check", "patches", a, help_patches);
            rc = CLI_USAGE;
        } else if (in) {
            cli_error("check", "one input at a time ('%s' and '%s' given)", in, a);
            rc = CLI_USAGE;
        } else
            in = a;
    }
    if (rc == CLI_OK && !in) {
        cli_error("check", "no input file (see tessera check --help)");
        rc = CLI_USAGE;
    }
    cli_patch_model p;
    memset(&p, 0, sizeof p);
    if (rc == CLI_OK && !cli_patch_model_load_weld("check", in, scheme, weld, orient, &p))
        rc = CLI_FAIL;
    if (rc == CLI_OK) {
        cli_patch_flat_warnings("check", in, &p, 5);
        cli_patch_trim_warnings("check", in, &p, 5);
        cli_patch_model_notes("check", in, &p);
    }
    if (rc != CLI_OK) {
        free(cam_args);
        return rc;
    }
    tsr_pmodel_info info;
    tsr_pmodel_get_info(p.model, &info);
    double diag = p.diag;
    if (!(diag > 0) || !isfinite(diag)) {
        cli_error("check", "%s: the model has no extent (its box is a point)", in);
        cli_patch_model_free(&p);
        free(cam_args);
        return CLI_FAIL;
    }
    /* the float32 mesh's floor, as tessera patch has it: a bound below it
     * refused, the default raised to it */
    double maxabs, step, floor_err = cli_patch_float_floor(p.model, &maxabs, &step);
    if (max_error > 0 && max_error < floor_err) {
        cli_error("check",
                  "%s: --max-error %g is below what the float32 mesh can hold: coordinates up to %g are "
                  "stored in steps of %.3g; give at least %.3g",
                  in, max_error, maxabs, step, floor_err);
        cli_patch_model_free(&p);
        free(cam_args);
        return CLI_USAGE;
    }
    double tol = max_error > 0 ? max_error : 1e-3 * diag;
    if (tol < floor_err) {
        if (!json)
            printf("note: the default tolerance %.3g is below what the float32 mesh holds this far from the origin "
                   "(coordinates up to %g); using %.3g\n",
                   tol, maxabs, floor_err);
        tol = floor_err;
    }
    if (!(v.near_dist > 0))
        v.near_dist = 1e-3 * diag;
    int n = ncam_args ? ncam_args : (int)ncams;
    patch_run *runs = calloc((size_t)n + 1, sizeof *runs);
    if (!runs) {
        cli_error("check", "out of memory");
        rc = CLI_FAIL;
    }
    uint64_t rng = 0x9E3779B97F4A7C15ull * ((uint64_t)seed + 1);
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        patch_run *r = &runs[k + 1];
        r->has_camera = true;
        r->tol = v.pixel_error;
        if (!ncam_args)
            random_patch_camera(&info, &rng, &v, &r->cam);
        else if (!parse_camera(cam_args[k], &v, &r->cam)) {
            cli_error("check", "--camera %s: expected EX,EY,EZ,TX,TY,TZ with eye != target", cam_args[k]);
            rc = CLI_USAGE;
        }
    }
    /* the view-independent run on the model `tessera patch` tessellates
     * for a bound (knot spans curved one way cut across their curve for
     * this bound and tile: cli_patch_model_split); camera runs, as patch's,
     * on the model as loaded */
    tsr_pmodel *vi_model = NULL;
    tsr_pmodel_info vi_info = info;
    if (rc == CLI_OK && !p.is_subd) {
        tsr_pmodel_set_options so = {weld, tol, tile};
        tsr_error e = {0};
        if (tsr_pmodel_from_set_opts(&p.set, &so, NULL, &vi_model, &e) != TSR_OK) {
            cli_error("check", "%s: %s", in, e.message);
            rc = CLI_FAIL;
        } else {
            tsr_pmodel_get_info(vi_model, &vi_info);
            cli_patch_partial_warning("check", in, vi_model);
        }
    }
    tsr_ptess_options base = {0};
    base.tile_n = tile;
    base.max_level = max_level;
    base.max_error = tol;
    if (rc == CLI_OK && !json)
        printf("input %s: %s, %u patches, %u pieces, %u linked edges, %u collapsed edges, %u mirrored, %u trimmed; "
               "box diagonal %.6g\n",
               in, p.kind, info.sources, info.pieces, info.links, info.collapsed_edges, info.mirrored,
               info.trimmed_sources, diag);
    /* a subdivision surface as Bfr evaluates it may disagree with itself
     * across a shared edge or corner: said, so that a failure there is
     * understood (the mesh can follow only one side) */
    double gap = 0;
    tsr_subd_gap_at ga = {0};
    if (rc == CLI_OK && p.subd && tsr_subd_link_gap(p.subd, &gap, &ga) != TSR_OK) {
        cli_error("check", "%s: out of memory", in);
        rc = CLI_FAIL;
    }
    if (rc == CLI_OK && p.subd && !json)
        printf("linked patches evaluated apart by up to %.3g (%.3g of the tolerance): face %u sub-patch %u (u %g, v %g) "
               "against face %u sub-patch %u (u %g, v %g)%s\n",
               gap, gap / tol, ga.face, ga.sub, ga.uv[0], ga.uv[1], ga.other_face, ga.other_sub, ga.other_uv[0],
               ga.other_uv[1],
               gap > 1e-3 * tol ? ": OpenSubdiv evaluates the two sides differently there, and the welded mesh "
                                  "follows one of them"
                                : "");
    int failures = 0, worst = 0;
    char why[800];
    for (int k = 0; k <= n && rc == CLI_OK; k++) {
        patch_run *r = &runs[k];
        if (k == 0)
            r->tol = tol;
        const tsr_pmodel *rm = k == 0 && vi_model ? vi_model : p.model;
        const tsr_pmodel_info *ri = k == 0 ? &vi_info : &info;
        rc = patch_run_do(rm, ri, p.subd, &base, per_side, retries, 1e-6 * diag, assume_linked, r);
        if (rc == CLI_OK && !max_level && !r->failed[0] && r->meas.max_error > r->tol * (1 + 1e-9)) {
            /* as tessera patch does: the default depth did not reach the
             * tolerance, so once more as deep as the quadtree goes */
            patch_run deep = {0};
            deep.has_camera = r->has_camera;
            deep.cam = r->cam;
            deep.tol = r->tol;
            tsr_ptess_options b12 = base;
            b12.max_level = 12;
            rc = patch_run_do(rm, ri, p.subd, &b12, per_side, retries, 1e-6 * diag, assume_linked, &deep);
            deep.deeper = true;
            *r = deep;
        }
        if (rc != CLI_OK)
            break;
        failures += !r->ok;
        if (k > 0 && (worst == 0 || r->meas.max_error > runs[worst].meas.max_error))
            worst = k;
        if (json)
            continue;
        patch_run_reasons(r, why, sizeof why);
        char retried[192] = "";
        if (r->rounds > 1)
            snprintf(retried, sizeof retried, "  rounds %u (%u pieces rescaled)", r->rounds, r->rescaled);
        if (r->deeper)
            snprintf(retried + strlen(retried), sizeof retried - strlen(retried), "  max-level 12");
        if (r->bnd.seams)
            snprintf(retried + strlen(retried), sizeof retried - strlen(retried), "  nonmanifold-seam-edges %u",
                     r->bnd.seams);
        if (r->t_junctions_discounted)
            snprintf(retried + strlen(retried), sizeof retried - strlen(retried), "  unlinked-edge-t-junctions %u",
                     r->t_junctions_discounted);
        if (r->gaps_open)
            snprintf(retried + strlen(retried), sizeof retried - strlen(retried), "  unjoined-gaps %u", r->gaps_open);
        char bound[64] = "no bound: estimates";
        if (!r->no_bound)
            snprintf(bound, sizeof bound, "bound %.6g", r->bound);
        if (k == 0)
            printf("view-independent  max_error %.6g (tolerance %.6g, %s)  rms %.3g  triangles %u  vertices %u  "
                   "seconds %.3f%s  %s%s\n",
                   r->meas.max_error, r->tol, bound, r->meas.rms_error, r->triangles, r->vertices, r->seconds, retried,
                   r->ok ? "ok" : "FAIL", why);
        else
            printf("camera %3d  eye %.9g,%.9g,%.9g  max_pixel_error %.4f  triangles %7u  seconds %.3f%s  %s%s\n", k - 1,
                   r->cam.eye[0], r->cam.eye[1], r->cam.eye[2], r->meas.max_error, r->triangles, r->seconds, retried,
                   r->ok ? "ok" : "FAIL", why);
    }
    if (rc == CLI_OK) {
        const patch_run *vi = &runs[0], *w = &runs[worst];
        if (json) {
            cJSON *j = cJSON_CreateObject();
            cJSON_AddStringToObject(j, "input", in);
            cJSON_AddStringToObject(j, "kind", p.kind);
            cJSON_AddNumberToObject(j, "max_error", tol);
            cJSON_AddNumberToObject(j, "pixel_error", v.pixel_error);
            cJSON *mo = cJSON_AddObjectToObject(j, "model");
            cJSON_AddNumberToObject(mo, "patches", info.sources);
            cJSON_AddNumberToObject(mo, "pieces", info.pieces);
            cJSON_AddNumberToObject(mo, "linked_edges", info.links); /* as tessera patch --stats names them */
            cJSON_AddNumberToObject(mo, "collapsed_edges", info.collapsed_edges);
            cJSON_AddNumberToObject(mo, "mirrored", info.mirrored);
            cJSON_AddNumberToObject(mo, "trimmed", info.trimmed_sources);
            cJSON_AddItemToObject(mo, "lo", cJSON_CreateDoubleArray(info.lo, 3));
            cJSON_AddItemToObject(mo, "hi", cJSON_CreateDoubleArray(info.hi, 3));
            cJSON_AddNumberToObject(mo, "diagonal", diag);
            if (p.subd) {
                cJSON *g = cJSON_AddObjectToObject(mo, "link_gap");
                cJSON_AddNumberToObject(g, "distance", gap);
                cJSON_AddNumberToObject(g, "face", ga.face);
                cJSON_AddNumberToObject(g, "sub", ga.sub);
                cJSON_AddItemToObject(g, "uv", cJSON_CreateDoubleArray(ga.uv, 2));
                cJSON_AddNumberToObject(g, "other_face", ga.other_face);
                cJSON_AddNumberToObject(g, "other_sub", ga.other_sub);
                cJSON_AddItemToObject(g, "other_uv", cJSON_CreateDoubleArray(ga.other_uv, 2));
            }
            cJSON *vj = patch_run_json(vi);
            cJSON_AddNumberToObject(vj, "patches", info.sources);
            /* the model this run tessellates, as tessera patch does for a
             * bound (pieces cut for it): the same counts as patch --stats */
            cJSON_AddNumberToObject(vj, "pieces", vi_info.pieces);
            cJSON_AddNumberToObject(vj, "linked_edges", vi_info.links);
            cJSON_AddItemToObject(j, "view_independent", vj);
            cJSON *arr = cJSON_AddArrayToObject(j, "cameras");
            for (int k = 1; k <= n; k++)
                cJSON_AddItemToArray(arr, patch_run_json(&runs[k]));
            if (n > 0) {
                cJSON *wj = cJSON_AddObjectToObject(j, "worst");
                cJSON_AddNumberToObject(wj, "camera", worst - 1);
                cJSON_AddNumberToObject(wj, "max_pixel_error", w->meas.max_error);
                if (w->meas.worst_source != UINT32_MAX) {
                    cJSON_AddNumberToObject(wj, "source", w->meas.worst_source);
                    cJSON_AddItemToObject(wj, "uv", cJSON_CreateDoubleArray(w->meas.worst_uv, 2));
                }
            }
            cJSON_AddNumberToObject(j, "failures", failures);
            char *txt = cJSON_Print(j);
            printf("%s\n", txt);
            free(txt);
            cJSON_Delete(j);
        } else {
            char at[2][96];
            for (int k = 0; k < 2; k++) {
                const patch_run *r = k ? vi : w;
                if (r->meas.worst_source == UINT32_MAX)
                    snprintf(at[k], sizeof at[k], "with no sample measured");
                else
                    snprintf(at[k], sizeof at[k], "at patch %u (u %.6g, v %.6g)", r->meas.worst_source,
                             r->meas.worst_uv[0], r->meas.worst_uv[1]);
            }
            printf("worst: ");
            if (n > 0)
                printf("camera %d, max_pixel_error %.4f px (tau %g) %s; ", worst - 1, w->meas.max_error, v.pixel_error,
                       at[0]);
            printf("view-independent max_error %.6g (tolerance %.6g) %s; %d of %d runs failed\n", vi->meas.max_error,
                   tol, at[1], failures, n + 1);
        }
        if (failures)
            rc = CLI_FAIL;
    }
    free(runs);
    free(cam_args);
    tsr_pmodel_destroy(vi_model);
    cli_patch_model_free(&p);
    return rc;
}

static int run(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "terrain"))
        return run_terrain(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "patches"))
        return run_patches(argc, argv);
    if (argc >= 2 && cli_is_help(argv[1])) {
        help(stdout);
        return CLI_OK;
    }
    cli_error("check", "what to check? 'tessera check terrain IN' or 'tessera check patches IN' (see tessera check "
                       "--help)");
    return CLI_USAGE;
}

const cli_command cli_cmd_check = {
    "check", "tessellation error tests: 'check terrain IN', 'check patches IN' measure the bounds", run, help};
