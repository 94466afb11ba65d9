/* bench_fly.c: `tessera bench fly`: the flyover's frame-time breakdown
 * (select, upload, record, draw) on a generated terrain, on the Vulkan
 * device and, as the baseline in the same run, on the null backend (the
 * host-side cost without any device), plus upload volumes. */
#include "bench.h"
#include "fly.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera bench fly [options]\n\n"
               "Flies along the automatic path over a generated terrain (or a file) at a steady speed (one loop\n"
               "in --loop-frames frames), renders offscreen, and prints per-phase frame times (mean, 95th\n"
               "percentile), tiles, triangles, and upload volumes: bytes per terrain vertex uploaded and\n"
               "bytes per frame as a share of the resident set. The null backend (no device) runs the same\n"
               "frames as the baseline.\n\n"
               "options:\n"
               "  --size S            generated terrain of S x S samples (default 4097), 10 m spacing\n"
               "  --input FILE        fly over this heightfield instead (heightfield options apply)\n"
               "  --frames N          frames measured (default 200; the first, which fills the cache, is\n"
               "                      reported apart)\n"
               "  --loop-frames L     frames per loop of the path (default 3600: a minute at 60 fps)\n"
               "  --width W, --height H  viewport (default 1280 x 720)\n"
               "  --pixel-error T     pixels (default 2)\n"
               "  --tile N            tile size (default 16)\n"
               "  --device NAME|INDEX the Vulkan device\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help          this help\n");
}

typedef struct series {
    double *v;
    uint32_t n;
} series;

static void summary(const series *s, double *mean, double *p95)
{
    double sum = 0;
    for (uint32_t i = 0; i < s->n; i++)
        sum += s->v[i];
    *mean = s->n ? sum / s->n : 0;
    double *c = malloc((s->n ? s->n : 1) * sizeof *c);
    memcpy(c, s->v, s->n * sizeof *c);
    qsort(c, s->n, sizeof *c, bench_cmp_double);
    /* the nearest rank: the smallest value with 95 % of the frames at or below it */
    *p95 = s->n ? c[(uint32_t)(((uint64_t)95 * s->n + 99) / 100) - 1] : 0;
    free(c);
}

enum { PH_SELECT, PH_UPLOAD, PH_RECORD, PH_DRAW, PH_WAIT, PH_CPU, NPH };

typedef struct run_result {
    series ph[NPH];
    double first_ms, tiles, triangles, bytes_frame, resident, bytes_per_vertex;
    uint64_t uploaded_bytes, uploaded_vertices, gpu_triangles_mismatch;
    uint32_t u16_tiles, resident_tiles;
    char device[256];
} run_result;

static int fly_run(const tsr_heightfield *hf, tsr_hw_backend *be, const fly_options *o, uint32_t frames,
                   uint32_t loop, run_result *r)
{
    memset(r, 0, sizeof *r);
    snprintf(r->device, sizeof r->device, "%s", be->name);
    fly_ctx f;
    tsr_error err = {0};
    if (fly_init(&f, hf, be, o, &err) != TSR_OK) {
        cli_error("bench", "fly: %s", err.message);
        return CLI_FAIL;
    }
    fly_path path;
    if (fly_path_auto(&f, &path, &err) != TSR_OK) {
        cli_error("bench", "fly: %s", err.message);
        fly_free(&f);
        return CLI_FAIL;
    }
    for (int k = 0; k < NPH; k++)
        r->ph[k].v = calloc(frames, sizeof(double));
    double clearance = 0.01 * (f.zmax - f.zmin) + 2 * f.o.near_dist;
    uint32_t n1 = (f.o.tile_n + 1) * (f.o.tile_n + 1);
    int rc = CLI_OK;
    for (uint32_t i = 0; i <= frames; i++) {
        tsr_camera cam;
        if (!fly_path_camera(&f, &path, fmod((double)i / loop, 1.0), clearance, &cam, NULL))
            continue;
        fly_frame_stats fs;
        if (fly_frame(&f, &cam, &fs, &err) != TSR_OK) {
            cli_error("bench", "fly: frame %u: %s", i, err.message);
            rc = CLI_FAIL;
            break;
        }
        const tsr_hw_render_stats *s = &fs.render;
        if (i == 0) { /* the cold frame fills the cache */
            r->first_ms = fs.select_ms + s->upload_ms + s->record_ms;
            continue;
        }
        double v[NPH] = {fs.select_ms, s->upload_ms, s->record_ms, s->device.gpu_ms, s->device.submit_wait_ms,
                         fs.select_ms + s->upload_ms + s->record_ms};
        for (int k = 0; k < NPH; k++)
            r->ph[k].v[r->ph[k].n++] = v[k];
        r->tiles += s->tiles;
        r->triangles += (double)s->triangles;
        r->bytes_frame += (double)s->bytes_uploaded;
        r->resident += (double)s->bytes_resident;
        r->uploaded_bytes += s->bytes_uploaded;
        r->uploaded_vertices += (uint64_t)s->tiles_uploaded * n1;
        r->gpu_triangles_mismatch += s->device.triangles != s->triangles && s->device.triangles != 0;
        r->u16_tiles = s->tiles_u16;
        r->resident_tiles = s->tiles_resident;
    }
    uint32_t n = r->ph[0].n ? r->ph[0].n : 1;
    r->tiles /= n;
    r->triangles /= n;
    r->bytes_frame /= n;
    r->resident /= n;
    r->bytes_per_vertex = r->uploaded_vertices ? (double)r->uploaded_bytes / r->uploaded_vertices : 0;
    fly_path_free(&path);
    fly_free(&f);
    return rc;
}

static void free_run(run_result *r)
{
    for (int k = 0; k < NPH; k++)
        free(r->ph[k].v);
}

int cli_bench_fly(int argc, char **argv)
{
    cli_heightfield_options ho = {0};
    uint32_t size = 4097, frames = 200, loop = 3600, width = 1280, height = 720;
    const char *input = NULL, *device = NULL;
    fly_options o = {.tile_n = 16, .pixel_error = 2, .geomorph = true};
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        int h = cli_heightfield_option("bench", argc, argv, &i, &ho);
        if (h < 0)
            return CLI_USAGE;
        if (h > 0)
            continue;
        bool more = i + 1 < argc, ok = true;
        const char *want = "";
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        } else if (!strcmp(a, "--size") && more)
            ok = cli_parse_u32(argv[++i], 17, 65537, &size), want = "a side from 17 to 65537 samples";
        else if (!strcmp(a, "--frames") && more)
            ok = cli_parse_u32(argv[++i], 1, 1000000, &frames), want = "a count from 1 to 1000000";
        else if (!strcmp(a, "--loop-frames") && more)
            ok = cli_parse_u32(argv[++i], 2, 100000000, &loop), want = "a count from 2 to 100000000";
        else if (!strcmp(a, "--width") && more)
            ok = cli_parse_u32(argv[++i], 16, 8192, &width), want = "pixels from 16 to 8192";
        else if (!strcmp(a, "--height") && more)
            ok = cli_parse_u32(argv[++i], 16, 8192, &height), want = "pixels from 16 to 8192";
        else if (!strcmp(a, "--pixel-error") && more)
            ok = cli_parse_double(argv[++i], &o.pixel_error) && o.pixel_error > 0 && o.pixel_error <= 1e4,
            want = "pixels > 0, up to 10000";
        else if (!strcmp(a, "--tile") && more)
            ok = cli_parse_u32(argv[++i], TSR_TILE_MIN, TSR_TILE_MAX, &o.tile_n) && cli_tile_size_ok(o.tile_n),
            want = "a power of two from 2 to 128";
        else if (!strcmp(a, "--input") && more)
            input = argv[++i];
        else if (!strcmp(a, "--device") && more)
            device = argv[++i];
        else {
            cli_option_error("bench", "fly", a, help);
            return CLI_USAGE;
        }
        if (!ok) {
            cli_error("bench", "fly: %s wants %s, not '%s'", a, want, argv[i]);
            return CLI_USAGE;
        }
    }
    tsr_heightfield *hf;
    if (input) {
        hf = cli_load_heightfield("bench", input, &ho);
        if (!hf)
            return CLI_FAIL;
    } else {
        hf = tsr_heightfield_create(size, size, NULL);
        if (!hf) {
            cli_error("bench", "fly: out of memory for a %ux%u terrain", size, size);
            return CLI_FAIL;
        }
        fprintf(stderr, "bench fly: generating a %ux%u terrain...\n", size, size);
        tsr_terrain_generate_fast(hf, 1, 2000);
        tsr_heightfield_set_spacing(hf, 10, 10, 1);
    }
    tsr_hw_vulkan_options vo = {.width = width, .height = height, .device = device};
    tsr_hw_backend *vk = NULL, *null = tsr_hw_null_create(width, height, NULL);
    tsr_error err = {0};
    if (tsr_hw_vulkan_create(&vo, NULL, &vk, &err) != TSR_OK) {
        cli_error("bench", "fly: %s", err.message);
        tsr_heightfield_destroy(hf);
        null->destroy(null);
        return CLI_FAIL;
    }
    fprintf(stderr, "bench fly: %u frames on %s and on the null backend...\n", frames, vk->name);
    run_result rv = {0}, rn = {0};
    int rc = fly_run(hf, vk, &o, frames, loop, &rv);
    if (rc == CLI_OK)
        rc = fly_run(hf, null, &o, frames, loop, &rn);
    if (rc == CLI_OK) {
        printf("tessera bench fly: %ux%u terrain, %ux%u, tau %.2f px, tile %u, %u frames at 1/%u loop per frame\n",
               tsr_heightfield_width(hf), tsr_heightfield_height(hf), width, height, o.pixel_error, o.tile_n, frames,
               loop);
        printf("device: %s\n\n", rv.device);
        printf("%-28s %12s %12s %14s %14s\n", "phase (ms per frame)", "mean", "p95", "null mean", "vs null");
        const char *names[NPH] = {"select (CPU)", "upload (CPU)", "record (CPU)", "draw (GPU timestamps)",
                                  "wait for the device", "select+upload+record"};
        for (int k = 0; k < NPH; k++) {
            double m, p, mn, pn;
            summary(&rv.ph[k], &m, &p);
            summary(&rn.ph[k], &mn, &pn);
            if (k == PH_DRAW || k == PH_WAIT)
                printf("%-28s %12.3f %12.3f %14s %14s\n", names[k], m, p, "-", "-");
            else
                printf("%-28s %12.3f %12.3f %14.3f %13.2fx\n", names[k], m, p, mn, mn > 0 ? m / mn : 0);
        }
        double m, p;
        summary(&rv.ph[PH_CPU], &m, &p);
        printf("\ncold first frame (fills the cache): %.1f ms\n", rv.first_ms);
        printf("tiles drawn per frame: %.0f; triangles: %.0f\n", rv.tiles, rv.triangles);
        printf("resident: %.1f MB in %u tiles (%u stored as 16-bit)\n", rv.resident / 1048576.0, rv.resident_tiles,
               rv.u16_tiles);
        printf("uploaded bytes per terrain vertex: %.3f (target <= 2 where 16 bits suffice)\n", rv.bytes_per_vertex);
        printf("uploaded per frame in steady flight: %.1f KB = %.2f%% of the resident set (target <= 5%%)\n",
               rv.bytes_frame / 1024, rv.resident > 0 ? 100 * rv.bytes_frame / rv.resident : 0);
        printf("CPU select+upload+record: %.3f ms mean, %.3f ms p95 (target < 2 ms)\n", m, p);
        if (rv.gpu_triangles_mismatch)
            printf("WARNING: the GPU's triangle count differed from the cut's in %llu frames\n",
                   (unsigned long long)rv.gpu_triangles_mismatch);
    }
    free_run(&rv);
    free_run(&rn);
    vk->destroy(vk);
    null->destroy(null);
    tsr_heightfield_destroy(hf);
    return rc;
}
