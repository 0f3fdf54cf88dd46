/* eval_hessian_batch.c — f, its gradient and Hessian at many points at once (eval.h's
 * ism_eval_hessian_batch): the forward-mode second-order rules of eval_hessian.c, each
 * register a value, three first and six second partials of ISM_HESS_BATCH lanes, each
 * instruction one step over the lanes. Every lane computes exactly what ism_eval_hessian
 * computes at its point, operation for operation and in its order (the one-variable
 * instructions' shortcut, the chain rule's zeros where g' and g'' are 0, min and max passing
 * on the whole chosen operand), so the two agree bit for bit and a caller may use either.
 *
 * Why: the dual mesher's straddle move takes the Hessian at the centre foot of every node
 * with both signs (dual_classify.c sag_split), ~1,000 instructions a point alone on the torus.
 *
 * The lanes are walked in groups of VL, each one value of GCC's vector extension (AVX2
 * registers in the AVX2 clone, chosen at run time, pairs of SSE2 ones otherwise); a batch
 * is padded to whole groups by repeating its last point. One-argument operations other than
 * the affine ones and squares take g, g' and g'' lane by lane (deriv_rules.h). */
#include "core/eval/avx2_clone.h"
#include "core/eval/deriv_rules.h"
#include "core/eval/lanes4.h"
#include "core/eval/workspace.h"
#include "core/util/cache_line.h"

#include <stdlib.h>
#include <string.h>

#define HL ISM_HESS_BATCH
#define VL 4
#define NG (HL / VL)
_Static_assert(VL == 4, "a group of lanes is one v4d (lanes4.h)");

/* One register of one group: value, gradient, Hessian (xx xy xz yy yz zz). */
typedef struct hj {
    v4d v, d[3], h[6];
} hj;

static const int HI[6] = {0, 0, 0, 1, 1, 2};
static const int HJ[6] = {0, 1, 2, 1, 2, 2};
static const int DIAG[3] = {0, 3, 5};

INLINE v4d splat(double x) { return (v4d){x, x, x, x}; }

INLINE void zero(hj *o)
{
    o->v = splat(0.0);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = splat(0.0);
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = splat(0.0);
}

/* *o = a where m is set, else b (min / max: the whole jet of the operand taken) */
INLINE void pick_jet(hj *o, v4i m, const hj *a, const hj *b)
{
    o->v = v4_pick(m, a->v, b->v);
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = v4_pick(m, a->d[k], b->d[k]);
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = v4_pick(m, a->h[k], b->h[k]);
}

/* eval_hessian.c's jet_binary (its jet_mul, jet_div) */
INLINE void binary(hj *o, int op, const hj *a, const hj *b)
{
    switch (op) {
    case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: {
        v4d s = splat(op == ISM_OP_SUB_RR ? -1.0 : 1.0);
        o->v = a->v + s * b->v;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = a->d[k] + s * b->d[k];
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = a->h[k] + s * b->h[k];
        return;
    }
    case ISM_OP_MUL_RR:
        o->v = a->v * b->v;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = a->d[k] * b->v + a->v * b->d[k];
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = a->h[k] * b->v + a->v * b->h[k] + a->d[HI[k]] * b->d[HJ[k]] +
                      a->d[HJ[k]] * b->d[HI[k]];
        return;
    case ISM_OP_DIV_RR:
        o->v = a->v / b->v;
        _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
            o->d[k] = (a->d[k] - o->v * b->d[k]) / b->v;
        _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
            o->h[k] = (a->h[k] - o->d[HI[k]] * b->d[HJ[k]] - b->d[HI[k]] * o->d[HJ[k]] -
                       o->v * b->h[k]) /
                      b->v;
        return;
    case ISM_OP_MIN_RR: pick_jet(o, (v4i)(a->v < b->v), a, b); return;
    default: pick_jet(o, (v4i)(a->v > b->v), a, b); return; /* MAX_RR */
    }
}

/* g(u), g'(u), g''(u) of a one-argument operation over a group: the affine ones and squares
 * as vectors (ism_unary_chain's expressions), the others lane by lane. */
INLINE void chain(const ism_instr *in, v4d u, v4d *g, v4d *g1, v4d *g2)
{
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_COPY: *g = u; *g1 = splat(1.0); *g2 = splat(0.0); return;
    case ISM_OP_ADD_RC: *g = u + splat(c); *g1 = splat(1.0); *g2 = splat(0.0); return;
    case ISM_OP_SUB_CR: *g = splat(c) - u; *g1 = splat(-1.0); *g2 = splat(0.0); return;
    case ISM_OP_MUL_RC: *g = u * splat(c); *g1 = splat(c); *g2 = splat(0.0); return;
    case ISM_OP_DIV_RC: *g = u / splat(c); *g1 = splat(1.0 / c); *g2 = splat(0.0); return;
    case ISM_OP_NEG: *g = -u; *g1 = splat(-1.0); *g2 = splat(0.0); return;
    case ISM_OP_SQUARE: *g = u * u; *g1 = splat(2.0) * u; *g2 = splat(2.0); return;
    default:
        for (int j = 0; j < VL; j++) {
            ism_chain ch = ism_unary_chain(in, u[j]);
            (*g)[j] = ch.g;
            (*g1)[j] = ch.g1;
            (*g2)[j] = ch.g2;
        }
        return;
    }
}

/* eval_hessian.c's jet_op for a one-argument operation or a constant */
INLINE void unary(const ism_instr *in, hj *o, const hj *a)
{
    if (in->op == ISM_OP_CONST) {
        zero(o);
        o->v = splat(in->imm);
        return;
    }
    v4d g, g1, g2;
    chain(in, a->v, &g, &g1, &g2);
    v4i live = ~((v4i)(g1 == splat(0.0)) & (v4i)(g2 == splat(0.0)));
    o->v = g;
    _Pragma("GCC unroll 3") for (int k = 0; k < 3; k++)
        o->d[k] = v4_pick(live, g1 * a->d[k], splat(0.0));
    _Pragma("GCC unroll 6") for (int k = 0; k < 6; k++)
        o->h[k] = v4_pick(live, g1 * a->h[k] + g2 * a->d[HI[k]] * a->d[HJ[k]], splat(0.0));
}

/* eval_hessian.c's one_var_op: an instruction whose value depends on variable k alone */
INLINE void one_var(const ism_instr *in, hj *o, const hj *a, const hj *b, int k)
{
    int e = DIAG[k];
    v4d v, d, h;
    switch (in->op) {
    case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: {
        v4d s = splat(in->op == ISM_OP_SUB_RR ? -1.0 : 1.0);
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
    case ISM_OP_MIN_RR: case ISM_OP_MAX_RR:
        binary(o, in->op, a, b);
        return;
    default: {
        v4d g1, g2;
        chain(in, a->v, &v, &g1, &g2);
        v4i live = ~((v4i)(g1 == splat(0.0)) & (v4i)(g2 == splat(0.0)));
        d = v4_pick(live, g1 * a->d[k], splat(0.0));
        h = v4_pick(live, g1 * a->h[e] + g2 * a->d[k] * a->d[k], splat(0.0));
        break;
    }
    }
    zero(o);
    o->v = v;
    o->d[k] = d;
    o->h[e] = h;
}

/* The variable of a one-variable instruction from its free_of (x: 6, y: 5, z: 3), else -1. */
static int var_of(uint8_t free_of)
{
    return free_of == 6u ? 0 : free_of == 5u ? 1 : free_of == 3u ? 2 : -1;
}

/* One instruction over ng groups (registers r: register-major, NG groups each). */
INLINE void step(const ism_instr *in, hj *r, size_t ng)
{
    int k = var_of(in->free_of);
    hj *o = r + (size_t)in->out * NG;
    const hj *a = r + (size_t)in->a * NG;
    const hj *b = ism_op_has_reg_b(in->op) ? r + (size_t)in->b * NG : a;
    for (size_t g = 0; g < ng; g++) {
        if (k >= 0)
            one_var(in, o + g, a + g, b + g, k);
        else if (ism_op_has_reg_b(in->op))
            binary(o + g, in->op, a + g, b + g);
        else
            unary(in, o + g, a + g);
    }
}

#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE static void run_avx2(const ism_tape *t, hj *r, size_t ng)
{
    for (size_t i = 0; i < t->len; i++)
        step(&t->code[i], r, ng);
}
#endif

static void run_base(const ism_tape *t, hj *r, size_t ng)
{
    for (size_t i = 0; i < t->len; i++)
        step(&t->code[i], r, ng);
}

/* Points p[0..n) (n <= HL) into f, g, h. */
static void chunk(const ism_tape *t, hj *r, const double (*p)[3], double *f, double (*g)[3],
                  double (*h)[6], size_t n)
{
    size_t ng = (n + VL - 1) / VL;
    for (int k = 0; k < 3; k++)
        for (size_t q = 0; q < ng; q++) {
            hj *x = r + (size_t)k * NG + q;
            zero(x);
            for (size_t j = 0; j < VL; j++)
                x->v[j] = p[q * VL + j < n ? q * VL + j : n - 1][k];
            x->d[k] = splat(1.0);
        }
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2())
        run_avx2(t, r, ng);
    else
#endif
        run_base(t, r, ng);
    const hj *res = r + (size_t)t->result * NG;
    for (size_t i = 0; i < n; i++) {
        const hj *x = res + i / VL;
        size_t j = i % VL;
        f[i] = x->v[j];
        for (int k = 0; k < 3; k++)
            g[i][k] = x->d[k][j];
        for (int k = 0; k < 6; k++)
            h[i][k] = x->h[k][j];
    }
}

void ism_eval_hessian_batch(const ism_tape *t, ism_eval_ws *ws, const double (*p)[3],
                            double *f, double (*g)[3], double (*h)[6], size_t n)
{
    if (ism_ws_fits(ws, t) && !ws->hbatch)
        ws->hbatch = ism_line_alloc((size_t)ws->nregs * NG * sizeof(hj));
    if (!ism_ws_fits(ws, t) || !ws->hbatch) { /* no room: what ism_eval_hessian gives */
        for (size_t i = 0; i < n; i++)
            f[i] = ism_eval_hessian(t, ws, p[i][0], p[i][1], p[i][2], g[i], h[i]);
        return;
    }
    for (size_t done = 0; done < n; done += HL) {
        size_t m = n - done < HL ? n - done : HL;
        chunk(t, (hj *)ws->hbatch, p + done, f + done, g + done, h + done, m);
    }
}
