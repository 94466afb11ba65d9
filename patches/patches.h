/* patches.h: parametric surfaces. For now the tensor-product Bézier patch
 * evaluator that the patch tessellator (a later issue) builds on.
 *
 * A Bézier patch of degree (du, dv), 1 <= du, dv <= TSR_BEZIER_MAX_DEGREE,
 * has (du+1)*(dv+1) control points stored row by row: point (i, j), the
 * i-th along u and j-th along v, is ctrl[3 * (j * (du+1) + i)].
 * The domain is (u, v) in [0,1]^2. */
#ifndef TSR_PATCHES_H
#define TSR_PATCHES_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

#define TSR_BEZIER_MAX_DEGREE 7

typedef struct tsr_bezier_patch {
    int du, dv;
    const float *ctrl; /* 3 * (du+1) * (dv+1) floats, borrowed */
} tsr_bezier_patch;

/* Position and first derivatives at (u, v) by de Casteljau's algorithm,
 * in double. du_out and dv_out may be NULL. Returns TSR_ERR_ARGUMENT for a
 * degree outside 1..TSR_BEZIER_MAX_DEGREE. Thread-safe; no allocation. */
tsr_status tsr_bezier_eval(const tsr_bezier_patch *p, double u, double v, double pos[3], double du_out[3],
                           double dv_out[3]);

#ifdef __cplusplus
}
#endif
#endif
