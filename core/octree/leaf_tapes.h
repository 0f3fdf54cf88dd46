/* leaf_tapes.h — the table of the leaves' shortened tapes while an octree is built (see
 * octree.h, ism_leaf_tape): every distinct tape once, numbered from 1, shared by the
 * build's threads (lookups without a lock, additions under one). */
#ifndef ISM_LEAF_TAPES_H
#define ISM_LEAF_TAPES_H

#include <pthread.h>
#include <stdatomic.h>
#include <stdbool.h>
#include "core/expr/tape.h"
#include "core/octree/octree.h"

typedef struct ism_leaf_tapes {
    ism_tape *v[ISM_OCTREE_TAPES];
    atomic_size_t n;        /* entries v[0..n) are complete and never change */
    pthread_mutex_t lock;   /* held to add one */
} ism_leaf_tapes;

/* An empty table, or, with previous, a copy of previous's tapes under the same numbers (so
 * that leaves taken over from it keep theirs). False when out of memory. */
bool ism_leaf_tapes_init(ism_leaf_tapes *lt, const ism_octree *previous);

/* The number of a tape equal to t (instruction by instruction), added when new; 0 when the
 * table is full or out of memory (the leaf then evaluates f). */
unsigned ism_leaf_tapes_number(ism_leaf_tapes *lt, const ism_tape *t);

/* Hands the tapes to tree (tree->tapes, tree->ntapes) and leaves lt empty. */
void ism_leaf_tapes_give(ism_leaf_tapes *lt, ism_octree *tree);

void ism_leaf_tapes_free(ism_leaf_tapes *lt);

#endif
