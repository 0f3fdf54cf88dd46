/* test_breaks_lines.c — the break-point registry (breaks.c) against a second method: every
 * leaf's 8 corners gathered here, sorted line by line along each axis with the C library's
 * comparison sort (qsort, not the registry's radix passes), and each point's successor read
 * off the next point on its line. The registry must hold exactly those points, each with
 * those three successors (ISM_BREAK_NONE past a line's last point), on adapted trees of the
 * ring torus, Barth's sextic and the gyroid ball in the three box placements, built on one
 * block and on a 2-thread pool's two blocks. It guards the successors along x and y, sorted
 * by the line alone (link_axis: the points of a line come in order along it from the sort
 * along z), and the radix passes' order across blocks. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "core/octree/breaks.h"
#include "core/octree/octree_build.h"
#include "core/util/pool.h"
#include "octree_fixture.h"
#include "poly_fixture.h"

#define MAX_DEPTH 7
#define MAX_ERROR 1e-2
#define HALF 1.5 /* the base box ±1.5 holds the three surfaces */

static void build(const ism_tape *t, int placement, ism_octree *tree)
{
    of_build_swept(t, HALF, MAX_DEPTH, MAX_ERROR, placement, tree);
}

/* The axis qsort's comparison orders points along (a file-scope setting: qsort passes none). */
static int sort_axis;

/* By line (the two other coordinates, next axis first), then along sort_axis. */
static int by_line(const void *pa, const void *pb)
{
    const int32_t *a = pa, *b = pb;
    int u = (sort_axis + 1) % 3, v = (sort_axis + 2) % 3;
    int order[3] = {u, v, sort_axis};
    for (int k = 0; k < 3; k++)
        if (a[order[k]] != b[order[k]])
            return a[order[k]] < b[order[k]] ? -1 : 1;
    return 0;
}

static bool same_line(const int32_t *a, const int32_t *b, int axis)
{
    return a[(axis + 1) % 3] == b[(axis + 1) % 3] && a[(axis + 2) % 3] == b[(axis + 2) % 3];
}

/* Every leaf's corners, distinct, into *out (sorted by x, y, z); their count. */
static size_t leaf_corners(const ism_octree *tree, int32_t (**out)[3])
{
    size_t leaves = 0;
    for (size_t i = 0; i < tree->n; i++)
        leaves += tree->nodes[i].state == ISM_NODE_LEAF;
    int32_t (*p)[3] = malloc((8 * leaves + 1) * sizeof *p);
    cr_assert(p);
    size_t n = 0;
    for (size_t i = 0; i < tree->n; i++) {
        const ism_node *nd = &tree->nodes[i];
        if (nd->state != ISM_NODE_LEAF)
            continue;
        int32_t s = ism_grid_cell_steps(&tree->grid, nd->level);
        for (int c = 0; c < 8; c++)
            for (int a = 0; a < 3; a++)
                p[n + c][a] = nd->org[a] + (c >> a & 1 ? s : 0);
        n += 8;
    }
    sort_axis = 2;
    qsort(p, n, sizeof *p, by_line);
    size_t m = 0;
    for (size_t i = 0; i < n; i++)
        if (m == 0 || by_line(p[m - 1], p[i]) != 0)
            memcpy(p[m++], p[i], sizeof p[0]);
    *out = p;
    return m;
}

/* The registry of tree's leaves, built on pool (NULL: one block), against the sorted
 * corners, every point on every axis; the points that have a successor along x and y counted
 * into *linked. */
static void check_tree(const ism_octree *tree, ism_pool *pool, size_t *linked)
{
    int32_t (*p)[3];
    size_t n = leaf_corners(tree, &p);
    ism_breaks b;
    cr_assert(ism_breaks_build(&b, tree, NULL, pool, NULL));
    cr_assert_eq(b.n, n, "%zu points registered, %zu leaf corners", b.n, n);
    for (int axis = 0; axis < 3; axis++) {
        sort_axis = axis;
        qsort(p, n, sizeof *p, by_line);
        for (size_t i = 0; i < n; i++) {
            int32_t want = i + 1 < n && same_line(p[i], p[i + 1], axis) ? p[i + 1][axis]
                                                                        : ISM_BREAK_NONE;
            const ism_break_point *e = ism_breaks_find(&b, p[i]);
            cr_assert(e, "corner (%d, %d, %d) not registered", p[i][0], p[i][1], p[i][2]);
            cr_assert_eq(e->next[axis], want, "(%d, %d, %d) along %d: next %d, want %d",
                         p[i][0], p[i][1], p[i][2], axis, e->next[axis], want);
            *linked += axis < 2 && want != ISM_BREAK_NONE;
        }
    }
    ism_breaks_free(&b);
    free(p);
}

static void check_surface(const pf_surface *s)
{
    ism_tape *t = pf_compile(s);
    /* two threads: the radix passes count and scatter in two blocks, which must keep the
       order a single block makes (digit_offsets: blocks in order within a digit) */
    ism_pool *pool = ism_pool_new(2);
    cr_assert(pool && ism_pool_threads(pool) == 2);
    size_t linked = 0;
    for (int placement = pf_first_box() - 1; placement <= 1; placement++) {
        ism_octree tree;
        build(t, placement, &tree);
        /* enough nodes for ism_breaks_build to split its arrays into the pool's blocks */
        cr_assert_geq(8 * tree.n, ISM_BREAKS_MIN_PARALLEL_CORNERS, "%zu nodes", tree.n);
        check_tree(&tree, NULL, &linked);
        check_tree(&tree, pool, &linked);
        ism_octree_free(&tree);
    }
    cr_assert_gt(linked, 1000); /* lines of many points along x and y, not a few */
    ism_pool_free(pool);
    ism_tape_free(t);
}

Test(breaks_lines, successors_as_a_comparison_sort_finds_them_torus)
{
    check_surface(&pf_ring_torus);
}

Test(breaks_lines, successors_as_a_comparison_sort_finds_them_barth)
{
    check_surface(&pf_barth_sextic);
}

Test(breaks_lines, successors_as_a_comparison_sort_finds_them_gyroid_ball)
{
    check_surface(&pf_gyroid_ball);
}
