/* test_resolvable.c — the coarse pass that refuses hopeless work (core/octree/resolvable.h):
 * functions that are hopeless by construction (0 on a volume; a term sin(huge x) whose period
 * is far below any cell) are refused, whatever their other terms; every preset, and surfaces
 * that are merely expensive (fine detail, a cone's apex, a long tape), pass — in their own box
 * and in boxes shifted off the octree lattice. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/octree/resolvable.h"
#include "proto/presets.h"
#include "tests/unit/placements.h"

/* Finest cells of a depth-10 request (2^-10 of the box): the shifts below are fractions of it. */
#define FINE_CELL_LOG2 10

static ism_resolvable check_in(const char *src, const ism_param *params, size_t np,
                               const ism_let *lets, size_t nl, const double box[6],
                               double shift)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, params, np, lets, nl, NULL, &err);
    cr_assert(t, "%s: %s", src, err.message);
    double b[6];
    for (int a = 0; a < 6; a++)
        b[a] = box[a] + shift * ldexp(box[a % 3 + 3] - box[a % 3], -FINE_CELL_LOG2);
    char why[400] = "";
    ism_resolvable v = ism_resolvable_check(t, b, why, sizeof why);
    cr_assert(v == ISM_RESOLVABLE_OK || why[0], "a refusal says why");
    ism_tape_free(t);
    return v;
}

static const double UNIT_BOX[6] = {-1, -1, -1, 1, 1, 1};
static const double SHIFTS[] = {0, 1e-3, PF_IRR}; /* of a finest cell (placements.h) */

static ism_resolvable check(const char *src, double shift)
{
    return check_in(src, NULL, 0, NULL, 0, UNIT_BOX, shift);
}

Test(resolvable, sin_of_a_huge_argument_is_refused_whatever_else_f_holds)
{
    const char *hopeless[] = {"sin(1e300*x) + 3*y", "sin(1e300*x) + 100*y",
                              "sin(1e300*x) + 0.5*y", "cos(1e12*(x+y)) + x^2 + y^2 + z^2 - 0.5",
                              "sin(1e300*x)*sin(1e300*y) + 0.1*z"};
    for (size_t i = 0; i < sizeof hopeless / sizeof *hopeless; i++)
        for (size_t s = 0; s < sizeof SHIFTS / sizeof *SHIFTS; s++)
            cr_expect_eq(check(hopeless[i], SHIFTS[s]), ISM_RESOLVABLE_TOO_FINE, "%s shift %g",
                         hopeless[i], SHIFTS[s]);
}

Test(resolvable, zero_on_a_volume_is_refused)
{
    const char *zero[] = {"0", "x - x", "min(x, 0)", "0*sin(x)"};
    for (size_t i = 0; i < sizeof zero / sizeof *zero; i++)
        for (size_t s = 0; s < sizeof SHIFTS / sizeof *SHIFTS; s++)
            cr_expect_eq(check(zero[i], SHIFTS[s]), ISM_RESOLVABLE_ZERO_VOLUME, "%s shift %g",
                         zero[i], SHIFTS[s]);
}

Test(resolvable, expensive_but_resolvable_surfaces_pass)
{
    const char *fine[] = {
        "sin(1000*x) + 3*y",                 /* period 6e-3: resolvable below depth 10 */
        "sqrt(x^2 + y^2) - z",               /* a cone: its apex is not smooth */
        "1 - x^2 - y^2 - z^2",               /* no sign change needed at the probes */
        "abs(x) + abs(y) + abs(z) - 0.5",    /* kinks on the box's symmetry planes */
        "sin(1e300*x) + 1e6*y",              /* noise, but in a slab thinner than a cell */
        "2",                                 /* constant, not 0: no surface, cheap */
        "1/x - 2",
    };
    for (size_t i = 0; i < sizeof fine / sizeof *fine; i++)
        for (size_t s = 0; s < sizeof SHIFTS / sizeof *SHIFTS; s++)
            cr_expect_eq(check(fine[i], SHIFTS[s]), ISM_RESOLVABLE_OK, "%s shift %g", fine[i],
                         SHIFTS[s]);
}

Test(resolvable, every_preset_passes)
{
    for (size_t i = 0; i < ism_preset_count(); i++) {
        const ism_preset *p = ism_preset_at(i);
        ism_param params[64];
        cr_assert(p->nparams <= 64);
        for (size_t j = 0; j < p->nparams; j++) {
            params[j].name = p->params[j].name;
            params[j].value = p->params[j].value;
        }
        for (size_t s = 0; s < sizeof SHIFTS / sizeof *SHIFTS; s++)
            cr_expect_eq(check_in(p->expr, params, p->nparams, p->lets, p->nlets, p->box,
                                  SHIFTS[s]),
                         ISM_RESOLVABLE_OK, "%s shift %g", p->name, SHIFTS[s]);
    }
}
