/* test_surface_shifted.c — surfaces through the whole pipeline of core/singular/surface.h
 * (locus from f, polygoniser, conformance) in the boxes of tests/bench/sweep_singular.py
 * shifted off the octree lattice, each at the depth and shift where the sweep once showed a
 * defect; the facts asserted come from the closed forms (χ, components, the double curve's
 * edges with four triangles each, no non-manifold element off the locus). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include "core/analysis/analysis.h"
#include "core/singular/check.h"
#include "core/singular/surface.h"
#include "tests/unit/core/poly_fixture.h"

typedef struct surface_run {
    ism_mesh m;
    ism_locus l;
    ism_conform_stats cs;
    ism_analysis a;
    size_t artefacts;       /* non-manifold edges and points off the locus */
} surface_run;

/* Meshes expr to depth dmax in base shifted by pf_sweep_box(which). */
static void run_surface(const char *expr, const double base[6], int dmax, int which,
                        surface_run *r)
{
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_poly_options po;
    ism_poly_options_default(&po);
    pf_sweep_box(base, dmax, which, po.box);
    po.min_depth = 3;
    po.max_depth = dmax;
    po.threads = 1;
    ism_mesh_init(&r->m);
    ism_locus_init(&r->l);
    ism_poly_stats ps;
    ism_surface_times times;
    ism_error err;
    cr_assert_eq(ism_mesh_surface(t, &po, &r->m, &r->l, &ps, &r->cs, &times, &err), ISM_POLY_OK,
                 "%s", err.message);
    ism_analysis_options ao;
    ism_analysis_options_default(&ao);
    ao.curvature = ao.accuracy = false;
    ao.threads = 1;
    cr_assert(ism_analyse(&r->m, t, &ao, &r->a, &err), "analyse: %s", err.message);
    ism_locus_check chk;
    cr_assert(ism_locus_check_mesh(&r->l, po.box, &r->m, &r->a, &chk, &err), "check: %s",
              err.message);
    r->artefacts = chk.nonmanifold_edges_off + chk.nonmanifold_points_off;
    ism_locus_check_free(&chk);
    ism_tape_free(t);
}

static void surface_run_free(surface_run *r)
{
    ism_analysis_free(&r->a);
    ism_locus_free(&r->l);
    ism_mesh_free(&r->m);
}

/* The crossing-spheres preset (unit spheres at x = ±1/4): their circle lies 0.03 below the
 * spheres' flat tops, where the octree stays coarse. At depth 8, 0.37 cell off the lattice,
 * the tube took a top triangle reaching 5 radii from the circle, its rim found no foot within
 * 4 radii and was fanned to its centroid across the sphere: χ 5, two components, edges of the
 * circle with three triangles. */
Test(surface_shifted, crossing_spheres_depth_8)
{
    const double base[6] = {-1.8, -1.3, -1.3, 1.8, 1.3, 1.3};
    surface_run r;
    run_surface("((x - 0.25)^2 + y^2 + z^2 - 1)*((x + 0.25)^2 + y^2 + z^2 - 1)", base, 8, 1,
                &r);
    size_t n = pf_count_edges(&r.m, 3, SIZE_MAX, NULL, NULL);
    size_t four = pf_count_edges(&r.m, 4, 4, NULL, NULL);
    cr_expect_eq(r.l.ncurves, 1, "%zu curves found, the spheres cross in one circle",
                 r.l.ncurves);
    cr_expect_eq(r.cs.loops_fallback, 0, "%zu rims fanned to their centroid",
                 r.cs.loops_fallback);
    /* χ(S1 ∪ S2) = χ(S1) + χ(S2) − χ(circle) = 2 + 2 − 0 */
    cr_expect_eq(r.a.euler, 4, "χ = %ld, expected 4", r.a.euler);
    cr_expect_eq(r.a.components, 1, "%zu components", r.a.components);
    cr_expect_eq(r.a.boundary_edges, 0, "%zu boundary edges", r.a.boundary_edges);
    cr_expect_gt(n, 0, "no non-manifold edge: the circle is not in the mesh");
    cr_expect_eq(four, n, "%zu of %zu non-manifold edges have four triangles", four, n);
    cr_expect_eq(r.artefacts, 0, "%zu non-manifold elements off the locus", r.artefacts);
    surface_run_free(&r);
}
