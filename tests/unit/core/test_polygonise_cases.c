/* test_polygonise_cases.c — behaviour around the edges of the polygoniser: near-touching
 * parts stay apart, an empty box gives an empty mesh, adaptivity pays, output is
 * deterministic and independent of the thread count (the gyroid ball and Barth's nodal sextic,
 * each in the three placements), budgets and bad options fail clearly. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>
#include "poly_fixture.h"

static const pf_surface two_spheres = {
    "min((x - 1.0005)^2 + y^2 + z^2 - 1, (x + 1.0005)^2 + y^2 + z^2 - 1)", NULL, 0, NULL, 0};
static const double two_box[6] = {-2.3, -1.3, -1.2, 2.4, 1.4, 1.3};
static const pf_surface gyroid = {
    "max(sin(4*x)*cos(4*y) + sin(4*y)*cos(4*z) + sin(4*z)*cos(4*x), x^2 + y^2 + z^2 - 1.96)",
    NULL, 0, NULL, 0};
static const double cube15[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};

Test(cases, spheres_a_thousandth_apart_stay_two)
{
    ism_tape *t = pf_compile(&two_spheres);
    for (int d = 6; d <= 8 - pf_quick(); d++) {
        ism_mesh m;
        ism_poly_stats st;
        pf_run(t, two_box, 3, d, 0, &m, &st);
        pf_props p;
        pf_measure(&m, t, &p);
        cr_expect_eq(p.components, 2, "depth %d: %zu components", d, p.components);
        cr_expect_eq(p.euler, 4, "depth %d: Euler characteristic %ld (two spheres: 4)", d, p.euler);
        cr_expect_eq(p.boundary_edges + p.nonmanifold_edges, 0, "depth %d: open or joined", d);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

Test(cases, empty_box_gives_empty_mesh)
{
    const pf_surface s = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};
    const double box[6] = {2, 2, 2, 3, 3, 3};
    ism_tape *t = pf_compile(&s);
    ism_mesh m;
    ism_poly_stats st;
    pf_run(t, box, 3, 7, 0, &m, &st);
    cr_expect_eq(m.ntris, 0);
    cr_expect_eq(m.nverts, 0);
    cr_expect_eq(st.plotting_nodes, 0, "no node may survive the interval test");
    cr_expect_eq(st.nodes_excluded, 1, "the root alone is excluded");
    ism_mesh_free(&m);
    ism_tape_free(t);
}

Test(cases, adaptive_beats_uniform)
{
    const pf_surface s = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    int d = 7; /* cheap even under sanitizers; adaptivity pays more the deeper it goes */
    ism_mesh a, u;
    ism_poly_stats sa, su;
    pf_run(t, cube15, 3, d, 0, &a, &sa);
    pf_run(t, cube15, d, d, 0, &u, &su);
    cr_expect_lt(a.ntris * 4, u.ntris, "adaptive %zu triangles vs uniform %zu", a.ntris, u.ntris);
    ism_mesh_free(&a);
    ism_mesh_free(&u);
    ism_tape_free(t);
}

static void expect_same_mesh(const ism_mesh *a, const ism_mesh *b, const char *what)
{
    cr_assert_eq(a->nverts, b->nverts, "%s: %zu vs %zu vertices", what, a->nverts, b->nverts);
    cr_assert_eq(a->ntris, b->ntris, "%s: %zu vs %zu triangles", what, a->ntris, b->ntris);
    cr_expect(memcmp(a->pos, b->pos, a->nverts * 3 * sizeof *a->pos) == 0, "%s: positions", what);
    cr_expect(memcmp(a->normal, b->normal, a->nverts * 3 * sizeof *a->normal) == 0, "%s: normals",
              what);
    cr_expect(memcmp(a->tri, b->tri, a->ntris * 3 * sizeof *a->tri) == 0, "%s: triangles", what);
}

/* t in base's three placements (pf_sweep_box at depth d): 1, 2 and 4 threads make the same
 * bytes, each mesh with more than min_tris triangles and (registry) more than 2^15 leaf
 * corners when asked, so the break-point registry's parallel path runs. */
static void same_on_1_2_4_threads(const ism_tape *t, const double base[6], int d, size_t min_tris,
                                  bool registry, const char *name)
{
    for (int which = pf_first_box() - 1; which <= 1; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        ism_mesh m[3];
        ism_poly_stats st;
        static const int threads[3] = {1, 2, 4};
        for (int k = 0; k < 3; k++)
            pf_run(t, box, 3, d, threads[k], &m[k], &st);
        cr_assert_gt(m[0].ntris, min_tris, "%s, placement %d: %zu triangles", name, which,
                     m[0].ntris);
        if (registry)
            cr_assert_gt(8 * st.nodes_visited, (uint64_t)1 << 15,
                         "%s, placement %d: %llu nodes: the registry's serial path", name, which,
                         (unsigned long long)st.nodes_visited);
        char what[96];
        snprintf(what, sizeof what, "%s, placement %d: one thread vs two", name, which);
        expect_same_mesh(&m[0], &m[1], what);
        snprintf(what, sizeof what, "%s, placement %d: one thread vs four", name, which);
        expect_same_mesh(&m[0], &m[2], what);
        for (int k = 0; k < 3; k++)
            ism_mesh_free(&m[k]);
    }
}

/* The gyroid in a ball (the thread-scaling goal's surface, a crease where the two meet) in
 * the three placements. */
Test(cases, deterministic_and_thread_independent)
{
    ism_tape *t = pf_compile(&gyroid);
    same_on_1_2_4_threads(t, cube15, 6 - pf_quick(), 1000, false, "gyroid-ball");
    ism_tape_free(t);
}

/* Barth's sextic (65 nodes) in a ball in the three placements, the last off the octree
 * lattice by irrational fractions of a finest cell: the break-point registry, the work
 * stealing and the weld on 1, 2 and 4 threads make the same bytes (the registry's parallel
 * path starts at 2^15 corners: reached here). */
Test(cases, nodal_sextic_thread_independent_off_lattice)
{
    const double base[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    ism_tape *t = pf_compile(&pf_barth_sextic);
    same_on_1_2_4_threads(t, base, 6 - pf_quick(), 5000, true, "barth-sextic");
    ism_tape_free(t);
}

Test(cases, triangle_budget_is_a_clear_error)
{
    ism_tape *t = pf_compile(&gyroid);
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, cube15, sizeof o.box);
    o.max_depth = 6;
    o.max_triangles = 1000;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats st;
    ism_error err;
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_TOO_BIG);
    cr_expect(strstr(err.message, "budget") != NULL, "message: %s", err.message);
    cr_expect_eq(m.ntris, 0, "no partial mesh");
    ism_mesh_free(&m);
    ism_tape_free(t);
}

Test(cases, cancellation_stops_the_run)
{
    ism_tape *t = pf_compile(&gyroid);
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, cube15, sizeof o.box);
    volatile int cancel = 1;
    o.cancel = &cancel;
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats st;
    ism_error err;
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_CANCELLED);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

Test(cases, bad_options_name_the_field)
{
    const pf_surface s = {"x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_poly_options o;
    ism_error err;
    ism_mesh m;
    ism_poly_stats st;
    ism_mesh_init(&m);

    ism_poly_options_default(&o);
    o.box[3] = o.box[0];
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_BAD_OPTIONS);
    cr_expect(strstr(err.message, "box") != NULL, "%s", err.message);

    ism_poly_options_default(&o);
    o.max_depth = 17;
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_BAD_OPTIONS);
    cr_expect(strstr(err.message, "depth.max") != NULL, "%s", err.message);

    ism_poly_options_default(&o);
    o.min_depth = 5;
    o.max_depth = 4;
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_BAD_OPTIONS);

    ism_poly_options_default(&o);
    o.gradient_test = 2;
    cr_expect_eq(ism_polygonise(t, &o, &m, &st, &err), ISM_POLY_BAD_OPTIONS);
    cr_expect(strstr(err.message, "gradient_test") != NULL, "%s", err.message);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* The helicoid x sin 2z = y cos 2z contains its axis (a lattice line in a box centred on
 * it) and, at z = ±π/4, rulings lying in the lattice plane x = 0 that leave the axis. Cut by
 * the box it is a disk: χ = 1, one piece. The rulings once had no partner on the zero run
 * of the axis (a hole of four triangles at each, χ = −1). */
Test(cases, helicoid_axis_on_the_lattice)
{
    static const ism_param k2[] = {{"k", 2}};
    const pf_surface helicoid = {"x*sin(k*z) - y*cos(k*z)", k2, 1, NULL, 0};
    ism_tape *t = pf_compile(&helicoid);
    const double base[6] = {-1.2, -1.2, -1.2, 1.2, 1.2, 1.2};
    int d = 6;
    for (int w = -1; w < 2; w++) {
        double box[6];
        ism_mesh m;
        pf_props p;
        pf_run_placed(t, base, d, w, box, &m, &p);
        cr_expect_eq(p.euler, 1, "box %d: χ = %ld, a disk has 1", w, p.euler);
        cr_expect_eq(p.components, 1, "box %d: %zu components", w, p.components);
        cr_expect_eq(p.nonmanifold_edges, 0, "box %d: %zu non-manifold edges", w,
                     p.nonmanifold_edges);
        cr_expect_eq(pf_count_edges(&m, 1, 1, pf_inside_box, box), 0, "box %d: holes", w);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* Clebsch's diagonal cubic is smooth and holds 27 real lines; in the box ±2 several are
 * lattice lines (x = 0, z = −1 …) and others run through the lattice points of a lattice
 * plane (x + z = 0 in y = 0), crossing the first at points where the surface is tangent to
 * that plane. Its mesh has no non-manifold edge and no boundary but the box's, and in every
 * box the χ of the surface in the box, −2 in one piece: so at depth 8 (cells 1/16 of those
 * here) in two boxes off the lattice, by 1e-3 and by √2 − 1 of a cell (4 boundary loops; the
 * same in the box [−2.0123, 1.9877] × [−1.9931, 2.0069] × [−2.0071, 1.9929]). These
 * crossings once had no line (open chains): 9 cone points, χ −20 in the own box at depth 6;
 * at depth 5, a tile of z = −1 with f = −3xy(x + y) zero on two sides and on its diagonal
 * through the centre passed for a tile of zeros (6 open chains, χ −8). */
Test(cases, clebsch_lines_on_the_lattice)
{
    const pf_surface clebsch = {"x^3 + y^3 + z^3 + 1 - (x + y + z + 1)^3", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&clebsch);
    const double base[6] = {-2, -2, -2, 2, 2, 2};
    for (int d = 5; d <= 6; d++) {
        for (int w = -1; w < 2; w++) {
            double box[6];
            pf_sweep_box(base, d, w, box);
            ism_mesh m;
            ism_poly_stats st;
            pf_run(t, box, 3, d, 0, &m, &st);
            pf_props p;
            pf_measure(&m, t, &p);
            cr_expect_eq(p.euler, -2, "depth %d box %d: χ = %ld", d, w, p.euler);
            cr_expect_eq(p.components, 1, "depth %d box %d: %zu components", d, w,
                         p.components);
            cr_expect_eq(p.nonmanifold_edges, 0, "depth %d box %d: %zu non-manifold edges", d,
                         w, p.nonmanifold_edges);
            cr_expect_eq(pf_count_edges(&m, 1, 1, pf_inside_box, box), 0,
                         "depth %d box %d: holes", d, w);
            cr_expect_eq(st.open_chains, 0, "depth %d box %d: %zu open chains", d, w,
                         st.open_chains);
            ism_mesh_free(&m);
        }
    }
    ism_tape_free(t);
}
