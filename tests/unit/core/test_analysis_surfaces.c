/* test_analysis_surfaces.c — the analysis on the polygoniser's own meshes of known surfaces:
 * curvature and Gauss-Bonnet on a sphere and a torus, Steiner's double lines along the three
 * axes meeting at the triple point, the four nodes of a Kummer surface, the Klein bottle's
 * self-intersection in the plane z = 0. Expected values come from the mathematics of each
 * surface. Shallower octrees under ISOMESH_TEST_QUICK=1 (the sanitizer run). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>

#include "core/analysis/analysis.h"
#include "core/eval/eval.h"
#include "core/octree/polygonise.h"

typedef struct surface {
    ism_tape *f;
    ism_mesh m;
    ism_analysis a;
    double cell; /* edge of a cell at max depth */
} surface;

static bool quick(void)
{
    const char *q = getenv("ISOMESH_TEST_QUICK");
    return q && *q == '1';
}

static void polygonise(surface *s, const char *src, const ism_param *p, size_t np,
                       const ism_let *lets, size_t nlets, double half, int depth)
{
    ism_error err;
    s->f = ism_tape_compile(src, p, np, lets, nlets, NULL, &err);
    cr_assert_not_null(s->f, "%s", err.message);
    ism_poly_options o;
    ism_poly_options_default(&o);
    for (int k = 0; k < 3; k++) {
        o.box[k] = -half;
        o.box[k + 3] = half;
    }
    o.max_depth = depth;
    s->cell = 2 * half / (1 << depth);
    ism_poly_stats st;
    ism_mesh_init(&s->m);
    cr_assert_eq(ism_polygonise(s->f, &o, &s->m, &st, &err), ISM_POLY_OK, "%s", err.message);
    cr_assert_gt(s->m.ntris, 0);
    cr_assert(ism_analyse(&s->m, s->f, NULL, &s->a, &err), "%s", err.message);
}

static void release(surface *s)
{
    ism_analysis_free(&s->a);
    ism_mesh_free(&s->m);
    ism_tape_free(s->f);
}

Test(analysis_surfaces, polygonised_sphere)
{
    double r = 1;
    ism_param p = {"r", r};
    surface s;
    polygonise(&s, "x^2+y^2+z^2-r^2", &p, 1, NULL, 0, 1.5, quick() ? 5 : 6);
    const ism_analysis *a = &s.a;
    cr_expect_eq(a->euler, 2);
    cr_expect_eq(a->genus, 0);
    cr_expect_eq(a->components, 1);
    cr_expect_eq(a->boundary_edges, 0);
    cr_expect_eq(a->nonmanifold_edges, 0);
    cr_expect_eq(a->nonmanifold_vertices, 0);
    cr_expect_eq(a->singular_vertices, 0);
    for (size_t v = 0; v < s.m.nverts; v++) {
        if (a->vertex_class[v] == ISM_VERTEX_ISOLATED)
            continue;
        cr_assert(fabs(a->mean_curvature[v] - 1 / r) <= 0.005 / r, "mean %g",
                  a->mean_curvature[v]);
        cr_assert(fabs(a->gauss_curvature[v] - 1 / (r * r)) <= 0.005 / (r * r), "K %g",
                  a->gauss_curvature[v]);
    }
    /* Gauss-Bonnet: 2πχ = 4π */
    cr_expect(fabs(a->total_gauss - 4 * M_PI) <= 0.02 * 4 * M_PI, "∫K dA = %g", a->total_gauss);
    cr_expect(fabs(a->area - 4 * M_PI * r * r) <= 0.02 * 4 * M_PI * r * r, "area %g", a->area);
    cr_expect_lt(a->max_dist_vertex, 1e-6 * r);
    release(&s);
}

Test(analysis_surfaces, polygonised_torus)
{
    double R = 1, r = 0.3;
    ism_param p[2] = {{"R", R}, {"r", r}};
    surface s;
    polygonise(&s, "(x^2+y^2+z^2+R^2-r^2)^2 - 4*R^2*(x^2+y^2)", p, 2, NULL, 0, 1.5,
               quick() ? 5 : 6);
    const ism_analysis *a = &s.a;
    cr_expect_eq(a->euler, 0);
    cr_expect_eq(a->genus, 1);
    cr_expect_eq(a->boundary_edges, 0);
    cr_expect_eq(a->nonmanifold_edges, 0);
    /* Gauss-Bonnet: ∫K dA = 0; the outer half gives +4π and the inner half -4π */
    cr_expect(fabs(a->total_abs_gauss - 8 * M_PI) <= 0.03 * 8 * M_PI, "∫|K| dA = %g",
              a->total_abs_gauss);
    cr_expect(fabs(a->total_gauss) <= 0.02 * 4 * M_PI, "∫K dA = %g", a->total_gauss);
    cr_expect(fabs(a->area - 4 * M_PI * M_PI * R * r) <= 0.02 * 4 * M_PI * M_PI * R * r,
              "area %g", a->area);
    release(&s);
}

/* Which coordinate axis p lies on (exactly: the polygoniser puts roots of f on cell edges),
 * or -1. */
static int on_axis(const double *p)
{
    for (int k = 0; k < 3; k++)
        if (p[(k + 1) % 3] == 0 && p[(k + 2) % 3] == 0)
            return k;
    return -1;
}

Test(analysis_surfaces, steiner_double_lines_on_the_three_axes)
{
    /* x²y² + y²z² + z²x² + xyz: two sheets cross along each axis for |t| <= 1/2, where the
     * double lines end at pinch points; the three meet at the triple point, the origin. On
     * the axes ∇f = 0: the double lines are singular. */
    surface s;
    polygonise(&s, "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", NULL, 0, NULL, 0, 1,
               quick() ? 5 : 6);
    const ism_analysis *a = &s.a;
    cr_expect_geq(a->ncurves, 6); /* at least the six half-axes, broken at the origin */
    double lo[3] = {0, 0, 0}, hi[3] = {0, 0, 0};
    for (size_t i = 0; i < a->curve_start[a->ncurves]; i++) {
        uint32_t v = a->curve_verts[i];
        const double *p = s.m.pos + 3 * v;
        int k = on_axis(p);
        if (k < 0)
            continue;
        lo[k] = fmin(lo[k], p[k]);
        hi[k] = fmax(hi[k], p[k]);
        cr_expect_eq(a->singular[v], 1, "double-line vertex (%g %g %g) not singular", p[0],
                     p[1], p[2]);
    }
    for (int k = 0; k < 3; k++)
        cr_expect(lo[k] <= -0.5 + 2 * s.cell && hi[k] >= 0.5 - 2 * s.cell,
                  "axis %d double line spans only [%g, %g]", k, lo[k], hi[k]);
    bool triple_point = false;
    for (size_t i = 0; i < a->npoints; i++) {
        const double *p = a->point_pos + 3 * i;
        if (p[0] == 0 && p[1] == 0 && p[2] == 0)
            triple_point = a->point_kind[i] == ISM_POINT_JUNCTION;
    }
    cr_expect(triple_point, "the origin is not a junction of non-manifold curves");
    release(&s);
}

/* Newton on ∇f = 0 (steps x -= H⁻¹ ∇f) from p; returns |∇f| at the end and moves p. */
static double find_critical_point(const ism_tape *f, double p[3])
{
    ism_eval_ws *ws = ism_eval_ws_new(f);
    cr_assert_not_null(ws);
    double g[3], h[6];
    for (int it = 0; it < 30; it++) {
        ism_eval_hessian(f, ws, p[0], p[1], p[2], g, h);
        double m[3][3] = {{h[0], h[1], h[2]}, {h[1], h[3], h[4]}, {h[2], h[4], h[5]}};
        double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                     m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                     m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
        if (fabs(det) < 1e-300)
            break;
        double d[3];
        for (int c = 0; c < 3; c++) { /* Cramer's rule: column c replaced by g */
            double n[3][3];
            for (int i = 0; i < 3; i++)
                for (int j = 0; j < 3; j++)
                    n[i][j] = j == c ? g[i] : m[i][j];
            d[c] = (n[0][0] * (n[1][1] * n[2][2] - n[1][2] * n[2][1]) -
                    n[0][1] * (n[1][0] * n[2][2] - n[1][2] * n[2][0]) +
                    n[0][2] * (n[1][0] * n[2][1] - n[1][1] * n[2][0])) / det;
        }
        for (int k = 0; k < 3; k++)
            p[k] -= d[k];
    }
    ism_eval_gradient(f, ws, p[0], p[1], p[2], g);
    ism_eval_ws_free(ws);
    return sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
}

Test(analysis_surfaces, kummer_nodes_are_non_manifold_features)
{
    /* the paper's Fig. 5(a): four nodes (double points, ∇f = 0 on f = 0) where parts meet */
    ism_param p[2] = {{"mu2", 0.6667}, {"w", 1}};
    ism_let lets[5] = {{"lambda", "(3*mu2 - 1)/(3 - mu2)"}, {"p", "w - z - sqrt(2)*x"},
                       {"q", "w - z + sqrt(2)*x"}, {"r", "w + z + sqrt(2)*y"},
                       {"s", "w + z - sqrt(2)*y"}};
    surface s;
    /* depth 7 in both runs: at depth 6 the octree misses the nodes */
    polygonise(&s, "(x^2 + y^2 + z^2 - mu2)^2 - lambda*p*q*r*s", p, 2, lets, 5, 3, 7);
    const ism_analysis *a = &s.a;
    cr_assert_gt(a->npoints, 0);
    /* every non-manifold point lies within a cell of a node; count the distinct nodes */
    double nodes[16][3];
    int nnodes = 0;
    for (size_t i = 0; i < a->npoints; i++) {
        double q[3] = {a->point_pos[3 * i], a->point_pos[3 * i + 1], a->point_pos[3 * i + 2]};
        double start[3] = {q[0], q[1], q[2]};
        double grad = find_critical_point(s.f, q);
        double d = sqrt(pow(q[0] - start[0], 2) + pow(q[1] - start[1], 2) +
                        pow(q[2] - start[2], 2));
        ism_eval_ws *ws = ism_eval_ws_new(s.f);
        double fv = ism_eval_point(s.f, ws, q[0], q[1], q[2]);
        ism_eval_ws_free(ws);
        cr_expect(grad < 1e-9 && fabs(fv) < 1e-9 && d <= 2 * s.cell,
                  "point (%g %g %g) is %g from a critical point with f = %g, |∇f| = %g",
                  start[0], start[1], start[2], d, fv, grad);
        int j = 0;
        while (j < nnodes && sqrt(pow(q[0] - nodes[j][0], 2) + pow(q[1] - nodes[j][1], 2) +
                                  pow(q[2] - nodes[j][2], 2)) > 1e-6)
            j++;
        if (j == nnodes && nnodes < 16) {
            for (int k = 0; k < 3; k++)
                nodes[nnodes][k] = q[k];
            nnodes++;
        }
    }
    cr_expect_eq(nnodes, 4, "non-manifold points gather at %d nodes", nnodes);
    release(&s);
}

Test(analysis_surfaces, klein_bottle_self_intersection_lies_in_z_0)
{
    surface s;
    polygonise(&s,
               "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2)"
               " + 16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
               NULL, 0, NULL, 0, 4, quick() ? 5 : 6);
    const ism_analysis *a = &s.a;
    cr_expect_gt(a->nonmanifold_edges, 0);
    cr_expect_gt(a->ncurves, 0);
    for (size_t i = 0; i < a->curve_start[a->ncurves]; i++) {
        const double *p = s.m.pos + 3 * a->curve_verts[i];
        cr_expect(fabs(p[2]) <= s.cell, "curve vertex (%g %g %g) off the plane z = 0", p[0],
                  p[1], p[2]);
    }
    release(&s);
}
