/* test_edge_roots.c — the double-root search on a lattice segment (edge_roots.h) against
 * closed forms: f = (x − c)² − h along a segment of x, c inside it. h > 0: two roots,
 * c ∓ √h, and the search answers 2 with its split point between them; h = 0: a tangent
 * root at c, answer 1 within √eps of c (|f| < eps there); h < 0: no root, answer 0 — since
 * the search asks an interval over what is left of its bracket, in fewer gradients than its
 * 25 halvings. The same f written out (x² − 2cx + c² − h: intervals wider by ~2c × the
 * bracket) gives the same answers, early too unless h is below what 25 halvings make the
 * interval see (h = −1e-8: all 25, the answer unchanged). Each in three placements: the
 * segment [0, 1], moved by 1e-3, and by (√2 − 1) / 2, c with it. The single-root search run
 * in lanes (ism_regula_falsi_lanes: the octree build's level prefetch) against the search
 * one segment at a time: the same root bits and the same evaluations counted, on every
 * example surface, with more segments than lanes, and f changing sign across each root
 * (t ± 1e-9, measured). Segments whose first secant lands exactly on the root (f = 0 there:
 * a lane freed after one step) mixed with ordinary ones: the same, and those roots the
 * closed form's t. The inline rootless test of a lattice segment against the general one
 * (segments of 0 to 5 steps, up and down), and its assert on gradient_test's precondition. */
#include <criterion/criterion.h>
#include <math.h>
#include <signal.h>
#include <string.h>
#include "core/octree/edge_roots.h"
#include "poly_fixture.h"
#include "test_eval_surfaces.h"

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

/* Segments with ends of opposite sign (neither 0) in box b of s, ends at random points
 * joined along one axis (node edges lie along axes) or across (any segment), up to max. */
static size_t crossing_segments(const test_surface *s, ism_tape *t, ism_eval_ws *ws,
                                test_rng *r, double (*a)[3], double (*b)[3], double *fa,
                                double *fb, size_t max)
{
    size_t n = 0;
    for (int tries = 0; tries < 200000 && n < max; tries++) {
        for (int k = 0; k < 3; k++)
            a[n][k] = test_uniform(r, s->box[k], s->box[k + 3]);
        memcpy(b[n], a[n], sizeof b[n]);
        int axis = tries % 4; /* 3: across */
        double len = 0.2 * (s->box[3] - s->box[0]);
        for (int k = 0; k < 3; k++)
            if (axis == 3 || k == axis)
                b[n][k] += test_uniform(r, 0.2, 1) * len;
        fa[n] = ism_eval_point(t, ws, a[n][0], a[n][1], a[n][2]);
        fb[n] = ism_eval_point(t, ws, b[n][0], b[n][1], b[n][2]);
        if (fa[n] != 0 && fb[n] != 0 && (fa[n] < 0) != (fb[n] < 0) && isfinite(fa[n]) &&
            isfinite(fb[n]))
            n++;
    }
    return n;
}

#define LANE_SEGMENTS 150 /* more than the lanes run at once (64): lanes are reused */
#define SIGN_STEP 1e-9     /* past the searches' bracket (1e-10 of the segment) */

/* Does f change sign across t on a→b (or vanish at t)? */
static bool sign_changes_at(ism_tape *tape, ism_eval_ws *ws, const double a[3],
                            const double b[3], double t)
{
    double f[3];
    for (int k = 0; k < 3; k++) {
        double u = t + (k - 1) * SIGN_STEP, p[3];
        for (int i = 0; i < 3; i++)
            p[i] = a[i] + u * (b[i] - a[i]);
        f[k] = ism_eval_point(tape, ws, p[0], p[1], p[2]);
    }
    return f[1] == 0 || (f[0] < 0 && f[2] > 0) || (f[0] > 0 && f[2] < 0);
}

Test(edge_roots, lanes_give_each_search_root_bit_for_bit)
{
    static double a[LANE_SEGMENTS][3], b[LANE_SEGMENTS][3], fa[LANE_SEGMENTS],
        fb[LANE_SEGMENTS], t[LANE_SEGMENTS];
    size_t tested = 0, full = 0; /* surfaces with more segments than lanes */
    for (size_t i = 0; i < TEST_NSURFACES; i++) {
        const test_surface *s = &TEST_SURFACES[i];
        ism_tape *tape = test_surface_compile(s);
        ism_sampler one, lanes;
        memset(&one, 0, sizeof one);
        one.tape = tape;
        one.ws = ism_eval_ws_new(tape);
        lanes = one;
        lanes.batch = true; /* as the octree build's samplers (else one at a time) */
        lanes.ws = ism_eval_ws_new(tape);
        cr_assert(one.ws && lanes.ws);
        test_rng r = {0x5eed + i};
        size_t n = crossing_segments(s, tape, one.ws, &r, a, b, fa, fb, LANE_SEGMENTS);
        for (size_t k = 0; k < 3; k++) { /* none, one segment, all of them */
            size_t m = k == 0 ? 0 : k == 1 ? (n > 0) : n;
            one.n_point = lanes.n_point = 0;
            ism_regula_falsi_lanes(&lanes, (const double (*)[3])a, (const double (*)[3])b, fa,
                                   fb, t, m);
            for (size_t j = 0; j < m; j++) {
                double want = ism_regula_falsi(&one, a[j], b[j], fa[j], fb[j]);
                cr_expect(memcmp(&want, &t[j], sizeof want) == 0,
                          "%s segment %zu of %zu: lanes %.17g, alone %.17g", s->name, j, m, t[j],
                          want);
                cr_expect(t[j] > 0 && t[j] < 1, "%s: root at %g", s->name, t[j]);
                cr_expect(sign_changes_at(tape, one.ws, a[j], b[j], t[j]),
                          "%s segment %zu: f keeps its sign across %.17g", s->name, j, t[j]);
            }
            cr_expect_eq(lanes.n_point, one.n_point, "%s: %llu evaluations in lanes, %llu alone",
                         s->name, (unsigned long long)lanes.n_point,
                         (unsigned long long)one.n_point);
        }
        tested += n;
        full += n == LANE_SEGMENTS;
        ism_eval_ws_free(one.ws);
        ism_eval_ws_free(lanes.ws);
        ism_tape_free(tape);
    }
    cr_expect_gt(full, TEST_NSURFACES / 2, "only %zu of %zu surfaces gave %d segments (%zu in all)",
                 full, TEST_NSURFACES, LANE_SEGMENTS, tested);
}

/* f = (x − c)(1 + y²), c dyadic (three placements): on a segment along x at a dyadic y from
 * c − c1 to c + c2 (c1, c2 dyadic) f is linear with exact values, so the first secant,
 * t = c1 / (c1 + c2), lands on x = c exactly and f is 0 there (the lane's zero exit); every
 * third segment is such, the others cross y from −0.4 to 0.6 (f cubic along them: several
 * steps). Searched in lanes (batch) and one at a time (no batch) against ism_regula_falsi. */
Test(edge_roots, lanes_free_a_lane_on_an_exact_zero)
{
    static double a[LANE_SEGMENTS][3], b[LANE_SEGMENTS][3], fa[LANE_SEGMENTS],
        fb[LANE_SEGMENTS], t[LANE_SEGMENTS], want_t[LANE_SEGMENTS];
    static const double halves[][2] = {{0.25, 0.25}, {0.25, 0.75}, {0.125, 0.375},
                                       {0.5, 0.5}, {0.375, 0.125}};
    const double places[] = {0.5, 0.5 + 0x1p-10, -0.75};
    for (int pl = 0; pl < 3; pl++) {
        double c = places[pl];
        ism_param prm[1] = {{"c", c}};
        pf_surface sf = {"(x - c) * (1 + y*y)", prm, 1, NULL, 0};
        ism_tape *tape = pf_compile(&sf);
        ism_sampler one;
        memset(&one, 0, sizeof one);
        one.tape = tape;
        one.ws = ism_eval_ws_new(tape);
        cr_assert(one.ws);
        size_t exact = 0;
        for (size_t i = 0; i < LANE_SEGMENTS; i++) {
            double z = -0.5 + 0x1p-6 * (double)(i % 64);
            want_t[i] = -1;
            if (i % 3 == 0) {
                const double *h = halves[(i / 3) % 5];
                double y = 0x1p-4 * (double)(i % 7);
                a[i][0] = c - h[0], a[i][1] = y, a[i][2] = z;
                b[i][0] = c + h[1], b[i][1] = y, b[i][2] = z;
                want_t[i] = h[0] / (h[0] + h[1]);
                exact++;
            } else {
                double w = 0.01 * (double)(i % 11);
                a[i][0] = c - 0.3 - w, a[i][1] = -0.4, a[i][2] = z;
                b[i][0] = c + 0.2 + w, b[i][1] = 0.6, b[i][2] = z;
            }
            fa[i] = ism_eval_point(tape, one.ws, a[i][0], a[i][1], a[i][2]);
            fb[i] = ism_eval_point(tape, one.ws, b[i][0], b[i][1], b[i][2]);
            cr_assert(fa[i] < 0 && fb[i] > 0, "segment %zu: ends %g, %g", i, fa[i], fb[i]);
        }
        cr_assert_gt(LANE_SEGMENTS - exact, 64, "more ordinary searches than lanes");
        for (int batch = 0; batch < 2; batch++) {
            ism_sampler lanes = one;
            lanes.batch = batch;
            lanes.ws = ism_eval_ws_new(tape);
            cr_assert(lanes.ws);
            one.n_point = lanes.n_point = 0;
            ism_regula_falsi_lanes(&lanes, (const double (*)[3])a, (const double (*)[3])b, fa,
                                   fb, t, LANE_SEGMENTS);
            size_t zeros = 0;
            for (size_t j = 0; j < LANE_SEGMENTS; j++) {
                uint64_t before = one.n_point;
                double want = ism_regula_falsi(&one, a[j], b[j], fa[j], fb[j]);
                cr_expect(memcmp(&want, &t[j], sizeof want) == 0,
                          "c %g batch %d segment %zu: lanes %.17g, alone %.17g", c, batch, j,
                          t[j], want);
                cr_expect(sign_changes_at(tape, one.ws, a[j], b[j], t[j]),
                          "c %g segment %zu: f keeps its sign across %.17g", c, j, t[j]);
                if (want_t[j] >= 0) {
                    cr_expect_eq(t[j], want_t[j], "c %g segment %zu: root %.17g, not %.17g", c,
                                 j, t[j], want_t[j]);
                    zeros += one.n_point - before == 1; /* ended on its first step */
                }
            }
            cr_expect_eq(zeros, exact, "c %g: %zu of %zu exact segments ended at once", c,
                         zeros, exact);
            cr_expect_eq(lanes.n_point, one.n_point, "c %g batch %d: %llu evaluations, %llu",
                         c, batch, (unsigned long long)lanes.n_point,
                         (unsigned long long)one.n_point);
            ism_eval_ws_free(lanes.ws);
        }
        ism_eval_ws_free(one.ws);
        ism_tape_free(tape);
    }
}

/* The inline rootless test of a lattice segment (ism_lattice_segment_rootless: the slopes as
 * one product along the segment's axis) against the general one (ism_segment_rootless_normed:
 * full dot products with b − a), the same answer on every segment: segments along each axis
 * of a lattice of step 1/64 in the three placements (its origin as given, moved by the 1e-3
 * shift and by the irrational one of a cell), ends drawn with f of either sign or 0, ±inf or
 * NaN now and then, gradients with components 0, −0, ±inf or NaN now and then, and many
 * nearly along the segment or across it (slopes of 0 or either sign), with crease on and
 * off and gradient_test across its range (-1 .. 1, tolerances.c). The draws must reach the
 * pocket test and see it both ways, or the sweep proves nothing about the slopes. Segments
 * are 0 to 5 steps long, a quarter of them drawn downward (b below a: d < 0, as the walk's
 * sides 2 and 3 and a single-point boundary's bp[0] → bp[0] give them). */
static double rl_unit(uint64_t *s) /* uniform in [0, 1); *s the xorshift state */
{
    *s ^= *s << 13, *s ^= *s >> 7, *s ^= *s << 17;
    return (double)(*s >> 11) * 0x1p-53;
}

static double rl_value(uint64_t *s) /* mostly ordinary, now and then 0, −0, ±inf or NaN */
{
    double r = rl_unit(s);
    if (r < 0.04)
        return 0.0;
    if (r < 0.06)
        return -0.0;
    if (r < 0.07)
        return INFINITY;
    if (r < 0.08)
        return -INFINITY;
    if (r < 0.09)
        return NAN;
    return (rl_unit(s) - 0.5) * 4;
}

Test(edge_roots, lattice_rootless_is_the_general_test)
{
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X / 64, PF_IRR_Y / 64, PF_IRR_Z / 64}};
    const double tests[] = {-1, 0, 0.5, 0.9, 1};
    size_t pockets[2] = {0, 0}, cases = 0, lengths[2] = {0, 0}; /* zero, downward */
    uint64_t s = 0x9e3779b97f4a7c15ull;
    for (int pl = 0; pl < 3; pl++)
        for (int n = 0; n < 200000; n++) {
            int axis = n % 3, i[3];
            double a[3], b[3], ga[3], gb[3];
            for (int k = 0; k < 3; k++) {
                i[k] = (int)(rl_unit(&s) * 128) - 64;
                a[k] = -1.0 + shift[pl][k] + (1.0 / 64) * (double)i[k];
                b[k] = a[k];
            }
            int len = (int)(rl_unit(&s) * 6) * (rl_unit(&s) < 0.25 ? -1 : 1);
            lengths[0] += len == 0, lengths[1] += len < 0;
            b[axis] = -1.0 + shift[pl][axis] + (1.0 / 64) * (double)(i[axis] + len);
            for (int k = 0; k < 3; k++) {
                ga[k] = rl_value(&s);
                gb[k] = rl_unit(&s) < 0.5 ? ga[k] + 0.1 * rl_value(&s) : rl_value(&s);
            }
            if (n % 4 == 1) /* across the segment: slopes ±0 */
                ga[axis] = n % 8 == 1 ? 0.0 : -0.0, gb[axis] = -ga[axis];
            double fa = rl_value(&s);
            double fb = rl_unit(&s) < 0.7 ? fa * (0.5 + rl_unit(&s)) : rl_value(&s);
            ism_root_params prm = {tests[n % 5], 1e-9, 25, n % 2 == 0};
            double na = ism_norm3(ga), nb = ism_norm3(gb);
            bool want = ism_segment_rootless_normed(&prm, a, b, fa, fb, ga, gb, na, nb);
            bool got = ism_lattice_segment_rootless(&prm, axis, a, b, fa, fb, ga, gb, na, nb);
            cr_assert_eq(got, want,
                         "placement %d axis %d: f %g, %g; ga (%g %g %g), gb (%g %g %g), "
                         "test %g crease %d: inline %d, general %d",
                         pl, axis, fa, fb, ga[0], ga[1], ga[2], gb[0], gb[1], gb[2],
                         prm.gradient_test, prm.crease, got, want);
            if (!ism_rootless_ends(fa, fb) && ism_one_sheet(&prm, fa, fb, ga, gb, na, nb)) {
                pockets[want ? 0 : 1]++;
            }
            cases++;
        }
    cr_expect_gt(lengths[0], cases / 20, "%zu of %zu of length 0", lengths[0], cases);
    cr_expect_gt(lengths[1], cases / 10, "%zu of %zu downward", lengths[1], cases);
    cr_expect_gt(pockets[0], cases / 100, "%zu of %zu reached the pocket test and passed",
                 pockets[0], cases);
    cr_expect_gt(pockets[1], cases / 100, "%zu of %zu reached the pocket test and failed",
                 pockets[1], cases);
}

/* ism_lattice_segment_rootless's precondition gradient_test > -2 (ism_one_sheet's sentinel
 * for a vanishing or undefined gradient): with -3 an inf gradient passes ism_one_sheet and
 * would reach the slopes, where the general test's dot product gives NaN (no pocket) and the
 * inline one a finite slope; the assert stops it there. */
Test(edge_roots, lattice_rootless_asserts_gradient_test_above_the_sentinel, .signal = SIGABRT)
{
    ism_root_params prm = {-3, 1e-9, 25, false};
    const double a[3] = {0, 0, 0}, b[3] = {0.25, 0, 0};
    const double ga[3] = {INFINITY, 0, 1}, gb[3] = {1, 0, 0};
    ism_lattice_segment_rootless(&prm, 0, a, b, 1.0, 0.5, ga, gb, 1.0, 1.0);
}
