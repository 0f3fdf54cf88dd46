/* test_edge_roots.c — the double-root search on a lattice segment (edge_roots.h) against
 * closed forms: f = (x − c)² − h along a segment of x, c inside it. h > 0: two roots,
 * c ∓ √h, and the search answers 2 with its split point between them; h = 0: a tangent
 * root at c, answer 1 within √eps of c (|f| < eps there); h < 0: no root, answer 0 — since
 * the search asks an interval over what is left of its bracket, in fewer gradients than its
 * 25 halvings. The same f written out (x² − 2cx + c² − h: intervals wider by ~2c × the
 * bracket) gives the same answers, early too unless h is below what 25 halvings make the
 * interval see (h = −1e-8: all 25, the answer unchanged). Each in three placements: the
 * segment [0, 1], moved by 1e-3, and by (√2 − 1) / 2, c with it. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "core/octree/edge_roots.h"
#include "poly_fixture.h"

#define ITERS 25     /* the default double_root_iters (tolerances.h) */
#define EPS 1e-9     /* the default double_root_eps */

typedef struct outcome {
    int found;
    double t;
    uint64_t gradients;
} outcome;

static outcome search(const char *expr, double c, double h, double shift)
{
    ism_param prm[2] = {{"c", c + shift}, {"h", h}};
    pf_surface s = {expr, prm, 2, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_sampler smp;
    memset(&smp, 0, sizeof smp);
    smp.tape = t;
    smp.ws = ism_eval_ws_new(t);
    cr_assert(smp.ws);
    double a[3] = {shift, 0.25, -0.5}, b[3] = {1 + shift, 0.25, -0.5}, g[3];
    double fa = ism_eval_gradient(t, smp.ws, a[0], a[1], a[2], g);
    double fb = ism_eval_gradient(t, smp.ws, b[0], b[1], b[2], g);
    cr_assert(fa > 0 && fb > 0, "%s: the ends must share a sign (%g, %g)", expr, fa, fb);
    ism_root_params rp = {0.9, EPS, ITERS, false};
    outcome o = {0, -1, 0};
    o.found = ism_double_root_search(&smp, &rp, a, b, fa, fb, &o.t);
    o.gradients = smp.n_gradient;
    ism_eval_ws_free(smp.ws);
    ism_tape_free(t);
    return o;
}

Test(edge_roots, double_root_search_against_closed_forms)
{
    static const char *const forms[] = {"(x - c)^2 - h", "x^2 - 2*c*x + c^2 - h"};
    const double shifts[] = {0, 1e-3, 0.5 * (sqrt(2.0) - 1)};
    const double c = 0.37;
    for (int f = 0; f < 2; f++)
        for (int k = 0; k < 3; k++) {
            const char *e = forms[f];
            /* two roots, c -+ 0.1: the split point between them */
            outcome two = search(e, c, 0.01, shifts[k]);
            cr_expect_eq(two.found, 2, "%s shift %g: %d", e, shifts[k], two.found);
            cr_expect(two.t > c - 0.1 && two.t < c + 0.1, "%s: split at %g", e, two.t);
            /* a tangent root at c */
            outcome one = search(e, c, 0, shifts[k]);
            cr_expect_eq(one.found, 1, "%s shift %g: %d", e, shifts[k], one.found);
            cr_expect(fabs(one.t - c) <= 1.01 * sqrt(EPS), "%s: tangent at %g", e, one.t);
            /* no root: f >= 1e-8 > eps (the search's own verdict too), and told early */
            const double folds[] = {-1e-8, -1e-3, -0.05};
            for (int m = 0; m < 3; m++) {
                outcome none = search(e, c, folds[m], shifts[k]);
                cr_expect_eq(none.found, 0, "%s shift %g h %g: %d", e, shifts[k], folds[m],
                             none.found);
                if (f == 0 || m > 0)
                    cr_expect_lt(none.gradients, ITERS, "%s shift %g h %g: %llu gradients", e,
                                 shifts[k], folds[m], (unsigned long long)none.gradients);
            }
        }
}
