/* fuzz_check.h — how a fuzz target says "this invariant broke". Under libFuzzer a broken
 * invariant prints its message and aborts (the input becomes a crash artifact); the
 * regression tests (tests/unit/{core,proto}/test_fuzz_regressions.c) define ISM_FUZZ_FAIL
 * before including a target so that the same check becomes a Criterion failure naming the
 * replayed file. */
#ifndef ISM_FUZZ_CHECK_H
#define ISM_FUZZ_CHECK_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#ifndef ISM_FUZZ_FAIL
#define ISM_FUZZ_FAIL(...) \
    (fprintf(stderr, "fuzz invariant broken: " __VA_ARGS__), fputc('\n', stderr), abort())
#endif

#define FUZZ_CHECK(cond, ...)          \
    do {                               \
        if (!(cond))                   \
            ISM_FUZZ_FAIL(__VA_ARGS__); \
    } while (0)

/* Same double, NaN equal to NaN (-0 equal to +0). */
static inline int fuzz_same(double a, double b)
{
    return (isnan(a) && isnan(b)) || a == b;
}

#endif
