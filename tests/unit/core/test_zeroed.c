/* test_zeroed.c — zero-filled arrays written on a pool's threads (core/util/zeroed.h): every
 * byte 0 over memory the allocator hands out dirty (glibc's M_PERTURB fills each allocation
 * with a non-zero byte, so a byte no thread wrote shows), for sizes below, at and across the
 * threads' shares, on 1 to 3 threads; the start on a cache line; overflow refused. */
#include <criterion/criterion.h>
#include <malloc.h>
#include <stdint.h>
#include <stdlib.h>

#include "core/util/cache_line.h"
#include "core/util/zeroed.h"

/* Every byte of the n * size at p is 0: the first non-zero one's offset, or -1. */
static long first_nonzero(const unsigned char *p, size_t bytes)
{
    for (size_t i = 0; i < bytes; i++)
        if (p[i])
            return (long)i;
    return -1;
}

static void check_pool(ism_pool *pool, const char *what)
{
    const size_t share = (size_t)1 << 18; /* zeroed.c's ZERO_SHARE */
    const size_t counts[] = {1, 63, 4095, share - 1, share, share + 1, 3 * share + 17,
                             (2u << 20) + 5};
    const size_t sizes[] = {1, 24};
    for (size_t i = 0; i < sizeof counts / sizeof *counts; i++)
        for (size_t j = 0; j < sizeof sizes / sizeof *sizes; j++) {
            ism_par_cost cost = {0, 0, 0, 0};
            unsigned char *p = ism_zeroed_alloc(pool, counts[i], sizes[j], &cost);
            cr_assert_not_null(p);
            cr_expect_eq((uintptr_t)p % ISM_CACHE_LINE, 0, "%s: not on a cache line", what);
            long at = first_nonzero(p, counts[i] * sizes[j]);
            cr_expect_eq(at, -1, "%s: %zu x %zu bytes: byte %ld is not 0", what, counts[i],
                         sizes[j], at);
            free(p);
        }
}

Test(zeroed, every_byte_zero_on_dirty_memory_on_any_thread_count)
{
    mallopt(M_PERTURB, 0x5a); /* this test's process only (criterion forks per test) */
    void *probe = malloc(64);
    cr_assert_not_null(probe);
    const volatile unsigned char *dirty = probe; /* read on purpose: what malloc left there */
    cr_assert_neq(dirty[0], 0, "M_PERTURB did not make allocations dirty: the test shows nothing");
    free(probe);
    check_pool(NULL, "no pool");
    for (int threads = 1; threads <= 3; threads++) {
        ism_pool *pool = ism_pool_new(threads);
        cr_assert_not_null(pool);
        check_pool(pool, threads == 1 ? "1 thread" : threads == 2 ? "2 threads" : "3 threads");
        ism_pool_free(pool);
    }
    mallopt(M_PERTURB, 0);
}

Test(zeroed, overflowing_size_is_refused)
{
    cr_expect_null(ism_zeroed_alloc(NULL, SIZE_MAX / 8 + 1, 16, NULL));
    void *p = ism_zeroed_alloc(NULL, 0, 24, NULL); /* nothing asked: still freeable */
    free(p);
}
