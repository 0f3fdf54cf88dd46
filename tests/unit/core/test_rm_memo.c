/* test_rm_memo.c — the point-keyed table of Newton measures (core/remesh/rm_memo.c): a slot
 * hands back what was stored for a point only to that very point, bit for bit — not to its
 * neighbour one ulp away, not to −0.0 for +0.0 — whatever else has been stored since (a
 * direct-mapped table evicts, it never mixes). */
#include <criterion/criterion.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/remesh/rm_memo.h"

/* Points stored: well beyond the smallest table's 2^10 slots, so slots are shared. */
#define POINTS 20000

/* A point spread over [-1.5, 1.5]³ from i (a fixed sequence: the test is repeatable). */
static void point(unsigned i, double x[3])
{
    uint64_t h = (uint64_t)i * 0x9e3779b97f4a7c15ull + 12345;
    for (int k = 0; k < 3; k++) {
        h ^= h >> 29;
        h *= 0xbf58476d1ce4e5b9ull;
        x[k] = -1.5 + 3.0 * (double)(h >> 11) / 9007199254740992.0;
    }
}

/* Stores point i's made-up measure in its slot. */
static void store(rm_memo *m, const double x[3])
{
    rm_memo_entry *e = rm_memo_slot(m, x);
    e->state = RM_MEMO_S2;
    e->s1 = x[0] + x[1];
    e->s2 = x[2];
}

Test(rm_memo, a_slot_answers_only_its_own_point)
{
    rm_memo *m = rm_memo_new();
    cr_assert_not_null(m);
    size_t hits = 0;
    for (unsigned i = 0; i < POINTS; i++) {
        double x[3];
        point(i, x);
        cr_assert_eq(rm_memo_slot(m, x)->state, RM_MEMO_EMPTY, "point %u is new", i);
        store(m, x);
        for (int k = 0; k < 3; k++) { /* one ulp away in any coordinate is another point */
            double y[3] = {x[0], x[1], x[2]};
            y[k] = nextafter(y[k], INFINITY);
            cr_assert_eq(rm_memo_slot(m, y)->state, RM_MEMO_EMPTY);
        }
        store(m, x); /* a neighbour may have taken x's slot */
    }
    /* newest first: a point found is its slot's last writer, and what it holds is exactly
     * what was stored for it (a miss re-keys the slot, so older points come after) */
    for (unsigned i = POINTS; i-- > 0;) {
        double x[3];
        point(i, x);
        rm_memo_entry *e = rm_memo_slot(m, x);
        if (e->state == RM_MEMO_EMPTY)
            continue;
        hits++;
        cr_assert_eq(memcmp(e->x, x, sizeof e->x), 0);
        cr_assert_eq(e->s1, x[0] + x[1]);
        cr_assert_eq(e->s2, x[2]);
    }
    cr_assert_gt(hits, 100, "a table of 1024 slots keeps many of the last points (%zu)", hits);
    cr_assert_leq(hits, 1024, "1024 slots keep at most 1024 points");
    rm_memo_free(m);
}

Test(rm_memo, signed_zero_is_its_own_point)
{
    rm_memo *m = rm_memo_new();
    double plus[3] = {0.0, 0.5, 0.25}, minus[3] = {-0.0, 0.5, 0.25};
    rm_memo_entry *e = rm_memo_slot(m, plus);
    e->state = RM_MEMO_S1;
    e->s1 = 1.0;
    cr_assert_eq(rm_memo_slot(m, minus)->state, RM_MEMO_EMPTY);
    rm_memo_free(m);
}
