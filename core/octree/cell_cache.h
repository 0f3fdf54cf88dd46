/* cell_cache.h — per-thread memo of what neighbouring nodes compute again and again: f and
 * ∇f at lattice points (with the points' successors on their lattice lines, copied from the
 * break-point registry, so that walking a tile's side and sampling it cost one lookup a
 * point), and the roots of lattice segments. All are pure functions of their lattice
 * coordinates, so a hit returns exactly what a recomputation would: the cache only saves
 * time, never changes the mesh. Direct-mapped: a collision simply overwrites. The octree
 * build memoises node corners through a lookup of the same kind (ism_point_memo). */
#ifndef ISM_CELL_CACHE_H
#define ISM_CELL_CACHE_H

#include <stdbool.h>
#include <stdint.h>
#include "core/octree/edge_roots.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"
#include "core/util/parallel.h"

#define ISM_POINT_CACHE_BITS 15
#define ISM_SEGMENT_CACHE_BITS 14
#define ISM_QUIET_CACHE_BITS 14 /* 256 KB: half the second-level cache */

typedef struct ism_point_entry {
    uint64_t key; /* 0: empty (lattice keys are stored + 1) */
    double f, g[3];
} ism_point_entry;

/* A lattice point as the cell phase memoises it: one cache line. */
typedef struct ism_lattice_entry {
    _Alignas(64) uint64_t key; /* 0: empty (lattice keys are stored + 1) */
    double f, g[3], gn; /* f, ∇f and |∇f| */
    int32_t next[3]; /* the registry's successors (ism_break_point.next), or next[0] =
                        ISM_LATTICE_UNREGISTERED when the point is no break point */
    uint32_t round;  /* the max_error round whose registry next[] was read from */
} ism_lattice_entry;

#define ISM_LATTICE_UNREGISTERED INT32_MIN

typedef struct ism_segment_entry {
    uint64_t a, b; /* lattice keys of the end points (+1), 0: empty */
    ism_seg_roots roots;
} ism_segment_entry;

/* A tile on which no line of f = 0 starts (nothing crosses its boundary): both nodes that
 * share a face walk its tiles, and the second walk of a quiet one is skipped. */
typedef struct ism_quiet_tile {
    uint64_t where; /* axis, plane, u0 (0: empty) */
    uint64_t span;  /* v0, u1, v1 */
} ism_quiet_tile;

typedef struct ism_cell_cache {
    ism_lattice_entry *points;
    ism_segment_entry *segments;
    ism_quiet_tile *quiet;
    uint32_t round;  /* the current max_error round (from 1) */
} ism_cell_cache;

/* A thread's empty memo, zeroed on pool's threads (what that cost added to *cost when not
 * NULL). False when out of memory (free what was made with ism_cell_cache_free). */
bool ism_cell_cache_init(ism_cell_cache *c, ism_pool *pool, ism_par_cost *cost);
void ism_cell_cache_free(ism_cell_cache *c);

/* The memo kept for another max_error round of the same f and lattice: f, ∇f and segment
 * roots stay (pure), the points' registry successors are read again on their first use
 * (the leaves, so the break points, changed) and the quiet tiles are forgotten (a tile's
 * sides may have gained break points). */
void ism_cell_cache_next_round(ism_cell_cache *c);

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
