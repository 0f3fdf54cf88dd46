/* test_tape_partial.c — the partial-derivative tapes (core/eval/tape_partial.h): their values
 * against central differences of f at random points of smooth expressions using every
 * operation (min/max/abs away from their kinks), a closed form of a third derivative through
 * their interval Hessian, and a non-finite value at a kink. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/eval/tape_partial.h"

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

/* Box [-1, 1]³ shifted by 0.5 where the operations are smooth. */
static const char *const SMOOTH[] = {
    "sin(3*x)*cos(2*y) + tan(z/2) + exp(x*y)",
    "log(x^2 + y^2 + 1) - z^3 + sqrt(x + 3)*y",
    "pow(x + 2, 1.5) + pow(y + 3, -0.5) - z^5 + 3/(x + 4) - y/(z + 3)",
    "max(x, 5)*min(y, -5) + max(z^2 + 1, 0.5) + abs(x + 4) + min(x + 7, y)*max(z - 7, y^2)",
    "let p = x - y\nlet q = p*p + z*x\nq*p/(1 + q^2) - (x - 0.3)^4",
};

Test(tape_partial, matches_differences)
{
    srand(7);
    for (size_t c = 0; c < sizeof SMOOTH / sizeof *SMOOTH; c++) {
        ism_tape *t = compile(SMOOTH[c]);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        for (int axis = 0; axis < 3; axis++) {
            ism_tape *d = ism_tape_partial(t, axis);
            cr_assert_not_null(d);
            ism_eval_ws *wd = ism_eval_ws_new(d);
            for (int i = 0; i < 50; i++) {
                double p[3], h = 1e-5;
                for (int k = 0; k < 3; k++)
                    p[k] = -0.5 + (double)rand() / RAND_MAX;
                double a[3] = { p[0], p[1], p[2] }, b[3] = { p[0], p[1], p[2] };
                a[axis] += h;
                b[axis] -= h;
                double diff = (ism_eval_point(t, ws, a[0], a[1], a[2])
                               - ism_eval_point(t, ws, b[0], b[1], b[2])) / (2 * h);
                double got = ism_eval_point(d, wd, p[0], p[1], p[2]);
                cr_expect(fabs(got - diff) <= 1e-6 * (1 + fabs(diff)),
                          "%s, axis %d at (%g, %g, %g): %.12g vs differences %.12g", SMOOTH[c],
                          axis, p[0], p[1], p[2], got, diff);
            }
            ism_eval_ws_free(wd);
            ism_tape_free(d);
        }
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}

/* f = x²z + y³ sin(x): ∂f/∂y = 3y² sin(x), whose Hessian holds f_yyy = 6 sin(x),
 * f_xyy = 6y cos(x), f_xxy = −3y² sin(x). Over a point box the enclosures hold them. */
Test(tape_partial, third_derivatives_by_interval_hessian)
{
    ism_tape *t = compile("x^2*z + y^3*sin(x)");
    ism_tape *dy = ism_tape_partial(t, 1);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(dy);
    double p[3] = { 0.7, -0.4, 0.3 };
    ism_interval box[3] = { { p[0], p[0] }, { p[1], p[1] }, { p[2], p[2] } };
    ism_ivjet j;
    ism_eval_interval_jet(dy, jw, box, NULL, NULL, &j);
    double want[3] = { -3 * p[1] * p[1] * sin(p[0]), 6 * p[1] * cos(p[0]), 6 * sin(p[0]) };
    ism_interval got[3] = { j.h[0], j.h[1], j.h[3] }; /* xx, xy, yy of ∂f/∂y */
    for (int i = 0; i < 3; i++)
        cr_expect(got[i].lo <= want[i] + 1e-12 && got[i].hi >= want[i] - 1e-12 &&
                      got[i].hi - got[i].lo < 1e-12,
                  "entry %d: [%g, %g] vs %g", i, got[i].lo, got[i].hi, want[i]);
    ism_ivjet_ws_free(jw);
    ism_tape_free(dy);
    ism_tape_free(t);
}

/* At a kink the derivative is not finite (never a wrong finite value). */
Test(tape_partial, kink_is_not_finite)
{
    ism_tape *t = compile("abs(x) + max(y, z)");
    ism_tape *dx = ism_tape_partial(t, 0), *dy = ism_tape_partial(t, 1);
    ism_eval_ws *wx = ism_eval_ws_new(dx), *wy = ism_eval_ws_new(dy);
    cr_expect(!isfinite(ism_eval_point(dx, wx, 0.0, 0.3, 0.1)));
    cr_expect(!isfinite(ism_eval_point(dy, wy, 0.2, 0.5, 0.5)));
    cr_expect_float_eq(ism_eval_point(dx, wx, -0.5, 0.3, 0.1), -1.0, 1e-15);
    cr_expect_float_eq(ism_eval_point(dy, wy, 0.2, 0.6, 0.5), 1.0, 1e-15);
    ism_eval_ws_free(wx);
    ism_eval_ws_free(wy);
    ism_tape_free(dx);
    ism_tape_free(dy);
    ism_tape_free(t);
}
