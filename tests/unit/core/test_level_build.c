/* test_level_build.c — the octree build's level-at-a-time way (level_build.c) on surfaces
 * whose tapes shorten on the way down (a max() the node intervals decide: Barth's sextic
 * and the gyroid, each cut by a ball), against the node-by-node way (depth_first): in three
 * placements, one thread, the same tree node for node (order, children, state, flags,
 * hidden-piece verdicts; each leaf's shortened tape by content, the numbers depending on the
 * order tapes are met), the same counters but the evaluation counts, and every corner value
 * (f, ∇f) and edge root both builds' memos hold, bit for bit. A level build that tested a node
 * on another node's tape (its parent's, or f's own) would decide some nodes otherwise or
 * give their leaves other tapes. */
#include <criterion/criterion.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/expr/tape.h"
#include "core/octree/cell_cache.h"
#include "core/octree/octree_build.h"
#include "core/octree/root_table.h"
#include "poly_fixture.h"

#define MIN_DEPTH 3
#define MAX_DEPTH 7
#define MAX_ERROR 1e-2
#define HALF 1.6 /* the box: ±1.6 (Barth's ball r 1.5 and the gyroid's 1.4 inside) */

/* One build's tree, counters and the memos it filled. */
typedef struct built {
    ism_octree tree;
    ism_octree_build_stats st;
    ism_point_entry *corners;
    ism_root_table roots;
} built;

/* tapes_max: the level build's own table of tapes holds at most this many (0: octree.h's);
 * max_nodes: the build's budget (0: 2^26) */
static void build(const ism_tape *t, const double box[6], bool depth_first,
                  unsigned tapes_max, size_t max_nodes, built *out)
{
    memset(out, 0, sizeof *out);
    ism_grid_init(&out->tree.grid, box, MAX_DEPTH);
    out->corners = calloc((size_t)1 << ISM_CORNER_MEMO_BITS, sizeof *out->corners);
    cr_assert(out->corners);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = MIN_DEPTH,
        .max_depth = MAX_DEPTH,
        .thin_depth = MAX_DEPTH,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&out->tree.grid, MAX_DEPTH),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = MAX_ERROR},
        .threads = 1,
        .max_nodes = max_nodes ? max_nodes : (size_t)1 << 26,
        .roots = &out->roots,
        .max_roots = (size_t)1 << 22,
        .corner_memos = out->corners,
        .depth_first = depth_first,
        .level_tapes_max = tapes_max,
    };
    cr_assert_eq(ism_octree_build(&out->tree, &p, &out->st), ISM_BUILD_OK);
}

static void unbuild(built *b)
{
    ism_octree_free(&b->tree);
    free(b->corners);
    ism_root_table_free(&b->roots);
}

/* Instruction by instruction, registers too (leaf_tapes.c's equality, written again here) */
static bool same_tape(const ism_tape *x, const ism_tape *y)
{
    if (!x || !y)
        return !x && !y;
    if (x->len != y->len || x->result != y->result || x->nregs != y->nregs)
        return false;
    for (size_t k = 0; k < x->len; k++)
        if (x->code[k].op != y->code[k].op || x->code[k].out != y->code[k].out ||
            x->code[k].a != y->code[k].a || x->code[k].b != y->code[k].b ||
            memcmp(&x->code[k].imm, &y->code[k].imm, sizeof x->code[k].imm) != 0)
            return false;
    return true;
}

/* The trees node for node; returns the leaves with a shortened tape. */
static size_t same_tree(const ism_octree *a, const ism_octree *b, const char *what)
{
    cr_assert_eq(a->n, b->n, "%s: %zu nodes against %zu", what, a->n, b->n);
    size_t short_leaves = 0;
    for (size_t i = 0; i < a->n; i++) {
        const ism_node *x = &a->nodes[i], *y = &b->nodes[i];
        cr_assert(memcmp(x->org, y->org, sizeof x->org) == 0 && x->child == y->child &&
                      x->level == y->level && x->state == y->state && x->flags == y->flags &&
                      x->thin == y->thin,
                  "%s: node %zu differs", what, i);
        const ism_tape *tx = ism_leaf_tape(a, x), *ty = ism_leaf_tape(b, y);
        cr_assert(same_tape(tx, ty), "%s: node %zu's tape differs", what, i);
        short_leaves += tx != NULL;
    }
    return short_leaves;
}

static void same_counts(const ism_octree_build_stats *a, const ism_octree_build_stats *b,
                        const char *what)
{
    cr_assert(a->visited == b->visited && a->excluded == b->excluded &&
                  a->unresolved == b->unresolved && a->thin_searched == b->thin_searched &&
                  a->thin_found == b->thin_found && a->thin_undecided == b->thin_undecided &&
                  a->thin_boxes == b->thin_boxes && a->deep_leaves == b->deep_leaves &&
                  a->tape_misses == b->tape_misses,
              "%s: counters differ", what);
}

/* Entries both corner memos hold (the same key in the same slot): f and ∇f bit for bit.
 * Returns how many. */
static size_t same_corners(const ism_point_entry *a, const ism_point_entry *b, const char *what)
{
    size_t both = 0;
    for (size_t i = 0; i < (size_t)1 << ISM_CORNER_MEMO_BITS; i++) {
        if (!a[i].key || a[i].key != b[i].key)
            continue;
        both++;
        cr_assert(memcmp(&a[i].f, &b[i].f, sizeof a[i].f) == 0 &&
                      memcmp(a[i].g, b[i].g, sizeof a[i].g) == 0,
                  "%s: corner value %zu differs", what, i);
    }
    return both;
}

/* Edges both root tables hold: one root, bit for bit. Returns how many. */
static size_t same_roots(const ism_root_table *a, const ism_root_table *b, const char *what)
{
    size_t both = 0;
    for (size_t i = 0; a->slots && i <= a->mask; i++) {
        const ism_root_entry *e = &a->slots[i];
        double t;
        if (!e->a || !ism_root_table_find(b, e->a, e->b, &t))
            continue;
        both++;
        cr_assert(memcmp(&t, &e->t, sizeof t) == 0, "%s: edge root %zu differs", what, i);
    }
    return both;
}

/* tapes_max: as build's; the level build also under a budget of exactly the nodes the
 * node-by-node build counted (a task given up counted twice would fail it) */
static void check(const pf_surface *s, const char *name, unsigned tapes_max)
{
    ism_tape *t = pf_compile(s);
    const double base[6] = {-HALF, -HALF, -HALF, HALF, HALF, HALF};
    for (int which = -1; which < 2; which++) {
        char what[64];
        snprintf(what, sizeof what, "%s, %u tapes, placement %d", name, tapes_max, which);
        double box[6];
        pf_sweep_box(base, MAX_DEPTH, which, box);
        built lv, df;
        build(t, box, true, 0, 0, &df);
        build(t, box, false, tapes_max, df.tree.n, &lv);
        size_t short_leaves = same_tree(&lv.tree, &df.tree, what);
        same_counts(&lv.st, &df.st, what);
        size_t corners = same_corners(lv.corners, df.corners, what);
        size_t roots = same_roots(&lv.roots, &df.roots, what);
        /* not vacuous: leaves on shortened tapes, and shared values compared */
        cr_assert(short_leaves > 100 && corners > 1000 && roots > 1000,
                  "%s: %zu leaves on shortened tapes, %zu corners, %zu roots compared", what,
                  short_leaves, corners, roots);
        unbuild(&lv);
        unbuild(&df);
    }
    ism_tape_free(t);
}

Test(level_build, barth_shortened_tapes_as_node_by_node)
{
    check(&pf_barth_sextic, "Barth", 0);
}

Test(level_build, gyroid_ball_shortened_tapes_as_node_by_node)
{
    check(&pf_gyroid_ball, "gyroid ball", 0);
}

/* A task whose shortened tapes overflow the level build's table is grown node by node, as
 * grow grows it (the table's limits bound a task's scratch, not the tree): the same tree,
 * counters and values, under the same budget of nodes, where a full table once failed the
 * build (ISM_BUILD_NO_MEMORY). A table of one tape: here 200 of the 384 tasks (two surfaces,
 * three placements, 64 tasks each) meet a second one and are given up, the others not. */
Test(level_build, a_full_table_of_tapes_falls_back_to_node_by_node)
{
    check(&pf_barth_sextic, "Barth", 1);
    check(&pf_gyroid_ball, "gyroid ball", 1);
}
