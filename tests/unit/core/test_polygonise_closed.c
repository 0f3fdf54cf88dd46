/* test_polygonise_closed.c — closed manifold surfaces come out as closed manifold meshes:
 * every edge in exactly two triangles, the right Euler characteristic, one piece, vertices
 * on the surface and the area of the true surface, at several depths and in boxes whose
 * centre is off the surface's symmetry planes (so lattice and surface never line up). */
#include <criterion/criterion.h>
#include <math.h>
#include "poly_fixture.h"

static const ism_param sphere_r[] = {{"r", 1}};
static const pf_surface sphere = {"x^2 + y^2 + z^2 - r^2", sphere_r, 1, NULL, 0};
static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};
static const ism_param pretzel_t[] = {{"t", 0.03}};
static const pf_surface pretzel = {"(x*(x-1)^2*(x-2) + y^2)^2 + z^2 - t", pretzel_t, 1, NULL, 0};

/* Checks a closed surface; area_expect <= 0 skips the area check. */
static void check_closed(const pf_surface *s, const double box[6], int dmin, int dmax,
                         long euler, double area_expect)
{
    dmax -= pf_quick();
    if (dmin > dmax)
        dmin = dmax;
    ism_tape *t = pf_compile(s);
    ism_mesh m;
    ism_poly_stats st;
    pf_run(t, box, dmin, dmax, 0, &m, &st);
    pf_props p;
    pf_measure(&m, t, &p);
    cr_assert_gt(p.faces, 100, "%s: only %zu triangles", s->expr, p.faces);
    cr_expect_eq(p.boundary_edges, 0, "%s depth %d: %zu boundary edges", s->expr, dmax,
                 p.boundary_edges);
    cr_expect_eq(p.nonmanifold_edges, 0, "%s depth %d: %zu edges in more than two triangles",
                 s->expr, dmax, p.nonmanifold_edges);
    cr_expect_eq(p.euler, euler, "%s depth %d: Euler characteristic %ld, expected %ld", s->expr,
                 dmax, p.euler, euler);
    cr_expect_eq(p.components, 1, "%s depth %d: %zu components", s->expr, dmax, p.components);
    double cell = pf_cell(box, dmax);
    cr_expect_leq(p.max_dist, 0.05 * cell, "%s: a vertex is %g from the surface (cell %g)",
                  s->expr, p.max_dist, cell);
    if (area_expect > 0 && dmax >= 7)
        cr_expect_leq(fabs(p.area - area_expect), 0.01 * area_expect,
                      "%s: area %g, expected %g within 1%%", s->expr, p.area, area_expect);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

static const double cube15[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
static const double skew_sphere[6] = {-1.3, -1.1, -1.2, 1.7, 1.4, 1.25};
static const double skew_torus[6] = {-1.4, -1.3, -0.9, 1.6, 1.5, 1.1};
static const double pretzel_box[6] = {-0.5, -1.5, -1.5, 2.5, 1.5, 1.5};
static const double skew_pretzel[6] = {-0.63, -1.37, -1.21, 2.61, 1.52, 1.18};

#define SPHERE_AREA (4 * M_PI)
#define TORUS_AREA (4 * M_PI * M_PI * 1.0 * 0.3)

Test(closed, sphere_depths)
{
    for (int d = 4; d <= 7; d++)
        check_closed(&sphere, cube15, 2, d, 2, SPHERE_AREA);
}

Test(closed, sphere_off_centre_box) { check_closed(&sphere, skew_sphere, 3, 7, 2, SPHERE_AREA); }

Test(closed, sphere_uniform) { check_closed(&sphere, cube15, 6, 6, 2, 0); }

Test(closed, torus_depths)
{
    for (int d = 5; d <= 7; d++)
        check_closed(&torus, cube15, 3, d, 0, TORUS_AREA);
}

Test(closed, torus_off_centre_box) { check_closed(&torus, skew_torus, 3, 8, 0, TORUS_AREA); }

Test(closed, pretzel_genus2)
{
    check_closed(&pretzel, pretzel_box, 3, 7, -2, 0);
    check_closed(&pretzel, skew_pretzel, 3, 8, -2, 0);
}
