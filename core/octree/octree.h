/* octree.h — the adaptive octree over the search box: nodes addressed by lattice origin
 * and level, built by interval exclusion, unconditional subdivision to the minimum depth and
 * the flatness test (plot_test.h) up to the maximum depth; and the queries the cell
 * polygoniser needs: point location and the tiling of a node's face by the leaves on the
 * other side (the basis of crack repair). */
#ifndef ISM_OCTREE_H
#define ISM_OCTREE_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/octree/grid.h"

enum ism_node_state {
    ISM_NODE_SPLIT = 0,  /* has 8 children */
    ISM_NODE_EMPTY = 1,  /* leaf proven empty by intervals (closed box) */
    ISM_NODE_LEAF = 2,   /* leaf that may hold surface: a candidate plotting node */
};

enum ism_node_flags {
    ISM_NODE_UNRESOLVED = 1, /* leaf at max depth that failed the flatness test */
    ISM_NODE_ZERO_FREE = 2,  /* leaf whose closed box intervals prove |f| > the double-root
                                eps on: no root and no tangent point on any of its segments,
                                so it emits nothing and its faces yield no tile (as an empty
                                node's); it stays a leaf, so its corners still break the
                                lattice lines (breaks.c) and no neighbour's segments change */
    ISM_NODE_UNFLAT = 4,     /* without max_error: an unresolved leaf neither on a crease
                                (its tape keeps a min/max) nor meeting a quiet ball (the
                                singular locus; octree_build.c unflat): its triangles are
                                measured against the flatness tolerance for the stats'
                                warning, and counted unless a quiet ball has its centre
                                within 1 / (4 flat_plane) of its sizes (a node's cone bends
                                beyond the tolerance there at every depth; polygonise.c
                                measure_unflat) */
    ISM_NODE_CONFORMED = 8,  /* under max_error: a leaf whose box lies in a quiet ball
                                (quiet.h: inside the tube or ball the conformance pass cuts
                                out round the singular locus and meshes again), left whole
                                though it failed the plot test and not split again when its
                                triangles miss E: none of them reaches the mesh
                                (octree_build.c conformed) */
};

/* What the hidden-piece search (thin_search.h) decided at a node, kept so that the next
 * max_error round can take the node over without searching again: the number of searches
 * (the whole node, or each face whose corners share a sign), how many of them could not
 * decide, and whether a piece was found (the node was split and its subtree may go
 * ISM_THIN_RESOLVE_LEVELS past depth.max, unless the piece was found where f has a kink,
 * ISM_NODE_THIN_AT_KINK: then only nodes that still hide it split). A node makes at most 7
 * searches (itself and its 6 faces). */
#define ISM_NODE_THIN_SEARCHES(t) ((t) & 7)
#define ISM_NODE_THIN_UNDECIDED(t) (((t) >> 3) & 7)
#define ISM_NODE_THIN_FOUND 0x40
#define ISM_NODE_THIN_AT_KINK 0x80
#define ISM_NODE_THIN_PACK(searches, undecided, found) \
    ((uint8_t)((searches) | (undecided) << 3 | ((found) ? ISM_NODE_THIN_FOUND : 0)))

typedef struct ism_node {
    int32_t org[3];  /* lattice origin */
    int32_t child;   /* index of the first of 8 consecutive children, -1 for leaves */
    uint8_t level;
    uint8_t state;
    uint8_t flags;
    uint8_t thin;    /* the hidden-piece search's verdict here (ISM_NODE_THIN_*), 0 if none ran */
} ism_node;

/* A leaf evaluates either f itself or f shortened by intervals over the leaf's closed box
 * (its min/max decided strictly there, so equal to f bit for bit, values and gradients, at
 * every point of the box: shorten.c). Which one is kept beside the nodes, in the side array
 * tape_of (one entry per node; NULL when no leaf has a shortened tape): 0 for f itself, k
 * for tree->tapes[k - 1]. A tree holds at most ISM_OCTREE_TAPES distinct tapes and
 * ISM_OCTREE_TAPE_BYTES of their code (a bound on memory: a union of n balls has about as
 * many distinct tapes as groups of balls that meet in one leaf, thousands for n = 200, each
 * a few hundred bytes); leaves past either limit evaluate f (the same mesh, for more). */
#define ISM_NODE_FLAG_BITS (ISM_NODE_UNRESOLVED | ISM_NODE_ZERO_FREE)
#define ISM_OCTREE_TAPES 65535u                /* the numbers fit tape_of's 16 bits */
#define ISM_OCTREE_TAPE_BYTES ((size_t)64 << 20)

typedef struct ism_octree {
    ism_grid grid;
    ism_node *nodes;
    size_t n, cap;
    uint16_t *tape_of;         /* per node: its tape's number (above), or NULL */
    struct ism_tape **tapes;   /* the leaves' shortened tapes (owned) */
    size_t ntapes;
} ism_octree;

/* The tape leaf nd (a node of t) evaluates inside its box, or NULL for f itself. */
static inline const struct ism_tape *ism_leaf_tape(const ism_octree *t, const ism_node *nd)
{
    unsigned k = t->tape_of ? t->tape_of[nd - t->nodes] : 0;
    return k ? t->tapes[k - 1] : NULL;
}

/* Does the node's closed box hold no point of f = 0 (empty, or a zero-free leaf)? */
static inline bool ism_node_void(const ism_node *nd)
{
    return nd->state == ISM_NODE_EMPTY ||
           (nd->state == ISM_NODE_LEAF && (nd->flags & ISM_NODE_ZERO_FREE));
}

/* Child k of a node sits at org + half * (k & 1, k >> 1 & 1, k >> 2 & 1). */
static inline void ism_child_origin(const ism_grid *g, const ism_node *nd, int k,
                                    int32_t out[3])
{
    int32_t half = ism_grid_cell_steps(g, nd->level + 1);
    for (int a = 0; a < 3; a++)
        out[a] = nd->org[a] + ((k >> a) & 1) * half;
}

/* Index of the deepest node of level <= level that contains the lattice cell with origin o
 * at that level; -1 when o is outside the root. */
int32_t ism_octree_find(const ism_octree *t, const int32_t o[3], int level);

/* The nodes ism_octree_find passes, the root first and the node it answers last, into path;
 * their number (0 when o is outside the root). */
int ism_octree_path(const ism_octree *t, const int32_t o[3], int level,
                    int32_t path[ISM_GRID_MAX_DEPTH + 1]);

/* Every node's parent (-1 for the root), for ism_octree_face_tiles; malloc'ed (NULL when
 * out of memory). */
int32_t *ism_octree_parents(const ism_octree *t);

/* The axes after `axis` in cyclic order, (axis + 1) % 3 and (axis + 2) % 3, without the
 * division (a tile's walk asks them of every tile). */
static inline int ism_axis_next(int axis) { return axis == 2 ? 0 : axis + 1; }
static inline int ism_axis_prev(int axis) { return axis == 0 ? 2 : axis - 1; }

/* A rectangle of a lattice plane: the face of one leaf, used as a piece of another node's
 * face. u = (axis+1)%3, v = (axis+2)%3 (ism_axis_next, ism_axis_prev). */
typedef struct ism_tile {
    int axis;
    int32_t plane;
    int32_t u0, u1, v0, v1;
} ism_tile;

/* Tiles the face (axis, side) of leaf `node` by the non-empty leaves on the other side
 * (or the face itself when the other side is not finer). Calls emit for each tile; a face
 * that lies in the closed box of an empty node or a zero-free leaf yields nothing. Returns
 * false if emit does.
 * parent (ism_octree_parents, or NULL) lets the neighbour be found from the node's nearest
 * common ancestor instead of the root. */
bool ism_octree_face_tiles(const ism_octree *t, const int32_t *parent, int32_t node, int axis,
                           int side, bool (*emit)(void *ctx, const ism_tile *tile), void *ctx);

/* The nodes across the six faces of one parent, kept for its other children (a thread's
 * leaves come sibling after sibling: Klein's bottle at E 3.27e-3, 45,468 of 56,460 nodes
 * polygonised right after a sibling). Empty when zeroed. Valid only while the tree and the
 * parent array it was filled from stay as they were: the caller zeroes it whenever either
 * may have changed (a new tree, a tree changed in place, an array freed and allocated
 * again). The pointers it keeps only catch a different tree or array at a different
 * address, not one at the same address. */
typedef struct ism_nb_memo {
    const ism_node *nodes;   /* the tree and parent array it was filled from */
    const int32_t *parent;
    int32_t of;              /* the parent node + 1; 0: empty */
    int32_t nb[6];           /* the parent's neighbours, as ism_octree_node_tiles finds them */
} ism_nb_memo;

/* ism_octree_face_tiles of the node's six faces in one pass, face 2 × axis + side from 0 to
 * 5, each face's tiles in that call's order, emit told the face: the node's ancestors are
 * climbed once (parent) and each face's neighbour is found from them (the node's path with
 * the face's bit flipped below their common ancestor), with no search from a lattice point;
 * with parent NULL, each searched from the root as ism_octree_face_tiles does. memo (NULL:
 * none; only used with parent; see ism_nb_memo for when to zero it) keeps the parent's six
 * neighbours for its children in a row: a child's neighbour across a face of its parent is
 * that of the parent's neighbour there toward the child, or the neighbour itself when it is
 * a leaf (the node's path below the common ancestor, one step shorter). Returns false if
 * emit does. */
bool ism_octree_node_tiles(const ism_octree *t, const int32_t *parent, int32_t node,
                           ism_nb_memo *memo,
                           bool (*emit)(void *ctx, int face, const ism_tile *tile), void *ctx);

#endif
