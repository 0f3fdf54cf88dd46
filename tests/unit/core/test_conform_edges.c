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

Test(conform_edges, numbers_as_a_list_of_first_additions)
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

Test(conform_edges, full_table_holds_what_it_has)
{
    cf_edge_table t = {0};
    cr_assert(cf_edge_table_start(&t, 5));
    bool added;
    for (uint32_t i = 0; i < 5; i++) {
        cr_assert_eq(cf_edge_table_add(&t, i, i + 1, &added), i);
        cr_assert(added);
    }
    cr_assert_eq(cf_edge_table_add(&t, 7, 9, &added), ISM_KEY_NONE);
    cr_assert_not(added);
    for (uint32_t i = 0; i < 5; i++) {
        cr_assert_eq(cf_edge_table_add(&t, i + 1, i, &added), i);
        cr_assert_not(added);
    }
    /* started again: empty, numbered from 0 */
    cr_assert(cf_edge_table_start(&t, 5));
    cr_assert_eq(cf_edge_table_add(&t, 3, 4, &added), 0u);
    cr_assert(added);
    cf_edge_table_free(&t);
}
