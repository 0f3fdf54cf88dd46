/* eval_gradient.c — f and its gradient by forward-mode differentiation: each register
 * carries a value and its three partial derivatives. min and max follow the branch they
 * take (the derivative of the side that is the result). */
#include "core/eval/deriv_rules.h"
#include "core/eval/trig_pair.h"
#include "core/eval/workspace.h"
#include <string.h>

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
    case ISM_OP_DIV_RR:
        r.v = a.v / b.v;
        for (int k = 0; k < 3; k++)
            r.d[k] = (a.d[k] - r.v * b.d[k]) / b.v;
        return r;
    case ISM_OP_MIN_RR:
        return a.v < b.v ? a : b;
    default: /* ISM_OP_MAX_RR */
        return a.v > b.v ? a : b;
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

/* out = g(a) with g' = g1: the chain rule, 0 where g1 is 0 (even when ∇a is not finite). */
static inline __attribute__((always_inline)) void dual_chain(ism_dual *out, double g, double g1,
                                                             const ism_dual *a)
{
    double d0 = g1 == 0.0 ? 0.0 : g1 * a->d[0], d1 = g1 == 0.0 ? 0.0 : g1 * a->d[1],
           d2 = g1 == 0.0 ? 0.0 : g1 * a->d[2];
    out->v = g;
    out->d[0] = d0;
    out->d[1] = d1;
    out->d[2] = d2;
}

/* One instruction in place: the frequent operations written out (the same arithmetic as
 * dual_op, without building and copying a value per step), the others through dual_op.
 * Inlined into each tape loop (a call per instruction cost as much as the arithmetic). */
static inline __attribute__((always_inline)) void dual_step(const ism_instr *in, ism_dual *r,
                                                            ism_trig_cache *trig)
{
    ism_dual *o = &r[in->out];
    const ism_dual *a = &r[in->a];
    switch (in->op) {
    case ISM_OP_ADD_RR: {
        const ism_dual *b = &r[in->b];
        double v = a->v + b->v, d0 = a->d[0] + b->d[0], d1 = a->d[1] + b->d[1],
               d2 = a->d[2] + b->d[2];
        *o = (ism_dual){v, {d0, d1, d2}};
        return;
    }
    case ISM_OP_SUB_RR: {
        const ism_dual *b = &r[in->b];
        double v = a->v - b->v, d0 = a->d[0] - b->d[0], d1 = a->d[1] - b->d[1],
               d2 = a->d[2] - b->d[2];
        *o = (ism_dual){v, {d0, d1, d2}};
        return;
    }
    case ISM_OP_MUL_RR: {
        const ism_dual *b = &r[in->b];
        double av = a->v, bv = b->v;
        double d0 = a->d[0] * bv + av * b->d[0], d1 = a->d[1] * bv + av * b->d[1],
               d2 = a->d[2] * bv + av * b->d[2];
        *o = (ism_dual){av * bv, {d0, d1, d2}};
        return;
    }
    case ISM_OP_ADD_RC:
        dual_chain(o, a->v + in->imm, 1.0, a);
        return;
    case ISM_OP_MUL_RC:
        dual_chain(o, a->v * in->imm, in->imm, a);
        return;
    case ISM_OP_SQUARE:
        dual_chain(o, a->v * a->v, 2.0 * a->v, a);
        return;
    case ISM_OP_SIN:
    case ISM_OP_COS: {
        double sv, cv;
        ism_trig_pair(trig, a->v, &sv, &cv);
        if (in->op == ISM_OP_SIN)
            dual_chain(o, sv, cv, a);
        else
            dual_chain(o, cv, -sv, a);
        return;
    }
    case ISM_OP_MAX_RR: {
        const ism_dual *b = &r[in->b];
        *o = a->v > b->v ? *a : *b;
        return;
    }
    case ISM_OP_MIN_RR: {
        const ism_dual *b = &r[in->b];
        *o = a->v < b->v ? *a : *b;
        return;
    }
    /* the one-operand steps of CSG and distance tapes, ism_unary_chain's g and g' written
     * out (through dual_op they cost cube-minus-ball ~810 instructions a gradient) */
    case ISM_OP_COPY:
        dual_chain(o, a->v, 1.0, a);
        return;
    case ISM_OP_NEG:
        dual_chain(o, -a->v, -1.0, a);
        return;
    case ISM_OP_SUB_CR:
        dual_chain(o, in->imm - a->v, -1.0, a);
        return;
    case ISM_OP_DIV_RC:
        dual_chain(o, a->v / in->imm, 1.0 / in->imm, a);
        return;
    case ISM_OP_MIN_RC:
        dual_chain(o, ism_min(a->v, in->imm), a->v < in->imm ? 1.0 : 0.0, a);
        return;
    case ISM_OP_MAX_RC:
        dual_chain(o, ism_max(a->v, in->imm), a->v > in->imm ? 1.0 : 0.0, a);
        return;
    case ISM_OP_ABS:
        dual_chain(o, fabs(a->v), a->v < 0.0 ? -1.0 : a->v > 0.0 ? 1.0 : 0.0, a);
        return;
    case ISM_OP_SQRT: {
        double g = ism_sqrt_clip(a->v);
        dual_chain(o, g, a->v > 0.0 ? 0.5 / g : 0.0, a);
        return;
    }
    /* integer powers and exp, ism_unary_chain's g and g' written out (its g'' unasked):
       through dual_op a power cost chmutov-quartic's x^4 about 225 instructions, exp
       catenoid's cosh about 60 besides exp itself */
    case ISM_OP_POWI: {
        unsigned n = in->b;
        double g, p2;
        ism_powi_chain(a->v, n, &g, &p2);
        dual_chain(o, g, n * (p2 * a->v), a);
        return;
    }
    case ISM_OP_EXP: {
        double g = exp(a->v);
        dual_chain(o, g, g, a);
        return;
    }
    default:
        *o = dual_op(in, r, trig);
    }
}

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

double ism_eval_gradient(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double grad[3])
{
    if (!ism_ws_fits(ws, t)) {
        grad[0] = grad[1] = grad[2] = NAN;
        return NAN;
    }
    ism_dual *r = dual_inputs(ws, x, y, z);
    for (size_t i = 0; i < t->len; i++)
        dual_step(&t->code[i], r, ws->trig);
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
    for (size_t i = 0; i < top; i++)
        dual_step(&t->code[i], r, ws->trig);
    const ism_dual br[2] = {r[mm->a], r[mm->b]}; /* the steps after may reuse a's, b's */
    for (int s = 0; s < 2; s++) {
        r[mm->out] = br[s];
        for (size_t i = top + 1; i < t->len; i++)
            dual_step(&t->code[i], r, ws->trig);
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
