/* eval_interval.c — the interval evaluator: one pass over the tape with interval registers
 * (arithmetic in interval_ops.h). Optionally records, for every min/max, which operand the
 * box proves to be the result everywhere; tape shortening reads those choices. */
#include "core/eval/interval_eval.h"
#include "core/eval/avx2_clone.h"
#include "core/eval/interval_ops.h"
#include "core/eval/interval_trig.h"
#include "core/eval/threaded.h"
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

/* Every operation's interval, as an expression in A (its first operand's interval), B (its
 * second operand's), C (its constant as a number), CC (the constant as an interval), CH (where
 * a min, max or abs writes its choice) and trig (the sine memo): one list, expanded by
 * ism_interval_run's labels. */
#define INTERVAL_OPS(X)                                                                     \
    X(ISM_OP_CONST, CC)                                                                     \
    X(ISM_OP_COPY, A)                                                                       \
    X(ISM_OP_ADD_RR, iv_add(A, B))                                                          \
    X(ISM_OP_ADD_RC, iv_add_c(A, C))                                                        \
    X(ISM_OP_SUB_RR, iv_sub(A, B))                                                          \
    X(ISM_OP_SUB_CR, iv_c_sub(C, A))                                                        \
    X(ISM_OP_MUL_RR, iv_mul(A, B))                                                          \
    X(ISM_OP_MUL_RC, iv_mul_c(A, C))                                                        \
    X(ISM_OP_DIV_RR, iv_div(A, B))                                                          \
    X(ISM_OP_DIV_RC, iv_div_c(A, C))                                                        \
    X(ISM_OP_DIV_CR, iv_c_div(C, A))                                                        \
    X(ISM_OP_MIN_RR, (CH = min_choice(A, B), iv_min(A, B)))                                 \
    X(ISM_OP_MIN_RC, (CH = min_choice(A, CC), iv_min(A, CC)))                               \
    X(ISM_OP_MAX_RR, (CH = max_choice(A, B), iv_max(A, B)))                                 \
    X(ISM_OP_MAX_RC, (CH = max_choice(A, CC), iv_max(A, CC)))                               \
    X(ISM_OP_NEG, iv_neg(A))                                                                \
    X(ISM_OP_SQUARE, iv_square(A))                                                          \
    X(ISM_OP_POWI, iv_powi(A, in->b))                                                       \
    X(ISM_OP_POWC, iv_powc(A, C))                                                           \
    X(ISM_OP_SQRT, iv_sqrt(A))                                                              \
    X(ISM_OP_SIN, ism_iv_trig(ISM_OP_SIN, A, trig))                                         \
    X(ISM_OP_COS, ism_iv_trig(ISM_OP_COS, A, trig))                                         \
    X(ISM_OP_TAN, iv_tan(A))                                                                \
    X(ISM_OP_EXP, iv_exp(A))                                                                \
    X(ISM_OP_LOG, iv_log(A))                                                                \
    X(ISM_OP_ABS, (CH = abs_choice(A), iv_abs(A)))
ISM_THREADED_COMPLETE(INTERVAL_OPS, "INTERVAL_OPS names every operation (the label table)");

/* abs's choice: its operand ≥ 0 over the box (1), < 0 (2), or either (0) */
static inline uint8_t abs_choice(ism_interval a)
{
    return a.lo >= 0 ? ONLY_A : a.hi < 0 ? ONLY_B : BOTH;
}

static ism_interval sane_input(ism_interval v)
{
    if (!(v.lo <= v.hi))
        return ism_iv_whole();
    return v;
}

/* The tape by direct threading (GNU C's labels as values, as eval_double.c's run_threaded):
 * each operation's code ends in its own test for the end and its own jump to the next
 * instruction's, where a switch in a loop paid a bound test, a table offset and the loop's
 * test on every step. An operation code past the list gives the whole line. Compiled twice
 * (avx2_clone.h's ISM_AVX2_TWICE: the same operations, VEX forms in the AVX2 copy). */
#define A r[in->a]
#define B r[in->b]
#define C in->imm
#define CC ((ism_interval){ in->imm, in->imm })
#define CH (*(choices ? &choices[in - t->code] : &scratch))
#define STEP(OP, E)                                                                         \
    L_##OP:                                                                                 \
    r[in->out] = ism_iv_sane(E);                                                            \
    ISM_THREADED_NEXT(next_op, in, end, return r[t->result])
ISM_AVX2_TWICE(ism_interval, run,
               (const ism_tape *t, ism_eval_ws *ws, ism_interval x, ism_interval y,
                ism_interval z, uint8_t *choices),
               (t, ws, x, y, z, choices),
    ISM_THREADED_TABLE(next_op, INTERVAL_OPS);
    ism_interval *r = ws->iv;
    ism_trig_cache *trig = ws->trig;
    r[ISM_REG_X] = sane_input(x);
    r[ISM_REG_Y] = sane_input(y);
    r[ISM_REG_Z] = sane_input(z);
    uint8_t scratch = 0;
    const ism_instr *in = t->code, *const end = t->code + t->len;
    if (in == end)
        return r[t->result];
    goto *next_op[in->op];
    INTERVAL_OPS(STEP)
    STEP(BAD, ism_iv_whole()))
#undef STEP
#undef A
#undef B
#undef C
#undef CC
#undef CH

ism_interval ism_interval_run(const ism_tape *t, ism_eval_ws *ws, ism_interval x,
                              ism_interval y, ism_interval z, uint8_t *choices)
{
    return run(t, ws, x, y, z, choices);
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
