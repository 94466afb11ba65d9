/* keymap.c: tsr_keymap, the vertex-welding hash map (tessellate.h). */
#include "tessellate/tessellate.h"

#include <string.h>

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
        size_t h = tsr__keymap_mix(m->slots[i].key) & (cap - 1);
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

bool tsr__keymap_grow(tsr_keymap *m, const tsr_allocator *a)
{
    return rehash(m, m->mask ? 2 * (m->mask + 1) : 16, a);
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
