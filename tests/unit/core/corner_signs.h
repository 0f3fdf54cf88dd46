/* corner_signs.h — the check of corners.h's sign masks, included by test_corners.c (the SSE2
 * branch on x86-64) and test_corners_scalar.c (the scalar one): each unit checks the
 * branch it compiled. */
#ifndef ISM_TEST_CORNER_SIGNS_H
#define ISM_TEST_CORNER_SIGNS_H

#include <criterion/criterion.h>
#include <math.h>
#include <stdbool.h>
#include "core/octree/corners.h"

/* ism_corner_sign_masks against C's < 0 and == 0 corner by corner, and ism_single_root_edges
 * against its rule (crossed by the sign change, touching no zero corner), on 8 corners drawn
 * from values whose signs are easy to get wrong lane by lane: ±0, NaN, ±inf, the least
 * subnormals, ±1; every corner position takes every value (an LCG picks the others). */
static void check_sign_masks(void)
{
    const double vals[] = {0.0, -0.0, NAN, -NAN, INFINITY, -INFINITY, 0x1p-1074, -0x1p-1074,
                           1.0, -1.0};
    const int nv = (int)(sizeof vals / sizeof vals[0]);
    unsigned long long s = 31;
    for (int round = 0; round < 4000; round++) {
        double f[8];
        for (int c = 0; c < 8; c++) {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            f[c] = vals[(s >> 33) % (unsigned long long)nv];
        }
        f[round % 8] = vals[round / 8 % nv]; /* every value at every corner */
        unsigned neg, zero, want_neg = 0, want_zero = 0;
        for (int c = 0; c < 8; c++) {
            want_neg |= (unsigned)(f[c] < 0) << c;
            want_zero |= (unsigned)(f[c] == 0) << c;
        }
        ism_corner_sign_masks(f, &neg, &zero);
        cr_assert_eq(neg, want_neg, "round %d: neg %#x, want %#x", round, neg, want_neg);
        cr_assert_eq(zero, want_zero, "round %d: zero %#x, want %#x", round, zero, want_zero);
        unsigned single = 0;
        for (int e = 0; e < 12; e++) {
            int c0, c1, faces[2];
            ism_cube_edge(e, &c0, &c1, faces);
            bool crossed = (f[c0] < 0) != (f[c1] < 0);
            bool on_zero = f[c0] == 0 || f[c1] == 0;
            single |= (unsigned)(crossed && !on_zero) << e;
        }
        cr_assert_eq(ism_single_root_edges(f), single, "round %d", round);
    }
}

#endif
