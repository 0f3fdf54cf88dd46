/* eval_double.c — f in double precision: one point (a plain loop over the tape), and
 * batches, where each register is an array of ISM_EVAL_BATCH lanes and each instruction is
 * one loop over the lanes. The lanes are walked in groups of 8 with a constant inner trip
 * count and restrict pointers (no instruction writes a register it reads), which is what
 * lets gcc -O2 vectorise them without run-time alias or remainder checks. Short batches
 * (ism_eval_points: the conformance pass's rim samples) loop over just their lanes and take
 * sines and cosines through the workspace's memo, as one point does. */
#include "core/eval/avx2_clone.h"
#include "core/eval/threaded.h"
#include "core/eval/top_branch.h"
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

/* Every operation's value, as an expression in A (its first operand's value), B (its second
 * operand's), C (its constant) and trig (the sine memo): one list that op_value's switch and
 * run_threaded's labels both expand, so that the two cannot differ. Each user defines A, B
 * and C before expanding it. Sines and cosines go through the memo trig (never NULL: every
 * workspace has one). */
#define POINT_OPS(X)                                                                        \
    X(ISM_OP_CONST, C)                                                                      \
    X(ISM_OP_COPY, A)                                                                       \
    X(ISM_OP_ADD_RR, A + B)                                                                 \
    X(ISM_OP_ADD_RC, A + C)                                                                 \
    X(ISM_OP_SUB_RR, A - B)                                                                 \
    X(ISM_OP_SUB_CR, C - A)                                                                 \
    X(ISM_OP_MUL_RR, A * B)                                                                 \
    X(ISM_OP_MUL_RC, A * C)                                                                 \
    X(ISM_OP_DIV_RR, A / B)                                                                 \
    X(ISM_OP_DIV_RC, A / C)                                                                 \
    X(ISM_OP_DIV_CR, C / A)                                                                 \
    X(ISM_OP_MIN_RR, ism_min(A, B))                                                         \
    X(ISM_OP_MIN_RC, ism_min(A, C))                                                         \
    X(ISM_OP_MAX_RR, ism_max(A, B))                                                         \
    X(ISM_OP_MAX_RC, ism_max(A, C))                                                         \
    X(ISM_OP_NEG, -A)                                                                       \
    X(ISM_OP_SQUARE, A * A)                                                                 \
    X(ISM_OP_POWI, ism_powi(A, in->b))                                                      \
    X(ISM_OP_POWC, ism_powc(A, C))                                                          \
    X(ISM_OP_SQRT, ism_sqrt_clip(A))                                                        \
    X(ISM_OP_SIN, trig_value(trig, A, true))                                                \
    X(ISM_OP_COS, trig_value(trig, A, false))                                               \
    X(ISM_OP_TAN, tan(A))                                                                   \
    X(ISM_OP_EXP, exp(A))                                                                   \
    X(ISM_OP_LOG, ism_log_clip(A))                                                          \
    X(ISM_OP_ABS, fabs(A))
ISM_THREADED_COMPLETE(POINT_OPS, "POINT_OPS names every operation (run_threaded's table)");

/* One instruction's value from its first operand's value a. The two-register operations read
 * their second operand, register in->b, as r[in->b * stride + lane] inside their own case
 * (a lane of ism_eval_points' registers: ISM_EVAL_BATCH and j; one point of
 * ism_eval_piece's: 1 and 0). */
static inline __attribute__((always_inline)) double op_value(const ism_instr *in, double a,
                                                          const double *r, size_t stride,
                                                          size_t lane, ism_trig_cache *trig)
{
#define A a
#define B r[(size_t)in->b * stride + lane]
#define C in->imm
#define CASE(OP, E) case OP: return E;
    switch (in->op) {
    POINT_OPS(CASE)
    default: return NAN;
    }
#undef CASE
#undef A
#undef B
#undef C
}

/* The first n instructions of code at the point whose x, y, z are in r[0..3), by direct
 * threading (GNU C's labels as values): each operation's code ends in its own test for the
 * end and its own jump to the next instruction's code, where a switch in a loop paid a bound
 * test, a table offset and the loop's test on every step. ism_eval_point on Klein bottle's
 * tape (callgrind, klein25_mb.c mode 3, with its caller's loop): 424 -> 310 instructions a
 * point. Bit for bit the switch's arithmetic (the same list, POINT_OPS). An operation code
 * past the list gives NAN, as op_value's default. */
static void run_threaded(const ism_instr *code, size_t n, double *r, ism_trig_cache *trig)
{
    ISM_THREADED_TABLE(next_op, POINT_OPS);
    if (!n)
        return;
    const ism_instr *in = code, *const end = code + n;
    goto *next_op[in->op];
#define A r[in->a]
#define B r[in->b]
#define C in->imm
#define STEP(OP, E)                                                                         \
    L_##OP:                                                                                 \
    r[in->out] = E;                                                                         \
    ISM_THREADED_NEXT(next_op, in, end, return)
    POINT_OPS(STEP)
    STEP(BAD, NAN)
#undef STEP
#undef A
#undef B
#undef C
}

static inline __attribute__((always_inline)) double point_op(const ism_instr *in,
                                                           const double *r,
                                                           ism_trig_cache *trig)
{
    return op_value(in, r[in->a], r, 1, 0, trig);
}

static unsigned natural_branch(const ism_instr *in, double a, const double *r);

/* ws->scalar with x, y, z in their registers. */
static double *point_inputs(ism_eval_ws *ws, double x, double y, double z)
{
    double *r = ws->scalar;
    r[ISM_REG_X] = x;
    r[ISM_REG_Y] = y;
    r[ISM_REG_Z] = z;
    return r;
}

double ism_eval_point(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z)
{
    if (!ism_ws_fits(ws, t))
        return NAN;
    double *r = point_inputs(ws, x, y, z);
    run_threaded(t->code, t->len, r, ws->trig);
    return r[t->result];
}

bool ism_eval_top_values(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z,
                         double val[2])
{
    const ism_instr *top = ism_tape_top_minmax(t);
    if (!top || !ism_ws_fits(ws, t))
        return false;
    double *r = point_inputs(ws, x, y, z);
    run_threaded(t->code, t->len - 1, r, ws->trig);
    val[0] = r[top->a];
    val[1] = r[top->b];
    return true;
}

/* The branch (1 or 2, as ism_piece) kink in takes with operand value a, r the registers
 * (min/max: the one ism_eval_gradient's result is, a tie the second operand; abs(0): +a). */
static unsigned natural_branch(const ism_instr *in, double a, const double *r)
{
    switch (in->op) {
    case ISM_OP_MIN_RR: return 1 + ism_minmax_gradient_operand(true, a, r[in->b]);
    case ISM_OP_MAX_RR: return 1 + ism_minmax_gradient_operand(false, a, r[in->b]);
    case ISM_OP_MIN_RC: return 1 + ism_minmax_gradient_operand(true, a, in->imm);
    case ISM_OP_MAX_RC: return 1 + ism_minmax_gradient_operand(false, a, in->imm);
    default: return a < 0.0 ? 2 : 1; /* ISM_OP_ABS */
    }
}

ism_piece ism_eval_piece(const ism_tape *t, ism_eval_ws *ws, double x, double y, double z)
{
    if (!ism_ws_fits(ws, t))
        return ISM_PIECE_NONE;
    double *r = point_inputs(ws, x, y, z);
    size_t kinks = 0;
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        if (ism_op_is_kink(in->op)) {
            ws->choice[i] = (uint8_t)natural_branch(in, r[in->a], r);
            kinks++;
        }
        r[in->out] = point_op(in, r, ws->trig);
    }
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
    double *r = point_inputs(ws, x, y, z);
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
/* sin or cos (sine: true) of a group, four lanes at a time by sincos.h's own pair: the bits
 * ism_eval_point's memo holds */
static inline __attribute__((always_inline)) void k_sincos(double *restrict o,
                                                           const double *restrict a, bool sine)
{
    _Pragma("GCC unroll 8")
    for (size_t j = 0; j < LANES; j += 4) {
        v4d s, c;
        ism_sincos4(v4_ld(a + j), &s, &c);
        v4_st(o + j, sine ? s : c);
    }
}
/* sin or cos (sine: true) of a chunk's ngroups groups, each lane k_sincos's. A chunk of one
 * group (sheet_cells.c's 27 points) takes its register's pair once for the SIN and the COS
 * steps (trig_pair.h's group pairs: the gyroid's three trig registers fit the
 * ISM_TRIG_GROUP_PAIRS kept). A longer chunk computes every group directly: its registers'
 * groups outnumber the pairs (the gyroid's three registers of two groups are six), so the
 * round robin evicts each pair before its second step, and each miss stores and copies on top
 * of the same sincos4 (revL 1: the gyroid tape at n = 96, 128, 256 cost ~5% more with pairs). */
_Static_assert(LANES == ISM_TRIG_GROUP_LANES, "a group pair holds a whole group");
static inline __attribute__((always_inline)) void k_trig(double *restrict o,
                                                         const double *restrict a, bool sine,
                                                         ism_trig_cache *trig, size_t ngroups)
{
    if (ngroups == 1) {
        const ism_trig_group_pair *p = ism_trig_groups(trig, a, LANES / 4);
        const double *v = sine ? p->s : p->c;
        _Pragma("GCC unroll 8")
        for (size_t j = 0; j < LANES; j += 4)
            v4_st(o + j, v4_ld(v + j));
        return;
    }
    for (size_t g = 0; g < ngroups; g++)
        k_sincos(o + g * LANES, a + g * LANES, sine);
}
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

static inline __attribute__((always_inline)) void batch_op(const ism_instr *in, double *regs,
                                                           ism_trig_cache *trig, size_t ngroups)
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
    case ISM_OP_SIN: k_trig(out, ra, true, trig, ngroups); break; /* sine a constant: no */
    case ISM_OP_COS: k_trig(out, ra, false, trig, ngroups); break; /* choice in the lanes */
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
ISM_AVX2_TWICE(void, run_tape,
               (const ism_tape *t, double *regs, ism_trig_cache *trig, size_t ngroups),
               (t, regs, trig, ngroups),
    for (size_t i = 0; i < t->len; i++)
        batch_op(&t->code[i], regs, trig, ngroups);
)

/* Evaluates n <= ISM_EVAL_BATCH points; lanes past n (up to a whole group) repeat the
 * last point so that they compute harmless values. */
static void eval_chunk(const ism_tape *t, double *regs, ism_trig_cache *trig, const double *x,
                       const double *y, const double *z, double *out, size_t n)
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
    run_tape(t, regs, trig, ngroups);
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
        eval_chunk(t, ws->batch, ws->trig, x + done, y + done, z + done, out + done, k);
    }
}

/* o = V over the lanes four at a time (j: the group's first lane), then S lane by lane over
 * the n % 4 left; V is S on GCC's vector extension, the same IEEE operation a lane. */
#define NARROW_LOOP(V, S)                                                                   \
    do {                                                                                    \
        size_t j = 0;                                                                       \
        for (; j + 4 <= n; j += 4)                                                          \
            v4_st(o + j, V);                                                                \
        for (; j < n; j++)                                                                  \
            o[j] = S;                                                                       \
    } while (0)

/* One instruction over n lanes of registers ISM_EVAL_BATCH apart: the frequent arithmetic
 * four lanes at a time (the last n % 4 alone), min, max, sine and cosine as lane loops (the
 * latter through the memo trig), the rest lane by lane through op_value — each lane's
 * arithmetic is run_threaded's. o, a and b restrict: no tape instruction writes a register
 * it reads (tape.h; test_eval_grad_batch's no_instruction_writes_its_operand). */
static inline __attribute__((always_inline)) void narrow_op(const ism_instr *in, double *regs,
                                                            ism_trig_cache *trig, size_t n)
{
    double *restrict o = regs + (size_t)in->out * ISM_EVAL_BATCH;
    const double *restrict a = regs + (size_t)in->a * ISM_EVAL_BATCH;
    const double *restrict b = regs + (size_t)(ism_op_has_reg_b(in->op) ? in->b : in->a)
                               * ISM_EVAL_BATCH;
    const double c = in->imm;
    switch (in->op) {
    case ISM_OP_ADD_RR: NARROW_LOOP(v4_ld(a + j) + v4_ld(b + j), a[j] + b[j]); return;
    case ISM_OP_SUB_RR: NARROW_LOOP(v4_ld(a + j) - v4_ld(b + j), a[j] - b[j]); return;
    case ISM_OP_MUL_RR: NARROW_LOOP(v4_ld(a + j) * v4_ld(b + j), a[j] * b[j]); return;
    case ISM_OP_ADD_RC: NARROW_LOOP(v4_ld(a + j) + c, a[j] + c); return;
    case ISM_OP_MUL_RC: NARROW_LOOP(v4_ld(a + j) * c, a[j] * c); return;
    case ISM_OP_SUB_CR: NARROW_LOOP(c - v4_ld(a + j), c - a[j]); return;
    case ISM_OP_SQUARE: NARROW_LOOP(v4_ld(a + j) * v4_ld(a + j), a[j] * a[j]); return;
    case ISM_OP_SIN: for (size_t j = 0; j < n; j++) o[j] = trig_value(trig, a[j], true); return;
    case ISM_OP_COS: for (size_t j = 0; j < n; j++) o[j] = trig_value(trig, a[j], false); return;
    case ISM_OP_MAX_RR: for (size_t j = 0; j < n; j++) o[j] = ism_max(a[j], b[j]); return;
    case ISM_OP_MIN_RR: for (size_t j = 0; j < n; j++) o[j] = ism_min(a[j], b[j]); return;
    default:
        for (size_t j = 0; j < n; j++)
            o[j] = op_value(in, a[j], regs, ISM_EVAL_BATCH, j, trig);
        return;
    }
}
#undef NARROW_LOOP

/* The tape over n lanes (narrow_op's), compiled for AVX2 and for the x86-64 baseline. */
ISM_AVX2_TWICE(void, narrow_run,
               (const ism_tape *t, double *regs, ism_trig_cache *trig, size_t n),
               (t, regs, trig, n),
    for (size_t i = 0; i < t->len; i++)
        narrow_op(&t->code[i], regs, trig, n);
)

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
        narrow_run(t, regs, ws->trig, k);
        memcpy(out + done, regs + (size_t)t->result * ISM_EVAL_BATCH, k * sizeof(double));
    }
}
