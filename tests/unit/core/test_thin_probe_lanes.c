/* test_thin_probe_lanes.c — ism_thin_probe runs its Newton probes (the box's, then its
 * octants' where their interval leaves the other sign possible) side by side where f has a
 * min or max (one by one elsewhere), and must answer as probing them one by one in that
 * order does: the first to reach the other sign gives the point. The reference is
 * ism_thin_probe_one over the box and then each octant in index order (an octant whose
 * interval keeps the corners' sign cannot be hit: a probe stays in its box, so the reference
 * probes it too). Verdict and point compared bit for bit over lattice
 * cells in the three placements (pf_sweep_box) of small balls, as the min of their
 * functions (side by side), two as their product (smooth: one by one), and of Barth's
 * sextic in its ball (a max: side by side, many probes).
 * Not vacuous: probes hit, octants hit where the box's own probe missed, and in some boxes a
 * later octant's probe hits in fewer steps than the first one to hit in order (so an answer
 * taken from whichever lane hits first in time would differ). */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/octree/thin_search.h"
#include "tests/unit/core/poly_fixture.h"

typedef struct tally {
    int boxes, hits, octant_hits, out_of_order;
} tally;

/* The one-by-one answer for the box lo..hi: the index of the first probe to hit (0: the
 * box's, 1 + c: octant c's; -1: none) with its point; *later_sooner: some later probe hits
 * in fewer gradients than that first one. */
static int one_by_one(ism_sampler *s, const double lo[3], const double hi[3], int sign,
                      double found[3], bool *later_sooner)
{
    int first = -1;
    uint64_t first_cost = 0;
    *later_sooner = false;
    for (int i = 0; i < 9; i++) {
        double a[3], b[3], at[3];
        for (int k = 0; k < 3; k++) {
            double m = 0.5 * lo[k] + 0.5 * hi[k];
            bool up = i > 0 && ((i - 1) >> k) & 1;
            a[k] = i == 0 || !up ? lo[k] : m;
            b[k] = i == 0 || up ? hi[k] : m;
        }
        uint64_t before = s->n_gradient;
        bool hit = ism_thin_probe_one(s, a, b, sign, at);
        uint64_t cost = s->n_gradient - before;
        if (hit && first < 0) {
            first = i;
            first_cost = cost;
            memcpy(found, at, sizeof at);
        } else if (hit && cost < first_cost)
            *later_sooner = true;
    }
    return first;
}

/* Every cell of depth d of the box base placed by which (pf_sweep_box), the corners' sign
 * taken at its lower corner. */
static void compare_cells(ism_sampler *s, const double base[6], int d, int which, tally *t)
{
    double box[6];
    pf_sweep_box(base, d, which, box);
    int n = 1 << d;
    for (int c = 0; c < n * n * n; c++) {
        double lo[3], hi[3], g[3];
        for (int k = 0; k < 3; k++) {
            int i = (c >> (d * k)) & (n - 1);
            double step = (box[k + 3] - box[k]) / n;
            lo[k] = box[k] + step * i;
            hi[k] = i == n - 1 ? box[k + 3] : box[k] + step * (i + 1);
        }
        double f0 = ism_sample_grad(s, lo, g);
        int sign = f0 < 0 ? -1 : 1;
        double want[3] = { 0 }, got[3] = { 0 };
        bool later_sooner;
        int first = one_by_one(s, lo, hi, sign, want, &later_sooner);
        enum ism_thin_verdict v = ism_thin_probe(s, lo, hi, sign, got);
        t->boxes++;
        cr_assert_eq(v != ISM_THIN_UNDECIDED, first >= 0,
                     "placement %d cell %d: verdict %d, one by one %d", which, c, (int)v,
                     first);
        if (first < 0)
            continue;
        cr_assert(!memcmp(want, got, sizeof want),
                  "placement %d cell %d: found (%.17g %.17g %.17g), one by one probe %d "
                  "(%.17g %.17g %.17g)",
                  which, c, got[0], got[1], got[2], first, want[0], want[1], want[2]);
        t->hits++;
        t->octant_hits += first > 0;
        t->out_of_order += later_sooner;
    }
}

static void sweep(const pf_surface *surf, const double base[6], int d, const char *name)
{
    ism_sampler s;
    ism_tape *tape = pf_build_sampler(surf, &s);
    cr_assert_not_null(tape);
    tally t = { 0 };
    for (int which = pf_first_box() - 1; which < 2; which++)
        compare_cells(&s, base, d, which, &t);
    cr_log_info("%s: %d boxes, %d hits, %d by an octant, %d out of order", name, t.boxes,
                t.hits, t.octant_hits, t.out_of_order);
    cr_expect_gt(t.hits, 0, "%s: no probe hit", name);
    cr_expect_gt(t.octant_hits, 0, "%s: no octant hit where the box's probe missed", name);
    cr_expect_gt(t.out_of_order, 0, "%s: the first hit in time always the first in order",
                 name);
    ism_eval_ws_free(s.ws);
    ism_tape_free(tape);
}

Test(thin_probe_lanes, min_of_small_balls_as_one_by_one)
{
    pf_surface s = { "min(min(min((x - 0.3)^2 + (y + 0.2)^2 + (z - 0.1)^2 - 0.0025,"
                     " (x + 0.35)^2 + (y - 0.3)^2 + (z + 0.25)^2 - 0.0016),"
                     " min((x - 0.45)^2 + (y - 0.05)^2 + (z - 0.4)^2 - 0.0036,"
                     " (x + 0.05)^2 + (y + 0.45)^2 + (z - 0.55)^2 - 0.0025)),"
                     " min((x - 0.6)^2 + (y - 0.55)^2 + (z + 0.45)^2 - 0.0016,"
                     " (x + 0.55)^2 + (y + 0.6)^2 + (z + 0.05)^2 - 0.0036))",
                     NULL, 0, NULL, 0 };
    const double base[6] = { -1, -1, -1, 1, 1, 1 };
    sweep(&s, base, 2, "min of small balls");
}

Test(thin_probe_lanes, two_balls_as_one_by_one)
{
    pf_surface s = { "((x - 0.3)^2 + (y + 0.2)^2 + (z - 0.1)^2 - 0.04)"
                     " * ((x + 0.35)^2 + (y - 0.3)^2 + (z + 0.25)^2 - 0.0225)",
                     NULL, 0, NULL, 0 };
    const double base[6] = { -1, -1, -1, 1, 1, 1 };
    sweep(&s, base, 2, "two balls");
}

Test(thin_probe_lanes, barth_as_one_by_one)
{
    const double base[6] = { -1.6, -1.6, -1.6, 1.6, 1.6, 1.6 };
    sweep(&pf_barth_sextic, base, 3, "barth-sextic");
}
