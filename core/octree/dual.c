/* dual.c — dual contouring on an octree under an error bound, for surfaces without features
 * (dual.h): the tree, the vertices, the split passes (the children's corners, then the feet
 * sag_split will ask for in batched lanes, then the children classified) and the
 * measure-and-split rounds; what a node is comes from its leaf tests (dual_classify.c),
 * the quads from the minimal-edge walk (dual_walk.c), the triangles' measure from
 * dual_measure.c, and the state all of them share is dual_tree.h's. The work is
 * cut into tasks for the pool whose outputs land in their own slots and are joined in a
 * fixed order (children level by level, walk calls, vertex pairs, triangles), so the mesh
 * does not depend on the number of threads. */
#include "core/octree/dual.h"
#include "core/octree/dual_tree.h"
#include "core/octree/dual_classify.h"
#include "core/octree/dual_measure.h"
#include "core/octree/dual_sides.h"
#include "core/octree/dual_walk.h"
#include "core/eval/interval_jet.h"
#include "core/octree/cell_cache.h"
#include "core/octree/corners.h"
#include "core/octree/dual_balls.h"
#include "core/octree/dual_box.h"
#include "core/octree/dual_cert.h"
#include "core/octree/dual_crease.h"
#include "core/octree/sample_dist.h"
#include "core/octree/edge_roots.h"
#include "core/octree/graph_cert.h"
#include "core/octree/grid.h"
#include "core/octree/sampler.h"
#include "core/octree/straddle.h"
#include "core/util/bits.h"
#include "core/util/grow.h"
#include "core/util/parallel.h"

#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

/* Measure-and-split rounds after the first mesh. Each splits the leaves round the triangles
 * that missed E, so a leaf reaches the size E needs in at most max_depth - min_depth rounds;
 * 20 covers every depth the options allow. */
#define DUAL_ROUNDS 20
/* The lattice point memo: 2^15 entries of 40 bytes (1.3 MB), the size the octree's own
 * corner memo uses (cell_cache.h); a collision only recomputes. */
#define DUAL_POINT_BITS ISM_POINT_CACHE_BITS
/* ... but the memo starts at 2^11 entries (80 KB) and grows with the tree, to four entries
 * a node (points_for): a small job neither faults in nor, in a long-lived worker, zeroes
 * 1.3 MB per thread (callgrind, the worker's pipeline run twice: 1.1M instructions of
 * memset a request and thread; a fresh process: ~320 page faults instead). Values are f and
 * ∇f at lattice points, so what the memo holds changes no mesh. */
#define DUAL_POINT_MIN_BITS 11
_Static_assert(DUAL_POINT_MIN_BITS >= 6 && DUAL_POINT_BITS >= DUAL_POINT_MIN_BITS,
               "the point memo: at least 64 slots (whole words of bits)");
#define DUAL_POINT_ENTRIES_PER_NODE 4

/* The point memo's entries are not cleared: a bit a slot (worker.filled, util/bits.h) says
 * which hold a point, and only those bits are (2^bits / 8 bytes). calloc clearing the 80 KB
 * of the first table was 82K of the sphere's 2.13M instructions at E 0.0141 (bench_error
 * under callgrind: memset counts a byte an instruction); the bit costs a test a look-up.
 * Room for a memo of 2^bits entries into *points and its bits into *filled; false (nothing
 * held) when out of memory. */
static bool points_alloc(int bits, ism_point_entry **points, uint64_t **filled)
{
    *points = ism_bits_table((size_t)1 << bits, sizeof **points, filled);
    return *points != NULL;
}

/* children_free's batches are made while the children they showed free (each spared the
 * interval of f and ∇f, 2-3x a batch's cost) are at least this many per batch so far (the
 * first split pass past min_depth always batches). With every batch made: kummer-16-nodes
 * at 1e-2 4.4 (38,328 of 8,658 batches; 1.3-1.9 in its first passes, 5.8 in its largest),
 * the sphere 4.1-5.4, the torus 0.53 at 1e-2 (2.1 in its first pass, then none: its
 * natural interval is wide) and 0.06 at 1e-3. Whole runs (bench_error, callgrind) against
 * no batch: at 1 kummer-16-nodes 1e-2 1,991.9M -> 1,884.6M, sphere 1e-2 / 1.3e-3 7.27M /
 * 54.30M -> 6.93M / 52.69M, torus 1e-2 / 3.57e-3 / 1.19e-3 +0.8% / +0.5% / +0.2% (the
 * pass after its first); at 3 the torus saves 0.2% and kummer nothing (off after its first
 * pass). */
#define BATCH_PAYS 1

/* Crease vertices of two leaves this close (a share of the box's smallest side) are one
 * point (weld_crease). */
#define WELD_TOL 1e-12

/* The tree's lattice over box down to depth, and its finest step. */
static void set_grid(dual *d, const double box[6], int depth)
{
    ism_grid_init(&d->g, box, depth);
    d->finest_step = min_of(d->g.step[0], min_of(d->g.step[1], d->g.step[2]));
}

/* f and the unit gradients at the lattice points q[0..n) (n <= 27), at p (their
 * coordinates, given), into f and g (f 0 where its sign is rounding noise:
 * ism_sample_zero_by_rounding), through the thread's point memo, as neighbouring nodes share
 * corners (a split's 27 points hold the parent's 8 and the 18 on its faces and edges that the
 * neighbours' splits sample too). The memo is looked up as ism_point_memo_many (cell_cache.h)
 * looks up its own — in order, a miss taking its slot at once, the misses' values in one
 * batch — but keeps the finished values, normalised and with the zero taken, so a hit is
 * read as it stands: normalising every point asked for, hits and all, cost the sphere at E
 * 1.3e-3 0.39M instructions of 27.86M (a point's zero test, and its count of an interval
 * where it takes one, then come once a point evaluated, not once a node asking). q[0..n)
 * must be distinct lattice points (a split's 27, a root's 8): a miss claims its slot before
 * its value exists, so a later copy of the same point in one call would read the slot's old
 * f and g as a hit (revR 8). */
static void sample_points(dual *d, worker *w, const int32_t (*q)[3], size_t n, double *f,
                          double (*p)[3], double (*g)[3])
{
    ism_point_entry *slot[ISM_POINT_MEMO_MANY];
    uint64_t key[ISM_POINT_MEMO_MANY], mask = ((uint64_t)1 << w->bits) - 1;
    size_t miss[ISM_POINT_MEMO_MANY], at[ISM_POINT_MEMO_MANY], nm = 0;
    for (size_t j = 0; j < n; j++) { /* the slots asked for at once: their misses overlap */
        key[j] = ism_lattice_key(q[j]);
        at[j] = ism_cache_mix(key[j]) & mask;
        slot[j] = &w->points[at[j]];
        __builtin_prefetch(slot[j], 1);
    }
    for (size_t j = 0; j < n; j++) {
        if (ism_bit_test(w->filled, at[j]) && slot[j]->key == key[j]) {
            f[j] = slot[j]->f;
            memcpy(g[j], slot[j]->g, sizeof g[j]);
            continue;
        }
        ism_bit_set(w->filled, at[j]);
        slot[j]->key = key[j];
        miss[nm++] = j;
    }
    if (nm >= ISM_POINT_BATCH_MIN) {
        double mp[ISM_POINT_MEMO_MANY][3], mf[ISM_POINT_MEMO_MANY], mg[ISM_POINT_MEMO_MANY][3];
        for (size_t k = 0; k < nm; k++)
            memcpy(mp[k], p[miss[k]], sizeof mp[k]);
        ism_sample_grad_batch(&w->s, (const double (*)[3])mp, mf, mg, nm);
        for (size_t k = 0; k < nm; k++) {
            f[miss[k]] = mf[k];
            memcpy(g[miss[k]], mg[k], sizeof mg[k]);
        }
    } else
        for (size_t k = 0; k < nm; k++)
            f[miss[k]] = ism_sample_grad(&w->s, p[miss[k]], g[miss[k]]);
    for (size_t k = 0; k < nm; k++) {
        size_t j = miss[k];
        double gn = ism_normalise3(g[j]); /* 0 at a critical point: no agreement there */
        if (f[j] != 0 && ism_sample_zero_by_rounding(&w->s, p[j], f[j], gn, d->finest_step))
            f[j] = 0; /* a zero for every node sharing the point, as the primal tiles take it */
        if (slot[j]->key == key[j]) { /* not taken since by a later miss */
            slot[j]->f = f[j];
            memcpy(slot[j]->g, g[j], sizeof slot[j]->g);
        }
    }
}

/* sample_points at the lattice points q[0..n), their coordinates (ism_grid_coord) into p. */
static void sample_corners(dual *d, worker *w, const int32_t (*q)[3], size_t n, double *f,
                           double (*p)[3], double (*g)[3])
{
    for (size_t j = 0; j < n; j++)
        for (int a = 0; a < 3; a++)
            p[j][a] = ism_grid_coord(&d->g, a, q[j][a]);
    sample_points(d, w, q, n, f, p, g);
}

/* The room grow leaves for need elements in an array of room cap: what the tree's arrays
 * would hold grown one node at a time (held_bytes' count; expand takes a level's at once).
 * Past SIZE_MAX's half, need itself (held_bytes is then past any max_memory anyway). */
static size_t room_for(size_t cap, size_t need)
{
    size_t n = ism_grow_room(cap, need, ISM_DUAL_FIRST_ROOM);
    return n ? n : need;
}

/* Bytes the tree and the vertices hold (the triangles are bounded by max_triangles), the
 * tree's arrays as grown one node at a time (heldn, heldat): max_memory stops the tree at the
 * node it always did. */
static size_t held_bytes(const dual *d)
{
    return d->heldn * sizeof *d->n + d->heldat * sizeof *d->at +
           d->capv * (3 * sizeof *d->pos + sizeof *d->vleaf + sizeof *d->vtwin);
}

/* A new node, or false when out of memory or past o->max_memory (too_big set). Inline:
 * expand makes every node (1,929 calls on the torus at E 0.0141). */
static inline __attribute__((always_inline)) bool new_node(dual *d, ism_ipt o, int level,
                                                           int32_t *out)
{
    if (held_bytes(d) > d->o->max_memory) {
        d->too_big = true;
        return false;
    }
    if (!grow((void **)&d->n, &d->capn, d->nn + 1, sizeof *d->n))
        return false;
    d->heldn = room_for(d->heldn, d->nn + 1);
    *out = (int32_t)d->nn++;
    dnode *n = &d->n[*out];
    memset(n, 0, sizeof *n);
    n->o = o;
    n->level = (uint8_t)level;
    n->child = n->vert = n->vert2 = -1;
    return true;
}

/* Node i's sag_split vertex p into d->at (grown only for such nodes); false when out of
 * memory (nomem set). */
static bool keep_at(dual *d, int32_t i, const double p[3])
{
    if (!grow((void **)&d->at, &d->capat, (size_t)i + 1, sizeof *d->at)) {
        d->nomem = true;
        return false;
    }
    d->heldat = room_for(d->heldat, (size_t)i + 1);
    memcpy(d->at[i], p, sizeof d->at[i]);
    return true;
}

/* Does node n (of side size; 0: any) lie within a singular point's limit (dual_balls.h)?
 * There a node the proofs cannot make plain (a node's nappes closer than a cell along its
 * flat direction) joins the point's hole once it is as small as the hole's leaves (or at the
 * deepest level), and the clip and the fan then close it: splitting it on to depth.max
 * first cost kummer-4-nodes 5-7% more instructions (whole run, 1e-2 / 3e-3 / 1e-3: 448.5M /
 * 554.5M / 908.6M -> 423.9M / 515.1M / 866.0M) and 5-8% more triangles (4,800 / 7,590 /
 * 17,862 -> 4,544 / 7,014 / 16,464). */
static bool near_point(const dual *d, const dnode *n, double size)
{
    double lo[3], hi[3];
    corner_point(d, n, 0, lo);
    corner_point(d, n, 7, hi);
    return ism_dual_balls_near(d->balls, d->nballs, &d->cover, lo, hi, size);
}

/* What splitting one node yields: its 8 children's corner values and kinds. */
typedef struct split_out {
    double f[8][8];
    double at[8][3]; /* child c's vertex when placed[c] is FOOT_AT (sag_split) */
    uint8_t kind[8];
    uint8_t placed[8];
    uint8_t free_kids[8]; /* child c's corner_view.free_kids */
    uint8_t kinked; /* bit c: child c split for the crease (corner_view.kinked) */
    uint8_t batch_free; /* bit c: child c shown free by children_free alone */
    bool batched;       /* children_free made a batch */
    bool bad;
} split_out;

/* Of a split's 27 lattice points (x fastest, 3 a row, 9 a layer), the offset of the step
 * b (bit 0: + x, 1: + y, 2: + z): child c's first corner is point SPLIT_OFF[c], its
 * corner j SPLIT_OFF[c] + SPLIT_OFF[j]. A table: computing them from the bits was ~10
 * instructions a corner, 1% of the torus at 3e-3. */
static const uint8_t SPLIT_OFF[8] = {0, 1, 3, 4, 9, 10, 12, 13};

/* Bit j of CHILD_CORNERS[c]: point j of a split's 27 (corners_task's order, x fastest) is
 * a corner of child c. */
#define CORNER_BITS(o) (0x361Bu << (o)) /* points o + {0, 1, 3, 4, 9, 10, 12, 13} */
static const uint32_t CHILD_CORNERS[8] = {CORNER_BITS(0), CORNER_BITS(1), CORNER_BITS(3),
                                          CORNER_BITS(4), CORNER_BITS(9), CORNER_BITS(10),
                                          CORNER_BITS(12), CORNER_BITS(13)};

/* The bits set in x (by halves, as __builtin_popcount is a libgcc call without -mpopcnt). */
static inline int bits_set(uint32_t x)
{
    x -= x >> 1 & 0x55555555u;
    x = (x & 0x33333333u) + (x >> 2 & 0x33333333u);
    x = (x + (x >> 4)) & 0x0f0f0f0fu;
    return (int)(x * 0x01010101u >> 24);
}

/* Are a split's children past min_depth, where batch_on's own judgement applies and the
 * batches are counted for it (expand), rather than above it, where they are always made? */
static bool batch_judged(const dual *d, int parent_level)
{
    return parent_level + 1 >= d->o->min_depth;
}

/* Bit c: child c's box is free of f = 0 by the natural interval of f over it (p: the 27
 * points in corners_task's order; neg27 bit j: f < 0 at point j). One batch of eight boxes
 * (ism_eval_interval_batch) costs less than one box's interval alone — callgrind, per call:
 * torus 912 instructions for the batch, 644 for one value, 1,947 for one value with ∇f;
 * kummer's quartic 1,602 / 1,286 / 4,330 — and the proofs of a child whose corners share a
 * sign began with f and ∇f's natural enclosure, whose value alone shows most such children
 * empty (kummer-16-nodes at 1e-2: 31,300 of 43,522; the torus, whose natural interval is
 * wide: 136 of 1,008). Only when some child has corners of one sign (the others' intervals
 * hold 0), and past min_depth only while the batches pay (d->batch_on, counted there
 * alone); above min_depth always: a child shown free there is an empty leaf, its whole
 * subtree down to min_depth never made, so a batch there spares up to 8^(min_depth - level)
 * nodes where batch_on weighs one split's proofs (sphere at 1e-2: 32 of the 64 level-2
 * nodes, 256 level-3 nodes and their corners spared, −7.1% of the run; the torus's natural
 * interval there frees none at depth.min 3, +0.05%). At depth.min 5 (at most 1 + 8 + ... +
 * 4,096 batches) it pays more: isomesh --surface S -d 5:10 --max-error E --threads 1 under
 * callgrind --toggle-collect=ism_polygonise, batches above depth.min always against gated
 * by batch_on past it alone: torus 0.0141 74.3M against 108.7M, kummer-16-nodes 1e-2
 * 1,127.8M against 1,169.5M, the same meshes. *batched tells whether one was made. */
static uint8_t children_free(const dual *d, worker *w, const dnode *parent, uint32_t neg27,
                             const double (*p)[3], bool *batched)
{
    *batched = false;
    if (!d->batch_on && batch_judged(d, parent->level))
        return 0;
    bool any = false;
    ism_interval x[8], y[8], z[8], out[8];
    for (int c = 0; c < 8; c++) {
        /* corners of one sign (no popcount: a libgcc call without -mpopcnt) */
        uint32_t neg = neg27 & CHILD_CORNERS[c];
        int lo = SPLIT_OFF[c];
        any |= neg == 0 || neg == CHILD_CORNERS[c];
        x[c] = (ism_interval){p[lo][0], p[lo + 13][0]};
        y[c] = (ism_interval){p[lo][1], p[lo + 13][1]};
        z[c] = (ism_interval){p[lo][2], p[lo + 13][2]};
    }
    if (!any)
        return 0;
    *batched = true;
    w->s.n_interval += 8; /* boxes, as the octree's batches count (octree_build.c) */
    ism_eval_interval_batch(w->s.tape, w->s.ws, x, y, z, out, 8);
    uint8_t free_bits = 0;
    for (int c = 0; c < 8; c++)
        free_bits |= (uint8_t)((out[c].lo > 0 || out[c].hi < 0) << c);
    return free_bits;
}

/* Bit c: sag_split will ask for child c's centre foot (p: the 27 points; bit j of finite:
 * f and ∇f finite at point j, of neg: f < 0 there): corners of both signs, finite (else
 * classify_head answers before sag_split), under the straddle move, between
 * min_depth and depth.max, inside the request's box. A child that asks for none after all
 * (classify's earlier answers) only costs its lane. */
static uint8_t wanted_feet(const dual *d, int level, uint32_t finite, uint32_t neg,
                          const double (*p)[3])
{
    if (!sag_may_split_any(d) || level >= d->o->max_depth || level < d->o->min_depth)
        return 0;
    uint8_t want = 0;
    for (int c = 0; c < 8; c++) {
        uint32_t m = CHILD_CORNERS[c], first = (uint32_t)__builtin_ctz(m);
        if ((finite & m) == m && (neg & m) && (neg & m) != m &&
            sag_may_split(d, level, p[first], p[first + 13]))
            want |= (uint8_t)(1u << c);
    }
    return want;
}

/* What a split pass learns of a node before its children are classified (corners_task,
 * feet_task): f, the points and the unit ∇f at the 27 lattice points of their corners, the
 * children known free and their centre feet. */
typedef struct split_in {
    double f[27], p[27][3], g[27][3];
    uint32_t neg, ok; /* bit j: f < 0 at point j; f and the unit ∇f finite there
                         (ism_dual_corner_finite) */
    uint8_t known;   /* bit c: child c's box known free (the parent's or children_free) */
    uint8_t wants;   /* bit c: sag_split will ask for child c's foot (wanted_feet) */
    uint8_t foot[8]; /* child c's centre foot (corner_view.foot) */
    double foot_at[8][3];
    ism_straddle_jet foot_jet[8]; /* child c's with FOOT_AT (corner_view.foot_jet) */
} split_in;

/* Nodes per block of a split pass: its three tasks run block by block, so split_in (2.3 KB
 * a node) is held for SPLIT_BLOCK nodes however large the pass (10^5 nodes: 230 MB); 1,024
 * is many more tasks than threads, and fills the feet's 32-lane batches. */
#define SPLIT_BLOCK 1024

/* A block of a split pass: nodes[0..), what the first tasks learn of each (in), what the
 * last leaves (out), and the feet asked for (lane: 8 × a node's place in the block +
 * child). */
typedef struct split_job {
    dual *d;
    const int32_t *nodes;
    size_t m; /* nodes in the block */
    split_in *in;
    split_out *out;
    uint32_t *lane;
    size_t nlanes;
} split_job;

/* First task of a split pass: f and ∇f at the 27 lattice points of node nodes[k]'s
 * children's corners (each taken once), the children known free and those whose feet
 * sag_split will ask for, into in[k]. */
static void corners_task(void *ctx, size_t k, int thread)
{
    split_job *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    const dnode *parent = &d->n[job->nodes[k]];
    split_in *in = &job->in[k];
    split_out *out = &job->out[k];
    int32_t half = ism_grid_cell_steps(&d->g, parent->level + 1);
    int32_t q[27][3], at[3][3]; /* at[a][i]: the lattice index i halves along axis a */
    double x[3][3];             /* ... and its coordinate: 9 ism_grid_coord, not 81 */
    for (int a = 0; a < 3; a++)
        for (int i = 0; i < 3; i++) {
            at[a][i] = parent->o.v[a] + i * half;
            x[a][i] = ism_grid_coord(&d->g, a, at[a][i]);
        }
    for (int j = 0, z = 0; z < 3; z++) /* x fastest, as SPLIT_OFF reads them */
        for (int i = 0; i < 3; i++)
            for (int h = 0; h < 3; h++, j++) {
                int32_t qj[3] = {at[0][h], at[1][i], at[2][z]};
                double pj[3] = {x[0][h], x[1][i], x[2][z]};
                memcpy(q[j], qj, sizeof qj);
                memcpy(in->p[j], pj, sizeof pj);
            }
    sample_points(d, w, (const int32_t (*)[3])q, 27, in->f, in->p, in->g);
    uint32_t neg = 0, ok = 0; /* bit j: f < 0 at point j; f and ∇f finite there */
    for (int j = 0; j < 27; j++) {
        neg |= (uint32_t)(in->f[j] < 0) << j;
        ok |= (uint32_t)ism_dual_corner_finite(in->f[j], in->g[j]) << j;
    }
    in->neg = neg;
    in->ok = ok;
    in->known = parent->free_kids | children_free(d, w, parent, neg,
                                                  (const double (*)[3])in->p, &out->batched);
    out->batch_free = (uint8_t)(in->known & ~parent->free_kids);
    in->wants = wanted_feet(d, parent->level + 1, ok, neg, (const double (*)[3])in->p);
    memset(in->foot, FOOT_UNKNOWN, sizeof in->foot);
}

/* Lanes of feet per task of feet_task: the gradient evaluator's chunk (eval.h). A child's
 * foot alone, as sag_split took it, cost ~375 instructions a Newton step on the torus; a
 * batch of two or three lanes (one node's children) cost more than that, one of 32 less. */
#define FEET_LANES ISM_GRAD_BATCH

/* Second task of a split pass: the feet of lanes FEET_LANES k .. (feet_in_nodes) into
 * their nodes' split_in, and f's jet at those in their nodes (one batch,
 * ism_eval_hessian_batch: bit for bit the scalar Hessian sag_split's balanced point would
 * take there, ~1,000 instructions a point alone on the torus). */
static void feet_task(void *ctx, size_t k, int thread)
{
    split_job *job = ctx;
    dual *d = job->d;
    const uint32_t *lane = job->lane + k * FEET_LANES;
    size_t n = job->nlanes - k * FEET_LANES < FEET_LANES ? job->nlanes - k * FEET_LANES
                                                         : FEET_LANES;
    double lo[FEET_LANES][3], hi[FEET_LANES][3], m[FEET_LANES][3];
    double size[FEET_LANES] = {0}; /* n >= 1 of them set; zeroed for gcc's maybe-uninitialized */
    uint8_t state[FEET_LANES];
    for (size_t j = 0; j < n; j++) {
        const split_in *in = &job->in[lane[j] / 8];
        int first = __builtin_ctz(CHILD_CORNERS[lane[j] % 8]);
        size[j] = ism_grid_cell_size(&d->g, d->n[job->nodes[lane[j] / 8]].level + 1);
        memcpy(lo[j], in->p[first], sizeof lo[j]);
        memcpy(hi[j], in->p[first + 13], sizeof hi[j]);
    }
    worker *w = &d->w[thread];
    ism_dual_feet_in_nodes(w, (const double (*)[3])lo, (const double (*)[3])hi, size, n, m, state);
    double at[FEET_LANES][3], f[FEET_LANES], g[FEET_LANES][3], h[FEET_LANES][6];
    size_t nat = 0;
    for (size_t j = 0; j < n; j++) {
        split_in *in = &job->in[lane[j] / 8];
        in->foot[lane[j] % 8] = state[j];
        memcpy(in->foot_at[lane[j] % 8], m[j], sizeof m[j]);
        if (state[j] == FOOT_AT)
            memcpy(at[nat++], m[j], sizeof at[0]);
    }
    if (nat)
        ism_eval_hessian_batch(w->s.tape, w->s.ws, (const double (*)[3])at, f, g, h, nat);
    for (size_t j = 0, q = 0; j < n; j++) {
        if (state[j] != FOOT_AT)
            continue;
        ism_straddle_jet *jet = &job->in[lane[j] / 8].foot_jet[lane[j] % 8];
        jet->f = f[q];
        memcpy(jet->g, g[q], sizeof jet->g);
        memcpy(jet->h, h[q], sizeof jet->h);
        q++;
    }
}

/* Node k of a split pass's block: its children's nodes and views (kids, views: 8 each) from
 * what the first two tasks left in in[k]; *empty, bit c: child c empty from the masks alone
 * (no view made). */
static void split_kids(const split_job *job, size_t k, dnode *kids, corner_view *views,
                       uint8_t *empty)
{
    dual *d = job->d;
    const dnode *parent = &d->n[job->nodes[k]];
    const split_in *in = &job->in[k];
    int32_t half = ism_grid_cell_steps(&d->g, parent->level + 1);
    const double *f = in->f;
    const double (*p)[3] = (const double (*)[3])in->p, (*g)[3] = (const double (*)[3])in->g;
    uint8_t known = in->known;
    *empty = 0;
    for (int c = 0; c < 8; c++) {
        corner_view *v = &views[c];
        v->kinked = false;
        v->placed = FOOT_UNKNOWN;
        v->free_kids = 0;
        uint32_t m = CHILD_CORNERS[c], neg = in->neg & m; /* classify_head's look at the
                                                             corners, from the masks */
        v->corners = (in->ok & m) != m ? CORNERS_NOT_FINITE : (uint8_t)(1 + bits_set(neg));
        dnode *n = &kids[c];
        memset(n, 0, sizeof *n);
        n->o = parent->o;
#pragma GCC unroll 3
        for (int a = 0; a < 3; a++)
            n->o.v[a] += ((c >> a) & 1) * half;
        n->level = (uint8_t)(parent->level + 1);
        /* corners of one sign in a box shown free: classify_head's first answer, DN_EMPTY,
           whatever else the view holds (not so near points: ism_dual_leaf_kind asks the balls
           first) */
        if (!d->nballs && v->corners != CORNERS_NOT_FINITE && (neg == 0 || neg == m) &&
            (known >> c & 1)) {
            *empty |= (uint8_t)(1u << c);
#pragma GCC unroll 8
            for (int j = 0; j < 8; j++)
                n->f[j] = f[SPLIT_OFF[c] + SPLIT_OFF[j]];
            continue;
        }
        v->foot = in->foot[c];
        memcpy(v->foot_at, in->foot_at[c], sizeof v->foot_at);
        if (v->foot == FOOT_AT)
            v->foot_jet = in->foot_jet[c];
        v->known_free = known >> c & 1;
#pragma GCC unroll 8 /* constant offsets: 64 corners a split, ~40% of split_task's own */
        for (int j = 0; j < 8; j++) {
            int at = SPLIT_OFF[c] + SPLIT_OFF[j];
            n->f[j] = f[at];
            memcpy(v->p[j], p[at], sizeof v->p[j]);
            memcpy(v->n[j], g[at], sizeof v->n[j]);
        }
    }
}

/* Last task of a split pass: the children of chunk k's nodes (ism_dual_chunk) of the block
 * classified together (ism_dual_kid_kinds) from what the first two tasks left in in[]. Reads
 * the tree, writes those nodes' out[] only. */
static void split_task(void *ctx, size_t k, int thread)
{
    split_job *job = ctx;
    dual *d = job->d;
    worker *w = &d->w[thread];
    size_t lo, nodes = ism_dual_chunk(job->m, k, &lo);
    dnode kids[8 * ISM_DUAL_SPLIT_CHUNK];
    corner_view views[8 * ISM_DUAL_SPLIT_CHUNK];
    uint8_t empty[ISM_DUAL_SPLIT_CHUNK] = {0}; /* set by split_kids: for gcc, which cannot see it */
    bool bad[ISM_DUAL_SPLIT_CHUNK] = {false};
    int kind[8 * ISM_DUAL_SPLIT_CHUNK];
    for (size_t j = 0; j < nodes; j++)
        split_kids(job, lo + j, &kids[8 * j], &views[8 * j], &empty[j]);
    ism_dual_kid_kinds(d, w, kids, views, empty, nodes, kind, bad);
    for (size_t j = 0; j < nodes; j++) {
        split_out *out = &job->out[lo + j];
        out->bad = bad[j];
        out->kinked = 0;
        for (int c = 0; c < 8; c++) {
            const corner_view *v = &views[8 * j + (size_t)c];
            memcpy(out->f[c], kids[8 * j + (size_t)c].f, sizeof out->f[c]);
            out->kind[c] = (uint8_t)kind[8 * j + (size_t)c];
            out->kinked |= (uint8_t)(v->kinked << c);
            out->placed[c] = v->placed;
            out->free_kids[c] = v->free_kids;
            if (v->placed == FOOT_AT)
                memcpy(out->at[c], v->at, sizeof v->at);
        }
    }
}

/* The split pass of nodes[0..n): their children classified into out[0..n), block by block:
 * corners_task, the feet sag_split will ask for (FEET_LANES at a time), split_task. Out of
 * memory for a block's scratch: node by node, every foot left to sag_split. */
static void split_pass(dual *d, const int32_t *nodes, split_out *out, size_t n)
{
    split_in *in = malloc((n < SPLIT_BLOCK ? n : SPLIT_BLOCK) * sizeof *in), one;
    /* no lanes where sag_split never asks for a foot (wanted_feet is 0 throughout) */
    uint32_t *lane = sag_may_split_any(d) ? malloc(8 * SPLIT_BLOCK * sizeof *lane) : NULL;
    if (!in || (!lane && sag_may_split_any(d))) {
        free(in);
        free(lane);
        in = NULL;
        lane = NULL;
    }
    for (size_t b = 0; b < n;) {
        size_t m = !in ? 1 : n - b < SPLIT_BLOCK ? n - b : SPLIT_BLOCK;
        split_job job = {d, nodes + b, m, in ? in : &one, out + b, lane, 0};
        ism_pool_for(d->pool, m, corners_task, &job, NULL);
        for (size_t k = 0; lane && k < m; k++)
            for (unsigned w = job.in[k].wants; w; w &= w - 1)
                lane[job.nlanes++] = (uint32_t)(8 * k + (size_t)__builtin_ctz(w));
        ism_pool_for(d->pool, (job.nlanes + FEET_LANES - 1) / FEET_LANES, feet_task, &job, NULL);
        size_t chunks = (m + ISM_DUAL_SPLIT_CHUNK - 1) / ISM_DUAL_SPLIT_CHUNK;
        ism_pool_for(d->pool, chunks, split_task, &job, NULL);
        b += m;
    }
    free(in);
    free(lane);
}

/* Every surface flag again, from the leaves up (children come after their parent). */
static void mark_surface(dual *d)
{
    for (size_t i = d->nn; i-- > 0;) {
        dnode *n = &d->n[i];
        if (n->child < 0) {
            n->surf = has_sheet(n->kind);
            continue;
        }
        uint8_t surf = 0;
        for (int c = 0; c < 8; c++)
            surf |= d->n[n->child + c].surf;
        n->surf = surf;
    }
}

/* Every thread's point memo grown to DUAL_POINT_ENTRIES_PER_NODE entries for each of
 * `nodes` nodes (at most 2^DUAL_POINT_BITS), its entries moved to their slots in the larger
 * table (one of two meeting there kept); false (nomem set) when out of memory. */
static bool points_for(dual *d, size_t nodes)
{
    int bits = DUAL_POINT_MIN_BITS;
    while (bits < DUAL_POINT_BITS && ((size_t)1 << bits) < DUAL_POINT_ENTRIES_PER_NODE * nodes)
        bits++;
    for (int k = 0; k < d->nw; k++) {
        worker *w = &d->w[k];
        if (w->bits >= bits)
            continue;
        ism_point_entry *grown;
        uint64_t *filled;
        if (!points_alloc(bits, &grown, &filled)) {
            d->nomem = true;
            return false;
        }
        uint64_t mask = ((uint64_t)1 << bits) - 1;
        ISM_BITS_EACH(w->filled, ism_bits_words((size_t)1 << w->bits), i) {
            size_t j = ism_cache_mix(w->points[i].key) & mask;
            grown[j] = w->points[i];
            ism_bit_set(filled, j);
        }
        free(w->points);
        free(w->filled);
        w->points = grown;
        w->filled = filled;
        w->bits = bits;
    }
    return true;
}

/* The nodes in list[0..n) split, and their children that are neither empty nor plain, level
 * by level, until every leaf is. The children's classifications run on the pool; the nodes
 * are made in list order, so the tree does not depend on the threads. */
static void expand(dual *d, const int32_t *list, size_t n)
{
    int32_t *cur = malloc((n ? n : 1) * sizeof *cur);
    split_out *out = NULL;
    if (!cur)
        d->nomem = true;
    else
        memcpy(cur, list, n * sizeof *cur);
    while (n && !d->bad && !d->nomem && !d->too_big && !(d->o->cancel && *d->o->cancel)) {
        int32_t *next = malloc(8 * n * sizeof *next);
        free(out); /* the last level's: nothing in it is read again (realloc would copy it) */
        split_out *grown = malloc(n * sizeof *out);
        out = grown;
        if (!next || !grown) {
            free(next);
            d->nomem = true;
            break;
        }
        if (!points_for(d, d->nn + 8 * n)) {
            free(next);
            break;
        }
        d->batch_on = d->batch_freed >= BATCH_PAYS * d->batches;
        split_pass(d, cur, out, n);
        for (size_t k = 0; k < n; k++)
            if (batch_judged(d, d->n[cur[k]].level)) {
                d->batches += out[k].batched;
                d->batch_freed += (uint64_t)bits_set(out[k].batch_free);
            }
        /* the level's room at once (the sag_split vertices' too, where there are any):
           one node at a time, the tree's doublings copied it over and over (sphere at E
           0.00714: 114K instructions of realloc's copying of 7.7M); out of memory here,
           new_node and keep_at grow node by node. At most the nodes max_memory lets
           held_bytes count (new_node stops the tree there): the doubling above the level's
           room could otherwise ask for several times max_memory of address space (revR 5) */
        size_t room = d->nn + 8 * n, most = d->o->max_memory / sizeof *d->n + 1;
        room = room < most ? room : most;
        grow((void **)&d->n, &d->capn, room, sizeof *d->n);
        if (sag_may_split_any(d))
            grow((void **)&d->at, &d->capat, room, sizeof *d->at);
        size_t nn = 0;
        for (size_t k = 0; k < n && !d->nomem && !d->too_big; k++) {
            int32_t i = cur[k], first = -1;
            int level = d->n[i].level + 1;
            int32_t half = ism_grid_cell_steps(&d->g, level);
            if (out[k].bad) /* the box cuts the surface (ism_dual_leaf_kind) */
                decline(d, ISM_DUAL_WHY_BOX_CUT);
            for (int c = 0; c < 8; c++) {
                ism_ipt o = d->n[i].o;
                int32_t at;
#pragma GCC unroll 3
                for (int a = 0; a < 3; a++)
                    o.v[a] += ((c >> a) & 1) * half;
                if (!new_node(d, o, level, &at)) {
                    d->nomem = !d->too_big;
                    break;
                }
                first = c ? first : at;
                dnode *ch = &d->n[at];
                memcpy(ch->f, out[k].f[c], sizeof ch->f);
                ch->placed = out[k].placed[c];
                ch->free_kids = out[k].free_kids[c];
                if (ch->placed == FOOT_AT && !keep_at(d, at, out[k].at[c]))
                    break;
                ch->kind = out[k].kind[c];
                if (ch->kind != DN_INNER)
                    continue;
                if (level < d->o->max_depth)
                    next[nn++] = at;
                else if (near_point(d, ch, 0))
                    ch->kind = DN_HOLE; /* sheets a cell apart beside a node: its hole */
                else if (out[k].kinked >> c & 1)
                    decline(d, ISM_DUAL_WHY_MIN_MAX); /* the crease not resolved */
                else
                    decline(d, ISM_DUAL_WHY_NOT_PLAIN); /* at the deepest level: a feature */
            }
            d->n[i].kind = DN_INNER;
            d->n[i].child = first;
        }
        free(cur);
        cur = next;
        n = nn;
    }
    free(out);
    free(cur);
    mark_surface(d);
}

/* In the grown box (dual_box.h): every vertex of a leaf touching the grown box lies beyond
 * the request's box's plane on each side it touches, so the mesh's open edges (between two
 * such leaves sharing a face on the grown box) are clipped away whole. */
static bool margin_vertices_outside(const dual *d)
{
    int32_t last = (int32_t)1 << d->g.depth;
    for (size_t i = 0; i < d->nn; i++) {
        const dnode *n = &d->n[i];
        if (n->child >= 0 || n->kind != DN_SURF || n->vert < 0)
            continue;
        int32_t step = ism_grid_cell_steps(&d->g, n->level);
        const double *p = &d->pos[3 * n->vert];
        for (int a = 0; a < 3; a++)
            if ((n->o.v[a] == 0 && !(p[a] < d->inner[a])) ||
                (n->o.v[a] + step == last && !(p[a] > d->inner[a + 3])))
                return false;
    }
    return true;
}

/* The mean of node n's (box lo..hi: its corners 0 and 7, corner_point's) crossed edges'
 * secant roots into m; its centre when no edge is crossed (a small crease-side leaf not
 * shown empty, dual_crease.h). */
static void roots_mean(const dual *d, const dnode *n, const double lo[3], const double hi[3],
                       double m[3])
{
    int roots = 0;
    memset(m, 0, 3 * sizeof *m);
    for (int e = 0; e < 12; e++) {
        int c0 = d->ec0[e], c1 = d->ec1[e];
        if ((n->f[c0] < 0) == (n->f[c1] < 0))
            continue;
        double t = n->f[c0] / (n->f[c0] - n->f[c1]); /* the secant root */
        for (int a = 0; a < 3; a++) { /* corner c's coordinate a: lo's or hi's (corner_point) */
            double p0 = c0 >> a & 1 ? hi[a] : lo[a], p1 = c1 >> a & 1 ? hi[a] : lo[a];
            m[a] += p0 + t * (p1 - p0);
        }
        roots++;
    }
    for (int a = 0; a < 3; a++)
        m[a] = roots ? m[a] / roots : 0.5 * lo[a] + 0.5 * hi[a];
}

/* ism_dual_feet_in_nodes of the na boxes lo[i]..hi[i] (side size[i]) into m[at[i]] and
 * state[at[i]]. */
static void lane_feet(worker *w, const double (*lo)[3], const double (*hi)[3],
                      const double *size, const size_t *at, size_t na, double (*m)[3],
                      uint8_t *state)
{
    double foot[MEASURE_LANES][3];
    uint8_t st[MEASURE_LANES];
    if (!na)
        return;
    ism_dual_feet_in_nodes(w, lo, hi, size, na, foot, st);
    for (size_t i = 0; i < na; i++) {
        memcpy(m[at[i]], foot[i], sizeof foot[i]);
        state[at[i]] = st[i];
    }
}

/* The vertices of the plain leaves leaf[0..n) (n <= MEASURE_LANES; none a pair, none whose
 * vertex sag_split made, none a crease leaf whose crease point was found) into pos: the
 * leaf's centre moved onto f = 0 by Newton when that lands in the leaf's closed box, else
 * the mean of its edges' secant roots so moved (the exact roots would cost a fifth of the
 * whole mesh for a start point Newton forgets); then along ∇f by the balanced straddle share
 * (straddle.h: the full 0.9 E where the surface bends one way, E (l1 + l2) / (l1 - l2) at
 * saddles; torus raw triangles 1e-2 / 3e-3 / 1e-3 3,536 / 5,792 / 17,472 -> 2,872 / 4,560 /
 * 18,048, the sphere's unchanged). The centre's foot spaces the vertices about a leaf apart
 * where the roots' mean bunches them toward the leaf's crossed corner (edges up to two
 * leaves long): raw triangles sphere 1e-2 / 3e-3 / 1e-3 1,068 / 3,496 / 8,556 -> 828 /
 * 3,108 / 8,220, torus 3,280 / 5,968 / 20,464 -> 3,536 / 5,792 / 17,472 (-9% over the six).
 * The one routine for these steps, each in lanes: the centres' feet not taken yet
 * (ism_dual_feet_in_nodes), then Newton from the secant roots' mean for those whose foot
 * left the leaf (ism_dual_newton_lanes), then f's jets at the points in one batch for the straddle
 * move (ism_eval_hessian_batch, as feet_task's). One by one, Newton's gradients and the Hessian
 * cost ~1,040 instructions each a leaf (sphere at 0.00714: 120 leaves whose foot left
 * them). */
static void place_plain(dual *d, worker *w, const int32_t *leaf, size_t n)
{
    double lo[MEASURE_LANES][3], hi[MEASURE_LANES][3], size[MEASURE_LANES], m[MEASURE_LANES][3];
    /* sz and at zeroed: lane_feet reads only the first na, which gcc -O1 (the sanitizer
     * lane) cannot see and calls maybe-uninitialized under -Werror */
    double a[MEASURE_LANES][3], b[MEASURE_LANES][3], sz[MEASURE_LANES] = {0};
    uint8_t state[MEASURE_LANES];
    size_t at[MEASURE_LANES] = {0}, na = 0;
    for (size_t j = 0; j < n; j++) {
        const dnode *nd = &d->n[leaf[j]];
        corner_point(d, nd, 0, lo[j]);
        corner_point(d, nd, 7, hi[j]);
        size[j] = ism_grid_cell_size(&d->g, nd->level);
        state[j] = FOOT_OUT;
        if (nd->placed != FOOT_OUT) {
            memcpy(a[na], lo[j], sizeof a[na]);
            memcpy(b[na], hi[j], sizeof b[na]);
            sz[na] = size[j];
            at[na++] = j;
        }
    }
    lane_feet(w, (const double (*)[3])a, (const double (*)[3])b, sz, at, na, m, state);
    na = 0;
    for (size_t j = 0; j < n; j++) {
        if (state[j] == FOOT_AT)
            continue;
        roots_mean(d, &d->n[leaf[j]], lo[j], hi[j], m[j]);
        memcpy(a[na], m[j], sizeof a[na]);
        sz[na] = size[j];
        at[na++] = j;
    }
    bool ok[MEASURE_LANES]; /* unread: a lane Newton failed in keeps where it stopped */
    ism_dual_newton_lanes(w, a, sz, na, ok);
    for (size_t i = 0; i < na; i++)
        memcpy(m[at[i]], a[i], sizeof a[i]);
    if (d->shift > 0) {
        double f[MEASURE_LANES], g[MEASURE_LANES][3], h[MEASURE_LANES][6];
        ism_eval_hessian_batch(w->s.tape, w->s.ws, (const double (*)[3])m, f, g, h, n);
        for (size_t j = 0; j < n; j++) {
            ism_straddle_jet jet = {f[j], {g[j][0], g[j][1], g[j][2]},
                                    {h[j][0], h[j][1], h[j][2], h[j][3], h[j][4], h[j][5]}};
            double q[3];
            if (ism_straddle_balanced_point_at(&w->s, d->shift, d->o->box, m[j], &jet, q, NULL))
                memcpy(m[j], q, sizeof q);
        }
    }
    for (size_t j = 0; j < n; j++)
        memcpy(&d->pos[3 * (size_t)d->n[leaf[j]].vert], m[j], sizeof m[j]);
}

/* Task k (job: in the leaves, all placed_in_lanes; n how many): place_plain for leaves
 * in[MEASURE_LANES k ..]. */
static void place_lanes(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    size_t first, n = chunk_of(k, job->n, &first);
    place_plain(job->d, &job->d->w[thread], (const int32_t *)job->in + first, n);
}

/* Leaf i's vertex into pos[3 vert]: a crease leaf's on its crease where classify's search
 * finds it, a pair's two, the one sag_split made; else place_plain's (a crease leaf whose
 * crease point was not found: one lane; the plain leaves go to place_plain through
 * place_lanes, MEASURE_LANES at a time). */
static void place_vertex(dual *d, worker *w, int32_t i)
{
    const dnode *n = &d->n[i];
    double m[3], lo[3], hi[3];
    corner_point(d, n, 0, lo);
    corner_point(d, n, 7, hi);
    if (n->kind == DN_CREASE && (ism_dual_crease_vertex(&w->s, lo, hi, m) ||
                                 ism_dual_crease_near(&w->s, lo, hi, m))) {
        memcpy(&d->pos[3 * n->vert], m, sizeof m); /* on the crease, as classify found it */
        return;
    }
    if (n->kind == DN_PAIR) {
        double p[8][3];
        for (int c = 0; c < 8; c++)
            corner_point(d, n, c, p[c]);
        for (int k = 0; k < 2; k++) {
            ism_dual_pair_vertex(&w->s, (const double (*)[3])p, n->f, k, m);
            memcpy(&d->pos[3 * (k ? n->vert2 : n->vert)], m, sizeof m);
        }
        return;
    }
    if (n->placed == FOOT_AT) { /* sag_split made it as below */
        memcpy(&d->pos[3 * n->vert], d->at[i], sizeof m);
        return;
    }
    place_plain(d, w, &i, 1); /* a crease leaf whose crease point was not found */
}

static void vertex_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    place_vertex(job->d, &job->d->w[thread], ((const int32_t *)job->in)[k]);
}

/* Is leaf n's vertex one place_lanes makes (a plain leaf's that sag_split did not make)? */
static bool placed_in_lanes(const dnode *n)
{
    return n->kind == DN_SURF && n->placed != FOOT_AT;
}

/* Room for n more vertices (positions and leaves); false when out of memory. */
bool ism_dual_reserve_vertices(dual *d, size_t n)
{
    size_t capl = d->capv;
    if (!grow((void **)&d->pos, &d->capv, d->nv + n, 3 * sizeof *d->pos))
        return false;
    if (d->capv != capl) {
        int32_t *vl = realloc(d->vleaf, d->capv * sizeof *vl);
        if (vl)
            d->vleaf = vl;
        int32_t *vt = vl ? realloc(d->vtwin, d->capv * sizeof *vt) : NULL;
        if (!vt)
            return false;
        d->vtwin = vt;
    }
    return true;
}

/* Two crease leaves that found one point (within WELD_TOL of the box: Newton's rounding is
 * ~1e-16 of it, any bound far above) share one vertex: the later leaf takes the earlier
 * vertex and its own joins that one's twin chain (ism_dual_mark_misses splits every leaf on it).
 * Without it the two make triangles of no area (the lens's crease on the lattice plane
 * x = 0: every such triangle counted as turned over, split to depth.max). New vertices are
 * from nv0 on. */
static void weld_crease(dual *d, size_t nv0)
{
    size_t n = 0;
    for (size_t i = 0; i < d->nn; i++)
        n += d->n[i].child < 0 && d->n[i].kind == DN_CREASE && d->n[i].vert >= 0;
    uint32_t *ids = malloc((n ? n : 1) * sizeof *ids), *to = malloc((n ? n : 1) * sizeof *to);
    int32_t *at = malloc((n ? n : 1) * sizeof *at);
    n = 0;
    for (size_t i = 0; ids && at && i < d->nn; i++)
        if (d->n[i].child < 0 && d->n[i].kind == DN_CREASE && d->n[i].vert >= 0) {
            at[n] = (int32_t)i;
            ids[n++] = (uint32_t)d->n[i].vert;
        }
    double size = fmin(d->o->box[3] - d->o->box[0],
                       fmin(d->o->box[4] - d->o->box[1], d->o->box[5] - d->o->box[2]));
    if (!ids || !to || !at || !ism_dual_weld(d->pos, ids, n, WELD_TOL * size, to))
        d->nomem = true;
    for (size_t k = 0; !d->nomem && k < n; k++) {
        uint32_t u = ids[k], r = to[k];
        if (u == r || u < nv0)
            continue;
        d->n[at[k]].vert = (int32_t)r;
        d->vtwin[u] = d->vtwin[r];
        d->vtwin[r] = (int32_t)u;
    }
    free(ids);
    free(to);
    free(at);
}

/* Vertices for the surface leaves that have none, numbered in node order, placed on the
 * pool. */
static void make_vertices(dual *d)
{
    size_t nv0 = d->nv;
    size_t n = 0, pairs = 0;
    for (size_t i = 0; i < d->nn; i++) {
        n += d->n[i].child < 0 && has_sheet(d->n[i].kind) && d->n[i].vert < 0;
        pairs += d->n[i].child < 0 && d->n[i].kind == DN_PAIR && d->n[i].vert < 0;
    }
    int32_t *leaves = malloc((n ? n : 1) * sizeof *leaves);
    if (!leaves || !ism_dual_reserve_vertices(d, n + pairs)) { /* a pair leaf has two */
        free(leaves);
        d->nomem = true;
        return;
    }
    size_t nl = 0; /* leaves[0..nl): placed in lanes; leaves[n..): one by one, from the end */
    for (size_t i = 0, top = n; i < d->nn; i++)
        if (d->n[i].child < 0 && has_sheet(d->n[i].kind) && d->n[i].vert < 0) {
            for (int k = 0; k <= (d->n[i].kind == DN_PAIR); k++) {
                *(k ? &d->n[i].vert2 : &d->n[i].vert) = (int32_t)d->nv;
                d->vtwin[d->nv] = -1;
                d->vleaf[d->nv++] = (int32_t)i;
            }
            if (placed_in_lanes(&d->n[i]))
                leaves[nl++] = (int32_t)i;
            else
                leaves[--top] = (int32_t)i;
        }
    task_ctx lanes = {d, leaves, NULL, nl}, one = {d, leaves + nl, NULL, 0};
    ism_pool_for(d->pool, chunks(nl), place_lanes, &lanes, NULL);
    ism_pool_for(d->pool, n - nl, vertex_task, &one, NULL);
    free(leaves);
    if (d->crease && n)
        weld_crease(d, nv0);
}

/* The leaves marked by ism_dual_mark_misses split (expand: their children built level by level). */
static void split_marked(dual *d)
{
    size_t n = 0;
    for (size_t i = 0; i < d->nn; i++)
        n += d->n[i].split;
    int32_t *list = malloc((n ? n : 1) * sizeof *list);
    if (!list) {
        d->nomem = true;
        return;
    }
    n = 0;
    for (size_t i = 0; i < d->nn; i++)
        if (d->n[i].split) {
            d->n[i].split = 0;
            list[n++] = (int32_t)i;
        }
    expand(d, list, n);
    free(list);
}

/* Task k (job: in the vertices, out their normals, n how many): the unit ∇f at vertices
 * used[MEASURE_LANES k ..], their gradients in one batch. */
static void normal_task(void *ctx, size_t k, int thread)
{
    task_ctx *job = ctx;
    const uint32_t *used = job->in;
    float *nrm = job->out;
    size_t lo, n = chunk_of(k, job->n, &lo);
    double p[MEASURE_LANES][3], f[MEASURE_LANES], g[MEASURE_LANES][3];
    for (size_t j = 0; j < n; j++)
        memcpy(p[j], &job->d->pos[3 * (size_t)used[lo + j]], sizeof p[j]);
    ism_sample_grad_batch(&job->d->w[thread].s, (const double (*)[3])p, f, g, n);
    for (size_t j = 0; j < n; j++) {
        ism_normalise3(g[j]);
        for (int a = 0; a < 3; a++)
            nrm[3 * (lo + j) + a] = (float)g[j][a];
    }
}

/* The vertices the triangles use (their normals from ∇f, on the pool) and the triangles,
 * renumbered in order of first use, into mesh. */
static bool to_mesh(dual *d, ism_mesh *mesh)
{
    size_t nv = d->nv ? d->nv : 1;
    uint32_t *map = malloc(nv * sizeof *map), *used = malloc(nv * sizeof *used);
    float *nrm = malloc(3 * nv * sizeof *nrm);
    bool ok = map && used && nrm;
    size_t nu = 0;
    if (ok) {
        memset(map, 0xff, nv * sizeof *map);
        for (size_t t = 0; t < 3 * d->nt; t++) {
            uint32_t v = d->tri[t];
            if (map[v] == UINT32_MAX) {
                map[v] = (uint32_t)nu;
                used[nu++] = v;
            }
        }
        task_ctx job = {d, used, nrm, nu};
        ism_pool_for(d->pool, chunks(nu), normal_task, &job, NULL);
        ok = ism_mesh_reserve(mesh, nu, d->nt); /* at once: one at a time copies */
    }
    for (size_t k = 0; k < nu && ok; k++)
        ok = ism_mesh_add_vertex(mesh, &d->pos[3 * used[k]], &nrm[3 * k]) == k;
    for (size_t t = 0; t < d->nt && ok; t++)
        ok = ism_mesh_add_triangle(mesh, map[d->tri[3 * t]], map[d->tri[3 * t + 1]],
                                   map[d->tri[3 * t + 2]]);
    free(map);
    free(used);
    free(nrm);
    return ok;
}

bool ism_dual_wanted(const ism_tape *f, const ism_poly_options *o)
{
    ism_poly_options asked = *o;
    asked.dual = true;
    return ism_dual_declined_before(f, &asked) == ISM_DUAL_WHY_NONE;
}

/* The miss masks of the round's triangles into miss[0..nt): those ism_dual_emit_quads measured
 * read from d->tmiss (a second measure gives the same masks: the pairs' distances from the
 * memo, the centroids measured again), the others (the fans' triangles, a quad's lone
 * triangle) measured now. Torus at 1e-2: 696 of its 984 triangles read, 15.395M -> 15.364M
 * instructions, 3.57e-3 34.82M -> 34.66M (bench_error, callgrind on ism_mesh_surface). */
static void measure_round(dual *d, uint8_t *miss)
{
    const uint8_t *known = d->ntmiss == d->nt ? d->tmiss : NULL;
    uint32_t *list = known ? malloc((d->nt ? d->nt : 1) * sizeof *list) : NULL;
    if (!list) { /* nothing known (or no memory for the list): every triangle */
        ism_dual_measure_triangles(d, NULL, d->nt, miss);
        return;
    }
    size_t nl = 0;
    for (size_t t = 0; t < d->nt; t++) {
        miss[t] = known[t] & (uint8_t)~TMISS_KNOWN;
        if (!(known[t] & TMISS_KNOWN))
            list[nl++] = (uint32_t)t;
    }
    uint8_t *lmiss = nl ? malloc(nl) : NULL;
    if (nl && !lmiss)
        ism_dual_measure_triangles(d, NULL, d->nt, miss);
    else if (nl) {
        ism_dual_measure_triangles(d, list, nl, lmiss);
        for (size_t k = 0; k < nl; k++)
            miss[list[k]] = lmiss[k];
    }
    free(lmiss);
    free(list);
}

/* The round's triangles measured; where every miss is a side a few E off those sides are cut
 * (dual_sides.h: nothing to mark), else the leaves round the misses are marked
 * (ism_dual_mark_misses). Returns the leaves marked; the misses at max_depth into *missed. */
static size_t mark_round(dual *d, uint64_t *missed)
{
    *missed = 0;
    uint8_t *miss = malloc(d->nt ? d->nt : 1);
    if (!miss) {
        d->nomem = true;
        return 0;
    }
    measure_round(d, miss);
    size_t marked = 0;
    if (!d->nomem && !ism_dual_split_sides(d, miss))
        marked = ism_dual_mark_misses(d, miss, missed);
    free(miss);
    return marked;
}

static enum ism_dual_status mesh_rounds(dual *d, ism_mesh *mesh, ism_dual_stats *st)
{
    int32_t root;
    if (!new_node(d, (ism_ipt){{0, 0, 0}}, 0, &root))
        return ISM_DUAL_NO_MEMORY;
    corner_view v;
    v.kinked = false;
    v.placed = FOOT_UNKNOWN;
    v.foot = FOOT_UNKNOWN;
    v.known_free = false;
    v.free_kids = 0;
    v.corners = 0; /* classify_head looks at them */
    int32_t last = (int32_t)1 << d->g.depth, q[8][3];
    dnode *r0 = &d->n[root];
    for (int c = 0; c < 8; c++)
        for (int a = 0; a < 3; a++)
            q[c][a] = (c >> a & 1) * last;
    sample_corners(d, &d->w[0], (const int32_t (*)[3])q, 8, r0->f, v.p, v.n);
    bool cut = false;
    r0->kind = (uint8_t)ism_dual_leaf_kind(d, &d->w[0], r0, &v, &cut);
    r0->free_kids = v.free_kids;
    if (cut)
        decline(d, ISM_DUAL_WHY_BOX_CUT);
    if (r0->kind == DN_INNER && !d->bad)
        expand(d, &root, 1); /* ends with mark_surface */
    else
        mark_surface(d);
    for (int r = 0;; r++) {
        if (d->o->cancel && *d->o->cancel)
            return ISM_DUAL_CANCELLED;
        if (d->too_big)
            return ISM_DUAL_TOO_BIG;
        if (d->nomem)
            return ISM_DUAL_NO_MEMORY;
        if (d->bad)
            return st->declined = d->why, ISM_DUAL_NOT_APPLICABLE;
        make_vertices(d);
        if (!d->nomem && d->inner && !margin_vertices_outside(d))
            decline(d, ISM_DUAL_WHY_BOX_CUT);
        if (!d->nomem && !d->bad)
            ism_dual_make_quads(d);
        if (!d->nomem && !d->bad)
            ism_dual_emit_quads(d);
        if (d->nomem)
            return ISM_DUAL_NO_MEMORY;
        if (d->bad)
            return st->declined = d->why, ISM_DUAL_NOT_APPLICABLE;
        if (d->nt > d->o->max_triangles)
            return ISM_DUAL_TOO_BIG;
        size_t marked = mark_round(d, &st->missed);
        if (!d->nomem && !marked && !st->missed && d->inner)
            marked = ism_dual_mark_cut_misses(d, &st->missed);
        if (d->crease)
            marked += ism_dual_mark_not_manifold(d);
        if (d->nomem)
            return ISM_DUAL_NO_MEMORY;
        if (d->bad)
            return st->declined = d->why, ISM_DUAL_NOT_APPLICABLE;
        if (st->missed) { /* beyond E at depth.max: the primal polygons */
            st->declined = ISM_DUAL_WHY_ERROR;
            return ISM_DUAL_NOT_APPLICABLE;
        }
        if (!marked || r == DUAL_ROUNDS)
            break;
        st->rounds++;
        split_marked(d);
    }
    st->coarse_nodes = 0;
    for (size_t i = 0; i < d->nn; i++) {
        st->leaves += d->n[i].child < 0 && has_sheet(d->n[i].kind);
        st->coarse_nodes += d->n[i].level <= d->o->min_depth;
    }
    return to_mesh(d, mesh) ? ISM_DUAL_OK : ISM_DUAL_NO_MEMORY;
}

/* The mesh of the request (mesh_rounds), the walk memo freed after it: it only serves the
 * next round, and a mesher kept for reuse would hold a full set of quads while idle. */
static enum ism_dual_status run(dual *d, ism_mesh *mesh, ism_dual_stats *st)
{
    enum ism_dual_status status = mesh_rounds(d, mesh, st);
    ism_dual_walk_memo_free(&d->memo);
    memset(&d->memo, 0, sizeof d->memo);
    return status;
}

/* The tree, the vertices, the triangles and the memos freed and zeroed (the pool, the
 * workers and the options kept): for the next try, or the end. */
static void forget(dual *d)
{
    free(d->n);
    free(d->at);
    free(d->pos);
    free(d->vleaf);
    free(d->vtwin);
    free(d->tri);
    free(d->tmiss);
    free(d->q.q);
    ism_dual_walk_memo_free(&d->memo);
    keyed_free(&d->passed);
    keyed_free(&d->mid);
    keyed_free(&d->fans);
    keyed_free(&d->sides);
    d->n = NULL;
    d->at = NULL;
    d->pos = NULL;
    d->vleaf = NULL;
    d->vtwin = NULL;
    d->tri = NULL;
    d->tmiss = NULL;
    d->ntmiss = 0;
    d->nn = d->capn = d->heldn = d->capat = d->heldat = d->nv = d->capv = d->nt = d->capt = 0;
    memset(&d->q, 0, sizeof d->q);
    memset(&d->memo, 0, sizeof d->memo);
    memset(&d->passed, 0, sizeof d->passed);
    memset(&d->mid, 0, sizeof d->mid);
    memset(&d->fans, 0, sizeof d->fans);
    memset(&d->sides, 0, sizeof d->sides);
    d->bad = d->nomem = d->too_big = false;
    d->why = ISM_DUAL_WHY_NONE;
}

/* A ball halved is stuck when its clip sphere comes out no smaller than this share of the
 * last try's: its rim is then held by the leaves round the point that the proofs could not
 * make plain within its limit (they join the hole, near_point), not by the hole, and
 * halving it again makes the same mesh. kummer-16-nodes 3e-3 depth.max 9, +1e-3 box: the
 * rim of the node (1, 0, −1) stayed at 0.159-0.160 through five halvings (folds of radius
 * 0.03-0.04 between it and (0.707, 0, −0.5), a cell 0.017 across), 7 meshes for point_fan. A
 * ball whose hole sets its rim shrinks it by 0.5-0.8 (the +1e-3 box at 1e-2 before the
 * turned cuts were mended: 0.099, 0.052, 0.041). */
#define RIM_STUCK 0.9

/* run, and round the isolated singular points o->dual_points (dual_balls.h): the mesh with a
 * hole at each, clipped and fanned to the point; where a fan misses E or a rim is not its
 * node's two loops (one for each nappe), every such ball is halved and the mesh made again,
 * each ball up to ISM_DUAL_BALL_SHRINKS times (then "point_fan"), and none again once a
 * halved ball's rim stays put (RIM_STUCK: "point_fan" at once). */
static enum ism_dual_status run_round_points(dual *d, ism_mesh *mesh, ism_dual_stats *st)
{
    size_t n = d->o->ndual_points;
    if (!n)
        return run(d, mesh, st);
    ism_dual_ball *balls = malloc(n * sizeof *balls);
    int *shrink = calloc(n, sizeof *shrink);
    uint8_t *missed = malloc(n);
    double *rim = malloc(n * sizeof *rim), *last = malloc(n * sizeof *last);
    enum ism_dual_status status =
        balls && shrink && missed && rim && last ? ISM_DUAL_OK : ISM_DUAL_NO_MEMORY;
    d->balls = balls;
    d->nballs = n;

    while (status == ISM_DUAL_OK) {
        for (size_t k = 0; k < n; k++)
            ism_dual_ball_make(&balls[k], d->o->dual_points[k], d->inner ? d->inner : d->o->box,
                               d->o->max_error, shrink[k]);
        ism_dual_ball_cover_free(&d->cover);
        ism_dual_ball_cover_init(&d->cover, balls, n);
        forget(d);
        ism_mesh_free(mesh);
        st->leaves = st->missed = 0;
        if ((status = run(d, mesh, st)) != ISM_DUAL_OK)
            break;
        enum ism_fan_status fan = ism_dual_balls_fan(mesh, &d->w[0].s, balls, n, &d->cover,
                                                     d->o->max_error, missed, rim);
        if (fan == ISM_FAN_OK)
            break;
        if (fan == ISM_FAN_NO_MEMORY) {
            status = ISM_DUAL_NO_MEMORY;
            break;
        }
        bool any = false, spent = false; /* every ball marked halves, all in one more try */
        for (size_t k = 0; k < n; k++)
            if (missed[k]) {
                any = true;
                /* at its smallest already, or halved last time for nothing */
                spent |= shrink[k] == ISM_DUAL_BALL_SHRINKS ||
                         (shrink[k] && !(rim[k] < RIM_STUCK * last[k]));
                shrink[k]++;
                last[k] = rim[k];
            }
        if (!any || spent) {
            st->declined = ISM_DUAL_WHY_POINT_FAN;
            status = ISM_DUAL_NOT_APPLICABLE;
        }
    }
    free(missed);
    free(balls);
    free(shrink);
    free(rim);
    free(last);
    ism_dual_ball_cover_free(&d->cover);
    d->balls = NULL;
    d->nballs = 0;
    return status;
}

/* run_round_points in the box grown round the request's (dual_box.h), its mesh then clipped
 * by the request's box: for a surface the box cuts. The memos keyed by lattice points are
 * emptied (the lattice is the grown box's). A cut beyond E or not settled declines for the
 * box (box_cut), as a margin leaf's vertex inside the request's box does. */
static enum ism_dual_status run_in_grown_box(dual *d, ism_mesh *mesh, ism_dual_stats *st)
{
    const ism_poly_options *given = d->o;
    st->declined = ISM_DUAL_WHY_BOX_CUT;
    if (given->max_depth <= ISM_DUAL_BOX_LEVEL) /* no level for the margin's leaves */
        return ISM_DUAL_NOT_APPLICABLE;
    ism_poly_options grown = *given;
    ism_dual_box_grow(given->box, ISM_DUAL_BOX_LEVEL, grown.box);
    d->o = &grown;
    d->inner = given->box;
    set_grid(d, grown.box, grown.max_depth);
    for (int k = 0; k < d->nw; k++) {
        memset(d->w[k].filled, 0,
               ism_bits_words((size_t)1 << d->w[k].bits) * sizeof *d->w[k].filled);
        free(d->w[k].pairs);
        free(d->w[k].pairs_filled);
        d->w[k].pairs = NULL;
        d->w[k].pairs_filled = NULL;
        d->w[k].pairs_tried = false;
    }
    forget(d);
    ism_mesh_free(mesh);
    st->declined = ISM_DUAL_WHY_NONE;
    st->leaves = st->missed = st->rounds = 0;
    enum ism_dual_status status = run_round_points(d, mesh, st);
    if (status == ISM_DUAL_OK) {
        ism_box_clip_stats cs;
        enum ism_box_clip_status c =
            ism_dual_box_clip(mesh, &d->w[0].s, given->box, given->max_error, NULL, &cs);
        if (c == ISM_BOX_CLIP_NO_MEMORY)
            status = ISM_DUAL_NO_MEMORY;
        else if (c != ISM_BOX_CLIP_OK) {
            st->declined = ISM_DUAL_WHY_BOX_CUT;
            status = ISM_DUAL_NOT_APPLICABLE;
        }
    }
    d->o = given;
    d->inner = NULL;
    return status;
}

/* Worker w zeroed but for its sampler's label memo (sampler.h, 40 KB a thread: clearing it
 * by calloc cost the sphere at E 0.0141 41K of its 2.51M instructions, bench_error under
 * callgrind): crease_split.c reads that memo only while the sampler's memo_tape is its tape,
 * and the dual mesher's samplers keep memo_tape NULL. */
static void worker_clear(worker *w)
{
    size_t from = offsetof(worker, s) + offsetof(ism_sampler, label_memo);
    size_t to = from + sizeof w->s.label_memo;
    memset(w, 0, from);
    memset((char *)w + to, 0, sizeof *w - to);
}

/* Threads for the call: o->threads, or every core (0), at most ISM_MAX_THREADS. */
static int thread_count(const ism_poly_options *o)
{
    return ism_threads_resolve(o->threads);
}

/* ism_dual_mesh, or with grown ism_dual_mesh_grown: the grown box at once, as if seen cut. */
static enum ism_dual_status dual_mesh(const ism_tape *f, const ism_poly_options *o,
                                      ism_mesh *mesh, ism_dual_stats *st, bool grown)
{
    memset(st, 0, sizeof *st);
    ism_mesh_free(mesh);
    ism_poly_options asked = *o; /* ism_dual_wanted's question, keeping the reason */
    asked.dual = true;
    if ((st->declined = ism_dual_declined_before(f, &asked)) != ISM_DUAL_WHY_NONE)
        return ISM_DUAL_NOT_APPLICABLE;
    dual d;
    memset(&d, 0, sizeof d);
    d.o = o;
    d.crease = o->dual_crease && ism_tape_top_min_max_only(f);
    d.shift = ism_straddle_shift(f, o->max_error, false);
    set_grid(&d, o->box, o->max_depth);
    for (int e = 0; e < 12; e++)
        ism_cube_edge(e, &d.ec0[e], &d.ec1[e], d.ef[e]);
    d.pool = ism_pool_new(thread_count(o));
    d.nw = d.pool ? ism_pool_threads(d.pool) : 0;
    d.w = malloc((d.nw ? (size_t)d.nw : 1) * sizeof *d.w);
    bool ok = d.pool && d.w;
    for (int k = 0; ok && k < d.nw; k++) {
        worker *w = &d.w[k];
        worker_clear(w);
        w->s.tape = f;
        w->s.ws = ism_eval_ws_new(f);
        w->s.batch = !o->scalar_eval; /* the measure's gradients in batches */
        w->jet = ism_ivjet_ws_new(f);
        w->bits = DUAL_POINT_MIN_BITS;
        bool memo = points_alloc(w->bits, &w->points, &w->filled);
        size_t len = ism_tape_length(f);
        if (d.crease)
            w->force = calloc(len ? len : 1, 1);
        ok = w->s.ws && w->jet && memo && (!d.crease || w->force);
    }
    /* a box whose faces f is seen to cross is grown at once (dual_box.h); one that cuts the
     * surface only between the face samples is found by the tree (box_cut), then grown */
    bool cut = ok && (grown || ism_dual_box_seen_cut(&d.w[0].s, o->box, ISM_DUAL_BOX_LOOK));
    enum ism_dual_status status = !ok  ? ISM_DUAL_NO_MEMORY
                                  : cut ? run_in_grown_box(&d, mesh, st)
                                        : run_round_points(&d, mesh, st);
    if (!cut && status == ISM_DUAL_NOT_APPLICABLE && st->declined == ISM_DUAL_WHY_BOX_CUT)
        status = run_in_grown_box(&d, mesh, st);
    st->threads = d.nw;
    for (int k = 0; d.w && k < d.nw; k++) {
        worker *w = &d.w[k];
        st->evals_point += w->s.n_point;
        st->evals_gradient += w->s.n_gradient;
        st->evals_interval += w->s.n_interval;
        ism_eval_ws_free(w->s.ws);
        ism_ivjet_ws_free(w->jet);
        free(w->points);
        free(w->filled);
        free(w->pairs);
        free(w->pairs_filled);
        free(w->force);
    }
    if (status != ISM_DUAL_OK)
        ism_mesh_free(mesh);
    free(d.w);
    ism_pool_free(d.pool);
    forget(&d);
    return status;
}

enum ism_dual_status ism_dual_mesh(const ism_tape *f, const ism_poly_options *o, ism_mesh *mesh,
                                   ism_dual_stats *st)
{
    return dual_mesh(f, o, mesh, st, false);
}

enum ism_dual_status ism_dual_mesh_grown(const ism_tape *f, const ism_poly_options *o,
                                         ism_mesh *mesh, ism_dual_stats *st)
{
    return dual_mesh(f, o, mesh, st, true);
}
