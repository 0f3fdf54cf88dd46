/* sort_u64.h — 64-bit keys sorted increasing by an LSD radix sort: qsort's array (equal keys
 * are indistinguishable) at a fraction of its cost. The dual mesher's edge keys (edge_keys.h,
 * dual_crease.c's manifold check) sort a few hundred thousand keys a round. */
#ifndef ISM_SORT_U64_H
#define ISM_SORT_U64_H

#include <stddef.h>
#include <stdint.h>

/* Sorts a[0..n) increasing (in place; a scratch array of n keys, or a slower sort in place
 * when that cannot be had). */
void ism_sort_u64(uint64_t *a, size_t n);

#endif
