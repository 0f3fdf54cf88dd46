/* test_weld_negative_zero.c — ism_weld (weld.c) joins a position held as x = −0 by one copy
 * and as x = +0 by another: same_point calls them one point, so hash_point must send them to
 * one slot (its v = p[k] + 0.0). A strip of triangles on either side of the plane x = 0, its
 * points on the plane copied into two pieces: piece 0 writes them +0, piece 1 writes each of
 * them once −0 and once +0 (in either order, so both the piece's own table and the shared one
 * meet a −0 beside a +0). Want, worked out by hand: every copy of a point joined (3K − 2
 * vertices), the triangles of both pieces on the same plane vertices, and those vertices kept
 * as their first copy, +0. The strip in its own place and moved in y and z by the placements'
 * offsets (tests/unit/placements.h); x stays 0, the plane the test is about. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/octree/weld.h"
#include "tests/unit/placements.h"

enum { K = 8 }; /* points on the plane x = 0: K − 1 triangles on either side */

/* Plane point i (x = 0, written with the sign of zero asked), or, side ±1, the apex of
   triangle i on that side; moved in y and z by shift. */
static ism_fpoint strip_point(int i, int side, bool negative_zero, const double shift[2])
{
    double y = 0.25 * i + (side ? 0.125 : 0), z = side ? 0.1 : 0.5 * sin(i);
    ism_fpoint v = {{side ? side : negative_zero ? -0.0 : 0.0, shift[0] + y, shift[1] + z},
                    {side ? side : 1, 0.5, 0.25}, 0};
    return v;
}

/* Piece 0: triangle j (A_j, B_j, B_{j+1}), B all +0. Piece 1: triangle j (B_j, B_{j+1}, D_j),
   both B −0 when j is even: B_i (0 < i < K − 1) is −0 first for i odd, second for i even. */
static void make_pieces(const double shift[2], ism_cell_out pieces[2])
{
    for (int k = 0; k < 2; k++) {
        ism_cell_out *o = &pieces[k];
        o->nverts = o->cap_verts = 3 * (K - 1);
        o->ntris = o->cap_tris = K - 1;
        o->verts = calloc(o->nverts, sizeof *o->verts);
        o->tris = malloc(3 * o->ntris * sizeof *o->tris);
        cr_assert(o->verts && o->tris);
        for (int j = 0; j + 1 < K; j++) {
            bool neg = k == 1 && j % 2 == 0;
            ism_fpoint *v = o->verts + 3 * j;
            v[0] = strip_point(j, k ? -1 : 1, false, shift);
            v[1] = strip_point(j, 0, neg, shift);
            v[2] = strip_point(j + 1, 0, neg, shift);
            uint32_t *t = o->tris + 3 * j, at = (uint32_t)(3 * j);
            if (k == 0)
                t[0] = at, t[1] = at + 1, t[2] = at + 2;
            else
                t[0] = at + 1, t[1] = at + 2, t[2] = at;
        }
    }
}

Test(weld, negative_zero_joins_positive_zero)
{
    const double shifts[3][2] = {{0, 0}, {PF_OFF_Y, PF_OFF_Z}, {PF_IRR_Y, PF_IRR_Z}};
    for (int w = 0; w < 3; w++) {
        ism_cell_out pieces[2];
        memset(pieces, 0, sizeof pieces);
        make_pieces(shifts[w], pieces);
        cr_assert(signbit(pieces[1].verts[1].p[0]) && !signbit(pieces[0].verts[1].p[0]),
                  "placement %d: the copies differ in their bits", w);
        ism_mesh m;
        memset(&m, 0, sizeof m);
        ism_weld_stats st;
        cr_assert(ism_weld(pieces, 2, NULL, &m, &st, NULL));
        cr_assert_eq(m.ntris, 2 * (K - 1), "placement %d", w);
        cr_assert_eq(m.nverts, 3 * K - 2, "placement %d: %zu vertices, the copies joined", w,
                     m.nverts);
        for (int j = 0; j + 1 < K; j++) { /* piece 1's triangle j on piece 0's B_j, B_{j+1} */
            const uint32_t *a = m.tri + 3 * j, *d = m.tri + 3 * (K - 1 + j);
            cr_assert(d[0] == a[1] && d[1] == a[2], "placement %d: triangle %d: %u %u, want "
                      "%u %u", w, j, d[0], d[1], a[1], a[2]);
        }
        size_t on_plane = 0;
        for (size_t v = 0; v < m.nverts; v++)
            if (m.pos[3 * v] == 0) {
                on_plane++;
                cr_assert(!signbit(m.pos[3 * v]), "placement %d: vertex %zu kept −0", w, v);
            }
        cr_assert_eq(on_plane, K, "placement %d", w);
        ism_mesh_free(&m);
        for (int k = 0; k < 2; k++) {
            free(pieces[k].verts);
            free(pieces[k].tris);
        }
    }
}
