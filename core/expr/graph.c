/* graph.c — the hash-consed expression DAG: node creation with constant folding, a few
 * algebraic identities, and canonical operand order for commutative operations. */
#include "core/expr/graph.h"
#include "core/expr/scalar_ops.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

void ism_graph_init(ism_graph *g, size_t max_count)
{
    memset(g, 0, sizeof *g);
    g->max_count = max_count;
}

void ism_graph_free(ism_graph *g)
{
    free(g->nodes);
    free(g->table);
    memset(g, 0, sizeof *g);
}

static uint64_t mix64(uint64_t h)
{
    h ^= h >> 33;
    h *= 0xff51afd7ed558ccdULL;
    h ^= h >> 33;
    h *= 0xc4ceb9fe1a85ec53ULL;
    h ^= h >> 33;
    return h;
}

static uint64_t double_bits(double v)
{
    uint64_t u;
    memcpy(&u, &v, sizeof u);
    return u;
}

static uint64_t structural_hash(const ism_graph *g, const ism_gnode *n)
{
    uint64_t h = mix64(0x9e3779b97f4a7c15ULL ^ n->op);
    if (n->a != ISM_G_NONE)
        h = mix64(h ^ g->nodes[n->a].shash);
    if (n->b != ISM_G_NONE)
        h = mix64((h * 31u) ^ g->nodes[n->b].shash);
    h = mix64(h ^ (uint64_t)(uint32_t)n->n);
    h = mix64(h ^ double_bits(n->value));
    return h;
}

static bool same_key(const ism_gnode *x, const ism_gnode *y)
{
    return x->op == y->op && x->a == y->a && x->b == y->b && x->n == y->n
        && double_bits(x->value) == double_bits(y->value);
}

static bool grow_table(ism_graph *g)
{
    uint32_t cap = g->table_cap ? g->table_cap * 2 : 256;
    uint32_t *t = malloc((size_t)cap * sizeof *t);
    if (!t)
        return false;
    memset(t, 0xff, (size_t)cap * sizeof *t);
    for (uint32_t i = 0; i < g->count; i++) {
        uint32_t s = (uint32_t)g->nodes[i].shash & (cap - 1);
        while (t[s] != ISM_G_NONE)
            s = (s + 1) & (cap - 1);
        t[s] = i;
    }
    free(g->table);
    g->table = t;
    g->table_cap = cap;
    return true;
}

/* Returns the id of the node equal to *n, adding it when new. */
static uint32_t intern(ism_graph *g, ism_gnode n)
{
    n.shash = structural_hash(g, &n);
    if ((size_t)(g->count + 1) * 2 > g->table_cap && !grow_table(g))
        return ISM_G_NONE;
    uint32_t mask = g->table_cap - 1;
    uint32_t s = (uint32_t)n.shash & mask;
    while (g->table[s] != ISM_G_NONE) {
        const ism_gnode *o = &g->nodes[g->table[s]];
        if (o->shash == n.shash && same_key(o, &n))
            return g->table[s];
        s = (s + 1) & mask;
    }
    if (g->count >= g->max_count)
        return ISM_G_NONE;
    if (g->count == g->cap) {
        uint32_t cap = g->cap ? g->cap * 2 : 64;
        ism_gnode *nodes = realloc(g->nodes, (size_t)cap * sizeof *nodes);
        if (!nodes)
            return ISM_G_NONE;
        g->nodes = nodes;
        g->cap = cap;
    }
    g->nodes[g->count] = n;
    g->table[s] = g->count;
    return g->count++;
}

static ism_gnode blank(int op)
{
    ism_gnode n = { .op = (uint8_t)op, .a = ISM_G_NONE, .b = ISM_G_NONE, .n = 0, .value = 0.0,
                    .shash = 0 };
    return n;
}

bool ism_graph_is_const(const ism_graph *g, uint32_t id, double *v)
{
    if (g->nodes[id].op != ISM_G_CONST)
        return false;
    if (v)
        *v = g->nodes[id].value;
    return true;
}

uint32_t ism_graph_const(ism_graph *g, double v)
{
    ism_gnode n = blank(ISM_G_CONST);
    n.value = v;
    return intern(g, n);
}

uint32_t ism_graph_var(ism_graph *g, int axis)
{
    return intern(g, blank(ISM_G_X + axis));
}

static double fold_unary(int op, double a)
{
    switch (op) {
    case ISM_G_NEG: return -a;
    case ISM_G_SQRT: return ism_sqrt_clip(a);
    case ISM_G_SIN: return sin(a);
    case ISM_G_COS: return cos(a);
    case ISM_G_TAN: return tan(a);
    case ISM_G_EXP: return exp(a);
    case ISM_G_LOG: return ism_log_clip(a);
    case ISM_G_ABS: return fabs(a);
    default: return NAN;
    }
}

uint32_t ism_graph_unary(ism_graph *g, int op, uint32_t a)
{
    if (a == ISM_G_NONE)
        return a;
    double va = 0.0;
    if (ism_graph_is_const(g, a, &va))
        return ism_graph_const(g, fold_unary(op, va));
    if (op == ISM_G_NEG && g->nodes[a].op == ISM_G_NEG)
        return g->nodes[a].a;
    if (op == ISM_G_ABS && g->nodes[a].op == ISM_G_ABS)
        return a;
    ism_gnode n = blank(op);
    n.a = a;
    return intern(g, n);
}

static double fold_binary(int op, double a, double b)
{
    switch (op) {
    case ISM_G_ADD: return a + b;
    case ISM_G_SUB: return a - b;
    case ISM_G_MUL: return a * b;
    case ISM_G_DIV: return a / b;
    case ISM_G_MIN: return ism_min(a, b);
    case ISM_G_MAX: return ism_max(a, b);
    default: return NAN;
    }
}

static bool commutative(int op)
{
    return op == ISM_G_ADD || op == ISM_G_MUL || op == ISM_G_MIN || op == ISM_G_MAX;
}

/* Canonical operand order: a constant last, otherwise by structural hash (ids break the
 * ties that only a hash collision could make). */
static bool operands_out_of_order(const ism_graph *g, uint32_t a, uint32_t b)
{
    bool ca = g->nodes[a].op == ISM_G_CONST, cb = g->nodes[b].op == ISM_G_CONST;
    if (ca != cb)
        return ca;
    uint64_t ha = g->nodes[a].shash, hb = g->nodes[b].shash;
    return ha != hb ? ha > hb : a > b;
}

uint32_t ism_graph_binary(ism_graph *g, int op, uint32_t a, uint32_t b)
{
    if (a == ISM_G_NONE || b == ISM_G_NONE)
        return ISM_G_NONE;
    double va = 0.0, vb = 0.0;
    bool ca = ism_graph_is_const(g, a, &va), cb = ism_graph_is_const(g, b, &vb);
    if (ca && cb)
        return ism_graph_const(g, fold_binary(op, va, vb));
    if (op == ISM_G_SUB) {
        if (cb) /* a - c is a + (-c), exactly */
            return ism_graph_binary(g, ISM_G_ADD, a, ism_graph_const(g, -vb));
        if (ca && va == 0.0)
            return ism_graph_unary(g, ISM_G_NEG, b);
    }
    /* a + (-b) and (-b) + a are a - b; a - (-b) is a + b */
    if (op == ISM_G_ADD && g->nodes[b].op == ISM_G_NEG)
        return ism_graph_binary(g, ISM_G_SUB, a, g->nodes[b].a);
    if (op == ISM_G_ADD && g->nodes[a].op == ISM_G_NEG)
        return ism_graph_binary(g, ISM_G_SUB, b, g->nodes[a].a);
    if (op == ISM_G_SUB && g->nodes[b].op == ISM_G_NEG)
        return ism_graph_binary(g, ISM_G_ADD, a, g->nodes[b].a);
    if (commutative(op) && operands_out_of_order(g, a, b)) {
        uint32_t t = a; a = b; b = t;
        double tv = va; va = vb; vb = tv;
        bool tc = ca; ca = cb; cb = tc;
    }
    if (cb) {
        if (op == ISM_G_ADD && vb == 0.0)
            return a;
        if ((op == ISM_G_MUL || op == ISM_G_DIV) && vb == 1.0)
            return a;
        if ((op == ISM_G_MUL || op == ISM_G_DIV) && vb == -1.0)
            return ism_graph_unary(g, ISM_G_NEG, a);
        if (op == ISM_G_MUL && vb == 0.0)
            return b;
    }
    if ((op == ISM_G_MIN || op == ISM_G_MAX) && a == b)
        return a;
    if (op == ISM_G_MUL && a == b) /* x*x is x^2: one operation, and a tight interval */
        return ism_graph_powi(g, a, 2);
    ism_gnode n = blank(op);
    n.a = a;
    n.b = b;
    return intern(g, n);
}

uint32_t ism_graph_powi(ism_graph *g, uint32_t a, int n)
{
    if (a == ISM_G_NONE)
        return a;
    if (n == 0)
        return ism_graph_const(g, 1.0);
    if (n == 1)
        return a;
    if (n < 0) {
        uint32_t p = ism_graph_powi(g, a, -n);
        if (p == ISM_G_NONE)
            return p;
        uint32_t one = ism_graph_const(g, 1.0);
        return one == ISM_G_NONE ? one : ism_graph_binary(g, ISM_G_DIV, one, p);
    }
    double va = 0.0;
    if (ism_graph_is_const(g, a, &va))
        return ism_graph_const(g, ism_powi(va, (unsigned)n));
    ism_gnode node = blank(ISM_G_POWI);
    node.a = a;
    node.n = n;
    return intern(g, node);
}

uint32_t ism_graph_powc(ism_graph *g, uint32_t a, double c)
{
    if (a == ISM_G_NONE)
        return a;
    double va = 0.0;
    if (ism_graph_is_const(g, a, &va))
        return ism_graph_const(g, ism_powc(va, c));
    ism_gnode node = blank(ISM_G_POWC);
    node.a = a;
    node.value = c;
    return intern(g, node);
}
