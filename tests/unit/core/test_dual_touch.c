/* test_dual_touch.c — dual_classify.c's touch_empty (Taylor's theorem from one corner c of a
 * node whose corners are all >= 0) on quadratics whose least value over the node is known in
 * closed form. In the signed coordinates of c, w_a = s_a (x − c)_a >= 0 over the node
 * (s_a = +1 when c is on the node's low side along a), every f here is
 *   f = e + Σ_a g_a w_a + Σ_a w_a² + 2 Σ_{a<b} k_ab w_a w_b,
 * so its Hessian in x has H_ab = 2 s_a s_b k_ab: which bound of H_ab touch_empty must take
 * (s_a s_b > 0 or not) and which side of the node c lies on differ from corner to corner,
 * and each case is run from each of the eight corners.
 * - touching: e = 0, g_a = G > 0, one pair with k = −MU, the other two +NU. f >= 0 on the
 *   node (w0² + w1² − 2 MU w0 w1 >= (1 − MU)(w0² + w1²), the rest >= 0), 0 only at c: empty.
 *   The mean-value form does not show it (∂f/∂w_a dips to G − 2 MU side < 0 along the open
 *   pair) and no enclosure can (f(c) = 0), so touch_empty decides: its D_a = 2 − 4 MU >= 0
 *   with the right bounds, 2 − 4 NU < 0 with a wrong one of any positive pair. The open pair
 *   is each of the three pairs in turn, so every (a, b) is a positive pair somewhere.
 * - near: e > 0 tiny, g_a = −DIP along one axis a* (each in turn), G along the others, every
 *   k = +NU. The least of f over the node is e − DIP² / 4 (at w_a* = DIP / 2, the other
 *   terms >= 0). With e = 1.01 DIP² / 4 the node is empty (touch_empty: f(c) plus the
 *   parabola's vertex −G_a*² / 2 D_a*, D_a* = 2 with the right bounds, far below 0 with any
 *   wrong one); with e = 0.5 DIP² / 4, f < 0 at that point (checked on the tape) and the
 *   node must not be called empty: a gradient at c (G_a* = −DIP) taken from the wrong side of
 *   the node along any axis gains 2 NU side or 2 side and would prove it.
 * Three placements (tests/unit/placements.h); the node and f move with the box. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include "core/eval/eval.h"
#include "core/octree/dual_classify.h"
#include "core/octree/grid.h"
#include "dual_rig.h"
#include "poly_fixture.h"

#define DEPTH 10
#define LEVEL 4 /* the node: 3/16 across, above depth.max (no face_cap) */
#define MU 0.25 /* the open pair's coupling: D_a = 2 − 4 MU = 1 >= 0 */
#define NU 1.0  /* the other couplings: a wrong bound of H_ab gives D_a <= 2 − 4 NU < 0 */
#define G 0.1   /* g_a, in node sides: below 2 MU, so ∂f/∂w_a changes sign in the node */
#define DIP 0.1 /* −g_a*, in node sides: the dip at DIP / 2 side lies inside the node */

/* f's text from corner c: params cx, cy, cz (c's point), f0 (e), g0, g1, g2 and kxy, kxz, kyz
 * (the couplings of pairs xy, xz, yz). */
static void f_text(int c, char *out, size_t len)
{
    char w[3][16]; /* w_a */
    const char *x[3] = {"x", "y", "z"}, *cx[3] = {"cx", "cy", "cz"};
    for (int a = 0; a < 3; a++) /* s_a = −1 on the node's upper side along a */
        snprintf(w[a], sizeof w[a], "(%s - %s)", c >> a & 1 ? cx[a] : x[a],
                 c >> a & 1 ? x[a] : cx[a]);
    snprintf(out, len,
             "f0 + g0*%s + g1*%s + g2*%s + %s^2 + %s^2 + %s^2 + 2*kxy*%s*%s + 2*kxz*%s*%s + "
             "2*kyz*%s*%s",
             w[0], w[1], w[2], w[0], w[1], w[2], w[0], w[1], w[0], w[2], w[1], w[2]);
}

/* The kind of the level-LEVEL node at (5, 9, 6) in placement i, f from its corner c (f_text:
 * e in sides², g in sides, k as is; a side: the node's least); when dip > 0, asserts first
 * that f < 0 at dip sides from c along axis a. */
static int kind_of(int i, int c, double e, const double g[3], const double k[3], int a,
                   double dip)
{
    double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, box[6], lo[3], side = INFINITY;
    ism_grid grid = pf_sweep_grid(base, DEPTH, i - 1, box);
    int32_t step = ism_grid_cell_steps(&grid, LEVEL), q[3] = {5 * step, 9 * step, 6 * step};
    for (int b = 0; b < 3; b++) {
        lo[b] = ism_grid_coord(&grid, b, q[b] + (c >> b & 1) * step); /* c's point */
        side = fmin(side, ism_grid_coord(&grid, b, q[b] + step) - ism_grid_coord(&grid, b, q[b]));
    }
    char text[400];
    f_text(c, text, sizeof text);
    ism_param p[10] = {{"cx", lo[0]},        {"cy", lo[1]},        {"cz", lo[2]},
                       {"f0", e * side * side}, {"g0", g[0] * side}, {"g1", g[1] * side},
                       {"g2", g[2] * side},  {"kxy", k[0]},        {"kxz", k[1]},
                       {"kyz", k[2]}};
    ism_tape *t = pf_compile(&(pf_surface){text, p, 10, NULL, 0});
    dual_rig r;
    dual_rig_set_up(&r, t, i, DEPTH, 0.0141);
    dnode n;
    corner_view v;
    dual_rig_node(&r, q, LEVEL, &n, &v);
    for (int b = 0; b < 8; b++)
        cr_assert(b == c && e == 0 ? n.f[b] == 0 : n.f[b] > 0,
                  "placement %d corner %d: f %g at corner %d", i, c, n.f[b], b);
    if (dip > 0) {
        double at[3], grad[3];
        for (int b = 0; b < 3; b++)
            at[b] = lo[b] + (b == a) * (c >> a & 1 ? -1 : 1) * dip * side;
        double f = ism_eval_gradient(r.w.s.tape, r.w.s.ws, at[0], at[1], at[2], grad);
        cr_assert(f < 0, "placement %d corner %d: f %g at the dip", i, c, f);
    }
    int kind = ism_dual_classify(&r.d, &r.w, &n, &v);
    dual_rig_tear_down(&r);
    ism_tape_free(t);
    return kind;
}

Test(dual_touch, touching_corner_proves_empty)
{
    const double g[3] = {G, G, G};
    for (int i = pf_first_box(); i < 3; i++)
        for (int open = 0; open < 3; open++) {
            double k[3] = {NU, NU, NU};
            k[open] = -MU;
            for (int c = 0; c < 8; c++)
                cr_assert_eq(kind_of(i, c, 0, g, k, 0, 0), DN_EMPTY,
                             "placement %d, pair %d open, corner %d: not shown empty", i, open,
                             c);
        }
}

Test(dual_touch, near_corner_empty_or_not)
{
    const double k[3] = {NU, NU, NU};
    for (int i = pf_first_box(); i < 3; i++)
        for (int a = 0; a < 3; a++) {
            double g[3] = {G, G, G};
            g[a] = -DIP;
            for (int c = 0; c < 8; c++) {
                cr_assert_eq(kind_of(i, c, 1.01 * DIP * DIP / 4, g, k, a, 0), DN_EMPTY,
                             "placement %d, dip along %d, corner %d: not shown empty", i, a, c);
                cr_assert_neq(kind_of(i, c, 0.5 * DIP * DIP / 4, g, k, a, DIP / 2), DN_EMPTY,
                              "placement %d, dip along %d, corner %d: f < 0 in it, called "
                              "empty", i, a, c);
            }
        }
}
