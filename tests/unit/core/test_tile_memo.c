/* test_tile_memo.c — the per-thread memos of walked tiles (cell_cache.h: quiet tiles and the
 * crossed-tile memo, whose hit copies a first walk's lines and counters) change no bit: a
 * mesh made with them is the mesh made when every node walks each of its tiles itself
 * (ism_poly_options.walk_every_tile), positions, normals and triangles, and the walk's
 * counters (open chains, singular points, crossed faces, lifted chords, face lines shared
 * by two polygons) are equal. Surfaces where the walk does most: the Klein bottle (many
 * crossed tiles, an X where its sheets cross), the Roman surface (double lines lying in
 * faces, a triple point), the Kummer surface (16 nodes: singular points), the gyroid in a
 * ball (a crease; under a bound it takes rounds after the first), each in its box,
 * moved by 1e-3 and by irrational fractions of a finest cell, with and without an error
 * bound (the gyroid's rounds: the memos are forgotten between rounds), on 1 and 2
 * threads. And the memos are really used: in every run tiles are found in both (counted
 * in ism_poly_stats' quiet_skips and tile_replays, both 0 without them), and the cells
 * evaluate f fewer times (over all these runs). The same comparison guards the walk's
 * shortcut for a tile quiet by its corners alone (face_lines.c quiet_by_corners: no point
 * between them, none zero, its four sides rootless), also off under walk_every_tile and
 * taken in every run (corner_quiets). And tile by tile: under walk_every_tile every tile's
 * answer from its corners is checked against its own full walk (face_lines.c
 * check_by_corners: quiet by its corners exactly when the walk collected the four corners
 * alone, looked at no segment and found no event), and no tile of any walk disagrees
 * (corner_mismatches), on surfaces of crossings, double lines, nodes and a crease in the
 * three placements, with many tiles quiet by their corners among them (corner_checks). */
#include <criterion/criterion.h>
#include "poly_fixture.h"
#include "test_eval_surfaces.h"
#include "tests/unit/same_mesh.h"

/* s meshed in box to depth 2..dmax under max_error (0: none) on `threads` threads, by the
 * primal cells (those that walk tiles), with the tile memos or without (walk_every_tile). */
static void mesh_of(const ism_tape *t, const double box[6], int dmax, double max_error,
                    int threads, bool walk_every_tile, ism_mesh *m, ism_poly_stats *st)
{
    ism_poly_options o;
    ism_poly_options_default(&o);
    o.dual = false;
    o.walk_every_tile = walk_every_tile;
    test_mesh_with(t, &o, box, dmax, max_error, threads, m, st);
}

Test(tile_memo, a_hit_is_the_fresh_walk_bit_for_bit, .timeout = 240)
{
    static const struct {
        const char *name;
        int dmax;
        double bound; /* max_error as a fraction of the box's side (0: none) */
        bool rounds;  /* the bound takes more than one round in some box (the memos are
                         forgotten between rounds); the Klein bottle's and the Roman
                         surface's first round ends at their depth.max */
    } cases[] = {
        {"klein-bottle", 6, 0, false},    {"klein-bottle", 8, 2e-3, false},
        {"steiner-roman", 6, 0, false},   {"steiner-roman", 7, 2e-3, false},
        {"kummer-16-nodes", 6, 0, false}, {"gyroid-ball", 7, 3e-3, true},
    };
    uint64_t evals[2] = {0, 0}; /* f and ∇f evaluations over all runs, with and without */
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const test_surface *s = test_surface_named(cases[c].name);
        ism_tape *t = test_surface_compile(s);
        int dmax = cases[c].dmax - pf_quick();
        uint64_t rounds = 0; /* rounds after the first, over the boxes and thread counts */
        for (int w = pf_first_box() - 1; w < 2; w++) {
            double box[6];
            pf_sweep_box(s->box, dmax, w, box);
            double bound = cases[c].bound * (box[3] - box[0]);
            for (int threads = 1; threads <= 2; threads++) {
                ism_mesh m[2];
                ism_poly_stats st[2];
                for (int every = 0; every < 2; every++)
                    mesh_of(t, box, dmax, bound, threads, every, &m[every], &st[every]);
                const char *n = s->name;
                cr_expect_gt(m[0].ntris, 500, "%s box %d E %g: %zu triangles", n, w, bound,
                             m[0].ntris);
                rounds += st[0].error_rounds;
                cr_expect(test_same_mesh(&m[0], &m[1]),
                          "%s box %d E %g, %d threads: the memo changed the mesh (%zu / %zu "
                          "triangles)", n, w, bound, threads, m[0].ntris, m[1].ntris);
                cr_expect_eq(st[0].open_chains, st[1].open_chains, "%s box %d", n, w);
                cr_expect_eq(st[0].singular_points, st[1].singular_points, "%s box %d", n, w);
                cr_expect_eq(st[0].crossed_faces, st[1].crossed_faces, "%s box %d", n, w);
                cr_expect_eq(st[0].lifted_chords, st[1].lifted_chords, "%s box %d", n, w);
                cr_expect_eq(st[0].nonmanifold_lines, st[1].nonmanifold_lines, "%s box %d", n,
                             w);
                /* the memos are asked and hit: quiet tiles skipped and crossed tiles copied
                 * (each face is walked from its two nodes), and never under walk_every_tile */
                cr_expect_gt(st[0].quiet_skips, 0, "%s box %d, %d threads: no quiet tile "
                             "skipped", n, w, threads);
                cr_expect_gt(st[0].tile_replays, 0, "%s box %d, %d threads: no tile replayed",
                             n, w, threads);
                cr_expect_gt(st[0].corner_quiets, 0, "%s box %d, %d threads: no tile quiet by "
                             "its corners", n, w, threads);
                cr_expect_eq(st[1].corner_quiets, 0, "%s box %d: walk_every_tile took a tile "
                             "as quiet by its corners", n, w);
                cr_expect_eq(st[1].corner_mismatches, 0, "%s box %d: %llu tiles' corners and "
                             "walks disagree", n, w, (unsigned long long)st[1].corner_mismatches);
                cr_expect_eq(st[1].quiet_skips, 0, "%s box %d: walk_every_tile skipped", n, w);
                cr_expect_eq(st[1].tile_replays, 0, "%s box %d: walk_every_tile replayed", n,
                             w);
                for (int every = 0; every < 2; every++)
                    evals[every] += st[every].evals_point + st[every].evals_gradient;
                ism_mesh_free(&m[0]);
                ism_mesh_free(&m[1]);
            }
        }
        if (cases[c].rounds)
            cr_expect_gt(rounds, 0, "%s under a bound: no round after the first", s->name);
        ism_tape_free(t);
    }
    /* over all runs, not per run: a skipped walk also leaves the lattice-point memo as it was,
     * so a later lookup may miss where the walk would have left its point (Kummer's lattice
     * box on one thread: 213,199 evaluations with the memos, 213,194 without) */
    cr_expect_lt(evals[0], evals[1], "the memos saved no evaluation (%llu >= %llu)",
                 (unsigned long long)evals[0], (unsigned long long)evals[1]);
}

/* Every tile's corners against its own walk (check_by_corners, under walk_every_tile): a tile
 * quiet by its corners walks idle (no point between its corners, no segment looked at, no
 * event), and a tile that walks idle is quiet by its corners. Each tile of each node is
 * walked (no memo), on one thread, in the three placements. */
/* The suite's two tests share one timeout: with 120 here beside the other's 240, Criterion's
 * runner itself (libcriterion 2.4, --jobs=2) left 48 bytes LeakSanitizer reported at exit, in
 * every run (3 of 3); with equal timeouts, none. */
Test(tile_memo, quiet_by_corners_exactly_when_the_walk_is_idle, .timeout = 240)
{
    static const struct {
        const char *name;
        int dmax; /* no bound: one round, whose stats ism_polygonise reports */
    } cases[] = {
        {"klein-bottle", 7}, {"steiner-roman", 6}, {"kummer-16-nodes", 6}, {"gyroid-ball", 7},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        const test_surface *s = test_surface_named(cases[c].name);
        ism_tape *t = test_surface_compile(s);
        int dmax = cases[c].dmax - pf_quick();
        for (int w = pf_first_box() - 1; w < 2; w++) {
            double box[6];
            pf_sweep_box(s->box, dmax, w, box);
            ism_mesh m;
            ism_poly_stats st;
            mesh_of(t, box, dmax, 0, 1, true, &m, &st);
            cr_expect_eq(st.corner_mismatches, 0, "%s box %d: %llu tiles whose corners and walk "
                         "disagree (%llu quiet by their corners)", s->name, w,
                         (unsigned long long)st.corner_mismatches,
                         (unsigned long long)st.corner_checks);
            /* the check is exercised: many tiles are quiet by their corners (17,687 to
             * 135,280 in these runs) */
            cr_expect_gt(st.corner_checks, 1000, "%s box %d: %llu tiles quiet by their corners",
                         s->name, w, (unsigned long long)st.corner_checks);
            ism_mesh_free(&m);
        }
        ism_tape_free(t);
    }
}
