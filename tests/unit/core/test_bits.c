/* test_bits.c — the slot bitmap (core/util/bits.h): a fresh map reads clear, a set bit reads
 * set and no other, and the walk visits exactly the set bits in ascending order, across word
 * boundaries (bits 0, 63, 64, the last), each once. The expected set is kept beside the map
 * in a byte array, not read back from it. */
#include <criterion/criterion.h>
#include "core/util/bits.h"

#define N 256 /* four words */

Test(bits, set_bits_read_back_and_walk_ascending)
{
    uint8_t want[N] = {0};
    uint64_t *b = ism_bits_new(N);
    cr_assert(b);
    for (size_t i = 0; i < N; i++)
        cr_expect_not(ism_bit_test(b, i), "bit %zu set in a fresh map", i);
    static const size_t at[] = {0, 5, 63, 64, 65, 127, 128, 200, N - 1};
    for (size_t k = 0; k < sizeof at / sizeof *at; k++) {
        ism_bit_set(b, at[k]);
        want[at[k]] = 1;
    }
    ism_bit_set(b, 5); /* again: still one bit */
    for (size_t i = 0; i < N; i++)
        cr_expect_eq(ism_bit_test(b, i), want[i], "bit %zu", i);
    size_t seen = 0, last = 0;
    ISM_BITS_EACH(b, ism_bits_words(N), i)
    {
        cr_expect(want[i], "the walk visited clear bit %zu", i);
        cr_expect(seen == 0 || i > last, "the walk went %zu -> %zu", last, i);
        last = i;
        seen++;
    }
    cr_expect_eq(seen, sizeof at / sizeof *at, "the walk visited %zu bits", seen);
    free(b);
}

Test(bits, a_table_and_its_bits_together)
{
    uint64_t *b;
    double *e = ism_bits_table(128, sizeof *e, &b);
    cr_assert(e && b);
    for (size_t i = 0; i < 128; i++)
        cr_expect_not(ism_bit_test(b, i), "bit %zu set in a fresh table", i);
    e[127] = 1.0; /* every entry is room */
    free(e);
    free(b);
    /* a size whose product overflows is refused, nothing held */
    void *big = ism_bits_table(128, SIZE_MAX / 64, &b);
    cr_expect_null(big);
    cr_expect_null(b);
}
