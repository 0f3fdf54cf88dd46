/* test_expr_parse.c — the parser and compiler on valid input: a table of expressions, each
 * beside the same formula written in C, compared at sample points through every
 * evaluator that returns a value (point, batch, gradient, Hessian). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>

#include "core/eval/eval.h"

typedef double (*cfun)(double x, double y, double z);

typedef struct valid_case {
    const char *source;
    cfun f;
} valid_case;

/* Parameters every case may use. */
static const ism_param PARAMS[] = { { "a", 1.5 }, { "r", 0.75 }, { "k", 3.0 }, { "n", 3.0 } };
#define A 1.5
#define R 0.75
#define K 3.0

static double c_sphere(double x, double y, double z) { return x*x + y*y + z*z - R*R; }
static double c_prec(double x, double y, double z) { return x + y * z - x / (y + 3.0); }
static double c_neg_sq(double x, double y, double z) { (void)y; (void)z; return -(x*x); }
static double c_neg_pow(double x, double y, double z) { (void)z; return 1.0 / (x*x) + y; }
static double c_numbers(double x, double y, double z) { return 1e-3 * x + .5 * y + 2.5e2 * z + 1E1; }
static double c_parens(double x, double y, double z) { return ((x + y) * (z - x)) / 4.0; }
static double c_unary(double x, double y, double z) { (void)z; return -(-x) - -y; }
static double c_trig(double x, double y, double z) { return sin(x) * cos(y) + tan(z / 3.0); }
static double c_exp_log(double x, double y, double z) { return exp(x / 4.0) + log(y*y + 1.0) - z; }
static double c_sqrt_abs(double x, double y, double z) { return sqrt(x*x + y*y) - fabs(z); }
static double c_minmax(double x, double y, double z) { return fmin(x, y) + fmax(y, fmax(z, x)); }
static double c_min3(double x, double y, double z) { return fmin(fmin(x, y - 0.5), fmin(z, 0.25)); }
static double c_consts(double x, double y, double z) { (void)y; (void)z; return M_PI * x + M_E; }
static double c_pow_int(double x, double y, double z) { (void)z; return x*x*x + 1.0 / (y*y); }
static double c_pow_real(double x, double y, double z) { (void)y; (void)z; return pow(fabs(x), 1.5); }
static double c_pow_var(double x, double y, double z) { (void)z; return exp(y * log(x*x + 1.0)); }
static double c_params(double x, double y, double z) { return A * x - K * y * z + R; }
static double c_power_param(double x, double y, double z) { (void)y; (void)z; return x*x*x; }
static double c_expo_chain(double x, double y, double z) { (void)y; (void)z; return pow(x, 8.0); }
static double c_torus(double x, double y, double z)
{
    double q = x*x + y*y + z*z + 1.0 - 0.09;
    return q*q - 4.0 * (x*x + y*y);
}
static double c_lets(double x, double y, double z)
{
    double p = x - y, q = p * p + z;
    return q * p - 1.0;
}
static double c_high(double x, double y, double z) { return pow(x, 6) + pow(y, 5) - pow(z, 7); }
static double c_sqrt_clip(double x, double y, double z) { (void)y; (void)z; return sqrt(fmax(x, 0.0)); }
static double c_div_chain(double x, double y, double z) { return x / 2.0 / (y*y + 1.0) * z; }
static double c_gyroid(double x, double y, double z)
{
    return sin(K*x) * cos(K*y) + sin(K*y) * cos(K*z) + sin(K*z) * cos(K*x);
}

static const valid_case VALID[] = {
    { "x^2 + y^2 + z^2 - r^2", c_sphere },
    { "x + y*z - x/(y + 3)", c_prec },
    { "-x^2", c_neg_sq },
    { "x^-2 + y", c_neg_pow },
    { "1e-3*x + .5*y + 2.5e2*z + 1E1", c_numbers },
    { "((x + y) * (z - x)) / 4", c_parens },
    { "-(-x) - -y", c_unary },
    { "sin(x)*cos(y) + tan(z/3)", c_trig },
    { "exp(x/4) + log(y^2 + 1) - z", c_exp_log },
    { "sqrt(x^2 + y^2) - abs(z)", c_sqrt_abs },
    { "min(x, y) + max(y, z, x)", c_minmax },
    { "min(x, y - 0.5, z, 0.25)", c_min3 },
    { "pi*x + e", c_consts },
    { "pow(x, 3) + pow(y, -2)", c_pow_int },
    { "pow(abs(x), 1.5)", c_pow_real },
    { "pow(x^2 + 1, y)", c_pow_var },
    { "a*x - k*y*z + r", c_params },
    { "x^n", c_power_param },
    { "x^2^3", c_expo_chain },
    { "(x^2 + y^2 + z^2 + 1 - 0.3^2)^2 - 4*(x^2 + y^2)", c_torus },
    { "let p = x - y\nlet q = p*p + z\nq*p - 1", c_lets },
    { "let p = x - y; let q = p*p + z; q*p - 1", c_lets },
    /* a let's value ends with its line: '(' on the next line starts the final expression,
     * an operator on the next line continues the value */
    { "let p = x - y\n(p*p + z)*p - 1", c_lets },
    { "let p = x\n  - y\nlet q = p*p + z\nq*p - 1", c_lets },
    { "x^6 + y^5 - z^7", c_high },
    { "sqrt(x)", c_sqrt_clip },
    { "x/2/(y*y + 1)*z", c_div_chain },
    { "sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x)", c_gyroid },
    { "  x^2+y^2\n + z^2\t- r^2  ", c_sphere },
};

#define NVALID (sizeof VALID / sizeof VALID[0])
#define NPARAMS (sizeof PARAMS / sizeof PARAMS[0])

/* Sample points away from poles and clipping edges of the table's functions. */
static const double PTS[][3] = {
    { 0.3, -0.2, 0.7 }, { -0.9, 0.4, 0.1 }, { 1.3, 1.1, -1.2 }, { -0.45, -1.7, 0.6 },
    { 0.05, 0.8, -0.35 }, { 2.0, -0.6, 1.9 },
};
#define NPTS (sizeof PTS / sizeof PTS[0])

static bool close_to(double got, double want, double rel)
{
    return fabs(got - want) <= rel * (1.0 + fabs(want));
}

Test(expr_parse, table_values_at_points)
{
    for (size_t i = 0; i < NVALID; i++) {
        ism_error err;
        char msg[256];
        ism_tape *t = ism_tape_compile(VALID[i].source, PARAMS, NPARAMS, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "'%s' failed: %s", VALID[i].source,
                           ism_error_format(&err, msg, sizeof msg));
        ism_eval_ws *ws = ism_eval_ws_new(t);
        cr_assert_not_null(ws);
        double xs[NPTS], ys[NPTS], zs[NPTS], out[NPTS];
        for (size_t k = 0; k < NPTS; k++) {
            double x = PTS[k][0], y = PTS[k][1], z = PTS[k][2];
            xs[k] = x; ys[k] = y; zs[k] = z;
            double want = VALID[i].f(x, y, z);
            double got = ism_eval_point(t, ws, x, y, z);
            cr_expect(close_to(got, want, 1e-12), "'%s' at (%g,%g,%g): got %.17g want %.17g",
                      VALID[i].source, x, y, z, got, want);
            double g[3], h[6];
            cr_expect(close_to(ism_eval_gradient(t, ws, x, y, z, g), want, 1e-12),
                      "'%s' gradient value", VALID[i].source);
            cr_expect(close_to(ism_eval_hessian(t, ws, x, y, z, g, h), want, 1e-12),
                      "'%s' hessian value", VALID[i].source);
        }
        ism_eval_batch(t, ws, xs, ys, zs, out, NPTS);
        for (size_t k = 0; k < NPTS; k++)
            cr_expect(close_to(out[k], VALID[i].f(xs[k], ys[k], zs[k]), 1e-12),
                      "'%s' batch lane %zu", VALID[i].source, k);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}

Test(expr_parse, lets_from_array_and_source_agree)
{
    ism_let lets[] = { { "p", "x - y" }, { "q", "p*p + z" } };
    ism_error err;
    ism_tape *t = ism_tape_compile("q*p - 1", NULL, 0, lets, 2, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    for (size_t k = 0; k < NPTS; k++)
        cr_expect(close_to(ism_eval_point(t, ws, PTS[k][0], PTS[k][1], PTS[k][2]),
                           c_lets(PTS[k][0], PTS[k][1], PTS[k][2]), 1e-12));
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(expr_parse, kummer_surface_with_lets)
{
    ism_param params[] = { { "mu2", 0.6667 }, { "w", 1.0 } };
    ism_let lets[] = { { "lambda", "(3*mu2 - 1)/(3 - mu2)" }, { "p", "w - z - sqrt(2)*x" },
                       { "q", "w - z + sqrt(2)*x" }, { "r", "w + z + sqrt(2)*y" },
                       { "s", "w + z - sqrt(2)*y" } };
    ism_error err;
    ism_tape *t = ism_tape_compile("(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s", params, 2,
                                   lets, 5, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double mu2 = 0.6667, lambda = (3 * mu2 - 1) / (3 - mu2), s2 = sqrt(2.0);
    for (size_t k = 0; k < NPTS; k++) {
        double x = PTS[k][0], y = PTS[k][1], z = PTS[k][2];
        double q = x*x + y*y + z*z - mu2;
        double want = q*q - lambda * (1 - z - s2*x) * (1 - z + s2*x) * (1 + z + s2*y)
                      * (1 + z - s2*y);
        cr_expect(close_to(ism_eval_point(t, ws, x, y, z), want, 1e-12));
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(expr_parse, constants_are_folded_and_subexpressions_shared)
{
    ism_error err;
    /* (x+y)^2 appears three times and the constants fold: one add, one square, one
     * multiply by 3 (plus at most one more for how the sum is shaped). */
    ism_tape *t = ism_tape_compile("(x+y)^2 + (x + y)^2 + (2*3 - 5)*((x+y)^2)", NULL, 0,
                                   NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    cr_expect_leq(ism_tape_length(t), 4, "tape has %zu instructions", ism_tape_length(t));
    ism_tape_free(t);
    t = ism_tape_compile("2*3 + 4^2 - sqrt(16)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    cr_expect_eq(ism_tape_length(t), 1); /* one constant */
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_expect_eq(ism_eval_point(t, ws, 0, 0, 0), 18.0);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(expr_parse, batch_handles_any_count)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("x*y - z^3 + min(x, z)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    size_t counts[] = { 1, 7, 8, 9, 255, 256, 257, 1000 };
    static double xs[1000], ys[1000], zs[1000], out[1000];
    for (size_t i = 0; i < 1000; i++) {
        xs[i] = sin(i * 0.37);
        ys[i] = cos(i * 0.11) * 2;
        zs[i] = 0.001 * i - 0.5;
    }
    for (size_t c = 0; c < sizeof counts / sizeof counts[0]; c++) {
        size_t n = counts[c];
        for (size_t i = 0; i < n; i++)
            out[i] = NAN;
        ism_eval_batch(t, ws, xs, ys, zs, out, n);
        for (size_t i = 0; i < n; i++) {
            double want = xs[i] * ys[i] - zs[i] * zs[i] * zs[i] + fmin(xs[i], zs[i]);
            cr_assert(close_to(out[i], want, 1e-13), "n=%zu lane %zu: %g vs %g", n, i, out[i],
                      want);
        }
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
