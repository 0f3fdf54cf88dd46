/* dual_keyed.h — the dual mesher's memos by 64-bit key (dual_tree.h: triangles that met E,
 * vertex pairs' midpoint distances, quads cut as fans): an open-addressed map to doubles. */
#ifndef ISM_DUAL_KEYED_H
#define ISM_DUAL_KEYED_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include "core/util/bits.h"

/* A table's first slots: 1,024 (8 KB of keys, 8 KB of values, 16 words of bits), 512 keys
 * before it grows; the size the map has had since 1d7f5dd2, not tuned since: the
 * sphere's pair memo at E 0.0141 grows three times from it (below).
 * Any power of 2 of at least 64 works — the bitmap's words must be whole (util/bits.h): below
 * 64 slots there would be no word, and every look-up would read past it. */
#define KEYED_MIN_CAP 1024
_Static_assert(KEYED_MIN_CAP >= 64 && (KEYED_MIN_CAP & (KEYED_MIN_CAP - 1)) == 0,
               "keyed: a power of 2 of at least 64 slots (whole words of bits)");

/* An open-addressed map from 64-bit keys (never 0) to doubles, kept at most half full. Bit
 * i of used says slot i holds a key: only used is cleared when the table is made (cap / 8
 * bytes), not the keys (8 cap): calloc's clearing of key[] was the larger part of a small
 * mesh's memo cost (the sphere at E 0.0141, bench_error under callgrind: 58K of its 2.13M
 * instructions for the pair memo's three growths, 8.5K each for the other three maps'
 * first tables). */
typedef struct keyed {
    uint64_t *key;
    double *val;
    uint64_t *used; /* cap / 64 words */
    size_t n, cap;
} keyed;

/* Does slot i hold a key? */
static inline bool keyed_used(const keyed *k, size_t i)
{
    return ism_bit_test(k->used, i);
}

/* Slot i (empty) takes key; the caller sets its value and counts it in n. */
static inline void keyed_claim(keyed *k, size_t i, uint64_t key)
{
    ism_bit_set(k->used, i);
    k->key[i] = key;
}

/* A key's first slot: the product's high half folded onto its low half, so that every bit
 * of the key reaches the slot. The old slot, bits 17.. of the product, read only the key's
 * low bits below the mask: a pair key (pair_key: ism_edge_key + 1, the smaller end in the
 * high word, the larger in the low) took its slot from its larger end alone, the ~3 pairs of
 * each vertex on one slot and their neighbours' runs merged (the sphere's measure,
 * ism_dual_measure_triangles and measure_pairs: ~1% of ism_mesh_surface, b3aba1d). */
static inline size_t keyed_hash(uint64_t key)
{
    uint64_t h = key * 0x9E3779B97F4A7C15ull;
    return (size_t)(h ^ h >> 32);
}

static inline size_t keyed_slot(const keyed *k, uint64_t key)
{
    size_t mask = k->cap - 1, i = keyed_hash(key) & mask;
    while (keyed_used(k, i) && k->key[i] != key)
        i = (i + 1) & mask;
    return i;
}

/* key's value, or NULL. */
static inline const double *keyed_get(const keyed *k, uint64_t key)
{
    if (!k->cap)
        return NULL;
    size_t i = keyed_slot(k, key);
    return keyed_used(k, i) ? &k->val[i] : NULL;
}

/* Room for `more` new keys without growing (so slots stay put meanwhile); false when out of
 * memory. */
static inline bool keyed_reserve(keyed *k, size_t more)
{
    size_t cap = k->cap ? k->cap : KEYED_MIN_CAP;
    while (2 * (k->n + more) > cap)
        cap *= 2;
    if (cap == k->cap)
        return true;
    keyed old = *k, grown = {NULL, NULL, NULL, old.n, cap};
    grown.key = malloc(cap * sizeof *grown.key);
    grown.val = malloc(cap * sizeof *grown.val);
    grown.used = ism_bits_new(cap); /* cap: a power of 2, >= KEYED_MIN_CAP */
    if (!grown.key || !grown.val || !grown.used) {
        free(grown.key);
        free(grown.val);
        free(grown.used);
        return false;
    }
    if (old.cap)
        ISM_BITS_EACH(old.used, ism_bits_words(old.cap), i) { /* the used slots */
            size_t j = keyed_slot(&grown, old.key[i]);
            keyed_claim(&grown, j, old.key[i]);
            grown.val[j] = old.val[i];
        }
    free(old.key);
    free(old.val);
    free(old.used);
    *k = grown;
    return true;
}

/* Sets key's value; out of memory, nothing is kept (a memo then recomputes, no more). Only
 * a new key can grow the table (and move slots): a key already there is set in its slot.
 * One probe unless the table grows. */
static inline void keyed_put(keyed *k, uint64_t key, double val)
{
    size_t i = k->cap ? keyed_slot(k, key) : 0;
    bool found = k->cap && keyed_used(k, i);
    if (!found && 2 * (k->n + 1) > k->cap) { /* keyed_reserve's load limit */
        if (!keyed_reserve(k, 1))
            return;
        i = keyed_slot(k, key);
    }
    if (!found) {
        k->n++;
        keyed_claim(k, i, key);
    }
    k->val[i] = val;
}

static inline void keyed_free(keyed *k)
{
    free(k->key);
    free(k->val);
    free(k->used);
}

#endif
