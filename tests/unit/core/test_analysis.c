/* test_analysis.c — the connectivity half of the mesh analysis on hand-built meshes whose
 * edges, cones, curves and topology follow from their construction: edge and vertex classes,
 * non-manifold curves and points, Euler characteristic, components, boundary loops,
 * orientability, genus, triangle quality, vertex areas, bad input and determinism. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "tests/unit/core/test_analysis_meshes.h"

static ism_analysis analyse(const ism_mesh *m)
{
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, NULL, NULL, &a, &err), "analysis failed: %s", err.message);
    return a;
}

static void assert_edges(const ism_analysis *a, size_t total, size_t boundary, size_t manifold,
                         size_t nonmanifold)
{
    cr_expect_eq(a->edges, total, "edges %zu, expected %zu", a->edges, total);
    cr_expect_eq(a->boundary_edges, boundary, "boundary edges %zu, expected %zu",
                 a->boundary_edges, boundary);
    cr_expect_eq(a->manifold_edges, manifold, "manifold edges %zu, expected %zu",
                 a->manifold_edges, manifold);
    cr_expect_eq(a->nonmanifold_edges, nonmanifold, "non-manifold edges %zu, expected %zu",
                 a->nonmanifold_edges, nonmanifold);
}

static size_t count_class(const ism_analysis *a, int cls)
{
    size_t n = 0;
    for (size_t v = 0; v < a->nverts; v++)
        n += a->vertex_class[v] == cls;
    return n;
}

Test(analysis, closed_cube_is_a_sphere)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    ism_analysis a = analyse(&m);
    /* 12 cube edges + 6 face diagonals, each on two triangles */
    assert_edges(&a, 18, 0, 18, 0);
    cr_expect_eq(a.euler, 2);
    cr_expect_eq(a.components, 1);
    cr_expect_eq(a.vertex_components, 1);
    cr_expect_eq(a.genus, 0);
    cr_expect(a.orientable);
    cr_expect_eq(a.inconsistent_edges, 0);
    cr_expect_eq(a.boundary_loops, 0);
    cr_expect_eq(a.class_count[ISM_VERTEX_MANIFOLD], 8);
    cr_expect_eq(count_class(&a, ISM_VERTEX_MANIFOLD), 8);
    cr_expect_eq(a.nonmanifold_vertices, 0);
    cr_expect_eq(a.ncurves, 0);
    cr_expect_eq(a.npoints, 0);
    cr_expect(a.component[0].closed && a.component[0].manifold && a.component[0].orientable);
    cr_expect_eq(a.component[0].euler, 2);
    cr_expect_eq(a.component[0].triangles, 12);
    cr_expect_eq(a.component[0].vertices, 8);
    cr_expect_eq(a.component[0].edges, 18);
    cr_expect_eq(a.triangles_used, 12);
    cr_expect_eq(a.vertices_used, 8);
    cr_expect_float_eq(a.area, 6.0, 1e-12);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, flipped_triangle_is_still_orientable_but_not_oriented)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    uint32_t t = m.tri[0];
    m.tri[0] = m.tri[1];
    m.tri[1] = t;
    ism_analysis a = analyse(&m);
    cr_expect(a.orientable);
    cr_expect_eq(a.inconsistent_edges, 3); /* the flipped triangle's three edges */
    cr_expect_eq(a.genus, 0);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, two_fans_sharing_their_apex)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t apex = ta_vertex(&m, 0, 0, 0);
    ta_fan(&m, apex, 4, 1);
    ta_fan(&m, apex, 4, -1);
    ism_analysis a = analyse(&m);
    /* 8 spokes (two triangles each) + 8 ring edges (one triangle each) */
    assert_edges(&a, 16, 8, 8, 0);
    cr_expect_eq(a.vertex_class[apex], ISM_VERTEX_NONMANIFOLD_POINT);
    cr_expect_eq(count_class(&a, ISM_VERTEX_BOUNDARY), 8);
    cr_expect_eq(a.nonmanifold_vertices, 1);
    cr_expect_eq(a.npoints, 1);
    cr_expect_eq(a.points[0], apex);
    cr_expect_eq(a.point_kind[0], ISM_POINT_CONES);
    cr_expect_eq(a.point_pos[0], 0.0);
    cr_expect_eq(a.point_pos[1], 0.0);
    cr_expect_eq(a.point_pos[2], 0.0);
    cr_expect_eq(a.ncurves, 0);
    cr_expect_eq(a.euler, 9 - 16 + 8);
    cr_expect_eq(a.components, 2);        /* no shared edge */
    cr_expect_eq(a.vertex_components, 1); /* but one shared vertex */
    cr_expect_eq(a.boundary_loops, 2);
    for (int c = 0; c < 2; c++) { /* each cone alone is a disc */
        cr_expect_eq(a.component[c].euler, 1);
        cr_expect_eq(a.component[c].boundary_loops, 1);
        cr_expect(a.component[c].manifold);
        cr_expect_eq(a.component[c].genus, 0);
    }
    cr_expect_eq(a.genus, -1);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, two_cubes_touching_at_a_corner)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    ta_cube(&m);
    /* move the second cube to [1,2]³ and weld its corner (0,0,0)+1 onto vertex 7 = (1,1,1) */
    for (size_t v = 8; v < 16; v++)
        for (int k = 0; k < 3; k++)
            m.pos[3 * v + k] += 1;
    for (size_t i = 36; i < 72; i++)
        if (m.tri[i] == 8)
            m.tri[i] = 7;
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.vertices_used, 15);
    cr_expect_eq(a.euler, 15 - 36 + 24);
    cr_expect_eq(a.vertex_class[7], ISM_VERTEX_NONMANIFOLD_POINT);
    cr_expect_eq(a.vertex_class[8], ISM_VERTEX_ISOLATED);
    cr_expect_eq(a.class_count[ISM_VERTEX_MANIFOLD], 14);
    cr_expect_eq(a.components, 2);
    cr_expect_eq(a.vertex_components, 1);
    for (int c = 0; c < 2; c++) {
        cr_expect_eq(a.component[c].vertices, 8); /* the shared corner counts in both */
        cr_expect_eq(a.component[c].euler, 2);
        cr_expect_eq(a.component[c].genus, 0);
        cr_expect(a.component[c].closed && a.component[c].manifold);
    }
    cr_expect_eq(a.component[0].first_triangle, 0);
    cr_expect_eq(a.component[1].first_triangle, 12);
    cr_expect_eq(a.genus, -1); /* two components */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, three_triangles_on_one_edge)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t p = ta_vertex(&m, 0, 0, 0), q = ta_vertex(&m, 1, 0, 0);
    uint32_t r = ta_vertex(&m, 0.5, 1, 0), s = ta_vertex(&m, 0.5, -1, 0);
    uint32_t t = ta_vertex(&m, 0.5, 0, 1);
    ta_triangle(&m, p, q, r);
    ta_triangle(&m, q, p, s);
    ta_triangle(&m, p, q, t);
    ism_analysis a = analyse(&m);
    assert_edges(&a, 7, 6, 0, 1);
    cr_expect_eq(a.euler, 5 - 7 + 3);
    cr_expect_eq(a.ncurves, 1);
    cr_expect_eq(a.curve_start[0], 0);
    cr_expect_eq(a.curve_start[1], 2); /* one curve of one edge */
    cr_expect_eq(a.curve_verts[0], p);
    cr_expect_eq(a.curve_verts[1], q);
    cr_expect_eq(a.vertex_class[p], ISM_VERTEX_NONMANIFOLD_EDGE);
    cr_expect_eq(a.vertex_class[q], ISM_VERTEX_NONMANIFOLD_EDGE);
    cr_expect_eq(a.vertex_class[r], ISM_VERTEX_BOUNDARY);
    cr_expect_eq(a.nonmanifold_vertices, 2);
    cr_expect_eq(a.npoints, 2); /* both ends of the curve */
    cr_expect_eq(a.points[0], p);
    cr_expect_eq(a.points[1], q);
    cr_expect_eq(a.point_kind[0], ISM_POINT_CURVE_END);
    cr_expect_eq(a.point_kind[1], ISM_POINT_CURVE_END);
    cr_expect_eq(a.point_pos[3], 1.0);
    /* each triangle's two free edges form an arc ending on the non-manifold edge */
    cr_expect_eq(a.boundary_loops, 0);
    cr_expect_eq(a.boundary_chains, 3);
    cr_expect_eq(a.components, 1);
    cr_expect(!a.component[0].manifold);
    cr_expect_eq(a.component[0].genus, -1);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, moebius_strip_is_not_orientable)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_moebius(&m, 8);
    ism_analysis a = analyse(&m);
    /* 8 rungs, 16 rails, 8 diagonals; the 16 rails are the boundary */
    assert_edges(&a, 32, 16, 16, 0);
    cr_expect_eq(a.euler, 0);
    cr_expect_eq(a.boundary_loops, 1); /* one loop runs twice around */
    cr_expect_eq(a.boundary_chains, 0);
    cr_expect(!a.orientable);
    cr_expect(!a.component[0].orientable);
    cr_expect_eq(a.component[0].genus, -1);
    cr_expect_eq(a.class_count[ISM_VERTEX_BOUNDARY], 16);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, cylinder_has_two_boundary_loops_and_is_orientable)
{
    /* the Möbius strip's builder without the twist: make the last quad close straight */
    ism_mesh m;
    ism_mesh_init(&m);
    ta_moebius(&m, 8);
    /* last quad (triangles 14, 15) = (7, 15, 0) (7, 0, 8): the twist joins top 7 to bottom 0
     * (vertex 8) and bottom 7 to top 0; straighten it to (7, 15, 8) (7, 8, 0) */
    size_t last = 3 * 14;
    m.tri[last + 2] = 8;
    m.tri[last + 4] = 8;
    m.tri[last + 5] = 0;
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.euler, 0);
    cr_expect_eq(a.boundary_loops, 2);
    cr_expect(a.orientable);
    cr_expect_eq(a.component[0].genus, 0); /* 0 = 2 - 2g - 2 */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, disc_has_one_boundary_loop)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_disc(&m, 12);
    ism_analysis a = analyse(&m);
    assert_edges(&a, 24, 12, 12, 0);
    cr_expect_eq(a.euler, 1);
    cr_expect_eq(a.boundary_loops, 1);
    cr_expect_eq(a.boundary_chains, 0);
    cr_expect_eq(a.vertex_class[0], ISM_VERTEX_MANIFOLD);
    cr_expect_eq(a.class_count[ISM_VERTEX_BOUNDARY], 12);
    cr_expect(a.orientable);
    cr_expect(!a.component[0].closed);
    cr_expect_eq(a.component[0].genus, 0);
    cr_expect_eq(a.genus, -1); /* the global figure is for closed meshes */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, torus_grid_has_genus_one)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_torus(&m, 12, 8, 2, 0.5);
    ism_analysis a = analyse(&m);
    assert_edges(&a, 3 * 96, 0, 3 * 96, 0);
    cr_expect_eq(a.euler, 0);
    cr_expect_eq(a.genus, 1);
    cr_expect(a.orientable);
    cr_expect_eq(a.inconsistent_edges, 0);
    cr_expect_eq(a.class_count[ISM_VERTEX_MANIFOLD], 96);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, two_tori_and_a_cube_are_three_components)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_torus(&m, 6, 5, 2, 0.5);
    ta_cube(&m);
    ta_torus(&m, 6, 5, 5, 0.5);
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.components, 3);
    cr_expect_eq(a.euler, 0 + 2 + 0);
    cr_expect_eq(a.component[0].genus, 1);
    cr_expect_eq(a.component[1].genus, 0);
    cr_expect_eq(a.component[2].genus, 1);
    cr_expect_eq(a.component[1].first_triangle, 60);
    cr_expect_eq(a.genus, -1);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, crossing_planes_have_one_curve_along_the_crossing)
{
    ism_mesh m;
    ism_mesh_init(&m);
    int k = 4;
    ta_plane_grid(&m, 0, 1, k); /* z = 0 */
    ta_plane_grid(&m, 0, 2, k); /* y = 0, sharing the k + 1 vertices on the x axis */
    ism_analysis a = analyse(&m);
    size_t per_plane = 2 * k * (k + 1) + k * k;
    assert_edges(&a, 2 * per_plane - k, 2 * 4 * k, 2 * per_plane - k - 8 * k - k, k);
    cr_expect_eq(a.vertices_used, 2 * (k + 1) * (k + 1) - (k + 1));
    cr_expect_eq(a.euler, 1); /* four half-squares glued along one segment */
    cr_expect_eq(a.ncurves, 1);
    cr_expect_eq(a.curve_start[1], k + 1);
    uint32_t first = a.curve_verts[0], last = a.curve_verts[k];
    cr_expect_neq(first, last); /* open */
    for (int i = 0; i <= k; i++) {
        const double *p = m.pos + 3 * a.curve_verts[i];
        cr_expect(p[1] == 0 && p[2] == 0, "curve vertex off the x axis");
        /* in order along the axis */
        double x = -1 + 2.0 * i / k;
        double x_rev = 1 - 2.0 * i / k;
        cr_expect(fabs(p[0] - x) < 1e-12 || fabs(p[0] - x_rev) < 1e-12);
    }
    cr_expect_eq(a.npoints, 2);
    for (size_t i = 0; i < a.npoints; i++) {
        cr_expect_eq(a.point_kind[i], ISM_POINT_CURVE_END);
        cr_expect_float_eq(fabs(a.point_pos[3 * i]), 1.0, 1e-12);
        cr_expect_eq(a.point_pos[3 * i + 1], 0.0);
        cr_expect_eq(a.point_pos[3 * i + 2], 0.0);
    }
    cr_expect_eq(a.class_count[ISM_VERTEX_NONMANIFOLD_EDGE], k + 1);
    cr_expect_eq(a.boundary_loops, 0);
    cr_expect_eq(a.boundary_chains, 4); /* each half-square's arc ends on the crossing line */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, three_coordinate_planes_meet_at_a_junction)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_plane_grid(&m, 0, 1, 2);
    ta_plane_grid(&m, 0, 2, 2);
    ta_plane_grid(&m, 1, 2, 2);
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.nonmanifold_edges, 6); /* the half-axes, 4 triangles each */
    cr_expect_eq(a.ncurves, 6);           /* broken at the origin, where 6 edges meet */
    uint32_t origin = UINT32_MAX;
    for (size_t v = 0; v < m.nverts; v++)
        if (m.pos[3 * v] == 0 && m.pos[3 * v + 1] == 0 && m.pos[3 * v + 2] == 0)
            origin = (uint32_t)v;
    for (size_t c = 0; c < a.ncurves; c++) {
        cr_expect_eq(a.curve_start[c + 1] - a.curve_start[c], 2);
        uint32_t u = a.curve_verts[a.curve_start[c]], w = a.curve_verts[a.curve_start[c] + 1];
        cr_expect(u == origin || w == origin);
    }
    cr_expect_eq(a.npoints, 7);
    size_t junctions = 0, ends = 0;
    for (size_t i = 0; i < a.npoints; i++) {
        junctions += a.point_kind[i] == ISM_POINT_JUNCTION;
        ends += a.point_kind[i] == ISM_POINT_CURVE_END;
        if (a.point_kind[i] == ISM_POINT_JUNCTION)
            cr_expect_eq(a.points[i], origin);
    }
    cr_expect_eq(junctions, 1);
    cr_expect_eq(ends, 6);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, fin_around_a_torus_is_a_closed_curve)
{
    ism_mesh m;
    ism_mesh_init(&m);
    int nu = 10, nv = 6;
    ta_torus(&m, nu, nv, 2, 0.5);
    /* a fin along the outer equator j = 0: one extra triangle on each of its nu edges */
    for (int i = 0; i < nu; i++) {
        uint32_t a = (uint32_t)(i * nv), b = (uint32_t)(((i + 1) % nu) * nv);
        const double *p = m.pos + 3 * a;
        uint32_t tip = ta_vertex(&m, p[0] * 1.5, p[1] * 1.5, 0);
        ta_triangle(&m, a, b, tip);
    }
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.nonmanifold_edges, nu);
    cr_expect_eq(a.ncurves, 1);
    cr_expect_eq(a.curve_start[1], nu + 1);
    cr_expect_eq(a.curve_verts[0], a.curve_verts[nu]); /* closed */
    cr_expect_eq(a.curve_verts[0], 0);                 /* starts at its smallest vertex */
    cr_expect_eq(a.npoints, 0); /* no end, no junction */
    cr_expect_eq(a.class_count[ISM_VERTEX_NONMANIFOLD_EDGE], nu);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, bowtie_has_two_loops_through_one_vertex)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t c = ta_vertex(&m, 0, 0, 0);
    uint32_t a1 = ta_vertex(&m, 1, 1, 0), a2 = ta_vertex(&m, 1, -1, 0);
    uint32_t b1 = ta_vertex(&m, -1, 1, 0), b2 = ta_vertex(&m, -1, -1, 0);
    ta_triangle(&m, c, a2, a1);
    ta_triangle(&m, c, b1, b2);
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.vertex_class[c], ISM_VERTEX_NONMANIFOLD_POINT);
    cr_expect_eq(a.boundary_loops, 2);
    cr_expect_eq(a.boundary_chains, 0);
    cr_expect_eq(a.components, 2);
    cr_expect_eq(a.vertex_components, 1);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, collapsed_and_isolated_are_counted_not_used)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    uint32_t lone = ta_vertex(&m, 5, 5, 5);
    ta_triangle(&m, 0, 0, 1); /* collapsed */
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.collapsed_triangles, 1);
    cr_expect_eq(a.degenerate_triangles, 1);
    cr_expect_eq(a.triangles_used, 12);
    cr_expect_eq(a.euler, 2);
    cr_expect_eq(a.genus, 0);
    cr_expect_eq(a.vertex_class[lone], ISM_VERTEX_ISOLATED);
    cr_expect_eq(a.class_count[ISM_VERTEX_ISOLATED], 1);
    cr_expect_eq(a.triangle_min_angle[12], 0.0f);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, empty_mesh)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.edges, 0);
    cr_expect_eq(a.euler, 0);
    cr_expect_eq(a.components, 0);
    cr_expect_eq(a.genus, -1);
    cr_expect_eq(a.ncurves, 0);
    cr_expect_eq(a.curve_start[0], 0);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, bad_index_is_an_error)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    m.tri[7] = 8;
    ism_analysis a;
    ism_error err;
    cr_assert(!ism_analyse(&m, NULL, NULL, &a, &err));
    cr_expect(strstr(err.message, "triangle 2") && strstr(err.message, "vertex 8"), "%s",
              err.message);
    cr_expect_null(a.vertex_class);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, non_finite_coordinate_is_an_error)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    m.pos[3 * 5 + 1] = NAN;
    ism_analysis a;
    ism_error err;
    cr_assert(!ism_analyse(&m, NULL, NULL, &a, &err));
    cr_expect(strstr(err.message, "vertex 5"), "%s", err.message);
    ism_mesh_free(&m);
}

Test(analysis, bad_options_are_an_error)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.singular_rel = -1;
    ism_analysis a;
    ism_error err;
    cr_expect(!ism_analyse(&m, NULL, &o, &a, &err));
    cr_expect(strstr(err.message, "singular_rel"), "%s", err.message);
    ism_mesh_free(&m);
}

Test(analysis, same_mesh_same_analysis)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_plane_grid(&m, 0, 1, 6);
    ta_plane_grid(&m, 0, 2, 6);
    ta_plane_grid(&m, 1, 2, 6);
    ism_analysis a = analyse(&m), b = analyse(&m);
    cr_expect_eq(a.ncurves, b.ncurves);
    cr_expect_eq(memcmp(a.curve_start, b.curve_start, (a.ncurves + 1) * 4), 0);
    cr_expect_eq(memcmp(a.curve_verts, b.curve_verts, a.curve_start[a.ncurves] * 4), 0);
    cr_expect_eq(a.npoints, b.npoints);
    cr_expect_eq(memcmp(a.points, b.points, a.npoints * 4), 0);
    cr_expect_eq(memcmp(a.vertex_class, b.vertex_class, a.nverts), 0);
    ism_analysis_free(&a);
    ism_analysis_free(&b);
    ism_mesh_free(&m);
}

/* ---- triangle quality ---- */

Test(analysis_quality, smallest_angles_histogram_and_median)
{
    ism_mesh m;
    ism_mesh_init(&m);
    /* equilateral: 60°; right isosceles: 45°; sliver (0,0)(1,0)(1,0.1): atan(0.1) = 5.71° */
    uint32_t a0 = ta_vertex(&m, 0, 0, 0), a1 = ta_vertex(&m, 1, 0, 0);
    uint32_t a2 = ta_vertex(&m, 0.5, sqrt(3) / 2, 0);
    ta_triangle(&m, a0, a1, a2);
    uint32_t b0 = ta_vertex(&m, 0, 0, 1), b1 = ta_vertex(&m, 1, 0, 1);
    uint32_t b2 = ta_vertex(&m, 0, 1, 1);
    ta_triangle(&m, b0, b1, b2);
    uint32_t c0 = ta_vertex(&m, 0, 0, 2), c1 = ta_vertex(&m, 1, 0, 2);
    uint32_t c2 = ta_vertex(&m, 1, 0.1, 2);
    ta_triangle(&m, c0, c1, c2);
    ism_analysis a = analyse(&m);
    double sliver = atan(0.1) * 180 / M_PI;
    cr_expect_float_eq(a.triangle_min_angle[0], 60.0, 1e-4);
    cr_expect_float_eq(a.triangle_min_angle[1], 45.0, 1e-4);
    cr_expect_float_eq(a.triangle_min_angle[2], sliver, 1e-4);
    cr_expect_float_eq(a.min_angle, sliver, 1e-9);
    cr_expect_float_eq(a.median_angle, 45.0, 1e-4);
    cr_expect_float_eq(a.share_under_10, 1.0 / 3, 1e-12);
    cr_expect_eq(a.angle_hist[12], 1); /* 60 in [60, 65) */
    cr_expect_eq(a.angle_hist[9], 1);  /* 45 in [45, 50) */
    cr_expect_eq(a.angle_hist[1], 1);  /* 5.71 in [5, 10) */
    uint64_t total = 0;
    for (int i = 0; i < ISM_ANGLE_BINS; i++)
        total += a.angle_hist[i];
    cr_expect_eq(total, 3);
    cr_expect_eq(a.degenerate_triangles, 0);
    /* aspect = longest side × perimeter / (2 √3 × twice the area): 1 for the equilateral,
     * (√2 + 1) / √3 for the right isosceles, the sliver's from its sides 1, 0.1, √1.01 */
    double eq = 1, right = (sqrt(2) + 1) / sqrt(3);
    double thin = sqrt(1.01) * (1.1 + sqrt(1.01)) / (2 * sqrt(3) * 0.1);
    cr_expect_float_eq(a.aspect_max, thin, 1e-5);
    cr_expect_float_eq(a.aspect_mean, (eq + right + thin) / 3, 1e-5);
    cr_expect_float_eq(a.aspect_p99, right, 1e-5); /* rank floor(0.99 × 2) = 1 of 3 */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis_quality, even_count_median_is_the_midpoint)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t a0 = ta_vertex(&m, 0, 0, 0), a1 = ta_vertex(&m, 1, 0, 0);
    uint32_t a2 = ta_vertex(&m, 0.5, sqrt(3) / 2, 0);
    ta_triangle(&m, a0, a1, a2); /* 60 */
    uint32_t b2 = ta_vertex(&m, 0, 1, 0);
    ta_triangle(&m, a0, a1, b2); /* 45 */
    ism_analysis a = analyse(&m);
    cr_expect_float_eq(a.median_angle, 52.5, 1e-4);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis_quality, collinear_triangle_is_degenerate)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t p = ta_vertex(&m, 0, 0, 0), q = ta_vertex(&m, 1, 0, 0);
    uint32_t r = ta_vertex(&m, 3, 0, 0), s = ta_vertex(&m, 0, 1, 0);
    ta_triangle(&m, p, q, r);
    ta_triangle(&m, p, q, s);
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.degenerate_triangles, 1);
    cr_expect_eq(a.triangle_min_angle[0], 0.0f);
    cr_expect_float_eq(a.min_angle, 45.0, 1e-9); /* only the proper triangle counts */
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis_quality, vertex_areas_are_thirds_of_triangle_areas)
{
    ism_mesh m;
    ism_mesh_init(&m);
    /* unit square split along the diagonal 0-2: triangles of area 1/2 */
    uint32_t v0 = ta_vertex(&m, 0, 0, 0), v1 = ta_vertex(&m, 1, 0, 0);
    uint32_t v2 = ta_vertex(&m, 1, 1, 0), v3 = ta_vertex(&m, 0, 1, 0);
    ta_triangle(&m, v0, v1, v2);
    ta_triangle(&m, v0, v2, v3);
    ism_analysis a = analyse(&m);
    cr_expect_float_eq(a.area, 1.0, 1e-12);
    cr_expect_float_eq(a.vertex_area[v0], 1.0 / 3, 1e-12);
    cr_expect_float_eq(a.vertex_area[v2], 1.0 / 3, 1e-12);
    cr_expect_float_eq(a.vertex_area[v1], 1.0 / 6, 1e-12);
    cr_expect_float_eq(a.vertex_area[v3], 1.0 / 6, 1e-12);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, duplicate_triangles_are_counted)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ta_cube(&m);
    ta_triangle(&m, m.tri[2], m.tri[1], m.tri[0]); /* triangle 0 again, flipped */
    ta_triangle(&m, m.tri[3], m.tri[4], m.tri[5]); /* triangle 1 again */
    ta_triangle(&m, m.tri[4], m.tri[5], m.tri[3]); /* and once more, rotated */
    ism_analysis a = analyse(&m);
    cr_expect_eq(a.duplicate_triangles, 3);
    /* triangles 0 and 1 share the face diagonal: 2 + 3 copies on it; the other four edges
     * of the face carry one cube triangle from elsewhere plus the copies */
    cr_expect_eq(a.nonmanifold_edges, 5);
    ism_analysis_free(&a);
    ta_cube(&m); /* a second, separate cube: no duplicates across distinct vertices */
    a = analyse(&m);
    cr_expect_eq(a.duplicate_triangles, 3);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(analysis, vertex_only_in_collapsed_triangles_joins_nothing)
{
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t lone = ta_vertex(&m, 9, 9, 9);
    uint32_t a = ta_vertex(&m, 0, 0, 0), b = ta_vertex(&m, 1, 0, 0), c = ta_vertex(&m, 0, 1, 0);
    ta_triangle(&m, lone, lone, a); /* collapsed: ignored by the topology */
    ta_triangle(&m, a, b, c);
    ism_analysis an = analyse(&m);
    cr_expect_eq(an.vertex_class[lone], ISM_VERTEX_ISOLATED);
    cr_expect_eq(an.vertices_used, 3);
    cr_expect_eq(an.components, 1);
    cr_expect_eq(an.vertex_components, 1);
    cr_expect_eq(an.euler, 1);
    ism_analysis_free(&an);
    ism_mesh_free(&m);
}

/* The parallel passes (duplicate count per edge block, the connectivity passes on the side
 * thread) on a mesh past the pool's cut-off (analysis.c's POOL_MIN_TRIANGLES, 8192): a flat
 * 70 x 70 grid (9522 triangles) with 5 interior triangles copied at the ends of the mesh,
 * chosen on both sides of the triangle blocks' boundaries (ISM_AN_TRI_BLOCK 4096) and sharing
 * no edge: 5 duplicates, each edge of a copy carries 3 triangles (15 non-manifold edges);
 * the same counts, classes, curves and genus on 1, 2 and 4 threads (revB 4). */
static ism_analysis analyse_on(const ism_mesh *m, int threads)
{
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.threads = threads;
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, NULL, &o, &a, &err), "analysis failed: %s", err.message);
    return a;
}

Test(analysis, duplicates_and_curves_on_threads_past_the_pool_cutoff)
{
    enum { G = 70 };
    ism_mesh m;
    ism_mesh_init(&m);
    for (int r = 0; r < G; r++)
        for (int c = 0; c < G; c++)
            ta_vertex(&m, c, r, 0);
    for (uint32_t r = 0; r + 1 < G; r++)
        for (uint32_t c = 0; c + 1 < G; c++) {
            uint32_t v00 = r * G + c, v10 = v00 + 1, v01 = v00 + G, v11 = v01 + 1;
            ta_triangle(&m, v00, v10, v11);
            ta_triangle(&m, v00, v11, v01);
        }
    cr_assert_eq(m.ntris, 2 * (G - 1) * (G - 1));
    const size_t copied[] = {4095, 4096, 6000, 8191, 8192};
    for (size_t i = 0; i < 5; i++) {
        const uint32_t *t = m.tri + 3 * copied[i];
        uint32_t a = t[0], b = t[1], c = t[2];
        if (i % 2)
            ta_triangle(&m, c, b, a); /* flipped */
        else
            ta_triangle(&m, b, c, a); /* rotated */
    }
    ism_analysis one = analyse_on(&m, 1);
    cr_expect_eq(one.duplicate_triangles, 5);
    cr_expect_eq(one.nonmanifold_edges, 15);
    cr_expect_eq(one.ncurves, 5, "curves %zu: one closed loop around each copy", one.ncurves);
    for (int threads = 2; threads <= 4; threads *= 2) {
        ism_analysis a = analyse_on(&m, threads);
        cr_expect_eq(a.duplicate_triangles, 5, "%d threads", threads);
        cr_expect_eq(a.nonmanifold_edges, 15, "%d threads", threads);
        cr_expect_eq(a.nonmanifold_vertices, one.nonmanifold_vertices, "%d threads", threads);
        cr_expect_eq(a.genus, one.genus, "%d threads", threads);
        cr_expect_eq(a.nboundaries, one.nboundaries, "%d threads", threads);
        cr_expect(memcmp(a.vertex_class, one.vertex_class, m.nverts * sizeof *a.vertex_class)
                      == 0, "%d threads: vertex classes differ", threads);
        cr_assert_eq(a.ncurves, one.ncurves, "%d threads", threads);
        cr_expect(memcmp(a.curve_start, one.curve_start,
                         (one.ncurves + 1) * sizeof *a.curve_start) == 0 &&
                      memcmp(a.curve_verts, one.curve_verts,
                             one.curve_start[one.ncurves] * sizeof *a.curve_verts) == 0,
                  "%d threads: curves differ", threads);
        ism_analysis_free(&a);
    }
    ism_analysis_free(&one);
    ism_mesh_free(&m);
}
