/* test_remesh.c — the quality pass (core/remesh/) on polygonised meshes, measured with the
 * fixture's own edge counting: a sphere gets no triangle under 20° with its counts, χ and
 * vertices on f = 0 kept; a hemisphere cut by the box keeps every boundary vertex where it was
 * and every boundary edge. (Non-manifold edges and points: tests/cli/test_quality.py, through
 * the conformance that makes them.) */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/remesh/remesh.h"
#include "tests/unit/core/poly_fixture.h"

static double min_angle_deg(const ism_mesh *m)
{
    return ism_remesh_min_angle(m);
}

/* Runs the pass on f's mesh in box at depth 3:d; before and after props. */
static void remesh(const char *expr, const double box[6], int d, ism_mesh *m, pf_props *before,
                   pf_props *after, ism_remesh_stats *st, ism_tape **tape)
{
    pf_surface s = {.expr = expr};
    *tape = pf_compile(&s);
    ism_poly_stats ps;
    ism_mesh_init(m);
    pf_run(*tape, box, 3, d, 1, m, &ps);
    pf_measure(m, *tape, before);
    ism_remesh_options o = {.f = *tape};
    ism_error err;
    cr_assert(ism_remesh_quality(m, &o, st, &err), "%s", err.message);
    pf_measure(m, *tape, after);
}

Test(remesh, sphere_has_no_triangle_under_20_degrees)
{
    /* box shifted by 0.37 of a finest cell so no lattice plane runs through the centre */
    int d = 6 - pf_quick();
    const double c = 0.37 * 3.0 / (1 << d);
    const double box[6] = {-1.5 + c, -1.5 - c, -1.5 + c, 1.5 + c, 1.5 - c, 1.5 + c};
    ism_mesh m;
    pf_props b, a;
    ism_remesh_stats st;
    ism_tape *t;
    remesh("x^2 + y^2 + z^2 - 1", box, d, &m, &b, &a, &st, &t);
    cr_expect_lt(st.min_angle_before, 20.0);
    cr_expect_geq(min_angle_deg(&m), 20.0, "%g", min_angle_deg(&m));
    cr_expect_eq(a.euler, 2);
    cr_expect_eq(a.faces, b.faces);
    cr_expect_eq(a.edges, b.edges);
    cr_expect_eq(a.nonmanifold_edges, 0);
    cr_expect_leq(a.max_dist, 1e-9);
    for (size_t v = 0; v < m.nverts; v++) { /* closed form: |p| = 1 */
        const double *p = m.pos + 3 * v;
        cr_expect_leq(fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1), 1e-9);
    }
    ism_mesh_free(&m);
    ism_tape_free(t);
}

Test(remesh, hemisphere_keeps_its_boundary)
{
    /* the box cuts the sphere at z = 0.3: one boundary loop */
    const double box[6] = {-1.5, -1.5, 0.3, 1.5, 1.5, 1.5};
    pf_surface s = {.expr = "x^2 + y^2 + z^2 - 1"};
    ism_tape *t = pf_compile(&s);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats ps;
    pf_run(t, box, 3, 6 - pf_quick(), 1, &m, &ps);
    double *before = malloc(m.nverts * 3 * sizeof *before);
    memcpy(before, m.pos, m.nverts * 3 * sizeof *before);
    pf_props b, a;
    pf_measure(&m, t, &b);
    ism_remesh_options o = {.f = t};
    ism_remesh_stats st;
    ism_error err;
    cr_assert(ism_remesh_quality(&m, &o, &st, &err));
    pf_measure(&m, t, &a);
    cr_expect_gt(st.moves, 0);
    cr_expect_eq(a.boundary_edges, b.boundary_edges);
    cr_expect_eq(a.euler, b.euler);
    size_t on_cut = 0;
    for (size_t v = 0; v < m.nverts; v++)
        if (fabs(before[3 * v + 2] - 0.3) < 1e-12) { /* a boundary vertex stays put */
            on_cut++;
            cr_expect(!memcmp(before + 3 * v, m.pos + 3 * v, 3 * sizeof *before));
        }
    cr_expect_gt(on_cut, 0);
    free(before);
    ism_mesh_free(&m);
    ism_tape_free(t);
}
