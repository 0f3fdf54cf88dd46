/* dual.h — under an error bound, a dual-contouring mesh of a surface with nothing to protect:
 * one vertex per octree leaf, within E of f = 0 (the leaf's centre, or the mean of its edge
 * roots, moved there by Newton along ∇f, then to straddle the surface, straddle.h), and a
 * quad across every minimal lattice edge where f changes sign, made of the vertices of the
 * (three or four) leaves round it: two triangles, or four round a centre placed as a vertex
 * is where the two miss E (their longest edges then the quad's sides). A leaf is kept
 * only when its corner gradients agree or interval gradients prove the surface one graph
 * over it (graph_cert.h, dual_cert.h) and its edges and faces are plain: no root on an edge
 * whose ends share a sign, at most one crossing curve per face; a leaf whose corners share a
 * sign must be proven free of f = 0. The leaves at the ends of a triangle's edge whose
 * midpoint lies farther than E (all three for its centroid, or facing against ∇f) are
 * split, and the mesh is made again, until every triangle meets E.
 *
 * The primal polygons (polygonise.h) put vertices on cell edges and need cells half the size
 * for the same error: their chords run along face diagonals. Here a cell of size h makes
 * triangles of sides about h with every vertex within E of the surface (0.9 E off it, on
 * the convex side, where the surface bends one way: straddle.h; the stats' vertex distance
 * reads that, README "Under an error bound"), so the same E is met about a level higher (sphere E = 1e-3: ~4 times fewer triangles before any simplification).
 *
 * Only for closed surfaces without features: no min/max or abs in f (creases), no singular
 * locus known (quiet or node balls given) but isolated certified nodes and isolated points
 * (o->dual_points: a hole round each, clipped and fanned to the point, dual_balls.h); a
 * surface the box cuts (without such points) is meshed in a larger box and clipped by the
 * box's planes (dual_box.h); and
 * only where every triangle meets E before depth.max (two sheets closer than E, where f's
 * gradient nearly cancels between them, do not); the call says "not applicable" otherwise
 * and the caller polygonises as before. The tree's splits, the vertices and the
 * measurements run on o->threads threads; the mesh is the same on any number. */
#ifndef ISM_DUAL_H
#define ISM_DUAL_H

#include <stdint.h>
#include "core/eval/eval.h"
#include "core/mesh/mesh.h"
#include "core/octree/mesher.h"
#include "core/octree/poly_options.h"

enum ism_dual_status {
    ISM_DUAL_OK = 0,
    ISM_DUAL_NOT_APPLICABLE, /* a feature, a leaf the tests cannot make plain, or the box */
    ISM_DUAL_TOO_BIG,        /* o->max_triangles or o->max_memory exceeded */
    ISM_DUAL_NO_MEMORY,
    ISM_DUAL_CANCELLED,
};

typedef struct ism_dual_stats {
    uint64_t rounds;      /* measure-and-split rounds after the first mesh */
    uint64_t missed;      /* triangles beyond E with every leaf at max_depth (then the call
                             says "not applicable") */
    uint64_t leaves;      /* leaves with a vertex */
    uint64_t coarse_nodes; /* the tree's nodes of levels up to depth.min (those its parent's
                              batch shows free are empty leaves, their subtrees never made) */
    uint64_t evals_point, evals_gradient, evals_interval;
    int threads;          /* threads the call ran on (o->threads, 0: every core) */
    enum ism_dual_reason declined; /* why "not applicable" (mesher.h), else NONE */
} ism_dual_stats;

/* May the dual mesh be tried for f under o? (max_error set, no locus, no min/max in f:
 * ism_dual_declined_before, mesher.h; o->dual is not looked at.) */
bool ism_dual_wanted(const ism_tape *f, const ism_poly_options *o);

/* The dual mesh of f = 0 in o->box within o->max_error, into mesh (replaced; initialised by
 * the caller). Deterministic. Anything but ISM_DUAL_OK leaves mesh empty. */
enum ism_dual_status ism_dual_mesh(const ism_tape *f, const ism_poly_options *o, ism_mesh *mesh,
                                   ism_dual_stats *st);

/* ism_dual_mesh as for a box seen to cut the surface at once: made in the grown box from the
 * start (dual_box.h), without the first look or a first tree in o->box. Where ism_dual_mesh
 * finds the cut only in the tree and then makes the mesh again in the grown box, its mesh is
 * this one bit for bit: nothing of the first tree reaches the second (its point memo is
 * emptied, its other memos freed). For the tests (test_dual_box.c). */
enum ism_dual_status ism_dual_mesh_grown(const ism_tape *f, const ism_poly_options *o,
                                         ism_mesh *mesh, ism_dual_stats *st);

#endif
