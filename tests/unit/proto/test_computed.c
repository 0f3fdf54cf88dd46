/* test_computed.c — the computed surface's cache entry (proto/computed.h): a hand-made
 * surface reads back field for field; every truncation, a wrong version, a wrong magic and a
 * triangle or polyline index past the vertices are refused. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "proto/computed.h"
#include "proto/request.h"

static float *floats(size_t n, float base)
{
    float *p = malloc(n * sizeof *p);
    for (size_t i = 0; i < n; i++)
        p[i] = base + (float)i;
    return p;
}

/* Two triangles on four vertices, a boundary loop, one feature point, one singular point and
 * one closed singular curve (its ends typed, and split finer than the depth). */
static void make(ism_computed *c)
{
    ism_computed_init(c);
    strcpy(c->surface_key, "0123456789abcdef0123456789abcdef0123456789abcdef0123456789abcdef");
    double p[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5}};
    float n[3] = {0, 0, 1};
    for (int i = 0; i < 4; i++)
        ism_mesh_add_vertex(&c->mesh, p[i], n);
    ism_mesh_add_triangle(&c->mesh, 0, 1, 2);
    ism_mesh_add_triangle(&c->mesh, 0, 2, 3);
    c->wire.nverts = 4;
    c->wire.ntris = 2;
    c->wire.tri = c->mesh.tri;
    c->wire.pos = floats(12, 0.25f);
    c->wire.normal = floats(12, -1);
    c->wire.mean_curvature = floats(4, 2);
    c->wire.gauss_curvature = NULL; /* not computed */
    c->vertex_class = malloc(4);
    memcpy(c->vertex_class, (uint8_t[]){0, 1, 1, 2}, 4);
    c->wire.vertex_class = c->vertex_class;
    c->tri_cell = malloc(2 * sizeof *c->tri_cell);
    memcpy(c->tri_cell, (uint32_t[]){0, 1}, 2 * sizeof *c->tri_cell);
    c->wire.tri_cell = c->tri_cell;
    ism_polylines *arcs = &c->features.arcs;
    arcs->n = 1;
    arcs->start = malloc(2 * sizeof *arcs->start);
    arcs->start[0] = 0;
    arcs->start[1] = 2;
    arcs->verts = malloc(2 * sizeof *arcs->verts);
    memcpy(arcs->verts, (uint32_t[]){0, 2}, 2 * sizeof *arcs->verts);
    c->features.arc_kind = malloc(1);
    c->features.arc_kind[0] = ISM_CUT_LEVEL;
    c->features.arc_curve = malloc(sizeof(uint32_t));
    c->features.arc_curve[0] = 0;
    c->wire.live_triangles = 2;
    for (int k = 0; k < 6; k++)
        c->wire.bounds[k] = k - 2.5;
    ism_polylines *b = &c->features.boundaries;
    b->n = 1;
    b->start = malloc(2 * sizeof *b->start);
    b->start[0] = 0;
    b->start[1] = 5;
    b->verts = malloc(5 * sizeof *b->verts);
    memcpy(b->verts, (uint32_t[]){0, 1, 2, 3, 0}, 5 * sizeof *b->verts);
    c->features.npoints = 1;
    c->features.points = malloc(sizeof(uint32_t));
    c->features.points[0] = 3;
    c->features.point_kind = malloc(1);
    c->features.point_kind[0] = 1;
    c->features.point_class = malloc(1);
    c->features.point_class[0] = 3;
    ism_sing_point sp = {.p = {0.1, 0.2, 0.3}, .type = ISM_SING_NODE, .certified = true};
    ism_locus_add_point(&c->locus, &sp);
    ism_sing_curve cv = {.kind = ISM_CURVE_WHISKER, .closed = true, .n = 2,
                         .end_type = {ISM_END_POINT, ISM_END_BOX}, .end_point = {0, -1},
                         .split_cell = 0.0625, .certified = false, .uncertified_points = 2,
                         .first_uncertified = 1, .first_residual_f = 1e-7,
                         .first_residual_grad = 2e-6, .cert_radius = 1e-10};
    cv.xyz = malloc(6 * sizeof(double));
    for (int i = 0; i < 6; i++)
        cv.xyz[i] = i / 7.0;
    ism_locus_add_curve(&c->locus, &cv);
    c->features.locus = &c->locus;
    c->features_json = strdup("{\"version\":2}");
    c->features_len = strlen(c->features_json);
    c->stats_json = strdup("{\"warnings\":[]}");
    c->stats_len = strlen(c->stats_json);
    c->timings_ms[ISM_TIME_POLYGONISE] = 12.5;
    /* corner 1 a crease side's, corner 4 a sheet normal at the singular locus */
    c->corner_at = malloc(2 * sizeof *c->corner_at);
    memcpy(c->corner_at, (uint32_t[]){1, 4}, 2 * sizeof *c->corner_at);
    c->corner_normal = floats(6, 0.5f);
    c->corner_locus = malloc(2);
    memcpy(c->corner_locus, (uint8_t[]){0, 1}, 2);
    c->wire.ncorner_normals = 2;
    c->wire.corner_at = c->corner_at;
    c->wire.corner_normal = c->corner_normal;
    c->wire.corner_locus = c->corner_locus;
}

static void entry(ism_frame_builder *b)
{
    ism_computed c;
    make(&c);
    memset(b, 0, sizeof *b);
    cr_assert(ism_computed_write(&c, b));
    ism_computed_free(&c);
}

Test(computed, round_trip)
{
    ism_frame_builder b;
    entry(&b);
    ism_computed c, want;
    char why[96];
    cr_assert(ism_computed_read(b.data, b.len, &c, why, sizeof why), "%s", why);
    make(&want);
    cr_assert_str_eq(c.surface_key, want.surface_key);
    cr_assert_eq(c.mesh.nverts, 4);
    cr_assert_eq(c.mesh.ntris, 2);
    cr_assert_eq(memcmp(c.mesh.pos, want.mesh.pos, 12 * sizeof(double)), 0);
    cr_assert_eq(memcmp(c.mesh.tri, want.mesh.tri, 6 * sizeof(uint32_t)), 0);
    cr_assert_eq(memcmp(c.wire.pos, want.wire.pos, 12 * sizeof(float)), 0);
    cr_assert_eq(memcmp(c.wire.normal, want.wire.normal, 12 * sizeof(float)), 0);
    cr_assert_eq(memcmp(c.wire.mean_curvature, want.wire.mean_curvature, 4 * sizeof(float)), 0);
    cr_assert_null(c.wire.gauss_curvature);
    cr_assert_eq(c.wire.vertex_class[3], 2);
    cr_assert_eq(c.wire.tri, c.mesh.tri);
    cr_assert_eq(c.wire.live_triangles, 2);
    cr_assert_eq(c.wire.bounds[5], 2.5);
    cr_assert_eq(c.features.boundaries.n, 1);
    cr_assert_eq(c.features.boundaries.verts[4], 0);
    cr_assert_eq(c.features.curves.n, 0);
    cr_assert_eq(c.features.points[0], 3);
    cr_assert_eq(c.tri_cell[1], 1);
    cr_assert_eq(c.wire.tri_cell, c.tri_cell);
    cr_assert_null(c.tri_sheet);
    cr_assert_eq(c.features.arcs.n, 1);
    cr_assert_eq(c.features.arcs.verts[1], 2);
    cr_assert_eq(c.features.arc_kind[0], ISM_CUT_LEVEL);
    cr_assert_eq(c.features.point_class[0], 3);
    cr_assert_eq(c.features.locus, &c.locus);
    cr_assert_eq(c.locus.npoints, 1);
    cr_assert_eq(c.locus.points[0].p[2], 0.3);
    cr_assert(c.locus.points[0].certified);
    cr_assert_eq(c.locus.ncurves, 1);
    cr_assert(c.locus.curves[0].closed);
    cr_assert_eq(c.locus.curves[0].kind, ISM_CURVE_WHISKER);
    cr_assert_eq(c.locus.curves[0].xyz[5], 5 / 7.0);
    cr_assert_eq(c.locus.curves[0].end_type[0], ISM_END_POINT);
    cr_assert_eq(c.locus.curves[0].end_type[1], ISM_END_BOX);
    cr_assert_eq(c.locus.curves[0].end_point[0], 0);
    cr_assert_eq(c.locus.curves[0].end_point[1], -1);
    cr_assert_eq(c.locus.curves[0].split_cell, 0.0625); /* the octree's cell along it */
    /* its certificate (curve_cert.h) */
    cr_assert(!c.locus.curves[0].certified);
    cr_assert_eq(c.locus.curves[0].uncertified_points, 2);
    cr_assert_eq(c.locus.curves[0].first_uncertified, 1);
    cr_assert_eq(c.locus.curves[0].first_residual_f, 1e-7);
    cr_assert_eq(c.locus.curves[0].first_residual_grad, 2e-6);
    cr_assert_eq(c.locus.curves[0].cert_radius, 1e-10);
    cr_assert_str_eq(c.features_json, "{\"version\":2}");
    cr_assert_str_eq(c.stats_json, "{\"warnings\":[]}");
    cr_assert_eq(c.timings_ms[ISM_TIME_POLYGONISE], 12.5);
    cr_assert_eq(c.wire.ncorner_normals, 2);
    cr_assert_eq(c.wire.corner_at, c.corner_at);
    cr_assert_eq(c.corner_at[1], 4);
    cr_assert_eq(memcmp(c.corner_normal, want.corner_normal, 6 * sizeof(float)), 0);
    cr_assert_eq(c.wire.corner_locus, c.corner_locus);
    cr_assert_eq(c.corner_locus[0], 0);
    cr_assert_eq(c.corner_locus[1], 1);
    ism_wire_mesh v;
    ism_computed_wire(&c, ISM_ATTR_CLASS, &v);
    cr_assert_null(v.normal);
    cr_assert_null(v.mean_curvature);
    cr_assert_eq(v.vertex_class, c.vertex_class);
    cr_assert_eq(v.tri_cell, c.tri_cell); /* triangle labels go whatever the attributes */
    ism_computed_free(&c);
    ism_computed_free(&want);
    ism_frame_builder_free(&b);
}

Test(computed, truncated_or_altered_entries_are_refused)
{
    ism_frame_builder b;
    entry(&b);
    ism_computed c;
    char why[96];
    for (size_t cut = 0; cut < b.len; cut++)
        cr_assert_not(ism_computed_read(b.data, cut, &c, why, sizeof why), "cut %zu", cut);
    unsigned char *copy = malloc(b.len + 1);
    memcpy(copy, b.data, b.len);
    copy[b.len] = 0;
    cr_assert_not(ism_computed_read(copy, b.len + 1, &c, why, sizeof why)); /* trailing */
    copy[8] ^= 1; /* version (after the 4-byte length and "ISMS") */
    cr_assert_not(ism_computed_read(copy, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "another entry version");
    memcpy(copy, b.data, b.len);
    copy[4] = 'X';
    cr_assert_not(ism_computed_read(copy, b.len, &c, why, sizeof why));
    free(copy);
    ism_frame_builder_free(&b);

    /* a triangle naming vertex 4 of 4 */
    ism_computed bad;
    make(&bad);
    bad.mesh.tri[5] = 4;
    memset(&b, 0, sizeof b);
    cr_assert(ism_computed_write(&bad, &b));
    cr_assert_not(ism_computed_read(b.data, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "triangle vertex out of range");
    ism_frame_builder_free(&b);
    bad.mesh.tri[5] = 3;
    bad.features.boundaries.verts[2] = 9;
    memset(&b, 0, sizeof b);
    cr_assert(ism_computed_write(&bad, &b));
    cr_assert_not(ism_computed_read(b.data, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "polyline vertex out of range");
    ism_frame_builder_free(&b);
    bad.features.boundaries.verts[2] = 2;
    bad.locus.curves[0].end_point[1] = 1; /* of 1 singular point */
    memset(&b, 0, sizeof b);
    cr_assert(ism_computed_write(&bad, &b));
    cr_assert_not(ism_computed_read(b.data, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "singular curve");
    ism_frame_builder_free(&b);
    bad.locus.curves[0].end_point[1] = -1;
    bad.locus.curves[0].split_cell = -1;
    memset(&b, 0, sizeof b);
    cr_assert(ism_computed_write(&bad, &b));
    cr_assert_not(ism_computed_read(b.data, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "singular curve");
    ism_frame_builder_free(&b);
    bad.locus.curves[0].split_cell = 0.0625;
    bad.corner_locus[0] = 2; /* a mark is 0 or 1 */
    memset(&b, 0, sizeof b);
    cr_assert(ism_computed_write(&bad, &b));
    cr_assert_not(ism_computed_read(b.data, b.len, &c, why, sizeof why));
    cr_assert_str_eq(why, "corner locus mark not 0 or 1");
    ism_frame_builder_free(&b);
    ism_computed_free(&bad);
}
