/* emit.c — graph to tape: canonical depth-first order (iterative, so a deep graph cannot
 * overflow the stack), instruction selection with immediate constants, and register
 * allocation by last use. An instruction's output register is always taken before its
 * operands' registers are released, so no instruction writes a register it reads (the
 * batch evaluator relies on this to vectorise). */
#include "core/expr/emit.h"

#include <stdlib.h>
#include <string.h>

static bool is_leaf(const ism_gnode *n)
{
    return n->op == ISM_G_CONST || n->op == ISM_G_X || n->op == ISM_G_Y || n->op == ISM_G_Z;
}

/* Post-order of the non-leaf nodes reachable from root; returns their count. */
static uint32_t postorder(const ism_graph *g, uint32_t root, uint32_t *order, uint8_t *seen,
                          uint32_t *stack)
{
    uint32_t count = 0, top = 0;
    /* stack entries: node id * 2 + (1 when its operands are done) */
    stack[top++] = root * 2u;
    while (top) {
        uint32_t e = stack[--top];
        uint32_t id = e >> 1;
        const ism_gnode *n = &g->nodes[id];
        if (e & 1u) {
            order[count++] = id;
            continue;
        }
        if (seen[id] || is_leaf(n))
            continue;
        seen[id] = 1;
        stack[top++] = id * 2u + 1u;
        /* pushed in reverse so that a is visited first */
        if (n->b != ISM_G_NONE && !seen[n->b] && !is_leaf(&g->nodes[n->b]))
            stack[top++] = n->b * 2u;
        if (n->a != ISM_G_NONE && !seen[n->a] && !is_leaf(&g->nodes[n->a]))
            stack[top++] = n->a * 2u;
    }
    return count;
}

static uint32_t leaf_register(const ism_gnode *n)
{
    return (uint32_t)(n->op - ISM_G_X); /* x y z are registers 0 1 2 */
}

static uint8_t select_op(int gop, bool a_const, bool b_const)
{
    switch (gop) {
    case ISM_G_ADD: return b_const ? ISM_OP_ADD_RC : ISM_OP_ADD_RR;
    case ISM_G_SUB: return a_const ? ISM_OP_SUB_CR : ISM_OP_SUB_RR;
    case ISM_G_MUL: return b_const ? ISM_OP_MUL_RC : ISM_OP_MUL_RR;
    case ISM_G_DIV: return a_const ? ISM_OP_DIV_CR : b_const ? ISM_OP_DIV_RC : ISM_OP_DIV_RR;
    case ISM_G_MIN: return b_const ? ISM_OP_MIN_RC : ISM_OP_MIN_RR;
    case ISM_G_MAX: return b_const ? ISM_OP_MAX_RC : ISM_OP_MAX_RR;
    case ISM_G_NEG: return ISM_OP_NEG;
    case ISM_G_POWC: return ISM_OP_POWC;
    case ISM_G_SQRT: return ISM_OP_SQRT;
    case ISM_G_SIN: return ISM_OP_SIN;
    case ISM_G_COS: return ISM_OP_COS;
    case ISM_G_TAN: return ISM_OP_TAN;
    case ISM_G_EXP: return ISM_OP_EXP;
    case ISM_G_LOG: return ISM_OP_LOG;
    case ISM_G_ABS: return ISM_OP_ABS;
    default: return ISM_OP_COUNT;
    }
}

typedef struct emitter {
    const ism_graph *g;
    uint32_t *reg_of;     /* node -> register */
    uint32_t *last_use;   /* node -> index of its last consumer */
    uint32_t *free_regs;  /* stack of released registers */
    uint32_t nfree;
    uint32_t next_reg;
} emitter;

/* The register holding node id, or with *imm set when it is a constant. */
static uint32_t operand(const emitter *em, uint32_t id, bool *is_const, double *imm)
{
    const ism_gnode *n = &em->g->nodes[id];
    *is_const = n->op == ISM_G_CONST;
    if (*is_const) {
        *imm = n->value;
        return 0;
    }
    if (n->op == ISM_G_X || n->op == ISM_G_Y || n->op == ISM_G_Z)
        return leaf_register(n);
    return em->reg_of[id];
}

static void release(emitter *em, uint32_t id, uint32_t i)
{
    if (id == ISM_G_NONE || is_leaf(&em->g->nodes[id]) || em->last_use[id] != i)
        return;
    em->free_regs[em->nfree++] = em->reg_of[id];
}

static ism_instr lower(emitter *em, uint32_t id, uint32_t i)
{
    const ism_gnode *n = &em->g->nodes[id];
    ism_instr ins = { .op = 0, .out = 0, .a = 0, .b = 0, .imm = 0.0 };
    bool ca = false, cb = false;
    double ia = 0.0, ib = 0.0;
    uint32_t ra = operand(em, n->a, &ca, &ia);
    uint32_t rb = n->b != ISM_G_NONE ? operand(em, n->b, &cb, &ib) : 0;
    if (n->op == ISM_G_POWI) {
        ins.op = n->n == 2 ? ISM_OP_SQUARE : ISM_OP_POWI;
        ins.a = ra;
        ins.b = (uint32_t)n->n;
    } else {
        ins.op = select_op(n->op, ca, cb);
        ins.a = ca ? rb : ra;
        ins.b = cb || ca ? 0 : rb;
        ins.imm = ca ? ia : cb ? ib : n->value;
    }
    ins.out = em->nfree ? em->free_regs[--em->nfree] : em->next_reg++;
    em->reg_of[id] = ins.out;
    release(em, n->a, i);
    if (n->b != n->a)
        release(em, n->b, i);
    return ins;
}

ism_tape *ism_emit_tape(const ism_graph *g, uint32_t root)
{
    const ism_gnode *r = &g->nodes[root];
    if (is_leaf(r)) {
        ism_tape *t = ism_tape_alloc(1, ISM_FIRST_FREE_REG + 1);
        if (!t)
            return NULL;
        if (r->op == ISM_G_CONST) {
            t->code[0] = (ism_instr){ .op = ISM_OP_CONST, .out = ISM_FIRST_FREE_REG, .a = 0,
                                      .b = 0, .imm = r->value };
            t->len = 1;
            t->result = ISM_FIRST_FREE_REG;
        } else {
            t->result = leaf_register(r);
        }
        t->origin_len = t->len;
        return t;
    }
    size_t n = g->count;
    uint32_t *order = malloc(n * sizeof *order);
    uint32_t *stack = malloc((3 * n + 1) * sizeof *stack);
    uint8_t *seen = calloc(n, 1);
    emitter em = { .g = g, .reg_of = malloc(n * sizeof(uint32_t)),
                   .last_use = malloc(n * sizeof(uint32_t)),
                   .free_regs = malloc(n * sizeof(uint32_t)), .nfree = 0,
                   .next_reg = ISM_FIRST_FREE_REG };
    ism_tape *t = NULL;
    if (order && stack && seen && em.reg_of && em.last_use && em.free_regs) {
        uint32_t count = postorder(g, root, order, seen, stack);
        for (uint32_t i = 0; i < count; i++) {
            const ism_gnode *node = &g->nodes[order[i]];
            if (node->a != ISM_G_NONE)
                em.last_use[node->a] = i;
            if (node->b != ISM_G_NONE)
                em.last_use[node->b] = i;
        }
        t = ism_tape_alloc(count, 0);
        if (t) {
            for (uint32_t i = 0; i < count; i++)
                t->code[i] = lower(&em, order[i], i);
            t->len = count;
            t->origin_len = count;
            t->nregs = em.next_reg;
            t->result = em.reg_of[root];
            if (!ism_tape_mark_free(t)) {
                ism_tape_free(t);
                t = NULL;
            }
        }
    }
    free(order);
    free(stack);
    free(seen);
    free(em.reg_of);
    free(em.last_use);
    free(em.free_regs);
    return t;
}
