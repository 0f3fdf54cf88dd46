/* test_eval_deriv.c — gradient and Hessian against central differences: the gradient
 * against differences of f, the Hessian against differences of the gradient (a separate
 * evaluator) and its diagonal against second differences of f, at random points of every
 * smooth example surface and of expressions using every operation. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/eval/workspace.h"
#include "test_eval_surfaces.h"

typedef struct deriv_case {
    const char *expr;
    double box[6];
} deriv_case;

/* Smooth expressions over boxes where they are smooth (no clipping edge, pole or kink). */
static const deriv_case CASES[] = {
    { "sin(3*x)*cos(2*y) + sin(y*z)", { -2, -2, -2, 2, 2, 2 } },
    { "exp(x/2 - y^2) * z", { -1, -1, -1, 1, 1, 1 } },
    { "log(x^2 + y^2 + 1) - z^3", { -2, -2, -2, 2, 2, 2 } },
    { "sqrt(x + 3) * (y - z)^2", { -2, -2, -2, 2, 2, 2 } },
    { "(x + y) / (z^2 + 1) - 1/(x + 5)", { -2, -2, -2, 2, 2, 2 } },
    { "tan(x/2) + y*z", { -1, -1, -1, 1, 1, 1 } },
    { "pow(x + 2, 1.5) + pow(y + 3, -0.5) - z", { -1, -1, -1, 1, 1, 1 } },
    { "pow(x^2 + 1, y) + x^-2", { 0.5, -1, -1, 2, 1, 1 } },
    { "3/(x + 4) - 2*y/(z + 3)", { -1, -1, -1, 1, 1, 1 } },
    { "x^5 - 3*x^3*y^2 + y^4*z - z^7/5", { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 } },
    { "sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x)", { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 } },
    { "let p = x - y\nlet q = p*p + z*x\nq*p/(1 + q^2)", { -1, -1, -1, 1, 1, 1 } },
};

static double scale_of(const double *box)
{
    return fmax(box[3] - box[0], fmax(box[4] - box[1], box[5] - box[2]));
}

/* Checks one tape at npoints random points of box. */
static void check_tape(const char *name, const ism_tape *t, const double *box, size_t npoints,
                       uint64_t seed)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    test_rng rng = { seed };
    double s = scale_of(box);
    double hg = 1e-6 * s, hh = 1e-4 * s;
    for (size_t n = 0; n < npoints; n++) {
        double p[3];
        for (int k = 0; k < 3; k++) /* keep the stencils inside the box */
            p[k] = test_uniform(&rng, box[k] + hh, box[k + 3] - hh);
        double g[3], gh[3], h[6];
        double f = ism_eval_gradient(t, ws, p[0], p[1], p[2], g);
        double fh = ism_eval_hessian(t, ws, p[0], p[1], p[2], gh, h);
        cr_assert_eq(f, ism_eval_point(t, ws, p[0], p[1], p[2]), "%s: value", name);
        cr_assert_eq(fh, f, "%s: Hessian evaluator value", name);
        double gscale = 1.0 + fabs(g[0]) + fabs(g[1]) + fabs(g[2]) + fabs(f) / s;
        for (int k = 0; k < 3; k++) {
            double a[3] = { p[0], p[1], p[2] }, b[3] = { p[0], p[1], p[2] };
            a[k] += hg;
            b[k] -= hg;
            double fd = (ism_eval_point(t, ws, a[0], a[1], a[2])
                         - ism_eval_point(t, ws, b[0], b[1], b[2])) / (2 * hg);
            cr_assert(fabs(g[k] - fd) <= 1e-6 * gscale,
                      "%s at (%g,%g,%g): df/d%c = %.12g, central difference %.12g", name, p[0],
                      p[1], p[2], 'x' + k, g[k], fd);
            cr_assert(fabs(gh[k] - g[k]) <= 1e-12 * gscale, "%s: gradients of the two "
                      "evaluators differ", name);
        }
        /* Hessian (xx xy xz yy yz zz) against central differences of the gradient */
        static const int HI[6] = { 0, 0, 0, 1, 1, 2 }, HJ[6] = { 0, 1, 2, 1, 2, 2 };
        double hscale = gscale / s + fabs(h[0]) + fabs(h[3]) + fabs(h[5]) + fabs(h[1])
                        + fabs(h[2]) + fabs(h[4]);
        for (int e = 0; e < 6; e++) {
            int i = HI[e], j = HJ[e];
            double a[3] = { p[0], p[1], p[2] }, b[3] = { p[0], p[1], p[2] };
            a[j] += hg;
            b[j] -= hg;
            double ga[3], gb[3];
            ism_eval_gradient(t, ws, a[0], a[1], a[2], ga);
            ism_eval_gradient(t, ws, b[0], b[1], b[2], gb);
            double fd = (ga[i] - gb[i]) / (2 * hg);
            cr_assert(fabs(h[e] - fd) <= 1e-5 * hscale,
                      "%s at (%g,%g,%g): H[%c%c] = %.12g, central difference %.12g", name,
                      p[0], p[1], p[2], 'x' + i, 'x' + j, h[e], fd);
        }
        /* diagonal against second differences of f itself */
        static const int DIAG[3] = { 0, 3, 5 };
        for (int k = 0; k < 3; k++) {
            double a[3] = { p[0], p[1], p[2] }, b[3] = { p[0], p[1], p[2] };
            a[k] += hh;
            b[k] -= hh;
            double fd = (ism_eval_point(t, ws, a[0], a[1], a[2]) - 2 * f
                         + ism_eval_point(t, ws, b[0], b[1], b[2])) / (hh * hh);
            cr_assert(fabs(h[DIAG[k]] - fd) <= 1e-4 * (hscale + fabs(f) / (s * s)),
                      "%s: H[%c%c] = %.12g, second difference %.12g", name, 'x' + k, 'x' + k,
                      h[DIAG[k]], fd);
        }
    }
    ism_eval_ws_free(ws);
}

Test(eval_deriv, smooth_expressions)
{
    size_t npoints = test_scaled(300);
    for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(CASES[i].expr, NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s: %s", CASES[i].expr, err.message);
        check_tape(CASES[i].expr, t, CASES[i].box, npoints, 31 + i);
        ism_tape_free(t);
    }
}

Test(eval_deriv, example_surfaces)
{
    size_t npoints = test_scaled(300);
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        if (!TEST_SURFACES[s].polynomial) /* the gyroid ball has a crease (max) */
            continue;
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        check_tape(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, npoints, 500 + s);
        ism_tape_free(t);
    }
}

/* Exact values where the answer is known in closed form. */
Test(eval_deriv, closed_forms)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("x^2*y + sin(z)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double g[3], h[6];
    double f = ism_eval_hessian(t, ws, 2.0, 3.0, 0.5, g, h);
    cr_expect_float_eq(f, 12.0 + sin(0.5), 1e-15);
    cr_expect_float_eq(g[0], 12.0, 1e-15);
    cr_expect_float_eq(g[1], 4.0, 1e-15);
    cr_expect_float_eq(g[2], cos(0.5), 1e-15);
    cr_expect_float_eq(h[0], 6.0, 1e-15);  /* xx = 2y */
    cr_expect_float_eq(h[1], 4.0, 1e-15);  /* xy = 2x */
    cr_expect_eq(h[2], 0.0);               /* xz */
    cr_expect_eq(h[3], 0.0);               /* yy */
    cr_expect_eq(h[4], 0.0);               /* yz */
    cr_expect_float_eq(h[5], -sin(0.5), 1e-15);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    /* where the domain is clipped the function is constant: zero derivatives, no NaN */
    t = ism_tape_compile("sqrt(x) + log(y)", NULL, 0, NULL, 0, NULL, &err);
    ws = ism_eval_ws_new(t);
    f = ism_eval_hessian(t, ws, -1.0, 1.0, 0.0, g, h);
    cr_expect_eq(f, 0.0);
    cr_expect_eq(g[0], 0.0);
    cr_expect_float_eq(g[1], 1.0, 1e-15);
    cr_expect_eq(h[0], 0.0);
    cr_expect_float_eq(h[3], -1.0, 1e-15);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* Sines and cosines of more arguments than the evaluators' sincos memo holds, some repeated
 * far apart: each argument's pair is computed once per evaluation, and every term must
 * still get its own argument's value and derivative. */
Test(eval_deriv, sines_and_cosines_of_many_arguments)
{
    ism_error err;
    const char *src = "sin(x) + cos(x) + sin(2*x)*cos(y) + cos(3*x) + sin(y) + cos(z) + sin(4*z)"
                      " + cos(2*x) + 10*sin(-0*x) + 100*cos(-y) + sin(x)";
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    const double pts[][3] = {{0.3, -1.2, 0.7}, {0, 0, 0}, {-2.5, 1.5, 3.25}, {1e-3, 40, -7}};
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        double x = pts[i][0], y = pts[i][1], z = pts[i][2];
        double want = sin(x) + cos(x) + sin(2 * x) * cos(y) + cos(3 * x) + sin(y) + cos(z) +
                      sin(4 * z) + cos(2 * x) + 10 * sin(-0.0 * x) + 100 * cos(-y) + sin(x);
        double gx = 2 * cos(x) - sin(x) + 2 * cos(2 * x) * cos(y) - 3 * sin(3 * x) - 2 * sin(2 * x);
        double gy = -sin(2 * x) * sin(y) + cos(y) - 100 * sin(y);
        double gz = -sin(z) + 4 * cos(4 * z);
        double g[3];
        cr_expect_float_eq(ism_eval_point(t, ws, x, y, z), want, 1e-12, "point %zu", i);
        cr_expect_float_eq(ism_eval_gradient(t, ws, x, y, z, g), want, 1e-12, "point %zu", i);
        cr_expect_float_eq(g[0], gx, 1e-12, "d/dx at point %zu", i);
        cr_expect_float_eq(g[1], gy, 1e-12, "d/dy at point %zu", i);
        cr_expect_float_eq(g[2], gz, 1e-12, "d/dz at point %zu", i);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The sincos memo's two sizes (trig_pair.h: the larger for a tape that takes sines or
 * cosines, the smaller for one that does not): a workspace of either size evaluates sines
 * and cosines of more arguments than it holds, each repeated after the others, bit for bit
 * what ism_sincos (sincos.h) returns, the gradient's as the value's. */
Test(eval_deriv, sines_and_cosines_through_either_memo_size)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("sin(x)*cos(y)", NULL, 0, NULL, 0, NULL, &err);
    ism_tape *plain = ism_tape_compile("x*y + y*z + z*x + x*x*y - z*z*(x + 1)", NULL, 0, NULL,
                                       0, NULL, &err);
    cr_assert(t && plain);
    ism_eval_ws *ws[2] = {ism_eval_ws_new(t), ism_eval_ws_new(plain)};
    cr_assert(ws[0] && ws[1]);
    /* ws[1] is plain's (the small memo) but evaluates t: it must hold t's registers and
     * instructions, or every call below gives NAN and fails as a wrong sine */
    cr_assert(ism_ws_fits(ws[1], t), "plain's workspace does not fit t: lengthen plain");
    cr_assert_eq(ws[0]->trig->mask, (1u << ISM_TRIG_CACHE_BITS) - 1);
    cr_assert_eq(ws[1]->trig->mask, (1u << ISM_TRIG_CACHE_SMALL_BITS) - 1);
    const int n = 3 << ISM_TRIG_CACHE_BITS; /* each argument's slot taken again in between */
    for (int w = 0; w < 2; w++)
        for (int pass = 0; pass < 2; pass++)
            for (int i = 0; i < n; i++) {
                double x = 0.37 * i - 11.0, y = -0.011 * i, g[3], sx, cx, sy, cy;
                ism_sincos(x, &sx, &cx);
                ism_sincos(y, &sy, &cy);
                double want = sx * cy;
                double got = ism_eval_point(t, ws[w], x, y, 0);
                cr_assert(memcmp(&got, &want, sizeof got) == 0, "memo %d, pass %d, x %.17g, y "
                          "%.17g: %.17g, ism_sincos gives %.17g", w, pass, x, y, got, want);
                got = ism_eval_gradient(t, ws[w], x, y, 0, g);
                cr_assert(memcmp(&got, &want, sizeof got) == 0, "memo %d, pass %d, x %.17g: "
                          "gradient's f %.17g", w, pass, x, got);
                cr_assert_float_eq(g[0], cos(x) * cos(y), 1e-15, "memo %d, x %.17g", w, x);
                cr_assert_float_eq(g[1], -sin(x) * sin(y), 1e-15, "memo %d, x %.17g", w, x);
            }
    ism_eval_ws_free(ws[0]);
    ism_eval_ws_free(ws[1]);
    ism_tape_free(plain);
    ism_tape_free(t);
}

/* The crease branches of f = g(max(a, b)), g one-operand steps (ism_eval_crease_branches):
 * g(a) and g(b) with their gradients by the closed form, in either order; the top-only
 * evaluator declines such an f, and a two-operand step after the max ends the chain. */
Test(eval_deriv, crease_branches_through_one_operand_steps)
{
    ism_error err;
    /* 2 max(x, y^2) - 1 at (0.3, 0.6, 0.1): 2x - 1 = -0.4, ∇ (2, 0, 0); 2y^2 - 1 = -0.28,
       ∇ (0, 4y, 0) = (0, 2.4, 0); sqrt(max(x, y^2) + 3): sqrt(3.3), ∇ (1/(2 sqrt 3.3), 0, 0)
       and sqrt(3.36), ∇ (0, 2y/(2 sqrt 3.36), 0) */
    /* max(x, y^2) * 2: a tail of one step (branches_at's `if (after)`): 0.6, ∇ (2, 0, 0);
       0.72, ∇ (0, 4y, 0) = (0, 2.4, 0) */
    const char *exprs[3] = {"2*max(x, y^2) - 1", "sqrt(max(x, y^2) + 3)", "max(x, y^2) * 2"};
    const size_t tail[3] = {2, 2, 1}; /* the steps after the max */
    const double x = 0.3, y = 0.6, z = 0.1;
    const double want[3][2][4] = {
        {{-0.4, 2, 0, 0}, {-0.28, 0, 2.4, 0}},
        {{sqrt(3.3), 0.5 / sqrt(3.3), 0, 0}, {sqrt(3.36), 0, y / sqrt(3.36), 0}},
        {{0.6, 2, 0, 0}, {0.72, 0, 2.4, 0}},
    };
    for (int e = 0; e < 3; e++) {
        ism_tape *t = ism_tape_compile(exprs[e], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s", exprs[e]);
        cr_assert_gt(t->len, tail[e], "%s", exprs[e]);
        cr_expect_eq(t->code[t->len - 1 - tail[e]].op, ISM_OP_MAX_RR, "%s: a tail of %zu",
                     exprs[e], tail[e]);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        double val[2], g[2][3];
        cr_expect_not(ism_eval_top_branches(t, ws, x, y, z, val, g), "%s", exprs[e]);
        cr_assert(ism_eval_crease_branches(t, ws, x, y, z, val, g), "%s", exprs[e]);
        int first = fabs(val[0] - want[e][0][0]) < fabs(val[0] - want[e][1][0]) ? 0 : 1;
        for (int s = 0; s < 2; s++) {
            const double *w = want[e][s == 0 ? first : 1 - first];
            cr_expect(fabs(val[s] - w[0]) < 1e-14, "%s: branch %d %.17g vs %.17g", exprs[e],
                      s, val[s], w[0]);
            for (int k = 0; k < 3; k++)
                cr_expect(fabs(g[s][k] - w[1 + k]) < 1e-14, "%s: branch %d ∂%d %.17g vs %.17g",
                          exprs[e], s, k, g[s][k], w[1 + k]);
        }
        /* f is the larger branch (g increasing) */
        cr_expect_eq(ism_eval_point(t, ws, x, y, z), fmax(val[0], val[1]), "%s", exprs[e]);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
    ism_tape *t = ism_tape_compile("max(x, y^2) * z", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    double val[2], g[2][3];
    cr_expect_not(ism_eval_crease_branches(t, ws, x, y, z, val, g), "max(x, y^2) * z");
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}
