/* test_cell_stats.c — the polygoniser's counter arithmetic (cell_stats.h) against each counter
 * named and added or subtracted on its own: every counter, in the lanes of four and the rest,
 * including a difference that wraps (a counter smaller after than before). */
#include <criterion/criterion.h>
#include "core/octree/cell_stats.h"

/* Counters that differ from each other and from any neighbour's sum. */
static ism_cell_stats numbered(uint64_t base)
{
    return (ism_cell_stats){base + 1,    base + 20,    base + 300,  base + 4000,
                            base + 5e4,  base + 6e5,   base + 7e6,  base + 8e7,
                            base + 9e8,  base + 1e10,  base + 1.1e11};
}

#define EACH(X)                                                                           \
    X(polygons) X(two_polygon_nodes) X(many_polygon_nodes) X(degenerate_polygons)         \
    X(double_lines) X(open_chains) X(crossed_faces) X(crack_tiles) X(singular_points)     \
    X(lifted_polygons) X(lifted_chords)

Test(cell_stats, add_and_minus_counter_by_counter)
{
    _Static_assert(sizeof(ism_cell_stats) == 11 * sizeof(uint64_t),
                   "a counter added to ism_cell_stats belongs in EACH");
    const ism_cell_stats a = numbered(7), b = numbered(1000003);
    ism_cell_stats sum = a;
    ism_cell_stats_add(&sum, &b);
    const ism_cell_stats d = ism_cell_stats_minus(&b, &a), w = ism_cell_stats_minus(&a, &b);
#define CHECK(f)                                                                          \
    cr_expect_eq(sum.f, a.f + b.f, #f ": sum %llu", (unsigned long long)sum.f);           \
    cr_expect_eq(d.f, b.f - a.f, #f ": difference %llu", (unsigned long long)d.f);       \
    cr_expect_eq(w.f, a.f - b.f, #f ": wrapped difference %llu", (unsigned long long)w.f);
    EACH(CHECK)
#undef CHECK
}
