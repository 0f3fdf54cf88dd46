/* test_singular_deadline.c — the singular stage under a deadline (locus.h's deadline_ms,
 * polygonise.h's deadline_ms through core/singular/surface.h): cut short, every stage says
 * the locus is incomplete and why, never returns a complete-looking answer, and the mesh is
 * still made. Steiner's Roman surface x²y² + y²z² + z²x² + xyz has work for every stage: 3
 * double lines on the axes (from its closed form: f = ∇f = 0 on each axis for |t| ≤ 1/2, the
 * rest of each axis a whisker), a triple point and 6 pinch points. Asserts flags and counts,
 * never wall time: inside one surgery the pass is stopped by its work budget, which the same
 * poll as the deadline checks. */
#include <criterion/criterion.h>
#include <string.h>

#include "core/octree/polygonise.h"
#include "core/singular/conform.h"
#include "core/singular/curves.h"
#include "core/singular/find.h"
#include "core/singular/points.h"
#include "core/singular/search.h"
#include "core/singular/surface.h"
#include "core/util/clock.h"

#define STEINER "x^2*y^2 + y^2*z^2 + z^2*x^2 + x*y*z"
/* Shallow depths: the deadline logic does not depend on them, the test's cost does. */
#define DMIN 3
#define DMAX 5

static ism_tape *compile(void)
{
    ism_error err;
    ism_tape *t = ism_tape_compile(STEINER, NULL, 0, NULL, 0, NULL, &err);
    cr_assert(t, "%s", err.message);
    return t;
}

static void poly_options(ism_poly_options *po)
{
    ism_poly_options_default(po);
    for (int k = 0; k < 3; k++) {
        po->box[k] = -0.6;
        po->box[k + 3] = 0.6;
    }
    po->min_depth = DMIN;
    po->max_depth = DMAX;
    po->threads = 1;
}

/* A deadline already passed by the time any stage looks at it (0 means none). */
static double passed(void)
{
    return ism_now_ms() - 1.0;
}

static bool says(const ism_locus *l, const char *word)
{
    return strstr(l->incomplete_why, word) != NULL;
}

/* The whole surface (core/singular/surface.h) with the given deadline (0: none); asserts
 * the mesh comes back. */
static void run_surface(double deadline_ms, ism_mesh *m, ism_locus *l, ism_conform_stats *cs)
{
    ism_tape *t = compile();
    ism_poly_options po;
    poly_options(&po);
    po.deadline_ms = deadline_ms;
    ism_mesh_init(m);
    ism_locus_init(l);
    ism_poly_stats ps;
    ism_surface_times tm;
    ism_error err;
    cr_assert_eq(ism_mesh_surface(t, &po, m, l, &ps, cs, &tm, &err), ISM_POLY_OK, "%s",
                 err.message);
    ism_tape_free(t);
}

/* The control: no deadline, the whole locus (3 double curves, conformed) and complete. */
Test(singular_deadline, none_gives_the_complete_locus)
{
    ism_mesh m;
    ism_locus l;
    ism_conform_stats cs;
    run_surface(0, &m, &l, &cs);
    cr_expect_not(l.incomplete, "incomplete without a deadline: %s", l.incomplete_why);
    size_t dbl = 0;
    for (size_t i = 0; i < l.ncurves; i++)
        dbl += l.curves[i].kind == ISM_CURVE_DOUBLE;
    cr_expect_geq(dbl, 3, "%zu double curves", dbl);
    cr_expect_eq(cs.curves_conformed, dbl);
    ism_locus_free(&l);
    ism_mesh_free(&m);
}

/* The whole surface with a deadline already passed: the mesh comes back (the polygoniser is
 * not cut), the locus says incomplete and why, and nothing was conformed. */
Test(singular_deadline, passed_deadline_cuts_the_whole_stage)
{
    ism_mesh m;
    ism_locus l;
    ism_conform_stats cs;
    run_surface(passed(), &m, &l, &cs);
    cr_expect(l.incomplete);
    cr_expect(says(&l, "deadline"), "why: %s", l.incomplete_why);
    cr_expect_eq(cs.curves_conformed + cs.points_conformed, 0);
    cr_expect_gt(m.ntris, 0, "the mesh is still made");
    ism_locus_free(&l);
    ism_mesh_free(&m);
}

/* The locus stages one by one, each given a passed deadline after the ones before it ran to
 * the end: each stops and names itself. */
static void locus_options(const ism_poly_options *po, ism_locus_options *lo)
{
    ism_locus_options_from_poly(po, lo);
    cr_assert_eq(lo->deadline_ms, po->deadline_ms, "the deadline reaches the locus options");
}

Test(singular_deadline, each_locus_stage_stops_and_says_so)
{
    ism_tape *t = compile();
    ism_poly_options po;
    poly_options(&po);
    ism_locus_options lo, late;
    locus_options(&po, &lo);
    late = lo;
    late.deadline_ms = passed();
    ism_error err;
    for (int stage = 0; stage < 3; stage++) {
        ism_locus l;
        ism_locus_init(&l);
        bool ok = ism_sing_search(t, stage == 0 ? &late : &lo, &l, &err) &&
                  (stage < 1 || ism_sing_points(t, stage == 1 ? &late : &lo, &l, &err)) &&
                  (stage < 2 || ism_sing_trace_curves(t, &late, &l, &err));
        cr_assert(ok, "%s", err.message);
        static const char *const name[3] = {"search", "certification", "curves"};
        cr_expect(l.incomplete, "stage %d not marked incomplete", stage);
        cr_expect(says(&l, name[stage]) && says(&l, "deadline"), "stage %d: %s", stage,
                  l.incomplete_why);
        if (stage == 2)
            cr_expect_eq(l.ncurves, 0, "a curve traced past the deadline");
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}

/* The conformance pass past its deadline: the complete locus and the polygoniser's mesh in,
 * the mesh left as it was (no surgery started), the locus marked incomplete naming the
 * double curves left. */
Test(singular_deadline, conformance_stops_and_leaves_the_mesh)
{
    ism_tape *t = compile();
    ism_poly_options po;
    poly_options(&po);
    ism_locus_options lo;
    locus_options(&po, &lo);
    ism_locus l;
    ism_locus_init(&l);
    ism_error err;
    cr_assert(ism_locus_find(t, &lo, &l, &err), "%s", err.message);
    cr_assert_not(l.incomplete, "%s", l.incomplete_why);
    ism_mesh m;
    ism_mesh_init(&m);
    ism_poly_stats ps;
    cr_assert_eq(ism_polygonise(t, &po, &m, &ps, &err), ISM_POLY_OK, "%s", err.message);
    size_t nt = m.ntris, nv = m.nverts;
    lo.deadline_ms = passed();
    ism_conform_stats cs;
    cr_assert(ism_conform_mesh(t, &lo, &l, &m, &cs, &err), "%s", err.message);
    cr_expect(l.incomplete);
    cr_expect(says(&l, "conformance") && says(&l, "deadline"), "why: %s", l.incomplete_why);
    cr_expect_eq(cs.curves_conformed + cs.points_conformed, 0);
    cr_expect_eq(m.ntris, nt);
    cr_expect_eq(m.nverts, nv);
    ism_mesh_free(&m);
    ism_locus_free(&l);
    ism_tape_free(t);
}

/* The locus and the polygoniser's mesh of the test surface, for the conformance pass. */
static void locus_and_mesh(const ism_tape *t, ism_locus_options *lo, ism_locus *l, ism_mesh *m)
{
    ism_poly_options po;
    poly_options(&po);
    locus_options(&po, lo);
    ism_locus_init(l);
    ism_error err;
    cr_assert(ism_locus_find(t, lo, l, &err), "%s", err.message);
    cr_assert_not(l->incomplete, "%s", l->incomplete_why);
    ism_mesh_init(m);
    ism_poly_stats ps;
    cr_assert_eq(ism_polygonise(t, &po, m, &ps, &err), ISM_POLY_OK, "%s", err.message);
}

/* Inside one surgery: Steiner's 6 double half-axes all meet at the triple point, so the pass
 * has ONE item (a group of curves cut and refilled at once). Without a limit it polls more
 * than once, once per ISM_CONFORM_POLL_WORK units at least; with a work budget of half what
 * that item needs (the deadline's stand-in that depends on no clock: the same poll stops
 * both) it stops in the middle of the item, undoes it — the mesh is the polygoniser's, byte
 * for byte — says why, and overruns the budget by less than one poll's worth. */
Test(singular_deadline, conformance_stops_inside_one_surgery)
{
    ism_tape *t = compile();
    ism_locus_options lo;
    ism_locus l;
    ism_mesh m;
    ism_error err;
    ism_conform_stats full;
    locus_and_mesh(t, &lo, &l, &m);
    cr_assert(ism_conform_mesh(t, &lo, &l, &m, &full, &err), "%s", err.message);
    cr_assert_eq(full.curves_conformed, 6, "%zu curves conformed", full.curves_conformed);
    cr_expect_eq(full.items_stopped, 0);
    cr_expect_geq(full.polls, full.work / ISM_CONFORM_POLL_WORK);
    cr_expect_geq(full.polls, 2, "one surgery of %zu units polled %zu times", full.work,
                  full.polls);
    ism_mesh_free(&m);
    ism_locus_free(&l);

    ism_mesh before;
    ism_locus unused;
    locus_and_mesh(t, &lo, &l, &m);
    locus_and_mesh(t, &lo, &unused, &before);
    ism_locus_free(&unused);
    /* half the surgery's work (the untangling after it, conform_refine.c, counts apart) */
    lo.conform_work_max = (full.work - full.refill_work) / 2;
    ism_conform_stats cut;
    cr_assert(ism_conform_mesh(t, &lo, &l, &m, &cut, &err), "%s", err.message);
    cr_expect(l.incomplete);
    cr_expect(says(&l, "conformance") && says(&l, "budget"), "why: %s", l.incomplete_why);
    cr_expect_eq(cut.items_stopped, 1);
    cr_expect_eq(cut.curves_conformed + cut.points_conformed, 0);
    cr_expect_gt(cut.work, ISM_CONFORM_POLL_WORK, "stopped before the surgery began");
    cr_expect_leq(cut.work, lo.conform_work_max + ISM_CONFORM_POLL_WORK);
    cr_log_info("one surgery: %zu units, %zu polls; budget %zu: stopped at %zu", full.work,
                full.polls, lo.conform_work_max, cut.work);
    cr_assert_eq(m.ntris, before.ntris);
    cr_assert_eq(m.nverts, before.nverts);
    cr_expect(memcmp(m.tri, before.tri, 3 * m.ntris * sizeof *m.tri) == 0, "triangles differ");
    cr_expect(memcmp(m.pos, before.pos, 3 * m.nverts * sizeof *m.pos) == 0, "positions differ");
    ism_mesh_free(&before);
    ism_mesh_free(&m);
    ism_locus_free(&l);
    ism_tape_free(t);
}
