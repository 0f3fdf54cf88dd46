/* eval_gradient_batch.c — f and its gradient at many points at once (forward mode, like
 * eval_gradient.c), each register a value and three partials of ISM_GRAD_BATCH lanes, each
 * instruction one loop over the lanes. Every lane computes exactly what ism_eval_gradient
 * computes at its point, operation for operation (min and max pass on the whole chosen
 * operand; the chain rule gives 0 where g' is 0; sines and cosines by sincos.h's own pair,
 * four lanes at once here, one through the memo there), so the two agree bit for bit: the
 * polygoniser may use either.
 *
 * The lanes are walked in groups of VL, each group one value of GCC's vector extension (the
 * IEEE operations of the scalar code, element by element; the chain rule's and min/max's
 * choices as bit masks with the same outcome, NaN included); a batch is padded up to a whole
 * group by repeating its last point. The tape loop is compiled for AVX2 and for the
 * x86-64 baseline, chosen at run time (as eval_double.c does). */
#include "core/eval/avx2_clone.h"
#include "core/eval/deriv_rules.h"
#include "core/eval/lanes4.h"
#include "core/eval/threaded.h"
#include "core/eval/trig_pair.h"
#include "core/eval/workspace.h"
#include <stdint.h>

#define GL ISM_GRAD_BATCH
#define VL 4 /* lanes per group: one AVX2 vector, two SSE2 ones */
_Static_assert(VL <= ISM_POWI_LANES, "a group's powers in one ism_powi_chain_lanes call");
_Static_assert(ISM_GRAD_UNROLLED == 4 * VL, "chunk_avx2 unrolls 1 to 4 groups (eval.h)");

/* Component k (0: value, 1-3: d/dx, d/dy, d/dz) of register r: the register's base, then
 * the component's fixed offset (an addressing mode's displacement). The empty asm makes the
 * base one value the compiler cannot take apart (it emits nothing; not volatile, so equal
 * bases are still shared): without it GCC formed two bases per operand, r 4 GL and
 * (r 4 + 1) GL, each its own shifts (callgrind --dump-instr, a 1-group MUL_RR: 33
 * instructions, 8 of them those). Barth's sextic at E 0.0259: 1,004.6M -> 998.5M. */
static inline double *comp(double *regs, uint32_t r, int k)
{
    double *base = regs + (size_t)r * (4 * GL);
    __asm__("" : "+r"(base));
    return base + (size_t)k * GL;
}

/* VL lanes as one value of GCC's vector extension (lanes4.h). */
_Static_assert(sizeof(v4d) == VL * sizeof(double), "a group is one v4d");

INLINE void k_add(double *o, const double *a, const double *b)
{
    v4_st(o, v4_ld(a) + v4_ld(b));
}

INLINE void k_sub(double *o, const double *a, const double *b)
{
    v4_st(o, v4_ld(a) - v4_ld(b));
}

INLINE void k_mul(double *o, const double *a, const double *b)
{
    v4_st(o, v4_ld(a) * v4_ld(b));
}

/* d(a b) = a' b + a b' (dual_step's order of terms) */
INLINE void k_mul_d(double *o, const double *ad, const double *bv, const double *av,
                    const double *bd)
{
    v4_st(o, v4_ld(ad) * v4_ld(bv) + v4_ld(av) * v4_ld(bd));
}

INLINE void k_div(double *o, const double *a, const double *b)
{
    v4_st(o, v4_ld(a) / v4_ld(b));
}

/* d(a / b) = (a' − (a / b) b') / b (dual_binary's) */
INLINE void k_div_d(double *o, const double *ad, const double *q, const double *bd,
                    const double *bv)
{
    v4_st(o, (v4_ld(ad) - v4_ld(q) * v4_ld(bd)) / v4_ld(bv));
}

/* min: a's component where a.v < b.v, else b's; max: where a.v > b.v (top_branch.h's
 * ism_minmax_gradient_operand, four lanes at once: a compare's mask is false on NaN) */
INLINE void k_pick(double *o, const double *av, const double *bv, const double *ak,
                   const double *bk, bool is_min)
{
    v4i m = is_min ? (v4i)(v4_ld(av) < v4_ld(bv)) : (v4i)(v4_ld(av) > v4_ld(bv));
    v4_st(o, v4_pick(m, v4_ld(ak), v4_ld(bk)));
}

/* the chain rule's partial g' a' (lanes4.h's v4_chain: 0 where g' is 0) */
INLINE void k_chain(double *o, const double *g1, const double *a)
{
    v4_st(o, v4_chain(v4_ld(g1), v4_ld(a)));
}

INLINE void k_chain_c(double *o, double g1, const double *a)
{
    v4_st(o, v4_chain((v4d){g1, g1, g1, g1}, v4_ld(a)));
}

INLINE void k_fill(double *o, double c)
{
    v4_st(o, (v4d){c, c, c, c});
}

/* The three partials of out = g(a) from per-lane g' (g1v) or one g' for all (g1c). */
INLINE void chain_partials(double *regs, const ism_instr *in, const double *g1v, double g1c,
                           size_t ng)
{
    #pragma GCC unroll 4
    for (int k = 1; k < 4; k++) {
        double *o = comp(regs, in->out, k);
        const double *a = comp(regs, in->a, k);
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            if (g1v)
                k_chain(o + g * VL, g1v + g * VL, a + g * VL);
            else
                k_chain_c(o + g * VL, g1c, a + g * VL);
        }
    }
}

_Static_assert(ISM_TRIG_GROUP_LANES == GL, "a group pair holds a whole register");
_Static_assert(VL == 4, "ism_trig_groups' groups are of four lanes");

/* One instruction over ng groups, its operation op (code->op: a constant where the threaded
 * loops below inline it, so that only op's own arm and addresses are compiled there). */
INLINE void grad_step_op(int op, const ism_instr *code, double *regs, ism_trig_cache *trig,
                         size_t ng)
{
    /* the instruction in a local: the lanes' stores go through memcpy, which may alias the
     * tape, so fields read through `code` were loaded again after every store (callgrind:
     * a third of the torus's batched steps were address arithmetic) */
    const ism_instr ins = *code, *in = &ins;
    const size_t n = ng * VL;
    double *ov = comp(regs, in->out, 0);
    const double *av = comp(regs, in->a, 0);
    const double *bv = comp(regs, ism_op_has_reg_b(op) ? in->b : in->a, 0);
    double g1[GL];
    switch (op) {
    case ISM_OP_ADD_RR:
    case ISM_OP_SUB_RR:
        #pragma GCC unroll 4
        for (int k = 0; k < 4; k++) {
            double *o = comp(regs, in->out, k);
            const double *a = comp(regs, in->a, k), *b = comp(regs, in->b, k);
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++) {
                if (op == ISM_OP_ADD_RR)
                    k_add(o + g * VL, a + g * VL, b + g * VL);
                else
                    k_sub(o + g * VL, a + g * VL, b + g * VL);
            }
        }
        return;
    case ISM_OP_MUL_RR:
        #pragma GCC unroll 4
        for (int k = 1; k < 4; k++) {
            double *o = comp(regs, in->out, k);
            const double *a = comp(regs, in->a, k), *b = comp(regs, in->b, k);
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++)
                k_mul_d(o + g * VL, a + g * VL, bv + g * VL, av + g * VL, b + g * VL);
        }
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++)
            k_mul(ov + g * VL, av + g * VL, bv + g * VL);
        return;
    case ISM_OP_DIV_RR:
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++)
            k_div(ov + g * VL, av + g * VL, bv + g * VL);
        #pragma GCC unroll 4
        for (int k = 1; k < 4; k++) {
            double *o = comp(regs, in->out, k);
            const double *a = comp(regs, in->a, k), *b = comp(regs, in->b, k);
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++)
                k_div_d(o + g * VL, a + g * VL, ov + g * VL, b + g * VL, bv + g * VL);
        }
        return;
    case ISM_OP_MIN_RR:
    case ISM_OP_MAX_RR:
        #pragma GCC unroll 4
        for (int k = 0; k < 4; k++) {
            double *o = comp(regs, in->out, k);
            const double *a = comp(regs, in->a, k), *b = comp(regs, in->b, k);
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++)
                k_pick(o + g * VL, av + g * VL, bv + g * VL, a + g * VL, b + g * VL,
                       op == ISM_OP_MIN_RR);
        }
        return;
    case ISM_OP_CONST:
        #pragma GCC unroll 4
        for (int k = 0; k < 4; k++)
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++)
                k_fill(comp(regs, in->out, k) + g * VL, k ? 0.0 : in->imm);
        return;
    case ISM_OP_ADD_RC:
    case ISM_OP_MUL_RC: {
        v4d c = {in->imm, in->imm, in->imm, in->imm};
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++)
            v4_st(ov + g * VL,
                  op == ISM_OP_ADD_RC ? v4_ld(av + g * VL) + c : v4_ld(av + g * VL) * c);
        chain_partials(regs, in, NULL, op == ISM_OP_ADD_RC ? 1.0 : in->imm, ng);
        return;
    }
    case ISM_OP_COPY:
    case ISM_OP_NEG:
    case ISM_OP_SUB_CR:
    case ISM_OP_DIV_RC: { /* g' one constant: ism_unary_chain's g and g' */
        v4d c = {in->imm, in->imm, in->imm, in->imm};
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            v4d a = v4_ld(av + g * VL);
            v4_st(ov + g * VL, op == ISM_OP_COPY     ? a
                               : op == ISM_OP_NEG    ? -a
                               : op == ISM_OP_SUB_CR ? c - a
                                                     : a / c);
        }
        chain_partials(regs, in, NULL,
                       op == ISM_OP_COPY     ? 1.0
                       : op == ISM_OP_DIV_RC ? 1.0 / in->imm
                                             : -1.0,
                       ng);
        return;
    }
    case ISM_OP_ABS: { /* |a|, g' = -1, +1 or 0 (a NaN: neither side, 0) */
        v4d zero = {0.0, 0.0, 0.0, 0.0}, one = {1.0, 1.0, 1.0, 1.0};
        v4i sign = {INT64_MIN, INT64_MIN, INT64_MIN, INT64_MIN};
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            v4d a = v4_ld(av + g * VL);
            v4_st(ov + g * VL, (v4d)((v4i)a & ~sign));
            v4_st(g1 + g * VL, v4_pick((v4i)(a < zero), -one, v4_keep(one, (v4i)(a > zero))));
        }
        break;
    }
    case ISM_OP_SQUARE: {
        v4d two = {2.0, 2.0, 2.0, 2.0};
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            v4d a = v4_ld(av + g * VL);
            v4_st(ov + g * VL, a * a);
            v4_st(g1 + g * VL, two * a);
        }
        break;
    }
    case ISM_OP_SIN:
    case ISM_OP_COS: { /* the register's sines and cosines (ism_trig_groups): what the scalar
                          evaluator's memo holds for each lane, bit for bit */
        const ism_trig_group_pair *p = ism_trig_groups(trig, av, ng);
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            v4d s = v4_ld(p->s + g * VL), c = v4_ld(p->c + g * VL);
            v4_st(ov + g * VL, op == ISM_OP_SIN ? s : c);
            v4_st(g1 + g * VL, op == ISM_OP_SIN ? c : -s);
        }
        break;
    }
    case ISM_OP_POWI: { /* a^n and n a^(n-2) a: ism_unary_chain's g and g', lane by lane
                           the same products (ism_powi_chain_lanes): through it, 74
                           instructions a lane on chmutov-quartic's x^4 */
        unsigned e = in->b;
        v4d nv = {(double)e, (double)e, (double)e, (double)e};
        #pragma GCC unroll 4
        for (size_t g = 0; g < ng; g++) {
            double p2[VL];
            ism_powi_chain_lanes(av + g * VL, e, ov + g * VL, p2, VL);
            v4_st(g1 + g * VL, nv * (v4_ld(p2) * v4_ld(av + g * VL)));
        }
        break;
    }
    case ISM_OP_EXP:
        for (size_t j = 0; j < n; j++)
            ov[j] = g1[j] = exp(av[j]);
        break;
    default: /* the other one-operand steps, by the rules the scalar evaluator uses */
        for (size_t j = 0; j < n; j++) {
            ism_chain ch = ism_unary_chain(in, av[j]);
            ov[j] = ch.g;
            g1[j] = ch.g1;
        }
        break;
    }
    chain_partials(regs, in, g1, 0.0, ng);
}

INLINE void grad_step(const ism_instr *code, double *regs, ism_trig_cache *trig, size_t ng)
{
    grad_step_op(code->op, code, regs, trig, ng);
}

/* The input registers for n points, ng groups (VL (ng - 1) < n <= VL ng): x, y, z in their
 * value lanes, lanes past n repeating the last point; their partials the unit vectors. */
INLINE void load_inputs(double *regs, const double *const src[3], size_t n, size_t ng)
{
    const size_t last = n - 1;
    #pragma GCC unroll 3
    for (uint32_t v = 0; v < 3; v++) {
        double *val = comp(regs, v, 0);
        #pragma GCC unroll 4
        for (size_t g = 0; g + 1 < ng; g++) /* the whole groups */
            v4_st(val + g * VL, v4_ld(src[v] + g * VL));
        #pragma GCC unroll 4
        for (size_t j = (ng - 1) * VL; j < ng * VL; j++) /* the last, padded */
            val[j] = src[v][j < last ? j : last];
        #pragma GCC unroll 4
        for (int k = 1; k < 4; k++)
            #pragma GCC unroll 4
            for (size_t g = 0; g < ng; g++)
                k_fill(comp(regs, v, k) + g * VL, (uint32_t)(k - 1) == v ? 1.0 : 0.0);
    }
}

/* Four lanes' partials (x, y, z: d/dx, d/dy, d/dz of lanes 0-3) into g[0..4), which are
 * 12 doubles in a row: x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3, three vectors by shuffles
 * (copies: the bits as they are) where twelve scalar loads and stores were. */
INLINE void store_group_grads(double (*g)[3], v4d x, v4d y, v4d z)
{
    double *flat = &g[0][0]; /* g[0..4) of a contiguous double[n][3], as 12 in a row */
    v4d xy01 = __builtin_shuffle(x, y, (v4i){0, 4, 1, 5}); /* x0 y0 x1 y1 */
    v4d xy23 = __builtin_shuffle(x, y, (v4i){2, 6, 3, 7}); /* x2 y2 x3 y3 */
    v4d mid = __builtin_shuffle(xy01, xy23, (v4i){3, 3, 4, 5}); /* y1 y1 x2 y2 */
    v4_st(flat, __builtin_shuffle(xy01, z, (v4i){0, 1, 4, 2}));
    v4_st(flat + 4, __builtin_shuffle(mid, z, (v4i){0, 5, 2, 3}));
    v4_st(flat + 8, __builtin_shuffle(xy23, z, (v4i){6, 2, 3, 7}));
}

/* f and the gradient of the first n lanes of register res. */
INLINE void store_results(const double *regs, uint32_t res, double *f, double (*g)[3],
                          size_t n, size_t ng)
{
    const double *rv = comp((double *)regs, res, 0), *rx = comp((double *)regs, res, 1),
                 *ry = comp((double *)regs, res, 2), *rz = comp((double *)regs, res, 3);
    #pragma GCC unroll 4
    for (size_t k = 0; k + 1 < ng; k++)
        v4_st(f + k * VL, v4_ld(rv + k * VL));
    for (size_t j = (ng - 1) * VL; j < n; j++)
        f[j] = rv[j];
    size_t whole = n / VL; /* groups all of whose lanes are asked */
    #pragma GCC unroll 4
    for (size_t k = 0; k < whole && k < ng; k++)
        store_group_grads(g + k * VL, v4_ld(rx + k * VL), v4_ld(ry + k * VL),
                          v4_ld(rz + k * VL));
    for (size_t j = whole * VL; j < n; j++) {
        g[j][0] = rx[j];
        g[j][1] = ry[j];
        g[j][2] = rz[j];
    }
}

/* The tape's steps over ng groups: the baseline's loop (the AVX2 clone threads it:
 * THREADED_RUN). */
INLINE void run_tape_n(const ism_tape *t, double *regs, ism_trig_cache *trig, size_t ng)
{
    for (size_t i = 0; i < t->len; i++)
        grad_step(&t->code[i], regs, trig, ng);
}

/* The groups of VL lanes that n points take (the last one padded). */
static inline size_t groups(size_t n)
{
    return (n + VL - 1) / VL;
}

/* One chunk of n points in ng groups: inputs, the tape's steps, results: the baseline's
 * (the AVX2 clone's is CHUNK_THREADED). */
INLINE void chunk_n(const ism_tape *t, double *regs, ism_trig_cache *trig,
                    const double *const src[3], double *f, double (*g)[3], size_t n, size_t ng)
{
    load_inputs(regs, src, n, ng);
    run_tape_n(t, regs, trig, ng);
    store_results(regs, t->result, f, g, n, ng);
}

#if ISM_HAVE_AVX2_CLONE
/* The rare steps (exp and the default arm's one-operand rules) out of line: grad_step's
 * switch, as the baseline runs every step. */
ISM_AVX2_CLONE __attribute__((noinline))
static void rare_step_avx2(const ism_instr *code, double *regs, ism_trig_cache *trig, size_t ng)
{
    grad_step(code, regs, trig, ng);
}

/* Every operation and how the threaded loops step it: OWN inlines grad_step_op with the
 * operation a constant (its arm alone, its own operands' addresses), RARE calls
 * rare_step_avx2. */
#define GRAD_STEPS(X)                                                                       \
    X(ISM_OP_CONST, OWN)                                                                    \
    X(ISM_OP_COPY, OWN)                                                                     \
    X(ISM_OP_ADD_RR, OWN)                                                                   \
    X(ISM_OP_ADD_RC, OWN)                                                                   \
    X(ISM_OP_SUB_RR, OWN)                                                                   \
    X(ISM_OP_SUB_CR, OWN)                                                                   \
    X(ISM_OP_MUL_RR, OWN)                                                                   \
    X(ISM_OP_MUL_RC, OWN)                                                                   \
    X(ISM_OP_DIV_RR, OWN)                                                                   \
    X(ISM_OP_DIV_RC, OWN)                                                                   \
    X(ISM_OP_DIV_CR, RARE)                                                                  \
    X(ISM_OP_MIN_RR, OWN)                                                                   \
    X(ISM_OP_MIN_RC, RARE)                                                                  \
    X(ISM_OP_MAX_RR, OWN)                                                                   \
    X(ISM_OP_MAX_RC, RARE)                                                                  \
    X(ISM_OP_NEG, OWN)                                                                      \
    X(ISM_OP_SQUARE, OWN)                                                                   \
    X(ISM_OP_POWI, OWN)                                                                     \
    X(ISM_OP_POWC, RARE)                                                                    \
    X(ISM_OP_SQRT, RARE)                                                                    \
    X(ISM_OP_SIN, OWN)                                                                      \
    X(ISM_OP_COS, OWN)                                                                      \
    X(ISM_OP_TAN, RARE)                                                                     \
    X(ISM_OP_EXP, RARE)                                                                     \
    X(ISM_OP_LOG, RARE)                                                                     \
    X(ISM_OP_ABS, OWN)
ISM_THREADED_COMPLETE(GRAD_STEPS, "GRAD_STEPS names every operation (THREADED_STEPS' table)");

#define GRAD_LABEL(OP, HOW) __label__ L_##OP;
#define GRAD_OWN(OP) grad_step_op(OP, in, regs, trig, ng)
#define GRAD_RARE(OP) rare_step_avx2(in, regs, trig, ng)
#define GRAD_BODY(OP, HOW)                                                                  \
    L_##OP:                                                                                 \
    GRAD_##HOW(OP);                                                                         \
    ISM_THREADED_NEXT(next_step, in, end, return)

/* A function NAME stepping t's tape over NG groups by direct threading (threaded.h): each
 * step's code computes only its operation's addresses and jumps to the next step's. The
 * switch in a loop (run_tape_n) paid, every step, the addresses of every arm's operands (some
 * spilled), a bound test, a table offset and the loop's test: about 43 instructions a step
 * before its arithmetic (callgrind --dump-instr, Barth's sextic at E 0.0259: 994K batched
 * steps of 1 to 4 groups). */
#define THREADED_RUN(NAME, NG)                                                              \
    ISM_AVX2_CLONE __attribute__((noinline)) static void NAME(                              \
        const ism_tape *t, double *regs, ism_trig_cache *trig, size_t ng_in)                \
    {                                                                                       \
        GRAD_STEPS(GRAD_LABEL)                                                              \
        __label__ L_BAD;                                                                    \
        ISM_THREADED_TABLE(next_step, GRAD_STEPS);                                          \
        const size_t ng = (NG);                                                             \
        (void)ng_in;                                                                        \
        if (!t->len)                                                                        \
            return;                                                                         \
        const ism_instr *in = t->code, *const end = t->code + t->len;                       \
        goto *next_step[in->op];                                                            \
        GRAD_STEPS(GRAD_BODY)                                                               \
        /* codes past the list: grad_step's default arm, as the baseline's switch (no       \
           compiled tape holds one: this arm has no test) */                                \
        GRAD_BODY(BAD, RARE)                                                                \
    }
THREADED_RUN(run_tape_1_avx2, 1)
THREADED_RUN(run_tape_2_avx2, 2)
THREADED_RUN(run_tape_3_avx2, 3)
THREADED_RUN(run_tape_4_avx2, 4)
/* More than 4 groups: ng as it comes */
THREADED_RUN(run_tape_wide_avx2, ng_in)

/* One chunk of n points in NG groups through RUN: inputs, steps, results. */
#define CHUNK_THREADED(NG, RUN)                                                             \
    do {                                                                                    \
        load_inputs(regs, src, n, NG);                                                      \
        RUN(t, regs, trig, NG);                                                             \
        store_results(regs, t->result, f, g, n, NG);                                        \
    } while (0)

/* ng a constant in each case (the polygoniser's batches: a node's or a leaf's few points),
 * so that grad_step's loops over the groups and the inputs' and results' copies unroll: the
 * per-step loop control and address arithmetic, and the copies by memcpy / rep movs in the
 * caller, were most of a short batch's cost. Klein bottle's tape, callgrind (notes/
 * klein25_mb.c mode 1), instructions a point at 1 / 4 / 6 / 8 / 10 / 16 / 32 points, as of
 * 29c1011: 1,316 / 348 / 304 / 235 / 216 / 160 / 206 (the earlier steps in that commit's and
 * its predecessors' messages). */
ISM_AVX2_CLONE
static void chunk_avx2(const ism_tape *t, double *regs, ism_trig_cache *trig,
                       const double *const src[3], double *f, double (*g)[3], size_t n)
{
    size_t ng = groups(n);
    switch (ng) {
    case 1: CHUNK_THREADED(1, run_tape_1_avx2); break;
    case 2: CHUNK_THREADED(2, run_tape_2_avx2); break;
    case 3: CHUNK_THREADED(3, run_tape_3_avx2); break;
    case 4: CHUNK_THREADED(4, run_tape_4_avx2); break;
    default: CHUNK_THREADED(ng, run_tape_wide_avx2); break;
    }
}
#endif

static void chunk_base(const ism_tape *t, double *regs, ism_trig_cache *trig,
                       const double *const src[3], double *f, double (*g)[3], size_t n)
{
    chunk_n(t, regs, trig, src, f, g, n, groups(n));
}

static void grad_chunk(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                       const double *z, double *f, double (*g)[3], size_t n)
{
    const double *const src[3] = {x, y, z};
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2())
        chunk_avx2(t, ws->gbatch, ws->trig, src, f, g, n);
    else
#endif
        chunk_base(t, ws->gbatch, ws->trig, src, f, g, n);
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
