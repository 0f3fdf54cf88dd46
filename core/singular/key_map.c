/* key_map.c — the 64-bit key to dense index hash map (see key_map.h): linear probing in a
 * power-of-two slot table kept at most half full, keys stored once in index order. */
#include "core/singular/key_map.h"

#include <stdlib.h>

/* Slots per key before the table doubles: at most half full keeps probe runs short. */
#define KEY_MAP_LOAD_INVERSE 2
#define KEY_MAP_MIN_SLOTS 1024

static size_t slot_of(uint64_t key, size_t mask)
{
    key ^= key >> 33; /* murmur3's finaliser: every key bit reaches the low bits */
    key *= 0xff51afd7ed558ccdull;
    key ^= key >> 33;
    key *= 0xc4ceb9fe1a85ec53ull;
    key ^= key >> 33;
    return (size_t)key & mask;
}

void ism_key_map_init(ism_key_map *m)
{
    m->keys = NULL;
    m->slots = NULL;
    m->n = m->cap_keys = m->mask = 0;
}

void ism_key_map_free(ism_key_map *m)
{
    free(m->keys);
    free(m->slots);
    ism_key_map_init(m);
}

static bool rehash(ism_key_map *m, size_t nslots)
{
    ism_key_slot *s = malloc(nslots * sizeof *s);
    if (!s)
        return false;
    for (size_t i = 0; i < nslots; i++)
        s[i].index = ISM_KEY_NONE;
    for (size_t i = 0; i < m->n; i++) {
        size_t j = slot_of(m->keys[i], nslots - 1);
        while (s[j].index != ISM_KEY_NONE)
            j = (j + 1) & (nslots - 1);
        s[j] = (ism_key_slot){m->keys[i], (uint32_t)i};
    }
    free(m->slots);
    m->slots = s;
    m->mask = nslots - 1;
    return true;
}

static bool grow(ism_key_map *m)
{
    if (m->n == m->cap_keys) {
        size_t c = m->cap_keys ? 2 * m->cap_keys : KEY_MAP_MIN_SLOTS / KEY_MAP_LOAD_INVERSE;
        uint64_t *k = realloc(m->keys, c * sizeof *k);
        if (!k)
            return false;
        m->keys = k;
        m->cap_keys = c;
    }
    if (!m->slots || (m->n + 1) * KEY_MAP_LOAD_INVERSE > m->mask + 1) {
        size_t ns = m->slots ? 2 * (m->mask + 1) : KEY_MAP_MIN_SLOTS;
        return rehash(m, ns);
    }
    return true;
}

uint32_t ism_key_map_find(const ism_key_map *m, uint64_t key)
{
    if (!m->slots)
        return ISM_KEY_NONE;
    for (size_t j = slot_of(key, m->mask);; j = (j + 1) & m->mask) {
        const ism_key_slot *s = &m->slots[j];
        if (s->index == ISM_KEY_NONE || s->key == key)
            return s->index;
    }
}

uint32_t ism_key_map_add(ism_key_map *m, uint64_t key, bool *added)
{
    *added = false;
    uint32_t i = ism_key_map_find(m, key);
    if (i != ISM_KEY_NONE)
        return i;
    if (m->n >= (size_t)UINT32_MAX - 1 || !grow(m))
        return ISM_KEY_NONE;
    size_t j = slot_of(key, m->mask);
    while (m->slots[j].index != ISM_KEY_NONE)
        j = (j + 1) & m->mask;
    m->slots[j] = (ism_key_slot){key, (uint32_t)m->n};
    m->keys[m->n] = key;
    *added = true;
    return (uint32_t)m->n++;
}
