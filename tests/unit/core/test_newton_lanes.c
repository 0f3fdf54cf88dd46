/* test_newton_lanes.c — ism_sing_newton_lanes (runs side by side, their Hessians in one
 * batch a pass) against ism_sing_newton run by run: the same final point, convergence,
 * iteration count, gradient norm, gradient and Hessian, bit for bit, and the same number of
 * Hessians. The starts are spread over the box (a deterministic stream), half of them held to
 * a small cell grown by half its width as the singular search's candidates are, half to the
 * whole box, so the runs end at different passes (some converge onto critical points of f,
 * some leave their bounds, some run out of steps); more runs than one pass takes
 * (ISM_SING_NEWTON_LANES), so a second pass of lanes runs too. A jet given to the wrong lane,
 * or a lane dropped or kept a pass too long, moves a point or a count here. The Klein bottle
 * (its double curve), Steiner's Roman surface (three double lines through a triple point),
 * Kummer's 16 nodes and the cross-cap, in the three placements (pf_sweep_box).
 * Since both drivers share their steps, also one answer from outside: runs started beside
 * Kummer's 16 nodes end on their closed-form coordinates. And starts where the Hessian is
 * not finite (sqrt and log at 0, 1/x at 0, a term past the double range): the Hessian at the
 * start is still ism_eval_hessian's there, bit for bit, in lanes and alone.
 *
 * And the pseudo-inverse step in lanes (sym3_lanes.h) against ism_sym3_pinv_step on
 * matrices chosen to take every path of the sweeps: random ones over many scales, diagonal
 * ones (no rotation), ones with a zero off-diagonal entry (a rotation skipped in one lane
 * only), equal diagonals (theta = 0), multiples of I and I plus a rank-one term (equal
 * eigenvalues), subnormal and huge
 * entries, NaN and infinity (no step), the zero matrix; a count not a multiple of four. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "poly_fixture.h"
#include "test_eval_surfaces.h"
#include "core/singular/newton.h"
#include "core/singular/sym3_lanes.h"
#include "core/util/sym3.h"

/* Starts per surface and placement: over two passes of lanes. */
#define LANES_RUNS (2 * ISM_SING_NEWTON_LANES + 22)

typedef struct starts {
    double p[LANES_RUNS][3], lo[LANES_RUNS][3], hi[LANES_RUNS][3];
    ism_newton_opts o[LANES_RUNS];
} starts;

/* Start i in box b: odd ones held to a cell of 1/64 of the box grown by half its width (the
 * search's candidates at depth 6), even ones to the box, with the search's options. */
static void make_starts(const double b[6], test_rng *rng, starts *s)
{
    double width = 0.0;
    for (int k = 0; k < 3; k++)
        width = fmax(width, (b[k + 3] - b[k]) / 64.0);
    for (int i = 0; i < LANES_RUNS; i++) {
        for (int k = 0; k < 3; k++) {
            double e = (b[k + 3] - b[k]) / 64.0;
            s->p[i][k] = test_uniform(rng, b[k] + e, b[k + 3] - e);
            s->lo[i][k] = i % 2 ? s->p[i][k] - e : b[k];
            s->hi[i][k] = i % 2 ? s->p[i][k] + e : b[k + 3];
        }
        s->o[i] = (ism_newton_opts){ ISM_SING_PINV_REL, i % 2 ? width : 8.0 * width,
                                     1e-10 * width, 64, s->lo[i], s->hi[i], true };
    }
}

static void expect_lanes_as_runs(const ism_tape *t, const char *name, const double base[6])
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, 6, w, box);
        test_rng rng = { 29u + (uint64_t)(w + 1) };
        static starts s;
        make_starts(box, &rng, &s);
        double lanes[LANES_RUNS][3];
        memcpy(lanes, s.p, sizeof lanes);
        ism_newton_result lr[LANES_RUNS];
        uint64_t lane_evals = 0, run_evals = 0;
        ism_sing_newton_lanes(t, ws, lanes, s.o, lr, LANES_RUNS, &lane_evals);
        int converged = 0, left = 0, most = 0, fewest = 1 << 30;
        for (int i = 0; i < LANES_RUNS; i++) {
            double p[3] = { s.p[i][0], s.p[i][1], s.p[i][2] };
            ism_newton_result r = ism_sing_newton(t, ws, p, &s.o[i], &run_evals);
            cr_expect(!memcmp(p, lanes[i], sizeof p), "%s box %d run %d: end point", name, w, i);
            cr_expect(r.converged == lr[i].converged && r.iterations == lr[i].iterations
                          && !memcmp(&r.grad_norm, &lr[i].grad_norm, sizeof r.grad_norm)
                          && !memcmp(r.grad, lr[i].grad, sizeof r.grad)
                          && !memcmp(r.hess, lr[i].hess, sizeof r.hess),
                      "%s box %d run %d: %d/%d iterations, converged %d/%d", name, w, i,
                      r.iterations, lr[i].iterations, r.converged, lr[i].converged);
            /* the Hessian at the start, both ways, is the one taken there alone */
            double g0[3], h0[6];
            ism_eval_hessian(t, ws, s.p[i][0], s.p[i][1], s.p[i][2], g0, h0);
            cr_expect(!memcmp(h0, r.start_hess, sizeof h0)
                          && !memcmp(h0, lr[i].start_hess, sizeof h0),
                      "%s box %d run %d: the Hessian at the start", name, w, i);
            converged += r.converged;
            left += !r.converged;
            most = r.iterations > most ? r.iterations : most;
            fewest = r.iterations < fewest ? r.iterations : fewest;
        }
        cr_expect_eq(lane_evals, run_evals, "%s box %d: %llu Hessians in lanes, %llu one by one",
                     name, w, (unsigned long long)lane_evals, (unsigned long long)run_evals);
        /* the runs end at different passes: some converge, some do not, counts differ */
        cr_expect_gt(converged, 5, "%s box %d: %d runs converged", name, w, converged);
        cr_expect_gt(left, 5, "%s box %d: %d runs did not converge", name, w, left);
        cr_expect_gt(most, fewest + 3, "%s box %d: iterations %d..%d", name, w, fewest, most);
    }
    ism_eval_ws_free(ws);
}

/* expect_lanes_as_runs on the test gallery's surface called name, in its box. */
static void gallery_lanes_as_runs(const char *name)
{
    const test_surface *s = test_surface_named(name);
    ism_tape *t = test_surface_compile(s);
    expect_lanes_as_runs(t, s->name, s->box);
    ism_tape_free(t);
}

Test(newton_lanes, klein_bottle) { gallery_lanes_as_runs("klein-bottle"); }

Test(newton_lanes, steiner_roman) { gallery_lanes_as_runs("steiner-roman"); }

Test(newton_lanes, kummer_16_nodes) { gallery_lanes_as_runs("kummer-16-nodes"); }

Test(newton_lanes, cross_cap)
{
    pf_surface s = { "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", NULL, 0, NULL, 0 };
    ism_tape *t = pf_compile(&s);
    const double box[6] = { -1.3, -1.3, -1.6, 1.3, 1.3, 1.4 };
    expect_lanes_as_runs(t, "cross-cap", box);
    ism_tape_free(t);
}

/* Kummer's quartic with mu2 = 2, w = 1 (lambda = 5), its 16 nodes in closed form. On an edge
 * of the tetrahedron pqrs = 0 two factors vanish, so f = (|P|^2 - 2)^2 and both f and its
 * gradient vanish where |P|^2 = 2: on p = q = 0 (x = 0, z = 1) at y = ±1, on r = s = 0 at x = ±1
 * (z = -1), on the other four edges (x = ±(1 - t)/√2, y = ±(1 + t)/√2, z = t) at t = ±1/√2.
 * The other four lie on the axes through the tetrahedron's vertices (0, ±√2, 1), (±√2, 0, -1):
 * along P = t v, f(t) = 24t^4 - 40t^3 + 18t^2 - 1 has the double root t = 1/2. */
static void kummer16_nodes(double n[16][3])
{
    const double r2 = sqrt(2.0), t = 1.0 / r2;
    int c = 0;
    for (int s = -1; s <= 1; s += 2) {
        double edge[2][3] = { { 0, s, 1 }, { s, 0, -1 } };
        double inner[2][3] = { { 0, s * r2 / 2, 0.5 }, { s * r2 / 2, 0, -0.5 } };
        memcpy(n[c++], edge[0], sizeof edge[0]);
        memcpy(n[c++], edge[1], sizeof edge[1]);
        memcpy(n[c++], inner[0], sizeof inner[0]);
        memcpy(n[c++], inner[1], sizeof inner[1]);
        for (int sx = -1; sx <= 1; sx += 2)
            for (int sy = -1; sy <= 1; sy += 2) {
                double z = s * t;
                double e[3] = { sx * (1 - z) / r2, sy * (1 + z) / r2, z };
                memcpy(n[c++], e, sizeof e);
            }
    }
}

/* Kummer's 16 nodes in the three placements: a run from the centre of the depth-6 cell (of
 * the placed box) that holds a node, held to that cell grown by half its width with the
 * search's options (start_of in search.c), converges to the closed-form node: within the
 * step tolerance (quadratic convergence at a node, whose Hessian is non-degenerate). Scalar
 * and in lanes, the same. This checks the shared steps (run_took_jet, run_wants_step,
 * run_move) against an answer neither driver computes. */
Test(newton_lanes, kummer_16_nodes_closed_form)
{
    const test_surface *g = test_surface_named("kummer-16-nodes");
    ism_tape *t = test_surface_compile(g);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    double node[16][3];
    kummer16_nodes(node);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6], p[16][3], lo[16][3], hi[16][3], width = 0.0;
        pf_sweep_box(g->box, 6, w, box);
        ism_newton_opts o[16];
        for (int k = 0; k < 3; k++)
            width = fmax(width, (box[k + 3] - box[k]) / 64.0);
        for (int i = 0; i < 16; i++) {
            for (int k = 0; k < 3; k++) {
                double e = (box[k + 3] - box[k]) / 64.0;
                double cell = box[k] + e * floor((node[i][k] - box[k]) / e);
                p[i][k] = cell + 0.5 * e;
                lo[i][k] = cell - 0.5 * e;
                hi[i][k] = cell + 1.5 * e;
            }
            o[i] = (ism_newton_opts){ ISM_SING_PINV_REL, width, 1e-10 * width, 64, lo[i], hi[i],
                                      true };
        }
        double lanes[16][3];
        memcpy(lanes, p, sizeof lanes);
        ism_newton_result lr[16];
        ism_sing_newton_lanes(t, ws, lanes, o, lr, 16, NULL);
        for (int i = 0; i < 16; i++) {
            ism_newton_result r = ism_sing_newton(t, ws, p[i], &o[i], NULL);
            double d = 0.0, dl = 0.0;
            for (int k = 0; k < 3; k++) {
                d = fmax(d, fabs(p[i][k] - node[i][k]));
                dl = fmax(dl, fabs(lanes[i][k] - node[i][k]));
            }
            cr_expect(r.converged && d <= o[i].tol,
                      "box %d node %d (%g, %g, %g): converged %d after %d steps, %g away", w, i,
                      node[i][0], node[i][1], node[i][2], r.converged, r.iterations, d);
            cr_expect(lr[i].converged && dl <= o[i].tol,
                      "box %d node %d in lanes: converged %d after %d steps, %g away", w, i,
                      lr[i].converged, lr[i].iterations, dl);
        }
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* Tapes and starts where f's Hessian at the start is NaN or infinite (or its gradient is):
 * each run's start_hess, alone and in lanes, is ism_eval_hessian's at the start, bit for bit
 * (search.c centre_rank ranks an unconverged candidate by it), and the two drivers end alike. */
Test(newton_lanes, non_finite_starts)
{
    static const char *const src[] = { "sqrt(x) + y^2 + z^2 - 1", "1/x + y^2 + z^2 - 1",
                                       "log(x) + y^2 + z^2", "x^2*y^2 + z^2 - 1e300*x^4" };
    enum { NS = 6 };
    static const double start[NS][3] = { { 0, 0.5, 0.5 }, { 0, 0, 0 }, { -1, 0.1, 0.2 },
                                         { 1e100, 1e100, 0 }, { 0.25, 0.25, 0 },
                                         { -0.0, 0.3, 0.1 } };
    int non_finite = 0;
    for (size_t f = 0; f < sizeof src / sizeof src[0]; f++) {
        pf_surface ps = { src[f], NULL, 0, NULL, 0 };
        ism_tape *t = pf_compile(&ps);
        ism_eval_ws *ws = ism_eval_ws_new(t);
        cr_assert_not_null(ws);
        double lo[NS][3], hi[NS][3], lanes[NS][3];
        ism_newton_opts o[NS];
        for (int i = 0; i < NS; i++) {
            for (int k = 0; k < 3; k++) {
                lo[i][k] = start[i][k] - 1.0;
                hi[i][k] = start[i][k] + 1.0;
            }
            o[i] = (ism_newton_opts){ ISM_SING_PINV_REL, 0.5, 1e-10, 10, lo[i], hi[i], true };
        }
        memcpy(lanes, start, sizeof lanes);
        ism_newton_result lr[NS];
        ism_sing_newton_lanes(t, ws, lanes, o, lr, NS, NULL);
        for (int i = 0; i < NS; i++) {
            double p[3] = { start[i][0], start[i][1], start[i][2] }, g0[3], h0[6];
            ism_newton_result r = ism_sing_newton(t, ws, p, &o[i], NULL);
            ism_eval_hessian(t, ws, start[i][0], start[i][1], start[i][2], g0, h0);
            bool finite = true;
            for (int k = 0; k < 6; k++)
                finite = finite && isfinite(h0[k]) && (k > 2 || isfinite(g0[k]));
            non_finite += !finite;
            cr_expect(!memcmp(h0, r.start_hess, sizeof h0)
                          && !memcmp(h0, lr[i].start_hess, sizeof h0),
                      "%s start %d: the Hessian at the start", src[f], i);
            cr_expect(!memcmp(p, lanes[i], sizeof p) && r.converged == lr[i].converged
                          && r.iterations == lr[i].iterations,
                      "%s start %d: %d/%d iterations, converged %d/%d", src[f], i, r.iterations,
                      lr[i].iterations, r.converged, lr[i].converged);
        }
        ism_eval_ws_free(ws);
        ism_tape_free(t);
    }
    cr_expect_gt(non_finite, 3, "%d starts with a non-finite Hessian or gradient", non_finite);
}

/* Matrix i of the pinv_lanes set (see the top). */
static void pick_matrix(int i, test_rng *rng, double h[6])
{
    double scale = pow(10.0, test_uniform(rng, -12.0, 12.0));
    for (int k = 0; k < 6; k++)
        h[k] = scale * test_uniform(rng, -1.0, 1.0);
    switch (i % 9) {
    case 1: h[1] = h[2] = h[4] = 0.0; break;                     /* diagonal */
    case 2: h[1 + (i / 9) % 2 * 3] = 0.0; break;                 /* xy or yz already 0 */
    case 3: /* equal diagonal: scale I, or a first rotation at theta = 0 */
        h[0] = h[3] = h[5] = scale;
        if ((i / 9) % 2)
            h[1] = h[2] = h[4] = 0.0;
        break;
    case 4: {                                                    /* I + u uᵀ */
        double u[3] = { h[0], h[1], h[2] };
        h[0] = 1.0 + u[0] * u[0]; h[1] = u[0] * u[1]; h[2] = u[0] * u[2];
        h[3] = 1.0 + u[1] * u[1]; h[4] = u[1] * u[2]; h[5] = 1.0 + u[2] * u[2];
        break;
    }
    case 5: h[(i / 9) % 6] = (i / 9) % 2 ? NAN : INFINITY; break;
    case 6: for (int k = 0; k < 6; k++) h[k] *= 1e-300; break;   /* subnormal products */
    case 7: for (int k = 0; k < 6; k++) h[k] = 0.0; break;
    case 8: h[5] = h[0] * h[3] > 0 ? 1e-14 * h[5] : h[5]; break; /* nearly singular */
    default: break;
    }
}

Test(newton_lanes, pinv_lanes_as_scalar)
{
    enum { N = 4 * 9 * 7 + 3 };
    static double g[N][3], h[N][6], rel[N], trust[N], step[N][3];
    static bool ok[N];
    test_rng rng = { 2929 };
    for (int i = 0; i < N; i++) {
        pick_matrix(i, &rng, h[i]);
        for (int k = 0; k < 3; k++)
            g[i][k] = test_uniform(&rng, -1.0, 1.0);
        rel[i] = i % 2 ? ISM_SING_PINV_REL : ISM_SING_PINV_REL_POINT;
        trust[i] = i % 3 ? INFINITY : test_uniform(&rng, 1e-6, 1.0);
    }
    ism_sym3_pinv_lanes((const double (*)[3])g, (const double (*)[6])h, rel, trust, step, ok, N);
    int stepped = 0, refused = 0;
    for (int i = 0; i < N; i++) {
        double s[3];
        bool want = ism_sym3_pinv_step(g[i], h[i], rel[i], trust[i], s);
        cr_expect_eq(ok[i], want, "matrix %d (kind %d): ok %d, one by one %d", i, i % 9, ok[i],
                     want);
        if (want && ok[i])
            cr_expect(!memcmp(s, step[i], sizeof s), "matrix %d (kind %d): step", i, i % 9);
        stepped += want;
        refused += !want;
    }
    cr_expect_gt(stepped, N / 2, "%d steps", stepped);
    cr_expect_gt(refused, 20, "%d refused", refused);
}
