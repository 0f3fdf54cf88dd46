/* test_corner_split.c — splitting vertices where triangle labels change (proto/corner_split.h):
 * a square of four triangles around its centre, two cells: the centre and the two corners on
 * the cut become two points each, the others one; every triangle's points carry its cell
 * and copy its vertices. */
#include <criterion/criterion.h>
#include <string.h>
#include "proto/corner_split.h"

/* Square corners 0..3, centre 4; triangles fan around the centre; cells cut along 0-4-2. */
static const uint32_t TRI[12] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
static const uint32_t CELL[4] = {7, 7, 9, 9};

/* The square as a wire mesh with the given labels. */
static ism_wire_mesh square(const uint32_t *cell, const uint8_t *sheet)
{
    ism_wire_mesh w = {.nverts = 5, .ntris = 4, .tri = TRI, .tri_cell = cell, .tri_sheet = sheet};
    return w;
}

Test(corner_split, points_split_only_where_cells_meet)
{
    ism_corner_split s;
    ism_wire_mesh w = square(CELL, NULL);
    cr_assert(ism_corner_split_build(&w, &s));
    cr_expect_eq(s.npoints, 8, "5 vertices, 3 of them (0, 2, 4) on the cut: %zu", s.npoints);
    cr_expect_null(s.point_sheet);
    for (size_t t = 0; t < 4; t++)
        for (int k = 0; k < 3; k++) {
            uint32_t p = s.tri[3 * t + k];
            cr_assert_lt(p, s.npoints);
            cr_expect_eq(s.point_vertex[p], TRI[3 * t + k]);
            cr_expect_eq(s.point_cell[p], CELL[t]);
        }
    ism_corner_split_free(&s);
}

Test(corner_split, one_label_everywhere_keeps_the_vertices)
{
    const uint8_t sheet[4] = {1, 1, 1, 1};
    ism_corner_split s;
    ism_wire_mesh w = square(NULL, sheet);
    cr_assert(ism_corner_split_build(&w, &s));
    cr_expect_eq(s.npoints, 5);
    cr_expect_null(s.point_cell);
    for (size_t p = 0; p < s.npoints; p++)
        cr_expect_eq(s.point_sheet[p], 1);
    ism_corner_split_free(&s);
    w = square(NULL, NULL);
    cr_expect(!ism_corner_split_build(&w, &s), "no labels: nothing to split");
}

/* A crease along 0-4-2: triangles 2 and 3 give their corners on it (vertices 2, 4, 0) their
 * own normal; vertices 0, 2, 4 become two points each, with the side's normal, no labels. */
Test(corner_split, crease_corners_get_points_of_their_own)
{
    float vn[15], side[3] = {0, 0.6f, 0.8f};
    for (int v = 0; v < 5; v++) {
        vn[3 * v] = vn[3 * v + 1] = 0;
        vn[3 * v + 2] = 1;
    }
    /* corners of triangles 2 (2, 3, 4) and 3 (3, 0, 4) on the crease: 6, 8, 10, 11 */
    const uint32_t at[4] = {6, 8, 10, 11};
    float cn[12];
    for (int j = 0; j < 4; j++)
        memcpy(cn + 3 * j, side, sizeof side);
    ism_wire_mesh w = square(NULL, NULL);
    w.normal = vn;
    w.ncorner_normals = 4;
    w.corner_at = at;
    w.corner_normal = cn;
    ism_corner_split s;
    cr_assert(ism_corner_split_build(&w, &s));
    cr_expect_eq(s.npoints, 8, "vertices 0, 2, 4 split: %zu points", s.npoints);
    cr_expect_null(s.point_cell);
    for (uint32_t c = 0; c < 12; c++) {
        uint32_t p = s.tri[c];
        bool own = c == 6 || c == 8 || c == 10 || c == 11;
        cr_expect_eq(s.point_vertex[p], TRI[c]);
        cr_expect_float_eq(s.point_normal[3 * p + 1], own ? 0.6f : 0.0f, 1e-7, "corner %u", c);
    }
    ism_corner_split_free(&s);
    w.normal = NULL; /* normals not sent: the corner normals split nothing */
    cr_expect(!ism_corner_split_build(&w, &s));
}
