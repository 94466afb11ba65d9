/* Bézier evaluation against the closed form sum B_i^du(u) B_j^dv(v) P_ij,
 * and its derivatives against central differences. */
#include "check.h"
#include "patches/patches.h"

static double binom(int n, int k)
{
    double r = 1;
    for (int i = 1; i <= k; i++)
        r = r * (n - k + i) / i;
    return r;
}

static double bern(int n, int i, double t) { return binom(n, i) * pow(t, i) * pow(1 - t, n - i); }

TEST(matches_bernstein_form)
{
    unsigned s = 99;
    for (int du = 1; du <= TSR_BEZIER_MAX_DEGREE; du++)
        for (int dv = 1; dv <= TSR_BEZIER_MAX_DEGREE; dv += 2) {
            float ctrl[3 * 64];
            for (int i = 0; i < 3 * (du + 1) * (dv + 1); i++) {
                s = s * 1664525u + 1013904223u;
                ctrl[i] = (float)((s >> 8) % 2000) / 100.0f - 10;
            }
            tsr_bezier_patch p = {du, dv, ctrl};
            for (int k = 0; k < 25; k++) {
                double u = (k % 5) / 4.0, v = (k / 5) / 4.0 * 0.9 + 0.05;
                double pos[3], pv[3];
                CHECK(tsr_bezier_eval(&p, u, v, pos, NULL, pv) == TSR_OK);
                for (int c = 0; c < 3; c++) {
                    double ref = 0;
                    for (int j = 0; j <= dv; j++)
                        for (int i = 0; i <= du; i++)
                            ref += bern(du, i, u) * bern(dv, j, v) * ctrl[3 * (j * (du + 1) + i) + c];
                    CHECK_NEAR(pos[c], ref, 1e-9);
                }
                double h = 1e-6, a[3], b[3];
                double uu = u < h ? h : u > 1 - h ? 1 - h : u;
                tsr_bezier_eval(&p, uu + h, v, a, NULL, NULL);
                tsr_bezier_eval(&p, uu - h, v, b, NULL, NULL);
                double pu2[3];
                tsr_bezier_eval(&p, uu, v, pos, pu2, NULL);
                for (int c = 0; c < 3; c++)
                    CHECK_NEAR(pu2[c], (a[c] - b[c]) / (2 * h), 1e-4 * (1 + fabs(pu2[c])));
                tsr_bezier_eval(&p, u, v + h, a, NULL, NULL);
                tsr_bezier_eval(&p, u, v - h, b, NULL, NULL);
                for (int c = 0; c < 3; c++)
                    CHECK_NEAR(pv[c], (a[c] - b[c]) / (2 * h), 1e-4 * (1 + fabs(pv[c])));
            }
        }
}

TEST(bad_degree)
{
    float c[3 * 4] = {0};
    tsr_bezier_patch p = {0, 1, c};
    double pos[3];
    CHECK(tsr_bezier_eval(&p, 0.5, 0.5, pos, NULL, NULL) == TSR_ERR_ARGUMENT);
    p.du = TSR_BEZIER_MAX_DEGREE + 1;
    CHECK(tsr_bezier_eval(&p, 0.5, 0.5, pos, NULL, NULL) == TSR_ERR_ARGUMENT);
}

TEST_MAIN(T(matches_bernstein_form), T(bad_degree))
