/* dual_tree.h — the dual mesher's state (dual.c), shared by the files that make up the
 * mesher: the octree's nodes, the per-thread workers that evaluate f, the vertices,
 * triangles and quads of a round, the memos kept across rounds, and the few helpers every
 * part reads the tree with — besides two that read no tree, declared here because another
 * part borrows them (Newton onto f = 0, room for vertices: at the end). Private to
 * core/octree/dual*.c: dual.h is the mesher's public face. */
#ifndef ISM_DUAL_TREE_H
#define ISM_DUAL_TREE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"
#include "core/octree/cell_cache.h"
#include "core/octree/mesher.h"
#include "core/octree/poly_options.h"
#include "core/octree/dual_balls.h"
#include "core/octree/dual_keyed.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"
#include "core/util/grow.h"
#include "core/util/parallel.h"

/* DN_HOLE: a leaf meeting a point's hole; DN_CREASE: a surface leaf whose vertex lies on f's
 * crease (dual_crease.h); DN_PAIR: a leaf at depth.max beside the crease holding a piece of
 * each branch apart (vert on a, vert2 on b: dual_crease.h ISM_CREASE_PAIR) */
enum { DN_INNER, DN_EMPTY, DN_SURF, DN_HOLE, DN_CREASE, DN_PAIR };

/* A leaf with a vertex: plain, on the crease, or one per branch. */
static inline bool has_sheet(int kind) { return kind == DN_SURF || kind == DN_CREASE || kind == DN_PAIR; }

/* What sag_split learnt of a node's centre foot (dnode.placed): nothing (it did not look,
 * or it split the node), the vertex of a node kept as a leaf (in d->at), or a foot outside
 * the node (place_vertex goes to the secant roots at once). */
enum { FOOT_UNKNOWN, FOOT_AT, FOOT_OUT };

typedef struct dnode {
    ism_ipt o;      /* lattice origin */
    int32_t child;  /* first of the 8 children (bit 0 = x, 1 = y, 2 = z), -1 for a leaf */
    int32_t vert;   /* the leaf's vertex, -1 for none yet */
    int32_t vert2;  /* a DN_PAIR leaf's second (branch b's) vertex, else -1 */
    uint8_t level;
    uint8_t kind;
    uint8_t split;  /* a triangle of this leaf missed E this round */
    uint8_t surf;   /* a surface leaf in the subtree (the walk skips the others) */
    uint8_t placed; /* FOOT_AT: d->at holds the vertex place_vertex would make (sag_split
                     * made it); FOOT_OUT: the centre's Newton left the node */
    uint8_t free_kids; /* bit c: child c's box shown free of f = 0 by this node's own proofs
                        * (corner_view.free_kids): the child is empty without its own */
    double f[8];    /* f at the corners */
} dnode;
/* The mesher's hot array (expand and every sweep over d->n move it): the flags fit in the
 * padding before f, 96 bytes on LP64; a kept leaf's sag_split vertex lives in d->at. */
_Static_assert(sizeof(dnode) <= 96, "dnode grew past 96 bytes");

/* Quads (4 vertices each, counter-clockwise seen from ∇f; u[3] = UINT32_MAX for a
 * triangle) and what went wrong making them. */
typedef struct quads {
    uint32_t *q;
    size_t n, cap;
    bool nomem, bad; /* bad: a leaf round a crossed edge without a vertex */
} quads;

/* The tree walk's calls put off to the pool in the last round, and their quads
 * (ism_dual_make_quads): a call whose nodes' subtrees have not changed since gives the same quads
 * again. Its quads are a second copy of the round's deferred quads beside d->q. While
 * dual_walk.c's join_parts joins a round's parts it holds the threads' scratch quads, the last
 * round's memo, the new memo and d->q at once: up to about four times the deferred quads,
 * each bounded by max_triangles (checked after each round's triangles); between rounds the
 * memo and d->q, twice. run frees it once the rounds end. */
typedef struct walk_memo {
    struct walk_call *calls;
    uint32_t *q;  /* the calls' quads, 4 vertices each, call by call */
    size_t *at;   /* call k's first quad in q (n + 1 entries) */
    size_t n;
    size_t nodes; /* the tree's nodes then (nodes are only ever added) */
} walk_memo;

/* What one thread evaluates f with: its sampler (counters), interval workspace, lattice
 * point memo and same-sign edge memo. */
typedef struct worker {
    ism_sampler s;
    ism_ivjet_ws *jet;
    ism_point_entry *points;
    uint64_t *filled; /* bit i: points[i] holds a point (only this is cleared, not points):
                         an entry's key, f and g mean something only when its bit is set
                         (key 0 does not mark an empty slot here, as in cell_cache.h) */
    int bits; /* points holds 2^bits entries */
    /* Same-sign edges' root searches (same_sign_edge_clear), made on the first search only
     * (a sphere never searches: no 128 KB to fault in); NULL: none yet, or no memory. */
    ism_pair_entry *pairs; /* 2^ISM_PAIR_MEMO_BITS entries (cell_cache.h), or NULL */
    uint64_t *pairs_filled; /* bit i: pairs[i] holds a search (only this is cleared) */
    bool pairs_tried;
    uint8_t *force; /* with a crease: a tape-length zeroed buffer, the top's branch forced by
                       dual_crease.c's enclosures (ism_dual_crease_node); else NULL */
} worker;

typedef struct dual {
    const ism_poly_options *o;
    ism_grid g;
    double finest_step; /* the least of g's finest steps (set_grid): sample_corners' scale */
    ism_pool *pool;
    worker *w;        /* one per thread of the pool */
    int nw;
    dnode *n;
    size_t nn, capn;
    double (*at)[3]; /* by node: the vertex of a node placed FOOT_AT (read only there) */
    size_t capat;
    size_t heldn, heldat; /* the room of n and at that held_bytes counts against max_memory:
                             what growing them one node at a time holds (capn and capat may
                             be more: expand takes a level's room at once), so the limit
                             stops the tree where it always did */
    double *pos;      /* 3 per vertex */
    int32_t *vleaf;   /* the leaf each vertex belongs to */
    int32_t *vtwin;   /* the next vertex of a leaf sharing this one's point, -1: none (two
                         leaves' crease vertices welded: weld_crease) */
    size_t nv, capv;
    uint32_t *tri;    /* this round's triangles */
    size_t nt, capt;
    /* The miss masks (ism_dual_measure_triangles') of this round's triangles that
     * ism_dual_emit_quads measured, each | TMISS_KNOWN, 0 for the others (fans' triangles);
     * they speak of tri while ntmiss == nt (mark_round then measures only the others) */
    uint8_t *tmiss;
    size_t ntmiss;
    quads q;          /* this round's quads (ism_dual_make_quads) */
    walk_memo memo;   /* the last round's put-off walk calls and their quads */
    keyed passed;       /* triangles (tri_key) that met E */
    keyed mid;          /* vertex pairs (pair_key): the distance of their midpoint to f = 0 */
    keyed fans;         /* quads (quad_key) cut as a fan: their centre vertex */
    keyed sides;        /* sides (pair_key) a round tried to cut: their vertex (dual_sides.c) */
    int ec0[12], ec1[12], ef[12][2]; /* the cube's edges: ends and faces (ism_cube_edge) */
    double shift;     /* vertices move at most this far along ∇f (straddle.h), or 0 */
    const ism_dual_ball *balls; /* round the isolated singular points (dual_balls.h) */
    size_t nballs;
    ism_dual_ball_cover cover; /* the balls by where they reach (nodes ask only those) */
    const double *inner; /* the request's box when the tree's is grown round it (dual_box.h) */
    bool crease; /* f = min/max(a, b), its only one: nodes with the kink go to dual_crease.h */
    /* children_free's batches so far and the children they showed free; batch_on while
     * they pay (BATCH_PAYS), decided between split passes (the same on any threads) */
    uint64_t batches, batch_freed;
    bool batch_on;
    bool bad, nomem, too_big;
    enum ism_dual_reason why; /* the first reason bad was set for (mesher.h) */
} dual;

/* dual.tmiss: the triangle's mask was measured this round (masks use bits 0-2). */
#define TMISS_KNOWN 0x80

/* The arrays below start at ISM_DUAL_FIRST_ROOM elements (ism_grow's first allocation). */
#define ISM_DUAL_FIRST_ROOM 64
static inline bool grow(void **p, size_t *cap, size_t need, size_t size)
{
    return ism_grow(p, cap, need, size, ISM_DUAL_FIRST_ROOM);
}

static inline void corner_point(const dual *d, const dnode *n, int c, double p[3])
{
    int32_t step = ism_grid_cell_steps(&d->g, n->level);
    for (int a = 0; a < 3; a++)
        p[a] = ism_grid_coord(&d->g, a, n->o.v[a] + ((c >> a) & 1) * step);
}

/* The dual mesh cannot be made, for reason why (the first one given is kept). */
static inline void decline(dual *d, enum ism_dual_reason why)
{
    if (!d->bad)
        d->why = why;
    d->bad = true;
}

/* What a parallel loop's tasks share: the mesher, their inputs and their outputs (slot k of
 * out is task k's alone), and for the chunked measures (chunk_of) how many items in all. */
typedef struct task_ctx {
    struct dual *d;
    const void *in;
    void *out;
    size_t n; /* the chunked loops' item count; 0 where a task is one item */
} task_ctx;

/* What a task of measure_pairs or ism_dual_measure_triangles measures: up to MEASURE_LANES points,
 * their gradients in one batch (ism_sample_grad_batch: bit for bit ism_dual_dist's first
 * sample, for less). */
#define MEASURE_LANES ISM_GRAD_BATCH

/* Task k's share of n items in chunks of MEASURE_LANES: its first item into *lo, and how
 * many it has. */
static inline size_t chunk_of(size_t k, size_t n, size_t *lo)
{
    *lo = k * MEASURE_LANES;
    return n - *lo < MEASURE_LANES ? n - *lo : MEASURE_LANES;
}

/* How many chunks of MEASURE_LANES n items make (chunk_of's tasks). */
static inline size_t chunks(size_t n)
{
    return (n + MEASURE_LANES - 1) / MEASURE_LANES;
}

/* Two helpers that read no tree, here because a second part borrows them. */
/* m moved onto f = 0 by Newton along ∇f, stopping once a step is below NEWTON_STOP of
 * size (dual_classify.c's; its lanes are ism_dual_newton_lanes); false when it could not finish a
 * step (∇f vanishing or not finite). */
bool ism_dual_newton_onto(worker *w, double m[3], double size);
/* ism_dual_newton_onto for the n <= ISM_GRAD_BATCH points m[k] (each by its size[k]) at
 * once, each step's gradients in one batch (ism_sample_grad_batch: bit for bit the scalar
 * run's), a lane leaving where its own run would stop: its answer into ok[k]. dual.c's
 * plain leaves' vertices (ism_dual_feet_in_nodes, place_plain) and dual_measure.c's fan
 * centres and side vertices (ism_dual_vertices_onto). */
void ism_dual_newton_lanes(worker *w, double (*m)[3], const double *size, size_t n, bool *ok);

/* Room for n more vertices (positions and leaves; dual.c's, dual_measure.c's fan centres
 * take room by it too); false when out of memory. */
bool ism_dual_reserve_vertices(dual *d, size_t n);

/* fmin and fmax as the comparisons they are (a NaN argument gives the other one; the sign of
 * a zero aside): libm's are calls, ~150,000 of each per torus mesh at 1e-2 (2% of it). */
static inline double min_of(double x, double y) { return y < x || x != x ? y : x; }
static inline double max_of(double x, double y) { return y > x || x != x ? y : x; }

#endif
