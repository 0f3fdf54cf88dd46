/* test_rm_newton2.c — rm_newton_two (core/remesh/rm_newton2.c) against closed forms: two
 * spheres' circle of intersection (lands on it to rounding, the gradients returned are the
 * ones measured at the last point before the step), a point already on both zero sets where
 * the gradients are parallel (true, x unmoved), parallel planes apart (false: never on),
 * a value that is not finite (false), and x³ = 0, where Newton gains only a third a step and
 * ISM_RM_CREASE_NEWTON_STEPS steps cannot reach the tolerance from 1 (false) but can from
 * 1e-4 (true). The spheres' start points are shifted off any symmetric place (1e-3 and an
 * irrational fraction), as the quality pass meets them. */
#include <criterion/criterion.h>
#include <math.h>

#include "core/remesh/rm_pass.h"

/* Which pair of functions: their kind and a parameter. */
typedef struct pair_fn {
    int kind; /* 0 spheres, 1 planes x = 0 and x = d, 2 x and 2x, 3 NaN, 4 x³ and y */
    double d;
    int calls;
    double last[3]; /* where it was evaluated last */
} pair_fn;

static bool eval_pair(void *ctx, const double x[3], double val[2], double g[2][3])
{
    pair_fn *c = ctx;
    c->calls++;
    for (int k = 0; k < 3; k++)
        c->last[k] = x[k];
    for (int s = 0; s < 2; s++)
        for (int k = 0; k < 3; k++)
            g[s][k] = 0;
    switch (c->kind) {
    case 0: /* unit spheres centred at (±0.5, 0, 0) */
        for (int s = 0; s < 2; s++) {
            double cx = s ? -0.5 : 0.5, dx = x[0] - cx;
            val[s] = dx * dx + x[1] * x[1] + x[2] * x[2] - 1;
            g[s][0] = 2 * dx, g[s][1] = 2 * x[1], g[s][2] = 2 * x[2];
        }
        return true;
    case 1:
        val[0] = x[0], val[1] = x[0] - c->d;
        g[0][0] = g[1][0] = 1;
        return true;
    case 2:
        val[0] = x[0], val[1] = 2 * x[0];
        g[0][0] = 1, g[1][0] = 2;
        return true;
    case 3:
        val[0] = NAN, val[1] = x[1];
        g[0][0] = 1, g[1][1] = 1;
        return true;
    default:
        val[0] = x[0] * x[0] * x[0], val[1] = x[1];
        g[0][0] = 3 * x[0] * x[0], g[1][1] = 1;
        return true;
    }
}

Test(rm_newton2, two_spheres_land_on_their_circle)
{
    const double shift[3] = {0, 1e-3, M_SQRT2 - 1};
    for (int s = 0; s < 3; s++) {
        pair_fn c = {.kind = 0};
        double x[3] = {0.11 + shift[s], 0.52 - shift[s], 0.47 + shift[s] / 3}, g[2][3];
        cr_assert(rm_newton_two(eval_pair, &c, x, 1e-9, g));
        /* the circle x = 0, y² + z² = 3/4 */
        cr_assert(fabs(x[0]) < 1e-12, "x %.3g", x[0]);
        cr_assert(fabs(hypot(x[1], x[2]) - sqrt(0.75)) < 1e-12);
        /* g is the gradients at the last point evaluated, before the last step */
        cr_assert(g[0][0] == 2 * (c.last[0] - 0.5) && g[1][0] == 2 * (c.last[0] + 0.5));
        cr_assert(g[0][1] == 2 * c.last[1] && g[1][2] == 2 * c.last[2]);
        cr_assert(c.last[0] != x[0] || c.last[1] != x[1], "one step more after the test");
        cr_assert(c.calls >= 2 && c.calls <= ISM_RM_CREASE_NEWTON_STEPS + 1);
    }
}

Test(rm_newton2, on_already_with_parallel_gradients_stays)
{
    pair_fn c = {.kind = 2};
    double x[3] = {0, 0.3, -0.7}, g[2][3];
    cr_assert(rm_newton_two(eval_pair, &c, x, 1e-9, g));
    cr_assert(x[0] == 0 && x[1] == 0.3 && x[2] == -0.7);
    cr_assert_eq(c.calls, 1);
}

Test(rm_newton2, parallel_planes_apart_never_land)
{
    pair_fn c = {.kind = 1, .d = 0.5};
    double x[3] = {0.2, 0, 0}, g[2][3];
    cr_assert_not(rm_newton_two(eval_pair, &c, x, 1e-9, g));
    cr_assert_eq(c.calls, 1, "a failed step off the zero sets ends the search");
}

Test(rm_newton2, a_value_not_finite_fails)
{
    pair_fn c = {.kind = 3};
    double x[3] = {0, 0, 0}, g[2][3];
    cr_assert_not(rm_newton_two(eval_pair, &c, x, 1e-9, g));
}

Test(rm_newton2, the_step_limit_holds)
{
    /* x³ (gradient 3x²) is on when |x³| <= tol · 3x², i.e. x <= 3 tol, and each step takes x
     * to 2x/3. From 1 with tol 1e-9 that needs (2/3)^k <= 3e-9, k = 48: past the limit. */
    pair_fn c = {.kind = 4};
    double x[3] = {1, 0.2, 0}, g[2][3];
    cr_assert_not(rm_newton_two(eval_pair, &c, x, 1e-9, g));
    cr_assert_eq(c.calls, ISM_RM_CREASE_NEWTON_STEPS + 1);
    /* with tol 0.02, (2/3)^k <= 0.06 from k = 7: on at the 8th evaluation, then one step */
    pair_fn d = {.kind = 4};
    double y[3] = {1, 0.2, 0};
    cr_assert(rm_newton_two(eval_pair, &d, y, 0.02, g));
    cr_assert_eq(d.calls, 8, "on at the 8th evaluation ((2/3)^7 = 0.0585 <= 0.06)");
    cr_assert(fabs(y[0] - pow(2.0 / 3, 8)) < 1e-15 && y[1] == 0);
}
