/* test_pinch_error.c — under an error bound the conformance's refill round pinch points is
 * measured against E (core/singular/conform_refine.c: centroids and edge midpoints, halving
 * edges until within E or at depth.max's finest cell). The cross-cap, Steiner's Roman surface
 * and the Whitney umbrella at E = 2e-3 × the box's width, depth.max 10, in the three boxes of
 * pf_sweep_box, and at E = 1e-3 × width: every centroid and edge midpoint's distance to
 * f = 0, found here by Newton from the closed-form polynomial (the test's own foot search,
 * independent of the mesher), is within E but for a measured margin (PINCH_ERROR_*); and the
 * analysis (what the stats' "met" reads) never says a mesh is
 * within E where the closed form finds a point farther.
 *
 * Measured by this test, E = 2e-3 / 1e-3 × width, own / 1e-3 / irrational box, in E: before
 * the refill was measured (main 672458c, the third box then at 0.37 of a cell) cross-cap
 * 0.93 / 0.93 / 0.93 and 0.97 / 1.26 / 0.98, Steiner 0.83 / 1.24 / 1.25 and 0.88 / 1.12 /
 * 1.45, Whitney 0.79 / 0.97 / 1.47 and 0.88 / 1.29 / 0.96 (the worst points edge midpoints on
 * the fold within two cells of a pinch point); now cross-cap 0.93 / 0.93 / 0.93 and 0.97 /
 * 0.98 / 0.98, Steiner 0.83 / 1.00 / 0.99 and 0.88 / 1.11 / 0.96, Whitney 0.79 / 0.97 / 0.98
 * and 0.88 / 0.99 / 1.00 (0.995). Steiner's 1.11 at the finer E is where the halving stops:
 * the fold beside its pinch points is tighter than the finest cell of depth.max, or a half
 * would turn over across it (the stats say met: false; the analysis' first-order estimate
 * puts it at 1.26 / 1.95 E). The old code fails the 1e-3 boxes (1.26, 1.24, 1.12, 1.29 E).
 * On Steiner's surface the analysis' largest centroid and midpoint distances are also checked
 * against the exact ones, from the surface's parametrisation (roman_dist.c, a second method
 * that never evaluates f), to ANALYSIS_EXACT: at E = 2e-3 / 1e-3 × width (the meshes of
 * 096a2a5) the first-order analysis said 0.97 / 1.24 / 1.23 and 0.61 / 1.26 / 1.39 E at
 * centroids, 1.01 / 1.88 / 1.85 and 0.88 / 1.95 / 2.46 E at midpoints where the exact figures
 * are 0.56 / 0.80 / 0.74 and 0.61 / 0.89 / 0.70, 0.83 / 1.00 / 0.99 and 0.88 / 1.11 / 0.96 E;
 * measured again near the surface (core/analysis/nearest.c) it agrees to 0.005 E (0.708
 * against 0.704 E the worst; on 78c2745's meshes 0.716 against 0.711). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include "core/analysis/analysis.h"
#include "core/eval/eval.h"
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/core/roman_dist.h"

/* At E = 2e-3 × width every run is within E (0.998 at most): the bound leaves 5% for the
 * boxes' placement; at 1e-3 × width Steiner reaches 1.11 E where depth.max stops it. */
#define PINCH_ERROR_COARSE 1.05
#define PINCH_ERROR_FINE 1.15
/* The analysis' largest centroid and midpoint distances against the exact ones (where the
 * surface's nearest point is known from its parametrisation, roman_dist.c), in E: the
 * analysis' first-order estimate, where it stands, is off by the distance times the
 * curvature, ~1e-3 E here. */
#define ANALYSIS_EXACT 0.01

/* The foot search stops when its steps and the residual are this share of the distance. */
#define FOOT_DONE 1e-6
/* A first foot nearer than this share of E settles the point (the bound only asks more). */
#define FOOT_SURE 0.5

/* A point of f = 0 near p, from the start x: Newton along ∇f to the surface, then steps
 * along its tangent plane towards p (to the foot where p − x is normal to the surface),
 * reprojected each time. Returns |x − p| plus the residual's first-order step. */
static double foot_from(const ism_tape *f, ism_eval_ws *ws, const double p[3], double x[3])
{
    double g[3];
    for (int it = 0; it < 60; it++) {
        double fv = ism_eval_gradient(f, ws, x[0], x[1], x[2], g), gg = ism_dot3(g, g);
        if (gg == 0 || fv == 0)
            break;
        for (int k = 0; k < 3; k++)
            x[k] -= fv * g[k] / gg;
        if (it >= 50)
            continue;
        fv = ism_eval_gradient(f, ws, x[0], x[1], x[2], g);
        gg = ism_dot3(g, g);
        double d[3] = {p[0] - x[0], p[1] - x[1], p[2] - x[2]}, step = 0;
        if (gg > 0) {
            double dn = ism_dot3(d, g) / gg;
            for (int k = 0; k < 3; k++) {
                double s = 0.5 * (d[k] - dn * g[k]);
                x[k] += s;
                step = fmax(step, fabs(s));
            }
        }
        if (step <= FOOT_DONE * ism_norm3(d) && fabs(fv) <= FOOT_DONE * sqrt(gg) * ism_norm3(d))
            break; /* at the foot: p − x along ∇f, x on f = 0, to a millionth */
    }
    double fv = ism_eval_gradient(f, ws, x[0], x[1], x[2], g), gl = ism_norm3(g);
    return ism_dist3(x, p) + (fv == 0 ? 0 : gl > 0 ? fabs(fv) / gl : INFINITY);
}

/* Distance from p to f = 0 (an upper bound: the nearest of the surface points found). The
 * searches start at p and a quarter of E from it along each axis: from a plane of symmetry
 * (x = 0 beside Whitney's pinch point, where ∇f has no x part) Newton alone stays in the plane
 * and reaches the fold 6 E away while a sheet passes 0.1 E off. */
static double foot_distance(const ism_tape *f, ism_eval_ws *ws, const double p[3], double E)
{
    double x0[3] = {p[0], p[1], p[2]}, best = foot_from(f, ws, p, x0);
    if (best <= FOOT_SURE * E)
        return best; /* well within E: the other starts can only find it nearer */
    for (int s = 1; s < 7; s++) {
        double x[3] = {p[0], p[1], p[2]};
        x[(s - 1) / 2] += (s % 2 ? 0.25 : -0.25) * E;
        best = fmin(best, foot_from(f, ws, p, x));
    }
    return best;
}

/* foot_distance for pf_worst_turned's callback: the case's tape, workspace and E. */
static const ism_tape *pe_f;
static ism_eval_ws *pe_ws;
static double pe_E;

static double pe_dist(const double *p)
{
    return foot_distance(pe_f, pe_ws, p, pe_E);
}

/* The largest exact distance at m's centroids (*centroid) and edge midpoints (*midpoint). */
static void exact_worst(const ism_mesh *m, const roman_dist *r, double *centroid,
                        double *midpoint)
{
    *centroid = *midpoint = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const double *v[3];
        for (int j = 0; j < 3; j++)
            v[j] = m->pos + 3 * (size_t)m->tri[3 * t + j];
        for (int j = 0; j < 4; j++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = j == 3 ? (v[0][a] + v[1][a] + v[2][a]) / 3
                              : 0.5 * (v[j][a] + v[(j + 1) % 3][a]);
            double d = roman_dist_at(r, q), *worst = j == 3 ? centroid : midpoint;
            *worst = fmax(*worst, d);
        }
    }
}

/* exact: the exact distance's search, NULL where the test has none (only Steiner's). */
static void pinch_case(const char *name, const char *expr, const double base[6],
                       const roman_dist *exact)
{
    ism_tape *t = pf_compile(&(pf_surface){expr, NULL, 0, NULL, 0});
    for (int run = 0; run < 6; run++) {
        /* E = 2e-3 and 1e-3 × the box's width, each in the three boxes */
        int which = run % 3 - 1;
        double E = (run < 3 ? 2e-3 : 1e-3) * (base[3] - base[0]);
        if (which < pf_first_box() - 1)
            continue;
        double box[6];
        pf_sweep_box(base, 10, which, box);
        ism_mesh m;
        ism_locus l;
        pf_run_surface_bounded(t, box, 3, 10, E, &m, &l);
        pe_f = t;
        pe_ws = ism_eval_ws_new(t);
        pe_E = E;
        cr_assert(pe_ws);
        size_t turned;
        double worst = pf_worst_turned(&m, t, pe_dist, &turned);
        ism_eval_ws_free(pe_ws);
        ism_analysis a;
        pf_analyse_plain(&m, t, &a);
        bool met = fmax(a.max_dist_centroid, a.max_dist_midpoint) <= E;
        cr_log_info("%s E %g box %d: closed form %.3f E, analysis centroid %.3f E midpoint %.3f E, "
                    "%zu triangles", name, E, which, worst / E, a.max_dist_centroid / E,
                    a.max_dist_midpoint / E, m.ntris);
        double bound = run < 3 ? PINCH_ERROR_COARSE : PINCH_ERROR_FINE;
        cr_expect_leq(worst, bound * E, "%s E %g box %d: a centroid or midpoint %.3f E from "
                      "f = 0", name, E, which, worst / E);
        cr_expect(!met || worst <= 1.01 * E, "%s box %d: the analysis says within E, the closed "
                  "form finds %.3f E", name, which, worst / E);
        if (exact) {
            double ec, em;
            exact_worst(&m, exact, &ec, &em);
            cr_log_info("%s E %g box %d: exact centroid %.4f E midpoint %.4f E, analysis %.4f / "
                        "%.4f E", name, E, which, ec / E, em / E, a.max_dist_centroid / E,
                        a.max_dist_midpoint / E);
            cr_expect(fabs(a.max_dist_centroid - ec) <= ANALYSIS_EXACT * E &&
                          fabs(a.max_dist_midpoint - em) <= ANALYSIS_EXACT * E,
                      "%s E %g box %d: the analysis says %.4f E at centroids, %.4f E at "
                      "midpoints; the nearest surface points are %.4f E and %.4f E away", name,
                      E, which, a.max_dist_centroid / E, a.max_dist_midpoint / E, ec / E,
                      em / E);
        }
        ism_analysis_free(&a);
        ism_locus_free(&l);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

Test(pinch_error, cross_cap)
{
    pinch_case("cross-cap", "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)",
               (const double[6]){-1.2, -1.2, -1.2, 1.2, 1.2, 1.2}, NULL);
}

Test(pinch_error, steiner)
{
    roman_dist *r = roman_dist_new();
    cr_assert(r);
    pinch_case("steiner", "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z",
               (const double[6]){-1, -1, -1, 1, 1, 1}, r);
    roman_dist_free(r);
}

Test(pinch_error, whitney)
{
    pinch_case("whitney", "x^2 - y^2*z", (const double[6]){-1, -1, -1, 1, 1, 1}, NULL);
}
