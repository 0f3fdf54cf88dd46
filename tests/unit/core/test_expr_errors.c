/* test_expr_errors.c — every kind of bad input gives its own error, with the exact line,
 * column and words a person reads; limits are enforced quickly (hostile inputs: 100k
 * parentheses, huge exponents, a million nodes, let chains that would explode if expanded). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/eval/eval.h"

typedef struct error_case {
    const char *source;
    int line, column;
    const char *message;
} error_case;

static const ism_param PARAMS[] = { { "r", 1.0 }, { "mu", 0.5 } };

static const error_case ERRORS[] = {
    { "sin(x) + sinn(y)", 1, 10, "unknown function 'sinn'" },
    { "x^0.5", 1, 3, "bad exponent 0.5: ^ needs an integer (for other powers use pow(a, b) or sqrt)" },
    { "x^y", 1, 3, "bad exponent: ^ needs a constant integer (for other powers use pow(a, b))" },
    { "x^1000000000", 1, 3, "exponent 1000000000 is too large (limit 64)" },
    { "y + x^-65", 1, 7, "exponent -65 is too large (limit 64)" },
    { "pow(x, 100)", 1, 8, "exponent 100 is too large (limit 64)" },
    { "foo + x", 1, 1, "unknown name 'foo'" },
    { "sin(x, y)", 1, 1, "'sin' takes 1 argument, got 2" },
    { "1 + max(x)", 1, 5, "'max' takes at least 2 arguments, got 1" },
    { "pow(x)", 1, 1, "'pow' takes 2 arguments, got 1" },
    { "abs()", 1, 1, "'abs' takes 1 argument, got 0" },
    { "(x + y", 1, 7, "expected ')' to close the '(' at line 1, col 1, found the end of the expression" },
    { "x + * y", 1, 5, "expected a number, a name or '(', found '*'" },
    { "x ** 2", 1, 3, "use ^ for powers, not **" },
    { "2x + 1", 1, 1, "malformed number '2x' (write 2*x, not 2x)" },
    { "x # y", 1, 3, "unexpected character '#'" },
    { "x + \xc3\xa9", 1, 5, "unexpected character byte 0xC3" },
    { "x\n+ y\n  + sinn(z)", 3, 5, "unknown function 'sinn'" },
    { "1e+ + x", 1, 1, "malformed number '1e+': the exponent needs digits" },
    { "x / 0", 1, 3, "division by zero" },
    { "log(0) + x", 1, 1, "log() of constants is not a finite number" },
    { "x y", 1, 3, "expected an operator before name 'y'" },
    { "x^2 + y^2 = 1", 1, 11, "unexpected '=': write the surface as one expression f, meaning f = 0 (e.g. x^2 + y^2 - 1)" },
    { "x + y)", 1, 6, "unexpected ')'" },
    { "r(x + 1)", 1, 1, "'r' is not a function (write '*' to multiply)" },
    { "sin + x", 1, 1, "'sin' is a function: write sin(...)" },
    { "", 1, 1, "the expression is empty" },
    { "  \n  ", 2, 3, "the expression is empty" },
    { "min(x,)", 1, 7, "expected a number, a name or '(', found ')'" },
    { "sin(x", 1, 6, "expected ',' or ')' in the call to sin( at col 4, found the end of the expression" },
    { "let a = x\nlet b = c + a\nb", 2, 9, "unknown name 'c'" },
    { "let x = 1\nx", 1, 5, "let 'x' would shadow the variable x" },
    { "let sin = 2\nx", 1, 5, "let 'sin' would shadow the function sin()" },
    { "let pi = 2\nx", 1, 5, "let 'pi' would shadow the constant pi" },
    { "let r = 2\nx", 1, 5, "let 'r' is already defined as a parameter" },
    { "let a = 1; let a = 2; x", 1, 16, "let 'a' is already defined as a let" },
    { "let a = 1 a", 1, 11, "expected ';' or a new line after the let, found name 'a'" },
    { "let a = y\n", 2, 1, "expected the final expression after the lets" },
    { "let = 3\nx", 1, 5, "expected a name after 'let', found '='" },
    { "let a 3\nx", 1, 7, "expected '=' after 'let NAME', found number 3" },
    { "x + let", 1, 5, "'let' can only start a line before the final expression: let NAME = EXPR" },
    { "1e999 + x", 1, 1, "number 1e999 is too large" },
};

#define NERRORS (sizeof ERRORS / sizeof ERRORS[0])

Test(expr_errors, table_of_positioned_messages)
{
    for (size_t i = 0; i < NERRORS; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile(ERRORS[i].source, PARAMS, 2, NULL, 0, NULL, &err);
        cr_expect_null(t, "'%s' compiled", ERRORS[i].source);
        if (t) {
            ism_tape_free(t);
            continue;
        }
        cr_expect_str_eq(err.message, ERRORS[i].message, "'%s'", ERRORS[i].source);
        cr_expect_eq(err.line, ERRORS[i].line, "'%s' line %d", ERRORS[i].source, err.line);
        cr_expect_eq(err.column, ERRORS[i].column, "'%s' col %d", ERRORS[i].source,
                     err.column);
        cr_expect_str_eq(err.where, "", "'%s'", ERRORS[i].source);
    }
}

Test(expr_errors, formatted_line)
{
    ism_error err;
    char buf[256];
    cr_assert_null(ism_tape_compile("sin(x) + sinn(y)", NULL, 0, NULL, 0, NULL, &err));
    cr_expect_str_eq(ism_error_format(&err, buf, sizeof buf), "col 10: unknown function 'sinn'");
    cr_assert_null(ism_tape_compile("x\n + (y", NULL, 0, NULL, 0, NULL, &err));
    cr_expect_str_eq(ism_error_format(&err, buf, sizeof buf),
                     "line 2, col 6: expected ')' to close the '(' at line 2, col 4, found the "
                     "end of the expression");
    ism_let lets[] = { { "p", "x +\n  )" } };
    cr_assert_null(ism_tape_compile("p", NULL, 0, lets, 1, NULL, &err));
    cr_expect_str_eq(ism_error_format(&err, buf, sizeof buf),
                     "let p: line 2, col 3: expected a number, a name or '(', found ')'");
    cr_assert_null(ism_tape_compile("x", (ism_param[]){ { "y", 1 } }, 1, NULL, 0, NULL, &err));
    cr_expect_str_eq(ism_error_format(&err, buf, sizeof buf),
                     "parameter 'y' would shadow the variable y");
    char tiny[8];
    ism_error_format(&err, tiny, sizeof tiny);
    cr_expect_str_eq(tiny, "paramet");
}

Test(expr_errors, error_set_is_positionless)
{
    ism_error err;
    cr_expect_not(ism_error_set(&err, "budget %d exceeded", 7));
    cr_expect_str_eq(err.message, "budget 7 exceeded");
    cr_expect_eq(err.line, 0);
    cr_expect_eq(err.column, 0);
    cr_expect_str_eq(err.where, "");
    cr_expect_not(ism_error_set(NULL, "no crash"));
}

typedef struct api_case {
    ism_param params[2];
    size_t nparams;
    ism_let lets[2];
    size_t nlets;
    const char *where;
    int line, column;
    const char *message;
} api_case;

Test(expr_errors, parameter_and_let_names)
{
    const api_case cases[] = {
        { { { "x", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'x' would shadow the variable x" },
        { { { "pi", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'pi' would shadow the constant pi" },
        { { { "e", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'e' would shadow the constant e" },
        { { { "cos", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'cos' would shadow the function cos()" },
        { { { "a", 1 }, { "a", 2 } }, 2, { { 0 } }, 0, "", 0, 0, "parameter 'a' is already defined as a parameter" },
        { { { "2a", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter name '2a' is not a valid name (letters, digits and _, not starting with a digit, at most 63)" },
        { { { "let", 1 } }, 1, { { 0 } }, 0, "", 0, 0, "parameter name 'let' is a keyword" },
        { { { "a", NAN } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'a' is not a finite number" },
        { { { "a", INFINITY } }, 1, { { 0 } }, 0, "", 0, 0, "parameter 'a' is not a finite number" },
        { { { "a", 1 } }, 1, { { "a", "x" } }, 1, "a", 0, 0, "let 'a' is already defined as a parameter" },
        { { { 0 } }, 0, { { "z", "x" } }, 1, "z", 0, 0, "let 'z' would shadow the variable z" },
        { { { 0 } }, 0, { { "p", "q + 1" }, { "q", "x" } }, 2, "p", 1, 1, "unknown name 'q' (a let can only use lets defined before it)" },
        { { { 0 } }, 0, { { "p", "x" }, { "q", "p +" } }, 2, "q", 1, 4, "expected a number, a name or '(', found the end of the expression" },
        { { { 0 } }, 0, { { "p", "" } }, 1, "p", 1, 1, "the expression is empty" },
        { { { 0 } }, 0, { { "p", "let a = 1\na" } }, 1, "p", 1, 1, "'let' can only start a line before the final expression: let NAME = EXPR" },
        { { { 0 } }, 0, { { "p", NULL } }, 1, "p", 0, 0, "the let has no expression" },
        { { { 0 } }, 0, { { NULL, "x" } }, 1, "", 0, 0, "let number 1 has no name" },
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        ism_error err;
        ism_tape *t = ism_tape_compile("x + 1", cases[i].params, cases[i].nparams,
                                       cases[i].lets, cases[i].nlets, NULL, &err);
        cr_expect_null(t, "case %zu compiled", i);
        if (t) {
            ism_tape_free(t);
            continue;
        }
        cr_expect_str_eq(err.message, cases[i].message, "case %zu", i);
        cr_expect_str_eq(err.where, cases[i].where, "case %zu", i);
        cr_expect_eq(err.line, cases[i].line, "case %zu", i);
        cr_expect_eq(err.column, cases[i].column, "case %zu", i);
    }
}

/* A source made of `reps` copies of unit between prefix and suffix. */
static char *repeat(const char *prefix, const char *unit, size_t reps, const char *suffix)
{
    size_t u = strlen(unit), p = strlen(prefix), s = strlen(suffix);
    char *buf = malloc(p + u * reps + s + 1);
    cr_assert_not_null(buf);
    memcpy(buf, prefix, p);
    for (size_t i = 0; i < reps; i++)
        memcpy(buf + p + i * u, unit, u);
    memcpy(buf + p + u * reps, suffix, s + 1);
    return buf;
}

static ism_expr_limits wide_source(size_t bytes)
{
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_source = bytes;
    return lim;
}

Test(expr_errors, default_limits_are_documented_values)
{
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    cr_expect_eq(lim.max_source, 16384);
    cr_expect_eq(lim.max_nodes, 20000);
    cr_expect_eq(lim.max_depth, 200);
    cr_expect_eq(lim.max_exponent, 64);
    cr_expect_eq(lim.max_lets, 64);
    cr_expect_eq(lim.max_params, 64);
}

Test(expr_errors, source_too_long)
{
    char *src = repeat("", "x+", 9000, "x");
    ism_error err;
    cr_expect_null(ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err));
    cr_expect_str_eq(err.message, "expression too long: more than 16384 bytes (limit)");
    cr_expect_eq(err.line, 0);
    ism_let lets[] = { { "p", src } };
    cr_expect_null(ism_tape_compile("p", NULL, 0, lets, 1, NULL, &err));
    cr_expect_str_eq(err.message, "expression too long: more than 16384 bytes (limit)");
    cr_expect_str_eq(err.where, "p");
    free(src);
}

Test(expr_errors, hundred_thousand_parentheses)
{
    char *src = repeat("", "(", 100000, "x");
    ism_expr_limits lim = wide_source(1u << 20);
    ism_error err;
    cr_expect_null(ism_tape_compile(src, NULL, 0, NULL, 0, &lim, &err));
    cr_expect_str_eq(err.message, "expression nests too deeply (more than 200 levels, the limit)");
    cr_expect_eq(err.line, 1);
    cr_expect_eq(err.column, 201); /* the 201st parenthesis */
    /* a raised depth limit is still capped far below what the stack could take */
    lim.max_depth = 1 << 30;
    cr_expect_null(ism_tape_compile(src, NULL, 0, NULL, 0, &lim, &err));
    cr_expect_str_eq(err.message, "expression nests too deeply (more than 1000 levels, the limit)");
    free(src);
    src = repeat("", "-", 5000, "x");
    cr_expect_null(ism_tape_compile(src, NULL, 0, NULL, 0, NULL, &err));
    cr_expect_str_eq(err.message, "expression nests too deeply (more than 200 levels, the limit)");
    free(src);
    /* within the limit, nesting works */
    src = repeat("", "(", 150, "x");
    char *closed = repeat(src, ")", 150, "");
    ism_tape *t = ism_tape_compile(closed, NULL, 0, NULL, 0, NULL, &err);
    cr_expect_not_null(t);
    ism_tape_free(t);
    free(closed);
    free(src);
}

Test(expr_errors, million_nodes)
{
    size_t reps = getenv("ISOMESH_TEST_QUICK") ? 200000 : 1000000;
    char *src = repeat("", "x*y+", reps, "z");
    ism_expr_limits lim = wide_source(8u << 20);
    ism_error err;
    cr_expect_null(ism_tape_compile(src, NULL, 0, NULL, 0, &lim, &err));
    cr_expect_str_eq(err.message, "expression too large: more than 20000 operations and "
                     "operands in the expression and its lets (limit)");
    cr_expect_eq(err.line, 1);
    /* with the node limit lifted too, the long chain compiles without recursion trouble:
     * x*y is shared, so the tape is one product plus one add per term */
    lim.max_nodes = 10 * reps;
    ism_tape *t = ism_tape_compile(src, NULL, 0, NULL, 0, &lim, &err);
    cr_assert_not_null(t, "%s", err.message);
    ism_eval_ws *ws = ism_eval_ws_new(t);
    cr_assert_not_null(ws);
    cr_expect_eq(ism_eval_point(t, ws, 2.0, 3.0, 1.0), 6.0 * reps + 1.0);
    cr_expect_leq(ism_tape_registers(t), 8);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    free(src);
}

Test(expr_errors, huge_exponents)
{
    ism_error err;
    const char *srcs[] = { "x^1000000000", "x^1e300", "x^-99999999999999999999", "pow(y, 1e20)",
                           "2^3^4" };
    for (size_t i = 0; i < sizeof srcs / sizeof srcs[0]; i++) {
        cr_expect_null(ism_tape_compile(srcs[i], NULL, 0, NULL, 0, NULL, &err), "%s", srcs[i]);
        cr_expect(strstr(err.message, "is too large (limit 64)") != NULL, "%s: %s", srcs[i],
                  err.message);
    }
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_exponent = 3;
    cr_expect_null(ism_tape_compile("x^4", NULL, 0, NULL, 0, &lim, &err));
    cr_expect_str_eq(err.message, "exponent 4 is too large (limit 3)");
}

Test(expr_errors, counts_of_lets_and_params)
{
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_lets = 2;
    lim.max_params = 1;
    ism_param params[] = { { "a", 1 }, { "b", 2 } };
    ism_let lets[] = { { "p", "x" }, { "q", "y" }, { "s", "z" } };
    ism_error err;
    cr_expect_null(ism_tape_compile("x", params, 2, NULL, 0, &lim, &err));
    cr_expect_str_eq(err.message, "too many parameters: 2 (limit 1)");
    cr_expect_null(ism_tape_compile("x", NULL, 0, lets, 3, &lim, &err));
    cr_expect_str_eq(err.message, "too many lets: 3 (limit 2)");
    /* lets in the source count with those of the array */
    cr_expect_null(ism_tape_compile("let t = 1\nt", NULL, 0, lets, 2, &lim, &err));
    cr_expect_str_eq(err.message, "too many lets (limit 2)");
    cr_expect_eq(err.line, 1);
    cr_expect_eq(err.column, 1);
}

/* Each let uses the previous one twice: expanded, the tree would have 2^200 nodes; shared,
 * the tape has a few instructions per let. */
Test(expr_errors, let_chain_is_shared_not_expanded)
{
    enum { N = 200 };
    static char names[N][16], sources[N][40];
    ism_let lets[N];
    for (int i = 0; i < N; i++) {
        snprintf(names[i], sizeof names[i], "a%d", i);
        if (i == 0)
            snprintf(sources[i], sizeof sources[i], "x");
        else
            snprintf(sources[i], sizeof sources[i], "a%d*y + a%d*z", i - 1, i - 1);
        lets[i] = (ism_let){ names[i], sources[i] };
    }
    ism_expr_limits lim;
    ism_expr_limits_default(&lim);
    lim.max_lets = N;
    ism_error err;
    ism_tape *t = ism_tape_compile("a199 - 1", NULL, 0, lets, N, &lim, &err);
    cr_assert_not_null(t, "%s", err.message);
    cr_expect_leq(ism_tape_length(t), 3 * N + 2, "%zu instructions", ism_tape_length(t));
    ism_eval_ws *ws = ism_eval_ws_new(t);
    /* a_i = a_{i-1} * (y + z): with y + z = 1.0 the value stays x */
    double want = 0.75;
    for (int i = 1; i < N; i++)
        want = want * 0.25 + want * 0.75;
    cr_expect_eq(ism_eval_point(t, ws, 0.75, 0.25, 0.75), want - 1.0);
    ism_eval_ws_free(ws);
    ism_tape_free(t);
    /* the default limit on lets stops the same chain with a clear message */
    cr_expect_null(ism_tape_compile("a199 - 1", NULL, 0, lets, N, NULL, &err));
    cr_expect_str_eq(err.message, "too many lets: 200 (limit 64)");
}

Test(expr_errors, null_arguments)
{
    ism_error err;
    cr_expect_null(ism_tape_compile(NULL, NULL, 0, NULL, 0, NULL, &err));
    cr_expect_str_eq(err.message, "no expression given");
    cr_expect_null(ism_tape_compile("x", NULL, 2, NULL, 0, NULL, &err));
    cr_expect_null(ism_tape_compile("x^", NULL, 0, NULL, 0, NULL, NULL)); /* err may be NULL */
}
