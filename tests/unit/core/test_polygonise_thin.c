/* test_polygonise_thin.c — pieces of the surface thinner than a cell (issue 13, item 5):
 * nothing lost, nothing flattened. Every expected value comes from a closed form: the area of
 * a tube (2πrL), the Euler characteristic of a sphere (2), of the horn cyclide (a torus whose
 * meridian shrinks to one point: χ = 0 − 0 + 1 = 1; a box face cutting its outermost cap off
 * leaves one boundary loop and χ = 0). Boxes: symmetric, and shifted off the lattice by 1e-3
 * and by √2 − 1 of a finest cell. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "core/octree/octree_build.h"
#include "core/octree/thin_search.h"
#include "core/singular/check.h"
#include "core/singular/surface.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/core/test_eval_surfaces.h"

static void shifted(const double base[6], double s, double box[6])
{
    for (int k = 0; k < 6; k++)
        box[k] = base[k] + s;
}

static double shift_of(int which, const double base[6], int dmax)
{
    return which == 0 ? 0 : which == 1 ? 1e-3 : PF_IRR * pf_cell(base, dmax);
}

/* pf_run with the hidden-piece search on; coarse: the live preview's search
 * (ism_poly_options.thin_coarse). */
static void pf_run_search(const ism_tape *t, const double box[6], int dmax, bool coarse,
                          ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.min_depth = 3;
    o.max_depth = dmax;
    o.threads = 2;
    o.thin_search = true;
    o.thin_coarse = coarse;
    ism_mesh_init(m);
    ism_error err;
    cr_assert_eq(ism_polygonise(t, &o, m, st, &err), ISM_POLY_OK, "%s", err.message);
}

static void pf_run_thin(const ism_tape *t, const double box[6], int dmax, ism_mesh *m,
                        ism_poly_stats *st)
{
    pf_run_search(t, box, dmax, false, m, st);
}

static void analyse(const ism_mesh *m, const ism_tape *t, ism_analysis *a)
{
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = ao.accuracy = false;
    ao.threads = 2;
    ism_error err;
    cr_assert(ism_analyse(m, t, &ao, a, &err), "analyse: %s", err.message);
}

/* The largest distance from the tube of radius R about the axis (y0, z0) to a triangle's
 * centroid or edge midpoints, |√((y − y0)² + (z − z0)²) − R| (exact). */
static double tube_worst(const ism_mesh *m, double y0, double z0, double R)
{
    double worst = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        const double *v[3];
        for (int c = 0; c < 3; c++)
            v[c] = m->pos + 3 * (size_t)m->tri[3 * t + c];
        double q[4][3];
        for (int k = 0; k < 3; k++) {
            q[3][k] = (v[0][k] + v[1][k] + v[2][k]) / 3;
            for (int c = 0; c < 3; c++)
                q[c][k] = 0.5 * (v[c][k] + v[(c + 1) % 3][k]);
        }
        for (int i = 0; i < 4; i++)
            worst = fmax(worst, fabs(hypot(q[i][1] - y0, q[i][2] - z0) - R));
    }
    return worst;
}

/* The tube's area deficit bound at depth d: 2% (the issue's), or, where the cells the
 * resolve reaches (ISM_THIN_RESOLVE_LEVELS below d) are wider than R / 2, the deficit of the
 * regular polygon inscribed in the section whose sides are one such cell h:
 * 1 − sin(θ) / θ with sin θ = h / 2R (depth 6: h = 0.0039, R / h = 1.02, 4.3%). The
 * inscribed 4-gon of one cell's lattice crossings (what a lattice line inside the tube gave
 * at depths 6–8) lies far outside: −12.57% off-centre, −9.97% on the line. The worst
 * centroid or edge midpoint lies within the sag of a chord one such cell's face diagonal
 * long, R − √(R² − h² / 2) (0.27 R at depth 6), and never needs more than R / 4 elsewhere
 * (leaves the flatness test passed above the finest level hold longer chords); the 4-gon's
 * sag was 0.57 R. */
static void tube_bounds(int d, double R, double *area_rel, double *dist)
{
    double h = 2.0 / (1 << (d + ISM_THIN_RESOLVE_LEVELS)), th = asin(h / (2 * R));
    *area_rel = fmax(0.02, 1 - sin(th) / th);
    *dist = fmax(R - sqrt(fmax(R * R - h * h / 2, 0)), 0.25 * R);
}

/* A tube of radius R along the x axis, its axis at (y0, z0), in the box ±1 (shifted), at
 * depths 6, 7 and 8 (a cell 3.9, 2.0 and 1.0 of the tube's diameters wide: one cell can
 * hold its section). */
static void check_tube(double y0, double z0, const char *name)
{
    const double R = 0.004, base[6] = {-1, -1, -1, 1, 1, 1};
    char expr[128];
    snprintf(expr, sizeof expr, "(y - %.17g)^2 + (z - %.17g)^2 - %.17g^2", y0, z0, R);
    pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    double want = 2 * M_PI * R * 2; /* the lateral area of a cylinder of length 2 */
    for (int dmax = 6; dmax <= 8; dmax++)
        for (int w = 0; w < 3; w++) {
            double box[6], area_rel, dist;
            shifted(base, shift_of(w, base, dmax), box);
            tube_bounds(dmax, R, &area_rel, &dist);
            ism_mesh m;
            ism_poly_stats st;
            pf_run_thin(t, box, dmax, &m, &st);
            ism_analysis a;
            analyse(&m, t, &a);
            /* where a lattice line runs inside the tube (PF_IRR off-centre, the own box on a
             * line) its cells see it (their corners differ in sign) and held one side each
             * of a 4-gon inscribed in the section; their corner gradients turn apart, and
             * such leaves are resolved as deep as a hidden tube (octree_build.c
             * visible_feature) */
            cr_expect_leq(fabs(a.area - want), area_rel * want,
                          "%s, depth %d shift %d: area %g, want %g (%.2f%%, bound %.2f%%)", name,
                          dmax, w, a.area, want, 100 * (a.area / want - 1), 100 * area_rel);
            double worst = tube_worst(&m, y0, z0, R);
            cr_expect_leq(worst, dist, "%s, depth %d shift %d: a centroid or midpoint %g off, bound %g",
                          name, dmax, w, worst, dist);
            cr_expect_eq(a.nonmanifold_edges, 0, "%s, depth %d shift %d: %zu non-manifold edges",
                         name, dmax, w, a.nonmanifold_edges);
            cr_expect_eq(a.boundary_loops, 2, "%s, depth %d shift %d: %zu boundary loops", name,
                         dmax, w, a.boundary_loops);
            cr_expect_eq(a.components, 1, "%s, depth %d shift %d: %zu components", name, dmax, w,
                         a.components);
            ism_analysis_free(&a);
            ism_mesh_free(&m);
        }
    ism_tape_free(t);
}

/* The tube inside one row of depth-7 cells (its axis at a cell's centre): no cell edge
 * sees it (the mesh was empty). */
Test(thin, tube_inside_one_row_of_cells)
{
    double h = 2.0 / 128;
    check_tube(0.5 * h, 0.5 * h, "tube off-centre");
}

/* The tube centred on the lattice plane z = 0: both cells beside the plane saw the same
 * flat strip (a doubly covered ribbon, 127 non-manifold edges, area 0.032). */
Test(thin, tube_centred_on_a_lattice_plane)
{
    double h = 2.0 / 128;
    check_tube(0.5 * h, 0, "tube on a plane");
}

/* The tube's axis on the lattice line y = z = 0 (own box): the four cells round it held an
 * inscribed square (area 2√2/π − 1 = −9.97%), their corners on the axis a zero gradient. */
Test(thin, tube_on_a_lattice_line)
{
    check_tube(0, 0, "tube on a line");
}

/* A sphere of radius 0.3 cell centred at c (in cells from the box's lower corner); coarse:
 * with the preview's search (no resolve levels: the area is not checked). */
static void check_small_sphere(const double c_cells[3], bool coarse, const char *name)
{
    const double base[6] = {-1, -1, -1, 1, 1, 1};
    const int dmax = 7;
    double h = pf_cell(base, dmax), r = 0.3 * h, c[3];
    for (int k = 0; k < 3; k++)
        c[k] = base[k] + c_cells[k] * h;
    char expr[160];
    snprintf(expr, sizeof expr, "(x - %.17g)^2 + (y - %.17g)^2 + (z - %.17g)^2 - %.17g^2", c[0],
             c[1], c[2], r);
    pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    for (int w = 0; w < 3; w++) {
        double box[6];
        shifted(base, shift_of(w, base, dmax), box);
        ism_mesh m;
        ism_poly_stats st;
        pf_run_search(t, box, dmax, coarse, &m, &st);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.euler, 2, "%s, shift %d: χ = %ld", name, w, p.euler);
        cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0,
                     "%s, shift %d: %zu boundary, %zu non-manifold edges", name, w,
                     p.boundary_edges, p.nonmanifold_edges);
        cr_expect_eq(p.components, 1, "%s, shift %d: %zu components", name, w, p.components);
        if (!coarse) /* at PF_IRR a lattice corner is inside: its 8 cells held an octahedron
                        (−52% at √2 − 1 cell) until their turned corner gradients resolved them */
            cr_expect_leq(fabs(p.area - 4 * M_PI * r * r), 0.25 * 4 * M_PI * r * r,
                          "%s, shift %d: area %g, sphere %g", name, w, p.area, 4 * M_PI * r * r);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

Test(thin, small_sphere_inside_one_cell)
{
    check_small_sphere((const double[3]){64.5, 63.5, 70.5}, false, "sphere in a cell");
}

/* Centred on a face's centre: the face cuts it in a circle of radius 0.3 cell, 0.5 cell
 * from the face's edges (an island in the face, seen by neither cell). */
Test(thin, small_sphere_straddling_a_face)
{
    check_small_sphere((const double[3]){64, 63.5, 70.5}, false, "sphere on a face");
}

/* The live preview's coarse search (whole cells of one corner sign, no resolve levels) finds
 * both spheres too, closed and in one piece. */
Test(thin, small_spheres_coarse_search)
{
    check_small_sphere((const double[3]){64.5, 63.5, 70.5}, true, "sphere in a cell, coarse");
    check_small_sphere((const double[3]){64, 63.5, 70.5}, true, "sphere on a face, coarse");
}

/* The horn cyclide a = 10, r = f = 2 (test_singular_points.c derives its one singular point,
 * (10, 0, 0), where the horns' tube (u + 5y²/96)² + z² = (y²/96)² shrinks to nothing). The
 * surface is a torus with one meridian pinched to a point: χ = 1, in one piece, and nothing
 * non-manifold but the point. Its box [−15, 17] × [−16, 16]² keeps the cap at x = −14 inside
 * (the paper's −14 touched it: a shift toward +x cut the cap off). */
/* The mesh of the horn cyclide in box (depths 3..dmax, under max_error when > 0: 0 none), its
 * facts checked; what: the run's name in messages. */
/* The service's mesh of the horn cyclide t in box, depths 3..dmax, max_error (0: none), on two
 * threads with the hidden-piece search; m and l are initialised here. */
static void horn_mesh(const ism_tape *t, const double box[6], int dmax, double max_error,
                      ism_mesh *m, ism_locus *l, ism_poly_stats *ps, ism_conform_stats *cs)
{
    ism_poly_options po;
    ism_poly_options_default(&po);
    memcpy(po.box, box, sizeof po.box);
    po.min_depth = 3;
    po.max_depth = dmax;
    po.threads = 2;
    po.thin_search = true;
    po.max_error = max_error;
    ism_mesh_init(m);
    ism_locus_init(l);
    ism_surface_times times;
    ism_error err;
    cr_assert_eq(ism_mesh_surface(t, &po, m, l, ps, cs, &times, &err), ISM_POLY_OK, "%s",
                 err.message);
}

static void check_horn_in(const double box[6], int dmax, double max_error, const char *what)
{
    const test_surface *hs = &TEST_SURFACES[6];
    cr_assert_str_eq(hs->name, "horn-cyclide");
    ism_tape *t = test_surface_compile(hs);
    ism_mesh m;
    ism_locus l;
    ism_poly_stats ps;
    ism_conform_stats cs;
    horn_mesh(t, box, dmax, max_error, &m, &l, &ps, &cs);
    ism_analysis a;
    analyse(&m, t, &a);
    ism_locus_check chk;
    ism_error err;
    cr_assert(ism_locus_check_mesh(&l, box, &m, &a, &chk, &err), "check: %s", err.message);
    cr_expect_eq(a.euler, 1, "%s: χ = %ld", what, a.euler);
    cr_expect_eq(a.components, 1, "%s: %zu components", what, a.components);
    cr_expect_eq(a.boundary_edges, 0, "%s: %zu boundary edges", what, a.boundary_edges);
    cr_expect_eq(chk.nonmanifold_edges_off + chk.nonmanifold_points_off, 0,
                 "%s: artefacts %zu + %zu", what, chk.nonmanifold_edges_off,
                 chk.nonmanifold_points_off);
    ism_locus_check_free(&chk);
    cr_expect_eq(cs.points_conformed, 1, "%s: %zu points conformed", what, cs.points_conformed);
    /* under a bound most searches are the blind leaves' Newton probes (octree_build.c), which
     * cannot exclude a piece: one that finds nothing is no undecided search. Own box, depth
     * 8, E 0.064 / 0.016: 0 / 64 undecided of 2,204 / 3,724 searches (84 / 308 found);
     * 2,064 / 2,392 while empty probes counted */
    if (max_error > 0)
        cr_expect_leq(4 * ps.thin_undecided, ps.thin_searched - ps.thin_found,
                      "%s: %llu of %llu searches undecided (%llu found)", what,
                      (unsigned long long)ps.thin_undecided,
                      (unsigned long long)ps.thin_searched, (unsigned long long)ps.thin_found);
    /* the point joined: one non-manifold vertex, at (10, 0, 0), where the two horns' cones
     * meet */
    cr_expect_eq(a.npoints, 1, "%s: %zu non-manifold points", what, a.npoints);
    if (a.npoints == 1) {
        const double *q = a.point_pos;
        cr_expect_lt(fabs(q[0] - 10) + fabs(q[1]) + fabs(q[2]), 1e-9, "%s: point at %g %g %g",
                     what, q[0], q[1], q[2]);
        cr_expect_eq(pf_vertex_cones(&m, a.points[0]), 2, "%s: %zu cones at the point", what,
                     pf_vertex_cones(&m, a.points[0]));
    }
    ism_analysis_free(&a);
    ism_locus_free(&l);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

static void check_horn(int dmax, int w)
{
    const test_surface *hs = &TEST_SURFACES[6];
    double box[6];
    shifted(hs->box, shift_of(w, hs->box, dmax), box);
    char what[64];
    snprintf(what, sizeof what, "depth %d shift %d", dmax, w);
    check_horn_in(box, dmax, 0, what);
}

Test(thin, horn_cyclide_depth_6, .timeout = 120)
{
    for (int w = pf_first_box(); w < 3; w++)
        check_horn(6, w);
}

Test(thin, horn_cyclide_depth_7, .timeout = 120)
{
    for (int w = pf_first_box(); w < 3; w++)
        check_horn(7, w);
}

/* 0.37 of a cell off the lattice at depth 8 the horns' tube (radius y²/96) passes between
 * lattice lines down to the conformance ball, 0.31 from the point, where it is 0.001 across:
 * 1/16 of a cell 3 levels down (the chase followed it only that far: a hole). */
Test(thin, horn_cyclide_depth_8, .timeout = 120)
{
    if (!pf_quick())
        check_horn(8, 2);
}

/* Under an error bound the nodes near the point are judged by their measured polygons alone
 * once at most 4 E across (plot_test.c), their corner gradients unread, and a node with no
 * polygon (corners of one sign) measures nothing: the horns, thinner than E within 1.26 of
 * the point (y²/96 < 0.016), passed unseen through such nodes until octree_build.c searched
 * them (ism_plot_test's blind, grow). At E = 2e-3 and 5e-4 of the box's 32 (0.064, 0.016),
 * depth 8, in the box moved by irrational fractions of a cell the horns ended ~1 from the
 * point in open loops, the point not joined (χ 2 with no non-manifold point; χ 3 in 3
 * pieces, 2 loops); the own and 1e-3 placements were right. Each must give what the closed
 * form does, as without a bound. The own box at E 0.064 also guards plot_test.c's
 * GRAPH_HALVES_ERRORS (16): with the graph proof on halves up to 32 E (or at every size)
 * graph_node_passes passed curved nodes 2 across whose polygons left 4 non-manifold edges and
 * 5 non-manifold points there (4 + 4 artefacts; the other placements and E 0.016 stayed
 * clean), so a quick run keeps that case beside its usual irrational placement. */
Test(thin, horn_cyclide_under_a_bound, .timeout = 120)
{
    const test_surface *hs = &TEST_SURFACES[6];
    const int dmax = 8;
    const double rel[2] = {2e-3, 5e-4};
    for (int w = -1; w < 2; w++)
        for (int e = 0; e < 2; e++) {
            if (w < pf_first_box() - 1 && !(w == -1 && e == 0))
                continue; /* quick: placement 1, and the own box at E 0.064 */
            double box[6];
            pf_sweep_box(hs->box, dmax, w, box);
            char what[96];
            snprintf(what, sizeof what, "depth %d placement %d E %g of the box", dmax, w, rel[e]);
            check_horn_in(box, dmax, rel[e] * (box[3] - box[0]), what);
        }
}

/* The horn cyclide is the Dupin cyclide a = 10, c = μ = 2 (b² = a² − c² = 96): the envelope
 * of the spheres centred on the ellipse (a cos t, b sin t, 0) of radius μ − c cos t, which
 * vanishes at t = 0, the point (10, 0, 0). Each sphere touches the surface along a circle, so
 * the distance from p to the surface is |min over t of |p − centre(t)| − radius(t)| (outside:
 * the nearest sphere; inside: the largest ball round p within one sphere). The minimum over t:
 * 512 samples, then golden sections round the best three (a thin horn's minimum is sharp). */
static double horn_s(const double p[3], double t)
{
    const double a = 10, b = sqrt(96.0), c = 2, mu = 2;
    double d[3] = {p[0] - a * cos(t), p[1] - b * sin(t), p[2]};
    return sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) - (mu - c * cos(t));
}

static double horn_dist(const double p[3])
{
    enum { N = 512 };
    const double step = 2 * M_PI / N, g = (sqrt(5.0) - 1) / 2;
    double best[3] = {INFINITY, INFINITY, INFINITY}, at[3] = {0, 0, 0};
    for (int i = 0; i < N; i++) {
        double t = -M_PI + i * step, v = horn_s(p, t);
        for (int k = 0; k < 3; k++)
            if (v < best[k]) {
                for (int j = 2; j > k; j--)
                    best[j] = best[j - 1], at[j] = at[j - 1];
                best[k] = v, at[k] = t;
                break;
            }
    }
    double m = best[0];
    for (int k = 0; k < 3; k++) {
        double lo = at[k] - step, hi = at[k] + step;
        for (int it = 0; it < 60; it++) {
            double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
            if (horn_s(p, x1) < horn_s(p, x2))
                hi = x2;
            else
                lo = x1;
        }
        m = fmin(m, horn_s(p, 0.5 * (lo + hi)));
    }
    return fabs(m);
}

/* At its default bound E = 1e-3 × the box's diagonal (0.0554), depth.max 10, the horn cyclide
 * met E everywhere by the canal form above (worst 0.0550 at a midpoint 17 from the point) but
 * its own measurement said 0.0623, "not met", 8 leaves short at depth 10: at edge midpoints
 * across the horns' tube (radius y²/96 = 0.0155 at y = ±1.22) near its core line, where ∇f
 * vanishes and |f| / |∇f| overstates the distance (0.0137 by the canal form) 4.5 times. The
 * polygoniser and the analysis now cap the estimate by the bound through the element's
 * corners (core/util/dist_bound.h). In the three placements: no leaf missed E, the analysis'
 * worst within E, and no lower than the canal form's worst (the measurement is not merely
 * smaller: it still sees the real error), which is within E. */
Test(thin, horn_cyclide_meets_its_default_bound, .timeout = 120)
{
    const test_surface *hs = &TEST_SURFACES[6];
    cr_assert_str_eq(hs->name, "horn-cyclide");
    ism_tape *t = test_surface_compile(hs);
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(hs->box, 10, w, box);
        const double E = pf_default_error(box);
        ism_mesh m;
        ism_locus l;
        ism_poly_stats ps;
        ism_conform_stats cs;
        horn_mesh(t, box, 10, E, &m, &l, &ps, &cs);
        ism_analysis a;
        pf_analyse_plain(&m, t, &a);
        double measured = fmax(a.max_dist_midpoint, a.max_dist_centroid);
        double exact = pf_worst_distance(&m, horn_dist);
        cr_expect_eq(ps.error_missed_nodes, 0, "placement %d: %zu leaves missed E %g (%g)", w,
                     (size_t)ps.error_missed_nodes, E, ps.error_worst);
        cr_expect_leq(measured, E, "placement %d: measured %g > E %g", w, measured, E);
        cr_expect_leq(exact, E, "placement %d: canal form %g > E %g", w, exact, E);
        cr_expect_geq(measured, 0.99 * exact, "placement %d: measured %g < canal form %g", w,
                      measured, exact);
        cr_expect_eq(a.euler, 1, "placement %d: χ %ld", w, a.euler);
        ism_analysis_free(&a);
        ism_locus_free(&l);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The cube [−1, 1]³ minus the ball of radius r, √2 − 0.02 < r < √2 (f = max(cube, ball)):
 * what is left is 12 bars along the cube's edges, joined at its 8 corners. Along the edge
 * through (0, 1, 1) the bar's section is {(1 − a)² + (1 − b)² ≥ r² − x², a, b ≥ 0}, legs
 * (2 − r² + x²)/2 about: at the edge's middle 0.02 for r = 1.4 (a quarter of a depth-5 cell of
 * the box ±1.3), 0.006 for r = 1.41 (1/13 of it), where no lattice line crosses it. A solid of
 * 8 corners joined by 12 bars has genus 12 − 8 + 1 = 5: its surface has χ = 2 − 2·5 = −8, in
 * one piece (losing the bars left the 8 corners: χ 16, 8 pieces; each bar lost adds 2). Every
 * hidden piece here lies on a crease (a wedge's tip, in a node where f has a kink), where
 * slivers past the corners are found at every depth: the chase must follow the bars without
 * refining every crease, so the triangles stay within twice those of the same run without
 * the hidden-piece search. */
static const char *frame_expr(double r, char buf[160])
{
    snprintf(buf, 160, "max(max(abs(x), abs(y), abs(z)) - 1, %.17g^2 - (x^2 + y^2 + z^2))", r);
    return buf;
}

/* The box base moved by an irrational fraction of a depth-d cell on each axis ((√2 − 1, π − 3,
 * e − 2): no lattice plane of any depth falls where it falls in the other boxes). */
static void irrational_box(const double base[6], int d, double box[6])
{
    const double frac[3] = {M_SQRT2 - 1, M_PI - 3, M_E - 2};
    for (int k = 0; k < 3; k++) {
        double s = frac[k] * ldexp(base[k + 3] - base[k], -d);
        box[k] = base[k] + s;
        box[k + 3] = base[k + 3] + s;
    }
}

/* The frame's properties: χ, one piece, closed, each bar's middle in the mesh. */
static void check_frame_mesh(const ism_mesh *m, const ism_tape *t, double r, int dmax,
                             int which, const char *how)
{
    pf_props p;
    pf_measure(m, t, &p);
    cr_expect_eq(p.euler, -8, "r %g %s depth %d box %d: χ = %ld", r, how, dmax, which, p.euler);
    cr_expect_eq(p.components, 1, "r %g %s depth %d box %d: %zu components", r, how, dmax,
                 which, p.components);
    cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0,
                 "r %g %s depth %d box %d: %zu boundary, %zu non-manifold edges", r, how, dmax,
                 which, p.boundary_edges, p.nonmanifold_edges);
    /* each bar's middle is in the mesh: vertices with |x| ≤ 0.1 (legs ≤ 0.025 there) within
     * 0.03 of the edge through (0, ±1, ±1), and so on for y and z */
    for (int bar = 0; bar < 12; bar++) {
        int axis = bar / 4, u = (axis + 1) % 3, w = (axis + 2) % 3;
        double cu = bar & 1 ? 1 : -1, cw = bar & 2 ? 1 : -1;
        size_t near = 0;
        for (size_t v = 0; v < m->nverts; v++) {
            const double *q = &m->pos[3 * v];
            near += fabs(q[axis]) <= 0.1 && fabs(q[u] - cu) <= 0.03 && fabs(q[w] - cw) <= 0.03;
        }
        cr_expect_geq(near, 3, "r %g %s depth %d box %d: bar %d: %zu vertices at its middle", r,
                      how, dmax, which, bar, near);
    }
}

static void check_frame(int dmax, int which)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    char expr[160];
    pf_surface s = {frame_expr(1.4, expr), NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    double box[6];
    pf_sweep_box(base, dmax, which, box);
    ism_poly_options o;
    pf_options(&o, box, 3, dmax);
    ism_mesh m, blind;
    ism_poly_stats st;
    pf_run_options(t, &o, &m, &st);
    o.thin_search = false;
    pf_run_options(t, &o, &blind, &st);
    check_frame_mesh(&m, t, 1.4, dmax, which, "polygoniser");
    cr_expect_leq(m.ntris, 2 * blind.ntris, "depth %d box %d: %zu triangles, %zu without the "
                  "search", dmax, which, m.ntris, blind.ntris);
    ism_mesh_free(&m);
    ism_mesh_free(&blind);
    ism_tape_free(t);
}

Test(thin, cube_minus_ball_bars_thinner_than_a_cell)
{
    for (int which = pf_first_box() - 1; which < 2; which++)
        for (int d = 5; d <= 6; d++)
            check_frame(d, which);
}

/* r = 1.41: bars 0.006 across at their middle, 1/13 of a depth-5 cell, through the service's
 * meshing (the singular stage finds no locus, so the chase may go ISM_THIN_EXTRA_DEPTH
 * levels down: a bar 1/13 of a cell needs 4). Boxes: as given, moved by 1e-3, by √2 − 1,
 * −(√5 − 1)/4, 1/e of a cell (pf_sweep_box; χ −6 at depth 6 there before face_lines.c 08432b2,
 * 0c63197), and by √2 − 1, π − 3, e − 2 of one (which 2). Moved by 0.37 cell a lattice plane runs
 * 0.0063 inside a cube face: past the bars' middle (legs 0.006) but not their ends, so the
 * plane met each bar only near the node's two ends and the cells capped the ends apart (χ −2
 * at depth 5, three bars cut; χ −6 at depth 6 in the irrational box; octree_build.c
 * edges_see). At depth 7 moved by 0.37 cell an edge along y at z = 0.993484 grazes a bar's
 * section near its tip: the ball at y = 0.999998, the cube face at y = 1, f ≈ −1e-6 between.
 * The two roots, closer than stitch_tol, were merged into one touching root, both faces at
 * that edge joined their crossings through it, and a depth-8 node's loop passed through that
 * point twice: χ −7, one non-manifold edge (face_lines.c compute_segment). */
Test(thin, cube_minus_ball_bars_a_thirteenth_of_a_cell, .timeout = 120)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    char expr[160];
    pf_surface s = {frame_expr(1.41, expr), NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    for (int which = pf_first_box() - 1; which < 3; which++)
        for (int d = 5; d <= (pf_quick() ? 6 : 7); d++) {
            double box[6];
            if (which < 2)
                pf_sweep_box(base, d, which, box);
            else
                irrational_box(base, d, box);
            ism_mesh m;
            ism_locus l;
            pf_run_surface(t, box, 3, d, &m, &l);
            check_frame_mesh(&m, t, 1.41, d, which, "surface");
            ism_locus_free(&l);
            ism_mesh_free(&m);
        }
    ism_tape_free(t);
}

/* The live preview's coarse search (ism_poly_options.thin_coarse) keeps the bars of r = 1.4 at
 * depth 4 (an eighth of a cell at their middle): it probes nodes where f has a kink too, and
 * the islands in the faces of nodes there (a bar's section), counting a piece found only
 * where the edges do not see it (pieces split only while hidden, ISM_THIN_BLIND_DEPTH
 * levels at most). The previews dropped them: χ 16, 8 pieces. */
Test(thin, cube_minus_ball_bars_in_a_preview)
{
    const double base[6] = {-1.3, -1.3, -1.3, 1.3, 1.3, 1.3};
    char expr[160];
    pf_surface s = {frame_expr(1.4, expr), NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    for (int which = -1; which < 3; which++) {
        double box[6];
        if (which < 2)
            pf_sweep_box(base, 4, which, box);
        else
            irrational_box(base, 4, box);
        ism_mesh m;
        ism_poly_stats st;
        pf_run_search(t, box, 4, true, &m, &st);
        check_frame_mesh(&m, t, 1.4, 4, which, "preview");
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* Two balls of radius 0.5 whose centres are 0.9992 apart overlap in a lens (f = max of the
 * two: one kink) of radius √(0.25 − 0.4996²) = 0.020 and 0.0008 thick, a third of a depth-5
 * cell of the box ±1 across: a piece of its own although its crease is one circle. It is
 * a closed surface, χ = 2, in one piece (off the lattice by 0.37 cell it was lost). */
Test(thin, lens_of_two_balls_thinner_than_a_cell)
{
    pf_surface s = {"max((x - 0.4996)^2 + (y - 0.01)^2 + (z - 0.013)^2 - 0.25, "
                    "(x + 0.4996)^2 + (y - 0.01)^2 + (z - 0.013)^2 - 0.25)",
                    NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-1, -1, -1, 1, 1, 1};
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        ism_mesh m;
        pf_props p;
        pf_run_placed(t, base, 5, which, box, &m, &p);
        cr_expect_eq(p.euler, 2, "box %d: χ = %ld", which, p.euler);
        cr_expect_eq(p.components, 1, "box %d: %zu components", which, p.components);
        cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0,
                     "box %d: %zu boundary, %zu non-manifold edges", which, p.boundary_edges,
                     p.nonmanifold_edges);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The preview's probes (ism_thin_probe) where f has a kink and nothing is hidden: f =
 * max(x, −x) + 1 ≥ 1 over the box x ∈ [−1, 2], y, z ∈ [−1, 1]. From the centre (x = 0.5,
 * f 1.5, ∇f (1, 0, 0)) Newton with its overshoot leaves the box and is clamped to x = −1,
 * then, on the other branch, to x = 2, then back to x = −1: a 2-cycle between the walls,
 * which ends the probe after 3 gradients (it ran all PROBE_STEPS + 1 = 7). The eight octants,
 * where f ≥ 0.5 (x ≤ 0.5) and f ≥ 1.5 (x ≥ 0.5) by their natural intervals in one batch, are
 * not probed: a probe stays in its box, so it cannot find the other sign there (they were:
 * 8 probes more). */
Test(thin, kinked_probe_ends_at_a_two_cycle_and_skips_what_keeps_the_sign)
{
    pf_surface s = {"max(x, -x) + 1", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_sampler smp = {.tape = t, .ws = ism_eval_ws_new(t)};
    cr_assert(smp.ws);
    const double lo[3] = {-1, -1, -1}, hi[3] = {2, 1, 1};
    double found[3];
    enum ism_thin_verdict v = ism_thin_probe(&smp, lo, hi, 1, found);
    cr_expect_eq(v, ISM_THIN_UNDECIDED, "verdict %d", (int)v);
    cr_expect_eq(smp.n_gradient, 3, "%llu gradients", (unsigned long long)smp.n_gradient);
    cr_expect_eq(smp.n_interval, 8, "%llu intervals (the octants in one batch)",
                 (unsigned long long)smp.n_interval);
    ism_eval_ws_free(smp.ws);
    ism_tape_free(t);
}
