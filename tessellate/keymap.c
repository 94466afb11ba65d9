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
    uint64_t *keys = tsr_alloc(a, cap * sizeof *keys);
    uint32_t *vals = tsr_alloc(a, cap * sizeof *vals);
    if (!keys || !vals) {
        tsr_free(a, keys);
        tsr_free(a, vals);
        return false;
    }
    memset(keys, 0, cap * sizeof *keys);
    for (size_t i = 0; m->keys && i <= m->mask; i++) {
        if (!m->keys[i])
            continue;
        size_t h = mix64(m->keys[i]) & (cap - 1);
        while (keys[h])
            h = (h + 1) & (cap - 1);
        keys[h] = m->keys[i];
        vals[h] = m->vals[i];
    }
    tsr_free(a, m->keys);
    tsr_free(a, m->vals);
    m->keys = keys;
    m->vals = vals;
    m->mask = cap - 1;
    return true;
}

bool tsr_keymap_reserve(tsr_keymap *m, size_t n, const tsr_allocator *a)
{
    size_t cap = 1024;
    while (cap < 2 * n + 2)
        cap *= 2;
    return (m->keys && cap <= m->mask + 1) || rehash(m, cap, a);
}

uint32_t *tsr_keymap_slot(tsr_keymap *m, uint64_t key, bool *found, const tsr_allocator *a)
{
    if ((m->count + 1) * 2 > m->mask + 1 && !rehash(m, m->mask ? 2 * (m->mask + 1) : 1024, a))
        return NULL;
    uint64_t k = key + 1;
    size_t h = mix64(k) & m->mask;
    while (m->keys[h] && m->keys[h] != k)
        h = (h + 1) & m->mask;
    *found = m->keys[h] == k;
    if (!*found) {
        m->keys[h] = k;
        m->count++;
    }
    return &m->vals[h];
}

uint32_t *tsr_keymap_find(const tsr_keymap *m, uint64_t key)
{
    if (!m->keys)
        return NULL;
    uint64_t k = key + 1;
    size_t h = mix64(k) & m->mask;
    while (m->keys[h] && m->keys[h] != k)
        h = (h + 1) & m->mask;
    return m->keys[h] == k ? &m->vals[h] : NULL;
}

void tsr_keymap_free(tsr_keymap *m, const tsr_allocator *a)
{
    tsr_free(a, m->keys);
    tsr_free(a, m->vals);
    memset(m, 0, sizeof *m);
}
