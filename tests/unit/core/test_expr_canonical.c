/* test_expr_canonical.c — the canonical text of a compiled function (cache keys): equal
 * for the same function written with other spacing, redundant parentheses, commuted
 * operands, lets or folded parameters; different for different functions or parameter
 * values; snprintf-like buffer handling. */
#include <criterion/criterion.h>
#include <stdlib.h>
#include <string.h>

#include "core/expr/expr.h"

static char *canonical(const char *src, const ism_param *params, size_t np, const ism_let *lets,
                       size_t nl)
{
    ism_error err;
    char msg[256];
    ism_tape *t = ism_tape_compile(src, params, np, lets, nl, NULL, &err);
    cr_assert_not_null(t, "%s: %s", src, ism_error_format(&err, msg, sizeof msg));
    size_t n = ism_tape_canonical(t, NULL, 0);
    char *buf = malloc(n + 1);
    cr_assert_not_null(buf);
    cr_assert_eq(ism_tape_canonical(t, buf, n + 1), n);
    cr_assert_eq(strlen(buf), n);
    ism_tape_free(t);
    return buf;
}

static char *plain(const char *src)
{
    return canonical(src, NULL, 0, NULL, 0);
}

typedef struct same_group {
    const char *spellings[6];
} same_group;

static const same_group SAME[] = {
    { { "x^2 + y^2 + z^2 - 1", "  x ^ 2+y^2\n+z^2 -1 ", "((x^2) + (y^2)) + (z^2) - (1)",
        "x*x + y*y + z*z - 1", "((x)^(2)) + y^2 + z^2 - 1.0", NULL } },
    { { "x*y - z", "y*x - z", "(y*x) - (z)", "-z + x*y", NULL } },
    { { "min(x, y) + max(z, x)", "min(y, x) + max(x, z)", "max(x, z) + min(y, x)", NULL } },
    { { "sin(x)*cos(y)", "cos(y)*sin(x)", "(cos((y)))*(sin(x))", NULL } },
    { { "x - 2", "x + -2", "x + (-2)", "-2 + x", NULL } },
    { { "(x + y)^2 - 3*(x + y)", "(y + x)^2 - (y + x)*3", NULL } },
    { { "x^-2", "1/x^2", "pow(x, -2)", "1/(x*x)", NULL } },
    { { "2*3*x", "6*x", "x*6", "(1 + 5)*x", NULL } },
};

Test(expr_canonical, equal_for_equivalent_spellings)
{
    for (size_t g = 0; g < sizeof SAME / sizeof SAME[0]; g++) {
        char *first = plain(SAME[g].spellings[0]);
        for (size_t i = 1; i < 6 && SAME[g].spellings[i]; i++) {
            char *other = plain(SAME[g].spellings[i]);
            cr_expect_str_eq(other, first, "'%s' vs '%s'", SAME[g].spellings[i],
                             SAME[g].spellings[0]);
            free(other);
        }
        free(first);
    }
}

Test(expr_canonical, lets_and_params_fold_into_the_same_text)
{
    ism_param r1[] = { { "r", 1.0 } };
    ism_let lets[] = { { "s", "x^2 + y^2" } };
    char *a = canonical("x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0);
    char *b = canonical("x^2 + y^2 + z^2 - r^2", r1, 1, NULL, 0);
    char *c = canonical("s + z^2 - r", r1, 1, lets, 1);
    char *d = canonical("let s = y^2 + x^2\ns + z^2 - 1", NULL, 0, NULL, 0);
    cr_expect_str_eq(b, a);
    cr_expect_str_eq(c, a);
    cr_expect_str_eq(d, a);
    free(a);
    free(b);
    free(c);
    free(d);
}

Test(expr_canonical, different_functions_differ)
{
    static const char *distinct[] = {
        "x^2 + y^2 + z^2 - 1", "x^2 + y^2 + z^2 - 0.99", "x^2 + y^2 - z^2 - 1",
        "x^2 + y^2 + z^3 - 1", "x - y", "y - x", "x / y", "y / x", "min(x, y)", "max(x, y)",
        "sin(x)", "cos(x)", "x", "y", "1", "2", "pow(x, 1.5)", "pow(x, 2.5)", "x^3", "x^4",
        "1 - x", "x - 1", "2/x", "x/2", "sqrt(x)", "abs(x)", "exp(x)", "log(x)", "tan(x)", "-x",
    };
    size_t n = sizeof distinct / sizeof distinct[0];
    char *text[sizeof distinct / sizeof distinct[0]];
    for (size_t i = 0; i < n; i++)
        text[i] = plain(distinct[i]);
    for (size_t i = 0; i < n; i++)
        for (size_t j = i + 1; j < n; j++)
            cr_expect_str_neq(text[i], text[j], "'%s' and '%s' share '%s'", distinct[i],
                              distinct[j], text[i]);
    for (size_t i = 0; i < n; i++)
        free(text[i]);
    ism_param a[] = { { "r", 1.0 } }, b[] = { { "r", 1.0000000000000002 } };
    char *ta = canonical("x - r", a, 1, NULL, 0), *tb = canonical("x - r", b, 1, NULL, 0);
    cr_expect_str_neq(ta, tb, "parameter values one ulp apart must differ");
    free(ta);
    free(tb);
}

Test(expr_canonical, snprintf_like_buffer)
{
    ism_error err;
    ism_tape *t = ism_tape_compile("x^2 + y^2 + z^2 - 1", NULL, 0, NULL, 0, NULL, &err);
    cr_assert_not_null(t);
    size_t n = ism_tape_canonical(t, NULL, 0);
    cr_assert_gt(n, 10);
    char *full = malloc(n + 1);
    ism_tape_canonical(t, full, n + 1);
    char small[8];
    memset(small, 'Q', sizeof small);
    cr_expect_eq(ism_tape_canonical(t, small, sizeof small), n);
    cr_expect_eq(small[7], '\0');
    cr_expect(strncmp(small, full, 7) == 0);
    free(full);
    ism_tape_free(t);
}
