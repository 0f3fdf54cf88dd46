/* test_remesh.c — the quality pass (core/remesh/) on polygonised meshes, measured with the
 * fixture's own edge counting: a sphere gets no triangle under 20° with χ and vertices on
 * f = 0 kept; a hemisphere cut by the box keeps every boundary vertex on the cut (in the face,
 * on f = 0) and every boundary edge, and its needles at the cut are mended. (Collapses and the
 * renumbering: test_remesh_collapse.c; non-manifold edges and points:
 * tests/cli/test_quality.py, through the conformance that makes them.) The per-triangle
 * centroid record (rm_cbound.h), a bound taken rather than a measure, leaves the gyroid in a
 * ball (its crease, where |∇f| jumps) and Steiner's surface (where the centroid rule refuses
 * moves: taking every centroid as within the bound changes its mesh) bit for bit as the
 * reference path that measures them all. */
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
    cr_assert(ism_remesh_quality(m, &o, st, NULL, &err), "%s", err.message);
    pf_measure(m, *tape, after);
}

Test(remesh, sphere_has_no_triangle_under_20_degrees)
{
    /* box shifted by √2 − 1 of a finest cell so no lattice plane runs through the centre */
    int d = 6 - pf_quick();
    const double c = PF_IRR * 3.0 / (1 << d);
    const double box[6] = {-1.5 + c, -1.5 - c, -1.5 + c, 1.5 + c, 1.5 - c, 1.5 + c};
    ism_mesh m;
    pf_props b, a;
    ism_remesh_stats st;
    ism_tape *t;
    remesh("x^2 + y^2 + z^2 - 1", box, d, &m, &b, &a, &st, &t);
    cr_expect_lt(st.min_angle_before, 20.0);
    cr_expect_geq(min_angle_deg(&m), 20.0, "%g", min_angle_deg(&m));
    cr_expect_eq(a.euler, 2);
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
    cr_assert(ism_remesh_quality(&m, &o, &st, NULL, &err));
    pf_measure(&m, t, &a);
    cr_expect_gt(st.moves, 0);
    cr_expect_eq(a.boundary_edges, b.boundary_edges);
    cr_expect_eq(a.euler, b.euler);
    size_t on_cut = 0;
    for (size_t v = 0; v < m.nverts; v++)
        if (fabs(before[3 * v + 2] - 0.3) < 1e-12) { /* a boundary vertex stays on the cut */
            const double *p = m.pos + 3 * v;
            on_cut++;
            cr_expect_eq(p[2], before[3 * v + 2]);
            cr_expect_leq(fabs(p[0] * p[0] + p[1] * p[1] + p[2] * p[2] - 1), 1e-9);
        }
    cr_expect_gt(on_cut, 0);
    free(before);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* The largest |(|c| - 1)| over the triangles' centroids c: the unit sphere's closed form. */
static double sphere_centroid_error(const ism_mesh *m)
{
    double worst = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            for (int j = 0; j < 3; j++)
                c[j] += m->pos[3 * m->tri[3 * t + k] + j] / 3;
        worst = fmax(worst, fabs(sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]) - 1));
    }
    return worst;
}

/* A box face cutting the sphere leaves boundary edges as short as the cut happens to make
 * them, and a needle on each that no flip or inner move can mend (kummer-16-nodes' box: 0.0008
 * beside 0.09). The pass slides such vertices along the cut circle, in the face and on f = 0.
 * In the box on the lattice and both shifted ones: every triangle at least 15° (measured
 * 25.7°, 25.8°, 26.6°; without the slide 21.6°, 17.1°, 9.5°: the 0.37-cell box fails), χ
 * and the boundary edges kept, every vertex on the face still on it (found through the
 * renumbering collapses make) and every vertex on the sphere (within 1e-9, or where the
 * polygoniser had put it), and the centroids no farther from the sphere than before. */
Test(remesh, box_cut_boundary_slides_along_the_cut)
{
    const double base[6] = {-1.5, -1.5, 0.3, 1.5, 1.5, 1.5};
    int d = 6 - pf_quick();
    pf_surface s = {.expr = "x^2 + y^2 + z^2 - 1"};
    ism_tape *t = pf_compile(&s);
    for (int which = -1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        ism_mesh m;
        ism_mesh_init(&m);
        ism_poly_stats ps;
        pf_run(t, box, 3, d, 1, &m, &ps);
        pf_props b, a;
        pf_measure(&m, t, &b);
        double err_before = sphere_centroid_error(&m), min_before = min_angle_deg(&m);
        size_t nverts_before = m.nverts;
        uint8_t *on_face = calloc(m.nverts, 1);
        double *off = calloc(m.nverts, sizeof *off); /* | |p| - 1 | before */
        for (size_t v = 0; v < m.nverts; v++) {
            const double *p = m.pos + 3 * v;
            on_face[v] = fabs(p[2] - box[2]) < 1e-12;
            off[v] = fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
        }
        ism_remesh_options o = {.f = t};
        ism_remesh_stats st;
        ism_remesh_renumber ren;
        ism_error err;
        cr_assert(ism_remesh_quality(&m, &o, &st, &ren, &err), "%s", err.message);
        pf_measure(&m, t, &a);
        cr_log_info("box %d: min angle %.2f -> %.2f, centroid error %.3g -> %.3g", which,
                    min_before, min_angle_deg(&m), err_before, sphere_centroid_error(&m));
        cr_expect_geq(min_angle_deg(&m), 15.0, "box %d: %g", which, min_angle_deg(&m));
        cr_expect_eq(a.euler, 1);
        cr_expect_eq(a.boundary_edges, b.boundary_edges);
        cr_expect_leq(sphere_centroid_error(&m), err_before, "box %d", which);
        cr_assert_eq(ren.nverts, nverts_before);
        for (size_t v = 0; v < ren.nverts; v++) { /* v: the index before the pass */
            if (ren.vert[v] == ISM_REMESH_GONE) {
                cr_expect(!on_face[v], "boundary vertex %zu collapsed", v);
                continue;
            }
            const double *p = m.pos + 3 * (size_t)ren.vert[v];
            double now = fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
            cr_expect_leq(now, fmax(1e-9, off[v]), "vertex %zu: %g, was %g", v, now, off[v]);
            if (on_face[v])
                cr_expect_eq(p[2], box[2], "vertex %zu left the face", v);
        }
        ism_remesh_renumber_free(&ren);
        free(on_face);
        free(off);
        ism_mesh_free(&m);
    }
    ism_tape_free(t);
}

/* The pass on f's mesh in box at depth 3:d, with the centroid record (under max_error E > 0:
 * the bounded record, rm_brec.h) and on the reference path, into m1 and m2. */
static void both_paths(const ism_tape *t, const double box[6], int d, double E, ism_mesh *m1,
                       ism_mesh *m2)
{
    ism_poly_stats ps;
    ism_mesh_init(m1);
    ism_mesh_init(m2);
    pf_run(t, box, 3, d, 1, m1, &ps);
    pf_run(t, box, 3, d, 1, m2, &ps);
    ism_remesh_options o = {.f = t, .max_error = E};
    ism_remesh_stats st;
    ism_error err;
    cr_assert(ism_remesh_quality(m1, &o, &st, NULL, &err), "%s", err.message);
    o.measure_all_centroids = true;
    cr_assert(ism_remesh_quality(m2, &o, &st, NULL, &err), "%s", err.message);
    cr_assert_gt(st.moves, 100, "the pass moved %zu vertices", st.moves);
}

/* f's meshes in the box ±half at depth 3:d, in the lattice box and the fixture's two boxes off
 * it (pf_sweep_box: by 1e-3, and by fractions of a cell): the same bits on both paths, the
 * pass under max_error E (0: none). */
static void same_on_both_paths(const pf_surface *s, double half, int d, double E)
{
    ism_tape *t = pf_compile(s);
    const double base[6] = {-half, -half, -half, half, half, half};
    for (int b = -1; b < 2; b++) {
        double box[6];
        pf_sweep_box(base, d, b, box);
        ism_mesh m1, m2;
        both_paths(t, box, d, E, &m1, &m2);
        cr_assert_eq(m1.nverts, m2.nverts, "%s box %d", s->expr, b);
        cr_assert_eq(m1.ntris, m2.ntris, "%s box %d", s->expr, b);
        cr_expect(!memcmp(m1.pos, m2.pos, 3 * m1.nverts * sizeof *m1.pos), "%s box %d", s->expr, b);
        cr_expect(!memcmp(m1.tri, m2.tri, 3 * m1.ntris * sizeof *m1.tri), "%s box %d", s->expr, b);
        ism_mesh_free(&m1);
        ism_mesh_free(&m2);
    }
    ism_tape_free(t);
}

Test(remesh, centroid_record_leaves_the_reference_mesh)
{
    ism_param k = {.name = "k", .value = 4};
    pf_surface gyroid = {.expr = "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + "
                                 "sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
                         .params = &k, .nparams = 1};
    pf_surface steiner = {.expr = "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z"};
    same_on_both_paths(&gyroid, 1.5, 6 - pf_quick(), 0);
    same_on_both_paths(&steiner, 1.0, 6 - pf_quick(), 0);
}

/* Under an error bound a fan's centroid or midpoint is not measured when what its triangle
 * knows, moved as far as the point moved, is within half the bound (rm_brec.h): every such
 * point measures within the bound, so the pass decides as when it measures every one. At 1e-3
 * of the box diagonal: the gyroid sheet, where the records are kept through the pass
 * (depth 6: about 205,000 points spared by the plain bound and 197,000 by the bent one, per
 * box); and the gyroid in a ball, where f creases and the pass takes no records (remesh.c):
 * with them, its third box's mesh changes (a centroid spared at 0.00257, twice its record
 * moved, measured 0.00520 against E 0.00520: across the crease |f|/|∇f| jumps). */
Test(remesh, bounded_record_leaves_the_reference_mesh)
{
    ism_param k = {.name = "k", .value = 4};
    pf_surface sheet = {.expr = "sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x)",
                        .params = &k, .nparams = 1};
    pf_surface ball = {.expr = "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + "
                               "sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
                       .params = &k, .nparams = 1};
    same_on_both_paths(&sheet, 1.5, 6 - pf_quick(), 1e-3 * 3 * sqrt(3));
    same_on_both_paths(&ball, 1.5, 6 - pf_quick(), 1e-3 * 3 * sqrt(3));
}
