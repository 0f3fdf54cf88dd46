/* test_tile_corners.c — ism_tile_corner_points (a tile's corner positions from its five
 * coordinates, each found once) against ism_grid_point of ism_tile_corners' lattice points,
 * bit for bit: random tiles (each axis, plane, u0 < u1, v0 < v1) on a grid whose steps and
 * origins differ per axis (a corner given another axis's coordinate or the other end of u or
 * v lands elsewhere), in the three placements (origin as given, moved by the 1e-3 shift and
 * by the irrational one of a cell); and ism_tile_corners against the walk's order,
 * counter-clockwise in (u, v) from (u0, v0), written out here. */
#include <criterion/criterion.h>
#include <string.h>
#include "core/octree/tile_corners.h"
#include "tests/unit/placements.h"

static uint32_t tc_draw(uint64_t *s, uint32_t n) /* uniform in 0 .. n - 1; *s xorshift state */
{
    *s ^= *s << 13, *s ^= *s >> 7, *s ^= *s << 17;
    return (uint32_t)((*s >> 11) % n);
}

Test(tile_corners, points_are_ism_grid_point_of_the_corners_bit_for_bit)
{
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X / 64, PF_IRR_Y / 64, PF_IRR_Z / 64}};
    uint64_t s = 0x2545f4914f6cdd1dull;
    for (int pl = 0; pl < 3; pl++) {
        ism_grid g = {10, {-1.25 + shift[pl][0], -0.5 + shift[pl][1], -2.0 + shift[pl][2]},
                      {1.0 / 64, 3.0 / 256, 0.0137}};
        for (int n = 0; n < 30000; n++) {
            ism_tile t;
            t.axis = n % 3;
            t.plane = (int32_t)tc_draw(&s, 1025);
            t.u0 = (int32_t)tc_draw(&s, 1024);
            t.u1 = t.u0 + 1 + (int32_t)tc_draw(&s, (uint32_t)(1024 - t.u0));
            t.v0 = (int32_t)tc_draw(&s, 1024);
            t.v1 = t.v0 + 1 + (int32_t)tc_draw(&s, (uint32_t)(1024 - t.v0));
            int32_t q[4][3];
            double p[4][3];
            ism_tile_corners(&t, q);
            ism_tile_corner_points(&g, &t, p);
            int u = (t.axis + 1) % 3, v = (t.axis + 2) % 3;
            const int32_t want_u[4] = {t.u0, t.u1, t.u1, t.u0};
            const int32_t want_v[4] = {t.v0, t.v0, t.v1, t.v1};
            for (int k = 0; k < 4; k++) {
                cr_assert(q[k][t.axis] == t.plane && q[k][u] == want_u[k] &&
                              q[k][v] == want_v[k],
                          "axis %d corner %d: lattice point (%d %d %d)", t.axis, k, q[k][0],
                          q[k][1], q[k][2]);
                ism_ipt ip = {{q[k][0], q[k][1], q[k][2]}};
                double w[3];
                ism_grid_point(&g, ip, w);
                cr_assert(memcmp(p[k], w, sizeof w) == 0,
                          "placement %d axis %d corner %d: (%a %a %a), ism_grid_point (%a %a %a)",
                          pl, t.axis, k, p[k][0], p[k][1], p[k][2], w[0], w[1], w[2]);
            }
        }
    }
}
