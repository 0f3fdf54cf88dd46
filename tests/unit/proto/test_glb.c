/* test_glb.c — the .glb container: the header and chunks are well formed, the JSON names the
 * documented nodes and attribute ids, the Khronos glTF validator finds zero errors, and
 * draco3d (Draco's JavaScript decoder, the browser's family) decodes the surface with every
 * attribute under its unique id and as many points and faces as the accessors say. Also for
 * a non-manifold mesh (LINES and POINTS primitives beside the surface) and for an empty one. */
#include <criterion/criterion.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/analysis/analysis.h"
#include "proto/corner_split.h"
#include "proto/glb.h"
#include "proto/request.h"
#include "tests/unit/proto/meshes_for_tests.h"
#include "tests/unit/proto/spawn_for_tests.h"

static uint32_t rd32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* Builds the glb of m (analysed; empty when m has no triangle). */
static unsigned char *build(const ism_mesh *m, size_t *len, ism_draco_output *d)
{
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, NULL, NULL, &a, &err), "%s", err.message);
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(m, &a, ISM_ATTR_NORMAL | ISM_ATTR_CLASS, 0, &w));
    ism_features f;
    cr_assert(ism_features_build(&a, &f));
    memset(d, 0, sizeof *d);
    bool empty = w.live_triangles == 0;
    if (!empty) {
        ism_draco_input in = {w.nverts, w.ntris, w.pos, w.tri, w.normal, NULL, NULL,
                              w.vertex_class, 14, 10, 0, NULL, 0, NULL, NULL, NULL, NULL};
        cr_assert(ism_draco_encode(&in, d), "%s", d->error);
    }
    ism_glb_input gi = {m, &w, empty ? NULL : d, &f, "0123abcd"};
    unsigned char *glb;
    cr_assert(ism_glb_build(&gi, &glb, len));
    free(d->data);
    d->data = NULL;
    ism_features_free(&f);
    ism_wire_mesh_free(&w);
    ism_analysis_free(&a);
    return glb;
}

/* Checks the container and returns the parsed JSON chunk. */
static json_t *check_container(const unsigned char *g, size_t len)
{
    cr_assert_geq(len, 20);
    cr_assert_eq(memcmp(g, "glTF", 4), 0);
    cr_assert_eq(rd32(g + 4), 2);
    cr_assert_eq(rd32(g + 8), len);
    uint32_t jlen = rd32(g + 12);
    cr_assert_eq(memcmp(g + 16, "JSON", 4), 0);
    cr_assert_eq(jlen % 4, 0);
    cr_assert_leq(20 + jlen, len);
    if (20 + jlen < len) {
        uint32_t blen = rd32(g + 20 + jlen);
        cr_assert_eq(memcmp(g + 24 + jlen, "BIN\0", 4), 0);
        cr_assert_eq(blen % 4, 0);
        cr_assert_eq(28 + jlen + blen, len);
    }
    json_error_t je;
    json_t *doc = json_loadb((const char *)g + 20, jlen, 0, &je);
    cr_assert_not_null(doc, "%s", je.text);
    return doc;
}

/* Runs validate_gltf.mjs; returns its report. */
static json_t *validate(const unsigned char *g, size_t len)
{
    char *path = test_write_temp(g, len, ".glb");
    cr_assert_not_null(path);
    char *argv[] = {"node", "tests/unit/proto/validate_gltf.mjs", path, NULL};
    char *out = NULL;
    int rc = test_run(argv, 120, &out, NULL);
    unlink(path);
    free(path);
    cr_assert_eq(rc, 0, "validate_gltf.mjs failed (run from the repository root; tests/"
                        "node_modules installed?): %s", out ? out : "");
    json_error_t je;
    json_t *report = json_loads(out, 0, &je);
    cr_assert_not_null(report, "%s: %s", je.text, out);
    free(out);
    return report;
}

static void expect_no_errors(json_t *report)
{
    json_t *msgs = json_object_get(report, "messages");
    char all[2000] = "";
    for (size_t i = 0; i < json_array_size(msgs); i++) {
        json_t *m = json_array_get(msgs, i);
        char line[300];
        snprintf(line, sizeof line, "[%lld] %s %s %s\n",
                 (long long)json_integer_value(json_object_get(m, "severity")),
                 json_string_value(json_object_get(m, "code")),
                 json_string_value(json_object_get(m, "message")),
                 json_string_value(json_object_get(m, "pointer")));
        strncat(all, line, sizeof all - strlen(all) - 1);
    }
    cr_expect_eq(json_integer_value(json_object_get(report, "errors")), 0, "%s", all);
    cr_expect_eq(json_integer_value(json_object_get(report, "warnings")), 0, "%s", all);
}

static json_t *node_named(json_t *doc, const char *name)
{
    json_t *nodes = json_object_get(doc, "nodes");
    for (size_t i = 0; i < json_array_size(nodes); i++) {
        json_t *n = json_array_get(nodes, i);
        if (strcmp(json_string_value(json_object_get(n, "name")), name) == 0)
            return n;
    }
    return NULL;
}

Test(glb, torus_is_valid_and_draco3d_finds_every_attribute, .timeout = 120)
{
    ism_mesh m;
    test_mesh_torus(&m, 48, 24, 1, 0.3);
    size_t len;
    ism_draco_output d;
    unsigned char *g = build(&m, &len, &d);
    json_t *doc = check_container(g, len);
    cr_expect_not_null(node_named(doc, "surface"));
    cr_expect_null(node_named(doc, "nonmanifold_curves"), "nothing to draw: no node");
    json_t *prim = json_array_get(
        json_object_get(json_array_get(json_object_get(doc, "meshes"), 0), "primitives"), 0);
    json_t *ext = json_object_get(json_object_get(prim, "extensions"),
                                  "KHR_draco_mesh_compression");
    json_t *ids = json_object_get(ext, "attributes");
    cr_expect_eq(json_integer_value(json_object_get(ids, "POSITION")), 0);
    cr_expect_eq(json_integer_value(json_object_get(ids, "NORMAL")), 1);
    cr_expect_eq(json_integer_value(json_object_get(ids, "_CLASS")), 4);
    cr_expect_null(json_object_get(ids, "_MEAN_CURVATURE"), "not asked for, not named");

    json_t *report = validate(g, len);
    expect_no_errors(report);
    json_t *dr = json_array_get(json_object_get(report, "draco"), 0);
    cr_assert_not_null(dr, "no Draco primitive decoded");
    cr_expect(json_is_true(json_object_get(dr, "ok")));
    cr_expect(json_is_true(json_object_get(dr, "accessors_match")));
    cr_expect_eq(json_integer_value(json_object_get(dr, "points")), (json_int_t)m.nverts);
    cr_expect_eq(json_integer_value(json_object_get(dr, "faces")), (json_int_t)m.ntris);
    json_t *atts = json_object_get(dr, "attributes");
    const char *names[] = {"POSITION", "NORMAL", "_CLASS"};
    for (int i = 0; i < 3; i++)
        cr_expect(json_is_true(json_object_get(json_object_get(atts, names[i]), "found")),
                  "%s", names[i]);
    json_t *cls = json_object_get(atts, "_CLASS");
    cr_expect_eq(json_number_value(json_object_get(cls, "max")), 0, "a torus is manifold");
    json_decref(report);
    json_decref(doc);
    free(g);
    ism_mesh_free(&m);
}

Test(glb, crossing_planes_carry_lines_and_points_beside_the_surface, .timeout = 120)
{
    ism_mesh m;
    test_mesh_crossing_planes(&m, 6);
    size_t len;
    ism_draco_output d;
    unsigned char *g = build(&m, &len, &d);
    json_t *doc = check_container(g, len);
    json_t *curves = node_named(doc, "nonmanifold_curves");
    json_t *points = node_named(doc, "nonmanifold_points");
    json_t *bounds = node_named(doc, "boundaries");
    cr_assert(curves && points && bounds);
    json_t *meshes = json_object_get(doc, "meshes");
    json_t *accessors = json_object_get(doc, "accessors");
    json_t *cprim = json_array_get(json_object_get(json_array_get(meshes,
                                   json_integer_value(json_object_get(curves, "mesh"))),
                                   "primitives"), 0);
    cr_expect_eq(json_integer_value(json_object_get(cprim, "mode")), 1, "LINES");
    json_t *idx = json_array_get(accessors, json_integer_value(json_object_get(cprim,
                                                                                "indices")));
    cr_expect_eq(json_integer_value(json_object_get(idx, "count")), 2 * 6,
                 "six non-manifold edges, two indices each");
    json_t *pprim = json_array_get(json_object_get(json_array_get(meshes,
                                   json_integer_value(json_object_get(points, "mesh"))),
                                   "primitives"), 0);
    cr_expect_eq(json_integer_value(json_object_get(pprim, "mode")), 0, "POINTS");
    json_t *extras = json_object_get(points, "extras");
    cr_expect_eq(json_array_size(json_object_get(extras, "class")), 2);
    json_t *report = validate(g, len);
    expect_no_errors(report);
    json_t *dr = json_array_get(json_object_get(report, "draco"), 0);
    cr_expect(json_is_true(json_object_get(dr, "accessors_match")));
    cr_expect_eq(json_integer_value(json_object_get(dr, "faces")), (json_int_t)m.ntris);
    cr_expect_gt(json_integer_value(json_object_get(dr, "points")), (json_int_t)m.nverts,
                 "Draco splits vertices along the non-manifold line");
    cr_expect_eq(json_number_value(json_object_get(
                     json_object_get(json_object_get(dr, "attributes"), "_CLASS"), "max")),
                 ISM_VERTEX_NONMANIFOLD_EDGE);
    json_decref(report);
    json_decref(doc);
    free(g);
    ism_mesh_free(&m);
}

/* The glb of m with per-triangle cells (Draco through a corner split, or plain). */
static unsigned char *build_cells(const ism_mesh *m, const uint32_t *cell, bool draco,
                                  size_t *len)
{
    ism_wire_mesh w;
    cr_assert(ism_wire_mesh_build(m, NULL, ISM_ATTR_NORMAL, 0, &w));
    w.tri_cell = cell;
    ism_corner_split sp;
    cr_assert(ism_corner_split_build(&w, &sp));
    ism_draco_output d;
    memset(&d, 0, sizeof d);
    ism_draco_input in = {w.nverts, w.ntris, w.pos, sp.tri, w.normal, NULL, NULL, NULL, 14, 10,
                          0, NULL, sp.npoints, sp.point_vertex, sp.point_cell, NULL, NULL};
    if (draco)
        cr_assert(ism_draco_encode(&in, &d), "%s", d.error);
    ism_glb_input gi = {m, &w, draco ? &d : NULL, NULL, NULL};
    unsigned char *glb;
    cr_assert(ism_glb_build(&gi, &glb, len));
    free(d.data);
    ism_corner_split_free(&sp);
    ism_wire_mesh_free(&w);
    return glb;
}

Test(glb, cells_travel_as_CELL_in_draco_and_plain_glb, .timeout = 120)
{
    ism_mesh m;
    test_mesh_torus(&m, 48, 24, 1, 0.3);
    uint32_t *cell = malloc(m.ntris * sizeof *cell);
    for (size_t t = 0; t < m.ntris; t++) /* two cells: the halves x < 0 and x > 0 */
        cell[t] = m.pos[3 * (size_t)m.tri[3 * t]] + m.pos[3 * (size_t)m.tri[3 * t + 1]] +
                      m.pos[3 * (size_t)m.tri[3 * t + 2]] > 0;
    for (int draco = 0; draco < 2; draco++) {
        size_t len;
        unsigned char *g = build_cells(&m, cell, draco, &len);
        json_t *doc = check_container(g, len);
        json_t *prim = json_array_get(
            json_object_get(json_array_get(json_object_get(doc, "meshes"), 0), "primitives"), 0);
        json_t *acc = json_array_get(json_object_get(doc, "accessors"),
                                     json_integer_value(json_object_get(
                                         json_object_get(prim, "attributes"), "_CELL")));
        cr_assert_not_null(acc, "the surface has _CELL");
        cr_expect_eq(json_integer_value(json_object_get(acc, "componentType")), 5126);
        cr_expect_gt(json_integer_value(json_object_get(acc, "count")), (json_int_t)m.nverts,
                     "vertices on the two cuts are split");
        json_t *report = validate(g, len);
        expect_no_errors(report);
        if (draco) {
            json_t *dr = json_array_get(json_object_get(report, "draco"), 0);
            cr_expect(json_is_true(json_object_get(dr, "accessors_match")));
            json_t *c = json_object_get(json_object_get(dr, "attributes"), "_CELL");
            cr_expect_eq(json_integer_value(json_object_get(c, "unique_id")), 5);
            cr_expect_eq(json_number_value(json_object_get(c, "min")), 0);
            cr_expect_eq(json_number_value(json_object_get(c, "max")), 1);
        }
        json_decref(report);
        json_decref(doc);
        free(g);
    }
    free(cell);
    ism_mesh_free(&m);
}

Test(glb, empty_surface_is_a_valid_empty_gltf, .timeout = 120)
{
    ism_mesh m;
    ism_mesh_init(&m);
    size_t len;
    ism_draco_output d;
    unsigned char *g = build(&m, &len, &d);
    json_t *doc = check_container(g, len);
    cr_expect_null(json_object_get(doc, "meshes"));
    cr_expect_null(json_object_get(doc, "buffers"));
    cr_expect_null(json_object_get(doc, "extensionsRequired"));
    json_t *report = validate(g, len);
    cr_expect_eq(json_integer_value(json_object_get(report, "errors")), 0);
    json_decref(report);
    json_decref(doc);
    free(g);
}
