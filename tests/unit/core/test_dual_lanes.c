/* test_dual_lanes.c — the lane steps dual.c's place_plain places plain leaves' vertices with,
 * against the one-point calls the rest of the mesher takes the same steps with (revF 1):
 *   - the centres' feet in lanes (ism_dual_feet_in_nodes) against one box at a time
 *     (ism_dual_foot_in_node, which sag_split asks and whose verdict a leaf keeps as
 *     FOOT_OUT): the same foot to the bit and the same verdict;
 *   - Newton from a point in lanes (ism_dual_newton_lanes) against ism_dual_newton_onto from
 *     it, for leaves whose foot left them: the same point to the bit, the same verdict;
 *   - the balanced straddle move with f's jets taken in one batch (ism_eval_hessian_batch,
 *     ism_straddle_balanced_point_at) against ism_straddle_balanced_point: the same move.
 * If one of these paths changed alone, place_plain would put vertices elsewhere than sag_split
 * and dual_measure assume. The torus's level-5 leaves reaching the tube, in the three
 * placements (PF_OFF_* / PF_IRR_*).
 * And fans' centres and cut sides' vertices (dual_measure.c's fan_task, dual_sides.c's
 * side_task: ism_dual_vertices_onto, Newton in lanes, then the straddle move on the lanes
 * Newton finished) against Newton and the straddle move one point at a time
 * (ism_dual_newton_onto, ism_straddle_balanced_point): the same vertex to the bit, NaN in the
 * same lanes (revR 1). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/dual_classify.h"
#include "core/octree/dual_measure.h"
#include "core/octree/dual_tree.h"
#include "core/octree/grid.h"
#include "core/octree/straddle.h"
#include "poly_fixture.h"

#define DEPTH 10
#define LEVEL 5
#define E 0.0141 /* the bench's 1e-2 setting on the torus */

/* Boxes lo[k]..hi[k] (side size) of the level-LEVEL cells whose centre lies within half a
 * diagonal (0.87 of a side) of the tube; returns how many (at most cap). */
static size_t tube_boxes(const ism_grid *g, double (*lo)[3], double (*hi)[3], size_t cap)
{
    int32_t step = ism_grid_cell_steps(g, LEVEL);
    int cells = 1 << LEVEL;
    double size = ism_grid_cell_size(g, LEVEL);
    size_t n = 0;
    for (int z = 0; z < cells; z++)
        for (int y = 0; y < cells; y++)
            for (int x = 0; x < cells && n < cap; x++) {
                int32_t q[3] = {x * step, y * step, z * step};
                double c[3];
                for (int a = 0; a < 3; a++) {
                    lo[n][a] = ism_grid_coord(g, a, q[a]);
                    hi[n][a] = ism_grid_coord(g, a, q[a] + step);
                    c[a] = ism_grid_coord(g, a, q[a] + step / 2);
                }
                if (pf_ring_torus_dist(c) <= 0.87 * size)
                    n++;
            }
    return n;
}

static bool same3(const double a[3], const double b[3])
{
    return !memcmp(a, b, 3 * sizeof *a);
}

Test(dual_lanes, lane_steps_bit_for_bit_the_one_point_calls)
{
    enum { CAP = 8192 };
    ism_tape *t = pf_compile(&pf_ring_torus);
    double (*lo)[3] = malloc(CAP * sizeof *lo), (*hi)[3] = malloc(CAP * sizeof *hi);
    cr_assert(t && lo && hi);
    for (int i = pf_first_box(); i < 3; i++) {
        double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5}, box[6];
        pf_sweep_box(base, DEPTH, i - 1, box);
        ism_grid g;
        ism_grid_init(&g, box, DEPTH);
        worker w;
        memset(&w, 0, sizeof w);
        w.s.tape = t;
        w.s.ws = ism_eval_ws_new(t);
        w.s.batch = true;
        cr_assert(w.s.ws);
        size_t n = tube_boxes(&g, lo, hi, CAP), out = 0, moved = 0;
        cr_assert(n > 0 && n < CAP, "placement %d: %zu boxes", i, n);
        double size = ism_grid_cell_size(&g, LEVEL);
        for (size_t k0 = 0; k0 < n; k0 += ISM_GRAD_BATCH) {
            size_t nb = n - k0 < ISM_GRAD_BATCH ? n - k0 : ISM_GRAD_BATCH;
            double sz[ISM_GRAD_BATCH], m[ISM_GRAD_BATCH][3], p[ISM_GRAD_BATCH][3];
            double from[ISM_GRAD_BATCH][3], one[3];
            uint8_t st[ISM_GRAD_BATCH];
            for (size_t j = 0; j < nb; j++)
                sz[j] = size;
            ism_dual_feet_in_nodes(&w, (const double (*)[3])lo + k0,
                                   (const double (*)[3])hi + k0, sz, nb, m, st);
            size_t nout = 0;
            for (size_t j = 0; j < nb; j++) {
                bool in = ism_dual_foot_in_node(&w, lo[k0 + j], hi[k0 + j], size, one);
                cr_assert_eq(st[j] == FOOT_AT, in, "placement %d box %zu: verdict", i, k0 + j);
                cr_assert(same3(m[j], one), "placement %d box %zu: the foot in lanes (%.17g "
                          "%.17g %.17g) is not the one-box foot (%.17g %.17g %.17g)",
                          i, k0 + j, m[j][0], m[j][1], m[j][2], one[0], one[1], one[2]);
                if (st[j] == FOOT_AT)
                    continue;
                /* a start point off the centre, inside the leaf (as the secant roots' mean
                   is), each coordinate the centre of its own one-point box */
                const double *l = lo[k0 + j], *u = hi[k0 + j];
                for (int a = 0; a < 3; a++)
                    p[nout][a] = l[a] + (0.25 + 0.125 * a) * (u[a] - l[a]);
                memcpy(from[nout], p[nout], sizeof p[nout]);
                nout++;
            }
            out += nout;
            if (nout) {
                double q[ISM_GRAD_BATCH][3];
                bool ok[ISM_GRAD_BATCH];
                memcpy(q, p, nout * sizeof *q);
                ism_dual_newton_lanes(&w, q, sz, nout, ok);
                for (size_t j = 0; j < nout; j++) {
                    memcpy(one, from[j], sizeof one);
                    bool fine = ism_dual_newton_onto(&w, one, size);
                    cr_assert_eq(ok[j], fine, "placement %d: Newton's verdict", i);
                    cr_assert(same3(q[j], one), "placement %d: Newton in lanes from (%.17g "
                              "%.17g %.17g) is not ism_dual_newton_onto's", i, from[j][0],
                              from[j][1], from[j][2]);
                }
            }
            /* the straddle move at the feet, f's jets in one batch */
            double f[ISM_GRAD_BATCH], gr[ISM_GRAD_BATCH][3], h[ISM_GRAD_BATCH][6];
            ism_eval_hessian_batch(t, w.s.ws, (const double (*)[3])m, f, gr, h, nb);
            for (size_t j = 0; j < nb; j++) {
                ism_straddle_jet jet = {f[j], {gr[j][0], gr[j][1], gr[j][2]},
                                        {h[j][0], h[j][1], h[j][2], h[j][3], h[j][4], h[j][5]}};
                double qa[3], qb[3];
                bool a = ism_straddle_balanced_point_at(&w.s, 0.9 * E, box, m[j], &jet, qa, NULL);
                bool b = ism_straddle_balanced_point(&w.s, 0.9 * E, box, m[j], qb, NULL);
                cr_assert_eq(a, b, "placement %d box %zu: moved", i, k0 + j);
                cr_assert(same3(qa, qb), "placement %d box %zu: the move with the batch's jet "
                          "differs", i, k0 + j);
                moved += a;
            }
        }
        /* both branches must be exercised: leaves whose foot left them, and moves made */
        cr_expect_gt(out, 0, "placement %d: %zu of %zu feet left their leaf", i, out, n);
        cr_expect_gt(moved, n / 2, "placement %d: %zu moves in %zu", i, moved, n);
        ism_eval_ws_free(w.s.ws);
    }
    free(lo);
    free(hi);
    ism_tape_free(t);
}

/* Equal to the bit, NaN counting equal to NaN (a lane Newton failed in). */
static bool same_or_nan3(const double a[3], const double b[3])
{
    for (int k = 0; k < 3; k++)
        if (isnan(a[k]) != isnan(b[k]) || (!isnan(a[k]) && memcmp(&a[k], &b[k], sizeof *a)))
            return false;
    return true;
}

/* A vertex from m (within size of f = 0) alone: Newton onto f = 0 (NaN when it cannot finish),
 * then, shift > 0, the balanced straddle move, the jet taken at the point itself. */
static void one_vertex(worker *w, double shift, const double box[6], double m[3], double size,
                       double out[3])
{
    double q[3];
    if (!ism_dual_newton_onto(w, m, size)) {
        out[0] = out[1] = out[2] = NAN;
        return;
    }
    if (shift > 0 && ism_straddle_balanced_point(&w->s, shift, box, m, q, NULL))
        memcpy(m, q, sizeof q);
    memcpy(out, m, sizeof q);
}

/* ism_dual_vertices_onto (fan_task's centres, all lanes at once) against one_vertex from
 * each start point alone, with the straddle move (shift 0.9 E, as a --quality setting
 * gives d->shift) and without (shift 0): every lane its own size (fans' diagonals differ;
 * the level-5 cell's side times 0.5 .. 1.375 by lane), and in every chunk one lane at the
 * torus's centre, where the quartic's ∇f vanishes (∂f/∂x = 4x(|p|² + R² - r²) - 8R²x, and
 * the same for y; ∂f/∂z = 4z(...)), so Newton fails there: NaN in that lane, the others
 * placed as their own runs place them. */
Test(dual_lanes, fan_centres_bit_for_bit_the_one_point_vertex)
{
    enum { CAP = 8192 };
    ism_tape *t = pf_compile(&pf_ring_torus);
    double (*lo)[3] = malloc(CAP * sizeof *lo), (*hi)[3] = malloc(CAP * sizeof *hi);
    cr_assert(t && lo && hi);
    for (int i = pf_first_box(); i < 3; i++) {
        double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
        ism_poly_options o;
        memset(&o, 0, sizeof o);
        pf_sweep_box(base, DEPTH, i - 1, o.box);
        ism_grid g;
        ism_grid_init(&g, o.box, DEPTH);
        worker w;
        memset(&w, 0, sizeof w);
        w.s.tape = t;
        w.s.ws = ism_eval_ws_new(t);
        w.s.batch = true;
        cr_assert(w.s.ws);
        size_t n = tube_boxes(&g, lo, hi, CAP);
        cr_assert(n > 0 && n < CAP, "placement %d: %zu boxes", i, n);
        double cell = ism_grid_cell_size(&g, LEVEL);
        for (int s = 0; s < 2; s++) {
            dual d;
            memset(&d, 0, sizeof d);
            d.o = &o;
            d.shift = s ? 0.9 * E : 0;
            size_t failed = 0, moved = 0;
            for (size_t k0 = 0; k0 < n; k0 += MEASURE_LANES) {
                size_t nb = n - k0 < MEASURE_LANES ? n - k0 : MEASURE_LANES;
                size_t bad = (k0 / MEASURE_LANES) % nb; /* the lane at the centre */
                double m[MEASURE_LANES][3], from[MEASURE_LANES][3], sz[MEASURE_LANES];
                double out[MEASURE_LANES][3];
                for (size_t j = 0; j < nb; j++) {
                    for (int a = 0; a < 3; a++)
                        m[j][a] = j == bad ? 0 : 0.5 * lo[k0 + j][a] + 0.5 * hi[k0 + j][a];
                    sz[j] = cell * (0.5 + 0.125 * (double)j);
                }
                memcpy(from, m, sizeof from);
                ism_dual_vertices_onto(&d, &w, m, sz, nb, out);
                for (size_t j = 0; j < nb; j++) {
                    double one[3], p[3];
                    memcpy(p, from[j], sizeof p);
                    one_vertex(&w, d.shift, o.box, p, sz[j], one);
                    cr_assert(same_or_nan3(out[j], one), "placement %d shift %g lane %zu of "
                              "%zu from (%.17g %.17g %.17g): in lanes (%.17g %.17g %.17g), "
                              "alone (%.17g %.17g %.17g)", i, d.shift, j, nb, from[j][0],
                              from[j][1], from[j][2], out[j][0], out[j][1], out[j][2], one[0],
                              one[1], one[2]);
                    cr_assert_eq(isnan(out[j][0]), j == bad, "placement %d lane %zu: NaN only "
                                 "at the centre", i, j);
                    failed += isnan(out[j][0]);
                    /* did the straddle move take this vertex off Newton's foot? */
                    memcpy(p, from[j], sizeof p);
                    moved += s && ism_dual_newton_onto(&w, p, sz[j]) && !same3(p, out[j]);
                }
            }
            /* both branches exercised: lanes Newton failed in, and (with the shift) moves */
            cr_expect_eq(failed, (n + MEASURE_LANES - 1) / MEASURE_LANES,
                         "placement %d: %zu failed lanes", i, failed);
            if (s)
                cr_expect_gt(moved, n / 2, "placement %d: %zu moves in %zu", i, moved, n);
        }
        ism_eval_ws_free(w.s.ws);
    }
    free(lo);
    free(hi);
    ism_tape_free(t);
}
