/* qtri.c: the quadtree triangulation method (stub until written). */
#include "tessellate/triangulate_internal.h"

tsr_status tsr__tri_quadtree(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                             const tsr_allocator *alloc, const char **why_not, tsr_error *err)
{
    (void)in, (void)opt, (void)out, (void)alloc, (void)err;
    *why_not = "the quadtree method is not built yet";
    return TSR_ERR_UNSUPPORTED;
}
