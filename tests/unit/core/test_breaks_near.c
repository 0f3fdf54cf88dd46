/* test_breaks_near.c — a later max_error round registers the break points of the leaves near
 * those it polygonises again (ism_breaks_near, breaks_near.h): every leaf whose closed box touches
 * a polygonised leaf's is taken (found here by comparing every leaf's box with every
 * polygonised one's), and inside a polygonised leaf's closed box the smaller registry holds
 * the same points as the whole tree's, each with the same successor on its three lattice
 * lines up to the box's end (past it, any successor at or beyond the end: the walks stop
 * there, face_lines.c tile_side). A leaf in `stride` polygonised, each tree in the three
 * boxes: the torus at depth 7; a plane and a sphere cut by the box (polygonised leaves on the
 * root box's upper faces, the grid's last cell); and a torus with a small ball beside it at
 * depths 1 to 10 (leaves of levels 2 to 8 beside the grid's cells of level 6). Each tree's
 * leaves wider than NEAR_BIG_CELLS cells (taken unasked) and narrower than a cell are
 * counted, and asserted where a case is meant to have them (the torus at depth 7 had both,
 * 739 and 268 over the boxes, until graph_cert.c proved its nodes on halves (graph32): now
 * 0 and 6,273, its commonest level coarser; the torus with a ball keeps both). */
#include <criterion/criterion.h>
#include <string.h>
#include "core/expr/tape.h"
#include "core/octree/breaks.h"
#include "core/octree/breaks_near.h"
#include "core/octree/node_lbox.h"
#include "core/octree/octree_build.h"
#include "poly_fixture.h"

#define MAX_DEPTH 7
#define THIN_DEPTH 10
/* One leaf in this many is polygonised again (as a later round's few: Barth's sextic at
 * 1e-2 polygonises 180 to 1,680 of ~38,000 leaves in rounds 2 to 6). */
#define PICK_STRIDE 31
/* What breaks.c documents of its grid, restated to count the paths a tree took: cells of the
 * commonest leaf level, at most NEAR_MAX_LEVEL; leaves wider than NEAR_BIG_CELLS cells taken
 * without asking. */
#define NEAR_MAX_LEVEL 8
#define NEAR_BIG_CELLS 4

static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};

static void build(const ism_tape *t, const double box[6], int min_depth, int max_depth,
                  ism_octree *tree)
{
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, THIN_DEPTH);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = min_depth,
        .max_depth = max_depth,
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

/* Every point of `whole` (its n entries, listed in e) inside box b is in `part` with the same
 * successors up to b's end. */
static void same_inside(const ism_break_point *const *e_of, size_t n, const ism_breaks *part,
                        const ism_node_lbox *b)
{
    for (size_t s = 0; s < n; s++) {
        const ism_break_point *e = e_of[s];
        int32_t p[3];
        ism_lattice_point(e->key, p);
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

/* The paths the trees took (summed over boxes): polygonised leaves on the root box's upper
 * faces; leaves wider than NEAR_BIG_CELLS grid cells, narrower than a cell; leaves asked and
 * not taken. */
typedef struct paths {
    size_t on_face, big, sub_cell, sub_cell_left, left;
} paths;

/* The commonest leaf level up to NEAR_MAX_LEVEL: the near grid's cells. */
static int grid_level(const ism_octree *t, const int32_t *leaves, size_t n)
{
    size_t count[ISM_GRID_MAX_DEPTH + 1] = {0};
    for (size_t k = 0; k < n; k++)
        count[t->nodes[leaves[k]].level]++;
    int best = 0;
    for (int l = 1; l <= NEAR_MAX_LEVEL; l++)
        best = count[l] > count[best] ? l : best;
    return best;
}

static void check_near(const ism_tape *t, const double box[6], int min_depth, int max_depth,
                       size_t stride, int which, paths *pt)
{
    ism_octree tree;
    build(t, box, min_depth, max_depth, &tree);
    size_t nleaves = 0, npol = 0;
    int32_t *leaves = malloc(tree.n * sizeof *leaves), *reuse = malloc(tree.n * sizeof *reuse);
    uint8_t *take = malloc(tree.n);
    ism_node_lbox *pb = malloc(tree.n * sizeof *pb);
    cr_assert(leaves && reuse && take && pb);
    for (size_t i = 0; i < tree.n; i++)
        if (tree.nodes[i].state == ISM_NODE_LEAF) {
            reuse[nleaves] = nleaves % stride == 0 ? -1 : (int32_t)nleaves;
            if (reuse[nleaves] < 0)
                pb[npol++] = ism_node_lbox_of(&tree, &tree.nodes[i]);
            leaves[nleaves++] = (int32_t)i;
        }
    cr_assert(ism_breaks_near(&tree, leaves, nleaves, reuse, take));
    int32_t top = ism_grid_cell_steps(&tree.grid, 0);
    int level = grid_level(&tree, leaves, nleaves), deepest = 0, widest = ISM_GRID_MAX_DEPTH;
    for (size_t k = 0; k < nleaves; k++) {
        int lv = tree.nodes[leaves[k]].level;
        deepest = lv > deepest ? lv : deepest;
        widest = lv < widest ? lv : widest;
    }
    cr_log_info("box %d: %zu leaves, levels %d to %d, grid level %d", which, nleaves, widest,
                deepest, level);
    size_t taken = 0, touching = 0;
    for (size_t k = 0; k < nleaves; k++) {
        ism_node_lbox x = ism_node_lbox_of(&tree, &tree.nodes[leaves[k]]);
        bool near = false;
        for (size_t j = 0; j < npol && !near; j++)
            near = ism_node_lboxes_touch(&x, &pb[j]);
        touching += near;
        taken += take[leaves[k]] != 0;
        cr_assert(!near || take[leaves[k]], "box %d: leaf %zu touches a polygonised one, "
                  "not taken", which, k);
        int lv = tree.nodes[leaves[k]].level;
        if (reuse[k] < 0) {
            for (int a = 0; a < 3; a++)
                pt->on_face += x.hi[a] == top;
        } else if (lv < level && (1 << (level - lv)) > NEAR_BIG_CELLS) {
            pt->big++;
            cr_assert(take[leaves[k]], "box %d: leaf %zu, level %d, wider than %d cells of "
                      "level %d, not taken", which, k, lv, NEAR_BIG_CELLS, level);
        } else {
            pt->left += !take[leaves[k]];
            pt->sub_cell += lv > level;
            pt->sub_cell_left += lv > level && !take[leaves[k]];
        }
    }
    /* the test means something: the polygonised leaves have neighbours, and the
       registry is a part of the whole */
    cr_assert_gt(touching, 2 * npol, "box %d", which);
    cr_assert_lt(taken, nleaves * 3 / 4, "box %d: %zu of %zu leaves taken", which, taken,
                 nleaves);
    ism_breaks whole, part;
    cr_assert(ism_breaks_build(&whole, &tree, NULL, NULL, NULL));
    cr_assert(ism_breaks_build(&part, &tree, take, NULL, NULL));
    cr_assert_lt(part.n, whole.n, "box %d", which);
    const ism_break_point **e_of = malloc(whole.n * sizeof *e_of);
    cr_assert(e_of);
    size_t n = 0;
    for (size_t s = 0; s <= whole.mask; s++)
        if (whole.slots[s].key)
            e_of[n++] = &whole.slots[s];
    for (size_t j = 0; j < npol; j++)
        same_inside(e_of, n, &part, &pb[j]);
    free(e_of);
    ism_breaks_free(&whole);
    ism_breaks_free(&part);
    free(leaves);
    free(reuse);
    free(take);
    free(pb);
    ism_octree_free(&tree);
}

static void check_sweep(const pf_surface *s, double half, int min_depth, int max_depth,
                        size_t stride, paths *pt)
{
    ism_tape *t = pf_compile(s);
    memset(pt, 0, sizeof *pt);
    for (int which = -1; which <= 1; which++) {
        double base[6] = {-half, -half, -half, half, half, half}, box[6];
        pf_sweep_box(base, max_depth, which, box);
        check_near(t, box, min_depth, max_depth, stride, which, pt);
    }
    ism_tape_free(t);
    cr_log_info("on face %zu, big %zu, sub-cell %zu (%zu left), left %zu", pt->on_face,
                pt->big, pt->sub_cell, pt->sub_cell_left, pt->left);
}

Test(breaks_near, takes_every_leaf_touching_and_answers_as_the_whole_tree)
{
    paths pt;
    check_sweep(&torus, 1.5, 3, MAX_DEPTH, PICK_STRIDE, &pt);
    cr_assert_gt(pt.sub_cell_left, 0);
    cr_assert_gt(pt.left, 0);
}

static const pf_surface plane = {"x + 0.37*y - 0.21*z - 0.1", NULL, 0, NULL, 0};
static const pf_surface sphere = {"x^2 + y^2 + z^2 - 2.2", NULL, 0, NULL, 0};

/* Leaves polygonised on the root box's upper faces: their shell reaches the grid's last
   cell (index 2^level). */
Test(breaks_near, leaves_on_the_root_box_faces)
{
    paths pt;
    check_sweep(&plane, 1.5, 4, MAX_DEPTH, PICK_STRIDE, &pt);
    cr_assert_gt(pt.on_face, 0);
    check_sweep(&sphere, 1.5, 3, MAX_DEPTH, PICK_STRIDE, &pt);
    cr_assert_gt(pt.on_face, 0);
    cr_assert_gt(pt.left, 0);
}

static const ism_param ball_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus_ball = {
    "min((x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2), "
    "(x - 0.3)^2 + (y - 0.2)^2 + (z - 0.1)^2 - 0.0004)", ball_rr, 2, NULL, 0};

/* Leaves far wider than the grid's cells (taken unasked) and narrower than a cell. */
Test(breaks_near, leaves_wider_and_narrower_than_the_grid)
{
    paths pt;
    check_sweep(&torus_ball, 1.5, 1, THIN_DEPTH, PICK_STRIDE, &pt);
    cr_assert_gt(pt.big, 0);
    cr_assert_gt(pt.sub_cell, 0);
    cr_assert_gt(pt.sub_cell_left, 0);
    cr_assert_gt(pt.left, 0);
}
