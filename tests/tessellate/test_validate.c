/* Validation checks, each against meshes whose defects are known by
 * construction: the oracle is how the mesh was built. */
#include "check.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "tessellate/tessellate.h"

/* An n x n grid of unit quads in the z = 0 plane, two CCW triangles each. */
static void grid(tsr_mesh *m, int n)
{
    tsr_mesh_init(m, 0, NULL);
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            float p[3] = {(float)i, (float)j, 0};
            tsr_mesh_add_vertex(m, p, NULL, NULL);
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            uint32_t a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            tsr_mesh_add_triangle(m, a, b, d);
            tsr_mesh_add_triangle(m, a, d, c);
        }
}

static tsr_validation validate(const tsr_mesh *m, bool up)
{
    tsr_validation v;
    tsr_validate_options o = {0};
    o.expect_up = up;
    CHECK(tsr_mesh_validate(m, &o, &v) == TSR_OK);
    return v;
}

TEST(grid_is_valid)
{
    tsr_mesh m;
    grid(&m, 8);
    tsr_validation v = validate(&m, true);
    char msg[512];
    tsr_validation_describe(&v, msg, sizeof msg);
    CHECK_MSG(tsr_validation_ok(&v), "%s", msg);
    CHECK(v.vertices == 81 && v.triangles == 128);
    CHECK(v.edges == 8 * 9 * 2 + 64);
    CHECK(v.euler == 1);
    CHECK(v.boundary_loops == 1 && v.loop_length[0] == 32 && v.boundary_edges == 32);
    CHECK(tsr_mesh_boundary_is_rect(&m, 0, 0, 8, 8, 1e-6, NULL));
    CHECK(!tsr_mesh_boundary_is_rect(&m, 0, 0, 9, 8, 1e-6, NULL));
    tsr_mesh_free(&m);
}

TEST(flipped_triangle)
{
    tsr_mesh m;
    grid(&m, 4);
    uint32_t *t = m.indices + 3 * 5;
    uint32_t tmp = t[1];
    t[1] = t[2];
    t[2] = tmp;
    tsr_validation v = validate(&m, true);
    CHECK(!tsr_validation_ok(&v));
    CHECK(v.misoriented_edges == 3);
    CHECK(v.downward_triangles == 1 && v.first_downward == 5);
    tsr_mesh_free(&m);
}

TEST(nonmanifold_edge)
{
    tsr_mesh m;
    grid(&m, 2);
    float p[3] = {0.5f, 0.5f, 1};
    uint32_t x = tsr_mesh_add_vertex(&m, p, NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 4, x); /* third triangle on the interior edge 0-4 */
    tsr_validation v = validate(&m, false);
    CHECK(v.nonmanifold_edges == 1);
    CHECK(v.first_nonmanifold[0] == 0 && v.first_nonmanifold[1] == 4);
    CHECK(!tsr_validation_ok(&v));
    tsr_mesh_free(&m);
}

TEST(coincident_sheets_no_t_junction)
{
    /* A closed two-sided square: the front as two triangles along the
     * diagonal (0,0)-(2,2), the back, facing the other way, as a fan about
     * (1, 1), which lies on the front's diagonal. Every edge is shared by
     * two triangles: no gap anywhere, so no T-junction, though the centre
     * vertex lies inside the diagonal. */
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    float pts[][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}, {1, 1, 0}};
    for (int i = 0; i < 5; i++)
        tsr_mesh_add_vertex(&m, pts[i], NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 1, 3);
    tsr_mesh_add_triangle(&m, 0, 3, 2);
    tsr_mesh_add_triangle(&m, 1, 0, 4);
    tsr_mesh_add_triangle(&m, 3, 1, 4);
    tsr_mesh_add_triangle(&m, 2, 3, 4);
    tsr_mesh_add_triangle(&m, 0, 2, 4);
    tsr_validation v = validate(&m, false);
    CHECK(v.t_junctions == 0);
    CHECK(v.boundary_edges == 0);
    CHECK(v.nonmanifold_edges == 0 && v.misoriented_edges == 0);
    /* the front's diagonal split at the centre on one side only: the front
     * becomes (0,1,3) and (0,4,2), (4,3,2): the edge 0-3 is open now and
     * the centre vertex lies inside it, a real T-junction */
    m.indices[3] = 0, m.indices[4] = 4, m.indices[5] = 2;
    tsr_mesh_add_triangle(&m, 4, 3, 2);
    v = validate(&m, false);
    CHECK(v.t_junctions == 1);
    CHECK(v.first_t_junction[0] == 4);
    tsr_mesh_free(&m);
}

TEST(t_junction)
{
    /* Left: one square as two triangles; right: two squares stacked, each
     * half the height. The right column's middle vertex (2, 1) lies on the
     * left square's edge (2,0)-(2,2): a T-junction and a crack. */
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    float pts[][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}, {3, 0, 0}, {3, 1, 0}, {3, 2, 0}, {2, 1, 0}};
    for (int i = 0; i < 8; i++)
        tsr_mesh_add_vertex(&m, pts[i], NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 1, 3);
    tsr_mesh_add_triangle(&m, 0, 3, 2);
    tsr_mesh_add_triangle(&m, 1, 4, 5);
    tsr_mesh_add_triangle(&m, 1, 5, 7);
    tsr_mesh_add_triangle(&m, 7, 5, 6);
    tsr_mesh_add_triangle(&m, 7, 6, 3);
    tsr_validation v = validate(&m, true);
    CHECK(v.t_junctions == 1);
    CHECK(v.first_t_junction[0] == 7);
    CHECK(!tsr_validation_ok(&v));
    /* The fix: split the left square's right triangle at (2, 1). */
    m.indices[0 * 3 + 0] = 0; m.indices[1] = 1; m.indices[2] = 7;
    tsr_mesh_add_triangle(&m, 0, 7, 3);
    v = validate(&m, true);
    char msg[512];
    tsr_validation_describe(&v, msg, sizeof msg);
    CHECK_MSG(tsr_validation_ok(&v), "%s", msg);
    CHECK(v.boundary_loops == 1);
    tsr_mesh_free(&m);
}

TEST(t_junction_in_3d_long_edge)
{
    /* A long edge far from the vertex cloud's typical spacing still finds
     * the vertex on it (the brute-force path of the spatial search). */
    tsr_mesh m;
    grid(&m, 40);
    /* a big triangle below the grid sharing no vertex, with one grid
     * vertex exactly on its long edge */
    float a[3] = {-1, 20, 0}, b[3] = {41, 20, 0}, c[3] = {20, 19.5f, -5};
    uint32_t ia = tsr_mesh_add_vertex(&m, a, NULL, NULL), ib = tsr_mesh_add_vertex(&m, b, NULL, NULL),
             ic = tsr_mesh_add_vertex(&m, c, NULL, NULL);
    tsr_mesh_add_triangle(&m, ia, ib, ic);
    tsr_validation v = validate(&m, false);
    CHECK(v.t_junctions == 41); /* every grid vertex of row 20 */
    tsr_mesh_free(&m);
}

static tsr_validation validate_hf(const tsr_mesh *m)
{
    tsr_validation v;
    tsr_validate_options o = {0};
    o.expect_up = true;
    o.height_field = true;
    CHECK(tsr_mesh_validate(m, &o, &v) == TSR_OK);
    return v;
}

TEST(height_field_junctions_in_xy)
{
    /* The t_junction layout as a terrain: the right column's middle vertex
     * (2, 1) stands 5 above the left square's edge (2,0)-(2,2) at height
     * 0, as a crack between a fine and a coarse tile does. In 3D it lies
     * off the edge; as a height field it is the T-junction it is. */
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    float pts[][3] = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {2, 2, 0}, {3, 0, 0}, {3, 1, 4}, {3, 2, 0}, {2, 1, 5}};
    for (int i = 0; i < 8; i++)
        tsr_mesh_add_vertex(&m, pts[i], NULL, NULL);
    uint32_t tris[][3] = {{0, 1, 3}, {0, 3, 2}, {1, 4, 5}, {1, 5, 7}, {7, 5, 6}, {7, 6, 3}};
    for (int t = 0; t < 6; t++)
        tsr_mesh_add_triangle(&m, tris[t][0], tris[t][1], tris[t][2]);
    CHECK(validate(&m, true).t_junctions == 0);
    tsr_validation v = validate_hf(&m);
    CHECK(v.t_junctions == 1 && v.first_t_junction[0] == 7);
    tsr_mesh_free(&m);

    /* A steep, narrow, valid terrain: samples 1e-4 apart with heights up
     * to 300. Every vertex lies within 1e-6 of the 3D diagonal (3e-4) of
     * some nearly vertical edge, so the 3D test reports junctions that
     * are not there; in xy there are none. */
    grid(&m, 16);
    uint64_t r = 12345;
    for (uint32_t i = 0; i < m.vertex_count; i++) {
        r = r * 6364136223846793005ull + 1442695040888963407ull;
        float *p = m.positions + 3 * i;
        p[0] *= 1e-4f;
        p[1] *= 1e-4f;
        p[2] = (float)((r >> 40) % 300000) * 1e-3f;
    }
    CHECK(validate(&m, false).t_junctions > 0);
    v = validate_hf(&m);
    char msg[512];
    tsr_validation_describe(&v, msg, sizeof msg);
    CHECK_MSG(tsr_validation_ok(&v), "%s", msg);
    CHECK(v.coincident_vertices == 0 && v.boundary_loops == 1);
    tsr_mesh_free(&m);
}

/* A tetrahedron at offset o, facing outward (or inward when in). */
static void add_tetra(tsr_mesh *m, float o, bool in)
{
    float p[4][3] = {{o, 0, 0}, {o + 1, 0, 0}, {o, 1, 0}, {o, 0, 1}};
    uint32_t base = m->vertex_count;
    for (int i = 0; i < 4; i++)
        tsr_mesh_add_vertex(m, p[i], NULL, NULL);
    uint32_t f[4][3] = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}; /* outward */
    for (int t = 0; t < 4; t++)
        tsr_mesh_add_triangle(m, base + f[t][0], base + f[t][in ? 2 : 1], base + f[t][in ? 1 : 2]);
}

TEST(inward_shells_found_and_turned)
{
    /* three bodies: outward, inward, and an open sheet (an inward
     * tetrahedron less one face): only the closed inward one is marked */
    tsr_mesh m;
    tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
    add_tetra(&m, 0, false);
    add_tetra(&m, 3, true);
    add_tetra(&m, 6, true);
    m.triangle_count--; /* the sheet */
    for (uint32_t i = 0; i < m.vertex_count; i++)
        m.normals[3 * i + 2] = 1;
    uint8_t flip[11];
    uint32_t shells = 0;
    CHECK(tsr_mesh_find_inward_shells(&m, flip, &shells) == TSR_OK);
    CHECK(shells == 1);
    for (uint32_t t = 0; t < m.triangle_count; t++)
        CHECK_MSG(flip[t] == (t >= 4 && t < 8), "triangle %u: %d", t, flip[t]);
    tsr_mesh_flip_marked(&m, flip);
    CHECK(tsr_mesh_find_inward_shells(&m, flip, &shells) == TSR_OK && shells == 0);
    for (uint32_t i = 0; i < m.vertex_count; i++)
        CHECK(m.normals[3 * i + 2] == (i >= 4 && i < 8 ? -1 : 1)); /* each vertex negated once */
    tsr_validation v = validate(&m, false);
    CHECK(v.misoriented_edges == 0 && v.boundary_loops == 1);
    tsr_mesh_free(&m);
}

TEST(degenerate_and_duplicate)
{
    tsr_mesh m;
    grid(&m, 3);
    tsr_mesh_add_triangle(&m, 0, 0, 1);   /* repeated index */
    tsr_mesh_add_triangle(&m, 0, 1, 2);   /* collinear: zero area */
    tsr_mesh_add_triangle(&m, 5, 6, 10);  /* same vertex set as triangle 2*(1*3+1) */
    tsr_validation v = validate(&m, false);
    CHECK(v.degenerate_triangles == 2);
    CHECK(v.first_degenerate == 18);
    CHECK(v.duplicate_triangles == 1);
    CHECK(!tsr_validation_ok(&v));
    tsr_mesh_free(&m);
}

TEST(closed_tetrahedron)
{
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    float p[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    for (int i = 0; i < 4; i++)
        tsr_mesh_add_vertex(&m, p[i], NULL, NULL);
    tsr_mesh_add_triangle(&m, 0, 2, 1);
    tsr_mesh_add_triangle(&m, 0, 1, 3);
    tsr_mesh_add_triangle(&m, 1, 2, 3);
    tsr_mesh_add_triangle(&m, 2, 0, 3);
    tsr_validation v = validate(&m, false);
    CHECK(tsr_validation_ok(&v));
    CHECK(v.euler == 2 && v.boundary_edges == 0 && v.boundary_loops == 0 && v.edges == 6);
    /* the half-edge view pairs every half-edge with its reverse */
    tsr_halfedges he;
    CHECK(tsr_halfedges_build(&he, &m, NULL) == TSR_OK);
    for (uint32_t h = 0; h < he.count; h++) {
        uint32_t t = he.twin[h];
        CHECK(t < he.count && he.twin[t] == h);
        CHECK(m.indices[h] == m.indices[3 * (t / 3) + (t % 3 + 1) % 3]);
    }
    tsr_halfedges_free(&he);
    tsr_mesh_free(&m);
}

TEST(holes_count_loops)
{
    /* a 6x6 grid with the triangles of two separate inner squares removed */
    tsr_mesh m;
    grid(&m, 6);
    tsr_mesh out;
    tsr_mesh_init(&out, 0, NULL);
    for (uint32_t i = 0; i < m.vertex_count; i++)
        tsr_mesh_add_vertex(&out, m.positions + 3 * i, NULL, NULL);
    for (uint32_t t = 0; t < m.triangle_count; t++) {
        uint32_t q = t / 2, qi = q % 6, qj = q / 6;
        if ((qi == 1 && qj == 1) || (qi == 4 && qj == 3))
            continue;
        const uint32_t *ix = m.indices + 3 * t;
        tsr_mesh_add_triangle(&out, ix[0], ix[1], ix[2]);
    }
    tsr_validation v = validate(&out, true);
    CHECK(tsr_validation_ok(&v));
    CHECK(v.boundary_loops == 3);
    CHECK(v.euler == 1 - 2); /* a disc with two holes */
    uint32_t bad;
    CHECK(!tsr_mesh_boundary_is_rect(&out, 0, 0, 6, 6, 1e-6, &bad));
    tsr_mesh_free(&m);
    tsr_mesh_free(&out);
}

TEST(coincident_vertices_make_a_crack)
{
    /* two grids side by side, not welded: the seam has coincident vertices
     * and shows as boundary, but no T-junction */
    tsr_mesh m;
    grid(&m, 2);
    uint32_t base = m.vertex_count;
    for (int j = 0; j <= 2; j++)
        for (int i = 0; i <= 2; i++) {
            float p[3] = {(float)(i + 2), (float)j, 0};
            tsr_mesh_add_vertex(&m, p, NULL, NULL);
        }
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 2; i++) {
            uint32_t a = base + j * 3 + i, b = a + 1, c = a + 3, d = c + 1;
            tsr_mesh_add_triangle(&m, a, b, d);
            tsr_mesh_add_triangle(&m, a, d, c);
        }
    tsr_validation v = validate(&m, true);
    CHECK(v.coincident_vertices == 3);
    CHECK(v.t_junctions == 0);
    CHECK(v.boundary_loops == 2);
    tsr_mesh_free(&m);
}

/* Gaps: a strip [0,4] x [0,1] of 4 quads, and above it a strip whose
 * bottom row has 9 vertices, the odd ones raised by 0.01 off the line
 * y = 1 (a curve sampled finer on one side than the other). */
static void gap_strips(tsr_mesh *m, float rise)
{
    tsr_mesh_init(m, 0, NULL);
    for (int j = 0; j <= 1; j++)
        for (int i = 0; i <= 4; i++)
            tsr_mesh_add_vertex(m, (float[3]){(float)i, (float)j, 0}, NULL, NULL);
    for (int i = 0; i < 4; i++) {
        tsr_mesh_add_triangle(m, (uint32_t)i, (uint32_t)i + 1, (uint32_t)i + 6);
        tsr_mesh_add_triangle(m, (uint32_t)i, (uint32_t)i + 6, (uint32_t)i + 5);
    }
    uint32_t b = m->vertex_count;
    for (int j = 0; j <= 1; j++)
        for (int i = 0; i <= 8; i++)
            tsr_mesh_add_vertex(m, (float[3]){0.5f * (float)i, 1 + (float)j + (j == 0 && i % 2 ? rise : 0), 0}, NULL,
                                NULL);
    for (uint32_t i = 0; i < 8; i++) {
        tsr_mesh_add_triangle(m, b + i, b + i + 1, b + i + 10);
        tsr_mesh_add_triangle(m, b + i, b + i + 10, b + i + 9);
    }
}

TEST(gaps_between_open_edges)
{
    tsr_mesh m;
    gap_strips(&m, 0.01f);
    bool *hit = calloc(3 * (size_t)m.triangle_count, sizeof *hit);
    uint32_t n = 99;
    /* the upper strip's 8 short bottom edges lie along the lower strip's
     * 4 long top edges within 0.02, running the other way, and the long
     * ones along the short ones */
    CHECK(tsr_mesh_find_gaps(&m, 0.02, hit, &n) == TSR_OK);
    CHECK_MSG(n == 12, "%u gap edges", n);
    uint32_t upper = 0;
    for (uint32_t h = 0; h < 3 * m.triangle_count; h++)
        upper += hit[h] && h / 3 >= 8 && m.positions[3 * (size_t)m.indices[h] + 1] < 1.5f;
    CHECK_MSG(upper == 8, "%u of them on the upper strip's bottom", upper);
    /* narrower than the rise: none */
    CHECK(tsr_mesh_find_gaps(&m, 0.005, NULL, &n) == TSR_OK);
    CHECK_MSG(n == 0, "%u gap edges at 0.005", n);
    tsr_mesh_free(&m);
    /* the same vertices on the line: still a gap (of width 0), not welded */
    gap_strips(&m, 0);
    CHECK(tsr_mesh_find_gaps(&m, 1e-6, NULL, &n) == TSR_OK && n == 12);
    /* the upper strip facing the other way (its triangles reversed): its
     * rim runs the same way as the lower strip's, on another sheet: the
     * same crack */
    for (uint32_t t = 8; t < m.triangle_count; t++) {
        uint32_t x = m.indices[3 * t + 1];
        m.indices[3 * t + 1] = m.indices[3 * t + 2];
        m.indices[3 * t + 2] = x;
    }
    CHECK(tsr_mesh_find_gaps(&m, 1e-6, NULL, &n) == TSR_OK);
    CHECK_MSG(n == 12, "%u gap edges against a strip facing the other way", n);
    tsr_mesh_free(&m);
    /* both sides cut at interleaved points (0 2 4 6 below, 0 1 3 5 6 above,
     * 0.001 apart): no edge lies along any one edge of the other side, all
     * 7 lie along the other side */
    tsr_mesh_init(&m, 0, NULL);
    const float below[4] = {0, 2, 4, 6}, above[5] = {0, 1, 3, 5, 6};
    for (int i = 0; i < 4; i++) {
        tsr_mesh_add_vertex(&m, (float[3]){below[i], 0, 0}, NULL, NULL);
        tsr_mesh_add_vertex(&m, (float[3]){below[i], 1, 0}, NULL, NULL);
    }
    for (uint32_t i = 0; i < 3; i++) {
        tsr_mesh_add_triangle(&m, 2 * i, 2 * i + 2, 2 * i + 3);
        tsr_mesh_add_triangle(&m, 2 * i, 2 * i + 3, 2 * i + 1);
    }
    uint32_t b0 = m.vertex_count;
    for (int i = 0; i < 5; i++) {
        tsr_mesh_add_vertex(&m, (float[3]){above[i], 1.001f, 0}, NULL, NULL);
        tsr_mesh_add_vertex(&m, (float[3]){above[i], 2, 0}, NULL, NULL);
    }
    for (uint32_t i = 0; i < 4; i++) {
        tsr_mesh_add_triangle(&m, b0 + 2 * i, b0 + 2 * i + 2, b0 + 2 * i + 3);
        tsr_mesh_add_triangle(&m, b0 + 2 * i, b0 + 2 * i + 3, b0 + 2 * i + 1);
    }
    CHECK(tsr_mesh_find_gaps(&m, 0.01, NULL, &n) == TSR_OK);
    CHECK_MSG(n == 7, "%u gap edges between interleaved cuts", n);
    tsr_mesh_free(&m);
    /* a grid's rim: consecutive edges run the same way, the far sides are
     * farther than eps: no gap, even with eps above the edge length */
    grid(&m, 8);
    CHECK(tsr_mesh_find_gaps(&m, 1.5, NULL, &n) == TSR_OK);
    CHECK_MSG(n == 0, "%u gap edges on a grid's rim", n);
    /* a strip narrower than eps is one gap by the definition */
    CHECK(tsr_mesh_find_gaps(&m, 8.5, NULL, &n) == TSR_OK);
    CHECK_MSG(n == 32, "%u gap edges at 8.5", n);
    CHECK(tsr_mesh_find_gaps(&m, -1, NULL, &n) == TSR_ERR_ARGUMENT &&
          tsr_mesh_find_gaps(NULL, 1, NULL, &n) == TSR_ERR_ARGUMENT);
    tsr_mesh_free(&m);
    free(hit);
}

TEST(bad_index_and_nan_position)
{
    tsr_mesh m;
    grid(&m, 2);
    tsr_mesh_add_triangle(&m, 0, 1, 99);
    m.positions[3 * 8 + 2] = NAN; /* corner of the last two grid triangles */
    tsr_validation v = validate(&m, false);
    CHECK(v.bad_indices == 1);
    CHECK(v.nonfinite_positions == 1);
    CHECK(v.first_bad_triangle == 6);
    CHECK(!tsr_validation_ok(&v));
    char msg[512];
    tsr_validation_describe(&v, msg, sizeof msg);
    CHECK(strstr(msg, "out-of-range") != NULL);
    tsr_mesh_free(&m);
}

TEST(random_grids_with_one_defect)
{
    /* Property check: adding a copy of any triangle of a grid makes one
     * duplicate, and each of its three edges becomes either non-manifold
     * (an interior edge, now used three times) or misoriented (a boundary
     * edge, now traversed twice the same way). */
    unsigned seed = 12345;
    for (int trial = 0; trial < 20; trial++) {
        seed = seed * 1103515245u + 12345u;
        int n = 3 + (int)(seed >> 16) % 10;
        tsr_mesh m;
        grid(&m, n);
        uint32_t t = (seed >> 8) % m.triangle_count;
        tsr_mesh_add_triangle(&m, m.indices[3 * t], m.indices[3 * t + 1], m.indices[3 * t + 2]);
        tsr_validation v = validate(&m, true);
        CHECK(v.duplicate_triangles == 1);
        CHECK(v.nonmanifold_edges + v.misoriented_edges == 3);
        tsr_mesh_free(&m);
    }
}

/* Whether p lies strictly inside segment ab (farther than eps from both
 * ends along it) within eps of it, in the first dims coordinates: the
 * oracle's own test, in long double. */
static bool oracle_on_segment(const float *p, const float *a, const float *b, double eps, int dims)
{
    long double ab2 = 0, t = 0, d2 = 0;
    for (int k = 0; k < dims; k++) {
        ab2 += ((long double)b[k] - a[k]) * ((long double)b[k] - a[k]);
        t += ((long double)b[k] - a[k]) * ((long double)p[k] - a[k]);
    }
    if (ab2 <= 0)
        return false;
    t /= ab2;
    long double len = sqrtl(ab2);
    if (t * len <= eps || (1 - t) * len <= eps)
        return false;
    for (int k = 0; k < dims; k++) {
        long double q = ((long double)p[k] - a[k]) - t * ((long double)b[k] - a[k]);
        d2 += q * q;
    }
    return d2 <= (long double)eps * eps;
}

/* Vertices spread very unevenly (most in a cluster a thousandth of the
 * box across, a point repeated more often than a leaf of validate's tree
 * holds, some on the midpoints of long edges): coincident pairs and
 * T-junctions counted by validate against every pair and every (vertex,
 * open edge) tried by brute force, in 3D and as a height field. */
TEST(clustered_vertices_against_brute_force)
{
    uint64_t st = 0x9E3779B97F4A7C15ull;
    for (int seed = 0; seed < 6; seed++) {
        tsr_mesh m;
        tsr_mesh_init(&m, 0, NULL);
        uint32_t nv = 1500 + 300 * (uint32_t)seed, nt = 700;
        for (uint32_t i = 0; i < nv; i++) {
            float p[3];
            for (int k = 0; k < 3; k++) {
                st ^= st << 13, st ^= st >> 7, st ^= st << 17;
                double u = (double)(st >> 11) * 0x1p-53;
                p[k] = (float)(i % 5 == 0 ? u : 0.5 + 1e-3 * u);
            }
            if (i % 97 < 40 && i > 200)
                memcpy(p, m.positions + 3 * 200, sizeof p); /* one point many times over */
            tsr_mesh_add_vertex(&m, p, NULL, NULL);
        }
        for (uint32_t t = 0; t < nt; t++) {
            uint32_t v[3];
            for (int k = 0; k < 3; k++) {
                do {
                    st ^= st << 13, st ^= st >> 7, st ^= st << 17;
                    v[k] = (uint32_t)(st % nv);
                } while ((k > 0 && v[k] == v[0]) || (k > 1 && v[k] == v[1]));
            }
            tsr_mesh_add_triangle(&m, v[0], v[1], v[2]);
            if (t % 7 == 0) { /* a vertex on the middle of this triangle's first edge */
                const float *a = m.positions + 3 * (size_t)v[0], *b = m.positions + 3 * (size_t)v[1];
                float q[3] = {(a[0] + b[0]) / 2, (a[1] + b[1]) / 2, (a[2] + b[2]) / 2};
                uint32_t w = tsr_mesh_add_vertex(&m, q, NULL, NULL);
                uint32_t o = (v[2] + 1) % nv;
                if (o != w && o != v[2])
                    tsr_mesh_add_triangle(&m, w, v[2], o);
            }
        }
        uint32_t n = m.vertex_count, T = m.triangle_count;
        unsigned char *used = calloc(n, 1);
        for (uint32_t k = 0; k < 3 * T; k++)
            used[m.indices[k]] = 1;
        for (int dims = 3; dims >= 2; dims--) {
            double eps = 1e-4;
            tsr_validate_options o = {0};
            o.epsilon = eps;
            o.height_field = dims == 2;
            tsr_validation v;
            CHECK(tsr_mesh_validate(&m, &o, &v) == TSR_OK);
            uint64_t pairs = 0, junctions = 0;
            for (uint32_t i = 0; i < n; i++)
                for (uint32_t j = i + 1; used[i] && j < n; j++) {
                    if (!used[j])
                        continue;
                    long double d2 = 0;
                    for (int k = 0; k < dims; k++)
                        d2 += ((long double)m.positions[3 * i + k] - m.positions[3 * j + k]) *
                              ((long double)m.positions[3 * i + k] - m.positions[3 * j + k]);
                    pairs += d2 <= (long double)eps * eps;
                }
            /* open half-edges: an undirected edge of one half-edge (or of
             * three or more: non-manifold) */
            for (uint32_t t = 0; t < T; t++)
                for (int e = 0; e < 3; e++) {
                    uint32_t a = m.indices[3 * t + e], b = m.indices[3 * t + (e + 1) % 3], count = 0;
                    for (uint32_t u = 0; u < T; u++)
                        for (int f = 0; f < 3; f++) {
                            uint32_t c = m.indices[3 * u + f], d = m.indices[3 * u + (f + 1) % 3];
                            count += (c == a && d == b) || (c == b && d == a);
                        }
                    if (count == 2)
                        continue;
                    for (uint32_t j = 0; j < n; j++)
                        junctions += used[j] && j != a && j != b &&
                                     oracle_on_segment(m.positions + 3 * (size_t)j, m.positions + 3 * (size_t)a,
                                                       m.positions + 3 * (size_t)b, eps, dims);
                }
            CHECK_MSG(v.coincident_vertices == pairs && v.t_junctions == junctions,
                      "seed %d dims %d: coincident %u against %llu, T-junctions %u against %llu", seed, dims,
                      v.coincident_vertices, (unsigned long long)pairs, v.t_junctions, (unsigned long long)junctions);
            CHECK(pairs > 100 && junctions > 50);
        }
        free(used);
        tsr_mesh_free(&m);
    }
}

/* Edge and triangle counts of a big random soup (indices above 2^16, so
 * every digit of the sorted keys matters; more than a thousand
 * non-manifold half-edges) against counts made here by sorting plain
 * pairs and triples. */
typedef struct soup_edge {
    uint32_t lo, hi, from;
} soup_edge;

static int cmp_soup_edge(const void *a, const void *b)
{
    const soup_edge *x = a, *y = b;
    if (x->lo != y->lo)
        return x->lo < y->lo ? -1 : 1;
    return (x->hi > y->hi) - (x->hi < y->hi);
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

static int cmp_triple(const void *a, const void *b)
{
    const uint32_t *x = a, *y = b;
    for (int k = 0; k < 3; k++)
        if (x[k] != y[k])
            return x[k] < y[k] ? -1 : 1;
    return 0;
}

TEST(edge_counts_of_a_random_soup)
{
    const uint32_t NV = 70000, NT = 30000;
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    srand(7);
    for (uint32_t v = 0; v < NV; v++) {
        float p[3] = {(float)rand() / RAND_MAX, (float)rand() / RAND_MAX, (float)rand() / RAND_MAX};
        tsr_mesh_add_vertex(&m, p, NULL, NULL);
    }
    for (uint32_t t = 0; t < NT; t++) {
        uint32_t a = (uint32_t)rand() % NV, b = (uint32_t)rand() % NV, c = (uint32_t)rand() % NV;
        int kind = rand() % 20;
        uint32_t made = m.triangle_count;
        if (made > 0 && kind < 8) { /* an edge of an earlier triangle, either way */
            const uint32_t *o = m.indices + 3 * (size_t)((uint32_t)rand() % made);
            int e = rand() % 3;
            a = o[e], b = o[(e + 1) % 3];
            if (kind < 3) {
                uint32_t s = a;
                a = b, b = s;
            }
        } else if (made > 0 && kind == 8) { /* an earlier triangle again, turned */
            const uint32_t *o = m.indices + 3 * (size_t)((uint32_t)rand() % made);
            a = o[1], b = o[2], c = o[0];
        }
        if (a == b || b == c || a == c)
            continue;
        tsr_mesh_add_triangle(&m, a, b, c);
    }
    uint32_t T = m.triangle_count;
    soup_edge *e = malloc(3 * (size_t)T * sizeof *e);
    uint32_t *tri = malloc(3 * (size_t)T * sizeof *tri);
    CHECK(e && tri);
    for (uint32_t t = 0; t < T; t++) {
        const uint32_t *ix = m.indices + 3 * (size_t)t;
        for (int k = 0; k < 3; k++) {
            uint32_t a = ix[k], b = ix[(k + 1) % 3];
            e[3 * t + k] = (soup_edge){a < b ? a : b, a < b ? b : a, a};
        }
        uint32_t s[3] = {ix[0], ix[1], ix[2]};
        qsort(s, 3, sizeof *s, cmp_u32);
        memcpy(tri + 3 * t, s, sizeof s);
    }
    qsort(e, 3 * (size_t)T, sizeof *e, cmp_soup_edge);
    qsort(tri, T, 3 * sizeof *tri, cmp_triple);
    uint32_t edges = 0, boundary = 0, nonmanifold = 0, misoriented = 0, duplicates = 0;
    for (size_t i = 0, j; i < 3 * (size_t)T; i = j) {
        for (j = i + 1; j < 3 * (size_t)T && e[j].lo == e[i].lo && e[j].hi == e[i].hi;)
            j++;
        edges++;
        boundary += j - i == 1;
        nonmanifold += j - i > 2;
        misoriented += j - i == 2 && e[i].from == e[i + 1].from;
    }
    for (uint32_t t = 1; t < T; t++)
        duplicates += cmp_triple(tri + 3 * t, tri + 3 * (t - 1)) == 0;
    tsr_validation v = validate(&m, false);
    CHECK_MSG(v.edges == edges && v.boundary_edges == boundary && v.nonmanifold_edges == nonmanifold &&
                  v.misoriented_edges == misoriented && v.duplicate_triangles == duplicates,
              "edges %u/%u boundary %u/%u non-manifold %u/%u misoriented %u/%u duplicates %u/%u", v.edges, edges,
              v.boundary_edges, boundary, v.nonmanifold_edges, nonmanifold, v.misoriented_edges, misoriented,
              v.duplicate_triangles, duplicates);
    CHECK(nonmanifold > 1000 && misoriented > 1000 && duplicates > 1000 && boundary > 30000);
    free(e);
    free(tri);
    tsr_mesh_free(&m);
}

TEST_MAIN(T(grid_is_valid), T(flipped_triangle), T(nonmanifold_edge), T(coincident_sheets_no_t_junction), T(t_junction),
          T(t_junction_in_3d_long_edge), T(height_field_junctions_in_xy), T(inward_shells_found_and_turned),
          T(degenerate_and_duplicate), T(closed_tetrahedron), T(holes_count_loops), T(coincident_vertices_make_a_crack),
          T(gaps_between_open_edges), T(bad_index_and_nan_position), T(random_grids_with_one_defect),
          T(clustered_vertices_against_brute_force), T(edge_counts_of_a_random_soup))
