/* test_singular_depth.c — under an error bound depth.max is only a safety limit for the
 * singular stage too (core/singular/surface.c ism_singular_depth): the locus search, the
 * conformance tube and the curves' split cells are sized from E, so the Klein bottle at
 * E = 1e-2 makes the same mesh with depth.max 8 and 10 (before: 31,834 and 42,792 triangles,
 * the tube's share growing with depth.max), in the own box and off the lattice, with the
 * same topology (χ 0, one component, one double curve closed) and within E at centroids and
 * edge midpoints. Nor does the octree go deeper than the tube needs along the locus
 * (octree_build.c conformed): the crossing planes' raw triangles are the same at depth.max 8
 * and 10 (before: 23,680 and 51,328 in the own box, the conformance cutting out the extra). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "core/analysis/analysis.h"
#include "core/singular/surface.h"
#include "tests/unit/core/poly_fixture.h"

#define KLEIN "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + " \
              "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)"
#define E 1e-2

/* The rule itself: no bound -> depth.max; box 8 at E 1e-2 -> 8 (cell 1/32 <= 5 E; 1/16 is
 * 6.25 E), never below 7 (a coarse E), never above depth.max; a cube box at the default
 * bound E = 1e-3 x diagonal -> 7 (cell 1/128 of the side = 4.51 E <= 5 E). */
Test(singular_depth, from_the_bound)
{
    ism_poly_options po;
    ism_poly_options_default(&po);
    const double box[6] = {-4, -4, -4, 4, 4, 4};
    memcpy(po.box, box, sizeof box);
    po.max_depth = 10;
    cr_expect_eq(ism_singular_depth(&po), 10, "no bound: depth.max");
    po.max_error = E;
    cr_expect_eq(ism_singular_depth(&po), 8);
    po.max_depth = 16;
    cr_expect_eq(ism_singular_depth(&po), 8);
    po.max_error = 1e-3; /* cell <= 5e-3: 8 / 2^11 (8 / 2^10 is 7.8e-3) */
    cr_expect_eq(ism_singular_depth(&po), 11);
    po.max_error = 1e-3 * 8 * sqrt(3.0); /* the default bound: 1/16 = 4.51 E, 1/8 = 9.0 E */
    cr_expect_eq(ism_singular_depth(&po), 7, "default bound on a cube box");
    po.max_error = 1e-3 * 8 * sqrt(3.0) * 0.9; /* 1/16 = 5.01 E > 5 E: one deeper */
    cr_expect_eq(ism_singular_depth(&po), 8);
    po.max_error = 1;
    cr_expect_eq(ism_singular_depth(&po), 7);
    po.max_depth = 10;
    po.max_error = 3.27e-3; /* 8 / 2^9 = 4.78 E <= 5 E: 9 (at 4.6 E it was 10) */
    cr_expect_eq(ism_singular_depth(&po), 9, "klein box at E 3.27e-3");
    po.max_depth = 6;
    cr_expect_eq(ism_singular_depth(&po), 6);
}

/* The depth.max 10 mesh within e at centroids and edge midpoints (box `which`); then both
 * runs' meshes and loci freed. */
static void expect_within_and_free(const ism_tape *t, double e, int which, ism_mesh *m8,
                                   ism_mesh *m10, ism_locus *l8, ism_locus *l10)
{
    ism_analysis a;
    pf_analyse_plain(m10, t, &a);
    cr_expect_leq(a.max_dist_centroid, e, "box %d: centroid %g", which, a.max_dist_centroid);
    cr_expect_leq(a.max_dist_midpoint, e, "box %d: midpoint %g", which, a.max_dist_midpoint);
    ism_analysis_free(&a);
    ism_locus_free(l8);
    ism_locus_free(l10);
    ism_mesh_free(m8);
    ism_mesh_free(m10);
}

/* The Klein bottle's topology in box `which`: one double curve found, χ 0, one component, the
 * curve meshed as one closed non-manifold line. */
static void expect_klein_topology(const ism_tape *t, const ism_mesh *m, const ism_locus *l,
                                  int which)
{
    cr_expect_eq(l->ncurves, 1, "box %d: %zu curves", which, l->ncurves);
    pf_props p;
    pf_measure(m, t, &p);
    cr_expect_eq(p.euler, 0, "box %d: χ %ld", which, p.euler);
    cr_expect_eq(p.components, 1, "box %d: %zu components", which, p.components);
    size_t nm = 0;
    cr_expect(pf_nm_edges_one_closed_curve(m, &nm), "box %d: the double curve", which);
}

Test(singular_depth, klein_depth_max_is_only_a_limit)
{
    const pf_surface s = {KLEIN, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-4, -4, -4, 4, 4, 4};
    for (int which = pf_first_box() - 1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, 10, which, box);
        ism_mesh m8, m10;
        ism_locus l8, l10;
        pf_run_surface_bounded(t, box, 3, 8, E, &m8, &l8);
        pf_run_surface_bounded(t, box, 3, 10, E, &m10, &l10);
        pf_same_mesh(&m8, &m10, "depth.max 8 and 10 under E 1e-2");
        expect_klein_topology(t, &m10, &l10, which);
        expect_within_and_free(t, E, which, &m8, &m10, &l8, &l10);
    }
    ism_tape_free(t);
}

/* The coarser tube the rule allows keeps its guarantees: the Klein bottle at E = 3.27e-3 (box 8,
 * depth.max 10) gets the singular stage's depth 9 (cell 4.78 E; the rule at 4.6 E made it 10,
 * 2.39 E: 86,632 triangles, now 61,172), and its mesh is still within E at centroids and edge
 * midpoints (|f| / |∇f| refined by Newton, pf_analyse_plain), with the topology of depth 10 in
 * each placement: χ 0, one component, one double curve found and meshed as one closed
 * non-manifold line. Only the depth check picks k (its within-E half holds up to k = 20);
 * test_pinch_error.c runs the pinch point at the coarsest cell the rule allows. */
Test(singular_depth, klein_coarser_tube_within_the_bound)
{
    const pf_surface s = {KLEIN, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-4, -4, -4, 4, 4, 4}, e = 3.27e-3;
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_poly_options o;
        ism_poly_options_default(&o);
        pf_sweep_box(base, 10, which, o.box);
        o.min_depth = 3, o.max_depth = 10, o.threads = 1, o.max_error = e;
        cr_expect_eq(ism_singular_depth(&o), 9, "box %d", which);
        ism_mesh m;
        ism_locus l;
        ism_poly_stats st;
        pf_mesh_surface_with(t, &o, &m, &l, &st);
        expect_klein_topology(t, &m, &l, which);
        ism_analysis a;
        pf_analyse_plain(&m, t, &a);
        cr_expect_leq(a.max_dist_centroid, e, "box %d: centroid %g", which, a.max_dist_centroid);
        cr_expect_leq(a.max_dist_midpoint, e, "box %d: midpoint %g", which, a.max_dist_midpoint);
        ism_analysis_free(&a);
        ism_locus_free(&l);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* x y = 0 at the default bound (1e-3 x the diagonal of the box ±1): the cells along the z axis
 * fail the plot test at every level (two sheets; a zero gradient on the axis) and their
 * triangles miss E, but they lie in the conformance tube: with depth.max 10 the octree stops
 * where it stops with 8, so the polygoniser's own triangles and the mesh are the same, and the
 * mesh is within E (the planes: f = x y, |f| / |grad f| is the distance off the axis). */
Test(singular_depth, crossing_planes_stop_at_the_tube)
{
    const pf_surface s = {"x*y", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-1, -1, -1, 1, 1, 1}, e = 2e-3 * sqrt(3);
    for (int which = pf_first_box() - 1; which < 2; which++) {
        ism_poly_options o;
        ism_poly_options_default(&o);
        pf_sweep_box(base, 10, which, o.box);
        o.min_depth = 3, o.threads = 1, o.max_error = e;
        ism_mesh m8, m10;
        ism_locus l8, l10;
        ism_poly_stats p8, p10;
        o.max_depth = 8;
        pf_mesh_surface_with(t, &o, &m8, &l8, &p8);
        o.max_depth = 10;
        pf_mesh_surface_with(t, &o, &m10, &l10, &p10);
        cr_expect_eq(p8.triangles, p10.triangles, "box %d: raw triangles %llu at 8, %llu at 10",
                     which, (unsigned long long)p8.triangles, (unsigned long long)p10.triangles);
        pf_same_mesh(&m8, &m10, "x y = 0: depth.max 8 and 10 under the default bound");
        cr_expect_eq(l10.ncurves, 1, "box %d: %zu curves", which, l10.ncurves);
        expect_within_and_free(t, e, which, &m8, &m10, &l8, &l10);
    }
    ism_tape_free(t);
}
