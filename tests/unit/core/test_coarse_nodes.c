/* test_coarse_nodes.c — certified nodes at coarse depths through the whole pipeline of
 * core/singular/surface.h (locus from f, polygoniser, conformance): kummer-4-nodes at depths
 * 3 and 4, in the preset box ±3 and in ±2.2, each as given and shifted off the octree lattice
 * as tests/bench/sweep_singular.py shifts it (1e-3, irrational fractions of a finest cell).
 * Before, cells 0.55-0.75 wide missed the small inner piece between the nodes and each node was
 * joined with one cone (χ 2, one component).
 *
 * What is asserted comes from the closed form, not from the code:
 *  - the nodes: f = (r² − μ²)² − λ pqrs with λ = (3μ² − 1)/(3 − μ²), p, q = w − z ∓ √2 x,
 *    r, s = w + z ± √2 y. On x = 0 (f is even in x), with u = y²: ∂f/∂u = 0 and f = 0 give
 *    u + z² − μ² = −λ(w − z)² and λ(w − z)² = (w + z)² − 2u, hence
 *    (3 + λ) z² + 2w(1 − λ) z + (1 + λ) w² − 2μ² = 0, whose discriminant is 0 for this λ
 *    (μ² = (3λ + 1)/(3 + λ)): z₀ = −w(1 − λ)/(3 + λ), y₀² = ((w + z₀)² − λ(w − z₀)²)/2. The
 *    nodes are (0, ±y₀, z₀), and by the symmetry x ↔ y, z ↔ −z, (±y₀, 0, −z₀); ∇f = 0 there
 *    is checked in long double below;
 *  - the topology: the real surface is two spheres (an outer shell and the inner piece
 *    spanned by the four nodes) meeting at the 4 nodes, each node a cone of two nappes, one
 *    on each sphere: χ = 2 + 2 − 4 = 0, two components through edges, no boundary, no
 *    non-manifold edge, 2 cones at each node (as the depth 5-7 meshes also show). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include "core/util/vec3.h"
#include "tests/unit/core/poly_fixture.h"
#include "tests/unit/core/test_eval_surfaces.h"

#define NODES 4

/* The four nodes in closed form (see the top of the file). */
static void kummer_nodes(double mu2, double w, double out[NODES][3])
{
    long double lam = (3.0L * mu2 - 1) / (3.0L - mu2);
    long double z0 = -w * (1 - lam) / (3 + lam);
    long double y0 = sqrtl(((w + z0) * (w + z0) - lam * (w - z0) * (w - z0)) / 2);
    const double n[NODES][3] = {{0, (double)y0, (double)z0}, {0, -(double)y0, (double)z0},
                                {(double)y0, 0, -(double)z0}, {-(double)y0, 0, -(double)z0}};
    for (int i = 0; i < NODES; i++)
        for (int k = 0; k < 3; k++)
            out[i][k] = n[i][k];
}

/* f and ∇f of the quartic in long double, to check the closed form is a singular point. */
static long double kummer_f(long double mu2, long double w, const long double p[3])
{
    long double lam = (3 * mu2 - 1) / (3 - mu2), s2 = sqrtl(2.0L);
    long double x = p[0], y = p[1], z = p[2], r = x * x + y * y + z * z - mu2;
    return r * r - lam * (w - z - s2 * x) * (w - z + s2 * x) * (w + z + s2 * y) *
                       (w + z - s2 * y);
}

static void expect_singular(double mu2, double w, const double n[3])
{
    const long double h = 1e-7L;
    long double p[3] = {n[0], n[1], n[2]}, g = 0;
    for (int k = 0; k < 3; k++) {
        long double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[k] += h;
        b[k] -= h;
        long double d = (kummer_f(mu2, w, a) - kummer_f(mu2, w, b)) / (2 * h);
        g += d * d;
    }
    cr_assert(fabsl(kummer_f(mu2, w, p)) < 1e-15L && sqrtl(g) < 1e-9L,
              "closed form (%g, %g, %g) is no singular point: f %Lg |grad f| %Lg", n[0], n[1],
              n[2], kummer_f(mu2, w, p), sqrtl(g));
}

static uint32_t vertex_at(const ism_mesh *m, const double p[3])
{
    for (size_t v = 0; v < m->nverts; v++)
        if (m->pos[3 * v] == p[0] && m->pos[3 * v + 1] == p[1] && m->pos[3 * v + 2] == p[2])
            return (uint32_t)v;
    return UINT32_MAX;
}

typedef struct tri_edge {
    uint32_t a, b, t;
} tri_edge;

static int cmp_edge(const void *x, const void *y)
{
    const tri_edge *e = x, *f = y;
    return e->a != f->a ? (e->a > f->a) - (e->a < f->a) : (e->b > f->b) - (e->b < f->b);
}

static uint32_t root(uint32_t *parent, uint32_t i)
{
    while (parent[i] != i)
        i = parent[i] = parent[parent[i]];
    return i;
}

/* Components of triangles joined through shared edges (not through a shared vertex alone:
 * two spheres meeting at nodes are two). */
static size_t edge_components(const ism_mesh *m)
{
    tri_edge *e = malloc((3 * m->ntris + 1) * sizeof *e);
    uint32_t *parent = malloc((m->ntris + 1) * sizeof *parent);
    cr_assert(e && parent);
    for (uint32_t t = 0; t < m->ntris; t++) {
        parent[t] = t;
        for (int k = 0; k < 3; k++) {
            uint32_t a = m->tri[3 * t + k], b = m->tri[3 * t + (k + 1) % 3];
            e[3 * t + k] = (tri_edge){a < b ? a : b, a < b ? b : a, t};
        }
    }
    qsort(e, 3 * m->ntris, sizeof *e, cmp_edge);
    for (size_t i = 1; i < 3 * m->ntris; i++)
        if (e[i].a == e[i - 1].a && e[i].b == e[i - 1].b)
            parent[root(parent, e[i].t)] = root(parent, e[i - 1].t);
    size_t n = 0;
    for (uint32_t t = 0; t < m->ntris; t++)
        n += root(parent, t) == t;
    free(e);
    free(parent);
    return n;
}

/* One run: 4 certified nodes within 1e-9 of the closed form, each one mesh vertex with 2
 * cones, χ 0, two components, closed, no non-manifold edge. */
static void check_run(const ism_tape *t, const double base[6], int d, int which,
                      const double want[NODES][3])
{
    double box[6];
    pf_sweep_box(base, d, which, box);
    ism_mesh m;
    ism_locus l;
    pf_run_surface(t, box, 3, d, &m, &l);
    const char *place = which < 0 ? "own" : which == 0 ? "1e-3" : "irr cell";
    double half = base[3];
    cr_expect_eq(l.npoints, NODES, "±%g d%d %s: %zu points", half, d, place, l.npoints);
    for (int i = 0; i < NODES; i++) {
        size_t hits = 0;
        for (size_t j = 0; j < l.npoints; j++) {
            const ism_sing_point *p = &l.points[j];
            if (ism_dist3(p->p, want[i]) > 1e-9)
                continue;
            hits++;
            cr_expect(p->certified && p->type == ISM_SING_NODE, "±%g d%d %s: node %d is %s%s",
                      half, d, place, i, p->certified ? "" : "uncertified ",
                      ism_sing_type_name(p->type));
            uint32_t v = vertex_at(&m, p->p);
            cr_expect_neq(v, UINT32_MAX, "±%g d%d %s: node %d is no vertex", half, d, place, i);
            if (v != UINT32_MAX)
                cr_expect_eq(pf_vertex_cones(&m, v), 2, "±%g d%d %s: node %d has %zu cones",
                             half, d, place, i, pf_vertex_cones(&m, v));
        }
        cr_expect_eq(hits, 1, "±%g d%d %s: node (%g, %g, %g) found %zu times", half, d, place,
                     want[i][0], want[i][1], want[i][2], hits);
    }
    pf_props pr;
    pf_measure(&m, t, &pr);
    cr_expect_eq(pr.euler, 0, "±%g d%d %s: χ %ld, want 2 + 2 − 4 = 0", half, d, place,
                 pr.euler);
    size_t pieces = edge_components(&m);
    cr_expect_eq(pieces, 2, "±%g d%d %s: %zu pieces (through edges)", half, d, place, pieces);
    cr_expect_eq(pr.components, 1, "±%g d%d %s: %zu components through vertices (the nodes "
                 "join the pieces)", half, d, place, pr.components);
    cr_expect_eq(pr.boundary_edges, 0, "±%g d%d %s: %zu boundary edges", half, d, place,
                 pr.boundary_edges);
    cr_expect_eq(pr.nonmanifold_edges, 0, "±%g d%d %s: %zu non-manifold edges", half, d, place,
                 pr.nonmanifold_edges);
    ism_locus_free(&l);
    ism_mesh_free(&m);
}

static void check_box(double half)
{
    const test_surface *s = &TEST_SURFACES[4];
    cr_assert_str_eq(s->name, "kummer-4-nodes");
    double want[NODES][3];
    kummer_nodes(s->params[0].value, s->params[1].value, want);
    for (int i = 0; i < NODES; i++)
        expect_singular(s->params[0].value, s->params[1].value, want[i]);
    ism_tape *t = test_surface_compile(s);
    const double base[6] = {-half, -half, -half, half, half, half};
    for (int d = 3; d <= 4; d++)
        for (int which = pf_first_box() - 1; which <= 1; which++)
            check_run(t, base, d, which, want);
    ism_tape_free(t);
}

/* The preset's box: cells 0.75 at depth 3. */
Test(coarse_nodes, kummer_4_nodes_box_3)
{
    check_box(3.0);
}

/* ±2.2: cells 0.55 at depth 3, whose edges never crossed the inner piece. */
Test(coarse_nodes, kummer_4_nodes_box_2_2)
{
    check_box(2.2);
}
