/* test_placements.c — the table of box placements (tests/unit/placements.h) holds what its
 * comment promises: the irrational fractions are their closed forms (√2 − 1, −(√5 − 1)/4, 1/e)
 * to the last bits of a double, and their magnitudes keep the box off the lattice of its own
 * depth and the next two (at least 1/20 of a cell from every multiple of ¼); pf_sweep_box moves
 * a box by exactly those fractions of its own finest cell, per axis. */
#include <criterion/criterion.h>
#include <math.h>

#include "tests/unit/core/poly_fixture.h"

Test(placements, irrational_fractions_are_their_closed_forms)
{
    const double irr[3] = {PF_IRR_X, PF_IRR_Y, PF_IRR_Z};
    const double closed[3] = {sqrt(2.0) - 1, -(sqrt(5.0) - 1) / 4, 1 / exp(1.0)};
    for (int k = 0; k < 3; k++) {
        cr_expect_leq(fabs(irr[k] - closed[k]), 4e-16, "axis %d: %.17g vs %.17g", k, irr[k],
                      closed[k]);
        double a = fabs(irr[k]), quarter = fabs(a - 0.25 * round(4 * a));
        cr_expect(a > 0.25 && a < 0.45, "axis %d: |%g| not between ¼ and 0.45 of a cell", k, a);
        cr_expect_geq(quarter, 0.05, "axis %d: %g of a cell from a multiple of ¼", k, quarter);
    }
    cr_expect_eq(PF_IRR, PF_IRR_X);
}

Test(placements, sweep_box_moves_by_the_table)
{
    const double base[6] = {-1, -2, -0.5, 3, 2, 1.5};
    const double off[3] = {PF_OFF_X, PF_OFF_Y, PF_OFF_Z}, irr[3] = {PF_IRR_X, PF_IRR_Y, PF_IRR_Z};
    const int d = 6;
    for (int which = -1; which <= 1; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        for (int k = 0; k < 3; k++) {
            double cell = (base[k + 3] - base[k]) / 64, want = which < 0 ? 0
                                                              : which == 0 ? off[k]
                                                                           : irr[k] * cell;
            cr_expect_leq(fabs(box[k] - base[k] - want), 1e-15, "which %d axis %d", which, k);
            cr_expect_leq(fabs(box[k + 3] - base[k + 3] - want), 1e-15, "which %d axis %d",
                          which, k);
        }
    }
}
