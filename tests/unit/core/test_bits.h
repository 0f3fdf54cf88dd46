/* test_bits.h — bit-level helpers the interval tests share: any bit pattern as a double (a
 * quarter of them subnormal or zero), and "the same bits, or both NaN". */
#ifndef TEST_BITS_H
#define TEST_BITS_H

#include <stdint.h>
#include <string.h>

#include "test_eval_surfaces.h"

/* A random bit pattern; a quarter get exponent field 0 (a subnormal or a zero). */
static inline double test_any_bits(test_rng *rng)
{
    uint64_t u = (uint64_t)(test_uniform(rng, 0, 0x1p32)) << 32 |
                 (uint64_t)(test_uniform(rng, 0, 0x1p32));
    if (test_uniform(rng, 0, 1) < 0.25)
        u &= ~(0x7ffull << 52);
    double x;
    memcpy(&x, &u, sizeof x);
    return x;
}

/* Equal bits, or both NaN (a NaN's sign may differ: interval_ops.h's round1_out). */
static inline int test_same_bits(double a, double b)
{
    return (a != a && b != b) || memcmp(&a, &b, sizeof a) == 0;
}

#endif
