/* dual_cert.h — what the dual mesher (dual.h) proves about one box without making octree
 * nodes: an enclosure of f and ∇f tighter than the natural interval (second-order Taylor
 * form round the box's centre, intersected with the natural one), f kept from 0 over the
 * box, and f = 0 one graph along a direction over it — both tried on sub-boxes when the whole
 * box's enclosure is too wide.
 *
 * Why: the natural interval of a polynomial like the torus's loses to its dependencies (∇f
 * of width ~2 |∇f| over a cell a third of the tube's radius across), so cells beside the
 * surface could be proven neither empty nor one sheet and were split, each split costing 27
 * gradient samples, 8 nodes and later vertices and triangles. The Taylor form's width shrinks
 * with the square of the box (f) or with the box times the Hessian (∇f).
 *
 * Every bound is outward rounded (interval_ops.h): the value and gradient at the centre are
 * the interval jet of the degenerate box, so the verdicts are proofs. */
#ifndef ISM_DUAL_CERT_H
#define ISM_DUAL_CERT_H

#include <stdbool.h>
#include <stdint.h>
#include "core/eval/interval_jet.h"
#include "core/eval/interval_ops.h"

/* A second-order Taylor model of f over a box: f and ∇f at the box's centre c (the interval
 * jet of the degenerate box [c, c]: exact up to outward rounding) and the natural enclosure
 * of f, ∇f and the Hessian over the box. */
typedef struct ism_dual_model {
    double c[3];
    ism_ivgrad at;
    ism_ivjet box;
} ism_dual_model;

/* The model of f over lo..hi; false when f has a kink in the box or the workspace does not
 * fit t. *intervals counts the interval evaluations made (two). */
bool ism_dual_taylor(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                     const double hi[3], ism_dual_model *m, uint64_t *intervals);

/* ism_dual_taylor over lo[k]..hi[k] for k < n (n <= ISM_IVGRAD_BATCH) into m[k], bit for
 * bit, ok[k] its answer: the jets over the boxes in lanes (ism_eval_interval_jet_lanes: from
 * the records a batch of natural enclosures left for the boxes when they are in one of its
 * groups, interval_jet.h), then the gradients at the centres in one batch
 * (ism_eval_interval_grad_batch; its cost against one by one: interval_jet.h,
 * ISM_IVGRAD_BATCH). Counts no evaluation (the caller counts each model when it uses it, as
 * ism_dual_taylor would). False, with nothing in m or ok to use, where t holds a min, max or
 * abs (the lanes tell no kinks) or the batch does not take t: then take the models one by
 * one. */
bool ism_dual_taylor_many(const ism_tape *t, ism_ivjet_ws *jet, const double (*lo)[3],
                          const double (*hi)[3], size_t n, ism_dual_model *m, bool *ok);

/* ism_dual_taylor over lo[k]..hi[k] for k < 2 into m[k], bit for bit, ok[k] its answer:
 * the two boxes' jets and their centres' in one group of lanes (ism_eval_interval_jet_lanes;
 * dearer than one model alone, so for callers that will read both: dual_cert.c's proofs on
 * sub-boxes, where PAIRED_OPEN's comment gives the figures). Counts no evaluation. False, with
 * nothing in m or ok to use, where t holds a min, max or abs (the lanes tell no kinks) or
 * the lanes do not take t: then take them one by one. */
bool ism_dual_taylor_pair(const ism_tape *t, ism_ivjet_ws *jet, const double (*lo)[3],
                          const double (*hi)[3], ism_dual_model *m, bool *ok);

/* Encloses f and ∇f over lo..hi — the model's box or any box inside it (no evaluation) —
 * into *g: the Taylor form round c intersected with the natural enclosure. False when a
 * bound is not a number. */
bool ism_dual_over(const ism_dual_model *m, const double lo[3], const double hi[3],
                   ism_ivgrad *g);

/* ism_dual_over with v2 = ism_dual_second_order(m, lo, hi) already taken (bit for bit). */
bool ism_dual_over_v2(const ism_dual_model *m, const double lo[3], const double hi[3],
                      ism_interval v2, ism_ivgrad *g);

/* f over lo..hi (the model's box or one inside it) by the second-order Taylor form alone
 * (no meet with the other forms, no evaluation): the part of ism_dual_over a caller that
 * already met the natural and mean-value forms needs. */
ism_interval ism_dual_second_order(const ism_dual_model *m, const double lo[3],
                                   const double hi[3]);

/* What the model m says of each sub-box k of lo..hi halved at mid (NULL: the centre; bit a
 * of k the upper half along a), as the proofs on the sub-boxes take it (four sub-boxes a step
 * in lanes): form[k], ism_dual_second_order's bounds on the sub-box, and g[k] / ok[k],
 * ism_dual_over's enclosure and answer there. Unless every (the proofs' way), a group of
 * sub-boxes 0-3 or 4-7 whose four forms keep f from 0 takes no enclosures: ok false there
 * (g undefined). Kept public as the unit tests' view of those lanes (test_dual_cert.c: bit
 * for bit the scalar functions on each sub-box). */
void ism_dual_sub_encls(const ism_dual_model *m, const double lo[3], const double *mid,
                        const double hi[3], bool every, ism_interval form[8], ism_ivgrad g[8],
                        bool ok[8]);

/* For each k < n (n <= ISM_IVGRAD_BATCH), on lo[k]..hi[k] by its model m[k], four boxes a
 * step in lanes: v2[k] = ism_dual_second_order's bounds, ok[k] = ism_dual_over's answer and
 * g[k] its enclosure (when ok), bit for bit. Unless every, a group of boxes 4q..4q+3 whose
 * four forms keep f from 0 takes no enclosures (ok false there, g undefined), as
 * ism_dual_sub_encls. False, computing nothing, when n is out of range. For the models
 * ism_dual_taylor_many made; a box whose model failed there (ok false: its jet may be partly
 * written) runs in its lane all the same, and its v2, g, ok are undefined: the caller reads
 * only the others (dual_classify.c ism_dual_pre_models). */
bool ism_dual_over_many(const ism_dual_model *m, const double (*lo)[3], const double (*hi)[3],
                        size_t n, bool every, ism_interval *v2, ism_ivgrad *g, bool *ok);

/* Both in one: f and ∇f over lo..hi by its own model. */
bool ism_dual_enclose(const ism_tape *t, ism_ivjet_ws *jet, const double lo[3],
                      const double hi[3], ism_ivgrad *g, uint64_t *intervals);

/* The Hessian pair (a, b) in ism_ivjet's order (xx xy xz yy yz zz). */
static inline int ism_dual_hess_at(int a, int b)
{
    static const int AT[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
    return AT[a][b];
}

/* The terms of f's second-order form round c over x − c ∈ dx (at: f and ∇f at c, j: the jet
 * over a box holding x): lin[a] = ∂f/∂xa(c) · dxa, and quad in ism_ivjet's Hessian order,
 * ½ H_aa dxa² on the diagonal, H_ab dxa dxb off it (the two equal off-diagonal terms counted
 * once at twice their weight: H's xy entry times δx δy, twice, halved). For a caller that sums
 * them twice. Inline (both loops unrolled, the terms kept in registers): dual_cert.c's
 * second-order form and the singular search's jet test, once per tested cell. */
typedef struct ism_dual_terms {
    ism_interval lin[3], quad[6];
} ism_dual_terms;

/* The quadratic form's term (a, b ≥ a) over x − c ∈ dx (j: the jet over a box holding x):
 * ½ H_aa dxa² on the diagonal, H_ab dxa dxb off it (the pair counted once, whole). The one
 * copy of the term: ism_dual_terms_of and ism_dual_quad. */
static inline ism_interval ism_dual_quad_term(const ism_ivjet *j, const ism_interval dx[3],
                                              int a, int b)
{
    if (a == b)
        return iv_mul_c(iv_mul(j->h[ism_dual_hess_at(a, a)], iv_square(dx[a])), 0.5);
    return iv_mul(j->h[ism_dual_hess_at(a, b)], iv_mul(dx[a], dx[b]));
}

static inline void ism_dual_terms_of(const ism_ivgrad *at, const ism_ivjet *j,
                                     const ism_interval dx[3], ism_dual_terms *t)
{
    _Pragma("GCC unroll 3") for (int a = 0; a < 3; a++) {
        t->lin[a] = iv_mul(at->d[a], dx[a]);
        _Pragma("GCC unroll 3") for (int b = a; b < 3; b++)
            t->quad[ism_dual_hess_at(a, b)] = ism_dual_quad_term(j, dx, a, b);
    }
}

/* ½ (x − c)ᵀ H (x − c) over x − c ∈ dx, H the Hessian enclosure of j: the terms of
 * ism_dual_quad_term summed from 0 in ism_ivjet's order (the singular search's centre test,
 * search.c children_quad). */
static inline ism_interval ism_dual_quad(const ism_ivjet *j, const ism_interval dx[3])
{
    ism_interval q = iv(0.0, 0.0);
    _Pragma("GCC unroll 3") for (int a = 0; a < 3; a++)
        _Pragma("GCC unroll 3") for (int b = a; b < 3; b++)
            q = iv_add(q, ism_dual_quad_term(j, dx, a, b));
    return q;
}

/* fc + Σ lin + Σ quad: f's second-order form, summed in ism_dual_second_order's order (the
 * same bounds): each variable's linear term, then its Hessian row from the diagonal on. */
static inline ism_interval ism_dual_terms_f(ism_interval fc, const ism_dual_terms *t)
{
    _Pragma("GCC unroll 3") for (int a = 0; a < 3; a++) {
        fc = iv_add(fc, t->lin[a]);
        _Pragma("GCC unroll 3") for (int b = a; b < 3; b++)
            fc = iv_add(fc, t->quad[ism_dual_hess_at(a, b)]);
    }
    return fc;
}

/* Σ quad: ½ (x − c)ᵀ H(X) (x − c) alone. */
ism_interval ism_dual_terms_quad(const ism_dual_terms *t);

/* 0 outside the enclosure's value: f has no zero in the box. */
static inline bool ism_dual_encl_free(const ism_ivgrad *g) { return g->v.lo > 0 || g->v.hi < 0; }

/* f has no zero in lo..hi (m: its model): by m's enclosure, else on each sub-box, split
 * down to `halvings` halvings — first by m (no evaluation), then by the sub-box's own
 * model. */
bool ism_dual_free(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                   const double lo[3], const double hi[3], int halvings, uint64_t *intervals);

/* ∇f · d > 0 at every point of lo..hi where f may vanish (sub-boxes whose enclosure excludes
 * 0 are dropped; the others split down to `halvings` halvings, as for ism_dual_free): then
 * every line along d meets f = 0 at most once in the box — between two zeros on it f would
 * have to fall through 0, at a zero where ∇f · d ≤ 0. d need not be a unit vector. */
bool ism_dual_graph_along(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                          const double lo[3], const double hi[3], const double d[3],
                          int halvings, uint64_t *intervals);

/* ism_dual_free (d NULL) or ism_dual_graph_along (d not NULL) on a node's box lo..hi whose
 * first halving is at mid (the node's lattice centre: each sub-box is exactly a child's box,
 * bit a of k the upper half along a; NULL: the box's centre), with bit k of *free_subs set
 * for every sub-box shown free of 0 on the way, whatever the verdict: such a child is empty
 * without proofs of its own (the sub-boxes are tried in order until one fails, so a bit not
 * set means unknown).
 * open_whole: the caller has m's enclosure of the whole box (ism_dual_over) and it
 * proves nothing (it holds 0, and with d its slope along d holds 0): the sub-boxes only. */
bool ism_dual_prove_halves(const ism_tape *t, ism_ivjet_ws *jet, const ism_dual_model *m,
                           const double lo[3], const double *mid, const double hi[3],
                           const double *d, int halvings, bool open_whole,
                           uint8_t *free_subs, uint64_t *intervals);

#endif
