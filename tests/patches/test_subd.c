/* test_subd.c: subdivision surfaces through OpenSubdiv's Bfr (patches/subd.h),
 * each property against an oracle written here:
 *  - the bilinear scheme against bilinear interpolation of the cage (quads),
 *    and of vertex, edge midpoints and centroid (N-gon sub-patches);
 *  - Catmull-Clark on a regular grid against the uniform bicubic B-spline of
 *    the 16 control points (closed-form basis), and a planar grid staying in
 *    its plane;
 *  - the cube's limit against the limit masks of a corner and of a face
 *    centre (one Catmull-Clark step done by hand), and against the cube's
 *    symmetries;
 *  - shared patch edges evaluated from both sides through the reported
 *    correspondence; bounds against dense samples; uniform tessellations
 *    against the vertex and triangle counts of a closed cube and the
 *    validator, with positive volume;
 *  - bad cages refused with a message naming the element.
 * The data_ test reads OpenSubdiv's regression shapes with a reader written
 * here (v, f and t lines only). */
#include "check.h"
#include "patches/subd.h"

/* ---- cages built by hand -------------------------------------------------- */

typedef struct cage_buf {
    tsr_cage c;
    double pts[3 * 64];
    uint32_t sizes[64];
    uint32_t verts[256];
} cage_buf;

static void cage_init(cage_buf *b, const double *pts, uint32_t np, const uint32_t *sizes, uint32_t nf,
                      const uint32_t *verts, int boundary)
{
    memset(b, 0, sizeof *b);
    uint32_t nv = 0;
    for (uint32_t f = 0; f < nf; f++)
        nv += sizes[f];
    memcpy(b->pts, pts, sizeof(double) * 3 * np);
    memcpy(b->sizes, sizes, sizeof(uint32_t) * nf);
    memcpy(b->verts, verts, sizeof(uint32_t) * nv);
    b->c.num_points = np;
    b->c.points = b->pts;
    b->c.num_faces = nf;
    b->c.face_sizes = b->sizes;
    b->c.face_verts = b->verts;
    b->c.boundary_interp = boundary;
    b->c.fvar_interp = 5;
}

/* Vertex x + 2y + 4z at (+-1, +-1, +-1); faces counter-clockwise seen from
 * outside: top, bottom, front (-y), back (+y), left (-x), right (+x). */
static const uint32_t cube_sizes[6] = {4, 4, 4, 4, 4, 4};
static const uint32_t cube_verts[24] = {4, 5, 7, 6, 0, 2, 3, 1, 0, 1, 5, 4, 2, 6, 7, 3, 0, 4, 6, 2, 1, 3, 7, 5};

static void cube(cage_buf *b)
{
    double p[24];
    for (int v = 0; v < 8; v++) {
        p[3 * v] = v & 1 ? 1 : -1;
        p[3 * v + 1] = v & 2 ? 1 : -1;
        p[3 * v + 2] = v & 4 ? 1 : -1;
    }
    cage_init(b, p, 8, cube_sizes, 6, cube_verts, 1);
}

/* A square pyramid: quad base (facing -z) and four triangles, closed. */
static void pyramid(cage_buf *b)
{
    static const double p[15] = {-1, -1, 0, 1, -1, 0, 1, 1, 0, -1, 1, 0, 0, 0, 1.5};
    static const uint32_t sizes[5] = {4, 3, 3, 3, 3};
    static const uint32_t verts[16] = {0, 3, 2, 1, 0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
    cage_init(b, p, 5, sizes, 5, verts, 1);
}

/* An (n+1) x (n+1) vertex grid of n x n quads, vertex (i, j) at (i, j,
 * z(i, j)), face (i, j) = j * n + i counter-clockwise seen from +z. */
static void grid(cage_buf *b, int n, const double *z, int boundary)
{
    double p[3 * 64];
    uint32_t sizes[64], verts[256];
    for (int j = 0; j <= n; j++)
        for (int i = 0; i <= n; i++) {
            int v = j * (n + 1) + i;
            p[3 * v] = i;
            p[3 * v + 1] = j;
            p[3 * v + 2] = z ? z[v] : 0;
        }
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            int f = j * n + i;
            uint32_t a = (uint32_t)(j * (n + 1) + i);
            sizes[f] = 4;
            verts[4 * f] = a;
            verts[4 * f + 1] = a + 1;
            verts[4 * f + 2] = a + (uint32_t)n + 2;
            verts[4 * f + 3] = a + (uint32_t)n + 1;
        }
    cage_init(b, p, (uint32_t)((n + 1) * (n + 1)), sizes, (uint32_t)(n * n), verts, boundary);
}

static tsr_subd *make(const tsr_cage *c, tsr_subd_scheme scheme)
{
    tsr_subd *s = NULL;
    tsr_error err = {0};
    tsr_status st = tsr_subd_create(c, scheme, NULL, &s, &err);
    CHECK_MSG(st == TSR_OK && s, "%s", err.message);
    return s;
}

static double dist3(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) + (a[2] - b[2]) * (a[2] - b[2]));
}

static void eval1(const tsr_subd *s, uint32_t f, uint32_t k, double u, double v, double p[3], double du[3],
                  double dv[3])
{
    double uv[2] = {u, v};
    CHECK(tsr_subd_eval(s, f, k, uv, 1, p, du, dv) == TSR_OK);
}

/* ---- (1) bilinear ----------------------------------------------------------- */

TEST(bilinear_quad_is_bilinear_interpolation)
{
    static const double p[12] = {0, 0, 0, 2, 0, 0.5, 2.5, 3, -1, -0.5, 2, 1};
    static const uint32_t sizes[1] = {4}, verts[4] = {0, 1, 2, 3};
    cage_buf b;
    cage_init(&b, p, 4, sizes, 1, verts, 1);
    tsr_subd *s = make(&b.c, TSR_SUBD_BILINEAR);
    if (!s)
        return;
    CHECK(tsr_subd_face_count(s) == 1 && tsr_subd_face_patches(s, 0) == 1 && tsr_subd_face_size(s, 0) == 4);
    CHECK(tsr_subd_face_has_limit(s, 0));
    double err = 0, derr = 0;
    for (int j = 0; j <= 10; j++)
        for (int i = 0; i <= 10; i++) {
            double u = i / 10.0, v = j / 10.0, q[3], du[3], dv[3];
            eval1(s, 0, 0, u, v, q, du, dv);
            for (int c = 0; c < 3; c++) {
                double ref =
                    (1 - u) * (1 - v) * p[c] + u * (1 - v) * p[3 + c] + u * v * p[6 + c] + (1 - u) * v * p[9 + c];
                double rdu = (1 - v) * (p[3 + c] - p[c]) + v * (p[6 + c] - p[9 + c]);
                double rdv = (1 - u) * (p[9 + c] - p[c]) + u * (p[6 + c] - p[3 + c]);
                err = fmax(err, fabs(q[c] - ref));
                derr = fmax(derr, fmax(fabs(du[c] - rdu), fabs(dv[c] - rdv)));
            }
        }
    CHECK_MSG(err <= 1e-14 && derr <= 1e-13, "position error %g, derivative error %g", err, derr);
    tsr_subd_destroy(s);
}

/* A bilinear N-gon splits into quads (vertex k, midpoint of edge k, centroid,
 * midpoint of edge k-1), each interpolated bilinearly. */
TEST(bilinear_ngon_subpatches)
{
    static const double p[15] = {0, 0, 0, 2, 0, 0.3, 2.6, 1.7, -0.2, 1, 2.8, 0.4, -0.6, 1.5, 0.1};
    static const uint32_t sizes[1] = {5}, verts[5] = {0, 1, 2, 3, 4};
    cage_buf b;
    cage_init(&b, p, 5, sizes, 1, verts, 1);
    tsr_subd *s = make(&b.c, TSR_SUBD_BILINEAR);
    if (!s)
        return;
    CHECK(tsr_subd_face_patches(s, 0) == 5);
    double cen[3] = {0, 0, 0};
    for (int v = 0; v < 5; v++)
        for (int c = 0; c < 3; c++)
            cen[c] += p[3 * v + c] / 5;
    double err = 0, derr = 0;
    for (uint32_t k = 0; k < 5; k++) {
        double A[3], B[3], D[3];
        for (int c = 0; c < 3; c++) {
            A[c] = p[3 * k + c];
            B[c] = (p[3 * k + c] + p[3 * ((k + 1) % 5) + c]) / 2;
            D[c] = (p[3 * k + c] + p[3 * ((k + 4) % 5) + c]) / 2;
        }
        for (int j = 0; j <= 8; j++)
            for (int i = 0; i <= 8; i++) {
                double u = i / 8.0, v = j / 8.0, q[3], du[3], dv[3];
                eval1(s, 0, k, u, v, q, du, dv);
                for (int c = 0; c < 3; c++) {
                    double ref = (1 - u) * (1 - v) * A[c] + u * (1 - v) * B[c] + u * v * cen[c] + (1 - u) * v * D[c];
                    double rdu = (1 - v) * (B[c] - A[c]) + v * (cen[c] - D[c]);
                    double rdv = (1 - u) * (D[c] - A[c]) + u * (cen[c] - B[c]);
                    err = fmax(err, fabs(q[c] - ref));
                    derr = fmax(derr, fmax(fabs(du[c] - rdu), fabs(dv[c] - rdv)));
                }
            }
    }
    CHECK_MSG(err <= 1e-14 && derr <= 1e-13, "position error %g, derivative error %g", err, derr);
    tsr_subd_destroy(s);
}

/* ---- (2) Catmull-Clark on regular grids -------------------------------------- */

TEST(planar_grid_stays_in_plane)
{
    for (int bnd = 1; bnd <= 2; bnd++) {
        cage_buf b;
        grid(&b, 5, NULL, bnd);
        tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
        if (!s)
            return;
        double zmax = 0, dzmax = 0, xymin = INFINITY, xymax = -INFINITY;
        for (uint32_t f = 0; f < 25; f++) {
            CHECK(tsr_subd_face_has_limit(s, f));
            for (int j = 0; j <= 8; j++)
                for (int i = 0; i <= 8; i++) {
                    double q[3], du[3], dv[3];
                    eval1(s, f, 0, i / 8.0, j / 8.0, q, du, dv);
                    zmax = fmax(zmax, fabs(q[2]));
                    dzmax = fmax(dzmax, fmax(fabs(du[2]), fabs(dv[2])));
                    xymin = fmin(xymin, fmin(q[0], q[1]));
                    xymax = fmax(xymax, fmax(q[0], q[1]));
                    double n[3];
                    double uv[2] = {i / 8.0, j / 8.0};
                    CHECK(tsr_subd_normal(s, f, 0, uv, n) == TSR_OK);
                    CHECK_NEAR(n[2], 1.0, 1e-12);
                }
        }
        CHECK_MSG(zmax == 0 && dzmax == 0, "z %g, dz %g", zmax, dzmax);
        CHECK(xymin >= -1e-12 && xymax <= 5 + 1e-12);
        if (bnd == 2) /* sharp corners: the limit is the whole square */
            CHECK(fabs(xymin) <= 1e-12 && fabs(xymax - 5) <= 1e-12);
        /* The uniform tessellation's boundary is the square's border when
         * the corners are sharp. */
        if (bnd == 2) {
            tsr_mesh m;
            tsr_mesh_init(&m, 0, NULL);
            tsr_error err = {0};
            CHECK(tsr_subd_tessellate_uniform(s, 4, &m, &err) == TSR_OK);
            CHECK(m.vertex_count == 21 * 21 && m.triangle_count == 25 * 32);
            CHECK(tsr_mesh_boundary_is_rect(&m, 0, 0, 5, 5, 1e-6, NULL));
            tsr_mesh_free(&m);
        }
        tsr_subd_destroy(s);
    }
}

static double bspline(int i, double t)
{
    switch (i) {
    case 0:
        return (1 - t) * (1 - t) * (1 - t) / 6;
    case 1:
        return (3 * t * t * t - 6 * t * t + 4) / 6;
    case 2:
        return (-3 * t * t * t + 3 * t * t + 3 * t + 1) / 6;
    default:
        return t * t * t / 6;
    }
}

static double bspline_d(int i, double t)
{
    switch (i) {
    case 0:
        return -(1 - t) * (1 - t) / 2;
    case 1:
        return (9 * t * t - 12 * t) / 6;
    case 2:
        return (-9 * t * t + 6 * t + 3) / 6;
    default:
        return t * t / 2;
    }
}

/* The middle face of a 3 x 3 grid of quads has all 16 grid points as its
 * control points: its limit is their uniform bicubic B-spline. */
TEST(regular_face_is_bicubic_bspline)
{
    double z[16];
    unsigned r = 12345;
    for (int k = 0; k < 16; k++) {
        r = r * 1103515245u + 12345u;
        z[k] = ((r >> 16) % 2001) / 1000.0 - 1;
    }
    cage_buf b;
    grid(&b, 3, z, 1);
    /* jiggle x and y too, so all three coordinates are tested */
    for (int k = 0; k < 16; k++) {
        b.pts[3 * k] += 0.1 * sin(k * 1.7);
        b.pts[3 * k + 1] += 0.1 * cos(k * 2.3);
    }
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    double err = 0, derr = 0;
    for (int j = 0; j <= 16; j++)
        for (int i = 0; i <= 16; i++) {
            double u = i / 16.0, v = j / 16.0, q[3], du[3], dv[3];
            eval1(s, 4, 0, u, v, q, du, dv);
            for (int c = 0; c < 3; c++) {
                double ref = 0, rdu = 0, rdv = 0;
                for (int jj = 0; jj < 4; jj++)
                    for (int ii = 0; ii < 4; ii++) {
                        double P = b.pts[3 * (jj * 4 + ii) + c];
                        ref += bspline(ii, u) * bspline(jj, v) * P;
                        rdu += bspline_d(ii, u) * bspline(jj, v) * P;
                        rdv += bspline(ii, u) * bspline_d(jj, v) * P;
                    }
                err = fmax(err, fabs(q[c] - ref));
                derr = fmax(derr, fmax(fabs(du[c] - rdu), fabs(dv[c] - rdv)));
            }
        }
    CHECK_MSG(err <= 1e-9 && derr <= 1e-9, "position error %g, derivative error %g", err, derr);
    tsr_subd_destroy(s);
}

/* ---- (3) the cube --------------------------------------------------------- */

/* Limit position of a vertex of valence n with edge neighbours e and face
 * diagonals f (quads): (n^2 v + 4 sum e + sum f) / (n (n + 5)). */
static void limit_mask(int n, const double v[3], const double *e, const double *f, double out[3])
{
    for (int c = 0; c < 3; c++) {
        double se = 0, sf = 0;
        for (int k = 0; k < n; k++)
            se += e[3 * k + c], sf += f[3 * k + c];
        out[c] = (n * n * v[c] + 4 * se + sf) / (n * (n + 5));
    }
}

static void cube_point(int v, double p[3])
{
    p[0] = v & 1 ? 1 : -1;
    p[1] = v & 2 ? 1 : -1;
    p[2] = v & 4 ? 1 : -1;
}

static int popcount3(int x)
{
    return (x & 1) + ((x >> 1) & 1) + ((x >> 2) & 1);
}

/* The limit of the cube's vertex v: its three edge neighbours differ in one
 * coordinate, its three face diagonals in two. */
static void cube_corner_limit(int v, double out[3])
{
    double P[3], e[9], f[9];
    int ne = 0, nf = 0;
    cube_point(v, P);
    for (int w = 0; w < 8; w++) {
        int d = popcount3(v ^ w);
        if (d == 1)
            cube_point(w, e + 3 * ne++);
        else if (d == 2)
            cube_point(w, f + 3 * nf++);
    }
    limit_mask(3, P, e, f, out);
}

/* The limit of the centre of the top face z = 1: one Catmull-Clark step
 * makes the face point F a regular vertex whose edge neighbours are the
 * top face's edge points and whose diagonals are its corners' vertex
 * points. By symmetry: F = (0,0,1); the edge point of the top edge at
 * x = 1 averages its ends (1,+-1,1) and the face points (0,0,1), (1,0,0):
 * (3/4, 0, 3/4); the vertex point of (1,1,1) is (Q + 2R + (n-3)S)/n with
 * Q the mean of its face points (1/3,1/3,1/3) and R of its edge midpoints
 * (2/3,2/3,2/3): (5/9,5/9,5/9). */
static void cube_top_centre_limit(double out[3])
{
    double F[3] = {0, 0, 1}, e[12], f[12];
    static const int sx[4] = {1, 0, -1, 0}, sy[4] = {0, 1, 0, -1};
    for (int k = 0; k < 4; k++) {
        double edge_ends_x = 2 * sx[k], edge_ends_y = 2 * sy[k]; /* sum of the two ends */
        double face_x = sx[k], face_y = sy[k];                   /* side face point (sx, sy, 0) */
        e[3 * k] = (edge_ends_x + 0 + face_x) / 4;
        e[3 * k + 1] = (edge_ends_y + 0 + face_y) / 4;
        e[3 * k + 2] = (2 + 1 + 0) / 4.0;
    }
    for (int k = 0; k < 4; k++) {
        double cx = k == 0 || k == 3 ? 1 : -1, cy = k < 2 ? 1 : -1; /* corner (cx, cy, 1) */
        double Q[3] = {cx / 3, cy / 3, 1 / 3.0};
        double R[3] = {2 * cx / 3, 2 * cy / 3, 2 / 3.0};
        double S[3] = {cx, cy, 1};
        for (int c = 0; c < 3; c++)
            f[3 * k + c] = (Q[c] + 2 * R[c] + 0 * S[c]) / 3;
    }
    limit_mask(4, F, e, f, out);
}

TEST(cube_limit_values_and_symmetry)
{
    cage_buf b;
    cube(&b);
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    /* corners of the top face (vertices 4, 5, 7, 6) at (0,0), (1,0), (1,1), (0,1) */
    static const double cu[4] = {0, 1, 1, 0}, cv[4] = {0, 0, 1, 1};
    for (int k = 0; k < 4; k++) {
        double q[3], ref[3];
        eval1(s, 0, 0, cu[k], cv[k], q, NULL, NULL);
        cube_corner_limit((int)cube_verts[k], ref);
        CHECK_MSG(dist3(q, ref) <= 1e-12, "corner %d: (%g %g %g) vs (%g %g %g)", k, q[0], q[1], q[2], ref[0], ref[1],
                  ref[2]);
        CHECK_NEAR(fabs(ref[0]), 0.5, 1e-15);
    }
    double q[3], ref[3];
    eval1(s, 0, 0, 0.5, 0.5, q, NULL, NULL);
    cube_top_centre_limit(ref);
    CHECK_MSG(dist3(q, ref) <= 1e-12, "centre (%.17g %.17g %.17g) vs (%.17g %.17g %.17g)", q[0], q[1], q[2], ref[0],
              ref[1], ref[2]);

    double rmin = INFINITY, rmax = 0, sym = 0;
    bool outward = true;
    for (uint32_t f = 0; f < 6; f++)
        for (int j = 0; j <= 16; j++)
            for (int i = 0; i <= 16; i++) {
                double u = i / 16.0, v = j / 16.0, p[3], n[3];
                eval1(s, f, 0, u, v, p, NULL, NULL);
                double r = fmax(fabs(p[0]), fmax(fabs(p[1]), fabs(p[2])));
                rmin = fmin(rmin, r);
                rmax = fmax(rmax, r);
                double uv[2] = {u, v};
                CHECK(tsr_subd_normal(s, f, 0, uv, n) == TSR_OK);
                outward = outward && n[0] * p[0] + n[1] * p[1] + n[2] * p[2] > 0;
                if (f != 0)
                    continue;
                /* rotation by 90 degrees about z, mirror in x, mirror in z */
                double a[3], rot[3] = {-p[1], p[0], p[2]}, mx[3] = {-p[0], p[1], p[2]}, mz[3] = {p[0], p[1], -p[2]};
                eval1(s, 0, 0, 1 - v, u, a, NULL, NULL);
                sym = fmax(sym, dist3(a, rot));
                eval1(s, 0, 0, 1 - u, v, a, NULL, NULL);
                sym = fmax(sym, dist3(a, mx));
                eval1(s, 1, 0, v, u, a, NULL, NULL);
                sym = fmax(sym, dist3(a, mz));
            }
    CHECK_MSG(rmin >= 0.5 - 1e-12 && rmax < 1 && rmax <= ref[2] + 1e-12, "max-norm radius in [%.17g, %.17g]", rmin,
              rmax);
    CHECK_MSG(sym <= 1e-12, "symmetry error %g", sym);
    CHECK(outward);
    tsr_subd_destroy(s);
}

TEST(holes_and_boundaries_have_no_limit)
{
    cage_buf b;
    cube(&b);
    uint32_t hole = 0;
    b.c.num_holes = 1;
    b.c.hole_faces = &hole;
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    CHECK(!tsr_subd_face_has_limit(s, 0));
    for (uint32_t f = 1; f < 6; f++)
        CHECK(tsr_subd_face_has_limit(s, f));
    double uv[2] = {0.5, 0.5}, p[3], lo[3], hi[3];
    CHECK(tsr_subd_eval(s, 0, 0, uv, 1, p, NULL, NULL) == TSR_ERR_ARGUMENT);
    CHECK(tsr_subd_face_bounds(s, 0, 0, lo, hi) == TSR_ERR_ARGUMENT);
    CHECK(tsr_subd_eval(s, 1, 1, uv, 1, p, NULL, NULL) == TSR_ERR_ARGUMENT); /* a quad has one patch */
    CHECK(tsr_subd_eval(s, 6, 0, uv, 1, p, NULL, NULL) == TSR_ERR_ARGUMENT);
    /* the side faces see no neighbour across the hole */
    tsr_subd_link l[2];
    uint32_t across = 0;
    for (uint32_t f = 2; f < 6; f++)
        for (uint32_t e = 0; e < 4; e++)
            if (tsr_subd_patch_neighbours(s, f, 0, e, l) == 0)
                across++;
    CHECK(across == 4);
    /* its tessellation is open along one loop of 4 * rate edges */
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    CHECK(tsr_subd_tessellate_uniform(s, 3, &m, NULL) == TSR_OK);
    tsr_validation v;
    CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
    CHECK(tsr_validation_ok(&v) && v.boundary_loops == 1 && v.loop_length[0] == 12);
    tsr_mesh_free(&m);
    tsr_subd_destroy(s);

    /* no boundary interpolation: only faces away from the boundary */
    grid(&b, 5, NULL, 0);
    s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    uint32_t with = 0;
    for (uint32_t f = 0; f < 25; f++) {
        bool inner = f % 5 >= 1 && f % 5 <= 3 && f / 5 >= 1 && f / 5 <= 3;
        CHECK(tsr_subd_face_has_limit(s, f) == inner);
        with += tsr_subd_face_has_limit(s, f);
    }
    CHECK(with == 9);
    tsr_subd_destroy(s);
}

/* ---- (4) shared edges ------------------------------------------------------ */

/* Every link of every patch edge: both sides evaluated at corresponding
 * points, the link's reverse present, and (for a closed cage) each edge
 * covered entirely. Returns the largest distance. */
static double check_links(const tsr_subd *s, bool closed, const char *name, uint32_t *links)
{
    double worst = 0;
    *links = 0;
    for (uint32_t f = 0; f < tsr_subd_face_count(s); f++) {
        if (!tsr_subd_face_has_limit(s, f))
            continue;
        for (uint32_t k = 0; k < tsr_subd_face_patches(s, f); k++)
            for (uint32_t e = 0; e < 4; e++) {
                tsr_subd_link l[2];
                uint32_t n = tsr_subd_patch_neighbours(s, f, k, e, l);
                double covered = 0;
                for (uint32_t q = 0; q < n; q++) {
                    (*links)++;
                    CHECK(l[q].t0 < l[q].t1 && l[q].t0 >= 0 && l[q].t1 <= 1);
                    CHECK(l[q].reversed == (l[q].s1 < l[q].s0));
                    covered += l[q].t1 - l[q].t0;
                    /* the documented rules of the correspondence */
                    bool quad = tsr_subd_face_patches(s, f) == 1, quad2 = tsr_subd_face_patches(s, l[q].face) == 1;
                    if (quad && quad2)
                        CHECK(l[q].reversed == ((e < 2) == (l[q].edge < 2)));
                    else if (!quad && !quad2 && (e == 1 || e == 2))
                        CHECK(!l[q].reversed && l[q].face == f && l[q].edge == 3 - e);
                    else if (!quad && !quad2)
                        CHECK(!l[q].reversed && l[q].edge == 3 - e && (e == 0 || e == 3));
                    else
                        CHECK(n == (quad ? 2u : 1u) && l[q].t1 - l[q].t0 == (quad ? 0.5 : 1) &&
                              fabs(l[q].s1 - l[q].s0) == (quad ? 1 : 0.5));
                    for (int i = 0; i <= 16; i++) {
                        double t = l[q].t0 + (l[q].t1 - l[q].t0) * i / 16.0;
                        double sv = l[q].s0 + (l[q].s1 - l[q].s0) * i / 16.0;
                        double a[2] = {e == 0 || e == 2 ? t : e == 1 ? 1 : 0, e == 1 || e == 3 ? t : e == 2 ? 1 : 0};
                        uint32_t g = l[q].edge;
                        double bb[2] = {g == 0 || g == 2 ? sv : g == 1 ? 1 : 0, g == 1 || g == 3 ? sv : g == 2 ? 1 : 0};
                        double pa[3], pb[3];
                        CHECK(tsr_subd_eval(s, f, k, a, 1, pa, NULL, NULL) == TSR_OK);
                        CHECK(tsr_subd_eval(s, l[q].face, l[q].sub, bb, 1, pb, NULL, NULL) == TSR_OK);
                        worst = fmax(worst, dist3(pa, pb));
                    }
                    /* the neighbour links back over the same stretch */
                    tsr_subd_link r[2];
                    uint32_t nr = tsr_subd_patch_neighbours(s, l[q].face, l[q].sub, l[q].edge, r);
                    bool back = false;
                    for (uint32_t w = 0; w < nr; w++) {
                        double lo = fmin(l[q].s0, l[q].s1), hi = fmax(l[q].s0, l[q].s1);
                        back = back || (r[w].face == f && r[w].sub == k && r[w].edge == e && r[w].t0 == lo &&
                                        r[w].t1 == hi && fmin(r[w].s0, r[w].s1) == l[q].t0 &&
                                        fmax(r[w].s0, r[w].s1) == l[q].t1 && r[w].reversed == l[q].reversed);
                    }
                    CHECK_MSG(back, "%s: face %u patch %u edge %u: no link back", name, f, k, e);
                }
                if (closed)
                    CHECK_MSG(covered == 1, "%s: face %u patch %u edge %u covered %g", name, f, k, e, covered);
            }
    }
    return worst;
}

TEST(shared_edges_agree)
{
    cage_buf b;
    uint32_t links;
    cube(&b);
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (s) {
        double w = check_links(s, true, "cube", &links);
        CHECK_MSG(w <= 1e-12, "cube: shared edges differ by %g", w);
        CHECK(links == 24);
        double gap = -1;
        CHECK(tsr_subd_link_gap(s, &gap, NULL) == TSR_OK);
        CHECK_MSG(gap >= 0 && gap <= w, "cube: link gap %g, edges differ by %g", gap, w);
        tsr_subd_destroy(s);
    }
    pyramid(&b);
    for (int sch = 0; sch < 2; sch++) {
        s = make(&b.c, sch ? TSR_SUBD_BILINEAR : TSR_SUBD_CATMARK);
        if (!s)
            continue;
        CHECK(tsr_subd_face_patches(s, 0) == 1 && tsr_subd_face_patches(s, 1) == 3);
        double w = check_links(s, true, "pyramid", &links);
        CHECK_MSG(w <= 1e-12, "pyramid: shared edges differ by %g", w);
        /* base: 4 edges x 2 halves; triangles: 3 patches x (2 inner + 2 outer halves) */
        CHECK(links == 8 + 4 * 3 * 4);
        /* a quad edge meeting a triangle is split at 1/2 */
        tsr_subd_link l[2];
        CHECK(tsr_subd_patch_neighbours(s, 0, 0, 0, l) == 2);
        CHECK(l[0].t0 == 0 && l[0].t1 == 0.5 && l[1].t0 == 0.5 && l[1].t1 == 1);
        tsr_subd_destroy(s);
    }
    /* An open grid: boundary edges have no neighbour. */
    grid(&b, 3, NULL, 1);
    s = make(&b.c, TSR_SUBD_CATMARK);
    if (s) {
        double w = check_links(s, false, "grid", &links);
        CHECK(w <= 1e-12);
        CHECK(links == 2 * 12); /* 12 interior edges */
        tsr_subd_destroy(s);
    }
}

/* ---- (5) bounds ---------------------------------------------------------- */

static void check_bounds(const tsr_subd *s, const char *name, int samples)
{
    for (uint32_t f = 0; f < tsr_subd_face_count(s); f++) {
        if (!tsr_subd_face_has_limit(s, f))
            continue;
        for (uint32_t k = 0; k < tsr_subd_face_patches(s, f); k++) {
            double lo[3], hi[3];
            CHECK(tsr_subd_face_bounds(s, f, k, lo, hi) == TSR_OK);
            bool in = true;
            for (int j = 0; j <= samples; j++)
                for (int i = 0; i <= samples; i++) {
                    double uv[2] = {(double)i / samples, (double)j / samples}, p[3];
                    CHECK(tsr_subd_eval(s, f, k, uv, 1, p, NULL, NULL) == TSR_OK);
                    for (int c = 0; c < 3; c++)
                        in = in && p[c] >= lo[c] && p[c] <= hi[c];
                }
            CHECK_MSG(in, "%s: face %u patch %u leaves its box", name, f, k);
        }
    }
}

TEST(bounds_contain_samples)
{
    cage_buf b;
    cube(&b);
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (s) {
        check_bounds(s, "cube", 32);
        /* the cube's limit is inside the cage's box */
        double lo[3], hi[3];
        CHECK(tsr_subd_face_bounds(s, 0, 0, lo, hi) == TSR_OK);
        CHECK(hi[2] <= 1 + 1e-12 && lo[2] >= -1 - 1e-12);
        tsr_subd_destroy(s);
    }
    pyramid(&b);
    s = make(&b.c, TSR_SUBD_CATMARK);
    if (s) {
        check_bounds(s, "pyramid", 32);
        tsr_subd_destroy(s);
    }
    double z[36];
    for (int k = 0; k < 36; k++)
        z[k] = sin(k * 0.9) * 2;
    grid(&b, 5, z, 2);
    uint32_t crease[4] = {7, 8, 8, 9};
    float sharp[2] = {1.5f, 3};
    b.c.num_creases = 2;
    b.c.crease_verts = crease;
    b.c.crease_sharpness = sharp;
    uint32_t corner = 21;
    float csharp = 2.5f;
    b.c.num_corners = 1;
    b.c.corner_verts = &corner;
    b.c.corner_sharpness = &csharp;
    s = make(&b.c, TSR_SUBD_CATMARK);
    if (s) {
        check_bounds(s, "creased wavy grid", 32);
        tsr_subd_destroy(s);
    }
}

/* ---- (6) bad cages ---------------------------------------------------------- */

static void refused(const tsr_cage *c, tsr_status want, const char *needle)
{
    tsr_subd *s = (tsr_subd *)1;
    tsr_error err = {0};
    tsr_status st = tsr_subd_create(c, TSR_SUBD_CATMARK, NULL, &s, &err);
    CHECK_MSG(st == want, "%s: status %d, want %d (%s)", needle, (int)st, (int)want, err.message);
    CHECK(s == NULL);
    CHECK_MSG(strstr(err.message, needle) != NULL, "message \"%s\" lacks \"%s\"", err.message, needle);
}

TEST(bad_cages_refused)
{
    cage_buf b;
    cube(&b);
    b.verts[5] = 8;
    refused(&b.c, TSR_ERR_VALUE, "face 1 names vertex 8");
    cube(&b);
    b.sizes[2] = 2;
    refused(&b.c, TSR_ERR_VALUE, "face 2 has 2 vertices");
    cube(&b);
    b.c.num_faces = 0;
    refused(&b.c, TSR_ERR_EMPTY, "empty");
    cube(&b);
    b.c.num_points = 0;
    refused(&b.c, TSR_ERR_EMPTY, "empty");
    refused(NULL, TSR_ERR_ARGUMENT, "NULL");
    cube(&b);
    b.pts[7] = NAN;
    refused(&b.c, TSR_ERR_VALUE, "point 2");
    cube(&b);
    uint32_t diag[2] = {4, 7}; /* a diagonal of the top face */
    float sharp = 2;
    b.c.num_creases = 1;
    b.c.crease_verts = diag;
    b.c.crease_sharpness = &sharp;
    refused(&b.c, TSR_ERR_VALUE, "crease 0 (4, 7) is not an edge");
    uint32_t edge[2] = {4, 5};
    b.c.crease_verts = edge;
    sharp = -1;
    refused(&b.c, TSR_ERR_VALUE, "crease 0 has sharpness -1");
    cube(&b);
    uint32_t hole = 6;
    b.c.num_holes = 1;
    b.c.hole_faces = &hole;
    refused(&b.c, TSR_ERR_VALUE, "hole 0 names face 6");
    cube(&b);
    uint32_t corner = 9;
    float cs = 1;
    b.c.num_corners = 1;
    b.c.corner_verts = &corner;
    b.c.corner_sharpness = &cs;
    refused(&b.c, TSR_ERR_VALUE, "corner 0 names vertex 9");
    cube(&b);
    b.c.boundary_interp = 3;
    refused(&b.c, TSR_ERR_ARGUMENT, "boundary interpolation 3");
    cube(&b);
    tsr_subd *s = NULL;
    CHECK(tsr_subd_create(&b.c, (tsr_subd_scheme)7, NULL, &s, NULL) == TSR_ERR_ARGUMENT && !s);
    CHECK(tsr_subd_create(&b.c, TSR_SUBD_CATMARK, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    /* queries on nothing answer nothing */
    CHECK(tsr_subd_face_count(NULL) == 0 && !tsr_subd_face_has_limit(NULL, 0));
    tsr_subd_destroy(NULL);
}

/* A quad with two coincident corners: du vanishes along v = 1, and the
 * normal comes from just inside. */
TEST(degenerate_patch_corner_normal)
{
    static const double p[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 0, 1, 0};
    static const uint32_t sizes[1] = {4}, verts[4] = {0, 1, 2, 3};
    cage_buf b;
    cage_init(&b, p, 4, sizes, 1, verts, 1);
    tsr_subd *s = make(&b.c, TSR_SUBD_BILINEAR);
    if (!s)
        return;
    double uv[2] = {0.5, 1}, q[3], du[3], dv[3], n[3];
    eval1(s, 0, 0, uv[0], uv[1], q, du, dv);
    CHECK(fabs(du[0]) + fabs(du[1]) + fabs(du[2]) == 0);
    CHECK(tsr_subd_normal(s, 0, 0, uv, n) == TSR_OK);
    CHECK_NEAR(n[2], 1, 1e-12);
    tsr_subd_destroy(s);
}

/* ---- (7) uniform tessellation ----------------------------------------------- */

static double signed_volume(const tsr_mesh *m)
{
    double v = 0;
    for (uint32_t t = 0; t < m->triangle_count; t++) {
        const float *a = m->positions + 3 * m->indices[3 * t], *b = m->positions + 3 * m->indices[3 * t + 1],
                    *c = m->positions + 3 * m->indices[3 * t + 2];
        v += ((double)a[0] * ((double)b[1] * c[2] - (double)b[2] * c[1]) -
              (double)a[1] * ((double)b[0] * c[2] - (double)b[2] * c[0]) +
              (double)a[2] * ((double)b[0] * c[1] - (double)b[1] * c[0])) /
             6;
    }
    return v;
}

/* Every undirected edge used exactly twice, once each way. */
static bool edges_paired(const tsr_mesh *m)
{
    uint32_t n = 3 * m->triangle_count;
    uint64_t *key = malloc(sizeof(uint64_t) * n);
    for (uint32_t h = 0; h < n; h++) {
        uint32_t a = m->indices[h], b = m->indices[h - h % 3 + (h % 3 + 1) % 3];
        key[h] = (uint64_t)a << 32 | b;
    }
    bool ok = true;
    for (uint32_t h = 0; h < n && ok; h++) {
        uint64_t twin = key[h] >> 32 | key[h] << 32;
        int same = 0, opposite = 0;
        for (uint32_t g = 0; g < n; g++)
            same += key[g] == key[h], opposite += key[g] == twin;
        ok = same == 1 && opposite == 1;
    }
    free(key);
    return ok;
}

TEST(uniform_tessellation_closed)
{
    cage_buf b;
    cube(&b);
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    for (uint32_t r = 1; r <= 7; r += 3) {
        tsr_mesh m;
        tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
        tsr_error err = {0};
        CHECK_MSG(tsr_subd_tessellate_uniform(s, r, &m, &err) == TSR_OK, "%s", err.message);
        /* 8 corners, r-1 points per edge, (r-1)^2 per face; 2 r^2 triangles per face */
        CHECK_MSG(m.vertex_count == 6 * r * r + 2 && m.triangle_count == 12 * r * r,
                  "rate %u: %u vertices %u triangles", r, m.vertex_count, m.triangle_count);
        tsr_validation v;
        CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
        char msg[512];
        tsr_validation_describe(&v, msg, sizeof msg);
        CHECK_MSG(tsr_validation_ok(&v) && v.boundary_edges == 0 && v.euler == 2, "rate %u: %s", r, msg);
        CHECK(edges_paired(&m));
        double vol = signed_volume(&m);
        CHECK_MSG(vol > 0 && vol < 8, "volume %g", vol);
        bool out = true;
        for (uint32_t i = 0; i < m.vertex_count; i++) {
            const float *p = m.positions + 3 * i, *n = m.normals + 3 * i;
            out = out && p[0] * n[0] + p[1] * n[1] + p[2] * n[2] > 0;
        }
        CHECK(out);
        tsr_mesh_free(&m);
    }
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    tsr_error err = {0};
    CHECK(tsr_subd_tessellate_uniform(s, 0, &m, &err) == TSR_ERR_ARGUMENT && strstr(err.message, "rate 0"));
    CHECK(m.vertex_count == 0);
    tsr_subd_destroy(s);

    /* quads meeting triangles (sub-face parameterisation) */
    pyramid(&b);
    s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    for (uint32_t r = 1; r <= 6; r++) {
        tsr_mesh_init(&m, 0, NULL);
        CHECK(tsr_subd_tessellate_uniform(s, r, &m, &err) == TSR_OK);
        tsr_validation v;
        CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
        char msg[512];
        tsr_validation_describe(&v, msg, sizeof msg);
        CHECK_MSG(tsr_validation_ok(&v) && v.boundary_edges == 0 && v.euler == 2, "pyramid rate %u: %s", r, msg);
        CHECK(edges_paired(&m));
        CHECK(signed_volume(&m) > 0);
        tsr_mesh_free(&m);
    }
    tsr_subd_destroy(s);
}

/* ---- OpenSubdiv's regression shapes ---------------------------------------- */

typedef struct obj_cage {
    tsr_cage c;
    double *pts;
    uint32_t *sizes, *verts, *creases, *corners, *holes;
    float *csharp, *vsharp;
    uint32_t np, nf, nv, ncr, nco, nh;
} obj_cage;

static void *grow(void *p, uint32_t n, size_t each)
{
    return (n & (n - 1)) == 0 ? realloc(p, each * (n ? 2 * n : 1)) : p;
}

/* v, f (first index of each corner, 1-based) and the t tags crease,
 * corner, hole, interpolateboundary (RenderMan's numbers: 0 none, 1 edge
 * and corner, 2 edge only; absent, edge only). */
static bool read_obj(const char *path, obj_cage *o)
{
    memset(o, 0, sizeof *o);
    FILE *fp = fopen(path, "r");
    if (!fp)
        return false;
    char line[4096];
    int boundary = 1;
    while (fgets(line, sizeof line, fp)) {
        char *p = line;
        if (p[0] == 'v' && p[1] == ' ') {
            o->pts = grow(o->pts, o->np, 3 * sizeof(double));
            sscanf(p + 2, "%lf %lf %lf", o->pts + 3 * o->np, o->pts + 3 * o->np + 1, o->pts + 3 * o->np + 2);
            o->np++;
        } else if (p[0] == 'f' && p[1] == ' ') {
            uint32_t n = 0;
            char *tok = strtok(p + 2, " \t\r\n");
            for (; tok; tok = strtok(NULL, " \t\r\n"), n++) {
                o->verts = grow(o->verts, o->nv, sizeof(uint32_t));
                o->verts[o->nv++] = (uint32_t)(atol(tok) - 1);
            }
            o->sizes = grow(o->sizes, o->nf, sizeof(uint32_t));
            o->sizes[o->nf++] = n;
        } else if (p[0] == 't' && p[1] == ' ') {
            char name[64];
            int ni = 0, nfl = 0, ns = 0, used = 0;
            if (sscanf(p + 2, "%63s %d/%d/%d%n", name, &ni, &nfl, &ns, &used) != 4)
                continue;
            p += 2 + used;
            long iv[64];
            double fv[64];
            for (int k = 0; k < ni && k < 64; k++)
                iv[k] = strtol(p, &p, 10);
            for (int k = 0; k < nfl && k < 64; k++)
                fv[k] = strtod(p, &p);
            if (!strcmp(name, "crease"))
                for (int k = 0; k + 1 < ni; k += 2) {
                    o->creases = grow(o->creases, o->ncr, 2 * sizeof(uint32_t));
                    o->csharp = grow(o->csharp, o->ncr, sizeof(float));
                    o->creases[2 * o->ncr] = (uint32_t)iv[k];
                    o->creases[2 * o->ncr + 1] = (uint32_t)iv[k + 1];
                    o->csharp[o->ncr++] = (float)fv[nfl > 1 ? k / 2 : 0];
                }
            else if (!strcmp(name, "corner"))
                for (int k = 0; k < ni; k++) {
                    o->corners = grow(o->corners, o->nco, sizeof(uint32_t));
                    o->vsharp = grow(o->vsharp, o->nco, sizeof(float));
                    o->corners[o->nco] = (uint32_t)iv[k];
                    o->vsharp[o->nco++] = (float)fv[nfl > 1 ? k : 0];
                }
            else if (!strcmp(name, "hole"))
                for (int k = 0; k < ni; k++) {
                    o->holes = grow(o->holes, o->nh, sizeof(uint32_t));
                    o->holes[o->nh++] = (uint32_t)iv[k];
                }
            else if (!strcmp(name, "interpolateboundary") && ni == 1)
                boundary = iv[0] == 1 ? 2 : iv[0] == 2 ? 1 : 0;
        }
    }
    fclose(fp);
    o->c.num_points = o->np;
    o->c.points = o->pts;
    o->c.num_faces = o->nf;
    o->c.face_sizes = o->sizes;
    o->c.face_verts = o->verts;
    o->c.num_creases = o->ncr;
    o->c.crease_verts = o->creases;
    o->c.crease_sharpness = o->csharp;
    o->c.num_corners = o->nco;
    o->c.corner_verts = o->corners;
    o->c.corner_sharpness = o->vsharp;
    o->c.num_holes = o->nh;
    o->c.hole_faces = o->holes;
    o->c.boundary_interp = boundary;
    o->c.fvar_interp = 5;
    return o->nf > 0;
}

static void free_obj(obj_cage *o)
{
    free(o->pts), free(o->sizes), free(o->verts), free(o->creases), free(o->corners), free(o->holes);
    free(o->csharp), free(o->vsharp);
}

/* Every shape: created (or refused with a message), shared edges agree to
 * 1e-12 of the shape's size, bounds hold, and the uniform tessellation of a
 * closed manifold shape is closed. */
TEST(data_osd_shapes)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    static const char *names[] = {"bilinear_cube",
                                  "bilinear_nonplanar",
                                  "bilinear_nonquads0",
                                  "bilinear_nonquads1",
                                  "catmark_chaikin0",
                                  "catmark_cube",
                                  "catmark_cube_corner0",
                                  "catmark_cube_creases0",
                                  "catmark_cube_creases2",
                                  "catmark_cubes_semisharp",
                                  "catmark_dart_edgecorner",
                                  "catmark_edgecorner",
                                  "catmark_edgenone",
                                  "catmark_edgeonly",
                                  "catmark_fan",
                                  "catmark_flap",
                                  "catmark_gregory_test0",
                                  "catmark_gregory_test2",
                                  "catmark_gregory_test5",
                                  "catmark_gregory_test8",
                                  "catmark_hole_test2",
                                  "catmark_hole_test3",
                                  "catmark_inf_crease1",
                                  "catmark_nonman_edges",
                                  "catmark_nonman_quadpole8",
                                  "catmark_nonman_verts",
                                  "catmark_nonquads",
                                  "catmark_pole8",
                                  "catmark_pyramid",
                                  "catmark_pyramid_creases1",
                                  "catmark_quadstrips",
                                  "catmark_single_crease",
                                  "catmark_smoothtris0",
                                  "catmark_tent_creases1",
                                  "catmark_toroidal_tet",
                                  "catmark_torus_creases1",
                                  "catmark_val2_back2back",
                                  "catmark_val2_foldover",
                                  "catmark_val2_interior",
                                  "catmark_val2_nonman",
                                  "catmark_xord_boundary",
                                  "catmark_xord_interior"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[8192];
        snprintf(path, sizeof path, "%s/patches/osd/%s.obj", data, names[i]);
        obj_cage o;
        if (!read_obj(path, &o)) {
            CHECK_MSG(0, "%s: cannot read", path);
            free_obj(&o);
            continue;
        }
        bool bilinear = !strncmp(names[i], "bilinear", 8);
        tsr_subd *s = NULL;
        tsr_error err = {0};
        tsr_status st = tsr_subd_create(&o.c, bilinear ? TSR_SUBD_BILINEAR : TSR_SUBD_CATMARK, NULL, &s, &err);
        CHECK_MSG(st == TSR_OK, "%s: %s", names[i], err.message);
        if (st != TSR_OK) {
            free_obj(&o);
            continue;
        }
        double size = 0;
        for (uint32_t k = 0; k < 3 * o.np; k++)
            size = fmax(size, fabs(o.pts[k]));
        uint32_t links, with = 0;
        for (uint32_t f = 0; f < o.nf; f++)
            with += tsr_subd_face_has_limit(s, f);
        double w = check_links(s, false, names[i], &links);
        CHECK_MSG(w <= 1e-12 * (1 + size), "%s: shared edges differ by %g", names[i], w);
        double gap = -1; /* 9 of check_links' 17 points per link */
        CHECK(tsr_subd_link_gap(s, &gap, NULL) == TSR_OK);
        CHECK_MSG(gap >= 0 && gap <= w, "%s: link gap %g, edges differ by %g", names[i], gap, w);
        check_bounds(s, names[i], 12);
        tsr_mesh m;
        tsr_mesh_init(&m, TSR_MESH_NORMALS, NULL);
        CHECK_MSG(tsr_subd_tessellate_uniform(s, 4, &m, &err) == TSR_OK, "%s: %s", names[i], err.message);
        CHECK(with == 0 || m.triangle_count > 0);
        if (!strcmp(names[i], "catmark_cube") || !strcmp(names[i], "catmark_pyramid") ||
            !strcmp(names[i], "catmark_torus_creases1") || !strcmp(names[i], "catmark_toroidal_tet")) {
            tsr_validation v;
            CHECK(tsr_mesh_validate(&m, NULL, &v) == TSR_OK);
            char msg[512];
            tsr_validation_describe(&v, msg, sizeof msg);
            CHECK_MSG(tsr_validation_ok(&v) && v.boundary_edges == 0, "%s: %s", names[i], msg);
            CHECK_MSG(signed_volume(&m) > 0, "%s: volume %g", names[i], signed_volume(&m));
        }
        fprintf(stderr, "  %-26s %3u/%3u faces with limit, %4u links, edge gap %.2g, %u triangles\n", names[i], with,
                o.nf, links, w, m.triangle_count);
        tsr_mesh_free(&m);
        tsr_subd_destroy(s);
        free_obj(&o);
    }
}

/* ---- Bézier patches as cages, and uniform tessellations of face lists ------ */

static double lcg_uniform(uint64_t *state)
{
    *state = *state * 6364136223846793005ull + 1442695040888963407ull;
    return (double)(*state >> 11) / 9007199254740992.0;
}

/* The bicubic Bézier patch b (48 doubles, point (i, j) at 3 (4 j + i)) at
 * (s, t), by the Bernstein polynomials written out. */
static void bezier_point(const double *b, double s, double t, double out[3])
{
    double bs[4] = {(1 - s) * (1 - s) * (1 - s), 3 * s * (1 - s) * (1 - s), 3 * s * s * (1 - s), s * s * s};
    double bt[4] = {(1 - t) * (1 - t) * (1 - t), 3 * t * (1 - t) * (1 - t), 3 * t * t * (1 - t), t * t * t};
    out[0] = out[1] = out[2] = 0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            for (int c = 0; c < 3; c++)
                out[c] += bs[i] * bt[j] * b[3 * (4 * j + i) + c];
}

/* Random bicubic nets (and one with a collapsed edge, like the teapot's lid)
 * become a cage whose middle faces reproduce them: the B-spline points map
 * back to the Bézier points by the forward basis change, and Bfr's limit
 * at (u, v) on face TSR_SUBD_BEZIER_FACE(p) is the Bézier point at (s, t) =
 * (u, v) (a swapped or mirrored parameterisation, or a wrong inverse, is
 * off by the patch's size). */
/* tsr_subd_link_gap where Bfr's faces disagree: catmark_chaikin1 (its
 * face 11, between Chaikin creases of sharpness 5, evaluates its corners
 * 1.7e-3 from its neighbours' with OpenSubdiv 3.5.0). The gap equals the
 * largest disagreement among the face corners that share a cage vertex,
 * found here from the cage's face lists (the link walk does not enter),
 * and check_links' sampling of the same links. */
TEST(data_link_gap_corners)
{
    const char *data = check_data_dir();
    if (!data)
        SKIP("no shared data folder (set TESSERA_DATA)");
    char path[8192];
    snprintf(path, sizeof path, "%s/patches/osd/catmark_chaikin1.obj", data);
    /* the library's loader: the file ends with "t creasemethod ... chaikin",
     * which read_obj above does not take */
    tsr_cage c;
    tsr_error err = {0};
    CHECK_MSG(tsr_cage_load(path, NULL, &c, &err) == TSR_OK, "%s", err.message);
    if (err.status != TSR_OK)
        return;
    CHECK(c.crease_method == 1);
    tsr_subd *s = make(&c, TSR_SUBD_CATMARK);
    if (!s) {
        tsr_cage_free(&c);
        return;
    }
    /* every face is a quad here: corner k at (0,0), (1,0), (1,1), (0,1) */
    static const double cuv[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    double corner = 0;
    for (uint32_t f = 0; f < c.num_faces; f++) {
        CHECK(c.face_sizes[f] == 4);
        for (uint32_t g = f + 1; g < c.num_faces; g++)
            for (uint32_t a = 0; a < 4; a++)
                for (uint32_t b = 0; b < 4; b++) {
                    if (c.face_verts[4 * f + a] != c.face_verts[4 * g + b])
                        continue;
                    double pa[3], pb[3];
                    CHECK(tsr_subd_eval(s, f, 0, cuv[a], 1, pa, NULL, NULL) == TSR_OK);
                    CHECK(tsr_subd_eval(s, g, 0, cuv[b], 1, pb, NULL, NULL) == TSR_OK);
                    corner = fmax(corner, dist3(pa, pb));
                }
    }
    uint32_t links;
    double w = check_links(s, true, "catmark_chaikin1", &links);
    double gap = -1;
    tsr_subd_gap_at at;
    CHECK(tsr_subd_link_gap(s, &gap, &at) == TSR_OK);
    CHECK_MSG(fabs(gap - corner) <= 1e-15 && gap <= w, "catmark_chaikin1: link gap %g, corners %g, edges %g", gap,
              corner, w);
    /* where it says: the two points evaluate that far apart */
    double pa[3], pb[3];
    CHECK(tsr_subd_eval(s, at.face, at.sub, at.uv, 1, pa, NULL, NULL) == TSR_OK);
    CHECK(tsr_subd_eval(s, at.other_face, at.other_sub, at.other_uv, 1, pb, NULL, NULL) == TSR_OK);
    CHECK(dist3(pa, pb) == gap);
    fprintf(stderr, "  catmark_chaikin1: link gap %.3g (face %u against face %u), corners %.3g\n", gap, at.face,
            at.other_face, corner);
    tsr_subd_destroy(s);
    tsr_cage_free(&c);
}

TEST(bezier_cage_reproduces_patches)
{
    enum { NP = 5 };
    double ctrl[48 * NP];
    uint64_t seed = 12345;
    for (int k = 0; k < 48 * NP; k++)
        ctrl[k] = 10 * lcg_uniform(&seed) - 5 + (k % 3 == 0 ? 100 : 0); /* off the origin: relative matters */
    for (int i = 0; i < 4; i++) /* patch 4: the row t = 0 collapsed to one point */
        for (int c = 0; c < 3; c++)
            ctrl[48 * 4 + 3 * i + c] = ctrl[48 * 4 + c];
    tsr_cage cage;
    tsr_error err = {0};
    CHECK_MSG(tsr_subd_cage_from_bezier(ctrl, NP, NULL, &cage, &err) == TSR_OK, "%s", err.message);
    CHECK(cage.num_points == 16 * NP && cage.num_faces == 9 * NP && cage.num_face_verts == 36 * NP);
    double scale = 0;
    for (int k = 0; k < 48 * NP; k++)
        scale = fmax(scale, fabs(ctrl[k]));

    /* forward change per direction: the segment's Bézier points from Q */
    static const double M[4][4] = {
        {1. / 6, 4. / 6, 1. / 6, 0}, {0, 4. / 6, 2. / 6, 0}, {0, 2. / 6, 4. / 6, 0}, {0, 1. / 6, 4. / 6, 1. / 6}};
    double back = 0;
    for (int p = 0; p < NP; p++)
        for (int j = 0; j < 4; j++)
            for (int i = 0; i < 4; i++)
                for (int c = 0; c < 3; c++) {
                    double sum = 0;
                    for (int l = 0; l < 4; l++)
                        for (int k = 0; k < 4; k++)
                            sum += M[i][k] * M[j][l] * cage.points[3 * (16 * p + 4 * l + k) + c];
                    back = fmax(back, fabs(sum - ctrl[48 * p + 3 * (4 * j + i) + c]));
                }
    CHECK_MSG(back <= 1e-13 * scale, "forward basis change of the B-spline points: off by %g", back / scale);

    tsr_subd *s = make(&cage, TSR_SUBD_CATMARK);
    if (!s) {
        tsr_cage_free(&cage);
        return;
    }
    for (uint32_t f = 0; f < 9 * NP; f++)
        CHECK_MSG(tsr_subd_face_has_limit(s, f) == (f % 9 == 4), "face %u", f);
    double worst = 0;
    int worst_p = -1;
    for (int p = 0; p < NP; p++) {
        double uv[2 * 204], pos[3 * 204];
        static const double corners[8] = {0, 0, 1, 0, 1, 1, 0, 1};
        memcpy(uv, corners, sizeof corners);
        for (int k = 8; k < 2 * 204; k++)
            uv[k] = lcg_uniform(&seed);
        CHECK(tsr_subd_eval(s, TSR_SUBD_BEZIER_FACE(p), 0, uv, 204, pos, NULL, NULL) == TSR_OK);
        for (int k = 0; k < 204; k++) {
            double ref[3];
            bezier_point(ctrl + 48 * p, uv[2 * k], uv[2 * k + 1], ref);
            double d = dist3(pos + 3 * k, ref) / scale;
            if (d > worst)
                worst = d, worst_p = p;
        }
    }
    CHECK_MSG(worst <= 1e-12, "Bfr's middle face off the Bezier patch by %g (relative; patch %d)", worst, worst_p);
    fprintf(stderr, "  Bfr middle face vs Bezier patch: max relative distance %.3g\n", worst);

    /* with boundary_interp 0 the whole cage is the patches: the middle faces listed alone give the same mesh */
    tsr_mesh all, mid;
    tsr_mesh_init(&all, 0, NULL);
    tsr_mesh_init(&mid, 0, NULL);
    uint32_t faces[NP];
    for (uint32_t p = 0; p < NP; p++)
        faces[p] = TSR_SUBD_BEZIER_FACE(p);
    CHECK(tsr_subd_tessellate_uniform(s, 5, &all, &err) == TSR_OK);
    CHECK(tsr_subd_tessellate_uniform_faces(s, 5, faces, NP, &mid, &err) == TSR_OK);
    CHECK_MSG(mid.triangle_count == NP * 50 && mid.vertex_count == NP * 36, "%u triangles, %u vertices",
              mid.triangle_count, mid.vertex_count);
    CHECK(all.triangle_count == mid.triangle_count && all.vertex_count == mid.vertex_count &&
          !memcmp(all.indices, mid.indices, 3 * sizeof(uint32_t) * mid.triangle_count) &&
          !memcmp(all.positions, mid.positions, 3 * sizeof(float) * mid.vertex_count));
    tsr_mesh_free(&all);
    tsr_mesh_free(&mid);
    tsr_subd_destroy(s);
    tsr_cage_free(&cage);

    /* refusals */
    CHECK(tsr_subd_cage_from_bezier(ctrl, 0, NULL, &cage, &err) == TSR_ERR_EMPTY);
    CHECK(tsr_subd_cage_from_bezier(NULL, 1, NULL, &cage, &err) == TSR_ERR_ARGUMENT);
    ctrl[48 * 2 + 7] = NAN;
    CHECK(tsr_subd_cage_from_bezier(ctrl, NP, NULL, &cage, &err) == TSR_ERR_VALUE && strstr(err.message, "patch 2"));
    CHECK(cage.points == NULL && cage.num_points == 0);
}

/* The faces of a list alone: in the list's order, each face's triangles
 * those of the whole tessellation (the same corners, up to the last bits
 * of points the two runs evaluate from different faces), and its vertices
 * welded among the listed faces only. */
TEST(uniform_faces_subset)
{
    cage_buf b;
    cube(&b);
    tsr_subd *s = make(&b.c, TSR_SUBD_CATMARK);
    if (!s)
        return;
    static const uint32_t list[3] = {4, 1, 3}; /* left, bottom, back: they meet at vertex 2 */
    tsr_error err = {0};
    for (uint32_t r = 1; r <= 6; r++) {
        tsr_mesh all, sub;
        tsr_mesh_init(&all, 0, NULL);
        tsr_mesh_init(&sub, 0, NULL);
        CHECK(tsr_subd_tessellate_uniform(s, r, &all, &err) == TSR_OK);
        CHECK_MSG(tsr_subd_tessellate_uniform_faces(s, r, list, 3, &sub, &err) == TSR_OK, "%s", err.message);
        uint32_t per = 2 * r * r;
        CHECK_MSG(sub.triangle_count == 3 * per, "rate %u: %u triangles", r, sub.triangle_count);
        /* three faces pairwise sharing an edge, all three a vertex */
        CHECK_MSG(sub.vertex_count == 3 * (r + 1) * (r + 1) - 3 * (r + 1) + 1, "rate %u: %u vertices", r,
                  sub.vertex_count);
        double worst = 0;
        for (uint32_t q = 0; q < 3 && sub.triangle_count == 3 * per; q++)
            for (uint32_t t = 0; t < per; t++)
                for (int a = 0; a < 3; a++) {
                    const float *x = sub.positions + 3 * sub.indices[3 * (q * per + t) + a];
                    const float *y = all.positions + 3 * all.indices[3 * (list[q] * per + t) + a];
                    for (int c = 0; c < 3; c++)
                        worst = fmax(worst, fabs((double)x[c] - y[c]));
                }
        CHECK_MSG(worst <= 1e-6, "rate %u: listed faces' triangles off the whole tessellation's by %g", r, worst);
        tsr_mesh_free(&sub);
        /* every face, in order: the whole tessellation, bit for bit */
        static const uint32_t every[6] = {0, 1, 2, 3, 4, 5};
        tsr_mesh_init(&sub, 0, NULL);
        CHECK(tsr_subd_tessellate_uniform_faces(s, r, every, 6, &sub, &err) == TSR_OK);
        CHECK(sub.triangle_count == all.triangle_count && sub.vertex_count == all.vertex_count &&
              !memcmp(sub.indices, all.indices, 3 * sizeof(uint32_t) * all.triangle_count) &&
              !memcmp(sub.positions, all.positions, 3 * sizeof(float) * all.vertex_count));
        tsr_mesh_free(&sub);
        tsr_mesh_free(&all);
    }
    tsr_mesh m;
    tsr_mesh_init(&m, 0, NULL);
    static const uint32_t bad[2] = {2, 6}, twice[3] = {2, 0, 2};
    CHECK(tsr_subd_tessellate_uniform_faces(s, 3, bad, 2, &m, &err) == TSR_ERR_ARGUMENT &&
          strstr(err.message, "face 6"));
    CHECK(tsr_subd_tessellate_uniform_faces(s, 3, twice, 3, &m, &err) == TSR_ERR_ARGUMENT &&
          strstr(err.message, "twice"));
    CHECK(tsr_subd_tessellate_uniform_faces(s, 0, list, 3, &m, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_subd_tessellate_uniform_faces(s, 3, NULL, 1, &m, &err) == TSR_ERR_ARGUMENT);
    CHECK(tsr_subd_tessellate_uniform_faces(s, 3, NULL, 0, &m, &err) == TSR_OK);
    CHECK(m.vertex_count == 0 && m.triangle_count == 0);
    tsr_mesh_free(&m);
    tsr_subd_destroy(s);
}

TEST_MAIN(T(bilinear_quad_is_bilinear_interpolation), T(bilinear_ngon_subpatches), T(planar_grid_stays_in_plane),
          T(regular_face_is_bicubic_bspline), T(cube_limit_values_and_symmetry), T(holes_and_boundaries_have_no_limit),
          T(shared_edges_agree), T(bounds_contain_samples), T(bad_cages_refused), T(degenerate_patch_corner_normal),
          T(uniform_tessellation_closed), T(bezier_cage_reproduces_patches), T(uniform_faces_subset),
          T(data_osd_shapes), T(data_link_gap_corners))
