/* test_polygonise_folds.c — the raw mesh under max_error (no simplification) keeps the surface's
 * orientation in every triangle: a fan from a corner of a polygon that is not star-shaped from
 * it (a polygon running along a node's face) used to fold triangles over. Checked against the
 * closed-form outward normal of the unit sphere (p) and of the torus with radii 1 and 0.4 (p
 * minus its nearest point on the core circle), in the lattice box and the two shifted boxes:
 * every triangle's normal (from its winding) has a positive dot product with that direction at
 * its centroid. Before the fix: the sphere 4 turned over at depth 8 in the 0.37-cell box, the
 * torus 4 and 7 in the shifted boxes at depth 8. */
#include <criterion/criterion.h>
#include <math.h>

#include "tests/unit/core/poly_fixture.h"

/* The error bound the folds were seen at (the simplify tests' bound). */
#define FOLD_MAX_ERROR 2e-3
/* The finest depth (one less under ISOMESH_TEST_QUICK). */
#define FOLD_DEPTH 8

typedef void (*outward_fn)(const double p[3], double out[3]);

static void sphere_outward(const double p[3], double out[3])
{
    for (int k = 0; k < 3; k++)
        out[k] = p[k];
}

static void torus_outward(const double p[3], double out[3])
{
    double r = hypot(p[0], p[1]); /* > 0: the torus stays 0.6 away from the z axis */
    out[0] = p[0] - p[0] / r, out[1] = p[1] - p[1] / r, out[2] = p[2];
}

/* Triangles whose normal does not point outward at their centroid. */
static size_t turned_over(const ism_mesh *m, outward_fn outward)
{
    size_t n = 0;
    for (size_t t = 0; t < m->ntris; t++) {
        double nrm[3], g[3] = {0, 0, 0}, o[3];
        pf_tri_normal(m, t, nrm);
        for (int c = 0; c < 3; c++)
            for (int k = 0; k < 3; k++)
                g[k] += m->pos[3 * (size_t)m->tri[3 * t + c] + k] / 3;
        outward(g, o);
        n += !(nrm[0] * o[0] + nrm[1] * o[1] + nrm[2] * o[2] > 0);
    }
    return n;
}

static void expect_no_folds(const char *expr, const double base[6], outward_fn outward)
{
    pf_surface s = {.expr = expr};
    ism_tape *t = pf_compile(&s);
    int d = FOLD_DEPTH - pf_quick();
    for (int which = pf_first_box() ? 1 : -1; which < 2; which++) {
        double box[6];
        pf_sweep_box(base, d, which, box);
        ism_mesh m;
        ism_locus l;
        pf_run_surface_bounded(t, box, 3, d, FOLD_MAX_ERROR, &m, &l);
        cr_expect_gt(m.ntris, 1000, "%s box %d: %zu triangles", expr, which, m.ntris);
        size_t bad = turned_over(&m, outward);
        cr_expect_eq(bad, 0, "%s box %d depth %d: %zu of %zu triangles turned over", expr, which,
                     d, bad, m.ntris);
        ism_mesh_free(&m);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

Test(accuracy_folds, sphere_raw_mesh_faces_outward)
{
    const double base[6] = {-1.5, -1.5, -1.5, 1.5, 1.5, 1.5};
    expect_no_folds("x^2 + y^2 + z^2 - 1", base, sphere_outward);
}

Test(accuracy_folds, torus_raw_mesh_faces_outward)
{
    const double base[6] = {-1.5, -1.5, -0.75, 1.5, 1.5, 0.75};
    expect_no_folds("(sqrt(x^2 + y^2) - 1)^2 + z^2 - 0.16", base, torus_outward);
}
