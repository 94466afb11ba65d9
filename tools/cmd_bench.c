/* cmd_bench.c: `tessera bench terrain`: pyramid build against a memcpy of
 * the same bytes in the same run, selection per frame over a flight, tiles
 * and triangles per frame, tile vertex generation rate, and memory beyond
 * the heightfield. Prints a table; figures are ratios against baselines
 * measured in the same run where that makes sense. */
#include "bench.h"
#include "camera.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f, "usage: tessera bench terrain [options]\n"
               "       tessera bench cdt [--points N] [--grid S] [--polygon V]   (Delaunay kernel; see tessera bench\n"
               "                     cdt --help)\n"
               "       tessera bench mesh [options]   (heightmap to mesh; see tessera bench mesh --help)\n"
               "       tessera bench fly [options]    (the flyover's frame times; see tessera bench fly --help)\n"
               "       tessera bench patch [options]  (patch tessellation against OpenSubdiv; see tessera bench patch "
               "--help)\n\n"
               "bench terrain benchmarks terrain level of detail on a generated heightfield (fast midpoint\n"
               "displacement; by default 16385 x 16385 samples, 1 GiB) or on a file, and prints a table.\n\n"
               "options:\n"
               "  --size S          generated heightfield of S x S samples (default 16385)\n"
               "  --input FILE      benchmark this heightfield instead (heightfield options apply)\n"
               "  --tile N          tile size: 2, 4, ..., 128 (default 16)\n"
               "  --frames F        frames of the flight (default 1000)\n"
               "  --pixel-error T   screen-space error, pixels (default 1)\n"
               "  --repeat R        best of R runs for the timed builds (default 3)\n" CLI_HEIGHTFIELD_HELP
               "  -h, --help        this help\n");
}

static void random_points(double *xy, uint32_t m, uint64_t s)
{
    for (uint32_t i = 0; i < 2 * m; i++) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        xy[i] = (double)(s >> 11) * (1.0 / 9007199254740992.0);
    }
}

/* A star-shaped polygon of n vertices (a smooth wavy outline with a
 * little noise) with `holes` small square holes
 * (rings, even-odd), for the constrained rows. */
static void star_polygon(uint32_t n, uint32_t holes, double **xy_out, uint32_t **seg_out, uint32_t *nv, uint32_t *ns)
{
    uint32_t m = n + 4 * holes;
    double *xy = malloc(2 * (size_t)m * sizeof *xy);
    uint32_t *seg = malloc(2 * (size_t)m * sizeof *seg);
    uint64_t s = 99;
    for (uint32_t i = 0; i < n; i++) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        double a = 6.283185307179586 * i / n,
               r = 0.85 + 0.1 * sin(7 * a) + 0.01 * ((double)(s >> 11) * (1.0 / 9007199254740992.0)) / n * 1000;
        xy[2 * i] = r * cos(a);
        xy[2 * i + 1] = r * sin(a);
        seg[2 * i] = i;
        seg[2 * i + 1] = (i + 1) % n;
    }
    uint32_t side = 1;
    while (side * side < holes)
        side++;
    for (uint32_t h = 0; h < holes; h++) {
        double cx = -0.5 + (h % side + 0.5) / side, cy = -0.5 + (h / side + 0.5) / side, r = 0.25 / side;
        double c[8] = {cx - r, cy - r, cx + r, cy - r, cx + r, cy + r, cx - r, cy + r};
        uint32_t base = n + 4 * h;
        for (int k = 0; k < 4; k++) {
            xy[2 * (base + k)] = c[2 * k];
            xy[2 * (base + k) + 1] = c[2 * k + 1];
            seg[2 * (base + k)] = base + k;
            seg[2 * (base + k) + 1] = base + (k + 1) % 4;
        }
    }
    *xy_out = xy;
    *seg_out = seg;
    *nv = *ns = m;
}

/* `tessera bench cdt`: the Delaunay kernel on uniform random points and
 * on an integer grid, with peak memory per point from a counting
 * allocator, and the constrained triangulator's two methods side by side.
 * The peers' figures from the issue, measured on these machines: CGAL
 * 0.8 s and Triangle 1.25 s for 1M uniform points; Triangle 1.05 s for the
 * 1000 x 1000 grid. A qsort of the same points, timed in the same run,
 * is the baseline that makes figures from different machines comparable. */
static void help_cdt(FILE *f)
{
    fprintf(f, "usage: tessera bench cdt [--points N] [--grid S] [--polygon V]\n\n"
               "Times Delaunay triangulation of N uniform random points and of an S x S integer grid,\n"
               "with peak memory per point; then triangulates a polygon of V vertices with 100 square\n"
               "holes (V + 400 points) by\n"
               "both methods (delaunay and quadtree), plain and with a maximum area, each the best of 3\n"
               "runs alternating with the other method, and prints the ratio of their times. A qsort of\n"
               "the points is timed in the same run as a baseline.\n\n"
               "options:\n"
               "  --points N        uniform random points (default 1000000)\n"
               "  --grid S          grid of S x S points (default 1000)\n"
               "  --polygon V       polygon vertices (default 20000)\n"
               "  -h, --help        this help\n");
}

static int run_cdt(int argc, char **argv)
{
    uint32_t n = 1000000, side = 1000, poly = 20000;
    for (int i = 2; i < argc; i++) {
        if (cli_is_help(argv[i])) {
            help_cdt(stdout);
            return CLI_OK;
        }
        uint32_t *dst = !strcmp(argv[i], "--points")    ? &n
                        : !strcmp(argv[i], "--grid")    ? &side
                        : !strcmp(argv[i], "--polygon") ? &poly
                                                        : NULL;
        if (!dst || i + 1 >= argc) {
            cli_option_error("bench", "cdt", argv[i], help_cdt);
            return CLI_USAGE;
        }
        if (!cli_parse_u32(argv[i + 1], 3, 1u << 26, dst)) {
            cli_error("bench", "cdt: %s %s: give a whole number from 3 to %u", argv[i], argv[i + 1], 1u << 26);
            return CLI_USAGE;
        }
        i++;
    }
    printf("tessera bench cdt\n\n| input | points | triangles | seconds | x qsort | peak bytes/point |\n"
           "|---|---|---|---|---|---|\n");
    for (int kind = 0; kind < 2; kind++) {
        uint32_t m = kind == 0 ? n : side * side;
        double *xy = malloc(2 * (size_t)m * sizeof *xy);
        if (!xy) {
            cli_error("bench", "out of memory");
            return CLI_FAIL;
        }
        if (kind == 0)
            random_points(xy, m, 1);
        else
            for (uint32_t i = 0; i < m; i++) {
                xy[2 * i] = i % side;
                xy[2 * i + 1] = i / side;
            }
        double *copy = malloc(2 * (size_t)m * sizeof *copy);
        double q0 = cli_now();
        if (copy) {
            memcpy(copy, xy, 2 * (size_t)m * sizeof *copy);
            qsort(copy, m, 2 * sizeof *copy, bench_cmp_double); /* by x: the first double of each point */
        }
        double qsecs = cli_now() - q0;
        free(copy);
        bench_counting c = {0, 0};
        tsr_allocator alloc = bench_counting_allocator(&c);
        double t0 = cli_now();
        tsr_cdt *d = tsr_cdt_create(&alloc);
        tsr_status st = d ? tsr_cdt_insert_points(d, xy, m, NULL) : TSR_ERR_NOMEM;
        double secs = cli_now() - t0;
        if (st == TSR_OK)
            printf("| %s | %u | %u | %.3f | %.1f | %.0f |\n", kind == 0 ? "uniform random" : "integer grid", m,
                   tsr_cdt_triangle_count(d), secs, secs / qsecs, (double)c.peak / m);
        tsr_cdt_destroy(d);
        free(xy);
        if (st != TSR_OK) {
            cli_error("bench", "cdt: %s", tsr_status_str(st));
            return CLI_FAIL;
        }
    }
    /* the constrained triangulator, both methods */
    double *pxy;
    uint32_t *pseg, pnv, pns;
    star_polygon(poly, 100, &pxy, &pseg, &pnv, &pns);
    if (!pxy || !pseg) {
        cli_error("bench", "out of memory");
        return CLI_FAIL;
    }
    tsr_pslg in = {pxy, pnv, pseg, pns, NULL, 0};
    /* both methods on the same input in the same run, alternating, each
     * the best of POLY_RUNS, and the first runs apart (they pay for
     * first-touch page faults, more so the method that uses more memory) */
    enum { POLY_RUNS = 3 };
    printf("\n| polygon, %u vertices, 100 holes | method | triangles | seconds, best of %d | first run | fallback | "
           "delaunay / quadtree: best (first) |\n|---|---|---|---|---|---|---|\n",
           pnv, POLY_RUNS);
    double areas[2] = {0, 3.0 / pnv};
    for (int ai = 0; ai < 2; ai++) {
        double secs[2] = {INFINITY, INFINITY}, first[2] = {0, 0};
        uint32_t nt[2] = {0, 0};
        char fb[48] = "";
        for (int run = 0; run < POLY_RUNS; run++)
            for (int m = 0; m < 2; m++) {
                tsr_tri_options o = {.method = m ? TSR_TRI_QUADTREE : TSR_TRI_DELAUNAY,
                                     .region = TSR_REGION_EVEN_ODD,
                                     .max_area = areas[ai]};
                tsr_triangulation t;
                tsr_error err;
                double t0 = cli_now();
                tsr_status st = tsr_triangulate(&in, &o, &t, NULL, &err);
                double dt = cli_now() - t0;
                if (st != TSR_OK) {
                    cli_error("bench", "cdt: %s", err.message);
                    free(pxy);
                    free(pseg);
                    return CLI_FAIL;
                }
                secs[m] = dt < secs[m] ? dt : secs[m];
                if (run == 0)
                    first[m] = dt;
                nt[m] = t.nt;
                if (m == 1)
                    snprintf(fb, sizeof fb, "%s%u cells%s%s", t.fell_back ? "whole input; " : "", t.fallback_cells,
                             t.fallback_reason ? ": " : "", t.fell_back && t.fallback_reason ? t.fallback_reason : "");
                tsr_triangulation_free(&t);
            }
        const char *what = ai ? "max area 3/V" : "plain";
        printf("| %s | delaunay | %u | %.3f | %.3f |  |  |\n", what, nt[0], secs[0], first[0]);
        printf("| %s | quadtree | %u | %.3f | %.3f | %s | %.2f (%.2f) |\n", what, nt[1], secs[1], first[1], fb,
               secs[0] / secs[1], first[0] / first[1]);
    }
    free(pxy);
    free(pseg);
    return CLI_OK;
}

static int run(int argc, char **argv)
{
    if (argc >= 2 && !strcmp(argv[1], "cdt"))
        return run_cdt(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "mesh"))
        return cli_bench_mesh(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "fly"))
        return cli_bench_fly(argc, argv);
    if (argc >= 2 && !strcmp(argv[1], "patch"))
        return cli_bench_patch(argc, argv);
    if (argc < 2 || (strcmp(argv[1], "terrain") && !cli_is_help(argv[1]))) {
        cli_error("bench",
                  "what to benchmark? 'tessera bench terrain', 'cdt', 'mesh', 'fly' or 'patch' (see tessera bench "
                  "--help)");
        return CLI_USAGE;
    }
    cli_heightfield_options o = {0};
    uint32_t size = 16385, tile = 16, frames = 1000, repeat = 3;
    double tau = 1;
    const char *input = NULL;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (cli_is_help(a)) {
            help(stdout);
            return CLI_OK;
        }
        if (i == 1)
            continue;
        int r = cli_heightfield_option("bench", argc, argv, &i, &o);
        if (r < 0)
            return CLI_USAGE;
        if (r > 0)
            continue;
        bool has_value = i + 1 < argc;
        uint32_t u;
        if (!strcmp(a, "--input") && has_value)
            input = argv[++i];
        else if ((!strcmp(a, "--size") || !strcmp(a, "--tile") || !strcmp(a, "--frames") || !strcmp(a, "--repeat")) &&
                 has_value) {
            if (!cli_parse_u32(argv[++i], !strcmp(a, "--size") ? 2 : 1, 1u << 20, &u)) {
                cli_error("bench", "%s wants a whole number from %d to 1048576, not '%s'", a,
                          !strcmp(a, "--size") ? 2 : 1, argv[i]);
                return CLI_USAGE;
            }
            *(!strcmp(a, "--size")     ? &size
              : !strcmp(a, "--tile")   ? &tile
              : !strcmp(a, "--frames") ? &frames
                                       : &repeat) = u;
        } else if (!strcmp(a, "--pixel-error") && has_value) {
            if (!cli_parse_double(argv[++i], &tau) || !(tau > 0)) {
                cli_error("bench", "--pixel-error %s: must be positive", argv[i]);
                return CLI_USAGE;
            }
        } else {
            cli_option_error("bench", "terrain", a, help);
            return CLI_USAGE;
        }
    }
    if (!cli_tile_size_ok(tile)) { /* before generating, not after */
        cli_error("bench", "terrain: --tile %u: must be a power of two from %u to %u", tile, TSR_TILE_MIN, TSR_TILE_MAX);
        return CLI_USAGE;
    }
    double t0 = cli_now();
    tsr_heightfield *hf;
    if (input) {
        hf = cli_load_heightfield("bench", input, &o);
        if (!hf)
            return CLI_FAIL;
    } else {
        hf = tsr_heightfield_create(size, size, NULL);
        if (!hf) {
            cli_error("bench", "out of memory for %ux%u samples", size, size);
            return CLI_FAIL;
        }
        fprintf(stderr, "tessera bench: generating %ux%u heightfield...\n", size, size);
        tsr_terrain_generate_fast(hf, 1, 1000);
        tsr_heightfield_set_spacing(hf, o.dx > 0 ? o.dx : 10, o.dy > 0 ? o.dy : (o.dx > 0 ? o.dx : 10),
                                    o.dz > 0 ? o.dz : 1);
    }
    double gen_s = cli_now() - t0;
    uint32_t W = tsr_heightfield_width(hf), Hh = tsr_heightfield_height(hf);
    size_t bytes = (size_t)W * Hh * sizeof(float);

    /* baseline: memcpy of the same bytes into touched memory, best of R */
    float *copy = malloc(bytes);
    if (!copy) {
        cli_error("bench", "out of memory for the memcpy baseline");
        tsr_heightfield_destroy(hf);
        return CLI_FAIL;
    }
    memset(copy, 0, bytes);
    double memcpy_s = INFINITY;
    for (uint32_t r = 0; r < repeat; r++) {
        double a = cli_now();
        memcpy(copy, tsr_heightfield_cdata(hf), bytes);
        __asm__ volatile("" : : "r"(copy) : "memory"); /* keep the copy */
        double e = cli_now() - a;
        memcpy_s = e < memcpy_s ? e : memcpy_s;
    }
    free(copy);
    /* the same copy into freshly allocated memory (through the library's
     * allocator, as the pyramid's arrays are): first-touch page faults
     * included, which on virtual machines can cost more than the copy */
    double fresh_s = INFINITY;
    for (uint32_t r = 0; r < repeat; r++) {
        double a = cli_now();
        float *f = tsr_alloc(NULL, bytes);
        if (!f)
            break;
        memcpy(f, tsr_heightfield_cdata(hf), bytes);
        __asm__ volatile("" : : "r"(f) : "memory");
        double e = cli_now() - a;
        tsr_free(NULL, f);
        fresh_s = e < fresh_s ? e : fresh_s;
    }

    tsr_terrain *t = NULL;
    tsr_terrain_options to = {tile};
    tsr_error err = {0};
    double build_s = INFINITY;
    for (uint32_t r = 0; r < repeat; r++) {
        tsr_terrain_destroy(t);
        t = NULL;
        double a = cli_now();
        if (tsr_terrain_create(hf, &to, NULL, &t, &err) != TSR_OK) {
            cli_error("bench", "%s", err.message);
            tsr_heightfield_destroy(hf);
            return CLI_FAIL;
        }
        double e = cli_now() - a;
        build_s = e < build_s ? e : build_s;
    }
    const tsr_surface *s = tsr_terrain_surface(t);
    tsr_quadtree *qt = tsr_quadtree_create(s, NULL);
    view_options v = {60, 1920, 1080, 1, tau};
    double *sel = malloc(frames * sizeof *sel), *tiles = malloc(frames * sizeof *tiles),
           *tris = malloc(frames * sizeof *tris);
    tsr_tile_patterns pat;
    tsr_tile_patterns_init(&pat, tile, NULL);
    uint64_t verts = 0;
    double vert_s = 0;
    float *vbuf = malloc((size_t)(tile + 1) * (tile + 1) * 3 * sizeof(float));
    for (uint32_t f = 0; f < frames; f++) {
        tsr_camera cam;
        flight_camera(t, (int)f, (int)frames, &v, &cam);
        double a = cli_now();
        tsr_quadtree_select(qt, tsr_refine_camera, &cam);
        sel[f] = (cli_now() - a) * 1e3;
        tsr_quadtree_apply_camera(qt, &cam);
        uint32_t nl = tsr_quadtree_leaf_count(qt), drawn = 0;
        double ntri = 0;
        const tsr_qleaf *L = tsr_quadtree_leaves(qt);
        for (uint32_t i = 0; i < nl; i++)
            if (!L[i].culled) {
                drawn++;
                ntri += pat.count[L[i].stitch & 15];
            }
        tiles[f] = drawn;
        tris[f] = ntri;
        /* tile vertex generation: positions of every drawn tile, every 10th frame */
        if (f % 10 == 0) {
            double b = cli_now();
            for (uint32_t i = 0; i < nl; i++) {
                if (L[i].culled)
                    continue;
                uint64_t w = (uint64_t)tile << (s->levels - L[i].node.level), st = w / tile;
                for (uint32_t j = 0, k = 0; j <= tile; j++)
                    for (uint32_t ii = 0; ii <= tile; ii++, k++) {
                        uint64_t gi = L[i].node.x * w + ii * st, gj = L[i].node.y * w + j * st;
                        gi = gi > s->extent_x ? s->extent_x : gi;
                        gj = gj > s->extent_y ? s->extent_y : gj;
                        s->evaluate(s->user, (uint32_t)gi, (uint32_t)gj, vbuf + 3 * k, NULL);
                    }
                verts += (uint64_t)(tile + 1) * (tile + 1);
            }
            vert_s += cli_now() - b;
        }
    }
    qsort(sel, frames, sizeof *sel, bench_cmp_double);
    qsort(tiles, frames, sizeof *tiles, bench_cmp_double);
    qsort(tris, frames, sizeof *tris, bench_cmp_double);
    double extra = (double)tsr_terrain_extra_bytes(t);
    printf("tessera bench terrain: %ux%u samples (%.2f GiB float32), tile %u, levels %u, 1920x1080, 60 deg, tau %g px, "
           "%u-frame flight\n\n",
           W, Hh, bytes / 1073741824.0, tile, s->levels, tau, frames);
    printf("| measure | value | ratio / target |\n|---|---|---|\n");
    printf("| heightfield %s | %.2f s | |\n", input ? "load" : "generation", gen_s);
    printf("| memcpy of the heightfield (baseline, best of %u) | %.3f s | 1.00 |\n", repeat, memcpy_s);
    printf("| memcpy into fresh memory (page faults included, best of %u) | %.3f s | %.2f |\n", repeat, fresh_s,
           fresh_s / memcpy_s);
    printf("| pyramid build (best of %u) | %.3f s | %.2fx memcpy (target <= 3x); %.2fx fresh memcpy |\n", repeat,
           build_s, build_s / memcpy_s, build_s / fresh_s);
    printf("| selection per frame, median | %.4f ms | target <= 0.1 ms |\n", sel[frames / 2]);
    printf("| selection per frame, 95th percentile | %.4f ms | |\n", sel[(size_t)(frames * 0.95)]);
    printf("| tiles drawn per frame, median | %.0f | |\n", tiles[frames / 2]);
    printf("| triangles drawn per frame, median | %.0f | |\n", tris[frames / 2]);
    printf("| tile vertex generation | %.1f M vertices/s | |\n", vert_s > 0 ? verts / vert_s / 1e6 : 0);
    printf("| memory beyond the heightfield | %.1f MiB | %.2fx heightfield (target <= 1x) |\n", extra / 1048576.0,
           extra / bytes);
    free(vbuf);
    free(sel);
    free(tiles);
    free(tris);
    tsr_tile_patterns_free(&pat);
    tsr_quadtree_destroy(qt);
    tsr_terrain_destroy(t);
    tsr_heightfield_destroy(hf);
    return CLI_OK;
}

const cli_command cli_cmd_bench = {
    "bench", "benchmarks: 'bench terrain', 'bench cdt', 'bench mesh', 'bench fly', 'bench patch'", run, help};
