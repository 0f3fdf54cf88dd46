/* test_ivgrad_lanes.c — the batched interval gradient pass with min, max and abs in lanes
 * (ism_eval_interval_grad_lanes): over every box of a batch, its value and partials are bit
 * for bit ism_eval_interval_grad's with no branch forced, its kink count that pass's return
 * and its kink bytes (ism_ivjet_lane_kinks) that pass's; ism_ivjet_top_pieces reads the same
 * bits from the batch's lanes as from the scalar pass's registers. The boxes lie on a lattice
 * of quarters, so min/max operands tie at bounds (x.hi == y.lo: a free kink, the tests being
 * strict) and abs meets its operand's bound at ±0; some bounds are −0, some NaN or lo > hi
 * (the whole line), and some tapes overflow to NaN inside (sanitized to infinities). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/eval/interval_jet.h"
#include "core/eval/workspace.h"
#include "core/expr/tape.h"
#include "test_eval_surfaces.h"

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

static const char *const KINKED[] = {
    "min(x, y)", "max(x, y) - z", "min(x, 0.25) * y", "max(x, -0.5) + z^2", "abs(x)",
    "abs(x - y) + abs(z)", "-abs(-x) * y", "max(min(x, y), z)", "abs(min(x, y)) - max(y, z)",
    "min(x*y, z^2) * max(x, z)", "max(y, 0.5) * x - abs(z*0.5)", "min(x, y, z) * max(x, -y)",
    "max(x^2 + y^2 + z^2 - 1, -z)", "abs(x*1e300*1e300 - y*1e300*1e300) + min(x, z)",
    "max(x*1e300*1e300, y) - abs(z)", "abs(2*x - 2*y) - min(3, x)",
    "max(4*(2.6*x^2 - y^2)*(2.6*y^2 - z^2)*(2.6*z^2 - x^2) - 4.2*(x^2 + y^2 + z^2 - 1)^2, "
    "x^2 + y^2 + z^2 - 2.25)",
    "max(y*z, x - 1)", "min(abs(x), abs(y))",
};

/* A lattice value of quarters in [-2, 2], its zero's sign chosen by the generator. */
static double quarter(test_rng *rng)
{
    double v = floor(test_uniform(rng, 0.0, 17.0)) * 0.25 - 2.0;
    return v == 0.0 && test_uniform(rng, 0.0, 1.0) < 0.5 ? -0.0 : v;
}

/* A box: each side two lattice values in order (one in six a point), or (rarely) an edge
 * case: a NaN bound, lo > hi, infinite bounds, a tiny width off the lattice. */
static void lattice_box(test_rng *rng, ism_interval b[3])
{
    for (int k = 0; k < 3; k++) {
        double u = quarter(rng), v = test_uniform(rng, 0.0, 1.0) < 1.0 / 6 ? u : quarter(rng);
        b[k] = u <= v ? (ism_interval){ u, v } : (ism_interval){ v, u };
        double e = test_uniform(rng, 0.0, 1.0);
        if (e < 0.01)
            b[k].lo = NAN;
        else if (e < 0.02)
            b[k] = (ism_interval){ 1, -1 };
        else if (e < 0.03)
            b[k] = (ism_interval){ -INFINITY, INFINITY };
        else if (e < 0.05)
            b[k].hi = nextafter(b[k].lo, INFINITY);
    }
}

static bool same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

typedef struct seen {
    size_t boxes, free_kinks, decided, whole, tops; /* what the boxes exercised */
} seen;

/* One batch of n boxes of t: every box against the scalar pass on `plain`. */
static void batch_against_scalar(const char *name, const ism_tape *t, const ism_interval (*b)[3],
                                 size_t n, ism_ivjet_ws *plain, ism_ivjet_ws *lanes, seen *s)
{
    ism_ivgrad G[ISM_IVGRAD_BATCH], g;
    uint32_t nk[ISM_IVGRAD_BATCH];
    size_t len = ism_tape_length(t);
    uint8_t ks[len], kl[len];
    cr_assert(ism_eval_interval_grad_lanes(t, lanes, b, n, G, nk), "%s: refused", name);
    for (size_t k = 0; k < n; k++) {
        memset(kl, 7, len);
        size_t count = ism_eval_interval_grad(t, plain, b[k], NULL, ks, &g);
        cr_assert(same_bits(&g, &G[k], sizeof g),
                  "%s: box %zu of %zu: v [%a, %a] d0 [%a, %a] d1 [%a, %a] vs v [%a, %a] d0 "
                  "[%a, %a] d1 [%a, %a]", name, k, n, g.v.lo, g.v.hi, g.d[0].lo, g.d[0].hi,
                  g.d[1].lo, g.d[1].hi, G[k].v.lo, G[k].v.hi, G[k].d[0].lo, G[k].d[0].hi,
                  G[k].d[1].lo, G[k].d[1].hi);
        cr_assert_eq(nk[k], count, "%s: box %zu: %u kinks, the scalar pass %zu", name, k,
                     nk[k], count);
        cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, b[k], kl), count, "%s: box %zu", name, k);
        cr_assert(same_bits(ks, kl, len), "%s: box %zu: kink bytes differ", name, k);
        ism_ivgrad ps[2], pl[2];
        bool top_s = ism_ivjet_top_pieces(t, plain, b[k], ps);
        bool top_l = ism_ivjet_top_pieces(t, lanes, b[k], pl);
        cr_assert_eq(top_s, top_l, "%s: box %zu: top pieces %d vs %d", name, k, top_s, top_l);
        if (top_s)
            cr_assert(same_bits(ps, pl, sizeof ps), "%s: box %zu: top pieces' bits", name, k);
        s->boxes++;
        s->free_kinks += count;
        s->tops += top_s;
        for (size_t i = 0; i < len; i++) {
            s->decided += ism_op_is_kink(t->code[i].op) && !ks[i];
        }
        for (int c = 0; c < 3; c++)
            s->whole += g.d[c].lo == -INFINITY && g.d[c].hi == INFINITY;
    }
}

Test(ivgrad_lanes, kinks_in_lanes_change_no_bit)
{
    unsigned ops = 0; /* which of the five kink operations the tapes hold */
    seen s = { 0 };
    for (size_t e = 0; e < sizeof KINKED / sizeof KINKED[0]; e++) {
        ism_tape *t = compile(KINKED[e]);
        for (size_t i = 0; i < ism_tape_length(t); i++) {
            int op = t->code[i].op;
            ops |= op == ISM_OP_MIN_RR ? 1u : op == ISM_OP_MIN_RC ? 2u : op == ISM_OP_MAX_RR ? 4u
                   : op == ISM_OP_MAX_RC ? 8u : op == ISM_OP_ABS ? 16u : 0u;
        }
        ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *lanes = ism_ivjet_ws_new(t);
        cr_assert(plain && lanes);
        test_rng rng = { 900 + e };
        size_t nb = test_scaled(120);
        for (size_t i = 0; i < nb; i++) {
            ism_interval b[ISM_IVGRAD_BATCH][3];
            size_t n = 1 + i % ISM_IVGRAD_BATCH;
            for (size_t k = 0; k < n; k++)
                lattice_box(&rng, b[k]);
            if (i % 4 == 3) { /* a scalar pass of another box on the lanes' workspace first */
                ism_ivgrad other;
                ism_eval_interval_grad(t, lanes, b[0], NULL, NULL, &other);
                lattice_box(&rng, b[0]);
            }
            batch_against_scalar(KINKED[e], t, (const ism_interval (*)[3])b, n, plain, lanes,
                                 &s);
        }
        ism_ivgrad G[1];
        const ism_interval one[1][3] = { { { 0, 1 }, { 0, 1 }, { 0, 1 } } };
        cr_assert(!ism_eval_interval_grad_batch(t, lanes, one, 1, G),
                  "%s: the record-keeping batch takes a tape with kinks", KINKED[e]);
        ism_ivjet_ws_free(plain);
        ism_ivjet_ws_free(lanes);
        ism_tape_free(t);
    }
    cr_assert_eq(ops, 31u, "the tapes hold every kink operation (min/max of registers and "
                           "constants, abs): %#x", ops);
    cr_assert(s.free_kinks > s.boxes / 8 && s.decided > s.boxes / 2 && s.whole > 0 &&
                  s.tops > 10,
              "the boxes exercise too little: %zu boxes, %zu free kinks, %zu decided, %zu "
              "whole partials, %zu top pieces", s.boxes, s.free_kinks, s.decided, s.whole,
              s.tops);
}

/* After a batch of a tape with kinks the jets over its boxes are fresh second-order passes
 * (no record: hess_only takes no min, max or abs), and the lanes' kinks and pieces are gone
 * once another batch (of other boxes, or ism_eval_interval_grad_batch of another tape on the
 * same workspace) runs; a call refused before it starts (a tape with sin; no box; more than
 * ISM_IVGRAD_BATCH boxes) leaves the last pass standing. */
Test(ivgrad_lanes, no_record_and_no_stale_lane)
{
    ism_tape *t = compile("max(x^2 + y^2 - 1, z) + abs(x - y)");
    ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *lanes = ism_ivjet_ws_new(t);
    cr_assert(plain && lanes);
    size_t len = ism_tape_length(t);
    const ism_interval b[2][3] = { { { 0, 1 }, { 0.5, 1 }, { -0.5, 0.5 } },
                                   { { -1, 0 }, { -1, -0.5 }, { 1, 2 } } };
    ism_ivgrad G[ISM_IVGRAD_BATCH + 1];
    uint32_t nk[2];
    cr_assert(ism_eval_interval_grad_lanes(t, lanes, b, 2, G, nk));
    cr_assert(nk[0] > 0, "box 0 holds a free kink");
    uint8_t k1[len], k2[len], kinks[len];
    /* the scalar pass's kinks over box 0, to compare the lane's with */
    cr_assert_eq(ism_eval_interval_grad(t, plain, b[0], NULL, k1, &G[2]), nk[0]);
    /* refused before it starts: the pass over b stands (lanes_take, can_run's n checks) */
    ism_tape *s = compile("max(sin(x), y)");
    const ism_interval many[ISM_IVGRAD_BATCH + 1][3] = { { { 0, 1 }, { 0, 1 }, { 0, 1 } } };
    cr_assert(!ism_eval_interval_grad_lanes(s, lanes, b, 1, G, NULL), "sin is not taken");
    cr_assert(!ism_eval_interval_grad_lanes(t, lanes, b, 0, G, NULL), "no box");
    cr_assert(!ism_eval_interval_grad_lanes(t, lanes, many, ISM_IVGRAD_BATCH + 1, G, NULL),
              "too many boxes");
    ism_tape_free(s);
    cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, b[0], kinks), (size_t)nk[0],
                 "the pass stands after refused calls");
    cr_assert(same_bits(k1, kinks, len), "its kinks as the scalar pass's");
    for (int k = 0; k < 2; k++) {
        ism_ivjet J1, J2;
        size_t n1 = ism_eval_interval_jet(t, plain, b[k], NULL, k1, &J1);
        size_t n2 = ism_eval_interval_jet(t, lanes, b[k], NULL, k2, &J2);
        cr_assert(n1 == n2 && same_bits(&J1, &J2, sizeof J1), "box %d: jet after the batch", k);
        cr_assert(same_bits(k1, k2, len), "box %d: the jet's kinks", k);
    }
    const ism_interval c[1][3] = { { { 3, 4 }, { 3, 4 }, { 3, 4 } } };
    uint32_t nkc;
    cr_assert(ism_eval_interval_grad_lanes(t, lanes, c, 1, G, &nkc));
    ism_ivgrad piece[2];
    cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, b[0], kinks), (size_t)-1, "a stale lane's kinks");
    cr_assert(!ism_ivjet_top_pieces(t, lanes, b[0], piece), "a stale lane's pieces");
    ism_tape *u = compile("max(x^2 + y^2 - 1, z) + abs(x - y) + 0");
    cr_assert_eq(ism_ivjet_lane_kinks(u, lanes, c[0], kinks), (size_t)-1, "another tape's lane");
    ism_tape_free(u);
    /* a smooth tape's batch on the same workspace: t's pass over c is gone */
    cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, c[0], kinks), (size_t)nkc, "c's pass stands");
    ism_tape *r = compile("x^2 + y^2 + z^2 - 1");
    cr_assert(ism_tape_length(r) <= len && r->nregs <= t->nregs, "r fits t's workspace");
    cr_assert(ism_eval_interval_grad_batch(r, lanes, c, 1, G));
    cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, c[0], kinks), (size_t)-1,
                 "t's lane after another tape's batch");
    cr_assert(!ism_ivjet_top_pieces(t, lanes, c[0], piece), "t's pieces after it");
    ism_tape_free(r);
    ism_ivjet_ws_free(plain);
    ism_ivjet_ws_free(lanes);
    ism_tape_free(t);
}

/* On a tape without kinks the lanes are the record-keeping batch: the same bits, no kink,
 * and the jets over its boxes take their records (the same bits as fresh ones). A tape with
 * an operation neither takes is refused. */
Test(ivgrad_lanes, smooth_tapes_as_the_batch)
{
    ism_tape *t = compile("(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2)");
    ism_ivjet_ws *a = ism_ivjet_ws_new(t), *b = ism_ivjet_ws_new(t);
    cr_assert(a && b);
    const ism_interval box[3][3] = { { { 0, 1 }, { 0.5, 1 }, { -0.5, 0.5 } },
                                     { { -1, 0 }, { -1, -0.5 }, { 1, 2 } },
                                     { { 0.25, 0.25 }, { 0, 0 }, { -0.0, 0 } } };
    ism_ivgrad G1[3], G2[3];
    uint32_t nk[3] = { 9, 9, 9 };
    cr_assert(ism_eval_interval_grad_batch(t, a, box, 3, G1));
    cr_assert(ism_eval_interval_grad_lanes(t, b, box, 3, G2, nk));
    cr_assert(same_bits(G1, G2, sizeof G1) && nk[0] == 0 && nk[1] == 0 && nk[2] == 0);
    for (int k = 0; k < 3; k++) {
        ism_ivjet J1, J2;
        ism_eval_interval_jet(t, a, box[k], NULL, NULL, &J1);
        ism_eval_interval_jet(t, b, box[k], NULL, NULL, &J2);
        cr_assert(same_bits(&J1, &J2, sizeof J1), "box %d", k);
    }
    ism_tape *s = compile("max(sin(x), y)");
    ism_ivjet_ws *c = ism_ivjet_ws_new(s);
    cr_assert(c && !ism_eval_interval_grad_lanes(s, c, box, 1, G2, nk), "sin is not taken");
    ism_ivjet_ws_free(c);
    ism_tape_free(s);
    ism_ivjet_ws_free(a);
    ism_ivjet_ws_free(b);
    ism_tape_free(t);
}
