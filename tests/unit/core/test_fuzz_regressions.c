/* test_fuzz_regressions.c — the core fuzz targets' inputs replayed in `make test`: every
 * seed (tests/fuzz/corpus/{expr,polygonise}/) and every input that once crashed a target or
 * broke one of its invariants (tests/fuzz/regressions/{expr,polygonise}/, one file per bug)
 * goes through the same checks as under libFuzzer (the target files are included here), so
 * a fixed bug stays fixed. A broken check fails the test and names the input. */
#include "tests/fuzz/replay_criterion.h"
#include "tests/fuzz/fuzz_expr.c"
#include "tests/fuzz/fuzz_polygonise.c"

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
