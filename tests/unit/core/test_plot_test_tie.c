/* test_plot_test_tie.c — a crease node whose corner sits exactly on the crease (a == b) where
 * f's gradient, as the evaluator reports it, vanishes: ism_plot_test lets it pass only through
 * one_branch_graph's certificate (plot_test.c crease_cell), however the label and f's
 * derivative break the tie. f = max(a, b), a = h/2 − (x − dx), b = h/2 − s², s = (x − dx) +
 * (y − dy) + (z − dz), on the node [d, d + h]³ (h = 0.1): at corner 0 (p = d) a = b = h/2, ∇b =
 * 0 and ∇a = (−m, 0, 0). A tie goes to the tape's second operand in f's derivative
 * (eval_gradient.c: a.v > b.v ? a : b) and to its first in the label (ism_top_active_branch:
 * val[1] > val[0]); the compiler orders them by structural hash (graph.c), so the slope m runs
 * 1..6 until the tape puts b second: then ∇f = 0 there while the labelled gradient is a's. By hand, with h = 0.1: corners 0, 2, 4, 6 (x = dx) on a (a = 0.05
 * ≥ b), whose gradients are all (−m, 0, 0); corners 1, 3, 5, 7 on b (b > a = −0.05), whose
 * gradients are all along −(1, 1, 1): each branch's corners agree, so only ∇f = 0 at corner 0
 * can send the node to the certificate, and the certificate refuses it (over the box a and b
 * both reach 0.05 > 0, so neither is proven below 0: no live branch). The node passed before
 * (revE 3). Run at the lattice origin and at the PF_OFF_* / PF_IRR_* offsets (the tie exact
 * at each: x − dx is 0 at x = dx). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/crease_split.h"
#include "core/octree/plot_test.h"
#include "core/octree/sampler.h"

#define H 0.1 /* the node's side */

/* The node's corners with f and ∇f; false when this spelling's tape does not put the tie the
 * way the case needs (∇f = 0 at corner 0, the label's gradient not): the compiler orders a
 * max's operands by their structure's hash (graph.c), so which operand a tie's derivative
 * takes depends on the spelling, and the caller tries a few slopes of a. */
static bool tie_corners(ism_sampler *smp, const double d[3], ism_corners *k)
{
    memset(k, 0, sizeof *k);
    for (int c = 0; c < 8; c++) {
        for (int a = 0; a < 3; a++)
            k->p[c][a] = d[a] + (c >> a & 1 ? H : 0);
        k->f[c] = ism_eval_gradient(smp->tape, smp->ws, k->p[c][0], k->p[c][1], k->p[c][2],
                                    k->g[c]);
    }
    double lg[3];
    int label = ism_crease_branch(smp, k->p[0], lg);
    return k->g[0][0] == 0 && k->g[0][1] == 0 && k->g[0][2] == 0 && label >= 0 &&
           fabs(lg[0]) + fabs(lg[1]) + fabs(lg[2]) > 0;
}

static void tie_node(const double d[3], int which)
{
    bool tried = false;
    for (int slope = 1; slope <= 6 && !tried; slope++) {
        char expr[512];
        snprintf(expr, sizeof expr,
                 "max(0.05 - %d * (x - %.17g), 0.05 - ((x - %.17g) + (y - %.17g) + (z - %.17g))^2)",
                 slope, d[0], d[0], d[1], d[2]);
        pf_surface s = {expr, NULL, 0, NULL, 0};
        ism_tape *t = pf_compile(&s);
        ism_sampler smp = {.tape = t, .ws = ism_eval_ws_new(t)};
        ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
        cr_assert(smp.ws && jet);
        ism_corners k;
        if (tie_corners(&smp, d, &k)) {
            tried = true;
            ism_flatness fl = {.gradient_test = 1.0, .normal_cos = cos(26 * M_PI / 180),
                               .plane_frac = 0.1, .abs_tol = 1.0, .double_root_eps = 1e-6,
                               .double_root_iters = 8, .max_error = 1.0, /* any error passes */
                               .straddle_shift = 0};
            double lo[3] = {d[0], d[1], d[2]}, hi[3] = {d[0] + H, d[1] + H, d[2] + H};
            for (int a = 0; a < 3; a++)
                fl.box[a] = lo[a] - 1, fl.box[a + 3] = hi[a] + 1;
            bool blind;
            cr_expect_not(ism_plot_test(&smp, jet, &fl, lo, hi, &k, &blind),
                          "box %d slope %d: a node with ∇f = 0 at a corner passed without the "
                          "certificate", which, slope);
        }
        ism_ivjet_ws_free(jet);
        ism_eval_ws_free(smp.ws);
        ism_tape_free(t);
    }
    cr_expect(tried, "box %d: no spelling put ∇f = 0 beside a labelled gradient", which);
}

Test(plot_test_tie, zero_gradient_at_a_tie_needs_the_certificate)
{
    const double base[6] = {0, 0, 0, 1, 1, 1};
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, 9, w, box);
        tie_node(box, w); /* the box's low corner: the offset of that placement */
    }
}
