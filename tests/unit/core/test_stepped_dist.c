/* test_stepped_dist.c — the band's Newton step (core/util/dist_bound.h: ism_stepped_dist), one
 * rule for the polygoniser's estimator (core/octree/sample_dist.h) and the analysis
 * (core/analysis/accuracy.c): ism_plain_dist one point at a time and ism_plain_dists in
 * batches give the same figures bit for bit, at a few hundred points of the band on the
 * sphere, the torus and the gyroid ball in the three boxes (tests/unit/placements.h); where
 * Newton's foot has no estimate both give INFINITY, and the analysis does not count the
 * point within the bound on the step's length alone (its maximum stays an upper bound of the
 * closed-form distance, beyond E where that is, though d1 is within it), while its mean and
 * 99th percentile are the same with a bound or without. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "core/octree/sample_dist.h"
#include "core/util/dist_bound.h"
#include "core/util/vec3.h"
#include "poly_fixture.h"

/* The bound the meshes are made and measured under: coarse (a few thousand triangles, a
 * fraction of a second a box) while a third of the points between vertices lie in its band
 * (ism_first_order_unsure). */
#define BOUND 1e-2
/* Points of the band each surface and box must give: "a few hundred". */
#define MIN_BAND_POINTS 300
/* Offsets along the unit normal from every mesh vertex, in units of BOUND: first-order
 * distances spread over the band (E/2, E], beside the mesh's own centroids and midpoints. */
static const double OFFSETS[] = {0.55, 0.7, 0.85, 0.99};

static const ism_param gyroid_k[] = {{"k", 4}};
static const pf_surface gyroid_ball = {
    "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
    gyroid_k, 1, NULL, 0};
static const double BOX15[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
/* The depth.max of the runs (a safety limit under the bound). */
#define DEPTH_MAX 8

typedef struct pts {
    double (*p)[3];
    size_t n, cap;
} pts;

static void push(pts *s, const double p[3])
{
    if (s->n == s->cap) {
        s->cap = s->cap ? 2 * s->cap : 1024;
        s->p = realloc(s->p, s->cap * sizeof *s->p);
        cr_assert_not_null(s->p);
    }
    memcpy(s->p[s->n++], p, sizeof s->p[0]);
}

/* The mesh's centroids and edge midpoints (each triangle's three: shared ones twice, which
 * only repeats a comparison), and every vertex moved along ∇f by OFFSETS. */
static void candidates(const ism_mesh *m, ism_sampler *s, pts *out)
{
    for (size_t t = 0; t < m->ntris; t++) {
        const double *v[3];
        for (int k = 0; k < 3; k++)
            v[k] = m->pos + 3 * (size_t)m->tri[3 * t + k];
        double c[3];
        for (int a = 0; a < 3; a++)
            c[a] = (v[0][a] + v[1][a] + v[2][a]) / 3;
        push(out, c);
        for (int k = 0; k < 3; k++) {
            for (int a = 0; a < 3; a++)
                c[a] = (v[k][a] + v[(k + 1) % 3][a]) / 2;
            push(out, c);
        }
    }
    for (size_t i = 0; i < m->nverts; i++) {
        const double *v = m->pos + 3 * i;
        double g[3];
        ism_sample_grad(s, v, g);
        double gl = ism_norm3(g);
        if (!(gl > 0))
            continue;
        for (size_t k = 0; k < sizeof OFFSETS / sizeof OFFSETS[0]; k++) {
            double q[3];
            for (int a = 0; a < 3; a++)
                q[a] = v[a] + OFFSETS[k] * BOUND * g[a] / gl;
            push(out, q);
        }
    }
}

/* t meshed under BOUND in the box BOX15 placed by which (−1 own, 0 the 1e-3 shift, 1 the
 * irrational one): at the points of the band, ism_plain_dist point by point (a sampler
 * evaluating one point at a time) equals ism_plain_dists (a batching sampler) bit for bit,
 * and the step moves most of them past the first-order figure. */
static void check_scalar_batched(const pf_surface *surf, int which)
{
    ism_tape *t = pf_compile(surf);
    double box[6];
    pf_sweep_box(BOX15, DEPTH_MAX, which, box);
    ism_poly_options o;
    pf_options(&o, box, 3, DEPTH_MAX);
    o.max_error = BOUND;
    ism_mesh m;
    ism_poly_stats st;
    pf_run_options(t, &o, &m, &st);
    ism_sampler one = {.tape = t, .ws = ism_eval_ws_new(t), .dist_above = BOUND};
    ism_sampler many = {.tape = t, .ws = ism_eval_ws_new(t), .dist_above = BOUND, .batch = true};
    pts all = {0}, band = {0};
    candidates(&m, &one, &all);
    for (size_t i = 0; i < all.n; i++) {
        double g[3], f = ism_sample_grad(&one, all.p[i], g);
        if (ism_first_order_unsure(ism_first_order_dist(f, g), BOUND))
            push(&band, all.p[i]);
    }
    cr_assert_geq(band.n, MIN_BAND_POINTS, "%s box %d: %zu points in the band", surf->expr,
                  which, band.n);
    double *f = malloc(band.n * sizeof *f), (*g)[3] = malloc(band.n * sizeof *g);
    double *batched = malloc(band.n * sizeof *batched);
    cr_assert(f && g && batched);
    ism_sample_grad_batch(&many, (const double (*)[3])band.p, f, g, band.n);
    ism_plain_dists(&many, (const double (*)[3])band.p, f, (const double (*)[3])g, BOUND,
                    batched, band.n);
    size_t stepped = 0;
    for (size_t i = 0; i < band.n; i++) {
        double gi[3], fi = ism_sample_grad(&one, band.p[i], gi);
        double scalar = ism_plain_dist(&one, band.p[i], fi, gi, BOUND);
        cr_assert(memcmp(&scalar, &batched[i], sizeof scalar) == 0,
                  "%s box %d point %zu (%.17g, %.17g, %.17g): one by one %.17g, batched %.17g",
                  surf->expr, which, i, band.p[i][0], band.p[i][1], band.p[i][2], scalar,
                  batched[i]);
        stepped += scalar > ism_first_order_dist(fi, gi);
    }
    cr_expect_gt(stepped, band.n / 2, "%s box %d: %zu of %zu points moved by the step",
                 surf->expr, which, stepped, band.n);
    free(f);
    free(g);
    free(batched);
    free(all.p);
    free(band.p);
    ism_eval_ws_free(one.ws);
    ism_eval_ws_free(many.ws);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

static void check_three_boxes(const pf_surface *s)
{
    for (int which = pf_first_box() - 1; which <= 1; which++)
        check_scalar_batched(s, which);
}

Test(stepped_dist, scalar_equals_batched_sphere) { check_three_boxes(&pf_unit_sphere); }

Test(stepped_dist, scalar_equals_batched_torus) { check_three_boxes(&pf_ring_torus); }

Test(stepped_dist, scalar_equals_batched_gyroid_ball) { check_three_boxes(&gyroid_ball); }

/* f = √x − √r, the plane x = r, whose Newton step from x = X0 > 4r lands at 2√(X0 r) − X0 < 0,
 * where √x has no value: the foot has no estimate. At X0 = 4.5 r, r = 2e-3, the first-order
 * distance 2 (X0 − √(X0 r)) = 9.51e-3 lies in the band of E = 1e-2. */
#define FOOT_R 2e-3
#define FOOT_X0 (4.5 * FOOT_R)
static const ism_param foot_r[] = {{"r", FOOT_R}};
static const pf_surface foot_less = {"sqrt(x) - sqrt(r)", foot_r, 1, NULL, 0};

/* The first-order distance at a point x = X0 of the plane x = X0 (closed form). */
static double foot_less_d1(void) { return 2 * (FOOT_X0 - sqrt(FOOT_X0 * FOOT_R)); }

Test(stepped_dist, no_foot_estimate_is_infinite_in_the_polygoniser)
{
    ism_tape *t = pf_compile(&foot_less);
    double p[1][3] = {{FOOT_X0, 0.3, -0.2}}, f[1], g[1][3], out[1];
    ism_sampler s = {.tape = t, .ws = ism_eval_ws_new(t), .dist_above = BOUND, .batch = true};
    ism_sample_grad_batch(&s, (const double (*)[3])p, f, g, 1);
    double d1 = ism_first_order_dist(f[0], g[0]);
    cr_assert_float_eq(d1, foot_less_d1(), 1e-12);
    cr_assert(ism_first_order_unsure(d1, BOUND), "d1 %g: in the band of %g", d1, BOUND);
    cr_expect(isinf(ism_plain_dist(&s, p[0], f[0], g[0], BOUND)));
    ism_plain_dists(&s, (const double (*)[3])p, f, (const double (*)[3])g, BOUND, out, 1);
    cr_expect(isinf(out[0]));
    /* the rule itself: a foot with f not finite, or ∇f vanishing where f is not 0 */
    double gz[3] = {0, 0, 0}, gx[3] = {1, 0, 0};
    cr_expect(isinf(ism_stepped_dist(d1, NAN, gx)));
    cr_expect(isinf(ism_stepped_dist(d1, 1e-3, gz)));
    cr_expect_eq(ism_stepped_dist(d1, 0, gz), d1, "f = 0 at the foot: on the surface");
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
}

/* One triangle of the plane x = x0 (v: its corners), its analysis under BOUND and without a
 * bound (one thread, no curvature). */
static void analyse_triangle(const pf_surface *surf, double x0, ism_analysis *bounded,
                             ism_analysis *plain)
{
    ism_tape *t = pf_compile(surf);
    ism_mesh m;
    ism_mesh_init(&m);
    const double v[3][3] = {{x0, 0, 0}, {x0, 0.1, 0}, {x0, 0, 0.1}};
    for (int k = 0; k < 3; k++)
        ism_mesh_add_vertex(&m, v[k], NULL);
    cr_assert(ism_mesh_add_triangle(&m, 0, 1, 2));
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.curvature = false;
    o.threads = 1;
    ism_error err;
    o.max_error = BOUND;
    cr_assert(ism_analyse(&m, t, &o, bounded, &err), "%s", err.message);
    o.max_error = 0;
    cr_assert(ism_analyse(&m, t, &o, plain, &err), "%s", err.message);
    ism_mesh_free(&m);
    ism_tape_free(t);
}

/* The bound moves only the maxima: the means and 99th percentiles are the same bits. */
static void expect_same_means(const ism_analysis *bounded, const ism_analysis *plain)
{
    cr_expect(memcmp(&bounded->mean_dist_centroid, &plain->mean_dist_centroid, sizeof(double)) == 0);
    cr_expect(memcmp(&bounded->p99_dist_centroid, &plain->p99_dist_centroid, sizeof(double)) == 0);
    cr_expect(memcmp(&bounded->mean_dist_midpoint, &plain->mean_dist_midpoint, sizeof(double)) == 0);
    cr_expect(memcmp(&bounded->p99_dist_midpoint, &plain->p99_dist_midpoint, sizeof(double)) == 0);
}

/* The analysis of one triangle of the plane x = X0 (every centroid and midpoint at d1 in the
 * band, its foot with no estimate), X0 − r from the surface x = r: under the bound the largest
 * centroid and midpoint figures are upper bounds of that distance, whatever bounds them (the
 * corners, or a point of the surface found); without the bound they are d1, the first-order
 * figure (closed form); the mean and 99th percentile are the same bits either way. */
Test(stepped_dist, no_foot_estimate_is_bounded_in_the_analysis)
{
    ism_analysis bounded, plain;
    analyse_triangle(&foot_less, FOOT_X0, &bounded, &plain);
    double d1 = foot_less_d1(), dist = FOOT_X0 - FOOT_R;
    cr_expect_geq(bounded.max_dist_centroid, dist * (1 - 1e-12));
    cr_expect_geq(bounded.max_dist_midpoint, dist * (1 - 1e-12));
    cr_expect_float_eq(plain.max_dist_centroid, d1, 1e-12);
    cr_expect_float_eq(plain.max_dist_midpoint, d1, 1e-12);
    expect_same_means(&bounded, &plain);
    ism_analysis_free(&bounded);
    ism_analysis_free(&plain);
}

/* f = min(x, b) + max(x − c, 0), 0 < b < c: the plane x = 0 (f = x up to b, then the
 * constant b up to c, then rising again with slope 1; only x = 0 is a zero), ∇f vanishing
 * where f = b is not 0 (no estimate) on the plateau b < x < c. From x = X0 = c + 5e-3 the
 * first-order distance f / |∇f| = b + X0 − c = 8e-3 lies in the band of E = 1e-2 (the plateau
 * makes it short) and Newton's foot lands at x = c − b, on the plateau: the foot has no
 * estimate while the true distance, X0 = 0.027, is beyond E. */
#define PLATEAU_B 3e-3
#define PLATEAU_C 0.022
#define PLATEAU_X0 0.027
static const ism_param plateau_bc[] = {{"b", PLATEAU_B}, {"c", PLATEAU_C}};
static const pf_surface plateau = {"min(x, b) + max(x - c, 0)", plateau_bc, 2, NULL, 0};

/* A point whose Newton foot has no estimate is not within the bound on the step's length
 * alone: where the true distance is beyond E and d1 within it, the analysis under E reads
 * the largest centroid and midpoint figures at least that distance (not met), while the
 * analysis without a bound reads d1 (the first-order figure, which falls short). */
Test(stepped_dist, no_foot_estimate_is_beyond_the_bound_in_the_analysis)
{
    double d1 = PLATEAU_B + PLATEAU_X0 - PLATEAU_C, foot = PLATEAU_X0 - d1;
    cr_assert(ism_first_order_unsure(d1, BOUND), "d1 %g: in the band of %g", d1, BOUND);
    cr_assert(foot > PLATEAU_B && foot < PLATEAU_C, "the foot x = %g: on the plateau", foot);
    cr_assert_gt(PLATEAU_X0, BOUND, "the true distance: beyond the bound");
    ism_analysis bounded, plain;
    analyse_triangle(&plateau, PLATEAU_X0, &bounded, &plain);
    cr_expect_geq(bounded.max_dist_centroid, PLATEAU_X0 * (1 - 1e-12));
    cr_expect_geq(bounded.max_dist_midpoint, PLATEAU_X0 * (1 - 1e-12));
    cr_expect_float_eq(plain.max_dist_centroid, d1, 1e-9 * d1);
    cr_expect_float_eq(plain.max_dist_midpoint, d1, 1e-9 * d1);
    expect_same_means(&bounded, &plain);
    ism_analysis_free(&bounded);
    ism_analysis_free(&plain);
}
