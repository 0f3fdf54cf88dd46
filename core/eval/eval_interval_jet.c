/* eval_interval_jet.c — interval forward-mode differentiation (interval_jet.h): every register
 * carries interval enclosures of a value, its 3 first and (second order only) its 6 second
 * partial derivatives over the box. The rules are those of eval_hessian.c written with the
 * outward-rounded operations of interval_ops.h; one-argument operations go through the chain
 * rule d = g'(U) u', h = g'(U) u'' + g''(U) u' u'^T with interval g'(U), g''(U). */
#include "core/eval/interval_jet.h"
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_jet_ws.h"
#include "core/eval/interval_ops.h"
#include "core/eval/threaded.h"
#include "core/expr/tape.h"
#include "core/util/cache_line.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

ism_ivjet_ws *ism_ivjet_ws_new(const ism_tape *t)
{
    if (!t)
        return NULL;
    ism_ivjet_ws *ws = ism_line_alloc(sizeof *ws); /* lines of its own: per thread */
    if (!ws)
        return NULL;
    ws->nregs = t->nregs;
    ws->r = ism_line_alloc(t->nregs * sizeof *ws->r);
    ws->kept_cap = t->len;
    ws->kept = ism_line_alloc((t->len ? t->len : 1) * sizeof *ws->kept);
    ws->kept_t = NULL;
    ws->kept_ok = false;
    ws->last_t = NULL;
    ws->lane_regs = ws->lane_kept = NULL;
    ws->lane_cap = 0;
    ws->lane_t = NULL;
    ws->lane_ok = 0;
    ws->lane_pass_t = NULL;
    ws->lane_n = 0;
    ws->lane_kinks = NULL;
    ws->lane_kink_at = NULL;
    ws->lane_nkink_at = 0;
    ws->jet_regs = ws->jet_hregs = NULL;
    if (!ws->r || !ws->kept) {
        free(ws->r);
        free(ws->kept);
        free(ws);
        return NULL;
    }
    return ws;
}

void ism_ivjet_ws_free(ism_ivjet_ws *ws)
{
    if (!ws)
        return;
    free(ws->r);
    free(ws->kept);
    free(ws->lane_regs);
    free(ws->lane_kept);
    free(ws->lane_kinks);
    free(ws->lane_kink_at);
    free(ws->jet_regs);
    free(ws->jet_hregs);
    free(ws);
}

static ism_interval ivc(double c) { return iv(c, c); }

/* The steps of one instruction are inlined into each of run's two variants (every partial,
 * or those of a tape's free_of), so the first pays nothing for the second's tests; their
 * loops over the 3 first partials are unrolled by pragma (gcc -O2 keeps them rolled): the
 * heart's interval gradients 85.8M -> 80.9M instructions in bench_singular. */
#define ALWAYS_INLINE inline __attribute__((always_inline))

/* What one instruction computes, as bits w (interval_jet_ws.h's ISM_IVJ_*, made by
 * ism_ivjet_want): do_d(w, k) the partial in variable k, do_h(w, e) the Hessian entry e,
 * keeps_hess(w) whether Hessian entries are kept at all (without it they are left
 * untouched: unused). A first partial outside the bits is one in a variable the
 * instruction's value does not depend on (the tape's free_of): the rules below make it
 * exactly 0 (every exact 0 stays one, see is_zero), so it is written as 0 without work
 * and the results are bit for bit those of computing it. Second partials likewise, but
 * only for values no kink feeds (the tape's smooth; ism_ivjet_want). On the heart's tape
 * 8 of 14 instructions depend on fewer than three variables. */
static ALWAYS_INLINE bool do_d(unsigned w, int k) { return (w & ISM_IVJ_D(k)) != 0; }
static ALWAYS_INLINE bool do_h(unsigned w, int e) { return (w & ISM_IVJ_H(e)) != 0; }
static ALWAYS_INLINE bool keeps_hess(unsigned w) { return (w & ISM_IVJ_SECOND) != 0; }

/* Exact zeros stay exact (outward rounding would widen 0 to ±2^-1074): a derivative that is
 * exactly 0 says the register does not depend on that variable, which the kink rule uses. */
static inline bool is_zero(ism_interval u)
{
    uint64_t lo, hi; /* both bounds ±0: their bits but the signs are 0 (one test, no branch) */
    memcpy(&lo, &u.lo, sizeof lo);
    memcpy(&hi, &u.hi, sizeof hi);
    return ((lo | hi) << 1) == 0;
}

static ALWAYS_INLINE ism_interval mulz(ism_interval a, ism_interval b)
{
    return is_zero(a) || is_zero(b) ? ivc(0.0) : iv_mul(a, b);
}

static ALWAYS_INLINE ism_interval addz(ism_interval a, ism_interval b)
{
    return is_zero(a) ? b : is_zero(b) ? a : iv_add(a, b);
}

static ALWAYS_INLINE ism_interval subz(ism_interval a, ism_interval b)
{
    return is_zero(b) ? a : is_zero(a) ? iv_neg(b) : iv_sub(a, b);
}

/* Whole-line derivatives of a result of a and b that is not differentiable in the box (a
 * kink, a pole), except where both a's and b's derivatives are exactly [0, 0] over the box
 * (or not wanted): there the result does not change either. */
static void set_whole_derivs(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b, unsigned w)
{
    bool flat[3];
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        flat[k] = !do_d(w, k) || (is_zero(a->d[k]) && is_zero(b->d[k]));
        o->d[k] = flat[k] ? ivc(0.0) : ism_iv_whole();
    }
    if (keeps_hess(w)) {
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++) {
            bool zero = !do_h(w, e) || (flat[ism_ivjet_hi[e]] && flat[ism_ivjet_hj[e]]
                                        && is_zero(a->h[e]) && is_zero(b->h[e]));
            o->h[e] = zero ? ivc(0.0) : ism_iv_whole();
        }
    }
}

static ALWAYS_INLINE void set_zero_derivs(ism_ivjet *o, unsigned w)
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = ivc(0.0);
    if (keeps_hess(w)) {
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = ivc(0.0);
    }
}

/* u'_i u'_j, the square when i = j (tighter: never negative). */
static ALWAYS_INLINE ism_interval dd(const ism_ivjet *a, int e)
{
    int i = ism_ivjet_hi[e], j = ism_ivjet_hj[e];
    if (is_zero(a->d[i]) || is_zero(a->d[j]))
        return ivc(0.0);
    return i == j ? iv_square(a->d[i]) : iv_mul(a->d[i], a->d[j]);
}

/* The Hessian parts of the steps below, one function each: the second-order pass computes
 * them after the value and the first partials, and hess_only alone. */
static ALWAYS_INLINE void chain_hess(ism_ivjet *o, const ism_ivjet *a, ism_interval g1,
                                     ism_interval g2, unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        o->h[e] = do_h(w, e) ? addz(mulz(g1, a->h[e]), mulz(g2, dd(a, e))) : ivc(0.0);
}

/* The chain rule for out = g(a) given g(U), g'(U), g''(U). */
static ALWAYS_INLINE void chain(ism_ivjet *o, const ism_ivjet *a, ism_interval g, ism_interval g1,
                  ism_interval g2, unsigned w)
{
    o->v = g;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = do_d(w, k) ? mulz(g1, a->d[k]) : ivc(0.0);
    if (keeps_hess(w))
        chain_hess(o, a, g1, g2, w);
}

static ism_interval lin_copy(ism_interval u, double c) { (void)c; return u; }
static ism_interval lin_neg(ism_interval u, double c) { (void)c; return iv_neg(u); }
/* iv_mul_c's three cases, its test of c taken once for the value and every partial */
static ism_interval lin_zero(ism_interval u, double c) { (void)u; (void)c; return ivc(0.0); }
static ism_interval lin_mul_pos(ism_interval u, double c) { return iv_mul_cpos(u, c); }
static ism_interval lin_mul_neg(ism_interval u, double c) { return iv_mul_cneg(u, c); }
static ism_interval lin_div(ism_interval u, double c) { return iv_div_c(u, c); }

static ALWAYS_INLINE void each_hess(ism_ivjet *o, const ism_ivjet *a,
                                    ism_interval (*fn)(ism_interval, double), double c,
                                    unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        o->h[e] = !do_h(w, e) ? ivc(0.0) : is_zero(a->h[e]) ? a->h[e] : fn(a->h[e], c);
}

/* Applies fn(., c) to the value and every derivative of a. */
static ALWAYS_INLINE void each(ism_ivjet *o, const ism_ivjet *a,
                               ism_interval (*fn)(ism_interval, double),
                 double c, unsigned w)
{
    o->v = fn(a->v, c);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = !do_d(w, k) ? ivc(0.0) : is_zero(a->d[k]) ? a->d[k] : fn(a->d[k], c);
    if (keeps_hess(w))
        each_hess(o, a, fn, c, w);
}

/* o = a * c (MUL_RC), iv_mul_c's choice (0, c > 0, else c < 0 or NaN) taken once for every
 * part: the value and partials (affine) or, hess_only, the Hessian alone (hess_op), so both
 * passes take the same branch for the same operation. */
static ALWAYS_INLINE void mul_rc(ism_ivjet *o, const ism_ivjet *a, double c, unsigned w,
                                 bool hess_only)
{
    if (hess_only) {
        if (c == 0.0)
            each_hess(o, a, lin_zero, c, w);
        else if (c > 0.0)
            each_hess(o, a, lin_mul_pos, c, w);
        else
            each_hess(o, a, lin_mul_neg, c, w);
    } else {
        if (c == 0.0)
            each(o, a, lin_zero, c, w);
        else if (c > 0.0)
            each(o, a, lin_mul_pos, c, w);
        else
            each(o, a, lin_mul_neg, c, w);
    }
}

/* out = s * a + shift for a constant factor s: derivatives scale exactly as the value. */
static ALWAYS_INLINE void affine(ism_ivjet *o, const ism_ivjet *a, int op, double c, unsigned w)
{
    switch (op) {
    case ISM_OP_NEG: each(o, a, lin_neg, c, w); break;
    case ISM_OP_SUB_CR: each(o, a, lin_neg, c, w); o->v = iv_c_sub(c, a->v); break;
    case ISM_OP_MUL_RC: mul_rc(o, a, c, w, false); break;
    case ISM_OP_DIV_RC: each(o, a, lin_div, c, w); break;
    case ISM_OP_ADD_RC: each(o, a, lin_copy, c, w); o->v = iv_add_c(a->v, c); break;
    default: each(o, a, lin_copy, c, w); break; /* COPY */
    }
}

/* c(c-1) for the second derivative of u^c, as an interval (c(c-1) is not exact in double). */
static ism_interval falling2(double c)
{
    return iv_mul(ivc(c), iv_add_c(ivc(c), -1.0));
}

/* max(u, 0)^c, c not an integer: smooth for u > 0, constant for u < 0, and at 0 the first
 * derivative is continuous only for c > 1, the second only for c > 2. */
static void op_powc(ism_ivjet *o, const ism_ivjet *a, double c, unsigned w)
{
    ism_interval u = a->v;
    ism_interval g = iv_powc(u, c);
    if (u.hi <= 0.0) {
        o->v = g;
        set_zero_derivs(o, w);
        return;
    }
    ism_interval whole = ism_iv_whole();
    ism_interval g1 = c > 1.0 || u.lo > 0.0 ? iv_mul_c(iv_powc(u, c - 1.0), c) : whole;
    ism_interval g2 = !keeps_hess(w)          ? ivc(0.0)
                      : c > 2.0 || u.lo > 0.0 ? iv_mul(falling2(c), iv_powc(u, c - 2.0))
                                              : whole;
    chain(o, a, g, g1, g2, w);
}

/* sqrt(max(u, 0)) and log(max(u, 0)): constant below 0, unbounded derivatives at 0+. */
static void op_sqrt_log(ism_ivjet *o, const ism_ivjet *a, int is_log, unsigned w)
{
    ism_interval u = a->v;
    ism_interval g = is_log ? iv_log(u) : iv_sqrt(u);
    if (u.hi <= 0.0) {
        o->v = g;
        set_zero_derivs(o, w);
        return;
    }
    if (!(u.lo > 0.0)) {
        o->v = g;
        set_whole_derivs(o, a, a, w);
        return;
    }
    ism_interval g1, g2 = ivc(0.0);
    if (is_log) {
        g1 = iv_c_div(1.0, u);
        if (keeps_hess(w))
            g2 = iv_neg(iv_square(g1));
    } else {
        g1 = iv_c_div(0.5, g);                       /* 1 / (2 sqrt u) */
        if (keeps_hess(w))
            g2 = iv_mul_c(iv_div(g1, u), -0.5);      /* -1 / (4 u sqrt u) */
    }
    chain(o, a, g, g1, g2, w);
}

/* g''(U) of a one-argument operation given U, g(U) and g'(U) (the second-order pass only). */
static ism_interval second_factor(const ism_instr *in, ism_interval u, ism_interval g,
                                  ism_interval g1)
{
    switch (in->op) {
    case ISM_OP_SQUARE: return ivc(2.0);
    case ISM_OP_POWI: {
        unsigned n = in->b;
        return iv_mul_c(iv_powi(u, n - 2), (double)n * (double)(n - 1));
    }
    case ISM_OP_DIV_CR: return iv_c_div(2.0 * in->imm, iv_powi(u, 3)); /* 2c / u^3 */
    case ISM_OP_SIN: case ISM_OP_COS: return iv_neg(g);
    case ISM_OP_TAN: return iv_mul_c(iv_mul(g, g1), 2.0); /* 2 tan (1 + tan^2) */
    default: return g; /* EXP */
    }
}

/* iv_sin and iv_cos of u, bit for bit, from one sincos per bound (glibc's sincos gives sin's
 * and cos's bits, as trig_pair.h's memo of libm pairs relies on): a sine's jet takes both.
 * Gyroid ball at E = 1.09e-3: 74,544 sin and 74,544 cos calls, 12.1M instructions. */
static void iv_sin_cos(ism_interval u, ism_interval *s, ism_interval *c)
{
    if (!iv_trig_resolves(u)) {
        *s = *c = iv(-1.0, 1.0);
        return;
    }
    double s1, c1, s2, c2;
    sincos(u.lo, &s1, &c1);
    sincos(u.hi, &s2, &c2);
    *s = iv_sin_at(u, s1, s2);
    *c = iv_cos_at(u, c1, c2);
}

/* One-argument operations other than the affine ones and the branches. The gradient-only
 * pass (second = 0) computes no g'': heart's search spent 26M of 88.7M instructions in
 * interval gradients, the power rule's u^(n−2) among them. */
static ALWAYS_INLINE void op_unary(ism_ivjet *o, const ism_instr *in, int op, const ism_ivjet *a,
                                   unsigned w)
{
    ism_interval u = a->v, g, g1;
    double c = in->imm;
    switch (op) {
    case ISM_OP_SQUARE:
        g = iv_square(u);
        g1 = iv_mul_c(u, 2.0);
        break;
    case ISM_OP_POWI: {
        unsigned n = in->b;
        g = iv_powi(u, n);
        g1 = iv_mul_c(iv_powi(u, n - 1), (double)n);
        break;
    }
    case ISM_OP_DIV_CR: /* c / u: -c / u^2 (whole when U holds the pole) */
        g = iv_c_div(c, u);
        g1 = iv_c_div(-c, iv_square(u));
        break;
    case ISM_OP_SIN: case ISM_OP_COS: {
        ism_interval s, co;
        iv_sin_cos(u, &s, &co);
        g = op == ISM_OP_SIN ? s : co;
        g1 = op == ISM_OP_SIN ? co : iv_neg(s);
        break;
    }
    case ISM_OP_TAN: /* 1 + tan^2; whole across a pole */
        g = iv_tan(u);
        g1 = iv_add_c(iv_square(g), 1.0);
        break;
    case ISM_OP_EXP:
        g = iv_exp(u);
        g1 = g;
        break;
    case ISM_OP_POWC: op_powc(o, a, c, w); return;
    case ISM_OP_SQRT: op_sqrt_log(o, a, 0, w); return;
    case ISM_OP_LOG: op_sqrt_log(o, a, 1, w); return;
    default:
        o->v = ism_iv_whole();
        set_whole_derivs(o, a, a, w);
        return;
    }
    chain(o, a, g, g1, keeps_hess(w) ? second_factor(in, u, g, g1) : ivc(0.0), w);
}

static ALWAYS_INLINE void add_hess(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b,
                                   int sub, unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        o->h[e] = !do_h(w, e) ? ivc(0.0)
                  : sub       ? subz(a->h[e], b->h[e])
                              : addz(a->h[e], b->h[e]);
}

static ALWAYS_INLINE void op_add(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b, int sub,
                                 unsigned w)
{
    ism_interval (*fn)(ism_interval, ism_interval) = sub ? subz : addz;
    o->v = sub ? iv_sub(a->v, b->v) : iv_add(a->v, b->v);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = do_d(w, k) ? fn(a->d[k], b->d[k]) : ivc(0.0);
    if (keeps_hess(w))
        add_hess(o, a, b, sub, w);
}

static ALWAYS_INLINE void mul_hess(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b,
                                   unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++) {
        if (!do_h(w, e)) {
            o->h[e] = ivc(0.0);
            continue;
        }
        int i = ism_ivjet_hi[e], j = ism_ivjet_hj[e];
        ism_interval cross = addz(mulz(a->d[i], b->d[j]), mulz(a->d[j], b->d[i]));
        o->h[e] = addz(addz(mulz(a->h[e], b->v), mulz(a->v, b->h[e])), cross);
    }
}

/* (ab)' = a'b + ab', (ab)'' = a''b + ab'' + a'b'^T + b'a'^T. */
static ALWAYS_INLINE void op_mul(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b, unsigned w)
{
    o->v = iv_mul(a->v, b->v);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = do_d(w, k) ? addz(mulz(a->d[k], b->v), mulz(a->v, b->d[k])) : ivc(0.0);
    if (keeps_hess(w))
        mul_hess(o, a, b, w);
}

/* q = a / b: q' = (a' - q b') / b, q'' = (a'' - q' b'^T - b' q'^T - q b'') / b. */
static void op_div(ism_ivjet *o, const ism_ivjet *a, const ism_ivjet *b, unsigned w)
{
    ism_interval q = iv_div(a->v, b->v);
    o->v = q;
    if (!(b->v.lo > 0.0 || b->v.hi < 0.0)) {
        set_whole_derivs(o, a, b, w);
        return;
    }
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        if (!do_d(w, k)) {
            o->d[k] = ivc(0.0);
            continue;
        }
        ism_interval num = subz(a->d[k], mulz(q, b->d[k]));
        o->d[k] = is_zero(num) ? num : iv_div(num, b->v);
    }
    if (keeps_hess(w)) {
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++) {
            if (!do_h(w, e)) {
                o->h[e] = ivc(0.0);
                continue;
            }
            int i = ism_ivjet_hi[e], j = ism_ivjet_hj[e];
            ism_interval cross = addz(mulz(o->d[i], b->d[j]), mulz(b->d[i], o->d[j]));
            ism_interval num = subz(subz(a->h[e], cross), mulz(q, b->h[e]));
            o->h[e] = is_zero(num) ? num : iv_div(num, b->v);
        }
    }
}

/* Copies the derivatives of src into o (the value of o is set by the caller). */
static ALWAYS_INLINE void take_derivs(ism_ivjet *o, const ism_ivjet *src, unsigned w)
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = do_d(w, k) ? src->d[k] : ivc(0.0);
    if (keeps_hess(w)) {
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = do_h(w, e) ? src->h[e] : ivc(0.0);
    }
}

/* Which branch of a min/max/abs the box decides: A, B, or FREE when both may be active.
 * Strict comparisons: where the operands tie the point evaluators may take either side. */
static int decided_branch(const ism_instr *in, ism_interval a, ism_interval b)
{
    switch (in->op) {
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC:
        return a.hi < b.lo ? ISM_BRANCH_A : b.hi < a.lo ? ISM_BRANCH_B : ISM_BRANCH_FREE;
    case ISM_OP_MAX_RR: case ISM_OP_MAX_RC:
        return a.lo > b.hi ? ISM_BRANCH_A : b.lo > a.hi ? ISM_BRANCH_B : ISM_BRANCH_FREE;
    default: /* ABS */
        return a.lo > 0.0 ? ISM_BRANCH_A : a.hi < 0.0 ? ISM_BRANCH_B : ISM_BRANCH_FREE;
    }
}

/* min, max, abs: the value is always the natural enclosure; the derivatives are those of
 * the decided (or forced) branch, the whole line at a free kink. Returns 1 at a free kink. */
/* The second operand of a min/max/abs: its register (RR), or cst filled as the constant
 * (RC: the immediate, partials 0), or cst all 0 (abs, which reads none). */
static const ism_ivjet *branch_b(const ism_instr *in, const ism_ivjet *r, ism_ivjet *cst)
{
    if (in->op == ISM_OP_MIN_RR || in->op == ISM_OP_MAX_RR)
        return &r[in->b];
    *cst = (ism_ivjet){ 0 };
    if (in->op != ISM_OP_ABS)
        cst->v = ivc(in->imm);
    return cst;
}

static int op_branch(ism_ivjet *o, const ism_instr *in, const ism_ivjet *r, uint8_t force,
                     unsigned w)
{
    const ism_ivjet *a = &r[in->a];
    ism_ivjet cst;
    const ism_ivjet *b = branch_b(in, r, &cst);
    switch (in->op) {
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC: o->v = iv_min(a->v, b->v); break;
    case ISM_OP_MAX_RR: case ISM_OP_MAX_RC: o->v = iv_max(a->v, b->v); break;
    default: o->v = iv_abs(a->v); break;
    }
    int side = decided_branch(in, a->v, b->v);
    if (side == ISM_BRANCH_FREE)
        side = force;
    if (side == ISM_BRANCH_FREE) {
        set_whole_derivs(o, a, b, w);
        return 1;
    }
    if (in->op != ISM_OP_ABS) {
        take_derivs(o, side == ISM_BRANCH_A ? a : b, w);
        return 0;
    }
    ism_interval v = o->v;
    affine(o, a, side == ISM_BRANCH_A ? ISM_OP_COPY : ISM_OP_NEG, 0.0, w);
    o->v = v;
    return 0;
}

/* Every operation's step, as an expression giving 1 at a free kink (else 0) in o (its
 * register), a (its first operand's jet), in, r (the registers), JET_W (the partials
 * wanted) and JET_F (its forced branch, read by min, max and abs alone; both macros, prefixed
 * so that no identifier in between is rewritten): one list, expanded by jet_op's switch
 * (the second-order pass) and by run_grad's labels (the gradient pass). Each step names its
 * operation as a constant, so the affine and one-argument steps' own switches fold away. */
#define JET_OPS(X)                                                                          \
    X(ISM_OP_CONST, (o->v = ivc(in->imm), set_zero_derivs(o, JET_W), 0))                    \
    X(ISM_OP_COPY, (affine(o, a, ISM_OP_COPY, in->imm, JET_W), 0))                          \
    X(ISM_OP_ADD_RR, (op_add(o, a, &r[in->b], 0, JET_W), 0))                                \
    X(ISM_OP_ADD_RC, (affine(o, a, ISM_OP_ADD_RC, in->imm, JET_W), 0))                      \
    X(ISM_OP_SUB_RR, (op_add(o, a, &r[in->b], 1, JET_W), 0))                                \
    X(ISM_OP_SUB_CR, (affine(o, a, ISM_OP_SUB_CR, in->imm, JET_W), 0))                      \
    X(ISM_OP_MUL_RR, (op_mul(o, a, &r[in->b], JET_W), 0))                                   \
    X(ISM_OP_MUL_RC, (affine(o, a, ISM_OP_MUL_RC, in->imm, JET_W), 0))                      \
    X(ISM_OP_DIV_RR, (op_div(o, a, &r[in->b], JET_W), 0))                                   \
    X(ISM_OP_DIV_RC, (affine(o, a, ISM_OP_DIV_RC, in->imm, JET_W), 0))                      \
    X(ISM_OP_DIV_CR, (op_unary(o, in, ISM_OP_DIV_CR, a, JET_W), 0))                         \
    X(ISM_OP_MIN_RR, op_branch(o, in, r, JET_F, JET_W))                                     \
    X(ISM_OP_MIN_RC, op_branch(o, in, r, JET_F, JET_W))                                     \
    X(ISM_OP_MAX_RR, op_branch(o, in, r, JET_F, JET_W))                                     \
    X(ISM_OP_MAX_RC, op_branch(o, in, r, JET_F, JET_W))                                     \
    X(ISM_OP_NEG, (affine(o, a, ISM_OP_NEG, in->imm, JET_W), 0))                            \
    X(ISM_OP_SQUARE, (op_unary(o, in, ISM_OP_SQUARE, a, JET_W), 0))                         \
    X(ISM_OP_POWI, (op_unary(o, in, ISM_OP_POWI, a, JET_W), 0))                             \
    X(ISM_OP_POWC, (op_unary(o, in, ISM_OP_POWC, a, JET_W), 0))                             \
    X(ISM_OP_SQRT, (op_unary(o, in, ISM_OP_SQRT, a, JET_W), 0))                             \
    X(ISM_OP_SIN, (op_unary(o, in, ISM_OP_SIN, a, JET_W), 0))                               \
    X(ISM_OP_COS, (op_unary(o, in, ISM_OP_COS, a, JET_W), 0))                               \
    X(ISM_OP_TAN, (op_unary(o, in, ISM_OP_TAN, a, JET_W), 0))                               \
    X(ISM_OP_EXP, (op_unary(o, in, ISM_OP_EXP, a, JET_W), 0))                               \
    X(ISM_OP_LOG, (op_unary(o, in, ISM_OP_LOG, a, JET_W), 0))                               \
    X(ISM_OP_ABS, op_branch(o, in, r, JET_F, JET_W))
ISM_THREADED_COMPLETE(JET_OPS, "JET_OPS names every operation (the label table)");

/* An operation code past the list: the whole line, its derivatives too. */
#define JET_BAD (o->v = ism_iv_whole(), set_whole_derivs(o, a, a, JET_W), 0)

/* One instruction; returns 1 when it is a free kink. */
static ALWAYS_INLINE int jet_op(const ism_instr *in, ism_ivjet *r, uint8_t force, unsigned w)
{
    ism_ivjet *o = &r[in->out];
    const ism_ivjet *a = &r[in->a];
#define JET_W w
#define JET_F force
#define CASE(OP, E) case OP: return E;
    switch (in->op) {
        JET_OPS(CASE)
    default:
        return JET_BAD;
    }
#undef CASE
#undef JET_F
#undef JET_W
}

#if defined(__SSE2__)
#define NAN_LANES(u) _mm_cmpunord_pd(_mm_loadu_pd(&(u).lo), _mm_loadu_pd(&(u).lo))
/* The NaN lanes of o's Hessian bounds, or'ed: one unordered compare per interval. */
static ALWAYS_INLINE __m128d h_nan_lanes(const ism_ivjet *o)
{
    __m128d bad = NAN_LANES(o->h[0]);
    _Pragma("GCC unroll 5") for (int e = 1; e < 6; e++)
        bad = _mm_or_pd(bad, NAN_LANES(o->h[e]));
    return bad;
}
#endif

/* Whether some bound of o's value, first partials and (second) Hessian is NaN: one
 * unordered compare per interval in SSE2 lanes, the masks or'ed and read once. */
static ALWAYS_INLINE bool any_nan(const ism_ivjet *o, bool second)
{
#if defined(__SSE2__)
    __m128d bad = NAN_LANES(o->v);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        bad = _mm_or_pd(bad, NAN_LANES(o->d[k]));
    if (second)
        bad = _mm_or_pd(bad, h_nan_lanes(o));
    return _mm_movemask_pd(bad) != 0;
#else
    (void)o;
    (void)second;
    return true;
#endif
}

/* Whether some Hessian bound of o is NaN (any_nan's test on the h part alone). */
static ALWAYS_INLINE bool any_nan_h(const ism_ivjet *o)
{
#if defined(__SSE2__)
    return _mm_movemask_pd(h_nan_lanes(o)) != 0;
#else
    (void)o;
    return true;
#endif
}
#undef NAN_LANES

/* The Hessian entries of o in w made NaN-free (sanitize's h part; hess_only's too). */
static ALWAYS_INLINE void sanitize_h(ism_ivjet *o, unsigned w)
{
    _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
        if (do_h(w, e))
            o->h[e] = ism_iv_sane(o->h[e]);
}

/* The partials outside w are 0 already. Nothing to do when no bound is NaN (nearly always:
 * a NaN needs an infinite operand or an overflow), which one test over the whole jet tells:
 * checking each bound cost the torus's jets ~20% of their instructions. */
static ALWAYS_INLINE void sanitize(ism_ivjet *o, unsigned w)
{
    if (!any_nan(o, keeps_hess(w)))
        return;
    o->v = ism_iv_sane(o->v);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        if (do_d(w, k))
            o->d[k] = ism_iv_sane(o->d[k]);
    if (keeps_hess(w))
        sanitize_h(o, w);
}

/* Operations whose Hessian hess_only computes from the operands' kept values and first
 * partials alone: the affine ones, +, −, ×, squares and integer powers (no branch, no pole,
 * no libm function whose value the chain rule would need again). */
bool ism_ivjet_hess_from_kept(int op)
{
    switch (op) {
    case ISM_OP_CONST: case ISM_OP_COPY: case ISM_OP_ADD_RC: case ISM_OP_SUB_CR:
    case ISM_OP_MUL_RC: case ISM_OP_DIV_RC: case ISM_OP_NEG: case ISM_OP_ADD_RR:
    case ISM_OP_SUB_RR: case ISM_OP_MUL_RR: case ISM_OP_SQUARE: case ISM_OP_POWI:
        return true;
    default:
        return false;
    }
}

/* The input registers over box (a bound not a number, or lo > hi: the whole line). */
static ALWAYS_INLINE void load_box(ism_ivjet *r, const ism_interval box[3], unsigned all)
{
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++) {
        r[k].v = box[k].lo <= box[k].hi ? box[k] : ism_iv_whole();
        set_zero_derivs(&r[k], all);
        r[k].d[k] = ivc(1.0);
    }
}

/* A tape longer than the workspace's registers: f and every partial the whole line. */
static size_t run_unfit(ism_ivjet *out, unsigned all)
{
    ism_ivjet any = { .d = { { -1.0, 1.0 } } }; /* depends on x: whole everywhere */
    out->v = ism_iv_whole();
    set_whole_derivs(out, &any, &any, all);
    return (size_t)-1;
}

static bool fits(const ism_tape *t, const ism_ivjet_ws *ws)
{
    return ws && t && ws->nregs >= t->nregs;
}

/* The second-order pass: jet_op's switch over the tape (compiled twice, as run_grad). */
ISM_AVX2_TWICE(size_t, run_jet,
               (const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                const uint8_t *force, uint8_t *kinks, ism_ivjet *out),
               (t, ws, box, force, kinks, out),
    const unsigned all = ism_ivjet_want(7u, 1, false);
    if (!fits(t, ws))
        return run_unfit(out, all);
    ism_ivjet *r = ws->r;
    load_box(r, box, all);
    size_t nkinks = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        uint8_t f = force ? force[i] : ISM_BRANCH_FREE;
        int kink;
        if (in->free_of == 0) {
            kink = jet_op(in, r, f, all);
            sanitize(&r[in->out], all);
        } else {
            unsigned w = ism_ivjet_want(ISM_FREE_ALL & ~(unsigned)in->free_of, 1, in->smooth);
            kink = jet_op(in, r, f, w);
            sanitize(&r[in->out], w);
        }
        nkinks += (size_t)kink;
        if (kinks)
            kinks[i] = (uint8_t)kink;
    }
    *out = r[t->result];
    ws->last_t = NULL; /* not a gradient pass: ism_ivjet_top_pieces reads nothing */
    return nkinks;)

/* The gradient pass (value and first partials) by direct threading (threaded.h; the pattern
 * of eval_interval.c's ism_interval_run): each operation's code, from JET_OPS, ends in its
 * own end test and its own jump to the next instruction's, where jet_op's switch in a loop
 * paid a bound test, a table offset, the loop's test and each step's own switch on every
 * instruction. Each step is expanded twice: for an instruction that depends on all three
 * variables (the partials wanted a constant, their tests folded) and for the others (the
 * tape's free_of). kinks (when asked) is cleared first and set at the free kinks, which only
 * min, max and abs make. KEEP: NULL, or ism_eval_interval_grad_kept's record of every
 * instruction's value and first partials as written to its register (the expanding
 * function's t, ws, box, force, kinks, out and keep are its arguments). A macro, not a
 * function: each expansion needs its own labels (GCC inlines no function that takes a
 * label's address). */
#define RUN_GRAD_BODY                                                                       \
    do {                                                                                    \
        if (!fits(t, ws))                                                                   \
            return run_unfit(out, 7u);                                                      \
        ISM_THREADED_TABLE(next_op, JET_OPS);                                               \
        ism_ivjet *r = (ws)->r;                                                             \
        load_box(r, box, 7u);                                                               \
        size_t nkinks = 0;                                                                  \
        const ism_instr *in = (t)->code, *const end = (t)->code + (t)->len;                 \
        clear_kinks(kinks, (t)->len);                                                       \
        if (in == end)                                                                      \
            goto done;                                                                      \
        goto *next_op[in->op];                                                              \
        JET_OPS(GRAD_STEP)                                                                  \
        GRAD_STEP(BAD, JET_BAD)                                                             \
    done:                                                                                   \
        *(out) = r[(t)->result];                                                            \
        (ws)->last_t = force ? NULL : (t); /* the registers ism_ivjet_top_pieces reads */   \
        memcpy((ws)->last_box, box, sizeof(ws)->last_box);                                  \
        return nkinks;                                                                      \
    } while (0)

/* One operation's labelled code in RUN_GRAD_BODY. */
#define JET_F (force ? force[in - t->code] : ISM_BRANCH_FREE)
#define JET_W w /* GRAD_STEP's local want bits */
#define GRAD_STEP(OP, E)                                                                    \
    L_##OP : {                                                                              \
        ism_ivjet *o = &r[in->out];                                                         \
        const ism_ivjet *a = &r[in->a];                                                     \
        (void)a; /* not every step reads it */                                              \
        int kink;                                                                           \
        if (in->free_of == 0) {                                                             \
            const unsigned w = 7u;                                                          \
            kink = E;                                                                       \
            sanitize(o, w);                                                                 \
        } else {                                                                            \
            const unsigned w = ISM_FREE_ALL & ~(unsigned)in->free_of;                       \
            kink = E;                                                                       \
            sanitize(o, w);                                                                 \
        }                                                                                   \
        if (kink) {                                                                         \
            nkinks++;                                                                       \
            if (kinks)                                                                      \
                kinks[in - t->code] = 1;                                                    \
        }                                                                                   \
        if (keep)                                                                           \
            keep_vd(&keep[in - t->code], o);                                                \
    }                                                                                       \
    ISM_THREADED_NEXT(next_op, in, end, goto done)

static ALWAYS_INLINE void clear_kinks(uint8_t *kinks, size_t n)
{
    if (kinks)
        memset(kinks, 0, n);
}

/* A kept record's entry: o's value and first partials. */
static ALWAYS_INLINE void keep_vd(ism_kept_vd *k, const ism_ivjet *o)
{
    (*k)[0] = o->v;
    _Pragma("GCC unroll 3") for (int i = 0; i < 3; i++)
        (*k)[i + 1] = o->d[i];
}

/* Both compiled twice (avx2_clone.h's ISM_AVX2_TWICE: the same operations, VEX forms in the
 * AVX2 copy; figures in notes/iv28.md). */
ISM_AVX2_TWICE(size_t, run_grad,
               (const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                const uint8_t *force, uint8_t *kinks, ism_ivjet *out),
               (t, ws, box, force, kinks, out),
    ism_kept_vd *const keep = NULL;
    RUN_GRAD_BODY;)

ISM_AVX2_TWICE(size_t, run_grad_kept,
               (const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3], ism_ivjet *out,
                ism_kept_vd *keep),
               (t, ws, box, out, keep),
    const uint8_t *const force = NULL;
    uint8_t *const kinks = NULL;
    RUN_GRAD_BODY;)

/* The gradient pass's values alone (RUN_GRAD_BODY with no partial wanted: each operation's
 * value is computed as there, whatever the want bits, and sanitize's clean-up of it too, so
 * every register's value, and so every min, max and abs's test of its operands, is the
 * gradient pass's bit for bit), ending true at the first free kink. Barth's sextic at
 * E = 0.0259: its node tapes that still hold the max meet it free in 6,752 of 6,752 of
 * zero_free's mean-value forms (the max is the tape's last instruction). */
#define VALUE_STEP(OP, E)                                                                   \
    L_##OP : {                                                                              \
        ism_ivjet *o = &r[in->out];                                                         \
        const ism_ivjet *a = &r[in->a];                                                     \
        (void)a; /* not every step reads it */                                              \
        const unsigned w = 0u;                                                              \
        if (E)                                                                              \
            return true;                                                                    \
        sanitize(o, w);                                                                     \
    }                                                                                       \
    ISM_THREADED_NEXT(next_op, in, end, goto done)

ISM_AVX2_TWICE(bool, run_values,
               (const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3]),
               (t, ws, box),
    const uint8_t *const force = NULL;
    ISM_THREADED_TABLE(next_op, JET_OPS);
    ism_ivjet *r = ws->r;
    ws->last_t = NULL; /* the registers hold no gradient pass */
    load_box(r, box, 7u);
    const ism_instr *in = t->code, *const end = t->code + t->len;
    if (in == end)
        goto done;
    goto *next_op[in->op];
    JET_OPS(VALUE_STEP)
    VALUE_STEP(BAD, JET_BAD)
done:
    return false;)
#undef VALUE_STEP
#undef GRAD_STEP
#undef JET_F
#undef JET_W
#undef RUN_GRAD_BODY

/* The Hessian part of one instruction (hess_from_kept(in->op)), the second-order pass's
 * want bits w: the h lines of jet_op's steps for it, reading the operands' registers as
 * they stand (values and first partials replayed from the kept record). */
static ALWAYS_INLINE void hess_op(const ism_instr *in, ism_ivjet *r, unsigned w)
{
    ism_ivjet *o = &r[in->out];
    const ism_ivjet *a = &r[in->a];
    switch (in->op) {
    case ISM_OP_CONST:
        _Pragma("GCC unroll 6") for (int e = 0; e < 6; e++)
            o->h[e] = ivc(0.0);
        return;
    case ISM_OP_COPY: case ISM_OP_ADD_RC: each_hess(o, a, lin_copy, in->imm, w); return;
    case ISM_OP_SUB_CR: case ISM_OP_NEG: each_hess(o, a, lin_neg, in->imm, w); return;
    case ISM_OP_MUL_RC: mul_rc(o, a, in->imm, w, true); return;
    case ISM_OP_DIV_RC: each_hess(o, a, lin_div, in->imm, w); return;
    case ISM_OP_ADD_RR: add_hess(o, a, &r[in->b], 0, w); return;
    case ISM_OP_SUB_RR: add_hess(o, a, &r[in->b], 1, w); return;
    case ISM_OP_MUL_RR: mul_hess(o, a, &r[in->b], w); return;
    default: { /* SQUARE, POWI: g' and g'' as op_unary takes them */
        ism_interval u = a->v, g1;
        if (in->op == ISM_OP_SQUARE)
            g1 = iv_mul_c(u, 2.0);
        else
            g1 = iv_mul_c(iv_powi(u, in->b - 1), (double)in->b);
        chain_hess(o, a, g1, second_factor(in, u, o->v, g1), w); /* o->v unused for these */
        return;
    }
    }
}

/* A kept record: instruction i's component c (0 value, 1-3 the first partials) has its
 * lower bound at at[i * step_i + c * step_c] and its upper one step_b further (the scalar
 * pass's ism_kept_vd, or one lane of the batched pass's: interval_jet_ws.h). */
typedef struct kept_rec {
    const double *at;
    size_t step_i, step_c, step_b;
} kept_rec;

static ALWAYS_INLINE ism_interval kept_of(const kept_rec *k, size_t i, int c)
{
    const double *p = k->at + i * k->step_i + (size_t)c * k->step_c;
    return iv(p[0], p[k->step_b]);
}

/* The second-order pass over the kept record of the gradient pass over the same box: each
 * instruction's value and first partials copied from it (the second-order pass computes
 * them with the same operations on the same operands, and cleans them the same way: a
 * NaN-free bound is kept as it is), its Hessian computed as run's would be. */
ISM_AVX2_TWICE(size_t, hess_only,
               (const ism_tape *t, ism_ivjet_ws *ws, const kept_rec *kept,
                const ism_interval box[3], uint8_t *kinks, ism_ivjet *out),
               (t, ws, kept, box, kinks, out),
    const unsigned all = ism_ivjet_want(7u, 1, false);
    ism_ivjet *r = ws->r;
    ws->last_t = NULL;
    load_box(r, box, all);
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        ism_ivjet *o = &r[in->out];
        unsigned w = in->free_of == 0
                         ? all
                         : ism_ivjet_want(ISM_FREE_ALL & ~(unsigned)in->free_of, 1, in->smooth);
        o->v = kept_of(kept, i, 0);
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = kept_of(kept, i, k + 1);
        hess_op(in, r, w);
        if (any_nan_h(o))
            sanitize_h(o, w);
        if (kinks)
            kinks[i] = 0;
    }
    *out = r[t->result];
    return 0;)

static bool same_box(const ism_interval a[3], const ism_interval b[3])
{
    return memcmp(a, b, 3 * sizeof *a) == 0;
}

size_t ism_eval_interval_grad(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                              const uint8_t *force, uint8_t *kinks, ism_ivgrad *out)
{
    ism_ivjet j;
    size_t n = run_grad(t, ws, box, force, kinks, &j);
    out->v = j.v;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        out->d[k] = j.d[k];
    return n;
}

bool ism_eval_interval_meets_kink(const ism_tape *t, ism_ivjet_ws *ws,
                                  const ism_interval box[3])
{
    if (!fits(t, ws))
        return true; /* the gradient pass returns (size_t)-1 */
    return run_values(t, ws, box);
}

size_t ism_eval_interval_grad_kept(const ism_tape *t, ism_ivjet_ws *ws,
                                   const ism_interval box[3], ism_ivgrad *out)
{
    bool keep = ws && t && ws->nregs >= t->nregs && t->len <= ws->kept_cap;
    if (!keep)
        return ism_eval_interval_grad(t, ws, box, NULL, NULL, out);
    ws->kept_ok = false;
    ism_ivjet j;
    size_t n = run_grad_kept(t, ws, box, &j, ws->kept);
    out->v = j.v;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        out->d[k] = j.d[k];
    ws->kept_t = t;
    memcpy(ws->kept_box, box, sizeof ws->kept_box);
    ws->kept_ok = n == 0; /* the tape's operations are asked when a jet would use the record */
    return n;
}

/* Every instruction of t is one hess_only computes (a fact of the tape, not of the box:
 * scanned only where a kept record would be used, not tested in run's loop). */
bool ism_ivjet_tape_hess_from_kept(const ism_tape *t)
{
    for (size_t i = 0; i < t->len; i++)
        if (!ism_ivjet_hess_from_kept(t->code[i].op))
            return false;
    return true;
}

/* The lane of the batched pass (eval_interval_grad_batch.c) whose unused record is of t
 * over box, or -1. */
static int kept_lane(const ism_ivjet_ws *ws, const ism_tape *t, const ism_interval box[3])
{
    if (ws->lane_t != t)
        return -1;
    for (uint32_t m = ws->lane_ok; m; m &= m - 1) {
        int k = __builtin_ctz(m);
        if (same_box(box, ws->lane_box[k]))
            return k;
    }
    return -1;
}

size_t ism_eval_interval_jet(const ism_tape *t, ism_ivjet_ws *ws, const ism_interval box[3],
                             const uint8_t *force, uint8_t *kinks, ism_ivjet *out)
{
    if (ws && ws->kept_ok && ws->kept_t == t && !force && same_box(box, ws->kept_box)) {
        ws->kept_ok = false; /* once: the record is of one gradient pass */
        if (ism_ivjet_tape_hess_from_kept(t)) {
            kept_rec k = {(const double *)ws->kept, 8, 2, 1};
            return hess_only(t, ws, &k, box, kinks, out);
        }
    }
    int lane = ws && !force ? kept_lane(ws, t, box) : -1;
    if (lane >= 0) { /* the batch took only tapes hess_only computes */
        ws->lane_ok &= ~(1u << lane);
        size_t g = (size_t)lane / ISM_IVG_VL, j = (size_t)lane % ISM_IVG_VL;
        kept_rec k = {ws->lane_kept + g * 8 * ISM_IVG_VL + j, ISM_IVG_REG, 2 * ISM_IVG_VL,
                      ISM_IVG_VL};
        return hess_only(t, ws, &k, box, kinks, out);
    }
    return run_jet(t, ws, box, force, kinks, out);
}

/* The lane of the last batched pass of t on ws whose box is box, or -1. */
static int pass_lane(const ism_ivjet_ws *ws, const ism_tape *t, const ism_interval box[3])
{
    if (!ws || !t || ws->lane_pass_t != t)
        return -1;
    for (uint32_t k = 0; k < ws->lane_n; k++)
        if (same_box(box, ws->lane_box[k]))
            return (int)k;
    return -1;
}

size_t ism_ivjet_lane_kinks(const ism_tape *t, const ism_ivjet_ws *ws,
                            const ism_interval box[3], uint8_t *kinks)
{
    int k = pass_lane(ws, t, box);
    if (k < 0)
        return (size_t)-1;
    memset(kinks, 0, t->len);
    for (size_t j = 0; j < ws->lane_nkink_at; j++) {
        uint32_t i = ws->lane_kink_at[j];
        kinks[i] = (uint8_t)(ws->lane_kinks[i] >> k & 1u);
    }
    return ws->lane_nkink_at ? ws->lane_nk[k] : 0; /* none listed: lane_nk not written */
}

/* Register reg of lane k of the last batched pass (eval_interval_grad_batch.c's layout: a
 * group's registers in a row, each the value's and the three partials' lower and upper
 * bounds as ISM_IVG_VL lanes apiece) as a value and first partials. */
static ism_ivjet lane_reg(const ism_ivjet_ws *ws, int k, uint32_t reg)
{
    size_t g = (size_t)k / ISM_IVG_VL, j = (size_t)k % ISM_IVG_VL;
    const double *p = ws->lane_regs + (g * ws->nregs + reg) * (8 * ISM_IVG_VL) + j;
    ism_ivjet r = { .v = iv(p[0], p[ISM_IVG_VL]) };
    _Pragma("GCC unroll 3") for (int c = 0; c < 3; c++)
        r.d[c] = iv(p[(2 + 2 * c) * ISM_IVG_VL], p[(3 + 2 * c) * ISM_IVG_VL]);
    return r;
}

/* The forced pass differs from the unforced one only at the forced instruction (the ones
 * before it read their force byte only at a kink, and it is free only there), and there
 * op_branch keeps the natural enclosure as the value and copies the branch's partials
 * (take_derivs; sanitize then changes nothing): what the unforced pass left in the operands'
 * registers, when t ends there and nothing overwrote them (or a batched pass's lane of them:
 * bit for bit the same, eval_interval_grad_batch.c). No bound read can be NaN: the pass, scalar
 * or batched (whose lanes turn NaN bounds into infinities as sanitize does), sanitized every
 * register it wrote, and kept the partials outside an instruction's want at 0, so no test
 * for one here. */
bool ism_ivjet_top_pieces(const ism_tape *t, const ism_ivjet_ws *ws, const ism_interval box[3],
                          ism_ivgrad piece[2])
{
    if (!ws || !t || t->len == 0 || ws->nregs < t->nregs)
        return false;
    /* the registers: the unforced gradient pass of t over this box, or a batched pass's lane */
    bool scalar = ws->last_t == t && same_box(box, ws->last_box);
    int lane = scalar ? -1 : pass_lane(ws, t, box);
    if (!scalar && lane < 0)
        return false;
    const ism_instr *in = &t->code[t->len - 1];
    bool rr = in->op == ISM_OP_MIN_RR || in->op == ISM_OP_MAX_RR;
    if (!rr && in->op != ISM_OP_MIN_RC && in->op != ISM_OP_MAX_RC)
        return false;
    /* every partial taken (all of x, y, z asked), the result its own register */
    if (in->free_of != 0 || in->out != t->result || in->out == in->a ||
        (rr && in->out == in->b))
        return false;
    ism_ivjet cst, la, lb, lo;
    const ism_ivjet *src[2], *out;
    if (scalar) {
        src[0] = &ws->r[in->a];
        src[1] = branch_b(in, ws->r, &cst);
        out = &ws->r[in->out];
    } else { /* the lane's registers copied out; the constant as branch_b makes it */
        la = lane_reg(ws, lane, in->a);
        lo = lane_reg(ws, lane, in->out);
        if (rr)
            lb = lane_reg(ws, lane, in->b);
        src[0] = &la;
        src[1] = rr ? &lb : branch_b(in, NULL, &cst);
        out = &lo;
    }
    if (decided_branch(in, src[0]->v, src[1]->v) != ISM_BRANCH_FREE)
        return false;
    for (int p = 0; p < 2; p++) {
        piece[p].v = out->v;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            piece[p].d[k] = src[p]->d[k];
    }
    return true;
}
