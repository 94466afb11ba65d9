/* Patch evaluation (tsr_patch_*) against independent oracles: closed forms
 * (planes, a rational cylinder and sphere whose every point lies at the
 * radius), a naive Cox-de Boor recursion written here, central finite
 * differences, and the parent patch for splits and Bézier pieces. */
#include "check.h"
#include "patches/patches.h"

static unsigned rng = 12345;
static double rnd(void) /* [0, 1) */
{
    rng = rng * 1664525u + 1013904223u;
    return (double)(rng >> 8) / 16777216.0;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
static double len3(const double a[3])
{
    return sqrt(dot3(a, a));
}

/* ---- Oracle: Cox-de Boor recursion, straight from the definition ---------- */

static double cox(const double *t, int i, int k, double x)
{
    if (k == 0)
        return t[i] <= x && x < t[i + 1] ? 1.0 : 0.0;
    double a = 0, b = 0;
    if (t[i + k] != t[i])
        a = (x - t[i]) / (t[i + k] - t[i]) * cox(t, i, k - 1, x);
    if (t[i + k + 1] != t[i + 1])
        b = (t[i + k + 1] - x) / (t[i + k + 1] - t[i + 1]) * cox(t, i + 1, k - 1, x);
    return a + b;
}

/* S(u, v) by the definition, for points strictly inside a span. */
static void oracle_eval(const tsr_patch *p, double u, double v, double out[3])
{
    double num[3] = {0, 0, 0}, den = 0, nu[64], nv[64];
    for (uint32_t i = 0; i < p->count_u; i++)
        nu[i] = cox(p->knots_u, (int)i, p->degree_u, u);
    for (uint32_t j = 0; j < p->count_v; j++)
        nv[j] = cox(p->knots_v, (int)j, p->degree_v, v);
    for (uint32_t j = 0; j < p->count_v; j++)
        for (uint32_t i = 0; i < p->count_u; i++) {
            double w = p->weights ? p->weights[j * p->count_u + i] : 1.0;
            for (int c = 0; c < 3; c++)
                num[c] += nu[i] * nv[j] * w * p->ctrl[3 * (j * p->count_u + i) + c];
            den += nu[i] * nv[j] * w;
        }
    for (int c = 0; c < 3; c++)
        out[c] = num[c] / den;
}

static double binom(int n, int k)
{
    double r = 1;
    for (int i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}
static double bern(int n, int i, double t)
{
    return binom(n, i) * pow(t, i) * pow(1 - t, n - i);
}

/* A rational Bézier patch by the Bernstein form over its domain. */
static void oracle_bezier(const tsr_patch *p, double u, double v, double out[3])
{
    double dom[4] = {p->u0, p->u1, p->v0, p->v1};
    if (dom[0] == 0 && dom[1] == 0 && dom[2] == 0 && dom[3] == 0)
        dom[1] = dom[3] = 1;
    double s = (u - dom[0]) / (dom[1] - dom[0]), t = (v - dom[2]) / (dom[3] - dom[2]);
    double num[3] = {0, 0, 0}, den = 0;
    for (int j = 0; j <= p->degree_v; j++)
        for (int i = 0; i <= p->degree_u; i++) {
            int k = j * (p->degree_u + 1) + i;
            double b = bern(p->degree_u, i, s) * bern(p->degree_v, j, t) * (p->weights ? p->weights[k] : 1.0);
            for (int c = 0; c < 3; c++)
                num[c] += b * p->ctrl[3 * k + c];
            den += b;
        }
    for (int c = 0; c < 3; c++)
        out[c] = num[c] / den;
}

/* Central differences of S at (u, v) against du, dv, with step h. */
static void check_derivatives(const tsr_patch *p, double u, double v, double h, double tol)
{
    double pos[3], du[3], dv[3], a[3], b[3];
    CHECK(tsr_patch_eval(p, u, v, pos, du, dv, NULL) == TSR_OK);
    tsr_patch_eval(p, u + h, v, a, NULL, NULL, NULL);
    tsr_patch_eval(p, u - h, v, b, NULL, NULL, NULL);
    for (int c = 0; c < 3; c++)
        CHECK_NEAR(du[c], (a[c] - b[c]) / (2 * h), tol * (1 + fabs(du[c])));
    tsr_patch_eval(p, u, v + h, a, NULL, NULL, NULL);
    tsr_patch_eval(p, u, v - h, b, NULL, NULL, NULL);
    for (int c = 0; c < 3; c++)
        CHECK_NEAR(dv[c], (a[c] - b[c]) / (2 * h), tol * (1 + fabs(dv[c])));
}

/* ---- Planes ------------------------------------------------------------------ */

/* A planar quadrilateral (on 2x + 3y - z = 1, not a parallelogram). */
static const double quad[4][3] = {{0, 0, -1}, {2, 0.5, 4.5}, {-0.5, 1.5, 2.5}, {1.5, 2.5, 9.5}};

static void bilinear(double u, double v, double out[3], double du[3], double dv[3])
{
    for (int c = 0; c < 3; c++) {
        out[c] =
            (1 - u) * (1 - v) * quad[0][c] + u * (1 - v) * quad[1][c] + (1 - u) * v * quad[2][c] + u * v * quad[3][c];
        du[c] = (1 - v) * (quad[1][c] - quad[0][c]) + v * (quad[3][c] - quad[2][c]);
        dv[c] = (1 - u) * (quad[2][c] - quad[0][c]) + u * (quad[3][c] - quad[1][c]);
    }
}

static void check_plane(const tsr_patch *p, double scale_u)
{
    double n_plane[3] = {-2, -3, 1}, l = len3(n_plane);
    for (int c = 0; c < 3; c++)
        n_plane[c] /= l;
    for (int k = 0; k < 121; k++) {
        double s = (k % 11) / 10.0, t = (k / 11) / 10.0;
        double pos[3], du[3], dv[3], n[3], rp[3], rdu[3], rdv[3];
        CHECK(tsr_patch_eval(p, p->u0 + s * scale_u, t, pos, du, dv, n) == TSR_OK);
        bilinear(s, t, rp, rdu, rdv);
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(pos[c], rp[c], 1e-12);
            CHECK_NEAR(du[c] * scale_u, rdu[c], 1e-11);
            CHECK_NEAR(dv[c], rdv[c], 1e-11);
        }
        /* the corners are ordered so that du x dv faces the plane normal */
        CHECK_NEAR(dot3(n, n_plane), 1.0, 1e-12);
    }
}

TEST(bilinear_plane)
{
    double ctrl[12];
    memcpy(ctrl, quad, sizeof ctrl);
    tsr_patch p = {TSR_PATCH_BEZIER, 1, 1, 2, 2, ctrl, NULL, NULL, NULL, 0, 0, 0, 0};
    CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
    check_plane(&p, 1);
    /* the same over a stretched domain [2, 5] x [0, 1] */
    p.u0 = 2, p.u1 = 5, p.v0 = 0, p.v1 = 1;
    check_plane(&p, 3);
}

TEST(degree_elevated_plane)
{
    /* degree elevation of a bilinear patch to bicubic: P_ij = B(i/3, j/3) */
    double ctrl[3 * 16], du[3], dv[3];
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++)
            bilinear(i / 3.0, j / 3.0, ctrl + 3 * (4 * j + i), du, dv);
    tsr_patch p = {TSR_PATCH_BEZIER, 3, 3, 4, 4, ctrl, NULL, NULL, NULL, 0, 0, 0, 0};
    check_plane(&p, 1);
    /* and as a clamped B-spline, and a NURBS with equal weights */
    double k[8] = {0, 0, 0, 0, 1, 1, 1, 1}, w[16];
    for (int i = 0; i < 16; i++)
        w[i] = 2.5;
    tsr_patch b = {TSR_PATCH_BSPLINE, 3, 3, 4, 4, ctrl, NULL, k, k, 0, 0, 0, 0};
    CHECK(tsr_patch_check(&b, NULL) == TSR_OK);
    check_plane(&b, 1);
    tsr_patch r = {TSR_PATCH_NURBS, 3, 3, 4, 4, ctrl, w, k, k, 0, 0, 0, 0};
    check_plane(&r, 1);
}

/* ---- Rational quadrics ------------------------------------------------------- */

#define S2 0.70710678118654752440

TEST(cylinder_quarter_rational)
{
    const double r = 2.5, h = 3;
    const double cx[3] = {1, 1, 0}, cy[3] = {0, 1, 1}, cw[3] = {1, S2, 1};
    double ctrl[3 * 6], w[6];
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 3; i++) {
            double *q = ctrl + 3 * (3 * j + i);
            q[0] = r * cx[i], q[1] = r * cy[i], q[2] = h * j;
            w[3 * j + i] = cw[i];
        }
    double ku[6] = {0, 0, 0, 1, 1, 1}, kv[4] = {0, 0, 1, 1};
    tsr_patch bez = {TSR_PATCH_BEZIER, 2, 1, 3, 2, ctrl, w, NULL, NULL, 0, 0, 0, 0};
    tsr_patch nurbs = {TSR_PATCH_NURBS, 2, 1, 3, 2, ctrl, w, ku, kv, 0, 0, 0, 0};
    const tsr_patch *ps[2] = {&bez, &nurbs};
    for (int q = 0; q < 2; q++) {
        CHECK(tsr_patch_check(ps[q], NULL) == TSR_OK);
        for (int k = 0; k < 400; k++) {
            double u = k < 21 ? k / 20.0 : rnd(), v = k < 21 ? 0.5 : rnd();
            double pos[3], n[3];
            CHECK(tsr_patch_eval(ps[q], u, v, pos, NULL, NULL, n) == TSR_OK);
            double rad = hypot(pos[0], pos[1]);
            CHECK_NEAR(rad, r, 1e-12);
            CHECK_NEAR(pos[2], h * v, 1e-12);
            CHECK(pos[0] >= -1e-12 && pos[1] >= -1e-12);
            /* the normal is radial, outwards for this orientation */
            CHECK_NEAR(n[0] * pos[0] / rad + n[1] * pos[1] / rad, 1.0, 1e-12);
            CHECK_NEAR(n[2], 0.0, 1e-12);
        }
        check_derivatives(ps[q], 0.3, 0.4, 1e-6, 1e-6);
    }
}

TEST(full_circle_nurbs_cylinder)
{
    /* the 9-point circle, knots with double interior knots: a clamped
     * NURBS with C1 joints, every point at the radius */
    const double r = 1.25;
    const double px[9] = {1, 1, 0, -1, -1, -1, 0, 1, 1}, py[9] = {0, 1, 1, 1, 0, -1, -1, -1, 0};
    double ctrl[3 * 18], w[18];
    for (int j = 0; j < 2; j++)
        for (int i = 0; i < 9; i++) {
            double *q = ctrl + 3 * (9 * j + i);
            q[0] = r * px[i], q[1] = r * py[i], q[2] = j;
            w[9 * j + i] = i % 2 ? S2 : 1;
        }
    double ku[12] = {0, 0, 0, 0.25, 0.25, 0.5, 0.5, 0.75, 0.75, 1, 1, 1}, kv[4] = {0, 0, 1, 1};
    tsr_patch p = {TSR_PATCH_NURBS, 2, 1, 9, 2, ctrl, w, ku, kv, 0, 0, 0, 0};
    CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
    for (int k = 0; k <= 400; k++) {
        double u = k / 400.0, v = rnd(), pos[3], n[3];
        CHECK(tsr_patch_eval(&p, u, v, pos, NULL, NULL, n) == TSR_OK);
        double rad = hypot(pos[0], pos[1]);
        CHECK_NEAR(rad, r, 1e-12);
        CHECK_NEAR(n[0] * pos[0] / rad + n[1] * pos[1] / rad, 1.0, 1e-12);
    }
    CHECK(tsr_patch_spans(&p, 0, NULL, 0) == 4);
    CHECK(tsr_patch_spans(&p, 1, NULL, 0) == 1);
}

/* The sphere octant as a rational biquadratic surface of revolution:
 * meridian quarter circle (v, equator to pole) swept by a quarter circle
 * (u); the row v = 1 collapses to the pole. */
static void sphere_octant(double r, double ctrl[27], double w[9])
{
    const double cx[3] = {1, 1, 0}, cy[3] = {0, 1, 1}, cw[3] = {1, S2, 1};
    const double mr[3] = {1, 1, 0}, mz[3] = {0, 1, 1};
    for (int j = 0; j < 3; j++)
        for (int i = 0; i < 3; i++) {
            double *q = ctrl + 3 * (3 * j + i);
            q[0] = r * mr[j] * cx[i], q[1] = r * mr[j] * cy[i], q[2] = r * mz[j];
            w[3 * j + i] = cw[i] * cw[j];
        }
}

TEST(sphere_octant_rational)
{
    const double r = 3;
    double ctrl[27], w[9];
    sphere_octant(r, ctrl, w);
    tsr_patch p = {TSR_PATCH_BEZIER, 2, 2, 3, 3, ctrl, w, NULL, NULL, 0, 0, 0, 0};
    CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
    for (int k = 0; k < 600; k++) {
        double u = k < 121 ? (k % 11) / 10.0 : rnd(), v = k < 121 ? (k / 11) / 10.0 : rnd();
        double pos[3], n[3];
        CHECK(tsr_patch_eval(&p, u, v, pos, NULL, NULL, n) == TSR_OK);
        CHECK_NEAR(len3(pos), r, 1e-12);
        /* outward radial normal everywhere, the pole (v = 1) included */
        CHECK_MSG(fabs(dot3(n, pos) / r - 1) < 1e-9, "u %g v %g: n (%g %g %g)", u, v, n[0], n[1], n[2]);
        CHECK_NEAR(len3(n), 1.0, 1e-14);
    }
    double pos[3], n[3], du[3];
    CHECK(tsr_patch_eval(&p, 0.3, 1.0, pos, du, NULL, n) == TSR_OK);
    CHECK(len3(du) < 1e-12); /* the collapsed edge */
    CHECK_NEAR(n[2], 1.0, 1e-12);
    check_derivatives(&p, 0.35, 0.55, 1e-6, 1e-6);
    /* the same octant as a NURBS over the domain [0,2] x [-1,1] */
    double k2[6] = {0, 0, 0, 2, 2, 2}, k3[6] = {-1, -1, -1, 1, 1, 1};
    tsr_patch q = {TSR_PATCH_NURBS, 2, 2, 3, 3, ctrl, w, k2, k3, 0, 0, 0, 0};
    for (int k = 0; k < 100; k++) {
        double u = 2 * rnd(), v = 2 * rnd() - 1, a[3], b[3];
        CHECK(tsr_patch_eval(&q, u, v, a, NULL, NULL, NULL) == TSR_OK);
        CHECK(tsr_patch_eval(&p, u / 2, (v + 1) / 2, b, NULL, NULL, NULL) == TSR_OK);
        for (int c = 0; c < 3; c++)
            CHECK_NEAR(a[c], b[c], 1e-12);
    }
}

/* ---- B-splines against the definition ---------------------------------------- */

static void random_net(double *ctrl, double *w, uint32_t n)
{
    for (uint32_t i = 0; i < 3 * n; i++)
        ctrl[i] = 10 * rnd() - 5;
    for (uint32_t i = 0; w && i < n; i++)
        w[i] = 0.2 + 2 * rnd();
}

TEST(bspline_matches_cox_de_boor)
{
    for (int round = 0; round < 60; round++) {
        int pu = 1 + round % 7, pv = 1 + (round / 7) % 7;
        uint32_t nu = (uint32_t)pu + 1 + round % 4, nv = (uint32_t)pv + 1 + (round / 3) % 3;
        double ctrl[3 * 20 * 20], w[20 * 20], ku[40], kv[40];
        random_net(ctrl, w, nu * nv);
        /* three flavours of knot vector: uniform unclamped, clamped with
         * double interior knots, random non-decreasing with multiplicities
         * up to degree + 1 */
        for (int dir = 0; dir < 2; dir++) {
            double *k = dir ? kv : ku;
            int deg = dir ? pv : pu, mult = 1;
            uint32_t n = dir ? nv : nu, m = n + (uint32_t)deg + 1;
            for (uint32_t i = 0; i < m; i++) {
                switch (round % 3) {
                case 0:
                    k[i] = (double)i - 2;
                    break;
                case 1:
                    k[i] = i <= (uint32_t)deg ? 0 : i >= n ? 1 : (double)((i - (uint32_t)deg + 1) / 2) / n;
                    break;
                default:
                    if (i > 0 && rnd() < 0.3 && mult < deg + 1 && i != n) {
                        k[i] = k[i - 1], mult++;
                    } else {
                        k[i] = i ? k[i - 1] + 0.1 + rnd() : -1;
                        mult = 1;
                    }
                    break;
                }
            }
        }
        tsr_patch p = {round % 2 ? TSR_PATCH_NURBS : TSR_PATCH_BSPLINE,
                       pu,
                       pv,
                       nu,
                       nv,
                       ctrl,
                       round % 2 ? w : NULL,
                       ku,
                       kv,
                       0,
                       0,
                       0,
                       0};
        tsr_error e = {0};
        CHECK_MSG(tsr_patch_check(&p, &e) == TSR_OK, "round %d: %s", round, e.message);
        double dom[4];
        CHECK(tsr_patch_domain(&p, dom) == TSR_OK);
        CHECK(dom[0] == ku[pu] && dom[1] == ku[nu] && dom[2] == kv[pv] && dom[3] == kv[nv]);
        for (int s = 0; s < 20; s++) {
            double u = dom[0] + (dom[1] - dom[0]) * (0.001 + 0.998 * rnd());
            double v = dom[2] + (dom[3] - dom[2]) * (0.001 + 0.998 * rnd());
            double a[3], b[3];
            CHECK(tsr_patch_eval(&p, u, v, a, NULL, NULL, NULL) == TSR_OK);
            oracle_eval(&p, u, v, b);
            for (int c = 0; c < 3; c++)
                CHECK_MSG(fabs(a[c] - b[c]) <= 1e-9 * (1 + fabs(b[c])), "round %d: %.17g vs %.17g", round, a[c], b[c]);
        }
    }
}

TEST(derivatives_central_differences)
{
    for (int round = 0; round < 30; round++) {
        int pu = 1 + round % 7, pv = 1 + (round * 3) % 7;
        uint32_t nu = (uint32_t)pu + 3, nv = (uint32_t)pv + 2;
        double ctrl[3 * 10 * 9], w[10 * 9], ku[20], kv[20];
        random_net(ctrl, w, nu * nv);
        for (uint32_t i = 0; i < nu + (uint32_t)pu + 1; i++)
            ku[i] = 0.5 * i;
        for (uint32_t i = 0; i < nv + (uint32_t)pv + 1; i++)
            kv[i] = i < 2 ? 0 : i - 1.0;
        tsr_patch b = {round % 2 ? TSR_PATCH_NURBS : TSR_PATCH_BSPLINE,
                       pu,
                       pv,
                       nu,
                       nv,
                       ctrl,
                       round % 2 ? w : NULL,
                       ku,
                       kv,
                       0,
                       0,
                       0,
                       0};
        double dom[4];
        tsr_patch_domain(&b, dom);
        for (int s = 0; s < 8; s++) {
            /* inside spans (widths 0.5 in u, 1 in v), away from the knots
             * where derivatives are only C^(degree-1) */
            double u = dom[0] + 0.5 * floor(rnd() * (dom[1] - dom[0]) / 0.5) + 0.5 * (0.1 + 0.8 * rnd());
            double v = dom[2] + floor(rnd() * (dom[3] - dom[2])) + 0.1 + 0.8 * rnd();
            check_derivatives(&b, u, v, 1e-6, 1e-5);
        }
        tsr_patch z = {TSR_PATCH_BEZIER,
                       pu,
                       pv,
                       (uint32_t)pu + 1,
                       (uint32_t)pv + 1,
                       ctrl,
                       round % 2 ? w : NULL,
                       NULL,
                       NULL,
                       -1,
                       2,
                       0.5,
                       1.5};
        check_derivatives(&z, 0.3, 0.8, 1e-6, 1e-5);
        double a[3], o[3];
        tsr_patch_eval(&z, 0.7, 0.6, a, NULL, NULL, NULL);
        oracle_bezier(&z, 0.7, 0.6, o);
        for (int c = 0; c < 3; c++)
            CHECK_NEAR(a[c], o[c], 1e-10 * (1 + fabs(o[c])));
    }
}

TEST(legacy_float_bezier_agrees)
{
    float f[3 * 16];
    double d[3 * 16];
    for (int i = 0; i < 48; i++)
        d[i] = f[i] = (float)(10 * rnd() - 5);
    tsr_bezier_patch lp = {3, 3, f};
    tsr_patch p = {TSR_PATCH_BEZIER, 3, 3, 4, 4, d, NULL, NULL, NULL, 0, 0, 0, 0};
    for (int k = 0; k < 20; k++) {
        double u = rnd(), v = rnd(), a[3], b[3], au[3], bu[3], av[3], bv[3];
        tsr_bezier_eval(&lp, u, v, a, au, av);
        tsr_patch_eval(&p, u, v, b, bu, bv, NULL);
        for (int c = 0; c < 3; c++) {
            CHECK_NEAR(a[c], b[c], 1e-12);
            CHECK_NEAR(au[c], bu[c], 1e-11);
            CHECK_NEAR(av[c], bv[c], 1e-11);
        }
    }
}

/* ---- Bézier pieces and splitting ---------------------------------------------- */

TEST(bspline_to_bezier_pieces)
{
    for (int round = 0; round < 24; round++) {
        int pu = 1 + round % 7, pv = 1 + (round / 2) % 4;
        uint32_t nu = (uint32_t)pu + 1 + (uint32_t)round % 5, nv = (uint32_t)pv + 2;
        double ctrl[3 * 12 * 7], w[12 * 7], ku[24], kv[24];
        random_net(ctrl, w, nu * nv);
        for (uint32_t i = 0; i < nu + (uint32_t)pu + 1; i++)
            ku[i] = (double)i; /* uniform, unclamped */
        for (uint32_t i = 0; i < nv + (uint32_t)pv + 1; i++)
            kv[i] = i <= (uint32_t)pv ? 0 : i >= nv ? 3 : (double)(i - (uint32_t)pv); /* clamped */
        tsr_patch p = {round % 2 ? TSR_PATCH_NURBS : TSR_PATCH_BSPLINE,
                       pu,
                       pv,
                       nu,
                       nv,
                       ctrl,
                       round % 2 ? w : NULL,
                       ku,
                       kv,
                       0,
                       0,
                       0,
                       0};
        if (round % 3 == 2) { /* a domain cutting spans in the middle */
            p.u0 = ku[pu] + 0.4, p.u1 = ku[nu] - 0.3, p.v0 = 0.25, p.v1 = 2.5;
        }
        CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
        uint32_t su = tsr_patch_spans(&p, 0, NULL, 0), sv = tsr_patch_spans(&p, 1, NULL, 0), count = 0;
        CHECK(su == nu - (uint32_t)pu);
        CHECK(tsr_patch_to_bezier(&p, NULL, 0, NULL, NULL, &count) == TSR_OK);
        CHECK(count == su * sv);
        tsr_patch pieces[64];
        double pc[64 * 3 * 64], pw[64 * 64];
        CHECK(tsr_patch_to_bezier(&p, pieces, count - 1, pc, pw, &count) == TSR_ERR_ARGUMENT);
        CHECK(tsr_patch_to_bezier(&p, pieces, 64, pc, pw, &count) == TSR_OK);
        double bu[16], bv[16], dom[4];
        tsr_patch_spans(&p, 0, bu, 16);
        tsr_patch_spans(&p, 1, bv, 16);
        tsr_patch_domain(&p, dom);
        CHECK(bu[0] == dom[0] && bu[su] == dom[1] && bv[0] == dom[2] && bv[sv] == dom[3]);
        for (uint32_t b = 0; b < sv; b++)
            for (uint32_t a = 0; a < su; a++) {
                const tsr_patch *q = &pieces[b * su + a];
                CHECK(q->kind == TSR_PATCH_BEZIER && (q->weights != NULL) == (p.weights != NULL));
                CHECK(q->u0 == bu[a] && q->u1 == bu[a + 1] && q->v0 == bv[b] && q->v1 == bv[b + 1]);
                CHECK(tsr_patch_check(q, NULL) == TSR_OK);
                for (int s = 0; s < 6; s++) {
                    double u = q->u0 + (q->u1 - q->u0) * (s < 2 ? s : rnd());
                    double v = q->v0 + (q->v1 - q->v0) * (s < 2 ? s : rnd());
                    double x[3], y[3], xu[3], yu[3], xv[3], yv[3];
                    tsr_patch_eval(q, u, v, x, xu, xv, NULL);
                    tsr_patch_eval(&p, u, v, y, yu, yv, NULL);
                    for (int c = 0; c < 3; c++) {
                        CHECK_NEAR(x[c], y[c], 1e-10 * (1 + fabs(y[c])));
                        if (s >= 2) { /* one-sided at knots: compare inside only */
                            CHECK_NEAR(xu[c], yu[c], 1e-8 * (1 + fabs(yu[c])));
                            CHECK_NEAR(xv[c], yv[c], 1e-8 * (1 + fabs(yv[c])));
                        }
                    }
                }
                /* the piece's box lies within the parent's */
                double lo[3], hi[3], plo[3], phi[3];
                tsr_patch_bounds(q, lo, hi);
                tsr_patch_bounds(&p, plo, phi);
                for (int c = 0; c < 3; c++)
                    CHECK(lo[c] >= plo[c] - 1e-9 && hi[c] <= phi[c] + 1e-9);
            }
    }
}

TEST(bezier_piece_refuses_knot_inside)
{
    double ctrl[3 * 5 * 4] = {0}, ku[8] = {0, 0, 0, 1, 2, 3, 3, 3}, kv[6] = {0, 0, 0, 1, 1, 1};
    tsr_patch p = {TSR_PATCH_BSPLINE, 2, 2, 5, 3, ctrl, NULL, ku, kv, 0, 0, 0, 0};
    double out[3 * 9];
    tsr_patch q;
    CHECK(tsr_patch_bezier_piece(&p, 0.5, 1.5, 0, 1, out, NULL, &q) == TSR_ERR_ARGUMENT);
    CHECK(tsr_patch_bezier_piece(&p, 1, 2, 0, 1, out, NULL, &q) == TSR_OK);
    CHECK(tsr_patch_bezier_piece(&p, 2, 2, 0, 1, out, NULL, &q) == TSR_ERR_ARGUMENT);
    CHECK(tsr_patch_bezier_piece(&p, 2.5, 3.5, 0, 1, out, NULL, &q) == TSR_ERR_ARGUMENT);
}

TEST(split_bezier_de_casteljau)
{
    for (int round = 0; round < 14; round++) {
        int du = 1 + round % 7, dv = 1 + (round * 5) % 7;
        uint32_t n = (uint32_t)((du + 1) * (dv + 1));
        double ctrl[3 * 64], w[64], lc[3 * 64], lw[64], hc[3 * 64], hw[64];
        random_net(ctrl, w, n);
        tsr_patch p = {TSR_PATCH_BEZIER,
                       du,
                       dv,
                       (uint32_t)du + 1,
                       (uint32_t)dv + 1,
                       ctrl,
                       round % 2 ? w : NULL,
                       NULL,
                       NULL,
                       1,
                       3,
                       -1,
                       0};
        int axis = round % 2 ? 1 : 0;
        double t = axis ? -0.3 : 1.7;
        tsr_patch lo, hi;
        CHECK(tsr_patch_split(&p, axis, t, &lo, lc, lw, &hi, hc, hw) == TSR_OK);
        CHECK(axis ? lo.v1 == t && hi.v0 == t && lo.v0 == -1 && hi.v1 == 0
                   : lo.u1 == t && hi.u0 == t && lo.u0 == 1 && hi.u1 == 3);
        for (int s = 0; s < 30; s++) {
            const tsr_patch *h = s % 2 ? &hi : &lo;
            double u = h->u0 + (h->u1 - h->u0) * rnd(), v = h->v0 + (h->v1 - h->v0) * rnd(), a[3], b[3];
            tsr_patch_eval(h, u, v, a, NULL, NULL, NULL);
            oracle_bezier(&p, u, v, b);
            for (int c = 0; c < 3; c++)
                CHECK_NEAR(a[c], b[c], 1e-10 * (1 + fabs(b[c])));
        }
        /* in place: the lower half over the parent's own arrays */
        double keep[3 * 64], keepw[64];
        memcpy(keep, ctrl, sizeof keep);
        memcpy(keepw, w, sizeof keepw);
        tsr_patch orig = p, q = p;
        orig.ctrl = keep;
        orig.weights = p.weights ? keepw : NULL;
        CHECK(tsr_patch_split(&q, axis, t, &q, ctrl, w, &hi, hc, hw) == TSR_OK);
        CHECK(q.ctrl == ctrl);
        for (int s = 0; s < 10; s++) {
            double u = q.u0 + (q.u1 - q.u0) * rnd(), v = q.v0 + (q.v1 - q.v0) * rnd(), a[3], b[3];
            tsr_patch_eval(&q, u, v, a, NULL, NULL, NULL);
            oracle_bezier(&orig, u, v, b);
            for (int c = 0; c < 3; c++)
                CHECK_NEAR(a[c], b[c], 1e-10 * (1 + fabs(b[c])));
        }
        CHECK(tsr_patch_split(&p, axis, axis ? 0 : 3, &lo, lc, lw, &hi, hc, hw) == TSR_ERR_ARGUMENT);
    }
    double c[12] = {0}, k[4] = {0, 0, 1, 1};
    tsr_patch b = {TSR_PATCH_BSPLINE, 1, 1, 2, 2, c, NULL, k, k, 0, 0, 0, 0};
    tsr_patch lo, hi;
    double lc[12], hc[12];
    CHECK(tsr_patch_split(&b, 0, 0.5, &lo, lc, NULL, &hi, hc, NULL) == TSR_ERR_ARGUMENT);
}

TEST(bounds_contain_surface)
{
    for (int round = 0; round < 20; round++) {
        int pu = 1 + round % 4, pv = 1 + round % 3;
        uint32_t nu = (uint32_t)pu + 4, nv = (uint32_t)pv + 3;
        double ctrl[3 * 8 * 6], w[8 * 6], ku[16], kv[16];
        random_net(ctrl, w, nu * nv);
        for (uint32_t i = 0; i < 16; i++)
            ku[i] = kv[i] = (double)i;
        tsr_patch p = {round % 2 ? TSR_PATCH_NURBS : TSR_PATCH_BSPLINE,
                       pu,
                       pv,
                       nu,
                       nv,
                       ctrl,
                       round % 2 ? w : NULL,
                       ku,
                       kv,
                       0,
                       0,
                       0,
                       0};
        double dom[4];
        tsr_patch_domain(&p, dom);
        if (round % 4 == 3) { /* a small domain: only the points of its spans */
            p.u0 = dom[0] + 0.2, p.u1 = dom[0] + 0.9, p.v0 = dom[2], p.v1 = dom[2] + 1;
            tsr_patch_domain(&p, dom);
        }
        double lo[3], hi[3];
        CHECK(tsr_patch_bounds(&p, lo, hi) == TSR_OK);
        for (int s = 0; s < 200; s++) {
            double x[3];
            tsr_patch_eval(&p, dom[0] + (dom[1] - dom[0]) * rnd(), dom[2] + (dom[3] - dom[2]) * rnd(), x, NULL, NULL,
                           NULL);
            for (int c = 0; c < 3; c++)
                CHECK(x[c] >= lo[c] && x[c] <= hi[c]);
        }
    }
}

/* ---- Degenerate points ------------------------------------------------------- */

/* The normal at (u, v) is finite, unit, and within `tol` (1 - cos) of the
 * normal a step h towards (cu, cv). */
static void check_normal_limit(const tsr_patch *p, double u, double v, double cu, double cv, double h, double tol)
{
    double n[3], m[3], pos[3];
    CHECK(tsr_patch_eval(p, u, v, pos, NULL, NULL, n) == TSR_OK);
    CHECK(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]));
    CHECK_NEAR(len3(n), 1.0, 1e-12);
    double l = hypot(cu - u, cv - v);
    CHECK(tsr_patch_eval(p, u + h * (cu - u) / l, v + h * (cv - v) / l, pos, NULL, NULL, m) == TSR_OK);
    CHECK_MSG(1 - dot3(n, m) <= tol, "at (%g, %g): n (%g %g %g), inside (%g %g %g)", u, v, n[0], n[1], n[2], m[0], m[1],
              m[2]);
}

TEST(degenerate_patch_corner)
{
    /* a bicubic dome whose row v = 0 collapses to the apex, with a
     * horizontal tangent plane there (as the teapot's lid knob) */
    double ctrl[3 * 16];
    const double ring[4][2] = {{1, 0}, {1, 0.55}, {0.55, 1}, {0, 1}};
    const double rad[4] = {0, 0.8, 1.2, 1.3}, z[4] = {2, 2, 1.5, 0};
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            double *q = ctrl + 3 * (4 * j + i);
            q[0] = rad[j] * ring[i][0], q[1] = rad[j] * ring[i][1], q[2] = z[j];
        }
    tsr_patch p = {TSR_PATCH_BEZIER, 3, 3, 4, 4, ctrl, NULL, NULL, NULL, 0, 0, 0, 0};
    for (int k = 0; k <= 10; k++) {
        double n[3], du[3], pos[3];
        CHECK(tsr_patch_eval(&p, k / 10.0, 0, pos, du, NULL, n) == TSR_OK);
        CHECK(len3(du) == 0);
        /* the apex's normal is vertical, the same from every u */
        CHECK_NEAR(fabs(n[2]), 1.0, 1e-12);
        check_normal_limit(&p, k / 10.0, 0, k / 10.0, 1, 1e-7, 1e-10);
        check_normal_limit(&p, k / 10.0, 0, 0.5, 0.5, 1e-7, 1e-10);
    }
    /* a bilinear patch whose edge v = 0 collapses: a flat triangle */
    double tri[12] = {0, 0, 0, 0, 0, 0, -1, 2, 0, 3, 1, 0};
    tsr_patch t = {TSR_PATCH_BEZIER, 1, 1, 2, 2, tri, NULL, NULL, NULL, 0, 0, 0, 0};
    for (int k = 0; k <= 4; k++) {
        double n[3];
        CHECK(tsr_patch_eval(&t, k / 4.0, 0, NULL, NULL, NULL, n) == TSR_OK);
        CHECK_NEAR(fabs(n[2]), 1.0, 1e-15);
        check_normal_limit(&t, k / 4.0, 0, 0.5, 0.5, 1e-6, 1e-12);
    }
    /* a corner where du and dv are parallel (not a collapsed edge) */
    double par[12] = {0, 0, 0, 1, 0, 0, 2, 0, 0, 1, 1, 0};
    tsr_patch c = {TSR_PATCH_BEZIER, 1, 1, 2, 2, par, NULL, NULL, NULL, 0, 0, 0, 0};
    double n[3];
    CHECK(tsr_patch_eval(&c, 0, 0, NULL, NULL, NULL, n) == TSR_OK);
    CHECK_NEAR(n[2], -1.0, 1e-15);
    check_normal_limit(&c, 0, 0, 1, 1, 1e-6, 1e-12);
}

TEST(collapsed_patch_normal_finite)
{
    /* every control point on one line: no tangent plane anywhere */
    double ctrl[3 * 9];
    for (int i = 0; i < 9; i++)
        ctrl[3 * i] = i % 3 + i / 3, ctrl[3 * i + 1] = 2 * ctrl[3 * i], ctrl[3 * i + 2] = 0;
    tsr_patch p = {TSR_PATCH_BEZIER, 2, 2, 3, 3, ctrl, NULL, NULL, NULL, 0, 0, 0, 0};
    double pts[27] = {0};
    tsr_patch q = {TSR_PATCH_BEZIER, 2, 2, 3, 3, pts, NULL, NULL, NULL, 0, 0, 0, 0};
    for (int k = 0; k < 9; k++) {
        double n[3];
        CHECK(tsr_patch_eval(&p, (k % 3) / 2.0, (k / 3) / 2.0, NULL, NULL, NULL, n) == TSR_OK);
        CHECK(isfinite(n[0]) && isfinite(n[1]) && isfinite(n[2]));
        CHECK_NEAR(len3(n), 1.0, 1e-12);
        CHECK(tsr_patch_eval(&q, (k % 3) / 2.0, (k / 3) / 2.0, NULL, NULL, NULL, n) == TSR_OK);
        CHECK_NEAR(len3(n), 1.0, 1e-12);
    }
}

TEST(parameters_clamped_to_domain)
{
    double ctrl[12];
    memcpy(ctrl, quad, sizeof ctrl);
    tsr_patch p = {TSR_PATCH_BEZIER, 1, 1, 2, 2, ctrl, NULL, NULL, NULL, 0, 0, 0, 0};
    double a[3], b[3];
    CHECK(tsr_patch_eval(&p, -3, 7, a, NULL, NULL, NULL) == TSR_OK);
    CHECK(tsr_patch_eval(&p, 0, 1, b, NULL, NULL, NULL) == TSR_OK);
    CHECK(a[0] == b[0] && a[1] == b[1] && a[2] == b[2]);
    CHECK(tsr_patch_eval(&p, NAN, NAN, a, NULL, NULL, NULL) == TSR_OK);
    CHECK(a[0] == quad[0][0] && a[1] == quad[0][1] && a[2] == quad[0][2]);
}

/* ---- Curves ---------------------------------------------------------------------- */

TEST(curve2_matches_definition)
{
    /* a rational quadratic quarter circle of radius 0.25 around (0.5, 0.5)
     * as a curve, and a random cubic against Cox-de Boor */
    double c[6] = {0.75, 0.5, 0.75, 0.75, 0.5, 0.75}, w[3] = {1, S2, 1}, k[6] = {0, 0, 0, 1, 1, 1};
    tsr_curve2 q = {2, 3, c, w, k};
    CHECK(tsr_curve2_check(&q, NULL) == TSR_OK);
    for (int s = 0; s <= 20; s++) {
        double uv[2], d[2];
        CHECK(tsr_curve2_eval(&q, s / 20.0, uv, d) == TSR_OK);
        CHECK_NEAR(hypot(uv[0] - 0.5, uv[1] - 0.5), 0.25, 1e-14);
        CHECK_NEAR((uv[0] - 0.5) * d[0] + (uv[1] - 0.5) * d[1], 0.0, 1e-12); /* tangent */
    }
    double cc[14], kk[11];
    for (int i = 0; i < 14; i++)
        cc[i] = rnd();
    for (int i = 0; i < 11; i++)
        kk[i] = i * 0.5;
    tsr_curve2 r = {3, 7, cc, NULL, kk};
    for (int s = 0; s < 20; s++) {
        double t = 1.5 + 2 * (0.001 + 0.998 * rnd()), uv[2], ref[2] = {0, 0};
        CHECK(tsr_curve2_eval(&r, t, uv, NULL) == TSR_OK);
        for (int i = 0; i < 7; i++) {
            double b = cox(kk, i, 3, t);
            ref[0] += b * cc[2 * i], ref[1] += b * cc[2 * i + 1];
        }
        CHECK_NEAR(uv[0], ref[0], 1e-12);
        CHECK_NEAR(uv[1], ref[1], 1e-12);
    }
}

/* ---- Invalid patches -------------------------------------------------------------- */

static void refused(const tsr_patch *p, const char *what)
{
    tsr_error e = {0};
    CHECK_MSG(tsr_patch_check(p, &e) == TSR_ERR_ARGUMENT, "%s accepted", what);
    CHECK_MSG(e.status == TSR_ERR_ARGUMENT && e.message[0], "%s: no detail", what);
    fprintf(stderr, "  %s: %s\n", what, e.message);
}

TEST(invalid_patches_refused)
{
    double ctrl[3 * 64] = {0}, w[64], ku[16], kv[16];
    for (int i = 0; i < 64; i++)
        w[i] = 1;
    for (int i = 0; i < 16; i++)
        ku[i] = kv[i] = i;
    tsr_patch good = {TSR_PATCH_BSPLINE, 2, 2, 4, 4, ctrl, NULL, ku, kv, 0, 0, 0, 0}, p;
    CHECK(tsr_patch_check(&good, NULL) == TSR_OK);
    double pos[3];
    CHECK(tsr_patch_eval(&good, 3, 3, pos, NULL, NULL, NULL) == TSR_OK);

    p = good, p.degree_u = 0;
    refused(&p, "degree 0");
    CHECK(tsr_patch_eval(&p, 3, 3, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    p = good, p.degree_v = 8, p.count_v = 9;
    refused(&p, "degree 8");
    CHECK(tsr_patch_eval(&p, 3, 3, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    p = good, p.count_u = 2;
    refused(&p, "fewer points than degree + 1");
    p = good, p.kind = TSR_PATCH_BEZIER, p.knots_u = p.knots_v = NULL;
    refused(&p, "Bézier with count != degree + 1");
    CHECK(tsr_patch_eval(&p, 0.5, 0.5, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    p = good, p.kind = (tsr_patch_kind)7;
    refused(&p, "unknown kind");
    p = good, p.ctrl = NULL;
    refused(&p, "no control points");
    CHECK(tsr_patch_eval(&p, 3, 3, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    p = good, p.knots_v = NULL;
    refused(&p, "B-spline without knots");
    double bad[16];
    memcpy(bad, ku, sizeof bad);
    bad[4] = 2.5; /* 0 1 2 3 2.5 5 6 ... */
    p = good, p.knots_u = bad;
    refused(&p, "non-monotone knots");
    CHECK(tsr_patch_eval(&p, 3.2, 3, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    double flat[16] = {0};
    p = good, p.knots_u = flat;
    refused(&p, "all knots equal");
    double nank[16];
    memcpy(nank, ku, sizeof nank);
    nank[6] = NAN;
    p = good, p.knots_u = nank;
    refused(&p, "NaN knot");
    p = good, p.kind = TSR_PATCH_NURBS;
    refused(&p, "NURBS without weights");
    p = good, p.weights = w;
    refused(&p, "weights on a polynomial B-spline");
    p = good, p.kind = TSR_PATCH_NURBS, p.weights = w;
    CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
    w[5] = 0;
    refused(&p, "zero weight");
    CHECK(tsr_patch_eval(&p, 3, 3, pos, NULL, NULL, NULL) == TSR_ERR_ARGUMENT);
    w[5] = -1;
    refused(&p, "negative weight");
    w[5] = NAN;
    refused(&p, "NaN weight");
    w[5] = 1;
    ctrl[7] = INFINITY;
    p = good;
    refused(&p, "infinite control point");
    ctrl[7] = 0;
    p = good, p.u0 = 1, p.u1 = 3;
    refused(&p, "domain outside the knots");
    p = good, p.u0 = 3, p.u1 = 3, p.v0 = 2, p.v1 = 3;
    refused(&p, "empty domain");
    p = good, p.count_u = TSR_PATCH_MAX_COUNT + 1;
    refused(&p, "count beyond the limit");
    ctrl[4] = 2e30;
    p = good;
    refused(&p, "coordinate beyond TSR_PATCH_MAX_ABS");
    ctrl[4] = 0;
    p = good, p.kind = TSR_PATCH_NURBS, p.weights = w;
    w[3] = 1e-25;
    refused(&p, "weight below TSR_PATCH_MIN_WEIGHT");
    w[3] = 1e25;
    refused(&p, "weight above TSR_PATCH_MAX_WEIGHT");
    w[3] = 1;
    double tiny[16];
    memcpy(tiny, ku, sizeof tiny);
    tiny[1] = 1e-35; /* knots 0, 1e-35, 2, 3, ... */
    p = good, p.knots_u = tiny;
    refused(&p, "knot span below TSR_PATCH_MIN_SPAN");
    p = good, p.kind = TSR_PATCH_BEZIER, p.count_u = p.count_v = 3, p.knots_u = p.knots_v = NULL;
    CHECK(tsr_patch_check(&p, NULL) == TSR_OK);
    p.u0 = 0, p.u1 = 1e-31, p.v0 = 0, p.v1 = 1;
    refused(&p, "Bézier domain narrower than TSR_PATCH_MIN_SPAN");

    tsr_curve2 c = {2, 2, ctrl, NULL, ku};
    tsr_error e = {0};
    CHECK(tsr_curve2_check(&c, &e) == TSR_ERR_ARGUMENT && e.message[0]);
    c.count = 3, c.degree = 8;
    CHECK(tsr_curve2_check(&c, &e) == TSR_ERR_ARGUMENT);
    double uv[2];
    CHECK(tsr_curve2_eval(&c, 0, uv, NULL) == TSR_ERR_ARGUMENT);
}

TEST_MAIN(T(bilinear_plane), T(degree_elevated_plane), T(cylinder_quarter_rational), T(full_circle_nurbs_cylinder),
          T(sphere_octant_rational), T(bspline_matches_cox_de_boor), T(derivatives_central_differences),
          T(legacy_float_bezier_agrees), T(bspline_to_bezier_pieces), T(bezier_piece_refuses_knot_inside),
          T(split_bezier_de_casteljau), T(bounds_contain_surface), T(degenerate_patch_corner),
          T(collapsed_patch_normal_finite), T(parameters_clamped_to_domain), T(curve2_matches_definition),
          T(invalid_patches_refused))
