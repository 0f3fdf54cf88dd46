/* test_lattice_pack.c — the registry's sort keys (lattice_pack.h) against their layout
 * written out here: a point's key along an axis holds the coordinate after the axis in the
 * top cb bits, the next in the middle ones and the axis's own at the bottom, each shifted
 * right by `shift`. Checked at every cb up to 20 (the deepest grid: ISM_GRID_MAX_DEPTH + 1)
 * on random points: the key, its inverse, the shift of each field, the rotation from the
 * key along z to the others, and the line and the coordinate along it. */
#include <criterion/criterion.h>
#include <stdint.h>

#include "core/octree/grid.h"
#include "core/octree/lattice_pack.h"

static uint64_t lcg(uint64_t *s)
{
    *s = *s * 6364136223846793005u + 1442695040888963407u;
    return *s >> 33;
}

Test(lattice_pack, fields_and_rotation)
{
    uint64_t seed = 29;
    int checked = 0;
    for (int cb = 1; cb <= ISM_GRID_MAX_DEPTH + 1; cb++)
        for (int shift = 0; shift + cb <= 31; shift += 5) {
            ism_packing k = { shift, cb };
            for (int trial = 0; trial < 200; trial++) {
                uint64_t c[3], top = ((uint64_t)1 << cb) - 1; /* fields: 0 .. top */
                int32_t p[3];
                for (int a = 0; a < 3; a++) { /* the first two trials at the extremes */
                    c[a] = trial == 0 ? top : trial == 1 ? 0 : lcg(&seed) & top;
                    p[a] = (int32_t)(c[a] << shift);
                }
                for (int axis = 0; axis < 3; axis++) {
                    int u = (axis + 1) % 3, v = (axis + 2) % 3;
                    uint64_t want = c[u] << 2 * cb | c[v] << cb | c[axis];
                    uint64_t key = ism_pack(&k, axis, p);
                    cr_assert_eq(key, want, "cb %d shift %d axis %d", cb, shift, axis);
                    cr_assert_eq(ism_repack(&k, axis, ism_pack(&k, 2, p)), want,
                                 "repack: cb %d shift %d axis %d", cb, shift, axis);
                    uint64_t m = ((uint64_t)1 << cb) - 1;
                    for (int a = 0; a < 3; a++)
                        cr_assert_eq(key >> ism_pack_shift(&k, axis, a) & m, c[a],
                                     "field of %d: cb %d axis %d", a, cb, axis);
                    int32_t q[3];
                    ism_unpack(&k, axis, key, q);
                    cr_assert(q[0] == p[0] && q[1] == p[1] && q[2] == p[2], "unpack: cb %d", cb);
                    cr_assert_eq(ism_pack_line(&k, key), c[u] << cb | c[v]);
                    cr_assert_eq(ism_pack_along(&k, key), p[axis]);
                    checked++;
                }
            }
        }
    cr_assert_gt(checked, 20 * 3 * 200);
}
