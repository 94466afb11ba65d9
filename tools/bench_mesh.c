/* bench_mesh.c: `tessera bench mesh`: the heightmap meshers on the demo
 * terrain, on the real terrains of the shared data and optionally on a
 * large generated one, over a ladder of error bounds. For each method:
 * triangles, the measured max error (tsr_terrain_measure, independent of
 * the mesher), seconds (best of R) and peak heap bytes (a counting
 * allocator under the heightfield copy, the mesher and the mesh), with the
 * quadtree's triangles and speed as ratios against delaunay's in the same
 * run, and plain greedy Delaunay (no_flip) beside delaunay with its flips. */
#include "bench.h"

#include <cjson/cJSON.h>
#ifdef __GLIBC__
#include <malloc.h> /* malloc_trim */
#endif
#include <math.h>
#include <stdlib.h>
#include <string.h>

static void help(FILE *f)
{
    fprintf(f,
            "usage: tessera bench mesh [options]\n\n"
            "Benchmarks tessera mesh's methods (delaunay, quadtree; grid as the baseline) over a\n"
            "ladder of error bounds (fractions of each input's height range) and prints a table:\n"
            "triangles, the measured max error, seconds (best of R) and peak heap memory; quadtree's\n"
            "triangles and time as ratios to delaunay's at the same bound; then delaunay without its\n"
            "data-dependent flips (--no-flip: plain greedy Delaunay insertion) and delaunay's\n"
            "triangles and time as ratios to that; then delaunay as one block on one thread (the\n"
            "window not cut into blocks, --block larger than the input) and delaunay's triangles and\n"
            "speed-up against that. With --peers, other meshers instead (below).\n\n"
            "inputs: the demo terrain (generated, 1025 x 1025, seed 1, 1200 m relief, dx 30) and every\n"
            "file of $TESSERA_DATA/terrain (default ../shared/data, from the working folder; skipped when\n"
            "absent).\n\n"
            "options:\n"
            "  --size S          also a generated S x S fractal terrain (e.g. 4097)\n"
            "  --errors LIST     bounds as fractions of the height range (default\n"
            "                    0.0005,0.001,0.002,0.01)\n"
            "  --input FILE      only this heightfield (heightfield options apply)\n"
            "  --repeat R        best of R runs (default 1)\n"
            "  --threads N       threads for delaunay's blocks (default: one per processor this\n"
            "                    process may use, by its CPU affinity and cgroup CPU limit)\n"
            "  --peers           instead of the usual columns, other meshers on the same input, each\n"
            "                    mesh measured as ours: delatin (Garland-Heckbert greedy insertion, the\n"
            "                    JavaScript port of hmm) against delaunay at the same bound (delaunay\n"
            "                    also on one thread: the peers run on one), and martini (RTIN)\n"
            "                    against the quadtree: at the bound as its error parameter, and at the\n"
            "                    largest parameter whose measured max error is within the bound; on\n"
            "                    inputs that are not (2^k+1)^2 (martini's only size) also the largest\n"
            "                    such window. Needs node and the npm packages delatin and\n"
            "                    @mapbox/martini, which tools/install-deps.sh puts in build/node_modules\n"
            "                    ($TSR_NODE_MODULES overrides); the peers' seconds are their own timing\n"
            "                    of their mesher, in node, best of R; no-data inputs skip them\n"
            "  --json FILE       also write the rows as JSON\n" CLI_HEIGHTFIELD_HELP "  -h, --help        this help\n");
}

typedef struct row {
    uint32_t triangles;
    double max_error, seconds, peak;
    bool ok;
} row;

static uint32_t bench_threads; /* --threads (0: one per processor) */
static bool bench_peers;       /* --peers */
static cJSON *bench_json;      /* --json: the rows */

/* Adds a method's figures to a JSON row (rows that did not run are left out). */
static void json_method(cJSON *jrow, const char *key, uint32_t triangles, double max_error, double seconds,
                        double bytes, const char *bytes_key)
{
    cJSON *j = cJSON_AddObjectToObject(jrow, key);
    cJSON_AddNumberToObject(j, "triangles", triangles);
    cJSON_AddNumberToObject(j, "max_error", max_error);
    if (seconds > 0)
        cJSON_AddNumberToObject(j, "seconds", seconds);
    if (bytes_key && bytes > 0)
        cJSON_AddNumberToObject(j, bytes_key, bytes);
}

static cJSON *json_row(const char *name, double e)
{
    cJSON *j = cJSON_CreateObject();
    cJSON_AddItemToArray(bench_json, j);
    cJSON_AddStringToObject(j, "input", name);
    cJSON_AddNumberToObject(j, "bound", e);
    return j;
}

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
#ifdef __GLIBC__
        /* each run as in a fresh process: the heap's free pages go back to
         * the system, so the run faults its pages in as `tessera mesh`
         * does (else whether a repeat finds them mapped depends on what ran
         * before it) */
        malloc_trim(0);
#endif
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

/* One peer mesh at error e, measured; false (why filled) when it failed. */
static bool peer_row(bench_peer *p, const tsr_heightfield *hf, const char *method, double e, uint32_t repeat,
                     bench_peer_run *run, double *measured, char *why, size_t n)
{
    tsr_mesh mesh;
    tsr_mesh_init(&mesh, 0, NULL);
    bool ok = bench_peer_mesh(p, method, e, repeat, &mesh, run, why, n);
    if (ok) {
        tsr_error_report er;
        ok = tsr_terrain_measure(hf, &mesh, NULL, &er) == TSR_OK;
        *measured = er.max_vertical;
        if (!ok)
            snprintf(why, n, "out of memory measuring the peer's mesh");
    }
    tsr_mesh_free(&mesh);
    return ok;
}

/* --peers: delaunay against delatin (hmm's greedy insertion, ported) at
 * the same bound, and the quadtree against martini (RTIN): martini at
 * its error parameter = the bound, then at the largest parameter whose
 * measured max error is within the bound (found by halving, then
 * bisection in log scale, each mesh measured by tsr_terrain_measure).
 * false when the peers could not start (their columns are left empty). */
static bool bench_input_peers(const char *name, const tsr_heightfield *hf, const double *fr, int nfr, uint32_t repeat)
{
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    double range = (st.max - st.min) * dz;
    char why[512], hwhy[512] = "", mwhy[512] = "", said_h[512] = "", said_m[512] = "";
    bench_peer *p = bench_peer_start(hf, why, sizeof why);
    if (!p)
        printf("%-34s peers skipped: %s\n", name, why);
    for (int i = 0; i < nfr; i++) {
        double e = fr[i] * range;
        row d = one(hf, TSR_TIN_DELAUNAY, e, false, 0, repeat), q = one(hf, TSR_TIN_QUADTREE, e, false, 0, repeat);
        uint32_t keep = bench_threads;
        bench_threads = 1;
        row d1 = one(hf, TSR_TIN_DELAUNAY, e, false, 0, repeat);
        bench_threads = keep;
        printf("%-34s %9.4g | %10u %9.4g %8.3f %8.3f %8.1f", name, e, d.triangles, d.max_error, d.seconds, d1.seconds,
               d.peak / 1048576.0);
        bench_peer_run h = {0}, m = {0}, mt = {0};
        double hmax = 0, mmax = 0, best_max = 0, best_param = -1;
        bool hok = p && peer_row(p, hf, "delatin", e, repeat, &h, &hmax, hwhy, sizeof hwhy);
        if (hok)
            printf(" | %10u %9.4g %8.3f %8.1f | %6.3fx %6.3fx %6.3fx", h.triangles, hmax, h.seconds,
                   h.live_bytes / 1048576.0, h.triangles ? (double)d.triangles / h.triangles : 0,
                   h.seconds > 0 ? d.seconds / h.seconds : 0, h.seconds > 0 ? d1.seconds / h.seconds : 0);
        else
            printf(" | %10s %9s %8s %8s | %7s %7s %7s", "-", "-", "-", "-", "-", "-", "-");
        printf(" | %10u %9.4g %8.3f | %6.2fx", q.triangles, q.max_error, q.seconds,
               d.triangles ? (double)q.triangles / d.triangles : 0);
        /* martini: at the bound as its parameter, then the largest
         * parameter within the bound */
        bool mok = p && peer_row(p, hf, "martini", e, 0, &m, &mmax, mwhy, sizeof mwhy);
        if (mok) {
            double lo = e, hi = e, lo_max = mmax;
            bench_peer_run untimed; /* the search's meshes: only their measured error counts */
            while (mok && lo_max > e && lo > e / 4096) {
                hi = lo;
                lo *= 0.5;
                mok = peer_row(p, hf, "martini", lo, 0, &untimed, &lo_max, mwhy, sizeof mwhy);
            }
            for (int k = 0; mok && k < 8 && hi > lo; k++) {
                double mid = sqrt(lo * hi), mid_max = INFINITY;
                mok = peer_row(p, hf, "martini", mid, 0, &untimed, &mid_max, mwhy, sizeof mwhy);
                if (mid_max <= e) {
                    lo = mid;
                    lo_max = mid_max;
                } else
                    hi = mid;
            }
            if (mok && lo_max <= e) {
                best_param = lo;
                best_max = lo_max;
                mok = peer_row(p, hf, "martini", lo, repeat, &mt, &best_max, mwhy, sizeof mwhy);
            }
        }
        cJSON *jr = json_row(name, e);
        json_method(jr, "delaunay", d.triangles, d.max_error, d.seconds, d.peak, "peak_bytes");
        cJSON_AddNumberToObject(cJSON_GetObjectItem(jr, "delaunay"), "seconds_one_thread", d1.seconds);
        json_method(jr, "quadtree", q.triangles, q.max_error, q.seconds, q.peak, "peak_bytes");
        if (hok)
            json_method(jr, "delatin", h.triangles, hmax, h.seconds, h.live_bytes, "live_bytes");
        if (mok && best_param >= 0) {
            json_method(jr, "martini_at_bound", m.triangles, mmax, 0, 0, NULL);
            json_method(jr, "martini_within_bound", mt.triangles, best_max, mt.seconds, 0, NULL);
            cJSON_AddNumberToObject(cJSON_GetObjectItem(jr, "martini_within_bound"), "parameter", best_param);
            printf(" | %9.4g %6.2fx | %9.4g %10u %9.4g %8.3f | %6.2fx %6.2fx\n", mmax, e > 0 ? mmax / e : 0, best_param,
                   mt.triangles, best_max, mt.seconds, d.triangles ? (double)mt.triangles / d.triangles : 0,
                   mt.triangles ? (double)q.triangles / mt.triangles : 0);
        } else
            printf(" | %9s %7s | %9s %10s %9s %8s | %7s %7s\n", "-", "-", "-", "-", "-", "-", "-", "-");
        /* each reason once per input */
        if (p && !hok && strcmp(hwhy, said_h)) {
            printf("%-34s   delatin: %s\n", "", hwhy);
            snprintf(said_h, sizeof said_h, "%s", hwhy);
        }
        if (p && !mok && strcmp(mwhy, said_m)) {
            printf("%-34s   martini: %s\n", "", mwhy);
            snprintf(said_m, sizeof said_m, "%s", mwhy);
        }
        fflush(stdout);
    }
    bench_peer_stop(p);
    return p != NULL;
}

static void bench_input(const char *name, const tsr_heightfield *hf, const double *fr, int nfr, uint32_t repeat)
{
    if (bench_peers) {
        bool ran = bench_input_peers(name, hf, fr, nfr, repeat);
        /* martini takes (2^k + 1)^2 grids only: also the largest such
         * window at the input's first sample, every method on it (not
         * when the peers could not run, e.g. on no-data) */
        uint32_t w = tsr_heightfield_width(hf), h = tsr_heightfield_height(hf), side = 2;
        while (side * 2 + 1 <= w && side * 2 + 1 <= h)
            side *= 2;
        if (ran && (w != h || w != side + 1) && side >= 64) {
            tsr_heightfield *win = tsr_heightfield_crop(hf, 0, 0, side + 1, side + 1, NULL);
            if (win) {
                char wname[64];
                snprintf(wname, sizeof wname, "%.20s %ux%u window", name, side + 1, side + 1);
                bench_input_peers(wname, win, fr, nfr, repeat);
                tsr_heightfield_destroy(win);
            }
        }
        return;
    }
    tsr_heightfield_stats st;
    tsr_heightfield_stats_compute(hf, &st);
    double dx, dy, dz;
    tsr_heightfield_spacing(hf, &dx, &dy, &dz);
    double range = (st.max - st.min) * dz;
    row g = one(hf, TSR_TIN_GRID, 0, false, 0, repeat);
    printf("%-34s %9s | %10u %9.4g %8.3f %8.1f |  (grid: every sample; the baseline of the triangle counts)\n", name,
           "grid", g.triangles, g.max_error, g.seconds, g.peak / 1048576.0);
    json_method(json_row(name, 0), "grid", g.triangles, g.max_error, g.seconds, g.peak, "peak_bytes");
    for (int i = 0; i < nfr; i++) {
        double e = fr[i] * range;
        row d = one(hf, TSR_TIN_DELAUNAY, e, false, 0, repeat), q = one(hf, TSR_TIN_QUADTREE, e, false, 0, repeat);
        row p = one(hf, TSR_TIN_DELAUNAY, e, true, 0, repeat);
        row b = one(hf, TSR_TIN_DELAUNAY, e, false, UINT32_MAX, repeat);
        cJSON *jr = json_row(name, e);
        json_method(jr, "delaunay", d.triangles, d.max_error, d.seconds, d.peak, "peak_bytes");
        json_method(jr, "quadtree", q.triangles, q.max_error, q.seconds, q.peak, "peak_bytes");
        json_method(jr, "no_flip", p.triangles, p.max_error, p.seconds, p.peak, "peak_bytes");
        json_method(jr, "one_block", b.triangles, b.max_error, b.seconds, b.peak, "peak_bytes");
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

static int run_inputs(const char *input, const cli_heightfield_options *o, uint32_t size, const double *fr, int nfr,
                      uint32_t repeat);

int cli_bench_mesh(int argc, char **argv)
{
    cli_heightfield_options o = {0};
    uint32_t size = 0, repeat = 1;
    const char *input = NULL, *json_path = NULL;
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
        if (!strcmp(a, "--peers"))
            bench_peers = true;
        else if (!strcmp(a, "--input") && has_value)
            input = argv[++i];
        else if (!strcmp(a, "--json") && has_value)
            json_path = argv[++i];
        else if ((!strcmp(a, "--size") || !strcmp(a, "--repeat") || !strcmp(a, "--threads")) && has_value) {
            uint32_t u;
            if (!cli_parse_u32(argv[++i], !strcmp(a, "--size") ? 2 : 1, 1u << 16, &u)) {
                cli_error("bench", "%s %s: must be a whole number from %u to %u", a, argv[i], !strcmp(a, "--size") ? 2 : 1,
                          1u << 16);
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
            cli_option_error("bench", "mesh", a, help);
            return CLI_USAGE;
        }
    }
    if (!cli_outputs_writable("bench mesh", 1, &json_path)) /* before the runs, not after them */
        return CLI_FAIL;
    bench_json = cJSON_CreateArray();
    if (!bench_json) {
        cli_error("bench", "out of memory");
        return CLI_FAIL;
    }
    int rc = run_inputs(input, &o, size, fr, nfr, repeat);
    if (rc == CLI_OK && json_path) {
        cJSON *top = cJSON_CreateObject();
        char *txt = NULL;
        if (top) {
            cJSON_AddNumberToObject(top, "repeat", repeat);
            cJSON_AddBoolToObject(top, "peers", bench_peers);
            cJSON_AddItemToObject(top, "rows", bench_json);
            bench_json = NULL;
            txt = cJSON_Print(top);
        }
        tsr_error err = {0};
        if (!txt || cli_write_text(json_path, txt, &err) != TSR_OK) {
            cli_error("bench", "mesh: %s", txt ? err.message : "out of memory");
            rc = CLI_FAIL;
        }
        free(txt);
        cJSON_Delete(top);
    }
    cJSON_Delete(bench_json);
    bench_json = NULL;
    return rc;
}

/* Every input of the run, with the table's header first. */
static int run_inputs(const char *input, const cli_heightfield_options *o, uint32_t size, const double *fr, int nfr,
                      uint32_t repeat)
{
    printf("tessera bench mesh: best of %u; bound = fraction x height range; max err = measured independently\n",
           repeat);
    if (bench_peers)
        printf("%-34s %9s | %10s %9s %8s %8s %8s | %10s %9s %8s %8s | %7s %7s %7s | %10s %9s %8s | %7s | %9s %7s | "
               "%9s %10s %9s %8s | %7s %7s\n",
               "input", "bound", "delaunay", "max err", "seconds", "1 thread", "peak MB", "delatin", "max err",
               "seconds", "live MB", "d/h tri", "d/h s", "d1/h s", "quadtree", "max err", "seconds", "q/d tri",
               "martini@b", "/bound", "m param", "martini", "max err", "seconds", "m/d tri", "q/m tri");
    else
        printf("%-34s %9s | %10s %9s %8s %8s | %10s %9s %8s %8s | %7s %7s | %10s %9s %8s | %7s %7s | %10s %8s %8s | "
           "%7s %7s\n",
           "input", "bound", "delaunay", "max err", "seconds", "peak MB", "quadtree", "max err", "seconds", "peak MB",
           "q/d tri", "q speed", "no-flip", "max err", "seconds", "d/n tri", "d/n s", "one block", "seconds",
           "peak MB", "d/1 tri", "speedup");
    if (input) {
        tsr_heightfield *hf = cli_load_heightfield("bench", input, o);
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
    const char *data = bench_data_dir("bench mesh");
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
