/* test_face_masks.c — ism_face_masks (face_flat.h), which triangulate.c reads to keep a
 * triangle out of a node's face: each of the 27 points at a node's corners, edge middles,
 * face middles and centre, and each of them one ulp off its planes, against the faces
 * worked out by hand from the coordinates (bit 2a: p[a] on the lower bound of axis a, bit
 * 2a + 1: on the upper); then, for every three of the 27, that their masks share a bit
 * exactly when one face plane holds all three (by coordinates). The node in its own box and
 * moved off the lattice (pf_sweep_box: 1e-3 and irrational). */
#include <criterion/criterion.h>
#include <math.h>

#include "core/octree/face_flat.h"
#include "poly_fixture.h"

enum { LO, MID, HI };

/* The point whose coordinate on axis a is the node's lower bound, middle or upper bound
 * (where[a]), moved one ulp up when nudge (off every plane it was on). */
static ism_fpoint at(const double node[6], const int where[3], bool nudge)
{
    ism_fpoint p = {{0, 0, 0}, {0, 0, 1}, 0};
    for (int a = 0; a < 3; a++) {
        double v = where[a] == LO ? node[a] : where[a] == HI ? node[3 + a]
                                                              : 0.5 * (node[a] + node[3 + a]);
        p.p[a] = nudge ? nextafter(v, INFINITY) : v;
    }
    return p;
}

/* Does one face plane of the node hold a, b and c (coordinates compared)? */
static bool one_plane(const double node[6], const double *a, const double *b, const double *c)
{
    for (int axis = 0; axis < 3; axis++)
        for (int side = 0; side < 2; side++) {
            double v = node[3 * side + axis];
            if (a[axis] == v && b[axis] == v && c[axis] == v)
                return true;
        }
    return false;
}

Test(face_masks, faces_of_points_by_hand)
{
    const double base[6] = {-1.5, -1.25, -1, 1.5, 1.25, 1};
    for (int which = -1; which <= 1; which++) {
        double node[6];
        pf_sweep_box(base, 5, which, node);
        ism_fpoint p[27], off[27];
        uint8_t mask[27], off_mask[27];
        unsigned want[27];
        for (int i = 0; i < 27; i++) {
            int where[3] = {i % 3, i / 3 % 3, i / 9};
            p[i] = at(node, where, false);
            off[i] = at(node, where, true);
            want[i] = 0;
            for (int a = 0; a < 3; a++)
                want[i] |= where[a] == LO ? 1u << 2 * a : where[a] == HI ? 1u << (2 * a + 1) : 0;
        }
        ism_face_masks(node, p, 27, mask);
        ism_face_masks(node, off, 27, off_mask);
        for (int i = 0; i < 27; i++) {
            cr_expect_eq(mask[i], want[i], "placement %d point %d: mask %#x, by hand %#x", which,
                         i, mask[i], want[i]);
            cr_expect_eq(off_mask[i], 0, "placement %d point %d an ulp off: mask %#x", which, i,
                         off_mask[i]);
        }
        for (int a = 0; a < 27; a++)
            for (int b = a + 1; b < 27; b++)
                for (int c = b + 1; c < 27; c++) {
                    bool shared = (mask[a] & mask[b] & mask[c]) != 0;
                    cr_expect_eq(shared, one_plane(node, p[a].p, p[b].p, p[c].p),
                                 "placement %d points %d %d %d", which, a, b, c);
                }
    }
}
