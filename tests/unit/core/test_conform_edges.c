/* test_conform_edges.c — a refinement round's edge table (cf_edge_table, conform_refine.c):
 * against a second method, a linear list of the edges seen, each edge of random rounds gets
 * the number the list gives it (its first addition's, whichever way round it is asked; new
 * edges numbered 0, 1, ... in order), across rounds that start the table again, and a table
 * full to its room answers ISM_KEY_NONE for a new edge but still finds those it holds. */
#include <criterion/criterion.h>
#include <stdlib.h>

#include "core/singular/conform_internal.h"

/* Rounds, and the most edges one asks (the table's room: max). */
#define ROUNDS 6
#define MAX_EDGES 3000

/* The number of edge {a, b} in the list of n seen (in order of first addition), or n. */
static size_t list_find(const uint32_t (*seen)[2], size_t n, uint32_t a, uint32_t b)
{
    for (size_t i = 0; i < n; i++)
        if ((seen[i][0] == a && seen[i][1] == b) || (seen[i][0] == b && seen[i][1] == a))
            return i;
    return n;
}

Test(conform_edges, numbers_as_a_list_of_first_additions, .timeout = 10)
{
    static uint32_t seen[MAX_EDGES][2];
    cf_edge_table t = {0};
    srand(32);
    for (int round = 0; round < ROUNDS; round++) {
        /* vertex numbers from a few ranges, so many edges recur, some reversed; sizes from a
         * small table (the first size) to one grown several times */
        size_t asks = 40 + (size_t)round * 500, n = 0;
        uint32_t span = 8 + 30 * (uint32_t)round, base = (uint32_t)round * 1000003u;
        cr_assert(cf_edge_table_start(&t, asks));
        for (size_t i = 0; i < asks; i++) {
            uint32_t a = base + (uint32_t)rand() % span, b = base + (uint32_t)rand() % span;
            if (a == b)
                b++;
            bool added;
            uint32_t got = cf_edge_table_add(&t, a, b, &added);
            size_t want = list_find((const uint32_t(*)[2])seen, n, a, b);
            cr_assert_eq(added, want == n, "round %d edge %u %u: added %d", round, a, b, added);
            cr_assert_eq(got, (uint32_t)want, "round %d edge %u %u: %u, the list %zu", round,
                         a, b, got, want);
            if (want == n) {
                seen[n][0] = a;
                seen[n][1] = b;
                n++;
            }
        }
        cr_assert_eq(t.n, n);
    }
    cf_edge_table_free(&t);
}

/* Whether t, just started with room for max, is as cf_edge_table_start promises: nothing added,
 * every slot empty and twice the room in slots (so cf_edge_table_add's probe, which stops only
 * at an empty slot, ends). Checked slot by slot, so a table left with stale or unset slots
 * fails here instead of hanging a probe. */
static void assert_started_empty(const cf_edge_table *t, size_t max)
{
    size_t slots = (size_t)1 << (64 - t->shift);
    cr_assert_eq(t->n, 0u);
    cr_assert_eq(t->max, max);
    cr_assert_geq(slots, 2 * max, "%zu slots for room %zu", slots, max);
    for (size_t j = 0; j < slots; j++)
        cr_assert_eq(t->slot[j].index, ISM_KEY_NONE, "slot %zu of %zu not empty", j, slots);
}

/* Fills t (just started with room for max) with the edges (i + base, i + base + 1), numbered
 * 0 .. max − 1; then a new edge finds no room while every held edge is still found, either
 * way round. */
static void fill_and_check(cf_edge_table *t, size_t max, uint32_t base)
{
    bool added;
    for (uint32_t i = 0; i < max; i++) {
        cr_assert_eq(cf_edge_table_add(t, base + i, base + i + 1, &added), i);
        cr_assert(added, "edge %u of %zu not added", i, max);
    }
    cr_assert_eq(cf_edge_table_add(t, base + 7, base + 9, &added), ISM_KEY_NONE);
    cr_assert_not(added);
    for (uint32_t i = 0; i < max; i++) {
        cr_assert_eq(cf_edge_table_add(t, base + i + 1, base + i, &added), i);
        cr_assert_not(added);
    }
}

/* The timeout turns a probe that never meets an empty slot into a failure, not a hang. */
Test(conform_edges, full_table_holds_what_it_has, .timeout = 10)
{
    cf_edge_table t = {0};
    cr_assert(cf_edge_table_start(&t, 5));
    assert_started_empty(&t, 5);
    fill_and_check(&t, 5, 0);
    /* started again: empty, the same five edges new again and numbered from 0 */
    cr_assert(cf_edge_table_start(&t, 5));
    assert_started_empty(&t, 5);
    fill_and_check(&t, 5, 0);
    /* room of the smallest table's slots (EDGE_SLOTS_MIN, 64) and past it, after a larger
     * table: the slots must still outnumber the room */
    size_t rooms[] = {64, 65, 31, 64};
    for (size_t k = 0; k < sizeof rooms / sizeof *rooms; k++) {
        cr_assert(cf_edge_table_start(&t, rooms[k]));
        assert_started_empty(&t, rooms[k]);
        fill_and_check(&t, rooms[k], 100 * (uint32_t)k);
    }
    cf_edge_table_free(&t);
}
