/* eval_double.c — f in double precision: one point (a plain loop over the tape), and
 * batches, where each register is an array of ISM_EVAL_BATCH lanes and each instruction is
 * one loop over the lanes. The lanes are walked in groups of 8 with a constant inner trip
 * count and restrict pointers (no instruction writes a register it reads), which is what
 * lets gcc -O2 vectorise them without run-time alias or remainder checks. Short batches
 * (ism_eval_points: the conformance pass's rim samples) loop over just their lanes and take
 * sines and cosines through the workspace's memo, as one point does. */
#include "core/eval/avx2_clone.h"
#include "core/eval/workspace.h"
#include "core/eval/trig_pair.h"
#include "core/expr/scalar_ops.h"

#include <math.h>
#include <string.h>

#define LANES 32

/* sin(u) or cos(u) (sine: true) through the workspace's memo. */
static inline __attribute__((always_inline)) double trig_value(ism_trig_cache *trig, double u,
                                                            bool sine)
{
    double sn, cs;
    ism_trig_pair(trig, u, &sn, &cs);
    return sine ? sn : cs;
}

/* One instruction's value from its first operand's value a. The two-register operations read
 * their second operand, register in->b, as r[in->b * stride + lane] inside their own case
 * (one point: stride 1, lane 0; a lane of ism_eval_points' registers: ISM_EVAL_BATCH and j),
 * so ism_eval_point pays no test of whether b exists and no load it does not use. Sines and
 * cosines go through the memo trig (never NULL: every workspace has one) inside their own
 * cases too, so the other operations pay no test for them. */
static inline __attribute__((always_inline)) double op_value(const ism_instr *in, double a,
                                                          const double *r, size_t stride,
                                                          size_t lane, ism_trig_cache *trig)
{
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_CONST: return c;
    case ISM_OP_COPY: return a;
    case ISM_OP_ADD_RR: return a + r[(size_t)in->b * stride + lane];
    case ISM_OP_ADD_RC: return a + c;
    case ISM_OP_SUB_RR: return a - r[(size_t)in->b * stride + lane];
    case ISM_OP_SUB_CR: return c - a;
    case ISM_OP_MUL_RR: return a * r[(size_t)in->b * stride + lane];
    case ISM_OP_MUL_RC: return a * c;
    case ISM_OP_DIV_RR: return a / r[(size_t)in->b * stride + lane];
    case ISM_OP_DIV_RC: return a / c;
    case ISM_OP_DIV_CR: return c / a;
    case ISM_OP_MIN_RR: return ism_min(a, r[(size_t)in->b * stride + lane]);
    case ISM_OP_MIN_RC: return ism_min(a, c);
    case ISM_OP_MAX_RR: return ism_max(a, r[(size_t)in->b * stride + lane]);
    case ISM_OP_MAX_RC: return ism_max(a, c);
    case ISM_OP_NEG: return -a;
    case ISM_OP_SQUARE: return a * a;
    case ISM_OP_POWI: return ism_powi(a, in->b);
    case ISM_OP_POWC: return ism_powc(a, c);
    case ISM_OP_SQRT: return ism_sqrt_clip(a);
    case ISM_OP_SIN: return trig_value(trig, a, true);
    case ISM_OP_COS: return trig_value(trig, a, false);
    case ISM_OP_TAN: return tan(a);
    case ISM_OP_EXP: return exp(a);
    case ISM_OP_LOG: return ism_log_clip(a);
    case ISM_OP_ABS: return fabs(a);
    default: return NAN;
    }
}

static inline __attribute__((always_inline)) double point_op(const ism_instr *in,
                                                           const double *r,
                                                           ism_trig_cache *trig)
{
    return op_value(in, r[in->a], r, 1, 0, trig);
}

static unsigned natural_branch(const ism_instr *in, double a, const double *r);

/* The first n instructions of t at (x, y, z) into ws->scalar; with record (a constant at
 * every call: the plain loop stays as it was), each kink's branch into ws->choice and the
 * number of kinks returned (0 without). */
static inline __attribute__((always_inline)) size_t run_point(const ism_tape *t,
                                                              ism_eval_ws *ws, size_t n,
                                                              double x, double y, double z,
                                                              bool record)
{
    size_t kinks = 0;
    double *r = ws->scalar;
    r[ISM_REG_X] = x;
    r[ISM_REG_Y] = y;
    r[ISM_REG_Z] = z;
    for (size_t i = 0; i < n; i++) {
        const ism_instr *in = &t->code[i];
        if (record && ism_op_is_kink(in->op)) {
            ws->choice[i] = (uint8_t)natural_branch(in, r[in->a], r);
            kinks++;
        }
        r[in->out] = point_op(in, r, ws->trig);
    }
    return kinks;
}

double ism_eval_point(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z)
{
    if (!ism_ws_fits(ws, t))
        return NAN;
    run_point(t, ws, t->len, x, y, z, false);
    return ws->scalar[t->result];
}

bool ism_eval_top_values(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double val[2])
{
    const ism_instr *top = ism_tape_top_minmax(t);
    if (!top || !ism_ws_fits(ws, t))
        return false;
    run_point(t, ws, t->len - 1, x, y, z, false);
    val[0] = ws->scalar[top->a];
    val[1] = ws->scalar[top->b];
    return true;
}

/* The branch (1 or 2, as ism_piece) kink in takes with operand value a, r the registers
 * (min/max: the one ism_eval_gradient's result is, a tie the second operand; abs(0): +a). */
static unsigned natural_branch(const ism_instr *in, double a, const double *r)
{
    switch (in->op) {
    case ISM_OP_MIN_RR: return a < r[in->b] ? 1 : 2;
    case ISM_OP_MAX_RR: return a > r[in->b] ? 1 : 2;
    case ISM_OP_MIN_RC: return a < in->imm ? 1 : 2;
    case ISM_OP_MAX_RC: return a > in->imm ? 1 : 2;
    default: return a < 0.0 ? 2 : 1; /* ISM_OP_ABS */
    }
}

ism_piece ism_eval_piece(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z)
{
    if (!ism_ws_fits(ws, t))
        return ISM_PIECE_NONE;
    size_t kinks = run_point(t, ws, t->len, x, y, z, true);
    return kinks > ISM_PIECE_KINKS ? ISM_PIECE_NONE : ism_piece_walk(t, ws, kinks, NULL);
}

/* Kink in on branch br (1 or 2, as ism_piece): what ism_kink_pass says it passes. */
static inline double forced_value(const ism_instr *in, const double *r, unsigned br)
{
    switch (ism_kink_pass(in, br)) {
    case ISM_PASS_A: return r[in->a];
    case ISM_PASS_B: return r[in->b];
    case ISM_PASS_NEG_A: return -r[in->a];
    case ISM_PASS_IMM: return in->imm;
    }
    return NAN; /* not reached: every pass is named above */
}

double ism_eval_piece_value(const ism_tape *t, ism_eval_ws *ws, ism_piece pc, double x,
                            double y, double z)
{
    if (!ism_ws_fits(ws, t))
        return NAN;
    double *r = ws->scalar;
    r[ISM_REG_X] = x;
    r[ISM_REG_Y] = y;
    r[ISM_REG_Z] = z;
    unsigned k = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        unsigned br = 0;
        if (ism_op_is_kink(in->op)) {
            br = ism_piece_branch(pc, k);
            k++;
        }
        r[in->out] = br ? forced_value(in, r, br) : point_op(in, r, ws->trig);
    }
    return r[t->result];
}

int ism_top_active_branch(const ism_tape *t, const double val[2])
{
    const ism_instr *top = ism_tape_top_minmax(t);
    if (!top)
        return -1;
    return top->op == ISM_OP_MIN_RR ? val[1] < val[0] : val[1] > val[0];
}

/* Lane kernels: one group of LANES lanes each, restrict parameters so that gcc knows the
 * output aliases no input (gcc honours restrict reliably on parameters, also once inlined). */
#define KERNEL_RR(NAME, EXPR)                                                          \
    static inline __attribute__((always_inline)) void NAME(double *restrict o, const double *restrict a,              \
                            const double *restrict b)                                  \
    {                                                                                  \
        _Pragma("GCC unroll 32")                                                        \
        for (size_t j = 0; j < LANES; j++)                                             \
            o[j] = EXPR;                                                               \
    }
#define KERNEL_R(NAME, EXPR)                                                           \
    static inline __attribute__((always_inline)) void NAME(double *restrict o, const double *restrict a)              \
    {                                                                                  \
        _Pragma("GCC unroll 32")                                                        \
        for (size_t j = 0; j < LANES; j++)                                             \
            o[j] = EXPR;                                                               \
    }
#define KERNEL_RC(NAME, EXPR)                                                          \
    static inline __attribute__((always_inline)) void NAME(double *restrict o, const double *restrict a, double c)    \
    {                                                                                  \
        _Pragma("GCC unroll 32")                                                        \
        for (size_t j = 0; j < LANES; j++)                                             \
            o[j] = EXPR;                                                               \
    }

KERNEL_RR(k_add, a[j] + b[j])
KERNEL_RR(k_sub, a[j] - b[j])
KERNEL_RR(k_mul, a[j] * b[j])
KERNEL_RR(k_div, a[j] / b[j])
KERNEL_RR(k_min, a[j] < b[j] ? a[j] : b[j])
KERNEL_RR(k_max, a[j] > b[j] ? a[j] : b[j])
KERNEL_R(k_copy, a[j])
KERNEL_RC(k_add_c, a[j] + c)
KERNEL_RC(k_sub_c, c - a[j])
KERNEL_RC(k_mul_c, a[j] * c)
KERNEL_RC(k_div_c, a[j] / c)
KERNEL_RC(k_c_div, c / a[j])
KERNEL_RC(k_min_c, a[j] < c ? a[j] : c)
KERNEL_RC(k_max_c, a[j] > c ? a[j] : c)
KERNEL_R(k_neg, -a[j])
KERNEL_R(k_square, a[j] * a[j])
KERNEL_R(k_abs, fabs(a[j]))
KERNEL_RC(k_powc, ism_powc(a[j], c))
KERNEL_R(k_sqrt, ism_sqrt_clip(a[j]))
KERNEL_R(k_sin, sin(a[j]))
KERNEL_R(k_cos, cos(a[j]))
KERNEL_R(k_tan, tan(a[j]))
KERNEL_R(k_exp, exp(a[j]))
KERNEL_R(k_log, ism_log_clip(a[j]))

/* a^n lane by lane, with the same products as ism_powi (ism_powi_lanes). */
_Static_assert(LANES <= ISM_POWI_LANES, "a group's powers in one ism_powi_lanes call");
static void powi_lanes(double *restrict out, const double *restrict ra, unsigned n,
                       size_t ngroups)
{
    for (size_t g = 0; g < ngroups; g++)
        ism_powi_lanes(out + g * LANES, ra + g * LANES, n, LANES);
}

static inline __attribute__((always_inline)) void batch_op(const ism_instr *in, double *regs, size_t ngroups)
{
    double *out = regs + (size_t)in->out * ISM_EVAL_BATCH;
    const double *ra = regs + (size_t)in->a * ISM_EVAL_BATCH;
    const double *rb = regs + (size_t)(ism_op_has_reg_b(in->op) ? in->b : in->a)
                       * ISM_EVAL_BATCH;
    const double c = in->imm;
#define RUN_RR(K) for (size_t g = 0; g < ngroups; g++) K(out + g * LANES, ra + g * LANES, rb + g * LANES)
#define RUN_R(K) for (size_t g = 0; g < ngroups; g++) K(out + g * LANES, ra + g * LANES)
#define RUN_RC(K) for (size_t g = 0; g < ngroups; g++) K(out + g * LANES, ra + g * LANES, c)
    switch (in->op) {
    case ISM_OP_CONST: for (size_t j = 0; j < ngroups * LANES; j++) out[j] = c; break;
    case ISM_OP_COPY: RUN_R(k_copy); break;
    case ISM_OP_ADD_RR: RUN_RR(k_add); break;
    case ISM_OP_ADD_RC: RUN_RC(k_add_c); break;
    case ISM_OP_SUB_RR: RUN_RR(k_sub); break;
    case ISM_OP_SUB_CR: RUN_RC(k_sub_c); break;
    case ISM_OP_MUL_RR: RUN_RR(k_mul); break;
    case ISM_OP_MUL_RC: RUN_RC(k_mul_c); break;
    case ISM_OP_DIV_RR: RUN_RR(k_div); break;
    case ISM_OP_DIV_RC: RUN_RC(k_div_c); break;
    case ISM_OP_DIV_CR: RUN_RC(k_c_div); break;
    case ISM_OP_MIN_RR: RUN_RR(k_min); break;
    case ISM_OP_MIN_RC: RUN_RC(k_min_c); break;
    case ISM_OP_MAX_RR: RUN_RR(k_max); break;
    case ISM_OP_MAX_RC: RUN_RC(k_max_c); break;
    case ISM_OP_NEG: RUN_R(k_neg); break;
    case ISM_OP_SQUARE: RUN_R(k_square); break;
    case ISM_OP_ABS: RUN_R(k_abs); break;
    case ISM_OP_POWI: powi_lanes(out, ra, in->b, ngroups); break;
    case ISM_OP_POWC: RUN_RC(k_powc); break;
    case ISM_OP_SQRT: RUN_R(k_sqrt); break;
    case ISM_OP_SIN: RUN_R(k_sin); break;
    case ISM_OP_COS: RUN_R(k_cos); break;
    case ISM_OP_TAN: RUN_R(k_tan); break;
    case ISM_OP_EXP: RUN_R(k_exp); break;
    case ISM_OP_LOG: RUN_R(k_log); break;
    default: for (size_t j = 0; j < ngroups * LANES; j++) out[j] = NAN; break;
    }
#undef RUN_RR
#undef RUN_RC
#undef RUN_R
}

/* The tape over one chunk, compiled twice: for AVX2 (4 lanes per vector) and for the
 * x86-64 baseline (SSE2, 2 lanes); chosen at run time by what the CPU supports
 * (avx2_clone.h). */
#if ISM_HAVE_AVX2_CLONE
ISM_AVX2_CLONE
static void run_tape_avx2(const ism_tape *t, double *regs, size_t ngroups)
{
    for (size_t i = 0; i < t->len; i++)
        batch_op(&t->code[i], regs, ngroups);
}
#endif

static void run_tape_base(const ism_tape *t, double *regs, size_t ngroups)
{
    for (size_t i = 0; i < t->len; i++)
        batch_op(&t->code[i], regs, ngroups);
}

static void run_tape(const ism_tape *t, double *regs, size_t ngroups)
{
#if ISM_HAVE_AVX2_CLONE
    if (ISM_RUN_AVX2()) {
        run_tape_avx2(t, regs, ngroups);
        return;
    }
#endif
    run_tape_base(t, regs, ngroups);
}

/* Evaluates n <= ISM_EVAL_BATCH points; lanes past n (up to a whole group) repeat the
 * last point so that they compute harmless values. */
static void eval_chunk(const ism_tape *t, double *regs, const double *x, const double *y,
                       const double *z, double *out, size_t n)
{
    size_t ngroups = (n + LANES - 1) / LANES;
    double *in[3] = { regs + ISM_REG_X * ISM_EVAL_BATCH, regs + ISM_REG_Y * ISM_EVAL_BATCH,
                      regs + ISM_REG_Z * ISM_EVAL_BATCH };
    const double *src[3] = { x, y, z };
    for (int k = 0; k < 3; k++) {
        memcpy(in[k], src[k], n * sizeof(double));
        for (size_t j = n; j < ngroups * LANES; j++)
            in[k][j] = src[k][n - 1];
    }
    run_tape(t, regs, ngroups);
    memcpy(out, regs + (size_t)t->result * ISM_EVAL_BATCH, n * sizeof(double));
}

void ism_eval_batch(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                    const double *z, double *out, size_t n)
{
    if (!ism_ws_fits(ws, t)) {
        for (size_t i = 0; i < n; i++)
            out[i] = NAN;
        return;
    }
    for (size_t done = 0; done < n; done += ISM_EVAL_BATCH) {
        size_t k = n - done < ISM_EVAL_BATCH ? n - done : ISM_EVAL_BATCH;
        eval_chunk(t, ws->batch, x + done, y + done, z + done, out + done, k);
    }
}

/* One instruction over n lanes of registers ISM_EVAL_BATCH apart: the frequent operations as
 * loops, the rest lane by lane through op_value (sines and cosines through the memo trig) —
 * each lane's arithmetic is run_point's. */
static void narrow_op(const ism_instr *in, double *regs, ism_trig_cache *trig, size_t n)
{
    double *restrict o = regs + (size_t)in->out * ISM_EVAL_BATCH;
    const double *restrict a = regs + (size_t)in->a * ISM_EVAL_BATCH;
    const double *restrict b = regs + (size_t)(ism_op_has_reg_b(in->op) ? in->b : in->a)
                               * ISM_EVAL_BATCH;
    const double c = in->imm;
    switch (in->op) {
    case ISM_OP_ADD_RR: for (size_t j = 0; j < n; j++) o[j] = a[j] + b[j]; return;
    case ISM_OP_SUB_RR: for (size_t j = 0; j < n; j++) o[j] = a[j] - b[j]; return;
    case ISM_OP_MUL_RR: for (size_t j = 0; j < n; j++) o[j] = a[j] * b[j]; return;
    case ISM_OP_ADD_RC: for (size_t j = 0; j < n; j++) o[j] = a[j] + c; return;
    case ISM_OP_MUL_RC: for (size_t j = 0; j < n; j++) o[j] = a[j] * c; return;
    case ISM_OP_SUB_CR: for (size_t j = 0; j < n; j++) o[j] = c - a[j]; return;
    case ISM_OP_SQUARE: for (size_t j = 0; j < n; j++) o[j] = a[j] * a[j]; return;
    default:
        for (size_t j = 0; j < n; j++)
            o[j] = op_value(in, a[j], regs, ISM_EVAL_BATCH, j, trig);
        return;
    }
}

void ism_eval_points(const ism_tape *t, ism_eval_ws *ws, const double *x, const double *y,
                     const double *z, double *out, size_t n)
{
    if (!ism_ws_fits(ws, t)) {
        for (size_t i = 0; i < n; i++)
            out[i] = NAN;
        return;
    }
    double *regs = ws->batch;
    for (size_t done = 0; done < n; done += ISM_EVAL_BATCH) {
        size_t k = n - done < ISM_EVAL_BATCH ? n - done : ISM_EVAL_BATCH;
        memcpy(regs + ISM_REG_X * ISM_EVAL_BATCH, x + done, k * sizeof(double));
        memcpy(regs + ISM_REG_Y * ISM_EVAL_BATCH, y + done, k * sizeof(double));
        memcpy(regs + ISM_REG_Z * ISM_EVAL_BATCH, z + done, k * sizeof(double));
        for (size_t i = 0; i < t->len; i++)
            narrow_op(&t->code[i], regs, ws->trig, k);
        memcpy(out + done, regs + (size_t)t->result * ISM_EVAL_BATCH, k * sizeof(double));
    }
}
