/* sampler.h — one thread's access to f during polygonisation: the compiled tape, that
 * thread's evaluation workspace, and counters of every kind of evaluation (the statistics
 * report them), and the first-order distance to f = 0 measured through it
 * (ism_first_order_dist, core/util/dist_bound.h). */
#ifndef ISM_SAMPLER_H
#define ISM_SAMPLER_H

#include <stdbool.h>
#include <stdint.h>
#include <math.h>
#include "core/eval/eval.h"
#include "core/util/dist_bound.h"
#include "core/util/vec3.h"

/* Entries of the sampler's label memo (a leaf labels a few dozen points; its neighbours share
 * a face's, some leaves later in node order). Barth's sextic at 1e-2 (callgrind, one thread,
 * ism_mesh_surface): label_at 123.6M without the memo, 94.0M with 64 entries, 79.5M with
 * 1,024 (40 KB a thread). */
#define ISM_LABEL_MEMO 1024

typedef struct ism_sampler {
    const ism_tape *tape;
    ism_eval_ws *ws;
    /* Optional: a tape that gives tape's values and gradients bit for bit at the points of
     * the closed box local_box (lo xyz, hi xyz) — a leaf's tape shortened by intervals over
     * its box (octree.h) — used there by ism_sample_f / ism_sample_grad; NULL for none. */
    const ism_tape *local;
    double local_box[6];
    /* crease_split.c's answer for local over local_box (its deciding_local: local when it
     * holds f to one label there, else NULL), looked up at its first use in a leaf and kept
     * while local is (valid when local_decided; whoever sets local clears that). */
    const ism_tape *local_deciding;
    bool local_decided;
    /* ism_sample_dist_between (sample_dist.h) seeks the bound through the corners only where
     * the estimate passes this: the polygoniser's max_error, which every figure it measures
     * is held against (one within it needs no bound; seeking it everywhere cost the Klein
     * bottle's default run 1.6% more instructions for the same mesh); 0: wherever. */
    double dist_above;
    /* ism_dist_capped searches rays for the nearest sheet (core/analysis/nearest.h) from the
     * points still beyond dist_above after Newton's foot whose |∇f| is below this: INFINITY
     * where the caller knows a singular locus (∇f vanishes on the surface there, and beside it
     * the estimate and the foot overstate), 0 elsewhere (the foot only). */
    double rays_below;
    /* Points a caller holds together (a leaf's triangles' centroids and midpoints, or
     * several leaves' at once, each on its own leaf's tape: refine.h's ism_emitted_errors)
     * are evaluated in passes over each tape (ism_sample_grad_batch, _tapes): bit for bit
     * the values one point at a time gives (eval.h), for less. It also decides a path:
     * polygonise.c defers a leaf's measuring to measure it with the next leaves' only when
     * batch is on. Off on the scalar reference path (poly_options.h's scalar_eval), which
     * therefore measures leaf by leaf, and which the tests compare with it. */
    bool batch;
    /* crease_split.c: a mixed edge at most this long may take its crease point as far as a
     * thin wedge puts it (|pq| / sin w): under max_error the diagonal of a cell one level
     * above depth.max (ism_crease_wedge_edges); 0: one edge's length only. */
    double wedge_edges_below;
    /* crease_split.c: f's crease read off its smooth pieces (ism_crease_pieces: kinks below
     * its top min/max, or a min/max passed on); false: f's top min/max's two branches. Set
     * with wedge_edges_below (asked once per run, not per leaf: the tape scan cost gyroid-ball
     * +1.5% instructions). */
    bool crease_pieces;
    /* crease_split.c, pieces mode: a mixed edge is left whole, the crease folded there, where
     * |f|/|∇f| at the point its pieces' values cross along it is within this and their wedge
     * passes CREASE_FOLD_COS (whole_edge; ism_crease_fold_below: a share of max_error); 0:
     * no edge folded. */
    double fold_below;
    /* crease_split.c's memos (label_memo, crease_memo) serve only while tape is this one
     * (f: set by polygonise.c, whose tape stays f for the run, and by the octree build, whose
     * nodes swap shortened tapes in and out of one buffer — a shortened tape holds f only
     * inside its node, and a buffer's contents change); NULL: none (the scalar reference
     * path, poly_options.h's scalar_eval). */
    const ism_tape *memo_tape;
    /* crease_split.c, while tape is memo_tape: the last labels looked up (ism_eval_piece of
     * tape at p in pieces mode, else the top branch at p), direct-mapped by p's bits; an
     * entry counts only for the tape it names (zeroed: none). A leaf labels a vertex up to
     * three times (its polygon cut, its triangles split, the crease test), and its
     * neighbours the shared ones again. */
    struct ism_label_memo {
        double p[3];
        const ism_tape *tape;
        uint64_t label;
    } label_memo[ISM_LABEL_MEMO];
    /* crease_split.c: mixed edges' crease points (crease_memo.h), the thread's for one
     * max_error round (polygonise.c's one_round, through the octree build and the
     * polygonisation; none on the scalar reference path), used while tape is memo_tape;
     * NULL: every crease point computed afresh. */
    struct ism_crease_memo *crease_memo;
    uint64_t n_point, n_gradient, n_interval;
} ism_sampler;

/* The tape to evaluate at p: the local one inside its box, else f's. */
static inline const ism_tape *ism_sampler_tape_at(const ism_sampler *s, const double p[3])
{
    const double *b = s->local_box;
    if (s->local && p[0] >= b[0] && p[1] >= b[1] && p[2] >= b[2] && p[0] <= b[3] &&
        p[1] <= b[4] && p[2] <= b[5])
        return s->local;
    return s->tape;
}

static inline double ism_sample_f(ism_sampler *s, const double p[3])
{
    s->n_point++;
    return ism_eval_point(ism_sampler_tape_at(s, p), s->ws, p[0], p[1], p[2]);
}

static inline double ism_sample_grad(ism_sampler *s, const double p[3], double g[3])
{
    s->n_gradient++;
    return ism_eval_gradient(ism_sampler_tape_at(s, p), s->ws, p[0], p[1], p[2], g);
}

/* The sampler's leaf (its local tape, box and crease_split.c's answer for them), kept while
 * other leaves are polygonised and put back to measure the leaf (polygonise.c's deferred
 * measuring, refine.h's ism_emitted_errors). */
typedef struct ism_sampler_leaf {
    const ism_tape *local, *deciding;
    double box[6];
    bool decided;
} ism_sampler_leaf;

static inline void ism_sampler_leaf_get(const ism_sampler *s, ism_sampler_leaf *l)
{
    l->local = s->local;
    l->deciding = s->local_deciding;
    l->decided = s->local_decided;
    for (int k = 0; k < 6; k++)
        l->box[k] = s->local_box[k];
}

static inline void ism_sampler_leaf_set(ism_sampler *s, const ism_sampler_leaf *l)
{
    s->local = l->local;
    s->local_deciding = l->deciding;
    s->local_decided = l->decided;
    for (int k = 0; k < 6; k++)
        s->local_box[k] = l->box[k];
}

/* No leaf: f's tape everywhere (whoever sets local clears local_decided). */
static inline void ism_sampler_leaf_clear(ism_sampler *s)
{
    s->local = NULL;
    s->local_decided = false;
}

/* f and ∇f at p[i] into f[i], g[i] for i < n, each through the tape ism_sample_grad would
 * use there: in batches when s->batch, else one point at a time (the same values bit for
 * bit). */
void ism_sample_grad_batch(ism_sampler *s, const double (*p)[3], double *f, double (*g)[3],
                           size_t n);

/* f and ∇f at p[i] into f[i], g[i] for i < n through tape[i] (the one ism_sample_grad
 * would use there for the point's own leaf: points of several leaves measured together):
 * the points on one tape evaluated together, in passes of at most ISM_GRAD_UNROLLED, so
 * the same values bit for bit (eval.h) with fewer, fuller passes; one at a time when
 * !s->batch. tape[] is used up (its entries set to NULL). */
void ism_sample_grad_tapes(ism_sampler *s, const ism_tape **tape, const double (*p)[3],
                           double *f, double (*g)[3], size_t n);

/* ism_first_order_dist of f and ∇f at p. */
static inline double ism_sample_dist(ism_sampler *s, const double p[3])
{
    double g[3];
    double f = ism_sample_grad(s, p, g);
    return ism_first_order_dist(f, g);
}

/* A lattice point whose first-order distance to f = 0 is under this fraction of a finest
 * lattice step is asked whether f's sign there is rounding noise (one interval over the
 * point). Rounding moves f by some ulps of its terms: roots that near a lattice point are
 * 1e-15 of a unit box away; 1e-9 of a step keeps the interval off every other point. */
#define ISM_ZERO_ROUNDING_NEAR 1e-9

/* Is f at lattice point p (value f, |∇f| gn; step: the finest lattice step) zero within its
 * rounding: the outward-rounded interval of f over the point itself holds 0, so the sign the
 * evaluation gave is noise? Asked only where the surface passes nearer than
 * ISM_ZERO_ROUNDING_NEAR of a step (first order): elsewhere the sign is far above any
 * rounding. The primal tiles (face_lines.c) and the dual mesher's corners (dual.c) then take
 * f there as 0, the same for every cell sharing the point. */
static inline bool ism_sample_zero_by_rounding(ism_sampler *s, const double p[3], double f,
                                               double gn, double step)
{
    if (!(fabs(f) <= ISM_ZERO_ROUNDING_NEAR * gn * step))
        return false;
    s->n_interval++;
    ism_interval r = ism_eval_interval(ism_sampler_tape_at(s, p), s->ws,
                                       (ism_interval){p[0], p[0]}, (ism_interval){p[1], p[1]},
                                       (ism_interval){p[2], p[2]});
    return r.lo <= 0 && r.hi >= 0;
}

/* -1, 0 or +1. */
static inline int ism_sign(double v) { return (v > 0) - (v < 0); }

#endif
