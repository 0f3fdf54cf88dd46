/* sort_u64.c — the LSD radix sort of sort_u64.h. */
#include "core/util/sort_u64.h"

#include <stdlib.h>
#include <string.h>

/* Below this many keys an insertion sort (the radix passes' counts cost more). */
#define SORT_SMALL 64
/* Bits per pass: 11 (2,048 counts, 16 KB: in L1) makes 6 passes of a 64-bit key, fewer
 * when the keys share their high bits (vertex indices below 2^21: 4 passes). */
#define RADIX_BITS 11
#define RADIX (1u << RADIX_BITS)

static void insertion(uint64_t *a, size_t n)
{
    for (size_t i = 1; i < n; i++) {
        uint64_t x = a[i];
        size_t j = i;
        for (; j > 0 && a[j - 1] > x; j--)
            a[j] = a[j - 1];
        a[j] = x;
    }
}

static int by_value(const void *x, const void *y)
{
    uint64_t p = *(const uint64_t *)x, q = *(const uint64_t *)y;
    return (p > q) - (p < q);
}

void ism_sort_u64(uint64_t *a, size_t n)
{
    if (n < SORT_SMALL) {
        insertion(a, n);
        return;
    }
    uint64_t *tmp = malloc(n * sizeof *tmp);
    size_t *count = malloc((RADIX + 1) * sizeof *count);
    if (!tmp || !count) { /* out of memory: qsort needs none */
        free(tmp);
        free(count);
        qsort(a, n, sizeof *a, by_value);
        return;
    }
    uint64_t all_or = 0, all_and = ~(uint64_t)0;
    for (size_t i = 0; i < n; i++) {
        all_or |= a[i];
        all_and &= a[i];
    }
    uint64_t *src = a, *dst = tmp;
    for (int shift = 0; shift < 64; shift += RADIX_BITS) {
        if (((all_or ^ all_and) >> shift & (RADIX - 1)) == 0)
            continue; /* a digit every key shares: no pass */
        memset(count, 0, (RADIX + 1) * sizeof *count);
        for (size_t i = 0; i < n; i++)
            count[(src[i] >> shift & (RADIX - 1)) + 1]++;
        for (size_t b = 0; b < RADIX; b++)
            count[b + 1] += count[b];
        for (size_t i = 0; i < n; i++)
            dst[count[src[i] >> shift & (RADIX - 1)]++] = src[i];
        uint64_t *t = src;
        src = dst;
        dst = t;
    }
    if (src != a)
        memcpy(a, src, n * sizeof *a);
    free(tmp);
    free(count);
}
