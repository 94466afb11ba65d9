/* The triangulation checker on small triangulations written by hand: it
 * accepts the correct ones and rejects each kind of defect, one defect per
 * case, so every rejection is a real failure of the rule it names. */
#include "check.h"
#include "tessellate/tessellate.h"

#include <limits.h>
#include <stdint.h>

#define PI 3.14159265358979323846

static uint32_t identity[64] = {0,  1,  2,  3,  4,  5,  6,  7,  8,  9,  10, 11, 12, 13, 14, 15,
                                16, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26, 27, 28, 29, 30, 31};

/* An output whose first `inputs` vertices are the input points, in order. */
static tsr_triangulation output(double *xy, uint32_t nv, uint32_t inputs, uint32_t *tri, uint32_t nt, uint32_t *edge,
                                uint32_t *edge_segment, uint32_t nedge)
{
    tsr_triangulation t = {0};
    t.xy = xy;
    t.nv = nv;
    t.tri = tri;
    t.nt = nt;
    t.edge = edge;
    t.edge_segment = edge_segment;
    t.nedge = nedge;
    t.vertex_of_input = identity;
    t.input_vertices = inputs;
    t.steiner = nv - inputs;
    return t;
}

static tsr_tri_check run(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *out)
{
    tsr_tri_check r;
    tsr_status s = tsr_triangulation_check(in, opt, out, &r);
    CHECK(s == TSR_OK);
    if (!r.ok)
        fprintf(stderr, "    (checker: %s)\n", r.first_problem);
    return r;
}

/* A rhombus: A(0,0) B(2,-1) C(4,0) D(2,1). BD is its Delaunay diagonal
 * (the angles facing it add up to 106 degrees), AC is not (254). */
static double rhombus[] = {0, 0, 2, -1, 4, 0, 2, 1};
static uint32_t rh_good[] = {0, 1, 3, 1, 2, 3};
static uint32_t rh_bad[] = {0, 1, 2, 0, 2, 3};

TEST(accepts_delaunay_rhombus)
{
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_good, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    CHECK_NEAR(r.area, 4, 1e-15);
    CHECK_NEAR(r.expected_area, 4, 1e-15);
    CHECK(r.euler == 1 && r.expected_euler == 1);
    CHECK(r.first_problem[0] == '\0');
    CHECK_NEAR(r.min_angle, 2 * atan(0.5) * 180 / PI, 1e-9);
}

TEST(rejects_non_delaunay_edge)
{
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_bad, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok);
    CHECK(r.not_delaunay == 1);
    CHECK(r.area_ok && r.not_ccw == 0 && r.bad_topology == 0);
    CHECK(strstr(r.first_problem, "not Delaunay") != NULL);
    /* the quadtree method makes no Delaunay promise */
    opt.method = TSR_TRI_QUADTREE;
    r = run(&in, &opt, &out);
    CHECK(r.ok);
}

TEST(constrained_edge_exempt_unless_conforming)
{
    static uint32_t seg[] = {0, 2};
    static uint32_t edge[] = {0, 2};
    static uint32_t eseg[] = {0};
    tsr_pslg in = {rhombus, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_bad, 2, edge, eseg, 1);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    opt.conforming = true;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.not_delaunay == 1);
}

TEST(rejects_missing_segment)
{
    /* the segment AC, but the Delaunay diagonal BD crosses it */
    static uint32_t seg[] = {0, 2};
    tsr_pslg in = {rhombus, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_good, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "input segment 0") != NULL);
}

TEST(rejects_unlisted_constrained_edge)
{
    /* AC is there but not listed as constrained */
    static uint32_t seg[] = {0, 2};
    tsr_pslg in = {rhombus, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_bad, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "not listed") != NULL || strstr(r.first_problem, "Delaunay") != NULL);
}

TEST(rejects_bogus_constrained_edge)
{
    /* BD listed as lying on segment AC (it crosses it) */
    static uint32_t seg[] = {0, 2};
    static uint32_t edge[] = {1, 3};
    static uint32_t eseg[] = {0};
    tsr_pslg in = {rhombus, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_good, 2, edge, eseg, 1);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.bad_topology >= 1);
    CHECK(strstr(r.first_problem, "does not lie on input segment 0") != NULL);
}

TEST(rejects_clockwise_triangle)
{
    static uint32_t tri[] = {0, 3, 1, 1, 2, 3}; /* the first reversed */
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, tri, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.not_ccw == 1);
    CHECK(strstr(r.first_problem, "triangle 0") && strstr(r.first_problem, "not counter-clockwise"));
}

TEST(rejects_vertex_id_out_of_range)
{
    static uint32_t tri[] = {0, 1, 3, 1, 2, 7};
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, tri, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.not_ccw == 1);
    CHECK(strstr(r.first_problem, "out of range") != NULL);
}

TEST(rejects_moved_input_point)
{
    static double xy[] = {0, 0, 2, -1, 4, 0, 2, 1.5};
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 4, 4, rh_good, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.bad_topology >= 1);
    CHECK(strstr(r.first_problem, "input point 3") != NULL);
}

TEST(rejects_missing_triangle)
{
    /* the unit square fanned around its centre, one of the four left out */
    static double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5};
    static uint32_t tri[] = {0, 1, 4, 1, 2, 4, 2, 3, 4};
    tsr_pslg in = {xy, 5, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 5, tri, 3, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && !r.area_ok);
    CHECK(r.overlapping == 0 && r.bad_topology == 0);
    CHECK(strstr(r.first_problem, "less than the expected area") != NULL);
}

TEST(rejects_overlapping_triangles)
{
    /* a square in two triangles, and a third triangle inside it sharing no edge */
    static double xy[] = {0, 0, 4, 0, 4, 4, 0, 4, 1, 1, 3, 1, 2, 3};
    static uint32_t tri[] = {0, 1, 2, 0, 2, 3, 4, 5, 6};
    tsr_pslg in = {xy, 7, NULL, 0, NULL, 0};
    tsr_tri_options opt = {.method = TSR_TRI_QUADTREE}; /* no Delaunay question here */
    tsr_triangulation out = output(xy, 7, 7, tri, 3, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.overlapping >= 1 && !r.area_ok);
    CHECK(r.bad_topology == 0 && r.not_ccw == 0);
    CHECK(strstr(r.first_problem, "more than the expected area") != NULL);
}

TEST(rejects_fan_winding_twice)
{
    /* seven triangles around a centre, each turning 720/7 degrees: every
     * edge is shared correctly, but the fan covers the plane twice */
    double xy[16];
    uint32_t tri[21];
    xy[0] = 0, xy[1] = 0;
    for (int k = 0; k < 7; k++) {
        xy[2 + 2 * k] = cos(k * 4 * PI / 7);
        xy[3 + 2 * k] = sin(k * 4 * PI / 7);
        tri[3 * k] = 0, tri[3 * k + 1] = 1 + k, tri[3 * k + 2] = 1 + (k + 1) % 7;
    }
    static double seed[] = {100, 100}; /* a hole seed: no expected area, only the fan sees it */
    tsr_pslg in = {xy, 8, NULL, 0, seed, 1};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation out = output(xy, 8, 8, tri, 7, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(isnan(r.expected_area));
    CHECK(r.bad_topology == 0 && r.not_ccw == 0);
    CHECK(!r.ok && r.overlapping == 1);
    CHECK(strstr(r.first_problem, "vertex 0") && strstr(r.first_problem, "2.000 times"));
}

TEST(rejects_edge_used_three_times)
{
    static double xy[] = {0, 0, 2, 0, 1, 1, 1, -1, 1, 2};
    static uint32_t tri[] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    tsr_pslg in = {xy, 5, NULL, 0, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation out = output(xy, 5, 5, tri, 3, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.bad_topology == 1);
    CHECK(strstr(r.first_problem, "used by 3 triangles") != NULL);
}

TEST(rejects_wrong_euler_characteristic)
{
    /* the unit square fanned around its centre, but the last triangle uses
     * a second vertex at the centre: same area, a slit, chi = 0 not 1 */
    static double xy[] = {0, 0, 1, 0, 1, 1, 0, 1, 0.5, 0.5, 0.5, 0.5};
    static uint32_t good[] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    static uint32_t slit[] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 5};
    tsr_pslg in = {xy, 5, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 5, good, 4, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.euler == 1);
    out = output(xy, 6, 5, slit, 4, NULL, NULL, 0);
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.euler == 0 && r.expected_euler == 1);
    CHECK(r.area_ok && r.bad_topology == 0 && r.not_delaunay == 0 && r.overlapping == 0);
    CHECK(strstr(r.first_problem, "Euler") != NULL);
}

/* A 10 x 10 square with a 4 x 4 hole, as rings for the even-odd rule. */
static double ring_xy[] = {0, 0, 10, 0, 10, 10, 0, 10, 3, 3, 7, 3, 7, 7, 3, 7};
static uint32_t ring_seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 4, 5, 5, 6, 6, 7, 7, 4};
static uint32_t ring_tri[] = {0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7};
static uint32_t ring_eseg[] = {0, 1, 2, 3, 4, 5, 6, 7};

TEST(accepts_even_odd_ring)
{
    tsr_pslg in = {ring_xy, 8, ring_seg, 8, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_EVEN_ODD};
    tsr_triangulation out = output(ring_xy, 8, 8, ring_tri, 8, ring_seg, ring_eseg, 8);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    CHECK_NEAR(r.expected_area, 84, 1e-12);
    CHECK(r.euler == 0 && r.expected_euler == 0);
    /* the enclosed region of the same input keeps the hole */
    opt.region = TSR_REGION_ENCLOSED;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && !r.area_ok && r.expected_euler == 1);
    CHECK_NEAR(r.expected_area, 100, 1e-12);
}

TEST(rejects_even_odd_ring_with_hole_filled)
{
    static uint32_t tri[] = {0, 1, 5, 0, 5, 4, 1, 2, 6, 1, 6, 5, 2, 3, 7, 2, 7, 6, 3, 0, 4, 3, 4, 7, 4, 5, 6, 4, 6, 7};
    tsr_pslg in = {ring_xy, 8, ring_seg, 8, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_EVEN_ODD};
    tsr_triangulation out = output(ring_xy, 8, 8, tri, 10, ring_seg, ring_eseg, 8);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && !r.area_ok && r.overlapping == 1 && r.euler == 1);
    CHECK(strstr(r.first_problem, "more than the expected area 84") != NULL);
}

TEST(even_odd_area_of_a_bowtie)
{
    /* a self-crossing quadrilateral: two triangles meeting at (1, 1) */
    static double xy[] = {0, 0, 2, 2, 2, 0, 0, 2, 1, 1};
    static uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0};
    static uint32_t tri[] = {4, 2, 1, 0, 4, 3};
    static uint32_t edge[] = {0, 4, 4, 1, 1, 2, 2, 4, 4, 3, 3, 0};
    static uint32_t eseg[] = {0, 0, 1, 2, 2, 3};
    tsr_pslg in = {xy, 4, seg, 4, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_EVEN_ODD};
    tsr_triangulation out = output(xy, 5, 4, tri, 2, edge, eseg, 6);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    CHECK_NEAR(r.expected_area, 2, 1e-15);
    CHECK(r.expected_euler == LONG_MIN); /* crossing loops: not derived */
    /* keeping the whole hull instead is caught by the area */
    static uint32_t all[] = {4, 2, 1, 0, 4, 3, 0, 2, 4, 1, 3, 4};
    out = output(xy, 5, 4, all, 4, edge, eseg, 6);
    r = run(&in, &opt, &out);
    CHECK(!r.ok && !r.area_ok);
}

TEST(even_odd_open_chain_not_checked)
{
    /* an open polyline has no even-odd interior: nothing expected */
    static double xy[] = {0, 0, 2, 0, 2, 2};
    static uint32_t seg[] = {0, 1, 1, 2};
    static uint32_t tri[] = {0, 1, 2};
    static uint32_t eseg[] = {0, 1};
    tsr_pslg in = {xy, 3, seg, 2, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_EVEN_ODD};
    tsr_triangulation out = output(xy, 3, 3, tri, 1, seg, eseg, 2);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(isnan(r.expected_area) && r.expected_euler == LONG_MIN && r.ok);
}

/* Two segments crossing at (0.3, 0.7), which no double holds exactly. */
static double cross_in[] = {0, 0, 3, 7, 0, 1, 1, 0};
static uint32_t cross_seg[] = {0, 1, 2, 3};
static uint32_t cross_tri[] = {0, 3, 4, 3, 1, 4, 1, 2, 4, 2, 0, 4};
static uint32_t cross_edge[] = {0, 4, 4, 1, 2, 4, 4, 3};
static uint32_t cross_eseg[] = {0, 0, 1, 1};

TEST(accepts_rounded_crossing_point)
{
    double xy[10] = {0, 0, 3, 7, 0, 1, 1, 0, 0.3, 0.7};
    tsr_pslg in = {cross_in, 4, cross_seg, 2, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 4, cross_tri, 4, cross_edge, cross_eseg, 4);
    CHECK(tsr_orient2d(cross_in, cross_in + 2, xy + 8) != 0); /* really off the line */
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    CHECK_NEAR(r.area, r.expected_area, 1e-14);
}

TEST(rejects_chain_off_the_segment)
{
    /* the same, with the crossing vertex a millionth off: a bent chain */
    double xy[10] = {0, 0, 3, 7, 0, 1, 1, 0, 0.3 + 1e-6, 0.7 - 1e-6};
    tsr_pslg in = {cross_in, 4, cross_seg, 2, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 4, cross_tri, 4, cross_edge, cross_eseg, 4);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments >= 1);
    CHECK(r.not_ccw == 0 && r.bad_topology >= 1); /* the listed edges are off their segment too */
}

TEST(accepts_splits_next_to_segment_end)
{
    /* segment a(1,0)-b(0,0) split at 2e-20 and 1e-20 from b: a parameter
     * in [0, 1] rounds both to 1, progress from the nearer end does not */
    static double xy[] = {1, 0, 0, 0, 0.5, 1, 0.5, -1, 1e-20, 0, 2e-20, 0};
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {5, 0, 2, 4, 5, 2, 1, 4, 2, 0, 5, 3, 5, 4, 3, 4, 1, 3};
    static uint32_t edge[] = {0, 5, 5, 4, 4, 1};
    static uint32_t eseg[] = {0, 0, 0};
    tsr_pslg in = {xy, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 6, 4, tri, 6, edge, eseg, 3);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
    CHECK_NEAR(r.expected_area, 1, 1e-15);
}

TEST(accepts_point_exactly_on_segment)
{
    static double xy[] = {0, 0, 2, 0, 1, 0, 1, 1, 1, -1};
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {0, 2, 3, 2, 1, 3, 0, 4, 2, 2, 4, 1};
    static uint32_t edge[] = {0, 2, 2, 1};
    static uint32_t eseg[] = {0, 0};
    tsr_pslg in = {xy, 5, seg, 1, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 5, tri, 4, edge, eseg, 2);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
}

TEST(enclosed_allows_segment_outside_region)
{
    /* a square loop and a dangling segment outside it: the enclosed region
     * is the square, and the outside segment needs no triangle */
    static double xy[] = {0, 0, 4, 0, 4, 4, 0, 4, 5, 1, 6, 3};
    static uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 4, 5};
    static uint32_t tri[] = {0, 1, 2, 0, 2, 3};
    static uint32_t eseg[] = {0, 1, 2, 3};
    tsr_pslg in = {xy, 6, seg, 5, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED};
    tsr_triangulation out = output(xy, 6, 6, tri, 2, seg, eseg, 4);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
    /* with the whole hull kept, the same output lacks the segment and area */
    opt.region = TSR_REGION_HULL;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1 && !r.area_ok);
}

TEST(enclosed_rejects_segment_missing_inside)
{
    /* square loop; inner segment (1,1)-(3,3) crossed by the diagonal 1-3 */
    static double xy[] = {0, 0, 4, 0, 4, 4, 0, 4, 1, 1, 3, 3};
    static uint32_t seg[] = {0, 1, 1, 2, 2, 3, 3, 0, 4, 5};
    static uint32_t tri[] = {0, 1, 4, 1, 3, 4, 3, 0, 4, 1, 2, 5, 2, 3, 5, 3, 1, 5};
    static uint32_t eseg[] = {0, 1, 2, 3};
    tsr_pslg in = {xy, 6, seg, 5, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 6, 6, tri, 6, seg, eseg, 4);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(r.not_ccw == 0 && r.bad_topology == 0 && r.area_ok);
    CHECK(strstr(r.first_problem, "input segment 4") != NULL);
}

TEST(enclosed_gap_passes_vertex_beside_segment)
{
    /* the enclosed region is the sliver P(0,0) B(4,4) q, q 2e-12 left of
     * the dangling segment S(4,-4)-B, which touches the sliver only at B.
     * q is within the segment's tolerance and its triangle covers the
     * direction back to S (its angle at q is near 180 degrees), yet the
     * segment passes it by: the gap runs from S to B. */
    static double xy[] = {0, 0, 4, 4, 4 - 2e-12, 4 - 1e-12, 4, -4};
    static uint32_t seg[] = {0, 1, 1, 2, 2, 0, 3, 1};
    static uint32_t tri[] = {0, 1, 2};
    static uint32_t eseg[] = {0, 1, 2};
    tsr_pslg in = {xy, 4, seg, 4, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 4, 4, tri, 1, seg, eseg, 3);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
}

TEST(enclosed_gap_rejects_segment_through_triangle_at_near_vertex)
{
    /* the kept triangle q X Y lies across the segment S(4,-4)-(4,4) below
     * q, 1e-12 right of it: the segment runs through the region with no
     * constrained edge, and q, off the line within the tolerance, may not
     * be passed over */
    static double xy[] = {4, -4, 4, 4, 4 + 1e-12, 0, 3, -3, 5, -3};
    static uint32_t seg[] = {0, 1, 2, 3, 3, 4, 4, 2};
    static uint32_t tri[] = {2, 3, 4};
    static uint32_t edge[] = {2, 3, 3, 4, 4, 2};
    static uint32_t eseg[] = {1, 2, 3};
    tsr_pslg in = {xy, 5, seg, 4, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 5, 5, tri, 1, edge, eseg, 3);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "input segment 0") != NULL);
}

TEST(enclosed_gap_passes_sliver_straddling_segment)
{
    /* the kept region is the sliver A p q, p and q an ulp either side of
     * the segment A(0,0)-B(4,0) and 2 ulps apart, all three edges listed:
     * the segment runs through the sliver (within rounding) and leaves it
     * between p and q. Each of p, q is the other's gap candidate and
     * covers the direction back, and the segment meets the sliver's
     * interior; the straight piece from either to B meets no kept
     * triangle, so the gap runs from there to B */
    static double xy[] = {0, 0, 4, 0, 2, 0, 2, 0, 3, -1, 3.6, -1, 3.3, 1};
    xy[5] = -0x1p-52, xy[7] = 0x1p-52;
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {0, 2, 3, 4, 5, 6};
    static uint32_t edge[] = {0, 2, 2, 3, 0, 3};
    static uint32_t eseg[] = {0, 0, 0};
    tsr_pslg in = {xy, 2, seg, 1, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 4, 2, tri, 1, edge, eseg, 3);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
    /* a kept triangle beyond, across the segment with its corners far
     * from it: the segment runs through the region there */
    out = output(xy, 7, 2, tri, 2, edge, eseg, 3);
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "input segment 0") != NULL);
}

TEST(enclosed_gap_passes_vertex_whose_triangle_segment_clips_behind)
{
    /* the chain of A(0,0)-B(8,0) jumps from A to m, an ulp below the
     * line, and follows m-p, p on it; q, 1e-9 above the line just ahead of
     * p, has the kept triangle m p q, which covers the direction back to p
     * and which the segment enters near m (it passes between m and q),
     * behind p. The piece from p to B meets no kept triangle: the gap
     * runs from p to B past q */
    static double xy[] = {0, 0, 8, 0, 1, 0, 1.0000001, 0, 1.0000002, 1e-9, 1, 1};
    xy[5] = -0x1p-52;
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {2, 3, 4, 2, 4, 5};
    static uint32_t edge[] = {2, 3};
    static uint32_t eseg[] = {0};
    tsr_pslg in = {xy, 2, seg, 1, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 6, 2, tri, 2, edge, eseg, 1);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
    /* with the chain edge m-p not listed the segment is missing inside */
    out.nedge = 0;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
}

TEST(enclosed_gap_backs_out_of_dead_end)
{
    /* the dangling segment A(0,0)-B(10,0) passes below the kept triangle
     * D Q R: D 1e-10 and Q 1e-11 above the line, both within its
     * tolerance, R far. The first gap from A goes to D, whose triangle
     * covers the direction on to B (Q lies below the ray D-B): a dead
     * end. The search backs out and jumps from A to Q, then from Q to B
     * (fuzz find quadtree_gap_dead_end_at_near_vertex). */
    static double xy[] = {0, 0, 10, 0, 5, 1e-10, 9, 1e-11, 9, 1, 9.5, -1, 9.8, -1, 9.6, 1};
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {2, 3, 4, 5, 6, 7};
    tsr_pslg in = {xy, 2, seg, 1, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 5, 2, tri, 1, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.missing_segments == 0); /* (the area differs: D Q R is enclosed by nothing) */
    /* a kept triangle across the segment beyond Q: missing there */
    out = output(xy, 8, 2, tri, 2, NULL, NULL, 0);
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "input segment 0") != NULL);
}

TEST(enclosed_gap_rejects_segment_through_triangle_between_far_vertices)
{
    /* the kept triangle (3,-1) (5,-1) (4,1) lies across the dangling
     * segment A(0,0)-B(8,0), none of its corners near it: the segment runs
     * through the region with no constrained edge, though both its ends
     * are outside and no vertex near it refuses the gap */
    static double xy[] = {0, 0, 8, 0, 3, -1, 5, -1, 4, 1};
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {2, 3, 4};
    tsr_pslg in = {xy, 2, seg, 1, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 5, 2, tri, 1, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    CHECK(strstr(r.first_problem, "input segment 0") != NULL);
}

TEST(enclosed_rejects_segment_along_unlisted_kept_edge)
{
    /* the kept triangles u v w and y u z have their edges y-u and u-v on
     * the segment A(0,0)-B(6,0), unlisted: the segment runs along the
     * region's boundary without constrained edges; the gaps A-y and v-B
     * alone are outside */
    static double xy[] = {0, 0, 6, 0, 2, 0, 4, 0, 3, 1, 1, 0, 1.5, 1};
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {2, 3, 4, 5, 2, 6};
    tsr_pslg in = {xy, 2, seg, 1, NULL, 0};
    tsr_tri_options opt = {.region = TSR_REGION_ENCLOSED, .method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 7, 2, tri, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
    /* listed, the same edges make the chain */
    static uint32_t edge[] = {5, 2, 2, 3};
    static uint32_t eseg[] = {0, 0};
    out = output(xy, 7, 2, tri, 2, edge, eseg, 2);
    r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
}

TEST(accepts_chain_step_back_within_rounding)
{
    /* the chain of (0,0)-(4,4) passes v1 (2,2) and then v2 an ulp below
     * it, a step back along the segment: one crossing rounded twice (by
     * two segments along one line); further back it is refused */
    static double xy[] = {0, 0, 4, 4, 4, 0, 0, 4, 2, 2, 2, 0};
    xy[11] = nextafter(2.0, 0.0);
    static uint32_t seg[] = {0, 1};
    static uint32_t tri[] = {0, 2, 5, 5, 2, 1, 0, 5, 4, 4, 5, 1, 0, 4, 3, 4, 1, 3};
    static uint32_t edge[] = {0, 4, 4, 5, 5, 1};
    static uint32_t eseg[] = {0, 0, 0};
    tsr_pslg in = {xy, 4, seg, 1, NULL, 0};
    tsr_tri_options opt = {.method = TSR_TRI_QUADTREE};
    tsr_triangulation out = output(xy, 6, 4, tri, 6, edge, eseg, 3);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.missing_segments == 0);
    xy[11] = 2 - 1e-13; /* 450 ulps: a step back */
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.missing_segments == 1);
}

TEST(rejects_angle_below_bound)
{
    /* a square fanned around (5, 0.3): two triangles have 3.4 degree angles */
    static double xy[] = {0, 0, 10, 0, 10, 10, 0, 10, 5, 0.3};
    static uint32_t tri[] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    tsr_pslg in = {xy, 5, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 5, 5, tri, 4, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok);
    CHECK_NEAR(r.min_angle, atan(0.3 / 5) * 180 / PI, 1e-9);
    opt.min_angle = 20;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.below_min_angle >= 1);
    CHECK(strstr(r.first_problem, "below 20 degrees") != NULL);
}

TEST(small_input_angle_excuses_triangle)
{
    /* segments O-P and O-Q meet at 5.7 degrees at O; triangle OPQ's
     * shortest edge PQ joins them, so its 5.7 degree angle is excused */
    static double xy[] = {0, 0, 10, 0, 10, 1, 0, 10};
    static uint32_t seg[] = {0, 1, 0, 2};
    static uint32_t tri[] = {0, 1, 2, 0, 2, 3};
    static uint32_t eseg[] = {0, 1};
    tsr_pslg in = {xy, 4, seg, 2, NULL, 0};
    tsr_tri_options opt = {.min_angle = 20};
    tsr_triangulation out = output(xy, 4, 4, tri, 2, seg, eseg, 2);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.below_min_angle == 0);
    CHECK(r.min_angle < 6);
    /* without the segment O-Q there is no small input angle at O */
    in.nseg = 1;
    out.nedge = 1;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.below_min_angle == 1);
    CHECK(strstr(r.first_problem, "triangle 0") != NULL);
}

/* Below the resolution of doubles (tsr_tri_below_resolution, the rule
 * refinement shares): a square fanned around (5, 1e-15), whose triangle
 * on the bottom edge is 1e-15 high, under 8 ulps of 10. It is excused only
 * when the result reports such triangles (quality_limited and
 * below_resolution); a triangle of ordinary size below the bound is never
 * excused, whatever the result says. */
TEST(below_resolution_excused_only_when_reported)
{
    static double flat[] = {0, 0, 10, 0, 10, 10, 0, 10, 5, 1e-15};
    static double skinny[] = {0, 0, 10, 0, 10, 10, 0, 10, 5, 0.3};
    static uint32_t tri[] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    CHECK(tsr_tri_below_resolution(flat, flat + 2, flat + 8));
    CHECK(tsr_tri_below_resolution(flat + 2, flat, flat + 8)); /* either orientation */
    CHECK(!tsr_tri_below_resolution(skinny, skinny + 2, skinny + 8));
    CHECK(!tsr_tri_below_resolution(flat + 2, flat + 4, flat + 8));
    static const double far[6] = {1e10, 0, 1e10 + 10, 0, 1e10 + 5, 1e-5}; /* relative to the coordinates */
    CHECK(tsr_tri_below_resolution(far, far + 2, far + 4));
    tsr_pslg in = {flat, 5, NULL, 0, NULL, 0};
    tsr_tri_options opt = {.min_angle = 20};
    tsr_triangulation out = output(flat, 5, 5, tri, 4, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(!r.ok && r.below_min_angle == 1 && r.below_resolution_excused == 0);
    out.quality_limited = true;
    out.below_resolution = 1;
    r = run(&in, &opt, &out);
    CHECK(r.ok && r.below_min_angle == 0 && r.below_resolution_excused == 1);
    out.below_resolution = 0; /* limited, but not for this reason */
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.below_min_angle == 1);
    CHECK(strstr(r.first_problem, "more below it than the result reports") != NULL);
    /* a real violation stays one */
    in.xy = skinny;
    out.xy = skinny;
    out.below_resolution = 4;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.below_min_angle >= 1 && r.below_resolution_excused == 0);
}

TEST(rejects_area_above_bound)
{
    tsr_pslg in = {rhombus, 4, NULL, 0, NULL, 0};
    tsr_tri_options opt = {.max_area = 2};
    tsr_triangulation out = output(rhombus, 4, 4, rh_good, 2, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok); /* both triangles have area exactly 2 */
    opt.max_area = 1.9;
    r = run(&in, &opt, &out);
    CHECK(!r.ok && r.above_max_area == 2);
    CHECK(strstr(r.first_problem, "area above 1.9") != NULL);
}

TEST(empty_output_of_collinear_points)
{
    static double xy[] = {0, 0, 1, 1, 2, 2};
    tsr_pslg in = {xy, 3, NULL, 0, NULL, 0};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(xy, 3, 3, NULL, 0, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(r.ok && r.expected_area == 0 && r.expected_euler == 0 && r.euler == 0);
}

TEST(hole_seeds_leave_area_unchecked)
{
    static double seeds[] = {1, 0};
    tsr_pslg in = {rhombus, 4, NULL, 0, seeds, 1};
    tsr_tri_options opt = {0};
    tsr_triangulation out = output(rhombus, 4, 4, rh_good, 1, NULL, NULL, 0);
    tsr_tri_check r = run(&in, &opt, &out);
    CHECK(isnan(r.expected_area) && r.expected_euler == LONG_MIN);
    CHECK(r.ok);
}

TEST_MAIN(T(accepts_delaunay_rhombus), T(rejects_non_delaunay_edge), T(constrained_edge_exempt_unless_conforming),
          T(rejects_missing_segment), T(rejects_unlisted_constrained_edge), T(rejects_bogus_constrained_edge),
          T(rejects_clockwise_triangle), T(rejects_vertex_id_out_of_range), T(rejects_moved_input_point),
          T(rejects_missing_triangle), T(rejects_overlapping_triangles), T(rejects_fan_winding_twice),
          T(rejects_edge_used_three_times), T(rejects_wrong_euler_characteristic), T(accepts_even_odd_ring),
          T(rejects_even_odd_ring_with_hole_filled), T(even_odd_area_of_a_bowtie), T(even_odd_open_chain_not_checked),
          T(accepts_rounded_crossing_point), T(rejects_chain_off_the_segment), T(accepts_splits_next_to_segment_end),
          T(accepts_point_exactly_on_segment), T(enclosed_allows_segment_outside_region),
          T(enclosed_rejects_segment_missing_inside), T(enclosed_gap_passes_vertex_beside_segment),
          T(enclosed_gap_rejects_segment_through_triangle_at_near_vertex),
          T(enclosed_gap_passes_sliver_straddling_segment),
          T(enclosed_gap_passes_vertex_whose_triangle_segment_clips_behind),
          T(enclosed_gap_backs_out_of_dead_end), T(enclosed_gap_rejects_segment_through_triangle_between_far_vertices),
          T(enclosed_rejects_segment_along_unlisted_kept_edge), T(accepts_chain_step_back_within_rounding),
          T(rejects_angle_below_bound), T(small_input_angle_excuses_triangle),
          T(below_resolution_excused_only_when_reported), T(rejects_area_above_bound),
          T(empty_output_of_collinear_points), T(hole_seeds_leave_area_unchecked))
