/* bench_mesh.c: `tessera bench mesh`: the heightmap meshers on the demo
 * terrain, on the real terrains of the shared data and optionally on a
 * large generated one, over a ladder of error bounds. For each method:
 * triangles, the measured max error (tsr_terrain_measure, independent of
 * the mesher), seconds (best of R) and peak heap bytes (a counting
 * allocator under the heightfield copy, the mesher and the mesh), with the
 * quadtree's triangles and speed as ratios against delaunay's in the same
 * run, and plain greedy Delaunay (no_flip) beside delaunay with its flips. */
#include "bench.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera bench mesh [options]\n\n"
               "Benchmarks tessera mesh's methods (delaunay, quadtree; grid as the baseline) over a ladder\n"
               "of error bounds\n"
               "(fractions of each input's height range) and prints a table: triangles, the measured\n"
               "max error, seconds (best of R) and peak heap memory; quadtree's triangles and time as\n"
               "ratios to delaunay's at the same bound; then delaunay without its data-dependent flips\n"
               "(--no-flip: plain greedy Delaunay insertion) and delaunay's triangles and time as ratios\n"
               "to that; then delaunay as one block on one thread (the window not cut into blocks,\n"
               "--block larger than the input) and delaunay's triangles and speed-up against that.\n\n"
               "inputs: the demo terrain (generated, 1025 x 1025, seed 1, 1200 m relief, dx 30) and every\n"
               "file of $TESSERA_DATA/terrain (default ../shared/data; skipped when absent).\n\n"
               "options:\n"
               "  --size S          also a generated S x S fractal terrain (e.g. 4097)\n"
               "  --errors LIST     bounds as fractions of the height range (default\n"
               "                    0.0005,0.001,0.002,0.01)\n"
               "  --input FILE      only this heightfield (heightfield options apply)\n"
               "  --repeat R        best of R runs (default 1)\n"
               "  --threads N       threads for delaunay's blocks (default: one per processor)\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help        this help\n");
}

typedef struct row {
    uint32_t triangles;
    double max_error, seconds, peak;
    bool ok;
} row;

static uint32_t bench_threads; /* --threads (0: one per processor) */

/* block: tsr_tin_options.block (UINT32_MAX: the window as one block, on
 * one thread) */
static row one(const tsr_heightfield *src, tsr_tin_method m, double e, bool no_flip, uint32_t block, uint32_t repeat)
{
    row r = {0};
    r.seconds = INFINITY;
    uint32_t w = tsr_heightfield_width(src), h = tsr_heightfield_height(src);
    for (uint32_t k = 0; k < repeat; k++) {
        bench_counting cnt = {0};
        tsr_allocator a = bench_counting_allocator(&cnt);
        tsr_heightfield *hf = tsr_heightfield_crop(src, 0, 0, w, h, &a);
        if (!hf)
            return r;
        tsr_mesh mesh;
        tsr_mesh_init(&mesh, 0, &a);
        tsr_tin_options o = {0};
        o.method = m;
        o.max_error = m == TSR_TIN_GRID ? 0 : e;
        o.no_flip = no_flip;
        o.block = block;
        o.threads = block == UINT32_MAX ? 1 : bench_threads;
        tsr_error err;
        double t0 = cli_now();
        tsr_status st = tsr_terrain_mesh(hf, &o, &mesh, NULL, &err);
        double secs = cli_now() - t0;
        if (st == TSR_OK) {
            tsr_error_report er;
            tsr_terrain_measure(hf, &mesh, NULL, &er);
            r.ok = true;
            r.triangles = mesh.triangle_count;
            r.max_error = er.max_vertical;
            r.seconds = fmin(r.seconds, secs);
            r.peak = (double)cnt.peak;
        } else
            fprintf(stderr, "tessera bench: %s\n", err.message);
        tsr_mesh_free(&mesh);
        tsr_heightfield_destroy(hf);
        if (st != TSR_OK)
            break;
    }
    return r;
}

static void bench_input(const char *name, const tsr_heightfield *hf, const double *fr, int nfr, uint32_t repeat)
{
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    double range = (st.max - st.min) * dz;
    row g = one(hf, TSR_TIN_GRID, 0, false, 0, repeat);
    printf("%-34s %9s | %10u %9.4g %8.3f %8.1f |  (grid: every sample; the baseline of the triangle counts)\n", name,
           "grid", g.triangles, g.max_error, g.seconds, g.peak / 1048576.0);
    for (int i = 0; i < nfr; i++) {
        double e = fr[i] * range;
        row d = one(hf, TSR_TIN_DELAUNAY, e, false, 0, repeat), q = one(hf, TSR_TIN_QUADTREE, e, false, 0, repeat);
        row p = one(hf, TSR_TIN_DELAUNAY, e, true, 0, repeat);
        row b = one(hf, TSR_TIN_DELAUNAY, e, false, UINT32_MAX, repeat);
        printf("%-34s %9.4g | %10u %9.4g %8.3f %8.1f | %10u %9.4g %8.3f %8.1f | %6.2fx %6.2fx | %10u %9.4g %8.3f | "
               "%6.2fx %6.2fx | %10u %8.3f %8.1f | %6.3fx %6.2fx\n",
               name, e, d.triangles, d.max_error, d.seconds, d.peak / 1048576.0, q.triangles, q.max_error, q.seconds,
               q.peak / 1048576.0, d.triangles ? (double)q.triangles / d.triangles : 0,
               q.seconds > 0 ? d.seconds / q.seconds : 0, p.triangles, p.max_error, p.seconds,
               p.triangles ? (double)d.triangles / p.triangles : 0, p.seconds > 0 ? d.seconds / p.seconds : 0,
               b.triangles, b.seconds, b.peak / 1048576.0, b.triangles ? (double)d.triangles / b.triangles : 0,
               d.seconds > 0 ? b.seconds / d.seconds : 0);
        fflush(stdout);
    }
}

int cli_bench_mesh(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    uint32_t size = 0, repeat = 1;
    const char *input = NULL;
    double fr[16] = {0.0005, 0.001, 0.002, 0.01};
    int nfr = 4;
    for (int i = 2; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        }
        int r = cli_heightfield_option("bench", argc, argv, &i, &o);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        bool has_value = i + 1 < argc;
        if (!strcmp(a, "--input") && has_value)
            input = argv[++i];
        else if ((!strcmp(a, "--size") || !strcmp(a, "--repeat") || !strcmp(a, "--threads")) && has_value) {
            uint32_t u;
            if (!cli_parse_u32(argv[++i], !strcmp(a, "--size") ? 2 : 1, 1u << 16, &u)) {
                cli_error("bench", "%s %s: must be a positive integer", a, argv[i]);
                return CLI_USAGE;
            }
            *(!strcmp(a, "--size") ? &size : !strcmp(a, "--repeat") ? &repeat : &bench_threads) = u;
        } else if (!strcmp(a, "--errors") && has_value) {
            const char *s = argv[++i];
            nfr = 0;
            while (*s && nfr < 16) {
                char *end;
                double v = strtod(s, &end);
                if (end == s || !(v > 0) || !isfinite(v) || (*end && *end != ',')) {
                    cli_error("bench", "--errors %s: give positive fractions separated by commas", argv[i]);
                    return CLI_USAGE;
                }
                fr[nfr++] = v;
                s = *end ? end + 1 : end;
            }
        } else {
            cli_error("bench", "%s '%s' (see tessera bench mesh --help)",
                      has_value ? "unknown option" : "missing value for", a);
            return CLI_USAGE;
        }
    }
    printf("tessera bench mesh: best of %u; bound = fraction x height range; max err = measured independently\n",
           repeat);
    printf("%-34s %9s | %10s %9s %8s %8s | %10s %9s %8s %8s | %7s %7s | %10s %9s %8s | %7s %7s | %10s %8s %8s | "
           "%7s %7s\n",
           "input", "bound", "delaunay", "max err", "seconds", "peak MB", "quadtree", "max err", "seconds", "peak MB",
           "q/d tri", "q speed", "no-flip", "max err", "seconds", "d/n tri", "d/n s", "one block", "seconds",
           "peak MB", "d/1 tri", "speedup");
    if (input) {
        tsr_heightfield *hf = cli_load_heightfield("bench", input, &o);
        if (!hf)
            return CLI_FAIL;
        bench_input(input, hf, fr, nfr, repeat);
        tsr_heightfield_destroy(hf);
        return CLI_OK;
    }
    /* the demo terrain */
    tsr_heightfield *hf = tsr_heightfield_create(1025, 1025, NULL);
    if (!hf) {
        cli_error("bench", "out of memory");
        return CLI_FAIL;
    }
    tsr_generate_options g = {0};
    g.seed = 1;
    g.relief = 1200;
    tsr_terrain_generate(hf, &g);
    tsr_heightfield_set_spacing(hf, 30, 30, 1);
    bench_input("demo terrain 1025x1025", hf, fr, nfr, repeat);
    tsr_heightfield_destroy(hf);
    /* the shared data */
    const char *data = getenv("TESSERA_DATA");
    if (!data || !*data)
        data = "../shared/data";
    static const struct {
        const char *file;
        bool rgb;
    } files[] = {{"bayhills-14-2625-6369-terrainrgb.png", true},
                 {"valid_raster-float32.tif", false},
                 {"egm84-epsg3857-float32.tif", false}};
    for (size_t i = 0; i < sizeof files / sizeof files[0]; i++) {
        char path[4096];
        snprintf(path, sizeof path, "%s/terrain/%s", data, files[i].file);
        tsr_load_options lo = {0};
        if (files[i].rgb)
            lo.decode = TSR_DECODE_TERRAIN_RGB;
        tsr_heightfield *f = NULL;
        tsr_error err;
        if (tsr_heightfield_load(path, &lo, NULL, &f, &err) != TSR_OK) {
            printf("%-34s skipped: %s\n", files[i].file, err.message);
            continue;
        }
        bench_input(files[i].file, f, fr, nfr, repeat);
        tsr_heightfield_destroy(f);
    }
    if (size) {
        tsr_heightfield *big = tsr_heightfield_create(size, size, NULL);
        if (!big) {
            cli_error("bench", "out of memory for a %ux%u terrain", size, size);
            return CLI_FAIL;
        }
        tsr_terrain_generate_fast(big, 1, 1200);
        char name[64];
        snprintf(name, sizeof name, "fractal %ux%u", size, size);
        bench_input(name, big, fr, nfr, repeat);
        tsr_heightfield_destroy(big);
    }
    return CLI_OK;
}
