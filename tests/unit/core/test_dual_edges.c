/* test_dual_edges.c — the plain-leaf tests' edge and face masks (corners.h ism_edges_across,
 * dual_classify.h ism_dual_faces_plain) against the cube's edge table itself
 * (corners.h ism_cube_edge: each edge's two corners and two faces), for all 256 corner
 * signs: an edge is crossed when its corners' signs differ, and a face is plain when at most
 * two of the edges naming it are crossed. */
#include <criterion/criterion.h>
#include "core/octree/corners.h"
#include "core/octree/dual_classify.h"

Test(dual_edges, crossed_edges_and_plain_faces_match_the_cube_table)
{
    for (unsigned signs = 0; signs < 256; signs++) {
        unsigned want = 0;
        int crossed_on[6] = {0};
        for (int e = 0; e < 12; e++) {
            int c0, c1, faces[2];
            ism_cube_edge(e, &c0, &c1, faces);
            if ((signs >> c0 & 1) != (signs >> c1 & 1)) {
                want |= 1u << e;
                crossed_on[faces[0]]++;
                crossed_on[faces[1]]++;
            }
        }
        bool plain = true;
        for (int k = 0; k < 6; k++)
            plain &= crossed_on[k] <= 2;
        unsigned got = ism_edges_across(signs);
        cr_assert_eq(got, want, "signs 0x%02x: crossed 0x%03x, the table's 0x%03x", signs, got,
                     want);
        cr_assert_eq(ism_dual_faces_plain(got), plain, "signs 0x%02x: plain faces", signs);
    }
}

/* Each face's mask in ISM_DUAL_FACE_EDGES is exactly the edges ism_cube_edge names on it
 * (revR 6: the table restates corners.h's facts). */
Test(dual_edges, face_masks_are_the_cube_tables_edges)
{
    unsigned want[6] = {0};
    for (int e = 0; e < 12; e++) {
        int c0, c1, faces[2];
        ism_cube_edge(e, &c0, &c1, faces);
        want[faces[0]] |= 1u << e;
        want[faces[1]] |= 1u << e;
    }
    for (int k = 0; k < 6; k++)
        cr_assert_eq(ISM_DUAL_FACE_EDGES[k], want[k], "face %d: 0x%03x, the table's 0x%03x", k,
                     ISM_DUAL_FACE_EDGES[k], want[k]);
}
