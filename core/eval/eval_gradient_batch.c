/* eval_gradient_batch.c — f and its gradient at many points at once (forward mode, like
 * eval_gradient.c), each register a value and three partials of ISM_GRAD_BATCH lanes, each
 * instruction one loop over the lanes. Every lane computes exactly what ism_eval_gradient
 * computes at its point, operation for operation (min and max pass on the whole chosen
 * operand; the chain rule gives 0 where g' is 0; sines and cosines through the same memo of
 * sincos pairs), so the two agree bit for bit: the polygoniser may use either. */
#include "core/eval/deriv_rules.h"
#include "core/eval/trig_pair.h"
#include "core/eval/workspace.h"

#define GL ISM_GRAD_BATCH

/* Component k (0: value, 1-3: d/dx, d/dy, d/dz) of register r. */
static inline double *comp(double *regs, uint32_t r, int k)
{
    return regs + ((size_t)r * 4 + (size_t)k) * GL;
}

/* The chain rule's partials of out = g(a) given g' per lane, as dual_chain writes them. */
static inline void chain_partials(double *regs, const ism_instr *in, const double *g1,
                                  size_t n)
{
    for (int k = 1; k < 4; k++) {
        double *restrict o = comp(regs, in->out, k);
        const double *restrict a = comp(regs, in->a, k);
        for (size_t j = 0; j < n; j++)
            o[j] = g1[j] == 0.0 ? 0.0 : g1[j] * a[j];
    }
}

/* min or max: each lane takes all four components of the operand it chooses. */
static void select_lanes(double *regs, const ism_instr *in, bool is_min, size_t n)
{
    const double *av = comp(regs, in->a, 0), *bv = comp(regs, in->b, 0);
    for (size_t j = 0; j < n; j++) {
        bool take_a = is_min ? av[j] < bv[j] : av[j] > bv[j];
        uint32_t src = take_a ? in->a : in->b;
        for (int k = 0; k < 4; k++)
            comp(regs, in->out, k)[j] = comp(regs, src, k)[j];
    }
}

static void grad_step(const ism_instr *in, double *regs, ism_trig_cache *trig, size_t n)
{
    double *ov = comp(regs, in->out, 0);
    const double *av = comp(regs, in->a, 0);
    double g1[GL];
    switch (in->op) {
    case ISM_OP_ADD_RR:
    case ISM_OP_SUB_RR: {
        bool add = in->op == ISM_OP_ADD_RR;
        for (int k = 0; k < 4; k++) {
            double *restrict o = comp(regs, in->out, k);
            const double *restrict a = comp(regs, in->a, k), *restrict b = comp(regs, in->b, k);
            if (add)
                for (size_t j = 0; j < n; j++)
                    o[j] = a[j] + b[j];
            else
                for (size_t j = 0; j < n; j++)
                    o[j] = a[j] - b[j];
        }
        return;
    }
    case ISM_OP_MUL_RR: {
        const double *restrict bv = comp(regs, in->b, 0);
        for (int k = 1; k < 4; k++) {
            double *restrict o = comp(regs, in->out, k);
            const double *restrict a = comp(regs, in->a, k), *restrict b = comp(regs, in->b, k);
            for (size_t j = 0; j < n; j++)
                o[j] = a[j] * bv[j] + av[j] * b[j];
        }
        for (size_t j = 0; j < n; j++)
            ov[j] = av[j] * bv[j];
        return;
    }
    case ISM_OP_DIV_RR: { /* dual_binary: v = a / b, d = (a' - v b') / b */
        const double *restrict bv = comp(regs, in->b, 0);
        for (size_t j = 0; j < n; j++)
            ov[j] = av[j] / bv[j];
        for (int k = 1; k < 4; k++) {
            double *restrict o = comp(regs, in->out, k);
            const double *restrict a = comp(regs, in->a, k), *restrict b = comp(regs, in->b, k);
            for (size_t j = 0; j < n; j++)
                o[j] = (a[j] - ov[j] * b[j]) / bv[j];
        }
        return;
    }
    case ISM_OP_MIN_RR:
    case ISM_OP_MAX_RR:
        select_lanes(regs, in, in->op == ISM_OP_MIN_RR, n);
        return;
    case ISM_OP_CONST:
        for (size_t j = 0; j < n; j++)
            ov[j] = in->imm;
        for (int k = 1; k < 4; k++)
            for (size_t j = 0; j < n; j++)
                comp(regs, in->out, k)[j] = 0.0;
        return;
    case ISM_OP_ADD_RC:
        for (size_t j = 0; j < n; j++) {
            ov[j] = av[j] + in->imm;
            g1[j] = 1.0;
        }
        break;
    case ISM_OP_MUL_RC:
        for (size_t j = 0; j < n; j++) {
            ov[j] = av[j] * in->imm;
            g1[j] = in->imm;
        }
        break;
    case ISM_OP_SQUARE:
        for (size_t j = 0; j < n; j++) {
            ov[j] = av[j] * av[j];
            g1[j] = 2.0 * av[j];
        }
        break;
    case ISM_OP_SIN:
    case ISM_OP_COS: {
        bool is_sin = in->op == ISM_OP_SIN;
        for (size_t j = 0; j < n; j++) {
            double s, c;
            ism_trig_pair(trig, av[j], &s, &c);
            ov[j] = is_sin ? s : c;
            g1[j] = is_sin ? c : -s;
        }
        break;
    }
    default: /* the other one-operand steps, by the rules the scalar evaluator uses */
        for (size_t j = 0; j < n; j++) {
            ism_chain ch = ism_unary_chain(in, av[j]);
            ov[j] = ch.g;
            g1[j] = ch.g1;
        }
        break;
    }
    chain_partials(regs, in, g1, n);
}

static void grad_chunk(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                       const double *z, double *f, double (*g)[3], size_t n)
{
    double *regs = ws->gbatch;
    const double *src[3] = {x, y, z};
    for (uint32_t v = 0; v < 3; v++) {
        double *val = comp(regs, v, 0);
        for (size_t j = 0; j < n; j++)
            val[j] = src[v][j];
        for (int k = 1; k < 4; k++) {
            double *d = comp(regs, v, k), one = (uint32_t)(k - 1) == v ? 1.0 : 0.0;
            for (size_t j = 0; j < n; j++)
                d[j] = one;
        }
    }
    for (size_t i = 0; i < t->len; i++)
        grad_step(&t->code[i], regs, ws->trig, n);
    for (size_t j = 0; j < n; j++) {
        f[j] = comp(regs, t->result, 0)[j];
        for (int k = 0; k < 3; k++)
            g[j][k] = comp(regs, t->result, k + 1)[j];
    }
}

void ism_eval_gradient_batch(const ism_tape *t, ism_eval_ws *ws, const double *x,
                             const double *y, const double *z, double *f, double (*g)[3],
                             size_t n)
{
    if (!ism_ws_fits(ws, t)) {
        for (size_t i = 0; i < n; i++)
            f[i] = g[i][0] = g[i][1] = g[i][2] = NAN;
        return;
    }
    for (size_t done = 0; done < n; done += GL) {
        size_t k = n - done < GL ? n - done : GL;
        grad_chunk(t, ws, x + done, y + done, z + done, f + done, g + done, k);
    }
}
