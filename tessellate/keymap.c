/* keymap.c: tsr_keymap, the vertex-welding hash map (tessellate.h). */
#include "tessellate/tessellate.h"

#include <string.h>

static uint64_t mix64(uint64_t k)
{
    k ^= k >> 33;
    k *= 0xff51afd7ed558ccdull;
    k ^= k >> 33;
    k *= 0xc4ceb9fe1a85ec53ull;
    k ^= k >> 33;
    return k;
}

/* Rehashes into cap slots (a power of two larger than the count). */
static bool rehash(tsr_keymap *m, size_t cap, const tsr_allocator *a)
{
    tsr_keyslot *slots = tsr_alloc(a, cap * sizeof *slots);
    if (!slots)
        return false;
    memset(slots, 0, cap * sizeof *slots);
    for (size_t i = 0; m->slots && i <= m->mask; i++) {
        if (!m->slots[i].key)
            continue;
        size_t h = mix64(m->slots[i].key) & (cap - 1);
        while (slots[h].key)
            h = (h + 1) & (cap - 1);
        slots[h] = m->slots[i];
    }
    tsr_free(a, m->slots);
    m->slots = slots;
    m->mask = cap - 1;
    return true;
}

bool tsr_keymap_reserve(tsr_keymap *m, size_t n, const tsr_allocator *a)
{
    size_t cap = 1024;
    while (cap < 2 * n + 2)
        cap *= 2;
    return (m->slots && cap <= m->mask + 1) || rehash(m, cap, a);
}

uint32_t *tsr_keymap_slot(tsr_keymap *m, uint64_t key, bool *found, const tsr_allocator *a)
{
    if ((m->count + 1) * 2 > m->mask + 1 && !rehash(m, m->mask ? 2 * (m->mask + 1) : 16, a))
        return NULL;
    uint64_t k = key + 1;
    size_t h = mix64(k) & m->mask;
    while (m->slots[h].key && m->slots[h].key != k)
        h = (h + 1) & m->mask;
    *found = m->slots[h].key == k;
    if (!*found) {
        m->slots[h].key = k;
        m->count++;
    }
    return &m->slots[h].val;
}

uint32_t *tsr_keymap_find(const tsr_keymap *m, uint64_t key)
{
    if (!m->slots)
        return NULL;
    uint64_t k = key + 1;
    size_t h = mix64(k) & m->mask;
    while (m->slots[h].key && m->slots[h].key != k)
        h = (h + 1) & m->mask;
    return m->slots[h].key == k ? &m->slots[h].val : NULL;
}

void tsr_keymap_clear(tsr_keymap *m)
{
    if (m->slots)
        memset(m->slots, 0, (m->mask + 1) * sizeof *m->slots);
    m->count = 0;
}

void tsr_keymap_free(tsr_keymap *m, const tsr_allocator *a)
{
    tsr_free(a, m->slots);
    memset(m, 0, sizeof *m);
}
