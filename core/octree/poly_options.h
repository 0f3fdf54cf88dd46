/* poly_options.h — the polygoniser's options, data only: what a caller sets before
 * ism_polygonise (polygonise.h has the defaults and the check; the tolerances' table,
 * tolerances.h, describes six of the fields). */
#ifndef ISM_POLY_OPTIONS_H
#define ISM_POLY_OPTIONS_H

#include <stdbool.h>
#include <stddef.h>

typedef struct ism_poly_options {
    double box[6];          /* xmin ymin zmin xmax ymax zmax: the octree root */
    int min_depth;          /* subdivide to here whatever the flatness (default 3); the dual
                               mesher leaves a node its parent's interval batch shows free of
                               f = 0 empty above it too (dual.c children_free) */
    int max_depth;          /* never deeper than here (default 7) */
    /* The six tolerances; their defaults, ranges and reasons are the table in
     * tolerances.h. */
    double gradient_test;   /* paper eq. (1): ĝa·ĝb > this means "same sheet" */
    double double_root_eps; /* |f(c)| below this is a double root */
    int double_root_iters;  /* bisection steps looking for two roots */
    double stitch_tol;      /* two roots closer than this fraction of a segment are one */
    double flat_normal;     /* flatness: min cos between gradients in a plotting node */
    double flat_plane;      /* flatness: max distance of polygon points from their plane,
                               as a fraction of the node size */
    double max_error;       /* > 0: subdivide until the triangles of each node lie within this
                               distance of the surface (world units, measured at triangle
                               centroids and edge midpoints); max_depth is then only a safety
                               limit, and flat_plane is not used. 0 (default): flat_plane */
    size_t max_triangles;   /* budget: stop with an error beyond this (default 4,000,000) */
    size_t max_memory;      /* bytes the polygoniser may hold (default 2 GiB) */
    int threads;            /* worker threads for one request (0 = number of cores, max 64) */
    bool thin_search;       /* search nodes that fail flatness for a piece no edge sees (one
                               corner sign, or an island in a face of one sign) and split them
                               below max_depth (thin_search.h; default on) */
    bool thin_coarse;       /* with thin_search, the live preview's cheaper search: only
                               nodes whose eight corners share a sign are searched (a small
                               closed piece or a tube inside them; the islands in the faces of
                               nodes with both signs, mostly the nappes round singular points,
                               only where f has a min/max kink: a CSG frame's thin bars pass
                               through faces there), by Newton probes without interval proofs
                               (ism_thin_probe), and a piece found is split only while it
                               stays hidden, not ISM_THIN_RESOLVE_LEVELS further (default off) */
    bool fresh_rounds;      /* under max_error, build every round's octree and polygons
                               afresh (default off: a round takes the last round's tree over
                               and copies the leaves its splits cannot have changed,
                               leaf_memo.h — the same mesh, for less; on is for tests) */
    bool straddle;          /* under max_error, on a surface without min/max and without a
                               singular locus: vertices where the surface bends one way move
                               0.9 E toward its convex side so the mesh straddles it, and
                               nodes are sized for that (straddle.h); default off */
    bool dual;              /* under max_error, on a surface without min/max and without a
                               singular locus (but isolated nodes and isolated points:
                               dual_points, where the box cuts nothing; a surface the box
                               cuts is meshed in a larger box and clipped: dual_box.h)
                               : one vertex per leaf
                               on f = 0 and quads across the crossed minimal edges, leaves
                               sized by the error of those triangles (dual.h; one thread);
                               where that cannot apply, the primal polygons as without it.
                               Default off */
    bool dual_crease;       /* with dual: also f = min/max(a, b) whose only min/max that is,
                               its crease followed by vertices on a = b = 0 (dual_crease.h).
                               Default off, and not asked for by requests: where it cannot
                               follow the crease before depth.max (Barth's clipped sextic in
                               its lattice box at 1e-2..1e-3, gyroid-ball) the failed try
                               costs 35-75% more than the primal polygons alone */
    bool scalar_eval;       /* evaluate the octree node by node: no batched intervals over a
                               node's children, no zero-free leaves (octree.h), no memo of
                               edge roots and crease labels between nodes (cell_cache.h's
                               ism_node_memo), of points' crease labels in the build or the
                               leaves (sampler.h's label_memo) or of crease points
                               (crease_memo.h) and no batched gradients (a leaf's measured
                               points: sampler.h's batch; so each leaf measured as it is
                               polygonised, none deferred) — the same mesh bit for bit, for
                               more, and a wrong memo hit cannot hide by showing up on both
                               sides of the tests' comparison; on is for tests (default
                               off) */
    bool walk_every_tile;   /* every node walks each tile of its faces itself: no memo of the
                               tiles another node of the thread walked in the round (quiet
                               ones, and crossed ones whose lines and counts a hit copies:
                               cell_cache.h), and every tile walked side by side, even one
                               quiet by its corners alone (face_lines.c; that answer is then
                               checked against the walk: ism_poly_stats' corner_mismatches) —
                               the same mesh bit for bit, for more; on is for tests (default
                               off) */
    bool full_tape;         /* every leaf evaluates f itself, not f shortened by intervals over
                               its box (octree.h) — the same mesh bit for bit, for more; on is
                               for tests (default off) */
    /* Balls (x, y, z, radius) whose mesh a later stage rebuilds — around the singular points
     * and along the curves found from f, which the conformance pass refills
     * (core/singular/conform.h): hidden pieces are not chased into them (a horn shrinking to
     * its point would be followed to the lattice's last level, the wedges between two sheets
     * along a double curve at every level). NULL when the caller knows no locus: the chase
     * then goes ISM_THIN_BLIND_DEPTH levels deep only. */
    const double (*quiet)[4];
    size_t nquiet;
    /* Balls around the certified nodes found from f and along its double curves
     * (node_balls.h: x, y, z, radius, cell; at most ISM_NODE_BALLS_MAX): a node meeting one
     * is split until it is no larger than the ball's cell, below max_depth too (down to the
     * lattice's last level), so both nappes of a cone cross cell edges there and a double
     * curve's tube is cut in cells of the curve's scale (core/singular/curve_cell.h). NULL
     * for none. */
    const double (*node_balls)[5];
    size_t nnode_balls;
    /* The locus found from f when it is isolated certified points only (no curves, none
     * uncertified, the search complete), each a node or an isolated point: x, y, z, the
     * point's clearance (ism_locus_clearance; INFINITY alone) and its nappes (2 for a node,
     * 0 for an isolated point). The dual mesher then meshes round them (dual_balls.h)
     * instead of declining. NULL otherwise. */
    const double (*dual_points)[5];
    size_t ndual_points;
    /* The locus is points only, but one of them is neither a certified node nor an isolated
     * point (a cusp, a degenerate contact, an uncertified point): the dual mesher declines
     * with its own reason (mesher.h). */
    bool dual_points_other;
    /* Optional progress report, fraction in [0, 1], from the calling thread or a worker
     * thread (serialised by the polygoniser). */
    void (*progress)(void *ctx, double fraction);
    void *progress_ctx;
    /* Optional cancellation: polled often; when it becomes non-zero the call stops with
     * ISM_POLY_CANCELLED. */
    const volatile int *cancel;
    /* Optional deadline, an ism_now_ms() time (0 = none), for the stages that can stop with a
     * partial answer: the singular locus, its double sheets and the conformance pass
     * (core/singular/surface.h) stop past it and mark the locus incomplete. The polygoniser
     * itself does not read it (a partial mesh is no answer; cancel stops it). */
    double deadline_ms;
} ism_poly_options;

#endif
