/* test_dual_keyed.c — the dual mesher's memo map (core/octree/dual_keyed.h): setting a key
 * already there never grows the table, so a slot or keyed_get pointer held across that put
 * stays valid (keyed_reserve's contract, the pattern dual_measure.c measure_pairs uses), and
 * every key keeps its value across growth. Counts from the map's stated load limit: at most
 * half full. */
#include <criterion/criterion.h>
#include "core/octree/dual_keyed.h"

Test(dual_keyed, a_present_key_set_at_the_load_limit_stays_in_its_slot)
{
    keyed k = {0};
    keyed_put(&k, 1, 1.0);
    size_t cap = k.cap;
    cr_assert(cap >= 2, "no table after the first put");
    /* fill to the limit: cap / 2 keys, the next new key would grow the table */
    for (uint64_t key = 2; key <= cap / 2; key++)
        keyed_put(&k, key, (double)key);
    cr_assert_eq(k.n, cap / 2);
    cr_assert_eq(k.cap, cap, "grew before the limit: %zu -> %zu", cap, k.cap);
    const double *held = keyed_get(&k, 7);
    const uint64_t *slots = k.key;
    cr_assert(held && *held == 7.0);
    keyed_put(&k, 7, 70.0); /* present: no growth due */
    cr_expect_eq(k.cap, cap, "setting a present key grew the table: %zu -> %zu", cap, k.cap);
    cr_expect_eq(k.key, slots, "setting a present key moved the slots");
    cr_expect_eq(k.n, cap / 2, "setting a present key counted it again");
    if (k.key == slots)
        cr_expect_eq(*held, 70.0, "the held slot reads %g, 70 expected", *held);
    /* a new key now grows it, and every value survives the move */
    keyed_put(&k, cap / 2 + 1, -1.0);
    cr_expect_gt(k.cap, cap, "a new key past the limit did not grow the table");
    cr_expect_eq(k.n, cap / 2 + 1);
    for (uint64_t key = 1; key <= cap / 2; key++) {
        const double *v = keyed_get(&k, key);
        double want = key == 7 ? 70.0 : (double)key;
        cr_expect(v && *v == want, "key %llu: %g after growth, %g expected",
                  (unsigned long long)key, v ? *v : -1.0, want);
    }
    const double *last = keyed_get(&k, cap / 2 + 1);
    cr_expect(last && *last == -1.0);
    keyed_free(&k);
}
