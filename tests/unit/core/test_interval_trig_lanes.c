/* test_interval_trig_lanes.c — the batched interval pass's sines and cosines (four lanes at a
 * time with the bounds' libm pairs from the workspace's memo, eval_interval_batch.c's
 * run_trig) against the single-box pass and against interval_ops.h's iv_sin / iv_cos, which
 * call libm's sin and cos directly: bit for bit, on tapes whose only inexact operations are
 * sines and cosines (min, max and negation are exact in both passes), over the boxes of a
 * lattice in the three placements (poly_fixture.h's pf_sweep_box) and over boxes that start,
 * end or straddle a multiple of pi/2 (where a bound becomes 1 or -1, or a lane whose bound
 * were rounded the other way would differ). Also interval_lanes.h's v_sin_at / v_cos_at in
 * both compiled copies (avx2_clone.h) against iv_sin_at / iv_cos_at, so the baseline copy is
 * checked on an AVX2 machine too. The single-box pass keeps whole intervals' sines and cosines
 * (trig_pair.h's interval entries): the lattice's cells repeat an axis's interval every
 * CELLS boxes, and boxes at k pi/2 share a bound, so its hits and misses are both checked.
 * And the interval jet's sine and cosine (eval_interval_jet.c's iv_sin_cos, one sincos per
 * bound) against iv_sin / iv_cos: its value and its x partial. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/eval/avx2_clone.h"
#include "core/eval/interval_jet.h"
#include "core/eval/interval_lanes.h"
#include "core/expr/tape.h"
#include "poly_fixture.h"
#include "test_bits.h"

/* Boxes an axis: the lattice's 2^DEPTH cells over the placed box. */
#define DEPTH 4
#define CELLS (1 << DEPTH)
/* Multiples k pi/2, |k| <= HALF_TURNS, each met by boxes that start, end and straddle it. */
#define HALF_TURNS 12
/* Boxes at the edge of may_contain's tolerance (far_boxes): FAR_N multiples of 2 pi, four
 * phases, two sides, and the edge box with its neighbour one ulp outside. */
#define FAR_N 8
#define FAR_BOXES (FAR_N * 4 * 2 * 2)
#define MAX_BOXES (CELLS * 3 + (2 * HALF_TURNS + 1) * 6 + 8 + FAR_BOXES)

typedef struct boxes {
    ism_interval v[3][MAX_BOXES];
    size_t n;
} boxes;

static void add(boxes *b, ism_interval x, ism_interval y, ism_interval z)
{
    cr_assert(b->n < MAX_BOXES);
    b->v[0][b->n] = x, b->v[1][b->n] = y, b->v[2][b->n] = z;
    b->n++;
}

/* may_contain with the tolerance's relative term taken from m instead of the larger bound:
 * the fixture's check of which term decides an edge box. */
static int contains_with(ism_interval a, double phase, double m)
{
    double tol = ISM_TRIG_TOL_ABS + ISM_TRIG_TOL_REL * m;
    return holds_integer((a.lo - phase) / (2.0 * M_PI) - tol, (a.hi - phase) / (2.0 * M_PI) + tol);
}

/* Boxes of width w beside the point phase + 2 pi n, at the edge of interval_ops.h's scalar
 * may_contain (found by walking ulp by ulp away from the point): side 1 a box ending below it,
 * the lowest hi that may_contain still counts as holding it; side 0 a box starting above it,
 * the highest lo. Each with its neighbour one ulp further out, which may_contain does not
 * count. The scalar form decides both, so a lane form with a smaller tolerance or one taken
 * from another bound differs on the edge box. For large n (|x| to 9.4e8, under ISM_TRIG_LIMIT)
 * the relative term 4e-16 |x| decides, not the 1e-12; for |n| = 2 and w = 6 the two bounds'
 * sizes differ by 6, so the relative term taken from the smaller bound misses the edge. Both
 * checked here (cr_assert), so the boxes keep testing what they are for. */
static void far_boxes(boxes *b)
{
    static const double ns[FAR_N] = {1 << 18, -(1 << 18), 2.5e6, -2.5e6, 1.5e8, -1.5e8, 2, -2};
    static const double phases[4] = {M_PI / 2, -M_PI / 2, 0.0, M_PI}; /* sin's, then cos's */
    for (int i = 0; i < FAR_N; i++)
        for (int p = 0; p < 4; p++)
            for (int side = 0; side < 2; side++) {
                double w = fabs(ns[i]) == 2 ? 6.0 : 0.01, ph = phases[p];
                double x = ph + 2.0 * M_PI * ns[i], out = side ? -INFINITY : INFINITY;
                ism_interval e = side ? (ism_interval){x - w, x} : (ism_interval){x, x + w}, o;
                for (int steps = 0;; steps++, e = o) {
                    double y = nextafter(side ? e.hi : e.lo, out);
                    o = side ? (ism_interval){y - w, y} : (ism_interval){y, y + w};
                    if (!may_contain(o.lo, o.hi, ph, 2 * M_PI))
                        break;
                    cr_assert(steps < 1 << 16);
                }
                cr_assert(may_contain(e.lo, e.hi, ph, 2 * M_PI));
                double m = w == 6.0 ? fmin(fabs(e.lo), fabs(e.hi)) : 0.0;
                cr_assert(!contains_with(e, ph, m), "n %g phase %d side %d", ns[i], p, side);
                add(b, e, e, e);
                add(b, o, o, o);
            }
}

/* The lattice's cells of the placed box (each axis its own cells, the other two a cell's
 * neighbours), then the boxes at k pi/2 on every axis (as a double: the rounded multiple),
 * then boxes a period or more wide and one whole line (they do not resolve: [-1, 1]). */
static void make_boxes(int which, boxes *b)
{
    const double base[6] = {-7.5, -7.5, -7.5, 7.5, 7.5, 7.5};
    double box[6];
    pf_sweep_box(base, DEPTH, which, box);
    b->n = 0;
    for (int i = 0; i < CELLS * 3; i++) {
        ism_interval s[3];
        for (int k = 0; k < 3; k++) {
            int c = (i + 5 * k) % CELLS;
            double h = (box[k + 3] - box[k]) / CELLS;
            s[k] = (ism_interval){box[k] + c * h, box[k] + (c + 1) * h};
        }
        add(b, s[0], s[1], s[2]);
    }
    for (int k = -HALF_TURNS; k <= HALF_TURNS; k++) {
        double m = k * (M_PI / 2), d = 0.01 + 0.003 * (k + HALF_TURNS);
        ism_interval at[3] = {{m, m + d}, {m - d, m}, {m - d, m + d}};
        for (int j = 0; j < 3; j++) {
            add(b, at[j], at[(j + 1) % 3], at[(j + 2) % 3]);
            add(b, (ism_interval){m, m}, at[j], (ism_interval){nextafter(m, -INFINITY), m});
        }
    }
    add(b, (ism_interval){0, 2 * M_PI}, (ism_interval){-1, 1}, (ism_interval){1, 9});
    add(b, (ism_interval){-INFINITY, INFINITY}, (ism_interval){2e9, 2e9 + 1},
        (ism_interval){-3, 3.5});
    far_boxes(b);
}

static void same_interval(const char *what, size_t i, ism_interval got, ism_interval want)
{
    cr_assert(test_same_bits(got.lo, want.lo) && test_same_bits(got.hi, want.hi),
              "%s box %zu: batch [%a, %a], want [%a, %a]", what, i, got.lo, got.hi, want.lo,
              want.hi);
}

/* iv_sin / iv_cos of the tapes below at box i, from libm directly */
static ism_interval libm_value(int e, const boxes *b, size_t i)
{
    switch (e) {
    case 0: return iv_sin(b->v[0][i]);
    case 1: return iv_cos(b->v[1][i]);
    default: return iv_max(iv_sin(b->v[2][i]), iv_neg(iv_cos(b->v[0][i])));
    }
}

Test(interval_trig_lanes, batch_is_single_box_and_libm)
{
    static const char *exprs[] = {"sin(x)", "cos(y)", "max(sin(z), -cos(x))"};
    boxes *b = malloc(sizeof *b);
    ism_interval *out = malloc(MAX_BOXES * sizeof *out);
    cr_assert(b && out);
    for (int e = 0; e < 3; e++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[e], NULL, 0, NULL, 0, NULL, &err);
        cr_assert(t, "%s", exprs[e]);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        for (int which = -1; which <= 1; which++) {
            make_boxes(which, b);
            /* batches of 1, 8, 3, 8, 1, ...: partial groups and the padding lanes too */
            static const size_t sizes[] = {1, 8, 3, 8, 5, 64, 2};
            for (size_t done = 0, k = 0; done < b->n; k++) {
                size_t n = sizes[k % 7] < b->n - done ? sizes[k % 7] : b->n - done;
                ism_eval_interval_batch(t, ws, b->v[0] + done, b->v[1] + done, b->v[2] + done,
                                        out + done, n);
                done += n;
            }
            for (size_t i = 0; i < b->n; i++) {
                ism_interval one = ism_eval_interval(t, ws, b->v[0][i], b->v[1][i], b->v[2][i]);
                same_interval(exprs[e], i, out[i], one);
                same_interval(exprs[e], i, out[i], libm_value(e, b, i));
            }
        }
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
    free(out);
    free(b);
}

/* The phases where sin (cosine 0) or cos (1) is 1 (minus 0) and -1 (minus 1), as written in
 * iv_sin_at / iv_cos_at */
static double phase_of(int cosine, int minus)
{
    return cosine ? (minus ? M_PI : 0.0) : (minus ? -M_PI / 2 : M_PI / 2);
}

/* v_sin_at / v_cos_at, v_trig_resolves and v_may_contain at the two phases (ok[4 + j],
 * ok[8 + j]) over four boxes' x, given libm's sines and cosines of their bounds; compiled
 * twice (avx2_clone.h). The masks alone too: at |x| near 10 a tolerance decides whether the
 * box holds a point within 1e-11 of the peak, where sin rounds to 1 either way. */
ISM_AVX2_TWICE(void, trig_lanes,
               (const double *lo, const double *hi, const double *w1, const double *w2,
                int cosine, double *olo, double *ohi, long long *ok),
               (lo, hi, w1, w2, cosine, olo, ohi, ok),
    vi a = {v4_ld(lo), v4_ld(hi)};
    vi r = cosine ? v_cos_at(a, v4_ld(w1), v4_ld(w2)) : v_sin_at(a, v4_ld(w1), v4_ld(w2));
    v4i m = v_trig_resolves(a);
    v4i up = v_may_contain(a, phase_of(cosine, 0), 2.0 * M_PI);
    v4i down = v_may_contain(a, phase_of(cosine, 1), 2.0 * M_PI);
    v4_st(olo, r.lo);
    v4_st(ohi, r.hi);
    for (int j = 0; j < 4; j++)
        ok[j] = m[j], ok[4 + j] = up[j], ok[8 + j] = down[j];)

static void check_lanes(void (*run)(const double *, const double *, const double *,
                                    const double *, int, double *, double *, long long *),
                        const boxes *b)
{
    for (size_t i = 0; i + 4 <= b->n; i++) /* every window of four: each box in each lane */
        for (int cosine = 0; cosine < 2; cosine++) {
            double lo[4], hi[4], w1[4], w2[4], olo[4], ohi[4];
            long long ok[12];
            for (int j = 0; j < 4; j++) {
                ism_interval a = b->v[0][i + j];
                lo[j] = a.lo, hi[j] = a.hi;
                w1[j] = cosine ? cos(a.lo) : sin(a.lo);
                w2[j] = cosine ? cos(a.hi) : sin(a.hi);
            }
            run(lo, hi, w1, w2, cosine, olo, ohi, ok);
            for (int j = 0; j < 4; j++) {
                ism_interval a = b->v[0][i + j];
                cr_assert_eq(ok[j] != 0, iv_trig_resolves(a), "box %zu", i + j);
                if (!ok[j])
                    continue;
                for (int minus = 0; minus < 2; minus++)
                    cr_assert_eq(ok[4 + 4 * minus + j] != 0,
                                 may_contain(a.lo, a.hi, phase_of(cosine, minus), 2.0 * M_PI),
                                 "box %zu [%a, %a] cosine %d minus %d", i + j, a.lo, a.hi, cosine,
                                 minus);
                ism_interval want = cosine ? iv_cos(a) : iv_sin(a);
                same_interval(cosine ? "v_cos_at" : "v_sin_at", i + j,
                              (ism_interval){olo[j], ohi[j]}, want);
            }
        }
}

Test(interval_trig_lanes, lanes_are_iv_sin_at_in_both_copies)
{
    boxes *b = malloc(sizeof *b);
    cr_assert(b);
    for (int which = -1; which <= 1; which++) {
        make_boxes(which, b);
        check_lanes(trig_lanes, b);
#if ISM_HAVE_AVX2_CLONE
        check_lanes(trig_lanes_base, b);
#endif
    }
    free(b);
}

/* ism_eval_interval_jet of sin(x) and cos(x) over the boxes: the value iv_sin / iv_cos of the
 * box's x bit for bit and the x partial cos / -sin times x's partial [1, 1] (iv_mul, as the
 * chain rule takes it). */
Test(interval_trig_lanes, jet_is_iv_sin_and_iv_cos)
{
    static const char *exprs[] = {"sin(x)", "cos(x)"};
    boxes *b = malloc(sizeof *b);
    cr_assert(b);
    for (int e = 0; e < 2; e++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[e], NULL, 0, NULL, 0, NULL, &err);
        cr_assert(t, "%s", exprs[e]);
        ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
        cr_assert(jw);
        for (int which = -1; which <= 1; which++) {
            make_boxes(which, b);
            for (size_t i = 0; i < b->n; i++) {
                ism_interval box[3] = {b->v[0][i], b->v[1][i], b->v[2][i]}, x = box[0];
                ism_ivjet out;
                ism_eval_interval_jet(t, jw, box, NULL, NULL, &out);
                ism_interval v = e ? iv_cos(x) : iv_sin(x), d = e ? iv_neg(iv_sin(x)) : iv_cos(x);
                same_interval(e ? "jet cos" : "jet sin", i, out.v, v);
                same_interval(e ? "jet cos'" : "jet sin'", i, out.d[0], iv_mul(d, iv(1.0, 1.0)));
            }
        }
        ism_ivjet_ws_free(jw);
        ism_tape_free(t);
    }
    free(b);
}
