/* octree.c — queries over a built octree: point location and the tiling of a leaf's face
 * by the leaves across it (what lets a coarse plotting node take in the vertices that finer
 * neighbours put on their shared face: the paper's FixHoles, done by construction), face by
 * face or a node's six faces in one pass (the cells'). */
#include "core/octree/octree.h"

#include <stdlib.h>

/* The child of split node i (which contains o) that contains o. Inline: every descent
 * steps through it (ism_octree_find, the face-by-face tiles). */
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
    int u = ism_axis_next(axis), v = ism_axis_prev(axis);
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    ism_tile tile = {axis, nd->org[axis] + side * s, nd->org[u], nd->org[u] + s, nd->org[v],
                     nd->org[v] + s};
    return tile;
}

/* Where a face's tiles go: told the face (2 × axis + side) of the node they tile. */
typedef bool (*tile_emit)(void *ctx, int face, const ism_tile *tile);

/* Emits the faces (on the plane facing the other node) of the non-empty leaves under
 * node i as tiles of `face`; `side` is the side of those leaves' faces that touches the
 * plane. */
static bool collect_leaves(const ism_octree *t, int32_t i, int axis, int side, int face,
                           tile_emit emit, void *ctx)
{
    const ism_node *nd = &t->nodes[i];
    if (ism_node_void(nd))
        return true;
    if (nd->child < 0) {
        ism_tile tile = face_of(t, nd, axis, side);
        return emit(ctx, face, &tile);
    }
    for (int k = 0; k < 8; k++)
        if (((k >> axis) & 1) == side)
            if (!collect_leaves(t, nd->child + k, axis, side, face, emit, ctx))
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

/* The node across node's face (axis, side): face_neighbour asked with the origin of the cell
 * of node's size beyond the face (parent may be NULL). */
static int32_t across(const ism_octree *t, const int32_t *parent, int32_t node, int axis,
                      int side)
{
    const ism_node *nd = &t->nodes[node];
    int32_t s = ism_grid_cell_steps(&t->grid, nd->level);
    int32_t o[3] = {nd->org[0], nd->org[1], nd->org[2]};
    o[axis] += side ? s : -s;
    return face_neighbour(t, parent, node, axis, side, o);
}

/* The tiles of the face (axis, side) of node nd whose neighbour across it is j (-1: none).
 * Always inlined: ism_octree_node_tiles' loop then takes each face's axis and side as
 * constants (Klein's bottle at E 3.27e-3: 9.8M instructions fewer over 56,460 nodes). */
static inline __attribute__((always_inline)) bool
face_tiles_from(const ism_octree *t, const ism_node *nd, int32_t j, int axis, int side,
                tile_emit emit, void *ctx)
{
    int face = 2 * axis + side;
    ism_tile own = face_of(t, nd, axis, side);
    if (j < 0)
        return emit(ctx, face, &own); /* the face is on the search box's boundary */
    const ism_node *nb = &t->nodes[j];
    if (ism_node_void(nb))
        return true; /* the face lies in a closed box proven free of f = 0 */
    if (nb->child < 0 || nb->level < nd->level)
        return emit(ctx, face, &own); /* the other side is as coarse or coarser */
    return collect_leaves(t, j, axis, 1 - side, face, emit, ctx);
}

/* The node across each face of `node` as find_near answers it, climbing node's ancestors
 * once and only as far as the faces need (into nb[face], -1 on the search box's boundary).
 * Below their lowest common ancestor, the node's cells lie on `side` of the face along its
 * axis and the neighbour's on the other, at the same place along the other axes: the
 * neighbour's path is the node's with the axis bit of its child indices flipped, from the
 * first ancestor (from the bottom) whose index's bit differs from side (the sibling across
 * the face there: each level settles one face of each axis), down to the node's level or a
 * leaf. */
static void node_neighbours(const ism_octree *t, const int32_t *parent, int32_t node,
                            int32_t nb[6])
{
    /* the faces a child index settles: per axis, the face on the side its bit is not */
    static const uint8_t settles[8] = {0x2a, 0x29, 0x26, 0x25, 0x1a, 0x19, 0x16, 0x15};
    int32_t up[ISM_GRID_MAX_DEPTH + 1]; /* up[d]: the node's ancestor d levels up */
    int k[ISM_GRID_MAX_DEPTH + 1];      /* up[d]'s child index in its parent */
    int top[6];                         /* per face: the level d its bit differs at */
    unsigned need = 63;                 /* faces not settled yet */
    int n = 0;
    for (int32_t i = node; need && i > 0; i = parent[i], n++) {
        up[n] = i;
        k[n] = i - t->nodes[parent[i]].child;
        unsigned now = need & settles[k[n]];
        need ^= now;
        for (; now; now &= now - 1)
            top[__builtin_ctz(now)] = n;
    }
    for (int face = 0; face < 6; face++) {
        nb[face] = -1;
        if (need >> face & 1)
            continue;
        int flip = 1 << (face / 2), d = top[face];
        int32_t j = t->nodes[parent[up[d]]].child + (k[d] ^ flip);
        while (--d >= 0 && t->nodes[j].child >= 0)
            j = t->nodes[j].child + (k[d] ^ flip);
        nb[face] = j;
    }
}

/* node_neighbours through memo: the parent's neighbours (found once for its children in a
 * row), then one step down each toward the node (node_neighbours' last step); a face inside
 * the parent has the node's sibling across it (the node's own index settles it). */
static void memo_neighbours(const ism_octree *t, const int32_t *parent, int32_t node,
                            ism_nb_memo *memo, int32_t nb[6])
{
    int32_t p = parent[node];
    if (memo->of != p + 1 || memo->nodes != t->nodes || memo->parent != parent) {
        *memo = (ism_nb_memo){t->nodes, parent, p + 1, {0}};
        node_neighbours(t, parent, p, memo->nb);
    }
    int32_t first = t->nodes[p].child;
    int k = node - first;
    for (int face = 0; face < 6; face++) {
        int axis = face / 2, flip = 1 << axis;
        int32_t j = memo->nb[face];
        if ((k >> axis & 1) != face % 2)
            j = first + (k ^ flip);
        else if (j >= 0 && t->nodes[j].child >= 0)
            j = t->nodes[j].child + (k ^ flip);
        nb[face] = j;
    }
}

bool ism_octree_node_tiles(const ism_octree *t, const int32_t *parent, int32_t node,
                           ism_nb_memo *memo,
                           bool (*emit)(void *ctx, int face, const ism_tile *tile), void *ctx)
{
    int32_t nb[6];
    if (parent && memo && node > 0)
        memo_neighbours(t, parent, node, memo, nb);
    else if (parent)
        node_neighbours(t, parent, node, nb);
    else /* no ancestors to climb: each neighbour searched from the root */
        for (int face = 0; face < 6; face++)
            nb[face] = across(t, NULL, node, face / 2, face % 2);
    const ism_node *nd = &t->nodes[node];
    for (int face = 0; face < 6; face++)
        if (!face_tiles_from(t, nd, nb[face], face / 2, face % 2, emit, ctx))
            return false;
    return true;
}

/* ism_octree_face_tiles' emit behind face_tiles_from's (which tells the face). */
typedef struct one_face {
    bool (*emit)(void *ctx, const ism_tile *tile);
    void *ctx;
} one_face;

static bool emit_one_face(void *ctx, int face, const ism_tile *tile)
{
    (void)face;
    one_face *of = ctx;
    return of->emit(of->ctx, tile);
}

bool ism_octree_face_tiles(const ism_octree *t, const int32_t *parent, int32_t node, int axis,
                           int side, bool (*emit)(void *ctx, const ism_tile *tile), void *ctx)
{
    one_face of = {emit, ctx};
    return face_tiles_from(t, &t->nodes[node], across(t, parent, node, axis, side), axis, side,
                           emit_one_face, &of);
}
