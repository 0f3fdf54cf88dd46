/* test_polygonise_accuracy.c — the max_error bound: on the sphere, the torus and the gyroid
 * ball the mesh lies within E (1e-3 and 1e-4, box ±1.5) of the surface between its vertices
 * (at every triangle centroid and every edge midpoint, distances from the closed forms, not
 * from f), in boxes on the octree lattice and shifted off it (tests/unit/placements.h: by
 * 1e-3 and by irrational fractions of a finest cell); refinement rounds meet
 * a bound the octree's estimate alone missed; the cost grows like area / E (halving E about
 * doubles the triangles, never 4x); depth.max stops the refinement and the octree then counts
 * the cells that missed E; without max_error the mesh is what it was. Fewer triangles for the
 * same error: the sphere within 3x the fewest any mesh with its vertices on it can have, and the
 * gyroid ball's crease no longer sending cells to depth.max. The stats' analysis of the
 * sphere, torus and gyroid ball at E = 1e-3 (check_stats), in the three boxes: "met" as the
 * closed forms say at E and at UNMET_SHARE of the farthest point (not met), its farthest
 * centroid and midpoint never nearer than theirs within E, and its means and 99th
 * percentiles the same with a bound or without. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/analysis/analysis.h"
#include "core/util/vec3.h"
#include "poly_fixture.h"

static const ism_param sphere_r[] = {{"r", 1}};
static const pf_surface sphere = {"x^2 + y^2 + z^2 - r^2", sphere_r, 1, NULL, 0};
static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};

/* Exact distances to the two surfaces. */
static double sphere_dist(const double p[3])
{
    return fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
}

static double torus_dist(const double p[3])
{
    double ring = sqrt(p[0] * p[0] + p[1] * p[1]) - 1;
    return fabs(sqrt(ring * ring + p[2] * p[2]) - 0.3);
}

/* The safety depth of these runs: cells of 3 / 2^10, far below what E needs on them. */
#define SAFETY_DEPTH 10
/* Finest cell of the safety depth over a side of 3 (the box shifts are fractions of it). */
#define FINEST (3.0 / (1 << SAFETY_DEPTH))

static void run_rounds(const ism_tape *t, double shift, double e, int max_depth, bool fresh,
                       ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    for (int k = 0; k < 3; k++) {
        o.box[k] = -1.5 + shift;
        o.box[3 + k] = 1.5 + shift;
    }
    o.min_depth = 3;
    o.max_depth = max_depth;
    o.max_error = e;
    o.fresh_rounds = fresh;
    ism_error err;
    ism_mesh_init(m);
    cr_assert_eq(ism_polygonise(t, &o, m, st, &err), ISM_POLY_OK, "%s", err.message);
}

static void run_bounded(const ism_tape *t, double shift, double e, int max_depth, ism_mesh *m,
                        ism_poly_stats *st)
{
    run_rounds(t, shift, e, max_depth, false, m, st);
}

/* Triangle t's points between its vertices: [0] its centroid, [1..3] its edges' midpoints. */
static void between_points(const ism_mesh *m, size_t t, double pts[4][3])
{
    const double *v[3];
    for (int k = 0; k < 3; k++)
        v[k] = m->pos + 3 * (size_t)m->tri[3 * t + k];
    for (int a = 0; a < 3; a++) {
        pts[0][a] = (v[0][a] + v[1][a] + v[2][a]) / 3;
        for (int k = 0; k < 3; k++)
            pts[1 + k][a] = (v[k][a] + v[(k + 1) % 3][a]) / 2;
    }
}

/* The largest distance at triangle centroids and at edge midpoints. */
static void between_vertices(const ism_mesh *m, double (*dist)(const double *), double *cen,
                             double *mid)
{
    *cen = *mid = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double pts[4][3];
        between_points(m, t, pts);
        *cen = fmax(*cen, dist(pts[0]));
        for (int k = 1; k < 4; k++)
            *mid = fmax(*mid, dist(pts[k]));
    }
}

/* The issue's box. */
static const double BOX15[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};

/* t under the bound e at depths 3:SAFETY_DEPTH in base placed by pf_sweep_box (which −1 own,
 * 0 the 1e-3 shift, 1 the irrational one). */
static void run_placed(const ism_tape *t, const double base[6], int which, double e,
                       ism_mesh *m, ism_poly_stats *st)
{
    double box[6];
    pf_sweep_box(base, SAFETY_DEPTH, which, box);
    ism_poly_options o;
    pf_options(&o, box, 3, SAFETY_DEPTH);
    o.max_error = e;
    pf_run_options(t, &o, m, st);
}

/* Relative shortfall allowed to the stats' farthest distance below the closed form's: the
 * analysis measures a point just within E one Newton step further, its foot's residual to
 * first order (an error second order in that residual, ~1e-8 E at E = 1e-3). */
#define STATS_TOL 1e-6
/* The bound the stats are also asked to judge that the mesh does not meet: this share of its
 * farthest centroid or midpoint by the closed form (so some point lies beyond it). */
#define UNMET_SHARE 0.9

/* The service's analysis of m (one thread, no curvature) under the bound e (0: none). */
static ism_analysis analyse_under(const ism_mesh *m, const ism_tape *t, double e)
{
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = false;
    ao.threads = 1;
    ao.max_error = e;
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, t, &ao, &a, &err), "analyse: %s", err.message);
    return a;
}

/* The stats' "met" (proto/stats.c): every measured distance, at vertices, edge midpoints and
 * centroids, within e. */
static bool stats_met(const ism_analysis *a, double e)
{
    return fmax(a->max_dist_vertex, fmax(a->max_dist_midpoint, a->max_dist_centroid)) <= e;
}

/* The stats' analysis of m under the bound e: "met" exactly when the closed forms' farthest
 * point (worst: vertices, centroids, midpoints) is within e, bar a margin of STATS_TOL below e
 * where the stats, an upper bound, may read either way; when it is within e, the stats'
 * farthest centroid and midpoint no nearer than the closed forms' cen and mid (the farthest
 * points lie in the band and are measured one step further). Beyond e the first-order figure
 * stands and may fall short by its curvature term (the gyroid ball's irrational box judged at
 * UNMET_SHARE: its farthest midpoint 1.11103 of that bound by the stats, 1.11111 by the closed
 * form): only the verdict counts there. */
static void check_stats_under(const ism_mesh *m, const ism_tape *t, double e, int which,
                              double cen, double mid, double worst, const ism_analysis *plain)
{
    ism_analysis a = analyse_under(m, t, e);
    if (worst <= e) {
        cr_expect_geq(a.max_dist_centroid, cen * (1 - STATS_TOL), "E %g box %d: the stats' "
                      "farthest centroid %.7f E, the closed form's %.7f E", e, which,
                      a.max_dist_centroid / e, cen / e);
        cr_expect_geq(a.max_dist_midpoint, mid * (1 - STATS_TOL), "E %g box %d: the stats' "
                      "farthest midpoint %.7f E, the closed form's %.7f E", e, which,
                      a.max_dist_midpoint / e, mid / e);
    }
    if (worst > e)
        cr_expect(!stats_met(&a, e), "E %g box %d: the closed form's %.7f E, the stats met", e,
                  which, worst / e);
    else if (worst <= e * (1 - STATS_TOL))
        cr_expect(stats_met(&a, e), "E %g box %d: the closed form's %.7f E, the stats' vertex "
                  "%.7f E, midpoint %.7f E, centroid %.7f E: not met", e, which, worst / e,
                  a.max_dist_vertex / e, a.max_dist_midpoint / e, a.max_dist_centroid / e);
    /* the bound moves only the maxima: the means and 99th percentiles are the same bits */
    cr_expect(memcmp(&a.mean_dist_centroid, &plain->mean_dist_centroid, sizeof(double)) == 0 &&
              memcmp(&a.p99_dist_centroid, &plain->p99_dist_centroid, sizeof(double)) == 0 &&
              memcmp(&a.mean_dist_midpoint, &plain->mean_dist_midpoint, sizeof(double)) == 0 &&
              memcmp(&a.p99_dist_midpoint, &plain->p99_dist_midpoint, sizeof(double)) == 0,
              "E %g box %d: mean/p99 differ from the analysis without a bound", e, which);
    ism_analysis_free(&a);
}

/* The stats of a mesh made under e judged at e (met by the closed forms, which the caller
 * asserted) and at UNMET_SHARE of its farthest point (not met), each against the closed forms
 * and the analysis without a bound (check_stats_under). */
static void check_stats(const ism_mesh *m, const ism_tape *t, double (*dist)(const double *),
                        double e, int which, double cen, double mid)
{
    double worst = fmax(fmax(cen, mid), pf_worst_distance(m, dist));
    ism_analysis plain = analyse_under(m, t, 0);
    check_stats_under(m, t, e, which, cen, mid, worst, &plain);
    check_stats_under(m, t, UNMET_SHARE * fmax(cen, mid), which, cen, mid, worst, &plain);
    ism_analysis_free(&plain);
}

/* t under the bound e, depth 3:SAFETY_DEPTH, in base placed by pf_sweep_box from placement
 * first to 1 (−1 own, 0 the 1e-3 shift, 1 the irrational one: tests/unit/placements.h): every
 * centroid and edge midpoint within e by dist, no cell missed, more than min_tris triangles;
 * with stats, the stats' analysis judged against dist (check_stats). */
static void check_within_stats(const ism_tape *t, const double base[6], int first,
                               double (*dist)(const double *), double e, size_t min_tris,
                               bool stats)
{
    for (int which = first; which <= 1; which++) {
        ism_mesh m;
        ism_poly_stats st;
        run_placed(t, base, which, e, &m, &st);
        cr_assert_gt(m.ntris, min_tris, "E %g box %d: %zu triangles", e, which, m.ntris);
        double cen, mid;
        between_vertices(&m, dist, &cen, &mid);
        cr_expect_leq(cen, e, "E %g box %d: a centroid is %g (%.5f E) from the surface", e,
                      which, cen, cen / e);
        cr_expect_leq(mid, e, "E %g box %d: an edge midpoint is %g (%.5f E) from the surface", e,
                      which, mid, mid / e);
        cr_expect_eq(st.error_missed_nodes, 0, "E %g box %d: %llu cells missed E (worst %g)", e,
                     which, (unsigned long long)st.error_missed_nodes, st.error_worst);
        if (stats)
            check_stats(&m, t, dist, e, which, cen, mid);
        ism_mesh_free(&m);
    }
}

/* check_within_stats without the stats. */
static void check_within(const ism_tape *t, const double base[6], int first,
                         double (*dist)(const double *), double e, size_t min_tris)
{
    check_within_stats(t, base, first, dist, e, min_tris, false);
}

/* s within e in the box ±1.5's three placements (under ISOMESH_TEST_QUICK the irrational
 * one); with stats, the stats judged too (check_stats). */
static void check_bound_stats(const pf_surface *s, double (*dist)(const double *), double e,
                              bool stats)
{
    ism_tape *t = pf_compile(s);
    check_within_stats(t, BOX15, pf_first_box() - 1, dist, e, 1000, stats);
    ism_tape_free(t);
}

static void check_bound(const pf_surface *s, double (*dist)(const double *), double e)
{
    check_bound_stats(s, dist, e, false);
}

Test(accuracy, sphere_within_the_bound) { check_bound_stats(&sphere, sphere_dist, 1e-3, true); }

Test(accuracy, torus_within_the_bound) { check_bound_stats(&torus, torus_dist, 1e-3, true); }

Test(accuracy, sphere_tight_bound) { check_bound(&sphere, sphere_dist, 4e-4); }

/* The issue's test at E = 1e-4 (box ±1.5, depth.max 10 as the safety limit), the primal
 * polygons: about 0.5 s of CPU a box for the sphere, 0.75 s for the torus in release; under
 * ISOMESH_TEST_QUICK the irrational box alone. */
Test(accuracy, sphere_within_1e_4) { check_bound(&sphere, sphere_dist, 1e-4); }

Test(accuracy, torus_within_1e_4) { check_bound(&torus, torus_dist, 1e-4); }

/* Fewest triangles any mesh with its vertices on the unit sphere can have with every
 * centroid within e of it: an inscribed equilateral triangle of side L has its centroid
 * L² / 6 inside, so L² <= 6 e and each covers at most (√3 / 4) 6 e of the area 4π. */
static double sphere_floor(double e) { return 4 * M_PI / (sqrt(3) / 4 * 6 * e); }

/* Under max_error, pentagons and hexagons are fanned from a corner (n − 2 triangles) when
 * that measures within E, not from a centre point (n triangles): at E = 7.9e-4 (marching
 * cubes' centroid distance at 64³ in this box, 17,192 triangles) the sphere takes 17,192
 * (2.81 × the floor) in all three boxes, and within E; centre fans took 21,224 (3.47 ×). */
Test(accuracy, sphere_corner_fans_near_the_floor)
{
    static const double shifts[] = {0, 1e-3 * FINEST, PF_IRR * FINEST};
    const double e = 7.9e-4;
    ism_tape *t = pf_compile(&sphere);
    for (size_t i = (size_t)pf_first_box(); i < sizeof shifts / sizeof shifts[0]; i++) {
        ism_mesh m;
        ism_poly_stats st;
        run_bounded(t, shifts[i], e, SAFETY_DEPTH, &m, &st);
        cr_expect_leq((double)m.ntris, 3 * sphere_floor(e), "shift %g: %zu triangles, floor %.0f",
                      shifts[i], m.ntris, sphere_floor(e));
        double cen, mid;
        between_vertices(&m, sphere_dist, &cen, &mid);
        cr_expect_leq(fmax(cen, mid), e, "shift %g: %g", shifts[i], fmax(cen, mid));
        pf_props pr;
        pf_measure(&m, t, &pr);
        cr_expect_eq(pr.euler, 2);
        cr_expect_eq(pr.boundary_edges + pr.nonmanifold_edges, 0);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* A bound the octree's own estimate misses on the lattice-aligned torus (a fan from a centre
 * that finer neighbours' tiles moved measured 6.3e-4 after one round): the refinement
 * rounds split those leaves until the mesh meets it. The rounds reuse the last round's
 * tree and leaves (test_round_reuse.c): the mesh is the one rounds computed afresh make. */
Test(accuracy, refinement_rounds_meet_what_the_estimate_missed)
{
    static const double shifts[] = {0}; /* where it was seen; the shifted boxes: above */
    ism_tape *t = pf_compile(&torus);
    for (size_t i = 0; i < sizeof shifts / sizeof shifts[0]; i++) {
        ism_mesh m;
        ism_poly_stats st;
        run_bounded(t, shifts[i], 5.97e-4, SAFETY_DEPTH, &m, &st);
        double cen, mid;
        between_vertices(&m, torus_dist, &cen, &mid);
        cr_expect_leq(fmax(cen, mid), 5.97e-4, "shift %g: %g (%llu rounds)", shifts[i],
                      fmax(cen, mid), (unsigned long long)st.error_rounds);
        cr_expect_eq(st.error_missed_nodes, 0);
        cr_expect_gt(st.error_rounds, 1, "shift %g: the rounds to compare", shifts[i]);
        if (!pf_quick()) { /* the sanitizer run compares rounds in test_round_reuse.c */
            ism_mesh fresh;
            ism_poly_stats sf;
            run_rounds(t, shifts[i], 5.97e-4, SAFETY_DEPTH, true, &fresh, &sf);
            pf_same_mesh(&fresh, &m, "torus, rounds afresh and reusing");
            cr_expect_lt(st.evals_gradient, sf.evals_gradient);
            ism_mesh_free(&fresh);
        }
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* Triangles of size h on a curved surface are about h² / R from it, so their number grows
 * like area / E: halving E about doubles it (a volume-like cost would be 2^1.5 or more). */
Test(accuracy, halving_the_bound_about_doubles_the_triangles)
{
    ism_tape *t = pf_compile(&sphere);
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        size_t prev = 0;
        for (double e = 4e-3; e >= 1e-3; e /= 2) {
            ism_mesh m;
            ism_poly_stats st;
            run_placed(t, BOX15, which, e, &m, &st);
            if (prev)
                cr_expect(m.ntris <= 4 * prev && m.ntris > prev,
                          "box %d E %g: %zu triangles after %zu at 2E", which, e, m.ntris, prev);
            prev = m.ntris;
            ism_mesh_free(&m);
        }
    }
    ism_tape_free(t);
}

/* A bound the safety depth cannot reach: the cells stopped there are counted, with the
 * worst distance the octree measured on them, and that distance is above E. */
Test(accuracy, safety_depth_counts_what_it_stopped)
{
    ism_tape *t = pf_compile(&torus);
    ism_mesh m;
    ism_poly_stats st;
    run_bounded(t, PF_IRR * FINEST, 1e-4, 5, &m, &st);
    cr_expect_gt(st.error_missed_nodes, 0);
    cr_expect_gt(st.error_worst, 1e-4);
    double cen, mid;
    between_vertices(&m, torus_dist, &cen, &mid);
    cr_expect_gt(fmax(cen, mid), 1e-4, "the mesh met a bound the octree said it missed");
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* max_error = 0 is the depth-driven flatness test, bit for bit as before the bound existed:
 * the sphere at depth 3:7 in the +-1.5 box (5,192 triangles, the count the issue reported). */
Test(accuracy, no_bound_keeps_the_depth_driven_mesh)
{
    ism_tape *t = pf_compile(&sphere);
    ism_mesh m;
    ism_poly_stats st;
    run_bounded(t, 0, 0, 7, &m, &st);
    cr_expect_eq(m.ntris, 5192);
    cr_expect_eq(st.error_missed_nodes, 0);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* The gyroid ball's crease, where max() switches from the gyroid to the ball: the solid's
 * wedge pokes through cell edges (two roots) and faces (four crossings) at every level, so
 * a cell there was split down to depth.max whatever E asked (depth 8: 47,096 triangles,
 * depth 10: 101,900 at E = 0.0334). Now a cell at most 4 E across is judged by what it
 * emits: E, not depth.max, sets the mesh (depth 10 within 1.25x of depth 8; 1.07x
 * measured), every centroid and edge midpoint lies within E of f = 0 — proved without
 * |f| / |∇f|: a point of the other sign within E along one of the two branches' gradients
 * or the 26 lattice directions — and the topology stays the gyroid ball's (χ −18, one
 * closed component). */
static const ism_param gyroid_k[] = {{"k", 4}};
static const pf_surface gyroid_ball = {
    "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
    gyroid_k, 1, NULL, 0};
static const pf_surface gyroid_part = {
    "sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x)", gyroid_k, 1, NULL, 0};
static const pf_surface ball_part = {"x^2 + y^2 + z^2 - 1.96", NULL, 0, NULL, 0};
#define CREASE_E 0.0334 /* bench_accuracy's 64³ marching cubes distance on this surface */

typedef struct within_e {
    const ism_tape *f, *branch[2];
    ism_eval_ws *ws, *bws[2];
} within_e;

/* A point of f's other sign (or a zero) within e of p: f = 0 lies within e of p. */
static bool zero_within(within_e *w, const double p[3], double e)
{
    double fp = ism_eval_point(w->f, w->ws, p[0], p[1], p[2]);
    if (fp == 0)
        return true;
    double dirs[2 + 26][3];
    int n = 0;
    for (int b = 0; b < 2; b++) {
        double g[3];
        ism_eval_gradient(w->branch[b], w->bws[b], p[0], p[1], p[2], g);
        double gl = sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        if (gl > 0)
            for (int a = 0; a < 3; a++)
                dirs[n][a] = g[a] / gl;
        n += gl > 0;
    }
    for (int i = 0; i < 27; i++) {
        int d[3] = {i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1};
        double l = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
        if (l > 0)
            for (int a = 0; a < 3; a++)
                dirs[n][a] = d[a] / l;
        n += l > 0;
    }
    for (int i = 0; i < n; i++)
        for (int s = -1; s <= 1; s += 2) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = p[a] + s * e * dirs[i][a];
            double fq = ism_eval_point(w->f, w->ws, q[0], q[1], q[2]);
            if ((fq <= 0) != (fp < 0) || fq == 0)
                return true;
        }
    return false;
}

/* The gyroid ball and its two branches, compiled, with their workspaces. */
static within_e within_e_open(void)
{
    within_e w = {pf_compile(&gyroid_ball), {pf_compile(&gyroid_part), pf_compile(&ball_part)},
                  NULL, {NULL, NULL}};
    w.ws = ism_eval_ws_new(w.f);
    for (int b = 0; b < 2; b++)
        w.bws[b] = ism_eval_ws_new(w.branch[b]);
    return w;
}

static void within_e_close(within_e *w)
{
    for (int b = 0; b < 2; b++) {
        ism_eval_ws_free(w->bws[b]);
        ism_tape_free((ism_tape *)w->branch[b]);
    }
    ism_eval_ws_free(w->ws);
    ism_tape_free((ism_tape *)w->f);
}

static double gyroid_ball_dist(const double q[3]);

/* Triangles whose centroid or an edge midpoint has no zero proved within e: by a point of
 * the other sign, or by a point of f = 0 found from the pieces' closed forms (below; a step
 * across a thin wedge of the solid, where the gyroid meets the ball at 21° in places, crosses
 * both its sides and comes back to the sign it left: 6 of 36,422 triangles at E = 3e-3 in the
 * irrational box, all within 0.9998 E by the closed forms). */
static size_t far_triangles(within_e *w, const ism_mesh *m, double e)
{
    size_t far = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double pts[4][3];
        between_points(m, t, pts);
        bool ok = true;
        for (int k = 0; k < 4 && ok; k++)
            ok = zero_within(w, pts[k], e) || gyroid_ball_dist(pts[k]) <= e;
        far += !ok;
    }
    return far;
}

/* The gyroid ball's mesh m (stats st) within e: no cell missed it, every centroid and edge
 * midpoint proved within e, χ −18 in one closed piece. */
static void expect_gyroid_ball_within(within_e *w, const ism_mesh *m, const ism_poly_stats *st,
                                      double e, double shift)
{
    cr_expect_eq(st->error_missed_nodes, 0, "shift %g: %llu cells missed E", shift,
                 (unsigned long long)st->error_missed_nodes);
    size_t far = far_triangles(w, m, e);
    cr_expect_eq(far, 0, "shift %g: %zu of %zu triangles farther than E", shift, far, m->ntris);
    pf_props pr;
    pf_measure(m, w->f, &pr);
    cr_expect_eq(pr.euler, -18, "shift %g: χ %ld", shift, pr.euler);
    cr_expect_eq(pr.components, 1, "shift %g", shift);
    cr_expect_eq(pr.boundary_edges + pr.nonmanifold_edges, 0, "shift %g", shift);
}

Test(accuracy, crease_does_not_set_the_depth)
{
    static const double shifts[] = {0, 1e-3 * FINEST, PF_IRR * FINEST};
    within_e w = within_e_open();
    const ism_tape *t = w.f;
    for (size_t i = (size_t)pf_first_box(); i < sizeof shifts / sizeof shifts[0]; i++) {
        ism_mesh m;
        ism_poly_stats st;
        run_bounded(t, shifts[i], CREASE_E, SAFETY_DEPTH, &m, &st);
        expect_gyroid_ball_within(&w, &m, &st, CREASE_E, shifts[i]);
        if (i == 2) { /* the depth comparison, off the lattice */
            ism_mesh coarse;
            ism_poly_stats sc;
            run_bounded(t, shifts[i], CREASE_E, SAFETY_DEPTH - 2, &coarse, &sc);
            cr_expect_leq(m.ntris * 4, coarse.ntris * 5, "depth %d: %zu triangles, depth %d: %zu",
                          SAFETY_DEPTH, m.ntris, SAFETY_DEPTH - 2, coarse.ntris);
            ism_mesh_free(&coarse);
        }
        ism_mesh_free(&m);
    }
    within_e_close(&w);
}

/* Cut along the crease (crease_split.h), a cell straddling it is as good as its branches:
 * the gyroid ball meets E = 3e-3 at depth.max 9 (finest cell 0.0059, about 2 E), every
 * centroid and edge midpoint proved within E as above, χ −18 in one closed piece. Folded
 * across the crease, its triangles were about a cell's width off it: main missed E on 27
 * cells there (max centroid distance 3.4e-3; 1,131 cells at depth 8). */
Test(accuracy, crease_cut_meets_the_bound_above_the_crease_depth)
{
    static const double shifts[] = {0, 1e-3 * FINEST, PF_IRR * FINEST};
    within_e w = within_e_open();
    const ism_tape *t = w.f;
    for (size_t i = (size_t)pf_first_box(); i < sizeof shifts / sizeof shifts[0]; i++) {
        ism_mesh m;
        ism_poly_stats st;
        run_bounded(t, shifts[i], 3e-3, 9, &m, &st);
        expect_gyroid_ball_within(&w, &m, &st, 3e-3, shifts[i]);
        ism_mesh_free(&m);
    }
    within_e_close(&w);
}

/* The gyroid ball at E = 1e-4 (the issue's test, box ±1.5, depth.max 10): every centroid and
 * edge midpoint within E of f = 0, by distances computed here from the two pieces' closed
 * forms, not from f's tape. f = max(g, s) with g the gyroid and s = |p|² − 1.96: f = 0 is the
 * gyroid where s ≤ 0, the sphere |p| = 1.4 where g ≤ 0, and their crease g = s = 0. A point's
 * distance is bounded above by its distance to any point of f = 0: the sphere's radial foot
 * (where g ≤ 0 there), the gyroid's foot by Newton along ∇g (where s ≤ 0), the crease point
 * by minimum-norm Newton on (g, s); the smallest of those found counts, none found counts as
 * infinitely far. Before a short edge's crease point could lie as far as the solid's wedge
 * puts it (crease_split.c), an edge crossing both sides of a thin wedge (21-52° there) kept
 * a point on one branch and its triangles were up to 10 E off at depth 10 and at depth 12
 * alike (1,467 cells missed E at depth 10, 1,391 in the irrational box: this test failed in
 * all three boxes; with two edges' reach, b9322d1, still 54 cells and 3.76 E in the own box);
 * now 657,094 / 661,742 / 661,382 triangles (685,038 at first in the own box), none missed,
 * the farthest 0.9999 E. About 8 s of CPU a box: under ISOMESH_TEST_QUICK
 * (the sanitizer build, 5-10x slower) it is skipped — crease_split's paths run there in the
 * coarser crease tests above. */
#define GYROID_K 4.0
#define BALL_R2 1.96

static double gyroid_grad(const double p[3], double g[3])
{
    double sx = sin(GYROID_K * p[0]), cx = cos(GYROID_K * p[0]);
    double sy = sin(GYROID_K * p[1]), cy = cos(GYROID_K * p[1]);
    double sz = sin(GYROID_K * p[2]), cz = cos(GYROID_K * p[2]);
    g[0] = GYROID_K * (cx * cy - sz * sx);
    g[1] = GYROID_K * (cy * cz - sx * sy);
    g[2] = GYROID_K * (cz * cx - sy * sz);
    return sx * cy + sy * cz + sz * cx;
}

static double ball_value(const double p[3]) { return p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - BALL_R2; }

/* Newton steps on the pieces: quadratic convergence from within a cell reaches rounding in
 * 4-6; a foot whose residual is still above FOOT_TOL is not counted. */
#define FOOT_STEPS 12
#define FOOT_TOL 1e-12

static double gyroid_ball_dist(const double q[3])
{
    double best = INFINITY, x[3], g[3];
    double r = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
    for (int a = 0; a < 3; a++)
        x[a] = q[a] * sqrt(BALL_R2) / r;
    if (gyroid_grad(x, g) <= 0)
        best = fabs(r - sqrt(BALL_R2));
    memcpy(x, q, sizeof x);
    double v = 1;
    for (int it = 0; it < FOOT_STEPS; it++) {
        v = gyroid_grad(x, g);
        double gg = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        for (int a = 0; a < 3; a++)
            x[a] -= v * g[a] / gg;
    }
    if (fabs(gyroid_grad(x, g)) < FOOT_TOL && ball_value(x) <= 0)
        best = fmin(best, ism_dist3(x, q));
    memcpy(x, q, sizeof x);
    for (int it = 0; it < FOOT_STEPS; it++) { /* (g, s) = 0: x −= J^T (J J^T)^-1 (g, s) */
        double vg = gyroid_grad(x, g), vs = ball_value(x), b[3] = {2 * x[0], 2 * x[1], 2 * x[2]};
        double aa = g[0] * g[0] + g[1] * g[1] + g[2] * g[2], bb = b[0] * b[0] + b[1] * b[1] +
               b[2] * b[2], ab = g[0] * b[0] + g[1] * b[1] + g[2] * b[2], det = aa * bb - ab * ab;
        if (!(det > 0))
            break;
        double l0 = (bb * vg - ab * vs) / det, l1 = (aa * vs - ab * vg) / det;
        for (int a = 0; a < 3; a++)
            x[a] -= l0 * g[a] + l1 * b[a];
    }
    if (fabs(gyroid_grad(x, g)) < FOOT_TOL && fabs(ball_value(x)) < FOOT_TOL)
        best = fmin(best, ism_dist3(x, q));
    return best;
}

Test(accuracy, gyroid_ball_tight_bound_by_its_pieces)
{
    if (pf_quick())
        cr_skip_test("about 8 s of CPU a box in release: not under the sanitizer");
    ism_tape *t = pf_compile(&gyroid_ball);
    check_within(t, BOX15, -1, gyroid_ball_dist, 1e-4, 100000);
    ism_tape_free(t);
}

/* The gyroid ball at E = 1e-3 (the issue's other bound; box ±1.5, depth.max 10), by the same
 * closed-form distances.
 * In the own box six edge midpoints (one by the gyroid's symmetry, e.g. of
 * (−0.140625, −0.140625, −0.761782)–(−0.1875, −0.17224949, −0.75)) lay just beyond E from
 * f = 0 (audit15: no zero within 1.00005 E of it on 400,000 rays), far from the crease (|p| 0.79),
 * while the octree and the stats measured it within E and "met" (the figures:
 * core/util/dist_bound.h, ISM_FIRST_ORDER_SURE): the first-order |f| / |∇f| falls short there
 * by the gyroid's curvature term. Both now measure an estimate just within E a Newton step
 * further (ism_stepped_dist). The stats judged too (check_stats). About 1 s of CPU a box;
 * under ISOMESH_TEST_QUICK the irrational box alone. */
Test(accuracy, gyroid_ball_within_1e_3_by_its_pieces)
{
    ism_tape *t = pf_compile(&gyroid_ball);
    check_within_stats(t, BOX15, pf_first_box() - 1, gyroid_ball_dist, 1e-3, 50000, true);
    ism_tape_free(t);
}

/* Cube-minus-ball at E = 1e-4 (box ±1.3, depth.max 10): f = max(c, b) with the cube
 * c = max(|x|, |y|, |z|) − 1 and the ball b = 1.69 − |p|². f = 0 is the cube's surface outside
 * the ball and the sphere |p| = 1.3 inside the cube; a point's distance is bounded above by its
 * distance to the nearest point of the cube's surface (the face of its largest coordinate
 * inside the cube, the clamp onto [−1, 1]³ outside) where that lies outside the ball, to its
 * radial foot on the sphere where that lies inside the cube, and to the nearest point of the
 * six crease circles (radius √0.69 on the faces). The crease circle met E since fold19/e4_19;
 * the cube's own edges and corners — creases of the cube's inner max, below f's top one — did
 * not: crease_split cut along f's top max only, so the triangles across an edge folded, about
 * half a depth-10 cell off at any bound (14.3 E at centroids, 10.7 E at midpoints, 9,440 cells
 * missed in the own box: this test failed there). Now cut along every piece's crease and at
 * three-piece corners (the cube's corners): 191,528 / 207,670 / 207,796 triangles, none
 * missed, the farthest 0.9979 E (centroid) and 0.9998 E (midpoint). About 1 s of CPU a box;
 * under ISOMESH_TEST_QUICK the irrational box alone. */
#define CMB_R 1.3

static double cube_minus_ball_dist(const double q[3])
{
    double best = INFINITY, f[3];
    double m = fmax(fabs(q[0]), fmax(fabs(q[1]), fabs(q[2])));
    memcpy(f, q, sizeof f);
    if (m <= 1) { /* inside the cube: the face of the largest coordinate */
        int a = fabs(q[0]) == m ? 0 : fabs(q[1]) == m ? 1 : 2;
        f[a] = q[a] < 0 ? -1 : 1;
    } else {
        for (int k = 0; k < 3; k++)
            f[k] = fmax(-1, fmin(1, q[k]));
    }
    if (ism_dot3(f, f) >= CMB_R * CMB_R)
        best = ism_dist3(f, q);
    double r = ism_norm3(q);
    for (int k = 0; k < 3; k++)
        f[k] = q[k] * CMB_R / r;
    if (fmax(fabs(f[0]), fmax(fabs(f[1]), fabs(f[2]))) <= 1)
        best = fmin(best, fabs(r - CMB_R));
    double rho = sqrt(CMB_R * CMB_R - 1);
    for (int a = 0; a < 3; a++)
        for (int sg = -1; sg <= 1; sg += 2) { /* the circle on the face x_a = sg */
            int b = (a + 1) % 3, c = (a + 2) % 3;
            double l = hypot(q[b], q[c]), x[3];
            x[a] = sg;
            x[b] = l > 0 ? rho * q[b] / l : rho;
            x[c] = l > 0 ? rho * q[c] / l : 0;
            best = fmin(best, ism_dist3(x, q));
        }
    return best;
}

Test(accuracy, cube_minus_ball_tight_bound_by_its_pieces)
{
    static const pf_surface cmb = {"max(max(abs(x), abs(y), abs(z)) - 1, 1.69 - (x^2 + y^2 + z^2))",
                                   NULL, 0, NULL, 0};
    static const double base[6] = {-CMB_R, -CMB_R, -CMB_R, CMB_R, CMB_R, CMB_R};
    ism_tape *t = pf_compile(&cmb);
    check_within(t, base, pf_first_box() - 1, cube_minus_ball_dist, 1e-4, 100000);
    ism_tape_free(t);
}
