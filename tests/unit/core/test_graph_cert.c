/* test_graph_cert.c — ism_graph_certified (graph_cert.h): f = 0 proven one graph over a box.
 * Closed-form boxes in the three placements (tests/unit/placements.h: the box as written,
 * moved by PF_OFF and by PF_IRR of a 1/64 cell): two where f = 0 is one graph that the
 * midpoint direction over the whole box's enclosure refused (a slope interval across 0
 * beside a clear one; a sphere cap whose box reaches past the centre) and the proof now
 * takes (and the cap across a kink), and two sheets (smooth and creased), a fold, a small
 * closed piece and two solids' union it must refuse. The premise of each case is checked by
 * sampling, independently of the code under test: a proven box's sampled surface normals lie
 * within 89° of one direction (an axis or their mean), a refused one shows a line along an
 * axis meeting f = 0 twice. The mutations each test catches: graph32's notes. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include "poly_fixture.h"
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/graph_cert.h"
#include "tests/unit/placements.h"

typedef struct gc_case {
    const char *expr;
    double lo[3], hi[3];
    bool graph; /* the truth, checked by sampling below */
} gc_case;

/* The placements' shifts of a box, in units of its own side (PF_IRR: of a 1/64 cell). */
static void placed(const gc_case *c, int p, double lo[3], double hi[3])
{
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X / 64, PF_IRR_Y / 64, PF_IRR_Z / 64}};
    for (int a = 0; a < 3; a++) {
        double side = c->hi[a] - c->lo[a];
        lo[a] = c->lo[a] + shift[p][a] * side;
        hi[a] = c->hi[a] + shift[p][a] * side;
    }
}

#define LINES 24   /* sampled lines per axis direction: LINES² of them */
#define STEPS 400  /* samples along each */

/* The most sign changes of f on any sampled line of the box parallel to axis a. */
static int most_crossings(const ism_tape *t, ism_eval_ws *ws, const double lo[3],
                          const double hi[3], int a)
{
    int b = (a + 1) % 3, c = (a + 2) % 3, most = 0;
    for (int i = 0; i < LINES; i++)
        for (int j = 0; j < LINES; j++) {
            double p[3];
            p[b] = lo[b] + (i + 0.5) / LINES * (hi[b] - lo[b]);
            p[c] = lo[c] + (j + 0.5) / LINES * (hi[c] - lo[c]);
            int n = 0;
            double last = 0;
            for (int s = 0; s <= STEPS; s++) {
                p[a] = lo[a] + (double)s / STEPS * (hi[a] - lo[a]);
                double v = ism_eval_point(t, ws, p[0], p[1], p[2]);
                if (s > 0 && (v > 0) != (last > 0))
                    n++;
                last = v;
            }
            most = n > most ? n : most;
        }
    return most;
}

/* Whether the unit normals at sampled zeros of f in the box (sign changes between grid
 * neighbours along x, y and z, taken at the nearer sample) all lie within 89° of one of the
 * candidate directions: the axes, their negatives and the mean normal. A plain check of the
 * premise, not the proof's own search: used only where the truth is "one graph". */
static bool normals_one_side(const ism_tape *t, ism_eval_ws *ws, const double lo[3],
                             const double hi[3])
{
    enum { N = 40 };
    static double nrm[3 * (N + 1) * (N + 1) * (N + 1)][3];
    size_t m = 0;
    double mean[3] = {0, 0, 0};
    for (int i = 0; i <= N; i++)
        for (int j = 0; j <= N; j++)
            for (int k = 0; k <= N; k++) {
                int at[3] = {i, j, k};
                double p[3], g[3];
                for (int a = 0; a < 3; a++)
                    p[a] = lo[a] + (double)at[a] / N * (hi[a] - lo[a]);
                double v = ism_eval_gradient(t, ws, p[0], p[1], p[2], g);
                for (int a = 0; a < 3; a++) {
                    if (at[a] == N)
                        continue;
                    double q[3] = {p[0], p[1], p[2]};
                    q[a] = lo[a] + (double)(at[a] + 1) / N * (hi[a] - lo[a]);
                    double w = ism_eval_point(t, ws, q[0], q[1], q[2]);
                    if ((v > 0) == (w > 0))
                        continue;
                    double len = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                    cr_assert_gt(len, 0, "a zero with no normal in a one-graph case");
                    for (int b = 0; b < 3; b++) {
                        nrm[m][b] = g[b] / len;
                        mean[b] += nrm[m][b];
                    }
                    m++;
                }
            }
    cr_assert_gt(m, 0, "the case's box holds some of the surface");
    double cand[7][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
    for (int b = 0; b < 3; b++)
        cand[6][b] = mean[b];
    for (int c = 0; c < 7; c++) {
        double len = sqrt(cand[c][0] * cand[c][0] + cand[c][1] * cand[c][1] +
                          cand[c][2] * cand[c][2]);
        size_t ok = 0;
        while (ok < m && (nrm[ok][0] * cand[c][0] + nrm[ok][1] * cand[c][1] +
                          nrm[ok][2] * cand[c][2]) > cos(89 * M_PI / 180) * len)
            ok++;
        if (ok == m)
            return true;
    }
    return false;
}

/* Whether the sampled box shows what no graph along an axis can hold: a line along an axis
 * meeting f = 0 twice (the refused cases' premise: their surfaces turn back or repeat along
 * every direction, by construction). */
static bool twice_on_a_line(const ism_tape *t, ism_eval_ws *ws, const double lo[3],
                            const double hi[3])
{
    for (int a = 0; a < 3; a++)
        if (most_crossings(t, ws, lo, hi, a) >= 2)
            return true;
    return false;
}

static bool certified(const ism_tape *t, const double lo[3], const double hi[3])
{
    ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
    uint64_t intervals = 0;
    bool r = ism_graph_certified(t, jet, lo, hi, &intervals, NULL);
    cr_assert_gt(intervals, 0, "the proof counts its evaluations");
    ism_ivjet_ws_free(jet);
    return r;
}

/* The old verdict: the whole box's enclosure of ∇f along the midpoint of its own enclosure
 * (ism_graph_from_enclosure), for a tape with no kink over the box. */
static bool midpoint_verdict(const ism_tape *t, const double lo[3], const double hi[3])
{
    ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
    ism_interval box[3] = {{lo[0], hi[0]}, {lo[1], hi[1]}, {lo[2], hi[2]}};
    ism_ivgrad g;
    cr_assert_eq(ism_eval_interval_grad(t, jet, box, NULL, NULL, &g), 0);
    ism_ivjet_ws_free(jet);
    return ism_graph_from_enclosure(&g);
}

static void check_case(const gc_case *c, bool old_refused)
{
    pf_surface sf = {c->expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&sf);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    for (int p = 0; p < 3; p++) {
        double lo[3], hi[3];
        placed(c, p, lo, hi);
        if (c->graph)
            cr_assert(normals_one_side(t, ws, lo, hi), "%s, placement %d: premise", c->expr,
                      p);
        if (old_refused)
            cr_assert(!midpoint_verdict(t, lo, hi), "%s, placement %d: the old proof took it",
                      c->expr, p);
        cr_expect_eq(certified(t, lo, hi), c->graph, "%s, placement %d", c->expr, p);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* A case whose truth is "no graph": its premise sampled (twice_on_a_line, own placement),
 * then the proof's verdict in the three placements. */
static void check_refused(const gc_case *c)
{
    pf_surface sf = {c->expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&sf);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(twice_on_a_line(t, ws, c->lo, c->hi), "%s: premise", c->expr);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    check_case(c, false);
}

/* x = y − 1.5 y² over y in [0, 2]: a graph over the y-z plane (along x), ∂f/∂y = 3y − 1
 * ranges over [−1, 5], so the enclosure's midpoint direction (1, 2, 0) has slope 1 − 2 < 0
 * at its worst corner, while x itself clears it. */
Test(graph_cert, proves_a_graph_the_midpoint_direction_missed)
{
    gc_case c = {"x + 1.5*y^2 - y", {-4, 0, -0.5}, {4, 2, 0.5}, true};
    check_case(&c, true);
}

/* The unit sphere's cap x = √(1 − y² − z²) in a box reaching back to x = −0.2: ∂f/∂x = 2x
 * holds 0 over the box and so do the others, no direction clears the whole box's
 * enclosure; the box's back half is below 0 throughout and drops out, the front half's x
 * slope is at least 1. */
Test(graph_cert, proves_a_cap_whose_box_reaches_past_the_centre)
{
    gc_case c = {"x^2 + y^2 + z^2 - 1", {-0.2, -0.3, -0.3}, {1.2, 0.3, 0.3}, true};
    check_case(&c, true);
}

/* The cap again inside a second solid that keeps f's sign to the sphere's (max with a
 * cylinder below 0 over the box, above the sphere's least value there): a kink the box
 * allows, whose pieces cleared no direction together; the cylinder's piece drops out (its
 * value decides f's sign to the sphere's), the halves prove the sphere's. */
Test(graph_cert, proves_a_cap_across_a_kink)
{
    gc_case c = {"max(x^2 + y^2 + z^2 - 1, y^2 + z^2 - 1.1)", {-0.2, -0.3, -0.3},
                 {1.2, 0.3, 0.3}, true};
    check_case(&c, false);
}

/* Two parallel sheets w = 0.3 and w = −0.15 (w = z + x/10 + y/10: the top max depends on x,
 * y and z, as its pieces' fast path asks) as the max of two planes, w − 0.3 and −2w − 0.3:
 * each half of the box is one plane's (the other below 0 there), each a graph on its own,
 * along opposite directions (gradients g and −2g: their midpoints' sum is no 0 that would
 * stop the search before it looks, and no direction sees both once). */
Test(graph_cert, refuses_two_creased_sheets)
{
    gc_case c = {"max(z + 0.1*x + 0.1*y - 0.3, -2*z - 0.2*x - 0.2*y - 0.3)",
                 {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, false};
    check_refused(&c);
}

/* Two sheets z = ±0.1. */
Test(graph_cert, refuses_two_sheets)
{
    gc_case c = {"z^2 - 0.01", {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, false};
    check_refused(&c);
}

/* A fold: a cylinder round the y axis whose arc in the box turns through more than 180°
 * (x below 0.1 on a radius of 0.3: 219°), so no direction sees it once. */
Test(graph_cert, refuses_a_fold)
{
    gc_case c = {"x^2 + z^2 - 0.09", {-0.5, -0.3, -0.5}, {0.1, 0.3, 0.5}, false};
    check_refused(&c);
}

/* A small closed piece: a ball of radius 0.05 inside the box, off its centre. */
Test(graph_cert, refuses_a_small_closed_piece)
{
    gc_case c = {"(x - 0.1)^2 + (y + 0.05)^2 + (z - 0.07)^2 - 0.0025",
                 {-0.5, -0.5, -0.5}, {0.5, 0.5, 0.5}, false};
    check_refused(&c);
}

/* Two solids crossing at a crease that turns back: max of two balls whose union's surface
 * inside the box holds both caps' backs (a line along x meets it twice). */
Test(graph_cert, refuses_a_crossing_that_folds)
{
    gc_case c = {"min((x - 0.3)^2 + y^2 + z^2 - 0.04, (x + 0.3)^2 + y^2 + z^2 - 0.04)",
                 {-0.6, -0.25, -0.25}, {0.6, 0.25, 0.25}, false};
    check_refused(&c);
}

/* f = x³/3 + δx − c over x in [0, 1] (its zero at x = 0.2): a graph along x (premise
 * sampled), ∂f/∂x = x² + δ in [δ, 1 + δ] with the other partials 0, so ∇f · d clears 0 along
 * d = x by δ of the largest term, 1 + δ (on the halves holding the zero by δ of 0.25 + δ; the
 * far halves are above 0). graph_cert.c's margin, MIN_SLOPE_FRACTION = 1e-3 of that term
 * (against rounding), refuses δ = 1e-4, though the enclosure's lower slope is above 0, and
 * takes δ = 1e-2. Trusting the sign alone (no margin) certifies δ = 1e-4. */
static void check_margin(double delta, bool proved)
{
    char expr[128];
    snprintf(expr, sizeof expr, "x^3/3 + %.17g*x - %.17g", delta, 0.008 / 3 + 0.2 * delta);
    gc_case c = {expr, {0, -0.5, -0.5}, {1, 0.5, 0.5}, true};
    pf_surface sf = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&sf);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
    for (int p = 0; p < 3; p++) {
        double lo[3], hi[3];
        placed(&c, p, lo, hi);
        cr_assert(normals_one_side(t, ws, lo, hi), "δ %g, placement %d: premise", delta, p);
        ism_interval box[3] = {{lo[0], hi[0]}, {lo[1], hi[1]}, {lo[2], hi[2]}};
        ism_ivgrad g;
        cr_assert_eq(ism_eval_interval_grad(t, jet, box, NULL, NULL, &g), 0);
        cr_assert_gt(g.d[0].lo, 0, "δ %g, placement %d: the slope along x clears 0", delta, p);
        cr_assert_lt(g.d[0].lo, 0.02 * g.d[0].hi, "δ %g, placement %d: by little", delta, p);
        cr_expect_eq(certified(t, lo, hi), proved, "δ %g, placement %d", delta, p);
    }
    ism_ivjet_ws_free(jet);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(graph_cert, refuses_a_slope_under_the_margin)
{
    check_margin(1e-4, false);
}

Test(graph_cert, proves_a_slope_over_the_margin)
{
    check_margin(1e-2, true);
}
