/* test_straddle.c — the polygoniser's straddle option (core/octree/straddle.h) under
 * max_error: on the sphere and the torus every vertex, centroid and edge midpoint lies within
 * E of the surface (closed-form distances), in boxes on the octree lattice and shifted off it
 * by 1e-3 and by an irrational fraction of a finest cell; the sphere's vertices sit outside it
 * (its convex side), the torus's outer vertices outside its tube and its saddle-shaped inner
 * ones on it; the meshes have fewer triangles than without the option; a surface with a min/max
 * is left exactly as it was. The balanced move the dual mesh uses (ism_straddle_balanced_point)
 * on closed-form saddles and bowls: the share of E their principal curvatures give. */
#include <criterion/criterion.h>
#include <math.h>
#include <string.h>
#include "core/octree/straddle.h"
#include "poly_fixture.h"

static const ism_param sphere_r[] = {{"r", 1}};
static const pf_surface sphere = {"x^2 + y^2 + z^2 - r^2", sphere_r, 1, NULL, 0};
static const ism_param torus_rr[] = {{"R", 1}, {"r", 0.3}};
static const pf_surface torus = {"(x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4*R^2*(x^2 + y^2)",
                                 torus_rr, 2, NULL, 0};
/* Two unit balls' union (a min: a crease where they meet). */
static const pf_surface balls = {"min(x^2 + y^2 + z^2 - 1, (x - 1)^2 + y^2 + z^2 - 1)", NULL,
                                 0, NULL, 0};

/* Signed closed-form distances (> 0 outside). */
static double sphere_signed(const double p[3])
{
    return sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1;
}

static double torus_signed(const double p[3])
{
    double ring = sqrt(p[0] * p[0] + p[1] * p[1]) - 1;
    return sqrt(ring * ring + p[2] * p[2]) - 0.3;
}

#define SAFETY_DEPTH 10
#define FINEST (3.0 / (1 << SAFETY_DEPTH))
static const double shifts[] = {0, 1e-3 * FINEST, PF_IRR * FINEST};

static void run(const ism_tape *t, double shift, double e, bool straddle, ism_mesh *m)
{
    double box[6];
    for (int k = 0; k < 3; k++) {
        box[k] = -1.5 + shift;
        box[3 + k] = 1.5 + shift;
    }
    ism_poly_options o;
    pf_options(&o, box, 3, SAFETY_DEPTH); /* 3: the default minimum depth */
    o.max_error = e;
    o.straddle = straddle;
    ism_poly_stats st;
    pf_run_options(t, &o, m, &st);
    cr_assert_eq(st.error_missed_nodes, 0);
}

/* Every box: within E, and at most `ratio` of the triangles without the option. */
static void check(const pf_surface *s, double (*dist)(const double *), double e, double ratio,
                  void (*vertices)(const ism_mesh *, double))
{
    ism_tape *t = pf_compile(s);
    for (size_t i = (size_t)pf_first_box(); i < sizeof shifts / sizeof shifts[0]; i++) {
        ism_mesh plain, moved;
        run(t, shifts[i], e, false, &plain);
        run(t, shifts[i], e, true, &moved);
        double worst = pf_worst_distance(&moved, dist);
        cr_expect_leq(worst, e, "%s E %g shift %g: a point %g from the surface", s->expr, e,
                      shifts[i], worst);
        cr_expect_lt((double)moved.ntris, ratio * (double)plain.ntris,
                     "%s E %g shift %g: %zu triangles, %zu without straddling", s->expr, e,
                     shifts[i], moved.ntris, plain.ntris);
        vertices(&moved, e);
        ism_mesh_free(&plain);
        ism_mesh_free(&moved);
    }
    ism_tape_free(t);
}

/* The sphere curves one way everywhere: every vertex moved out by 0.9 E (box faces aside:
 * the sphere does not reach them). */
static void sphere_vertices(const ism_mesh *m, double e)
{
    for (size_t v = 0; v < m->nverts; v++) {
        double d = sphere_signed(m->pos + 3 * v);
        cr_assert(d > 0.85 * e && d < 0.95 * e, "vertex %zu at %g (E %g)", v, d, e);
    }
}

/* Outside the ring's circle (x² + y² > 1, both curvatures one sign) vertices move out of the
 * tube; on the inner side (a saddle) they stay on it. Beside the circles x² + y² = 1 where
 * the curvature changes sign either may hold. */
static void torus_vertices(const ism_mesh *m, double e)
{
    size_t out = 0, on = 0;
    for (size_t v = 0; v < m->nverts; v++) {
        const double *p = m->pos + 3 * v;
        double ring = sqrt(p[0] * p[0] + p[1] * p[1]) - 1, d = torus_signed(p);
        if (ring > 0.05) {
            cr_assert(d > 0.85 * e && d < 0.95 * e, "outer vertex %zu at %g (E %g)", v, d, e);
            out++;
        } else if (ring < -0.05) {
            cr_assert(fabs(d) < 1e-3 * e, "inner vertex %zu at %g (E %g)", v, d, e);
            on++;
        }
    }
    cr_assert(out > 100 && on > 100, "%zu outer, %zu inner vertices", out, on);
}

/* At these bounds the octree's levels fall so that straddling saves about a third
 * (measured: sphere 1e-3 17,192 -> 12,008, torus 3e-3 13,792 -> 8,816 on the lattice). */
Test(straddle, sphere_within_the_bound_with_fewer_triangles)
{
    check(&sphere, sphere_signed, 1e-3, 0.85, sphere_vertices);
}

Test(straddle, torus_within_the_bound_with_fewer_triangles)
{
    check(&torus, torus_signed, 3e-3, 0.85, torus_vertices);
}

/* A min/max's crease is not straddled: the same mesh bit for bit. */
Test(straddle, min_max_surface_unchanged)
{
    ism_tape *t = pf_compile(&balls);
    ism_mesh plain, moved;
    run(t, PF_IRR * FINEST, 1e-2, false, &plain);
    run(t, PF_IRR * FINEST, 1e-2, true, &moved);
    cr_assert_eq(plain.nverts, moved.nverts);
    cr_assert_eq(plain.ntris, moved.ntris);
    cr_assert(memcmp(plain.pos, moved.pos, 3 * plain.nverts * sizeof *plain.pos) == 0);
    cr_assert(memcmp(plain.tri, moved.tri, 3 * plain.ntris * sizeof *plain.tri) == 0);
    ism_mesh_free(&plain);
    ism_mesh_free(&moved);
    ism_tape_free(t);
}

/* z = a x² − b y² (f = a x² − b y² − z): at the origin ∇f = (0, 0, −1) and the tangential
 * Hessian has eigenvalues 2a and −2b, so the balanced move is E (a − b) / (a + b) along
 * −z, capped at ±0.9 E (the straddle share): a bowl (b < 0) and a cylinder (b = 0) take the
 * cap, exactly the move ism_straddle_point makes; the symmetric saddle does not move. */
Test(straddle, balanced_move_on_saddles_and_bowls)
{
    static const struct {
        double a, b, share; /* the move as a share of E along +z; NAN: none */
    } cases[] = {
        {1, 1, NAN}, {2, 1, -1.0 / 3}, {1, 2, 1.0 / 3}, {5, 1, -2.0 / 3}, {1, 0, -0.9},
        {1, -1, -0.9}, {0, 3, 0.9}, {19, 1, -0.9}, {3, 2, -0.2},
    };
    const double e = 1e-2, box[6] = {-1, -1, -1, 1, 1, 1}, p[3] = {0, 0, 0};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ism_param prm[2] = {{"a", cases[i].a}, {"b", cases[i].b}};
        pf_surface s = {"a*x^2 - b*y^2 - z", prm, 2, NULL, 0};
        ism_tape *t = pf_compile(&s);
        ism_sampler smp;
        memset(&smp, 0, sizeof smp);
        smp.tape = t;
        smp.ws = ism_eval_ws_new(t);
        cr_assert(smp.ws);
        double q[3], r[3];
        bool moved = ism_straddle_balanced_point(&smp, 0.9 * e, box, p, q, NULL);
        cr_assert_eq(moved, !isnan(cases[i].share), "a %g b %g", cases[i].a, cases[i].b);
        double want = isnan(cases[i].share) ? 0 : cases[i].share * e;
        cr_assert(fabs(q[0]) == 0 && fabs(q[1]) == 0 && fabs(q[2] - want) < 1e-12 * e,
                  "a %g b %g: moved to (%g, %g, %g), expected z %g", cases[i].a, cases[i].b,
                  q[0], q[1], q[2], want);
        /* the same move with the curvatures beside it (|∇f| = 1, principal curvatures 2a and
         * -2b): the largest max(|2a|, |2b|); the least min(|2a|, |2b|) where both bend one way
         * (a b < 0), else 0 */
        double q2[3], bend, bends[2] = {-1, -1};
        cr_assert_eq(ism_straddle_balanced_point(&smp, 0.9 * e, box, p, q2, &bend), moved);
        cr_assert(memcmp(q, q2, sizeof q) == 0, "a %g b %g", cases[i].a, cases[i].b);
        cr_assert(fabs(bend - fmax(fabs(2 * cases[i].a), fabs(2 * cases[i].b))) < 1e-12,
                  "a %g b %g: bend %g", cases[i].a, cases[i].b, bend);
        cr_assert_eq(ism_straddle_balanced_point_at(&smp, 0.9 * e, box, p, NULL, q2, bends),
                     moved);
        cr_assert(memcmp(q, q2, sizeof q) == 0, "a %g b %g", cases[i].a, cases[i].b);
        double least = cases[i].a * cases[i].b < 0
                           ? fmin(fabs(2 * cases[i].a), fabs(2 * cases[i].b)) : 0;
        cr_assert(bends[0] == bend && fabs(bends[1] - least) < 1e-12,
                  "a %g b %g: bends %g %g, expected %g %g", cases[i].a, cases[i].b, bends[0],
                  bends[1], bend, least);
        if (fabs(cases[i].share) == 0.9) { /* the cap: ism_straddle_point's move, bit for bit */
            bool one_way = ism_straddle_point(&smp, 0.9 * e, box, p, r);
            cr_assert(!one_way || memcmp(q, r, sizeof q) == 0, "a %g b %g", cases[i].a,
                      cases[i].b);
        }
        ism_eval_ws_free(smp.ws);
        ism_tape_free(t);
    }
}

/* The curvatures beside the move (ism_straddle_balanced_point_at's bend[2], dual.c's sag_split
 * reads them) are the surface's largest principal curvature in magnitude and, where both bend
 * one way, its least (else 0), from f's scale-free form: sphere r 0.8 anywhere 1.25 and
 * 1.25; ellipsoid x² + y²/4 + 4z² = 1 at (1, 0, 0) a / c² = 4 and a / b² = 1/4; the torus
 * R 1, r 0.3 at its outer equator (1.3, 0, 0) 1 / r and 1 / 1.3, at its inner one
 * (0, 0.7, 0) 1 / r and 0 (a saddle: −1 / 0.7 the other); the hyperboloid x² + y² − z² = 1
 * at (1, 0, 0) 1 and 0 (a saddle of ±1: no move, the curvature still given); 0 and 0 on a
 * box face. ism_straddle_balanced_point's one bend is bend[0]. */
Test(straddle, bends_are_the_largest_and_least_principal_curvatures)
{
    static const ism_param sphere_08[] = {{"r", 0.8}};
    const pf_surface ellipsoid = {"x^2 + y^2/4 + 4*z^2 - 1", NULL, 0, NULL, 0};
    const pf_surface hyperboloid = {"x^2 + y^2 - z^2 - 1", NULL, 0, NULL, 0};
    const pf_surface ball = {"x^2 + y^2 + z^2 - r^2", sphere_08, 1, NULL, 0};
    const double k = 0.8 / sqrt(3);
    const struct {
        const pf_surface *s;
        double p[3], bend, least;
        bool moves;
    } cases[] = {
        {&ball, {k, -k, k}, 1.25, 1.25, true},      {&ellipsoid, {1, 0, 0}, 4, 0.25, true},
        {&torus, {1.3, 0, 0}, 1 / 0.3, 1 / 1.3, true}, {&torus, {0, 0.7, 0}, 1 / 0.3, 0, true},
        {&hyperboloid, {1, 0, 0}, 1, 0, false},     {&ball, {0.8, 0, 0}, 0, 0, false},
    };
    const double shift = 0.9e-2, box[6] = {-2, -2, -2, 2, 2, 2};
    const double faced[6] = {-2, -2, -2, 0.8, 2, 2}; /* the last case's point on x = 0.8 */
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ism_tape *t = pf_compile(cases[i].s);
        ism_sampler smp;
        memset(&smp, 0, sizeof smp);
        smp.tape = t;
        smp.ws = ism_eval_ws_new(t);
        cr_assert(smp.ws);
        double q[3], bend = -1;
        bool last = i + 1 == sizeof cases / sizeof cases[0];
        bool moved =
            ism_straddle_balanced_point(&smp, shift, last ? faced : box, cases[i].p, q, &bend);
        cr_expect_eq(moved, cases[i].moves, "case %zu", i);
        cr_expect(fabs(bend - cases[i].bend) < 1e-12 * (1 + cases[i].bend),
                  "case %zu: bend %.15g, expected %.15g", i, bend, cases[i].bend);
        double q2[3], bends[2] = {-1, -1};
        cr_expect_eq(ism_straddle_balanced_point_at(&smp, shift, last ? faced : box, cases[i].p,
                                                    NULL, q2, bends),
                     moved, "case %zu", i);
        cr_expect(memcmp(q, q2, sizeof q) == 0, "case %zu", i);
        cr_expect(bends[0] == bend, "case %zu: bend[0] %.15g, bend %.15g", i, bends[0], bend);
        cr_expect(fabs(bends[1] - cases[i].least) < 1e-12 * (1 + cases[i].least),
                  "case %zu: bend[1] %.15g, expected %.15g", i, bends[1], cases[i].least);
        ism_eval_ws_free(smp.ws);
        ism_tape_free(t);
    }
}
