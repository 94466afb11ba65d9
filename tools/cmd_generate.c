/* cmd_generate.c: `tessera generate`: the project's own sample terrain. */
#include "cli.h"

#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera generate -o OUT [options]\n\n"
               "Generates a realistic sample terrain (fractal noise, ridged mountains, hydraulic and\n"
               "thermal erosion), deterministic by seed, and saves it. OUT's extension picks the format:\n"
               ".png (16-bit, with the height scale and offset stored in the file), .tif or .exr (float32).\n"
               "The sample spacing is stored in the file too: mesh, fly, check and info use it unless\n"
               "given --dx.\n\n"
               "options:\n"
               "  -o, --output OUT   file to write (required)\n"
               "  --size N           width and height in samples (default 1025)\n"
               "  --width W          width in samples (default: --size)\n"
               "  --height H         height in samples (default: --size)\n"
               "  --seed S           random seed, 0..4294967295 (default 1)\n"
               "  --relief M         height range in metres (default 1200)\n"
               "  --spacing S        metres between samples (default 30, as the SRTM's 1 arc-second;\n"
               "                     with the default size and relief, 30.7 km across, 1200 m high)\n"
               "  --quiet            print nothing on success (no summary, no progress bar)\n"
               "  -h, --help         this help\n\n"
               "The noise runs on every processor, the erosion on one (about 35 s for 4097 x 4097 on\n"
               "a small machine, 4 to 5 times as long for each doubling of the side); the terrain is\n"
               "the same on any machine. Where stderr is a terminal, a progress bar shows after a\n"
               "second.\n");
}

static int run(int argc, char **argv)
{
    const char *out = NULL;
    uint32_t w = 1025, h = 1025, seed = 1;
    bool w_set = false, h_set = false, quiet = false;
    double relief = 1200, spacing = 30;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        }
        bool has_value = i + 1 < argc;
        if ((!strcmp(a, "-o") || !strcmp(a, "--output")) && has_value)
            out = argv[++i];
        else if (!strcmp(a, "--quiet"))
            quiet = true;
        else if (!strcmp(a, "--size") && has_value) {
            uint32_t s;
            if (!cli_parse_u32(argv[++i], TSR_HEIGHTFIELD_MIN_SIDE, 65536, &s)) {
                cli_error("generate", "--size %s: must be an integer from 2 to 65536", argv[i]);
                return CLI_USAGE;
            }
            if (!w_set)
                w = s;
            if (!h_set)
                h = s;
        } else if ((!strcmp(a, "--width") || !strcmp(a, "--height")) && has_value) {
            uint32_t s;
            if (!cli_parse_u32(argv[++i], TSR_HEIGHTFIELD_MIN_SIDE, 65536, &s)) {
                cli_error("generate", "%s %s: must be an integer from 2 to 65536", a, argv[i]);
                return CLI_USAGE;
            }
            if (a[2] == 'w')
                w = s, w_set = true;
            else
                h = s, h_set = true;
        } else if (!strcmp(a, "--seed") && has_value) {
            if (!cli_parse_u32(argv[++i], 0, UINT32_MAX, &seed)) {
                cli_error("generate", "--seed %s: must be an integer from 0 to 4294967295", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--spacing") && has_value) {
            if (!cli_parse_double(argv[++i], &spacing) || !(spacing > 0) || !(spacing <= 1e9)) {
                cli_error("generate", "--spacing %s: must be a positive number of metres, at most 1e9", argv[i]);
                return CLI_USAGE;
            }
        } else if (!strcmp(a, "--relief") && has_value) {
            if (!cli_parse_double(argv[++i], &relief) || !(relief > 0)) {
                cli_error("generate", "--relief %s: must be a positive number", argv[i]);
                return CLI_USAGE;
            }
        } else {
            if (a[0] == '-')
                cli_option_error("generate", NULL, a, help);
            else
                cli_error("generate", "unexpected argument '%s' (see tessera generate --help)", a);
            return CLI_USAGE;
        }
    }
    if (!out) {
        cli_error("generate", "no output file: give -o OUT.png (see tessera generate --help)");
        return CLI_USAGE;
    }
    if ((uint64_t)w * h > TSR_HEIGHTFIELD_MAX_SAMPLES) {
        cli_error("generate", "%ux%u is beyond Tessera's limit of %llu samples", w, h,
                  (unsigned long long)TSR_HEIGHTFIELD_MAX_SAMPLES);
        return CLI_USAGE;
    }
    tsr_error err = {0};
    tsr_status cs = tsr_heightfield_save_check(out, &err); /* before the work, not after it */
    if (cs != TSR_OK) {
        cli_error("generate", "%s", err.message);
        return cs == TSR_ERR_IO ? CLI_FAIL : CLI_USAGE;
    }
    tsr_heightfield *hf = tsr_heightfield_create(w, h, NULL);
    if (!hf) {
        cli_error("generate", "out of memory for %ux%u samples", w, h);
        return CLI_FAIL;
    }
    double t0 = cli_now();
    cli_progress pr;
    cli_progress_start(&pr, "generate", !quiet);
    tsr_generate_options go = {.seed = seed, .relief = relief, .progress = cli_progress_cb, .progress_user = &pr};
    tsr_terrain_generate(hf, &go);
    cli_progress_end(&pr);
    double t1 = cli_now();
    tsr_heightfield_set_spacing(hf, spacing, spacing, 1);
    tsr_save_info info;
    if (tsr_heightfield_save(hf, out, &info, &err) != TSR_OK) {
        cli_error("generate", "%s", err.message);
        tsr_heightfield_destroy(hf);
        return CLI_FAIL;
    }
    if (!quiet)
        fprintf(stderr, "tessera generate: wrote %s (%ux%u, %g m apart, seed %u, relief %g m; generated in %.2f s)\n",
                out, w, h, spacing, seed, relief, t1 - t0);
    tsr_heightfield_destroy(hf);
    return CLI_OK;
}

const cli_command cli_cmd_generate = {"generate", "generate the sample terrain (fractal noise and erosion)", run, help};
