/* face_lines.h — the lines of f = 0 on one tile of a node's face (face_lines.c). */
#ifndef ISM_FACE_LINES_H
#define ISM_FACE_LINES_H

#include <stdbool.h>
#include "core/octree/cell_ctx.h"
#include "core/octree/cell_types.h"
#include "core/octree/octree.h"

/* Appends the line a-b of the given kind (enum ism_line_kind); false when out of memory. */
bool ism_flines_push(ism_flines *l, const ism_fpoint *a, const ism_fpoint *b, int kind);

/* Asks the memory for lattice point ip's memo entry and its break-point registry slot (which
 * a memo miss probes). Changes nothing. */
void ism_lattice_prefetch(ism_cell_ctx *cx, const int32_t ip[3]);

/* One tile of the current node's faces with its quiet-tile key and that key's hash, set
 * together by ism_node_tile_set where the tile is kept, and read by ism_tile_prefetch and
 * ism_tile_lines (the key and hash computed once a tile, not again at the walk). */
typedef struct ism_node_tile {
    ism_tile t;
    ism_quiet_tile key;
    uint64_t hash;
} ism_node_tile;

/* The tile as a quiet-tile memo entry (lattice coordinates take 20 bits, the axis 2). */
static inline ism_quiet_tile ism_quiet_key(const ism_tile *t)
{
    return (ism_quiet_tile){
        ((uint64_t)t->axis << 40 | (uint64_t)t->plane << 20 | (uint64_t)t->u0) + 1,
        (uint64_t)t->v0 << 40 | (uint64_t)t->u1 << 20 | (uint64_t)t->v1};
}

/* The tile's hash, which each tile table masks to its own size (a tile is quiet or crossed
 * in a round, never both, and the tables are apart: one hash serves both). The key's two
 * words are folded into one before the mixer as `where` times an odd constant plus `span`:
 * a plain sum would add u0 to v1 and the plane to u1, so tiles with those swapped would fold
 * alike, while an odd multiplier is a bijection on 64 bits that moves `where`'s fields off
 * the span's (any odd one does; 31 is small). A fold collision only costs a miss: each slot
 * compares the whole key. */
static inline uint64_t ism_tile_hash(const ism_quiet_tile *k)
{
    return ism_cache_mix(k->where * 31 + k->span);
}

/* Sets nt to tile t with its key and hash (inline: every tile of a node's faces is kept so). */
static inline void ism_node_tile_set(ism_node_tile *nt, const ism_tile *t)
{
    nt->t = *t;
    nt->key = ism_quiet_key(t);
    nt->hash = ism_tile_hash(&nt->key);
}

/* Asks the memory for what ism_tile_lines will read first about tile nt->t (its quiet-tile
 * memo slot, the first cache line of its crossed-tile memo slot, and with `corners` its
 * corners as ism_lattice_prefetch: a caller that asked for them already, as a node's own
 * corners, passes false): the node's tiles are prefetched together, so that these misses
 * overlap. Changes nothing. */
void ism_tile_prefetch(ism_cell_ctx *cx, const ism_node_tile *nt, bool corners);

/* Appends to cx->lines the lines of f = 0 on one tile nt->t (a face or part of a face, set
 * by ism_node_tile_set): walked, or copied from the thread's memo of tiles
 * walked in the round (cell_cache.h; unless cx->walk_every_tile). When f vanishes on the
 * whole tile (a plane of the surface lying in the lattice), sets cx->zero_tile, leaves cx->bp
 * holding its boundary and adds no lines. */
bool ism_tile_lines(ism_cell_ctx *cx, const ism_node_tile *nt);

#endif
