/* test_eval_shorten.c — interval-driven tape shortening: inside its box a shortened tape
 * gives exactly the values of the full tape (point, batch, gradient, Hessian), deeper boxes
 * shorten further (a shortened tape shortened again, as an octree does), the workspace of
 * the original serves every shortened tape, and a tape without decidable min/max is left
 * alone. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "test_eval_surfaces.h"

/* Constructive solids: unions (min) and intersections (max) of simple shapes. */
static const char *CSG[] = {
    "min(x^2 + y^2 + z^2 - 1, (x - 1.5)^2 + y^2 + z^2 - 0.25, max(abs(x + 1.5) - 0.4, "
    "abs(y) - 0.4, abs(z) - 0.4))",
    "max(min(x^2 + y^2 - 0.3, (x - 0.8)^2 + z^2 - 0.2), -(x^2 + y^2 + z^2 - 1.5), z - 0.9)",
    "min(min(x, y), min(z, 0.5 - x*y)) + max(sin(3*x), cos(2*y))",
    "max(sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x), x^2 + y^2 + z^2 - 1.96)",
};

static const double BOX[6] = { -2, -2, -2, 2, 2, 2 };

static ism_interval side(test_rng *rng, double lo, double hi, double w)
{
    double a = test_uniform(rng, lo, hi - w);
    return (ism_interval){ a, a + w };
}

/* Values of the two tapes agree exactly at n random points of the box. */
static void expect_same_values(const char *name, const ism_tape *full, const ism_tape *shrt,
                               ism_eval_ws *ws, ism_interval bx, ism_interval by,
                               ism_interval bz, test_rng *rng, int n)
{
    enum { M = 64 };
    double x[M], y[M], z[M], f1[M], f2[M];
    cr_assert_leq(n, M);
    for (int i = 0; i < n; i++) {
        x[i] = test_uniform(rng, bx.lo, bx.hi);
        y[i] = test_uniform(rng, by.lo, by.hi);
        z[i] = test_uniform(rng, bz.lo, bz.hi);
        double a = ism_eval_point(full, ws, x[i], y[i], z[i]);
        double b = ism_eval_point(shrt, ws, x[i], y[i], z[i]);
        cr_assert(a == b || (isnan(a) && isnan(b)), "%s: full %.17g, shortened %.17g", name,
                  a, b);
        double ga[3], gb[3], ha[6], hb[6];
        ism_eval_hessian(full, ws, x[i], y[i], z[i], ga, ha);
        ism_eval_hessian(shrt, ws, x[i], y[i], z[i], gb, hb);
        for (int k = 0; k < 3; k++)
            cr_assert(ga[k] == gb[k], "%s: gradient differs", name);
        for (int k = 0; k < 6; k++)
            cr_assert(ha[k] == hb[k], "%s: Hessian differs", name);
    }
    ism_eval_batch(full, ws, x, y, z, f1, (size_t)n);
    ism_eval_batch(shrt, ws, x, y, z, f2, (size_t)n);
    for (int i = 0; i < n; i++)
        cr_assert(f1[i] == f2[i], "%s: batch lane %d differs", name, i);
}

Test(eval_shorten, same_values_inside_the_box_and_deeper)
{
    size_t nboxes = test_scaled(800);
    size_t deeper = 0; /* over all solids: the last one has a single max */
    for (size_t c = 0; c < sizeof CSG / sizeof CSG[0]; c++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(CSG[c], NULL, 0, NULL, 0, NULL, &err);
        cr_assert_not_null(t, "%s", err.message);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        ism_tape *s1 = ism_tape_new_like(t), *s2 = ism_tape_new_like(t);
        cr_assert(ws && s1 && s2);
        test_rng rng = { 9000 + c };
        size_t shortened = 0;
        for (size_t b = 0; b < nboxes; b++) {
            double w = 4.0 * exp2(-test_uniform(&rng, 1.0, 6.0));
            ism_interval bx = side(&rng, BOX[0], BOX[3], w), by = side(&rng, BOX[1], BOX[4], w),
                         bz = side(&rng, BOX[2], BOX[5], w);
            ism_interval range;
            bool shorter = ism_tape_shorten(t, ws, bx, by, bz, s1, &range);
            ism_interval direct = ism_eval_interval(t, ws, bx, by, bz);
            cr_assert(range.lo == direct.lo && range.hi == direct.hi, "range differs");
            if (!shorter)
                continue;
            shortened++;
            cr_assert_lt(ism_tape_length(s1), ism_tape_length(t));
            expect_same_values(CSG[c], t, s1, ws, bx, by, bz, &rng, 32);
            /* the shortened tape still encloses f over its box */
            ism_interval r1 = ism_eval_interval(s1, ws, bx, by, bz);
            for (int i = 0; i < 16; i++) {
                double f = ism_eval_point(t, ws, test_uniform(&rng, bx.lo, bx.hi),
                                          test_uniform(&rng, by.lo, by.hi),
                                          test_uniform(&rng, bz.lo, bz.hi));
                cr_assert(r1.lo <= f && f <= r1.hi);
            }
            /* an octant of the box, shortened from the shortened tape */
            ism_interval cx = { bx.lo, 0.5 * (bx.lo + bx.hi) }, cy = { 0.5 * (by.lo + by.hi), by.hi },
                         cz = { bz.lo, 0.5 * (bz.lo + bz.hi) };
            if (ism_tape_shorten(s1, ws, cx, cy, cz, s2, NULL)) {
                deeper++;
                cr_assert_lt(ism_tape_length(s2), ism_tape_length(s1));
                expect_same_values(CSG[c], t, s2, ws, cx, cy, cz, &rng, 32);
            }
        }
        /* shortening must actually happen on these solids, or this test proves nothing */
        cr_expect_geq(shortened, nboxes / 4, "%s: only %zu of %zu boxes shortened", CSG[c],
                      shortened, nboxes);
        ism_tape_free(s1);
        ism_tape_free(s2);
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
    cr_expect_gt(deeper, 0, "no box shortened a shortened tape further");
}

Test(eval_shorten, dominated_branch_is_dropped)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("min(x^2 + y^2 + z^2 - 1, sin(x)*cos(y)*exp(z) + 5)", NULL,
                                   0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_tape *s = ism_tape_new_like(t);
    ism_interval u = { -0.5, 0.5 };
    cr_assert(ism_tape_shorten(t, ws, u, u, u, s, NULL));
    /* only the sphere remains: 3 squares, 2 adds, the constant add, the copy */
    cr_expect_leq(ism_tape_length(s), ism_tape_length(t) - 4, "%zu vs %zu",
                  ism_tape_length(s), ism_tape_length(t));
    char text[512];
    ism_tape_canonical(s, text, sizeof text);
    cr_expect(strstr(text, "sin") == NULL && strstr(text, "exp") == NULL, "%s", text);
    /* a box where neither branch dominates keeps everything */
    ism_interval wide = { -3, 3 };
    size_t before = ism_tape_length(s);
    cr_expect_not(ism_tape_shorten(t, ws, wide, wide, wide, s, NULL));
    cr_expect_eq(ism_tape_length(s), before, "out must be left unchanged");
    ism_tape_free(s);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(eval_shorten, nothing_to_drop_without_min_max)
{
    ism_tape *t = test_surface_compile(&TEST_SURFACES[1]); /* torus */
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_tape *s = ism_tape_new_like(t);
    ism_interval u = { 0.1, 0.2 }, range = { 0, 0 };
    cr_expect_not(ism_tape_shorten(t, ws, u, u, u, s, &range));
    ism_interval direct = ism_eval_interval(t, ws, u, u, u);
    cr_expect(range.lo == direct.lo && range.hi == direct.hi);
    ism_tape_free(s);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

Test(eval_shorten, constant_branch_becomes_constant)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("max(x^3 - y, 2)", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_tape *s = ism_tape_new_like(t);
    ism_interval u = { -0.5, 0.5 };
    cr_assert(ism_tape_shorten(t, ws, u, u, u, s, NULL));
    cr_expect_eq(ism_tape_length(s), 1);
    cr_expect_eq(ism_eval_point(s, ws, 0.1, 0.2, 0.3), 2.0);
    ism_tape_free(s);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* Bit for bit (a -0 is not a +0) at the corners, edge midpoints, face centres and centre of
 * the box, where a min/max may tie: an octree's cells evaluate there (octree.h). */
static void expect_same_bits_on_the_box(const char *name, const ism_tape *full,
                                        const ism_tape *shrt, ism_eval_ws *ws,
                                        const ism_interval b[3])
{
    for (int i = 0; i < 27; i++) {
        double p[3];
        for (int k = 0, d = i; k < 3; k++, d /= 3)
            p[k] = d % 3 == 0 ? b[k].lo : d % 3 == 2 ? b[k].hi : 0.5 * (b[k].lo + b[k].hi);
        double ga[3], gb[3];
        double fa = ism_eval_gradient(full, ws, p[0], p[1], p[2], ga);
        double fb = ism_eval_gradient(shrt, ws, p[0], p[1], p[2], gb);
        double va = ism_eval_point(full, ws, p[0], p[1], p[2]);
        double vb = ism_eval_point(shrt, ws, p[0], p[1], p[2]);
        cr_assert(memcmp(&fa, &fb, sizeof fa) == 0 && memcmp(&va, &vb, sizeof va) == 0 &&
                      memcmp(ga, gb, sizeof ga) == 0,
                  "%s at (%.17g, %.17g, %.17g): full %.17g (%g, %g, %g), shortened %.17g "
                  "(%g, %g, %g)", name, p[0], p[1], p[2], fa, ga[0], ga[1], ga[2], fb, gb[0],
                  gb[1], gb[2]);
    }
}

/* Boxes for expr's checks: box k of n into b (the touching cases give their own). */
typedef void (*box_maker)(size_t k, test_rng *rng, ism_interval b[3], const void *arg);

/* Shortens expr's tape over n boxes and compares bits on each box that shortened it. */
static void check_boxes(const char *expr, size_t n, box_maker make, const void *arg,
                        uint64_t seed)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    ism_tape *s = ism_tape_new_like(t);
    test_rng rng = { seed };
    for (size_t k = 0; k < n; k++) {
        ism_interval b[3];
        make(k, &rng, b, arg);
        if (ism_tape_shorten(t, ws, b[0], b[1], b[2], s, NULL))
            expect_same_bits_on_the_box(expr, t, s, ws, b);
    }
    ism_tape_free(s);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

static void given_box(size_t k, test_rng *rng, ism_interval b[3], const void *arg)
{
    (void)k, (void)rng;
    memcpy(b, arg, 3 * sizeof *b);
}

/* Dyadic sides, every other box on the lattice of its side. */
static void dyadic_box(size_t k, test_rng *rng, ism_interval b[3], const void *arg)
{
    (void)arg;
    double w = 4.0 * exp2(-(double)(1 + k % 6));
    for (int a = 0; a < 3; a++) {
        b[a] = side(rng, BOX[a], BOX[a + 3], w);
        if (k % 2 == 0)
            b[a] = (ism_interval){ floor(b[a].lo / w) * w, floor(b[a].lo / w) * w + w };
    }
}

/* Branches that touch on the box's boundary (min(x, y) over x <= 1 <= y: a tie at x = y =
 * 1, where min picks y) are not decided; the CSG solids agree bit for bit on the boundary
 * points of boxes, on the lattice and off it (fails when min/max are decided with <=). */
Test(eval_shorten, same_bits_on_the_box_boundary_where_branches_touch)
{
    static const char *touching[] = { "min(x, y) + z", "max(abs(x), 0) + y", "max(y, x) - z" };
    static const ism_interval tb[3][3] = { { { 0, 1 }, { 1, 2 }, { 0, 1 } },
                                           { { 0, 1 }, { 0, 1 }, { 0, 1 } },
                                           { { 0, 1 }, { -1, 0 }, { 0, 1 } } };
    for (size_t c = 0; c < sizeof touching / sizeof touching[0]; c++)
        check_boxes(touching[c], 1, given_box, tb[c], 0);
    for (size_t c = 0; c < sizeof CSG / sizeof CSG[0]; c++)
        check_boxes(CSG[c], test_scaled(400), dyadic_box, NULL, 7100 + c);
}
