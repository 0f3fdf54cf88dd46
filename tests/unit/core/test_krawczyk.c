/* test_krawczyk.c — the Krawczyk test on ∇f (core/singular/krawczyk.h). Its plain-double
 * shortcut (a K sure to be neither inside X nor apart from it answers UNKNOWN without the
 * interval pass) must never change an answer: asked with K wanted (the full pass always
 * runs) and without, the answers agree on random boxes whose Hessian enclosures range from
 * tight round a regular matrix (UNIQUE or EMPTY) to wide round a singular one (UNKNOWN), and
 * on boxes placed right at the edge between answers. Closed forms: ∇(x² + y² + z²) = 2x,
 * H = 2I, has its one zero at 0 (a box round it: UNIQUE; a box beside it: EMPTY); on the
 * cross-cap's and the Whitney umbrella's axes (H singular there) no box round the axis can
 * be decided. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>

#include "core/eval/interval_jet.h"
#include "core/eval/interval_ops.h"
#include "core/expr/expr.h"
#include "core/singular/krawczyk.h"

/* xorshift64: reproducible without global state */
static double uniform(uint64_t *s, double lo, double hi)
{
    *s ^= *s << 13;
    *s ^= *s >> 7;
    *s ^= *s << 17;
    return lo + (hi - lo) * ((double)(*s >> 11) * 0x1p-53);
}

/* The answer asked both ways; they must agree. */
static int both_ways(const ism_interval x[3], const double c[3], const ism_interval gc[3],
                     const ism_interval h[6])
{
    ism_interval k[3];
    int full = ism_krawczyk(x, c, gc, h, k), quick = ism_krawczyk(x, c, gc, h, NULL);
    cr_assert_eq(quick, full, "answer %d without K, %d with it", quick, full);
    return full;
}

/* ∇f = 2x, H = 2I on the box c ± r: the enclosure of ∇f at c is the point 2c. */
static int sphere_box(double cx, double cy, double cz, double r)
{
    double c[3] = { cx, cy, cz };
    ism_interval x[3], gc[3], h[6];
    for (int k = 0; k < 3; k++) {
        x[k] = iv(c[k] - r, c[k] + r);
        gc[k] = iv(2.0 * c[k], 2.0 * c[k]);
    }
    for (int e = 0; e < 6; e++)
        h[e] = e == 0 || e == 3 || e == 5 ? iv(2.0, 2.0) : iv(0.0, 0.0);
    return both_ways(x, c, gc, h);
}

static void axis_cells(const char *expr, double z0);

Test(singular_krawczyk, closed_forms)
{
    cr_assert_eq(sphere_box(0.01, -0.02, 0.005, 0.1), ISM_KRAWCZYK_UNIQUE);
    cr_assert_eq(sphere_box(0.5, 0.0, 0.0, 0.1), ISM_KRAWCZYK_EMPTY);
    axis_cells("4*x^2*(x^2+y^2+z^2+z) + y^2*(y^2+z^2-1)", -0.5);
    axis_cells("x^2 - y^2*z", 0.5);
}

/* The four cells (h = 1/64 a side) touching the z axis at height z0 of a surface singular
 * all along it (H of rank ≤ 2 there: the cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1),
 * the Whitney umbrella x² − y²z), with ∇f at the centre and H over the cell enclosed by the
 * evaluators as the search does: no answer but UNKNOWN, both ways. */
static void axis_cells(const char *expr, double z0)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert_not_null(jw);
    double hw = 1.0 / 64;
    for (int q = 0; q < 4; q++) {
        double lo[3] = { q & 1 ? 0.0 : -hw, q & 2 ? 0.0 : -hw, z0 - hw / 2 };
        double c[3];
        ism_interval x[3], cx[3];
        for (int k = 0; k < 3; k++) {
            x[k] = iv(lo[k], lo[k] + hw);
            c[k] = 0.5 * x[k].lo + 0.5 * x[k].hi;
            cx[k] = iv(c[k], c[k]);
        }
        ism_ivgrad g;
        ism_ivjet j;
        ism_eval_interval_grad(t, jw, cx, NULL, NULL, &g);
        ism_eval_interval_jet(t, jw, x, NULL, NULL, &j);
        cr_assert_eq(both_ways(x, c, g.d, j.h), ISM_KRAWCZYK_UNKNOWN, "%s: cell %d", expr, q);
    }
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
}

/* A random symmetric matrix with eigenvalues of random sizes and signs (one possibly near 0),
 * widened entry by entry by a radius from 1e-12 to 10 times its scale. */
static void random_hessian(uint64_t *s, ism_interval h[6])
{
    for (int e = 0; e < 6; e++) {
        double mid = uniform(s, -2.0, 2.0), rad = pow(10.0, uniform(s, -12.0, 1.0));
        if (e == 0 || e == 3 || e == 5)
            mid += uniform(s, 0.0, 1.0) < 0.5 ? uniform(s, -3.0, 3.0) : 0.0;
        h[e] = iv(mid - rad, mid + rad);
    }
}

Test(singular_krawczyk, the_shortcut_never_changes_an_answer)
{
    uint64_t s = 0x9e3779b97f4a7c15ull;
    size_t seen[3] = { 0 };
    for (int n = 0; n < 200000; n++) {
        double c[3], r = pow(10.0, uniform(&s, -6.0, 0.0));
        ism_interval x[3], gc[3], h[6];
        random_hessian(&s, h);
        for (int k = 0; k < 3; k++) {
            c[k] = uniform(&s, -1.0, 1.0);
            double w = r * uniform(&s, 0.5, 1.5);
            x[k] = iv(c[k] - w, c[k] + w);
            /* ∇f at c: near the Hessian's Newton step back to a zero at distance ~ r · t */
            double g = uniform(&s, -1.0, 1.0) * r * pow(10.0, uniform(&s, -3.0, 2.0));
            double gr = pow(10.0, uniform(&s, -16.0, -2.0)) * r;
            gc[k] = iv(g - gr, g + gr);
        }
        seen[both_ways(x, c, gc, h)]++;
    }
    /* the cases span every answer, so the agreement is tested on each */
    cr_assert_gt(seen[ISM_KRAWCZYK_UNKNOWN], 1000);
    cr_assert_gt(seen[ISM_KRAWCZYK_UNIQUE], 1000);
    cr_assert_gt(seen[ISM_KRAWCZYK_EMPTY], 1000);
}

/* At the edges between answers, on H = lam I ± lam f on the diagonal (Y = I / lam): row i of K
 * is a_i ± f r with a_i = c_i − g_i / lam, X_i = c_i ± r. "Inside" needs f < 1 and
 * |a_i − c_i| < (1 − f) r: f is put below 1 by 1e-12 to 1e-6 with a_i that close to c_i;
 * "apart" needs |a_i − c_i| > (1 + f) r: a_i is put that far off, give or take 1e-12 to 1e-6
 * of it. Each answer must come out the same both ways, and each edge must give both of its
 * answers. */
static double tiny(uint64_t *s) { return pow(10.0, uniform(s, -12.0, -6.0)); }

Test(singular_krawczyk, boxes_at_the_edge_between_answers)
{
    uint64_t s = 12345;
    size_t seen[2][3] = { { 0 } };
    for (int n = 0; n < 100000; n++) {
        int apart = n & 1;
        double c[3] = { uniform(&s, -1, 1), uniform(&s, -1, 1), uniform(&s, -1, 1) };
        double r = pow(10.0, uniform(&s, -6.0, 0.0)), lam = uniform(&s, 0.5, 4.0);
        double f = apart ? uniform(&s, 0.5, 2.0) : 1.0 - tiny(&s);
        ism_interval x[3], gc[3], h[6];
        for (int e = 0; e < 6; e++)
            h[e] = e == 0 || e == 3 || e == 5 ? iv(lam - lam * f, lam + lam * f) : iv(0.0, 0.0);
        for (int k = 0; k < 3; k++) {
            x[k] = iv(c[k] - r, c[k] + r);
            double side = uniform(&s, 0, 1) < 0.5 ? -1.0 : 1.0;
            double off = apart ? (1.0 + f) * r * (1.0 + side * tiny(&s))
                               : (1.0 - f) * r * uniform(&s, -1.5, 1.5);
            double g = -lam * off * (apart ? side : 1.0);
            gc[k] = iv(g, g);
        }
        seen[apart][both_ways(x, c, gc, h)]++;
    }
    cr_assert_gt(seen[0][ISM_KRAWCZYK_UNIQUE], 100);
    cr_assert_gt(seen[0][ISM_KRAWCZYK_UNKNOWN], 100);
    cr_assert_gt(seen[1][ISM_KRAWCZYK_EMPTY], 100);
    cr_assert_gt(seen[1][ISM_KRAWCZYK_UNKNOWN], 100);
}
