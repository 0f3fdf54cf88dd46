/* test_sincos.c — the evaluators' own sine and cosine (core/eval/sincos.h): their error in
 * ulps against long double sinl / cosl (glibc's, ~2^-64 relative) over 10^7 arguments across
 * the whole range the reduction covers (uniform at every magnitude from 2^-30 to
 * ISM_SINCOS_LIMIT, and next to multiples of pi/2, where the reduction cancels); one lane and
 * four lanes bit for bit; libm's bits past the range and for non-finite arguments; and every
 * point evaluator (one point, batch, gradient, batched gradient, Hessian) of a trig surface
 * giving the same f bit for bit; the batched gradient's kept pairs serving only their own
 * arguments, and ism_eval_batch's sharing them on one workspace (one-group chunks only). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/eval/sincos.h"
#include "core/eval/eval.h"
#include "core/eval/workspace.h"
#include "test_eval_surfaces.h"

/* The bound this file asserts, from the measurement it repeats (10^7 arguments, seed below):
 * sine 0.750 ulp, cosine 0.750 ulp (libm's own, measured the same way: 0.515). */
#define SINCOS_MAX_ULP 0.76
/* Own and libm's may differ by one rounding each: at most this far apart, in libm's ulps */
#define SINCOS_FROM_LIBM_ULP 1.0

/* |v - t| in units of the last place of the double nearest t */
static double ulps(double v, long double t)
{
    if (t == 0)
        return v == 0 ? 0 : INFINITY;
    int e;
    frexpl(t, &e);
    return (double)(fabsl((long double)v - t) / ldexpl(1.0L, e - 53));
}

/* The i-th test argument, a quarter each: uniform in ±2^m for a random m in [-30, 17]
 * (ISM_SINCOS_LIMIT = 2^17); uniform in ±ISM_SINCOS_LIMIT; within 2^-20 of k pi/2 for a
 * random k in range; and the double nearest k pi (long double's pi) moved by up to 8 ulps,
 * where sin x is smallest against x (the reduction's hardest case). */
static double argument(test_rng *r, size_t i)
{
    double k = floor(test_uniform(r, -ISM_SINCOS_LIMIT, ISM_SINCOS_LIMIT) / M_PI * 2);
    switch (i % 4) {
    case 0:
        return ldexp(test_uniform(r, -1, 1), (int)floor(test_uniform(r, -30, 18)));
    case 1:
        return test_uniform(r, -ISM_SINCOS_LIMIT, ISM_SINCOS_LIMIT);
    case 2:
        return (double)((long double)k * (M_PIl / 2)) + test_uniform(r, -0x1p-20, 0x1p-20);
    default: {
        double x = (double)(floorl(k / 2) * M_PIl);
        int steps = (int)floor(test_uniform(r, -8, 9));
        for (; steps > 0; steps--)
            x = nextafter(x, INFINITY);
        for (; steps < 0; steps++)
            x = nextafter(x, -INFINITY);
        return x;
    }
    }
}

Test(sincos, within_its_bound_of_long_double_and_a_rounding_of_libm)
{
    test_rng r = {27};
    size_t n = test_scaled(10000000);
    double worst_s = 0, worst_c = 0, xs = 0, xc = 0;
    for (size_t i = 0; i < n; i++) {
        double x = argument(&r, i), s, c, ls, lc;
        ism_sincos(x, &s, &c);
        sincos(x, &ls, &lc);
        long double ts = sinl(x), tc = cosl(x);
        double es = ulps(s, ts), ec = ulps(c, tc);
        if (es > worst_s)
            worst_s = es, xs = x;
        if (ec > worst_c)
            worst_c = ec, xc = x;
        if (ulps(s, ls) > SINCOS_FROM_LIBM_ULP || ulps(c, lc) > SINCOS_FROM_LIBM_ULP)
            cr_assert_fail("x %a: own (%a, %a), libm (%a, %a)", x, s, c, ls, lc);
    }
    cr_assert(worst_s <= SINCOS_MAX_ULP, "sin %.3f ulp at x %a", worst_s, xs);
    cr_assert(worst_c <= SINCOS_MAX_ULP, "cos %.3f ulp at x %a", worst_c, xc);
    /* an evaluation this close to its bound on both: the measurement is not vacuous */
    cr_assert(worst_s > 0.5 && worst_c > 0.5, "sin %.3f, cos %.3f", worst_s, worst_c);
}

/* Closed forms: signed zeros, the exact 1 of cos 0, the quadrants' signs, sin^2 + cos^2. */
Test(sincos, closed_forms_and_signs)
{
    double s, c;
    ism_sincos(0.0, &s, &c);
    cr_assert(s == 0 && !signbit(s) && c == 1.0);
    ism_sincos(-0.0, &s, &c);
    cr_assert(s == 0 && signbit(s) && c == 1.0);
    ism_sincos(0x1p-40, &s, &c);
    cr_assert(s == 0x1p-40 && c == 1.0);
    /* the double next to (k + 1/2) pi/2: the quadrant's signs, each value within the bound of
     * sinl / cosl of that double itself (not of the exact (k + 1/2) pi/2, which the double
     * misses by up to half its ulp: ~1e-15 at k = -8, as much as the values' own error) */
    const int sign_s[4] = {1, 1, -1, -1}, sign_c[4] = {1, -1, -1, 1};
    for (int k = -8; k < 8; k++) {
        double x = (k + 0.5) * (M_PI / 2);
        ism_sincos(x, &s, &c);
        int q = ((k % 4) + 4) % 4;
        cr_assert((s > 0) == (sign_s[q] > 0) && (c > 0) == (sign_c[q] > 0), "k %d", k);
        cr_assert(ulps(s, sinl(x)) <= SINCOS_MAX_ULP && ulps(c, cosl(x)) <= SINCOS_MAX_ULP,
                  "k %d: %.17g %.17g", k, s, c);
    }
    /* sin^2 + cos^2 - 1: each value off by at most SINCOS_MAX_ULP of its own ulp (relative
     * 2^-52 at most), so the two squares by twice that, plus three roundings (two squares and
     * the sum, 2^-53 each) */
    const double unit_bound = 2 * SINCOS_MAX_ULP * 0x1p-52 + 3 * 0x1p-53;
    test_rng r = {3};
    for (int i = 0; i < 100000; i++) {
        double x = test_uniform(&r, -1e4, 1e4);
        ism_sincos(x, &s, &c);
        cr_assert(fabs(s * s + c * c - 1) <= unit_bound, "x %a", x);
    }
}

/* Past ISM_SINCOS_LIMIT and for ±inf and NaN: libm's pair, bit for bit (NaN as NaN). */
Test(sincos, far_and_non_finite_arguments_take_libm)
{
    const double xs[] = {ISM_SINCOS_LIMIT * 1.0000001, -3e7, 1e300, INFINITY, -INFINITY, NAN};
    for (size_t i = 0; i < sizeof xs / sizeof xs[0]; i++) {
        double s, c, ls, lc;
        ism_sincos(xs[i], &s, &c);
        sincos(xs[i], &ls, &lc);
        cr_assert(isnan(ls) ? isnan(s) && isnan(c)
                            : memcmp(&s, &ls, sizeof s) == 0 && memcmp(&c, &lc, sizeof c) == 0,
                  "x %g: (%a, %a) vs libm (%a, %a)", xs[i], s, c, ls, lc);
    }
}

/* Four lanes (any mix of near, far and non-finite arguments) give each lane's one-lane bits. */
Test(sincos, four_lanes_are_each_one_lane)
{
    test_rng r = {11};
    const double odd[] = {0.0, -0.0, 1e300, NAN, INFINITY, 3e6, 1.5707963267948966, -1e-300};
    for (int i = 0; i < 200000; i++) {
        double x[4], s4[4], c4[4];
        for (int j = 0; j < 4; j++)
            x[j] = i % 7 == 0 && j == i % 4 ? odd[(i / 7) % 8] : argument(&r, (size_t)(i + j));
        v4d sv, cv;
        ism_sincos4(v4_ld(x), &sv, &cv);
        v4_st(s4, sv), v4_st(c4, cv);
        for (int j = 0; j < 4; j++) {
            double s, c;
            ism_sincos(x[j], &s, &c);
            cr_assert(memcmp(&s, &s4[j], sizeof s) == 0 && memcmp(&c, &c4[j], sizeof c) == 0,
                      "lane %d, x %a", j, x[j]);
        }
    }
}

/* A trig surface's f by every point evaluator, bit for bit: the gyroid ball, in its box and
 * far out (arguments up to ~2e6 and past ISM_SINCOS_LIMIT, where libm takes over). */
Test(sincos, every_point_evaluator_gives_the_same_f)
{
    const test_surface *gs = test_surface_named("gyroid-ball");
    ism_tape *t = test_surface_compile(gs);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    enum { N = 77 }; /* not a whole number of groups */
    test_rng r = {5};
    for (int round = 0; round < 3; round++) {
        double scale = round == 0 ? 1 : round == 1 ? 1e5 : 1e7;
        double x[N], y[N], z[N], fb[N], fg[N], g[N][3], fp[N], fh[N], h[N][6], p[N][3];
        for (int i = 0; i < N; i++) {
            x[i] = p[i][0] = scale * test_uniform(&r, gs->box[0], gs->box[3]);
            y[i] = p[i][1] = scale * test_uniform(&r, gs->box[1], gs->box[4]);
            z[i] = p[i][2] = scale * test_uniform(&r, gs->box[2], gs->box[5]);
        }
        ism_eval_batch(t, ws, x, y, z, fb, N);
        ism_eval_points(t, ws, x, y, z, fp, N);
        ism_eval_gradient_batch(t, ws, x, y, z, fg, g, N);
        ism_eval_hessian_batch(t, ws, (const double(*)[3])p, fh, (double(*)[3])g, h, N);
        for (int i = 0; i < N; i++) {
            double one = ism_eval_point(t, ws, x[i], y[i], z[i]), gr[3], hs[6];
            double fgs = ism_eval_gradient(t, ws, x[i], y[i], z[i], gr);
            double fhs = ism_eval_hessian(t, ws, x[i], y[i], z[i], gr, hs);
            const double *all[] = {&fb[i], &fp[i], &fg[i], &fh[i], &fgs, &fhs};
            for (size_t k = 0; k < sizeof all / sizeof all[0]; k++)
                cr_assert(memcmp(all[k], &one, sizeof one) == 0,
                          "scale %g point %d evaluator %zu: %.17g vs one point's %.17g", scale,
                          i, k, *all[k], one);
        }
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The batched gradient keeps the last registers' sines and cosines by their arguments' bits
 * (trig_pair.h's group pairs): batches that repeat, or differ from the last in one lane by one
 * ulp, or in their length, each still give every lane ism_eval_gradient's f and gradient bit
 * for bit. A pair served for a near but different argument fails here. */
Test(sincos, kept_group_pairs_serve_only_their_own_arguments)
{
    const test_surface *gs = test_surface_named("gyroid-ball");
    ism_tape *t = test_surface_compile(gs);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    enum { N = ISM_GRAD_BATCH };
    test_rng r = {9};
    double x[N], y[N], z[N];
    for (int i = 0; i < N; i++) {
        x[i] = test_uniform(&r, gs->box[0], gs->box[3]);
        y[i] = test_uniform(&r, gs->box[1], gs->box[4]);
        z[i] = test_uniform(&r, gs->box[2], gs->box[5]);
    }
    for (int round = 0; round < 60; round++) {
        size_t n = round % 3 == 0 ? N : (size_t)(1 + round % N);
        int lane = round % N;
        double *c = round % 3 == 0 ? x : round % 3 == 1 ? y : z;
        if (round % 2)
            c[lane] = nextafter(c[lane], INFINITY); /* one lane one ulp off the last batch */
        double f[N], g[N][3];
        ism_eval_gradient_batch(t, ws, x, y, z, f, g, n);
        for (size_t i = 0; i < n; i++) {
            double gs1[3], f1 = ism_eval_gradient(t, ws, x[i], y[i], z[i], gs1);
            cr_assert(memcmp(&f1, &f[i], sizeof f1) == 0 && memcmp(gs1, g[i], sizeof gs1) == 0,
                      "round %d lane %zu: f %.17g vs %.17g", round, i, f[i], f1);
        }
    }
    /* and they are served: the same batch again takes no new pair (a miss would advance the
     * round robin; the gyroid's three trig registers fit the ISM_TRIG_GROUP_PAIRS kept) */
    double f[N], g[N][3];
    ism_eval_gradient_batch(t, ws, x, y, z, f, g, N);
    unsigned next = ws->trig->next_pair;
    ism_eval_gradient_batch(t, ws, x, y, z, f, g, N);
    cr_assert_eq(ws->trig->next_pair, next, "a repeated batch computed its pairs again");
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* ism_eval_batch and the batched gradient share the workspace's group pairs: batches of both,
 * interleaved on one workspace, of lengths 27, 32, 96 and 256 (one group, and chunks of three
 * and eight), with one lane one ulp off the last batch (lane 0 among them: its bits are the
 * pairs' first test), each give every lane ism_eval_point's f (and ism_eval_gradient's
 * gradient) bit for bit. Then that the pairs are served where they fit, and only there: a
 * chunk of one group repeated takes no new pair (a miss advances the round robin), and a
 * chunk of more than one group takes none at all (revL 1: its groups outnumber the pairs,
 * which the gyroid's eight groups a register evicted before their second step). */
Test(sincos, eval_batch_and_the_batched_gradient_share_the_pairs_exactly)
{
    const test_surface *gs = test_surface_named("gyroid-ball");
    ism_tape *t = test_surface_compile(gs);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    enum { N = ISM_EVAL_BATCH };
    static const size_t lens[] = {27, 32, 96, 256};
    static const int lanes[] = {0, 5, 31, 0, 64, 200, 0, 33};
    test_rng r = {11};
    double x[N], y[N], z[N], f[N], g[N][3];
    for (int i = 0; i < N; i++) {
        x[i] = test_uniform(&r, gs->box[0], gs->box[3]);
        y[i] = test_uniform(&r, gs->box[1], gs->box[4]);
        z[i] = test_uniform(&r, gs->box[2], gs->box[5]);
    }
    for (int round = 0; round < 48; round++) {
        size_t n = lens[round % 4];
        size_t lane = (size_t)lanes[(round / 4) % 8] % n;
        double *c = round % 3 == 0 ? x : round % 3 == 1 ? y : z;
        if (round % 5 != 4) /* one round in five repeats the last batch's arguments */
            c[lane] = nextafter(c[lane], round % 2 ? INFINITY : -INFINITY);
        bool grad = (round / 2) % 2 == 1;
        if (grad) {
            for (size_t i0 = 0; i0 < n; i0 += ISM_GRAD_BATCH) {
                size_t m = n - i0 < ISM_GRAD_BATCH ? n - i0 : ISM_GRAD_BATCH;
                ism_eval_gradient_batch(t, ws, x + i0, y + i0, z + i0, f + i0, g + i0, m);
            }
        } else {
            ism_eval_batch(t, ws, x, y, z, f, n);
        }
        for (size_t i = 0; i < n; i++) {
            double one = ism_eval_point(t, ws, x[i], y[i], z[i]), gr[3];
            cr_assert(memcmp(&one, &f[i], sizeof one) == 0, "round %d (%s, n %zu) lane %zu: "
                      "f %.17g vs one point's %.17g", round, grad ? "gradient" : "batch", n, i,
                      f[i], one);
            if (grad) {
                ism_eval_gradient(t, ws, x[i], y[i], z[i], gr);
                cr_assert(memcmp(gr, g[i], sizeof gr) == 0, "round %d lane %zu: gradient",
                          round, i);
            }
        }
    }
    /* served where they fit: 27 points again take no new pair ... */
    ism_eval_batch(t, ws, x, y, z, f, 27);
    unsigned next = ws->trig->next_pair;
    ism_eval_batch(t, ws, x, y, z, f, 27);
    cr_assert_eq(ws->trig->next_pair, next, "a repeated one-group chunk computed its pairs");
    /* ... and new arguments take one a trig register (the gyroid ball's three) */
    for (int i = 0; i < 27; i++)
        x[i] += 0.25, y[i] += 0.25, z[i] += 0.25;
    ism_eval_batch(t, ws, x, y, z, f, 27);
    cr_assert_eq(ws->trig->next_pair, (next + 3) % ISM_TRIG_GROUP_PAIRS);
    /* longer chunks take none, new arguments or not: no pair is written */
    static ism_trig_group_pair held[ISM_TRIG_GROUP_PAIRS];
    memcpy(held, ws->trig->pairs, sizeof held);
    next = ws->trig->next_pair;
    static const size_t longer[] = {33, 96, 256};
    for (size_t k = 0; k < 3; k++) {
        for (int i = 0; i < N; i++)
            x[i] -= 0.125;
        ism_eval_batch(t, ws, x, y, z, f, longer[k]);
        cr_assert(ws->trig->next_pair == next &&
                  memcmp(held, ws->trig->pairs, sizeof held) == 0,
                  "n %zu: a chunk of more than one group took pairs it cannot keep", longer[k]);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
