/* graph.h — the expression graph the parser builds: a DAG in which every node is unique
 * (hash-consing: equal sub-expressions are one node), constants are folded on the way in,
 * and the operands of commutative operations are put in a canonical order, so that the
 * same function spelled differently becomes the same graph. Internal to core/expr. */
#ifndef ISM_GRAPH_H
#define ISM_GRAPH_H

#include <stddef.h>
#include <stdint.h>
#include <stdbool.h>

enum ism_gop {
    ISM_G_CONST, ISM_G_X, ISM_G_Y, ISM_G_Z,
    ISM_G_ADD, ISM_G_SUB, ISM_G_MUL, ISM_G_DIV, ISM_G_MIN, ISM_G_MAX,
    ISM_G_NEG, ISM_G_POWI, ISM_G_POWC, ISM_G_SQRT, ISM_G_SIN, ISM_G_COS, ISM_G_TAN,
    ISM_G_EXP, ISM_G_LOG, ISM_G_ABS
};

#define ISM_G_NONE UINT32_MAX

typedef struct ism_gnode {
    uint8_t op;
    uint32_t a, b;     /* operands (ISM_G_NONE when absent) */
    int32_t n;         /* POWI exponent */
    double value;      /* CONST value, POWC exponent */
    uint64_t shash;    /* structural hash: equal for equal structure, whatever the ids */
} ism_gnode;

typedef struct ism_graph {
    ism_gnode *nodes;
    uint32_t count, cap;
    uint32_t *table;   /* open-addressing hash table of node ids */
    uint32_t table_cap;
    size_t max_count;  /* refuse to grow past this many nodes */
} ism_graph;

void ism_graph_init(ism_graph *g, size_t max_count);
void ism_graph_free(ism_graph *g);

/* Each constructor returns the node id, or ISM_G_NONE when out of memory or past
 * max_count. Operands must be valid ids. */
uint32_t ism_graph_const(ism_graph *g, double v);
uint32_t ism_graph_var(ism_graph *g, int axis /* 0 x, 1 y, 2 z */);
uint32_t ism_graph_unary(ism_graph *g, int op, uint32_t a);
uint32_t ism_graph_binary(ism_graph *g, int op, uint32_t a, uint32_t b);
uint32_t ism_graph_powi(ism_graph *g, uint32_t a, int n);
uint32_t ism_graph_powc(ism_graph *g, uint32_t a, double c);

/* True (and *v set) when node id is a constant. */
bool ism_graph_is_const(const ism_graph *g, uint32_t id, double *v);

#endif
