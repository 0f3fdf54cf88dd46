/* test_crease_memo.c — the crease-point memo (crease_memo.h) changes nothing but the work: a
 * strip of triangles across the crease circle of a unit ball cut by the plane z = 0.3 split
 * by ism_crease_split with the memo gives bit for bit the triangles and vertices it gives
 * without one, both the first time (edges that two triangles share hit within the one call)
 * and again with every edge in the memo; hits are counted, so a memo that never answered
 * would fail. Four contexts: the top's two branches (f = max(|p|² − 1, z − 0.3)); f's pieces
 * (a third piece below the top, pieces mode) with folds allowed, the strip's lower row moved
 * inside the ball by differing amounts so that some mixed edges are left whole and others cut
 * (a memo that dropped the whole verdict would fail); the memo filled beside one leaf's
 * shortened tape and read beside another's (polygonise.c's leaves: one memo, each leaf its own
 * local tape); and a node's shortened tape in the octree build, which must neither read nor
 * write it. Independently of the code, every crease point (ISM_FP_CREASE) lies on the circle:
 * |p|² = 1 and z = 0.3 to CIRCLE_TOL. The strip (not the surface) is placed as given, moved
 * by PF_OFF_* and by PF_IRR_* of its step: its edges cross the circle at other points. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/octree/cell.h"
#include "core/octree/crease_memo.h"
#include "core/octree/crease_split.h"
#include "core/octree/triangulate.h"

#define STRIP_N 12          /* quads round the circle: 24 triangles, 25 mixed edges */
#define STRIP_ARC 0.6       /* radians the strip spans */
#define BELOW_Z 0.2         /* the strip's lower row, on the ball's branch (z − 0.3 < |p|² − 1) */
#define ABOVE_Z 0.4         /* its upper row, on the plane's branch */
#define CIRCLE_TOL 1e-12    /* Newton's crease points on both zero sets, to rounding */
/* A split of the strip asks for 4 STRIP_N crease points (each triangle its two mixed edges'),
 * 2 STRIP_N + 1 distinct edges. With them all in the memo, every ask hits but those of two
 * edges that share a direct-mapped slot (45 and 46 of 48 hits in the placements here): at
 * least this many. */
#define SECOND_HITS (3 * STRIP_N)
/* Pieces mode: the lower row's vertex i moved inside the ball by INSET_STEP × (i mod 3) of
 * its radius, so f where a mixed edge's pieces' values cross on it (fold_within) lies at
 * differing distances from 0: under FOLD_ERROR (fold bound 0.75 × it) some edges fold and
 * the others are cut (measured: 32 of the 48 crease points a full cut adds in the own
 * placement; on the sphere, no inset, every edge folds, f being 0 there). */
#define INSET_STEP 0.02
#define FOLD_ERROR 0.005

static const pf_surface cut_ball = {"max(x^2 + y^2 + z^2 - 1, z - 0.3)", NULL, 0, NULL, 0};
/* The same surface near the strip (3 − x > 1.5 there), with a kink below its top: pieces
 * mode (ism_crease_pieces), and a tape that intervals over a box round the strip shorten
 * (min(z − 0.3, 3 − x) decided) while keeping the top max. */
static const pf_surface cut_ball_pieces = {"max(x^2 + y^2 + z^2 - 1, min(z - 0.3, 3 - x))",
                                           NULL, 0, NULL, 0};

/* The strip: row k (0 below, 1 above) of points on the unit sphere at height BELOW_Z or
 * ABOVE_Z, the lower row's moved inward by inset × (i mod 3) of the radius, all moved by off;
 * triangles (a_i, a_i+1, b_i) and (a_i+1, b_i+1, b_i). */
static void strip(const double off[3], double inset, ism_cell_out *out)
{
    memset(out, 0, sizeof *out);
    const double zs[2] = {BELOW_Z, ABOVE_Z};
    for (int k = 0; k < 2; k++)
        for (int i = 0; i <= STRIP_N; i++) {
            double th = STRIP_ARC * i / STRIP_N, r = sqrt(1 - zs[k] * zs[k]);
            double in = k ? 1 : 1 - inset * (i % 3);
            ism_fpoint v = {{in * r * cos(th) + off[0], in * r * sin(th) + off[1],
                             in * zs[k] + off[2]},
                            {0, 0, 1},
                            0};
            uint32_t idx;
            cr_assert(ism_cell_out_vert(out, &v, &idx));
        }
    for (uint32_t i = 0; i < STRIP_N; i++) {
        uint32_t a = i, a1 = i + 1, b = STRIP_N + 1 + i, b1 = b + 1;
        cr_assert(ism_cell_out_tri(out, a, a1, b) && ism_cell_out_tri(out, a1, b1, b));
    }
}

/* How a strip is split: the sampler's tape (f, or a node's shortened one), its crease mode
 * and fold bound, a leaf's local tape over local_box (NULL: none), the memo (NULL: none). */
typedef struct split_ctx {
    const ism_tape *f, *tape, *local;
    double local_box[6];
    bool pieces;
    double fold_below;
    ism_crease_memo *memo;
} split_ctx;

static void split(const split_ctx *c, ism_eval_ws *ws, ism_cell_out *out)
{
    ism_sampler s = {.tape = c->tape ? c->tape : c->f,
                     .ws = ws,
                     .local = c->local,
                     .crease_pieces = c->pieces,
                     .fold_below = c->fold_below,
                     .memo_tape = c->memo ? c->f : NULL,
                     .crease_memo = c->memo};
    memcpy(s.local_box, c->local_box, sizeof s.local_box);
    cr_assert(ism_crease_split(&s, out, 0));
}

static bool same_out(const ism_cell_out *a, const ism_cell_out *b)
{
    if (a->nverts != b->nverts || a->ntris != b->ntris ||
        memcmp(a->tris, b->tris, 3 * a->ntris * sizeof *a->tris))
        return false;
    for (size_t v = 0; v < a->nverts; v++)
        if (memcmp(a->verts[v].p, b->verts[v].p, sizeof a->verts[v].p) ||
            memcmp(a->verts[v].g, b->verts[v].g, sizeof a->verts[v].g) ||
            a->verts[v].flags != b->verts[v].flags)
            return false;
    return true;
}

/* The crease points of out (ISM_FP_CREASE), each asserted on the circle. */
static size_t crease_points(const ism_cell_out *out, int placed)
{
    size_t n = 0;
    for (size_t v = 0; v < out->nverts; v++) {
        const double *p = out->verts[v].p;
        if (!(out->verts[v].flags & ISM_FP_CREASE))
            continue;
        n++;
        cr_expect_leq(fabs(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1), CIRCLE_TOL,
                      "placement %d", placed);
        cr_expect_leq(fabs(p[2] - 0.3), CIRCLE_TOL, "placement %d", placed);
    }
    return n;
}

static void placements(double offs[3][3])
{
    double step = STRIP_ARC / STRIP_N;
    const double o[3][3] = {{0, 0, 0},
                            {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                            {PF_IRR_X * step, PF_IRR_Y * step, PF_IRR_Z * step}};
    memcpy(offs, o, sizeof o);
}

/* The strip split fresh (c without memo), then twice through a new memo: both bit for bit
 * the fresh split, the second with almost every ask answered again (SECOND_HITS). Returns
 * the fresh split's crease points. */
static size_t fresh_first_again(split_ctx c, ism_eval_ws *ws, const double off[3],
                                double inset, int placed)
{
    ism_crease_memo *m = ism_crease_memo_new(NULL, 1, NULL);
    cr_assert_not_null(m);
    ism_cell_out fresh, first, again;
    strip(off, inset, &fresh);
    strip(off, inset, &first);
    strip(off, inset, &again);
    split(&c, ws, &fresh);
    c.memo = m;
    split(&c, ws, &first);
    uint64_t hits_first = m->hits;
    split(&c, ws, &again);
    /* the first pass: each mixed edge but the strip's two ends is shared by two triangles */
    cr_expect_gt(hits_first, 0, "placement %d: no edge answered from the memo", placed);
    /* the second: every ask but a collision's */
    cr_expect_geq(m->hits - hits_first, SECOND_HITS, "placement %d: %llu hits again",
                  placed, (unsigned long long)(m->hits - hits_first));
    cr_expect(same_out(&fresh, &first), "placement %d: memo's first pass differs", placed);
    cr_expect(same_out(&fresh, &again), "placement %d: memo's hits differ", placed);
    size_t n = crease_points(&fresh, placed);
    ism_cell_out_free(&fresh);
    ism_cell_out_free(&first);
    ism_cell_out_free(&again);
    ism_crease_memo_free(m);
    return n;
}

Test(crease_memo, hit_is_the_fresh_crease_point)
{
    ism_tape *t = pf_compile(&cut_ball);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double offs[3][3];
    placements(offs);
    for (int placed = 0; placed < 3; placed++) {
        split_ctx c = {.f = t};
        size_t n = fresh_first_again(c, ws, offs[placed], 0, placed);
        cr_expect_geq(n, 2 * STRIP_N + 1, "placement %d: %zu crease points", placed, n);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* Pieces mode under a fold bound: some mixed edges folded whole, others cut, through a hit
 * as without one. */
Test(crease_memo, hit_keeps_the_pieces_whole_verdicts)
{
    ism_tape *t = pf_compile(&cut_ball_pieces);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(ism_crease_pieces(t));
    double offs[3][3];
    placements(offs);
    for (int placed = 0; placed < 3; placed++) {
        split_ctx c = {.f = t, .pieces = true, .fold_below = ism_crease_fold_below(FOLD_ERROR)};
        size_t n = fresh_first_again(c, ws, offs[placed], INSET_STEP, placed);
        /* a whole edge adds no crease point; each triangle adds its own for each of its
           two mixed edges it cuts (4 STRIP_N when all are cut) */
        cr_expect(n > 0 && n < 4 * STRIP_N,
                  "placement %d: %zu crease points, want some edges whole and some cut",
                  placed, n);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* t shortened over box b (lo xyz, hi xyz): must shorten (the fixture's point). */
static ism_tape *shortened(const ism_tape *t, ism_eval_ws *ws, const double b[6])
{
    ism_tape *s = ism_tape_new_like(t);
    cr_assert_not_null(s);
    cr_assert(ism_tape_shorten(t, ws, (ism_interval){b[0], b[3]}, (ism_interval){b[1], b[4]},
                               (ism_interval){b[2], b[5]}, s, NULL));
    return s;
}

/* The strip's bounding box, cut at y = cut into the part below (half 0) or above (1). */
static void half_box(const double off[3], double cut, int half, double b[6])
{
    double r = sqrt(1 - BELOW_Z * BELOW_Z);
    const double lo[3] = {r * cos(STRIP_ARC) - 0.1, -0.1, BELOW_Z - 0.1};
    const double hi[3] = {1.1, r * sin(STRIP_ARC) + 0.1, ABOVE_Z + 0.1};
    for (int k = 0; k < 3; k++)
        b[k] = lo[k] + off[k], b[3 + k] = hi[k] + off[k];
    b[half ? 1 : 4] = cut;
}

/* One memo, two leaves: filled while the sampler evaluates one leaf's shortened tape inside
 * its box (f beyond it), read while it evaluates the next leaf's (polygonise.c hands each
 * leaf's local tape to the thread's sampler, the memo stays): the second leaf's every edge a
 * hit, and both splits bit for bit the split by f alone. In both modes. */
Test(crease_memo, a_hit_made_beside_one_leaf_serves_the_next)
{
    ism_tape *t = pf_compile(&cut_ball_pieces);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double offs[3][3];
    placements(offs);
    for (int placed = 0; placed < 3; placed++)
        for (int pm = 0; pm < 2; pm++) {
            const double *off = offs[placed];
            /* the leaves meet at the strip's middle column of vertices */
            double cut = sin(STRIP_ARC / 2) * sqrt(1 - BELOW_Z * BELOW_Z) + off[1];
            split_ctx c[2];
            ism_tape *leaf[2];
            for (int h = 0; h < 2; h++) {
                c[h] = (split_ctx){.f = t, .pieces = pm};
                half_box(off, cut, h, c[h].local_box);
                c[h].local = leaf[h] = shortened(t, ws, c[h].local_box);
            }
            ism_cell_out fresh, a, b;
            strip(off, 0, &fresh);
            strip(off, 0, &a);
            strip(off, 0, &b);
            split_ctx plain = {.f = t, .pieces = pm};
            split(&plain, ws, &fresh);
            ism_crease_memo *m = ism_crease_memo_new(NULL, 1, NULL);
            cr_assert_not_null(m);
            c[0].memo = c[1].memo = m;
            split(&c[0], ws, &a);
            uint64_t hits_a = m->hits;
            split(&c[1], ws, &b);
            cr_expect_geq(m->hits - hits_a, SECOND_HITS,
                          "placement %d, pieces %d: %llu hits beside the second leaf", placed,
                          pm, (unsigned long long)(m->hits - hits_a));
            cr_expect(same_out(&fresh, &a), "placement %d, pieces %d: first leaf", placed, pm);
            cr_expect(same_out(&fresh, &b), "placement %d, pieces %d: second leaf", placed, pm);
            crease_points(&fresh, placed);
            ism_cell_out_free(&fresh);
            ism_cell_out_free(&a);
            ism_cell_out_free(&b);
            ism_crease_memo_free(m);
            ism_tape_free(leaf[0]);
            ism_tape_free(leaf[1]);
        }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The octree build evaluates a node's shortened tape as the sampler's tape itself (no f
 * beyond the node's box). That tape gives f only inside the box, and crease_point's Newton
 * may leave it (within_reach: CREASE_REACH_EDGES edges from the edge, or a thin wedge's
 * reach), where the node tape's dropped branches give other values: an entry made there
 * could differ from f's answer the polygonisation would read. So crease_split.c's guard
 * (tape == memo_tape) keeps such a sampler off the memo. Tested with a memo filled through f
 * and then spoilt (every entry's point moved, its verdicts flipped): a split through the
 * node's tape must return what it returns without the memo, count no hit and write nothing. */
Test(crease_memo, a_node_tape_neither_reads_nor_writes_the_memo)
{
    ism_tape *t = pf_compile(&cut_ball_pieces);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double offs[3][3];
    placements(offs);
    for (int placed = 0; placed < 3; placed++) {
        const double *off = offs[placed];
        double box[6];
        half_box(off, 0, 0, box);
        box[4] = 1.1 + off[1]; /* the whole strip */
        ism_tape *node = shortened(t, ws, box);
        ism_crease_memo *m = ism_crease_memo_new(NULL, 1, NULL);
        cr_assert_not_null(m);
        ism_cell_out filled, fresh, guarded;
        strip(off, 0, &filled);
        strip(off, 0, &fresh);
        strip(off, 0, &guarded);
        split(&(split_ctx){.f = t, .memo = m}, ws, &filled);
        size_t spoilt = 0;
        for (size_t i = 0; i < sizeof m->e / sizeof m->e[0]; i++)
            if (m->e[i].k.lo != m->e[i].k.hi) {
                m->e[i].x.p[0] += 0.25;
                m->e[i].whole = !m->e[i].whole;
                m->e[i].found = !m->e[i].found;
                spoilt++;
            }
        cr_assert_geq(spoilt, STRIP_N, "placement %d: %zu entries", placed, spoilt);
        ism_crease_memo *kept = ism_crease_memo_new(NULL, 1, NULL);
        cr_assert_not_null(kept);
        memcpy(kept, m, sizeof *m);
        split(&(split_ctx){.f = t, .tape = node}, ws, &fresh);
        split(&(split_ctx){.f = t, .tape = node, .memo = m}, ws, &guarded);
        cr_expect(same_out(&fresh, &guarded), "placement %d: the node tape read the memo",
                  placed);
        cr_expect(!memcmp(kept, m, sizeof *m), "placement %d: the node tape wrote the memo",
                  placed);
        ism_cell_out_free(&filled);
        ism_cell_out_free(&fresh);
        ism_cell_out_free(&guarded);
        ism_crease_memo_free(m);
        ism_crease_memo_free(kept);
        ism_tape_free(node);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
