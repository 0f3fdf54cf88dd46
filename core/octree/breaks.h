/* breaks.h — where lattice lines are cut by the corners of the plotting-candidate leaves.
 * A node's edge is processed as the sequence of the smallest segments that any leaf sharing
 * that line uses there, so every node touching an edge finds the same roots on it, bit for
 * bit, however coarse or fine each node is: the mechanism behind crack-free output. */
#ifndef ISM_BREAKS_H
#define ISM_BREAKS_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/octree.h"
#include "core/util/parallel.h"

/* A registered lattice point: a corner of some non-empty leaf. */
typedef struct ism_break_point {
    uint64_t key;     /* ism_lattice_key of the point; 0: an empty slot */
    int32_t next[3];  /* along each axis, the coordinate of the next registered point on the
                         lattice line through this one (ISM_BREAK_NONE: none) */
} ism_break_point;

#define ISM_BREAK_NONE INT32_MAX

typedef struct ism_breaks {
    ism_break_point *slots; /* open addressing by ism_cache_mix(key), linear probing */
    size_t mask;            /* slot count - 1 (a power of two) */
    size_t n;               /* registered points */
} ism_breaks;

/* Below this many corners (8 a node) ism_breaks_build works in one block, whatever the pool
 * (a loop's threads cost more than they save); at or above it, one block per thread. */
#define ISM_BREAKS_MIN_PARALLEL_CORNERS (1u << 15)

/* Registers the corners of every non-empty leaf (with take: of those whose take[node] is
 * set), each with its successor on the three lattice lines through it, working on the
 * threads of pool (NULL: the calling thread alone; what their loops cost is added to *cost
 * when not NULL); every query answers the same for any thread count. False when out of
 * memory. */
bool ism_breaks_build(ism_breaks *b, const ism_octree *t, const uint8_t *take, ism_pool *pool,
                      ism_par_cost *cost);

void ism_breaks_free(ism_breaks *b);

/* The first slot probed for the point whose key's ism_cache_mix is `hash`. */
static inline size_t ism_breaks_index(const ism_breaks *b, uint64_t hash)
{
    return (size_t)(hash & b->mask);
}

/* The registered point of lattice key `key`, whose ism_cache_mix is `hash` (a caller that
 * looks the point up in other tables too hashes it once), or NULL. */
static inline const ism_break_point *ism_breaks_find_hashed(const ism_breaks *b, uint64_t key,
                                                            uint64_t hash)
{
    for (size_t s = ism_breaks_index(b, hash);; s = (s + 1) & b->mask) {
        const ism_break_point *e = &b->slots[s];
        if (e->key == key)
            return e;
        if (!e->key)
            return NULL;
    }
}

/* The registered point p, or NULL. */
static inline const ism_break_point *ism_breaks_find(const ism_breaks *b, const int32_t p[3])
{
    uint64_t key = ism_lattice_key(p);
    return ism_breaks_find_hashed(b, key, ism_cache_mix(key));
}

/* That first slot itself (to prefetch). */
static inline const ism_break_point *ism_breaks_slot(const ism_breaks *b, uint64_t hash)
{
    return &b->slots[ism_breaks_index(b, hash)];
}

/* Asks the memory for p's slot (a query follows soon); breaks.c's fill_block calls it (the
 * cells hash a point once and prefetch ism_breaks_slot themselves). Always inlined: as a
 * plain static inline, GCC 12.2 at -O2 once left no prefetch instruction in its callers
 * (objdump); what drops it depends on the caller. */
static inline __attribute__((always_inline)) void ism_breaks_prefetch(const ism_breaks *b,
                                                                      const int32_t p[3])
{
    __builtin_prefetch(ism_breaks_slot(b, ism_cache_mix(ism_lattice_key(p))));
}

#endif
