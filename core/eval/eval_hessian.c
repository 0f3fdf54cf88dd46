/* eval_hessian.c — f, gradient and Hessian by forward-mode second-order differentiation:
 * each register carries a value, 3 first and 6 second partial derivatives
 * (xx xy xz yy yz zz). Product and quotient rules below; one-argument operations use the
 * chain rule h = g'(u) u'' + g''(u) u' u'^T.
 *
 * An instruction whose value depends on one variable only (the tape's free_of, core/expr/
 * tape.h: x^2, z^3, 9/4 y^2 ...) computes that variable's partial and second partial alone
 * (one_var_op) and writes 0 for the other eight, which are 0 in exact arithmetic and were
 * sums of products of zeros before: the results differ at most in the sign of a zero, or
 * where such a partial met an infinite value (0 · inf: NaN before, 0 now). The singular
 * search's Newton steps spend most of their time here. */
#include "core/eval/deriv_rules.h"
#include "core/eval/top_branch.h"
#include "core/eval/workspace.h"

/* The loops over the 3 first and 6 second partials are unrolled by pragma: gcc -O2 keeps
 * them rolled, a table lookup of HI/HJ and a branch per entry (the heart's Hessian, 1,870
 * instructions a point rolled, 1,527 unrolled; the same operations in the same order). */

/* The (i, j) index pairs of the six Hessian entries. */
static const int HI[6] = { 0, 0, 0, 1, 1, 2 };
static const int HJ[6] = { 0, 1, 2, 1, 2, 2 };

/* Each rule writes its result into o, which is never one of its operands (no instruction
 * writes a register it reads, tape.h): no jet is copied on the way. */
static inline void jet_mul(ism_jet *o, const ism_jet *a, const ism_jet *b)
{
    o->v = a->v * b->v;
    _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
        o->d[k] = a->d[k] * b->v + a->v * b->d[k];
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = a->h[k] * b->v + a->v * b->h[k] + a->d[HI[k]] * b->d[HJ[k]]
                  + a->d[HJ[k]] * b->d[HI[k]];
}

/* q = a / b: q' = (a' - q b') / b, q'' = (a'' - q' b'^T - b' q'^T - q b'') / b. */
static inline void jet_div(ism_jet *o, const ism_jet *a, const ism_jet *b)
{
    o->v = a->v / b->v;
    _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
        o->d[k] = (a->d[k] - o->v * b->d[k]) / b->v;
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = (a->h[k] - o->d[HI[k]] * b->d[HJ[k]] - b->d[HI[k]] * o->d[HJ[k]]
                   - o->v * b->h[k]) / b->v;
}

static inline void jet_binary(ism_jet *o, int op, const ism_jet *a, const ism_jet *b)
{
    double s = op == ISM_OP_SUB_RR ? -1.0 : 1.0;
    switch (op) {
    case ISM_OP_ADD_RR:
    case ISM_OP_SUB_RR:
        o->v = a->v + s * b->v;
        _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
            o->d[k] = a->d[k] + s * b->d[k];
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = a->h[k] + s * b->h[k];
        return;
    case ISM_OP_MUL_RR: jet_mul(o, a, b); return;
    case ISM_OP_DIV_RR: jet_div(o, a, b); return;
    case ISM_OP_MIN_RR: *o = ism_minmax_gradient_operand(true, a->v, b->v) ? *b : *a; return;
    default: *o = ism_minmax_gradient_operand(false, a->v, b->v) ? *b : *a; return; /* MAX_RR */
    }
}

static inline void jet_op(const ism_instr *in, ism_jet *r)
{
    ism_jet *o = &r[in->out];
    if (ism_op_has_reg_b(in->op)) {
        jet_binary(o, in->op, &r[in->a], &r[in->b]);
        return;
    }
    if (in->op == ISM_OP_CONST) {
        *o = (ism_jet){ 0 };
        o->v = in->imm;
        return;
    }
    const ism_jet *a = &r[in->a];
    ism_chain ch = ism_unary_chain(in, a->v);
    o->v = ch.g;
    if (ch.g1 == 0.0 && ch.g2 == 0.0) {
        _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
            o->d[k] = 0.0;
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = 0.0;
        return;
    }
    _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
        o->d[k] = ch.g1 * a->d[k];
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = ch.g1 * a->h[k] + ch.g2 * a->d[HI[k]] * a->d[HJ[k]];
}

/* Index of the Hessian entry (k, k). */
static const int DIAG[3] = { 0, 3, 5 };

/* An instruction whose value depends on variable k alone (and so its operands): the value,
 * d[k] and h[kk] by the same rules as above, every other partial 0. */
static void one_var_op(const ism_instr *in, ism_jet *r, int k)
{
    ism_jet *o = &r[in->out];
    const ism_jet *a = &r[in->a];
    int e = DIAG[k];
    double v, d, h;
    if (ism_op_has_reg_b(in->op)) {
        const ism_jet *b = &r[in->b];
        switch (in->op) {
        case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: {
            double s = in->op == ISM_OP_SUB_RR ? -1.0 : 1.0;
            v = a->v + s * b->v;
            d = a->d[k] + s * b->d[k];
            h = a->h[e] + s * b->h[e];
            break;
        }
        case ISM_OP_MUL_RR:
            v = a->v * b->v;
            d = a->d[k] * b->v + a->v * b->d[k];
            h = a->h[e] * b->v + a->v * b->h[e] + a->d[k] * b->d[k] + a->d[k] * b->d[k];
            break;
        case ISM_OP_DIV_RR:
            v = a->v / b->v;
            d = (a->d[k] - v * b->d[k]) / b->v;
            h = (a->h[e] - d * b->d[k] - b->d[k] * d - v * b->h[e]) / b->v;
            break;
        default: /* min, max: the jet of the operand taken */
            jet_binary(o, in->op, a, b);
            return;
        }
    } else {
        ism_chain ch = ism_unary_chain(in, a->v);
        v = ch.g;
        if (ch.g1 == 0.0 && ch.g2 == 0.0) {
            d = 0.0;
            h = 0.0;
        } else {
            d = ch.g1 * a->d[k];
            h = ch.g1 * a->h[e] + ch.g2 * a->d[k] * a->d[k];
        }
    }
    *o = (ism_jet){ 0 };
    o->v = v;
    o->d[k] = d;
    o->h[e] = h;
}

/* The variable of a one-variable instruction from its free_of (x: 6, y: 5, z: 3), else -1. */
static int one_var(uint8_t free_of)
{
    return free_of == 6u ? 0 : free_of == 5u ? 1 : free_of == 3u ? 2 : -1;
}

double ism_eval_hessian(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                        double grad[3], double hess[6])
{
    if (!ism_ws_fits(ws, t)) {
        _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
            grad[k] = NAN;
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            hess[k] = NAN;
        return NAN;
    }
    ism_jet *r = ws->jet;
    const double in[3] = { x, y, z };
    _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++) {
        r[k] = (ism_jet){ 0 };
        r[k].v = in[k];
        r[k].d[k] = 1.0;
    }
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *c = &t->code[i];
        int k = one_var(c->free_of); /* -1 for a constant (free of all) or no mask (0) */
        if (k >= 0)
            one_var_op(c, r, k);
        else
            jet_op(c, r);
    }
    const ism_jet *f = &r[t->result];
    _Pragma("GCC unroll 6") for (int k = 0; k < 3; k++)
        grad[k] = f->d[k];
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        hess[k] = f->h[k];
    return f->v;
}
