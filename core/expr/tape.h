/* tape.h — the compiled tape's layout, shared by the compiler (core/expr) and the evaluators
 * (core/eval); not part of the public API.
 *
 * A tape is a flat list of instructions in evaluation order. Registers 0, 1, 2 hold x, y, z;
 * every instruction writes one register (never one of its own operands) from at most two
 * operands, each a register or the instruction's immediate constant. Registers are reused
 * once their value is dead, so `nregs` is the peak number of live values, not the length. */
#ifndef ISM_TAPE_H
#define ISM_TAPE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include "core/expr/expr.h"

enum ism_opcode {
    ISM_OP_CONST,   /* out = imm */
    ISM_OP_COPY,    /* out = a (what a shortened min/max becomes) */
    ISM_OP_ADD_RR,  /* out = a + b */
    ISM_OP_ADD_RC,  /* out = a + imm */
    ISM_OP_SUB_RR,  /* out = a - b */
    ISM_OP_SUB_CR,  /* out = imm - a */
    ISM_OP_MUL_RR,  /* out = a * b */
    ISM_OP_MUL_RC,  /* out = a * imm */
    ISM_OP_DIV_RR,  /* out = a / b */
    ISM_OP_DIV_RC,  /* out = a / imm */
    ISM_OP_DIV_CR,  /* out = imm / a */
    ISM_OP_MIN_RR,  /* out = min(a, b) */
    ISM_OP_MIN_RC,  /* out = min(a, imm) */
    ISM_OP_MAX_RR,  /* out = max(a, b) */
    ISM_OP_MAX_RC,  /* out = max(a, imm) */
    ISM_OP_NEG,     /* out = -a */
    ISM_OP_SQUARE,  /* out = a * a */
    ISM_OP_POWI,    /* out = a ^ n, n = b >= 3 (negative powers compile to 1 / a^n) */
    ISM_OP_POWC,    /* out = max(a, 0) ^ imm, imm not an integer */
    ISM_OP_SQRT,    /* out = sqrt(max(a, 0)) */
    ISM_OP_SIN,
    ISM_OP_COS,
    ISM_OP_TAN,
    ISM_OP_EXP,
    ISM_OP_LOG,     /* out = log(max(a, 0)) (-inf at and below 0) */
    ISM_OP_ABS,
    ISM_OP_COUNT
};

typedef struct ism_instr {
    uint8_t op;
    /* Bit k (x, y, z) set: the instruction's value is proven not to depend on variable k
     * (ism_tape_mark_free computes it from the data flow once per compiled tape). 0 claims
     * nothing, so a tape built without it (or edited: shortening only ever narrows what a
     * value depends on) stays correct; derivative evaluators skip the partials it names,
     * which are exactly 0. Sits in the padding after op: the instruction stays 24 bytes. */
    uint8_t free_of;
    /* 1: no operation that may be non-differentiable in a box (min, max, abs, division by a
     * register, sqrt, log) feeds this value (ism_tape_mark_free): then its second partials
     * in a variable it does not depend on are 0 as well, even under the interval jet's
     * kink rule (which makes them the whole line otherwise). 0 claims nothing. */
    uint8_t smooth;
    uint32_t out;
    uint32_t a;
    uint32_t b;     /* second register, or the integer exponent of POWI */
    double imm;
} ism_instr;

#define ISM_REG_X 0u
#define ISM_REG_Y 1u
#define ISM_REG_Z 2u
#define ISM_FIRST_FREE_REG 3u

struct ism_tape {
    size_t len;        /* instructions in use */
    size_t cap;        /* instructions allocated */
    uint32_t nregs;    /* registers an evaluation needs (>= 3) */
    uint32_t result;   /* register holding f after the last instruction */
    size_t origin_len; /* length of the tape this one was compiled or shortened from */
    ism_instr code[];
};

/* Allocates an empty tape with room for cap instructions (NULL when out of memory). */
ism_tape *ism_tape_alloc(size_t cap, uint32_t nregs);

/* The three variables' bits of free_of. */
#define ISM_FREE_ALL 7u

/* Sets every instruction's free_of and smooth from the data flow of t (registers x, y, z
 * depend on themselves, a constant on nothing, every other value on what its operands depend
 * on; a value is smooth when its operation and its operands are). Returns false (t
 * unchanged) when out of memory. */
bool ism_tape_mark_free(ism_tape *t);

/* True for opcodes whose second operand is register b. */
static inline int ism_op_has_reg_b(int op)
{
    switch (op) {
    case ISM_OP_ADD_RR: case ISM_OP_SUB_RR: case ISM_OP_MUL_RR: case ISM_OP_DIV_RR:
    case ISM_OP_MIN_RR: case ISM_OP_MAX_RR:
        return 1;
    default:
        return 0;
    }
}

/* Is op a min or max, the kinks shortening decides (abs is a kink it keeps)? Inline: asked
 * of every instruction by the shortening (shorten.c) and the memo's key (shorten_memo.c). */
static inline bool ism_op_is_min_max(int op)
{
    return op == ISM_OP_MIN_RR || op == ISM_OP_MIN_RC || op == ISM_OP_MAX_RR ||
           op == ISM_OP_MAX_RC;
}

/* Is op a kink: min, max or abs (an ism_piece names its branch)? */
static inline bool ism_op_is_kink(int op)
{
    return ism_op_is_min_max(op) || op == ISM_OP_ABS;
}

/* f's top min/max: the last instruction when it is a register min or max writing the result
 * (the one kink whose two operands crease-aware code reads as f's branches), else NULL. */
static inline const ism_instr *ism_tape_top_minmax(const ism_tape *t)
{
    if (!t->len)
        return NULL;
    const ism_instr *top = &t->code[t->len - 1];
    if ((top->op != ISM_OP_MIN_RR && top->op != ISM_OP_MAX_RR) || top->out != t->result)
        return NULL;
    return top;
}

/* True for opcodes that read register a. */
static inline int ism_op_has_reg_a(int op)
{
    return op != ISM_OP_CONST;
}

#endif
