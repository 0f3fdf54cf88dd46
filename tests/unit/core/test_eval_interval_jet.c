/* test_eval_interval_jet.c — the interval jet's promises: over random boxes (and degenerate
 * ones) its enclosures of f, ∇f and the Hessian hold the point jets of ism_eval_hessian at
 * every sampled point, for every example surface (Kummer's included) and expressions using
 * every operation; derivatives are the whole line only where f is not differentiable in the
 * box; forced branches give the branch's derivatives; affine gradients come out exact. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>

#include "core/eval/interval_jet.h"
#include "core/expr/tape.h"
#include "test_eval_surfaces.h"

enum { PTS = 48 };

/* A random box inside `within`, each side 2^-U(0, 14) of the whole, or (one in eight) a
 * single point. */
static void random_box(test_rng *rng, const double *within, ism_interval b[3])
{
    int degenerate = test_uniform(rng, 0.0, 1.0) < 0.125;
    for (int k = 0; k < 3; k++) {
        double lo = within[k], hi = within[k + 3];
        double w = degenerate ? 0.0 : (hi - lo) * exp2(-test_uniform(rng, 0.0, 14.0));
        double a = test_uniform(rng, lo, hi - w);
        b[k] = (ism_interval){ a, a + w };
    }
}

/* The double-precision point jet carries its own rounding errors; the enclosure holds the
 * exact jet. Allow a few hundred ulps of the bounds' magnitude (far below the widths of
 * non-degenerate boxes). */
static bool holds(ism_interval r, double v)
{
    if (!isfinite(v))
        return true;
    double tol = 1e-13 * (1.0 + fmax(fabs(isfinite(r.lo) ? r.lo : 0), fabs(isfinite(r.hi) ? r.hi : 0)));
    return r.lo - tol <= v && v <= r.hi + tol;
}

static bool sane(ism_interval r)
{
    return !isnan(r.lo) && !isnan(r.hi) && r.lo <= r.hi;
}

/* Checks nboxes random boxes of `within`; returns the points checked. */
static size_t check_jets(const char *name, const ism_tape *t, const double *within,
                         size_t nboxes, uint64_t seed)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert(ws && jw);
    test_rng rng = { seed };
    size_t checked = 0;
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3];
        random_box(&rng, within, b);
        ism_ivjet J;
        ism_ivgrad G;
        size_t k1 = ism_eval_interval_jet(t, jw, b, NULL, NULL, &J);
        size_t k2 = ism_eval_interval_grad(t, jw, b, NULL, NULL, &G);
        cr_assert_eq(k1, k2, "%s: kink counts differ", name);
        cr_assert(sane(J.v), "%s: value [%g, %g]", name, J.v.lo, J.v.hi);
        for (int k = 0; k < 3; k++) {
            cr_assert(sane(J.d[k]) && sane(J.h[k]) && sane(J.h[k + 3]), "%s: NaN bound", name);
            cr_assert(G.d[k].lo == J.d[k].lo && G.d[k].hi == J.d[k].hi,
                      "%s: gradient of the two variants differs", name);
        }
        cr_assert(G.v.lo == J.v.lo && G.v.hi == J.v.hi, "%s: value of the variants", name);
        for (int i = 0; i < PTS; i++) {
            double p[3];
            for (int k = 0; k < 3; k++)
                p[k] = i < 8 ? ((i >> k) & 1 ? b[k].hi : b[k].lo)
                             : test_uniform(&rng, b[k].lo, b[k].hi);
            double g[3], h[6];
            double f = ism_eval_hessian(t, ws, p[0], p[1], p[2], g, h);
            if (!isfinite(f))
                continue;
            checked++;
            cr_assert(holds(J.v, f), "%s: f(%.17g, %.17g, %.17g) = %.17g outside [%.17g, %.17g]",
                      name, p[0], p[1], p[2], f, J.v.lo, J.v.hi);
            for (int k = 0; k < 3; k++)
                cr_assert(holds(J.d[k], g[k]),
                          "%s at (%.17g, %.17g, %.17g): df/d%c = %.17g outside [%.17g, %.17g]",
                          name, p[0], p[1], p[2], 'x' + k, g[k], J.d[k].lo, J.d[k].hi);
            for (int e = 0; e < 6; e++)
                cr_assert(holds(J.h[e], h[e]),
                          "%s at (%.17g, %.17g, %.17g): hess[%d] = %.17g outside [%.17g, %.17g]",
                          name, p[0], p[1], p[2], e, h[e], J.h[e].lo, J.h[e].hi);
        }
    }
    ism_ivjet_ws_free(jw);
    ism_eval_ws_free(ws);
    return checked;
}

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

Test(eval_interval_jet, encloses_point_jets_of_example_surfaces)
{
    size_t nboxes = test_scaled(600);
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        size_t n = check_jets(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, nboxes, 300 + s);
        cr_expect_geq(n, nboxes * PTS * 9 / 10, "%s: too few finite samples",
                      TEST_SURFACES[s].name);
        ism_tape_free(t);
    }
}

/* Every operation, including domain edges, poles and kinks. */
static const char *const OPS_EXPRS[] = {
    "x^2 + 2*y^2 - 3*z^2 + 0.5*x*z", "x^2 + z^2 - y^3", "x*y*z - x/(1 + y^2)",
    "sin(3*x)*cos(2*y) + sin(y*z)", "exp(x/2 - y^2) * z", "exp(-x^2 - y^2) - 0.5",
    "(x + y) / (z^2 + 1) - 1/(x + 5)", "(x - y) / (x + y + 0.1)", "1 / x + y / (z - 0.5)",
    "3/(x + 4) - 2*y/(z + 3)", "tan(x + y)", "tan(x/2) + y*z", "log(x^2 + y^2 + 1) - z^3",
    "log(x) * y", "sqrt(x) + sqrt(y - z)", "sqrt(x + 3) * (y - z)^2",
    "pow(abs(x), 0.7) - pow(y, 2.5)", "pow(x, 1.5) * z", "pow(x, -1.5)",
    "pow(x^2 + 0.1, y)", "x^5 - 3*x^3*y^2 + y^4*z - z^7/5", "x^-3 + y^-2",
    "abs(x) - abs(y*z)", "min(x, y, z) * max(x, -y)", "max(x^2 - 1, -z) / (2 - sin(y))",
    "min(x, 0.25) + max(y*z, -0.5)", "(x^2 + y^2 + z^2 - 0.5)^2", "-x^2 - y^4 + 7",
    "((x-1)^2 + y^2 + z^2 - 1)*((x+1)^2 + y^2 + z^2 - 1)",
    "sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x)",
};

Test(eval_interval_jet, encloses_point_jets_of_every_operation)
{
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    size_t nboxes = test_scaled(300);
    for (size_t i = 0; i < sizeof OPS_EXPRS / sizeof OPS_EXPRS[0]; i++) {
        ism_tape *t = compile(OPS_EXPRS[i]);
        check_jets(OPS_EXPRS[i], t, within, nboxes, 17 + i);
        ism_tape_free(t);
    }
}

static ism_ivjet jet_over(const char *src, double x0, double x1, double y0, double y1,
                          double z0, double z1, const uint8_t *force, size_t *kinks)
{
    ism_tape *t = compile(src);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    ism_interval b[3] = { { x0, x1 }, { y0, y1 }, { z0, z1 } };
    ism_ivjet J;
    size_t n = ism_eval_interval_jet(t, jw, b, force, NULL, &J);
    if (kinks)
        *kinks = n;
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
    return J;
}

/* r holds v and is at most a few ulps wide. */
static bool near(ism_interval r, double v)
{
    return r.lo <= v && v <= r.hi && r.hi - r.lo <= 1e-15 * (1.0 + fabs(v));
}

static bool whole(ism_interval r) { return r.lo == -INFINITY && r.hi == INFINITY; }
static bool bounded(ism_interval r) { return isfinite(r.lo) && isfinite(r.hi); }

/* sqrt, log and real powers: whole derivatives exactly where the box reaches the clipping
 * edge and the derivative is unbounded there; zero on the clipped side; finite inside. */
Test(eval_interval_jet, domain_edges)
{
    ism_ivjet J = jet_over("sqrt(x)", -1, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(whole(J.d[0]) && whole(J.h[0]));
    cr_expect(J.d[1].lo == 0 && J.d[1].hi == 0, "no dependence on y");
    J = jet_over("sqrt(x)", 0.25, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(J.d[0].lo <= 0.5 && J.d[0].hi >= 1.0 && J.d[0].hi < 1.0 + 1e-12, "1/(2 sqrt x)");
    J = jet_over("sqrt(x) + log(y)", -2, -1, -3, -2, 0, 0, NULL, NULL);
    cr_expect(J.d[0].lo == 0 && J.d[0].hi == 0 && J.d[1].lo == 0 && J.d[1].hi == 0);
    J = jet_over("log(x)", 0, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(whole(J.d[0]), "log at the edge 0");
    J = jet_over("pow(x, 2.5)", -1, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(bounded(J.d[0]) && bounded(J.h[0]), "C2 at 0 for c > 2");
    cr_expect(J.d[0].lo <= 0 && J.d[0].hi >= 2.5 && J.h[0].hi >= 3.75);
    J = jet_over("pow(x, 1.5)", -1, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(bounded(J.d[0]) && whole(J.h[0]), "C1 only for 1 < c < 2");
    J = jet_over("pow(x, 0.5)", -1, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(whole(J.d[0]));
    J = jet_over("1/x", -1, 1, 0, 0, 0, 0, NULL, NULL);
    cr_expect(whole(J.v) && whole(J.d[0]) && whole(J.h[0]), "pole");
    J = jet_over("y/x", -1, 1, 1, 2, 0, 0, NULL, NULL);
    cr_expect(whole(J.d[1]), "quotient across a pole");
    J = jet_over("tan(x)", 1.5, 1.6, 0, 0, 0, 0, NULL, NULL);
    cr_expect(J.d[0].lo <= 1 && J.d[0].hi == INFINITY && whole(J.h[0]),
              "tan across pi/2: tan' >= 1 still holds");
}

/* min/max/abs: kinks counted and whole derivatives when both branches may be active; a
 * forced branch gives exactly that branch's derivatives; decided branches are no kink. */
Test(eval_interval_jet, kinks_and_forced_branches)
{
    size_t nk;
    ism_ivjet J = jet_over("max(x, 2*y)", -1, 1, -1, 1, 0, 0, NULL, &nk);
    cr_expect_eq(nk, 1);
    cr_expect(whole(J.d[0]) && whole(J.d[1]) && whole(J.h[0]));
    cr_expect(J.v.lo <= -1 && J.v.hi >= 2 && J.v.hi < 2 + 1e-12);
    /* find the max instruction: the only one that is a kink */
    ism_tape *t = compile("max(x, 2*y)");
    size_t len = ism_tape_length(t);
    uint8_t *kinks = calloc(len, 1), *force = calloc(len, 1);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    ism_interval b[3] = { { -1, 1 }, { -1, 1 }, { 0, 0 } };
    cr_assert_eq(ism_eval_interval_jet(t, jw, b, NULL, kinks, &J), 1);
    for (size_t i = 0; i < len; i++)
        force[i] = kinks[i] ? ISM_BRANCH_A : ISM_BRANCH_FREE;
    cr_assert_eq(ism_eval_interval_jet(t, jw, b, force, NULL, &J), 0);
    cr_expect(J.d[0].lo == 1 && J.d[0].hi == 1 && J.d[1].lo == 0 && J.d[1].hi == 0);
    for (size_t i = 0; i < len; i++)
        force[i] = kinks[i] ? ISM_BRANCH_B : ISM_BRANCH_FREE;
    ism_eval_interval_jet(t, jw, b, force, NULL, &J);
    cr_expect(J.d[0].lo == 0 && J.d[0].hi == 0 && near(J.d[1], 2.0));
    ism_ivjet_ws_free(jw);
    free(kinks);
    free(force);
    ism_tape_free(t);

    J = jet_over("max(x, 2*y)", 2.5, 3, -1, 1, 0, 0, NULL, &nk);
    cr_expect(nk == 0 && J.d[0].lo == 1 && J.d[0].hi == 1, "decided branch");
    J = jet_over("abs(x - y)", -1, 1, -1, 1, 0, 0, NULL, &nk);
    cr_expect(nk == 1 && whole(J.d[0]));
    J = jet_over("abs(x - y)", 2, 3, -1, 1, 0, 0, NULL, &nk);
    cr_expect(nk == 0 && near(J.d[0], 1.0) && near(J.d[1], -1.0));
    J = jet_over("abs(x - y)", -3, -2, -1, 1, 0, 0, NULL, &nk);
    cr_expect(nk == 0 && near(J.d[0], -1.0) && near(J.d[1], 1.0));
    J = jet_over("min(x, 0.5)", -1, 0.25, 0, 0, 0, 0, NULL, &nk);
    cr_expect(nk == 0 && J.d[0].lo == 1 && J.d[0].hi == 1);
}

/* A quadratic's gradient is affine in each variable once: the natural enclosure is the
 * exact range (up to rounding), i.e. the extremes over the box's corners; the Hessian is the
 * constant matrix of the closed form. */
Test(eval_interval_jet, affine_gradient_exact)
{
    ism_ivjet J = jet_over("x^2 + 2*y^2 - 3*z^2 + 0.5*x*z", 0.1, 0.3, -0.2, 0.4, 0.5, 0.7,
                           NULL, NULL);
    /* df/dx = 2x + 0.5z over the box: [0.2 + 0.25, 0.6 + 0.35] */
    cr_expect(fabs(J.d[0].lo - 0.45) < 1e-14 && fabs(J.d[0].hi - 0.95) < 1e-14);
    /* df/dy = 4y: [-0.8, 1.6]; df/dz = -6z + 0.5x: [-4.2 + 0.05, -3 + 0.15] */
    cr_expect(fabs(J.d[1].lo + 0.8) < 1e-14 && fabs(J.d[1].hi - 1.6) < 1e-14);
    cr_expect(fabs(J.d[2].lo + 4.15) < 1e-14 && fabs(J.d[2].hi + 2.85) < 1e-14);
    const double H[6] = { 2, 0, 0.5, 4, 0, -6 };
    for (int e = 0; e < 6; e++)
        cr_expect(J.h[e].lo <= H[e] && H[e] <= J.h[e].hi && J.h[e].hi - J.h[e].lo < 1e-13,
                  "hess[%d] = [%.17g, %.17g]", e, J.h[e].lo, J.h[e].hi);
}

/* On a degenerate box the enclosure is the point jet up to rounding: narrow, not just
 * correct (Krawczyk needs ∇f(c) as a tight interval). */
Test(eval_interval_jet, degenerate_box_is_tight)
{
    const test_surface *s = &TEST_SURFACES[5]; /* kummer-16-nodes */
    ism_tape *t = test_surface_compile(s);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    test_rng rng = { 4242 };
    for (int n = 0; n < 200; n++) {
        double p[3], g[3], h[6];
        for (int k = 0; k < 3; k++)
            p[k] = test_uniform(&rng, s->box[k], s->box[k + 3]);
        ism_interval b[3] = { { p[0], p[0] }, { p[1], p[1] }, { p[2], p[2] } };
        ism_ivjet J;
        ism_eval_interval_jet(t, jw, b, NULL, NULL, &J);
        ism_eval_hessian(t, ws, p[0], p[1], p[2], g, h);
        double scale = 1.0 + fabs(J.v.lo);
        for (int k = 0; k < 3; k++)
            scale += fabs(g[k]) + fabs(h[k]) + fabs(h[k + 3]);
        scale *= 1.0 + p[0] * p[0] + p[1] * p[1] + p[2] * p[2];
        cr_expect(J.v.hi - J.v.lo < 1e-12 * scale);
        for (int k = 0; k < 3; k++)
            cr_expect(J.d[k].hi - J.d[k].lo < 1e-12 * scale, "width %g", J.d[k].hi - J.d[k].lo);
        for (int e = 0; e < 6; e++)
            cr_expect(J.h[e].hi - J.h[e].lo < 1e-12 * scale);
    }
    ism_ivjet_ws_free(jw);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The compiler's free_of (core/expr/tape.h) from the expression's own variables. */
Test(eval_interval_jet, free_of_names_the_variables_a_value_lacks)
{
    ism_tape *t = compile("x^2 + 3*y - sin(z)*y");
    int whole = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        if (in->op == ISM_OP_SQUARE)
            cr_expect_eq(in->free_of, 6u, "x^2 lacks y and z");
        if (in->op == ISM_OP_SIN)
            cr_expect_eq(in->free_of, 3u, "sin(z) lacks x and y");
        if (in->op == ISM_OP_MUL_RC)
            cr_expect_eq(in->free_of, 5u, "3 y lacks x and z");
        whole += in->free_of == 0;
    }
    cr_expect_eq(t->code[t->len - 1].free_of, 0u, "f depends on all three");
    cr_expect(whole >= 1 && whole < (int)t->len);
    for (size_t i = 0; i < t->len; i++)
        cr_expect_eq(t->code[i].smooth, 1u, "a polynomial and sin: nothing kinks");
    ism_tape_free(t);
    t = compile("sqrt(x^2 + 1) * y + z^2");
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        if (in->op == ISM_OP_SQRT || in->op == ISM_OP_MUL_RR)
            cr_expect_eq(in->smooth, 0u, "sqrt and what it feeds may kink");
        if (in->op == ISM_OP_SQUARE)
            cr_expect_eq(in->smooth, 1u);
    }
    cr_expect_eq(t->code[t->len - 1].smooth, 0u);
    ism_tape_free(t);
}

/* Skipping the partials free_of names changes no bit: each expression's tape evaluated as
 * compiled and with free_of cleared (claiming nothing) gives the same interval jets and
 * gradients to the bit, over random boxes, single points among them (where a partial that
 * does depend on a variable can still be exactly 0), and the same point Hessians where they
 * are finite. */
static bool same_bits(const void *a, const void *b, size_t n) { return memcmp(a, b, n) == 0; }

static void same_without_free_of(const char *name, ism_tape *t, ism_tape *plain,
                                 const double *within, uint64_t seed)
{
    for (size_t i = 0; i < plain->len; i++) {
        plain->code[i].free_of = 0;
        plain->code[i].smooth = 0;
    }
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(jw && ws);
    test_rng rng = { seed };
    size_t nboxes = test_scaled(200);
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3];
        random_box(&rng, within, b);
        ism_ivjet J1, J2;
        ism_ivgrad G1, G2;
        size_t k1 = ism_eval_interval_jet(t, jw, b, NULL, NULL, &J1);
        size_t k2 = ism_eval_interval_jet(plain, jw, b, NULL, NULL, &J2);
        cr_assert(k1 == k2 && same_bits(&J1, &J2, sizeof J1), "%s: interval jet differs", name);
        k1 = ism_eval_interval_grad(t, jw, b, NULL, NULL, &G1);
        k2 = ism_eval_interval_grad(plain, jw, b, NULL, NULL, &G2);
        cr_assert(k1 == k2 && same_bits(&G1, &G2, sizeof G1), "%s: gradient differs", name);
        double p[3], g1[3], g2[3], h1[6], h2[6];
        for (int k = 0; k < 3; k++)
            p[k] = test_uniform(&rng, b[k].lo, b[k].hi);
        double f1 = ism_eval_hessian(t, ws, p[0], p[1], p[2], g1, h1);
        double f2 = ism_eval_hessian(plain, ws, p[0], p[1], p[2], g2, h2);
        bool finite = isfinite(f2);
        for (int k = 0; k < 3; k++)
            finite = finite && isfinite(g2[k]) && isfinite(h2[k]) && isfinite(h2[k + 3]);
        if (!finite)
            continue; /* 0 · inf: NaN without free_of, 0 with it (eval_hessian.c) */
        cr_assert(same_bits(&f1, &f2, sizeof f1), "%s: point value differs", name);
        for (int k = 0; k < 3; k++)
            cr_assert(g1[k] == g2[k], "%s: point gradient differs", name);
        for (int k = 0; k < 6; k++)
            cr_assert(h1[k] == h2[k], "%s: point Hessian differs", name);
    }
    ism_ivjet_ws_free(jw);
    ism_eval_ws_free(ws);
}

Test(eval_interval_jet, free_of_changes_no_bit)
{
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    for (size_t i = 0; i < sizeof OPS_EXPRS / sizeof OPS_EXPRS[0]; i++) {
        ism_tape *t = compile(OPS_EXPRS[i]), *plain = compile(OPS_EXPRS[i]);
        same_without_free_of(OPS_EXPRS[i], t, plain, within, 900 + i);
        ism_tape_free(t);
        ism_tape_free(plain);
    }
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        ism_tape *plain = test_surface_compile(&TEST_SURFACES[s]);
        same_without_free_of(TEST_SURFACES[s].name, t, plain, TEST_SURFACES[s].box, 950 + s);
        ism_tape_free(t);
        ism_tape_free(plain);
    }
}

/* Boxes at the edges of the doubles: infinite, huge (inf − inf, 0 · inf, overflow), zero
 * width, subnormal. */
static const ism_interval EDGE_BOXES[][3] = {
    { { -INFINITY, INFINITY }, { -INFINITY, INFINITY }, { -INFINITY, INFINITY } },
    { { 0, 0 }, { -INFINITY, INFINITY }, { 1, 2 } },
    { { 1e300, 1e308 }, { -1e308, -1e300 }, { 1e200, 1e300 } },
    { { 1000, 2000 }, { 1000, 2000 }, { -2000, 1000 } },
    { { -5, 0 }, { 0, 0 }, { 0, 0 } },
    { { INFINITY, INFINITY }, { -INFINITY, -INFINITY }, { 0, INFINITY } },
    { { -1e-320, 1e-320 }, { 5e-324, 1e-310 }, { -1e-300, 0 } },
    { { 1e150, 1e160 }, { 1e150, 1e160 }, { 1e150, 1e160 } },
};
#define N_EDGE_BOXES (sizeof EDGE_BOXES / sizeof EDGE_BOXES[0])

/* No bound of a jet or a gradient is NaN (interval_jet.h), whatever the box: infinite and
 * huge boxes (inf − inf, 0 · inf, overflow in the second partials), poles and domain edges.
 * The evaluator tests the whole jet of an instruction for NaN at once and cleans it bound by
 * bound only then: a partial the test skipped (a Hessian entry, say) would show here. */
Test(eval_interval_jet, no_nan_bound_in_any_partial)
{
    static const char *exprs[] = {
        "x*y*z", "x/y + z", "exp(x) - exp(y)", "log(x) * 0.5 + log(y)", "x - x", "sqrt(x)*y",
        "x^64 - y^63 + z^5", "exp(x)/exp(y)", "sin(x*y) + cos(z)", "min(log(x), y)",
        "abs(x)*log(y)", "(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2)", "tan(x)*y^3",
        "pow(x, 2.5) * z",
    };
    const ism_interval (*boxes)[3] = EDGE_BOXES;
    for (size_t i = 0; i < sizeof exprs / sizeof exprs[0]; i++) {
        ism_tape *t = compile(exprs[i]);
        ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
        cr_assert(jw);
        for (size_t b = 0; b < N_EDGE_BOXES; b++) {
            ism_ivjet J;
            ism_ivgrad G;
            ism_eval_interval_jet(t, jw, boxes[b], NULL, NULL, &J);
            ism_eval_interval_grad(t, jw, boxes[b], NULL, NULL, &G);
            cr_expect(sane(J.v) && sane(G.v), "%s, box %zu: value", exprs[i], b);
            for (int k = 0; k < 3; k++)
                cr_expect(sane(J.d[k]) && sane(G.d[k]), "%s, box %zu: d%d [%g, %g]", exprs[i],
                          b, k, J.d[k].lo, J.d[k].hi);
            for (int e = 0; e < 6; e++)
                cr_expect(sane(J.h[e]), "%s, box %zu: h%d [%g, %g]", exprs[i], b, e, J.h[e].lo,
                          J.h[e].hi);
        }
        ism_ivjet_ws_free(jw);
        ism_tape_free(t);
    }
}

/* zero_free.c's mean-value form takes f at a node's centre from the natural evaluator
 * (ism_eval_interval) beside the slopes of this one: both passes build each value from the
 * same interval_ops.h steps and clean NaN alike, so the value is the gradient pass's to the
 * bit. Each pass on a fresh workspace (trig memo cold), the natural one first: point boxes
 * (the centres zero_free uses) and random boxes of every example surface and every
 * operation's expression, and the edge boxes for both. */
static void natural_value(const char *name, const ism_tape *t, const ism_interval b[3])
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert(ws && jw);
    ism_interval v = ism_eval_interval(t, ws, b[0], b[1], b[2]);
    ism_ivgrad G;
    ism_eval_interval_grad(t, jw, b, NULL, NULL, &G);
    cr_assert(same_bits(&G.v, &v, sizeof v),
              "%s over [%g, %g] x [%g, %g] x [%g, %g]: [%.17g, %.17g] vs [%.17g, %.17g]", name,
              b[0].lo, b[0].hi, b[1].lo, b[1].hi, b[2].lo, b[2].hi, v.lo, v.hi, G.v.lo, G.v.hi);
    ism_ivjet_ws_free(jw);
    ism_eval_ws_free(ws);
}

/* nboxes random boxes of within (one in eight a point), then as many points, then the edge
 * boxes. */
static void natural_values(const char *name, ism_tape *t, const double *within, uint64_t seed)
{
    size_t nboxes = test_scaled(100);
    test_rng rng = { seed };
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3];
        random_box(&rng, within, b);
        natural_value(name, t, b);
    }
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval p[3];
        for (int k = 0; k < 3; k++) {
            double a = test_uniform(&rng, within[k], within[k + 3]);
            p[k] = (ism_interval){ a, a };
        }
        natural_value(name, t, p);
    }
    for (size_t b = 0; b < N_EDGE_BOXES; b++)
        natural_value(name, t, EDGE_BOXES[b]);
}

/* check(name, tape, within, seed) over every operation's expression (within ±2, seeds from
 * ops_seed) and every example surface (its own box, seeds from surface_seed). */
static void over_every_tape(void (*check)(const char *, ism_tape *, const double *, uint64_t),
                            uint64_t ops_seed, uint64_t surface_seed)
{
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    for (size_t i = 0; i < sizeof OPS_EXPRS / sizeof OPS_EXPRS[0]; i++) {
        ism_tape *t = compile(OPS_EXPRS[i]);
        check(OPS_EXPRS[i], t, within, ops_seed + i);
        ism_tape_free(t);
    }
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        check(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, surface_seed + s);
        ism_tape_free(t);
    }
}

Test(eval_interval_jet, natural_value_is_gradient_value)
{
    over_every_tape(natural_values, 1200, 1300);
}

/* A gradient kept (ism_eval_interval_grad_kept) then the jet of the same box: the jet computes
 * only the Hessian where the tape allows, and must give the jet of a fresh second-order pass
 * to the bit — with other boxes evaluated on the workspace in between (registers overwritten:
 * the values and first partials come from the record), with free_of cleared, and the kept
 * gradient itself the plain one's bits. */
static void kept_then_jet(const char *name, ism_tape *t, const double *within, uint64_t seed)
{
    ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *kept = ism_ivjet_ws_new(t);
    cr_assert(plain && kept);
    test_rng rng = { seed };
    size_t nboxes = test_scaled(200);
    for (size_t n = 0; n < nboxes; n++) {
        ism_interval b[3], other[3];
        random_box(&rng, within, b);
        random_box(&rng, within, other);
        ism_ivjet J1, J2, scratch;
        ism_ivgrad G1, G2, gs;
        size_t k1 = ism_eval_interval_jet(t, plain, b, NULL, NULL, &J1);
        size_t g1 = ism_eval_interval_grad(t, plain, b, NULL, NULL, &G1);
        size_t g2 = ism_eval_interval_grad_kept(t, kept, b, &G2);
        cr_assert(g1 == g2 && same_bits(&G1, &G2, sizeof G1), "%s: kept gradient differs", name);
        if (n % 3 == 1)
            ism_eval_interval_grad(t, kept, other, NULL, NULL, &gs);
        if (n % 3 == 2)
            ism_eval_interval_jet(t, kept, other, NULL, NULL, &scratch);
        uint8_t kinks[64];
        cr_assert(t->len <= sizeof kinks);
        memset(kinks, 7, sizeof kinks);
        size_t k2 = ism_eval_interval_jet(t, kept, b, NULL, kinks, &J2);
        cr_assert(k1 == k2 && same_bits(&J1, &J2, sizeof J1), "%s: jet after a kept gradient",
                  name);
        for (size_t i = 0; i < t->len; i++)
            cr_assert(kinks[i] <= 1, "%s: kinks not written", name);
        size_t k3 = ism_eval_interval_jet(t, kept, b, NULL, NULL, &J2); /* the record is spent */
        cr_assert(k1 == k3 && same_bits(&J1, &J2, sizeof J1), "%s: second jet", name);
    }
    ism_ivjet_ws_free(plain);
    ism_ivjet_ws_free(kept);
}

Test(eval_interval_jet, kept_gradient_then_jet_changes_no_bit)
{
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    for (size_t i = 0; i < sizeof OPS_EXPRS / sizeof OPS_EXPRS[0]; i++) {
        ism_tape *t = compile(OPS_EXPRS[i]), *bare = compile(OPS_EXPRS[i]);
        for (size_t k = 0; k < bare->len; k++)
            bare->code[k].free_of = bare->code[k].smooth = 0;
        kept_then_jet(OPS_EXPRS[i], t, within, 1300 + i);
        kept_then_jet(OPS_EXPRS[i], bare, within, 1400 + i);
        ism_tape_free(t);
        ism_tape_free(bare);
    }
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        kept_then_jet(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, 1500 + s);
        ism_tape_free(t);
    }
}

/* The batched gradient pass (ism_eval_interval_grad_batch) over n boxes: each box's
 * enclosure the scalar kept pass's to the bit, and each box's jet afterwards (in another
 * order, with other boxes evaluated in between) a fresh second-order pass's to the bit, the
 * record then spent. Returns false when the tape is not one the batch takes. */
static bool batch_matches(const char *name, ism_tape *t, const ism_interval (*b)[3], size_t n,
                          ism_ivjet_ws *plain, ism_ivjet_ws *batch, test_rng *rng,
                          const double *within)
{
    ism_ivgrad G[ISM_IVGRAD_BATCH], g;
    if (!ism_eval_interval_grad_batch(t, batch, b, n, G))
        return false;
    for (size_t k = 0; k < n; k++) {
        size_t kinks = ism_eval_interval_grad_kept(t, plain, b[k], &g);
        cr_assert(kinks == 0, "%s: a batched tape with kinks", name);
        cr_assert(same_bits(&g, &G[k], sizeof g), "%s: box %zu of %zu: [%a, %a] d0 [%a, %a] vs "
                  "[%a, %a] d0 [%a, %a]", name, k, n, g.v.lo, g.v.hi, g.d[0].lo, g.d[0].hi,
                  G[k].v.lo, G[k].v.hi, G[k].d[0].lo, G[k].d[0].hi);
    }
    for (size_t i = 0; i < n; i++) {
        size_t k = (i * 5 + 3) % n; /* every box once, out of order when n > 1 */
        if (n % 5 == 0 || k % 2)
            continue; /* some records left unused: a later batch replaces them */
        ism_interval other[3];
        ism_ivjet J1, J2, scratch;
        ism_ivgrad gs;
        random_box(rng, within, other);
        if (i % 3 == 1)
            ism_eval_interval_grad(t, batch, other, NULL, NULL, &gs);
        if (i % 3 == 2)
            ism_eval_interval_jet(t, batch, other, NULL, NULL, &scratch);
        ism_eval_interval_jet(t, plain, b[k], NULL, NULL, &J1);
        ism_eval_interval_jet(t, batch, b[k], NULL, NULL, &J2);
        cr_assert(same_bits(&J1, &J2, sizeof J1), "%s: jet after the batch, box %zu", name, k);
        ism_eval_interval_jet(t, batch, b[k], NULL, NULL, &J2);
        cr_assert(same_bits(&J1, &J2, sizeof J1), "%s: second jet, box %zu", name, k);
    }
    return true;
}

/* Random batches of 1-8 boxes (one in eight a point), then the edge boxes (EDGE_BOXES and
 * one with lo > hi and a NaN bound) in batches. */
static size_t batch_check(const char *name, ism_tape *t, const double *within, uint64_t seed)
{
    ism_interval edges[N_EDGE_BOXES + 1][3];
    memcpy(edges, EDGE_BOXES, sizeof EDGE_BOXES);
    edges[N_EDGE_BOXES][0] = (ism_interval){ 2, 1 };
    edges[N_EDGE_BOXES][1] = (ism_interval){ NAN, 1 };
    edges[N_EDGE_BOXES][2] = (ism_interval){ 0, 0 };
    ism_ivjet_ws *plain = ism_ivjet_ws_new(t), *batch = ism_ivjet_ws_new(t);
    cr_assert(plain && batch);
    test_rng rng = { seed };
    size_t batches = 0, nb = test_scaled(60);
    for (size_t i = 0; i < nb; i++) {
        ism_interval b[ISM_IVGRAD_BATCH][3];
        size_t n = 1 + i % ISM_IVGRAD_BATCH;
        for (size_t k = 0; k < n; k++)
            random_box(&rng, within, b[k]);
        batches += batch_matches(name, t, (const ism_interval (*)[3])b, n, plain, batch, &rng,
                                 within);
    }
    size_t ne = sizeof edges / sizeof edges[0];
    for (size_t first = 0; first < ne; first += ISM_IVGRAD_BATCH) {
        size_t n = ne - first < ISM_IVGRAD_BATCH ? ne - first : ISM_IVGRAD_BATCH;
        batches += batch_matches(name, t, (const ism_interval (*)[3])(edges + first), n, plain,
                                 batch, &rng, within);
    }
    ism_ivjet_ws_free(plain);
    ism_ivjet_ws_free(batch);
    return batches;
}

Test(eval_interval_jet, batched_gradient_changes_no_bit)
{
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    size_t taken = 0;
    for (size_t i = 0; i < sizeof OPS_EXPRS / sizeof OPS_EXPRS[0]; i++) {
        ism_tape *t = compile(OPS_EXPRS[i]), *bare = compile(OPS_EXPRS[i]);
        for (size_t k = 0; k < bare->len; k++)
            bare->code[k].free_of = bare->code[k].smooth = 0;
        taken += batch_check(OPS_EXPRS[i], t, within, 1700 + i) > 0;
        batch_check(OPS_EXPRS[i], bare, within, 1800 + i);
        ism_tape_free(t);
        ism_tape_free(bare);
    }
    /* the polynomials among them (affine, +, -, ×, squares, integer powers): the first two,
     * the quintic, the squared sphere, -x^2 - y^4 + 7 and the two spheres' product */
    cr_expect_eq(taken, 6, "batched %zu of the expressions", taken);
    static const char *more[] = {
        "(x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2)", "1 - x - 2*(y - z)/3 + x*y*z",
        "-(x - y)^3 + 0.5*z^4/7", "x", "3",
    };
    for (size_t i = 0; i < sizeof more / sizeof more[0]; i++) {
        ism_tape *t = compile(more[i]);
        cr_expect(batch_check(more[i], t, within, 1900 + i) > 0, "%s: not batched", more[i]);
        ism_tape_free(t);
    }
    for (size_t s = 0; s < TEST_NSURFACES; s++) {
        /* the polynomial ones (the fixture's flag) are those dual.c batches: each taken */
        ism_tape *t = test_surface_compile(&TEST_SURFACES[s]);
        size_t b = batch_check(TEST_SURFACES[s].name, t, TEST_SURFACES[s].box, 2000 + s);
        cr_expect(!TEST_SURFACES[s].polynomial || b > 0, "%s: not batched", TEST_SURFACES[s].name);
        ism_tape_free(t);
    }
}

/* revF 1: the batch asks each call's tape whether it takes it, not the tape's address. One
 * block holds a polynomial's tape, then sin(x) + y*z's: the batch must refuse the second
 * (it computes no sine) or enclose its values; taking it as the first gives x + y*z. */
Test(eval_interval_jet, batch_asks_the_tape_not_its_address)
{
    ism_tape *a = compile("x*y + z"), *b = compile("sin(x) + y*z");
    size_t na = sizeof *a + a->len * sizeof a->code[0];
    size_t nb = sizeof *b + b->len * sizeof b->code[0];
    ism_tape *slot = malloc(na > nb ? na : nb);
    cr_assert_not_null(slot);
    ism_ivjet_ws *ws = ism_ivjet_ws_new(a->nregs >= b->nregs ? a : b);
    cr_assert_not_null(ws);
    const ism_interval box[1][3] = { { { 2, 3 }, { 1, 1.5 }, { 0.5, 1 } } };
    ism_ivgrad G[1];
    memcpy(slot, a, na);
    cr_assert(ism_eval_interval_grad_batch(slot, ws, box, 1, G), "the polynomial is batched");
    memcpy(slot, b, nb);
    if (ism_eval_interval_grad_batch(slot, ws, box, 1, G))
        for (int i = 0; i < 8; i++) {
            double x = box[0][0].lo + (i & 1) * 0.5 + 0.25, y = box[0][1].lo + (i >> 1 & 1) * 0.25;
            double z = box[0][2].lo + (i >> 2 & 1) * 0.25;
            cr_assert(holds(G[0].v, sin(x) + y * z), "[%g, %g] lacks f(%g, %g, %g)", G[0].v.lo,
                      G[0].v.hi, x, y, z);
        }
    ism_ivjet_ws_free(ws);
    free(slot);
    ism_tape_free(a);
    ism_tape_free(b);
}

/* revF 2: a batch that cannot grow its records (the address space capped just above what
 * the process uses) leaves no record standing: the next jet over the previous batch's box
 * is a fresh pass's, to the bit. */
Test(eval_interval_jet, batch_failing_to_grow_leaves_no_record)
{
#if defined(__SANITIZE_ADDRESS__)
    cr_skip_test("the sanitizer's allocator aborts when the address space runs out");
#endif
    char src[16384] = "z";
    for (int i = 1; i <= 400; i++) /* ~1200 instructions: records of ~600 KB, mapped apart */
        snprintf(src + strlen(src), sizeof src - strlen(src), " + (x + %d)*y", i);
    ism_tape *a = compile("x*y + z"), *big = compile(src);
    cr_assert_gt(big->len, 1000);
    ism_ivjet_ws *ws = ism_ivjet_ws_new(a->nregs >= big->nregs ? a : big);
    ism_ivjet_ws *plain = ism_ivjet_ws_new(a);
    cr_assert(ws && plain);
    const ism_interval box[1][3] = { { { 0.5, 1 }, { -1, 2 }, { 0, 0.25 } } };
    ism_ivgrad G[1];
    cr_assert(ism_eval_interval_grad_batch(a, ws, box, 1, G));
    long pages = 0;
    FILE *f = fopen("/proc/self/statm", "r");
    cr_assert(f && fscanf(f, "%ld", &pages) == 1);
    fclose(f);
    struct rlimit old, cap;
    cr_assert(getrlimit(RLIMIT_AS, &old) == 0);
    cap = old;
    cap.rlim_cur = (rlim_t)pages * 4096 + (64u << 10); /* 64 KB more than in use */
    cr_assert(setrlimit(RLIMIT_AS, &cap) == 0);
    bool grown = ism_eval_interval_grad_batch(big, ws, box, 1, G);
    cr_assert(setrlimit(RLIMIT_AS, &old) == 0);
    cr_assert(!grown, "the records grew under the cap: the test probes nothing");
    ism_ivjet J1, J2;
    ism_eval_interval_jet(a, plain, box[0], NULL, NULL, &J1);
    ism_eval_interval_jet(a, ws, box[0], NULL, NULL, &J2);
    cr_assert(memcmp(&J1, &J2, sizeof J1) == 0);
    ism_ivjet_ws_free(ws);
    ism_ivjet_ws_free(plain);
    ism_tape_free(a);
    ism_tape_free(big);
}

/* The gradient pass (run_grad: JET_OPS by direct threading) and the second-order pass
 * (run_jet: the same list through jet_op's switch) compute the value and first partials
 * with the same steps: over every operation's expression and every example surface, random
 * boxes and the edge boxes, with no branch forced and with branches forced at random, both
 * give the same value, partials, kink count and kinks to the bit (kinks written in full over
 * a poisoned array). A step mapped to the wrong operation in one expansion, or a tail that
 * skips or repeats an instruction, makes them differ. */
static void grad_as_jet(const char *name, const ism_tape *t, const ism_interval b[3],
                        const uint8_t *force, ism_ivjet_ws *jw)
{
    uint8_t kg[64], kj[64];
    cr_assert(t->len <= sizeof kg);
    memset(kg, 7, sizeof kg);
    memset(kj, 9, sizeof kj);
    ism_ivgrad G;
    ism_ivjet J;
    size_t ng = ism_eval_interval_grad(t, jw, b, force, kg, &G);
    size_t nj = ism_eval_interval_jet(t, jw, b, force, kj, &J);
    cr_assert(ng == nj, "%s: %zu kinks vs %zu", name, ng, nj);
    cr_assert(memcmp(kg, kj, t->len) == 0, "%s: kinks differ", name);
    cr_assert(same_bits(&G.v, &J.v, sizeof G.v) && same_bits(G.d, J.d, sizeof G.d),
              "%s over [%g, %g] x [%g, %g] x [%g, %g]: gradient pass [%a, %a] d0 [%a, %a], "
              "second-order [%a, %a] d0 [%a, %a]", name, b[0].lo, b[0].hi, b[1].lo, b[1].hi,
              b[2].lo, b[2].hi, G.v.lo, G.v.hi, G.d[0].lo, G.d[0].hi, J.v.lo, J.v.hi,
              J.d[0].lo, J.d[0].hi);
}

static void grads_as_jets_once(const char *name, const ism_tape *t, const double *within,
                               uint64_t seed)
{
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    cr_assert(jw);
    test_rng rng = { seed };
    uint8_t force[64];
    cr_assert(t->len <= sizeof force);
    size_t nboxes = test_scaled(150);
    for (size_t n = 0; n < nboxes + N_EDGE_BOXES; n++) {
        ism_interval b[3];
        if (n < nboxes)
            random_box(&rng, within, b);
        else
            memcpy(b, EDGE_BOXES[n - nboxes], sizeof b);
        grad_as_jet(name, t, b, NULL, jw);
        for (size_t i = 0; i < t->len; i++)
            force[i] = (uint8_t)(test_uniform(&rng, 0.0, 3.0)); /* FREE, A or B */
        grad_as_jet(name, t, b, force, jw);
    }
    ism_ivjet_ws_free(jw);
}

/* The tape as compiled, then with free_of cleared (every step's other copy). */
static void grads_as_jets(const char *name, ism_tape *t, const double *within, uint64_t seed)
{
    grads_as_jets_once(name, t, within, seed);
    for (size_t k = 0; k < t->len; k++)
        t->code[k].free_of = t->code[k].smooth = 0;
    grads_as_jets_once(name, t, within, seed + 1000);
}

Test(eval_interval_jet, gradient_pass_is_the_second_order_pass_value_and_partials)
{
    over_every_tape(grads_as_jets, 2100, 2300);
    const double within[6] = { -2, -2, -2, 2, 2, 2 };
    /* an operation code past the list: the whole line in both, its partials too */
    ism_tape *t = compile("x*y + z");
    t->code[t->len - 1].op = ISM_OP_COUNT + 3;
    grads_as_jets("x*y + z, last code past the list", t, within, 2400);
    ism_ivgrad G;
    ism_ivjet_ws *jw = ism_ivjet_ws_new(t);
    ism_interval b[3] = { { 0, 1 }, { 0, 1 }, { 0, 1 } };
    ism_eval_interval_grad(t, jw, b, NULL, NULL, &G);
    cr_expect(whole(G.v) && whole(G.d[0]), "a code past the list gives the whole line");
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
}
