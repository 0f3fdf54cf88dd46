/* tape.c — allocating, freeing and measuring compiled tapes (layout in tape.h). */
#include "core/expr/tape.h"

#include <stdlib.h>

ism_tape *ism_tape_alloc(size_t cap, uint32_t nregs)
{
    if (cap > (SIZE_MAX - sizeof(ism_tape)) / sizeof(ism_instr))
        return NULL;
    ism_tape *t = malloc(sizeof *t + (cap ? cap : 1) * sizeof(ism_instr));
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
