/* test_round_reuse.c — the max_error rounds reuse the last round's work (the octree's
 * decisions, octree_build.h; the triangles of leaves its splits cannot have changed,
 * leaf_memo.h): the mesh and the counters are bit for bit those of rounds computed afresh
 * (fresh_rounds), on one and two threads, while f is evaluated less. The Klein bottle,
 * which crosses itself, √2 − 1 of a finest cell off the lattice; the gyroid in its ball (a
 * crease, 5 rounds) in the three placements (tests/unit/placements.h), where the leaves that
 * touch a split one at a corner alone are copied (leaf_memo.c strike); the torus on the
 * lattice (4 rounds) is checked the same way in test_polygonise_accuracy.c. */
#include <criterion/criterion.h>
#include <string.h>
#include "poly_fixture.h"

static const pf_surface klein = {
    "(x^2 + y^2 + z^2 + 2*y - 1)*((x^2 + y^2 + z^2 - 2*y - 1)^2 - 8*z^2) + "
    "16*x*z*(x^2 + y^2 + z^2 - 2*y - 1)",
    NULL, 0, NULL, 0};

static const ism_param gyroid_k[] = {{"k", 4}};
static const pf_surface gyroid_ball = {
    "max(sin(k*x)*cos(k*y) + sin(k*y)*cos(k*z) + sin(k*z)*cos(k*x), x^2 + y^2 + z^2 - 1.96)",
    gyroid_k, 1, NULL, 0};

typedef struct run_case {
    const pf_surface *s;
    double half;      /* the box is [-half, half]^3 ... */
    double cells;     /* ... shifted by this many finest cells, unless placed */
    double max_error;
    int max_depth;
    bool placed;      /* the box is instead pf_sweep_box's placement ... */
    int placement;    /* ... of this number (-1: as given) */
} run_case;

static void run(const ism_tape *t, const run_case *c, int threads, bool fresh, ism_mesh *m,
                ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    if (c->placed) {
        const double base[6] = {-c->half, -c->half, -c->half, c->half, c->half, c->half};
        pf_sweep_box(base, c->max_depth, c->placement, o.box);
    } else {
        double shift = c->cells * 2 * c->half / (1 << c->max_depth);
        for (int k = 0; k < 3; k++) {
            o.box[k] = -c->half + shift;
            o.box[3 + k] = c->half + shift;
        }
    }
    o.max_depth = c->max_depth;
    o.max_error = c->max_error;
    o.threads = threads;
    o.fresh_rounds = fresh;
    ism_error err;
    ism_mesh_init(m);
    cr_assert_eq(ism_polygonise(t, &o, m, st, &err), ISM_POLY_OK, "%s", err.message);
}

static void same_counts(const ism_poly_stats *a, const ism_poly_stats *b, const char *what)
{
    cr_expect_eq(a->error_rounds, b->error_rounds, "%s: rounds", what);
    cr_expect_eq(a->plotting_nodes, b->plotting_nodes, "%s: leaves", what);
    cr_expect_eq(a->polygons, b->polygons, "%s: polygons", what);
    cr_expect_eq(a->two_polygon_nodes, b->two_polygon_nodes, "%s: two-polygon nodes", what);
    cr_expect_eq(a->degenerate_polygons, b->degenerate_polygons, "%s: degenerate", what);
    cr_expect_eq(a->nonmanifold_lines, b->nonmanifold_lines, "%s: double lines", what);
    cr_expect_eq(a->open_chains, b->open_chains, "%s: open chains", what);
    cr_expect_eq(a->cracks_repaired, b->cracks_repaired, "%s: crack tiles", what);
    cr_expect_eq(a->crossed_faces, b->crossed_faces, "%s: crossed faces", what);
    cr_expect_eq(a->thin_searched, b->thin_searched, "%s: thin searches", what);
    cr_expect_eq(a->error_missed_nodes, b->error_missed_nodes, "%s: missed", what);
}

static void check(const run_case *c)
{
    ism_tape *t = pf_compile(c->s);
    ism_mesh fresh, reused;
    ism_poly_stats sf, sr;
    run(t, c, 1, true, &fresh, &sf);
    cr_assert_gt(sf.error_rounds, 0, "%s: no second round, nothing to reuse", c->s->expr);
    for (int threads = pf_quick() ? 2 : 1; threads <= 2; threads++) {
        run(t, c, threads, false, &reused, &sr);
        pf_same_mesh(&fresh, &reused, c->s->expr);
        same_counts(&sf, &sr, c->s->expr);
        cr_expect_lt(sr.evals_gradient, sf.evals_gradient, "%s, %d threads: %llu gradients "
                     "reusing, %llu afresh", c->s->expr, threads,
                     (unsigned long long)sr.evals_gradient,
                     (unsigned long long)sf.evals_gradient);
        ism_mesh_free(&reused);
    }
    ism_mesh_free(&fresh);
    ism_tape_free(t);
}

Test(round_reuse, klein_bottle_off_the_lattice_as_computed_afresh)
{
    check(&(run_case){&klein, 4, PF_IRR, 3e-3, 8, false, 0});
}

Test(round_reuse, gyroid_ball_in_three_placements_as_computed_afresh)
{
    for (int which = pf_first_box() - 1; which <= 1; which++)
        check(&(run_case){&gyroid_ball, 1.5, 0, 1.09e-2, 8, true, which});
}
