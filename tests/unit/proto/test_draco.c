/* test_draco.c — the Draco encoder checked with Draco's own decoder (libdraco via
 * draco_decode_helper.cc, and the Debian draco_decoder program): vertex and face counts,
 * positions within the quantisation error, every attribute under its fixed unique id and
 * metadata name with the right values, faces with their winding; on non-manifold meshes,
 * that the decoded Draco plus the features JSON show the same non-manifold edges and points
 * as the server's analysis. */
#include <criterion/criterion.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/analysis/analysis.h"
#include "core/octree/polygonise.h"
#include "proto/draco_encode.h"
#include "proto/features.h"
#include "proto/request.h"
#include "proto/wire_mesh.h"
#include "tests/unit/proto/draco_decode_helper.h"
#include "tests/unit/proto/meshes_for_tests.h"
#include "tests/unit/proto/spawn_for_tests.h"

/* ---- helpers ---------------------------------------------------------------------------- */

typedef struct keyed {
    float x;
    uint32_t i;
} keyed;

static int by_x(const void *a, const void *b)
{
    float x = ((const keyed *)a)->x, y = ((const keyed *)b)->x;
    return (x > y) - (x < y);
}

/* For each decoded point, the original vertex within tol in every coordinate (the closest
 * such); fails the test when a point has none. Returns a malloc'd map. */
static uint32_t *match_points(const float *orig, size_t n, const float *dec, size_t m,
                              double tol)
{
    keyed *k = malloc(n * sizeof *k);
    for (size_t i = 0; i < n; i++)
        k[i] = (keyed){orig[3 * i], (uint32_t)i};
    qsort(k, n, sizeof *k, by_x);
    uint32_t *map = malloc((m ? m : 1) * sizeof *map);
    for (size_t j = 0; j < m; j++) {
        const float *p = dec + 3 * j;
        size_t lo = 0, hi = n;
        while (lo < hi) {
            size_t mid = (lo + hi) / 2;
            if (k[mid].x < p[0] - tol)
                lo = mid + 1;
            else
                hi = mid;
        }
        double best = INFINITY;
        uint32_t found = UINT32_MAX;
        for (size_t i = lo; i < n && k[i].x <= p[0] + tol; i++) {
            const float *q = orig + 3 * k[i].i;
            double d = fmax(fabs(q[0] - p[0]), fmax(fabs(q[1] - p[1]), fabs(q[2] - p[2])));
            if (d <= tol && d < best) {
                best = d;
                found = k[i].i;
            }
        }
        cr_assert_neq(found, UINT32_MAX, "decoded point %zu (%g %g %g) is not within %g of any "
                      "vertex", j, p[0], p[1], p[2], tol);
        map[j] = found;
    }
    free(k);
    return map;
}

/* Largest error Draco's position quantisation may introduce: half a step of the grid over
 * the bounding cube, plus float rounding. */
static double position_tolerance(const ism_wire_mesh *w, int bits)
{
    double range = 0;
    for (int k = 0; k < 3; k++)
        range = fmax(range, w->bounds[k + 3] - w->bounds[k]);
    return range / ((1 << bits) - 1) * 0.5 + range * 1e-6;
}

static bool encode(const ism_wire_mesh *w, int bits, int nbits, int cbits, ism_draco_output *d)
{
    ism_draco_input in = {w->nverts, w->ntris, w->pos, w->tri, w->normal, w->mean_curvature,
                          w->gauss_curvature, w->vertex_class, bits, nbits, cbits, NULL, 0, NULL, NULL, NULL, NULL};
    bool ok = ism_draco_encode(&in, d);
    cr_assert(ok, "%s", d->error);
    return ok;
}

/* Every decoded face, mapped to original vertices, is an original triangle with the same
 * winding (rotation allowed). */
static void check_faces(const ism_mesh *m, const test_draco_mesh *dm, const uint32_t *map)
{
    for (size_t f = 0; f < dm->nfaces; f++) {
        uint32_t a = map[dm->faces[3 * f]], b = map[dm->faces[3 * f + 1]],
                 c = map[dm->faces[3 * f + 2]];
        bool found = false;
        for (size_t t = 0; t < m->ntris && !found; t++) {
            const uint32_t *v = m->tri + 3 * t;
            for (int r = 0; r < 3 && !found; r++)
                found = v[r] == a && v[(r + 1) % 3] == b && v[(r + 2) % 3] == c;
        }
        cr_assert(found, "decoded face %zu (%u %u %u) is not an original triangle", f, a, b, c);
    }
}

/* A synthetic analysis-free wire mesh with curvature and class arrays made up for the test. */
static void synthetic_attributes(ism_wire_mesh *w)
{
    w->mean_curvature = malloc(w->nverts * sizeof(float));
    w->gauss_curvature = malloc(w->nverts * sizeof(float));
    uint8_t *cls = malloc(w->nverts);
    for (size_t i = 0; i < w->nverts; i++) {
        w->mean_curvature[i] = (float)sin(0.01 * (double)i);
        w->gauss_curvature[i] = (float)(w->pos[3 * i + 2] * 3.5);
        cls[i] = (uint8_t)(i % 5);
    }
    w->vertex_class = cls;
}

/* ---- round trips ------------------------------------------------------------------------ */

Test(draco, torus_round_trip_with_every_attribute)
{
    ism_mesh m;
    test_mesh_torus(&m, 120, 60, 1, 0.3);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, ISM_ATTR_ALL, 0, &w));
    synthetic_attributes(&w);
    ism_draco_output d;
    encode(&w, 14, 10, 0, &d);
    test_draco_mesh dm;
    char why[200];
    cr_assert(test_draco_decode(d.data, d.len, &dm, why, sizeof why), "%s", why);

    /* a closed, consistently wound manifold keeps its counts */
    cr_expect_eq(dm.npoints, m.nverts);
    cr_expect_eq(dm.nfaces, m.ntris);
    cr_expect_eq(d.points, dm.npoints);
    cr_expect_eq(d.faces, dm.nfaces);
    /* fixed ids, names and types */
    static const char *const names[] = {"position", "normal", "mean_curvature",
                                        "gauss_curvature", "class"};
    static const int types[] = {0, 1, 4, 4, 4}; /* POSITION, NORMAL, GENERIC */
    cr_expect_eq(dm.nattributes, 5);
    for (int id = 0; id < 5; id++) {
        cr_expect_str_eq(dm.name_of[id], names[id], "unique id %d", id);
        cr_expect_eq(dm.type_of[id], types[id], "unique id %d", id);
    }
    uint32_t *map = match_points(w.pos, w.nverts, dm.pos, dm.npoints, position_tolerance(&w, 14));
    for (size_t j = 0; j < dm.npoints; j++) {
        uint32_t i = map[j];
        const float *n0 = w.normal + 3 * i, *n1 = dm.normal + 3 * j;
        double dot = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2];
        cr_assert_gt(dot, 0.9995, "normal of vertex %u off by more than 10-bit octahedral", i);
        cr_assert_eq(dm.mean[j], w.mean_curvature[i], "float curvature is sent exactly");
        cr_assert_eq(dm.gauss[j], w.gauss_curvature[i]);
        cr_assert_eq(dm.cls[j], w.vertex_class[i]);
    }
    check_faces(&m, &dm, map);
    free(map);
    test_draco_mesh_free(&dm);
    free(d.data);
    free((void *)w.vertex_class);
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

Test(draco, quantisation_bits_bound_the_position_error)
{
    ism_mesh m;
    test_mesh_torus(&m, 80, 40, 1, 0.3);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, 0, 0, &w));
    size_t last = SIZE_MAX;
    for (int bits = 16; bits >= 8; bits -= 4) {
        ism_draco_output d;
        encode(&w, bits, 10, 0, &d);
        cr_expect_lt(d.len, last, "fewer bits, fewer bytes");
        last = d.len;
        test_draco_mesh dm;
        char why[200];
        cr_assert(test_draco_decode(d.data, d.len, &dm, why, sizeof why), "%s", why);
        cr_expect_eq(dm.nattributes, 1, "only positions were asked for");
        cr_expect_null(dm.normal);
        uint32_t *map = match_points(w.pos, w.nverts, dm.pos, dm.npoints,
                                     position_tolerance(&w, bits));
        free(map);
        test_draco_mesh_free(&dm);
        free(d.data);
    }
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

Test(draco, quantised_curvature_stays_within_its_step)
{
    ism_mesh m;
    test_mesh_torus(&m, 60, 30, 1, 0.3);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, ISM_ATTR_ALL, 0, &w));
    synthetic_attributes(&w);
    ism_draco_output d;
    encode(&w, 14, 10, 12, &d);
    test_draco_mesh dm;
    char why[200];
    cr_assert(test_draco_decode(d.data, d.len, &dm, why, sizeof why), "%s", why);
    uint32_t *map = match_points(w.pos, w.nverts, dm.pos, dm.npoints, position_tolerance(&w, 14));
    double lo = INFINITY, hi = -INFINITY;
    for (size_t i = 0; i < w.nverts; i++) {
        lo = fmin(lo, w.gauss_curvature[i]);
        hi = fmax(hi, w.gauss_curvature[i]);
    }
    double step = (hi - lo) / ((1 << 12) - 1);
    for (size_t j = 0; j < dm.npoints; j++)
        cr_assert_leq(fabs(dm.gauss[j] - w.gauss_curvature[map[j]]), step * 0.51 + 1e-6);
    free(map);
    test_draco_mesh_free(&dm);
    free(d.data);
    free((void *)w.vertex_class);
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

Test(draco, degenerate_faces_are_dropped_and_all_degenerate_is_refused)
{
    ism_mesh m;
    test_mesh_grid(&m, 4);
    ism_mesh_add_triangle(&m, 3, 3, 7); /* collapsed */
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, ISM_ATTR_NORMAL, 0, &w));
    cr_expect_eq(w.live_triangles, m.ntris - 1);
    ism_draco_output d;
    encode(&w, 14, 10, 0, &d);
    cr_expect_eq(d.faces, m.ntris - 1);
    free(d.data);
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);

    /* only collapsed triangles: Draco refuses, with a message and no crash */
    ism_mesh_init(&m);
    double p[3] = {0, 0, 0};
    ism_mesh_add_vertex(&m, p, NULL);
    ism_mesh_add_vertex(&m, p, NULL);
    ism_mesh_add_triangle(&m, 0, 0, 1);
    cr_assert(ism_wire_mesh_build(&m, NULL, 0, 0, &w));
    cr_expect_eq(w.live_triangles, 0);
    ism_draco_input in = {w.nverts, w.ntris, w.pos, w.tri, NULL, NULL, NULL, NULL, 14, 10, 0, NULL, 0, NULL, NULL, NULL, NULL};
    cr_expect(!ism_draco_encode(&in, &d));
    cr_expect_null(d.data);
    cr_expect_neq(d.error[0], '\0');
    /* an index out of range is refused before Draco sees it */
    uint32_t bad[3] = {0, 1, 9};
    in.tri = bad;
    cr_expect(!ism_draco_encode(&in, &d));
    cr_expect_not_null(strstr(d.error, "vertex that does not exist"));
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

Test(draco, zero_normals_are_replaced_by_unit_normals)
{
    ism_mesh m;
    test_mesh_touching_tetrahedra(&m);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, ISM_ATTR_NORMAL, 0, &w));
    for (size_t i = 0; i < w.nverts; i++) {
        const float *n = w.normal + 3 * i;
        cr_expect_float_eq(n[0] * n[0] + n[1] * n[1] + n[2] * n[2], 1.0f, 1e-5, "vertex %zu", i);
    }
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

Test(draco, debian_draco_decoder_reads_the_stream)
{
    ism_mesh m;
    test_mesh_torus(&m, 40, 20, 1, 0.3);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(&m, NULL, ISM_ATTR_NORMAL, 0, &w));
    ism_draco_output d;
    encode(&w, 14, 10, 0, &d);
    char *in = test_write_temp(d.data, d.len, ".drc");
    cr_assert_not_null(in);
    char out[300];
    snprintf(out, sizeof out, "%s.obj", in);
    char *argv[] = {"draco_decoder", "-i", in, "-o", out, NULL};
    char *text = NULL;
    int rc = test_run(argv, 60, &text, NULL);
    cr_assert_eq(rc, 0, "draco_decoder failed: %s", text ? text : "");
    FILE *f = fopen(out, "r");
    cr_assert_not_null(f);
    char line[256];
    size_t v = 0, faces = 0;
    while (fgets(line, sizeof line, f)) {
        v += strncmp(line, "v ", 2) == 0;
        faces += strncmp(line, "f ", 2) == 0;
    }
    fclose(f);
    cr_expect_eq(v, m.nverts);
    cr_expect_eq(faces, m.ntris);
    unlink(in);
    unlink(out);
    free(in);
    free(text);
    free(d.data);
    ism_wire_mesh_free(&w);
    ism_mesh_free(&m);
}

/* ---- non-manifold structure: what arrives equals the server's analysis -------------------- */

typedef struct pt {
    float p[3];
} pt;

static bool same_point(const float *a, const float *b, double tol)
{
    return fabs(a[0] - b[0]) <= tol && fabs(a[1] - b[1]) <= tol && fabs(a[2] - b[2]) <= tol;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Non-manifold edges of a triangle list over n vertices (pairs lo < hi, sorted), counted
 * independently of the analysis: an undirected edge in more than two triangles. */
static size_t nonmanifold_edges(const uint32_t *tri, size_t ntris, uint64_t **out)
{
    uint64_t *e = malloc((3 * ntris + 1) * sizeof *e);
    size_t n = 0;
    for (size_t t = 0; t < ntris; t++) {
        const uint32_t *v = tri + 3 * t;
        if (v[0] == v[1] || v[1] == v[2] || v[0] == v[2])
            continue;
        for (int k = 0; k < 3; k++) {
            uint64_t a = v[k], b = v[(k + 1) % 3];
            e[n++] = a < b ? a << 32 | b : b << 32 | a;
        }
    }
    qsort(e, n, sizeof *e, cmp_u64);
    size_t k = 0;
    for (size_t i = 0; i < n;) {
        size_t j = i;
        while (j < n && e[j] == e[i])
            j++;
        if (j - i > 2)
            e[k++] = e[i];
        i = j;
    }
    *out = e;
    return k;
}

/* bits: position quantisation; fine enough that no two vertices share a quantisation cell,
 * so that welding by position is unambiguous (the polygoniser places vertices as close as
 * 1e-5 of the box: 14 bits would merge some). */
static void check_arrival(ism_mesh *m, size_t want_nm_edges, size_t want_points, int bits)
{
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, NULL, NULL, &a, &err), "%s", err.message);
    if (want_nm_edges != SIZE_MAX) {
        cr_expect_eq(a.nonmanifold_edges, want_nm_edges);
        cr_expect_eq(a.npoints, want_points);
    }

    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(m, &a, ISM_ATTR_ALL, 0, &w));
    ism_draco_output d;
    encode(&w, bits, 10, 0, &d);
    test_draco_mesh dm;
    char why[200];
    cr_assert(test_draco_decode(d.data, d.len, &dm, why, sizeof why), "%s", why);
    cr_expect_eq(dm.nfaces, w.live_triangles);
    cr_assert_not_null(dm.cls, "the class attribute arrives");

    ism_features f;
    cr_assert(ism_features_build(&a, &f));
    size_t flen;
    char *ftext = ism_features_json(m, &f, &flen);
    json_error_t je;
    json_t *doc = json_loadb(ftext, flen, JSON_REJECT_DUPLICATES, &je);
    cr_assert_not_null(doc, "%s", je.text);

    /* Weld the decoded points back by position (Draco split them along the non-manifold
     * edges) and count edges: the same non-manifold edges as an independent count over the
     * original mesh, and as many as the analysis says. */
    double tol = position_tolerance(&w, bits);
    uint32_t *map = match_points(w.pos, w.nverts, dm.pos, dm.npoints, tol);
    uint32_t *welded = malloc(dm.nfaces * 3 * sizeof *welded);
    for (size_t i = 0; i < dm.nfaces * 3; i++)
        welded[i] = map[dm.faces[i]];
    uint64_t *e_orig, *e_dec;
    size_t n_orig = nonmanifold_edges(m->tri, m->ntris, &e_orig);
    size_t n_dec = nonmanifold_edges(welded, dm.nfaces, &e_dec);
    cr_expect_eq(n_orig, a.nonmanifold_edges);
    cr_assert_eq(n_dec, n_orig);
    cr_expect(memcmp(e_dec, e_orig, n_orig * sizeof *e_orig) == 0);

    /* The features' non-manifold edge chains are exactly those edges, as coordinate pairs. */
    json_t *curves = json_object_get(doc, "nonmanifold_edges");
    size_t curve_edges = 0;
    for (size_t c = 0; c < json_array_size(curves); c++) {
        json_t *xyz = json_object_get(json_array_get(curves, c), "xyz");
        size_t np = json_array_size(xyz) / 3;
        for (size_t i = 0; i + 1 < np; i++, curve_edges++) {
            float p[2][3];
            for (int s = 0; s < 2; s++)
                for (int k = 0; k < 3; k++)
                    p[s][k] = (float)json_number_value(json_array_get(xyz, 3 * (i + s) + k));
            /* find the original vertices at these coordinates */
            uint32_t v[2] = {UINT32_MAX, UINT32_MAX};
            for (size_t q = 0; q < w.nverts; q++)
                for (int s = 0; s < 2; s++)
                    if (same_point(w.pos + 3 * q, p[s], 0))
                        v[s] = (uint32_t)q;
            cr_assert(v[0] != UINT32_MAX && v[1] != UINT32_MAX);
            uint64_t key = v[0] < v[1] ? (uint64_t)v[0] << 32 | v[1] : (uint64_t)v[1] << 32 | v[0];
            bool found = false;
            for (size_t k = 0; k < n_orig; k++)
                found = found || e_orig[k] == key;
            cr_expect(found, "curve segment %u-%u is not a non-manifold edge", v[0], v[1]);
            /* and the decoded class says "non-manifold edge" at both ends, at every copy */
            for (size_t j = 0; j < dm.npoints; j++)
                if (map[j] == v[0] || map[j] == v[1])
                    cr_expect_geq(dm.cls[j], ISM_VERTEX_NONMANIFOLD_EDGE);
        }
    }
    cr_expect_eq(curve_edges, n_orig);

    /* The features' points are the analysis's points, with the decoded class. */
    json_t *points = json_object_get(doc, "nonmanifold_points");
    cr_assert_eq(json_array_size(points), a.npoints);
    for (size_t i = 0; i < a.npoints; i++) {
        json_t *p = json_array_get(points, i);
        json_t *xyz = json_object_get(p, "xyz");
        float q[3];
        for (int k = 0; k < 3; k++)
            q[k] = (float)json_number_value(json_array_get(xyz, k));
        cr_expect(same_point(q, w.pos + 3 * a.points[i], 0));
        int cls = (int)json_integer_value(json_object_get(p, "class"));
        cr_expect_eq(cls, a.vertex_class[a.points[i]]);
        size_t copies = 0;
        for (size_t j = 0; j < dm.npoints; j++)
            if (map[j] == a.points[i]) {
                copies++;
                cr_expect_eq(dm.cls[j], cls);
            }
        cr_expect_geq(copies, 1);
    }
    /* Every decoded point carries its vertex's class. */
    for (size_t j = 0; j < dm.npoints; j++)
        cr_assert_eq(dm.cls[j], a.vertex_class[map[j]]);

    json_decref(doc);
    free(ftext);
    free(e_orig);
    free(e_dec);
    free(welded);
    free(map);
    ism_features_free(&f);
    test_draco_mesh_free(&dm);
    free(d.data);
    ism_wire_mesh_free(&w);
    ism_analysis_free(&a);
}

Test(draco, crossing_planes_arrive_with_their_nonmanifold_line)
{
    ism_mesh m;
    test_mesh_crossing_planes(&m, 8);
    ism_mesh_add_triangle(&m, 5, 5, 6); /* a collapsed triangle Draco drops */
    /* 8 non-manifold edges along the x axis; its two ends are curve ends */
    check_arrival(&m, 8, 2, 14);
    ism_mesh_free(&m);
}

Test(draco, touching_tetrahedra_arrive_with_their_nonmanifold_point)
{
    ism_mesh m;
    test_mesh_touching_tetrahedra(&m);
    check_arrival(&m, 0, 1, 14);
    ism_mesh_free(&m);
}

/* The polygoniser's own non-manifold surfaces (smaller depths under the sanitizers). */
static void polygonised(const char *preset, int depth, size_t *nm_edges)
{
    char json[128];
    bool quick = getenv("ISOMESH_TEST_QUICK") != NULL;
    snprintf(json, sizeof json, "{\"preset\": \"%s\", \"depth\": {\"max\": %d}}", preset,
             quick ? depth - 1 : depth);
    ism_request req;
    ism_req_error rerr;
    cr_assert(ism_request_decode(json, strlen(json), NULL, &req, &rerr), "%s", rerr.message);
    ism_tape *t = ism_request_compile(&req, &rerr);
    cr_assert_not_null(t, "%s", rerr.message);
    ism_poly_options o;
    ism_request_poly_options(&req, &o);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats ps;
    ism_error err;
    cr_assert_eq(ism_polygonise(t, &o, &m, &ps, &err), ISM_POLY_OK, "%s", err.message);
    ism_analysis a;
    cr_assert(ism_analyse(&m, NULL, NULL, &a, &err));
    *nm_edges = a.nonmanifold_edges;
    ism_analysis_free(&a);
    check_arrival(&m, SIZE_MAX, SIZE_MAX, 20);
    ism_mesh_free(&m);
    ism_tape_free(t);
    ism_request_free(&req);
}

Test(draco, polygonised_klein_bottle_arrives_with_its_self_intersection, .timeout = 120)
{
    size_t nm;
    polygonised("klein-bottle", 6, &nm);
    cr_expect_gt(nm, 0, "the Klein bottle self-intersects");
}

Test(draco, polygonised_steiner_surface_arrives_with_its_double_lines, .timeout = 120)
{
    size_t nm;
    polygonised("steiner-roman", 6, &nm);
    cr_expect_gt(nm, 0, "Steiner's surface has three double lines");
}
