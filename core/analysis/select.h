/* select.h — the k-th smallest of an array (select.c), for medians and percentiles: in place
 * on the calling thread, or on a pool's threads for large arrays. */
#ifndef ISM_AN_SELECT_H
#define ISM_AN_SELECT_H

#include <stddef.h>

#include "core/util/pool.h"

/* The k-th smallest (0-based) of v[0..n), reordering v. n > k. */
double ism_an_select_double(double *v, size_t n, size_t k);
float ism_an_select_float(float *v, size_t n, size_t k);

/* The same value (bit for bit, for any number of threads) found on the threads of pool by
 * a radix selection, without reordering v; on the calling thread alone (reordering v as
 * above) when pool is NULL, n is small, or scratch memory cannot be had. Values are finite
 * (a -0 sorts below +0 here: callers pass distances, norms and angles, never -0). */
double ism_an_select_double_on(ism_pool *pool, double *v, size_t n, size_t k);
float ism_an_select_float_on(ism_pool *pool, float *v, size_t n, size_t k);

/* Elements k-1 (into *below) and k of the sorted order, as two calls of
 * ism_an_select_float_on would give them (for even-length medians); 0 < k < n. */
float ism_an_select_float_pair_on(ism_pool *pool, float *v, size_t n, size_t k, float *below);

/* The rank of the "p99" figures (aspect ratio, distances): 99 of 100 items are at most the
 * value at rank floor(0.99 (n - 1)) in ascending order. n > 0. */
static inline size_t ism_an_p99_rank(size_t n)
{
    return (size_t)(0.99 * (double)(n - 1));
}

#endif
