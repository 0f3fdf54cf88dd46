/* replay_criterion.h — what both regression suites (tests/unit/{core,proto}/
 * test_fuzz_regressions.c) need to run fuzz targets under Criterion: a failed check becomes a
 * Criterion failure naming the input, and replay() runs a directory of inputs. Include it
 * before the target files (it defines ISM_FUZZ_FAIL and ISM_FUZZ_NO_ENTRY for them). */
#ifndef ISM_REPLAY_CRITERION_H
#define ISM_REPLAY_CRITERION_H

#include <criterion/criterion.h>
#include <stdarg.h>
#include <stdio.h>
#include "tests/fuzz/fuzz_replay.h"

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

/* Replays every input of dir through fn; an empty directory fails unless may_be_empty. */
static void replay(const char *dir, fuzz_target_fn fn, int may_be_empty)
{
    long n = fuzz_replay_dir(dir, fn, fuzz_current, sizeof fuzz_current, may_be_empty);
    cr_assert_geq(n, 0, "cannot read %s (run the tests from the repository root)", dir);
    if (!may_be_empty)
        cr_assert_gt(n, 0, "%s holds no inputs", dir);
    cr_log_info("%s: %ld inputs replayed", dir, n);
}

#endif
