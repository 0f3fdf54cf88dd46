/* eval_gradient.c — f and its gradient by forward-mode differentiation: each register
 * carries a value and its three partial derivatives. min and max follow the branch they
 * take (the derivative of the side that is the result). */
#include "core/eval/avx2_clone.h"
#include "core/eval/deriv_rules.h"
#include "core/eval/lanes4.h"
#include "core/eval/threaded.h"
#include "core/eval/top_branch.h"
#include "core/eval/trig_pair.h"
#include "core/eval/workspace.h"
#include <string.h>

/* The two-register operations step_other hands dual_op (DIV_RR; +, − and × kept for
 * completeness of the rule): min and max have their own steps. */
static ism_dual dual_binary(int op, ism_dual a, ism_dual b)
{
    ism_dual r;
    switch (op) {
    case ISM_OP_ADD_RR:
        r.v = a.v + b.v;
        for (int k = 0; k < 3; k++)
            r.d[k] = a.d[k] + b.d[k];
        return r;
    case ISM_OP_SUB_RR:
        r.v = a.v - b.v;
        for (int k = 0; k < 3; k++)
            r.d[k] = a.d[k] - b.d[k];
        return r;
    case ISM_OP_MUL_RR:
        r.v = a.v * b.v;
        for (int k = 0; k < 3; k++)
            r.d[k] = a.d[k] * b.v + a.v * b.d[k];
        return r;
    default: /* ISM_OP_DIV_RR (min and max have their own steps, which never come here) */
        r.v = a.v / b.v;
        for (int k = 0; k < 3; k++)
            r.d[k] = (a.d[k] - r.v * b.d[k]) / b.v;
        return r;
    }
}

static ism_dual dual_op(const ism_instr *in, const ism_dual *r, ism_trig_cache *trig)
{
    if (ism_op_has_reg_b(in->op))
        return dual_binary(in->op, r[in->a], r[in->b]);
    if (in->op == ISM_OP_CONST) {
        ism_dual c = { in->imm, { 0.0, 0.0, 0.0 } };
        return c;
    }
    ism_dual a = r[in->a], out;
    ism_chain ch;
    if (in->op == ISM_OP_SIN || in->op == ISM_OP_COS) {
        double s, c;
        ism_trig_pair(trig, a.v, &s, &c);
        ch.g = in->op == ISM_OP_SIN ? s : c;
        ch.g1 = in->op == ISM_OP_SIN ? c : -s;
    } else {
        ch = ism_unary_chain(in, a.v);
    }
    out.v = ch.g;
    for (int k = 0; k < 3; k++)
        out.d[k] = ch.g1 == 0.0 ? 0.0 : ch.g1 * a.d[k];
    return out;
}

/* A dual number as one value of GCC's vector extension (lanes4.h), lanes v, d[0], d[1],
 * d[2]: each lane the scalar code's IEEE operation (one AVX2 register in the tape loop's AVX2
 * clone, two SSE2 ones elsewhere), so the bits are the scalar code's. */
_Static_assert(sizeof(ism_dual) == sizeof(v4d), "ism_dual is v, d[0..2] in a row");

INLINE v4d dld(const ism_dual *a)
{
    return v4_ld((const double *)(const void *)a);
}

INLINE void dst(ism_dual *o, v4d v)
{
    v4_st((double *)(void *)o, v);
}

INLINE v4d splat(double c)
{
    return (v4d){c, c, c, c};
}

/* out = g(a) with g' = g1: the chain rule, +0 where g1 is 0 (even when ∇a is not finite), as
 * a mask on the product (lanes4.h's v4_chain, the batched gradient's rule). */
INLINE void dual_chain(ism_dual *out, double g, double g1, const ism_dual *a)
{
    v4d d = v4_chain(splat(g1), dld(a));
    d[0] = g;
    dst(out, d);
}

/* One instruction in place, each operation its own step: the frequent ones written out (the
 * same arithmetic as dual_op, without building and copying a value per step), the others
 * through dual_op. Each is inlined into the tape loops (a call per instruction cost as much
 * as the arithmetic). o is the output register, a the first operand's. */
#define STEP(NAME) INLINE void NAME(const ism_instr *in, ism_dual *r, ism_trig_cache *trig, \
                                    ism_dual *o, const ism_dual *a)

STEP(step_add_rr)
{
    (void)trig;
    dst(o, dld(a) + dld(&r[in->b]));
}

STEP(step_sub_rr)
{
    (void)trig;
    dst(o, dld(a) - dld(&r[in->b]));
}

STEP(step_mul_rr) /* v = a b; d = a' b + a b' (each lane in that order) */
{
    (void)trig;
    v4d va = dld(a);
    v4d vb = dld(&r[in->b]);
    v4d left = va * splat(vb[0]);
    v4d d = left + splat(va[0]) * vb;
    d[0] = left[0];
    dst(o, d);
}

STEP(step_add_rc)
{
    (void)r, (void)trig;
    dual_chain(o, a->v + in->imm, 1.0, a);
}

STEP(step_mul_rc)
{
    (void)r, (void)trig;
    dual_chain(o, a->v * in->imm, in->imm, a);
}

STEP(step_square)
{
    (void)in, (void)r, (void)trig;
    dual_chain(o, a->v * a->v, 2.0 * a->v, a);
}

STEP(step_sin)
{
    (void)in, (void)r;
    double sv, cv;
    ism_trig_pair(trig, a->v, &sv, &cv);
    dual_chain(o, sv, cv, a);
}

STEP(step_cos)
{
    (void)in, (void)r;
    double sv, cv;
    ism_trig_pair(trig, a->v, &sv, &cv);
    dual_chain(o, cv, -sv, a);
}

STEP(step_max_rr)
{
    (void)trig;
    const ism_dual *b = &r[in->b];
    *o = ism_minmax_gradient_operand(false, a->v, b->v) ? *b : *a;
}

STEP(step_min_rr)
{
    (void)trig;
    const ism_dual *b = &r[in->b];
    *o = ism_minmax_gradient_operand(true, a->v, b->v) ? *b : *a;
}

/* the one-operand steps of CSG and distance tapes, ism_unary_chain's g and g' written out
 * (through dual_op they cost cube-minus-ball ~810 instructions a gradient) */
STEP(step_copy)
{
    (void)in, (void)r, (void)trig;
    dual_chain(o, a->v, 1.0, a);
}

STEP(step_neg)
{
    (void)in, (void)r, (void)trig;
    dual_chain(o, -a->v, -1.0, a);
}

STEP(step_sub_cr)
{
    (void)r, (void)trig;
    dual_chain(o, in->imm - a->v, -1.0, a);
}

STEP(step_div_rc)
{
    (void)r, (void)trig;
    dual_chain(o, a->v / in->imm, 1.0 / in->imm, a);
}

STEP(step_min_rc)
{
    (void)r, (void)trig;
    double d = ism_minmax_gradient_operand(true, a->v, in->imm) ? 0.0 : 1.0; /* imm is b */
    dual_chain(o, ism_min(a->v, in->imm), d, a);
}

STEP(step_max_rc)
{
    (void)r, (void)trig;
    double d = ism_minmax_gradient_operand(false, a->v, in->imm) ? 0.0 : 1.0;
    dual_chain(o, ism_max(a->v, in->imm), d, a);
}

STEP(step_abs)
{
    (void)in, (void)r, (void)trig;
    dual_chain(o, fabs(a->v), a->v < 0.0 ? -1.0 : a->v > 0.0 ? 1.0 : 0.0, a);
}

STEP(step_sqrt)
{
    (void)in, (void)r, (void)trig;
    double g = ism_sqrt_clip(a->v);
    dual_chain(o, g, a->v > 0.0 ? 0.5 / g : 0.0, a);
}

/* integer powers and exp, ism_unary_chain's g and g' written out (its g'' unasked): through
 * dual_op a power cost chmutov-quartic's x^4 about 225 instructions, exp catenoid's cosh
 * about 60 besides exp itself */
STEP(step_powi)
{
    (void)r, (void)trig;
    unsigned n = in->b;
    double g, p2;
    ism_powi_chain(a->v, n, &g, &p2);
    dual_chain(o, g, n * (p2 * a->v), a);
}

STEP(step_exp)
{
    (void)in, (void)r, (void)trig;
    double g = exp(a->v);
    dual_chain(o, g, g, a);
}

STEP(step_other)
{
    (void)a;
    *o = dual_op(in, r, trig);
}
#undef STEP

/* Every operation and its step: one list that dual_step's switch and THREADED_STEPS' labels
 * both expand, so that the two cannot differ. */
#define DUAL_STEPS(X)                                                                       \
    X(ISM_OP_CONST, step_other)                                                             \
    X(ISM_OP_COPY, step_copy)                                                               \
    X(ISM_OP_ADD_RR, step_add_rr)                                                           \
    X(ISM_OP_ADD_RC, step_add_rc)                                                           \
    X(ISM_OP_SUB_RR, step_sub_rr)                                                           \
    X(ISM_OP_SUB_CR, step_sub_cr)                                                           \
    X(ISM_OP_MUL_RR, step_mul_rr)                                                           \
    X(ISM_OP_MUL_RC, step_mul_rc)                                                           \
    X(ISM_OP_DIV_RR, step_other)                                                            \
    X(ISM_OP_DIV_RC, step_div_rc)                                                           \
    X(ISM_OP_DIV_CR, step_other)                                                            \
    X(ISM_OP_MIN_RR, step_min_rr)                                                           \
    X(ISM_OP_MIN_RC, step_min_rc)                                                           \
    X(ISM_OP_MAX_RR, step_max_rr)                                                           \
    X(ISM_OP_MAX_RC, step_max_rc)                                                           \
    X(ISM_OP_NEG, step_neg)                                                                 \
    X(ISM_OP_SQUARE, step_square)                                                           \
    X(ISM_OP_POWI, step_powi)                                                               \
    X(ISM_OP_POWC, step_other)                                                              \
    X(ISM_OP_SQRT, step_sqrt)                                                               \
    X(ISM_OP_SIN, step_sin)                                                                 \
    X(ISM_OP_COS, step_cos)                                                                 \
    X(ISM_OP_TAN, step_other)                                                               \
    X(ISM_OP_EXP, step_exp)                                                                 \
    X(ISM_OP_LOG, step_other)                                                               \
    X(ISM_OP_ABS, step_abs)
ISM_THREADED_COMPLETE(DUAL_STEPS, "DUAL_STEPS names every operation (THREADED_STEPS' table)");

/* One instruction in place, chosen by a switch (the piece gradient's loop, which steps
 * instruction by instruction between its forced kinks). */
INLINE void dual_step(const ism_instr *in, ism_dual *r, ism_trig_cache *trig)
{
    ism_dual *o = &r[in->out];
    const ism_dual *a = &r[in->a];
#define CASE(OP, FN) case OP: FN(in, r, trig, o, a); return;
    switch (in->op) {
    DUAL_STEPS(CASE)
    default: step_other(in, r, trig, o, a);
    }
#undef CASE
}

/* The body of a function stepping code[0..n) on r in order, by direct threading (GNU C's
 * labels as values): each step's code ends in its own test for the end and its own jump to
 * the next instruction's step, where a switch in a loop paid a bound test, a table offset and
 * the loop's test on every step. ism_eval_gradient on Klein bottle's tape (callgrind,
 * klein25_mb.c mode 0, with its caller's loop): 608 -> 510 instructions a gradient, with
 * run_steps_base below. An operation code past the list goes to dual_op, as
 * dual_step's default. A macro, not a function: each clone below holds its own labels. */
#define THREADED_STEPS(code, n, r, trig)                                                    \
    do {                                                                                    \
        DUAL_STEPS(DUAL_LABEL)                                                              \
        __label__ L_BAD;                                                                    \
        ISM_THREADED_TABLE(next_step, DUAL_STEPS);                                          \
        if (!(n))                                                                           \
            break;                                                                          \
        ism_dual *const regs = (r);                                                         \
        ism_trig_cache *const memo = (trig);                                                \
        const ism_instr *in = (code), *const end = (code) + (n);                            \
        goto *next_step[in->op];                                                            \
        DUAL_STEPS(DUAL_BODY)                                                               \
        DUAL_BODY(BAD, step_other)                                                          \
    } while (0)
#define DUAL_LABEL(OP, FN) __label__ L_##OP;
#define DUAL_BODY(OP, FN)                                                                   \
    L_##OP:                                                                                 \
    FN(in, regs, memo, &regs[in->out], &regs[in->a]);                                       \
    ISM_THREADED_NEXT(next_step, in, end, break)

/* ws's dual registers with x, y, z seeded (each its own unit derivative). */
static inline __attribute__((always_inline)) ism_dual *dual_inputs(ism_eval_ws *ws, double x,
                                                                   double y, double z)
{
    ism_dual *r = ws->dual;
    r[ISM_REG_X] = (ism_dual){ x, { 1.0, 0.0, 0.0 } };
    r[ISM_REG_Y] = (ism_dual){ y, { 0.0, 1.0, 0.0 } };
    r[ISM_REG_Z] = (ism_dual){ z, { 0.0, 0.0, 1.0 } };
    return r;
}

/* Steps code[0..n) in order, compiled twice: for AVX2 (a dual number one register) and for
 * the x86-64 baseline (two SSE2 ones); chosen at run time as eval_double.c chooses. Klein
 * bottle's tape, callgrind, a gradient: 702 instructions with the steps written out on
 * scalars, 631 so. */
#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE
static void run_steps_avx2(const ism_instr *code, size_t n, ism_dual *r, ism_trig_cache *trig)
{
    THREADED_STEPS(code, n, r, trig);
}
#endif

/* Its own function, not run_steps' fallback: there its prologue (the threaded loop's saved
 * registers) was paid by every gradient, the AVX2 clone's too (klein25_mb.c: 28 instructions
 * a gradient in run_steps). */
static __attribute__((noinline)) void run_steps_base(const ism_instr *code, size_t n,
                                                     ism_dual *r, ism_trig_cache *trig)
{
    THREADED_STEPS(code, n, r, trig);
}

static void run_steps(const ism_instr *code, size_t n, ism_dual *r, ism_trig_cache *trig)
{
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2()) {
        run_steps_avx2(code, n, r, trig);
        return;
    }
#endif
    run_steps_base(code, n, r, trig);
}

double ism_eval_gradient(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double grad[3])
{
    if (!ism_ws_fits(ws, t)) {
        grad[0] = grad[1] = grad[2] = NAN;
        return NAN;
    }
    ism_dual *r = dual_inputs(ws, x, y, z);
    run_steps(t->code, t->len, r, ws->trig);
    const ism_dual *f = &r[t->result];
    for (int k = 0; k < 3; k++)
        grad[k] = f->d[k];
    return f->v;
}

/* The index of t's min(a, b) or max(a, b) of two registers that f passes on through one-
 * operand steps alone (each reads only the step before's result: - 1, × c, a copy, ...),
 * with through: any such steps; without: none (it is the last instruction). t->len: none. */
static size_t crease_top(const ism_tape *t, bool through)
{
    if (!t->len || t->code[t->len - 1].out != t->result)
        return t->len;
    size_t i = t->len - 1;
    while (through && i > 0 && ism_op_has_reg_a(t->code[i].op) &&
           !ism_op_has_reg_b(t->code[i].op) && t->code[i].a == t->code[i - 1].out)
        i--;
    return t->code[i].op == ISM_OP_MIN_RR || t->code[i].op == ISM_OP_MAX_RR ? i : t->len;
}

/* Both branches at the point: the min/max at index top's two operands, each passed through
 * the steps after it (what f would be if that branch alone were taken). */
static bool branches_at(const ism_tape *t, size_t top, ism_eval_ws *ws, double x, double y,
                        double z, double val[2], double grad[2][3])
{
    if (top >= t->len || !ism_ws_fits(ws, t))
        return false;
    const ism_instr *mm = &t->code[top];
    ism_dual *r = dual_inputs(ws, x, y, z);
    run_steps(t->code, top, r, ws->trig);
    const ism_dual br[2] = {r[mm->a], r[mm->b]}; /* the steps after may reuse a's, b's */
    const size_t after = t->len - top - 1;
    for (int s = 0; s < 2; s++) {
        r[mm->out] = br[s];
        if (after) /* none where the min/max is f (ism_eval_top_branches): no call, no
                      prologue (Barth's sextic at E 0.00389: 89K empty runs, ~30 each) */
            run_steps(t->code + top + 1, after, r, ws->trig);
        val[s] = r[t->result].v;
        memcpy(grad[s], r[t->result].d, sizeof grad[s]);
    }
    return true;
}

bool ism_eval_top_branches(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                           double val[2], double grad[2][3])
{
    return branches_at(t, crease_top(t, false), ws, x, y, z, val, grad);
}

bool ism_eval_crease_branches(const ism_tape *t, ism_eval_ws *ws, double x, double y,
                              double z, double val[2], double grad[2][3])
{
    return branches_at(t, crease_top(t, true), ws, x, y, z, val, grad);
}

/* Kink in on branch br (1 or 2, as ism_piece): what ism_kink_pass says it passes. */
static inline void forced_step(const ism_instr *in, ism_dual *r, unsigned br)
{
    ism_dual *o = &r[in->out];
    const ism_dual *a = &r[in->a];
    switch (ism_kink_pass(in, br)) {
    case ISM_PASS_A: *o = *a; return;
    case ISM_PASS_B: *o = r[in->b]; return;
    case ISM_PASS_NEG_A: *o = (ism_dual){-a->v, {-a->d[0], -a->d[1], -a->d[2]}}; return;
    case ISM_PASS_IMM: *o = (ism_dual){in->imm, {0.0, 0.0, 0.0}}; return;
    }
}

double ism_eval_piece_gradient(const ism_tape *t, ism_eval_ws *ws, ism_piece pc, double x,
                               double y, double z, double grad[3])
{
    if (!ism_ws_fits(ws, t)) {
        grad[0] = grad[1] = grad[2] = NAN;
        return NAN;
    }
    ism_dual *r = dual_inputs(ws, x, y, z);
    unsigned k = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        if (!ism_op_is_kink(in->op)) {
            dual_step(in, r, ws->trig);
            continue;
        }
        unsigned br = ism_piece_branch(pc, k);
        k++;
        if (br)
            forced_step(in, r, br);
        else
            dual_step(in, r, ws->trig);
    }
    const ism_dual *f = &r[t->result];
    memcpy(grad, f->d, sizeof f->d);
    return f->v;
}
