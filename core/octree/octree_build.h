/* octree_build.h — building the adaptive octree: interval exclusion of empty nodes (with
 * min/max tape shortening on the way down), unconditional subdivision to the minimum depth,
 * then the flatness test until the maximum depth; a node that would be a leaf but hides a
 * piece of the surface from its corners (thin_search.h) is split further, below the
 * maximum depth when it must (thin_depth), and so is one whose corners see a feature
 * about a cell across (turned.h). Subtrees are built in parallel and joined
 * in a fixed order, so the tree is identical for any number of threads. */
#ifndef ISM_OCTREE_BUILD_H
#define ISM_OCTREE_BUILD_H

#include <stdint.h>
#include "core/expr/expr.h"
#include "core/octree/octree.h"
#include "core/util/parallel.h"
#include "core/octree/plot_test.h"
#include "core/octree/refine.h"

/* Below a node where a hidden piece was found, nodes that fail the flatness test are split
 * down to this many levels past max_depth (at most thin_depth): a piece found in a cell of
 * depth.max is then meshed by cells of 1/8 of it, about what the flatness test asks of a
 * tube of radius 1/4 cell. A tube of radius 0.26 cell (depth 7, r = 0.004) measured 3.9%
 * short of its area with 2 levels, 0.6% with 3. Deeper than that a node is split only while
 * it still hides a piece (the chase ends where the piece crosses the cells' edges). */
#define ISM_THIN_RESOLVE_LEVELS 3

/* A crossed leaf at depth.max on the depth path whose corners see a feature about a cell
 * across (turned.h: the tube r = 0.004 with a lattice line inside it, a small ball over a
 * lattice corner) is split down ISM_THIN_RESOLVE_LEVELS further too, as the same feature
 * hidden between the lattice lines is. The tests it must pass, and why each threshold is
 * what it is:
 * - ISM_TURNED_COS: two corner gradients more than 120° apart (or one zero). A surface the
 *   cells resolve turns by about a cell's size over its radius of curvature across a cell:
 *   120° needs a radius under about a cell. The tube's cells have corners on both sides of its
 *   axis (up to 180°); the presets' meshes are unchanged (mesh_identity.py).
 * - ISM_TURNED_MIN_RADIUS: the feature f's nearby critical point stands for, √(2|f| / max|λ|)
 *   there, is wider than this fraction of the leaf. A crossing of two sheets has f = 0 at its
 *   critical point (ρ ≈ 0): without the test the Klein bottle's
 *   self-intersection and the lattice planes of xyz (the paper suite, no singular stage) were
 *   resolved; the tube r = 0.004 at depth 7 is 0.26 cell. A real tube thinner than 0.02 cell
 *   whose critical set f = 0 also reaches is not told from a crossing: it stays as coarse
 *   as the cells show it.
 * - ISM_TURNED_LOCUS_CELLS: no quiet ball (the singular stage's locus) has its centre within
 *   this many leaf sizes. Beside a pinch point or double curve the corner gradients turn at
 *   every depth: Steiner's Roman surface at its depth 8 with the cone's reach (5 sizes, as
 *   polygonise.c's measure_unflat) had 9 patches up to 14 cells from its 6 pinch points come
 *   loose (10 edge components, 9 non-manifold artefact points, +20% triangles); 20 leaves its
 *   mesh as without the resolve. A fixed count, not the flatness plane_frac it equalled: a
 *   request's flat_plane must not narrow it.
 * - ISM_TURNED_NEWTON_STEPS, _REACH, _PINV_REL: Newton on ∇f = 0 from the corner with the
 *   least gradient. A quadratic feature (tube, ball) is found in one step, 3 leave room for a
 *   quartic's slower start; a critical point further than 2 leaf sizes is not this leaf's
 *   feature (0 then); eigenvalues under 1e-6 of the largest (a tube's axis, exactly 0 for
 *   y² + z² − r²) take no step, well above a Hessian's rounding (~1e-16), well below any
 *   curvature ratio across a cell. */
#define ISM_TURNED_COS (-0.5)
#define ISM_TURNED_MIN_RADIUS 0.02
#define ISM_TURNED_LOCUS_CELLS 20.0
#define ISM_TURNED_NEWTON_STEPS 3
#define ISM_TURNED_NEWTON_REACH 2.0
#define ISM_TURNED_PINV_REL 1e-6

typedef struct ism_octree_build_params {
    const ism_tape *tape;
    int min_depth, max_depth;
    int thin_depth;                   /* >= max_depth: a node hiding a piece of the surface
                                         from its corners (thin_search.h) is split down to
                                         here; the grid must be at least this deep */
    bool thin_coarse;                 /* whole nodes only (faces too where f has a
                                         kink), no resolve levels
                                         (ism_poly_options.thin_coarse) */
    ism_flatness flatness;
    const double (*quiet)[4];         /* balls hidden pieces are not chased into (see
                                         ism_poly_options): NULL for none */
    size_t nquiet;
    const double (*node_balls)[5];    /* balls round certified nodes split finer (see
                                         ism_poly_options): NULL for none */
    size_t nnode_balls;
    int threads;
    ism_pool *pool;                   /* the threads to build on (pool.h), or NULL: `threads`
                                         threads made for the build */
    size_t max_nodes;                 /* stop with ISM_BUILD_TOO_BIG beyond this */
    const ism_split_set *force_split; /* nodes split whatever the flatness test says (their
                                         emitted triangles missed max_error): NULL for none */
    const ism_octree *previous;       /* the last round's tree, built with these parameters
                                         and a force_split set this one's contains, or NULL:
                                         its leaves that are not forced now and its empty
                                         nodes are taken over without evaluating f, its split
                                         nodes split again with the hidden-piece verdict they
                                         keep (a node's decision depends on nothing else), so
                                         the tree is the one a fresh build makes, counters
                                         included but thin_boxes (boxes searched now) and
                                         the evaluation counts (n_point ..: a node split
                                         again shortens its tape only when a node below is
                                         decided afresh) */
    bool scalar_eval;                 /* no batched intervals, no zero-free leaves (the
                                         reference path: ism_poly_options.scalar_eval) */
    bool full_tape;                   /* leaves evaluate f itself, not a shortened tape (the
                                         reference path: ism_poly_options.full_tape) */
    bool depth_first;                 /* every task grown node by node, never a level at a
                                         time (level_build.c): tests hold the two builds
                                         equal, bit for bit */
    unsigned level_tapes_max;         /* tests: a level-built task's own table of shortened
                                         tapes holds at most this many (0: octree.h's
                                         ISM_OCTREE_TAPES); past it the task is grown node
                                         by node (level_build.c) */
    const volatile int *cancel;
    void (*progress)(void *ctx, double fraction); /* fraction of subtrees done */
    void *progress_ctx;
    ism_par_cost *cost;               /* what the parallel part cost is added here (parallel.h),
                                         or NULL */
    struct ism_root_table *roots;     /* when not NULL, filled with the single roots the
                                         flatness test searched on node edges, for the cells
                                         (root_table.h; empty on failure) */
    size_t max_roots;                 /* ... of which the build's logs keep at most this many
                                         (past it the cells search for themselves) */
    struct ism_crease_memo *crease_memos; /* one crease-point memo per thread the build
                                         runs on, indexed by thread (crease_memo.h, handed
                                         on to the polygonisation): as many as
                                         ism_pool_threads(pool), or `threads` when pool is
                                         NULL; or NULL for none */
    struct ism_point_entry *corner_memos; /* the threads' memos of f and ∇f at node corners
                                         (cell_cache.h ism_point_memo), 2^ISM_CORNER_MEMO_BITS
                                         entries each, end to end, indexed by thread as
                                         crease_memos: kept by the caller, so that the cells
                                         and the next rounds' builds read what this build
                                         evaluated; NULL: the build's own, freed with it */
} ism_octree_build_params;

typedef struct ism_octree_build_stats {
    uint64_t visited, excluded, unresolved;
    uint64_t thin_searched;  /* would-be leaves with one corner sign searched for a piece */
    uint64_t thin_found;     /* ... where one was found (split, below max_depth too) */
    uint64_t thin_undecided; /* ... where the search with interval proofs could neither find
                                nor exclude one (empty Newton probes not counted) */
    uint64_t thin_boxes;     /* boxes those searches examined (in this build only) */
    uint64_t deep_leaves;    /* leaves below max_depth (under hidden pieces) */
    uint64_t tape_misses;    /* leaves (in this build) whose shortened tape found no room in
                                the tree's table (octree.h's limits): they evaluate f */
    uint64_t copied;         /* nodes copied whole from previous (a subtree no force_split
                                key reaches): counted in visited too */
    uint64_t n_point, n_gradient, n_interval;
} ism_octree_build_stats;

enum ism_build_status { ISM_BUILD_OK, ISM_BUILD_CANCELLED, ISM_BUILD_TOO_BIG, ISM_BUILD_NO_MEMORY };

/* t->grid must be set; t->nodes is allocated here (free with ism_octree_free). */
enum ism_build_status ism_octree_build(ism_octree *t, const ism_octree_build_params *p,
                                       ism_octree_build_stats *stats);

void ism_octree_free(ism_octree *t);

#endif
