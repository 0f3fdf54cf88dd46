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
