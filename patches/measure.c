/* measure.c: tsr_ptess_measure, the independent oracle of ptess.h.
 * (Placeholder until written.) */
#include "patches/ptess.h"

tsr_status tsr_ptess_measure(const tsr_pmodel *m, const tsr_ptess_result *r, uint32_t per_side,
                             const tsr_camera *camera, bool per_source_error, const tsr_allocator *alloc,
                             tsr_ptess_measure_result *out)
{
    (void)m, (void)r, (void)per_side, (void)camera, (void)per_source_error, (void)alloc, (void)out;
    return TSR_ERR_UNSUPPORTED;
}
