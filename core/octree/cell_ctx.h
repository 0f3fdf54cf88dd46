/* cell_ctx.h — the per-thread context of the polygonisation of plotting nodes: the sampler,
 * the octree and its break points, the root parameters, and scratch arrays reused from node
 * to node. Filled by polygonise.c, used by cell.c and face_lines.c, released by
 * ism_cell_ctx_free (cell.h). */
#ifndef ISM_CELL_CTX_H
#define ISM_CELL_CTX_H

#include <stddef.h>
#include <stdbool.h>
#include "core/octree/breaks.h"
#include "core/octree/cell_cache.h"
#include "core/octree/cell_types.h"
#include "core/octree/edge_roots.h"
#include "core/octree/octree.h"
#include "core/octree/sampler.h"

struct ism_node_tile; /* face_lines.h */

typedef struct ism_cell_ctx {
    ism_sampler s;
    const ism_octree *tree;
    const int32_t *parent;    /* each node's parent in tree (ism_octree_parents) */
    ism_nb_memo nbs;          /* the last parent's neighbours (octree.h; zeroed: empty) */
    const ism_breaks *breaks;
    const struct ism_root_table *found; /* the roots the octree build searched on node edges
                                           (root_table.h), or NULL */
    ism_root_params roots;
    const ism_point_entry *corners; /* this thread's memo of the octree build's corner values
                                       (octree_build.h corner_memos), asked before f is
                                       evaluated at a lattice point; NULL: none */
    double stitch_tol;        /* two roots closer than this × segment length are one */
    double max_error;         /* > 0: polygons may be fanned from a corner within this
                                 distance of f = 0 (triangulate.h); 0: from their centre
                                 (no bound, or a singular locus is known: options.quiet) */
    bool cut_creases;         /* a polygon whose corners lie on both sides of f's min/max
                                 crease is cut along it, one polygon per side
                                 (crease_split.h ism_crease_cut_loop): under a bound where no
                                 locus is known; where one is, only while polygonise.c's
                                 one_leaf polygonises a leaf again whose fans, split along
                                 the crease, left it unresolved (the sides then fanned from
                                 their centres: max_error 0) */
    bool walk_every_tile;     /* the tile memos (cell_cache.h) are neither asked nor filled,
                                 and no tile is taken as quiet by its corners alone (each
                                 such answer is checked against the tile's walk instead:
                                 corner_checks, corner_mismatches) (poly_options.h's
                                 walk_every_tile: the reference the tests compare memo hits
                                 and that shortcut with) */
    /* scratch, reused from node to node */
    ism_bpoint *bp;
    size_t nbp, cap_bp;
    ism_fevent *ev;
    size_t nev, cap_ev;
    struct ism_walk_gap *gap; /* per boundary point: its segment's memo slot, the sign after
                                 it (face_lines.c) */
    size_t cap_gap;
    ism_flines lines;
    ism_loops loops;
    ism_cell_cache cache;     /* must be initialised (ism_cell_cache_init) */
    bool zero_tile;           /* set by ism_tile_lines: f vanishes on the whole tile */
    bool unregistered;        /* set by ism_tile_lines when a tile's side met a lattice point
                                 the registry lacks (it then returns false: ISM_POLY_INTERNAL,
                                 not out of memory) */
    struct ism_node_tile *tiles; /* the current node's tiles, face by face */
    size_t ntiles, cap_tiles;
    ism_tile *zero;           /* the current node's tiles lying in f = 0 */
    size_t nzero, cap_zero;
    ism_cell_stats stats;
    ism_tile_counts walk;     /* the counters the current tile's walk moved (face_lines.c),
                                 added to stats when it ends */
    /* the tile memos' hits, kept out of stats (a memo entry copies stats, and a later round's
     * copied leaf adds its stats again): work saved, not a fact of the mesh */
    uint64_t quiet_skips;     /* tiles found in the quiet memo: not walked again */
    uint64_t tile_replays;    /* tiles whose lines were copied from the crossed-tile memo */
    uint64_t corner_quiets;   /* tiles quiet by their corners alone: their sides not walked */
    uint64_t corner_checks;   /* under walk_every_tile: tiles quiet by their corners alone,
                                 walked all the same (face_lines.c check_by_corners) */
    uint64_t corner_mismatches; /* ... and tiles where that answer and the walk differ */
    uint64_t corner_values;   /* lattice points whose f and ∇f came from `corners` */
} ism_cell_ctx;

#endif
