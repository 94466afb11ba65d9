/* hw_internal.h: what the files of hw/ share and the header does not
 * promise. */
#ifndef TSR_HW_INTERNAL_H
#define TSR_HW_INTERNAL_H

#include "hw/hw.h"

/* Milliseconds from a monotonic clock (renderer.c). */
double tsr_hw_now_ms(void);

#endif
