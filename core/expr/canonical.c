/* canonical.c — ism_tape_canonical: the compiled function as text, one SSA assignment per
 * instruction ("v3=mul(v1,v2)"), inputs as x y z and constants to 17 significant digits.
 * Tapes come out of the compiler in a canonical order with canonical operand order, so the
 * same function spelled differently (spacing, redundant parentheses, commuted operands)
 * gives the same text; a different function or parameter value gives a different one. */
#include "core/expr/expr.h"
#include "core/expr/tape.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct out_text {
    char *buf;
    size_t cap;
    size_t len;   /* length the full text needs so far */
} out_text;

__attribute__((format(printf, 2, 3)))
static void put(out_text *o, const char *fmt, ...)
{
    char tmp[96];
    va_list ap;
    va_start(ap, fmt);
    int k = vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    if (k < 0)
        return;
    for (int i = 0; i < k; i++, o->len++)
        if (o->len + 1 < o->cap)
            o->buf[o->len] = tmp[i];
}

static const char *const op_names[ISM_OP_COUNT] = {
    [ISM_OP_CONST] = "const", [ISM_OP_COPY] = "copy",
    [ISM_OP_ADD_RR] = "add", [ISM_OP_ADD_RC] = "add", [ISM_OP_SUB_RR] = "sub",
    [ISM_OP_SUB_CR] = "sub", [ISM_OP_MUL_RR] = "mul", [ISM_OP_MUL_RC] = "mul",
    [ISM_OP_DIV_RR] = "div", [ISM_OP_DIV_RC] = "div", [ISM_OP_DIV_CR] = "div",
    [ISM_OP_MIN_RR] = "min", [ISM_OP_MIN_RC] = "min", [ISM_OP_MAX_RR] = "max",
    [ISM_OP_MAX_RC] = "max", [ISM_OP_NEG] = "neg", [ISM_OP_SQUARE] = "pow",
    [ISM_OP_POWI] = "pow", [ISM_OP_POWC] = "powr", [ISM_OP_SQRT] = "sqrt",
    [ISM_OP_SIN] = "sin", [ISM_OP_COS] = "cos", [ISM_OP_TAN] = "tan", [ISM_OP_EXP] = "exp",
    [ISM_OP_LOG] = "log", [ISM_OP_ABS] = "abs",
};

/* Names the value in register r: an input or the instruction that last wrote it. */
static void put_reg(out_text *o, const size_t *writer, uint32_t r)
{
    if (r < ISM_FIRST_FREE_REG)
        put(o, "%c", (char)('x' + r));
    else
        put(o, "v%zu", writer[r]);
}

static void put_instr(out_text *o, const ism_instr *in, const size_t *writer)
{
    int op = in->op;
    put(o, "%s(", op_names[op]);
    switch (op) {
    case ISM_OP_CONST:
        put(o, "%.17g", in->imm);
        break;
    case ISM_OP_SUB_CR: case ISM_OP_DIV_CR:
        put(o, "%.17g,", in->imm);
        put_reg(o, writer, in->a);
        break;
    case ISM_OP_ADD_RC: case ISM_OP_MUL_RC: case ISM_OP_DIV_RC: case ISM_OP_MIN_RC:
    case ISM_OP_MAX_RC: case ISM_OP_POWC:
        put_reg(o, writer, in->a);
        put(o, ",%.17g", in->imm);
        break;
    case ISM_OP_SQUARE:
        put_reg(o, writer, in->a);
        put(o, ",2");
        break;
    case ISM_OP_POWI:
        put_reg(o, writer, in->a);
        put(o, ",%u", (unsigned)in->b);
        break;
    default:
        put_reg(o, writer, in->a);
        if (ism_op_has_reg_b(op)) {
            put(o, ",");
            put_reg(o, writer, in->b);
        }
        break;
    }
    put(o, ")");
}

size_t ism_tape_canonical(const ism_tape *t, char *buf, size_t n)
{
    out_text o = { .buf = buf, .cap = buf ? n : 0, .len = 0 };
    size_t *writer = calloc(t->nregs ? t->nregs : 1, sizeof *writer);
    if (!writer) {
        if (buf && n)
            buf[0] = '\0';
        return 0;
    }
    for (size_t i = 0; i < t->len; i++) {
        put(&o, "v%zu=", i);
        put_instr(&o, &t->code[i], writer);
        put(&o, ";");
        writer[t->code[i].out] = i;
    }
    put(&o, "f=");
    put_reg(&o, writer, t->result);
    free(writer);
    if (o.cap)
        o.buf[o.len < o.cap ? o.len : o.cap - 1] = '\0';
    return o.len;
}
