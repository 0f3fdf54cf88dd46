/* test_batch_identity.c — the batched evaluation on the octree's path (the children's
 * intervals in one call, leaves proven free of f = 0 skipped: octree_build.c, zero_free.h)
 * changes no mesh: every example surface, in its box and 0.37 of a finest cell off the
 * lattice, and under an error bound (several rounds), gives bit for bit the mesh of the
 * node-by-node path (scalar_eval), on 1, 2 and 4 threads; and the batched path is really
 * taken (it evaluates f fewer times on the torus, where most leaves are zero-free). */
#include <criterion/criterion.h>
#include <string.h>
#include "poly_fixture.h"
#include "test_eval_surfaces.h"

#define DEPTH_MAX 4   /* a few hundred leaves a surface: about a second for the whole file */
#define SHIFT_CELLS 0.37

static void mesh_of(const ism_tape *t, const double box[6], int dmax, double max_error,
                    int threads, bool scalar, ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.min_depth = 2;
    o.max_depth = dmax;
    o.max_error = max_error;
    o.threads = threads;
    o.scalar_eval = scalar;
    ism_error err;
    ism_mesh_init(m);
    cr_assert_eq(ism_polygonise(t, &o, m, st, &err), ISM_POLY_OK, "%s", err.message);
}

/* n bytes at p and q equal (either may be NULL when n is 0). */
static bool same_bytes(const void *p, const void *q, size_t n)
{
    return n == 0 || memcmp(p, q, n) == 0;
}

static bool same_mesh(const ism_mesh *a, const ism_mesh *b)
{
    return a->nverts == b->nverts && a->ntris == b->ntris && a->nsegs == b->nsegs &&
           same_bytes(a->pos, b->pos, a->nverts * 3 * sizeof *a->pos) &&
           same_bytes(a->normal, b->normal, a->nverts * 3 * sizeof *a->normal) &&
           same_bytes(a->tri, b->tri, a->ntris * 3 * sizeof *a->tri) &&
           same_bytes(a->seg, b->seg, a->nsegs * 2 * sizeof *a->seg);
}

/* The scalar mesh on one thread against the batched one on 1, 2 and 4; returns the
 * evaluations (points + gradients) of the scalar and the one-thread batched run. */
static void check(const test_surface *s, const double box[6], int dmax, double max_error,
                  uint64_t evals[2])
{
    ism_tape *t = test_surface_compile(s);
    ism_mesh ref, m;
    ism_poly_stats st;
    mesh_of(t, box, dmax, max_error, 1, true, &ref, &st);
    evals[0] = st.evals_point + st.evals_gradient;
    cr_expect_gt(ref.ntris, 0, "%s: no triangles", s->name);
    const int threads[] = {1, 2, 4};
    for (size_t i = 0; i < sizeof threads / sizeof threads[0]; i++) {
        mesh_of(t, box, dmax, max_error, threads[i], false, &m, &st);
        if (i == 0)
            evals[1] = st.evals_point + st.evals_gradient;
        cr_expect(same_mesh(&ref, &m), "%s (box %g.., E %g): batched on %d threads differs",
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
        for (int placed = pf_first_box(); placed < 3; placed += 2) { /* as given, 0.37 off */
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

/* Under an error bound the rounds take the last round's tree over (zero-free flags too). */
Test(batch_identity, error_bound_rounds)
{
    static const char *names[] = {"torus", "gyroid-ball"};
    static const double bound[] = {3e-3, 1e-2};
    for (size_t n = 0; n < 2; n++)
        for (size_t i = 0; i < TEST_NSURFACES; i++) {
            if (strcmp(TEST_SURFACES[i].name, names[n]) != 0)
                continue;
            uint64_t evals[2];
            check(&TEST_SURFACES[i], TEST_SURFACES[i].box, 7 - pf_quick(), bound[n], evals);
            if (n == 0) /* the torus: half its leaves are skipped as zero-free */
                cr_expect_lt(evals[1], evals[0], "torus: batched path not taken (%llu >= %llu)",
                             (unsigned long long)evals[1], (unsigned long long)evals[0]);
        }
}
