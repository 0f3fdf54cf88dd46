/* lattice_key.h — a lattice point (or the cell it is the lowest corner of) packed into one
 * 64-bit key, 21 bits per axis: sortable, hashable, and exact for any depth the lattice
 * supports (ISM_GRID_MAX_DEPTH 19 needs 20 bits). */
#ifndef ISM_LATTICE_KEY_H
#define ISM_LATTICE_KEY_H

#include <stdint.h>

#define ISM_LKEY_BITS 21
#define ISM_LKEY_MASK ((1u << ISM_LKEY_BITS) - 1u)

static inline uint64_t ism_lkey(int32_t i, int32_t j, int32_t k)
{
    return ((uint64_t)(uint32_t)i << (2 * ISM_LKEY_BITS)) | ((uint64_t)(uint32_t)j << ISM_LKEY_BITS)
         | (uint64_t)(uint32_t)k;
}

static inline void ism_lkey_unpack(uint64_t key, int32_t v[3])
{
    v[0] = (int32_t)((key >> (2 * ISM_LKEY_BITS)) & ISM_LKEY_MASK);
    v[1] = (int32_t)((key >> ISM_LKEY_BITS) & ISM_LKEY_MASK);
    v[2] = (int32_t)(key & ISM_LKEY_MASK);
}

/* The key of the lattice point d steps (each 0 or ±1) from key's point; the caller keeps
 * the result inside the lattice. */
static inline uint64_t ism_lkey_step(uint64_t key, int dx, int dy, int dz)
{
    int32_t v[3];
    ism_lkey_unpack(key, v);
    return ism_lkey(v[0] + dx, v[1] + dy, v[2] + dz);
}

#endif
