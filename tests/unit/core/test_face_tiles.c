/* test_face_tiles.c — ism_octree_face_tiles finds a face's neighbour from the node's parent
 * (octree.c: find_near starts at parent[node], face_neighbour answers a sibling across a face
 * that looks into the parent directly). Its oracle is the same call without parents, which
 * descends from the root as ism_octree_find does: for every node of adapted trees (the torus
 * and the gyroid in a ball, three box placements) and each of its 6 faces, both emit the same
 * tiles in the same order, and every tile lies in that face. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "core/octree/octree_build.h"
#include "poly_fixture.h"

#define MAX_DEPTH 7
#define MAX_ERROR 1e-2
#define MAX_TILES 4096 /* a face's tiles: at most 4^(MAX_DEPTH) leaves, far fewer in practice */
#define HALF 1.5       /* the base box ±1.5 holds both surfaces */


typedef struct tile_list {
    ism_tile v[MAX_TILES];
    size_t n;
} tile_list;

static bool keep(void *ctx, const ism_tile *tile)
{
    tile_list *l = ctx;
    cr_assert_lt(l->n, MAX_TILES);
    l->v[l->n++] = *tile;
    return true;
}

static void build(const ism_tape *t, int placement, ism_octree *tree)
{
    const double base[6] = {-HALF, -HALF, -HALF, HALF, HALF, HALF};
    double box[6];
    pf_sweep_box(base, MAX_DEPTH, placement, box);
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, MAX_DEPTH);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = 3,
        .max_depth = MAX_DEPTH,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&tree->grid, MAX_DEPTH),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = MAX_ERROR},
        .threads = 1,
        .max_nodes = (size_t)1 << 26,
    };
    ism_octree_build_stats st;
    cr_assert_eq(ism_octree_build(tree, &p, &st), ISM_BUILD_OK);
}

/* Each tile lies in node's face (axis, side): on its plane, inside its rectangle. */
static void in_face(const ism_octree *tree, size_t node, int axis, int side, const tile_list *l)
{
    const ism_node *nd = &tree->nodes[node];
    int32_t s = ism_grid_cell_steps(&tree->grid, nd->level);
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    for (size_t k = 0; k < l->n; k++) {
        const ism_tile *tl = &l->v[k];
        cr_assert(tl->axis == axis && tl->plane == nd->org[axis] + side * s &&
                      tl->u0 >= nd->org[u] && tl->u1 <= nd->org[u] + s && tl->u0 < tl->u1 &&
                      tl->v0 >= nd->org[v] && tl->v1 <= nd->org[v] + s && tl->v0 < tl->v1,
                  "node %zu face %d: tile %zu outside the face", node, 2 * axis + side, k);
    }
}

/* Faces whose tiles are a finer neighbour's leaves (more than one tile), over all placements:
 * the walk down the neighbour is exercised, not only the own-face answer. */
static size_t compare(const pf_surface *s)
{
    ism_tape *t = pf_compile(s);
    tile_list *near = malloc(sizeof *near), *root = malloc(sizeof *root);
    cr_assert(near && root);
    size_t finer = 0;
    for (int placement = pf_first_box() - 1; placement <= 1; placement++) {
        ism_octree tree;
        build(t, placement, &tree);
        int32_t *parent = ism_octree_parents(&tree);
        cr_assert(parent);
        for (size_t i = 0; i < tree.n; i++)
            for (int face = 0; face < 6; face++) {
                near->n = root->n = 0;
                cr_assert(ism_octree_face_tiles(&tree, parent, (int32_t)i, face / 2, face % 2,
                                                keep, near));
                cr_assert(ism_octree_face_tiles(&tree, NULL, (int32_t)i, face / 2, face % 2,
                                                keep, root));
                cr_assert(near->n == root->n &&
                              memcmp(near->v, root->v, near->n * sizeof *near->v) == 0,
                          "placement %d node %zu face %d: %zu tiles from the parent, %zu from "
                          "the root",
                          placement, i, face, near->n, root->n);
                in_face(&tree, i, face / 2, face % 2, root);
                finer += root->n > 1;
            }
        free(parent);
        ism_octree_free(&tree);
    }
    free(near);
    free(root);
    ism_tape_free(t);
    return finer;
}

Test(face_tiles, torus_from_the_parent_as_from_the_root)
{
    cr_assert_gt(compare(&pf_ring_torus), 100);
}

Test(face_tiles, gyroid_ball_from_the_parent_as_from_the_root)
{
    cr_assert_gt(compare(&pf_gyroid_ball), 100);
}
