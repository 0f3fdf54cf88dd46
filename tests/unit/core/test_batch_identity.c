/* test_batch_identity.c — the batched evaluation on the octree's path (the children's
 * intervals in one call, leaves proven free of f = 0 skipped: octree_build.c, zero_free.h)
 * changes no mesh: every example surface, in its box and √2 − 1 of a finest cell off the
 * lattice, and under an error bound (several rounds), gives bit for bit the mesh of the
 * node-by-node path (scalar_eval), on 1, 2 and 4 threads; and the batched path is really
 * taken (it evaluates f fewer times on the torus, where most leaves are zero-free). The
 * node-by-node path also keeps no memo of edge roots and crease labels between nodes
 * (cell_cache.h's ism_node_memo): under a bound, on a CSG sextic and the Klein bottle in
 * three boxes, the memos change no bit either and save evaluations. */
#include <criterion/criterion.h>
#include "poly_fixture.h"
#include "test_eval_surfaces.h"
#include "tests/unit/same_mesh.h"

#define DEPTH_MAX 4   /* a few hundred leaves a surface: about a second for the whole file */
#define SHIFT_CELLS PF_IRR

/* The scalar mesh on one thread against the batched one on 1, 2 and 4; returns the
 * evaluations (points + gradients) of the scalar and the one-thread batched run. */
static void check(const test_surface *s, const double box[6], int dmax, double max_error,
                  uint64_t evals[2])
{
    ism_tape *t = test_surface_compile(s);
    ism_mesh ref, m;
    ism_poly_stats st;
    test_mesh_of(t, box, dmax, max_error, 1, true, &ref, &st);
    evals[0] = st.evals_point + st.evals_gradient;
    cr_expect_gt(ref.ntris, 0, "%s: no triangles", s->name);
    const int threads[] = {1, 2, 4};
    for (size_t i = 0; i < sizeof threads / sizeof threads[0]; i++) {
        test_mesh_of(t, box, dmax, max_error, threads[i], false, &m, &st);
        if (i == 0)
            evals[1] = st.evals_point + st.evals_gradient;
        cr_expect(test_same_mesh(&ref, &m), "%s (box %g.., E %g): batched on %d threads differs",
                  s->name, box[0], max_error, threads[i]);
        ism_mesh_free(&m);
    }
    ism_mesh_free(&ref);
    ism_tape_free(t);
}

Test(batch_identity, every_surface_lattice_and_shifted)
{
    int dmax = DEPTH_MAX - pf_quick();
    for (size_t i = 0; i < TEST_NSURFACES; i++) {
        const test_surface *s = &TEST_SURFACES[i];
        for (int placed = pf_first_box(); placed < 3; placed += 2) { /* as given, PF_IRR off */
            double box[6];
            memcpy(box, s->box, sizeof box);
            double shift = placed ? SHIFT_CELLS * (box[3] - box[0]) / (1 << dmax) : 0;
            for (int k = 0; k < 6; k++)
                box[k] += shift;
            uint64_t evals[2];
            check(s, box, dmax, 0, evals);
        }
    }
}

/* Under an error bound the rounds take the last round's tree over (zero-free flags too).
 * gyroid-ball (a crease cut, no known locus: the batched path defers its leaves' measuring,
 * polygonise.c's measure_pending, the scalar one measures leaf by leaf) also in its box moved
 * by SHIFT_CELLS of a finest cell. */
Test(batch_identity, error_bound_rounds)
{
    static const char *names[] = {"torus", "gyroid-ball"};
    static const double bound[] = {3e-3, 1e-2};
    int dmax = 7 - pf_quick();
    for (size_t n = 0; n < 2; n++) {
        const test_surface *s = test_surface_named(names[n]);
        uint64_t evals[2];
        check(s, s->box, dmax, bound[n], evals);
        if (n == 0) /* the torus: half its leaves are skipped as zero-free */
            cr_expect_lt(evals[1], evals[0], "torus: batched path not taken (%llu >= %llu)",
                         (unsigned long long)evals[1], (unsigned long long)evals[0]);
        if (n == 1) {
            double box[6], shift = SHIFT_CELLS * (s->box[3] - s->box[0]) / (1 << dmax);
            for (int k = 0; k < 6; k++)
                box[k] = s->box[k] + shift;
            check(s, box, dmax, bound[n], evals);
        }
    }
}

/* The build's memos of edge roots and crease labels (under max_error: cell_error.c's roots,
 * plot_test.c's crease cells) are pure: Barth's nodal sextic cut by a ball (a max(): crease
 * labels) and the Klein bottle (roots only), each at a bound that takes a few hundred
 * tested nodes, in its box, moved by 1e-3 and by (sqrt 2 - 1) / 2 of a finest cell; the
 * mesh bit for bit that of the path without them on 1, 2 and 4 threads (a thread's memo
 * holds what its own nodes found: a schedule changes the hits, never a value). */
Test(batch_identity, node_memo_under_a_bound)
{
    static const test_surface surfaces[] = {
        {"barth-in-a-ball",
         "max(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
         "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2, x^2 + y^2 + z^2 - 2.25)",
         {{"phi", 1.6180339887498949}}, 1, {{0}}, 0, {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6}, 0},
        {"klein-bottle",
         "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
         "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
         {{0}}, 0, {{0}}, 0, {-4, -4, -4, 4, 4, 4}, 1},
    };
    static const double bound[] = {3e-2, 6e-2};
    int dmax = 7 - pf_quick();
    for (size_t i = 0; i < 2; i++) {
        const test_surface *s = &surfaces[i];
        double cell = (s->box[3] - s->box[0]) / (1 << dmax);
        const double shifts[] = {0, 1e-3, 0.5 * (1.4142135623730951 - 1) * cell};
        for (int b = pf_first_box(); b < 3; b++) {
            double box[6];
            for (int k = 0; k < 6; k++)
                box[k] = s->box[k] + shifts[b];
            uint64_t evals[2];
            check(s, box, dmax, bound[i], evals);
            cr_expect_lt(evals[1], evals[0], "%s box %d: no fewer evaluations (%llu >= %llu)",
                         s->name, b, (unsigned long long)evals[1], (unsigned long long)evals[0]);
        }
    }
}
