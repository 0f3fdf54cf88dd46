/* test_ivjet_lanes.c — the batched interval jet (ism_eval_interval_jet_lanes) against the
 * one-box pass: over every box of a batch its value, first partials and Hessian are bit for
 * bit ism_eval_interval_jet's with no branch forced, whichever way the batch computes them
 * (its own second-order pass; or, right after a batched gradient pass over the same boxes,
 * the Hessians alone from that pass's records), and the batched gradient pass's kinks and
 * registers stand after it (ism_ivjet_lane_kinks, ism_ivjet_top_pieces). The tapes are the
 * singular search's: the Klein bottle (smooth), Barth's sextic in its ball (a max at the
 * top) and Kummer's quartic with 16 nodes, over cells of the search's lattice (depths 1 to
 * 6, with their centres as point boxes) of each surface's box in the three placements
 * (pf_sweep_box). A lane that read another lane's operand, or a rule that took one operand
 * for another, moves some box's bits here; and the test itself tells the jets of different
 * boxes apart (two lanes' answers swapped fail it). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/eval/interval_jet.h"
#include "core/eval/interval_jet_ws.h"
#include "core/expr/tape.h"
#include "poly_fixture.h"
#include "test_eval_surfaces.h"

static bool same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

/* Barth's sextic in its ball, as bench_error meshes it (phi the golden ratio). */
static ism_tape *barth(void)
{
    const ism_param phi = { "phi", 1.6180339887498949 };
    ism_error err;
    ism_tape *t = ism_tape_compile(
        "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
        "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
        &phi, 1, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    return t;
}

/* A cell of the 2^d lattice over box (a random one; d from 1 to 6), or (odd i) its centre
 * as a point box, as the search takes them (centre_of: 0.5 lo + 0.5 hi). */
static void lattice_cell(const double box[6], test_rng *rng, size_t i, ism_interval x[3])
{
    int d = 1 + (int)floor(test_uniform(rng, 0.0, 6.0));
    double n = ldexp(1.0, d);
    for (int k = 0; k < 3; k++) {
        double at = floor(test_uniform(rng, 0.0, n)), ext = box[k + 3] - box[k];
        double lo = box[k] + ext * (at / n), hi = box[k] + ext * ((at + 1.0) / n);
        double c = 0.5 * lo + 0.5 * hi;
        x[k] = i % 2 ? (ism_interval){ c, c } : (ism_interval){ lo, hi };
    }
}

/* Every fifth batch (i % 5 == 4, n > 1): one box made odd in one side (the one-box pass and
 * the lanes both take it): the whole line, lo > hi (taken as the whole line), a NaN bound,
 * or far out (its powers overflow to [inf, inf]: inf - inf in the Hessian rules, whose NaN
 * the passes clean up). */
static void odd_box(ism_interval (*b)[3], size_t n, size_t i)
{
    if (i % 5 != 4 || n < 2)
        return;
    ism_interval *x = &b[i % n][(i / 5) % 3];
    switch ((i / 5) % 4) {
    case 0: *x = (ism_interval){ -INFINITY, INFINITY }; break;
    case 1: *x = (ism_interval){ x->hi + 0.25, x->lo }; break;
    case 2: x->lo = NAN; break;
    default: *x = (ism_interval){ 1e200, 1e201 }; break; /* its square overflows: inf - inf */
    }
}

/* What the boxes exercised. */
typedef struct seen {
    size_t boxes, differ, records, kinked;
} seen;

/* One batch b[0..n) of t on `lanes` against the one-box jets on `plain`. Tapes with kinks:
 * a batched gradient pass over the boxes first, whose kink bytes and top pieces are read
 * after the jets as before them. Without kinks, a batched gradient pass first over the
 * boxes (records: the jets are taken from its records) or over another box (none). */
static void batch_against_scalar(const char *name, const ism_tape *t,
                                 const ism_interval (*b)[3], size_t n, bool kinked,
                                 bool records, ism_ivjet_ws *plain, ism_ivjet_ws *lanes,
                                 seen *s);

/* No unused record of t's batched gradient pass on ws is of box (the jets used them all). */
static bool no_record_of(const ism_ivjet_ws *ws, const ism_interval box[3])
{
    for (uint32_t m = ws->lane_ok; m; m &= m - 1)
        if (same_bits(ws->lane_box[__builtin_ctz(m)], box, sizeof(ism_interval[3])))
            return false;
    return true;
}

/* The jets of b[0..n) (n <= ISM_IVG_VL) from the records of group 1 of a batched gradient
 * pass over [ISM_IVG_VL other boxes, b[0..n)], bit for bit the one-box jets; their records
 * used after it, as the one-box jet uses its own. */
static void from_group_one(const char *name, const ism_tape *t, const ism_interval (*b)[3],
                           size_t n, ism_ivjet_ws *plain, ism_ivjet_ws *lanes, seen *s)
{
    ism_interval all[ISM_IVG_VL * 2][3];
    for (size_t k = 0; k < ISM_IVG_VL; k++)
        for (int a = 0; a < 3; a++) /* boxes of no lattice: none is one of b's */
            all[k][a] = (ism_interval){ 0.1 + 0.01 * (double)k, 0.2 + 0.01 * (double)a };
    memcpy(all[ISM_IVG_VL], b, n * sizeof all[0]);
    ism_ivgrad G[ISM_IVGRAD_BATCH];
    uint32_t nk[ISM_IVGRAD_BATCH];
    cr_assert(ism_eval_interval_grad_lanes(t, lanes, (const ism_interval (*)[3])all,
                                           ISM_IVG_VL + n, G, nk));
    ism_ivjet J[ISM_IVG_VL], j;
    cr_assert(ism_eval_interval_jet_lanes(t, lanes, b, n, J), "%s: refused", name);
    for (size_t k = 0; k < n; k++) {
        cr_assert(no_record_of(lanes, b[k]), "%s: box %zu's record left unused", name, k);
        ism_eval_interval_jet(t, plain, b[k], NULL, NULL, &j);
        cr_assert(same_bits(&j, &J[k], sizeof j), "%s: group 1, box %zu of %zu: h0 [%a, %a] "
                  "vs [%a, %a]", name, k, n, j.h[0].lo, j.h[0].hi, J[k].h[0].lo, J[k].h[0].hi);
    }
    s->boxes += n;
    s->records += n;
}

static void batch_against_scalar(const char *name, const ism_tape *t,
                                 const ism_interval (*b)[3], size_t n, bool kinked,
                                 bool records, ism_ivjet_ws *plain, ism_ivjet_ws *lanes,
                                 seen *s)
{
    size_t len = ism_tape_length(t);
    ism_ivgrad G[ISM_IVGRAD_BATCH];
    uint32_t nk[ISM_IVGRAD_BATCH];
    uint8_t before[ISM_IVGRAD_BATCH][len], after[len];
    ism_ivgrad top_before[ISM_IVGRAD_BATCH][2], top_after[2];
    bool top[ISM_IVGRAD_BATCH];
    const ism_interval other[1][3] = { { { 0.1, 0.2 }, { 0.1, 0.2 }, { 0.1, 0.2 } } };
    bool own = !kinked && !records;
    cr_assert(ism_eval_interval_grad_lanes(t, lanes, own ? other : b, own ? 1 : n, G, nk),
              "%s: refused", name);
    for (size_t k = 0; kinked && k < n; k++) {
        cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, b[k], before[k]), nk[k]);
        top[k] = ism_ivjet_top_pieces(t, lanes, b[k], top_before[k]);
        s->kinked += nk[k] != 0;
    }
    s->records += records && n <= ISM_IVG_VL ? n : 0; /* else two groups: the own pass */
    ism_ivjet J[ISM_IVGRAD_BATCH], j;
    cr_assert(ism_eval_interval_jet_lanes(t, lanes, b, n, J), "%s: refused", name);
    for (size_t k = 0; k < n; k++) {
        ism_eval_interval_jet(t, plain, b[k], NULL, NULL, &j);
        if (records && n <= ISM_IVG_VL)
            cr_assert(no_record_of(lanes, b[k]), "%s: box %zu's record left unused", name, k);
        cr_assert(same_bits(&j, &J[k], sizeof j),
                  "%s: box %zu of %zu (records %d): v [%a, %a] h0 [%a, %a] h1 [%a, %a] vs v "
                  "[%a, %a] h0 [%a, %a] h1 [%a, %a]", name, k, n, records, j.v.lo, j.v.hi,
                  j.h[0].lo, j.h[0].hi, j.h[1].lo, j.h[1].hi, J[k].v.lo, J[k].v.hi,
                  J[k].h[0].lo, J[k].h[0].hi, J[k].h[1].lo, J[k].h[1].hi);
        s->boxes++;
        /* the answers of two lanes told apart: a swap of them fails the comparison */
        if (k > 0 && !same_bits(&J[k - 1], &J[k], sizeof j))
            s->differ++;
        if (!kinked)
            continue;
        cr_assert_eq(ism_ivjet_lane_kinks(t, lanes, b[k], after), nk[k], "%s: box %zu", name,
                     k);
        cr_assert(same_bits(before[k], after, len), "%s: box %zu: kink bytes", name, k);
        cr_assert_eq(ism_ivjet_top_pieces(t, lanes, b[k], top_after), top[k]);
        if (top[k])
            cr_assert(same_bits(top_before[k], top_after, sizeof top_after), "%s: box %zu",
                      name, k);
    }
}

/* Batches of 1 to ISM_IVGRAD_BATCH cells of t over base in the three placements. */
static void jets_as_one_by_one(const char *name, const ism_tape *t, const double base[6],
                               bool kinked)
{
    ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *lanes = ism_ivjet_ws_new(t);
    cr_assert(plain && lanes);
    seen s = { 0 };
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, 6, w, box);
        test_rng rng = { 4100u + (uint64_t)(w + 1) };
        size_t nb = test_scaled(60);
        for (size_t i = 0; i < nb; i++) {
            ism_interval b[ISM_IVGRAD_BATCH][3];
            size_t n = 1 + i % ISM_IVGRAD_BATCH;
            for (size_t k = 0; k < n; k++)
                lattice_cell(box, &rng, k + i, b[k]);
            odd_box(b, n, i);
            /* with kinks the batched gradient pass keeps no records: the jets' own pass */
            batch_against_scalar(name, t, (const ism_interval (*)[3])b, n, kinked,
                                 !kinked && i % 2 == 0, plain, lanes, &s);
            if (!kinked && i % 3 == 0)
                from_group_one(name, t, (const ism_interval (*)[3])b, 1 + i % ISM_IVG_VL,
                               plain, lanes, &s);
        }
    }
    cr_assert(s.differ > s.boxes / 2, "%s: %zu of %zu neighbouring jets differ", name,
              s.differ, s.boxes);
    if (kinked)
        cr_assert(s.kinked > 0, "%s: no box met the kink", name);
    else
        /* only batches within one group count (246 of 936 on Klein and Kummer) */
        cr_assert(s.records > s.boxes / 5, "%s: %zu of %zu jets from records", name,
                  s.records, s.boxes);
    ism_ivjet_ws_free(plain);
    ism_ivjet_ws_free(lanes);
}

static void gallery(const char *name)
{
    const test_surface *g = test_surface_named(name);
    ism_tape *t = test_surface_compile(g);
    jets_as_one_by_one(name, t, g->box, false);
    ism_tape_free(t);
}

Test(ivjet_lanes, klein_bottle) { gallery("klein-bottle"); }

Test(ivjet_lanes, kummer_16_nodes) { gallery("kummer-16-nodes"); }

Test(ivjet_lanes, barth_sextic)
{
    ism_tape *t = barth();
    const double box[6] = { -1.6, -1.6, -1.6, 1.6, 1.6, 1.6 };
    jets_as_one_by_one("barth-sextic", t, box, true);
    ism_tape_free(t);
}

/* Refused before anything is computed (then the boxes are taken one by one): a tape with an
 * operation the lanes do not take, no box, too many boxes. */
Test(ivjet_lanes, refuses)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("sin(x) + y*z", NULL, 0, NULL, 0, NULL, &err);
    ism_tape *u = ism_tape_compile("x*y - z", NULL, 0, NULL, 0, NULL, &err);
    cr_assert(t && u);
    ism_ivjet_ws *ws = ism_ivjet_ws_new(t);
    ism_interval b[ISM_IVGRAD_BATCH + 1][3];
    for (int k = 0; k < ISM_IVGRAD_BATCH + 1; k++)
        for (int a = 0; a < 3; a++)
            b[k][a] = (ism_interval){ -1.0 + 0.1 * k, 0.5 };
    ism_ivjet J[ISM_IVGRAD_BATCH + 1];
    const ism_interval (*bb)[3] = (const ism_interval (*)[3])b;
    cr_assert(!ism_eval_interval_jet_lanes(t, ws, bb, 2, J));
    cr_assert(!ism_eval_interval_jet_lanes(u, ws, bb, 0, J));
    cr_assert(!ism_eval_interval_jet_lanes(u, ws, bb, ISM_IVGRAD_BATCH + 1, J));
    cr_assert(ism_eval_interval_jet_lanes(u, ws, bb, ISM_IVGRAD_BATCH, J));
    ism_ivjet_ws_free(ws);
    ism_tape_free(t);
    ism_tape_free(u);
}

/* A tape whose square writes its own operand's register (r3 = x x; r3 = r3^2; r4 = r3 z),
 * filled by hand since the compiler never emits one: the lanes' own pass is bit for bit the
 * one-box pass here too. That pass reads the square's operand before writing its output;
 * the lanes read it after step's write once, so h_xx took g' = 2 x^4 for 2 x^2 (x x has
 * h_xx = 2, which g' multiplies; an operand with no Hessian, as x + y, would hide it). */
Test(ivjet_lanes, square_writing_its_operand)
{
    ism_tape *t = ism_tape_alloc(3, 5);
    cr_assert_not_null(t);
    t->code[0] = (ism_instr){ .op = ISM_OP_MUL_RR, .out = 3, .a = ISM_REG_X, .b = ISM_REG_X };
    t->code[1] = (ism_instr){ .op = ISM_OP_SQUARE, .out = 3, .a = 3 };
    t->code[2] = (ism_instr){ .op = ISM_OP_MUL_RR, .out = 4, .a = 3, .b = ISM_REG_Z };
    t->len = 3;
    t->result = 4;
    cr_assert(ism_tape_mark_free(t));
    ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *lanes = ism_ivjet_ws_new(t);
    cr_assert(plain && lanes);
    const double base[6] = { 0.5, 0.5, -1.0, 1.0, 1.0, 2.0 };
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, 6, w, box);
        ism_interval b[5][3];
        for (size_t k = 0; k < 5; k++) /* two groups; box k's sides [lo, hi - k/8 of them] */
            for (int a = 0; a < 3; a++) {
                double ext = box[a + 3] - box[a];
                b[k][a] = (ism_interval){ box[a], box[a + 3] - ext * (double)k / 8.0 };
            }
        ism_ivjet J[5], j;
        cr_assert(ism_eval_interval_jet_lanes(t, lanes, (const ism_interval (*)[3])b, 5, J));
        for (size_t k = 0; k < 5; k++) {
            ism_eval_interval_jet(t, plain, b[k], NULL, NULL, &j);
            cr_assert(j.h[0].lo != 0.0 || j.h[0].hi != 0.0, "box %zu: h_xx is 0", k);
            cr_assert(same_bits(&j, &J[k], sizeof j),
                      "w %d box %zu: h0 [%a, %a] vs [%a, %a]", w, k, j.h[0].lo, j.h[0].hi,
                      J[k].h[0].lo, J[k].h[0].hi);
        }
    }
    ism_ivjet_ws_free(plain);
    ism_ivjet_ws_free(lanes);
    ism_tape_free(t);
}
