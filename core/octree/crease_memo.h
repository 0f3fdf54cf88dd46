/* crease_memo.h — a thread's memo of mixed edges' crease points (crease_split.c's
 * crease_point) for one max_error round, its octree build's and then its polygonisation's:
 * the point, its gradient and flags, and what the edge's whole-or-cut verdict and Newton's
 * success were, keyed by the edge's two ends (in the one order crease_point takes them) and
 * its two labels (in increasing order). Within one max_error round (polygonise.c's
 * one_round: a thread's memo serves its octree build, then its polygonisation, and goes) a
 * crease point is a pure function of those while the sampler evaluates f itself
 * (s->tape == s->memo_tape == f: always in the polygonisation, whose leaves' local
 * shortened tapes give f's branches bit for bit; in the build only at nodes whose tape
 * intervals left unshortened, since a shortened node tape holds f only inside the node and
 * Newton may step out), its wedge_edges_below, fold_below and crease_pieces fixed for the
 * round. So a hit returns exactly what a recomputation would: the memo only saves time,
 * never changes the mesh. How much it saves depends on which edges a thread met before (the
 * memo is the thread's own, and chunks land on threads as they come), so the evaluation
 * counts --stats shows (n_point, n_gradient) and `hits` vary with the thread count and
 * scheduling, as the sampler's label memo already made them vary; the mesh does not (no
 * test compares those counts across thread counts). The leaves beside an edge of a face
 * both cut it, a leaf's triangles beside one mixed edge ask for its point twice, and the
 * build's error test cuts the polygons the leaf cuts again (measured, gyroid-ball
 * E = 0.0109 at depth 10: 5,644 crease points asked for, 2,203 distinct edges; 3,138 asked
 * by the build, 1,868 distinct, 607 of the polygonisation's 942 among them).
 * Direct-mapped: a collision simply overwrites. */
#ifndef ISM_CREASE_MEMO_H
#define ISM_CREASE_MEMO_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/eval.h"
#include "core/octree/cell_types.h"
#include "core/util/parallel.h"

/* 1,024 entries of 128 bytes, 128 KB a thread: gyroid-ball E = 0.0109 at depth 10 on one
 * thread finds 2,931 of its 3,441 repeated edges (a repeat comes a median 5 edges after
 * the first ask, within its leaf; 10% come 1,852 or more later, from the neighbour on the
 * far side of a chunk's row); 512 found 2,665, 4,096 3,268. In the whole run (callgrind,
 * build and polygonisation sharing it) 4,096 entries saved 0.3M more of 813M instructions:
 * not worth four times the memory. */
#define ISM_CREASE_MEMO_BITS 10

/* A mixed edge as the memos key it (this one, and crease_split.c's chord memo): its two
 * ends in one order whichever way it was walked, its two labels lo < hi; compared bit for
 * bit, so -0 against +0 or a NaN end can only miss. */
typedef struct ism_edge_key {
    double p[3], q[3]; /* the ends, p before q (first differing coordinate smaller) */
    ism_piece lo, hi;  /* the labels, lo < hi; lo == hi: no edge (a zeroed entry) */
} ism_edge_key;

_Static_assert(sizeof(ism_edge_key) == 64, "no padding: ism_edge_key_same compares bytes");

/* *k: edge a-b (either order) with labels lo < hi. */
void ism_edge_key_set(ism_edge_key *k, const double a[3], const double b[3], ism_piece lo,
                      ism_piece hi);

/* Do a and b name the same edge, bit for bit (an empty key names none)? */
bool ism_edge_key_same(const ism_edge_key *a, const ism_edge_key *b);

typedef struct ism_crease_entry {
    ism_edge_key k;      /* the edge (crease_point's ends and ordered labels) */
    ism_fpoint x;        /* the crease point as crease_point returned it */
    int32_t whole;       /* crease_point's *whole */
    bool found;          /* crease_point's result */
} ism_crease_entry;

_Static_assert(sizeof(ism_crease_entry) == 128, "ISM_CREASE_MEMO_BITS's comment gives 128 bytes");

typedef struct ism_crease_memo {
    ism_crease_entry e[(size_t)1 << ISM_CREASE_MEMO_BITS];
    uint64_t hits; /* lookups answered (for tests and measurements) */
} ism_crease_memo;

/* n empty memos (one a thread), or NULL when out of memory; zeroed on pool's threads, what
 * that cost added to *cost (zeroed.h: a NULL pool zeroes on the calling thread, a NULL cost
 * counts nothing); ism_crease_memo_free releases all n. */
ism_crease_memo *ism_crease_memo_new(ism_pool *pool, int n, ism_par_cost *cost);
void ism_crease_memo_free(ism_crease_memo *m);

/* The slot of edge k (by its ends; the entry holds k when ism_edge_key_same(&slot->k, k)). */
ism_crease_entry *ism_crease_memo_slot(ism_crease_memo *m, const ism_edge_key *k);

#endif
