/* renderer.c: the device-independent tile renderer of hw.h, section 2,
 * and the camera's view-projection matrix.
 *
 * The cache. The backend holds one VERTEX buffer, the sample pool,
 * divided into slots of ceil((n+1)^2 / 2) 32-bit words: a U16 tile takes
 * one slot, an F32 tile two adjacent slots starting at an even slot. The
 * slots are grouped in pairs (2k, 2k+1), each empty, half (one free slot)
 * or full; a stack of empty pairs and a set of half pairs make every
 * allocation O(1), U16 tiles fill half pairs first so that empty pairs
 * stay for F32 tiles. A used-slot bitmap says which half of a pair is
 * free. With an odd slot count the last pair's second slot does not
 * exist: its bit stays set, so that pair is never empty.
 *
 * Resident tiles are entries found by key through an open-addressing hash
 * table (linear probing, backward-shift deletion: no tombstones) and kept
 * on a doubly-linked LRU list, most recently drawn first. A frame first
 * touches every tile it draws (moving it to the front and stamping it
 * with the frame number), so the tiles behind the first one stamped with
 * an older frame are exactly the evictable ones, and eviction pops the
 * list's tail: O(1) per tile.
 *
 * Fragmentation. Once every tile not drawn by the frame is evicted, an
 * F32 tile may still find no empty pair while two free slots lie in two
 * half pairs; then the U16 tile of one of them is fetched again and moved
 * into the other (rare; the alternative would be failing a frame that
 * fits). So a frame fails with TSR_ERR_NOMEM exactly when its tiles need
 * more slots than the pool has. */
#define _POSIX_C_SOURCE 200809L
#include "hw/hw_internal.h"

#include <assert.h>
#include <float.h>
#include <inttypes.h>
#include <math.h>
#include <string.h>
#include <time.h>

#define NIL UINT32_MAX
#define DEFAULT_TILE_N 16u
#define DEFAULT_CACHE_BYTES ((uint64_t)256 << 20)
#define MAX_SLOTS ((uint64_t)1 << 31)

/* ---- View-projection -------------------------------------------------- */

/* Rows of the matrix, for d = world - eye and the camera's basis:
 *   clip = (2K/width (d.right), -2K/height (d.up), near, d.fwd),
 * so ndc_x = 2K r / (width f) and pixel x = (ndc_x + 1) / 2 * width =
 * width/2 + K r / f; Vulkan's NDC y grows downwards, so pixel y =
 * (ndc_y + 1) / 2 * height = height/2 - K u / f: both as in
 * tsr_camera_project. Depth = near / f: reversed, infinite far plane. */
void tsr_hw_view_proj(const tsr_camera *c, float m[16])
{
    double sx = 2 * c->K / c->width, sy = -2 * c->K / c->height;
    memset(m, 0, 16 * sizeof *m);
    for (int k = 0; k < 3; k++) { /* column k multiplies d[k] */
        m[4 * k + 0] = (float)(sx * c->right[k]);
        m[4 * k + 1] = (float)(sy * c->up[k]);
        m[4 * k + 3] = (float)c->fwd[k];
    }
    m[4 * 3 + 2] = (float)c->near_dist;
}

/* ---- Encoding ----------------------------------------------------------- */

uint32_t tsr_hw_encode_bound(uint32_t count) { return count * 4; } /* F32, the larger form */

uint64_t tsr_hw_draw_sample_bytes(tsr_hw_height_format format, uint32_t n, uint32_t first_sample)
{
    if (n < TSR_TILE_MIN || n > TSR_TILE_MAX || (n & 1))
        return 0;
    uint64_t count = (uint64_t)(n + 1) * (n + 1);
    if (format == TSR_HW_HEIGHT_U16 && first_sample <= 1)
        return (count + first_sample + 1) / 2 * 4;
    if (format == TSR_HW_HEIGHT_F32 && first_sample == 0)
        return count * 4;
    return 0;
}

bool tsr_hw_draw_fits(const tsr_hw_tile_draw *d, uint64_t samples_size, uint64_t indices_size)
{
    uint64_t bytes = tsr_hw_draw_sample_bytes(d->format, d->n, d->first_sample);
    if (bytes == 0 || d->samples_offset % 4 || d->samples_offset > samples_size ||
        bytes > samples_size - d->samples_offset)
        return false;
    if (d->index_count % 3 || ((uint64_t)d->first_index + d->index_count) * 4 > indices_size)
        return false;
    /* negated comparisons so that NaN fails too; finite positions, since
     * the shader finds neighbours' samples from them */
    return d->spacing[0] > 0 && d->spacing[1] > 0 && isfinite(d->spacing[0]) && isfinite(d->spacing[1]) &&
           isfinite(d->origin[0]) && isfinite(d->origin[1]) && d->morph >= 0 && d->morph <= 1;
}

static void put_word(void *dst, uint32_t w, uint32_t word)
{
    memcpy((unsigned char *)dst + 4 * (size_t)w, &word, 4);
}

tsr_hw_encoding tsr_hw_encode_samples(const float *samples, uint32_t count, double max_error, void *dst)
{
    tsr_hw_encoding enc = {TSR_HW_HEIGHT_U16, 0, 1, 0};
    uint32_t words = count / 2 + (count & 1);
    double tolerance = max_error > 0 ? max_error : 0; /* NaN: lossless */
    double lo = INFINITY, hi = -INFINITY;
    uint32_t valid = 0;
    for (uint32_t k = 0; k < count; k++) {
        double s = samples[k];
        if (isnan(s))
            continue;
        if (isinf(s))
            goto f32; /* no code stands for an infinity */
        lo = s < lo ? s : lo;
        hi = s > hi ? s : hi;
        valid++;
    }
    if (valid == 0) { /* all no-data */
        for (uint32_t w = 0; w < words; w++)
            put_word(dst, w, 0xFFFFFFFFu);
        enc.bytes = 4 * words;
        return enc;
    }
    double range = hi - lo, scale = 1;
    bool integral = range <= 65534;
    for (uint32_t k = 0; k < count && integral; k++) {
        double d = (double)samples[k] - lo; /* exact: both are floats */
        integral = isnan(d) || d == floor(d);
    }
    if (!integral)
        scale = range / 65534; /* codes 0..65534 span [lo, hi] */
    if (!(scale > 0))
        goto f32; /* a range of denormals */
    for (uint32_t w = 0; w < words; w++) {
        uint32_t word = 0;
        for (uint32_t h = 0; h < 2; h++) {
            uint32_t k = 2 * w + h, code = 0xFFFF; /* no-data, and the padding */
            if (k < count && !isnan(samples[k])) {
                double c = floor(((double)samples[k] - lo) / scale + 0.5);
                c = c < 0 ? 0 : c > 65534 ? 65534 : c;
                if (fabs(lo + scale * c - (double)samples[k]) > tolerance)
                    goto f32;
                code = (uint32_t)c;
            }
            word |= code << (16 * h);
        }
        put_word(dst, w, word);
    }
    enc.offset = lo;
    enc.scale = scale;
    enc.bytes = 4 * words;
    return enc;
f32:
    memcpy(dst, samples, (size_t)count * 4);
    enc.format = TSR_HW_HEIGHT_F32;
    enc.offset = 0;
    enc.scale = 1;
    enc.bytes = 4 * count;
    return enc;
}

/* ---- The renderer ------------------------------------------------------- */

enum { FMT_PENDING = 0, FMT_FREE = 255 }; /* besides TSR_HW_HEIGHT_U16 / F32 */

typedef struct entry {
    uint64_t key;
    uint64_t frame;       /* the last frame that drew it */
    double offset, scale; /* its encoding */
    uint32_t slot;        /* first slot; NIL while pending */
    uint32_t bytes;       /* encoded bytes */
    uint32_t prev, next;  /* LRU list (next also links the free entries) */
    uint32_t tile;        /* index into the tiles of frame `frame` */
    uint8_t format;       /* tsr_hw_height_format, FMT_PENDING (fetch due this frame) or FMT_FREE */
} entry;

struct tsr_hw_renderer {
    tsr_hw_backend *be;
    tsr_allocator alloc;
    const tsr_allocator *ap; /* &alloc, or NULL for malloc */
    uint32_t n, samples, slot_bytes;
    double max_q;
    tsr_hw_buffer index_buf, pool;
    uint32_t first_index[16], index_count[16];

    /* the pool's slots */
    uint32_t slot_count, pair_count, slots_used;
    uint64_t *used; /* bit per slot, 2 * pair_count bits */
    uint32_t *empty, empty_n;
    uint32_t *half, *half_pos, half_n;

    /* the resident (and pending) tiles */
    entry *e;
    uint32_t e_count, e_cap, free_head;
    uint32_t lru_head, lru_tail;
    uint32_t *table; /* entry index + 1, 0 empty */
    uint32_t table_mask, table_count;
    uint32_t resident, resident_u16;
    uint64_t bytes_resident;

    uint64_t frame;
    uint64_t frame_need; /* slots the frame's distinct tiles need so far (pending ones count 1) */
    uint32_t *tile_entry, tile_cap;
    float *fetch_buf, *reloc_fetch_buf;
    void *encode_buf, *reloc_encode_buf;
};

double tsr_hw_now_ms(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return ts.tv_sec * 1e3 + ts.tv_nsec * 1e-6;
}

/* -- pool slots -- */

static bool bit(const tsr_hw_renderer *r, uint32_t s) { return (r->used[s >> 6] >> (s & 63)) & 1; }
static void set_bit(tsr_hw_renderer *r, uint32_t s) { r->used[s >> 6] |= (uint64_t)1 << (s & 63); }
static void clear_bit(tsr_hw_renderer *r, uint32_t s) { r->used[s >> 6] &= ~((uint64_t)1 << (s & 63)); }
static bool phantom_pair(const tsr_hw_renderer *r, uint32_t p) { return 2 * p + 1 >= r->slot_count; }

static void half_add(tsr_hw_renderer *r, uint32_t p)
{
    r->half_pos[p] = r->half_n;
    r->half[r->half_n++] = p;
}

static void half_remove(tsr_hw_renderer *r, uint32_t p)
{
    uint32_t i = r->half_pos[p], last = r->half[--r->half_n];
    r->half[i] = last;
    r->half_pos[last] = i;
}

static void pool_reset(tsr_hw_renderer *r)
{
    memset(r->used, 0, (size_t)(2 * r->pair_count + 63) / 64 * sizeof *r->used);
    r->empty_n = r->half_n = r->slots_used = 0;
    for (uint32_t p = r->pair_count; p-- > 0;) {
        if (phantom_pair(r, p)) {
            set_bit(r, 2 * p + 1); /* beyond the pool */
            half_add(r, p);
        } else {
            r->empty[r->empty_n++] = p;
        }
    }
}

/* Takes the free slot of half pair p, which becomes full. */
static uint32_t take_half(tsr_hw_renderer *r, uint32_t p)
{
    uint32_t s = bit(r, 2 * p) ? 2 * p + 1 : 2 * p;
    set_bit(r, s);
    half_remove(r, p);
    r->slots_used++;
    return s;
}

static uint32_t alloc_slots(tsr_hw_renderer *r, uint8_t format)
{
    if (format == TSR_HW_HEIGHT_U16 && r->half_n)
        return take_half(r, r->half[r->half_n - 1]);
    if (!r->empty_n)
        return NIL;
    uint32_t p = r->empty[--r->empty_n];
    set_bit(r, 2 * p);
    r->slots_used++;
    if (format == TSR_HW_HEIGHT_U16) {
        half_add(r, p);
    } else {
        set_bit(r, 2 * p + 1);
        r->slots_used++;
    }
    return 2 * p;
}

static void free_slots(tsr_hw_renderer *r, uint32_t s, uint8_t format)
{
    uint32_t p = s / 2;
    if (format == TSR_HW_HEIGHT_F32) {
        clear_bit(r, 2 * p);
        clear_bit(r, 2 * p + 1);
        r->slots_used -= 2;
        r->empty[r->empty_n++] = p;
        return;
    }
    clear_bit(r, s);
    r->slots_used--;
    if (bit(r, s ^ 1)) { /* was full, now half */
        half_add(r, p);
    } else { /* was half, now empty */
        half_remove(r, p);
        r->empty[r->empty_n++] = p;
    }
}

/* -- the key -> entry table -- */

static uint32_t hash_key(uint64_t k)
{
    k ^= k >> 33; /* splitmix64's finaliser: Morton keys differ in low bits only */
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ull;
    k ^= k >> 33;
    return (uint32_t)k;
}

static uint32_t table_find(const tsr_hw_renderer *r, uint64_t key)
{
    for (uint32_t i = hash_key(key) & r->table_mask;; i = (i + 1) & r->table_mask) {
        uint32_t v = r->table[i];
        if (v == 0)
            return NIL;
        if (r->e[v - 1].key == key)
            return v - 1;
    }
}

static void table_put(uint32_t *table, uint32_t mask, const entry *e, uint32_t idx)
{
    uint32_t i = hash_key(e[idx].key) & mask;
    while (table[i])
        i = (i + 1) & mask;
    table[i] = idx + 1;
}

static bool table_insert(tsr_hw_renderer *r, uint32_t idx)
{
    if ((uint64_t)(r->table_count + 1) * 2 > (uint64_t)r->table_mask + 1) {
        uint32_t cap = 2 * (r->table_mask + 1);
        uint32_t *t = tsr_alloc(r->ap, (size_t)cap * sizeof *t);
        if (!t)
            return false;
        memset(t, 0, (size_t)cap * sizeof *t);
        for (uint32_t i = 0; i <= r->table_mask; i++)
            if (r->table[i])
                table_put(t, cap - 1, r->e, r->table[i] - 1);
        tsr_free(r->ap, r->table);
        r->table = t;
        r->table_mask = cap - 1;
    }
    table_put(r->table, r->table_mask, r->e, idx);
    r->table_count++;
    return true;
}

static void table_remove(tsr_hw_renderer *r, uint64_t key)
{
    uint32_t mask = r->table_mask, i = hash_key(key) & mask;
    while (r->e[r->table[i] - 1].key != key) /* present by contract */
        i = (i + 1) & mask;
    /* backward shift: pull later members of the cluster into the hole
     * unless their home lies cyclically in (hole, their position] */
    for (uint32_t j = i;;) {
        j = (j + 1) & mask;
        if (r->table[j] == 0)
            break;
        uint32_t home = hash_key(r->e[r->table[j] - 1].key) & mask;
        bool stays = i <= j ? (i < home && home <= j) : (i < home || home <= j);
        if (!stays) {
            r->table[i] = r->table[j];
            i = j;
        }
    }
    r->table[i] = 0;
    r->table_count--;
}

/* -- entries and the LRU list -- */

static void lru_unlink(tsr_hw_renderer *r, uint32_t i)
{
    entry *e = &r->e[i];
    if (e->prev != NIL)
        r->e[e->prev].next = e->next;
    else
        r->lru_head = e->next;
    if (e->next != NIL)
        r->e[e->next].prev = e->prev;
    else
        r->lru_tail = e->prev;
}

static void lru_push_front(tsr_hw_renderer *r, uint32_t i)
{
    entry *e = &r->e[i];
    e->prev = NIL;
    e->next = r->lru_head;
    if (r->lru_head != NIL)
        r->e[r->lru_head].prev = i;
    else
        r->lru_tail = i;
    r->lru_head = i;
}

/* A new pending entry for key, in the table and at the front of the LRU
 * list; NIL when out of memory. */
static uint32_t entry_new(tsr_hw_renderer *r, uint64_t key)
{
    uint32_t i = r->free_head;
    if (i != NIL) {
        r->free_head = r->e[i].next;
    } else {
        if (r->e_count == r->e_cap) {
            if (r->e_cap >= NIL / 2)
                return NIL;
            uint32_t cap = r->e_cap ? 2 * r->e_cap : 256;
            entry *ne = tsr_realloc(r->ap, r->e, (size_t)cap * sizeof *ne);
            if (!ne)
                return NIL;
            r->e = ne;
            r->e_cap = cap;
        }
        i = r->e_count++;
    }
    entry *e = &r->e[i];
    memset(e, 0, sizeof *e);
    e->key = key;
    e->slot = NIL;
    e->format = FMT_PENDING;
    if (!table_insert(r, i)) {
        e->format = FMT_FREE;
        e->next = r->free_head;
        r->free_head = i;
        return NIL;
    }
    lru_push_front(r, i);
    return i;
}

/* Removes an entry (resident or pending) from the cache. */
static void entry_drop(tsr_hw_renderer *r, uint32_t i)
{
    entry *e = &r->e[i];
    if (e->format == TSR_HW_HEIGHT_U16 || e->format == TSR_HW_HEIGHT_F32) {
        free_slots(r, e->slot, e->format);
        r->resident--;
        r->resident_u16 -= e->format == TSR_HW_HEIGHT_U16;
        r->bytes_resident -= e->bytes;
    }
    table_remove(r, e->key);
    lru_unlink(r, i);
    e->format = FMT_FREE;
    e->next = r->free_head;
    r->free_head = i;
}

static void touch(tsr_hw_renderer *r, uint32_t i, uint32_t tile)
{
    if (r->lru_head != i) {
        lru_unlink(r, i);
        lru_push_front(r, i);
    }
    r->e[i].frame = r->frame;
    r->e[i].tile = tile;
}

static uint32_t slots_of(uint8_t format) { return format == TSR_HW_HEIGHT_F32 ? 2 : 1; }

/* -- one frame -- */

typedef struct frame_ctx {
    const tsr_hw_tile *tiles;
    uint32_t count;
    tsr_hw_fetch_fn fetch;
    void *user;
    tsr_hw_render_stats *st;
    tsr_error *err;
} frame_ctx;

/* Fetches and encodes a tile into the given buffers. */
static tsr_status fetch_encode(tsr_hw_renderer *r, frame_ctx *f, const tsr_hw_tile *t, float *samples, void *buf,
                               tsr_hw_encoding *enc)
{
    if (!f->fetch(f->user, t, samples))
        return tsr_error_set(f->err, TSR_ERR_IO,
                             "hw renderer: fetching the samples of tile %" PRIu32 " (key %#" PRIx64 ") failed",
                             (uint32_t)(t - f->tiles), t->key);
    double q = t->max_quantization > 0 && isfinite(t->max_quantization) ? t->max_quantization : r->max_q;
    *enc = tsr_hw_encode_samples(samples, r->samples, q, buf);
    return TSR_OK;
}

static tsr_status upload(tsr_hw_renderer *r, frame_ctx *f, uint32_t slot, const void *data, uint32_t bytes,
                         uint64_t key)
{
    if (!r->be->upload(r->be, r->pool, (uint64_t)slot * r->slot_bytes, data, bytes))
        return tsr_error_set(f->err, TSR_ERR_IO,
                             "hw renderer: the %s backend refused the upload of tile key %#" PRIx64 " (%" PRIu32
                             " bytes at slot %" PRIu32 ")",
                             r->be->name, key, bytes, slot);
    f->st->bytes_uploaded += bytes;
    return TSR_OK;
}

/* Every resident tile is drawn by this frame, no pair is empty, and two
 * slots are free in two half pairs: moves the U16 tile of one of them
 * into the other, which empties a pair. */
static tsr_status relocate(tsr_hw_renderer *r, frame_ctx *f)
{
    uint32_t from = r->half[0], to = r->half[1];
    if (phantom_pair(r, from)) { /* emptying the phantom pair gains nothing */
        from = r->half[1];
        to = r->half[0];
    }
    uint32_t s = bit(r, 2 * from) ? 2 * from : 2 * from + 1, i;
    for (i = 0; i < r->e_count; i++) /* rare: a scan beats a per-slot owner array */
        if (r->e[i].format == TSR_HW_HEIGHT_U16 && r->e[i].slot == s)
            break;
    assert(i < r->e_count && r->e[i].frame == r->frame); /* a half pair holds a tile, drawn by this frame */
    entry *e = &r->e[i];
    const tsr_hw_tile *t = &f->tiles[e->tile];
    tsr_hw_encoding enc;
    tsr_status st = fetch_encode(r, f, t, r->reloc_fetch_buf, r->reloc_encode_buf, &enc);
    if (st != TSR_OK)
        return st;
    if (enc.format != TSR_HW_HEIGHT_U16 || r->samples * 2 != e->bytes)
        return tsr_error_set(f->err, TSR_ERR_VALUE,
                             "hw renderer: tile key %#" PRIx64 " fetched different samples than before (a key "
                             "must always name the same samples)",
                             t->key);
    uint32_t ns = take_half(r, to);
    st = upload(r, f, ns, r->reloc_encode_buf, r->samples * 2, t->key);
    if (st != TSR_OK) {
        free_slots(r, ns, TSR_HW_HEIGHT_U16);
        return st;
    }
    free_slots(r, s, TSR_HW_HEIGHT_U16);
    e->slot = ns;
    e->offset = enc.offset;
    e->scale = enc.scale;
    return TSR_OK;
}

/* Slots for a tile of the given format, evicting tiles this frame does
 * not draw, least recently drawn first. */
static tsr_status make_room(tsr_hw_renderer *r, frame_ctx *f, uint8_t format, uint32_t *slot)
{
    for (;;) {
        *slot = alloc_slots(r, format);
        if (*slot != NIL)
            return TSR_OK;
        uint32_t tail = r->lru_tail;
        if (tail != NIL && r->e[tail].frame != r->frame) {
            entry_drop(r, tail);
            f->st->tiles_evicted++;
            continue;
        }
        if (format == TSR_HW_HEIGHT_F32 && r->slot_count - r->slots_used >= 2) {
            tsr_status st = relocate(r, f);
            if (st != TSR_OK)
                return st;
            continue;
        }
        return tsr_error_set(f->err, TSR_ERR_TOO_LARGE,
                             "hw renderer: the frame's %" PRIu32 " tiles need at least %" PRIu64
                             " sample slots of %" PRIu32 " bytes (U16 tiles 1, F32 tiles 2), the cache has %" PRIu32
                             " slots (cache_bytes %" PRIu64 ")",
                             f->count, r->frame_need, r->slot_bytes, r->slot_count,
                             (uint64_t)r->slot_count * r->slot_bytes);
    }
}

/* Fetches, encodes and uploads a pending entry. */
static tsr_status load(tsr_hw_renderer *r, frame_ctx *f, uint32_t i, const tsr_hw_tile *t)
{
    tsr_hw_encoding enc;
    tsr_status st = fetch_encode(r, f, t, r->fetch_buf, r->encode_buf, &enc);
    if (st != TSR_OK)
        return st;
    r->frame_need += slots_of((uint8_t)enc.format) - 1; /* counted as 1 while pending */
    uint32_t slot;
    st = make_room(r, f, (uint8_t)enc.format, &slot);
    if (st != TSR_OK)
        return st;
    /* U16: the samples alone, without the encoding's padding to a word */
    uint32_t bytes = enc.format == TSR_HW_HEIGHT_U16 ? r->samples * 2 : enc.bytes;
    st = upload(r, f, slot, r->encode_buf, bytes, t->key);
    if (st != TSR_OK) {
        free_slots(r, slot, (uint8_t)enc.format);
        return st;
    }
    entry *e = &r->e[i];
    e->slot = slot;
    e->format = (uint8_t)enc.format;
    e->offset = enc.offset;
    e->scale = enc.scale;
    e->bytes = bytes;
    r->resident++;
    r->resident_u16 += enc.format == TSR_HW_HEIGHT_U16;
    r->bytes_resident += bytes;
    f->st->tiles_uploaded++;
    return TSR_OK;
}

static void drop_pending(tsr_hw_renderer *r, uint32_t count)
{
    for (uint32_t k = 0; k < count; k++) {
        uint32_t i = r->tile_entry[k];
        if (i != NIL && r->e[i].format == FMT_PENDING)
            entry_drop(r, i);
    }
}

/* Whether a double converts to a finite float (converting one beyond
 * FLT_MAX is undefined behaviour). */
static bool fits_float(double x) { return fabs(x) <= FLT_MAX; }

static tsr_status check_tile(const tsr_hw_frame *frame, const tsr_hw_tile *t, uint32_t k, uint32_t count,
                             tsr_error *err)
{
    const char *why = NULL;
    if (!fits_float(t->spacing[0]) || !fits_float(t->spacing[1]) || !((float)t->spacing[0] > 0) ||
        !((float)t->spacing[1] > 0))
        why = "spacing not positive and finite (as a float)";
    else if (!fits_float(t->origin[0] - frame->eye[0]) || !fits_float(t->origin[1] - frame->eye[1]))
        why = "origin not finite (relative to the eye, as a float)";
    else if (!fits_float(t->z_scale))
        why = "z_scale not finite (as a float)";
    else if (!(t->morph >= 0 && t->morph <= 1))
        why = "morph outside [0, 1]";
    else if (t->stitch > 15)
        why = "stitch has bits beyond TSR_EDGE_*";
    for (int e = 0; e < 8 && !why; e++)
        if (t->neighbour[e] > count || t->neighbour[e] == k + 1)
            why = t->neighbour[e] > count ? "a neighbour beyond the frame's tiles" : "itself as a neighbour";
    if (why)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: tile %" PRIu32 " (key %#" PRIx64 "): %s", k, t->key,
                             why);
    return TSR_OK;
}

tsr_status tsr_hw_renderer_frame(tsr_hw_renderer *r, const tsr_hw_frame *frame, const tsr_hw_tile *tiles,
                                 uint32_t count, tsr_hw_fetch_fn fetch, void *user, tsr_hw_render_stats *stats,
                                 tsr_error *err)
{
    tsr_hw_render_stats st;
    memset(&st, 0, sizeof st);
    if (stats)
        *stats = st;
    if (!r || !frame || (count && !tiles))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: NULL renderer, frame or tiles");
    if (!isfinite(frame->eye[0]) || !isfinite(frame->eye[1]) || !isfinite(frame->eye[2]))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: the frame's eye is not finite");
    for (uint32_t k = 0; k < count; k++) {
        tsr_status s = check_tile(frame, &tiles[k], k, count, err);
        if (s != TSR_OK)
            return s;
    }
    if (count > r->tile_cap) {
        uint32_t *te = tsr_realloc(r->ap, r->tile_entry, (size_t)count * sizeof *te);
        if (!te)
            return tsr_error_set(err, TSR_ERR_NOMEM, "hw renderer: out of memory for %" PRIu32 " tiles", count);
        r->tile_entry = te;
        r->tile_cap = count;
    }
    frame_ctx f = {tiles, count, fetch, user, &st, err};
    r->frame++;
    r->frame_need = 0;

    /* 1. Stamp every tile of the frame, resident or pending, before any
     *    eviction, so that none of them is evicted. */
    uint32_t pending = 0;
    for (uint32_t k = 0; k < count; k++) {
        uint32_t i = table_find(r, tiles[k].key);
        if (i == NIL) {
            i = entry_new(r, tiles[k].key);
            if (i == NIL) {
                drop_pending(r, k);
                return tsr_error_set(err, TSR_ERR_NOMEM, "hw renderer: out of host memory for the tile table");
            }
            pending++;
        }
        if (r->e[i].frame != r->frame)
            r->frame_need += slots_of(r->e[i].format);
        touch(r, i, k);
        r->tile_entry[k] = i;
    }
    tsr_status status = TSR_OK;
    if (r->frame_need > r->slot_count)
        status =
            tsr_error_set(err, TSR_ERR_TOO_LARGE,
                          "hw renderer: the frame's %" PRIu32 " tiles need at least %" PRIu64
                          " sample slots of %" PRIu32 " bytes, the cache has %" PRIu32 " (cache_bytes %" PRIu64 ")",
                          count, r->frame_need, r->slot_bytes, r->slot_count, (uint64_t)r->slot_count * r->slot_bytes);
    else if (pending && !fetch)
        status = tsr_error_set(err, TSR_ERR_ARGUMENT,
                               "hw renderer: %" PRIu32 " tiles are not resident and fetch is NULL", pending);
    else if (!r->be->begin_frame(r->be, frame))
        status = tsr_error_set(err, TSR_ERR_IO, "hw renderer: the %s backend refused to begin a frame", r->be->name);
    if (status != TSR_OK) {
        drop_pending(r, count);
        return status;
    }

    /* 2. Fetch, encode and upload the tiles entering the cache (inside
     *    the frame: the backend copies them before the frame's draws). */
    double t0 = tsr_hw_now_ms();
    for (uint32_t k = 0; k < count && status == TSR_OK; k++)
        if (r->e[r->tile_entry[k]].format == FMT_PENDING)
            status = load(r, &f, r->tile_entry[k], &tiles[k]);
    double t1 = tsr_hw_now_ms();
    st.upload_ms = t1 - t0;

    /* 3. Record one draw per tile. */
    for (uint32_t k = 0; k < count && status == TSR_OK; k++) {
        const tsr_hw_tile *t = &tiles[k];
        const entry *e = &r->e[r->tile_entry[k]];
        unsigned m = t->stitch & 15;
        tsr_hw_tile_draw d;
        memset(&d, 0, sizeof d);
        d.samples = r->pool;
        uint64_t at = (uint64_t)e->slot * r->slot_bytes;
        d.samples_offset = at & ~(uint64_t)3;
        d.first_sample = (uint32_t)(at & 3) / 2;
        d.format = (tsr_hw_height_format)e->format;
        d.indices = r->index_buf;
        d.first_index = r->first_index[m];
        d.index_count = r->index_count[m];
        d.n = r->n;
        for (int a = 0; a < 2; a++) {
            d.origin[a] = (float)(t->origin[a] - frame->eye[a]); /* in double, then rounded */
            d.spacing[a] = (float)t->spacing[a];
            double lim = t->limit[a] - frame->eye[a];
            d.limit[a] = t->limit[a] == 0 || !fits_float(lim) ? FLT_MAX : (float)lim;
        }
        double z_base = t->z_scale * e->offset - frame->eye[2], z_step = t->z_scale * e->scale;
        if (!fits_float(z_base) || !fits_float(z_step)) {
            status = tsr_error_set(err, TSR_ERR_VALUE,
                                   "hw renderer: tile %" PRIu32 " (key %#" PRIx64 "): heights beyond float range", k,
                                   t->key);
            break;
        }
        d.z_base = (float)z_base;
        d.z_step = (float)z_step;
        d.morph = t->morph;
        d.level = t->level;
        d.parity = t->parity;
        memcpy(d.neighbour, t->neighbour, sizeof d.neighbour); /* draw k is tile k */
        if (!r->be->draw_tile(r->be, &d))
            status = tsr_error_set(err, TSR_ERR_IO, "hw renderer: the %s backend refused the draw of tile %" PRIu32
                                                    " (key %#" PRIx64 ")",
                                   r->be->name, k, t->key);
        st.triangles += d.index_count / 3;
    }
    st.record_ms = tsr_hw_now_ms() - t1;

    if (status != TSR_OK) {
        drop_pending(r, count);
        r->be->end_frame(r->be, NULL); /* what was uploaded stays resident */
    } else if (!r->be->end_frame(r->be, &st.device)) {
        status = tsr_error_set(err, TSR_ERR_IO, "hw renderer: the %s backend failed to end the frame", r->be->name);
    }
    st.tiles = status == TSR_OK ? count : 0;
    st.tiles_u16 = r->resident_u16;
    st.tiles_resident = r->resident;
    st.bytes_resident = r->bytes_resident;
    if (stats)
        *stats = st;
    return status;
}

void tsr_hw_renderer_flush(tsr_hw_renderer *r)
{
    if (!r)
        return;
    memset(r->table, 0, ((size_t)r->table_mask + 1) * sizeof *r->table);
    r->table_count = 0;
    r->e_count = 0;
    r->free_head = r->lru_head = r->lru_tail = NIL;
    r->resident = r->resident_u16 = 0;
    r->bytes_resident = 0;
    pool_reset(r);
}

void tsr_hw_renderer_destroy(tsr_hw_renderer *r)
{
    if (!r)
        return;
    if (r->pool)
        r->be->destroy_buffer(r->be, r->pool);
    if (r->index_buf)
        r->be->destroy_buffer(r->be, r->index_buf);
    tsr_allocator a = r->alloc; /* r is freed last */
    const tsr_allocator *ap = r->ap ? &a : NULL;
    void *blocks[] = {r->used,     r->empty,      r->half,      r->half_pos,        r->e,
                      r->table,    r->tile_entry, r->fetch_buf, r->reloc_fetch_buf, r->encode_buf,
                      r->reloc_encode_buf};
    for (size_t k = 0; k < sizeof blocks / sizeof blocks[0]; k++)
        tsr_free(ap, blocks[k]);
    tsr_free(ap, r);
}

static tsr_status upload_patterns(tsr_hw_renderer *r, tsr_error *err)
{
    tsr_tile_patterns pat;
    if (tsr_tile_patterns_init(&pat, r->n, r->ap) != TSR_OK)
        return tsr_error_set(err, TSR_ERR_NOMEM, "hw renderer: out of memory for the stitch patterns of n = %" PRIu32,
                             r->n);
    uint64_t total = 0;
    for (unsigned m = 0; m < 16; m++) {
        r->first_index[m] = (uint32_t)total;
        r->index_count[m] = 3 * pat.count[m];
        total += r->index_count[m];
    }
    tsr_status st = TSR_OK;
    r->index_buf = r->be->create_buffer(r->be, TSR_HW_INDEX, total * 4);
    if (!r->index_buf)
        st = tsr_error_set(err, TSR_ERR_NOMEM,
                           "hw renderer: the %s backend could not create an index buffer of %" PRIu64 " bytes",
                           r->be->name, total * 4);
    for (unsigned m = 0; m < 16 && st == TSR_OK; m++)
        if (!r->be->upload(r->be, r->index_buf, (uint64_t)r->first_index[m] * 4, pat.tri[m],
                           (uint64_t)r->index_count[m] * 4))
            st = tsr_error_set(err, TSR_ERR_IO, "hw renderer: the %s backend refused the stitch patterns' upload",
                               r->be->name);
    tsr_tile_patterns_free(&pat);
    return st;
}

tsr_status tsr_hw_renderer_create(tsr_hw_backend *backend, const tsr_hw_renderer_options *opts,
                                  const tsr_allocator *alloc, tsr_hw_renderer **out, tsr_error *err)
{
    if (!out || !backend)
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: NULL backend or output");
    *out = NULL;
    uint32_t n = opts && opts->tile_n ? opts->tile_n : DEFAULT_TILE_N;
    uint64_t cache = opts && opts->cache_bytes ? opts->cache_bytes : DEFAULT_CACHE_BYTES;
    double max_q = opts ? opts->max_quantization : 0;
    if (n < TSR_TILE_MIN || n > TSR_TILE_MAX || (n & 1))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: tile_n %" PRIu32 " is not even in 2..%u", n,
                             TSR_TILE_MAX);
    if (!(max_q >= 0))
        return tsr_error_set(err, TSR_ERR_ARGUMENT, "hw renderer: max_quantization %g is negative or NaN", max_q);
    /* a slot holds one U16 tile, unpadded (2 bytes per sample); a pair of
     * slots, 4-byte aligned, holds an F32 tile */
    uint32_t samples = (n + 1) * (n + 1), slot_bytes = samples * 2;
    uint64_t slots = cache / slot_bytes;
    if (slots == 0)
        return tsr_error_set(err, TSR_ERR_ARGUMENT,
                             "hw renderer: cache_bytes %" PRIu64 " is smaller than one tile of n = %" PRIu32
                             " (%" PRIu32 " bytes)",
                             cache, n, slot_bytes);
    if (slots > MAX_SLOTS)
        slots = MAX_SLOTS;

    tsr_hw_renderer *r = tsr_alloc(alloc, sizeof *r);
    if (!r)
        return tsr_error_set(err, TSR_ERR_NOMEM, "hw renderer: out of memory");
    memset(r, 0, sizeof *r);
    if (alloc) {
        r->alloc = *alloc;
        r->ap = &r->alloc;
    }
    r->be = backend;
    r->n = n;
    r->samples = samples;
    r->slot_bytes = slot_bytes;
    r->max_q = max_q;
    r->slot_count = (uint32_t)slots;
    r->pair_count = (r->slot_count + 1) / 2;
    r->free_head = r->lru_head = r->lru_tail = NIL;
    uint32_t table_cap = 1024;
    r->table_mask = table_cap - 1;
    size_t bound = tsr_hw_encode_bound(samples);
    r->used = tsr_alloc(r->ap, (size_t)(2 * r->pair_count + 63) / 64 * sizeof *r->used);
    r->empty = tsr_alloc(r->ap, (size_t)r->pair_count * sizeof *r->empty);
    r->half = tsr_alloc(r->ap, (size_t)r->pair_count * sizeof *r->half);
    r->half_pos = tsr_alloc(r->ap, (size_t)r->pair_count * sizeof *r->half_pos);
    r->table = tsr_alloc(r->ap, table_cap * sizeof *r->table);
    r->fetch_buf = tsr_alloc(r->ap, samples * sizeof(float));
    r->reloc_fetch_buf = tsr_alloc(r->ap, samples * sizeof(float));
    r->encode_buf = tsr_alloc(r->ap, bound);
    r->reloc_encode_buf = tsr_alloc(r->ap, bound);
    if (!r->used || !r->empty || !r->half || !r->half_pos || !r->table || !r->fetch_buf || !r->reloc_fetch_buf ||
        !r->encode_buf || !r->reloc_encode_buf) {
        tsr_hw_renderer_destroy(r);
        return tsr_error_set(err, TSR_ERR_NOMEM, "hw renderer: out of memory for a cache of %" PRIu64 " slots", slots);
    }
    memset(r->table, 0, table_cap * sizeof *r->table);
    pool_reset(r);

    tsr_status st = upload_patterns(r, err);
    if (st == TSR_OK) {
        /* + 4: a U16 tile in the last slot reads whole words */
        uint64_t pool_bytes = (uint64_t)r->slot_count * slot_bytes + 4;
        r->pool = backend->create_buffer(backend, TSR_HW_VERTEX, pool_bytes);
        if (!r->pool)
            st = tsr_error_set(err, TSR_ERR_NOMEM,
                               "hw renderer: the %s backend could not create the sample pool of %" PRIu64 " bytes",
                               backend->name, pool_bytes);
    }
    if (st != TSR_OK) {
        tsr_hw_renderer_destroy(r);
        return st;
    }
    *out = r;
    return TSR_OK;
}
