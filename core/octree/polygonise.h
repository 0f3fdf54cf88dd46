/* polygonise.h — the non-manifold adaptive octree polygoniser of Balsys & Suffern (2005):
 * one call turns a compiled surface and a search box into a welded, consistently oriented
 * triangle mesh, with statistics that count every case the algorithm could not resolve. */
#ifndef ISM_POLYGONISE_H
#define ISM_POLYGONISE_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>
#include "core/expr/expr.h"
#include "core/mesh/mesh.h"
#include "core/octree/grid.h"
#include "core/octree/mesher.h"
#include "core/octree/poly_options.h"

/* Hard limit of depth.max (cells are addressed by integer coordinates on a lattice that also
 * holds the levels below it, ISM_THIN_EXTRA_DEPTH). */
#define ISM_MAX_DEPTH_LIMIT 16
/* How far below depth.max a piece of the surface thinner than a cell is followed when
 * thin_search is on (the octree splits a node whose corners cannot see a piece it holds,
 * thin_search.h). A tube of radius r stops being chased where it crosses the cells' edges,
 * about where cells are 2r across; a horn shrinking to a singular point is followed to the
 * conformance ball around the point (the `quiet` balls below). The horn cyclide's horns,
 * radius y²/96 at distance y from the point, are 1/16 of a cell 3 levels below depth 8 where
 * they reach the ball (0.31 at depth 8): 8 levels keep them tubes at depths 6-9 in boxes off
 * the lattice (3 left holes and detached horns). Capped by the lattice (ISM_GRID_MAX_DEPTH). */
#define ISM_THIN_EXTRA_DEPTH 8
/* ... and this far when the caller gives no `quiet` balls (the polygoniser alone, without the
 * singular locus): near a singular point the chase would go to the last level, and the cells
 * it leaves there are not rebuilt by anyone. */
#define ISM_THIN_BLIND_DEPTH 3


void ism_poly_options_default(ism_poly_options *o);

/* Checks an options struct; false with a message naming the bad field. */
bool ism_poly_options_check(const ism_poly_options *o, ism_error *err);

/* Phases timed in the statistics: building the octree; registering leaf corners on lattice
 * lines (what makes crack repair exact); polygonising the nodes (face lines, stitching,
 * triangles — crack repair happens here by construction); welding into one mesh. */
enum ism_poly_phase { ISM_PHASE_OCTREE, ISM_PHASE_POLYGONS, ISM_PHASE_CRACKS, ISM_PHASE_MESH,
                      ISM_PHASE_COUNT };

typedef struct ism_poly_stats {
    enum ism_mesher mesher;      /* which mesher made the mesh (mesher.h) */
    enum ism_dual_reason dual_declined; /* when not the dual one, why (NONE when it did) */
    uint64_t nodes_visited;      /* octree nodes examined */
    uint64_t nodes_excluded;     /* nodes whose interval proved them empty */
    uint64_t plotting_nodes;     /* leaves that produced polygons */
    uint64_t unresolved_nodes;   /* leaves at max depth that failed flatness or polygonisation */
    uint64_t unflat_nodes;       /* without max_error: of those, the ones a larger depth.max
                                    could improve: not on a crease (min/max) nor meeting or
                                    beside the singular locus's balls and tubes
                                    (ISM_NODE_UNFLAT), their
                                    emitted triangles farther from the surface than the
                                    flatness test allows a node of their size */
    double unflat_worst;         /* the largest distance measured on them (centroids and edge
                                    midpoints, |f| / |∇f|; 0 when none) */
    uint64_t thin_searched;      /* would-be leaves whose corners all had one sign, searched
                                    for a piece of the surface they hide (thin_search.h) */
    uint64_t thin_found;         /* ... that hid one, and were split (below max depth too) */
    uint64_t thin_undecided;     /* ... where the search with interval proofs could neither
                                    find nor exclude one (Newton probes, which cannot
                                    exclude, are not counted when they find nothing) */
    uint64_t deep_leaves;        /* leaves below max depth (meshing the hidden pieces) */
    uint64_t leaf_tapes;         /* distinct tapes shortened over leaves (octree.h) */
    uint64_t short_tape_leaves;  /* leaves evaluating one of them instead of f */
    uint64_t tape_misses;        /* leaves whose shortened tape found no room (a limit of
                                    octree.h): they evaluate f */
    uint64_t error_missed_nodes; /* under max_error: leaves whose emitted triangles were
                                    measured farther than max_error from the surface (at
                                    centroids and edge midpoints) and could not be split:
                                    at max depth, or after the last round */
    double error_worst;          /* the largest such distance (0 when none) */
    uint64_t error_rounds;       /* rounds after the first, each splitting such leaves */
    uint64_t edges_single_root;  /* node edges with one root */
    uint64_t edges_double_root;  /* node edges with two roots (paper's bisection) */
    uint64_t edges_touching;     /* edges with a double (tangent) root |f(c)| < eps */
    uint64_t edges_many_roots;   /* edges suspected to hold more than two roots (paper's
                                    known failure case: counted, never hidden) */
    uint64_t zero_vertices;      /* node vertices where f is exactly 0 */
    uint64_t polygons;           /* polygons made by stitching */
    uint64_t two_polygon_nodes;  /* plotting nodes with two polygons */
    uint64_t degenerate_polygons;/* one-edge polygons (kept, paper §4) */
    uint64_t nonmanifold_lines;  /* face lines shared by two polygons */
    uint64_t open_chains;        /* line chains that could not be closed into a polygon */
    uint64_t cracks_repaired;    /* coarse face lines replaced by finer neighbours' lines */
    uint64_t singular_points;    /* isolated singular points found inside nodes (cone apexes,
                                    Kummer nodes): the node's polygons meet there */
    uint64_t crossed_faces;      /* faces where two sheets cross inside (an X of face lines):
                                    the node's polygons intersect (paper Fig. 1a) */
    uint64_t lifted_polygons;    /* polygons lying in a node's face, fanned from the surface
                                    point above them on the node's side (face_flat.h) */
    uint64_t lifted_chords;      /* face lines along one side of their tile, taken through
                                    their arc's point across the tile (face_flat.h) */
    uint64_t quiet_skips;        /* tiles a node did not walk: the thread walked them before
                                    and nothing crossed them (cell_cache.h's quiet memo) */
    uint64_t tile_replays;       /* tiles a node did not walk: their lines copied from the
                                    thread's first walk (cell_cache.h's crossed-tile memo) */
    uint64_t corner_quiets;      /* tiles a node did not walk: quiet by their corners alone
                                    (face_lines.c quiet_by_corners) */
    uint64_t corner_checks;      /* under walk_every_tile (for tests): tiles quiet by their
                                    corners alone, walked all the same and checked against
                                    the walk (face_lines.c check_by_corners) ... */
    uint64_t corner_mismatches;  /* ... and those checks, of any tile walked, that failed: the
                                    corners' answer and the walk's differ (0 where f is finite) */
    uint64_t corner_values;      /* lattice points whose f and ∇f the cells took from the
                                    octree build's corner memo instead of evaluating them
                                    (octree_build.h's corner_memos), over all rounds */
    uint64_t evals_point;        /* f evaluations */
    uint64_t evals_interval;     /* interval evaluations */
    uint64_t evals_gradient;     /* gradient evaluations */
    uint64_t triangles;
    uint64_t vertices;
    int threads;                 /* threads actually used */
    double time_ms[ISM_PHASE_COUNT];
    /* CPU per phase in milliseconds (every thread's, CLOCK_THREAD_CPUTIME_ID), the part of it
     * the calling thread spent outside parallel loops, and two critical paths: that serial
     * part plus, per parallel loop, its busiest thread's CPU (the phase's wall time on idle
     * cores, as the threads were scheduled), or plus per loop the even share (parallel.h: a
     * fair split of the same tasks). Unlike time_ms, none is stretched by other processes. */
    double cpu_ms[ISM_PHASE_COUNT], serial_ms[ISM_PHASE_COUNT], critical_ms[ISM_PHASE_COUNT];
    double even_ms[ISM_PHASE_COUNT];
    double total_ms;
} ism_poly_stats;

enum ism_poly_status {
    ISM_POLY_OK = 0,
    ISM_POLY_BAD_OPTIONS,   /* err says which */
    ISM_POLY_TOO_BIG,       /* triangle budget or memory bound exceeded */
    ISM_POLY_CANCELLED,
    ISM_POLY_NO_MEMORY,
    ISM_POLY_INTERNAL,      /* a broken invariant (err says which): a bug, never the input's
                               fault; e.g. a tile's side met a lattice point the break-point
                               registry (ism_breaks_near's partial one) does not hold */
};

/* Polygonises f = 0 inside o->box. The mesh is replaced (mesh must be initialised). The
 * output is deterministic: identical for any number of threads. */
enum ism_poly_status ism_polygonise(const ism_tape *f, const ism_poly_options *o,
                                    ism_mesh *mesh, ism_poly_stats *stats, ism_error *err);

#endif
