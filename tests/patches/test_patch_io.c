/* The patch loaders (patch_io.c): .bpt files, OBJ free-form surfaces with
 * trim loops, polygon OBJ cages with OpenSubdiv tags. Real files are
 * checked against a second, naive reader written here; a free-form file
 * written by the test against the closed forms it encodes; and a
 * catalogue of bad files, each against the line it should name. */
#define _POSIX_C_SOURCE 200809L
#include "check.h"
#include "patches/patches.h"

#include <dirent.h>
#include <unistd.h>

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static double len3(const double a[3])
{
    return sqrt(dot3(a, a));
}

static const char *write_temp(const char *dir, const char *name, const char *text)
{
    static char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f)
        return NULL;
    fwrite(text, 1, strlen(text), f);
    fclose(f);
    return path;
}

/* ---- .bpt -------------------------------------------------------------------- */

static const char *teapot_path(char *buf, size_t cap)
{
    const char *data = check_data_dir();
    if (!data)
        return NULL;
    snprintf(buf, cap, "%s/patches/teapot.bpt", data);
    FILE *f = fopen(buf, "rb");
    if (!f)
        return NULL;
    fclose(f);
    return buf;
}

TEST(data_teapot_loads)
{
    char path[5000];
    if (!teapot_path(path, sizeof path))
        SKIP("no shared data folder with patches/teapot.bpt (set TESSERA_DATA)");
    check_alloc c = {0};
    tsr_allocator al = {check_realloc, &c, NULL};
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_load(path, TSR_PATCH_FORMAT_UNKNOWN, &al, &s, &e) == TSR_OK, "%s", e.message);
    CHECK(s.num_patches == 32); /* the data README */
    CHECK(s.num_loops == 0 && s.first_loop != NULL);
    /* a second reader: fscanf, straight through */
    FILE *f = fopen(path, "r");
    int n = 0;
    CHECK(f && fscanf(f, "%d", &n) == 1 && n == 32);
    for (uint32_t i = 0; f && i < s.num_patches && i < (uint32_t)n; i++) {
        const tsr_patch *p = &s.patches[i];
        int du = 0, dv = 0;
        CHECK(fscanf(f, "%d %d", &du, &dv) == 2);
        CHECK(p->kind == TSR_PATCH_BEZIER && p->degree_u == du && p->degree_v == dv);
        CHECK(p->count_u == (uint32_t)du + 1 && p->count_v == (uint32_t)dv + 1 && p->weights == NULL);
        CHECK(tsr_patch_check(p, NULL) == TSR_OK);
        for (int k = 0; k < 3 * (du + 1) * (dv + 1); k++) {
            double x = 0;
            CHECK(fscanf(f, "%lf", &x) == 1);
            CHECK(p->ctrl[k] == x);
        }
    }
    if (f)
        fclose(f);
    tsr_patch_set_free(&s);
    CHECK_MSG(c.live == 0, "%ld blocks leaked", c.live);
}

/* Rows or columns of a net whose points coincide: collapsed edges. */
static int collapsed_edge(const tsr_patch *p, int edge)
{
    /* edge 0: v = v0 (row 0), 1: u = u1, 2: v = v1, 3: u = u0 */
    uint32_t n = edge % 2 ? p->count_v : p->count_u;
    const double *first = NULL;
    for (uint32_t k = 0; k < n; k++) {
        uint32_t i = edge == 0 || edge == 2 ? k : edge == 1 ? p->count_u - 1 : 0;
        uint32_t j = edge == 1 || edge == 3 ? k : edge == 2 ? p->count_v - 1 : 0;
        const double *q = p->ctrl + 3 * (j * p->count_u + i);
        if (first && (q[0] != first[0] || q[1] != first[1] || q[2] != first[2]))
            return 0;
        first = q;
    }
    return 1;
}

TEST(data_teapot_degenerate_normals)
{
    char path[5000];
    if (!teapot_path(path, sizeof path))
        SKIP("no shared data folder with patches/teapot.bpt (set TESSERA_DATA)");
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_load(path, TSR_PATCH_FORMAT_BPT, NULL, &s, &e) == TSR_OK, "%s", e.message);
    int edges = 0;
    for (uint32_t i = 0; i < s.num_patches; i++) {
        const tsr_patch *p = &s.patches[i];
        for (int edge = 0; edge < 4; edge++) {
            if (!collapsed_edge(p, edge))
                continue;
            edges++;
            for (int k = 0; k <= 8; k++) {
                double t = k / 8.0;
                double u = edge == 1 ? 1 : edge == 3 ? 0 : t, v = edge == 0 ? 0 : edge == 2 ? 1 : t;
                double n[3], m[3], pos[3], du[3], dv[3];
                CHECK(tsr_patch_eval(p, u, v, pos, du, dv, n) == TSR_OK);
                CHECK(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]));
                CHECK_NEAR(len3(n), 1.0, 1e-12);
                /* a tiny step inside, perpendicular to the edge */
                double h = 1e-6;
                double ui = edge == 1 ? 1 - h : edge == 3 ? h : u, vi = edge == 0 ? h : edge == 2 ? 1 - h : v;
                CHECK(tsr_patch_eval(p, ui, vi, pos, NULL, NULL, m) == TSR_OK);
                CHECK_MSG(dot3(n, m) > 1 - 1e-8, "patch %u edge %d t %g: n (%g %g %g), inside (%g %g %g)", i, edge, t,
                          n[0], n[1], n[2], m[0], m[1], m[2]);
                /* the teapot's collapsed edges are the lid's top and the
                 * bottom, on the z axis, with a horizontal tangent plane */
                CHECK_NEAR(fabs(n[2]), 1.0, 1e-9);
            }
        }
    }
    CHECK_MSG(edges >= 8, "only %d collapsed edges found", edges); /* 4 lid patches, 4 bottom patches */
    tsr_patch_set_free(&s);
}

TEST(bpt_small_and_memory_parse)
{
    const char *text = "2\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 1\n"
                       "2 1 # a comment\n0 0 0\n1 0 0\n2 0 0\n\n0 1 0\n1 1 0\n2 1 0.5\n";
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_parse(text, strlen(text), "small.bpt", TSR_PATCH_FORMAT_BPT, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    CHECK(s.num_patches == 2);
    CHECK(s.patches[1].degree_u == 2 && s.patches[1].degree_v == 1 && s.patches[1].count_u == 3);
    double pos[3];
    CHECK(tsr_patch_eval(&s.patches[0], 1, 1, pos, NULL, NULL, NULL) == TSR_OK);
    CHECK(pos[0] == 1 && pos[1] == 1 && pos[2] == 1);
    CHECK(tsr_patch_eval(&s.patches[1], 1, 1, pos, NULL, NULL, NULL) == TSR_OK);
    CHECK(pos[0] == 2 && pos[1] == 1 && pos[2] == 0.5);
    tsr_patch_set_free(&s);
    tsr_patch_set_free(&s); /* zeroed: a second free is harmless */
    /* a UTF-8 byte order mark before the first line is skipped, in every
     * reader, and lines are still counted from 1 */
    char bom[256];
    snprintf(bom, sizeof bom, "\xEF\xBB\xBF%s", text);
    CHECK_MSG(tsr_patch_set_parse(bom, strlen(bom), "bom.bpt", TSR_PATCH_FORMAT_BPT, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    CHECK(s.num_patches == 2);
    tsr_patch_set_free(&s);
    const char *obj = "\xEF\xBB\xBF"
                      "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\nend\n";
    CHECK_MSG(tsr_patch_set_parse(obj, strlen(obj), "bom.obj", TSR_PATCH_FORMAT_OBJ, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    CHECK(s.num_patches == 1);
    tsr_patch_set_free(&s);
    const char *cage = "\xEF\xBB\xBF"
                       "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    tsr_cage c;
    CHECK_MSG(tsr_cage_parse(cage, strlen(cage), "bom_cage.obj", NULL, &c, &e) == TSR_OK, "%s", e.message);
    tsr_cage_free(&c);
    const char *bad = "\xEF\xBB\xBF"
                      "1\n1 1\n0 0 x\n1 0 0\n0 1 0\n1 1 1\n";
    CHECK(tsr_patch_set_parse(bad, strlen(bad), "bom_bad.bpt", TSR_PATCH_FORMAT_BPT, NULL, &s, &e) != TSR_OK);
    CHECK_MSG(!strncmp(e.message, "bom_bad.bpt:3: ", 15), "%s", e.message);
    CHECK(tsr_patch_format_from_path("a/b.BPT") == TSR_PATCH_FORMAT_BPT);
    CHECK(tsr_patch_format_from_path("x.obj") == TSR_PATCH_FORMAT_OBJ);
    CHECK(tsr_patch_format_from_path("x.obj.txt") == TSR_PATCH_FORMAT_UNKNOWN);
}

/* ---- OBJ free-form ---------------------------------------------------------------- */

/* A quarter cylinder of radius 1 and height 2 (a rational quadratic
 * B-spline in u, linear in v), trimmed by the unit square (a degree-1
 * curve) and with a hole: the rational 9-point circle of radius 0.25
 * around (0.5, 0.5). */
static const char freeform_obj[] = "# written by test_patch_io\n"
                                   "v 1 0 0 1\n"
                                   "v 1 1 0 0.70710678118654752\n"
                                   "v 0 1 0 1\n"
                                   "v 1 0 2\n"
                                   "v 1 1 2 0.70710678118654752\n"
                                   "v 0 1 2 1\n"
                                   "vp 0 0\nvp 1 0\nvp 1 1\nvp 0 1\nvp 0 0\n"
                                   "vp 0.75 0.5 1\nvp 0.75 0.75 0.70710678118654752\nvp 0.5 0.75 1\n"
                                   "vp 0.25 0.75 0.70710678118654752\nvp 0.25 0.5 1\n"
                                   "vp 0.25 0.25 0.70710678118654752\nvp 0.5 0.25 1\n"
                                   "vp 0.75 0.25 0.70710678118654752\nvp 0.75 0.5 1\n"
                                   "cstype bspline\n"
                                   "deg 1\n"
                                   "curv2 1 2 3 4 5\n"
                                   "parm u 0 0 1 2 3 4 4\n"
                                   "end\n"
                                   "cstype rat bspline\n"
                                   "deg 2\n"
                                   "curv2 -9 -8 -7 -6 -5 -4 -3 -2 -1\n"
                                   "parm u 0 0 0 1 1 2 2 3 3 4 4 4\n"
                                   "end\n"
                                   "g cylinder\n"
                                   "deg 2 1\n"
                                   "surf 0 1 0 1 1 2 3 \\\n"
                                   "     4/1 5//2 6/1/2\n"
                                   "parm u 0 0 0 1 1 1\n"
                                   "parm v 0 0 1 1\n"
                                   "trim 0 4 1\n"
                                   "hole 0 4 -1\n"
                                   "end\n"
                                   "f 1 2 3\n"
                                   "l 4 5\n";

TEST(obj_freeform_trimmed)
{
    const char *dir = check_temp_dir();
    CHECK(dir != NULL);
    if (!dir)
        return;
    const char *path = write_temp(dir, "cyl.obj", freeform_obj);
    check_alloc c = {0};
    tsr_allocator al = {check_realloc, &c, NULL};
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_load(path, TSR_PATCH_FORMAT_UNKNOWN, &al, &s, &e) == TSR_OK, "%s", e.message);
    remove(path);
    rmdir(dir);
    if (e.status != TSR_OK)
        return;
    CHECK(s.num_patches == 1 && s.num_curves == 2 && s.num_loops == 2 && s.num_segments == 2);
    CHECK(s.num_skipped == 3 && s.first_skipped_line == 32); /* g, f, l */
    CHECK(s.num_polygons == 2 && s.first_polygon_line == 41);
    const tsr_patch *p = &s.patches[0];
    CHECK(p->kind == TSR_PATCH_NURBS && p->degree_u == 2 && p->degree_v == 1);
    CHECK(p->count_u == 3 && p->count_v == 2 && p->weights && p->knots_u && p->knots_v);
    CHECK(p->u0 == 0 && p->u1 == 1 && p->v0 == 0 && p->v1 == 1);
    CHECK(p->weights[0] == 1 && p->weights[3] == 1 && fabs(p->weights[4] - 0.70710678118654752) < 1e-16);
    for (int k = 0; k < 100; k++) {
        double u = (k % 10) / 9.0, v = (k / 10) / 9.0, pos[3];
        CHECK(tsr_patch_eval(p, u, v, pos, NULL, NULL, NULL) == TSR_OK);
        CHECK_NEAR(hypot(pos[0], pos[1]), 1.0, 1e-12);
        CHECK_NEAR(pos[2], 2 * v, 1e-12);
    }
    CHECK(s.first_loop[0] == 0 && s.first_loop[1] == 2);
    const tsr_trim_loop *outer = &s.loops[0], *hole = &s.loops[1];
    CHECK(outer->patch == 0 && !outer->hole && outer->num_segments == 1);
    CHECK(hole->patch == 0 && hole->hole && hole->num_segments == 1);
    const tsr_trim_segment *so = &s.segments[outer->first_segment], *sh = &s.segments[hole->first_segment];
    CHECK(so->curve == 0 && so->t0 == 0 && so->t1 == 4);
    CHECK(sh->curve == 1 && sh->t0 == 0 && sh->t1 == 4);
    CHECK(s.curves[0].degree == 1 && s.curves[0].count == 5 && s.curves[0].weights == NULL);
    CHECK(s.curves[1].degree == 2 && s.curves[1].count == 9 && s.curves[1].weights != NULL);

    /* the outer loop samples to the square's four corners exactly */
    uint32_t n = 0;
    CHECK(tsr_trim_loop_sample(&s, 0, 1e-3, NULL, 0, &n) == TSR_OK);
    CHECK(n == 4);
    double sq[8];
    CHECK(tsr_trim_loop_sample(&s, 0, 1e-3, sq, 8, &n) == TSR_OK);
    const double corners[8] = {0, 0, 1, 0, 1, 1, 0, 1};
    for (int i = 0; i < 8; i++)
        CHECK(sq[i] == corners[i]);
    /* the hole: every point on the circle; every chord's midpoint within
     * tol of it; finer tolerances give more points */
    uint32_t prev = 0;
    for (double tol = 1e-2; tol >= 1e-6; tol /= 10) {
        CHECK(tsr_trim_loop_sample(&s, 1, tol, NULL, 0, &n) == TSR_OK);
        CHECK(n > prev && n < 100000);
        prev = n;
        double *uv = malloc(2 * sizeof(double) * n);
        uint32_t n2 = 0;
        CHECK(uv && tsr_trim_loop_sample(&s, 1, tol, uv, n, &n2) == TSR_OK && n2 == n);
        double area = 0;
        for (uint32_t i = 0; uv && i < n; i++) {
            const double *a = uv + 2 * i, *b = uv + 2 * ((i + 1) % n);
            CHECK_NEAR(hypot(a[0] - 0.5, a[1] - 0.5), 0.25, 1e-12);
            double mid = hypot(0.5 * (a[0] + b[0]) - 0.5, 0.5 * (a[1] + b[1]) - 0.5);
            CHECK(0.25 - mid <= tol && mid <= 0.25 + 1e-12);
            area += a[0] * b[1] - a[1] * b[0];
        }
        CHECK(area > 0); /* counter-clockwise, as written */
        free(uv);
    }
    /* the hole run backwards: the same points, clockwise */
    uint32_t fwd = 0, bwd = 0;
    CHECK(tsr_trim_loop_sample(&s, 1, 1e-4, NULL, 0, &fwd) == TSR_OK);
    s.segments[1].t0 = 4, s.segments[1].t1 = 0;
    CHECK(tsr_trim_loop_sample(&s, 1, 1e-4, NULL, 0, &bwd) == TSR_OK);
    CHECK(fwd == bwd);
    double *back = malloc(2 * sizeof(double) * (bwd ? bwd : 1));
    CHECK(back && tsr_trim_loop_sample(&s, 1, 1e-4, back, bwd, &bwd) == TSR_OK);
    double area = 0;
    for (uint32_t i = 0; back && i < bwd; i++) {
        const double *a = back + 2 * i, *b = back + 2 * ((i + 1) % bwd);
        CHECK_NEAR(hypot(a[0] - 0.5, a[1] - 0.5), 0.25, 1e-12);
        area += a[0] * b[1] - a[1] * b[0];
    }
    CHECK(area < 0 && back && back[0] == 0.75 && back[1] == 0.5);
    free(back);
    CHECK(tsr_trim_loop_sample(&s, 2, 1e-3, NULL, 0, &n) == TSR_ERR_ARGUMENT);
    CHECK(tsr_trim_loop_sample(&s, 0, 0, NULL, 0, &n) == TSR_ERR_ARGUMENT);
    CHECK(tsr_trim_loop_sample(&s, 0, NAN, NULL, 0, &n) == TSR_ERR_ARGUMENT);
    tsr_patch_set_free(&s);
    CHECK_MSG(c.live == 0, "%ld blocks leaked", c.live);

    /* every allocation failure is reported, and leaks nothing */
    long calls = c.calls;
    for (long k = 1; k <= calls; k++) {
        c = (check_alloc){.fail_at = k};
        tsr_status st =
            tsr_patch_set_parse(freeform_obj, sizeof freeform_obj - 1, "cyl.obj", TSR_PATCH_FORMAT_OBJ, &al, &s, &e);
        CHECK_MSG(st == TSR_OK || st == TSR_ERR_NOMEM, "failure at allocation %ld: status %d", k, (int)st);
        if (st == TSR_OK)
            tsr_patch_set_free(&s);
        CHECK_MSG(c.live == 0, "failure at allocation %ld: %ld blocks leaked", k, c.live);
    }
}

TEST(obj_bezier_surfaces)
{
    /* a bicubic Bézier (one span: TSR_PATCH_BEZIER) and a composite
     * bilinear Bézier of 2 x 1 spans (a B-spline with double knots) */
    char text[4096];
    int o = 0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            o += snprintf(text + o, sizeof text - (size_t)o, "v %d %d %g\n", i, j, 0.1 * i * j);
    o += snprintf(text + o, sizeof text - (size_t)o, "cstype bezier\ndeg 3 3\nsurf 0 1 0 1");
    for (int i = 1; i <= 16; i++)
        o += snprintf(text + o, sizeof text - (size_t)o, " %d", i);
    o += snprintf(text + o, sizeof text - (size_t)o,
                  "\nend\n"
                  "v 0 0 5\nv 1 0 5\nv 3 0 5\nv 0 1 5\nv 1 1 6\nv 3 1 5\n"
                  "deg 1 1\nsurf 0 2 0 1 -6 -5 -4 -3 -2 -1\nparm u 0 1 2\nparm v 0 1\nend\n"
                  "deg 3 3\nsurf 0.5 1 0 1 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16\nparm u 0 1\nparm v 0 1\nend\n");
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_parse(text, (size_t)o, "bez.obj", TSR_PATCH_FORMAT_OBJ, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    if (e.status != TSR_OK)
        return;
    CHECK(s.num_patches == 3);
    const tsr_patch *a = &s.patches[0], *b = &s.patches[1], *c = &s.patches[2];
    CHECK(a->kind == TSR_PATCH_BEZIER && a->count_u == 4 && a->weights == NULL);
    double pos[3];
    for (int k = 0; k < 25; k++) {
        double u = (k % 5) / 4.0, v = (k / 5) / 4.0;
        tsr_patch_eval(a, u, v, pos, NULL, NULL, NULL);
        /* x = 3u, y = 3v, z = 0.1 * 9uv: degree elevation of bilinear terms */
        CHECK_NEAR(pos[0], 3 * u, 1e-12);
        CHECK_NEAR(pos[1], 3 * v, 1e-12);
        CHECK_NEAR(pos[2], 0.9 * u * v, 1e-12);
    }
    CHECK(b->kind == TSR_PATCH_BSPLINE && b->count_u == 3 && b->count_v == 2);
    CHECK(tsr_patch_spans(b, 0, NULL, 0) == 2);
    /* span 1 (u in [1, 2]) is the bilinear patch of points 2, 3, 5, 6 */
    tsr_patch_eval(b, 1.5, 0.5, pos, NULL, NULL, NULL);
    CHECK_NEAR(pos[0], 2.0, 1e-12);
    CHECK_NEAR(pos[2], 5.25, 1e-12);
    tsr_patch_eval(b, 0.5, 0.5, pos, NULL, NULL, NULL);
    CHECK_NEAR(pos[0], 0.5, 1e-12);
    CHECK_NEAR(pos[2], 5.25, 1e-12);
    /* part of a span: kept as a B-spline over the sub-domain */
    CHECK(c->kind == TSR_PATCH_BSPLINE && c->u0 == 0.5 && c->u1 == 1);
    tsr_patch_eval(c, 0.75, 0.5, pos, NULL, NULL, NULL);
    CHECK_NEAR(pos[0], 2.25, 1e-12);
    tsr_patch_set_free(&s);
}

/* ---- Cages ---------------------------------------------------------------------- */

/* Counts lines starting with the given prefix: the second reader. */
static uint32_t count_lines(const char *path, const char *prefix)
{
    FILE *f = fopen(path, "r");
    char line[65536];
    uint32_t n = 0;
    while (f && fgets(line, sizeof line, f))
        n += !strncmp(line, prefix, strlen(prefix));
    if (f)
        fclose(f);
    return n;
}

static tsr_status load_cage(const char *dir, const char *name, tsr_cage *c, tsr_error *e)
{
    char p[5000];
    snprintf(p, sizeof p, "%s/patches/osd/%s", dir, name);
    return tsr_cage_load(p, NULL, c, e);
}

TEST(data_osd_cages_load)
{
    const char *data = check_data_dir();
    char osd[5000];
    snprintf(osd, sizeof osd, "%s/patches/osd", data ? data : "");
    DIR *d = data ? opendir(osd) : NULL;
    if (!d)
        SKIP("no shared data folder with patches/osd (set TESSERA_DATA)");
    int files = 0;
    struct dirent *de;
    while ((de = readdir(d)) != NULL) {
        size_t l = strlen(de->d_name);
        if (l < 5 || strcmp(de->d_name + l - 4, ".obj"))
            continue;
        char p[10000];
        snprintf(p, sizeof p, "%s/%s", osd, de->d_name);
        check_alloc cnt = {0};
        tsr_allocator al = {check_realloc, &cnt, NULL};
        tsr_cage c;
        tsr_error e = {0};
        CHECK_MSG(tsr_cage_load(p, &al, &c, &e) == TSR_OK, "%s", e.message);
        files++;
        CHECK_MSG(c.num_points == count_lines(p, "v "), "%s: %u points", de->d_name, c.num_points);
        CHECK_MSG(c.num_faces == count_lines(p, "f "), "%s: %u faces", de->d_name, c.num_faces);
        CHECK(c.num_uvs == count_lines(p, "vt "));
        uint32_t sum = 0;
        for (uint32_t f = 0; f < c.num_faces; f++) {
            CHECK(c.face_sizes[f] >= 3);
            sum += c.face_sizes[f];
        }
        CHECK(sum == c.num_face_verts);
        for (uint32_t i = 0; i < c.num_face_verts; i++)
            CHECK(c.face_verts[i] < c.num_points && (!c.face_uvs || c.face_uvs[i] < c.num_uvs));
        for (uint32_t i = 0; i < 2 * c.num_creases; i++)
            CHECK(c.crease_verts[i] < c.num_points);
        for (uint32_t i = 0; i < c.num_holes; i++)
            CHECK(c.hole_faces[i] < c.num_faces);
        CHECK(c.boundary_interp >= 0 && c.boundary_interp <= 2 && c.fvar_interp >= 0 && c.fvar_interp <= 5);
        tsr_cage_free(&c);
        CHECK_MSG(cnt.live == 0, "%s: %ld blocks leaked", de->d_name, cnt.live);
    }
    closedir(d);
    CHECK_MSG(files == 85, "%d cages", files); /* the data README */

    tsr_cage c;
    tsr_error e = {0};
    CHECK(load_cage(data, "catmark_cube.obj", &c, &e) == TSR_OK);
    CHECK(c.num_faces == 6 && c.num_points == 8 && c.num_face_verts == 24 && c.num_creases == 0);
    CHECK(c.boundary_interp == 1 && c.fvar_interp == 5); /* no tags: the defaults */
    tsr_cage_free(&c);
    /* t crease 2/1/0 0 1 2.0, t crease 2/1/0 1 3 2.0, interpolateboundary 2 */
    CHECK(load_cage(data, "catmark_cube_creases0.obj", &c, &e) == TSR_OK);
    CHECK(c.num_creases == 2 && c.crease_verts[0] == 0 && c.crease_verts[1] == 1 && c.crease_verts[2] == 1 &&
          c.crease_verts[3] == 3 && c.crease_sharpness[0] == 2.0f && c.crease_sharpness[1] == 2.0f);
    CHECK(c.boundary_interp == 1); /* RenderMan's 2 is edge only */
    tsr_cage_free(&c);
    CHECK(load_cage(data, "catmark_hole_test1.obj", &c, &e) == TSR_OK);
    CHECK(c.num_holes == 1 && c.hole_faces[0] == 1);
    tsr_cage_free(&c);
    CHECK(load_cage(data, "catmark_chaikin0.obj", &c, &e) == TSR_OK);
    CHECK(c.crease_method == 0); /* t creasemethod 0/0/1 normal */
    tsr_cage_free(&c);
    CHECK(load_cage(data, "catmark_chaikin1.obj", &c, &e) == TSR_OK);
    CHECK(c.crease_method == 1); /* chaikin */
    tsr_cage_free(&c);
    CHECK(load_cage(data, "catmark_square_hedit0.obj", &c, &e) == TSR_OK);
    CHECK(c.num_skipped_tags == 3 && c.first_skipped_tag_line > 0);
    tsr_cage_free(&c);
    /* corner tags: count them with the second reader */
    char p[5000];
    snprintf(p, sizeof p, "%s/patches/osd/catmark_cube_corner0.obj", data);
    CHECK(tsr_cage_load(p, NULL, &c, &e) == TSR_OK);
    CHECK(c.num_corners == count_lines(p, "t corner ") && c.num_corners > 0);
    for (uint32_t i = 0; i < c.num_corners; i++)
        CHECK(c.corner_verts[i] < c.num_points && c.corner_sharpness[i] >= 0);
    tsr_cage_free(&c);
}

TEST(cage_small_forms)
{
    const char *text = "v 0 0 0\nv 1 0 0\nv 1 1 0 1\nv 0 1 0 0.5 0.5 0.5\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                       "vn 0 0 1\n"
                       "f 1/1/1 2/2/1 3/3/1 4/4/1\n"
                       "f -4/-4 -2/-2 -1/-1\n"
                       "t crease 4/2/0 0 1 1 2 1.5 3\n"
                       "t corner 2/1/0 0 3 4\n"
                       "t hole 1/0/0 1\n"
                       "t interpolateboundary 1/0/0 1\n"
                       "t facevaryinginterpolateboundary 1/0/0 3\n"
                       "t smoothtriangles 0/0/1 smooth\n"
                       "t creasemethod 0/0/1 chaikin\n"
                       "t vertexedit 1/0/0 1\n";
    tsr_cage c;
    tsr_error e = {0};
    CHECK_MSG(tsr_cage_parse(text, strlen(text), "small.obj", NULL, &c, &e) == TSR_OK, "%s", e.message);
    CHECK(c.num_points == 4 && c.points[6] == 1 && c.points[11] == 0);
    CHECK(c.num_faces == 2 && c.face_sizes[0] == 4 && c.face_sizes[1] == 3 && c.num_face_verts == 7);
    const uint32_t fv[7] = {0, 1, 2, 3, 0, 2, 3};
    for (int i = 0; i < 7; i++)
        CHECK(c.face_verts[i] == fv[i] && c.face_uvs && c.face_uvs[i] == fv[i]);
    CHECK(c.num_uvs == 4 && c.uvs[5] == 1);
    CHECK(c.num_creases == 2 && c.crease_verts[2] == 1 && c.crease_verts[3] == 2);
    CHECK(c.crease_sharpness[0] == 1.5f && c.crease_sharpness[1] == 3.0f);
    CHECK(c.num_corners == 2 && c.corner_verts[1] == 3 && c.corner_sharpness[0] == 4.0f &&
          c.corner_sharpness[1] == 4.0f);
    CHECK(c.num_holes == 1 && c.hole_faces[0] == 1);
    CHECK(c.boundary_interp == 2 && c.fvar_interp == 3 && c.triangle_subdiv == 1 && c.crease_method == 1);
    CHECK(c.num_skipped_tags == 1 && c.first_skipped_tag_line == 19);
    tsr_cage_free(&c);
    tsr_cage_free(&c);
    /* a face without vt: no face_uvs at all */
    const char *mixed = "v 0 0 0\nv 1 0 0\nv 1 1 0\nvt 0 0\nf 1/1 2/1 3/1\nf 1 2 3\n";
    CHECK(tsr_cage_parse(mixed, strlen(mixed), NULL, NULL, &c, &e) == TSR_OK);
    CHECK(c.face_uvs == NULL && c.num_faces == 2);
    tsr_cage_free(&c);
}

/* ---- Bad files -------------------------------------------------------------- */

typedef enum { BPT, OBJ, CAGE } reader;

typedef struct bad_case {
    const char *name; /* what broke; also the file's name in the message */
    reader r;
    const char *text;
    tsr_status status;
    unsigned line; /* the line the message must name */
} bad_case;

static const bad_case bad_cases[] = {
    {"bpt_not_a_number", BPT, "x\n", TSR_ERR_FORMAT, 1},
    {"bpt_negative_count", BPT, "-1\n", TSR_ERR_FORMAT, 1},
    {"bpt_zero_patches", BPT, "0\n", TSR_ERR_EMPTY, 1},
    {"bpt_huge_count", BPT, "4000000000\n1 1\n0 0 0\n", TSR_ERR_TOO_LARGE, 1},
    {"bpt_count_beyond_u32", BPT, "99999999999999999999\n", TSR_ERR_TOO_LARGE, 1},
    {"bpt_two_coordinates", BPT, "1\n1 1\n0 0 0\n1 0 0\n0 1\n1 1 0\n", TSR_ERR_FORMAT, 5},
    {"bpt_four_coordinates", BPT, "1\n1 1\n0 0 0\n1 0 0 7\n0 1 0\n1 1 0\n", TSR_ERR_FORMAT, 4},
    {"bpt_truncated", BPT, "1\n1 1\n0 0 0\n", TSR_ERR_TRUNCATED, 4},
    {"bpt_truncated_header", BPT, "2\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n", TSR_ERR_TRUNCATED, 7},
    {"bpt_degree_zero", BPT, "1\n0 1\n0 0 0\n0 1 0\n", TSR_ERR_VALUE, 2},
    {"bpt_degree_8", BPT, "1\n8 1\n", TSR_ERR_UNSUPPORTED, 2},
    {"bpt_one_degree", BPT, "1\n3\n", TSR_ERR_FORMAT, 2},
    {"bpt_nan_coordinate", BPT, "1\n1 1\n0 0 0\nnan 0 0\n0 1 0\n1 1 0\n", TSR_ERR_VALUE, 4},
    {"bpt_inf_coordinate", BPT, "1\n1 1\n0 0 0\n1 0 0\n0 1e999 0\n1 1 0\n", TSR_ERR_VALUE, 5},
    {"bpt_coordinate_beyond_limit", BPT, "1\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 -1e31\n", TSR_ERR_VALUE, 6},
    {"bpt_trailing_data", BPT, "1\n1 1\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n1 1\n", TSR_ERR_FORMAT, 7},
    {"bpt_binary_bytes", BPT, "\x01\x7f\xff\xfe\n", TSR_ERR_FORMAT, 1},
    {"bpt_empty", BPT, "", TSR_ERR_EMPTY, 0},
    {"bpt_only_continuations", BPT, "\\\n \\ \n\\", TSR_ERR_EMPTY, 0},
    {"bpt_only_comments", BPT, "# nothing\n\n", TSR_ERR_EMPTY, 0},

    {"obj_no_surface", OBJ, "v 0 0 0\nv 1 0 0\n", TSR_ERR_EMPTY, 0},
    {"obj_nan_vertex", OBJ, "v 0 0 0\nv nan 0 0\n", TSR_ERR_VALUE, 2},
    {"obj_vertex_two_values", OBJ, "v 0 0\n", TSR_ERR_FORMAT, 1},
    {"obj_surf_without_cstype", OBJ, "v 0 0 0\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_FORMAT, 3},
    {"obj_surf_without_deg", OBJ, "v 0 0 0\ncstype bezier\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_FORMAT, 3},
    {"obj_surf_one_degree", OBJ, "v 0 0 0\ncstype bezier\ndeg 1\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_FORMAT, 4},
    {"obj_deg_zero", OBJ, "cstype bezier\ndeg 0 1\n", TSR_ERR_VALUE, 2},
    {"obj_deg_8", OBJ, "cstype bezier\ndeg 8 1\n", TSR_ERR_UNSUPPORTED, 2},
    {"obj_cstype_cardinal", OBJ, "v 0 0 0\ncstype cardinal\ndeg 3 3\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_UNSUPPORTED,
     4},
    {"obj_cstype_unknown", OBJ, "cstype wobbly\n", TSR_ERR_FORMAT, 1},
    {"obj_surf_index_out_of_range", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 9\nend\n", TSR_ERR_VALUE,
     4},
    {"obj_surf_index_zero", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 0 1 1\nend\n", TSR_ERR_VALUE, 4},
    {"obj_surf_relative_too_far", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 -1 -1 -1 -2\nend\n",
     TSR_ERR_VALUE, 4},
    {"obj_surf_count_mismatch", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1\nend\n", TSR_ERR_FORMAT, 4},
    {"obj_surf_bad_index", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 x 1\nend\n", TSR_ERR_FORMAT, 4},
    {"obj_surf_missing_range", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1\nend\n", TSR_ERR_FORMAT, 4},
    {"obj_missing_end", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\n", TSR_ERR_TRUNCATED, 4},
    {"obj_nested_surf", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nsurf 0 1 0 1 1 1 1 1\nend\n",
     TSR_ERR_FORMAT, 5},
    {"obj_end_without_element", OBJ, "end\n", TSR_ERR_FORMAT, 1},
    {"obj_parm_outside_element", OBJ, "parm u 0 1\n", TSR_ERR_FORMAT, 1},
    {"obj_parm_bad_direction", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nparm w 0 1\nend\n",
     TSR_ERR_FORMAT, 5},
    {"obj_non_monotone_knots", OBJ,
     "v 0 0 0\ncstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nparm u 0 0 1 0.5\nparm v 0 0 1 1\nend\n", TSR_ERR_VALUE,
     5},
    {"obj_bspline_without_parm", OBJ, "v 0 0 0\ncstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_FORMAT,
     4},
    {"obj_bspline_wrong_knot_count", OBJ,
     "v 0 0 0\ncstype bspline\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nparm u 0 0 1 1 1\nparm v 0 0 1 1\nend\n", TSR_ERR_FORMAT,
     4},
    {"obj_interior_knot_beyond_degree", OBJ,
     "v 0 0 0\ncstype bspline\ndeg 2 1\nsurf 0 1 0 1 1 1 1 1 1 1 1 1 1 1 1 1\nparm u 0 0 0 0.5 0.5 0.5 0.5 1 1 "
     "1\nparm v 0 0 1 1\nend\n",
     TSR_ERR_VALUE, 5},
    {"obj_domain_outside_knots", OBJ,
     "v 0 0 0\ncstype bspline\ndeg 1 1\nsurf 0 2 0 1 1 1 1 1\nparm u 0 0 1 1\nparm v 0 0 1 1\nend\n", TSR_ERR_VALUE, 4},
    {"obj_inverted_domain", OBJ, "v 0 0 0\ncstype bezier\ndeg 1 1\nsurf 1 0 0 1 1 1 1 1\nend\n", TSR_ERR_VALUE, 4},
    {"obj_zero_weight", OBJ, "v 0 0 0\nv 1 0 0 0\ncstype rat bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 1 1\nend\n",
     TSR_ERR_VALUE, 5},
    {"obj_negative_weight", OBJ, "v 0 0 0 -2\ncstype rat bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nend\n", TSR_ERR_VALUE,
     4},
    {"obj_trim_outside_surf", OBJ, "trim 0 1 1\n", TSR_ERR_FORMAT, 1},
    {"obj_trim_in_curv2", OBJ, "vp 0 0\nvp 1 1\ncstype bezier\ndeg 1\ncurv2 1 2\ntrim 0 1 1\nend\n", TSR_ERR_FORMAT, 6},
    {"obj_trim_unknown_curve", OBJ,
     "v 0 0 0\nvp 0 0\nvp 1 1\ncstype bezier\ndeg 1 1\ncurv2 1 2\nend\nsurf 0 1 0 1 1 1 1 1\ntrim 0 1 5\nend\n",
     TSR_ERR_VALUE, 9},
    {"obj_trim_range_outside_curve", OBJ,
     "v 0 0 0\nvp 0 0\nvp 1 1\ncstype bezier\ndeg 1 1\ncurv2 1 2\nend\nsurf 0 1 0 1 1 1 1 1\ntrim 0 9 1\nend\n",
     TSR_ERR_VALUE, 9},
    {"obj_trim_incomplete_triple", OBJ,
     "v 0 0 0\nvp 0 0\nvp 1 1\ncstype bezier\ndeg 1 1\ncurv2 1 2\nend\nsurf 0 1 0 1 1 1 1 1\ntrim 0 1\nend\n",
     TSR_ERR_FORMAT, 9},
    {"obj_curv2_unknown_vp", OBJ, "vp 0 0\ncstype bezier\ndeg 1\ncurv2 1 2\nend\n", TSR_ERR_VALUE, 4},
    {"obj_vp_inf", OBJ, "vp 0 inf\n", TSR_ERR_VALUE, 1},
    {"obj_binary_keyword", OBJ, "v 0 0 0\n\x01\x02 3\n", TSR_ERR_FORMAT, 2},
    {"obj_coordinate_beyond_limit", OBJ, "v 0 0 2e30\ncstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 1 1 1\nend\n",
     TSR_ERR_VALUE, 4},
    {"obj_discontinuous_knot", OBJ,
     "v 0 0 0\nv 1 0 0\nv 2 0 1\nv 3 0 0\nv 0 1 0\nv 1 1 0\nv 2 1 1\nv 3 1 0\ncstype bspline\ndeg 1 1\n"
     "surf 0 3 0 1 1 2 3 4 5 6 7 8\nparm u 0 0 1 1 3 3\nparm v 0 0 1 1\nend\n",
     TSR_ERR_VALUE, 11},
    {"obj_trailing_continuation", OBJ, "v 0 0 0\n\\", TSR_ERR_EMPTY, 0},

    {"cage_no_faces", CAGE, "v 0 0 0\n", TSR_ERR_EMPTY, 0},
    {"cage_face_two_vertices", CAGE, "v 0 0 0\nv 1 0 0\nf 1 2\n", TSR_ERR_FORMAT, 3},
    {"cage_face_index_out_of_range", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", TSR_ERR_VALUE, 4},
    {"cage_face_index_zero", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n", TSR_ERR_VALUE, 4},
    {"cage_face_bad_token", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 a 3\n", TSR_ERR_FORMAT, 4},
    {"cage_face_bad_vt", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/4 2 3\n", TSR_ERR_VALUE, 4},
    {"cage_nan_point", CAGE, "v 0 0 0\nv 1 NaN 0\n", TSR_ERR_VALUE, 2},
    {"cage_crease_odd", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 3/1/0 0 1 2 1.0\n", TSR_ERR_FORMAT, 5},
    {"cage_crease_missing_values", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 1\n", TSR_ERR_FORMAT, 5},
    {"cage_crease_extra_values", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 1 1 1\n", TSR_ERR_FORMAT,
     5},
    {"cage_crease_vertex_out_of_range", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 99 1\n",
     TSR_ERR_VALUE, 5},
    {"cage_crease_nan_sharpness", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 1 nan\n", TSR_ERR_VALUE,
     5},
    {"cage_crease_negative_sharpness", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/1/0 0 1 -1\n",
     TSR_ERR_VALUE, 5},
    {"cage_crease_sharpness_count", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2/2/0 0 1 1 1\n",
     TSR_ERR_FORMAT, 5},
    {"cage_corner_out_of_range", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt corner 1/1/0 3 1\n", TSR_ERR_VALUE, 5},
    {"cage_hole_face_out_of_range", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt hole 1/0/0 1\n", TSR_ERR_VALUE, 5},
    {"cage_interpolateboundary_7", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt interpolateboundary 1/0/0 7\n",
     TSR_ERR_VALUE, 5},
    {"cage_creasemethod_unknown", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt creasemethod 0/0/1 wiggly\n",
     TSR_ERR_VALUE, 5},
    {"cage_tag_bad_counts", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 2-1-0 0 1 1\n", TSR_ERR_FORMAT, 5},
    {"cage_tag_huge_counts", CAGE, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nt crease 4000000000/1/0 0 1 1\n",
     TSR_ERR_TOO_LARGE, 5},
    {"cage_binary_bytes", CAGE, "\xff\xfe\x00\x01 v\n", TSR_ERR_FORMAT, 1},
};

/* Whether every edge used by two faces is run both ways (the oracle of
 * tsr_cage_orient, by brute force over pairs of face corners). */
static uint32_t cage_disagreements(const tsr_cage *c)
{
    uint32_t bad = 0, k = 0;
    for (uint32_t f = 0; f < c->num_faces; f++) {
        uint32_t n = c->face_sizes[f];
        for (uint32_t i = 0; i < n; i++) {
            uint32_t a = c->face_verts[k + i], b = c->face_verts[k + (i + 1) % n], l = 0;
            for (uint32_t g = 0; g < c->num_faces; g++) {
                uint32_t m = c->face_sizes[g];
                for (uint32_t j = 0; j < m; j++)
                    if (g > f && c->face_verts[l + j] == a && c->face_verts[l + (j + 1) % m] == b)
                        bad++;
                l += m;
            }
        }
        k += n;
    }
    return bad;
}

TEST(cage_orient)
{
    /* a cube whose faces 1 and 2 (0-based) list their corners backwards;
     * face 1 carries texture corners, which turn with it */
    const char *cube = "v -1 -1 1\nv 1 -1 1\nv -1 1 1\nv 1 1 1\nv -1 1 -1\nv 1 1 -1\nv -1 -1 -1\nv 1 -1 -1\n"
                       "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
                       "f 1/1 2/2 4/3 3/4\nf 5/1 6/2 4/3 3/4\nf 7/1 8/2 6/3 5/4\nf 7/1 8/2 2/3 1/4\n"
                       "f 2/1 8/2 6/3 4/4\nf 7/1 1/2 3/3 5/4\nt hole 1/0/0 3\n";
    tsr_cage c;
    tsr_error e = {0};
    tsr_status st = tsr_cage_parse(cube, strlen(cube), "cube.obj", NULL, &c, &e);
    CHECK_MSG(st == TSR_OK, "%s", e.message);
    if (st != TSR_OK)
        return;
    /* faces 1 (5 6 4 3 for 3 4 6 5) and 2 (7 8 6 5 for 5 6 8 7) are listed backwards: reversed, the other
     * four, the majority, keep their order */
    uint32_t before = cage_disagreements(&c), rev = 99, bad = 99, first = 99;
    CHECK_MSG(before > 0, "the fixture is consistent: %u", before);
    /* counted only */
    CHECK(tsr_cage_orient(&c, false, &rev, &first, &bad) == TSR_OK);
    CHECK_MSG(rev == 2 && first == 1 && bad == 0, "reversed %u first %u unorientable %u", rev, first, bad);
    CHECK(cage_disagreements(&c) == before);
    CHECK(tsr_cage_orient(&c, true, &rev, &first, &bad) == TSR_OK);
    CHECK_MSG(rev == 2 && first == 1 && bad == 0, "reversed %u first %u unorientable %u", rev, first, bad);
    CHECK_MSG(cage_disagreements(&c) == 0, "%u edges still run one way twice", cage_disagreements(&c));
    /* face 1 (corners 4..7) is now 5 3 4 6 with its texture corners 1 4 3 2 */
    CHECK(c.face_verts[4] == 4 && c.face_verts[5] == 2 && c.face_verts[6] == 3 && c.face_verts[7] == 5);
    CHECK(c.face_uvs && c.face_uvs[4] == 0 && c.face_uvs[5] == 3 && c.face_uvs[6] == 2 && c.face_uvs[7] == 1);
    CHECK(c.num_holes == 1 && c.hole_faces[0] == 3);
    /* again: nothing to do */
    CHECK(tsr_cage_orient(&c, true, &rev, &first, &bad) == TSR_OK && rev == 0 && first == UINT32_MAX && bad == 0);
    tsr_cage_free(&c);
    /* a Möbius band of four quads: no orientation agrees; left as it is */
    const char *band = "v 0 0 0\nv 0 0 1\nv 1 0 0\nv 1 0 1\nv 1 1 0\nv 1 1 1\nv 0 1 0\nv 0 1 1\n"
                       "f 1 3 4 2\nf 3 5 6 4\nf 5 7 8 6\nf 7 2 1 8\n";
    st = tsr_cage_parse(band, strlen(band), "band.obj", NULL, &c, &e);
    CHECK_MSG(st == TSR_OK, "%s", e.message);
    if (st != TSR_OK)
        return;
    uint32_t verts[16];
    memcpy(verts, c.face_verts, sizeof verts);
    CHECK(tsr_cage_orient(&c, true, &rev, NULL, &bad) == TSR_OK);
    CHECK_MSG(rev == 0 && bad == 1, "band: reversed %u unorientable %u", rev, bad);
    CHECK(!memcmp(verts, c.face_verts, sizeof verts));
    tsr_cage_free(&c);
    CHECK(tsr_cage_orient(NULL, true, &rev, NULL, &bad) == TSR_OK && rev == 0);
    /* two overlapping faces run their shared edge the same way: a fold,
     * left a seam (OpenSubdiv's reading), nothing reversed */
    const char *fold = "v 0.3 0 -0.7\nv 0.7 0 -0.7\nv 0.3 -0.2 -0.9\nv 0.7 -0.2 -0.9\nf 3 4 1\nf 3 4 2\n";
    st = tsr_cage_parse(fold, strlen(fold), "fold.obj", NULL, &c, &e);
    CHECK_MSG(st == TSR_OK, "%s", e.message);
    if (st == TSR_OK) {
        CHECK(tsr_cage_orient(&c, true, &rev, NULL, &bad) == TSR_OK && rev == 0 && bad == 0);
        tsr_cage_free(&c);
    }
}

/* A knot repeated degree + 1 times inside the range: refused only where
 * the control points on either side of it differ (bad_cases:
 * obj_discontinuous_knot); two Bézier pieces written as one B-spline with
 * the shared column repeated are one continuous surface. */
TEST(obj_repeated_knot_continuous)
{
    const char *obj =
        "v 0 0 0\nv 1 0 0\nv 1 0 0\nv 2 0 1\nv 0 1 0\nv 1 1 0\nv 1 1 0\nv 2 1 1\n"
        "cstype bspline\ndeg 1 1\nsurf 0 2 0 1 1 2 3 4 5 6 7 8\nparm u 0 0 1 1 2 2\nparm v 0 0 1 1\nend\n";
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_parse(obj, strlen(obj), "split.obj", TSR_PATCH_FORMAT_OBJ, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    if (e.status == TSR_OK) {
        double pos[3];
        CHECK(s.num_patches == 1 && tsr_patch_eval(&s.patches[0], 1.5, 0.5, pos, NULL, NULL, NULL) == TSR_OK);
        CHECK(fabs(pos[0] - 1.5) < 1e-12 && fabs(pos[2] - 0.5) < 1e-12);
        tsr_patch_set_free(&s);
    }
}

TEST(bad_files_name_the_line)
{
    for (size_t i = 0; i < sizeof bad_cases / sizeof bad_cases[0]; i++) {
        const bad_case *b = &bad_cases[i];
        size_t len = strlen(b->text);
        if (!strcmp(b->name, "cage_binary_bytes"))
            len = 7; /* a NUL inside */
        check_alloc c = {0};
        tsr_allocator al = {check_realloc, &c, NULL};
        tsr_error e = {0};
        tsr_status st;
        if (b->r == CAGE) {
            tsr_cage cage;
            st = tsr_cage_parse(b->text, len, b->name, &al, &cage, &e);
            if (st == TSR_OK)
                tsr_cage_free(&cage);
        } else {
            tsr_patch_set s;
            st = tsr_patch_set_parse(b->text, len, b->name, b->r == BPT ? TSR_PATCH_FORMAT_BPT : TSR_PATCH_FORMAT_OBJ,
                                     &al, &s, &e);
            if (st == TSR_OK)
                tsr_patch_set_free(&s);
        }
        char want[256];
        if (b->line)
            snprintf(want, sizeof want, "%s:%u: ", b->name, b->line);
        else
            snprintf(want, sizeof want, "%s: ", b->name);
        CHECK_MSG(st == b->status && e.status == st, "%s: status %d (%s), expected %d: %s", b->name, (int)st,
                  tsr_status_str(st), (int)b->status, e.message);
        CHECK_MSG(!strncmp(e.message, want, strlen(want)), "%s: message '%s' does not begin '%s'", b->name, e.message,
                  want);
        CHECK_MSG(c.live == 0, "%s: %ld blocks leaked", b->name, c.live);
        CHECK_MSG(c.largest < ((size_t)1 << 20), "%s: an allocation of %zu bytes", b->name, c.largest);
        fprintf(stderr, "  %s\n", e.message);
    }
}

TEST(missing_and_odd_paths)
{
    tsr_patch_set s;
    tsr_cage c;
    tsr_error e = {0};
    CHECK(tsr_patch_set_load("/nonexistent/teapot.bpt", TSR_PATCH_FORMAT_UNKNOWN, NULL, &s, &e) == TSR_ERR_NOT_FOUND);
    CHECK(strstr(e.message, "/nonexistent/teapot.bpt") != NULL);
    CHECK(tsr_cage_load("/nonexistent/cube.obj", NULL, &c, &e) == TSR_ERR_NOT_FOUND);
    CHECK(tsr_patch_set_load("/tmp", TSR_PATCH_FORMAT_BPT, NULL, &s, &e) == TSR_ERR_ARGUMENT);
    CHECK(tsr_patch_set_load("x.stl", TSR_PATCH_FORMAT_UNKNOWN, NULL, &s, &e) == TSR_ERR_ARGUMENT);
    CHECK(tsr_patch_set_parse("1", 1, NULL, TSR_PATCH_FORMAT_UNKNOWN, NULL, &s, &e) == TSR_ERR_ARGUMENT);
    const char *dir = check_temp_dir();
    const char *path = dir ? write_temp(dir, "empty.bpt", "") : NULL;
    CHECK(path && tsr_patch_set_load(path, TSR_PATCH_FORMAT_UNKNOWN, NULL, &s, &e) == TSR_ERR_EMPTY);
    if (path)
        remove(path);
    if (dir)
        rmdir(dir);
    tsr_patch_set_free(NULL);
    tsr_cage_free(NULL);
}

/* A square hole's four edges listed out of order, one backwards: the
 * loader chains them end to start, and the loop encloses the square (0.64
 * of the unit domain: the oracle is the square's own area); listed in
 * order, nothing moves; with a real gap, nothing moves either. */
static void square_loop(const char *trim, bool gap, double *area, bool *reordered, double *gap_out)
{
    char text[2048];
    snprintf(text, sizeof text,
             "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n"
             "vp 0.1 0.1\nvp 0.9 0.1\nvp 0.9 0.1\nvp 0.9 0.9\nvp 0.9 0.9\nvp %s\nvp 0.1 0.9\nvp 0.1 0.1\n"
             "cstype bspline\ndeg 1\ncurv2 1 2\nparm u 0 0 1 1\nend\n"
             "curv2 3 4\nparm u 0 0 1 1\nend\ncurv2 5 6\nparm u 0 0 1 1\nend\ncurv2 7 8\nparm u 0 0 1 1\nend\n"
             "cstype bezier\ndeg 1 1\nsurf 0 1 0 1 1 2 3 4\n%s\nend\n",
             gap ? "0.2 0.8" : "0.1 0.9", trim);
    tsr_patch_set s;
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_set_parse(text, strlen(text), "sq.obj", TSR_PATCH_FORMAT_OBJ, NULL, &s, &e) == TSR_OK, "%s",
              e.message);
    tsr_trim_loop_info in;
    CHECK(s.num_loops == 1 && tsr_trim_loop_check(&s, 0, 1e-9, NULL, &in) == TSR_OK);
    *area = in.area;
    *gap_out = in.gap;
    *reordered = s.loops[0].reordered;
    for (uint32_t k = 0; *reordered && k + 1 < s.loops[0].num_segments; k++) {
        const tsr_trim_segment *a = &s.segments[s.loops[0].first_segment + k], *b = a + 1;
        double p[2], q[2];
        CHECK(tsr_curve2_eval(&s.curves[a->curve], a->t1, p, NULL) == TSR_OK &&
              tsr_curve2_eval(&s.curves[b->curve], b->t0, q, NULL) == TSR_OK);
        CHECK_MSG(hypot(p[0] - q[0], p[1] - q[1]) < 1e-12, "segments %u and %u do not meet", k, k + 1);
    }
    tsr_patch_set_free(&s);
}

TEST(obj_trim_curves_out_of_order_chained)
{
    double area, gap;
    bool re;
    square_loop("trim 0 1 1 0 1 2 0 1 3 0 1 4", false, &area, &re, &gap);
    CHECK(!re && fabs(area - 0.64) < 1e-12 && gap == 0);
    square_loop("trim 0 1 1 0 1 3 0 1 2 0 1 4", false, &area, &re, &gap);
    CHECK_MSG(re && fabs(area - 0.64) < 1e-12 && gap == 0, "shuffled: reordered %d area %g gap %g", re, area, gap);
    square_loop("trim 0 1 1 1 0 3 0 1 4 1 0 2", false, &area, &re, &gap);
    CHECK_MSG(re && fabs(area - 0.64) < 1e-12 && gap == 0, "shuffled and turned: reordered %d area %g", re, area);
    square_loop("hole 0 1 4 0 1 3 0 1 2 0 1 1", false, &area, &re, &gap);
    CHECK_MSG(re && fabs(area - 0.64) < 1e-12 && gap == 0, "reversed list: reordered %d area %g", re, area);
    square_loop("trim 0 1 1 0 1 3 0 1 2 0 1 4", true, &area, &re, &gap); /* curve 3 starts off curve 2's end */
    CHECK(!re);
}

TEST_MAIN(T(data_teapot_loads), T(data_teapot_degenerate_normals), T(bpt_small_and_memory_parse), T(cage_orient),
          T(obj_repeated_knot_continuous), T(obj_freeform_trimmed), T(obj_bezier_surfaces), T(data_osd_cages_load),
          T(cage_small_forms), T(bad_files_name_the_line), T(missing_and_odd_paths),
          T(obj_trim_curves_out_of_order_chained))
