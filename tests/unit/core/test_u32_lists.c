/* test_u32_lists.c — lists of uint32 values per key (core/util/u32_lists.h): a value is found
 * in its own key's list and in no other, past the first allocation's 1,024 entries (the growth
 * keeps the links), newest first; no keys at all; a freed list can be freed again. */
#include <criterion/criterion.h>
#include <stdint.h>

#include "core/util/u32_lists.h"

Test(u32_lists, values_found_under_their_key_only_across_growth)
{
    enum { KEYS = 37, VALUES = 3000 };
    ism_u32_lists l;
    cr_assert(ism_u32_lists_init(&l, KEYS));
    for (uint32_t v = 0; v < VALUES; v++) /* value v under key v * 7 % KEYS, odd values only */
        if (v & 1)
            cr_assert(ism_u32_lists_add(&l, v * 7 % KEYS, v));
    cr_expect_eq(l.n, VALUES / 2);
    for (uint32_t v = 0; v < VALUES; v++)
        for (uint32_t k = 0; k < KEYS; k++)
            cr_expect_eq(ism_u32_lists_has(&l, k, v), (v & 1) && k == v * 7 % KEYS,
                         "value %u under key %u", v, k);
    /* newest first: key 0's values are the odd multiples of KEYS, largest first */
    uint32_t last = UINT32_MAX, count = 0;
    for (uint32_t i = l.head[0]; i != ISM_U32_LISTS_END; i = l.e[i][0], count++) {
        cr_expect_lt(l.e[i][1], last);
        cr_expect_eq(l.e[i][1] % KEYS, 0);
        last = l.e[i][1];
    }
    cr_expect_eq(count, 41); /* 37 times 1, 3, ..., 81 */
    ism_u32_lists_free(&l);
    ism_u32_lists_free(&l);
}

Test(u32_lists, no_keys)
{
    ism_u32_lists l;
    cr_assert(ism_u32_lists_init(&l, 0));
    cr_expect_eq(l.n, 0);
    ism_u32_lists_free(&l);
}
