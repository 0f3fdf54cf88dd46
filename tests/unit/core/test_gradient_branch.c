/* test_gradient_branch.c — top_branch.h's min/max gradient rule (ism_minmax_gradient_operand,
 * ism_top_gradient_branch): the operand a min or max passes its derivative on from is a where
 * a wins strictly, else b (a tie, a NaN), while the label (ism_top_active_branch) takes a on a
 * tie or a NaN. Checked three ways: the rule's values written out by hand (ties, NaN on either
 * side, ±0, infinities), the rule against what each evaluator passes on (ism_eval_gradient,
 * ism_eval_gradient_batch, ism_eval_hessian, ism_eval_piece) at points where the top max or min
 * ties or reads a NaN — each evaluator's gradient must be bit for bit the gradient of the
 * branch the rule names, as ism_eval_top_branches evaluates the two branches apart — and the
 * label against the rule (they part exactly at the ties and NaN). The points sit on the
 * diagonal x = y at the own, PF_OFF and PF_IRR placements (the tie exact at each). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/eval/top_branch.h"
#include "core/eval/workspace.h"
#include "tests/unit/placements.h"

/* The rule by hand: 0 only where a wins strictly. */
Test(gradient_branch, rule_by_hand)
{
    const double nan = NAN, inf = INFINITY;
    /* {a, b, max's operand, min's operand} */
    const double cases[][4] = {
        {2, 1, 0, 1},   {1, 2, 1, 0},       /* strict: the winner */
        {1, 1, 1, 1},   {-0.0, 0.0, 1, 1},  /* ties (±0 compare equal): b */
        {0.0, -0.0, 1, 1}, {inf, inf, 1, 1}, {-inf, -inf, 1, 1},
        {nan, 1, 1, 1}, {1, nan, 1, 1},     /* NaN on either side: b */
        {nan, nan, 1, 1}, {inf, nan, 1, 1}, {nan, -inf, 1, 1},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        double a = cases[i][0], b = cases[i][1];
        cr_expect_eq(ism_minmax_gradient_operand(false, a, b), (int)cases[i][2],
                     "max(%g, %g)", a, b);
        cr_expect_eq(ism_minmax_gradient_operand(true, a, b), (int)cases[i][3],
                     "min(%g, %g)", a, b);
    }
}

/* The tape's top min/max: the rule and the label on values v, and -1 without one. */
Test(gradient_branch, top_and_label)
{
    pf_surface smax = {"max(x, y)", NULL, 0, NULL, 0}, smin = {"min(x, y)", NULL, 0, NULL, 0},
               none = {"x + y", NULL, 0, NULL, 0};
    ism_tape *tmax = pf_compile(&smax), *tmin = pf_compile(&smin), *tn = pf_compile(&none);
    const double tie[2] = {0.5, 0.5}, an[2] = {NAN, 0.5}, bn[2] = {0.5, NAN};
    const double hi_a[2] = {1, 0}, hi_b[2] = {0, 1};
    cr_expect_eq(ism_top_gradient_branch(tmax, tie), 1);
    cr_expect_eq(ism_top_gradient_branch(tmin, tie), 1);
    cr_expect_eq(ism_top_gradient_branch(tmax, an), 1);
    cr_expect_eq(ism_top_gradient_branch(tmax, bn), 1);
    cr_expect_eq(ism_top_gradient_branch(tmin, an), 1);
    cr_expect_eq(ism_top_gradient_branch(tmin, bn), 1);
    cr_expect_eq(ism_top_gradient_branch(tmax, hi_a), 0);
    cr_expect_eq(ism_top_gradient_branch(tmax, hi_b), 1);
    cr_expect_eq(ism_top_gradient_branch(tmin, hi_a), 1);
    cr_expect_eq(ism_top_gradient_branch(tmin, hi_b), 0);
    cr_expect_eq(ism_top_gradient_branch(tn, tie), -1);
    /* the label takes a on a tie and a NaN; elsewhere the two agree */
    const double *vals[] = {tie, an, bn};
    for (int i = 0; i < 3; i++) {
        cr_expect_eq(ism_top_active_branch(tmax, vals[i]), 0);
        cr_expect_eq(ism_top_active_branch(tmin, vals[i]), 0);
    }
    cr_expect_eq(ism_top_active_branch(tmax, hi_a), ism_top_gradient_branch(tmax, hi_a));
    cr_expect_eq(ism_top_active_branch(tmin, hi_a), ism_top_gradient_branch(tmin, hi_a));
    ism_tape_free(tmax);
    ism_tape_free(tmin);
    ism_tape_free(tn);
}

/* At p, every evaluator's gradient of t is bit for bit the gradient of the branch
 * ism_top_gradient_branch names from the two branches' values (ism_eval_top_branches), and
 * ism_eval_piece's top kink takes 1 + it. Returns that branch. */
static int check_point(const ism_tape *t, ism_eval_ws *ws, const double p[3], const char *what)
{
    double v[2], bg[2][3];
    cr_assert(ism_eval_top_branches(t, ws, p[0], p[1], p[2], v, bg));
    int b = ism_top_gradient_branch(t, v);
    cr_assert(b == 0 || b == 1);
    double g[3], f = ism_eval_gradient(t, ws, p[0], p[1], p[2], g);
    cr_expect_eq(memcmp(g, bg[b], sizeof g), 0, "%s: ism_eval_gradient (%g %g %g), branch %d",
                 what, g[0], g[1], g[2], b);
    cr_expect(f == v[b] || (isnan(f) && isnan(v[b])), "%s: f %g, branch value %g", what, f,
              v[b]);
    double x[5], y[5], z[5], bf[5], bgr[5][3]; /* a batch: the point among others */
    for (int i = 0; i < 5; i++)
        x[i] = p[0] + (i - 2) * 0.25, y[i] = p[1], z[i] = p[2];
    x[2] = p[0];
    ism_eval_gradient_batch(t, ws, x, y, z, bf, bgr, 5);
    cr_expect_eq(memcmp(bgr[2], bg[b], sizeof g), 0, "%s: batch lane (%g %g %g), branch %d",
                 what, bgr[2][0], bgr[2][1], bgr[2][2], b);
    double hg[3], hh[6];
    ism_eval_hessian(t, ws, p[0], p[1], p[2], hg, hh);
    cr_expect_eq(memcmp(hg, bg[b], sizeof g), 0, "%s: ism_eval_hessian's gradient", what);
    ism_piece pc = ism_eval_piece(t, ws, p[0], p[1], p[2]);
    cr_expect_eq(ism_piece_branch(pc, 0), 1u + (unsigned)b, "%s: piece %llx", what,
                 (unsigned long long)pc);
    return b;
}

/* max and min of two planes of different slopes meeting on x = y (so ∇a ≠ ∇b there): at a
 * tie on the diagonal, at a NaN x (both operands read it: NaN values, finite distinct
 * gradients) and off the diagonal on both sides, in the three placements. */
Test(gradient_branch, evaluators_follow_the_rule)
{
    const char *exprs[] = {"max(2 * x - y, x)", "min(2 * x - y, x)"};
    for (int e = 0; e < 2; e++) {
        pf_surface s = {exprs[e], NULL, 0, NULL, 0};
        ism_tape *t = pf_compile(&s);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        cr_assert(ws && ism_tape_top_minmax(t));
        const double base[3][3] = {{0.5, 0.5, 0.25},
                                   {0.5 + PF_OFF_X, 0.5 + PF_OFF_X, 0.25 + PF_OFF_Z},
                                   {0.5 + PF_IRR_X, 0.5 + PF_IRR_X, 0.25 + PF_IRR_Z}};
        int took_b = 0;
        for (int w = 0; w < 3; w++) {
            const double *d = base[w];
            double tie[3] = {d[0], d[1], d[2]}, nan_x[3] = {NAN, d[1], d[2]};
            double above[3] = {d[0] + 0.125, d[1], d[2]}, below[3] = {d[0] - 0.125, d[1], d[2]};
            double v[2], bg[2][3];
            cr_assert(ism_eval_top_branches(t, ws, tie[0], tie[1], tie[2], v, bg));
            cr_assert(v[0] == v[1] && memcmp(bg[0], bg[1], sizeof bg[0]) != 0,
                      "%s: the diagonal ties with distinct gradients", exprs[e]);
            took_b += check_point(t, ws, tie, exprs[e]) == 1;
            took_b += check_point(t, ws, nan_x, exprs[e]) == 1;
            int ba = check_point(t, ws, above, exprs[e]), bb = check_point(t, ws, below,
                                                                          exprs[e]);
            cr_expect_neq(ba, bb, "%s: the two sides of the crease take different branches",
                          exprs[e]);
        }
        cr_expect_eq(took_b, 6, "%s: ties and NaN take b", exprs[e]);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
}

/* The register–constant forms min(x, c) and max(x, c) (MIN_RC / MAX_RC: the constant is
 * operand b) follow the same rule: ∂/∂x is 1 only where x wins strictly, 0 on the tie x = c
 * and at a NaN x — written out by hand here, not read from the rule. ism_eval_gradient,
 * ism_eval_hessian's gradient and a batch's tail lane (lane 4 of 5) must give it, and
 * ism_eval_piece's kink 1 + the operand. c sits at 0.5 moved by the three placements' shifts,
 * and x one ulp either side of it. */
Test(gradient_branch, constant_operand_follows_the_rule)
{
    const double shift[3] = {0, PF_OFF_X, PF_IRR_X};
    for (int e = 0; e < 2; e++)
        for (int w = 0; w < 3; w++) {
            double c = 0.5 + shift[w];
            char text[64];
            snprintf(text, sizeof text, e ? "max(x, %.17g)" : "min(x, %.17g)", c);
            pf_surface s = {text, NULL, 0, NULL, 0};
            ism_tape *t = pf_compile(&s);
            ism_eval_ws *ws = ism_eval_ws_new(t);
            cr_assert(ws && t->len > 0);
            cr_assert_eq(t->code[t->len - 1].op, e ? ISM_OP_MAX_RC : ISM_OP_MIN_RC, "%s", text);
            /* x, and ∂/∂x by hand: {tie, one ulp up, one ulp down, NaN} */
            const double xs[4] = {c, nextafter(c, 2), nextafter(c, 0), NAN};
            const double want[2][4] = {{0, 0, 1, 0}, {0, 1, 0, 0}}; /* min, max */
            for (int i = 0; i < 4; i++) {
                double x = xs[i], d = want[e][i], g[3], hg[3], hh[6];
                ism_eval_gradient(t, ws, x, 0.25, 0.25, g);
                cr_expect(g[0] == d && g[1] == 0 && g[2] == 0, "%s at %.17g: gradient %g",
                          text, x, g[0]);
                ism_eval_hessian(t, ws, x, 0.25, 0.25, hg, hh);
                cr_expect(hg[0] == d, "%s at %.17g: ism_eval_hessian's %g", text, x, hg[0]);
                double bx[5] = {0, 1, -1, 2, x}, by[5] = {0}, bz[5] = {0}, bf[5], bgr[5][3];
                ism_eval_gradient_batch(t, ws, bx, by, bz, bf, bgr, 5);
                cr_expect(bgr[4][0] == d, "%s at %.17g: batch lane 4's %g", text, x, bgr[4][0]);
                ism_piece pc = ism_eval_piece(t, ws, x, 0.25, 0.25);
                cr_expect_eq(ism_piece_branch(pc, 0), d == 1 ? 1u : 2u, "%s at %.17g: piece",
                             text, x);
            }
            ism_eval_ws_free(ws);
            ism_tape_free(t);
        }
}
