/* test_breaks_near.c — a later max_error round registers the break points of the leaves near
 * those it polygonises again (ism_breaks_near, breaks.h): every leaf whose closed box touches
 * a polygonised leaf's is taken (found here by comparing every pair of boxes), and inside a
 * polygonised leaf's closed box the smaller registry holds the same points as the whole
 * tree's, each with the same successor on its three lattice lines up to the box's end (past
 * it, any successor at or beyond the end: the walks stop there, face_lines.c side_breaks).
 * The torus at depth 7, a leaf in PICK_STRIDE polygonised, in the three boxes. */
#include <criterion/criterion.h>
#include <string.h>
#include "core/expr/tape.h"
#include "core/octree/breaks.h"
#include "core/octree/octree_build.h"
#include "poly_fixture.h"

#define MAX_DEPTH 7
#define THIN_DEPTH 10
/* One leaf in this many is polygonised again (as a later round's few: Barth's sextic at
 * 1e-2 polygonises 180 to 1,680 of ~38,000 leaves in rounds 2 to 6). */
#define PICK_STRIDE 31

static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};

static void build(const ism_tape *t, const double box[6], ism_octree *tree)
{
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, THIN_DEPTH);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = 3,
        .max_depth = MAX_DEPTH,
        .thin_depth = THIN_DEPTH,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&tree->grid, MAX_DEPTH),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = 1e-2},
        .threads = 1,
        .max_nodes = (size_t)1 << 26,
    };
    ism_octree_build_stats st;
    cr_assert_eq(ism_octree_build(tree, &p, &st), ISM_BUILD_OK);
}

typedef struct lbox {
    int32_t lo[3], hi[3];
} lbox;

static lbox box_of(const ism_octree *t, int32_t node)
{
    const ism_node *nd = &t->nodes[node];
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    lbox b;
    for (int a = 0; a < 3; a++) {
        b.lo[a] = nd->org[a];
        b.hi[a] = nd->org[a] + s;
    }
    return b;
}

static bool touch(const lbox *x, const lbox *y)
{
    for (int a = 0; a < 3; a++)
        if (x->hi[a] < y->lo[a] || y->hi[a] < x->lo[a])
            return false;
    return true;
}

/* The lattice point of a registry key (the inverse of ism_lattice_key). */
static void point_of(uint64_t key, int32_t p[3])
{
    key -= 1;
    p[0] = (int32_t)(key >> 42);
    p[1] = (int32_t)((key >> 21) & ((1u << 21) - 1));
    p[2] = (int32_t)(key & ((1u << 21) - 1));
}

/* Every point of `whole` inside box b is in `part` with the same successors up to b's end. */
static void same_inside(const ism_breaks *whole, const ism_breaks *part, const lbox *b)
{
    for (size_t s = 0; s <= whole->mask; s++) {
        const ism_break_point *e = &whole->slots[s];
        int32_t p[3];
        if (!e->key)
            continue;
        point_of(e->key, p);
        bool inside = true;
        for (int a = 0; a < 3; a++)
            inside &= b->lo[a] <= p[a] && p[a] <= b->hi[a];
        if (!inside)
            continue;
        const ism_break_point *f = ism_breaks_find(part, p);
        cr_assert(f, "(%d, %d, %d) registered in the whole tree, not near", p[0], p[1], p[2]);
        for (int a = 0; a < 3; a++)
            if (e->next[a] < b->hi[a])
                cr_assert_eq(f->next[a], e->next[a], "(%d, %d, %d) axis %d", p[0], p[1], p[2], a);
            else
                cr_assert_geq(f->next[a], b->hi[a], "(%d, %d, %d) axis %d", p[0], p[1], p[2], a);
    }
}

Test(breaks_near, takes_every_leaf_touching_and_answers_as_the_whole_tree)
{
    ism_tape *t = pf_compile(&torus);
    for (int which = -1; which <= 1; which++) {
        double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, box[6];
        pf_sweep_box(base, MAX_DEPTH, which, box);
        ism_octree tree;
        build(t, box, &tree);
        size_t nleaves = 0;
        int32_t *leaves = malloc(tree.n * sizeof *leaves), *reuse = malloc(tree.n * sizeof *reuse);
        uint8_t *take = malloc(tree.n);
        cr_assert(leaves && reuse && take);
        for (size_t i = 0; i < tree.n; i++)
            if (tree.nodes[i].state == ISM_NODE_LEAF) {
                reuse[nleaves] = nleaves % PICK_STRIDE == 0 ? -1 : (int32_t)nleaves;
                leaves[nleaves++] = (int32_t)i;
            }
        cr_assert(ism_breaks_near(&tree, leaves, nleaves, reuse, take));
        size_t taken = 0, touching = 0;
        for (size_t k = 0; k < nleaves; k++) {
            lbox x = box_of(&tree, leaves[k]);
            bool near = false;
            for (size_t j = 0; j < nleaves && !near; j++) {
                lbox y = box_of(&tree, leaves[j]);
                near = reuse[j] < 0 && touch(&x, &y);
            }
            touching += near;
            taken += take[leaves[k]] != 0;
            cr_assert(!near || take[leaves[k]], "box %d: leaf %zu touches a polygonised one, "
                      "not taken", which, k);
        }
        /* the test means something: the polygonised leaves have neighbours, and the
           registry is a part of the whole */
        cr_assert_gt(touching, 2 * (nleaves / PICK_STRIDE), "box %d", which);
        cr_assert_lt(taken, nleaves * 3 / 4, "box %d: %zu of %zu leaves taken", which, taken,
                     nleaves);
        ism_breaks whole, part;
        cr_assert(ism_breaks_build(&whole, &tree, NULL, NULL, NULL));
        cr_assert(ism_breaks_build(&part, &tree, take, NULL, NULL));
        cr_assert_lt(part.n, whole.n, "box %d", which);
        for (size_t k = 0; k < nleaves; k++)
            if (reuse[k] < 0) {
                lbox b = box_of(&tree, leaves[k]);
                same_inside(&whole, &part, &b);
            }
        ism_breaks_free(&whole);
        ism_breaks_free(&part);
        free(leaves);
        free(reuse);
        free(take);
        ism_octree_free(&tree);
    }
    ism_tape_free(t);
}
