/* test_eval_grad_batch.c — the short-batch evaluators against the one-point ones, bit for
 * bit: ism_eval_gradient_batch against ism_eval_gradient (value and three partials),
 * ism_eval_hessian_batch against ism_eval_hessian (value, gradient and Hessian, with the
 * tapes' free_of and without it) and ism_eval_points against ism_eval_point, lane by lane, on every example surface and on
 * expressions using every operation — including where the scalar rules take a branch (min
 * and max ties, the chain rule's 0 where g' is 0, clipped sqrt/log/pow, division by 0, abs at
 * 0) — over batches of many sizes (1, a chunk less one, a chunk, a chunk and a bit), with the
 * lanes' points repeated and interleaved so the sincos memo is hit and missed. The polygoniser
 * relies on this equality for byte-identical meshes with batches on or off. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/expr/tape.h"
#include "test_eval_surfaces.h"

/* Every operation, and places where each takes its other branch. */
static const char *const EXPRS[] = {
    "max(x, y) - min(y, z) + max(x, 0.25) + min(z, -0.5)",
    "abs(x) * abs(y - z) + abs(x - y)",
    "sqrt(x) + log(y) + pow(z, 1.5) + pow(x, -0.5)",
    "x / y + 3 / (z - x) - y / 2 + (2 - x) * 3",
    "tan(x) + exp(y) - cos(z) * sin(x) + sin(y) * sin(y)",
    "x^3 - y^5 + z^-2 + (x*y)^4 - x^2 - -y",
    "pow(x^2 + 1, y) + 1 / (x*x + y*y + z*z)",
    "let p = x - y\nlet q = p*p + z*x\nq*p/(1 + q^2) + max(q, p) * min(p, 0)",
    "sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x)",
    "max(x^2 + y^2 + z^2 - 1, -(x^2 + y^2 - 0.25))",
};

/* Points in [-1.5, 1.5]^3, every seventh on a special value (0, ±1, a tie x = y = z), every
 * eleventh with coordinates drawn from values past the finite range or at its edges (±NaN,
 * ±inf, ±1e300, whose powers overflow, DBL_MAX, a denormal) or ordinary ones, each on its
 * own, and every fifth a repeat of an earlier one. */
static void fill_points(test_rng *rng, double *x, double *y, double *z, size_t n)
{
    static const double SPECIAL[] = {0.0, -0.0, 1.0, -1.0, 0.25, -0.5, 1.5};
    static const double EDGE[] = {NAN, -NAN, INFINITY, -INFINITY, 1e300, -1e300, DBL_MAX,
                                  5e-324, 0.5, -1.25};
    const size_t nedge = sizeof EDGE / sizeof EDGE[0];
    for (size_t i = 0; i < n; i++) {
        if (i % 11 == 6) {
            x[i] = EDGE[(size_t)test_uniform(rng, 0, nedge - 0.01)];
            y[i] = EDGE[(size_t)test_uniform(rng, 0, nedge - 0.01)];
            z[i] = EDGE[(size_t)test_uniform(rng, 0, nedge - 0.01)];
        } else if (i % 7 == 3) {
            double v = SPECIAL[i / 7 % (sizeof SPECIAL / sizeof SPECIAL[0])];
            x[i] = v;
            y[i] = i % 2 ? v : test_uniform(rng, -1.5, 1.5);
            z[i] = i % 3 ? v : 0.0;
        } else if (i % 5 == 4 && i > 10) {
            size_t j = i - 1 - (size_t)test_uniform(rng, 0, 9.99);
            x[i] = x[j], y[i] = y[j], z[i] = z[j];
        } else {
            x[i] = test_uniform(rng, -1.5, 1.5);
            y[i] = test_uniform(rng, -1.5, 1.5);
            z[i] = test_uniform(rng, -1.5, 1.5);
        }
    }
}

/* The same bits, or both NaN: the evaluators' contract (eval.h) leaves a NaN's sign and
 * payload free. x86 passes on the first operand's NaN when both are NaN, and the batch does
 * not always keep the scalar's operand order: points with two NaN inputs of opposite signs
 * give NaNs of opposite signs (torus at (-inf, nan, -nan), Kummer, the gyroids). Every caller
 * tests isfinite or a comparison, which treat every NaN alike. */
static bool same_bits(double a, double b)
{
    return memcmp(&a, &b, sizeof a) == 0 || (isnan(a) && isnan(b));
}

#define MAXN 200

static void check_tape(const char *name, const ism_tape *t, uint64_t seed)
{
    /* chunks of 1-32 points in 4-lane groups: 9-16 the 3- and 4-group arms (12 and 16 with
     * a full last group), 17-28 the wide arm with a full (20, 24, 28) or a padded (17) last
     * group, besides 1, 2, 5, 31, 32 and the remainders 3, 7, 8 of the longer batches */
    static const size_t SIZES[] = {1, 2, 5, 9, 12, 13, 16, 17, 20, 24, 28,
                                   ISM_GRAD_BATCH - 1, ISM_GRAD_BATCH, ISM_GRAD_BATCH + 3,
                                   3 * ISM_GRAD_BATCH + 7, MAXN};
    ism_eval_ws *ws = ism_eval_ws_new(t), *ws1 = ism_eval_ws_new(t);
    cr_assert(ws && ws1);
    test_rng rng = {seed};
    size_t mismatch = 0, lanes = 0;
    for (size_t s = 0; s < sizeof SIZES / sizeof SIZES[0]; s++) {
        size_t n = SIZES[s];
        double x[MAXN], y[MAXN], z[MAXN], f[MAXN], g[MAXN][3], v[MAXN];
        fill_points(&rng, x, y, z, n);
        double p[MAXN][3], hf[MAXN], hg[MAXN][3], hh[MAXN][6];
        ism_eval_gradient_batch(t, ws, x, y, z, f, g, n);
        ism_eval_points(t, ws, x, y, z, v, n);
        for (size_t i = 0; i < n; i++) {
            p[i][0] = x[i], p[i][1] = y[i], p[i][2] = z[i];
        }
        ism_eval_hessian_batch(t, ws, (const double (*)[3])p, hf, hg, hh, n);
        for (size_t i = 0; i < n; i++) {
            double g1[3], g2[3], h2[6];
            double f1 = ism_eval_gradient(t, ws1, x[i], y[i], z[i], g1);
            double v1 = ism_eval_point(t, ws1, x[i], y[i], z[i]);
            double f2 = ism_eval_hessian(t, ws1, x[i], y[i], z[i], g2, h2);
            bool ok = same_bits(f[i], f1) && same_bits(v[i], v1) && same_bits(hf[i], f2);
            for (int k = 0; k < 3; k++)
                ok = ok && same_bits(g[i][k], g1[k]) && same_bits(hg[i][k], g2[k]);
            for (int k = 0; k < 6; k++)
                ok = ok && same_bits(hh[i][k], h2[k]);
            if (!ok && mismatch++ < 3)
                cr_log_error("%s, lane %zu of %zu at (%.17g, %.17g, %.17g): batch f %.17g "
                             "g (%.17g, %.17g, %.17g) points %.17g; scalar f %.17g g (%.17g, "
                             "%.17g, %.17g) point %.17g", name, i, n, x[i], y[i], z[i], f[i],
                             g[i][0], g[i][1], g[i][2], v[i], f1, g1[0], g1[1], g1[2], v1);
            lanes++;
        }
    }
    cr_expect_eq(mismatch, 0, "%s: %zu of %zu lanes differ from the scalar evaluators", name,
                 mismatch, lanes);
    ism_eval_ws_free(ws);
    ism_eval_ws_free(ws1);
}

Test(eval_grad_batch, every_operation_bit_for_bit)
{
    for (size_t i = 0; i < sizeof EXPRS / sizeof EXPRS[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(EXPRS[i], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s: %s", EXPRS[i], err.message);
        check_tape(EXPRS[i], t, 77 + i);
        for (size_t k = 0; k < t->len; k++) /* the Hessians' general rules, not one_var's */
            t->code[k].free_of = 0;
        check_tape(EXPRS[i], t, 177 + i);
        ism_tape_free(t);
    }
}

Test(eval_grad_batch, example_surfaces_bit_for_bit)
{
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        check_tape(TEST_SURFACES[s].name, t, 900 + s);
        ism_tape_free(t);
    }
}

/* The values are f's, not merely the scalar evaluator's: a closed form at a few lanes (a
 * check that would pass if both evaluators shared one mistake only by accident). */
Test(eval_grad_batch, closed_form)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("x^2*y + sin(z) + max(x, y)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double x[3] = {2.0, -1.0, 0.5}, y[3] = {3.0, 4.0, 0.25}, z[3] = {0.5, 0.0, -1.0};
    double f[3], g[3][3];
    ism_eval_gradient_batch(t, ws, x, y, z, f, g, 3);
    for (int i = 0; i < 3; i++) {
        bool xa = x[i] > y[i];
        cr_expect_float_eq(f[i], x[i] * x[i] * y[i] + sin(z[i]) + (xa ? x[i] : y[i]), 1e-15);
        cr_expect_float_eq(g[i][0], 2 * x[i] * y[i] + (xa ? 1 : 0), 1e-15);
        cr_expect_float_eq(g[i][1], x[i] * x[i] + (xa ? 0 : 1), 1e-15);
        cr_expect_float_eq(g[i][2], cos(z[i]), 1e-15);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
