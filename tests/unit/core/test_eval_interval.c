/* test_eval_interval.c — the interval evaluator's promises: every interval encloses f at
 * every point of its box (all example surfaces, thousands of random boxes, hundreds of
 * points each, plus operations at their domain edges), exact bounds where the issue asks
 * (even powers, abs, sin/cos extrema, min/max), the whole line for division by an interval
 * holding 0, clipped sqrt/log, no NaN bound ever, and widths within a stated factor of the
 * sampled range for polynomials on small boxes. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/eval/interval_ops.h"
#include "test_bits.h"
#include "test_eval_surfaces.h"

enum { PTS = 256 };

typedef struct box {
    ism_interval x, y, z;
} box;

/* A random box inside `within`, each side 2^-U(0, 14) of the whole. */
static box random_box(test_rng *rng, const double *within)
{
    ism_interval s[3];
    for (int k = 0; k < 3; k++) {
        double lo = within[k], hi = within[k + 3];
        double w = (hi - lo) * exp2(-test_uniform(rng, 0.0, 14.0));
        double a = test_uniform(rng, lo, hi - w);
        s[k] = (ism_interval){ a, a + w };
    }
    return (box){ s[0], s[1], s[2] };
}

/* Fills PTS points of the box: its 8 corners, then uniform samples. */
static void sample_box(test_rng *rng, const box *b, double *x, double *y, double *z)
{
    for (int i = 0; i < PTS; i++) {
        if (i < 8) {
            x[i] = i & 1 ? b->x.hi : b->x.lo;
            y[i] = i & 2 ? b->y.hi : b->y.lo;
            z[i] = i & 4 ? b->z.hi : b->z.lo;
        } else {
            x[i] = test_uniform(rng, b->x.lo, b->x.hi);
            y[i] = test_uniform(rng, b->y.lo, b->y.hi);
            z[i] = test_uniform(rng, b->z.lo, b->z.hi);
        }
    }
}

static bool sane(ism_interval r)
{
    return !isnan(r.lo) && !isnan(r.hi) && r.lo <= r.hi;
}

/* Checks enclosure over nboxes random boxes; returns the number of points checked. */
static size_t check_enclosure(const char *name, const ism_tape *t, const double *within,
                              size_t nboxes, uint64_t seed)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    test_rng rng = { seed };
    double x[PTS], y[PTS], z[PTS], f[PTS];
    size_t checked = 0;
    for (size_t b = 0; b < nboxes; b++) {
        box bx = random_box(&rng, within);
        ism_interval r = ism_eval_interval(t, ws, bx.x, bx.y, bx.z);
        cr_assert(sane(r), "%s: bad interval [%g, %g]", name, r.lo, r.hi);
        sample_box(&rng, &bx, x, y, z);
        ism_eval_batch(t, ws, x, y, z, f, PTS);
        for (int i = 0; i < PTS; i++) {
            if (isnan(f[i]))
                continue;
            checked++;
            cr_assert(r.lo <= f[i] && f[i] <= r.hi,
                      "%s: f(%.17g, %.17g, %.17g) = %.17g outside [%.17g, %.17g]", name, x[i],
                      y[i], z[i], f[i], r.lo, r.hi);
        }
    }
    ism_eval_ws_free(ws);
    return checked;
}

/* The outward-rounding primitive moves every finite double by at least one ulp: down1(x)
 * <= nextafter(x, -inf) and up1(x) >= nextafter(x, +inf), over all magnitudes. */
Test(eval_interval, outward_rounding_moves_at_least_one_ulp)
{
    test_rng rng = { 5 };
    const double special[] = { 0.0, -0.0, 1.0, -1.0, 2.0, 0.5, 0x1p-1022, -0x1p-1022, 0x1p-1074,
                               -0x1p-1074, 0x1.fffffffffffffp-1023, 0x1.fffffffffffffp0,
                               0x1.0000000000001p0, 0x1p1023, -0x1p1023, 3.0, 1e-300, 1e300 };
    size_t n = test_scaled(200000);
    for (size_t i = 0; i < n + sizeof special / sizeof special[0]; i++) {
        double x;
        if (i < sizeof special / sizeof special[0]) {
            x = special[i];
        } else {
            x = ldexp(test_uniform(&rng, 1.0, 2.0), (int)test_uniform(&rng, -1074, 1023));
            if (test_uniform(&rng, 0, 1) < 0.5)
                x = -x;
        }
        cr_assert(down1(x) <= nextafter(x, -INFINITY), "down1(%a) = %a", x, down1(x));
        cr_assert(up1(x) >= nextafter(x, INFINITY) || x >= 0x1p1023, "up1(%a) = %a", x, up1(x));
        cr_assert(down4(x) <= down1(x) && up4(x) >= up1(x));
    }
    cr_expect_eq(down1(-INFINITY), -INFINITY);
    cr_expect_eq(up1(INFINITY), INFINITY);
}

#define LANES_SAME(name, got, want_lo, want_hi)                                             \
    do {                                                                                    \
        ism_interval g_ = (got);                                                            \
        double wl_ = (want_lo), wh_ = (want_hi);                                            \
        cr_assert(test_same_bits(g_.lo, wl_) && test_same_bits(g_.hi, wh_),               \
                  "%s(a=[%a, %a], b=[%a, %a], c=%a) = [%a, %a], scalar [%a, %a]", name,     \
                  a.lo, a.hi, b.lo, b.hi, c, g_.lo, g_.hi, wl_, wh_);                       \
    } while (0)

/* The SSE2 forms of the common operations (the only ones compiled on x86-64) against
 * down1 / up1 of the scalar expressions, written out here: the same bits for every input,
 * a NaN as a NaN; special values (signed zeros, infinities, NaN, subnormals, DBL_MAX) in
 * every combination of the bounds an operation reads, then random bit patterns. Swapping
 * round1_out's lanes fails it. ism_iv_sane's one-test form against the two NaN tests
 * written out (no NaN left, each the side's infinity). */
Test(eval_interval, sse2_lanes_are_the_scalar_bounds)
{
    const double sp[] = { 0.0, -0.0, INFINITY, -INFINITY, NAN, -NAN, 0x1p-1074, -0x1p-1074,
                          0x1p-1022, -0x1p-1022, 0x1.ffffffffffffep-1023, -0x1.ffffffffffffep-1023,
                          DBL_MAX, -DBL_MAX, 0x1p-970, -0x1p-1000, 1.0, -1.0, 3.0, -0.5 };
    enum { NSP = sizeof sp / sizeof sp[0] };
    test_rng rng = { 27 };
    /* each of a.lo, a.hi, b.lo, b.hi its own digit: every 4-tuple of special values; c, which
     * meets only a, the third digit: every (a.lo, a.hi, c) */
    enum { NSP4 = NSP * NSP * NSP * NSP };
    size_t n = NSP4 + test_scaled(400000);
    for (size_t i = 0; i < n; i++) {
        ism_interval a, b;
        double c;
        if (i < NSP4) {
            a = iv(sp[i % NSP], sp[i / NSP % NSP]);
            b = iv(sp[i / NSP / NSP % NSP], sp[i / NSP / NSP / NSP % NSP]);
            c = sp[i / NSP / NSP % NSP];
        } else {
            a = iv(test_any_bits(&rng), test_any_bits(&rng));
            b = iv(test_any_bits(&rng), test_any_bits(&rng));
            c = test_any_bits(&rng);
        }
        LANES_SAME("iv_add", iv_add(a, b), down1(a.lo + b.lo), up1(a.hi + b.hi));
        LANES_SAME("iv_add_c", iv_add_c(a, c), down1(a.lo + c), up1(a.hi + c));
        LANES_SAME("iv_sub", iv_sub(a, b), down1(a.lo - b.hi), up1(a.hi - b.lo));
        LANES_SAME("iv_c_sub", iv_c_sub(c, a), down1(c - a.hi), up1(c - a.lo));
        ism_interval m = iv_mul_scalar(a, b);
        LANES_SAME("iv_mul", iv_mul(a, b), m.lo, m.hi);
        if (c > 0.0 && c < INFINITY)
            LANES_SAME("iv_mul_cpos", iv_mul_cpos(a, c), down1(a.lo * c), up1(a.hi * c));
        if (c < 0.0 && c > -INFINITY)
            LANES_SAME("iv_mul_cneg", iv_mul_cneg(a, c), down1(a.hi * c), up1(a.lo * c));
        double l2 = a.lo * a.lo, h2 = a.hi * a.hi;
        double lo2 = a.lo >= 0.0 ? l2 : a.hi <= 0.0 ? h2 : 0.0;
        LANES_SAME("iv_square", iv_square(a), ism_max(down1(lo2), 0.0), up1(ism_max(l2, h2)));
        LANES_SAME("ism_iv_sane", ism_iv_sane(a), a.lo == a.lo ? a.lo : -INFINITY,
                   a.hi == a.hi ? a.hi : INFINITY);
    }
}

/* Relative slack of the batch's width over the single box's: the batch rounds each bound
 * correctly outward (the single box one ulp further), so it is never wider but for the
 * last bits of libm results (sin, exp, ...) taken on slightly different arguments. */
#define BATCH_WIDTH_SLACK 1e-9

/* The batched interval evaluator, for chunks of every size (also past its internal chunk
 * and with a partial last group): box by box an interval as tight as the single-box one
 * (within BATCH_WIDTH_SLACK), finite where that one is, and holding every sample of f. */
static void check_batch_matches_single(const char *name, const ism_tape *t, const double *within,
                                       size_t nboxes, uint64_t seed)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    test_rng rng = { seed };
    ism_interval *bx = malloc(nboxes * sizeof *bx), *by = malloc(nboxes * sizeof *by),
                 *bz = malloc(nboxes * sizeof *bz), *out = malloc(nboxes * sizeof *out);
    cr_assert(ws && bx && by && bz && out);
    for (size_t b = 0; b < nboxes; b++) {
        box r = random_box(&rng, within);
        bx[b] = r.x;
        by[b] = r.y;
        bz[b] = r.z;
    }
    size_t done = 0, step = 1;
    while (done < nboxes) {
        size_t n = step < nboxes - done ? step : nboxes - done;
        ism_eval_interval_batch(t, ws, bx + done, by + done, bz + done, out + done, n);
        done += n;
        step = step * 3 + 1; /* 1, 4, 13, 40, 121, ... */
    }
    double x[PTS], y[PTS], z[PTS], f[PTS];
    for (size_t b = 0; b < nboxes; b++) {
        ism_interval r = ism_eval_interval(t, ws, bx[b], by[b], bz[b]);
        cr_assert(sane(out[b]), "%s: batch box %zu [%g, %g]", name, b, out[b].lo, out[b].hi);
        cr_assert(out[b].lo >= r.lo - BATCH_WIDTH_SLACK * (r.hi - r.lo)
                      && out[b].hi <= r.hi + BATCH_WIDTH_SLACK * (r.hi - r.lo),
                  "%s: box %zu single [%.17g, %.17g] batch [%.17g, %.17g]", name, b, r.lo, r.hi,
                  out[b].lo, out[b].hi);
        if (b % 8 != 0)
            continue;
        box one = { bx[b], by[b], bz[b] };
        sample_box(&rng, &one, x, y, z);
        ism_eval_batch(t, ws, x, y, z, f, PTS);
        for (int i = 0; i < PTS; i++)
            cr_assert(isnan(f[i]) || (out[b].lo <= f[i] && f[i] <= out[b].hi),
                      "%s: batch box %zu [%.17g, %.17g] misses f = %.17g", name, b, out[b].lo,
                      out[b].hi, f[i]);
    }
    free(bx);
    free(by);
    free(bz);
    free(out);
    ism_eval_ws_free(ws);
}

Test(eval_interval, batch_within_single_boxes)
{
    size_t nboxes = test_scaled(1500);
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        check_batch_matches_single(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, nboxes, 70 + s);
        ism_tape_free(t);
    }
    static const char *exprs[] = {
        "1 / x + y / (z - 0.5) - 2/(x*y)", "-3*x + 2*y - z/3 + 7/z", "abs(x) - abs(y*z) + min(x, 1) * max(y, -1)",
        "sqrt(x) + log(y) * exp(z) + sin(x) * cos(y) - tan(z)", "x^5 - y^-3 + pow(abs(z), 1.5)",
        "(x - y) / (x + y + 0.1)", "0*x + x*0.0 - y*(-0.5)",
    };
    const double within[6] = { -3, -3, -3, 3, 3, 3 };
    for (size_t i = 0; i < sizeof exprs / sizeof exprs[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[i], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s: %s", exprs[i], err.message);
        check_batch_matches_single(exprs[i], t, within, nboxes, 7 + i);
        ism_tape_free(t);
    }
}

Test(eval_interval, encloses_every_example_surface)
{
    size_t nboxes = test_scaled(2000);
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        size_t n = check_enclosure(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, nboxes,
                                   1000 + s);
        cr_expect_geq(n, nboxes * PTS * 9 / 10, "%s: too few finite samples", TEST_SURFACES[s].name);
        ism_tape_free(t);
    }
}

/* Every operation, including at its domain edges and poles. */
Test(eval_interval, encloses_every_operation)
{
    static const char *exprs[] = {
        "sqrt(x) + sqrt(y - z)", "log(x) * y", "log(x^2 + y^2)", "exp(x) - exp(y)",
        "sin(4*x) * cos(3*y)", "tan(x + y)", "abs(x) - abs(y*z)", "min(x, y, z) * max(x, -y)",
        "1 / x + y / (z - 0.5)", "(x + y) / (x - y)", "x^3 - y^5 + z^7", "x^-3 + y^-2",
        "pow(abs(x), 0.7) - pow(y, 2.5)", "pow(x, -1.5)", "pow(x^2 + 0.1, y)",
        "x*y*z - x/(1 + y^2)", "-x^2 - y^4", "(x - y)^2 - (x + y)^2", "sin(x)^2 + cos(x)^2",
        "exp(-x^2 - y^2) - 0.5", "max(x^2 - 1, -z) / (2 - sin(y))",
    };
    const double within[6] = { -3, -3, -3, 3, 3, 3 };
    const double far[6] = { -1e6, -1e6, -1e6, 1e6, 1e6, 1e6 };
    size_t nboxes = test_scaled(600);
    for (size_t i = 0; i < sizeof exprs / sizeof exprs[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[i], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s: %s", exprs[i], err.message);
        check_enclosure(exprs[i], t, within, nboxes, 77 + i);
        check_enclosure(exprs[i], t, far, nboxes / 4, 99 + i);
        ism_tape_free(t);
    }
}

static ism_interval eval1(const char *src, ism_interval x)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_interval r = ism_eval_interval(t, ws, x, (ism_interval){ 0, 0 }, (ism_interval){ 0, 0 });
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    cr_assert(sane(r), "%s gave [%g, %g]", src, r.lo, r.hi);
    return r;
}

static ism_interval I(double lo, double hi)
{
    return (ism_interval){ lo, hi };
}

/* hi is an upper bound for want within a few ulps (outward rounding). */
static bool near_above(double got, double want)
{
    return got >= want && got <= want + 8 * fabs(want) * 0x1p-52 + 1e-300;
}

static bool near_below(double got, double want)
{
    return got <= want && got >= want - 8 * fabs(want) * 0x1p-52 - 1e-300;
}

Test(eval_interval, even_powers_and_abs_are_exact)
{
    ism_interval r = eval1("x^2", I(-1, 2));
    cr_expect_eq(r.lo, 0.0);
    cr_expect(near_above(r.hi, 4.0), "x^2 over [-1,2] hi %.17g", r.hi);
    r = eval1("x^4", I(-3, 2));
    cr_expect_eq(r.lo, 0.0);
    cr_expect(near_above(r.hi, 81.0));
    r = eval1("x^4", I(-3, -2));
    cr_expect(near_below(r.lo, 16.0) && near_above(r.hi, 81.0), "[%.17g, %.17g]", r.lo, r.hi);
    r = eval1("x^3", I(-2, 1));
    cr_expect(near_below(r.lo, -8.0) && near_above(r.hi, 1.0));
    r = eval1("abs(x)", I(-3, 2));
    cr_expect_eq(r.lo, 0.0);
    cr_expect_eq(r.hi, 3.0);
    r = eval1("x*x", I(-1, 2)); /* the same variable twice is a square */
    cr_expect_eq(r.lo, 0.0);
    r = eval1("-x^2", I(-1, 2));
    cr_expect_eq(r.hi, 0.0);
}

Test(eval_interval, min_max_exact)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("min(x, y) + 0*z", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_interval r = ism_eval_interval(t, ws, I(-1, 3), I(0.5, 2), I(0, 0));
    cr_expect_eq(r.lo, -1.0);
    cr_expect_eq(r.hi, 2.0);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    r = eval1("max(x, 0.25)", I(-1, 0.5));
    cr_expect_eq(r.lo, 0.25);
    cr_expect_eq(r.hi, 0.5);
}

Test(eval_interval, trig_exact_at_extrema)
{
    ism_interval r = eval1("sin(x)", I(0, M_PI));
    cr_expect_eq(r.hi, 1.0);
    cr_expect(r.lo <= 0.0 && r.lo > -1e-15);
    r = eval1("sin(x)", I(4.0, 5.0)); /* holds 3pi/2 */
    cr_expect_eq(r.lo, -1.0);
    cr_expect(near_above(r.hi, sin(4.0)) || r.hi >= sin(4.0));
    r = eval1("sin(x)", I(-0.5, 0.5)); /* no extremum: bounds from the ends */
    cr_expect(r.lo <= sin(-0.5) && r.lo > sin(-0.5) - 1e-15);
    cr_expect(r.hi >= sin(0.5) && r.hi < sin(0.5) + 1e-15);
    r = eval1("sin(x)", I(100 * M_PI + 1.0, 100 * M_PI + 2.0)); /* holds pi/2 + 50 periods */
    cr_expect_eq(r.hi, 1.0);
    cr_expect_gt(r.lo, 0.5);
    r = eval1("cos(x)", I(-0.1, 0.2));
    cr_expect_eq(r.hi, 1.0);
    cr_expect(r.lo <= cos(0.2) && r.lo > cos(0.2) - 1e-15);
    r = eval1("cos(x)", I(3.0, 3.5));
    cr_expect_eq(r.lo, -1.0);
    r = eval1("cos(x)", I(-20, -10)); /* more than a period */
    cr_expect_eq(r.lo, -1.0);
    cr_expect_eq(r.hi, 1.0);
    r = eval1("tan(x)", I(1.0, 2.0)); /* holds the pole at pi/2 */
    cr_expect_eq(r.lo, -INFINITY);
    cr_expect_eq(r.hi, INFINITY);
    r = eval1("tan(x)", I(-1.0, 1.0));
    cr_expect(r.lo <= tan(-1.0) && r.lo > tan(-1.0) - 1e-14);
    cr_expect(r.hi >= tan(1.0) && r.hi < tan(1.0) + 1e-14);
}

Test(eval_interval, division_and_domains)
{
    ism_interval r = eval1("1/x", I(-1, 1));
    cr_expect_eq(r.lo, -INFINITY);
    cr_expect_eq(r.hi, INFINITY);
    r = eval1("1/x", I(0, 1));
    cr_expect_eq(r.lo, -INFINITY);
    r = eval1("1/x", I(2, 4));
    cr_expect(near_below(r.lo, 0.25) && near_above(r.hi, 0.5));
    r = eval1("sqrt(x)", I(-1, 4));
    cr_expect_eq(r.lo, 0.0);
    cr_expect(near_above(r.hi, 2.0));
    r = eval1("sqrt(x)", I(-3, -1));
    cr_expect_eq(r.lo, 0.0);
    cr_expect(r.hi >= 0.0 && r.hi < 1e-300);
    r = eval1("log(x)", I(-1, M_E));
    cr_expect_eq(r.lo, -INFINITY);
    cr_expect(r.hi >= 1.0 && r.hi < 1.0 + 1e-15);
    r = eval1("log(x)", I(-2, -1));
    cr_expect_eq(r.lo, -INFINITY);
    cr_expect(r.hi == -INFINITY);
    r = eval1("pow(x, 0.5)", I(-1, 9));
    cr_expect_eq(r.lo, 0.0);
    cr_expect(r.hi >= 3.0 && r.hi < 3.0 + 1e-14);
}

Test(eval_interval, no_nan_bounds_ever)
{
    static const char *exprs[] = {
        "x*y", "x/y", "exp(x) - exp(y)", "log(x) * 0.5 + log(y)", "x - x", "sqrt(x)*y",
        "log(x)*log(y)", "exp(x)*exp(-y)", "1/x - 1/y", "tan(x)*y", "pow(x, y)", "x^64 - y^63",
        "exp(x)/exp(y)", "sin(x*y)", "min(log(x), y)", "abs(x)*log(y)",
    };
    const ism_interval boxes[][2] = {
        { { -INFINITY, INFINITY }, { -INFINITY, INFINITY } },
        { { 0, 0 }, { -INFINITY, INFINITY } },
        { { 1e300, 1e308 }, { -1e308, -1e300 } },
        { { 1000, 2000 }, { 1000, 2000 } },
        { { -5, 0 }, { 0, 0 } },
        { { 0, 0 }, { 0, 0 } },
        { { INFINITY, INFINITY }, { -INFINITY, -INFINITY } },
        { { NAN, 1 }, { 2, 1 } }, /* bad input boxes count as the whole line */
        { { -1e-320, 1e-320 }, { 5e-324, 1e-310 } },
    };
    for (size_t i = 0; i < sizeof exprs / sizeof exprs[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(exprs[i], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s", exprs[i]);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        for (size_t b = 0; b < sizeof boxes / sizeof boxes[0]; b++) {
            ism_interval r = ism_eval_interval(t, ws, boxes[b][0], boxes[b][1], I(0, 1));
            cr_expect(sane(r), "%s over box %zu: [%g, %g]", exprs[i], b, r.lo, r.hi);
        }
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}

/* iv_mul's SSE2 lanes (interval_ops.h) give iv_mul_scalar's bounds to the bit: every pair of
 * intervals from bounds among signed zeros, the smallest subnormal, ones, huge values and
 * infinities (0 · inf products, ties of ±0 in min/max, overflow), a NaN bound, and random
 * finite intervals of every sign. A lane taken in the wrong order or a min of ±0 taken the
 * other way round shows as a differing bit. */
Test(eval_interval, product_lanes_match_the_scalar_products)
{
    const double v[] = { -INFINITY, -0x1p1023, -3.5, -1.0, -0x1p-1074, -0.0, 0.0, 0x1p-1074,
                         1.0, 2.5, 0x1p1023, INFINITY, NAN };
    const size_t nv = sizeof v / sizeof v[0];
    size_t pairs = 0;
    for (size_t i = 0; i < nv; i++)
        for (size_t j = 0; j < nv; j++)
            for (size_t k = 0; k < nv; k++)
                for (size_t l = 0; l < nv; l++) {
                    ism_interval a = I(v[i], v[j]), b = I(v[k], v[l]);
                    if (!(v[i] <= v[j] && v[k] <= v[l]) && !isnan(v[i] + v[k]))
                        continue; /* not an interval (NaN bounds are kept: sanitised later) */
                    ism_interval p = iv_mul(a, b), q = iv_mul_scalar(a, b);
                    cr_assert(memcmp(&p, &q, sizeof p) == 0,
                              "[%a, %a] * [%a, %a]: [%a, %a] vs [%a, %a]", a.lo, a.hi, b.lo,
                              b.hi, p.lo, p.hi, q.lo, q.hi);
                    pairs++;
                }
    cr_assert(pairs > 2000);
    test_rng rng = { 77 };
    for (size_t n = 0; n < test_scaled(100000); n++) {
        double x[4];
        for (int k = 0; k < 4; k++)
            x[k] = ldexp(test_uniform(&rng, -1, 1), (int)test_uniform(&rng, -60, 60));
        ism_interval a = I(fmin(x[0], x[1]), fmax(x[0], x[1]));
        ism_interval b = I(fmin(x[2], x[3]), fmax(x[2], x[3]));
        ism_interval p = iv_mul(a, b), q = iv_mul_scalar(a, b);
        cr_assert(memcmp(&p, &q, sizeof p) == 0, "[%a, %a] * [%a, %a]", a.lo, a.hi, b.lo, b.hi);
    }
}

/* Width factor. Over a small box of side h the true range of f is about h times its
 * gradient, while naive interval arithmetic bounds each term of the formula separately,
 * so it overestimates by about (sum of the terms' gradients) / |grad f|: a property of how
 * the formula is written, bounded wherever the gradient is not small. Near a critical point
 * the true range shrinks like h^2 and no factor holds, so boxes whose centre gradient is
 * below a tenth of the surface's typical (median) gradient are left out. We state: width
 * <= 20 x the sampled range, on boxes of side 1e-3 of the surface's box (the worst seen
 * is about 15, for the torus, whose two terms nearly cancel). */
#define WIDTH_FACTOR 20.0

static double gradient_norm(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z)
{
    double g[3];
    ism_eval_gradient(t, ws, x, y, z, g);
    return sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
}

static int cmp_double(const void *a, const void *b)
{
    double x = *(const double *)a, y = *(const double *)b;
    return (x > y) - (x < y);
}

static double median_gradient(const ism_tape *t, ism_eval_ws *ws, const double *within,
                              test_rng *rng)
{
    enum { N = 1001 };
    static double g[N];
    for (int i = 0; i < N; i++)
        g[i] = gradient_norm(t, ws, test_uniform(rng, within[0], within[3]),
                             test_uniform(rng, within[1], within[4]),
                             test_uniform(rng, within[2], within[5]));
    qsort(g, N, sizeof g[0], cmp_double);
    return g[N / 2];
}

Test(eval_interval, polynomial_widths_within_factor_of_true_range)
{
    size_t nboxes = test_scaled(1000);
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        const test_surface *sf = &TEST_SURFACES[s];
        if (!sf->polynomial)
            continue;
        ism_tape *t = test_surface_compile(sf);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        test_rng rng = { 4242 + s };
        double gmed = median_gradient(t, ws, sf->box, &rng);
        double x[PTS], y[PTS], z[PTS], f[PTS];
        double worst = 0.0;
        size_t used = 0;
        for (size_t b = 0; b < nboxes; b++) {
            double size = 1e-3 * (sf->box[3] - sf->box[0]);
            box bx;
            ism_interval *sides[3] = { &bx.x, &bx.y, &bx.z };
            for (int k = 0; k < 3; k++) {
                double a = test_uniform(&rng, sf->box[k], sf->box[k + 3] - size);
                *sides[k] = I(a, a + size);
            }
            double cx = 0.5 * (bx.x.lo + bx.x.hi), cy = 0.5 * (bx.y.lo + bx.y.hi),
                   cz = 0.5 * (bx.z.lo + bx.z.hi);
            if (gradient_norm(t, ws, cx, cy, cz) < 0.1 * gmed)
                continue;
            ism_interval r = ism_eval_interval(t, ws, bx.x, bx.y, bx.z);
            sample_box(&rng, &bx, x, y, z);
            ism_eval_batch(t, ws, x, y, z, f, PTS);
            double lo = INFINITY, hi = -INFINITY;
            for (int i = 0; i < PTS; i++) {
                lo = fmin(lo, f[i]);
                hi = fmax(hi, f[i]);
            }
            double ratio = (r.hi - r.lo) / (hi - lo);
            worst = fmax(worst, ratio);
            used++;
            cr_expect_leq(ratio, WIDTH_FACTOR, "%s: width %g vs sampled range %g (x%g)",
                          sf->name, r.hi - r.lo, hi - lo, ratio);
            cr_expect_geq(ratio, 1.0, "%s: interval narrower than the samples", sf->name);
        }
        cr_expect_geq(used, nboxes / 2, "%s: only %zu boxes used", sf->name, used);
        if (getenv("ISM_TEST_VERBOSE"))
            fprintf(stderr, "%s: %zu boxes, worst width / sampled range %.2f\n", sf->name,
                    used, worst);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}
