/* null_backend.c: the backend without a device (GLFW's null platform and
 * sokol's dummy backend do the same). It validates every call as a real
 * driver would and counts what would have been uploaded and drawn. */
#include "hw/hw.h"

#include <string.h>

typedef struct null_buffer {
    tsr_hw_buffer_kind kind; /* 0 when the slot is free */
    uint64_t size;
} null_buffer;

typedef struct null_backend {
    tsr_hw_backend base; /* first, so the table pointer is the object */
    tsr_allocator alloc;
    null_buffer *buffers;
    uint32_t count, cap;
} null_backend;

static const tsr_allocator *alloc_of(null_backend *b) { return b->alloc.realloc ? &b->alloc : NULL; }

static null_buffer *lookup(null_backend *b, tsr_hw_buffer id)
{
    if (id == 0 || id > b->count || b->buffers[id - 1].kind == 0)
        return NULL;
    return &b->buffers[id - 1];
}

static tsr_hw_buffer nb_create(tsr_hw_backend *self, tsr_hw_buffer_kind kind, uint64_t size)
{
    null_backend *b = (null_backend *)self;
    if (size == 0 || kind < TSR_HW_VERTEX || kind > TSR_HW_STAGING)
        return 0;
    uint32_t slot = UINT32_MAX;
    for (uint32_t i = 0; i < b->count; i++)
        if (b->buffers[i].kind == 0) {
            slot = i;
            break;
        }
    if (slot == UINT32_MAX) {
        if (b->count == b->cap) {
            uint32_t cap = b->cap ? b->cap * 2 : 16;
            null_buffer *nbuf = tsr_realloc(alloc_of(b), b->buffers, cap * sizeof *nbuf);
            if (!nbuf)
                return 0;
            b->buffers = nbuf;
            b->cap = cap;
        }
        slot = b->count++;
    }
    b->buffers[slot].kind = kind;
    b->buffers[slot].size = size;
    self->stats.buffers_live++;
    self->stats.bytes_live += size;
    return slot + 1;
}

static bool nb_upload(tsr_hw_backend *self, tsr_hw_buffer id, uint64_t offset, const void *data, uint64_t size)
{
    null_buffer *buf = lookup((null_backend *)self, id);
    if (!buf || !data || offset > buf->size || size > buf->size - offset)
        return false;
    self->stats.bytes_uploaded += size;
    return true;
}

static bool nb_draw(tsr_hw_backend *self, tsr_hw_buffer vertices, tsr_hw_buffer indices, uint32_t index_count)
{
    null_backend *b = (null_backend *)self;
    null_buffer *v = lookup(b, vertices), *i = lookup(b, indices);
    if (!v || !i || v->kind != TSR_HW_VERTEX || i->kind != TSR_HW_INDEX || index_count % 3 ||
        (uint64_t)index_count * 4 > i->size)
        return false;
    self->stats.draws++;
    self->stats.triangles_drawn += index_count / 3;
    return true;
}

static void nb_destroy_buffer(tsr_hw_backend *self, tsr_hw_buffer id)
{
    null_buffer *buf = lookup((null_backend *)self, id);
    if (!buf)
        return;
    self->stats.buffers_live--;
    self->stats.bytes_live -= buf->size;
    buf->kind = 0;
}

static void nb_destroy(tsr_hw_backend *self)
{
    null_backend *b = (null_backend *)self;
    tsr_allocator a = b->alloc;
    const tsr_allocator *ap = a.realloc ? &a : NULL;
    tsr_free(ap, b->buffers);
    tsr_free(ap, b);
}

tsr_hw_backend *tsr_hw_null_create(const tsr_allocator *alloc)
{
    null_backend *b = tsr_alloc(alloc, sizeof *b);
    if (!b)
        return NULL;
    memset(b, 0, sizeof *b);
    if (alloc)
        b->alloc = *alloc;
    b->base.name = "null";
    b->base.create_buffer = nb_create;
    b->base.upload = nb_upload;
    b->base.draw = nb_draw;
    b->base.destroy_buffer = nb_destroy_buffer;
    b->base.destroy = nb_destroy;
    return &b->base;
}
