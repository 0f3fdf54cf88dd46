/* expr.h — the expression engine's public face: turn a surface written by a person
 * (x y z, named parameters, `let` bindings) into a compiled tape, or into an error that
 * says where (line, column, which let) and what went wrong in words a person understands.
 *
 * Everything here is reentrant: no global mutable state. A compiled tape is immutable and
 * may be shared by any number of threads, each with its own evaluation workspace (eval.h). */
#ifndef ISM_EXPR_H
#define ISM_EXPR_H

#include <stddef.h>
#include <stdbool.h>

/* Where and why a compile failed. `where` is "" for the main expression, or the let name
 * the error is in. line and column are 1-based; 0 when the error has no position (a limit
 * on the whole request, for instance). */
typedef struct ism_error {
    int line;
    int column;
    char where[64];
    char message[192];
} ism_error;

/* Formats an error as one line, e.g. "col 14: unknown function 'sinn'" or
 * "let p: line 2, col 3: expected ')'". Returns buf. */
char *ism_error_format(const ism_error *err, char *buf, size_t n);

/* Sets err to a positionless message (printf-style). Returns false, so callers can write
 * `return ism_error_set(err, "...")`. err may be NULL. */
bool ism_error_set(ism_error *err, const char *fmt, ...)
    __attribute__((format(printf, 2, 3)));

typedef struct ism_param {
    const char *name;
    double value;
} ism_param;

typedef struct ism_let {
    const char *name;
    const char *source; /* may use x y z, parameters and earlier lets */
} ism_let;

/* Bounds that keep a hostile expression from costing more than a parse. Each breach has
 * its own error message. */
typedef struct ism_expr_limits {
    size_t max_source;   /* bytes of one expression source (default 16384) */
    size_t max_nodes;    /* syntax tree nodes over expr + all lets (default 20000) */
    int max_depth;       /* nesting depth of parentheses / operators (default 200) */
    int max_exponent;    /* |n| in x^n (default 64) */
    size_t max_lets;     /* number of let bindings (default 64) */
    size_t max_params;   /* number of parameters (default 64) */
} ism_expr_limits;

void ism_expr_limits_default(ism_expr_limits *lim);

/* An immutable compiled tape (opaque; see eval.h for evaluating it). */
typedef struct ism_tape ism_tape;

/* Parses and compiles. Parameters and constants are folded, common sub-expressions shared.
 * lim may be NULL for the defaults. Returns NULL and fills err on failure. */
ism_tape *ism_tape_compile(const char *source,
                           const ism_param *params, size_t nparams,
                           const ism_let *lets, size_t nlets,
                           const ism_expr_limits *lim, ism_error *err);

void ism_tape_free(ism_tape *t);

/* Number of instructions (operations) in the tape. */
size_t ism_tape_length(const ism_tape *t);

/* Number of registers an evaluation of this tape needs. */
size_t ism_tape_registers(const ism_tape *t);

/* Writes a canonical text form of the compiled function (after folding and sharing; the
 * same function written with different spacing or redundant parentheses gives the same
 * text). Used for cache keys. Returns the length that the full text needs (like snprintf). */
size_t ism_tape_canonical(const ism_tape *t, char *buf, size_t n);

#endif
