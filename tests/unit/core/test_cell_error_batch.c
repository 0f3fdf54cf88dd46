/* test_cell_error_batch.c — the flatness test's error measure (cell_error.h) in batches and on
 * the scalar reference path (the sampler's batch off: every point by ism_sample_grad alone)
 * gives every node the same verdict and the same figure bit for bit: on every node of a level
 * of the gyroid ball, Barth's sextic and the ring torus, in three placements, each under no
 * bound (every point measured) and under a finite one (the measuring stops at the first point
 * beyond). Among them the fans, polygons of five sides or more, whose centre the batched path
 * starts from a gradient evaluated among the edges' points. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/cell_error.h"
#include "poly_fixture.h"

#define SIDE 24   /* nodes an axis */
#define HALF 1.6  /* the box: ±1.6 (the gyroid's ball r 1.4, Barth's 1.5, inside) */
#define FANS 5    /* crossed edges from which a node's polygon (or polygons) may be a fan */

/* Node (i, j, l)'s corners in box, f and ∇f on s's tape (corner c: bit a of c, one step
 * along axis a); no memo (each measure searches its own roots). */
static void node_corners(ism_sampler *s, const double box[6], int i, int j, int l,
                         ism_corners *k)
{
    const int at[3] = {i, j, l};
    memset(k, 0, sizeof *k);
    for (int c = 0; c < 8; c++) {
        for (int a = 0; a < 3; a++) {
            double h = (box[a + 3] - box[a]) / SIDE;
            k->p[c][a] = box[a] + (at[a] + (c >> a & 1)) * h;
        }
        k->f[c] = ism_eval_gradient(s->tape, s->ws, k->p[c][0], k->p[c][1], k->p[c][2],
                                    k->g[c]);
    }
}

/* Nodes whose batched and scalar measures differ (verdict or figure's bits); *fans: the
 * nodes measured with FANS or more crossed edges. */
static size_t compare(const pf_surface *surf, int placement, double bound, size_t *fans)
{
    const double base[6] = {-HALF, -HALF, -HALF, HALF, HALF, HALF};
    double box[6];
    pf_sweep_box(base, 6, placement, box);
    ism_sampler s;
    ism_tape *t = pf_build_sampler(surf, &s);
    s.dist_above = bound < INFINITY ? bound : 0;
    size_t differ = 0;
    for (int i = 0; i < SIDE * SIDE * SIDE; i++) {
        ism_corners k;
        node_corners(&s, box, i % SIDE, i / SIDE % SIDE, i / SIDE / SIDE, &k);
        unsigned crossed = ism_single_root_edges(k.f);
        if (!crossed)
            continue;
        double err[2] = {-1, -1};
        bool ok[2];
        for (int b = 0; b < 2; b++) {
            s.batch = b == 0;
            ok[b] = ism_cell_error(&s, &k, bound, 0, NULL, &err[b]);
        }
        *fans += ok[0] && __builtin_popcount(crossed) >= FANS;
        if (ok[0] != ok[1] || memcmp(&err[0], &err[1], sizeof err[0]) != 0) {
            if (differ++ < 3)
                cr_log_error("%s placement %d bound %g node %d: batch %d %.17g, scalar %d "
                             "%.17g", surf->expr, placement, bound, i, ok[0], err[0], ok[1],
                             err[1]);
        }
    }
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
    return differ;
}

Test(cell_error_batch, batched_and_scalar_measures_agree_bit_for_bit)
{
    const pf_surface *surfs[] = {&pf_gyroid_ball, &pf_barth_sextic, &pf_ring_torus};
    const double bounds[] = {INFINITY, 2e-3};
    for (int sf = 0; sf < 3; sf++) {
        size_t fans = 0;
        for (int p = -1; p < 2; p++) /* own box, +1e-3, irrational (pf_sweep_box) */
            for (int b = 0; b < 2; b++)
                cr_expect_eq(compare(surfs[sf], p, bounds[b], &fans), 0,
                             "%s placement %d bound %g: nodes measured otherwise",
                             surfs[sf]->expr, p, bounds[b]);
        cr_expect_gt(fans, 60, "%s: %zu nodes with a fan's edges", surfs[sf]->expr, fans);
    }
}
