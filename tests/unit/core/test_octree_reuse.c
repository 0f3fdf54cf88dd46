/* test_octree_reuse.c — the max_error rounds take the last round's octree over
 * (octree_build.h, previous): built from the last tree with a larger set of forced splits,
 * the tree is node for node the one a fresh build makes with that set (same order, children,
 * flags, hidden-piece verdicts and counts), while evaluating f far less. On the torus, the
 * gyroid in a ball (its max() shortens tapes on the way down) and a torus whose tube is
 * thinner than the finest cells (the hidden-piece search splits below depth.max), in boxes
 * on the lattice and shifted off it by 1e-3 and by an irrational fraction of a finest cell, on
 * one and two threads. */
#include <criterion/criterion.h>
#include <string.h>
#include "core/expr/tape.h"
#include "core/octree/node_balls.h"
#include "core/octree/octree_build.h"
#include "poly_fixture.h"

#define MAX_DEPTH 7
#define MAX_ERROR 1e-2
/* A reused tree costs at most this share of a fresh build's gradients. Measured on the torus
 * 0.53-0.54 (three boxes): the fresh build's double-root searches stop early since their
 * bracket's interval answers (edge_roots.c), so it no longer spends twice the reused
 * build's gradients (it did: the bound was 0.5); the gyroid ball and the thin torus lower. */
#define REUSE_GRADIENTS 0.6

/* tube radius 0.26 of a depth-7 cell: only the hidden-piece search sees most of it */
static const ism_param thin_rr[] = {{"R", 1}, {"r", 0.006}};
static const pf_surface thin_torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                      thin_rr, 2, NULL, 0};
#define THIN_LEVELS 3 /* the polygoniser's ISM_THIN_BLIND_DEPTH: no quiet balls */

/* Balls round certified nodes (ism_octree_build_params.node_balls) for build(): none unless a
 * test sets them. */
static const double (*node_balls)[ISM_NODE_BALL_FIELDS];
static size_t nnode_balls;

static void build(const ism_tape *t, double shift, int thin_depth, int threads,
                  const ism_split_set *split, const ism_octree *previous, ism_octree *tree,
                  ism_octree_build_stats *st)
{
    double box[6];
    for (int k = 0; k < 3; k++) {
        box[k] = -1.5 + shift;
        box[3 + k] = 1.5 + shift;
    }
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, thin_depth);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = 3,
        .max_depth = MAX_DEPTH,
        .thin_depth = thin_depth,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&tree->grid, MAX_DEPTH),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = MAX_ERROR},
        .threads = threads,
        .max_nodes = (size_t)1 << 26,
        .force_split = split,
        .previous = previous,
        .node_balls = node_balls,
        .nnode_balls = nnode_balls,
    };
    cr_assert_eq(ism_octree_build(tree, &p, st), ISM_BUILD_OK);
}

/* Every stride-th leaf above the maximum depth (at or below it when deep), from the
 * offset-th on, into s. */
static void add_leaves(const ism_octree *tree, size_t offset, size_t stride, bool deep,
                       ism_split_set *s)
{
    size_t seen = 0;
    for (size_t i = 0; i < tree->n; i++) {
        const ism_node *nd = &tree->nodes[i];
        if (nd->state != ISM_NODE_LEAF || (nd->level >= MAX_DEPTH) != deep)
            continue;
        if (seen++ % stride == offset)
            cr_assert(ism_split_set_add(s, ism_node_key(nd)));
    }
    ism_split_set_sort(s);
}

static void same_tree(const ism_octree *a, const ism_octree *b, const char *what)
{
    cr_assert_eq(a->n, b->n, "%s: %zu nodes against %zu", what, a->n, b->n);
    for (size_t i = 0; i < a->n; i++) {
        const ism_node *x = &a->nodes[i], *y = &b->nodes[i];
        cr_assert(memcmp(x->org, y->org, sizeof x->org) == 0 && x->child == y->child &&
                      x->level == y->level && x->state == y->state &&
                      ((x->flags ^ y->flags) & ISM_NODE_FLAG_BITS) == 0 && x->thin == y->thin,
                  "%s: node %zu differs", what, i);
        /* the leaf's shortened tape, by content (the numbers depend on the order found) */
        const ism_tape *tx = ism_leaf_tape(a, x), *ty = ism_leaf_tape(b, y);
        cr_assert(!tx == !ty && (!tx || (tx->len == ty->len && tx->result == ty->result)),
                  "%s: node %zu's tape differs", what, i);
        for (size_t k = 0; tx && k < tx->len; k++)
            cr_assert(tx->code[k].op == ty->code[k].op && tx->code[k].out == ty->code[k].out &&
                          tx->code[k].a == ty->code[k].a,
                      "%s: node %zu's tape differs at %zu", what, i, k);
    }
}

/* A box shift (in finest cells), a thread count and the levels the hidden-piece search may
 * go past depth.max. */
typedef struct run_case {
    double cells;
    int threads;
    int thin_levels;
} run_case;

/* pieces: the surface has pieces only the hidden-piece search finds. */
static void check(const pf_surface *s, const run_case *cases, size_t ncases, bool pieces)
{
    ism_tape *t = pf_compile(s);
    /* under sanitizers (pf_quick) only the last case, each test's box off the lattice */
    for (size_t i = pf_quick() ? ncases - 1 : 0; i < ncases; i++) {
        double shift = cases[i].cells * 3.0 / (1 << MAX_DEPTH);
        int threads = cases[i].threads, thin = MAX_DEPTH + cases[i].thin_levels;
        ism_octree first, fresh, reused;
        ism_octree_build_stats s1, sf, sr;
        ism_split_set split = {0};
        build(t, shift, thin, threads, NULL, NULL, &first, &s1);
        add_leaves(&first, 0, 7, false, &split);
        ism_octree second;
        ism_octree_build_stats s2;
        build(t, shift, thin, threads, &split, &first, &second, &s2);
        add_leaves(&second, 3, 5, false, &split); /* a third round's larger set */
        /* keys at or below depth.max force nothing, yet mark their descent: the subtrees
         * they alone reach are walked, not copied, and must come out the same */
        add_leaves(&second, 1, 13, true, &split);
        build(t, shift, thin, threads, &split, NULL, &fresh, &sf);
        build(t, shift, thin, threads, &split, &second, &reused, &sr);
        same_tree(&fresh, &reused, s->expr);
        cr_expect_eq(sf.visited, sr.visited);
        cr_expect_eq(sf.excluded, sr.excluded);
        cr_expect_eq(sf.unresolved, sr.unresolved);
        cr_expect_eq(sf.deep_leaves, sr.deep_leaves);
        cr_expect_eq(sf.thin_searched, sr.thin_searched);
        cr_expect_eq(sf.thin_found, sr.thin_found);
        cr_expect_eq(sf.thin_undecided, sr.thin_undecided);
        if (pieces)
            cr_expect_gt(sf.thin_found, 0, "shift %g: no hidden piece found", shift);
        /* the copy ran (some subtree no key reaches), yet not everywhere (the forced paths
         * were walked); none with node balls (they may force any leaf) or without a tree */
        cr_expect_eq(sf.copied, 0);
        if (nnode_balls) {
            cr_expect_eq(sr.copied, 0, "shift %g: %llu nodes copied beside node balls", shift,
                         (unsigned long long)sr.copied);
        } else {
            cr_expect_gt(sr.copied, 0, "shift %g: nothing copied", shift);
            cr_expect_lt(sr.copied, sr.visited, "shift %g: every node copied", shift);
        }
        /* far less: at most REUSE_GRADIENTS of the fresh build's gradients */
        cr_expect_lt((double)sr.n_gradient, REUSE_GRADIENTS * (double)sf.n_gradient,
                     "shift %g: %llu gradients of %llu",
                     shift, (unsigned long long)sr.n_gradient,
                     (unsigned long long)sf.n_gradient);
        ism_octree_free(&first);
        ism_octree_free(&second);
        ism_octree_free(&fresh);
        ism_octree_free(&reused);
        ism_split_set_free(&split);
    }
    ism_tape_free(t);
}

Test(octree_reuse, torus_tree_as_a_fresh_build)
{
    static const run_case cases[] = {{0, 1, 0}, {1e-3, 2, 0}, {PF_IRR, 2, THIN_LEVELS}};
    check(&pf_ring_torus, cases, sizeof cases / sizeof cases[0], false);
}

Test(octree_reuse, gyroid_ball_tree_as_a_fresh_build)
{
    static const run_case cases[] = {{PF_IRR, 2, THIN_LEVELS}}; /* the costly one: one box */
    check(&pf_gyroid_ball, cases, sizeof cases / sizeof cases[0], false);
}

/* Split below depth.max where hidden pieces were found: the next round must split the same
 * nodes as deep (the verdict kept per node), not stop at depth.max. */
Test(octree_reuse, thin_torus_tree_as_a_fresh_build)
{
    static const run_case cases[] = {{0, 1, THIN_LEVELS}, {1e-3, 2, THIN_LEVELS},
                                     {PF_IRR, 1, THIN_LEVELS}};
    check(&thin_torus, cases, sizeof cases / sizeof cases[0], true);
}

/* With node balls (a round after certified nodes asked for finer cells) a ball may force a
 * leaf in a subtree no key reaches: every node is grown, none copied, and the tree is still
 * a fresh build's. Two balls on the torus's tube asking for depth-6 cells, in the three placements. */
Test(octree_reuse, torus_with_node_balls_grows_every_node)
{
    double cell = 3.0 / (1 << 6);
    static double balls[2][ISM_NODE_BALL_FIELDS];
    double b0[ISM_NODE_BALL_FIELDS] = {1.3, 0, 0, 0.1, cell};
    double b1[ISM_NODE_BALL_FIELDS] = {0, -0.7, 0, 0.15, cell};
    memcpy(balls[0], b0, sizeof b0);
    memcpy(balls[1], b1, sizeof b1);
    node_balls = (const double (*)[ISM_NODE_BALL_FIELDS])balls;
    nnode_balls = 2;
    static const run_case cases[] = {{0, 1, 0}, {1e-3, 2, 0}, {PF_IRR, 2, 0}};
    check(&pf_ring_torus, cases, sizeof cases / sizeof cases[0], false);
    node_balls = NULL;
    nnode_balls = 0;
}

/* The forced marks' two parts (octree_build.c's mark_forced): a node key decodes to the node's
 * level and origin, and the path to a node's origin at its level runs root to node, each a
 * child of the one before, ending where ism_octree_find answers. Every node of the torus's
 * tree, box off the lattice. */
Test(octree_reuse, node_key_decodes_and_path_descends)
{
    ism_tape *t = pf_compile(&pf_ring_torus);
    ism_octree tree;
    ism_octree_build_stats st;
    build(t, PF_IRR * 3.0 / (1 << MAX_DEPTH), MAX_DEPTH, 1, NULL, NULL, &tree, &st);
    for (size_t i = 0; i < tree.n; i++) {
        const ism_node *nd = &tree.nodes[i];
        int32_t o[3], path[ISM_GRID_MAX_DEPTH + 1];
        int level = ism_node_key_decode(ism_node_key(nd), o);
        cr_assert(level == nd->level && memcmp(o, nd->org, sizeof o) == 0, "node %zu", i);
        int n = ism_octree_path(&tree, o, level, path);
        cr_assert_eq(n, level + 1, "node %zu: path of %d", i, n);
        cr_assert_eq(path[0], 0);
        cr_assert_eq(path[n - 1], (int32_t)i);
        cr_assert_eq(path[n - 1], ism_octree_find(&tree, o, level));
        for (int j = 1; j < n; j++) {
            int32_t c = tree.nodes[path[j - 1]].child;
            cr_assert(c >= 0 && path[j] >= c && path[j] < c + 8, "node %zu step %d", i, j);
        }
    }
    int32_t outside[3] = {-1, 0, 0}, path[ISM_GRID_MAX_DEPTH + 1];
    cr_assert_eq(ism_octree_path(&tree, outside, MAX_DEPTH, path), 0);
    ism_octree_free(&tree);
    ism_tape_free(t);
}
