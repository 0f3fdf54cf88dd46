/* test_turned.c — the two tests core/octree/turned.h asks of a leaf whose corners see a
 * feature about a cell across: the corner-gradient turn and the critical radius, against
 * closed forms. A tube y'² + z'² − r² and a ball |p − c|² − r² have f = −r² and Hessian
 * eigenvalues 2 (and 0 along the tube's axis) at their critical set, so the radius
 * √(2|f| / max|λ|) is r; two planes crossing, y·z, have f = 0 at theirs, radius 0. Every
 * case is placed in three cells: on the lattice, moved by 1e-3 and by irrational fractions. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>

#include "core/octree/octree_build.h"
#include "core/octree/turned.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/placements.h"

/* The corners of the cell [lo, lo + size]³ with f and ∇f of t there. */
static void cell_corners(const ism_tape *t, ism_eval_ws *ws, const double lo[3], double size,
                         ism_corners *k)
{
    for (int c = 0; c < 8; c++) {
        for (int a = 0; a < 3; a++)
            k->p[c][a] = lo[a] + ((c >> a) & 1) * size;
        k->f[c] = ism_eval_gradient(t, ws, k->p[c][0], k->p[c][1], k->p[c][2], k->g[c]);
    }
    k->memo = NULL;
}

/* The lower corner of a cell `size` wide: `at` moved by placement w (none, −1e-3, or
 * (−PF_IRR_X, PF_IRR_Y, −PF_IRR_Z) × size); each test's feature stays inside the cell. */
static void placed(const double at[3], double size, int w, double lo[3])
{
    const double irr[3] = {-PF_IRR_X, PF_IRR_Y, -PF_IRR_Z};
    for (int a = 0; a < 3; a++)
        lo[a] = at[a] + (w == 0 ? 0 : w == 1 ? -1e-3 : irr[a] * size);
}

static void check(const char *expr, const double at[3], double size, double want_cells,
                  bool turned, const char *name)
{
    pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    for (int w = 0; w < 3; w++) {
        double lo[3];
        placed(at, size, w, lo);
        ism_corners k;
        cell_corners(t, ws, lo, size, &k);
        cr_expect_eq(ism_corners_turned(k.g, ISM_TURNED_COS), turned, "%s, placement %d: turned",
                     name, w);
        double rho = ism_critical_radius(t, ws, &k, size, ISM_TURNED_NEWTON_STEPS,
                                         ISM_TURNED_PINV_REL, ISM_TURNED_NEWTON_REACH);
        cr_expect_leq(fabs(rho - want_cells), 1e-9 * fmax(want_cells, 1),
                      "%s, placement %d: radius %.17g cells, want %.17g", name, w, rho,
                      want_cells);
    }
    ism_eval_ws_free(ws);
    ism_tape_free(t);
}

/* The tube r = 0.004 of issue 13 about the axis y = z = 0.0078125 in cells 0.015625 wide
 * (depth 7 of ±1): 0.256 cell, with the axis inside the cell (its corners on both sides). */
Test(turned, a_thin_tube_gives_its_radius)
{
    const double h = 2.0 / 128, at[3] = {0.3, 0.0078125 - 0.4 * h, 0.0078125 - 0.45 * h};
    check("(y - 0.0078125)^2 + (z - 0.0078125)^2 - 0.004^2", at, h, 0.004 / h, true, "tube");
}

/* A ball of radius 0.3 cell with its centre inside the cell. */
Test(turned, a_small_ball_gives_its_radius)
{
    const double h = 2.0 / 128, c[3] = {0.21, -0.33, 0.47};
    const double at[3] = {c[0] - 0.4 * h, c[1] - 0.35 * h, c[2] - 0.45 * h};
    char expr[160];
    snprintf(expr, sizeof expr, "(x - %.17g)^2 + (y - %.17g)^2 + (z - %.17g)^2 - %.17g^2", c[0],
             c[1], c[2], 0.3 * h);
    check(expr, at, h, 0.3, true, "ball");
}

/* Two planes crossing along x: f = 0 on the critical line, radius 0 (a crossing, not a
 * feature); the corners on four sides of the line turn by 180°. */
Test(turned, a_crossing_of_two_sheets_has_no_radius)
{
    const double h = 2.0 / 128, at[3] = {0.1, -0.4 * h, -0.45 * h};
    check("y * z", at, h, 0, true, "crossing");
}

/* A smooth sphere of radius 0.5, a cell of depth 7 on it: gradients within a few degrees,
 * not turned (the critical point, the centre, is 32 cells away: radius 0). */
Test(turned, a_resolved_sphere_is_not_turned)
{
    const double h = 2.0 / 128, at[3] = {0.5 - 0.5 * h, -0.5 * h, -0.5 * h};
    check("x^2 + y^2 + z^2 - 0.25", at, h, 0, false, "sphere");
}

/* A corner on a critical point (the tube's axis on a lattice line) counts as turned; a
 * gradient that is not finite never does. */
Test(turned, a_zero_gradient_turns_and_a_nan_does_not)
{
    double g[8][3];
    for (int c = 0; c < 8; c++)
        g[c][0] = 1, g[c][1] = 0.01 * c, g[c][2] = 0;
    cr_expect_not(ism_corners_turned(g, ISM_TURNED_COS));
    g[5][0] = g[5][1] = 0;
    cr_expect(ism_corners_turned(g, ISM_TURNED_COS));
    g[3][2] = NAN;
    cr_expect_not(ism_corners_turned(g, ISM_TURNED_COS));
    /* 119° apart is not turned, 121° is */
    double a = 119 * M_PI / 180, b = 121 * M_PI / 180;
    for (int c = 0; c < 8; c++)
        g[c][0] = 1, g[c][1] = g[c][2] = 0;
    g[7][0] = cos(a), g[7][1] = sin(a);
    cr_expect_not(ism_corners_turned(g, ISM_TURNED_COS));
    g[7][0] = cos(b), g[7][1] = sin(b);
    cr_expect(ism_corners_turned(g, ISM_TURNED_COS));
}
