/* test_coarse_curves.c — the singular locus of surfaces with double curves and whiskers at
 * coarse depths (3 and 4), found from f (ism_locus_find), in the preset's box as given and
 * shifted off the octree lattice as tests/bench/sweep_singular.py shifts it (1e-3, 0.37 of a
 * finest cell). Before, at depth 3 the boxes along the curves projected onto their end
 * points only (rank ≤ 1), no curve had a seed: the cross-cap reported nothing at all in the
 * box as given and shifted 1e-3, Steiner's surface 5 or 3 of its 6 pinch points, and at
 * depth 4 the cross-cap's whisker below z = −1 was missing in every box.
 *
 * What is asserted comes from the closed forms, not from the code:
 *  - cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1): f and ∇f vanish on the z axis, where
 *    the Hessian across is diag(8(z² + z), 2(z² − 1)): indefinite (two sheets cross: a
 *    double curve) for 0 < z < 1, definite (a whisker) for −1 < z < 0 and |z| > 1; rank 1 at
 *    z = 0 and z = 1 (pinch points), 0 at z = −1 (a degenerate point, where the whiskers
 *    z < −1 and −1 < z < 0 meet). In ±1.2 (shifted by at most 0.12): 1 double curve from
 *    (0, 0, 0) to (0, 0, 1), 3 whiskers, 2 pinch points, 1 degenerate point.
 *  - Steiner's Roman surface x²y² + y²z² + z²x² + xyz: on the x axis the Hessian across is
 *    [[2x², x], [x, 2x²]], determinant x²(4x² − 1): indefinite for |x| < 1/2 (double), definite
 *    beyond (whisker), rank 1 at x = ±1/2 (pinch), 0 at the origin, where the three axes
 *    meet (a triple point); the same on each axis. In ±1: 6 double curves (half-axes), 6
 *    whiskers, 6 pinch points (±1/2 on each axis), 1 triple point. */
#include <criterion/criterion.h>
#include <math.h>
#include "core/singular/find.h"
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"

typedef struct want_points {
    size_t n;
    double p[8][3];
    int type[8];
} want_points;

typedef struct locus_case {
    const char *name, *expr;
    double half;
    size_t doubles, whiskers;
    want_points pts;
} locus_case;

static const locus_case CASES[] = {
    {"cross-cap", "4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", 1.2, 1, 3,
     {3, {{0, 0, 0}, {0, 0, 1}, {0, 0, -1}},
      {ISM_SING_PINCH, ISM_SING_PINCH, ISM_SING_DEGENERATE}}},
    {"steiner-roman", "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", 1.0, 6, 6,
     {7, {{0.5, 0, 0}, {-0.5, 0, 0}, {0, 0.5, 0}, {0, -0.5, 0}, {0, 0, 0.5}, {0, 0, -0.5},
          {0, 0, 0}},
      {ISM_SING_PINCH, ISM_SING_PINCH, ISM_SING_PINCH, ISM_SING_PINCH, ISM_SING_PINCH,
       ISM_SING_PINCH, ISM_SING_TRIPLE}}},
};

static void check_case(const locus_case *c, int d, int which)
{
    const char *place = which < 0 ? "own" : which == 0 ? "1e-3" : "0.37 cell";
    const double base[6] = {-c->half, -c->half, -c->half, c->half, c->half, c->half};
    ism_tape *t = pf_compile(&(pf_surface){c->expr, NULL, 0, NULL, 0});
    ism_locus_options o;
    ism_locus_options_default(&o);
    pf_sweep_box(base, d, which, o.box);
    o.max_depth = d;
    o.threads = 1;
    ism_locus l;
    ism_locus_init(&l);
    ism_error err;
    cr_assert(ism_locus_find(t, &o, &l, &err), "%s: %s", c->name, err.message);
    size_t kinds[ISM_CURVE_KINDS] = {0};
    for (size_t i = 0; i < l.ncurves; i++)
        kinds[l.curves[i].kind]++;
    cr_expect(kinds[ISM_CURVE_DOUBLE] == c->doubles && kinds[ISM_CURVE_WHISKER] == c->whiskers,
              "%s d%d %s: %zu double curves and %zu whiskers, want %zu and %zu", c->name, d,
              place, kinds[ISM_CURVE_DOUBLE], kinds[ISM_CURVE_WHISKER], c->doubles,
              c->whiskers);
    cr_expect_eq(l.npoints, c->pts.n, "%s d%d %s: %zu points, want %zu", c->name, d, place,
                 l.npoints, c->pts.n);
    double diag = 2 * sqrt(3.0) * c->half;
    for (size_t i = 0; i < c->pts.n; i++) {
        size_t hits = 0;
        for (size_t j = 0; j < l.npoints; j++) {
            if (ism_dist3(l.points[j].p, c->pts.p[i]) > 1e-9 * diag)
                continue;
            hits++;
            cr_expect(l.points[j].certified && l.points[j].type == c->pts.type[i],
                      "%s d%d %s: (%g, %g, %g) is %s%s, want %s", c->name, d, place,
                      c->pts.p[i][0], c->pts.p[i][1], c->pts.p[i][2],
                      l.points[j].certified ? "" : "uncertified ",
                      ism_sing_type_name(l.points[j].type), ism_sing_type_name(c->pts.type[i]));
        }
        cr_expect_eq(hits, 1, "%s d%d %s: (%g, %g, %g) found %zu times", c->name, d, place,
                     c->pts.p[i][0], c->pts.p[i][1], c->pts.p[i][2], hits);
    }
    cr_expect(!l.incomplete, "%s d%d %s: incomplete (%s)", c->name, d, place, l.incomplete_why);
    ism_locus_free(&l);
    ism_tape_free(t);
}

Test(coarse_curves, cross_cap_and_steiner_at_depths_3_and_4)
{
    for (size_t i = 0; i < sizeof CASES / sizeof CASES[0]; i++)
        for (int d = 3; d <= 4; d++)
            for (int which = pf_first_box() - 1; which <= 1; which++)
                check_case(&CASES[i], d, which);
}
