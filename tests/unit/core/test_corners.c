/* test_corners.c — the numbering of a node's edges (corners.h's ism_cube_edge, a written-out
 * table): every one of the cube's 12 edges once, each joining two corners one step apart
 * along its axis (edges 4a .. 4a + 3 along axis a, c0 the lower end), and its two faces the
 * ones both its corners lie on across the two other axes (corner c lies on face
 * 2 × axis + side when bit `axis` of c is `side`); the edge masks of corner masks and the
 * corners' sign masks against the rules they pack. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdbool.h>
#include "core/octree/corners.h"
#include "corner_signs.h"

Test(corners, cube_edges_join_neighbours_on_their_faces)
{
    int seen[8][8] = {{0}};
    for (int e = 0; e < 12; e++) {
        int c0, c1, faces[2];
        ism_cube_edge(e, &c0, &c1, faces);
        int axis = e / 4;
        cr_assert(c0 >= 0 && c0 < 8 && c1 >= 0 && c1 < 8, "edge %d", e);
        cr_expect_eq(c1 ^ c0, 1 << axis, "edge %d: %d -> %d", e, c0, c1);
        cr_expect_eq(c0 & (1 << axis), 0, "edge %d starts at its upper end", e);
        cr_expect_eq(seen[c0][c1]++, 0, "edge %d repeats %d -> %d", e, c0, c1);
        cr_expect_neq(faces[0] / 2, faces[1] / 2, "edge %d", e);
        for (int k = 0; k < 2; k++) {
            int fa = faces[k] / 2, side = faces[k] % 2;
            cr_expect_neq(fa, axis, "edge %d lies across its own axis", e);
            cr_expect_eq((c0 >> fa) & 1, side, "edge %d corner %d off face %d", e, c0, faces[k]);
            cr_expect_eq((c1 >> fa) & 1, side, "edge %d corner %d off face %d", e, c1, faces[k]);
        }
    }
}

/* The exact order corners.h documents, which callers that tabulate by e rely on (dual.c's
 * per-edge corner and face tables): with a = e / 4, r = e % 4, o1 = (a + 1) % 3, o2 = (a + 2)
 * % 3, c0 = (r & 1) << o1 | (r >> 1 & 1) << o2, c1 = c0 | 1 << a, faces o1 * 2 + (r & 1) and
 * o2 * 2 + (r >> 1 & 1) (a table swapping two edges of one axis passes the test above). */
Test(corners, cube_edges_in_the_documented_order)
{
    for (int e = 0; e < 12; e++) {
        int a = e / 4, r = e % 4, o1 = (a + 1) % 3, o2 = (a + 2) % 3;
        int want0 = (r & 1) << o1 | (r >> 1 & 1) << o2;
        int c0, c1, faces[2];
        ism_cube_edge(e, &c0, &c1, faces);
        cr_expect_eq(c0, want0, "edge %d: c0 %d, documented %d", e, c0, want0);
        cr_expect_eq(c1, want0 | 1 << a, "edge %d: c1 %d", e, c1);
        cr_expect_eq(faces[0], o1 * 2 + (r & 1), "edge %d: face %d", e, faces[0]);
        cr_expect_eq(faces[1], o2 * 2 + (r >> 1 & 1), "edge %d: face %d", e, faces[1]);
    }
}

/* ism_edges_across / ism_edges_touching against the edge table read one edge at a time, for
 * every corner mask: an edge is across m when exactly one of its corners is in m, touching
 * when at least one is (a packing that swaps two edges or drops a bit fails here). */
Test(corners, edge_masks_are_the_table_read_edge_by_edge)
{
    for (unsigned m = 0; m < 256; m++) {
        unsigned across = 0, touching = 0;
        for (int e = 0; e < 12; e++) {
            int c0, c1, faces[2];
            ism_cube_edge(e, &c0, &c1, faces);
            unsigned in0 = m >> c0 & 1, in1 = m >> c1 & 1;
            across |= (in0 ^ in1) << e;
            touching |= (in0 | in1) << e;
        }
        cr_expect_eq(ism_edges_across(m), across, "mask %#x", m);
        cr_expect_eq(ism_edges_touching(m), touching, "mask %#x", m);
    }
}

/* ism_corner_sign_masks and ism_single_root_edges against the compares (corner_signs.h);
 * the scalar branch: test_corners_scalar.c. */
Test(corners, sign_masks_are_the_compares_corner_by_corner)
{
    check_sign_masks();
}
