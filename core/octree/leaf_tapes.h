/* leaf_tapes.h — the table of the leaves' shortened tapes while an octree is built (see
 * octree.h, ism_leaf_tape): every distinct tape once, numbered from 1, shared by the
 * build's threads. A tape is found by a hash of its code: first in the asking thread's own
 * cache (no lock, no shared write), then in the shared index under the table's lock, where
 * a new tape is added while the limits of octree.h allow. */
#ifndef ISM_LEAF_TAPES_H
#define ISM_LEAF_TAPES_H

#include <pthread.h>
#include <stdbool.h>
#include <stdint.h>
#include "core/expr/tape.h"
#include "core/octree/octree.h"

/* Entries of a thread's cache (direct-mapped by hash): the leaves of one subtree share a
 * few dozen tapes, so the lock is taken about once per tape and thread. */
#define ISM_LEAF_TAPES_CACHE 256

typedef struct ism_leaf_tape_hit {
    uint64_t hash;
    const ism_tape *tape; /* the table's copy (never changes while the table lives) */
    unsigned number;
} ism_leaf_tape_hit;

typedef struct ism_leaf_tapes_cache {
    ism_leaf_tape_hit e[ISM_LEAF_TAPES_CACHE];
} ism_leaf_tapes_cache; /* all zero: empty */

/* A slot of the shared index: tape number k (0: free) and the top half of its hash. */
typedef struct ism_leaf_tape_slot {
    uint32_t number, tag;
} ism_leaf_tape_slot;

typedef struct ism_leaf_tapes {
    pthread_mutex_t lock; /* held for every field below */
    ism_tape **v;         /* tape number k is v[k - 1] */
    size_t n, cap;
    ism_leaf_tape_slot *index; /* open addressing by hash */
    size_t index_cap;     /* a power of two, at least twice n */
    size_t bytes;         /* the code the tapes hold (ISM_OCTREE_TAPE_BYTES at most) */
    size_t max_n;         /* tapes it holds at most: ISM_OCTREE_TAPES (set by init; a table
                             of a task's own may lower it, octree_build.h level_tapes_max) */
} ism_leaf_tapes;

/* An empty table, or, with previous, a copy of previous's tapes under the same numbers (so
 * that leaves taken over from it keep theirs). False when out of memory. */
bool ism_leaf_tapes_init(ism_leaf_tapes *lt, const ism_octree *previous);

/* The number of a tape equal to t (instruction by instruction), added when new; 0 when a
 * limit of octree.h is reached or out of memory (the leaf then evaluates f). cache: the
 * calling thread's own (zeroed before its first use). */
unsigned ism_leaf_tapes_number(ism_leaf_tapes *lt, ism_leaf_tapes_cache *cache,
                               const ism_tape *t);

/* Are a and b the same tape, instruction by instruction (the table's equality)? */
bool ism_leaf_tapes_same(const ism_tape *a, const ism_tape *b);

/* Hands the tapes to tree (tree->tapes, tree->ntapes) and leaves lt empty. */
void ism_leaf_tapes_give(ism_leaf_tapes *lt, ism_octree *tree);

void ism_leaf_tapes_free(ism_leaf_tapes *lt);

#endif
