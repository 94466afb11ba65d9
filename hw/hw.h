/* hw.h: the GPU layer's backend table. The renderer's logic talks only to
 * this table, so it is testable with the null backend (no device), and the
 * Vulkan backend (a later issue) slots in behind the same calls.
 *
 * hw/ takes grid tiles (heights or positions, origin, scale, stitch mask),
 * never a terrain or a patch (../shared/DESIGN.md). */
#ifndef TSR_HW_H
#define TSR_HW_H

#include "tessellate/tessellate.h"

#ifdef __cplusplus
extern "C" {
#endif

typedef uint32_t tsr_hw_buffer; /* 0 is never a valid buffer */

typedef enum tsr_hw_buffer_kind { TSR_HW_VERTEX = 1, TSR_HW_INDEX = 2, TSR_HW_STAGING = 3 } tsr_hw_buffer_kind;

/* Counters every backend keeps, so tests and HUDs can see what happened. */
typedef struct tsr_hw_stats {
    uint64_t buffers_live;
    uint64_t bytes_live;
    uint64_t bytes_uploaded;
    uint64_t draws;
    uint64_t triangles_drawn;
} tsr_hw_stats;

typedef struct tsr_hw_backend tsr_hw_backend;

/* The table. Every function receives the backend itself; `self` state
 * lives behind it. create_buffer returns 0 on failure. upload writes
 * `size` bytes at `offset` into a buffer and fails (false) outside it.
 * draw draws `index_count` indices of an index buffer over a vertex
 * buffer. Not thread-safe: one thread drives one backend. */
struct tsr_hw_backend {
    const char *name;
    tsr_hw_buffer (*create_buffer)(tsr_hw_backend *self, tsr_hw_buffer_kind kind, uint64_t size);
    bool (*upload)(tsr_hw_backend *self, tsr_hw_buffer buf, uint64_t offset, const void *data, uint64_t size);
    bool (*draw)(tsr_hw_backend *self, tsr_hw_buffer vertices, tsr_hw_buffer indices, uint32_t index_count);
    void (*destroy_buffer)(tsr_hw_backend *self, tsr_hw_buffer buf);
    void (*destroy)(tsr_hw_backend *self);
    tsr_hw_stats stats;
};

/* A backend that keeps no data, only sizes and counters; NULL when out of
 * memory. alloc may be NULL. Destroy it with backend->destroy(backend). */
tsr_hw_backend *tsr_hw_null_create(const tsr_allocator *alloc);

#ifdef __cplusplus
}
#endif
#endif
