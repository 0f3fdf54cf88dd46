/* test_coarse_points.c — singular points other than nodes at coarse depths (3 and 4) through
 * the whole pipeline of core/singular/surface.h, in the preset's box as given and shifted off
 * the octree lattice as tests/bench/sweep_singular.py shifts it (1e-3, irrational fractions of a
 * finest cell).
 *
 * What is asserted comes from the closed forms, not from the code:
 *  - isolated-point, f = |p|² g with g = (x − 1.1)² + y² + z² − 0.25: ∇f = 2p g + |p|² ∇g.
 *    Where f = 0 either p = 0 (g(0) = 0.96, so ∇f = 0 there and H = 2 g(0) I = 1.92 I,
 *    definite: an isolated point) or g = 0 with p ≠ 0, where ∇f = |p|² ∇g ≠ 0 (∇g = 2(p − c)
 *    does not vanish on the sphere). So exactly one singular point, the origin, isolated;
 *    the rest is the sphere of radius 0.5 about (1.1, 0, 0), inside every box tried: χ 2, one
 *    component, no boundary, no non-manifold edge. Before, at depth 3 in the box shifted 0.37
 *    cell the point was lost (its cell joined a cluster whose projections all reached a
 *    critical point off the surface, and the cluster was dropped whole).
 *  - horn-cyclide, f = S² − 4(a x − f r)² − 4(a² − f²) y², S = x² + y² + z² + a² − f² − r²,
 *    a = 10, f = r = 2 (S ≥ 92 > 0): ∂f/∂z = 4 S z gives z = 0; ∂f/∂y = 4 y (S − 2(a² − f²))
 *    gives y = 0 or S = 192. With y = z = 0, f = 0 is x² + 92 = ±2(10x − 4): x = 10 (double
 *    root), −6 or −14, and ∂f/∂x = 4 S x − 8a(a x − f r) vanishes only at x = 10 (7680 −
 *    7680; at −6: 2048, at −14: −4608). With S = 192, ∂f/∂x = 0 gives x = 10 and then f = 0
 *    gives y = 0: the same point. So exactly one singular point, (10, 0, 0), where the horns
 *    touch; f is quartic along y there (an A3 point), no singular curve. Before, at depth 3
 *    (cell 4) its cells joined one cluster with the tube's and with critical points off the
 *    surface; its projections were taken for a curve's, and a two-point whisker with lost
 *    ends was reported instead of the point (in all three boxes); at depth 4 in the box
 *    shifted 0.37 cell the same projections passed the curve test (f's null component
 *    0.17 d³ at the probe, under its bound).
 *  - lone points (no other piece of the locus in the box; their conformance ball has no
 *    clearance to bound its growth). The horn cyclide at depth 3 (cell 4): a torus whose
 *    tube shrinks to the point, i.e. a sphere with two points identified, χ = 2 − 1 = 1,
 *    the point one vertex where the two horns' cones meet. Its y = 0 section is the point
 *    and the circle (x + 10)² + z² = 16 (from x² + z² + 92 = ±2(10x − 4)), so the surface
 *    reaches x = −14: the box shifted 0.37 cell (x ≥ −13.52) cuts a disc off the tube: χ 0
 *    and one boundary loop. The wide cone x² + y² = 36 z² in ±1: two nappes z = ±r/6, each a
 *    disc over the box's square, sharing the apex: χ = 1 + 1 − 1 = 1, two boundary loops,
 *    the apex one vertex with 2 cones. Before, the ball grew (×1.4 up to 6 times) while its
 *    rim saw the other horn or nappe close by, until it swallowed both into one loop: horn
 *    χ 2 (one cone), the cone χ 2 or 0 in the shifted boxes.
 *  - heart, f = g³ − z³ h, g = x² + 9/4 y² + z² − 1, h = x² + 9/80 y²: ∂f/∂x = 2x(3g² − z³),
 *    ∂f/∂y = (9/40) y (60 g² − z³), ∂f/∂z = 6 z g² − 3 z² h. With z = 0, f = 0 gives g = 0:
 *    the equator ellipse, where ∇f = 0 but f ~ g³ − z³ h keeps the zero set a smooth graph
 *    g = z h^(1/3) (no singular curve of the surface). With z ≠ 0 and x ≠ 0: 3g² = z³ and
 *    2g² = z h give h = 2z²/3, and f = 0 gives z = 1/12, then y = 0 (60 g² ≠ z³) and x² = h
 *    against x² = 1 + g − z² ≈ 1: none. With x = 0, y ≠ 0: 60 g² = z³, h = z²/30, f = 0 gives
 *    z ≈ 0.004 and then g ≈ −1 against g > 0: none. With x = y = 0: h = 0, so g = 0, z = ±1.
 *    So exactly two singular points, (0, 0, ±1). There H = ∓diag(2, 9/40, 0) and along the
 *    null direction f(0, 0, ±1 + w) = (±2w + w²)³ changes sign: two cusps, each a mesh
 *    vertex. Before, at depth 3 (cell 0.375) the heart's candidate cells formed one cluster
 *    with critical points off the surface (the lobes' (±0.53, 0, 0.65), (±0.79, 0, 0.96));
 *    the top cusp's four cells did not project (Newton from their centres went towards
 *    those points) and were never searched: 1 cusp of 2, in all three boxes.
 *  - linked tori (the preset), f = min(T₁, T₂), T₁ = (|p|² + 0.91)² − 4(x² + y²) (R = 1,
 *    r = 0.3 about the z axis), T₂ the same about the y axis through (1, 0, 0). Each core
 *    circle passes through the other's centre; a point (1 + cos t, 0, sin t) of the second
 *    lies sqrt(cos² t + sin² t) = 1 from the first, > 2r: the tubes are disjoint, each a
 *    smooth torus (r < R), so f has no singular point on f = 0 (where f = T₁ = 0 < T₂ or the
 *    reverse, ∇f = ∇T_i ≠ 0): χ 0 + 0, two components, no boundary in the box. ∇T₁ = 0 on
 *    the circle |p|² = 1.09, z = 0 inside the tube, where f = T₁ = −0.36. Before, at depth 5
 *    (cell 0.14) the natural interval of f over a cell there held 0, and Newton landed on
 *    that circle (Hessian rank 2, no certificate): 4 uncertified "degenerate points" (14 in
 *    the 0.37-cell box), their balls cut into the tori: χ 4 in 4 components (2 in 2). */
#include <criterion/criterion.h>
#include <math.h>
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/core/test_eval_surfaces.h"

static const char *place_name(int which)
{
    return which < 0 ? "own" : which == 0 ? "1e-3" : "irr cell";
}

/* Exactly one singular point in l, certified, of the given type, within tol of want. */
static void expect_one_point(const ism_locus *l, int type, const double want[3], double tol,
                             const char *what, int d, int which)
{
    const char *place = place_name(which);
    cr_expect_eq(l->npoints, 1, "%s d%d %s: %zu singular points", what, d, place, l->npoints);
    cr_expect_eq(l->ncurves, 0, "%s d%d %s: %zu singular curves", what, d, place, l->ncurves);
    cr_expect(!l->incomplete, "%s d%d %s: incomplete (%s)", what, d, place, l->incomplete_why);
    if (l->npoints < 1)
        return;
    const ism_sing_point *p = &l->points[0];
    cr_expect(p->certified && p->type == type, "%s d%d %s: the point is %s%s", what, d, place,
              p->certified ? "" : "uncertified ", ism_sing_type_name(p->type));
    cr_expect(ism_dist3(p->p, want) <= tol, "%s d%d %s: point (%g, %g, %g), want (%g, %g, %g)",
              what, d, place, p->p[0], p->p[1], p->p[2], want[0], want[1], want[2]);
}

/* The service's meshing of t in base placed by which (pf_sweep_box) at depths 3..d. */
static void run_placed(const ism_tape *t, const double base[6], int d, int which, ism_mesh *m,
                       ism_locus *l)
{
    double box[6];
    pf_sweep_box(base, d, which, box);
    pf_run_surface(t, box, 3, d, m, l);
}

Test(coarse_points, isolated_point)
{
    ism_tape *t = pf_compile(&(pf_surface){
        "(x^2 + y^2 + z^2)*((x - 1.1)^2 + y^2 + z^2 - 0.25)", NULL, 0, NULL, 0});
    const double base[6] = {-0.8, -0.8, -0.8, 1.8, 0.8, 0.8}, origin[3] = {0, 0, 0};
    for (int d = 3; d <= 4; d++)
        for (int which = pf_first_box() - 1; which <= 1; which++) {
            ism_mesh m;
            ism_locus l;
            run_placed(t, base, d, which, &m, &l);
            expect_one_point(&l, ISM_SING_ISOLATED, origin, 1e-9, "isolated-point", d, which);
            pf_props pr;
            pf_measure(&m, t, &pr);
            const char *place = place_name(which);
            cr_expect(pr.euler == 2 && pr.components == 1 && pr.boundary_edges == 0 &&
                          pr.nonmanifold_edges == 0,
                      "isolated-point d%d %s: χ %ld, %zu components, %zu boundary and %zu "
                      "non-manifold edges; want the sphere: 2, 1, 0, 0",
                      d, place, pr.euler, pr.components, pr.boundary_edges,
                      pr.nonmanifold_edges);
            ism_locus_free(&l);
            ism_mesh_free(&m);
        }
    ism_tape_free(t);
}

Test(coarse_points, horn_cyclide)
{
    const test_surface *s = &TEST_SURFACES[6];
    cr_assert_str_eq(s->name, "horn-cyclide");
    ism_tape *t = test_surface_compile(s);
    const double want[3] = {10, 0, 0};
    double diag = sqrt(32.0 * 32.0 + 2 * 32.0 * 32.0);
    for (int d = 3; d <= 4; d++)
        for (int which = pf_first_box() - 1; which <= 1; which++) {
            double box[6];
            pf_sweep_box(s->box, d, which, box);
            ism_mesh m;
            ism_locus l;
            pf_run_surface(t, box, 3, d, &m, &l);
            expect_one_point(&l, ISM_SING_DEGENERATE, want, 1e-9 * diag, "horn-cyclide", d,
                             which);
            ism_locus_free(&l);
            ism_mesh_free(&m);
        }
    ism_tape_free(t);
}

static uint32_t vertex_at(const ism_mesh *m, const double p[3])
{
    for (size_t v = 0; v < m->nverts; v++)
        if (m->pos[3 * v] == p[0] && m->pos[3 * v + 1] == p[1] && m->pos[3 * v + 2] == p[2])
            return (uint32_t)v;
    return UINT32_MAX;
}

/* One run of a surface with one lone point: χ, boundary (edges or none) and the point's
 * vertex with 2 cones. */
static void check_lone(const ism_tape *t, const double box[6], int d, long euler, bool open,
                       const char *what, int which)
{
    ism_mesh m;
    ism_locus l;
    pf_run_surface(t, box, 3, d, &m, &l);
    const char *place = place_name(which);
    cr_expect_eq(l.npoints, 1, "%s d%d %s: %zu points", what, d, place, l.npoints);
    if (l.npoints == 1) {
        uint32_t v = vertex_at(&m, l.points[0].p);
        cr_expect(v != UINT32_MAX && pf_vertex_cones(&m, v) == 2,
                  "%s d%d %s: the point is %s with %zu cones, want 2", what, d, place,
                  v == UINT32_MAX ? "no vertex" : "a vertex",
                  v == UINT32_MAX ? (size_t)0 : pf_vertex_cones(&m, v));
    }
    pf_props pr;
    pf_measure(&m, t, &pr);
    cr_expect(pr.euler == euler && (pr.boundary_edges > 0) == open && pr.nonmanifold_edges == 0,
              "%s d%d %s: χ %ld, %zu boundary and %zu non-manifold edges; want χ %ld, %s, 0",
              what, d, place, pr.euler, pr.boundary_edges, pr.nonmanifold_edges, euler,
              open ? "a boundary" : "none");
    ism_locus_free(&l);
    ism_mesh_free(&m);
}

Test(coarse_points, lone_points_keep_their_ball)
{
    const test_surface *s = &TEST_SURFACES[6];
    ism_tape *horn = test_surface_compile(s);
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        double box[6];
        pf_sweep_box(s->box, 3, which, box);
        bool cut = box[0] > -14.0; /* the tube reaches x = −14 */
        check_lone(horn, box, 3, cut ? 0 : 1, cut, "horn-cyclide", which);
    }
    ism_tape_free(horn);
    ism_tape *cone = pf_compile(&(pf_surface){"x^2 + y^2 - 36*z^2", NULL, 0, NULL, 0});
    const double base[6] = {-1, -1, -1, 1, 1, 1};
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        double box[6];
        pf_sweep_box(base, 3, which, box);
        check_lone(cone, box, 3, 1, true, "wide cone", which);
    }
    ism_tape_free(cone);
}

/* In the irrational placement (pf_sweep_box 1) the cell of the cusp (0, 0, 1) projected onto
 * the critical point (0, 0.441, 0.810) off the surface, outside the cell: the cusp was lost
 * (1 point, the search complete) until such cells were searched below (points.c
 * projected_inside). */
Test(coarse_points, heart_two_cusps)
{
    ism_tape *t = pf_compile(&(pf_surface){
        "(x^2 + 9/4*y^2 + z^2 - 1)^3 - x^2*z^3 - 9/80*y^2*z^3", NULL, 0, NULL, 0});
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    const double want[2][3] = {{0, 0, -1}, {0, 0, 1}}; /* points are sorted by z */
    double tol = 1e-9 * sqrt(3 * 3.0 * 3.0);
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        double box[6];
        pf_sweep_box(base, 3, which, box);
        ism_mesh m;
        ism_locus l;
        pf_run_surface(t, box, 3, 3, &m, &l);
        const char *place = place_name(which);
        cr_expect_eq(l.npoints, 2, "heart d3 %s: %zu singular points, want 2", place, l.npoints);
        cr_expect_eq(l.ncurves, 0, "heart d3 %s: %zu singular curves", place, l.ncurves);
        for (size_t i = 0; i < l.npoints && i < 2; i++) {
            const ism_sing_point *p = &l.points[i];
            cr_expect(p->certified && p->type == ISM_SING_CUSP, "heart d3 %s: point %zu is %s%s",
                      place, i, p->certified ? "" : "uncertified ", ism_sing_type_name(p->type));
            cr_expect(ism_dist3(p->p, want[i]) <= tol,
                      "heart d3 %s: point (%g, %g, %g), want (0, 0, %g)", place, p->p[0],
                      p->p[1], p->p[2], want[i][2]);
            cr_expect(vertex_at(&m, p->p) != UINT32_MAX,
                      "heart d3 %s: the cusp at z = %g is no mesh vertex", place, p->p[2]);
        }
        ism_locus_free(&l);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

Test(coarse_points, linked_tori_no_point_off_the_surface)
{
    ism_tape *t = pf_compile(&(pf_surface){
        "min((x^2 + y^2 + z^2 + 0.91)^2 - 4*(x^2 + y^2), "
        "((x - 1)^2 + y^2 + z^2 + 0.91)^2 - 4*((x - 1)^2 + z^2))", NULL, 0, NULL, 0});
    const double base[6] = {-1.8, -1.8, -1.8, 2.8, 1.8, 1.8};
    int d = 5 - pf_quick();
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        ism_mesh m;
        ism_locus l;
        run_placed(t, base, d, which, &m, &l);
        const char *place = place_name(which);
        cr_expect(l.npoints == 0 && l.ncurves == 0, "linked tori d%d %s: %zu singular points, "
                  "%zu curves; want none", d, place, l.npoints, l.ncurves);
        pf_props pr;
        pf_measure(&m, t, &pr);
        cr_expect(pr.euler == 0 && pr.components == 2 && pr.boundary_edges == 0 &&
                      pr.nonmanifold_edges == 0,
                  "linked tori d%d %s: χ %ld, %zu components, %zu boundary and %zu non-manifold "
                  "edges; want two tori: 0, 2, 0, 0", d, place, pr.euler, pr.components,
                  pr.boundary_edges, pr.nonmanifold_edges);
        ism_locus_free(&l);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}
