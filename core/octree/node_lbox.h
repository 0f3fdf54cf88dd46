/* node_lbox.h — a node's closed box in lattice steps (lo[a] .. hi[a]), whether two such
 * boxes touch (share at least a point: a face, an edge or a corner) and whether touching ones
 * share more than a corner. The leaf memo strikes out the leaves sharing an edge segment or a
 * face with a split one (leaf_memo.h: a corner alone is a lattice point before and after);
 * test_breaks_near.c checks ism_breaks_near's grid against ism_node_lboxes_touch. */
#ifndef ISM_NODE_LBOX_H
#define ISM_NODE_LBOX_H

#include "core/octree/octree.h"

#include <stdbool.h>
#include <stdint.h>

typedef struct ism_node_lbox {
    int32_t lo[3], hi[3];
} ism_node_lbox;

static inline ism_node_lbox ism_node_lbox_of(const ism_octree *t, const ism_node *nd)
{
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    ism_node_lbox b;
    for (int a = 0; a < 3; a++) {
        b.lo[a] = nd->org[a];
        b.hi[a] = nd->org[a] + s;
    }
    return b;
}

static inline bool ism_node_lboxes_touch(const ism_node_lbox *x, const ism_node_lbox *y)
{
    for (int a = 0; a < 3; a++)
        if (x->hi[a] < y->lo[a] || y->hi[a] < x->lo[a])
            return false;
    return true;
}

/* Do touching boxes x and y share more than a corner: a segment of an edge or more (on some
 * axis their ranges overlap in more than a point)? */
static inline bool ism_node_lboxes_share_segment(const ism_node_lbox *x, const ism_node_lbox *y)
{
    for (int a = 0; a < 3; a++) {
        int32_t lo = x->lo[a] > y->lo[a] ? x->lo[a] : y->lo[a];
        int32_t hi = x->hi[a] < y->hi[a] ? x->hi[a] : y->hi[a];
        if (hi > lo)
            return true;
    }
    return false;
}

#endif
