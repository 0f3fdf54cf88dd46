/* test_fuzz_regressions.c — the core fuzz targets' inputs replayed in `make test`: every
 * seed (tests/fuzz/corpus/{expr,polygonise}/) and every input that once crashed a target or
 * broke one of its invariants (tests/fuzz/regressions/{expr,polygonise}/, one file per bug)
 * goes through the same checks as under libFuzzer (the target files are included here), so
 * a fixed bug stays fixed. A broken check fails the test and names the input. */
#include <criterion/criterion.h>
#include <stdarg.h>
#include <stdio.h>

static char fuzz_current[1024];

__attribute__((format(printf, 1, 2)))
static void fuzz_failed(const char *fmt, ...)
{
    char msg[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    cr_assert_fail("%s: %s", fuzz_current, msg);
}

#define ISM_FUZZ_FAIL(...) fuzz_failed(__VA_ARGS__)
#define ISM_FUZZ_NO_ENTRY
#include "tests/fuzz/fuzz_expr.c"
#include "tests/fuzz/fuzz_polygonise.c"
#include "tests/fuzz/fuzz_replay.h"

static void replay(const char *dir, fuzz_target_fn fn, int may_be_empty)
{
    long n = fuzz_replay_dir(dir, fn, fuzz_current, sizeof fuzz_current, may_be_empty);
    cr_assert_geq(n, 0, "cannot read %s (run the tests from the repository root)", dir);
    if (!may_be_empty)
        cr_assert_gt(n, 0, "%s holds no inputs", dir);
    cr_log_info("%s: %ld inputs replayed", dir, n);
}

Test(fuzz_regressions, expr_seeds)
{
    replay("tests/fuzz/corpus/expr", ism_fuzz_expr, 0);
}

Test(fuzz_regressions, expr_regressions)
{
    replay("tests/fuzz/regressions/expr", ism_fuzz_expr, 1);
}

Test(fuzz_regressions, polygonise_seeds)
{
    replay("tests/fuzz/corpus/polygonise", ism_fuzz_polygonise, 0);
}

Test(fuzz_regressions, polygonise_regressions)
{
    replay("tests/fuzz/regressions/polygonise", ism_fuzz_polygonise, 1);
}
