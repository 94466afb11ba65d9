/* tsr_mesh_add_base: closing height-field meshes into solids. The oracles
 * are independent of the code under test: directed edges counted by index
 * and by position, the signed volume (divergence theorem) against the sum
 * of the prisms under the top triangles, the bottom's area against the
 * top's projected area, and the Euler characteristic against the genus
 * known from how each mesh was built. */
#include "check.h"
#include "tessellate/tessellate.h"

#include <stdint.h>

/* ---- Building height-field meshes ---------------------------------------- */

static double height_fn(double x, double y)
{
    return 3.0 + 0.5 * sin(0.7 * x) + 0.25 * cos(1.3 * y) + 0.1 * x;
}

/* An nx x ny grid of unit cells, two CCW triangles per cell (a, b, d) and
 * (a, d, c), triangle 2*(j*nx+i)+s kept when keep[...] (NULL: all). z from
 * height_fn, or the constant flat_z when flat_z is not NaN. */
static void grid_mesh(tsr_mesh *m, unsigned attrs, int nx, int ny, const bool *keep, double flat_z)
{
    tsr_mesh_init(m, attrs, NULL);
    for (int j = 0; j <= ny; j++)
        for (int i = 0; i <= nx; i++) {
            float p[3] = {(float)i, (float)j, (float)(isnan(flat_z) ? height_fn(i, j) : flat_z)};
            float uv[2] = {(float)i / nx, (float)j / ny};
            tsr_mesh_add_vertex(m, p, NULL, uv);
        }
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++) {
            uint32_t a = j * (nx + 1) + i, b = a + 1, c = a + nx + 1, d = c + 1;
            int t = 2 * (j * nx + i);
            if (!keep || keep[t])
                tsr_mesh_add_triangle(m, a, b, d);
            if (!keep || keep[t + 1])
                tsr_mesh_add_triangle(m, a, d, c);
        }
    if (attrs & TSR_MESH_NORMALS)
        tsr_mesh_compute_normals(m);
}

/* keep[] for whole cells: cell (i, j) removed where pattern[j][i] == '.' */
static bool *cells_from(const char *const *rows, int nx, int ny)
{
    bool *k = calloc((size_t)2 * nx * ny, sizeof *k);
    for (int j = 0; j < ny; j++)
        for (int i = 0; i < nx; i++)
            k[2 * (j * nx + i)] = k[2 * (j * nx + i) + 1] = rows[j][i] != '.';
    return k;
}

/* ---- Oracles -------------------------------------------------------------- */

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static size_t count_key(const uint64_t *k, size_t n, uint64_t key)
{
    size_t lo = 0, hi = n;
    while (lo < hi) {
        size_t mid = (lo + hi) / 2;
        if (k[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    size_t c = 0;
    while (lo + c < n && k[lo + c] == key)
        c++;
    return c;
}

/* Directed edges by vertex id (ids: vertex index, or first vertex at the
 * same position): unique is "each directed edge once and its reverse
 * once", balanced is "as many times as its reverse". */
static void directed_edges(const tsr_mesh *m, bool by_position, bool *unique, bool *balanced)
{
    uint32_t *id = malloc(m->vertex_count * sizeof *id);
    for (uint32_t v = 0; v < m->vertex_count; v++) {
        id[v] = v;
        if (by_position)
            for (uint32_t u = 0; u < v; u++)
                if (!memcmp(m->positions + 3 * u, m->positions + 3 * v, 3 * sizeof(float))) {
                    id[v] = u;
                    break;
                }
    }
    size_t n = 3 * (size_t)m->triangle_count;
    uint64_t *k = malloc(n * sizeof *k);
    for (size_t h = 0; h < n; h++) {
        uint32_t a = id[m->indices[h]], b = id[m->indices[h / 3 * 3 + (h % 3 + 1) % 3]];
        k[h] = (uint64_t)a << 32 | b;
    }
    qsort(k, n, sizeof *k, cmp_u64);
    *unique = *balanced = true;
    for (size_t h = 0; h < n; h++) {
        uint64_t rev = (k[h] << 32) | (k[h] >> 32);
        size_t fw = count_key(k, n, k[h]), bw = count_key(k, n, rev);
        if (fw != 1 || bw != 1)
            *unique = false;
        if (fw != bw)
            *balanced = false;
        if ((uint32_t)k[h] == (uint32_t)(k[h] >> 32))
            *unique = *balanced = false;
    }
    free(k);
    free(id);
}

static double signed_volume(const tsr_mesh *m)
{
    double v = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *p = m->positions + 3 * m->indices[3 * t], *q = m->positions + 3 * m->indices[3 * t + 1],
                    *r = m->positions + 3 * m->indices[3 * t + 2];
        v += (double)p[0] * ((double)q[1] * r[2] - (double)q[2] * r[1]) -
             (double)p[1] * ((double)q[0] * r[2] - (double)q[2] * r[0]) +
             (double)p[2] * ((double)q[0] * r[1] - (double)q[1] * r[0]);
    }
    return v / 6;
}

static double xy_area(const float *p, const float *q, const float *r)
{
    return 0.5 * (((double)q[0] - p[0]) * ((double)r[1] - p[1]) - ((double)q[1] - p[1]) * ((double)r[0] - p[0]));
}

/* The volume between the top triangles and z = base: over each, its
 * projected area times the mean height above base (exact for a linear
 * top). Also the top's projected area. */
static double prisms(const tsr_mesh *m, double base, double *area)
{
    double v = 0;
    *area = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *p = m->positions + 3 * m->indices[3 * t], *q = m->positions + 3 * m->indices[3 * t + 1],
                    *r = m->positions + 3 * m->indices[3 * t + 2];
        double a = xy_area(p, q, r);
        *area += a;
        v += a * (((double)p[2] + q[2] + r[2]) / 3 - base);
    }
    return v;
}

static uint32_t find(uint32_t *parent, uint32_t x)
{
    while (parent[x] != x)
        x = parent[x] = parent[parent[x]];
    return x;
}

/* V - E + F over referenced vertices and distinct undirected edges, and
 * the number of connected components (through triangles). */
static long euler(const tsr_mesh *m, uint32_t *components)
{
    bool *used = calloc(m->vertex_count, 1);
    uint32_t *parent = malloc(m->vertex_count * sizeof *parent);
    for (uint32_t v = 0; v < m->vertex_count; v++)
        parent[v] = v;
    size_t n = 3 * (size_t)m->triangle_count;
    uint64_t *k = malloc(n * sizeof *k);
    for (size_t h = 0; h < n; h++) {
        uint32_t a = m->indices[h], b = m->indices[h / 3 * 3 + (h % 3 + 1) % 3];
        used[a] = true;
        k[h] = a < b ? (uint64_t)a << 32 | b : (uint64_t)b << 32 | a;
        parent[find(parent, a)] = find(parent, b);
    }
    qsort(k, n, sizeof *k, cmp_u64);
    long e = 0, v = 0;
    for (size_t h = 0; h < n; h++)
        e += h == 0 || k[h] != k[h - 1];
    *components = 0;
    for (uint32_t i = 0; i < m->vertex_count; i++) {
        v += used[i];
        *components += used[i] && find(parent, i) == i;
    }
    free(k);
    free(parent);
    free(used);
    return v - e + (long)m->triangle_count;
}

/* Every check that holds for any successful result; returns the bottom's
 * area. pinched: loops touch at vertices, so by position edges are only
 * balanced. */
static void check_solid(const tsr_mesh *before, const tsr_mesh *m, double base, bool pinched)
{
    double top_area, expect = prisms(before, base, &top_area);
    double vol = signed_volume(m);
    CHECK_MSG(fabs(vol - expect) <= 1e-9 * fabs(expect) + 1e-9, "volume %.17g, prisms %.17g", vol, expect);
    CHECK(vol > 0);
    bool unique, balanced;
    directed_edges(m, false, &unique, &balanced);
    CHECK_MSG(unique, "not a closed 2-manifold by index");
    directed_edges(m, true, &unique, &balanced);
    CHECK_MSG(balanced, "not closed by position");
    if (!pinched)
        CHECK_MSG(unique, "not a closed 2-manifold by position");

    /* The top is unchanged, and the added vertices are at base. */
    CHECK(m->vertex_count > before->vertex_count && m->triangle_count > before->triangle_count);
    CHECK(!memcmp(m->positions, before->positions, 3 * sizeof(float) * before->vertex_count));
    CHECK(!memcmp(m->indices, before->indices, 3 * sizeof(uint32_t) * before->triangle_count));
    for (uint32_t v = before->vertex_count; v < m->vertex_count; v++)
        CHECK(m->positions[3 * v + 2] == (float)base);

    /* Added triangles: vertical walls or a bottom facing -z, and the
     * bottom covers exactly the top's projection. Bottom vertices are all
     * wall vertices (no T-junction, no Steiner point). */
    double bottom_area = 0;
    bool *on_wall = calloc(m->vertex_count, 1), *on_bottom = calloc(m->vertex_count, 1);
    for (uint32_t t = before->triangle_count; t < m->triangle_count; t++) {
        const uint32_t *ix = m->indices + 3 * t;
        const float *p = m->positions + 3 * ix[0], *q = m->positions + 3 * ix[1], *r = m->positions + 3 * ix[2];
        bool bottom = p[2] == (float)base && q[2] == (float)base && r[2] == (float)base;
        double a = xy_area(p, q, r);
        if (bottom) {
            CHECK_MSG(a < 0, "bottom triangle %u does not face -z", t);
            bottom_area -= a;
        } else {
            CHECK_MSG(fabs(a) < 1e-9, "wall triangle %u is not vertical", t);
        }
        for (int j = 0; j < 3; j++)
            (bottom ? on_bottom : on_wall)[ix[j]] = true;
    }
    for (uint32_t v = before->vertex_count; v < m->vertex_count; v++)
        CHECK(on_wall[v] && on_bottom[v]);
    free(on_wall);
    free(on_bottom);
    CHECK_NEAR(bottom_area, top_area, 1e-9 * top_area);

    tsr_validation val;
    CHECK(tsr_mesh_validate(m, NULL, &val) == TSR_OK);
    char msg[512];
    tsr_validation_describe(&val, msg, sizeof msg);
    CHECK_MSG(tsr_validation_ok(&val), "%s", msg);
    CHECK_MSG(val.boundary_edges == 0 && val.boundary_loops == 0, "%u boundary edges", val.boundary_edges);
    CHECK(val.t_junctions == 0);
    if (!pinched)
        CHECK(val.coincident_vertices == 0);
}

static void copy_mesh(tsr_mesh *dst, const tsr_mesh *src)
{
    tsr_mesh_init(dst, 0, NULL);
    tsr_mesh_reserve(dst, src->vertex_count, src->triangle_count);
    memcpy(dst->positions, src->positions, 3 * sizeof(float) * src->vertex_count);
    memcpy(dst->indices, src->indices, 3 * sizeof(uint32_t) * src->triangle_count);
    dst->vertex_count = src->vertex_count;
    dst->triangle_count = src->triangle_count;
}

/* Closes m at base and runs the checks; returns V - E + F. */
static long close_and_check(tsr_mesh *m, double base, bool pinched, uint32_t *components)
{
    tsr_mesh before;
    copy_mesh(&before, m);
    tsr_error err = {0};
    tsr_status s = tsr_mesh_add_base(m, base, &err);
    CHECK_MSG(s == TSR_OK, "%s", err.message);
    long chi = 0;
    if (s == TSR_OK) {
        check_solid(&before, m, base, pinched);
        chi = euler(m, components);
    }
    tsr_mesh_free(&before);
    return chi;
}

/* ---- Cases ------------------------------------------------------------------ */

TEST(grid_heightfield)
{
    tsr_mesh m;
    grid_mesh(&m, 0, 9, 7, NULL, NAN);
    uint32_t nv = m.vertex_count, comps = 0;
    long chi = close_and_check(&m, -1.5, false, &comps);
    CHECK(chi == 2 && comps == 1);
    /* one bottom vertex per boundary vertex, 2 wall triangles per boundary
     * edge, and a bottom of n + 2h - 2 triangles (n = 32 corners, h = 0) */
    CHECK(m.vertex_count == nv + 32);
    CHECK(m.triangle_count == 2 * 9 * 7 + 2 * 32 + 30);
    tsr_mesh_free(&m);
}

TEST(flat_top_volume_is_area_times_height)
{
    tsr_mesh m;
    grid_mesh(&m, 0, 5, 4, NULL, 2.5);
    tsr_error err;
    CHECK(tsr_mesh_add_base(&m, -0.5, &err) == TSR_OK);
    CHECK_NEAR(signed_volume(&m), 5 * 4 * 3.0, 1e-9);
    tsr_mesh_free(&m);
}

TEST(hole_makes_genus_one)
{
    static const char *rows[] = {"######", "######", "##..##", "##..##", "######", "######"};
    bool *keep = cells_from(rows, 6, 6);
    tsr_mesh m;
    grid_mesh(&m, 0, 6, 6, keep, NAN);
    uint32_t comps = 0;
    long chi = close_and_check(&m, 0, false, &comps);
    CHECK_MSG(chi == 0 && comps == 1, "chi %ld, %u components", chi, comps);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(two_components)
{
    static const char *rows[] = {"###.####", "###.####", "###.####", "###....."};
    bool *keep = cells_from(rows, 8, 4);
    tsr_mesh m;
    grid_mesh(&m, 0, 8, 4, keep, NAN);
    uint32_t comps = 0;
    long chi = close_and_check(&m, 1.0, false, &comps);
    CHECK_MSG(chi == 4 && comps == 2, "chi %ld, %u components", chi, comps);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(notched_boundary)
{
    /* non-convex outline: a notch from the top, an L-shaped corner cut */
    static const char *rows[] = {"###..###", "###..###", "########", "########", "####....", "####...."};
    bool *keep = cells_from(rows, 8, 6);
    tsr_mesh m;
    grid_mesh(&m, 0, 8, 6, keep, NAN);
    uint32_t comps = 0;
    long chi = close_and_check(&m, -0.25, false, &comps);
    CHECK_MSG(chi == 2 && comps == 1, "chi %ld, %u components", chi, comps);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(island_in_a_hole)
{
    /* a ring with an island in its hole: even-odd nesting puts the island's
     * bottom in, the gap out */
    static const char *rows[] = {"#######", "#.....#", "#.....#", "#..#..#", "#.....#", "#.....#", "#######"};
    bool *keep = cells_from(rows, 7, 7);
    tsr_mesh m;
    grid_mesh(&m, 0, 7, 7, keep, NAN);
    uint32_t comps = 0;
    long chi = close_and_check(&m, 0.5, false, &comps);
    CHECK_MSG(chi == 0 + 2 && comps == 2, "chi %ld, %u components", chi, comps);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(diagonal_holes_pinch)
{
    /* two missing cells meeting at one corner: the hole's loop visits that
     * vertex twice, which gets two bottom vertices */
    static const char *rows[] = {"#####", "#.###", "##.##", "#####", "#####"};
    bool *keep = cells_from(rows, 5, 5);
    tsr_mesh m;
    grid_mesh(&m, 0, 5, 5, keep, NAN);
    uint32_t comps = 0;
    close_and_check(&m, 0, true, &comps);
    CHECK(comps == 1);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(bowtie_outer_pinch)
{
    /* two cells touching at a corner of the outline */
    static const char *rows[] = {"#.", ".#"};
    bool *keep = cells_from(rows, 2, 2);
    tsr_mesh m;
    grid_mesh(&m, 0, 2, 2, keep, NAN);
    uint32_t comps = 0;
    close_and_check(&m, 0, true, &comps);
    tsr_mesh_free(&m);
    free(keep);
}

TEST(reflex_pinch)
{
    /* an L of three unit squares around the origin (a 270-degree corner)
     * and a thin triangle touching it only at the origin, inside the
     * fourth quadrant; built in both orders so either corner is met first */
    const float p[][3] = {{0, 0, 1},  {1, 0, 1},   {1, 1, 1},  {0, 1, 1},     {-1, 1, 1},
                          {-1, 0, 1}, {-1, -1, 1}, {0, -1, 1}, {1, -0.8f, 2}, {1, -0.2f, 2}};
    const uint32_t l[][3] = {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 5}, {0, 5, 6}, {0, 6, 7}};
    const uint32_t thin[3] = {0, 8, 9};
    for (int order = 0; order < 2; order++) {
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        for (int i = 0; i < 10; i++)
            tsr_mesh_add_vertex(&m, p[i], NULL, NULL);
        if (order == 0)
            tsr_mesh_add_triangle(&m, thin[0], thin[1], thin[2]);
        for (int t = 0; t < 6; t++)
            tsr_mesh_add_triangle(&m, l[t][0], l[t][1], l[t][2]);
        if (order == 1)
            tsr_mesh_add_triangle(&m, thin[0], thin[1], thin[2]);
        uint32_t comps = 0;
        close_and_check(&m, 0, true, &comps);
        tsr_mesh_free(&m);
    }
}

TEST(normals_and_uvs_of_new_vertices)
{
    tsr_mesh m;
    grid_mesh(&m, TSR_MESH_NORMALS | TSR_MESH_UVS, 4, 3, NULL, NAN);
    uint32_t nv = m.vertex_count;
    float *top_normals = malloc(3 * sizeof(float) * nv);
    memcpy(top_normals, m.normals, 3 * sizeof(float) * nv);
    uint32_t comps;
    close_and_check(&m, 0, false, &comps);
    CHECK(!memcmp(m.normals, top_normals, 3 * sizeof(float) * nv));
    for (uint32_t v = nv; v < m.vertex_count; v++) {
        const float *n = m.normals + 3 * v, *p = m.positions + 3 * v;
        CHECK_NEAR(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1, 1e-6);
        CHECK_NEAR(n[2], -sqrt(0.5), 1e-6);
        /* outward: away from the grid's centre (2, 1.5) */
        CHECK(n[0] * (p[0] - 2) + n[1] * (p[1] - 1.5) > 0);
        /* a side vertex's bevel is perpendicular to its side */
        if (p[0] == 0 && p[1] > 0 && p[1] < 3)
            CHECK_NEAR(n[0], -sqrt(0.5), 1e-6);
        /* uv of the vertex above */
        CHECK_NEAR(m.uvs[2 * v], p[0] / 4, 1e-7);
        CHECK_NEAR(m.uvs[2 * v + 1], p[1] / 3, 1e-7);
    }
    free(top_normals);
    tsr_mesh_free(&m);
}

TEST(random_masks)
{
    /* random triangles removed from a grid: holes, notches, islands and
     * pinches (up to three fans at a vertex) of every kind */
    uint32_t seed = 12345;
    int runs = 0;
    for (int it = 0; it < 150; it++) {
        int nx = 4 + it % 9, ny = 3 + it % 7;
        bool *keep = malloc((size_t)2 * nx * ny);
        int kept = 0;
        for (int t = 0; t < 2 * nx * ny; t++) {
            seed = seed * 1664525u + 1013904223u;
            keep[t] = (seed >> 8) % 100 < 70u + (unsigned)(it % 4) * 8;
            kept += keep[t];
        }
        if (kept == 0) {
            free(keep);
            continue;
        }
        tsr_mesh m;
        grid_mesh(&m, 0, nx, ny, keep, NAN);
        uint32_t comps;
        int before = check_failures;
        close_and_check(&m, -2, true, &comps);
        if (check_failures > before)
            fprintf(stderr, "random mask %d (%dx%d) failed\n", it, nx, ny);
        runs++;
        tsr_mesh_free(&m);
        free(keep);
    }
    CHECK(runs > 100);
}

/* ---- Refusals ----------------------------------------------------------- */

static void check_refused(tsr_mesh *m, double base, tsr_status want, const char *word)
{
    uint32_t nv = m->vertex_count, nt = m->triangle_count;
    tsr_error err = {0};
    tsr_status s = tsr_mesh_add_base(m, base, &err);
    CHECK_MSG(s == want, "status %d (%s), wanted %d", (int)s, err.message, (int)want);
    CHECK_MSG(strstr(err.message, word) != NULL, "message \"%s\" lacks \"%s\"", err.message, word);
    CHECK(m->vertex_count == nv && m->triangle_count == nt);
}

TEST(base_not_below_mesh)
{
    tsr_mesh m;
    grid_mesh(&m, 0, 3, 3, NULL, 1.0);
    check_refused(&m, 1.0, TSR_ERR_ARGUMENT, "below");
    check_refused(&m, 2.0, TSR_ERR_ARGUMENT, "below");
    check_refused(&m, 1.0 - 1e-12, TSR_ERR_ARGUMENT, "below"); /* equal as a float */
    check_refused(&m, NAN, TSR_ERR_ARGUMENT, "finite");
    check_refused(&m, -INFINITY, TSR_ERR_ARGUMENT, "finite");
    CHECK(tsr_mesh_add_base(&m, 0.999, NULL) == TSR_OK);
    tsr_mesh_free(&m);
}

TEST(bad_meshes_refused)
{
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    check_refused(&m, 0, TSR_ERR_ARGUMENT, "no triangle");
    tsr_mesh_free(&m);

    grid_mesh(&m, 0, 2, 2, NULL, 1.0);
    float p[3] = {0.5f, 0.5f, 2};
    uint32_t x = tsr_mesh_add_vertex(&m, p, NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 4, x); /* a third triangle on edge 0-4 */
    check_refused(&m, 0, TSR_ERR_INVALID_MESH, "more than two");
    tsr_mesh_free(&m);

    grid_mesh(&m, 0, 2, 2, NULL, 1.0);
    uint32_t t = m.indices[4];
    m.indices[4] = m.indices[5];
    m.indices[5] = t; /* one triangle flipped */
    check_refused(&m, 0, TSR_ERR_INVALID_MESH, "same way");
    tsr_mesh_free(&m);

    grid_mesh(&m, 0, 2, 2, NULL, 1.0);
    m.indices[7] = m.indices[6]; /* repeated index */
    check_refused(&m, 0, TSR_ERR_INVALID_MESH, "repeats");
    tsr_mesh_free(&m);

    grid_mesh(&m, 0, 2, 2, NULL, 1.0);
    m.positions[5] = NAN;
    check_refused(&m, 0, TSR_ERR_ARGUMENT, "non-finite");
    tsr_mesh_free(&m);

    /* two overlapping squares: not a height field */
    tsr_mesh_init(&m, 0, NULL);
    float q[8][3] = {{0, 0, 1}, {2, 0, 1}, {2, 2, 1}, {0, 2, 1}, {1, 1, 2}, {3, 1, 2}, {3, 3, 2}, {1, 3, 2}};
    for (int i = 0; i < 8; i++)
        tsr_mesh_add_vertex(&m, q[i], NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 1, 2);
    tsr_mesh_add_triangle(&m, 0, 2, 3);
    tsr_mesh_add_triangle(&m, 4, 5, 6);
    tsr_mesh_add_triangle(&m, 4, 6, 7);
    check_refused(&m, 0, TSR_ERR_INVALID_MESH, "height field");
    tsr_mesh_free(&m);

    CHECK(tsr_mesh_add_base(NULL, 0, NULL) == TSR_ERR_ARGUMENT);
}

TEST(closed_mesh_left_alone)
{
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    float p[4][3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {0, 0, 2}};
    for (int i = 0; i < 4; i++)
        tsr_mesh_add_vertex(&m, p[i], NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 2, 1);
    tsr_mesh_add_triangle(&m, 0, 1, 3);
    tsr_mesh_add_triangle(&m, 1, 2, 3);
    tsr_mesh_add_triangle(&m, 2, 0, 3);
    CHECK(tsr_mesh_add_base(&m, 0, NULL) == TSR_OK);
    CHECK(m.vertex_count == 4 && m.triangle_count == 4);
    tsr_mesh_free(&m);
}

/* tsr_mesh_split_flat on a closed grid (a 4 x 3 rectangle): the walls
 * and the bottom shade flat, the top keeps its vertices and normals, every
 * corner stays where it was. Each top rim vertex gains one vertex per wall
 * direction meeting there (2 at the 4 corners, 1 on the 10 side
 * vertices); each bottom vertex is split between the bottom and its wall
 * directions, keeping its index for the first: 36 new vertices. */
TEST(split_flat_walls_and_bottom)
{
    tsr_mesh m;
    grid_mesh(&m, TSR_MESH_NORMALS | TSR_MESH_UVS, 4, 3, NULL, NAN);
    uint32_t ntop = m.triangle_count;
    tsr_error err = {0};
    CHECK(tsr_mesh_add_base(&m, 0, &err) == TSR_OK);
    uint32_t nv = m.vertex_count, nt = m.triangle_count;
    CHECK(nv == 20 + 14);
    float *pos = malloc(9 * sizeof(float) * nt), *nrm = malloc(9 * sizeof(float) * ntop);
    uint32_t *idx = malloc(3 * sizeof(uint32_t) * ntop);
    for (uint32_t c = 0; c < 3 * nt; c++)
        memcpy(pos + 3 * c, m.positions + 3 * m.indices[c], 3 * sizeof(float));
    for (uint32_t c = 0; c < 3 * ntop; c++) {
        idx[c] = m.indices[c];
        memcpy(nrm + 3 * c, m.normals + 3 * m.indices[c], 3 * sizeof(float));
    }
    CHECK_MSG(tsr_mesh_split_flat(&m, ntop, 1, &err) == TSR_OK, "%s", err.message);
    CHECK(m.triangle_count == nt);
    CHECK_MSG(m.vertex_count == nv + 36, "%u vertices, want %u + 36", m.vertex_count, nv);
    uint32_t moved = 0, top_changed = 0, smeared = 0;
    for (uint32_t c = 0; c < 3 * nt; c++)
        moved += memcmp(pos + 3 * c, m.positions + 3 * m.indices[c], 3 * sizeof(float)) != 0;
    for (uint32_t c = 0; c < 3 * ntop; c++)
        top_changed += idx[c] != m.indices[c] || memcmp(nrm + 3 * c, m.normals + 3 * m.indices[c], 12) != 0;
    for (uint32_t t = ntop; t < nt; t++) {
        const float *p[3];
        for (int k = 0; k < 3; k++)
            p[k] = m.positions + 3 * m.indices[3 * t + k];
        double a[3], b[3], n[3];
        for (int k = 0; k < 3; k++) {
            a[k] = p[1][k] - p[0][k];
            b[k] = p[2][k] - p[0][k];
        }
        n[0] = a[1] * b[2] - a[2] * b[1];
        n[1] = a[2] * b[0] - a[0] * b[2];
        n[2] = a[0] * b[1] - a[1] * b[0];
        double l = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
        for (int k = 0; k < 3; k++) {
            const float *q = m.normals + 3 * m.indices[3 * t + k];
            smeared += (q[0] * n[0] + q[1] * n[1] + q[2] * n[2]) / l < 1 - 1e-6;
        }
        /* and no top vertex is used by a wall or the bottom */
        for (int k = 0; k < 3; k++)
            moved += m.indices[3 * t + k] < 20;
    }
    CHECK_MSG(moved == 0, "%u corners moved", moved);
    CHECK_MSG(top_changed == 0, "%u top corners changed", top_changed);
    CHECK_MSG(smeared == 0, "%u wall or bottom corners not their face's normal", smeared);
    for (uint32_t v = nv; v < m.vertex_count; v++) /* uv of the vertex copied: the one above */
        CHECK_NEAR(m.uvs[2 * v], m.positions[3 * v] / 4, 1e-7);
    tsr_mesh_free(&m);
    /* 180 degrees: one vertex per rim vertex for the walls, the bottom's kept */
    grid_mesh(&m, TSR_MESH_NORMALS, 4, 3, NULL, NAN);
    CHECK(tsr_mesh_add_base(&m, 0, &err) == TSR_OK);
    CHECK(tsr_mesh_split_flat(&m, ntop, 180, &err) == TSR_OK);
    CHECK_MSG(m.vertex_count == nv + 14, "180: %u vertices", m.vertex_count);
    /* refusals */
    CHECK(tsr_mesh_split_flat(&m, m.triangle_count + 1, 1, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_mesh_split_flat(&m, 0, -1, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_mesh_split_flat(&m, 0, NAN, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_mesh_split_flat(NULL, 0, 1, &err) == TSR_ERR_ARGUMENT);
    tsr_mesh_free(&m);
    grid_mesh(&m, 0, 4, 3, NULL, NAN);
    CHECK(tsr_mesh_add_base(&m, 0, &err) == TSR_OK);
    CHECK(tsr_mesh_split_flat(&m, ntop, 1, &err) == TSR_ERR_ARGUMENT);
    tsr_mesh_free(&m);
    free(pos);
    free(nrm);
    free(idx);
}

/* tsr_mesh_split_flat with a triangle without area met first at its
 * vertices: it joins the first real face's group (it makes none of its
 * own, and takes none of theirs); and an index beyond the vertices, in the
 * faces kept or those split, is refused. */
TEST(split_flat_degenerate_and_bad_index)
{
    static const float P[5][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {1, 0, 0}};
    for (int wide = 0; wide < 2; wide++) {
        tsr_mesh m;
        tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
        const float up[3] = {0, 0, 1};
        for (int k = 0; k < 5; k++)
            tsr_mesh_add_vertex(&m, P[k], up, NULL);
        tsr_mesh_add_triangle(&m, 0, 1, 4); /* no area (4 is where 1 is) */
        tsr_mesh_add_triangle(&m, 0, 1, 2); /* facing +z */
        tsr_mesh_add_triangle(&m, 0, 3, 1); /* facing +y */
        tsr_error err = {0};
        CHECK_MSG(tsr_mesh_split_flat(&m, 0, wide ? 120 : 1, &err) == TSR_OK, "%s", err.message);
        if (!wide) {
            /* 0 and 1 split between +z and +y; the flat triangle on the first */
            CHECK_MSG(m.vertex_count == 7, "%u vertices", m.vertex_count);
            CHECK(m.indices[0] == m.indices[3] && m.indices[1] == m.indices[4]);
            CHECK(m.indices[0] != m.indices[6] && m.indices[1] != m.indices[8]);
            const float *n0 = m.normals + 3 * m.indices[3], *n2 = m.normals + 3 * m.indices[6];
            CHECK(n0[0] == 0 && n0[1] == 0 && n0[2] == 1);
            CHECK_NEAR(n2[1], 1, 1e-7);
        } else {
            /* 120 degrees: +z and +y together, nothing split */
            CHECK_MSG(m.vertex_count == 5, "%u vertices", m.vertex_count);
            const float *n0 = m.normals;
            CHECK_NEAR(n0[1], sqrt(0.5), 1e-7);
            CHECK_NEAR(n0[2], sqrt(0.5), 1e-7);
        }
        tsr_mesh_free(&m);
    }
    for (int kept = 0; kept < 2; kept++) {
        tsr_mesh m;
        tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
        const float up[3] = {0, 0, 1};
        for (int k = 0; k < 3; k++)
            tsr_mesh_add_vertex(&m, P[k], up, NULL);
        tsr_mesh_add_triangle(&m, 0, 1, 2);
        tsr_mesh_add_triangle(&m, 0, 2, 1);
        m.indices[kept ? 1 : 4] = 1000000; /* beyond the vertices */
        tsr_error err = {0};
        CHECK(tsr_mesh_split_flat(&m, 1, 1, &err) == TSR_ERR_INVALID_MESH);
        CHECK(m.vertex_count == 3);
        tsr_mesh_free(&m);
    }
}

TEST_MAIN(T(grid_heightfield), T(flat_top_volume_is_area_times_height), T(hole_makes_genus_one), T(two_components),
          T(notched_boundary), T(island_in_a_hole), T(diagonal_holes_pinch), T(bowtie_outer_pinch), T(reflex_pinch),
          T(normals_and_uvs_of_new_vertices), T(random_masks), T(base_not_below_mesh), T(bad_meshes_refused),
          T(closed_mesh_left_alone), T(split_flat_walls_and_bottom),
          T(split_flat_degenerate_and_bad_index))
