/* key_map.h — an open-addressing hash map from 64-bit keys to dense 32-bit indices: the first
 * key added gets 0, the next new key 1, and so on, so the indices can address parallel arrays
 * (lattice vertices, grid edges). Insertion order, hence every index, is deterministic. */
#ifndef ISM_KEY_MAP_H
#define ISM_KEY_MAP_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#define ISM_KEY_NONE UINT32_MAX

typedef struct ism_key_slot {
    uint64_t key;
    uint32_t index;  /* ISM_KEY_NONE: empty */
} ism_key_slot;

typedef struct ism_key_map {
    uint64_t *keys;        /* by index: the key that index stands for */
    ism_key_slot *slots;   /* hash slots (the key beside its index: one cache line a probe) */
    size_t n, cap_keys, mask;
} ism_key_map;

void ism_key_map_init(ism_key_map *m);
void ism_key_map_free(ism_key_map *m);

/* The index of key, adding it when new (*added says which). ISM_KEY_NONE when out of
 * memory or past 2^32 - 2 keys. */
uint32_t ism_key_map_add(ism_key_map *m, uint64_t key, bool *added);

/* The index of key, or ISM_KEY_NONE when it was never added. */
uint32_t ism_key_map_find(const ism_key_map *m, uint64_t key);

#endif
