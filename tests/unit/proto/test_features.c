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
#include "tests/unit/placements.h"
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
/* The test mesh of crossing planes y = 0 and z = 0 with n cells a side, analysed. */
static void analysed_crossing_planes(int n, ism_mesh *m, ism_analysis *a)
{
    ism_error err;
    test_mesh_crossing_planes(m, n);
    cr_assert(ism_analyse(m, NULL, NULL, a, &err), "%s", err.message);
}

/* A locus of one double curve, the line through c along x from lo[0] to hi[0], and a node at
 * c + (0.1 / 3, 0, 0). */
static void x_axis_locus(const double lo[3], const double hi[3], const double c[3],
                         ism_locus *l)
{
    ism_locus_init(l);
    ism_sing_curve cv = {.kind = ISM_CURVE_DOUBLE, .n = 2, .end_type = {ISM_END_BOX, ISM_END_BOX},
                         .end_point = {-1, -1}};
    cv.xyz = malloc(6 * sizeof *cv.xyz);
    double ends[6] = {lo[0], c[1], c[2], hi[0], c[1], c[2]};
    memcpy(cv.xyz, ends, sizeof ends);
    cr_assert(ism_locus_add_curve(l, &cv));
    ism_sing_point p = {.p = {c[0] + 0.1 / 3, c[1], c[2]}, .type = ISM_SING_NODE,
                        .certified = true, .cones = -1};
    cr_assert(ism_locus_add_point(l, &p));
}

/* Frees what a locus test's JSON run made. */
static void drop(json_t *doc, char *text, ism_features *f, ism_locus_check *chk, ism_locus *l)
{
    json_decref(doc);
    free(text);
    ism_features_free(f);
    ism_locus_check_free(chk);
    ism_locus_free(l);
}

Test(features, locus_and_check_in_the_json)
{
    ism_mesh m;
    ism_analysis a;
    ism_error err;
    analysed_crossing_planes(6, &m, &a);
    cr_assert_gt(a.nonmanifold_edges, 0);
    double lo[3], hi[3];
    cr_assert(ism_mesh_bounds(&m, lo, hi));
    double box[6] = {lo[0] - 1, lo[1] - 1, lo[2] - 1, hi[0] + 1, hi[1] + 1, hi[2] + 1};
    for (int wrong = 0; wrong < 2; wrong++) {
        ism_locus l;
        x_axis_locus(lo, hi, (double[3]){0, wrong ? 0.25 * (hi[1] - lo[1]) : 0.0, 0}, &l);
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
        drop(doc, text, &f, &chk, &l);
    }
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

/* The digits of each decimal in a number's text after the point (0 without one). */
static int decimals_of(const char *s, size_t n)
{
    const char *dot = memchr(s, '.', n);
    if (!dot)
        return 0;
    int d = 0;
    for (const char *c = dot + 1; c < s + n && *c >= '0' && *c <= '9'; c++)
        d++;
    return d;
}

/* A singular curve's points are printed with the fewest decimals d whose rounding
 * ((sqrt 3 / 2) 10^-d for a point) is within the curve's certificate radius r (the table in
 * features.h), and the JSON states r + that rounding. Closed forms: a circle of radius 1/3
 * round (1/7, 0, 0) in z = 0 through irrational angles, with a node at its first point, and
 * its z printed as 1e-30 noise where the true value is 0 reads back as exactly 0. A curve with
 * no radius reads back bit for bit. */
Test(features, curve_points_printed_within_their_certificate)
{
    ism_mesh m;
    ism_analysis a;
    analysed_crossing_planes(4, &m, &a);
    const double radii[] = {6.928203230275509e-12, 1.7320508075688772e-12, 3e-7, 0.0};
    for (size_t t = 0; t < sizeof radii / sizeof radii[0]; t++) {
        double r = radii[t];
        ism_locus l;
        ism_locus_init(&l);
        const size_t n = 40;
        ism_sing_curve c = {.kind = ISM_CURVE_DOUBLE, .n = n, .closed = false,
                            .end_type = {ISM_END_POINT, ISM_END_BOX}, .end_point = {0, -1},
                            .certified = r > 0, .cert_radius = r, .first_uncertified = -1};
        c.xyz = malloc(3 * n * sizeof *c.xyz);
        cr_assert_not_null(c.xyz);
        for (size_t i = 0; i < n; i++) {
            double th = 0.1 + i * (M_SQRT2 - 1.0); /* irrational steps */
            c.xyz[3 * i] = 1.0 / 7 + cos(th) / 3;
            c.xyz[3 * i + 1] = sin(th) / 3;
            c.xyz[3 * i + 2] = (i % 2 ? -1e-30 : 1e-30);
        }
        ism_sing_point p = {.p = {c.xyz[0], c.xyz[1], 0}, .type = ISM_SING_NODE,
                            .certified = true, .cones = -1};
        cr_assert(ism_locus_add_curve(&l, &c));
        cr_assert(ism_locus_add_point(&l, &p));
        ism_features f;
        cr_assert(ism_features_build(&a, &f));
        f.locus = &l;
        size_t len;
        char *text = ism_features_json(&m, &f, &len);
        cr_assert_not_null(text);
        json_error_t je;
        json_t *doc = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
        cr_assert_not_null(doc, "%s", je.text);
        json_t *curve = json_array_get(json_object_get(doc, "curves"), 0);
        json_t *xyz = json_object_get(curve, "xyz");
        cr_assert_eq(json_array_size(xyz), 3 * n);
        double stated = json_number_value(json_object_get(curve, "certificate_radius"));
        int d = ism_features_decimals(r);
        if (r > 0) {
            cr_assert_geq(d, 0);
            double rounding = 0.8660254037844386 * pow(10.0, -d);
            cr_expect_leq(rounding, r, "d %d rounds by %g > r %g", d, rounding, r);
            cr_expect_gt(10 * rounding, r, "d %d is more decimals than r %g needs", d, r);
            cr_expect_eq(stated, r + rounding);
        } else {
            cr_expect_eq(d, -1);
            cr_expect_eq(stated, 0.0);
        }
        for (size_t i = 0; i < n; i++) {
            double q[3], dist2 = 0;
            for (int k = 0; k < 3; k++) {
                q[k] = json_number_value(json_array_get(xyz, 3 * i + k));
                double e = q[k] - c.xyz[3 * i + k];
                dist2 += e * e;
                if (r > 0)
                    cr_expect_leq(fabs(e), 0.5 * pow(10.0, -d) * (1 + 1e-9),
                                  "coordinate %zu.%d off by %g at %d decimals", i, k, e, d);
                else
                    cr_expect_eq(q[k], c.xyz[3 * i + k], "a curve without radius is exact");
            }
            /* the printed point is within the stated radius minus r of the full one (so a
             * zero within r of the full one is within the stated radius of the printed one) */
            cr_expect_leq(sqrt(dist2), stated - r + 1e-18, "point %zu moved %g", i,
                          sqrt(dist2));
            /* the circle's closed form: |(x - 1/7, y)| = 1/3 within the rounding, z = 0 */
            if (r > 0) {
                cr_expect_leq(fabs(hypot(q[0] - 1.0 / 7, q[1]) - 1.0 / 3), stated);
                cr_expect_eq(q[2], 0.0, "1e-30 noise prints as 0 at %d decimals", d);
            }
        }
        /* the ends and the node agree with the curve's printed points, and each number's text
         * has at most d decimals */
        json_t *end0 = json_object_get(json_array_get(json_object_get(curve, "ends"), 0), "xyz");
        json_t *end1 = json_object_get(json_array_get(json_object_get(curve, "ends"), 1), "xyz");
        for (int k = 0; k < 3; k++) {
            cr_expect_eq(json_number_value(json_array_get(end0, k)),
                         json_number_value(json_array_get(xyz, k)));
            cr_expect_eq(json_number_value(json_array_get(end1, k)),
                         json_number_value(json_array_get(xyz, 3 * (n - 1) + k)));
        }
        const char *at = strstr(strstr(text, "\"curves\":["), "\"xyz\":[") + 7;
        const char *stop = strchr(at, ']');
        int most = 0;
        for (const char *s = at; s < stop;) {
            const char *comma = memchr(s, ',', (size_t)(stop - s));
            const char *e = comma ? comma : stop;
            int dd = decimals_of(s, (size_t)(e - s));
            most = dd > most ? dd : most;
            s = e + 1;
        }
        if (r > 0)
            cr_expect_leq(most, d, "a coordinate printed with %d > %d decimals", most, d);
        else
            cr_expect_geq(most, 15, "a curve without radius prints in full");
        json_decref(doc);
        free(text);
        f.locus = NULL;
        ism_features_free(&f);
        ism_locus_free(&l);
    }
    ism_analysis_free(&a);
    ism_mesh_free(&m);
}

/* features.h's drawing table on crossing planes y = 0, z = 0 over [-1, 1]^2 (n = 6), moved by
 * nothing and by an irrational fraction of a cell (tests/unit/placements.h), with a drawing
 * tolerance t = 0.01: the document states it, every printed position has d = 3 decimals (the
 * fewest with (sqrt 3 / 2) 10^-d <= t / 2) and lies within that rounding of the closed form;
 * the chain on the double line (on the locus) prints its two ends, the same chain off a
 * locus line elsewhere every one of its 7 vertices (off_edges index them); each of the four
 * boundary chains, a U round one half-plane from the line's end to its other end, its four
 * corners; counts.boundary_edges and nonmanifold_edges are still the mesh's. */
Test(features, mesh_polylines_drawn_within_the_tolerance)
{
    const double t = 0.01, rounding = ISM_FEATURES_ROUNDING(3);
    cr_assert_eq(ism_features_decimals(0.5 * t), 3);
    for (int moved = 0; moved < 2; moved++)
        for (int wrong = 0; wrong < 2; wrong++) {
            ism_mesh m;
            ism_analysis a;
            ism_error err;
            test_mesh_crossing_planes(&m, 6);
            double s[3] = {0, 0, 0};
            if (moved) { /* a third of a cell, irrational, per axis (placements.h) */
                s[0] = PF_IRR_X / 3, s[1] = PF_IRR_Y / 3, s[2] = PF_IRR_Z / 3;
                for (size_t v = 0; v < m.nverts; v++)
                    for (int k = 0; k < 3; k++)
                        m.pos[3 * v + k] += s[k];
            }
            cr_assert(ism_analyse(&m, NULL, NULL, &a, &err), "%s", err.message);
            double lo[3], hi[3];
            cr_assert(ism_mesh_bounds(&m, lo, hi));
            double box[6] = {lo[0] - 1, lo[1] - 1, lo[2] - 1, hi[0] + 1, hi[1] + 1, hi[2] + 1};
            ism_locus l;
            x_axis_locus(lo, hi, (double[3]){s[0], s[1] + (wrong ? 0.5 : 0), s[2]}, &l);
            ism_locus_check chk;
            cr_assert(ism_locus_check_mesh(&l, box, &m, &a, &chk, &err));
            ism_features f;
            cr_assert(ism_features_build(&a, &f));
            f.locus = &l;
            f.check = &chk;
            f.draw_tol = t;
            size_t n;
            char *text = ism_features_json(&m, &f, &n);
            json_error_t je;
            json_t *doc = json_loadb(text, n, JSON_REJECT_DUPLICATES, &je);
            cr_assert_not_null(doc, "%s", je.text);
            cr_expect_eq(json_real_value(json_object_get(doc, "tolerance")), t);
            json_t *counts = json_object_get(doc, "counts");
            cr_expect_eq(json_integer_value(json_object_get(counts, "boundary_edges")),
                         (json_int_t)a.boundary_edges);
            cr_expect_eq(json_integer_value(json_object_get(counts, "nonmanifold_edges")),
                         (json_int_t)a.nonmanifold_edges);
            json_t *chains = json_object_get(doc, "nonmanifold_edges");
            cr_assert_eq(json_array_size(chains), 1);
            json_t *xyz = json_object_get(json_array_get(chains, 0), "xyz");
            cr_expect_eq(json_array_size(xyz), wrong ? 3 * 7 : 3 * 2);
            for (size_t i = 0; i < json_array_size(xyz); i += 3) { /* on the line y = z = 0 */
                double x = json_number_value(json_array_get(xyz, i));
                cr_expect_leq(fabs(json_number_value(json_array_get(xyz, i + 1)) - s[1]) +
                                  fabs(json_number_value(json_array_get(xyz, i + 2)) - s[2]),
                              1e-3);
                cr_expect_eq(x, round(x * 1e3) / 1e3, "%.17g has more than 3 decimals", x);
            }
            json_t *bounds = json_object_get(doc, "boundaries");
            cr_assert_eq(json_array_size(bounds), 4);
            for (size_t b = 0; b < 4; b++) {
                json_t *p = json_object_get(json_array_get(bounds, b), "xyz");
                cr_expect_eq(json_array_size(p), 3 * 4, "boundary %zu: %zu numbers", b,
                             json_array_size(p));
                for (size_t i = 0; i < json_array_size(p); i += 3) {
                    /* a corner of a half-plane: each coordinate -1, 0 or 1 moved by s */
                    double off2 = 0;
                    for (int k = 0; k < 3; k++) {
                        double v = json_number_value(json_array_get(p, i + (size_t)k));
                        cr_expect_eq(v, round(v * 1e3) / 1e3, "%.17g: over 3 decimals", v);
                        double c = round(v - s[k]);
                        off2 += (v - s[k] - c) * (v - s[k] - c);
                    }
                    cr_expect_leq(sqrt(off2), rounding, "boundary %zu point %zu", b, i / 3);
                }
            }
            drop(doc, text, &f, &chk, &l);
            ism_analysis_free(&a);
            ism_mesh_free(&m);
        }
}
