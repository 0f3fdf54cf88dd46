/* trig_pair.h — the sine and cosine of one argument, computed as a pair. Surfaces such as the
 * gyroid take both of the same argument (sin(k*x) … cos(k*x)), and the derivative of either
 * needs the other; sincos gives both for little more than the price of one. A memo of
 * arguments, kept by the workspace, hands out the second of the pair and repeats. It is
 * keyed on the argument's bits, so a hit is exactly what a fresh call would return (and
 * glibc's sincos returns bit for bit what sin and cos return). Not public. */
#ifndef ISM_TRIG_PAIR_H
#define ISM_TRIG_PAIR_H

#include <math.h>
#include <stdint.h>
#include <string.h>

/* A direct-mapped cache of arguments, kept by the workspace from one evaluation to the next:
 * the polygoniser evaluates f along lattice edges and faces, where two of the three
 * coordinates stay the same from point to point (sin(k*x) repeats), and corners shared by
 * neighbours. 2^ISM_TRIG_CACHE_BITS entries (96 KB) for a tape that takes sines or cosines:
 * gyroid ball at E = 1e-3 (callgrind, ism_mesh_surface, one thread), 4.76M sincos calls with
 * 2^9 entries; the whole run 3,735.5M instructions with 2^9, 3,694.6M with 2^11, 3,679.8M
 * with 2^12, 3,660.5M with 2^13 (a lookup costs ~15 instructions, a call ~63; 2^12 stays
 * well within a core's second-level cache, 1 MB here). 2^ISM_TRIG_CACHE_SMALL_BITS for
 * the others (nothing looks there unless the workspace evaluates another tape): filling 2^13
 * entries cost the sphere at E = 0.0141, 2.86M instructions in all, 9.5% more. Every entry
 * starts as the pair of +0.0, which is what sincos gives there, so no entry is ever
 * invalid. */
#define ISM_TRIG_CACHE_BITS 12
#define ISM_TRIG_CACHE_SMALL_BITS 9

typedef struct ism_trig_entry {
    uint64_t key;
    double s, c;
} ism_trig_entry;

typedef struct ism_trig_cache {
    uint64_t mask; /* entries − 1 (a power of two, at most 2^ISM_TRIG_CACHE_BITS) */
    ism_trig_entry e[];
} ism_trig_cache;

/* The bytes of a cache of 2^bits entries. */
static inline size_t ism_trig_cache_size(unsigned bits)
{
    return sizeof(ism_trig_cache) + ((size_t)1 << bits) * sizeof(ism_trig_entry);
}

static inline void ism_trig_cache_init(ism_trig_cache *m, unsigned bits)
{
    m->mask = ((uint64_t)1 << bits) - 1;
    for (uint64_t i = 0; i <= m->mask; i++)
        m->e[i] = (ism_trig_entry){0, 0.0, 1.0}; /* sincos(+0.0) */
}

static inline void ism_trig_pair(ism_trig_cache *m, double u, double *s, double *c)
{
    uint64_t key;
    memcpy(&key, &u, sizeof key);
    ism_trig_entry *e =
        &m->e[((key * 0x9e3779b97f4a7c15ull) >> (64 - ISM_TRIG_CACHE_BITS)) & m->mask];
    if (e->key != key) {
        sincos(u, &e->s, &e->c);
        e->key = key;
    }
    *s = e->s;
    *c = e->c;
}

#endif
