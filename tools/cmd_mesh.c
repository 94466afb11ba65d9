/* cmd_mesh.c: `tessera mesh IN -o OUT`: heightmap to mesh. For now the
 * regular grid (every sample, or every step-th); the error-bounded methods
 * come with the heightmap-to-mesh issue. */
#include "cli.h"

#include <cjson/cJSON.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera mesh IN -o OUT [options]\n\n"
               "Converts a heightfield into a triangle mesh. OUT's extension picks the format:\n"
               ".obj, .ply (binary), .stl (binary) or .glb (glTF 2.0, +y up). Sample (c, r) becomes the\n"
               "vertex (c*dx, r*dy, h*dz); no-data samples become holes.\n\n"
               "options:\n"
               "  -o, --output OUT      mesh file to write (required)\n"
               "  --method grid         the regular grid of samples (the only method so far)\n"
               "  --step N              keep every N-th column and row (default 1: all samples)\n"
               "  --normals             per-vertex normals from the heightfield's gradients\n"
               "  --stats FILE.json     write vertices, triangles, seconds and the input's size and range\n"
               "  --quiet               print nothing on success\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help            this help\n");
}

static int run(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    const char *in = NULL, *out = NULL, *stats = NULL;
    uint32_t step = 1;
    bool normals = false, quiet = false;
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
        else if (!strcmp(a, "--method") && has_value) {
            if (strcmp(argv[++i], "grid")) {
                cli_error("mesh", "--method %s: only 'grid' is available in this version", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--step") && has_value) {
            if (!cli_parse_u32(argv[++i], 1, 1u << 20, &step)) {
                cli_error("mesh", "--step %s: must be a positive integer", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--normals"))
            normals = true;
        else if (!strcmp(a, "--quiet") || !strcmp(a, "-q"))
            quiet = true;
        else if (a[0] == '-' && a[1] != '\0') {
            cli_error("mesh", "%s '%s' (see tessera mesh --help)", has_value ? "unknown option" : "missing value for",
                      a);
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
    double t0 = cli_now();
    tsr_heightfield *hf = cli_load_heightfield("mesh", in, &o);
    if (!hf)
        return CLI_FAIL;
    tsr_mesh mesh;
    tsr_mesh_init(&mesh, normals ? TSR_MESH_NORMALS : 0, NULL);
    tsr_error err = {0};
    int rc = CLI_OK;
    if (tsr_terrain_grid_mesh(hf, step, normals, &mesh, &err) != TSR_OK ||
        tsr_mesh_write(&mesh, out, TSR_FORMAT_UNKNOWN, &err) != TSR_OK) {
        cli_error("mesh", "%s", err.message);
        rc = CLI_FAIL;
    }
    double secs = cli_now() - t0;
    if (rc == CLI_OK && stats) {
        tsr_heightfield_stats st;
        tsr_heightfield_stats_compute(hf, &st);
        cJSON *j = cJSON_CreateObject();
        cJSON_AddNumberToObject(j, "vertices", mesh.vertex_count);
        cJSON_AddNumberToObject(j, "triangles", mesh.triangle_count);
        cJSON_AddNumberToObject(j, "seconds", secs);
        cJSON_AddStringToObject(j, "method", "grid");
        cJSON_AddNumberToObject(j, "step", step);
        cJSON *inp = cJSON_AddObjectToObject(j, "input");
        cJSON_AddNumberToObject(inp, "width", tsr_heightfield_width(hf));
        cJSON_AddNumberToObject(inp, "height", tsr_heightfield_height(hf));
        cJSON_AddNumberToObject(inp, "min", st.min);
        cJSON_AddNumberToObject(inp, "max", st.max);
        cJSON_AddNumberToObject(inp, "nodata", (double)st.nodata);
        char *s = cJSON_Print(j);
        cJSON_Delete(j);
        size_t n = strlen(s);
        char *text = malloc(n + 2);
        if (text) {
            memcpy(text, s, n);
            text[n] = '\n';
            text[n + 1] = '\0';
        }
        if (!text || cli_write_text(stats, text, &err) != TSR_OK) {
            cli_error("mesh", "%s", text ? err.message : "out of memory");
            rc = CLI_FAIL;
        }
        free(text);
        free(s);
    }
    if (rc == CLI_OK && !quiet)
        fprintf(stderr, "tessera mesh: wrote %s (%s, %u vertices, %u triangles, grid step %u) in %.2f s\n", out,
                tsr_mesh_format_name(tsr_mesh_format_from_path(out)), mesh.vertex_count, mesh.triangle_count, step,
                secs);
    tsr_mesh_free(&mesh);
    tsr_heightfield_destroy(hf);
    return rc;
}

const cli_command cli_cmd_mesh = {"mesh", "convert a heightfield into a mesh (OBJ, PLY, STL, glTF)", run, help};
