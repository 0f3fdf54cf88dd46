/* test_simplify.c — the error-bounded simplification (core/remesh/simplify.c), checked from
 * closed forms, never from the pass's own figures, in the lattice box and in boxes shifted off
 * the octree lattice by 1e-3 and by an irrational fraction of a finest cell:
 * - the unit sphere at E = 2e-3: every vertex, edge midpoint and triangle centroid within E of
 *   the sphere (|‖p‖ − 1|), χ = 2, one component, every triangle facing outward, no angle
 *   below the smaller of the raw mesh's smallest and 25°, and fewer triangles than any mesh
 *   whose vertices lie on the sphere can have within E: for a triangle inscribed in the unit
 *   sphere with sides a, b, c the centroid has |g|² = 1 − (a² + b² + c²)/9 (Euler's
 *   |OG|² = R² − (a² + b² + c²)/9 in its plane), so |g| ≥ 1 − E bounds a² + b² + c² by
 *   9(2E − E²), and Weitzenböck's a² + b² + c² ≥ 4√3 area bounds its area by (3√3/4)(2E − E²);
 *   the sphere's 4π takes that many, less 10% for the spherical triangles being larger than
 *   the flat ones (sides under 3√(2E) ≈ 0.19: a per cent or two);
 * - a cylinder of radius 1/2 cut by the box (two boundary circles): the same bounds, χ = 0,
 *   and the boundary — vertices and edges — bit for bit as the polygoniser made it;
 * - Steiner's Roman surface with its singular locus (χ = 5): non-manifold edges and their
 *   vertices bit for bit, one component, no boundary, vertices within E. */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/remesh/quality_pass.h"
#include "tests/unit/core/poly_fixture.h"

/* Relative slack on E for rounding in the closed forms (the pass measures with a Newton step,
 * accurate to third order in the distance). */
#define BOUND_SLACK 1e-6
/* No angle may fall below the smaller of this (degrees) and the raw mesh's smallest. */
#define SHAPE_FLOOR_DEG 25.0

typedef double (*distance_fn)(const double *p);

static double sphere_distance(const double *p)
{
    return fabs(sqrt(p[0] * p[0] + p[1] * p[1] + p[2] * p[2]) - 1);
}

static double cylinder_distance(const double *p)
{
    return fabs(sqrt(p[0] * p[0] + p[1] * p[1]) - 0.5);
}

static const double *V(const ism_mesh *m, uint32_t v) { return m->pos + 3 * (size_t)v; }

/* The largest distance over vertices, edge midpoints and centroids. */
static double worst_distance(const ism_mesh *m, distance_fn d)
{
    double worst = 0;
    for (size_t v = 0; v < m->nverts; v++)
        worst = fmax(worst, d(V(m, (uint32_t)v)));
    for (size_t t = 0; t < m->ntris; t++) {
        const uint32_t *c = m->tri + 3 * t;
        double g[3], mid[3];
        for (int j = 0; j < 3; j++)
            g[j] = (V(m, c[0])[j] + V(m, c[1])[j] + V(m, c[2])[j]) / 3;
        worst = fmax(worst, d(g));
        for (int k = 0; k < 3; k++) {
            for (int j = 0; j < 3; j++)
                mid[j] = 0.5 * (V(m, c[k])[j] + V(m, c[(k + 1) % 3])[j]);
            worst = fmax(worst, d(mid));
        }
    }
    return worst;
}

static double min_angle(const ism_mesh *m)
{
    double worst = 90;
    for (size_t t = 0; t < m->ntris; t++)
        worst = fmin(worst, pf_tri_min_angle(m, t));
    return worst;
}

/* Triangles whose normal points toward the axis or centre (outward is away from it: the
 * polygoniser winds by ∇f; a sliver's normal may be rounding noise, so the raw mesh may have
 * a few, which merges remove, never add); axis_only drops z (the cylinder). */
static size_t inward(const ism_mesh *m, bool axis_only)
{
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double nrm[3], g[3], dot = 0;
        pf_tri_normal(m, t, nrm);
        for (int j = 0; j < 3; j++)
            g[j] = (V(m, m->tri[3 * t])[j] + V(m, m->tri[3 * t + 1])[j] +
                    V(m, m->tri[3 * t + 2])[j]) / 3;
        for (int j = 0; j < (axis_only ? 2 : 3); j++)
            dot += nrm[j] * g[j];
        n += !(dot > 0);
    }
    return n;
}

/* An edge as its two end points' positions, the smaller (lexicographically) first. */
typedef struct placed {
    double p[6];
} placed;

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

static int cmp_point(const double *a, const double *b)
{
    for (int k = 0; k < 3; k++)
        if (a[k] != b[k])
            return a[k] < b[k] ? -1 : 1;
    return 0;
}

static int cmp_placed(const void *a, const void *b)
{
    const placed *x = a, *y = b;
    int c = cmp_point(x->p, y->p);
    return c ? c : cmp_point(x->p + 3, y->p + 3);
}

/* Edges of m used by exactly one triangle (nm false) or by three or more (nm true), placed
 * and sorted; returns how many. */
static size_t feature_edges(const ism_mesh *m, bool nm, placed **out)
{
    size_t ne = 3 * m->ntris, n = 0;
    uint64_t *key = malloc((ne + 1) * sizeof *key);
    cr_assert(key && (*out = malloc((ne + 1) * sizeof **out)));
    for (size_t t = 0; t < m->ntris; t++)
        for (int k = 0; k < 3; k++) {
            uint64_t a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            key[3 * t + k] = a < b ? a << 32 | b : b << 32 | a;
        }
    qsort(key, ne, sizeof *key, cmp_u64);
    for (size_t i = 0, j; i < ne; i = j) {
        for (j = i; j < ne && key[j] == key[i]; j++)
            ;
        if (nm ? j - i < 3 : j - i != 1)
            continue;
        const double *a = V(m, (uint32_t)(key[i] >> 32)), *b = V(m, (uint32_t)key[i]);
        if (cmp_point(a, b) > 0) {
            const double *s = a;
            a = b, b = s;
        }
        memcpy((*out)[n].p, a, 3 * sizeof *a);
        memcpy((*out)[n].p + 3, b, 3 * sizeof *b);
        n++;
    }
    free(key);
    qsort(*out, n, sizeof **out, cmp_placed);
    return n;
}

/* The same feature edges, bit for bit, before and after. */
static void expect_same_features(const ism_mesh *before, const ism_mesh *after, bool nm,
                                 const char *what)
{
    placed *a, *b;
    size_t na = feature_edges(before, nm, &a), nb = feature_edges(after, nm, &b);
    cr_expect_eq(na, nb, "%s: %zu %s edges before, %zu after", what, na,
                 nm ? "non-manifold" : "boundary", nb);
    cr_expect(na == nb && !memcmp(a, b, na * sizeof *a), "%s: the %s edges moved", what,
              nm ? "non-manifold" : "boundary");
    free(a);
    free(b);
}

static ism_mesh copy_mesh(const ism_mesh *m)
{
    ism_mesh c;
    ism_mesh_init(&c);
    cr_assert(ism_mesh_reserve(&c, m->nverts, m->ntris));
    memcpy(c.pos, m->pos, 3 * m->nverts * sizeof *c.pos);
    memcpy(c.tri, m->tri, 3 * m->ntris * sizeof *c.tri);
    c.nverts = m->nverts, c.ntris = m->ntris;
    return c;
}

/* One run: the service's meshing under e in box, a copy of the raw mesh, the simplification,
 * and the fixture's measures before and after. */
typedef struct run {
    ism_mesh m, raw;
    ism_locus l;
    pf_props before, after;
    ism_simplify_stats st;
} run;

static void run_case(const ism_tape *t, const double box[6], double e, int dmax, run *r)
{
    pf_run_surface_bounded(t, box, 3, dmax, e, &r->m, &r->l);
    r->raw = copy_mesh(&r->m);
    pf_measure(&r->m, t, &r->before);
    ism_error err;
    cr_assert(ism_simplify_pass(t, &r->l, NULL, e, NULL, &r->m, &r->st, &err), "%s",
              err.message);
    pf_measure(&r->m, t, &r->after);
}

static void run_free(run *r)
{
    ism_mesh_free(&r->raw);
    ism_mesh_free(&r->m);
    ism_locus_free(&r->l);
}

/* One smooth surface in one box: the bound, the topology, orientation, shape; returns the
 * triangles before and after in *nb, *na. */
static void smooth_case(const char *expr, distance_fn dist, bool axis_only, long euler,
                        double e, int dmax, int which, size_t *nb, size_t *na)
{
    const pf_surface s = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    /* the cylinder is cut by the box's z faces */
    const double base[6] = {-1.5, -1.5, axis_only ? -1 : -1.5, 1.5, 1.5, axis_only ? 1 : 1.5};
    double box[6];
    pf_sweep_box(base, dmax, which, box);
    run r;
    run_case(t, box, e, dmax, &r);
    const ism_mesh *m = &r.m;
    double angle_before = min_angle(&r.raw);
    char what[96];
    snprintf(what, sizeof what, "%s, box %d", expr, which);
    double worst = worst_distance(m, dist);
    cr_log_info("%s: %zu -> %zu triangles, worst distance %.4g (E %g), min angle %.1f -> %.1f",
                what, r.raw.ntris, m->ntris, worst, e, angle_before, min_angle(m));
    cr_expect_leq(worst, e * (1 + BOUND_SLACK), "%s: %.6g beyond E = %g", what, worst, e);
    cr_expect_eq(r.after.euler, euler, "%s: χ = %ld", what, r.after.euler);
    cr_expect_eq(r.before.euler, euler, "%s: χ = %ld before", what, r.before.euler);
    cr_expect_eq(r.after.components, r.before.components, "%s", what);
    cr_expect_eq(r.after.nonmanifold_edges, 0, "%s", what);
    size_t in_before = inward(&r.raw, axis_only), in_after = inward(m, axis_only);
    cr_expect_leq(in_after, in_before, "%s: %zu triangles face inward, %zu before", what,
                  in_after, in_before);
    cr_expect_geq(min_angle(m), fmin(angle_before, SHAPE_FLOOR_DEG) - 1e-9, "%s", what);
    expect_same_features(&r.raw, m, false, what);
    *nb = r.raw.ntris, *na = m->ntris;
    run_free(&r);
    ism_tape_free(t);
}

Test(simplify, sphere_within_bound_and_below_the_inscribed_floor)
{
    const double e = 2e-3;
    /* inscribed triangles within E of the unit sphere: area ≤ (3√3/4)(2E − E²), 10% off */
    double floor_count = 0.9 * 4 * M_PI / (3 * sqrt(3) / 4 * (2 * e - e * e));
    for (int which = pf_first_box() ? 1 : -1; which < 2; which++) {
        size_t nb, na;
        smooth_case("x^2 + y^2 + z^2 - 1", sphere_distance, false, 2, e, 9 - pf_quick(), which,
                    &nb, &na);
        cr_expect_lt((double)na, floor_count, "box %d: %zu triangles, the floor for vertices "
                     "on the sphere is %.0f", which, na, floor_count);
        cr_expect_leq(3 * na, nb, "box %d: %zu -> %zu", which, nb, na);
    }
}

Test(simplify, cylinder_keeps_its_box_boundary)
{
    for (int which = pf_first_box() ? 1 : -1; which < 2; which++) {
        size_t nb, na;
        smooth_case("x^2 + y^2 - 0.25", cylinder_distance, true, 0, 2e-3, 8 - pf_quick(), which,
                    &nb, &na);
        cr_expect_leq(2 * na, nb, "box %d: %zu -> %zu", which, nb, na);
    }
}

Test(simplify, steiner_keeps_its_double_lines)
{
    const pf_surface s = {"x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-1, -1, -1, 1, 1, 1}, e = 1e-2;
    int d = 6 - pf_quick();
    for (int which = pf_first_box() ? 1 : -1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        run r;
        run_case(t, box, e, d, &r);
        char what[64];
        snprintf(what, sizeof what, "steiner, box %d", which);
        cr_log_info("%s: %zu -> %zu triangles, %zu locked vertices", what, r.raw.ntris,
                    r.m.ntris, r.st.locked_vertices);
        /* RP² immersed with a triple point and six half-segments of double line: χ = 5 */
        cr_expect_eq(r.after.euler, 5, "%s: χ = %ld", what, r.after.euler);
        cr_expect_eq(r.before.euler, 5, "%s: χ = %ld before", what, r.before.euler);
        cr_expect_eq(r.after.components, 1, "%s", what);
        cr_expect_eq(r.after.boundary_edges, 0, "%s", what);
        cr_expect_gt(r.before.nonmanifold_edges, 0, "%s", what);
        expect_same_features(&r.raw, &r.m, true, what);
        cr_expect_leq(r.after.max_dist, e, "%s: a vertex %.3g from f = 0", what,
                      r.after.max_dist);
        cr_expect_lt(r.m.ntris, r.raw.ntris, "%s", what);
        run_free(&r);
    }
    ism_tape_free(t);
}

/* The torus (x² + y² + z² + R² − r²)² − 4R²(x² + y²), R = 1, r = 0.4, and its gradient, in
 * long double. */
#define TORUS_R 1.0L
#define TORUS_RR 0.4L
/* Newton's projection stops when a step is below this, or after NEWTON_STEPS. */
#define NEWTON_TOL 1e-15L
#define NEWTON_STEPS 50

static long double torus_f(const long double q[3], long double g[3])
{
    long double s = q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + TORUS_R * TORUS_R -
                    TORUS_RR * TORUS_RR;
    for (int k = 0; k < 3; k++)
        g[k] = 4 * s * q[k] - (k < 2 ? 8 * TORUS_R * TORUS_R * q[k] : 0);
    return s * s - 4 * TORUS_R * TORUS_R * (q[0] * q[0] + q[1] * q[1]);
}

/* How far p is from the torus, bounded from above: Newton's projection q <- q − f ∇f / |∇f|²
 * in long double lands on f = 0, so |q − p| is no less than the distance (a second method:
 * the pass measures with |f|/|∇f| and one step in double, never the landing point). */
static double torus_newton_distance(const double *p)
{
    long double q[3] = {p[0], p[1], p[2]}, g[3];
    for (int i = 0; i < NEWTON_STEPS; i++) {
        long double f = torus_f(q, g), g2 = g[0] * g[0] + g[1] * g[1] + g[2] * g[2];
        long double step = fabsl(f) / sqrtl(g2);
        for (int k = 0; k < 3; k++)
            q[k] -= f * g[k] / g2;
        if (step < NEWTON_TOL)
            break;
    }
    long double d2 = 0;
    for (int k = 0; k < 3; k++)
        d2 += (q[k] - p[k]) * (q[k] - p[k]);
    return (double)sqrtl(d2);
}

/* The quality pass run after the simplification keeps its bound: every vertex, edge midpoint
 * and centroid of the final mesh within E (issue 15: the error is measured between vertices).
 * The quality pass moves vertices and flips edges on the simplified mesh, whose vertices sit
 * off f = 0 and whose midpoints are at the bound. */
Test(simplify, quality_pass_after_keeps_the_bound)
{
    const pf_surface s = {"(x^2 + y^2 + z^2 + 1 - 0.16)^2 - 4*(x^2 + y^2)", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double base[6] = {-1.5, -1.5, -0.5, 1.5, 1.5, 0.5}, e = 3e-3;
    int d = 8 - pf_quick();
    for (int which = pf_first_box() ? 1 : -1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        run r;
        run_case(t, box, e, d, &r);
        double simplified = worst_distance(&r.m, torus_newton_distance);
        ism_remesh_stats rs;
        ism_error err;
        cr_assert(ism_quality_pass(t, &r.l, NULL, e, NULL, &r.m, &rs, &err), "%s", err.message);
        double worst = worst_distance(&r.m, torus_newton_distance);
        cr_log_info("torus, box %d: %zu -> %zu -> %zu triangles, worst distance %.6g after "
                    "the simplification, %.6g after the quality pass (E %g), %zu flips, %zu "
                    "moves", which, r.raw.ntris, r.st.triangles_after, r.m.ntris, simplified,
                    worst, e, rs.flips, rs.moves);
        cr_expect_leq(simplified, e * (1 + BOUND_SLACK), "box %d: simplified %.6g", which,
                      simplified);
        cr_expect_leq(worst, e * (1 + BOUND_SLACK), "box %d: %.6g beyond E = %g after the "
                      "quality pass", which, worst, e);
        run_free(&r);
    }
    ism_tape_free(t);
}
