/* test_features.c — boundary chains and the features JSON: a grid's boundary is one closed
 * loop that follows the triangles' winding; crossing planes' boundaries are four chains that
 * end on the crossing line; a closed torus has none; the JSON agrees with the analysis. */
#include <criterion/criterion.h>
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "proto/features.h"
#include "core/singular/check.h"
#include "tests/unit/proto/meshes_for_tests.h"

/* Number of triangles that use the undirected edge a-b, and whether one runs it a -> b. */
static int edge_use(const ism_mesh *m, uint32_t a, uint32_t b, bool *forward)
{
    int n = 0;
    *forward = false;
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t u = m->tri[3 * t + k], v = m->tri[3 * t + (k + 1) % 3];
            if ((u == a && v == b) || (u == b && v == a))
                n++;
            if (u == a && v == b)
                *forward = true;
        }
    return n;
}

Test(features, grid_boundary_is_one_loop_along_the_winding)
{
    ism_mesh m;
    test_mesh_grid(&m, 6);
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(&m, NULL, NULL, &a, &err));
    ism_features f;
    cr_assert(ism_features_build(&a, &f));
    const ism_polylines p = f.boundaries;
    cr_assert_eq(p.n, 1);
    cr_expect_eq(p.start[1] - p.start[0], 24 + 1, "24 edges, first vertex repeated");
    cr_expect_eq(p.verts[0], p.verts[24], "closed");
    for (uint32_t i = 0; i + 1 < p.start[1]; i++) {
        bool fwd;
        cr_expect_eq(edge_use(&m, p.verts[i], p.verts[i + 1], &fwd), 1);
        cr_expect(fwd, "the chain follows its triangle's winding");
        const double *q = m.pos + 3 * p.verts[i];
        cr_expect(q[0] == 0 || q[0] == 1 || q[1] == 0 || q[1] == 1, "on the square's rim");
    }
    ism_features_free(&f);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(features, crossing_planes_boundaries_are_chains_ending_on_the_crossing_line)
{
    /* the planes z = 0 and y = 0 share the line y = z = 0; each square's rim runs into that
     * line at x = ±1, where the cone of faces ends on a non-manifold edge: 4 half-rims */
    ism_mesh m;
    test_mesh_crossing_planes(&m, 4);
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(&m, NULL, NULL, &a, &err));
    ism_features f;
    cr_assert(ism_features_build(&a, &f));
    const ism_polylines p = f.boundaries;
    cr_expect_eq(p.n, 4);
    cr_expect_eq(a.boundary_chains, 4);
    cr_expect_eq(a.boundary_loops, 0);
    size_t edges = 0;
    for (size_t c = 0; c < p.n; c++) {
        uint32_t s = p.start[c], e = p.start[c + 1];
        cr_expect_neq(p.verts[s], p.verts[e - 1], "chain %zu is open", c);
        const uint32_t ends[2] = {p.verts[s], p.verts[e - 1]};
        for (int k = 0; k < 2; k++) {
            const double *q = m.pos + 3 * ends[k];
            cr_expect(q[1] == 0 && q[2] == 0 && fabs(q[0]) == 1,
                      "chain %zu ends at (%g, %g, %g), not on the crossing line's ends", c,
                      q[0], q[1], q[2]);
        }
        for (uint32_t i = s; i + 1 < e; i++, edges++) {
            bool fwd;
            cr_expect_eq(edge_use(&m, p.verts[i], p.verts[i + 1], &fwd), 1);
            cr_expect(fwd, "chain %zu follows its triangles' winding", c);
        }
    }
    cr_expect_eq(edges, a.boundary_edges);
    cr_expect_eq(edges, 2 * 16);
    ism_features_free(&f);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

Test(features, json_agrees_with_the_analysis)
{
    ism_mesh meshes[3];
    test_mesh_torus(&meshes[0], 24, 12, 1, 0.3);
    test_mesh_crossing_planes(&meshes[1], 6);
    test_mesh_touching_tetrahedra(&meshes[2]);
    for (int i = 0; i < 3; i++) {
        ism_mesh *m = &meshes[i];
        ism_analysis a;
        ism_error err;
        cr_assert(ism_analyse(m, NULL, NULL, &a, &err));
        ism_features f;
        cr_assert(ism_features_build(&a, &f));
        size_t n;
        char *text = ism_features_json(m, &f, &n);
        json_error_t je;
        json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
        cr_assert_not_null(doc, "%s", je.text);
        cr_expect_eq(json_integer_value(json_object_get(doc, "version")), 2);
        json_t *counts = json_object_get(doc, "counts");
        cr_expect_eq(json_array_size(json_object_get(doc, "nonmanifold_edges")), a.ncurves);
        cr_expect_eq(json_integer_value(json_object_get(counts, "nonmanifold_edges")),
                     (json_int_t)a.nonmanifold_edges);
        cr_expect_eq(json_array_size(json_object_get(doc, "nonmanifold_points")), a.npoints);
        cr_expect_eq(json_integer_value(json_object_get(counts, "boundary_edges")),
                     (json_int_t)a.boundary_edges);
        json_t *classes = json_object_get(doc, "classes");
        cr_expect_str_eq(json_string_value(json_array_get(classes, ISM_VERTEX_NONMANIFOLD_POINT)),
                         "nonmanifold_point");
        if (i == 2) {
            json_t *p = json_array_get(json_object_get(doc, "nonmanifold_points"), 0);
            cr_expect_eq(json_integer_value(json_object_get(p, "class")),
                         ISM_VERTEX_NONMANIFOLD_POINT);
            cr_expect_str_eq(json_string_value(json_object_get(p, "kind")), "cones");
        }
        json_decref(doc);
        free(text);
        ism_features_free(&f);
        ism_analysis_free(&a);
        ism_mesh_free(m);
    }
}

Test(features, empty_mesh_has_empty_features)
{
    ism_mesh m;
    ism_mesh_init(&m);
    ism_features f;
    cr_assert(ism_features_build(NULL, &f));
    size_t n;
    char *text = ism_features_json(&m, &f, &n);
    cr_expect_str_eq(text, "{\"version\":2,\"classes\":[\"manifold\",\"boundary\","
                           "\"nonmanifold_edge\",\"nonmanifold_point\",\"isolated\"],"
                           "\"singular_points\":[],\"curves\":[],\"double_sheets\":[],"
                           "\"nonmanifold_edges\":[],\"nonmanifold_points\":[],"
                           "\"boundaries\":[],\"incomplete\":false,\"counts\":"
                           "{\"singular_points\":0,\"certified\":0,\"uncertified\":0,"
                           "\"by_type\":{\"node\":0,\"isolated\":0,\"cusp\":0,"
                           "\"degenerate\":0,\"pinch\":0,\"triple\":0},\"curves\":0,"
                           "\"double_curves\":0,\"whisker_curves\":0,"
                           "\"certified_curves\":0,\"uncertified_curves\":0,\"double_sheets\":0,"
                           "\"nonmanifold_chains\":0,\"nonmanifold_edges\":0,"
                           "\"nonmanifold_points\":0,\"artefacts\":null,\"boundaries\":0,"
                           "\"boundary_edges\":0}}");
    free(text);
    ism_features_free(&f);
}

/* Crossing planes y = 0 and z = 0 (test mesh): their double line is the x axis. A locus that
 * lists the x axis as a double curve makes every non-manifold edge lie on it (no artefact);
 * a locus that lists a line elsewhere makes every one an artefact. The JSON carries the
 * locus in full precision and the check per element. */
Test(features, locus_and_check_in_the_json)
{
    ism_mesh m;
    test_mesh_crossing_planes(&m, 6);
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(&m, NULL, NULL, &a, &err));
    cr_assert_gt(a.nonmanifold_edges, 0);
    double lo[3], hi[3];
    cr_assert(ism_mesh_bounds(&m, lo, hi));
    double box[6] = {lo[0] - 1, lo[1] - 1, lo[2] - 1, hi[0] + 1, hi[1] + 1, hi[2] + 1};
    for (int wrong = 0; wrong < 2; wrong++) {
        ism_locus l;
        ism_locus_init(&l);
        ism_sing_curve c = {.kind = ISM_CURVE_DOUBLE, .n = 2, .end_type = {ISM_END_BOX, ISM_END_BOX},
                            .end_point = {-1, -1}};
        c.xyz = malloc(6 * sizeof *c.xyz);
        double off = wrong ? 0.25 * (hi[1] - lo[1]) : 0.0;
        double ends[6] = {lo[0], off, 0, hi[0], off, 0};
        memcpy(c.xyz, ends, sizeof ends);
        cr_assert(ism_locus_add_curve(&l, &c));
        ism_sing_point p = {.p = {0.1 / 3, 0, 0}, .type = ISM_SING_NODE, .certified = true,
                            .cones = -1};
        cr_assert(ism_locus_add_point(&l, &p));
        ism_locus_check chk;
        cr_assert(ism_locus_check_mesh(&l, box, &m, &a, &chk, &err));
        cr_expect_eq(chk.nonmanifold_edges, a.nonmanifold_edges);
        cr_expect_eq(chk.nonmanifold_edges_off, wrong ? a.nonmanifold_edges : 0);
        ism_features f;
        cr_assert(ism_features_build(&a, &f));
        f.locus = &l;
        f.check = &chk;
        size_t n;
        char *text = ism_features_json(&m, &f, &n);
        json_error_t je;
        json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
        cr_assert_not_null(doc, "%s", je.text);
        json_t *curve = json_array_get(json_object_get(doc, "curves"), 0);
        cr_expect_str_eq(json_string_value(json_object_get(curve, "kind")), "double");
        json_t *end = json_array_get(json_object_get(curve, "ends"), 1);
        cr_expect_str_eq(json_string_value(json_object_get(end, "type")), "box");
        cr_expect(json_is_null(json_object_get(end, "point")));
        json_t *sp = json_array_get(json_object_get(doc, "singular_points"), 0);
        cr_expect_eq(json_real_value(json_array_get(json_object_get(sp, "xyz"), 0)), 0.1 / 3);
        cr_expect_str_eq(json_string_value(json_object_get(sp, "type")), "node");
        json_t *counts = json_object_get(doc, "counts");
        cr_expect_eq(json_integer_value(json_object_get(counts, "artefacts")),
                     (json_int_t)chk.artefacts);
        cr_expect_eq(json_integer_value(json_object_get(json_object_get(counts, "by_type"),
                                                        "node")), 1);
        json_t *chain = json_array_get(json_object_get(doc, "nonmanifold_edges"), 0);
        cr_expect_eq(json_is_true(json_object_get(chain, "on_locus")), !wrong);
        /* the edges the check counts, by number: all of the chain's or none */
        size_t counted = 0;
        for (size_t c = 0; c < json_array_size(json_object_get(doc, "nonmanifold_edges")); c++)
            counted += json_array_size(json_object_get(
                json_array_get(json_object_get(doc, "nonmanifold_edges"), c), "off_edges"));
        cr_expect_eq(counted, chk.nonmanifold_edges_off);
        json_t *first = json_array_get(json_object_get(chain, "off_edges"), 0);
        cr_expect(wrong ? json_integer_value(first) == 0 : first == NULL);
        json_decref(doc);
        free(text);
        ism_features_free(&f);
        ism_locus_check_free(&chk);
        ism_locus_free(&l);
    }
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}
