/* bits.h — a bitmap of a table's slots in 64-bit words: which slots hold an entry, so that
 * only the bits are cleared when the table is made, not its entries (the dual mesher's
 * point memo, pair memo and keyed maps: dual_tree.h, dual_keyed.h). A table's slot count is
 * a multiple of 64 (a power of 2 of at least 64): each word is whole. */
#ifndef ISM_BITS_H
#define ISM_BITS_H

#include <assert.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>

/* Words for n slots. n < 64 would round down to no word, and every look-up would then read
 * and write past the bitmap: callers hold n to a power of 2 >= 64 (their _Static_asserts). */
static inline size_t ism_bits_words(size_t n)
{
    assert(n >= 64 && n % 64 == 0);
    return n / 64;
}

/* Is bit i set? */
static inline bool ism_bit_test(const uint64_t *bits, size_t i)
{
    return bits[i >> 6] >> (i & 63) & 1;
}

static inline void ism_bit_set(uint64_t *bits, size_t i)
{
    bits[i >> 6] |= (uint64_t)1 << (i & 63);
}

/* n bits, all clear; NULL when out of memory. */
static inline uint64_t *ism_bits_new(size_t n)
{
    return calloc(ism_bits_words(n), sizeof(uint64_t));
}

/* A table of n entries of `size` bytes, uncleared (returned), and its n bits, clear (into
 * *bits); NULL (and *bits NULL: nothing held) when out of memory. */
static inline void *ism_bits_table(size_t n, size_t size, uint64_t **bits)
{
    void *entries = size && n <= SIZE_MAX / size ? malloc(n * size) : NULL;
    *bits = ism_bits_new(n);
    if (entries && *bits)
        return entries;
    free(entries);
    free(*bits);
    *bits = NULL;
    return NULL;
}

/* The body once for each set bit of bits[0..words), i (size_t) its index, ascending; a word
 * is read once, before its first bit's body. `break` leaves only the innermost of the three
 * loops: the body must not break. */
#define ISM_BITS_EACH(bits, words, i)                                                  \
    for (size_t ism_bits_w_ = 0; ism_bits_w_ < (words); ism_bits_w_++)                 \
        for (uint64_t ism_bits_b_ = (bits)[ism_bits_w_]; ism_bits_b_;                  \
             ism_bits_b_ &= ism_bits_b_ - 1)                                           \
            for (size_t i = 64 * ism_bits_w_ + (size_t)__builtin_ctzll(ism_bits_b_),   \
                        ism_bits_once_ = 1;                                            \
                 ism_bits_once_; ism_bits_once_ = 0)

#endif
