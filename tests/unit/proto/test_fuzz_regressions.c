/* test_fuzz_regressions.c — the proto fuzz targets' inputs replayed in `make test`: every
 * seed (tests/fuzz/corpus/{request,frame}/) and every input that once crashed a target or
 * broke one of its invariants (tests/fuzz/regressions/{request,frame}/, one file per bug)
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
#include "tests/fuzz/fuzz_request.c"
#include "tests/fuzz/fuzz_frame.c"
#include "tests/fuzz/fuzz_replay.h"

static void replay(const char *dir, fuzz_target_fn fn, int may_be_empty)
{
    long n = fuzz_replay_dir(dir, fn, fuzz_current, sizeof fuzz_current, may_be_empty);
    cr_assert_geq(n, 0, "cannot read %s (run the tests from the repository root)", dir);
    if (!may_be_empty)
        cr_assert_gt(n, 0, "%s holds no inputs", dir);
    cr_log_info("%s: %ld inputs replayed", dir, n);
}

Test(fuzz_regressions, request_seeds)
{
    replay("tests/fuzz/corpus/request", ism_fuzz_request, 0);
}

Test(fuzz_regressions, request_regressions)
{
    replay("tests/fuzz/regressions/request", ism_fuzz_request, 1);
}

Test(fuzz_regressions, frame_seeds)
{
    replay("tests/fuzz/corpus/frame", ism_fuzz_frame, 0);
}

Test(fuzz_regressions, frame_regressions)
{
    replay("tests/fuzz/regressions/frame", ism_fuzz_frame, 1);
}
