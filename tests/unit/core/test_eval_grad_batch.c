/* test_eval_grad_batch.c — the short-batch evaluators against the one-point ones, bit for
 * bit: ism_eval_gradient_batch against ism_eval_gradient (value and three partials),
 * ism_eval_hessian_batch against ism_eval_hessian (value, gradient and Hessian, with the
 * tapes' free_of and without it) and ism_eval_points against ism_eval_point, lane by lane,
 * on every example surface and on expressions using every operation — including where the
 * scalar rules take a branch (min and max ties, the chain rule's 0 where g' is 0, clipped
 * sqrt/log/pow, division by 0, abs at 0) — over batches of many sizes (1, a chunk less one,
 * a chunk, a chunk and a bit), with the lanes' points repeated and interleaved so the sincos
 * memo is hit and missed, and over a lattice of exact values (exact cancellation, ±0, NaN,
 * ±inf in every lane position). The polygoniser relies on this equality for byte-identical
 * meshes with batches on or off. Also the tapes' promise that the batch loops' restrict
 * pointers rest on: no instruction writes a register it reads. */
#include <criterion/criterion.h>
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/eval/tape_partial.h"
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
    /* a product keeps the sign of a zero factor: -0 from any of the 4-lane arithmetic
       ops (constant minus, sub, add, add and mul by a constant, mul, square) shows in f */
    "(2 - x) * (z - x) * (x + y) * (y + 1) * (z * 0.5) * (x * y) * y^2",
    /* a bare leaf compiles to an empty tape (emit.c): f = x, g = (1, 0, 0), the inputs'
       registers as loaded; the threaded loops' `if (!t->len)` guard keeps them off code[0] */
    "x",
    "z",
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

/* The three batch evaluators over lanes x, y, z [0..n) against the one-point ones, lane by
 * lane; the differing lanes counted into *mismatch (the first three logged). */
static void compare_lanes(const char *name, const ism_tape *t, ism_eval_ws *ws,
                          ism_eval_ws *ws1, const double *x, const double *y, const double *z,
                          size_t n, size_t *mismatch)
{
    double f[MAXN], g[MAXN][3], v[MAXN], p[MAXN][3], hf[MAXN], hg[MAXN][3], hh[MAXN][6];
    cr_assert(n <= MAXN);
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
        if (!ok && (*mismatch)++ < 3)
            cr_log_error("%s, lane %zu of %zu at (%.17g, %.17g, %.17g): batch f %.17g "
                         "g (%.17g, %.17g, %.17g) points %.17g; scalar f %.17g g (%.17g, "
                         "%.17g, %.17g) point %.17g", name, i, n, x[i], y[i], z[i], f[i],
                         g[i][0], g[i][1], g[i][2], v[i], f1, g1[0], g1[1], g1[2], v1);
    }
}

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
        double x[MAXN], y[MAXN], z[MAXN];
        fill_points(&rng, x, y, z, n);
        compare_lanes(name, t, ws, ws1, x, y, z, n, &mismatch);
        lanes += n;
    }
    cr_expect_eq(mismatch, 0, "%s: %zu of %zu lanes differ from the scalar evaluators", name,
                 mismatch, lanes);
    ism_eval_ws_free(ws);
    ism_eval_ws_free(ws1);
}

/* Every point of a lattice of exact values, in chunks of 1 to 13 lanes (every n % 4, so
 * both the 4-lane groups and the lone remainder lanes see each point): x, y and z from
 * {-2, -1, -0, +0, 0.5, 1, 2, NaN, inf, -inf}, so EXPRS' differences and sums cancel
 * exactly ((2 - x) at x = 2, z - x at z = x, x^2 + y^2 + z^2 - 1 at (1, 0, 0)) and the
 * sign of a zero result is compared too (EXPRS' product passes it on to f), which random
 * points in a box never reach. */
static void check_lattice(const char *name, const ism_tape *t)
{
    static const double L[] = {-2.0, -1.0, -0.0, 0.0, 0.5, 1.0, 2.0, NAN, INFINITY,
                               -INFINITY};
    enum { NL = sizeof L / sizeof L[0], NPTS = NL * NL * NL };
    ism_eval_ws *ws = ism_eval_ws_new(t), *ws1 = ism_eval_ws_new(t);
    cr_assert(ws && ws1);
    size_t mismatch = 0, done = 0;
    for (size_t n = 1; done < NPTS; n = n % 13 + 1) {
        double x[13], y[13], z[13];
        size_t k = NPTS - done < n ? NPTS - done : n;
        for (size_t i = 0; i < k; i++) {
            size_t q = done + i;
            x[i] = L[q % NL], y[i] = L[q / NL % NL], z[i] = L[q / (NL * NL)];
        }
        compare_lanes(name, t, ws, ws1, x, y, z, k, &mismatch);
        done += k;
    }
    cr_expect_eq(mismatch, 0, "%s: %zu of %d lattice points differ from the scalar "
                 "evaluators", name, mismatch, (int)NPTS);
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
        check_lattice(EXPRS[i], t);
        for (size_t k = 0; k < t->len; k++) /* the Hessians' general rules, not one_var's */
            t->code[k].free_of = 0;
        check_tape(EXPRS[i], t, 177 + i);
        check_lattice(EXPRS[i], t);
        ism_tape_free(t);
    }
}

Test(eval_grad_batch, example_surfaces_bit_for_bit)
{
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        check_tape(TEST_SURFACES[s].name, t, 900 + s);
        check_lattice(TEST_SURFACES[s].name, t);
        ism_tape_free(t);
    }
}

/* Tape t and what the evaluators are handed made from it (its partial tapes, its shortenings
 * over the cells of a 4^3 grid on box) write no register they read (tape.h): the batch
 * loops take o, a and b as restrict pointers (eval_double.c's narrow_op and batch_op).
 * Returns how many cells shortened t. */
static size_t check_no_self_write(const char *name, const ism_tape *t, const double box[6])
{
    enum { CELLS = 4 * 4 * 4 };
    const ism_tape *ts[1 + 3 + CELLS];
    ism_tape *own[3 + CELLS];
    size_t nt = 0, nown = 0;
    ts[nt++] = t;
    for (int axis = 0; axis < 3; axis++) {
        own[nown] = ism_tape_partial(t, axis);
        cr_assert_not_null(own[nown]);
        ts[nt++] = own[nown++];
    }
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    for (int o = 0; o < CELLS; o++) {
        ism_interval iv[3], range;
        for (int k = 0; k < 3; k++) {
            double step = (box[k + 3] - box[k]) / 4;
            int at = o >> 2 * k & 3;
            iv[k] = (ism_interval){box[k] + at * step, box[k] + (at + 1) * step};
        }
        own[nown] = ism_tape_new_like(t);
        cr_assert_not_null(own[nown]);
        if (ism_tape_shorten(t, ws, iv[0], iv[1], iv[2], own[nown], &range))
            ts[nt++] = own[nown];
        nown++;
    }
    for (size_t i = 0; i < nt; i++)
        for (size_t k = 0; k < ts[i]->len; k++) {
            const ism_instr *in = &ts[i]->code[k];
            bool reads_b = ism_op_has_reg_b(in->op);
            cr_expect(in->out != in->a && !(reads_b && in->out == in->b),
                      "%s, tape %zu, instruction %zu: op %d writes r%u from r%u, r%u", name, i,
                      k, in->op, in->out, in->a, in->b);
        }
    for (size_t i = 0; i < nown; i++)
        ism_tape_free(own[i]);
    ism_eval_ws_free(ws);
    return nt - 4;
}

Test(eval_grad_batch, no_instruction_writes_its_operand)
{
    static const double BOX[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    size_t shortened = 0;
    for (size_t i = 0; i < sizeof EXPRS / sizeof EXPRS[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(EXPRS[i], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s: %s", EXPRS[i], err.message);
        shortened += check_no_self_write(EXPRS[i], t, BOX);
        ism_tape_free(t);
    }
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        shortened += check_no_self_write(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box);
        ism_tape_free(t);
    }
    cr_expect_gt(shortened, 0, "no cell shortened a tape: shortened tapes unchecked");
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
