/* test_search_batch.c — the singular search with its children's interval gradients taken in
 * batches (search.c pre_gradients: a parent's children that classify will test, their
 * gradients over their boxes and at their centres in one ism_eval_interval_grad_batch)
 * against the same search taking them one by one (ism_sing_search_batched, batch false): the
 * same candidate boxes (bounds, projected centre, rank, flags) and the same counters, bit
 * for bit, and the batch ran (grads_batched > 0) and classify read every record it took
 * (grads_batch_read: a child batched that the centre test then drops wastes its lanes). A
 * batch record given to the wrong child or the box's gradient read for the centre's (g[k] /
 * g[n + k]) would move a box or a count here; so would, on tapes without kinks (boxes 8 to a
 * pass, then the centres of those whose gradient may vanish: search.c round_take), a centre's
 * gradient or a jet given to another slot. On those tapes each centre given to a batch is
 * one smooth_tests reads (centres_batch_read == centres_batched): a centre batched for a cell
 * whose ∇F over the box excludes 0, or one queued and left out of the last pass (taken again
 * alone, the same bits), would only cost, and is seen here. The cross-cap (pinch points and a
 * double segment: cells kept to the finest level along it), Kummer's 16 nodes and Barth's
 * sextic in its ball (kinks listed in the lanes), and one with two kinks on a cell (a cell
 * whose top kink is free along with another is not read from the top's pieces alone: search.c
 * top_kink_verdict), in three placements (pf_sweep_box). */
#include <criterion/criterion.h>
#include <string.h>
#include "poly_fixture.h"
#include "test_eval_surfaces.h"
#include "core/singular/search.h"
#include "core/util/sym3.h"

/* The search of t over box at depth, batched or not, into l (asserted complete). */
static void search(const ism_tape *t, const double box[6], int depth, bool batch, ism_locus *l)
{
    ism_locus_options o;
    ism_locus_options_default(&o);
    memcpy(o.box, box, sizeof o.box);
    o.max_depth = depth;
    o.threads = 1;
    ism_locus_init(l);
    ism_error err;
    cr_assert(ism_sing_search_batched(t, &o, batch, l, &err), "%s", err.message);
    cr_assert(!l->incomplete, "%s", l->incomplete_why);
}

/* What expect_same asks of a tape beyond batched == one by one. */
enum {
    SMOOTH_TAPE = 1,  /* no min, max or abs: every centre batched is read, and some are */
    CENTRE_DROPS = 2, /* the centre test drops some cells (parents with a model) */
};

static void expect_same(const ism_tape *t, const char *name, const double base[6], int depth,
                        int want)
{
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, depth, w, box);
        ism_locus a, b;
        search(t, box, depth, true, &a);
        search(t, box, depth, false, &b);
        cr_expect_gt(a.grads_batched, 0, "%s box %d: no gradient taken in a batch", name, w);
        cr_expect_eq(b.grads_batched, 0, "%s box %d: batched with the batch off", name, w);
        cr_expect_eq(a.grads_batch_read, a.grads_batched,
                     "%s box %d: %llu records batched, %llu read", name, w,
                     (unsigned long long)a.grads_batched, (unsigned long long)a.grads_batch_read);
        if (want & CENTRE_DROPS)
            cr_expect_gt(a.centre_dropped, 0, "%s box %d: the centre test dropped nothing", name,
                         w);
        if (want & SMOOTH_TAPE)
            cr_expect(a.centres_batch_read == a.centres_batched && a.centres_batched > 0,
                      "%s box %d: %llu centres batched, %llu read", name, w,
                      (unsigned long long)a.centres_batched,
                      (unsigned long long)a.centres_batch_read);
        else /* with kinks a box's centre goes with it, read or not */
            cr_expect_leq(a.centres_batch_read, a.centres_batched, "%s box %d: centres", name, w);
        cr_expect_eq(b.centres_batched, 0, "%s box %d: centres batched with the batch off",
                     name, w);
        cr_expect_eq(a.boxes_visited, b.boxes_visited, "%s box %d: cells visited", name, w);
        cr_expect_eq(a.evals_interval, b.evals_interval, "%s box %d: interval evaluations", name,
                     w);
        cr_expect_eq(a.evals_jet, b.evals_jet, "%s box %d: jets", name, w);
        cr_expect_eq(a.centre_dropped, b.centre_dropped, "%s box %d: centre drops", name, w);
        cr_expect(a.hessian_scale == b.hessian_scale, "%s box %d: Hessian scale", name, w);
        cr_expect_eq(a.nboxes, b.nboxes, "%s box %d: %zu boxes batched, %zu one by one", name, w,
                     a.nboxes, b.nboxes);
        cr_expect_gt(a.nboxes, 0, "%s box %d: no candidate box", name, w);
        for (size_t i = 0; i < a.nboxes && i < b.nboxes; i++) {
            const ism_lbox *p = &a.boxes[i], *q = &b.boxes[i];
            cr_expect(!memcmp(p->lo, q->lo, sizeof p->lo) && !memcmp(p->hi, q->hi, sizeof p->hi) &&
                          !memcmp(p->q, q->q, sizeof p->q) && p->rank == q->rank &&
                          p->flags == q->flags,
                      "%s box %d: candidate %zu differs", name, w, i);
        }
        ism_locus_free(&a);
        ism_locus_free(&b);
    }
}

Test(search_batch, cross_cap_batched_as_one_by_one)
{
    pf_surface s = {"4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)", NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double box[6] = {-1.3, -1.3, -1.6, 1.3, 1.3, 1.4};
    expect_same(t, "cross-cap", box, 6 - pf_quick(), SMOOTH_TAPE | CENTRE_DROPS);
    ism_tape_free(t);
}

Test(search_batch, kummer_16_nodes_batched_as_one_by_one)
{
    const test_surface *s = test_surface_named("kummer-16-nodes");
    ism_tape *t = test_surface_compile(s);
    expect_same(t, s->name, s->box, 7 - pf_quick(), SMOOTH_TAPE | CENTRE_DROPS);
    ism_tape_free(t);
}

/* The candidates of l that Newton left at their centre (neither projected nor unique): each
 * ranked by the Hessian there, evaluated here (search.c centre_rank reads it from the run's
 * first jet); returns how many. */
static size_t centres_ranked(const ism_tape *t, const ism_locus *l, const char *name, int w)
{
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    size_t n = 0;
    for (size_t i = 0; i < l->nboxes; i++) {
        const ism_lbox *b = &l->boxes[i];
        if (b->flags & (ISM_LBOX_PROJECTED | ISM_LBOX_UNIQUE))
            continue;
        double g[3], h[6], eig[3];
        ism_eval_hessian(t, ws, b->q[0], b->q[1], b->q[2], g, h);
        ism_sym3_eigen(h, eig, NULL);
        for (int k = 0; k < 3; k++)
            cr_expect(b->q[k] == b->lo[k] + 0.5 * (b->hi[k] - b->lo[k]),
                      "%s box %d: candidate %zu not at its centre", name, w, i);
        cr_expect_eq(b->rank, ism_sing_rank(eig, l->hessian_scale),
                     "%s box %d: candidate %zu ranked %d at its centre", name, w, i, b->rank);
        n++;
    }
    ism_eval_ws_free(ws);
    return n;
}

/* Barth's sextic in its ball: a max at the top, so classify lists kinks — the lanes take
 * them (ism_eval_interval_grad_lanes), the children of parents without a model in batches of
 * their boxes alone, and a kink at the top is read from the batch's lanes. */
Test(search_batch, barth_with_kinks_batched_as_one_by_one)
{
    ism_tape *t = pf_compile(&pf_barth_sextic);
    const double box[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    expect_same(t, "barth-sextic", box, 6 - pf_quick(), CENTRE_DROPS);
    ism_tape_free(t);
}

/* The cross-cap under abs, cut by a sphere with max: the abs is a free kink on every cell
 * the surface crosses, and the max's a second one at the top near the sphere. A cell with
 * both is not decided by the top's two pieces alone (search.c top_kink_verdict takes one free
 * kink only); one whose only free kink is the abs's (not at the top) goes the listed-kinks
 * way. The parents have no model (the top kink leaves them SURVIVES), so nothing is dropped by
 * the centre test. */
Test(search_batch, two_kinks_batched_as_one_by_one)
{
    pf_surface s = {"max(abs(4*x^2*(x^2 + y^2 + z^2 + z) + y^2*(y^2 + z^2 - 1)), "
                    "x^2 + y^2 + z^2 - 1.1)",
                    NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&s);
    const double box[6] = {-1.3, -1.3, -1.6, 1.3, 1.3, 1.4};
    expect_same(t, "two-kinks", box, 6 - pf_quick(), 0);
    ism_tape_free(t);
}

/* Barth's sextic in its ball, the candidates Newton does not converge in (the sextic's
 * gradient interval holds 0 where it has no zero): ranked at their centres as by a Hessian
 * taken there, in the three placements. */
Test(search_batch, barth_unconverged_ranked_at_their_centres)
{
    ism_tape *t = pf_compile(&pf_barth_sextic);
    const double base[6] = {-1.6, -1.6, -1.6, 1.6, 1.6, 1.6};
    int depth = 6 - pf_quick();
    for (int w = pf_first_box() - 1; w < 2; w++) {
        double box[6];
        pf_sweep_box(base, depth, w, box);
        ism_locus l;
        search(t, box, depth, true, &l);
        cr_expect_gt(centres_ranked(t, &l, "barth-sextic", w), 0,
                     "barth-sextic box %d: every candidate projected", w);
        ism_locus_free(&l);
    }
    ism_tape_free(t);
}
