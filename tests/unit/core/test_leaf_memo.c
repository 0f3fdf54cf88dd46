/* test_leaf_memo.c — which leaves the next max_error round copies (ism_leaf_memo_match,
 * leaf_memo.h), asserted leaf by leaf on trees built by hand: the root split, seven of its
 * octants split again (leaves of level 2) and the eighth left a leaf of level 1; the next
 * tree is the same with one leaf split. The expected answer is derived from the lattice
 * boxes by brute force here (lo = org, hi = org + 2^(depth - level) on each axis): a leaf new
 * in the next tree, or one whose closed box meets the split leaf's in more than a point on
 * some axis (an edge segment or a face), is -1; every other leaf, corner-only neighbours
 * included, keeps its index among the old tree's leaves. Each case asserts it has leaves
 * touching the split one at a corner alone, along an edge alone and across a face; the small
 * leaf's split has the big leaf among its corner-only neighbours. Only lattice indices enter, so
 * the box's placement cannot matter. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "core/octree/leaf_memo.h"
#include "core/octree/octree.h"

#define DEPTH 6 /* lattice steps of a level-2 leaf: 16 */

static int32_t add(ism_octree *t, const int32_t org[3], int level)
{
    if (t->n == t->cap) {
        t->cap = t->cap ? 2 * t->cap : 16;
        t->nodes = realloc(t->nodes, t->cap * sizeof *t->nodes);
        cr_assert_not_null(t->nodes);
    }
    ism_node *nd = &t->nodes[t->n];
    memset(nd, 0, sizeof *nd);
    memcpy(nd->org, org, sizeof nd->org);
    nd->child = -1;
    nd->level = (uint8_t)level;
    nd->state = ISM_NODE_LEAF;
    return (int32_t)t->n++;
}

/* Leaf i becomes split: 8 leaves appended, child k's origin moved by half along axis a when
   bit a of k is set. */
static void split(ism_octree *t, int32_t i)
{
    int level = t->nodes[i].level + 1;
    int32_t half = (int32_t)1 << (DEPTH - level), org[3];
    int32_t first = (int32_t)t->n;
    for (int k = 0; k < 8; k++) {
        for (int a = 0; a < 3; a++)
            org[a] = t->nodes[i].org[a] + ((k >> a) & 1) * half;
        add(t, org, level);
    }
    t->nodes[i].state = ISM_NODE_SPLIT;
    t->nodes[i].child = first;
}

static void before_tree(ism_octree *t)
{
    memset(t, 0, sizeof *t);
    const double box[6] = {-1, -1, -1, 1, 1, 1};
    ism_grid_init(&t->grid, box, DEPTH);
    add(t, (int32_t[3]){0, 0, 0}, 0);
    split(t, 0);
    for (int k = 0; k < 7; k++)
        split(t, t->nodes[0].child + k);
}

/* On how many axes the closed boxes of nodes x and y overlap in more than a point, or -1
   when they do not touch. */
static int overlap_axes(const ism_node *x, const ism_node *y)
{
    int n = 0;
    for (int a = 0; a < 3; a++) {
        int32_t xlo = x->org[a], xhi = xlo + ((int32_t)1 << (DEPTH - x->level));
        int32_t ylo = y->org[a], yhi = ylo + ((int32_t)1 << (DEPTH - y->level));
        int32_t lo = xlo > ylo ? xlo : ylo, hi = xhi < yhi ? xhi : yhi;
        if (hi < lo)
            return -1;
        n += hi > lo;
    }
    return n;
}

/* The next tree splits node `which` of the old one (a leaf). Returns how many level-1 leaves
   touch it at a corner alone. */
static size_t check(int32_t which)
{
    ism_octree before, now;
    before_tree(&before);
    cr_assert_eq(before.nodes[which].state, ISM_NODE_LEAF);
    before_tree(&now);
    split(&now, which);
    const ism_node cut = before.nodes[which];

    size_t nleaves = 0;
    for (size_t i = 0; i < now.n; i++)
        nleaves += now.nodes[i].state == ISM_NODE_LEAF;
    int32_t *reuse = malloc(nleaves * sizeof *reuse);
    cr_assert_not_null(reuse);
    cr_assert(ism_leaf_memo_match(&before, &now, reuse));

    size_t leaf = 0, kinds[4] = {0}, sizes[3] = {0};
    int32_t old_index = 0; /* leaves of `before` so far, in node order */
    for (size_t i = 0; i < now.n; i++) {
        bool old = i < before.n, was_leaf = old && before.nodes[i].state == ISM_NODE_LEAF;
        if (now.nodes[i].state != ISM_NODE_LEAF) {
            old_index += was_leaf; /* the split one */
            continue;
        }
        const ism_node *nd = &now.nodes[i];
        int axes = overlap_axes(nd, &cut);
        int32_t want = old ? old_index : -1;
        if (old && axes > 0)
            want = -1;
        if (old && axes >= 0)
            kinds[axes]++;
        if (old && axes == 0)
            sizes[nd->level]++;
        cr_expect_eq(reuse[leaf], want, "split node %d: leaf %zu (node %zu, level %d, org %d "
                     "%d %d, %d axes shared) gave %d, want %d", (int)which, leaf, i,
                     nd->level, nd->org[0], nd->org[1], nd->org[2], axes, reuse[leaf], want);
        old_index += was_leaf;
        leaf++;
    }
    cr_assert_eq(leaf, nleaves);
    cr_expect_gt(kinds[0], 0, "a corner-only neighbour");
    cr_expect_gt(kinds[1], 0, "an edge-only neighbour");
    cr_expect_gt(kinds[2], 0, "a face neighbour");
    cr_log_info("split node %d: %zu corner, %zu edge, %zu face neighbours", (int)which,
                kinds[0], kinds[1], kinds[2]);
    free(reuse);
    free(before.nodes);
    free(now.nodes);
    return sizes[1];
}

/* The level-2 leaf of octant 0 at the root's centre (child 7 of node 1): its corner there is
   the level-1 leaf's (octant 7) only point in common with it. */
Test(leaf_memo, a_small_leaf_split_beside_a_big_one_at_a_corner)
{
    ism_octree t;
    before_tree(&t);
    int32_t which = t.nodes[t.nodes[0].child].child + 7;
    free(t.nodes);
    cr_assert_gt(check(which), 0, "the level-1 leaf touches it at a corner alone");
}

/* The level-1 leaf (octant 7): its corner, edge and face neighbours are level-2 leaves. */
Test(leaf_memo, a_big_leaf_split_among_small_ones)
{
    ism_octree t;
    before_tree(&t);
    int32_t which = t.nodes[0].child + 7;
    free(t.nodes);
    check(which);
}
