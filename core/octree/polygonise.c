/* polygonise.c — the polygoniser's driver: checks the options, builds the octree (phase 1),
 * registers the leaves' corners on their lattice lines, polygonises every candidate node in
 * parallel chunks (phase 2: face lines, stitching, crack repair, triangles), welds the
 * chunks in order (phase 3), and fills the statistics. */
#include "core/octree/polygonise.h"
#include "core/octree/node_balls.h"
#include "core/octree/tolerances.h"
#include "core/util/clock.h"
#include "core/util/grow.h"
#include "core/octree/breaks.h"
#include "core/octree/breaks_near.h"
#include "core/octree/cell.h"
#include "core/octree/crease_memo.h"
#include "core/octree/crease_split.h"
#include "core/octree/dual.h"
#include "core/octree/cell_stats.h"
#include "core/octree/leaf_memo.h"
#include "core/octree/octree_build.h"
#include "core/octree/quiet.h"
#include "core/octree/refine.h"
#include "core/octree/root_table.h"
#include "core/octree/straddle.h"
#include "core/octree/weld.h"
#include "core/util/parallel.h"
#include "core/util/zeroed.h"

#include <math.h>
#include <pthread.h>
#include <stdalign.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

/* Leaves come in depth-first order, so a run of them is a compact piece of space whose
 * nodes share corners and edges, and each thread's memo (cell_cache.h) serves its
 * neighbours only when they land on the same thread. Chunks are therefore long: about
 * CHUNKS_PER_THREAD per thread (enough to even out the load), never under MIN_CHUNK_LEAVES
 * (the weld and the progress reports work chunk by chunk). Short chunks handed out in turn
 * cost 2 threads a quarter more evaluations on the gyroid. */
#define CHUNKS_PER_THREAD 16
#define MIN_CHUNK_LEAVES 64
/* A leaf's centroid gradients kept on the stack up to this many triangles (a leaf makes a
 * few to a few dozen; more are malloc'd). */
#define CENTROIDS_ON_STACK 64
/* The flatness tolerance (edge roots off their plane, their centroid off the surface) is
 * plane_frac × node size but never more than this fraction of the finest cell h. Without the
 * cap a large node that is flat enough relative to its own size stays coarse whatever
 * depth.max asks, so a deeper request would not refine it. A quarter: with the default
 * plane_frac 0.05 the cap binds only on nodes at least 5 finest cells across (0.05 × 5h =
 * h/4), so nodes at the finest levels keep the paper's test, while a coarse node must lie
 * within h/4 of its plane and of the surface — less than the finest cells' own vertex
 * spacing shows; a smaller fraction splits flat regions toward depth.max for no visible
 * gain. Overridable at build time (-DISM_FLAT_ABS_FRACTION=...) to measure other values. */
#ifndef ISM_FLAT_ABS_FRACTION
#define ISM_FLAT_ABS_FRACTION 0.25
#endif

/* The flatness test's cap in world units (above). */
static double flat_abs_tol(const ism_octree *tree, const ism_poly_options *o)
{
    return ISM_FLAT_ABS_FRACTION * ism_grid_cell_size(&tree->grid, o->max_depth);
}
/* Under max_error, up to this many rounds of octree + polygons, each splitting the leaves
 * whose triangles measured farther than the bound (a leaf's polygons depend on its
 * neighbours' tiles, which the octree's estimate cannot see, and a split changes its
 * neighbours' polygons in turn). Measured: the torus at E = 6e-4 needs 4 more rounds, the
 * gyroid ball at 1e-2 one, the sphere none; what is left is counted (error_missed_nodes). */
#define ISM_ERROR_ROUNDS 6
#define BYTES_PER_TRIANGLE 256 /* node outputs + welded mesh + analysis, per triangle */
/* The build's edge roots handed to the cells (root_table.h) may hold 1/ROOT_MEMORY_SHARE of
 * max_memory at ISM_ROOT_BYTES a root, a share of the budget as the nodes have theirs (a
 * quarter: max_nodes); small, since the cache is only speed (past it the cells search for
 * themselves: the same mesh). 1/16 of the default
 * 2 GiB is ~0.9M roots, 29x Barth's sextic's 31,390 at E 1e-2: no gallery run reaches it. */
#define ROOT_MEMORY_SHARE 16

void ism_poly_options_default(ism_poly_options *o)
{
    memset(o, 0, sizeof *o);
    double box[6] = {-1, -1, -1, 1, 1, 1};
    memcpy(o->box, box, sizeof box);
    o->min_depth = 3;
    o->max_depth = 7;
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++)
        ism_tolerance_set(o, &ism_tolerances[i], ism_tolerances[i].def);
    o->max_triangles = 4000000;
    o->max_memory = (size_t)2 << 30;
    o->threads = 0;
    o->thin_search = true;
}

static bool in_range(double v, double lo, double hi) { return isfinite(v) && v >= lo && v <= hi; }

bool ism_poly_options_check(const ism_poly_options *o, ism_error *err)
{
    for (int k = 0; k < 6; k++)
        if (!isfinite(o->box[k]))
            return ism_error_set(err, "box: coordinate %d is not a finite number", k);
    for (int k = 0; k < 3; k++)
        if (!(o->box[3 + k] > o->box[k]))
            return ism_error_set(err, "box: max must be greater than min on axis %c", "xyz"[k]);
    if (o->min_depth < 0 || o->min_depth > ISM_MAX_DEPTH_LIMIT)
        return ism_error_set(err, "depth.min: %d is outside 0..%d", o->min_depth,
                             ISM_MAX_DEPTH_LIMIT);
    if (o->max_depth < o->min_depth || o->max_depth > ISM_MAX_DEPTH_LIMIT)
        return ism_error_set(err, "depth.max: %d is outside %d..%d", o->max_depth, o->min_depth,
                             ISM_MAX_DEPTH_LIMIT);
    for (int i = 0; i < ISM_TOLERANCE_COUNT; i++) {
        const ism_tolerance *t = &ism_tolerances[i];
        if (!ism_tolerance_accepts(t, ism_tolerance_get(o, t)))
            return ism_error_set(err, "%s: must be in [%g, %g]", t->field, t->lo, t->hi);
    }
    if (!in_range(o->max_error, 0, 1e300))
        return ism_error_set(err, "max_error: must be a finite number >= 0 (0: off)");
    if (o->threads < 0 || o->threads > ISM_MAX_THREADS)
        return ism_error_set(err, "threads: must be in 0..%d", ISM_MAX_THREADS);
    if (o->max_triangles < 1)
        return ism_error_set(err, "max_triangles: must be at least 1");
    if (!in_range(o->deadline_ms, 0, 1e300))
        return ism_error_set(err, "deadline_ms: must be a finite number >= 0 (0: none)");
    if (o->nnode_balls > ISM_NODE_BALLS_MAX || (o->nnode_balls && !o->node_balls))
        return ism_error_set(err, "node_balls: at most %d, and given", ISM_NODE_BALLS_MAX);
    if (o->ndual_points && !o->dual_points)
        return ism_error_set(err, "dual_points: given with their count");
    return true;
}

/* The distance vertices move under the straddle option (straddle.h), 0 when they stay. */
static double straddle_shift(const ism_tape *f, const ism_poly_options *o)
{
    return o->straddle ? ism_straddle_shift(f, o->max_error, o->nquiet || o->nnode_balls) : 0;
}

/* Progress reports from several threads, mapped into one [0, 1] range. */
typedef struct progress {
    const ism_poly_options *o;
    pthread_mutex_t lock;
    double from, span;
} progress;

static void report(void *ctx, double fraction)
{
    progress *p = ctx;
    if (!p->o->progress)
        return;
    pthread_mutex_lock(&p->lock);
    p->o->progress(p->o->progress_ctx, p->from + p->span * fraction);
    pthread_mutex_unlock(&p->lock);
}

/* Under max_error, where no leaf is polygonised twice (the crease cut on: no fold test's
 * retry) and nothing moves the vertices, a leaf's triangles are measured with the next
 * leaves' (ism_emitted_errors: a leaf measures ~9 points, the batched gradient evaluator's
 * passes take 16 and cost nearly as much for fewer): the leaves polygonised since the last
 * measuring are measured once they hold PENDING_TRIANGLES triangles, or PENDING_LEAVES
 * leaves (the room kept), or the chunk ends. Only when the sampler batches (sampler.h's
 * batch): the scalar reference path measures leaf by leaf as before, so batch_identity
 * compares the deferred measuring with the leaf-by-leaf one. A leaf's figure reaches
 * nothing another leaf's polygons read (the memos it fills are exact: crease_memo.h,
 * sampler.h's label memo), so the meshes are those measured leaf by leaf. */
/* PENDING_TRIANGLES, callgrind --toggle-collect=ism_mesh_surface of bench_error mesh
 * gyroid-ball 0.00109 10 repeat=1 threads=1 (2,345.9M measured leaf by leaf): 16 triangles
 * 2,323.5M, 48 2,317.5M, 128 2,316.5M — past 48, 0.04% for more scratch. PENDING_LEAVES
 * only sizes the arrays (span[] and pending[]: 248 bytes a leaf, ~8 KB a thread at 32): 32
 * leaves hold 48 triangles at 1.5 a leaf, so the triangles, not the room, end a batch unless
 * the leaves emit fewer than that on average. */
#define PENDING_LEAVES 32
#define PENDING_TRIANGLES 48

/* A leaf polygonised and not yet measured: where its output went (ism_leaf_rec's fields
 * but its triangles, which its span holds) and the counters it added. */
typedef struct pending_leaf {
    size_t i, v0, s0, nverts, nsegs;
    ism_cell_stats added;
} pending_leaf;

/* A thread's context in cache lines of its own: the counters and scratch lengths a thread
 * writes for every node and evaluation do not share a line with another thread's. */
typedef struct padded_ctx {
    alignas(ISM_CACHE_LINE) ism_cell_ctx c;
    uint64_t unflat;             /* ism_poly_stats.unflat_nodes, this thread's */
    double unflat_worst;
    /* the leaves waiting to be measured (PENDING_LEAVES) and their triangles */
    ism_leaf_span span[PENDING_LEAVES];
    pending_leaf pending[PENDING_LEAVES];
    size_t npending, pending_tris;
    ism_measure_scratch measure;
    /* what this thread's chunks of the round have held so far (chunk_room) */
    size_t seen_leaves, seen_verts, seen_tris;
} padded_ctx;

typedef struct phase2 {
    const ism_poly_options *o;
    const ism_octree *tree;
    ism_breaks *breaks;          /* built once the leaves to copy are known */
    int32_t *leaves;
    size_t nleaves, nchunks, chunk_leaves;
    ism_cell_out *out;           /* one per chunk */
    padded_ctx *ctx;             /* one per thread */
    size_t max_triangles;
    atomic_size_t triangles;
    atomic_size_t chunks_done;
    atomic_int status;           /* enum ism_poly_status */
    progress *prog;
    float *leaf_error;           /* under max_error: what each leaf's triangles measured */
    double flat_abs;             /* without it: the flatness test's abs_tol (plot_test.h) */
    double straddle;             /* > 0: vertices are moved by this much (straddle.h) */
    const ism_leaf_memo *memo;   /* the last round's leaves, or NULL */
    const int32_t *reuse;        /* per leaf: its leaf in memo to copy, or -1; or NULL */
    ism_leaf_rec *rec;           /* per leaf: where its output went, when another round may
                                    follow; else NULL */
    ism_quiet quiet;             /* without max_error: o->quiet indexed (measure_unflat) */
    bool last_round;             /* under max_error: no round follows to split a leaf */
} phase2;

/* The leaf's shortened tape (octree.h) for the sampler inside the leaf's closed box. */
static void leaf_sampler(ism_cell_ctx *cx, int32_t leaf)
{
    const ism_node *nd = &cx->tree->nodes[leaf];
    ism_sampler_leaf l = {.local = ism_leaf_tape(cx->tree, nd), .decided = false};
    int32_t steps = ism_grid_cell_steps(&cx->tree->grid, nd->level);
    for (int a = 0; a < 3; a++) {
        l.box[a] = ism_grid_coord(&cx->tree->grid, a, nd->org[a]);
        l.box[3 + a] = ism_grid_coord(&cx->tree->grid, a, nd->org[a] + steps);
    }
    ism_sampler_leaf_set(&cx->s, &l);
}

/* Without max_error: a leaf marked ISM_NODE_UNFLAT (octree_build.c) whose emitted
 * triangles (from t0 on) lie farther from the surface than the flatness test allows a node
 * of its size, at their centroids and edge midpoints (|f| / |∇f|, ism_emitted_error: what
 * the analysis's accuracy block measures), is counted with its distance — unless it is
 * beside the singular locus: a quiet ball's centre within 1 / (4 flat_plane) of its sizes
 * (why: octree_build.c unflat; a leaf a ball meets is not marked). That question is asked
 * last, of the few leaves measured beyond the tolerance (Steiner's Roman surface: 564 of
 * 43,364 unresolved leaves). */
static void measure_unflat(const phase2 *p, padded_ctx *pc, int32_t leaf,
                           const ism_cell_out *out, size_t t0)
{
    const ism_node *nd = &p->tree->nodes[leaf];
    if (!(nd->flags & ISM_NODE_UNFLAT) || out->ntris == t0)
        return;
    double tol = ism_flat_tolerance(p->o->flat_plane, p->flat_abs,
                                    ism_grid_cell_size(&p->tree->grid, nd->level));
    double e = ism_emitted_error(&pc->c.s, out, t0, INFINITY);
    if (!(e > tol))
        return;
    const double *box = pc->c.s.local_box; /* the leaf's lo (0..2) and hi (3..5), as built */
    double pf = p->o->flat_plane, cone = pf > 0 ? (box[3] - box[0]) / (4 * pf) : 0;
    if (ism_quiet_near(&p->quiet, box, box + 3, cone))
        return;
    pc->unflat++;
    if (isfinite(e) && e > pc->unflat_worst)
        pc->unflat_worst = e;
}

/* Under max_error: leaf i may still be split (a later round follows and it is above
 * depth.max). */
static bool leaf_may_split(const phase2 *p, size_t i)
{
    return p->leaf_error && !p->last_round &&
           p->tree->nodes[p->leaves[i]].level < p->o->max_depth;
}

/* Leaf i polygonised into out (its output from vertex v0 and triangle t0 on) and, under
 * max_error, cut along a CSG crease and measured into *e; *unresolved: ism_crease_unresolved's
 * verdict on its triangles, asked when they meet max_error and the crease test applies (it
 * then makes *e infinite: the leaf is split) or fold_test is set. */
static bool leaf_measured(phase2 *p, ism_cell_ctx *cx, size_t i, ism_cell_out *out, size_t v0,
                          size_t t0, bool fold_test, double *e, bool *unresolved)
{
    bool ok = ism_cell_polygonise(cx, p->leaves[i], out) &&
              /* under max_error: cut along a CSG crease before measuring */
              (!p->leaf_error || ism_crease_split(&cx->s, out, t0));
    *e = 0;
    *unresolved = false;
    /* the crease test below may take the measuring's centroid gradients (not the
       straddle's: it measures moved vertices) */
    bool crease_test = leaf_may_split(p, i);
    bool ask = crease_test || fold_test;
    double(*cg)[3] = NULL, cg_stack[CENTROIDS_ON_STACK][3];
    if (ok && p->leaf_error && p->straddle > 0) {
        ok = ism_straddle_emitted_error(&cx->s, p->straddle, p->o->box, out, v0, t0, e);
    } else if (ok && p->leaf_error) {
        size_t n = out->ntris - t0;
        cg = !ask                       ? NULL
             : n <= CENTROIDS_ON_STACK ? cg_stack
                                       : malloc(n * sizeof *cg); /* NULL: sampled again */
        *e = ism_emitted_error_kept(&cx->s, out, t0, INFINITY, cg);
    }
    /* a crease the leaf's triangles do not follow (a triangle turned against ∇f, a
       bump of the other branch between corners, a chord of the crease E / 2 off it):
       split while the leaf may be; at depth.max or in the last round what was measured
       stands (without it the gyroid ball at E = 3e-3, depth 9, had 6–12 edge midpoints
       no zero was proved within E of, test_polygonise_accuracy.c; marked in the last
       round, 6 leaves of the gyroid ball at E = 1e-4 within E by the closed forms were
       counted missed with an infinite worst distance) */
    if (ok && ask && *e <= p->o->max_error)
        *unresolved = ism_crease_unresolved(&cx->s, out, t0, p->o->max_error,
                                            (const double(*)[3])cg);
    if (crease_test && *unresolved && *e <= p->o->max_error)
        *e = INFINITY;
    if (cg != cg_stack)
        free(cg);
    return ok;
}

/* Leaf i's first attempt (its output from v0, t0, s0 on; its stats were *before) undone
 * and the leaf polygonised and measured into *e again, as cx now says (one_leaf's retries:
 * with the crease cut, or back to the fan); no fold test. Only cx->stats is reset: the
 * thread's cache and memo counters (quiet_skips, tile_replays, corner_quiets, corner_values,
 * corner_checks) count both attempts, as they count the work done. The fold test that asks
 * for a retry costs little where no leaf folds: steiner-roman (locus known, default bound, one
 * thread) spends 2.35M in ism_crease_split and 1.43M in ism_crease_unresolved of
 * ism_polygonise's 1,479.5M (0.26%, callgrind). */
static bool leaf_again(phase2 *p, ism_cell_ctx *cx, size_t i, ism_cell_out *out, size_t v0,
                       size_t t0, size_t s0, const ism_cell_stats *before, double *e)
{
    bool unresolved;
    out->nverts = v0, out->ntris = t0, out->nsegs = s0;
    cx->stats = *before;
    return leaf_measured(p, cx, i, out, v0, t0, false, e, &unresolved);
}

/* The pending leaves of chunk (all in out) measured as leaf_measured measures them with
 * fold_test off: their figures into p->leaf_error (and p->rec). */
static bool measure_pending(phase2 *p, padded_ctx *pc, size_t chunk, const ism_cell_out *out)
{
    ism_sampler *s = &pc->c.s;
    size_t n = pc->npending;
    pc->npending = pc->pending_tris = 0;
    if (!n)
        return true;
    if (!ism_emitted_errors(s, out, pc->span, n, &pc->measure))
        return false;
    double E = p->o->max_error;
    for (size_t k = 0; k < n; k++) {
        const ism_leaf_span *sp = &pc->span[k];
        const pending_leaf *pl = &pc->pending[k];
        ism_cell_out view = *out; /* the leaf's triangles end its output, as they did */
        view.ntris = sp->t1;
        double e = sp->err;
        ism_sampler_leaf_set(s, &sp->leaf);
        if (leaf_may_split(p, pl->i) && e <= E &&
            ism_crease_unresolved(s, &view, sp->t0, E,
                                  (const double(*)[3])(pc->measure.cg + sp->cg0)))
            e = INFINITY;
        float err = (float)e;
        p->leaf_error[pl->i] = err;
        if (p->rec)
            p->rec[pl->i] = (ism_leaf_rec){chunk, pl->v0, sp->t0, pl->s0, pl->nverts,
                                           sp->t1 - sp->t0, pl->nsegs, err, pl->added};
    }
    ism_sampler_leaf_clear(s);
    return true;
}

/* Leaf i (sampler set on it; its output from v0, t0, s0 on; its stats were *before)
 * polygonised and cut along a CSG crease, its measuring left pending (PENDING_LEAVES). */
static bool defer_leaf(phase2 *p, padded_ctx *pc, size_t chunk, size_t i, ism_cell_out *out,
                       size_t v0, size_t t0, size_t s0, const ism_cell_stats *before)
{
    ism_cell_ctx *cx = &pc->c;
    bool ok = ism_cell_polygonise(cx, p->leaves[i], out) && ism_crease_split(&cx->s, out, t0);
    if (ok) {
        size_t k = pc->npending++;
        pc->span[k] = (ism_leaf_span){.t0 = t0, .t1 = out->ntris};
        ism_sampler_leaf_get(&cx->s, &pc->span[k].leaf);
        pc->pending[k] = (pending_leaf){i, v0, s0, out->nverts - v0, out->nsegs - s0,
                                        p->rec ? ism_cell_stats_minus(&cx->stats, before)
                                               : (ism_cell_stats){0}};
        pc->pending_tris += out->ntris - t0;
    }
    ism_sampler_leaf_clear(&cx->s);
    if (!ok)
        return false;
    return pc->npending < PENDING_LEAVES && pc->pending_tris < PENDING_TRIANGLES
               ? true
               : measure_pending(p, pc, chunk, out);
}

/* Leaf i of chunk into out: copied from the last round when it emits the same there, else
 * polygonised (and measured under max_error, maybe later: defer_leaf). */
static bool one_leaf(phase2 *p, padded_ctx *pc, size_t chunk, size_t i, ism_cell_out *out)
{
    ism_cell_ctx *cx = &pc->c;
    ism_cell_stats added; /* the counters this leaf added to cx->stats */
    size_t v0 = out->nverts, t0 = out->ntris, s0 = out->nsegs;
    float err = 0;
    bool copied = p->reuse && p->reuse[i] >= 0;
    if (copied) {
        if (!ism_leaf_memo_copy(p->memo, (size_t)p->reuse[i], out, &cx->stats, &added, &err))
            return false;
    } else {
        ism_cell_stats before = cx->stats;
        leaf_sampler(cx, p->leaves[i]);
        if (p->leaf_error && !(p->straddle > 0) && cx->cut_creases && cx->s.batch)
            return defer_leaf(p, pc, chunk, i, out, v0, t0, s0, &before);
        double e;
        bool unresolved, fold_test = p->leaf_error && !cx->cut_creases;
        bool ok = leaf_measured(p, cx, i, out, v0, t0, fold_test, &e, &unresolved);
        if (ok && fold_test && unresolved) {
            /* where a locus is known (no crease cut, cell_ctx.h): the centre's fan, split
               along the crease, meets E but leaves it unresolved, so the leaf is polygonised
               again with the cut (fan and split fold where the crease runs round the fan's
               centre: Barth's sextic at E 0.0259, 24 leaves split for 5 more rounds and 108
               triangles turned in its mesh; cut everywhere, 104 instead of 24 leaves of
               its E 0.00389 mesh measured beyond E in round 1: a chord follows a crease
               bending through a coarse leaf less well than the fan's crease points). A fan
               beyond E is split, or missed at depth.max, as it was: its cut never met E in
               those runs (Barth, E 0.0259 / 0.00389 / 0.00109, depth.max 4..10) */
            cx->cut_creases = true;
            ok = leaf_again(p, cx, i, out, v0, t0, s0, &before, &e);
            cx->cut_creases = false;
            if (ok && !(e <= p->o->max_error) && !leaf_may_split(p, i)) {
                /* nothing splits it: the fan, which met E, stands rather than a cut beyond
                   it (Barth at E 0.00389, depth.max 5: 24 leaves' fans 0.0031 from f = 0,
                   their cuts 0.0060) */
                ok = leaf_again(p, cx, i, out, v0, t0, s0, &before, &e);
            }
        }
        err = (float)e;
        if (ok && !p->leaf_error)
            measure_unflat(p, pc, p->leaves[i], out, t0);
        ism_sampler_leaf_clear(&cx->s);
        if (!ok)
            return false;
        if (p->rec)
            added = ism_cell_stats_minus(&cx->stats, &before);
    }
    if (p->leaf_error)
        p->leaf_error[i] = err;
    if (p->rec)
        p->rec[i] = (ism_leaf_rec){chunk, v0, t0, s0, out->nverts - v0, out->ntris - t0,
                                   out->nsegs - s0, err, added};
    return true;
}

/* Room in a new chunk's output for nleaves leaves at the rate the thread's earlier chunks of
 * the round emitted, so that it seldom grows: a chunk's arrays doubled from 256 elements
 * copied their whole length again (realloc's memcpy: 13.3M instructions of the Klein
 * bottle's E 3.27e-3 mesh, 14.2M of the gyroid ball's at 1.09e-3). Room only: what the
 * chunk emits does not depend on it. Rounds that copy the last round's leaves size the
 * output from those (ism_leaf_memo_reserve) instead. No cap: the rate is the mean of the
 * thread's earlier chunks, so at worst a sparse chunk after dense ones reserves its leaves at
 * the densest earlier chunk's rate, (that rate / its own) times what it fills; chunks are
 * contiguous runs of leaves, so that is about one dense chunk's arrays, held until the chunk
 * is freed after the weld (or by the round's memo). */
static bool chunk_room(const padded_ctx *pc, size_t nleaves, ism_cell_out *out)
{
    if (!pc->seen_leaves)
        return true; /* the thread's first chunk: no rate yet */
    size_t nv = (size_t)((double)pc->seen_verts / (double)pc->seen_leaves * (double)nleaves);
    size_t nt = (size_t)((double)pc->seen_tris / (double)pc->seen_leaves * (double)nleaves);
    return ism_grow((void **)&out->verts, &out->cap_verts, nv, sizeof *out->verts, 256) &&
           ism_grow((void **)&out->tris, &out->cap_tris, nt, 3 * sizeof *out->tris, 256);
}

static void run_chunk(void *arg, size_t chunk, int thread)
{
    phase2 *p = arg;
    if (atomic_load(&p->status) != ISM_POLY_OK)
        return;
    if (p->o->cancel && *p->o->cancel) {
        atomic_store(&p->status, ISM_POLY_CANCELLED);
        return;
    }
    padded_ctx *pc = &p->ctx[thread];
    ism_cell_out *out = &p->out[chunk];
    size_t first = chunk * p->chunk_leaves;
    size_t last = first + p->chunk_leaves < p->nleaves ? first + p->chunk_leaves : p->nleaves;
    if (!(p->reuse ? ism_leaf_memo_reserve(p->memo, p->reuse + first, last - first, out)
                   : chunk_room(pc, last - first, out))) {
        atomic_store(&p->status, ISM_POLY_NO_MEMORY);
        return;
    }
    pc->npending = pc->pending_tris = 0;
    for (size_t i = first; i <= last; i++)
        if (!(i < last ? one_leaf(p, pc, chunk, i, out) : measure_pending(p, pc, chunk, out))) {
            atomic_store(&p->status, pc->c.unregistered ? ISM_POLY_INTERNAL : ISM_POLY_NO_MEMORY);
            return;
        }
    pc->seen_leaves += last - first;
    pc->seen_verts += out->nverts;
    pc->seen_tris += out->ntris;
    if (atomic_fetch_add(&p->triangles, out->ntris) + out->ntris > p->max_triangles) {
        atomic_store(&p->status, ISM_POLY_TOO_BIG);
        return;
    }
    size_t done = atomic_fetch_add(&p->chunks_done, 1) + 1;
    report(p->prog, (double)done / (double)p->nchunks);
}

/* The CPU a phase costs (ism_poly_stats.cpu_ms, serial_ms, critical_ms, even_ms): the
 * calling thread's CPU from start to stop, and what the parallel loops given `par` cost. */
typedef struct phase_meter {
    double caller0;
    ism_par_cost par;
} phase_meter;

static void meter_start(phase_meter *m)
{
    m->caller0 = ism_thread_cpu_ms();
    memset(&m->par, 0, sizeof m->par);
}

static void meter_stop(const phase_meter *m, ism_poly_stats *st, enum ism_poly_phase ph)
{
    double serial = ism_thread_cpu_ms() - m->caller0 - m->par.caller_ms;
    st->serial_ms[ph] += serial;
    st->cpu_ms[ph] += serial + m->par.cpu_ms;
    st->critical_ms[ph] += serial + m->par.busiest_ms;
    st->even_ms[ph] += serial + m->par.even_ms;
}

/* Stops a meter running inside another (outer): the outer one leaves out what the calling
 * thread spent in this one. */
static void meter_stop_inside(const phase_meter *m, ism_poly_stats *st, enum ism_poly_phase ph,
                              phase_meter *outer)
{
    meter_stop(m, st, ph);
    outer->caller0 += ism_thread_cpu_ms() - m->caller0;
}

static void add_cell_stats(ism_poly_stats *st, const ism_cell_ctx *cx)
{
    st->polygons += cx->stats.polygons;
    st->two_polygon_nodes += cx->stats.two_polygon_nodes;
    st->degenerate_polygons += cx->stats.degenerate_polygons;
    st->nonmanifold_lines += cx->stats.double_lines;
    st->open_chains += cx->stats.open_chains;
    st->cracks_repaired += cx->stats.crack_tiles;
    st->singular_points += cx->stats.singular_points;
    st->crossed_faces += cx->stats.crossed_faces;
    st->lifted_polygons += cx->stats.lifted_polygons;
    st->lifted_chords += cx->stats.lifted_chords;
    st->quiet_skips += cx->quiet_skips;
    st->tile_replays += cx->tile_replays;
    st->corner_quiets += cx->corner_quiets;
    st->corner_checks += cx->corner_checks;
    st->corner_mismatches += cx->corner_mismatches;
    st->corner_values += cx->corner_values;
    st->evals_point += cx->s.n_point;
    st->evals_gradient += cx->s.n_gradient;
    st->evals_interval += cx->s.n_interval;
}

/* Under max_error: the leaves whose triangles measured farther than the bound go into
 * next (to be split by the next round) when they may still be split; the others are
 * counted as missed, with the worst distance among them. Leaves the conformance pass meshes
 * again (ISM_NODE_CONFORMED) are neither: what they emit is cut out. */
static bool collect_misses(const phase2 *p, const ism_poly_options *o, ism_split_set *next,
                           ism_poly_stats *st)
{
    st->error_missed_nodes = 0;
    st->error_worst = 0;
    for (size_t i = 0; i < p->nleaves; i++) {
        const ism_node *nd = &p->tree->nodes[p->leaves[i]];
        if (!(p->leaf_error[i] > o->max_error) || (nd->flags & ISM_NODE_CONFORMED))
            continue; /* met, or meshed again by the conformance pass (octree.h) */
        if (nd->level < o->max_depth && next) {
            if (!ism_split_set_add(next, ism_node_key(nd)))
                return false;
            continue;
        }
        st->error_missed_nodes++;
        st->error_worst = fmax(st->error_worst, p->leaf_error[i]);
    }
    return true;
}

/* What a max_error round leaves the next: its tree (octree_build.h, previous) and what its
 * leaves emitted (leaf_memo.h). Empty before the first round. */
typedef struct carry {
    ism_octree tree;
    ism_leaf_memo memo;
    ism_cell_cache *caches; /* each thread's memo (cell_cache.h), or NULL */
    int ncaches;
    ism_point_entry *corners; /* the build's corner memos (octree_build.h corner_memos), or
                                 NULL (none yet, or the scalar reference path) */
} carry;

/* Thread t's memo for this round: the last round's, or a new one (zeroed on pool). */
static bool round_cache(carry *c, ism_pool *pool, ism_par_cost *cost, int t,
                        ism_cell_cache *out)
{
    int threads = ism_pool_threads(pool);
    if (!c->caches) {
        if (!(c->caches = calloc((size_t)threads, sizeof *c->caches)))
            return false;
        c->ncaches = threads;
        for (int k = 0; k < threads; k++)
            if (!ism_cell_cache_init(&c->caches[k], pool, cost))
                return false;
    } else if (t == 0) {
        for (int k = 0; k < c->ncaches; k++)
            ism_cell_cache_next_round(&c->caches[k]);
    }
    *out = c->caches[t];
    return true;
}

static void free_caches(carry *c)
{
    for (int k = 0; c->caches && k < c->ncaches; k++)
        ism_cell_cache_free(&c->caches[k]);
    free(c->caches);
    c->caches = NULL;
    c->ncaches = 0;
}

/* The threads' corner memos for the build and the cells of a round: the last round's (the
 * values are pure), or new ones zeroed on pool (the cost in *cost); none on the scalar
 * reference path, which the tests compare the memos with. False when out of memory. */
static bool round_corners(carry *c, const ism_poly_options *o, ism_pool *pool,
                          ism_par_cost *cost)
{
    if (o->scalar_eval || c->corners)
        return true;
    size_t n = (size_t)ism_pool_threads(pool) << ISM_CORNER_MEMO_BITS;
    return (c->corners = ism_zeroed_alloc(pool, n, sizeof *c->corners, cost)) != NULL;
}

static void free_corners(carry *c)
{
    free(c->corners);
    c->corners = NULL;
}

/* The leaves of p->tree that emit what they emitted in the last round (c), when there was
 * one. */
static bool match_last_round(phase2 *p, const carry *c, int32_t **reuse)
{
    *reuse = NULL;
    if (!c->memo.rec || !c->tree.n || p->o->fresh_rounds)
        return true;
    if (!(*reuse = malloc((p->nleaves ? p->nleaves : 1) * sizeof **reuse)))
        return false;
    p->memo = &c->memo;
    p->reuse = *reuse;
    return ism_leaf_memo_match(&c->tree, p->tree, *reuse);
}

/* The break-point registry (breaks.h) p's leaves to polygonise query: of every leaf, or,
 * when the last round's outputs are copied, of those near a leaf polygonised again
 * (ism_breaks_near: the same answers to these queries; rounds after the first polygonise a
 * few leaves and rebuilt the whole registry each time, about a tenth of Barth's sextic's cost:
 * 359.9M of 3,401M instructions at 1e-2, 1f44c4c's figures). */
static bool build_breaks(phase2 *p, ism_pool *pool, ism_par_cost *cost)
{
    uint8_t *take = NULL;
    if (p->reuse && !(take = malloc(p->tree->n ? p->tree->n : 1)))
        return false;
    bool ok = (!take || ism_breaks_near(p->tree, p->leaves, p->nleaves, p->reuse, take)) &&
              ism_breaks_build(p->breaks, p->tree, take, pool, cost);
    free(take);
    return ok;
}

/* This round's leaf outputs become the memo the next round copies from. */
static void keep_for_next_round(phase2 *p, carry *c)
{
    ism_leaf_memo_free(&c->memo);
    c->memo = (ism_leaf_memo){p->out, p->nchunks, p->rec, p->nleaves};
    p->out = NULL;
    p->rec = NULL;
}

/* Phase 2: every candidate leaf polygonised, chunk by chunk, on all threads (its CPU seen by
 * the meter `outer`; the breaks' and the weld's go to their own phases). With next
 * (under max_error), the leaves to split in another round are added to it, and what they
 * emitted is kept in c for it; leaves that emit what they emitted in c's round are copied
 * from there. */
static enum ism_poly_status polygonise_leaves(const ism_tape *f, const ism_poly_options *o,
                                              const ism_octree *tree, ism_pool *pool,
                                              progress *prog, ism_mesh *mesh,
                                              ism_poly_stats *st, double *t_weld,
                                              phase_meter *outer, ism_split_set *next,
                                              carry *c, const ism_root_table *found,
                                              ism_crease_memo *crease)
{
    int32_t *reuse = NULL, *parent = NULL;
    ism_breaks breaks = {0};
    phase2 p;
    memset(&p, 0, sizeof p);
    p.o = o;
    p.tree = tree;
    p.breaks = &breaks;
    p.prog = prog;
    p.flat_abs = flat_abs_tol(tree, o);
    size_t by_memory = o->max_memory / BYTES_PER_TRIANGLE;
    p.max_triangles = o->max_triangles < by_memory ? o->max_triangles : by_memory;
    atomic_init(&p.status, ISM_POLY_OK);
    p.straddle = straddle_shift(f, o);
    enum ism_poly_status status = ISM_POLY_NO_MEMORY;
    int threads = ism_pool_threads(pool);
    double t0;
    phase_meter m;
    p.leaves = malloc((tree->n ? tree->n : 1) * sizeof *p.leaves);
    parent = ism_octree_parents(tree);
    if (!p.leaves || !parent)
        goto done;
    for (size_t i = 0; i < tree->n; i++)
        if (tree->nodes[i].state == ISM_NODE_LEAF)
            p.leaves[p.nleaves++] = (int32_t)i;
    if (!match_last_round(&p, c, &reuse))
        goto done;
    t0 = ism_now_ms();
    meter_start(&m);
    if (!build_breaks(&p, pool, &m.par))
        goto done;
    meter_stop_inside(&m, st, ISM_PHASE_CRACKS, outer);
    st->time_ms[ISM_PHASE_CRACKS] = ism_now_ms() - t0;
    p.chunk_leaves = p.nleaves / ((size_t)threads * CHUNKS_PER_THREAD);
    if (p.chunk_leaves < MIN_CHUNK_LEAVES)
        p.chunk_leaves = MIN_CHUNK_LEAVES;
    p.nchunks = (p.nleaves + p.chunk_leaves - 1) / p.chunk_leaves;
    p.out = calloc(p.nchunks ? p.nchunks : 1, sizeof *p.out);
    if ((p.ctx = aligned_alloc(ISM_CACHE_LINE, (size_t)threads * sizeof *p.ctx)))
        memset(p.ctx, 0, (size_t)threads * sizeof *p.ctx);
    if (o->max_error > 0 && !(p.leaf_error = calloc(p.nleaves ? p.nleaves : 1, sizeof(float))))
        goto done;
    p.last_round = !next;
    if (next && !o->fresh_rounds &&
        !(p.rec = malloc((p.nleaves ? p.nleaves : 1) * sizeof *p.rec)))
        goto done;
    if (!p.out || !p.ctx)
        goto done;
    if (!p.leaf_error && !ism_quiet_init(&p.quiet, o->quiet, o->nquiet))
        goto done;
    ism_root_params roots = {o->gradient_test, o->double_root_eps, o->double_root_iters,
                             ism_tape_has_min_max(f)};
    for (int t = 0; t < threads; t++) {
        ism_cell_ctx *cx = &p.ctx[t].c;
        cx->s.tape = f;
        cx->s.dist_above = o->max_error;
        cx->s.rays_below = o->nquiet ? INFINITY : 0;
        cx->s.batch = !o->scalar_eval;
        cx->walk_every_tile = o->walk_every_tile;
        cx->s.wedge_edges_below = ism_crease_wedge_edges(&tree->grid, o->max_depth, o->max_error);
        cx->s.crease_pieces = ism_crease_pieces(f);
        cx->s.fold_below = ism_crease_fold_below(o->max_error);
        cx->s.memo_tape = o->scalar_eval ? NULL : f; /* poly_options.h */
        cx->s.crease_memo = crease ? &crease[t] : NULL;
        cx->tree = tree;
        cx->parent = parent;
        cx->breaks = &breaks;
        cx->found = found;
        cx->corners = c->corners ? c->corners + ((size_t)t << ISM_CORNER_MEMO_BITS) : NULL;
        cx->roots = roots;
        cx->stitch_tol = o->stitch_tol;
        /* corner fans only where no singular locus is known: beside a double curve they
         * changed what the conformance pass rebuilt (Steiner at E = 0.01: χ 5 -> −1) */
        cx->max_error = o->nquiet ? 0 : o->max_error;
        /* the crease cut with them; where they are off, one_leaf cuts a leaf whose fans
           split along the crease leave it unresolved */
        cx->cut_creases = cx->max_error > 0;
        if (!(cx->s.ws = ism_eval_ws_new(f)) ||
            !round_cache(c, pool, &outer->par, t, &cx->cache))
            goto done;
    }
    ism_pool_for(pool, p.nchunks, run_chunk, &p, &outer->par);
    status = atomic_load(&p.status);
    for (int t = 0; t < threads; t++) {
        add_cell_stats(st, &p.ctx[t].c);
        st->unflat_nodes += p.ctx[t].unflat;
        st->unflat_worst = fmax(st->unflat_worst, p.ctx[t].unflat_worst);
    }
    if (status != ISM_POLY_OK)
        goto done;
    if (p.leaf_error && !collect_misses(&p, o, next, st)) {
        status = ISM_POLY_NO_MEMORY;
        goto done;
    }
    if (next && next->n) {
        if (p.rec)
            keep_for_next_round(&p, c);
        goto done; /* another round will mesh it again: no weld */
    }

    t0 = ism_now_ms();
    meter_start(&m);
    ism_weld_stats ws;
    status = ism_weld(p.out, p.nchunks, pool, mesh, &ws, &m.par) ? ISM_POLY_OK
                                                                      : ISM_POLY_NO_MEMORY;
    if (status == ISM_POLY_OK)
        ism_straddle_mesh(&p.ctx[0].c.s, p.straddle, o->box, mesh);
    meter_stop_inside(&m, st, ISM_PHASE_MESH, outer);
    *t_weld = ism_now_ms() - t0;
    st->zero_vertices = ws.zero_vertices;
    st->edges_touching = ws.touch_vertices;
    st->edges_double_root = ws.pair_vertices / 2;
    st->edges_many_roots = ws.many_vertices;
done:
    for (size_t c = 0; p.out && c < p.nchunks; c++)
        ism_cell_out_free(&p.out[c]);
    free(p.out);
    for (int t = 0; p.ctx && t < threads; t++) {
        if (p.ctx[t].c.s.ws)
            ism_eval_ws_free(p.ctx[t].c.s.ws);
        ism_cell_ctx_free(&p.ctx[t].c);
        ism_measure_scratch_free(&p.ctx[t].measure);
    }
    if (!next || !next->n || o->fresh_rounds || status != ISM_POLY_OK) {
        free_caches(c); /* no round follows, or it starts afresh */
        free_corners(c);
    }
    free(p.ctx);
    free(p.leaves);
    free(parent);
    free(p.leaf_error);
    free(p.rec);
    free(reuse);
    ism_quiet_free(&p.quiet);
    ism_breaks_free(&breaks);
    return status;
}

static enum ism_poly_status from_build(enum ism_build_status b)
{
    switch (b) {
    case ISM_BUILD_OK: return ISM_POLY_OK;
    case ISM_BUILD_CANCELLED: return ISM_POLY_CANCELLED;
    case ISM_BUILD_TOO_BIG: return ISM_POLY_TOO_BIG;
    default: return ISM_POLY_NO_MEMORY;
    }
}

static void count_leaves(const ism_octree *t, ism_poly_stats *st)
{
    for (size_t i = 0; i < t->n; i++) {
        st->plotting_nodes += t->nodes[i].state == ISM_NODE_LEAF;
        st->short_tape_leaves += t->nodes[i].state == ISM_NODE_LEAF && t->tape_of && t->tape_of[i];
    }
    st->leaf_tapes = t->ntapes;
}

static enum ism_poly_status fail_with(enum ism_poly_status s, const ism_poly_options *o,
                                      ism_error *err)
{
    if (s == ISM_POLY_TOO_BIG)
        ism_error_set(err, "the mesh would exceed the budget (%zu triangles, %zu MiB)",
                      o->max_triangles, o->max_memory >> 20);
    else if (s == ISM_POLY_CANCELLED)
        ism_error_set(err, "cancelled");
    else if (s == ISM_POLY_NO_MEMORY)
        ism_error_set(err, "out of memory");
    else if (s == ISM_POLY_INTERNAL)
        ism_error_set(err, "internal error: a tile met a lattice point the break-point "
                           "registry does not hold");
    return s;
}

/* One octree and its polygons; with next (under max_error, when another round may
 * follow), the leaves to split are collected instead of welding a mesh. *prev: the last
 * round's tree and leaf outputs (empty in the first), whose decisions the octree takes
 * over and whose leaves are copied where they still hold; replaced by this round's when
 * another round may follow. */
static enum ism_poly_status one_round(const ism_tape *f, const ism_poly_options *o, ism_pool *pool,
                                      progress *prog, const ism_split_set *split,
                                      ism_split_set *next, ism_mesh *mesh, ism_poly_stats *st,
                                      carry *prev)
{
    double t_start = ism_now_ms(), from = prog->from, span = prog->span;
    phase_meter m;
    meter_start(&m);
    prog->span = span * 0.4 / 0.95; /* the octree's share of this round's progress */
    ism_octree tree;
    memset(&tree, 0, sizeof tree);
    ism_root_table found; /* the build's edge roots, for the cells (root_table.h) */
    int thin_depth = o->max_depth + (!o->thin_search ? 0
                                     : o->quiet ? ISM_THIN_EXTRA_DEPTH
                                                : ISM_THIN_BLIND_DEPTH);
    if (thin_depth > ISM_GRID_MAX_DEPTH)
        thin_depth = ISM_GRID_MAX_DEPTH;
    ism_grid_init(&tree.grid, o->box, thin_depth);
    /* the threads' crease-point memos for this round: none on the scalar reference path,
       nor where f has no kink (no min, max or abs: crease_split.c asks for no crease point
       without a top min/max or pieces); zeroed on the pool's threads, the cost in the
       octree's meter as the build's own memos' */
    ism_crease_memo *crease = NULL;
    if (!o->scalar_eval && ism_tape_has_kink(f) &&
        !(crease = ism_crease_memo_new(pool, ism_pool_threads(pool), &m.par)))
        return ISM_POLY_NO_MEMORY;
    if (!round_corners(prev, o, pool, &m.par)) {
        ism_crease_memo_free(crease);
        return ISM_POLY_NO_MEMORY;
    }
    ism_octree_build_params bp = {
        .tape = f,
        .min_depth = o->min_depth,
        .max_depth = o->max_depth,
        .thin_depth = thin_depth,
        .thin_coarse = o->thin_coarse,
        .flatness = {.gradient_test = o->gradient_test,
                     .normal_cos = o->flat_normal,
                     .plane_frac = o->flat_plane,
                     .abs_tol = flat_abs_tol(&tree, o),
                     .double_root_eps = o->double_root_eps,
                     .double_root_iters = o->double_root_iters,
                     .max_error = o->max_error,
                     .straddle_shift = straddle_shift(f, o)},
        .quiet = o->quiet,
        .nquiet = o->nquiet,
        .node_balls = o->node_balls,
        .nnode_balls = o->nnode_balls,
        .threads = ism_pool_threads(pool),
        .pool = pool,
        .max_nodes = o->max_memory / 4 / sizeof(ism_node),
        .force_split = split,
        .scalar_eval = o->scalar_eval,
        .full_tape = o->full_tape,
        .previous = o->fresh_rounds ? NULL : &prev->tree,
        .cancel = o->cancel,
        .progress = report,
        .progress_ctx = prog,
        .cost = &m.par,
        .roots = &found,
        .max_roots = o->max_memory / ROOT_MEMORY_SHARE / ISM_ROOT_BYTES,
        .crease_memos = crease,
        .corner_memos = prev->corners,
    };
    memcpy(bp.flatness.box, o->box, sizeof bp.flatness.box);
    ism_octree_build_stats bs;
    enum ism_poly_status status = from_build(ism_octree_build(&tree, &bp, &bs));
    st->nodes_visited = bs.visited;
    st->nodes_excluded = bs.excluded;
    st->unresolved_nodes = bs.unresolved;
    st->thin_searched = bs.thin_searched;
    st->thin_found = bs.thin_found;
    st->thin_undecided = bs.thin_undecided;
    st->deep_leaves = bs.deep_leaves;
    st->tape_misses = bs.tape_misses;
    double t_tree = ism_now_ms();
    st->time_ms[ISM_PHASE_OCTREE] = t_tree - t_start;
    meter_stop(&m, st, ISM_PHASE_OCTREE);
    if (status != ISM_POLY_OK) {
        ism_root_table_free(&found);
        ism_crease_memo_free(crease);
        return status;
    }
    count_leaves(&tree, st);

    prog->from = from + span * 0.4 / 0.95;
    prog->span = span * 0.55 / 0.95;
    double t_weld = 0;
    meter_start(&m);
    status = polygonise_leaves(f, o, &tree, pool, prog, mesh, st, &t_weld, &m, next,
                               prev, &found, crease);
    ism_root_table_free(&found);
    ism_crease_memo_free(crease);
    ism_octree_free(&prev->tree);
    if (next && next->n)
        prev->tree = tree;
    else
        ism_octree_free(&tree);
    meter_stop(&m, st, ISM_PHASE_POLYGONS);
    double t_end = ism_now_ms();
    st->time_ms[ISM_PHASE_POLYGONS] = t_end - t_tree - t_weld - st->time_ms[ISM_PHASE_CRACKS];
    st->time_ms[ISM_PHASE_MESH] = t_weld;
    st->total_ms = t_end - t_start;
    return status;
}

/* What every round cost: evaluations and phase times add up over the rounds. */
static void add_round_costs(ism_poly_stats *total, const ism_poly_stats *r)
{
    total->evals_point += r->evals_point;
    total->evals_gradient += r->evals_gradient;
    total->evals_interval += r->evals_interval;
    total->corner_values += r->corner_values;
    for (int k = 0; k < ISM_PHASE_COUNT; k++) {
        total->time_ms[k] += r->time_ms[k];
        total->cpu_ms[k] += r->cpu_ms[k];
        total->serial_ms[k] += r->serial_ms[k];
        total->critical_ms[k] += r->critical_ms[k];
        total->even_ms[k] += r->even_ms[k];
    }
}

/* The dual mesh (dual.h) when asked for and possible: ISM_POLY_OK with the mesh, a failure,
 * or *tried false (the primal polygons then, stats->dual_declined saying why). */
static enum ism_poly_status try_dual(const ism_tape *f, const ism_poly_options *o,
                                     ism_mesh *mesh, ism_poly_stats *stats, bool *tried)
{
    *tried = false;
    if ((stats->dual_declined = ism_dual_declined_before(f, o)) != ISM_DUAL_WHY_NONE)
        return ISM_POLY_OK;
    double t0 = ism_now_ms();
    ism_dual_stats ds;
    enum ism_dual_status d = ism_dual_mesh(f, o, mesh, &ds);
    if (d == ISM_DUAL_NOT_APPLICABLE) {
        stats->dual_declined = ds.declined;
        return ISM_POLY_OK;
    }
    *tried = true;
    stats->mesher = ISM_MESHER_DUAL;
    stats->threads = ds.threads;
    stats->error_rounds = ds.rounds;
    stats->error_missed_nodes = ds.missed;
    stats->plotting_nodes = ds.leaves;
    stats->evals_point = ds.evals_point;
    stats->evals_gradient = ds.evals_gradient;
    stats->evals_interval = ds.evals_interval;
    stats->triangles = mesh->ntris;
    stats->vertices = mesh->nverts;
    stats->total_ms = ism_now_ms() - t0;
    stats->time_ms[ISM_PHASE_MESH] = stats->total_ms;
    return d == ISM_DUAL_OK          ? ISM_POLY_OK
           : d == ISM_DUAL_TOO_BIG   ? ISM_POLY_TOO_BIG
           : d == ISM_DUAL_CANCELLED ? ISM_POLY_CANCELLED
                                     : ISM_POLY_NO_MEMORY;
}

enum ism_poly_status ism_polygonise(const ism_tape *f, const ism_poly_options *o,
                                    ism_mesh *mesh, ism_poly_stats *stats, ism_error *err)
{
    memset(stats, 0, sizeof *stats);
    ism_mesh_free(mesh);
    if (!ism_poly_options_check(o, err))
        return ISM_POLY_BAD_OPTIONS;
    bool dual;
    enum ism_poly_status ds = try_dual(f, o, mesh, stats, &dual);
    if (dual)
        return ds == ISM_POLY_OK ? ISM_POLY_OK : fail_with(ds, o, err);
    double t_start = ism_now_ms();
    /* one pool for every round and phase: threads made once per call */
    ism_pool *pool = ism_pool_new(ism_threads_resolve(o->threads));
    int threads = ism_pool_threads(pool);
    ism_split_set split = {0}, next = {0};
    carry prev;
    memset(&prev, 0, sizeof prev);
    ism_poly_stats costs, round;
    memset(&costs, 0, sizeof costs);
    enum ism_poly_status status = ISM_POLY_OK;
    for (int r = 0;; r++) {
        bool last = !(o->max_error > 0) || r == ISM_ERROR_ROUNDS - 1;
        /* the first round reports 0 .. 0.95, later ones stay at 0.95 */
        progress prog = {o, PTHREAD_MUTEX_INITIALIZER, r ? 0.95 : 0, r ? 0 : 0.95};
        memset(&round, 0, sizeof round);
        next.n = 0;
        status = one_round(f, o, pool, &prog, &split, last ? NULL : &next, mesh, &round,
                           &prev);
        add_round_costs(&costs, &round);
        if (status != ISM_POLY_OK || !next.n)
            break;
        for (size_t i = 0; i < next.n; i++)
            if (!ism_split_set_add(&split, next.keys[i])) {
                status = ISM_POLY_NO_MEMORY;
                break;
            }
        ism_split_set_sort(&split);
        stats->error_rounds++;
        if (status != ISM_POLY_OK)
            break;
    }
    ism_pool_free(pool);
    ism_split_set_free(&split);
    ism_split_set_free(&next);
    ism_octree_free(&prev.tree);
    ism_leaf_memo_free(&prev.memo);
    free_caches(&prev);
    free_corners(&prev);
    uint64_t rounds = stats->error_rounds;
    enum ism_dual_reason declined = stats->dual_declined;
    *stats = round;
    stats->error_rounds = rounds;
    stats->mesher = straddle_shift(f, o) > 0 ? ISM_MESHER_STRADDLE : ISM_MESHER_PRIMAL;
    stats->dual_declined = declined;
    stats->threads = threads;
    stats->evals_point = costs.evals_point;
    stats->evals_gradient = costs.evals_gradient;
    stats->corner_values = costs.corner_values;
    stats->evals_interval = costs.evals_interval;
    memcpy(stats->time_ms, costs.time_ms, sizeof stats->time_ms);
    memcpy(stats->cpu_ms, costs.cpu_ms, sizeof stats->cpu_ms);
    memcpy(stats->serial_ms, costs.serial_ms, sizeof stats->serial_ms);
    memcpy(stats->critical_ms, costs.critical_ms, sizeof stats->critical_ms);
    memcpy(stats->even_ms, costs.even_ms, sizeof stats->even_ms);
    stats->total_ms = ism_now_ms() - t_start;
    if (status != ISM_POLY_OK) {
        ism_mesh_free(mesh);
        return fail_with(status, o, err);
    }
    stats->triangles = mesh->ntris;
    stats->vertices = mesh->nverts;
    progress done = {o, PTHREAD_MUTEX_INITIALIZER, 1.0, 0};
    report(&done, 0);
    return ISM_POLY_OK;
}
