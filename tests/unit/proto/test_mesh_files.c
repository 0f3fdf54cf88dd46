/* test_mesh_files.c — the corners on the singular locus (proto/wire_mesh.h: a double curve's
 * vertex, shared by two sheets, where ∇f = 0) carry their own sheet's normal in the viewer's
 * formats and the OBJ, while the PLY keeps one row per mesh vertex (issue 13).
 * Two planes z = 0 and y = 0 crossing on the x axis (meshes_for_tests.h, n = 4: 5 shared
 * vertices on the axis, whose normal is the z plane's +z), f = y z (∇f = (0, z, y): zero on
 * the axis only). Counted by hand: in the y = 0 plane each of the 4 quads of the row below
 * the axis and of the row above gives 3 corners on it (1 + 2 triangles' corners), 24
 * corners, whose sheet normal is the y plane's (0, 1, 0); the z plane's corners there keep
 * their vertex's normal (+z). Checked: those 24 corners and no other get a normal of their
 * own, all marked as the locus's; the PLY is byte for byte the PLY without them (vertex
 * count the mesh's), the OBJ has one `v` per vertex and each of those corners names a `vn`
 * of (0, 1, 0), one per axis vertex (bit-equal normals at a vertex share their `vn`), Draco's
 * point split (corner_split.h) gives each axis vertex one more point.
 * The same 24 corners taken as crease sides instead (marked 0: the y plane one side of a
 * crease along the axis, the z plane the other, whose normal is the vertex's): the PLY still
 * has one row per mesh vertex and the mesh's faces, every row but the 5 axis vertices' is the
 * bare PLY's byte for byte, and theirs carry the sides' normalised sum, (0, 1, 1) / sqrt 2. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/expr.h"
#include "core/eval/eval.h"
#include "proto/corner_split.h"
#include "proto/mesh_files.h"
#include "proto/request.h"
#include "proto/wire_mesh.h"
#include "tests/unit/proto/meshes_for_tests.h"

#define N 4             /* quads per side of each plane */
#define AXIS_CORNERS 24 /* 2 rows x N quads x 3 corners, counted above */

typedef struct membuf {
    char *data;
    size_t len, cap;
} membuf;

static size_t mem_write(void *ctx, const void *p, size_t n)
{
    membuf *b = ctx;
    if (b->len + n + 1 > b->cap) {
        b->cap = (b->len + n + 1) * 2;
        b->data = realloc(b->data, b->cap);
    }
    memcpy(b->data + b->len, p, n);
    b->len += n;
    b->data[b->len] = 0; /* text formats: strstr / strtok safe */
    return n;
}

static bool on_axis(const ism_mesh *m, uint32_t v)
{
    return m->pos[3 * v + 1] == 0 && m->pos[3 * v + 2] == 0;
}

/* A triangle of the y = 0 plane (every corner at y = 0; the axis triangles of the z plane
 * have a corner off it). */
static bool in_y_plane(const ism_mesh *m, size_t t)
{
    for (int k = 0; k < 3; k++)
        if (m->pos[3 * m->tri[3 * t + k] + 1] != 0)
            return false;
    return true;
}

typedef struct fixture {
    ism_mesh m;
    ism_wire_mesh w;
    uint32_t *at;
    float *normal;
    uint8_t *locus;
} fixture;

static void setup_planes(fixture *fx)
{
    test_mesh_crossing_planes(&fx->m, N);
    ism_error err;
    ism_tape *f = ism_tape_compile("y * z", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(f, "%s", err.message);
    cr_assert(ism_wire_mesh_build(&fx->m, NULL, ISM_ATTR_NORMAL, 0, &fx->w));
    size_t n;
    cr_assert(ism_wire_corner_normals(f, NULL, &fx->m, NULL, &fx->w, &n, &fx->at, &fx->normal,
                                      &fx->locus));
    ism_tape_free(f);
    fx->w.ncorner_normals = n;
    fx->w.corner_at = fx->at;
    fx->w.corner_normal = fx->normal;
    fx->w.corner_locus = fx->locus;
}

static void teardown(fixture *fx)
{
    free(fx->at);
    free(fx->normal);
    free(fx->locus);
    ism_wire_mesh_free(&fx->w);
    ism_mesh_free(&fx->m);
}

Test(mesh_files, locus_corners_get_their_sheet_normal_marked)
{
    fixture fx;
    setup_planes(&fx);
    cr_assert_eq(fx.w.ncorner_normals, AXIS_CORNERS, "%zu corners", fx.w.ncorner_normals);
    cr_assert_not_null(fx.locus);
    for (size_t j = 0; j < AXIS_CORNERS; j++) {
        uint32_t c = fx.at[j];
        cr_expect(on_axis(&fx.m, fx.m.tri[c]), "corner %u on the axis", c);
        cr_expect(in_y_plane(&fx.m, c / 3), "corner %u of the y plane", c);
        cr_expect_eq(fx.locus[j], 1);
        const float *nv = fx.normal + 3 * j;
        cr_expect(nv[0] == 0 && nv[1] == 1 && nv[2] == 0, "corner %u: (%g, %g, %g)", c,
                  (double)nv[0], (double)nv[1], (double)nv[2]);
    }
    teardown(&fx);
}

Test(mesh_files, ply_keeps_the_mesh_vertices_at_the_locus)
{
    fixture fx;
    setup_planes(&fx);
    membuf with = {0}, without = {0};
    cr_assert(ism_write_ply_wire(&fx.m, &fx.w, mem_write, &with));
    ism_wire_mesh bare = fx.w;
    bare.ncorner_normals = 0;
    bare.corner_at = NULL;
    bare.corner_normal = NULL;
    bare.corner_locus = NULL;
    cr_assert(ism_write_ply_wire(&fx.m, &bare, mem_write, &without));
    char head[64];
    snprintf(head, sizeof head, "element vertex %zu\n", fx.m.nverts);
    cr_expect_not_null(strstr(with.data, head), "the PLY's vertices are the mesh's");
    cr_assert_eq(with.len, without.len);
    cr_expect_eq(memcmp(with.data, without.data, with.len), 0, "byte for byte");
    free(with.data);
    free(without.data);
    teardown(&fx);
}

/* Bytes per PLY row with positions and normals only. */
#define ROW_BYTES (6 * sizeof(float))

Test(mesh_files, ply_crease_sides_share_their_vertex_row)
{
    fixture fx;
    setup_planes(&fx);
    membuf bare_ply = {0}, crease = {0};
    ism_wire_mesh bare = fx.w;
    bare.ncorner_normals = 0;
    cr_assert(ism_write_ply_wire(&fx.m, &bare, mem_write, &bare_ply));
    memset(fx.locus, 0, fx.w.ncorner_normals); /* every one a crease side */
    cr_assert(ism_write_ply_wire(&fx.m, &fx.w, mem_write, &crease));
    char head[64];
    snprintf(head, sizeof head, "element vertex %zu\n", fx.m.nverts);
    cr_expect_not_null(strstr(crease.data, head), "one row per mesh vertex");
    cr_assert_eq(crease.len, bare_ply.len, "no extra rows");
    const char *end = strstr(crease.data, "end_header\n");
    cr_assert_not_null(end);
    size_t at = (size_t)(end - crease.data) + strlen("end_header\n");
    size_t faces = at + fx.m.nverts * ROW_BYTES;
    cr_expect_eq(memcmp(crease.data, bare_ply.data, at), 0, "the same header");
    cr_expect_eq(memcmp(crease.data + faces, bare_ply.data + faces, crease.len - faces), 0,
                 "the mesh's faces");
    size_t axis = 0;
    const float half = (float)sqrt(0.5);
    for (uint32_t v = 0; v < fx.m.nverts; v++) {
        const char *r = crease.data + at + v * ROW_BYTES;
        if (!on_axis(&fx.m, v)) {
            cr_expect_eq(memcmp(r, bare_ply.data + at + v * ROW_BYTES, ROW_BYTES), 0,
                         "row %u", v);
            continue;
        }
        float n[3];
        memcpy(n, r + 3 * sizeof(float), sizeof n);
        cr_expect(fabsf(n[0]) < 1e-7f && fabsf(n[1] - half) < 1e-7f &&
                      fabsf(n[2] - half) < 1e-7f,
                  "axis vertex %u: (%g, %g, %g), the sides' bisector", v, (double)n[0],
                  (double)n[1], (double)n[2]);
        axis++;
    }
    cr_expect_eq(axis, N + 1);
    free(bare_ply.data);
    free(crease.data);
    teardown(&fx);
}

Test(mesh_files, obj_and_draco_points_carry_the_sheet_normals)
{
    fixture fx;
    setup_planes(&fx);
    membuf b = {0};
    cr_assert(ism_write_obj_features(&fx.m, &fx.w, NULL, mem_write, &b));
    size_t nv = 0, nn = 0, nf = 0, sheet = 0;
    float (*vn)[3] = malloc((fx.m.nverts + AXIS_CORNERS) * sizeof *vn);
    unsigned long *vn_of = calloc(fx.m.nverts, sizeof *vn_of); /* an axis vertex's sheet vn */
    char *save = NULL;
    for (char *line = strtok_r(b.data, "\n", &save); line; line = strtok_r(NULL, "\n", &save)) {
        float x, y, z;
        unsigned long v[3], n[3];
        if (!strncmp(line, "v ", 2)) {
            nv++;
        } else if (sscanf(line, "vn %f %f %f", &x, &y, &z) == 3) {
            cr_assert_lt(nn, fx.m.nverts + AXIS_CORNERS);
            vn[nn][0] = x, vn[nn][1] = y, vn[nn][2] = z;
            nn++;
        } else if (sscanf(line, "f %lu//%lu %lu//%lu %lu//%lu", v, n, v + 1, n + 1, v + 2,
                          n + 2) == 6) {
            for (int k = 0; k < 3; k++) {
                cr_assert_eq(v[k] - 1, fx.m.tri[3 * nf + k]);
                cr_assert(n[k] >= 1 && n[k] <= nn);
                if (on_axis(&fx.m, (uint32_t)(v[k] - 1)) && in_y_plane(&fx.m, nf)) {
                    cr_expect(n[k] > fx.m.nverts, "a vn of its own");
                    cr_expect(vn[n[k] - 1][1] == 1, "the y plane's normal");
                    unsigned long *seen = vn_of + (v[k] - 1);
                    cr_expect(!*seen || *seen == n[k], "one `vn` per axis vertex");
                    *seen = n[k];
                    sheet++;
                }
            }
            nf++;
        }
    }
    cr_expect_eq(nv, fx.m.nverts, "one `v` per mesh vertex");
    /* one `vn` per axis vertex: its y plane corners on both sides of the axis share (0, 1, 0),
     * as they share one Draco point */
    cr_expect_eq(nn, fx.m.nverts + N + 1, "%zu vn", nn);
    cr_expect_eq(nf, fx.m.ntris);
    cr_expect_eq(sheet, AXIS_CORNERS);
    free(vn);
    free(vn_of);
    free(b.data);

    ism_corner_split s;
    cr_assert(ism_corner_split_build(&fx.w, &s));
    cr_expect_eq(s.npoints, fx.m.nverts + N + 1, "each axis vertex one more point: %zu",
                 s.npoints);
    for (size_t c = 0; c < 3 * fx.m.ntris; c++) {
        const float *pn = s.point_normal + 3 * (size_t)s.tri[c];
        bool sheet_corner = on_axis(&fx.m, fx.m.tri[c]) && in_y_plane(&fx.m, c / 3);
        cr_expect_eq(s.point_vertex[s.tri[c]], fx.m.tri[c]);
        if (on_axis(&fx.m, fx.m.tri[c]))
            cr_expect_eq(pn[sheet_corner ? 1 : 2], 1, "corner %zu", c);
    }
    ism_corner_split_free(&s);
    teardown(&fx);
}
