/* cmd_info.c: `tessera info FILE`: what a heightfield holds. */
#include "cli.h"

#include <cjson/cJSON.h>
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera info FILE [options]\n\n"
               "Prints a heightfield's format, size, minimum, maximum, mean height and no-data count (a file\n"
               "whose every sample is no-data is described too: min, max and mean none, null in --json).\n"
               "Heights are in the file's units (8/16-bit images give their integer values, unless the file\n"
               "stores a height scale, as tessera generate's PNGs do); with --dz, the\n"
               "range scaled as meshes get it is printed too (z, JSON z_min and z_max).\n\n"
               "options:\n"
               "  --json                print the same as a JSON object\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help            this help\n");
}

static int run(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    const char *path = NULL;
    bool json = false;
    for (int i = 1; i < argc; i++) {
        if (cli_is_help(argv[i])) {
            help(stdout);
            return CLI_OK;
        }
        int r = cli_heightfield_option("info", argc, argv, &i, &o);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        if (!strcmp(argv[i], "--json"))
            json = true;
        else if (argv[i][0] == '-' && argv[i][1] != '\0') {
            cli_option_error("info", NULL, argv[i], help);
            return CLI_USAGE;
        } else if (path) {
            cli_error("info", "one file at a time ('%s' and '%s' given)", path, argv[i]);
            return CLI_USAGE;
        } else
            path = argv[i];
    }
    if (!path) {
        cli_error("info", "no input file (see tessera info --help)");
        return CLI_USAGE;
    }
    o.load.all_nodata_ok = true; /* a tile of sea is a file to describe, not a bad one */
    tsr_heightfield *hf = cli_load_heightfield("info", path, &o);
    if (!hf)
        return CLI_FAIL;
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    uint32_t w = tsr_heightfield_width(hf), h = tsr_heightfield_height(hf);
    bool none = st.nodata >= (uint64_t)w * h; /* no valid sample: no heights to give */
    const tsr_georef *g = tsr_heightfield_georef(hf);
    char spacing[256];
    cli_georef_describe(hf, &o, spacing, sizeof spacing);
    if (json) {
        cJSON *j = cJSON_CreateObject();
        cJSON_AddStringToObject(j, "file", path);
        cJSON_AddStringToObject(j, "format", tsr_heightfield_source_format(hf));
        cJSON_AddNumberToObject(j, "width", w);
        cJSON_AddNumberToObject(j, "height", h);
        cJSON_AddNumberToObject(j, "samples", (double)w * h);
        if (none) {
            cJSON_AddNullToObject(j, "min");
            cJSON_AddNullToObject(j, "max");
            cJSON_AddNullToObject(j, "mean");
        } else {
            cJSON_AddNumberToObject(j, "min", st.min);
            cJSON_AddNumberToObject(j, "max", st.max);
            cJSON_AddNumberToObject(j, "mean", st.mean);
        }
        cJSON_AddNumberToObject(j, "nodata", (double)st.nodata);
        if (o.dz > 0 && !none) { /* what the meshes get: z = h * dz */
            cJSON_AddNumberToObject(j, "dz", o.dz);
            cJSON_AddNumberToObject(j, "z_min", st.min * o.dz);
            cJSON_AddNumberToObject(j, "z_max", st.max * o.dz);
        }
        cli_georef_json(j, hf, &o);
        char *s = cJSON_Print(j);
        printf("%s\n", s);
        free(s);
        cJSON_Delete(j);
    } else {
        printf("file:    %s\nformat:  %s\nsize:    %u x %u (%llu samples)\n", path, tsr_heightfield_source_format(hf),
               w, h, (unsigned long long)w * h);
        if (none)
            printf("min:     none\nmax:     none\nmean:    none\nnodata:  %llu (every sample)",
                   (unsigned long long)st.nodata);
        else
            printf("min:     %.9g\nmax:     %.9g\nmean:    %.9g\nnodata:  %llu", st.min, st.max, st.mean,
                   (unsigned long long)st.nodata);
        if (g && g->has_nodata) {
            /* the float extremes are no-data whatever --nodata says
             * (tsr_heightfield_load) */
            bool extreme = fabs(g->nodata) >= FLT_MAX;
            printf(" (the file's no-data value: %.9g%s)", g->nodata,
                   !o.load.has_nodata ? ""
                   : extreme          ? "; still no-data beside --nodata's: the float extremes always are"
                                      : ", replaced by --nodata");
        }
        printf("\nspacing: %s\n", spacing);
        if (o.dz > 0 && !none)
            printf("z:       %.9g to %.9g (heights * %.9g, --dz: what meshes get)\n", st.min * o.dz, st.max * o.dz,
                   o.dz);
        if (g && g->has_transform)
            printf("origin:  %.12g, %.12g (sample 0, 0; pixel %.9g x %.9g)\n", g->origin[0], g->origin[1],
                   g->pixel[0], g->pixel[1]);
        if (g && (g->z_unit[0] || g->z_scale != 1 || g->z_offset != 0)) {
            printf("heights: %s", g->z_unit[0] ? g->z_unit : "");
            if (g->z_scale != 1 || g->z_offset != 0)
                printf("%sstored value * %.9g + %.9g (the file's scale and offset)", g->z_unit[0] ? "; " : "",
                       g->z_scale, g->z_offset);
            printf("\n");
        }
    }
    tsr_heightfield_destroy(hf);
    return CLI_OK;
}

const cli_command cli_cmd_info = {"info", "print a heightfield's format, size and height statistics", run, help};
