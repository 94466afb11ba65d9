/* cmd_check.c: `tessera check terrain IN`: tessellation error tests. For
 * each camera: select the cut, build its mesh, and measure with the
 * brute-force oracle (tsr_terrain_measure: heightfield and mesh only) the
 * worst screen error, plus validation and the 2:1 restriction. */
#include "camera.h"

#include <cjson/cJSON.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera check terrain IN [options]\n\n"
               "Selects the view-dependent tessellation of a heightfield for each camera and measures it\n"
               "independently: the worst screen-space error over all samples (the distance in pixels between\n"
               "a sample and the mesh point above or below it), watertightness, conformity (no T-junctions)\n"
               "and the 2:1 restriction. Exits 1 when any camera exceeds the pixel error or fails a check.\n\n"
               "options:\n"
               "  --pixel-error T       screen-space error allowed, pixels (default 1)\n"
               "  --cameras N           N random cameras, a third of them low and grazing (default 20)\n"
               "  --seed S              seed of the random cameras (default 1)\n"
               "  --camera EX,EY,EZ,TX,TY,TZ  a camera at eye E looking at T (world units; repeatable;\n"
               "                        replaces the random cameras)\n"
               "  --tile N              tile size: 8, 16, 32, 64 or 128 quads (default 16)\n"
               "  --width W, --height H viewport in pixels (default 1920 x 1080)\n"
               "  --fov DEG             vertical field of view (default 60)\n"
               "  --near D              near plane distance (default 1)\n"
               "  --export-mesh F.ply   write the selected mesh of the (single) given camera\n"
               "  --criterion C         exact (default): the conservative screen error of tessera; naive: the\n"
               "                        textbook delta*K/z, which the check shows failing near the viewport's edges\n"
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

static int run(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    view_options v = {60, 1920, 1080, 1, 1};
    const char *in = NULL, *export_mesh = NULL;
    uint32_t ncams = 20, seed = 1, tile = 16;
    bool json = false, naive = false;
    char **cam_args = calloc((size_t)argc + 1, sizeof *cam_args);
    int ncam_args = 0;
    int rc = CLI_OK;
    if (argc < 2 || strcmp(argv[1], "terrain")) {
        if (argc >= 2 && cli_is_help(argv[1])) {
            help(stdout);
            free(cam_args);
            return CLI_OK;
        }
        cli_error("check", "what to check? 'tessera check terrain IN' (see tessera check --help)");
        free(cam_args);
        return CLI_USAGE;
    }
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
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
        double d;
        uint32_t u;
        if (!strcmp(a, "--json"))
            json = true;
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
            *(!strcmp(a, "--cameras") ? &ncams : !strcmp(a, "--seed") ? &seed : &tile) = u;
        } else if ((!strcmp(a, "--pixel-error") || !strcmp(a, "--width") || !strcmp(a, "--height") ||
                    !strcmp(a, "--fov") || !strcmp(a, "--near")) &&
                   has_value) {
            if (!cli_parse_double(argv[++i], &d) || !(d > 0) || (!strcmp(a, "--fov") && d >= 179)) {
                cli_error("check", "%s %s: must be a positive number%s", a, argv[i],
                          !strcmp(a, "--fov") ? " below 179" : "");
                rc = CLI_USAGE;
                break;
            }
            *(!strcmp(a, "--pixel-error") ? &v.pixel_error
              : !strcmp(a, "--width")     ? &v.width
              : !strcmp(a, "--height")    ? &v.height
              : !strcmp(a, "--fov")       ? &v.fovy_deg
                                          : &v.near_dist) = d;
        } else if (a[0] == '-' && a[1] != '\0') {
            cli_error("check", "%s '%s' (see tessera check --help)", has_value ? "unknown option" : "missing value for", a);
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
    int n = ncam_args ? ncam_args : (int)ncams;
    tsr_camera *cams = calloc((size_t)n, sizeof *cams);
    cam_result *res = calloc((size_t)n, sizeof *res);
    uint64_t rng = 0x9E3779B97F4A7C15ull * (seed + 1);
    for (int k = 0; k < n && rc == CLI_OK; k++) {
        if (ncam_args) {
            if (!parse_camera(cam_args[k], &v, &cams[k])) {
                cli_error("check", "--camera %s: expected EX,EY,EZ,TX,TY,TZ with eye != target, not looking straight "
                          "up or down", cam_args[k]);
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
        if (tsr_quadtree_mesh(qt, false, &m) != TSR_OK || tsr_terrain_measure(hf, &m, &cams[k], &rep) != TSR_OK ||
            tsr_mesh_validate(&m, NULL, &val) != TSR_OK) {
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
        bool ok = r->max_px <= v.pixel_error * (1 + 1e-6) && r->watertight && r->conforming && r->balanced;
        failures += !ok;
        if (r->max_px > res[worst].max_px)
            worst = k;
        if (export_mesh && tsr_mesh_write(&m, export_mesh, TSR_FORMAT_UNKNOWN, &err) != TSR_OK) {
            cli_error("check", "%s", err.message);
            rc = CLI_FAIL;
        }
        tsr_mesh_free(&m);
        if (!json)
            printf("camera %3d  eye %.1f,%.1f,%.1f  max_pixel_error %.4f  tiles %5u  triangles %7u  select_us %8.1f  "
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
            printf("worst: camera %d, max_pixel_error %.4f px (tau %g) at sample %u,%u; %d of %d cameras failed\n", worst,
                   res[worst].max_px, v.pixel_error, res[worst].worst_c, res[worst].worst_r, failures, n);
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

const cli_command cli_cmd_check = {"check", "tessellation error tests: 'check terrain IN' measures the screen-space bound",
                                   run, help};
