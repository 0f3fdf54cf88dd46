/* search.c — the interval subdivision of the singular-locus search (search.h).
 *
 * Level by level: the surviving cells of one level (the frontier) are cut in eight, and each
 * child is tested, in parallel over chunks of the frontier; chunk outputs are joined in chunk
 * order, so the result never depends on the thread count. A child is tested cheapest first:
 *
 *   F(X) ∌ 0 (batched over the 8 children)  ─▶ dropped
 *   (children of a smooth cell P, centre p) ∇f(p) + H(P)(X − p) ∌ 0 for some row, from
 *   what P's own tests evaluated, no evaluation  ─▶ dropped
 *   (the same, X's centre c) f(c) ∉ ½ (X − c)ᵀ H(P) (X − c) (Taylor round a singular point
 *   of the cell), f(c) batched over the children where a guess says it may hold  ─▶ dropped
 *   ∂F/∂xi(X) ∌ 0 for some i, for every smooth piece of a min/max/abs kink ─▶ dropped
 *   (smooth cells only, c: X's own centre) f(c) + ∇F(X)·(X − c) ∌ 0, or with H the
 *   cell's own H(X):
 *   ∇f(c) + H (X − c) ∌ 0 for some row,
 *   f(c) ∉ ½ (X − c)ᵀ H (X − c) (Taylor round a singular point of the cell),
 *   f(c) + ∇f(c)·(X − c) + ½ (X − c)ᵀ H (X − c) ∌ 0,
 *   or Krawczyk's K(X) ∩ X = ∅  ─▶ dropped;   K(X) ⊂ int X  ─▶ one zero of ∇f: kept whole
 *
 * Cells reaching the finest size are the candidates, projected onto ∇f = 0 and ranked after
 * the subdivision, in key order (project_all): a candidate on whose closure an earlier
 * candidate's projection lies takes that projection instead of a Newton run of its own. */
#include "core/singular/search.h"
#include "core/singular/krawczyk.h"
#include "core/singular/newton.h"
#include "core/octree/dual_cert.h"
#include "core/eval/eval.h"
#include "core/eval/interval_jet.h"
#include "core/eval/interval_ops.h"
#include "core/util/clock.h"
#include "core/util/parallel.h"
#include "core/util/sym3.h"

#include <float.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

/* Deepest subdivision: lattice coordinates keep 17 bits each in the sort key (the
 * polygoniser's own limit is 16). */
#define SEARCH_MAX_DEPTH 16
/* A cell with more undecided min/max/abs kinks than this is kept without testing its 2^n
 * smooth pieces (each piece costs one gradient pass). */
#define SEARCH_MAX_SPLIT 3
/* Newton projection of a candidate's centre: steps at most, and the step (× cell width)
 * below which it has converged — degenerate zeros (cusp, touching spheres) converge only
 * linearly, by a factor 1/2 to 2/3 a step, hence the generous cap. */
#define SEARCH_GN_ITERS 64
#define SEARCH_GN_TOL 1e-10
/* Frontier cells per parallel task, and tasks between two looks at the clock. */
#define SEARCH_CELLS_PER_TASK 16
/* Candidates per projection task (project_all), in key order: a candidate shares a projection
 * only with the earlier candidates of its own run, so runs are fixed by the order alone (the
 * thread count changes nothing). Cells round a curve on a lattice line (the cross-cap's axis:
 * four cells at each height) sit a few keys apart, well inside one run. */
#define SEARCH_PROJECT_RUN 64
/* newton.h's lanes take one run in one pass (ism_sing_newton_lanes would split a longer one) */
_Static_assert(SEARCH_PROJECT_RUN <= ISM_SING_NEWTON_LANES,
               "a projection run fits one pass of Newton lanes");
/* An earlier candidate's projection q serves a candidate X when q lies in X grown by this
 * fraction of its width on each side: on X's face, edge or corner to Newton's own precision
 * (SEARCH_GN_TOL), not beside it. q is then a point of ∇f = 0 in X's closure, which is what
 * X's own Newton run would have found in its grown box: the four cells round the cross-cap's
 * axis, a lattice line, all converge onto the axis at their common height. */
#define SEARCH_SHARE_REL 1e-6
/* Jets of a parent's children taken in lanes (pre_jets) at the least; fewer are taken one by
 * one. One 4-lane group of ism_eval_interval_jet_lanes costs ~9,100 instructions on Klein's
 * tape (Hessians from the gradient pass's records) against ~5,200 for one box's jet from
 * its record, and ~12,000 on Barth's (its own pass: min/max keep no records) against
 * ~6,450 (callgrind, bench_error mesh klein-bottle 0.0141 / barth-sextic 0.0259): lanes
 * pay from two jets up. */
#define PRE_JETS_MIN 2
/* Below this many frontier cells a level runs on the calling thread (thread start-up
 * costs more than the work). */
#define SEARCH_PARALLEL_MIN 64

/* A tested cell's verdict; SMOOTH: it survives, f is smooth on it and its model was filled.
 * OPEN: screen's cheap tests left it undecided (only screen returns it; classify, which
 * decides such a cell, never does). */
enum { EXCLUDED = 0, SURVIVES = 1, UNIQUE = 2, SMOOTH = 3, OPEN = 4 };

/* A cell. A frontier cell on which f is smooth has a Taylor model (centre, f and ∇f there,
 * the jet over the cell: what smooth_tests evaluated), from which its children's ∇f is
 * enclosed with no evaluation (parent_excludes); the models (~250 bytes) sit beside the
 * frontier, in its own order, so a cell carries only its model's index. edges and lines are
 * the cell's certified singular segments (locus_edges). */
typedef struct scell {
    uint32_t i[3];
    uint8_t level;
    uint8_t lines;  /* bit a: the line along axis a through the centre, across the cell */
    uint16_t edges; /* bit edge_bit(a, sb, sc): that edge of the cell */
    uint32_t model; /* NO_MODEL: none (f not smooth on it, or the root untested) */
} scell;

#define NO_MODEL UINT32_MAX
_Static_assert(sizeof(scell) == 20,
               "a frontier cell is its lattice position, level, certified segments and model");
_Static_assert(SEARCH_MAX_DEPTH < 256, "a level fits scell.level");

typedef struct keyed_box {
    uint64_t key; /* z, y, x lattice coordinates of the lower corner, then the level */
    ism_lbox box;
    bool pending; /* a finest candidate not projected yet (project_all) */
} keyed_box;

/* A growable array of one element type. */
typedef struct vec {
    void *p;
    size_t n, cap;
} vec;

/* Appends the n elements at e (of sz bytes each). */
static bool vec_append(vec *v, const void *e, size_t n, size_t sz)
{
    if (v->n + n > v->cap) {
        size_t c = v->cap ? v->cap : 64;
        while (c < v->n + n)
            c *= 2;
        void *q = realloc(v->p, c * sz);
        if (!q)
            return false;
        v->p = q;
        v->cap = c;
    }
    if (n)
        memcpy((char *)v->p + v->n * sz, e, n * sz);
    v->n += n;
    return true;
}

static bool vec_push(vec *v, const void *e, size_t sz) { return vec_append(v, e, 1, sz); }

/* Per-thread evaluation state and counters. */
typedef struct worker {
    ism_eval_ws *ws;
    ism_ivjet_ws *jw;
    uint8_t *kinks, *force;
    uint64_t visited, evals_interval, evals_jet;
    uint64_t centre_dropped; /* cells the centre test (children_quad) dropped */
    uint64_t grads_batched;  /* cells whose gradients pre_gradients took */
    uint64_t grads_batch_read; /* ... and classify read */
    uint64_t centres_batched;  /* cells whose centre's gradient was given to a batch */
    uint64_t centres_batch_read; /* ... and smooth_tests read from it */
    /* a task's parents between screening and finish (expand_task): SEARCH_CELLS_PER_TASK
     * expansions of 3,352 bytes (8 pre_grad with a full ism_ivjet each), 52 KiB a worker */
    struct expansion *ex;
} worker;

/* One task's output: surviving children (their models indexed within models) and boxes, in
 * the order of its parents. */
typedef struct task_out {
    vec cells, models, boxes;
    bool oom;
} task_out;

typedef struct search {
    const ism_tape *t;
    const ism_locus_options *o;
    int depth;
    double lo[3], hi[3], ext[3];
    double unit;            /* 2^-depth: a lattice step as a fraction of the box */
    worker *workers;
    int threads;
    /* the level being expanded */
    const scell *frontier;
    const ism_dual_model *models; /* the frontier's, by scell.model */
    size_t nfrontier;
    task_out *outs;
    double hscale;          /* the Hessian scale of the box (hessian_scale) */
    bool branches;          /* t holds a min, max or abs: a gradient pass may meet a kink */
    bool batch;             /* the children's gradients in batches (pre_gradients) */
    atomic_int stop;        /* 1 deadline, 2 cancel, 3 budget */
    atomic_size_t kept;     /* cells and boxes kept so far in this level */
} search;

static double coord(const search *s, int k, uint32_t i)
{
    return i >= (1u << s->depth) ? s->hi[k] : s->lo[k] + s->ext[k] * ((double)i * s->unit);
}

static void cell_box(const search *s, const scell *c, ism_interval x[3])
{
    uint32_t size = 1u << (s->depth - (int)c->level);
    for (int k = 0; k < 3; k++)
        x[k] = iv(coord(s, k, c->i[k]), coord(s, k, c->i[k] + size));
}

static bool holds0(ism_interval r) { return r.lo <= 0.0 && r.hi >= 0.0; }

static bool grad_may_vanish(const ism_interval d[3])
{
    return holds0(d[0]) && holds0(d[1]) && holds0(d[2]);
}

/* Either piece of a kink at the top (ism_ivjet_top_pieces) may have ∇f = 0. */
static bool pieces_may_vanish(const ism_ivgrad piece[2])
{
    return grad_may_vanish(piece[0].d) || grad_may_vanish(piece[1].d);
}

/* Some smooth piece of a cell with nk (<= SEARCH_MAX_SPLIT) free kinks may have ∇f = 0:
 * each kink forced to each of its branches in turn. Forcing leaves every value enclosure as
 * it was, so the set of kinks does not change. Called right after classify's unforced pass
 * over x on w->jw, whose registers a kink at the top is read from. */
static bool some_piece_may_vanish(const search *s, worker *w, const ism_interval x[3], size_t nk)
{
    /* one kink, at the top (a min or max of two solids: Barth's sextic in its ball): both
       pieces' gradients are the operands' the unforced pass just left in w->jw, no pass of
       its own (Barth at E 0.0259: 25,745 forced passes, 90.8M of the search's 225.8M) */
    ism_ivgrad piece[2];
    if (nk == 1 && ism_ivjet_top_pieces(s->t, w->jw, x, piece))
        return pieces_may_vanish(piece);
    size_t at[SEARCH_MAX_SPLIT], n = 0;
    for (size_t i = 0; i < ism_tape_length(s->t) && n < nk; i++)
        if (w->kinks[i])
            at[n++] = i;
    bool any = false;
    for (unsigned m = 0; m < (1u << n) && !any; m++) {
        for (size_t j = 0; j < n; j++)
            w->force[at[j]] = (m >> j) & 1u ? ISM_BRANCH_B : ISM_BRANCH_A;
        ism_ivgrad g;
        ism_eval_interval_grad(s->t, w->jw, x, w->force, NULL, &g);
        w->evals_interval++;
        any = grad_may_vanish(g.d);
    }
    for (size_t j = 0; j < n; j++)
        w->force[at[j]] = ISM_BRANCH_FREE;
    return any;
}

/* ((base + p_0) + p_1) + p_2: the one order in which a row of a linear form is summed, by
 * add_linear and by parent_excludes from products taken once (their bits agree only while
 * both sum in this order). */
static ism_interval sum_terms(ism_interval base, const ism_interval p[3])
{
    _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++)
        base = iv_add(base, p[j]);
    return base;
}

/* Σ_j a_j (x_j − c_j) added to base. */
static ism_interval add_linear(ism_interval base, const ism_interval a[3], const ism_interval dx[3])
{
    ism_interval p[3];
    _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++)
        p[j] = iv_mul(a[j], dx[j]);
    return sum_terms(base, p);
}

/* f at the centre c against its Taylor expansion round a singular point p of the cell X:
 * there f(p) = 0 and ∇f(p) = 0, so f(c) = ½ (c − p)ᵀ H(ξ) (c − p) with ξ between p and c, in
 * the cell. The cell holds no singular point when f(c) (fc) lies outside
 * q = ½ (X − c)ᵀ H(X) (X − c). The second-order form round c must also carry ∇f(c)·(X − c),
 * an interval as wide as |∇f(c)| times the cell: this one does not, so it drops cells a level
 * sooner where f ≠ 0 but ∇f is small, the torus's tube round its circle of minima
 * (f = −4R²r² there): 1,481 → 969 cells on the torus. A zero of ∇f off the surface (f ≠ 0)
 * is no singular point, so such cells go too. */
static bool f_off_singular_taylor(ism_interval fc, ism_interval q)
{
    ism_interval r = iv_sub(fc, q);
    return r.lo > 0.0 || r.hi < 0.0; /* a NaN bound (∞ − ∞) proves nothing */
}

/* classify's first test of a cell screen left OPEN (fc: f at its centre, or NULL when not
 * evaluated; q: its parent's children_quad): dropped by f_off_singular_taylor, before any
 * evaluation. In one place for classify and pre_gradients, which batches the gradients of
 * exactly the children this leaves. */
static bool centre_drops(const ism_interval *fc, ism_interval q)
{
    return fc && f_off_singular_taylor(*fc, q);
}

/* Whether some row of the mean-value form ∇f(c) + H(X)(X − c) excludes 0 (at: ∇f at c, j: the
 * jet over a cell holding X, dx = X − c). */
static bool some_row_excludes(const ism_ivgrad *at, const ism_ivjet *j, const ism_interval dx[3])
{
    _Pragma("GCC unroll 3") for (int i = 0; i < 3; i++) {
        ism_interval hrow[3] = { j->h[ism_dual_hess_at(i, 0)], j->h[ism_dual_hess_at(i, 1)],
                                 j->h[ism_dual_hess_at(i, 2)] };
        if (!holds0(add_linear(at->d[i], hrow, dx)))
            return true;
    }
    return false;
}

/* The tests on X's own jet j (a parent's would serve too, ξ in X lying in the parent, but
 * interval arithmetic is inclusion-monotone, so a test the parent's wider jet passes the
 * cell's own passes as well: smooth_tests), round X's centre c (gc: f and ∇f there,
 * dx = X − c): a row of ∇f's mean-value form, Taylor round a singular point, and f's
 * second-order form (dual_cert.h), whose width shrinks with the square of the cell, so near
 * a minimum of f off the surface (the torus's circle of minima inside the tube, where ∇f = 0
 * and only f ≠ 0 rules a cell out) cells are dropped a level sooner than by the first-order
 * form. The last two share the form's terms. Pure arithmetic on what smooth_tests
 * evaluated. */
static bool jet_excludes(const ism_ivgrad *gc, const ism_ivjet *j, const ism_interval dx[3])
{
    if (some_row_excludes(gc, j, dx))
        return true;
    ism_dual_terms t;
    ism_dual_terms_of(gc, j, dx, &t);
    return f_off_singular_taylor(gc->v, ism_dual_terms_quad(&t))
           || !holds0(ism_dual_terms_f(gc->v, &t));
}

/* The centre of the cell x, as every test round it takes it (centre_at, expand_prepare's
 * centre lanes): a double within the cell. */
static inline void centre_of(const ism_interval x[3], double c[3])
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        c[k] = 0.5 * x[k].lo + 0.5 * x[k].hi;
}

/* The cell x's centre into m->c and cx (a point interval) and f's interval gradient there
 * into m->at (one evaluation counted): the start of every cell model (smooth_tests,
 * certified_model). */
static void centre_at(const search *s, worker *w, const ism_interval x[3], ism_dual_model *m,
                      ism_interval cx[3], const ism_ivgrad *pre)
{
    centre_of(x, m->c);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        cx[k] = iv(m->c[k], m->c[k]);
    if (pre) { /* taken beforehand (pre_gradients, centres_take), counted now */
        m->at = *pre;
        w->centres_batch_read++;
    } else
        ism_eval_interval_grad(s->t, w->jw, cx, NULL, NULL, &m->at);
    w->evals_interval++;
}

/* A cell's interval gradient over its box and at its centre, taken beforehand with its
 * siblings' in one batch (pre_gradients), when ok. */
typedef struct pre_grad {
    bool ok, at_ok; /* g taken; at taken too */
    bool jet_ok;    /* jet taken too (pre_jets) */
    ism_ivgrad g, at;
    uint32_t nk; /* the box's free kinks (their bytes: ism_ivjet_lane_kinks) */
    ism_ivjet jet;  /* the jet over the box smooth_tests takes (pre_jets) */
} pre_grad;

/* smooth_tests' first test, the mean-value form of F round x's centre cx (a point
 * interval; at: f there, g: ∇F over x): whether f(c) + ∇F(X)·(X − c) holds 0, X − c into
 * dx. In one place for smooth_tests and pre_jets, which takes the jets of exactly the
 * cells it passes. */
static bool first_order_holds(const ism_interval x[3], const ism_interval cx[3],
                              const ism_ivgrad *at, const ism_ivgrad *g, ism_interval dx[3])
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        dx[k] = iv_sub(x[k], cx[k]);
    return holds0(add_linear(at->v, g->d, dx));
}

/* Krawczyk's test on the cell x from its model m (∇f at the centre, the Hessian over x).
 * Its own function: inlined into smooth_tests, GCC 12 takes m's members for 8-byte regions
 * and rejects the call (-Wstringop-overread; a false report, m is always a whole model). */
static __attribute__((noinline)) int krawczyk_of(const ism_interval x[3], const ism_dual_model *m)
{
    return ism_krawczyk(x, m->c, m->at.d, m->box.h, NULL);
}

/* The tests that need f smooth on the cell: mean-value forms of F and ∇F, the second-order
 * form of F, and Krawczyk. The cell's own model is built in *m as they go: valid when the
 * verdict is SMOOTH. */
static int smooth_tests(const search *s, worker *w, const ism_interval x[3], const ism_ivgrad *g,
                        ism_dual_model *m, const pre_grad *pre)
{
    ism_interval cx[3], dx[3];
    centre_at(s, w, x, m, cx, pre && pre->ok && pre->at_ok ? &pre->at : NULL);
    if (!first_order_holds(x, cx, &m->at, g, dx))
        return EXCLUDED;
    /* The cell's own jet only. The parent's (no evaluation, round the cell's centre) drops no
     * cell the own jet keeps (jet_excludes: inclusion-monotone); it only spared a jet, and
     * cost more than it spared: 0 of the 160 cells reaching it dropped on the torus, 126 of
     * 2,682 on kummer-16-nodes. Search instructions without it at E 0.0141 (bench_error mesh
     * S 0.0141 10, callgrind): torus 2.67M -> 2.47M, kummer-16-nodes 69.8M -> 67.5M. */
    if (pre && pre->jet_ok) /* taken beforehand (pre_jets), bit for bit; counted now */
        m->box = pre->jet;
    else
        ism_eval_interval_jet(s->t, w->jw, x, NULL, NULL, &m->box);
    w->evals_jet++;
    if (jet_excludes(&m->at, &m->box, dx))
        return EXCLUDED;
    int k = krawczyk_of(x, m);
    if (k == ISM_KRAWCZYK_EMPTY)
        return EXCLUDED;
    return k == ISM_KRAWCZYK_UNIQUE ? UNIQUE : SMOOTH;
}

/* The rows of the mean-value form of ∇f over a child X of a cell P with a model pm:
 * ∇f(p) + H(P)(X − p) round P's centre p, no evaluation. Along each axis j a child's X − p
 * is P's lower or upper half less p, so each product H(P)_ij (X_j − p_j) takes one of two
 * values per axis: the 18 products are taken once for the eight children (at the first
 * child that asks) instead of up to 9 per child, and each row is then summed by sum_terms,
 * as add_linear sums it, from the same products: bit for bit what that form gives per
 * child. */
typedef struct parent_rows {
    const ism_dual_model *pm;
    const ism_interval *lower, *upper; /* P's halves per axis */
    bool ready;                        /* t taken */
    ism_interval t[3][3][2];           /* [row i][axis j][upper half?]: H_ij (half_j − p_j) */
} parent_rows;

static void rows_take(parent_rows *r)
{
    _Pragma("GCC unroll 3") for (int j = 0; j < 3; j++) {
        ism_interval p = iv(r->pm->c[j], r->pm->c[j]);
        ism_interval d[2] = { iv_sub(r->lower[j], p), iv_sub(r->upper[j], p) };
        for (int i = 0; i < 3; i++) {
            ism_interval h = r->pm->box.h[ism_dual_hess_at(i, j)];
            r->t[i][j][0] = iv_mul(h, d[0]);
            r->t[i][j][1] = iv_mul(h, d[1]);
        }
    }
    r->ready = true;
}

/* Whether ∇f excludes 0 on P's child m (bit k: its upper half along axis k) by the
 * mean-value form of P (r: its rows; NULL when P has no model, f not smooth there). On the
 * torus it drops 560 of 968 children, most of which the child's own interval gradient
 * (~1,900 instructions) would drop, at ~180 instructions a row. */
static bool parent_excludes(parent_rows *r, unsigned m)
{
    if (!r)
        return false;
    if (!r->ready)
        rows_take(r);
    _Pragma("GCC unroll 3") for (int i = 0; i < 3; i++) {
        ism_interval p[3];
        for (int j = 0; j < 3; j++)
            p[j] = r->t[i][j][(m >> j) & 1u];
        if (!holds0(sum_terms(r->pm->at.d[i], p)))
            return true;
    }
    return false;
}

/* Taylor round a singular point for the children of a cell P with a model pm (lower and
 * upper: their lower and upper halves of P per axis), from f at a child's centre alone: no
 * gradient evaluated. The form q returned serves all eight children.
 *
 * Why it is sound: let p in a child X be a singular point, f(p) = 0 and ∇f(p) = 0, and c
 * X's centre. f is smooth on P (pm exists only then), X ⊂ P and P is convex, so Taylor's
 * theorem with the integral remainder along the segment from p to c (inside X) gives
 * f(c) = f(p) + ∇f(p)·(c − p) + ½ (c − p)ᵀ Ĥ (c − p) = ½ (c − p)ᵀ Ĥ (c − p), with
 * Ĥ = 2 ∫₀¹ (1 − t) H(p + t (c − p)) dt: each entry a weighted mean (weights ≥ 0, summing
 * to 1) of values of that entry of H on X, so inside its enclosure over P. c − p lies in
 * c − X = −(X − c) and the form is even in it, so f(c) ∈ ism_dual_quad(P's jet, X − c) ⊂ q, q
 * the form over the hull of every child's X − c (inclusion-monotone): an enclosure of f(c)
 * apart from q rules p out.
 *
 * It is the Taylor test of jet_excludes on P's jet, before the child's interval gradient
 * and centre gradient (~1,700 instructions each on the torus).
 * There, of the torus's 640 level-4 cells, the parent's rows (parent_excludes) drop 448 and
 * this test the other 192 but 16 (each of which its own jet drops): the search 3.51M → 2.77M
 * instructions. A cusp inside cells (test_singular_points.c) sees it at every level. */
static ism_interval children_quad(const ism_dual_model *pm, const ism_interval lower[3],
                                  const ism_interval upper[3])
{
    double cl[3], cu[3];
    centre_of(lower, cl);
    centre_of(upper, cu);
    ism_interval dx[3];
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        ism_interval a = iv_sub(lower[k], iv(cl[k], cl[k])), b = iv_sub(upper[k], iv(cu[k], cu[k]));
        dx[k] = iv(fmin(a.lo, b.lo), fmax(a.hi, b.hi));
    }
    return ism_dual_quad(&pm->box, dx);
}

/* Whether f at a child's centre c is worth evaluating for children_quad's test (q): its
 * first-order estimate from the parent's model, f(p) + ∇f(p)·(c − p) in plain doubles, lies
 * outside q. A guess only, never a proof (the test takes the evaluated enclosure). Round a
 * singular point f(c) is small and inside q, and a point costs a walk of the whole tape
 * as a box does: evaluated for every open child, the heart's search (mostly such cells)
 * cost 5% more (86.9M → 91.2M instructions); with the guess 0.7% less. */
static bool centre_worth(const ism_dual_model *pm, const double c[3], ism_interval q)
{
    double e = 0.5 * pm->at.v.lo + 0.5 * pm->at.v.hi;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        e += (0.5 * pm->at.d[k].lo + 0.5 * pm->at.d[k].hi) * (c[k] - pm->c[k]);
    return e < q.lo || e > q.hi;
}

/* Segments of the locus on lattice lines (cells along a lattice line: the three axes of
 * xyz = 0, the double line of xy = 0 and Whitney's x² = y²z, the cross-cap's and Steiner's
 * axes).
 *
 * A closed segment S of X on which f and ∇f vanish is a segment of singular points. Then no
 * test of screen, the centre test (children_quad) or classify drops X — each encloses f or
 * ∇f over X, or over the parent holding X, or f(c) against a Taylor form round a singular
 * point of X, and S's points are such (f(c) ∈ q) — and Krawczyk answers neither EMPTY (S's
 * points are zeros of ∇f in X) nor UNIQUE (there are more than one): the verdict is SMOOTH
 * whatever those tests compute. So such a cell is not tested (screen answers SMOOTH); finish
 * only gives it the model its children are tested by (a finest one, which has no children,
 * not even that).
 *
 * S is taken as such when the interval f and ∇f over S (a degenerate box) lie within
 * SEARCH_ZERO: outward rounding widens an exact 0 by one subnormal step per operation
 * (interval_ops.h down1/up1), so an exact 0 never comes back as [0, 0]; no f a person writes
 * has |f| or |∇f| below the smallest normal double at a point that is not singular. Were S
 * not singular after all, the cell would merely be kept (and cut on) where the tests might
 * have dropped it, or kept whole by Krawczyk: the search only ever keeps more, never loses a
 * point of the locus.
 *
 * Where segments come from: a cell whose interval f and ∇f at the centre (which smooth_tests
 * evaluates anyway) vanish so has its three centre lines, across the whole cell, evaluated as
 * degenerate boxes (3 interval gradients; a centre on the locus is the lattice-line case,
 * elsewhere it does not happen); a line that vanishes is half an edge of each of the four
 * children on either side. A certified edge of a cell is, halved, an edge of the two
 * children along it. The root's centre on coordinate-planes, crossing-planes, Whitney, the
 * cross-cap and Steiner is such a point, and from there every cell along the axes is taken
 * at every level. Lines through a face centre only (not the cell's) are not looked for.
 * Tapes with min, max or abs are left out: their interval gradient over a kink is a hull of
 * branches. */

/* |f|, |∇f| at most this over a segment: 0 to the last bit (the smallest normal double; see
 * above). */
#define SEARCH_ZERO DBL_MIN

/* An edge of a cell along axis a, at the lower (0) or upper (1) side sb of the next axis
 * (a + 1) % 3 and sc of the one after. */
static inline unsigned edge_bit(int a, unsigned sb, unsigned sc)
{
    return 4u * (unsigned)a + sb + 2u * sc;
}

static bool within_zero(ism_interval r) { return r.lo >= -SEARCH_ZERO && r.hi <= SEARCH_ZERO; }

/* Whether an enclosure of f and ∇f is 0 to the last bit (SEARCH_ZERO; NaN bounds are not). */
static bool vanishes(const ism_ivgrad *g)
{
    return within_zero(g->v) && within_zero(g->d[0]) && within_zero(g->d[1])
           && within_zero(g->d[2]);
}

/* Child m's certified edges (bit k of m: its upper half along axis k) from its parent's
 * edges and centre lines. Along axis a, with (mb, mc) child m's halves along the next two
 * axes: the parent's edge at sides (mb, mc) is, halved, the child's edge at the same sides
 * (edge_bit unchanged); the parent's centre line along a is the child's edge at the sides
 * facing the parent's centre, (1 − mb, 1 − mc). No other child edge lies on a parent's edge
 * or centre line. */
static uint16_t child_edges(const scell *p, unsigned m)
{
    if (!p->edges && !p->lines)
        return 0;
    unsigned e = 0;
    _Pragma("GCC unroll 3") for (int a = 0; a < 3; a++) {
        unsigned mb = (m >> ((a + 1) % 3)) & 1u, mc = (m >> ((a + 2) % 3)) & 1u;
        e |= p->edges & (1u << edge_bit(a, mb, mc));
        if ((p->lines >> a) & 1u)
            e |= 1u << edge_bit(a, 1u - mb, 1u - mc);
    }
    return (uint16_t)e;
}

/* The centre lines of a cell c whose model m was just built (see above). */
static uint8_t centre_lines(const search *s, worker *w, const scell *c, const ism_dual_model *m)
{
    if (s->branches || (int)c->level >= s->depth || !vanishes(&m->at))
        return 0;
    uint32_t size = 1u << (s->depth - (int)c->level), half = size >> 1;
    uint8_t lines = 0;
    for (int a = 0; a < 3; a++) {
        ism_interval x[3];
        for (int k = 0; k < 3; k++) {
            double mid = coord(s, k, c->i[k] + half);
            x[k] = k == a ? iv(coord(s, k, c->i[k]), coord(s, k, c->i[k] + size)) : iv(mid, mid);
        }
        ism_ivgrad g;
        ism_eval_interval_grad(s->t, w->jw, x, NULL, NULL, &g);
        w->evals_interval++;
        /* a line of one point (a box so far off the origin that the cell's bounds round
         * together) certifies no segment */
        if (x[a].lo < x[a].hi && vanishes(&g))
            lines |= (uint8_t)(1u << a);
    }
    return lines;
}

/* Whether the cell c (box x) holds a certified segment of more than one point (a box so far
 * off the origin that a cell's bounds round together has none). */
static bool holds_segment(const scell *c, const ism_interval x[3])
{
    for (int a = 0; c->edges && a < 3; a++)
        if ((c->edges >> (4 * a)) & 0xFu && x[a].lo < x[a].hi)
            return true;
    return false;
}

/* The model of a cell holding a certified segment (its verdict is SMOOTH without a test):
 * what smooth_tests builds, bit for bit (the jet without the kept gradient pass is the same
 * bits, interval_jet.h). */
static void certified_model(const search *s, worker *w, const ism_interval x[3], ism_dual_model *m)
{
    ism_interval cx[3];
    centre_at(s, w, x, m, cx, NULL);
    ism_eval_interval_jet(s->t, w->jw, x, NULL, NULL, &m->box);
    w->evals_jet++;
}

/* The tests of a cell that evaluate nothing beyond its F interval f (r: its parent's rows,
 * or NULL; m: which child it is): SMOOTH for a certified segment (above; its model not built
 * yet), EXCLUDED, or OPEN. */
static int screen(worker *w, const scell *c, const ism_interval x[3], ism_interval f,
                  parent_rows *r, unsigned m)
{
    w->visited++;
    if (holds_segment(c, x))
        return SMOOTH;
    return !holds0(f) || parent_excludes(r, m) ? EXCLUDED : OPEN;
}

/* classify's verdict on a cell whose gradient a batch took (pre) with one free kink, at the
 * top: its pieces read from the batch's lane (ism_ivjet_top_pieces), as some_piece_may_vanish
 * reads them first, without listing its kink bytes (ism_ivjet_lane_kinks: only the forced
 * passes read them). The batch is the last batched pass (batch_kinked finishes a parent's
 * children right after it), so its lane holds the box and lane_kinks would have answered
 * pre->nk: the same verdict and counts. top_pieces would prefer a scalar pass's registers
 * over the same box, which lane_kinks never reads; none can match here: a child's box gets no
 * scalar gradient pass before its classify (a scalar pass of another box does not match, and
 * then the lane answers). Barth at E 0.0259: 12,840 lane_kinks calls, 1.55M instructions.
 * False when not decided so (the caller goes on as before). */
static bool top_kink_verdict(const search *s, worker *w, const ism_interval x[3],
                             const pre_grad *pre, int *v)
{
    ism_ivgrad piece[2];
    if (!pre || !pre->ok || pre->nk != 1 || !ism_ivjet_top_pieces(s->t, w->jw, x, piece))
        return false;
    w->grads_batch_read++;
    w->evals_interval++;
    *v = pieces_may_vanish(piece) ? SURVIVES : EXCLUDED;
    return true;
}

/* Whether a cell screen left OPEN (f at its centre fc, NULL when not evaluated, and then q
 * its parent's children_quad) may hold a singular point;
 * SMOOTH leaves the cell's model in *m. */
static int classify(const search *s, worker *w, const ism_interval x[3], const ism_interval *fc,
                    ism_interval q, ism_dual_model *m, const pre_grad *pre)
{
    if (centre_drops(fc, q)) {
        w->centre_dropped++;
        return EXCLUDED;
    }
    int v;
    if (top_kink_verdict(s, w, x, pre, &v))
        return v;
    ism_ivgrad g;
    /* Without min, max or abs there is no kink to list: the pass keeps its values and first
     * partials instead, and smooth_tests' jet over the same box then computes only the
     * Hessian from them (interval_jet.h: the same bits). heart 4,037 jets, cross-cap 2,093. */
    size_t nk = 0;
    if (pre && pre->ok &&
        (!pre->nk || ism_ivjet_lane_kinks(s->t, w->jw, x, w->kinks) == pre->nk)) {
        g = pre->g;
        nk = pre->nk;
        w->grads_batch_read++;
    } else
        nk = s->branches ? ism_eval_interval_grad(s->t, w->jw, x, NULL, w->kinks, &g)
                         : ism_eval_interval_grad_kept(s->t, w->jw, x, &g);
    w->evals_interval++;
    if (nk == 0)
        return grad_may_vanish(g.d) ? smooth_tests(s, w, x, &g, m, pre) : EXCLUDED;
    if (nk > SEARCH_MAX_SPLIT)
        return SURVIVES;
    return some_piece_may_vanish(s, w, x, nk) ? SURVIVES : EXCLUDED;
}

/* A finest candidate left at its centre (Newton did not converge), the Hessian's rank there:
 * at (NULL: evaluated here) the Hessian there already taken, the first jet of Newton's run
 * from the centre (start_of's, the same point; ism_eval_hessian's bits in lanes too:
 * newton.h). Barth at E 0.0259: 584 of 720 runs do not converge, 1.1M instructions. */
static ism_lbox centre_rank(const search *s, worker *w, const ism_interval x[3],
                            const double *at)
{
    ism_lbox b = { .rank = 0, .flags = 0 };
    double g[3], h[6], eig[3];
    for (int k = 0; k < 3; k++) {
        b.lo[k] = x[k].lo;
        b.hi[k] = x[k].hi;
        b.q[k] = x[k].lo + 0.5 * (x[k].hi - x[k].lo);
    }
    if (at)
        memcpy(h, at, sizeof h);
    else {
        ism_eval_hessian(s->t, w->ws, b.q[0], b.q[1], b.q[2], g, h);
        w->evals_jet++;
    }
    ism_sym3_eigen(h, eig, NULL);
    b.rank = (uint8_t)ism_sing_rank(eig, s->hscale);
    return b;
}

/* Where a finest candidate x's projection starts: its centre, and into *no Newton's options
 * (steps within the cell grown by half its width each side; lo, hi point into st). */
typedef struct newton_start {
    double q[3], lo[3], hi[3];
} newton_start;

static void start_of(const ism_interval x[3], newton_start *st, ism_newton_opts *no)
{
    double width = 0.0;
    for (int k = 0; k < 3; k++) {
        double half = 0.5 * (x[k].hi - x[k].lo);
        width = fmax(width, x[k].hi - x[k].lo);
        st->q[k] = x[k].lo + half;
        st->lo[k] = x[k].lo - half;
        st->hi[k] = x[k].hi + half;
    }
    *no = (ism_newton_opts){ ISM_SING_PINV_REL, width, SEARCH_GN_TOL * width,
                             SEARCH_GN_ITERS, st->lo, st->hi, true };
}

/* The candidate x's box from Newton's run r from its centre, ended at q: projected there with
 * the Hessian's rank, or (not converged) centre_rank's. */
static ism_lbox ranked(const search *s, worker *w, const ism_interval x[3], const double q[3],
                       const ism_newton_result *r)
{
    if (!r->converged)
        return centre_rank(s, w, x, r->start_hess);
    ism_lbox b = { .rank = 0, .flags = ISM_LBOX_PROJECTED }; /* Newton's last jet is at q */
    for (int k = 0; k < 3; k++) {
        b.lo[k] = x[k].lo;
        b.hi[k] = x[k].hi;
        b.q[k] = q[k];
    }
    double eig[3];
    ism_sym3_eigen(r->hess, eig, NULL);
    b.rank = (uint8_t)ism_sing_rank(eig, s->hscale);
    return b;
}

/* A finest candidate: the centre projected onto ∇f = 0, the Hessian's rank there. */
static ism_lbox candidate(const search *s, worker *w, const ism_interval x[3])
{
    newton_start st;
    ism_newton_opts no;
    start_of(x, &st, &no);
    ism_newton_result r = ism_sing_newton(s->t, w->ws, st.q, &no, &w->evals_jet);
    return ranked(s, w, x, st.q, &r);
}

int ism_sing_rank(const double eig[3], double hscale)
{
    double m = fmax(fabs(eig[0]), fmax(fabs(eig[1]), fabs(eig[2])));
    double zero = fmax(ISM_SING_RANK_REL * m, ISM_SING_HZERO_REL * hscale);
    int r = 0;
    for (int i = 0; i < 3; i++)
        r += m > 0 && fabs(eig[i]) > zero;
    return r;
}

/* The largest Frobenius norm of the Hessian at the box's 3 × 3 × 3 lattice points (corners,
 * edge and face middles, centre), non-finite values skipped: the scale of f's curvature
 * across the box, against which a vanishing Hessian is told from a small one. */
static double hessian_scale(search *s)
{
    double best = 0.0;
    for (int m = 0; m < 27; m++) {
        double p[3], g[3], h[6];
        for (int k = 0; k < 3; k++)
            p[k] = s->lo[k] + 0.5 * s->ext[k] * (double)(m / (k == 0 ? 1 : k == 1 ? 3 : 9) % 3);
        ism_eval_hessian(s->t, s->workers[0].ws, p[0], p[1], p[2], g, h);
        s->workers[0].evals_jet++;
        double n2 = h[0] * h[0] + h[3] * h[3] + h[5] * h[5]
                    + 2.0 * (h[1] * h[1] + h[2] * h[2] + h[4] * h[4]);
        if (isfinite(n2))
            best = fmax(best, sqrt(n2));
    }
    return best;
}

/* The lattice z of a cell's key (cell_key). */
#define KEY_Z_SHIFT 39

static uint64_t cell_key(const scell *c)
{
    return (uint64_t)c->i[2] << KEY_Z_SHIFT | (uint64_t)c->i[1] << 22 | (uint64_t)c->i[0] << 5
           | c->level;
}

/* Keeps a tested child (whose F interval is f; m: its model when the verdict is SMOOTH): a
 * frontier cell (with its model), a finest candidate or a UNIQUE box. A finest cell where f
 * is unbounded (a pole: 1/(x² + y² + z² − 1/4) would otherwise leave the whole pole sphere)
 * and Newton finds no zero of ∇f is not kept: nothing finer than a cell can be said there,
 * and no later stage could use it. A level holds far fewer than 2^32 cells (each model is
 * ~250 bytes; max_boxes), so a model's index fits its field. */
static void keep(search *s, worker *w, task_out *out, scell c, const ism_dual_model *m,
                 const ism_interval x[3], ism_interval f, int verdict)
{
    bool ok;
    if (verdict != UNIQUE && (int)c.level < s->depth) {
        c.model = verdict == SMOOTH ? (uint32_t)out->models.n : NO_MODEL;
        ok = (verdict != SMOOTH || vec_push(&out->models, m, sizeof *m))
             && vec_push(&out->cells, &c, sizeof c);
    } else {
        keyed_box kb = { cell_key(&c), { .rank = 0 }, false };
        if (verdict != UNIQUE && !(isfinite(f.lo) && isfinite(f.hi))) {
            kb.box = candidate(s, w, x); /* kept only if projected: decided here */
            if (!(kb.box.flags & ISM_LBOX_PROJECTED))
                return;
        } else if (verdict != UNIQUE) {
            for (int k = 0; k < 3; k++) {
                kb.box.lo[k] = x[k].lo;
                kb.box.hi[k] = x[k].hi;
            }
            kb.pending = true;
        } else {
            for (int k = 0; k < 3; k++) {
                kb.box.lo[k] = x[k].lo;
                kb.box.hi[k] = x[k].hi;
                kb.box.q[k] = x[k].lo + 0.5 * (x[k].hi - x[k].lo);
            }
            kb.box.rank = 3; /* Krawczyk: every Hessian in the box is non-singular */
            kb.box.flags = ISM_LBOX_UNIQUE;
        }
        ok = vec_push(&out->boxes, &kb, sizeof kb);
    }
    out->oom |= !ok;
    if (atomic_fetch_add(&s->kept, 1) + 1 > s->o->max_boxes)
        atomic_store(&s->stop, 3);
}

/* Deadline and cancel, looked at between tasks. */
static bool should_stop(search *s)
{
    if (atomic_load(&s->stop))
        return true;
    if (s->o->cancel && *s->o->cancel) {
        atomic_store(&s->stop, 2);
        return true;
    }
    if (s->o->deadline_ms > 0 && ism_now_ms() > s->o->deadline_ms) {
        atomic_store(&s->stop, 1);
        return true;
    }
    return false;
}

/* Whether q lies in b grown by SEARCH_SHARE_REL of its width. */
static bool on_box(const double q[3], const ism_lbox *b)
{
    for (int k = 0; k < 3; k++) {
        double g = SEARCH_SHARE_REL * (b->hi[k] - b->lo[k]);
        if (!(q[k] >= b->lo[k] - g && q[k] <= b->hi[k] + g))
            return false;
    }
    return true;
}

typedef struct projection {
    search *s;
    keyed_box *boxes;
    size_t n;
} projection;

/* The nearest earlier projected box of the run [a, i) whose projection lies on box i (NULL:
 * none): back through the run while the lattice z (the key's top bits) can still touch,
 * every projected box being a finest cell, whose lower corner then lies at most one cell
 * below. */
static const ism_lbox *shared_from(const keyed_box *boxes, size_t a, size_t i)
{
    uint64_t z = boxes[i].key >> KEY_Z_SHIFT;
    for (size_t j = i; j-- > a && (boxes[j].key >> KEY_Z_SHIFT) + 1 >= z;) {
        const ism_lbox *o = &boxes[j].box;
        if ((o->flags & ISM_LBOX_PROJECTED) && on_box(o->q, &boxes[i].box))
            return o;
    }
    return NULL;
}

/* One run of candidates in key order: each pending one takes the projection of an earlier
 * projected box of the run lying on it (the nearest before it), else its own (candidate).
 * Which it takes depends on the projections before it, so every pending candidate's own
 * run is taken first, side by side (ism_sing_newton_lanes: each exactly candidate's), and
 * the rule then applied in key order. The runs of candidates that then share are spent
 * for nothing, and still the runs cost less side by side than one by one (their Hessians
 * batched and their pseudo-inverse steps four at a time, sym3_lanes.h; measured in commits
 * fe537109 and f59c663a). Past the deadline or cancelled: centres and their ranks only (a spent
 * box budget stops the subdivision, not this); w->evals_jet counts every Hessian taken, spent
 * ones too. */
static void project_run(void *ctx, size_t task, int thread)
{
    projection *pr = ctx;
    search *s = pr->s;
    worker *w = &s->workers[thread];
    size_t a = task * SEARCH_PROJECT_RUN, b = a + SEARCH_PROJECT_RUN;
    if (b > pr->n)
        b = pr->n;
    should_stop(s);
    int why = atomic_load(&s->stop);
    bool late = why == 1 || why == 2;
    newton_start st[SEARCH_PROJECT_RUN];
    ism_newton_opts no[SEARCH_PROJECT_RUN];
    double p[SEARCH_PROJECT_RUN][3];
    ism_newton_result r[SEARCH_PROJECT_RUN];
    size_t lane[SEARCH_PROJECT_RUN], n = 0;
    for (size_t i = a; i < b && !late; i++) {
        keyed_box *kb = &pr->boxes[i];
        if (!kb->pending)
            continue;
        ism_interval x[3];
        for (int k = 0; k < 3; k++)
            x[k] = iv(kb->box.lo[k], kb->box.hi[k]);
        start_of(x, &st[n], &no[n]);
        memcpy(p[n], st[n].q, sizeof p[n]);
        lane[i - a] = n++;
    }
    ism_sing_newton_lanes(s->t, w->ws, p, no, r, n, &w->evals_jet);
    for (size_t i = a; i < b; i++) {
        keyed_box *kb = &pr->boxes[i];
        if (!kb->pending)
            continue;
        kb->pending = false;
        ism_lbox *bx = &kb->box;
        const ism_lbox *from = shared_from(pr->boxes, a, i);
        if (from) {
            memcpy(bx->q, from->q, sizeof bx->q);
            bx->rank = from->rank;
            bx->flags = ISM_LBOX_PROJECTED;
            continue;
        }
        ism_interval x[3];
        for (int k = 0; k < 3; k++)
            x[k] = iv(bx->lo[k], bx->hi[k]);
        if (late) {
            *bx = centre_rank(s, w, x, NULL);
            continue;
        }
        size_t l = lane[i - a];
        *bx = ranked(s, w, x, p[l], &r[l]);
    }
}

/* Projects the pending candidates of boxes (sorted by key), in runs of SEARCH_PROJECT_RUN. */
static void project_all(search *s, keyed_box *boxes, size_t n)
{
    projection pr = { s, boxes, n };
    size_t runs = (n + SEARCH_PROJECT_RUN - 1) / SEARCH_PROJECT_RUN;
    ism_parallel_for(runs < 2 ? 1 : s->threads, runs, project_run, &pr);
}

/* Finishes a cell c (box x, F interval f; v: screen's verdict; fc: f at its centre or NULL,
 * q: its parent's children_quad): classified when open,
 * then kept unless excluded, with its centre lines when it joins the frontier with a model
 * (m: scratch). A certified segment's cell gets its model here (the finest need none). */
static void finish(search *s, worker *w, task_out *out, scell *c, const ism_interval x[3],
                   ism_interval f, int v, const ism_interval *fc, ism_interval q,
                   ism_dual_model *m, const pre_grad *pre)
{
    if (v == SMOOTH && (int)c->level < s->depth)
        certified_model(s, w, x, m);
    if (v == OPEN)
        v = classify(s, w, x, fc, q, m, pre);
    if (v == EXCLUDED)
        return;
    if (v == SMOOTH)
        c->lines = centre_lines(s, w, c, m);
    keep(s, w, out, *c, m, x, f, v);
}

/* A child whose interval gradients a batch takes (pre_gradients): its box and where they
 * go. */
typedef struct pre_slot {
    ism_interval x[3];
    pre_grad *pre;
} pre_slot;

/* A parent's children between their screening (expand_prepare) and their finish
 * (expand_finish): cells, boxes, F intervals and screen's verdicts, f at the centres taken
 * (at[m] into fc; NULL when not), the parent's children_quad q and what the batches took. */
typedef struct expansion {
    scell kids[8];
    ism_interval bx[8], by[8], bz[8], f[8], fc[8], q;
    const ism_interval *at[8];
    int v[8];
    bool model; /* the parent has a model: its children's centre test ran */
    pre_grad pre[8];
} expansion;

/* Child m of e that classify will take the interval gradient of (left OPEN by screen and
 * not dropped by the centre test) into *sl. */
static bool open_slot(expansion *e, int m, pre_slot *sl)
{
    if (e->v[m] != OPEN || centre_drops(e->at[m], e->q))
        return false;
    sl->x[0] = e->bx[m];
    sl->x[1] = e->by[m];
    sl->x[2] = e->bz[m];
    sl->pre = &e->pre[m];
    return true;
}

/* The children sl[0..n) that classify will take the interval gradient of, in order: with
 * centres, at most ISM_IVGRAD_BATCH / 2 of them, their gradients over their boxes and at their
 * centres (smooth_tests' centre_at, taken for every such child: the box's may exclude 0, and
 * then the centre's is not used); without, at most ISM_IVGRAD_BATCH, over their boxes only.
 * In one ism_eval_interval_grad_lanes (or _batch without kinks), bit for bit the one-by-one
 * passes (classify's kept pass; centre_at's), into each slot's pre_grad; the jets
 * smooth_tests then takes over the boxes take the batch's records as they took the kept
 * pass's (pre_jets or box_jets, right after). Cheaper than one by one from 2 lanes up
 * (interval_jet.h, ISM_IVGRAD_BATCH's figures). With min, max or abs the lanes list each box's
 * kinks as classify's pass would (ism_eval_interval_grad_lanes). Without centres: on tapes
 * without kinks round_take, which takes the centres needed afterwards (centres_take); on tapes
 * with kinks a parent without a model (no centre test), whose children's centres are left to
 * centre_at: few of those children reach smooth_tests (Barth at E 0.0259: with the centres
 * 1,287.5M instructions, without 1,273.1M, one by one 1,284.2M). Whether they were taken. */
static bool pre_gradients(const search *s, worker *w, const pre_slot *sl, size_t n, bool centres)
{
    ism_interval box[ISM_IVGRAD_BATCH][3];
    ism_ivgrad g[ISM_IVGRAD_BATCH];
    for (size_t k = 0; k < n; k++) {
        double c[3];
        centre_of(sl[k].x, c);
        for (int a = 0; a < 3; a++) {
            box[k][a] = sl[k].x[a];
            if (centres)
                box[n + k][a] = iv(c[a], c[a]);
        }
    }
    uint32_t nk[ISM_IVGRAD_BATCH] = { 0 };
    size_t nb = centres ? 2 * n : n;
    const ism_interval (*b)[3] = (const ism_interval (*)[3])box;
    if (!n || !(s->branches ? ism_eval_interval_grad_lanes(s->t, w->jw, b, nb, g, nk)
                            : ism_eval_interval_grad_batch(s->t, w->jw, b, nb, g)))
        return false;
    for (size_t k = 0; k < n; k++) { /* field by field: jet is written by pre_jets alone */
        pre_grad *p = sl[k].pre;
        p->ok = true;
        p->at_ok = centres;
        p->g = g[k];
        p->at = centres ? g[n + k] : g[k];
        p->nk = nk[k];
    }
    w->grads_batched += n;
    w->centres_batched += centres ? n : 0;
    return true;
}

/* The jets over box[0..n) (n <= ISM_IVGRAD_BATCH) into kid[k]'s jet, bit for bit the
 * one-by-one jets: in one ism_eval_interval_jet_lanes (Hessians alone from the last batched
 * pass's records on tapes without kinks, when every box's lies in one group of its lanes); a
 * lone one (PRE_JETS_MIN) by ism_eval_interval_jet, now: on tapes without kinks from its
 * record, which only stands until the next pass (with kinks the pass keeps no record, and the
 * order does not matter). */
static void jets_into(const search *s, worker *w, const ism_interval (*box)[3], pre_grad **kid,
                      size_t n)
{
    ism_ivjet jet[ISM_IVGRAD_BATCH];
    if (!n)
        return;
    if (n < PRE_JETS_MIN)
        ism_eval_interval_jet(s->t, w->jw, box[0], NULL, NULL, &jet[0]);
    else if (!ism_eval_interval_jet_lanes(s->t, w->jw, box, n, jet))
        return;
    for (size_t k = 0; k < n; k++) {
        kid[k]->jet = jet[k];
        kid[k]->jet_ok = true;
    }
}

/* After pre_gradients with centres over sl[0..n) (tapes with kinks: batch_kinked): the jets
 * (jets_into) over the boxes of those whose smooth_tests will take one (classify's and
 * smooth_tests' tests on what pre_gradients took, the same functions: no free kink, ∇F may
 * vanish, first_order_holds). */
static void pre_jets(const search *s, worker *w, const pre_slot *sl, size_t ns)
{
    ism_interval box[ISM_IVGRAD_BATCH][3];
    pre_grad *kid[ISM_IVGRAD_BATCH];
    size_t n = 0;
    for (size_t i = 0; i < ns && n < ISM_IVGRAD_BATCH; i++) {
        pre_grad *p = sl[i].pre;
        if (!p->ok || !p->at_ok || p->nk || !grad_may_vanish(p->g.d))
            continue;
        ism_interval cx[3], dx[3];
        double c[3];
        centre_of(sl[i].x, c);
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            cx[k] = iv(c[k], c[k]);
        if (!first_order_holds(sl[i].x, cx, &p->at, &p->g, dx))
            continue;
        memcpy(box[n], sl[i].x, sizeof box[n]);
        kid[n++] = p;
    }
    jets_into(s, w, (const ism_interval (*)[3])box, kid, n);
}

/* p's eight children's F intervals in one batch, screened; then, when p has a model, f at
 * the centres of the children left open where centre_worth guesses it may rule them out, in
 * a second batch (point boxes: rigorous enclosures of f there), for children_quad's test.
 * No gradient taken yet (every pre[m] not ok). */
static void expand_prepare(search *s, worker *w, const scell *p, expansion *e)
{
    uint32_t half = 1u << (s->depth - (int)p->level - 1);
    /* the parent's low, middle and high lattice coordinates per axis: each child's bounds
     * are two of them (cell_box's, bit for bit) */
    ism_interval lower[3], upper[3];
    for (int k = 0; k < 3; k++) {
        double lo = coord(s, k, p->i[k]), mid = coord(s, k, p->i[k] + half),
               hi = coord(s, k, p->i[k] + 2 * half);
        lower[k] = iv(lo, mid);
        upper[k] = iv(mid, hi);
    }
    for (int m = 0; m < 8; m++) {
        scell *kid = &e->kids[m];
        kid->level = (uint8_t)(p->level + 1); /* .model: keep sets it */
        kid->lines = 0;                       /* .lines: set once tested (finish) */
        kid->edges = child_edges(p, (unsigned)m);
        for (int k = 0; k < 3; k++)
            kid->i[k] = p->i[k] + ((m >> k) & 1u ? half : 0u);
        e->bx[m] = m & 1 ? upper[0] : lower[0];
        e->by[m] = m & 2 ? upper[1] : lower[1];
        e->bz[m] = m & 4 ? upper[2] : lower[2];
        e->at[m] = NULL;
        e->pre[m].ok = e->pre[m].jet_ok = false;
    }
    ism_eval_interval_batch(s->t, w->ws, e->bx, e->by, e->bz, e->f, 8);
    w->evals_interval += 8;
    const ism_dual_model *pm = p->model == NO_MODEL ? NULL : &s->models[p->model];
    e->model = pm != NULL;
    e->q = iv(0.0, 0.0);
    if (!pm) { /* no centre test */
        for (int m = 0; m < 8; m++) {
            ism_interval x[3] = { e->bx[m], e->by[m], e->bz[m] };
            e->v[m] = screen(w, &e->kids[m], x, e->f[m], NULL, 0);
        }
        return;
    }
    parent_rows rows = { .pm = pm, .lower = lower, .upper = upper, .ready = false };
    ism_interval cx[8], cy[8], cz[8];
    size_t lane[8], open = 0;
    bool have_q = false; /* q taken (once, for the first child left open) */
    for (int m = 0; m < 8; m++) {
        ism_interval x[3] = { e->bx[m], e->by[m], e->bz[m] };
        double c[3];
        e->v[m] = screen(w, &e->kids[m], x, e->f[m], &rows, (unsigned)m);
        lane[m] = SIZE_MAX;
        if (e->v[m] != OPEN)
            continue;
        if (!have_q) {
            e->q = children_quad(pm, lower, upper);
            have_q = true;
        }
        centre_of(x, c);
        if (!centre_worth(pm, c, e->q))
            continue;
        cx[open] = iv(c[0], c[0]);
        cy[open] = iv(c[1], c[1]);
        cz[open] = iv(c[2], c[2]);
        lane[m] = open++;
    }
    if (open) {
        ism_eval_interval_batch(s->t, w->ws, cx, cy, cz, e->fc, open);
        w->evals_interval += open;
    }
    for (int m = 0; m < 8; m++)
        e->at[m] = lane[m] == SIZE_MAX ? NULL : &e->fc[lane[m]];
}

/* One parent's batches, on a tape with kinks (classify reads the last pass's kink bytes and
 * registers, ism_ivjet_lane_kinks, ism_ivjet_top_pieces, so its children are finished right
 * after): with a model, its first ISM_IVGRAD_BATCH / 2 such children with their centres and
 * their jets; without, up to ISM_IVGRAD_BATCH boxes alone, two at the least (a lone box:
 * one 4-lane group, ~2,100 instructions, against its pass alone, ~1,700). */
static void batch_kinked(const search *s, worker *w, expansion *e)
{
    pre_slot sl[8];
    size_t n = 0, most = e->model ? ISM_IVGRAD_BATCH / 2 : ISM_IVGRAD_BATCH;
    for (int m = 0; m < 8 && n < most; m++)
        n += open_slot(e, m, &sl[n]);
    if (e->model && pre_gradients(s, w, sl, n, true))
        pre_jets(s, w, sl, n);
    else if (!e->model && n >= 2)
        pre_gradients(s, w, sl, n, false);
}

/* Boxes of one group of a batched gradient pass (interval_jet.h): the jets from a pass's
 * records take the boxes of one group at a time. */
#define GRAD_GROUP ISM_IVGRAD_GROUP

/* After pre_gradients over boxes alone (tapes without kinks: round_take), sl[0..ns) one group
 * of its boxes, no other batched pass since: the jets (jets_into, from the pass's records)
 * over those whose ∇F over the box may vanish (classify's test on what pre_gradients took),
 * their slots moved to the front of sl; returns how many. Taken before the centres'
 * gradients (centres_take), so also for the cells first_order_holds then drops, which it
 * rarely does on a smooth tape (Klein at E 0.0141 and the torus: none). */
static size_t box_jets(const search *s, worker *w, pre_slot *sl, size_t ns)
{
    ism_interval box[GRAD_GROUP][3];
    pre_grad *kid[GRAD_GROUP];
    size_t n = 0;
    for (size_t i = 0; i < ns; i++)
        if (sl[i].pre->ok && grad_may_vanish(sl[i].pre->g.d)) {
            memcpy(box[n], sl[i].x, sizeof box[n]);
            kid[n] = sl[i].pre;
            sl[n++] = sl[i];
        }
    jets_into(s, w, (const ism_interval (*)[3])box, kid, n);
    return n;
}

/* The gradients at the centres of the cells sl[0..n) (n <= ISM_IVGRAD_BATCH) in one
 * ism_eval_interval_grad_batch over their centres as point boxes (centre_at's, bit for bit),
 * into each slot's pre_grad at. */
static void centres_take(const search *s, worker *w, const pre_slot *sl, size_t n)
{
    ism_interval box[ISM_IVGRAD_BATCH][3];
    ism_ivgrad g[ISM_IVGRAD_BATCH];
    for (size_t k = 0; k < n; k++) {
        double c[3];
        centre_of(sl[k].x, c);
        _Pragma("GCC unroll 3") for (int a = 0; a < 3; a++)
            box[k][a] = iv(c[a], c[a]);
    }
    if (!n || !ism_eval_interval_grad_batch(s->t, w->jw, (const ism_interval (*)[3])box, n, g))
        return;
    for (size_t k = 0; k < n; k++) {
        sl[k].pre->at = g[k];
        sl[k].pre->at_ok = true;
    }
}

/* A task's batches on a tape without kinks (batch_smooth): the open children's boxes in
 * rounds of ISM_IVGRAD_BATCH, the centres of those whose ∇F may vanish (the only ones
 * smooth_tests takes a centre of) gathered across rounds. */
typedef struct smooth_rounds {
    pre_slot box[ISM_IVGRAD_BATCH], centre[ISM_IVGRAD_BATCH];
    size_t nbox, ncentre;
} smooth_rounds;

/* One round: its boxes' gradients in one pass, each group's jets right after it (before the
 * next pass overwrites its records), then their centres queued, a full queue taken. */
static void round_take(const search *s, worker *w, smooth_rounds *r)
{
    if (!r->nbox || !pre_gradients(s, w, r->box, r->nbox, false)) {
        r->nbox = 0;
        return;
    }
    size_t kept[ISM_IVGRAD_BATCH / GRAD_GROUP], groups = 0;
    for (size_t a = 0; a < r->nbox; a += GRAD_GROUP, groups++)
        kept[groups] = box_jets(s, w, r->box + a,
                                r->nbox - a < GRAD_GROUP ? r->nbox - a : GRAD_GROUP);
    for (size_t g = 0; g < groups; g++)
        for (size_t k = 0; k < kept[g]; k++) {
            r->centre[r->ncentre++] = r->box[g * GRAD_GROUP + k];
            w->centres_batched++; /* given to the queue: read only once centres_take ran */
            if (r->ncentre == ISM_IVGRAD_BATCH) {
                centres_take(s, w, r->centre, r->ncentre);
                r->ncentre = 0;
            }
        }
    r->nbox = 0;
}

/* The batches of a task's parents e[0..n) on a tape without kinks: the children with a
 * parent with a model, across parents, in rounds of ISM_IVGRAD_BATCH boxes alone (round_take),
 * and the centres' gradients only for the children whose ∇F over the box may vanish: the
 * others' centres are never read (Klein at E 0.0141: 1,726 of the 4,211 boxes). Before,
 * every box went with its centre, 4 + 4 lanes a pass. Children of parents without a model are
 * taken one by one (on smooth tapes the torus's search paid more for their batches). */
static void batch_smooth(const search *s, worker *w, expansion *e, size_t n)
{
    smooth_rounds r;
    r.nbox = r.ncentre = 0;
    for (size_t i = 0; i < n; i++)
        for (int m = 0; e[i].model && m < 8; m++)
            if (open_slot(&e[i], m, &r.box[r.nbox]) && ++r.nbox == ISM_IVGRAD_BATCH)
                round_take(s, w, &r);
    round_take(s, w, &r);
    centres_take(s, w, r.centre, r.ncentre);
}

/* Each child of e finished in order. */
static void expand_finish(search *s, worker *w, task_out *out, expansion *e)
{
    ism_dual_model km; /* a child's model, built by its tests */
    for (int m = 0; m < 8; m++) {
        ism_interval x[3] = { e->bx[m], e->by[m], e->bz[m] };
        finish(s, w, out, &e->kids[m], x, e->f[m], e->v[m], e->at[m], e->q, &km, &e->pre[m]);
    }
}

/* Expands a task's frontier cells, in order, into its output. */
static void expand_task(void *ctx, size_t task, int thread)
{
    search *s = ctx;
    if (should_stop(s))
        return;
    size_t a = task * SEARCH_CELLS_PER_TASK, b = a + SEARCH_CELLS_PER_TASK;
    if (b > s->nfrontier)
        b = s->nfrontier;
    worker *w = &s->workers[thread];
    task_out *out = &s->outs[task];
    if (s->branches) {
        for (size_t i = a; i < b; i++) {
            expand_prepare(s, w, &s->frontier[i], &w->ex[0]);
            if (s->batch)
                batch_kinked(s, w, &w->ex[0]);
            expand_finish(s, w, out, &w->ex[0]);
        }
        return;
    }
    for (size_t i = a; i < b; i++)
        expand_prepare(s, w, &s->frontier[i], &w->ex[i - a]);
    if (s->batch)
        batch_smooth(s, w, w->ex, b - a);
    for (size_t i = a; i < b; i++)
        expand_finish(s, w, out, &w->ex[i - a]);
}

static void free_workers(search *s)
{
    for (int i = 0; s->workers && i < s->threads; i++) {
        ism_eval_ws_free(s->workers[i].ws);
        ism_ivjet_ws_free(s->workers[i].jw);
        free(s->workers[i].kinks);
        free(s->workers[i].force);
        free(s->workers[i].ex);
    }
    free(s->workers);
}

static bool make_workers(search *s)
{
    s->workers = calloc((size_t)s->threads, sizeof *s->workers);
    if (!s->workers)
        return false;
    size_t len = ism_tape_length(s->t) ? ism_tape_length(s->t) : 1;
    for (int i = 0; i < s->threads; i++) {
        worker *w = &s->workers[i];
        w->ws = ism_eval_ws_new(s->t);
        w->jw = ism_ivjet_ws_new(s->t);
        w->kinks = calloc(len, 1);
        w->force = calloc(len, 1);
        w->ex = malloc(SEARCH_CELLS_PER_TASK * sizeof *w->ex);
        if (!w->ws || !w->jw || !w->kinks || !w->force || !w->ex)
            return false;
    }
    return true;
}

/* A frontier: its cells and their models. */
typedef struct level {
    vec cells, models;
} level;

/* Appends a task's output to the next frontier l (its model indices moved past the models
 * before it) and to boxes, and frees it. */
static bool join(task_out *o, level *l, vec *boxes, bool ok)
{
    size_t base = l->models.n;
    ok = ok && !o->oom
         && vec_append(&l->models, o->models.p, o->models.n, sizeof(ism_dual_model))
         && vec_append(boxes, o->boxes.p, o->boxes.n, sizeof(keyed_box));
    size_t at = l->cells.n;
    ok = ok && vec_append(&l->cells, o->cells.p, o->cells.n, sizeof(scell));
    for (size_t i = at; ok && i < l->cells.n; i++) {
        scell *c = (scell *)l->cells.p + i;
        if (c->model != NO_MODEL)
            c->model += (uint32_t)base;
    }
    free(o->cells.p);
    free(o->models.p);
    free(o->boxes.p);
    return ok;
}

/* Runs one level: expands the frontier into *next and appends boxes to *boxes. */
static bool run_level(search *s, level *next, vec *boxes)
{
    size_t ntasks = (s->nfrontier + SEARCH_CELLS_PER_TASK - 1) / SEARCH_CELLS_PER_TASK;
    s->outs = calloc(ntasks ? ntasks : 1, sizeof *s->outs);
    if (!s->outs)
        return false;
    int threads = s->nfrontier < SEARCH_PARALLEL_MIN ? 1 : s->threads;
    ism_parallel_for(threads, ntasks, expand_task, s);
    bool ok = true;
    for (size_t t = 0; t < ntasks; t++)
        ok = join(&s->outs[t], next, boxes, ok);
    free(s->outs);
    s->outs = NULL;
    return ok;
}

static int by_key(const void *a, const void *b)
{
    uint64_t x = ((const keyed_box *)a)->key, y = ((const keyed_box *)b)->key;
    return x < y ? -1 : x > y;
}

static const char *stop_reason(int why)
{
    switch (why) {
    case 1: return "deadline reached during the singular-point search";
    case 2: return "cancelled during the singular-point search";
    default: return "candidate-box budget (max_boxes) exhausted in the singular-point search";
    }
}

/* The root cell: tested like any child (its F interval computed alone). */
static bool seed(search *s, level *l, vec *boxes)
{
    scell root = { .level = 0, .lines = 0, .edges = 0, .model = NO_MODEL };
    ism_interval x[3];
    cell_box(s, &root, x);
    worker *w = &s->workers[0];
    ism_interval f = ism_eval_interval(s->t, w->ws, x[0], x[1], x[2]);
    w->evals_interval++;
    ism_dual_model m;
    task_out out = { .oom = false };
    int v = screen(w, &root, x, f, NULL, 0);
    finish(s, w, &out, &root, x, f, v, NULL, iv(0.0, 0.0), &m, NULL);
    return join(&out, l, boxes, true);
}

static bool check_options(const ism_locus_options *o, ism_error *err)
{
    if (o->max_depth < 0 || o->max_depth > SEARCH_MAX_DEPTH)
        return ism_error_set(err, "singular search: depth %d outside 0..%d", o->max_depth,
                             SEARCH_MAX_DEPTH);
    for (int k = 0; k < 3; k++)
        if (!(o->box[k] < o->box[k + 3]) || !isfinite(o->box[k]) || !isfinite(o->box[k + 3]))
            return ism_error_set(err, "singular search: empty or non-finite box");
    return true;
}

/* Runs the levels into *boxes; returns false on out of memory. */
static bool subdivide(search *s, vec *boxes)
{
    level cur = { { 0 }, { 0 } }, next = { { 0 }, { 0 } };
    bool ok = seed(s, &cur, boxes);
    for (int depth = 0; ok && depth < s->depth && cur.cells.n && !atomic_load(&s->stop);
         depth++) {
        s->frontier = cur.cells.p;
        s->models = cur.models.p;
        s->nfrontier = cur.cells.n;
        atomic_store(&s->kept, boxes->n);
        next.cells.n = next.models.n = 0;
        ok = run_level(s, &next, boxes);
        level t = cur;
        cur = next;
        next = t;
    }
    free(cur.cells.p);
    free(cur.models.p);
    free(next.cells.p);
    free(next.models.p);
    return ok;
}

bool ism_sing_search(const ism_tape *f, const ism_locus_options *o, ism_locus *out,
                     ism_error *err)
{
    return ism_sing_search_batched(f, o, true, out, err);
}

bool ism_sing_search_batched(const ism_tape *f, const ism_locus_options *o, bool batch,
                             ism_locus *out, ism_error *err)
{
    double t0 = ism_now_ms();
    if (!check_options(o, err))
        return false;
    search s = { .t = f, .o = o, .depth = o->max_depth, .unit = ldexp(1.0, -o->max_depth),
                 .branches = ism_tape_has_kink(f), .batch = batch };
    for (int k = 0; k < 3; k++) {
        s.lo[k] = o->box[k];
        s.hi[k] = o->box[k + 3];
        s.ext[k] = s.hi[k] - s.lo[k];
    }
    s.threads = ism_threads_resolve(o->threads);
    atomic_init(&s.stop, 0);
    atomic_init(&s.kept, 0);
    vec boxes = { 0 };
    bool ok = make_workers(&s);
    if (ok) {
        s.hscale = hessian_scale(&s);
        out->hessian_scale = s.hscale;
    }
    ok = ok && subdivide(&s, &boxes);
    if (ok) {
        if (boxes.n)
            qsort(boxes.p, boxes.n, sizeof(keyed_box), by_key);
        size_t n = boxes.n < o->max_boxes ? boxes.n : o->max_boxes;
        project_all(&s, boxes.p, n);
        for (size_t i = 0; ok && i < n; i++)
            ok = ism_locus_add_box(out, &((keyed_box *)boxes.p)[i].box);
    }
    int why = atomic_load(&s.stop);
    if (ok && why) {
        out->incomplete = true;
        snprintf(out->incomplete_why, sizeof out->incomplete_why, "%s", stop_reason(why));
    }
    for (int i = 0; s.workers && i < s.threads; i++) {
        out->boxes_visited += s.workers[i].visited;
        out->evals_interval += s.workers[i].evals_interval;
        out->evals_jet += s.workers[i].evals_jet;
        out->centre_dropped += s.workers[i].centre_dropped;
        out->grads_batched += s.workers[i].grads_batched;
        out->grads_batch_read += s.workers[i].grads_batch_read;
        out->centres_batched += s.workers[i].centres_batched;
        out->centres_batch_read += s.workers[i].centres_batch_read;
    }
    free(boxes.p);
    free_workers(&s);
    out->time_ms += ism_now_ms() - t0;
    if (!ok)
        return ism_error_set(err, "singular search: out of memory");
    return true;
}
