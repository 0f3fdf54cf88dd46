/* trig_pair.h — the sine and cosine of one argument, computed as a pair. Surfaces such as the
 * gyroid take both of the same argument (sin(k*x) … cos(k*x)), and the derivative of either
 * needs the other; ism_sincos (sincos.h, our own, not libm's) gives both at once. A memo of
 * arguments, kept by the workspace, hands out the second of the pair and repeats. It is
 * keyed on the argument's bits, so a hit is exactly what a fresh call would return, and what
 * the batched evaluators' ism_sincos4 computes four lanes at a time. Also the group pairs
 * (ism_trig_groups): whole registers' sines and cosines for the batched gradient and for
 * ism_eval_batch's one-group chunks. Not public. */
#ifndef ISM_TRIG_PAIR_H
#define ISM_TRIG_PAIR_H

#include "core/eval/eval.h"
#include "core/eval/sincos.h"
#include <stdint.h>
#include <string.h>

/* A direct-mapped cache of arguments, kept by the workspace from one evaluation to the next:
 * the polygoniser evaluates f along lattice edges and faces, where two of the three
 * coordinates stay the same from point to point (sin(k*x) repeats), and corners shared by
 * neighbours. 2^ISM_TRIG_CACHE_BITS entries (96 KB for each of the two tables below, 192 KB
 * in all, plus the group pairs' ~3.1 KB) for a tape that takes sines or cosines: gyroid ball
 * at E = 1e-3 (callgrind, ism_mesh_surface, one thread), 4.76M sincos calls with 2^9 entries;
 * the whole run 3,735.5M instructions with 2^9, 3,694.6M with 2^11, 3,679.8M with 2^12,
 * 3,660.5M with 2^13 (measured with glibc's sincos: a lookup costs ~15 instructions, a call
 * ~63; ism_sincos's ~90 a call only favours the memo more; 2^12 tables stay well within a
 * core's second-level cache, 1 MB here). 2^ISM_TRIG_CACHE_SMALL_BITS for the others (nothing
 * looks there unless the workspace evaluates another tape): filling 2^13 entries of one table
 * cost the sphere at E = 0.0141, 2.86M instructions in all, 9.5% more (measured before the
 * libm table was added); 2^9 entries in both tables still cost ~4.3K instructions a
 * workspace, eight workspaces a mesh (the sphere at E = 0.0141: 2.538M -> 2.508M with 2^4).
 * Every entry starts as the pair of +0.0, which is what ism_sincos (and libm) gives there, so
 * no entry is ever invalid.
 *
 * A second table of as many entries holds libm's pairs for the interval evaluator's bounds
 * (eval_interval.c: sound under glibc's documented error, which ism_sincos's measured one is
 * not). The bounds are lattice coordinates that repeat from box to box: gyroid ball at
 * E = 1e-3 (callgrind, as above), the 279K interval sines and cosines called libm's sin and
 * cos 558K times without a memo (47.5M instructions), 1,833 times (0.24M) through this
 * table. */
#define ISM_TRIG_CACHE_BITS 12
#define ISM_TRIG_CACHE_SMALL_BITS 4

typedef struct ism_trig_entry {
    uint64_t key;
    double s, c;
} ism_trig_entry;

/* The batched evaluators' last sines and cosines of whole registers (eval_gradient_batch.c;
 * eval_double.c's ism_eval_batch for a chunk of one group only: a longer chunk's registers
 * span several groups, more than the pairs hold), kept by their arguments' bits: a surface
 * takes sin u and cos u of one register at different steps (the gyroid: sin and cos of kx, ky
 * and kz, six steps on three registers), and a register's pair is computed once.
 * ISM_TRIG_GROUP_PAIRS registers: the gyroid's three, and one more (a power of two: the round
 * robin's index is masked). ISM_TRIG_GROUP_LANES: ISM_GRAD_BATCH's and a group of
 * ism_eval_batch's (asserted there). Gyroid ball at E = 1e-3 (callgrind, as above): the whole run
 * 2,741.8M instructions without them, ~2,703M with. */
#define ISM_TRIG_GROUP_PAIRS 4
#define ISM_TRIG_GROUP_LANES 32

typedef struct ism_trig_group_pair {
    size_t n; /* lanes held (0: none) */
    double u[ISM_TRIG_GROUP_LANES], s[ISM_TRIG_GROUP_LANES], c[ISM_TRIG_GROUP_LANES];
} ism_trig_group_pair;

/* The single-box interval pass's sines and cosines of whole intervals (interval_trig.h's
 * ism_iv_trig), kept by the bounds' bits, both from one miss: the gyroid takes sin u and cos u
 * of each of three registers, and a node's neighbours share its intervals on two axes.
 * 2^ISM_TRIG_IV_BITS direct-mapped entries (the index: a hash's top bits). A key starts as
 * a NaN's bits, which no bound looked up has (only intervals that resolve are); an empty
 * entry's s and c are left uninitialised, never read before a miss fills them. */
#define ISM_TRIG_IV_BITS 6
#define ISM_TRIG_IV_ENTRIES (1 << ISM_TRIG_IV_BITS)
#define ISM_TRIG_IV_EMPTY 0x7ff8dead00000000ull

typedef struct ism_trig_iv_entry {
    uint64_t lo, hi; /* the interval's bounds' bits */
    ism_interval s, c;
} ism_trig_iv_entry;

typedef struct ism_trig_cache {
    uint64_t mask; /* entries − 1 of each table (a power of two, at most 2^ISM_TRIG_CACHE_BITS) */
    unsigned next_pair; /* the group pair a miss takes next (round robin) */
    ism_trig_group_pair pairs[ISM_TRIG_GROUP_PAIRS];
    ism_trig_iv_entry iv[ISM_TRIG_IV_ENTRIES];
    ism_trig_entry e[]; /* ism_sincos's pairs, then (from mask + 1 on) libm's */
} ism_trig_cache;

/* The bytes of a cache of 2^bits entries in each table. */
static inline size_t ism_trig_cache_size(unsigned bits)
{
    return sizeof(ism_trig_cache) + ((size_t)2 << bits) * sizeof(ism_trig_entry);
}

static inline void ism_trig_cache_init(ism_trig_cache *m, unsigned bits)
{
    m->mask = ((uint64_t)1 << bits) - 1;
    m->next_pair = 0;
    memset(m->pairs, 0, sizeof m->pairs); /* n = 0: none held (u's first lane read first) */
    for (int i = 0; i < ISM_TRIG_IV_ENTRIES; i++)
        m->iv[i].lo = m->iv[i].hi = ISM_TRIG_IV_EMPTY;
    for (uint64_t i = 0; i <= 2 * m->mask + 1; i++)
        m->e[i] = (ism_trig_entry){0, 0.0, 1.0}; /* ism_sincos(+0.0), and libm's */
}

/* u's slot in a table of mask + 1 entries */
static inline ism_trig_entry *ism_trig_slot(ism_trig_entry *table, uint64_t mask, double u,
                                            uint64_t *key)
{
    memcpy(key, &u, sizeof *key);
    return &table[((*key * 0x9e3779b97f4a7c15ull) >> (64 - ISM_TRIG_CACHE_BITS)) & mask];
}

static inline void ism_trig_pair(ism_trig_cache *m, double u, double *s, double *c)
{
    uint64_t key;
    ism_trig_entry *e = ism_trig_slot(m->e, m->mask, u, &key);
    if (e->key != key) {
        ism_sincos(u, &e->s, &e->c);
        e->key = key;
    }
    *s = e->s;
    *c = e->c;
}

/* libm's sin u and cos u (glibc: what sin and cos return, bit for bit), for bounds that must
 * be sound. */
static inline void ism_trig_pair_libm(ism_trig_cache *m, double u, double *s, double *c)
{
    uint64_t key;
    ism_trig_entry *e = ism_trig_slot(m->e + m->mask + 1, m->mask, u, &key);
    if (e->key != key) {
        sincos(u, &e->s, &e->c);
        e->key = key;
    }
    *s = e->s;
    *c = e->c;
}

/* The sines and cosines of ng groups of four arguments av (ng * 4 <= ISM_TRIG_GROUP_LANES):
 * a pair trig keeps when one holds av's very bits, else computed four lanes at a time
 * (ism_sincos4) into the pair next in turn; either way each lane is ism_sincos's. A pair is
 * told apart by its first argument's bits before the rest are compared (a pair of other
 * arguments nearly always differs there already). */
_Static_assert((ISM_TRIG_GROUP_PAIRS & (ISM_TRIG_GROUP_PAIRS - 1)) == 0,
               "the round robin's index is masked");
INLINE const ism_trig_group_pair *ism_trig_groups(ism_trig_cache *trig, const double *av,
                                                  size_t ng)
{
    const size_t n = ng * 4;
    uint64_t first;
    memcpy(&first, av, sizeof first);
    #pragma GCC unroll 4
    for (int k = 0; k < ISM_TRIG_GROUP_PAIRS; k++) {
        const ism_trig_group_pair *p = &trig->pairs[k];
        uint64_t held;
        memcpy(&held, p->u, sizeof held);
        if (held != first || p->n != n)
            continue;
        v4i diff = {0, 0, 0, 0};
        #pragma GCC unroll 8
        for (size_t g = 0; g < ng; g++)
            diff |= (v4i)v4_ld(av + g * 4) ^ (v4i)v4_ld(p->u + g * 4);
        if (!(diff[0] | diff[1] | diff[2] | diff[3]))
            return p;
    }
    ism_trig_group_pair *p = &trig->pairs[trig->next_pair];
    trig->next_pair = (trig->next_pair + 1) & (ISM_TRIG_GROUP_PAIRS - 1);
    p->n = n;
    #pragma GCC unroll 8
    for (size_t g = 0; g < ng; g++) {
        v4d u = v4_ld(av + g * 4), s, c;
        ism_sincos4(u, &s, &c);
        v4_st(p->u + g * 4, u);
        v4_st(p->s + g * 4, s);
        v4_st(p->c + g * 4, c);
    }
    return p;
}

#endif
