/* eval_interval.c — the interval evaluator: one pass over the tape with interval registers
 * (arithmetic in interval_ops.h). Optionally records, for every min/max, which operand the
 * box proves to be the result everywhere; tape shortening reads those choices. */
#include "core/eval/interval_eval.h"
#include "core/eval/interval_ops.h"
#include "core/eval/workspace.h"

enum { BOTH = 0, ONLY_A = 1, ONLY_B = 2 };

/* Strictly: the intervals enclose every double evaluation at a point of the box (each
 * operation rounds monotonically, the intervals outward), so a.hi < b.lo makes a < b there
 * and min(a, b) exactly a — its value and its gradient; where they may touch, a tie
 * (min picks b, and -0 against +0) would make the shortened tape differ. */
static uint8_t min_choice(ism_interval a, ism_interval b)
{
    return a.hi < b.lo ? ONLY_A : b.hi < a.lo ? ONLY_B : BOTH;
}

static uint8_t max_choice(ism_interval a, ism_interval b)
{
    return a.lo > b.hi ? ONLY_A : b.lo > a.hi ? ONLY_B : BOTH;
}

/* sin or cos over a: the bounds' sines and cosines as pairs from the workspace's memo
 * (trig_pair.h: bit for bit what sin and cos return), so the gyroid's sin x and cos x of one
 * box cost one sincos per bound instead of two calls each. */
static ism_interval trig_op(int op, ism_interval a, ism_trig_cache *trig)
{
    if (!iv_trig_resolves(a))
        return iv(-1.0, 1.0);
    double s1, c1, s2, c2;
    ism_trig_pair(trig, a.lo, &s1, &c1);
    ism_trig_pair(trig, a.hi, &s2, &c2);
    return op == ISM_OP_SIN ? iv_sin_at(a, s1, s2) : iv_cos_at(a, c1, c2);
}

static ism_interval interval_op(const ism_instr *in, const ism_interval *r, uint8_t *choice,
                                ism_trig_cache *trig)
{
    ism_interval a = r[in->a];
    double c = in->imm;
    ism_interval cc = { c, c };
    switch (in->op) {
    case ISM_OP_CONST: return cc;
    case ISM_OP_COPY: return a;
    case ISM_OP_ADD_RR: return iv_add(a, r[in->b]);
    case ISM_OP_ADD_RC: return iv_add_c(a, c);
    case ISM_OP_SUB_RR: return iv_sub(a, r[in->b]);
    case ISM_OP_SUB_CR: return iv_c_sub(c, a);
    case ISM_OP_MUL_RR: return iv_mul(a, r[in->b]);
    case ISM_OP_MUL_RC: return iv_mul_c(a, c);
    case ISM_OP_DIV_RR: return iv_div(a, r[in->b]);
    case ISM_OP_DIV_RC: return iv_div_c(a, c);
    case ISM_OP_DIV_CR: return iv_c_div(c, a);
    case ISM_OP_MIN_RR: *choice = min_choice(a, r[in->b]); return iv_min(a, r[in->b]);
    case ISM_OP_MIN_RC: *choice = min_choice(a, cc); return iv_min(a, cc);
    case ISM_OP_MAX_RR: *choice = max_choice(a, r[in->b]); return iv_max(a, r[in->b]);
    case ISM_OP_MAX_RC: *choice = max_choice(a, cc); return iv_max(a, cc);
    case ISM_OP_NEG: return iv_neg(a);
    case ISM_OP_SQUARE: return iv_square(a);
    case ISM_OP_POWI: return iv_powi(a, in->b);
    case ISM_OP_POWC: return iv_powc(a, c);
    case ISM_OP_SQRT: return iv_sqrt(a);
    case ISM_OP_SIN: case ISM_OP_COS: return trig_op(in->op, a, trig);
    case ISM_OP_TAN: return iv_tan(a);
    case ISM_OP_EXP: return iv_exp(a);
    case ISM_OP_LOG: return iv_log(a);
    case ISM_OP_ABS: *choice = a.lo >= 0 ? ONLY_A : a.hi < 0 ? ONLY_B : BOTH; return iv_abs(a);
    default: return ism_iv_whole();
    }
}

static ism_interval sane_input(ism_interval v)
{
    if (!(v.lo <= v.hi))
        return ism_iv_whole();
    return v;
}

ism_interval ism_interval_run(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                              ism_interval y, ism_interval z, uint8_t *choices)
{
    ism_interval *r = ws->iv;
    r[ISM_REG_X] = sane_input(x);
    r[ISM_REG_Y] = sane_input(y);
    r[ISM_REG_Z] = sane_input(z);
    uint8_t scratch = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        r[in->out] = ism_iv_sane(interval_op(in, r, choices ? &choices[i] : &scratch, ws->trig));
    }
    return r[t->result];
}

ism_interval ism_eval_interval(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                               ism_interval y, ism_interval z)
{
    if (!ism_ws_fits(ws, t))
        return ism_iv_whole();
    return ism_interval_run(t, ws, x, y, z, NULL);
}

int ism_eval_interval_top(const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                          ism_interval z, ism_interval val[2])
{
    const ism_instr *top = ism_tape_top_minmax(t);
    if (!top || !ism_ws_fits(ws, t))
        return -1;
    ism_interval_run(t, ws, x, y, z, NULL);
    val[0] = ws->iv[top->a];
    val[1] = ws->iv[top->b];
    return top->op == ISM_OP_MAX_RR;
}
