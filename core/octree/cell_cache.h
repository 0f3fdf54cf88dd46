/* cell_cache.h — per-thread memo of what neighbouring nodes compute again and again: f and
 * ∇f at lattice points (with the points' successors on their lattice lines, copied from the
 * break-point registry, so that walking a tile's side and sampling it cost one lookup a
 * point), the roots of lattice segments, and the lines of tiles walked once. Within one
 * max_error round all are pure functions of their lattice coordinates (quiet and crossed
 * tiles also read the round's break points, so they are cleared between rounds:
 * ism_cell_cache_next_round), so a hit returns exactly what a recomputation would: the cache
 * only saves time, never changes the mesh. Direct-mapped: a collision
 * simply overwrites. The octree build memoises node corners through a lookup of the same
 * kind (ism_point_memo), and what its flatness test finds on node edges and at corners
 * (ism_node_memo). */
#ifndef ISM_CELL_CACHE_H
#define ISM_CELL_CACHE_H

#include <stdbool.h>
#include <stdint.h>
#include <string.h>
#include "core/octree/cell_types.h"
#include "core/octree/edge_roots.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"
#include "core/util/parallel.h"

#define ISM_POINT_CACHE_BITS 15
#define ISM_SEGMENT_CACHE_BITS 14
#define ISM_QUIET_CACHE_BITS 14 /* 256 KB: half the second-level cache */

typedef struct ism_point_entry {
    uint64_t key; /* 0: empty (lattice keys are never 0) in the tables cleared to 0; the
                     dual's memo (dual_tree.h worker.points) is not cleared: there a slot's
                     bit says it holds a point, and an unmarked slot's key is garbage */
    double f, g[3];
} ism_point_entry;

/* The octree build's memo of f and ∇f at node corners (ism_point_memo): 2^16 entries of 40
 * bytes, 2.5 MB a thread. Its values are pure, so the polygoniser keeps one per thread from
 * the build through its cells and on over the max_error rounds (octree_build.h's
 * corner_memos; under ism_poly_options.fresh_rounds it is freed after each round and
 * allocated again for the next) and the cells of a round ask their thread's before they
 * evaluate a lattice point of their own (face_lines.c lattice_entry): most points a cell
 * walks are corners the build evaluated in its flatness tests. Memory: held until the last
 * round's cells are done, 2.5 MB × threads (160 MB at 64), and like the cells' own caches
 * above (about 6 MB a thread) not counted against ism_poly_options.max_memory, which sizes
 * only the nodes, roots and triangles (polygonise.c). */
#define ISM_CORNER_MEMO_BITS 16

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

/* A tile some line of f = 0 crosses, as its first walk left it: the lines it appended and
 * what it added to each counter of ism_cell_stats. The walk is a function of the tile alone
 * (face_lines.c: its lattice points, its sides' break points and roots, f on the tile, which
 * both nodes' shortened tapes give bit for bit on their shared closed face), so the second
 * node that shares the tile copies the first one's lines instead of walking it again. */
#define ISM_TILE_MEMO_BITS 12 /* 4,096 entries of 288 bytes, 1.2 MB a thread: the two nodes of
                                 a face are polygonised close together (depth first), and the
                                 second walk of a crossed tile then mostly hits */
#define ISM_TILE_MEMO_LINES 2 /* one curve across the tile, or its chord lifted into two lines
                                 (face_flat.h): nearly every crossed tile; more are walked again */
/* The counters of ism_cell_stats a tile's walk moves (face_lines.c), counted apart during a
 * walk and then added to the thread's: what a memo entry adds again on a hit. A walk adds
 * at most a few to each (its lines are bounded by MAX_CROSS). */
typedef struct ism_tile_counts {
    uint32_t crossed_faces, lifted_chords, open_chains, singular_points, double_lines;
} ism_tile_counts;

typedef struct ism_tile_memo {
    ism_quiet_tile key;    /* the tile (quiet-tile key; where = 0: empty) */
    size_t nlines;
    ism_tile_counts counted; /* what the walk added to the counters */
    ism_fline lines[ISM_TILE_MEMO_LINES];
} ism_tile_memo;
/* The size ISM_TILE_MEMO_BITS's comment states. */
_Static_assert(sizeof(ism_tile_memo) == 288, "ISM_TILE_MEMO_BITS's comment gives 288 bytes");

typedef struct ism_cell_cache {
    ism_lattice_entry *points;
    ism_segment_entry *segments;
    ism_quiet_tile *quiet;
    ism_tile_memo *tiles;
    uint32_t round;  /* the current max_error round (from 1) */
} ism_cell_cache;

/* A thread's empty memo, zeroed on pool's threads (what that cost added to *cost when not
 * NULL). False when out of memory (free what was made with ism_cell_cache_free). */
bool ism_cell_cache_init(ism_cell_cache *c, ism_pool *pool, ism_par_cost *cost);
void ism_cell_cache_free(ism_cell_cache *c);

/* The memo kept for another max_error round of the same f and lattice: f, ∇f and segment
 * roots stay (pure), the points' registry successors are read again on their first use
 * (the leaves, so the break points, changed) and the quiet and crossed tiles are forgotten
 * (a tile's sides may have gained break points). */
void ism_cell_cache_next_round(ism_cell_cache *c);

/* The octree build's memo of single roots on node edges (cell_error.c: regula falsi between
 * two corners of opposite sign). Up to four nodes of one level share an edge, and each
 * tested node measures its would-be triangles from its edges' roots: on Barth's sextic at
 * E = 3e-3 that was 190,088 root searches of ~10 evaluations for 44,128 nodes. The root is
 * a pure function of the edge's lattice points — their coordinates, f there (the corner
 * memo) and f along the edge, which a node's shortened tape gives bit for bit inside its
 * closed box (sampler.h) — so a hit returns what the search would. 2^13 entries of 24
 * bytes a thread: a depth-first subtree's neighbours test their shared edges close in
 * time. */
#define ISM_ROOT_MEMO_BITS 13

typedef struct ism_root_entry {
    uint64_t a, b; /* lattice keys of the edge's first and second corner (+1), 0: empty */
    double t;      /* the root's parameter from a to b */
} ism_root_entry;

/* The slot of the edge from key a to key b in a direct-mapped table of 2^bits edge entries. */
static inline size_t ism_edge_slot(uint64_t a, uint64_t b, int bits)
{
    return (size_t)(ism_cache_mix(a * 0x9e3779b97f4a7c15ull ^ b) & (((uint64_t)1 << bits) - 1));
}

static inline ism_root_entry *ism_root_slot(ism_root_entry *table, uint64_t a, uint64_t b)
{
    return &table[ism_edge_slot(a, b, ISM_ROOT_MEMO_BITS)];
}

/* ... and of root pairs on edges whose ends share a sign (ism_double_root_search): where a
 * piece found at a CSG kink may be a sliver (octree_build.c edges_see) and where the dual
 * mesher asks an edge for a hidden pair (dual_classify.c edge_root_pair). Up to four nodes of a
 * level share an edge, and the answer is a function of the edge's two lattice points and
 * of f along it, which every node's shortened tape gives bit for bit inside its closed box
 * (sampler.h): a hit answers what the search would. 2^12 entries of 32 bytes a thread. */
#define ISM_PAIR_MEMO_BITS 12

typedef struct ism_pair_entry {
    uint64_t a, b; /* lattice keys of the edge's first and second corner (+1), 0: empty */
    double t;      /* the search's point between the two roots, or its tangent point */
    int32_t found; /* the search's answer: 0, 1 or 2 */
} ism_pair_entry;

static inline ism_pair_entry *ism_pair_slot(ism_pair_entry *table, uint64_t a, uint64_t b)
{
    return &table[ism_edge_slot(a, b, ISM_PAIR_MEMO_BITS)];
}

/* ... and of the branch of f's top min/max at node corners (plot_test.c's crease cells:
 * under max_error every node whose tape keeps that min/max labels its 8 corners, 503,096
 * labels for 109,632 nodes on Barth's sextic at 3e-3, while a lattice point is a corner of
 * up to 8 nodes of a level and of nodes of every level below). Only labels of nodes whose
 * shortened tape keeps the top min/max are asked for, and those give f's own label bit for
 * bit (crease_split.h): a pure function of the lattice point. */
/* 2^13 entries of 40 bytes: 320 KB a build thread (was 128 KB at 16 bytes an entry before
 * the gradient joined the label, 5394f96: the gradient a crease cell asks for at corners on
 * both branches is kept beside the label it needs, so one table holds both). */
#define ISM_LABEL_MEMO_BITS 13

typedef struct ism_label_entry {
    uint64_t key;  /* lattice key of the point (+1), 0: empty */
    int32_t label; /* 0 or 1: ism_crease_branch's answer (never -1: not kept) */
    bool has_g;    /* g holds ism_crease_branch's gradient there (crease_cell asks for it at
                      the corners of nodes on both branches: Barth's sextic at 1e-2, 100,864
                      times, 76M instructions) */
    double g[3];
} ism_label_entry;
_Static_assert(sizeof(ism_label_entry) == 40, "ISM_LABEL_MEMO_BITS's comment gives 40 bytes");

/* A build thread's memos (tables of 2^ISM_ROOT_MEMO_BITS, 2^ISM_LABEL_MEMO_BITS and
 * 2^ISM_PAIR_MEMO_BITS entries; all NULL on the scalar reference path), and beside them,
 * not a memo, its append-only log of the roots searched for the cells (root_table.h): NULL
 * on that path and whenever the build hands no roots on (octree_build.h's roots). */
typedef struct ism_node_memo {
    ism_root_entry *roots;
    ism_label_entry *labels;
    ism_pair_entry *pairs;
    struct ism_root_log *log; /* every root searched is appended here too (root_table.h), or
                                 NULL */
} ism_node_memo;

static inline ism_label_entry *ism_label_slot(ism_label_entry *table, uint64_t key)
{
    return &table[ism_cache_mix(key) & (((uint64_t)1 << ISM_LABEL_MEMO_BITS) - 1)];
}

/* The slot of the lattice point whose key's ism_cache_mix is `hash` in a direct-mapped table
 * of 2^bits point entries. */
static inline size_t ism_point_hash_index(int bits, uint64_t hash)
{
    return (size_t)(hash & (((uint64_t)1 << bits) - 1));
}

/* The slot of lattice point ip in such a table. */
static inline size_t ism_point_index(int bits, const int32_t ip[3])
{
    return ism_point_hash_index(bits, ism_cache_mix(ism_lattice_key(ip)));
}

static inline ism_point_entry *ism_point_slot(ism_point_entry *table, int bits,
                                              const int32_t ip[3])
{
    return &table[ism_point_index(bits, ip)];
}

/* The entry of the lattice point of key `key` (ism_cache_mix(key) = hash: a caller that
 * looks the point up in other tables too hashes it once) when the table holds it, else NULL. */
static inline const ism_point_entry *ism_point_find_hashed(const ism_point_entry *table,
                                                           int bits, uint64_t key,
                                                           uint64_t hash)
{
    const ism_point_entry *e = &table[ism_point_hash_index(bits, hash)];
    return e->key == key ? e : NULL;
}

/* The entry of lattice point ip when the table holds it, else NULL. */
static inline const ism_point_entry *ism_point_find(const ism_point_entry *table, int bits,
                                                    const int32_t ip[3])
{
    uint64_t key = ism_lattice_key(ip);
    return ism_point_find_hashed(table, bits, key, ism_cache_mix(key));
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

/* At most this many points in one ism_point_memo_many call: a dual split's 27 (a node's 8
 * corners and the 19 points its children add). */
#define ISM_POINT_MEMO_MANY 27
/* ism_point_memo_many evaluates its misses in one ism_sample_grad_batch from this many on,
 * one at a time below (the batched gradient's fixed cost per call loses there: Klein bottle's
 * tape through the sampler, callgrind, instructions a point at 1 / 2 / 3 / 4 points, one at a
 * time 624 / 612 / 608 / 606, batched 1,665 / 850 / 579 / 442; main 95b3f52,
 * /work/wt/notes/mendC25_mb.c). */
#define ISM_POINT_BATCH_MIN 3

/* f and ∇f at lattice points ip[0..n) (world positions p, n <= ISM_POINT_MEMO_MANY) into f
 * and g, their lattice keys into key, through the table as ism_point_memo point by point:
 * looked up in order, a miss taking its slot at once (a later point mapped to that slot misses
 * too), so the table ends as one point at a time leaves it, with the same evaluations counted;
 * the misses are evaluated together (ism_sample_grad_batch: bit for bit ism_sample_grad's) and
 * stored where their slot still holds them. Inline: a node's corners ask it once per node
 * (out of line, with n unknown, it cost the torus's dual mesh at E 3e-3 0.7% more). */
static inline void ism_point_memo_many(ism_point_entry *table, int bits, const int32_t (*ip)[3],
                                       const double (*p)[3], size_t n, ism_sampler *s,
                                       double *f, double (*g)[3], uint64_t *key)
{
    ism_point_entry *slot[ISM_POINT_MEMO_MANY];
    size_t at[ISM_POINT_MEMO_MANY], nm = 0;
    for (size_t j = 0; j < n; j++) { /* the slots asked for at once: their misses overlap */
        key[j] = ism_lattice_key(ip[j]);
        slot[j] = &table[ism_cache_mix(key[j]) & (((uint64_t)1 << bits) - 1)];
        __builtin_prefetch(slot[j], 1);
    }
    for (size_t j = 0; j < n; j++) {
        ism_point_entry *e = slot[j];
        if (e->key == key[j]) {
            f[j] = e->f;
            memcpy(g[j], e->g, sizeof g[j]);
            continue;
        }
        e->key = key[j];
        at[nm++] = j;
    }
    if (nm >= ISM_POINT_BATCH_MIN) {
        double mp[ISM_POINT_MEMO_MANY][3], mf[ISM_POINT_MEMO_MANY], mg[ISM_POINT_MEMO_MANY][3];
        for (size_t k = 0; k < nm; k++)
            memcpy(mp[k], p[at[k]], sizeof mp[k]);
        ism_sample_grad_batch(s, (const double (*)[3])mp, mf, mg, nm);
        for (size_t k = 0; k < nm; k++) {
            f[at[k]] = mf[k];
            memcpy(g[at[k]], mg[k], sizeof mg[k]);
        }
    } else {
        for (size_t k = 0; k < nm; k++)
            f[at[k]] = ism_sample_grad(s, p[at[k]], g[at[k]]);
    }
    for (size_t k = 0; k < nm; k++) {
        size_t j = at[k];
        if (slot[j]->key == key[j]) { /* not taken since by a later miss */
            slot[j]->f = f[j];
            memcpy(slot[j]->g, g[j], sizeof slot[j]->g);
        }
    }
}

#endif
