/* test_corner_memo.c — the octree build's memo of f and ∇f at node corners, kept by the
 * polygoniser for the cells of the round and the next rounds' builds (octree_build.h's
 * corner_memos, face_lines.c lattice_entry), holds f's own values: every point it holds
 * gives, bit for bit, what f's full tape evaluates there, though the build evaluated most of
 * them through a node's shortened tape (the gyroid in a ball: max() dropped on the way down;
 * a torus: no min/max, the full tape everywhere), in the box as given, shifted by 1e-3 and
 * by irrational fractions of a finest cell, on one and two threads. And the cells take those
 * values (ism_poly_stats.corner_values > 0) without changing the mesh: it is the scalar
 * reference path's (which keeps no such memo: corner_values 0), bit for bit. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/octree/cell_cache.h"
#include "core/octree/octree_build.h"
#include "poly_fixture.h"
#include "test_eval_surfaces.h"
#include "tests/unit/same_mesh.h"

#define MAX_DEPTH 6
#define MAX_ERROR 1e-2

/* f built over box (the grid MAX_DEPTH deep) down to max_depth on `threads` threads into
 * the caller's corner memos, which may hold an earlier build's entries. */
static void build_into(const ism_tape *t, const double box[6], int threads, int min_depth,
                       int max_depth, ism_point_entry *memos, ism_octree *tree)
{
    memset(tree, 0, sizeof *tree);
    ism_grid_init(&tree->grid, box, MAX_DEPTH);
    ism_octree_build_params p = {
        .tape = t,
        .min_depth = min_depth,
        .max_depth = max_depth,
        .thin_depth = MAX_DEPTH,
        .flatness = {.gradient_test = 0.9, .normal_cos = 0.9, .plane_frac = 0.05,
                     .abs_tol = 0.25 * ism_grid_cell_size(&tree->grid, MAX_DEPTH),
                     .double_root_eps = 1e-9, .double_root_iters = 25, .max_error = MAX_ERROR},
        .threads = threads,
        .max_nodes = (size_t)1 << 24,
        .corner_memos = memos,
    };
    memcpy(p.flatness.box, box, sizeof p.flatness.box);
    ism_octree_build_stats st;
    cr_assert_eq(ism_octree_build(tree, &p, &st), ISM_BUILD_OK);
}

/* f built over box on `threads` threads into the caller's corner memos, empty or (refill)
 * first filled by a coarser build with another min_depth on the same grid, as a later
 * round's build finds them; every entry held checked against f's full tape; returns how
 * many entries were held. */
static size_t check_memos(const ism_tape *t, const double box[6], int threads, bool refill)
{
    size_t per = (size_t)1 << ISM_CORNER_MEMO_BITS;
    ism_point_entry *memos = calloc((size_t)threads * per, sizeof *memos);
    cr_assert(memos);
    ism_octree tree;
    if (refill) {
        build_into(t, box, threads, 2, MAX_DEPTH - 2, memos, &tree);
        ism_octree_free(&tree);
    }
    build_into(t, box, threads, 3, MAX_DEPTH, memos, &tree);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert(ws);
    size_t held = 0;
    for (size_t i = 0; i < (size_t)threads * per; i++) {
        const ism_point_entry *e = &memos[i];
        if (!e->key)
            continue;
        int32_t ip[3];
        ism_lattice_point(e->key, ip);
        cr_assert_eq(ism_lattice_key(ip), e->key);
        /* held where its key's slot is (a cell finds it there) */
        cr_assert_eq(ism_point_find(memos + i / per * per, ISM_CORNER_MEMO_BITS, ip), e);
        double x[3], g[3];
        ism_grid_point(&tree.grid, (ism_ipt){{ip[0], ip[1], ip[2]}}, x);
        double f = ism_eval_gradient(t, ws, x[0], x[1], x[2], g);
        cr_assert(memcmp(&f, &e->f, sizeof f) == 0 && memcmp(g, e->g, sizeof g) == 0,
                  "(%d, %d, %d): the memo holds f %.17g, ∇f (%.17g, %.17g, %.17g); f's tape "
                  "gives %.17g, (%.17g, %.17g, %.17g)", ip[0], ip[1], ip[2], e->f, e->g[0],
                  e->g[1], e->g[2], f, g[0], g[1], g[2]);
        held++;
    }
    ism_eval_ws_free(ws);
    ism_octree_free(&tree);
    free(memos);
    return held;
}

Test(corner_memo, holds_f_own_values_bit_for_bit, .timeout = 120)
{
    const char *names[] = {"gyroid-ball", "torus"};
    for (size_t n = 0; n < 2; n++) {
        const test_surface *s = test_surface_named(names[n]);
        ism_tape *t = test_surface_compile(s);
        for (int w = pf_first_box(); w < 3; w++) {
            double box[6];
            pf_sweep_box(s->box, MAX_DEPTH, w, box);
            for (int threads = 1; threads <= 2; threads++)
                for (int refill = 0; refill < 2; refill++) {
                    size_t held = check_memos(t, box, threads, refill);
                    /* thousands of corners (the leaves alone have ~10^4) */
                    cr_expect_gt(held, 1000, "%s box %d, %d threads%s: %zu points held",
                                 s->name, w, threads, refill ? " (refilled)" : "", held);
                }
        }
        ism_tape_free(t);
    }
}

Test(corner_memo, cells_take_the_builds_values, .timeout = 120)
{
    const test_surface *s = test_surface_named("gyroid-ball");
    ism_tape *t = test_surface_compile(s);
    int dmax = 7 - pf_quick();
    for (int w = pf_first_box(); w < 3; w++) {
        double box[6];
        pf_sweep_box(s->box, dmax, w, box);
        double bound = 3e-3 * (box[3] - box[0]); /* takes rounds after the first (below) */
        ism_mesh ref, m;
        ism_poly_stats rs, st;
        test_mesh_of(t, box, dmax, bound, 1, true, &ref, &rs);
        cr_expect_eq(rs.corner_values, 0, "box %d: the scalar path took corner values", w);
        for (int threads = 1; threads <= 2; threads++) {
            test_mesh_of(t, box, dmax, bound, threads, false, &m, &st);
            cr_expect_gt(st.corner_values, 0, "box %d, %d threads: no corner value taken", w,
                         threads);
            /* the later rounds' builds read a memo the earlier rounds filled */
            cr_expect_gt(st.error_rounds, 0, "box %d, %d threads: one round only", w, threads);
            cr_expect(test_same_mesh(&ref, &m), "box %d, %d threads: the mesh differs (%zu / "
                      "%zu triangles)", w, threads, ref.ntris, m.ntris);
            ism_mesh_free(&m);
        }
        ism_mesh_free(&ref);
    }
    ism_tape_free(t);
}
