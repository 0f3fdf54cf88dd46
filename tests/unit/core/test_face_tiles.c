/* test_face_tiles.c — ism_octree_face_tiles finds a face's neighbour from the node's parent
 * (octree.c: find_near starts at parent[node], face_neighbour answers a sibling across a face
 * that looks into the parent directly). Its oracle is the same call without parents, which
 * descends from the root as ism_octree_find does: for every node of adapted trees (the torus
 * and the gyroid in a ball, three box placements) and each of its 6 faces, both emit the same
 * tiles in the same order, and every tile lies in that face. ism_octree_node_tiles (all six
 * faces in one climb of the node's ancestors, each neighbour found by flipping the face's bit
 * of the node's path; without parents, each searched from the root) against the same oracle
 * face by face: the same tiles bit for bit, each told its own face, on the torus, Barth's
 * sextic and the gyroid ball; with parents, through one memo of the last parent's neighbours
 * kept from node to node, the nodes visited in order (siblings in a row: memo hits) and
 * scattered (mostly refilled). */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "core/octree/octree_build.h"
#include "octree_fixture.h"
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
    of_build_swept(t, HALF, MAX_DEPTH, MAX_ERROR, placement, tree);
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

/* The tiles ism_octree_node_tiles emits, with the face each was told. */
typedef struct face_tile_list {
    ism_tile v[6 * MAX_TILES];
    int face[6 * MAX_TILES];
    size_t n;
} face_tile_list;

static bool keep_with_face(void *ctx, int face, const ism_tile *tile)
{
    face_tile_list *l = ctx;
    cr_assert_lt(l->n, 6 * MAX_TILES);
    l->face[l->n] = face;
    l->v[l->n++] = *tile;
    return true;
}

/* The lists a node's check fills, and what the checks count over a sweep. */
typedef struct sweep {
    tile_list near, root;
    face_tile_list all;
    int placement;
    size_t finer;    /* faces tiled by a finer neighbour's leaves (more than one tile) */
    size_t boundary; /* faces on the search box's boundary (no neighbour) */
    ism_nb_memo memo; /* one_pass's, kept from node to node of a tree (zeroed for each) */
    size_t stride;    /* over_nodes visits node i × stride mod n (1: in order, siblings in a
                         row; a prime: mostly not) */
    size_t memo_hits; /* nodes one_pass found with their parent's neighbours in the memo */
} sweep;

/* One node's faces checked: counts into w. */
typedef void (*node_check)(const ism_octree *tree, const int32_t *parent, size_t node,
                           sweep *w);

static size_t gcd(size_t a, size_t b)
{
    while (b) {
        size_t r = a % b;
        a = b, b = r;
    }
    return a;
}

/* check on every node of s's trees in the three placements; *w's counts. */
static void over_nodes(const pf_surface *s, node_check check, sweep *w)
{
    ism_tape *t = pf_compile(s);
    w->finer = w->boundary = 0;
    for (w->placement = pf_first_box() - 1; w->placement <= 1; w->placement++) {
        ism_octree tree;
        build(t, w->placement, &tree);
        int32_t *parent = ism_octree_parents(&tree);
        cr_assert(parent);
        memset(&w->memo, 0, sizeof w->memo);
        /* i × stride mod n visits every node once only when stride and n are coprime */
        cr_assert_eq(gcd(w->stride, tree.n), 1, "stride %zu shares a factor with %zu nodes",
                     w->stride, tree.n);
        for (size_t i = 0; i < tree.n; i++)
            check(&tree, parent, i * w->stride % tree.n, w);
        free(parent);
        ism_octree_free(&tree);
    }
    ism_tape_free(t);
}

/* Each face's tiles from the parent as from the root, inside the face. */
static void from_the_parent(const ism_octree *tree, const int32_t *parent, size_t i, sweep *w)
{
    for (int face = 0; face < 6; face++) {
        w->near.n = w->root.n = 0;
        cr_assert(ism_octree_face_tiles(tree, parent, (int32_t)i, face / 2, face % 2, keep,
                                        &w->near));
        cr_assert(ism_octree_face_tiles(tree, NULL, (int32_t)i, face / 2, face % 2, keep,
                                        &w->root));
        cr_assert(w->near.n == w->root.n &&
                      memcmp(w->near.v, w->root.v, w->near.n * sizeof *w->near.v) == 0,
                  "placement %d node %zu face %d: %zu tiles from the parent, %zu from the root",
                  w->placement, i, face, w->near.n, w->root.n);
        in_face(tree, i, face / 2, face % 2, &w->root);
        w->finer += w->root.n > 1;
    }
}

/* node_tiles' list from parent (NULL: none) against the face-by-face oracle (one_pass). */
static void one_pass_from(const ism_octree *tree, const int32_t *parent, size_t i, sweep *w)
{
    w->all.n = 0;
    if (parent && i > 0)
        w->memo_hits += w->memo.of == parent[i] + 1;
    cr_assert(ism_octree_node_tiles(tree, parent, (int32_t)i, parent ? &w->memo : NULL,
                                    keep_with_face, &w->all));
    size_t at = 0;
    const ism_node *nd = &tree->nodes[i];
    int32_t steps = ism_grid_cell_steps(&tree->grid, nd->level);
    for (int face = 0; face < 6; face++) {
        w->root.n = 0;
        cr_assert(ism_octree_face_tiles(tree, NULL, (int32_t)i, face / 2, face % 2, keep,
                                        &w->root));
        cr_assert(at + w->root.n <= w->all.n &&
                      memcmp(&w->all.v[at], w->root.v, w->root.n * sizeof *w->root.v) == 0,
                  "placement %d node %zu face %d: one pass differs from the face's own %zu "
                  "tiles", w->placement, i, face, w->root.n);
        for (size_t k = 0; k < w->root.n; k++)
            cr_assert_eq(w->all.face[at + k], face, "placement %d node %zu: a tile of face %d "
                         "told face %d", w->placement, i, face, w->all.face[at + k]);
        at += w->root.n;
        w->finer += w->root.n > 1;
        int32_t plane = nd->org[face / 2] + face % 2 * steps;
        w->boundary += plane == 0 || plane == ((int32_t)1 << tree->grid.depth);
    }
    cr_assert_eq(at, w->all.n, "placement %d node %zu: %zu tiles in one pass, %zu face by face",
                 w->placement, i, w->all.n, at);
}

/* node_tiles' list, from the parents and without them (parent NULL: each neighbour searched
 * from the root), is face after face what ism_octree_face_tiles answers from the root (no
 * parents) for that face, bit for bit, each tile told that face. */
static void one_pass(const ism_octree *tree, const int32_t *parent, size_t i, sweep *w)
{
    one_pass_from(tree, parent, i, w);
    one_pass_from(tree, NULL, i, w);
}

/* The sweep of check over s, its finer faces (the walk down the neighbour is exercised, not
 * only the own-face answer) and, with `boundary`, faces on the box's boundary counted. */
static void sweep_checks(const pf_surface *s, node_check check, bool boundary)
{
    sweep *w = calloc(1, sizeof *w);
    cr_assert(w);
    /* in order, then in a scattered order (the memo mostly refilled, each node's parent's
       neighbours from a stale one), through both the memo's hits and its misses */
    size_t strides[2] = {1, 7919}, hits[2];
    for (int k = 0; k < 2; k++) {
        w->stride = strides[k];
        w->memo_hits = 0;
        over_nodes(s, check, w);
        hits[k] = w->memo_hits;
        cr_assert_gt(w->finer, 100);
        if (boundary)
            cr_assert_gt(w->boundary, 0);
    }
    if (check == one_pass)
        cr_assert(hits[0] > 1000 && hits[1] < hits[0] / 4, "memo hits: %zu in order, %zu "
                  "scattered", hits[0], hits[1]);
    free(w);
}

Test(face_tiles, torus_from_the_parent_as_from_the_root)
{
    sweep_checks(&pf_ring_torus, from_the_parent, false);
}

Test(face_tiles, gyroid_ball_from_the_parent_as_from_the_root)
{
    sweep_checks(&pf_gyroid_ball, from_the_parent, false);
}

Test(face_tiles, node_tiles_as_face_by_face_torus)
{
    sweep_checks(&pf_ring_torus, one_pass, true);
}

Test(face_tiles, node_tiles_as_face_by_face_barth)
{
    sweep_checks(&pf_barth_sextic, one_pass, true);
}

Test(face_tiles, node_tiles_as_face_by_face_gyroid_ball)
{
    sweep_checks(&pf_gyroid_ball, one_pass, true);
}
