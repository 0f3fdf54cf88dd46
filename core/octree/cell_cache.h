/* cell_cache.h — per-thread memo of what neighbouring nodes compute again and again: f and
 * ∇f at lattice points, and the roots of lattice segments. Both are pure functions of their
 * lattice coordinates, so a hit returns exactly what a recomputation would: the cache only
 * saves time, never changes the mesh. Direct-mapped: a collision simply overwrites. The
 * octree build memoises node corners through the same lookup (ism_point_memo). */
#ifndef ISM_CELL_CACHE_H
#define ISM_CELL_CACHE_H

#include <stdbool.h>
#include <stdint.h>
#include "core/octree/edge_roots.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"

#define ISM_POINT_CACHE_BITS 15
#define ISM_SEGMENT_CACHE_BITS 14

typedef struct ism_point_entry {
    uint64_t key; /* 0: empty (lattice keys are stored + 1) */
    double f, g[3];
} ism_point_entry;

typedef struct ism_segment_entry {
    uint64_t a, b; /* lattice keys of the end points (+1), 0: empty */
    ism_seg_roots roots;
} ism_segment_entry;

typedef struct ism_cell_cache {
    ism_point_entry *points;
    ism_segment_entry *segments;
} ism_cell_cache;

bool ism_cell_cache_init(ism_cell_cache *c);
void ism_cell_cache_free(ism_cell_cache *c);

/* The entry of lattice point ip in a direct-mapped table of 2^bits point entries. */
static inline ism_point_entry *ism_point_slot(ism_point_entry *table, int bits,
                                              const int32_t ip[3])
{
    return &table[ism_cache_mix(ism_lattice_key(ip)) & (((uint64_t)1 << bits) - 1)];
}

/* f and ∇f at lattice point ip (world position p): from the table, or computed into it. */
static inline const ism_point_entry *ism_point_memo(ism_point_entry *table, int bits,
                                                    const int32_t ip[3], const double p[3],
                                                    ism_sampler *s)
{
    uint64_t key = ism_lattice_key(ip);
    ism_point_entry *e = ism_point_slot(table, bits, ip);
    if (e->key != key) {
        e->key = key;
        e->f = ism_sample_grad(s, p, e->g);
    }
    return e;
}

#endif
