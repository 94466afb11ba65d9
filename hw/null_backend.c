/* null_backend.c: the backend without a device (GLFW's null platform and
 * sokol's dummy backend do the same). It validates every call as a real
 * driver would (hw.h's rules for buffers, frames and tile draws) and
 * counts what would have been uploaded and drawn, so the renderer's logic
 * is tested without a GPU. */
#include "hw/hw.h"

#include <string.h>

typedef struct null_buffer {
    tsr_hw_buffer_kind kind; /* 0 when the slot is free */
    uint64_t size;
    uint64_t drawn_in;       /* the last frame (frame_no) with a draw from it */
} null_buffer;

typedef struct null_backend {
    tsr_hw_backend base; /* first, so the table pointer is the object */
    tsr_allocator alloc;
    null_buffer *buffers;
    uint32_t count, cap;
    bool in_frame;
    uint64_t frame_no; /* frames begun */
    uint64_t frame_triangles;
    uint32_t frame_draws, max_neighbour; /* this frame's draws, the largest neighbour number named */
    bool self_neighbour;                 /* a draw named itself */
    bool lost;                           /* a buffer this frame draws from was destroyed */
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
    b->buffers[slot].drawn_in = 0;
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

static void nb_destroy_buffer(tsr_hw_backend *self, tsr_hw_buffer id)
{
    null_backend *b = (null_backend *)self;
    null_buffer *buf = lookup(b, id);
    if (!buf)
        return;
    if (b->in_frame && buf->drawn_in == b->frame_no)
        b->lost = true;
    self->stats.buffers_live--;
    self->stats.bytes_live -= buf->size;
    buf->kind = 0;
}

static bool nb_begin_frame(tsr_hw_backend *self, const tsr_hw_frame *frame)
{
    null_backend *b = (null_backend *)self;
    if (b->in_frame || !frame)
        return false;
    b->in_frame = true;
    b->frame_no++;
    b->frame_triangles = 0;
    b->frame_draws = b->max_neighbour = 0;
    b->self_neighbour = b->lost = false;
    return true;
}

static bool nb_draw_tile(tsr_hw_backend *self, const tsr_hw_tile_draw *d)
{
    null_backend *b = (null_backend *)self;
    if (!b->in_frame || !d)
        return false;
    null_buffer *s = lookup(b, d->samples), *ix = lookup(b, d->indices);
    if (!s || s->kind != TSR_HW_VERTEX || !ix || ix->kind != TSR_HW_INDEX || !tsr_hw_draw_fits(d, s->size, ix->size))
        return false;
    s->drawn_in = ix->drawn_in = b->frame_no;
    b->frame_draws++;
    for (int k = 0; k < 8; k++) {
        b->max_neighbour = d->neighbour[k] > b->max_neighbour ? d->neighbour[k] : b->max_neighbour;
        b->self_neighbour |= d->neighbour[k] == b->frame_draws;
    }
    self->stats.draws++;
    self->stats.triangles_drawn += d->index_count / 3;
    b->frame_triangles += d->index_count / 3;
    return true;
}

static bool nb_end_frame(tsr_hw_backend *self, tsr_hw_frame_stats *stats)
{
    null_backend *b = (null_backend *)self;
    if (!b->in_frame)
        return false;
    b->in_frame = false;
    /* a neighbour beyond the frame's draws, or itself, or a buffer gone:
     * nothing drawn */
    bool drawn = b->max_neighbour <= b->frame_draws && !b->self_neighbour && !b->lost;
    self->stats.frames++;
    if (stats) {
        memset(stats, 0, sizeof *stats);
        stats->triangles = drawn ? b->frame_triangles : 0;
    }
    return drawn;
}

static bool nb_read_color(tsr_hw_backend *self, uint8_t *rgba)
{
    (void)self;
    (void)rgba;
    return false;
}

static bool nb_read_depth(tsr_hw_backend *self, float *depth)
{
    (void)self;
    (void)depth;
    return false;
}

static void nb_destroy(tsr_hw_backend *self)
{
    null_backend *b = (null_backend *)self;
    tsr_allocator a = b->alloc;
    const tsr_allocator *ap = a.realloc ? &a : NULL;
    tsr_free(ap, b->buffers);
    tsr_free(ap, b);
}

tsr_hw_backend *tsr_hw_null_create(uint32_t width, uint32_t height, const tsr_allocator *alloc)
{
    null_backend *b = tsr_alloc(alloc, sizeof *b);
    if (!b)
        return NULL;
    memset(b, 0, sizeof *b);
    if (alloc)
        b->alloc = *alloc;
    b->base.name = "null";
    b->base.width = width;
    b->base.height = height;
    b->base.create_buffer = nb_create;
    b->base.upload = nb_upload;
    b->base.destroy_buffer = nb_destroy_buffer;
    b->base.begin_frame = nb_begin_frame;
    b->base.draw_tile = nb_draw_tile;
    b->base.end_frame = nb_end_frame;
    b->base.read_color = nb_read_color;
    b->base.read_depth = nb_read_depth;
    b->base.destroy = nb_destroy;
    return &b->base;
}
