/* rm_memo.h — distances to f = 0 remembered by point (rm_memo.c): the simplification measures
 * the same centroid, edge midpoint or vertex again and again (a merge's verdict, then its
 * trial, the ring's moves, the sweep after), each time with one or two evaluations of f and
 * ∇f. A direct-mapped table keyed on the point's exact bits keeps what rm_bound.c's Newton
 * measure found there, so a repeat costs a lookup and returns bit for bit what a fresh
 * measure would (f is pure; nothing else enters the measure). */
#ifndef ISM_RM_MEMO_H
#define ISM_RM_MEMO_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>

/* What an entry knows about its point x. */
enum rm_memo_state {
    RM_MEMO_EMPTY = 0,
    RM_MEMO_FAIL1, /* ∇f vanishes at x or f is not finite there */
    RM_MEMO_S1,    /* s1 = f/|∇f| at x, ∇f there (g), and y, where the Newton step lands */
    RM_MEMO_S2,    /* those and s2 = f/|∇f| at y */
    RM_MEMO_FAIL2, /* those; ∇f vanishes at y or f is not finite there */
};

typedef struct rm_memo_entry {
    double x[3], y[3], g[3];
    double s1, s2;
    uint32_t state;
} rm_memo_entry;

typedef struct rm_memo {
    rm_memo_entry *e;
    unsigned bits;
} rm_memo;

/* An empty table (a fixed 2^10 slots, small enough to stay in cache). NULL when out of
 * memory (the measures then go without it). */
rm_memo *rm_memo_new(void);
void rm_memo_free(rm_memo *m);

/* The entry for x: x's own (its state says what it knows) or, on a miss, the slot emptied
 * and keyed on x for the caller to fill. rm_memo_claim(rm_memo_peek(m, x), x). */
rm_memo_entry *rm_memo_slot(rm_memo *m, const double x[3]);

/* x's slot, whatever it holds; nothing changes (a caller asking of one point more than once
 * finds its slot once). By x's exact bits. Inline, as rm_memo_holds and rm_memo_claim: a fan
 * check asks them of each of its points, twice (rm_bound.c; chmutov-quartic's pass, own
 * box: 493,516 calls). */
static inline rm_memo_entry *rm_memo_peek(const rm_memo *m, const double x[3])
{
    uint64_t k[3];
    memcpy(k, x, sizeof k);
    uint64_t h = k[0] * 0x9e3779b97f4a7c15ull ^ k[1] * 0xc2b2ae3d27d4eb4full ^
                 k[2] * 0x165667b19e3779f9ull;
    h ^= h >> 31;
    return &m->e[(h * 0xd6e8feb86659fd93ull) >> (64 - m->bits)];
}

/* True when slot e (x's, rm_memo_peek) knows x: its entry is x's and not empty. */
static inline bool rm_memo_holds(const rm_memo_entry *e, const double x[3])
{
    return e->state != RM_MEMO_EMPTY && memcmp(e->x, x, sizeof e->x) == 0;
}

/* x's slot e as rm_memo_slot leaves it: kept when it holds x, else emptied and keyed on x.
 * e must be rm_memo_peek's answer for this very x (unchecked: checking would hash x again,
 * which is what peeking once spares): given another point's slot, x would be keyed where no
 * lookup of x looks, and a pointer kept to e would read x's measures from a slot that is
 * not x's. */
static inline rm_memo_entry *rm_memo_claim(rm_memo_entry *e, const double x[3])
{
    if (!rm_memo_holds(e, x)) {
        memcpy(e->x, x, sizeof e->x);
        e->state = RM_MEMO_EMPTY;
    }
    return e;
}

#endif
