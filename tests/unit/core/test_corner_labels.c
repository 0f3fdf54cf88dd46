/* test_corner_labels.c — the flatness test's crease labels through the build's label memo
 * (plot_test.c corner_branch): where a corner's labelled branch is the one f's own derivative
 * follows, the memo keeps the corner's ∇f as that branch's gradient instead of evaluating it
 * (ism_crease_branch). Checked on every level-4 node of Barth's sextic in its ball and of the
 * gyroid in its ball (box ±1.6, depth 6), in the three placements (pf_sweep_box), the
 * corners' ∇f taken as the build takes them (ism_point_memo_many: the batch evaluator): each memo
 * gradient equals, bit for bit, the one ism_crease_branch evaluates at that corner, and each
 * node's verdict (ism_plot_test, and its blind flag) is the one it gets with no memo at all,
 * and, with each corner's ∇f marked one ulp off, some distinct points keep the marked ∇f as
 * branch 0's and some as branch 1's (copied_by_branch: the memo takes k->g on both arms).
 * And at a tie (a == b at a corner: f's derivative takes b, the label a; test_plot_test_tie.c's
 * node, and the same through a top min) the memo keeps no gradient there, or only the
 * labelled branch's — f's (0 there) would be the wrong one and would let the node pass
 * without the certificate. Barth's sextic is swept through a top min as well (barth_min). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/octree/cell_cache.h"
#include "core/octree/crease_split.h"
#include "core/octree/grid.h"
#include "core/octree/plot_test.h"
#include "poly_fixture.h"

#define DEPTH 6  /* the lattice: 64 steps an axis */
#define LEVEL 4  /* the nodes tested: 16^3, 4 steps across */
#define HALF 1.6 /* the box: ±1.6 (both balls, r 1.5, inside) */
/* The sweep's point memo: 2^19 slots for the lattice's 65^3 points, so that nearly every
 * corner stays (the build's ISM_CORNER_MEMO_BITS table evicts more; either is bit for bit). */
#define POINT_BITS 19

/* The build's three node memos, zeroed (cell_cache.h). */
typedef struct memos {
    ism_root_entry *roots;
    ism_label_entry *labels;
    ism_pair_entry *pairs;
    ism_node_memo memo;
} memos;

static void memos_new(memos *m)
{
    m->roots = calloc((size_t)1 << ISM_ROOT_MEMO_BITS, sizeof *m->roots);
    m->labels = calloc((size_t)1 << ISM_LABEL_MEMO_BITS, sizeof *m->labels);
    m->pairs = calloc((size_t)1 << ISM_PAIR_MEMO_BITS, sizeof *m->pairs);
    cr_assert(m->roots && m->labels && m->pairs);
    m->memo = (ism_node_memo){m->roots, m->labels, m->pairs, NULL};
}

static void memos_free(memos *m)
{
    free(m->roots);
    free(m->labels);
    free(m->pairs);
}

/* Corners whose memo entry keeps a gradient that is not ism_crease_branch's there (bit for
 * bit); *kept counts the entries checked. */
static size_t wrong_gradients(ism_sampler *s, const ism_corners *k, const memos *m,
                              size_t *kept)
{
    size_t bad = 0;
    for (int c = 0; c < 8; c++) {
        const ism_label_entry *e = ism_label_slot(m->labels, k->key[c]);
        if (e->key != k->key[c] || !e->has_g)
            continue;
        double g[3];
        int b = ism_crease_branch(s, k->p[c], g);
        bad += b != e->label || memcmp(g, e->g, sizeof g) != 0;
        (*kept)++;
    }
    return bad;
}

/* The corner's ∇f one ulp off in x: a memo gradient equal to it bit for bit was copied from
 * the node's k->g (corner_branch), not evaluated (ism_crease_branch never gives it). */
static void mark(double g[3])
{
    g[0] = nextafter(g[0], INFINITY);
}

/* Distinct lattice points whose memo gradient in `labels` was copied from the corners' marked
 * ∇f (mark), by the label's branch: the entries the rule "keep ∇f where the branch wins
 * strictly" wrote and kept (one count a point however many nodes share it). */
static void copied_by_branch(const ism_label_entry *labels, const ism_point_entry *pts,
                             size_t copied[2])
{
    for (size_t i = 0; i < (size_t)1 << ISM_LABEL_MEMO_BITS; i++) {
        const ism_label_entry *e = &labels[i];
        if (!e->key || !e->has_g || e->label < 0 || e->label > 1)
            continue;
        const ism_point_entry *pe = ism_point_find_hashed(pts, POINT_BITS, e->key,
                                                          ism_cache_mix(e->key));
        if (!pe)
            continue;
        double g[3];
        memcpy(g, pe->g, sizeof g);
        mark(g);
        copied[e->label] += memcmp(g, e->g, sizeof g) == 0;
    }
}

static ism_flatness flatness(double max_error, const double box[6])
{
    ism_flatness fl = {.gradient_test = 0.8, .normal_cos = cos(26 * M_PI / 180),
                       .plane_frac = 0.1, .abs_tol = 1.0, .double_root_eps = 1e-6,
                       .double_root_iters = 8, .max_error = max_error,
                       .straddle_shift = 0};
    memcpy(fl.box, box, sizeof fl.box);
    return fl;
}

static void sweep(const pf_surface *surf, int placement)
{
    ism_sampler s;
    ism_tape *t = pf_build_sampler(surf, &s);
    ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
    cr_assert(jet);
    const double base[6] = {-HALF, -HALF, -HALF, HALF, HALF, HALF};
    double box[6];
    ism_grid g = pf_sweep_grid(base, DEPTH, placement, box);
    ism_flatness fl = flatness(2e-2, box); /* nodes of 0.2: judged by their corners */
    memos m, marked;
    memos_new(&m);
    memos_new(&marked);
    ism_point_entry *pts = calloc((size_t)1 << POINT_BITS, sizeof *pts);
    cr_assert(pts);
    const int side = 1 << LEVEL, step = 1 << (DEPTH - LEVEL);
    size_t kept = 0, wrong = 0, verdicts = 0, crease = 0;
    for (int i = 0; i < side * side * side; i++) {
        int32_t org[3] = {(i % side) * step, (i / side % side) * step, (i / side / side) * step};
        ism_corners k;
        memset(&k, 0, sizeof k);
        double lo[3], hi[3];
        for (int a = 0; a < 3; a++) {
            lo[a] = ism_grid_coord(&g, a, org[a]);
            hi[a] = ism_grid_coord(&g, a, org[a] + step);
        }
        int32_t ip[8][3];
        for (int c = 0; c < 8; c++)
            for (int a = 0; a < 3; a++) {
                ip[c][a] = org[a] + ((c >> a) & 1) * step;
                k.p[c][a] = ism_grid_coord(&g, a, ip[c][a]);
            }
        /* f and ∇f as the build takes them (octree_build.c node_corners): through the
         * thread's point memo, its misses in one ism_sample_grad_batch */
        ism_point_memo_many(pts, POINT_BITS, (const int32_t (*)[3])ip,
                            (const double (*)[3])k.p, 8, &s, k.f, k.g, k.key);
        int seen = 0;
        for (int c = 0; c < 8; c++) {
            double v[2];
            if (ism_eval_top_values(t, s.ws, k.p[c][0], k.p[c][1], k.p[c][2], v))
                seen |= 1 << ism_top_active_branch(t, v);
        }
        crease += seen == 3;
        ism_corners fresh = k; /* no memo: every label and gradient evaluated */
        k.memo = &m.memo;
        bool blind_memo = false, blind_fresh = false;
        bool with_memo = ism_plot_test(&s, jet, &fl, lo, hi, &k, &blind_memo);
        bool without = ism_plot_test(&s, jet, &fl, lo, hi, &fresh, &blind_fresh);
        verdicts += with_memo != without || blind_memo != blind_fresh;
        wrong += wrong_gradients(&s, &k, &m, &kept);
        for (int c = 0; c < 8; c++) /* the same node, ∇f marked, into its own memo */
            mark(fresh.g[c]);
        fresh.memo = &marked.memo;
        ism_plot_test(&s, jet, &fl, lo, hi, &fresh, &blind_fresh);
    }
    size_t copied[2] = {0, 0};
    copied_by_branch(marked.labels, pts, copied);
    cr_expect_eq(wrong, 0, "%s placement %d: %zu memo gradients not the branch's", surf->expr,
                 placement, wrong);
    cr_expect_eq(verdicts, 0, "%s placement %d: %zu nodes judged otherwise with the memo",
                 surf->expr, placement, verdicts);
    cr_expect_gt(crease, 10, "%s placement %d: %zu nodes on both branches", surf->expr,
                 placement, crease);
    cr_expect_gt(kept, 0, "%s placement %d: no memo gradient checked", surf->expr, placement);
    for (int b = 0; b < 2; b++)
        cr_expect_gt(copied[b], 0, "%s placement %d: no point's ∇f kept as branch %d's",
                     surf->expr, placement, b);
    free(pts);
    memos_free(&marked);
    memos_free(&m);
    ism_ivjet_ws_free(jet);
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
}

/* Barth's sextic through a top min: min(-B, 2.25 - r²) = -max(B, r² - 2.25), the same zero
 * set, so that ism_top_gradient_branch's min arm (a wins where a < b) is swept too. */
static const ism_param barth_min_phi[] = {{"phi", 1.6180339887498949}};
static const pf_surface barth_min = {
    "min(-(4*(phi^2*x^2 - y^2)*(phi^2*y^2 - z^2)*(phi^2*z^2 - x^2) - "
    "(1 + 2*phi)*(x^2 + y^2 + z^2 - 1)^2), 2.25 - (x^2 + y^2 + z^2))",
    barth_min_phi, 1, NULL, 0};

Test(corner_labels, memo_gradients_are_the_branches_own)
{
    const pf_surface *surfs[] = {&pf_barth_sextic, &pf_gyroid_ball, &barth_min};
    for (int sf = 0; sf < 3; sf++)
        for (int p = pf_first_box() - 1; p < 2; p++) /* own, +1e-3, irrational */
            sweep(surfs[sf], p);
}

/* test_plot_test_tie.c's node (see there) with a memo: corner 0 ties, ∇f = 0 there and the
 * labelled branch's gradient is not; the node must still fail (the certificate refuses it)
 * and the memo must not hold ∇f as the label's gradient. */
static bool tie_once(const double d[3], int slope, bool is_min, bool *checked)
{
    const double h = 0.1;
    char expr[512];
    if (is_min) /* -max(a, b) = min(-a, -b): the same node through the min arm */
        snprintf(expr, sizeof expr,
                 "min(-(0.05 - %d * (x - %.17g)), "
                 "-(0.05 - ((x - %.17g) + (y - %.17g) + (z - %.17g))^2))",
                 slope, d[0], d[0], d[1], d[2]);
    else
        snprintf(expr, sizeof expr,
                 "max(0.05 - %d * (x - %.17g), "
                 "0.05 - ((x - %.17g) + (y - %.17g) + (z - %.17g))^2)",
                 slope, d[0], d[0], d[1], d[2]);
    pf_surface surf = {expr, NULL, 0, NULL, 0};
    ism_tape *t = pf_compile(&surf);
    ism_sampler s = {.tape = t, .ws = ism_eval_ws_new(t), .batch = true};
    ism_ivjet_ws *jet = ism_ivjet_ws_new(t);
    cr_assert(s.ws && jet);
    ism_corners k;
    memset(&k, 0, sizeof k);
    for (int c = 0; c < 8; c++) {
        int32_t ip[3];
        for (int a = 0; a < 3; a++) {
            ip[a] = (c >> a) & 1;
            k.p[c][a] = d[a] + (ip[a] ? h : 0);
        }
        k.key[c] = ism_lattice_key(ip);
    }
    /* ∇f at the corners as the build takes them: one batch (ism_point_memo_many) */
    ism_sample_grad_batch(&s, (const double (*)[3])k.p, k.f, k.g, 8);
    double lg[3];
    int label = ism_crease_branch(&s, k.p[0], lg);
    bool tie = k.g[0][0] == 0 && k.g[0][1] == 0 && k.g[0][2] == 0 && label >= 0 &&
               fabs(lg[0]) + fabs(lg[1]) + fabs(lg[2]) > 0;
    if (tie) {
        memos m;
        memos_new(&m);
        k.memo = &m.memo;
        double lo[3] = {d[0], d[1], d[2]}, hi[3] = {d[0] + h, d[1] + h, d[2] + h};
        double box[6] = {lo[0] - 1, lo[1] - 1, lo[2] - 1, hi[0] + 1, hi[1] + 1, hi[2] + 1};
        ism_flatness fl = flatness(1.0, box); /* any error passes */
        fl.gradient_test = 1.0;
        bool blind;
        cr_expect_not(ism_plot_test(&s, jet, &fl, lo, hi, &k, &blind),
                      "slope %d: the tie node passed through the memo", slope);
        size_t kept = 0;
        cr_expect_eq(wrong_gradients(&s, &k, &m, &kept), 0,
                     "slope %d: a memo gradient is not the labelled branch's", slope);
        const ism_label_entry *e = ism_label_slot(m.labels, k.key[0]);
        cr_expect(e->key == k.key[0], "slope %d: corner 0 not labelled", slope);
        *checked = true;
        memos_free(&m);
    }
    ism_ivjet_ws_free(jet);
    ism_eval_ws_free(s.ws);
    ism_tape_free(t);
    return tie;
}

Test(corner_labels, a_tie_keeps_the_labelled_gradient)
{
    const double base[6] = {0, 0, 0, 1, 1, 1};
    for (int w = pf_first_box() - 1; w < 2; w++)
        for (int is_min = 0; is_min < 2; is_min++) {
            double box[6];
            pf_sweep_box(base, 9, w, box);
            bool checked = false; /* the operands' order on the tape depends on the
                                   * spelling: up to 12 slopes (own box, min: 10 is the first) */
            for (int slope = 1; slope <= 12 && !tie_once(box, slope, is_min, &checked); slope++)
                ;
            cr_expect(checked, "box %d %s: no spelling put ∇f = 0 beside a labelled gradient",
                      w, is_min ? "min" : "max");
        }
}
