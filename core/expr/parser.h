/* parser.h — the recursive-descent parser: reads one source (the main expression with its
 * optional leading `let NAME = EXPR` statements, or one let's body) straight into the
 * hash-consed graph, so a let used many times is one shared sub-graph, never a copy.
 * Internal to core/expr. */
#ifndef ISM_PARSER_H
#define ISM_PARSER_H

#include <locale.h>
#include "core/expr/expr.h"
#include "core/expr/graph.h"
#include "core/expr/names.h"

/* Hard ceiling on the nesting depth whatever the limits say: parsing recurses about five
 * C frames per level, and this keeps that well inside any thread's stack. */
#define ISM_DEPTH_CEILING 1000

typedef struct ism_parse_ctx {
    ism_graph *graph;
    ism_names *names;
    const ism_expr_limits *lim;
    size_t nodes;             /* syntax-tree nodes read so far, over all sources */
    size_t lets;              /* lets bound so far */
    const ism_let *all_lets;  /* the caller's lets, for "defined later" hints */
    size_t nall_lets;
    locale_t c_locale;
    ism_error *err;
} ism_parse_ctx;

/* Parses src (len bytes). `where` names the let being parsed ("" for the main expression);
 * allow_let_statements accepts leading `let` lines (main expression only). Returns the
 * graph node of the value, or ISM_G_NONE with c->err filled. */
uint32_t ism_parse_source(ism_parse_ctx *c, const char *src, size_t len, const char *where,
                          bool allow_let_statements);

#endif
