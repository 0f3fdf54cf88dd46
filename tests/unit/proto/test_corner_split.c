/* test_corner_split.c — splitting vertices where triangle labels change (proto/corner_split.h):
 * a square of four triangles around its centre, two cells: the centre and the two corners on
 * the cut become two points each, the others one; every triangle's points carry its cell
 * and copy its vertices. */
#include <criterion/criterion.h>
#include "proto/corner_split.h"

/* Square corners 0..3, centre 4; triangles fan around the centre; cells cut along 0-4-2. */
static const uint32_t TRI[12] = {0, 1, 4, 1, 2, 4, 2, 3, 4, 3, 0, 4};
static const uint32_t CELL[4] = {7, 7, 9, 9};

Test(corner_split, points_split_only_where_cells_meet)
{
    ism_corner_split s;
    cr_assert(ism_corner_split_build(TRI, 4, 5, CELL, NULL, &s));
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
    cr_assert(ism_corner_split_build(TRI, 4, 5, NULL, sheet, &s));
    cr_expect_eq(s.npoints, 5);
    cr_expect_null(s.point_cell);
    for (size_t p = 0; p < s.npoints; p++)
        cr_expect_eq(s.point_sheet[p], 1);
    ism_corner_split_free(&s);
    cr_expect(!ism_corner_split_build(TRI, 4, 5, NULL, NULL, &s), "no labels: nothing to split");
}
