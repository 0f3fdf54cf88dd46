/* lattice_pack.h — the break-point registry's sort keys of lattice points (breaks.c): a
 * point's three coordinates, each shifted right by `shift` (every corner is a multiple of
 * the finest leaf's size) into a field of cb bits, the two coordinates across a lattice
 * line first and the one along it last, so that the points of one line are consecutive in
 * key order. The field layout lives here alone: pack_shift gives a coordinate's field and
 * repack turns the key along z into the key along another axis. */
#ifndef ISM_LATTICE_PACK_H
#define ISM_LATTICE_PACK_H

#include <stdint.h>

typedef struct ism_packing {
    int shift, cb;
} ism_packing;

/* The bit where coordinate a's field starts in the key along `axis`: the coordinate after
 * the axis (cyclically) in the top field, the next in the middle one, the axis's own at 0. */
static inline int ism_pack_shift(const ism_packing *k, int axis, int a)
{
    return a == (axis + 1) % 3 ? 2 * k->cb : a == (axis + 2) % 3 ? k->cb : 0;
}

/* Point p's key along `axis`. */
static inline uint64_t ism_pack(const ism_packing *k, int axis, const int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    return ((uint64_t)(p[u] >> k->shift) << 2 * k->cb) |
           ((uint64_t)(p[v] >> k->shift) << k->cb) | (uint64_t)(p[axis] >> k->shift);
}

/* The point whose key along `axis` is key. */
static inline void ism_unpack(const ism_packing *k, int axis, uint64_t key, int32_t p[3])
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    uint64_t m = ((uint64_t)1 << k->cb) - 1;
    p[u] = (int32_t)(key >> 2 * k->cb) << k->shift;
    p[v] = (int32_t)((key >> k->cb) & m) << k->shift;
    p[axis] = (int32_t)(key & m) << k->shift;
}

/* The lattice line a key along some axis lies on (its two top fields). */
static inline uint64_t ism_pack_line(const ism_packing *k, uint64_t key) { return key >> k->cb; }

/* The coordinate along its axis of the point whose key is key (its bottom field). */
static inline int32_t ism_pack_along(const ism_packing *k, uint64_t key)
{
    return (int32_t)(key & (((uint64_t)1 << k->cb) - 1)) << k->shift;
}

/* The key along `axis` of the point whose key along z is key2: the key along z, (x, y, z)
 * from the top field down, with its three fields rotated left by (axis + 1) fields, to
 * (y, z, x) along x and (z, x, y) along y. Needs 0 < cb and 3 cb < 64 (cb = finest + 1 ≤
 * ISM_GRID_MAX_DEPTH + 1 = 20: 60 bits), so neither shift reaches 64 (along z, rot = 0:
 * key2 itself, as key2 < 2^width). */
static inline uint64_t ism_repack(const ism_packing *k, int axis, uint64_t key2)
{
    int width = 3 * k->cb, rot = (axis + 1) % 3 * k->cb;
    uint64_t mask = ((uint64_t)1 << width) - 1;
    return ((key2 << rot) & mask) | key2 >> (width - rot);
}

#endif
