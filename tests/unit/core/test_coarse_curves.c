/* test_coarse_curves.c — the singular locus of surfaces with double curves and whiskers at
 * coarse depths (3 and 4), found from f (ism_locus_find), in the preset's box as given and
 * shifted off the octree lattice as tests/bench/sweep_singular.py shifts it (1e-3, irrational
 * fractions of a finest cell). Before, at depth 3 the boxes along the curves projected onto their
 * end points only (rank ≤ 1), no curve had a seed: the cross-cap reported nothing at all in the
 * box as given and shifted 1e-3, Steiner's surface 5 or 3 of its 6 pinch points, and at depth 4
 * the cross-cap's whisker below z = −1 was missing in every box.
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
 *    whiskers, 6 pinch points (±1/2 on each axis), 1 triple point.
 *  - nine planes sin πx sin πy sin πz = 0 (x, y, z ∈ Z) in a box holding n_a integers
 *    strictly inside on axis a: every integer point is a triple point (three planes cross;
 *    the Hessian vanishes there), n_x n_y n_z of them; the lines where two planes cross are
 *    cut by the third family into n_a + 1 double curves along axis a, each between two
 *    consecutive stops of lo face, integers, hi face. In ±1.9: 27 triple points, 108 curves.
 *    Before, at depth 3 the curve stage probed only the first 32 distinct rank-0 projections,
 *    24 of which are triple points just outside the box (±2): 84 curves, the last 7 triple
 *    points typed degenerate (20 and 84 in the 1e-3 box too); at depth 4 42 curves. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
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

/* The locus of expr in base placed by which (pf_sweep_box) at depth d, one thread; *o gets
 * the options (o->box the placed box). */
static ism_tape *find_placed(const char *expr, const double base[6], int d, int which,
                             ism_locus_options *o, ism_locus *l)
{
    ism_tape *t = pf_compile(&(pf_surface){expr, NULL, 0, NULL, 0});
    ism_locus_options_default(o);
    pf_sweep_box(base, d, which, o->box);
    o->max_depth = d;
    o->threads = 1;
    ism_locus_init(l);
    ism_error err;
    cr_assert(ism_locus_find(t, o, l, &err), "%s: %s", expr, err.message);
    return t;
}

static void check_case(const locus_case *c, int d, int which)
{
    const char *place = which < 0 ? "own" : which == 0 ? "1e-3" : "irr cell";
    const double base[6] = {-c->half, -c->half, -c->half, c->half, c->half, c->half};
    ism_locus_options o;
    ism_locus l;
    ism_tape *t = find_placed(c->expr, base, d, which, &o, &l);
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

/* The integers strictly inside (lo, hi): the first in *first, their count returned. */
static int integers_inside(double lo, double hi, int *first)
{
    *first = (int)floor(lo) + 1;
    return (int)ceil(hi) - *first;
}

/* Whether v is within tol of an integer. */
static bool near_integer(double v, double tol)
{
    return fabs(v - round(v)) <= tol;
}

/* Which double curve of the nine planes in box c is (its axis a, its line's two integer
 * coordinates, the stop it starts from: 0 the lo face, 1 + m - first[a] the integer m), as
 * one index into a table of all of them; -1 when its ends are no two consecutive stops of one
 * line or are mistyped. */
static long grid_segment(const ism_locus *l, const ism_sing_curve *cu, const double box[6],
                         const int first[3], const int n[3], double tol)
{
    const double *e[2] = {cu->xyz, cu->xyz + 3 * (cu->n - 1)};
    int a = -1;
    for (int k = 0; k < 3; k++)
        if (fabs(e[0][k] - e[1][k]) > tol)
            a = a < 0 ? k : 3;
    if (cu->closed || a < 0 || a > 2)
        return -1;
    int b = (a + 1) % 3, c = (a + 2) % 3, stop[2];
    for (int s = 0; s < 2; s++) {
        if (!near_integer(e[s][b], tol) || !near_integer(e[s][c], tol))
            return -1;
        double v = e[s][a];
        bool face = fabs(v - box[a]) <= tol || fabs(v - box[a + 3]) <= tol;
        if (face && cu->end_type[s] == ISM_END_BOX)
            stop[s] = fabs(v - box[a]) <= tol ? 0 : n[a] + 1;
        else if (near_integer(v, tol) && cu->end_type[s] == ISM_END_TRIPLE &&
                 cu->end_point[s] >= 0 && ism_dist3(l->points[cu->end_point[s]].p, e[s]) <= tol)
            stop[s] = 1 + (int)round(v) - first[a];
        else
            return -1;
    }
    int lo = stop[0] < stop[1] ? stop[0] : stop[1];
    if (abs(stop[0] - stop[1]) != 1)
        return -1;
    long jb = lround(e[0][b]) - first[b], jc = lround(e[0][c]) - first[c];
    return ((a * 64L + jb) * 64L + jc) * 64L + lo;
}

static void check_nine_planes(const double base[6], int d, int which)
{
    const char *place = which < 0 ? "own" : which == 0 ? "1e-3" : "irr cell";
    ism_locus_options o;
    ism_locus l;
    ism_tape *t = find_placed("sin(pi*x)*sin(pi*y)*sin(pi*z)", base, d, which, &o, &l);
    int first[3], n[3];
    for (int a = 0; a < 3; a++)
        n[a] = integers_inside(o.box[a], o.box[a + 3], &first[a]);
    size_t want_points = (size_t)n[0] * n[1] * n[2], want_curves = 0;
    for (int a = 0; a < 3; a++)
        want_curves += (size_t)n[(a + 1) % 3] * n[(a + 2) % 3] * (n[a] + 1);
    double tol = 1e-9 * ism_dist3(o.box, o.box + 3);
    size_t triples = 0;
    for (size_t j = 0; j < l.npoints; j++) {
        const ism_sing_point *p = &l.points[j];
        triples += p->certified && p->type == ISM_SING_TRIPLE && near_integer(p->p[0], tol) &&
                   near_integer(p->p[1], tol) && near_integer(p->p[2], tol);
    }
    cr_expect(l.npoints == want_points && triples == want_points,
              "nine planes d%d %s: %zu points, %zu of them certified triple points at integer "
              "points; want %zu", d, place, l.npoints, triples, want_points);
    size_t nkeys = 3 * 64 * 64 * 64, bad = 0, twice = 0, found = 0;
    unsigned char *seen = calloc(nkeys, 1);
    cr_assert(seen);
    for (size_t i = 0; i < l.ncurves; i++) {
        long k = l.curves[i].kind == ISM_CURVE_DOUBLE
                     ? grid_segment(&l, &l.curves[i], o.box, first, n, tol) : -1;
        if (k < 0 || k >= (long)nkeys) {
            bad++;
            continue;
        }
        twice += seen[k];
        found += !seen[k];
        seen[k] = 1;
    }
    cr_expect(l.ncurves == want_curves && found == want_curves && bad == 0 && twice == 0,
              "nine planes d%d %s: %zu curves, %zu distinct segments between consecutive stops "
              "(%zu not such a segment or mistyped, %zu repeated); want %zu", d, place,
              l.ncurves, found, bad, twice, want_curves);
    cr_expect(!l.incomplete, "nine planes d%d %s: incomplete (%s)", d, place, l.incomplete_why);
    free(seen);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* ±1.9 holds x, y, z ∈ {−1, 0, 1}; the search's boxes at the faces project onto the triple
 * points at ±2, 0.1 outside. */
Test(coarse_curves, nine_planes_every_triple_point_at_depths_3_and_4)
{
    const double base[6] = {-1.9, -1.9, -1.9, 1.9, 1.9, 1.9};
    for (int d = 3; d <= 4; d++)
        for (int which = pf_first_box() - 1; which <= 1; which++)
            check_nine_planes(base, d, which);
}
