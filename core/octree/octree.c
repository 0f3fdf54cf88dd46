/* octree.c — queries over a built octree: point location and the tiling of a leaf's face
 * by the leaves across it (what lets a coarse plotting node take in the vertices that finer
 * neighbours put on their shared face: the paper's FixHoles, done by construction). */
#include "core/octree/octree.h"

#include <stdlib.h>

/* The child of split node i (which contains o) that contains o. Inline: every descent
 * steps through it (the cells' face tiles, 670,528 steps on the Klein bottle at E 3.27e-3). */
static inline int32_t child_toward(const ism_octree *t, int32_t i, const int32_t o[3])
{
    const ism_node *nd = &t->nodes[i];
    int32_t half = ism_grid_cell_steps(&t->grid, nd->level + 1);
    int k = 0;
    for (int a = 0; a < 3; a++)
        if (o[a] - nd->org[a] >= half)
            k |= 1 << a;
    return nd->child + k;
}

/* Down from node i (which contains o) as ism_octree_find goes down from the root. */
static int32_t descend(const ism_octree *t, int32_t i, const int32_t o[3], int level)
{
    while (t->nodes[i].level < level && t->nodes[i].child >= 0)
        i = child_toward(t, i, o);
    return i;
}

static bool inside_root(const ism_octree *t, const int32_t o[3])
{
    int32_t full = (int32_t)1 << t->grid.depth;
    for (int a = 0; a < 3; a++)
        if (o[a] < 0 || o[a] >= full)
            return false;
    return true;
}

int32_t ism_octree_find(const ism_octree *t, const int32_t o[3], int level)
{
    return inside_root(t, o) ? descend(t, 0, o, level) : -1;
}

int ism_octree_path(const ism_octree *t, const int32_t o[3], int level,
                    int32_t path[ISM_GRID_MAX_DEPTH + 1])
{
    if (!inside_root(t, o))
        return 0;
    int n = 0;
    int32_t i = 0;
    path[n++] = i;
    while (t->nodes[i].level < level && t->nodes[i].child >= 0)
        path[n++] = i = child_toward(t, i, o);
    return n;
}

int32_t *ism_octree_parents(const ism_octree *t)
{
    int32_t *parent = malloc((t->n ? t->n : 1) * sizeof *parent);
    if (!parent)
        return NULL;
    if (t->n)
        parent[0] = -1;
    for (size_t i = 0; i < t->n; i++)
        if (t->nodes[i].child >= 0)
            for (int k = 0; k < 8; k++)
                parent[t->nodes[i].child + k] = (int32_t)i;
    return parent;
}

/* Does node nd contain the lattice point o? */
static bool contains(const ism_octree *t, const ism_node *nd, const int32_t o[3])
{
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    for (int a = 0; a < 3; a++)
        if (o[a] < nd->org[a] || o[a] - nd->org[a] >= s)
            return false;
    return true;
}

/* ism_octree_find, from the nearest ancestor of `from` that contains o (the same node:
 * every path to o runs through it); parent NULL: from the root. o lies outside `from` (a
 * neighbour's origin), so the search starts at its parent; the root has none (parent[0] is
 * -1) and contains every point inside_root admits, so from the root it starts there. */
static int32_t find_near(const ism_octree *t, const int32_t *parent, int32_t from,
                         const int32_t o[3], int level)
{
    if (!inside_root(t, o))
        return -1;
    if (!parent)
        return descend(t, 0, o, level);
    int32_t i = from > 0 ? parent[from] : 0;
    while (i > 0 && !contains(t, &t->nodes[i], o))
        i = parent[i];
    return descend(t, i, o, level);
}

static ism_tile face_of(const ism_octree *t, const ism_node *nd, int axis, int side)
{
    int u = (axis + 1) % 3, v = (axis + 2) % 3;
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    ism_tile tile = {axis, nd->org[axis] + side * s, nd->org[u], nd->org[u] + s, nd->org[v],
                     nd->org[v] + s};
    return tile;
}

/* Emits the faces (on the plane facing the other node) of the non-empty leaves under
 * node i; `side` is the side of those leaves' faces that touches the plane. */
static bool collect_leaves(const ism_octree *t, int32_t i, int axis, int side,
                           bool (*emit)(void *, const ism_tile *), void *ctx)
{
    const ism_node *nd = &t->nodes[i];
    if (ism_node_void(nd))
        return true;
    if (nd->child < 0) {
        ism_tile tile = face_of(t, nd, axis, side);
        return emit(ctx, &tile);
    }
    for (int k = 0; k < 8; k++)
        if (((k >> axis) & 1) == side)
            if (!collect_leaves(t, nd->child + k, axis, side, emit, ctx))
                return false;
    return true;
}

/* The node of the neighbour's origin o as find_near answers it, directly when it is node's
 * sibling across the face (half of a node's faces face into its parent: its child index's
 * bit along axis differs from side; find_near would step up to the parent and back down). */
static int32_t face_neighbour(const ism_octree *t, const int32_t *parent, int32_t node,
                              int axis, int side, const int32_t o[3])
{
    if (parent && node > 0) {
        int32_t first = t->nodes[parent[node]].child, k = node - first;
        if (((k >> axis) & 1) != side)
            return first + (k ^ (1 << axis));
    }
    return find_near(t, parent, node, o, t->nodes[node].level);
}

bool ism_octree_face_tiles(const ism_octree *t, const int32_t *parent, int32_t node, int axis,
                           int side, bool (*emit)(void *ctx, const ism_tile *tile), void *ctx)
{
    const ism_node *nd = &t->nodes[node];
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    int32_t o[3] = {nd->org[0], nd->org[1], nd->org[2]};
    o[axis] += side ? s : -s;
    int32_t j = face_neighbour(t, parent, node, axis, side, o);
    ism_tile own = face_of(t, nd, axis, side);
    if (j < 0)
        return emit(ctx, &own); /* the face is on the search box's boundary */
    const ism_node *nb = &t->nodes[j];
    if (ism_node_void(nb))
        return true; /* the face lies in a closed box proven free of f = 0 */
    if (nb->child < 0 || nb->level < nd->level)
        return emit(ctx, &own); /* the other side is as coarse or coarser */
    return collect_leaves(t, j, axis, 1 - side, emit, ctx);
}
