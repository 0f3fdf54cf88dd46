/* test_singular_points.c — the singular-point stage (core/singular/find.h) against closed
 * forms, each run in the symmetric box and in boxes shifted off the search lattice by 1e-3
 * and by √2 − 1 of a finest cell: the tilted cone's node, Kummer's 4 and 16 nodes (positions
 * from a separate long-double Newton on hand-written derivatives), an isolated point, a
 * cusp, a sphere (nothing), two touching spheres (one degenerate point), the horn cyclide
 * (its one singular point, derived below); plus a double sheet (boxes, no point), the box
 * budget, cancel, and identical output for 1 and 2 threads. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/singular/find.h"
#include "core/singular/search.h"
#include "test_eval_surfaces.h"
#include "tests/unit/placements.h"

/* The three placements of a box: as given, shifted by 1e-3, shifted by √2 − 1 of a finest
 * cell (an irrational-looking fraction: no lattice plane of one is a plane of another). */
static void placed_box(const double *box, int depth, int placement, double out[6])
{
    for (int k = 0; k < 3; k++) {
        double cell = (box[k + 3] - box[k]) / ldexp(1.0, depth);
        double shift = placement == 0 ? 0.0 : placement == 1 ? 1e-3 : PF_IRR * cell;
        out[k] = box[k] + shift;
        out[k + 3] = box[k + 3] + shift;
    }
}

static void find(const ism_tape *t, const double *box, int depth, int placement, int threads,
                 ism_locus *l)
{
    ism_locus_options o;
    ism_locus_options_default(&o);
    placed_box(box, depth, placement, o.box);
    o.max_depth = depth;
    o.threads = threads;
    ism_locus_init(l);
    ism_error err;
    cr_assert(ism_locus_find(t, &o, l, &err), "%s", err.message);
    cr_assert(!l->incomplete, "%s", l->incomplete_why);
}

static ism_tape *compile(const char *src)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, err.message);
    return t;
}

static double dist(const double *a, const double *b)
{
    return sqrt((a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1])
                + (a[2] - b[2]) * (a[2] - b[2]));
}

/* Exactly n points, the i-th expected one matched by exactly one found point within tol,
 * each of the given type (and certified when asked). */
static void expect_points(const char *name, int placement, const ism_locus *l,
                          const double *box, const double (*want)[3], size_t n, double tol,
                          int type, bool certified)
{
    double diag = dist(box, box + 3);
    cr_assert_eq(l->npoints, n, "%s (placement %d): %zu points, want %zu", name, placement,
                 l->npoints, n);
    for (size_t i = 0; i < n; i++) {
        size_t hits = 0;
        for (size_t j = 0; j < l->npoints; j++) {
            const ism_sing_point *p = &l->points[j];
            if (dist(p->p, want[i]) > tol)
                continue;
            hits++;
            cr_expect_eq(p->type, type, "%s (placement %d): point %zu is %s", name, placement,
                         i, ism_sing_type_name(p->type));
            if (certified)
                cr_expect(p->certified && p->radius > 0 && p->radius <= 0.5e-9 * diag,
                          "%s (placement %d): point %zu not certified", name, placement, i);
            cr_expect_eq(p->cones, -1);
        }
        cr_expect_eq(hits, 1, "%s (placement %d): (%g, %g, %g) matched %zu times", name,
                     placement, want[i][0], want[i][1], want[i][2], hits);
    }
}

static void check_surface(const char *src, const double *box, int depth,
                          const double (*want)[3], size_t n, double tol, int type,
                          bool certified)
{
    ism_tape *t = compile(src);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, box, depth, placement, 0, &l);
        expect_points(src, placement, &l, box, want, n, tol, type, certified);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

static const double UNIT[6] = { -1, -1, -1, 1, 1, 1 };
static const double ORIGIN[1][3] = { { 0, 0, 0 } };

/* ∇f = (2x + 0.5z, 4y, 0.5x − 6z) vanishes only at 0 (det ≠ 0); H = [[2,0,.5],[0,4,0],
 * [.5,0,−6]] has eigenvalues of both signs: one node. */
Test(singular_points, tilted_cone_one_node)
{
    check_surface("x^2 + 2*y^2 - 3*z^2 + 0.5*x*z", UNIT, 6, ORIGIN, 1, 1e-9, ISM_SING_NODE, true);
}

/* f = |p|²: zero only at 0, H = 2I definite: one isolated point. */
Test(singular_points, isolated_point)
{
    check_surface("x^2 + y^2 + z^2", UNIT, 6, ORIGIN, 1, 1e-9, ISM_SING_ISOLATED, true);
}

/* The one point of l is certified by deflation and its box holds want. */
static void expect_deflated(const char *name, int placement, const ism_locus *l,
                            const double want[3])
{
    bool hit = false;
    for (size_t j = 0; j < l->npoints; j++) {
        const ism_sing_point *p = &l->points[j];
        if (fabs(p->p[0] - want[0]) > p->radius || fabs(p->p[1] - want[1]) > p->radius
            || fabs(p->p[2] - want[2]) > p->radius)
            continue;
        hit = true;
        cr_expect(p->certified && p->certificate == ISM_CERT_DEFLATION,
                  "%s (placement %d): not certified by deflation", name, placement);
        cr_expect(p->perturbation < 1e-9, "%s (placement %d): perturbation %g", name,
                  placement, p->perturbation);
    }
    cr_expect(hit, "%s (placement %d): no enclosure holds (%g, %g, %g)", name, placement,
              want[0], want[1], want[2]);
}

/* In each box placement, every want[i] is held by a deflation-certified enclosure, and no
 * singular curve is reported (none of these surfaces has one). */
static void check_deflated(const char *src, const double *box, int depth,
                           const double (*want)[3], size_t n)
{
    ism_tape *t = compile(src);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, box, depth, placement, 0, &l);
        for (size_t i = 0; i < n; i++)
            expect_deflated(src, placement, &l, want[i]);
        cr_expect_eq(l.ncurves, 0, "%s (placement %d): %zu curves", src, placement, l.ncurves);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* ∇f = (2x, −3y², 2z) = 0 only at 0, where f = 0 and H = diag(2, 0, 2): the A2 cusp
 * (f changes sign along y). Krawczyk on ∇f cannot hold (H is singular); the deflated system
 * (∇f − εn, Hv, nᵀv − 1) has the non-singular Jacobian of an A2 point (f_yyy = −6 ≠ 0). */
Test(singular_points, cusp)
{
    check_surface("x^2 + z^2 - y^3", UNIT, 6, ORIGIN, 1, 1e-9, ISM_SING_CUSP, true);
    check_deflated("x^2 + z^2 - y^3", UNIT, 6, ORIGIN, 1);
}

/* The same cusp moved to c = (0.125, 0.3125, −0.1875) (exact in binary) and turned by 45°
 * about z, so its null direction (1, 1, 0)/√2 is no axis: f = u² + w² − t³ with
 * u = (X − Y)/√2, t = (X + Y)/√2, w = Z, (X, Y, Z) = p − c. */
Test(singular_points, cusp_moved_and_turned)
{
    static const double want[1][3] = { { 0.125, 0.3125, -0.1875 } };
    const char *src = "((x - 0.125 - (y - 0.3125))/sqrt(2))^2 + (z + 0.1875)^2"
                      " - ((x - 0.125 + (y - 0.3125))/sqrt(2))^3";
    check_surface(src, UNIT, 6, want, 1, 1e-9, ISM_SING_CUSP, true);
    check_deflated(src, UNIT, 6, want, 1);
}

/* cusp_moved_and_turned's cusp moved to (0.3, 0.1, 0.2), inside cells in every placement:
 * Krawczyk cannot decide its cells (H is singular there), so they are cut on, and each is
 * tested, as the child of a cell with a model, by f at its centre against the parent's
 * Taylor form round a singular point (search.c, children_quad). Turned, H at the point is
 * [[1, −1, 0], [−1, 1, 0], [0, 0, 2]]: the form's off-diagonal term counts. The point is
 * kept, and the test ran in every placement (it dropped cells: ism_locus.centre_dropped).
 * Whether the cells holding the point get the test at all rests on centre_worth's guess,
 * so the form's own bounds are checked apart, against closed forms, where a form without
 * its off-diagonal terms or halved fails (test_dual_cert.c quad_form_of_a_turned_hessian). */
Test(singular_points, cusp_inside_cells_the_centre_test_sees)
{
    static const double want[1][3] = { { 0.3, 0.1, 0.2 } };
    const char *src = "((x - 0.3 - (y - 0.1))/sqrt(2))^2 + (z - 0.2)^2"
                      " - ((x - 0.3 + (y - 0.1))/sqrt(2))^3";
    check_surface(src, UNIT, 6, want, 1, 1e-9, ISM_SING_CUSP, true);
    ism_tape *t = compile(src);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, UNIT, 6, placement, 0, &l);
        cr_expect_gt(l.centre_dropped, 0, "placement %d: the centre test dropped no cell",
                     placement);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* Taubin's heart f = A³ − z³B, A = x² + 9/4 y² + z² − 1, B = x² + 9/80 y². ∇f = 3A²∇A −
 * 3z²B e_z − z³∇B vanishes on f = 0 where A = 0 and z = 0 (the ring x² + 9/4 y² = 1: f
 * vanishes to third order there, H = 0, and the zero set A = z·B^(1/3) is a smooth sheet —
 * no point, no curve to report) and where A = 0 and B = 0, i.e. x = y = 0, z = ±1. There
 * f ≈ ∓B + (2(z ∓ 1))³: H = ∓diag(2, 9/40, 0) of rank 2 and f changes sign along z — two
 * cusps (f_zzz = ±48 ≠ 0: deflation certifies them). The ring's Hessian is rounding, ~1e-13 (its eigenvalue ratios once made hundreds
 * of "rank-2" seeds, degenerate points and two-point curves). */
Test(singular_points, heart_two_cusps_no_ring)
{
    static const double want[2][3] = { { 0, 0, -1 }, { 0, 0, 1 } };
    const double box[6] = { -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 };
    const char *src = "(x^2 + 9/4*y^2 + z^2 - 1)^3 - x^2*z^3 - 9/80*y^2*z^3";
    check_surface(src, box, 6, want, 2, 1e-9, ISM_SING_CUSP, true);
    check_deflated(src, box, 6, want, 2);
    /* depth 5: the cusp at z = 1 shares its cluster with a lobe's critical points off the
       surface (not one point): found among the cluster's rank-2 projections by its cubic
       term (a curve's is 0), not taken for a whisker */
    check_deflated(src, box, 5, want, 2);
}

/* The unit sphere is smooth; its centre is a critical point with f = −1. */
Test(singular_points, sphere_has_none)
{
    check_surface("x^2 + y^2 + z^2 - 1", (const double[6]){ -1.5, -1.5, -1.5, 1.5, 1.5, 1.5 },
                  6, NULL, 0, 0, 0, false);
}

/* s1 s2 with s1, s2 the unit spheres about (±1, 0, 0): they touch at 0 only, where
 * ∇f = s2∇s1 + s1∇s2 = 0 and H = ∇s1∇s2ᵀ + ∇s2∇s1ᵀ = diag(−8, 0, 0) (rank 1); along y,
 * f = y⁴, so the zero of ∇f is isolated but degenerate. f = (x² + y² + z²)² − 4x² has no
 * cubic term: no regular defining system exists (typecert.c), and ∇f's rounding hides the
 * point within ~1e-5 — in every box it is reported, uncertified, as a contact. Poincaré–
 * Miranda still proves a zero of ∇f within exists_radius ≤ 1e-6 × diagonal of the reported
 * point; the only zero of ∇f near 0 is 0 itself, so that ball must hold the origin. */
Test(singular_points, touching_spheres_degenerate)
{
    const char *src = "((x-1)^2 + y^2 + z^2 - 1)*((x+1)^2 + y^2 + z^2 - 1)";
    const double box[6] = { -2, -2, -2, 2, 2, 2 };
    check_surface(src, box, 6, ORIGIN, 1, 1e-6, ISM_SING_DEGENERATE, false);
    ism_tape *t = compile(src);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, box, 6, placement, 0, &l);
        cr_assert_eq(l.npoints, 1);
        cr_expect(!l.points[0].certified);
        cr_expect_eq(l.points[0].uncertified_why, ISM_UNCERT_CONTACT, "placement %d: reason %d",
                     placement, l.points[0].uncertified_why);
        double r = l.points[0].exists_radius;
        cr_expect(r > 0 && r <= 1e-6 * dist(box, box + 3), "placement %d: exists within %g",
                  placement, r);
        cr_expect_leq(dist(l.points[0].p, ORIGIN[0]), r, "placement %d: 0 is %g away, > %g",
                      placement, dist(l.points[0].p, ORIGIN[0]), r);
        cr_expect_str_eq(ism_uncert_why_name(ISM_UNCERT_CONTACT),
                         "contact of two sheets (Hessian rank 1, the rank-1 system singular): "
                         "no regular system defines such a point and double precision places "
                         "it only to ~1e-5 of f's scale - not certifiable in principle");
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* Every want[i] is held (coordinate-wise) by the enclosure of exactly one point, certified
 * by kind[i] with a half-width ≤ 0.5e-9 × diagonal, of type type[i], and a perturbation
 * below 1e-9; l has no other point. */
static void expect_enclosed(const char *name, int placement, const ism_locus *l,
                            const double *box, const double (*want)[3], const int *kind,
                            const int *type, size_t n)
{
    double diag = dist(box, box + 3);
    cr_expect_eq(l->npoints, n, "%s (placement %d): %zu points, want %zu", name, placement,
                 l->npoints, n);
    for (size_t i = 0; i < n; i++) {
        size_t hits = 0;
        for (size_t j = 0; j < l->npoints; j++) {
            const ism_sing_point *p = &l->points[j];
            if (fabs(p->p[0] - want[i][0]) > p->radius || fabs(p->p[1] - want[i][1]) > p->radius
                || fabs(p->p[2] - want[i][2]) > p->radius)
                continue;
            hits++;
            cr_expect(p->certified && p->certificate == kind[i],
                      "%s (placement %d): point %zu certificate %s (%s)", name, placement, i,
                      ism_cert_kind_name(p->certificate), ism_uncert_why_name(p->uncertified_why));
            cr_expect(p->radius > 0 && p->radius <= 0.5e-9 * diag,
                      "%s (placement %d): point %zu radius %g", name, placement, i, p->radius);
            cr_expect(p->perturbation < 1e-9, "%s (placement %d): point %zu perturbation %g",
                      name, placement, i, p->perturbation);
            cr_expect_eq(p->type, type[i], "%s (placement %d): point %zu is %s", name,
                         placement, i, ism_sing_type_name(p->type));
        }
        cr_expect_eq(hits, 1, "%s (placement %d): (%g, %g, %g) enclosed %zu times", name,
                     placement, want[i][0], want[i][1], want[i][2], hits);
    }
}

static void check_enclosed(const char *src, const double *box, int depth,
                           const double (*want)[3], const int *kind, const int *type, size_t n)
{
    ism_tape *t = compile(src);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, box, depth, placement, 0, &l);
        expect_enclosed(src, placement, &l, box, want, kind, type, n);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* Horn cyclide (a = 10, r = f = 2): with S = x² + y² + z² + 92,
 *   f_z = 4zS, f_y = 4y(S − 192), f_x = 4xS − 80(10x − 4).
 * S > 0, so z = 0. If y = 0: f = S² − 4(10x − 4)² = (x − 10)²(x² + 20x + 84), zero at
 * x = 10, −6, −14, and f_x = 0 only at x = 10. If S = 192 (x² + y² = 100):
 * f = −16(x − 10)², zero only at x = 10, y = 0. So (10, 0, 0) is the only singular point.
 * There f = 384u² + 384z² + 40uy² + y⁴ + ... (u = x − 10): rank 2, and f < 0 between the
 * horns u = −y²/24 and u = −y²/16 — degenerate, not isolated, not a cusp. f_yyy = 0 (no
 * deflation), but the quartic along the critical curve u = −y²/48 is y⁴(1 − 40²/(4·384)) =
 * −y⁴/24 ≠ 0: an A3 point, certified by the A3 system. */
Test(singular_points, horn_cyclide_one_point)
{
    static const double want[1][3] = { { 10, 0, 0 } };
    static const int kind[1] = { ISM_CERT_A3 }, type[1] = { ISM_SING_DEGENERATE };
    const test_surface *s = &TEST_SURFACES[6];
    cr_assert_str_eq(s->name, "horn-cyclide");
    ism_tape *t = test_surface_compile(s);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, s->box, 7, placement, 0, &l);
        expect_enclosed(s->name, placement, &l, s->box, want, kind, type, 1);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* Steiner's Roman surface x²y² + y²z² + z²x² + xyz: on the x axis the Hessian across it is
 * [[2x², x], [x, 2x²]], determinant x²(4x² − 1): a double line for |x| < 1/2, a whisker
 * beyond, pinch points at x = ±1/2 (rank 1: H = diag(0, 1/2, 1/2) + offdiag 1/2 → one
 * non-zero eigenvalue), likewise on y and z; at 0, H = 0 and the cubic xyz has a 1-1
 * Hessian map: the triple point, certified by the rank-0 system. */
Test(singular_points, steiner_triple_and_pinch_points_certified)
{
    static const double want[7][3] = { { 0, 0, 0 },    { 0.5, 0, 0 }, { -0.5, 0, 0 },
                                       { 0, 0.5, 0 },  { 0, -0.5, 0 }, { 0, 0, 0.5 },
                                       { 0, 0, -0.5 } };
    static const int kind[7] = { ISM_CERT_RANK0, ISM_CERT_RANK1, ISM_CERT_RANK1, ISM_CERT_RANK1,
                                 ISM_CERT_RANK1, ISM_CERT_RANK1, ISM_CERT_RANK1 };
    static const int type[7] = { ISM_SING_TRIPLE, ISM_SING_PINCH, ISM_SING_PINCH, ISM_SING_PINCH,
                                 ISM_SING_PINCH,  ISM_SING_PINCH, ISM_SING_PINCH };
    check_enclosed("x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", UNIT, 5, want, kind, type, 7);
}

/* The cross-cap 4x²(x² + y² + z² + z) + y²(y² + z² − 1): on the z axis the Hessian across
 * it is diag(8z(z + 1), 2(z² − 1)), a double segment for 0 < z < 1 between pinch points at
 * z = 0 and z = 1 (one factor 0: rank 1) and a whisker beyond; at z = −1 both vanish (H = 0,
 * cubic −w(4x² + 2y²), w = z + 1, with a 1-1 Hessian map): a degenerate point on the
 * whisker, certified by the rank-0 system. */
Test(singular_points, cross_cap_pinch_points_certified)
{
    static const double want[3][3] = { { 0, 0, -1 }, { 0, 0, 0 }, { 0, 0, 1 } };
    static const int kind[3] = { ISM_CERT_RANK0, ISM_CERT_RANK1, ISM_CERT_RANK1 };
    static const int type[3] = { ISM_SING_DEGENERATE, ISM_SING_PINCH, ISM_SING_PINCH };
    const double box[6] = { -1.3, -1.3, -1.6, 1.3, 1.3, 1.4 };
    check_enclosed("4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", box, 5, want, kind,
                   type, 3);
}

/* xyz = 0: three planes, double lines on the axes, H = 0 only at 0 (H = [[0, z, y], [z, 0,
 * x], [y, x, 0]]): the triple point, rank-0 system. Whitney's umbrella x² − zy²: double
 * line y = 0 for z > 0, whisker for z < 0, the pinch point at 0 (H = diag(2, 0, 0)). */
Test(singular_points, xyz_triple_and_whitney_pinch_certified)
{
    static const int triple[1] = { ISM_SING_TRIPLE }, pinch[1] = { ISM_SING_PINCH };
    static const int rank0[1] = { ISM_CERT_RANK0 }, rank1[1] = { ISM_CERT_RANK1 };
    check_enclosed("x*y*z", UNIT, 5, ORIGIN, rank0, triple, 1);
    check_enclosed("x^2 - z*y^2", UNIT, 5, ORIGIN, rank1, pinch, 1);
}

/* The whisker loop (x² + y² − r²)² + z² (its source in src). */
static ism_tape *loop_tape(double r, char src[96])
{
    snprintf(src, 96, "(x^2 + y^2 - %.17g^2)^2 + z^2", r);
    return compile(src);
}

/* l holds the loop of radius r as one closed whisker and nothing else: every point within
 * 1e-9 × diagonal of the circle, its length 2πr within 1% (a polygon of n sides inscribed:
 * −π²/(6n²)). */
static void expect_traced_loop(const ism_locus *l, const char *src, int placement, double r)
{
    cr_expect_eq(l->npoints, 0, "%s (placement %d): %zu points", src, placement, l->npoints);
    cr_assert_eq(l->ncurves, 1, "%s (placement %d): %zu curves", src, placement, l->ncurves);
    const ism_sing_curve *c = &l->curves[0];
    cr_expect(c->closed && c->kind == ISM_CURVE_WHISKER);
    double len = 0.0, worst = 0.0;
    for (size_t k = 0; k < c->n; k++) {
        const double *a = c->xyz + 3 * k, *b = c->xyz + 3 * ((k + 1) % c->n);
        len += dist(a, b);
        worst = fmax(worst, fabs(hypot(a[0], a[1]) - r) + fabs(a[2]));
    }
    cr_expect(worst <= 1e-9 * dist(UNIT, UNIT + 3), "%s: %g off the circle", src, worst);
    cr_expect(fabs(len / (2 * M_PI * r) - 1) < 1e-2, "%s (placement %d): length %.6g, 2πr %.6g",
              src, placement, len, 2 * M_PI * r);
}

/* (x² + y² − r²)² + z²: ∇f = 0 on the circle ρ = r, z = 0 (f ≥ 0: a whisker), H across it
 * diag(8r², 2). Radii below a finest cell (1/32 at depth 6 in ±1) once made one cluster
 * taken for an uncertified point; now one closed whisker. */
Test(singular_points, small_whisker_loops_traced)
{
    static const double radii[3] = { 0.02, 0.006, 0.003 };
    for (int i = 0; i < 3; i++) {
        char src[96];
        ism_tape *t = loop_tape(radii[i], src);
        for (int placement = 0; placement < 3; placement++) {
            ism_locus l;
            find(t, UNIT, 6, placement, 0, &l);
            expect_traced_loop(&l, src, placement, radii[i]);
            ism_locus_free(&l);
        }
        ism_tape_free(t);
    }
}

/* The same loops smaller still, box ±1, depth 7 (cell 1/64): at the centre f = r⁴ > 0 and
 * ∇f = 0, every box's projection landed there, and that off-surface point took the loop
 * with it (r = 0.001 and 0.0002: nothing in the own and 1e-3 boxes), or the loop was
 * read as a contact of two sheets (r = 0.0005, 0.37 cell off). The Hessian across the
 * circle is diag(8r², 2): r = 0.001 clears the tracer's rank test twice over (8r²/2 ≥ 2 ×
 * 1e-6) and is one closed whisker of length 2πr; below (r < 7.1e-4: 0.0005, the tracer's
 * own edge, and 0.0002) the loop is one uncertified point of the circle, reason "small
 * loop", its radius bounding the loop (≥ 2r: the farthest point of the circle from one of
 * its points; at most the cluster's 4 cells across). */
Test(singular_points, whisker_loops_below_a_sixteenth_of_a_cell)
{
    static const double radii[3] = { 0.001, 0.0005, 0.0002 };
    double diag = dist(UNIT, UNIT + 3);
    for (int i = 0; i < 3; i++) {
        char src[96];
        ism_tape *t = loop_tape(radii[i], src);
        for (int placement = 0; placement < 3; placement++) {
            ism_locus l;
            find(t, UNIT, 7, placement, 0, &l);
            if (i == 0) {
                expect_traced_loop(&l, src, placement, radii[i]);
            } else {
                cr_expect_eq(l.ncurves, 0, "%s (placement %d): %zu curves", src, placement,
                             l.ncurves);
                cr_assert_eq(l.npoints, 1, "%s (placement %d): %zu points", src, placement,
                             l.npoints);
                const ism_sing_point *p = &l.points[0];
                cr_expect(!p->certified && p->uncertified_why == ISM_UNCERT_LOOP,
                          "%s (placement %d): certified %d, reason %s", src, placement,
                          p->certified, ism_uncert_why_name(p->uncertified_why));
                cr_expect_eq(p->type, ISM_SING_DEGENERATE);
                double off = fabs(hypot(p->p[0], p->p[1]) - radii[i]) + fabs(p->p[2]);
                cr_expect(off <= 1e-9 * diag, "%s (placement %d): %g off the circle", src,
                          placement, off);
                cr_expect(p->radius >= 2 * radii[i] && p->radius <= 4.0 / 64 * sqrt(3.0),
                          "%s (placement %d): radius %g", src, placement, p->radius);
            }
            ism_locus_free(&l);
        }
        ism_tape_free(t);
    }
}

/* z² + x²y² ≥ 0 vanishes on z = 0, xy = 0: the x and y axes, where ∇f = (2xy², 2x²y, 2z)
 * = 0 too; across the x axis at (a, 0, 0) H = diag(0, 2a², 2), definite: whiskers. x²y² −
 * z² = (xy − z)(xy + z): the sheets z = ±xy cross along the same axes, H across diag(2a²,
 * −2): double curves. At the origin H = diag(0, 0, ±2), rank 1, and four branches meet: a
 * triple point in the list's sense, whose rank-1 system is singular — reported once as
 * "contact of two sheets", which no sheet makes there. Four curves on the axes, each from
 * the origin to the box (total length: the box's x and y extents), and the point named a
 * crossing of curves. */
Test(singular_points, curves_crossing_at_a_rank_one_point)
{
    static const char *const src[2] = { "z^2 + x^2*y^2", "x^2*y^2 - z^2" };
    static const int kind[2] = { ISM_CURVE_WHISKER, ISM_CURVE_DOUBLE };
    double diag = dist(UNIT, UNIT + 3);
    for (int s = 0; s < 2; s++) {
        ism_tape *t = compile(src[s]);
        for (int placement = 0; placement < 3; placement++) {
            ism_locus l;
            double box[6];
            placed_box(UNIT, 6, placement, box);
            find(t, UNIT, 6, placement, 0, &l);
            cr_assert_eq(l.npoints, 1, "%s (placement %d): %zu points", src[s], placement,
                         l.npoints);
            const ism_sing_point *p = &l.points[0];
            cr_expect(dist(p->p, ORIGIN[0]) <= 1e-9 * diag, "%s (placement %d): point at "
                      "(%g, %g, %g)", src[s], placement, p->p[0], p->p[1], p->p[2]);
            cr_expect_eq(p->type, ISM_SING_TRIPLE);
            cr_expect(!p->certified && p->uncertified_why == ISM_UNCERT_CROSSING,
                      "%s (placement %d): reason %s", src[s], placement,
                      ism_uncert_why_name(p->uncertified_why));
            cr_assert_eq(l.ncurves, 4, "%s (placement %d): %zu curves", src[s], placement,
                         l.ncurves);
            double total = 0.0;
            for (size_t c = 0; c < l.ncurves; c++) {
                const ism_sing_curve *cv = &l.curves[c];
                cr_expect(cv->kind == kind[s] && !cv->closed);
                bool to_point = cv->end_type[0] == ISM_END_TRIPLE || cv->end_type[1] == ISM_END_TRIPLE;
                bool to_box = cv->end_type[0] == ISM_END_BOX || cv->end_type[1] == ISM_END_BOX;
                cr_expect(to_point && to_box, "%s (placement %d): curve %zu ends %d %d", src[s],
                          placement, c, cv->end_type[0], cv->end_type[1]);
                for (size_t k = 0; k < cv->n; k++) {
                    const double *a = cv->xyz + 3 * k;
                    cr_expect(fmin(fabs(a[0]), fabs(a[1])) + fabs(a[2]) <= 1e-9 * diag,
                              "%s: (%g, %g, %g) off the axes", src[s], a[0], a[1], a[2]);
                    if (k + 1 < cv->n)
                        total += dist(a, cv->xyz + 3 * (k + 1));
                }
            }
            double want = (box[3] - box[0]) + (box[4] - box[1]);
            cr_expect(fabs(total - want) <= 1e-6, "%s (placement %d): length %.9g, want %.9g",
                      src[s], placement, total, want);
            ism_locus_free(&l);
        }
        ism_tape_free(t);
    }
}

/* Kummer's quartic (x²+y²+z²−μ²)² − λ p q r s written out with its derivatives by hand, in
 * long double: an evaluation independent of the tape and its evaluators. */
typedef struct kummer {
    long double mu2, lambda, w;
} kummer;

static void kummer_jet(const kummer *k, const long double x[3], long double *f,
                       long double g[3], long double h[3][3])
{
    const long double r2 = sqrtl(2.0L);
    /* the four planes: value and (constant) gradient */
    long double v[4] = { k->w - x[2] - r2 * x[0], k->w - x[2] + r2 * x[0],
                         k->w + x[2] + r2 * x[1], k->w + x[2] - r2 * x[1] };
    const long double d[4][3] = { { -r2, 0, -1 }, { r2, 0, -1 }, { 0, r2, 1 }, { 0, -r2, 1 } };
    long double q = x[0] * x[0] + x[1] * x[1] + x[2] * x[2] - k->mu2;
    long double prod = v[0] * v[1] * v[2] * v[3];
    *f = q * q - k->lambda * prod;
    for (int i = 0; i < 3; i++) {
        long double gp = 0; /* ∂(pqrs)/∂xi */
        for (int a = 0; a < 4; a++) {
            long double others = 1;
            for (int b = 0; b < 4; b++)
                if (b != a)
                    others *= v[b];
            gp += others * d[a][i];
        }
        g[i] = 4.0L * q * x[i] - k->lambda * gp;
        for (int j = 0; j < 3; j++) {
            long double hp = 0; /* ∂²(pqrs)/∂xi∂xj */
            for (int a = 0; a < 4; a++)
                for (int b = 0; b < 4; b++) {
                    if (a == b)
                        continue;
                    long double others = 1;
                    for (int c = 0; c < 4; c++)
                        if (c != a && c != b)
                            others *= v[c];
                    hp += others * d[a][i] * d[b][j];
                }
            h[i][j] = 8.0L * x[i] * x[j] + (i == j ? 4.0L * q : 0.0L) - k->lambda * hp;
        }
    }
}

/* Newton on ∇f = 0 in long double from a start, by Cramer's rule; asserts it lands on a
 * singular point (f and ∇f at rounding level). */
static void kummer_node(const kummer *k, const double start[3], double out[3])
{
    long double x[3] = { start[0], start[1], start[2] }, f, g[3], h[3][3];
    for (int it = 0; it < 60; it++) {
        kummer_jet(k, x, &f, g, h);
        long double det = h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1])
                          - h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0])
                          + h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
        cr_assert(fabsl(det) > 1e-12L, "Kummer Hessian singular at a start");
        long double s[3];
        for (int c = 0; c < 3; c++) {
            long double m[3][3];
            memcpy(m, h, sizeof m);
            for (int r = 0; r < 3; r++)
                m[r][c] = -g[r];
            s[c] = (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
                    - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
                    + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) / det;
        }
        for (int c = 0; c < 3; c++)
            x[c] += s[c];
    }
    kummer_jet(k, x, &f, g, h);
    cr_assert(fabsl(f) < 1e-15L && fabsl(g[0]) + fabsl(g[1]) + fabsl(g[2]) < 1e-15L,
              "no singular point near (%g, %g, %g): f = %Lg", start[0], start[1], start[2], f);
    for (int c = 0; c < 3; c++)
        out[c] = (double)x[c];
}

static void check_kummer(const test_surface *s, const double (*starts)[3], size_t n, int depth)
{
    kummer k = { s->params[0].value, 0, s->params[1].value };
    k.lambda = (3 * k.mu2 - 1) / (3 - k.mu2);
    double want[16][3];
    for (size_t i = 0; i < n; i++)
        kummer_node(&k, starts[i], want[i]);
    for (size_t i = 0; i < n; i++) /* the starts lead to n distinct nodes */
        for (size_t j = 0; j < i; j++)
            cr_assert(dist(want[i], want[j]) > 1e-3, "%s: starts %zu, %zu meet", s->name, i, j);
    ism_tape *t = test_surface_compile(s);
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, s->box, depth, placement, 0, &l);
        expect_points(s->name, placement, &l, s->box, want, n, 1e-9, ISM_SING_NODE, true);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* μ² = 0.6667 (the preset's value, λ ≈ 0.4286): four real nodes, two on the plane x = 0
 * and two on y = 0 (the quartic is even in x and in y, and the swap x <-> y, z <-> -z maps
 * it to itself). Starts: the published picture's node positions to two digits. */
Test(singular_points, kummer_4_nodes)
{
    static const double starts[4][3] = {
        { 0, 0.24, -0.17 }, { 0, -0.24, -0.17 }, { 0.24, 0, 0.17 }, { -0.24, 0, 0.17 },
    };
    cr_assert_str_eq(TEST_SURFACES[4].name, "kummer-4-nodes");
    check_kummer(&TEST_SURFACES[4], starts, 4, 7);
}

/* The same four nodes at depth 3 (cell 0.75 in ±3): the nodes' cells join one cluster with
 * the quartic's 8 critical points off the surface, which are all the search's Newton
 * projections reach; the nodes' own cells are not projected, and the points stage once found
 * nothing there and still called the locus complete. */
Test(singular_points, kummer_4_nodes_coarse)
{
    static const double starts[4][3] = {
        { 0, 0.24, -0.17 }, { 0, -0.24, -0.17 }, { 0.24, 0, 0.17 }, { -0.24, 0, 0.17 },
    };
    check_kummer(&TEST_SURFACES[4], starts, 4, 3);
}

/* μ² = 2 (λ = 5): the 16 nodes in closed form, each checked a singular point by the
 * long-double Newton above (which leaves an exact node where it is): (±1, 0, −1),
 * (0, ±1, 1), (±1/√2, 0, −1/2), (0, ±1/√2, 1/2), (±(√2+1)/2, ±(√2−1)/2, −1/√2),
 * (±(√2−1)/2, ±(√2+1)/2, 1/√2). */
Test(singular_points, kummer_16_nodes)
{
    const double a = (sqrt(2.0) + 1) / 2, b = (sqrt(2.0) - 1) / 2, c = 1 / sqrt(2.0);
    const double starts[16][3] = {
        { 1, 0, -1 },   { -1, 0, -1 },  { 0, 1, 1 },    { 0, -1, 1 },
        { c, 0, -0.5 }, { -c, 0, -0.5 }, { 0, c, 0.5 }, { 0, -c, 0.5 },
        { a, b, -c },   { a, -b, -c },  { -a, b, -c },  { -a, -b, -c },
        { b, a, c },    { b, -a, c },   { -b, a, c },   { -b, -a, c },
    };
    cr_assert_str_eq(TEST_SURFACES[5].name, "kummer-16-nodes");
    check_kummer(&TEST_SURFACES[5], starts, 16, 7);
}

/* Same points, same boxes, bit for bit, on 1 and 2 threads. */
Test(singular_points, thread_count_does_not_matter)
{
    const test_surface *s = &TEST_SURFACES[5];
    ism_tape *t = test_surface_compile(s);
    ism_locus a, b;
    find(t, s->box, 7, 2, 1, &a);
    find(t, s->box, 7, 2, 2, &b);
    cr_assert_eq(a.npoints, b.npoints);
    cr_assert_eq(a.nboxes, b.nboxes);
    for (size_t i = 0; i < a.npoints; i++) { /* field by field: structs have padding */
        const ism_sing_point *p = &a.points[i], *q = &b.points[i];
        cr_expect(memcmp(p->p, q->p, sizeof p->p) == 0 && p->radius == q->radius
                  && p->type == q->type && p->certified == q->certified
                  && memcmp(p->eig, q->eig, sizeof p->eig) == 0
                  && p->residual_f == q->residual_f && p->residual_grad == q->residual_grad,
                  "point %zu differs", i);
    }
    for (size_t i = 0; i < a.nboxes; i++) {
        const ism_lbox *p = &a.boxes[i], *q = &b.boxes[i];
        cr_expect(memcmp(p->lo, q->lo, sizeof p->lo) == 0 && memcmp(p->hi, q->hi, sizeof p->hi) == 0
                  && memcmp(p->q, q->q, sizeof p->q) == 0 && p->rank == q->rank
                  && p->flags == q->flags, "box %zu differs", i);
    }
    cr_expect_eq(a.boxes_visited, b.boxes_visited);
    ism_locus_free(&a);
    ism_locus_free(&b);
    ism_tape_free(t);
}

/* (|p|² − 1/2)²: ∇f = 0 on the whole sphere of radius 1/√2, a double sheet. No point; the
 * candidate boxes are rank 1, their projections on the sphere. */
Test(singular_points, double_sheet_boxes)
{
    ism_tape *t = compile("(x^2 + y^2 + z^2 - 0.5)^2");
    ism_locus l;
    find(t, UNIT, 5, 2, 0, &l);
    cr_expect_eq(l.npoints, 0);
    cr_assert_gt(l.nboxes, 100);
    size_t projected = 0;
    for (size_t i = 0; i < l.nboxes; i++) {
        const ism_lbox *b = &l.boxes[i];
        if (!(b->flags & ISM_LBOX_PROJECTED))
            continue;
        projected++;
        double r = sqrt(b->q[0] * b->q[0] + b->q[1] * b->q[1] + b->q[2] * b->q[2]);
        cr_expect(fabs(r - sqrt(0.5)) < 1e-9, "projection at radius %.17g", r);
        cr_expect_eq(b->rank, 1);
        cr_expect(!(b->flags & ISM_LBOX_USED));
    }
    cr_expect_geq(projected, l.nboxes * 9 / 10);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* A budget of 50 boxes or a raised cancel flag: incomplete, saying why, nothing false. */
Test(singular_points, budget_and_cancel)
{
    ism_tape *t = compile("(x^2 + y^2 + z^2 - 0.5)^2");
    ism_locus_options o;
    ism_locus_options_default(&o);
    o.max_depth = 6;
    o.max_boxes = 50;
    ism_locus l;
    ism_locus_init(&l);
    ism_error err;
    cr_assert(ism_locus_find(t, &o, &l, &err));
    cr_expect(l.incomplete && strstr(l.incomplete_why, "budget"), "%s", l.incomplete_why);
    cr_expect_leq(l.nboxes, 50);
    cr_expect_eq(l.npoints, 0);
    ism_locus_free(&l);
    volatile int cancel = 1;
    ism_locus_options_default(&o);
    o.cancel = &cancel;
    ism_locus_init(&l);
    cr_assert(ism_locus_find(t, &o, &l, &err));
    cr_expect(l.incomplete && strstr(l.incomplete_why, "cancel"), "%s", l.incomplete_why);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* Smooth surfaces leave nothing: no point and no candidate box — the gyroid ball's crease
 * (max of two smooth functions) included, each smooth piece being excluded on its own. */
Test(singular_points, smooth_surfaces_leave_no_box)
{
    static const size_t which[] = { 0, 1, 2, 3 }; /* sphere, torus, pretzel, gyroid-ball */
    for (size_t i = 0; i < sizeof which / sizeof which[0]; i++) {
        const test_surface *s = &TEST_SURFACES[which[i]];
        ism_tape *t = test_surface_compile(s);
        for (int placement = 0; placement < 3; placement += 2) {
            ism_locus l;
            find(t, s->box, 6, placement, 0, &l);
            cr_expect_eq(l.npoints, 0, "%s: %zu points", s->name, l.npoints);
            cr_expect_eq(l.nboxes, 0, "%s: %zu boxes", s->name, l.nboxes);
            ism_locus_free(&l);
        }
        ism_tape_free(t);
    }
}

/* The proof that the torus (R 1, r 0.3) has no singular point is cheap, in the three
 * placements at depth 7. ∇f vanishes on its circle of minima (f = −4R²r² ≈ −0.36, H ≈ 8 across
 * the tube) and at the origin (f = (R² − r²)² ≈ 0.83), where only f ≠ 0 rules a cell out. The
 * second-order form round the centre must carry ∇f(c)·(X − c); Taylor round a singular point
 * p (f(p) = 0, ∇f(p) = 0: f(c) = ½ (c − p)ᵀ H (c − p)) does not, and drops those cells a
 * level sooner: 1,481 / 745 / 761 cells before it, 969 / 489 / 489 with it. A child's
 * gradient rows and jet tests first on its parent's model (no evaluation) then cut interval
 * evaluations 3,491 / 1,755 / 1,794 (old) → 2,315 / 1,167 / 1,162 (Taylor test alone) →
 * 1,715 / 867 / 858, and jets 364 / 196 / 190 (parent rows) → 188 / 108 / 110 (parent jet).
 * Each bound sits ~10-25% above today's count and below the step before. */
Test(singular_points, smooth_torus_proof_is_cheap)
{
    const test_surface *s = &TEST_SURFACES[1];
    cr_assert_str_eq(s->name, "torus");
    ism_tape *t = test_surface_compile(s);
    static const uint64_t intervals_max[3] = { 1900, 960, 960 }, jets_max[3] = { 240, 135, 135 },
                          visited_max[3] = { 1100, 560, 560 };
    for (int placement = 0; placement < 3; placement++) {
        ism_locus l;
        find(t, s->box, 7, placement, 1, &l);
        cr_expect_eq(l.npoints, 0, "placement %d: %zu points", placement, l.npoints);
        cr_expect_eq(l.nboxes, 0, "placement %d: %zu boxes", placement, l.nboxes);
        cr_expect_lt(l.evals_interval, intervals_max[placement],
                     "placement %d: %llu interval evaluations", placement,
                     (unsigned long long)l.evals_interval);
        cr_expect_lt(l.evals_jet, jets_max[placement], "placement %d: %llu jets", placement,
                     (unsigned long long)l.evals_jet);
        cr_expect_lt(l.boxes_visited, visited_max[placement], "placement %d: %llu cells",
                     placement, (unsigned long long)l.boxes_visited);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* A deadline already past: incomplete, saying so. */
Test(singular_points, deadline)
{
    const test_surface *s = &TEST_SURFACES[5];
    ism_tape *t = test_surface_compile(s);
    ism_locus_options o;
    ism_locus_options_default(&o);
    memcpy(o.box, s->box, sizeof o.box);
    o.deadline_ms = 1e-3; /* the monotonic clock is past it */
    ism_locus l;
    ism_locus_init(&l);
    ism_error err;
    cr_assert(ism_locus_find(t, &o, &l, &err));
    cr_expect(l.incomplete && strstr(l.incomplete_why, "deadline"), "%s", l.incomplete_why);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* A pole sphere: f = 1/(|p|² − 1/4) is unbounded there and never 0, ∇f = −2p/(|p|² − 1/4)²
 * vanishes only at 0 (f = −4): no point and no box (without the pole rule, every finest
 * cell along the sphere was kept: 19304 boxes at depth 7). */
Test(singular_points, pole_leaves_no_box)
{
    ism_tape *t = compile("1/(x^2 + y^2 + z^2 - 0.25)");
    for (int placement = 0; placement < 3; placement += 2) {
        ism_locus l;
        find(t, UNIT, 5, placement, 0, &l);
        cr_expect_eq(l.nboxes, 0, "%zu boxes", l.nboxes);
        cr_expect_eq(l.npoints, 0);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}
