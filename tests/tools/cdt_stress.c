/* cdt_stress.c: random planar straight-line graphs through tsr_triangulate
 * (Delaunay method), every result judged by tsr_triangulation_check; a
 * tool for hunting the constrained-Delaunay kernel's rounding bugs, not a
 * CTest test (tests/fuzz/known/README.md lists what it still finds).
 *
 *   build/bin/cdt_stress [FIRST [COUNT [--dump]]]   seeds FIRST.. (default 1, 1000);
 *   --dump prints a failing seed's graph and output
 *   CDT_STRESS_REFINE=1: also conforming / min-angle refinement
 *
 * Each seed makes 4-17 points whose coordinates mix four kinds (a small
 * integer grid, magnitudes from 1e-5 to 1e35, uniform in [0, 4), small
 * integers an ulp off or times 1e20), up to 3 points a few ulps off the
 * line through two others, and 1 to nv + 4 segments between random
 * points. A seed that takes more than 5 s is reported as a hang and the
 * run stops (exit 3). Prints one line per failure and a count. */
#include "tessellate/tessellate.h"
#include "tessellate/triangulate.h"

#include <math.h>
#include <signal.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static uint64_t state, cur_seed;
static double xy[2 * 64];
static uint32_t seg[2 * 64];
static int nv, ns;

static uint64_t rnd(void)
{
    state ^= state << 13;
    state ^= state >> 7;
    state ^= state << 17;
    return state;
}

static double ur(void)
{
    return (double)(rnd() >> 11) * 0x1p-53;
}

static double coord(int mode)
{
    switch (mode) {
    case 0:
        return floor(ur() * 16);
    case 1: {
        double m = pow(10, ur() * 40 - 5);
        return rnd() & 1 ? m : -m;
    }
    case 2:
        return ur() * 4;
    default: {
        double v = floor(ur() * 8);
        if (rnd() % 3 == 0)
            v = nextafter(v, rnd() & 1 ? INFINITY : -INFINITY);
        if (rnd() % 5 == 0)
            v *= 1e20;
        return v;
    }
    }
}

static void on_alarm(int sig)
{
    (void)sig;
    static const char msg[] = "cdt_stress: a seed ran past 5 s (a hang)\n";
    if (write(2, msg, sizeof msg - 1) < 0)
        _exit(4);
    _exit(3);
}

static void dump(void)
{
    printf("  nv %d ns %d\n", nv, ns);
    for (int i = 0; i < nv; i++)
        printf("  %.17g %.17g\n", xy[2 * i], xy[2 * i + 1]);
    for (int i = 0; i < ns; i++)
        printf("  s %u %u\n", seg[2 * i], seg[2 * i + 1]);
}

int main(int argc, char **argv)
{
    uint64_t first = argc > 1 ? strtoull(argv[1], NULL, 10) : 1, count = argc > 2 ? strtoull(argv[2], NULL, 10) : 1000;
    bool verbose = argc > 3, refine = getenv("CDT_STRESS_REFINE") != NULL;
    signal(SIGALRM, on_alarm);
    setvbuf(stdout, NULL, _IOLBF, 0);
    unsigned failures = 0;
    for (uint64_t seed = first; seed < first + count; seed++) {
        cur_seed = seed;
        state = seed * 0x9E3779B97F4A7C15ull + 1;
        for (int i = 0; i < 5; i++)
            rnd();
        nv = 4 + (int)(rnd() % 14);
        int mode = (int)(rnd() % 4);
        for (int i = 0; i < nv; i++) {
            int m = rnd() % 3 == 0 ? (int)(rnd() % 4) : mode;
            xy[2 * i] = coord(m);
            xy[2 * i + 1] = coord(m);
        }
        int nc = (int)(rnd() % 4);
        for (int c = 0; c < nc; c++) {
            int a = (int)(rnd() % (uint64_t)nv), b = (int)(rnd() % (uint64_t)nv);
            double t = ur(), x = xy[2 * a] + t * (xy[2 * b] - xy[2 * a]),
                   y = xy[2 * a + 1] + t * (xy[2 * b + 1] - xy[2 * a + 1]);
            for (int k = (int)(rnd() % 4); k-- > 0;) {
                if (rnd() & 1)
                    x = nextafter(x, rnd() & 1 ? INFINITY : -INFINITY);
                else
                    y = nextafter(y, rnd() & 1 ? INFINITY : -INFINITY);
            }
            xy[2 * nv] = x;
            xy[2 * nv + 1] = y;
            nv++;
        }
        ns = 1 + (int)(rnd() % (uint64_t)(nv + 4));
        for (int i = 0; i < ns; i++) {
            seg[2 * i] = (uint32_t)(rnd() % (uint64_t)nv);
            seg[2 * i + 1] = (uint32_t)(rnd() % (uint64_t)nv);
        }
        for (int i = 0; i < 2 * nv; i++) { /* where the exact predicates hold (predicates.h) */
            double a = fabs(xy[i]);
            if (a != 0 && (a < 0x1p-128 || a >= 0x1p250))
                xy[i] = 1;
        }
        tsr_pslg in = {xy, (uint32_t)nv, seg, (uint32_t)ns, NULL, 0};
        tsr_tri_options o;
        memset(&o, 0, sizeof o);
        o.max_steiner = 1000;
        int r = (int)(rnd() % 8);
        if (r == 0)
            o.region = TSR_REGION_EVEN_ODD;
        if (refine) {
            if (r & 1)
                o.conforming = true;
            else
                o.min_angle = 25;
            if (r == 2)
                o.region = TSR_REGION_ENCLOSED;
        }
        tsr_triangulation t;
        tsr_error err = {0};
        alarm(5);
        tsr_status st = tsr_triangulate(&in, &o, &t, NULL, &err);
        alarm(0);
        if (st != TSR_OK) {
            printf("seed %llu: refused: %s\n", (unsigned long long)seed, err.message);
            if (verbose)
                dump();
            failures++;
            continue;
        }
        if (t.steiner_limited || t.unrefined) {
            o.min_angle = o.max_area = 0;
            o.conforming = false;
        }
        tsr_tri_check c;
        if (tsr_triangulation_check(&in, &o, &t, &c) == TSR_OK && !c.ok && t.nt > 0) {
            printf("seed %llu: %s\n", (unsigned long long)seed, c.first_problem);
            if (verbose) {
                dump();
                printf("  output: %u vertices, %u triangles, %u constrained edges\n", t.nv, t.nt, t.nedge);
                for (uint32_t i = 0; i < t.nv; i++)
                    printf("  v%u %.17g %.17g\n", i, t.xy[2 * i], t.xy[2 * i + 1]);
                for (int i = 0; i < nv; i++)
                    printf("  input %d -> v%u\n", i, t.vertex_of_input[i]);
                for (uint32_t i = 0; i < t.nt; i++)
                    printf("  t %u %u %u\n", t.tri[3 * i], t.tri[3 * i + 1], t.tri[3 * i + 2]);
                for (uint32_t i = 0; i < t.nedge; i++)
                    printf("  e %u %u (segment %u)\n", t.edge[2 * i], t.edge[2 * i + 1], t.edge_segment[i]);
            }
            failures++;
        }
        tsr_triangulation_free(&t);
    }
    printf("cdt_stress: seeds %llu..%llu: %u failures\n", (unsigned long long)first,
           (unsigned long long)(first + count - 1), failures);
    return failures ? 1 : 0;
}
