/* bezier.c: tensor-product Bézier evaluation by de Casteljau's algorithm
 * (Farin, "Curves and Surfaces for CAGD", ch. 4 and 15): reduce each row
 * along u, then the column of results along v. The derivative along a
 * direction is degree times the difference of the last two points of the
 * reduction one step short of the end. */
#include "patches/patches.h"

/* Reduces n+1 points (stride 3) to the point at t, and the derivative. */
static void casteljau(const double *pts, int n, double t, double out[3], double d[3])
{
    double w[(TSR_BEZIER_MAX_DEGREE + 1) * 3] = {0};
    for (int i = 0; i <= n; i++)
        for (int k = 0; k < 3; k++)
            w[3 * i + k] = pts[3 * i + k];
    for (int r = n; r >= 1; r--) {
        if (r == 1 && d)
            for (int k = 0; k < 3; k++)
                d[k] = n * (w[3 + k] - w[k]);
        for (int i = 0; i < r; i++)
            for (int k = 0; k < 3; k++)
                w[3 * i + k] = (1 - t) * w[3 * i + k] + t * w[3 * (i + 1) + k];
    }
    for (int k = 0; k < 3; k++)
        out[k] = w[k];
}

tsr_status tsr_bezier_eval(const tsr_bezier_patch *p, double u, double v, double pos[3], double du_out[3],
                           double dv_out[3])
{
    if (p->du < 1 || p->dv < 1 || p->du > TSR_BEZIER_MAX_DEGREE || p->dv > TSR_BEZIER_MAX_DEGREE)
        return TSR_ERR_ARGUMENT;
    int nu = p->du + 1, nv = p->dv + 1;
    double rows[(TSR_BEZIER_MAX_DEGREE + 1) * 3], rows_du[(TSR_BEZIER_MAX_DEGREE + 1) * 3];
    double pts[(TSR_BEZIER_MAX_DEGREE + 1) * 3];
    for (int j = 0; j < nv; j++) {
        for (int i = 0; i < nu; i++)
            for (int k = 0; k < 3; k++)
                pts[3 * i + k] = p->ctrl[3 * (j * nu + i) + k];
        casteljau(pts, p->du, u, rows + 3 * j, rows_du + 3 * j);
    }
    casteljau(rows, p->dv, v, pos, dv_out);
    if (du_out)
        casteljau(rows_du, p->dv, v, du_out, NULL);
    return TSR_OK;
}
