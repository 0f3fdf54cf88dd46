/* parser.c — recursive descent over the grammar
 *
 *   source  := { "let" NAME "=" expr (";" | newline) } expr
 *   expr    := term { ("+" | "-") term }
 *   term    := unary { ("*" | "/") unary }
 *   unary   := ("-" | "+") unary | power          so -x^2 is -(x^2)
 *   power   := primary [ "^" expo ]               expo folds to a constant integer
 *   expo    := ("-" | "+") expo | power           so x^-2 and 2^3^2 = 2^9 work
 *   primary := NUMBER | NAME | NAME "(" args ")" | "(" expr ")"
 *
 * building graph nodes as it goes, with a precise line:column message for every error and
 * the limits (nodes, depth, exponent, lets) enforced before they can cost anything. */
#include "core/expr/parser.h"
#include "core/expr/lexer.h"

#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <string.h>

typedef struct parser {
    ism_parse_ctx *c;
    ism_lexer lx;
    ism_token tok;
    int prev_line;     /* line of the last consumed token */
    const char *where;
    int depth;
    bool in_let;       /* parsing the value of a `let NAME = EXPR` line */
    int open_parens;   /* parentheses (groups and calls) open at this point */
} parser;

__attribute__((format(printf, 3, 4)))
static uint32_t fail(parser *p, const ism_token *at, const char *fmt, ...)
{
    ism_error *err = p->c->err;
    if (err) {
        err->line = at->line;
        err->column = at->column;
        snprintf(err->where, sizeof err->where, "%s", p->where);
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->message, sizeof err->message, fmt, ap);
        va_end(ap);
    }
    return ISM_G_NONE;
}

/* Moves to the next token; false (with the error set) when it cannot be read. */
static bool next(parser *p)
{
    p->prev_line = p->tok.end_line;
    p->tok = ism_lexer_next(&p->lx);
    if (p->tok.kind == ISM_T_BAD) {
        fail(p, &p->tok, "%s", p->lx.message);
        return false;
    }
    return true;
}

static bool count_node(parser *p, const ism_token *at)
{
    if (++p->c->nodes > p->c->lim->max_nodes) {
        fail(p, at, "expression too large: more than %zu operations and operands in the "
             "expression and its lets (limit)", p->c->lim->max_nodes);
        return false;
    }
    return true;
}

static bool enter(parser *p, const ism_token *at)
{
    int limit = p->c->lim->max_depth;
    if (limit > ISM_DEPTH_CEILING)
        limit = ISM_DEPTH_CEILING;
    if (++p->depth > limit) {
        fail(p, at, "expression nests too deeply (more than %d levels, the limit)", limit);
        return false;
    }
    return true;
}

/* Turns a graph failure into an error and a folded non-finite constant into a message. */
static uint32_t checked(parser *p, const ism_token *at, uint32_t id, const char *what)
{
    if (id == ISM_G_NONE)
        return fail(p, at, "out of memory building the expression");
    double v;
    if (ism_graph_is_const(p->c->graph, id, &v) && !isfinite(v))
        return fail(p, at, "%s of constants is not a finite number", what);
    return id;
}

static uint32_t parse_expr(parser *p);
static uint32_t parse_power(parser *p);

static uint32_t build_power(parser *p, uint32_t base, uint32_t expo, const ism_token *at)
{
    double v;
    if (!ism_graph_is_const(p->c->graph, expo, &v))
        return fail(p, at, "bad exponent: ^ needs a constant integer (for other powers "
                    "use pow(a, b))");
    if (v != floor(v))
        return fail(p, at, "bad exponent %g: ^ needs an integer (for other powers use "
                    "pow(a, b) or sqrt)", v);
    if (fabs(v) > p->c->lim->max_exponent)
        return fail(p, at, "exponent %.15g is too large (limit %d)", v,
                    p->c->lim->max_exponent);
    return checked(p, at, ism_graph_powi(p->c->graph, base, (int)v), "this power");
}

static uint32_t parse_exponent(parser *p)
{
    ism_token at = p->tok;
    if (at.kind == ISM_T_MINUS || at.kind == ISM_T_PLUS) {
        if (!next(p) || !enter(p, &at))
            return ISM_G_NONE;
        uint32_t e = parse_exponent(p);
        p->depth--;
        if (e == ISM_G_NONE || !count_node(p, &at))
            return ISM_G_NONE;
        if (at.kind == ISM_T_PLUS)
            return e;
        return checked(p, &at, ism_graph_unary(p->c->graph, ISM_G_NEG, e), "negation");
    }
    return parse_power(p);
}

static bool expect(parser *p, int kind, const char *what, const ism_token *opened)
{
    if (p->tok.kind == kind)
        return next(p);
    char found[80];
    ism_token_describe(&p->tok, found, sizeof found);
    if (opened)
        fail(p, &p->tok, "expected %s to close the '(' at line %d, col %d, found %s", what,
             opened->line, opened->column, found);
    else
        fail(p, &p->tok, "expected %s, found %s", what, found);
    return false;
}

static uint32_t unary_call(parser *p, int f, uint32_t a, const ism_token *at)
{
    static const int gop[] = { [ISM_F_SQRT] = ISM_G_SQRT, [ISM_F_SIN] = ISM_G_SIN,
                               [ISM_F_COS] = ISM_G_COS, [ISM_F_TAN] = ISM_G_TAN,
                               [ISM_F_EXP] = ISM_G_EXP, [ISM_F_LOG] = ISM_G_LOG,
                               [ISM_F_ABS] = ISM_G_ABS };
    char what[32];
    snprintf(what, sizeof what, "%s()", ism_func_get(f)->name);
    return checked(p, at, ism_graph_unary(p->c->graph, gop[f], a), what);
}

/* pow(a, b): integer constant b as a^b, other constant b as a real power of max(a, 0),
 * variable b as exp(b * log(a)). */
static uint32_t pow_call(parser *p, uint32_t a, uint32_t b, const ism_token *at,
                         const ism_token *b_at)
{
    ism_graph *g = p->c->graph;
    double v;
    if (ism_graph_is_const(g, b, &v)) {
        if (v == floor(v))
            return build_power(p, a, b, b_at);
        return checked(p, at, ism_graph_powc(g, a, v), "pow()");
    }
    uint32_t l = ism_graph_unary(g, ISM_G_LOG, a);
    uint32_t m = ism_graph_binary(g, ISM_G_MUL, b, l);
    return checked(p, at, ism_graph_unary(g, ISM_G_EXP, m), "pow()");
}

static uint32_t parse_call(parser *p, const ism_token *name)
{
    int f = ism_func_lookup(name->text, name->len);
    if (f < 0) {
        double v;
        if (ism_var_lookup(name->text, name->len) >= 0 || ism_const_lookup(name->text, name->len, &v)
            || ism_names_find(p->c->names, name->text, name->len))
            return fail(p, name, "'%.*s' is not a function (write '*' to multiply)",
                        (int)name->len, name->text);
        return fail(p, name, "unknown function '%.*s'", (int)name->len, name->text);
    }
    const ism_func_info *info = ism_func_get(f);
    ism_token open = p->tok;
    if (!enter(p, &open) || !next(p) || !count_node(p, name))
        return ISM_G_NONE;
    p->open_parens++;
    uint32_t first = ISM_G_NONE, acc = ISM_G_NONE;
    ism_token second_at = p->tok;
    int nargs = 0;
    if (p->tok.kind != ISM_T_RPAREN) {
        for (;;) {
            ism_token arg_at = p->tok;
            uint32_t a = parse_expr(p);
            if (a == ISM_G_NONE)
                return a;
            nargs++;
            if (nargs == 1) {
                first = acc = a;
            } else if (f == ISM_F_MIN || f == ISM_F_MAX) {
                acc = checked(p, name, ism_graph_binary(p->c->graph, f == ISM_F_MIN ? ISM_G_MIN
                                                        : ISM_G_MAX, acc, a), info->name);
                if (acc == ISM_G_NONE)
                    return acc;
            } else if (nargs == 2) {
                acc = a;
                second_at = arg_at;
            }
            if (p->tok.kind != ISM_T_COMMA)
                break;
            if (!next(p))
                return ISM_G_NONE;
        }
    }
    p->depth--;
    p->open_parens--;
    if (p->tok.kind != ISM_T_RPAREN) {
        char found[80];
        ism_token_describe(&p->tok, found, sizeof found);
        return fail(p, &p->tok, "expected ',' or ')' in the call to %s( at col %d, found %s",
                    info->name, open.column, found);
    }
    if (!next(p))
        return ISM_G_NONE;
    if (nargs < info->min_args || (info->max_args >= 0 && nargs > info->max_args)) {
        if (info->max_args < 0)
            return fail(p, name, "'%s' takes at least %d arguments, got %d", info->name,
                        info->min_args, nargs);
        return fail(p, name, "'%s' takes %d argument%s, got %d", info->name, info->min_args,
                    info->min_args == 1 ? "" : "s", nargs);
    }
    if (f == ISM_F_MIN || f == ISM_F_MAX)
        return acc;
    if (f == ISM_F_POW)
        return pow_call(p, first, acc, name, &second_at);
    return unary_call(p, f, first, name);
}

static bool defined_later(const parser *p, const ism_token *name)
{
    for (size_t i = 0; i < p->c->nall_lets; i++) {
        const char *n = p->c->all_lets[i].name;
        if (n && strlen(n) == name->len && memcmp(n, name->text, name->len) == 0)
            return true;
    }
    return false;
}

static uint32_t parse_name(parser *p)
{
    ism_token name = p->tok;
    if (!next(p))
        return ISM_G_NONE;
    /* NAME ( is a call, except that a let's value ends at the end of its line: a '(' that
     * starts the next line begins the next statement (`let p = w - x` then `(p + 1)^2`). */
    bool next_statement = p->in_let && p->open_parens == 0 && p->tok.line > name.end_line;
    if (p->tok.kind == ISM_T_LPAREN && !next_statement)
        return parse_call(p, &name);
    if (!count_node(p, &name))
        return ISM_G_NONE;
    int axis = ism_var_lookup(name.text, name.len);
    if (axis >= 0)
        return checked(p, &name, ism_graph_var(p->c->graph, axis), "variable");
    double v;
    if (ism_const_lookup(name.text, name.len, &v))
        return checked(p, &name, ism_graph_const(p->c->graph, v), "constant");
    const ism_name *bound = ism_names_find(p->c->names, name.text, name.len);
    if (bound)
        return bound->node;
    if (ism_func_lookup(name.text, name.len) >= 0)
        return fail(p, &name, "'%.*s' is a function: write %.*s(...)", (int)name.len,
                    name.text, (int)name.len, name.text);
    if (name.len == 3 && memcmp(name.text, "let", 3) == 0)
        return fail(p, &name, "'let' can only start a line before the final expression: "
                    "let NAME = EXPR");
    if (defined_later(p, &name))
        return fail(p, &name, "unknown name '%.*s' (a let can only use lets defined before "
                    "it)", (int)name.len, name.text);
    return fail(p, &name, "unknown name '%.*s'", (int)name.len, name.text);
}

static uint32_t parse_primary(parser *p)
{
    ism_token at = p->tok;
    switch (at.kind) {
    case ISM_T_NUM:
        if (!next(p) || !count_node(p, &at))
            return ISM_G_NONE;
        return checked(p, &at, ism_graph_const(p->c->graph, at.number), "number");
    case ISM_T_NAME:
        return parse_name(p);
    case ISM_T_LPAREN: {
        if (!enter(p, &at) || !next(p))
            return ISM_G_NONE;
        p->open_parens++;
        uint32_t e = parse_expr(p);
        p->open_parens--;
        p->depth--;
        if (e == ISM_G_NONE || !expect(p, ISM_T_RPAREN, "')'", &at))
            return ISM_G_NONE;
        return e;
    }
    default: {
        char found[80];
        ism_token_describe(&at, found, sizeof found);
        return fail(p, &at, "expected a number, a name or '(', found %s", found);
    }
    }
}

static uint32_t parse_power(parser *p)
{
    uint32_t base = parse_primary(p);
    if (base == ISM_G_NONE || p->tok.kind != ISM_T_CARET)
        return base;
    ism_token caret = p->tok;
    if (!next(p) || !enter(p, &caret))
        return ISM_G_NONE;
    ism_token expo_at = p->tok;
    uint32_t expo = parse_exponent(p);
    p->depth--;
    if (expo == ISM_G_NONE || !count_node(p, &caret))
        return ISM_G_NONE;
    return build_power(p, base, expo, &expo_at);
}

static uint32_t parse_unary(parser *p)
{
    ism_token at = p->tok;
    if (at.kind != ISM_T_MINUS && at.kind != ISM_T_PLUS)
        return parse_power(p);
    if (!next(p) || !enter(p, &at))
        return ISM_G_NONE;
    uint32_t u = parse_unary(p);
    p->depth--;
    if (u == ISM_G_NONE || !count_node(p, &at))
        return ISM_G_NONE;
    if (at.kind == ISM_T_PLUS)
        return u;
    return checked(p, &at, ism_graph_unary(p->c->graph, ISM_G_NEG, u), "negation");
}

static uint32_t parse_term(parser *p)
{
    uint32_t l = parse_unary(p);
    while (l != ISM_G_NONE && (p->tok.kind == ISM_T_STAR || p->tok.kind == ISM_T_SLASH)) {
        ism_token op = p->tok;
        if (!next(p))
            return ISM_G_NONE;
        if (op.kind == ISM_T_STAR && p->tok.kind == ISM_T_STAR)
            return fail(p, &op, "use ^ for powers, not **");
        uint32_t r = parse_unary(p);
        if (r == ISM_G_NONE || !count_node(p, &op))
            return ISM_G_NONE;
        double v;
        if (op.kind == ISM_T_SLASH && ism_graph_is_const(p->c->graph, r, &v) && v == 0.0)
            return fail(p, &op, "division by zero");
        l = checked(p, &op, ism_graph_binary(p->c->graph, op.kind == ISM_T_STAR ? ISM_G_MUL
                                             : ISM_G_DIV, l, r),
                    op.kind == ISM_T_STAR ? "product" : "quotient");
    }
    return l;
}

static uint32_t parse_expr(parser *p)
{
    uint32_t l = parse_term(p);
    while (l != ISM_G_NONE && (p->tok.kind == ISM_T_PLUS || p->tok.kind == ISM_T_MINUS)) {
        ism_token op = p->tok;
        if (!next(p))
            return ISM_G_NONE;
        uint32_t r = parse_term(p);
        if (r == ISM_G_NONE || !count_node(p, &op))
            return ISM_G_NONE;
        l = checked(p, &op, ism_graph_binary(p->c->graph, op.kind == ISM_T_PLUS ? ISM_G_ADD
                                             : ISM_G_SUB, l, r),
                    op.kind == ISM_T_PLUS ? "sum" : "difference");
    }
    return l;
}

static bool is_let_keyword(const ism_token *t)
{
    return t->kind == ISM_T_NAME && t->len == 3 && memcmp(t->text, "let", 3) == 0;
}

/* One `let NAME = EXPR` statement with its separator. */
static bool parse_let_statement(parser *p)
{
    ism_token let_at = p->tok;
    if (!next(p))
        return false;
    ism_token name = p->tok;
    if (name.kind != ISM_T_NAME) {
        char found[80];
        ism_token_describe(&name, found, sizeof found);
        fail(p, &name, "expected a name after 'let', found %s", found);
        return false;
    }
    char msg[160];
    if (!ism_names_check_new(p->c->names, name.text, name.len, "let", msg, sizeof msg)) {
        fail(p, &name, "%s", msg);
        return false;
    }
    if (++p->c->lets > p->c->lim->max_lets) {
        fail(p, &let_at, "too many lets (limit %zu)", p->c->lim->max_lets);
        return false;
    }
    if (!next(p) || !expect(p, ISM_T_ASSIGN, "'=' after 'let NAME'", NULL))
        return false;
    p->in_let = true;
    uint32_t value = parse_expr(p);
    p->in_let = false;
    if (value == ISM_G_NONE)
        return false;
    if (!ism_names_add(p->c->names, name.text, name.len, ISM_N_LET, value)) {
        fail(p, &name, "out of memory");
        return false;
    }
    if (p->tok.kind == ISM_T_SEMI)
        return next(p);
    if (p->tok.kind == ISM_T_END || p->tok.line > p->prev_line)
        return true;
    char found[80];
    ism_token_describe(&p->tok, found, sizeof found);
    fail(p, &p->tok, "expected ';' or a new line after the let, found %s", found);
    return false;
}

static uint32_t trailing_garbage(parser *p)
{
    char found[80];
    ism_token_describe(&p->tok, found, sizeof found);
    switch (p->tok.kind) {
    case ISM_T_NUM: case ISM_T_NAME: case ISM_T_LPAREN:
        return fail(p, &p->tok, "expected an operator before %s", found);
    case ISM_T_ASSIGN:
        return fail(p, &p->tok, "unexpected '=': write the surface as one expression f, "
                    "meaning f = 0 (e.g. x^2 + y^2 - 1)");
    default:
        return fail(p, &p->tok, "unexpected %s", found);
    }
}

uint32_t ism_parse_source(ism_parse_ctx *c, const char *src, size_t len, const char *where,
                          bool allow_let_statements)
{
    parser p = { .c = c, .where = where, .depth = 0, .prev_line = 1 };
    ism_lexer_init(&p.lx, src, len, c->c_locale);
    if (!next(&p))
        return ISM_G_NONE;
    if (p.tok.kind == ISM_T_END)
        return fail(&p, &p.tok, "the expression is empty");
    while (allow_let_statements && is_let_keyword(&p.tok)) {
        if (!parse_let_statement(&p))
            return ISM_G_NONE;
        if (p.tok.kind == ISM_T_END)
            return fail(&p, &p.tok, "expected the final expression after the lets");
    }
    uint32_t value = parse_expr(&p);
    if (value == ISM_G_NONE)
        return value;
    if (p.tok.kind != ISM_T_END)
        return trailing_garbage(&p);
    return value;
}
