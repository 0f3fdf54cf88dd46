/* test_meets_kink.c — ism_eval_interval_meets_kink (interval_jet.h): whether the gradient
 * pass over a box meets a free min, max or abs, told from the values alone. Checked against
 * the gradient pass itself (ism_eval_interval_grad's count, in a workspace of its own) over
 * boxes of three sizes on a grid through each surface's features, in the three placements
 * (tests/unit/placements.h: the grid moved by PF_OFF and by PF_IRR of a box), and over odd
 * boxes (a point, the whole line, lo > hi, a NaN bound); each surface must give both answers
 * somewhere, so a test that always says yes or always no fails. Also: a workspace too small
 * for the tape says yes (the pass's (size_t)-1), and the call leaves no gradient pass in the
 * registers for ism_ivjet_top_pieces to read. */
#include <criterion/criterion.h>
#include <math.h>
#include "poly_fixture.h"
#include "core/eval/interval_jet.h"
#include "tests/unit/placements.h"

#define PHI "1.6180339887498949"
/* Tapes with kinks where the boxes meet them, a kink beside a pole (sqrt's whole slopes at 0
 * are not a kink), and a smooth one (never). */
static const char *const EXPRS[] = {
    "max(4*(" PHI "^2*x^2 - y^2)*(" PHI "^2*y^2 - z^2)*(" PHI "^2*z^2 - x^2) - (1 + 2*" PHI
    ")*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
    "min(x - 0.25, y*y - z) + abs(z - 0.5*x)",
    "max(x*y*z, 0.125) - sqrt(x*x + y*y)",
    "abs(x) + abs(y) + abs(z) - 1",
    "x^2 + y^2 + z^2 - 1",
};
#define NEXPRS (sizeof EXPRS / sizeof EXPRS[0])

/* Whether the gradient pass over box reports a kink or a misfit (its own workspace). */
static bool grad_meets(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3])
{
    ism_ivgrad g;
    return ism_eval_interval_grad(t, ws, box, NULL, NULL, &g) != 0;
}

/* The two agree over every box of side s on the grid [-1.6, 1.6)^3 moved by shift[] times s;
 * the count of boxes each answer came from added to seen[]. */
static void sweep(const ism_tape *t, ism_ivjet_ws *ws, ism_ivjet_ws *ref, double s,
                  const double shift[3], int seen[2])
{
    int n = (int)lround(3.2 / s);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++)
            for (int k = 0; k < n; k++) {
                int at[3] = {i, j, k};
                ism_interval box[3];
                for (int a = 0; a < 3; a++) {
                    double lo = -1.6 + (at[a] + shift[a]) * s;
                    box[a] = (ism_interval){lo, lo + s};
                }
                bool want = grad_meets(t, ref, box);
                bool got = ism_eval_interval_meets_kink(t, ws, box);
                cr_assert_eq(got, want, "box [%.17g %.17g] [%.17g %.17g] [%.17g %.17g]: %d, "
                             "the gradient pass %d", box[0].lo, box[0].hi, box[1].lo,
                             box[1].hi, box[2].lo, box[2].hi, got, want);
                seen[got]++;
            }
}

Test(meets_kink, agrees_with_the_gradient_pass)
{
    const double shifts[3][3] = {{0, 0, 0},
                                 {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                 {PF_IRR_X, PF_IRR_Y, PF_IRR_Z}};
    const double sides[] = {0.8, 0.2, 0.1};
    for (size_t e = 0; e < NEXPRS; e++) {
        pf_surface sf = {EXPRS[e], NULL, 0, NULL, 0};
        ism_tape *t = pf_compile(&sf);
        ism_ivjet_ws *ws = ism_ivjet_ws_new(t), *ref = ism_ivjet_ws_new(t);
        int seen[2] = {0, 0};
        for (int p = pf_first_box(); p < 3; p++)
            for (size_t z = 0; z < sizeof sides / sizeof sides[0]; z++)
                sweep(t, ws, ref, sides[z], shifts[p], seen);
        bool smooth = e == NEXPRS - 1;
        cr_expect_gt(seen[0], 0, "%s: some box meets no kink", EXPRS[e]);
        cr_expect(smooth ? seen[1] == 0 : seen[1] > 0, "%s: %d boxes meet a kink", EXPRS[e],
                  seen[1]);
        ism_ivjet_ws_free(ws);
        ism_ivjet_ws_free(ref);
        ism_tape_free(t);
    }
}

/* A point (a tie at the kink: both branches), the whole line, lo > hi (taken as the whole
 * line), NaN bounds, a box far out whose powers overflow. */
Test(meets_kink, odd_boxes)
{
    const double nan = NAN, inf = INFINITY;
    const ism_interval odd[][3] = {
        {{0.5, 0.5}, {0.5, 0.5}, {0.0, 0.0}},
        {{-inf, inf}, {-inf, inf}, {-inf, inf}},
        {{1.0, -1.0}, {0.0, 0.1}, {0.0, 0.1}},
        {{nan, 0.2}, {0.0, 0.1}, {0.0, 0.1}},
        {{0.0, 0.1}, {0.0, nan}, {0.3, 0.4}},
        {{1e200, 1e201}, {1e200, 1e201}, {-1e201, -1e200}},
        {{1.0, 1.1}, {1.0, 1.1}, {1.0, 1.1}},
    };
    for (size_t e = 0; e < NEXPRS; e++) {
        pf_surface sf = {EXPRS[e], NULL, 0, NULL, 0};
        ism_tape *t = pf_compile(&sf);
        ism_ivjet_ws *ws = ism_ivjet_ws_new(t), *ref = ism_ivjet_ws_new(t);
        for (size_t b = 0; b < sizeof odd / sizeof odd[0]; b++)
            cr_expect_eq(ism_eval_interval_meets_kink(t, ws, odd[b]), grad_meets(t, ref, odd[b]),
                         "%s, odd box %zu", EXPRS[e], b);
        ism_ivjet_ws_free(ws);
        ism_ivjet_ws_free(ref);
        ism_tape_free(t);
    }
}

/* A workspace made for a shorter tape: the gradient pass returns (size_t)-1, so yes. */
Test(meets_kink, workspace_too_small)
{
    pf_surface small = {"x", NULL, 0, NULL, 0}, big = {EXPRS[0], NULL, 0, NULL, 0};
    ism_tape *ts = pf_compile(&small), *tb = pf_compile(&big);
    ism_ivjet_ws *ws = ism_ivjet_ws_new(ts);
    const ism_interval box[3] = {{0.1, 0.2}, {0.1, 0.2}, {0.1, 0.2}};
    cr_assert(grad_meets(tb, ws, box), "the pass refuses the tape");
    cr_expect(ism_eval_interval_meets_kink(tb, ws, box));
    ism_ivjet_ws_free(ws);
    ism_tape_free(ts);
    ism_tape_free(tb);
}

/* After the values pass the registers hold no gradient pass: ism_ivjet_top_pieces, which
 * reads the pieces of a free top max from them, finds none (it did after the gradient pass
 * over the same box). */
Test(meets_kink, leaves_no_gradient_pass)
{
    pf_surface sf = {"max(x*x + y - 0.25, z - x)", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&sf);
    ism_ivjet_ws *ws = ism_ivjet_ws_new(t);
    const double shifts[3] = {0.0, PF_OFF_X, PF_IRR_X * 0.1};
    for (int p = pf_first_box(); p < 3; p++) {
        double o = shifts[p];
        const ism_interval box[3] = {{o, o + 0.5}, {o, o + 0.5}, {o, o + 0.5}};
        ism_ivgrad g, piece[2];
        cr_assert_eq(ism_eval_interval_grad(t, ws, box, NULL, NULL, &g), 1, "a free top max");
        cr_assert(ism_ivjet_top_pieces(t, ws, box, piece), "the pass stands");
        cr_assert(ism_eval_interval_meets_kink(t, ws, box));
        cr_expect(!ism_ivjet_top_pieces(t, ws, box, piece), "placement %d: no pass stands", p);
    }
    ism_ivjet_ws_free(ws);
    ism_tape_free(t);
}
