/* tape.c — allocating, freeing and measuring compiled tapes (layout in tape.h). */
#include "core/expr/tape.h"
#include "core/util/cache_line.h"

#include <stdlib.h>

ism_tape *ism_tape_alloc(size_t cap, uint32_t nregs)
{
    if (cap > (SIZE_MAX - sizeof(ism_tape)) / sizeof(ism_instr))
        return NULL;
    /* lines of its own: a thread rewrites its shortened tapes node after node */
    ism_tape *t = ism_line_alloc(sizeof *t + (cap ? cap : 1) * sizeof(ism_instr));
    if (!t)
        return NULL;
    t->len = 0;
    t->cap = cap;
    t->nregs = nregs;
    t->result = 0;
    t->origin_len = cap;
    return t;
}

void ism_tape_free(ism_tape *t)
{
    free(t);
}

size_t ism_tape_length(const ism_tape *t)
{
    return t->len;
}

size_t ism_tape_registers(const ism_tape *t)
{
    return t->nregs;
}

/* Operations the interval jet may find non-differentiable in a box (a kink, a pole, the
 * edge of a clipped domain). */
static bool may_kink(int op)
{
    switch (op) {
    case ISM_OP_DIV_RR: case ISM_OP_SQRT: case ISM_OP_LOG: case ISM_OP_ABS:
    case ISM_OP_MIN_RR: case ISM_OP_MIN_RC: case ISM_OP_MAX_RR: case ISM_OP_MAX_RC:
        return true;
    default:
        return false;
    }
}

/* Per register: bits 0-2 the variables it depends on, bit 3 set when it may kink. */
#define REG_KINK 8u

bool ism_tape_mark_free(ism_tape *t)
{
    uint8_t *dep = malloc(t->nregs > ISM_FIRST_FREE_REG ? t->nregs : ISM_FIRST_FREE_REG);
    if (!dep)
        return false;
    for (uint32_t r = 0; r < t->nregs; r++)
        dep[r] = 0;
    dep[ISM_REG_X] = 1u;
    dep[ISM_REG_Y] = 2u;
    dep[ISM_REG_Z] = 4u;
    for (size_t i = 0; i < t->len; i++) {
        ism_instr *in = &t->code[i];
        uint8_t d = may_kink(in->op) ? REG_KINK : 0u;
        if (ism_op_has_reg_a(in->op))
            d |= dep[in->a];
        if (ism_op_has_reg_b(in->op))
            d |= dep[in->b];
        dep[in->out] = d;
        in->free_of = (uint8_t)(ISM_FREE_ALL & ~d);
        in->smooth = (d & REG_KINK) == 0;
    }
    free(dep);
    return true;
}
