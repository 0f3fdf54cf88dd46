/* test_analysis_curvature.c — the half of the analysis that evaluates f: curvature from the
 * gradient and Hessian (formula checks against hand-derived values, then whole meshes whose
 * vertices lie exactly on a sphere, a torus, a cone), singular points, distance estimates,
 * Newton distances, the projection step and thread-count independence. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/analysis/analysis.h"
#include "core/expr/expr.h"
#include "tests/unit/core/test_analysis_meshes.h"

static ism_tape *compile(const char *src, const ism_param *p, size_t np)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(src, p, np, NULL, 0, NULL, &err);
    cr_assert_not_null(t, "compile %s: %s", src, err.message);
    return t;
}

static ism_analysis analyse_with(const ism_mesh *m, const ism_tape *f,
                                 const ism_analysis_options *o)
{
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(m, f, o, &a, &err), "analysis failed: %s", err.message);
    return a;
}

static bool all_finite(const float *v, size_t n)
{
    for (size_t i = 0; i < n; i++)
        if (!isfinite(v[i]))
            return false;
    return true;
}

/* ---- the formulas alone (g and H written down by hand) ---- */

Test(analysis_curvature, sphere_formula)
{
    /* f = x²+y²+z²-r² at (r, 0, 0): g = (2r, 0, 0), H = 2I */
    double r = 3, g[3] = {2 * r, 0, 0}, h[6] = {2, 0, 0, 2, 0, 2}, mean, K, k1, k2;
    cr_assert(ism_curvature_from_derivatives(g, h, &mean, &K, &k1, &k2));
    cr_expect_float_eq(mean, 1 / r, 1e-14);
    cr_expect_float_eq(K, 1 / (r * r), 1e-14);
    cr_expect_float_eq(k1, 1 / r, 1e-7);
    cr_expect_float_eq(k2, 1 / r, 1e-7);
    /* r² - x² - y² - z²: the mean curvature changes sign, the Gaussian does not */
    double gn[3] = {-2 * r, 0, 0}, hn[6] = {-2, 0, 0, -2, 0, -2};
    cr_assert(ism_curvature_from_derivatives(gn, hn, &mean, &K, NULL, NULL));
    cr_expect_float_eq(mean, -1 / r, 1e-14);
    cr_expect_float_eq(K, 1 / (r * r), 1e-14);
}

Test(analysis_curvature, cylinder_and_saddle_formulas)
{
    /* x²+y²-r² at (r,0,0): g = (2r,0,0), H = diag(2,2,0): k1 = 1/r, k2 = 0, mean 1/(2r) */
    double r = 0.5, g[3] = {2 * r, 0, 0}, h[6] = {2, 0, 0, 2, 0, 0}, mean, K, k1, k2;
    cr_assert(ism_curvature_from_derivatives(g, h, &mean, &K, &k1, &k2));
    cr_expect_float_eq(mean, 1 / (2 * r), 1e-14);
    cr_expect_float_eq(K, 0.0, 1e-14);
    cr_expect_float_eq(k1, 1 / r, 1e-14);
    cr_expect_float_eq(k2, 0.0, 1e-14);
    /* z - xy at the origin: g = (0,0,1), H_xy = -1: K = -1, mean 0, k = ±1 */
    double gs[3] = {0, 0, 1}, hs[6] = {0, -1, 0, 0, 0, 0};
    cr_assert(ism_curvature_from_derivatives(gs, hs, &mean, &K, &k1, &k2));
    cr_expect_float_eq(mean, 0.0, 1e-14);
    cr_expect_float_eq(K, -1.0, 1e-14);
    cr_expect_float_eq(k1, 1.0, 1e-14);
    cr_expect_float_eq(k2, -1.0, 1e-14);
    /* scaling f by 1000 changes no curvature */
    double g3[3] = {2000 * r, 0, 0}, h3[6] = {2000, 0, 0, 2000, 0, 0};
    cr_assert(ism_curvature_from_derivatives(g3, h3, &mean, &K, NULL, NULL));
    cr_expect_float_eq(mean, 1 / (2 * r), 1e-12);
}

Test(analysis_curvature, vanishing_or_broken_derivatives_give_zeros)
{
    double g0[3] = {0, 0, 0}, h[6] = {2, 0, 0, 2, 0, 2}, mean = 7, K = 7, k1 = 7, k2 = 7;
    cr_expect(!ism_curvature_from_derivatives(g0, h, &mean, &K, &k1, &k2));
    cr_expect(mean == 0 && K == 0 && k1 == 0 && k2 == 0);
    double gnan[3] = {1, NAN, 0};
    cr_expect(!ism_curvature_from_derivatives(gnan, h, &mean, &K, &k1, &k2));
    cr_expect(mean == 0 && K == 0);
    double g[3] = {1, 0, 0}, hinf[6] = {INFINITY, 0, 0, 1, 0, 1};
    cr_expect(!ism_curvature_from_derivatives(g, hinf, &mean, &K, &k1, &k2));
    cr_expect(isfinite(mean) && isfinite(K));
}

/* ---- whole meshes ---- */

Test(analysis_curvature, icosphere_vertices_have_sphere_curvature)
{
    double r = 2;
    ism_param p = {"r", r};
    ism_tape *f = compile("x^2+y^2+z^2-r^2", &p, 1);
    ism_mesh m;
    ta_icosphere(&m, 4, r); /* 5120 triangles */
    ism_analysis a = analyse_with(&m, f, NULL);
    cr_assert_not_null(a.mean_curvature);
    for (size_t v = 0; v < m.nverts; v++) {
        cr_assert(fabs(a.mean_curvature[v] - 1 / r) <= 0.005 / r, "mean %g at %zu",
                  a.mean_curvature[v], v);
        cr_assert(fabs(a.gauss_curvature[v] - 1 / (r * r)) <= 0.005 / (r * r), "K %g at %zu",
                  a.gauss_curvature[v], v);
        cr_assert(fabs(a.k1[v] - 1 / r) <= 0.005 / r && fabs(a.k2[v] - 1 / r) <= 0.005 / r);
        cr_assert_eq(a.singular[v], 0);
    }
    cr_expect_eq(a.singular_vertices, 0);
    /* Gauss-Bonnet: ∫K dA = 2π χ = 4π */
    cr_expect(fabs(a.total_gauss - 4 * M_PI) <= 0.02 * 4 * M_PI, "∫K dA = %g",
              a.total_gauss);
    cr_expect_eq(a.euler, 2);
    /* |∇f| = 2r at every vertex, so the scale is 2r */
    cr_expect_float_eq(a.gradient_scale, 2 * r, 1e-9);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(analysis_curvature, torus_grid_integrates_to_zero)
{
    double R = 2, r = 0.5;
    ism_param p[2] = {{"R", R}, {"r", r}};
    ism_tape *f = compile("(x^2+y^2+z^2+R^2-r^2)^2 - 4*R^2*(x^2+y^2)", p, 2);
    ism_mesh m;
    ism_mesh_init(&m);
    int nu = 96, nv = 48;
    ta_torus(&m, nu, nv, R, r);
    ism_analysis a = analyse_with(&m, f, NULL);
    cr_expect_eq(a.singular_vertices, 0);
    /* pointwise: on the tube angle v, K = cos v / (r (R + r cos v)) and
     * mean = (R + 2 r cos v) / (2 r (R + r cos v)) */
    double kmax = 1 / (r * (R - r));
    for (int i = 0; i < nu; i++)
        for (int j = 0; j < nv; j++) {
            double v = 2 * M_PI * j / nv, c = cos(v);
            size_t k = (size_t)i * nv + j;
            double K = c / (r * (R + r * c)), H = (R + 2 * r * c) / (2 * r * (R + r * c));
            cr_assert(fabs(a.gauss_curvature[k] - K) <= 1e-4 * kmax, "K %g vs %g",
                      a.gauss_curvature[k], K);
            cr_assert(fabs(a.mean_curvature[k] - H) <= 1e-4 * H, "H %g vs %g",
                      a.mean_curvature[k], H);
        }
    /* Gauss-Bonnet: ∫K dA = 0, the outer +4π cancelling the inner -4π */
    cr_expect(fabs(a.total_abs_gauss - 8 * M_PI) <= 0.02 * 8 * M_PI, "∫|K| dA = %g",
              a.total_abs_gauss);
    cr_expect(fabs(a.total_gauss) <= 0.02 * 4 * M_PI, "∫K dA = %g", a.total_gauss);
    cr_expect_eq(a.genus, 1);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

/* Double cone x²+y² = z² made of two fans: the apex is singular (∇f = 0 there). */
static void check_cone_apex(const char *src)
{
    ism_tape *f = compile(src, NULL, 0);
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t apex = ta_vertex(&m, 0, 0, 0);
    ta_fan(&m, apex, 16, 1);
    ta_fan(&m, apex, 16, -1);
    ism_analysis a = analyse_with(&m, f, NULL);
    cr_expect_eq(a.singular[apex], 1, "%s: apex not flagged", src);
    cr_expect_eq(a.singular_vertices, 1, "%s: %zu singular", src, a.singular_vertices);
    cr_expect_eq(a.mean_curvature[apex], 0.0f);
    cr_expect_eq(a.gauss_curvature[apex], 0.0f);
    cr_expect(all_finite(a.mean_curvature, m.nverts) && all_finite(a.gauss_curvature, m.nverts));
    cr_expect(all_finite(a.k1, m.nverts) && all_finite(a.k2, m.nverts));
    cr_expect(all_finite(a.distance, m.nverts));
    cr_expect(isfinite(a.total_gauss) && isfinite(a.max_dist_vertex) &&
              isfinite(a.max_dist_centroid) && isfinite(a.max_newton_dist));
    cr_expect_geq(a.accuracy_skipped, 1);
    /* ring vertices lie on a cone of half-angle 45°: K = 0, mean = 1/(2 sqrt(2) ρ) at
     * radius ρ = 1 (principal curvature 1/(ρ sqrt 2) around, 0 along the ruling) */
    for (size_t v = 1; v < m.nverts; v++) {
        cr_expect_eq(a.singular[v], 0);
        cr_expect(fabs(a.gauss_curvature[v]) < 1e-9);
        cr_expect(fabs(fabs(a.mean_curvature[v]) - 1 / (2 * sqrt(2))) < 1e-6, "mean %g",
                  a.mean_curvature[v]);
    }
    cr_expect_eq(a.vertex_class[apex], ISM_VERTEX_NONMANIFOLD_POINT);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(analysis_curvature, cone_apex_is_singular_with_finite_outputs)
{
    check_cone_apex("x^2+y^2-z^2");
    /* the threshold is relative to f's scale: scaling f flags the same vertex */
    check_cone_apex("1e6*(x^2+y^2-z^2)");
    check_cone_apex("1e-6*(x^2+y^2-z^2)");
}

Test(analysis_curvature, nan_derivatives_are_singular_not_nan)
{
    /* sqrt(x²+y²) - |z| is the same cone; its derivatives at the apex are not finite */
    ism_tape *f = compile("sqrt(x^2+y^2)-abs(z)", NULL, 0);
    ism_mesh m;
    ism_mesh_init(&m);
    uint32_t apex = ta_vertex(&m, 0, 0, 0);
    ta_fan(&m, apex, 8, 1);
    ta_fan(&m, apex, 8, -1);
    ism_analysis a = analyse_with(&m, f, NULL);
    cr_expect_eq(a.singular[apex], 1);
    cr_expect(all_finite(a.mean_curvature, m.nverts) && all_finite(a.gauss_curvature, m.nverts));
    cr_expect(all_finite(a.k1, m.nverts) && all_finite(a.k2, m.nverts));
    cr_expect(all_finite(a.distance, m.nverts));
    cr_expect(isfinite(a.total_gauss) && isfinite(a.mean_dist_vertex));
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(analysis_accuracy, distances_of_a_sphere_one_percent_too_big)
{
    double r = 1.5, s = 1.01;
    ism_param p = {"r", r};
    ism_tape *f = compile("x^2+y^2+z^2-r^2", &p, 1);
    ism_mesh m;
    ta_icosphere(&m, 3, r * s);
    ism_analysis a = analyse_with(&m, f, NULL);
    /* at radius ρ = s r: |f| / |∇f| = (ρ² - r²) / (2ρ); Newton lands on the sphere: ρ - r */
    double rho = s * r, est = (rho * rho - r * r) / (2 * rho);
    cr_expect_float_eq(a.max_dist_vertex, est, 1e-9);
    cr_expect_float_eq(a.mean_dist_vertex, est, 1e-9);
    cr_expect_float_eq(a.max_newton_dist, rho - r, 1e-9);
    cr_expect_float_eq(a.mean_newton_dist, rho - r, 1e-9);
    /* centroids sit inside the radius-ρ sphere: |c| < ρ, estimate |(|c|² - r²)| / (2|c|) */
    double cmax = 0, csum = 0;
    for (size_t t = 0; t < m.ntris; t++) {
        double c[3] = {0, 0, 0};
        for (int k = 0; k < 3; k++)
            for (int i = 0; i < 3; i++)
                c[i] += m.pos[3 * m.tri[3 * t + k] + i] / 3;
        double len = sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]);
        double d = fabs(len * len - r * r) / (2 * len);
        cmax = fmax(cmax, d);
        csum += d;
    }
    cr_expect_float_eq(a.max_dist_centroid, cmax, 1e-9);
    cr_expect_float_eq(a.mean_dist_centroid, csum / m.ntris, 1e-9);
    cr_expect_eq(a.accuracy_skipped, 0);
    for (size_t v = 0; v < m.nverts; v++)
        cr_assert_float_eq(a.distance[v], est, 1e-6);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(analysis_accuracy, options_turn_parts_off)
{
    ism_tape *f = compile("x^2+y^2+z^2-1", NULL, 0);
    ism_mesh m;
    ta_icosphere(&m, 1, 1);
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.curvature = false;
    ism_analysis a = analyse_with(&m, f, &o);
    cr_expect_null(a.mean_curvature);
    cr_expect_not_null(a.distance);
    cr_expect_not_null(a.singular);
    ism_analysis_free(&a);
    o.curvature = true;
    o.accuracy = false;
    a = analyse_with(&m, f, &o);
    cr_expect_not_null(a.mean_curvature);
    cr_expect_null(a.distance);
    cr_expect_eq(a.max_dist_centroid, 0.0);
    ism_analysis_free(&a);
    a = analyse_with(&m, NULL, NULL); /* no f: connectivity and quality only */
    cr_expect_null(a.mean_curvature);
    cr_expect_null(a.singular);
    cr_expect_eq(a.euler, 2);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

Test(analysis_accuracy, same_figures_for_any_thread_count)
{
    ism_param p = {"r", 1};
    ism_tape *f = compile("x^2+y^2+z^2-r^2 + 0.1*sin(5*x)", &p, 1);
    ism_mesh m;
    ta_icosphere(&m, 4, 1);
    ism_analysis_options o;
    ism_analysis_options_default(&o);
    o.threads = 1;
    ism_analysis a = analyse_with(&m, f, &o);
    o.threads = 2;
    ism_analysis b = analyse_with(&m, f, &o);
    size_t n = m.nverts * sizeof(float);
    cr_expect_eq(memcmp(a.mean_curvature, b.mean_curvature, n), 0);
    cr_expect_eq(memcmp(a.gauss_curvature, b.gauss_curvature, n), 0);
    cr_expect_eq(memcmp(a.distance, b.distance, n), 0);
    cr_expect_eq(a.total_gauss, b.total_gauss);
    cr_expect_eq(a.mean_dist_centroid, b.mean_dist_centroid);
    cr_expect_eq(a.mean_newton_dist, b.mean_newton_dist);
    cr_expect_eq(a.max_dist_centroid, b.max_dist_centroid);
    ism_analysis_free(&a);
    ism_analysis_free(&b);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

/* ---- projection ---- */

Test(analysis_project, bumpy_sphere_lands_on_the_sphere)
{
    double r = 1.25;
    ism_param p = {"r", r};
    ism_tape *f = compile("x^2+y^2+z^2-r^2", &p, 1);
    ism_mesh m;
    ta_icosphere(&m, 3, r);
    for (size_t v = 0; v < m.nverts; v++) { /* radially in and out by 2% */
        double s = v % 2 ? 1.02 : 0.98;
        for (int k = 0; k < 3; k++)
            m.pos[3 * v + k] *= s;
        m.normal[3 * v] = m.normal[3 * v + 1] = m.normal[3 * v + 2] = 0;
    }
    ism_analysis a = analyse_with(&m, f, NULL);
    ism_projection pr;
    ism_error err;
    cr_assert(ism_analysis_project(&m, f, &a, NULL, &pr, &err), "%s", err.message);
    cr_expect_eq(pr.moved, m.nverts);
    cr_expect_eq(pr.kept_feature + pr.kept_singular + pr.kept_far, 0);
    cr_expect_float_eq(pr.max_move, 0.02 * r, 1e-9);
    for (size_t v = 0; v < m.nverts; v++) {
        const double *q = m.pos + 3 * v;
        double len = sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2]);
        cr_assert_float_eq(len, r, 1e-12);
        for (int k = 0; k < 3; k++) /* normal along ±∇f, i.e. radial */
            cr_assert_float_eq(fabs(m.normal[3 * v + k]), fabs(q[k] / len), 1e-6);
    }
    ism_analysis_free(&a);
    a = analyse_with(&m, f, NULL);
    cr_expect_lt(a.max_dist_vertex, 1e-12);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_tape_free(f);
}

static ism_projection project_disc(const char *src, ism_mesh *m)
{
    ism_tape *f = compile(src, NULL, 0);
    ism_mesh_init(m);
    ta_disc(m, 12); /* centre (class 0) and a ring of 12 boundary vertices at distance 1 */
    ism_analysis a = analyse_with(m, f, NULL);
    ism_projection pr;
    ism_error err;
    cr_assert(ism_analysis_project(m, f, &a, NULL, &pr, &err), "%s", err.message);
    ism_analysis_free(&a);
    ism_tape_free(f);
    return pr;
}

Test(analysis_project, only_manifold_vertices_move)
{
    ism_mesh m;
    ism_projection pr = project_disc("z-0.1", &m);
    cr_expect_eq(pr.moved, 1);
    cr_expect_eq(pr.kept_feature, 12);
    cr_expect_float_eq(m.pos[2], 0.1, 1e-15); /* the centre went up to the plane */
    for (size_t v = 1; v < m.nverts; v++)
        cr_expect_eq(m.pos[3 * v + 2], 0.0); /* the boundary stayed */
    cr_expect_float_eq(m.normal[2], 1.0, 1e-7);
    ism_mesh_free(&m);
}

Test(analysis_project, never_further_than_half_the_shortest_edge)
{
    ism_mesh m;
    ism_projection pr = project_disc("z-0.9", &m);
    cr_expect_eq(pr.moved, 0);
    cr_expect_eq(pr.kept_far, 1);
    cr_expect_eq(m.pos[2], 0.0);
    ism_mesh_free(&m);
}

Test(analysis_project, never_where_the_gradient_vanishes)
{
    ism_mesh m;
    ism_projection pr = project_disc("z^2", &m); /* a double plane: ∇f = 0 on it */
    cr_expect_eq(pr.moved, 0);
    cr_expect_eq(pr.kept_singular, 1);
    ism_mesh_free(&m);
}

Test(analysis_project, analysis_of_another_mesh_is_refused)
{
    ism_tape *f = compile("z", NULL, 0);
    ism_mesh m, other;
    ism_mesh_init(&m);
    ism_mesh_init(&other);
    ta_disc(&m, 6);
    ta_disc(&other, 7);
    ism_analysis a = analyse_with(&other, f, NULL);
    ism_projection pr;
    ism_error err;
    cr_expect(!ism_analysis_project(&m, f, &a, NULL, &pr, &err));
    cr_expect(strstr(err.message, "not of this mesh"), "%s", err.message);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    ism_mesh_free(&other);
    ism_tape_free(f);
}
