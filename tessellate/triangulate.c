/* triangulate.c: tsr_triangulate (being written). */
#include "tessellate/triangulate_internal.h"

#include <string.h>

tsr_status tsr_triangulate(const tsr_pslg *in, const tsr_tri_options *opt, tsr_triangulation *out,
                           const tsr_allocator *alloc, tsr_error *err)
{
    (void)in, (void)opt, (void)alloc;
    memset(out, 0, sizeof *out);
    return tsr_error_set(err, TSR_ERR_UNSUPPORTED, "not yet");
}

void tsr_triangulation_free(tsr_triangulation *t)
{
    const tsr_allocator *a = t->alloc.realloc ? &t->alloc : NULL;
    tsr_free(a, t->xy);
    tsr_free(a, t->tri);
    tsr_free(a, t->edge);
    tsr_free(a, t->edge_segment);
    tsr_free(a, t->vertex_of_input);
    memset(t, 0, sizeof *t);
}

tsr_status tsr__tri_apply_region(tsr_triangulation *t, const tsr_pslg *in, const tsr_tri_options *opt)
{
    (void)t, (void)in, (void)opt;
    return TSR_OK;
}
