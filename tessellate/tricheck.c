/* tricheck.c: independent checker of a triangulation (stub until written). */
#include "tessellate/tessellate.h"

#include <string.h>

tsr_status tsr_triangulation_check(const tsr_pslg *in, const tsr_tri_options *opt, const tsr_triangulation *out,
                                   tsr_tri_check *res)
{
    (void)in, (void)opt, (void)out;
    memset(res, 0, sizeof *res);
    return TSR_ERR_UNSUPPORTED;
}
