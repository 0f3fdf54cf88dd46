/* test_conform_tube.c — which triangles the tube round a double curve takes (tri_in_tube,
 * core/singular/conform_tube.c, through cf_tube_selects), against a closed form. The curve is
 * a straight segment along x; the mesh is strips of small triangles (edges r / 20) laid in
 * planes parallel to it, each at a distance D from it, its rows going away from the curve
 * from the plane's nearest line. A point of such a strip at in-plane offset w from that line
 * is sqrt(D^2 + w^2) from the curve, so a triangle has a point within r exactly when its
 * corner of least w does: sqrt(D^2 + w_min^2) <= r. Every triangle is asked twice at radius
 * r1 and twice at r2 = 1.3 r1 in the same group, so the second answers come from the memo and
 * those at r2 from distances memoised at r1 (kept when finite) and those asked anew (the ones
 * beyond r1 + reach at r1). In the three placements. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/singular/conform_internal.h"
#include "tests/unit/placements.h"

#define NCURVE 81 /* the curve's points, x from -1 to 1 */
#define NX 160    /* triangle columns along x, from x = -0.2 */
#define NROW 2    /* triangle rows away from the curve */

/* the strips' distances from the curve, in r1: inside at both radii, just inside and just
 * outside r1, outside r1 + reach but inside r2 (memoised INFINITY at r1), outside r2 but
 * memoised finite there, beyond every reach */
static const double band[] = {0.5, 0.99, 1.01, 1.25, 1.45, 1.99, 3};
#define NBAND (sizeof band / sizeof *band)

/* The strips in mesh m, the scene moved by o: band b's plane has the unit normal n_b (from
 * the curve, across x) and in-plane direction u_b (away from the plane's nearest line). */
static void build_strips(ism_mesh *m, double r1, const double o[3])
{
    double h = r1 / 20;
    for (size_t b = 0; b < NBAND; b++) {
        double th = 0.9 * (double)b + 0.3, d = band[b] * r1;
        double n[2] = {cos(th), sin(th)}, u[2] = {-sin(th), cos(th)};
        uint32_t v0 = (uint32_t)m->nverts;
        for (int i = 0; i <= NX; i++)
            for (int j = 0; j <= NROW; j++) {
                double w = j * h;
                double p[3] = {o[0] - 0.2 + i * h, o[1] + d * n[0] + w * u[0],
                               o[2] + d * n[1] + w * u[1]};
                cr_assert_neq(ism_mesh_add_vertex(m, p, NULL), UINT32_MAX);
            }
        for (int i = 0; i < NX; i++)
            for (int j = 0; j < NROW; j++) {
                uint32_t a = v0 + (uint32_t)(i * (NROW + 1) + j), a1 = a + NROW + 1;
                cr_assert(ism_mesh_add_triangle(m, a, a1, a1 + 1));
                cr_assert(ism_mesh_add_triangle(m, a, a1 + 1, a + 1));
            }
    }
}

/* Triangle t's answer by the closed form at radius r (the strips' layout: two triangles per
 * cell, NROW cells a column, NX columns a band). */
static bool expected(size_t t, double r1, double r)
{
    size_t b = t / (2 * NROW * NX), j = (t / 2) % NROW;
    double h = r1 / 20, d = band[b] * r1, w = (double)j * h;
    double dist = sqrt(d * d + w * w);
    cr_assert(fabs(dist - r) > 1e-3 * r, "triangle %zu: %g at the radius %g", t, dist, r);
    return dist <= r;
}

Test(conform_tube, selects_by_the_nearest_corner)
{
    const double r1 = 0.05, reach = 0.2 * r1, radius[2] = {r1, 1.3 * r1};
    const double shift[3][3] = {{0, 0, 0},
                                {PF_OFF_X, PF_OFF_Y, PF_OFF_Z},
                                {PF_IRR_X * r1, PF_IRR_Y * r1, PF_IRR_Z * r1}};
    for (int sh = 0; sh < 3; sh++) {
        const double *o = shift[sh];
        double p[3 * NCURVE];
        for (int i = 0; i < NCURVE; i++) {
            p[3 * i] = o[0] - 1 + 2.0 * i / (NCURVE - 1);
            p[3 * i + 1] = o[1];
            p[3 * i + 2] = o[2];
        }
        cf_polyline pl;
        cr_assert(cf_polyline_init(&pl, p, NCURVE, false, r1));
        ism_mesh m;
        ism_mesh_init(&m);
        build_strips(&m, r1, o);
        ism_conform_stats st;
        memset(&st, 0, sizeof st);
        cf_ctx c;
        memset(&c, 0, sizeof c);
        c.m = &m;
        c.st = &st;
        cf_tube *tb = cf_tube_new(&pl, 1, r1, reach);
        cr_assert_not_null(tb);
        for (int k = 0; k < 2; k++) {
            cr_assert(cf_tube_radius(&c, tb, radius[k]));
            size_t in = 0;
            for (int ask = 0; ask < 2; ask++) /* the second from the memo */
                for (size_t t = 0; t < m.ntris; t++) {
                    bool want = expected(t, r1, radius[k]);
                    in += want;
                    cr_assert_eq(cf_tube_selects(&c, tb, (uint32_t)t), want,
                                 "placement %d radius %g ask %d triangle %zu (band %g r1)", sh,
                                 radius[k], ask, t, band[t / (2 * NROW * NX)]);
                }
            /* both answers occur: 2 bands in at r1, 4 at r2, of 7 */
            cr_assert_eq(in, 2 * (size_t)(k ? 4 : 2) * 2 * NROW * NX);
        }
        cf_tube_free(tb);
        cf_ctx_free(&c);
        ism_mesh_free(&m);
        cf_polyline_free(&pl);
    }
}
