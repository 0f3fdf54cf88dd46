/* dual_classify.h — what the dual mesher (dual_tree.h's state) makes of one node: empty
 * (proven free of f = 0), a surface leaf with one sheet, or to be split; and the centre's
 * foot (Newton onto f = 0) that sag_split and the vertices start from. */
#ifndef ISM_DUAL_CLASSIFY_H
#define ISM_DUAL_CLASSIFY_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include "core/octree/dual_cert.h"
#include "core/octree/dual_tree.h"
#include "core/octree/straddle.h"

/* What the node's corners and interval say: f and ∇f at the corners, the enclosure of f and
 * ∇f over the box (have_g false when it has a kink), and the corner gradients' agreement. */
typedef struct corner_view {
    double p[8][3], n[8][3];
    ism_ivgrad g;
    ism_dual_model model; /* f's Taylor model over the box (dual_cert.h), when have_model */
    bool have_g, have_model, agree;
    bool kinked;  /* split for the crease (dual_crease.h): at depth.max it declines min_max */
    int monotone; /* bit a: ∇f's a-th component keeps a sign over the box */
    uint8_t placed; /* what sag_split found (dnode.placed); FOOT_AT: the vertex in at */
    double at[3];
    /* In: the centre's foot (foot_in_node) when the split pass took it beforehand with
     * other nodes' (split_pass): FOOT_AT, in foot_at; FOOT_OUT: outside the node (or Newton
     * failed); FOOT_UNKNOWN: not taken (sag_split takes it itself). */
    uint8_t foot;
    double foot_at[3];
    ism_straddle_jet foot_jet; /* with FOOT_AT: f's jet at foot_at (feet_task) */
    /* In: the node's box was shown free of f = 0 by its parent's proofs (the parent's
     * free_kids) or its natural interval (children_free). Out: bit c, child c's box shown
     * free by this node's proofs (dnode). */
    bool known_free;
    uint8_t free_kids;
    /* classify_head's count of corners < 0, for classify_tail */
    int neg;
    /* In: 0, classify_head looks at the corners itself; CORNERS_NOT_FINITE, some corner's f
     * or unit ∇f is not finite; else 1 + the count of corners < 0 (split_task reads them
     * off its 27 points' masks, each point looked at once, not once for each child holding
     * it: sphere at E 1.3e-3, ~720K instructions of classify_head's 3.0M). Every builder
     * of a view must set it (dual.c's mesh_rounds 0, split_task from the masks): a view
     * reused for another node with its old count is classified by that count, unchecked
     * (test_dual_pre compares both paths). */
    uint8_t corners;
    /* In (classify_tail): f and ∇f's natural enclosure over the box is in g already, taken
     * in one batch with the node's siblings' (ism_dual_kid_kinds); classify_head clears it. */
    bool pre_g;
    /* In (classify_tail's first tighten): the Taylor model over the box is in model already
     * (ism_dual_pre_models), pre_ok its ism_dual_taylor answer, and the natural enclosure's
     * tests before it are known to fail (not taken again); classify_head clears it. */
    bool pre_model, pre_ok;
    /* In (classify_tail, pre_g; read only without pre_model): natural_open's answer on the
     * natural enclosure in g, taken by ism_dual_pre_models when it chose the models
     * (pre_open_known; the tail reads it once instead of taking it again: torus at 1e-2,
     * ~1,000 such tests of ~300 instructions); classify_head clears it, and so does each
     * place that replaces g. */
    bool pre_open_known, pre_open;
    /* With pre_model: that model's second-order form over the box (pre_v2) and enclosure
     * (pre_over, pre_over_ok: ism_dual_over's answer), taken in lanes with the other models'
     * (ism_dual_over_many), for the first enclosure the tail takes; classify_head clears it. */
    bool pre_forms, pre_over_ok;
    ism_interval pre_v2;
    ism_ivgrad pre_over;
} corner_view;

/* classify_head's answer when the corners leave the node to classify_tail. */
#define UNDECIDED (-1)
/* corner_view.corners when some corner is not finite. */
#define CORNERS_NOT_FINITE 0xff

/* Are a corner's f and unit ∇f n finite (classify_head's first test)? */
static inline bool ism_dual_corner_finite(double f, const double n[3])
{
    return isfinite(f) && isfinite(n[0] + n[1] + n[2]);
}

/* The edges (ism_edges_across' bits, corners.h) of each face of the cube (ism_cube_edges'
 * face numbers). A constant restating corners.h's ism_cube_edge facts, so that
 * ism_dual_faces_plain stays an inline test of six masks; test_dual_edges derives each mask
 * from ism_cube_edge and fails on any difference (revR 6). */
static const unsigned ISM_DUAL_FACE_EDGES[6] = {0x530, 0xac0, 0x305, 0xc0a, 0x053, 0x0ac};

/* Crossed edges (ism_edges_across) 0 or 2 on every face (one curve): a face's crossed
 * edges are even in number (its corners' signs go round a loop), so a face fails only with
 * all four crossed. */
static inline bool ism_dual_faces_plain(unsigned crossed)
{
    for (int k = 0; k < 6; k++)
        if ((crossed & ISM_DUAL_FACE_EDGES[k]) == ISM_DUAL_FACE_EDGES[k])
            return false;
    return true;
}

/* The node's box from its corners 0 and 7: one builder, since a jet takes a batch's record
 * only for a box equal to the bit (ism_dual_kid_kinds's batch, classify_tail's jet). */
static inline void ism_dual_node_box(const corner_view *v, ism_interval box[3])
{
    for (int a = 0; a < 3; a++)
        box[a] = (ism_interval){v->p[0][a], v->p[7][a]};
}

/* Does the box lo..hi lie in the request's box (always, but in the grown box: dual_box.h)? */
static inline bool in_request_box(const dual *d, const double lo[3], const double hi[3])
{
    for (int a = 0; d->inner && a < 3; a++)
        if (lo[a] < d->inner[a] || hi[a] > d->inner[a + 3])
            return false;
    return true;
}

/* May sag_split split any node at all (the straddle move on, no crease, no points)? Those
 * leaves place vertices otherwise. */
static inline bool sag_may_split_any(const dual *d)
{
    return d->shift > 0 && !d->crease && !d->nballs;
}

/* May sag_split split a node of this level in the box lo..hi: sag_may_split_any, between
 * depth.min and depth.max (classify answers above depth.min before asking sag_split, so
 * min_depth only spares split passes' lanes there), inside the request's box. sag_split
 * and wanted_feet (the split pass's feet taken beforehand) both ask this. */
static inline bool sag_may_split(const dual *d, int level, const double lo[3], const double hi[3])
{
    return sag_may_split_any(d) && level < d->o->max_depth && level >= d->o->min_depth &&
           in_request_box(d, lo, hi);
}

/* Does classify_tail take f and ∇f's enclosure over the node (classify_head UNDECIDED)? */
static inline bool tail_wants_g(const dual *d, const corner_view *v)
{
    return !v->agree || d->crease; /* with a crease, agreeing corners may straddle it */
}

/* What node n is (f and the unit gradients at its corners in n->f and v): DN_EMPTY, a
 * surface leaf (DN_SURF, or DN_CREASE / DN_PAIR with a crease), DN_INNER (to split). In two
 * steps for a split's children (ism_dual_kid_kinds): ism_dual_classify_head answers what the
 * corners (and sag_split) decide, else UNDECIDED, and ism_dual_classify_tail the rest (with
 * v->g taken beforehand when v->pre_g). */
int ism_dual_classify(dual *d, worker *w, dnode *n, corner_view *v);
/* After a batch of natural enclosures (ism_dual_kid_kinds: views[at[k]].pre_g for k < nb,
 * classify_head UNDECIDED), the Taylor models the tails of nodes kids[at[k]] will take (the same
 * test classify_tail makes before its first tighten) made at once (ism_dual_taylor_many), when
 * there are at least two; bit for bit what tighten would make. With each model whose jet succeeded
 * (pre_forms) it leaves its second-order form and enclosure over the node, taken in lanes
 * (ism_dual_over_many: pre_v2, pre_over, pre_over_ok), bit for bit the scalar ones; the tail's
 * node_form (empty_proven's form) and node_over (tighten's enclosure) consume them once. */
void ism_dual_pre_models(worker *w, const dnode *kids, corner_view *views, const int *at,
                         int nb);
int ism_dual_classify_head(dual *d, worker *w, dnode *n, corner_view *v);
int ism_dual_classify_tail(dual *d, worker *w, dnode *n, corner_view *v);

/* Node n's kind after ism_dual_classify and the checks near singular points and on the
 * request's box: empty, a surface leaf, a hole leaf round a singular point, or inner (to
 * split; *bad set when the box cuts the surface there: its faces need the primal polygons). */
int ism_dual_leaf_kind(dual *d, worker *w, dnode *n, corner_view *v, bool *bad);

/* Nodes whose children one task of the split pass's last step classifies together
 * (dual.c split_task, ism_dual_kid_kinds): their natural enclosures and Taylor models are
 * batched across the nodes, so the lanes' groups of four fill. One node's children alone left
 * them part empty: the torus at 1e-2 took its 1,264 natural enclosures in 344 groups and its
 * 664 models in 216 (32 of them alone), at 3.57e-3 3,088 in 960 and 856 in 416. Whole runs
 * (bench_error mesh P E 10 threads=1, callgrind on ism_mesh_surface), 1 / 2 / 4 / 8 nodes a
 * task: torus 1e-2 15.35M / 15.29M / 15.04M / 14.99M, 3.57e-3 34.61M / 34.10M / 33.69M /
 * 33.44M, sphere 1e-2 1.845M / 1.845M / 1.843M / 1.843M, the same meshes. 8: split_task's
 * frame is 67,008 bytes and ism_dual_kid_kinds' 1,328 (gcc -fstack-usage; 64 nodes and
 * views), on a pool thread's stack made with default attributes (core/util/pool.c, and the
 * caller's own thread, which runs tasks too): 8 MB on glibc, but 128 KB on musl, where the
 * proofs below it (ism_dual_kid_kinds -> classify_tail) would have to fit in the rest.
 * A constant, so a task's nodes, and the mesh, do not depend on the threads. */
#define ISM_DUAL_SPLIT_CHUNK 8

/* Of a block of m nodes cut into chunks of ISM_DUAL_SPLIT_CHUNK (the last one shorter),
 * chunk k's first node into *lo; returns its number of nodes (k < the chunks' count). */
static inline size_t ism_dual_chunk(size_t m, size_t k, size_t *lo)
{
    *lo = k * ISM_DUAL_SPLIT_CHUNK;
    return m - *lo < ISM_DUAL_SPLIT_CHUNK ? m - *lo : ISM_DUAL_SPLIT_CHUNK;
}

/* ism_dual_leaf_kind of the children kids[0..8 nodes) of `nodes` <= ISM_DUAL_SPLIT_CHUNK
 * split nodes (views: their corners; node j's children at 8 j ..) into kind, bad[j] set when
 * node j's children meet the request's box (bad[0..nodes) cleared by the caller): every
 * child's classify_head first (but those in empty[j], bit c: node j's child c found DN_EMPTY
 * by split_task from the masks, its view not made), then the natural enclosures the
 * undecided ones' tails take, ISM_IVGRAD_BATCH at a time (bit for bit the box-by-box pass's;
 * each batch's records replace the previous batch's, so only the last batch's boxes find
 * their records again when the Taylor models' jets and the tails' own run over the same boxes
 * — those take the Hessian only, the others the whole second-order pass: a cost, not a
 * difference, as the records are matched by box), then the Taylor models of those whose
 * tails will tighten made at once (ism_dual_pre_models), then the tails and the box's check.
 * Child by child near singular points (ism_dual_leaf_kind's balls come first). */
void ism_dual_kid_kinds(dual *d, worker *w, dnode *kids, corner_view *views,
                        const uint8_t *empty, size_t nodes, int *kind, bool *bad);

/* Where surface leaf n lies on the request's box: -1 when f changes sign between its
 * corners on a face of the box (the box cuts the surface), 1 when f is proven free of 0 on
 * every such face, 0 when neither is known (split it). */
int ism_dual_box_faces_clear(dual *d, worker *w, const dnode *n, const corner_view *v);

/* The centre of the box lo..hi (size across) moved onto f = 0 by Newton into m; true when it
 * stays in the closed box. */
bool ism_dual_foot_in_node(worker *w, const double lo[3], const double hi[3], double size,
                           double m[3]);

/* ism_dual_foot_in_node for n <= ISM_GRAD_BATCH boxes at once (each Newton step's
 * gradients in one batch, bit for bit the scalar run's): m[k] and state[k] (FOOT_AT when the
 * foot lands in the closed box, else FOOT_OUT). */
void ism_dual_feet_in_nodes(worker *w, const double (*lo)[3], const double (*hi)[3],
                            const double *size, size_t n, double (*m)[3], uint8_t *state);

#endif
