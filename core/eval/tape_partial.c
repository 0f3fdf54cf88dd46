/* tape_partial.c — forward differentiation of a tape into a tape (tape_partial.h). Each
 * register of f has a value register and a tangent register in the new tape, both fresh
 * (nothing is reused, so no instruction writes one of its operands); a tangent known to be
 * 0 has no register (ZERO) and the rules skip its terms. Derivatives of min, max and abs use
 * the sign s = d/|d| of the switching quantity d, which is NaN (so non-finite under
 * intervals) exactly at the kink. */
#include "core/eval/tape_partial.h"
#include "core/expr/tape.h"

#include <stdbool.h>
#include <stdlib.h>

#define ZERO UINT32_MAX
/* Instructions the rules emit at most per instruction of f (min/max: 8). */
#define OPS_PER_INSTR 10

typedef struct builder {
    ism_tape *t;
    uint32_t next; /* the next fresh register */
} builder;

static uint32_t emit(builder *b, int op, uint32_t a, uint32_t rb, double imm)
{
    ism_instr *in = &b->t->code[b->t->len++];
    *in = (ism_instr){ .op = (uint8_t)op, .out = b->next, .a = a, .b = rb, .imm = imm };
    return b->next++;
}

static uint32_t add(builder *b, uint32_t x, uint32_t y)
{
    return x == ZERO ? y : y == ZERO ? x : emit(b, ISM_OP_ADD_RR, x, y, 0.0);
}

static uint32_t sub(builder *b, uint32_t x, uint32_t y)
{
    if (y == ZERO)
        return x;
    return x == ZERO ? emit(b, ISM_OP_NEG, y, 0, 0.0) : emit(b, ISM_OP_SUB_RR, x, y, 0.0);
}

static uint32_t mul(builder *b, uint32_t x, uint32_t y)
{
    return x == ZERO || y == ZERO ? ZERO : emit(b, ISM_OP_MUL_RR, x, y, 0.0);
}

static uint32_t scale(builder *b, uint32_t x, double c)
{
    return x == ZERO ? ZERO : emit(b, ISM_OP_MUL_RC, x, 0, c);
}

/* ta · u'(a) for the one-argument operations, out being u(a). */
static uint32_t unary_tangent(builder *b, const ism_instr *in, uint32_t a, uint32_t out,
                              uint32_t ta)
{
    double c = in->imm;
    switch (in->op) {
    case ISM_OP_COPY: case ISM_OP_ADD_RC: return ta;
    case ISM_OP_SUB_CR: case ISM_OP_NEG: return scale(b, ta, -1.0);
    case ISM_OP_MUL_RC: return scale(b, ta, c);
    case ISM_OP_DIV_RC: return scale(b, ta, 1.0 / c);
    case ISM_OP_DIV_CR: /* (c/a)' = −(c/a)/a */
        return scale(b, mul(b, emit(b, ISM_OP_DIV_RR, out, a, 0.0), ta), -1.0);
    case ISM_OP_MIN_RC: case ISM_OP_MAX_RC: { /* ta (1 ∓ s)/2, s = sign(a − c) */
        uint32_t d = emit(b, ISM_OP_ADD_RC, a, 0, -c);
        uint32_t s = emit(b, ISM_OP_DIV_RR, d, emit(b, ISM_OP_ABS, d, 0, 0.0), 0.0);
        uint32_t w = emit(b, ISM_OP_ADD_RC, scale(b, s, in->op == ISM_OP_MIN_RC ? -0.5 : 0.5),
                          0, 0.5);
        return mul(b, w, ta);
    }
    case ISM_OP_SQUARE: return scale(b, mul(b, a, ta), 2.0);
    case ISM_OP_POWI: {
        unsigned n = in->b;
        uint32_t p = n - 1 >= 3 ? emit(b, ISM_OP_POWI, a, n - 1, 0.0)
                                : emit(b, ISM_OP_SQUARE, a, 0, 0.0);
        return scale(b, mul(b, p, ta), (double)n);
    }
    case ISM_OP_POWC: /* max(a,0)^(c−1) is 0 or ∞ where clipped: never a wrong finite value */
        return scale(b, mul(b, emit(b, ISM_OP_POWC, a, 0, c - 1.0), ta), c);
    case ISM_OP_SQRT: return scale(b, emit(b, ISM_OP_DIV_RR, ta, out, 0.0), 0.5);
    case ISM_OP_SIN: return mul(b, emit(b, ISM_OP_COS, a, 0, 0.0), ta);
    case ISM_OP_COS: return scale(b, mul(b, emit(b, ISM_OP_SIN, a, 0, 0.0), ta), -1.0);
    case ISM_OP_TAN:
        return mul(b, emit(b, ISM_OP_ADD_RC, emit(b, ISM_OP_SQUARE, out, 0, 0.0), 0, 1.0), ta);
    case ISM_OP_EXP: return mul(b, out, ta);
    case ISM_OP_LOG: /* ta / max(a, 0): infinite where clipped */
        return emit(b, ISM_OP_DIV_RR, ta, emit(b, ISM_OP_MAX_RC, a, 0, 0.0), 0.0);
    case ISM_OP_ABS: return mul(b, emit(b, ISM_OP_DIV_RR, a, out, 0.0), ta);
    default: return ZERO;
    }
}

/* The tangent of out = op(a, b) with both operands registers. */
static uint32_t binary_tangent(builder *b, const ism_instr *in, uint32_t a, uint32_t rb,
                               uint32_t out, uint32_t ta, uint32_t tb)
{
    switch (in->op) {
    case ISM_OP_ADD_RR: return add(b, ta, tb);
    case ISM_OP_SUB_RR: return sub(b, ta, tb);
    case ISM_OP_MUL_RR: return add(b, mul(b, ta, rb), mul(b, a, tb));
    case ISM_OP_DIV_RR: { /* (ta − out·tb) / b */
        uint32_t num = sub(b, ta, mul(b, out, tb));
        return num == ZERO ? ZERO : emit(b, ISM_OP_DIV_RR, num, rb, 0.0);
    }
    default: { /* min, max: (ta + tb ∓ s (ta − tb)) / 2, s = sign(a − b) */
        uint32_t diff = sub(b, ta, tb);
        uint32_t d = emit(b, ISM_OP_SUB_RR, a, rb, 0.0);
        uint32_t s = emit(b, ISM_OP_DIV_RR, d, emit(b, ISM_OP_ABS, d, 0, 0.0), 0.0);
        uint32_t sd = mul(b, s, diff);
        uint32_t sum = in->op == ISM_OP_MIN_RR ? sub(b, add(b, ta, tb), sd)
                                               : add(b, add(b, ta, tb), sd);
        return scale(b, sum, 0.5);
    }
    }
}

ism_tape *ism_tape_partial(const ism_tape *t, int axis)
{
    if (axis < 0 || axis > 2 || t->len > (SIZE_MAX / OPS_PER_INSTR) - 4)
        return NULL;
    uint32_t *val = malloc(t->nregs * sizeof *val), *tan = malloc(t->nregs * sizeof *tan);
    builder b = { ism_tape_alloc(OPS_PER_INSTR * t->len + 4, 0), ISM_FIRST_FREE_REG };
    if (!val || !tan || !b.t) {
        free(val);
        free(tan);
        ism_tape_free(b.t);
        return NULL;
    }
    for (uint32_t r = 0; r < t->nregs; r++)
        val[r] = r < ISM_FIRST_FREE_REG ? r : ZERO, tan[r] = ZERO;
    tan[axis] = emit(&b, ISM_OP_CONST, 0, 0, 1.0);
    for (size_t i = 0; i < t->len; i++) {
        const ism_instr *in = &t->code[i];
        uint32_t a = val[in->a], ta = tan[in->a];
        bool two = ism_op_has_reg_b(in->op);
        uint32_t rb = two ? val[in->b] : in->b, tb = two ? tan[in->b] : ZERO;
        uint32_t out = in->op == ISM_OP_CONST ? emit(&b, ISM_OP_CONST, 0, 0, in->imm)
                                              : emit(&b, in->op, a, rb, in->imm);
        uint32_t to = in->op == ISM_OP_CONST ? ZERO
                      : two ? binary_tangent(&b, in, a, rb, out, ta, tb)
                            : (ta == ZERO ? ZERO : unary_tangent(&b, in, a, out, ta));
        val[in->out] = out;
        tan[in->out] = to;
    }
    uint32_t res = tan[t->result];
    if (res == ZERO)
        res = emit(&b, ISM_OP_CONST, 0, 0, 0.0);
    b.t->result = res;
    b.t->nregs = b.next;
    b.t->origin_len = b.t->len;
    (void)ism_tape_mark_free(b.t); /* out of memory: free_of stays 0, which claims nothing */
    free(val);
    free(tan);
    return b.t;
}
