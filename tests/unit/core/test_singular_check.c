/* test_singular_check.c — the mesh checked against the locus (core/singular/check.h) on a
 * circle of radius 1 traced, as the curve search does, at steps of 0.01 (a chord then bends
 * 1.25e-5 from the arc, over the 1e-6 × diagonal = 5.2e-6 of the box [-1.5, 1.5]³). A
 * non-manifold chain of 40 mesh vertices placed exactly on the circle, each half way between
 * two traced points (where a chord is farthest from the arc), is on the locus: no edge off.
 * A vertex moved off the circle by 1e-4, outwards or inwards, makes its two edges off and
 * its chain off, and the per-vertex flags name the same two edges. In the box as given and moved off the lattice (1e-3, irrational). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdlib.h>
#include "core/analysis/analysis.h"
#include "core/singular/check.h"
#include "poly_fixture.h"

#define TRACED 628    /* points of the traced circle: steps of 2π / 628 ≈ 0.0100 */
#define CHAIN 40      /* vertices of the mesh's chain round the circle */

/* The chain round the unit circle of z = 0: vertex k half a step past the traced point
 * nearest to angle 2π k / CHAIN (half way between two traced points), moved radially by
 * push[k]; each
 * chain edge is shared by three triangles (apexes above, below and outside), so the chain is
 * the mesh's one non-manifold curve. */
static void chain_mesh(ism_mesh *m, const double *push)
{
    ism_mesh_init(m);
    uint32_t v[CHAIN];
    for (int k = 0; k < CHAIN; k++) {
        int i = (int)lround((double)k * TRACED / CHAIN);
        double t = 2 * M_PI * (i + 0.5) / TRACED, r = 1 + push[k];
        double p[3] = {r * cos(t), r * sin(t), 0};
        v[k] = ism_mesh_add_vertex(m, p, NULL);
    }
    for (int k = 0; k < CHAIN; k++) {
        uint32_t a = v[k], b = v[(k + 1) % CHAIN];
        double t = 2 * M_PI * (k + 0.5) / CHAIN;
        double apex[3][3] = {{0.9 * cos(t), 0.9 * sin(t), 0.2},
                             {0.9 * cos(t), 0.9 * sin(t), -0.2},
                             {1.2 * cos(t), 1.2 * sin(t), 0}};
        for (int j = 0; j < 3; j++)
            cr_assert(ism_mesh_add_triangle(m, a, b, ism_mesh_add_vertex(m, apex[j], NULL)));
    }
}

static void traced_circle(ism_locus *l)
{
    ism_locus_init(l);
    ism_sing_curve c = {.kind = ISM_CURVE_DOUBLE, .closed = true, .n = TRACED,
                        .end_type = {ISM_END_BOX, ISM_END_BOX}, .end_point = {-1, -1}};
    c.xyz = malloc(3 * TRACED * sizeof *c.xyz);
    cr_assert_not_null(c.xyz);
    for (int i = 0; i < TRACED; i++) {
        double t = 2 * M_PI * i / TRACED;
        c.xyz[3 * i] = cos(t);
        c.xyz[3 * i + 1] = sin(t);
        c.xyz[3 * i + 2] = 0;
    }
    cr_assert(ism_locus_add_curve(l, &c));
}

/* Edges off and whether the one chain is on, for the chain pushed by push. */
static size_t edges_off(const double *push, const double box[6], bool *chain_on)
{
    ism_mesh m;
    chain_mesh(&m, push);
    ism_analysis a;
    ism_error err;
    cr_assert(ism_analyse(&m, NULL, NULL, &a, &err), "%s", err.message);
    cr_assert_eq(a.nonmanifold_edges, CHAIN);
    cr_assert_eq(a.ncurves, 1);
    ism_locus l;
    traced_circle(&l);
    ism_locus_check chk;
    cr_assert(ism_locus_check_mesh(&l, box, &m, &a, &chk, &err), "%s", err.message);
    cr_expect_eq(chk.nonmanifold_edges, CHAIN);
    size_t off = chk.nonmanifold_edges_off, by_vertex = 0;
    cr_expect_eq(chk.artefacts, off);
    /* the per-vertex flags name the same edges (the features JSON's off_edges) */
    for (uint32_t j = a.curve_start[0]; j + 1 < a.curve_start[1]; j++)
        by_vertex += !(chk.curve_vert_on[j] && chk.curve_vert_on[j + 1]);
    cr_expect_eq(by_vertex, off);
    *chain_on = chk.curve_on[0];
    ism_locus_check_free(&chk);
    ism_locus_free(&l);
    ism_analysis_free(&a);
    ism_mesh_free(&m);
    return off;
}

Test(singular_check, vertices_on_the_curve_between_traced_points_are_on)
{
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    for (int which = -1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, 7, which, box);
        double push[CHAIN] = {0};
        bool on;
        cr_expect_eq(edges_off(push, box, &on), 0, "box %d: on the circle", which);
        cr_expect(on, "box %d", which);
        for (int sign = -1; sign <= 1; sign += 2) {
            push[7] = sign * 1e-4;
            cr_expect_eq(edges_off(push, box, &on), 2, "box %d: vertex moved %+g", which,
                         push[7]);
            cr_expect(!on, "box %d", which);
        }
    }
}
