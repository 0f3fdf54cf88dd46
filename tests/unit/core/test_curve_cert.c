/* test_curve_cert.c — the singular curves' certificates (core/singular/curve_cert.h): every
 * curve of Steiner's surface (6 double segments, 6 whiskers), the Klein bottle's double
 * circle, the Whitney umbrella's double line and handle and the whisker circle
 * (x² + y² − 1/4)² + z² is certified, in the box's own placement and moved by 1e-3 and by an
 * irrational fraction of a cell (tests/unit/placements.h); a point moved off the locus by
 * 1e-6 × diagonal across the curve is not, one moved along it still is. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>

#include "core/singular/curve_cert.h"
#include "core/singular/find.h"
#include "core/singular/point_cert.h"
#include "tests/unit/placements.h"

/* The locus search's depth: what the mesher uses by default (locus.h). */
#define DEPTH ISM_LOCUS_DEFAULT_DEPTH

typedef struct run {
    ism_tape *t;
    ism_locus l;
    double diag;
} run;

/* The locus of expr in the cube ±half moved by placement 0 (own), 1 (1e-3), 2 (irrational). */
static void find(run *r, const char *expr, double half, int placement)
{
    ism_error err;
    r->t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(r->t, "%s: %s", expr, err.message);
    ism_locus_options o;
    ism_locus_options_default(&o);
    o.max_depth = DEPTH;
    o.threads = 1;
    double cell = 2.0 * half / (double)(1 << DEPTH);
    const double off[3][3] = { { 0, 0, 0 },
                               { PF_OFF_X, PF_OFF_Y, PF_OFF_Z },
                               { PF_IRR_X * cell, PF_IRR_Y * cell, PF_IRR_Z * cell } };
    for (int k = 0; k < 3; k++) {
        o.box[k] = -half + off[placement][k];
        o.box[k + 3] = half + off[placement][k];
    }
    r->diag = 2.0 * half * sqrt(3.0);
    ism_locus_init(&r->l);
    cr_assert(ism_locus_find(r->t, &o, &r->l, &err), "%s: %s", expr, err.message);
    cr_assert(!r->l.incomplete, "%s: %s", expr, r->l.incomplete_why);
}

static void done(run *r)
{
    ism_locus_free(&r->l);
    ism_tape_free(r->t);
}

/* Every curve certified, its boxes within the bound; counts by kind as expected (-1: any ≥ 1). */
static void assert_all_certified(const char *name, const char *expr, double half, int doubles,
                                 int whiskers, int closed)
{
    for (int pl = 0; pl < 3; pl++) {
        run r;
        find(&r, expr, half, pl);
        int kinds[ISM_CURVE_KINDS] = { 0 }, loops = 0;
        for (size_t c = 0; c < r.l.ncurves; c++) {
            const ism_sing_curve *cv = &r.l.curves[c];
            kinds[cv->kind]++;
            loops += cv->closed;
            cr_expect(cv->certified,
                      "%s placement %d curve %zu (%s, %zu points): %zu uncertified, first %ld "
                      "|f| %g |grad f| %g", name, pl, c, ism_curve_kind_name(cv->kind), cv->n,
                      cv->uncertified_points, cv->first_uncertified, cv->first_residual_f,
                      cv->first_residual_grad);
            cr_expect_eq(cv->uncertified_points, 0);
            cr_expect(cv->cert_radius > 0.0 && cv->cert_radius <= ISM_SING_CERT_REL * r.diag,
                      "%s: radius %g", name, cv->cert_radius);
        }
        cr_expect_eq(kinds[ISM_CURVE_DOUBLE], doubles, "%s placement %d: %d double curves",
                     name, pl, kinds[ISM_CURVE_DOUBLE]);
        cr_expect_eq(kinds[ISM_CURVE_WHISKER], whiskers, "%s placement %d: %d whiskers", name,
                     pl, kinds[ISM_CURVE_WHISKER]);
        cr_expect_eq(loops, closed, "%s placement %d: %d closed", name, pl, loops);
        done(&r);
    }
}

/* The axes: from the triple point at 0 to the pinch points at ±1/2 a double segment, beyond
 * them to the box a whisker, on each of the three axes. */
Test(curve_cert, steiner_double_segments_and_whiskers)
{
    assert_all_certified("steiner", "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", 1.0, 6, 6, 0);
}

/* The figure-8 Klein bottle's double circle x² + y² = 1 in z = 0 (the preset's box). */
Test(curve_cert, klein_bottle_double_circle)
{
    assert_all_certified("klein",
                         "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
                         "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)", 4.0, 1, 0, 1);
}

/* x² = y²z: the z axis, double above the pinch point at 0, a whisker (the handle) below. */
Test(curve_cert, whitney_double_line_and_handle)
{
    assert_all_certified("whitney", "x^2 - y^2*z", 1.0, 1, 1, 0);
}

/* (x² + y² − 1/4)² + z²: f ≥ 0, zero only on the circle of radius 1/2 in z = 0. */
Test(curve_cert, whisker_circle)
{
    assert_all_certified("whisker circle", "(x^2 + y^2 - 0.25)^2 + z^2", 1.0, 0, 1, 1);
}

/* expr's tape and a workspace of its interval jets, for the certifier called directly (the
 * cube ±1: diagonal 2√3). */
static ism_tape *certifier(const char *expr, ism_ivjet_ws **jw)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(expr, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", expr, err.message);
    *jw = ism_ivjet_ws_new(t);
    cr_assert_not_null(*jw);
    return t;
}

/* The certifier itself on the Whitney double line (the z axis, x² − y²z: ∇f = (2x, −2yz,
 * −y²), Hessian across diag(2, −2z)): a point of it passes, one moved along it (still on the
 * locus) passes, one moved off it across by 1e-6 × diagonal (in x, in y, or both) does not —
 * ∇f there is 2e-6 × diag ≠ 0 and the square of half-width ≤ 0.5e-9 × diag holds no zero. */
Test(curve_cert, a_point_off_the_locus_is_not_certified)
{
    ism_ivjet_ws *jw;
    ism_tape *t = certifier("x^2 - y^2*z", &jw);
    double diag = 2.0 * sqrt(3.0), rmax = ISM_SING_CERT_REL * diag, d = 1e-6 * diag;
    uint64_t evals = 0;
    const double on[][3] = { { 0, 0, 0.3 }, { 0, 0, 0.3 + d }, { 0, 0, -0.7 } };
    for (size_t i = 0; i < sizeof on / sizeof *on; i++) {
        ism_ccert c;
        cr_expect(ism_curve_cert_point(t, jw, on[i], rmax, &c, &evals), "on %zu", i);
        cr_expect(c.radius <= rmax && c.residual_grad == 0.0, "on %zu: %g %g", i, c.radius,
                  c.residual_grad);
    }
    const double s = d / sqrt(2.0);
    const double off[][3] = { { d, 0, 0.3 }, { 0, d, 0.3 }, { s, s, 0.3 }, { d, 0, -0.7 },
                              { 0, -d, -0.7 } };
    for (size_t i = 0; i < sizeof off / sizeof *off; i++) {
        ism_ccert c;
        cr_expect(!ism_curve_cert_point(t, jw, off[i], rmax, &c, &evals), "off %zu", i);
        cr_expect(c.residual_grad > 0.5e-6 * diag, "off %zu: |grad f| %g", i, c.residual_grad);
    }
    /* one jet at the point, one or two over squares */
    cr_expect(evals >= 2 * 8 && evals <= 3 * 8, "%llu evaluations", (unsigned long long)evals);
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
}

/* Two planes x = ±y crossing in the z axis (x² − y²): at (d, d, z), 1e-6 × diagonal off the
 * axis on the plane x = y, f = 0 and ∂f/∂z = 0 hold exactly, so the intervals of f and ∂f/∂t
 * contain 0 — only Krawczyk on the gradient across (2d, −2d) refutes the point. The axis
 * itself passes. */
Test(curve_cert, only_krawczyk_refutes_a_point_of_the_sheet_beside_the_curve)
{
    ism_ivjet_ws *jw;
    ism_tape *t = certifier("x^2 - y^2", &jw);
    double diag = 2.0 * sqrt(3.0), rmax = ISM_SING_CERT_REL * diag, d = 1e-6 * diag;
    uint64_t evals = 0;
    ism_ccert c;
    cr_expect(ism_curve_cert_point(t, jw, (double[3]){ 0, 0, 0.3 }, rmax, &c, &evals));
    cr_expect(!ism_curve_cert_point(t, jw, (double[3]){ d, d, 0.3 }, rmax, &c, &evals));
    cr_expect(c.residual_f == 0.0 && c.residual_grad > 2.0 * d, "%g %g", c.residual_f,
              c.residual_grad);
    ism_ivjet_ws_free(jw);
    ism_tape_free(t);
}

/* A traced curve moved bodily off its locus by 1e-6 × diagonal across it: the driver's
 * per-curve figures say so (every interior point fails; the first is point 0 or 1). */
Test(curve_cert, a_curve_moved_off_the_locus_is_not_certified)
{
    run r;
    find(&r, "x^2 - y^2*z", 1.0, 2);
    cr_assert_eq(r.l.ncurves, 2);
    ism_locus_options o;
    ism_locus_options_default(&o);
    for (int k = 0; k < 3; k++) {
        o.box[k] = -1.0;
        o.box[k + 3] = 1.0;
    }
    for (size_t c = 0; c < r.l.ncurves; c++) {
        ism_sing_curve *cv = &r.l.curves[c];
        cr_assert(cv->certified);
        for (size_t i = 0; i < cv->n; i++)
            cv->xyz[3 * i] += 1e-6 * r.diag;
    }
    ism_error err;
    cr_assert(ism_sing_certify_curves(r.t, &o, &r.l, &err));
    for (size_t c = 0; c < r.l.ncurves; c++) {
        const ism_sing_curve *cv = &r.l.curves[c];
        cr_expect(!cv->certified);
        /* the end at the pinch point is now 1e-6 × diag from it: it fails too */
        cr_expect_eq(cv->uncertified_points, cv->n, "curve %zu: %zu of %zu", c,
                     cv->uncertified_points, cv->n);
        cr_expect_eq(cv->first_uncertified, 0);
        cr_expect(cv->first_residual_grad > 1e-6 * r.diag, "%g", cv->first_residual_grad);
    }
    done(&r);
}
